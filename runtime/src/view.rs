//! Borrowed views of a frame's lists: what a generated `RequestView`/`ResponseView` holds
//! where the owned message holds an `rt::Repeated` or `rt::Bits`. Made by the same checks as
//! the owned list ([`RepeatAt::view`] refuses exactly what [`RepeatAt::elements`] refuses, with
//! the same error), then read in place: no copy, no fixed-capacity array.

use core::fmt;
use core::marker::PhantomData;

use crate::codec::Wire;
use crate::repeated::{Bits, RepeatAt, Repeated};
use crate::DecodeError;

/// A repeated field's elements as they sit in the frame, read on demand: `len`, `get`,
/// `iter`. Made by [`RepeatAt::view`] once the frame's checks passed; each element reads as the
/// owned decode reads it (its byte order, sign-extended where the field is signed).
pub struct ListView<'a, T> {
    bytes: &'a [u8],
    width: usize,
    le: bool,
    signed: bool,
    /// Elements of 32 or 64 bits whose 16-bit words travel swapped (`word_order: swapped`).
    swapped: bool,
    elem: PhantomData<T>,
}

impl<T> Clone for ListView<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for ListView<'_, T> {}

impl<'a, T: Wire + 'a> ListView<'a, T> {
    /// How many elements the frame holds.
    #[inline]
    pub fn len(&self) -> usize {
        // `width` is 1 to 8 (checked by `RepeatAt::view`).
        self.bytes.len() / self.width.max(1)
    }

    /// Whether it holds none.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Element `i`, `None` past the last.
    #[inline]
    pub fn get(&self, i: usize) -> Option<T> {
        let at = i.checked_mul(self.width)?;
        let c = self.bytes.get(at..at.checked_add(self.width)?)?;
        Some(self.read(c))
    }

    #[inline(always)]
    fn read(&self, c: &[u8]) -> T {
        let u = if self.swapped && (c.len() == 4 || c.len() == 8) {
            let n = c.len();
            let mut b = [0u8; 8];
            for (i, d) in b[..n].iter_mut().enumerate() {
                *d = c[crate::repeated::swap_index(i, n)];
            }
            crate::codec::uint(&b[..n], self.le)
        } else {
            crate::codec::uint(c, self.le)
        };
        let bits = 8 * self.width as u32;
        let v = if self.signed && bits < 64 {
            ((u << (64 - bits)) as i64) >> (64 - bits)
        } else {
            u as i64
        };
        T::from_i64(v)
    }

    /// The elements in order.
    #[inline]
    pub fn iter(&self) -> impl Iterator<Item = T> + 'a {
        let v = *self;
        self.bytes
            .chunks_exact(self.width.max(1))
            .map(move |c| v.read(c))
    }

    /// The elements' bytes as the frame holds them.
    #[inline]
    pub fn as_bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// The elements copied into an owned list of `N` (the first `N`; a view the generated
    /// code made holds at most the owned field's `N`).
    pub fn to_repeated<const N: usize>(&self) -> Repeated<T, N>
    where
        T: Default,
    {
        let mut r = Repeated::new();
        for v in self.iter() {
            if r.push(v).is_err() {
                break;
            }
        }
        r
    }
}

impl<T: Wire + fmt::Debug> fmt::Debug for ListView<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<T: Wire + PartialEq> PartialEq for ListView<'_, T> {
    fn eq(&self, other: &Self) -> bool {
        self.iter().eq(other.iter())
    }
}

/// A repeated field of bits as it sits in the frame: `len` bits, the first in bit 0 of the
/// first byte. Made by [`RepeatAt::view_bits`]; bits past `len` in the last byte are not part
/// of it (as the owned `Bits` clears them).
#[derive(Clone, Copy)]
pub struct BitsView<'a> {
    packed: &'a [u8],
    len: usize,
}

impl<'a> BitsView<'a> {
    /// How many bits.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it holds none.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bit `i`, `None` past the last.
    #[inline]
    pub fn get(&self, i: usize) -> Option<bool> {
        if i >= self.len {
            return None;
        }
        self.packed.get(i / 8).map(|b| b >> (i % 8) & 1 != 0)
    }

    /// The bits in order.
    pub fn iter(&self) -> impl Iterator<Item = bool> + 'a {
        let v = *self;
        (0..self.len).filter_map(move |i| v.get(i))
    }

    /// The bytes the bits fill as the frame holds them (the last one's padding as it
    /// travelled).
    #[inline]
    pub fn as_bytes(&self) -> &'a [u8] {
        self.packed
    }

    /// The bits copied into an owned `Bits` (the first `8 * BYTES`).
    pub fn to_bits<const BYTES: usize>(&self) -> Bits<BYTES> {
        let mut r = Bits::new();
        for b in self.iter() {
            if r.push(b).is_err() {
                break;
            }
        }
        r
    }
}

impl fmt::Debug for BitsView<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter().map(u8::from)).finish()
    }
}

impl PartialEq for BitsView<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.iter().eq(other.iter())
    }
}

impl RepeatAt {
    /// The elements `bytes` holds, lent in place: refuses what [`RepeatAt::elements`] into a
    /// `Repeated<T, N>` refuses, with its error.
    #[inline]
    pub fn view<'a, T: Wire, const N: usize>(
        &self,
        bytes: &'a [u8],
    ) -> Result<ListView<'a, T>, DecodeError> {
        let width = self.width;
        let found = bytes.len() / width.max(1);
        if width == 0 || width > 8 || bytes.len() % width != 0 || found > N {
            return Err(self.refuse_count(found));
        }
        Ok(ListView {
            bytes,
            width,
            le: self.le,
            signed: self.signed,
            swapped: false,
            elem: PhantomData,
        })
    }

    /// [`Self::view`] of elements of 32 or 64 bits whose 16-bit words travel swapped
    /// (`word_order: swapped`): refuses what [`RepeatAt::words`] refuses, with its error.
    #[inline]
    pub fn view_words<'a, T: Wire, const N: usize>(
        &self,
        bytes: &'a [u8],
    ) -> Result<ListView<'a, T>, DecodeError> {
        let v = self.view::<T, N>(bytes)?;
        Ok(ListView { swapped: true, ..v })
    }

    /// The `n` bits `bytes` packs, lent in place: refuses what [`RepeatAt::bits`] refuses,
    /// with its error.
    #[inline]
    pub fn view_bits<'a, const BYTES: usize>(
        &self,
        bytes: &'a [u8],
        n: usize,
    ) -> Result<BitsView<'a>, DecodeError> {
        if bytes.len() > BYTES {
            // `read_bits`'s refusal, as `bits` names it.
            return Err(self.refuse_count(bytes.len().saturating_mul(8)));
        }
        Ok(BitsView {
            packed: bytes,
            len: n.min(8 * bytes.len()),
        })
    }

    /// [`RepeatAt::in_range`] of a view's elements.
    #[inline]
    pub fn view_in_range<T: Wire>(
        &self,
        items: &ListView<'_, T>,
        min: i64,
        max: i64,
    ) -> Result<(), DecodeError> {
        for (i, v) in items.iter().enumerate() {
            let found = v.to_i64();
            if !T::within(found, min, max) {
                return Err(self.out_of_range(i, found, min, max, T::KIND));
            }
        }
        Ok(())
    }
}

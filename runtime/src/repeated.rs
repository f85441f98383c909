//! [`Repeated`]: the value of a repeated field (registers) in generated code, a
//! fixed-capacity array holding at most the spec's `max` elements; [`Bits`] for a repeated bit
//! field (coils), packed eight to a byte as they travel.
//!
//! Why not `heapless::Vec`: every generated message is `Copy` (the [`crate::Message`] trait
//! asks it, so a decoded frame can be kept, compared and passed around like the fixed-length
//! messages), and `heapless::Vec` is not `Copy`. An array and a length are all it takes, with no
//! dependency; the elements past the length are never read, compared or printed.
//!
//! Why bits are packed: a message enum is as large as its largest variant, and Modbus allows
//! 2000 coils; as `bool`s every Modbus response would take 2 KB, packed it takes 250 bytes, no
//! more than its 125 registers.

use core::fmt;

use crate::codec::Wire;
use crate::{
    CountRule, DecodeError, Elements, EncodeError, FieldDesc, FieldError, FieldValue, ValueKind,
};

/// At most `N` elements of `T`, stored in place: no allocation, `Copy` when `T` is.
///
/// Equality, hashing and `Debug` look only at the elements held ([`Self::as_slice`]), never at
/// the unused capacity.
#[derive(Clone, Copy)]
pub struct Repeated<T, const N: usize> {
    len: usize,
    items: [T; N],
}

/// More elements than a [`Repeated`] holds: `found` where the spec's `max` is `capacity`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CapacityError {
    pub capacity: usize,
    pub found: usize,
}

impl fmt::Display for CapacityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} elements, but the field holds at most {}",
            self.found, self.capacity
        )
    }
}

impl core::error::Error for CapacityError {}

impl<T: Copy + Default, const N: usize> Repeated<T, N> {
    /// The most elements it holds: the spec's `max` (for bits, rounded up to whole bytes).
    pub const CAPACITY: usize = N;

    /// No elements.
    pub fn new() -> Self {
        Repeated {
            len: 0,
            items: [T::default(); N],
        }
    }

    /// The elements of `items`, or an error if there are more than `N`.
    pub fn from_slice(items: &[T]) -> Result<Self, CapacityError> {
        let mut r = Self::new();
        let dst = r.items.get_mut(..items.len()).ok_or(CapacityError {
            capacity: N,
            found: items.len(),
        })?;
        dst.copy_from_slice(items);
        r.len = items.len();
        Ok(r)
    }

    /// Appends `item`, or gives it back if it is full.
    pub fn push(&mut self, item: T) -> Result<(), T> {
        match self.items.get_mut(self.len) {
            Some(slot) => {
                *slot = item;
                self.len += 1;
                Ok(())
            }
            None => Err(item),
        }
    }
}

impl<T, const N: usize> Repeated<T, N> {
    /// The elements held.
    pub fn as_slice(&self) -> &[T] {
        &self.items[..self.len]
    }

    /// How many elements it holds.
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether it holds none.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl<T: Copy + Default, const N: usize> Default for Repeated<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T, const N: usize> core::ops::Deref for Repeated<T, N> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        self.as_slice()
    }
}

impl<T: fmt::Debug, const N: usize> fmt::Debug for Repeated<T, N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

impl<T: PartialEq, const N: usize> PartialEq for Repeated<T, N> {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl<T: Eq, const N: usize> Eq for Repeated<T, N> {}

impl<T: core::hash::Hash, const N: usize> core::hash::Hash for Repeated<T, N> {
    fn hash<H: core::hash::Hasher>(&self, state: &mut H) {
        self.as_slice().hash(state);
    }
}

impl<'a, T, const N: usize> IntoIterator for &'a Repeated<T, N> {
    type Item = &'a T;
    type IntoIter = core::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.as_slice().iter()
    }
}

/// An element type of a repeated field: how its slice is lent to [`crate::Message::visit`].
pub trait Element: Copy + Default {
    /// `items` as the [`Elements`] variant of this type.
    fn elements(items: &[Self]) -> Elements<'_>;
}

macro_rules! element {
    ($($t:ty => $v:ident,)*) => {$(
        impl Element for $t {
            #[inline]
            fn elements(items: &[Self]) -> Elements<'_> {
                Elements::$v(items)
            }
        }
    )*};
}
element! {
    u8 => U8, i8 => I8, u16 => U16, i16 => I16, u32 => U32, i32 => I32, i64 => I64,
}

impl<T: Element, const N: usize> Repeated<T, N> {
    /// The elements as [`crate::Message::visit`] reports them.
    #[inline]
    pub fn elements(&self) -> Elements<'_> {
        T::elements(self.as_slice())
    }
}

impl<T: Wire, const N: usize> crate::ElementTable for Repeated<T, N> {
    fn count(&self) -> usize {
        self.len
    }
    fn raw(&self, i: usize) -> i64 {
        self.as_slice().get(i).map_or(0, |v| v.to_i64())
    }
}

impl<T: Wire, const N: usize> Repeated<T, N> {
    /// Elements of a type of the spec's (a unit's newtype, an enum) as
    /// [`crate::Message::visit`] reports them: by their raw values.
    #[inline]
    pub fn table(&self) -> Elements<'_> {
        Elements::Table(crate::ElementRef(self))
    }
}

impl<R: crate::Record, const N: usize> crate::RecordTable for Repeated<R, N> {
    fn records(&self) -> usize {
        self.len
    }
    fn fields(&self) -> usize {
        R::FIELDS
    }
    fn raw(&self, record: usize, field: usize) -> i64 {
        self.as_slice().get(record).map_or(0, |r| r.raw(field))
    }
}

impl<R: crate::Record, const N: usize> Repeated<R, N> {
    /// The records as [`crate::Message::visit`] reports them.
    #[inline]
    pub fn records(&self) -> crate::RecordList<'_> {
        crate::RecordList::Table(self)
    }
}

/// Repeated record `name` from a [`crate::Message::from_fields`] getter: a list of at most
/// `N` records, each of `R::FIELDS` raw values within their fields' wire limits. Public only
/// for generated code.
#[inline]
pub fn records<'v, R: crate::Record, const N: usize>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
) -> Result<Repeated<R, N>, FieldError> {
    let list = match field(name) {
        Some(FieldValue::Records(list)) if list.fields() == R::FIELDS || list.is_empty() => list,
        Some(_) => {
            return Err(FieldError::WrongKind {
                field: name,
                expected: ValueKind::Records,
            })
        }
        None => return Err(FieldError::Missing { field: name }),
    };
    if list.len() > N {
        return Err(FieldError::TooMany {
            field: name,
            found: list.len(),
            max: N,
        });
    }
    let mut out = Repeated::new();
    for k in 0..list.len() {
        let r = R::from_raw(&list, k)?;
        if out.push(r).is_err() {
            break;
        }
    }
    Ok(out)
}

/// The elements the getter gives for repeated field `name`: a list, or the error that says
/// it gave none or something else.
#[inline]
fn list_items<'v>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
) -> Result<Elements<'v>, FieldError> {
    match field(name) {
        Some(FieldValue::List(items)) => Ok(items),
        Some(_) => Err(FieldError::WrongKind {
            field: name,
            expected: ValueKind::List,
        }),
        None => Err(FieldError::Missing { field: name }),
    }
}

/// Repeated field `name` from a [`crate::Message::from_fields`] getter: a list of at most `N`
/// elements, each within `min..=max` (its wire type's raw values; a bit takes 0 or 1, or a
/// `bool`). Public only for generated code.
#[inline]
pub fn list<'v, T: crate::codec::Wire + Default, const N: usize>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
    min: i64,
    max: i64,
) -> Result<Repeated<T, N>, FieldError> {
    let items = list_items(field, name)?;
    if items.len() > N {
        return Err(FieldError::TooMany {
            field: name,
            found: items.len(),
            max: N,
        });
    }
    let mut r = Repeated::<T, N>::new();
    for (slot, value) in r.items.iter_mut().zip(items.iter()) {
        if !(min..=max).contains(&value) {
            return Err(FieldError::OutOfRange {
                field: name,
                value,
                min,
                max,
            });
        }
        *slot = T::from_i64(value);
    }
    r.len = items.len();
    Ok(r)
}

/// Counted text `name` (`type: ascii` with `repeat`) from a [`crate::Message::from_fields`]
/// getter: text of at most `N` bytes, held as the list of its bytes. Public only for generated
/// code.
#[inline]
pub fn list_text<'v, const N: usize>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
) -> Result<Repeated<u8, N>, FieldError> {
    match field(name) {
        Some(FieldValue::Text(t)) => Repeated::from_slice(t).map_err(|_| FieldError::TooMany {
            field: name,
            found: t.len(),
            max: N,
        }),
        Some(_) => Err(FieldError::WrongKind {
            field: name,
            expected: ValueKind::Text,
        }),
        None => Err(FieldError::Missing { field: name }),
    }
}

/// Repeated bit field `name` from a [`crate::Message::from_fields`] getter, as [`list`]: at
/// most `8 × BYTES` elements, each 0 or 1. Public only for generated code.
#[inline]
pub fn list_bits<'v, const BYTES: usize>(
    field: &mut impl FnMut(&'static str) -> Option<FieldValue<'v>>,
    name: &'static str,
) -> Result<Bits<BYTES>, FieldError> {
    let items = list_items(field, name)?;
    let mut r = Bits::<BYTES>::new();
    for value in items.iter() {
        if !(0..=1).contains(&value) {
            return Err(FieldError::OutOfRange {
                field: name,
                value,
                min: 0,
                max: 1,
            });
        }
        r.push(value == 1).map_err(|_| FieldError::TooMany {
            field: name,
            found: items.len(),
            max: 8 * BYTES,
        })?;
    }
    Ok(r)
}

/// At most `8 × BYTES` bits, packed eight to a byte, least significant first, as Modbus coils
/// travel: no allocation, `Copy`. The bits past the length are always zero, so equality and
/// hashing compare what it holds.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Bits<const BYTES: usize> {
    len: usize,
    packed: [u8; BYTES],
}

impl<const BYTES: usize> Bits<BYTES> {
    /// The most bits it holds.
    pub const CAPACITY: usize = 8 * BYTES;

    /// No bits.
    pub const fn new() -> Self {
        Bits {
            len: 0,
            packed: [0; BYTES],
        }
    }

    /// The bits of `items`, or an error if there are more than [`Self::CAPACITY`].
    pub fn from_bools(items: &[bool]) -> Result<Self, CapacityError> {
        let mut r = Self::new();
        for &b in items {
            r.push(b).map_err(|_| CapacityError {
                capacity: Self::CAPACITY,
                found: items.len(),
            })?;
        }
        Ok(r)
    }

    /// Appends `bit`, or gives it back if it is full.
    pub fn push(&mut self, bit: bool) -> Result<(), bool> {
        let Some(byte) = self.packed.get_mut(self.len / 8) else {
            return Err(bit);
        };
        *byte |= u8::from(bit) << (self.len % 8);
        self.len += 1;
        Ok(())
    }

    /// Bit `i`, if it holds that many.
    pub fn get(&self, i: usize) -> Option<bool> {
        (i < self.len).then(|| self.packed[i / 8] >> (i % 8) & 1 == 1)
    }

    /// How many bits it holds.
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether it holds none.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The bytes the bits fill, as they travel (the last one's padding zero).
    pub fn as_bytes(&self) -> &[u8] {
        &self.packed[..self.len.div_ceil(8)]
    }

    /// The bits in order.
    pub fn iter(&self) -> impl Iterator<Item = bool> + '_ {
        (0..self.len).filter_map(move |i| self.get(i))
    }

    /// The bits as [`crate::Message::visit`] reports them.
    pub fn elements(&self) -> Elements<'_> {
        Elements::Bits {
            packed: self.as_bytes(),
            len: self.len,
        }
    }
}

impl<const BYTES: usize> Default for Bits<BYTES> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const BYTES: usize> fmt::Debug for Bits<BYTES> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter().map(u8::from)).finish()
    }
}

/// Where a message's repeated field sits and how its elements are counted: what generated
/// decoders and the stream decoder need to tell how many elements a frame holds, and so how
/// long the frame is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RepeatAt {
    /// The field, as refusals name it.
    pub field: &'static FieldDesc,
    /// The length of the message's frame without any element.
    pub base: usize,
    /// Where the first element sits in the frame.
    pub at: usize,
    /// Bytes of one element; 0 for bits, packed eight to a byte.
    pub width: usize,
    /// Its elements travel least significant byte first (`byte_order: little`).
    pub le: bool,
    /// Its elements are signed: sign-extended from their width.
    pub signed: bool,
    pub count: CountBy,
    /// The fewest and most elements the spec allows (bits: rounded to whole bytes).
    pub min: usize,
    pub max: usize,
}

/// A repeat counted by one byte, as the numbers that give its frame's length from that byte
/// ([`RepeatAt::byte_count`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ByteCount {
    pub at: usize,
    pub mul: usize,
    pub add: usize,
    pub shift: u32,
    pub lo: usize,
    pub hi: usize,
    pub mask: usize,
    pub base: usize,
}

impl ByteCount {
    /// [`RepeatAt::frame_len`] of the repeat this came from.
    #[inline(always)]
    pub fn frame_len(&self, head: &[u8]) -> Option<usize> {
        let v = usize::from(*head.get(self.at)?);
        let extra = (v * self.mul + self.add) >> self.shift;
        let fits = extra >= self.lo && extra <= self.hi && extra & self.mask == 0;
        Some(if fits { self.base + extra } else { 0 })
    }
}

/// How the stream decoder finds a variable-length frame's length from its count field
/// ([`RepeatAt::count_len`], computed where the generated tables are written, in a `const`):
/// a count of one byte as plain numbers, any other through its [`RepeatAt`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CountLen {
    Byte(ByteCount),
    Other(RepeatAt),
}

impl CountLen {
    /// [`RepeatAt::frame_len`] of the repeat this came from.
    #[inline(always)]
    pub fn frame_len(&self, head: &[u8]) -> Option<usize> {
        match self {
            CountLen::Byte(b) => b.frame_len(head),
            CountLen::Other(r) => r.frame_len_inline(head),
        }
    }
}

/// What a repeated field's count is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CountBy {
    /// As many elements as fit before the checksum.
    End,
    /// As many elements as fit before these end bytes, where end bytes alone delimit the
    /// frame (no length field, no checksum: Nextion's `FF FF FF`): the list ends at their
    /// first appearance from its first byte, so it never holds them ([`RepeatAt::count`]
    /// refuses a frame whose list does, [`RepeatAt::encode_delimited`] a list that would) and
    /// a stream decoder ends the frame there ([`RepeatAt::frame_len`]).
    Delimited(&'static [u8]),
    /// An earlier field holds the number of elements.
    Elements(CountField),
    /// An earlier field holds the number of bytes the elements take.
    Bytes(CountField),
    /// Records to the end of the frame whose last field's bytes an earlier field gives
    /// (Dynamixel 2.0 SYNC_WRITE's `data_length`): each record takes
    /// `fixed` + that field's value, which must be 1..=`most`. The `width` of its
    /// [`RepeatAt`] is a record at its widest.
    EndSized(SizedBy),
    /// Text up to the first terminator byte (this one) among the bytes the frame's length
    /// leaves it (`repeat: {until: 0x00}`): its characters, then the terminator, which is no
    /// character. Always decoded through [`crate::codec::Lists`]. Where the frame has no
    /// length field it is the message's only list and its terminator ends the frame: a stream
    /// decoder reads for it ([`RepeatAt::frame_len`]).
    Until(u8),
    /// Exactly this many elements, always (records of a fixed count: `repeat: {count: 3}`):
    /// no field counts them, and the frame's length must give them.
    Fixed(usize),
}

/// The field that gives the bytes of each record's last field ([`CountBy::EndSized`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizedBy {
    pub field: CountField,
    /// The bytes of a record's other fields.
    pub fixed: usize,
    /// The most bytes the last field takes (its type's width).
    pub most: usize,
}

/// An unsigned field of the frame that counts a repeated field's elements or bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CountField {
    pub name: &'static str,
    /// Its offset in the frame.
    pub at: usize,
    /// Its width, bytes.
    pub width: usize,
    /// Least significant byte first.
    pub le: bool,
}

impl CountField {
    /// Its value in `frame` (`None` if the frame does not reach it).
    #[inline(always)]
    pub fn read(&self, frame: &[u8]) -> Option<u64> {
        let b = frame.get(self.at..self.at + self.width)?;
        Some(crate::codec::uint(b, self.le))
    }
}

/// The bytes of `frame` past `base`, the length of its message's frame with every list empty:
/// what its lists take ([`DecodeError::Truncated`] where it is shorter).
pub(crate) fn beyond(frame: &[u8], base: usize) -> Result<usize, DecodeError> {
    frame.len().checked_sub(base).ok_or(DecodeError::Truncated {
        needed: base,
        found: frame.len(),
    })
}

impl RepeatAt {
    /// The bytes one element takes in `frame` (or its fixed head): [`Self::width`], or for
    /// records whose last field's bytes a field gives, their fixed bytes plus its value
    /// (held to `1..=most`; [`Self::count`] refuses any other).
    #[inline]
    pub fn element_width(&self, frame: &[u8]) -> usize {
        match self.count {
            CountBy::EndSized(s) => {
                let v = s.field.read(frame).unwrap_or(1).clamp(1, s.most as u64);
                s.fixed + v as usize
            }
            _ => self.width,
        }
    }

    /// The length of a frame of records whose last field's bytes a field gives, holding
    /// `held` records with that field `width` bytes wide: [`EncodeError::NotInRange`] for a
    /// width outside `1..=most` (naming that field), [`EncodeError::WrongCount`] for a count
    /// outside the bounds. Any other
    /// list: [`Self::encode_len`].
    #[inline]
    pub fn encode_len_sized(&self, held: usize, width: u64) -> Result<usize, EncodeError> {
        let CountBy::EndSized(s) = self.count else {
            return self.encode_len(held);
        };
        if width < 1 || width > s.most as u64 {
            return Err(EncodeError::NotInRange {
                field: s.field.name,
                value: width as i64,
                min: 1,
                max: s.most as i64,
                kind: crate::NumKind::Int,
            });
        }
        if held < self.min || held > self.max {
            return Err(EncodeError::WrongCount {
                field: self.field.name,
                min: self.min,
                max: self.max,
                found: held,
            });
        }
        Ok(self.base + held * (s.fixed + width as usize))
    }

    /// Bytes `n` elements take.
    #[inline]
    pub const fn bytes_of(&self, n: usize) -> usize {
        if self.width == 0 {
            n.div_ceil(8)
        } else if let CountBy::Until(_) = self.count {
            // The characters and their terminator.
            n.saturating_add(1)
        } else {
            n.saturating_mul(self.width)
        }
    }

    /// The number of elements `frame` (a whole frame of the message) holds: its length less
    /// [`Self::base`], which must be a whole number of elements agreeing with the count field
    /// and within the bounds. Bits count eight to a byte, padding included, as the interpreter
    /// counts them. Inlined always, as [`Self::split`], its caller.
    #[inline(always)]
    pub fn count(&self, frame: &[u8]) -> Result<usize, DecodeError> {
        let bad = |found: i64, expected: CountRule| DecodeError::BadCount {
            field: self.field,
            offset: self.at,
            found,
            expected,
        };
        let extra = beyond(frame, self.base)?;
        // Records whose width a field gives: that field first, within 1..=its most.
        if let CountBy::EndSized(s) = self.count {
            let v = s.field.read(frame).unwrap_or(0);
            if v < 1 || v > s.most as u64 {
                return Err(DecodeError::BadWidth {
                    list: self.field,
                    field: s.field.name,
                    offset: s.field.at,
                    found: v as i64,
                    most: s.most,
                });
            }
        }
        let width = self.element_width(frame);
        let whole = width == 0 || extra % width == 0;
        // Bits (width 0) come eight to a byte.
        let mut n = extra.checked_div(width).unwrap_or(extra.saturating_mul(8));
        match self.count {
            CountBy::Until(t) => n = self.until(frame, t, extra, true)?,
            // The end bytes must first appear where the frame's own sit (checked in this arm,
            // not before the match: there it cost every other list 1 to 2.5 instructions a
            // frame, `bash benches/icount.sh modbus dynamixel`).
            CountBy::Delimited(_) => {
                if let Some(e) = self.end_inside(frame) {
                    return Err(e);
                }
                if !whole {
                    return Err(bad(extra as i64, CountRule::Whole(width)));
                }
            }
            CountBy::End | CountBy::EndSized(_) if !whole => {
                return Err(bad(extra as i64, CountRule::Whole(width)))
            }
            CountBy::End | CountBy::EndSized(_) => {}
            CountBy::Elements(c) => {
                // Bits by count: as many as it says, the last byte's padding left out.
                let v = c.read(frame).unwrap_or(0);
                match usize::try_from(v) {
                    Ok(v) if self.bytes_of(v) == extra => n = v,
                    _ => {
                        let by_length = CountRule::ByLength(extra / self.width.max(1));
                        return Err(bad(v as i64, by_length));
                    }
                }
            }
            // As a count field saying that many would.
            CountBy::Fixed(v) if self.bytes_of(v) == extra => n = v,
            CountBy::Fixed(v) => {
                let by_length = CountRule::ByLength(extra / self.width.max(1));
                return Err(bad(v as i64, by_length));
            }
            CountBy::Bytes(c) => {
                let v = c.read(frame).unwrap_or(0);
                if !whole || usize::try_from(v) != Ok(extra) {
                    return Err(DecodeError::ByteCount {
                        list: self.field,
                        field: c.name,
                        offset: c.at,
                        expected: extra as i64,
                        found: v as i64,
                    });
                }
            }
        }
        let (lo, hi) = if self.width == 0 {
            (self.min.div_ceil(8) * 8, self.max.div_ceil(8) * 8)
        } else {
            (self.min, self.max)
        };
        if n < lo || n > hi {
            return Err(bad(n as i64, CountRule::Between(self.min, self.max)));
        }
        Ok(n)
    }

    /// The characters of text up to terminator `t` that starts at [`Self::at`] in `frame`,
    /// among the `rest` bytes the frame's length leaves it; as the last list (`last`) its
    /// terminator must be the last of them.
    pub(crate) fn until(
        &self,
        frame: &[u8],
        t: u8,
        rest: usize,
        last: bool,
    ) -> Result<usize, DecodeError> {
        let n = frame
            .get(self.at..self.at.saturating_add(rest))
            .and_then(|b| b.iter().position(|&x| x == t))
            .ok_or(DecodeError::NoTerminator {
                field: self.field,
                offset: self.at,
                terminator: t,
                within: rest,
            })?;
        if last && n + 1 != rest {
            return Err(DecodeError::BadCount {
                field: self.field,
                offset: self.at,
                found: n as i64,
                expected: CountRule::ByLength(rest - 1),
            });
        }
        Ok(n)
    }

    /// The length of the frame that starts `head` whose list ends at the first end bytes
    /// ([`CountBy::Delimited`]): up to them, where they are buffered within the longest frame
    /// (`Some(0)` where that frame cannot hold a whole number of elements within the bounds);
    /// `Some(0)` where they are not within the longest frame, `None` while it is not all
    /// buffered.
    fn delimited_len(&self, head: &[u8], end: &[u8]) -> Option<usize> {
        let most = self.base.saturating_add(self.bytes_of(self.max));
        let seen = head.get(self.at..head.len().min(most)).unwrap_or(&[]);
        let Some(i) = find(seen, end) else {
            return (head.len() >= most).then_some(0);
        };
        // Fields after the list sit between it and the end bytes.
        let len = self.at + i + end.len();
        let Some(bytes) = len.checked_sub(self.base) else {
            return Some(0);
        };
        let width = self.width.max(1);
        let n = if self.width == 0 {
            bytes * 8
        } else {
            bytes / width
        };
        let fits = bytes % width == 0 || self.width == 0;
        let (lo, hi) = if self.width == 0 {
            (self.min.div_ceil(8) * 8, self.max.div_ceil(8) * 8)
        } else {
            (self.min, self.max)
        };
        Some(if fits && (lo..=hi).contains(&n) {
            len
        } else {
            0
        })
    }

    /// The length of the frame that starts `head` whose text up to terminator `t`
    /// ([`CountBy::Until`]) only its terminator ends (a frame without a length field): the
    /// frame with its characters up to the first terminator from [`Self::at`] and the
    /// terminator, where that is buffered within `max` characters and the terminator
    /// (`Some(0)` where it comes before `min` characters, or they hold none), `None` while
    /// they are not all buffered.
    fn terminated_len(&self, head: &[u8], t: u8) -> Option<usize> {
        let most = self.at.saturating_add(self.max).saturating_add(1);
        let seen = head.get(self.at..head.len().min(most)).unwrap_or(&[]);
        let Some(n) = seen.iter().position(|&b| b == t) else {
            return (head.len() >= most).then_some(0);
        };
        Some(if n >= self.min {
            self.base.saturating_add(n + 1)
        } else {
            0
        })
    }

    /// Where end bytes alone delimit the frame ([`CountBy::Delimited`]): the refusal of
    /// `frame` (a whole frame of the message) where they appear from the list's first byte on
    /// before the frame's own. Any other list: none.
    #[inline]
    pub(crate) fn end_inside(&self, frame: &[u8]) -> Option<DecodeError> {
        let CountBy::Delimited(end) = self.count else {
            return None;
        };
        let own = frame.len().checked_sub(end.len())?;
        let i = frame.get(self.at..).and_then(|from| find(from, end))?;
        (self.at + i < own).then_some(DecodeError::EndInside {
            field: self.field,
            offset: self.at + i,
            end,
        })
    }

    /// Where end bytes alone delimit the frame ([`CountBy::Delimited`]), `frame` (a whole
    /// frame of the message as encode lays it out, its end bytes not yet written) with its
    /// list followed by the end bytes must not show them before: [`EncodeError::HoldsEnd`]
    /// at the first place it does. Any other list: nothing to check.
    #[inline]
    pub fn encode_delimited(&self, frame: &[u8]) -> Result<(), EncodeError> {
        let CountBy::Delimited(end) = self.count else {
            return Ok(());
        };
        let list = frame
            .get(self.at..frame.len().saturating_sub(end.len()))
            .unwrap_or(&[]);
        // The list, then the end bytes: a match that starts in the list is one too early.
        let at = (0..list.len()).find(|&i| {
            end.iter().enumerate().all(|(k, e)| {
                let b = list.get(i + k).or_else(|| end.get(i + k - list.len()));
                b == Some(e)
            })
        });
        match at {
            Some(i) => Err(EncodeError::HoldsEnd {
                field: self.field.name,
                offset: self.at + i,
                end,
            }),
            None => Ok(()),
        }
    }

    /// Text up to a terminator ([`CountBy::Until`]) to encode: none of its characters may be
    /// the terminator, which would end it early. Any other list: nothing to check.
    #[inline]
    pub fn encode_until(&self, chars: &[u8]) -> Result<(), EncodeError> {
        let CountBy::Until(t) = self.count else {
            return Ok(());
        };
        match chars.iter().position(|&b| b == t) {
            Some(index) => Err(EncodeError::HoldsTerminator {
                field: self.field.name,
                index,
                terminator: t,
            }),
            None => Ok(()),
        }
    }

    /// The length of the frame that starts `head` (the bytes buffered so far), once its count
    /// field has arrived: `None` for a count to the end (the frame's length comes from
    /// elsewhere: a length field, or the candidates' lengths) or while the count field is still
    /// missing. A count whose frame could not hold `min..=max` elements gives `Some(0)`, which
    /// no frame has: the stream decoder then drops a byte and resynchronises.
    #[inline]
    pub fn frame_len(&self, head: &[u8]) -> Option<usize> {
        self.frame_len_inline(head)
    }

    /// [`Self::frame_len`] as plain numbers where the count is one byte (Modbus's byte
    /// counts): the length the count byte `v` gives is `base + extra`, `extra` being
    /// `(v * mul + add) >> shift`, where `lo <= extra <= hi` and `extra & mask == 0`, else 0;
    /// `None` for any other count. What the generated `variable_candidates` hand
    /// `rt::var_by_count` ([`Self::count_len`], in a `const`): the compiler did not fold the
    /// generic arithmetic (the count's kind, its width, the bounds as bytes, a division) where
    /// several messages' repeats share one path (Modbus's four read replies became a table of
    /// the four constants and the arithmetic on each), and as these numbers it is a few
    /// operations whether folded or not.
    pub const fn byte_count(&self) -> Option<ByteCount> {
        let (c, bytes) = match self.count {
            CountBy::Elements(c) => (c, false),
            CountBy::Bytes(c) => (c, true),
            _ => return None,
        };
        if c.width != 1 {
            return None;
        }
        // `extra % width == 0` as a mask: where it is not always true, the width must be a
        // power of two.
        let mask = if self.width == 0 || !bytes {
            0
        } else if self.width.is_power_of_two() {
            self.width - 1
        } else {
            return None;
        };
        let (mul, add, shift) = match (bytes, self.width) {
            (true, _) => (1, 0, 0),
            (false, 0) => (1, 7, 3),
            (false, w) => (w, 0, 0),
        };
        Some(ByteCount {
            at: c.at,
            mul,
            add,
            shift,
            lo: self.bytes_of(self.min),
            hi: self.bytes_of(self.max),
            mask,
            base: self.base,
        })
    }

    /// [`Self::frame_len`] as the stream decoder's tables hold it ([`CountLen`]), for a
    /// `const`.
    pub const fn count_len(self) -> CountLen {
        match self.byte_count() {
            Some(b) => CountLen::Byte(b),
            None => CountLen::Other(self),
        }
    }

    /// [`Self::frame_len`], always inlined: where the repeat is a constant (the generated
    /// `variable_candidates`), its arithmetic folds.
    #[inline(always)]
    pub(crate) fn frame_len_inline(&self, head: &[u8]) -> Option<usize> {
        let (c, bytes) = match self.count {
            CountBy::Delimited(end) => return self.delimited_len(head, end),
            CountBy::Until(t) => return self.terminated_len(head, t),
            CountBy::End | CountBy::EndSized(_) => return None,
            CountBy::Fixed(v) => return Some(self.base + self.bytes_of(v)),
            CountBy::Elements(c) => (c, false),
            CountBy::Bytes(c) => (c, true),
        };
        let v = usize::try_from(c.read(head)?).unwrap_or(usize::MAX);
        let extra = if bytes { v } else { self.bytes_of(v) };
        let fits = extra >= self.bytes_of(self.min)
            && extra <= self.bytes_of(self.max)
            && (self.width == 0 || extra % self.width == 0);
        Some(if fits { self.base + extra } else { 0 })
    }
}

/// A list of its elements, as a generated message with the `serde` feature carries it.
#[cfg(feature = "serde")]
impl<T: serde::Serialize, const N: usize> serde::Serialize for Repeated<T, N> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.as_slice())
    }
}

/// A list of at most `N` elements; a longer one is an error.
#[cfg(feature = "serde")]
impl<'de, T: serde::Deserialize<'de> + Copy + Default, const N: usize> serde::Deserialize<'de>
    for Repeated<T, N>
{
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Seq<T, const N: usize>(core::marker::PhantomData<T>);
        impl<'de, T: serde::Deserialize<'de> + Copy + Default, const N: usize>
            serde::de::Visitor<'de> for Seq<T, N>
        {
            type Value = Repeated<T, N>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a list of at most {N} elements")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<Self::Value, A::Error> {
                let mut r = Repeated::new();
                while let Some(v) = a.next_element()? {
                    if r.push(v).is_err() {
                        return Err(serde::de::Error::invalid_length(N + 1, &self));
                    }
                }
                Ok(r)
            }
        }
        d.deserialize_seq(Seq::<T, N>(core::marker::PhantomData))
    }
}

/// A list of its bits.
#[cfg(feature = "serde")]
impl<const BYTES: usize> serde::Serialize for Bits<BYTES> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.iter())
    }
}

/// A list of at most `8 × BYTES` bits; a longer one is an error.
#[cfg(feature = "serde")]
impl<'de, const BYTES: usize> serde::Deserialize<'de> for Bits<BYTES> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Seq<const BYTES: usize>;
        impl<'de, const BYTES: usize> serde::de::Visitor<'de> for Seq<BYTES> {
            type Value = Bits<BYTES>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a list of at most {} bits", 8 * BYTES)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<Self::Value, A::Error> {
                let mut r = Bits::new();
                while let Some(v) = a.next_element()? {
                    if r.push(v).is_err() {
                        return Err(serde::de::Error::invalid_length(8 * BYTES + 1, &self));
                    }
                }
                Ok(r)
            }
        }
        d.deserialize_seq(Seq::<BYTES>)
    }
}

/// Any number of elements up to `N`, each arbitrary.
#[cfg(feature = "arbitrary")]
impl<'a, T: arbitrary::Arbitrary<'a> + Copy + Default, const N: usize> arbitrary::Arbitrary<'a>
    for Repeated<T, N>
{
    fn arbitrary(u: &mut arbitrary::Unstructured<'a>) -> arbitrary::Result<Self> {
        let n = u.int_in_range(0..=N)?;
        let mut r = Repeated::new();
        for _ in 0..n {
            let _ = r.push(T::arbitrary(u)?);
        }
        Ok(r)
    }
}

/// Any number of bits up to `8 × BYTES`, each arbitrary.
#[cfg(feature = "arbitrary")]
impl<'a, const BYTES: usize> arbitrary::Arbitrary<'a> for Bits<BYTES> {
    fn arbitrary(u: &mut arbitrary::Unstructured<'a>) -> arbitrary::Result<Self> {
        let n = u.int_in_range(0..=8 * BYTES)?;
        let mut r = Bits::new();
        for _ in 0..n {
            let _ = r.push(bool::arbitrary(u)?);
        }
        Ok(r)
    }
}

/// What generated decoders and encoders do with a message's repeated field.
impl RepeatAt {
    /// The elements a frame's count field stands for, `min..=max` inclusive: where it counts
    /// bytes of bits, any number that fills that many bytes.
    fn elements_for(&self, count: u64) -> (i64, i64) {
        let v = i64::try_from(count).unwrap_or(i64::MAX);
        match self.count {
            CountBy::Bytes(_) if self.width == 0 => (
                v.saturating_sub(1).saturating_mul(8).saturating_add(1),
                v.saturating_mul(8),
            ),
            CountBy::Bytes(_) => {
                let w = self.width as i64;
                if v % w == 0 {
                    (v / w, v / w)
                } else {
                    // No whole number of elements takes that many bytes.
                    (v / w + 1, v / w)
                }
            }
            CountBy::Elements(_)
            | CountBy::End
            | CountBy::Delimited(_)
            | CountBy::EndSized(_)
            | CountBy::Until(_)
            | CountBy::Fixed(_) => (v, v),
        }
    }

    /// The frame checked for its element count ([`Self::count`]), split into its first `AT`
    /// bytes (every fixed field; `AT` is [`Self::at`]) as an array, the bytes of its elements,
    /// and their number.
    ///
    /// Inlined always, [`Self::count`] with it: every caller's `self` is a generated constant,
    /// so the match on the count's kind and the element width fold away (Dynamixel: decode
    /// 279.5 -> 229.4, stream 411.2 -> 310.6 instructions a frame).
    #[inline(always)]
    pub fn split<'f, const AT: usize>(
        &self,
        frame: &'f [u8],
    ) -> Result<(&'f [u8; AT], &'f [u8], usize), DecodeError> {
        let n = self.count(frame)?;
        let bytes = match self.count {
            // Bits by bytes or to the end: every byte before the checksum.
            CountBy::End | CountBy::Delimited(_) | CountBy::Bytes(_) if self.width == 0 => n / 8,
            CountBy::EndSized(_) => n * self.element_width(frame),
            // The characters, not their terminator.
            CountBy::Until(_) => n,
            _ => self.bytes_of(n),
        };
        let head = frame.first_chunk::<AT>();
        let items = frame.get(self.at..self.at + bytes);
        match (head, items) {
            (Some(head), Some(items)) => Ok((head, items, n)),
            _ => Err(DecodeError::Truncated {
                needed: self.base + bytes,
                found: frame.len(),
            }),
        }
    }

    /// [`Self::bad_count`], for the views (`view.rs`).
    #[inline]
    pub(crate) fn refuse_count(&self, found: usize) -> DecodeError {
        self.bad_count(found)
    }

    /// The refusal of element `i` of value `found` outside `min..=max`.
    #[inline]
    pub(crate) fn out_of_range(
        &self,
        i: usize,
        found: i64,
        min: i64,
        max: i64,
        kind: crate::NumKind,
    ) -> DecodeError {
        DecodeError::OutOfRange {
            field: self.field,
            offset: self.at + i * self.width,
            found,
            min,
            max,
            kind,
        }
    }

    fn bad_count(&self, found: usize) -> DecodeError {
        DecodeError::BadCount {
            field: self.field,
            offset: self.at,
            found: found as i64,
            expected: CountRule::Between(self.min, self.max),
        }
    }

    /// The elements `bytes` holds, in its width, byte order and sign, as `read_elements`
    /// reads them.
    #[inline]
    pub fn elements<T: Wire + Default, const N: usize>(
        &self,
        bytes: &[u8],
    ) -> Result<Repeated<T, N>, DecodeError> {
        read_elements(bytes, self.width, self.le, self.signed).map_err(|e| self.bad_count(e.found))
    }

    /// Writes `items` as its elements into `out` (which must hold them), in its width and
    /// byte order; returns the bytes written.
    #[inline]
    pub fn write<T: Wire>(&self, items: &[T], out: &mut [u8]) -> usize {
        write_elements(items, self.width, self.le, out)
    }

    /// [`Self::write`] of elements of 32 or 64 bits whose 16-bit words travel swapped
    /// (`word_order: swapped`), as [`Self::words`] reads them.
    #[inline]
    pub fn write_words<T: Wire>(&self, items: &[T], out: &mut [u8]) -> usize {
        write_words(items, self.width, self.le, out)
    }

    /// The elements `bytes` holds, each of 32 or 64 bits whose 16-bit words travel swapped
    /// (`word_order: swapped`), as `read_words` reads them; refuses what [`Self::elements`]
    /// refuses.
    #[inline]
    pub fn words<T: Wire + Default, const N: usize>(
        &self,
        bytes: &[u8],
    ) -> Result<Repeated<T, N>, DecodeError> {
        read_words(bytes, self.width, self.le, self.signed).map_err(|e| self.bad_count(e.found))
    }

    /// The `n` bits `bytes` packs (every bit of every byte where the count is in bytes or to
    /// the end, as the interpreter reads them).
    #[inline]
    pub fn bits<const BYTES: usize>(
        &self,
        bytes: &[u8],
        n: usize,
    ) -> Result<Bits<BYTES>, DecodeError> {
        let mut r = read_bits::<BYTES>(bytes).map_err(|e| self.bad_count(e.found))?;
        if n < r.len {
            // The padding of the last byte is not part of a count of elements.
            for i in n..r.len {
                r.packed[i / 8] &= !(1 << (i % 8));
            }
            r.len = n;
        }
        Ok(r)
    }

    /// Every element of a decoded repeated field within its spec range `min..=max`; the error
    /// names the offset of the first that is not.
    #[inline]
    pub fn in_range<T: Wire>(&self, items: &[T], min: i64, max: i64) -> Result<(), DecodeError> {
        for (i, v) in items.iter().enumerate() {
            let found = v.to_i64();
            if !T::within(found, min, max) {
                return Err(self.out_of_range(i, found, min, max, T::KIND));
            }
        }
        Ok(())
    }

    /// The value of the count field of a frame holding `held` elements: their number or their
    /// bytes (0 for a count to the end, which has no field).
    #[inline]
    pub const fn count_value(&self, held: usize) -> usize {
        match self.count {
            CountBy::Elements(_) => held,
            CountBy::Bytes(_) if self.width == 0 => held.div_ceil(8),
            CountBy::Bytes(_) => held * self.width,
            CountBy::End
            | CountBy::Delimited(_)
            | CountBy::EndSized(_)
            | CountBy::Until(_)
            | CountBy::Fixed(_) => 0,
        }
    }

    /// A reply holding `held` elements whose count follows the request
    /// (`ceil(base × multiply / divide)` elements): it must take as many bytes as they would.
    #[inline]
    pub fn follows_request(
        &self,
        held: usize,
        base: i64,
        (multiply, divide): (u64, u64),
        rule: &'static str,
    ) -> Result<(), DecodeError> {
        let expected = crate::codec::follows(base, multiply, divide);
        match usize::try_from(expected) {
            Ok(n) if self.bytes_of(n) == self.bytes_of(held) => Ok(()),
            _ => Err(DecodeError::BadCount {
                field: self.field,
                offset: self.at,
                found: held as i64,
                expected: CountRule::Request(expected, rule),
            }),
        }
    }

    /// The length of the frame holding `held` elements, which must lie in the spec's bounds
    /// (bits: up to the whole bytes `max` fills, as decode reads them):
    /// [`EncodeError::WrongCount`] otherwise, worded as the interpreter words it.
    #[inline]
    pub fn encode_len(&self, held: usize) -> Result<usize, EncodeError> {
        let hi = if self.width == 0 {
            self.max.div_ceil(8) * 8
        } else {
            self.max
        };
        if held < self.min || held > hi {
            return Err(EncodeError::WrongCount {
                field: self.field.name,
                min: self.min,
                max: hi,
                found: held,
            });
        }
        Ok(self.base + self.bytes_of(held))
    }

    /// A count field computed from another field (`follows`) agrees with the `held` elements
    /// being encoded: [`EncodeError::WrongCount`] with the element count and the counts that
    /// would agree otherwise.
    #[inline]
    pub fn encode_agrees(&self, held: usize, count: u64) -> Result<(), EncodeError> {
        if u64::try_from(self.count_value(held)).ok() == Some(count) {
            return Ok(());
        }
        let (min, max) = self.elements_for(count);
        Err(EncodeError::WrongCount {
            field: self.field.name,
            min: usize::try_from(min).unwrap_or(usize::MAX),
            max: usize::try_from(max).unwrap_or(usize::MAX),
            found: held,
        })
    }

    /// Every element to encode within its spec range `min..=max`.
    #[inline]
    pub fn encode_in_range<T: Wire>(
        &self,
        items: &[T],
        min: i64,
        max: i64,
    ) -> Result<(), EncodeError> {
        for v in items {
            let value = v.to_i64();
            if !T::within(value, min, max) {
                return Err(EncodeError::NotInRange {
                    field: self.field.name,
                    value,
                    min,
                    max,
                    kind: T::KIND,
                });
            }
        }
        Ok(())
    }
}

/// The elements of `width` bytes each (`le`: least significant byte first; `signed`: sign-
/// extended from `8 × width` bits) that `bytes` holds, which must be a whole number of them and
/// at most `N`. Generated decoders call it after checking the count against the frame, so an
/// error here means a count the frame's length does not give.
#[inline]
pub(crate) fn read_elements<T: crate::codec::Wire + Default, const N: usize>(
    bytes: &[u8],
    width: usize,
    le: bool,
    signed: bool,
) -> Result<Repeated<T, N>, CapacityError> {
    let found = bytes.len() / width.max(1);
    if width == 0 || width > 8 || bytes.len() % width != 0 || found > N {
        return Err(CapacityError { capacity: N, found });
    }
    let mut r = Repeated::<T, N>::new();
    for (slot, c) in r.items.iter_mut().zip(bytes.chunks_exact(width)) {
        *slot = T::from_i64(crate::codec::int(c, le, signed));
    }
    r.len = found;
    Ok(r)
}

/// [`read_elements`] of elements of 32 or 64 bits whose 16-bit words travel swapped
/// (`word_order: swapped`): each element's bytes put back in its byte order first.
#[inline]
pub(crate) fn read_words<T: crate::codec::Wire + Default, const N: usize>(
    bytes: &[u8],
    width: usize,
    le: bool,
    signed: bool,
) -> Result<Repeated<T, N>, CapacityError> {
    let found = bytes.len() / width.max(1);
    if width == 0 || width > 8 || bytes.len() % width != 0 || found > N {
        return Err(CapacityError { capacity: N, found });
    }
    let swapped = width == 4 || width == 8;
    let mut r = Repeated::<T, N>::new();
    for (slot, c) in r.items.iter_mut().zip(bytes.chunks_exact(width)) {
        let mut b = [0u8; 8];
        for (i, d) in b[..width].iter_mut().enumerate() {
            let j = if swapped { swap_index(i, width) } else { i };
            *d = c.get(j).copied().unwrap_or(0);
        }
        *slot = T::from_i64(crate::codec::int(&b[..width], le, signed));
    }
    r.len = found;
    Ok(r)
}

/// [`write_elements`] of elements of 32 or 64 bits whose 16-bit words travel swapped
/// (`word_order: swapped`), as [`read_words`] reads them; returns the bytes written.
#[inline]
pub(crate) fn write_words<T: crate::codec::Wire>(
    items: &[T],
    width: usize,
    le: bool,
    out: &mut [u8],
) -> usize {
    let width = width.clamp(1, 8);
    let swapped = width == 4 || width == 8;
    for (c, v) in out.chunks_exact_mut(width).zip(items) {
        let u = v.to_u64();
        for i in 0..width {
            let shift = if le { 8 * i } else { 8 * (width - 1 - i) };
            let j = if swapped { swap_index(i, width) } else { i };
            c[j] = (u >> shift) as u8;
        }
    }
    items.len() * width
}

/// Writes `items` as elements of `width` bytes each into `out` (which must hold them), and
/// returns the bytes written.
#[inline]
pub(crate) fn write_elements<T: crate::codec::Wire>(
    items: &[T],
    width: usize,
    le: bool,
    out: &mut [u8],
) -> usize {
    for (c, v) in out.chunks_exact_mut(width.max(1)).zip(items) {
        let u = v.to_u64();
        let n = c.len();
        for (k, b) in c.iter_mut().enumerate() {
            let shift = if le { 8 * k } else { 8 * (n - 1 - k) };
            *b = (u >> shift) as u8;
        }
    }
    items.len() * width
}

/// The bits `bytes` packs, eight to a byte, least significant bit first (Modbus coils): always
/// `8 × bytes.len()` of them, the padding of the last byte included (as the interpreter reads
/// them), at most `8 × BYTES`.
#[inline]
pub fn read_bits<const BYTES: usize>(bytes: &[u8]) -> Result<Bits<BYTES>, CapacityError> {
    let mut r = Bits::<BYTES>::new();
    let dst = r.packed.get_mut(..bytes.len()).ok_or(CapacityError {
        capacity: 8 * BYTES,
        found: bytes.len().saturating_mul(8),
    })?;
    dst.copy_from_slice(bytes);
    r.len = 8 * bytes.len();
    Ok(r)
}

/// Writes `bits` as they travel into `out` (which must hold `ceil(len / 8)` bytes), and returns
/// the bytes written.
#[inline]
pub fn write_bits<const BYTES: usize>(bits: &Bits<BYTES>, out: &mut [u8]) -> usize {
    let b = bits.as_bytes();
    if let Some(dst) = out.get_mut(..b.len()) {
        dst.copy_from_slice(b);
    }
    b.len()
}

/// The stream position of bit `j` of element `k` of `bits`-bit packed elements, and which bit
/// of the byte at `s / 8` holds it (`lsb`: element 0 from bit 0 of the first byte, each element
/// least significant bit first; else from bit 7, most significant bit first).
#[inline(always)]
fn packed_bit(k: usize, j: usize, bits: usize, lsb: bool) -> (usize, usize, u32) {
    let s = k * bits + j;
    let weight = if lsb { j } else { bits - 1 - j };
    let shift = if lsb { s % 8 } else { 7 - s % 8 };
    (s / 8, weight, shift as u32)
}

/// `N` elements of `bits` bits each (at most 32) packed in `bytes` (a packed field,
/// `packed: {count: N, bits, bit_order}`), as the interpreter's `ir::Packed::read` reads them.
#[inline]
pub fn unpack<T: crate::codec::Wire + Default, const N: usize>(
    bytes: &[u8],
    bits: usize,
    lsb: bool,
) -> Repeated<T, N> {
    let mut r = Repeated::<T, N>::new();
    for k in 0..N {
        let mut v = 0u64;
        for j in 0..bits {
            let (at, weight, shift) = packed_bit(k, j, bits, lsb);
            let b = bytes.get(at).copied().unwrap_or(0);
            v |= u64::from(b >> shift & 1) << weight;
        }
        r.items[k] = T::from_i64(v as i64);
    }
    r.len = N;
    r
}

/// The bits of the last byte of `count` packed `bits`-bit elements that no element takes
/// (0 in a valid frame).
#[inline]
pub fn packed_padding(bytes: &[u8], count: usize, bits: usize, lsb: bool) -> u8 {
    let used = count * bits;
    let len = used.div_ceil(8);
    let pad = 8 * len - used;
    let last = bytes.get(len.wrapping_sub(1)).copied().unwrap_or(0);
    if pad == 0 {
        0
    } else if lsb {
        last & (0xFFu8 << (8 - pad))
    } else {
        last & (0xFFu8 >> (8 - pad))
    }
}

/// Writes `items` as `count` packed elements of `bits` bits each into `out` (at least
/// `ceil(count × bits / 8)` bytes, which it zeroes first). A list of another length than
/// `count` is refused for `field` as [`EncodeError::WrongCount`], an element wider than `bits`
/// as [`EncodeError::OutOfRange`].
#[inline]
pub fn pack<T: crate::codec::Wire>(
    field: &'static str,
    items: &[T],
    count: usize,
    bits: usize,
    lsb: bool,
    out: &mut [u8],
) -> Result<(), EncodeError> {
    if items.len() != count {
        return Err(EncodeError::WrongCount {
            field,
            min: count,
            max: count,
            found: items.len(),
        });
    }
    let max = (1u64 << bits) - 1;
    let len = (count * bits).div_ceil(8);
    if let Some(o) = out.get_mut(..len) {
        o.fill(0);
    }
    for (k, v) in items.iter().enumerate() {
        let v = v.to_u64();
        if v > max {
            return Err(EncodeError::OutOfRange { field });
        }
        for j in 0..bits {
            let (at, weight, shift) = packed_bit(k, j, bits, lsb);
            if v >> weight & 1 == 1 {
                if let Some(b) = out.get_mut(at) {
                    *b |= 1 << shift;
                }
            }
        }
    }
    Ok(())
}

/// The byte of a `width`-byte number whose 16-bit words travel swapped (`word_order: swapped`)
/// that carries byte `i` of it in its byte order.
#[inline(always)]
pub(crate) fn swap_index(i: usize, width: usize) -> usize {
    (width / 2 - 1 - i / 2) * 2 + i % 2
}

/// `N` elements of `width` bytes each (1 to 8) from `bytes` (a list of a fixed count,
/// `repeat: {count: N}`, of other elements than unsigned ones of 1, 2 or 4 bytes: those go
/// through [`unpack`]): each in its byte order (`le`: least significant byte first), its 16-bit
/// words swapped where `swapped` says (4 and 8 bytes), sign-extended where `signed`, as the
/// interpreter's `ir::Field::packed_elements` reads them. Missing bytes read as 0.
#[inline]
pub fn fixed_elements<T: crate::codec::Wire + Default, const N: usize>(
    bytes: &[u8],
    width: usize,
    le: bool,
    swapped: bool,
    signed: bool,
) -> Repeated<T, N> {
    let mut r = Repeated::<T, N>::new();
    let width = width.clamp(1, 8);
    let swapped = swapped && (width == 4 || width == 8);
    for (k, slot) in r.items.iter_mut().enumerate() {
        let mut b = [0u8; 8];
        for (i, d) in b[..width].iter_mut().enumerate() {
            let j = if swapped { swap_index(i, width) } else { i };
            *d = bytes.get(k * width + j).copied().unwrap_or(0);
        }
        *slot = T::from_i64(crate::codec::int(&b[..width], le, signed));
    }
    r.len = N;
    r
}

/// Writes `items` as `count` elements of `width` bytes each into `out` (at least
/// `count × width` bytes), each in its byte order and word order as [`fixed_elements`] reads
/// them. A list of another length than `count` is refused for `field`.
#[inline]
pub fn write_fixed<T: crate::codec::Wire>(
    field: &'static str,
    items: &[T],
    count: usize,
    width: usize,
    le: bool,
    swapped: bool,
    out: &mut [u8],
) -> Result<(), EncodeError> {
    if items.len() != count {
        return Err(EncodeError::WrongCount {
            field,
            min: count,
            max: count,
            found: items.len(),
        });
    }
    let width = width.clamp(1, 8);
    let swapped = swapped && (width == 4 || width == 8);
    for (c, v) in out.chunks_exact_mut(width).zip(items) {
        let u = v.to_u64();
        for i in 0..width {
            let shift = if le { 8 * i } else { 8 * (width - 1 - i) };
            let j = if swapped { swap_index(i, width) } else { i };
            c[j] = (u >> shift) as u8;
        }
    }
    Ok(())
}

/// Every decoded packed element within its spec range `min..=max` (raw values, compared as
/// its type compares numbers); the error names the byte
/// where the first that is not starts (`at`: where the field does).
#[inline]
pub fn packed_in_range<T: crate::codec::Wire>(
    field: &'static FieldDesc,
    at: usize,
    bits: usize,
    items: &[T],
    min: i64,
    max: i64,
) -> Result<(), DecodeError> {
    for (k, v) in items.iter().enumerate() {
        let found = v.to_i64();
        if !T::within(found, min, max) {
            return Err(DecodeError::OutOfRange {
                field,
                offset: at + k * bits / 8,
                found,
                min,
                max,
                kind: T::KIND,
            });
        }
    }
    Ok(())
}

/// A packed list to encode of its `count` elements ([`EncodeError::WrongCount`]), each within
/// its spec range `min..=max`.
#[inline]
pub fn encode_packed_in_range<T: crate::codec::Wire>(
    field: &'static str,
    items: &[T],
    count: usize,
    min: i64,
    max: i64,
) -> Result<(), EncodeError> {
    if items.len() != count {
        return Err(EncodeError::WrongCount {
            field,
            min: count,
            max: count,
            found: items.len(),
        });
    }
    for v in items {
        let value = v.to_i64();
        if !T::within(value, min, max) {
            return Err(EncodeError::NotInRange {
                field,
                value,
                min,
                max,
                kind: T::KIND,
            });
        }
    }
    Ok(())
}

/// Where `needle` first appears in `hay` (never for an empty needle).
fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() {
        return None;
    }
    hay.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;

    /// A count of one byte gives the stream decoder the same frame length as plain numbers
    /// ([`RepeatAt::count_len`]) as through the repeat, for every count byte and a head that
    /// does not reach it yet.
    #[test]
    fn a_byte_count_gives_the_lengths_the_repeat_gives() {
        static DESC: crate::FieldDesc = crate::FieldDesc {
            message: "m",
            name: "values",
        };
        let field = CountField {
            name: "count",
            at: 2,
            width: 1,
            le: false,
        };
        let mut byte = 0;
        for width in [0, 1, 2, 3, 4, 8] {
            for bytes in [false, true] {
                for (min, max) in [(0, 0), (0, 255), (1, 125), (3, 7), (8, 2000), (16, 16)] {
                    let r = RepeatAt {
                        field: &DESC,
                        base: 5,
                        at: 3,
                        width,
                        le: false,
                        signed: false,
                        count: if bytes {
                            CountBy::Bytes(field)
                        } else {
                            CountBy::Elements(field)
                        },
                        min,
                        max,
                    };
                    let c = r.count_len();
                    byte += usize::from(matches!(c, CountLen::Byte(_)));
                    assert_eq!(c.frame_len(&[1, 2]), r.frame_len(&[1, 2]));
                    for v in 0..=255u8 {
                        let head = [1, 3, v, 0];
                        assert_eq!(c.frame_len(&head), r.frame_len(&head), "{r:?} {v}");
                    }
                }
            }
        }
        // All but the byte counts of 3-byte elements.
        assert_eq!(byte, 66);
    }

    #[test]
    fn holds_at_most_its_capacity_and_compares_only_what_it_holds() {
        let mut a = Repeated::<u16, 3>::from_slice(&[1, 2]).unwrap();
        assert_eq!(a.as_slice(), &[1, 2]);
        assert_eq!(a.len(), 2);
        assert_eq!(a.push(3), Ok(()));
        assert_eq!(a.push(4), Err(4));
        assert_eq!(
            Repeated::<u16, 3>::from_slice(&[1, 2, 3, 4]),
            Err(CapacityError {
                capacity: 3,
                found: 4
            })
        );
        // Stale capacity behind the length is invisible to ==, Debug and iteration.
        let mut b = Repeated::<u16, 3>::from_slice(&[9, 9, 9]).unwrap();
        b.len = 1;
        let c = Repeated::<u16, 3>::from_slice(&[9]).unwrap();
        assert_eq!(b, c);
        assert_ne!(b, Repeated::<u16, 3>::new());
        assert_eq!(format!("{b:?}"), "[9]");
        assert_eq!(b.iter().count(), 1);
        assert!(Repeated::<u8, 0>::new().is_empty());
    }

    #[test]
    fn elements_read_and_write_in_either_byte_order() {
        let r = read_elements::<u16, 4>(&[0x00, 0x07, 0x01, 0x00], 2, false, false).unwrap();
        assert_eq!(r.as_slice(), &[7, 256]);
        let r = read_elements::<u16, 4>(&[0x00, 0x07, 0x01, 0x00], 2, true, false).unwrap();
        assert_eq!(r.as_slice(), &[0x0700, 1]);
        let r = read_elements::<i32, 2>(&[0xFF, 0xFF, 0xFE], 3, false, true).unwrap();
        assert_eq!(r.as_slice(), &[-2]);
        let mut out = [0u8; 6];
        assert_eq!(write_elements(&[-2i32, 5], 3, true, &mut out), 6);
        assert_eq!(out, [0xFE, 0xFF, 0xFF, 0x05, 0x00, 0x00]);
        // Not a whole number of elements, or more than the capacity: refused, not truncated.
        assert!(read_elements::<u16, 4>(&[1, 2, 3], 2, false, false).is_err());
        assert_eq!(
            read_elements::<u8, 2>(&[1, 2, 3], 1, false, false),
            Err(CapacityError {
                capacity: 2,
                found: 3
            })
        );
        assert!(read_elements::<u8, 2>(&[], 0, false, false).is_err());
    }

    #[test]
    fn lists_come_from_fields_checked_and_go_to_visit() {
        let values = [7i64, 256];
        let mut ask = |_: &'static str| Some(FieldValue::List(Elements::I64(&values)));
        let r = list::<u16, 4>(&mut ask, "values", 0, 0xFFFF).unwrap();
        assert_eq!(r.as_slice(), &[7, 256]);
        assert_eq!(r.elements(), Elements::U16(&[7, 256]));
        assert_eq!(r.elements().iter().collect::<std::vec::Vec<_>>(), [7, 256]);
        assert_eq!(
            list::<u16, 1>(&mut ask, "values", 0, 0xFFFF),
            Err(FieldError::TooMany {
                field: "values",
                found: 2,
                max: 1
            })
        );
        assert_eq!(
            list::<u8, 4>(&mut ask, "values", 0, 255),
            Err(FieldError::OutOfRange {
                field: "values",
                value: 256,
                min: 0,
                max: 255
            })
        );
        let mut int = |_: &'static str| Some(FieldValue::Int(1));
        assert_eq!(
            list::<u8, 4>(&mut int, "values", 0, 255),
            Err(FieldError::WrongKind {
                field: "values",
                expected: ValueKind::List
            })
        );
        let mut none = |_: &'static str| None;
        assert_eq!(
            list_bits::<8>(&mut none, "coils"),
            Err(FieldError::Missing { field: "coils" })
        );
        let bits = [1i64, 0, 1];
        let mut ask = |_: &'static str| Some(FieldValue::List(Elements::I64(&bits)));
        let r = list_bits::<1>(&mut ask, "coils").unwrap();
        let packed = Elements::Bits {
            packed: &[0b101],
            len: 3,
        };
        assert_eq!(r.elements(), packed);
        assert_eq!(packed.iter().collect::<std::vec::Vec<_>>(), [1, 0, 1]);
        assert_eq!(packed.get(3), None);
        let nine = [0i64; 9];
        let mut ask = |_: &'static str| Some(FieldValue::List(Elements::I64(&nine)));
        assert_eq!(
            list_bits::<1>(&mut ask, "coils"),
            Err(FieldError::TooMany {
                field: "coils",
                found: 9,
                max: 8
            })
        );
        let two = [2i64];
        let mut ask = |_: &'static str| Some(FieldValue::List(Elements::I64(&two)));
        assert!(matches!(
            list_bits::<1>(&mut ask, "coils"),
            Err(FieldError::OutOfRange { value: 2, .. })
        ));
        assert_eq!(
            format!(
                "{}",
                FieldError::TooMany {
                    field: "x",
                    found: 3,
                    max: 2
                }
            ),
            "x holds at most 2 elements, got 3"
        );
    }

    #[test]
    fn bits_pack_least_significant_first() {
        // Modbus application protocol 6.1: coils 20..=38, status CD 6B 05.
        let r = read_bits::<3>(&[0xCD, 0x6B, 0x05]).unwrap();
        assert_eq!(r.len(), 24);
        assert_eq!(
            r.iter().take(8).collect::<std::vec::Vec<_>>(),
            [true, false, true, true, false, false, true, true]
        );
        let mut out = [0xFFu8; 4];
        assert_eq!(write_bits(&r, &mut out), 3);
        assert_eq!(out, [0xCD, 0x6B, 0x05, 0xFF]);
        assert!(read_bits::<1>(&[0, 0]).is_err());
        // Built bit by bit: the padding stays zero, so equal bits are equal values.
        let bools: std::vec::Vec<bool> = r.iter().take(19).collect();
        let b = Bits::<3>::from_bools(&bools).unwrap();
        assert_eq!(b.as_bytes(), &[0xCD, 0x6B, 0x05]);
        assert_eq!(b.len(), 19);
        assert_ne!(b, r);
        assert_eq!(
            format!("{:?}", Bits::<1>::from_bools(&[true, false]).unwrap()),
            "[1, 0]"
        );
        assert_eq!(
            Bits::<1>::from_bools(&[false; 9]),
            Err(CapacityError {
                capacity: 8,
                found: 9
            })
        );
        assert_eq!(Bits::<1>::new().get(0), None);
    }

    /// CRSF's RC channels: 16 × 11 bits, channel 1 from bit 0 of the first byte; and 5 × 3
    /// bits most significant bit first, with its padding bit; each read back as written, a
    /// wrong count or an element past its bits refused.
    #[test]
    fn packed_elements_read_back_as_written() {
        let ch: [u16; 16] = [
            992, 992, 992, 992, 172, 1811, 992, 992, 992, 992, 992, 992, 992, 992, 992, 992,
        ];
        let mut out = [0xFFu8; 22];
        pack("channels", &ch, 16, 11, true, &mut out).unwrap();
        assert_eq!(&out[..4], &[0xE0, 0x03, 0x1F, 0xF8]);
        let back = unpack::<u16, 16>(&out, 11, true);
        assert_eq!(back.as_slice(), &ch);
        assert_eq!(packed_padding(&out, 16, 11, true), 0);

        let levels: [u8; 5] = [1, 2, 3, 4, 5];
        let mut out = [0u8; 2];
        pack("levels", &levels, 5, 3, false, &mut out).unwrap();
        assert_eq!(out, [0x29, 0xCA]);
        assert_eq!(unpack::<u8, 5>(&out, 3, false).as_slice(), &levels);
        assert_eq!(packed_padding(&[0x29, 0xCB], 5, 3, false), 1);

        // A wrong count in the interpreter's words (it was a value out of range), an element
        // past its bits as a value out of range.
        let count = EncodeError::WrongCount {
            field: "levels",
            min: 5,
            max: 5,
            found: 4,
        };
        assert_eq!(
            pack("levels", &levels[..4], 5, 3, false, &mut out),
            Err(count)
        );
        assert_eq!(
            write_fixed("levels", &levels[..4], 5, 1, false, false, &mut out),
            Err(count)
        );
        assert_eq!(
            encode_packed_in_range("levels", &levels[..4], 5, 0, 7),
            Err(count)
        );
        assert_eq!(
            pack("levels", &[1u8, 2, 3, 4, 8], 5, 3, false, &mut out),
            Err(EncodeError::OutOfRange { field: "levels" })
        );
    }
}

//! [`Ascii`], a fixed-length text field (`type: ascii` with `length:`) as generated code carries
//! it: its bytes exactly as the frame holds them (padding included, nothing checked or
//! trimmed), shown as text.

use core::fmt;
use core::ops::{Deref, DerefMut};

/// A text field of exactly `N` bytes (`type: ascii`, `length: N`), as the frame holds them.
///
/// The bytes are the field's; nothing is checked or trimmed, so encode writes back what decode
/// read. [`Ascii::as_str`] reads them as text where all are ASCII, `Debug` and `Display` show them as text with
/// any byte outside printable ASCII escaped (`"SD\x00\x00"`), and the array is there through
/// `Deref` or the public field:
///
/// ```
/// use busspec_runtime::Ascii;
///
/// let firmware = Ascii(*b"2.10\0\0");
/// assert_eq!(format!("{firmware:?}"), r#""2.10\x00\x00""#);
/// assert_eq!(firmware.as_str(), Some("2.10\0\0"));
/// assert_eq!(firmware.trim_end(), b"2.10");
/// assert_eq!(firmware.len(), 6);
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
#[repr(transparent)]
pub struct Ascii<const N: usize>(pub [u8; N]);

impl<const N: usize> Ascii<N> {
    /// The field's bytes.
    pub const fn as_bytes(&self) -> &[u8; N] {
        &self.0
    }

    /// The field's bytes as text where every one is ASCII (0x00..=0x7F); `None` where one is
    /// not (busspec's JSON reads such a byte as the character of its value, U+0080..U+00FF,
    /// which a `&str` of these bytes cannot be).
    pub fn as_str(&self) -> Option<&str> {
        if self.0.is_ascii() {
            core::str::from_utf8(&self.0).ok()
        } else {
            None
        }
    }

    /// The bytes without the padding a device puts after shorter text: trailing NUL bytes and
    /// spaces.
    pub fn trim_end(&self) -> &[u8] {
        let end = self
            .0
            .iter()
            .rposition(|&b| b != 0 && b != b' ')
            .map_or(0, |i| i + 1);
        &self.0[..end]
    }
}

impl<const N: usize> Default for Ascii<N> {
    /// `N` NUL bytes.
    fn default() -> Self {
        Ascii([0; N])
    }
}

impl<const N: usize> Deref for Ascii<N> {
    type Target = [u8; N];

    fn deref(&self) -> &[u8; N] {
        &self.0
    }
}

impl<const N: usize> DerefMut for Ascii<N> {
    fn deref_mut(&mut self) -> &mut [u8; N] {
        &mut self.0
    }
}

impl<const N: usize> AsRef<[u8]> for Ascii<N> {
    fn as_ref(&self) -> &[u8] {
        &self.0
    }
}

impl<const N: usize> From<[u8; N]> for Ascii<N> {
    fn from(bytes: [u8; N]) -> Self {
        Ascii(bytes)
    }
}

impl<const N: usize> From<Ascii<N>> for [u8; N] {
    fn from(text: Ascii<N>) -> Self {
        text.0
    }
}

impl<const N: usize> PartialEq<[u8; N]> for Ascii<N> {
    fn eq(&self, other: &[u8; N]) -> bool {
        self.0 == *other
    }
}

impl<const N: usize> fmt::Display for Ascii<N> {
    /// The text, any byte outside printable ASCII escaped as `\xNN` (`\t`, `\n`, `\r`, `\'`,
    /// `\"` and `\\` as such).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0.escape_ascii(), f)
    }
}

impl<const N: usize> fmt::Debug for Ascii<N> {
    /// The text in quotes, escaped as `Display` escapes it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "\"{}\"", self.0.escape_ascii())
    }
}

/// In a human-readable format (JSON) text where every byte is ASCII, else the bytes; in any
/// other format, the bytes.
#[cfg(feature = "serde")]
impl<const N: usize> serde::Serialize for Ascii<N> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.as_str() {
            Some(text) if s.is_human_readable() => s.serialize_str(text),
            _ => s.serialize_bytes(&self.0),
        }
    }
}

/// Text, bytes or a sequence of bytes, exactly `N` bytes of them (what `Serialize` writes).
#[cfg(feature = "serde")]
impl<'de, const N: usize> serde::Deserialize<'de> for Ascii<N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Text<const N: usize>;
        impl<'de, const N: usize> serde::de::Visitor<'de> for Text<N> {
            type Value = Ascii<N>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "text of {N} bytes")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Ascii<N>, E> {
                self.visit_bytes(v.as_bytes())
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<Ascii<N>, E> {
                v.try_into()
                    .map(Ascii)
                    .map_err(|_| E::invalid_length(v.len(), &self))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Ascii<N>, A::Error> {
                let mut out = [0u8; N];
                for (i, b) in out.iter_mut().enumerate() {
                    *b = seq
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<u8>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(N + 1, &self));
                }
                Ok(Ascii(out))
            }
        }
        if d.is_human_readable() {
            d.deserialize_any(Text::<N>)
        } else {
            d.deserialize_bytes(Text::<N>)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    extern crate std;
    use std::format;
    #[cfg(feature = "serde")]
    use std::string::ToString;

    #[test]
    fn shows_its_bytes_as_text_and_keeps_them() {
        let t = Ascii(*b"SD\x00\xFF");
        assert_eq!(format!("{t:?}"), r#""SD\x00\xff""#);
        assert_eq!(format!("{t}"), r"SD\x00\xff");
        assert_eq!(t.as_str(), None);
        // Bytes that are UTF-8 but not ASCII are not text here.
        assert_eq!(Ascii(*b"\xC3\xA9").as_str(), None);
        assert_eq!(t.trim_end(), b"SD\x00\xFF");
        assert_eq!(<[u8; 4]>::from(t), *b"SD\x00\xFF");
        assert_eq!(Ascii(*b"  \0").trim_end(), b"");
        assert_eq!(Ascii(*b"a b \0").trim_end(), b"a b");
        assert_eq!(Ascii::<3>::default(), [0u8; 3]);
    }

    #[cfg(feature = "serde")]
    #[test]
    fn serde_carries_text_where_it_is_text_and_bytes_where_not() {
        let t = Ascii(*b"1.20");
        let json = serde_json::to_string(&t).unwrap();
        assert_eq!(json, r#""1.20""#);
        assert_eq!(serde_json::from_str::<Ascii<4>>(&json).unwrap(), t);
        let raw = Ascii([0x31, 0xFF]);
        let json = serde_json::to_string(&raw).unwrap();
        assert_eq!(json, "[49,255]");
        assert_eq!(serde_json::from_str::<Ascii<2>>(&json).unwrap(), raw);
        let short = serde_json::from_str::<Ascii<4>>(r#""1.2""#).unwrap_err();
        assert!(short.to_string().contains("text of 4 bytes"), "{short}");
        assert!(serde_json::from_str::<Ascii<2>>("[1,2,3]").is_err());
    }
}

//! Random valid specs, covering the spec language as `spec/SCHEMA.md` describes it.
//!
//! A spec is built valid by construction in two passes: the spec without examples (framing,
//! units, enums, flags, commands, responses), loaded and validated; then its examples, each
//! derived by encoding random values with the interpreter and kept only where the frame decodes
//! on its own (or as the reply to its `reply_to`) as the message it shows, as the validator
//! replays it. [`random_spec`] is deterministic in its seed.

use std::fmt::Write as _;

use busspec_model::checksum;
use busspec_model::interp::{self, Raw};
use busspec_model::ir::{self, ChecksumAlgorithm, CrcParams, Direction, MessageRef, Part};

use crate::values::random_values;

const INT_TYPES: [(&str, usize, bool); 8] = [
    ("u8", 1, false),
    ("u16", 2, false),
    ("u24", 3, false),
    ("u32", 4, false),
    ("i8", 1, true),
    ("i16", 2, true),
    ("i24", 3, true),
    ("i32", 4, true),
];

const UNITS: [(&str, &str, Option<&str>); 5] = [
    ("count", "1", None),
    ("centi", "0.01", None),
    ("angle", "360/4096", None),
    ("celsius", "0.5", Some("-40")),
    ("double", "2", None),
];

/// A field as generated: its YAML and what later fields may do with it.
#[derive(Clone)]
struct Gf {
    name: String,
    ty: &'static str,
    width: usize,
    yaml: String,
    /// No bits, not ascii, not repeated: a `follows` source, or an `equals` target.
    plain: bool,
    /// A plain unsigned number with a unit: a count field, a request field a reply follows.
    countable: bool,
    repeat_tail: usize,
}

struct Gm {
    name: String,
    code: Vec<u8>,
    fields: Vec<Gf>,
    extra: String,
}

/// Whether `f` is a list of a fixed count (`repeat: {count: 3}`), which has a fixed size.
fn fixed_count(f: &Gf) -> bool {
    f.yaml.split("repeat: {count: ").nth(1).is_some_and(|r| {
        let digits = r.chars().take_while(char::is_ascii_digit).count();
        digits > 0 && r[digits..].starts_with('}')
    })
}

impl Gm {
    fn fixed(&self) -> usize {
        self.fields
            .iter()
            .filter(|f| f.repeat_tail == 0 && (!f.yaml.contains("repeat:") || fixed_count(f)))
            .map(|f| f.width)
            .sum()
    }
    fn tail(&self) -> usize {
        self.fields.iter().map(|f| f.repeat_tail).sum()
    }
    /// The bytes of its optional fields (`present:`), all present.
    fn optional(&self) -> usize {
        self.fields
            .iter()
            .filter(|f| f.yaml.contains("present:"))
            .map(|f| f.width)
            .sum()
    }
}

/// Whether `f` may be an optional field's condition: an unsigned binary integer always on the
/// wire (a constant or sub-fields too), no list, not derived from another field.
fn condition_target(f: &Gf) -> bool {
    matches!(f.ty, "u8" | "u16" | "u24" | "u32")
        && f.repeat_tail == 0
        && [
            "repeat",
            "packed:",
            "encoding",
            "word_order",
            "equals:",
            "follows:",
            "present:",
        ]
        .iter()
        .all(|k| !f.yaml.contains(k))
}

/// Whether `f` is a list a random spec may turn into counted text: plain `u8` elements with a
/// unit (no range, enum or record), its count not from the request.
fn counted_text_eligible(f: &Gf) -> bool {
    // The list's own type, not a field of a record's (a record of one u8 field is a u8 list
    // too, and its record text must stay whole).
    f.ty == "u8"
        && f.repeat_tail > 0
        && f.yaml
            .starts_with(&format!("{{name: {}, type: u8, unit: ", f.name))
        && !f.yaml.contains("range:")
        && !f.yaml.contains("request:")
}

/// Code-less messages beside others of their direction are told apart by a constant first
/// byte, as Pelco-D's `ptz` is by a constant bit (the validator refuses them otherwise): a
/// value no code of the direction starts with, one per code-less message, shared by the two
/// responses of a `needs_request` pair.
fn tag_codeless(ms: &mut [Gm]) {
    if ms.len() < 2 || !ms.iter().any(|m| m.code.is_empty()) {
        return;
    }
    let mut taken: Vec<u8> = ms.iter().filter_map(|m| m.code.first().copied()).collect();
    let mut paired: Option<u8> = None;
    for m in ms.iter_mut().filter(|m| m.code.is_empty()) {
        let pair = m.extra.contains("needs_request");
        let v = match paired.take() {
            Some(v) if pair => v,
            _ => {
                let v = (0..=255u8).rev().find(|b| !taken.contains(b)).unwrap_or(0);
                taken.push(v);
                if pair {
                    paired = Some(v);
                }
                v
            }
        };
        m.fields.insert(
            0,
            Gf {
                name: "tag".into(),
                ty: "u8",
                width: 1,
                yaml: format!("{{name: tag, type: u8, value: {v}}}"),
                plain: false,
                countable: false,
                repeat_tail: 0,
            },
        );
    }
}

struct G {
    rng: fastrand::Rng,
    n_enums: usize,
    n_flags: usize,
    /// Frames have a length field: a message may end in records whose width a field gives.
    sized: bool,
    /// Drawn for payload truncation (`Own::Truncation`): a length field, no lists and no
    /// optional fields, so every message has one length.
    fixed: bool,
    /// Whether a field as drawn becomes a list of a fixed count of it (`Own::FixedElements`):
    /// a generator of its own, so the fields are drawn as they were.
    fixed_elements: fastrand::Rng,
    /// Whether a 32-bit CRC as drawn becomes a 24-bit one (`Own::Crc24`).
    crc24: fastrand::Rng,
    /// Whether an 8-bit sum or XOR as drawn becomes FrSky's end-around sum (`Own::EndAround`).
    end_around: fastrand::Rng,
}

/// The types a record's field may have: name, bytes, signed.
const RECORD_FIELD_TYPES: [(&str, usize, bool); 8] = [
    ("u8", 1, false),
    ("i8", 1, true),
    ("u16", 2, false),
    ("i16", 2, true),
    ("u24", 3, false),
    ("i24", 3, true),
    ("u32", 4, false),
    ("i32", 4, true),
];

fn limits(width: usize, signed: bool) -> (i64, i64) {
    interp::raw_limits(8 * width as u32, signed)
}

fn code_text(code: &[u8]) -> String {
    let mut s = String::from("0x");
    for b in code {
        let _ = write!(s, "{b:02X}");
    }
    if code.is_empty() {
        s.clear();
    }
    s
}

/// A type whose raw value is its bits (64-bit integers, floats): never copied, counted or
/// followed.
/// A field another may repeat (`equals`): one value, neither text, wide nor a list.
fn equals_target(f: &Gf) -> bool {
    f.ty != "ascii"
        && !is_wide(f.ty)
        && f.repeat_tail == 0
        && !fixed_count(f)
        && !f.yaml.contains("packed:")
        && !f.yaml.contains("encoding: bcd")
}

fn is_wide(ty: &str) -> bool {
    matches!(ty, "u64" | "i64" | "f32" | "f64")
}

/// What is drawn from a generator of its own, each seeded by the spec's seed XOR its salt, so a
/// construct added to the generator leaves every spec drawn without it as it was (the stream
/// of `G::rng` unchanged). A new construct takes a new salt here.
#[derive(Clone, Copy)]
#[repr(u64)]
enum Own {
    /// The examples, drawn after the spec text is complete.
    Examples = 0x5EED_E8A3_71E5,
    /// Optional fields (`present:`).
    Optionals = 0x0971_0971_0971_0971,
    /// Counted text (`type: ascii` with `repeat`).
    CountedText = 0x7E47_7E47_7E47_7E47,
    /// A preamble of wake-up bytes.
    Preamble = 0xFEFE_FEFE_FEFE_FEFE,
    /// A per-byte transform of the payload.
    Transform = 0x3333_3333_3333_3333,
    /// Whether an eligible spec takes a long length form.
    TakesLongForm = 0x0302_0302_0302_0302,
    /// The long length form: its start byte, its length's adjustment.
    LongForm = 0x0303_0303_0303_0303,
    /// Text up to a terminator (`repeat: {until}`), from counted text.
    TerminatedText = 0x0000_5A5A_0000_5A5A,
    /// Text up to a terminator in frames without a length field, which only its terminator
    /// ends, from counted text.
    TerminatedFrame = 0x5A00_5A00_5A00_5A00,
    /// A short form of the frame (`framing.forms`): whether an eligible spec takes one, its
    /// start byte.
    ShortForm = 0x1068_1068_1068_1068,
    /// A payload longer than 255 bytes: whether a spec takes one, the list and its new most.
    BigPayload = 0x0100_0100_0100_0100,
    /// Lists of a fixed count (`repeat: {count: N}`), from packed elements of whole bytes.
    FixedList = 0xF1ED_F1ED_F1ED_F1ED,
    /// Lists of a fixed count of any number type (signed, 24- and 64-bit, floats, enum and
    /// unit elements), from fields as drawn.
    FixedElements = 0xF1ED_E1E5_F1ED_E1E5,
    /// Payload truncation (`framing.truncation`, MAVLink v2): whether a spec tries it.
    Truncation = 0x00FD_00FD_00FD_00FD,
    /// A layout per direction (`framing.layout: {request, response}`, SHDLC): whether a spec
    /// tries one, and how the two directions' layouts differ.
    LayoutByDirection = 0x7E5D_7E5D_7E5D_7E5D,
    /// Responses without start or end bytes beside flagged, escaped requests (F.Port's
    /// uplink): whether an eligible spec tries them.
    BareResponses = 0x0881_7E7E_0881_7E7E,
    /// Frames only end bytes delimit: whether an eligible spec drops its checksum, its end
    /// bytes.
    EndDelimited = 0xFFFF_FF00_FFFF_FF00,
    /// A 24-bit CRC (RTCM 3's CRC-24Q) in place of a 32-bit one as drawn.
    Crc24 = 0x0086_4CFB_0086_4CFB,
    /// Records of a fixed count (`type: record`, `repeat: {count: N}`), from records as drawn.
    FixedRecords = 0xF1ED_2EC0_F1ED_2EC0,
    /// Lists of floats and 64-bit integers (counted, in bytes, to the end, by the request),
    /// from lists of integers as drawn.
    WideLists = 0x64F3_64F3_64F3_64F3,
    /// Replies whose checksum takes in their request's bytes (`checksum_over_request`, Pelco
    /// D's general response): whether a spec tries them, which replies, from which part.
    OverRequest = 0x00FF_0121_00FF_0121,
    /// Messages without a checksum (`checksum: none`, RoboClaw's reads): whether a spec tries
    /// them, and which messages.
    Unchecked = 0x8010_8010_8010_8010,
    /// Responses sent unasked (`unasked: true`): a reply made also sent unasked, a response
    /// no command lists.
    Unasked = 0x0A5E_0A5E_0A5E_0A5E,
    /// FrSky's end-around-carry sum (`sum8_end_around`, S.Port and F.Port) in place of an 8-bit
    /// sum or XOR as drawn, masked or not.
    EndAround = 0x7E7D_5E5D_7E7D_5E5D,
    /// A message's own values for its header fields (`header:`, JBD's request state and reply
    /// status): whether a spec tries them, which messages, which fields, which values.
    HeaderValues = 0xA55A_A55A_A55A_A55A,
    /// A checksum before the bytes it covers (Septentrio SBF's CRC at offset 2): whether a
    /// spec tries it, and where it goes.
    ChecksumLead = 0x5BF0_2440_5BF0_2440,
    /// A checksum before the payload covering from a part before it too (HerkuleX's, from its
    /// size byte): whether a spec with a checksum before the payload tries it, from which
    /// part.
    ChecksumAround = 0x4E5C_0707_4E5C_0707,
    /// A checksum followed by its complement (`complement: true`, HerkuleX's CS2): whether a
    /// spec tries it.
    ChecksumComplement = 0xC5C2_FEFE_C5C2_FEFE,
    /// DLE stuffing (Garmin's serial link, TSIP): whether a spec takes it in place of the
    /// escaping it drew.
    Doubled = 0x1010_1003_1010_1003,
}

/// The generator of `what` for the spec of `seed`.
fn own_rng(seed: u64, what: Own) -> fastrand::Rng {
    fastrand::Rng::with_seed(seed ^ what as u64)
}

impl G {
    /// Runs `f` with the generator of `what` in place of the spec's own, which is put back
    /// after: what `f` draws leaves the rest of the spec as it was.
    fn with_own<R>(&mut self, seed: u64, what: Own, f: impl FnOnce(&mut G) -> R) -> R {
        let spec_rng = std::mem::replace(&mut self.rng, own_rng(seed, what));
        let r = f(self);
        self.rng = spec_rng;
        r
    }

    fn pick<'a, T>(&mut self, xs: &'a [T]) -> &'a T {
        &xs[self.rng.usize(..xs.len())]
    }

    fn chance(&mut self, percent: u8) -> bool {
        self.rng.u8(..100) < percent
    }

    fn unit(&mut self) -> &'static str {
        self.pick(&UNITS).0
    }

    fn range_yaml(&mut self, lo: i64, hi: i64) -> String {
        let a = self.rng.i64(lo..=hi);
        let b = self.rng.i64(a..=hi);
        // Often a narrow range near zero, where random values land outside it.
        if self.chance(50) && lo <= 0 && hi >= 10 {
            let a = self.rng.i64(lo.max(-5)..=3);
            return format!(
                "range: {{min: {a}, max: {}}}",
                (a + self.rng.i64(0..=20)).min(hi)
            );
        }
        format!("range: {{min: {a}, max: {b}}}")
    }

    /// A header field every message carries (`framing.header`): an integer of 1 to 4 bytes
    /// with a unit (maybe a range and a special value), an enum or flags. Its YAML and width.
    fn header_field(&mut self, name: String) -> (String, usize) {
        let &(ty, width, signed) = self.pick(&INT_TYPES);
        let (lo, hi) = limits(width, signed);
        match self.rng.u8(..100) {
            0..=19 if self.n_enums > 0 => {
                let e = self.rng.usize(..self.n_enums);
                (format!("{{name: {name}, type: u8, enum: e{e}}}"), 1)
            }
            20..=29 if self.n_flags > 0 => (format!("{{name: {name}, type: u16, flags: fl0}}"), 2),
            // A constant every frame holds (a header's own length, a reserved byte).
            50..=59 => {
                let (ty, width) = if self.rng.bool() {
                    ("u8", 1)
                } else {
                    ("u16", 2)
                };
                let v = self.rng.u64(..1 << (8 * width));
                (
                    format!("{{name: {name}, type: {ty}, value: {v:#X}}}"),
                    width,
                )
            }
            // Sub-fields (MSP v2's flag byte), some of them constant.
            30..=49 => {
                for _ in 0..64 {
                    let f = self.field(name.clone(), &[]);
                    if f.yaml.contains(", bits: [") {
                        return (f.yaml, f.width);
                    }
                }
                (format!("{{name: {name}, type: u8, unit: count}}"), 1)
            }
            _ => {
                let mut y = format!("{{name: {name}, type: {ty}, unit: {}", self.unit());
                self.range_and_special(&mut y, &name, (lo, hi), (40, 15));
                y.push('}');
                (y, width)
            }
        }
    }

    /// A plain number's optional keys, appended to its YAML `y`: a range within `lo..=hi`
    /// and a special value, each with its odds (percent).
    fn range_and_special(
        &mut self,
        y: &mut String,
        name: &str,
        (lo, hi): (i64, i64),
        (range, special): (u8, u8),
    ) {
        if self.chance(range) {
            let r = self.range_yaml(lo, hi);
            let _ = write!(y, ", {r}");
        }
        if self.chance(special) {
            let v = self.rng.i64(lo..=hi);
            let _ = write!(y, ", special: [{{value: {v}, name: sp_{name}}}]");
        }
    }

    /// Optional fields (`present:`) for the messages of one direction that may have them (a
    /// code of their own, not from the request, no list, a direction whose every message has
    /// a code), about 13 % of them: 1 to 4 plain numbers after the message's fields, each on
    /// a bit or a value of an earlier unsigned field (one of the message's, or one added).
    fn optionals(&mut self, ms: &mut [Gm]) {
        if ms.iter().any(|m| m.code.is_empty()) {
            return;
        }
        let codes: Vec<Vec<u8>> = ms.iter().map(|m| m.code.clone()).collect();
        for m in ms.iter_mut() {
            let own_code = codes.iter().filter(|c| **c == m.code).count() == 1;
            let listless = m
                .fields
                .iter()
                .all(|f| f.repeat_tail == 0 && !f.yaml.contains("repeat"));
            if !own_code || !listless || m.extra.contains("code_from_request") {
                continue;
            }
            if !self.chance(13) {
                continue;
            }
            let targets: Vec<usize> = (0..m.fields.len())
                .filter(|&i| condition_target(&m.fields[i]))
                .collect();
            let mut on: Vec<(String, usize)> = targets
                .iter()
                .filter(|_| self.chance(50))
                .map(|&i| (m.fields[i].name.clone(), m.fields[i].width))
                .collect();
            if on.is_empty() {
                let (ty, width) = *self.pick(&[("u8", 1), ("u8", 1), ("u16", 2), ("u24", 3)]);
                let kind = match self.rng.u8(..100) {
                    0..=29 if self.n_flags > 0 => {
                        format!("flags: fl{}", self.rng.usize(..self.n_flags))
                    }
                    30..=49 if self.n_enums > 0 && width <= 2 => {
                        format!("enum: e{}", self.rng.usize(..self.n_enums))
                    }
                    _ => "unit: count".to_owned(),
                };
                m.fields.push(Gf {
                    name: "pc".into(),
                    ty,
                    width,
                    yaml: format!("{{name: pc, type: {ty}, {kind}}}"),
                    plain: true,
                    countable: false,
                    repeat_tail: 0,
                });
                on.push(("pc".into(), width));
            }
            for k in 0..self.rng.usize(1..=4) {
                let name = format!("o{k}");
                let (of, width) = self.pick(&on).clone();
                let when = if self.chance(60) {
                    format!(
                        "bit: {}",
                        self.rng
                            .usize(..8 * width)
                            .min(if self.chance(70) { 3 } else { 63 })
                    )
                } else {
                    let top = limits(width, false).1;
                    let v = if self.chance(70) {
                        self.rng.i64(0..=3)
                    } else {
                        self.rng.i64(0..=top)
                    };
                    format!("equals: {v}")
                };
                let mut f = if self.chance(15) {
                    self.wide_field(name.clone())
                } else {
                    let &(ty, width, signed) = self.pick(&INT_TYPES);
                    let (lo, hi) = limits(width, signed);
                    let mut y = match self.rng.u8(..100) {
                        0..=9 if self.n_enums > 0 && !signed && width <= 2 => {
                            format!(
                                "{{name: {name}, type: {ty}, enum: e{}",
                                self.rng.usize(..self.n_enums)
                            )
                        }
                        10..=19 if self.n_flags > 0 && !signed && width <= 2 => {
                            format!(
                                "{{name: {name}, type: {ty}, flags: fl{}",
                                self.rng.usize(..self.n_flags)
                            )
                        }
                        _ => {
                            let mut y =
                                format!("{{name: {name}, type: {ty}, unit: {}", self.unit());
                            if width == 4 && self.chance(20) {
                                y.push_str(", word_order: swapped");
                            }
                            self.range_and_special(&mut y, &name, (lo, hi), (40, 20));
                            y
                        }
                    };
                    y.push('}');
                    Gf {
                        name,
                        ty,
                        width,
                        yaml: y,
                        plain: false,
                        countable: false,
                        repeat_tail: 0,
                    }
                };
                // `present` inside the mapping, before its closing brace.
                f.yaml.pop();
                let _ = write!(f.yaml, ", present: {{field: {of}, {when}}}}}");
                f.plain = false;
                m.fields.push(f);
            }
        }
    }

    /// One field that is not repeated. `earlier`: the fields before it.
    /// A field ([`Self::drawn_field`]), in about one in eight where it may be (a number of
    /// any type, maybe of an enum, a unit, a range, flags or its words swapped; no constant,
    /// copy, sub-fields, special values or relation) a list of a fixed count of 1 to 4 of it.
    fn field(&mut self, name: String, earlier: &[Gf]) -> Gf {
        let mut f = self.drawn_field(name, earlier);
        let eligible = f.repeat_tail == 0
            && f.yaml.ends_with('}')
            && [
                "repeat",
                "packed:",
                "value:",
                "equals:",
                "bits:",
                "special:",
                "follows:",
                "encoding",
                "present:",
                "type: ascii",
                "type: bit",
                "type: record",
            ]
            .iter()
            .all(|k| !f.yaml.contains(k));
        if eligible && self.fixed_elements.u8(..100) < 12 {
            let n = self.fixed_elements.usize(1..=4);
            f.yaml.pop();
            let _ = write!(f.yaml, ", repeat: {{count: {n}}}}}");
            f.width *= n;
            f.plain = false;
            f.countable = false;
        }
        f
    }

    fn drawn_field(&mut self, name: String, earlier: &[Gf]) -> Gf {
        let &(ty, width, signed) = self.pick(&INT_TYPES);
        let (lo, hi) = limits(width, signed);
        let plain_unsigned = |ty: &'static str, width, yaml: String, name: String| Gf {
            name,
            ty,
            width,
            yaml,
            plain: true,
            countable: false,
            repeat_tail: 0,
        };
        if self.chance(10) {
            return self.wide_field(name);
        }
        if self.chance(6) {
            return self.packed_field(name);
        }
        if self.chance(6) {
            return self.bcd_field(name);
        }
        match self.rng.u8(..100) {
            // A plain number: unit, maybe a range and special values.
            0..=29 => {
                let mut y = format!("{{name: {name}, type: {ty}, unit: {}", self.unit());
                if width == 4 && self.chance(30) {
                    y.push_str(", word_order: swapped");
                }
                self.range_and_special(&mut y, &name, (lo, hi), (50, 25));
                y.push('}');
                let mut g = plain_unsigned(ty, width, y, name);
                g.countable = !signed && !g.yaml.contains("range") && width <= 2;
                g
            }
            // A constant.
            30..=41 => {
                let (_, top) = limits(width, false);
                let v = if self.chance(50) {
                    self.rng.i64(0..=3)
                } else {
                    self.rng.i64(0..=top)
                };
                plain_unsigned(
                    ty,
                    width,
                    format!("{{name: {name}, type: {ty}, value: {v}}}"),
                    name,
                )
            }
            // An enum, maybe with a range.
            42..=51 if self.n_enums > 0 => {
                let (ty, width) = *self.pick(&[("u8", 1), ("u16", 2)]);
                let e = self.rng.usize(..self.n_enums);
                let mut y = format!("{{name: {name}, type: {ty}, enum: e{e}");
                if self.chance(30) {
                    let _ = write!(y, ", range: {{min: 0, max: {}}}", self.rng.u8(1..8));
                }
                y.push('}');
                plain_unsigned(ty, width, y, name)
            }
            // Flags.
            52..=59 if self.n_flags > 0 => {
                let (ty, width) = *self.pick(&[("u8", 1), ("u16", 2)]);
                let fl = self.rng.usize(..self.n_flags);
                plain_unsigned(
                    ty,
                    width,
                    format!("{{name: {name}, type: {ty}, flags: fl{fl}}}"),
                    name,
                )
            }
            // Packed bits.
            60..=71 => {
                let (ty, width) = *self.pick(&[("u8", 1), ("u16", 2), ("u24", 3), ("u32", 4)]);
                let total = 8 * width as i64;
                let mut msb = total - 1;
                let mut subs = Vec::new();
                let mut k = 0;
                while msb >= 0 {
                    let w = self.rng.i64(1..=(msb + 1).min(12));
                    let lsb = msb - w + 1;
                    let sub = format!("{name}_b{k}");
                    k += 1;
                    let s = if self.chance(25) {
                        let v = self.rng.i64(0..=(1i64 << w) - 1);
                        format!("{{name: {sub}, msb: {msb}, lsb: {lsb}, value: {v}}}")
                    } else {
                        let signed = w >= 2 && self.chance(30);
                        let mut s = format!(
                            "{{name: {sub}, msb: {msb}, lsb: {lsb}, unit: {}",
                            self.unit()
                        );
                        if signed {
                            s.push_str(", signed: true");
                        }
                        if self.chance(25) {
                            let (a, b) = interp::raw_limits(w as u32, signed);
                            let r = self.range_yaml(a, b);
                            let _ = write!(s, ", {r}");
                        }
                        s.push('}');
                        s
                    };
                    subs.push(s);
                    msb = lsb - 1;
                }
                Gf {
                    name: name.clone(),
                    ty,
                    width,
                    yaml: format!("{{name: {name}, type: {ty}, bits: [{}]}}", subs.join(", ")),
                    plain: false,
                    countable: false,
                    repeat_tail: 0,
                }
            }
            // A repeat of an earlier field.
            72..=77 if earlier.iter().any(equals_target) => {
                let cands: Vec<&Gf> = earlier.iter().filter(|f| equals_target(f)).collect();
                let o = *self.pick(&cands);
                Gf {
                    name: name.clone(),
                    ty: o.ty,
                    width: o.width,
                    yaml: format!("{{name: {name}, type: {}, equals: {}}}", o.ty, o.name),
                    plain: false,
                    countable: false,
                    repeat_tail: 0,
                }
            }
            // A value following an earlier field.
            78..=85 if earlier.iter().any(|f| f.plain) => {
                let cands: Vec<&Gf> = earlier.iter().filter(|f| f.plain).collect();
                let o = *self.pick(&cands);
                let (ty, width) = *self.pick(&[("u8", 1), ("u16", 2), ("u32", 4)]);
                let m = self.rng.u8(1..=4);
                let d = self.rng.u8(1..=8);
                Gf {
                    name: name.clone(),
                    ty,
                    width,
                    yaml: format!(
                        "{{name: {name}, type: {ty}, follows: {{field: {}, multiply: {m}, divide: {d}}}}}",
                        o.name
                    ),
                    plain: false,
                    countable: false,
                    repeat_tail: 0,
                }
            }
            // Text.
            86..=90 => {
                let n = self.rng.usize(1..=4);
                Gf {
                    name: name.clone(),
                    ty: "ascii",
                    width: n,
                    yaml: format!("{{name: {name}, type: ascii, length: {n}}}"),
                    plain: false,
                    countable: false,
                    repeat_tail: 0,
                }
            }
            // A count-like number (a plain unsigned byte with a unit).
            _ => {
                let y = format!("{{name: {name}, type: u8, unit: count}}");
                let mut g = plain_unsigned("u8", 1, y, name);
                g.countable = true;
                g
            }
        }
    }

    /// A BCD number (`encoding: bcd`) of 1 to 4 bytes: any unit, maybe a range within its
    /// digits and its words swapped.
    fn bcd_field(&mut self, name: String) -> Gf {
        let &(ty, width) = self.pick(&[("u8", 1), ("u16", 2), ("u24", 3), ("u32", 4)]);
        let most = 10i64.pow(2 * width as u32) - 1;
        let mut y = format!(
            "{{name: {name}, type: {ty}, encoding: bcd, unit: {}",
            self.unit()
        );
        if width == 4 && self.chance(30) {
            y.push_str(", word_order: swapped");
        }
        if self.chance(50) {
            let r = self.range_yaml(0, most);
            let _ = write!(y, ", {r}");
        }
        y.push('}');
        Gf {
            name,
            ty,
            width,
            yaml: y,
            plain: false,
            countable: false,
            repeat_tail: 0,
        }
    }

    /// Packed elements: 1 to 6 elements of 2 bits up to their type's width, least or most
    /// significant bit first, maybe with a range.
    fn packed_field(&mut self, name: String) -> Gf {
        let &(ty, tw) = self.pick(&[("u8", 8i64), ("u16", 16), ("u32", 32)]);
        let bits = if self.chance(30) {
            tw
        } else {
            self.rng.i64(2..=tw)
        };
        let count = self.rng.i64(1..=6);
        let order = if self.chance(50) {
            "lsb_first"
        } else {
            "msb_first"
        };
        let mut y = format!(
            "{{name: {name}, type: {ty}, unit: {}, packed: {{count: {count}, bits: {bits}, bit_order: {order}}}",
            self.unit()
        );
        if self.chance(40) {
            let r = self.range_yaml(0, (1i64 << bits) - 1);
            let _ = write!(y, ", {r}");
        }
        y.push('}');
        Gf {
            name: name.clone(),
            ty,
            width: ((count * bits) as usize).div_ceil(8),
            yaml: y,
            plain: false,
            countable: false,
            repeat_tail: 0,
        }
    }

    /// A 64-bit integer or float: a unit of scale 1, maybe a range and its words swapped.
    fn wide_field(&mut self, name: String) -> Gf {
        let &(ty, width) = self.pick(&[("u64", 8), ("i64", 8), ("f32", 4), ("f64", 8)]);
        let mut y = format!("{{name: {name}, type: {ty}, unit: count");
        if self.chance(40) {
            y.push_str(", word_order: swapped");
        }
        if self.chance(50) {
            let r = match ty {
                "u64" => {
                    let a = if self.chance(50) {
                        self.rng.u64(..4)
                    } else {
                        self.rng.u64(..)
                    };
                    let b = if self.chance(50) {
                        a.saturating_add(self.rng.u64(..100))
                    } else {
                        self.rng.u64(a..)
                    };
                    format!("{{min: {a}, max: {b}}}")
                }
                "i64" => {
                    let a = if self.chance(50) {
                        self.rng.i64(-5..4)
                    } else {
                        self.rng.i64(..)
                    };
                    let b = if self.chance(50) {
                        a.saturating_add(self.rng.i64(0..100))
                    } else {
                        self.rng.i64(a..)
                    };
                    format!("{{min: {a}, max: {b}}}")
                }
                _ => {
                    // Decimals (quarters: exact in both widths) and now and then an integer.
                    let a = f64::from(self.rng.i32(-400..400)) / 4.0;
                    let b = a + f64::from(self.rng.i32(0..400)) / 4.0;
                    if self.chance(30) {
                        format!("{{min: {}, max: {}}}", a.floor(), b.ceil())
                    } else {
                        format!("{{min: {a:?}, max: {b:?}}}")
                    }
                }
            };
            let _ = write!(y, ", range: {r}");
        }
        y.push('}');
        Gf {
            name,
            ty,
            width,
            yaml: y,
            plain: false,
            countable: false,
            repeat_tail: 0,
        }
    }

    /// A repeated field; may first add a count field to `fields`. `later`: another list comes
    /// before or after it in the message, so it is counted (never to the `end`, which the
    /// validator allows only for the last list and, without a length field, the only one) by a
    /// count field of its own (a new one, not one an earlier list uses).
    fn repeated(&mut self, fields: &mut Vec<Gf>, request_field: Option<&str>, later: bool) {
        let k = fields.len();
        let bit = self.chance(20);
        // A repeated record: one to three fixed-width fields, each with a unit (maybe a range
        // and a special value) or an enum (maybe a range) or flags.
        let record = !bit && self.chance(30);
        let (ty, width, signed) = if bit {
            ("bit", 1, false)
        } else {
            *self.pick(&[
                ("u8", 1, false),
                ("u16", 2, false),
                ("i16", 2, true),
                ("u24", 3, false),
                ("i32", 4, true),
            ])
        };
        let min = self.rng.usize(0..=2);
        let max = if bit {
            self.rng.usize(min.max(1)..=20)
        } else {
            self.rng.usize(min.max(1)..=6)
        };
        let count = if !later && self.chance(40) {
            "end".to_owned()
        } else {
            let existing: Vec<String> = fields
                .iter()
                .filter(|f| f.countable)
                .map(|f| f.name.clone())
                .collect();
            if !later && !existing.is_empty() && self.chance(50) {
                self.pick(&existing).clone()
            } else {
                let name = format!("f{k}");
                // A later list's count is no field a reply takes from its request (the
                // generator emits those for the first list only).
                fields.push(Gf {
                    name: name.clone(),
                    ty: "u8",
                    width: 1,
                    yaml: format!("{{name: {name}, type: u8, unit: count}}"),
                    plain: !later,
                    countable: !later,
                    repeat_tail: 0,
                });
                name
            }
        };
        let name = format!("f{}", fields.len());
        let mut r = format!("count: {count}");
        if count != "end" && (bit || self.chance(40)) {
            r.push_str(", of: bytes");
        } else if count != "end" && self.chance(30) {
            r.push_str(", of: elements");
        }
        if min > 0 || self.chance(30) {
            let _ = write!(r, ", min: {min}");
        }
        let _ = write!(r, ", max: {max}");
        if let Some(q) = request_field {
            let _ = write!(
                r,
                ", request: {{field: {q}, multiply: {}, divide: {}}}",
                self.rng.u8(1..=2),
                self.rng.u8(1..=2)
            );
        }
        let (mut y, width) = if record {
            let (fs, w) = self.record_fields();
            (format!("{{name: {name}, type: record, fields: [{fs}]"), w)
        } else if !bit && !signed && width <= 2 && self.n_enums > 0 && self.chance(20) {
            // Enum elements (a list of the enum's type in generated code).
            let e = self.rng.usize(..self.n_enums);
            (format!("{{name: {name}, type: {ty}, enum: e{e}"), width)
        } else if bit {
            (format!("{{name: {name}, type: bit"), width)
        } else {
            (
                format!("{{name: {name}, type: {ty}, unit: {}", self.unit()),
                width,
            )
        };
        if !bit && !record && self.chance(30) {
            let (lo, hi) = limits(width, signed);
            let rr = self.range_yaml(lo, hi);
            let _ = write!(y, ", {rr}");
        }
        let _ = write!(y, ", repeat: {{{r}}}}}");
        let tail = if bit { max.div_ceil(8) } else { max * width };
        fields.push(Gf {
            name,
            ty,
            width,
            yaml: y,
            plain: false,
            countable: false,
            repeat_tail: tail.max(1),
        });
    }

    /// Records to the end whose last field's bytes a field gives (Dynamixel 2.0 SYNC_WRITE's
    /// `data_length`): the width field (u8 or u16, maybe with the range 1..=the last field's
    /// most), then one to three fixed fields and the last field of 1 to 4 bytes, any integer
    /// type, maybe with a range.
    fn sized_records(&mut self, fields: &mut Vec<Gf>) {
        let wname = format!("f{}", fields.len());
        let &(wty, ww) = self.pick(&[("u8", 1usize), ("u16", 2)]);
        let &(ty, most, signed) = self.pick(&RECORD_FIELD_TYPES);
        let mut wy = format!("{{name: {wname}, type: {wty}, unit: count");
        if self.chance(50) {
            let _ = write!(wy, ", range: {{min: 1, max: {most}}}");
        }
        wy.push('}');
        fields.push(Gf {
            name: wname.clone(),
            ty: wty,
            width: ww,
            yaml: wy,
            plain: false,
            countable: false,
            repeat_tail: 0,
        });
        let (fs, w) = self.record_fields();
        let mut last = format!("{{name: rl, type: {ty}, unit: {}", self.unit());
        if self.chance(40) {
            let (lo, hi) = limits(most, signed);
            let r = self.range_yaml(lo, hi);
            let _ = write!(last, ", {r}");
        }
        let _ = write!(last, ", bytes: {wname}}}");
        let min = self.rng.usize(0..=2);
        let max = self.rng.usize(min.max(1)..=6);
        let name = format!("f{}", fields.len());
        let mut r = String::from("count: end");
        if min > 0 || self.chance(30) {
            let _ = write!(r, ", min: {min}");
        }
        let _ = write!(r, ", max: {max}");
        fields.push(Gf {
            name: name.clone(),
            ty: "record",
            width: w + most,
            yaml: format!(
                "{{name: {name}, type: record, fields: [{fs}, {last}], repeat: {{{r}}}}}"
            ),
            plain: false,
            countable: false,
            repeat_tail: (max * (w + most)).max(1),
        });
    }

    /// A record's fields (YAML flow items) and its width.
    fn record_fields(&mut self) -> (String, usize) {
        let mut items = Vec::new();
        let mut width = 0;
        for j in 0..self.rng.usize(1..=3) {
            let &(ty, w, signed) = self.pick(&RECORD_FIELD_TYPES);
            width += w;
            let name = format!("r{j}");
            let mut y = match self.rng.u8(..10) {
                0..=1 if self.n_enums > 0 && !signed && w <= 2 => {
                    let e = self.rng.usize(..self.n_enums);
                    let mut y = format!("{{name: {name}, type: {ty}, enum: e{e}");
                    if self.chance(30) {
                        let _ = write!(y, ", range: {{min: 0, max: {}}}", self.rng.u8(1..8));
                    }
                    y
                }
                2 if self.n_flags > 0 && !signed && w <= 2 => {
                    let fl = self.rng.usize(..self.n_flags);
                    format!("{{name: {name}, type: {ty}, flags: fl{fl}")
                }
                _ => {
                    let mut y = format!("{{name: {name}, type: {ty}, unit: {}", self.unit());
                    let (lo, hi) = limits(w, signed);
                    if self.chance(40) {
                        let r = self.range_yaml(lo, hi);
                        let _ = write!(y, ", {r}");
                    }
                    if self.chance(15) {
                        let v = self.rng.i64(lo..=hi);
                        let _ = write!(y, ", special: [{{value: {v}, name: sp_{name}}}]");
                    }
                    y
                }
            };
            y.push('}');
            items.push(y);
        }
        (items.join(", "), width)
    }

    fn fields(&mut self, request_field: Option<&str>, follows_request: Option<&str>) -> Vec<Gf> {
        let n = self.rng.usize(0..=4);
        let mut out: Vec<Gf> = Vec::new();
        for k in 0..n {
            let f = self.field(format!("f{k}"), &out);
            out.push(f);
        }
        if let Some(q) = follows_request {
            let name = format!("f{}", out.len());
            out.push(Gf {
                name: name.clone(),
                ty: "u16",
                width: 2,
                yaml: format!(
                    "{{name: {name}, type: u16, unit: count, follows: {{request: {q}, multiply: {}, divide: {}}}}}",
                    self.rng.u8(1..=3),
                    self.rng.u8(1..=3)
                ),
                plain: false,
                countable: false,
                repeat_tail: 0,
            });
        }
        if !self.fixed && (self.chance(30) || request_field.is_some()) {
            // One list, or two (each counted by its own field, the second's count possibly
            // after the first list), each possibly followed by fixed fields.
            let lists = if self.chance(30) { 2 } else { 1 };
            for l in 0..lists {
                let request = if l == 0 { request_field } else { None };
                // Records whose width a field gives: the message's only list, its last field.
                if lists == 1 && request.is_none() && self.sized && self.chance(35) {
                    self.sized_records(&mut out);
                    break;
                }
                self.repeated(&mut out, request, lists > 1);
                if self.chance(35) {
                    for _ in 0..self.rng.usize(1..=2) {
                        let f = self.field(format!("f{}", out.len()), &out);
                        out.push(f);
                    }
                }
            }
        }
        out
    }
}

/// A random checksum: its YAML lines (without `covers_from`) and its width in bytes.
/// A checksum section's keys and the checksum's bytes; `("", 0)` for frames without one.
fn checksum_yaml(g: &mut G) -> (String, usize) {
    let check = |a: &ChecksumAlgorithm| checksum::compute(a, b"123456789");
    let order = |g: &mut G| *g.pick(&["big", "little"]);
    let draw = g.rng.u8(..16);
    // About two 8-bit sums or XORs in five (unmasked: draws 0 to 3, which draw nothing more
    // from the spec's generator) become FrSky's end-around sum, drawn by a generator of its
    // own, so the rest of the spec is as it was.
    if draw <= 3 && g.end_around.u8(..100) < 40 {
        let c = check(&ChecksumAlgorithm::Sum8EndAround);
        return (
            format!("algorithm: sum8_end_around, width: 8, check: {c}"),
            1,
        );
    }
    match draw {
        10 => (String::new(), 0),
        // The 16-bit sums.
        11..=13 => {
            let (name, a) = g
                .pick(&[
                    ("sum16", ChecksumAlgorithm::Sum16),
                    (
                        "sum16_ones_complement",
                        ChecksumAlgorithm::Sum16OnesComplement,
                    ),
                    (
                        "sum16_twos_complement",
                        ChecksumAlgorithm::Sum16TwosComplement,
                    ),
                    ("fletcher8", ChecksumAlgorithm::Fletcher8),
                    ("fletcher16", ChecksumAlgorithm::Fletcher16),
                ])
                .clone();
            let y = format!(
                "algorithm: {name}, width: 16, byte_order: {}, check: {}",
                order(g),
                check(&a)
            );
            (y, 2)
        }
        14 => {
            let (name, a, width) = g
                .pick(&[
                    ("sum8", ChecksumAlgorithm::Sum8, 8u32),
                    ("lrc", ChecksumAlgorithm::Sum8TwosComplement, 8),
                    ("xor8", ChecksumAlgorithm::Xor8, 8),
                    ("sum16", ChecksumAlgorithm::Sum16, 16),
                    (
                        "sum16_twos_complement",
                        ChecksumAlgorithm::Sum16TwosComplement,
                        16,
                    ),
                ])
                .clone();
            let mask = g.rng.u64(1..1 << width);
            // An 8-bit one masked becomes the end-around sum masked as often (after the spec's
            // generator drew the mask, so nothing else changes).
            let (name, a) = if width == 8 && g.end_around.u8(..100) < 40 {
                ("sum8_end_around", ChecksumAlgorithm::Sum8EndAround)
            } else {
                (name, a)
            };
            let c = check(&ChecksumAlgorithm::Masked(Box::new(a), mask));
            let mut y =
                format!("algorithm: {name}, width: {width}, mask: {mask:#X}, check: {c:#X}");
            if width > 8 {
                let _ = write!(y, ", byte_order: {}", order(g));
            }
            (y, width as usize / 8)
        }
        15 => (
            format!(
                "algorithm: lrc, width: 8, check: {}",
                check(&ChecksumAlgorithm::Sum8TwosComplement)
            ),
            1,
        ),
        0 => ("algorithm: sum8, width: 8, check: 0xDD".into(), 1),
        1 => (
            format!(
                "algorithm: sum8_ones_complement, width: 8, check: {}",
                check(&ChecksumAlgorithm::Sum8OnesComplement)
            ),
            1,
        ),
        2 => (
            format!(
                "algorithm: sum8_twos_complement, width: 8, check: {}",
                check(&ChecksumAlgorithm::Sum8TwosComplement)
            ),
            1,
        ),
        3 => (
            format!(
                "algorithm: xor8, width: 8, check: {}",
                check(&ChecksumAlgorithm::Xor8)
            ),
            1,
        ),
        _ => {
            let width: u8 = *g.pick(&[8, 16, 16, 32]);
            // About two 32-bit CRCs in five become 24-bit ones (a generator of their own).
            let width = if width == 32 && g.crc24.u8(..100) < 40 {
                24
            } else {
                width
            };
            let mask = if width == 64 {
                u64::MAX
            } else {
                (1u64 << width) - 1
            };
            let catalogue: [(u8, u64, u64, bool, bool, u64); 8] = [
                (8, 0x07, 0, false, false, 0),
                (8, 0x31, 0, true, true, 0),
                (16, 0x8005, 0xFFFF, true, true, 0),
                (16, 0x1021, 0, false, false, 0),
                (16, 0x8005, 0xFFFF, false, false, 0),
                (32, 0x04C1_1DB7, 0xFFFF_FFFF, true, true, 0xFFFF_FFFF),
                // RTCM 3's CRC-24Q (CRC-24/LTE-A) and CRC-24/OPENPGP.
                (24, 0x86_4CFB, 0, false, false, 0),
                (24, 0x86_4CFB, 0xB7_04CE, false, false, 0),
            ];
            let params = if g.chance(50) {
                let c: Vec<_> = catalogue.iter().filter(|c| c.0 == width).collect();
                let c = **g.pick(&c);
                CrcParams {
                    width: c.0,
                    poly: c.1,
                    init: c.2,
                    refin: c.3,
                    refout: c.4,
                    xorout: c.5,
                }
            } else {
                CrcParams {
                    width,
                    poly: (g.rng.u64(..) & mask) | 1,
                    init: if g.rng.bool() {
                        0
                    } else {
                        g.rng.u64(..) & mask
                    },
                    refin: g.rng.bool(),
                    refout: g.rng.bool(),
                    xorout: if g.rng.bool() {
                        0
                    } else {
                        g.rng.u64(..) & mask
                    },
                }
            };
            let c = check(&ChecksumAlgorithm::Crc(params));
            let mut y = format!(
                "algorithm: crc, width: {width}, poly: {:#X}, init: {:#X}, refin: {}, refout: {}, xorout: {:#X}, check: {c:#X}",
                params.poly, params.init, params.refin, params.refout, params.xorout
            );
            if width > 8 {
                let o = *g.pick(&["big", "little"]);
                let _ = write!(y, ", byte_order: {o}");
            }
            (y, usize::from(width / 8))
        }
    }
}

/// A random spec that the validator accepts, as YAML text; the same text for the same seed.
pub fn random_spec(seed: u64) -> String {
    let (text, _) = random_spec_without_examples(seed);
    let mut p = match busspec_model::load_str("generated.yaml", &text) {
        Ok(p) => p,
        // A generator bug: the caller validates the text and reports it.
        Err(_) => return text,
    };
    // Payload truncation (MAVLink v2's trailing zeros): tried on about half the specs whose
    // framing could take it (a length field, one code length, fixed-length messages), kept
    // where the validator accepts it, so every rule it holds truncation to is the
    // validator's; drawn by a generator of its own, so every spec without it is as it was.
    let mut text = text;
    let eligible = p.framing.length.is_some()
        && p.framing.escaping.is_none()
        && p.framing.truncation.is_none()
        && p.commands
            .iter()
            .chain(&p.responses)
            .all(|m| !m.is_variable());
    if eligible && truncation_draw(seed).1 {
        let head = "framing:\n  section: \"2\"\n";
        let with = text.replacen(head, &format!("{head}  truncation: trailing_zeros\n"), 1);
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
        }
    }
    // Responses without start or end bytes beside flagged requests, both escaped (F.Port's
    // uplink): tried on half the specs whose one layout opens with start bytes and ends in an
    // end byte beside byte escaping, a length field and a checksum, kept where the validator
    // accepts it; drawn by a generator of its own, before any other layout per direction.
    if let Some(with) = bare_responses(seed, &text) {
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
        }
    }
    // A layout per direction (Sensirion SHDLC's state byte in replies only): tried on a
    // fraction of the specs, kept where the validator accepts it, so every rule it holds a
    // layout per direction to is the validator's; drawn by a generator of its own.
    for with in layout_by_direction(seed, &text) {
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
            break;
        }
    }
    // Replies whose checksum takes in their request's bytes (Pelco D's general response):
    // tried on a fraction of the specs with a checksum, kept where the validator accepts
    // them (every rule it holds them to is the validator's); drawn by a generator of its own.
    for with in over_request(seed, &text, &p) {
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
            break;
        }
    }
    // Messages without a checksum (RoboClaw's reads, its acknowledgement): tried on a
    // fraction of the specs with a checksum, kept where the validator accepts them; drawn by
    // a generator of its own.
    for with in unchecked(seed, &text, &p) {
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
            break;
        }
    }
    // A message's own header values (JBD's read state A5, a reply's status 00 or 80): tried
    // on about half the specs with header fields, kept where the validator accepts them;
    // drawn by a generator of its own.
    for with in header_values(seed, &text, &p) {
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
            break;
        }
    }
    // A checksum before the bytes it covers (Septentrio SBF's CRC at offset 2, over the ID,
    // length and body after it): tried last, on three in five of the specs whose one layout
    // ends in its checksum, kept where the validator accepts it (every rule it holds such a
    // checksum to is the validator's); drawn by a generator of its own.
    for with in checksum_lead(seed, &text) {
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
            break;
        }
    }
    // A checksum followed by its complement (HerkuleX's CS1 and CS2): tried after, on half
    // the specs, kept where the validator accepts it (an 8-bit sum or XOR); drawn by a
    // generator of its own.
    if let Some(with) = checksum_complement(seed, &text) {
        if let Ok(q) = busspec_model::load_str("generated.yaml", &with) {
            (text, p) = (with, q);
        }
    }
    let mut rng = own_rng(seed, Own::Examples);
    match examples(&p, &mut rng) {
        Some(examples) => format!("{text}examples:\n{examples}errata: []\n"),
        None => format!("{text}examples: []\nerrata: []\n"),
    }
}

/// `text` with replies whose checksum takes in their request's bytes (`Own::OverRequest`), in
/// about two specs in five with a checksum: one or two framed replies drawn, each covering
/// its own bytes from a part of the response's layout before the payload, or from the
/// payload; the variants in the order tried (the drawn replies, then each reply alone).
fn over_request(seed: u64, text: &str, p: &ir::Protocol) -> Vec<String> {
    let mut rng = own_rng(seed, Own::OverRequest);
    if rng.u8(..100) >= 40 || p.framing.checksum.is_empty() {
        return Vec::new();
    }
    let replies: Vec<&str> = p
        .framed(Direction::Response)
        .iter()
        .map(|m| m.name.as_str())
        .collect();
    if replies.is_empty() {
        return Vec::new();
    }
    let parts: Vec<&str> = p
        .framing
        .layout_of(Direction::Response)
        .iter()
        .take_while(|x| **x != Part::Payload)
        .filter_map(|x| match x {
            Part::Start => Some("start"),
            Part::Address => Some("address"),
            Part::Length => Some("length"),
            Part::Header => Some("header"),
            Part::Code => Some("code"),
            _ => None,
        })
        .chain(["payload", "payload"])
        .collect();
    let mut drawn: Vec<(&str, &str)> = Vec::new();
    for _ in 0..rng.usize(1..=2) {
        let r = replies[rng.usize(..replies.len())];
        if drawn.iter().all(|(x, _)| *x != r) {
            drawn.push((r, parts[rng.usize(..parts.len())]));
        }
    }
    let with = |chosen: &[(&str, &str)]| {
        let keys = chosen.iter().map(|(r, part)| {
            (
                *r,
                format!("checksum_over_request: {{covers_from: {part}}}"),
            )
        });
        with_keys(text, keys)
    };
    let mut out = vec![with(&drawn)];
    // Then each reply alone, in an order drawn: the validator refuses a reply that another
    // message could be by its code and length.
    let mut alone: Vec<&str> = replies.clone();
    rng.shuffle(&mut alone);
    for r in alone {
        out.push(with(&[(r, parts[rng.usize(..parts.len())])]));
    }
    out
}

/// `text` with each named message's line given a key right after its name (`  - {name: m,
/// KEY, ...`): a message's own `checksum`, `header` or `checksum_over_request`.
fn with_keys<'a>(text: &str, keys: impl IntoIterator<Item = (&'a str, String)>) -> String {
    let mut t = text.to_owned();
    for (m, key) in keys {
        let line = format!("  - {{name: {m}, ");
        t = t.replacen(&line, &format!("{line}{key}, "), 1);
    }
    t
}

/// `text` with messages that give their header fields a value (`Own::HeaderValues`), in
/// about half the specs whose messages carry header fields: one to three framed messages
/// drawn, each giving one or all of its whole (not sub-divided, not constant) header fields a value within
/// its range (or one of its enum's values, or any of its width); the variants in the order
/// tried (the drawn messages, then each alone, in an order drawn).
fn header_values(seed: u64, text: &str, p: &ir::Protocol) -> Vec<String> {
    let mut rng = own_rng(seed, Own::HeaderValues);
    if rng.bool() {
        return Vec::new();
    }
    let messages: Vec<&ir::Message> = [Direction::Request, Direction::Response]
        .into_iter()
        .flat_map(|d| p.framed(d))
        .filter(|m| {
            let mut header = m.fields.iter().take_while(|f| f.header);
            header.any(|f| f.bits.is_empty() && f.constant.is_none())
        })
        .collect();
    if messages.is_empty() {
        return Vec::new();
    }
    let value = |rng: &mut fastrand::Rng, f: &ir::Field| -> u64 {
        let bits = 8 * f.width as u32;
        let mask = if bits >= 64 {
            u64::MAX
        } else {
            (1u64 << bits) - 1
        };
        if let Some(e) = f
            .enumeration
            .map(|e| &p.enums[e])
            .filter(|e| !e.values.is_empty())
        {
            return e.values[rng.usize(..e.values.len())].value & mask;
        }
        match f.range {
            Some((lo, hi)) => (rng.i64(lo..=hi) as u64) & mask,
            None => rng.u64(..=mask),
        }
    };
    let mut given: Vec<(String, String)> = Vec::new();
    for _ in 0..rng.usize(1..=3) {
        let m = messages[rng.usize(..messages.len())];
        if given.iter().any(|(n, _)| *n == m.name) {
            continue;
        }
        let whole: Vec<&ir::Field> = m
            .fields
            .iter()
            .take_while(|f| f.header)
            .filter(|f| f.bits.is_empty() && f.constant.is_none())
            .collect();
        let chosen: Vec<&ir::Field> = if rng.bool() {
            whole.clone()
        } else {
            vec![whole[rng.usize(..whole.len())]]
        };
        let items: Vec<String> = chosen
            .iter()
            .map(|f| format!("{}: 0x{:X}", f.name, value(&mut rng, f)))
            .collect();
        given.push((m.name.clone(), items.join(", ")));
    }
    let with = |chosen: &[(String, String)]| {
        let keys = chosen
            .iter()
            .map(|(m, items)| (m.as_str(), format!("header: {{{items}}}")));
        with_keys(text, keys)
    };
    let mut out = vec![with(&given)];
    let mut alone = given.clone();
    rng.shuffle(&mut alone);
    out.extend(alone.iter().map(|g| with(std::slice::from_ref(g))));
    out
}

/// `text` with messages that travel without a checksum (`Own::Unchecked`), in about one spec
/// in three with a checksum: one to three framed messages of one length drawn from either
/// direction; the variants in the order tried (the drawn messages, then each alone, in an
/// order drawn: the validator refuses one that a message with a checksum could be by its code
/// and length).
fn unchecked(seed: u64, text: &str, p: &ir::Protocol) -> Vec<String> {
    let mut rng = own_rng(seed, Own::Unchecked);
    if rng.u8(..100) >= 33 || p.framing.checksum.is_empty() {
        return Vec::new();
    }
    let names: Vec<&str> = [Direction::Request, Direction::Response]
        .into_iter()
        .flat_map(|d| p.framed(d))
        .filter(|m| !m.is_variable() && m.over_request.is_none())
        .map(|m| m.name.as_str())
        .collect();
    if names.is_empty() {
        return Vec::new();
    }
    let mut drawn: Vec<&str> = Vec::new();
    for _ in 0..rng.usize(1..=3) {
        let m = names[rng.usize(..names.len())];
        if !drawn.contains(&m) {
            drawn.push(m);
        }
    }
    let with = |chosen: &[&str]| {
        with_keys(
            text,
            chosen.iter().map(|m| (*m, "checksum: none".to_owned())),
        )
    };
    let mut out = vec![with(&drawn)];
    let mut alone = names.clone();
    rng.shuffle(&mut alone);
    out.extend(alone.into_iter().map(|m| with(&[m])));
    out
}

/// `text` with its layout given per direction (`Own::LayoutByDirection`), in about one spec
/// in three: the header fields in one direction only, the address in one direction only, or
/// two neighbouring parts before the payload in another order in one direction, each in one
/// direction drawn, in the order drawn (the caller keeps the first the validator accepts).
/// None where the spec is not drawn for it or its layout has nothing to vary.
fn layout_by_direction(seed: u64, text: &str) -> Vec<String> {
    let mut rng = own_rng(seed, Own::LayoutByDirection);
    if rng.u8(..100) >= 35 {
        return Vec::new();
    }
    let Some(line) = text.lines().find(|l| l.starts_with("  layout: [")) else {
        return Vec::new();
    };
    let Some(inner) = line
        .strip_prefix("  layout: [")
        .and_then(|l| l.strip_suffix(']'))
    else {
        return Vec::new();
    };
    let layout: Vec<&str> = inner.split(", ").collect();
    let Some(payload) = layout.iter().position(|p| *p == "payload") else {
        return Vec::new();
    };
    let mut variants: Vec<Vec<&str>> = Vec::new();
    for part in ["header", "address"] {
        if layout.contains(&part) {
            variants.push(layout.iter().copied().filter(|p| *p != part).collect());
        }
    }
    // Two neighbouring parts before the payload swapped (the start bytes keep their place).
    for i in 0..payload.saturating_sub(1) {
        if layout[i] != layout[i + 1] && layout[i] != "start" && layout[i + 1] != "start" {
            let mut v = layout.clone();
            v.swap(i, i + 1);
            variants.push(v);
        }
    }
    rng.shuffle(&mut variants);
    // The checksum's line, where it has one: each variant is tried first with a part per
    // direction to cover from (`covers_from: {request, response}`, JBD's BMS), in half the
    // specs with a checksum, a part before the payload of each direction's layout, drawn.
    let checksum = text
        .lines()
        .find(|l| l.starts_with("  checksum: {") && l.ends_with('}'))
        .filter(|_| rng.bool());
    // The header fields' line, where both directions' layouts keep `header`: each variant is
    // tried first with header fields per direction (`header: {request, response}`, JBD's
    // BMS), in half the specs with header fields: the response's renamed, all of them or
    // the first alone.
    let header = text
        .lines()
        .find(|l| l.starts_with("  header: [") && l.ends_with(']'))
        .filter(|_| rng.bool());
    let mut out = Vec::new();
    for other in &variants {
        let (request, response) = if rng.bool() {
            (other, &layout)
        } else {
            (&layout, other)
        };
        let by_direction = format!(
            "  layout:\n    request: [{}]\n    response: [{}]",
            request.join(", "),
            response.join(", ")
        );
        let plain = text.replacen(line, &by_direction, 1);
        let mut bases = Vec::new();
        if let Some(h) =
            header.filter(|_| request.contains(&"header") && response.contains(&"header"))
        {
            let inner = &h["  header: [".len()..h.len() - 1];
            let renamed: Vec<String> = flow_items(inner)
                .iter()
                .map(|i| i.replace("name: ", "name: r_"))
                .collect();
            let theirs = if renamed.len() < 2 || rng.bool() {
                renamed.join(", ")
            } else {
                renamed[0].clone()
            };
            let per = format!("  header:\n    request: [{inner}]\n    response: [{theirs}]");
            bases.push(plain.replacen(h, &per, 1));
        }
        bases.push(plain);
        for base in bases {
            if let Some(cs) = checksum {
                let before = |l: &[&str]| -> Vec<String> {
                    l.iter()
                        .take_while(|p| **p != "payload")
                        .map(|p| (*p).to_owned())
                        .collect()
                };
                let (rq, rs) = (before(request), before(response));
                let body = match cs.find(", covers_from: ") {
                    Some(i) => &cs[..i],
                    None => cs.strip_suffix('}').unwrap_or(cs),
                };
                for _ in 0..3 {
                    if rq.is_empty() || rs.is_empty() {
                        break;
                    }
                    let (a, b) = (&rq[rng.usize(..rq.len())], &rs[rng.usize(..rs.len())]);
                    let with = format!("{body}, covers_from: {{request: {a}, response: {b}}}}}");
                    out.push(base.replacen(cs, &with, 1));
                }
            }
            out.push(base);
        }
    }
    out
}

/// `text` with its responses laid out without start and end bytes (`Own::BareResponses`), the
/// requests' layout as it was: in half the specs whose layout opens with `start`, ends in
/// `end` and has `length` and `checksum`, beside byte escaping (`escape:`). None otherwise.
fn bare_responses(seed: u64, text: &str) -> Option<String> {
    let mut rng = own_rng(seed, Own::BareResponses);
    if !rng.bool() || !text.contains("  escaping: {escape: ") {
        return None;
    }
    let line = text.lines().find(|l| l.starts_with("  layout: ["))?;
    let inner = line.strip_prefix("  layout: [")?.strip_suffix(']')?;
    let layout: Vec<&str> = inner.split(", ").collect();
    let eligible = layout.first() == Some(&"start")
        && layout.last() == Some(&"end")
        && layout.contains(&"length")
        && layout.contains(&"checksum");
    if !eligible {
        return None;
    }
    let bare: Vec<&str> = layout
        .iter()
        .copied()
        .filter(|p| *p != "start" && *p != "end")
        .collect();
    let by_direction = format!(
        "  layout:\n    request: [{inner}]\n    response: [{}]",
        bare.join(", ")
    );
    let mut out = text.replacen(line, &by_direction, 1);
    // The length field counts only parts both directions have: not the start or end bytes.
    let counts = out.lines().find_map(|l| {
        let i = l.find("counts: [")? + "counts: [".len();
        let j = i + l[i..].find(']')?;
        Some((l.to_owned(), l[i..j].to_owned()))
    })?;
    let kept: Vec<&str> = (counts.1.split(", "))
        .filter(|p| *p != "start" && *p != "end")
        .collect();
    if kept.is_empty() {
        return None;
    }
    let line = counts.0.replacen(
        &format!("counts: [{}]", counts.1),
        &format!("counts: [{}]", kept.join(", ")),
        1,
    );
    out = out.replacen(&counts.0, &line, 1);
    // Every start byte travels escaped, so that none appears inside a response.
    let start = out.lines().find(|l| l.starts_with("  start: "))?.to_owned();
    let sync: Vec<u8> = start["  start: ".len()..]
        .trim_matches(|c| c == '[' || c == ']')
        .split(", ")
        .map(|b| u8::from_str_radix(b.trim_start_matches("0x"), 16).ok())
        .collect::<Option<_>>()?;
    let esc = out
        .lines()
        .find(|l| l.starts_with("  escaping: {escape: "))?
        .to_owned();
    let hex = |b: u8| format!("{b:#04X}").replace("0X", "0x");
    let mut with = esc.clone();
    for b in sync {
        if with.contains("bytes: [") {
            let i = with.find("bytes: [")? + "bytes: [".len();
            let j = i + with[i..].find(']')?;
            if !with[i..j]
                .split(", ")
                .any(|x| x.eq_ignore_ascii_case(&hex(b)))
            {
                with = format!("{}, {}{}", &with[..j], hex(b), &with[j..]);
            }
        } else {
            let i = with.find("map: [")? + "map: [".len();
            let j = i + with[i..].rfind(']')?;
            if with[i..j].contains(&format!("byte: {}", hex(b))) {
                continue;
            }
            // A replacement no byte of the map, escape or start byte takes.
            let taken = |r: u8| with.contains(&hex(r)) || r == b;
            let r = (0..=255u8)
                .cycle()
                .skip(rng.usize(..256))
                .take(256)
                .find(|&r| !taken(r))?;
            with = format!(
                "{}, {{byte: {}, as: {}}}{}",
                &with[..j],
                hex(b),
                hex(r),
                &with[j..]
            );
        }
    }
    Some(out.replacen(&esc, &with, 1))
}

/// The items of a YAML flow sequence's inside (`{a: 1, b: [2, 3]}, {c: 4}`), each as written:
/// split at the commas outside brackets and braces.
/// `text` with its checksum moved before the payload (`Own::ChecksumLead`), in three in five
/// of the specs whose one layout ends in it: just before a part of the layout before the
/// payload, which it then covers from, to the frame's end (`covers_from` that part); the
/// variants in the order tried, each place once.
fn checksum_lead(seed: u64, text: &str) -> Vec<String> {
    let mut rng = own_rng(seed, Own::ChecksumLead);
    if rng.u8(..100) >= 60 {
        return Vec::new();
    }
    let Some(line) = text.lines().find(|l| l.starts_with("  layout: [")) else {
        return Vec::new();
    };
    let Some(inner) = line
        .strip_prefix("  layout: [")
        .and_then(|l| l.strip_suffix(']'))
    else {
        return Vec::new();
    };
    let layout: Vec<&str> = inner.split(", ").collect();
    let Some((&"checksum", rest)) = layout.split_last() else {
        return Vec::new();
    };
    let Some(payload) = rest.iter().position(|p| *p == "payload") else {
        return Vec::new();
    };
    let Some(cs_line) = text.lines().find(|l| l.starts_with("  checksum: {")) else {
        return Vec::new();
    };
    let Some(body) = cs_line
        .strip_prefix("  checksum: {")
        .and_then(|l| l.strip_suffix('}'))
    else {
        return Vec::new();
    };
    let items: Vec<String> = flow_items(body)
        .into_iter()
        .filter(|i| !i.starts_with("covers_from:"))
        .collect();
    let mut places: Vec<usize> = (0..payload).collect();
    rng.shuffle(&mut places);
    // Covering from a part before it too (HerkuleX's, `Own::ChecksumAround`): on three in
    // four specs, each place that has a part before it tried first so, from one of those.
    let mut around = own_rng(seed, Own::ChecksumAround);
    let tries_around = around.u8(..4) != 0;
    places
        .into_iter()
        .flat_map(|i| {
            let mut moved = rest.to_vec();
            moved.insert(i, "checksum");
            let layout = format!("  layout: [{}]", moved.join(", "));
            let with = |from: &str| {
                let checksum =
                    format!("  checksum: {{{}, covers_from: {from}}}", items.join(", "),);
                text.replacen(line, &layout, 1)
                    .replacen(cs_line, &checksum, 1)
            };
            let mut variants = Vec::new();
            if tries_around && i > 0 {
                variants.push(with(rest[around.usize(..i)]));
            }
            variants.push(with(rest[i]));
            variants
        })
        .collect()
}

/// `text` with its checksum followed by its complement (`Own::ChecksumComplement`,
/// `complement: true`), on half the specs with a checksum; the validator takes it after
/// an 8-bit sum or XOR only.
fn checksum_complement(seed: u64, text: &str) -> Option<String> {
    let mut rng = own_rng(seed, Own::ChecksumComplement);
    if rng.bool() {
        return None;
    }
    let cs_line = text.lines().find(|l| l.starts_with("  checksum: {"))?;
    let body = cs_line
        .strip_prefix("  checksum: {")
        .and_then(|l| l.strip_suffix('}'))?;
    let checksum = format!("  checksum: {{{body}, complement: true}}");
    Some(text.replacen(cs_line, &checksum, 1))
}

fn flow_items(inner: &str) -> Vec<String> {
    let (mut out, mut depth, mut from) = (Vec::new(), 0i32, 0usize);
    for (i, c) in inner.char_indices() {
        match c {
            '{' | '[' => depth += 1,
            '}' | ']' => depth -= 1,
            ',' if depth == 0 => {
                out.push(inner[from..i].trim().to_owned());
                from = i + 1;
            }
            _ => {}
        }
    }
    if !inner[from..].trim().is_empty() {
        out.push(inner[from..].trim().to_owned());
    }
    out
}

/// Payload truncation's draw for the spec of `seed` (`Own::Truncation`): whether the spec is
/// drawn without lists and optional fields, with a length field (one in five), and
/// whether truncation is tried where the validator may take it (those, and half the others).
fn truncation_draw(seed: u64) -> (bool, bool) {
    let mut rng = own_rng(seed, Own::Truncation);
    let fixed = rng.u8(..100) < 20;
    let tries = rng.u8(..100) < 50;
    (fixed, fixed || tries)
}

/// The examples of `p`: for each message up to two frames the interpreter encodes from random
/// allowed values, kept where the validator would replay them.
fn examples(p: &ir::Protocol, rng: &mut fastrand::Rng) -> Option<String> {
    let mut out = String::new();
    let mut any = false;
    for d in [Direction::Request, Direction::Response] {
        for (index, m) in p.messages(d).iter().enumerate() {
            let r = MessageRef {
                direction: d,
                index,
            };
            let answering: Vec<usize> = (0..p.commands.len())
                .filter(|&c| p.commands[c].gets(index))
                .collect();
            let mut kept = 0;
            for _ in 0..6 {
                if kept == 2 {
                    break;
                }
                let values = random_values(p, m, rng, true);
                let a = &p.framing.address;
                let address = match a.default {
                    Some(x) if rng.bool() => x,
                    _ => rng.u8(a.min..=a.max),
                };
                // A direction whose layout has no address (a layout per direction): 0.
                let address = if p.framing.has_address_in(d) {
                    address
                } else {
                    0
                };
                let over = m.over_request.is_some();
                let reply_to = match d {
                    Direction::Response
                        if !answering.is_empty()
                            && (m.needs_request || over || rng.u8(..3) == 0) =>
                    {
                        Some(answering[rng.usize(..answering.len())])
                    }
                    _ => None,
                };
                // A reply whose checksum takes in its request's bytes: over a frame of the
                // request it answers, which the example gives.
                let request = match reply_to {
                    Some(c) if over => {
                        let q = MessageRef {
                            direction: Direction::Request,
                            index: c,
                        };
                        let qv = random_values(p, &p.commands[c], rng, true);
                        let qa = if p.framing.has_address_in(Direction::Request) {
                            address.max(a.min)
                        } else {
                            0
                        };
                        match interp::encode(p, q, qa, &qv) {
                            Ok(w)
                                if interp::decode(p, Some(Direction::Request), None, &w)
                                    .is_ok_and(|f| f.message == q) =>
                            {
                                Some(w)
                            }
                            _ => continue,
                        }
                    }
                    _ if over => continue,
                    _ => None,
                };
                let covered = request.as_deref().and_then(|w| p.checksum_span(w));
                let Ok(wire) = interp::encode_with(p, r, address, &values, covered) else {
                    continue;
                };
                match interp::decode_with(p, Some(d), reply_to, covered, &wire) {
                    Ok(f) if f.message == r => {}
                    _ => continue,
                }
                if interp::decode_as_reply(p, r, covered, &wire).is_err() {
                    continue;
                }
                kept += 1;
                any = true;
                let printed = interp::format_hex(&interp::wire_to_printed(p, m, &wire));
                let _ = write!(
                    out,
                    "  - {{section: \"9\", message: {}, derived: \"{printed}\"",
                    m.name
                );
                if let Some(c) = reply_to {
                    let _ = write!(out, ", reply_to: {}", p.commands[c].name);
                }
                if let Some(w) = &request {
                    let _ = write!(out, ", request: \"{}\"", interp::format_hex(w));
                }
                let stated = stated_values(p, m, &values);
                let _ = writeln!(out, ", values: {{{stated}}}}}");
            }
        }
    }
    // None where no frame of any message decodes on its own: a spec without examples, which
    // the harness reports (it needs at least one).
    any.then_some(out)
}

/// Values an example can state in its own words: numbers of fields whose unit is `count`
/// (scale 1) without special values, enum values by name.
fn stated_values(p: &ir::Protocol, m: &ir::Message, values: &[interp::Value]) -> String {
    let mut out = Vec::new();
    for v in values {
        let Some((f, bits)) = interp::leaf_field(m, &v.name) else {
            continue;
        };
        let unit = bits.map_or(f.unit, |b| b.unit);
        let plain = unit.is_some_and(|u| p.units[u].name == "count") && f.special.is_empty();
        match &v.raw {
            // A 64-bit integer or a float as its type reads its bits: the text JSON prints,
            // quoted where it is not a number (NaN, infinities).
            Raw::Int(i) if bits.is_none() && f.is_wide() => {
                let k = f.num_kind();
                if k.is_non_finite(*i) {
                    out.push(format!("{}: \"{}\"", v.name, k.text(*i)));
                } else {
                    out.push(format!("{}: {}", v.name, k.text(*i)));
                }
            }
            Raw::Int(i) if plain => out.push(format!("{}: {i}", v.name)),
            Raw::Int(i) if bits.is_none() && f.enumeration.is_some() && f.range.is_none() => {
                let e = &p.enums[f.enumeration.unwrap_or(0)];
                if let Some(x) = e.values.iter().find(|x| x.value as i64 == *i) {
                    out.push(format!("{}: {}", v.name, x.name));
                }
            }
            // Records whose fields are all plain counts, as a list of mappings.
            Raw::Records(rs)
                if !rs.is_empty()
                    && f.record.iter().all(|g| {
                        g.unit.is_some_and(|u| p.units[u].name == "count") && g.special.is_empty()
                    }) =>
            {
                let items: Vec<String> = rs
                    .iter()
                    .map(|r| {
                        let kv: Vec<String> = f
                            .record
                            .iter()
                            .zip(r)
                            .map(|(g, x)| format!("{}: {x}", g.name))
                            .collect();
                        format!("{{{}}}", kv.join(", "))
                    })
                    .collect();
                out.push(format!("{}: [{}]", v.name, items.join(", ")));
            }
            // A list of a fixed count of 64-bit integers or floats: each element as its type
            // reads it, where every one is a finite number of at most 15 digits (an example
            // states a list as plain numbers).
            Raw::List(l) if bits.is_none() && f.is_wide() => {
                let k = f.num_kind();
                let items: Vec<String> = l.iter().map(|x| k.text(*x)).collect();
                let short = |t: &String| {
                    t.chars().filter(char::is_ascii_digit).count() <= 15
                        && t.chars()
                            .all(|c| c.is_ascii_digit() || c == '-' || c == '.')
                };
                if !l.is_empty() && items.iter().all(short) {
                    out.push(format!("{}: [{}]", v.name, items.join(", ")));
                }
            }
            Raw::List(l) if plain && f.range.is_none() && !l.is_empty() => {
                let items: Vec<String> = l.iter().map(|x| x.to_string()).collect();
                out.push(format!("{}: [{}]", v.name, items.join(", ")));
            }
            _ => {}
        }
    }
    out.join(", ")
}

/// The spec text up to its examples, and the number of messages.
fn random_spec_without_examples(seed: u64) -> (String, usize) {
    let mut g = G {
        rng: fastrand::Rng::with_seed(seed),
        n_enums: 0,
        n_flags: 0,
        sized: false,
        fixed: truncation_draw(seed).0,
        fixed_elements: own_rng(seed, Own::FixedElements),
        crc24: own_rng(seed, Own::Crc24),
        end_around: own_rng(seed, Own::EndAround),
    };
    let mut y = String::new();
    let _ = writeln!(y, "# busspec-difftest random spec, seed {seed}");
    let _ = writeln!(y, "protocol: s{seed}");
    let _ = writeln!(y, "title: \"Random spec {seed}\"");
    let _ = writeln!(
        y,
        "document: {{title: \"generated\", revision: \"1\", date: \"2024-01-01\"}}"
    );
    let bo = *g.pick(&["big", "little"]);
    let pbo = *g.pick(&["big", "little"]);
    let _ = writeln!(y, "byte_order: {bo}\nprinted_byte_order: {pbo}");

    g.n_enums = g.rng.usize(0..=2);
    g.n_flags = g.rng.usize(0..=1);

    // Serial.
    let baud = *g.pick(&[2400, 9600, 19200, 115_200]);
    let parity = *g.pick(&["none", "even", "odd"]);
    let _ = write!(
        y,
        "serial: {{section: \"1\", baud: {baud}, data_bits: 8, parity: {parity}, stop_bits: {}",
        g.rng.u8(1..=2)
    );
    let gap_ms = g.chance(30);
    if gap_ms {
        let _ = write!(y, ", inter_frame_gap_ms: {}", g.rng.u32(1..20));
    }
    if g.chance(20) {
        let _ = write!(y, ", frame_rate: {{typical_per_s: 10, max_per_s: 50}}");
    }
    if g.n_enums > 0 && g.chance(20) {
        y.push_str(", baud_rates: e0");
    }
    y.push_str("}\n");

    // What a master needs: no effect on the codec, but the generated `Protocol` items
    // (`TRANSACTIONS`, and `may_retry` where the kinds differ from the default) must compile.
    if g.chance(25) {
        y.push_str("transactions: {section: \"1\"");
        if g.chance(50) {
            let _ = write!(y, ", response_timeout_ms: {}", g.rng.u32(1..2000));
        }
        if g.chance(50) {
            let _ = write!(
                y,
                ", turnaround_ms: \"{}.{}\"",
                g.rng.u32(0..5),
                g.rng.u32(0..10)
            );
        }
        // A gap in characters must agree with a gap in milliseconds: only without one.
        if !gap_ms && g.chance(50) {
            let _ = write!(
                y,
                ", inter_frame_gap: {{characters: \"{}.5\", at_least_ms: 1}}",
                g.rng.u32(1..5)
            );
        }
        if g.chance(60) {
            let kinds = ["movement", "completion_check", "setter", "getter", "reset"];
            let picked: Vec<&str> = kinds.iter().copied().filter(|_| g.chance(40)).collect();
            let _ = write!(y, ", retry: {{safe_kinds: [{}]}}", picked.join(", "));
        }
        y.push_str("}\n");
    }

    // Framing.
    let has_start = g.chance(70);
    let mut sync: Vec<u8> = if has_start {
        let n = *g.pick(&[1, 1, 1, 2, 3, 4]);
        (0..n).map(|_| g.rng.u8(..)).collect()
    } else {
        Vec::new()
    };
    // Stuffing (Dynamixel 2.0's) needs a length field before the code.
    let want_insert = g.chance(8);
    let has_length = want_insert || g.fixed || g.chance(30);
    g.sized = has_length;
    // Frames without an address (a point-to-point link).
    let addressed = !g.chance(15);
    let code_first = addressed && g.chance(12);
    let lens_of = |g: &mut G| -> Vec<usize> {
        let sets: [&[usize]; 9] = [
            &[0],
            &[1],
            &[2],
            &[0, 1],
            &[0, 2],
            &[1, 2],
            &[0, 1, 2],
            &[1],
            &[0, 2],
        ];
        g.pick(&sets).to_vec()
    };
    let (req_lens, resp_lens) = if code_first {
        let l = *g.pick(&[0usize, 1, 2]);
        (vec![l], vec![l])
    } else if g.fixed {
        // Drawn for payload truncation: one code length both ways, 1 to 3 bytes (MAVLink
        // v2's message id is 3).
        let l = *g.pick(&[1usize, 2, 3]);
        (vec![l], vec![l])
    } else if has_length {
        // A length field holds one rule per direction: codes of one length each.
        let a = *g.pick(&[0usize, 1, 2]);
        let b = *g.pick(&[0usize, 1, 2]);
        (vec![a], vec![b])
    } else {
        (lens_of(&mut g), lens_of(&mut g))
    };
    let mut layout: Vec<&str> = Vec::new();
    if has_start {
        layout.push("start");
    }
    if !addressed {
        layout.push("code");
    } else if code_first {
        layout.extend(["code", "address"]);
    } else {
        layout.extend(["address", "code"]);
    }
    if has_length {
        let last = if want_insert {
            layout
                .iter()
                .position(|p| *p == "code")
                .unwrap_or(layout.len())
        } else {
            layout.len()
        };
        let at = g.rng.usize(usize::from(has_start)..=last);
        layout.insert(at, "length");
    }
    let (mut csum, mut csum_len) = checksum_yaml(&mut g);
    layout.push("payload");
    if !csum.is_empty() {
        layout.push("checksum");
    }
    // Constant bytes after the checksum (M-Bus's 16, a line end).
    let mut end: Vec<u8> = if !g.fixed && g.chance(15) {
        let n = *g.pick(&[1, 1, 2, 3]);
        (0..n).map(|_| g.rng.u8(..)).collect()
    } else {
        Vec::new()
    };
    if !end.is_empty() {
        // After the checksum (FT1.2's 16) or just before it, covered by it (Pelco-P's ETX).
        if !csum.is_empty() && g.chance(40) {
            let at = layout.len() - 1;
            layout.insert(at, "end");
        } else {
            layout.push("end");
        }
    }
    // Escaping (`framing.escaping`): byte escaping and COBS end every frame in one end byte
    // (last); stuffing needs a length field before the code, which counts the stuffed bytes.
    let pos = |layout: &[&str], x: &str| layout.iter().position(|p| *p == x);
    let stuffable = has_length && pos(&layout, "length") < pos(&layout, "code");
    // DLE stuffing (the escape byte doubled, frames ending in it and a byte no escape stands
    // for: Garmin's `10 03`) in about three specs in ten, drawn by a generator of its own (every
    // spec drawn without it is as it was).
    let doubled = own_rng(seed, Own::Doubled).u8(..100) < 30;
    let escaping = match g.rng.u8(0..100) {
        _ if want_insert && stuffable => Escaping::Insert,
        _ if doubled => Escaping::Doubled,
        0..=9 => Escaping::Bytes,
        10..=17 => Escaping::Cobs,
        _ => Escaping::None,
    };
    // Frames only end bytes delimit (Nextion's `FF FF FF`: no length field, no checksum):
    // where nothing escapes and no length field counts, one such spec in four loses its
    // checksum and ends in end bytes, drawn by a generator of its own (every spec drawn
    // without it is as it was).
    if escaping == Escaping::None && !has_length && !g.fixed {
        let mut rng = own_rng(seed, Own::EndDelimited);
        if rng.u8(..100) < 25 {
            (csum, csum_len) = (String::new(), 0);
            layout.retain(|p| *p != "checksum");
            if end.is_empty() {
                end = (0..rng.usize(1..=3)).map(|_| rng.u8(..)).collect();
                layout.push("end");
            }
        }
    }
    // The start bytes or the length field sent twice (FT1.2's and M-Bus's `68 L L 68`),
    // anywhere after the first and before the payload.
    // After the code only where every code has one length (it would move it).
    if escaping == Escaping::None {
        let mut lens: Vec<usize> = req_lens.iter().chain(&resp_lens).copied().collect();
        lens.sort_unstable();
        lens.dedup();
        for part in ["start", "length"] {
            if let (Some(first), true) = (pos(&layout, part), !g.fixed && g.chance(20)) {
                let last = if lens.len() == 1 {
                    pos(&layout, "payload")
                } else {
                    pos(&layout, "code")
                };
                let last = last.unwrap_or(layout.len());
                if first < last {
                    let at = g.rng.usize(first + 1..=last);
                    layout.insert(at, part);
                }
            }
        }
    }
    // Header fields every message carries (MAVLink's sequence, system and component IDs):
    // anywhere after the leading start bytes and before the payload; after the code only
    // where every code has one length (it would move them).
    let mut header: Vec<(String, usize)> = if g.chance(15) {
        (0..g.rng.usize(1..=3))
            .map(|k| g.header_field(format!("h{k}")))
            .collect()
    } else {
        Vec::new()
    };
    if !header.is_empty() {
        let mut lens: Vec<usize> = req_lens.iter().chain(&resp_lens).copied().collect();
        lens.sort_unstable();
        lens.dedup();
        let first = usize::from(layout.first() == Some(&"start"));
        let last = if lens.len() == 1 {
            pos(&layout, "payload")
        } else {
            pos(&layout, "code")
        }
        .unwrap_or(layout.len());
        let at = g.rng.usize(first..=last.max(first));
        layout.insert(at, "header");
        // Header fields in two places (NovAtel's OEM header around the message id and the
        // length): the later fields in a second `header` (`part: 2`) not beside the first,
        // before the payload, and before the code where codes have several lengths.
        let last = if lens.len() == 1 {
            pos(&layout, "payload")
        } else {
            pos(&layout, "code")
        }
        .unwrap_or(layout.len());
        if header.len() >= 2 && at + 2 <= last && g.chance(40) {
            let second = g.rng.usize(at + 2..=last);
            layout.insert(second, "header");
            let k = g.rng.usize(1..header.len());
            for h in &mut header[k..] {
                h.0 = h.0.replacen(", ", ", part: 2, ", 1);
            }
        }
    }
    let header_len: usize = header.iter().map(|h| h.1).sum();
    let mut escaping_yaml = String::new();
    match escaping {
        Escaping::Bytes | Escaping::Cobs => {
            layout.retain(|p| *p != "end");
            // Without an end byte, framed by the length field before the code (XBee API
            // mode 2); `e` is then one more escaped byte.
            let by_length = escaping == Escaping::Bytes
                && has_length
                && pos(&layout, "length") < pos(&layout, "code")
                && g.chance(70);
            if !by_length {
                layout.push("end");
            }
            let e = if escaping == Escaping::Cobs {
                0
            } else if sync.len() == 1 && g.chance(60) {
                // One flag that opens and closes every frame, which frames may share (HDLC),
                // or a start byte escaped inside the frame (XBee).
                sync[0]
            } else {
                g.rng.u8(..)
            };
            end = if by_length { Vec::new() } else { vec![e] };
            if escaping == Escaping::Cobs {
                escaping_yaml = "  escaping: {cobs: true, computed: unescaped}\n".to_owned();
            } else {
                // The escape byte and the end byte travel escaped, and perhaps more bytes; by
                // a mask or a map whose replacements are none of them.
                let x = loop {
                    let x = g.rng.u8(..);
                    if x != e {
                        break x;
                    }
                };
                let mut raw = vec![e, x];
                for _ in 0..g.rng.usize(0..=2) {
                    let b = g.rng.u8(..);
                    if !raw.contains(&b) {
                        raw.push(b);
                    }
                }
                let items = |v: &[String]| v.join(", ");
                if g.chance(50) {
                    let mask = loop {
                        let m = g.rng.u8(1..);
                        if raw.iter().all(|b| !raw.contains(&(b ^ m))) {
                            break Some(m);
                        }
                        if g.chance(5) {
                            break None;
                        }
                    };
                    if let Some(m) = mask {
                        let bytes: Vec<String> = raw.iter().map(|b| format!("{b:#04X}")).collect();
                        escaping_yaml = format!(
                            "  escaping: {{escape: {x:#04X}, xor: {m:#04X}, bytes: [{}], computed: unescaped}}\n",
                            items(&bytes)
                        );
                    }
                }
                if escaping_yaml.is_empty() {
                    let mut used = raw.clone();
                    let pairs: Vec<String> = raw
                        .iter()
                        .map(|b| {
                            let r = loop {
                                let r = g.rng.u8(..);
                                if !used.contains(&r) {
                                    break r;
                                }
                            };
                            used.push(r);
                            format!("{{byte: {b:#04X}, as: {r:#04X}}}")
                        })
                        .collect();
                    escaping_yaml = format!(
                        "  escaping: {{escape: {x:#04X}, map: [{}], computed: unescaped}}\n",
                        items(&pairs)
                    );
                }
            }
        }
        Escaping::Doubled => {
            // The escape byte (often the one start byte, as Garmin's and TSIP's DLE) travels
            // doubled; frames end in it and a byte no escape stands for; perhaps more bytes
            // travel escaped by a map whose replacements are none of them.
            layout.retain(|p| *p != "end");
            layout.push("end");
            let x = if !sync.is_empty() && g.chance(60) {
                // One start byte, the escape byte itself (Garmin's and TSIP's DLE).
                sync.truncate(1);
                sync[0]
            } else {
                g.rng.u8(..)
            };
            let t = loop {
                let t = g.rng.u8(..);
                if t != x {
                    break t;
                }
            };
            let mut raw = vec![x];
            for _ in 0..g.rng.usize(0..=2) {
                let b = g.rng.u8(..);
                if !raw.contains(&b) {
                    raw.push(b);
                }
            }
            let mut used = raw.clone();
            used.push(t);
            let mut pairs: Vec<String> = raw[1..]
                .iter()
                .map(|b| {
                    let r = loop {
                        let r = g.rng.u8(..);
                        if !used.contains(&r) {
                            break r;
                        }
                    };
                    used.push(r);
                    format!("{{byte: {b:#04X}, as: {r:#04X}}}")
                })
                .collect();
            let at = g.rng.usize(..=pairs.len());
            pairs.insert(at, format!("{{byte: {x:#04X}, as: {x:#04X}}}"));
            end = vec![x, t];
            escaping_yaml = format!(
                "  escaping: {{escape: {x:#04X}, map: [{}], computed: unescaped}}\n",
                pairs.join(", ")
            );
        }
        Escaping::Insert => {
            // A short pattern of few distinct bytes, so that random values hold it.
            let n = *g.pick(&[1usize, 2, 2, 3]);
            let pool = [g.rng.u8(..), g.rng.u8(..)];
            let after: Vec<String> = (0..n).map(|_| format!("{:#04X}", g.pick(&pool))).collect();
            escaping_yaml = format!(
                "  escaping: {{insert: {:#04X}, after: [{}], from: code, computed: escaped}}\n",
                g.rng.u8(..),
                after.join(", ")
            );
        }
        Escaping::None => {}
    }

    // Address.
    let full = g.chance(10);
    let (dmin, dmax) = if full {
        (0u8, 255u8)
    } else {
        let a = g.rng.u8(0..=0x30);
        (a, g.rng.u8(a..=0xF0))
    };
    let outside: Vec<u8> = (0..=255u8).filter(|v| *v < dmin || *v > dmax).collect();
    let mut addr = format!("devices: {{min: {dmin}, max: {dmax}}}");
    let mut broadcast = None;
    if !outside.is_empty() && g.chance(50) {
        let b = *g.pick(&outside);
        broadcast = Some(b);
        let _ = write!(addr, ", broadcast: {b}");
    }
    let hosts: Vec<u8> = outside
        .iter()
        .copied()
        .filter(|v| Some(*v) != broadcast)
        .collect();
    if !hosts.is_empty() && g.chance(35) {
        let _ = write!(addr, ", host: {}", g.pick(&hosts));
    }
    if g.chance(40) {
        let _ = write!(addr, ", default: {}", g.rng.u8(dmin..=dmax));
    }
    if !addressed {
        broadcast = None;
    }

    // Units, enums, flags.
    let mut units = String::from("units:\n");
    for (name, scale, offset) in UNITS {
        let _ = write!(
            units,
            "  - {{name: {name}, symbol: \"{name}\", scale: \"{scale}\""
        );
        if let Some(o) = offset {
            let _ = write!(units, ", offset: \"{o}\"");
        }
        units.push_str("}\n");
    }
    let mut enums = String::new();
    if g.n_enums > 0 {
        enums.push_str("enums:\n");
        for e in 0..g.n_enums {
            let n = g.rng.usize(1..=4);
            let mut vals: Vec<u8> = Vec::new();
            while vals.len() < n {
                let v = if g.rng.bool() {
                    g.rng.u8(..6)
                } else {
                    g.rng.u8(..)
                };
                if !vals.contains(&v) {
                    vals.push(v);
                }
            }
            let items: Vec<String> = vals
                .iter()
                .enumerate()
                .map(|(k, v)| format!("{{value: {v}, name: e{e}_v{k}}}"))
                .collect();
            let _ = writeln!(
                enums,
                "  - {{name: e{e}, section: \"2\", values: [{}]}}",
                items.join(", ")
            );
        }
    }
    let mut flags = String::new();
    if g.n_flags > 0 {
        flags.push_str("flags:\n");
        let bits: Vec<String> = (0..g.rng.u8(1..=5))
            .map(|k| format!("{{bit: {k}, name: fl0_b{k}}}"))
            .collect();
        let _ = writeln!(
            flags,
            "  - {{name: fl0, section: \"2\", bits: [{}]}}",
            bits.join(", ")
        );
    }

    // Commands.
    let n_cmd = g.rng.usize(1..=5);
    let mut used1: Vec<u8> = Vec::new();
    let mut used2: Vec<[u8; 2]> = Vec::new();
    let code_for =
        |g: &mut G, lens: &[usize], used1: &mut Vec<u8>, used2: &mut Vec<[u8; 2]>, resp: bool| {
            let l = *g.pick(lens);
            match l {
                0 => Vec::new(),
                1 => loop {
                    let b = if resp {
                        g.rng.u8(0x01..=0x3F) | 0x40
                    } else {
                        g.rng.u8(0x01..=0x3F)
                    };
                    if !used1.contains(&b) {
                        used1.push(b);
                        break vec![b];
                    }
                },
                _ => loop {
                    let low = g.rng.u8(..);
                    let c = [g.rng.u8(0xC0..=0xFF), *g.pick(&[0u8, 1, 2, 3, low])];
                    if !used2.contains(&c) {
                        used2.push(c);
                        let mut code = c.to_vec();
                        // Three bytes (drawn for payload truncation: MAVLink v2's id).
                        if l == 3 {
                            code.push(*g.pick(&[0u8, 1]));
                        }
                        break code;
                    }
                },
            }
        };
    let mut commands: Vec<Gm> = Vec::new();
    for k in 0..n_cmd {
        let code = if k > 0 && !g.fixed && g.chance(10) {
            // A code shared with another command (told apart by payload length or constants).
            commands[k - 1].code.clone()
        } else {
            code_for(&mut g, &req_lens, &mut used1, &mut used2, false)
        };
        let fields = g.fields(None, None);
        let kind = *g.pick(&["movement", "completion_check", "setter", "getter", "reset"]);
        let mut extra = format!(", kind: {kind}");
        if broadcast.is_some() && g.chance(70) {
            let accepted = g.rng.bool();
            let _ = write!(
                extra,
                ", broadcast: {{accepted: {}, answered: {}}}",
                accepted,
                accepted && g.rng.bool()
            );
        }
        commands.push(Gm {
            name: format!("c{k}"),
            code,
            fields,
            extra,
        });
    }
    // Shared codes must differ in payload length or a constant: make them differ in length,
    // longer than every earlier command of the code (padding against one alone could land on
    // another's length).
    for k in 1..commands.len() {
        let same: Vec<usize> = (0..k)
            .filter(|&j| commands[j].code == commands[k].code && !commands[k].code.is_empty())
            .collect();
        let clash = same.iter().any(|&j| {
            commands[j].fixed() == commands[k].fixed()
                || commands[j].tail() > 0
                || commands[k].tail() > 0
        });
        if !clash {
            continue;
        }
        // Distinct lengths: drop the repeat, pad to one more byte than the longest other.
        commands[k].fields.retain(|f| f.repeat_tail == 0);
        commands[k].fields.retain(|f| !f.yaml.contains("repeat:"));
        let target = same
            .iter()
            .map(|&j| commands[j].fixed() + commands[j].tail() + 1)
            .max()
            .unwrap_or(0);
        let mut i = 0;
        while commands[k].fixed() < target {
            commands[k].fields.push(Gf {
                name: format!("pad{i}"),
                ty: "u8",
                width: 1,
                yaml: format!("{{name: pad{i}, type: u8, value: 1}}"),
                plain: true,
                countable: false,
                repeat_tail: 0,
            });
            i += 1;
        }
    }

    // Responses: who answers each, then their fields (a reply may follow its request).
    let n_resp = g.rng.usize(1..=5);
    let mut responses: Vec<Gm> = Vec::new();
    let mut lists: Vec<Vec<usize>> = vec![Vec::new(); n_cmd];
    let mut common: Vec<usize> = Vec::new();
    let mut needs_request: Vec<usize> = Vec::new();
    let mut resp_used1: Vec<u8> = Vec::new();
    let mut resp_used2: Vec<[u8; 2]> = Vec::new();
    let mut k = 0;
    while k < n_resp {
        let mut extra = format!(", kind: {}", g.pick(&["ack", "nak", "data", "echo"]));
        let roll = g.rng.u8(..100);
        // A reply whose code is its request's with bits set.
        let one_byte_cmds: Vec<usize> = (0..n_cmd)
            .filter(|&c| commands[c].code.len() == 1 && resp_lens.contains(&1))
            .collect();
        if roll < 15 && !one_byte_cmds.is_empty() {
            let c = *g.pick(&one_byte_cmds);
            let code = vec![commands[c].code[0] | 0x80];
            let answered: Vec<usize> = (0..n_cmd)
                .filter(|&x| commands[x].code.len() == 1 && commands[x].code[0] | 0x80 == code[0])
                .collect();
            if resp_used1.contains(&code[0]) {
                k += 1;
                continue;
            }
            resp_used1.push(code[0]);
            let _ = write!(extra, ", code_from_request: {{or: 0x80}}");
            for &x in &answered {
                lists[x].push(k);
            }
            let fields = g.fields(None, None);
            responses.push(Gm {
                name: format!("r{k}"),
                code,
                fields,
                extra,
            });
            k += 1;
            continue;
        }
        // Two replies only their requests tell apart.
        if roll < 30 && n_cmd >= 2 && k + 1 < n_resp {
            let code = code_for(&mut g, &resp_lens, &mut resp_used1, &mut resp_used2, true);
            let n = g.rng.usize(1..=3);
            let mk = |g: &mut G, signed: bool| -> Vec<Gf> {
                (0..n)
                    .map(|i| {
                        let ty = if signed { "i8" } else { "u8" };
                        let _ = g;
                        Gf {
                            name: format!("f{i}"),
                            ty,
                            width: 1,
                            yaml: format!("{{name: f{i}, type: {ty}, unit: count}}"),
                            plain: true,
                            countable: !signed,
                            repeat_tail: 0,
                        }
                    })
                    .collect()
            };
            let a = g.rng.usize(..n_cmd);
            let b = (a + g.rng.usize(1..n_cmd)) % n_cmd;
            for (j, c, signed) in [(k, a, false), (k + 1, b, true)] {
                lists[c].push(j);
                needs_request.push(j);
                let fields = mk(&mut g, signed);
                responses.push(Gm {
                    name: format!("r{j}"),
                    code: code.clone(),
                    fields,
                    extra: format!("{extra}, needs_request: true"),
                });
            }
            k += 2;
            continue;
        }
        let code = code_for(&mut g, &resp_lens, &mut resp_used1, &mut resp_used2, true);
        let is_common = g.chance(25);
        let answered: Vec<usize> = if is_common {
            common.push(k);
            (0..n_cmd).collect()
        } else {
            let mut v: Vec<usize> = (0..n_cmd).filter(|_| g.chance(50)).collect();
            if v.is_empty() {
                v.push(g.rng.usize(..n_cmd));
            }
            for &c in &v {
                lists[c].push(k);
            }
            v
        };
        // A field every answered command has, for `follows: {request}` and `repeat.request`.
        let shared: Vec<String> = commands[answered[0]]
            .fields
            .iter()
            .filter(|f| f.plain && f.ty != "ascii")
            .map(|f| f.name.clone())
            .filter(|n| {
                answered.iter().all(|&c| {
                    commands[c]
                        .fields
                        .iter()
                        .any(|f| &f.name == n && f.plain && f.ty != "ascii")
                })
            })
            .collect();
        let (rf, ff) = if !shared.is_empty() && g.chance(50) {
            let q = g.pick(&shared).clone();
            if g.rng.bool() {
                (Some(q), None)
            } else {
                (None, Some(q))
            }
        } else {
            (None, None)
        };
        let fields = g.fields(rf.as_deref(), ff.as_deref());
        responses.push(Gm {
            name: format!("r{k}"),
            code,
            fields,
            extra,
        });
        k += 1;
    }
    // Responses sent unasked (`unasked: true`), drawn by a generator of their own so every
    // spec drawn without them is as it was: in about a fifth of the specs, replies that need
    // no request made also sent unasked, and often a response no command lists (a
    // heartbeat), which the stream decoders meet after requests whose reply it is not.
    let mut unlisted: Vec<usize> = Vec::new();
    g.with_own(seed, Own::Unasked, |g| {
        if !g.chance(20) {
            return;
        }
        for r in responses.iter_mut() {
            let alone = !r.extra.contains("code_from_request")
                && !r.extra.contains("needs_request")
                && !r.fields.iter().any(|f| f.yaml.contains("request:"));
            if alone && g.chance(30) {
                r.extra.push_str(", unasked: true");
            }
        }
        if g.chance(70) {
            let code = code_for(g, &resp_lens, &mut resp_used1, &mut resp_used2, true);
            let fields = g.fields(None, None);
            let kind = g.pick(&["ack", "nak", "data", "echo"]);
            unlisted.push(k);
            responses.push(Gm {
                name: format!("r{k}"),
                code,
                fields,
                extra: format!(", kind: {kind}, unasked: true"),
            });
            k += 1;
        }
    });
    // Responses sharing a code that are not a needs_request pair must not clash: the codes
    // were drawn distinct, so only code-less ones share one, which the validator allows.
    // Every response is listed by some command (or is common), but one sent unasked only.
    for (j, r) in responses.iter().enumerate() {
        let idx: usize = r.name[1..].parse().unwrap_or(0);
        let listed = common.contains(&idx)
            || unlisted.contains(&idx)
            || lists.iter().any(|l| l.contains(&idx));
        if !listed {
            lists[j % n_cmd].push(idx);
        }
    }

    // Every command lists a response of its own: one that any command may get.
    let plain: Vec<usize> = responses
        .iter()
        .filter(|r| !r.extra.contains("code_from_request") && !r.extra.contains("needs_request"))
        .filter(|r| !r.fields.iter().any(|f| f.yaml.contains("request:")))
        .filter_map(|r| r.name[1..].parse().ok())
        .filter(|k| !common.contains(k) && !unlisted.contains(k))
        .collect();
    #[allow(clippy::needless_range_loop)]
    for c in 0..n_cmd {
        if lists[c].is_empty() && common.is_empty() {
            if plain.is_empty() {
                let k = responses.len().max(n_resp) + c;
                let code = code_for(&mut g, &resp_lens, &mut resp_used1, &mut resp_used2, true);
                responses.push(Gm {
                    name: format!("r{k}"),
                    code,
                    fields: Vec::new(),
                    extra: ", kind: ack".into(),
                });
                lists[c].push(k);
            } else {
                lists[c].push(*g.pick(&plain));
            }
        }
    }

    // Commands that get no reply (each response they list is listed by another command too,
    // or common) and commands whose reply is optional.
    let mut reply: Vec<&str> = vec![""; n_cmd];
    for c in 0..n_cmd {
        if g.chance(10) && !commands[c].extra.contains("answered: true") {
            let elsewhere = lists[c].iter().all(|r| {
                common.contains(r)
                    || (0..n_cmd)
                        .any(|o| o != c && reply[o] != ", reply: none" && lists[o].contains(r))
            });
            let others_reply = (0..n_cmd).any(|o| o != c && reply[o] != ", reply: none");
            if elsewhere && others_reply {
                reply[c] = ", reply: none";
                lists[c].clear();
            }
        } else if g.chance(10) {
            reply[c] = ", reply: optional";
        }
    }

    tag_codeless(&mut commands);
    tag_codeless(&mut responses);

    // Optional fields (`present:`): where the frames have a length field and nothing
    // escapes, in about 13 % of the messages that may have them; drawn by a generator of
    // their own (`Own`), so every spec drawn without them is as it was.
    if has_length && escaping == Escaping::None && !g.fixed {
        g.with_own(seed, Own::Optionals, |g| {
            g.optionals(&mut commands);
            g.optionals(&mut responses);
        });
    }

    // Counted text (`type: ascii` with `repeat`): a list of plain u8 elements (a unit, no
    // range, no enum, no record) becomes text of as many characters, in about 30 % of the
    // messages that have one; drawn by a generator of its own, so every spec drawn without
    // them is as it was (the count field, bounds and tail stay the list's).
    {
        let mut rng = own_rng(seed, Own::CountedText);
        for m in commands.iter_mut().chain(responses.iter_mut()) {
            let Some(f) = m.fields.iter_mut().find(|f| counted_text_eligible(f)) else {
                continue;
            };
            if rng.u8(..100) >= 30 {
                continue;
            }
            if let (Some(a), Some(b)) = (f.yaml.find("type: u8, unit: "), f.yaml.find(", repeat:"))
            {
                f.yaml = format!("{}type: ascii{}", &f.yaml[..a], &f.yaml[b..]);
                f.ty = "ascii";
            }
        }
    }

    // Text up to a terminator (`repeat: {until}`): counted text becomes text ended by a
    // terminator byte (0x00 mostly) in about 40 % of the messages that have it, where frames
    // have a length field (which the validator requires); its count field stays as a plain
    // field. Drawn by a generator of its own, so every spec drawn without it is as it was.
    if has_length {
        let mut rng = own_rng(seed, Own::TerminatedText);
        for m in commands.iter_mut().chain(responses.iter_mut()) {
            for f in m.fields.iter_mut().filter(|f| f.ty == "ascii") {
                let Some(a) = f.yaml.find("repeat: {count: ") else {
                    continue;
                };
                if rng.u8(..100) >= 40 {
                    continue;
                }
                let start = a + "repeat: {".len();
                let Some(len) = f.yaml[start..].find(", ") else {
                    continue;
                };
                let mut rest = f.yaml[start + len..].to_owned();
                for of in [", of: elements", ", of: bytes"] {
                    rest = rest.replacen(of, "", 1);
                }
                let t = if rng.u8(..4) == 0 { rng.u8(..) } else { 0 };
                f.yaml = format!("{}until: {t:#04X}{rest}", &f.yaml[..start]);
                // Its terminator travels after the characters.
                f.repeat_tail += 1;
            }
        }
    } else if escaping == Escaping::None {
        // Without a length field only the terminator ends the frame (RoboClaw's firmware
        // version): counted text becomes text up to a terminator in about 40 % of the messages
        // where it is the only list and no other message of the direction shares the code (a
        // stream decoder frames one variable-length message per code). Drawn by a generator
        // of its own, so every spec drawn without it is as it was.
        let mut rng = own_rng(seed, Own::TerminatedFrame);
        for msgs in [&mut commands, &mut responses] {
            let codes: Vec<Vec<u8>> = msgs.iter().map(|m| m.code.clone()).collect();
            for (k, m) in msgs.iter_mut().enumerate() {
                let lists = m
                    .fields
                    .iter()
                    .filter(|f| f.yaml.contains("repeat: {"))
                    .count();
                let apart = codes
                    .iter()
                    .enumerate()
                    .all(|(j, c)| j == k || !(c.starts_with(&m.code) || m.code.starts_with(c)));
                if !apart || m.fields.iter().any(|f| f.yaml.contains("present:")) {
                    continue;
                }
                // A message without a list may end in such text, in about one in eight.
                if lists == 0 && rng.u8(..100) < 12 {
                    let (min, max) = (rng.usize(..=1), rng.usize(1..=12));
                    let t = if rng.u8(..4) == 0 { rng.u8(..) } else { 0 };
                    m.fields.push(Gf {
                        name: "txt".to_owned(),
                        ty: "ascii",
                        width: 1,
                        yaml: format!(
                            "{{name: txt, type: ascii, repeat: {{until: {t:#04X}, min: {min}, max: {max}}}}}"
                        ),
                        plain: false,
                        countable: false,
                        repeat_tail: max + 1,
                    });
                    continue;
                }
                if lists != 1 {
                    continue;
                }
                for f in m.fields.iter_mut().filter(|f| f.ty == "ascii") {
                    let Some(a) = f.yaml.find("repeat: {count: ") else {
                        continue;
                    };
                    if rng.u8(..100) >= 40 {
                        continue;
                    }
                    let start = a + "repeat: {".len();
                    let Some(len) = f.yaml[start..].find(", ") else {
                        continue;
                    };
                    let mut rest = f.yaml[start + len..].to_owned();
                    for of in [", of: elements", ", of: bytes"] {
                        rest = rest.replacen(of, "", 1);
                    }
                    let t = if rng.u8(..4) == 0 { rng.u8(..) } else { 0 };
                    f.yaml = format!("{}until: {t:#04X}{rest}", &f.yaml[..start]);
                    f.repeat_tail += 1;
                }
            }
        }
    }

    // Lists of a fixed count (`repeat: {count: N}`): packed elements of whole bytes in the
    // protocol's byte order (any order for u8) are written so in about 60 % of the fields that
    // may be; the same bytes, so the rest of the spec stays as it was drawn. Drawn by a
    // generator of its own.
    {
        let mut rng = own_rng(seed, Own::FixedList);
        let order = if bo == "little" {
            "lsb_first"
        } else {
            "msb_first"
        };
        for f in commands
            .iter_mut()
            .chain(responses.iter_mut())
            .flat_map(|m| m.fields.iter_mut())
        {
            let Some(at) = f.yaml.find(", packed: {count: ") else {
                continue;
            };
            let tw = match f.ty {
                "u8" => 8,
                "u16" => 16,
                "u32" => 32,
                _ => continue,
            };
            let rest = &f.yaml[at + ", packed: {count: ".len()..];
            let Some(close) = rest.find('}') else {
                continue;
            };
            let inner = &rest[..close];
            let mut parts = inner.split(", ");
            let count = parts.next().unwrap_or("");
            let whole = inner.contains(&format!("bits: {tw},"));
            if !whole || !(tw == 8 || inner.ends_with(order)) || rng.u8(..100) >= 60 {
                continue;
            }
            f.yaml = format!(
                "{}, repeat: {{count: {count}}}{}",
                &f.yaml[..at],
                &rest[close + 1..]
            );
        }
    }

    // Only in a message whose code no other message of its direction has: messages that share
    // a code (or have none) are told apart by their lengths (padding drawn from the lists as
    // they were), which a list that takes other bytes would blur.
    let own_code = |ms: &[Gm]| -> Vec<bool> {
        ms.iter()
            .map(|m| !m.code.is_empty() && ms.iter().filter(|o| o.code == m.code).count() == 1)
            .collect()
    };
    // Lists of floats and 64-bit integers (a meter's block of float registers): about 30 % of
    // the lists of integers of a unit as drawn become lists of u64, i64, f32 or f64 (maybe
    // word-swapped, maybe with a range), counted as they were. Drawn by a generator of its own.
    {
        let mut rng = own_rng(seed, Own::WideLists);
        let (own_c, own_r) = (own_code(&commands), own_code(&responses));
        for f in commands
            .iter_mut()
            .zip(own_c)
            .chain(responses.iter_mut().zip(own_r))
            .filter(|(_, own)| *own)
            .flat_map(|(m, _)| m.fields.iter_mut())
        {
            let own = format!("{{name: {}, type: {}, unit: ", f.name, f.ty);
            let eligible = matches!(f.ty, "u8" | "u16" | "i16" | "u24" | "i32")
                && f.repeat_tail > 0
                && f.yaml.starts_with(&own)
                && !f.yaml.contains("until:")
                && !fixed_count(f);
            let Some(at) = f.yaml.find(", repeat: {").filter(|_| eligible) else {
                continue;
            };
            if rng.u8(..100) >= 30 {
                continue;
            }
            let max: usize = f.yaml[at..]
                .split("max: ")
                .nth(1)
                .map(|r| {
                    r.chars()
                        .take_while(char::is_ascii_digit)
                        .collect::<String>()
                })
                .and_then(|d| d.parse().ok())
                .unwrap_or(1);
            let (ty, width) = [("u64", 8), ("i64", 8), ("f32", 4), ("f64", 8)][rng.usize(..4)];
            let mut y = format!("{{name: {}, type: {ty}, unit: count", f.name);
            if rng.u8(..100) < 40 {
                y.push_str(", word_order: swapped");
            }
            if rng.u8(..100) < 40 {
                let r = match ty {
                    "u64" => {
                        let a = rng.u64(..4);
                        format!("{{min: {a}, max: {}}}", a + rng.u64(..100))
                    }
                    "i64" => {
                        let a = rng.i64(-5..4);
                        format!("{{min: {a}, max: {}}}", a + rng.i64(0..100))
                    }
                    _ => {
                        let a = f64::from(rng.i32(-400..400)) / 4.0;
                        let b = a + f64::from(rng.i32(0..400)) / 4.0;
                        format!("{{min: {a:?}, max: {b:?}}}")
                    }
                };
                let _ = write!(y, ", range: {r}");
            }
            f.yaml = format!("{y}{}", &f.yaml[at..]);
            f.ty = ty;
            f.width = width;
            f.repeat_tail = (max * width).max(1);
        }
    }

    // Records of a fixed count (`repeat: {count: N}`, UBX's fixed blocks): about 40 % of the
    // records as drawn (not those whose width a field gives, nor those counted by the
    // request) become exactly 1 to 3 of them; a field that counted them stays, a free number.
    // Drawn by a generator of its own.
    {
        let mut rng = own_rng(seed, Own::FixedRecords);
        let (own_c, own_r) = (own_code(&commands), own_code(&responses));
        for f in commands
            .iter_mut()
            .zip(own_c)
            .chain(responses.iter_mut().zip(own_r))
            .filter(|(_, own)| *own)
            .flat_map(|(m, _)| m.fields.iter_mut())
        {
            // A record's `ty` is the type drawn for a list (records whose width a field gives:
            // "record"): its YAML says what it is.
            let record = f
                .yaml
                .starts_with(&format!("{{name: {}, type: record,", f.name));
            if !record || f.yaml.contains("bytes:") || f.yaml.contains("request:") {
                continue;
            }
            let Some(at) = f.yaml.find(", repeat: {") else {
                continue;
            };
            if rng.u8(..100) >= 40 {
                continue;
            }
            let n = rng.usize(1..=3);
            f.yaml = format!("{}, repeat: {{count: {n}}}}}", &f.yaml[..at]);
            f.repeat_tail = n * f.width;
        }
    }

    // Payloads longer than 255 bytes (UBX's NAV-SAT, MSP v2's long replies, KISS's data
    // frames): where frames have a length field, or none and an end byte frames them (escaped,
    // SLIP, KISS, COBS; or end bytes alone), in about half the specs with an eligible list, a
    // list to the end (of numbers, text or records) may hold enough elements to pass 255
    // bytes, up to 4096, and a length field is two bytes wide. Drawn by a generator of its
    // own, so every spec drawn without it is as it was.
    let framed_by_end =
        !has_length && !end.is_empty() && (escaping != Escaping::None || csum_len == 0);
    let big = (has_length || framed_by_end) && {
        let mut rng = own_rng(seed, Own::BigPayload);
        // Only in a message whose code no other message of its direction has: messages that
        // share a code (or have none) are told apart by their lengths, which it would blur.
        let own_code = |ms: &[Gm]| -> Vec<bool> {
            ms.iter()
                .map(|m| !m.code.is_empty() && ms.iter().filter(|o| o.code == m.code).count() == 1)
                .collect()
        };
        let (own_c, own_r) = (own_code(&commands), own_code(&responses));
        let mut eligible: Vec<&mut Gf> = commands
            .iter_mut()
            .zip(own_c)
            .chain(responses.iter_mut().zip(own_r))
            .filter(|(_, own)| *own)
            .flat_map(|(m, _)| m.fields.iter_mut())
            .filter(|f| {
                f.yaml.contains("repeat: {count: end")
                    && !f.yaml.contains("bytes:")
                    && f.ty != "bit"
            })
            .collect();
        if rng.u8(..100) < 50 && !eligible.is_empty() {
            let at = rng.usize(..eligible.len());
            let f = &mut eligible[at];
            let w = f.width.max(1);
            let most = rng.usize(256 / w + 1..=4000 / w);
            let from = f.yaml.rfind(", max: ").unwrap_or(f.yaml.len());
            f.yaml = format!("{}, max: {most}}}}}", &f.yaml[..from]);
            f.repeat_tail = most * w;
            true
        } else {
            false
        }
    };

    // Payload bounds per direction (the shortest without optional fields).
    let bounds = |ms: &[Gm]| {
        let lo = ms
            .iter()
            .map(|m| m.fixed() - m.optional() + min_tail(m))
            .min()
            .unwrap_or(0);
        let hi = ms.iter().map(|m| m.fixed() + m.tail()).max().unwrap_or(0);
        (lo, hi)
    };
    fn min_tail(m: &Gm) -> usize {
        // The repeat's minimum is small (at most 2 elements of at most 4 bytes): take 0, and
        // widen the lower bound to it (a payload minimum below every message is allowed).
        let _ = m;
        0
    }
    let (qlo, qhi) = bounds(&commands);
    let (slo, shi) = bounds(&responses);
    let qlo = g.rng.usize(0..=qlo);
    let slo = g.rng.usize(0..=slo);
    let qhi = qhi + g.rng.usize(0..=2);
    let shi = shi + g.rng.usize(0..=2);

    let mut framing = String::from("framing:\n  section: \"2\"\n");
    let _ = writeln!(framing, "  layout: [{}]", layout.join(", "));
    // Start bytes that differ by direction (MSP's `$M<` and `$M>`): one byte of the
    // response's differs.
    let response_sync = if !sync.is_empty() && escaping == Escaping::None && g.chance(15) {
        let mut r = sync.clone();
        let i = g.rng.usize(0..r.len());
        r[i] = r[i].wrapping_add(g.rng.u8(1..=255));
        Some(r)
    } else {
        None
    };
    let list = |s: &[u8]| {
        let items: Vec<String> = s.iter().map(|b| format!("{b:#04X}")).collect();
        format!("[{}]", items.join(", "))
    };
    match sync.len() {
        0 => {}
        _ if response_sync.is_some() => {
            let r = response_sync.as_deref().unwrap_or_default();
            let _ = writeln!(
                framing,
                "  start: {{request: {}, response: {}}}",
                list(&sync),
                list(r)
            );
        }
        1 => {
            let _ = writeln!(framing, "  start: {:#04X}", sync[0]);
        }
        _ => {
            let _ = writeln!(framing, "  start: {}", list(&sync));
        }
    }
    if has_length {
        // Stuffed frames count their stuffed bytes, at worst one in every pattern's length.
        let stuffed = escaping == Escaping::Insert;
        let width = if g.chance(70) && !stuffed && !big {
            1
        } else {
            2
        };
        let mut parts: Vec<&str> = Vec::new();
        // Each part once, though the layout may hold a start or the length twice.
        for p in layout.iter().copied() {
            if !parts.contains(&p) && (p != "length" || g.chance(20)) && g.chance(70) {
                parts.push(p);
            }
        }
        // It counts the payload, as the validator requires (and the code where it is stuffed).
        if !parts.contains(&"payload") {
            parts.push("payload");
        }
        if stuffed {
            let code_at = pos(&layout, "code");
            for part in ["code", "address"] {
                if pos(&layout, part) >= code_at && !parts.contains(&part) {
                    parts.push(part);
                }
            }
        }
        g.rng.shuffle(&mut parts);
        // The smallest count, so the adjustment keeps every value at or above zero.
        let size = |p: &str| match p {
            "start" => sync.len(),
            "address" => 1,
            "length" => width,
            "code" => req_lens
                .iter()
                .chain(&resp_lens)
                .copied()
                .min()
                .unwrap_or(0),
            "payload" => qlo.min(slo),
            "end" => end.len(),
            "header" => header_len,
            _ => csum_len,
        };
        let least: usize = parts.iter().map(|p| size(p)).sum();
        let adjust = g.rng.i64(-(least.min(2) as i64)..=2);
        let _ = write!(
            framing,
            "  length: {{width: {width}, counts: [{}]",
            parts.join(", ")
        );
        if adjust != 0 || g.chance(30) {
            let _ = write!(framing, ", adjust: {adjust}");
        }
        framing.push_str("}\n");
    }
    if !header.is_empty() {
        let items: Vec<&str> = header.iter().map(|h| h.0.as_str()).collect();
        let _ = writeln!(framing, "  header: [{}]", items.join(", "));
    }
    match end.len() {
        0 => {}
        1 => {
            let _ = writeln!(framing, "  end: {:#04X}", end[0]);
        }
        _ => {
            let items: Vec<String> = end.iter().map(|b| format!("{b:#04X}")).collect();
            let _ = writeln!(framing, "  end: [{}]", items.join(", "));
        }
    }
    if addressed {
        let _ = writeln!(framing, "  address: {{{addr}}}");
    }
    let lens = |l: &[usize]| {
        l.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(
        framing,
        "  request: {{code_lengths: [{}], payload: {{min: {qlo}, max: {qhi}}}}}",
        lens(&req_lens)
    );
    let _ = writeln!(
        framing,
        "  response: {{code_lengths: [{}], payload: {{min: {slo}, max: {shi}}}}}",
        lens(&resp_lens)
    );
    let mut cs = csum;
    // What the checksum may cover from: a part of the layout before the payload.
    // A part after the code moves with the code's length: only where every code has one.
    let mut lens: Vec<usize> = req_lens.iter().chain(&resp_lens).copied().collect();
    lens.sort_unstable();
    lens.dedup();
    let code_at = layout.iter().position(|p| *p == "code");
    let before: Vec<&str> = layout
        .iter()
        .copied()
        .enumerate()
        .take_while(|(_, p)| *p != "payload")
        .filter(|(i, _)| lens.len() == 1 || code_at.map_or(true, |c| *i <= c))
        .map(|(_, p)| p)
        .collect();
    let mut from = layout.first().copied().unwrap_or("");
    if !cs.is_empty() && g.chance(40) {
        from = *g.pick(&before);
        let _ = write!(cs, ", covers_from: {from}");
    }
    // A CRC that takes each message's extra byte (MAVLink's CRC_EXTRA): where nothing
    // escapes, every code has one length and the checksum covers the code. The byte is drawn
    // per code, so a request and a response of one code take the same.
    let pos = |part: &str| layout.iter().position(|p| *p == part);
    let extra_by_code = cs.starts_with("algorithm: crc")
        && escaping == Escaping::None
        && matches!(lens.as_slice(), [n] if *n > 0)
        && pos(from) <= pos("code")
        && !responses
            .iter()
            .any(|r| r.extra.contains("code_from_request"))
        && g.chance(70);
    let mut extras: Vec<(Vec<u8>, u8)> = Vec::new();
    let mut extra_of = |g: &mut G, code: &[u8]| -> String {
        if !extra_by_code {
            return String::new();
        }
        let x = match extras.iter().find(|(c, _)| c.as_slice() == code) {
            Some((_, x)) => *x,
            None => {
                let x = g.rng.u8(..);
                extras.push((code.to_vec(), x));
                x
            }
        };
        format!(", checksum_extra: {x}")
    };
    if extra_by_code {
        cs.push_str(", extra: per_message");
    }
    if !cs.is_empty() {
        let _ = writeln!(framing, "  checksum: {{{cs}}}");
    }
    framing.push_str(&escaping_yaml);

    // A length field whose width the start byte chooses (VESC's `02 len …` and `03 lenH lenL
    // …`): where the layout begins with start bytes (the same both ways) and the length
    // field, each once, and nothing escapes (three such specs in five); drawn by a
    // generator of its own, so every spec drawn without one is as it was. A spec that takes it
    // is made to fit: one start byte (a sync sequence's first), a one-byte short field that
    // counts neither the start byte nor itself
    // (half of them adjusted near 255, so frames of both forms occur), a checksum that covers
    // from the part after the length field, examples printed in the wire's byte order.
    let once = |x: &str| layout.iter().filter(|p| **p == x).count() == 1;
    let length_line = framing
        .lines()
        .find(|l| l.starts_with("  length: {"))
        .map(str::to_owned);
    let after_length = layout.get(2).copied().unwrap_or("payload");
    let long_form = layout.starts_with(&["start", "length"])
        && once("start")
        && once("length")
        && !sync.is_empty()
        && response_sync.is_none()
        && escaping == Escaping::None
        && (cs.is_empty() || after_length != "payload")
        && length_line.is_some()
        && {
            let mut rng = own_rng(seed, Own::TakesLongForm);
            rng.u8(..100) < 60
        };
    if let (true, Some(line)) = (long_form, &length_line) {
        let mut rng = own_rng(seed, Own::LongForm);
        let start = loop {
            let b = rng.u8(..);
            if b != sync[0] {
                break b;
            }
        };
        let counts: Vec<&str> = line
            .split("counts: [")
            .nth(1)
            .and_then(|r| r.split(']').next())
            .unwrap_or("payload")
            .split(", ")
            .filter(|p| *p != "start" && *p != "length")
            .collect();
        let adjust = if rng.bool() {
            rng.i64(240..=256)
        } else {
            rng.i64(0..=2)
        };
        let long = format!(
            "  length: {{width: 1, counts: [{}], adjust: {adjust}, long: {{start: {start:#04X}, width: 2}}}}",
            counts.join(", ")
        );
        framing = framing.replacen(line.as_str(), &long, 1);
        if let Some(ck) = framing
            .lines()
            .find(|l| l.starts_with("  checksum: {"))
            .map(str::to_owned)
        {
            // Its `covers_from` item out (whatever follows it kept), the new one last.
            let body = ck.trim_end_matches('}');
            let body = match body.find(", covers_from: ") {
                Some(at) => {
                    let rest = &body[at + 2..];
                    let tail = rest.find(", ").map_or("", |k| &rest[k..]);
                    format!("{}{tail}", &body[..at])
                }
                None => body.to_owned(),
            };
            let fixed = format!("{body}, covers_from: {after_length}}}");
            framing = framing.replacen(ck.as_str(), &fixed, 1);
        }
        // One start byte: a sync sequence keeps its first.
        if let Some(st) = framing
            .lines()
            .find(|l| l.starts_with("  start: "))
            .map(str::to_owned)
        {
            framing = framing.replacen(st.as_str(), &format!("  start: {:#04X}", sync[0]), 1);
        }
        y = y.replacen(
            &format!("printed_byte_order: {pbo}"),
            &format!("printed_byte_order: {bo}"),
            1,
        );
    }

    // A short form of the frame (M-Bus's `10 C A CS 16` beside `68 L L 68 ...`): where the
    // layout begins with start bytes (the same both ways) and holds the length field's copies
    // together (with the start bytes again where they sit beside them: the parts the form
    // drops), every code has one length, nothing escapes, no header field and no long form
    // and no checksum byte per message found by a code before them (three eligible specs in
    // four: about 2 % of specs); drawn by a generator of its own, so
    // every spec drawn without one is as it was. A spec that takes it is made to fit: one start
    // byte (a sync sequence's first), a checksum that covers from the part after the dropped
    // ones, examples printed in the wire's byte order; no preamble or transform, no constant
    // frame beginning with its start byte.
    let lengths: Vec<usize> = (0..layout.len())
        .filter(|&i| layout[i] == "length")
        .collect();
    let again = (1..layout.len()).find(|&i| layout[i] == "start");
    let (mut run_lo, mut run_hi) = (
        lengths.first().copied().unwrap_or(0),
        lengths.last().map_or(0, |l| l + 1),
    );
    let mut run_ok = !lengths.is_empty() && run_hi - run_lo == lengths.len();
    let mut drops_start = false;
    match again {
        Some(i) if i == run_hi => (run_hi, drops_start) = (i + 1, true),
        Some(i) if i + 1 == run_lo => (run_lo, drops_start) = (i, true),
        Some(_) => run_ok = false,
        None => {}
    }
    run_ok &= run_lo > 0;
    let after_run = layout.get(run_hi).copied().unwrap_or("payload");
    let same_code_len = req_lens
        .iter()
        .chain(&resp_lens)
        .all(|l| Some(l) == req_lens.first());
    let short_form: Option<u8> = if layout.first() == Some(&"start")
        && run_ok
        && !long_form
        && !sync.is_empty()
        && response_sync.is_none()
        && escaping == Escaping::None
        && header.is_empty()
        && same_code_len
        && (cs.is_empty() || after_run != "payload")
        && length_line.is_some()
        // A byte per message is found by the code, which the checksum then covers.
        && !(extra_by_code && pos("code") < Some(run_hi))
    {
        let mut rng = own_rng(seed, Own::ShortForm);
        (rng.u8(..100) < 75).then(|| loop {
            let b = rng.u8(..);
            if b != sync[0] {
                break b;
            }
        })
    } else {
        None
    };
    if let Some(start) = short_form {
        let drops = if drops_start {
            "length, start"
        } else {
            "length"
        };
        let _ = writeln!(
            framing,
            "  forms:\n    - {{start: {start:#04X}, drops: [{drops}]}}"
        );
        if let Some(ck) = framing
            .lines()
            .find(|l| l.starts_with("  checksum: {"))
            .map(str::to_owned)
        {
            // Its `covers_from` item out (whatever follows it kept), the new one last.
            let body = ck.trim_end_matches('}');
            let body = match body.find(", covers_from: ") {
                Some(at) => {
                    let rest = &body[at + 2..];
                    let tail = rest.find(", ").map_or("", |k| &rest[k..]);
                    format!("{}{tail}", &body[..at])
                }
                None => body.to_owned(),
            };
            let fixed = format!("{body}, covers_from: {after_run}}}");
            framing = framing.replacen(ck.as_str(), &fixed, 1);
        }
        // One start byte: a sync sequence keeps its first.
        if let Some(st) = framing
            .lines()
            .find(|l| l.starts_with("  start: "))
            .map(str::to_owned)
        {
            framing = framing.replacen(st.as_str(), &format!("  start: {:#04X}", sync[0]), 1);
        }
        y = y.replacen(
            &format!("printed_byte_order: {pbo}"),
            &format!("printed_byte_order: {bo}"),
            1,
        );
        // Room for a command without payload (`short_cmd`, below), which travels short.
        framing = framing.replacen(
            &format!("payload: {{min: {qlo}, max: {qhi}}}"),
            &format!("payload: {{min: 0, max: {qhi}}}"),
            1,
        );
        // A negative adjustment was drawn for the payloads as they were (at least `qlo` and
        // `slo` bytes): with empty ones now, the length could say less than zero (seed
        // 218775648902149: `counts: [payload, start], adjust: -2`), so it is dropped.
        if let Some(line) = framing
            .lines()
            .find(|l| l.starts_with("  length: {") && l.contains(", adjust: -"))
            .map(str::to_owned)
        {
            let at = line.find(", adjust: -").unwrap_or(0);
            let rest = &line[at + 2..];
            let tail = rest.find([',', '}']).map_or("", |k| &rest[k..]);
            let fixed = format!("{}{tail}", &line[..at]);
            framing = framing.replacen(line.as_str(), &fixed, 1);
        }
    }

    // Constant whole frames (M-Bus's single character E5): where every frame begins with its
    // start bytes and nothing escapes, carries header fields or takes a byte per message, one or
    // two responses of 1 to 3 bytes, none beginning with a start byte, none a prefix of
    // another, each listed by some commands that get a reply.
    let mut constants: Vec<Vec<u8>> = Vec::new();
    // The first start byte of each direction (requests', responses'), where frames have one.
    let first_starts: Option<[u8; 2]> = sync.first().map(|&s| {
        let r = response_sync.as_ref().and_then(|r| r.first().copied());
        [s, r.unwrap_or(s)]
    });
    let mut constant_of: Vec<Vec<usize>> = vec![Vec::new(); n_cmd];
    let replying: Vec<usize> = (0..n_cmd)
        .filter(|&c| reply[c] != ", reply: none")
        .collect();
    if layout.first() == Some(&"start")
        && !sync.is_empty()
        && escaping == Escaping::None
        && header.is_empty()
        && !extra_by_code
        && !replying.is_empty()
        && !long_form
        && g.chance(13)
    {
        let starts = first_starts.unwrap_or_default();
        for _ in 0..g.rng.usize(1..=2) {
            let len = *g.pick(&[1, 1, 1, 2, 3]);
            let bytes: Vec<u8> = (0..len).map(|_| g.rng.u8(..)).collect();
            let prefix = constants
                .iter()
                .any(|o| o.starts_with(&bytes) || bytes.starts_with(o));
            if starts.contains(&bytes[0]) || prefix || short_form == Some(bytes[0]) {
                continue;
            }
            let k = constants.len();
            constants.push(bytes);
            let mut listed = false;
            for &c in &replying {
                if g.chance(50) {
                    constant_of[c].push(k);
                    listed = true;
                }
            }
            if !listed {
                constant_of[*g.pick(&replying)].push(k);
            }
        }
    }

    // A preamble of wake-up bytes (DL/T 645's FE FE FE FE): where every frame begins with its
    // start bytes, nothing escapes and no frame is constant; drawn by a generator of its own,
    // so every spec drawn without one is as it was.
    if constants.is_empty()
        && !long_form
        && short_form.is_none()
        && layout.first() == Some(&"start")
        && !sync.is_empty()
        && escaping == Escaping::None
    {
        let mut rng = own_rng(seed, Own::Preamble);
        if rng.u8(..100) < 12 {
            let starts = first_starts.unwrap_or_default();
            let byte = loop {
                let b = if rng.bool() { 0xFE } else { rng.u8(..) };
                if !starts.contains(&b) {
                    break b;
                }
            };
            let send = rng.u8(..=4);
            let max = rng.u8(send.max(1)..=send + 3);
            let _ = writeln!(
                framing,
                "  preamble: {{byte: {byte:#04X}, send: {send}, max: {max}}}"
            );
        }
    }
    // A per-byte transform of the payload (DL/T 645's +33H): where nothing escapes, every code
    // has one length, and a list counted by a field has a length field beside it (about one
    // spec in ten; 40 % of those: 4 % of specs); drawn by a generator of its own, so every
    // spec drawn without one is as it was.
    let one_code_len = req_lens
        .iter()
        .chain(&resp_lens)
        .all(|l| Some(l) == req_lens.first());
    let counted = commands.iter().chain(&responses).any(|m| {
        m.fields
            .iter()
            .any(|f| f.yaml.contains("repeat: {count: ") && !f.yaml.contains("repeat: {count: end"))
    });
    // Never beside text up to a terminator (not expressible yet).
    let terminated = commands
        .iter()
        .chain(&responses)
        .any(|m| m.fields.iter().any(|f| f.yaml.contains("repeat: {until: ")));
    // Nor where end bytes alone delimit a list to the end (not expressible yet).
    let to_end = commands.iter().chain(&responses).any(|m| {
        m.fields
            .iter()
            .any(|f| f.yaml.contains("repeat: {count: end"))
    });
    let delimited = !end.is_empty() && csum_len == 0 && !has_length && to_end;
    if escaping == Escaping::None
        && one_code_len
        && (has_length || !counted)
        && !long_form
        && !terminated
        && !delimited
        && short_form.is_none()
        && !g.fixed
    {
        let mut rng = own_rng(seed, Own::Transform);
        if rng.u8(..100) < 40 {
            let k = rng.u8(1..);
            let kind = if rng.bool() { "add" } else { "xor" };
            let _ = writeln!(framing, "  transform: {{{kind}: {k:#04X}}}");
        }
    }
    y.push_str(&framing);
    y.push_str(&units);
    y.push_str(&enums);
    y.push_str(&flags);
    y.push_str("commands:\n");
    for (c, m) in commands.iter().enumerate() {
        let resp: Vec<String> = lists[c]
            .iter()
            .map(|r| format!("r{r}"))
            .chain(constant_of[c].iter().map(|k| format!("k{k}")))
            .collect();
        let fields: Vec<&str> = m.fields.iter().map(|f| f.yaml.as_str()).collect();
        let x = extra_of(&mut g, &m.code);
        let _ = writeln!(
            y,
            "  - {{name: {}, title: \"{}\", section: \"3\", code: \"{}\"{}{x}{}, fields: [{}], responses: [{}]}}",
            m.name,
            m.name,
            code_text(&m.code),
            m.extra,
            reply[c],
            fields.join(", "),
            resp.join(", ")
        );
    }
    // Beside a short form, a command without payload that travels in it, its code one no
    // other command has (the request payload's least made 0 above).
    let mut short_cmd = 0;
    if let (Some(_), Some(&len)) = (short_form, req_lens.first().filter(|l| **l > 0)) {
        let mut rng = own_rng(seed, Own::ShortForm);
        let code = loop {
            let code: Vec<u8> = (0..len).map(|_| rng.u8(..)).collect();
            if commands.iter().all(|m| m.code != code) {
                break code;
            }
        };
        let x = extra_of(&mut g, &code);
        let _ = writeln!(
            y,
            "  - {{name: short_cmd, title: \"short_cmd\", section: \"3\", code: \"{}\", kind: setter{x}, reply: none, fields: [], responses: []}}",
            code_text(&code)
        );
        short_cmd = 1;
    }
    y.push_str("responses:\n");
    for m in &responses {
        let fields: Vec<&str> = m.fields.iter().map(|f| f.yaml.as_str()).collect();
        let x = extra_of(&mut g, &m.code);
        let _ = writeln!(
            y,
            "  - {{name: {}, title: \"{}\", section: \"4\", code: \"{}\"{}{x}, fields: [{}]}}",
            m.name,
            m.name,
            code_text(&m.code),
            m.extra,
            fields.join(", ")
        );
    }
    for (k, bytes) in constants.iter().enumerate() {
        let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
        let _ = writeln!(
            y,
            "  - {{name: k{k}, title: \"k{k}\", section: \"4\", kind: ack, frame: \"{}\"}}",
            hex.join(" ")
        );
    }
    if !common.is_empty() {
        let c: Vec<String> = common.iter().map(|r| format!("r{r}")).collect();
        let _ = writeln!(y, "common_responses: [{}]", c.join(", "));
    }
    let _ = needs_request;
    (y, n_cmd + short_cmd + responses.len() + constants.len())
}

/// The escaping a random spec takes, if any.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Escaping {
    None,
    Bytes,
    /// Byte escaping whose escape byte travels doubled (DLE stuffing).
    Doubled,
    Insert,
    Cobs,
}

/// The constructs `p` uses, by name: the coverage tally counts specs per construct.
pub fn constructs(p: &ir::Protocol) -> Vec<&'static str> {
    use ir::{Count, FieldType, Follows, Part};
    let mut c = Vec::new();
    let mut add = |cond: bool, name: &'static str| {
        if cond {
            c.push(name)
        }
    };
    let f = &p.framing;
    let msgs: Vec<&ir::Message> = p.commands.iter().chain(&p.responses).collect();
    let fields: Vec<&ir::Field> = msgs.iter().flat_map(|m| &m.fields).collect();
    let esc = f.escaping.as_ref().map(|e| &e.kind);
    add(
        matches!(esc, Some(ir::EscapeKind::Bytes { xor: Some(_), .. })),
        "byte escaping (xor)",
    );
    add(
        matches!(esc, Some(ir::EscapeKind::Bytes { xor: None, .. })),
        "byte escaping (map)",
    );
    add(
        matches!(esc, Some(ir::EscapeKind::Insert { .. })),
        "stuffing (insert)",
    );
    add(matches!(esc, Some(ir::EscapeKind::Cobs)), "cobs");
    add(
        esc.is_some_and(|e| e.doubled().is_some()),
        "DLE stuffing (escape byte doubled)",
    );
    add(f.shared_flag().is_some(), "shared flag");
    add(f.preamble.is_some(), "preamble");
    add(f.transform.is_some(), "transform");
    add(f.long.is_some(), "long length form");
    add(f.form.is_some(), "short form");
    add(f.truncation.is_some(), "payload truncation");
    add(
        matches!(esc, Some(ir::EscapeKind::Bytes { .. })) && f.end.is_empty(),
        "byte escaping framed by length",
    );
    add(f.sync.len() == 1, "start byte");
    add(f.sync.len() > 1, "sync sequence");
    add(f.sync_by_direction(), "start bytes by direction");
    add(f.layout_by_direction(), "layout by direction");
    add(
        f.checksum.covers_by_direction(),
        "checksum covering from another offset by direction",
    );
    add(f.header_by_direction(), "header fields by direction");
    add(
        f.layout_by_direction()
            && f.has_header(Direction::Request) != f.has_header(Direction::Response),
        "header in one direction only",
    );
    add(
        f.has_address_in(Direction::Request) != f.has_address_in(Direction::Response),
        "address in one direction only",
    );
    add(
        f.head(Direction::Request, 1).code != f.head(Direction::Response, 1).code,
        "code at another offset by direction",
    );
    let twice = |x: Part| f.layout.iter().filter(|y| **y == x).count() == 2;
    add(twice(Part::Start), "start twice");
    add(twice(Part::Length), "length twice");
    add(f.length.is_some(), "length field");
    add(
        f.length.as_ref().is_some_and(|l| l.adjust != 0),
        "length adjust",
    );
    add(
        f.length.is_some()
            && (f.request.code_lengths.len() > 1 || f.response.code_lengths.len() > 1),
        "length + several code lengths",
    );
    let pos = |x: Part| f.layout.iter().position(|y| *y == x);
    add(pos(Part::Code) < pos(Part::Address), "code before address");
    add(!f.has_address(), "no address");
    add(!f.header.is_empty(), "header fields");
    add(
        f.header
            .iter()
            .chain(&f.response_header)
            .any(|h| h.constant.is_some()),
        "header constants",
    );
    add(
        p.commands.iter().chain(&p.responses).any(|m| {
            let framing = f.header_of(m.direction);
            m.fields.iter().any(|h| {
                h.header
                    && h.constant.is_some()
                    && !framing
                        .iter()
                        .any(|g| g.name == h.name && g.constant.is_some())
            })
        }),
        "header values",
    );
    add(
        p.responses.iter().any(|m| m.frame.is_some()),
        "constant frame",
    );
    add(
        f.header.iter().any(|h| !h.bits.is_empty()),
        "header sub-fields",
    );
    add(
        f.length
            .as_ref()
            .is_some_and(|l| l.counts.contains(&Part::Header)),
        "header counted by the length",
    );
    add(
        !f.header.is_empty() && pos(Part::Code) < pos(Part::Header),
        "header after the code",
    );
    add(
        f.header
            .iter()
            .chain(&f.response_header)
            .any(|h| h.part > 0),
        "header in two parts",
    );
    add(!f.end.is_empty(), "end bytes");
    add(f.end_first(), "end bytes before the checksum");
    add(
        p.commands
            .iter()
            .chain(&p.responses)
            .any(|m| m.terminated_text(f).is_some()),
        "text only its terminator ends",
    );
    add(
        p.commands
            .iter()
            .chain(&p.responses)
            .any(|m| m.delimited_list(f).is_some()),
        "a list end bytes alone delimit",
    );
    add(
        p.commands.iter().any(|m| m.reply == ir::Reply::None),
        "reply none",
    );
    add(
        p.commands.iter().any(|m| m.reply == ir::Reply::Optional),
        "reply optional",
    );
    add(f.address.host.is_some(), "host address");
    add(f.address.broadcast.is_some(), "broadcast address");
    add(
        f.address.min == 0 && f.address.max == 255,
        "every address a device",
    );
    for d in [Direction::Request, Direction::Response] {
        let lens: Vec<usize> = p.messages(d).iter().map(|m| m.code.len()).collect();
        add(lens.contains(&0), "code length 0");
        add(lens.contains(&1), "code length 1");
        add(lens.contains(&2), "code length 2");
        add(
            lens.contains(&0) && lens.iter().any(|l| *l > 0),
            "code-less beside coded",
        );
    }
    add(
        p.commands.iter().enumerate().any(|(i, a)| {
            p.commands[..i]
                .iter()
                .any(|b| !a.code.is_empty() && b.code == a.code)
        }),
        "shared command code",
    );
    add(
        fields.iter().any(|x| x.present.is_some()),
        "optional fields",
    );
    add(fields.iter().any(|x| x.is_counted_text()), "counted text");
    add(
        fields.iter().any(|x| x.terminator().is_some()),
        "text up to a terminator",
    );
    add(
        f.request.payload_max > 255 || f.response.payload_max > 255,
        "payload over 255 bytes",
    );
    add(
        (f.request.payload_max > 255 || f.response.payload_max > 255) && f.length.is_none(),
        "payload over 255 bytes without a length field",
    );
    add(
        fields
            .iter()
            .any(|x| x.packed.as_ref().is_some_and(|pk| pk.whole())),
        "whole packed elements or a fixed count",
    );
    add(
        fields.iter().any(|x| {
            x.fixed_count().is_some()
                && (x.signed
                    || x.is_wide()
                    || x.enumeration.is_some()
                    || x.flags.is_some()
                    || x.word_swapped
                    || !matches!(x.packed.map_or(0, |pk| pk.elem_width), 1 | 2 | 4))
        }),
        "a fixed count of signed, 24- or 64-bit, float, enum or flags elements",
    );
    add(fields.iter().any(|x| x.constant.is_some()), "constant");
    add(fields.iter().any(|x| !x.bits.is_empty()), "bits");
    add(
        fields
            .iter()
            .any(|x| x.bits.iter().any(|b| b.constant.is_some())),
        "constant sub-field",
    );
    add(
        fields.iter().any(|x| x.bits.iter().any(|b| b.signed)),
        "signed sub-field",
    );
    // A 1-bit unsigned sub-field without a scaled unit or a narrower range: a `bool` in
    // generated code.
    add(
        fields.iter().any(|x| {
            x.bits.iter().any(|b| {
                let identity = b.unit.map_or(true, |u| {
                    let u = &p.units[u];
                    u.scale == busspec_model::rational::Rational::ONE
                        && u.offset == busspec_model::rational::Rational::ZERO
                });
                b.width() == 1
                    && !b.signed
                    && b.constant.is_none()
                    && identity
                    && b.range.map_or(true, |r| r == (0, 1))
            })
        }),
        "1-bit bool sub-field",
    );
    add(fields.iter().any(|x| x.enumeration.is_some()), "enum");
    add(fields.iter().any(|x| x.flags.is_some()), "flags");
    add(fields.iter().any(|x| x.range.is_some()), "range");
    add(fields.iter().any(|x| !x.special.is_empty()), "special");
    add(
        fields.iter().any(|x| {
            x.unit.is_some_and(|u| {
                let u = &p.units[u];
                u.scale != busspec_model::rational::Rational::int(1)
            })
        }),
        "scaled unit",
    );
    add(fields.iter().any(|x| x.width == 3), "24-bit");
    add(fields.iter().any(|x| x.ty == FieldType::F32), "f32");
    add(fields.iter().any(|x| x.bcd), "bcd");
    add(fields.iter().any(|x| x.ty == FieldType::F64), "f64");
    add(fields.iter().any(|x| x.ty == FieldType::U64), "u64");
    add(fields.iter().any(|x| x.ty == FieldType::I64), "i64");
    add(
        fields.iter().any(|x| x.is_float() && x.range.is_some()),
        "float range",
    );
    add(
        fields.iter().any(|x| x.word_swapped && x.is_float()),
        "word-swapped float",
    );
    add(
        fields.iter().any(|x| x.word_swapped && !x.is_float()),
        "word-swapped integer",
    );
    add(fields.iter().any(|x| x.width == 4), "32-bit");
    add(fields.iter().any(|x| x.signed), "signed");
    add(fields.iter().any(|x| x.ty == FieldType::Ascii), "ascii");
    add(fields.iter().any(|x| x.equals.is_some()), "equals");
    add(
        fields
            .iter()
            .any(|x| matches!(x.follows, Some(Follows::Field(..)))),
        "follows field",
    );
    add(
        fields
            .iter()
            .any(|x| matches!(x.follows, Some(Follows::Request(..)))),
        "follows request",
    );
    let repeats: Vec<(&ir::Field, &ir::Repeat)> = msgs.iter().filter_map(|m| m.repeat()).collect();
    add(
        repeats
            .iter()
            .any(|(_, r)| matches!(r.count, Count::Elements(_))),
        "repeat counted",
    );
    add(
        repeats
            .iter()
            .any(|(_, r)| matches!(r.count, Count::Bytes(_))),
        "repeat length-given",
    );
    add(
        repeats.iter().any(|(_, r)| r.count == Count::ToEnd),
        "repeat to end",
    );
    add(
        msgs.iter().any(|m| {
            m.repeats()
                .any(|(_, _, r)| matches!(r.count, Count::Fixed(_)))
        }),
        "records of a fixed count",
    );
    add(
        msgs.iter().any(|m| {
            m.repeats()
                .any(|(_, f, _)| f.is_wide() && f.packed.is_none())
        }),
        "list of floats or 64-bit integers",
    );
    add(
        repeats.iter().any(|(f, _)| f.ty == FieldType::Bit),
        "repeat of bits",
    );
    add(fields.iter().any(|f| f.packed.is_some()), "packed elements");
    add(
        msgs.iter().any(|m| m.fields.iter().any(|f| f.is_record())),
        "records",
    );
    add(
        msgs.iter()
            .any(|m| m.fields.iter().any(|f| f.record_bytes_from().is_some())),
        "records sized by a field",
    );
    add(
        msgs.iter().any(|m| {
            m.fields.iter().any(|f| {
                f.repeat.is_some()
                    && f.ty != FieldType::Bit
                    && !f.is_record()
                    && (f.enumeration.is_some()
                        || f.unit.is_some_and(|u| {
                            let u = &p.units[u];
                            u.scale != busspec_model::rational::Rational::ONE
                                || u.offset != busspec_model::rational::Rational::ZERO
                        }))
            })
        }),
        "list of a unit or enum type",
    );
    add(
        repeats.iter().any(|(_, r)| r.request.is_some()),
        "repeat from request",
    );
    add(
        msgs.iter()
            .any(|m| m.repeat().is_some() && m.fields.last().is_some_and(|f| f.repeat.is_none())),
        "fields after a list",
    );
    add(
        msgs.iter().any(|m| m.repeats().count() > 1),
        "several lists",
    );
    add(
        p.responses.iter().any(|m| m.code_from_request.is_some()),
        "code_from_request",
    );
    add(p.responses.iter().any(|m| m.needs_request), "needs_request");
    add(
        p.responses
            .iter()
            .any(|m| m.unasked && !m.answers.is_empty()),
        "a reply also sent unasked",
    );
    add(
        p.responses
            .iter()
            .any(|m| m.unasked && m.answers.is_empty()),
        "a response sent unasked only",
    );
    add(!p.common_responses.is_empty(), "common responses");
    add(
        p.commands.iter().any(|m| m.broadcast.is_some()),
        "broadcast rule",
    );
    let alg = match &f.checksum.algorithm {
        ChecksumAlgorithm::Sum8 => "sum8",
        ChecksumAlgorithm::Sum8OnesComplement => "sum8_ones_complement",
        ChecksumAlgorithm::Sum8TwosComplement => "sum8_twos_complement",
        ChecksumAlgorithm::Sum8EndAround => "sum8_end_around",
        ChecksumAlgorithm::Xor8 => "xor8",
        ChecksumAlgorithm::Sum16 => "sum16",
        ChecksumAlgorithm::Sum16OnesComplement => "sum16_ones_complement",
        ChecksumAlgorithm::Sum16TwosComplement => "sum16_twos_complement",
        ChecksumAlgorithm::Fletcher8 => "fletcher8",
        ChecksumAlgorithm::Fletcher16 => "fletcher16",
        ChecksumAlgorithm::Masked(a, _) if **a == ChecksumAlgorithm::Sum8EndAround => {
            "masked sum8_end_around"
        }
        ChecksumAlgorithm::Masked(..) => "masked sum",
        ChecksumAlgorithm::Complemented(a, _) => match **a {
            ChecksumAlgorithm::Masked(..) => "masked sum then its complement",
            _ => "sum then its complement",
        },
        ChecksumAlgorithm::None => "no checksum",
        ChecksumAlgorithm::Crc(c) => match c.width {
            8 => "crc8",
            16 => "crc16",
            24 => "crc24",
            _ => "crc32",
        },
    };
    add(true, alg);
    add(f.checksum.covers_from > 0, "covers_from");
    add(f.checksum.lead.is_some(), "checksum before the payload");
    add(f.covers_around(), "checksum covering both sides of it");
    add(
        matches!(f.checksum.algorithm, ChecksumAlgorithm::Complemented(..)),
        "checksum followed by its complement",
    );
    add(
        f.checksum.extra.is_some(),
        "checksum extra byte per message",
    );
    add(
        p.has_over_request(),
        "a reply's checksum over its request's bytes",
    );
    add(p.has_unchecked(), "a message without a checksum");
    add(
        p.has_over_request()
            && p.framed(Direction::Response).iter().any(|m| {
                m.over_request.is_some()
                    && p.framed(Direction::Request).iter().any(|c| {
                        c.min_len() <= m.max_len
                            && m.min_len() <= c.max_len
                            && (m.code.is_empty()
                                || c.code.is_empty()
                                || m.code.len() != c.code.len())
                    })
            }),
        "a reply's checksum over its request's bytes beside requests of its length",
    );
    add(
        f.checksum.len() > 1 && f.checksum.byte_order == ir::ByteOrder::Little,
        "checksum little-endian",
    );
    add(p.byte_order == ir::ByteOrder::Little, "byte_order little");
    add(
        p.byte_order != p.printed_byte_order,
        "printed order differs",
    );
    add(
        p.examples.iter().any(|e| e.reply_to.is_some()),
        "example reply_to",
    );
    c
}

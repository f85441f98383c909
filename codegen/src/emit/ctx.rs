use super::*;

/// A Rust integer type and the raw values it holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IntType {
    pub bits: u32,
    pub signed: bool,
    /// An IEEE-754 float of `bits` bits (`f32`, `f64`), its raw value its bits.
    pub float: bool,
}

impl IntType {
    pub(super) fn ident(self) -> Ident {
        if self.float {
            return format_ident!("f{}", self.bits);
        }
        let name = match (self.signed, self.rust_bits()) {
            (false, 8) => "u8",
            (true, 8) => "i8",
            (false, 16) => "u16",
            (true, 16) => "i16",
            (false, 32) => "u32",
            (true, 32) => "i32",
            (false, 64) => "u64",
            (true, 64) => "i64",
            (signed, bits) => return format_ident!("{}{bits}", if signed { "i" } else { "u" }),
        };
        ident(name)
    }

    /// Bits of the Rust integer holding it: a 24-bit wire integer is held in 32 bits.
    pub(super) fn rust_bits(self) -> u32 {
        if self.bits == 24 {
            32
        } else {
            self.bits
        }
    }

    pub(super) fn limits(self) -> (i64, i64) {
        raw_limits(self.bits, self.signed)
    }

    /// The smallest Rust integer type holding `lo..=hi`.
    pub(super) fn covering(lo: i64, hi: i64) -> IntType {
        for bits in [8, 16, 32, 64] {
            for signed in [false, true] {
                let (a, b) = raw_limits(bits, signed);
                if a <= lo && hi <= b {
                    return IntType {
                        bits,
                        signed,
                        float: false,
                    };
                }
            }
        }
        IntType {
            bits: 64,
            signed: true,
            float: false,
        }
    }
}

/// Where a typed value comes from: a whole field or a packed sub-field.
pub(super) struct Leaf<'a> {
    pub(super) name: &'a str,
    pub(super) doc: String,
    /// Raw wire limits.
    pub(super) wire: IntType,
    pub(super) bits: Option<&'a BitField>,
    pub(super) field: &'a Field,
    /// The message it belongs to (a repeated record's struct is named by it).
    pub(super) message: &'a str,
}

/// The generated Rust type of a value, and how to turn raw integers into it and back.
pub(super) enum Kind {
    Int(IntType),
    /// A 1-bit unsigned sub-field of no scaled unit and no narrower range: `bool`.
    Bool,
    Unit {
        ty: Ident,
        raw: IntType,
    },
    Enum {
        ty: Ident,
        raw: IntType,
    },
    Flags {
        ty: Ident,
        raw: IntType,
    },
    Text(usize),
    /// A repeated field: at most `max` elements, each its field's wire integer, or the type
    /// of its enum or (scaled) unit where it has one (`typed`).
    List {
        elem: IntType,
        max: usize,
        typed: Option<Ident>,
        /// Counted text (`type: ascii` with `repeat`): bytes as any `u8` list, its value text.
        text: bool,
    },
    /// A repeated bit field, packed into `bytes` bytes.
    BitList {
        bytes: usize,
    },
    /// A repeated record: at most `max` records, each the generated struct `ty`.
    Records {
        ty: Ident,
        max: usize,
    },
}

/// A field check [`Ctx::field_check`] registered: its message's direction and name, the
/// field's name, the constant's name and its field descriptor's, the offset, and the range
/// and relation as builder calls (text, so two checks compare).
pub(super) struct FieldCheck {
    pub(super) direction: Direction,
    pub(super) message: String,
    pub(super) field: String,
    pub(super) name: Ident,
    pub(super) desc: Ident,
    pub(super) at: usize,
    pub(super) range: Option<String>,
    pub(super) follows: Option<String>,
}

pub(super) struct Ctx<'a> {
    pub(super) p: &'a Protocol,
    pub(super) unit_raw: Vec<Option<IntType>>,
    pub(super) enum_raw: Vec<IntType>,
    pub(super) flag_raw: Vec<IntType>,
    /// The field descriptors the emitted refusals point at, in the order first named: the
    /// message's direction and name, the field's name, the constant's name.
    pub(super) field_descs: std::cell::RefCell<Vec<(Direction, String, String, Ident)>>,
    /// The field checks the emitted range and relation checks take (`Ctx::field_check`), in
    /// the order first named.
    pub(super) field_checks: std::cell::RefCell<Vec<FieldCheck>>,
    /// Each direction's message structs, emitted in its `request`/`response` module.
    pub(super) structs: std::cell::RefCell<Vec<(Direction, TokenStream)>>,
    /// Each message's `impl` (`messages::message_impl`): its direction and name, the struct's
    /// path, its constants and its methods; emitted by `emit_descs` with the field
    /// descriptors the refusals named.
    #[allow(clippy::type_complexity)]
    pub(super) impls:
        std::cell::RefCell<Vec<(Direction, String, TokenStream, TokenStream, TokenStream)>>,
    /// Set while the borrowed views are emitted (`view.rs`): decode then lends each list as
    /// `rt::ListView`/`rt::BitsView` instead of copying it, and its functions take the
    /// frame as `&'a [u8]`.
    pub(super) view: std::cell::Cell<bool>,
    /// Whether a decoder of each direction (request, response) quotes an unknown code, so
    /// the module defines its `REQUEST_CODE`/`RESPONSE_CODE` (`dispatch::code_consts`).
    pub(super) codes_used: std::cell::Cell<[bool; 2]>,
    /// Set while a message's fields are decoded inside its own `impl` (`from_frame`,
    /// [`super::dispatch::from_frame`]): its descriptors are named through `Self`.
    pub(super) own: std::cell::Cell<bool>,
    /// Each message's `from_frame` (its direction and name, the function), emitted in its
    /// `impl` by `emit_descs`.
    pub(super) readers: std::cell::RefCell<Vec<(Direction, String, TokenStream)>>,
    /// Each message's `write` (its direction and name, the function: the encoder's arm of a
    /// message with fields, `encode::emit_encode_arm`), emitted in its `impl` likewise.
    pub(super) writers: std::cell::RefCell<Vec<(Direction, String, TokenStream)>>,
    /// Each response's checks against a request it answers (`follows_<command>`, its
    /// direction and name, the function: `protocol::emit_follows_request`), emitted in its
    /// `impl` likewise; the owned and the view's `follows_request` both call it.
    pub(super) followers: std::cell::RefCell<Vec<(Direction, String, TokenStream)>>,
}

impl<'a> Ctx<'a> {
    pub(super) fn new(p: &'a Protocol) -> Self {
        let mut unit_span: Vec<Option<(i64, i64)>> = vec![None; p.units.len()];
        let mut enum_raw = vec![
            IntType {
                bits: 8,
                signed: false,
                float: false
            };
            p.enums.len()
        ];
        let mut flag_raw = vec![
            IntType {
                bits: 8,
                signed: false,
                float: false
            };
            p.flags.len()
        ];
        let widen = |slot: &mut Option<(i64, i64)>, (lo, hi): (i64, i64)| {
            *slot = Some(match *slot {
                None => (lo, hi),
                Some((a, b)) => (a.min(lo), b.max(hi)),
            });
        };
        for m in p.commands.iter().chain(&p.responses) {
            // A record's fields are typed as fields are.
            for f in m
                .fields
                .iter()
                .flat_map(|f| std::iter::once(f).chain(&f.record))
            {
                if f.is_record() {
                    continue;
                }
                let w = wire_type(f);
                if let Some(u) = f.unit {
                    widen(&mut unit_span[u], w.limits());
                }
                if let Some(e) = f.enumeration {
                    if w.bits > enum_raw[e].bits {
                        enum_raw[e] = IntType {
                            bits: w.bits,
                            signed: false,
                            float: false,
                        };
                    }
                }
                if let Some(fl) = f.flags {
                    if w.bits > flag_raw[fl].bits {
                        flag_raw[fl] = IntType {
                            bits: w.bits,
                            signed: false,
                            float: false,
                        };
                    }
                }
                for b in &f.bits {
                    if let Some(u) = b.unit {
                        widen(
                            &mut unit_span[u],
                            raw_limits(u32::from(b.width()), b.signed),
                        );
                    }
                }
            }
        }
        let unit_raw = unit_span
            .into_iter()
            .map(|s| s.map(|(lo, hi)| IntType::covering(lo, hi)))
            .collect();
        Ctx {
            p,
            unit_raw,
            enum_raw,
            flag_raw,
            field_descs: std::cell::RefCell::new(Vec::new()),
            field_checks: std::cell::RefCell::new(Vec::new()),
            structs: std::cell::RefCell::new(Vec::new()),
            impls: std::cell::RefCell::new(Vec::new()),
            view: std::cell::Cell::new(false),
            codes_used: std::cell::Cell::new([false; 2]),
            own: std::cell::Cell::new(false),
            readers: std::cell::RefCell::new(Vec::new()),
            writers: std::cell::RefCell::new(Vec::new()),
            followers: std::cell::RefCell::new(Vec::new()),
        }
    }

    /// `&request::ReadCoils::QUANTITY_DESC`: the descriptor of field (or sub-field) `name` of
    /// `m`, a constant of `m`'s struct beside its `DESC` (`emit_descs`). Its constant is the
    /// field's name upper-cased with `_DESC` after it (a record's field `list.field`:
    /// `LIST_FIELD_DESC`), `__DESC` where another of the struct's constants takes that name.
    pub(super) fn field_desc(&self, m: &Message, name: &str) -> TokenStream {
        let c = self.field_desc_const(m, name);
        let path = self.path(m, &c);
        quote!(&#path)
    }

    /// `Self::C` inside `m`'s own `impl`, `request::ReadCoils::C` elsewhere.
    fn path(&self, m: &Message, c: &Ident) -> TokenStream {
        if self.own.get() {
            return quote!(Self::#c);
        }
        let dir = direction_module(m.direction);
        let v = variant(m);
        quote!(#dir::#v::#c)
    }

    /// The name of [`Ctx::field_desc`]'s constant, registered the first time.
    fn field_desc_const(&self, m: &Message, name: &str) -> Ident {
        let mut descs = self.field_descs.borrow_mut();
        let found = descs
            .iter()
            .find(|(d, mn, f, _)| *d == m.direction && *mn == m.name && f == name);
        if let Some((.., c)) = found {
            return c.clone();
        }
        let upper = name.to_uppercase().replace('.', "_");
        let mut c = format!("{upper}_DESC");
        let consts = struct_consts(m);
        let taken = |c: &str| {
            consts.iter().any(|k| k == c)
                || descs
                    .iter()
                    .any(|(d, mn, _, k)| *d == m.direction && *mn == m.name && *k == c)
        };
        if taken(&c) {
            c = format!("{upper}__DESC");
        }
        let c = ident(&c);
        descs.push((m.direction, m.name.clone(), name.to_owned(), c.clone()));
        c
    }

    /// `&request::ReadCoils::QUANTITY_CHECK`: the [`FieldCheck`] of field (or sub-field)
    /// `name` of `m` at offset `at` (a sub-field's field's; where lists or optional fields move
    /// it, the offset in a frame with its lists empty and its optional fields present), with
    /// the range (`leaf_range`'s builder calls) and relation (`.follows(..)`) a check names.
    /// One constant a field gathers what its decoder and encoder check; its name is the
    /// field's upper-cased with `_CHECK` after it (`__CHECK`, then a number, where another of
    /// the struct's constants or another check of the field takes it). Where `at_run` (the
    /// offset as the decoder computes it) is not `at`, the check is moved there:
    /// `&Self::FLAGS_CHECK.at(4 + s.shift(1))`.
    pub(super) fn field_check(
        &self,
        m: &Message,
        name: &str,
        (at, at_run): (usize, &TokenStream),
        range: Option<TokenStream>,
        follows: Option<TokenStream>,
    ) -> TokenStream {
        let path = self.field_check_const(m, name, at, range, follows);
        if at_run.to_string() == usize_lit(at).to_string() {
            quote!(&#path)
        } else {
            quote!(&#path.at(#at_run))
        }
    }

    fn field_check_const(
        &self,
        m: &Message,
        name: &str,
        at: usize,
        range: Option<TokenStream>,
        follows: Option<TokenStream>,
    ) -> TokenStream {
        let desc = self.field_desc_const(m, name);
        let (range, follows) = (range.map(|r| r.to_string()), follows.map(|f| f.to_string()));
        let mut checks = self.field_checks.borrow_mut();
        let agrees = |mine: &Option<String>, theirs: &Option<String>| {
            mine.is_none() || theirs.is_none() || mine == theirs
        };
        let found = checks.iter_mut().find(|c| {
            c.direction == m.direction
                && c.message == m.name
                && c.field == name
                && c.at == at
                && agrees(&c.range, &range)
                && agrees(&c.follows, &follows)
        });
        if let Some(c) = found {
            c.range = c.range.take().or(range);
            c.follows = c.follows.take().or(follows);
            let c = c.name.clone();
            drop(checks);
            return self.path(m, &c);
        }
        let upper = name.to_uppercase().replace('.', "_");
        let consts = struct_consts(m);
        let taken = |c: &str| {
            consts.iter().any(|k| k == c)
                || checks
                    .iter()
                    .any(|k| k.direction == m.direction && k.message == m.name && k.name == c)
        };
        let mut c = format!("{upper}_CHECK");
        let mut n = 1;
        while taken(&c) {
            c = format!(
                "{upper}__CHECK{}",
                if n == 1 { String::new() } else { n.to_string() }
            );
            n += 1;
        }
        let c = ident(&c);
        checks.push(FieldCheck {
            direction: m.direction,
            message: m.name.clone(),
            field: name.to_owned(),
            name: c.clone(),
            desc,
            at,
            range,
            follows,
        });
        drop(checks);
        self.path(m, &c)
    }

    pub(super) fn kind(&self, leaf: &Leaf) -> Kind {
        let (unit, field) = match leaf.bits {
            Some(b) => (b.unit, None),
            None => (leaf.field.unit, Some(leaf.field)),
        };
        if let Some(f) = field {
            if let Some(pk) = &f.packed {
                return Kind::List {
                    elem: leaf.wire,
                    max: pk.count,
                    typed: self.element_type(f),
                    text: false,
                };
            }
            if let (Some(r), true) = (&f.repeat, f.is_record()) {
                return Kind::Records {
                    ty: record_type(leaf.message, f),
                    max: r.max,
                };
            }
            if let Some(r) = &f.repeat {
                return if f.ty == FieldType::Bit {
                    Kind::BitList {
                        bytes: r.max.div_ceil(8),
                    }
                } else {
                    Kind::List {
                        elem: leaf.wire,
                        max: r.max,
                        typed: self.element_type(f),
                        text: f.is_ascii(),
                    }
                };
            }
            if f.is_ascii() {
                return Kind::Text(f.width);
            }
            if let Some(e) = f.enumeration {
                return Kind::Enum {
                    ty: type_ident(&self.p.enums[e].name),
                    raw: self.enum_raw[e],
                };
            }
            if let Some(fl) = f.flags {
                return Kind::Flags {
                    ty: type_ident(&self.p.flags[fl].name),
                    raw: self.flag_raw[fl],
                };
            }
        }
        if let Some(b) = leaf.bits {
            let plain = unit.map_or(true, |u| is_identity(&self.p.units[u]));
            let whole = b.range.map_or(true, |r| r == (0, 1));
            if b.width() == 1 && !b.signed && plain && whole {
                return Kind::Bool;
            }
        }
        match unit {
            Some(u) if !is_identity(&self.p.units[u]) => Kind::Unit {
                ty: type_ident(&self.p.units[u].name),
                raw: self.unit_raw[u].unwrap_or(leaf.wire),
            },
            _ => Kind::Int(leaf.wire),
        }
    }

    /// The type of a repeated field's elements where it is one of the spec's: its enum's, or
    /// its unit's newtype (a unit of scale 1 and offset 0 leaves them integers).
    pub(super) fn element_type(&self, f: &Field) -> Option<Ident> {
        // Packed elements of fewer bits than their type's (CRSF's channels) stay integers.
        let whole = f.fixed_count().is_some();
        if (f.repeat.is_none() && !whole) || f.ty == FieldType::Bit || f.is_record() {
            return None;
        }
        if let Some(e) = f.enumeration {
            return Some(type_ident(&self.p.enums[e].name));
        }
        match f.unit {
            Some(u) if !is_identity(&self.p.units[u]) => Some(type_ident(&self.p.units[u].name)),
            _ => None,
        }
    }

    pub(super) fn rust_type(&self, leaf: &Leaf) -> TokenStream {
        match self.kind(leaf) {
            Kind::Int(t) => {
                let i = t.ident();
                quote!(#i)
            }
            Kind::Bool => quote!(bool),
            Kind::Unit { ty, .. } | Kind::Enum { ty, .. } | Kind::Flags { ty, .. } => quote!(#ty),
            Kind::Text(n) => {
                let n = Literal::usize_unsuffixed(n);
                quote!(rt::Ascii<#n>)
            }
            Kind::List {
                elem, max, typed, ..
            } => {
                let e = typed.unwrap_or_else(|| elem.ident());
                let max = usize_lit(max);
                quote!(rt::Repeated<#e, #max>)
            }
            Kind::BitList { bytes } => {
                let bytes = usize_lit(bytes);
                quote!(rt::Bits<#bytes>)
            }
            Kind::Records { ty, max } => {
                let max = usize_lit(max);
                quote!(rt::Repeated<#ty, #max>)
            }
        }
    }
}

/// The struct generated for repeated record `f` of message `m` (its name is the message's
/// and the field's: `SyncWriteBlocks`).
pub(super) fn record_type(m: &str, f: &Field) -> Ident {
    type_ident(&format!("{m}_{}", f.name))
}

/// Whether packed field `f` is a list of a fixed count whose elements the generated code reads
/// and writes whole (`rt::fixed_elements`, `rt::write_fixed`): signed, 3 or 8 bytes wide,
/// floats, or their words swapped. Unsigned elements of 1, 2 or 4 bytes in their byte order go
/// through `rt::unpack`/`rt::pack` as other packed elements do.
pub(super) fn fixed_elements(f: &Field) -> bool {
    f.fixed_count().is_some_and(|pk| {
        f.signed || f.is_float() || f.word_swapped || !matches!(pk.elem_width, 1 | 2 | 4)
    })
}

pub(super) fn wire_type(f: &Field) -> IntType {
    // Packed elements: the element type's.
    let width = f.packed.map_or(f.width, |pk| pk.elem_width);
    IntType {
        bits: 8 * width as u32,
        signed: f.signed,
        float: f.is_float(),
    }
}

pub(super) fn bits_type(b: &BitField) -> IntType {
    let (lo, hi) = raw_limits(u32::from(b.width()), b.signed);
    let mut t = IntType::covering(lo, hi);
    t.signed = b.signed;
    t
}

pub(super) fn leaves(m: &Message) -> Vec<Leaf<'_>> {
    let mut out = Vec::new();
    for (i, f) in m.fields.iter().enumerate() {
        if m.is_derived(i) {
            continue;
        }
        if f.bits.is_empty() {
            out.push(Leaf {
                name: &f.name,
                doc: f.doc.clone(),
                wire: wire_type(f),
                bits: None,
                field: f,
                message: &m.name,
            });
        }
        for b in &f.bits {
            if b.constant.is_none() {
                out.push(Leaf {
                    name: &b.name,
                    doc: b.doc.clone(),
                    wire: bits_type(b),
                    bits: Some(b),
                    field: f,
                    message: &m.name,
                });
            }
        }
    }
    out
}

/// The wire integer of field `f`, read from `frame`: one byte as is (or reinterpreted as
/// `i8`), wider fields through `from_le_bytes`/`from_be_bytes`.
pub(super) fn read_wire(f: &Field, payload_at: usize) -> TokenStream {
    let w = wire_type(f);
    let t = w.ident();
    let at = payload_at + f.offset;
    if f.width == 1 {
        let i = usize_lit(at);
        return if w.signed {
            quote!(frame[#i] as i8)
        } else {
            quote!(frame[#i])
        };
    }
    let idx = (0..f.width).map(|i| {
        let i = if f.word_swapped {
            busspec_model::number::swap_index(i, f.width)
        } else {
            i
        };
        let at = usize_lit(at + i);
        quote!(frame[#at])
    });
    if f.width == 3 {
        let read = if w.signed { ident("i24") } else { ident("u24") };
        let le = f.byte_order == ByteOrder::Little;
        return quote!(rt::#read([#(#idx),*], #le));
    }
    let conv = match f.byte_order {
        ByteOrder::Little => format_ident!("from_le_bytes"),
        ByteOrder::Big => format_ident!("from_be_bytes"),
    };
    quote!(#t::#conv([#(#idx),*]))
}

/// The pattern binding every field of `m` to its `v_<name>` local (so that no spec name can
/// shadow the generated code's own variables), or `Self::Name(_)` without fields.
pub(super) fn binding(m: &Message, ls: &[Leaf]) -> TokenStream {
    let v = variant(m);
    if ls.is_empty() {
        return quote!(Self::#v(_));
    }
    let own = own_binding(m, ls);
    quote!(Self::#v(#own))
}

pub(super) fn leaf_doc(p: &Protocol, l: &Leaf) -> String {
    let mut s = l.doc.clone();
    let unit = l.bits.map(|b| b.unit).unwrap_or(l.field.unit);
    if let Some(u) = unit.map(|u| &p.units[u]) {
        if !u.symbol.is_empty() {
            s.push_str(&format!(" [{}]", u.symbol));
        }
    }
    let range = l.bits.map(|b| b.range).unwrap_or(l.field.range);
    if let Some((a, b)) = range {
        let k = match l.bits {
            Some(_) => busspec_model::number::NumKind::Int,
            None => l.field.num_kind(),
        };
        s.push_str(&format!(" Valid raw range {}..={}.", k.text(a), k.text(b)));
    }
    if l.bits.is_none() && l.field.word_swapped {
        s.push_str(" Its 16-bit words travel swapped.");
    }
    if l.bits.is_none() {
        for sp in &l.field.special {
            s.push_str(&format!(
                " Raw {} = {}{}.",
                sp.value,
                sp.name,
                if sp.doc.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", sp.doc)
                }
            ));
        }
    }
    s.trim().to_owned()
}

/// The raw value of a typed value `v` (a local, or a field read `m.quantity`), of the type the
/// value holds.
pub(super) fn raw_of(
    ctx: &Ctx,
    l: &Leaf,
    v: &impl quote::ToTokens,
) -> Option<(IntType, TokenStream)> {
    match ctx.kind(l) {
        Kind::Int(t) => Some((t, quote!(#v))),
        Kind::Bool => Some((IntType::covering(0, 1), quote!(#v as u8))),
        Kind::Unit { raw, .. } | Kind::Enum { raw, .. } | Kind::Flags { raw, .. } => {
            Some((raw, quote!(#v.raw())))
        }
        Kind::Text(_) | Kind::List { .. } | Kind::BitList { .. } | Kind::Records { .. } => None,
    }
}

/// Converts a typed value bound to `v` into the wire integer of its field, with a range check
/// when the typed value can hold more than the field.
///
/// `as_type` is the type wanted (the field's wire type where `None`); a sub-field's value is
/// wanted as the whole field's type, to be shifted into place.
pub(super) fn to_wire(ctx: &Ctx, l: &Leaf, v: &Ident, as_type: Option<IntType>) -> TokenStream {
    let field_name = l.name;
    let wt = l.wire;
    let target = as_type.unwrap_or(wt);
    let w = target.ident();
    if let Kind::Bool = ctx.kind(l) {
        // 0 or 1, which every wire type holds.
        return quote!(#v as #w);
    }
    let Some((raw_t, raw_expr)) = raw_of(ctx, l, v) else {
        return quote!(#v);
    };
    let bits_limits = l.bits.map(|b| raw_limits(u32::from(b.width()), b.signed));
    let (lo, hi) = bits_limits.unwrap_or(wt.limits());
    let (rlo, rhi) = raw_t.limits();
    if lo <= rlo && rhi <= hi && raw_t == wt && wt.bits != 24 {
        if raw_t == target {
            return raw_expr;
        }
        return quote!(#raw_expr as #w);
    }
    let (lo, hi) = (i64_lit(lo), i64_lit(hi));
    quote!(rt::fits(#field_name, #raw_expr, #lo, #hi)? as #w)
}

/// The spec range of a leaf (a whole field or a sub-field) and the special values that may lie
/// outside it (whole fields only), as a field check's builder calls (`.range(1, 2000)`,
/// `.range(1, 254).or(&[0])`, `.range_f32(0f32, 45f32)`, [`Ctx::field_check`]); `None`
/// where there is no range, or where range and special values together admit every value of
/// `limits` (the checked value's type), as SD's temperatures (1..=254, 0 and 255) do: such a
/// check cannot fail, and at `opt-level = "s"` its special values stayed a loop.
pub(super) fn leaf_range(
    f: &Field,
    b: Option<&BitField>,
    limits: (i64, i64),
) -> Option<TokenStream> {
    let (range, special): ((i64, i64), Vec<i64>) = match b {
        Some(b) => (b.range?, Vec::new()),
        None => (f.range?, f.special.iter().map(|s| s.value).collect()),
    };
    let sp: Vec<i64> = special
        .iter()
        .copied()
        .filter(|v| !(range.0..=range.1).contains(v))
        .collect();
    // The admitted values grown from the range by the special values next to it.
    let (mut lo, mut hi) = range;
    while let Some(&v) = sp.iter().find(|&&v| v == lo - 1 || v == hi + 1) {
        (lo, hi) = (lo.min(v), hi.max(v));
    }
    if b.is_none() && f.is_wide() {
        // Raw values are bits: no check is left out, and the bounds are written as numbers.
        let (a, b) = range;
        return Some(match f.ty {
            FieldType::F32 => {
                let (a, b) = (f32::from_bits(a as u32), f32::from_bits(b as u32));
                let (a, b) = (Literal::f32_suffixed(a), Literal::f32_suffixed(b));
                quote!(.range_f32(#a, #b))
            }
            FieldType::F64 => {
                let (a, b) = (f64::from_bits(a as u64), f64::from_bits(b as u64));
                let (a, b) = (Literal::f64_suffixed(a), Literal::f64_suffixed(b));
                quote!(.range_f64(#a, #b))
            }
            FieldType::U64 => {
                let (a, b) = (
                    Literal::u64_suffixed(a as u64),
                    Literal::u64_suffixed(b as u64),
                );
                quote!(.range(rt::u64_raw(#a), rt::u64_raw(#b)))
            }
            _ => {
                let (a, b) = (i64_lit(a), i64_lit(b));
                quote!(.range(#a, #b))
            }
        });
    }
    if lo <= limits.0 && limits.1 <= hi {
        return None;
    }
    let (lo, hi) = (i64_lit(range.0), i64_lit(range.1));
    let sp: Vec<Literal> = sp.iter().map(|v| i64_lit(*v)).collect();
    if sp.is_empty() {
        return Some(quote!(.range(#lo, #hi)));
    }
    Some(quote!(.range(#lo, #hi).or(&[#(#sp),*])))
}

/// The typed value of leaf `l` from `raw`, an expression of type `wire` (`None`: an `i64`).
pub(super) fn from_wire(
    ctx: &Ctx,
    l: &Leaf,
    wire: Option<IntType>,
    raw: TokenStream,
) -> TokenStream {
    match ctx.kind(l) {
        Kind::Int(t) if Some(t) == wire => raw,
        Kind::Int(t) => {
            let (t, raw) = (t.ident(), paren(raw));
            quote!(#raw as #t)
        }
        Kind::Bool => {
            let raw = paren(raw);
            quote!(#raw != 0)
        }
        Kind::Unit { ty, raw: r } | Kind::Enum { ty, raw: r } | Kind::Flags { ty, raw: r }
            if Some(r) == wire =>
        {
            quote!(#ty::from_raw(#raw))
        }
        Kind::Unit { ty, raw: r } | Kind::Enum { ty, raw: r } | Kind::Flags { ty, raw: r } => {
            let (r, raw) = (r.ident(), paren(raw));
            quote!(#ty::from_raw(#raw as #r))
        }
        Kind::Text(_) | Kind::List { .. } | Kind::BitList { .. } | Kind::Records { .. } => raw,
    }
}

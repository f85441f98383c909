use super::*;

/// A direction's enum (`Request` or `Response`) and its impls, each message's struct (pushed
/// to `ctx.structs`, emitted in the direction's module), the lists' and records' descriptors.
pub(super) fn emit_messages(ctx: &Ctx, d: Direction) -> TokenStream {
    let p = ctx.p;
    let (ty, what) = direction_names(d);
    let msgs = p.messages(d);
    let framed = p.framed(d);
    // Where every frame of the direction has one length, `encode` takes the buffer's frame
    // once before its match (one `BufferTooSmall` check instead of one per arm: SD's 21
    // arms took 8 bytes each at opt-level s); the arms write into it.
    let one_len = match framed.first() {
        Some(m)
            if framed
                .iter()
                .all(|x| !x.is_variable() && p.frame_len(x) == p.frame_len(m)) =>
        {
            Some(p.frame_len(m))
        }
        _ => None,
    };
    let mut variants = Vec::new();
    let mut rows = Vec::new();
    let mut index_arms = Vec::new();
    let mut encode_arms = Vec::new();
    let mut visit_arms = Vec::new();
    let mut len_arms = Vec::new();
    let mut constant_arms = Vec::new();
    let mut structs = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        let v = variant(m);
        let ls = leaves(m);
        let dm = direction_module(m.direction);
        variants.push(quote!(#v(#dm::#v)));
        let (doc, fields) = (message_doc(m), struct_fields(ctx, m, &ls));
        structs.push(message_struct(ctx, m, &ls, doc, fields));
        let name = &m.name;
        let code = m.code.iter().map(|b| hex_u8(*b));
        let len = p.frame_len(m);
        let (len, i) = (usize_lit(len), usize_lit(i));
        rows.push(quote!((#name, &[#(#code),*], #len)));
        let any = any_of(&ident("Self"), m);
        index_arms.push(quote!(#any => #i));
        let pattern = binding(m, &ls);
        if let Some(bytes) = &m.frame {
            let bytes = bytes.iter().map(|b| hex_u8(*b));
            let frame = quote!(&[#(#bytes),*]);
            constant_arms.push(quote!(#any => rt::Some(#frame),));
            encode_arms.push(quote!(#any => return rt::put_frame(buf, #frame),));
            message_impl(ctx, m, &ls, quote!());
            continue;
        }
        encode_arms.push(emit_encode_arm(ctx, m, &pattern, &ls, one_len.is_some()));
        len_arms.extend(len_arm(ctx, m, &ls));
        let visits = visits(ctx, &ls);
        let visit = match visits.as_slice() {
            // Nothing to visit: the enum's `visit` passes it by.
            [] => quote!(),
            many => {
                visit_arms.push(quote!(Self::#v(m) => m.visit(f),));
                quote! {
                    pub fn visit(&self, mut f: impl FnMut(&'static str, rt::FieldValue<'_>)) {
                        #(#many;)*
                    }
                }
            }
        };
        message_impl(ctx, m, &ls, visit);
    }
    let (visit_param, visit_body) = if visit_arms.is_empty() {
        (quote!(_f), quote!())
    } else {
        if visit_arms.len() < msgs.len() {
            visit_arms.push(quote!(_ => {}));
        }
        (quote!(f), quote!(match self { #(#visit_arms)* }))
    };
    let n = usize_lit(msgs.len());
    let frame_len = if len_arms.is_empty() {
        quote!(Self::MESSAGES[self.index()].2)
    } else {
        quote! {
            match self {
                #(#len_arms,)*
                _ => Self::MESSAGES[self.index()].2,
            }
        }
    };
    let repeats = emit_repeats(ctx, d);
    let records = emit_records(ctx, d);
    let dispatch = emit_dispatch(ctx, d, &quote!(#ty));
    let from_fields = emit_from_fields(ctx, d);
    let command_info = if d == Direction::Request {
        emit_command_info(p)
    } else {
        quote!()
    };
    let frame_const = frame_of(p, d);
    let take_once = one_len.map(|n| {
        let n = usize_lit(n);
        quote!(let out = rt::frame_mut::<#n>(buf, &[])?;)
    });
    // A transform of the payload (`framing.transform`): done before the checksum is computed.
    let transform = if p.framing.transform.is_some() {
        let range = p.framing.transformed(0);
        let (at, trailer) = (usize_lit(range.start), usize_lit(p.framing.trailer_len()));
        quote!(TRANSFORM.put(buf, len, #at, #trailer);)
    } else {
        quote!()
    };
    let seal = encode_seal(p, d);
    // A float has no `Eq` or `Hash`: a direction with a float field derives `PartialEq`
    // alone (every other direction, and every spec without floats, keeps both).
    let derives = if ctx
        .p
        .messages(d)
        .iter()
        .any(|m| m.fields.iter().any(Field::is_float))
    {
        quote!(#[derive(Debug, Clone, Copy, PartialEq)])
    } else {
        quote!(#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)])
    };
    let (constant_first, constant_fns) = constant_fns(msgs, &constant_arms);
    // Every encoder lays the frame out alike: its address checked, each message's arm, the
    // transform and the seal; what differs is what comes before and after.
    let laid_out = quote! {
        rt::encode_address(address, &#frame_const)?;
        #take_once
        let len = match *self { #(#encode_arms)* };
        #transform
        #seal
    };
    let encode_fn = encode_fn(p, d, msgs, &laid_out, &constant_first);
    let (derive_arbitrary, no_arbitrary) = arbitrary_derive(&ty, msgs);
    ctx.structs.borrow_mut().push((d, quote!(#(#structs)*)));
    quote! {
        #repeats
        #records
        #[doc = #what]
        #derives
        #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
        #derive_arbitrary
        #[allow(clippy::large_enum_variant)]
        pub enum #ty {
            #(#variants,)*
        }
        #no_arbitrary
        impl #ty {
            /// Each message's spec name, code and frame length, in spec order.
            const MESSAGES: [(&'static str, &'static [u8], usize); #n] = [#(#rows),*];
            /// This message's row in [`Self::MESSAGES`].
            const fn index(&self) -> usize {
                match *self { #(#index_arms,)* }
            }
            /// The spec's snake_case name of this message.
            pub const fn name(&self) -> &'static str {
                Self::MESSAGES[self.index()].0
            }
            /// The command or response code, as sent.
            pub const fn code(&self) -> &'static [u8] {
                Self::MESSAGES[self.index()].1
            }
            /// The length of this message's frame, in bytes.
            pub const fn frame_len(&self) -> usize {
                #frame_len
            }
            /// Calls `f` with each field's spec name and raw wire value (sign-extended where the
            /// field is signed), in frame order; constant and repeated fields are not visited.
            pub fn visit(&self, #visit_param: impl FnMut(&'static str, rt::FieldValue<'_>)) {
                #visit_body
            }
            /// Encodes the frame for `address` into `buf`; returns the frame length. Refuses what
            /// decode refuses: an address no frame may carry, the broadcast address for a command
            /// that does not accept it, a value outside its field's range.
            #encode_fn
            #constant_fns
            #dispatch
            #from_fields
        }
        impl rt::Message for #ty {
            #[inline]
            fn name(&self) -> &'static str {
                #ty::name(self)
            }
            #[inline]
            fn code(&self) -> &'static [u8] {
                #ty::code(self)
            }
            #[inline]
            fn frame_len(&self) -> usize {
                #ty::frame_len(self)
            }
            #[inline]
            fn visit<F: FnMut(&'static str, rt::FieldValue<'_>)>(&self, f: F) {
                #ty::visit(self, f)
            }
            #[inline]
            fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #ty::encode(self, address, buf)
            }
            #[inline]
            fn from_fields<'v, F: FnMut(&'static str) -> rt::Option<rt::FieldValue<'v>>>(
                name: &str,
                field: F,
            ) -> rt::Result<Self, rt::FieldError> {
                #ty::from_fields(name, field)
            }
        }
        #command_info
    }
}

/// The fields of message `m`'s struct, each with its doc: an optional one an `Option`.
fn struct_fields(ctx: &Ctx, m: &Message, ls: &[Leaf]) -> Vec<TokenStream> {
    let p = ctx.p;
    ls.iter()
        .map(|l| {
            let n = ident(l.name);
            let t = ctx.rust_type(l);
            let mut d = leaf_doc(p, l);
            // An optional field: `None` where its condition does not hold.
            let t = match l.field.present.as_ref().filter(|_| l.bits.is_none()) {
                Some(c) => {
                    d.push_str(&format!(
                        " On the wire only when {}; `None` where it is not.",
                        condition_text(m, c)
                    ));
                    quote!(rt::Option<#t>)
                }
                None => t,
            };
            let d = doc(d.trim());
            let t = in_parent(t);
            quote!(#d pub #n: #t)
        })
        .collect()
}

/// The doc of message `m`'s struct: its title, section, code or constant frame, and length:
/// `Read (§Read; code `0x02`, 8 bytes). …`.
fn message_doc(m: &Message) -> TokenStream {
    let size = match len_range(m) {
        (lo, hi) if lo == hi => format!("{lo} bytes"),
        (lo, hi) => format!("{lo} to {hi} bytes"),
    };
    let what = match &m.frame {
        Some(bytes) => format!("constant frame `{}`", hex_spaced(bytes)),
        None if m.code.is_empty() => "no code".to_string(),
        None => format!("code `{}`", m.code_hex()),
    };
    let section = if m.section.is_empty() {
        String::new()
    } else {
        format!("§{}; ", m.section)
    };
    doc(&format!("{} ({section}{what}, {size}). {}", m.title, m.doc))
}

/// `frame_len`'s arm for message `m` where its length varies (optional fields, lists).
fn len_arm(ctx: &Ctx, m: &Message, ls: &[Leaf]) -> Option<TokenStream> {
    let v = variant(m);
    let len = if m.has_optional() {
        // The frame as long as the optional fields given make it.
        let c = optional_const(m);
        let given = m.optionals().map(|(_, f, _)| {
            let n = ident(&f.name);
            quote!(m.#n.is_some())
        });
        quote!(#c.frame_len(&[#(#given),*]))
    } else if has_lists(m) {
        let c = lists_const(m);
        let sum = m.repeats().enumerate().map(|(k, (_, f, _))| {
            let (n, k) = (ident(&f.name), usize_lit(k));
            quote!(#c.lists[#k].bytes_of(m.#n.len()))
        });
        quote!(#c.base #(+ #sum)*)
    } else {
        let (f, _) = m.repeat()?;
        let (n, c) = (ident(&f.name), repeat_const(m));
        let sized = sized_record(m, f).and_then(|(wf, fixed, _)| {
            let wl = ls
                .iter()
                .find(|l| std::ptr::eq(l.field, wf) && l.bits.is_none())?;
            let wn = ident(wl.name);
            Some((raw_of(ctx, wl, &quote!(m.#wn))?.1, fixed))
        });
        match sized {
            Some((raw, fixed)) => {
                // Each record as wide as its width field says.
                let fixed = usize_lit(fixed);
                quote!(#c.base + m.#n.len() * (#fixed + (#raw) as usize))
            }
            None => quote!(#c.base + #c.bytes_of(m.#n.len())),
        }
    };
    Some(quote!(Self::#v(m) => #len))
}

/// `visit`'s calls for each leaf of a message.
fn visits(ctx: &Ctx, ls: &[Leaf]) -> Vec<TokenStream> {
    // Each field read where the struct holds it (`self.quantity`), an optional one where
    // it is present.
    ls.iter()
        .map(|l| {
            let (n, f) = (l.name, ident(l.name));
            let optional = l.field.present.is_some() && l.bits.is_none();
            let v = if optional {
                let l = local(l.name);
                quote!(#l)
            } else {
                quote!(self.#f)
            };
            let value = match ctx.kind(l) {
                Kind::Int(t) if t.float => quote!(rt::Int(rt::raw(#v))),
                Kind::Int(_) | Kind::Bool => quote!(rt::Int(#v as i64)),
                Kind::Unit { .. } | Kind::Enum { .. } | Kind::Flags { .. } => {
                    quote!(rt::Int(#v.raw() as i64))
                }
                Kind::Text(_) => quote!(rt::Text(&#v[..])),
                Kind::List { text: true, .. } => quote!(rt::Text(#v.as_slice())),
                Kind::List { typed: Some(_), .. } => quote!(rt::List(#v.table())),
                // 64-bit and float elements (a list of a fixed count): by their raw values.
                Kind::List { elem, .. } if elem.float || elem.bits == 64 => {
                    quote!(rt::List(#v.table()))
                }
                Kind::List { .. } | Kind::BitList { .. } => quote!(rt::List(#v.elements())),
                Kind::Records { .. } => quote!(rt::Records(#v.records())),
            };
            if optional {
                quote!(if let rt::Some(#v) = self.#f { f(#n, #value) })
            } else {
                quote!(f(#n, #value))
            }
        })
        .collect()
}

/// The end of every encoder: the checksum (and end bytes) written after the arms, or the
/// arms' length where they write it.
fn encode_seal(p: &Protocol, d: Direction) -> TokenStream {
    if checksum_in_arms(p) {
        quote!(rt::Ok(len))
    } else {
        let sum = frame_sum(p, d);
        let frame = seal_frame_of(p, d);
        quote! {
            #frame.seal(buf, len, #sum);
            rt::Ok(len)
        }
    }
}

/// Constant whole frames (`frame:`): their bytes, whatever the address, before any check
/// of a framed frame; `constant` recognises them before `decode` checks the framing. The
/// encoder's first lines and the functions, or nothing without such a frame.
fn constant_fns(msgs: &[Message], constant_arms: &[TokenStream]) -> (TokenStream, TokenStream) {
    if constant_arms.is_empty() {
        (quote!(), quote!())
    } else {
        let recognise = msgs.iter().filter_map(|m| {
            let bytes = m.frame.as_ref()?.iter().map(|b| hex_u8(*b));
            let (v, dm) = (variant(m), direction_module(m.direction));
            Some(quote!([#(#bytes),*] => rt::Some(Self::#v(#dm::#v)),))
        });
        (
            quote! {
                if let rt::Some(frame) = self.constant_frame() {
                    return rt::put_frame(buf, frame);
                }
            },
            quote! {
                /// The bytes of a constant whole frame (`frame:` in the spec), `None` for a
                /// framed message.
                pub const fn constant_frame(&self) -> rt::Option<&'static [u8]> {
                    match *self {
                        #(#constant_arms)*
                        _ => rt::None,
                    }
                }
                /// The constant whole frame `frame` is, byte for byte, if any.
                #[inline]
                fn constant(frame: &[u8]) -> rt::Option<Self> {
                    match frame {
                        #(#recognise)*
                        _ => rt::None,
                    }
                }
            },
        )
    }
}

/// The direction's `encode` (and what it calls), around the frame `laid_out` writes: the
/// preamble, truncation, the long or short form, a reply over its request's bytes, escaping.
fn encode_fn(
    p: &Protocol,
    d: Direction,
    msgs: &[Message],
    laid_out: &TokenStream,
    constant_first: &TokenStream,
) -> TokenStream {
    if p.framing.preamble.is_some() {
        // Escaping and constant frames are refused beside a preamble (validated).
        quote! {
            ///
            /// The preamble's wake-up bytes come first (`framing.preamble`); `buf` of
            /// `MAX_FRAME_LEN` bytes holds any frame with them.
            pub fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                let n = PREAMBLE.put(buf)?;
                let len = self.encode_frame(address, &mut buf[n..])?;
                rt::Ok(n + len)
            }
            /// The frame after the preamble, into `buf`.
            fn encode_frame(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #laid_out
            }
        }
    } else if p.framing.truncation.is_some() {
        // Payload truncation (`framing.truncation`; escaping, preambles, transforms, forms
        // and constant frames are refused beside it: validated): the frame laid out with its
        // whole payload, then its trailing zeros stripped.
        let sum = super::head::frame_sum(p, d);
        quote! {
            ///
            /// The payload's trailing zero bytes are stripped (one byte kept), the length field
            /// and checksum rewritten (`framing.truncation`).
            pub fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                let len = self.encode_laid_out(address, buf)?;
                rt::Ok(TRUNCATION.travel(buf, len, &FRAME, #sum))
            }
            /// The frame laid out with its whole payload, into `buf`.
            fn encode_laid_out(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #laid_out
            }
        }
    } else if p.framing.long.is_some() || p.framing.form.is_some() {
        // A length field whose width the start byte chooses (`framing.length.long`; escaping,
        // preambles and constant frames are refused beside it: validated): laid out in the
        // long form's width, then sent in the form the length needs. A short form of the
        // frame (`framing.forms`: escaping and preambles refused beside it) likewise: laid out
        // in the framing's own layout, then sent short where the payload is empty; a constant
        // whole frame beside it is its bytes, whatever the address.
        let (lay, travels) = if p.framing.form.is_some() {
            (
                quote!(FORM),
                quote! {
                    /// The frame travels short where its payload is empty, else in the
                    /// framing's own layout (`framing.forms`); `buf` of `MAX_FRAME_LEN` bytes
                    /// holds any.
                },
            )
        } else {
            (
                quote!(LONG),
                quote! {
                    /// The frame travels short where its length fits the short length field, else long
                    /// (`framing.length.long`); `buf` of `MAX_FRAME_LEN` bytes holds any.
                },
            )
        };
        quote! {
            ///
            #travels
            pub fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #constant_first
                let len = self.encode_laid_out(address, buf)?;
                rt::Ok(#lay.travel(buf, len))
            }
            /// The frame laid out in the long form's width, into `buf`.
            fn encode_laid_out(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #laid_out
            }
        }
    } else if d == Direction::Response && p.has_over_request() {
        // A reply whose checksum takes in its request's bytes (`checksum_over_request`;
        // escaping, preambles, forms, long lengths, truncation and transforms refused beside
        // it: validated): written with its checksum over its own bytes, then over the
        // request's first by `encode_reply_over`; `encode` refuses it.
        let over_arms = msgs.iter().filter_map(|m| {
            let (v, from) = (variant(m), usize_lit(m.over_request?));
            Some(quote!(Self::#v { .. } => rt::Some(#from),))
        });
        quote! {
            ///
            /// A reply whose checksum takes in its request's bytes is refused
            /// ([`busspec_runtime::EncodeError::NeedsRequest`]): see [`Self::encode_reply_over`].
            pub fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                let len = self.encode_own(address, buf)?;
                match self.over_request() {
                    rt::Some(_) => rt::Err(rt::EncodeError::NeedsRequest { message: self.name() }),
                    rt::None => rt::Ok(len),
                }
            }
            /// Encodes the frame for `address` into `buf` as the reply to a request whose
            /// checksum covered `covered` (`busspec_runtime::RequestMessage::covered` of its
            /// frame): as [`Self::encode`], and the checksum of a reply that takes in its
            /// request's bytes over them.
            pub fn encode_reply_over(&self, address: u8, covered: &[u8], buf: &mut [u8]) -> rt::EncodeResult {
                let len = self.encode_own(address, buf)?;
                if let rt::Some(from) = self.over_request() {
                    rt::seal_end(buf, len, |b| u32::from(checksum_after(covered, rt::covered(b, from))), &FRAME);
                }
                rt::Ok(len)
            }
            /// Where this reply's checksum takes up its own bytes after its request's, for a
            /// reply whose checksum takes them in (`checksum_over_request`).
            pub const fn over_request(&self) -> rt::Option<usize> {
                match *self {
                    #(#over_arms)*
                    _ => rt::None,
                }
            }
            /// The frame with its checksum over its own bytes alone, into `buf`.
            fn encode_own(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #constant_first
                #laid_out
            }
        }
    } else if p.framing.escaping.is_none() {
        quote! {
            pub fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #constant_first
                #laid_out
            }
        }
    } else {
        let sum = frame_sum(p, d);
        let escaping = escaping_of(p, d);
        quote! {
            ///
            /// The frame is written escaped (`framing.escaping`); `buf` of `MAX_FRAME_LEN`
            /// bytes holds any.
            pub fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                let mut plain = [0u8; UNESCAPED_LEN];
                let len = self.encode_unescaped(address, &mut plain)?;
                rt::escape_frame(&#escaping, &plain[..len], buf, #sum)
            }
            /// The frame before escaping, into `buf`.
            fn encode_unescaped(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
                #laid_out
            }
        }
    }
}

/// The `arbitrary` derive of a direction's enum, or an impl that makes no value where it has
/// no variant.
fn arbitrary_derive(ty: &Ident, msgs: &[Message]) -> (TokenStream, TokenStream) {
    // `arbitrary`'s derive refuses an enum without variants (a protocol whose commands get no
    // reply has no responses): such a type has no value to make.
    if msgs.is_empty() {
        (
            quote!(),
            quote! {
                #[cfg(feature = "arbitrary")]
                impl<'a> ::arbitrary::Arbitrary<'a> for #ty {
                    fn arbitrary(_: &mut ::arbitrary::Unstructured<'a>) -> ::arbitrary::Result<Self> {
                        rt::Err(::arbitrary::Error::IncorrectFormat)
                    }
                }
            },
        )
    } else {
        (
            quote!(#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]),
            quote!(),
        )
    }
}

/// `from_fields`: one arm per message, building it from the getter's raw value of each field,
/// each checked against its wire type as the encoder checks it (`to_wire`), then typed as the
/// decoder types it (`from_wire`). Fields are asked for in frame order.
pub(super) fn emit_from_fields(ctx: &Ctx, d: Direction) -> TokenStream {
    let field_param = if ctx.p.messages(d).iter().all(|m| leaves(m).is_empty()) {
        quote!(_field)
    } else {
        quote!(mut field)
    };
    let arms = ctx.p.messages(d).iter().map(|m| {
        let name = &m.name;
        let v = variant(m);
        let dm = direction_module(d);
        let ls = leaves(m);
        if ls.is_empty() {
            return quote!(#name => Self::#v(#dm::#v));
        }
        let fields = ls.iter().map(|l| {
            let (n, f) = (l.name, ident(l.name));
            let value = match ctx.kind(l) {
                Kind::Text(_) => quote!(rt::text(&mut field, #n)?),
                Kind::List {
                    max, text: true, ..
                } => {
                    let max = usize_lit(max);
                    quote!(rt::list_text::<#max>(&mut field, #n)?)
                }
                Kind::List {
                    elem, max, typed, ..
                } => {
                    let (e, max) = (typed.unwrap_or_else(|| elem.ident()), usize_lit(max));
                    // A 64-bit element's raw value is its bits: every `i64`.
                    let (lo, hi) = if elem.bits == 64 {
                        (i64::MIN, i64::MAX)
                    } else {
                        elem.limits()
                    };
                    let (lo, hi) = (i64_lit(lo), i64_lit(hi));
                    quote!(rt::list::<#e, #max>(&mut field, #n, #lo, #hi)?)
                }
                Kind::BitList { bytes } => {
                    let bytes = usize_lit(bytes);
                    quote!(rt::list_bits::<#bytes>(&mut field, #n)?)
                }
                Kind::Records { ty, max } => {
                    let max = usize_lit(max);
                    quote!(rt::records::<#ty, #max>(&mut field, #n)?)
                }
                _ if l.bits.is_none() && l.field.present.is_some() => {
                    // An optional field: no value, absent (`None`).
                    let raw = ident("raw");
                    let get = if l.wire.bits == 24 {
                        let (lo, hi) = l.wire.limits();
                        let (lo, hi) = (i64_lit(lo), i64_lit(hi));
                        quote!(rt::field_int_opt(#n, field(#n), #lo, #hi)?)
                    } else {
                        let w = l.wire.ident();
                        quote!(rt::get_opt::<#w>(&mut field, #n)?)
                    };
                    let wire = (l.wire.bits != 24).then_some(l.wire);
                    match ctx.kind(l) {
                        Kind::Int(t) if Some(t) == wire => get,
                        Kind::Unit { ty, raw: r }
                        | Kind::Enum { ty, raw: r }
                        | Kind::Flags { ty, raw: r }
                            if Some(r) == wire =>
                        {
                            quote!(#get.map(#ty::from_raw))
                        }
                        _ => {
                            let value = from_wire(ctx, l, wire, quote!(#raw));
                            quote!(#get.map(|#raw| #value))
                        }
                    }
                }
                _ if l.bits.is_none() && l.wire.bits != 24 => {
                    let w = l.wire.ident();
                    let get = match raw_of(ctx, l, &ident("x")) {
                        Some((t, _)) if t == l.wire => quote!(rt::get(&mut field, #n)?),
                        _ => quote!(rt::get::<#w>(&mut field, #n)?),
                    };
                    from_wire(ctx, l, Some(l.wire), get)
                }
                _ => {
                    let (lo, hi) = l
                        .bits
                        .map(|b| raw_limits(u32::from(b.width()), b.signed))
                        .unwrap_or(l.wire.limits());
                    let (lo, hi) = (i64_lit(lo), i64_lit(hi));
                    from_wire(
                        ctx,
                        l,
                        None,
                        quote!(rt::field_int(#n, field(#n), #lo, #hi)?),
                    )
                }
            };
            quote!(#f: #value)
        });
        quote!(#name => Self::#v(#dm::#v { #(#fields),* }))
    });
    quote! {
        /// The message called `name` in the spec, from each field's raw wire value by its spec
        /// name, as [`Self::visit`] gives them (`None`: no value); constant and repeated fields
        /// are not asked for. See [`::busspec_runtime::Message::from_fields`].
        pub fn from_fields<'v>(
            name: &str,
            #field_param: impl FnMut(&'static str) -> rt::Option<rt::FieldValue<'v>>,
        ) -> rt::Result<Self, rt::FieldError> {
            let message = match name {
                #(#arms,)*
                _ => return rt::Err(rt::FieldError::UnknownMessage),
            };
            rt::Ok(message)
        }
    }
}

/// Message `m`'s struct, defined in its direction's module (`request::ReadCoils`): its fields
/// public, typed as the enum's variants type them; a message without fields a unit struct.
/// A struct with fields is aligned to 4 bytes, so that every message of a direction keeps its
/// fields at one offset in the enum and decode moves no field to build it (`BENCHMARKS.md`).
fn message_struct(
    ctx: &Ctx,
    m: &Message,
    ls: &[Leaf],
    doc: TokenStream,
    fields: Vec<TokenStream>,
) -> TokenStream {
    let v = variant(m);
    let derives = if m.fields.iter().any(Field::is_float) {
        quote!(#[derive(Debug, Clone, Copy, PartialEq)])
    } else {
        quote!(#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)])
    };
    let _ = ctx;
    let body = if ls.is_empty() {
        quote!(pub struct #v;)
    } else {
        quote!(#[repr(align(4))] pub struct #v { #(#fields),* })
    };
    quote! {
        #doc
        #derives
        #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
        #[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
        #body
    }
}

/// `request::ReadCoils { starting_address: v_starting_address, .. }`: `m`'s struct binding
/// each field to its `v_<name>` local.
pub(super) fn own_binding(m: &Message, ls: &[Leaf]) -> TokenStream {
    let (v, dm) = (variant(m), direction_module(m.direction));
    fields_binding(quote!(#dm::#v), ls)
}

/// `path { a: v_a, b: v_b }`: a struct pattern (or literal) over leaves `ls`, each field
/// bound to its `v_<name>` local.
pub(super) fn fields_binding(path: TokenStream, ls: &[Leaf]) -> TokenStream {
    let fields = ls.iter().map(|l| {
        let (n, v) = (ident(l.name), local(l.name));
        quote!(#n: #v)
    });
    quote!(#path { #(#fields),* })
}

/// Message `m`'s constants and methods: `NAME`, `CODE`, its frame length (`LEN`, or `MIN_LEN`
/// and `MAX_LEN`), `DESC` (what its refusals point at) where it is framed, the byte range of
/// each field at a fixed offset (named as the field, upper-cased; `AT_` before a name the
/// others take), a typed constant for each special value of a field (`PAN_SPEED_TURBO`),
/// `visit` where it has fields to visit, and `encode` (the frame for an address, as the enum's
/// `encode` writes it). Kept in `Ctx::impls` and emitted by `emit_descs` once every refusal
/// has named its fields, whose descriptors (`QUANTITY_DESC`) join the constants.
fn message_impl(ctx: &Ctx, m: &Message, ls: &[Leaf], visit: TokenStream) {
    let (v, dm) = (variant(m), direction_module(m.direction));
    let (ty, _) = direction_names(m.direction);
    let name = &m.name;
    let code = m.code.iter().map(|b| hex_u8(*b));
    let lens = match len_range(m) {
        (lo, hi) if lo == hi => {
            let lo = usize_lit(lo);
            quote!(pub const LEN: usize = #lo;)
        }
        (lo, hi) => {
            let (lo, hi) = (usize_lit(lo), usize_lit(hi));
            quote!(pub const MIN_LEN: usize = #lo; pub const MAX_LEN: usize = #hi;)
        }
    };
    let o = m.layout;
    let ranges = ls.iter().filter_map(|l| {
        let f = l.field;
        let fi = m.fields.iter().position(|g| std::ptr::eq(g, f))?;
        let after_list = m.fields[..fi].iter().any(|g| g.repeat.is_some());
        if l.bits.is_some() || f.repeat.is_some() || f.present.is_some() || after_list {
            return None;
        }
        let at = f.frame_at(&o);
        let c = ident(&range_const(l.name));
        let (a, b) = (usize_lit(at), usize_lit(at + f.width));
        Some(quote!(pub const #c: rt::Range<usize> = #a..#b;))
    });
    let specials = special_consts(ctx, ls);
    let desc = message_desc_const(ctx.p, m);
    let consts = quote! {
        pub const NAME: &'static str = #name;
        pub const CODE: &'static [u8] = &[#(#code),*];
        #lens
        #desc
        #(#ranges)*
        #specials
    };
    let fns = quote! {
        #visit
        pub fn encode(&self, address: u8, buf: &mut [u8]) -> rt::EncodeResult {
            #ty::#v(*self).encode(address, buf)
        }
    };
    ctx.impls
        .borrow_mut()
        .push((m.direction, m.name.clone(), quote!(#dm::#v), consts, fns));
}

/// The constant of a field's byte range: its name upper-cased, `AT_` before a name the
/// struct's other constants take.
fn range_const(field: &str) -> String {
    let upper = field.to_ascii_uppercase();
    match upper.as_str() {
        "NAME" | "CODE" | "LEN" | "MIN_LEN" | "MAX_LEN" | "DESC" => format!("AT_{upper}"),
        _ => upper,
    }
}

/// The names of `m`'s struct constants other than its field descriptors: `NAME`, `CODE`, the
/// lengths, `DESC`, a byte range for (at most) each field and the special values' constants.
pub(super) fn struct_consts(m: &Message) -> Vec<String> {
    let mut names: Vec<String> = ["NAME", "CODE", "LEN", "MIN_LEN", "MAX_LEN", "DESC"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for l in leaves(m) {
        names.push(range_const(l.name));
    }
    let ranges = names.clone();
    for l in leaves(m) {
        if l.bits.is_none() {
            for sp in &l.field.special {
                names.push(special_const(&ranges, l.name, &sp.name));
            }
        }
    }
    names
}

/// The constant of special value `special` of `field`: `PAN_SPEED_TURBO`, or
/// `FIELD__SPECIAL` where a byte range's constant or another of the struct's takes that name.
fn special_const(taken: &[String], field: &str, special: &str) -> String {
    let c = format!("{}_{}", field, special).to_ascii_uppercase();
    if taken.contains(&c) {
        format!("{}__{}", field, special).to_ascii_uppercase()
    } else {
        c
    }
}

/// A typed constant for each special value of a whole field of `ls` whose type has a constant
/// form (an integer, a unit, an enum, a flag set), with the special value's doc.
fn special_consts(ctx: &Ctx, ls: &[Leaf]) -> TokenStream {
    let ranges: Vec<String> = ["NAME", "CODE", "LEN", "MIN_LEN", "MAX_LEN", "DESC"]
        .iter()
        .map(|s| s.to_string())
        .chain(ls.iter().map(|l| range_const(l.name)))
        .collect();
    let mut out = Vec::new();
    for l in ls
        .iter()
        .filter(|l| l.bits.is_none() && l.field.repeat.is_none())
    {
        for sp in &l.field.special {
            // The raw value as the spec writes it: hex, two digits a wire byte.
            let digits = l.field.width * 2;
            let raw = if sp.value < 0 {
                let v = i64_lit(sp.value);
                quote!(#v)
            } else {
                format!("0x{:0digits$X}", sp.value)
                    .parse()
                    .unwrap_or_else(|_| hex_lit(sp.value as u64))
            };
            let value = match ctx.kind(l) {
                Kind::Int(t) if !t.float => raw,
                Kind::Unit { ty, .. } | Kind::Enum { ty, .. } | Kind::Flags { ty, .. } => {
                    quote!(#ty::from_raw(#raw))
                }
                _ => continue,
            };
            let c = ident(&special_const(&ranges, l.name, &sp.name));
            let t = ctx.rust_type(l);
            let text = if sp.doc.is_empty() {
                format!("`{}`'s special value `{}`.", l.name, sp.name)
            } else {
                format!("`{}`'s special value `{}`: {}", l.name, sp.name, sp.doc)
            };
            let d = doc(&text);
            out.push(quote!(#d pub const #c: #t = #value;));
        }
    }
    quote!(#(#out)*)
}

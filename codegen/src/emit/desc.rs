use super::*;

/// The `request` and `response` modules: each message's struct (its `rt::MessageDesc`, its
/// name, code and the frame lengths of its code, is its constant `DESC`:
/// `request::ReadCoils::DESC`, [`message_desc_const`]), and an `rt::FieldDesc` for each field
/// a refusal names
/// (`request::READ_COILS_QUANTITY`, [`Ctx::field_desc`]), which the refusals point at
/// (`rt::fixed`, `rt::in_range`, `rt::Group::end`, ...) instead of spelling names at every
/// call. Emitted last, once every refusal has named its fields.
pub(super) fn emit_descs(ctx: &Ctx) -> TokenStream {
    let p = ctx.p;
    let fields = ctx.field_descs.borrow();
    let dir = |d: Direction| {
        let mut consts = Vec::new();
        for m in p.messages(d) {
            for (_, _, f, c) in fields
                .iter()
                .filter(|(fd, mn, ..)| *fd == d && *mn == m.name)
            {
                let name = &m.name;
                let doc = doc(&format!("`{name}.{f}`"));
                consts.push(quote! {
                    #doc
                    pub const #c: FieldDesc = FieldDesc::new(#name, #f);
                });
            }
        }
        let structs: Vec<TokenStream> = ctx
            .structs
            .borrow()
            .iter()
            .filter(|(sd, _)| *sd == d)
            .map(|(_, t)| t.clone())
            .collect();
        if consts.is_empty() {
            return quote!(#(#structs)*);
        }
        quote! {
            use ::busspec_runtime::FieldDesc;
            #(#structs)*
            #(#consts)*
        }
    };
    let (requests, responses) = (dir(Direction::Request), dir(Direction::Response));
    quote! {
        /// Each request as a struct of its own (its `DESC` names it as refusals do: name,
        /// code and the frame lengths of its code), and each field a refusal names
        /// (`message.field`, `FieldDesc`).
        pub mod request {
            #requests
        }
        /// Each response as a struct of its own, and the fields its refusals name.
        pub mod response {
            #responses
        }
    }
}

/// `&request::ReadCoils::DESC`: message `m`'s descriptor, as the refusals take it (a
/// constant of its struct, [`message_desc_const`]).
pub(super) fn message_desc(m: &Message) -> TokenStream {
    let dir = direction_module(m.direction);
    let v = variant(m);
    quote!(&#dir::#v::DESC)
}

/// `DESC`, the descriptor of framed message `m`: its name, code and the frame lengths of its
/// code; `None` for a constant whole frame, which no refusal names.
pub(super) fn message_desc_const(p: &Protocol, m: &Message) -> Option<TokenStream> {
    if !p.framed(m.direction).iter().any(|x| x.name == m.name) {
        return None;
    }
    let (code, code_len) = code_args(m);
    let lengths = dispatch_lengths(p, m).into_iter().map(usize_lit);
    Some(quote! {
        pub const DESC: rt::MessageDesc = rt::MessageDesc::new(Self::NAME, #code, #code_len, &[#(#lengths),*]);
    })
}

/// The module of direction `d`'s descriptors: `request` or `response`.
pub(super) fn direction_module(d: Direction) -> Ident {
    match d {
        Direction::Request => ident("request"),
        Direction::Response => ident("response"),
    }
}

/// `m`'s code as a descriptor gives it: its value and length in bytes.
pub(super) fn code_args(m: &Message) -> (TokenStream, Literal) {
    let code = if m.code.is_empty() {
        quote!(0)
    } else {
        hex_code(&m.code)
    };
    (code, Literal::u8_unsuffixed(m.code.len() as u8))
}

/// The frame lengths `dispatch` tries a frame of `m`'s code at, sorted, as a wrong length
/// names them: those of every message of its code, and, where code-less messages sit beside
/// coded ones, of the code-less ones too (which every coded arm also tries).
fn dispatch_lengths(p: &Protocol, m: &Message) -> Vec<usize> {
    let msgs = p.framed(m.direction);
    let codeless = msgs.iter().any(|x| x.code.is_empty());
    let mixed = codeless && msgs.iter().any(|x| !x.code.is_empty());
    let mut lengths: Vec<usize> = msgs
        .iter()
        .filter(|x| x.code == m.code || (mixed && x.code.is_empty()))
        .map(|x| p.frame_len(x))
        .collect();
    lengths.sort_unstable();
    lengths.dedup();
    lengths
}

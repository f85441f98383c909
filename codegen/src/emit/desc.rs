use super::*;

/// The `request` and `response` modules: one `rt::MessageDesc` per framed message of the
/// direction (`request::READ_COILS`), its name, code and the frame lengths of its code, and
/// after it an `rt::FieldDesc` for each of its fields a refusal names
/// (`request::READ_COILS_QUANTITY`, [`Ctx::field_desc`]), which the refusals point at
/// (`rt::fixed`, `rt::in_range`, `rt::Group::end`, ...) instead of spelling names at every
/// call. Emitted last, once every refusal has named its fields.
pub(super) fn emit_descs(ctx: &Ctx) -> TokenStream {
    let p = ctx.p;
    let fields = ctx.field_descs.borrow();
    let dir = |d: Direction| {
        let framed = p.framed(d);
        let mut consts = Vec::new();
        let mut uses = Vec::new();
        for m in p.messages(d) {
            if framed.iter().any(|x| x.name == m.name) {
                let c = desc_ident(m);
                let name = &m.name;
                let (code, code_len) = code_args(m);
                let lengths = dispatch_lengths(p, m);
                let text = match m.code.as_slice() {
                    [] => format!("`{name}` (no code)"),
                    code => format!("`{name}`, code {}", hex_code(code)),
                };
                let doc = doc(&text);
                let lengths = lengths.into_iter().map(usize_lit);
                consts.push(quote! {
                    #doc
                    pub const #c: MessageDesc = MessageDesc::new(#name, #code, #code_len, &[#(#lengths),*]);
                });
                if uses.is_empty() {
                    uses.push(quote!(MessageDesc));
                }
            }
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
                if !uses.iter().any(|u| u.to_string() == "FieldDesc") {
                    uses.push(quote!(FieldDesc));
                }
            }
        }
        if consts.is_empty() {
            return quote!();
        }
        let uses = match uses.as_slice() {
            [one] => quote!(#one),
            more => quote!({#(#more),*}),
        };
        quote! {
            use ::busspec_runtime::#uses;
            #(#consts)*
        }
    };
    let (requests, responses) = (dir(Direction::Request), dir(Direction::Response));
    quote! {
        /// Each request and its fields as refusals name them: name, code and the frame
        /// lengths of its code (`MessageDesc`), and `message.field` (`FieldDesc`).
        pub mod request {
            #requests
        }
        /// Each response as its refusals name it.
        pub mod response {
            #responses
        }
    }
}

/// The constant naming message `m` in its direction's module: its name upper-cased.
fn desc_ident(m: &Message) -> Ident {
    ident(&m.name.to_uppercase())
}

/// `&request::READ_COILS`: message `m`'s descriptor, as the refusals take it.
pub(super) fn message_desc(m: &Message) -> TokenStream {
    let dir = direction_module(m.direction);
    let c = desc_ident(m);
    quote!(&#dir::#c)
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

use super::*;

/// Each message's `impl` (`messages::message_impl`: `NAME`, `CODE`, the lengths, `DESC`, its
/// `rt::MessageDesc`, [`message_desc_const`], byte ranges, special values, `visit`, `encode`)
/// with an `rt::FieldDesc` for each field a refusal names (`request::ReadCoils::QUANTITY_DESC`,
/// [`Ctx::field_desc`]), which the refusals point at (`rt::fixed`, `rt::equal`,
/// `rt::Group::end`, ...) instead of spelling names at every call, each followed by the field's
/// `rt::FieldCheck`s (`QUANTITY_CHECK`, [`Ctx::field_check`]: its offset, range and relation,
/// which `rt::in_range`, `rt::encode_in_range` and `rt::following` take); then the `request` and
/// `response` modules with the message structs. Emitted last, once every refusal has named its
/// fields.
pub(super) fn emit_descs(ctx: &Ctx) -> TokenStream {
    let fields = ctx.field_descs.borrow();
    let checks = ctx.field_checks.borrow();
    let impls = ctx.impls.borrow();
    let (readers, writers) = (ctx.readers.borrow(), ctx.writers.borrow());
    let followers = ctx.followers.borrow();
    let impls = impls.iter().map(|(d, name, path, consts, fns)| {
        let read = writers
            .iter()
            .chain(readers.iter())
            .chain(followers.iter())
            .filter(|(rd, rn, _)| rd == d && rn == name)
            .map(|(.., f)| f);
        let descs = fields
            .iter()
            .filter(|(fd, mn, ..)| fd == d && mn == name)
            .map(|(_, _, f, c)| {
                let checks = checks.iter().filter(|k| k.direction == *d && k.message == *name && k.desc == *c).map(|k| {
                    let (n, at) = (&k.name, usize_lit(k.at));
                    let parse = |s: &Option<String>| -> TokenStream {
                        s.as_deref().map_or_else(TokenStream::new, |s| s.parse().expect("builder calls"))
                    };
                    let (range, follows) = (parse(&k.range), parse(&k.follows));
                    quote!(pub const #n: rt::FieldCheck = rt::check(&Self::#c, #at)#range #follows;)
                });
                quote! {
                    pub const #c: rt::FieldDesc = rt::field(Self::NAME, #f);
                    #(#checks)*
                }
            });
        quote! {
            impl #path {
                #consts
                #(#descs)*
                #fns
                #(#read)*
            }
        }
    });
    let dir = |d: Direction| {
        let structs: Vec<TokenStream> = ctx
            .structs
            .borrow()
            .iter()
            .filter(|(sd, _)| *sd == d)
            .map(|(_, t)| t.clone())
            .collect();
        quote!(#(#structs)*)
    };
    let (requests, responses) = (dir(Direction::Request), dir(Direction::Response));
    quote! {
        #(#impls)*
        /// Each request as a struct of its own; its constants (`DESC`, which names it as
        /// refusals do: name, code and the frame lengths of its code; `QUANTITY_DESC`, each
        /// field a refusal names) and methods are in the `impl` of each.
        pub mod request {
            #requests
        }
        /// Each response as a struct of its own.
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
        pub const DESC: rt::MessageDesc = rt::desc(Self::NAME, #code, #code_len, &[#(#lengths),*]);
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

use super::*;

/// Why protocol `p` gets no borrowed views in direction `d`, or `None` where it gets them.
///
/// A view lends the frame's own bytes, so it needs the bytes the decoder reads to be the
/// frame's: not where the frame is unescaped, laid out in the long length form or from a short
/// form, or has its payload transform undone into a buffer of the decoder's (escaping,
/// `length.long`, `forms`, `transform`), nor where the direction has constant whole frames (recognised before the
/// framing, outside the dispatch the view shares). A direction with no list has nothing to
/// lend: its owned value is already a copy of a few scalars.
pub(super) fn no_view(p: &Protocol, d: Direction) -> Option<&'static str> {
    if p.framing.escaping.is_some() {
        return Some("its frames are escaped: the decoder reads an unescaped copy");
    }
    if p.framing.long.is_some() {
        return Some("its long length form is laid out into a copy before decode");
    }
    if p.framing.form.is_some() {
        return Some("its short form is laid out into a copy before decode");
    }
    if p.framing.transform.is_some() {
        return Some("its payload transform is undone into a copy before decode");
    }
    if p.framing.truncation.is_some() {
        return Some("its truncated payloads are padded into a copy before decode");
    }
    if p.constants(d).next().is_some() {
        return Some("it has constant whole frames");
    }
    let lends = p
        .messages(d)
        .iter()
        .any(|m| leaves(m).iter().any(|l| lent(l)));
    if !lends {
        return Some("no message of the direction has a list to lend");
    }
    None
}

/// A type of the spec's (unit, enum, flag set, repeated record) whose Rust name would be a view
/// type the module defines (`RequestView`, `ResponseView`) is refused with a message naming it.
pub(super) fn view_names(p: &Protocol) -> Result<(), String> {
    let mut types: Vec<(String, String)> = Vec::new();
    for (names, what) in [
        (p.units.iter().map(|u| &u.name).collect::<Vec<_>>(), "unit"),
        (p.enums.iter().map(|e| &e.name).collect(), "enum"),
        (p.flags.iter().map(|f| &f.name).collect(), "flag set"),
    ] {
        types.extend(
            names
                .into_iter()
                .map(|n| (camel(n), format!("the {what} `{n}`"))),
        );
    }
    for m in p.commands.iter().chain(&p.responses) {
        for f in m.fields.iter().filter(|f| f.is_record()) {
            let what = format!("the record `{}.{}`", m.name, f.name);
            types.push((record_type(&m.name, f).to_string(), what));
        }
    }
    for (d, view) in [
        (Direction::Request, "RequestView"),
        (Direction::Response, "ResponseView"),
    ] {
        if no_view(p, d).is_some() {
            continue;
        }
        if let Some((_, what)) = types.iter().find(|(n, _)| n == view) {
            return Err(format!(
                "{}: {what} would be the type `{view}`, the name of the module's borrowed view; rename it",
                p.name
            ));
        }
    }
    Ok(())
}

/// The module docs' line on its borrowed views: which directions have one, and why a direction
/// has none.
pub(super) fn views_doc(p: &Protocol) -> String {
    let one = |d: Direction, ty: &str| match no_view(p, d) {
        None => format!("`{ty}View<'a>` lends its lists"),
        Some(why) => format!("no `{ty}View`: {why}"),
    };
    format!(
        "Borrowed views: {}; {}.",
        one(Direction::Request, "Request"),
        one(Direction::Response, "Response")
    )
}

/// Whether leaf `l` is a list a view lends (`rt::ListView`, `rt::BitsView`): a repeated field
/// of numbers or bits. A repeated record, a packed field and text keep their owned types.
fn lent(l: &Leaf) -> bool {
    l.bits.is_none() && l.field.repeat.is_some() && !l.field.is_record() && l.field.packed.is_none()
}

/// The type of leaf `l` in a view: its owned type, but a lent list's view.
fn view_type(ctx: &Ctx, l: &Leaf) -> TokenStream {
    if lent(l) {
        match ctx.kind(l) {
            Kind::List { elem, typed, .. } => {
                let e = typed.unwrap_or_else(|| elem.ident());
                return quote!(rt::ListView<'a, #e>);
            }
            Kind::BitList { .. } => return quote!(rt::BitsView<'a>),
            _ => {}
        }
    }
    let t = ctx.rust_type(l);
    match l.field.present.as_ref().filter(|_| l.bits.is_none()) {
        Some(_) => quote!(rt::Option<#t>),
        None => t,
    }
}

/// The view of direction `d` (`RequestView<'a>`/`ResponseView<'a>`): one variant per message,
/// its fields the owned message's, a list lent as it sits in the frame. Made by `decode`
/// (`decode_reply` for a response), the owned decoder's checks emitted again with the lists
/// lent (`Ctx::view`), so a view is made of exactly the frames the owned decode accepts and
/// refuses the others with the same error; `to_owned` gives the owned message. Empty where
/// [`no_view`] says why not.
pub(super) fn emit_view(ctx: &Ctx, d: Direction) -> TokenStream {
    let p = ctx.p;
    if no_view(p, d).is_some() {
        return quote!();
    }
    let (ty, _) = direction_names(d);
    let vt = format_ident!("{}View", ty);
    let msgs = p.messages(d);
    let mut variants = Vec::new();
    let mut index_arms = Vec::new();
    let mut owned_arms = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        let v = variant(m);
        let dm = direction_module(d);
        let ls = leaves(m);
        let i = usize_lit(i);
        let d = doc(&format!("[`{dm}::{v}`], read from the frame."));
        if ls.is_empty() {
            variants.push(quote!(#d #v));
            index_arms.push(quote!(Self::#v => #i,));
            owned_arms.push(quote!(Self::#v => #ty::#v(#dm::#v),));
            continue;
        }
        let fields = ls.iter().map(|l| {
            let (n, t) = (ident(l.name), view_type(ctx, l));
            quote!(#n: #t)
        });
        variants.push(quote!(#d #v { #(#fields),* }));
        index_arms.push(quote!(Self::#v { .. } => #i,));
        let names = ls.iter().map(|l| ident(l.name));
        let values = ls.iter().map(|l| {
            let n = ident(l.name);
            match (lent(l), ctx.kind(l)) {
                (true, Kind::List { .. }) => quote!(#n: #n.to_repeated()),
                (true, Kind::BitList { .. }) => quote!(#n: #n.to_bits()),
                _ => quote!(#n),
            }
        });
        owned_arms.push(quote!(Self::#v { #(#names),* } => #ty::#v(#dm::#v { #(#values),* }),));
    }
    ctx.view.set(true);
    let dispatch = emit_dispatch(ctx, d, &quote!(Self));
    let follows = if d == Direction::Response {
        emit_follows_request(ctx).unwrap_or_default()
    } else {
        quote!()
    };
    ctx.view.set(false);
    let doc_enum = doc(&format!(
        "A {} checked once and read in place: [`{ty}`] with each list lent by the frame \
         (`rt::ListView`, `rt::BitsView`) instead of copied. Scalar fields are read (and \
         checked) when the view is made.",
        if d == Direction::Request {
            "request"
        } else {
            "response"
        }
    ));
    quote! {
        #doc_enum
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum #vt<'a> {
            #(#variants,)*
        }
        impl<'a> #vt<'a> {
            #dispatch
            /// This message's row in the owned type's `MESSAGES`.
            const fn index(&self) -> usize {
                match *self {
                    #(#index_arms)*
                }
            }
            /// The spec's snake_case name of this message.
            pub const fn name(&self) -> &'static str {
                #ty::MESSAGES[self.index()].0
            }
            /// The owned message: each lent list copied.
            pub fn to_owned(self) -> #ty {
                match self {
                    #(#owned_arms)*
                }
            }
            #follows
        }
    }
}

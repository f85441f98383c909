use super::*;

/// The struct of each repeated record of direction `d`'s messages (`type: record`): its
/// fields typed as fields are (units, enums, flags), `Copy`, read from and written to a
/// fixed-size array of its width, each field's range checked, and its raw values lent to
/// `visit` and taken from `from_fields` (`rt::Record`).
pub(super) fn emit_records(ctx: &Ctx, d: Direction) -> TokenStream {
    let mut out = TokenStream::new();
    for m in ctx.p.messages(d) {
        for f in m.fields.iter().filter(|f| f.is_record()) {
            out.extend(emit_record(ctx, m, f));
        }
    }
    out
}

fn emit_record(ctx: &Ctx, m: &Message, f: &Field) -> TokenStream {
    let p = ctx.p;
    let ty = record_type(&m.name, f);
    let width = usize_lit(f.width);
    // Each field goes by `record.field` in errors, as the interpreter names it.
    let names: Vec<String> = (0..f.record.len())
        .map(|j| f.record_field_name(j))
        .collect();
    let leaves: Vec<Leaf> = f
        .record
        .iter()
        .zip(&names)
        .map(|(g, n)| Leaf {
            name: n,
            doc: g.doc.clone(),
            wire: wire_type(g),
            bits: None,
            field: g,
            message: &m.name,
        })
        .collect();
    let mut decls = Vec::new();
    let mut reads = Vec::new();
    let mut built = Vec::new();
    let mut writes = Vec::new();
    let mut raws = Vec::new();
    let mut from_raw = Vec::new();
    let mut defaults = Vec::new();
    // A last field whose bytes another field gives reads and writes `last` bytes.
    let sized = f.record_bytes_from().is_some();
    for (j, (g, l)) in f.record.iter().zip(&leaves).enumerate() {
        let is_sized = sized && j + 1 == f.record.len();
        let (gn, v) = (ident(&g.name), local(&g.name));
        let t = ctx.rust_type(l);
        let d = doc(&leaf_doc(p, l));
        decls.push(quote!(#d pub #gn: #t));
        let wt = wire_type(g);
        let w = wt.ident();
        let name = l.name;
        // Decode: the wire integer, its range, the typed value.
        let read = if is_sized {
            let (at, le, signed) = (
                usize_lit(g.offset),
                g.byte_order == ByteOrder::Little,
                wt.signed,
            );
            quote!(rt::sized_int(frame.get(#at..#at + last).unwrap_or(&[]), #le, #signed) as #w)
        } else {
            read_wire(g, 0)
        };
        reads.push(quote!(let #v: #w = #read;));
        if let Some(range) = leaf_range(g, None, wt.limits()) {
            let at = match g.offset {
                0 => quote!(at),
                o => {
                    let o = usize_lit(o);
                    quote!(at + #o)
                }
            };
            let c = ctx.field_check(m, name, (g.offset, &at), Some(range), None);
            reads.push(quote!(rt::in_range(#c, #v)?;));
        }
        let typed = from_wire(ctx, l, Some(wt), quote!(#v));
        built.push(quote!(#gn: #typed));
        // Encode: its range, its wire integer in the field's bytes.
        writes.push(quote!(let #v = self.#gn;));
        if let Some((raw_t, raw)) = raw_of(ctx, l, &v) {
            if let Some(range) = leaf_range(g, None, raw_t.limits()) {
                let at = usize_lit(g.offset).to_token_stream();
                let c = ctx.field_check(m, name, (g.offset, &at), Some(range), None);
                writes.push(quote!(rt::encode_in_range(#c, #raw)?;));
            }
        }
        let value = paren(to_wire(ctx, l, &v, None));
        let (at, end) = (usize_lit(g.offset), usize_lit(g.offset + g.width));
        writes.push(if is_sized {
            let (le, signed) = (g.byte_order == ByteOrder::Little, wt.signed);
            quote!(rt::write_sized(#name, #value as i64, #signed, #le, out.get_mut(#at..#at + last).unwrap_or(&mut []))?;)
        } else if g.width == 1 && !wt.signed {
            quote!(out[#at] = #value;)
        } else if g.width == 3 {
            let le = g.byte_order == ByteOrder::Little;
            quote!(out[#at..#end].copy_from_slice(&rt::bytes24(#value as u32, #le));)
        } else {
            let conv = to_bytes(g.byte_order);
            quote!(out[#at..#end].copy_from_slice(&#value.#conv());)
        });
        // Its raw value, and from a raw value.
        let jl = usize_lit(j);
        let raw = match raw_of(ctx, l, &format_ident!("x")) {
            Some(_) => match ctx.kind(l) {
                Kind::Int(_) | Kind::Bool => quote!(self.#gn as i64),
                _ => quote!(self.#gn.raw() as i64),
            },
            None => quote!(0),
        };
        raws.push(quote!(#jl => #raw));
        let (lo, hi) = wt.limits();
        let (lo, hi) = (i64_lit(lo), i64_lit(hi));
        let get = quote!(rt::field_int(#name, rt::Some(rt::Int(list.get(k, #jl).unwrap_or(0))), #lo, #hi)?);
        let typed = from_wire(ctx, l, None, get);
        from_raw.push(quote!(#gn: #typed));
        let zero_t = raw_of(ctx, l, &v).map(|(t, _)| t);
        let zero = from_wire(ctx, l, zero_t, quote!(0));
        defaults.push(quote!(#gn: #zero));
    }
    let n = usize_lit(f.record.len());
    // Plain integers derive their zero; a unit, enum or flag set is made from raw 0.
    let plain = leaves.iter().all(|l| matches!(ctx.kind(l), Kind::Int(_)));
    let (derive_default, default_impl) = if plain {
        (quote!(, Default), quote!())
    } else {
        (
            quote!(),
            quote! {
                impl ::core::default::Default for #ty {
                    fn default() -> Self {
                        Self { #(#defaults,)* }
                    }
                }
            },
        )
    };
    let d = doc(&format!(
        "One record of `{}.{}` ({} bytes). {}",
        m.name, f.name, f.width, f.doc
    ));
    let read_doc = " Reads a record from its bytes, at frame offset `at` (for errors), each field's range checked as the spec says.";
    let (last_param, last_doc) = if sized {
        let d = " Its last field takes `last` bytes (the frame's width field says how many; the array holds a record at its widest).";
        (quote!(, last: usize), quote!(#[doc = #d]))
    } else {
        (quote!(), quote!())
    };
    quote! {
        #d
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash #derive_default)]
        #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
        #[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
        pub struct #ty {
            #(#decls,)*
        }
        impl #ty {
            /// Its bytes on the wire.
            pub const WIDTH: usize = #width;
            #[doc = #read_doc]
            #last_doc
            pub fn read(frame: &[u8; #width], at: usize #last_param) -> rt::DecodeResult<Self> {
                #(#reads)*
                rt::Ok(Self { #(#built,)* })
            }
            /// Writes the record into its bytes, each field's range checked as the spec says.
            #last_doc
            pub fn write(&self, out: &mut [u8; #width] #last_param) -> rt::Result<(), rt::EncodeError> {
                #(#writes)*
                rt::Ok(())
            }
        }
        #default_impl
        impl rt::Record for #ty {
            const FIELDS: usize = #n;
            fn raw(&self, field: usize) -> i64 {
                match field {
                    #(#raws,)*
                    _ => 0,
                }
            }
            fn from_raw(list: &rt::RecordList<'_>, k: usize) -> rt::Result<Self, rt::FieldError> {
                rt::Ok(Self { #(#from_raw,)* })
            }
        }
    }
}

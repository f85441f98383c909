use super::*;

/// An optional field `fi` (a plain number, the `k`th optional one), read from the frame laid
/// out as if every optional field were present (`rt::Optionals::split`) where it is present,
/// checked against its range there: its statement into `stmts`, its value's name and local.
fn decode_optional(
    ctx: &Ctx,
    m: &Message,
    ls: &[Leaf],
    fi: usize,
    k: usize,
    stmts: &mut Vec<TokenStream>,
) -> Option<(Ident, TokenStream)> {
    let (o, f) = (m.layout, &m.fields[fi]);
    let (name, n) = (&f.name, wire_local(&f.name));
    let read = read_wire(f, f.frame_at(&o) - f.offset + full_shift(m, fi));
    let wt = wire_type(f);
    let (w, k, v) = (wt.ident(), usize_lit(k), local(name));
    let mut inner = Vec::new();
    let wire = match leaf_range(f, None, wt.limits()) {
        Some(range) => {
            inner.push(quote!(let #n: #w = #read;));
            let c = ctx.field_check(
                m,
                name,
                (f.frame_at(&o), &quote!(s.at(#k))),
                Some(range),
                None,
            );
            inner.push(quote!(rt::in_range(#c, #n)?;));
            quote!(#n)
        }
        None => read,
    };
    if let Some(leaf) = ls.iter().find(|l| l.bits.is_none() && l.name == f.name) {
        let value = from_wire(ctx, leaf, Some(wt), wire);
        stmts.push(quote! {
            let #v = if s.has(#k) {
                #(#inner)*
                rt::Some(#value)
            } else {
                rt::None
            };
        });
        return Some((ident(name), quote!(#v)));
    }
    None
}

/// A list of packed elements (`packed`) at `at`: its padding bits checked 0, its elements
/// unpacked (or read whole, of other types) and checked within the field's range; its local.
fn decode_packed(
    ctx: &Ctx,
    m: &Message,
    f: &Field,
    pk: &Packed,
    at: &TokenStream,
    stmts: &mut Vec<TokenStream>,
) -> TokenStream {
    let (o, name) = (m.layout, &f.name);
    let read_at = usize_lit(f.frame_at(&o));
    let e = wire_type(f).ident();
    let (count, bits, lsb) = (
        usize_lit(pk.count),
        usize_lit(pk.bits as usize),
        pk.lsb_first,
    );
    let end = usize_lit(f.frame_at(&o) + f.width);
    let last = usize_lit(f.width - 1);
    let v = local(name);
    let bytes = quote!(&frame[#read_at..#end]);
    let fd = ctx.field_desc(m, name);
    stmts.push(
        quote!(rt::equal(#fd, #at + #last, rt::packed_padding(#bytes, #count, #bits, #lsb), 0)?;),
    );
    // Elements typed by their enum or unit where they have one.
    let e = match ctx.element_type(f) {
        Some(t) => quote!(#t),
        None => quote!(#e),
    };
    if fixed_elements(f) {
        // A list of a fixed count of other elements than unsigned ones of 1, 2 or 4
        // bytes: each whole, in its byte and word order.
        let width = usize_lit(pk.elem_width);
        let (le, swapped, signed) = (f.byte_order == ByteOrder::Little, f.word_swapped, f.signed);
        stmts.push(quote!(let #v = rt::fixed_elements::<#e, #count>(#bytes, #width, #le, #swapped, #signed);));
    } else {
        stmts.push(quote!(let #v = rt::unpack::<#e, #count>(#bytes, #bits, #lsb);));
    }
    if let Some((lo, hi)) = f.range {
        let (lo, hi) = (i64_lit(lo), i64_lit(hi));
        let fd = ctx.field_desc(m, name);
        stmts.push(quote!(rt::packed_in_range(#fd, #at, #bits, #v.as_slice(), #lo, #hi)?;));
    }
    quote!(#v)
}

/// The sub-fields (`bits`) of field `f`, whose wire value is `wire`, at `at`: each shifted
/// and masked out (sign-extended where signed), a constant one checked, the others checked
/// within their range; their values.
fn decode_bits(
    ctx: &Ctx,
    m: &Message,
    ls: &[Leaf],
    f: &Field,
    wire: &TokenStream,
    at: &TokenStream,
    stmts: &mut Vec<TokenStream>,
) -> Vec<(Ident, TokenStream)> {
    let wt = wire_type(f);
    let unsigned = IntType {
        bits: wt.bits,
        signed: false,
        float: false,
    };
    let mut values = Vec::new();
    let ut = unsigned.ident();
    // The wire value as unsigned bits.
    let bits = if wt.signed {
        quote!(#wire as #ut)
    } else {
        wire.clone()
    };
    for b in &f.bits {
        let lsb = u32::from(b.lsb);
        let width = u32::from(b.width());
        let mask = hex_lit((1u64 << width) - 1);
        let bt = bits_type(b);
        let btid = bt.ident();
        let shifted = if lsb == 0 {
            bits.clone()
        } else {
            let (lsb, bits) = (Literal::u32_unsuffixed(lsb), paren(bits.clone()));
            quote!(#bits >> #lsb)
        };
        let field = if lsb + width >= wt.rust_bits() {
            shifted
        } else {
            let shifted = paren(shifted);
            quote!(#shifted & #mask)
        };
        let field_p = paren(field.clone());
        let extract = if b.signed {
            let shift = Literal::u32_unsuffixed(bt.bits - width);
            let ubt = IntType {
                bits: bt.bits,
                signed: false,
                float: false,
            }
            .ident();
            quote!(((#field_p as #ubt) << #shift) as #btid >> #shift)
        } else {
            quote!(#field_p as #btid)
        };
        let bname = &b.name;
        match b.constant {
            Some(c) => {
                let l = hex_lit(c);
                let fd = ctx.field_desc(m, bname);
                stmts.push(quote!(rt::equal(#fd, #at, #field, #l)?;));
            }
            None => {
                let limits = raw_limits(u32::from(b.width()), b.signed);
                if let Some(range) = leaf_range(f, Some(b), limits) {
                    let c =
                        ctx.field_check(m, bname, (f.frame_at(&m.layout), at), Some(range), None);
                    stmts.push(quote!(rt::in_range(#c, #extract)?;));
                }
                if let Some(leaf) = ls.iter().find(|l| l.name == b.name) {
                    let value = match ctx.kind(leaf) {
                        Kind::Bool => quote!(#field_p != 0),
                        _ => from_wire(ctx, leaf, Some(bt), extract),
                    };
                    values.push((ident(&b.name), value));
                }
            }
        }
    }
    values
}

/// Decoding one message from `frame`, a fixed-size array of exactly its length whose checksum
/// is verified: the statements that check its constants, repeated fields, ranges and
/// broadcast rule, and the expression building it.
pub(super) fn decode_body(ctx: &Ctx, m: &Message) -> (Vec<TokenStream>, TokenStream) {
    let p = ctx.p;
    let ls = leaves(m);
    let ls = ls.as_slice();
    let o = m.layout;
    let v = variant(m);
    let mut stmts = Vec::new();
    if let (Some(_), Some(at)) = (refuses_broadcast(p, m), o.address) {
        let desc = if ctx.own.get() {
            quote!(&Self::DESC)
        } else {
            message_desc(m)
        };
        let at = usize_lit(at);
        stmts.push(quote!(FRAME.no_broadcast(frame[#at], #desc)?;));
    }
    let named = repeated(m);
    // Each leaf's value: an expression over `frame` or over a named wire value.
    let mut values: Vec<(Ident, TokenStream)> = Vec::new();
    // Each field's wire value: its read from `frame`, or the name it is bound to.
    let mut wires: Vec<TokenStream> = Vec::new();
    for (fi, f) in m.fields.iter().enumerate() {
        let n = wire_local(&f.name);
        let read_at = usize_lit(f.frame_at(&o));
        // Where the field sits in this frame, as errors say it: after `j` lists, further by
        // their bytes (`s`, the frame taken apart by `rt::Lists`).
        let j = m.fields[..fi].iter().filter(|g| g.repeat.is_some()).count();
        let at = if has_lists(m) && j > 0 {
            let j = usize_lit(j);
            quote!(#read_at + s.shift(#j))
        } else {
            quote!(#read_at)
        };
        let name = &f.name;
        if let (Some(_), Some(k)) = (&f.present, optional_index(m, fi)) {
            // An optional field (a plain number): where it is present.
            values.extend(decode_optional(ctx, m, ls, fi, k, &mut stmts));
            wires.push(quote!());
            continue;
        }
        if let Some(pk) = &f.packed {
            // Packed elements: the padding bits 0, then each element within its range.
            values.push((ident(name), decode_packed(ctx, m, f, pk, &at, &mut stmts)));
            wires.push(quote!());
            continue;
        }
        if let Some(leaf) = ls.iter().find(|l| l.bits.is_none() && l.name == f.name) {
            if let Some(value) = decode_repeat(ctx, m, leaf, &mut stmts) {
                values.push((ident(name), value));
                wires.push(quote!());
                continue;
            }
        }
        if f.is_ascii() {
            let end = usize_lit(f.frame_at(&o) + f.width);
            let width = usize_lit(f.width);
            values.push((
                ident(name),
                quote!(rt::Ascii(frame[#read_at..#end].try_into().unwrap_or([0; #width]))),
            ));
            wires.push(quote!());
            continue;
        }
        let read = read_wire(f, f.frame_at(&o) - f.offset);
        let wt = wire_type(f);
        let w = wt.ident();
        let unsigned = IntType {
            bits: wt.bits,
            signed: false,
            float: false,
        };
        let range = match leaf_range(f, None, wt.limits()) {
            Some(range) if f.bits.is_empty() => Some(range),
            _ => None,
        };
        // A field read more than once is read into a local (a one-byte read is as short as
        // its name).
        let uses = usize::from(f.constant.is_some())
            + usize::from(f.equals.is_some() || f.follows.is_some())
            + usize::from(range.is_some())
            + usize::from(named.contains(&fi))
            + f.bits
                .iter()
                .map(|b| 1 + usize::from(b.constant.is_none() && b.range.is_some()))
                .sum::<usize>()
            + usize::from(
                f.bits.is_empty()
                    && f.constant.is_none()
                    && f.equals.is_none()
                    && follows_field(f).is_none()
                    && m.counted_by(fi).is_none(),
            );
        let wire = if f.bcd {
            // Its digits checked, the decimal number they give (what every check below reads).
            let fd = ctx.field_desc(m, name);
            stmts.push(quote!(let #n: #w = rt::bcd(#fd, #at, #read as u64)? as #w;));
            quote!(#n)
        } else if f.width > 1 && uses > 1 {
            stmts.push(quote!(let #n: #w = #read;));
            quote!(#n)
        } else {
            read
        };
        wires.push(wire.clone());
        if let Some(c) = f.constant {
            // A constant is its wire bits: a signed field's value is compared unsigned.
            let l = hex_lit(c);
            let ut = unsigned.ident();
            let bits = match (wt.signed, wt.bits) {
                (false, _) => wire.clone(),
                (true, 24) => quote!(#wire as u32 & 0xFF_FFFF),
                (true, _) => quote!(#wire as #ut),
            };
            let fd = ctx.field_desc(m, name);
            stmts.push(quote!(rt::equal(#fd, #at, #bits, #l)?;));
        }
        if let Some(other) = f.equals {
            let on = wires.get(other).cloned().unwrap_or_default();
            let other_name = m.fields.get(other).map_or("", |o| o.name.as_str());
            let fd = ctx.field_desc(m, name);
            stmts.push(quote!(rt::same(#fd, #at, #wire, #other_name, #on)?;));
        }
        if let Some((other, rel)) = follows_field(f) {
            let on = wires.get(other).cloned().unwrap_or_default();
            let args = relation_args(rel);
            let rule = rel.describe(&rel.field);
            let rel = quote!(.follows(#args, #rule));
            let c = ctx.field_check(m, name, (f.frame_at(&o), &at), range.clone(), Some(rel));
            stmts.push(quote!(rt::following(#c, #wire, #on as i64)?;));
        }
        if let Some(range) = range {
            let c = ctx.field_check(m, name, (f.frame_at(&o), &at), Some(range), None);
            stmts.push(quote!(rt::in_range(#c, #wire)?;));
        }
        if f.bits.is_empty() {
            if f.constant.is_none() && f.equals.is_none() && follows_field(f).is_none() {
                if let Some(leaf) = ls.iter().find(|l| l.bits.is_none() && l.name == f.name) {
                    values.push((ident(&f.name), from_wire(ctx, leaf, Some(wt), wire)));
                }
            }
            continue;
        }
        values.extend(decode_bits(ctx, m, ls, f, &wire, &at, &mut stmts));
    }
    let fields = values.iter().map(|(n, v)| quote!(#n: #v));
    let dm = direction_module(m.direction);
    if ctx.own.get() {
        let build = if ls.is_empty() {
            quote!(Self)
        } else {
            quote!(Self { #(#fields),* })
        };
        return (stmts, build);
    }
    let build = match (ls.is_empty(), ctx.view.get()) {
        (true, true) => quote!(Self::#v),
        (true, false) => quote!(Self::#v(#dm::#v)),
        (false, true) => quote!(Self::#v { #(#fields),* }),
        (false, false) => quote!(Self::#v(#dm::#v { #(#fields),* })),
    };
    (stmts, build)
}

use super::*;

/// The name of the `rt::RepeatAt` constant of a message with a repeated field.
pub(super) fn repeat_const(m: &Message) -> Ident {
    format_ident!("REPEAT_{}", m.name.to_ascii_uppercase())
}

/// The shortest and longest frames of `m`.
pub(super) fn len_range(m: &Message) -> (usize, usize) {
    (m.min_len(), m.max_len)
}

/// The name of the `rt::Lists` constant of a message with several repeated fields, or fields
/// after one.
pub(super) fn lists_const(m: &Message) -> Ident {
    format_ident!("LISTS_{}", m.name.to_ascii_uppercase())
}

/// Whether `m`'s fields do not all keep a fixed offset, or it has text up to a terminator
/// (whose bytes are its characters and the terminator): it is decoded through `rt::Lists`.
pub(super) fn has_lists(m: &Message) -> bool {
    !m.tail_repeat() || m.fields.iter().any(|f| f.terminator().is_some())
}

/// The `rt::RepeatAt` of repeated field `f` of `m`: its offset (and its count field's) with
/// every earlier list empty, how it is counted and its bounds.
pub(super) fn repeat_at(
    ctx: &Ctx,
    m: &Message,
    f: &Field,
    r: &busspec_model::ir::Repeat,
) -> TokenStream {
    let fd = ctx.field_desc(m, &f.name);
    let base = usize_lit(m.layout.len);
    let at = usize_lit(m.layout.payload + f.offset);
    let width = usize_lit(if f.ty == FieldType::Bit { 0 } else { f.width });
    let (le, signed) = (f.byte_order == ByteOrder::Little, f.signed);
    let counter = |i: usize| {
        let cf = &m.fields[i];
        let (cn, cat, cw) = (
            &cf.name,
            usize_lit(m.layout.payload + cf.offset),
            usize_lit(cf.width),
        );
        let le = cf.byte_order == ByteOrder::Little;
        quote!(rt::CountField { name: #cn, at: #cat, width: #cw, le: #le })
    };
    let count = match r.count {
        Count::ToEnd if sized_record(m, f).is_some() => {
            let (wf, fixed, most) = sized_record(m, f).unwrap_or((f, 0, 1));
            let i = m
                .fields
                .iter()
                .position(|g| std::ptr::eq(g, wf))
                .unwrap_or(0);
            let (c, fixed, most) = (counter(i), usize_lit(fixed), usize_lit(most));
            quote!(rt::CountBy::EndSized(rt::SizedBy { field: #c, fixed: #fixed, most: #most }))
        }
        Count::ToEnd if m.delimited_list(&ctx.p.framing).is_some() => {
            // End bytes alone delimit the frame: the list ends at their first appearance.
            let end = ctx.p.framing.end.iter().map(|b| hex_u8(*b));
            quote!(rt::CountBy::Delimited(&[#(#end),*]))
        }
        Count::ToEnd => quote!(rt::CountBy::End),
        Count::Until(t) => {
            let t = Literal::u8_unsuffixed(t);
            quote!(rt::CountBy::Until(#t))
        }
        Count::Elements(i) => {
            let c = counter(i);
            quote!(rt::CountBy::Elements(#c))
        }
        Count::Bytes(i) => {
            let c = counter(i);
            quote!(rt::CountBy::Bytes(#c))
        }
        Count::Fixed(n) => {
            let n = usize_lit(n);
            quote!(rt::CountBy::Fixed(#n))
        }
    };
    let (min, max) = (usize_lit(r.min), usize_lit(r.max));
    quote! {
        rt::RepeatAt {
            field: #fd,
            base: #base,
            at: #at,
            width: #width,
            le: #le,
            signed: #signed,
            count: #count,
            min: #min,
            max: #max,
        }
    }
}

/// The `rt::RepeatAt` constant of each message of direction `d` with a repeated field (its
/// first): where it sits, how it is counted and its bounds, for decode, encode and the
/// stream's framing; and the `rt::Lists` constant of each message with several lists or
/// fields after one.
pub(super) fn emit_repeats(ctx: &Ctx, d: Direction) -> TokenStream {
    let p = ctx.p;
    let mut out = TokenStream::new();
    for m in p.messages(d) {
        if m.has_optional() {
            let (c, value) = (optional_const(m), optionals_value(m));
            let names: Vec<String> = m
                .optionals()
                .map(|(_, f, c)| format!("`{}` when {}", f.name, condition_text(m, c)))
                .collect();
            let d = format!(
                " The optional fields of `{}`, each on the wire only where its condition holds: {}.",
                m.name,
                names.join(", ")
            );
            out.extend(quote! {
                #[doc = #d]
                pub const #c: rt::Optionals = #value;
            });
        }
        let Some((f, r)) = m.repeat() else { continue };
        let c = repeat_const(m);
        let value = repeat_at(ctx, m, f, r);
        let d = format!(
            " Where `{}.{}` sits in the frame and how its elements are counted.",
            m.name, f.name
        );
        out.extend(quote! {
            #[doc = #d]
            pub const #c: rt::RepeatAt = #value;
        });
        if has_lists(m) {
            let c = lists_const(m);
            let base = usize_lit(m.layout.len);
            let lists = m.repeats().map(|(_, f, r)| repeat_at(ctx, m, f, r));
            let d = format!(
                " Every repeated field of `{}`, in wire order, each where it sits with every earlier list empty.",
                m.name
            );
            out.extend(quote! {
                #[doc = #d]
                pub const #c: rt::Lists = rt::Lists { base: #base, lists: &[#(#lists),*] };
            });
        }
    }
    out
}

/// The name of the `rt::Optionals` constant of a message with optional fields.
pub(super) fn optional_const(m: &Message) -> Ident {
    format_ident!("OPTIONAL_{}", m.name.to_ascii_uppercase())
}

/// How much further than its `offset` field `fi` of `m` sits in the layout where every
/// optional field is present (the array `rt::Optionals` decodes into and encodes from): the
/// widths of the optional fields before it.
pub(super) fn full_shift(m: &Message, fi: usize) -> usize {
    m.fields[..fi.min(m.fields.len())]
        .iter()
        .filter(|g| g.present.is_some())
        .map(|g| g.width)
        .sum()
}

/// The index among `m`'s optional fields of field `fi`, if it is one.
pub(super) fn optional_index(m: &Message, fi: usize) -> Option<usize> {
    m.optionals().position(|(i, _, _)| i == fi)
}

/// The condition of optional field `fi` of `m` in words, as the interpreter's refusal says it
/// (``bit 0 of `status` is set``).
pub(super) fn condition_text(m: &Message, c: &Presence) -> String {
    c.describe(m.fields.get(c.field).map_or("", |g| g.name.as_str()))
}

/// The `rt::Optionals` constant of `m`: where its optional fields sit, what each condition
/// reads, and every length a frame can have.
pub(super) fn optionals_value(m: &Message) -> TokenStream {
    let (message, base) = (&m.name, usize_lit(m.layout.len));
    let first = m.optionals().next().map_or(0, |(_, f, _)| f.offset);
    let at = usize_lit(m.layout.payload + first);
    let fields = m.optionals().map(|(_, f, c)| {
        let (name, width) = (&f.name, usize_lit(f.width));
        let g = &m.fields[c.field];
        let (cn, cat, cw) = (
            &g.name,
            usize_lit(m.layout.payload + g.offset),
            usize_lit(g.width),
        );
        let le = g.byte_order == ByteOrder::Little;
        let when = match c.when {
            PresentWhen::Bit(b) => {
                let b = Literal::u32_unsuffixed(b);
                quote!(rt::When::Bit(#b))
            }
            PresentWhen::Equals(v) => {
                let v = Literal::u64_unsuffixed(v as u64);
                quote!(rt::When::Equals(#v))
            }
        };
        quote! {
            rt::OptionalAt {
                name: #name,
                width: #width,
                on: rt::CountField { name: #cn, at: #cat, width: #cw, le: #le },
                when: #when,
            }
        }
    });
    let mut lengths = vec![m.layout.len];
    for (_, f, _) in m.optionals() {
        let more: Vec<usize> = lengths.iter().map(|l| l + f.width).collect();
        lengths.extend(more);
    }
    lengths.sort_unstable();
    lengths.dedup();
    // The message as a wrong length names it, once for each length: naming that length.
    let (code, code_len) = code_args(m);
    let by_length = lengths.iter().map(|&l| {
        let l = usize_lit(l);
        quote!(rt::MessageDesc::new(#message, #code, #code_len, &[#l]))
    });
    let lengths = lengths.iter().map(|&l| usize_lit(l));
    quote! {
        rt::Optionals {
            by_length: &[#(#by_length),*],
            base: #base,
            at: #at,
            fields: &[#(#fields),*],
            lengths: &[#(#lengths),*],
        }
    }
}

/// Indices of the fields another field repeats (`equals`): their wire value gets a name.
pub(super) fn repeated(m: &Message) -> Vec<usize> {
    m.fields
        .iter()
        .filter_map(|f| f.equals.or(follows_field(f).map(|(i, _)| i)))
        .collect()
}

/// A repeated record whose last field's bytes an earlier field gives (`bytes:`): that field,
/// the bytes of the record's other fields, and the most its last field takes.
pub(super) fn sized_record<'m>(m: &'m Message, f: &Field) -> Option<(&'m Field, usize, usize)> {
    let wi = f.record_bytes_from()?;
    let g = f.record.last()?;
    Some((m.fields.get(wi)?, f.width - g.width, g.width))
}

/// The local holding the bytes of the last field of each record of a message whose records'
/// width a field gives (set by encode before the records are written).
pub(super) fn sized_local() -> Ident {
    format_ident!("last_width")
}

/// The statement writing repeated field `f`'s elements (the local `v`) into `out` from `at`,
/// through its `rt::RepeatAt` `c` (its width and byte order).
pub(super) fn write_list(f: &Field, c: &TokenStream, v: &Ident, at: TokenStream) -> TokenStream {
    if f.is_record() && f.record_bytes_from().is_some() {
        // Each record into an array of its widest, then as many bytes as it takes here.
        let (w, last) = (usize_lit(f.width), sized_local());
        let fixed = usize_lit(f.width - f.record.last().map_or(0, |g| g.width));
        return quote! {
            let rec_width = #fixed + #last;
            for (k, r) in #v.iter().enumerate() {
                let mut bytes = [0u8; #w];
                r.write(&mut bytes, #last)?;
                let at = #at + k * rec_width;
                if let (rt::Some(to), rt::Some(from)) = (out.get_mut(at..at + rec_width), bytes.get(..rec_width)) {
                    to.copy_from_slice(from);
                }
            }
        };
    }
    if f.is_record() {
        // Each record into an array of its width, then into the frame.
        let w = usize_lit(f.width);
        return quote! {
            for (k, r) in #v.iter().enumerate() {
                let mut bytes = [0u8; #w];
                r.write(&mut bytes)?;
                let at = #at + k * #w;
                if let rt::Some(to) = out.get_mut(at..at + #w) {
                    to.copy_from_slice(&bytes);
                }
            }
        };
    }
    if f.ty == FieldType::Bit {
        quote!(rt::write_bits(&#v, &mut out[#at..]);)
    } else if let Some(t) = f.terminator() {
        // The characters, then their terminator.
        let t = Literal::u8_unsuffixed(t);
        quote! {{
            let at = #at;
            if let rt::Some(to) = out.get_mut(at..at + #v.len()) {
                to.copy_from_slice(#v.as_slice());
            }
            if let rt::Some(b) = out.get_mut(at + #v.len()) {
                *b = #t;
            }
        }}
    } else if words_swapped(f) {
        quote!(#c.write_words(#v.as_slice(), &mut out[#at..]);)
    } else {
        quote!(#c.write(#v.as_slice(), &mut out[#at..]);)
    }
}

/// Whether repeated field `f`'s elements are 32- or 64-bit numbers whose 16-bit words travel
/// swapped (`word_order: swapped`): read by `rt::RepeatAt::words`, written by `rt::write_words`.
fn words_swapped(f: &Field) -> bool {
    f.word_swapped && matches!(f.width, 4 | 8) && !f.is_record()
}

/// The value of repeated field `l` of `m` (`None` if it is not one), read from the bytes of
/// its elements (`elements`, from the frame's `split`), with the check of its range pushed on
/// `stmts`.
pub(super) fn decode_repeat(
    ctx: &Ctx,
    m: &Message,
    l: &Leaf,
    stmts: &mut Vec<TokenStream>,
) -> Option<TokenStream> {
    let f = l.field;
    f.repeat.as_ref()?;
    // With several lists (`rt::Lists`), each as the frame places it, from the split `s`.
    let (c, elements, count) = match m.repeats().position(|(_, g, _)| std::ptr::eq(g, f)) {
        Some(k) if has_lists(m) => {
            let k = usize_lit(k);
            (quote!(s.lists[#k]), quote!(s.elements(#k)), quote!(s.n[#k]))
        }
        _ => {
            let c = repeat_const(m);
            (quote!(#c), quote!(elements), quote!(count))
        }
    };
    let value = match ctx.kind(l) {
        Kind::Records { ty, max } if f.record_bytes_from().is_some() => {
            // Each record as wide as the frame's width field says, read from an array of its
            // widest.
            let (w, max, v) = (usize_lit(f.width), usize_lit(max), local(&f.name));
            let fixed = usize_lit(f.width - f.record.last().map_or(0, |g| g.width));
            let base = usize_lit(m.layout.payload + f.offset);
            stmts.push(quote! {
                let rec_width = #c.element_width(frame);
                let mut #v = rt::Repeated::<#ty, #max>::new();
                for (k, chunk) in #elements.chunks_exact(rec_width).enumerate() {
                    let mut bytes = [0u8; #w];
                    if let rt::Some(to) = bytes.get_mut(..rec_width) {
                        to.copy_from_slice(chunk);
                    }
                    let _ = #v.push(#ty::read(&bytes, #base + k * rec_width, rec_width - #fixed)?);
                }
            });
            let _ = count;
            return Some(quote!(#v));
        }
        Kind::Records { ty, max } => {
            // Each record read from an array of its width, at its offset in the frame.
            let (w, max, v) = (usize_lit(f.width), usize_lit(max), local(&f.name));
            let base = usize_lit(m.layout.payload + f.offset);
            let j = m
                .fields
                .iter()
                .take_while(|g| !std::ptr::eq(*g, f))
                .filter(|g| g.repeat.is_some())
                .count();
            let at = if has_lists(m) && j > 0 {
                let j = usize_lit(j);
                quote!(#base + s.shift(#j))
            } else {
                quote!(#base)
            };
            stmts.push(quote! {
                let mut #v = rt::Repeated::<#ty, #max>::new();
                for (k, bytes) in #elements.chunks_exact(#w).enumerate() {
                    let bytes = <[u8; #w]>::try_from(bytes).unwrap_or([0; #w]);
                    let _ = #v.push(#ty::read(&bytes, #at + k * #w)?);
                }
            });
            let _ = (c, count);
            return Some(quote!(#v));
        }
        Kind::List {
            elem, max, typed, ..
        } => {
            let (e, max) = (typed.unwrap_or_else(|| elem.ident()), usize_lit(max));
            // 32- and 64-bit elements whose 16-bit words travel swapped (`word_order`).
            let swapped = words_swapped(f);
            match (ctx.view.get(), swapped) {
                (true, false) => quote!(#c.view::<#e, #max>(#elements)?),
                (true, true) => quote!(#c.view_words::<#e, #max>(#elements)?),
                (false, false) => quote!(#c.elements::<#e, #max>(#elements)?),
                (false, true) => quote!(#c.words::<#e, #max>(#elements)?),
            }
        }
        Kind::BitList { bytes } => {
            let bytes = usize_lit(bytes);
            if ctx.view.get() {
                quote!(#c.view_bits::<#bytes>(#elements, #count)?)
            } else {
                quote!(#c.bits::<#bytes>(#elements, #count)?)
            }
        }
        _ => return None,
    };
    let Some((lo, hi)) = f.range.filter(|_| f.ty != FieldType::Bit) else {
        return Some(value);
    };
    let (v, lo, hi) = (local(&f.name), i64_lit(lo), i64_lit(hi));
    stmts.push(quote!(let #v = #value;));
    if ctx.view.get() {
        stmts.push(quote!(#c.view_in_range(&#v, #lo, #hi)?;));
    } else {
        stmts.push(quote!(#c.in_range(#v.as_slice(), #lo, #hi)?;));
    }
    Some(quote!(#v))
}

/// The statement splitting a frame of variable-length message `m` into its fixed part (as
/// the array `frame`, so every fixed field's read is in bounds by type), the bytes of its
/// elements and their number, once their count is checked.
pub(super) fn split_frame(m: &Message, stmts: &[TokenStream], build: &TokenStream) -> TokenStream {
    if m.has_optional() {
        // Optional fields: the frame laid out as if every one were present.
        let (c, max) = (optional_const(m), usize_lit(m.max_len));
        return quote!(let s = #c.split::<#max>(frame)?; let frame = &s.frame;);
    }
    if has_lists(m) {
        let (c, (base, k)) = (lists_const(m), lists_dims(m));
        return quote!(let s = #c.split::<#base, #k>(frame)?; let frame = &s.frame;);
    }
    let Some((f, _)) = m.repeat() else {
        return quote!();
    };
    let (c, at) = (repeat_const(m), usize_lit(m.layout.payload + f.offset));
    let frame = if stmts.iter().chain([build]).any(mentions_frame) {
        quote!(frame)
    } else {
        quote!(_)
    };
    let count = if f.ty == FieldType::Bit {
        quote!(count)
    } else {
        quote!(_)
    };
    quote!(let (#frame, elements, #count) = #c.split::<#at>(frame)?;)
}

/// The parameters a variable-length message's decoder takes from `rt::Group::attempt_split`
/// (its fixed part as an array, the elements' bytes, their number), `_` where unused.
pub(super) fn split_params(
    ctx: &Ctx,
    m: &Message,
    stmts: &[TokenStream],
    build: &TokenStream,
) -> TokenStream {
    // A view lends the elements: they live as long as the frame (`'a`).
    let view = ctx.view.get();
    if has_lists(m) {
        let (base, k) = lists_dims(m);
        if view {
            return quote!(s: &rt::Split<'a, #base, #k>);
        }
        return quote!(s: &rt::Split<'_, #base, #k>);
    }
    let at = m.repeat().map_or(0, |(f, _)| m.layout.payload + f.offset);
    let at = usize_lit(at);
    let frame = if stmts.iter().chain([build]).any(mentions_frame) {
        quote!(frame)
    } else {
        quote!(_)
    };
    let count = if m.repeat().is_some_and(|(f, _)| f.ty == FieldType::Bit) {
        quote!(count)
    } else {
        quote!(_)
    };
    if view {
        return quote!(#frame: &'a [u8; #at], elements: &'a [u8], #count: usize);
    }
    quote!(#frame: &[u8; #at], elements: &[u8], #count: usize)
}

/// The const parameters of `rt::Lists::split` for `m`: its frame's length with every list
/// empty, and its number of lists.
pub(super) fn lists_dims(m: &Message) -> (Literal, Literal) {
    (usize_lit(m.layout.len), usize_lit(m.repeats().count()))
}

/// What a decoder taking a frame split by `rt::Lists` (`s`) starts with: its fixed fields as
/// the array `frame`.
pub(super) fn lists_prelude(m: &Message) -> TokenStream {
    if has_lists(m) {
        quote!(let frame = &s.frame;)
    } else {
        quote!()
    }
}

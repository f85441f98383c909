use super::*;

/// The broadcast address, if `m` is a request for a command that does not accept it: encode and
/// decode refuse that address for it.
pub(super) fn refuses_broadcast(p: &Protocol, m: &Message) -> Option<u8> {
    let b = p.framing.address.broadcast?;
    let accepted = m.broadcast.as_ref().is_some_and(|x| x.accepted);
    (m.direction == Direction::Request && !accepted).then_some(b)
}

/// The field of the same frame `f` follows, and how (`follows: {field}`): encode computes `f`,
/// decode checks it, and it is not part of the typed message.
pub(super) fn follows_field(f: &Field) -> Option<(usize, &Relation)> {
    match &f.follows {
        Some(Follows::Field(i, rel)) => Some((*i, rel)),
        _ => None,
    }
}

/// `multiply, divide` of a relation, as the runtime's `follows` takes them.
pub(super) fn relation_args(rel: &Relation) -> TokenStream {
    let (m, d) = (
        Literal::u64_unsuffixed(rel.multiply),
        Literal::u64_unsuffixed(rel.divide),
    );
    quote!(#m, #d)
}

/// One arm of `encode`'s match; `taken`: the frame was taken from the buffer before the match
/// (as `out`), the arm writes its known bytes into it.
/// A message with fields is written by its struct's own `write` (`write_arm`), which names its
/// constants as `Self::`.
pub(super) fn emit_encode_arm(
    ctx: &Ctx,
    m: &Message,
    pattern: &TokenStream,
    ls: &[Leaf],
    taken: bool,
) -> TokenStream {
    ctx.own.set(!ls.is_empty() && !m.unchecked);
    let arm = encode_arm(ctx, m, pattern, ls, taken);
    ctx.own.set(false);
    arm
}

fn encode_arm(
    ctx: &Ctx,
    m: &Message,
    pattern: &TokenStream,
    ls: &[Leaf],
    taken: bool,
) -> TokenStream {
    let p = ctx.p;
    let len = usize_lit(p.frame_len(m));
    let o = m.layout;
    let mut stmts = Vec::new();
    if refuses_broadcast(p, m).is_some() {
        let desc = if ctx.own.get() {
            quote!(&Self::DESC)
        } else {
            message_desc(m)
        };
        stmts.push(quote!(FRAME.encode_broadcast(address, #desc)?;));
    }
    let repeat = m
        .repeat()
        .filter(|_| !has_lists(m))
        .map(|(f, _)| (f, repeat_const(m), local(&f.name)));
    // Several lists, or fields after one: the fixed fields are written at their offsets with
    // every list empty (`compact`), then spread around the lists (`rt::Lists::expand`).
    let lc = lists_const(m);
    let lists: Vec<(usize, usize, &Field, Ident)> = if has_lists(m) {
        m.repeats()
            .enumerate()
            .map(|(k, (fi, f, _))| (k, fi, f, local(&f.name)))
            .collect()
    } else {
        Vec::new()
    };
    let list_bytes: Vec<Ident> = lists
        .iter()
        .map(|(k, ..)| format_ident!("bytes_{}", k))
        .collect();
    // The lists first, as the interpreter checks them: each its terminator, count, elements.
    for ((k, _, f, v), b) in lists.iter().zip(&list_bytes) {
        let k = usize_lit(*k);
        if f.terminator().is_some() {
            stmts.push(quote!(#lc.lists[#k].encode_until(#v.as_slice())?;));
        }
        stmts.push(quote!(let #b: usize = #lc.lists[#k].encode_len(#v.len())? - #lc.base;));
        if let Some((lo, hi)) = element_range(ctx, f) {
            let (lo, hi) = (i64_lit(lo), i64_lit(hi));
            stmts.push(quote!(#lc.lists[#k].encode_in_range(#v.as_slice(), #lo, #hi)?;));
        }
    }
    // The list (its index among the lists, its value) whose count field is field `fi`.
    let list_counted = |fi: usize| {
        let (li, _, _) = m.counted_by(fi)?;
        lists
            .iter()
            .find(|(_, lfi, ..)| *lfi == li)
            .map(|(k, _, _, v)| (usize_lit(*k), v.clone()))
    };
    if let Some((f, c, v)) = &repeat {
        // The count within its bounds, which gives the frame's length, then each element
        // within its range.
        match sized_record(m, f).and_then(|(wf, ..)| {
            let l = ls
                .iter()
                .find(|l| std::ptr::eq(l.field, wf) && l.bits.is_none())?;
            raw_of(ctx, l, &local(l.name))
        }) {
            Some((_, raw)) => {
                // The records' last field as wide as its width field says (1..=its most).
                let last = sized_local();
                stmts.push(quote!(let frame_len = #c.encode_len_sized(#v.len(), (#raw) as u64)?;));
                stmts.push(quote!(let #last = (#raw) as usize;));
            }
            None => stmts.push(quote!(let frame_len = #c.encode_len(#v.len())?;)),
        }
        if let Some((lo, hi)) = element_range(ctx, f) {
            let (lo, hi) = (i64_lit(lo), i64_lit(hi));
            stmts.push(quote!(#c.encode_in_range(#v.as_slice(), #lo, #hi)?;));
        }
    }
    // The bytes known without a field value (start byte, address, code, constant fields), one
    // write per contiguous run. A field an optional field's condition reads gets a name too.
    let mut named = repeated(m);
    named.extend(m.optionals().map(|(_, _, c)| c.field));
    let (known, consts) = known_bytes(p, m, &named);
    // The run from the first byte is written as the frame is taken from `buf`.
    let first: Vec<TokenStream> = known.iter().map_while(Clone::clone).collect();
    let i = first.len();
    // Its sum, for a sum-8 sealed in the arm: the generator adds the constants.
    let k = consts[..i].iter().fold(0u8, |a, b| a.wrapping_add(*b));
    let head = (i, o.address.is_some_and(|a| a < i).then_some(k));
    let take = if taken {
        quote!(rt::head(out, &[#(#first),*]))
    } else if m.has_optional() {
        // Optional fields: the frame laid out as if every one were present, packed into the
        // buffer once written (`rt::Optionals::pack`).
        let (full, n) = (usize_lit(m.max_len), usize_lit(first.len()));
        stmts.push(quote!(let mut compact = [0u8; #full];));
        quote!({ compact[..#n].copy_from_slice(&[#(#first),*]); &mut compact })
    } else if !lists.is_empty() {
        let (base, n) = (usize_lit(m.layout.len), usize_lit(first.len()));
        stmts.push(quote!(let mut compact = [0u8; #base];));
        quote!({ compact[..#n].copy_from_slice(&[#(#first),*]); &mut compact })
    } else if repeat.is_some() {
        quote!(rt::frame_mut_len(buf, frame_len, &[#(#first),*])?)
    } else {
        quote!(rt::frame_mut::<#len>(buf, &[#(#first),*])?)
    };
    if i == known.len() && repeat.is_none() && lists.is_empty() && !m.has_optional() {
        stmts.extend(range_checks(ctx, m, ls));
        if checksum_in_arms(p) {
            // The frame taken, then sealed: two short lines rather than one nested call.
            let end = encode_end(p, quote!(out), false, head);
            return write_arm(
                ctx,
                m,
                ls,
                taken,
                pattern,
                quote!(#(#stmts)* let out = #take;),
                end,
            );
        }
        let (check, end) = (stmts, encode_end(p, take, false, head));
        return write_arm(ctx, m, ls, taken, pattern, quote!(#(#check)*), end);
    }
    let take_at = stmts.len();
    stmts.push(quote!(let out = #take;));
    // Where each field's range checks went, to hoist them before the frame is taken.
    let mut checked: Vec<usize> = Vec::new();
    if repeat.is_some() {
        // The length field of a frame of variable length, from its length.
        stmts.extend(put_lengths(p, m.direction));
    }
    stmts.extend(known_runs(&known, i));
    let counter = m.count_field();
    for (fi, f) in m.fields.iter().enumerate() {
        // An optional field sits where it does when every optional field is present.
        let full = f.frame_at(&o) + full_shift(m, fi);
        let at = usize_lit(full);
        let end = usize_lit(full + f.width);
        let wt = wire_type(f);
        let w = wt.ident();
        let unsigned = IntType {
            bits: wt.bits,
            signed: false,
            float: false,
        };
        if f.repeat.is_some() && !lists.is_empty() {
            // Written once the frame is spread around the lists.
            continue;
        }
        if let (Some(_), Some((_, c, v))) = (&f.repeat, &repeat) {
            stmts.push(write_list(f, &quote!(#c), v, quote!(#at)));
            continue;
        }
        // The fields after the lists, in frame order: each its presence (where optional),
        // then its range, then its value.
        let checks = range_checks(ctx, m, ls.iter().filter(|l| l.field.name == f.name));
        if let Some(pk) = &f.packed {
            place(&mut stmts, &mut checked, checks);
            stmts.push(write_packed(f, pk, full));
            continue;
        }
        if f.is_ascii() {
            let n = local(&f.name);
            stmts.push(quote!(out[#at..#end].copy_from_slice(&#n.0);));
            continue;
        }
        if f.constant.is_some() && !named.contains(&fi) {
            continue;
        }
        let value: TokenStream = if let Some(c) = f.constant {
            if let (true, Some(v)) = (wt.signed, f.constant_value()) {
                // Its value as decode reads it (a 24-bit one held in 32 bits sign-extended
                // too): what a field that follows it is computed from.
                let l = i64_lit(v);
                quote!(#l as #w)
            } else {
                let l = lit_u(c, unsigned);
                quote!(#l as #w)
            }
        } else if let Some(other) = f.equals {
            let n = wire_local(&m.fields[other].name);
            quote!(#n)
        } else if let Some((other, rel)) = follows_field(f) {
            let (n, args) = (wire_local(&m.fields[other].name), relation_args(rel));
            fits(f, wt, quote!(rt::follows(#n as i64, #args)))
        } else if let (true, Some((_, c, v))) = (counter == Some(fi), &repeat) {
            fits(f, wt, quote!(#c.count_value(#v.len()) as u64))
        } else if let Some((k, v)) = list_counted(fi) {
            fits(f, wt, quote!(#lc.lists[#k].count_value(#v.len()) as u64))
        } else if !f.bits.is_empty() {
            bits_value(ctx, f, ls, wt, unsigned)
        } else {
            let Some(leaf) = ls.iter().find(|l| l.bits.is_none() && l.name == f.name) else {
                continue;
            };
            to_wire(ctx, leaf, &local(&f.name), None)
        };
        let put = |v: TokenStream| put_field(f, wt, full, v);
        let agrees = match (&repeat, follows_field(f)) {
            (Some((_, c, v)), Some(_)) if counter == Some(fi) => Some((quote!(#c), v.clone())),
            (None, Some(_)) => list_counted(fi).map(|(k, v)| (quote!(#lc.lists[#k]), v)),
            _ => None,
        };
        if let Some(c) = &f.present {
            // Written where a value is given, which must be exactly where its condition holds.
            let v = local(&f.name);
            stmts.push(presence_check(m, f, c));
            place(&mut stmts, &mut checked, checks);
            let put = put(value);
            stmts.push(quote!(if let rt::Some(#v) = #v { #put }));
        } else if named.contains(&fi)
            || !f.bits.is_empty()
            || f.constant.is_some()
            || agrees.is_some()
        {
            place(&mut stmts, &mut checked, checks);
            let n = wire_local(&f.name);
            stmts.push(quote!(let #n: #w = #value;));
            if let Some((c, v)) = agrees {
                // A count computed from another field must count the list.
                stmts.push(quote!(#c.encode_agrees(#v.len(), #n as u64)?;));
            }
            stmts.push(put(quote!(#n)));
        } else {
            place(&mut stmts, &mut checked, checks);
            stmts.push(put(value));
        }
    }
    hoist_checks(&mut stmts, take_at, &checked);
    if !lists.is_empty() {
        stmts.push(quote!(let out = #lc.expand(&compact, &[#(#list_bytes),*], buf)?;));
        for ((k, _, f, v), _) in lists.iter().zip(&list_bytes) {
            let at = usize_lit(m.layout.payload + f.offset);
            let before = &list_bytes[..*k];
            let at = quote!(#at #(+ #before)*);
            let k = usize_lit(*k);
            stmts.push(write_list(f, &quote!(#lc.lists[#k]), v, at));
        }
        stmts.extend(put_lengths(p, m.direction));
    }
    if m.has_optional() {
        let c = optional_const(m);
        let given = m.optionals().map(|(_, f, _)| {
            let v = local(&f.name);
            quote!(#v.is_some())
        });
        stmts.push(quote!(let out = #c.pack(&compact, &[#(#given),*], buf)?;));
        stmts.extend(put_lengths(p, m.direction));
    }
    if m.delimited_list(&p.framing).is_some() {
        // End bytes alone delimit the frame: the list must not show them before its end.
        match &repeat {
            Some((_, c, _)) => stmts.push(quote!(#c.encode_delimited(out)?;)),
            None => stmts.push(quote!(#lc.lists[0].encode_delimited(out)?;)),
        }
    }
    let variable = repeat.is_some() || !lists.is_empty() || m.has_optional();
    let end = encode_end(p, quote!(out), variable, head);
    write_arm(ctx, m, ls, taken, pattern, quote!(#(#stmts)*), end)
}

/// Pushes a field's range checks `checks` onto `stmts`, noting where they went in `checked`.
fn place(stmts: &mut Vec<TokenStream>, checked: &mut Vec<usize>, checks: Vec<TokenStream>) {
    for c in checks {
        checked.push(stmts.len());
        stmts.push(c);
    }
}

/// The fields' range checks (at `checked`, in frame order) moved before the frame is taken
/// (`stmts[take_at]`) where nothing else the fields write can refuse: the same refusal first,
/// and no stores into the buffer before them (which the compiler may not move past a check).
fn hoist_checks(stmts: &mut Vec<TokenStream>, take_at: usize, checked: &[usize]) {
    let fallible = |t: &TokenStream| t.to_string().contains('?');
    let others_refuse = stmts
        .iter()
        .enumerate()
        .skip(take_at + 1)
        .any(|(i, t)| !checked.contains(&i) && fallible(t));
    if others_refuse || checked.is_empty() {
        return;
    }
    let checks: Vec<TokenStream> = checked.iter().map(|&i| stmts[i].clone()).collect();
    let mut i = 0;
    stmts.retain(|_| {
        i += 1;
        !checked.contains(&(i - 1))
    });
    stmts.splice(take_at..take_at, checks);
}

/// The encoder's arm of message `m`: a message with fields is written by its struct's own
/// `write` (emitted in its `impl` by `emit_descs`: its fields bound to their locals, `stmts`,
/// then `end`, the frame's length), into `out` where the direction took the frame before its
/// match (`taken`), else into `buf`; the arm calls it (`Self::ReadCoils(ref m) =>
/// m.write(address, buf)?`). A message without fields, or without a checksum (whose arm
/// returns past the seal), keeps `stmts` in its arm.
#[allow(clippy::too_many_arguments)]
fn write_arm(
    ctx: &Ctx,
    m: &Message,
    ls: &[Leaf],
    taken: bool,
    pattern: &TokenStream,
    stmts: TokenStream,
    end: TokenStream,
) -> TokenStream {
    if ls.is_empty() || m.unchecked {
        return sealed(m, pattern, stmts, end);
    }
    let v = variant(m);
    let this = fields_binding(quote!(Self), ls);
    let (param, arg) = if taken {
        let len = usize_lit(ctx.p.frame_len(m));
        (quote!(out: &mut [u8; #len]), quote!(out))
    } else {
        (quote!(buf: &mut [u8]), quote!(buf))
    };
    let mut writers = ctx.writers.borrow_mut();
    if !writers
        .iter()
        .any(|(d, n, _)| *d == m.direction && *n == m.name)
    {
        writers.push((
            m.direction,
            m.name.clone(),
            quote! {
                /// Writes this message's frame for `address`, as the direction's `encode` does.
                #[inline(always)]
                fn write(&self, address: u8, #param) -> rt::EncodeResult {
                    let #this = *self;
                    #stmts
                    rt::Ok(#end)
                }
            },
        ));
    }
    quote!(Self::#v(ref m) => m.write(address, #arg)?,)
}

/// Writes the packed elements (`packed`) of field `f` at offset `at`: each in its bits, or
/// whole in its byte and word order where they are not unsigned of 1, 2 or 4 bytes.
fn write_packed(f: &Field, pk: &Packed, at: usize) -> TokenStream {
    let (end, at) = (usize_lit(at + f.width), usize_lit(at));
    let (name, n) = (&f.name, local(&f.name));
    let (count, bits, lsb) = (
        usize_lit(pk.count),
        usize_lit(pk.bits as usize),
        pk.lsb_first,
    );
    if super::ctx::fixed_elements(f) {
        let width = usize_lit(pk.elem_width);
        let (le, swapped) = (f.byte_order == ByteOrder::Little, f.word_swapped);
        quote!(rt::write_fixed(#name, #n.as_slice(), #count, #width, #le, #swapped, &mut out[#at..#end])?;)
    } else {
        quote!(rt::pack(#name, #n.as_slice(), #count, #bits, #lsb, &mut out[#at..#end])?;)
    }
}

/// Value `v` of field `f` computed from another (a relation, a list's count), refused where
/// it does not fit the field's wire type `wt`, as that type.
fn fits(f: &Field, wt: IntType, v: TokenStream) -> TokenStream {
    let (name, w) = (&f.name, wt.ident());
    let (lo, hi) = wt.limits();
    let (lo, hi) = (i64_lit(lo), i64_lit(hi));
    quote!(rt::fits(#name, #v, #lo, #hi)? as #w)
}

/// The check that optional field `f` is given exactly where its condition `c` holds.
fn presence_check(m: &Message, f: &Field, c: &Presence) -> TokenStream {
    let (name, v) = (&f.name, local(&f.name));
    let cond = wire_local(&m.fields[c.field].name);
    let on = match c.when {
        PresentWhen::Bit(b) => {
            let mask = hex_lit(1u64 << b);
            quote!(#cond & #mask != 0)
        }
        PresentWhen::Equals(x) => {
            let x = Literal::u64_unsuffixed(x as u64);
            quote!(#cond == #x)
        }
    };
    let words = condition_text(m, c);
    quote!(rt::presence(#name, #on, #v.is_some(), #words)?;)
}

/// Each field's value within its range (the spec's, or its wire type's where the Rust type
/// is wider), a packed list's elements too; an optional field where a value is given.
fn range_checks<'a>(
    ctx: &Ctx,
    m: &Message,
    ls: impl IntoIterator<Item = &'a Leaf<'a>>,
) -> Vec<TokenStream> {
    let mut checks = Vec::new();
    for l in ls {
        if let (Some(pk), Some((lo, hi)), None) = (&l.field.packed, l.field.range, l.bits) {
            let (name, v, lo, hi) = (l.name, local(l.name), i64_lit(lo), i64_lit(hi));
            let count = usize_lit(pk.count);
            checks
                .push(quote!(rt::encode_packed_in_range(#name, #v.as_slice(), #count, #lo, #hi)?;));
            continue;
        }
        let Some((raw_t, raw)) = raw_of(ctx, l, &local(l.name)) else {
            continue;
        };
        let Some(range) = leaf_range(l.field, l.bits, raw_t.limits()) else {
            continue;
        };
        let at = l.field.frame_at(&m.layout);
        let at_lit = usize_lit(at).to_token_stream();
        let c = ctx.field_check(m, l.name, (at, &at_lit), Some(range), None);
        if l.field.present.is_some() && l.bits.is_none() {
            // An optional field, where a value is given.
            let v = local(l.name);
            checks.push(quote!(if let rt::Some(#v) = #v { rt::encode_in_range(#c, #raw)?; }));
            continue;
        }
        checks.push(quote!(rt::encode_in_range(#c, #raw)?;));
    }
    checks
}

/// The bytes of message `m`'s frame known without a field value (start bytes, the length of a
/// frame of one length, the code, constant fields but those in `named`) and the address's
/// place, up to the checksum; beside them the same bytes' values, 0 for the address.
fn known_bytes(p: &Protocol, m: &Message, named: &[usize]) -> (Vec<Option<TokenStream>>, Vec<u8>) {
    let o = m.layout;
    let mut known: Vec<Option<TokenStream>> = vec![None; o.checksum];
    // The same bytes' values, but the address's.
    let mut consts: Vec<u8> = vec![0; o.checksum];
    let mut set = |at: usize, b: u8| {
        consts[at] = b;
        known[at] = Some(hex_u8(b));
    };
    for at in o.starts() {
        for (i, s) in p.framing.sync_of(m.direction).iter().enumerate() {
            set(at + i, *s);
        }
    }
    if let (Some(l), false) = (&p.framing.length, m.is_variable()) {
        let v = p
            .framing
            .length_value_of(m.direction, l, m.code.len(), m.payload_len);
        for at in o.lengths() {
            for (i, b) in constant_bytes(v as u64, l.width, p.byte_order)
                .into_iter()
                .enumerate()
            {
                set(at + i, b);
            }
        }
    }
    for (i, b) in m.code.iter().enumerate() {
        set(o.code + i, *b);
    }
    for (fi, f) in m.fields.iter().enumerate() {
        if let (Some(c), false) = (f.constant, named.contains(&fi)) {
            let bytes = constant_bytes(c, f.width, f.byte_order);
            for (i, b) in bytes.into_iter().enumerate() {
                set(f.frame_at(&o) + i, b);
            }
        }
    }
    if let Some(at) = o.address {
        known[at] = Some(quote!(address));
    }
    (known, consts)
}

/// The value of a field of sub-fields (`bits`): each sub-field's wire value masked and
/// shifted into place, or-ed with the others; constant sub-fields as their literals.
fn bits_value(ctx: &Ctx, f: &Field, ls: &[Leaf], wt: IntType, unsigned: IntType) -> TokenStream {
    let mut parts = Vec::new();
    for b in &f.bits {
        let lsb = u32::from(b.lsb);
        let part = match b.constant {
            Some(0) => continue,
            Some(c) => hex_lit(c),
            None => {
                let Some(leaf) = ls.iter().find(|l| l.name == b.name) else {
                    continue;
                };
                let v = to_wire(ctx, leaf, &local(&b.name), Some(unsigned));
                if lsb + u32::from(b.width()) >= wt.rust_bits()
                    || matches!(ctx.kind(leaf), Kind::Bool)
                {
                    // Parenthesized below where it is shifted or or-ed with others.
                    v
                } else {
                    let (v, mask) = (paren(v), hex_lit((1u64 << b.width()) - 1));
                    quote!(#v & #mask)
                }
            }
        };
        parts.push(if lsb == 0 {
            part
        } else {
            let (lsb, part) = (Literal::u32_unsuffixed(lsb), paren(part));
            quote!(#part << #lsb)
        });
    }
    match parts.as_slice() {
        [] => quote!(0),
        [one] => one.clone(),
        many => {
            let many = many.iter().cloned().map(paren);
            quote!(#(#many)|*)
        }
    }
}

/// Writes value `v` of field `f` (wire type `wt`) at offset `at` of `out`: a byte, 24 bits,
/// word-swapped registers, BCD digits, or the number's bytes in the field's byte order.
fn put_field(f: &Field, wt: IntType, at: usize, v: TokenStream) -> TokenStream {
    let (end, at) = (usize_lit(at + f.width), usize_lit(at));
    let conv = to_bytes(f.byte_order);
    let wt_ident = wt.ident();
    // A BCD field's digits (its value is in range, checked above).
    let v = if f.bcd {
        let v = paren(v);
        quote!(rt::to_bcd(#v as u64) as #wt_ident)
    } else {
        v
    };
    if f.width == 1 && !wt.signed {
        quote!(out[#at] = #v;)
    } else if f.width == 3 {
        let le = f.byte_order == ByteOrder::Little;
        let v = paren(v);
        quote!(out[#at..#end].copy_from_slice(&rt::bytes24(#v as u32, #le));)
    } else if f.word_swapped {
        // The number's bytes in the field's byte order, its 16-bit words swapped.
        let v = paren(v);
        let idx = (0..f.width).map(|i| usize_lit(busspec_model::number::swap_index(i, f.width)));
        quote!({ let b = #v.#conv(); out[#at..#end].copy_from_slice(&[#(b[#idx]),*]); })
    } else {
        let v = paren(v);
        quote!(out[#at..#end].copy_from_slice(&#v.#conv());)
    }
}

/// Writes the length field (each copy of it) of a frame of direction `d` from its length,
/// where the framing has one.
fn put_lengths(p: &Protocol, d: Direction) -> Vec<TokenStream> {
    length_consts(p, d)
        .into_iter()
        .map(|(name, _)| quote!(#name.put(out)?;))
        .collect()
}

/// The elements' range of a list field `f`: the spec's, else its wire field's where the
/// element's Rust type is wider (a 24-bit element, one of the spec's types); `None` where the
/// type bounds it.
fn element_range(ctx: &Ctx, f: &Field) -> Option<(i64, i64)> {
    let limits = (f.ty != FieldType::Bit
        && !f.is_record()
        && (f.width == 3 || ctx.element_type(f).is_some()))
    .then(|| wire_type(f).limits());
    f.range.or(limits)
}

/// The writes of the known bytes from offset `i` on, one a contiguous run.
fn known_runs(known: &[Option<TokenStream>], mut i: usize) -> Vec<TokenStream> {
    let mut writes = Vec::new();
    while i < known.len() {
        let run: Vec<TokenStream> = known[i..].iter().map_while(Clone::clone).collect();
        match run.as_slice() {
            [] => i += 1,
            [b] => {
                let at = usize_lit(i);
                writes.push(quote!(out[#at] = #b;));
                i += 1;
            }
            bytes => {
                let (from, to) = (usize_lit(i), usize_lit(i + bytes.len()));
                let from = if i == 0 { quote!() } else { quote!(#from) };
                writes.push(quote!(out[#from..#to].copy_from_slice(&[#(#bytes),*]);));
                i += bytes.len();
            }
        }
    }
    writes
}

/// An encoder arm of `pattern`: `stmts`, then `end`, the frame's length, its value; a message
/// without a checksum (`checksum: none`) returns it, past the seal after the arms.
fn sealed(m: &Message, pattern: &TokenStream, stmts: TokenStream, end: TokenStream) -> TokenStream {
    if m.unchecked {
        quote!(#pattern => { #stmts return rt::Ok(#end); })
    } else {
        quote!(#pattern => { #stmts #end })
    }
}

/// An encoder arm's value, the frame length, from `out`, its frame: with a sum-8, once it is
/// written into the last byte (each arm seals its own frame). `head` is the length of the run
/// of known bytes at the frame's start and, where the address lies in it, the sum of its
/// constant bytes: the sum then adds only the address and the bytes after the run, which for
/// a frame without fields is one add instead of a loop over the frame at `opt-level = "s"`.
pub(super) fn encode_end(
    p: &Protocol,
    out: TokenStream,
    variable: bool,
    head: (usize, Option<u8>),
) -> TokenStream {
    if checksum_in_arms(p) && variable {
        quote!(rt::seal_sum8_len(#out))
    } else if let (true, (from, Some(k))) = (checksum_in_arms(p), head) {
        let from = usize_lit(from);
        let sum = match k {
            0 => quote!(address),
            k => {
                let k = hex_u8(k);
                quote!(address.wrapping_add(#k))
            }
        };
        quote!(rt::seal_sum8_head(#out, #from, #sum))
    } else if checksum_in_arms(p) {
        quote!(rt::seal_sum8(#out))
    } else {
        quote!(#out.len())
    }
}

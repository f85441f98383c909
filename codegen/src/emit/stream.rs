use super::*;

/// Each start byte of `sync` from offset `at`: the head's byte where it sits (`None` past the
/// head), and its value.
fn sync_bytes(at: usize, sync: &[u8]) -> impl Iterator<Item = (TokenStream, TokenStream)> + '_ {
    sync.iter()
        .enumerate()
        .map(move |(i, s)| (head_byte(at + i), hex_u8(*s)))
}

/// The protocol's type (its `rt::Protocol` impl: `protocol.rs`) and the stream decoder's view
/// of it, `rt::Framing`: every distinct frame length (longest first) and a `candidates`
/// function that narrows them by start byte and code, one `match` arm per code and per code
/// prefix. Not by address: a frame from an address the spec does not allow is still a frame,
/// which the stream decoder reports as out of spec (strict decoding says why).
pub(super) fn emit_stream(p: &Protocol) -> TokenStream {
    let lengths = frame_lengths(p);
    let shapes = length_shapes(p, &lengths);
    let first = p.framing.head(Direction::Request, 1);
    let code_at = first.code;
    // Start bytes that differ by direction say which direction's messages the head may start.
    let by_direction = p.framing.sync_by_direction();
    let agree = |at: usize, sync: &[u8]| {
        let each = sync_bytes(at, sync).map(|(at, s)| quote!(#at.map_or(true, |&b| b == #s)));
        quote!(#(#each)&&*)
    };
    let start_check = |none: TokenStream| match first.start {
        Some(at) if by_direction => {
            let (requests, responses) = (
                agree(at, &p.framing.sync),
                agree(at, &p.framing.response_sync),
            );
            quote! {
                let requests_agree = #requests;
                let responses_agree = #responses;
                if !requests_agree && !responses_agree {
                    return #none;
                }
            }
        }
        Some(at) => {
            let checks = sync_bytes(at, &p.framing.sync).map(|(at, s)| {
                quote! {
                    if #at.is_some_and(|&b| b != #s) {
                        return #none;
                    }
                }
            });
            quote!(#(#checks)*)
        }
        None => quote!(),
    };
    // Constant whole frames (`frame:`): a head that begins with one's first byte (never a
    // start byte: validated) has those frames for candidates, each of its length, and no
    // framed one; the fast path's table asks `candidates` there.
    let firsts = constant_firsts(p, &lengths);
    let constant_check = |each: &dyn Fn(u128) -> TokenStream| {
        if firsts.is_empty() {
            return quote!();
        }
        let arms = firsts.iter().map(|(b, m)| {
            let (b, v) = (hex_u8(*b), each(*m));
            quote!(rt::Some(&#b) => return #v,)
        });
        quote! {
            match head.first() {
                #(#arms)*
                _ => {}
            }
        }
    };
    let constants_in_mask = constant_check(&|m| {
        let (q, r) = (mask_lit(m & u128::from(u64::MAX)), mask_lit(m >> 64));
        quote!(rt::Candidates { requests: #q as u64, responses: #r as u64 })
    });
    let constants_in_table = constant_check(&|_| quote!(rt::Candidate::MANY));
    let variable = emit_variable_candidates(p, start_check(quote!(rt::VarLens::NONE)));
    // Not where a variable-length message exists: the route would ask `variable_candidates`
    // too, and the mask's route pays for both (Modbus 1254.6 -> 1280.5 a frame with it).
    let code_apart = p.framing.head(Direction::Response, 1).code != code_at;
    let candidate = if variable.is_empty() && !by_direction && !code_apart {
        emit_candidate(&shapes, &lengths, code_at, {
            let framed = start_check(quote!(rt::Candidate::NONE));
            quote!(#constants_in_table #framed)
        })
    } else {
        quote!()
    };
    let start_check = {
        let framed = start_check(quote!(rt::Candidates {
            requests: 0,
            responses: 0
        }));
        quote!(#constants_in_mask #framed)
    };
    let mask = candidates_mask(p, &shapes, code_at);
    let lens = lengths.iter().map(|l| usize_lit(*l));
    let ty = type_ident(&p.name);
    let protocol = super::protocol::emit_protocol_impl(p);
    let checksum_ok = super::protocol::checksum_ok_fn(p);
    // A reply whose checksum takes in its request's bytes (`checksum_over_request`): the
    // request's covered bytes kept by the stream decoder.
    let span = if p.has_over_request() {
        quote! {
            const OVER_REQUEST: bool = true;
            type Span = [u8; MAX_REQUEST_LEN];
            const EMPTY_SPAN: [u8; MAX_REQUEST_LEN] = [0; MAX_REQUEST_LEN];
        }
    } else {
        quote! {
            type Span = [u8; 0];
            const EMPTY_SPAN: [u8; 0] = [];
        }
    };
    let by_sync = if by_direction && first.start.is_some() {
        quote! {
            let keep: u128 = (if requests_agree { u64::MAX as u128 } else { 0 })
                | (if responses_agree { (u64::MAX as u128) << 64 } else { 0 });
            let mask = mask & keep;
        }
    } else {
        quote!()
    };
    let (views, view_fns) = view_checks(p);
    // No response only its request tells apart, and none whose checksum takes in its
    // request's bytes: a response decodes as the reply to any request as on its own, so the
    // stream decoder need not pair it (`Framing::REPLY_BY_REQUEST`, `true` by default).
    let by_request = if p.has_over_request() || p.responses.iter().any(|m| m.needs_request) {
        quote!()
    } else {
        quote!(
            const REPLY_BY_REQUEST: bool = false;
        )
    };
    let framing_fns = if p.framing.truncation.is_some() {
        // Payload truncation (`framing.truncation`): every frame is framed by its length
        // field, within the lengths its code's message travels in.
        let trailer = usize_lit(p.framing.trailer_len());
        quote! {
            #[inline]
            fn candidates(_head: &[u8]) -> rt::Candidates {
                rt::Candidates { requests: 0, responses: 0 }
            }
            #[inline]
            fn variable_candidates(head: &[u8]) -> rt::VarLens {
                TRUNCATION.frame_lens(head, #trailer)
            }
        }
    } else if p.framing.form.is_some() {
        // A short form of the frame (`framing.forms`): both forms are framed by their start
        // byte and the long one's length field; a constant whole frame by its first byte.
        quote! {
            #[inline]
            fn candidates(head: &[u8]) -> rt::Candidates {
                let _ = head;
                #constants_in_mask
                rt::Candidates { requests: 0, responses: 0 }
            }
            #[inline]
            fn variable_candidates(head: &[u8]) -> rt::VarLens {
                FORM.frame_lens(head)
            }
        }
    } else if p.framing.long.is_some() {
        // Both forms of a length field the start byte chooses are framed by their length
        // field alone (`framing.length.long`).
        quote! {
            const LONG: rt::Option<rt::LongLength> = rt::Some(LONG);
            #[inline]
            fn candidates(_head: &[u8]) -> rt::Candidates {
                rt::Candidates { requests: 0, responses: 0 }
            }
            #[inline]
            fn variable_candidates(head: &[u8]) -> rt::VarLens {
                LONG.frame_lens(head)
            }
        }
    } else if p.framing.escaping.is_none() {
        let preamble = p
            .framing
            .preamble
            .as_ref()
            .map(|_| quote! { const PREAMBLE: rt::Option<rt::Preamble> = rt::Some(PREAMBLE); });
        let transform = p.framing.transform.as_ref().map(|_| {
            quote! { const TRANSFORM: rt::Option<rt::Transform> = rt::Some(TRANSFORM); }
        });
        quote! {
            #preamble
            #transform
            #[inline]
            fn candidates(head: &[u8]) -> rt::Candidates {
                #start_check
                #mask
                #by_sync
                rt::Candidates { requests: mask as u64, responses: (mask >> 64) as u64 }
            }
            #candidate
            #variable
        }
    } else {
        // Escaped frames are framed by their end byte or their length field alone; a flag
        // that opens and closes them may be shared by two frames.
        // Requests and responses framed apart (F.Port's uplink: responses without start or
        // end bytes, found by their length field): each direction by its own escaping.
        let lens_fn = if p.framing.end_by_direction() {
            quote!(rt::escaped_lens_by_direction(
                &ESCAPING,
                &RESPONSE_ESCAPING,
                head,
                MAX_FRAME_LEN
            ))
        } else {
            quote!(rt::escaped_lens(&ESCAPING, head, MAX_FRAME_LEN))
        };
        let shared_flag = p.framing.shared_flag().map(|flag| {
            let flag = hex_u8(flag);
            quote! { const SHARED_FLAG: rt::Option<u8> = rt::Some(#flag); }
        });
        quote! {
            #shared_flag
            #[inline]
            fn candidates(_head: &[u8]) -> rt::Candidates {
                rt::Candidates { requests: 0, responses: 0 }
            }
            #[inline]
            fn variable_candidates(head: &[u8]) -> rt::VarLens {
                #lens_fn
            }
        }
    };
    let lens: Vec<Literal> = if p.framing.escaping.is_some() || p.framing.long.is_some() {
        Vec::new()
    } else {
        lens.collect()
    };
    quote! {
        #protocol
        impl rt::Framing for #ty {
            const MAX_REQUEST_LEN: usize = MAX_REQUEST_LEN;
            const MAX_RESPONSE_LEN: usize = MAX_RESPONSE_LEN;
            const FRAME_LENGTHS: &'static [usize] = &[#(#lens),*];
            #span
            #by_request
            #views
            #framing_fns
            #view_fns
            #checksum_ok
        }
        /// A streaming decoder for this protocol: see [`busspec_runtime::stream`].
        pub type StreamDecoder = ::busspec_runtime::stream::StreamDecoder<#ty>;
        /// What [`StreamDecoder`] finds in a stream.
        pub type Event = ::busspec_runtime::stream::Event<Request, Response>;
    }
}

/// The fixed frame lengths of direction `d` where the stream decoder's fast path decodes its
/// frames by length (`Protocol::decode_request_fixed`, `decode_response_fixed`: a copy of the
/// decoder for each length, which then checks a frame of constant length), shortest first;
/// empty where it does not: the protocol has no candidate table ([`emit_candidate`], the
/// route that asks them), or its frames are unescaped, laid out or checksummed over their
/// request before they are checked.
pub(super) fn fixed_lengths(p: &Protocol, d: Direction) -> Vec<usize> {
    let f = &p.framing;
    if f.escaping.is_some()
        || f.truncation.is_some()
        || f.long.is_some()
        || f.form.is_some()
        || p.has_over_request()
    {
        return Vec::new();
    }
    let lengths = frame_lengths(p);
    let shapes = length_shapes(p, &lengths);
    let depth = shapes.iter().map(|s| s.0.len()).max().unwrap_or(0);
    let code_at = f.head(Direction::Request, 1).code;
    let table = lengths.len() >= 2
        && (1..=2).contains(&depth)
        && emit_variable_candidates(p, quote!()).is_empty()
        && !f.sync_by_direction()
        && f.head(Direction::Response, 1).code == code_at;
    if !table {
        return Vec::new();
    }
    let mut own: Vec<usize> = p
        .framed(d)
        .iter()
        .flat_map(|m| m.listed_lengths(f))
        .collect();
    own.sort_unstable();
    own.dedup();
    own
}

/// Every distinct frame length the stream decoder lists, longest first (`FRAME_LENGTHS`).
/// A variable-length message whose length or count field gives its length lists none
/// (`variable_candidates` reads it); a repeat to the end without a length field lists every
/// length.
fn frame_lengths(p: &Protocol) -> Vec<usize> {
    let mut lengths: Vec<usize> = [Direction::Request, Direction::Response]
        .iter()
        .flat_map(|d| {
            p.messages(*d)
                .iter()
                .flat_map(|m| m.listed_lengths(&p.framing))
        })
        .collect();
    lengths.sort_unstable_by(|a, b| b.cmp(a));
    lengths.dedup();
    // A short form of the frame (`framing.forms`): framed messages are framed by their start
    // byte and length field (`variable_candidates`); only constant whole frames are listed.
    // Payload truncation (`framing.truncation`): every frame by its length field alone.
    if p.framing.truncation.is_some() {
        lengths.clear();
    }
    if p.framing.form.is_some() {
        lengths.clear();
        for d in [Direction::Request, Direction::Response] {
            lengths.extend(p.constants(d).map(|(_, f)| f.len()));
        }
        lengths.sort_unstable_by(|a, b| b.cmp(a));
        lengths.dedup();
    }
    lengths
}

/// Shapes: (code, mask) where the mask has bit i (requests) or 64 + i (responses) for
/// `lengths[i]`, one a framed message. The validator keeps distinct lengths to at most 64.
fn length_shapes<'p>(p: &'p Protocol, lengths: &[usize]) -> Vec<(&'p [u8], u128)> {
    let mut shapes: Vec<(&[u8], u128)> = Vec::new();
    for (d, shift) in [(Direction::Request, 0u32), (Direction::Response, 64)] {
        for m in p.framed(d) {
            let mask = m.listed_lengths(&p.framing).iter().fold(0u128, |a, len| {
                let i = lengths.iter().position(|l| l == len).unwrap_or(0) as u32;
                a | 1u128 << (i + shift)
            });
            if mask != 0 {
                shapes.push((&m.code, mask));
            }
        }
    }
    shapes
}

/// The first byte of each constant whole frame (`frame:`), and the mask of the lengths of the
/// constant frames that begin with it.
fn constant_firsts(p: &Protocol, lengths: &[usize]) -> Vec<(u8, u128)> {
    let mut firsts: Vec<(u8, u128)> = Vec::new();
    for (d, shift) in [(Direction::Request, 0u32), (Direction::Response, 64)] {
        for (_, f) in p.constants(d) {
            let i = lengths.iter().position(|l| *l == f.len()).unwrap_or(0) as u32;
            let bit = 1u128 << (i + shift);
            match firsts.iter_mut().find(|(b, _)| Some(b) == f.first()) {
                Some((_, m)) => *m |= bit,
                None => firsts.push((f.first().copied().unwrap_or(0), bit)),
            }
        }
    }
    firsts
}

/// The mask of `candidates` (`let mask: u128`): the lengths the code bytes at `code_at` allow,
/// by table for one code byte, by a `match` over a trie of the codes for more.
fn candidates_mask(p: &Protocol, shapes: &[(&[u8], u128)], code_at: usize) -> TokenStream {
    let depth = shapes.iter().map(|s| s.0.len()).max().unwrap_or(1);
    let mut arms = Vec::new();
    flat_trie(shapes, 0, depth, &mut Vec::new(), 0, &mut arms);
    // Where a code-less message matches any code byte, the trie ends in a wildcard arm already.
    let open = arms
        .last()
        .is_some_and(|(pat, _)| pat.iter().all(|t| t.to_string() == "_"));
    let other = if open { quote!() } else { quote!(_ => 0,) };
    let arms: Vec<TokenStream> = arms
        .into_iter()
        .map(|(pat, mask)| {
            let mask = mask_lit(mask);
            let pat = if pat.len() == 1 {
                pat.into_iter().collect::<TokenStream>()
            } else {
                quote!((#(#pat),*))
            };
            quote!(#pat => #mask,)
        })
        .collect();
    // The mask of the code bytes at `code_at`.
    let mask_at = |code_at: usize| {
        let bytes: Vec<TokenStream> = (0..depth).map(|i| head_byte(code_at + i)).collect();
        let scrutinee = if depth == 1 {
            quote!(#(#bytes)*)
        } else {
            quote!((#(#bytes),*))
        };
        // One code byte: the masks by table, a class per byte and the distinct masks (SD: three),
        // where the `match` compiled to a jump table (SD's stream: 132.6 instructions a frame
        // with it, 131.4 with the table and the one-length route of `Core::fast_with`).
        let mask = if depth == 1 {
            let all = shapes.iter().fold(0u128, |a, s| a | s.1);
            let mut masks: Vec<Vec<u128>> = Vec::new();
            let class: Vec<u8> = (0..=255u8)
                .map(|b| {
                    let m = shapes
                        .iter()
                        .filter(|s| s.0.first().map_or(true, |&c| c == b))
                        .fold(0u128, |a, s| a | s.1);
                    index_of(&mut masks, vec![m])
                })
                .collect();
            // One table, the classes then the masks (16 bytes each, low first), so one base
            // address. Up to 16 masks, a class is its mask's offset and the table is padded past
            // the largest, so the index is neither scaled nor checked (SD: 127.6 -> 125.6
            // instructions a frame); more, the class is masked to a power of two.
            let size = masks.len().next_power_of_two();
            let (mut table, index) = if size <= 16 {
                let offsets = class.iter().map(|c| 16 * c).collect();
                (offsets, quote!(TABLE[b as usize] as usize))
            } else {
                let last = usize_lit(size - 1);
                (class, quote!(16 * (TABLE[b as usize] as usize & #last)))
            };
            for m in masks.iter().map(|m| m[0]) {
                table.extend_from_slice(&m.to_le_bytes());
            }
            let end = if size <= 16 {
                256 + 256 + 16
            } else {
                256 + 16 * size
            };
            table.resize(end, 0);
            let (n, table) = (usize_lit(table.len()), Literal::byte_string(&table));
            let (all, byte) = (mask_lit(all), &bytes[0]);
            quote! {
                static TABLE: [u8; #n] = *#table;
                let mask = match #byte {
                    rt::Some(&b) => {
                        let i = 256 + #index;
                        let mut m = [0; 16];
                        m.copy_from_slice(&TABLE[i..i + 16]);
                        u128::from_le_bytes(m)
                    }
                    rt::None => #all,
                };
            }
        } else {
            quote! {
                let mask: u128 = match #scrutinee {
                    #(#arms)*
                    #other
                };
            }
        };
        mask
    };
    // A layout per direction with the code at another offset in each: a request's candidates
    // by the bytes where a request's code sits, a response's by a response's.
    let response_code_at = p.framing.head(Direction::Response, 1).code;
    if response_code_at == code_at {
        mask_at(code_at)
    } else {
        let (requests, responses) = (mask_at(code_at), mask_at(response_code_at));
        quote! {
            let mask: u128 = ({ #requests mask } & (u64::MAX as u128))
                | ({ #responses mask } & !(u64::MAX as u128));
        }
    }
}

/// Whether a frame decodes, without its value, through the direction's borrowed view where
/// it has one (no list copied): what the stream decoder asks of a frame that may be either
/// direction. Without a view, the trait's default (the owned decoder).
/// Returns `Framing::VIEWS` where a direction has a view, and the functions.
fn view_checks(p: &Protocol) -> (TokenStream, TokenStream) {
    let request_decodes = if no_view(p, Direction::Request).is_none() {
        quote! {
            #[inline]
            fn request_decodes(frame: &[u8]) -> rt::Result<(), rt::DecodeError> {
                RequestView::decode(frame).map(|_| ())
            }
        }
    } else {
        quote!()
    };
    let response_decodes = if no_view(p, Direction::Response).is_some() {
        quote!()
    } else if p.has_over_request() {
        quote! {
            #[inline]
            fn response_decodes(frame: &[u8], request: rt::Option<&Request>, covered: rt::Option<&[u8]>) -> rt::Result<(), rt::DecodeError> {
                ResponseView::decode_over(frame, request, covered).map(|_| ())
            }
        }
    } else {
        quote! {
            #[inline]
            fn response_decodes(frame: &[u8], request: rt::Option<&Request>, _covered: rt::Option<&[u8]>) -> rt::Result<(), rt::DecodeError> {
                ResponseView::decode_for(frame, request).map(|_| ())
            }
        }
    };
    let both_ways = both_ways_check(p);
    let may_decode = request_may_decode(p);
    let views =
        if no_view(p, Direction::Request).is_none() || no_view(p, Direction::Response).is_none() {
            quote!(
                const VIEWS: bool = true;
            )
        } else {
            quote!()
        };
    (
        views,
        quote!(#request_decodes #response_decodes #both_ways #may_decode),
    )
}

/// `request_may_decode`, where requests have a view whose framing checks are only
/// `rt::check_frame` (no sync byte, length field or preamble) and a request's shortest frame
/// reaches past its address and holds its checksum and end bytes: for a frame of a request's
/// length bounds, the view's `dispatch` (what its decoder checks after the framing, which the
/// framing's failing would not make pass). Otherwise the trait's default (`true`).
fn request_may_decode(p: &Protocol) -> TokenStream {
    use super::dispatch::{address_at, frame_bounds, length_check, syncs};
    if no_view(p, Direction::Request).is_some() || p.framing.preamble.is_some() {
        return quote!();
    }
    let (min, max) = frame_bounds(p, Direction::Request);
    if min <= address_at(p, Direction::Request)
        || min < p.framing.trailer_len_of(Direction::Request)
    {
        return quote!();
    }
    // Only the frame check (no sync sequence, length field or message without a checksum):
    // `dispatch` then relies on nothing but the frame's length bounds.
    let d = Direction::Request;
    if !syncs(p, d).is_empty()
        || !length_check(p, d).is_empty()
        || p.framed(d).iter().any(|m| m.unchecked)
    {
        return quote!();
    }
    let (min, max) = (usize_lit(min), usize_lit(max));
    quote! {
        #[inline]
        fn request_may_decode(frame: &[u8]) -> bool {
            !(#min..=#max).contains(&frame.len()) || RequestView::dispatch(frame).is_ok()
        }
    }
}

/// `decodes_both_ways`, where both directions have a view, no response needs its request
/// (neither to be told apart nor for its checksum) and both directions' frame checks are the
/// same tokens (the same start, longest frame, address, checksum and length field; no preamble
/// to skip) once each takes the longer of the two directions' shortest frames: a frame at
/// least that long is checked once, then each view's `dispatch` reads its code, which is what
/// each view's decoder does after the same checks. A shorter frame goes through both views'
/// decoders whole, as everywhere else (the trait's default).
fn both_ways_check(p: &Protocol) -> TokenStream {
    use super::dispatch::{address_at, dispatch_groups, frame_bounds, framing_checks};
    let simple = no_view(p, Direction::Request).is_none()
        && no_view(p, Direction::Response).is_none()
        && !p.has_over_request()
        && !p.responses.iter().any(|m| m.needs_request)
        && p.framing.preamble.is_none();
    if !simple {
        return quote!();
    }
    let (q, r) = (
        frame_bounds(p, Direction::Request).0,
        frame_bounds(p, Direction::Response).0,
    );
    // The frame checks refuse every frame of a direction whose shortest frame does not
    // reach past its address or hold its checksum and end bytes, whatever its length: such a
    // direction's checks are not the other's for any frame.
    let lies =
        |d: Direction, min: usize| min <= address_at(p, d) || min < p.framing.trailer_len_of(d);
    if lies(Direction::Request, q) || lies(Direction::Response, r) {
        return quote!();
    }
    // Past both shortest frames, the shortest frame plays no part in the checks.
    let min = q.max(r);
    let checks = framing_checks(p, Direction::Request, Some(min));
    if checks.to_string() != framing_checks(p, Direction::Response, Some(min)).to_string() {
        return quote!();
    }
    let shorter = if q == r {
        quote!()
    } else {
        let min = usize_lit(min);
        quote! {
            if frame.len() < #min {
                Self::request_decodes(frame)?;
                return rt::Ok(matches!(
                    Self::response_decodes(frame, rt::None, rt::None),
                    rt::Ok(()) | rt::Err(rt::DecodeError::Ambiguous { .. })
                ));
            }
        }
    };
    let no_request = if dispatch_groups(p, Direction::Response).is_empty() {
        quote!()
    } else {
        quote!(, rt::None)
    };
    quote! {
        #[inline]
        fn decodes_both_ways(frame: &[u8]) -> rt::Result<bool, rt::DecodeError> {
            #shorter
            #checks
            RequestView::dispatch(frame)?;
            rt::Ok(matches!(
                ResponseView::dispatch(frame #no_request),
                rt::Ok(_) | rt::Err(rt::DecodeError::Ambiguous { .. })
            ))
        }
    }
}

/// `candidate`, where the code is one or two bytes, there is more than one frame length and no
/// variable-length message (otherwise the trait's default, which says "ask `candidates`"): the
/// frames a whole head's start byte and code fix, as [`candidate_cell`] says it, by table
/// lookup. One code byte: a table of 256 cells. Two: one table of the first byte's row, the
/// second byte's class (bytes whose column is the same for every first byte share one) and the
/// cells, rows and classes deduplicated, so the cells are few. Byte strings (a cell is two
/// bytes, low first), so a table takes one line in the generated code.
pub(super) fn emit_candidate(
    shapes: &[(&[u8], u128)],
    lengths: &[usize],
    code_at: usize,
    start_check: TokenStream,
) -> TokenStream {
    let depth = shapes.iter().map(|s| s.0.len()).max().unwrap_or(0);
    // With one frame length the stream decoder's mask walk is one test already, which the
    // lookup does not beat (SD: 132.6 instructions a frame with the mask, 146.1 with it).
    if lengths.len() < 2 {
        return quote!();
    }
    if !(1..=2).contains(&depth) {
        return quote!();
    }
    let cells = head_cells(shapes, depth, lengths);
    let bytes = |v: &[u16]| {
        let b: Vec<u8> = v.iter().flat_map(|c| c.to_le_bytes()).collect();
        Literal::byte_string(&b)
    };
    let (at, next) = (usize_lit(code_at), usize_lit(code_at + 1));
    let lookup = match depth {
        1 => {
            let table = bytes(&cells);
            quote! {
                static CELLS: [u8; 512] = *#table;
                match head.get(#at) {
                    rt::Some(&b) => {
                        let i = 2 * b as usize;
                        rt::Candidate(u16::from_le_bytes([CELLS[i], CELLS[i + 1]]))
                    }
                    rt::None => rt::Candidate::MANY,
                }
            }
        }
        2 => {
            let grid: Vec<&[u16]> = cells.chunks(256).collect();
            let mut columns: Vec<Vec<u16>> = Vec::new();
            let class: Vec<u8> = (0..256)
                .map(|b| {
                    let col: Vec<u16> = grid.iter().map(|row| row[b]).collect();
                    index_of(&mut columns, col)
                })
                .collect();
            let mut rows: Vec<Vec<u16>> = Vec::new();
            let row: Vec<u8> = grid
                .iter()
                .map(|r| {
                    let mut by_class = vec![0u16; columns.len()];
                    for (b, &k) in class.iter().enumerate() {
                        by_class[k as usize] = r[b];
                    }
                    index_of(&mut rows, by_class)
                })
                .collect();
            // One table (rows by first byte, classes by second, then the cells), so the
            // stream decoder's loop loads one address, not three (UB2: 148.4 -> 146.4
            // instructions a frame). Where every row starts below 256, a row is its first
            // cell's index and the cells are padded (with MANY) past the largest sum of two
            // bytes, so the index is neither scaled nor checked (146.4 -> 143.4); else
            // padded to a power of two, and the index masked.
            let classes = columns.len();
            let mut cells = rows.concat();
            let (row, index) = if (rows.len() - 1) * classes < 256 {
                cells.resize(511, 0xFFFF);
                let starts = row.iter().map(|&r| r * classes as u8).collect();
                (
                    starts,
                    quote!(TABLE[a as usize] as usize + TABLE[256 + b as usize] as usize),
                )
            } else {
                let size = cells.len().next_power_of_two();
                cells.resize(size, 0xFFFF);
                let (classes, last) = (usize_lit(classes), usize_lit(size - 1));
                let index = quote!((TABLE[a as usize] as usize * #classes + TABLE[256 + b as usize] as usize) & #last);
                (row, index)
            };
            let mut table = row;
            table.extend_from_slice(&class);
            table.extend(cells.iter().flat_map(|c| c.to_le_bytes()));
            let n = usize_lit(table.len());
            let table = Literal::byte_string(&table);
            quote! {
                static TABLE: [u8; #n] = *#table;
                match (head.get(#at), head.get(#next)) {
                    (rt::Some(&a), rt::Some(&b)) => {
                        let i = #index;
                        rt::Candidate(u16::from_le_bytes([TABLE[512 + 2 * i], TABLE[513 + 2 * i]]))
                    }
                    _ => rt::Candidate::MANY,
                }
            }
        }
        _ => return quote!(),
    };
    quote! {
        #[inline]
        fn candidate(head: &[u8]) -> rt::Candidate {
            #start_check
            #lookup
        }
    }
}

/// The cell ([`candidate_cell`]) of every value of the `depth` (1 or 2) code bytes, the first
/// byte most significant: the masks of the shapes whose code is a prefix of those bytes. Each
/// shape marks its block of cells, so the work is the shapes plus the cells, not their product.
pub(super) fn head_cells(shapes: &[(&[u8], u128)], depth: usize, lengths: &[usize]) -> Vec<u16> {
    let mut masks = vec![0u128; 1 << (8 * depth)];
    for (code, mask) in shapes {
        let code = &code[..code.len().min(depth)];
        let block = 1usize << (8 * (depth - code.len()));
        let start = code.iter().fold(0usize, |a, &b| a << 8 | usize::from(b)) * block;
        for m in &mut masks[start..start + block] {
            *m |= mask;
        }
    }
    // Neighbouring cells mostly share their mask (none at all, above all): worked out once.
    let mut last = (0u128, candidate_cell(0, lengths));
    masks
        .into_iter()
        .map(|mask| {
            if mask != last.0 {
                last = (mask, candidate_cell(mask, lengths));
            }
            last.1
        })
        .collect()
}

/// The index of `v` in `all`, added if new (at most 256 distinct: one per byte value).
pub(super) fn index_of<T: PartialEq>(all: &mut Vec<Vec<T>>, v: Vec<T>) -> u8 {
    let i = all.iter().position(|x| *x == v).unwrap_or_else(|| {
        all.push(v);
        all.len() - 1
    });
    i as u8
}

/// A candidate mask (bit i requests, 64 + i responses, of `lengths[i]`, longest first) as the
/// runtime's `Candidate`: up to two frames, the longer in the low byte, each its length (below
/// 127) with bit 7 for a response; 0 for none; 0xFFFF for more, or a length of both
/// directions. The rule of `Candidate::of`.
pub(super) fn candidate_cell(mask: u128, lengths: &[usize]) -> u16 {
    let mut slots = 0u16;
    let mut n = 0;
    for (i, &len) in lengths.iter().enumerate().take(64) {
        let (q, r) = (mask >> i & 1 != 0, mask >> (64 + i) & 1 != 0);
        if q && r || (q || r) && (n == 2 || len == 0 || len >= 127) {
            return 0xFFFF;
        }
        if q || r {
            slots |= u16::from(len as u8 | if r { 0x80 } else { 0 }) << (8 * n);
            n += 1;
        }
    }
    slots
}

/// `variable_candidates`, where a message has a repeated field whose length a length field or
/// a count field gives (none otherwise: the trait's default, which costs the stream decoder
/// nothing): per direction, the length the head's field gives for the messages whose code
/// agrees with it (`rt::var_by_length`, `rt::var_by_count`). `start_check` returns early
/// where the head's start bytes are not the protocol's.
pub(super) fn emit_variable_candidates(p: &Protocol, start_check: TokenStream) -> TokenStream {
    // A list to the end is framed by its listed lengths, but where end bytes alone delimit
    // the frame: its length is up to their first appearance (`rt::CountBy::Delimited`).
    let counted = |m: &&Message| {
        m.is_variable()
            && (m.repeats().all(|(_, _, r)| r.count != Count::ToEnd)
                || m.delimited_list(&p.framing).is_some())
    };
    let mut any = false;
    let mut per = Vec::new();
    for d in [Direction::Request, Direction::Response] {
        // A message's code and the constants that lead its payload: what tells code-less
        // messages (and messages sharing a code) apart before their count is read.
        let code = |m: &Message| {
            // As they travel (`framing.transform`).
            let lead = m
                .leading_constants()
                .into_iter()
                .map(|b| match &p.framing.transform {
                    Some(t) => t.apply(b),
                    None => b,
                });
            let (at, lead_at) = (usize_lit(m.layout.code), usize_lit(m.layout.payload));
            let code = m.code.iter().map(|b| hex_u8(*b));
            let lead = lead.map(hex_u8);
            quote!(rt::Fixed { code_at: #at, code: &[#(#code),*], lead_at: #lead_at, lead: &[#(#lead),*] })
        };
        let rule = p.framing.length_rule(d).filter(|r| r.grows);
        let value = match rule {
            Some(rule) => {
                let shapes: Vec<TokenStream> = p
                    .messages(d)
                    .iter()
                    .filter(|m| m.is_variable())
                    .map(|m| {
                        let fixed = code(m);
                        let (lo, hi) = (usize_lit(m.min_len()), usize_lit(m.max_len));
                        quote!((#fixed, #lo, #hi))
                    })
                    .collect();
                if shapes.is_empty() {
                    quote!(rt::VarLen::NONE)
                } else {
                    let (at, width) = (usize_lit(rule.at), usize_lit(rule.width));
                    let le = p.byte_order == ByteOrder::Little;
                    let excess = Literal::i64_unsuffixed(-rule.k);
                    quote!(rt::var_by_length(head, &[#(#shapes),*], rt::LengthField {
                        at: #at, width: #width, le: #le, excess: #excess, min: 0, max: 0
                    }))
                }
            }
            None => {
                // Messages with several lists or fields after one (`rt::Lists`) need
                // `var_by_counts`; a direction without them keeps `var_by_count`.
                let many = p.messages(d).iter().filter(counted).any(has_lists);
                let shapes: Vec<TokenStream> = p
                    .messages(d)
                    .iter()
                    .filter(counted)
                    .map(|m| {
                        let fixed = code(m);
                        match (many, has_lists(m)) {
                            (false, _) => {
                                let r = repeat_const(m);
                                quote!((#fixed, #r.count_len()))
                            }
                            (true, false) => {
                                let r = repeat_const(m);
                                quote!((#fixed, rt::Counted::One(#r)))
                            }
                            (true, true) => {
                                let c = lists_const(m);
                                quote!((#fixed, rt::Counted::Many(#c)))
                            }
                        }
                    })
                    .collect();
                if shapes.is_empty() {
                    quote!(rt::VarLen::NONE)
                } else if many {
                    quote!(rt::var_by_counts(head, &[#(#shapes),*]))
                } else {
                    quote!(rt::var_by_count(head, const { &[#(#shapes),*] }))
                }
            }
        };
        any |= value.to_string() != quote!(rt::VarLen::NONE).to_string();
        per.push(value);
    }
    if !any {
        return quote!();
    }
    let (requests, responses) = (&per[0], &per[1]);
    // Start bytes by direction: a direction whose start bytes the head does not have has no
    // candidate (`start_check`'s early return reads both flags).
    let by_direction =
        p.framing.sync_by_direction() && p.framing.head(Direction::Request, 1).start.is_some();
    let none = quote!(rt::VarLen::NONE).to_string();
    let only_if = |agree: TokenStream, v: &TokenStream| {
        if by_direction && v.to_string() != none {
            quote!(if #agree { #v } else { rt::VarLen::NONE })
        } else {
            quote!(#v)
        }
    };
    let (requests, responses) = (
        only_if(quote!(requests_agree), requests),
        only_if(quote!(responses_agree), responses),
    );
    quote! {
        #[inline]
        fn variable_candidates(head: &[u8]) -> rt::VarLens {
            #start_check
            rt::VarLens { requests: #requests, responses: #responses }
        }
    }
}

/// The byte at `at` of the buffered head, if it is there.
pub(super) fn head_byte(at: usize) -> TokenStream {
    if at == 0 {
        return quote!(head.first());
    }
    let at = usize_lit(at);
    quote!(head.get(#at))
}

/// The candidate masks by code bytes as flat `match` arms over the `depth` code bytes, most
/// specific first: `None` where a byte is not yet buffered (every shape with the prefix so far
/// remains), `Some(b)` per next code byte, and `Some(_)` for shapes whose code already ended
/// (they match whatever follows). `extra` holds the shapes that ended above.
pub(super) fn flat_trie(
    shapes: &[(&[u8], u128)],
    at: usize,
    depth: usize,
    prefix: &mut Vec<TokenStream>,
    extra: u128,
    arms: &mut Vec<(Vec<TokenStream>, u128)>,
) {
    let all = shapes.iter().fold(extra, |a, s| a | s.1);
    let ended = shapes
        .iter()
        .filter(|s| s.0.len() == at)
        .fold(extra, |a, s| a | s.1);
    let mut next: Vec<u8> = shapes.iter().filter_map(|s| s.0.get(at).copied()).collect();
    next.sort_unstable();
    next.dedup();
    let rest = |p: &[TokenStream], first: TokenStream| {
        let mut v = p.to_vec();
        v.push(first);
        v.resize(depth, quote!(_));
        v
    };
    if next.is_empty() {
        arms.push((rest(prefix, quote!(_)), all));
        return;
    }
    arms.push((rest(prefix, quote!(rt::None)), all));
    for b in next {
        let below: Vec<(&[u8], u128)> = shapes
            .iter()
            .filter(|s| s.0.get(at) == Some(&b))
            .copied()
            .collect();
        let lit = hex_u8(b);
        prefix.push(quote!(rt::Some(#lit)));
        flat_trie(&below, at + 1, depth, prefix, ended, arms);
        prefix.pop();
    }
    if ended != 0 {
        arms.push((rest(prefix, quote!(_)), ended));
    }
}

/// A candidate mask as a hex literal, so its bits can be read.
pub(super) fn mask_lit(v: u128) -> TokenStream {
    let lit = Literal::u128_unsuffixed(v);
    format!("{v:#x}").parse().unwrap_or_else(|_| quote!(#lit))
}

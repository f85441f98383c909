use super::*;

pub(super) fn emit_header(p: &Protocol, source: &str, spec_path: &str) -> TokenStream {
    let d = &p.document;
    let title = &d.title;
    let revision = &d.revision;
    let date = &d.date;
    let spec_sha256 = &p.spec_sha256;
    let name = &p.name;
    // Escaped frames: buffers hold the worst case on the wire.
    let max_req = p.max_wire_len(Direction::Request);
    let max_resp = p.max_wire_len(Direction::Response);
    let max = p.longest_wire();
    let (max_req, max_resp, max) = (usize_lit(max_req), usize_lit(max_resp), usize_lit(max));
    let escaping = emit_escaping(p);
    let preamble = preamble_const(p);
    let transform = transform_const(p);
    let form = form_const(p);
    let long = long_const(p);
    let truncation = truncation_const(p);
    let lengths = length_field_consts(p);
    let inner = inner_doc(&format!(
        "{} (`{}`).\n\nGenerated from `{source}`, transcribed from *{title}*, revision {revision} ({date}).\nNumbers travel {} on the wire.\n{}",
        p.title,
        name,
        if p.byte_order == ByteOrder::Little { "little-endian" } else { "big-endian" },
        views_doc(p)
    ));
    let (lo, hi) = (hex_u8(p.framing.address.min), hex_u8(p.framing.address.max));
    let byte = |v: Option<u8>| match v {
        Some(b) => {
            let b = hex_u8(b);
            quote!(rt::Some(#b))
        }
        None => quote!(rt::None),
    };
    let broadcast = byte(p.framing.address.broadcast);
    let host = byte(p.framing.address.host);
    // Start bytes that differ by direction are checked by each direction's `decode` alone.
    let start = match (p.framing.head(Direction::Request, 1).start, p.framing.start) {
        _ if starts_by_direction(p)
            || p.framing.head(Direction::Request, 1).start_again.is_some() =>
        {
            quote!(rt::None)
        }
        (Some(at), Some(s)) => {
            let (at, s) = (usize_lit(at), hex_u8(s));
            quote!(rt::Some((#at, #s)))
        }
        _ => quote!(rt::None),
    };
    let checksum_len = usize_lit(p.framing.checksum.len());
    let end = p.framing.end.iter().map(|b| hex_u8(*b));
    let end_first = p.framing.end_first();
    // A checksum before the bytes it covers (SBF's CRC at offset 2): where it sits.
    let lead = match p.framing.checksum.lead {
        Some(at) => {
            let at = usize_lit(at);
            quote!(rt::Some(#at))
        }
        None => quote!(rt::None),
    };
    let addressed = p.framing.has_address();
    // A layout per direction with the address in one direction only: the other direction's
    // frames are checked and encoded as a protocol's without addresses.
    let unaddressed = if addressed
        && [Direction::Request, Direction::Response]
            .iter()
            .any(|d| !p.framing.has_address_in(*d))
    {
        quote! {
            /// What every frame of the direction whose layout has no address shares.
            const FRAME_UNADDRESSED: rt::Frame = rt::Frame {
                addressed: false,
                devices: (0, 0),
                broadcast: rt::None,
                host: rt::None,
                ..FRAME
            };
        }
    } else {
        quote!()
    };
    // End bytes in requests only (responses without start or end bytes, F.Port's uplink):
    // a response's frames are checked and sealed without them.
    let response_frame = if p.framing.end_by_direction() {
        let d = Direction::Response;
        let end = p.framing.end_of(d).iter().map(|b| hex_u8(*b));
        let end_first = p.framing.end_first_of(d);
        let base = frame_of(p, Direction::Request);
        let base = if p.framing.has_address() && !p.framing.has_address_in(d) {
            quote!(FRAME_UNADDRESSED)
        } else {
            base
        };
        quote! {
            /// What every response shares, where its end bytes are not the requests'.
            const RESPONSE_FRAME: rt::Frame = rt::Frame {
                end: &[#(#end),*],
                end_first: #end_first,
                ..#base
            };
        }
    } else {
        quote!()
    };
    let checksum_be = p.framing.checksum.byte_order == ByteOrder::Big;
    let baud = p.serial.baud;
    let optional = |v: Option<u32>| match v {
        Some(v) => quote!(rt::Some(#v)),
        None => quote!(rt::None),
    };
    let gap = optional(p.serial.inter_frame_gap_ms);
    let rate = optional(p.serial.frame_rate.as_ref().map(|r| r.max_per_s));
    quote! {
        #inner
        // Generated code is uniform across specs: a cast that is the identity for one field
        // width, a conversion to `u32` of a 32-bit checksum, a `match` with one message (or
        // one that binds one), a `_` arm after arms that happen to cover every message, an
        // identity in a scale, a head a protocol without codes does not look at, `{ .. }` on
        // a message without fields, a code at offset 0 read as `get(0)` like any other offset,
        // the code after a `match` on a direction without messages (no reply to any command).
        #![allow(
            clippy::get_first,
            clippy::unnecessary_cast,
            clippy::useless_conversion,
            clippy::single_match,
            clippy::match_single_binding,
            clippy::identity_op,
            clippy::unneeded_struct_pattern,
            unreachable_patterns,
            unreachable_code,
            unused_variables
        )]
        /// The protocol's name in the spec.
        pub const PROTOCOL: &str = #name;
        /// The vendor document this module was generated from.
        pub const DOCUMENT: &str = #title;
        /// The document's revision.
        pub const DOCUMENT_REVISION: &str = #revision;
        /// The document's date.
        pub const DOCUMENT_DATE: &str = #date;
        /// SHA-256 of the spec file this module was generated from, lowercase hex (`sha256sum`).
        pub const SPEC_SHA256: &str = #spec_sha256;
        /// The spec's text, exactly as this module was generated from it.
        pub const SPEC_YAML: &str = include_str!(#spec_path);
        /// The longest request frame, in bytes.
        pub const MAX_REQUEST_LEN: usize = #max_req;
        /// The longest response frame, in bytes.
        pub const MAX_RESPONSE_LEN: usize = #max_resp;
        /// The longest frame in either direction: a buffer this long holds any frame.
        pub const MAX_FRAME_LEN: usize = #max;
        /// The document's baud rate.
        pub const BAUD: u32 = #baud;
        /// The quiet time the document demands between frames, in milliseconds, if it says.
        pub const INTER_FRAME_GAP_MS: rt::Option<u32> = #gap;
        /// The most frames per second the document allows, if it says.
        pub const MAX_FRAMES_PER_S: rt::Option<u32> = #rate;
        /// Device addresses, inclusive.
        pub const DEVICE_ADDRESSES: rt::RangeInclusive<u8> = #lo..=#hi;
        /// The broadcast address, if the protocol has one.
        pub const BROADCAST_ADDRESS: rt::Option<u8> = #broadcast;
        /// The host's own address, if the spec gives one.
        pub const HOST_ADDRESS: rt::Option<u8> = #host;
        pub use ::busspec_runtime::Decoded;
        use ::busspec_runtime::codec as rt;
        /// What every frame shares, for the runtime's frame checks.
        const FRAME: rt::Frame = rt::Frame {
            start: #start,
            addressed: #addressed,
            devices: (#lo, #hi),
            broadcast: BROADCAST_ADDRESS,
            host: HOST_ADDRESS,
            checksum_len: #checksum_len,
            checksum_be: #checksum_be,
            end: &[#(#end),*],
            end_first: #end_first,
            lead: #lead,
        };
        #unaddressed
        #response_frame
        #escaping
        #preamble
        #transform
        #long
        #form
        #truncation
        #lengths
    }
}

/// `PREAMBLE`, where the framing has wake-up bytes.
fn preamble_const(p: &Protocol) -> Option<TokenStream> {
    p.framing.preamble.as_ref().map(|pre| {
        let (byte, send, max) = (hex_u8(pre.byte), pre.send, pre.max);
        quote! {
            /// The wake-up bytes sent before every frame (`framing.preamble`): `send` of
            /// them are written, 0 to `max` taken.
            pub const PREAMBLE: rt::Preamble = rt::Preamble { byte: #byte, send: #send, max: #max };
        }
    })
}

/// `TRANSFORM`, where the payload travels transformed.
fn transform_const(p: &Protocol) -> Option<TokenStream> {
    p.framing.transform.as_ref().map(|t| {
        let kind = match t.kind {
            TransformKind::Add(k) => {
                let k = hex_u8(k);
                quote!(rt::Transform::Add(#k))
            }
            TransformKind::Xor(k) => {
                let k = hex_u8(k);
                quote!(rt::Transform::Xor(#k))
            }
        };
        quote! {
            /// The per-byte transform of every payload byte as it travels
            /// (`framing.transform`): undone before fields are read, done before the checksum
            /// is computed.
            pub const TRANSFORM: rt::Transform = #kind;
        }
    })
}

/// Each direction's length rule as the runtime's forms take it: `(k, shortest, longest)`
/// where the length field grows with the frame.
fn length_rules(p: &Protocol) -> [TokenStream; 2] {
    [Direction::Request, Direction::Response].map(|d| {
        match (
            p.framing.length_rule(d).filter(|r| r.grows),
            p.frame_len_bounds(d),
        ) {
            (Some(r), Some((lo, hi))) => {
                let k = Literal::i64_unsuffixed(r.k);
                let (lo, hi) = (usize_lit(lo.max(r.head_len)), usize_lit(hi));
                quote!(rt::Some((#k, #lo, #hi)))
            }
            _ => quote!(rt::None),
        }
    })
}

/// `FORM`, where the frame has a short form (`framing.forms`).
fn form_const(p: &Protocol) -> Option<TokenStream> {
    p.framing.form.as_ref().map(|f| {
        let (start, long_start) = (hex_u8(f.start), hex_u8(f.long_start));
        let (start_at, at) = (usize_lit(f.start_at), usize_lit(f.at));
        let fill = f.fill.iter().map(|b| hex_u8(*b));
        let (length_at, width) = (usize_lit(f.length_at), usize_lit(f.width));
        let le = p.byte_order == ByteOrder::Little;
        let most = Literal::i64_unsuffixed(f.most);
        let laid_len = usize_lit(f.laid_len);
        let [rq, rs] = length_rules(p);
        quote! {
            /// The short form of the frame (`framing.forms`): frames starting with its start
            /// byte lack the parts it drops and carry an empty payload. Decoding lays every
            /// frame out in the framing's own layout; encoding sends a frame with an empty
            /// payload short.
            pub const FORM: rt::ShortForm = rt::ShortForm {
                start: #start,
                long_start: #long_start,
                start_at: #start_at,
                at: #at,
                fill: &[#(#fill),*],
                length_at: #length_at,
                width: #width,
                le: #le,
                most: #most,
                laid_len: #laid_len,
                rules: [#rq, #rs],
            };
        }
    })
}

/// `LONG`, where the start byte chooses the length field's width (`framing.length.long`).
fn long_const(p: &Protocol) -> Option<TokenStream> {
    p.framing.long.as_ref().map(|l| {
        let (start, short_start) = (hex_u8(l.start), hex_u8(l.short_start));
        let (start_at, length_at) = (usize_lit(l.start_at), usize_lit(l.length_at));
        let (short_width, width) = (usize_lit(l.short_width), usize_lit(l.width));
        let le = p.byte_order == ByteOrder::Little;
        let [rq, rs] = length_rules(p);
        quote! {
            /// The long form of the length field (`framing.length.long`): frames starting with
            /// its start byte carry the wider length field. Decoding lays every frame out in
            /// its width; encoding sends the long form only where the length does not fit the
            /// short one.
            pub const LONG: rt::LongLength = rt::LongLength {
                start: #start,
                short_start: #short_start,
                start_at: #start_at,
                length_at: #length_at,
                short_width: #short_width,
                width: #width,
                le: #le,
                rules: [#rq, #rs],
            };
        }
    })
}

/// `TRUNCATION`, where payloads travel without their trailing zeros.
fn truncation_const(p: &Protocol) -> Option<TokenStream> {
    p.framing.truncation.map(|_| {
        let code_len = p.framing.request.code_lengths.first().copied().unwrap_or(0);
        let head = p.framing.head(Direction::Request, code_len);
        let rule = p.framing.length_rule(Direction::Request);
        let start_at = match head.start {
            Some(at) => {
                let at = usize_lit(at);
                quote!(rt::Some(#at))
            }
            None => quote!(rt::None),
        };
        let sync = p.framing.sync.iter().map(|b| hex_u8(*b));
        let response_sync = p.framing.response_sync.iter().map(|b| hex_u8(*b));
        let length_at = usize_lit(head.length.unwrap_or(0));
        let width = usize_lit(p.framing.length.as_ref().map_or(1, |l| l.width));
        let le = p.byte_order == ByteOrder::Little;
        let k = Literal::i64_unsuffixed(rule.map_or(0, |r| r.k));
        let (code_at, code_len_lit, payload_at) = (
            usize_lit(head.code),
            usize_lit(code_len),
            usize_lit(head.payload),
        );
        // Each code once, its payload's length and the directions that have it.
        let mut codes: Vec<(u32, usize, u8)> = Vec::new();
        for (d, bit) in [(Direction::Request, 1u8), (Direction::Response, 2)] {
            for m in p.framed(d) {
                let code = m.code.iter().fold(0u32, |a, b| a << 8 | u32::from(*b));
                match codes.iter_mut().find(|(c, _, _)| *c == code) {
                    Some((_, _, dirs)) => *dirs |= bit,
                    None => codes.push((code, m.payload_len, bit)),
                }
            }
        }
        let entries = codes.iter().map(|(c, n, d)| {
            let c = hex_lit(u64::from(*c));
            let n = usize_lit(*n);
            let d = Literal::u8_unsuffixed(*d);
            quote!((#c, #n, #d))
        });
        quote! {
            /// Payload truncation (`framing.truncation: trailing_zeros`): a payload's trailing
            /// zero bytes are stripped as it travels (one byte kept); decoding pads it with
            /// zeros up to its message's length.
            pub const TRUNCATION: rt::Truncation = rt::Truncation {
                start_at: #start_at,
                sync: &[#(#sync),*],
                response_sync: &[#(#response_sync),*],
                length_at: #length_at,
                width: #width,
                le: #le,
                k: #k,
                code_at: #code_at,
                code_len: #code_len_lit,
                payload_at: #payload_at,
                payloads: &[#(#entries),*],
            };
        }
    })
}

/// Whether each direction's decode checks its own start bytes where its layout puts them
/// (`FRAME.start` is `None`): start bytes that differ by direction, or a layout per direction.
pub(super) fn starts_by_direction(p: &Protocol) -> bool {
    p.framing.sync_by_direction() || p.framing.layout_by_direction()
}

/// The frame constant direction `d`'s encode seals by (its checksum and end bytes): `FRAME`,
/// or a response's `RESPONSE_FRAME` where the end bytes differ by direction.
pub(super) fn seal_frame_of(p: &Protocol, d: Direction) -> TokenStream {
    if p.framing.end_by_direction() && d == Direction::Response {
        quote!(RESPONSE_FRAME)
    } else {
        quote!(FRAME)
    }
}

/// The frame checks a direction's decode and encode take: `FRAME`, or where the direction's
/// layout has no address beside one that has, `FRAME_UNADDRESSED`; a response's
/// `RESPONSE_FRAME` where the end bytes differ by direction.
pub(super) fn frame_of(p: &Protocol, d: Direction) -> TokenStream {
    if p.framing.end_by_direction() && d == Direction::Response {
        quote!(RESPONSE_FRAME)
    } else if p.framing.has_address() && !p.framing.has_address_in(d) {
        quote!(FRAME_UNADDRESSED)
    } else {
        quote!(FRAME)
    }
}

/// A sum, XOR or Fletcher checksum (masked or not): its doc line, type and expression over
/// `bytes`; `None` for a CRC, and for no checksum.
pub(super) fn sum_checksum(a: &ChecksumAlgorithm) -> Option<(String, TokenStream, TokenStream)> {
    let (doc, ty, e) = match a {
        ChecksumAlgorithm::Sum8 => (
            "8-bit sum of every byte before it",
            quote!(u8),
            quote!(rt::sum8(bytes)),
        ),
        ChecksumAlgorithm::Sum8OnesComplement => (
            "the 8-bit sum of the bytes it covers, inverted",
            quote!(u8),
            quote!(rt::sum8_ones(bytes)),
        ),
        ChecksumAlgorithm::Sum8TwosComplement => (
            "the 8-bit sum of the bytes it covers, negated",
            quote!(u8),
            quote!(rt::sum8_twos(bytes)),
        ),
        ChecksumAlgorithm::Sum8EndAround => (
            "the 8-bit sum of the bytes it covers, each carry added back in, inverted",
            quote!(u8),
            quote!(rt::sum8_end_around(bytes)),
        ),
        ChecksumAlgorithm::Xor8 => (
            "8-bit XOR of the bytes it covers",
            quote!(u8),
            quote!(rt::xor8(bytes)),
        ),
        ChecksumAlgorithm::Sum16 => (
            "16-bit sum of the bytes it covers",
            quote!(u16),
            quote!(rt::sum16(bytes)),
        ),
        ChecksumAlgorithm::Sum16OnesComplement => (
            "the 16-bit sum of the bytes it covers, inverted",
            quote!(u16),
            quote!(!rt::sum16(bytes)),
        ),
        ChecksumAlgorithm::Sum16TwosComplement => (
            "the 16-bit sum of the bytes it covers, negated",
            quote!(u16),
            quote!(rt::sum16(bytes).wrapping_neg()),
        ),
        ChecksumAlgorithm::Fletcher8 => (
            "8-bit Fletcher (modulo 256) of the bytes it covers",
            quote!(u16),
            quote!(rt::fletcher8(bytes)),
        ),
        ChecksumAlgorithm::Fletcher16 => (
            "Fletcher-16 of the bytes it covers",
            quote!(u16),
            quote!(rt::fletcher16(bytes)),
        ),
        ChecksumAlgorithm::Masked(inner, mask) => {
            let (doc, ty, e) = sum_checksum(inner)?;
            let m = Literal::u64_unsuffixed(*mask);
            let doc = format!("{doc}, kept to the bits of 0x{mask:X}");
            return Some((doc, ty.clone(), quote!(#e & (#m as #ty))));
        }
        ChecksumAlgorithm::Complemented(inner, mask) => {
            let (doc, ty, e) = sum_checksum(inner)?;
            let m = Literal::u64_unsuffixed(*mask & 0xFF);
            let doc = format!(
                "{doc}, followed by its bitwise complement kept to the bits of 0x{mask:X} (the value in the high byte)"
            );
            let _ = ty;
            return Some((
                doc,
                quote!(u16),
                quote!({
                    let v: u8 = #e;
                    u16::from(v) << 8 | u16::from(!v & #m)
                }),
            ));
        }
        ChecksumAlgorithm::Crc(_) | ChecksumAlgorithm::None => return None,
    };
    Some((doc.to_owned(), ty, e))
}

/// A sum or XOR over two spans `x` and `y` without copying them (a checksum with bytes on
/// both sides of it, HerkuleX's): each span's sum added (XORed), then masked or complemented
/// as over one. `None` for what the validator refuses over two spans.
pub(super) fn split_checksum(
    a: &ChecksumAlgorithm,
    x: &TokenStream,
    y: &TokenStream,
) -> Option<(TokenStream, TokenStream)> {
    Some(match a {
        ChecksumAlgorithm::Sum8 => (quote!(u8), quote!(rt::sum8(#x).wrapping_add(rt::sum8(#y)))),
        ChecksumAlgorithm::Sum8OnesComplement => {
            (quote!(u8), quote!(!rt::sum8(#x).wrapping_add(rt::sum8(#y))))
        }
        ChecksumAlgorithm::Sum8TwosComplement => (
            quote!(u8),
            quote!(rt::sum8(#x).wrapping_add(rt::sum8(#y)).wrapping_neg()),
        ),
        ChecksumAlgorithm::Sum16OnesComplement => (
            quote!(u16),
            quote!(!rt::sum16(#x).wrapping_add(rt::sum16(#y))),
        ),
        ChecksumAlgorithm::Sum16TwosComplement => (
            quote!(u16),
            quote!(rt::sum16(#x).wrapping_add(rt::sum16(#y)).wrapping_neg()),
        ),
        ChecksumAlgorithm::Xor8 => (quote!(u8), quote!(rt::xor8(#x) ^ rt::xor8(#y))),
        ChecksumAlgorithm::Sum16 => (
            quote!(u16),
            quote!(rt::sum16(#x).wrapping_add(rt::sum16(#y))),
        ),
        ChecksumAlgorithm::Masked(inner, mask) => {
            let (ty, e) = split_checksum(inner, x, y)?;
            let m = Literal::u64_unsuffixed(*mask);
            (ty.clone(), quote!((#e) & (#m as #ty)))
        }
        ChecksumAlgorithm::Complemented(inner, mask) => {
            let (_, e) = split_checksum(inner, x, y)?;
            let m = Literal::u64_unsuffixed(*mask & 0xFF);
            (
                quote!(u16),
                quote!({
                    let v: u8 = #e;
                    u16::from(v) << 8 | u16::from(!v & #m)
                }),
            )
        }
        _ => return None,
    })
}

/// The type [`emit_checksum`]'s `checksum` returns.
fn checksum_type(p: &Protocol) -> TokenStream {
    let c = &p.framing.checksum;
    if let Some((_, ty, _)) = sum_checksum(&c.algorithm) {
        return quote!(#ty);
    }
    match &c.algorithm {
        ChecksumAlgorithm::Crc(_) => {
            let ty = format_ident!("u{}", if c.width == 24 { 32 } else { c.width });
            quote!(#ty)
        }
        _ => quote!(u8),
    }
}

/// The name of the function that tells a frame of direction `d` without a checksum
/// (`checksum: none`) by its code and length ([`emit_unchecked`]).
pub(super) fn unchecked_fn(d: Direction) -> proc_macro2::Ident {
    match d {
        Direction::Request => format_ident!("unchecked_request"),
        Direction::Response => format_ident!("unchecked_response"),
    }
}

/// Messages that travel without a checksum (`checksum: none`): per direction with any, a
/// function that tells such a frame by its code and length, as the interpreter's
/// `Protocol::unchecked` does, and `UNCHECKED`, the frame checks without the checksum.
/// Nothing for other protocols.
pub(super) fn emit_unchecked(p: &Protocol) -> TokenStream {
    if !p.has_unchecked() {
        return quote!();
    }
    let dirs: Vec<Direction> = [Direction::Request, Direction::Response]
        .into_iter()
        .filter(|&d| p.framed(d).iter().any(|m| m.unchecked))
        .collect();
    let fns = dirs.iter().map(|&d| {
        let tests = p.framed(d).iter().filter(|m| m.unchecked).map(|m| {
            let len = usize_lit(m.layout.len);
            if m.code.is_empty() {
                return quote!(frame.len() == #len);
            }
            let (at, end) = (
                usize_lit(m.layout.code),
                usize_lit(m.layout.code + m.code.len()),
            );
            let code = m.code.iter().map(|b| hex_u8(*b));
            quote!(frame.len() == #len && frame.get(#at..#end) == rt::Some(&[#(#code),*]))
        });
        let name = unchecked_fn(d);
        let body = quote!(#(#tests)||*);
        let doc = doc(&format!(
            "Whether `frame` is a {} that travels without a checksum (`checksum: none`), by its code and length.",
            match d {
                Direction::Request => "request",
                Direction::Response => "response",
            }
        ));
        quote! {
            #doc
            #[inline]
            fn #name(frame: &[u8]) -> bool {
                #body
            }
        }
    });
    quote!(#(#fns)*)
}

/// Where a reply's checksum takes in its request's bytes (`checksum_over_request`):
/// `checksum_after`, the checksum over the request's covered bytes and then the reply's own,
/// and `over_request`, which reply a frame is by its code and length (as the interpreter's
/// `Protocol::over_request` finds it). Nothing for other protocols.
pub(super) fn emit_over_request(p: &Protocol) -> TokenStream {
    if !p.has_over_request() {
        return quote!();
    }
    let ty = checksum_type(p);
    let sum = frame_sum(p, Direction::Response);
    let arms = p.framed(Direction::Response).iter().filter_map(|m| {
        let from = usize_lit(m.over_request?);
        let (min, max) = (usize_lit(m.layout.len), usize_lit(m.max_len));
        let (at, end) = (
            usize_lit(m.layout.code),
            usize_lit(m.layout.code + m.code.len()),
        );
        let code = m.code.iter().map(|b| hex_u8(*b));
        let desc = super::desc::message_desc(m);
        Some(quote! {
            if (#min..=#max).contains(&frame.len()) && frame.get(#at..#end) == rt::Some(&[#(#code),*]) {
                return rt::Some((#from, #desc));
            }
        })
    });
    quote! {
        /// The checksum of a reply that takes in its request's bytes
        /// (`checksum_over_request`): over `request`, the bytes the request's checksum
        /// covers, then over the reply's own `bytes`.
        pub fn checksum_after(request: &[u8], bytes: &[u8]) -> #ty {
            let mut all = [0u8; MAX_REQUEST_LEN + MAX_RESPONSE_LEN];
            let q = request.len().min(MAX_REQUEST_LEN);
            let b = bytes.len().min(MAX_RESPONSE_LEN);
            all[..q].copy_from_slice(&request[..q]);
            all[q..q + b].copy_from_slice(&bytes[..b]);
            checksum(&all[..q + b])
        }
        /// The reply whose checksum takes in its request's bytes that a frame of `frame`'s
        /// length and code is, and where in it its checksum takes up its own bytes; `None`
        /// for every other frame (no other message shares a code and a length with one).
        fn over_request(frame: &[u8]) -> rt::Option<(usize, &'static rt::MessageDesc)> {
            #(#arms)*
            rt::None
        }
        /// The checksum of a response frame, as the frame checks take it
        /// (`RESPONSE_CHECKS.check_with`): over the request's bytes `covered` first where the frame
        /// is a reply that takes them in, refused without them.
        #[inline]
        fn response_sum(frame: &[u8], b: &[u8], covered: rt::Option<&[u8]>) -> rt::Result<u32, rt::DecodeError> {
            match over_request(frame) {
                rt::None => rt::Ok(#sum(b)),
                rt::Some((from, message)) => match covered {
                    rt::Some(q) => rt::Ok(u32::from(checksum_after(q, rt::covered(b, from)))),
                    rt::None => rt::Err(rt::DecodeError::NeedsRequest { message, offset: b.len() }),
                },
            }
        }
    }
}

pub(super) fn emit_checksum(p: &Protocol) -> TokenStream {
    let c = &p.framing.checksum;
    if let Some((doc, ty, e)) = sum_checksum(&c.algorithm) {
        // The doc lines of the four 8-bit sums are those of the generated code before masks
        // and 16-bit sums came.
        let d = format!(" The frame checksum: {doc}.");
        return quote! {
            #[doc = #d]
            #[inline]
            pub fn checksum(bytes: &[u8]) -> #ty {
                #e
            }
        };
    }
    match &c.algorithm {
        ChecksumAlgorithm::None => quote! {
            /// Frames carry no checksum: nothing to compute.
            #[inline]
            pub fn checksum(_bytes: &[u8]) -> u8 {
                0
            }
        },
        ChecksumAlgorithm::Crc(k) => {
            // A 24-bit CRC is computed in a `u32`.
            let bits = if c.width == 24 { 32 } else { c.width };
            let ty = format_ident!("u{}", bits);
            let (w, poly, init, refin, refout, xorout, check) = (
                k.width as usize,
                k.poly,
                k.init,
                k.refin,
                k.refout,
                k.xorout,
                c.check,
            );
            let lit = |v: u64| {
                lit_u(
                    v,
                    IntType {
                        bits: u32::from(bits),
                        signed: false,
                        float: false,
                    },
                )
            };
            let (poly, init, xorout, check) = (lit(poly), lit(init), lit(xorout), lit(check));
            let checksum_fn = match &c.extra {
                None => quote! {
                    /// The frame checksum over `bytes`.
                    #[inline]
                    pub fn checksum(bytes: &[u8]) -> #ty {
                        CRC.checksum(bytes)
                    }
                },
                Some(e) => {
                    let (at, end) = (
                        usize_lit(e.code_at),
                        usize_lit(e.code_at + e.by_code.first().map_or(0, |c| c.0.len())),
                    );
                    let arms = e.by_code.iter().map(|(code, x)| {
                        let code = code.iter().map(|b| hex_u8(*b));
                        let x = hex_u8(*x);
                        quote!(rt::Some(&[#(#code),*]) => rt::Some(#x),)
                    });
                    quote! {
                        /// The byte of each message's own the checksum takes after the bytes
                        /// it covers (`checksum_extra`), found by the code they hold.
                        pub fn checksum_extra(bytes: &[u8]) -> rt::Option<u8> {
                            match bytes.get(#at..#end) {
                                #(#arms)*
                                _ => rt::None,
                            }
                        }
                        /// The frame checksum over `bytes` and their message's extra byte
                        /// (without one for a code no message has).
                        #[inline]
                        pub fn checksum(bytes: &[u8]) -> #ty {
                            match checksum_extra(bytes) {
                                rt::Some(x) => {
                                    let mut d = CRC.digest();
                                    d.update(bytes);
                                    d.update(&[x]);
                                    d.finalize()
                                }
                                rt::None => CRC.checksum(bytes),
                            }
                        }
                    }
                }
            };
            let name = c.catalogue.clone().unwrap_or_else(|| "CRC".into());
            let d = format!(" {name}: the frame checksum, over every byte before it.");
            quote! {
                #[doc = #d]
                pub const CRC_ALGORITHM: rt::crc::Algorithm<#ty> = rt::crc::Algorithm {
                    width: #w as u8,
                    poly: #poly,
                    init: #init,
                    refin: #refin,
                    refout: #refout,
                    xorout: #xorout,
                    check: #check,
                    residue: 0,
                };
                // A static, not a const: one table in memory. Where `checksum` was not inlined,
                // a const cost 40 % more per 4-byte CRC (BENCHMARKS.md, "What the benches
                // taught the generator").
                static CRC: rt::crc::Crc<#ty> = rt::crc::Crc::<#ty>::new(&CRC_ALGORITHM);
                #checksum_fn
            }
        }
        // Every sum took the path above.
        _ => TokenStream::new(),
    }
}

/// `UNESCAPED_LEN` and `ESCAPING` for a protocol with `framing.escaping` (nothing without).
pub(super) fn emit_escaping(p: &Protocol) -> TokenStream {
    let f = &p.framing;
    if f.escaping.is_none() {
        return quote!();
    }
    let unescaped = usize_lit(p.longest_frame());
    if !f.end_by_direction() {
        let value = escaping_value(p, None);
        return quote! {
            /// The longest frame before escaping: what generated code unescapes into.
            const UNESCAPED_LEN: usize = #unescaped;
            /// How frames are escaped on the wire (`framing.escaping`).
            const ESCAPING: rt::Escaping = #value;
        };
    }
    let (rq, rs) = (
        escaping_value(p, Some(Direction::Request)),
        escaping_value(p, Some(Direction::Response)),
    );
    quote! {
        /// The longest frame before escaping: what generated code unescapes into.
        const UNESCAPED_LEN: usize = #unescaped;
        /// How requests are escaped on the wire (`framing.escaping`, between their start and
        /// end bytes).
        const ESCAPING: rt::Escaping = #rq;
        /// How responses are escaped on the wire (`framing.escaping`, between their own start
        /// and end bytes, or from their first byte to their last where they have none).
        const RESPONSE_ESCAPING: rt::Escaping = #rs;
    }
}

/// The escaping constant direction `d`'s decode and encode take: `ESCAPING`, or where the
/// end bytes differ by direction a response's `RESPONSE_ESCAPING`.
pub(super) fn escaping_of(p: &Protocol, d: Direction) -> TokenStream {
    if p.framing.end_by_direction() && d == Direction::Response {
        quote!(RESPONSE_ESCAPING)
    } else {
        quote!(ESCAPING)
    }
}

/// An `rt::Escaping` value: of both directions (`None`), or of direction `d` alone (its
/// escaped region, start and end bytes, length field and checksum's place; no rule or lengths
/// for the other direction, so that a stream reads each direction's frames by its own).
fn escaping_value(p: &Protocol, only: Option<Direction>) -> TokenStream {
    let f = &p.framing;
    let Some(e) = &f.escaping else {
        return quote!();
    };
    let d0 = only.unwrap_or(Direction::Request);
    let kind = match &e.kind {
        EscapeKind::Bytes { escape, map, .. } => {
            let escape = hex_u8(*escape);
            let pairs = map.iter().map(|(b, r)| {
                let (b, r) = (hex_u8(*b), hex_u8(*r));
                quote!((#b, #r))
            });
            quote!(rt::EscapeKind::Bytes { escape: #escape, map: &[#(#pairs),*] })
        }
        EscapeKind::Insert { after, byte, .. } => {
            let after = after.iter().map(|b| hex_u8(*b));
            let byte = hex_u8(*byte);
            quote!(rt::EscapeKind::Insert { after: &[#(#after),*], byte: #byte })
        }
        EscapeKind::Cobs => quote!(rt::EscapeKind::Cobs),
    };
    let (from, tail) = f.escaped_bounds_of(d0).unwrap_or((0, 0));
    let (from_l, tail) = (usize_lit(from), usize_lit(tail));
    let head = f.head(d0, 0);
    let (sync_at, sync) = match head.start {
        Some(at) => (at, f.sync_of(d0).to_vec()),
        None => (0, Vec::new()),
    };
    let sync_at = usize_lit(sync_at);
    let sync = sync.iter().map(|b| hex_u8(*b));
    // Where the escape byte travels doubled, the end byte after it (DLE ETX's 03).
    let end = if e.kind.doubled().is_some() {
        f.end_of(d0).last()
    } else {
        f.end_of(d0).first()
    };
    let end = hex_u8(end.copied().unwrap_or(0));
    let length = match (&f.length, head.length) {
        (Some(l), Some(at)) => {
            let (at, w, le) = (
                usize_lit(at),
                usize_lit(l.width),
                p.byte_order == ByteOrder::Little,
            );
            quote!(rt::Some((#at, #w, #le)))
        }
        _ => quote!(rt::None),
    };
    let wanted = |d: Direction| only.map_or(true, |o| o == d);
    let rule = |d: Direction| match f.length_rule(d).filter(|r| r.grows && wanted(d)) {
        Some(r) => {
            let (k, h) = (i64_lit(r.k), usize_lit(r.head_len));
            quote!(rt::Some((#k, #h)))
        }
        None => quote!(rt::None),
    };
    let (rq, rs) = (rule(Direction::Request), rule(Direction::Response));
    let bounds = |d: Direction| match p.frame_len_bounds(d).filter(|_| wanted(d)) {
        Some((lo, hi)) => {
            let (lo, hi) = (usize_lit(lo), usize_lit(hi));
            quote!((#lo, #hi))
        }
        None => quote!((usize::MAX, 0)),
    };
    let (bq, bs) = (bounds(Direction::Request), bounds(Direction::Response));
    let computed = e.computed == busspec_model::ir::Computed::Escaped;
    let c = &f.checksum;
    let covers = usize_lit(c.covers_from_of(d0));
    let ck_len = usize_lit(c.len());
    let ck_be = c.byte_order == ByteOrder::Big;
    let from_end = usize_lit(f.checksum_from_end_of(d0));
    quote! {
        rt::Escaping {
            kind: #kind,
            from: #from_l,
            tail: #tail,
            sync_at: #sync_at,
            sync: &[#(#sync),*],
            end: #end,
            length: #length,
            rules: [#rq, #rs],
            lens: [#bq, #bs],
            computed_escaped: #computed,
            covers_from: #covers,
            checksum_len: #ck_len,
            checksum_be: #ck_be,
            checksum_from_end: #from_end,
        }
    }
}

/// Whether `encode` computes the checksum in each arm of its match, over the frame as a
/// fixed-size array, or once after it. A sum-8 in each arm is inlined and folds the constant
/// header bytes (UB2: 36 instructions per frame against 58 after the match); a table CRC in
/// each arm is a call the inliner refuses in a match this large, and costs twice as much as
/// one call site after the match, which it inlines (SD: 138 against 68). Only where the frame
/// ends in its checksum (no end bytes after it).
pub(super) fn checksum_in_arms(p: &Protocol) -> bool {
    matches!(p.framing.checksum.algorithm, ChecksumAlgorithm::Sum8)
        // A reply's checksum over its request's bytes is sealed after the arms.
        && !p.has_over_request()
        // So is every frame's, where a message travels without one.
        && !p.has_unchecked()
        && p.framing.checksum.covers_from == 0
        && p.framing.checksum.response_covers_from == 0
        // A checksum before the bytes it covers is sealed where it sits, after the arms.
        && p.framing.checksum.lead.is_none()
        && p.framing.end.is_empty()
        && p.framing.response_end.is_empty()
        // The sum covers the payload as it travels, transformed after the arms write it.
        && p.framing.transform.is_none()
}

/// The checksum of a frame of direction `d`'s bytes before it, as the runtime's frame checks
/// take it: the name of the function [`emit_frame_sums`] writes, one for both directions
/// (`frame_sum`) where they cover the same bytes.
pub(super) fn frame_sum(p: &Protocol, d: Direction) -> TokenStream {
    if !p.framing.checksum.covers_by_direction() {
        quote!(frame_sum)
    } else if d == Direction::Request {
        quote!(request_frame_sum)
    } else {
        quote!(response_frame_sum)
    }
}

/// The functions [`frame_sum`] names: over the bytes from `covers_from` on where the checksum
/// skips the first (Dynamixel's sync bytes), each direction's own where they differ
/// (`covers_from: {request, response}`).
pub(super) fn emit_frame_sums(p: &Protocol) -> TokenStream {
    let dirs = if p.framing.checksum.covers_by_direction() {
        &[Direction::Request, Direction::Response][..]
    } else {
        &[Direction::Request][..]
    };
    let fns = dirs.iter().map(|&d| {
        let name = frame_sum(p, d);
        // Bytes on both sides of it (HerkuleX's, from the size byte before it): the bytes
        // from `covers_from` up to it, then those after it to the frame's end (the whole
        // frame given, to its end bytes).
        if let (Some(at), true) = (p.framing.checksum.lead, p.framing.covers_around()) {
            let from = p.framing.checksum.covers_from_of(d);
            let after = at + p.framing.checksum.len();
            let (from_lit, at_lit, after_lit) = (usize_lit(from), usize_lit(at), usize_lit(after));
            let (x, y) = (quote!(before), quote!(after));
            let (_, e) = split_checksum(&p.framing.checksum.algorithm, &x, &y)
                .expect("the validator takes only a sum or XOR over two spans");
            let doc = format!(" The checksum a frame carries, as the frame checks compare it: at offset {at}, over the bytes from offset {from} up to it and those after it (from offset {after}) to the frame's end (the whole frame given).");
            return quote! {
                #[doc = #doc]
                #[inline]
                fn #name(bytes: &[u8]) -> u32 {
                    let before = bytes.get(#from_lit..#at_lit).unwrap_or(&[]);
                    let after = bytes.get(#after_lit..).unwrap_or(&[]);
                    u32::from(#e)
                }
            };
        }
        let (doc, covered) = match p.framing.checksum.covers_from_of(d) {
            0 => (
                " The checksum a frame carries, as the frame checks compare it: over every byte before it.".to_string(),
                quote!(bytes),
            ),
            from => {
                let lit = usize_lit(from);
                let over = match p.framing.checksum.lead {
                    Some(at) => format!("at offset {at}: over the bytes after it from offset {from} to the frame's end (the whole frame given)"),
                    None => format!("over the bytes before it from offset {from} on"),
                };
                (
                    format!(" The checksum a frame carries, as the frame checks compare it: {over}."),
                    quote!(rt::covered(bytes, #lit)),
                )
            }
        };
        quote! {
            #[doc = #doc]
            #[inline]
            fn #name(bytes: &[u8]) -> u32 {
                u32::from(checksum(#covered))
            }
        }
    });
    quote!(#(#fns)*)
}

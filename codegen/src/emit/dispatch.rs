use super::*;

/// Where the address of a frame of direction `d` is. Where the code precedes the address, the
/// address sits after a code of this direction's only length; the validator restricts such
/// layouts to one code length. 0 where frames carry no address (the frame checks then do not
/// look at it).
pub(super) fn address_at(p: &Protocol, d: Direction) -> usize {
    let layout = p.framing.layout_of(d);
    if layout.iter().position(|x| *x == Part::Code)
        < layout.iter().position(|x| *x == Part::Address)
    {
        let l = p
            .framing
            .direction(d)
            .code_lengths
            .first()
            .copied()
            .unwrap_or(1);
        p.framing.head(d, l).address.unwrap_or(0)
    } else {
        p.framing.head(d, 1).address.unwrap_or(0)
    }
}

/// The messages of each code, codes in the order their first message comes (spec order), each
/// code's messages in spec order: one pass, so a spec of many codes costs no scan per code.
pub(super) fn messages_by_code(msgs: &[Message]) -> Vec<(&[u8], Vec<&Message>)> {
    let mut index: std::collections::HashMap<&[u8], usize> = std::collections::HashMap::new();
    let mut out: Vec<(&[u8], Vec<&Message>)> = Vec::new();
    for m in msgs {
        let i = *index.entry(m.code.as_slice()).or_insert_with(|| {
            out.push((m.code.as_slice(), Vec::new()));
            out.len() - 1
        });
        out[i].1.push(m);
    }
    out
}

/// `decode` (and, for responses, `decode_reply`): the frame checks shared by every message
/// (`CHECKS.check`, an `rt::FrameChecks`), then `dispatch`, one `match` on the code per code length, each arm
/// decoding its message from the frame as a fixed-size array. Messages sharing a code are
/// told apart by length, then constants (`rt::Group`).
pub(super) fn emit_dispatch(ctx: &Ctx, d: Direction, ty: &TokenStream) -> TokenStream {
    let p = ctx.p;
    // The frame as the decoders take it: a view's lends its lists (`view.rs`).
    let fr = if ctx.view.get() {
        quote!(&'a [u8])
    } else {
        quote!(&[u8])
    };
    // Constant whole frames (`frame:`) are recognised before the framing is checked.
    let msgs = p.framed(d);
    // Messages without a checksum (`checksum: none`, one code length in their direction:
    // validated) are told by their code and length before the frame checks, which then leave
    // the checksum out; every other frame is at least as long as the shortest with one.
    let unchecked = msgs.iter().any(|m| m.unchecked);
    let clen = if unchecked {
        0
    } else {
        p.framing.trailer_len_of(d)
    };
    let (min_len, max_len) = frame_bounds(p, d);
    let replies = d == Direction::Response;
    let codes = code_const(d);
    let unknown = quote!(rt::Err(#codes.unknown(frame)));
    // Code-less messages beside coded ones: the empty code is a prefix of every code, so a
    // frame whose code is known is tried as its coded messages first, then as each code-less
    // one (the interpreter's order: the longest code that matches first), and a frame whose
    // code is unknown as the code-less messages alone.
    let codeless: Vec<&Message> = msgs.iter().filter(|m| m.code.is_empty()).collect();
    let mixed = !codeless.is_empty() && codeless.len() < msgs.len();
    let by_code = messages_by_code(msgs);
    let body = code_matches(ctx, d, &by_code, &codeless, min_len, clen, &unknown);
    let max_len = usize_lit(max_len);
    let mask = reply_mask(p);
    let groups = dispatch_groups(p, d);
    let (request_param, request_arg) = if replies && !groups.is_empty() {
        (quote!(, request: rt::Option<&Request>), quote!(, request))
    } else {
        (quote!(), quote!())
    };
    let settles = groups.iter().any(|g| g.iter().any(|m| is_ambiguous(m, g)));
    let asked = if replies && settles {
        // The responses the request may get, bit i for row i of MESSAGES.
        quote!(let asked: #mask = request.map_or(!0, Request::replies);)
    } else {
        quote!()
    };
    let answered = answered(p, replies);
    let constant = if p.constants(d).next().is_some() {
        quote! {
            if let rt::Some(message) = Self::constant(frame) {
                #answered
                return rt::Ok(Decoded { address: 0, message });
            }
        }
    } else {
        quote!()
    };
    // Wake-up bytes before the frame (`framing.preamble`): offsets count after them.
    let preamble = if p.framing.preamble.is_some() {
        quote!(let frame = PREAMBLE.skip(frame);)
    } else {
        quote!()
    };
    // A transform of the payload (`framing.transform`): the checksum checked on the bytes as
    // they travelled, the fields read from a copy with the transform undone.
    let untransform = if p.framing.transform.is_some() {
        let range = p.framing.transformed(0);
        let (at, trailer) = (usize_lit(range.start), usize_lit(p.framing.trailer_len()));
        quote! {
            let mut plain = [0u8; #max_len];
            let frame = TRANSFORM.undo_into(frame, #at, #trailer, &mut plain);
        }
    } else {
        quote!()
    };
    let framing = framing_checks(p, d, None);
    // A reply whose checksum takes in its request's bytes (`checksum_over_request`).
    let over = replies && p.has_over_request();
    let checks = quote! {
        #constant
        #preamble
        #framing
        #untransform
        let message = Self::dispatch(frame #request_arg)?;
        #answered
        rt::Ok(Decoded { address, message })
    };
    let codeless_fns = if mixed {
        emit_codeless_fns(ctx, &codeless)
    } else {
        quote!()
    };
    // A direction without messages (commands that get no reply: no response at all) knows no
    // code; the frame checks refuse every frame before this is reached.
    let no_message = if msgs.is_empty() {
        unknown.clone()
    } else {
        quote!()
    };
    // The direction's `CodeAt` is defined where a decoder quotes an unknown code with it.
    let name = codes.to_string();
    if body
        .iter()
        .chain([&no_message])
        .any(|t| t.to_string().contains(&name))
    {
        let mut used = ctx.codes_used.get();
        used[usize::from(d == Direction::Response)] = true;
        ctx.codes_used.set(used);
    }
    // The stream decoder's fast path decodes a frame of a length its candidate table gave
    // through a copy of the checks for each length (`Protocol::decode_request_fixed`): the
    // length a constant in each, its bounds, checksum loop and messages' length checks fold.
    // The dispatch is then inlined into every copy and into `decode`, as it is into `decode`
    // alone otherwise (not inlined, it would cost the decoder a call).
    let lens = if ctx.view.get() {
        Vec::new()
    } else {
        super::stream::fixed_lengths(p, d)
    };
    let inline = if lens.is_empty() {
        quote!(#[inline])
    } else {
        quote!(#[inline(always)])
    };
    let dispatch = quote! {
        /// The message of a frame that passed the checks every frame passes, by its code.
        #inline
        fn dispatch(frame: #fr #request_param) -> rt::DecodeResult<Self> {
            #asked
            #(#body)*
            #no_message
        }
        #codeless_fns
    };
    let doc_decode = quote! {
        /// Decodes one whole frame: refuses one longer than the longest, checks its start byte,
        /// checksum and address, then its code, constants, repeated fields, the ranges the
        /// spec gives its fields and the command's broadcast rule.
    };
    // Escaped frames (`framing.escaping`): unescaped into a buffer of the longest frame, then
    // checked as any frame by a function of its own.
    let (checks, unescaped_fn) = if p.framing.escaping.is_some() {
        let sum = frame_sum(p, d);
        let max = usize_lit(p.max_frame_len(d));
        let escaping = escaping_of(p, d);
        let unescape = quote! {
            let mut plain = [0u8; UNESCAPED_LEN];
            let un = rt::unescape_frame(&#escaping, frame, &mut plain, #sum)?;
            let rt::Some(plain) = plain.get(..un.len) else {
                return rt::Err(rt::DecodeError::TooLong { max: #max, found: un.len });
            };
        };
        let own = Own {
            suffix: "unescaped",
            doc: "unescaped",
            frame: quote!(plain),
            locate: quote!(.map_err(|e| un.locate(e))),
        };
        own.decoder(replies, ty, unescape, &checks)
    } else if p.framing.truncation.is_some() {
        // Payload truncation (`framing.truncation`): a truncated frame padded into a copy
        // with its whole payload, checked as any frame by a function of its own; its errors
        // keep their offsets.
        let max = usize_lit(p.max_frame_len(d));
        let sum = super::head::frame_sum(p, d);
        let lay_out = quote! {
            let mut laid = [0u8; #max];
            let laid = TRUNCATION.lay_out(frame, &mut laid, &FRAME, #sum)?;
        };
        let own = Own {
            suffix: "laid_out",
            doc: "with its whole payload",
            frame: quote!(laid),
            locate: quote!(),
        };
        own.decoder(replies, ty, lay_out, &checks)
    } else if p.framing.long.is_some() || p.framing.form.is_some() {
        let lay = if p.framing.form.is_some() {
            quote!(FORM)
        } else {
            quote!(LONG)
        };
        // A length field whose width the start byte chooses (or a short form of the frame,
        // `framing.forms`) (`framing.length.long`): the frame
        // laid out in the long form's width, checked as any frame by a function of its own,
        // its errors placed back on the frame as it travelled.
        let max = usize_lit(p.max_frame_len(d));
        let lay_out = quote! {
            let mut laid = [0u8; #max];
            let (laid, short) = #lay.lay_out(frame, &mut laid)?;
        };
        let own = Own {
            suffix: "laid_out",
            doc: "laid out in the long form's width",
            frame: quote!(laid),
            locate: quote!(.map_err(|e| #lay.locate(e, short))),
        };
        own.decoder(replies, ty, lay_out, &checks)
    } else {
        (checks, quote!())
    };
    let (decode_for_body, over_fns) = if over {
        (
            quote!(Self::decode_over(frame, request, rt::None)),
            quote! {
                /// Decodes a frame as the reply to `request`, whose frame's checksum covered
                /// `covered` (`busspec_runtime::RequestMessage::covered` of it): as
                /// [`Self::decode_reply`], and the checksum of a reply that takes in its
                /// request's bytes (`checksum_over_request`) is checked over them, where
                /// [`Self::decode_reply`] refuses such a reply
                /// ([`busspec_runtime::DecodeError::NeedsRequest`]).
                #[inline]
                pub fn decode_reply_over(frame: #fr, request: &Request, covered: &[u8]) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
                    Self::decode_over(frame, rt::Some(request), rt::Some(covered))
                }
                /// [`Self::decode_for`] with the bytes the request's checksum covered, where
                /// known.
                pub(crate) fn decode_over(frame: #fr, request: rt::Option<&Request>, covered: rt::Option<&[u8]>) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
                    #checks
                }
            },
        )
    } else {
        (checks, quote!())
    };
    let fixed = if lens.is_empty() {
        quote!()
    } else {
        let (inline_fn, each, other) = if replies {
            (
                quote!(decode_for_inline(frame: &[u8], request: rt::Option<&Request>)),
                quote!(decode_for_inline),
                quote!(Self::decode_for(frame, rt::None)),
            )
        } else {
            (
                quote!(decode_inline(frame: &[u8])),
                quote!(decode_inline),
                quote!(Self::decode(frame)),
            )
        };
        let none = if replies {
            quote!(, rt::None)
        } else {
            quote!()
        };
        let arms = lens.iter().map(|l| {
            let l = usize_lit(*l);
            quote!(#l => Self::#each(&frame[..#l] #none),)
        });
        quote! {
            /// What [`Self::decode`] answers, for the stream decoder's fast path: a frame of
            /// one of the direction's fixed lengths through a copy of the checks for that
            /// length.
            pub(crate) fn decode_fixed(frame: &[u8]) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
                match frame.len() {
                    #(#arms)*
                    _ => #other,
                }
            }
            /// The decoder's checks, inlined into each length of [`Self::decode_fixed`].
            #[inline(always)]
            fn #inline_fn -> rt::Result<Decoded<#ty>, rt::DecodeError> {
                #decode_for_body
            }
        }
    };
    if !replies {
        let checks = decode_for_body;
        return quote! {
            #doc_decode
            pub fn decode(frame: #fr) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
                #checks
            }
            #fixed
            #unescaped_fn
            #dispatch
        };
    }
    quote! {
        #doc_decode
        ///
        /// Responses that only their request tells apart are reported as
        /// [`busspec_runtime::DecodeError::Ambiguous`]; decode those with [`Self::decode_reply`].
        #[inline]
        pub fn decode(frame: #fr) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
            Self::decode_for(frame, rt::None)
        }
        /// Decodes a frame as the reply to `request`: only responses `request` may get are
        /// considered, which settles responses that share code and length (and are otherwise
        /// reported as [`busspec_runtime::DecodeError::Ambiguous`]).
        #[inline]
        pub fn decode_reply(frame: #fr, request: &Request) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
            Self::decode_for(frame, rt::Some(request))
        }
        /// The one decoder behind [`Self::decode`] (`request` is `None`) and
        /// [`Self::decode_reply`].
        fn decode_for(frame: #fr, request: rt::Option<&Request>) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
            #decode_for_body
        }
        #over_fns
        #fixed
        #unescaped_fn
        #dispatch
    }
}

/// The shortest and the longest frame of direction `d` its decoder's frame checks take.
pub(super) fn frame_bounds(p: &Protocol, d: Direction) -> (usize, usize) {
    let msgs = p.framed(d);
    // A direction of messages without a checksum alone: the shortest head of a frame with
    // one (the interpreter's `shortest_head`).
    let head_len = || {
        let code = p.framing.direction(d).code_lengths.iter().min();
        p.framing.head(d, code.copied().unwrap_or(0)).len
    };
    let min_len = msgs
        .iter()
        .filter(|m| !m.unchecked)
        .map(|m| len_range(m).0)
        .min()
        .unwrap_or_else(|| if msgs.is_empty() { 0 } else { head_len() });
    let max_len = msgs.iter().map(|m| m.max_len).max().unwrap_or(0);
    (min_len, max_len)
}

/// The checks of direction `d`'s decoder that every frame passes before its code is read:
/// `rt::FrameChecks` (length, sync, start, address, checksum: `let address = …;`) and the
/// length field. Two directions whose checks are the same tokens check a frame alike.
/// `shortest`: the shortest frame checked, where not the direction's own.
pub(super) fn framing_checks(p: &Protocol, d: Direction, shortest: Option<usize>) -> TokenStream {
    // A shortest frame of its own (`decodes_both_ways`, past both directions' shortest) is
    // written out, unless it is each direction's.
    let own = |d: Direction| shortest.map_or(true, |min| min == frame_bounds(p, d).0);
    let checks = if own(Direction::Request) && own(Direction::Response) {
        checks_name(p, d)
    } else {
        checks_value(p, d, shortest)
    };
    let check_frame = frame_check(p, d, &checks);
    let length = length_check(p, d);
    quote! {
        #check_frame
        #length
    }
}

/// The groups direction `d`'s `dispatch` tries (`rt::Group`, several messages of one code):
/// the request names the reply in its refusal, and settles replies only the request tells
/// apart. A response's `dispatch` takes the request where there is one.
pub(super) fn dispatch_groups(p: &Protocol, d: Direction) -> Vec<Vec<&Message>> {
    let msgs = p.framed(d);
    let codeless: Vec<&Message> = msgs.iter().filter(|m| m.code.is_empty()).collect();
    let mixed = !codeless.is_empty() && codeless.len() < msgs.len();
    messages_by_code(msgs)
        .iter()
        .filter(|(code, _)| !code.is_empty() || !mixed)
        .map(|(_, g)| {
            let mut g = g.clone();
            if mixed {
                g.extend(&codeless);
            }
            g
        })
        .chain(mixed.then(|| codeless.clone()))
        .filter(|g| g.len() > 1)
        .collect()
}

/// The sync sequences checked before the other frame checks, each at its offset: a sync
/// sequence's first byte is `FRAME.start`'s, the others are checked first. Start bytes that
/// differ by direction, or come twice, are all checked here (`FRAME.start` is `None`), in the
/// order the interpreter checks them.
pub(super) fn syncs(p: &Protocol, d: Direction) -> Vec<(usize, &[u8])> {
    let by_direction = starts_by_direction(p);
    // The direction's own layout: a second start after the code sits after its one length.
    let code_len = p
        .framing
        .direction(d)
        .code_lengths
        .first()
        .copied()
        .unwrap_or(0);
    let head = p.framing.head(d, code_len);
    match (head.start, p.framing.sync_of(d)) {
        (Some(_), sync)
            if sync.len() > 1
                || ((by_direction || head.start_again.is_some()) && !sync.is_empty()) =>
        {
            head.starts().map(|at| (at, sync)).collect()
        }
        _ => Vec::new(),
    }
}

/// A reply the request does not get is refused once decoded, then one whose fields do
/// not follow the request's: the interpreter's order.
fn answered(p: &Protocol, replies: bool) -> TokenStream {
    let follows = if has_follows_request(p) {
        quote!(message.follows_request(request)?;)
    } else {
        quote!()
    };
    // Where responses are sent unasked, the refusal says whether this one is (the
    // interpreter's words), by its row in a mask of them (a borrowed view has no
    // `is_unasked`); elsewhere the code is what it was.
    let unasked = p
        .responses
        .iter()
        .enumerate()
        .filter(|(_, r)| r.unasked)
        .fold(0u128, |a, (i, _)| a | 1 << i);
    let refused = if unasked != 0 {
        let mask = if p.responses.len() <= 64 {
            Literal::u64_suffixed(unasked as u64)
        } else {
            Literal::u128_suffixed(unasked)
        };
        quote!(rt::not_a_reply_unasked(
            message.name(),
            request.name(),
            #mask >> message.index() & 1 != 0
        ))
    } else {
        quote!(rt::not_a_reply(message.name(), request.name()))
    };
    if replies {
        quote! {
            if let rt::Some(request) = request {
                if request.replies() >> message.index() & 1 == 0 {
                    return rt::Err(#refused);
                }
                #follows
            }
        }
    } else {
        quote!()
    }
}

/// A frame made into another before its checks (unescaped, padded to its whole payload, laid
/// out in the long form's width): checked as any frame by a function of its own,
/// `decode_SUFFIX` (`decode_for_SUFFIX` for replies), its errors placed back by `locate`.
struct Own {
    suffix: &'static str,
    doc: &'static str,
    /// The frame the checks take.
    frame: TokenStream,
    /// What the errors of the checks go through (nothing where they keep their offsets).
    locate: TokenStream,
}

impl Own {
    /// The decoder's body (`before`, then the call) and the function of the checks.
    fn decoder(
        &self,
        replies: bool,
        ty: &TokenStream,
        before: TokenStream,
        checks: &TokenStream,
    ) -> (TokenStream, TokenStream) {
        let (frame, locate) = (&self.frame, &self.locate);
        let (outer, name, param, arg) = if replies {
            (
                "decode_for",
                format_ident!("decode_for_{}", self.suffix),
                quote!(, request: rt::Option<&Request>),
                quote!(, request),
            )
        } else {
            (
                "decode",
                format_ident!("decode_{}", self.suffix),
                quote!(),
                quote!(),
            )
        };
        let doc = format!(" [`Self::{outer}`] of the frame {}.", self.doc);
        (
            quote! {
                #before
                Self::#name(#frame #arg)#locate
            },
            quote! {
                #[doc = #doc]
                fn #name(frame: &[u8] #param) -> rt::Result<Decoded<#ty>, rt::DecodeError> {
                    #checks
                }
            },
        )
    }
}

/// One match per code length, shortest first; non-empty codes are prefix-free within a
/// direction (validated). The last is the function's value, or with code-less messages
/// beside coded ones, theirs is.
fn code_matches(
    ctx: &Ctx,
    d: Direction,
    by_code: &[(&[u8], Vec<&Message>)],
    codeless: &[&Message],
    min_len: usize,
    clen: usize,
    unknown: &TokenStream,
) -> Vec<TokenStream> {
    let p = ctx.p;
    let msgs = p.framed(d);
    let mixed = !codeless.is_empty() && codeless.len() < msgs.len();
    let replies = d == Direction::Response;
    let code_at = |l: usize| p.framing.head(d, l).code;
    let mut lens: Vec<usize> = msgs
        .iter()
        .map(|m| m.code.len())
        .filter(|&l| !mixed || l > 0)
        .collect();
    lens.sort_unstable();
    lens.dedup();
    let mut body = Vec::new();
    for (li, &l) in lens.iter().enumerate() {
        let last = li + 1 == lens.len() && !mixed;
        let at = code_at(l);
        let codes = by_code.iter().filter(|(code, _)| code.len() == l);
        let codes = codes.map(|(code, group)| {
            let mut group = group.clone();
            if mixed {
                group.extend(codeless);
            }
            (hex_code(code), emit_group(ctx, &group, replies, mixed))
        });
        let need = at + l + clen;
        let code = read_code(at, l);
        // The one message group without a code needs no `match` on it.
        if l == 0 {
            let arm = codes.map(|(_, arm)| arm);
            if last {
                body.push(quote!(#(#arm)*));
            } else {
                let need = usize_lit(need);
                body.push(quote! {
                    if frame.len() >= #need {
                        #(return #arm;)*
                    }
                });
            }
            continue;
        }
        let arms = codes.map(|(lit, arm)| {
            if last {
                quote!(#lit => #arm,)
            } else {
                quote!(#lit => return #arm,)
            }
        });
        if !last {
            let need = usize_lit(need);
            body.push(quote! {
                if frame.len() >= #need {
                    match #code {
                        #(#arms)*
                        _ => {}
                    }
                }
            });
            continue;
        }
        if need > min_len {
            let need = usize_lit(need);
            body.push(quote! {
                if frame.len() < #need {
                    return #unknown;
                }
            });
        }
        body.push(quote! {
            match #code {
                #(#arms)*
                _ => #unknown,
            }
        });
    }
    if mixed {
        body.push(emit_group(ctx, codeless, replies, true));
    }
    body
}

/// The `l`-byte code at offset `at` of a frame long enough to hold it, big-endian as codes
/// are written: the byte itself, or the bytes as a `u16` or `u32` (through `rt::code` for a
/// code of three bytes).
fn read_code(at: usize, l: usize) -> TokenStream {
    let bytes = (at..at + l).map(|i| {
        let i = usize_lit(i);
        quote!(frame[#i])
    });
    match l {
        1 => quote!(#(#bytes)*),
        2 => quote!(u16::from_be_bytes([#(#bytes),*])),
        4 => quote!(u32::from_be_bytes([#(#bytes),*])),
        _ => {
            let (at, l) = (usize_lit(at), usize_lit(l));
            quote!(rt::code(frame, #at, #l))
        }
    }
}

/// The checks every frame of direction `d` passes (length, address, checksum, end bytes),
/// which give its address: `let address = …;`, by `checks` (an `rt::FrameChecks`). A message
/// without a checksum is checked without one, found by its code and length first.
fn frame_check(p: &Protocol, d: Direction, checks: &TokenStream) -> TokenStream {
    let unchecked = p.framed(d).iter().any(|m| m.unchecked);
    let replies = d == Direction::Response;
    let sum = frame_sum(p, d);
    // A reply whose checksum takes in its request's bytes (`checksum_over_request`):
    // `response_sum` checks it over `covered`, or refuses it without them.
    let over = replies && p.has_over_request();
    let check_frame = if over {
        quote!(#checks.check_with(frame, |b| response_sum(frame, b, covered))?)
    } else {
        quote!(#checks.check(frame, #sum)?)
    };
    if unchecked {
        let is = super::head::unchecked_fn(d);
        quote! {
            let address = if #is(frame) {
                #checks.check_unsummed(frame)?
            } else {
                #check_frame
            };
        }
    } else {
        quote!(let address = #check_frame;)
    }
}

/// What direction `d`'s frames are checked by before their code is read ([`checks_of`]).
#[derive(PartialEq)]
struct Checks<'p> {
    syncs: Vec<(usize, &'p [u8])>,
    frame: String,
    min: usize,
    max: usize,
    address_at: usize,
}

/// Direction `d`'s frame checks: its sync sequences, its frame constant, its shortest (or
/// `shortest`) and longest frame, its address's offset.
fn checks_of(p: &Protocol, d: Direction, shortest: Option<usize>) -> Checks<'_> {
    let (min, max) = frame_bounds(p, d);
    Checks {
        syncs: syncs(p, d),
        frame: frame_of(p, d).to_string(),
        min: shortest.unwrap_or(min),
        max,
        address_at: address_at(p, d),
    }
}

/// Direction `d`'s frame checks ([`checks_of`]) as an `rt::FrameChecks` value.
fn checks_value(p: &Protocol, d: Direction, shortest: Option<usize>) -> TokenStream {
    let c = checks_of(p, d, shortest);
    let (min, max, at) = (usize_lit(c.min), usize_lit(c.max), usize_lit(c.address_at));
    let frame = frame_of(p, d);
    let sync = c.syncs.into_iter().map(|(at, bytes)| {
        let (at, bytes) = (usize_lit(at), bytes.iter().map(|b| hex_u8(*b)));
        quote!((#at, &[#(#bytes),*]))
    });
    quote!(rt::FrameChecks { sync: &[#(#sync),*], frame: &#frame, min: #min, max: #max, address_at: #at })
}

/// Whether both directions check frames alike (one `CHECKS` constant).
fn checks_alike(p: &Protocol) -> bool {
    checks_of(p, Direction::Request, None) == checks_of(p, Direction::Response, None)
}

/// The name of direction `d`'s frame checks constant ([`emit_frame_checks`]): `CHECKS` where
/// both directions check frames alike.
pub(super) fn checks_name(p: &Protocol, d: Direction) -> TokenStream {
    match (checks_alike(p), d) {
        (true, _) => quote!(CHECKS),
        (false, Direction::Request) => quote!(REQUEST_CHECKS),
        (false, Direction::Response) => quote!(RESPONSE_CHECKS),
    }
}

/// The constants [`checks_name`] names: what each direction's frames are checked by before
/// their code is read.
pub(super) fn emit_frame_checks(p: &Protocol) -> TokenStream {
    let alike = checks_alike(p);
    let dirs = if alike {
        &[Direction::Request][..]
    } else {
        &[Direction::Request, Direction::Response][..]
    };
    let consts = dirs.iter().map(|&d| {
        let (name, value) = (checks_name(p, d), checks_value(p, d, None));
        let (min, max) = frame_bounds(p, d);
        let whose = match (alike, d) {
            (true, _) => "every frame",
            (_, Direction::Request) => "every request",
            (_, Direction::Response) => "every response",
        };
        let f = &p.framing;
        let head = f.head(d, 1);
        let syncs = syncs(p, d);
        let sync = syncs
            .iter()
            .map(|(at, bytes)| {
                let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
                format!("{} at offset {at}", hex.join(" "))
            })
            .collect::<Vec<_>>()
            .join(" and ");
        let parts = [
            (!syncs.is_empty(), format!("its sync bytes ({sync})")),
            (
                syncs.is_empty() && head.start.is_some() && f.start.is_some(),
                "its start byte".to_string(),
            ),
            (!f.end_of(d).is_empty(), "its end bytes".to_string()),
            (!f.checksum.is_empty(), "its checksum".to_string()),
            (
                f.has_address_in(d),
                format!("its address (offset {})", address_at(p, d)),
            ),
        ];
        let parts: Vec<String> = parts
            .into_iter()
            .filter(|(on, _)| *on)
            .map(|(_, t)| t)
            .collect();
        let then = if parts.is_empty() {
            String::new()
        } else {
            format!(", then {}", parts.join(", "))
        };
        let bytes = if min == max {
            format!("{min} bytes")
        } else {
            format!("{min} to {max} bytes")
        };
        let doc = format!(" The checks {whose} passes before its code is read: {bytes}{then}.");
        quote! {
            #[doc = #doc]
            const #name: rt::FrameChecks = #value;
        }
    });
    quote!(#(#consts)*)
}

/// The check of the length field of a frame of direction `d`, where the framing has one: it
/// holds a constant plus the frame's length where it counts the payload (every message of the
/// direction has it at the same offset, and only the payload varies).
pub(super) fn length_check(p: &Protocol, d: Direction) -> TokenStream {
    let checks = length_consts(p, d)
        .into_iter()
        .map(|(name, _)| quote!(#name.check(frame)?;));
    quote!(#(#checks)*)
}

/// The name of direction `d`'s `rt::CodeAt` ([`code_consts`]).
pub(super) fn code_const(d: Direction) -> Ident {
    format_ident!("{}_CODE", direction_names(d).0.to_string().to_uppercase())
}

/// `REQUEST_CODE` and `RESPONSE_CODE`: where each direction's code sits (its first code
/// length's offset, its longest code, the trailer after it), from which a code no message has
/// is quoted; each where a decoder of its direction quotes one (`Ctx::codes_used`, so call
/// this after the decoders are emitted).
pub(super) fn code_consts(ctx: &Ctx) -> TokenStream {
    let (p, used) = (ctx.p, ctx.codes_used.get());
    let consts = [Direction::Request, Direction::Response].map(|d| {
        if !used[usize::from(d == Direction::Response)] {
            return quote!();
        }
        let name = code_const(d);
        let longest = p.framing.direction(d).code_lengths.iter().copied().max().unwrap_or(1);
        let (at, longest, trailer) = (
            usize_lit(p.framing.head(d, 1).code),
            usize_lit(longest),
            usize_lit(p.framing.trailer_len_of(d)),
        );
        let response = d == Direction::Response;
        let what = if response { "a response's" } else { "a request's" };
        let doc = doc(&format!(
            "Where {what} code sits: from `at`, at most `longest` bytes, before `trailer` bytes."
        ));
        quote! {
            #doc
            const #name: rt::CodeAt = rt::CodeAt { at: #at, longest: #longest, trailer: #trailer, response: #response };
        }
    });
    quote!(#(#consts)*)
}

/// The length field of direction `d` as the module names it (`rt::FrameLength`), and again
/// where the layout repeats it (the same value): `LENGTH` (`LENGTH_AGAIN`) where both
/// directions have the same field, else `REQUEST_LENGTH` and `RESPONSE_LENGTH`; none where
/// the direction has no length field.
pub(super) fn length_consts(p: &Protocol, d: Direction) -> Vec<(Ident, LengthRule)> {
    let Some(rule) = p.framing.length_rule(d) else {
        return Vec::new();
    };
    let other = match d {
        Direction::Request => Direction::Response,
        Direction::Response => Direction::Request,
    };
    // The same field where it sits, reads and counts alike (the shortest frame may differ).
    let same = |o: LengthRule| {
        (o.at, o.again, o.width, o.grows, o.k)
            == (rule.at, rule.again, rule.width, rule.grows, rule.k)
    };
    let shared = p.framing.length_rule(other).map_or(true, same);
    let base = if shared {
        "LENGTH".to_string()
    } else {
        format!("{}_LENGTH", direction_names(d).0.to_string().to_uppercase())
    };
    let again = rule.again.map(|at| LengthRule { at, ..rule });
    [
        Some((format_ident!("{base}"), rule)),
        again.map(|r| (format_ident!("{base}_AGAIN"), r)),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// Each length field the module names ([`length_consts`]), once: `rt::FrameLength` constants
/// of its offset, width, byte order, whether it counts the payload and its constant.
pub(super) fn length_field_consts(p: &Protocol) -> TokenStream {
    let mut seen: Vec<Ident> = Vec::new();
    let mut out = Vec::new();
    for d in [Direction::Request, Direction::Response] {
        for (name, rule) in length_consts(p, d) {
            if seen.contains(&name) {
                continue;
            }
            seen.push(name.clone());
            let (at, width, le, grows, k) = (
                usize_lit(rule.at),
                usize_lit(rule.width),
                p.byte_order == ByteOrder::Little,
                rule.grows,
                i64_lit(rule.k),
            );
            let what = if grows {
                "the frame's length plus `k`"
            } else {
                "`k`"
            };
            let doc = doc(&format!(
                "The length field{}: `width` bytes at `at`, holding {what}.",
                if name.to_string().ends_with("_AGAIN") {
                    " where the layout repeats it"
                } else {
                    ""
                }
            ));
            out.push(quote! {
                #doc
                const #name: rt::FrameLength = rt::FrameLength { at: #at, width: #width, le: #le, grows: #grows, k: #k };
            });
        }
    }
    quote!(#(#out)*)
}

/// Whether `m` needs the request (`needs_request`) and shares code and length with another
/// message of `group` (its code group): decoded as the reply to a request that does not get
/// it, it is set aside.
pub(super) fn is_ambiguous(m: &Message, group: &[&Message]) -> bool {
    let (lo, hi) = len_range(m);
    // Decoded as the reply to a request that does not get it, such a message is set aside
    // wherever another of its group could have its length (the interpreter's rule), not only
    // beside another that needs the request.
    m.needs_request
        && group
            .iter()
            .filter(|o| {
                let (a, b) = len_range(o);
                a <= hi && lo <= b
            })
            .count()
            > 1
}

/// The name of the function decoding code-less message `m` where coded messages sit beside it.
pub(super) fn codeless_fn(m: &Message) -> Ident {
    format_ident!("codeless_{}", m.name)
}

/// One function per code-less message of a direction that has coded ones too: every arm of
/// `dispatch` tries them after its own code's messages, so each is written once. A fixed
/// message takes the frame as an array of its length, a variable one the whole frame.
pub(super) fn emit_codeless_fns(ctx: &Ctx, codeless: &[&Message]) -> TokenStream {
    let fns = codeless.iter().map(|m| {
        let f = codeless_fn(m);
        let (stmts, build) = decode_body(ctx, m);
        let doc = doc(&format!(
            "`{}` (no code) from a frame whose checks every frame passes, as `dispatch` tries it.",
            m.name
        ));
        if m.is_variable() {
            let params = split_params(ctx, m, &stmts, &build);
            let prelude = lists_prelude(m);
            return quote! {
                #doc
                #[inline]
                fn #f(#params) -> rt::DecodeResult<Self> {
                    #prelude
                    #(#stmts)*
                    rt::Ok(#build)
                }
            };
        }
        let len = usize_lit(ctx.p.frame_len(m));
        let param = if stmts.is_empty() && !mentions_frame(&build) {
            quote!(_: &[u8; #len])
        } else {
            quote!(frame: &[u8; #len])
        };
        quote! {
            #doc
            #[inline]
            fn #f(#param) -> rt::DecodeResult<Self> {
                #(#stmts)*
                rt::Ok(#build)
            }
        }
    });
    quote!(#(#fns)*)
}

/// `request::ReadCoils::from_frame`: the owned decoder of message `m`, a function of its
/// struct (emitted in its `impl` by `emit_descs`), which checks a fixed-length frame's length
/// (or splits a variable-length one into its fixed part and lists), then each field's rule,
/// naming its descriptors through `Self`; the dispatch wraps it in its direction's variant
/// (`.map(Self::ReadCoils)`), a lone message's arm and a fixed-length group member's closure
/// alike. `None` in a view (whose variants are no structs) and for a fixed-length message
/// with nothing to check or read, which the arm decodes in one line. Measured against the
/// same code inline in the arms (`bash benches/icount.sh`, `benches/flash/size.sh`): decode
/// 1 to 8 instructions a frame cheaper, the subset's flash 176 bytes larger.
fn from_frame(ctx: &Ctx, m: &Message) -> Option<TokenStream> {
    if ctx.view.get() {
        return None;
    }
    let (v, dm) = (variant(m), direction_module(m.direction));
    let path = quote!(#dm::#v::from_frame);
    // Written once, where the message is first dispatched; later arms (a group's, an
    // escaped frame's) call it.
    let written = ctx
        .readers
        .borrow()
        .iter()
        .any(|(d, n, _)| *d == m.direction && *n == m.name);
    if written {
        return Some(path);
    }
    ctx.own.set(true);
    let (stmts, build) = decode_body(ctx, m);
    ctx.own.set(false);
    if !m.is_variable() && stmts.is_empty() && !mentions_frame(&build) {
        return None;
    }
    // A variable-length frame is split into its fixed part and its lists' bytes; a
    // fixed-length one is checked to have its length.
    let head = if m.is_variable() {
        split_frame(m, &stmts, &build)
    } else {
        let len = usize_lit(ctx.p.frame_len(m));
        quote!(let frame = rt::fixed::<#len>(frame, &Self::DESC)?;)
    };
    ctx.readers.borrow_mut().push((
        m.direction,
        m.name.clone(),
        quote! {
            /// Reads this message from a frame whose framing and code are checked.
            #[inline(always)]
            fn from_frame(frame: &[u8]) -> rt::DecodeResult<Self> {
                #head
                #(#stmts)*
                rt::Ok(#build)
            }
        },
    ));
    Some(path)
}

/// The dispatch arm for the messages of one code: a lone message is decoded in the arm;
/// several are tried in spec order by `rt::Group`, each decoder a closure over the frame as an
/// array of its length. `shared`: code-less messages are decoded by their own function
/// ([`emit_codeless_fns`]), as every arm tries them.
pub(super) fn emit_group(
    ctx: &Ctx,
    group: &[&Message],
    replies: bool,
    shared: bool,
) -> TokenStream {
    let p = ctx.p;
    let by_fn = |m: &Message| (shared && m.code.is_empty()).then(|| codeless_fn(m));
    // Whether the request gets a reply decides between candidates only the request tells
    // apart; every other reply is checked once it is decoded (`decode_for`).
    let admitted = |m: &Message| {
        let i = p
            .responses
            .iter()
            .position(|r| r.name == m.name)
            .unwrap_or(0) as u32;
        if i == 0 {
            return quote!(asked & 1 != 0);
        }
        let i = Literal::u32_unsuffixed(i);
        quote!(asked >> #i & 1 != 0)
    };
    let value = hex_code(&group[0].code);
    if let [m] = group {
        if m.is_variable() {
            if let (Some(f), true) = (by_fn(m), has_lists(m)) {
                let (c, (base, k)) = (lists_const(m), lists_dims(m));
                return quote! {{
                    let s = #c.split::<#base, #k>(frame)?;
                    Self::#f(&s)
                }};
            }
            if let Some(f) = by_fn(m) {
                let (rc, at) = (
                    repeat_const(m),
                    usize_lit(m.layout.payload + m.repeat().map_or(0, |(f, _)| f.offset)),
                );
                return quote! {{
                    let (frame, elements, count) = #rc.split::<#at>(frame)?;
                    Self::#f(frame, elements, count)
                }};
            }
            if let Some(read) = from_frame(ctx, m) {
                let v = variant(m);
                return quote!(#read(frame).map(Self::#v));
            }
            let (stmts, build) = decode_body(ctx, m);
            let split = split_frame(m, &stmts, &build);
            return quote! {{
                #split
                #(#stmts)*
                rt::Ok(#build)
            }};
        }
        let len = usize_lit(p.frame_len(m));
        let desc = message_desc(m);
        let frame = quote!(rt::fixed::<#len>(frame, #desc));
        if let Some(f) = by_fn(m) {
            return quote!(#frame.and_then(Self::#f));
        }
        if let Some(read) = from_frame(ctx, m) {
            let v = variant(m);
            return quote!(#read(frame).map(Self::#v));
        }
        let (stmts, build) = decode_body(ctx, m);
        if stmts.is_empty() && !build.to_string().contains("frame") {
            return quote!(#frame.map(|_| #build));
        }
        return quote! {{
            let frame = #frame?;
            #(#stmts)*
            rt::Ok(#build)
        }};
    }
    let tries = group.iter().map(|m| {
        let len = usize_lit(p.frame_len(m));
        let name = message_desc(m);
        let ambiguous = is_ambiguous(m, group);
        let a = if ambiguous { admitted(m) } else { quote!() };
        let decode = match by_fn(m) {
            Some(f) => quote!(Self::#f),
            None => {
                if let Some(read) = (!m.is_variable()).then(|| from_frame(ctx, m)).flatten() {
                    let v = variant(m);
                    return match ambiguous {
                        false => quote!(g.attempt(|frame: &[u8; #len]| #read(frame).map(Self::#v));),
                        true => quote!(g.ambiguous(#a, #name, |frame: &[u8; #len]| #read(frame).map(Self::#v));),
                    };
                }
                let (stmts, build) = decode_body(ctx, m);
                if m.is_variable() {
                    let params = split_params(ctx, m, &stmts, &build);
                    let prelude = lists_prelude(m);
                    quote!(|#params| {
                        #prelude
                        #(#stmts)*
                        rt::Ok(#build)
                    })
                } else if stmts.is_empty() && !build.to_string().contains("frame") {
                    quote!(|_: &[u8; #len]| rt::Ok(#build))
                } else {
                    quote!(|frame: &[u8; #len]| {
                        #(#stmts)*
                        rt::Ok(#build)
                    })
                }
            }
        };
        let rc = repeat_const(m);
        if has_lists(m) {
            let (c, (base, k)) = (lists_const(m), lists_dims(m));
            return if ambiguous {
                quote!(g.ambiguous_lists::<#base, #k>(#a, #name, &#c, #decode);)
            } else {
                quote!(g.attempt_lists::<#base, #k>(&#c, #decode);)
            };
        }
        match (m.is_variable(), ambiguous) {
            (false, false) => quote!(g.attempt(#decode);),
            (false, true) => quote!(g.ambiguous(#a, #name, #decode);),
            (true, false) => quote!(g.attempt_split(&#rc, #decode);),
            (true, true) => quote!(g.ambiguous_split(#a, #name, &#rc, #decode);),
        }
    });
    // A frame of none of the group's lengths is refused naming the first and every length,
    // as the interpreter refuses it.
    let first = message_desc(group[0]);
    let request = if replies {
        quote!(request.map(Request::name))
    } else {
        quote!(rt::None)
    };
    quote! {{
        let mut g = rt::Group::new(frame, #value, #request);
        #(#tries)*
        g.end(#first)
    }}
}

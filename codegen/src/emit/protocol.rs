use super::*;

/// What the spec says of each command beyond its frame, as a table: its kind, how it treats
/// the broadcast address (for transaction layers: what may be retried, what expects no
/// answer), and the responses it may get (bit `i`: row `i` of `Response::MESSAGES`).
pub(super) fn emit_command_info(p: &Protocol) -> TokenStream {
    let n = usize_lit(p.commands.len());
    let mut rows = Vec::new();
    for c in &p.commands {
        // Every command has a command kind (the validator builds them so).
        let kind = match &c.kind {
            MessageKind::Command(CommandKind::Movement) => quote!(rt::Movement),
            MessageKind::Command(CommandKind::CompletionCheck) => quote!(rt::CompletionCheck),
            MessageKind::Command(CommandKind::Setter) => quote!(rt::Setter),
            MessageKind::Command(CommandKind::Reset) => quote!(rt::Reset),
            _ => quote!(rt::Getter),
        };
        let (accepted, answered) = c
            .broadcast
            .as_ref()
            .map_or((false, false), |b| (b.accepted, b.answered));
        let replies = c.responses.iter().fold(0u128, |a, (r, _)| a | 1 << r);
        let replies = mask_lit(replies);
        rows.push(quote!((#kind, #accepted, #answered, #replies)));
    }
    let mask = reply_mask(p);
    // Commands whose reply is not required, by pattern; the rest are.
    let arms: Vec<TokenStream> = p
        .commands
        .iter()
        .filter_map(|c| {
            let r = match c.reply {
                busspec_model::ir::Reply::Required => return None,
                busspec_model::ir::Reply::Optional => quote!(rt::Reply::Optional),
                busspec_model::ir::Reply::None => quote!(rt::Reply::None),
            };
            let pat = any_of(&ident("Request"), c);
            Some(quote!(#pat => #r,))
        })
        .collect();
    let reply = if arms.is_empty() {
        quote!(rt::Reply::Required)
    } else {
        quote!(match self { #(#arms)* _ => rt::Reply::Required })
    };
    let may_retry =
        crate::transactions::may_retry(p, quote!(c.0), |c| any_of(&ident("Request"), c));
    quote! {
        impl Request {
            /// Each command's kind, whether it accepts and answers the broadcast address, and the
            /// responses it may get (bit `i`: row `i` of `Response::MESSAGES`), in spec order.
            const COMMANDS: [(rt::CommandKind, bool, bool, #mask); #n] = [#(#rows),*];
            /// What the spec says of the command beyond its frame: its kind, the broadcast
            /// address, its reply, whether a master may send it again.
            pub const fn command(&self) -> rt::Command {
                let c = Self::COMMANDS[self.index()];
                rt::Command {
                    kind: c.0,
                    broadcast: rt::Broadcast { accepted: c.1, answered: c.2 },
                    reply: #reply,
                    may_retry: #may_retry,
                }
            }
            /// The responses this command may get, bit `i` for row `i` of `Response::MESSAGES`.
            const fn replies(&self) -> #mask {
                Self::COMMANDS[self.index()].3
            }
        }
    }
}

/// The integer type of a set of responses, one bit each.
pub(super) fn reply_mask(p: &Protocol) -> Ident {
    if p.responses.len() <= 64 {
        ident("u64")
    } else {
        ident("u128")
    }
}

/// A pattern matching any value of a message's variant.
pub(super) fn any_of(ty: &Ident, m: &Message) -> TokenStream {
    let v = variant(m);
    quote!(#ty::#v(_))
}

pub(super) fn emit_pairing(ctx: &Ctx) -> TokenStream {
    let unasked: Vec<TokenStream> = ctx
        .p
        .responses
        .iter()
        .filter(|r| r.unasked)
        .map(|r| any_of(&ident("Response"), r))
        .collect();
    let is_unasked = if unasked.is_empty() {
        quote!()
    } else {
        quote! {
            impl Response {
                /// Whether the device sends this response on its own (`unasked: true`), not
                /// only as a reply: after a request that does not list it, it is not that
                /// request's reply.
                pub fn is_unasked(&self) -> bool {
                    matches!(self, #(#unasked)|*)
                }
            }
        }
    };
    let Some(follows) = emit_follows_request(ctx) else {
        return quote! {
            impl Response {
                /// Whether this response is one the document says `request` may get.
                pub fn answers(&self, request: &Request) -> bool {
                    request.replies() >> self.index() & 1 != 0
                }
            }
            #is_unasked
        };
    };
    quote! {
        #is_unasked
        impl Response {
            /// Whether this response is one the document says `request` may get, and every
            /// field it takes from the request agrees with it.
            pub fn answers(&self, request: &Request) -> bool {
                request.replies() >> self.index() & 1 != 0 && self.follows_request(request).is_ok()
            }
            #follows
        }
    }
}

/// Whether a response has a field that follows from its request (`follows: {request}`, or a
/// repeated field's count: `repeat.request`).
pub(super) fn has_follows_request(p: &Protocol) -> bool {
    p.responses.iter().flat_map(|m| &m.fields).any(|f| {
        matches!(f.follows, Some(Follows::Request(_)))
            || f.repeat.as_ref().is_some_and(|r| r.request.is_some())
    })
}

/// `follows_request`: one arm per response and command it answers, checking each field the
/// response takes from the request (`None` where no response has one).
/// The value of field `name` of request `cmd` as the relations of `follows: {request}` take it:
/// its constant (sign-extended where the field is signed, as the interpreter reads it), or its
/// raw value bound in the arm's pattern (`r_<name>`, pushed on `theirs` once). `None` where the
/// request has no such integer.
pub(super) fn request_value(
    ctx: &Ctx,
    cmd: &Message,
    cls: &[Leaf],
    name: &str,
    theirs: &mut Vec<String>,
) -> Option<TokenStream> {
    let field = cmd.fields.iter().find(|f| f.name == name);
    if let Some(c) = field.and_then(Field::constant_value) {
        let c = i64_lit(c);
        return Some(quote!(#c));
    }
    // A count field is not carried: the request's list gives it.
    let counter = cmd.count_field().and_then(|i| cmd.fields.get(i));
    let list = cmd.repeat().map(|(f, _)| f.name.as_str());
    let (cl, counted) = match (counter, list) {
        (Some(c), Some(list)) if c.name == name => (cls.iter().find(|x| x.name == list)?, true),
        _ => (
            cls.iter().find(|x| x.bits.is_none() && x.name == name)?,
            false,
        ),
    };
    let cn = ident(cl.name);
    let their = quote!(r.#cn);
    let b = if counted {
        let rc = repeat_const(cmd);
        quote!(#rc.count_value(#their.len()))
    } else {
        raw_of(ctx, cl, &their)?.1
    };
    if !theirs.iter().any(|t| t == cl.name) {
        theirs.push(cl.name.to_owned());
    }
    Some(b)
}

pub(super) fn emit_follows_request(ctx: &Ctx) -> Option<TokenStream> {
    let p = ctx.p;
    if !has_follows_request(p) {
        return None;
    }
    let mut arms = Vec::new();
    for m in &p.responses {
        let ls = leaves(m);
        let follows: Vec<(&Leaf, &Relation)> = ls
            .iter()
            .filter_map(|l| match (&l.field.follows, l.bits) {
                (Some(Follows::Request(rel)), None) => Some((l, rel)),
                _ => None,
            })
            .collect();
        // The repeated field's list, where its count or its count field follows the request.
        let list = m
            .repeat()
            .and_then(|(f, _)| ls.iter().find(|l| l.name == f.name));
        let counted: Vec<(&Field, &Relation, bool)> = m
            .fields
            .iter()
            .enumerate()
            .filter_map(|(i, f)| match &f.follows {
                Some(Follows::Request(rel)) if m.count_field() == Some(i) => Some((f, rel, true)),
                _ => None,
            })
            .chain(
                m.repeat()
                    .and_then(|(f, r)| r.request.as_ref().map(|rel| (f, rel, false))),
            )
            .collect();
        if follows.is_empty() && counted.is_empty() {
            continue;
        }
        let v = variant(m);
        for &c in &m.answers {
            let cmd = &p.commands[c];
            let cls = leaves(cmd);
            // The checks are one function of the response's struct a pair (`follows_<command>`,
            // written once, in its `impl`, by the owned decoder's pass), which takes the
            // values it compares and the request's struct `r`; the owned and the view's
            // `follows_request` call it with their own.
            let (mut own, mut params, mut values) = (Vec::new(), Vec::new(), Vec::new());
            let mut theirs = Vec::new();
            let mut checks = Vec::new();
            // An owned response's field is read where its struct holds it (`m.coils`), a view's
            // from its variant's binding (`v_coils`).
            let field = |name: &str| {
                let (n, l) = (ident(name), local(name));
                if ctx.view.get() {
                    quote!(#l)
                } else {
                    quote!(m.#n)
                }
            };
            ctx.own.set(true);
            for (l, rel) in &follows {
                let (n, mine) = (ident(l.name), local(l.name));
                let (Some((_, a)), Some(b)) = (
                    raw_of(ctx, l, &mine),
                    request_value(ctx, cmd, &cls, &rel.field, &mut theirs),
                ) else {
                    continue;
                };
                own.push(quote!(#n: #mine));
                let ty = ctx.rust_type(l);
                params.push(quote!(#mine: #ty));
                values.push(field(l.name));
                let at = m.layout.payload + l.field.offset;
                let args = relation_args(rel);
                let rule = format!("{} of the request", rel.describe(&rel.field));
                let rel = quote!(.follows(#args, #rule));
                let c = ctx.field_check(
                    m,
                    l.name,
                    (at, &usize_lit(at).to_token_stream()),
                    None,
                    Some(rel),
                );
                checks.push(quote!(rt::following(#c, #a, #b as i64)?;));
            }
            if let Some(list) = list {
                let rc = repeat_const(m);
                let (n, len) = (ident(list.name), format_ident!("n_{}", list.name));
                let mut bound = false;
                for (f, rel, is_count) in &counted {
                    let Some(b) = request_value(ctx, cmd, &cls, &rel.field, &mut theirs) else {
                        continue;
                    };
                    if !bound {
                        let (l, mine) = (local(list.name), field(list.name));
                        own.push(quote!(#n: #l));
                        params.push(quote!(#len: usize));
                        values.push(quote!(#mine.len()));
                        bound = true;
                    }
                    let args = relation_args(rel);
                    if *is_count {
                        let at = m.layout.payload + f.offset;
                        let rule = format!("{} of the request", rel.describe(&rel.field));
                        let rel = quote!(.follows(#args, #rule));
                        let c = ctx.field_check(
                            m,
                            &f.name,
                            (at, &usize_lit(at).to_token_stream()),
                            None,
                            Some(rel),
                        );
                        checks.push(
                            quote!(rt::following(#c, #rc.count_value(#len) as u64, #b as i64)?;),
                        );
                    } else {
                        let rule = rel.describe(&rel.field);
                        checks.push(quote!(#rc.follows_request(#len, #b as i64, (#args), #rule)?;));
                    }
                }
            }
            ctx.own.set(false);
            let cv = variant(cmd);
            let check = format_ident!("follows_{}", cmd.name);
            if !ctx.view.get() {
                let r = if theirs.is_empty() {
                    quote!(_)
                } else {
                    quote!(r)
                };
                let doc = doc(&format!(
                    "Checks the fields this response takes from its request, `{}` (`r`).",
                    cmd.name
                ));
                ctx.followers.borrow_mut().push((
                    m.direction,
                    m.name.clone(),
                    quote! {
                        #doc
                        #[inline(always)]
                        fn #check(#(#params,)* #r: &request::#cv) -> rt::DecodeResult<()> {
                            #(#checks)*
                            rt::Ok(())
                        }
                    },
                ));
            }
            // A view's variant holds its fields, bound by name; an owned response's, its
            // message's struct (`m`); the request's struct is `r`.
            let mine_pat = match (ctx.view.get(), own.is_empty()) {
                (true, _) => quote!(&Self::#v { #(#own,)* .. }),
                (false, false) => quote!(Self::#v(m)),
                (false, true) => quote!(Self::#v(_)),
            };
            arms.push(quote! {
                (#mine_pat, Request::#cv(r)) => response::#v::#check(#(#values,)* r)?,
            });
        }
    }
    Some(quote! {
        /// Checks every field this response takes from `request` (`follows: {request}` in the
        /// spec): [`busspec_runtime::DecodeError::InvalidValue`] names the first that differs.
        pub fn follows_request(&self, request: &Request) -> rt::DecodeResult<()> {
            match (self, request) {
                #(#arms)*
                _ => {}
            }
            rt::Ok(())
        }
    })
}

/// The protocol's unit type and its `rt::Protocol` impl (where it came from, its bus, its
/// decoders), and what its message types say beyond their frames: `rt::RequestMessage` for
/// `Request`, `rt::ResponseMessage` for `Response` (which requests a response answers, its
/// NAKs, its decoding as a reply).
pub(super) fn emit_protocol_impl(p: &Protocol) -> TokenStream {
    let ty = type_ident(&p.name);
    // The decoders by fixed length of the stream decoder's fast path, where generated.
    let fixed_request = (!super::stream::fixed_lengths(p, Direction::Request).is_empty()).then(|| {
        quote! {
            #[inline]
            fn decode_request_fixed(frame: &[u8]) -> rt::Result<Decoded<Request>, rt::DecodeError> {
                Request::decode_fixed(frame)
            }
        }
    });
    let fixed_response = (!super::stream::fixed_lengths(p, Direction::Response).is_empty()).then(|| {
        quote! {
            #[inline]
            fn decode_response_fixed(frame: &[u8]) -> rt::Result<Decoded<Response>, rt::DecodeError> {
                Response::decode_fixed(frame)
            }
        }
    });
    let fixed = quote!(#fixed_request #fixed_response);
    let naks: Vec<TokenStream> = p
        .responses
        .iter()
        .filter(|r| matches!(r.kind, MessageKind::Response(ResponseKind::Nak)))
        .map(|r| any_of(&ident("Response"), r))
        .collect();
    let is_nak = if naks.is_empty() {
        quote!(false)
    } else {
        quote!(matches!(self, #(#naks)|*))
    };
    // Responses sent unasked (`unasked: true`): only a protocol with one says so.
    let unasked: Vec<TokenStream> = p
        .responses
        .iter()
        .filter(|r| r.unasked)
        .map(|r| any_of(&ident("Response"), r))
        .collect();
    let is_unasked = if unasked.is_empty() {
        quote!()
    } else {
        quote! {
            #[inline]
            fn is_unasked(&self) -> bool {
                Response::is_unasked(self)
            }
            const HAS_UNASKED: bool = true;
        }
    };
    let doc_text = format!(
        "The {} protocol as a type: implements [`busspec_runtime::Protocol`], so code generic over protocols works with it.",
        p.name
    );
    let type_doc = doc(&doc_text);
    let transactions = crate::transactions::transactions(p);
    let replies_addressed = p.framing.has_address_in(Direction::Response);
    // A reply whose checksum takes in its request's bytes (`checksum_over_request`): decoded
    // and encoded over its request's covered bytes.
    let (covered, over_fns) = if p.has_over_request() {
        let from = usize_lit(p.framing.checksum.covers_from);
        // A request without a checksum (`checksum: none`): its bytes from where the
        // checksum would cover to its end.
        let span_of = if p.framed(Direction::Request).iter().any(|m| m.unchecked) {
            let is = super::head::unchecked_fn(Direction::Request);
            quote! {
                if #is(frame) {
                    return frame.get(#from..).unwrap_or(&[]);
                }
                rt::span(frame, #from, &FRAME)
            }
        } else {
            quote!(rt::span(frame, #from, &FRAME))
        };
        (
            quote! {
                #[inline]
                fn covered(frame: &[u8]) -> &[u8] {
                    #span_of
                }
            },
            quote! {
                #[inline]
                fn decode_as_reply_over(frame: &[u8], request: rt::Option<&Request>, covered: rt::Option<&[u8]>) -> rt::Result<Decoded<Response>, rt::DecodeError> {
                    Response::decode_over(frame, request, covered)
                }
                #[inline]
                fn encode_reply_over(&self, address: u8, covered: &[u8], buf: &mut [u8]) -> rt::Result<usize, rt::EncodeError> {
                    Response::encode_reply_over(self, address, covered, buf)
                }
            },
        )
    } else {
        (quote!(), quote!())
    };
    quote! {
        #type_doc
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
        pub struct #ty;
        impl rt::Protocol for #ty {
            type Request = Request;
            type Response = Response;
            type Buffer = [u8; MAX_FRAME_LEN];
            const NAME: &'static str = PROTOCOL;
            const SOURCE: rt::Source = rt::Source {
                document: DOCUMENT,
                revision: DOCUMENT_REVISION,
                spec_sha256: SPEC_SHA256,
                spec_yaml: SPEC_YAML,
            };
            const BUS: rt::Bus = rt::Bus {
                baud: BAUD,
                inter_frame_gap_ms: INTER_FRAME_GAP_MS,
                max_frames_per_s: MAX_FRAMES_PER_S,
                device_addresses: DEVICE_ADDRESSES,
                broadcast_address: BROADCAST_ADDRESS,
                host_address: HOST_ADDRESS,
                replies_addressed: #replies_addressed,
                transactions: #transactions,
            };
            const MAX_FRAME_LEN: usize = MAX_FRAME_LEN;
            #[inline]
            fn decode_request(frame: &[u8]) -> rt::Result<Decoded<Request>, rt::DecodeError> {
                Request::decode(frame)
            }
            #fixed
        }
        impl rt::RequestMessage for Request {
            #[inline]
            fn command(&self) -> rt::Command {
                Request::command(self)
            }
            #covered
        }
        impl rt::ResponseMessage<Request> for Response {
            #[inline]
            fn answers(&self, request: &Request) -> bool {
                Response::answers(self, request)
            }
            fn is_nak(&self) -> bool {
                #is_nak
            }
            #is_unasked
            #[inline]
            fn decode_as_reply(frame: &[u8], request: rt::Option<&Request>) -> rt::Result<Decoded<Response>, rt::DecodeError> {
                Response::decode_for(frame, request)
            }
            #over_fns
        }
    }
}

/// `Framing::checksum_ok`: whether a frame ends in the checksum of the bytes it covers, laid
/// out in the long form's width or unescaped first where the framing says so; a message
/// without a checksum passes.
///
/// Where each direction's checksum covers from its own byte (`covers_from: {request,
/// response}`), a frame passes whose checksum is either direction's.
pub(super) fn checksum_ok_fn(p: &Protocol) -> TokenStream {
    let sum = frame_sum(p, Direction::Request);
    let check = if p.framing.checksum.covers_by_direction() {
        let rs = frame_sum(p, Direction::Response);
        quote!(FRAME.checksum_ok(frame, #sum) || FRAME.checksum_ok(frame, #rs))
    } else {
        quote!(FRAME.checksum_ok(frame, #sum))
    };
    let skip_preamble = if p.framing.preamble.is_some() {
        quote!(let frame = PREAMBLE.skip(frame);)
    } else {
        quote!()
    };
    let lay = if p.framing.form.is_some() {
        quote!(FORM)
    } else {
        quote!(LONG)
    };
    if p.framing.long.is_some() || p.framing.form.is_some() {
        // Laid out in the long form's width (`framing.length.long`) before the check.
        quote! {
            fn checksum_ok(frame: &[u8]) -> bool {
                let mut laid = [0u8; MAX_FRAME_LEN];
                let rt::Ok((frame, _)) = #lay.lay_out(frame, &mut laid) else {
                    return false;
                };
                #check
            }
        }
    } else if p.framing.escaping.is_none() {
        // Frames that travel without a checksum (`checksum: none`) have none to fail.
        let unchecked = [Direction::Request, Direction::Response]
            .into_iter()
            .filter(|&d| p.framed(d).iter().any(|m| m.unchecked))
            .map(|d| {
                let is = super::head::unchecked_fn(d);
                quote!(if #is(frame) { return true; })
            });
        quote! {
            fn checksum_ok(frame: &[u8]) -> bool {
                #skip_preamble
                #(#unchecked)*
                #check
            }
        }
    } else if p.framing.end_by_direction() {
        // Requests and responses escaped and ended apart (F.Port's uplink): a frame passes
        // whose checksum is either direction's, unescaped as that direction.
        // Each direction's `Frame` holds its own trailer (checksum and end bytes).
        let rs = frame_sum(p, Direction::Response);
        quote! {
            fn checksum_ok(frame: &[u8]) -> bool {
                fn ok(
                    frame: &[u8],
                    e: &rt::Escaping,
                    f: &rt::Frame,
                    sum: fn(&[u8]) -> u32,
                ) -> bool {
                    let mut plain = [0u8; UNESCAPED_LEN];
                    let rt::Ok(un) = rt::unescape_frame(e, frame, &mut plain, sum) else {
                        return false;
                    };
                    plain.get(..un.len).is_some_and(|frame| f.checksum_ok(frame, sum))
                }
                ok(frame, &ESCAPING, &FRAME, #sum)
                    || ok(frame, &RESPONSE_ESCAPING, &RESPONSE_FRAME, #rs)
            }
        }
    } else {
        quote! {
            fn checksum_ok(frame: &[u8]) -> bool {
                let mut plain = [0u8; UNESCAPED_LEN];
                let un = match rt::unescape_frame(&ESCAPING, frame, &mut plain, #sum) {
                    rt::Ok(un) => un,
                    rt::Err(_) => return false,
                };
                let rt::Some(frame) = plain.get(..un.len) else {
                    return false;
                };
                #check
            }
        }
    }
}

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
    let Some(follows) = emit_follows_request(ctx) else {
        return quote! {
            impl Response {
                /// Whether this response is one the document says `request` may get.
                pub fn answers(&self, request: &Request) -> bool {
                    request.replies() >> self.index() & 1 != 0
                }
            }
        };
    };
    quote! {
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
            let mut own = Vec::new();
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
            for (l, rel) in &follows {
                let (n, mine) = (ident(l.name), field(l.name));
                let (Some((_, a)), Some(b)) = (
                    raw_of(ctx, l, &mine),
                    request_value(ctx, cmd, &cls, &rel.field, &mut theirs),
                ) else {
                    continue;
                };
                own.push(quote!(#n: #mine));
                let fd = ctx.field_desc(m, l.name);
                let at = usize_lit(m.layout.payload + l.field.offset);
                let args = relation_args(rel);
                let rule = format!("{} of the request", rel.describe(&rel.field));
                checks.push(quote!(rt::following(#fd, #at, #a, #b as i64, (#args), #rule)?;));
            }
            if let Some(list) = list {
                let rc = repeat_const(m);
                let (n, mine) = (ident(list.name), field(list.name));
                let mut bound = false;
                for (f, rel, is_count) in &counted {
                    let Some(b) = request_value(ctx, cmd, &cls, &rel.field, &mut theirs) else {
                        continue;
                    };
                    if !bound {
                        own.push(quote!(#n: #mine));
                        bound = true;
                    }
                    let args = relation_args(rel);
                    if *is_count {
                        let fd = ctx.field_desc(m, &f.name);
                        let at = usize_lit(m.layout.payload + f.offset);
                        let rule = format!("{} of the request", rel.describe(&rel.field));
                        checks.push(quote!(rt::following(#fd, #at, #rc.count_value(#mine.len()) as u64, #b as i64, (#args), #rule)?;));
                    } else {
                        let rule = rel.describe(&rel.field);
                        checks.push(
                            quote!(#rc.follows_request(#mine.len(), #b as i64, (#args), #rule)?;),
                        );
                    }
                }
            }
            let cv = variant(cmd);
            // A view's variant holds its fields, bound by name; an owned response's, its
            // message's struct (`m`); the request's struct is `r`.
            let mine_pat = match (ctx.view.get(), own.is_empty()) {
                (true, _) => quote!(&Self::#v { #(#own,)* .. }),
                (false, false) => quote!(Self::#v(m)),
                (false, true) => quote!(Self::#v(_)),
            };
            let theirs_pat = if theirs.is_empty() {
                quote!(Request::#cv(_))
            } else {
                quote!(Request::#cv(r))
            };
            arms.push(quote! {
                (#mine_pat, #theirs_pat) => {
                    #(#checks)*
                }
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

use super::*;

pub(super) fn is_identity(u: &Unit) -> bool {
    u.scale == Rational::ONE && u.offset == Rational::ZERO
}

pub(super) fn emit_units(ctx: &Ctx) -> TokenStream {
    let mut out = TokenStream::new();
    for (i, u) in ctx.p.units.iter().enumerate() {
        let Some(raw) = ctx.unit_raw[i] else { continue };
        if is_identity(u) {
            continue;
        }
        let ty = type_ident(&u.name);
        let r = raw.ident();
        let sym = &u.symbol;
        let (sn, sd) = (u.scale.num as f64, u.scale.den as f64);
        let (on, od) = (u.offset.num as f64, u.offset.den as f64);
        // raw × num / den + offset, and back, without the factors that are 1 or the offset
        // that is 0 (each an identity in f64: a raw integer is never -0).
        let times = |x: TokenStream, num: f64, den: f64| {
            let x = if num == 1.0 { x } else { quote!(#x * #num) };
            if den == 1.0 {
                x
            } else {
                quote!(#x / #den)
            }
        };
        // The offset as a magnitude added or taken away (x + (−m) is x − m exactly).
        let magnitude = on.abs();
        let offset = match (on == 0.0, od == 1.0) {
            (true, _) => None,
            (false, true) => Some(quote!(#magnitude)),
            (false, false) => Some(quote!((#magnitude / #od))),
        };
        let negative = on < 0.0;
        let value = times(quote!(self.0 as f64), sn, sd);
        let value = match (&offset, negative) {
            (Some(o), true) => quote!(#value - #o),
            (Some(o), false) => quote!(#value + #o),
            (None, _) => value,
        };
        let unshifted = match (&offset, negative) {
            (Some(o), true) => quote!(value + #o),
            (Some(o), false) => quote!(value - #o),
            (None, _) => quote!(value),
        };
        let scaled = sn != 1.0 || sd != 1.0;
        let unshifted = if offset.is_some() && scaled {
            quote!((#unshifted))
        } else {
            unshifted
        };
        let raw_of = times(unshifted, sd, sn);
        let debug = format!(
            "{}({{}} = {{}}{}{})",
            ty,
            if sym.is_empty() { "" } else { " " },
            sym.replace('{', "{{").replace('}', "}}")
        );
        let d = doc(&format!(
            "{}\n\nPhysical value = raw × {}{}.",
            if u.doc.is_empty() { &u.name } else { &u.doc },
            u.scale,
            match u.offset.num {
                0 => String::new(),
                n => format!(
                    " {} {}",
                    if n < 0 { "−" } else { "+" },
                    Rational {
                        num: n.abs(),
                        den: u.offset.den
                    }
                ),
            }
        ));
        let (lo, hi) = raw.limits();
        let (lo, hi) = (Literal::i64_unsuffixed(lo), Literal::i64_unsuffixed(hi));
        out.extend(quote! {
            #d
            #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
            #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
            #[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
            pub struct #ty(pub #r);
            /// Shows the raw value and the physical one.
            impl rt::Debug for #ty {
                fn fmt(&self, f: &mut rt::Formatter<'_>) -> rt::FmtResult {
                    write!(f, #debug, self.0, self.value())
                }
            }
            impl #ty {
                /// The unit's symbol.
                pub const SYMBOL: &'static str = #sym;
                /// The raw wire value.
                #[inline]
                pub const fn raw(self) -> #r { self.0 }
                /// From a raw wire value.
                #[inline]
                pub const fn from_raw(raw: #r) -> Self { Self(raw) }
                /// The physical value, in [`Self::SYMBOL`].
                #[inline]
                pub fn value(self) -> f64 {
                    #value
                }
                /// The raw value nearest to a physical value; `None` if it is not finite or out of range.
                pub fn from_value(value: f64) -> rt::Option<Self> {
                    let raw = rt::round(#raw_of)?;
                    if !(#lo..=#hi).contains(&raw) {
                        return rt::None;
                    }
                    rt::Some(Self(raw as #r))
                }
            }
        });
        if list_elements(ctx).contains(&ty.to_string()) {
            out.extend(wire_impl(&ty, raw, quote!(Self(v as #r)), quote!(self.0)));
        }
    }
    out
}

/// The names of the spec's types some repeated field's elements take (`Kind::List`'s `typed`).
fn list_elements(ctx: &Ctx) -> Vec<String> {
    ctx.p
        .commands
        .iter()
        .chain(&ctx.p.responses)
        .flat_map(|m| &m.fields)
        .filter_map(|f| ctx.element_type(f))
        .map(|t| t.to_string())
        .collect()
}

/// `rt::Wire` for a type of the spec's a list's elements take, over its raw type `raw`:
/// `from` makes it from the raw `v: i64`, `to` is its raw value.
fn wire_impl(ty: &Ident, raw: IntType, from: TokenStream, to: TokenStream) -> TokenStream {
    let (lo, hi) = raw.limits();
    let (lo, hi) = (i64_lit(lo), i64_lit(hi));
    let d = " A list's element: its raw value as it travels.";
    quote! {
        #[doc = #d]
        impl rt::Wire for #ty {
            const MIN: i64 = #lo;
            const MAX: i64 = #hi;
            #[inline]
            fn from_i64(v: i64) -> Self {
                #from
            }
            #[inline]
            fn to_i64(self) -> i64 {
                #to as i64
            }
            #[inline]
            fn to_u64(self) -> u64 {
                #to as u64
            }
        }
    }
}

pub(super) fn emit_enums(ctx: &Ctx) -> TokenStream {
    let mut out = TokenStream::new();
    for (i, e) in ctx.p.enums.iter().enumerate() {
        let ty = type_ident(&e.name);
        let raw = ctx.enum_raw[i];
        let r = raw.ident();
        let d = doc(&format!("{}{}\n\nOpen: a value this revision does not list decodes as `Unknown(raw)` and re-encodes unchanged.", e.doc, e.section.as_ref().map(|s| format!(" (§{s})")).unwrap_or_default()));
        let variants: Vec<TokenStream> = e
            .values
            .iter()
            .map(|v| {
                let n = type_ident(&v.name);
                let d = doc(&format!("{} ({})", v.doc, v.value));
                quote!(#d #n)
            })
            .collect();
        let from: Vec<TokenStream> = e
            .values
            .iter()
            .map(|v| {
                let n = type_ident(&v.name);
                let l = lit_u(v.value, raw);
                quote!(#l => Self::#n)
            })
            .collect();
        let to: Vec<TokenStream> = e
            .values
            .iter()
            .map(|v| {
                let n = type_ident(&v.name);
                let l = lit_u(v.value, raw);
                quote!(Self::#n => #l)
            })
            .collect();
        let names: Vec<TokenStream> = e
            .values
            .iter()
            .map(|v| {
                let n = type_ident(&v.name);
                let s = &v.name;
                quote!(Self::#n => rt::Some(#s))
            })
            .collect();
        out.extend(quote! {
            #d
            #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
            #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
            pub enum #ty {
                #(#variants,)*
                /// A value this revision of the document does not list.
                Unknown(#r),
            }
            /// Not derived: an arbitrary value goes through `from_raw`, so `Unknown` never holds
            /// a listed value (which would encode as that value and decode as its variant).
            #[cfg(feature = "arbitrary")]
            impl<'a> ::arbitrary::Arbitrary<'a> for #ty {
                fn arbitrary(u: &mut ::arbitrary::Unstructured<'a>) -> ::arbitrary::Result<Self> {
                    rt::Ok(Self::from_raw(<#r as ::arbitrary::Arbitrary<'a>>::arbitrary(u)?))
                }
                fn size_hint(depth: usize) -> (usize, rt::Option<usize>) {
                    <#r as ::arbitrary::Arbitrary<'a>>::size_hint(depth)
                }
            }
            impl #ty {
                /// From a raw wire value; never fails.
                pub const fn from_raw(raw: #r) -> Self {
                    match raw {
                        #(#from,)*
                        other => Self::Unknown(other),
                    }
                }
                /// The raw wire value.
                pub const fn raw(self) -> #r {
                    match self {
                        #(#to,)*
                        Self::Unknown(raw) => raw,
                    }
                }
                /// The spec's name of this value, `None` for `Unknown`.
                pub const fn name(self) -> rt::Option<&'static str> {
                    match self {
                        #(#names,)*
                        Self::Unknown(_) => rt::None,
                    }
                }
            }
        });
        if list_elements(ctx).contains(&ty.to_string()) {
            out.extend(wire_impl(
                &ty,
                raw,
                quote!(Self::from_raw(v as #r)),
                quote!(self.raw()),
            ));
            out.extend(quote! {
                /// A list's empty slots: raw 0.
                impl ::core::default::Default for #ty {
                    fn default() -> Self {
                        Self::from_raw(0)
                    }
                }
            });
        }
    }
    out
}

pub(super) fn emit_flags(ctx: &Ctx) -> TokenStream {
    let mut out = TokenStream::new();
    for (i, f) in ctx.p.flags.iter().enumerate() {
        let ty = type_ident(&f.name);
        let raw = ctx.flag_raw[i];
        let r = raw.ident();
        let d = doc(&format!(
            "{}{}",
            f.doc,
            f.section
                .as_ref()
                .map(|s| format!(" (§{s})"))
                .unwrap_or_default()
        ));
        let consts: Vec<TokenStream> = f
            .bits
            .iter()
            .map(|b| {
                let n = format_ident!("{}", b.name.to_ascii_uppercase());
                let d = doc(&format!("Bit {}: {}", b.bit, b.doc));
                let l = lit_u(1u64 << b.bit, raw);
                quote!(#d pub const #n: Self = Self(#l);)
            })
            .collect();
        let all: u64 = f.bits.iter().map(|b| 1u64 << b.bit).sum();
        // Every bit named: none is unnamed (`x & !0xFF` is always 0, which clippy refuses).
        let unnamed = if raw.bits < 64 && all == (1u64 << raw.bits) - 1 {
            quote!(0)
        } else {
            let all = lit_u(all, raw);
            quote!(self.0 & !#all)
        };
        let names: Vec<TokenStream> = f
            .bits
            .iter()
            .map(|b| {
                let n = format_ident!("{}", b.name.to_ascii_uppercase());
                let s = &b.name;
                quote!((Self::#n, #s))
            })
            .collect();
        let count = f.bits.len();
        out.extend(quote! {
            #d
            #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
            #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
            #[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
            pub struct #ty(pub #r);
            impl #ty {
                #(#consts)*
                /// Every named flag, with its spec name.
                pub const NAMED: [(Self, &'static str); #count] = [#(#names),*];
                /// The bits no name is given to; a newer firmware may set them.
                pub const fn unnamed(self) -> #r { #unnamed }
                /// Whether every bit of `other` is set.
                pub const fn contains(self, other: Self) -> bool { self.0 & other.0 == other.0 }
                /// The raw wire value.
                pub const fn raw(self) -> #r { self.0 }
                /// From a raw wire value; every bit is kept.
                pub const fn from_raw(raw: #r) -> Self { Self(raw) }
            }
        });
    }
    out
}

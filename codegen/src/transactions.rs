//! What a spec's `transactions:` section declares, as generated code: the `transactions`
//! of the protocol's `rt::Bus` and, where the section's `retry` differs from the default by
//! kind, which commands a master may send again (`rt::Command::may_retry`). A spec without
//! the section gets the runtime's defaults.

use proc_macro2::TokenStream;
use quote::quote;

use busspec_model::ir::Protocol;

/// The `rt::Transactions` value of the protocol's bus.
pub fn transactions(p: &Protocol) -> TokenStream {
    let t = &p.transactions;
    if !t.declared {
        return quote!(rt::Transactions::UNDECLARED);
    }
    let opt = |v: Option<u32>| match v {
        Some(v) => quote!(rt::Some(#v)),
        None => quote!(rt::None),
    };
    let (timeout, turnaround) = (opt(t.response_timeout_us), opt(t.turnaround_us));
    let tenths = opt(t.gap.map(|g| g.tenths));
    let at_least = t.gap.map_or(0, |g| g.at_least_us);
    let bits = t.character_bits;
    quote! {
        rt::Transactions {
            response_timeout_us: #timeout,
            turnaround_us: #turnaround,
            gap_tenths_of_character: #tenths,
            gap_at_least_us: #at_least,
            character_bits: #bits,
        }
    }
}

/// Whether `self` (a `Request`) may be sent again, given `kind`, its `rt::CommandKind`: by
/// its kind unless the section's `retry` says otherwise for some command. `any_of` is the
/// emitter's pattern matching any value of a command's variant.
pub fn may_retry(
    p: &Protocol,
    kind: TokenStream,
    any_of: impl Fn(&busspec_model::ir::Message) -> TokenStream,
) -> TokenStream {
    let t = &p.transactions;
    // The commands whose safety differs from their kind's default in the runtime.
    let by_default = |c: &busspec_model::ir::Message| match c.kind {
        busspec_model::ir::MessageKind::Command(k) => {
            busspec_model::transactions::DEFAULT_SAFE_KINDS.contains(&k)
        }
        busspec_model::ir::MessageKind::Response(_) => false,
    };
    if !t.declared || !p.commands.iter().any(|c| t.retry_safe(c) != by_default(c)) {
        return quote!(#kind.safe_to_repeat());
    }
    let safe: Vec<TokenStream> = p
        .commands
        .iter()
        .filter(|c| t.retry_safe(c))
        .map(&any_of)
        .collect();
    if safe.is_empty() {
        quote!(false)
    } else {
        quote!(matches!(self, #(#safe)|*))
    }
}

//! The `Protocol` items a spec's `transactions:` section declares: `TRANSACTIONS` and, where
//! the section's `retry` differs from the default by kind, `may_retry`. A spec without the
//! section gets the trait's defaults, and its module no line more.

use proc_macro2::TokenStream;
use quote::quote;

use busspec_model::ir::Protocol;

/// The items inside `impl rt::Protocol for ...` (empty without the section). `any_of` is the
/// emitter's pattern matching any value of a command's variant.
pub fn protocol_items(
    p: &Protocol,
    any_of: impl Fn(&busspec_model::ir::Message) -> TokenStream,
) -> TokenStream {
    let t = &p.transactions;
    if !t.declared {
        return quote!();
    }
    let opt = |v: Option<u32>| match v {
        Some(v) => quote!(rt::Some(#v)),
        None => quote!(rt::None),
    };
    let (timeout, turnaround) = (opt(t.response_timeout_us), opt(t.turnaround_us));
    let tenths = opt(t.gap.map(|g| g.tenths));
    let at_least = t.gap.map_or(0, |g| g.at_least_us);
    let bits = t.character_bits;
    // The commands whose safety differs from their kind's default in the runtime.
    let by_default = |c: &busspec_model::ir::Message| match c.kind {
        busspec_model::ir::MessageKind::Command(k) => {
            busspec_model::transactions::DEFAULT_SAFE_KINDS.contains(&k)
        }
        busspec_model::ir::MessageKind::Response(_) => false,
    };
    let differs = p.commands.iter().any(|c| t.retry_safe(c) != by_default(c));
    let may_retry = if differs {
        let safe: Vec<TokenStream> = p
            .commands
            .iter()
            .filter(|c| t.retry_safe(c))
            .map(&any_of)
            .collect();
        let body = if safe.is_empty() {
            quote!(false)
        } else {
            quote!(matches!(request, #(#safe)|*))
        };
        let param = if safe.is_empty() {
            quote!(_request)
        } else {
            quote!(request)
        };
        quote! {
            #[inline]
            fn may_retry(#param: &Request) -> bool {
                #body
            }
        }
    } else {
        quote!()
    };
    quote! {
        const TRANSACTIONS: ::busspec_runtime::Transactions = ::busspec_runtime::Transactions {
            response_timeout_us: #timeout,
            turnaround_us: #turnaround,
            gap_tenths_of_character: #tenths,
            gap_at_least_us: #at_least,
            character_bits: #bits,
        };
        #may_retry
    }
}

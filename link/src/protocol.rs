//! What a bus master adds to a protocol beyond its spec: the [`Link`] extension trait, which
//! lives in `busspec-link-core` (the `no_std` master keeps every rule), and what only a `std`
//! master says about it.

pub use busspec_link_core::link::*;

use busspec_runtime::Protocol;

/// Where the spec declares its byte order, to quote in a message:
/// `spec/ub2.yaml:8: byte_order: little`.
pub fn byte_order_source<P: Protocol>() -> String {
    match spec_byte_order_line::<P>() {
        Some((n, line)) => format!("spec/{}.yaml:{n}: {line}", P::NAME),
        None => format!("spec/{}.yaml: no byte_order line", P::NAME),
    }
}

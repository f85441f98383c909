//! Differential testing of busspec's two engines over random valid specs: the generated code
//! (`busspec_codegen`) and the interpreter (`busspec_model::interp`, `busspec_model::stream`)
//! must accept, refuse, encode and split streams alike for every spec the validator accepts.
//!
//! * [`gen`]: random valid specs ([`gen::random_spec`]), deterministic in a seed;
//! * [`compare`]: the comparison for one generated protocol, generic over its
//!   `busspec_runtime::Protocol` type, recording disagreements instead of stopping at the first;
//! * [`batch`]: writes a batch of specs as one crate (one rustc run for many specs), whose
//!   `main` runs [`compare`] on each; the `busspec-difftest` binary drives rounds of it.
//!
//! `FUZZING.md` ("Random specs") says how to run it, reproduce a disagreement and keep it as a
//! fixture in `difftest/fixtures/`.

pub mod batch;
pub mod compare;
pub mod gen;
pub mod values;

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| busspec_fuzz_bodies::pelco_p::generated_decode(data));

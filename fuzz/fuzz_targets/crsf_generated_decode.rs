#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| busspec_fuzz_bodies::crsf::generated_decode(data));

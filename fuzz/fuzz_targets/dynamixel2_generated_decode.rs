#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| busspec_fuzz_bodies::dynamixel2::generated_decode(data));

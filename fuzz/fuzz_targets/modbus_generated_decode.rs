#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| busspec_fuzz_bodies::modbus::generated_decode(data));

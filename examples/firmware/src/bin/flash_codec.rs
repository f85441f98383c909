//! Flash probe (BENCHMARKS.md): the SD codec alone — decode any request and any reply from
//! bytes the linker cannot see, encode them back — as the baseline for `flash_core`.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod probe {
    use busspec_devices::{Protocol, Sd};

    #[no_mangle]
    pub extern "C" fn _start() -> ! {
        let mut out = [0u8; 8];
        loop {
            let frame: [u8; 6] = core::hint::black_box([0; 6]);
            if let Ok(d) = Sd::decode_request(&frame) {
                let _ = core::hint::black_box(d.message.encode(d.address, &mut out));
                if let Ok(r) = Sd::decode_reply(core::hint::black_box(&frame), &d.message) {
                    let _ = core::hint::black_box(r.message.encode(r.address, &mut out));
                }
            }
        }
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        loop {
            core::hint::spin_loop();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}

//! Flash probe (BENCHMARKS.md): the sans-IO master core with the SD codec — every request
//! decoded from bytes the linker cannot see goes through `MasterCore` (gap, pairing, retries,
//! freshness, settle), fed with unseen bytes and times — without any driver.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod probe {
    use core::hint::black_box;
    use core::time::Duration;

    use busspec_devices::{Protocol, Sd};
    use busspec_link_core::master::{Action, MasterCore};

    #[no_mangle]
    pub extern "C" fn _start() -> ! {
        let mut core: MasterCore<Sd> = MasterCore::new();
        loop {
            let frame: [u8; 6] = black_box([0; 6]);
            let Ok(d) = Sd::decode_request(&frame) else {
                continue;
            };
            core.start(d.address, d.message);
            loop {
                let now = Duration::from_micros(black_box(0));
                match core.poll(now) {
                    Action::Done => break,
                    Action::Write(bytes) => {
                        black_box(bytes);
                    }
                    _ => core.received(black_box(&frame), now),
                }
            }
            black_box(core.take_outcome());
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

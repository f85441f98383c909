//! The Modbus master variant as firmware for a Cortex-M4F (thumbv7em-none-eabihf): the board's
//! UART, timer and driver-enable pin (`board.rs`) under the `embedded-io-async` driver, polling
//! device 1 with `modbus::poll_and_count` through link-core's `Plain<Modbus>`. Built for the target in
//! CI with the other firmware binaries (BENCHMARKS.md: flash). On a host it only says so.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
#[path = "../board.rs"]
mod board;

#[cfg(target_os = "none")]
mod firmware {
    use busspec_firmware_example::modbus::poll_and_count;
    use busspec_link_core::nonblocking::Driver;
    use busspec_link_core::{DriverEnable, Line, Plain};
    use busspec_protocols::modbus::Modbus;

    use crate::board::{block_on, DePin, Timer, Uart};

    #[no_mangle]
    pub extern "C" fn _start() -> ! {
        let mut line = Line::for_protocol::<Plain<Modbus>>();
        line.driver_enable = Some(DriverEnable::Computed);
        let mut driver: Driver<Plain<Modbus>, _, _, _, _> = Driver::new(Uart, Timer, Timer)
            .with_driver_enable(DePin)
            .with_line(line);
        let start = core::hint::black_box(0u16);
        loop {
            let report = block_on(poll_and_count(&mut driver, 1, start, 8));
            core::hint::black_box(&report);
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
fn main() {
    println!(
        "Modbus master firmware for a Cortex-M4F: cargo build -p busspec-firmware-example \
         --bin modbus_master --profile firmware --target thumbv7em-none-eabihf"
    );
}

//! The set-point loop as firmware for a Cortex-M4F (thumbv7em-none-eabihf): the board's
//! UART, timer and driver-enable pin (`board.rs`) under the `embedded-io-async` driver, with
//! the RS485 line's driver enable timed from the baud rate. Built for the target in CI:
//! `cargo build -p busspec-firmware-example --bin busspec-firmware-example --profile firmware
//! --target thumbv7em-none-eabihf`. On a host it only says so.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod board;

#[cfg(target_os = "none")]
mod firmware {
    use busspec_devices::Sd;
    use busspec_firmware_example::set_point_loop;
    use busspec_link_core::nonblocking::Driver;
    use busspec_link_core::{DriverEnable, Line};

    use crate::board::{block_on, DePin, Timer, Uart};

    #[no_mangle]
    pub extern "C" fn _start() -> ! {
        let mut line = Line::for_protocol::<Sd>();
        line.driver_enable = Some(DriverEnable::Computed);
        // SD's frames are 6 bytes: a 32-byte receive buffer (four frames and more) instead of
        // the default 1024 keeps about 1 KiB of RAM off the stack.
        let mut driver: Driver<Sd, _, _, _, _, 32> = Driver::new(Uart, Timer, Timer)
            .with_driver_enable(DePin)
            .with_line(line);
        let targets = core::hint::black_box([0i16, 512, 1024, -512]);
        loop {
            let report = block_on(set_point_loop(&mut driver, 1, &targets));
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
        "firmware for a Cortex-M4F: cargo build -p busspec-firmware-example --profile firmware \
         --target thumbv7em-none-eabihf"
    );
}

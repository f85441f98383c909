//! The board shape the thumb binaries are built for: a UART, a microsecond timer and a
//! driver-enable pin, as registers an interrupt handler fills (atomics here, so the
//! binaries build without a HAL), and a spinning executor. It need not run; it must build,
//! with everything the driver needs linked in.

use core::sync::atomic::{AtomicBool, AtomicU32, AtomicU8, Ordering};
use core::task::{Context, Poll, RawWaker, RawWakerVTable, Waker};
use core::time::Duration;

use busspec_link_core::driver::Now;
use embedded_io_async::{ErrorKind, ErrorType, Read, ReadReady, Write};

/// The receive register and its "full" flag (set by the UART's interrupt).
pub static RX_BYTE: AtomicU8 = AtomicU8::new(0);
pub static RX_FULL: AtomicBool = AtomicBool::new(false);
/// The transmit register.
pub static TX_BYTE: AtomicU8 = AtomicU8::new(0);
/// A free-running microsecond counter (a timer's interrupt counts it up).
pub static MICROS: AtomicU32 = AtomicU32::new(0);
/// The transceiver's driver-enable line.
pub static DE: AtomicBool = AtomicBool::new(false);

pub struct Uart;

impl ErrorType for Uart {
    type Error = ErrorKind;
}

impl ReadReady for Uart {
    fn read_ready(&mut self) -> Result<bool, ErrorKind> {
        Ok(RX_FULL.load(Ordering::Acquire))
    }
}

impl Read for Uart {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
        if buf.is_empty() {
            return Ok(0);
        }
        while !RX_FULL.load(Ordering::Acquire) {
            core::hint::spin_loop();
        }
        buf[0] = RX_BYTE.load(Ordering::Relaxed);
        RX_FULL.store(false, Ordering::Release);
        Ok(1)
    }
}

impl Write for Uart {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        for &b in buf {
            TX_BYTE.store(b, Ordering::Release);
        }
        Ok(buf.len())
    }

    async fn flush(&mut self) -> Result<(), ErrorKind> {
        Ok(())
    }
}

pub struct Timer;

impl Now for Timer {
    fn now(&self) -> Duration {
        Duration::from_micros(u64::from(MICROS.load(Ordering::Relaxed)))
    }
}

impl embedded_hal_async::delay::DelayNs for Timer {
    async fn delay_ns(&mut self, ns: u32) {
        let start = MICROS.load(Ordering::Relaxed);
        let wait = ns.div_ceil(1000);
        while MICROS.load(Ordering::Relaxed).wrapping_sub(start) < wait {
            core::hint::spin_loop();
        }
    }
}

pub struct DePin;

impl embedded_hal::digital::ErrorType for DePin {
    type Error = core::convert::Infallible;
}

impl embedded_hal::digital::OutputPin for DePin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        DE.store(false, Ordering::Release);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        DE.store(true, Ordering::Release);
        Ok(())
    }
}

const VTABLE: RawWakerVTable = RawWakerVTable::new(|_| RAW, |_| {}, |_| {}, |_| {});
const RAW: RawWaker = RawWaker::new(core::ptr::null(), &VTABLE);

/// Polls `f` until it is done: the executor of a board with one task.
pub fn block_on<F: core::future::Future>(f: F) -> F::Output {
    // SAFETY: every function of the vtable ignores its data pointer and does nothing, which
    // satisfies RawWaker's contract for any pointer.
    let waker = unsafe { Waker::from_raw(RAW) };
    let mut cx = Context::from_waker(&waker);
    let mut f = core::pin::pin!(f);
    loop {
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
}

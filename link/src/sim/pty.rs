//! Simulators on a pseudo-terminal, served in a thread: the other end is a real serial port
//! for any driver (the tokio one, an external program). What `busspec sim --pty` does, in
//! process.

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use crate::clock::SystemClock;
use crate::sim::{serve, Device};
use crate::transport::SerialTransport;

/// Devices served on one end of a pseudo-terminal pair until this is dropped.
pub struct PtySim {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<io::Result<()>>>,
}

impl PtySim {
    /// Opens a pseudo-terminal pair, serves `devices` on one end in a thread (frames end after
    /// 3 ms of quiet) and returns the other end.
    pub fn spawn<D: Device + Send + 'static>(
        mut devices: Vec<D>,
    ) -> io::Result<(serialport::TTYPort, PtySim)> {
        let (master_end, device_end) = serialport::TTYPort::pair()
            .map_err(|e| io::Error::other(format!("cannot open a pseudo-terminal: {e}")))?;
        let stop = Arc::new(AtomicBool::new(false));
        let keep = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            let mut port = SerialTransport::from_port(Box::new(device_end));
            let clock = SystemClock::new();
            serve(
                &mut port,
                &clock,
                &mut devices,
                Duration::from_millis(3),
                || !keep.load(Ordering::Relaxed),
                |_, _| {},
            )
        });
        Ok((
            master_end,
            PtySim {
                stop,
                thread: Some(thread),
            },
        ))
    }
}

impl Drop for PtySim {
    /// Stops serving (within one frame gap) and waits for the thread.
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

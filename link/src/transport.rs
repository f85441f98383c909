//! Byte transports: what a master writes requests to and reads replies from.

use std::io;
use std::time::Duration;

/// A half-duplex byte pipe to a bus.
///
/// `read` waits at most `timeout` for bytes and returns how many it put in `buf`; `Ok(0)` means
/// nothing arrived in time (a timeout is not an error at this level). Implementations on a
/// simulated clock advance that clock instead of blocking.
pub trait Transport {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()>;
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize>;
    /// Discards bytes received but not yet read.
    fn clear_input(&mut self) -> io::Result<()>;
    /// Drives the RS485 driver-enable line, where the port has one ([`crate::Line`]'s
    /// `driver_enable`); nothing by default.
    fn set_driver_enable(&mut self, _on: bool) -> io::Result<()> {
        Ok(())
    }
}

impl<T: Transport + ?Sized> Transport for Box<T> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        (**self).write(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        (**self).read(buf, timeout)
    }
    fn clear_input(&mut self) -> io::Result<()> {
        (**self).clear_input()
    }
    fn set_driver_enable(&mut self, on: bool) -> io::Result<()> {
        (**self).set_driver_enable(on)
    }
}

/// A serial port (or a pseudo-terminal) opened through the `serialport` crate.
#[cfg(feature = "serial")]
pub struct SerialTransport {
    port: Box<dyn serialport::SerialPort>,
}

#[cfg(feature = "serial")]
impl SerialTransport {
    /// Opens `path` at `baud`, 8 data bits, no parity, 1 stop bit (both documents' defaults).
    pub fn open(path: &str, baud: u32) -> io::Result<Self> {
        let port = serialport::new(path, baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(10))
            .open()
            .map_err(|e| io::Error::other(format!("cannot open serial port {path}: {e}")))?;
        Ok(SerialTransport { port })
    }

    /// Wraps a port opened elsewhere (for instance one end of a pseudo-terminal pair).
    pub fn from_port(port: Box<dyn serialport::SerialPort>) -> Self {
        SerialTransport { port }
    }
}

#[cfg(feature = "serial")]
fn serial_error(e: serialport::Error) -> io::Error {
    io::Error::other(e.to_string())
}

#[cfg(feature = "serial")]
impl Transport for SerialTransport {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.port.write_all(bytes)?;
        self.port.flush()
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        // serialport treats a zero timeout as "wait forever" on some platforms.
        let timeout = timeout.max(Duration::from_millis(1));
        self.port.set_timeout(timeout).map_err(serial_error)?;
        match self.port.read(buf) {
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::TimedOut => Ok(0),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn clear_input(&mut self) -> io::Result<()> {
        self.port
            .clear(serialport::ClearBuffer::Input)
            .map_err(serial_error)
    }

    /// RTS as the driver-enable line, as RS485 adapters without automatic direction wire it.
    fn set_driver_enable(&mut self, on: bool) -> io::Result<()> {
        self.port.write_request_to_send(on).map_err(serial_error)
    }
}

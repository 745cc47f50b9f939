//! Where a device's bytes come from: a serial port (`/dev/ttyUSB0`, 8N1 at the device's rate) or a
//! TCP connection (`tcp:HOST:PORT`: a serial-over-IP bridge, or `twin serve`).

use core::fmt;
use core::str::FromStr;
use core::time::Duration;
use std::io::{self, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::path::PathBuf;

/// An address a device can be reached at.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Endpoint {
    /// A serial device path such as `/dev/ttyUSB0` (or `COM3`).
    Serial(PathBuf),
    /// `tcp:HOST:PORT`.
    Tcp(String),
}

/// An endpoint that does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "`{given}` is not a device address: expected a serial device path (/dev/ttyUSB0, COM3) or tcp:HOST:PORT"
)]
pub struct EndpointError {
    /// What was given.
    pub given: String,
}

impl FromStr for Endpoint {
    type Err = EndpointError;

    /// ```
    /// use robot::serial::Endpoint;
    /// assert_eq!("tcp:127.0.0.1:4001".parse(), Ok(Endpoint::Tcp("127.0.0.1:4001".into())));
    /// assert!(matches!("/dev/ttyUSB0".parse(), Ok(Endpoint::Serial(_))));
    /// assert!("ttyUSB0".parse::<Endpoint>().is_err());
    /// assert!("tcp:localhost".parse::<Endpoint>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || EndpointError { given: s.into() };
        if let Some(address) = s.strip_prefix("tcp:") {
            let (host, port) = address.rsplit_once(':').ok_or_else(bad)?;
            if host.is_empty() || port.parse::<u16>().is_err() {
                return Err(bad());
            }
            return Ok(Endpoint::Tcp(address.into()));
        }
        let is_com = s.len() > 3
            && s[..3].eq_ignore_ascii_case("com")
            && s[3..].bytes().all(|b| b.is_ascii_digit());
        if s.starts_with('/') || is_com {
            Ok(Endpoint::Serial(s.into()))
        } else {
            Err(bad())
        }
    }
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Endpoint::Serial(path) => write!(f, "{}", path.display()),
            Endpoint::Tcp(address) => write!(f, "tcp:{address}"),
        }
    }
}

/// An open byte stream to a device. Reads wait at most the poll interval set with
/// [`Port::set_poll`], then fail with `TimedOut`/`WouldBlock`.
pub trait Port: Read + Write + Send {
    /// Sets how long a read waits for the first byte.
    fn set_poll(&mut self, poll: Duration) -> io::Result<()>;
    /// A second handle on the same stream (for a reader thread).
    fn try_clone_port(&self) -> io::Result<Box<dyn Port>>;
}

impl Port for TcpStream {
    fn set_poll(&mut self, poll: Duration) -> io::Result<()> {
        self.set_read_timeout(Some(poll.max(Duration::from_micros(1))))
    }
    fn try_clone_port(&self) -> io::Result<Box<dyn Port>> {
        Ok(Box::new(self.try_clone()?))
    }
}

impl Port for Box<dyn serialport::SerialPort> {
    fn set_poll(&mut self, poll: Duration) -> io::Result<()> {
        self.set_timeout(poll).map_err(io::Error::from)
    }
    fn try_clone_port(&self) -> io::Result<Box<dyn Port>> {
        Ok(Box::new(self.try_clone().map_err(io::Error::from)?))
    }
}

/// How long opening a TCP connection may take.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(2);

/// Opens `endpoint`: a serial port at `baud` 8N1 without flow control, or a TCP connection (the
/// bridge sets the rate). Reads then wait at most `poll`.
pub fn open(endpoint: &Endpoint, baud: u32, poll: Duration) -> io::Result<Box<dyn Port>> {
    let mut port: Box<dyn Port> = match endpoint {
        Endpoint::Serial(path) => {
            let port = serialport::new(path.to_string_lossy(), baud)
                .data_bits(serialport::DataBits::Eight)
                .parity(serialport::Parity::None)
                .stop_bits(serialport::StopBits::One)
                .flow_control(serialport::FlowControl::None)
                .timeout(poll)
                .open()
                .map_err(io::Error::from)?;
            Box::new(port)
        }
        Endpoint::Tcp(address) => {
            let mut last = io::Error::new(io::ErrorKind::NotFound, "the name resolves to nothing");
            let mut connected = None;
            for addr in address.to_socket_addrs()? {
                match TcpStream::connect_timeout(&addr, CONNECT_TIMEOUT) {
                    Ok(stream) => {
                        connected = Some(stream);
                        break;
                    }
                    Err(e) => last = e,
                }
            }
            let stream = connected.ok_or(last)?;
            stream.set_nodelay(true)?;
            Box::new(stream)
        }
    };
    port.set_poll(poll)?;
    Ok(port)
}

//! Byte transports to a controller, behind one trait: TCP/telnet (FluidNC, ESP32 boards), a
//! serial port, and a pseudo-terminal; plus in-memory pipes for tests.
//!
//! A transport is any `AsyncRead + AsyncWrite` byte stream ([`Transport`]); a [`Connect`]
//! opens a fresh one, which is what reconnecting after a link drop needs.
//!
//! Serial ports: the `serialport` crate opens and configures the port (baud, 8N1, no flow
//! control, exclusive access); its file descriptor is then driven by tokio's `AsyncFd` in
//! non-blocking mode, exactly like the pseudo-terminal. This keeps the crate off `tokio-serial`
//! and `mio-serial` (one extra layer and their own pinned `serialport`/`mio` versions) and needs
//! no blocking threads; it is Unix-only, like the rest of this ROS 2 suite.

use std::future::Future;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, IntoRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use tokio::io::unix::AsyncFd;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};

/// A bidirectional byte stream to a controller.
pub trait Transport: AsyncRead + AsyncWrite + Send + Unpin + 'static {}

impl<T: AsyncRead + AsyncWrite + Send + Unpin + 'static> Transport for T {}

/// A boxed [`Transport`].
pub type BoxedTransport = Box<dyn Transport>;

/// The future a [`Connect`] returns.
pub type ConnectFuture<'a> = Pin<Box<dyn Future<Output = io::Result<BoxedTransport>> + Send + 'a>>;

/// Opens a new connection to the same controller (first connection and every reconnect).
pub trait Connect: Send + Sync {
    /// Opens the link.
    fn connect(&self) -> ConnectFuture<'_>;
    /// A short human-readable description (`tcp 127.0.0.1:23`, `serial /dev/ttyUSB0`).
    fn describe(&self) -> String;
}

/// The standard places a GRBL controller is reached at.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Endpoint {
    /// TCP/telnet, `host:port` (FluidNC and ESP32 boards listen on port 23).
    Tcp(String),
    /// A serial port opened at `baud` 8N1 with no flow control.
    Serial {
        /// Device path, `/dev/ttyUSB0`, `/dev/ttyACM0`.
        path: PathBuf,
        /// Baud rate (GRBL 1.1: 115 200).
        baud: u32,
    },
    /// A pseudo-terminal's device path (the `grbl_sim --pty` side), opened raw.
    Pty(PathBuf),
}

impl Connect for Endpoint {
    fn connect(&self) -> ConnectFuture<'_> {
        Box::pin(async move {
            match self {
                Endpoint::Tcp(addr) => {
                    let s = tokio::net::TcpStream::connect(addr.as_str()).await?;
                    s.set_nodelay(true)?;
                    Ok(Box::new(s) as BoxedTransport)
                }
                Endpoint::Serial { path, baud } => {
                    Ok(Box::new(open_serial(path, *baud)?) as BoxedTransport)
                }
                Endpoint::Pty(path) => Ok(Box::new(open_tty_raw(path)?) as BoxedTransport),
            }
        })
    }

    fn describe(&self) -> String {
        match self {
            Endpoint::Tcp(a) => format!("tcp {a}"),
            Endpoint::Serial { path, baud } => format!("serial {} @{baud}", path.display()),
            Endpoint::Pty(p) => format!("pty {}", p.display()),
        }
    }
}

/// A file descriptor (tty, pty master, serial port) driven by tokio in non-blocking mode.
#[derive(Debug)]
pub struct FdStream {
    fd: AsyncFd<OwnedFd>,
}

impl FdStream {
    /// Wraps `fd`, switching it to non-blocking mode. Must be called inside a tokio runtime.
    pub fn new(fd: OwnedFd) -> io::Result<FdStream> {
        set_nonblocking(fd.as_raw_fd())?;
        // SAFETY: `OwnedFd` keeps the descriptor open and unchanged for as long as the
        // `AsyncFd` owns it.
        let fd = unsafe { AsyncFd::register(fd) }.map_err(io::Error::from)?;
        Ok(FdStream { fd })
    }
}

fn set_nonblocking(fd: i32) -> io::Result<()> {
    use nix::fcntl::{fcntl, FcntlArg, OFlag};
    let flags = fcntl(fd, FcntlArg::F_GETFL).map_err(io::Error::from)?;
    let flags = OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK;
    fcntl(fd, FcntlArg::F_SETFL(flags)).map_err(io::Error::from)?;
    Ok(())
}

impl AsyncRead for FdStream {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        loop {
            let mut guard = match self.fd.poll_read_ready(cx) {
                Poll::Ready(g) => g?,
                Poll::Pending => return Poll::Pending,
            };
            let unfilled = buf.initialize_unfilled();
            match guard.try_io(|inner| {
                nix::unistd::read(inner.as_raw_fd(), unfilled).map_err(io::Error::from)
            }) {
                Ok(Ok(n)) => {
                    buf.advance(n);
                    return Poll::Ready(Ok(()));
                }
                // A pty master reads EIO once its slave side is closed: that is end of stream.
                Ok(Err(e)) if e.raw_os_error() == Some(nix::libc::EIO) => {
                    return Poll::Ready(Ok(()))
                }
                Ok(Err(e)) => return Poll::Ready(Err(e)),
                Err(_would_block) => continue,
            }
        }
    }
}

impl AsyncWrite for FdStream {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        loop {
            let mut guard = match self.fd.poll_write_ready(cx) {
                Poll::Ready(g) => g?,
                Poll::Pending => return Poll::Pending,
            };
            match guard
                .try_io(|inner| nix::unistd::write(inner.as_raw_fd(), buf).map_err(io::Error::from))
            {
                Ok(r) => return Poll::Ready(r),
                Err(_would_block) => continue,
            }
        }
    }

    fn poll_flush(self: Pin<&mut Self>, _cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Poll::Ready(Ok(()))
    }

    fn poll_shutdown(self: Pin<&mut Self>, _cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Poll::Ready(Ok(()))
    }
}

/// Puts a terminal in raw mode: no echo, no line editing, no CR/LF translation, no signals,
/// 8-bit clean (GRBL's real-time bytes 0x18 and 0x80-0xA1 pass untouched).
pub fn make_raw(fd: i32) -> io::Result<()> {
    use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
    let mut t = tcgetattr(fd).map_err(io::Error::from)?;
    cfmakeraw(&mut t);
    tcsetattr(fd, SetArg::TCSANOW, &t).map_err(io::Error::from)?;
    Ok(())
}

/// Opens a tty device (a pty slave) read/write, raw, without making it the controlling terminal.
pub fn open_tty_raw(path: &Path) -> io::Result<FdStream> {
    use nix::fcntl::{open, OFlag};
    use nix::sys::stat::Mode;
    let raw = open(
        path,
        OFlag::O_RDWR | OFlag::O_NOCTTY | OFlag::O_NONBLOCK | OFlag::O_CLOEXEC,
        Mode::empty(),
    )
    .map_err(|e| {
        io::Error::new(
            io::Error::from(e).kind(),
            format!("{}: {e}", path.display()),
        )
    })?;
    // SAFETY: `open` just returned this descriptor and nothing else owns it.
    let fd = unsafe { OwnedFd::from_raw_fd(raw) };
    make_raw(fd.as_raw_fd())?;
    FdStream::new(fd)
}

/// Opens a serial port at `baud`, 8N1, no flow control, exclusive, and drives it with tokio.
pub fn open_serial(path: &Path, baud: u32) -> io::Result<FdStream> {
    let port = serialport::new(path.to_string_lossy(), baud)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .timeout(Duration::from_millis(10))
        .open_native()
        .map_err(|e| io::Error::other(format!("{}: {e}", path.display())))?;
    // SAFETY: `into_raw_fd` hands over the descriptor `serialport` opened; it no longer owns it.
    let fd = unsafe { OwnedFd::from_raw_fd(port.into_raw_fd()) };
    FdStream::new(fd)
}

/// A pseudo-terminal pair: the master side as an async stream and the slave's device path.
///
/// The slave is opened once here and kept open (raw mode) for the pair's lifetime, so the master
/// never reads EIO between two clients opening the device.
#[derive(Debug)]
pub struct Pty {
    /// The master side (the simulator's end).
    pub master: FdStream,
    /// Device path of the slave side (`/dev/pts/N`), the path a sender opens.
    pub path: PathBuf,
    _slave: OwnedFd,
}

impl Pty {
    /// Splits the pair into the master stream, the slave path and the slave descriptor (keep the
    /// descriptor open for as long as the pty should stay usable).
    pub fn into_parts(self) -> (FdStream, PathBuf, OwnedFd) {
        (self.master, self.path, self._slave)
    }
}

/// Creates a raw pseudo-terminal pair. Must be called inside a tokio runtime.
pub fn open_pty() -> io::Result<Pty> {
    use nix::fcntl::OFlag;
    use nix::pty::{grantpt, posix_openpt, ptsname_r, unlockpt};
    let master = posix_openpt(OFlag::O_RDWR | OFlag::O_NOCTTY).map_err(io::Error::from)?;
    grantpt(&master).map_err(io::Error::from)?;
    unlockpt(&master).map_err(io::Error::from)?;
    let path = PathBuf::from(ptsname_r(&master).map_err(io::Error::from)?);
    let slave = {
        use nix::fcntl::open;
        use nix::sys::stat::Mode;
        let raw = open(
            &path,
            OFlag::O_RDWR | OFlag::O_NOCTTY | OFlag::O_CLOEXEC,
            Mode::empty(),
        )
        .map_err(io::Error::from)?;
        // SAFETY: freshly opened descriptor, owned by nobody else.
        unsafe { OwnedFd::from_raw_fd(raw) }
    };
    make_raw(slave.as_raw_fd())?;
    // SAFETY: `into_raw_fd` releases the master descriptor from `PtyMaster`.
    let master_fd = unsafe { OwnedFd::from_raw_fd(master.into_raw_fd()) };
    Ok(Pty {
        master: FdStream::new(master_fd)?,
        path,
        _slave: slave,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    #[tokio::test]
    async fn a_pty_is_raw_and_8_bit_clean() {
        let mut pty = open_pty().unwrap();
        let mut client = Endpoint::Pty(pty.path.clone()).connect().await.unwrap();
        let bytes = [b'G', b'0', b'\n', 0x18, 0x85, 0x91, b'?', b'\r'];
        client.write_all(&bytes).await.unwrap();
        let mut got = vec![0u8; bytes.len()];
        pty.master.read_exact(&mut got).await.unwrap();
        assert_eq!(got, bytes);
        pty.master.write_all(b"ok\r\n").await.unwrap();
        let mut back = [0u8; 4];
        client.read_exact(&mut back).await.unwrap();
        assert_eq!(&back, b"ok\r\n");
    }

    #[tokio::test]
    async fn a_missing_serial_port_is_an_error_naming_it() {
        let e = open_serial(Path::new("/dev/does-not-exist-grbl"), 115_200).unwrap_err();
        assert!(e.to_string().contains("/dev/does-not-exist-grbl"), "{e}");
    }
}

//! The runner's raw socket: one `AF_PACKET` socket bound to an interface,
//! read without blocking (`MSG_DONTWAIT`), waited on with `poll` and
//! written with one `send` per frame.
//!
//! pnet's channel polls before every receive and every send (two system
//! calls per direction) and waits in whole milliseconds; the runner needs
//! a receive that does not block, so it can look for a waiting frame
//! between two firmware runs and poll the socket while a cyclic master's
//! frame is due ([`super::cycle`]).
//!
//! A wait with a timeout sleeps in `poll` without one, on the socket and
//! a timerfd armed for the timeout. Measured on this project's 2-vCPU VM
//! (a C reflector as in `../shared/bench/veth-floor`, 1 kHz paced pings,
//! three interleaved runs): a frame that wakes a `poll` sleeping with its
//! own 1 ms timeout comes back 6-8 µs later (p50 17-18 µs against the
//! blocking `recvfrom` floor's 10-12 µs); with `poll(-1)` on the socket
//! and a 1 ms timerfd, or a blocking `recvfrom` with `SO_RCVTIMEO`, it is
//! at the floor (10.1-10.5 µs). The socket is created here (rustix)
//! and a duplicate of it is handed to pnet, which binds it to the
//! interface and enables promiscuous reception as before; pnet's channel
//! is then dropped, and this descriptor keeps the socket (and its
//! binding) open.

use super::RunnerError;
use pnet_datalink::{Channel, Config, NetworkInterface};
use rustix::fd::{IntoRawFd, OwnedFd};
use rustix::net::{AddressFamily, RecvFlags, SendFlags, SocketFlags, SocketType};
use std::io;
use std::time::Duration;

/// A raw socket receiving and sending every Ethernet frame of one
/// interface.
#[derive(Debug)]
pub(crate) struct PacketSocket {
    fd: OwnedFd,
    /// The timeout of [`PacketSocket::wait`] (one waiting thread at a
    /// time; a second one would only wake early).
    timer: OwnedFd,
}

impl PacketSocket {
    /// Opens a socket bound to `iface` (promiscuous).
    pub(crate) fn open(iface: &NetworkInterface) -> Result<Self, RunnerError> {
        let io_err = |source: io::Error| {
            if source.kind() == io::ErrorKind::PermissionDenied {
                RunnerError::Permission(iface.name.clone())
            } else {
                RunnerError::Io {
                    context: format!("opening raw socket on {}", iface.name),
                    source,
                }
            }
        };
        let fd = rustix::net::socket_with(
            AddressFamily::PACKET,
            SocketType::RAW,
            SocketFlags::CLOEXEC,
            Some(rustix::net::eth::ALL),
        )
        .map_err(|e| io_err(e.into()))?;
        let for_pnet = rustix::io::fcntl_dupfd_cloexec(&fd, 0).map_err(|e| io_err(e.into()))?;
        let timer = rustix::time::timerfd_create(
            rustix::time::TimerfdClockId::Monotonic,
            rustix::time::TimerfdFlags::CLOEXEC | rustix::time::TimerfdFlags::NONBLOCK,
        )
        .map_err(|e| io_err(e.into()))?;
        let cfg = Config {
            promiscuous: true,
            // pnet owns (and closes) the duplicate, also when it fails.
            socket_fd: Some(for_pnet.into_raw_fd()),
            ..Config::default()
        };
        match pnet_datalink::channel(iface, cfg) {
            // Bound, promiscuous and non-blocking (a flag of the socket,
            // shared by both descriptors); pnet's buffers are not needed.
            Ok(Channel::Ethernet(_tx, _rx)) => Ok(PacketSocket { fd, timer }),
            Ok(_) => Err(RunnerError::Io {
                context: format!("opening {}", iface.name),
                source: io::Error::other("not an Ethernet channel"),
            }),
            Err(e) => Err(io_err(e)),
        }
    }

    /// The next frame waiting on the socket, into `buf` (its length), or
    /// `None` when none is waiting. A frame longer than `buf` is cut.
    pub(crate) fn try_recv(&self, buf: &mut [u8]) -> io::Result<Option<usize>> {
        match rustix::net::recv(&self.fd, &mut *buf, RecvFlags::DONTWAIT) {
            Ok((n, _)) => Ok(Some(n)),
            Err(rustix::io::Errno::AGAIN) => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    /// Waits up to `timeout` for a frame (or an error) on the socket;
    /// whether there is one. `Duration::ZERO` only looks.
    pub(crate) fn wait(&self, timeout: Duration) -> io::Result<bool> {
        use rustix::event::{PollFd, PollFlags, Timespec};
        let ready = |r: rustix::io::Result<usize>| match r {
            Err(rustix::io::Errno::INTR) => Ok(()),
            r => r.map(|_| ()),
        };
        if timeout.is_zero() {
            let mut fds = [PollFd::new(&self.fd, PollFlags::IN)];
            ready(rustix::event::poll(&mut fds, Some(&Timespec::default())))?;
            return Ok(!fds[0].revents().is_empty());
        }
        let spec = rustix::time::Itimerspec {
            it_interval: Timespec::default(),
            it_value: Timespec {
                tv_sec: i64::try_from(timeout.as_secs()).unwrap_or(i64::MAX),
                tv_nsec: i64::from(timeout.subsec_nanos()),
            },
        };
        rustix::time::timerfd_settime(
            &self.timer,
            rustix::time::TimerfdTimerFlags::empty(),
            &spec,
        )?;
        let mut fds = [
            PollFd::new(&self.fd, PollFlags::IN),
            PollFd::new(&self.timer, PollFlags::IN),
        ];
        ready(rustix::event::poll(&mut fds, None))?;
        if !fds[1].revents().is_empty() {
            // Expired: read its count so the next wait starts clean.
            let mut count = [0u8; 8];
            let _ = rustix::io::read(&self.timer, &mut count);
        }
        Ok(!fds[0].revents().is_empty())
    }

    /// Sends `frame` out of the interface. A full transmit queue
    /// (`ENOBUFS`, `EAGAIN`) is an error the caller may take as a lost
    /// frame ([`is_queue_full`]).
    pub(crate) fn send(&self, frame: &[u8]) -> io::Result<()> {
        rustix::net::send(&self.fd, frame, SendFlags::empty())
            .map(|_| ())
            .map_err(Into::into)
    }
}

/// Whether a send failed only because the interface's queue was full
/// (`ENOBUFS`, or `EAGAIN` on the non-blocking socket): the frame is lost,
/// the socket still works.
pub(crate) fn is_queue_full(e: &io::Error) -> bool {
    matches!(
        e.raw_os_error(),
        Some(c) if c == rustix::io::Errno::NOBUFS.raw_os_error()
            || c == rustix::io::Errno::AGAIN.raw_os_error()
    )
}

//! The virtual serial link and the host side of the protocol.
//!
//! [`PtyDevice`] serves the in-process device on the master end of a
//! pseudo-terminal pair; the host opens the slave end by its path with the
//! `serialport` crate, exactly as it opens a USB-serial adapter wired to the
//! board (or the pty QEMU gives the firmware's USART1). [`Client`] speaks the
//! protocol over any such port: it sends requests with a `*HH` checksum and
//! checks the checksum of every reply line.

use crate::device::LocalDevice;
use serialport::{SerialPort, TTYPort};
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Baud rate of the device's UART (USART1, 8N1).
pub const BAUD: u32 = 115_200;

/// A reply to one request: `DATA` lines, then the final `OK`/`ERR` line,
/// each without its `*HH` and terminator.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Reply {
    /// `DATA …` lines, in order.
    pub data: Vec<String>,
    /// The final line, `OK …` or `ERR …`.
    pub last: String,
}

impl Reply {
    /// Whether the final line is `OK`.
    pub fn is_ok(&self) -> bool {
        self.last == "OK" || self.last.starts_with("OK ")
    }

    /// The value of `KEY=` in the final line.
    pub fn value(&self, key: &str) -> Option<&str> {
        words_value(&self.last, key)
    }
}

/// The final reply lines (`OK …`, `ERR …`) in a CRLF-separated byte stream:
/// one per request answered.
pub fn final_lines(bytes: &[u8]) -> usize {
    String::from_utf8_lossy(bytes)
        .split("\r\n")
        .filter(|l| l.starts_with("OK") || l.starts_with("ERR "))
        .count()
}

/// The value of `KEY=` among space-separated words.
pub fn words_value<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split(' ').find_map(|w| {
        w.split_once('=')
            .filter(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v)
    })
}

/// What can go wrong on the link.
#[derive(Debug)]
pub enum LinkError {
    /// The port failed.
    Io(io::Error),
    /// No complete reply within the timeout.
    Timeout,
    /// A reply line with a missing or wrong checksum.
    BadChecksum(String),
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "serial link: {e}"),
            LinkError::Timeout => write!(f, "serial link: no reply in time"),
            LinkError::BadChecksum(l) => write!(f, "serial link: bad reply checksum: {l:?}"),
        }
    }
}

impl std::error::Error for LinkError {}

impl From<io::Error> for LinkError {
    fn from(e: io::Error) -> Self {
        LinkError::Io(e)
    }
}

impl From<serialport::Error> for LinkError {
    fn from(e: serialport::Error) -> Self {
        LinkError::Io(e.into())
    }
}

/// Appends `*HH`, the XOR of every byte of `body`.
pub fn with_checksum(body: &str) -> String {
    let xor = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("{body}*{xor:02X}")
}

/// Splits a received reply line into its body, checking `*HH`.
pub fn check_reply_line(line: &str) -> Result<&str, LinkError> {
    let bad = || LinkError::BadChecksum(line.to_owned());
    let (body, sum) = line.rsplit_once('*').ok_or_else(bad)?;
    let xor = body.bytes().fold(0u8, |a, b| a ^ b);
    if sum.len() == 2 && u8::from_str_radix(sum, 16).ok() == Some(xor) {
        Ok(body)
    } else {
        Err(bad())
    }
}

/// Anything that answers protocol requests.
pub trait Transport {
    /// Sends one request line and waits for its whole reply.
    fn request(&mut self, line: &str) -> Result<Reply, LinkError>;
}

/// The in-process device called directly, no link in between.
impl Transport for LocalDevice {
    fn request(&mut self, line: &str) -> Result<Reply, LinkError> {
        let lines = LocalDevice::request(self, &with_checksum(line));
        split_reply(lines.iter().map(String::as_str))
    }
}

fn split_reply<'a>(mut lines: impl Iterator<Item = &'a str>) -> Result<Reply, LinkError> {
    collect_reply(|| lines.next().map(str::to_owned).ok_or(LinkError::Timeout))
}

/// Reads checked reply lines up to and including the final `OK`/`ERR` line.
fn collect_reply(mut next: impl FnMut() -> Result<String, LinkError>) -> Result<Reply, LinkError> {
    let mut data = Vec::new();
    loop {
        let line = next()?;
        if line.starts_with('!') {
            // The answer to a real-time byte, not part of a reply.
            continue;
        }
        let body = check_reply_line(&line)?;
        if body.starts_with("DATA") {
            data.push(body.to_owned());
        } else {
            return Ok(Reply {
                data,
                last: body.to_owned(),
            });
        }
    }
}

/// The host end of a serial link: requests out, replies in.
pub struct Client {
    port: Box<dyn SerialPort>,
    pending: Vec<u8>,
    timeout: Duration,
}

impl Client {
    /// Opens a serial device by path (a real adapter, or a pty) at 115200 8N1.
    pub fn open(path: &str, timeout: Duration) -> Result<Client, LinkError> {
        let port = serialport::new(path, BAUD)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(20))
            .open()?;
        Ok(Client {
            port,
            pending: Vec::new(),
            timeout,
        })
    }

    /// Writes raw bytes (tests of framing and garbage).
    pub fn write_raw(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.port.write_all(bytes)?;
        self.port.flush()?;
        Ok(())
    }

    /// Reads one reply line (without CRLF), waiting up to the timeout.
    pub fn read_line(&mut self) -> Result<String, LinkError> {
        let deadline = Instant::now() + self.timeout;
        loop {
            if let Some(end) = self.pending.iter().position(|&b| b == b'\n') {
                let mut line: Vec<u8> = self.pending.drain(..=end).collect();
                while matches!(line.last(), Some(b'\n' | b'\r')) {
                    line.pop();
                }
                return Ok(String::from_utf8_lossy(&line).into_owned());
            }
            if Instant::now() >= deadline {
                return Err(LinkError::Timeout);
            }
            let mut buf = [0u8; 512];
            match self.port.read(&mut buf) {
                Ok(n) => self.pending.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
    }

    /// Reads reply lines until `n` final lines have come; returns them all
    /// as received, each with its CRLF (to compare with a recorded stream).
    pub fn read_finals(&mut self, n: usize) -> Result<Vec<u8>, LinkError> {
        let mut got = Vec::new();
        while final_lines(&got) < n {
            let line = self.read_line()?;
            got.extend_from_slice(line.as_bytes());
            got.extend_from_slice(b"\r\n");
        }
        Ok(got)
    }

    /// Reads reply lines up to and including a final `OK`/`ERR` line.
    pub fn read_reply(&mut self) -> Result<Reply, LinkError> {
        collect_reply(|| self.read_line())
    }

    /// How long to wait for a reply line.
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// Discards whatever has arrived and not been read.
    pub fn drain(&mut self) {
        self.pending.clear();
        let _ = self.port.clear(serialport::ClearBuffer::Input);
    }
}

impl Transport for Client {
    fn request(&mut self, line: &str) -> Result<Reply, LinkError> {
        let mut bytes = with_checksum(line).into_bytes();
        bytes.extend_from_slice(b"\r\n");
        self.write_raw(&bytes)?;
        self.read_reply()
    }
}

/// Whoever is on the pty's other end, as a program stop waits on them.
struct PtyOperator<'a> {
    master: &'a mut TTYPort,
    stop: &'a AtomicBool,
}

impl crate::device::Operator for PtyOperator<'_> {
    fn write(&mut self, bytes: &[u8]) {
        let _ = self.master.write_all(bytes);
    }

    fn read(&mut self) -> Option<u8> {
        let mut b = [0u8; 1];
        while !self.stop.load(Ordering::Relaxed) {
            match self.master.read(&mut b) {
                Ok(1) => return Some(b[0]),
                Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
                _ => std::thread::sleep(Duration::from_millis(5)),
            }
        }
        None
    }
}

/// The in-process device serving the master end of a pseudo-terminal.
pub struct PtyDevice {
    path: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<LocalDevice>>,
    /// Keeps the slave end open until the host has opened it by path.
    _slave: TTYPort,
}

impl PtyDevice {
    /// Opens a pty pair and starts serving a fresh device on it.
    pub fn start() -> Result<PtyDevice, LinkError> {
        Self::start_with(LocalDevice::new())
    }

    /// Serves the given device on a new pty pair.
    pub fn start_with(mut device: LocalDevice) -> Result<PtyDevice, LinkError> {
        let (mut master, slave) = TTYPort::pair()?;
        let path = slave
            .name()
            .ok_or_else(|| LinkError::Io(io::Error::other("pty without a name")))?;
        master.set_timeout(Duration::from_millis(20))?;
        let stop = Arc::new(AtomicBool::new(false));
        let stop_flag = Arc::clone(&stop);
        let thread = std::thread::Builder::new()
            .name("pty-device".into())
            .spawn(move || {
                let mut buf = [0u8; 512];
                while !stop_flag.load(Ordering::Relaxed) {
                    match master.read(&mut buf) {
                        Ok(0) => std::thread::sleep(Duration::from_millis(1)),
                        Ok(n) => {
                            let mut operator = PtyOperator {
                                master: &mut master,
                                stop: &stop_flag,
                            };
                            let out = device.feed_operated(&buf[..n], &mut operator);
                            if !out.is_empty() && master.write_all(&out).is_err() {
                                std::thread::sleep(Duration::from_millis(1));
                            }
                        }
                        // Quiet for the read's 20 ms: a grbl link's queued
                        // blocks start.
                        Err(e) if e.kind() == io::ErrorKind::TimedOut => {
                            let out = device.quiet();
                            if !out.is_empty() {
                                let _ = master.write_all(&out);
                            }
                        }
                        // No slave open (EIO) or a passing error: wait and retry.
                        Err(_) => std::thread::sleep(Duration::from_millis(5)),
                    }
                }
                device
            })?;
        Ok(PtyDevice {
            path,
            stop,
            thread: Some(thread),
            _slave: slave,
        })
    }

    /// The path of the host end (`/dev/pts/N`).
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Stops serving and returns the device.
    pub fn stop(mut self) -> Option<LocalDevice> {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.take().and_then(|t| t.join().ok())
    }

    /// Serves until the process ends.
    pub fn wait(mut self) {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for PtyDevice {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

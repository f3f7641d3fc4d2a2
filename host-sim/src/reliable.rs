//! Requests that survive a faulty serial link.
//!
//! Every request goes out as `@id <request> ~CCCCCCCC*HH`: a fresh id, a
//! CRC-32 word and the XOR checksum. The device refuses any line whose CRC
//! fails, so it never runs a corrupted request; it answers with the id and a
//! CRC on every line, so the host recognises corrupted, stale and foreign
//! replies and drops them. When no good final line arrives in time the host
//! sends the same request (same id) again: the device runs it if it never
//! arrived, or repeats its remembered reply if it did, so nothing runs
//! twice. A device reset since the session began answers a numbered request
//! with `ERR SESSION` before running anything: the host then restores the
//! session token, configuration and position from its own record
//! (`SESSION`, `CFG`, `ZERO X= Z=`) and sends the request again.
//!
//! [`FaultInjector`] sits between the session and a link and corrupts bytes
//! both ways — flipped bits, dropped and duplicated bytes, bursts of noise —
//! and resets the device now and then.

use crate::device::LocalDevice;
use crate::link::{Client, LinkError, Reply};
use core_nostd::crc32::Crc32;
use core_nostd::protocol::Realtime;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::{HashSet, VecDeque};
use std::time::Duration;

/// A byte stream to a device.
pub trait ByteLink {
    /// Sends bytes.
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError>;
    /// The next received line without its terminator, or `None` when nothing
    /// arrives within `timeout`.
    fn recv_line(&mut self, timeout: Duration) -> Result<Option<Vec<u8>>, LinkError>;
    /// Power-cycles the device; false if this link cannot.
    fn reset_device(&mut self) -> Result<bool, LinkError> {
        Ok(false)
    }
    /// Notes a request line as the host meant it (for the device-side audit).
    fn intend(&mut self, _line: &[u8]) {}
}

/// The in-process device as a byte link, with an audit of what it ran.
#[derive(Default)]
pub struct LocalLink {
    dev: LocalDevice,
    partial: Vec<u8>,
    replies: VecDeque<Vec<u8>>,
    intended: HashSet<Vec<u8>>,
    /// Request lines the device accepted (final reply `OK`) that the host
    /// never sent as such: corrupted requests that ran. Must stay 0.
    pub executed_corrupted: u64,
    /// Request lines the device accepted.
    pub executed: u64,
    /// Times the device was power-cycled.
    pub resets: u64,
}

impl LocalLink {
    /// A link to a device at power-on.
    pub fn new() -> Self {
        Self::default()
    }

    /// The device (state inspection after a session).
    pub fn device(&self) -> &LocalDevice {
        &self.dev
    }

    fn run_line(&mut self, line: &[u8]) {
        let mut bytes = line.to_vec();
        bytes.push(b'\n');
        let out = self.dev.feed(&bytes);
        let text = String::from_utf8_lossy(&out).into_owned();
        let accepted = text.split("\r\n").any(|l| l.starts_with("OK"));
        if accepted {
            self.executed += 1;
            // Real-time bytes never reach the line: the device ran the rest.
            let ran: Vec<u8> = line
                .iter()
                .copied()
                .filter(|&b| Realtime::from_byte(b).is_none())
                .collect();
            // Damage that left only a comment (noise after a `;`) is
            // answered as the empty block it is, and moves nothing: not a
            // request run.
            let start = ran.iter().position(|b| !matches!(b, b' ' | b'\t'));
            let comment = start
                .and_then(|i| ran.get(i))
                .is_some_and(|b| matches!(b, b';' | b'('));
            let still = text.contains("OK NX=0 NZ=0 ") && text.contains(" SEQ=00000000");
            let harmless = comment && still;
            if !(self.intended.contains(content(&ran)) || harmless) {
                self.executed_corrupted += 1;
            }
        }
        for l in text.split_terminator("\r\n") {
            self.replies.push_back(l.as_bytes().to_vec());
        }
    }
}

/// A request up to the end of its CRC word: what the CRC vouches for (a
/// line cut just before its `*HH` still says exactly what the host meant).
fn content(line: &[u8]) -> &[u8] {
    match line.windows(2).rposition(|w| w == b" ~") {
        Some(i) if line.len() >= i + 10 => line.get(..i + 10).unwrap_or(line),
        _ => line,
    }
}

impl ByteLink for LocalLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        // The device's own framing: LF, CR or CRLF end a line.
        for &b in bytes {
            if b == b'\n' || b == b'\r' {
                let line = std::mem::take(&mut self.partial);
                if !(line.is_empty() && b == b'\n') {
                    self.run_line(&line);
                }
            } else {
                self.partial.push(b);
            }
        }
        Ok(())
    }

    fn recv_line(&mut self, _timeout: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        // The device answers at once: nothing queued means nothing will come.
        Ok(self.replies.pop_front())
    }

    fn reset_device(&mut self) -> Result<bool, LinkError> {
        self.dev = LocalDevice::new();
        self.partial.clear();
        self.replies.clear();
        self.resets += 1;
        Ok(true)
    }

    fn intend(&mut self, line: &[u8]) {
        self.intended.insert(content(line).to_vec());
    }
}

impl ByteLink for Client {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.write_raw(bytes)
    }

    fn recv_line(&mut self, timeout: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        self.set_timeout(timeout);
        match self.read_line() {
            Ok(l) => Ok(Some(l.into_bytes())),
            Err(LinkError::Timeout) => Ok(None),
            Err(e) => Err(e),
        }
    }
}

/// Fault rates: per byte for flips, drops and duplicates, per line for noise
/// bursts, per request for device resets.
#[derive(Clone, Copy, Debug)]
pub struct Faults {
    /// A bit of a byte flipped.
    pub flip: f64,
    /// A byte lost.
    pub drop: f64,
    /// A byte received twice.
    pub dup: f64,
    /// A burst of 1–16 random bytes inserted into a line.
    pub noise: f64,
    /// The device power-cycled around a request.
    pub reset: f64,
}

impl Faults {
    /// A harsh link: about one request or reply line in twelve damaged.
    pub const HARSH: Faults = Faults {
        flip: 0.001,
        drop: 0.0005,
        dup: 0.0005,
        noise: 0.02,
        reset: 0.0005,
    };
}

/// What the injector did.
#[derive(Clone, Copy, Debug, Default)]
pub struct FaultStats {
    /// Request lines that left damaged.
    pub requests_damaged: u64,
    /// Reply lines that arrived damaged.
    pub replies_damaged: u64,
    /// Bits flipped.
    pub flips: u64,
    /// Bytes dropped.
    pub drops: u64,
    /// Bytes duplicated.
    pub dups: u64,
    /// Noise bursts.
    pub bursts: u64,
    /// Device resets.
    pub resets: u64,
}

/// Corrupts the bytes between a session and its link.
pub struct FaultInjector<L> {
    inner: L,
    rng: ChaCha8Rng,
    faults: Faults,
    incoming: VecDeque<Vec<u8>>,
    /// Counts of what was done.
    pub stats: FaultStats,
}

impl<L: ByteLink> FaultInjector<L> {
    /// Wraps a link with seeded faults.
    pub fn new(inner: L, faults: Faults, seed: u64) -> Self {
        FaultInjector {
            inner,
            rng: ChaCha8Rng::seed_from_u64(seed),
            faults,
            incoming: VecDeque::new(),
            stats: FaultStats::default(),
        }
    }

    /// The wrapped link.
    pub fn inner(&self) -> &L {
        &self.inner
    }

    /// The wrapped link, mutably.
    pub fn inner_mut(&mut self) -> &mut L {
        &mut self.inner
    }

    /// Damages `bytes`; true if anything changed.
    fn damage(&mut self, bytes: &[u8]) -> (Vec<u8>, bool) {
        let f = self.faults;
        let mut out = Vec::with_capacity(bytes.len() + 16);
        let mut changed = false;
        for &b in bytes {
            if self.rng.random_bool(f.drop) {
                self.stats.drops += 1;
                changed = true;
                continue;
            }
            let mut b = b;
            if self.rng.random_bool(f.flip) {
                b ^= 1 << self.rng.random_range(0..8);
                self.stats.flips += 1;
                changed = true;
            }
            out.push(b);
            if self.rng.random_bool(f.dup) {
                out.push(b);
                self.stats.dups += 1;
                changed = true;
            }
        }
        if self.rng.random_bool(f.noise) {
            let at = self.rng.random_range(0..=out.len());
            let n = self.rng.random_range(1..=16);
            let burst: Vec<u8> = (0..n).map(|_| self.rng.random()).collect();
            out.splice(at..at, burst);
            self.stats.bursts += 1;
            changed = true;
        }
        (out, changed)
    }
}

impl<L: ByteLink> ByteLink for FaultInjector<L> {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let line = bytes.strip_suffix(b"\r\n").unwrap_or(bytes);
        self.inner.intend(line);
        let reset_after = self.rng.random_bool(self.faults.reset);
        let reset_before = self.rng.random_bool(self.faults.reset);
        if reset_before && self.inner.reset_device()? {
            self.stats.resets += 1;
        }
        let (out, changed) = self.damage(bytes);
        self.stats.requests_damaged += u64::from(changed);
        self.inner.send(&out)?;
        if reset_after && self.inner.reset_device()? {
            self.stats.resets += 1;
            self.incoming.clear();
        }
        Ok(())
    }

    fn recv_line(&mut self, timeout: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        if let Some(l) = self.incoming.pop_front() {
            return Ok(Some(l));
        }
        let Some(mut line) = self.inner.recv_line(timeout)? else {
            return Ok(None);
        };
        line.extend_from_slice(b"\r\n");
        let (out, changed) = self.damage(&line);
        self.stats.replies_damaged += u64::from(changed);
        // Damage may split or join lines: re-frame.
        for l in out.split(|&b| b == b'\n' || b == b'\r') {
            if !l.is_empty() {
                self.incoming.push_back(l.to_vec());
            }
        }
        Ok(self.incoming.pop_front())
    }

    fn reset_device(&mut self) -> Result<bool, LinkError> {
        self.inner.reset_device()
    }
}

/// What the session had to do.
#[derive(Clone, Copy, Debug, Default)]
pub struct SessionStats {
    /// Requests answered.
    pub requests: u64,
    /// Requests sent again.
    pub retries: u64,
    /// Reply lines dropped for a bad XOR, CRC or form.
    pub corrupt_replies: u64,
    /// Good reply lines for another request (late answers), dropped.
    pub stale_replies: u64,
    /// Device resets found by the session token.
    pub resets_detected: u64,
}

/// The host's record of the device: what to restore after a reset.
#[derive(Clone, Debug)]
pub struct Shadow {
    /// X impulse price word.
    pub hx: String,
    /// Z impulse price word.
    pub hz: String,
    /// Diameter mode.
    pub diam: bool,
    /// The commanded X as a diameter word, exact.
    pub x_diameter: String,
    /// Commanded Z, exact.
    pub z: String,
}

impl Default for Shadow {
    fn default() -> Self {
        Shadow {
            hx: "0.005".into(),
            hz: "0.01".into(),
            diam: true,
            x_diameter: "0".into(),
            z: "0".into(),
        }
    }
}

/// Frames `@id request ~CCCCCCCC*HH\r\n`.
pub fn frame(id: u32, request: &str) -> Vec<u8> {
    let body = format!("@{id} {request} ");
    let mut crc = Crc32::new();
    crc.update(body.as_bytes());
    let body = format!("{body}~{:08X}", crc.finish());
    let xor = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("{body}*{xor:02X}\r\n").into_bytes()
}

/// Checks a reply line's `*HH`, ` ~CCCCCCCC` and ` @id`; returns the id and
/// the line without them.
pub fn unframe(line: &[u8]) -> Option<(u32, String)> {
    let text = std::str::from_utf8(line).ok()?;
    let (body, sum) = text.rsplit_once('*')?;
    let xor = body.bytes().fold(0u8, |a, b| a ^ b);
    if sum.len() != 2 || u8::from_str_radix(sum, 16).ok()? != xor {
        return None;
    }
    let (before, crc) = body.rsplit_once('~')?;
    let mut c = Crc32::new();
    c.update(before.as_bytes());
    if crc.len() != 8 || u32::from_str_radix(crc, 16).ok()? != c.finish() {
        return None;
    }
    let (content, id) = before.strip_suffix(' ')?.rsplit_once(" @")?;
    Some((id.parse().ok()?, content.to_owned()))
}

/// A request/reply session that survives a faulty link.
pub struct ReliableSession<L> {
    link: L,
    next_id: u32,
    token: u32,
    timeout: Duration,
    /// What to restore after a device reset.
    pub shadow: Shadow,
    /// Counts of what the session did.
    pub stats: SessionStats,
}

/// Attempts before a request is given up.
const ATTEMPTS: u32 = 200;

impl<L: ByteLink> ReliableSession<L> {
    /// Starts a session: sets a session token on the device.
    pub fn new(link: L, timeout: Duration, token: u32) -> Result<Self, LinkError> {
        let mut s = ReliableSession {
            link,
            next_id: 1,
            token,
            timeout,
            shadow: Shadow::default(),
            stats: SessionStats::default(),
        };
        let id = s.fresh_id();
        let r = s.exchange(id, &format!("SESSION TOKEN={token}"))?;
        if !r.is_ok() {
            return Err(LinkError::Io(std::io::Error::other(r.last)));
        }
        Ok(s)
    }

    /// The link.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// Ends the session, handing back the link.
    pub fn into_link(self) -> L {
        self.link
    }

    fn fresh_id(&mut self) -> u32 {
        let id = self.next_id;
        self.next_id = self.next_id.checked_add(1).unwrap_or(1);
        id
    }

    /// Sends `request` until its reply arrives intact. A lost or damaged
    /// reply makes the host send the same request (same id) again: the device
    /// runs it if it never arrived, or repeats its reply if it did. `ERR
    /// SESSION` means the device was reset: the host restores it, then sends
    /// the request again.
    pub fn request(&mut self, request: &str) -> Result<Reply, LinkError> {
        let id = self.fresh_id();
        let reply = self.exchange(id, request)?;
        self.stats.requests += 1;
        Ok(reply)
    }

    fn exchange(&mut self, id: u32, request: &str) -> Result<Reply, LinkError> {
        let line = frame(id, request);
        for attempt in 0..ATTEMPTS {
            if attempt > 0 {
                self.stats.retries += 1;
                // This host never holds: a cycle start releases a hold
                // that noise on the line may have given (a 0x82 byte).
                self.link.send(&[0x81])?;
            }
            self.link.send(&line)?;
            match self.await_reply(id)? {
                Some(r) if r.last.starts_with("ERR SESSION") => self.restore()?,
                Some(r) => return Ok(r),
                None => {}
            }
        }
        Err(LinkError::Timeout)
    }

    fn await_reply(&mut self, id: u32) -> Result<Option<Reply>, LinkError> {
        let mut data = Vec::new();
        let mut wait = self.timeout;
        while let Some(line) = self.link.recv_line(wait)? {
            if line.first() == Some(&b'!') {
                // The answer to a real-time byte (noise can make one).
                continue;
            }
            match unframe(&line) {
                // The device has answered, damaged: what else comes, comes soon.
                None => {
                    self.stats.corrupt_replies += 1;
                    wait = self.timeout.min(Duration::from_millis(30));
                }
                Some((got, _)) if got != id => self.stats.stale_replies += 1,
                Some((_, text)) if text.starts_with("DATA") => data.push(text),
                Some((_, text)) => return Ok(Some(Reply { data, last: text })),
            }
        }
        Ok(None)
    }

    /// Sets the session token and restores configuration and position from
    /// the host's record.
    fn restore(&mut self) -> Result<(), LinkError> {
        self.stats.resets_detected += 1;
        'again: for _ in 0..ATTEMPTS {
            let shadow = self.shadow.clone();
            let steps = [
                format!("SESSION TOKEN={}", self.token),
                format!("CFG HX={} HZ={} DIAM=1", shadow.hx, shadow.hz),
                format!("ZERO X={} Z={}", shadow.x_diameter, shadow.z),
                format!("CFG DIAM={}", u8::from(shadow.diam)),
            ];
            for s in &steps {
                let id = self.fresh_id();
                let line = frame(id, s);
                let mut done = false;
                for _ in 0..ATTEMPTS {
                    self.link.send(&line)?;
                    match self.await_reply(id)? {
                        // Reset again while restoring: start over.
                        Some(r) if r.last.starts_with("ERR SESSION") => continue 'again,
                        Some(r) if r.is_ok() => {
                            done = true;
                            break;
                        }
                        Some(r) => {
                            return Err(LinkError::Io(std::io::Error::other(format!(
                                "restoring the device: {s}: {}",
                                r.last
                            ))))
                        }
                        None => {}
                    }
                }
                if !done {
                    return Err(LinkError::Timeout);
                }
            }
            return Ok(());
        }
        Err(LinkError::Timeout)
    }
}

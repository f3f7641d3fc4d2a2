//! Reply lines: `OK …`, `ERR <CODE> <text>` and `DATA …`, each closed by
//! `*HH` (XOR of every byte before the `*`) and CRLF.

use core::fmt;

/// Room for one reply line, checksum and terminator included. Every reply
/// the handler composes fits; a longer one would be cut, never overrun.
pub const REPLY_CAPACITY: usize = 200;

/// One reply line under construction.
#[derive(Clone)]
pub struct ReplyLine {
    buf: [u8; REPLY_CAPACITY],
    len: usize,
}

impl Default for ReplyLine {
    fn default() -> Self {
        Self::new()
    }
}

impl ReplyLine {
    /// An empty line.
    pub const fn new() -> Self {
        ReplyLine {
            buf: [0; REPLY_CAPACITY],
            len: 0,
        }
    }

    /// Appends bytes, cutting what does not fit before the checksum's room.
    pub fn push_bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.len + 5 >= REPLY_CAPACITY {
                return;
            }
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = b;
                self.len += 1;
            }
        }
    }

    /// The bytes written so far.
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    /// Appends `*HH\r\n` and returns the finished line.
    ///
    /// ```
    /// use core_nostd::protocol::reply::ReplyLine;
    /// use core::fmt::Write;
    /// let mut r = ReplyLine::new();
    /// write!(r, "OK").unwrap();
    /// assert_eq!(r.finish(), b"OK*04\r\n");
    /// ```
    pub fn finish(&mut self) -> &[u8] {
        let sum = checksum(self.buf.get(..self.len).unwrap_or(&[]));
        let hex = hex_digits(sum);
        let tail = [b'*', hex[0], hex[1], b'\r', b'\n'];
        for b in tail {
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = b;
                self.len += 1;
            }
        }
        self.buf.get(..self.len).unwrap_or(&[])
    }
}

impl fmt::Write for ReplyLine {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        self.push_bytes(s.as_bytes());
        Ok(())
    }
}

/// The protocol checksum: XOR of all bytes.
pub fn checksum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |acc, &b| acc ^ b)
}

/// Two upper-case hex digits.
pub const fn hex_digits(v: u8) -> [u8; 2] {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    [HEX[(v >> 4) as usize], HEX[(v & 0xF) as usize]]
}

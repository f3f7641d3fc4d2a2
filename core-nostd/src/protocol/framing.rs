//! Request framing: bytes in, complete lines out.
//!
//! A line ends with LF, CR or CRLF (a CR followed by LF is one terminator).
//! At most [`MAX_LINE`] bytes are kept; the byte that would exceed it makes the
//! assembler report [`Framed::TooLong`] once, and everything up to the next
//! terminator is discarded.

use heapless::Vec;

/// The longest request line, terminator excluded.
pub const MAX_LINE: usize = 120;

/// What one received byte completed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Framed {
    /// A terminator ended a line; read it with [`LineAssembler::line`].
    Line,
    /// The line grew beyond [`MAX_LINE`]; its rest will be discarded.
    TooLong,
}

/// Collects bytes into request lines, in bounded memory.
#[derive(Clone, Debug, Default)]
pub struct LineAssembler {
    buf: Vec<u8, MAX_LINE>,
    /// Discarding the rest of an over-long line.
    overflow: bool,
    /// The previous byte was CR (an LF right after it is part of the same terminator).
    after_cr: bool,
    /// The buffer holds a finished line not yet consumed.
    complete: bool,
}

impl LineAssembler {
    /// An empty assembler.
    pub const fn new() -> Self {
        LineAssembler {
            buf: Vec::new(),
            overflow: false,
            after_cr: false,
            complete: false,
        }
    }

    /// Takes one byte. Returns what it completed, if anything.
    ///
    /// ```
    /// use core_nostd::protocol::framing::{Framed, LineAssembler};
    /// let mut a = LineAssembler::new();
    /// let mut lines = Vec::new();
    /// for &b in b"VER\r\nPOS\n\r" {
    ///     if a.push(b) == Some(Framed::Line) {
    ///         lines.push(a.line().to_vec());
    ///     }
    /// }
    /// assert_eq!(lines, [b"VER".to_vec(), b"POS".to_vec(), b"".to_vec()]);
    /// ```
    pub fn push(&mut self, byte: u8) -> Option<Framed> {
        self.push_with(byte, true)
    }

    /// As [`LineAssembler::push`], with `pairs` false every CR and every LF
    /// ending a line of its own, as grbl 1.1 reads its input (a CRLF is
    /// a line and an empty line, each answered).
    ///
    /// ```
    /// use core_nostd::protocol::framing::{Framed, LineAssembler};
    /// let mut a = LineAssembler::new();
    /// let ends = b"G0\r\n".iter().filter(|&&b| a.push_with(b, false) == Some(Framed::Line));
    /// assert_eq!(ends.count(), 2);
    /// ```
    pub fn push_with(&mut self, byte: u8, pairs: bool) -> Option<Framed> {
        if self.complete {
            self.buf.clear();
            self.complete = false;
        }
        let after_cr = core::mem::replace(&mut self.after_cr, byte == b'\r') && pairs;
        match byte {
            b'\n' if after_cr => None,
            b'\r' | b'\n' => {
                if core::mem::replace(&mut self.overflow, false) {
                    self.buf.clear();
                    None
                } else {
                    self.complete = true;
                    Some(Framed::Line)
                }
            }
            _ if self.overflow => None,
            _ => match self.buf.push(byte) {
                Ok(()) => None,
                Err(_) => {
                    self.overflow = true;
                    self.buf.clear();
                    Some(Framed::TooLong)
                }
            },
        }
    }

    /// Drops the line being received (a reset): the next byte begins a
    /// new one.
    pub fn clear(&mut self) {
        *self = LineAssembler::new();
    }

    /// The line that the last [`Framed::Line`] completed (terminator excluded).
    pub fn line(&self) -> &[u8] {
        if self.complete {
            &self.buf
        } else {
            &[]
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec as StdVec;

    fn run(input: &[u8]) -> StdVec<Result<StdVec<u8>, ()>> {
        let mut a = LineAssembler::new();
        let mut out = StdVec::new();
        for &b in input {
            match a.push(b) {
                Some(Framed::Line) => out.push(Ok(a.line().to_vec())),
                Some(Framed::TooLong) => out.push(Err(())),
                None => {}
            }
        }
        out
    }

    #[test]
    fn terminators() {
        assert_eq!(
            run(b"A\rB\nC\r\nD"),
            [Ok(b"A".to_vec()), Ok(b"B".to_vec()), Ok(b"C".to_vec())]
        );
        assert_eq!(run(b"\r\n\r\n"), [Ok(StdVec::new()), Ok(StdVec::new())]);
        assert_eq!(run(b"\n\r"), [Ok(StdVec::new()), Ok(StdVec::new())]);
        assert_eq!(run(b"\r\r\n"), [Ok(StdVec::new()), Ok(StdVec::new())]);
    }

    #[test]
    fn long_lines_are_reported_once_and_discarded() {
        let mut input = StdVec::from([b'A'; MAX_LINE]);
        input.push(b'\n');
        assert_eq!(run(&input), [Ok(StdVec::from([b'A'; MAX_LINE]))]);

        let mut input = StdVec::from([b'B'; 500]);
        input.extend_from_slice(b"\r\nPOS\n");
        assert_eq!(run(&input), [Err(()), Ok(b"POS".to_vec())]);

        // Over-long line ended by CRLF: the LF does not produce an empty line.
        let mut input = StdVec::from([b'C'; MAX_LINE + 1]);
        input.extend_from_slice(b"\r\n\n");
        assert_eq!(run(&input), [Err(()), Ok(StdVec::new())]);
    }
}

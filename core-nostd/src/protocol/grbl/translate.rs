//! The one [`Io`] the session answers through: on a pendant link every
//! call passes through; on a grbl link replies turn into grbl's.

use super::report::*;
use crate::protocol::io::{Io, Refused, StatusRecord, StatusView, Timing};
use crate::protocol::reply::ReplyLine;
use core::fmt::Write;

/// A refusal's way to the other dialect, as the pendant protocol ends it
/// and as a grbl sender sets it (`$450`).
const DIALECT_HINTS: [(&[u8], &[u8]); 3] = [
    (b"(OPT DIALECT=FANUC)", b"($450=1)"),
    (b"(OPT DIALECT=ISO)", b"($450=0)"),
    // And the way to wire the probe.
    (
        b"INPUT USED= with PROBE",
        b"$6=0 (or $6=1, inverted) wires it",
    ),
];

/// The one [`Io`] the session answers through (so that its code exists
/// once on the board): on a pendant link every call passes through; on a
/// grbl link motion passes through and reply lines turn into grbl's.
pub struct Translate<'a, I: Io + ?Sized> {
    pub(super) inner: &'a mut I,
    pub(super) grbl: bool,
    pub(super) extras: Extras,
    /// Status lines pass (a `?`), or are dropped (the answer to `!`, `~`).
    pub statuses: bool,
    /// The final line of the request: `None` before it came.
    pub outcome: Option<Result<(), u8>>,
    /// A refusal's text, for its `[MSG:…]` line (a query's final line).
    pub message: ReplyLine,
    /// The next line is a refusal's, whose text grbl's `[MSG:…]` shows.
    pub(super) refusal_text: bool,
    /// What the status line about to be sent says.
    pub(super) status: Option<StatusRecord>,
    /// A reset came, with a block running (`OF` > 0).
    pub reset: Option<bool>,
    /// Check mode (`$C`): replies go out; nothing moves, waits or
    /// switches (a flag, not a second transport type, so that the
    /// session's code exists once on the board).
    pub dry: bool,
}

impl<'a, I: Io + ?Sized> Translate<'a, I> {
    /// Every call through to `inner` unchanged: the pendant protocol.
    pub fn pendant(inner: &'a mut I) -> Self {
        Self::grbl(inner, Extras::NONE).plain()
    }

    fn plain(mut self) -> Self {
        self.grbl = false;
        self
    }

    /// Around `inner`, speaking grbl.
    pub fn grbl(inner: &'a mut I, extras: Extras) -> Self {
        Translate {
            inner,
            grbl: true,
            extras,
            statuses: true,
            outcome: None,
            message: ReplyLine::new(),
            refusal_text: false,
            status: None,
            reset: None,
            dry: false,
        }
    }

    /// Sends a plain grbl line.
    pub fn line(&mut self, text: &[u8]) {
        let mut l = ReplyLine::new();
        l.push_bytes(text);
        self.inner.send(finish(&mut l));
    }

    /// Sends `ok`, or `[MSG:…]` and `error:N`, for the request's outcome.
    pub fn answer(&mut self) {
        match self.outcome {
            Some(Err(code)) => {
                let mut m = ReplyLine::new();
                m.push_bytes(b"[MSG:");
                m.push_bytes(self.message.as_bytes());
                m.push_bytes(b"]");
                self.inner.send(finish(&mut m));
                let mut e = ReplyLine::new();
                let _ = write!(e, "error:{code}");
                self.inner.send(finish(&mut e));
            }
            _ => self.inner.send(b"ok\r\n"),
        }
    }
}

impl<I: Io + ?Sized> Io for Translate<'_, I> {
    fn send(&mut self, line: &[u8]) {
        if !self.grbl {
            return self.inner.send(line);
        }
        // Without the `*HH` and CRLF.
        let body = line
            .iter()
            .rposition(|&b| b == b'*')
            .and_then(|i| line.get(..i))
            .unwrap_or(line);
        // What a line is was told first (`accepted`, `refused`, `status`,
        // `message`); only a refusal's text is taken from its line, for
        // grbl's `[MSG:…]`: the words after `ERR`.
        if self.refusal_text {
            self.refusal_text = false;
            let text = body.iter().position(|&b| b == b' ');
            let text = text.and_then(|i| body.get(i + 1..)).unwrap_or(b"");
            self.message = ReplyLine::new();
            // The way to the other dialect, in a grbl sender's words.
            let to_grbl = DIALECT_HINTS
                .iter()
                .find_map(|&(pendant, grbl)| Some((text.strip_suffix(pendant)?, grbl)));
            match to_grbl {
                Some((head, grbl)) => {
                    self.message.push_bytes(head);
                    self.message.push_bytes(grbl);
                }
                None => self.message.push_bytes(text),
            }
        }
        // `DATA` lines and the rest: not grbl's.
    }
    fn accepted(&mut self) {
        if self.grbl {
            self.outcome = Some(Ok(()));
        } else {
            self.inner.accepted();
        }
    }
    fn refused(&mut self, why: Refused) {
        if self.grbl {
            self.outcome = Some(Err(error_number(why)));
            self.refusal_text = true;
        } else {
            self.inner.refused(why);
        }
    }
    fn message(&mut self, text: &[u8]) {
        if !self.grbl {
            return self.inner.message(text);
        }
        // What the operator must do at a stop: grbl's feedback message.
        let mut l = ReplyLine::new();
        l.push_bytes(b"[MSG:");
        l.push_bytes(text);
        l.push_bytes(b"]");
        self.inner.send(finish(&mut l));
    }
    fn alarm(&mut self, code: u8) {
        if !self.grbl {
            return self.inner.alarm(code);
        }
        let mut l = ReplyLine::new();
        let _ = write!(l, "ALARM:{code}");
        self.inner.send(finish(&mut l));
    }
    fn probed(&mut self, at: [crate::length::Length; 2], diameter: bool, changed: bool) {
        if !self.grbl {
            return self.inner.probed(at, diameter, changed);
        }
        let p = crate::inputs::ProbeResult { at, changed };
        let l = probe_line(Some(p), diameter);
        self.inner.send(l.as_bytes());
    }
    fn reset_done(&mut self, running: bool) {
        if self.grbl {
            self.reset = Some(running);
        } else {
            self.inner.reset_done(running);
        }
    }
    fn status(&mut self, record: &StatusRecord, realtime: bool) {
        if !self.grbl {
            return self.inner.status(record, realtime);
        }
        if !realtime {
            // For the line a program stop gives `stop_status`.
            self.status = Some(*record);
        } else if self.statuses {
            let mut l = status_report(record, &self.extras);
            self.inner.send(finish(&mut l));
        }
    }
    fn stop_status(&mut self, line: &[u8]) {
        if !self.grbl {
            return self.inner.stop_status(line);
        }
        if let Some(record) = self.status.take() {
            let mut l = status_report(&record, &self.extras);
            self.inner.stop_status(finish(&mut l));
        }
    }
    fn timing(&mut self) -> Option<Timing> {
        self.inner.timing()
    }
    fn stop_holds(&mut self) -> bool {
        !self.dry && self.grbl && self.inner.background().is_some()
    }
    fn view(&mut self, view: &StatusView) {
        self.inner.view(view);
    }
    fn pause(&mut self) {
        self.inner.pause();
    }
    crate::protocol::io::forward_motion!(unless dry);
}

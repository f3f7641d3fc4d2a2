//! [`Device`]: a link's endpoint. It frames received bytes into lines,
//! runs them on its [`Session`] (or its grbl front), and answers real-time
//! bytes at once.

use super::framing::{self, Framed, LineAssembler};
use super::grbl;
use super::io::{ErrorCode, Io, Realtime};
use super::session::{self, Session};

/// One protocol endpoint: framing plus a session.
#[derive(Clone, Debug, Default)]
pub struct Device {
    rx: LineAssembler,
    session: Session,
    grbl: grbl::Front,
    /// The request `GRBL` switched the link at the byte before: an LF now
    /// ends that request's CRLF, not a grbl line.
    switched: bool,
}

impl Device {
    /// A device at power-on: default configuration, at program zero.
    pub const fn new() -> Self {
        Device {
            rx: LineAssembler::new(),
            session: Session::new(),
            grbl: grbl::Front::new(),
            switched: false,
        }
    }

    /// A device whose planner looks `window` blocks ahead (1 … 64; the
    /// device's own is 64). With a window of one every block starts, and
    /// issues its events, within the request that queues it.
    pub const fn with_window(window: usize) -> Self {
        Device {
            rx: LineAssembler::new(),
            session: Session::with_window(window),
            grbl: grbl::Front::new(),
            switched: false,
        }
    }

    /// Takes one received byte; answers through `io` when it completes a
    /// line, or at once for a real-time byte (which leaves the line being
    /// received as it was).
    pub fn receive<I: Io>(&mut self, byte: u8, io: &mut I) {
        if self.grbl.on {
            if let Some(rt) = grbl::GrblRealtime::from_byte(byte) {
                return self.realtime_grbl(rt, io);
            }
            // As grbl: every other byte above 0x7F (the UTF-8 prefix a
            // sender puts before an override byte, noise) and every control
            // byte but the line's ends and tab is dropped, never part of a
            // line.
            if grbl::dropped(byte) {
                return;
            }
        } else if let Some(rt) = Realtime::from_byte(byte) {
            return self.realtime(rt, io);
        }
        let pairs = !self.grbl.on || core::mem::take(&mut self.switched);
        match self.rx.push_with(byte, pairs) {
            Some(Framed::Line) => self.line(io),
            Some(Framed::TooLong) => {
                let mut t = self.link(io);
                session::send_error(
                    &mut t,
                    ErrorCode::LineTooLong,
                    format_args!("longer than {} bytes", framing::MAX_LINE),
                );
                if self.grbl.on {
                    t.answer();
                }
            }
            None => {}
        }
    }

    /// The session's one way out to `io`, as the link speaks.
    fn link<'a, I: Io>(&self, io: &'a mut I) -> grbl::Translate<'a, I> {
        if self.grbl.on {
            grbl::Translate::grbl(io, grbl::Extras::of(&self.session, &self.grbl))
        } else {
            grbl::Translate::pendant(io)
        }
    }

    /// A complete line: the pendant's request, or grbl's line. The pendant
    /// request `GRBL` switches the link to grbl (`OK GRBL=1`, then the
    /// banner); grbl's `$PENDANT` switches back. Nothing else does: noise
    /// on a pendant link never makes it speak grbl.
    fn line<I: Io>(&mut self, io: &mut I) {
        let line = self.rx.line();
        if self.grbl.on {
            grbl::line(&mut self.grbl, &mut self.session, line, io);
        } else if line.eq_ignore_ascii_case(b"GRBL") {
            let mut t = grbl::Translate::pendant(io);
            session::send_ok(&mut t, Some(format_args!("GRBL=1")));
            t.send(grbl::BANNER);
            self.grbl.on = true;
            self.switched = true;
        } else {
            self.session
                .handle_line(line, &mut grbl::Translate::pendant(io));
        }
    }

    /// Whether the link speaks grbl.
    pub const fn grbl(&self) -> bool {
        self.grbl.on
    }

    /// Switches the link to grbl (the banner first) or to the pendant
    /// protocol.
    pub fn set_grbl<I: Io>(&mut self, on: bool, io: &mut I) {
        if on && !self.grbl.on {
            io.send(grbl::BANNER);
        }
        self.grbl.on = on;
    }

    /// What a grbl status report adds to the session's status line (for a
    /// transport that answers `?` itself while it waits).
    pub fn grbl_extras(&self) -> Option<grbl::Extras> {
        self.grbl
            .on
            .then(|| grbl::Extras::of(&self.session, &self.grbl))
    }

    /// A grbl real-time character, picked out by a transport or by
    /// [`Device::receive`].
    pub fn realtime_grbl<I: Io>(&mut self, rt: grbl::GrblRealtime, io: &mut I) {
        if rt == grbl::GrblRealtime::Common(Realtime::Reset) {
            self.rx.clear();
        }
        grbl::realtime(&mut self.grbl, &mut self.session, rt, io);
    }

    /// A board's stepper needs the next block: starts it if one is queued
    /// (called between received bytes). A cancelled jog is dropped here
    /// once held at rest.
    pub fn poll<I: Io>(&mut self, io: &mut I) {
        let mut t = grbl::Translate::pendant(io);
        if self.grbl.cancel && self.session.held_or_idle(&mut t) {
            self.grbl.cancel = false;
            self.grbl.jogging = false;
            self.session.cancel_motion(&mut t);
        }
        self.session.poll(&mut t);
    }

    /// Whether a grbl link has blocks waiting to start (in a run under way
    /// too): when the link has been quiet a while, [`Device::quiet`]
    /// starts them, the run ending at rest after them.
    pub fn waiting(&self) -> bool {
        self.grbl.on && self.session.waiting()
    }

    /// The link has been quiet (about 50 ms without a byte): on a grbl
    /// link the queued blocks start now, as grbl plans with what it has —
    /// a line typed alone, a jog, the end of a stream. The pendant protocol
    /// waits for its window or a flush (`SYNC`), as before.
    pub fn quiet<I: Io>(&mut self, io: &mut I) {
        if self.waiting() {
            self.session.release(&mut grbl::Translate::pendant(io));
        }
    }

    /// A jog cancel waits for the axes to come to rest ([`Device::poll`]
    /// finishes it).
    pub const fn cancel_pending(&self) -> bool {
        self.grbl.cancel
    }

    /// Whether [`Device::poll`] could start a block.
    pub fn can_feed(&self) -> bool {
        self.session.can_feed()
    }

    /// Acts on a real-time command and answers it (a transport that picks
    /// real-time bytes out as they arrive hands them over here); on a grbl
    /// link, as grbl answers it.
    pub fn realtime<I: Io>(&mut self, rt: Realtime, io: &mut I) {
        if rt == Realtime::Reset {
            // A reset drops the line being received with everything else.
            self.rx.clear();
        }
        if self.grbl.on {
            return self.realtime_grbl(grbl::GrblRealtime::Common(rt), io);
        }
        self.session.realtime(rt, &mut grbl::Translate::pendant(io));
    }

    /// The board's inputs changed (`active`: those active now, filtered;
    /// see [`Session::inputs`]). On a grbl link an input's stop is
    /// `ALARM:n`, and a hold or resume from a button answers nothing.
    pub fn inputs<I: Io>(&mut self, active: u16, io: &mut I) {
        let mut t = self.link(io);
        t.statuses = false;
        self.session.inputs(active, &mut t);
        if self.session.alarm().is_some() {
            // A jog in progress was dropped with everything else.
            self.grbl.jogging = false;
            self.grbl.cancel = false;
        }
    }

    /// The handwheel turned by `counts` since the last call
    /// ([`Session::wheel`]).
    pub fn wheel<I: Io>(&mut self, counts: i32, io: &mut I) {
        let mut t = self.link(io);
        t.statuses = false;
        self.session.wheel(counts, &mut t);
    }

    /// The pendant's own selectors set the handwheel's axis (0 X, 1 Z) and
    /// scale (1, 10, 100), as `WHEEL AXIS= SCALE=` would
    /// ([`Session::wheel_select`]); false, and nothing changed, for
    /// another value.
    pub fn wheel_select(&mut self, axis: u8, scale: u8) -> bool {
        self.session.wheel_select(axis, scale)
    }

    /// The inputs wired, for the board's filter.
    pub const fn wiring(&self) -> crate::inputs::InputConfig {
        self.session.wiring()
    }

    /// Takes received bytes in order.
    ///
    /// ```
    /// use core_nostd::protocol::{Device, Io};
    /// struct Lines(Vec<String>);
    /// impl Io for Lines {
    ///     fn send(&mut self, line: &[u8]) { self.0.push(String::from_utf8_lossy(line).into()) }
    /// }
    /// let mut dev = Device::new();
    /// let mut out = Lines(Vec::new());
    /// dev.receive_bytes(b"MOVE X=10 Z=-5\r\n", &mut out);
    /// assert_eq!(out.0, ["OK NX=1000 NZ=-500 PX=1000 PZ=-500 SEQ=34F89895*2A\r\n"]);
    /// ```
    pub fn receive_bytes<I: Io>(&mut self, bytes: &[u8], io: &mut I) {
        for &b in bytes {
            self.receive(b, io);
        }
    }

    /// The session's state.
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// The table, work offsets and stored positions kept from before the
    /// power cut, put back at power-on.
    pub fn restore_offsets(&mut self, offsets: crate::interp::Offsets) {
        self.session.restore_offsets(offsets);
    }

    /// Probing blocks run as feed moves to their end
    /// ([`Session::set_probe_as_feed`]): a host's run of a program.
    pub fn set_probe_as_feed(&mut self, on: bool) {
        self.session.set_probe_as_feed(on);
    }
}

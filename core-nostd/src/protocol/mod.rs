//! The pendant line protocol (`docs/protocol.md`): transport-agnostic, bytes in,
//! reply lines out, bounded buffers.
//!
//! [`Device`] is what a transport owns: it frames received bytes into lines
//! ([`framing`]), checks them and runs them on its [`Session`], and hands every
//! reply line and every accepted motion block to an [`Io`].

#[cfg(feature = "calc")]
mod calc;
pub mod framing;
pub mod grbl;
pub mod reply;
mod session;
mod words;

pub use session::{status_line, Config, Pass, Session, NAME, VERSION};

use crate::interleave::{LinearBlock, StepEvent};
use crate::machine::Background;
use crate::outputs::Outputs;
use crate::stepdir::DriveTiming;
use core::fmt;
use framing::{Framed, LineAssembler};
use reply::ReplyLine;

/// The error codes of the protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ErrorCode {
    /// A request's `*HH` does not match, or is malformed.
    Checksum,
    /// A request longer than 120 bytes.
    LineTooLong,
    /// An empty request.
    Empty,
    /// An unknown command.
    Unknown,
    /// A request that is not of the command's form.
    Syntax,
    /// A malformed or out-of-range value; the text names the key.
    Value,
    /// A result or a position beyond what the machine can hold.
    Range,
    /// Impossible geometry.
    Geometry,
    /// A numbered request (`@id`) while no session token is set: the device
    /// was reset since the host set it (an extension).
    Session,
}

impl ErrorCode {
    /// The code as it appears after `ERR`.
    pub const fn as_str(self) -> &'static str {
        match self {
            ErrorCode::Checksum => "CHECKSUM",
            ErrorCode::LineTooLong => "LINE_TOO_LONG",
            ErrorCode::Empty => "EMPTY",
            ErrorCode::Unknown => "UNKNOWN",
            ErrorCode::Syntax => "SYNTAX",
            ErrorCode::Value => "VALUE",
            ErrorCode::Range => "RANGE",
            ErrorCode::Geometry => "GEOMETRY",
            ErrorCode::Session => "SESSION",
        }
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The real-time bytes (`docs/protocol.md`): acted on the moment they
/// arrive, wherever they fall, and never part of a request. They are
/// grblHAL's non-printing codes (and grbl's reset): bytes a request can
/// never hold, where grbl's printable `?`, `!`, `~` would collide with the
/// CRC word ` ~CCCCCCCC` and with text in comments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Realtime {
    /// 0x80: one `!STATUS` line at once.
    Status,
    /// 0x81: cycle start, resume after a hold.
    Resume,
    /// 0x82: feed hold.
    Hold,
    /// 0x18 (Ctrl-X): stop at once and drop everything queued.
    Reset,
}

impl Realtime {
    /// The real-time command a byte is, if it is one.
    pub const fn from_byte(byte: u8) -> Option<Realtime> {
        match byte {
            0x80 => Some(Realtime::Status),
            0x81 => Some(Realtime::Resume),
            0x82 => Some(Realtime::Hold),
            0x18 => Some(Realtime::Reset),
            _ => None,
        }
    }
}

/// What a `!STATUS` line needs that only the session knows, handed to the
/// transport so that it can answer a status request while it waits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StatusView {
    /// X's impulse price, Å (on the radius).
    pub hx: i64,
    /// Z's impulse price, Å.
    pub hz: i64,
    /// X printed as a diameter.
    pub diam: bool,
    /// The speed, 10⁻⁴ mm/min.
    pub speed: i64,
    /// Starved block starts since the last `SYNC` or `ZERO`.
    pub starved: u32,
    /// Waiting for cycle start after `M00` (0), `M01` (1), a gear range
    /// (41 … 44) or a machine's own M code: ` STOP=M00`.
    pub stop: Option<u16>,
    /// The spindle and coolant outputs (` SPINDLE= S= COOLANT=`); a board
    /// puts in the speed it drives now.
    pub outputs: Outputs,
}

/// Where replies and motion go: the transport side of a [`Device`].
pub trait Io {
    /// Sends one complete reply line (it ends with `*HH` and CRLF).
    fn send(&mut self, line: &[u8]);

    /// A run of motion begins: its tick 0 is now.
    fn run_start(&mut self) {}

    /// A linear block starts: its events follow. (Events of a direct arc
    /// come without one.)
    fn block_start(&mut self, block: &LinearBlock) {
        let _ = block;
    }

    /// Issues one step event at `tick` of the current run (ticks of the
    /// device's step clock since the run began), with the drive's pulse
    /// width and DIR set-up. Events come in order; ticks never decrease
    /// within a run. The default does nothing (a calculator without motion).
    fn step(&mut self, event: StepEvent, tick: u64, drive: &DriveTiming) {
        let _ = (event, tick, drive);
    }

    /// The run ended `ticks` after it began; the axes are at rest.
    fn run_end(&mut self, ticks: u64) {
        let _ = ticks;
    }

    /// The transport's stepper that runs in time beside the protocol (a
    /// board's step interrupt), if it has one. Without one, started motion
    /// is issued at once through [`Io::step`] (the virtual clock).
    fn background(&mut self) -> Option<&mut dyn Background> {
        None
    }

    /// What a status line needs besides the stepper, kept current by the
    /// session (a board answers a status byte itself while it waits).
    fn view(&mut self, view: &StatusView) {
        let _ = view;
    }

    /// The handler is in the middle of a long computation and between two
    /// of its steps (every [`CHORDS_PER_PAUSE`] chords of an arc's check):
    /// a board answers a waiting status byte here and shows it is alive.
    fn pause(&mut self) {}

    /// A `G04` dwell of `us` microseconds, the axes at rest: a board
    /// waits (answering status bytes meanwhile); the virtual clock, whose
    /// runs are timed each from its own start, has nothing to wait for.
    fn dwell(&mut self, us: u64) {
        let _ = us;
    }

    /// A program stop (`M00`, or `M01` with the switch on; `code` 0 or 1),
    /// the axes at rest: a board waits for cycle start (0x81), answering
    /// status bytes meanwhile (`STOP=M00`); a reset ends the wait too. A
    /// transport without an operator presses cycle start at once.
    fn program_stop(&mut self, code: u16) {
        let _ = code;
    }

    /// A machine's M code switches user output `n` (1 … 4), the axes at
    /// rest: a board drives its pin.
    fn user_output(&mut self, n: u8, on: bool) {
        let _ = (n, on);
    }

    /// A machine's M code waits for user input `n` (1 … 4) to read
    /// `level`, the axes at rest, answering status bytes meanwhile (a
    /// reset ends the wait). A transport without inputs goes on at once.
    fn wait_input(&mut self, n: u8, level: bool) {
        let _ = (n, level);
    }

    /// Whether a program stop is a feed hold at rest rather than a wait
    /// (grbl's `M0`: answered at once, the state `Hold:0`, the lines after
    /// it received and queued, cycle start going on). Only with a
    /// background stepper, which holds.
    fn stop_holds(&mut self) -> bool {
        false
    }

    /// Before a program stop on a transport without a background stepper:
    /// the `!STATUS … STOP=M00` line (complete) that answers a status byte
    /// while it waits, nothing moving meanwhile.
    fn stop_status(&mut self, line: &[u8]) {
        let _ = line;
    }

    /// The spindle and the coolant switch, the axes at rest (the speed
    /// also changes at block starts, through the stepper): a board drives
    /// its outputs.
    fn outputs(&mut self, outputs: &Outputs) {
        let _ = outputs;
    }

    /// For a `!STATUS` line: how the transport keeps time, where it
    /// measures it (a board); the line then ends with `LAT= LATE=`.
    fn timing(&mut self) -> Option<Timing> {
        None
    }
}

/// The [`Io`] methods a wrapper hands to its `inner` unchanged: motion,
/// the background, waits and outputs (a wrapper writes its own `send`,
/// `stop_status`, `timing` and `stop_holds`).
macro_rules! forward_io {
    () => {
        fn run_start(&mut self) {
            self.inner.run_start();
        }
        fn block_start(&mut self, block: &crate::interleave::LinearBlock) {
            self.inner.block_start(block);
        }
        #[inline(always)]
        fn step(
            &mut self,
            event: crate::interleave::StepEvent,
            tick: u64,
            drive: &crate::stepdir::DriveTiming,
        ) {
            self.inner.step(event, tick, drive);
        }
        fn run_end(&mut self, ticks: u64) {
            self.inner.run_end(ticks);
        }
        fn background(&mut self) -> Option<&mut dyn crate::machine::Background> {
            self.inner.background()
        }
        fn view(&mut self, view: &crate::protocol::StatusView) {
            self.inner.view(view);
        }
        fn pause(&mut self) {
            self.inner.pause();
        }
        fn dwell(&mut self, us: u64) {
            self.inner.dwell(us);
        }
        fn program_stop(&mut self, code: u16) {
            self.inner.program_stop(code);
        }
        fn user_output(&mut self, n: u8, on: bool) {
            self.inner.user_output(n, on);
        }
        fn wait_input(&mut self, n: u8, level: bool) {
            self.inner.wait_input(n, level);
        }
        fn outputs(&mut self, outputs: &crate::outputs::Outputs) {
            self.inner.outputs(outputs);
        }
    };
}
pub(crate) use forward_io;

/// A board's own timing, at the end of its `!STATUS` lines.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Timing {
    /// Microseconds from the status byte's arrival to the line (`LAT=`).
    pub latency_us: u32,
    /// Step events issued later than their tick since power-on (`LATE=`).
    pub late_events: u32,
}

impl Timing {
    /// Appends ` LAT= LATE=` to a status line.
    pub fn write_to(&self, line: &mut ReplyLine) {
        use core::fmt::Write;
        let _ = write!(line, " LAT={} LATE={}", self.latency_us, self.late_events);
    }
}

/// Chords an arc's check takes between two [`Io::pause`] calls (about
/// 150 000 instructions on a Cortex-M4: 1 ms at 168 MHz).
pub const CHORDS_PER_PAUSE: u32 = 16;

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
}

#[cfg(test)]
mod tests;

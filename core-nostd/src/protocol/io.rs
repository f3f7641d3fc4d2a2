//! What the protocol shares with the transports around it: the [`Io`] a
//! device replies and hands its motion through, the real-time commands,
//! the error codes, the status a transport may answer itself.

use super::reply::ReplyLine;
use crate::interleave::{ImpulsePoint, LinearBlock, StepEvent};
use crate::length::{div_round_half_away, Length};
use crate::machine::Background;
use crate::outputs::Outputs;
use crate::stepdir::DriveTiming;
use crate::stepper::AxesState as Axes;
use core::fmt;

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
    /// The E-stop was pressed and the machine is not cleared: release,
    /// reset, `UNLOCK` (an extension).
    Estop,
    /// A hard limit or a drive's fault stopped the machine: `UNLOCK` (an
    /// extension).
    Alarm,
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
            ErrorCode::Estop => "ESTOP",
            ErrorCode::Alarm => "ALARM",
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
    /// The active inputs (` PN=`), when any input is wired.
    pub pins: Option<u16>,
    /// What an input stopped, as grbl numbers its alarm (0: nothing):
    /// `STATE=ESTOP` (10) or `STATE=ALARM`, ` ALARM=`.
    pub alarm: u8,
    /// The axes were stopped at once in motion since the last `UNLOCK`
    /// (` LOST=1`).
    pub lost: bool,
}

/// A refusal as a front numbers it, from the refusal itself (never from
/// its text): the protocol's code, and the address or key it is about
/// when that is one letter (`F` for a feed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Refused {
    /// The code after `ERR`.
    pub code: ErrorCode,
    /// The word's letter the refusal is about, if it is about one.
    pub about: Option<u8>,
}

/// What a status says, before a front writes it: the pendant's
/// `STATE= PX= …` line ([`crate::protocol::status_line`]) and grbl's
/// `<Idle|MPos:…>` report ([`crate::protocol::grbl::status_report`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StatusRecord {
    /// What the axes are doing.
    pub motion: Axes,
    /// The registers of the steps issued.
    pub issued: ImpulsePoint,
    /// Blocks queued and not started.
    pub queued: usize,
    /// The session's part: prices, speed, outputs, a program stop.
    pub view: StatusView,
}

impl StatusRecord {
    /// X as printed, 10⁻⁴ mm: the registers times the price, a diameter
    /// when the view says so.
    pub fn x_mm4(&self) -> i64 {
        let factor = if self.view.diam { 2 } else { 1 };
        // |registers| ≤ 999 999 999 and prices ≤ 10⁷ Å: within i64.
        div_round_half_away(
            i64::from(self.issued.x.get()) * self.view.hx * factor,
            1_000,
        )
    }

    /// Z as printed, 10⁻⁴ mm.
    pub fn z_mm4(&self) -> i64 {
        div_round_half_away(i64::from(self.issued.z.get()) * self.view.hz, 1_000)
    }

    /// The speed as printed, 10⁻⁴ mm/min: 0 once held at rest.
    pub fn speed_mm4(&self) -> i64 {
        if self.motion == Axes::Held {
            0
        } else {
            self.view.speed
        }
    }

    /// Running, holding (braking or held) or idle.
    pub const fn state(&self) -> State {
        match self.motion {
            Axes::Idle => State::Idle,
            Axes::Run => State::Run,
            Axes::Braking | Axes::Held => State::Hold,
        }
    }
}

/// The state a status reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// At rest, nothing started.
    Idle,
    /// Moving.
    Run,
    /// A feed hold: braking, or at rest.
    Hold,
}

impl State {
    /// The pendant's word (`STATE=`).
    pub const fn as_str(self) -> &'static str {
        match self {
            State::Idle => "IDLE",
            State::Run => "RUN",
            State::Hold => "HOLD",
        }
    }
}

/// Where replies and motion go: the transport side of a [`Device`].
pub trait Io {
    /// Sends one complete reply line (it ends with `*HH` and CRLF).
    fn send(&mut self, line: &[u8]);

    /// The next line sent is a refusal's `ERR` line, and this is what it
    /// is about.
    fn refused(&mut self, why: Refused) {
        let _ = why;
    }

    /// The next status line sent (a `STATUS` reply, a `!STATUS` line, or
    /// the line given to [`Io::stop_status`]) says this; `realtime` when it
    /// answers a status byte (a `!STATUS` line).
    fn status(&mut self, record: &StatusRecord, realtime: bool) {
        let _ = (record, realtime);
    }

    /// The next line sent is the request's final `OK` line (an `ERR` line
    /// is told through [`Io::refused`]).
    fn accepted(&mut self) {}

    /// The next line sent is `DATA MSG` with this text: what the operator
    /// must do at a stop (a gear range, the machine's own M code).
    fn message(&mut self, text: &[u8]) {
        let _ = text;
    }

    /// A reset dropped the motion (its `!RESET` line comes next):
    /// `running` when a block was running then (`OF=` above 0).
    fn reset_done(&mut self, running: bool) {
        let _ = running;
    }

    /// An input stopped the machine, grbl's alarm number `code` (1 a hard
    /// limit, 10 the E-stop, 17 a drive's fault): its `!ALARM` line comes
    /// next.
    fn alarm(&mut self, code: u8) {
        let _ = code;
    }

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

    /// The inputs active now, filtered, where the transport reads
    /// switches (a board, a simulated machine); `None` where it has none
    /// (nothing can home there). The homing cycle reads its switch
    /// through this while it waits for the motion.
    fn inputs_now(&mut self) -> Option<u16> {
        None
    }

    /// A probing move is about to start (`Some(touch)`) or has ended
    /// (`None`): meanwhile the transport stops the axes at once where the
    /// probe becomes active (`touch`) or inactive, as it stops them for a
    /// hard limit, the spindle and coolant left as they are. The session
    /// reads where through [`Io::inputs_now`] and the registers.
    fn probe_arm(&mut self, stop_on: Option<bool>) {
        let _ = stop_on;
    }

    /// A probing move ended at the machine position `at` (X on the radius;
    /// `diameter` when X is shown as a diameter), `changed` when the probe
    /// changed there: its `!PROBE` line comes next.
    fn probed(&mut self, at: [Length; 2], diameter: bool, changed: bool) {
        let _ = (at, diameter, changed);
    }

    /// For a `!STATUS` line: how the transport keeps time, where it
    /// measures it (a board); the line then ends with `LAT= LATE=`.
    fn timing(&mut self) -> Option<Timing> {
        None
    }
}

/// The [`Io`] methods a wrapper hands to its `inner` unchanged: what the
/// replies are, motion, the background, waits and outputs (a wrapper
/// writes its own `send`, `stop_status`, `timing` and `stop_holds`).
macro_rules! forward_io {
    () => {
        crate::protocol::io::forward_replies!();
        fn view(&mut self, view: &crate::protocol::io::StatusView) {
            self.inner.view(view);
        }
        fn pause(&mut self) {
            self.inner.pause();
        }
        crate::protocol::io::forward_motion!();
    };
}
pub(crate) use forward_io;

/// What the replies are ([`Io::refused`], [`Io::status`], [`Io::accepted`],
/// [`Io::message`], [`Io::reset_done`], [`Io::alarm`]), handed to `inner` unchanged.
macro_rules! forward_replies {
    () => {
        fn refused(&mut self, why: crate::protocol::io::Refused) {
            self.inner.refused(why);
        }
        fn status(&mut self, record: &crate::protocol::io::StatusRecord, realtime: bool) {
            self.inner.status(record, realtime);
        }
        fn accepted(&mut self) {
            self.inner.accepted();
        }
        fn message(&mut self, text: &[u8]) {
            self.inner.message(text);
        }
        fn reset_done(&mut self, running: bool) {
            self.inner.reset_done(running);
        }
        fn alarm(&mut self, code: u8) {
            self.inner.alarm(code);
        }
        fn probed(&mut self, at: [crate::length::Length; 2], diameter: bool, changed: bool) {
            self.inner.probed(at, diameter, changed);
        }
    };
}
pub(crate) use forward_replies;

/// Motion, the background, waits and outputs handed to `inner`; with
/// `unless flag`, none of them while the wrapper's `flag` is set (grbl's
/// check mode: replies go out, nothing moves, waits or switches).
macro_rules! forward_motion {
    ($(unless $flag:ident)?) => {
        fn run_start(&mut self) {
            if !(false $(|| self.$flag)?) {
                self.inner.run_start();
            }
        }
        fn block_start(&mut self, block: &crate::interleave::LinearBlock) {
            if !(false $(|| self.$flag)?) {
                self.inner.block_start(block);
            }
        }
        #[inline(always)]
        fn step(
            &mut self,
            event: crate::interleave::StepEvent,
            tick: u64,
            drive: &crate::stepdir::DriveTiming,
        ) {
            if !(false $(|| self.$flag)?) {
                self.inner.step(event, tick, drive);
            }
        }
        fn run_end(&mut self, ticks: u64) {
            if !(false $(|| self.$flag)?) {
                self.inner.run_end(ticks);
            }
        }
        fn background(&mut self) -> Option<&mut dyn crate::machine::Background> {
            if false $(|| self.$flag)? {
                return None;
            }
            self.inner.background()
        }
        fn dwell(&mut self, us: u64) {
            if !(false $(|| self.$flag)?) {
                self.inner.dwell(us);
            }
        }
        fn program_stop(&mut self, code: u16) {
            if !(false $(|| self.$flag)?) {
                self.inner.program_stop(code);
            }
        }
        fn user_output(&mut self, n: u8, on: bool) {
            if !(false $(|| self.$flag)?) {
                self.inner.user_output(n, on);
            }
        }
        fn wait_input(&mut self, n: u8, level: bool) {
            if !(false $(|| self.$flag)?) {
                self.inner.wait_input(n, level);
            }
        }
        fn outputs(&mut self, outputs: &crate::outputs::Outputs) {
            if !(false $(|| self.$flag)?) {
                self.inner.outputs(outputs);
            }
        }
        fn inputs_now(&mut self) -> Option<u16> {
            if false $(|| self.$flag)? {
                return None;
            }
            self.inner.inputs_now()
        }
        fn probe_arm(&mut self, stop_on: Option<bool>) {
            if !(false $(|| self.$flag)?) {
                self.inner.probe_arm(stop_on);
            }
        }
    };
}
pub(crate) use forward_motion;

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

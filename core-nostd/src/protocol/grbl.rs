//! The grbl 1.1 serial protocol, a second front over the same session, so
//! that the senders machinists already use (Universal Gcode Sender, bCNC,
//! CNCjs, ioSender) stream to the controller unchanged.
//!
//! It translates at the edge and interprets nothing twice: a G-code line
//! runs on the [`Session`] exactly as a pendant request does, and its
//! pendant reply becomes `ok` or `error:N` (with a `[MSG:…]` line that says
//! what and where); the session's status line becomes grbl's
//! `<Idle|MPos:…|FS:…|WCO:…|Ov:…>`; a reset's report becomes the banner.
//! The lathe is reported as grblHAL reports its lathe mode: `$32=2`,
//! `LATHE` among the options, X as a diameter in diameter mode (`G7` in
//! `$G`, `|D:1`) and Y always 0.
//!
//! What a grbl sender needs of the link: character counting against an RX
//! buffer of [`RX_BUFFER`] bytes (the board's serial ring holds 512), `?`,
//! `!`, `~` and Ctrl-X as real-time characters wherever they fall, 0x85
//! jog cancel and the feed overrides 0x90–0x94. Rapid and spindle
//! overrides are not implemented: their bytes are answered with a message
//! and change nothing.

use super::io::{ErrorCode, Io, Realtime, Refused, State, StatusRecord, StatusView, Timing};
use super::reply::ReplyLine;
use super::session::{Session, VERSION};
use core::fmt::Write;

/// The RX buffer a sender may fill by character counting (`$I`'s `OPT`).
pub const RX_BUFFER: usize = 128;
/// Planner blocks (`$I`'s `OPT`: the queue less one, as grbl counts).
pub const BLOCKS: usize = 63;
/// The welcome line after a reset.
pub const BANNER: &[u8] = b"\r\nGrbl 1.1h ['$' for help]\r\n";

/// A real-time character of grbl.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GrblRealtime {
    /// One of the pendant's real-time commands (`?`, `!`, `~`, Ctrl-X, and
    /// the pendant's own 0x80–0x82).
    Common(Realtime),
    /// 0x85: stop a jog and drop what is left of it.
    JogCancel,
    /// 0x90–0x94: feed override to 100 %, +10, −10, +1, −1.
    Feed(u8),
    /// 0x95–0x97: rapid override to 100, 50, 25 %.
    Rapid(u8),
    /// 0x99–0x9D: spindle override to 100 %, +10, −10, +1, −1.
    Spindle(u8),
    /// The spindle stop (0x9E) and coolant toggles (0xA0, 0xA1): not
    /// implemented.
    Unsupported(u8),
}

impl GrblRealtime {
    /// The feed, rapid and spindle overrides (percent) after this command:
    /// a transport that shows them before the protocol has acted on the
    /// byte computes them as the protocol will.
    pub const fn overrides(self, [feed, rapid, spindle]: [u8; 3]) -> [u8; 3] {
        match self {
            GrblRealtime::Feed(byte) => [stepped(feed, byte), rapid, spindle],
            GrblRealtime::Rapid(byte) => [
                feed,
                match byte {
                    0x95 => 100,
                    0x96 => 50,
                    _ => 25,
                },
                spindle,
            ],
            GrblRealtime::Spindle(byte) => [feed, rapid, stepped(spindle, byte - 0x09)],
            _ => [feed, rapid, spindle],
        }
    }

    /// The real-time command a byte is in grbl mode, if it is one.
    pub const fn from_byte(byte: u8) -> Option<GrblRealtime> {
        match byte {
            b'?' => Some(GrblRealtime::Common(Realtime::Status)),
            b'!' => Some(GrblRealtime::Common(Realtime::Hold)),
            b'~' => Some(GrblRealtime::Common(Realtime::Resume)),
            0x85 => Some(GrblRealtime::JogCancel),
            0x90..=0x94 => Some(GrblRealtime::Feed(byte)),
            0x95..=0x97 => Some(GrblRealtime::Rapid(byte)),
            0x99..=0x9D => Some(GrblRealtime::Spindle(byte)),
            0x9E | 0xA0 | 0xA1 => Some(GrblRealtime::Unsupported(byte)),
            _ => match Realtime::from_byte(byte) {
                Some(rt) => Some(GrblRealtime::Common(rt)),
                None => None,
            },
        }
    }
}

/// Whether a byte that is not a real-time command is dropped on a grbl
/// link rather than taken into the line: above 0x7F (grbl keeps only its
/// real-time commands there; CNCjs sends an override byte as UTF-8, `C2 91`)
/// and control bytes other than CR, LF and tab.
pub const fn dropped(byte: u8) -> bool {
    byte >= 0x80 || (byte < 0x20 && !matches!(byte, b'\r' | b'\n' | b'\t'))
}

/// The grbl front's own state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Front {
    /// Whether the link speaks grbl.
    pub on: bool,
    /// The alarm in force (`ALARM:3` after a reset in motion), until `$X`.
    pub alarm: Option<u8>,
    /// Feed override, percent (10 … 200).
    pub feed: u8,
    /// Rapid override, percent (100, 50, 25).
    pub rapid: u8,
    /// Spindle override, percent (10 … 200).
    pub spindle: u8,
    /// A jog runs; a jog cancel waits for the axes to come to rest.
    pub jogging: bool,
    /// A jog cancel came: drop the rest once at rest.
    pub cancel: bool,
    /// `$C`: lines are checked, nothing moves or switches.
    pub check: bool,
    /// `$10` bit 0: status reports give machine positions (else work).
    pub mpos: bool,
    /// The settings kept for senders (see `$$`).
    pub kept: [u32; KEPT],
}

impl Front {
    /// Power-on: the pendant protocol, no alarm, 100 %.
    pub const fn new() -> Front {
        Front {
            on: false,
            alarm: None,
            feed: 100,
            rapid: 100,
            spindle: 100,
            jogging: false,
            cancel: false,
            check: false,
            mpos: true,
            kept: KEPT_DEFAULT,
        }
    }
}

impl Default for Front {
    fn default() -> Self {
        Self::new()
    }
}

/// The value of `KEY=` in a pendant reply line.
fn value<'a>(line: &'a [u8], key: &[u8]) -> Option<&'a [u8]> {
    let mut words = line.split(|&b| b == b' ' || b == b'*');
    words.find_map(|w| w.strip_prefix(key).and_then(|rest| rest.strip_prefix(b"=")))
}

/// A line ended without a checksum, as grbl ends its lines.
fn finish(line: &mut ReplyLine) -> &[u8] {
    line.push_bytes(b"\r\n");
    line.as_bytes()
}

/// Writes `Å` as mm with 4 decimals (X doubled when `diameter`).
fn write_mm(line: &mut ReplyLine, angstrom: i64, diameter: bool) {
    let v = if diameter { 2 * angstrom } else { angstrom };
    let _ = crate::length::write_mm4(line, crate::length::div_round_half_away(v, 1_000));
}

/// What the grbl link shows of the session's machine state, beside the
/// status line: the work offset, the override, the mode.
#[derive(Clone, Copy, Debug)]
pub struct Extras {
    /// Work zero in machine coordinates, Å, X on the radius (`WCO:`).
    pub wco: [i64; 2],
    /// X as a diameter.
    pub diameter: bool,
    /// Feed, rapid and spindle overrides, percent.
    pub overrides: [u8; 3],
    /// A jog runs.
    pub jogging: bool,
    /// The alarm in force.
    pub alarm: Option<u8>,
    /// Check mode (`$C`).
    pub check: bool,
    /// Positions as machine coordinates (`MPos:`), else work (`WPos:`).
    pub mpos: bool,
}

impl Extras {
    /// Nothing to add (a pendant link).
    pub const NONE: Extras = Extras {
        wco: [0, 0],
        diameter: false,
        overrides: [100; 3],
        jogging: false,
        alarm: None,
        check: false,
        mpos: true,
    };

    /// The session's.
    pub fn of(session: &Session, front: &Front) -> Extras {
        let v = session
            .offsets()
            .vector(session.selection())
            .unwrap_or([crate::length::Length::ZERO; 2]);
        Extras {
            wco: [v[0].as_angstrom(), v[1].as_angstrom()],
            diameter: session.config().diam,
            overrides: [front.feed, front.rapid, front.spindle],
            jogging: front.jogging,
            alarm: front.alarm,
            check: front.check,
            mpos: front.mpos,
        }
    }
}

/// A pendant status line (`STATUS`/`!STATUS`) as grbl's status report:
/// `<Run|MPos:X,0.0000,Z|FS:F,S|WCO:…|Ov:…|D:1>`.
pub fn status_report(record: &StatusRecord, extras: &Extras) -> ReplyLine {
    let mut line = ReplyLine::new();
    let at_rest = record.speed_mm4() == 0;
    let state: &[u8] = match (extras.alarm, record.state(), record.view.stop) {
        (Some(_), _, _) => b"Alarm",
        _ if extras.check => b"Check",
        (_, _, Some(_)) => b"Hold:0",
        (_, State::Hold, _) if at_rest => b"Hold:0",
        (_, State::Hold, _) => b"Hold:1",
        (_, State::Run, _) if extras.jogging => b"Jog",
        (_, State::Run, _) => b"Run",
        (_, State::Idle, _) => b"Idle",
    };
    line.push_bytes(b"<");
    line.push_bytes(state);
    let (x, z) = (record.x_mm4(), record.z_mm4());
    if extras.mpos {
        line.push_bytes(b"|MPos:");
        let _ = crate::length::write_mm4(&mut line, x);
        line.push_bytes(b",0.0000,");
        let _ = crate::length::write_mm4(&mut line, z);
    } else {
        // Work position: the machine's less the work offset.
        line.push_bytes(b"|WPos:");
        let wco = |a: i64, diameter| {
            let v = if diameter { 2 * a } else { a };
            crate::length::div_round_half_away(v, 1_000)
        };
        let _ = crate::length::write_mm4(&mut line, x - wco(extras.wco[0], extras.diameter));
        line.push_bytes(b",0.0000,");
        let _ = crate::length::write_mm4(&mut line, z - wco(extras.wco[1], false));
    }
    line.push_bytes(b"|FS:");
    let _ = crate::length::write_mm4(&mut line, record.speed_mm4());
    line.push_bytes(b",");
    let _ = crate::outputs::write_rpm(&mut line, record.view.outputs.rpm);
    line.push_bytes(b"|WCO:");
    write_mm(&mut line, extras.wco[0], extras.diameter);
    line.push_bytes(b",0.0000,");
    write_mm(&mut line, extras.wco[1], false);
    let [f, r, s] = extras.overrides;
    let _ = write!(line, "|Ov:{f},{r},{s}|D:{}>", u8::from(extras.diameter));
    line
}

/// The grbl error number of a refusal: expected command letter or bad
/// number format (1), undefined feed rate (22), unsupported command (20),
/// invalid target (33), line overflow (11), travel exceeded (15).
pub fn error_number(why: Refused) -> u8 {
    use ErrorCode as E;
    match why.code {
        E::Syntax | E::Checksum => 1,
        E::Value if why.about == Some(b'F') => 22,
        E::Unknown | E::Value | E::Empty | E::Session => 20,
        E::Geometry => 33,
        E::LineTooLong => 11,
        E::Range => 15,
    }
}

/// The one [`Io`] the session answers through (so that its code exists
/// once on the board): on a pendant link every call passes through; on a
/// grbl link motion passes through and reply lines turn into grbl's.
pub struct Translate<'a, I: Io + ?Sized> {
    inner: &'a mut I,
    grbl: bool,
    /// A query of the front's own: the final line is kept, nothing sent.
    capture: bool,
    extras: Extras,
    /// Status lines pass (a `?`), or are dropped (the answer to `!`, `~`).
    pub statuses: bool,
    /// The final line of the request: `None` before it came.
    pub outcome: Option<Result<(), u8>>,
    /// A refusal's text, for its `[MSG:…]` line (a query's final line).
    pub message: ReplyLine,
    /// What the refusal about to be sent is about.
    refused: Option<Refused>,
    /// What the status line about to be sent says.
    status: Option<StatusRecord>,
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
            capture: false,
            extras,
            statuses: true,
            outcome: None,
            message: ReplyLine::new(),
            refused: None,
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
        if self.capture {
            if line.starts_with(b"OK") || line.starts_with(b"ERR") {
                self.message = ReplyLine::new();
                self.message.push_bytes(line);
            }
            return;
        }
        // Without the `*HH` and CRLF.
        let body = line
            .iter()
            .rposition(|&b| b == b'*')
            .and_then(|i| line.get(..i))
            .unwrap_or(line);
        if body.starts_with(b"OK") {
            self.outcome = Some(Ok(()));
        } else if body.starts_with(b"ERR ") {
            // Every `ERR` line is told first (`send_error_about`); one
            // that was not is no command this control runs.
            let why = self.refused.take().unwrap_or(Refused {
                code: ErrorCode::Unknown,
                about: None,
            });
            self.outcome = Some(Err(error_number(why)));
            self.message = ReplyLine::new();
            self.message.push_bytes(body.get(4..).unwrap_or(b""));
        } else if body.starts_with(b"!STATUS") {
            // Every status line is told first (`Io::status`).
            if let (true, Some(record)) = (self.statuses, self.status.take()) {
                let mut l = status_report(&record, &self.extras);
                self.inner.send(finish(&mut l));
            }
        } else if let Some(text) = body.strip_prefix(b"DATA MSG ") {
            // What the operator must do at a stop (a gear range, the
            // machine's own M code): grbl's feedback message.
            let mut l = ReplyLine::new();
            l.push_bytes(b"[MSG:");
            l.push_bytes(text);
            l.push_bytes(b"]");
            self.inner.send(finish(&mut l));
        }
        // `DATA` lines and the rest: not grbl's.
    }
    fn refused(&mut self, why: Refused) {
        if self.grbl {
            self.refused = Some(why);
        } else {
            self.inner.refused(why);
        }
    }
    fn reset_done(&mut self, running: bool) {
        if self.grbl {
            self.reset = Some(running);
        } else {
            self.inner.reset_done(running);
        }
    }
    fn status(&mut self, record: &StatusRecord) {
        if self.grbl {
            self.status = Some(*record);
        } else {
            self.inner.status(record);
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
    fn run_start(&mut self) {
        if !self.dry {
            self.inner.run_start();
        }
    }
    fn block_start(&mut self, block: &crate::interleave::LinearBlock) {
        if !self.dry {
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
        if !self.dry {
            self.inner.step(event, tick, drive);
        }
    }
    fn run_end(&mut self, ticks: u64) {
        if !self.dry {
            self.inner.run_end(ticks);
        }
    }
    fn background(&mut self) -> Option<&mut dyn crate::machine::Background> {
        if self.dry {
            return None;
        }
        self.inner.background()
    }
    fn view(&mut self, view: &StatusView) {
        self.inner.view(view);
    }
    fn pause(&mut self) {
        self.inner.pause();
    }
    fn dwell(&mut self, us: u64) {
        if !self.dry {
            self.inner.dwell(us);
        }
    }
    fn program_stop(&mut self, code: u16) {
        if !self.dry {
            self.inner.program_stop(code);
        }
    }
    fn user_output(&mut self, n: u8, on: bool) {
        if !self.dry {
            self.inner.user_output(n, on);
        }
    }
    fn wait_input(&mut self, n: u8, level: bool) {
        if !self.dry {
            self.inner.wait_input(n, level);
        }
    }
    fn outputs(&mut self, outputs: &crate::outputs::Outputs) {
        if !self.dry {
            self.inner.outputs(outputs);
        }
    }
}

/// Runs a pendant request that moves nothing and returns its final line.
fn query<I: Io + ?Sized>(
    session: &mut Session,
    t: &mut Translate<'_, I>,
    request: &[u8],
) -> ReplyLine {
    let saved = (t.capture, t.outcome);
    t.capture = true;
    session.handle_line(request, t);
    let line = core::mem::take(&mut t.message);
    (t.capture, t.outcome) = saved;
    line
}

/// Where a `$n` setting lives on this controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Place {
    /// A key of a pendant request: `$110` is `LIMITS VX`.
    Request(&'static [u8], &'static [u8]),
    /// Steps per mm of an axis: one over the impulse price of `CFG`'s key.
    StepsPerMm(&'static [u8]),
    /// Kept by the front for senders that write and read it back; it
    /// changes nothing on this machine (`Front::kept`, by index). A decimal
    /// when `decimal`, else a whole number up to 65535.
    Kept(usize, bool),
    /// Only the value shown is accepted; another is refused with the
    /// reason (grbl's error 3, or the code given).
    Fixed(&'static [u8], u8, &'static str),
    /// `$10`, the status report's mask: bit 0 machine (1) or work (0)
    /// positions. Bit 1 (`Bf:`) is not reported.
    ReportMask,
}

/// One grbl setting: its number and where it lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Setting {
    n: u16,
    place: Place,
}

const fn setting(n: u16, place: Place) -> Setting {
    Setting { n, place }
}

/// The settings `$$` lists, in grbl's order, and what `$n=` does to each.
/// Those that would change the machine's behaviour but have nothing on
/// this board to act on (inverted pins, limit and home switches) accept
/// only the value that leaves the machine as it is; the rest of grbl's
/// list is kept and read back.
const SETTINGS: [Setting; 30] = [
    setting(0, Place::Request(b"DRIVE", b"PULSE")),
    setting(1, Place::Kept(0, false)),
    setting(
        2,
        Place::Fixed(b"0", 3, "step pulses are not inverted on this board"),
    ),
    setting(
        3,
        Place::Fixed(b"0", 3, "set an axis' direction by wiring its DIR"),
    ),
    setting(
        4,
        Place::Fixed(b"0", 3, "this board has no stepper enable output"),
    ),
    setting(
        5,
        Place::Fixed(b"0", 3, "this board has no limit switch inputs"),
    ),
    setting(6, Place::Fixed(b"0", 3, "this board has no probe input")),
    setting(10, Place::ReportMask),
    setting(11, Place::Request(b"LIMITS", b"JD")),
    setting(12, Place::Request(b"CFG", b"TOL")),
    setting(13, Place::Fixed(b"0", 3, "reports are in mm")),
    setting(
        20,
        Place::Fixed(
            b"0",
            10,
            "soft limits need homing, which this board has not",
        ),
    ),
    setting(
        21,
        Place::Fixed(b"0", 3, "this board has no limit switch inputs"),
    ),
    setting(
        22,
        Place::Fixed(b"0", 3, "this board has no home switch inputs"),
    ),
    setting(23, Place::Kept(2, false)),
    setting(24, Place::Kept(3, true)),
    setting(25, Place::Kept(4, true)),
    setting(26, Place::Kept(5, false)),
    setting(27, Place::Kept(6, true)),
    setting(30, Place::Request(b"AUX", b"SMAX")),
    setting(
        31,
        Place::Fixed(b"0", 3, "the spindle output starts from 0 rpm"),
    ),
    setting(
        32,
        Place::Fixed(b"2", 3, "this is a lathe: grblHAL's lathe mode 2"),
    ),
    setting(100, Place::StepsPerMm(b"HX")),
    setting(102, Place::StepsPerMm(b"HZ")),
    setting(110, Place::Request(b"LIMITS", b"VX")),
    setting(112, Place::Request(b"LIMITS", b"VZ")),
    setting(120, Place::Request(b"LIMITS", b"AX")),
    setting(122, Place::Request(b"LIMITS", b"AZ")),
    setting(130, Place::Kept(7, true)),
    setting(132, Place::Kept(8, true)),
];

/// How many settings the front keeps.
pub const KEPT: usize = 9;

/// The kept settings at power-on, as grbl's defaults: `$1` 25 ms, (unused
/// slot), `$23` 0, `$24` 25 mm/min, `$25` 500 mm/min, `$26` 250 ms, `$27`
/// 1 mm, `$130`/`$132` 200 mm (decimals in 10⁻³).
pub const KEPT_DEFAULT: [u32; KEPT] = [25, 0, 0, 25_000, 500_000, 250, 1_000, 200_000, 200_000];

fn settings<I: Io + ?Sized>(session: &mut Session, front: &Front, io: &mut Translate<'_, I>) {
    let cfg = *session.config();
    for s in SETTINGS {
        let mut l = ReplyLine::new();
        let _ = write!(l, "${}=", s.n);
        match s.place {
            Place::Request(command, key) => {
                let reply = query(session, io, command);
                l.push_bytes(value(reply.as_bytes(), key).unwrap_or(b"0"));
            }
            Place::StepsPerMm(key) => {
                let h = if key == b"HX" { cfg.hx } else { cfg.hz }.as_angstrom();
                // 10⁷/h steps per mm, to 3 decimals.
                let milli = crate::length::div_round_half_away(10_000_000_000, h.max(1));
                let _ = write!(l, "{}.{:03}", milli / 1000, milli % 1000);
            }
            Place::Kept(i, decimal) => {
                let v = front.kept.get(i).copied().unwrap_or(0);
                let _ = if decimal {
                    write!(l, "{}.{:03}", v / 1000, v % 1000)
                } else {
                    write!(l, "{v}")
                };
            }
            Place::Fixed(v, _, _) => l.push_bytes(v),
            Place::ReportMask => {
                let _ = write!(l, "{}", u8::from(front.mpos));
            }
        }
        io.inner.send(finish(&mut l));
    }
}

/// Refuses a `$n=` with grbl's `code` and what is wrong.
fn refuse_setting<I: Io + ?Sized>(io: &mut Translate<'_, I>, code: u8, n: u16, why: &[u8]) {
    io.outcome = Some(Err(code));
    io.message = ReplyLine::new();
    let _ = write!(io.message, "${n}: ");
    io.message.push_bytes(why);
}

/// A whole number of at most 5 digits, or a decimal with up to 3 places,
/// in thousandths.
fn parse_setting(v: &[u8], decimal: bool) -> Option<u32> {
    let (int, frac) = match v.iter().position(|&b| b == b'.') {
        Some(dot) if decimal => (v.get(..dot)?, v.get(dot + 1..)?),
        Some(_) => return None,
        None => (v, &b""[..]),
    };
    if int.is_empty() && frac.is_empty()
        || int.len() > 5
        || frac.len() > 3
        || !int.iter().chain(frac).all(u8::is_ascii_digit)
    {
        return None;
    }
    let digits = |d: &[u8]| d.iter().fold(0u32, |a, &b| a * 10 + u32::from(b - b'0'));
    let whole = digits(int);
    if !decimal {
        return (whole <= 65_535).then_some(whole);
    }
    let mut f = digits(frac);
    for _ in frac.len()..3 {
        f *= 10;
    }
    Some(whole * 1000 + f)
}

/// `$n=value`: the setting, or grbl's error for it.
fn set<I: Io + ?Sized>(
    session: &mut Session,
    front: &mut Front,
    n: &[u8],
    v: &[u8],
    io: &mut Translate<'_, I>,
) {
    let number = core::str::from_utf8(n)
        .ok()
        .and_then(|t| t.parse::<u16>().ok());
    let Some(s) = SETTINGS.iter().find(|s| Some(s.n) == number).copied() else {
        io.outcome = Some(Err(3));
        io.message = ReplyLine::new();
        io.message
            .push_bytes(b"no such setting on this controller: $");
        io.message.push_bytes(n);
        return;
    };
    if v.first() == Some(&b'-') {
        return refuse_setting(io, 4, s.n, b"a negative value");
    }
    match s.place {
        Place::Request(command, key) => {
            let mut req = ReplyLine::new();
            req.push_bytes(command);
            req.push_bytes(b" ");
            req.push_bytes(key);
            req.push_bytes(b"=");
            req.push_bytes(v);
            let request = ReplyLine::clone(&req);
            session.handle_line(request.as_bytes(), io);
        }
        Place::StepsPerMm(key) => {
            // One over the steps: a price on the 10⁻⁷ mm grid.
            let steps = core::str::from_utf8(v)
                .ok()
                .and_then(|t| crate::length::Length::from_gcode_mm(t).ok())
                .map(|l| l.as_angstrom())
                .filter(|&l| l > 0);
            let Some(steps) = steps else {
                return refuse_setting(io, 2, s.n, b"steps per mm above 0");
            };
            // h Å = 10⁷ Å / (steps / 10⁷).
            let steps = steps.unsigned_abs();
            let price = 100_000_000_000_000u64.checked_div(steps);
            let exact = 100_000_000_000_000u64.checked_rem(steps) == Some(0);
            let Some(price) = price.filter(|_| exact) else {
                return refuse_setting(
                    io,
                    3,
                    s.n,
                    b"one step must be a whole number of 0.0000001 mm",
                );
            };
            let mut req = ReplyLine::new();
            req.push_bytes(b"CFG ");
            req.push_bytes(key);
            req.push_bytes(b"=");
            let _ = crate::length::write_exact_mm(&mut req, price as i64);
            let request = ReplyLine::clone(&req);
            session.handle_line(request.as_bytes(), io);
        }
        Place::Kept(i, decimal) => match (parse_setting(v, decimal), front.kept.get_mut(i)) {
            (Some(value), Some(slot)) => {
                *slot = value;
                io.outcome = Some(Ok(()));
            }
            _ => refuse_setting(
                io,
                2,
                s.n,
                if decimal {
                    b"a number with up to 3 decimals"
                } else {
                    b"a whole number up to 65535"
                },
            ),
        },
        Place::ReportMask => match parse_setting(v, false) {
            Some(m @ (0 | 1)) => {
                front.mpos = m == 1;
                io.outcome = Some(Ok(()));
            }
            _ => refuse_setting(
                io,
                3,
                s.n,
                b"0 (work position) or 1 (machine position); Bf: is not reported",
            ),
        },
        Place::Fixed(only, code, why) => {
            let same = parse_setting(v, true).is_some_and(|x| Some(x) == parse_setting(only, true));
            if same {
                io.outcome = Some(Ok(()));
            } else {
                refuse_setting(io, code, s.n, why.as_bytes());
            }
        }
    }
}

/// `$#`: work offsets, the stored positions, the G92 shift.
fn offsets<I: Io + ?Sized>(session: &Session, io: &mut Translate<'_, I>) {
    let o = session.offsets();
    let diameter = session.config().diam;
    let mut put = |name: &[u8], p: [crate::length::Length; 2]| {
        let mut l = ReplyLine::new();
        l.push_bytes(b"[");
        l.push_bytes(name);
        l.push_bytes(b":");
        write_mm(&mut l, p[0].as_angstrom(), diameter);
        l.push_bytes(b",0.0000,");
        write_mm(&mut l, p[1].as_angstrom(), false);
        l.push_bytes(b"]");
        io.inner.send(finish(&mut l));
    };
    let names: [&[u8]; 6] = [b"G54", b"G55", b"G56", b"G57", b"G58", b"G59"];
    for (name, w) in names.iter().zip(o.work.iter()) {
        put(name, *w);
    }
    put(b"G28", o.reference[0]);
    put(b"G30", o.reference[1]);
    put(b"G92", o.shift);
    io.line(b"[TLO:0.0000]");
    io.line(b"[PRB:0.0000,0.0000,0.0000:0]");
}

/// `$G`: the modal state, grblHAL's lathe words included.
fn modes<I: Io + ?Sized>(session: &Session, io: &mut Translate<'_, I>) {
    use crate::gcode::{Coolant, FeedMode, Spindle, SpindleMode, Units};
    let m = session.modal();
    let aux = session.aux();
    let mut l = ReplyLine::new();
    let _ = write!(
        l,
        "[GC:G{} G{} {} G18 {} {} {} {} {} {} T{}",
        match m.motion {
            crate::gcode::Motion::Rapid => 0,
            crate::gcode::Motion::Linear => 1,
            crate::gcode::Motion::ArcCw => 2,
            crate::gcode::Motion::ArcCcw => 3,
        },
        54 + session.selection().wcs,
        if session.config().diam { "G7" } else { "G8" },
        if m.units == Units::Inch { "G20" } else { "G21" },
        if m.incremental { "G91" } else { "G90" },
        if m.feed_mode == FeedMode::PerRev {
            "G95"
        } else {
            "G94"
        },
        if aux.spindle.mode == SpindleMode::Surface {
            "G96"
        } else {
            "G97"
        },
        match aux.spindle.turning {
            Spindle::Cw => "M3",
            Spindle::Ccw => "M4",
            Spindle::Off => "M5",
        },
        match aux.coolant {
            Coolant::Mist => "M7",
            Coolant::Flood => "M8",
            Coolant::Off => "M9",
        },
        session.selection().loaded,
    );
    l.push_bytes(b" F");
    let _ = write!(l, "{}", m.feed.unwrap_or(crate::length::Length::ZERO));
    l.push_bytes(b" S");
    let _ = write!(
        l,
        "{}",
        aux.spindle.s.unwrap_or(crate::length::Length::ZERO)
    );
    l.push_bytes(b"]");
    io.inner.send(finish(&mut l));
}

/// `$J=…`: a jog as a `MOVE` in machine coordinates (G90 words are work
/// coordinates unless `G53`; G91 an increment; mm only; `F` required).
fn jog_line<I: Io + ?Sized>(
    session: &mut Session,
    words: &[u8],
    io: &mut Translate<'_, I>,
) -> bool {
    let refuse = |io: &mut Translate<'_, I>, code: u8, why: &[u8]| {
        io.outcome = Some(Err(code));
        io.message = ReplyLine::new();
        io.message.push_bytes(b"$J: ");
        io.message.push_bytes(why);
        false
    };
    let (mut inc, mut machine) = (false, false);
    let mut axes: [Option<crate::length::Length>; 2] = [None, None];
    let mut feed = None;
    let mut rest = words;
    while let Some((&first, tail)) = rest.split_first() {
        let letter = first.to_ascii_uppercase();
        let len = tail
            .iter()
            .position(|b| !(b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+')))
            .unwrap_or(tail.len());
        let (digits, after) = (
            tail.get(..len).unwrap_or(b""),
            tail.get(len..).unwrap_or(b""),
        );
        let number = core::str::from_utf8(digits).unwrap_or("");
        rest = after;
        match (letter, number) {
            (b' ', _) => continue,
            (b'G', "90") => inc = false,
            (b'G', "91") => inc = true,
            (b'G', "53") => machine = true,
            (b'G', "21") => {}
            (b'G', "20") => return refuse(io, 20, b"inches are not jogged here: G21"),
            (b'X' | b'Z' | b'F', n) => match crate::length::Length::from_gcode_mm(n) {
                Ok(v) if letter == b'X' => axes[0] = Some(v),
                Ok(v) if letter == b'Z' => axes[1] = Some(v),
                Ok(v) => feed = Some(v),
                Err(_) => return refuse(io, 2, b"bad number"),
            },
            _ => return refuse(io, 20, b"only X, Z, F, G20/G21, G90/G91, G53"),
        }
    }
    let Some(f) = feed else {
        return refuse(io, 22, b"F is required");
    };
    if axes == [None, None] {
        return refuse(io, 26, b"no axis word");
    }
    // `MOVE` takes work coordinates (as `POS` prints them): a G53 target
    // less the offsets in effect (X on the diameter when the words are
    // diameters).
    let wco = if machine && !inc {
        let w = Extras::of(session, &Front::new()).wco;
        [-w[0], -w[1]]
    } else {
        [0, 0]
    };
    let diameter = session.config().diam;
    let mut req = ReplyLine::new();
    req.push_bytes(b"MOVE");
    let shifts = [if diameter { 2 * wco[0] } else { wco[0] }, wco[1]];
    for ((a, name), shift) in axes.iter().zip([b" X=", b" Z="]).zip(shifts) {
        if let Some(v) = a {
            req.push_bytes(name);
            let _ = crate::length::write_exact_mm(&mut req, v.as_angstrom() + shift);
        }
    }
    if inc {
        req.push_bytes(b" INC=1");
    }
    req.push_bytes(b" F=");
    let _ = crate::length::write_exact_mm(&mut req, f.as_angstrom());
    let request = ReplyLine::clone(&req);
    session.handle_line(request.as_bytes(), io);
    io.outcome == Some(Ok(()))
}

/// Runs one line received in grbl mode. Returns whether the link goes
/// back to the pendant protocol (`$PENDANT`).
pub fn line<I: Io + ?Sized>(
    front: &mut Front,
    session: &mut Session,
    text: &[u8],
    io: &mut I,
) -> bool {
    let extras = Extras::of(session, front);
    let trimmed = trim(text);
    let upper = |i: usize| trimmed.get(i).map(u8::to_ascii_uppercase);
    let command = trimmed.first() == Some(&b'$');
    let jog = command && upper(1) == Some(b'J') && upper(2) == Some(b'=');
    if front.check && (jog || !command) && !trimmed.is_empty() {
        // Check mode: the line is read and checked, its motion goes
        // nowhere.
        let mut t = Translate::grbl(io, extras);
        t.dry = true;
        if jog {
            jog_line(session, trimmed.get(3..).unwrap_or(b""), &mut t);
        } else {
            session.handle_line(text, &mut t);
        }
        t.answer();
        return false;
    }
    let mut t = Translate::grbl(io, extras);
    if trimmed.first() == Some(&b'$') {
        t.outcome = Some(Ok(()));
        match (upper(1), trimmed.len()) {
            (None, _) => {
                t.line(b"[HLP:$$ $# $G $I $N $x=val $J=line $C $X $H $PENDANT ~ ! ? ctrl-x]")
            }
            (Some(b'$'), 2) => settings(session, front, &mut t),
            (Some(b'C'), 2) if front.check => {
                // As grbl: check mode ends with a reset (the banner).
                front.check = false;
                session.check_end();
                t.line(b"[MSG:Disabled]");
                realtime(front, session, GrblRealtime::Common(Realtime::Reset), io);
                return false;
            }
            (Some(b'C'), 2) => {
                if session.check_begin(&mut t) {
                    front.check = true;
                    t.line(b"[MSG:Enabled]");
                } else {
                    t.outcome = Some(Err(8));
                    t.message.push_bytes(b"$C only at rest with nothing queued");
                }
            }
            (Some(b'#'), 2) => offsets(session, &mut t),
            (Some(b'G'), 2) => modes(session, &mut t),
            (Some(b'I'), 2) => {
                let mut l = ReplyLine::new();
                let _ = write!(l, "[VER:1.1h.{VERSION}:lathe-retrofit]");
                t.inner.send(finish(&mut l));
                let mut l = ReplyLine::new();
                let _ = write!(l, "[OPT:VNM,{BLOCKS},{RX_BUFFER}]");
                t.inner.send(finish(&mut l));
                t.line(b"[NEWOPT:LATHE]");
                t.line(b"[FIRMWARE:lathe-retrofit]");
            }
            (Some(b'N'), 2) => {
                t.line(b"$N0=");
                t.line(b"$N1=");
            }
            (Some(b'X'), 2) => {
                front.alarm = None;
                t.line(b"[MSG:Caution: Unlocked]");
            }
            (Some(b'H'), 2) => {
                t.outcome = Some(Err(5));
                t.message
                    .push_bytes(b"no homing cycle: these lathes have no home switches");
            }
            (Some(b'J'), _) if upper(2) == Some(b'=') => {
                if let Some(a) = front.alarm {
                    t.outcome = Some(Err(9));
                    let _ = write!(t.message, "alarm {a}: $X to unlock");
                } else if jog_line(session, trimmed.get(3..).unwrap_or(b""), &mut t) {
                    front.jogging = true;
                }
            }
            _ if trimmed.eq_ignore_ascii_case(b"$PENDANT") => {
                t.answer();
                front.on = false;
                return true;
            }
            _ => match trimmed.iter().position(|&b| b == b'=') {
                Some(eq)
                    if trimmed
                        .get(1..eq)
                        .is_some_and(|n| !n.is_empty() && n.iter().all(u8::is_ascii_digit)) =>
                {
                    let n = trimmed.get(1..eq).unwrap_or(b"");
                    let v = trim(trimmed.get(eq + 1..).unwrap_or(b""));
                    set(session, front, n, v, &mut t);
                }
                _ => {
                    t.outcome = Some(Err(3));
                    t.message.push_bytes(b"not a $ command of this controller");
                }
            },
        }
    } else if trimmed.is_empty() {
        t.outcome = Some(Ok(()));
    } else if let Some(a) = front.alarm {
        t.outcome = Some(Err(9));
        let _ = write!(t.message, "alarm {a}: $X to unlock");
    } else {
        front.jogging = false;
        session.handle_line(text, &mut t);
    }
    t.answer();
    false
}

fn trim(text: &[u8]) -> &[u8] {
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    let end = text
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(start, |e| e + 1);
    text.get(start..end).unwrap_or(&[])
}

/// An override stepped by its byte, as 0x90–0x94 step the feed's: 100 %,
/// +10, −10, +1, −1, within 10 … 200 %.
const fn stepped(percent: u8, byte: u8) -> u8 {
    let p = percent as i16;
    let next = match byte {
        0x90 => 100,
        0x91 => p + 10,
        0x92 => p - 10,
        0x93 => p + 1,
        _ => p - 1,
    };
    (if next < 10 {
        10
    } else if next > 200 {
        200
    } else {
        next
    }) as u8
}

/// Acts on a grbl real-time character.
pub fn realtime<I: Io + ?Sized>(
    front: &mut Front,
    session: &mut Session,
    rt: GrblRealtime,
    io: &mut I,
) {
    let extras = Extras::of(session, front);
    let mut t = Translate::grbl(io, extras);
    match rt {
        GrblRealtime::Common(Realtime::Status) => session.realtime(Realtime::Status, &mut t),
        GrblRealtime::Common(Realtime::Reset) => {
            t.statuses = false;
            session.realtime(Realtime::Reset, &mut t);
            // Motion answered `ok` and not all run (in motion, braking,
            // held with more to do, or queued) was dropped: the sender
            // hears it as an alarm, never as silence.
            let moving = session.reset_dropped_motion();
            front.jogging = false;
            front.cancel = false;
            (front.feed, front.rapid, front.spindle) = (100, 100, 100);
            session.set_feed_override(100);
            session.set_rapid_override(100);
            session.set_spindle_override(100, &mut t);
            if moving || t.reset == Some(true) {
                // Stopped at once in motion: a drive may have lost steps.
                front.alarm = Some(3);
                t.line(b"ALARM:3");
            }
            t.inner.send(BANNER);
            if front.alarm.is_some() {
                t.line(b"[MSG:'$H'|'$X' to unlock]");
            }
        }
        GrblRealtime::Common(rt) => {
            t.statuses = false;
            session.realtime(rt, &mut t);
        }
        GrblRealtime::JogCancel => {
            if front.jogging {
                t.statuses = false;
                session.realtime(Realtime::Hold, &mut t);
                front.cancel = true;
            }
        }
        GrblRealtime::Feed(_) => {
            [front.feed, _, _] = rt.overrides([front.feed, front.rapid, front.spindle]);
            session.set_feed_override(front.feed);
        }
        GrblRealtime::Rapid(_) => {
            [_, front.rapid, _] = rt.overrides([front.feed, front.rapid, front.spindle]);
            session.set_rapid_override(front.rapid);
        }
        GrblRealtime::Spindle(_) => {
            [_, _, front.spindle] = rt.overrides([front.feed, front.rapid, front.spindle]);
            session.set_spindle_override(front.spindle, &mut t);
        }
        GrblRealtime::Unsupported(_) => {
            t.line(b"[MSG:spindle stop and coolant toggles are not implemented]")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// X 10 mm on the diameter (1000 impulses of 0.005 mm on the radius),
    /// Z −5 mm (−500 of 0.01 mm), at `speed` (10⁻⁴ mm/min).
    fn record(motion: crate::stepper::Motion, speed: i64) -> StatusRecord {
        use crate::interleave::ImpulsePoint;
        StatusRecord {
            motion,
            issued: ImpulsePoint {
                x: crate::impulse::Impulses(1000),
                z: crate::impulse::Impulses(-500),
            },
            queued: 3,
            view: StatusView {
                hx: 50_000,
                hz: 100_000,
                diam: true,
                speed,
                starved: 0,
                stop: None,
                outputs: crate::outputs::Outputs {
                    spindle: crate::gcode::Spindle::Cw,
                    rpm: 800_000,
                    top: 0,
                    coolant: crate::gcode::Coolant::Off,
                },
            },
        }
    }

    #[test]
    fn a_status_record_becomes_a_report() {
        let extras = Extras {
            wco: [5_000_000, -1_200_000_000],
            diameter: true,
            overrides: [100; 3],
            jogging: false,
            alarm: None,
            check: false,
            mpos: true,
        };
        let r = status_report(&record(crate::stepper::Motion::Run, 2_000_000), &extras);
        assert_eq!(
            r.as_bytes(),
            b"<Run|MPos:10.0000,0.0000,-5.0000|FS:200.0000,800.000|WCO:1.0000,0.0000,-120.0000|Ov:100,100,100|D:1>"
        );
        // The pendant's line says the same.
        let line = crate::protocol::status_line(
            "!STATUS",
            &record(crate::stepper::Motion::Run, 2_000_000),
        );
        assert_eq!(
            line.as_bytes(),
            b"!STATUS STATE=RUN PX=1000 PZ=-500 X=10.0000 Z=-5.0000 V=200.0000 Q=3 STARVED=0 SPINDLE=CW S=800.000 COOLANT=OFF"
        );
        // Braking still moves; held is at rest whatever the last speed.
        let braking = status_report(&record(crate::stepper::Motion::Braking, 5), &extras);
        assert!(braking.as_bytes().starts_with(b"<Hold:1|"));
        let held = status_report(&record(crate::stepper::Motion::Held, 5), &extras);
        assert!(held.as_bytes().starts_with(b"<Hold:0|"));
    }

    #[test]
    fn a_work_position_is_the_machine_position_less_the_offset() {
        let extras = Extras {
            wco: [5_000_000, -1_200_000_000],
            diameter: true,
            overrides: [100; 3],
            jogging: false,
            alarm: None,
            check: false,
            mpos: false,
        };
        let idle = record(crate::stepper::Motion::Idle, 0);
        let r = status_report(&idle, &extras);
        // X 10 on the diameter less 2·0.5 mm; Z −5 less −120.
        assert!(
            r.as_bytes()
                .starts_with(b"<Idle|WPos:9.0000,0.0000,115.0000|"),
            "{:?}",
            core::str::from_utf8(r.as_bytes())
        );
        let check = Extras {
            check: true,
            ..extras
        };
        assert!(status_report(&idle, &check)
            .as_bytes()
            .starts_with(b"<Check|"));
    }

    #[test]
    fn setting_values_are_read_as_grbl_writes_them() {
        assert_eq!(parse_setting(b"25", false), Some(25));
        assert_eq!(parse_setting(b"25.5", true), Some(25_500));
        assert_eq!(parse_setting(b".125", true), Some(125));
        assert_eq!(parse_setting(b"2.", true), Some(2_000));
        assert_eq!(parse_setting(b"2.5", false), None);
        assert_eq!(parse_setting(b"1.0001", true), None);
        assert_eq!(parse_setting(b"65536", false), None);
        assert_eq!(parse_setting(b"", false), None);
        assert_eq!(parse_setting(b"x", true), None);
    }

    #[test]
    fn refusals_map_to_grbl_codes_by_what_they_are() {
        struct Out(std::vec::Vec<u8>);
        impl Io for Out {
            fn send(&mut self, line: &[u8]) {
                self.0.extend_from_slice(line);
            }
        }
        extern crate std;
        let error = |line: &str| {
            let mut dev = crate::protocol::Device::new();
            let mut out = Out(std::vec::Vec::new());
            dev.set_grbl(true, &mut out);
            out.0.clear();
            dev.receive_bytes(line.as_bytes(), &mut out);
            let text = std::string::String::from_utf8(out.0).expect("text");
            text.lines()
                .find_map(|l| l.strip_prefix("error:"))
                .and_then(|n| n.parse::<u8>().ok())
        };
        // Undefined feed rate: a feed move under F0.
        assert_eq!(error("G01 X1 F0\n"), Some(22));
        // Invalid target: an arc whose radius cannot reach its end.
        assert_eq!(error("G02 X10 Z-10 R1\n"), Some(33));
        // Expected command letter: an address this control does not know.
        assert_eq!(error("G01 X1 Q3 F100\n"), Some(1));
        // Unsupported command: a G code it does not run, a word of the
        // other dialect (whose text names FANUC: not a feed's refusal).
        assert_eq!(error("G12 X1\n"), Some(20));
        assert_eq!(error("G01 U1 F100\n"), Some(20));
        assert_eq!(
            error_number(Refused {
                code: ErrorCode::Value,
                about: None
            }),
            20
        );
        assert_eq!(
            error_number(Refused {
                code: ErrorCode::Value,
                about: Some(b'F')
            }),
            22
        );
    }
}

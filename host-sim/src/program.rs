//! `host-sim run FILE`: a whole program through the in-process device in
//! virtual time, with what a person asks of it before cutting: the cycle
//! time, the travel, the tool changes, every block the device refused, and
//! on request the path as the device ran it.

use core_nostd::comp::{MoveKind, Origin};
use core_nostd::gcode::{is_block, parse, Dialect, FeedMode, Motion, SpindleMode, Units};
use core_nostd::interleave::{LinearBlock, StepEvent};
use core_nostd::interp::{path_feed, Modal, SpindleState};
use core_nostd::length::Length;
use core_nostd::protocol::{Device, Io};
use core_nostd::stepdir::DriveTiming;

/// How to run a program.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// The program's dialect.
    pub dialect: Dialect,
    /// X words are radii at the start (`G8`), not diameters.
    pub radius: bool,
    /// The optional stop switch: `M01` stops too.
    pub optional_stop: bool,
}

/// A line the device refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refused {
    /// Line, from 1.
    pub line: usize,
    /// The device's `ERR …` reply (without its checksum).
    pub reply: String,
}

/// What running a program came to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// For each of [`Report::refused`], its place in [`program_lines`]
    /// (from 0): which expanded block it was.
    pub refused_at: Vec<usize>,
    /// G-code lines the device ran.
    pub blocks: usize,
    /// The lines it refused.
    pub refused: Vec<Refused>,
    /// The setup requests it refused (line 0: the run's own settings).
    pub setup_refused: Vec<Refused>,
    /// Why the host could not expand the program's macros, subprograms or
    /// expressions (nothing ran then).
    pub expand_error: Option<crate::expand::ExpandError>,
    /// Time in motion, µs (the runs' ticks at the 1 MHz step clock).
    pub motion_us: u64,
    /// Time dwelling (`G04`), µs.
    pub dwell_us: u64,
    /// Step events issued.
    pub events: u64,
    /// Path length at feed and at the rapid rate, mm (X on the radius).
    pub feed_mm: f64,
    /// See `feed_mm`.
    pub rapid_mm: f64,
    /// Each tool change: the line and the `T` word as written.
    pub tools: Vec<(usize, String)>,
    /// Each canned cycle run, in order.
    pub cycles: Vec<CycleRun>,
    /// Each program stop, where cycle start was pressed: the line and
    /// `M00` or `M01`.
    pub stops: Vec<(usize, String)>,
    /// Every motion block the device ran, as G-code in machine coordinates
    /// (X a diameter, I/K radius values from the block's start).
    pub trace: Vec<String>,
    /// The same blocks exactly: the end point and, for an arc, the centre
    /// (X on the radius, ångström), with the G code.
    pub path: Vec<Traced>,
}

/// A canned cycle the device ran: its block, its moves in
/// [`Report::path`], and how long they took.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CycleRun {
    /// The line of its cycle block (`G71 P… Q…`, `G70`, `G90 X… Z…`, or
    /// the block repeating a single cycle), from 1.
    pub line: usize,
    /// What it does: `roughing` (`G71`, `G72`, `G73`), `finishing`
    /// (`G70`), `grooving` (`G74`, `G75`), `single` (`G90`, `G94`).
    pub kind: &'static str,
    /// Its moves: a range of [`Report::path`].
    pub moves: std::ops::Range<usize>,
    /// From the start of its first move to the end of its last (its last
    /// step event, or the axes at rest when its run ends with it), dwells
    /// between included, µs; `None` when the step events could not be
    /// matched to the moves.
    pub us: Option<u64>,
}

impl CycleRun {
    /// What a cycle block starts, by its words: the kind of
    /// [`CycleRun::kind`].
    fn kind_of(b: &core_nostd::gcode::Block) -> Option<&'static str> {
        use core_nostd::gcode::CycleKind;
        if b.single.is_some() {
            return Some("single");
        }
        b.cycle.map(|c| match c.kind {
            CycleKind::Finish => "finishing",
            CycleKind::PeckFace | CycleKind::PeckGroove => "grooving",
            _ => "roughing",
        })
    }
}

/// One motion block the device ran, exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Traced {
    /// 0 to 3: `G00` … `G03`.
    pub g: u8,
    /// The end point, X on the radius, Å.
    pub to: [i64; 2],
    /// An arc's centre, Å.
    pub centre: Option<[i64; 2]>,
    /// The line of the file its programmed block is on, from 1.
    pub line: usize,
    /// Its programmed block's place in [`program_lines`], from 0.
    pub seq: usize,
}

impl Report {
    /// The cycle time, µs.
    pub const fn cycle_us(&self) -> u64 {
        self.motion_us + self.dwell_us
    }
}

/// What the device did in time, in the order it did it (kept by
/// [`run_timed`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Happening {
    /// A linear block started (a line, or one chord of an arc); its step
    /// events follow.
    Block(LinearBlock),
    /// A step event: its byte (bit0 X steps, bit1 Z steps, bit2 X
    /// negative, bit3 Z negative) and its tick since its run began.
    Event {
        /// The event's byte.
        bits: u8,
        /// Ticks of the 1 MHz step clock since the run began.
        tick: u64,
    },
    /// The run ended this many ticks after it began, the axes at rest.
    RunEnd(u64),
    /// A dwell of this many µs, the axes at rest (`G04`, or the spindle
    /// getting up to speed).
    Dwell(u64),
}

/// A program's motion in time, beside its [`Report`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timeline {
    /// Everything the device did in time, in order.
    pub happenings: Vec<Happening>,
    /// The commanded feed of each block of [`Report::path`], mm/min along
    /// the path: `F` per minute, or `F` times the spindle's rpm under
    /// `G97`; `None` for a rapid, and under `G96`, where the rpm follows X.
    pub feeds: Vec<Option<f64>>,
    /// The impulse prices (ångström): X on the radius, Z.
    pub price: [i64; 2],
}

/// Sums what the device reports through its transport.
#[derive(Default)]
struct Tally {
    out: Vec<u8>,
    run_ticks: u64,
    dwell_us: u64,
    events: u64,
    stops: Vec<u16>,
    /// Kept when asked for.
    timeline: Option<Vec<Happening>>,
    /// The lathe the events move (`run --machine`).
    watch: Option<Watch>,
    /// The line whose request is being sent, and where the event of
    /// [`Tally::find`] fell.
    line: usize,
    /// Counting the events to this one, the line whose request issued it.
    find: Option<(u64, Option<usize>)>,
    /// Time of the runs ended and the dwells so far, µs.
    clock: u64,
    /// Each linear block run: its end in impulses (X on the radius, Z),
    /// when it started and when it ended (its last step event, or its
    /// run's end), µs from the start.
    ends: Vec<([i64; 2], u64, u64)>,
}

/// A machine file's lathe following the events of a run.
struct Watch {
    lathe: crate::lathe::Lathe,
    /// The impulse prices, mm (X on the radius).
    price: [f64; 2],
    /// The inputs that stop the machine when they rise (its limits and
    /// drive faults).
    stops: u16,
    /// The first stop: the event's number (from 1), the inputs that rose
    /// (none: a carriage ran past the end of its travel), the carriages.
    trip: Option<(u64, u16, [f64; 2])>,
    /// The first speed asked above the spindle's top: the line, rpm, the
    /// top.
    over_top: Option<(usize, f64, f64)>,
}

impl Watch {
    fn step(&mut self, n: u64, event: StepEvent, tick: u64) {
        if self.trip.is_some() {
            // The machine stopped there.
            return;
        }
        let (x, z) = event.moves();
        let steps = [i32::from(x), i32::from(z)];
        let before = self.lathe.active();
        let now = self.lathe.event(steps, tick, self.price);
        let rose = now & !before & self.stops;
        let c = self.lathe.carriage();
        let file = self.lathe.file();
        let beyond = [&file.x, &file.z].iter().zip(c).any(|(axis, c)| {
            axis.travel
                .is_some_and(|[lo, hi]| c < lo - 1e-9 || c > hi + 1e-9)
        });
        if rose != 0 || beyond {
            self.trip = Some((n, rose, c));
        }
    }
}

impl Tally {
    fn keep(&mut self, h: Happening) {
        if let Some(t) = self.timeline.as_mut() {
            t.push(h);
        }
    }
}

impl Io for Tally {
    fn send(&mut self, line: &[u8]) {
        self.out.extend_from_slice(line);
    }
    fn block_start(&mut self, block: &LinearBlock) {
        let t = block.to();
        // From rest, when its run starts; else when the block before
        // issued its last event.
        let at = self.ends.last().map_or(self.clock, |e| e.2.max(self.clock));
        self.ends
            .push(([i64::from(t.x.0), i64::from(t.z.0)], at, at));
        self.keep(Happening::Block(*block));
    }
    fn run_start(&mut self) {
        if let Some(w) = self.watch.as_mut() {
            w.lathe.run_start();
        }
    }
    fn outputs(&mut self, outputs: &core_nostd::outputs::Outputs) {
        let Some(w) = self.watch.as_mut() else {
            return;
        };
        let top = w.lathe.file().spindle.as_ref().and_then(|s| s.max_rpm);
        let rpm = f64::from(outputs.rpm) / 1000.0;
        let on = outputs.spindle != core_nostd::gcode::Spindle::Off;
        if let Some(top) = top.filter(|&top| on && rpm > top) {
            w.over_top = w.over_top.or(Some((self.line, rpm, top)));
        }
    }
    fn step(&mut self, event: StepEvent, tick: u64, _: &DriveTiming) {
        self.events += 1;
        if let Some(e) = self.ends.last_mut() {
            e.2 = self.clock + tick;
        }
        if let Some(w) = self.watch.as_mut() {
            w.step(self.events, event, tick);
        }
        if let Some((n, found @ None)) = self.find.as_mut() {
            if *n == self.events {
                *found = Some(self.line);
            }
        }
        self.keep(Happening::Event {
            bits: event.bits(),
            tick,
        });
    }
    fn run_end(&mut self, ticks: u64) {
        self.run_ticks += ticks;
        // The run's last block ends with it, at rest.
        if let Some(e) = self.ends.last_mut() {
            e.2 = e.2.max(self.clock + ticks);
        }
        self.clock += ticks;
        self.keep(Happening::RunEnd(ticks));
    }
    fn dwell(&mut self, us: u64) {
        self.dwell_us += us;
        self.clock += us;
        self.keep(Happening::Dwell(us));
    }
    fn program_stop(&mut self, code: u16) {
        // Cycle start, pressed at once.
        self.stops.push(code);
    }
}

/// The moves of a request's `DATA G0n X Z [I K]` lines (X a diameter
/// when `diam`), in ångström, from `at`.
pub fn data_moves(out: &[u8], diam: bool, mut at: [i64; 2]) -> Vec<core_nostd::comp::Move> {
    let text = String::from_utf8_lossy(out);
    let mut moves = Vec::new();
    for line in text.split("\r\n") {
        let Some(rest) = line.strip_prefix("DATA G0") else {
            continue;
        };
        let body = rest.rsplit_once('*').map_or(rest, |(b, _)| b);
        let mut words = body.split(' ');
        let g: u8 = words.next().and_then(|w| w.parse().ok()).unwrap_or(0);
        let (mut x, mut z, mut i, mut k) = (None, None, None, None);
        let a = |v: &str| Length::from_mm_str(v).ok().map(Length::as_angstrom);
        for w in words {
            match w.split_at_checked(1) {
                Some(("X", v)) => x = a(v).map(|v| if diam { v / 2 } else { v }),
                Some(("Z", v)) => z = a(v),
                Some(("I", v)) => i = a(v),
                Some(("K", v)) => k = a(v),
                _ => {}
            }
        }
        let to = [x.unwrap_or(at[0]), z.unwrap_or(at[1])];
        let kind = match g {
            0 | 1 => MoveKind::Line { rapid: g == 0 },
            _ => MoveKind::Arc {
                centre: [at[0] + i.unwrap_or(0), at[1] + k.unwrap_or(0)],
                dir: if g == 3 {
                    core_nostd::arc::ArcDir::Ccw
                } else {
                    core_nostd::arc::ArcDir::Cw
                },
            },
        };
        moves.push(core_nostd::comp::Move {
            to,
            kind,
            origin: Origin::Current,
        });
        at = to;
    }
    moves
}

/// Sends one request; the final reply line without its checksum.
fn request(dev: &mut Device, io: &mut Tally, line: &str) -> String {
    io.out.clear();
    dev.receive_bytes(line.as_bytes(), io);
    dev.receive_bytes(b"\n", io);
    let text = String::from_utf8_lossy(&io.out);
    let last = text.lines().last().unwrap_or("");
    last.rsplit_once('*').map_or(last, |(b, _)| b).to_string()
}

/// Ångström as mm with 4 decimals, half away from zero.
fn mm4(a: i64) -> String {
    let q = (a.unsigned_abs() + 500) / 1000;
    let sign = if a < 0 && q != 0 { "-" } else { "" };
    format!("{sign}{}.{:04}", q / 10_000, q % 10_000)
}

/// Runs a program's text.
pub fn run(text: &str, options: Options) -> Report {
    run_with(text, options, &[])
}

/// Runs a program's text after `setup` requests (`CFG RN=0.8 TIP=2`).
pub fn run_with(text: &str, options: Options, setup: &[&str]) -> Report {
    let setup: Vec<(usize, &str)> = setup.iter().map(|l| (0, *l)).collect();
    run_setup(text, options, &setup)
}

/// A setup file's requests (`TOOL N=1 X=… R=0.4 T=3`, `WORK G=54 Z=…`):
/// one per line, with its line number; blank lines and `#` comments
/// skipped.
pub fn setup_lines(text: &str) -> Vec<(usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty())
        .collect()
}

/// The lines the device is sent, each with its line index in the file
/// (from 0): the file's own lines, or its macros, subprograms and
/// parameters expanded when it has any; each as [`device_text`] makes it;
/// the tape's leader and trailer left out ([`framing`]). `run`, `check`, `plot`, `send` and `tape` all read a program through
/// here, so they read every line one way.
///
/// # Errors
/// Why the program cannot be expanded.
pub fn program_lines(
    text: &str,
    dialect: Dialect,
) -> Result<Vec<(usize, String)>, crate::expand::ExpandError> {
    let framed = framing(text).apply(text);
    let text = framed.as_str();
    let lines: Vec<(usize, String)> = if crate::expand::needs_expansion(text) {
        crate::expand::expand(text, dialect)?
            .into_iter()
            .map(|l| (l.source - 1, l.text))
            .collect()
    } else {
        text.lines().map(str::to_owned).enumerate().collect()
    };
    Ok(lines
        .into_iter()
        .map(|(i, l)| (i, device_text(&l)))
        .collect())
}

/// What a file holds around its program as a punched tape or a DNC link
/// carries it, outside what is read (`docs/protocol.md` §5): the
/// leader before the first `%`, the trailer after the closing one.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Framing {
    /// The line (index from 0) whose text before its `%` is the tape's
    /// leader, and that text as [`control_names`] shows it.
    pub leader: Option<(usize, String)>,
    /// Lines before the first `%` line holding nothing but control
    /// characters (a reader's DC2 on a line of its own): the first and the
    /// last (indices from 0), and their characters as [`control_names`]
    /// shows them.
    pub leading: Option<(usize, usize, String)>,
    /// The closing `%`'s line when control characters follow it there,
    /// and those as [`control_names`] shows them.
    pub tail: Option<(usize, String)>,
    /// The first and last line (indices from 0) after the closing `%`
    /// that are not blank.
    pub trailer: Option<(usize, usize)>,
}

impl Framing {
    /// The text with the leader and the trailer left out, line for line
    /// (the leader's and the tail's line are `%`, the trailer's lines are
    /// empty), so every line keeps its number.
    pub fn apply(&self, text: &str) -> String {
        if *self == Framing::default() {
            return text.to_string();
        }
        let at = |m: &Option<(usize, String)>, i: usize| m.as_ref().is_some_and(|(l, _)| *l == i);
        let mut out = String::with_capacity(text.len());
        for (i, line) in text.lines().enumerate() {
            let leading = self
                .leading
                .as_ref()
                .is_some_and(|(a, b, _)| (*a..=*b).contains(&i));
            if at(&self.leader, i) || at(&self.tail, i) {
                out.push('%');
            } else if !leading && !self.trailer.is_some_and(|(a, b)| (a..=b).contains(&i)) {
                out.push_str(line);
            }
            out.push('\n');
        }
        out
    }

    /// What `check` and `run` say of it, each with its line (from 1).
    pub fn notes(&self) -> Vec<(usize, String)> {
        let mut out = Vec::new();
        if let Some((l, _, what)) = &self.leading {
            out.push((
                l + 1,
                format!("the tape's leader before % is not read: {what}"),
            ));
        }
        if let Some((l, what)) = &self.leader {
            out.push((
                l + 1,
                format!("the tape's leader before % is not read: {what}"),
            ));
        }
        if let Some((l, what)) = &self.tail {
            out.push((
                l + 1,
                format!("the tape's trailer after % is not read: {what}"),
            ));
        }
        if let Some((a, b)) = self.trailer {
            let lines = if a == b {
                format!("line {} after it is", a + 1)
            } else {
                format!("lines {} to {} after it are", a + 1, b + 1)
            };
            out.push((
                a + 1,
                format!("the program ends at its closing %: {lines} not read"),
            ));
        }
        out
    }
}

/// A file's [`Framing`]. A line is a tape mark when it holds a `%` with
/// only blanks before it and only blanks and control characters after it.
/// The leader: on the file's first line that is not blank, text before a
/// `%` that holds a control character (a reader's DC1–DC4, a printer's ESC
/// sequence, NUL or DEL feed holes); printable text alone is not taken for
/// one (it is refused as the line it is). The trailer: when the file has an
/// opening and a closing mark, the control characters after the closing
/// `%` and every line after it that is not blank, as LinuxCNC and a Fanuc
/// reading a tape both stop at the closing `%`.
pub fn framing(text: &str) -> Framing {
    let lines: Vec<&str> = text.lines().collect();
    let mut f = Framing::default();
    let blank = |l: &str| l.trim_matches([' ', '\t', '\r']).is_empty();
    let control_only = |t: &str| t.chars().all(|c| c == ' ' || c.is_control());
    let first = lines.iter().position(|l| !blank(l));
    if let Some(first) = first {
        if let Some((before, after)) = lines[first].split_once('%') {
            if before.chars().any(|c| c.is_control() && c != '\t') && control_only(after) {
                f.leader = Some((first, control_names(before)));
            }
        }
    }
    // Lines of control characters alone before the first `%` line.
    let percent = |l: &str| {
        l.trim_start_matches([' ', '\t'])
            .strip_prefix('%')
            .is_some_and(control_only)
    };
    if let (Some(first), Some(p)) = (first, lines.iter().position(|l| percent(l))) {
        let before: Vec<usize> = (first..p).filter(|&i| !blank(lines[i])).collect();
        let controls = |l: &str| l.chars().any(|c| c.is_control() && c != '\t' && c != '\r');
        if let (Some(&a), Some(&b)) = (before.first(), before.last()) {
            if before
                .iter()
                .all(|&i| control_only(lines[i]) && controls(lines[i]))
            {
                let names: Vec<String> = before
                    .iter()
                    .map(|&i| control_names(lines[i].trim_matches([' ', '\t', '\r'])))
                    .collect();
                f.leading = Some((a, b, names.join(" ")));
            }
        }
    }
    let mark = |i: usize| {
        f.leader.as_ref().is_some_and(|(l, _)| *l == i)
            || lines[i]
                .trim_start_matches([' ', '\t'])
                .strip_prefix('%')
                .is_some_and(control_only)
    };
    let marks: Vec<usize> = (0..lines.len()).filter(|&i| mark(i)).collect();
    if let [_, .., last] = marks[..] {
        let after = lines[last]
            .trim_start_matches([' ', '\t'])
            .strip_prefix('%')
            .unwrap_or("");
        if after
            .chars()
            .any(|c| c.is_control() && c != '\t' && c != '\r')
        {
            f.tail = Some((
                last,
                control_names(after.trim_end_matches(['\r', ' ', '\t'])),
            ));
        }
        let rest: Vec<usize> = (last + 1..lines.len())
            .filter(|&i| !blank(lines[i]))
            .collect();
        if let (Some(&a), Some(&b)) = (rest.first(), rest.last()) {
            f.trailer = Some((a, b));
        }
    }
    f
}

/// Text with its control characters named (`DC2`, `ESC`, `0x1c`), the
/// rest as it is.
pub fn control_names(text: &str) -> String {
    const NAMES: [&str; 32] = [
        "NUL", "SOH", "STX", "ETX", "EOT", "ENQ", "ACK", "BEL", "BS", "HT", "LF", "VT", "FF", "CR",
        "SO", "SI", "DLE", "DC1", "DC2", "DC3", "DC4", "NAK", "SYN", "ETB", "CAN", "EM", "SUB",
        "ESC", "FS", "GS", "RS", "US",
    ];
    let mut out = String::new();
    for c in text.chars() {
        let name = match c {
            '\u{7f}' => Some("DEL"),
            c if (c as u32) < 32 => NAMES.get(c as usize).copied(),
            _ => None,
        };
        match name {
            Some(n) => {
                if !out.is_empty() && !out.ends_with(' ') {
                    out.push(' ');
                }
                out.push_str(n);
                out.push(' ');
            }
            None => out.push(c),
        }
    }
    out.trim_end().to_string()
}

/// A program line as it goes over the link: the CR of a CRLF file gone;
/// inside comments (`( … )`, `;` to the end) every character the link does
/// not carry as text (outside printable ASCII: a UTF-8 letter, a tape
/// control character, and the bytes 0x80–0x82 the link reserves for its
/// real-time commands) replaced by `?`; and when the line would still be
/// longer than the device's 120 bytes, its comments left out. Comments are
/// never read, so nothing the device does changes; outside them the text
/// is sent as written (and refused there if it is not G-code).
pub fn device_text(raw: &str) -> String {
    let line = raw.strip_suffix('\r').unwrap_or(raw);
    let mut out = String::with_capacity(line.len());
    let mut words = String::with_capacity(line.len());
    let (mut paren, mut rest) = (false, false);
    for c in line.chars() {
        let comment = rest || paren || c == '(' || c == ';';
        if comment {
            out.push(if c == '\t' || (' '..='~').contains(&c) {
                c
            } else {
                '?'
            });
        } else {
            out.push(c);
            words.push(c);
        }
        if rest {
            continue;
        }
        if paren {
            paren = c != ')';
        } else if c == '(' {
            paren = true;
        } else if c == ';' {
            rest = true;
        }
    }
    if out.len() > core_nostd::protocol::framing::MAX_LINE {
        words.trim_end().to_string()
    } else {
        out
    }
}

/// The run's own settings, before any setup file: the dialect, diameters
/// or radii, the optional stop switch.
pub fn run_settings(options: Options) -> [String; 3] {
    [
        format!("OPT DIALECT={}", options.dialect.as_str()),
        format!("CFG DIAM={}", u8::from(!options.radius)),
        format!("OPT OPTSTOP={}", u8::from(options.optional_stop)),
    ]
}

/// Runs a program's text after setup requests, each with the line of the
/// file it comes from ([`Report::setup_refused`]).
pub fn run_setup(text: &str, options: Options, setup: &[(usize, &str)]) -> Report {
    run_inner(text, options, setup, false, None, None).0
}

/// What [`run_inner`] comes to: the report, the timeline, the machine's
/// run, and the line of the event `find` asked for.
type Inner = (Report, Timeline, Option<MachineRun>, Option<usize>);

/// What the lathe of a machine file met in a run (`run --machine`).
#[derive(Clone, Debug, PartialEq)]
pub struct MachineRun {
    /// What stopped the machine, if anything did.
    pub trip: Option<Trip>,
    /// The least and most each carriage was at, mm (X on the radius):
    /// `[[x_min, x_max], [z_min, z_max]]`.
    pub range: [[f64; 2]; 2],
    /// Where the carriages ended, mm (X on the radius), the leadscrews'
    /// play in it.
    pub carriage: [f64; 2],
    /// Where the registers say they are, mm (X on the radius).
    pub registers: [f64; 2],
    /// The first spindle speed commanded above the spindle's top
    /// (`max_rpm`): the line, the speed and the top, rpm. (Under `G96` the speed
    /// changes at block starts, which are not seen here.)
    pub over_top: Option<(usize, f64, f64)>,
}

/// A switch or a drive that stopped the machine, or the end of a travel
/// a carriage ran into.
#[derive(Clone, Debug, PartialEq)]
pub struct Trip {
    /// The inputs that rose ([`core_nostd::inputs::Input::bit`]); none
    /// when a carriage ran past the end of its travel.
    pub inputs: u16,
    /// Where the carriages were, mm (X on the radius).
    pub carriage: [f64; 2],
    /// The step event it came at, from 1 (0: at the start, before any).
    pub event: u64,
    /// The line whose block was moving (its request, sent one at a time).
    pub line: Option<usize>,
    /// What the device said when the input reached it (`ERR ALARM …`),
    /// or nothing, for the end of a travel (no switch there).
    pub alarm: String,
    /// The program's lines not sent after it.
    pub lines_left: usize,
}

/// As [`run_setup`], the lathe of `machine` behind the board: the inputs
/// its switches and drives are wired to (`INPUT USED=`), its carriages
/// moved by the events and tripping the switches from their own
/// positions. A limit or a drive's fault that rises stops the program
/// there as on the machine (the device's alarm, no more lines sent), as
/// does a carriage running past the end of its travel; the line it came
/// in is found by running the program again one line at a time (a `SYNC`
/// after each: the same events, so the same one).
pub fn run_machine(
    text: &str,
    options: Options,
    setup: &[(usize, &str)],
    machine: &crate::lathe::MachineFile,
) -> (Report, MachineRun) {
    let (report, _, run, _) = run_inner(text, options, setup, false, Some(machine), None);
    let mut run = run.unwrap_or(MachineRun {
        // Nothing ran (the program could not be expanded).
        trip: None,
        range: [[0.0; 2]; 2],
        carriage: [0.0; 2],
        registers: [0.0; 2],
        over_top: None,
    });
    if let Some(trip) = run.trip.as_mut() {
        if trip.event > 0 {
            // Without the lathe: the same events, nothing stopping them
            // (a drive's stall depends on their times, which differ).
            trip.line = run_inner(text, options, setup, false, None, Some(trip.event)).3;
        }
    }
    (report, run)
}

/// The inputs a machine file's switches and drives are wired to, as
/// `INPUT USED=` names them, and those of them that stop the machine.
pub fn machine_inputs(machine: &crate::lathe::MachineFile) -> (String, u16) {
    use core_nostd::inputs::{Input, ALL, FAULTS, LIMITS};
    let mut bits = 0u16;
    for (axis, fault) in [(&machine.x, Input::FaultX), (&machine.z, Input::FaultZ)] {
        for s in &axis.switches {
            if let Some(i) = Input::from_name(&s.input) {
                bits |= i.bit();
            }
        }
        if axis.drive.max_rate.is_some() {
            bits |= fault.bit();
        }
    }
    let names: Vec<&str> = ALL
        .iter()
        .filter(|i| bits & i.bit() != 0)
        .map(|i| i.name())
        .collect();
    let used = if names.is_empty() {
        "-".to_string()
    } else {
        names.join(",")
    };
    (used, bits & (LIMITS | FAULTS))
}

/// As [`run_setup`], keeping what the device did in time: every block
/// started, step event with its tick, run end and dwell, and the commanded
/// feed of every block run. The report is the same.
pub fn run_timed(text: &str, options: Options, setup: &[(usize, &str)]) -> (Report, Timeline) {
    let (r, t, _, _) = run_inner(text, options, setup, true, None, None);
    (r, t)
}

/// The commanded feed along the path, mm/min, as the device reads it
/// (`None` under `G96`, or where it has none).
fn commanded_feed(modal: &Modal, spindle: &SpindleState) -> Option<f64> {
    if modal.feed_mode == FeedMode::PerRev && spindle.mode == SpindleMode::Surface {
        return None;
    }
    let feed = path_feed(modal, spindle, Length::ZERO).ok()??;
    Some(feed.mm_per_min().as_angstrom() as f64 / 1e7)
}

/// The run: with `machine`, its lathe behind the board; with `find`, one
/// line at a time (a `SYNC` after each) until the event of that number,
/// whose line the machine run's trip then names.
fn run_inner(
    text: &str,
    options: Options,
    setup: &[(usize, &str)],
    timed: bool,
    machine: Option<&crate::lathe::MachineFile>,
    find: Option<u64>,
) -> Inner {
    let mut dev = Device::new();
    // Nothing here reads a probe: a probing block is the feed move to its
    // end (`check` warns of it).
    dev.set_probe_as_feed(true);
    let mut io = Tally {
        timeline: timed.then(Vec::new),
        ..Tally::default()
    };
    let mut report = Report::default();
    let mut timeline = Timeline::default();
    let mut settings = run_settings(options).to_vec();
    let wiring = machine.map(machine_inputs);
    if let Some((used, _)) = &wiring {
        settings.push(format!("INPUT USED={used}"));
    }
    io.find = find.map(|n| (n, None));
    for (line, setting) in settings
        .iter()
        .map(|s| (0, s.as_str()))
        .chain(setup.iter().copied())
    {
        let reply = request(&mut dev, &mut io, setting);
        if !reply.starts_with("OK") {
            report.setup_refused.push(Refused { line, reply });
        }
    }
    let lines = match program_lines(text, options.dialect) {
        Ok(lines) => lines,
        Err(e) => {
            report.expand_error = Some(e);
            return (report, timeline, None, None);
        }
    };
    let cfg = *dev.session().config();
    timeline.price = [cfg.hx.as_angstrom(), cfg.hz.as_angstrom()];
    let price = timeline.price.map(|h| h as f64 / 1e7);
    let registers = |dev: &mut Device, io: &mut Tally| {
        let pos = request(dev, io, "POS");
        let n = |k| {
            crate::link::words_value(&pos, k)
                .and_then(|v| v.parse::<f64>().ok())
                .unwrap_or(0.0)
        };
        [n("PX") * price[0], n("PZ") * price[1]]
    };
    let mut alarm = String::new();
    if let (Some(m), Some((_, stops))) = (machine, &wiring) {
        let mut lathe = crate::lathe::Lathe::new(m.clone());
        let at = registers(&mut dev, &mut io);
        let active = lathe.moved(at);
        io.watch = Some(Watch {
            lathe,
            price,
            stops: *stops,
            trip: (active & stops != 0).then_some((0, active & stops, at)),
            over_top: None,
        });
    }
    // A trip reaches the device (its alarm) once; nothing more is sent.
    let mut deliver = |dev: &mut Device, io: &mut Tally| -> bool {
        let Some(w) = io.watch.as_ref() else {
            return false;
        };
        let Some((_, inputs, _)) = w.trip else {
            return false;
        };
        if alarm.is_empty() {
            let active = w.lathe.active();
            io.out.clear();
            if inputs != 0 {
                dev.inputs(active, io);
            }
            let text = String::from_utf8_lossy(&io.out).to_string();
            alarm = text
                .lines()
                .rev()
                .find(|l| !l.is_empty())
                .map(|l| l.rsplit_once('*').map_or(l, |(b, _)| b))
                .unwrap_or("")
                .to_string();
            if alarm.is_empty() {
                alarm.push(' ');
            }
        }
        true
    };
    let mut stopped_at = None;
    // The last cycle block (its line and kind), and whether a single cycle
    // is in force (a block of only X, Z repeats it).
    let (mut cycle_at, mut single) = (None, false);
    let mut units = Units::Mm;
    let mut tool = None;
    let mut at = [0i64; 2];
    // The last programmed motion block (line, place): a block sent one
    // block late belongs to it.
    let mut motion_block = (0, 0);
    // The modal feed and spindle as the device reads them, for the
    // commanded feed of each block (the device's own is not reported).
    let (mut modal, mut spindle) = (Modal::POWER_ON, SpindleState::POWER_ON);
    let mut feed_now = None;
    let mut element_feed = None;
    // The feed of a move waiting for its ,C/,R corner, and whether one
    // waits.
    let (mut round_feed, mut rounding) = (None, false);
    for (seq, (i, raw)) in lines.iter().enumerate() {
        if deliver(&mut dev, &mut io) || io.find.is_some_and(|(_, f)| f.is_some()) {
            stopped_at = Some(seq);
            break;
        }
        let mut element = false;
        let i = *i;
        io.line = i + 1;
        let line = raw.trim_end_matches('\r');
        if line.trim().is_empty() {
            continue;
        }
        let refuse = |reply: String| Refused { line: i + 1, reply };
        if !is_block(line) {
            report
                .refused
                .push(refuse("ERR SYNTAX not a G-code line".into()));
            report.refused_at.push(seq);
            continue;
        }
        // Whether this block may end a profile the device is reading (a
        // two-block cycle's roughing runs with it).
        let profile = dev.session().reading_profile();
        let reply = request(&mut dev, &mut io, line);
        if !reply.starts_with("OK") {
            report.refused_at.push(seq);
            report.refused.push(refuse(reply));
            continue;
        }
        report.blocks += 1;
        for code in io.stops.drain(..) {
            report.stops.push((i + 1, format!("M{code:02}")));
        }
        // What the device read: the tool word and the unit.
        let mut this_block = motion_block;
        let mut this_cycle = None;
        if let Ok(b) = parse(line, options.dialect, units) {
            let kind = CycleRun::kind_of(&b);
            if let Some(k) = kind {
                cycle_at = Some((i + 1, k));
                single = k == "single";
                this_cycle = cycle_at;
            } else if profile {
                this_cycle = cycle_at;
            } else if single && b.motion.is_none() && !b.cancel_cycle {
                if b.x.is_some() || b.z.is_some() {
                    this_cycle = Some((i + 1, "single"));
                }
            } else {
                single = false;
            }
            if b.x.is_some() || b.z.is_some() {
                this_block = (i + 1, seq);
            }
            units = b.units.unwrap_or(units);
            (modal, spindle) = (modal.after(&b), spindle.after(&b));
            feed_now = if modal.motion == Motion::Rapid {
                None
            } else {
                commanded_feed(&modal, &spindle)
            };
            element =
                (b.x.is_some() || b.z.is_some()) && b.special.is_none() && b.set_work.is_none();
            if let Some(t) = b.tool {
                if tool != Some(t.tool) {
                    tool = Some(t.tool);
                    let word = match t.offset {
                        Some(o) => format!("T{:02}{o:02}", t.tool),
                        None => format!("T{}", t.tool),
                    };
                    report.tools.push((i + 1, word));
                }
            }
        }
        if reply.contains("SKIP=BDEL") {
            continue;
        }
        // The blocks this request sent (none for a block without motion,
        // or one whose motion waits for the next block).
        let mut moves: Vec<core_nostd::comp::Move> =
            dev.session().last_moves().iter().copied().collect();
        // A request that ran many blocks (a turning cycle's roughing, a
        // G70's profile): its moves from its DATA lines, one per block.
        let data = data_moves(&io.out, !options.radius, at);
        let first = report.path.len();
        let many = data.len() != moves.len();
        if many {
            moves = data;
        }
        for m in &moves {
            let (line, seq) = match m.origin {
                Origin::Previous | Origin::Waiting => motion_block,
                Origin::Corner | Origin::Current => this_block,
            };
            // As the device: the element held back by compensation at its
            // own feed, this block's and the corners between at this one's.
            let feed = match m.origin {
                Origin::Previous => element_feed,
                Origin::Waiting => round_feed,
                Origin::Current => feed_now,
                Origin::Corner => feed_now.or(element_feed),
            };
            timeline.feeds.push(match m.kind {
                MoveKind::Line { rapid: true } => None,
                _ => feed,
            });
            let (dx, dz) = ((m.to[0] - at[0]) as f64, (m.to[1] - at[1]) as f64);
            let mut block = String::new();
            let x = mm4(2 * m.to[0]);
            let z = mm4(m.to[1]);
            match m.kind {
                MoveKind::Line { rapid } => {
                    let l = dx.hypot(dz) / 1e7;
                    if rapid {
                        report.rapid_mm += l;
                    } else {
                        report.feed_mm += l;
                    }
                    let g = if rapid { "G00" } else { "G01" };
                    block.push_str(&format!("{g} X{x} Z{z}"));
                    report.path.push(Traced {
                        g: u8::from(!rapid),
                        to: m.to,
                        centre: None,
                        line,
                        seq,
                    });
                }
                MoveKind::Arc { centre, dir } => {
                    let (i, k) = (centre[0] - at[0], centre[1] - at[1]);
                    let r = (i as f64).hypot(k as f64);
                    let a0 = (-(i as f64)).atan2(-(k as f64));
                    let a1 = ((m.to[0] - centre[0]) as f64).atan2((m.to[1] - centre[1]) as f64);
                    let ccw = matches!(dir, core_nostd::arc::ArcDir::Ccw);
                    let mut sweep = if ccw { a1 - a0 } else { a0 - a1 };
                    sweep = sweep.rem_euclid(std::f64::consts::TAU);
                    if sweep == 0.0 {
                        sweep = std::f64::consts::TAU;
                    }
                    report.feed_mm += r * sweep / 1e7;
                    let g = if ccw { "G03" } else { "G02" };
                    block.push_str(&format!("{g} X{x} Z{z} I{} K{}", mm4(i), mm4(k)));
                    report.path.push(Traced {
                        g: if ccw { 3 } else { 2 },
                        to: m.to,
                        centre: Some(centre),
                        line,
                        seq,
                    });
                }
            }
            report.trace.push(block);
            at = m.to;
        }
        if let (true, Some((line, kind))) = (many, this_cycle) {
            report.cycles.push(CycleRun {
                line,
                kind,
                moves: first..report.path.len(),
                us: None,
            });
        }
        motion_block = this_block;
        if element {
            // As the device keeps them (a move that waits for its corner
            // keeps its own feed).
            let waits = dev.session().contour().rounding();
            if waits {
                if rounding {
                    element_feed = round_feed;
                }
                round_feed = feed_now;
            } else {
                element_feed = feed_now;
            }
            rounding = waits;
        }
        if io.find.is_some() {
            // One line at a time: its motion runs before the next is sent.
            request(&mut dev, &mut io, "SYNC");
        }
    }
    // The end: everything queued runs.
    if stopped_at.is_none() {
        let reply = request(&mut dev, &mut io, "SYNC");
        debug_assert!(reply.starts_with("OK"), "SYNC: {reply}");
        deliver(&mut dev, &mut io);
    }
    let machine_run = match io.watch.take() {
        Some(w) => {
            let at = registers(&mut dev, &mut io);
            Some(MachineRun {
                trip: w.trip.map(|(event, inputs, carriage)| Trip {
                    inputs,
                    carriage,
                    event,
                    line: None,
                    alarm: alarm.trim().to_string(),
                    lines_left: stopped_at.map_or(0, |seq| {
                        lines[seq..]
                            .iter()
                            .filter(|(_, l)| !l.trim().is_empty())
                            .count()
                    }),
                }),
                range: w.lathe.range(),
                carriage: w.lathe.carriage(),
                registers: at,
                over_top: w.over_top,
            })
        }
        None => None,
    };
    cycle_times(&mut report, &io.ends, timeline.price);
    report.motion_us = io.run_ticks;
    report.dwell_us = io.dwell_us;
    report.events = io.events;
    timeline.happenings = io.timeline.unwrap_or_default();
    if !timed {
        timeline.feeds.clear();
    }
    (
        report,
        timeline,
        machine_run,
        io.find.and_then(|(_, found)| found),
    )
}

/// Each cycle's time: the step events' linear blocks matched in order to
/// the moves of [`Report::path`] (a line is one block; an arc's chords
/// end with one on its end; a move shorter than an impulse runs none).
/// Left unknown if the two do not match.
fn cycle_times(report: &mut Report, ends: &[([i64; 2], u64, u64)], price: [i64; 2]) {
    if report.cycles.is_empty() || price.contains(&0) {
        return;
    }
    let q = |p: [i64; 2]| [div_round(p[0], price[0]), div_round(p[1], price[1])];
    // When each move's first linear block started and its last step event
    // came, µs (a move that runs none: when the move before ended).
    let mut spans = Vec::with_capacity(report.path.len());
    let (mut k, mut at, mut t) = (0usize, [0i64; 2], 0u64);
    for m in &report.path {
        let end = q(m.to);
        let mut span = [t, t];
        if m.centre.is_some() || end != at {
            let mut first = true;
            loop {
                let Some(&(to, start, last)) = ends.get(k) else {
                    return;
                };
                k += 1;
                if first {
                    (span[0], first) = (start, false);
                }
                span[1] = last;
                if to == end {
                    break;
                }
            }
        }
        (at, t) = (end, span[1]);
        spans.push(span);
    }
    if k != ends.len() {
        // Blocks not among the moves: not known which is which.
        return;
    }
    for c in &mut report.cycles {
        if let (Some(first), Some(last)) = (
            spans.get(c.moves.start),
            c.moves.end.checked_sub(1).and_then(|i| spans.get(i)),
        ) {
            c.us = Some(last[1] - first[0]);
        }
    }
}

/// `a / b` rounded half away from zero (`b > 0`).
pub(crate) fn div_round(a: i64, b: i64) -> i64 {
    let q = (2 * a.unsigned_abs() + b.unsigned_abs()) / (2 * b.unsigned_abs());
    if a < 0 {
        -(q as i64)
    } else {
        q as i64
    }
}

/// Microseconds as `m:ss.sss`.
pub fn minutes(us: u64) -> String {
    let ms = us.div_ceil(1000);
    format!("{}:{:02}.{:03}", ms / 60_000, ms / 1000 % 60, ms % 1000)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FANUC: Options = Options {
        dialect: Dialect::Fanuc,
        radius: false,
        optional_stop: false,
    };

    /// A DNC file's DC2 before the first `%` and DC4 after the last are
    /// the tape's leader and trailer: not sent, named, and every other line
    /// keeps its number (a refusal after them is placed where it is).
    /// A cycle's time is the time its moves take written out as blocks:
    /// the roughing of a `G71` and a `G73`, and the `G70` after each, run
    /// between two dwells (the axes at rest), against the program with
    /// their traced moves in their place, less the program without them.
    #[test]
    fn a_cycles_time_is_its_moves_time() {
        let head = "G21 G18 G40 G98\nS800 M03\nG00 X30. Z2.\nG04 P0.2\n";
        let tail = "G04 P0.2\nG00 X60. Z20.\nM30\n";
        for (cycle, feed, kind) in [
            (
                "G71 U1.5 R0.5\nG71 P10 Q40 U0.4 W0.1 F200.\nN10 G00 X20.\n\
                 N20 G01 Z-10. F100.\nN30 X26. Z-15.\nN40 Z-25.\n",
                200,
                "roughing",
            ),
            (
                "G73 U2. W1. R3\nG73 P84 Q87 U0.4 W0.1 F150.\nN84 G00 X16. Z1.\n\
                 N85 G01 Z0 F80.\nN86 G03 X20. Z-2. R2.\nN87 G01 Z-8.\n",
                150,
                "roughing",
            ),
            (
                "G71 U1.5 R0.5\nG71 P10 Q40 U0.4 W0.1 F200.\nN10 G00 X20.\n\
                 N20 G01 Z-10. F100.\nN30 X26. Z-15.\nN40 Z-25.\nG04 P0.2\nG70 P10 Q40\n",
                100,
                "finishing",
            ),
        ] {
            let r = run(&format!("{head}{cycle}{tail}"), FANUC);
            assert!(r.refused.is_empty(), "{:?}", r.refused);
            let c = r.cycles.last().expect("a cycle ran");
            assert_eq!(c.kind, kind);
            let moves = &r.trace[c.moves.clone()];
            assert!(moves.len() > 4, "{moves:?}");
            let written: String = moves.iter().map(|m| format!("{m}\n")).collect();
            let with = run(&format!("{head}F{feed}.\n{written}{tail}"), FANUC);
            let without = run(&format!("{head}{tail}"), FANUC);
            assert!(with.refused.is_empty(), "{:?}", with.refused);
            assert_eq!(
                with.trace[with.trace.len() - moves.len() - 1..with.trace.len() - 1],
                *moves
            );
            let us = c.us.expect("the cycle's time is known");
            assert_eq!(us, with.motion_us - without.motion_us, "{kind}: {moves:?}");
            assert!(us > 1_000_000, "{us}");
        }
    }

    #[test]
    fn a_tapes_leader_and_trailer_are_named_and_not_read() {
        let text = "\u{12}%\nG21 G18 G98\nG00 X20. Z2.\nG01 Z-30. F300. Q5\nM30\n%\u{14}\n";
        let f = framing(text);
        assert_eq!(f.leader, Some((0, "DC2".to_string())));
        assert_eq!(f.tail, Some((5, "DC4".to_string())));
        assert_eq!(f.trailer, None);
        let lines = program_lines(text, Dialect::Fanuc).unwrap();
        assert_eq!(lines[0], (0, "%".to_string()));
        assert_eq!(lines[5], (5, "%".to_string()));
        let report = run(text, FANUC);
        assert_eq!(report.refused.len(), 1, "{:?}", report.refused);
        assert_eq!(report.refused[0].line, 4);
        assert_eq!(
            f.notes(),
            vec![
                (1, "the tape's leader before % is not read: DC2".to_string()),
                (6, "the tape's trailer after % is not read: DC4".to_string()),
            ]
        );
        // A printer's escape sequence before DC2 is leader too.
        let esc = framing("\u{1b}&HE:\u{12}%\n:0100\nG00 X1.\n%\n");
        assert_eq!(esc.leader, Some((0, "ESC &HE: DC2".to_string())));
        // The reader's DC2 on a line of its own, blank lines around it.
        let text = "\n\u{12}\r\n\n%\nG00 X20. Z2.\nM30\n%\n";
        let own = framing(text);
        assert_eq!(own.leading, Some((1, 1, "DC2".to_string())));
        assert_eq!(own.leader, None);
        assert_eq!(
            own.notes(),
            vec![(2, "the tape's leader before % is not read: DC2".to_string())]
        );
        let lines = program_lines(text, Dialect::Fanuc).unwrap();
        assert!(
            lines.iter().all(|(_, l)| !l.contains('\u{12}')),
            "{lines:?}"
        );
        let report = run(text, FANUC);
        assert!(report.refused.is_empty(), "{:?}", report.refused);
        // The two `%` lines and the two blocks.
        assert_eq!(report.blocks, 4);
        // Not when a printable line stands before the `%` too.
        let mixed = framing("\u{12}\nO100\n%\nG00 X1.\n%\n");
        assert_eq!(mixed.leading, None);
        assert!(!run("\u{12}\nO100\n%\nG00 X1.\n%\n", FANUC)
            .refused
            .is_empty());
    }

    /// Lines after the closing `%` are not run, and are named; a file
    /// without an opening `%` has no closing one; printable text before a
    /// `%` is not a leader.
    #[test]
    fn lines_after_the_closing_mark_are_not_run_and_are_named() {
        let text = "%\nG00 X20. Z2.\n%\n\nG00 X999.\nM30\n";
        let f = framing(text);
        assert_eq!(f.trailer, Some((4, 5)));
        assert_eq!(
            f.notes(),
            vec![(
                5,
                "the program ends at its closing %: lines 5 to 6 after it are not read".to_string()
            )]
        );
        let report = run(text, FANUC);
        assert!(report.refused.is_empty(), "{:?}", report.refused);
        assert_eq!(report.blocks, 3);
        // One mark only: nothing is a trailer.
        assert_eq!(framing("G00 X1.\n%\nG00 X2.\n"), Framing::default());
        // Readable text before the first `%`: sent as it is, and refused.
        let label = "PART 7 %\nG00 X1.\n%\n";
        assert_eq!(framing(label).leader, None);
        assert_eq!(run(label, FANUC).refused.len(), 1);
        assert_eq!(framing(label).apply(label), label);
    }

    #[test]
    fn a_program_reports_its_time_travel_and_tools() {
        let program = "%\nO1000\nG21 G18 G98\nT0101\nG00 X20. Z2.\nG01 Z-30. F300.\n\
                       G04 P1500\nT0202\nG00 X40.\nG02 X40. Z-30. I-10. K0\nM30\n%\n";
        let r = run(program, FANUC);
        assert!(r.refused.is_empty(), "{:?}", r.refused);
        assert_eq!(r.tools, [(4, "T0101".into()), (8, "T0202".into())]);
        // 32 mm at 300 mm/min take 6.4 s, the circle at its feed 12.6 s,
        // the ramps and the rapids a little more; the dwell 1.5 s.
        assert_eq!(r.dwell_us, 1_500_000);
        assert!(
            r.motion_us > 19_000_000 && r.motion_us < 20_500_000,
            "{}",
            r.motion_us
        );
        assert!(
            (r.feed_mm - 32.0 - 20.0 * std::f64::consts::PI).abs() < 1e-6,
            "{}",
            r.feed_mm
        );
        let rapid = 10f64.hypot(2.0) + 10.0;
        assert!((r.rapid_mm - rapid).abs() < 1e-6, "{}", r.rapid_mm);
        assert_eq!(
            r.trace,
            [
                "G00 X20.0000 Z2.0000",
                "G01 X20.0000 Z-30.0000",
                "G00 X40.0000 Z-30.0000",
                "G02 X40.0000 Z-30.0000 I-10.0000 K0.0000"
            ]
        );
        assert_eq!(r.cycle_us(), r.motion_us + 1_500_000);
        assert_eq!(minutes(61_234_001), "1:01.235");
    }

    #[test]
    fn coordinate_setting_program_stops_and_the_reference_return() {
        let program = "G21 G18\nT0101\nG00 X40. Z5.\nG50 X0 Z0\nG00 X10. Z-2.\n\
                       M00\nM01\nG28 U0 W0\nG00 U4. W-1.\nG28 U0\nM30\n";
        let setup = [(1, "TOOL N=1 X=2 Z=-1"), (2, "WORK G=54 Z=-50")];
        let r = run_setup(program, FANUC, &setup);
        assert!(r.refused.is_empty() && r.setup_refused.is_empty(), "{r:?}");
        // Register 1 adds X 1 (radius) and Z -1, G54 Z -50; G50 makes the
        // point X40 Z5 the zero; G28 returns to machine zero, through the
        // way point (the point itself with U0 W0) on the axes named.
        assert_eq!(
            r.trace,
            [
                "G00 X42.0000 Z-46.0000",
                "G00 X52.0000 Z-48.0000",
                "G00 X0.0000 Z0.0000",
                "G00 X4.0000 Z-1.0000",
                "G00 X0.0000 Z-1.0000"
            ]
        );
        assert_eq!(r.stops, [(6, "M00".to_string())]);
        let r = run_setup(
            program,
            Options {
                optional_stop: true,
                ..FANUC
            },
            &setup,
        );
        assert_eq!(r.stops, [(6, "M00".into()), (7, "M01".into())]);
        let r = run_setup("G00 X2.\n", FANUC, &[(3, "TOOL N=40")]);
        assert_eq!(r.setup_refused.len(), 1);
        assert_eq!(r.setup_refused[0].line, 3);
    }

    #[test]
    fn subprograms_and_macro_loops_are_expanded_by_the_host() {
        let program = "%\nO1000\nG21 G18 G98\nG00 X40. Z2.\n#100 = 0\n\
                       WHILE [#100 LT 2] DO1\nG01 X[38. - #100 * 2] Z0 F200.\n\
                       #100 = #100 + 1\nEND1\nM98 P2000 L2\nM30\n\
                       O2000\nG00 W-5.\nG76 P010060 Q100 R.05\nM99\n%\n";
        let r = run(program, FANUC);
        assert_eq!(
            r.trace,
            [
                "G00 X40.0000 Z2.0000",
                "G01 X38.0000 Z0.0000",
                "G01 X36.0000 Z0.0000",
                "G00 X36.0000 Z-5.0000",
                "G00 X36.0000 Z-10.0000"
            ]
        );
        // The refusal inside the subprogram, at its line, once per call.
        let at: Vec<usize> = r.refused.iter().map(|x| x.line).collect();
        assert_eq!(at, [14, 14]);
        let r = run("G01 X[1 / 0] F100\n", FANUC);
        let e = r.expand_error.unwrap();
        assert_eq!((e.line, r.blocks), (1, 0));
        assert!(e.what.contains("zero"), "{e}");
    }

    #[test]
    fn refusals_are_listed_and_the_rest_runs() {
        let r = run("G00 X10\nG76 P010060 Q100 R.05\nMOVE X=1\nG00 X20\n", FANUC);
        assert_eq!(
            r.refused,
            [
                Refused {
                    line: 2,
                    reply: "ERR VALUE G76 canned cycles not supported".into()
                },
                Refused {
                    line: 3,
                    reply: "ERR SYNTAX not a G-code line".into()
                }
            ]
        );
        assert_eq!(r.trace, ["G00 X10.0000 Z0.0000", "G00 X20.0000 Z0.0000"]);
    }
}

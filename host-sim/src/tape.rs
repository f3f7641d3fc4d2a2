//! `host-sim tape encode FILE --format bck5|iso7`: a G-code program punched
//! as the old controls read it.
//!
//! The program runs through the in-process device first ([`crate::program`]),
//! so the tape carries every motion block exactly as the device ran it: X on
//! the radius, machine coordinates, offsets and nose compensation done. Each
//! axis position is quantized with the carry rule (`docs/impulses.md` §2): a block
//! issues `Q(P_k/h) − Q(P_{k−1}/h)` impulses, so the tape's impulses sum to
//! the program's end position and nothing accumulates.
//!
//! # BCK-5 (АТПр-2М12, Kosenko ch. IV §5)
//! - Frame К000 `П00 Ш00 С00 В00` as the seed starts, then each tool change
//!   as the seed's tool-search frame `П00 Ш00 С<tool> В00` (С the tool
//!   number 0–99).
//! - Every tool returns to where its tool-change frame found it (the
//!   machine changes tools at its zero point, and a tool's frames must close,
//!   `Σ+ + Σ− = 0`): when the program does not bring it back, rapid frames
//!   to that point are added — out in X first, then along Z, then in X, as
//!   a turner retracts an outside tool, never diagonally across the part —
//!   with `Ш00 В00` as the seed's last frame of each tool has, and a note
//!   says so. A program for a boring bar brings its tool back itself.
//! - G00: `П75` over 10 mm of path, `П54` up to 10 mm; G01 (and each chord
//!   of a G02/G03: the control interpolates lines only) the feed code nearest
//!   `S/0.6` Hz, `S` the feed in mm/min (mm/rev × rpm under G95/G99).
//!   Arcs are cut into chords no farther than `--chord` mm from the arc
//!   (the finishing rule of `docs/arcs.md` §1.2).
//! - Ш: the speed of Table 23 nearest the program's (code 11, 12, 21 or 22 of
//!   its gear range) plus 04 for M03, 40 for M04; `Ш00` for M05. Under G96
//!   the speed is `1000·V/(π·d)` at the largest diameter the tool feeds at
//!   (capped by the G50/G92 limit), as the seed chooses `n` from the blank's
//!   diameter. One gear range serves the whole program (its change gears are
//!   set by hand). В: `В01` for M07/M08, `В00` for M09. Both are written
//!   on the next frame after they change.
//! - The program ends with its `Я` frame.
//!
//! # ISO-7bit (ЭМ-907, Kosenko ch. VI, Table 31)
//! - `%`, then one block per motion: G00, G01 with `F = S·10³/l`, G02/G03
//!   as the ЭМ-907's circular block (I, K the centre's distance from the
//!   start, unsigned, `F = S·10³/R`). The ЭМ-907 interpolates an arc within
//!   one quadrant: an arc crossing an axis is an error.
//! - S: the code of Table 25 for the nearest speed without back gear (140 to
//!   1800 rpm), with M12 (motor at 1400 rpm) or M11 (700 rpm); T: the
//!   holder position of Table 26 (tools 1–4 the front holder T500, T600,
//!   T700, T400; 5–8 the rear T050 … T080) with M06; M03, M04, M05, M08
//!   (M07 too), M09 as programmed; M02/M30 on the last block.
//! - `--punch` shows each character as its row of holes: tracks 8 to 1,
//!   track 8 the even parity, the feed holes between tracks 3 and 4.

use core_nostd::arc::{ArcDir, ArcPoints, ChordPlan, DirectArc};
use core_nostd::calc::tape::{
    self as core_tape, Alphabet, Bck5Block, Bck5Encoder, Bck5Feed, Bck5Move, Em907Encoder,
    Em907Motion, Em907Move, FeedCode, FeedPerRev, Iso7Block, Travel, BCK5_MAX_IMPULSES,
    EM907_MAX_WORD,
};
use core_nostd::gcode::{
    is_block, parse, Coolant, Dialect, FeedMode, Spindle, SpindleMode, Stop, Units,
};
use core_nostd::impulse::{quantize, ImpulsePrice};
use core_nostd::interleave::ImpulsePoint;
use core_nostd::length::Length;
use std::fmt;

use crate::program::{program_lines, run, Options, Traced};

/// Which tape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// BCK-5 frames of the АТПр-2М12.
    Bck5,
    /// ISO-7bit blocks of the ЭМ-907.
    Iso7,
}

/// How to encode a program.
#[derive(Clone, Copy, Debug)]
pub struct Job {
    /// The tape.
    pub format: Format,
    /// The program's dialect.
    pub dialect: Dialect,
    /// X words are radii at the start, not diameters.
    pub radius: bool,
    /// BCK-5: the largest distance of a chord from its arc.
    pub chord: Length,
    /// Show the rows of holes instead of the text (ISO-7bit).
    pub punch: bool,
}

/// What cannot go on the tape: the line of the program and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// Line of the file, from 1 (0: the program as a whole).
    pub line: usize,
    /// What is wrong.
    pub what: String,
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "line {}: {}", self.line, self.what)
        } else {
            f.write_str(&self.what)
        }
    }
}

/// The tape and what the machinist should know about it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Encoded {
    /// The listing (or the rows of holes), one line each, ending in LF.
    pub text: String,
    /// Set-up and added frames, one sentence each.
    pub notes: Vec<String>,
}

fn err(line: usize, what: impl Into<String>) -> LineError {
    LineError {
        line,
        what: what.into(),
    }
}

/// Spindle command in effect.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Turn {
    #[default]
    Off,
    Cw,
    Ccw,
}

/// The modal state after a line: what the tape needs beyond the path.
#[derive(Clone, Copy, Debug, Default)]
struct State {
    units: Units,
    per_rev: bool,
    surface: bool,
    /// S as written: rpm, or m/min (ft/min under G20) under G96.
    s: Option<f64>,
    /// The G50/G96 D speed limit, rpm.
    clamp: Option<f64>,
    /// F, mm/min or mm/rev.
    f: Option<f64>,
    turn: Turn,
    coolant: bool,
    /// The tool and the line of its T word.
    tool: Option<(u8, usize)>,
    /// M02/M30 read.
    end: bool,
}

fn mm(l: Length) -> f64 {
    l.as_angstrom() as f64 / 1e7
}

/// The state after every line the device was sent, by place.
fn states(lines: &[(usize, String)], dialect: Dialect) -> Vec<State> {
    let mut st = State::default();
    let mut out = Vec::with_capacity(lines.len());
    for (i, raw) in lines {
        let line = raw.trim_end_matches('\r');
        if !line.trim().is_empty() && is_block(line) {
            if let Ok(b) = parse(line, dialect, st.units) {
                if !b.deleted {
                    st.units = b.units.unwrap_or(st.units);
                    if let Some(m) = b.feed_mode {
                        st.per_rev = m == FeedMode::PerRev;
                    }
                    if let Some(m) = b.spindle_mode {
                        st.surface = m == SpindleMode::Surface;
                    }
                    if let Some(c) = b.clamp {
                        st.clamp = Some(mm(c));
                    }
                    // Fanuc `G50 S`: the limit only.
                    if b.clamp.is_none() {
                        if let Some(s) = b.s {
                            st.s = Some(mm(s));
                        }
                    }
                    if let Some(f) = b.f {
                        st.f = Some(mm(f));
                    }
                    match b.spindle {
                        Some(Spindle::Cw) => st.turn = Turn::Cw,
                        Some(Spindle::Ccw) => st.turn = Turn::Ccw,
                        Some(Spindle::Off) => st.turn = Turn::Off,
                        None => {}
                    }
                    match b.coolant {
                        Some(Coolant::Mist | Coolant::Flood) => st.coolant = true,
                        Some(Coolant::Off) => st.coolant = false,
                        None => {}
                    }
                    if let Some(t) = b.tool {
                        if st.tool.map(|(n, _)| n) != Some(t.tool) {
                            st.tool = Some((t.tool, i + 1));
                        }
                    }
                    if b.stop == Some(Stop::End) {
                        st.end = true;
                    }
                }
            }
        }
        out.push(st);
    }
    out
}

/// Table 23 (АТПр-2М12): per gear range its name, change gears A, B and
/// the speeds of codes 11, 12, 21, 22, rpm.
const TABLE_23: [(&str, u8, u8, [f64; 4]); 4] = [
    ("I", 43, 91, [70.0, 140.0, 199.0, 398.0]),
    ("II", 53, 81, [98.0, 195.0, 275.0, 550.0]),
    ("III", 81, 53, [228.0, 455.0, 643.0, 1290.0]),
    ("IV", 91, 43, [315.0, 630.0, 890.0, 1780.0]),
];
const TABLE_23_CODES: [u8; 4] = [11, 12, 21, 22];

/// Table 25 (16Б16Ф3): speed, rpm, and its code without back gear with the
/// motor at 1400 rpm (M12) and at 700 rpm (M11); 0 where the column has none.
const TABLE_25: [(f64, u8, u8); 12] = [
    (1800.0, 80, 0),
    (1400.0, 84, 0),
    (1120.0, 82, 0),
    (900.0, 48, 88),
    (710.0, 44, 84),
    (560.0, 42, 82),
    (450.0, 28, 48),
    (355.0, 24, 44),
    (280.0, 22, 42),
    (224.0, 0, 28),
    (180.0, 0, 24),
    (140.0, 0, 22),
];

/// How far beyond a table's slowest or fastest speed a program's speed may
/// lie and still take it: half a step of the R10 series.
const SPEED_MARGIN: f64 = 1.12;

/// The index of the speed nearest `n` by ratio, if `n` lies within the
/// table's range (with [`SPEED_MARGIN`]).
fn nearest_speed(n: f64, speeds: &[f64]) -> Option<usize> {
    let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds.iter().copied().fold(0.0, f64::max);
    if !(n >= lo / SPEED_MARGIN && n <= hi * SPEED_MARGIN) {
        return None;
    }
    let mut best = 0;
    for (i, s) in speeds.iter().enumerate() {
        if (n / s).ln().abs() < (n / speeds[best]).ln().abs() {
            best = i;
        }
    }
    Some(best)
}

/// The lowest and highest feed-code frequencies, Hz.
fn feed_code_span() -> (f64, f64) {
    let lo = FeedCode::new(0, 1).map_or(0.0, FeedCode::frequency_hz);
    let hi = FeedCode::new(7, 4).map_or(0.0, FeedCode::frequency_hz);
    (lo, hi)
}

/// A feed per minute as [`FeedPerRev`], which carries only the product of
/// its speed and feed: one revolution a minute at `mm_per_min` per
/// revolution.
fn per_minute(mm_per_min: f64) -> FeedPerRev {
    FeedPerRev {
        n_rpm: 1.0,
        s_mm_per_rev: mm_per_min,
    }
}

/// One motion of the path with what it needs from the program.
struct Step<'a> {
    t: &'a Traced,
    st: &'a State,
    /// Index into the tool segments.
    tool: usize,
}

/// A tool's stretch of the path: its number, the line of its T word, the
/// spindle speed under G96 (rpm).
struct ToolRun {
    number: u8,
    line: usize,
    rpm: Option<f64>,
}

/// Which tool every motion belongs to, and each tool's spindle speed.
fn tool_runs<'a>(
    path: &'a [Traced],
    states: &'a [State],
) -> Result<(Vec<Step<'a>>, Vec<ToolRun>), LineError> {
    let mut runs = vec![ToolRun {
        number: 0,
        line: 0,
        rpm: None,
    }];
    let mut steps = Vec::with_capacity(path.len());
    let mut current: Option<u8> = None;
    for t in path {
        let st = states
            .get(t.seq)
            .ok_or_else(|| err(t.line, "a motion the program's lines do not hold"))?;
        if let Some((n, line)) = st.tool {
            if current != Some(n) {
                current = Some(n);
                runs.push(ToolRun {
                    number: n,
                    line,
                    rpm: None,
                });
            }
        }
        steps.push(Step {
            t,
            st,
            tool: runs.len() - 1,
        });
    }
    // The speed of each tool: rpm as written, or under G96 at the largest
    // diameter it feeds at.
    for (k, run) in runs.iter_mut().enumerate() {
        let mut start = [0i64; 2];
        let mut d_max: f64 = 0.0;
        let mut surface: Option<(f64, &State, usize)> = None;
        for (i, s) in steps.iter().enumerate() {
            if i > 0 {
                start = steps[i - 1].t.to;
            }
            if s.tool != k || s.t.g == 0 {
                continue;
            }
            if s.st.surface {
                let r = [start[0], s.t.to[0]]
                    .iter()
                    .map(|x| x.unsigned_abs() as f64)
                    .chain(s.t.centre.map(|c| {
                        let (dx, dz) = ((start[0] - c[0]) as f64, (start[1] - c[1]) as f64);
                        c[0].unsigned_abs() as f64 + dx.hypot(dz)
                    }))
                    .fold(0.0, f64::max);
                d_max = d_max.max(2.0 * r / 1e7);
                let v = s.st.s.unwrap_or(0.0);
                let v = if s.st.units == Units::Inch {
                    v * 0.3048
                } else {
                    v
                };
                surface = Some((v, s.st, s.t.line));
            }
        }
        if let Some((v, st, line)) = surface {
            if d_max <= 0.0 || v <= 0.0 {
                return Err(err(
                    line,
                    "constant surface speed (G96) with no speed or at the spindle axis only",
                ));
            }
            let n = 1000.0 * v / (std::f64::consts::PI * d_max);
            run.rpm = Some(st.clamp.map_or(n, |c| n.min(c)));
        }
    }
    Ok((steps, runs))
}

/// The spindle speed a motion is programmed at, rpm: its S, or under G96
/// its tool's.
fn rpm(s: &Step<'_>, runs: &[ToolRun]) -> Option<f64> {
    if s.st.surface {
        runs.get(s.tool).and_then(|r| r.rpm)
    } else {
        s.st.s
    }
}

/// Adds a note once.
fn note(notes: &mut Vec<String>, text: String) {
    if !notes.contains(&text) {
        notes.push(text);
    }
}

/// The feed of a G01–G03 motion, mm/min, `rpm` the speed the spindle turns.
fn feed_mm_per_min(st: &State, rpm: Option<f64>, line: usize) -> Result<f64, LineError> {
    let f =
        st.f.filter(|f| *f > 0.0)
            .ok_or_else(|| err(line, "a feed motion with no feed (F)"))?;
    if st.per_rev {
        let n = rpm.ok_or_else(|| {
            err(
                line,
                "a feed per revolution (G95/G99) with no spindle speed (S and M03/M04)",
            )
        })?;
        Ok(f * n)
    } else {
        Ok(f)
    }
}

/// Exact lengths of a point in ångström.
fn point(p: [i64; 2], line: usize) -> Result<[Length; 2], LineError> {
    let l = |a: i64| Length::from_angstrom(a).ok_or_else(|| err(line, "position beyond range"));
    Ok([l(p[0])?, l(p[1])?])
}

/// The impulse position of a point (X radius at 0.005 mm, Z at 0.01 mm).
fn impulses(p: [i64; 2], line: usize) -> Result<[i64; 2], LineError> {
    let [x, z] = point(p, line)?;
    let q = |l, h| {
        quantize(l, h)
            .map(|n| i64::from(n.get()))
            .map_err(|_| err(line, "position beyond the axis' impulses"))
    };
    Ok([
        q(x, ImpulsePrice::DEFAULT_X)?,
        q(z, ImpulsePrice::DEFAULT_Z)?,
    ])
}

/// Encodes a program's text as a tape.
///
/// # Errors
/// Every line the device refuses, or the first thing the tape cannot
/// express, each with its line.
pub fn encode(program: &str, job: &Job) -> Result<Encoded, Vec<LineError>> {
    let options = Options {
        dialect: job.dialect,
        radius: job.radius,
        optional_stop: false,
    };
    let report = run(program, options);
    if let Some(e) = &report.expand_error {
        return Err(vec![err(e.line, e.what.clone())]);
    }
    if !report.refused.is_empty() {
        return Err(report
            .refused
            .iter()
            .map(|r| err(r.line, format!("refused by the device: {}", r.reply)))
            .collect());
    }
    let lines = program_lines(program, job.dialect).map_err(|e| vec![err(e.line, e.what)])?;
    let states = states(&lines, job.dialect);
    let (steps, runs) = tool_runs(&report.path, &states).map_err(|e| vec![e])?;
    let last = states.last().copied().unwrap_or_default();
    let out = match job.format {
        Format::Bck5 => bck5(&steps, &runs, &last, job),
        Format::Iso7 => iso7(&steps, &runs, &last),
    }
    .map_err(|e| vec![e])?;
    if job.punch {
        if job.format == Format::Bck5 {
            return Err(vec![err(
                0,
                "--punch shows the rows of the ISO-7bit tape; use --format iso7",
            )]);
        }
        return Ok(Encoded {
            text: punch_rows(&out.text),
            notes: out.notes,
        });
    }
    Ok(out)
}

// ───────────────────────────── BCK-5 ─────────────────────────────

/// The chosen gear range (index into [`TABLE_23`]) and the line that chose it.
type Range = Option<(usize, usize)>;

/// The Ш code for a spindle command at `rpm`, and the speed the machine
/// turns at then.
fn bck5_spindle(
    turn: Turn,
    rpm: Option<f64>,
    line: usize,
    range: &mut Range,
    notes: &mut Vec<String>,
) -> Result<(u8, Option<f64>), LineError> {
    let direction = match turn {
        Turn::Off => return Ok((0, None)),
        Turn::Cw => 4,
        Turn::Ccw => 40,
    };
    let n = rpm.ok_or_else(|| err(line, "the spindle turns with no speed (S)"))?;
    let all: Vec<f64> = TABLE_23.iter().flat_map(|r| r.3).collect();
    let i = nearest_speed(n, &all).ok_or_else(|| {
        err(
            line,
            format!("{n:.0} rpm: the АТПр-2М12 turns 70 to 1780 rpm (Table 23)"),
        )
    })?;
    let (r, c) = (i / 4, i % 4);
    let (name, a, b, speeds) = TABLE_23[r];
    match *range {
        None => {
            *range = Some((r, line));
            note(
                notes,
                format!("gear range {name}: change gears A={a} B={b} (Table 23)"),
            );
        }
        Some((had, at)) if had != r => {
            return Err(err(
                line,
                format!(
                    "{n:.0} rpm needs gear range {name} (A={a} B={b}); line {at} set range {} \
                     and the change gears are set by hand",
                    TABLE_23[had].0
                ),
            ))
        }
        Some(_) => {}
    }
    note(
        notes,
        format!(
            "spindle {n:.0} rpm runs at {:.0} rpm, Ш code {}",
            speeds[c], TABLE_23_CODES[c]
        ),
    );
    Ok((TABLE_23_CODES[c] + direction, Some(speeds[c])))
}

/// The BCK-5 frames written so far and where they leave the tape.
struct Frames {
    encoder: Bck5Encoder,
    out: String,
    /// Tape position, impulses: X (Д), Z (Е).
    at: [i64; 2],
    /// Ш and В as the tape last set them.
    spindle: u8,
    coolant: u8,
}

impl Frames {
    fn push(&mut self, block: &Bck5Block, line: usize) -> Result<(), LineError> {
        let frame = self.encoder.frame(block).map_err(|e| {
            err(
                line,
                match e {
                    core_tape::TapeError::WordRange => {
                        "more than 1000 frames (К999 is the last) or a code beyond 99".to_string()
                    }
                    e => e.to_string(),
                },
            )
        })?;
        frame
            .write(&mut self.out, Alphabet::Cyrillic)
            .map_err(|_| err(line, "output refused"))?;
        self.out.push('\n');
        Ok(())
    }

    /// A move to the impulse position `to`.
    fn move_to(
        &mut self,
        to: [i64; 2],
        feed: Bck5Feed,
        words: (Option<u8>, Option<u8>),
        line: usize,
    ) -> Result<(), LineError> {
        let d = [to[0] - self.at[0], to[1] - self.at[1]];
        for (n, axis, h) in [
            (d[1], "Е (carriage)", 0.01),
            (d[0], "Д (cross slide)", 0.005),
        ] {
            if n.unsigned_abs() > u64::from(BCK5_MAX_IMPULSES) {
                return Err(err(
                    line,
                    format!(
                        "a move of {n} impulses ({:.3} mm) on {axis}: a frame moves at most \
                         {BCK5_MAX_IMPULSES}",
                        n as f64 * h
                    ),
                ));
            }
        }
        let mut m = Bck5Move::new(
            // |n| ≤ 99 999: checked above.
            Travel::Impulses(d[1] as i32),
            Travel::Impulses(d[0] as i32),
            feed,
        );
        m.spindle = words.0;
        m.coolant = words.1;
        self.push(&Bck5Block::Move(m), line)?;
        self.at = to;
        if let Some(s) = words.0 {
            self.spindle = s;
        }
        if let Some(c) = words.1 {
            self.coolant = c;
        }
        Ok(())
    }

    /// Ш and В words for what the program wants now.
    fn words(&self, spindle: u8, coolant: u8) -> (Option<u8>, Option<u8>) {
        (
            (spindle != self.spindle).then_some(spindle),
            (coolant != self.coolant).then_some(coolant),
        )
    }

    /// Brings the tool back to `start` if it is not there.
    fn close(
        &mut self,
        start: [i64; 2],
        tool: &ToolRun,
        line: usize,
        notes: &mut Vec<String>,
    ) -> Result<(), LineError> {
        if self.at == start {
            return Ok(());
        }
        let number = self.encoder_number();
        let words = self.words(0, 0);
        let open = [self.at[0] - start[0], self.at[1] - start[1]];
        // As a turner brings a tool back: out in X first (to the start's X
        // if that is farther out), then along Z, then in X; never across
        // the part diagonally.
        let out_x = self.at[0].max(start[0]);
        for p in [[out_x, self.at[1]], [out_x, start[1]], start] {
            if p != self.at {
                self.move_to(p, Bck5Feed::Rapid, words, line)?;
            }
        }
        notes.push(format!(
            "frame К{number:03}: tool {:02}{} returned to its start at rapid, \
             out in X first, then along Z (Е{:+}, Д{:+} impulses) to close its frames",
            tool.number,
            if tool.line > 0 {
                format!(" (line {})", tool.line)
            } else {
                String::new()
            },
            -open[1],
            -open[0]
        ));
        Ok(())
    }

    fn encoder_number(&self) -> u16 {
        // The encoder's next number: the frames written so far.
        self.out.lines().count() as u16
    }
}

fn bck5(
    steps: &[Step<'_>],
    runs: &[ToolRun],
    last: &State,
    job: &Job,
) -> Result<Encoded, LineError> {
    let mut notes = Vec::new();
    let mut f = Frames {
        encoder: Bck5Encoder::new(0),
        out: String::new(),
        at: [0, 0],
        spindle: 0,
        coolant: 0,
    };
    let (lo, hi) = feed_code_span();
    let mut range: Range = None;
    // К000: nothing turns, no tool.
    f.push(&Bck5Block::Move(Bck5Move::tool_change(0)), 0)?;
    let mut tool = 0usize;
    let mut start = [0i64; 2];
    let mut from = [0i64; 2];
    let mut last_line = 0;
    for s in steps {
        let line = s.t.line;
        if s.tool != tool {
            f.close(start, &runs[tool], line, &mut notes)?;
            tool = s.tool;
            let number = runs[tool].number;
            if number > 99 {
                return Err(err(
                    runs[tool].line,
                    format!("tool {number}: С takes 00 to 99"),
                ));
            }
            f.push(
                &Bck5Block::Move(Bck5Move::tool_change(number)),
                runs[tool].line,
            )?;
            f.spindle = 0;
            f.coolant = 0;
            start = f.at;
        }
        let (spindle, turns) = bck5_spindle(s.st.turn, rpm(s, runs), line, &mut range, &mut notes)?;
        let coolant = u8::from(s.st.coolant);
        let feed = if s.t.g == 0 {
            Bck5Feed::Rapid
        } else {
            let mpm = feed_mm_per_min(s.st, turns, line)?;
            let hz = mpm / 0.6;
            if hz < lo / 1.5 || hz > hi * 1.5 {
                return Err(err(
                    line,
                    format!(
                        "feed {mpm:.1} mm/min ({hz:.1} Hz): the feed codes run {lo:.3} to \
                         {hi:.0} Hz ({:.2} to {:.0} mm/min)",
                        lo * 0.6,
                        hi * 0.6
                    ),
                ));
            }
            Bck5Feed::PerRev(per_minute(mpm))
        };
        let words = f.words(spindle, coolant);
        match s.t.centre {
            None => {
                let to = impulses(s.t.to, line)?;
                if to != f.at || words != (None, None) {
                    f.move_to(to, feed, words, line)?;
                }
            }
            Some(c) => {
                let arc = ArcPoints {
                    start: point(from, line)?,
                    end: point(s.t.to, line)?,
                    centre: point(c, line)?,
                };
                let dir = if s.t.g == 3 { ArcDir::Ccw } else { ArcDir::Cw };
                let plan = ChordPlan::new(&arc, dir, job.chord, true)
                    .map_err(|e| err(line, format!("arc: {}", arc_error(e))))?;
                let mut words = words;
                for i in 1..=plan.chords() {
                    let p = plan
                        .chord_end(i, ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z)
                        .map_err(|_| err(line, "arc beyond the axis' impulses"))?;
                    let to = [i64::from(p.x.get()), i64::from(p.z.get())];
                    if to != f.at {
                        f.move_to(to, feed, words, line)?;
                        words = (None, None);
                    }
                }
            }
        }
        from = s.t.to;
        last_line = line;
    }
    f.close(start, &runs[tool], last_line, &mut notes)?;
    // What the program leaves on at its end is switched off as it says.
    let spindle = if last.turn == Turn::Off { 0 } else { f.spindle };
    let coolant = if last.coolant { f.coolant } else { 0 };
    let words = f.words(spindle, coolant);
    if words != (None, None) {
        f.move_to(f.at, Bck5Feed::Keep, words, last_line)?;
    }
    f.push(&Bck5Block::End, last_line)?;
    Ok(Encoded { text: f.out, notes })
}

fn arc_error(e: core_nostd::arc::ArcError) -> &'static str {
    match e {
        core_nostd::arc::ArcError::Geometry(s) | core_nostd::arc::ArcError::Range(s) => s,
    }
}

// ───────────────────────────── ISO-7bit ─────────────────────────────

/// Table 26: the T word of tools 1–8.
fn em907_tool(number: u8, line: usize) -> Result<u16, LineError> {
    match number {
        1 => Ok(500),
        2 => Ok(600),
        3 => Ok(700),
        4 => Ok(400),
        5 => Ok(50),
        6 => Ok(60),
        7 => Ok(70),
        8 => Ok(80),
        _ => Err(err(
            line,
            format!(
                "tool {number}: the ЭМ-907's holders have positions 1–4 (front) and 5–8 (rear)"
            ),
        )),
    }
}

/// Table 25: the S code and the motor speed's M word for `n` rpm.
fn em907_speed(n: f64, line: usize, notes: &mut Vec<String>) -> Result<(u8, u8, f64), LineError> {
    let speeds: Vec<f64> = TABLE_25.iter().map(|r| r.0).collect();
    let i = nearest_speed(n, &speeds).ok_or_else(|| {
        err(
            line,
            format!("{n:.0} rpm: the 16Б16Ф3 turns 140 to 1800 rpm without back gear (Table 25)"),
        )
    })?;
    let (speed, fast, slow) = TABLE_25[i];
    let (code, motor) = if fast != 0 { (fast, 12) } else { (slow, 11) };
    note(
        notes,
        format!("spindle {n:.0} rpm runs at {speed:.0} rpm, S{code:02} M{motor}"),
    );
    Ok((code, motor, speed))
}

fn iso7(steps: &[Step<'_>], runs: &[ToolRun], last: &State) -> Result<Encoded, LineError> {
    let mut notes = Vec::new();
    let mut out = String::from("%\n");
    let mut encoder = Em907Encoder::new(1);
    let mut number: u16 = 1;
    let mut at = [0i64; 2];
    let mut from = [0i64; 2];
    // What the tape last set: tool, S code, spindle, coolant.
    let mut tool = 0usize;
    let mut s_code: Option<u8> = None;
    let mut turn = Turn::Off;
    let mut coolant = false;
    let mut last_line = 0;
    for s in steps {
        let line = s.t.line;
        let mut extra: Vec<(char, u16)> = Vec::new();
        if s.tool != tool {
            tool = s.tool;
            extra.push(('T', em907_tool(runs[tool].number, runs[tool].line)?));
            extra.push(('M', 6));
        }
        let mut turns = None;
        if s.st.turn != Turn::Off {
            let n = rpm(s, runs).ok_or_else(|| err(line, "the spindle turns with no speed (S)"))?;
            let (code, motor, speed) = em907_speed(n, line, &mut notes)?;
            turns = Some(speed);
            if s_code != Some(code) {
                s_code = Some(code);
                extra.push(('S', u16::from(code)));
                extra.push(('M', u16::from(motor)));
            }
        }
        if s.st.turn != turn {
            turn = s.st.turn;
            extra.push((
                'M',
                match turn {
                    Turn::Cw => 3,
                    Turn::Ccw => 4,
                    Turn::Off => 5,
                },
            ));
        }
        if s.st.coolant != coolant {
            coolant = s.st.coolant;
            extra.push(('M', if coolant { 8 } else { 9 }));
        }
        let to = impulses(s.t.to, line)?;
        let d = [to[0] - at[0], to[1] - at[1]];
        for (n, axis) in [(d[0], "X"), (d[1], "Z")] {
            if n.unsigned_abs() > u64::from(EM907_MAX_WORD) {
                return Err(err(
                    line,
                    format!(
                        "a move of {n} impulses on {axis}: a block moves at most {EM907_MAX_WORD}"
                    ),
                ));
            }
        }
        if d == [0, 0] {
            // Too short for an impulse: what it carries waits for the next block.
            if !extra.is_empty() {
                return Err(err(
                    line,
                    "a block shorter than one impulse carries a tool, spindle or coolant word",
                ));
            }
            from = s.t.to;
            continue;
        }
        let motion = match (s.t.g, s.t.centre) {
            (0, _) => Em907Motion::Rapid,
            (_, None) => Em907Motion::Linear(per_minute(feed_mm_per_min(s.st, turns, line)?)),
            (g, Some(c)) => {
                let arc = ArcPoints {
                    start: point(from, line)?,
                    end: point(s.t.to, line)?,
                    centre: point(c, line)?,
                };
                let dir = if g == 3 { ArcDir::Ccw } else { ArcDir::Cw };
                let here = ImpulsePoint {
                    // |at| fits an i32: it was quantized from one.
                    x: core_nostd::impulse::Impulses(at[0] as i32),
                    z: core_nostd::impulse::Impulses(at[1] as i32),
                };
                let direct = DirectArc::new(
                    &arc,
                    dir,
                    here,
                    ImpulsePrice::DEFAULT_X,
                    ImpulsePrice::DEFAULT_Z,
                )
                .map_err(|e| {
                    err(
                        line,
                        format!(
                            "arc: {} (the ЭМ-907 interpolates within one quadrant; \
                             split the arc where it crosses an axis)",
                            arc_error(e)
                        ),
                    )
                })?;
                let (j, k) = direct.jk();
                Em907Motion::Arc {
                    clockwise: g == 2,
                    i: Travel::Impulses(j as i32),
                    k: Travel::Impulses(k as i32),
                    feed: per_minute(feed_mm_per_min(s.st, turns, line)?),
                }
            }
        };
        let mv = Em907Move {
            // |d| ≤ 130 000: checked above.
            x: Travel::Impulses(d[0] as i32),
            z: Travel::Impulses(d[1] as i32),
            motion,
        };
        let mut block = encoder.block(&mv).map_err(|e| {
            err(
                line,
                match e {
                    core_tape::TapeError::WordRange => {
                        "a word beyond 130 000 (F = S·10³/l too large for a short block?) \
                         or more than 999 blocks"
                            .to_string()
                    }
                    e => e.to_string(),
                },
            )
        })?;
        block = with_words(block, &extra).map_err(|e| err(line, e.to_string()))?;
        out.push_str(&block.to_string());
        out.push('\n');
        number += 1;
        at = to;
        from = s.t.to;
        last_line = line;
    }
    // The end: the spindle and coolant as the program leaves them, M02/M30.
    let mut extra = Vec::new();
    if turn != Turn::Off && last.turn == Turn::Off {
        extra.push(('M', 5));
    }
    if coolant && !last.coolant {
        extra.push(('M', 9));
    }
    if last.end {
        extra.push(('M', 30));
    }
    if !extra.is_empty() {
        if number > 999 {
            return Err(err(last_line, "more than 999 blocks"));
        }
        let block = Iso7Block::parse(&format!("N{number:03}"))
            .map_err(|e| err(last_line, e.to_string()))
            .and_then(|b| with_words(b, &extra).map_err(|e| err(last_line, e.to_string())))?;
        out.push_str(&block.to_string());
        out.push('\n');
    }
    Ok(Encoded { text: out, notes })
}

/// A block with S, T and M words added, in the block's order.
fn with_words(mut b: Iso7Block, words: &[(char, u16)]) -> Result<Iso7Block, core_tape::TapeError> {
    for (_, v) in words.iter().filter(|(l, _)| *l == 'S') {
        b = b.with_s(u8::try_from(*v).unwrap_or(u8::MAX))?;
    }
    for (_, v) in words.iter().filter(|(l, _)| *l == 'T') {
        b = b.with_t(*v)?;
    }
    let mut ms: Vec<u8> = words
        .iter()
        .filter(|(l, _)| *l == 'M')
        .map(|(_, v)| u8::try_from(*v).unwrap_or(u8::MAX))
        .collect();
    ms.sort_unstable();
    for m in ms {
        b = b.with_m(m)?;
    }
    Ok(b)
}

// ───────────────────────────── rows ─────────────────────────────

/// The rows of holes of an ISO-7bit listing: one row per character, LF
/// included, as `hex  tracks 8 7 6 5 4 | 3 2 1  character`.
pub fn punch_rows(text: &str) -> String {
    let mut out = String::from("row  8 7 6 5 4   3 2 1  (o hole, | feed holes)\n");
    for c in text.bytes() {
        let Some(row) = core_tape::iso7_parity(c) else {
            continue;
        };
        let hole = |t: u8| if row & (1 << (t - 1)) != 0 { 'o' } else { '.' };
        let shown = if c == b'\n' {
            "LF".to_string()
        } else {
            char::from(c).to_string()
        };
        out.push_str(&format!(
            "{row:02X}   {} {} {} {} {} | {} {} {}  {shown}\n",
            hole(8),
            hole(7),
            hole(6),
            hole(5),
            hole(4),
            hole(3),
            hole(2),
            hole(1)
        ));
    }
    out
}

/// Reads rows written by [`punch_rows`] back into text, checking each
/// row's parity.
///
/// # Errors
/// The line of a row that is not one, or whose holes are odd.
pub fn read_rows(rows: &str) -> Result<String, LineError> {
    let mut text = String::new();
    for (i, line) in rows.lines().enumerate().skip(1) {
        let marks: Vec<char> = line
            .get(5..)
            .unwrap_or("")
            .chars()
            .filter(|c| matches!(c, 'o' | '.'))
            .take(8)
            .collect();
        if marks.len() != 8 {
            return Err(err(i + 1, "not a row of eight tracks"));
        }
        let row = marks
            .iter()
            .fold(0u8, |acc, c| (acc << 1) | u8::from(*c == 'o'));
        let c = core_tape::iso7_row(row).map_err(|e| err(i + 1, e.to_string()))?;
        text.push(char::from(c));
    }
    Ok(text)
}

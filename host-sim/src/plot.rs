//! `host-sim plot FILE`: a G-code program drawn as an SVG picture in the
//! plane a lathe drawing uses, Z to the right and X up, at equal scale on
//! both axes, the X ticks read as diameters.
//!
//! Three paths, each from the in-process device (the protocol handler the
//! firmware runs), exact to the ångström it computes in:
//!
//! - **the tool tip** (the theoretical tool tip, TTT): every motion block the
//!   device ran, from its `last_moves` after each accepted line, in machine
//!   coordinates: the blocks of `host-sim run`'s [`program::Report::path`]
//!   (a test holds the two equal);
//! - **the part as programmed**: the same program run again through a second
//!   device whose nose radius is 0 (`CFG RN=0`, and `R=0` in every register
//!   of the tool table whose nose is set). With `r = 0` every rule of
//!   `docs/compensation.md` returns the programmed point itself (offset
//!   elements are the elements, corners their junctions, the entry and exit
//!   points the programmed ones, transition arcs of radius 0 are left out),
//!   while the program is read exactly as in the first run: the same modal
//!   states, G41/G42 look-ahead, offsets and refusals of blocks the
//!   compensation forbids. This is cleaner than re-reading G41/G42 as G40,
//!   which changes what the device accepts (offset changes, `G28`, `G53`
//!   under compensation), and exact, unlike reconstructing the contour from
//!   the compensated blocks;
//! - **the nose centre**: each tool-tip block shifted back by the tip vector
//!   of the tool in effect (`C = TTT − tip`, the table of
//!   `docs/compensation.md`: its tip code and nose radius), arcs about their
//!   centre shifted alike. The tool in effect is followed as the device
//!   selects it: Fanuc, the `T` word's offset register; ISO, the tool `M06`
//!   loaded; its register's nose when set, else `CFG RN`/`TIP`.
//!
//! Rapids (`G00`) are dashed, feeds solid (the nose centre's rapids, the
//! tip's shifted, are left out); arrowheads give the direction of travel.
//! A line the device refused is a red ring where the tool tip stood when
//! the line came (the end of the last block run: with G41/G42 on, the
//! element before the one that waits for its corner), with its line number.
//!
//! With a zoom window the picture also shows the blocks the device started
//! (an arc's chords, a line's one block, on the impulse grid) and the
//! staircase of its step events (from [`LocalDevice::recording`]), against
//! the exact tool-tip path drawn as a smooth curve (within 1/20 pixel).
//!
//! The SVG is written by `Canvas`, a plotters backend of this module:
//! plotters lays out the chart, axes, ticks and text; the canvas writes its
//! coordinates in tenths of a pixel (the view box is ten times the picture's
//! size), strokes a rapid with `stroke-dasharray` and names each stroke's
//! layer (`data-layer="tip rapid"`), none of which the `plotters-svg`
//! backend does (it writes whole pixels and draws dashes as separate
//! segments). Text is SVG `<text>` in the viewer's sans-serif font, level
//! and placed by its baseline, which browsers, librsvg and ImageMagick's
//! own renderer all read alike: nothing here needs a font library.

use crate::device::LocalDevice;
use crate::program::{self, Refused};
use core_nostd::arc::ArcDir;
use core_nostd::comp::MoveKind;
use core_nostd::gcode::{is_block, parse, Dialect, Units};
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, Pos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind, FontTransform,
};
use std::cell::RefCell;
use std::fmt::Write as _;
use std::rc::Rc;

/// SVG user units per pixel of the picture.
pub const UNITS_PER_PX: i32 = 10;

/// Ångström per millimetre.
const A_PER_MM: f64 = 1e7;

/// A zoom window: Z and X (a diameter) ranges in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Z from, to (mm), ascending.
    pub z: [f64; 2],
    /// X as a diameter from, to (mm), ascending.
    pub x_diam: [f64; 2],
}

/// Why a `--zoom` window was not read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WindowError {
    /// Not four comma-separated values.
    Count,
    /// The value at this place (from 1) is not a finite number.
    Number(usize),
    /// Z0 = Z1 or X0 = X1.
    Empty,
}

impl std::fmt::Display for WindowError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WindowError::Count => {
                f.write_str("a zoom window is four numbers Z0,X0,Z1,X1 (mm, X a diameter)")
            }
            WindowError::Number(n) => write!(f, "zoom window value {n} is not a number of mm"),
            WindowError::Empty => f.write_str("the zoom window is empty (Z0 = Z1 or X0 = X1)"),
        }
    }
}

impl std::error::Error for WindowError {}

impl std::str::FromStr for Window {
    type Err = WindowError;

    /// `Z0,X0,Z1,X1` in mm, X diameters, corners in any order.
    ///
    /// ```
    /// use host_sim::plot::{Window, WindowError};
    /// let w: Window = "-12,20,-10,18".parse().unwrap();
    /// assert_eq!((w.z, w.x_diam), ([-12.0, -10.0], [18.0, 20.0]));
    /// assert_eq!("1,2,3".parse::<Window>(), Err(WindowError::Count));
    /// assert_eq!("1,2,x,4".parse::<Window>(), Err(WindowError::Number(3)));
    /// assert_eq!("1,2,1,4".parse::<Window>(), Err(WindowError::Empty));
    /// ```
    fn from_str(s: &str) -> Result<Window, WindowError> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let [z0, x0, z1, x1] = parts[..] else {
            return Err(WindowError::Count);
        };
        let number = |i: usize, t: &str| {
            t.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or(WindowError::Number(i))
        };
        let (z0, x0, z1, x1) = (
            number(1, z0)?,
            number(2, x0)?,
            number(3, z1)?,
            number(4, x1)?,
        );
        if z0 == z1 || x0 == x1 {
            return Err(WindowError::Empty);
        }
        Ok(Window {
            z: [z0.min(z1), z0.max(z1)],
            x_diam: [x0.min(x1), x0.max(x1)],
        })
    }
}

impl Window {
    /// The window in (Z, X radius) mm: `[z0, r0, z1, r1]`.
    fn rect(&self) -> Rect {
        Rect {
            z: self.z,
            r: [self.x_diam[0] / 2.0, self.x_diam[1] / 2.0],
        }
    }
}

/// How to plot a program.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// How the device reads it (dialect, `--radius`).
    pub program: program::Options,
    /// The zoom window, if any: then the steps and blocks are traced.
    pub zoom: Option<Window>,
}

/// One block of a path, in ångström, X on the radius, machine coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment {
    /// Start point.
    pub from: [i64; 2],
    /// End point.
    pub to: [i64; 2],
    /// Line (rapid or feed) or arc about its centre.
    pub kind: MoveKind,
}

impl Segment {
    /// A `G00` block.
    pub const fn rapid(&self) -> bool {
        matches!(self.kind, MoveKind::Line { rapid: true })
    }

    /// The segment moved by `-by` (ångström).
    const fn back_by(&self, by: [i64; 2]) -> Segment {
        let kind = match self.kind {
            MoveKind::Arc { centre, dir } => MoveKind::Arc {
                centre: [centre[0] - by[0], centre[1] - by[1]],
                dir,
            },
            line => line,
        };
        Segment {
            from: [self.from[0] - by[0], self.from[1] - by[1]],
            to: [self.to[0] - by[0], self.to[1] - by[1]],
            kind,
        }
    }
}

/// A line the device refused, and where the tool stood when it came.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mark {
    /// Line, from 1.
    pub line: usize,
    /// The device's `ERR …` reply, without its checksum.
    pub reply: String,
    /// The end of the last block run (ångström, X radius).
    pub at: [i64; 2],
}

/// The device's steps near a zoom window, in impulses (X on the radius).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Steps {
    /// The impulse prices (ångström): X on the radius, Z.
    pub price: [i64; 2],
    /// Runs of consecutive step positions inside the traced region, each
    /// with the position before its first event.
    pub staircase: Vec<Vec<[i64; 2]>>,
    /// The blocks the device started that cross the region: start and end.
    pub blocks: Vec<[[i64; 2]; 2]>,
    /// Step events issued in the whole program.
    pub events: u64,
}

/// A tool's nose: radius (ångström) and tip code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Nose {
    /// Nose radius, Å.
    pub r: i64,
    /// Tip code 0–9.
    pub tip: u8,
}

impl Nose {
    /// The tip vector (nose centre to tool tip), `[x, z]` in ångström on the
    /// radius: 1 `(+r, +r)`, 2 `(+r, −r)`, 3 `(−r, −r)`, 4 `(−r, +r)`,
    /// 5 `(0, +r)`, 6 `(+r, 0)`, 7 `(0, −r)`, 8 `(−r, 0)`, 0 and 9 `(0, 0)`.
    ///
    /// ```
    /// use host_sim::plot::Nose;
    /// assert_eq!(Nose { r: 4_000_000, tip: 3 }.tip_vector(), [-4_000_000, -4_000_000]);
    /// assert_eq!(Nose { r: 4_000_000, tip: 9 }.tip_vector(), [0, 0]);
    /// ```
    pub const fn tip_vector(&self) -> [i64; 2] {
        // The core's table; a radius or code out of range has no vector.
        match (
            core_nostd::length::Length::from_angstrom(self.r),
            core_nostd::comp::TipCode::new(self.tip),
        ) {
            (Some(r), Some(tip)) => core_nostd::comp::Tool::new(r, tip).tip_vector(),
            _ => [0, 0],
        }
    }
}

/// Everything the picture shows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Paths {
    /// The part as programmed (the run with nose radius 0).
    pub programmed: Vec<Segment>,
    /// The theoretical tool tip: the blocks the device ran.
    pub tip: Vec<Segment>,
    /// The nose centre: each tip block less its tool's tip vector.
    pub centre: Vec<Segment>,
    /// The noses used, in order of first use.
    pub noses: Vec<Nose>,
    /// The lines the device refused.
    pub refused: Vec<Mark>,
    /// The setup requests it refused (line 0: the run's own settings).
    pub setup_refused: Vec<Refused>,
    /// Why the program's macros could not be expanded (nothing ran).
    pub expand_error: Option<crate::expand::ExpandError>,
    /// What went wrong setting up the programmed run (its nose radius 0):
    /// then its path is not the programmed contour.
    pub notes: Vec<String>,
    /// The steps and blocks near the zoom window, when one was given.
    pub steps: Option<Steps>,
}

/// The final line of a reply, without its checksum.
fn final_reply(lines: &[String]) -> String {
    let last = lines.last().map_or("", String::as_str);
    last.rsplit_once('*').map_or(last, |(b, _)| b).to_string()
}

/// Which run of the program.
#[derive(Clone, Copy, PartialEq)]
enum Pass {
    /// Nose radius 0: the contour as programmed.
    Programmed,
    /// The tools as set up: the tool tip, its nose centre, the refusals,
    /// and the steps near this region (impulses `[x0, z0, x1, z1]`).
    Tool(Option<Rect>),
}

/// A rectangle in (Z, X radius), mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Rect {
    pub(crate) z: [f64; 2],
    pub(crate) r: [f64; 2],
}

impl Rect {
    fn width(&self) -> f64 {
        self.z[1] - self.z[0]
    }
    fn height(&self) -> f64 {
        self.r[1] - self.r[0]
    }
    fn contains(&self, (z, r): (f64, f64)) -> bool {
        (self.z[0]..=self.z[1]).contains(&z) && (self.r[0]..=self.r[1]).contains(&r)
    }
    fn grown(&self, by: f64) -> Rect {
        Rect {
            z: [self.z[0] - by, self.z[1] + by],
            r: [self.r[0] - by, self.r[1] + by],
        }
    }
}

/// The tool in effect, followed as the device selects it.
struct ToolInEffect {
    dialect: Dialect,
    /// Fanuc: the offset register of the last `T` word.
    register: u8,
    /// ISO: the last `T` word, and the tool `M06` loaded.
    named: Option<u8>,
    loaded: u8,
}

impl ToolInEffect {
    fn after(&mut self, b: &core_nostd::gcode::Block) {
        match self.dialect {
            Dialect::Fanuc => {
                if let Some(t) = b.tool {
                    self.register = t.offset.unwrap_or(0);
                }
            }
            Dialect::Iso => {
                if let Some(t) = b.tool {
                    self.named = Some(t.tool);
                }
                if b.tool_change {
                    if let Some(t) = self.named {
                        self.loaded = t;
                    }
                }
            }
        }
    }

    /// Its nose: the register's when set, else the configured one.
    fn nose(&self, dev: &LocalDevice) -> Nose {
        let session = dev.device().session();
        let register = match self.dialect {
            Dialect::Fanuc => self.register,
            Dialect::Iso => self.loaded,
        };
        let cfg = session.config();
        match session.offsets().register(register).and_then(|t| t.nose) {
            Some((r, tip)) => Nose {
                r: r.as_angstrom(),
                tip: if tip <= 9 { tip } else { cfg.tip.get() },
            },
            None => Nose {
                r: cfg.rn.as_angstrom(),
                tip: cfg.tip.get(),
            },
        }
    }
}

/// Follows the step events of a recording device near a region.
struct StepTrace {
    /// The region in impulses: `[x0, x1]`, `[z0, z1]`.
    x: [i64; 2],
    z: [i64; 2],
    at: [i64; 2],
    run: Vec<[i64; 2]>,
    steps: Steps,
}

impl StepTrace {
    fn new(region: Rect, start: [i64; 2], price: [i64; 2]) -> StepTrace {
        let imp = |mm: f64, p: i64, up: bool| {
            let v = mm * A_PER_MM / p as f64;
            (if up { v.ceil() } else { v.floor() }) as i64 + if up { 1 } else { -1 }
        };
        StepTrace {
            x: [
                imp(region.r[0], price[0], false),
                imp(region.r[1], price[0], true),
            ],
            z: [
                imp(region.z[0], price[1], false),
                imp(region.z[1], price[1], true),
            ],
            at: start,
            run: Vec::new(),
            steps: Steps {
                price,
                ..Steps::default()
            },
        }
    }

    fn inside(&self, p: [i64; 2]) -> bool {
        (self.x[0]..=self.x[1]).contains(&p[0]) && (self.z[0]..=self.z[1]).contains(&p[1])
    }

    /// Whether the segment `a`–`b` may cross the region (its bounding box
    /// meets it).
    fn crosses(&self, a: [i64; 2], b: [i64; 2]) -> bool {
        a[0].min(b[0]) <= self.x[1]
            && a[0].max(b[0]) >= self.x[0]
            && a[1].min(b[1]) <= self.z[1]
            && a[1].max(b[1]) >= self.z[0]
    }

    /// Takes the blocks started and the events issued since the last call.
    fn take(&mut self, dev: &mut LocalDevice) {
        for (_, b) in dev.block_starts() {
            let p = |q: core_nostd::interleave::ImpulsePoint| [i64::from(q.x.0), i64::from(q.z.0)];
            let (a, e) = (p(b.from()), p(b.to()));
            if self.crosses(a, e) {
                self.steps.blocks.push([a, e]);
            }
        }
        for e in dev.take_events() {
            let d = |steps: u8, negative: u8| match (e.bits & steps != 0, e.bits & negative != 0) {
                (false, _) => 0,
                (true, false) => 1,
                (true, true) => -1,
            };
            let next = [self.at[0] + d(1, 4), self.at[1] + d(2, 8)];
            self.steps.events += 1;
            if self.inside(self.at) || self.inside(next) {
                if self.run.is_empty() {
                    self.run.push(self.at);
                }
                self.run.push(next);
            } else if !self.run.is_empty() {
                self.steps.staircase.push(std::mem::take(&mut self.run));
            }
            self.at = next;
        }
    }

    fn finish(mut self) -> Steps {
        if !self.run.is_empty() {
            self.steps.staircase.push(std::mem::take(&mut self.run));
        }
        self.steps
    }
}

/// What one run gives.
#[derive(Default)]
struct Run {
    path: Vec<Segment>,
    centre: Vec<Segment>,
    noses: Vec<Nose>,
    refused: Vec<Mark>,
    setup_refused: Vec<Refused>,
    notes: Vec<String>,
    steps: Option<Steps>,
}

/// Runs the program's lines (expanded) through a new device, as `host-sim
/// run` does, keeping every block it ran.
fn run_pass(
    lines: &[(usize, String)],
    options: program::Options,
    setup: &[(usize, &str)],
    pass: Pass,
) -> Run {
    let region = match pass {
        Pass::Tool(region) => region,
        Pass::Programmed => None,
    };
    let mut dev = if region.is_some() {
        LocalDevice::recording()
    } else {
        LocalDevice::new()
    };
    let mut run = Run::default();
    let settings = [
        format!("OPT DIALECT={}", options.dialect.as_str()),
        format!("CFG DIAM={}", u8::from(!options.radius)),
        "OPT OPTSTOP=0".to_string(),
    ];
    for (line, request) in settings
        .iter()
        .map(|s| (0, s.as_str()))
        .chain(setup.iter().copied())
    {
        let reply = final_reply(&dev.request(request));
        if !reply.starts_with("OK") {
            run.setup_refused.push(Refused { line, reply });
        }
    }
    if pass == Pass::Programmed {
        // Every nose radius 0: the compensated path is the programmed one.
        let mut zero = vec!["CFG RN=0".to_string()];
        let offsets = *dev.device().session().offsets();
        for (i, t) in offsets.tools.iter().enumerate() {
            if t.nose.is_some() {
                zero.push(format!("TOOL N={} R=0", i + 1));
            }
        }
        for request in &zero {
            let reply = final_reply(&dev.request(request));
            if !reply.starts_with("OK") {
                run.notes
                    .push(format!("the programmed contour's {request}: {reply}"));
            }
        }
    }
    let cfg = *dev.device().session().config();
    let price = [cfg.hx.as_angstrom(), cfg.hz.as_angstrom()];
    let start = dev.device().session().position();
    let mut trace =
        region.map(|r| StepTrace::new(r, [i64::from(start.x.0), i64::from(start.z.0)], price));
    let mut tool = ToolInEffect {
        dialect: options.dialect,
        register: 0,
        named: None,
        loaded: 0,
    };
    let mut units = Units::Mm;
    let mut at = [0i64; 2];
    for (i, raw) in lines {
        let line = raw.trim_end_matches('\r');
        if line.trim().is_empty() {
            continue;
        }
        let mark = |reply: String| Mark {
            line: i + 1,
            reply,
            at,
        };
        if !is_block(line) {
            run.refused
                .push(mark("ERR SYNTAX not a G-code line".into()));
            continue;
        }
        let replies = dev.request(line);
        let reply = final_reply(&replies);
        if let Some(t) = trace.as_mut() {
            t.take(&mut dev);
        }
        if !reply.starts_with("OK") {
            run.refused.push(mark(reply));
            continue;
        }
        if let Ok(b) = parse(line, options.dialect, units) {
            units = b.units.unwrap_or(units);
            tool.after(&b);
        }
        if reply.contains("SKIP=BDEL") {
            continue;
        }
        let nose = tool.nose(&dev);
        let mut moves: Vec<core_nostd::comp::Move> = dev
            .device()
            .session()
            .last_moves()
            .iter()
            .copied()
            .collect();
        // A request that ran many blocks (a turning cycle): its moves from
        // its DATA lines.
        let data = crate::program::data_moves(
            replies.join("\r\n").as_bytes(),
            dev.device().session().config().diam,
            at,
        );
        if data.len() != moves.len() {
            moves = data;
        }
        for m in &moves {
            let s = Segment {
                from: at,
                to: m.to,
                kind: m.kind,
            };
            run.path.push(s);
            if pass != Pass::Programmed {
                run.centre.push(s.back_by(nose.tip_vector()));
                if !run.noses.contains(&nose) {
                    run.noses.push(nose);
                }
            }
            at = m.to;
        }
    }
    // The end: everything queued runs.
    dev.request("SYNC");
    if let Some(mut t) = trace {
        t.take(&mut dev);
        run.steps = Some(t.finish());
    }
    run
}

/// Runs a program's text after setup requests (as `host-sim run --tools`):
/// the tool-tip path, the programmed contour, the nose centre, the
/// refusals, and with a zoom window the steps near it.
pub fn trace(text: &str, options: &Options, setup: &[(usize, &str)]) -> Paths {
    let lines = match crate::program::program_lines(text, options.program.dialect) {
        Ok(lines) => lines,
        Err(e) => {
            return Paths {
                expand_error: Some(e),
                ..Paths::default()
            }
        }
    };
    // The steps are kept over a square about the window wide enough for
    // any picture the window is fitted into.
    let region = options.zoom.map(|w| {
        let r = w.rect();
        r.grown(2.0 * r.width().max(r.height()))
    });
    // The two runs are independent: one on another thread.
    let (tool, programmed) = std::thread::scope(|s| {
        let programmed = s.spawn(|| run_pass(&lines, options.program, setup, Pass::Programmed));
        let tool = run_pass(&lines, options.program, setup, Pass::Tool(region));
        (tool, programmed.join())
    });
    let programmed = programmed.unwrap_or_else(|e| std::panic::resume_unwind(e));
    let mut notes = programmed.notes;
    // Refusals of the programmed run that the tool's run did not have.
    let own: Vec<String> = programmed
        .refused
        .iter()
        .filter(|p| !tool.refused.iter().any(|t| t.line == p.line))
        .map(|p| p.line.to_string())
        .collect();
    if !own.is_empty() {
        notes.push(format!(
            "the programmed contour (nose radius 0) is refused at line {} as well",
            own.join(", ")
        ));
    }
    Paths {
        programmed: programmed.path,
        tip: tool.path,
        centre: tool.centre,
        noses: tool.noses,
        refused: tool.refused,
        setup_refused: tool.setup_refused,
        expand_error: None,
        notes,
        steps: tool.steps,
    }
}

// ---------------------------------------------------------------------------
// Geometry to polylines.

/// A point in mm: (Z, X radius).
pub(crate) type P = (f64, f64);

fn mm(p: [i64; 2]) -> P {
    (p[1] as f64 / A_PER_MM, p[0] as f64 / A_PER_MM)
}

/// The points of a segment from its start: its end for a line; for an arc,
/// points on it no more than `sag` mm from the true curve between them (the
/// radius blended from the start's to the end's, as the device allows the
/// two to differ by up to 0.002 mm), ending on the exact end point.
fn points(s: &Segment, sag: f64, out: &mut Vec<P>) {
    let MoveKind::Arc { centre, dir } = s.kind else {
        out.push(mm(s.to));
        return;
    };
    let (c, a, b) = (mm(centre), mm(s.from), mm(s.to));
    let (r0, r1) = ((a.0 - c.0).hypot(a.1 - c.1), (b.0 - c.0).hypot(b.1 - c.1));
    // Angles in the (Z right, X up) picture: G03 counter-clockwise.
    let (t0, t1) = ((a.1 - c.1).atan2(a.0 - c.0), (b.1 - c.1).atan2(b.0 - c.0));
    let tau = std::f64::consts::TAU;
    let sweep = match dir {
        ArcDir::Ccw => (t1 - t0).rem_euclid(tau),
        ArcDir::Cw => -(t0 - t1).rem_euclid(tau),
    };
    let sweep = if s.from == s.to {
        if dir == ArcDir::Ccw {
            tau
        } else {
            -tau
        }
    } else {
        sweep
    };
    let r = r0.max(r1).max(1e-9);
    // A chord of angle θ leaves r(1 − cos θ/2) ≈ rθ²/8 between it and the arc.
    let step = (8.0 * sag / r).sqrt().min(5f64.to_radians());
    let n = ((sweep.abs() / step).ceil() as usize).clamp(1, 2_000_000);
    for k in 1..n {
        let f = k as f64 / n as f64;
        let (t, rr) = (t0 + sweep * f, r0 + (r1 - r0) * f);
        out.push((c.0 + rr * t.cos(), c.1 + rr * t.sin()));
    }
    out.push(b);
}

/// A path as polylines, each of one kind (rapid or feed): consecutive
/// segments of one kind that join make one polyline.
fn polylines(path: &[Segment], sag: f64) -> Vec<(bool, Vec<P>)> {
    let mut out: Vec<(bool, Vec<P>)> = Vec::new();
    let mut last: Option<(bool, [i64; 2])> = None;
    for s in path {
        let rapid = s.rapid();
        if last != Some((rapid, s.from)) {
            out.push((rapid, vec![mm(s.from)]));
        }
        if let Some((_, pts)) = out.last_mut() {
            points(s, sag, pts);
        }
        last = Some((rapid, s.to));
    }
    out
}

/// The part of segment `a`–`b` inside `r` (Liang–Barsky), if any.
fn clip(a: P, b: P, r: &Rect) -> Option<(P, P)> {
    let (dz, dr) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dz, a.0 - r.z[0]),
        (dz, r.z[1] - a.0),
        (-dr, a.1 - r.r[0]),
        (dr, r.r[1] - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| {
        if t == 0.0 {
            a
        } else if t == 1.0 {
            b
        } else {
            (a.0 + dz * t, a.1 + dr * t)
        }
    };
    Some((at(t0), at(t1)))
}

/// A polyline cut to `r`: the pieces inside it.
pub(crate) fn clipped(pts: &[P], r: &Rect) -> Vec<Vec<P>> {
    let mut out: Vec<Vec<P>> = Vec::new();
    let mut open = false;
    if let [only] = pts {
        if r.contains(*only) {
            out.push(vec![*only]);
        }
        return out;
    }
    for w in pts.windows(2) {
        match clip(w[0], w[1], r) {
            Some((a, b)) => {
                let joined = open && a == w[0];
                if !joined {
                    out.push(vec![a]);
                }
                if let Some(piece) = out.last_mut() {
                    piece.push(b);
                }
                open = b == w[1];
            }
            None => open = false,
        }
    }
    out
}

/// The bounding box of polylines and points, if any.
fn bounds<'a>(pts: impl Iterator<Item = &'a P>) -> Option<Rect> {
    let mut b: Option<Rect> = None;
    for &(z, r) in pts {
        b = Some(match b {
            None => Rect {
                z: [z, z],
                r: [r, r],
            },
            Some(b) => Rect {
                z: [b.z[0].min(z), b.z[1].max(z)],
                r: [b.r[0].min(r), b.r[1].max(r)],
            },
        });
    }
    b
}

// ---------------------------------------------------------------------------
// The SVG canvas: a plotters backend (the speed chart of `report` draws
// on it too).

/// How the next strokes are drawn, besides plotters' colour and width.
#[derive(Clone, Debug, Default)]
struct Pen {
    /// What the strokes show, written as `data-layer` (ImageMagick's
    /// renderer fails on many `class` attributes).
    class: Option<&'static str>,
    /// `stroke-dasharray`, in pixels.
    dash: Option<&'static [u32]>,
}

#[derive(Debug)]
struct Doc {
    svg: String,
    size: (u32, u32),
    pen: Pen,
}

/// The SVG document plotters draws into: a cheap handle, so that the
/// plotting code keeps one to set the pen between plotters' calls.
/// Coordinates are in user units of 1/[`UNITS_PER_PX`] pixel.
#[derive(Clone, Debug)]
pub(crate) struct Canvas(Rc<RefCell<Doc>>);

impl Canvas {
    /// A picture `w` × `h` pixels, white.
    pub(crate) fn new(w: u32, h: u32) -> Canvas {
        let k = UNITS_PER_PX as u32;
        let size = (w * k, h * k);
        let mut svg = String::new();
        let _ = writeln!(
            svg,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {} {}\">",
            size.0, size.1
        );
        let _ = writeln!(
            svg,
            "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#FFFFFF\" stroke=\"none\"/>",
            size.0, size.1
        );
        Canvas(Rc::new(RefCell::new(Doc {
            svg,
            size,
            pen: Pen::default(),
        })))
    }

    pub(crate) fn pen(&self, class: &'static str, dash: Option<&'static [u32]>) {
        self.0.borrow_mut().pen = Pen {
            class: Some(class),
            dash,
        };
    }

    pub(crate) fn plain(&self) {
        self.0.borrow_mut().pen = Pen::default();
    }

    /// The finished document.
    pub(crate) fn finish(&self) -> String {
        let mut doc = self.0.borrow_mut();
        let mut svg = std::mem::take(&mut doc.svg);
        svg.push_str("</svg>\n");
        svg
    }

    /// Writes a stroke's attributes.
    fn stroke(doc: &mut Doc, color: BackendColor, width: u32) {
        let (r, g, b) = color.rgb;
        let _ = write!(
            doc.svg,
            " fill=\"none\" stroke=\"#{r:02X}{g:02X}{b:02X}\" stroke-width=\"{width}\""
        );
        if color.alpha < 1.0 {
            let _ = write!(doc.svg, " stroke-opacity=\"{:.3}\"", color.alpha);
        }
        if let Some(class) = doc.pen.class {
            let _ = write!(doc.svg, " data-layer=\"{class}\"");
        }
        if let Some(dash) = doc.pen.dash {
            doc.svg.push_str(" stroke-dasharray=\"");
            for (i, d) in dash.iter().enumerate() {
                let sep = if i == 0 { "" } else { " " };
                let _ = write!(doc.svg, "{sep}{}", d * UNITS_PER_PX as u32);
            }
            doc.svg.push('"');
        }
    }

    fn fill(doc: &mut Doc, color: BackendColor) {
        let (r, g, b) = color.rgb;
        let _ = write!(doc.svg, " fill=\"#{r:02X}{g:02X}{b:02X}\" stroke=\"none\"");
        if color.alpha < 1.0 {
            let _ = write!(doc.svg, " fill-opacity=\"{:.3}\"", color.alpha);
        }
    }
}

fn escape(text: &str, out: &mut String) {
    for c in text.chars() {
        match c {
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            '"' => out.push_str("&quot;"),
            c => out.push(c),
        }
    }
}

type Drawn = Result<(), DrawingErrorKind<std::fmt::Error>>;

impl DrawingBackend for Canvas {
    type ErrorType = std::fmt::Error;

    fn get_size(&self) -> (u32, u32) {
        self.0.borrow().size
    }

    fn ensure_prepared(&mut self) -> Drawn {
        Ok(())
    }

    fn present(&mut self) -> Drawn {
        Ok(())
    }

    fn draw_pixel(&mut self, p: BackendCoord, color: BackendColor) -> Drawn {
        if color.alpha == 0.0 {
            return Ok(());
        }
        let mut doc = self.0.borrow_mut();
        let _ = write!(
            doc.svg,
            "<rect x=\"{}\" y=\"{}\" width=\"1\" height=\"1\"",
            p.0, p.1
        );
        Canvas::fill(&mut doc, color);
        doc.svg.push_str("/>\n");
        Ok(())
    }

    fn draw_line<S: plotters_backend::BackendStyle>(
        &mut self,
        a: BackendCoord,
        b: BackendCoord,
        s: &S,
    ) -> Drawn {
        if s.color().alpha == 0.0 {
            return Ok(());
        }
        let mut doc = self.0.borrow_mut();
        let _ = write!(
            doc.svg,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"",
            a.0, a.1, b.0, b.1
        );
        Canvas::stroke(&mut doc, s.color(), s.stroke_width());
        doc.svg.push_str("/>\n");
        Ok(())
    }

    fn draw_rect<S: plotters_backend::BackendStyle>(
        &mut self,
        a: BackendCoord,
        b: BackendCoord,
        s: &S,
        fill: bool,
    ) -> Drawn {
        if s.color().alpha == 0.0 {
            return Ok(());
        }
        let mut doc = self.0.borrow_mut();
        let _ = write!(
            doc.svg,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"",
            a.0.min(b.0),
            a.1.min(b.1),
            (b.0 - a.0).abs(),
            (b.1 - a.1).abs()
        );
        if fill {
            Canvas::fill(&mut doc, s.color());
        } else {
            Canvas::stroke(&mut doc, s.color(), s.stroke_width());
        }
        doc.svg.push_str("/>\n");
        Ok(())
    }

    fn draw_path<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        s: &S,
    ) -> Drawn {
        if s.color().alpha == 0.0 {
            return Ok(());
        }
        let mut doc = self.0.borrow_mut();
        doc.svg.push_str("<polyline points=\"");
        let mut last = None;
        let mut first = true;
        for p in path {
            // A point on the last one adds nothing.
            if last == Some(p) {
                continue;
            }
            let sep = if first { "" } else { " " };
            let _ = write!(doc.svg, "{sep}{},{}", p.0, p.1);
            (last, first) = (Some(p), false);
        }
        doc.svg.push('"');
        Canvas::stroke(&mut doc, s.color(), s.stroke_width());
        doc.svg
            .push_str(" stroke-linejoin=\"round\" stroke-linecap=\"butt\"/>\n");
        Ok(())
    }

    fn draw_circle<S: plotters_backend::BackendStyle>(
        &mut self,
        c: BackendCoord,
        radius: u32,
        s: &S,
        fill: bool,
    ) -> Drawn {
        if s.color().alpha == 0.0 {
            return Ok(());
        }
        let mut doc = self.0.borrow_mut();
        let _ = write!(
            doc.svg,
            "<circle cx=\"{}\" cy=\"{}\" r=\"{radius}\"",
            c.0, c.1
        );
        if fill {
            Canvas::fill(&mut doc, s.color());
        } else {
            Canvas::stroke(&mut doc, s.color(), s.stroke_width());
        }
        doc.svg.push_str("/>\n");
        Ok(())
    }

    fn fill_polygon<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        s: &S,
    ) -> Drawn {
        if s.color().alpha == 0.0 {
            return Ok(());
        }
        let mut doc = self.0.borrow_mut();
        doc.svg.push_str("<polygon points=\"");
        for (i, p) in vert.into_iter().enumerate() {
            let sep = if i == 0 { "" } else { " " };
            let _ = write!(doc.svg, "{sep}{},{}", p.0, p.1);
        }
        doc.svg.push('"');
        Canvas::fill(&mut doc, s.color());
        doc.svg.push_str("/>\n");
        Ok(())
    }

    fn draw_text<T: BackendTextStyle>(&mut self, text: &str, s: &T, pos: BackendCoord) -> Drawn {
        let color = s.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let size = s.size();
        let anchor = match s.anchor().h_pos {
            HPos::Left => "start",
            HPos::Center => "middle",
            HPos::Right => "end",
        };
        // The baseline from the anchor point, in the text's own frame (the
        // ascent of a sans-serif face is about 0.72 em, its descent 0.21).
        let dy = match s.anchor().v_pos {
            VPos::Top => 0.72 * size,
            VPos::Center => 0.26 * size,
            VPos::Bottom => -0.21 * size,
        };
        let turn = match s.transform() {
            FontTransform::Rotate90 => Some(90),
            FontTransform::Rotate180 => Some(180),
            FontTransform::Rotate270 => Some(-90),
            FontTransform::None => None,
        };
        let mut doc = self.0.borrow_mut();
        // Turned text is placed by a translation and a rotation about its
        // own origin, which every renderer reads (ImageMagick's own does
        // not read `rotate(a, x, y)`).
        // The baseline is written as a position, not as `dy`, which
        // ImageMagick's renderer misplaces.
        let dy = dy.round() as i32;
        let _ = match turn {
            Some(deg) => write!(
                doc.svg,
                "<text transform=\"translate({},{}) rotate({deg})\" x=\"0\" y=\"{dy}\"",
                pos.0, pos.1
            ),
            None => write!(doc.svg, "<text x=\"{}\" y=\"{}\"", pos.0, pos.1 + dy),
        };
        let _ = write!(
            doc.svg,
            " text-anchor=\"{anchor}\" font-family=\"{}\" font-size=\"{size:.0}\"",
            s.family().as_str(),
        );
        Canvas::fill(&mut doc, color);
        if let plotters_backend::FontStyle::Bold = s.style() {
            doc.svg.push_str(" font-weight=\"bold\"");
        }
        doc.svg.push('>');
        escape(text, &mut doc.svg);
        doc.svg.push_str("</text>\n");
        Ok(())
    }

    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        s: &T,
    ) -> Result<(u32, u32), DrawingErrorKind<std::fmt::Error>> {
        // An average sans-serif character is about 0.55 em wide.
        let w = 0.55 * s.size() * text.chars().count() as f64;
        Ok((w.ceil() as u32, s.size().ceil() as u32))
    }
}

// ---------------------------------------------------------------------------
// The picture.

/// How SVG user units map to the drawing: `z = z0 + (x − px0) / scale`,
/// `r = r0 + (py0 − y) / scale` (mm, X on the radius).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// The Z (mm) at user x `px0`.
    pub z0: f64,
    /// The X radius (mm) at user y `py0`.
    pub r0: f64,
    /// User x of `z0`.
    pub px0: f64,
    /// User y of `r0`.
    pub py0: f64,
    /// User units per mm, both axes.
    pub scale: f64,
}

impl Transform {
    /// A point of the SVG as (Z, X radius) in mm.
    pub fn to_mm(&self, x: f64, y: f64) -> (f64, f64) {
        (
            self.z0 + (x - self.px0) / self.scale,
            self.r0 + (self.py0 - y) / self.scale,
        )
    }
}

/// A drawn picture.
#[derive(Clone, Debug)]
pub struct Plot {
    /// The SVG document.
    pub svg: String,
    /// Its plotting area's mapping, for reading coordinates back.
    pub transform: Transform,
}

/// Why a picture could not be drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotError {
    /// plotters refused a layout or an element.
    Drawing,
}

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("the picture could not be laid out")
    }
}

impl std::error::Error for PlotError {}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(_: DrawingAreaErrorKind<E>) -> PlotError {
        PlotError::Drawing
    }
}

/// The picture's layout, in pixels.
pub(crate) const WIDTH: u32 = 1400;
pub(crate) const PANEL: u32 = 330;
const TITLE: u32 = 56;
pub(crate) const MARGIN: u32 = 14;
/// Above the plotting area: the X axis's title, level (not turned, so that
/// it reads as the ticks do).
const X_TITLE: u32 = 24;
pub(crate) const Y_LABELS: u32 = 78;
pub(crate) const X_LABELS: u32 = 48;
const PLOT_W: u32 = WIDTH - PANEL - Y_LABELS - 2 * MARGIN;
const PLOT_H_MIN: u32 = 420;
const PLOT_H_MAX: u32 = 760;

/// Colours and strokes of the layers.
const PROGRAMMED: RGBColor = RGBColor(30, 30, 30);
pub(crate) const TIP: RGBColor = RGBColor(31, 95, 191);
pub(crate) const CENTRE: RGBColor = RGBColor(224, 112, 0);
const REFUSED: RGBColor = RGBColor(208, 0, 0);
const BLOCKS: RGBColor = RGBColor(142, 68, 173);
pub(crate) const STEPS: RGBColor = RGBColor(0, 140, 120);
pub(crate) const GRID: RGBColor = RGBColor(236, 236, 236);
pub(crate) const DASH: &[u32] = &[9, 5];
const DASH_DOT: &[u32] = &[14, 4, 3, 4];

/// How an axis writes the value at a tick.
pub(crate) type Label<'f> = &'f dyn Fn(&f64) -> String;

/// A chart of the house style on `area`: the margins (`top` above the
/// plotting area), the label areas, the grid, the axes and their labels;
/// `x` along with its description, `y` up.
pub(crate) fn styled_chart<'a>(
    area: &'a DrawingArea<Canvas, Shift>,
    top: u32,
    (x, x_desc, x_fmt): (Axis, &str, Label<'_>),
    (y, y_fmt): (Axis, Label<'_>),
) -> Result<ChartContext<'a, Canvas, Cartesian2d<Axis, Axis>>, PlotError> {
    let mut chart = ChartBuilder::on(area)
        .margin(k(MARGIN))
        .margin_top(k(top))
        .x_label_area_size(k(X_LABELS))
        .y_label_area_size(k(Y_LABELS))
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .x_label_formatter(x_fmt)
        .y_label_formatter(y_fmt)
        .label_style(font(13))
        .axis_desc_style(font(14))
        .bold_line_style(GRID.stroke_width(k(1)))
        .light_line_style(GRID.stroke_width(k(1)))
        .axis_style(BLACK.stroke_width(k(1)))
        .set_all_tick_mark_size(ki(5))
        .draw()?;
    Ok(chart)
}

pub(crate) const fn k(px: u32) -> u32 {
    px * UNITS_PER_PX as u32
}

pub(crate) const fn ki(px: i32) -> i32 {
    px * UNITS_PER_PX
}

/// Sans-serif text `px` pixels high.
pub(crate) fn font(px: u32) -> TextStyle<'static> {
    TextStyle::from(("sans-serif", f64::from(k(px))).into_font())
}

/// The same, bold, in `color`.
pub(crate) fn bold(px: u32, color: &RGBColor) -> TextStyle<'static> {
    ("sans-serif", f64::from(k(px)))
        .into_font()
        .style(FontStyle::Bold)
        .color(color)
}

/// The step of a 1-2-5 series at least `min`.
pub(crate) fn nice_step(min: f64) -> f64 {
    let p = 10f64.powf(min.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s >= min * (1.0 - 1e-9))
        .unwrap_or(10.0 * p)
}

/// Decimals to print multiples of a 1-2-5 step.
pub(crate) fn decimals(step: f64) -> usize {
    (-step.log10() - 1e-9).ceil().max(0.0) as usize
}

/// A tick value with `d` decimals, never `-0`.
pub(crate) fn label(v: f64, d: usize) -> String {
    let s = format!("{v:.d$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// The multiples of `step` within `[a, b]`.
pub(crate) fn multiples(a: f64, b: f64, step: f64) -> Vec<f64> {
    let (i0, i1) = ((a / step).ceil() as i64, (b / step).floor() as i64);
    (i0..=i1).map(|i| i as f64 * step).collect()
}

/// A layer's polylines, clipped to the view and handed to plotters.
struct Layer<'a> {
    class_feed: &'static str,
    class_rapid: &'static str,
    color: RGBColor,
    width: u32,
    lines: &'a [(bool, Vec<P>)],
}

/// An axis in mm with its ticks where this module puts them (plotters'
/// own `WithKeyPoints` cannot take a label formatter over `f64`). It maps
/// to the nearest user unit, not down to it as plotters' `f64` axes do.
#[derive(Clone, Debug)]
pub(crate) struct Axis {
    pub(crate) range: [f64; 2],
    pub(crate) ticks: Vec<f64>,
}

impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let f = (v - self.range[0]) / (self.range[1] - self.range[0]);
        // Saturates far outside the view; what is drawn is clipped first.
        limit.0 + (f64::from(limit.1 - limit.0) * f).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.range[0]..self.range[1]
    }
}

type Chart<'a> = ChartContext<'a, Canvas, Cartesian2d<Axis, Axis>>;

fn draw_layer(
    chart: &mut Chart,
    canvas: &Canvas,
    view: &Rect,
    layer: &Layer,
) -> Result<(), PlotError> {
    for (rapid, pts) in layer.lines {
        let (class, dash) = if *rapid {
            (layer.class_rapid, Some(DASH))
        } else {
            (layer.class_feed, None)
        };
        canvas.pen(class, dash);
        for piece in clipped(pts, view) {
            chart.draw_series(LineSeries::new(
                piece,
                layer.color.stroke_width(k(layer.width)),
            ))?;
        }
    }
    canvas.plain();
    Ok(())
}

/// Draws the picture of `paths` (the steps and blocks too when `zoom` is
/// given), titled `title`.
pub fn render(paths: &Paths, title: &str, zoom: Option<Window>) -> Result<Plot, PlotError> {
    // The view: the zoom window, or everything drawn with a margin.
    let coarse = |path: &[Segment]| polylines(path, 0.01);
    let all = [
        coarse(&paths.programmed),
        coarse(&paths.tip),
        coarse(&paths.centre),
    ];
    let marks: Vec<P> = paths.refused.iter().map(|m| mm(m.at)).collect();
    let wanted = match zoom {
        Some(w) => w.rect(),
        None => {
            let b = bounds(
                all.iter()
                    .flatten()
                    .flat_map(|(_, pts)| pts.iter())
                    .chain(marks.iter()),
            )
            .unwrap_or(Rect {
                z: [-5.0, 5.0],
                r: [0.0, 5.0],
            });
            let pad = 0.04 * b.width().max(b.height()).max(1.0);
            b.grown(pad)
        }
    };
    // Equal scale: px per mm the same on both axes; the plot as wide as the
    // picture allows, as tall as the view needs within limits.
    let s = (f64::from(PLOT_W) / wanted.width()).min(f64::from(PLOT_H_MAX) / wanted.height());
    let plot_h = ((wanted.height() * s).ceil() as u32).clamp(PLOT_H_MIN, PLOT_H_MAX);
    let (cz, cr) = (
        (wanted.z[0] + wanted.z[1]) / 2.0,
        (wanted.r[0] + wanted.r[1]) / 2.0,
    );
    // Plotters maps a range onto the plotting area's first to last user
    // unit: one unit less than its size.
    let units = |px: u32| f64::from(k(px) - 1) / f64::from(UNITS_PER_PX);
    let (hw, hh) = (units(PLOT_W) / s / 2.0, units(plot_h) / s / 2.0);
    let view = Rect {
        z: [cz - hw, cz + hw],
        r: [cr - hh, cr + hh],
    };
    let chart_h = TITLE + X_TITLE + plot_h + X_LABELS + 2 * MARGIN;
    let height = chart_h.max(560);
    let canvas = Canvas::new(WIDTH, height);
    let root = canvas.clone().into_drawing_area();

    // Ticks: Z every nice step of at least 90 px, X diameters every nice
    // step of at least 55 px (on the radius, half the step).
    let z_step = nice_step(90.0 / s);
    let d_step = nice_step(2.0 * 55.0 / s);
    let z_ticks = multiples(view.z[0], view.z[1], z_step);
    let d_ticks = multiples(2.0 * view.r[0], 2.0 * view.r[1], d_step);
    let r_ticks: Vec<f64> = d_ticks.iter().map(|d| d / 2.0).collect();
    let (zd, dd) = (decimals(z_step), decimals(d_step));
    let z_fmt = |z: &f64| label(*z, zd);
    let d_fmt = |r: &f64| label(2.0 * *r, dd);

    let chart_area = root.clone().shrink(
        (0, ki(TITLE as i32)),
        (k(WIDTH - PANEL), k(chart_h - TITLE)),
    );
    let mut chart = styled_chart(
        &chart_area,
        MARGIN + X_TITLE,
        (
            Axis {
                range: view.z,
                ticks: z_ticks,
            },
            "Z (mm)",
            &z_fmt,
        ),
        (
            Axis {
                range: view.r,
                ticks: r_ticks,
            },
            &d_fmt,
        ),
    )?;

    // The transform of the plotting area, from the corners plotters maps.
    let (px0, py0) = chart.backend_coord(&(view.z[0], view.r[0]));
    let (px1, py1) = chart.backend_coord(&(view.z[1], view.r[1]));
    let transform = Transform {
        z0: view.z[0],
        r0: view.r[0],
        px0: f64::from(px0),
        py0: f64::from(py0),
        scale: f64::from(px1 - px0) / view.width(),
    };
    debug_assert!(
        (f64::from(py0 - py1) / view.height() - transform.scale).abs() < 1e-6 * transform.scale,
        "unequal scales"
    );
    chart_area.draw(&Text::new(
        "X as a diameter, Ø (mm)",
        (ki(MARGIN as i32), ki((MARGIN + X_TITLE) as i32 - 8)),
        font(14).pos(Pos::new(HPos::Left, VPos::Bottom)),
    ))?;
    let px_per_mm = transform.scale / f64::from(UNITS_PER_PX);
    // Arcs as polylines no further than 1/20 px from the curve.
    let sag = 0.05 / px_per_mm;

    // The spindle axis, where the view shows it.
    if view.r[0] < 0.0 && view.r[1] > 0.0 {
        canvas.pen("axis", Some(DASH_DOT));
        chart.draw_series(LineSeries::new(
            [(view.z[0], 0.0), (view.z[1], 0.0)],
            RGBColor(120, 120, 120).stroke_width(k(1)),
        ))?;
        canvas.plain();
    }

    if let (Some(_), Some(steps)) = (zoom, &paths.steps) {
        draw_steps(&mut chart, &canvas, &view, steps, px_per_mm)?;
    }

    let layers = [
        (
            &paths.programmed,
            "programmed feed",
            "programmed rapid",
            PROGRAMMED,
            3,
        ),
        (&paths.centre, "centre feed", "centre rapid", CENTRE, 1),
        (&paths.tip, "tip feed", "tip rapid", TIP, 2),
    ];
    for (path, class_feed, class_rapid, color, width) in layers {
        let mut lines = polylines(path, sag);
        if color == CENTRE {
            // The nose centre's rapids are the tip's shifted: drawn once.
            lines.retain(|(rapid, _)| !rapid);
        }
        let layer = Layer {
            class_feed,
            class_rapid,
            color,
            width,
            lines: &lines,
        };
        draw_layer(&mut chart, &canvas, &view, &layer)?;
    }
    draw_arrows(&chart, &canvas, &view, &paths.tip, px_per_mm)?;
    draw_marks(&chart, &canvas, &view, &paths.refused)?;

    // Title, legend and scale.
    root.draw(&Text::new(
        title.to_string(),
        (ki(MARGIN as i32), ki(12)),
        bold(17, &BLACK),
    ))?;
    let what = match zoom {
        Some(w) => format!(
            "zoom: Z {} … {}, X Ø {} … {} mm; machine coordinates, Z to the right, X up, equal scale",
            w.z[0], w.z[1], w.x_diam[0], w.x_diam[1]
        ),
        None => "machine coordinates; Z to the right, X up (ticks: X as a diameter); equal scale"
            .to_string(),
    };
    root.draw(&Text::new(what, (ki(MARGIN as i32), ki(34)), font(13)))?;
    let panel = root.clone().shrink(
        (ki((WIDTH - PANEL) as i32), ki(TITLE as i32)),
        (k(PANEL), k(height - TITLE)),
    );
    draw_panel(&panel, &canvas, paths, zoom.is_some(), px_per_mm)?;
    root.present()?;
    Ok(Plot {
        svg: canvas.finish(),
        transform,
    })
}

/// The zoom's extra layers: the impulse grid when its cells are 10 px or
/// more, the device's blocks (their ends as dots) and the staircase.
fn draw_steps(
    chart: &mut Chart,
    canvas: &Canvas,
    view: &Rect,
    steps: &Steps,
    px_per_mm: f64,
) -> Result<(), PlotError> {
    let (hx, hz) = (
        steps.price[0] as f64 / A_PER_MM,
        steps.price[1] as f64 / A_PER_MM,
    );
    if hx * px_per_mm >= 10.0 && hz * px_per_mm >= 10.0 {
        canvas.pen("impulse-grid", None);
        let grid = RGBColor(215, 230, 228).stroke_width(k(1));
        for z in multiples(view.z[0], view.z[1], hz) {
            chart.draw_series(LineSeries::new([(z, view.r[0]), (z, view.r[1])], grid))?;
        }
        for r in multiples(view.r[0], view.r[1], hx) {
            chart.draw_series(LineSeries::new([(view.z[0], r), (view.z[1], r)], grid))?;
        }
    }
    let at = |p: [i64; 2]| (p[1] as f64 * hz, p[0] as f64 * hx);
    canvas.pen("steps", None);
    for run in &steps.staircase {
        let pts: Vec<P> = run.iter().map(|p| at(*p)).collect();
        for piece in clipped(&pts, view) {
            chart.draw_series(LineSeries::new(piece, STEPS.stroke_width(k(1))))?;
        }
    }
    canvas.pen("blocks", None);
    let mut ends: Vec<P> = Vec::new();
    for [a, b] in &steps.blocks {
        if let Some((p, q)) = clip(at(*a), at(*b), view) {
            chart.draw_series(LineSeries::new([p, q], BLOCKS.stroke_width(k(1))))?;
            for e in [at(*a), at(*b)] {
                if view.contains(e) {
                    ends.push(e);
                }
            }
        }
    }
    ends.dedup();
    if ends.len() <= 5000 {
        canvas.pen("block-ends", None);
        chart.draw_series(ends.iter().map(|p| Circle::new(*p, k(3), BLOCKS.filled())))?;
    }
    canvas.plain();
    Ok(())
}

/// The direction of travel: an arrowhead in the middle of every tool-tip
/// block at least 60 px long (at most 400), and a ring where the program
/// starts.
fn draw_arrows(
    chart: &Chart,
    canvas: &Canvas,
    view: &Rect,
    tip: &[Segment],
    px_per_mm: f64,
) -> Result<(), PlotError> {
    let area = chart.plotting_area();
    canvas.pen("arrow", None);
    let mut drawn = 0;
    for s in tip {
        let (a, b) = (mm(s.from), mm(s.to));
        // The middle and the direction there (Z, X radius).
        let (mid, dir, len) = match s.kind {
            MoveKind::Arc { centre, dir } => {
                let mut pts = vec![a];
                points(s, 0.2 / px_per_mm, &mut pts);
                let len: f64 = pts
                    .windows(2)
                    .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
                    .sum();
                let c = mm(centre);
                // A full circle's middle is its start: a quarter on.
                let at = if s.from == s.to { 4 } else { 2 };
                let m = pts[pts.len() / at];
                let t = match dir {
                    ArcDir::Ccw => (-(m.1 - c.1), m.0 - c.0),
                    ArcDir::Cw => (m.1 - c.1, -(m.0 - c.0)),
                };
                (m, t, len)
            }
            MoveKind::Line { .. } => (
                ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0),
                (b.0 - a.0, b.1 - a.1),
                (b.0 - a.0).hypot(b.1 - a.1),
            ),
        };
        if len * px_per_mm < 60.0 || !view.contains(mid) {
            continue;
        }
        drawn += 1;
        if drawn > 400 {
            break;
        }
        // In user units, y down.
        let n = dir.0.hypot(dir.1);
        let (ux, uy) = (dir.0 / n, -dir.1 / n);
        let at = |along: f64, across: f64| {
            let u = f64::from(UNITS_PER_PX);
            (
                ((ux * along - uy * across) * u).round() as i32,
                ((uy * along + ux * across) * u).round() as i32,
            )
        };
        area.draw(
            &(EmptyElement::at(mid)
                + Polygon::new(
                    vec![at(6.0, 0.0), at(-5.0, 4.5), at(-5.0, -4.5)],
                    TIP.filled(),
                )),
        )?;
    }
    if let Some(first) = tip.first() {
        let p = mm(first.from);
        if view.contains(p) {
            canvas.pen("start", None);
            area.draw(
                &(EmptyElement::at(p)
                    + Circle::new((0, 0), k(5), BLACK.stroke_width(k(2)))
                    + Rectangle::new(
                        [(ki(7), ki(5)), (ki(44), ki(21))],
                        RGBAColor(255, 255, 255, 0.85).filled(),
                    )
                    + Text::new(
                        "start".to_string(),
                        (ki(9), ki(6)),
                        font(12).pos(Pos::new(HPos::Left, VPos::Top)),
                    )),
            )?;
        }
    }
    canvas.plain();
    Ok(())
}

/// The refused lines: a red ring where the tool stood, its line numbers
/// beside it (several at one point share a label; labels step down where
/// they would overlap).
fn draw_marks(
    chart: &Chart,
    canvas: &Canvas,
    view: &Rect,
    refused: &[Mark],
) -> Result<(), PlotError> {
    let mut at: Vec<([i64; 2], Vec<usize>)> = Vec::new();
    for m in refused {
        match at.iter_mut().find(|(p, _)| *p == m.at) {
            Some((_, lines)) => {
                if !lines.contains(&m.line) {
                    lines.push(m.line);
                }
            }
            None => at.push((m.at, vec![m.line])),
        }
    }
    let area = chart.plotting_area();
    // Label boxes placed so far: their upper left corners (user units).
    let mut placed: Vec<(i32, i32, i32)> = Vec::new();
    canvas.pen("refused", None);
    for (p, lines) in &at {
        let p = mm(*p);
        if !view.contains(p) {
            continue;
        }
        let text = if lines.len() == 1 {
            format!("line {}", lines[0])
        } else {
            let shown: Vec<String> = lines.iter().take(6).map(usize::to_string).collect();
            let more = if lines.len() > 6 { ", …" } else { "" };
            format!("lines {}{more}", shown.join(", "))
        };
        let (x, y) = chart.backend_coord(&p);
        let w = ki(8 * text.chars().count() as i32 + 6);
        let (dx, mut dy) = (ki(10), ki(-26));
        while placed.iter().any(|(px, py, pw)| {
            (y + dy - py).abs() < ki(19) && x + dx < px + pw && *px < x + dx + w
        }) {
            dy += ki(19);
        }
        placed.push((x + dx, y + dy, w));
        area.draw(
            &(EmptyElement::at(p)
                + Circle::new((0, 0), k(7), REFUSED.stroke_width(k(2)))
                + Rectangle::new(
                    [(dx, dy), (dx + w, dy + ki(18))],
                    RGBAColor(255, 255, 255, 0.85).filled(),
                )
                + Text::new(text, (dx + ki(3), dy + ki(2)), font(13).color(&REFUSED))),
        )?;
    }
    canvas.plain();
    Ok(())
}

/// The panel on the right: the legend, the tools, the scale bar, the
/// refusals.
fn draw_panel(
    panel: &DrawingArea<Canvas, Shift>,
    canvas: &Canvas,
    paths: &Paths,
    zoom: bool,
    px_per_mm: f64,
) -> Result<(), PlotError> {
    let x0 = ki(16);
    let mut y = ki(24);
    let line = |panel: &DrawingArea<Canvas, Shift>,
                y: i32,
                color: RGBColor,
                width: u32,
                dash: Option<&'static [u32]>,
                class: &'static str|
     -> Result<(), PlotError> {
        canvas.pen(class, dash);
        panel.draw(&PathElement::new(
            vec![(x0, y), (x0 + ki(44), y)],
            color.stroke_width(k(width)),
        ))?;
        canvas.plain();
        Ok(())
    };
    let text = |panel: &DrawingArea<Canvas, Shift>,
                s: &str,
                x: i32,
                y: i32,
                style: TextStyle|
     -> Result<(), PlotError> {
        panel.draw(&Text::new(
            s.to_string(),
            (x, y),
            style.pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
        Ok(())
    };
    text(panel, "Legend", x0, y, bold(15, &BLACK))?;
    y += ki(28);
    let entries = [
        ("part as programmed", PROGRAMMED, 3, "legend programmed"),
        ("tool tip (TTT), as the device ran it", TIP, 2, "legend tip"),
        ("nose centre (its feeds)", CENTRE, 1, "legend centre"),
    ];
    for (name, color, width, class) in entries {
        line(panel, y, color, width, None, class)?;
        text(panel, name, x0 + ki(54), y, font(13))?;
        y += ki(22);
    }
    line(panel, y, RGBColor(90, 90, 90), 2, None, "legend feed")?;
    text(panel, "feed (G01, G02, G03)", x0 + ki(54), y, font(13))?;
    y += ki(22);
    line(
        panel,
        y,
        RGBColor(90, 90, 90),
        2,
        Some(DASH),
        "legend rapid",
    )?;
    text(panel, "rapid (G00)", x0 + ki(54), y, font(13))?;
    y += ki(22);
    canvas.pen("legend refused", None);
    panel.draw(&Circle::new(
        (x0 + ki(22), y),
        k(7),
        REFUSED.stroke_width(k(2)),
    ))?;
    canvas.plain();
    text(panel, "refused line (its number)", x0 + ki(54), y, font(13))?;
    y += ki(22);
    canvas.pen("legend arrow", None);
    panel.draw(&Polygon::new(
        vec![
            (x0 + ki(28), y),
            (x0 + ki(17), y - ki(5)),
            (x0 + ki(17), y + ki(5)),
        ],
        TIP.filled(),
    ))?;
    panel.draw(&Circle::new(
        (x0 + ki(22), y + ki(22)),
        k(5),
        BLACK.stroke_width(k(2)),
    ))?;
    canvas.plain();
    text(panel, "direction of travel", x0 + ki(54), y, font(13))?;
    y += ki(22);
    text(
        panel,
        "start (machine position at power-on)",
        x0 + ki(54),
        y,
        font(13),
    )?;
    y += ki(22);
    if zoom {
        line(panel, y, BLOCKS, 1, None, "legend blocks")?;
        panel.draw(&Circle::new((x0 + ki(44), y), k(3), BLOCKS.filled()))?;
        text(
            panel,
            "device blocks: arcs by chords",
            x0 + ki(54),
            y,
            font(13),
        )?;
        y += ki(22);
        line(panel, y, STEPS, 1, None, "legend steps")?;
        text(panel, "impulse steps", x0 + ki(54), y, font(13))?;
        y += ki(22);
        if let Some(st) = &paths.steps {
            let p = |a: i64| label(a as f64 / A_PER_MM, 4);
            text(
                panel,
                &format!(
                    "impulse: X {} mm (radius), Z {} mm",
                    p(st.price[0]),
                    p(st.price[1])
                ),
                x0,
                y,
                font(12),
            )?;
            y += ki(20);
        }
    }
    y += ki(10);
    // The tools.
    for n in paths.noses.iter().take(6) {
        let r = label(n.r as f64 / A_PER_MM, 3);
        let on = if n.r == 0 || n.tip == 0 || n.tip == 9 {
            " (centre on the tip)"
        } else {
            ""
        };
        text(
            panel,
            &format!("nose R{r} mm, tip code {}{on}", n.tip),
            x0,
            y,
            font(12),
        )?;
        y += ki(20);
    }
    y += ki(14);
    // The scale bar: a 1-2-5 length of 60 to 150 px.
    let len = nice_step(60.0 / px_per_mm);
    let w = (len * px_per_mm * f64::from(UNITS_PER_PX)).round() as i32;
    canvas.pen("scale-bar", None);
    panel.draw(&PathElement::new(
        vec![(x0, y - ki(5)), (x0, y), (x0 + w, y), (x0 + w, y - ki(5))],
        BLACK.stroke_width(k(2)),
    ))?;
    canvas.plain();
    text(
        panel,
        &format!("{} mm", label(len, decimals(len))),
        x0 + w + ki(8),
        y - ki(2),
        font(13),
    )?;
    y += ki(18);
    text(
        panel,
        &format!(
            "scale {} px per mm, both axes",
            label(
                px_per_mm,
                (3 - px_per_mm.log10().floor() as i64).max(0) as usize
            )
        ),
        x0,
        y,
        font(12),
    )?;
    y += ki(30);
    if !paths.refused.is_empty() {
        text(
            panel,
            &format!("Refused lines: {}", paths.refused.len()),
            x0,
            y,
            bold(13, &REFUSED),
        )?;
        y += ki(20);
        for m in paths.refused.iter().take(10) {
            let mut s = format!("{}: {}", m.line, m.reply.trim_start_matches("ERR "));
            if s.chars().count() > 44 {
                s = s.chars().take(43).collect::<String>() + "…";
            }
            text(panel, &s, x0, y, font(12).color(&REFUSED))?;
            y += ki(18);
        }
        if paths.refused.len() > 10 {
            text(panel, "…", x0, y, font(12).color(&REFUSED))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::program::{run_setup, Traced};
    use reference::comp::CompSettings;

    const FIG22: &str = include_str!("../../examples/krylenko-fig22.nc");
    const FIG12: &str = include_str!("../../examples/krylenko-fig12.nc");

    fn options(dialect: Dialect, zoom: Option<Window>) -> Options {
        Options {
            program: program::Options {
                dialect,
                radius: false,
                optional_stop: false,
            },
            zoom,
        }
    }

    /// The value of attribute `name` in an element's text.
    fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
        let key = format!(" {name}=\"");
        let at = element.find(&key)? + key.len();
        let len = element[at..].find('"')?;
        Some(&element[at..at + len])
    }

    /// A polyline of the SVG: its class, whether dashed, its points (user
    /// units).
    type Drawn = (String, bool, Vec<(f64, f64)>);

    /// The SVG's polylines in document order.
    fn polylines_in(svg: &str) -> Vec<Drawn> {
        svg.lines()
            .filter(|l| l.starts_with("<polyline "))
            .map(|l| {
                let pts = attr(l, "points")
                    .unwrap_or("")
                    .split(' ')
                    .filter_map(|p| {
                        let (x, y) = p.split_once(',')?;
                        Some((x.parse().ok()?, y.parse().ok()?))
                    })
                    .collect();
                (
                    attr(l, "data-layer").unwrap_or("").to_string(),
                    attr(l, "stroke-dasharray").is_some(),
                    pts,
                )
            })
            .collect()
    }

    /// Whether `p` (mm) lies on segment `s` within `tol` mm.
    fn on(s: &Segment, p: P, tol: f64) -> bool {
        let (a, b) = (mm(s.from), mm(s.to));
        match s.kind {
            MoveKind::Line { .. } => {
                let (dz, dr) = (b.0 - a.0, b.1 - a.1);
                let l2 = dz * dz + dr * dr;
                let t = if l2 == 0.0 {
                    0.0
                } else {
                    (((p.0 - a.0) * dz + (p.1 - a.1) * dr) / l2).clamp(0.0, 1.0)
                };
                (a.0 + t * dz - p.0).hypot(a.1 + t * dr - p.1) <= tol
            }
            MoveKind::Arc { centre, .. } => {
                let c = mm(centre);
                let (r0, r1) = ((a.0 - c.0).hypot(a.1 - c.1), (b.0 - c.0).hypot(b.1 - c.1));
                let r = (p.0 - c.0).hypot(p.1 - c.1);
                r >= r0.min(r1) - tol && r <= r0.max(r1) + tol
            }
        }
    }

    /// Every vertex of the polylines of `class` mapped back lies on the
    /// path, and every end point of the path is a vertex, in order.
    fn assert_drawn(plot: &Plot, class: &str, path: &[Segment]) {
        let t = plot.transform;
        // Three quarters of a user unit: the mapping rounds to the nearest.
        let tol = 0.75 / t.scale;
        let lines: Vec<Vec<P>> = polylines_in(&plot.svg)
            .into_iter()
            .filter(|(c, _, _)| c.split(' ').next() == Some(class))
            .map(|(_, _, pts)| pts.iter().map(|(x, y)| t.to_mm(*x, *y)).collect())
            .collect();
        assert!(!lines.is_empty(), "no {class} polylines");
        let near = |p: P, q: [i64; 2]| {
            let q = mm(q);
            (p.0 - q.0).hypot(p.1 - q.1) <= tol
        };
        let mut k = 0;
        for line in &lines {
            for (i, p) in line.iter().enumerate() {
                if i == 0 {
                    assert!(
                        k < path.len() && near(*p, path[k].from)
                            || k > 0 && near(*p, path[k - 1].to),
                        "{class}: a polyline starts at {p:?}, not at block {k}'s start"
                    );
                    continue;
                }
                assert!(k < path.len(), "{class}: vertex {p:?} after the last block");
                assert!(
                    on(&path[k], *p, tol),
                    "{class}: {p:?} is not on block {k}: {:?}",
                    path[k]
                );
                // Past its end (and any block shorter than the precision).
                while k < path.len() && near(*p, path[k].to) {
                    k += 1;
                }
            }
        }
        assert_eq!(k, path.len(), "{class}: blocks {k}.. not drawn");
    }

    fn same_as_report(tip: &[Segment], path: &[Traced]) {
        assert_eq!(tip.len(), path.len());
        for (s, t) in tip.iter().zip(path) {
            assert_eq!(s.to, t.to);
            let (g, centre) = match s.kind {
                MoveKind::Line { rapid } => (u8::from(!rapid), None),
                MoveKind::Arc { centre, dir } => {
                    (if dir == ArcDir::Ccw { 3 } else { 2 }, Some(centre))
                }
            };
            assert_eq!((g, centre), (t.g, t.centre));
        }
    }

    #[test]
    fn plot_draws_the_devices_paths_exactly() {
        // Krylenko's Fig. 22 (G42, R arcs both ways) and random G42
        // contours with every tip code.
        let mut cases = vec![(FIG22.to_string(), Dialect::Fanuc, Vec::<String>::new())];
        for c in crate::contour::random_contours(1977, 6) {
            let setup = vec![format!("CFG RN={} TIP={}", c.rn, c.tip)];
            cases.push((c.lines.join("\n"), Dialect::Iso, setup));
        }
        for (text, dialect, setup) in &cases {
            let setup: Vec<(usize, &str)> = setup.iter().map(|s| (1, s.as_str())).collect();
            let paths = trace(text, &options(dialect.to_owned(), None), &setup);
            assert!(
                paths.refused.is_empty() && paths.notes.is_empty(),
                "{paths:?}"
            );
            let report = run_setup(text, options(*dialect, None).program, &setup);
            same_as_report(&paths.tip, &report.path);
            assert!(
                paths
                    .tip
                    .iter()
                    .any(|s| matches!(s.kind, MoveKind::Arc { .. }))
                    || !text.contains("G0")
            );
            let plot = render(&paths, "test", None).unwrap();
            assert_drawn(&plot, "tip", &paths.tip);
            assert_drawn(&plot, "programmed", &paths.programmed);
            let feeds: Vec<Segment> = paths
                .centre
                .iter()
                .filter(|s| !s.rapid())
                .copied()
                .collect();
            // The nose centre's feeds only: check each run of them.
            let plot_feeds = |s: &Segment| !s.rapid();
            assert!(paths.centre.iter().any(plot_feeds));
            let mut runs: Vec<Vec<Segment>> = Vec::new();
            for s in &paths.centre {
                match (s.rapid(), runs.last_mut()) {
                    (true, _) => runs.push(Vec::new()),
                    (false, Some(run)) => run.push(*s),
                    (false, None) => runs.push(vec![*s]),
                }
            }
            let joined: Vec<Segment> = runs.concat();
            assert_eq!(joined, feeds);
            assert_drawn(&plot, "centre", &feeds);
        }
    }

    #[test]
    fn plot_programmed_contour_is_the_program_without_compensation() {
        let paths = trace(FIG22, &options(Dialect::Fanuc, None), &[]);
        // The same program with G42/G40 taken out: the TTT on the drawing.
        let plain = FIG22.replace("G42 ", "").replace("G40 ", "");
        let uncompensated = trace(&plain, &options(Dialect::Fanuc, None), &[]);
        assert_eq!(paths.programmed, uncompensated.tip);
        // Point 3 of the drawing, X12 Z-2, is an end.
        assert!(paths
            .programmed
            .iter()
            .any(|s| s.to == [60_000_000, -20_000_000]));
        assert!(!paths.tip.iter().any(|s| s.to == [60_000_000, -20_000_000]));
    }

    #[test]
    fn plot_nose_centre_is_the_devices_for_tip_code_0() {
        // With compensation on, the device moves the nose centre itself
        // when the tip code is 0: the centre path of tip code 3 is that.
        let paths = trace(FIG22, &options(Dialect::Fanuc, None), &[]);
        let centre_run = trace(FIG22, &options(Dialect::Fanuc, None), &[(1, "CFG TIP=0")]);
        assert_eq!(
            paths.noses,
            [Nose {
                r: 4_000_000,
                tip: 3
            }]
        );
        assert_eq!(
            centre_run.noses,
            [Nose {
                r: 4_000_000,
                tip: 0
            }]
        );
        assert_eq!(paths.tip.len(), 11);
        // Blocks 2 (the start-up) to 9 end compensated; 0, 1 are the
        // approach and 10 the G40 exit, on the programmed points.
        assert_eq!(&paths.centre[3..10], &centre_run.tip[3..10]);
        assert_eq!(paths.centre[2].to, centre_run.tip[2].to);
        // The table is the reference's.
        for tip in 0..=9 {
            let r = CompSettings {
                rn_mm: 0.4,
                tip,
                diam: true,
            }
            .tip_vector();
            let v = Nose { r: 4_000_000, tip }.tip_vector();
            assert_eq!(
                [v[0] as f64 / 1e7, v[1] as f64 / 1e7],
                [r.0, r.1],
                "tip {tip}"
            );
        }
        // A register's nose, as the device selects it (Fanuc T0202).
        let program = FIG12.replace("T0101", "T0202");
        let paths = trace(
            &program,
            &options(Dialect::Fanuc, None),
            &[(1, "TOOL N=2 R=0.8 T=2")],
        );
        assert_eq!(
            paths.noses,
            [Nose {
                r: 8_000_000,
                tip: 2
            }]
        );
        // ISO: the tool M06 loads.
        let iso = "G21 G18\nT3 M6\nG00 X20 Z2\nG01 Z-5 F100\n";
        let paths = trace(
            iso,
            &options(Dialect::Iso, None),
            &[(1, "TOOL N=3 R=1.2 T=8")],
        );
        assert_eq!(
            paths.noses,
            [Nose {
                r: 12_000_000,
                tip: 8
            }]
        );
        assert_eq!(paths.centre[1].to, [100_000_000 + 12_000_000, -50_000_000]);
    }

    #[test]
    fn plot_rapids_are_dashed_and_feeds_solid() {
        let paths = trace(FIG12, &options(Dialect::Fanuc, None), &[]);
        let plot = render(&paths, "fig12", None).unwrap();
        let lines = polylines_in(&plot.svg);
        let mut seen = [0; 2];
        for (class, dashed, _) in &lines {
            if class.ends_with(" rapid") {
                assert!(dashed, "{class}");
                seen[0] += 1;
            } else if class.ends_with(" feed") {
                assert!(!dashed, "{class}");
                seen[1] += 1;
            }
        }
        assert!(seen[0] >= 2 && seen[1] >= 2, "{seen:?}");
        // The legend says which is which.
        assert!(plot.svg.contains(">rapid (G00)</text>"));
        assert!(polylines_in(&plot.svg)
            .iter()
            .any(|(c, dashed, _)| c == "legend rapid" && *dashed));
        // X is read as a diameter: the 20 tick sits at radius 10.
        let tick = plot
            .svg
            .lines()
            .find(|l| {
                l.starts_with("<text")
                    && l.contains("text-anchor=\"end\"")
                    && l.ends_with(">20</text>")
            })
            .unwrap();
        let y: f64 = attr(tick, "y").unwrap().parse().unwrap();
        let (_, r) = plot.transform.to_mm(0.0, y - 0.26 * f64::from(k(13)));
        assert!((r - 10.0).abs() < 1.0 / plot.transform.scale, "{r}");
    }

    #[test]
    fn plot_marks_refused_lines_where_the_tool_stood() {
        let program = "G21 G18\nG00 X20 Z2\nG01 Z-10 F100\nG76 P010060 Q100 R.05\nG01 X30\n";
        let paths = trace(program, &options(Dialect::Fanuc, None), &[]);
        assert_eq!(paths.refused.len(), 1);
        let m = &paths.refused[0];
        assert_eq!((m.line, m.at), (4, [100_000_000, -100_000_000]));
        let plot = render(&paths, "refused", None).unwrap();
        let ring = plot
            .svg
            .lines()
            .find(|l| l.starts_with("<circle") && l.contains("data-layer=\"refused\""))
            .unwrap();
        let (x, y): (f64, f64) = (
            attr(ring, "cx").unwrap().parse().unwrap(),
            attr(ring, "cy").unwrap().parse().unwrap(),
        );
        let (z, r) = plot.transform.to_mm(x, y);
        let tol = 0.75 / plot.transform.scale;
        assert!((z + 10.0).abs() < tol && (r - 10.0).abs() < tol, "{z} {r}");
        assert!(plot.svg.contains(">line 4</text>"));
        assert!(plot
            .svg
            .contains("4: VALUE G76 canned cycles not supported"));
    }

    #[test]
    fn plot_zoom_shows_the_chords_and_the_staircase() {
        // The G02 arc of the tool tip in Fig. 22: centre X17.2 Z-14.4
        // (diameter), radius 2.6.
        let window: Window = "-16.45,13.25,-16.05,13.75".parse().unwrap();
        let paths = trace(FIG22, &options(Dialect::Fanuc, Some(window)), &[]);
        let steps = paths.steps.as_ref().unwrap();
        let report = run_setup(FIG22, options(Dialect::Fanuc, None).program, &[]);
        assert_eq!(steps.events, report.events);
        assert_eq!(steps.price, [50_000, 100_000]);
        let plot = render(&paths, "zoom", Some(window)).unwrap();
        let t = plot.transform;
        let stairs: Vec<Vec<P>> = polylines_in(&plot.svg)
            .into_iter()
            .filter(|(c, _, _)| c == "steps")
            .map(|(_, _, pts)| pts.iter().map(|(x, y)| t.to_mm(*x, *y)).collect())
            .collect();
        let n: usize = stairs.iter().map(Vec::len).sum();
        assert!(n > 40, "{n} step vertices");
        // Each step is one impulse on one axis or on both; all of them
        // within the chord tolerance (0.01 mm) and an impulse of the arc.
        let (hx, hz) = (0.005, 0.01);
        let tol = 0.75 / t.scale;
        let centre = (-14.4, 8.6);
        // Inside the window less an impulse: no step cut by the view's edge.
        let inner = Rect {
            z: [window.z[0] + hz, window.z[1] - hz],
            r: [window.x_diam[0] / 2.0 + hx, window.x_diam[1] / 2.0 - hx],
        };
        for run in &stairs {
            for w in run
                .windows(2)
                .filter(|w| inner.contains(w[0]) && inner.contains(w[1]))
            {
                let (dz, dr) = ((w[1].0 - w[0].0).abs(), (w[1].1 - w[0].1).abs());
                // A difference of two rounded values: within one unit.
                let one = |d: f64, h: f64| d <= 2.0 * tol || (d - h).abs() <= 2.0 * tol;
                assert!(one(dz, hz) && one(dr, hx) && dz + dr > tol, "{w:?}");
            }
            for p in run.iter().filter(|p| window.rect().contains(**p)) {
                let r = (p.0 - centre.0).hypot(p.1 - centre.1);
                assert!((r - 2.6).abs() < 0.01 + hz, "{p:?} {r}");
            }
        }
        // The chord and the exact arc, smooth (many vertices).
        assert!(polylines_in(&plot.svg)
            .iter()
            .any(|(c, _, _)| c == "blocks"));
        let arc = polylines_in(&plot.svg)
            .into_iter()
            .filter(|(c, _, _)| c == "tip feed")
            .max_by_key(|(_, _, pts)| pts.len())
            .unwrap()
            .2;
        assert!(arc.len() > 10, "{arc:?}");
        for (x, y) in arc {
            let p = t.to_mm(x, y);
            let r = (p.0 - centre.0).hypot(p.1 - centre.1);
            assert!((r - 2.6).abs() <= tol, "{p:?} {r}");
        }
    }

    #[test]
    fn plot_clips_polylines_to_the_view() {
        let r = Rect {
            z: [0.0, 10.0],
            r: [0.0, 10.0],
        };
        let pieces = clipped(
            &[
                (-5.0, 5.0),
                (5.0, 5.0),
                (5.0, 15.0),
                (15.0, 15.0),
                (15.0, 5.0),
                (8.0, 5.0),
            ],
            &r,
        );
        assert_eq!(
            pieces,
            [
                vec![(0.0, 5.0), (5.0, 5.0), (5.0, 10.0)],
                vec![(10.0, 5.0), (8.0, 5.0)]
            ]
        );
        assert_eq!(nice_step(0.7), 1.0);
        assert_eq!(nice_step(1.2), 2.0);
        assert_eq!(nice_step(0.003), 0.005);
        assert_eq!((decimals(0.5), decimals(2.0), decimals(0.05)), (1, 0, 2));
        assert_eq!(label(-0.0001, 2), "0.00");
    }
}

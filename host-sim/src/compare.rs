//! Bit-for-bit comparison of the device against the f64 reference.
//!
//! Every step of a scenario goes to the device over a [`Transport`] and to
//! the [`RefMachine`]; for every block the device's `NX`, `NZ`, `PX`, `PZ` and
//! `SEQ` must equal the reference's. Every block also goes to the
//! [`RefMotion`], and at every `SYNC` the device's `EV`, `T` and `TSEQ`
//! (the CRC of every step event with its tick) must equal the reference's:
//! the time of every step event is compared. The tally keeps how close the
//! rounding decisions came to a tie (`docs/verification.md` §2), so the margin is visible.

use crate::link::{LinkError, Reply, Transport};
use reference::arc::{ChordCoord, RefArc, RefArcError, RefDirect};
use reference::impulse::{RefBlock, RefConfig, RefMachine, TieStats};
use reference::motion::{MotionLimits, Point, RefMotion};
use std::fmt::Write as _;

/// One request of a scenario.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// `CFG` with the impulse prices and diameter mode (words as written).
    Cfg {
        /// `HX=`, mm.
        hx: Option<String>,
        /// `HZ=`, mm.
        hz: Option<String>,
        /// `DIAM=`.
        diam: Option<bool>,
    },
    /// `ZERO`.
    Zero,
    /// `ARC`, words as written.
    Arc {
        /// End `X=` (a diameter when DIAM=1).
        x: String,
        /// End `Z=`.
        z: String,
        /// `I=`, start to centre on X (radius value).
        i: String,
        /// `K=`, start to centre on Z.
        k: String,
        /// `DIR=CCW` (else CW).
        ccw: bool,
        /// `TOL=` if named.
        tol: Option<String>,
        /// `PASS=ROUGH` (true) or `PASS=FIN` (false) if named.
        rough: Option<bool>,
        /// `MODE=DIRECT`.
        direct: bool,
        /// `F=`, mm/min: the feed along the chords, or the ЭМ-907 feed word
        /// of a direct arc.
        feed: Option<String>,
    },
    /// `MOVE`, words as written.
    Move {
        /// `X=` (a diameter when DIAM=1).
        x: Option<String>,
        /// `Z=`.
        z: Option<String>,
        /// `INC=1`.
        inc: bool,
        /// `F=`, mm/min (rapid when `None`).
        feed: Option<String>,
    },
    /// `SYNC`: everything queued runs; its events and ticks are compared.
    Sync,
}

impl Step {
    /// Whether the step asks for motion (`MOVE`, `ARC`).
    pub fn is_motion(&self) -> bool {
        matches!(self, Step::Move { .. } | Step::Arc { .. })
    }

    /// An absolute move.
    pub fn to(x: impl Into<String>, z: impl Into<String>) -> Step {
        Step::Move {
            x: Some(x.into()),
            z: Some(z.into()),
            inc: false,
            feed: None,
        }
    }

    /// An absolute move at a feed (mm/min).
    pub fn feed_to(x: impl Into<String>, z: impl Into<String>, feed: &str) -> Step {
        Step::Move {
            x: Some(x.into()),
            z: Some(z.into()),
            inc: false,
            feed: Some(feed.into()),
        }
    }

    /// The request line.
    pub fn request(&self) -> String {
        let mut line = String::new();
        match self {
            Step::Cfg { hx, hz, diam } => {
                line.push_str("CFG");
                if let Some(v) = hx {
                    let _ = write!(line, " HX={v}");
                }
                if let Some(v) = hz {
                    let _ = write!(line, " HZ={v}");
                }
                if let Some(d) = diam {
                    let _ = write!(line, " DIAM={}", u8::from(*d));
                }
            }
            Step::Zero => line.push_str("ZERO"),
            Step::Arc {
                x,
                z,
                i,
                k,
                ccw,
                tol,
                rough,
                direct,
                feed,
            } => {
                let dir = if *ccw { "CCW" } else { "CW" };
                let _ = write!(line, "ARC X={x} Z={z} I={i} K={k} DIR={dir}");
                if let Some(t) = tol {
                    let _ = write!(line, " TOL={t}");
                }
                if let Some(r) = rough {
                    line.push_str(if *r { " PASS=ROUGH" } else { " PASS=FIN" });
                }
                if *direct {
                    line.push_str(" MODE=DIRECT");
                }
                if let Some(f) = feed {
                    let _ = write!(line, " F={f}");
                }
            }
            Step::Move { x, z, inc, feed } => {
                line.push_str("MOVE");
                if let Some(v) = x {
                    let _ = write!(line, " X={v}");
                }
                if let Some(v) = z {
                    let _ = write!(line, " Z={v}");
                }
                if *inc {
                    line.push_str(" INC=1");
                }
                if let Some(f) = feed {
                    let _ = write!(line, " F={f}");
                }
            }
            Step::Sync => line.push_str("SYNC"),
        }
        line
    }
}

/// A named list of steps.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Shown in the report.
    pub name: String,
    /// The requests, in order.
    pub steps: Vec<Step>,
}

impl Scenario {
    /// Number of `MOVE` and `ARC` steps.
    pub fn blocks(&self) -> usize {
        self.steps.iter().filter(|s| s.is_motion()).count()
    }
}

/// A difference between the device and the reference.
#[derive(Clone, Debug)]
pub struct Mismatch {
    /// Scenario name.
    pub scenario: String,
    /// Index of the step in its scenario.
    pub index: usize,
    /// The request sent.
    pub request: String,
    /// What the device replied (final line).
    pub device: String,
    /// What the reference expected.
    pub expected: String,
}

/// Running totals of a comparison.
#[derive(Clone, Debug)]
pub struct Tally {
    /// Blocks compared.
    pub blocks: u64,
    /// Step events in those blocks.
    pub events: u64,
    /// Impulses issued, summed over axes, absolute.
    pub impulses: u64,
    /// Differences found.
    pub mismatches: Vec<Mismatch>,
    /// Ties of the quantizer `Q(P/h)`.
    pub quantizer: TieStats,
    /// Ties of the interleaver `Q(i·Δb/|Δlead|)`.
    pub interleave: TieStats,
    /// Arcs by chords compared (each chord also counts as a block).
    pub arcs: u64,
    /// Direct arcs compared (each also counts as a block).
    pub direct_arcs: u64,
    /// Arcs refused alike by device and reference.
    pub refused_alike: u64,
    /// Worst chord error of a finishing arc, as a fraction of its tolerance.
    pub worst_chord_error: f64,
    /// Worst radial deviation of a direct-mode step, in impulses of the
    /// coarser axis.
    pub worst_direct_deviation: f64,
    /// Nearest the exact Δφ came to a whole arc-second (floor/ceil decision).
    pub dphi_margin: f64,
    /// Nearest sweep/Δφ came to a whole number (chord count decision).
    pub n_margin: f64,
    /// Step events whose ticks were compared (through `SYNC`).
    pub timed: u64,
    /// `SYNC` replies compared.
    pub syncs: u64,
    /// Runs and their total length, ticks.
    pub runs: u64,
    /// Rounding decisions of the event ticks `Q(T·TICK)`.
    pub ticks: TieStats,
    /// The longest `T` a `SYNC` reported, ticks.
    pub longest_run: u64,
    /// Chord ends rounded to the 10⁻⁷ mm grid for timing: distance of the
    /// computed point from a rounding tie, units of 10⁻⁷ mm.
    pub chord_grid: TieStats,
}

impl Default for Tally {
    fn default() -> Self {
        Tally {
            blocks: 0,
            events: 0,
            impulses: 0,
            mismatches: Vec::new(),
            quantizer: TieStats::new(),
            interleave: TieStats::new(),
            arcs: 0,
            direct_arcs: 0,
            refused_alike: 0,
            worst_chord_error: 0.0,
            worst_direct_deviation: 0.0,
            dphi_margin: f64::INFINITY,
            n_margin: f64::INFINITY,
            timed: 0,
            syncs: 0,
            runs: 0,
            ticks: TieStats::new(),
            longest_run: 0,
            chord_grid: TieStats::new(),
        }
    }
}

impl Tally {
    /// The smallest distance to a rounding tie over all values that were not
    /// exact ties, in impulses.
    pub fn min_tie_distance(&self) -> f64 {
        self.quantizer
            .min_distance
            .min(self.interleave.min_distance)
    }

    /// Exact ties met, over both sources.
    pub fn exact_ties(&self) -> u64 {
        self.quantizer.exact_ties + self.interleave.exact_ties
    }

    /// The time line of the report.
    pub fn time_line(&self) -> String {
        format!(
            "time: {} step events timed in {} runs, {} SYNC compared; {} exact half-tick ties decided up, nearest non-tie {} ticks from a tie; chord ends on the 1e-7 mm grid: nearest {} units from a rounding tie",
            self.timed,
            self.runs,
            self.syncs,
            self.ticks.exact_ties,
            format_distance(self.ticks.min_distance),
            format_distance(self.chord_grid.min_distance)
        )
    }

    /// The closing line of the main job.
    pub fn result_line(&self) -> String {
        format!(
            "RESULT: {} blocks compared bit-for-bit, {} mismatches, min tie distance {} impulses",
            self.blocks,
            self.mismatches.len(),
            format_distance(self.min_tie_distance())
        )
    }
}

/// A tie distance for the report.
pub fn format_distance(d: f64) -> String {
    if d.is_finite() {
        format!("{d:.3e}")
    } else {
        "none".into()
    }
}

/// Drives a device and the reference through the same steps.
pub struct Comparator<T: Transport> {
    link: T,
    reference: RefMachine,
    motion: RefMotion,
    /// `TOL` and `PASS` of the session, for arcs that do not name their own.
    default_tol: String,
    default_rough: bool,
    /// Totals so far.
    pub tally: Tally,
    /// Keep the reference's events of the last `SYNC` ([`Self::last_events`]).
    pub keep_events: bool,
    last_events: Vec<reference::motion::TimedEvent>,
}

impl<T: Transport> Comparator<T> {
    /// Starts from power-on state on both sides. The device is brought there
    /// with `CFG` defaults and `ZERO`.
    pub fn new(mut link: T) -> Result<Self, LinkError> {
        for line in [
            "LIMITS VX=1500 VZ=3000 AX=100 AZ=150 JD=0.01",
            "DRIVE RATE=50000",
            "CFG HX=0.005 HZ=0.01 DIAM=1 TOL=0.01 PASS=FIN",
            "ZERO",
            "SYNC",
        ] {
            let r = link.request(line)?;
            if !r.is_ok() {
                return Err(LinkError::Io(std::io::Error::other(format!(
                    "device refused {line:?}: {}",
                    r.last
                ))));
            }
        }
        Ok(Comparator {
            link,
            reference: RefMachine::new(RefConfig::default()),
            motion: RefMotion::new(MotionLimits::default(), [0.005, 0.01]),
            default_tol: "0.01".into(),
            default_rough: false,
            tally: Tally::default(),
            keep_events: false,
            last_events: Vec::new(),
        })
    }

    /// The link, for requests outside the comparison.
    pub fn link(&mut self) -> &mut T {
        &mut self.link
    }

    /// Runs every step of a scenario; `progress` is called after each block.
    pub fn run(
        &mut self,
        scenario: &Scenario,
        mut progress: impl FnMut(&Tally),
    ) -> Result<(), LinkError> {
        for (index, step) in scenario.steps.iter().enumerate() {
            self.step(&scenario.name, index, step)?;
            if step.is_motion() {
                progress(&self.tally);
            }
        }
        Ok(())
    }

    /// Runs one step on both sides and compares.
    pub fn step(&mut self, scenario: &str, index: usize, step: &Step) -> Result<(), LinkError> {
        let request = step.request();
        let reply = self.link.request(&request)?;
        let mismatch = |expected: String, reply: &Reply| Mismatch {
            scenario: scenario.to_owned(),
            index,
            request: request.clone(),
            device: reply.last.clone(),
            expected,
        };
        match step {
            Step::Cfg { hx, hz, diam } => {
                let mut cfg = self.reference.config();
                if let Some(v) = hx {
                    cfg.hx_mm = parse_mm(v);
                }
                if let Some(v) = hz {
                    cfg.hz_mm = parse_mm(v);
                }
                if let Some(d) = diam {
                    cfg.diam = *d;
                }
                let old = self.reference.config();
                self.reference.set_config(cfg);
                let (px, pz) = self.reference.position();
                // A new price is a flush; the rest of CFG is not.
                if (old.hx_mm, old.hz_mm) != (cfg.hx_mm, cfg.hz_mm) {
                    self.motion.set_prices([cfg.hx_mm, cfg.hz_mm]);
                    self.motion.set_position(self.commanded(), [px, pz]);
                }
                if !reply.is_ok() {
                    self.tally
                        .mismatches
                        .push(mismatch(format!("OK (PX={px} PZ={pz})"), &reply));
                }
            }
            Step::Zero => {
                self.reference.zero();
                self.motion.zero_counters();
                self.motion.set_position(Point::from_units(0, 0), [0, 0]);
                if !reply.is_ok() {
                    self.tally.mismatches.push(mismatch("OK".into(), &reply));
                }
            }
            Step::Arc {
                x,
                z,
                i,
                k,
                ccw,
                tol,
                rough,
                direct,
                feed,
            } => {
                let cfg = self.reference.config();
                if *direct {
                    let mut bytes = Vec::new();
                    let expected = self.reference.arc_direct_with_steps(
                        x,
                        z,
                        i,
                        k,
                        *ccw,
                        feed.as_deref(),
                        &mut |b| bytes.extend_from_slice(b),
                    );
                    if let Ok(d) = &expected {
                        self.motion
                            .direct(&bytes, DRIVE_RATE, self.commanded(), [d.px, d.pz]);
                    }
                    self.compare_direct(&reply, expected, &cfg, &mismatch);
                } else {
                    let tol_s = tol.clone().unwrap_or_else(|| self.default_tol.clone());
                    let rough = rough.unwrap_or(self.default_rough);
                    let start = self.reference.position();
                    let expected = self.reference.arc(x, z, i, k, *ccw, &tol_s, rough);
                    if let Ok(a) = &expected {
                        let speed = feed.as_deref().map(parse_mm);
                        let (mut px, mut pz) = start;
                        for (end, &(nx, nz)) in a.ends.iter().zip(&a.chords) {
                            (px, pz) = (px + nx, pz + nz);
                            let (point, tie) = chord_point(end);
                            self.tally.chord_grid.min_distance =
                                self.tally.chord_grid.min_distance.min(tie);
                            if tie == 0.0 {
                                self.tally.chord_grid.exact_ties += 1;
                            }
                            self.motion.push(point, [px, pz], speed);
                        }
                    }
                    let tol_mm = parse_mm(&tol_s);
                    self.compare_chords(&reply, expected, rough, tol_mm, &mismatch);
                }
            }
            Step::Move { x, z, inc, feed } => {
                let expected = self.reference.move_block(x.as_deref(), z.as_deref(), *inc);
                self.motion.push(
                    self.commanded(),
                    [expected.px, expected.pz],
                    feed.as_deref().map(parse_mm),
                );
                self.tally.blocks += 1;
                self.tally.events += expected.events;
                self.tally.impulses += expected.nx.unsigned_abs() + expected.nz.unsigned_abs();
                self.tally.quantizer.merge(&expected.quantizer_ties);
                self.tally.interleave.merge(&expected.interleave_ties);
                if !block_matches(&reply, &expected) {
                    self.tally
                        .mismatches
                        .push(mismatch(expected_line(&expected), &reply));
                }
            }
            Step::Sync => {
                let runs = self.motion.runs();
                let r = self.motion.sync();
                self.tally.syncs += 1;
                self.tally.timed += r.ev;
                self.tally.runs = runs.max(self.motion.runs());
                self.tally.ticks = self.motion.ties();
                self.tally.longest_run = self.tally.longest_run.max(r.t);
                // Events are compared through TSEQ; the reference's own list
                // is kept only when asked for (to find a differing event).
                let events = self.motion.take_events();
                if self.keep_events {
                    self.last_events = events;
                }
                let expected = format!("OK EV={} T={} TSEQ={:08X} STARVED=0", r.ev, r.t, r.tseq);
                if reply.last != expected {
                    self.tally.mismatches.push(mismatch(expected, &reply));
                }
            }
        }
        Ok(())
    }

    /// The reference's commanded point.
    fn commanded(&self) -> Point {
        let (x, z) = self.reference.commanded_half_nm();
        Point::from_half_nm(x, z)
    }

    /// The motion reference (profiles, ties).
    pub fn motion(&self) -> &RefMotion {
        &self.motion
    }

    /// The reference's events of the last `SYNC`, when kept.
    pub fn last_events(&self) -> &[reference::motion::TimedEvent] {
        &self.last_events
    }
}

/// The step event rate of direct arcs the comparator sets (`DRIVE RATE`).
const DRIVE_RATE: f64 = 50_000.0;

/// A chord end as a point of the motion reference: on the 10⁻⁷ mm grid
/// (`docs/motion.md`), with its distance from a rounding tie in units.
fn chord_point(end: &[ChordCoord; 2]) -> (Point, f64) {
    let units = |c: ChordCoord| -> (i64, [f64; 2]) {
        match c {
            // Quarter-nanometres: 2.5 units each.
            ChordCoord::Exact(q) => {
                let twice = q * 5;
                (
                    twice.div_euclid(2) as i64,
                    [(twice.rem_euclid(2)) as f64 / 2.0, 0.0],
                )
            }
            // Half-nanometres: 5 units each (exact in f64).
            ChordCoord::OnCircle { centre, offset } => {
                (centre * 5, [offset[0] * 5.0, offset[1] * 5.0])
            }
        }
    };
    Point::grid_rounded(units(end[0]), units(end[1]))
}

impl<T: Transport> Comparator<T> {
    fn compare_chords(
        &mut self,
        reply: &Reply,
        expected: Result<RefArc, RefArcError>,
        rough: bool,
        tol_mm: f64,
        mismatch: &dyn Fn(String, &Reply) -> Mismatch,
    ) {
        let a = match expected {
            Ok(a) => a,
            Err(e) => {
                self.refusal(reply, e, mismatch);
                return;
            }
        };
        self.tally.arcs += 1;
        self.tally.blocks += u64::from(a.n);
        self.tally.events += a.events;
        self.tally.impulses += a.nx.unsigned_abs() + a.nz.unsigned_abs();
        self.tally.quantizer.merge(&a.quantizer_ties);
        self.tally.interleave.merge(&a.interleave_ties);
        self.tally.dphi_margin = self.tally.dphi_margin.min(a.dphi_margin);
        self.tally.n_margin = self.tally.n_margin.min(a.n_margin);
        if !rough && tol_mm > 0.0 {
            self.tally.worst_chord_error = self
                .tally
                .worst_chord_error
                .max(a.max_chord_error_mm / tol_mm);
        }
        let data_ok = reply.data.len() == a.chords.len()
            && reply
                .data
                .iter()
                .zip(&a.chords)
                .enumerate()
                .all(|(i, (line, &(nx, nz)))| *line == format!("DATA I={} NX={nx} NZ={nz}", i + 1));
        let expected_last = expected_arc_line(&a);
        if !data_ok || reply.last != expected_last {
            self.tally.mismatches.push(mismatch(expected_last, reply));
        }
    }

    fn compare_direct(
        &mut self,
        reply: &Reply,
        expected: Result<RefDirect, RefArcError>,
        cfg: &RefConfig,
        mismatch: &dyn Fn(String, &Reply) -> Mismatch,
    ) {
        let d = match expected {
            Ok(d) => d,
            Err(e) => {
                self.refusal(reply, e, mismatch);
                return;
            }
        };
        self.tally.direct_arcs += 1;
        self.tally.blocks += 1;
        self.tally.events += d.events;
        self.tally.impulses += d.nx.unsigned_abs() + d.nz.unsigned_abs();
        let coarse = cfg.hx_mm.max(cfg.hz_mm);
        self.tally.worst_direct_deviation = self
            .tally
            .worst_direct_deviation
            .max(d.max_radial_dev_mm / coarse);
        let expected_last = format!(
            "OK N={} NX={} NZ={} PX={} PZ={} SEQ={:08X}",
            d.events, d.nx, d.nz, d.px, d.pz, d.seq
        );
        let data_ok = reply.data.len() == 1 && reply.data[0] == format!("DATA {}", d.block);
        if !data_ok || reply.last != expected_last {
            self.tally.mismatches.push(mismatch(expected_last, reply));
        }
    }

    fn refusal(
        &mut self,
        reply: &Reply,
        e: RefArcError,
        mismatch: &dyn Fn(String, &Reply) -> Mismatch,
    ) {
        let code = match e {
            RefArcError::Geometry => "ERR GEOMETRY ",
            RefArcError::Range => "ERR RANGE ",
            RefArcError::Syntax => "ERR SYNTAX ",
        };
        if reply.last.starts_with(code) {
            self.tally.refused_alike += 1;
        } else {
            self.tally
                .mismatches
                .push(mismatch(code.trim().to_owned(), reply));
        }
    }
}

/// The summary line of an arc by chords as the device should print it.
pub fn expected_arc_line(a: &RefArc) -> String {
    // Δφ in degrees, 6 decimals, half away from zero: Δφ″·10⁶/3600.
    let micro_deg = (a.dphi_arcsec as u64 * 5000 + 9) / 18;
    format!(
        "OK N={} DPHI={}.{:06} NX={} NZ={} PX={} PZ={} SEQ={:08X}",
        a.n,
        micro_deg / 1_000_000,
        micro_deg % 1_000_000,
        a.nx,
        a.nz,
        a.px,
        a.pz,
        a.seq
    )
}

fn parse_mm(v: &str) -> f64 {
    v.parse().unwrap_or(f64::NAN)
}

/// The reference's block as the device should print it.
pub fn expected_line(b: &RefBlock) -> String {
    format!(
        "OK NX={} NZ={} PX={} PZ={} SEQ={:08X}",
        b.nx, b.nz, b.px, b.pz, b.seq
    )
}

/// Whether a `MOVE` reply carries exactly the reference's values.
pub fn block_matches(reply: &Reply, b: &RefBlock) -> bool {
    let int = |k: &str| reply.value(k).and_then(|v| v.parse::<i64>().ok());
    reply.is_ok()
        && int("NX") == Some(b.nx)
        && int("NZ") == Some(b.nz)
        && int("PX") == Some(b.px)
        && int("PZ") == Some(b.pz)
        && reply
            .value("SEQ")
            .and_then(|v| u32::from_str_radix(v, 16).ok())
            == Some(b.seq)
        && reply.value("SEQ").map(str::len) == Some(8)
}

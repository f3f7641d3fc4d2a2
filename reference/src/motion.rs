//! Reference model of motion in time: the planner and the step timer.
//!
//! This module gives every step event its tick exactly as `docs/motion.md`
//! §1–§6 defines it: blocks, junction speeds, the plan over a
//! rolling window of `W` blocks, runs between flushes, event times at the
//! rounding boundaries of the lead axis, `Q(T·TICK)`, the fixed rate of
//! `ARC … MODE=DIRECT` and what `SYNC` reports. It is written from that page
//! alone, independently of the controller's fixed-point core, so
//! that the two can be compared event by event. The step bytes themselves
//! come from [`crate::impulse::step_events`] (`docs/impulses.md` §3).
//!
//! The arithmetic is double-double (an unevaluated sum of two f64, about 106
//! bits); see *Arithmetic and error bound* below for why plain f64 would not
//! do.
//!
//! # Rules implemented
//!
//! Units: lengths mm (X on the radius), speeds mm/s, accelerations mm/s²,
//! times s; the limits `VMAX` and the feeds `F` are given in mm/min, as in
//! the protocol, and divided by 60.
//!
//! * A block goes from the current commanded point `P0` to `P1`,
//!   `L = |P1 − P0|`, `u = (P1 − P0)/L`. `L = 0` takes no time and is not
//!   planned; `L > 0` is planned even without impulses.
//! * `v_max = min(F, VMAX_a/|u_a|)` (feed) or `min VMAX_a/|u_a|` (rapid), and
//!   `a = min AMAX_a/|u_a|`, over the axes with `u_a ≠ 0`.
//! * Junction between consecutive planned blocks `k`, `k+1` of a run:
//!   `cos θ = −u_k·u_{k+1}`, `s = √((1 − cos θ)/2)`,
//!   `v_j² = min(a_k, a_{k+1})·δ·s/(1 − s)`, capped by both `v_max²`; a
//!   straight continuation is the cap, a reversal 0.
//! * When block `k` starts, its exit speed is fixed by the plan over the
//!   blocks `k … k+W−1` then queued (fewer at a flush), with rest at the end of
//!   that window: `v_exit² = min(E, v_entry² + 2aL)`, `E` the largest entry²
//!   of block `k+1` the backward pass allows (`E_j = min(v_j², E_{j+1} +
//!   2a_jL_j)`, 0 past the window). Its entry is the exit of block `k−1` as
//!   it ran (0 for the first block of a run). Block `k` starts when `W − 1`
//!   planned blocks are queued after it, or at a flush.
//! * Trapezoid: `v_c = min(v_max, √((2aL + v_entry² + v_exit²)/2))`;
//!   accelerating part `(v_c² − v_entry²)/(2a)`, decelerating part
//!   `(v_c² − v_exit²)/(2a)`, cruise in between.
//! * Event `i` of a block (lead axis by impulses, X when equal) happens when
//!   the lead coordinate crosses `(a0 + (i − ½)·σ)·h`: at the fraction
//!   `λ_i = (b_i − P0_lead)/(P1_lead − P0_lead)` of the block, path distance
//!   `λ_i·L`. Its tick is `Q(T·TICK)`, `T` the time since its run began, `Q`
//!   rounding half away from zero. A run ends when its last block ends and
//!   lasts `Q(T_end·TICK)` ticks.
//! * `ARC … MODE=DIRECT`: a flush, then a run of its own whose event `j` is at
//!   tick `Q(j·TICK/RATE)` and which lasts `Q(N·TICK/RATE)` ticks.
//! * `SYNC`: a flush, then `EV` (events since the previous `SYNC`/`ZERO`),
//!   `T` (ticks of the last run that ended since then, 0 if none) and `TSEQ`
//!   (CRC-32 over one record per event: its byte, then the tick delta from
//!   the previous event of its run, or from the run start, as a
//!   little-endian u32 modulo 2³²); then these counters restart. `ZERO`
//!   restarts them too.
//!
//! # Decisions where the rules are silent
//!
//! * **Prices.** The event boundaries need the impulse price `h` of each
//!   axis, which the limits do not carry: [`RefMotion::new`] and
//!   [`RefMotion::set_prices`] take them. A price is a decimal with at most
//!   6 decimals (`h = q·10⁻⁶ mm`), so every boundary `(a0 + (i − ½)σ)·h` is a
//!   whole number `(2a0 + (2i − 1)σ)·5q` of 10⁻⁷ mm and is held exactly.
//! * **Settings change at rest.** [`RefMotion::set_limits`],
//!   [`RefMotion::set_prices`] and [`RefMotion::set_position`] flush first:
//!   every request that changes them (`LIMITS`, `CFG`, `ZERO`, `DRIVE`) is a
//!   flush, so a caller that mirrors those requests gets the flush for free.
//! * **A block of zero length** (`P1 = P0` exactly) has equal start and end
//!   registers when the registers are `Q(P/h)` of the points, so it has no
//!   events; one that claims impulses is a caller error and panics. It is
//!   not planned and is transparent to the junction rule: the junction is
//!   between the planned blocks before and after it ("consecutive planned
//!   blocks"), and it does not count in the window.
//! * **A direct arc without events** (`N = 0`) moves nothing and takes no
//!   time; it is not a run (as a request that queues no planned block, it
//!   adds nothing), so the `T` that `SYNC` reports is unchanged by it.
//! * **Straight and reversed** are decided exactly when the points are whole
//!   numbers of 10⁻⁷ mm: the cross product `Δ_k × Δ_{k+1}` is then computed
//!   without error, and is 0 exactly for collinear blocks (straight if the
//!   dot product is positive, a reversal otherwise). So with `δ = 0` two
//!   collinear lines never stop at their junction. Computed chord ends are
//!   used as given: they are never exactly collinear.
//! * **Decimal inputs.** `VMAX`, `AMAX`, `δ`, `TICK`, `F`, `RATE` are
//!   decimals with at most 6 decimals in the protocol. An f64 argument that
//!   is the f64 nearest such a decimal `m·10⁻⁶` is taken as that decimal (to
//!   double-double accuracy), not as its f64 rounding; any other value is
//!   taken as given.
//! * **Time ties** (`docs/motion.md`). A computed `T·TICK` within `2⁻³⁶`
//!   tick of a half-integer is taken as the tie and rounds up (half away
//!   from zero; times are never negative). Exact ties do happen:
//!   a cruise at a rational speed between rational boundaries is at a
//!   rational time (tests show one). They are counted in
//!   [`TieStats::exact_ties`]; every other rounding feeds
//!   [`TieStats::min_distance`]. For direct arcs with decimal `TICK` and
//!   `RATE` the ticks are computed exactly in integers, ties included.
//! * **Registers that do not match the point.** The event fraction `λ_i` is
//!   in `[0, 1]` when the registers are `Q(P/h)` of the points. A computed
//!   chord end that lies within f64 rounding of a boundary may have been
//!   quantized on the other side of it: `λ_i` slightly outside `[0, 1]`
//!   (by at most `2⁻⁴⁰` of the coordinates' magnitude) is clamped; more is a
//!   caller error and panics.
//! * **`W ≥ 1`.** With `W = 1` every block starts as soon as it is queued and
//!   ends at rest.
//!
//! # Arithmetic and error bound
//!
//! The tick of an event is `Q(T·TICK)` with `T` the time since its run
//! began; runs last minutes, i.e. `T·TICK` up to 10⁸–10¹⁰. In plain f64 every
//! block's duration would carry a relative error of some `10u` (`u = 2⁻⁵³`),
//! and the errors of the blocks add along the run: `10u·T·TICK ≈ 3·10⁻⁷`
//! tick after 5 minutes, and an inexact f64 feed (`F = 123.456789`) alone
//! shifts a 5-minute cruise by `3·10⁻⁸` tick. The model therefore holds every
//! real quantity as a double-double `hi + lo` and the inputs exactly:
//!
//! * commanded points of lines are whole numbers of 10⁻⁷ mm
//!   ([`Point::from_units`], [`Point::from_half_nm`]), held exactly; event
//!   boundaries are exact integers in the same unit, so the numerators
//!   `b_i − P0_lead` and `P1_lead − b_i` carry one rounding of `3u²`
//!   relative to themselves, however close the boundary is to an end;
//! * the decimal limits, feeds and `TICK` are within `2⁻¹⁰²` (relative) of
//!   their decimal value;
//! * chord ends are taken as given ([`Point::from_mm`], exactly the f64 value;
//!   [`Point::from_mm_dd`] for more precise ones).
//!
//! Basic operations (accurate double-word algorithms of Joldes, Muller and
//! Popescu, *ACM TOMS* 2017: sum, product with FMA, quotient, and a square
//! root by one exact-residual Newton step) have a relative error below
//! `16u² = 2⁻¹⁰²`. The cancellations that remain in the closed forms are
//! removed:
//!
//! * `1 − s` near a straight continuation (chords of an arc): with
//!   `cos ψ = Δ_k·Δ_{k+1}/(L_kL_{k+1})` (ψ the turn) and the cross product
//!   `c = Δ_k × Δ_{k+1}`, `1 − s² = (1 − cos ψ)/2` is computed as
//!   `c²/(2P(P + dot))` (`P = L_kL_{k+1}`) when `dot > 0`, and
//!   `s² = (1 + cos ψ)/2` as `c²/(2P(P − dot))` when `dot < 0` (near a
//!   reversal); then `s/(1 − s) = s(1 + s)/(1 − s²)`. No subtraction of
//!   nearly equal numbers is left.
//! * Ramps: `t = 2s/(v0 + √(v0² + 2as))`, never `(√(…) − v0)/a`.
//! * Deceleration: an event in the decelerating part is timed from the end
//!   of the block, `t = D − 2r/(v_exit + √(v_exit² + 2ar))`, with the
//!   remaining distance `r = L·(P1_lead − b_i)/(P1_lead − P0_lead)` computed
//!   from its own exact numerator, not as `L − s`.
//! * The run clock is a double-double sum of the block durations, and each
//!   event is timed from the start of its block, then added to the clock.
//!
//! What is left are subtractions whose operands are bounded by the block's
//! time scale `σ_k = D_k + 2v_c/a` (duration plus twice the time to reach the
//! cruise speed from rest; lengths and speeds enter through `length/v_c` and
//! `v_c/a`): `d_acc = (v_c² − v_entry²)/(2a)`, `s − d_acc` in the cruise,
//! `D − t` in the deceleration. Counting the operations of one event (about
//! 40), the backward pass over the window (3 relative `u²` per block, at most
//! `W` blocks) and the chain of entry speeds along a run of `N` blocks (at
//! most 3 relative `u²` per block, reset whenever a limit other than the
//! previous exit binds), the absolute error of an event's `T·TICK` is below
//!
//! `(3N + 3W + 300)·u²·TICK·S`, `S = Σ σ_k` over the run so far,
//!
//! and the sum of durations adds at most `3N·u²·T·TICK ≤ 3N·u²·TICK·S`
//! (included above). With `u² = 2⁻¹⁰⁶ ≈ 1.2·10⁻³²`: a run of 10⁶ blocks
//! with `S ≤ 10⁶ s` (hours of motion plus 1 s of ramp scale per block) at
//! 1 MHz stays below `4·10⁻¹⁴` tick. The tie band of `2⁻³⁶ ≈ 1.5·10⁻¹¹`
//! tick exceeds this bound by far, so an exact tie is always recognised; a
//! non-tie is taken for a tie only if it lies within the band, and then it
//! is visible in the count of exact ties.
//!
//! For lines this is the whole error: the model's `T·TICK` is exact to far
//! below 10⁻⁹ tick. For arcs it is exact *for the chord ends it is given*:
//! a chord end computed in f64 is off the exact one by about `2⁻⁵³·|P|`
//! (10⁻¹⁴ mm at 100 mm), and an event near it moves by that over the path
//! speed (10⁻⁸ tick at 1 mm/s), more where a junction speed is set by the
//! junction formula. That term belongs to the chord ends, not to this model.
//!
//! [`RefMotion::ties`] reports the smallest distance of a rounded `T·TICK`
//! from a half-integer over every event and run end, and the exact ties;
//! [`TimedEvent::offset_ticks`] gives each event's `T·TICK − tick`.
//!
//! # Use
//!
//! Mirror the device's requests: [`RefMotion::push`] for every block (a
//! line, or each chord of an arc, with the registers the impulse reference
//! gives its end), [`RefMotion::flush`] for a flush that reports nothing
//! (`CFG`, `DRIVE`, `RESET`), [`RefMotion::sync`], [`RefMotion::zero_counters`]
//! then [`RefMotion::set_position`] for `ZERO`, [`RefMotion::direct`] for a
//! direct arc. Events accumulate in [`RefMotion::events`] until taken with
//! [`RefMotion::take_events`] (a long session should take them as it goes).

use std::collections::VecDeque;

use crate::dd::Dd;
use crate::impulse::{step_events, TieStats};

/// Length unit of [`Point`]: 10⁻⁷ mm per unit.
pub const UNITS_PER_MM: i64 = 10_000_000;

/// The tie band of `docs/motion.md`: a computed `T·TICK` this close to a
/// half-integer is the tie and rounds up: `2⁻³⁶` tick.
pub const TIME_TIE_BAND_TICKS: f64 = 1.0 / (1u64 << 36) as f64;

/// Relative tolerance (of the lead coordinates' magnitude) by which an event
/// boundary may lie outside its block before the registers are taken as
/// inconsistent with the points: `2⁻⁴⁰`.
const BOUNDARY_SLACK_REL: f64 = 1.0 / (1u64 << 40) as f64;

/// The integer `m` when `x` is the f64 nearest the decimal `m·10⁻⁶`
/// (decided exactly), else `None`.
fn decimal_micro(x: f64) -> Option<i64> {
    if !x.is_finite() {
        return None;
    }
    let m = (x * 1e6).round();
    if m.abs() >= 9.0e15 {
        return None;
    }
    // x·10⁶ exactly, minus m: the f64 nearest m·10⁻⁶ is within u·|m|·10⁻⁶ of it.
    let diff = Dd::prod(x, 1e6).minus(Dd::from_f64(m)).abs();
    (diff.to_f64() <= m.abs() * f64::EPSILON * 0.5 * (1.0 + 1e-9)).then_some(m as i64)
}

/// `x` as a double-double: the decimal it stands for (see [`decimal_micro`])
/// or, failing that, `x` itself.
fn decimal(x: f64) -> Dd {
    match decimal_micro(x) {
        Some(m) => Dd::from_i128(m as i128).over(Dd::from_f64(1e6)),
        None => Dd::from_f64(x),
    }
}

// ---------------------------------------------------------------------------
// Public types.

/// Motion limits (`docs/motion.md` §1); they apply at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionLimits {
    /// Rapid rates `VX`, `VZ` of X (on the radius) and Z, mm/min.
    pub vmax_mm_min: [f64; 2],
    /// Accelerations `AX`, `AZ` of X and Z, mm/s².
    pub amax_mm_s2: [f64; 2],
    /// Junction deviation `δ` (`JD`), mm.
    pub junction_mm: f64,
    /// The step clock `TICK`, Hz.
    pub tick_hz: f64,
    /// The planning window `W`, blocks (at least 1).
    pub window: usize,
}

impl Default for MotionLimits {
    /// The defaults of `docs/motion.md`: `VX=1500 VZ=3000 AX=100 AZ=150
    /// JD=0.01`, `TICK` 1 MHz, `W = 64`.
    fn default() -> Self {
        MotionLimits {
            vmax_mm_min: [1500.0, 3000.0],
            amax_mm_s2: [100.0, 150.0],
            junction_mm: 0.01,
            tick_hz: 1e6,
            window: 64,
        }
    }
}

/// A point in the (X radius, Z) plane, held as double-double in units of
/// 10⁻⁷ mm ([`UNITS_PER_MM`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    c: [Dd; 2],
}

impl Point {
    /// An exact point: whole numbers of 10⁻⁷ mm (X radius, Z).
    pub fn from_units(x: i64, z: i64) -> Point {
        Point {
            c: [Dd::from_i128(x as i128), Dd::from_i128(z as i128)],
        }
    }

    /// An exact point in half-nanometres (5·10⁻⁷ mm), the unit of the
    /// commanded coordinates in [`crate::impulse`].
    pub fn from_half_nm(x: i64, z: i64) -> Point {
        Point::from_units(x * 5, z * 5)
    }

    /// A point in mm (X radius, Z), taken exactly as the f64 values given
    /// (a computed chord end).
    pub fn from_mm(x_mm: f64, z_mm: f64) -> Point {
        Point {
            c: [
                Dd::prod(x_mm, UNITS_PER_MM as f64),
                Dd::prod(z_mm, UNITS_PER_MM as f64),
            ],
        }
    }

    /// A point in mm given as unevaluated sums `[hi, lo]` per axis, for chord
    /// ends computed beyond f64 precision.
    pub fn from_mm_dd(x_mm: [f64; 2], z_mm: [f64; 2]) -> Point {
        let f = |v: [f64; 2]| Dd::norm(v[0], v[1]).times_f64(UNITS_PER_MM as f64);
        Point {
            c: [f(x_mm), f(z_mm)],
        }
    }

    /// A point given per axis as a whole number of 10⁻⁷ mm plus an offset
    /// in the same unit as a double-double `[hi, lo]` (a chord end: its
    /// exact centre plus its offset on the circle).
    pub fn from_units_plus(x: (i64, [f64; 2]), z: (i64, [f64; 2])) -> Point {
        let c = |(whole, off): (i64, [f64; 2])| {
            Dd::from_i128(whole as i128).plus(Dd::norm(off[0], off[1]))
        };
        Point { c: [c(x), c(z)] }
    }

    /// A chord end given as in [`Point::from_units_plus`], rounded half away
    /// from zero to the grid of 10⁻⁷ mm as `docs/motion.md` times it; also
    /// the smallest distance (in units) of a coordinate from a rounding tie.
    pub fn grid_rounded(x: (i64, [f64; 2]), z: (i64, [f64; 2])) -> (Point, f64) {
        let round = |(whole, off): (i64, [f64; 2])| -> (i64, f64) {
            let f = Dd::norm(off[0], off[1]);
            let k = f.hi.floor();
            let frac = f.minus(Dd::from_f64(k)).to_f64();
            let (k, frac) = if frac < 0.0 {
                (k - 1.0, frac + 1.0)
            } else if frac >= 1.0 {
                (k + 1.0, frac - 1.0)
            } else {
                (k, frac)
            };
            let v = whole as f64 + k + frac;
            let up = if v < 0.0 { frac > 0.5 } else { frac >= 0.5 };
            (whole + k as i64 + i64::from(up), (frac - 0.5).abs())
        };
        let ((x, dx), (z, dz)) = (round(x), round(z));
        (Point::from_units(x, z), dx.min(dz))
    }

    /// The point in mm (X radius, Z), rounded to f64.
    pub fn mm(&self) -> [f64; 2] {
        let f = |v: Dd| v.over(Dd::from_f64(UNITS_PER_MM as f64)).to_f64();
        [f(self.c[0]), f(self.c[1])]
    }
}

impl From<[f64; 2]> for Point {
    /// `[X radius, Z]` in mm, as [`Point::from_mm`].
    fn from(p: [f64; 2]) -> Point {
        Point::from_mm(p[0], p[1])
    }
}

/// One step event with its tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedEvent {
    /// The step byte (`docs/impulses.md` §3.2, `SEQ` bits).
    pub byte: u8,
    /// Its tick, `Q(T·TICK)`, counted from the start of its run.
    pub tick: u64,
    /// Index of its run (0 for the first run of this model).
    pub run: u64,
    /// Index of its block in [`RefMotion::profiles`]; `None` for a direct
    /// arc's event.
    pub block: Option<u64>,
    /// `T·TICK − tick`, ticks, in `[−½, ½]`.
    pub offset_ticks: f64,
}

/// A planned block as it ran (values rounded to f64).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockProfile {
    /// Index of its run.
    pub run: u64,
    /// `L`, mm.
    pub length_mm: f64,
    /// Entry speed, mm/s.
    pub v_entry: f64,
    /// Cruise (peak) speed `v_c`, mm/s.
    pub v_cruise: f64,
    /// Exit speed, mm/s.
    pub v_exit: f64,
    /// Speed limit `v_max`, mm/s.
    pub v_max: f64,
    /// Acceleration `a`, mm/s².
    pub accel: f64,
    /// Start time since the run began, s.
    pub start_s: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Number of step events.
    pub events: u64,
}

/// What `SYNC` reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncReport {
    /// `EV`: step events since the previous `SYNC` or `ZERO`.
    pub ev: u64,
    /// `T`: ticks of the last run that ended since then (0 if none).
    pub t: u64,
    /// `TSEQ`: CRC-32 of the (byte, u32 LE tick delta) records since then.
    pub tseq: u32,
}

// ---------------------------------------------------------------------------
// Internal state.

/// Limits as double-doubles.
#[derive(Clone, Copy, Debug)]
struct Lim {
    /// Rapid rates, mm/s.
    vmax: [Dd; 2],
    /// Accelerations, mm/s².
    amax: [Dd; 2],
    /// Junction deviation, mm.
    delta: Dd,
    /// `TICK`, Hz.
    tick: Dd,
    /// `TICK` in µHz when it is a decimal with at most 6 decimals.
    tick_micro: Option<i64>,
}

impl Lim {
    fn new(l: &MotionLimits) -> Lim {
        for a in 0..2 {
            assert!(
                l.vmax_mm_min[a].is_finite() && l.vmax_mm_min[a] > 0.0,
                "rapid rate must be over 0 mm/min, got {}",
                l.vmax_mm_min[a]
            );
            assert!(
                l.amax_mm_s2[a].is_finite() && l.amax_mm_s2[a] > 0.0,
                "acceleration must be over 0 mm/s², got {}",
                l.amax_mm_s2[a]
            );
        }
        assert!(
            l.junction_mm.is_finite() && l.junction_mm >= 0.0,
            "junction deviation must be at least 0 mm, got {}",
            l.junction_mm
        );
        assert!(
            l.tick_hz.is_finite() && l.tick_hz > 0.0,
            "TICK must be over 0 Hz, got {}",
            l.tick_hz
        );
        assert!(l.window >= 1, "the window must hold at least one block");
        let sixty = Dd::from_f64(60.0);
        Lim {
            vmax: [
                decimal(l.vmax_mm_min[0]).over(sixty),
                decimal(l.vmax_mm_min[1]).over(sixty),
            ],
            amax: [decimal(l.amax_mm_s2[0]), decimal(l.amax_mm_s2[1])],
            delta: decimal(l.junction_mm),
            tick: decimal(l.tick_hz),
            tick_micro: decimal_micro(l.tick_hz),
        }
    }
}

/// A planned block waiting to start.
#[derive(Clone, Debug)]
struct Block {
    /// Start and end points, units of 10⁻⁷ mm.
    p0: [Dd; 2],
    p1: [Dd; 2],
    /// `L`, mm.
    l_mm: Dd,
    /// `a`, mm/s².
    a: Dd,
    /// `v_max`, mm/s, and its square, mm²/s².
    vmax: Dd,
    vmax2: Dd,
    /// `2aL`, mm²/s².
    two_al: Dd,
    /// Junction cap² at its entry, mm²/s² (unused for the first of a run).
    junction2: Dd,
    /// Step bytes.
    bytes: Vec<u8>,
    /// Lead axis (0 X, 1 Z), its register at the start and its direction.
    lead: usize,
    a0: i64,
    sigma: i64,
}

/// What the junction rule needs of the last planned block of the run.
#[derive(Clone, Copy, Debug)]
struct Prev {
    /// `P1 − P0` and `L`, units of 10⁻⁷ mm.
    delta: [Dd; 2],
    l_units: Dd,
    /// `a`, mm/s².
    a: Dd,
    /// `v_max²`, mm²/s².
    vmax2: Dd,
}

/// The trapezoid of a started block: speeds (`ve`, `vc`, `vx`) mm/s and
/// their squares mm²/s², `2a` mm/s², lengths of the ramps mm, times s.
struct Trapezoid {
    ve: Dd,
    ve2: Dd,
    vc: Dd,
    vx: Dd,
    vx2: Dd,
    two_a: Dd,
    d_acc: Dd,
    d_dec: Dd,
    t_acc: Dd,
    dur: Dd,
}

impl Trapezoid {
    /// Time from the block start to path distance `s` (`r = L − s`, given
    /// separately), s.
    fn time_at(&self, s: Dd, r: Dd) -> Dd {
        if s.is_zero() {
            return Dd::ZERO;
        }
        if r.is_zero() {
            return self.dur;
        }
        if s.le(self.d_acc) {
            let v = self.ve2.plus(self.two_a.times(s)).sqrt();
            s.plus(s).over(self.ve.plus(v))
        } else if r.le(self.d_dec) {
            let v = self.vx2.plus(self.two_a.times(r)).sqrt();
            self.dur.minus(r.plus(r).over(self.vx.plus(v)))
        } else {
            self.t_acc.plus(s.minus(self.d_acc).over(self.vc))
        }
    }
}

/// The reference planner and step timer.
#[derive(Clone, Debug)]
pub struct RefMotion {
    limits: MotionLimits,
    lim: Lim,
    /// Prices in 10⁻⁶ mm (X radius, Z).
    price_q: [i64; 2],
    point: Point,
    registers: [i64; 2],
    queue: VecDeque<Block>,
    prev: Option<Prev>,
    // The run in progress: the clock (start of the next block, s), the time
    // scale S of the error bound (s), the last exit speed² (mm²/s²) and the
    // tick of its last event.
    run_active: bool,
    runs: u64,
    clock: Dd,
    scale: Dd,
    exit2: Dd,
    last_tick: u64,
    // Counters since the last SYNC or ZERO.
    ev: u64,
    last_run_ticks: Option<u64>,
    tseq: crc32fast::Hasher,
    // Diagnostics.
    events: Vec<TimedEvent>,
    profiles: Vec<BlockProfile>,
    ties: TieStats,
    interleave_ties: TieStats,
}

impl RefMotion {
    /// A model at rest at program zero, with the given limits and impulse
    /// prices (X on the radius, Z; mm per impulse, decimals with at most 6
    /// decimals).
    ///
    /// # Panics
    /// If a limit is out of range (see [`set_limits`](Self::set_limits)) or
    /// a price is not such a decimal.
    pub fn new(limits: MotionLimits, price_mm: [f64; 2]) -> Self {
        RefMotion {
            limits,
            lim: Lim::new(&limits),
            price_q: prices(price_mm),
            point: Point::from_units(0, 0),
            registers: [0, 0],
            queue: VecDeque::new(),
            prev: None,
            run_active: false,
            runs: 0,
            clock: Dd::ZERO,
            scale: Dd::ZERO,
            exit2: Dd::ZERO,
            last_tick: 0,
            ev: 0,
            last_run_ticks: None,
            tseq: crc32fast::Hasher::new(),
            events: Vec::new(),
            profiles: Vec::new(),
            ties: TieStats::new(),
            interleave_ties: TieStats::new(),
        }
    }

    /// The limits in force.
    pub fn limits(&self) -> MotionLimits {
        self.limits
    }

    /// A flush, then new limits (`LIMITS`).
    ///
    /// # Panics
    /// If a rate, an acceleration or `TICK` is not over 0, `δ` is negative or
    /// the window is 0.
    pub fn set_limits(&mut self, limits: MotionLimits) {
        let lim = Lim::new(&limits);
        self.flush();
        self.limits = limits;
        self.lim = lim;
    }

    /// A flush, then new impulse prices (`CFG HX=`/`HZ=`), mm per impulse.
    /// The caller re-expresses the registers with
    /// [`set_position`](Self::set_position).
    ///
    /// # Panics
    /// If a price is not a positive decimal with at most 6 decimals.
    pub fn set_prices(&mut self, price_mm: [f64; 2]) {
        let q = prices(price_mm);
        self.flush();
        self.price_q = q;
    }

    /// A flush, then the commanded point and the impulse registers (after
    /// `ZERO`, a price change).
    pub fn set_position(&mut self, point: Point, registers: [i64; 2]) {
        self.flush();
        self.point = point;
        self.registers = registers;
    }

    /// The current commanded point (the end of the last queued block).
    pub fn point(&self) -> Point {
        self.point
    }

    /// The current impulse registers (X radius, Z).
    pub fn registers(&self) -> [i64; 2] {
        self.registers
    }

    /// Queues a block from the current point to `to`, whose registers end at
    /// `to_registers` (the caller quantizes; the step bytes are
    /// [`step_events`] from the current registers). `feed_mm_min`: the feed
    /// `F` of a feed block, mm/min; `None` for a rapid block.
    ///
    /// A block of zero length is not planned (and has no events). Blocks
    /// start as the window fills (see the module documentation).
    ///
    /// # Panics
    /// If the feed is not over 0, a zero-length block claims impulses, or the
    /// registers are not those of the points (an event boundary lies outside
    /// the block).
    pub fn push(&mut self, to: Point, to_registers: [i64; 2], feed_mm_min: Option<f64>) {
        if let Some(f) = feed_mm_min {
            assert!(f.is_finite() && f > 0.0, "feed must be over 0, got {f}");
        }
        let from = self.point;
        let from_reg = self.registers;
        let bytes = step_events(
            (from_reg[0], from_reg[1]),
            (to_registers[0], to_registers[1]),
            &mut self.interleave_ties,
        );
        self.point = to;
        self.registers = to_registers;

        let delta = [to.c[0].minus(from.c[0]), to.c[1].minus(from.c[1])];
        if delta[0].is_zero() && delta[1].is_zero() {
            assert!(
                bytes.is_empty(),
                "a block of zero length cannot issue impulses ({from_reg:?} → {to_registers:?})"
            );
            return;
        }
        let l_units = delta[0]
            .times(delta[0])
            .plus(delta[1].times(delta[1]))
            .sqrt();
        let l_mm = l_units.over(Dd::from_f64(UNITS_PER_MM as f64));

        // Speed and acceleration limits over the moving axes; L/|Δ_a| = 1/|u_a|.
        let mut a: Option<Dd> = None;
        let mut vmax = feed_mm_min.map(|f| decimal(f).over(Dd::from_f64(60.0)));
        for (axis, d) in delta.iter().enumerate() {
            if d.is_zero() {
                continue;
            }
            let ratio = l_units.over(d.abs());
            let aa = self.lim.amax[axis].times(ratio);
            let vv = self.lim.vmax[axis].times(ratio);
            a = Some(a.map_or(aa, |x| x.min(aa)));
            vmax = Some(vmax.map_or(vv, |x| x.min(vv)));
        }
        let a = a.expect("a block of positive length moves an axis");
        let vmax = vmax.expect("a block of positive length moves an axis");
        let vmax2 = vmax.times(vmax);

        let junction2 = match self.prev {
            Some(p) => junction2(
                p.delta,
                p.l_units,
                delta,
                l_units,
                p.a.min(a),
                self.lim.delta,
                p.vmax2.min(vmax2),
            ),
            None => Dd::ZERO,
        };
        self.prev = Some(Prev {
            delta,
            l_units,
            a,
            vmax2,
        });

        let dx = to_registers[0] - from_reg[0];
        let dz = to_registers[1] - from_reg[1];
        let lead = if dx.unsigned_abs() >= dz.unsigned_abs() {
            0
        } else {
            1
        };
        let d_lead = [dx, dz][lead];
        self.queue.push_back(Block {
            p0: from.c,
            p1: to.c,
            l_mm,
            a,
            vmax,
            vmax2,
            two_al: a.times(l_mm).times_f64(2.0),
            junction2,
            bytes,
            lead,
            a0: from_reg[lead],
            sigma: d_lead.signum(),
        });
        while self.queue.len() >= self.limits.window {
            self.start_front();
        }
    }

    /// A backlash take-up block (`docs/motion.md` §7): `steps` impulses per
    /// axis (X radius, Z), a rapid block from a point on the grid at the
    /// origin with registers 0, planned and timed as any; the commanded
    /// point and the registers stay where they are.
    pub fn push_takeup(&mut self, steps: [i64; 2]) {
        let (point, registers) = (self.point, self.registers);
        self.point = Point::from_units(0, 0);
        self.registers = [0, 0];
        // Prices in 10⁻⁶ mm; points in 10⁻⁷ mm.
        let to = Point::from_units(
            steps[0] * self.price_q[0] * 10,
            steps[1] * self.price_q[1] * 10,
        );
        self.push(to, steps, None);
        self.point = point;
        self.registers = registers;
    }

    /// A flush: every queued block starts in turn, the last ends at rest and
    /// the run (if any) ends.
    pub fn flush(&mut self) {
        while !self.queue.is_empty() {
            self.start_front();
        }
        self.prev = None;
        if self.run_active {
            self.run_active = false;
            let (tick, _) = self.round_time(self.clock, self.scale);
            self.last_run_ticks = Some(tick);
        }
    }

    /// `ARC … MODE=DIRECT`: a flush, then the arc's step bytes as a run of
    /// their own at the fixed event rate `rate_hz` (events/s): event `j` at
    /// tick `Q(j·TICK/RATE)`, the run `Q(N·TICK/RATE)` ticks long. The
    /// commanded point and registers become `to` and `to_registers`. An arc
    /// without events is no run.
    ///
    /// # Panics
    /// If the rate is not over 0.
    pub fn direct(&mut self, bytes: &[u8], rate_hz: f64, to: Point, to_registers: [i64; 2]) {
        assert!(
            rate_hz.is_finite() && rate_hz > 0.0,
            "the event rate must be over 0, got {rate_hz}"
        );
        self.flush();
        self.point = to;
        self.registers = to_registers;
        if bytes.is_empty() {
            return;
        }
        self.runs += 1;
        self.last_tick = 0;
        let run = self.runs - 1;
        let n = bytes.len() as u64;
        let exact = self.lim.tick_micro.zip(decimal_micro(rate_hz));
        let rate = decimal(rate_hz);
        for (j, &byte) in (1..=n).zip(bytes) {
            let (tick, offset) = self.direct_tick(j, exact, rate);
            self.record(byte, tick, run, None, offset);
        }
        let (tick, _) = self.direct_tick(n, exact, rate);
        self.last_run_ticks = Some(tick);
    }

    /// `SYNC`: a flush, then `EV`, `T`, `TSEQ` since the previous `SYNC` or
    /// `ZERO`; the counters restart.
    pub fn sync(&mut self) -> SyncReport {
        self.flush();
        let report = SyncReport {
            ev: self.ev,
            t: self.last_run_ticks.unwrap_or(0),
            tseq: self.tseq.clone().finalize(),
        };
        self.restart_counters();
        report
    }

    /// `ZERO`: a flush, then the counters of `SYNC` restart. The caller sets
    /// the new point with [`set_position`](Self::set_position).
    pub fn zero_counters(&mut self) {
        self.flush();
        self.restart_counters();
    }

    /// Every event so far (those taken by [`take_events`](Self::take_events)
    /// excepted), in order.
    pub fn events(&self) -> &[TimedEvent] {
        &self.events
    }

    /// Hands over the events recorded so far and forgets them.
    pub fn take_events(&mut self) -> Vec<TimedEvent> {
        std::mem::take(&mut self.events)
    }

    /// Every planned block as it ran, in order.
    pub fn profiles(&self) -> &[BlockProfile] {
        &self.profiles
    }

    /// Rounding decisions of `Q(T·TICK)` over every event and run end:
    /// exact ties, and the smallest distance (ticks) of `T·TICK` to a
    /// half-integer among the others.
    pub fn ties(&self) -> TieStats {
        self.ties
    }

    /// Rounding decisions of the step interleaver ([`step_events`]).
    pub fn interleave_ties(&self) -> TieStats {
        self.interleave_ties
    }

    /// Number of runs so far (direct arcs included).
    pub fn runs(&self) -> u64 {
        self.runs
    }

    fn restart_counters(&mut self) {
        self.ev = 0;
        self.last_run_ticks = None;
        self.tseq = crc32fast::Hasher::new();
    }

    fn record(&mut self, byte: u8, tick: u64, run: u64, block: Option<u64>, offset: f64) {
        let delta = tick.wrapping_sub(self.last_tick) as u32;
        self.last_tick = tick;
        self.tseq.update(&[byte]);
        self.tseq.update(&delta.to_le_bytes());
        self.ev += 1;
        self.events.push(TimedEvent {
            byte,
            tick,
            run,
            block,
            offset_ticks: offset,
        });
    }

    /// `Q(j·TICK/RATE)` and its offset; exact in integers when both are
    /// decimals.
    fn direct_tick(&mut self, j: u64, exact: Option<(i64, i64)>, rate: Dd) -> (u64, f64) {
        match exact {
            Some((mt, mr)) => {
                let num = j as i128 * mt as i128;
                let den = mr as i128;
                let rem = num % den;
                let tick = (2 * num + den) / (2 * den);
                if 2 * rem == den {
                    self.ties.exact_ties += 1;
                } else {
                    let d = (2 * rem - den).abs() as f64 / (2 * den) as f64;
                    self.ties.min_distance = self.ties.min_distance.min(d);
                }
                let offset = (num - tick * den) as f64 / den as f64;
                (tick as u64, offset)
            }
            None => {
                let t = Dd::from_f64(j as f64).over(rate);
                let scale = t;
                self.round_time(t, scale)
            }
        }
    }

    /// `Q(t·TICK)` for a time `t ≥ 0` (s) whose error scale is `scale` (s),
    /// recorded in the tie statistics; returns the tick and `t·TICK − tick`.
    fn round_time(&mut self, t: Dd, scale: Dd) -> (u64, f64) {
        let x = t.times(self.lim.tick);
        assert!(
            !x.is_neg() && x.hi < 9.0e15,
            "time out of range: {} ticks",
            x.hi
        );
        let mut k = x.hi.floor();
        let mut f = x.minus(Dd::from_f64(k));
        if f.is_neg() {
            k -= 1.0;
            f = f.plus(Dd::from_f64(1.0));
        } else if Dd::from_f64(1.0).le(f) {
            k += 1.0;
            f = f.minus(Dd::from_f64(1.0));
        }
        let d = f.minus(Dd::from_f64(0.5));
        let dist = d.abs().to_f64();
        let _ = scale;
        let up = if dist <= TIME_TIE_BAND_TICKS {
            self.ties.exact_ties += 1;
            true
        } else {
            self.ties.min_distance = self.ties.min_distance.min(dist);
            !d.is_neg()
        };
        let tick = k + if up { 1.0 } else { 0.0 };
        (tick as u64, x.minus(Dd::from_f64(tick)).to_f64())
    }

    /// Starts the front block: fixes its profile from the plan over the
    /// window, times its events and advances the run clock.
    fn start_front(&mut self) {
        let m = self.queue.len().min(self.limits.window);
        // Backward pass: the largest entry² of block 1 of the window given
        // rest at its end.
        let mut exit2_max = Dd::ZERO;
        for j in (1..m).rev() {
            let b = &self.queue[j];
            exit2_max = b.junction2.min(exit2_max.plus(b.two_al));
        }
        let block = self.queue.pop_front().expect("a queued block");
        if !self.run_active {
            self.run_active = true;
            self.runs += 1;
            self.clock = Dd::ZERO;
            self.scale = Dd::ZERO;
            self.exit2 = Dd::ZERO;
            self.last_tick = 0;
        }
        let run = self.runs - 1;

        // The trapezoid.
        let ve2 = self.exit2;
        let vx2 = exit2_max.min(ve2.plus(block.two_al));
        let vc2 = block
            .vmax2
            .min(block.two_al.plus(ve2).plus(vx2).half())
            .max(ve2)
            .max(vx2);
        let (ve, vc, vx) = (ve2.sqrt(), vc2.sqrt(), vx2.sqrt());
        let two_a = block.a.times_f64(2.0);
        let d_acc = vc2.minus(ve2).over(two_a);
        let d_dec = vc2.minus(vx2).over(two_a);
        let d_cruise = block.l_mm.minus(d_acc).minus(d_dec).max(Dd::ZERO);
        let t_acc = d_acc.plus(d_acc).over(ve.plus(vc));
        let t_dec = d_dec.plus(d_dec).over(vx.plus(vc));
        let t_cruise = d_cruise.over(vc);
        let dur = t_acc.plus(t_cruise).plus(t_dec);
        let trap = Trapezoid {
            ve,
            ve2,
            vc,
            vx,
            vx2,
            two_a,
            d_acc,
            d_dec,
            t_acc,
            dur,
        };
        // Error scale of this block's times: its duration and twice the time
        // to reach v_c from rest.
        let block_scale = dur.plus(vc.over(block.a).times_f64(2.0));
        let event_scale = self.scale.plus(block_scale);

        // The events.
        let index = self.profiles.len() as u64;
        let lead = block.lead;
        let p0 = block.p0[lead];
        let p1 = block.p1[lead];
        let sigma = block.sigma;
        let span = if sigma < 0 {
            p0.minus(p1)
        } else {
            p1.minus(p0)
        };
        // Chord ends are on the grid, their impulses of the points before
        // rounding: a boundary may lie up to half a unit beyond.
        let slack = 0.5 + BOUNDARY_SLACK_REL * (p0.hi.abs() + p1.hi.abs() + UNITS_PER_MM as f64);
        // A chord of a fraction of a grid unit may not move its lead axis
        // the way its impulses go at all: its events happen at its end.
        let forward = !span.is_neg() && !span.is_zero();
        assert!(
            block.bytes.is_empty() || forward || span.abs().to_f64() <= 1.0,
            "the registers move the lead axis against its coordinate"
        );
        let q = self.price_q[lead] as i128;
        let a0 = block.a0 as i128;
        for (i, &byte) in (1i128..).zip(&block.bytes) {
            let b = Dd::from_i128((2 * a0 + (2 * i - 1) * sigma as i128) * 5 * q);
            let (mut n0, mut n1) = (b.minus(p0), p1.minus(b));
            if sigma < 0 {
                (n0, n1) = (n0.neg(), n1.neg());
            }
            let (s, r) = if forward {
                assert!(
                    n0.to_f64() >= -slack && n1.to_f64() >= -slack,
                    "event {i} boundary lies outside its block: registers do not match the points"
                );
                (
                    block.l_mm.times(n0.max(Dd::ZERO)).over(span),
                    block.l_mm.times(n1.max(Dd::ZERO)).over(span),
                )
            } else {
                (block.l_mm, Dd::ZERO)
            };
            let t = self.clock.plus(trap.time_at(s, r));
            let (tick, offset) = self.round_time(t, event_scale);
            self.record(byte, tick, run, Some(index), offset);
        }

        self.profiles.push(BlockProfile {
            run,
            length_mm: block.l_mm.to_f64(),
            v_entry: ve.to_f64(),
            v_cruise: vc.to_f64(),
            v_exit: vx.to_f64(),
            v_max: block.vmax.to_f64(),
            accel: block.a.to_f64(),
            start_s: self.clock.to_f64(),
            duration_s: dur.to_f64(),
            events: block.bytes.len() as u64,
        });
        self.clock = self.clock.plus(dur);
        self.scale = event_scale;
        self.exit2 = vx2;
    }
}

/// Prices in 10⁻⁶ mm.
fn prices(price_mm: [f64; 2]) -> [i64; 2] {
    price_mm.map(|h| match decimal_micro(h) {
        Some(q) if q >= 1 => q,
        _ => panic!("a price must be a positive decimal with at most 6 decimals, got {h}"),
    })
}

/// Junction cap², mm²/s², between a block along `d0` (length `l0`) and the
/// next along `d1` (length `l1`), both in units of 10⁻⁷ mm: `a_min·δ·s/(1 −
/// s)` capped by `cap2`, computed without cancellation (see the module
/// documentation).
fn junction2(d0: [Dd; 2], l0: Dd, d1: [Dd; 2], l1: Dd, a_min: Dd, delta: Dd, cap2: Dd) -> Dd {
    let dot = d0[0].times(d1[0]).plus(d0[1].times(d1[1]));
    let cross = d0[0].times(d1[1]).minus(d0[1].times(d1[0]));
    if cross.is_zero() {
        // Collinear: straight on (s = 1) or back (s = 0).
        return if dot.is_neg() { Dd::ZERO } else { cap2 };
    }
    if delta.is_zero() {
        return Dd::ZERO;
    }
    let p = l0.times(l1);
    let c2 = cross.times(cross);
    let two_p = p.times_f64(2.0);
    // 1 − s² = (1 − cos ψ)/2 and s² = (1 + cos ψ)/2, cos ψ = dot/p.
    let (one_minus_s2, s2) = if dot.is_neg() {
        (p.minus(dot).over(two_p), c2.over(two_p.times(p.minus(dot))))
    } else {
        (c2.over(two_p.times(p.plus(dot))), p.plus(dot).over(two_p))
    };
    let s = s2.sqrt();
    let v2 = a_min
        .times(delta)
        .times(s)
        .times(s.plus(Dd::from_f64(1.0)))
        .over(one_minus_s2);
    v2.min(cap2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::impulse::seq_crc;

    /// Exact `Q(n/d)`, round half away from zero: the exact model's.
    fn q_exact(n: i128, d: i128) -> i64 {
        crate::exact::q_div(n, d) as i64
    }

    /// mm → units of 10⁻⁷ mm (for test values with at most 7 decimals).
    fn u(mm: f64) -> i64 {
        (mm * UNITS_PER_MM as f64).round() as i64
    }

    /// Default prices: X 0.005 mm, Z 0.01 mm.
    const PRICES: [f64; 2] = [0.005, 0.01];

    fn model(limits: MotionLimits) -> RefMotion {
        RefMotion::new(limits, PRICES)
    }

    /// Registers `Q(P/h)` of a point in units, for the default prices.
    fn regs(x: i64, z: i64) -> [i64; 2] {
        [
            q_exact(x as i128, 50_000), // 0.005 mm = 50 000 units
            q_exact(z as i128, 100_000),
        ]
    }

    /// Queues a line to (X radius, Z) in mm.
    fn line(m: &mut RefMotion, x_mm: f64, z_mm: f64, feed: Option<f64>) {
        let (x, z) = (u(x_mm), u(z_mm));
        m.push(Point::from_units(x, z), regs(x, z), feed);
    }

    /// Ticks strictly increase within every block, and never decrease within
    /// a run.
    fn check_monotone(events: &[TimedEvent]) {
        for w in events.windows(2) {
            if w[0].run == w[1].run {
                assert!(w[1].tick >= w[0].tick, "{w:?}");
                if w[0].block.is_some() && w[0].block == w[1].block {
                    assert!(w[1].tick > w[0].tick, "{w:?}");
                }
            }
            assert!(w[0].offset_ticks.abs() <= 0.5);
        }
    }

    fn tick_of(t_s: f64) -> u64 {
        (t_s * 1e6).round() as u64
    }

    #[test]
    fn double_double_basics() {
        let two = Dd::from_f64(2.0);
        let r = two.sqrt();
        assert!(r.times(r).minus(two).abs().to_f64() < 1e-31);
        let third = Dd::from_f64(1.0).over(Dd::from_f64(3.0));
        assert!(third.times_f64(3.0).minus(Dd::from_f64(1.0)).abs().to_f64() < 1e-31);
        // 0.1 is taken as the decimal one tenth, not as its f64 rounding.
        let tenth = decimal(0.1);
        assert!(
            tenth
                .times_f64(10.0)
                .minus(Dd::from_f64(1.0))
                .abs()
                .to_f64()
                < 1e-31
        );
        assert_eq!(decimal_micro(123.456789), Some(123_456_789));
        assert_eq!(decimal_micro(0.1 + 1e-12), None);
        assert_eq!(decimal_micro(1.0 / 3.0), None);
        assert_eq!(Dd::from_i128(1 << 100).hi, (1u128 << 100) as f64);
        let big = (1i128 << 80) + 12345;
        let d = Dd::from_i128(big);
        assert_eq!(d.hi as i128 + d.lo as i128, big);
    }

    #[test]
    fn rapid_along_z_trapezoid() {
        // Z 0 → 100 mm, rapid: v = 3000/60 = 50 mm/s, a = 150 mm/s².
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.0, 100.0, None);
        let r = m.sync();
        let (v, a, l) = (50.0f64, 150.0f64, 100.0f64);
        // Accelerating part v²/2a = 8.33 mm, duration L/v + v/a = 7/3 s.
        let d = l / v + v / a;
        assert!((d - 7.0 / 3.0).abs() < 1e-15);
        let p = m.profiles()[0];
        assert_eq!((p.v_entry, p.v_exit), (0.0, 0.0));
        assert!((p.v_cruise - v).abs() < 1e-12 && (p.v_max - v).abs() < 1e-12);
        assert!((p.accel - a).abs() < 1e-12);
        assert!((p.duration_s - d).abs() < 1e-14);
        assert_eq!(r.t, 2_333_333);
        assert_eq!(r.ev, 10_000);
        let ev = m.events();
        assert_eq!(ev.len(), 10_000);
        // First event at 0.005 mm: t = √(2·0.005/150) = √(1/15000) s = 8164.97 µs.
        assert_eq!(ev[0].tick, 8165);
        assert!((ev[0].offset_ticks - (8_164.965_809_277_26 - 8165.0)).abs() < 1e-8);
        // Event 5001 at 50.005 mm, in the cruise: 1/3 + (50.005 − 25/3)/50 s.
        assert_eq!(ev[5000].tick, 1_166_767);
        // The last one at 99.995 mm, by symmetry 7/3 s − 8164.97 µs.
        assert_eq!(ev[9999].tick, 2_325_168);
        assert!(ev.iter().all(|e| e.byte == 0x02 && e.block == Some(0)));
        // Every event against the closed form in f64.
        for (i, e) in ev.iter().enumerate() {
            let s = (i as f64 + 0.5) * 0.01;
            let da = v * v / (2.0 * a);
            let t = if s <= da {
                (2.0 * s / a).sqrt()
            } else if l - s <= da {
                d - (2.0 * (l - s) / a).sqrt()
            } else {
                v / a + (s - da) / v
            };
            assert!(
                (t * 1e6 - (e.tick as f64 + e.offset_ticks)).abs() < 1e-6,
                "{i}"
            );
        }
        check_monotone(ev);
    }

    #[test]
    fn short_block_is_a_triangle() {
        // Z 0 → 10 mm: √(aL) = √1500 = 38.73 < 50 mm/s.
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.0, 10.0, None);
        let r = m.sync();
        let p = m.profiles()[0];
        assert!((p.v_cruise - 1500f64.sqrt()).abs() < 1e-12);
        let d = 2.0 * (10.0f64 / 150.0).sqrt(); // 0.516 397 779 s
        assert!((p.duration_s - d).abs() < 1e-15);
        assert_eq!(r.t, 516_398);
        assert_eq!(r.ev, 1000);
        assert_eq!(m.events()[0].tick, 8165);
        // The middle event (4.995 mm) is just before the peak at 5 mm.
        let t = (2.0f64 * 4.995 / 150.0).sqrt();
        assert_eq!(m.events()[499].tick, tick_of(t));
        check_monotone(m.events());
    }

    #[test]
    fn collinear_blocks_do_not_slow_down() {
        let mut one = model(MotionLimits::default());
        line(&mut one, 0.0, 100.0, None);
        one.flush();
        let mut two = model(MotionLimits::default());
        line(&mut two, 0.0, 50.0, None);
        line(&mut two, 0.0, 100.0, None);
        two.flush();
        let p = two.profiles();
        assert!((p[0].v_exit - 50.0).abs() < 1e-12);
        assert_eq!(p[1].v_entry, p[0].v_exit);
        assert_eq!(one.events().len(), two.events().len());
        for (a, b) in one.events().iter().zip(two.events()) {
            assert_eq!((a.byte, a.tick), (b.byte, b.tick));
            assert!((a.offset_ticks - b.offset_ticks).abs() < 1e-12);
        }
        assert_eq!(one.sync().t, two.sync().t);

        // A diagonal with δ = 0: collinearity is decided exactly, no stop.
        let limits = MotionLimits {
            junction_mm: 0.0,
            ..MotionLimits::default()
        };
        let mut m = model(limits);
        line(&mut m, 1.0, 2.0, Some(600.0));
        line(&mut m, 3.0, 6.0, Some(600.0));
        m.flush();
        assert!((m.profiles()[0].v_exit - 10.0).abs() < 1e-12);
        // ... but a real corner is taken at rest.
        let mut m = model(limits);
        line(&mut m, 1.0, 2.0, Some(600.0));
        line(&mut m, 3.0, 6.000001, Some(600.0));
        m.flush();
        assert_eq!(m.profiles()[0].v_exit, 0.0);
    }

    #[test]
    fn right_angle_corner() {
        // Z 0 → −20, then X 0 → 10 (radius). cos θ = 0, s = √½,
        // s/(1 − s) = 1 + √2; a_min = AX = 100, δ = 0.01: v_j² = 1 + √2.
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.0, -20.0, None);
        line(&mut m, 10.0, -20.0, None);
        let r = m.sync();
        let p = m.profiles();
        let vj = (1.0 + 2f64.sqrt()).sqrt(); // 1.553 773 974 mm/s
        assert!((p[0].v_exit - vj).abs() < 1e-14, "{}", p[0].v_exit);
        assert_eq!(p[1].v_entry, p[0].v_exit);
        assert!((p[1].v_max - 25.0).abs() < 1e-12 && (p[1].accel - 100.0).abs() < 1e-12);
        assert_eq!(r.ev, 2000 + 2000);
        // Block 1 in closed form: from vj to 25 mm/s and back to rest at 100 mm/s².
        let (a, v) = (100.0, 25.0);
        let d1 =
            (v - vj) / a + (10.0 - (v * v - vj * vj) / (2.0 * a) - v * v / (2.0 * a)) / v + v / a;
        assert!((p[1].duration_s - d1).abs() < 1e-13);
        assert_eq!(r.t, tick_of(p[0].duration_s + d1));
        // Events of the X block are negative-free X steps.
        assert!(m.events()[2000..].iter().all(|e| e.byte == 0x01));
        check_monotone(m.events());

        // A larger δ raises the junction, capped by the slower block (25 mm/s).
        let mut m = model(MotionLimits {
            junction_mm: 10.0,
            ..MotionLimits::default()
        });
        line(&mut m, 0.0, -20.0, None);
        line(&mut m, 10.0, -20.0, None);
        m.flush();
        assert!((m.profiles()[0].v_exit - 25.0).abs() < 1e-12);
    }

    #[test]
    fn reversal_stops() {
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.0, 10.0, None);
        line(&mut m, 0.0, 0.0, None);
        let r = m.sync();
        let p = m.profiles();
        assert_eq!(p[0].v_exit, 0.0);
        assert_eq!(p[1].v_entry, 0.0);
        let d = 2.0 * (10.0f64 / 150.0).sqrt();
        assert!((p[0].duration_s - d).abs() < 1e-15);
        assert!((p[1].start_s - d).abs() < 1e-15);
        assert_eq!(r.t, tick_of(2.0 * d)); // 1 032 795.56
        assert_eq!(r.t, 1_032_796);
        assert!(m.events()[1000..].iter().all(|e| e.byte == 0x0A));
        check_monotone(m.events());
    }

    #[test]
    fn junction_near_straight_keeps_its_digits() {
        // Turn by ψ = atan(10⁻⁷): 1 − s = 2·sin²(ψ/4), s = cos(ψ/2).
        let d0 = [Dd::ZERO, Dd::from_f64(1e7)];
        let d1 = [Dd::from_f64(1.0), Dd::from_f64(1e7)];
        let l0 = Dd::from_f64(1e7);
        let l1 = Dd::from_f64(1e14 + 1.0).sqrt();
        let huge = Dd::from_f64(1e300);
        let v2 = junction2(d0, l0, d1, l1, Dd::from_f64(100.0), decimal(0.01), huge);
        let psi = 1e-7f64.atan();
        let exact = 1.0 * (psi / 2.0).cos() / (2.0 * (psi / 4.0).sin().powi(2));
        assert!((v2.to_f64() / exact - 1.0).abs() < 1e-14, "{}", v2.to_f64());
        // Near a reversal: s = sin(ψ/2).
        let d1 = [Dd::from_f64(1.0), Dd::from_f64(-1e7)];
        let v2 = junction2(d0, l0, d1, l1, Dd::from_f64(100.0), decimal(0.01), huge);
        let s = (psi / 2.0).sin();
        assert!((v2.to_f64() / (s / (1.0 - s)) - 1.0).abs() < 1e-14);
        // Straight and reversed exactly.
        let d1 = [Dd::ZERO, Dd::from_f64(3.0)];
        let v2 = junction2(
            d0,
            l0,
            d1,
            Dd::from_f64(3.0),
            Dd::from_f64(1.0),
            Dd::ZERO,
            huge,
        );
        assert_eq!(v2, huge);
        let d1 = [Dd::ZERO, Dd::from_f64(-3.0)];
        let v2 = junction2(
            d0,
            l0,
            d1,
            Dd::from_f64(3.0),
            Dd::from_f64(1.0),
            decimal(0.01),
            huge,
        );
        assert_eq!(v2, Dd::ZERO);
    }

    /// A program of mixed lines, feeds and corners.
    fn mixed(m: &mut RefMotion) {
        line(m, 0.0, -5.0, None);
        line(m, 2.5, -7.5, Some(300.0));
        line(m, 2.5, -20.0, Some(300.0));
        line(m, 2.5, -20.0, Some(300.0)); // zero length
        line(m, 4.0, -23.0, Some(120.0));
        line(m, 4.0, -30.0, None);
        line(m, 10.0, -30.0, None);
        line(m, 10.0, -29.999, Some(50.0)); // short, no impulse
        line(m, 9.9973, -29.9, Some(900.0));
        line(m, 9.9973, -29.9004, Some(900.0)); // no impulse, still planned
        line(m, 0.0, 0.0, None);
    }

    #[test]
    fn window_larger_than_program_changes_nothing() {
        let mut a = model(MotionLimits::default());
        let mut b = model(MotionLimits {
            window: 10_000,
            ..MotionLimits::default()
        });
        mixed(&mut a);
        mixed(&mut b);
        assert_eq!(a.sync(), b.sync());
        assert_eq!(a.events(), b.events());
        assert_eq!(a.profiles(), b.profiles());
        assert_eq!(a.profiles().len(), 10);
        let p = a.profiles()[8];
        assert_eq!((p.events, p.length_mm), (0, 0.0004));
        check_monotone(a.events());

        // 100 collinear blocks of 1 mm: the braking distance (8.3 mm) is inside
        // a window of 64 mm, so W = 64 plans as an unlimited window does.
        let mut a = model(MotionLimits::default());
        let mut b = model(MotionLimits {
            window: 10_000,
            ..MotionLimits::default()
        });
        for k in 1..=100 {
            line(&mut a, 0.0, k as f64, None);
            line(&mut b, 0.0, k as f64, None);
        }
        assert_eq!(a.sync(), b.sync());
        assert_eq!(a.events(), b.events());
    }

    #[test]
    fn rolling_horizon_with_two_blocks() {
        // W = 2: block k is planned with k, k+1 and rest at the end of k+1.
        // Collinear 1 mm blocks along Z, a = 150: 2aL = 300 mm²/s².
        let mut m = model(MotionLimits {
            window: 2,
            ..MotionLimits::default()
        });
        line(&mut m, 0.0, 1.0, None);
        assert!(
            m.profiles().is_empty(),
            "block 0 waits for one block after it"
        );
        for k in 2..=5 {
            line(&mut m, 0.0, k as f64, None);
            assert_eq!(m.profiles().len(), k - 1);
        }
        m.flush();
        let p = m.profiles();
        let exits: Vec<f64> = p.iter().map(|b| b.v_exit * b.v_exit).collect();
        let cruise: Vec<f64> = p.iter().map(|b| b.v_cruise * b.v_cruise).collect();
        for (e, x) in exits.iter().zip([300.0, 300.0, 300.0, 300.0, 0.0]) {
            assert!((e - x).abs() < 1e-11, "{exits:?}");
        }
        // v_c² = (2aL + v_entry² + v_exit²)/2.
        for (c, x) in cruise.iter().zip([300.0, 450.0, 450.0, 450.0, 300.0]) {
            assert!((c - x).abs() < 1e-11, "{cruise:?}");
        }
        for w in p.windows(2) {
            assert_eq!(w[1].v_entry, w[0].v_exit);
        }
        // Block 1: accelerate √300 → √450 over 0.5 mm, decelerate back.
        let (a, v0, v1) = (150.0f64, 300f64.sqrt(), 450f64.sqrt());
        assert!((p[1].duration_s - 2.0 * (v1 - v0) / a).abs() < 1e-15);
        check_monotone(m.events());

        // With an unlimited window the same program peaks mid-way (in block
        // 2) at √(a·5 mm) = √750 = 27.4 mm/s.
        let mut b = model(MotionLimits {
            window: 10_000,
            ..MotionLimits::default()
        });
        for k in 1..=5 {
            line(&mut b, 0.0, k as f64, None);
        }
        b.flush();
        let peak = b.profiles()[2].v_cruise;
        assert!((peak - 750f64.sqrt()).abs() < 1e-12);

        // W = 1: every block ends at rest.
        let mut c = model(MotionLimits {
            window: 1,
            ..MotionLimits::default()
        });
        for k in 1..=3 {
            line(&mut c, 0.0, k as f64, None);
            assert_eq!(c.profiles().len(), k);
        }
        assert!(c.profiles().iter().all(|p| p.v_exit == 0.0));
    }

    #[test]
    fn zero_length_block_is_transparent() {
        let mut a = model(MotionLimits::default());
        line(&mut a, 0.0, 50.0, None);
        line(&mut a, 0.0, 100.0, None);
        let mut b = model(MotionLimits::default());
        line(&mut b, 0.0, 50.0, None);
        line(&mut b, 0.0, 50.0, None);
        line(&mut b, 0.0, 100.0, None);
        assert_eq!(a.sync(), b.sync());
        assert_eq!(a.profiles(), b.profiles());
        // Alone, it makes no run.
        let mut c = model(MotionLimits::default());
        line(&mut c, 0.0, 0.0, None);
        assert_eq!(
            c.sync(),
            SyncReport {
                ev: 0,
                t: 0,
                tseq: 0
            }
        );
        assert_eq!(c.runs(), 0);
    }

    #[test]
    fn block_without_impulses_takes_time() {
        // Z 0.004 mm at 0.01 mm per impulse: no impulse, a triangle of
        // 2·√(0.004/150) s = 10 327.96 µs.
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.0, 0.004, None);
        let r = m.sync();
        assert_eq!(m.profiles().len(), 1);
        assert_eq!(
            r,
            SyncReport {
                ev: 0,
                t: 10_328,
                tseq: 0
            }
        );
    }

    #[test]
    fn exact_half_tick_ties_round_up() {
        // X from radius 0.0000005 mm (diameter word 0.000001) to 1 mm at
        // F = 60 mm/min = 1 mm/s, AX = 100: ramps of 0.01 s over 0.005 mm.
        // Event i ≥ 2 (boundary (i − ½)·0.005 mm) cruises at
        // 0.01 + (i − ½)·0.005 − 0.0000005 − 0.005 s = (5000i + 2499.5) µs.
        let mut m = model(MotionLimits::default());
        m.set_position(Point::from_units(5, 0), [0, 0]);
        m.push(Point::from_units(u(1.0), 0), [200, 0], Some(60.0));
        let r = m.sync();
        let ev = m.events();
        assert_eq!(ev.len(), 200);
        // Event 1 accelerates: √(2·0.0024995/100) s = 7070.36 µs.
        assert_eq!(ev[0].tick, 7070);
        for (i, e) in (1u64..).zip(ev).take(199).skip(1) {
            assert_eq!(e.tick, 5000 * i + 2500, "event {i}");
            assert!((e.offset_ticks + 0.5).abs() < 1e-12);
        }
        // Event 200 decelerates: 1.0099995 − √(2·0.0025/100) s.
        assert_eq!(ev[199].tick, tick_of(1.0099995 - 0.00005f64.sqrt()));
        // The run lasts 1 009 999.5 µs: a tie too.
        assert_eq!(r.t, 1_010_000);
        assert_eq!(m.ties().exact_ties, 198 + 1);
        assert!(m.ties().min_distance > 0.05);
    }

    #[test]
    fn tseq_records_byte_and_tick_delta() {
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.03, -0.05, Some(100.0));
        line(&mut m, 0.0, 0.0, None);
        m.flush(); // a run of its own
        line(&mut m, 0.0, 0.02, None);
        let r = m.sync();
        let ev = m.events();
        assert_eq!(r.ev, ev.len() as u64);
        assert_eq!(r.ev, 6 + 6 + 2);
        let mut bytes = Vec::new();
        let mut last = (u64::MAX, 0u64);
        for e in ev {
            let base = if e.run == last.0 { last.1 } else { 0 };
            bytes.push(e.byte);
            bytes.extend_from_slice(&((e.tick - base) as u32).to_le_bytes());
            last = (e.run, e.tick);
        }
        assert_eq!(r.tseq, seq_crc(&bytes));
        assert_eq!(m.runs(), 2);
        // T is the last run's: Z 0.02 mm from rest to rest.
        assert_eq!(r.t, tick_of(2.0 * (0.02f64 / 150.0).sqrt()));
        // The counters restart.
        assert_eq!(
            m.sync(),
            SyncReport {
                ev: 0,
                t: 0,
                tseq: 0
            }
        );
        line(&mut m, 0.0, 0.01, None);
        m.zero_counters();
        m.set_position(Point::from_units(0, 0), [0, 0]);
        assert_eq!(
            m.sync(),
            SyncReport {
                ev: 0,
                t: 0,
                tseq: 0
            }
        );
        check_monotone(m.events());
    }

    #[test]
    fn direct_arc_runs_at_its_rate() {
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.0, 1.0, None);
        // RATE 400 000: j·2.5 ticks, ties at odd j round up.
        let bytes = [0x01, 0x03, 0x02, 0x03];
        m.direct(&bytes, 400_000.0, Point::from_units(0, 0), [0, 0]);
        let ev: Vec<&TimedEvent> = m.events().iter().filter(|e| e.block.is_none()).collect();
        let ticks: Vec<u64> = ev.iter().map(|e| e.tick).collect();
        assert_eq!(ticks, [3, 5, 8, 10]);
        assert!(ev.iter().all(|e| e.run == 1));
        assert_eq!(m.ties().exact_ties, 2);
        let r = m.sync();
        assert_eq!(r.t, 10);
        assert_eq!(r.ev, 100 + 4);

        // RATE 30 000: 33.3, 66.7, 100 ticks.
        m.direct(&[0x02; 3], 30_000.0, Point::from_units(0, 0), [0, 0]);
        let r = m.sync();
        let mut rec = Vec::new();
        for (b, d) in [(0x02u8, 33u32), (0x02, 34), (0x02, 33)] {
            rec.push(b);
            rec.extend_from_slice(&d.to_le_bytes());
        }
        assert_eq!(
            r,
            SyncReport {
                ev: 3,
                t: 100,
                tseq: seq_crc(&rec)
            }
        );
        // Against Q(j·TICK/RATE) in integers.
        for (j, e) in (1i128..).zip(&m.events()[m.events().len() - 3..]) {
            assert_eq!(e.tick as i64, q_exact(j * 1_000_000, 30_000));
        }
        // No events: no run.
        m.direct(&[], 30_000.0, Point::from_units(0, 0), [0, 0]);
        assert_eq!(
            m.sync(),
            SyncReport {
                ev: 0,
                t: 0,
                tseq: 0
            }
        );
    }

    #[test]
    fn settings_flush() {
        let mut m = model(MotionLimits::default());
        line(&mut m, 0.0, 10.0, None);
        m.set_limits(MotionLimits {
            vmax_mm_min: [600.0, 600.0],
            ..MotionLimits::default()
        });
        assert_eq!(m.profiles().len(), 1);
        assert_eq!(m.profiles()[0].v_exit, 0.0);
        line(&mut m, 0.0, 20.0, None);
        m.flush();
        assert!((m.profiles()[1].v_cruise - 10.0).abs() < 1e-12);
        assert_eq!(m.runs(), 2);
    }

    #[test]
    fn long_run_keeps_its_clock() {
        // Z 0 → 1000 mm at F = 100 mm/min (10 minutes): one block, or 1000
        // collinear blocks of 1 mm summed on the run clock. Same ticks, same
        // offsets to 10⁻¹² tick at 6·10⁸ ticks.
        let mut one = model(MotionLimits::default());
        line(&mut one, 0.0, 1000.0, Some(100.0));
        let r1 = one.sync();
        let mut many = model(MotionLimits::default());
        for k in 1..=1000 {
            line(&mut many, 0.0, k as f64, Some(100.0));
        }
        let r2 = many.sync();
        assert_eq!(r1, r2);
        let v = 100.0 / 60.0;
        assert_eq!(r1.t, tick_of(1000.0 / v + v / 150.0));
        let mut worst = 0.0f64;
        for (a, b) in one.events().iter().zip(many.events()) {
            assert_eq!((a.byte, a.tick), (b.byte, b.tick));
            worst = worst.max((a.offset_ticks - b.offset_ticks).abs());
        }
        assert!(worst < 1e-12, "{worst}");
        check_monotone(many.events());
    }

    /// An independent f64 model of the rules, written the plain way: the
    /// rolling horizon as "block k is planned over k … min(k+W−1, n−1)",
    /// closed-form trapezoids, event times from the block start. Returns
    /// (exit speed per block, T·TICK per event).
    fn naive(
        points: &[(i64, i64)],
        feeds: &[Option<f64>],
        lim: &MotionLimits,
    ) -> (Vec<f64>, Vec<f64>) {
        struct B {
            l: f64,
            a: f64,
            vmax: f64,
            p0: (i64, i64),
            p1: (i64, i64),
            dint: (i64, i64),
        }
        let mut bs: Vec<B> = Vec::new();
        for (w, f) in points.windows(2).zip(feeds) {
            let dint = (w[1].0 - w[0].0, w[1].1 - w[0].1);
            if dint == (0, 0) {
                continue;
            }
            let d = (dint.0 as f64 / 1e7, dint.1 as f64 / 1e7);
            let l = d.0.hypot(d.1);
            let mut a = f64::INFINITY;
            let mut vmax = f.map_or(f64::INFINITY, |f| f / 60.0);
            for (k, c) in [d.0, d.1].into_iter().enumerate() {
                if c != 0.0 {
                    a = a.min(lim.amax_mm_s2[k] * l / c.abs());
                    vmax = vmax.min(lim.vmax_mm_min[k] / 60.0 * l / c.abs());
                }
            }
            bs.push(B {
                l,
                a,
                vmax,
                p0: w[0],
                p1: w[1],
                dint,
            });
        }
        let n = bs.len();
        // Junction speed² at the entry of block k (k ≥ 1).
        let jn: Vec<f64> = (0..n)
            .map(|k| {
                if k == 0 {
                    return 0.0;
                }
                let (p, q) = (&bs[k - 1], &bs[k]);
                let cap = p.vmax.min(q.vmax).powi(2);
                let cross =
                    p.dint.0 as i128 * q.dint.1 as i128 - p.dint.1 as i128 * q.dint.0 as i128;
                let dot = p.dint.0 as i128 * q.dint.0 as i128 + p.dint.1 as i128 * q.dint.1 as i128;
                if cross == 0 {
                    return if dot > 0 { cap } else { 0.0 };
                }
                // ψ the turn between the directions: s = cos(ψ/2), 1 − s = 2·sin²(ψ/4).
                let psi = (cross as f64).abs().atan2(dot as f64);
                let s = (psi / 2.0).cos();
                let one_minus_s = 2.0 * (psi / 4.0).sin().powi(2);
                (p.a.min(q.a) * lim.junction_mm * s / one_minus_s).min(cap)
            })
            .collect();
        let mut exits = Vec::new();
        let mut times = Vec::new();
        let mut clock = 0.0;
        let mut ve = 0.0f64;
        for k in 0..n {
            let end = (k + lim.window - 1).min(n - 1);
            let mut e2 = 0.0f64;
            for j in (k + 1..=end).rev() {
                e2 = jn[j].min(e2 + 2.0 * bs[j].a * bs[j].l);
            }
            let b = &bs[k];
            let vx = e2.min(ve * ve + 2.0 * b.a * b.l).sqrt();
            let vc = b
                .vmax
                .min(((2.0 * b.a * b.l + ve * ve + vx * vx) / 2.0).sqrt());
            let da = (vc * vc - ve * ve) / (2.0 * b.a);
            let dd = (vc * vc - vx * vx) / (2.0 * b.a);
            let dur = (vc - ve) / b.a + (b.l - da - dd).max(0.0) / vc + (vc - vx) / b.a;
            // Events along the lead axis by impulses.
            let r0 = regs(b.p0.0, b.p0.1);
            let r1 = regs(b.p1.0, b.p1.1);
            let (dx, dz) = (r1[0] - r0[0], r1[1] - r0[1]);
            let lead = usize::from(dx.abs() < dz.abs());
            let (a0, dl, h) = if lead == 0 {
                (r0[0], dx, 50_000.0)
            } else {
                (r0[1], dz, 100_000.0)
            };
            let (c0, c1) = if lead == 0 {
                (b.p0.0 as f64, b.p1.0 as f64)
            } else {
                (b.p0.1 as f64, b.p1.1 as f64)
            };
            for i in 1..=dl.abs() {
                let bnd = (a0 as f64 + (i as f64 - 0.5) * dl.signum() as f64) * h;
                let s = (bnd - c0) / (c1 - c0) * b.l;
                let t = if s <= 0.0 {
                    0.0
                } else if b.l - s <= 0.0 {
                    dur
                } else if s <= da {
                    2.0 * s / (ve + (ve * ve + 2.0 * b.a * s).sqrt())
                } else if b.l - s <= dd {
                    let r = (b.l - s).max(0.0);
                    dur - 2.0 * r / (vx + (vx * vx + 2.0 * b.a * r).sqrt())
                } else {
                    (vc - ve) / b.a + (s - da) / vc
                };
                times.push((clock + t) * lim.tick_hz);
            }
            clock += dur;
            exits.push(vx);
            ve = vx;
        }
        times.push(clock * lim.tick_hz);
        (exits, times)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        #[test]
        fn agrees_with_a_plain_f64_model(
            steps in proptest::collection::vec(
                ((-400i64..=400, -400i64..=400), proptest::option::of(10u32..3000)),
                1..14,
            ),
            window in proptest::sample::select(vec![1usize, 2, 3, 5, 64]),
            jd in proptest::sample::select(vec![0.0, 0.01, 0.5]),
        ) {
            let lim = MotionLimits { window, junction_mm: jd, ..MotionLimits::default() };
            let mut m = model(lim);
            // Points on a 0.0025 mm grid, within ±1 mm; some repeat.
            let mut points = vec![(0i64, 0i64)];
            let mut feeds = Vec::new();
            for ((x, z), f) in &steps {
                let p = (x * 25_000, z * 25_000);
                points.push(p);
                feeds.push(f.map(f64::from));
                m.push(Point::from_units(p.0, p.1), regs(p.0, p.1), f.map(f64::from));
            }
            let r = m.sync();
            let (exits, times) = naive(&points, &feeds, &lim);
            let p = m.profiles();
            proptest::prop_assert_eq!(p.len(), exits.len());
            for (b, e) in p.iter().zip(&exits) {
                proptest::prop_assert!((b.v_exit - e).abs() <= 1e-9 * (1.0 + e), "{:?} {}", b, e);
                proptest::prop_assert!(b.v_cruise <= b.v_max * (1.0 + 1e-15));
            }
            let ev = m.events();
            proptest::prop_assert_eq!(ev.len() + 1, times.len());
            for (e, t) in ev.iter().zip(&times) {
                let tol = 1e-7 + 1e-11 * t;
                let mine = e.tick as f64 + e.offset_ticks;
                proptest::prop_assert!((mine - t).abs() < tol, "{:?} {}", e, t);
                if (e.offset_ticks.abs() - 0.5).abs() > tol {
                    proptest::prop_assert_eq!(e.tick, t.round() as u64);
                }
            }
            let t_end = times[times.len() - 1];
            if !p.is_empty() {
                proptest::prop_assert!((r.t as f64 - t_end).abs() <= 0.5 + 1e-6);
            }
            check_monotone(ev);
        }
    }

    #[test]
    fn chord_ends_as_computed_points() {
        // A quarter circle of radius 5 about (0, −5) in 90 chords, from
        // (0, 0) to (5, −5), at F = 300 mm/min: chord ends given in mm.
        let mut m = model(MotionLimits::default());
        let n = 90;
        let mut regs_prev = [0i64, 0];
        for i in 1..=n {
            let phi = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
            let (x, z) = (5.0 * phi.sin(), -5.0 + 5.0 * phi.cos());
            let mut t = TieStats::new();
            let r = [
                crate::impulse::quantize(x / 0.005, &mut t),
                crate::impulse::quantize(z / 0.01, &mut t),
            ];
            m.push(Point::from_mm(x, z), r, Some(300.0));
            regs_prev = r;
        }
        assert_eq!(regs_prev, [1000, -500]);
        m.flush();
        let p = m.profiles();
        assert_eq!(p.len(), n);
        // 1° turns: v_j² = a·δ·s/(1 − s) ≈ 8aδ/ψ² ≈ 2.6·10⁴ mm²/s², far above
        // the feed (5 mm/s), which binds once reached (after 0.08 mm).
        for b in &p[10..n - 10] {
            assert!((b.v_entry - 5.0).abs() < 1e-12, "{b:?}");
        }
        assert!(p.iter().all(|b| b.v_cruise <= 5.0 + 1e-12));
        check_monotone(m.events());
    }
}

/// The backlash rule of `docs/motion.md` §7: each axis' play in impulses
/// and the take-up steps issued, net.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefBacklash {
    /// `B_a`, impulses (X radius, Z).
    pub play: [i64; 2],
    /// `U_a`: 0 after a move towards minus, `B_a` after one towards plus.
    pub taken: [i64; 2],
}

impl RefBacklash {
    /// The play of `backlash_mm` (X radius, Z) at prices `price_mm`,
    /// `Q(backlash/h)` rounded half away from zero; nothing taken up.
    pub fn new(backlash_mm: [f64; 2], price_mm: [f64; 2]) -> RefBacklash {
        let q = prices(price_mm);
        let b = backlash_mm.map(|b| decimal_micro(b).expect("a decimal of at most 6 decimals"));
        let n = |b: i64, h: i64| (2 * b + h) / (2 * h);
        RefBacklash {
            play: [n(b[0], q[0]), n(b[1], q[1])],
            taken: [0, 0],
        }
    }

    /// Before a block whose impulses go `delta` (X, Z): the take-up block's
    /// steps, if any axis it moves must turn through its play first.
    pub fn before(&mut self, delta: [i64; 2]) -> Option<[i64; 2]> {
        let mut steps = [0; 2];
        for a in 0..2 {
            let want = match delta[a].signum() {
                1 => self.play[a],
                -1 => 0,
                _ => self.taken[a],
            };
            steps[a] = want - self.taken[a];
            self.taken[a] = want;
        }
        (steps != [0, 0]).then_some(steps)
    }
}

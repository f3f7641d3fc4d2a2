//! Properties of the velocity planner and the timed step generator
//! (`docs/motion.md` §1–§4), checked against an independent f64 model
//! of the rules on random programs and random limits, and the `SYNC`,
//! `STATUS` and refusal behaviour of the protocol at their boundaries.
//!
//! # The f64 model and its tolerances
//! Squared speeds are compared in the core's unit, Q64 (Å/tick)² (one unit
//! is 2⁻⁶⁴ (Å/tick)²). The model computes every quantity of a block from
//! its exact grid segment (integer ångström) and the limits:
//! `v_max² = min((F/60)², (VMAX_a/60/|u_a|)²)`, `a = min AMAX_a/|u_a|`,
//! `2aL`, and the junction speed with `sin ψ` and `cos ψ` taken from the
//! exact integer cross and dot products, so each is within a few 10⁻¹⁶ of
//! exact, relatively.
//!
//! The core floors every quotient and root once (one unit of its format);
//! directions between grid points are exact, their lengths floors of roots
//! (relative 2⁻⁶¹). The largest relative error of a junction speed is that
//! of `sin ψ` in Q64 near a straight continuation, about 2⁻⁶⁴/ψ, and a
//! junction is below its cap only for ψ > √(8aδ)/v_max ≥ 3·10⁻⁶ with the
//! limits' ranges, so it stays under 10⁻¹³. Bounds are therefore checked as
//! `core ≤ model·(1 + 10⁻⁹) + 64 units`: orders of magnitude above both
//! errors, and still far below anything a wrong formula produces (a
//! relative 10⁻⁶ off in `2aL`, `v_max²` or a junction fails them).
//! Where the core must *equal* the model (the plan being the largest one
//! the rules allow), the same margin applies on both sides, relative to the
//! largest squared speed involved since the backward pass adds 2aL terms,
//! plus the resolution of the slower axis's rate² (see [`check_run`]).

use core_nostd::impulse::{quantize, ImpulsePrice};
use core_nostd::interleave::{ImpulsePoint, LinearBlock};
use core_nostd::length::Length;
use core_nostd::machine::Status;
use core_nostd::plan::{Block, Feed, Limits, Planner, Rates, WINDOW};
use core_nostd::step::{TickRate, TimedBlock};
use host_sim::device::LocalDevice;
use proptest::prelude::*;
use std::collections::VecDeque;

// ---------------------------------------------------------------------------
// Units and the f64 model
// ---------------------------------------------------------------------------

/// Ticks per second.
const TICK: f64 = 1e6;
/// 2⁶⁴: squared speeds are Q64 (Å/tick)², times Q64 ticks.
const Q64: f64 = 18_446_744_073_709_551_616.0;
/// Relative margin of a comparison with the model (see the module docs).
const REL: f64 = 1e-9;
/// Absolute margin, Q64 (Å/tick)² units: a few floors of one unit each,
/// summed over a window of up to 64 blocks.
const ABS: f64 = 64.0;

/// The default impulse prices, X (radius) and Z.
const H: [ImpulsePrice; 2] = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];

fn len(angstrom: i64) -> Length {
    Length::from_angstrom(angstrom).unwrap()
}

/// `a ≤ b` up to the model's margin.
fn at_most(a: u128, b: f64) -> bool {
    (a as f64) <= b * (1.0 + REL) + ABS
}

/// The motion limits in integer units: rapid rates Å/min, accelerations
/// Å/s², junction deviation Å.
#[derive(Clone, Copy, Debug)]
struct Lim {
    v: [i64; 2],
    a: [i64; 2],
    jd: i64,
}

impl Lim {
    const DEFAULT: Lim = Lim {
        v: [15_000_000_000, 30_000_000_000],
        a: [1_000_000_000, 1_500_000_000],
        jd: 100_000,
    };

    fn limits(&self) -> Limits {
        Limits::new(
            [len(self.v[0]), len(self.v[1])],
            [len(self.a[0]), len(self.a[1])],
            len(self.jd),
        )
        .unwrap()
    }

    fn rates(&self) -> Rates {
        Rates::new(self.limits(), TickRate::TIMER)
    }
}

/// A rate in Å/min as a squared speed, Q64 (Å/tick)².
fn speed2(angstrom_per_min: f64) -> f64 {
    let v = angstrom_per_min / (60.0 * TICK);
    v * v * Q64
}

/// A straight segment between grid points (Å), at a feed (Å/min) or rapid.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Seg {
    from: [i64; 2],
    to: [i64; 2],
    feed: Option<i64>,
}

/// What the rules make of a segment, in f64.
#[derive(Clone, Copy, Debug)]
struct Model {
    /// Segment, Å.
    d: [f64; 2],
    /// Length, Å.
    l: f64,
    /// `v_max²`, Q64 (Å/tick)².
    vmax2: f64,
    /// `a`, Å/tick².
    accel: f64,
    /// `2aL`, Q64 (Å/tick)².
    two_al: f64,
}

impl Seg {
    fn delta(&self) -> [i64; 2] {
        [self.to[0] - self.from[0], self.to[1] - self.from[1]]
    }

    fn model(&self, lim: &Lim) -> Model {
        let d = self.delta();
        let l2 = (d[0] as i128).pow(2) + (d[1] as i128).pow(2);
        let l = (l2 as f64).sqrt();
        let mut vmax2 = f64::INFINITY;
        let mut accel = f64::INFINITY;
        for ((&da, &v), &a) in d.iter().zip(&lim.v).zip(&lim.a) {
            if da == 0 {
                continue;
            }
            let ratio = l / (da.unsigned_abs() as f64); // 1/|u_a|
            vmax2 = vmax2.min(speed2(v as f64) * ratio * ratio);
            accel = accel.min(a as f64 / (TICK * TICK) * ratio);
        }
        if let Some(f) = self.feed {
            vmax2 = vmax2.min(speed2(f as f64));
        }
        Model {
            d: [d[0] as f64, d[1] as f64],
            l,
            vmax2,
            accel,
            two_al: 2.0 * accel * l * Q64,
        }
    }

    /// The block the device would plan, or `None` when it has no length.
    fn block(&self, h: [ImpulsePrice; 2], rates: &Rates) -> Option<Block> {
        let reg = |p: [i64; 2]| ImpulsePoint {
            x: quantize(len(p[0]), h[0]).unwrap(),
            z: quantize(len(p[1]), h[1]).unwrap(),
        };
        let q = |p: [i64; 2]| [i128::from(p[0]) << 32, i128::from(p[1]) << 32];
        let events = LinearBlock::new(reg(self.from), reg(self.to)).unwrap();
        let feed = self.feed.map(|f| Feed::new(len(f)).unwrap());
        Block::new(q(self.from), q(self.to), events, feed, h, rates)
    }
}

/// The junction `v²` from `p` into `q` (grbl's rule, capped by both
/// `v_max²`), Q64 (Å/tick)².
fn junction2(p: &Seg, q: &Seg, lim: &Lim) -> f64 {
    let (mp, mq) = (p.model(lim), q.model(lim));
    let cap = mp.vmax2.min(mq.vmax2);
    let (a, b) = (p.delta(), q.delta());
    let (a0, a1, b0, b1) = (a[0] as i128, a[1] as i128, b[0] as i128, b[1] as i128);
    let cross = a0 * b1 - a1 * b0;
    let dot = a0 * b0 + a1 * b1;
    if cross == 0 {
        // A straight continuation is the cap, a reversal a stop.
        return if dot > 0 { cap } else { 0.0 };
    }
    if lim.jd == 0 {
        return 0.0;
    }
    // ψ the angle between the directions: s = cos(ψ/2), s' = sin(ψ/2),
    // each from the side without cancellation.
    let nn = mp.l * mq.l;
    let (cos, sin) = (dot as f64 / nn, (cross.unsigned_abs() as f64) / nn);
    let (s2, s2p) = if dot >= 0 {
        let s2 = (1.0 + cos) / 2.0;
        (s2, sin * sin / (4.0 * s2))
    } else {
        let s2p = (1.0 - cos) / 2.0;
        (sin * sin / (4.0 * s2p), s2p)
    };
    let s = s2.sqrt();
    let a = mp.accel.min(mq.accel);
    // v² = a·δ·s/(1 − s) = a·δ·s(1 + s)/s'².
    let v2 = a * lim.jd as f64 * s * (1.0 + s) / s2p * Q64;
    v2.min(cap)
}

// ---------------------------------------------------------------------------
// Running the planner as the device does
// ---------------------------------------------------------------------------

/// A started block: the segment it came from, its timing, and the segments
/// queued behind it in its window when it started.
#[derive(Clone, Debug)]
struct Started {
    seg: usize,
    timed: TimedBlock,
    behind: Vec<usize>,
}

/// A program planned in one run: block `k` starts when the window behind it
/// is full, the rest at the flush at the end.
#[derive(Clone, Debug)]
struct Run {
    started: Vec<Started>,
    /// The run's length in ticks (`None`: nothing planned).
    end: Option<u64>,
}

fn plan<const N: usize>(
    segs: &[Seg],
    lim: &Lim,
    h: [ImpulsePrice; 2],
    window: usize,
    planner: &mut Planner<N>,
) -> Run {
    let rates = lim.rates();
    let mut queue: VecDeque<usize> = VecDeque::new();
    let mut started = Vec::new();
    let mut start = |p: &mut Planner<N>, queue: &mut VecDeque<usize>| {
        let n = queue.len().min(window);
        let behind = queue.iter().take(n).skip(1).copied().collect();
        let timed = p.start(&rates).expect("a queued block starts");
        let seg = queue.pop_front().unwrap();
        started.push(Started { seg, timed, behind });
    };
    for (i, s) in segs.iter().enumerate() {
        let Some(b) = s.block(h, &rates) else {
            continue;
        };
        if planner.window_full() {
            start(planner, &mut queue);
        }
        planner.push(b, &rates).expect("room after a start");
        queue.push_back(i);
        if planner.window_full() {
            start(planner, &mut queue);
        }
        assert_eq!(planner.queued(), queue.len());
    }
    while !queue.is_empty() {
        start(planner, &mut queue);
    }
    assert!(planner.start(&rates).is_none());
    let end = planner.end_run();
    assert!(planner.is_idle());
    Run { started, end }
}

fn plan_w(segs: &[Seg], lim: &Lim, window: usize) -> Run {
    plan::<WINDOW>(segs, lim, H, window, &mut Planner::new(window))
}

// ---------------------------------------------------------------------------
// Random programs and limits
// ---------------------------------------------------------------------------

/// A value 10^e mm (or mm/min, mm/s²) in whole multiples of 10 Å (the six
/// decimals of a request), within `lo ..= hi` Å.
fn decimal(e: f64, lo: i64, hi: i64) -> i64 {
    let a = (10f64.powf(e) * 1e6).round() as i64 * 10;
    a.clamp(lo, hi)
}

/// The largest word below 100 000: 99 999.999999 (mm, mm/min, mm/s²).
const TOP: i64 = 999_999_999_990;
/// The smallest rapid rate, 10⁻⁶ mm/min, as log₁₀.
const FULL: f64 = -6.0;

/// Limits over their ranges: rapid rates from 10^`lo` to 99 999.999999
/// mm/min, or up to `vmax` Å/min per axis; accelerations 10 … 99 999.999999
/// mm/s²; δ 0 (about one case in seven) or 10⁻⁶ … 10 mm. Log-uniform.
fn limits(lo: f64, vmax: [i64; 2]) -> impl Strategy<Value = Lim> {
    (
        lo..5.0,
        lo..5.0,
        1.0f64..5.0,
        1.0f64..5.0,
        prop_oneof![1 => Just(None), 6 => (-6.0f64..1.0).prop_map(Some)],
    )
        .prop_map(move |(vx, vz, ax, az, jd)| Lim {
            v: [decimal(vx, 10, vmax[0]), decimal(vz, 10, vmax[1])],
            a: [decimal(ax, 100_000_000, TOP), decimal(az, 100_000_000, TOP)],
            jd: jd.map_or(0, |e| decimal(e, 10, 100_000_000)),
        })
}

/// One move of a random program.
#[derive(Clone, Copy, Debug)]
struct MoveSpec {
    /// 0–3 any direction, 4 along an axis, 5 straight on, 6 back, 7 nearly
    /// straight on (the previous direction rounded to the grid).
    shape: u8,
    /// Direction as a fraction of a turn.
    turn: f64,
    /// log₁₀ of the length in mm: 0.001 … 200 mm.
    len_exp: f64,
    /// log₁₀ of the feed in mm/min (1 … 5000), or rapid.
    feed_exp: Option<f64>,
}

fn move_spec(max_len_exp: f64) -> impl Strategy<Value = MoveSpec> {
    (
        0u8..8,
        0.0f64..1.0,
        -3.0f64..max_len_exp,
        prop_oneof![1 => Just(None), 4 => (0.0f64..3.699).prop_map(Some)],
    )
        .prop_map(|(shape, turn, len_exp, feed_exp)| MoveSpec {
            shape,
            turn,
            len_exp,
            feed_exp,
        })
}

/// log₁₀ 200.
const LOG_200: f64 = 2.301_03;

fn gcd(a: i64, b: i64) -> i64 {
    let (mut a, mut b) = (a.abs(), b.abs());
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The segments of a program, from the origin.
fn program(moves: &[MoveSpec]) -> Vec<Seg> {
    program_on(moves, 1)
}

/// The segments of a program, from the origin, every point rounded to a
/// multiple of `grid` Å (a half impulse puts ends on rounding boundaries;
/// blocks may then have no length).
fn program_on(moves: &[MoveSpec], grid: i64) -> Vec<Seg> {
    let mut p = [0i64, 0];
    let mut prev: Option<[i64; 2]> = None;
    let mut out = Vec::new();
    for m in moves {
        let l = 10f64.powf(m.len_exp) * 1e7; // Å
        let angle = m.turn * std::f64::consts::TAU;
        let any = [
            (l * angle.cos()).round() as i64,
            (l * angle.sin()).round() as i64,
        ];
        let d = match (m.shape, prev) {
            (4, _) => {
                let l = l.round() as i64;
                [[l, 0], [-l, 0], [0, l], [0, -l]][(m.turn * 4.0) as usize % 4]
            }
            (5 | 6, Some(q)) => {
                // An exact multiple of the previous direction's primitive
                // vector: exactly collinear.
                let g = gcd(q[0], q[1]);
                let prim = [q[0] / g, q[1] / g];
                let pl = ((prim[0] as f64).powi(2) + (prim[1] as f64).powi(2)).sqrt();
                let k = ((l / pl).round() as i64).max(1);
                let sign = if m.shape == 5 { 1 } else { -1 };
                [sign * k * prim[0], sign * k * prim[1]]
            }
            (7, Some(q)) => {
                let ql = ((q[0] as f64).powi(2) + (q[1] as f64).powi(2)).sqrt();
                [
                    (q[0] as f64 * l / ql).round() as i64,
                    (q[1] as f64 * l / ql).round() as i64,
                ]
            }
            _ => any,
        };
        let snap = |v: i64| (v as f64 / grid as f64).round() as i64 * grid;
        let to = [snap(p[0] + d[0]), snap(p[1] + d[1])];
        let d = [to[0] - p[0], to[1] - p[1]];
        let feed = m.feed_exp.map(|e| decimal(e, 10_000_000, 50_000_000_000));
        out.push(Seg { from: p, to, feed });
        if d != [0, 0] {
            prev = Some(d);
        }
        p = to;
    }
    out
}

// ---------------------------------------------------------------------------
// 1. Never above a limit; 2. rest at start and end, continuity
// ---------------------------------------------------------------------------

/// Every started block against the rules: speed and acceleration limits,
/// junctions, rest at both ends of the run, continuity, and the plan being
/// the largest the rules allow over the window the block started with.
fn check_run(segs: &[Seg], lim: &Lim, run: &Run) -> Result<(), TestCaseError> {
    let rates = lim.rates();
    let models: Vec<Model> = segs.iter().map(|s| s.model(lim)).collect();
    // The junction into each planned segment from the one planned before it.
    let planned: Vec<usize> = run.started.iter().map(|s| s.seg).collect();
    let mut junction = vec![0.0f64; segs.len()];
    for w in planned.windows(2) {
        junction[w[1]] = junction2(&segs[w[0]], &segs[w[1]], lim);
    }
    // Where the core must equal the model, one more margin: the core
    // rounds an axis's (VMAX/TICK)² to a unit of Q64 before scaling it by
    // 1/u_a², so a rapid block's v_max² is exact only to one unit of the
    // slower axis's rate², relatively (2·10⁻⁶ at 10⁻⁶ mm/min, 2·10⁻¹² at
    // 0.001 mm/min; see `a_slow_rapid_block_keeps_its_documented_accuracy`).
    // Floors only lower it, so the upper bounds need no such margin.
    let slowest = speed2(lim.v[0].min(lim.v[1]) as f64);
    let rel = REL + 2.0 / slowest;
    let mut prev: Option<&Started> = None;
    for st in &run.started {
        let (seg, m) = (&segs[st.seg], &models[st.seg]);
        let [e2, c2, x2] = st.timed.speeds2();
        let block = seg.block(H, &rates).unwrap();
        let ctx = || format!("block {} {seg:?}: e² {e2}, c² {c2}, x² {x2}, {m:?}", st.seg);

        // The block's own quantities against the model, both ways.
        for (core, model, rel) in [
            (block.vmax2(), m.vmax2, rel),
            (block.two_al(), m.two_al, REL),
        ] {
            prop_assert!(
                (core as f64 - model).abs() <= model * rel + ABS,
                "{core} vs {model}: {}",
                ctx()
            );
        }

        // 1. Speed: cruise within v_max (feed and every moving axis), hence
        // entry and exit too, which it bounds.
        prop_assert!(c2 >= e2 && c2 >= x2, "{}", ctx());
        prop_assert!(c2 <= block.vmax2(), "{}", ctx());
        prop_assert!(at_most(c2, m.vmax2), "{}", ctx());
        if let Some(f) = seg.feed {
            prop_assert!(at_most(c2, speed2(f as f64)), "feed: {}", ctx());
        }
        for axis in 0..2 {
            // (u_a·v)² ≤ VMAX_a².
            let u2 = (m.d[axis] / m.l).powi(2);
            prop_assert!(
                c2 as f64 * u2 <= speed2(lim.v[axis] as f64) * (1.0 + REL) + ABS,
                "axis {axis}: {}",
                ctx()
            );
        }

        // 1. Acceleration: |x² − e²| ≤ 2aL, and the peak no higher than
        // accelerating from e and decelerating to x within L allows.
        prop_assert!(at_most(x2.abs_diff(e2), m.two_al), "ramp: {}", ctx());
        prop_assert!(
            at_most(c2, (m.two_al + e2 as f64 + x2 as f64) / 2.0),
            "peak: {}",
            ctx()
        );

        // 1. Junction: entry within the junction speed and both v_max².
        prop_assert!(at_most(e2, junction[st.seg]), "junction: {}", ctx());

        // 2. Rest at the start, continuity in speed and time.
        match prev {
            None => {
                prop_assert_eq!(e2, 0, "first entry: {}", ctx());
                prop_assert_eq!(st.timed.span_q64().0, 0);
            }
            Some(p) => {
                prop_assert_eq!(e2, p.timed.speeds2()[2], "continuity: {}", ctx());
                prop_assert!(at_most(e2, models[p.seg].vmax2), "{}", ctx());
                prop_assert_eq!(st.timed.span_q64().0, p.timed.span_q64().1);
            }
        }
        prop_assert!(st.timed.span_q64().1 > st.timed.span_q64().0);

        // The largest exit the rules allow: the backward pass over the
        // blocks behind, from rest at the window's end, then the forward
        // step from the entry as run.
        let mut next = 0.0f64;
        for &b in st.behind.iter().rev() {
            next = junction[b].min(next + models[b].two_al);
        }
        let best = next.min(e2 as f64 + m.two_al);
        let scale = st
            .behind
            .iter()
            .map(|&b| models[b].two_al + models[b].vmax2)
            .fold(m.vmax2 + e2 as f64, f64::max);
        prop_assert!(
            (x2 as f64 - best).abs() <= scale * rel + ABS,
            "exit {x2} vs the largest allowed {best}: {}",
            ctx()
        );

        // The block's duration against the one its speeds, a and L define
        // (10⁻⁹ relative and 10⁻⁶ tick: far above the f64 model's 10⁻¹⁵ and
        // the core's rounding, far below a wrong ramp or cruise).
        let t = trapezoid([e2, c2, x2], block.vmax2(), m).duration;
        let (s0, s1) = st.timed.span_q64();
        let got = (s1 - s0) as f64 / Q64;
        prop_assert!(
            (got - t).abs() <= t * 1e-9 + 1e-6,
            "duration {got} vs {t}: {}",
            ctx()
        );
        prev = Some(st);
    }
    // 2. Rest at the end of the run.
    if let Some(last) = prev {
        prop_assert_eq!(last.timed.speeds2()[2], 0, "the run ends at rest");
        prop_assert_eq!(run.end, Some(last.timed.end_tick()));
    } else {
        prop_assert_eq!(run.end, None);
    }
    Ok(())
}

/// A block's trapezoid in f64: speeds Å/tick, distances Å, times ticks.
struct Trapezoid {
    e: f64,
    c: f64,
    x: f64,
    a: f64,
    l: f64,
    /// Where the acceleration ends and the deceleration starts.
    s_accel: f64,
    s_decel: f64,
    t_accel: f64,
    duration: f64,
}

/// The trapezoid of a block with the core's squared speeds; a cruise at
/// the block's `v_max` is taken at the model's exact `v_max`, as the core
/// times it from the rate itself (at a very slow rate one unit of `c²` is a
/// relative 10⁻¹², a tick over a cruise of 10¹² ticks).
fn trapezoid(speeds2: [u128; 3], vmax2: u128, m: &Model) -> Trapezoid {
    let [e2, c2, x2] = speeds2.map(|v| v as f64);
    let c2 = if speeds2[1] >= vmax2 { m.vmax2 } else { c2 };
    let v = |v2: f64| (v2 / Q64).sqrt();
    let (e, c, x, a, l) = (v(e2), v(c2), v(x2), m.accel, m.l);
    let s_accel = ((c * c - e * e) / (2.0 * a)).clamp(0.0, l);
    let s_decel = (l - (c * c - x * x) / (2.0 * a)).clamp(s_accel, l);
    let t_accel = (c - e) / a;
    let t_decel = t_accel + (s_decel - s_accel) / c;
    Trapezoid {
        e,
        c,
        x,
        a,
        l,
        s_accel,
        s_decel,
        t_accel,
        duration: t_decel + (c - x) / a,
    }
}

impl Trapezoid {
    /// When the path reaches `s` (Å from the block's start), in ticks
    /// after the block's start (roots in the form without cancellation).
    fn time_at(&self, s: f64) -> f64 {
        // 2d/(v + √(v² + 2ad)): the time to cover d from speed v.
        let ramp = |v: f64, d: f64| {
            if d <= 0.0 {
                0.0
            } else {
                2.0 * d / (v + (v * v + 2.0 * self.a * d).sqrt())
            }
        };
        if s <= self.s_accel {
            ramp(self.e, s)
        } else if s <= self.s_decel {
            self.t_accel + (s - self.s_accel) / self.c
        } else {
            self.duration - ramp(self.x, self.l - s)
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// 1 and 2: random programs under random limits, looking 64, or only a
    /// few, blocks ahead.
    #[test]
    fn plans_stay_within_the_limits(
        lim in limits(FULL, [TOP, TOP]),
        moves in proptest::collection::vec(move_spec(LOG_200), 1..48),
        window in prop_oneof![Just(WINDOW), 1usize..9],
    ) {
        let segs = program(&moves);
        let run = plan_w(&segs, &lim, window);
        check_run(&segs, &lim, &run)?;
    }
}

// ---------------------------------------------------------------------------
// 3. The window
// ---------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// A program of at most W blocks plans the same with a window of W, of
    /// 256, or of exactly its own length: same speeds, spans and ticks.
    #[test]
    fn a_program_within_the_window_plans_as_with_any_larger_one(
        lim in limits(FULL, [TOP, TOP]),
        moves in proptest::collection::vec(move_spec(LOG_200), 1..=WINDOW),
    ) {
        let segs = program(&moves);
        let w = plan_w(&segs, &lim, WINDOW);
        let wide = plan::<256>(&segs, &lim, H, 256, &mut Planner::new(256));
        let own = plan_w(&segs, &lim, segs.len());
        // A planner that ran another program first: a run starts afresh.
        let mut used = Planner::<WINDOW>::new(WINDOW);
        let _ = plan(&program(&moves[moves.len() / 2..]), &lim, H, WINDOW, &mut used);
        let again = plan(&segs, &lim, H, WINDOW, &mut used);
        for other in [&wide, &own, &again] {
            prop_assert_eq!(w.end, other.end);
            prop_assert_eq!(w.started.len(), other.started.len());
            for (a, b) in w.started.iter().zip(&other.started) {
                prop_assert_eq!(a.seg, b.seg);
                prop_assert_eq!(a.timed, b.timed);
            }
        }
        // Ticks too (they follow from the timed block, checked once here).
        let ticks = |r: &Run| -> Vec<u64> {
            r.started.iter().flat_map(|s| s.timed.events().map(|(_, k)| k)).collect()
        };
        prop_assert_eq!(ticks(&w), ticks(&wide));
    }

    /// A program longer than the window (short blocks, so that the window
    /// binds): every started block's exit lets the axes stop within the
    /// blocks behind it, `x² ≤ Σ 2aL` over them, and the plan is otherwise
    /// the largest (checked by `check_run` with the window as started). The
    /// queue's ring wraps around several times.
    #[test]
    fn a_longer_program_can_always_stop_within_the_window(
        lim in limits(FULL, [TOP, TOP]),
        moves in proptest::collection::vec(move_spec(0.0), 70..200),
        window in prop_oneof![Just(WINDOW), 2usize..16],
    ) {
        let segs = program(&moves);
        let run = plan_w(&segs, &lim, window);
        for st in &run.started {
            prop_assert!(st.behind.len() < window);
            let room: f64 = st.behind.iter().map(|&b| segs[b].model(&lim).two_al).sum();
            let x2 = st.timed.speeds2()[2];
            prop_assert!(at_most(x2, room), "exit {} beyond stopping room {}", x2, room);
        }
        check_run(&segs, &lim, &run)?;
    }
}

/// The window binds: collinear 0.1 mm rapids along Z at 3000 mm/min and
/// 150 mm/s² need 8.3 mm to stop from the rapid rate, so with 63 blocks
/// behind (6.3 mm) the speed is that of stopping within them, while a
/// 256-block window reaches the rapid rate.
#[test]
fn the_window_limits_the_speed_of_short_blocks() {
    let segs: Vec<Seg> = (0..400)
        .map(|i| Seg {
            from: [0, -1_000_000 * i],
            to: [0, -1_000_000 * (i + 1)],
            feed: None,
        })
        .collect();
    let lim = Lim::DEFAULT;
    let w = plan_w(&segs, &lim, WINDOW);
    let wide = plan::<256>(&segs, &lim, H, 256, &mut Planner::new(256));
    let m = segs[0].model(&lim);
    // Block 100 starts with 63 blocks behind it: x² = 63·2aL.
    let x2 = w.started[100].timed.speeds2()[2] as f64;
    assert!((x2 - 63.0 * m.two_al).abs() <= 63.0 * m.two_al * REL + ABS);
    let cruise = wide.started[300].timed.speeds2()[1] as f64;
    assert!((cruise - m.vmax2).abs() <= m.vmax2 * REL + ABS);
    assert!(w.end > wide.end);
}

// ---------------------------------------------------------------------------
// 4. Step times
// ---------------------------------------------------------------------------

/// The events of a run: as many as the lead axis has impulses, ticks
/// strictly increasing within a block and never decreasing along the run,
/// each no earlier than its block's start and no later than its end, at
/// least the lead axis's rapid interval apart, and each at `Q(t)`, `t` the
/// time the block's trapezoid (f64) gives its rounding boundary: exactly,
/// or within one tick where `t` lies closer to a half tick than the model
/// resolves.
fn check_events(
    segs: &[Seg],
    lim: &Lim,
    h: [ImpulsePrice; 2],
    run: &Run,
) -> Result<(), TestCaseError> {
    let mut last = 0u64;
    for st in &run.started {
        let seg = &segs[st.seg];
        let m = seg.model(lim);
        let blk = st.timed.block();
        let (nx, nz) = blk.delta();
        let lead = usize::from(nz.unsigned_abs() > nx.unsigned_abs());
        let n = nx.unsigned_abs().max(nz.unsigned_abs());
        let events: Vec<u64> = st.timed.events().map(|(_, k)| k).collect();
        prop_assert_eq!(events.len(), n as usize, "events of {:?}", seg);
        let vmax2 = seg.block(h, &lim.rates()).unwrap().vmax2();
        let tz = trapezoid(st.timed.speeds2(), vmax2, &m);
        let (start, _) = st.timed.span_q64();
        let start_f = start as f64 / Q64;
        // The lead axis: its register at the start, direction, price.
        let (a0, nl) = if lead == 0 {
            (blk.from().x.get(), nx)
        } else {
            (blk.from().z.get(), nz)
        };
        let sigma = f64::from(nl.signum());
        let h = h[lead].as_angstrom() as f64;
        let from = seg.from[lead] as f64;
        // Events at least h/VMAX_lead apart: ⌊gap⌋ − 1 ticks once rounded
        // (Q(t + g) ≥ Q(t) + ⌊g⌋, less one for a time a hair off a tie).
        let gap = (h * 60.0 * TICK / lim.v[lead] as f64).floor() - 1.0;
        for (i, &k) in events.iter().enumerate() {
            if i == 0 {
                prop_assert!(k >= last, "tick {} before the run's previous {}", k, last);
            } else {
                prop_assert!(
                    k > events[i - 1],
                    "not increasing at event {}: {:?}",
                    i + 1,
                    seg
                );
                prop_assert!(
                    (k - events[i - 1]) as f64 >= gap,
                    "events {} ticks apart, the rapid rate allows {}: {:?}",
                    k - events[i - 1],
                    gap,
                    seg
                );
            }
            // Event i+1 at the boundary (a0 + (i + ½)σ)·h.
            let boundary = (f64::from(a0) + (i as f64 + 0.5) * sigma) * h;
            let s = sigma * (boundary - from) / m.d[lead].abs() * m.l;
            let t = start_f + tz.time_at(s);
            // Q(t) exactly, unless t is closer to a half tick than the f64
            // model can tell (its relative error is a few 10⁻¹⁶ of the run's
            // time; 10⁻¹² and 10⁻⁷ tick leave room for the core's rounding).
            let near_tie = (t - t.floor() - 0.5).abs() <= t * 1e-12 + 1e-7;
            let want = (t + 0.5).floor();
            prop_assert!(
                k as f64 == want || (near_tie && (k as f64 - want).abs() <= 1.0),
                "event {} at {} ticks, the trapezoid puts it at {}: {:?}",
                i + 1,
                k,
                t,
                seg
            );
        }
        if let Some(&k) = events.last() {
            prop_assert!(k <= st.timed.end_tick());
            last = k;
        }
        // The next block's events come no earlier than this one's end.
        last = last.max(st.timed.end_tick());
    }
    Ok(())
}

/// Impulse prices (Å) and limits the device accepts with them at the
/// highest drive rate: `VMAX_a ≤ 60·h_a·200 000` per minute.
fn prices_and_limits() -> impl Strategy<Value = ([ImpulsePrice; 2], Lim)> {
    let price = prop::sample::select(vec![25_000i64, 50_000, 100_000, 1_000_000, 10_000_000]);
    (price.clone(), price).prop_flat_map(|(hx, hz)| {
        let h = [hx, hz].map(|a| ImpulsePrice::from_length(len(a)).unwrap());
        let fastest = [hx, hz].map(|a| (a * 60 * 200_000).min(TOP));
        // From 0.001 mm/min: a 200 mm block then lasts up to 1.2·10¹³
        // ticks, which f64 resolves to 10⁻³ tick; much slower and it no
        // longer resolves one.
        (Just(h), limits(-3.0, fastest))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// 4: random programs at random prices, their points on the grid or on
    /// multiples of half an impulse (ends on rounding boundaries).
    #[test]
    fn step_events_follow_the_plan(
        (h, lim) in prices_and_limits(),
        moves in proptest::collection::vec(move_spec(LOG_200), 1..24),
        window in prop_oneof![Just(WINDOW), 1usize..6],
        grid in 0usize..3,
    ) {
        let grid = [1, h[0].as_angstrom() / 2, h[1].as_angstrom() / 2][grid];
        let segs = program_on(&moves, grid);
        let run = plan::<WINDOW>(&segs, &lim, h, window, &mut Planner::new(window));
        check_events(&segs, &lim, h, &run)?;
    }
}

// ---------------------------------------------------------------------------
// 5. Splitting a line
// ---------------------------------------------------------------------------

/// A line from `p0` along `k`·`prim` split at the multiples `cuts` of
/// `prim` (increasing, within `1 .. k`), all at `feed`.
fn split(p0: [i64; 2], prim: [i64; 2], k: i64, cuts: &[i64], feed: Option<i64>) -> Vec<Seg> {
    let at = |t: i64| [p0[0] + t * prim[0], p0[1] + t * prim[1]];
    let mut ts = vec![0];
    ts.extend_from_slice(cuts);
    ts.push(k);
    ts.windows(2)
        .map(|w| Seg {
            from: at(w[0]),
            to: at(w[1]),
            feed,
        })
        .collect()
}

/// A random exact line: a primitive-ish integer direction (Å) scaled to
/// about 0.01 … 200 mm, and `pieces − 1` distinct cut points on it.
fn line() -> impl Strategy<Value = ([i64; 2], i64, Vec<i64>)> {
    (
        (-1000i64..=1000, -1000i64..=1000).prop_filter("moves", |d| *d != (0, 0)),
        -1.0f64..LOG_200,
        proptest::collection::vec(0.0f64..1.0, 1..WINDOW),
    )
        .prop_map(|(d, e, fr)| {
            let prim = [d.0, d.1];
            let pl = ((d.0 as f64).powi(2) + (d.1 as f64).powi(2)).sqrt();
            let k = ((10f64.powf(e) * 1e7 / pl) as i64).max(2 * WINDOW as i64);
            let mut cuts: Vec<i64> = fr.iter().map(|f| 1 + (f * (k - 2) as f64) as i64).collect();
            cuts.sort_unstable();
            cuts.dedup();
            (prim, k, cuts)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// 5: a line cut into up to W exactly collinear pieces at one feed (or
    /// rapid) arrives no later than the whole line, and in fact at the same
    /// tick: the junctions are straight continuations, taken at v_max.
    #[test]
    fn splitting_a_line_changes_no_arrival(
        lim in limits(FULL, [TOP, TOP]),
        (prim, k, cuts) in line(),
        feed in proptest::option::weighted(0.8, (0.0f64..3.699).prop_map(|e| decimal(e, 10_000_000, 50_000_000_000))),
        p0 in (-100_000_000i64..100_000_000, -100_000_000i64..100_000_000),
    ) {
        let p0 = [p0.0, p0.1];
        let whole = plan_w(&split(p0, prim, k, &[], feed), &lim, WINDOW).end.unwrap();
        let pieces = split(p0, prim, k, &cuts, feed);
        prop_assert!(pieces.len() <= WINDOW);
        let run = plan_w(&pieces, &lim, WINDOW);
        check_run(&pieces, &lim, &run)?;
        let parts = run.end.unwrap();
        prop_assert!(parts <= whole, "split {} later than whole {}", parts, whole);
        prop_assert_eq!(parts, whole);
    }
}

/// Beyond the window, splitting does cost time: with more than W short
/// pieces the rest-at-window-end constraint slows the middle, so the split
/// line arrives later (never earlier); with pieces long enough to stop in
/// W − 1 of them from the cruise speed, it arrives at the same tick.
#[test]
fn splitting_beyond_the_window() {
    let lim = Lim::DEFAULT;
    let feed = Some(20_000_000_000); // 2000 mm/min along Z
    let whole = |k: i64, step: i64| {
        let segs = split([0, 0], [0, -step], k, &[], feed);
        plan_w(&segs, &lim, WINDOW).end.unwrap()
    };
    let pieces = |k: i64, step: i64| {
        let cuts: Vec<i64> = (1..k).collect();
        let segs = split([0, 0], [0, -step], k, &cuts, feed);
        plan_w(&segs, &lim, WINDOW).end.unwrap()
    };
    // 500 pieces of 0.02 mm: 1.26 mm of stopping room in the window, 3.7 mm
    // needed from 2000 mm/min at 150 mm/s².
    assert!(pieces(500, 200_000) > whole(500, 200_000));
    // 100 pieces of 1 mm: 63 mm of room.
    assert_eq!(pieces(100, 10_000_000), whole(100, 10_000_000));
}

// ---------------------------------------------------------------------------
// 6. SYNC and STATUS through the protocol
// ---------------------------------------------------------------------------

/// The body of a single reply line (its `*HH` checked).
fn one(dev: &mut LocalDevice, line: &str) -> String {
    let r = dev.request(line);
    assert_eq!(r.len(), 1, "{line}: {r:?}");
    let (body, sum) = r[0].rsplit_once('*').unwrap();
    let want = body.bytes().fold(0u8, |a, b| a ^ b);
    assert_eq!(u8::from_str_radix(sum, 16).unwrap(), want, "{}", r[0]);
    body.to_owned()
}

/// The value of `KEY=` in a reply.
fn value<'a>(reply: &'a str, key: &str) -> &'a str {
    reply
        .split(' ')
        .find_map(|w| w.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key}= in {reply}"))
}

fn int(reply: &str, key: &str) -> i64 {
    value(reply, key).parse().unwrap()
}

/// CRC-32 (IEEE, reflected, as zlib), bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A device with X words on the radius, as the planner's segments are.
fn radius_device() -> LocalDevice {
    let mut dev = LocalDevice::recording();
    assert!(one(&mut dev, "CFG DIAM=0").starts_with("OK "));
    dev
}

/// A length in Å as a request word.
fn word(a: i64) -> String {
    let sign = if a < 0 { "-" } else { "" };
    let m = a.unsigned_abs();
    format!("{sign}{}.{:06}", m / 10_000_000, (m % 10_000_000) / 10)
}

fn move_to(dev: &mut LocalDevice, s: &Seg) -> String {
    let f = s
        .feed
        .map(|f| format!(" F={}", word(f)))
        .unwrap_or_default();
    let r = one(
        dev,
        &format!("MOVE X={} Z={}{f}", word(s.to[0]), word(s.to[1])),
    );
    assert!(r.starts_with("OK NX="), "{r}");
    r
}

#[test]
fn sync_with_nothing_queued_reports_nothing() {
    let mut dev = radius_device();
    assert_eq!(one(&mut dev, "SYNC"), "OK EV=0 T=0 TSEQ=00000000 STARVED=0");
    assert_eq!(one(&mut dev, "SYNC"), "OK EV=0 T=0 TSEQ=00000000 STARVED=0");
    assert_eq!(dev.issued(), 0);
}

#[test]
fn sync_reports_the_run_then_starts_again() {
    let mut dev = radius_device();
    // X 7.5 mm (radius) and Z −12.3456 mm at 900 mm/min.
    let seg = Seg {
        from: [0, 0],
        to: [75_000_000, -123_456_000],
        feed: Some(9_000_000_000),
    };
    let mv = move_to(&mut dev, &seg);
    let n = int(&mv, "NX").abs().max(int(&mv, "NZ").abs()) as u64;
    assert_eq!(dev.issued(), 0, "one block waits for the window or a flush");
    let sync = one(&mut dev, "SYNC");

    // The planner, run directly, and the trapezoid in f64.
    let run = plan_w(std::slice::from_ref(&seg), &Lim::DEFAULT, WINDOW);
    let t = run.end.unwrap();
    let m = seg.model(&Lim::DEFAULT);
    let v2 = (m.vmax2 / Q64).min(m.accel * m.l); // peak² ≤ aL from rest to rest
    let v = v2.sqrt();
    let exact = (m.l - v2 / m.accel) / v + 2.0 * v / m.accel;
    assert!((t as f64 - exact).abs() <= 1.0, "{t} vs {exact}");

    let events = dev.take_events();
    assert_eq!(events.len() as u64, n);
    let planned: Vec<(u8, u64)> = run.started[0]
        .timed
        .events()
        .map(|(e, k)| (e.bits(), k))
        .collect();
    let issued: Vec<(u8, u64)> = events.iter().map(|e| (e.bits, e.tick)).collect();
    assert_eq!(issued, planned);
    // TSEQ: the event byte, then the tick delta from the previous event of
    // the run (the first from the run's start) as a little-endian u32.
    let mut rec = Vec::new();
    let mut prev = 0;
    for e in &events {
        rec.push(e.bits);
        rec.extend_from_slice(&((e.tick - prev) as u32).to_le_bytes());
        prev = e.tick;
    }
    assert_eq!(
        sync,
        format!("OK EV={n} T={t} TSEQ={:08X} STARVED=0", crc32(&rec)),
        "EV the move's events, T its run"
    );
    // Since that SYNC nothing ran: no events, and no run ended (T=0).
    assert_eq!(one(&mut dev, "SYNC"), "OK EV=0 T=0 TSEQ=00000000 STARVED=0");

    // ZERO flushes and forgets: the run it ends is not reported either.
    move_to(
        &mut dev,
        &Seg {
            from: seg.to,
            to: [0, 0],
            feed: None,
        },
    );
    assert_eq!(one(&mut dev, "ZERO"), "OK");
    assert!(dev.issued() > n, "ZERO ran the queued move");
    assert_eq!(one(&mut dev, "SYNC"), "OK EV=0 T=0 TSEQ=00000000 STARVED=0");
    // And counts afresh afterwards: the same move from the new origin.
    dev.take_events();
    move_to(&mut dev, &seg);
    assert_eq!(one(&mut dev, "SYNC"), sync);
}

/// The STATUS reply's state, queue and registers.
fn status(dev: &mut LocalDevice) -> (String, i64, i64, i64, String) {
    let s = one(dev, "STATUS");
    (
        value(&s, "STATE").to_owned(),
        int(&s, "Q"),
        int(&s, "PX"),
        int(&s, "PZ"),
        value(&s, "V").to_owned(),
    )
}

#[test]
fn status_reports_the_steps_issued_and_the_queue() {
    let mut dev = radius_device();
    assert_eq!(status(&mut dev), ("IDLE".into(), 0, 0, 0, "0.0000".into()));
    // A zig-zag of 70 feed moves: the first 7 start as the window fills.
    let mut segs = Vec::new();
    let mut p = [0i64, 0];
    for i in 0..70i64 {
        let to = [(i % 2) * 20_000_000 + i * 1_000_000, -(i + 1) * 30_000_000];
        segs.push(Seg {
            from: p,
            to,
            feed: Some(6_000_000_000 + i * 100_000_000),
        });
        p = to;
    }
    let mut replies = Vec::new();
    for (i, s) in segs.iter().enumerate() {
        replies.push(move_to(&mut dev, s));
        if i == 0 {
            // Queued, nothing issued: the registers are still at the start
            // (POS shows the commanded end).
            assert_eq!(status(&mut dev), ("RUN".into(), 1, 0, 0, "0.0000".into()));
            let pos = one(&mut dev, "POS");
            assert_eq!(
                (int(&pos, "PX"), int(&pos, "PZ")),
                (int(&replies[0], "PX"), int(&replies[0], "PZ"))
            );
        }
    }
    let started = segs.len() - (WINDOW - 1);
    let (state, q, px, pz, v) = status(&mut dev);
    assert_eq!((state.as_str(), q), ("RUN", (WINDOW - 1) as i64));
    let after = &replies[started - 1];
    assert_eq!((px, pz), (int(after, "PX"), int(after, "PZ")));
    assert_ne!((px, pz), (int(&replies[69], "PX"), int(&replies[69], "PZ")));
    // V: the exit speed of the block that started last, as the planner has
    // it when the same blocks are pushed directly.
    let rates = Rates::default();
    let mut planner = Planner::<WINDOW>::default();
    let mut issued = ImpulsePoint {
        x: core_nostd::impulse::Impulses(0),
        z: core_nostd::impulse::Impulses(0),
    };
    for s in &segs {
        planner.push(s.block(H, &rates).unwrap(), &rates).unwrap();
        if planner.window_full() {
            issued = planner.start(&rates).unwrap().block().to();
        }
    }
    assert_eq!(
        (px, pz),
        (i64::from(issued.x.get()), i64::from(issued.z.get()))
    );
    let speed = Status {
        queued: planner.queued(),
        issued,
        speed2: planner.exit2(),
        motion: core_nostd::stepper::AxesState::Run,
        spindle: 0,
    }
    .speed(TickRate::TIMER);
    assert!(speed > 0, "moving at a corner taken with δ = 0.01 mm");
    assert_eq!(v, format!("{}.{:04}", speed / 10_000, speed % 10_000));

    assert!(one(&mut dev, "SYNC").starts_with("OK EV="));
    let pos = one(&mut dev, "POS");
    assert_eq!(
        status(&mut dev),
        (
            "IDLE".into(),
            0,
            int(&pos, "PX"),
            int(&pos, "PZ"),
            "0.0000".into()
        )
    );
}

// ---------------------------------------------------------------------------
// 7. Bad input changes nothing
// ---------------------------------------------------------------------------

/// Everything a refused request must leave as it was.
fn state(dev: &mut LocalDevice) -> Vec<String> {
    let mut out: Vec<String> = ["POS", "CFG", "LIMITS", "DRIVE", "STATUS"]
        .iter()
        .map(|r| one(dev, r))
        .collect();
    out.push(format!("issued {} runs {}", dev.issued(), dev.runs()));
    out
}

#[test]
fn bad_limits_and_feeds_change_nothing() {
    let moves = [
        Seg {
            from: [0, 0],
            to: [50_000_000, -100_000_000],
            feed: Some(3_000_000_000),
        },
        Seg {
            from: [50_000_000, -100_000_000],
            to: [50_000_000, -300_000_000],
            feed: None,
        },
        Seg {
            from: [50_000_000, -300_000_000],
            to: [0, -310_000_000],
            feed: Some(1_234_567_890),
        },
    ];
    let bad = [
        ("LIMITS VX=0", "VX"),
        ("LIMITS VZ=-1", "VZ"),
        ("LIMITS AX=9.999999", "AX"),
        ("LIMITS AZ=100000", "AZ"),
        ("LIMITS JD=10.000001", "JD"),
        ("LIMITS VX=1.1234567", "VX"),
        // 15 000 mm/min on X at 0.005 mm is the default 50 000 events/s.
        ("LIMITS VX=15000.000001", "VX"),
        ("LIMITS VZ=30000.000001", "VZ"),
        ("LIMITS VX=1500 AZ=9", "AZ"),
        ("MOVE X=1 Z=-1 F=0", "F"),
        ("MOVE X=1 Z=-1 F=-1", "F"),
        ("MOVE X=1 Z=-1 F=1.1234567", "F"),
        ("MOVE X=1 Z=-1 F=0.000999", "F"),
        ("MOVE X=1 INC=1 F=100000", "F"),
    ];
    let mut dev = radius_device();
    for s in &moves {
        move_to(&mut dev, s);
    }
    let before = state(&mut dev);
    assert!(before[4].starts_with("OK STATE=RUN"), "{}", before[4]);
    for (req, key) in bad {
        let r = one(&mut dev, req);
        assert!(r.starts_with(&format!("ERR VALUE {key} ")), "{req}: {r}");
        assert_eq!(state(&mut dev), before, "after {req}");
    }
    // The plan is untouched too: the run equals that of a device that never
    // saw the bad requests (the junction into the next block included).
    let next = Seg {
        from: moves[2].to,
        to: [20_000_000, -350_000_000],
        feed: Some(2_000_000_000),
    };
    move_to(&mut dev, &next);
    let mut clean = radius_device();
    for s in moves.iter().chain([&next]) {
        move_to(&mut clean, s);
    }
    assert_eq!(one(&mut dev, "SYNC"), one(&mut clean, "SYNC"));

    // At their boundaries the same keys are accepted.
    let mut edge = radius_device();
    for req in [
        "LIMITS VX=15000 VZ=30000 AX=10 AZ=99999.999999 JD=10",
        "LIMITS VX=0.000001 JD=0",
        "MOVE X=1 Z=-1 F=0.001",
        "MOVE X=2 F=99999.999999",
    ] {
        let r = one(&mut edge, req);
        assert!(r.starts_with("OK "), "{req}: {r}");
    }
}

// ---------------------------------------------------------------------------
// The planner's documented accuracy
// ---------------------------------------------------------------------------

/// `core_nostd::plan` documents its squared speeds as within a few
/// 2⁻⁶⁴ (Å/tick)² of exact. A rapid block's
/// `v_max² = (VMAX_a/(60·TICK))²·(L/d_a)²` is rational; scaling a floored
/// axis rate² by `L²/d_a²` would multiply its one-unit error by that
/// ratio (133 881 units here: VZ = 0.000001 mm/min on a block of 490 Å
/// along X and 1 Å along Z), so the planner scales the rate itself, kept
/// to 2⁻⁹⁶ Å/tick, and squares the product.
#[test]
fn a_slow_rapid_block_keeps_its_documented_accuracy() {
    let lim = Lim {
        v: [10_000_000, 10], // 1 and 0.000001 mm/min
        a: [100_000_000, 100_000_000],
        jd: 100_000,
    };
    let seg = Seg {
        from: [0, 0],
        to: [490, 1],
        feed: None,
    };
    let block = seg.block(H, &lim.rates()).unwrap();
    // Exact: VZ²·2⁶⁴·(dx² + dz²) / (3600·TICK²·dz²), the Z term being the
    // smaller (X: 10¹⁴·2⁶⁴·240 101/(3.6·10¹⁵·240 100)).
    let (vz, dx, dz) = (10u128, 490u128, 1u128);
    let exact = ((vz * vz) << 64) * (dx * dx + dz * dz) / (3_600_000_000_000_000 * dz * dz);
    let got = block.vmax2();
    assert!(
        got.abs_diff(exact) <= 4,
        "v_max² {got}, exact {exact}: {} units off",
        got.abs_diff(exact)
    );
}

//! The velocity planner: per-axis limits, junction speeds, the look-ahead
//! window and each block's trapezoid (`docs/motion.md` §1–§4).
//!
//! A [`Block`] is a straight segment with its impulses, checked when it is
//! made; the [`Planner`] queues blocks and, when one starts, fixes its
//! profile from the blocks queued behind it (the backward pass to rest at
//! the end of the window, the forward step from its entry as run) and hands
//! it to the step generator as a [`TimedBlock`]. Nothing here can fail once
//! a block exists.
//!
//! # Formats
//! | quantity | format |
//! |---|---|
//! | points, segment vectors | ångström · 2³² (`i128`) |
//! | direction | the vector scaled to `max(|x|,|z|)` in `[2⁶¹, 2⁶²]` (`i64`), its length `lnq` in Q32 |
//! | squared speed `v²` | (Å/tick)² · 2⁶⁴ |
//! | speed `v` | Å/tick · 2⁶⁴ (an axis's rapid rate: 2⁹⁶) |
//! | acceleration `a` | Å/tick² · 2⁹⁶ |
//! | time, `v/a` | ticks · 2⁶⁴ |
//! | `u² = (v/a)²`, `2s/a` | ticks² · 2⁶⁴ |
//!
//! Every quotient is taken once, from exact integers and the block's
//! length, with 256-bit intermediates, so its error is one unit of its
//! format; the cruise time at a programmed feed or a rapid rate is exact
//! but for the length. Irrational quantities (`|d|`, junction speeds,
//! `√v²`) are floors of exact roots, within one unit; the length carries
//! some 94 significant bits, so the path along a block is within 2⁻⁶⁰ Å of
//! exact. The
//! planner's squared speeds are therefore within a few 2⁻⁶⁴ (Å/tick)² of
//! exact, and event times within about 2⁻⁴⁰ tick even for the longest
//! block the limits allow (10⁶ events at 0.001 mm/min, some 2⁴⁶ ticks).

use crate::impulse::ImpulsePrice;
use crate::interleave::LinearBlock;
use crate::length::{Length, ANGSTROM_PER_MM};
use crate::step::{Cruise, Ramp, TickRate, TimedBlock, HALF, TIE};
use crate::trig::isqrt;
use crate::wide::{divrem_u128, mul_div, mul_shr, shl_div, sqrt_shl, U256};
use core::fmt;
use core::num::NonZeroU128;
use heapless::Deque;

/// The look-ahead window of the device, in blocks.
pub const WINDOW: usize = 64;

/// Why limits were refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LimitsError {
    /// A rapid rate outside (0, 99 999.999999] mm/min (axis 0 X, 1 Z).
    Rate(usize),
    /// An acceleration outside [10, 99 999.999999] mm/s².
    Accel(usize),
    /// A junction deviation outside [0, 10] mm.
    Junction,
}

impl fmt::Display for LimitsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LimitsError::Rate(_) => "rapid rate must be over 0, at most 99999.999999 mm/min",
            LimitsError::Accel(_) => "acceleration must be 10 to 99999.999999 mm/s2",
            LimitsError::Junction => "junction deviation must be 0 to 10 mm",
        })
    }
}

/// The machine's motion limits, validated: rapid rates (X on the radius)
/// and accelerations per axis, and the junction deviation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Limits {
    /// Rapid rates, Å/min.
    vmax: [u64; 2],
    /// Accelerations, Å/s².
    amax: [u64; 2],
    /// Junction deviation δ, Å.
    junction: u64,
}

const MM: u64 = ANGSTROM_PER_MM as u64;

impl Limits {
    /// A small lathe with steppers: rapids 1500 (X, radius) and 3000 mm/min,
    /// 100 and 150 mm/s², δ = 0.01 mm.
    pub const DEFAULT: Limits = Limits {
        vmax: [1500 * MM, 3000 * MM],
        amax: [100 * MM, 150 * MM],
        junction: MM / 100,
    };

    /// Limits from rates (mm/min), accelerations (mm/s²) and δ (mm).
    ///
    /// ```
    /// use core_nostd::{length::Length, plan::{Limits, LimitsError}};
    /// let l = |s| Length::from_mm_str(s).unwrap();
    /// let ok = Limits::new([l("1500"), l("3000")], [l("100"), l("150")], l("0.01"));
    /// assert_eq!(ok, Ok(Limits::DEFAULT));
    /// let slow = Limits::new([l("1500"), l("3000")], [l("9.999999"), l("150")], l("0.01"));
    /// assert_eq!(slow, Err(LimitsError::Accel(0)));
    /// ```
    pub fn new(
        vmax: [Length; 2],
        amax: [Length; 2],
        junction: Length,
    ) -> Result<Limits, LimitsError> {
        let mut out = Limits::DEFAULT;
        for axis in 0..2 {
            let v = vmax[axis].as_angstrom();
            if v <= 0 || v > 100_000 * ANGSTROM_PER_MM {
                return Err(LimitsError::Rate(axis));
            }
            let a = amax[axis].as_angstrom();
            if !(10 * ANGSTROM_PER_MM..=100_000 * ANGSTROM_PER_MM).contains(&a) {
                return Err(LimitsError::Accel(axis));
            }
            out.vmax[axis] = v as u64;
            out.amax[axis] = a as u64;
        }
        let j = junction.as_angstrom();
        if !(0..=10 * ANGSTROM_PER_MM).contains(&j) {
            return Err(LimitsError::Junction);
        }
        out.junction = j as u64;
        Ok(out)
    }

    /// The rapid rate of an axis (0 X, 1 Z), mm/min as a length.
    pub fn rate(&self, axis: usize) -> Length {
        length(self.vmax.get(axis).copied().unwrap_or(0))
    }

    /// The acceleration of an axis, mm/s² as a length.
    pub fn accel(&self, axis: usize) -> Length {
        length(self.amax.get(axis).copied().unwrap_or(0))
    }

    /// The junction deviation.
    pub fn junction(&self) -> Length {
        length(self.junction)
    }

    /// The first axis (0 X, 1 Z) whose rapid rate needs more than `rate_hz`
    /// step events per second at price `h`: `VMAX/h > RATE`.
    ///
    /// ```
    /// use core_nostd::{impulse::ImpulsePrice, plan::Limits};
    /// let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
    /// assert_eq!(Limits::DEFAULT.too_fast(h, 5000), None); // 1500/60/0.005 = 5000
    /// assert_eq!(Limits::DEFAULT.too_fast(h, 4999), Some(0));
    /// ```
    pub fn too_fast(&self, h: [ImpulsePrice; 2], rate_hz: u32) -> Option<usize> {
        (0..2).find(|&a| {
            let price = h[a].as_angstrom() as u128;
            // VMAX[Å/min] > 60·h[Å]·RATE
            u128::from(self.vmax[a]) > 60 * price * u128::from(rate_hz)
        })
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits::DEFAULT
    }
}

/// A whole number of ångström as a [`Length`] (limits stay far inside).
fn length(angstrom: u64) -> Length {
    Length::from_angstrom(angstrom as i64).unwrap_or(Length::ZERO)
}

/// A programmed feed along the path, 0.001 … 99 999.999999 mm/min.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Feed {
    /// Å/min.
    angstrom_per_min: u64,
}

impl Feed {
    /// A feed from mm/min, if 0.001 … 99 999.999999.
    ///
    /// ```
    /// use core_nostd::{length::Length, plan::Feed};
    /// let l = |s| Length::from_mm_str(s).unwrap();
    /// assert!(Feed::new(l("0.001")).is_some());
    /// assert!(Feed::new(l("0.000999")).is_none());
    /// assert!(Feed::new(l("-1")).is_none());
    /// ```
    pub fn new(mm_per_min: Length) -> Option<Feed> {
        let a = mm_per_min.as_angstrom();
        if (ANGSTROM_PER_MM / 1000..=100_000 * ANGSTROM_PER_MM).contains(&a) {
            Some(Feed {
                angstrom_per_min: a as u64,
            })
        } else {
            None
        }
    }

    /// The feed in mm/min, as a length.
    pub fn mm_per_min(self) -> Length {
        length(self.angstrom_per_min)
    }
}

/// The limits in tick units, for one clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rates {
    limits: Limits,
    tick: TickRate,
    /// `VMAX/(60·TICK)` per axis, Q96 Å/tick.
    vmax: [u128; 2],
    /// `AMAX/TICK²` per axis, Q96 Å/tick².
    accel: [u128; 2],
    /// The rapid override, percent of the rapid rates (grbl's 100, 50, 25).
    rapid: u8,
}

impl Rates {
    /// The default limits on the device's timer.
    pub const DEFAULT: Rates = Rates::new(Limits::DEFAULT, TickRate::TIMER);

    /// The limits on a clock of `tick`.
    pub const fn new(limits: Limits, tick: TickRate) -> Rates {
        let t2 = tick.hz() as u128 * tick.hz() as u128;
        let per_min = 60 * tick.hz() as u128;
        Rates {
            limits,
            tick,
            vmax: [
                shl_div(limits.vmax[0] as u128, 96, per_min),
                shl_div(limits.vmax[1] as u128, 96, per_min),
            ],
            accel: [
                shl_div(limits.amax[0] as u128, 96, t2),
                shl_div(limits.amax[1] as u128, 96, t2),
            ],
            rapid: 100,
        }
    }

    /// The same rates, rapids at `percent` (1 … 100) of the rapid rates.
    pub const fn with_rapid(mut self, percent: u8) -> Rates {
        self.rapid = if percent == 0 || percent > 100 {
            100
        } else {
            percent
        };
        self
    }

    /// The rapid override, percent.
    pub const fn rapid(&self) -> u8 {
        self.rapid
    }

    /// The limits.
    pub const fn limits(&self) -> &Limits {
        &self.limits
    }

    /// The clock.
    pub const fn tick(&self) -> TickRate {
        self.tick
    }

    /// `(F/(60·TICK))²`, Q64 (Å/tick)².
    fn feed2(&self, f: Feed) -> u128 {
        let t = u128::from(self.tick.hz());
        let fa = u128::from(f.angstrom_per_min);
        shl_div(fa * fa, 64, 3600 * t * t)
    }

    /// `60·TICK`: ticks per minute.
    fn ticks_per_min(&self) -> u128 {
        60 * u128::from(self.tick.hz())
    }
}

impl Default for Rates {
    fn default() -> Self {
        Rates::DEFAULT
    }
}

/// A point in ångström · 2³² (X on the radius, Z).
pub type Point = [i128; 2];

/// A length as a [`Point`] coordinate.
pub const fn q32(l: Length) -> i128 {
    (l.as_angstrom() as i128) << 32
}

/// What the cruise speed is, for an exact cruise time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Source {
    /// The programmed feed, Å/min.
    Feed(u64),
    /// An axis's rapid rate.
    Axis(usize),
}

/// A motion block: a straight segment with its impulses, checked and ready
/// to plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    events: LinearBlock,
    /// The segment, Å·2³².
    d: [i128; 2],
    /// The direction, `max(|x|,|z|)` in `[2⁶¹, 2⁶²]`.
    dn: [i64; 2],
    /// `⌊|dn|·2³²⌋`.
    lnq: u128,
    /// `|d| = |dn| · 2^scale` (Å·2³²).
    scale: i32,
    /// The lead axis: distance from the start to the first event's boundary
    /// and the whole move along it (Å·2⁶⁴), its price (Å), `|dn|` on it.
    lead_first: u128,
    lead_len: u128,
    lead_price: u64,
    lead_dn: u64,
    /// The rounded segment does not move the lead axis the way its impulses
    /// go (a chord of a fraction of a grid unit): every event at the end.
    backwards: bool,
    /// `v_max²`, Q64 (Å/tick)², and what limits it.
    vmax2: u128,
    source: Source,
    /// `a`, Q96 Å/tick².
    accel: u128,
    /// `2aL`, Q64 (Å/tick)².
    two_al: u128,
    /// The highest entry `v²` the junction with the block before allows.
    junction2: u128,
    /// A part of a block (a hold stopped it): the events before it, and
    /// its own.
    skip: u32,
    count: u32,
    /// Ticks per minute, and the rapid rate (Å/min) of the axis that
    /// limits a rapid cruise: what timing a cruise needs besides the block.
    per_min: u64,
    axis_vmax: u64,
    /// The spindle speed commanded while it runs, 10⁻³ rpm (0: stopped):
    /// the output follows it at the block's start.
    spindle: u32,
    /// A backlash take-up: its steps turn the leadscrew through its play
    /// and move no register (`docs/motion.md` §7).
    takeup: bool,
}

impl Block {
    /// The block as a backlash take-up: its steps move no register.
    pub const fn as_takeup(mut self) -> Block {
        self.takeup = true;
        self
    }

    /// Whether it is a backlash take-up.
    pub const fn takeup(&self) -> bool {
        self.takeup
    }

    /// The block with the spindle speed commanded while it runs (10⁻³
    /// rpm).
    pub const fn with_spindle(mut self, milli_rpm: u32) -> Block {
        self.spindle = milli_rpm;
        self
    }

    /// The spindle speed commanded while it runs, 10⁻³ rpm.
    pub const fn spindle(&self) -> u32 {
        self.spindle
    }

    /// The block from `from` to `to` (Å·2³², `|coordinate| < 2⁷²`) issuing
    /// `events` at prices `h`, at `feed` (rapid when `None`); `None` when it
    /// has no length (such a block takes no time and issues nothing).
    pub fn new(
        from: Point,
        to: Point,
        events: LinearBlock,
        feed: Option<Feed>,
        h: [ImpulsePrice; 2],
        rates: &Rates,
    ) -> Option<Block> {
        let mut d = [to[0].checked_sub(from[0])?, to[1].checked_sub(from[1])?];
        let (nx, nz) = events.delta();
        let lead = usize::from(nz.unsigned_abs() > nx.unsigned_abs());
        if d == [0, 0] {
            // No length: nothing to plan, unless the ends lie on either side
            // of a rounding boundary closer than 2⁻³² Å (then 2⁻³² Å long).
            let n = if lead == 0 { nx } else { nz };
            if n == 0 {
                return None;
            }
            d[lead] = i128::from(n.signum());
        }
        let m = d[0].unsigned_abs().max(d[1].unsigned_abs());
        if m >= 1 << 100 {
            return None;
        }
        let bits = 128 - m.leading_zeros() as i32;
        let scale = bits - 62;
        let norm = |v: i128| -> i64 {
            if scale > 0 {
                // Half away from zero.
                let half = 1i128 << (scale - 1);
                let r = (v.unsigned_abs() as i128 + half) >> scale;
                (if v < 0 { -r } else { r }) as i64
            } else {
                (v << -scale) as i64
            }
        };
        let dn = [norm(d[0]), norm(d[1])];
        let d2n = sq(dn[0]) + sq(dn[1]);
        let lnq = sqrt_shl(d2n, 64);
        // a and v_max over the moving axes: the axis's limit times
        // |d|/|d_axis|.
        let mut accel = u128::MAX;
        let mut vmax2 = u128::MAX;
        let mut source = Source::Axis(0);
        for (axis, &c) in dn.iter().enumerate() {
            let m = u128::from(c.unsigned_abs()) << 32;
            if m == 0 {
                continue;
            }
            let (acc, vmax) = (rates.accel[axis & 1], rates.vmax[axis & 1]);
            accel = accel.min(mul_div(acc, lnq, m));
            // v in Q96 Å/tick, squared to Q64.
            let v = mul_div(vmax, lnq, m);
            let v2 = mul_shr(v, v, 128);
            if v2 < vmax2 {
                (vmax2, source) = (v2, Source::Axis(axis));
            }
        }
        if let Some(f) = feed {
            let f2 = rates.feed2(f);
            if f2 <= vmax2 {
                (vmax2, source) = (f2, Source::Feed(f.angstrom_per_min));
            }
        } else if rates.rapid < 100 {
            // A rapid under the override: the speed scaled, so its square
            // by the percentage squared.
            let p = u128::from(rates.rapid);
            vmax2 = mul_div(vmax2, p * p, 10_000);
        }
        // 2aL = 2·a·|dn|·2^scale, Q96 · Q32·Q32 → Q64.
        let two_al = mul_shr(accel, lnq, (95 - scale) as u32);
        // The lead axis by impulses, X when equal (`docs/impulses.md` §3.1); a block
        // without impulses is measured along the axis that moves most.
        let lead = if nx == 0 && nz == 0 {
            usize::from(d[1].unsigned_abs() > d[0].unsigned_abs())
        } else {
            lead
        };
        let (a0, n) = if lead == 0 {
            (events.from().x.get(), nx)
        } else {
            (events.from().z.get(), nz)
        };
        let price = h[lead].as_angstrom();
        // Boundary of the first impulse, (a0 + σ/2)·h, in Å·2³².
        let sigma: i128 = if n < 0 { -1 } else { 1 };
        let boundary = ((2 * i128::from(a0) + sigma) * i128::from(price)) << 31;
        let first = ((sigma * (boundary - from[lead])).max(0) as u128) << 32;
        // A chord of a fraction of a grid unit that does not move its lead
        // axis the way its impulses go: every event at its end, and the
        // block measured along the axis that moves most (it still takes
        // the time of its length).
        let backwards = n != 0 && sigma * d[lead] <= 0;
        let lead = if backwards {
            usize::from(d[1].unsigned_abs() > d[0].unsigned_abs())
        } else {
            lead
        };
        let lead_len = d[lead].unsigned_abs() << 32;
        Some(Block {
            events,
            d,
            dn,
            lnq,
            scale,
            lead_first: first,
            lead_len,
            backwards,
            lead_price: price as u64,
            lead_dn: dn[lead].unsigned_abs().max(1),
            vmax2,
            source,
            accel,
            two_al,
            junction2: 0,
            skip: 0,
            count: nx.unsigned_abs().max(nz.unsigned_abs()),
            spindle: 0,
            takeup: false,
            per_min: rates.ticks_per_min() as u64,
            axis_vmax: match source {
                // Under the rapid override, the axis's rate scaled as v² is.
                Source::Axis(axis) => {
                    rates.limits.vmax[axis & 1] / 100 * u64::from(rates.rapid)
                        + rates.limits.vmax[axis & 1] % 100 * u64::from(rates.rapid) / 100
                }
                Source::Feed(_) => 0,
            },
        })
    }

    /// The part of the block between lead-axis distances `from` and `to`
    /// (Å·2⁶⁴ from its start, `from ≤ to ≤` its length) holding its
    /// events `done + 1 ..= done + count`: what remains of it after a hold,
    /// or up to where a hold stops it. It enters from whatever speed it
    /// is given (no junction).
    pub(crate) fn part(&self, from: u128, to: u128, done: u32, count: u32) -> Block {
        let to = to.min(self.lead_len).max(from);
        let h = u128::from(self.lead_price) << 64;
        // The boundary of event `done + 1` (of this part's first), from
        // the part's start.
        let first = self
            .lead_first
            .saturating_add(u128::from(done.saturating_sub(self.skip)) * h)
            .saturating_sub(from);
        Block {
            lead_first: if self.backwards { 0 } else { first },
            lead_len: to - from,
            two_al: mul_div(self.two_al, to - from, self.lead_len.max(1)),
            junction2: 0,
            skip: done,
            count,
            ..*self
        }
    }

    /// The lead-axis distance from the block's start to the boundary of
    /// its event `i` (1-based, of this part), Å·2⁶⁴; its end when the
    /// block runs backwards.
    pub(crate) fn boundary(&self, i: u32) -> u128 {
        if self.backwards {
            return self.lead_len;
        }
        let h = u128::from(self.lead_price) << 64;
        self.lead_first
            .saturating_add(u128::from(i.saturating_sub(1)) * h)
            .min(self.lead_len)
    }

    /// How many of this part's events have their boundaries at or before
    /// lead-axis distance `at`.
    pub(crate) fn events_upto(&self, at: u128) -> u32 {
        if self.backwards {
            return if at >= self.lead_len { self.count } else { 0 };
        }
        if at < self.lead_first {
            return 0;
        }
        let h = u128::from(self.lead_price) << 64;
        let h = NonZeroU128::new(h).unwrap_or(NonZeroU128::MIN);
        divrem_u128(at - self.lead_first, h)
            .0
            .saturating_add(1)
            .min(u128::from(self.count)) as u32
    }

    /// The events before this part, and its own.
    pub(crate) const fn span(&self) -> (u32, u32) {
        (self.skip, self.count)
    }

    /// The part up to where a hold brings the axes to rest from `v2`: its
    /// `2aL` is that `v²` exactly (the stop was placed by it).
    pub(crate) const fn braking_to_rest(self, v2: u128) -> Block {
        Block { two_al: v2, ..self }
    }

    /// The lead axis's length of the block, Å·2⁶⁴.
    pub(crate) const fn lead_len(&self) -> u128 {
        self.lead_len
    }

    /// The block's impulses.
    pub const fn events(&self) -> &LinearBlock {
        &self.events
    }

    /// `v_max²` of the block, Q64 (Å/tick)².
    pub const fn vmax2(&self) -> u128 {
        self.vmax2
    }

    /// Step events along the lead axis.
    fn lead_events(&self) -> u32 {
        self.count
    }

    /// `2aL`, Q64 (Å/tick)².
    pub const fn two_al(&self) -> u128 {
        self.two_al
    }

    /// The largest entry `v²` the junction with the block before allows,
    /// Q64 (Å/tick)² (0 for the first block of a run).
    pub const fn junction2(&self) -> u128 {
        self.junction2
    }

    /// The junction `v²` from `self` into `next` (`docs/motion.md` §3, grbl's rule),
    /// capped by both blocks' `v_max²`.
    fn junction_into(&self, next: &Block, delta: u64) -> u128 {
        let cap = self.vmax2.min(next.vmax2);
        let (a, b) = (self.d, next.d);
        // Exactly collinear: a straight continuation or a reversal.
        if cross_is_zero(a, b) {
            let same = (a[0] >= 0) == (b[0] >= 0) && (a[1] >= 0) == (b[1] >= 0);
            return if same { cap } else { 0 };
        }
        if delta == 0 {
            return 0;
        }
        let (p, q) = (self.dn, next.dn);
        let g = i128::from(p[0]) * i128::from(q[0]) + i128::from(p[1]) * i128::from(q[1]);
        let c = i128::from(p[0]) * i128::from(q[1]) - i128::from(p[1]) * i128::from(q[0]);
        let pp = (self.lnq >> 32) * (next.lnq >> 32);
        // s² = cos²(ψ/2) = (P + g)/(2P), Q126 (ψ the angle between the
        // directions); s' = sin(ψ/2).
        let pg = (pp as i128).saturating_add(g).max(0) as u128;
        let s2 = shl_div(pg, 125, pp).min(1 << 126);
        let s = isqrt(s2) as u128; // Q63
                                   // s'² = 1 − s², without cancellation on either side of 90°.
        let s2p = if g >= 0 {
            // sin ψ = |c|/P, and s'² = sin²ψ/(4s²).
            let sin = shl_div(c.unsigned_abs(), 64, pp); // Q64
            U256::mul(sin, sin)
                .shl_by(122)
                .map_or(u128::MAX, |n| n.div(s2))
        } else {
            shl_div((pp as i128 - g) as u128, 125, pp).min(1 << 126)
        };
        if s2p == 0 {
            return cap;
        }
        // v² = a·δ·s(1 + s)/s'².
        let a = self.accel.min(next.accel);
        let a_delta = mul_shr(a, u128::from(delta), 32); // Q64 (Å/tick)²
        let s_one_s = s * (s + (1 << 63)); // Q126
        mul_div(a_delta, s_one_s, s2p).min(cap)
    }
}

/// `v²` of a 64-bit value, exact.
const fn sq(v: i64) -> u128 {
    let m = v.unsigned_abs() as u128;
    m * m
}

/// Whether `a × b = 0` exactly.
fn cross_is_zero(a: [i128; 2], b: [i128; 2]) -> bool {
    let l = U256::mul(a[0].unsigned_abs(), b[1].unsigned_abs());
    let r = U256::mul(a[1].unsigned_abs(), b[0].unsigned_abs());
    if l != r {
        return false;
    }
    // Equal magnitudes: zero, or equal signs of the two products.
    let zero = l == U256::mul(0, 0);
    zero || ((a[0] < 0) != (b[1] < 0)) == ((a[1] < 0) != (b[0] < 0))
}

/// Where a started block is at the boundary of its event `i` (1-based, of
/// its timing; 0 its start): the exact time in its run (Q64 ticks) and the
/// speed squared (Q64 (Å/tick)²) of its trapezoid there.
pub(crate) fn state_at(b: &Block, t: &TimedBlock, i: u32) -> (u128, u128) {
    let [e2, c2, x2] = t.speeds2;
    if i == 0 {
        return (t.start, e2);
    }
    if b.backwards {
        return (t.end, x2);
    }
    let (d, len, tal) = (b.boundary(i), b.lead_len.max(1), b.two_al);
    let v2 = e2
        .saturating_add(mul_div(tal, d, len))
        .min(c2)
        .min(x2.saturating_add(mul_div(tal, len - d.min(len), len)));
    let u = |v2: u128| shl_div(sqrt_shl(v2, 64), 96, b.accel);
    let time = if i <= t.accel_events {
        // start + u(v) − u_entry: the ramp's origin is ½ − start + u_entry.
        let t = (u(v2) as i128)
            .saturating_add((HALF - TIE) as i128)
            .saturating_sub(t.accel.origin);
        t.max(0) as u128
    } else if i <= t.cruise_end {
        let n = u128::from(i.saturating_sub(t.accel_events + 1));
        t.cruise
            .first
            .saturating_sub(HALF + TIE)
            .saturating_add(n.saturating_mul(t.cruise.per_event))
    } else {
        // T_stop − u(v).
        let stop = t.decel.origin.saturating_add((HALF - TIE) as i128).max(0) as u128;
        stop.saturating_sub(u(v2))
    };
    (time.max(t.start).min(t.end), v2)
}

/// A block as it started: its timing, and its plan (a stepper times what
/// remains of it again after a hold).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Started {
    pub(crate) block: Block,
    pub(crate) timed: TimedBlock,
}

impl Started {
    /// Its timing.
    pub const fn timed(&self) -> &TimedBlock {
        &self.timed
    }
}

/// Blocks waiting to start, the current run's clock, and the exit speed of
/// the block that started last.
#[derive(Clone, Debug)]
pub struct Planner<const N: usize> {
    blocks: Deque<Block, N>,
    window: usize,
    /// The block queued last in this run, for the next junction.
    last: Option<Block>,
    /// Exit `v²` of the block that started last.
    exit2: u128,
    /// The current run's time at the end of the block that started last.
    clock: u128,
    /// A block has started since the last run ended.
    running: bool,
}

impl<const N: usize> Default for Planner<N> {
    fn default() -> Self {
        Self::new(WINDOW)
    }
}

impl<const N: usize> Planner<N> {
    /// An empty planner with a window of `window` blocks (1 … N).
    pub const fn new(window: usize) -> Self {
        Planner {
            blocks: Deque::new(),
            window: if window == 0 {
                1
            } else if window > N {
                N
            } else {
                window
            },
            last: None,
            exit2: 0,
            clock: 0,
            running: false,
        }
    }

    /// Blocks queued and not started.
    pub fn queued(&self) -> usize {
        self.blocks.len()
    }

    /// Whether a run is open: a block has started since the last one ended.
    pub const fn in_run(&self) -> bool {
        self.running
    }

    /// Whether nothing is queued and no run is open.
    pub fn is_idle(&self) -> bool {
        self.blocks.is_empty() && !self.running
    }

    /// Queues a block behind the others, with the junction from the block
    /// queued before it in this run. A full queue hands the block back.
    #[allow(clippy::result_large_err)] // the block itself, as heapless does
    pub fn push(&mut self, block: Block, rates: &Rates) -> Result<(), Block> {
        self.push_joined(block, rates, Some(rates.limits.junction))
    }

    /// As [`Planner::push`], the junction from the block before taken at
    /// the speed junction deviation `deviation` (Å) allows, or at rest
    /// (`None`: an exact stop, `G61`).
    #[allow(clippy::result_large_err)] // the block itself, as heapless does
    pub fn push_joined(
        &mut self,
        mut block: Block,
        rates: &Rates,
        deviation: Option<u64>,
    ) -> Result<(), Block> {
        let _ = rates;
        if self.blocks.is_full() {
            return Err(block);
        }
        block.junction2 = match (&self.last, deviation) {
            (Some(prev), Some(d)) => prev.junction_into(&block, d),
            _ => 0,
        };
        self.last = Some(block);
        self.blocks.push_back(block)
    }

    /// Drops every queued block and the run (a reset).
    pub fn clear(&mut self) {
        *self = Planner::new(self.window);
    }

    /// Whether the first block may start without a flush: the window behind
    /// it is full.
    pub fn window_full(&self) -> bool {
        self.blocks.len() >= self.window
    }

    /// Starts the first queued block: fixes its profile from the window
    /// behind it and returns it timed in its run.
    pub fn start(&mut self, rates: &Rates) -> Option<TimedBlock> {
        self.start_block(rates).map(|s| s.timed)
    }

    /// As [`Planner::start`], keeping the block's plan with its timing (a
    /// stepper times what remains of it again after a hold).
    pub fn start_block(&mut self, rates: &Rates) -> Option<Started> {
        // The rates are the blocks' own, fixed when they were queued.
        let _ = rates;
        let n = self.blocks.len().min(self.window);
        // Backward: the highest entry v² of block 1 that still lets every
        // block up to the window's end stop in time.
        let mut next = 0u128;
        // The window behind the head, from its far end: the deque's two
        // slices cut to `n` blocks, the head left out (slices, not a
        // reversed `Skip`, whose length check could panic).
        let (a, b) = self.blocks.as_slices();
        let wa = a.get(..n.min(a.len())).unwrap_or(&[]);
        let wb = b.get(..n.saturating_sub(a.len())).unwrap_or(&[]);
        let (wa, wb) = match wa.split_first() {
            Some((_, rest)) => (rest, wb),
            None => (wa, wb.get(1..).unwrap_or(&[])),
        };
        let behind = wb.iter().rev().chain(wa.iter().rev());
        for b in behind {
            next = b.junction2.min(next.saturating_add(b.two_al));
        }
        let head = self.blocks.pop_front()?;
        let entry = if self.running { self.exit2 } else { 0 };
        let exit = next.min(entry.saturating_add(head.two_al));
        let timed = profile(&head, entry, exit, self.clock);
        self.clock = timed.end;
        self.exit2 = exit;
        self.running = true;
        Some(Started { block: head, timed })
    }

    /// Ends the open run once every block has started: returns its length
    /// in ticks (half up), or `None` when no run is open or blocks wait.
    pub fn end_run(&mut self) -> Option<u64> {
        if !self.blocks.is_empty() || !self.running {
            if self.blocks.is_empty() {
                self.last = None;
            }
            return None;
        }
        let ticks = crate::step::round_ticks(self.clock);
        self.clock = 0;
        self.exit2 = 0;
        self.running = false;
        self.last = None;
        Some(ticks)
    }

    /// Exit `v²` of the block that started last (0 at rest), Q64 (Å/tick)².
    pub const fn exit2(&self) -> u128 {
        if self.running {
            self.exit2
        } else {
            0
        }
    }
}

/// The profile of block `b` from entry `e2` to exit `x2` (squared speeds),
/// starting at `start` (Q64 ticks) in its run: a trapezoid, timed.
pub(crate) fn profile(b: &Block, e2: u128, x2: u128, start: u128) -> TimedBlock {
    let tal = b.two_al.max(1);
    let peak2 = tal.saturating_add(e2).saturating_add(x2) / 2;
    let c2 = b.vmax2.min(peak2);
    // 2(c2 − e2) + 2(c2 − x2) ≤ 2aL: the ramps fit the block.
    let (da, dd) = (c2.saturating_sub(e2), c2.saturating_sub(x2));
    let speed = |v2: u128| sqrt_shl(v2, 64);
    let (ve, vc, vx) = (speed(e2), speed(c2), speed(x2));
    // u = v/a, Q64 ticks.
    let u = |v: u128| shl_div(v, 96, b.accel);
    let (ue, uc, ux) = (u(ve), u(vc), u(vx));
    let t_accel = uc.saturating_sub(ue);
    let t_decel = uc.saturating_sub(ux);
    // Where the ramps end and start along the lead axis (Å·2⁶⁴).
    let len = b.lead_len;
    let l_accel = mul_div(da, len, tal).min(len);
    let l_decel = (len - mul_div(dd, len, tal).min(len)).max(l_accel);
    let dn_lead = u128::from(b.lead_dn);
    // The path along the segment for a distance along the lead axis:
    // times |d|/|d_lead|, Q64.
    let ratio = mul_div(b.lnq, 1 << 32, dn_lead);
    let path = |dl: u128| mul_shr(dl, ratio, 64);
    let per_min = u128::from(b.per_min);
    // The time to cruise `dl` along the lead axis, Q64 ticks; exact but
    // for |d| at a rapid rate.
    let cruise_source = (c2 >= b.vmax2).then_some(b.source);
    let cruise_time = |dl: u128| -> u128 {
        if dl == 0 {
            return 0;
        }
        match cruise_source {
            Some(Source::Feed(f)) => mul_div(path(dl), per_min, u128::from(f)),
            Some(Source::Axis(axis)) => {
                let vmax = u128::from(b.axis_vmax);
                let m = u128::from(b.dn[axis & 1].unsigned_abs());
                mul_div(dl, per_min * m, dn_lead * vmax)
            }
            None => shl_div(path(dl), 64, vc),
        }
    };
    let t_cruise = cruise_time(l_decel - l_accel);
    // Event i is at o + (i − 1)·h along the lead axis.
    let n = b.lead_events();
    let o = b.lead_first;
    let h = u128::from(b.lead_price) << 64;
    let h_nz = NonZeroU128::new(h).unwrap_or(NonZeroU128::MIN);
    let upto = |limit: u128, inclusive: bool| -> u32 {
        let reach = if inclusive {
            limit
        } else {
            limit.saturating_sub(1)
        };
        if reach < o || (!inclusive && limit == 0) {
            0
        } else {
            divrem_u128(reach - o, h_nz)
                .0
                .saturating_add(1)
                .min(u128::from(n)) as u32
        }
    };
    let (accel_events, cruise_end) = if b.backwards {
        (0, 0)
    } else {
        let a = upto(l_accel, true);
        (a, upto(l_decel, false).max(a))
    };
    // 2s/a for a lead-axis distance, Q64 ticks².
    let two_s_over_a = |dl: u128| shl_div(path(dl), 97, b.accel);
    let per_event = two_s_over_a(h);
    let at = |i: u32| o.saturating_add(u128::from(i) * h);
    let signed = |v: u128| i128::try_from(v).unwrap_or(i128::MAX);
    let decel_start = start.saturating_add(t_accel).saturating_add(t_cruise);
    TimedBlock {
        events: b.events,
        part: b.span(),
        accel_events,
        cruise_end,
        accel: Ramp {
            first: mul_shr(ue, ue, 64).saturating_add(two_s_over_a(o)),
            per_event,
            origin: signed(HALF - TIE + ue).saturating_sub(signed(start)),
        },
        cruise: Cruise {
            first: start
                .saturating_add(t_accel)
                .saturating_add(cruise_time(at(accel_events).saturating_sub(l_accel)))
                .saturating_add(HALF + TIE),
            per_event: cruise_time(h),
        },
        decel: Ramp {
            // A backwards block's events are all at its end: Y = u_x².
            first: mul_shr(ux, ux, 64).saturating_add(if b.backwards {
                0
            } else {
                two_s_over_a(len.saturating_sub(at(cruise_end)))
            }),
            per_event: if b.backwards { 0 } else { per_event },
            origin: signed(decel_start.saturating_add(uc)).saturating_sub((HALF - TIE) as i128),
        },
        start,
        end: decel_start.saturating_add(t_decel),
        speeds2: [e2, c2, x2],
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::impulse::{quantize, Impulses};
    use crate::interleave::ImpulsePoint;
    use std::vec::Vec;

    fn mm(s: &str) -> Length {
        Length::from_mm_str(s).unwrap()
    }

    const H: [ImpulsePrice; 2] = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];

    fn block(from: [&str; 2], to: [&str; 2], feed: Option<&str>) -> Block {
        let p = |c: [&str; 2]| [mm(c[0]), mm(c[1])];
        let (a, b) = (p(from), p(to));
        let reg = |c: [Length; 2]| ImpulsePoint {
            x: quantize(c[0], H[0]).unwrap(),
            z: quantize(c[1], H[1]).unwrap(),
        };
        let events = LinearBlock::new(reg(a), reg(b)).unwrap();
        Block::new(
            [q32(a[0]), q32(a[1])],
            [q32(b[0]), q32(b[1])],
            events,
            feed.map(|f| Feed::new(mm(f)).unwrap()),
            H,
            &Rates::default(),
        )
        .unwrap()
    }

    fn run(blocks: &[Block]) -> (Vec<(u8, u64)>, u64) {
        let rates = Rates::default();
        let mut p = Planner::<WINDOW>::new(WINDOW);
        let mut out = Vec::new();
        for b in blocks {
            p.push(*b, &rates).unwrap();
            if p.window_full() {
                let t = p.start(&rates).unwrap();
                out.extend(t.events().map(|(e, k)| (e.bits(), k)));
            }
        }
        while let Some(t) = p.start(&rates) {
            out.extend(t.events().map(|(e, k)| (e.bits(), k)));
        }
        let end = p.end_run().unwrap();
        (out, end)
    }

    #[test]
    fn a_rapid_from_rest_to_rest_is_a_triangle() {
        // Z 10 mm at 150 mm/s², 3000 mm/min: too short to reach the rate.
        let (ev, end) = run(&[block(["0", "0"], ["0", "-10"], None)]);
        assert_eq!(ev.len(), 1000);
        let a = 150.0f64;
        let total = 2.0 * libm::sqrt(10.0 / a);
        assert_eq!(end, libm::round(total * 1e6) as u64);
        for (i, &(byte, tick)) in ev.iter().enumerate() {
            let s = (i as f64 + 0.5) * 0.01;
            let t = if s <= 5.0 {
                libm::sqrt(2.0 * s / a)
            } else {
                total - libm::sqrt(2.0 * (10.0 - s) / a)
            };
            assert_eq!(byte, 0b1010);
            assert_eq!(tick, libm::round(t * 1e6) as u64, "event {}", i + 1);
        }
    }

    #[test]
    fn a_long_feed_block_cruises_at_its_feed() {
        // X 20 mm on the radius (diameter 40) at F300: 5 mm/s, a = 100 mm/s².
        let (ev, end) = run(&[block(["0", "0"], ["20", "0"], Some("300"))]);
        assert_eq!(ev.len(), 4000);
        let (v, a) = (5.0f64, 100.0f64);
        let ramp = v * v / (2.0 * a);
        let total = 20.0 / v + v / a;
        assert!(end.abs_diff(libm::round(total * 1e6) as u64) <= 1);
        for (i, &(_, tick)) in ev.iter().enumerate() {
            let s = (i as f64 + 0.5) * 0.005;
            let t = if s <= ramp {
                libm::sqrt(2.0 * s / a)
            } else if s <= 20.0 - ramp {
                v / (2.0 * a) + s / v
            } else {
                total - libm::sqrt(2.0 * (20.0 - s) / a)
            };
            assert_eq!(tick, libm::round(t * 1e6) as u64, "event {}", i + 1);
        }
    }

    #[test]
    fn collinear_blocks_keep_their_speed() {
        let one = run(&[block(["0", "0"], ["0", "-60"], Some("1200"))]);
        let split = run(&[
            block(["0", "0"], ["0", "-20"], Some("1200")),
            block(["0", "-20"], ["0", "-40"], Some("1200")),
            block(["0", "-40"], ["0", "-60"], Some("1200")),
        ]);
        assert_eq!(one, split);
    }

    #[test]
    fn ramps_take_a_square_root_only_where_the_interval_changes_fast() {
        use core::sync::atomic::Ordering;
        let before = crate::step::DIRECT.load(Ordering::Relaxed);
        let (ev, _) = run(&[block(["0", "0"], ["0", "-50"], None)]);
        let direct = crate::step::DIRECT.load(Ordering::Relaxed) - before;
        std::println!("{} events, {direct} square roots", ev.len());
        let before = crate::step::DIRECT.load(Ordering::Relaxed);
        let s0 = crate::step::STEPS.load(Ordering::Relaxed);
        let (ev, _) = run(&[block(["0", "0"], ["0", "-5"], None)]);
        let tri = crate::step::DIRECT.load(Ordering::Relaxed) - before;
        let steps = crate::step::STEPS.load(Ordering::Relaxed) - s0;
        std::println!(
            "triangle: {} events, {tri} square roots, {steps} steps",
            ev.len()
        );
        // The ramp of a long rapid: 8 mm accelerating from rest.
        let rates = Rates::default();
        let mut p = Planner::<WINDOW>::new(WINDOW);
        for (a, b) in [("0", "-8"), ("-8", "-408"), ("-408", "-416")] {
            p.push(block(["0", a], ["0", b], None), &rates).unwrap();
        }
        let t = p.start(&rates).unwrap();
        let d0 = crate::step::DIRECT.load(Ordering::Relaxed);
        let s0 = crate::step::STEPS.load(Ordering::Relaxed);
        let n = t.events().count();
        let d1 = crate::step::DIRECT.load(Ordering::Relaxed) - d0;
        let s1 = crate::step::STEPS.load(Ordering::Relaxed) - s0;
        std::println!("ramp from rest: {n} events, {d1} square roots, {s1} steps; speeds {:?} accel events {} cruise end {}", t.speeds2(), t.accel_events, t.cruise_end);
        assert!(
            direct < 200,
            "{direct} square roots for {} events",
            ev.len()
        );
    }

    #[test]
    fn a_block_without_impulses_takes_its_time() {
        // Z 0.004 mm from 0 at 0.01 mm per impulse: no impulse, but the
        // slide moves for 2·√(L/a) (a triangle at 150 mm/s²).
        let (ev, end) = run(&[block(["0", "0"], ["0", "-0.004"], None)]);
        assert!(ev.is_empty());
        let t = 2.0 * libm::sqrt(0.004 / 150.0);
        assert_eq!(end, libm::round(t * 1e6) as u64);
        // Measured along Z even though X leads a block without impulses.
        let (_, end) = run(&[block(["0.001", "0"], ["0.001", "-0.004"], None)]);
        assert_eq!(end, libm::round(t * 1e6) as u64);
    }

    #[test]
    fn a_reversal_stops() {
        let b1 = block(["0", "0"], ["0", "-10"], Some("600"));
        let b2 = block(["0", "-10"], ["0", "0"], Some("600"));
        let mut p = Planner::<WINDOW>::new(WINDOW);
        let rates = Rates::default();
        p.push(b1, &rates).unwrap();
        p.push(b2, &rates).unwrap();
        assert_eq!(p.blocks.back().unwrap().junction2, 0);
        let first = p.start(&rates).unwrap();
        assert_eq!(p.exit2(), 0);
        // Symmetric: the run lasts twice the first block.
        let second = p.start(&rates).unwrap();
        assert_eq!(second.end, 2 * first.end);
        let _ = Impulses(0);
    }
}

//! Step events at their ticks: the timed generator a timer interrupt pulls
//! (`docs/motion.md` §5).
//!
//! A started block's profile (fixed by [`crate::plan`]) becomes a
//! [`TimedBlock`]; its [`TimedEvents`] yield `(event, tick)` one at a time,
//! with integer arithmetic only. Event `i` happens when the lead axis crosses
//! the rounding boundary of its new impulse; its tick is `Q(T·TICK)`, `T` the
//! exact time since the run began.
//!
//! # The clock
//! Ticks are counts of a clock the generator is given ([`TickRate`]): the
//! step timer today; a spindle encoder's counts when threading locks Z to
//! the spindle. The generator assumes nothing else about it.
//!
//! # Arithmetic
//! Times are Q64.64 ticks in a `u128`. In the cruise an event costs one
//! 128-bit addition: `T_i = T_1 + (i − 1)·B`, the rest of a cruise after
//! its first event without any other state. In the ramps the time is a
//! square root, which the generator does not take per event: with
//! `u = v/a` the virtual time since the ramp's speed would have been zero,
//! `X = u² = u_entry² + 2s/a` grows by a constant per event, and event `i`
//! is before the half tick `k + ½` exactly when `X_i < z_k²`,
//! `z_k = k + ½ − T_ramp + u_entry`. Moving `k` by `d` changes `z_k²` by
//! `2d·z_k + d²`: a few 32-bit multiplies. The generator predicts the next
//! tick from the last two intervals (second order, in Q16 ticks), then
//! checks it exactly against `X_i` and corrects it, by single ticks and
//! Newton steps `(z² − X)/2z` taken from the leading bits; after
//! 24 corrections (the first events of a ramp from rest) it
//! takes the square root once, so no event costs more than one root and
//! every tick is decided by the exact comparison, never by the estimate.
//! The deceleration is the same with `w_k = T_stop − k − ½` counting down.
//!
//! Errors: every tick is exact for the profile's times, which carry the
//! profile's own rounding (see [`crate::plan`]).

use crate::crc32::Crc32;
use crate::interleave::{LinearBlock, StepEvent, StepEvents};
use crate::wide::{mul_shr, sqrt_shl};

/// One tick in Q64.64.
pub(crate) const ONE: u128 = 1 << 64;
/// Half a tick in Q64.64.
pub(crate) const HALF: u128 = 1 << 63;
/// A time this close below a half tick is taken as the tie and rounds up:
/// 2⁻³⁶ tick. Exact ties occur (a cruise at a round feed along an axis), the
/// formats carry far less error than this (about 2⁻⁴⁰ tick), and the
/// reference decides ties by the same rule (`docs/motion.md`).
pub(crate) const TIE: u128 = 1 << 28;

/// The frequency of the clock events are timed on, 1 Hz … 2 MHz.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TickRate {
    hz: u32,
}

impl TickRate {
    /// The device's step timer: 1 MHz.
    pub const TIMER: TickRate = TickRate { hz: 1_000_000 };
    /// The highest rate the planner's formats are proven for.
    pub const MAX_HZ: u32 = 1 << 21;

    /// A clock of `hz` ticks per second, if 1 … [`Self::MAX_HZ`].
    ///
    /// ```
    /// use core_nostd::step::TickRate;
    /// assert_eq!(TickRate::new(1_000_000), Some(TickRate::TIMER));
    /// assert!(TickRate::new(0).is_none());
    /// ```
    pub const fn new(hz: u32) -> Option<TickRate> {
        if hz >= 1 && hz <= Self::MAX_HZ {
            Some(TickRate { hz })
        } else {
            None
        }
    }

    /// Ticks per second.
    pub const fn hz(self) -> u32 {
        self.hz
    }
}

/// `Q(t)`: a Q64.64 time rounded half up to whole ticks (half away from
/// zero, times being positive), a tie within [`TIE`].
pub(crate) const fn round_ticks(t: u128) -> u64 {
    (t.saturating_add(HALF + TIE) >> 64) as u64
}

/// A ramp of a started block: accelerating or decelerating at constant `a`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Ramp {
    /// `X` (accelerating) or `Y` (decelerating) of the ramp's first event,
    /// Q64 ticks².
    pub first: u128,
    /// Its change per event, Q64 ticks².
    pub per_event: u128,
    /// Accelerating: `½ − T_ramp + u_entry`, so `z_k = k + origin`.
    /// Decelerating: `T_stop − ½`, so `w_k = origin − k`. Q64 ticks, the
    /// half tick moved by [`TIE`] so that ties round up.
    pub origin: i128,
}

/// The cruise of a started block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Cruise {
    /// The time of its first event plus half a tick (and [`TIE`]), Q64.
    pub first: u128,
    /// Time between events, Q64 ticks.
    pub per_event: u128,
}

/// A block whose profile is fixed: its events and everything needed to time
/// them. Built by the planner when the block starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimedBlock {
    pub(crate) events: LinearBlock,
    /// The events of the block before this timing, and its own (all of
    /// them, but for what a hold re-timed).
    pub(crate) part: (u32, u32),
    /// Events `1 ..= accel_events` accelerate, up to `cruise_end` cruise,
    /// the rest decelerate.
    pub(crate) accel_events: u32,
    pub(crate) cruise_end: u32,
    pub(crate) accel: Ramp,
    pub(crate) cruise: Cruise,
    pub(crate) decel: Ramp,
    /// When the block starts and ends in its run, Q64 ticks.
    pub(crate) start: u128,
    pub(crate) end: u128,
    /// Entry, cruise and exit speeds squared, Q64 (Å/tick)².
    pub(crate) speeds2: [u128; 3],
}

impl TimedBlock {
    /// The block's impulses.
    pub const fn block(&self) -> &LinearBlock {
        &self.events
    }

    /// When the block ends, in whole ticks of its run (rounded half up).
    pub const fn end_tick(&self) -> u64 {
        round_ticks(self.end)
    }

    /// When the block starts and ends in its run, ticks · 2⁶⁴.
    pub const fn span_q64(&self) -> (u128, u128) {
        (self.start, self.end)
    }

    /// The squared entry, cruise (peak) and exit speeds of its trapezoid,
    /// (Å/tick)² · 2⁶⁴.
    pub const fn speeds2(&self) -> [u128; 3] {
        self.speeds2
    }

    /// The events with their ticks, one at a time.
    pub fn events(&self) -> TimedEvents {
        let steps = self.events.events().part(self.part.0, self.part.1);
        TimedEvents {
            total: steps.size_hint().0 as u32,
            steps,
            t: 0,
            fast: 0,
            block: *self,
            phase: Phase::Start,
            a: 0,
            r: 0,
            rr: 0,
            tick: 0,
            predict: Predict::START,
            end: self.end_tick(),
        }
    }
}

/// The phase the generator is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// No event yet in this phase: the next one is placed directly.
    Start,
    /// Accelerating: `a` is `x` of the last event, `r` `z_k` (positive) of
    /// its tick, `rr` `⌊z_k²⌋`.
    Accel,
    /// Cruising: the next event's time is in `TimedEvents::t`.
    Cruise,
    /// Decelerating: `a` is `y` of the last event, `r` `w_k` of its tick
    /// (an `i128`'s bits), `rr` `⌊w_k²⌋` (meaningful while `w ≥ 0`).
    Decel,
}

/// The timed step events of a [`TimedBlock`].
#[derive(Clone, Debug)]
pub struct TimedEvents {
    steps: StepEvents,
    /// The cruise: the next event's time plus half a tick (and [`TIE`]),
    /// and how many events take it by one addition each.
    t: u128,
    fast: u32,
    /// Events of the block.
    total: u32,
    block: TimedBlock,
    phase: Phase,
    /// The ramp's state (see [`Phase`]).
    a: u128,
    r: u128,
    rr: u128,
    /// The tick of the last event outside the fast cruise.
    tick: u64,
    /// Where the next ramp event is expected.
    predict: Predict,
    /// The block's end, whole ticks.
    end: u64,
}

impl TimedEvents {
    /// The timing these events come from.
    pub const fn timed(&self) -> &TimedBlock {
        &self.block
    }

    /// Events of the timing handed out so far.
    pub fn done(&self) -> u32 {
        self.total - self.steps.size_hint().0 as u32
    }
}

impl Iterator for TimedEvents {
    type Item = (StepEvent, u64);

    #[inline(always)]
    fn next(&mut self) -> Option<(StepEvent, u64)> {
        let event = self.steps.next()?;
        if self.fast > 0 {
            // The cruise: one addition.
            self.fast -= 1;
            let tick = (self.t >> 64) as u64;
            self.t = self.t.wrapping_add(self.block.cruise.per_event);
            return Some((event, tick));
        }
        Some((event, self.slow()))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.steps.size_hint()
    }
}

impl ExactSizeIterator for TimedEvents {}

/// `z = k + origin` in Q64, if positive.
fn z_of(k: u64, origin: i128) -> Option<u128> {
    let z = (i128::from(k) << 64).saturating_add(origin);
    u128::try_from(z).ok().filter(|&z| z > 0)
}

/// `⌊num/den⌋` to about 2⁻³⁰ relative, in whole units (at most 2⁴⁰): the
/// size of a correction, never a result.
fn approx_div(num: u128, den: u128) -> u64 {
    // 32 significant bits of the divisor; a 64-by-64-bit division.
    let s = (128 - den.leading_zeros()).saturating_sub(32);
    let d = (den >> s) as u64;
    let n = num >> s;
    if d == 0 || n >> 64 != 0 {
        return 1 << 40;
    }
    ((n as u64) / d).min(1 << 40)
}

/// Corrections after a prediction before the exact root is taken.
const MAX_STEPS: u32 = 24;

impl TimedEvents {
    /// The next event outside the fast cruise: a phase's first event, a
    /// ramp's, or the block's last (which may need to wait for its end).
    fn slow(&mut self) -> u64 {
        // The event's number in its block, 1-based.
        let i = self.total - self.steps.size_hint().0 as u32;
        let b = &self.block;
        let tick = if i <= b.accel_events {
            let (x, found) = if self.phase == Phase::Accel {
                let x = self.a.wrapping_add(b.accel.per_event);
                (
                    x,
                    accel_walk(x, self.tick, self.r, self.rr, self.predict.jump()),
                )
            } else {
                (b.accel.first, None)
            };
            let first = found.is_none();
            let (k, z, zz) = match found {
                Some(v) => v,
                None => accel_direct(x, b.accel.origin),
            };
            (self.phase, self.a, self.r, self.rr) = (Phase::Accel, x, z, zz);
            // φ = z − √x ≈ (z² − x)/2z: how far the event lies below k.
            self.predict
                .next(first, k.wrapping_sub(self.tick), phi(zz.wrapping_sub(x), z));
            k
        } else if i <= b.cruise_end {
            if self.phase != Phase::Cruise {
                self.phase = Phase::Cruise;
                self.t = b.cruise.first;
                // The rest of the cruise by additions, but for the block's
                // last event, which may need the clamp below.
                self.fast =
                    (b.cruise_end - i).saturating_sub(u32::from(b.cruise_end == self.total));
            }
            let tick = (self.t >> 64) as u64;
            self.t = self.t.wrapping_add(b.cruise.per_event);
            tick
        } else {
            let (y, found) = if self.phase == Phase::Decel {
                let y = self.a.saturating_sub(b.decel.per_event);
                (
                    y,
                    decel_walk(y, self.tick, self.r as i128, self.rr, self.predict.jump()),
                )
            } else {
                (b.decel.first, None)
            };
            let first = found.is_none();
            let (k, w, ww) = match found {
                Some(v) => v,
                None => decel_direct(y, b.decel.origin),
            };
            (self.phase, self.a, self.r, self.rr) = (Phase::Decel, y, w as u128, ww);
            // φ = √y − w ≈ (y − w²)/2w; past the virtual stop, unknown.
            let f = if w > 0 {
                phi(y.wrapping_sub(ww), w as u128)
            } else {
                ONE_Q16
            };
            self.predict
                .next(first || w <= 0, k.wrapping_sub(self.tick), f);
            k
        };
        // A chord's last boundary may lie up to half a grid unit beyond its
        // rounded end: that event happens at the end.
        let tick = tick.min(self.end);
        self.tick = tick;
        tick
    }
}

/// One tick in Q16.
const ONE_Q16: i64 = 1 << 16;

/// `z·m`, exact while the product fits (`z < 2⁹⁶`): four 32-bit multiplies
/// (a general 128-bit product costs a library call on a Cortex-M4).
#[inline(always)]
fn mul_small(z: u128, m: u32) -> u128 {
    let m = u64::from(m);
    let w0 = u64::from(z as u32) * m;
    let w1 = u64::from((z >> 32) as u32) * m + (w0 >> 32);
    let w2 = u64::from((z >> 64) as u32) * m + (w1 >> 32);
    let w3 = u64::from((z >> 96) as u32) * m + (w2 >> 32);
    u128::from(w0 as u32)
        | u128::from(w1 as u32) << 32
        | u128::from(w2 as u32) << 64
        | u128::from(w3 as u32) << 96
}

/// `(z ± d)² = z² ± 2d·z + d²` for the squares kept in Q64 (`d < 2³⁰`).
#[inline(always)]
fn square_step(zz: u128, z: u128, d: u64, up: bool) -> u128 {
    let (two_dz, dd) = (mul_small(z, 2 * d as u32), u128::from(d * d) << 64);
    if up {
        zz.wrapping_add(two_dz).wrapping_add(dd)
    } else {
        zz.wrapping_sub(two_dz).wrapping_add(dd)
    }
}

/// `num/2den` in Q16, clamped to [0, 1], from the leading bits (about 2⁻¹⁴
/// relative): for the prediction only. `den` is a Q64 tick count below
/// 2⁹⁴, `num < 2·den`.
#[inline(always)]
fn phi(num: u128, den: u128) -> i64 {
    // Q32 views (shifts by whole words), then 15 significant bits of the
    // divisor and one 32-bit division.
    let (n, d) = ((num >> 32) as u64, (den >> 32) as u64);
    let bits = 64 - d.leading_zeros();
    if bits < 15 {
        return ONE_Q16;
    }
    let sh = bits - 15;
    let (n, d) = (n >> sh, (d >> sh) as u32);
    if d == 0 || n >> 16 != 0 {
        return ONE_Q16;
    }
    // (n / d) / 2 in Q16: n·2¹⁵ / d.
    i64::from(((n as u32) << 15) / d).min(ONE_Q16)
}

/// The next ramp event's tick, predicted from the last ones: with `s` the
/// exact event time less half a tick, each event's tick is `⌊s⌋ + 1` and
/// `φ = tick − s` (in (0, 1]); the next `s` is extrapolated from the last
/// two intervals of `s` (second order: a ramp's intervals change smoothly).
#[derive(Clone, Copy, Debug)]
struct Predict {
    /// The last two intervals of `s`, Q16 ticks.
    d1: i64,
    d2: i64,
    /// `φ` of the last event, Q16.
    phi: i64,
    /// Intervals known: 0, 1 or 2.
    known: u8,
}

impl Predict {
    const START: Predict = Predict {
        d1: 0,
        d2: 0,
        phi: 0,
        known: 0,
    };

    /// After an event `dk` ticks after the one before (`fresh`: a phase's
    /// first, or one whose `φ` is unknown) at `φ`.
    #[inline(always)]
    fn next(&mut self, fresh: bool, dk: u64, phi: i64) {
        if fresh {
            *self = Predict {
                phi,
                ..Predict::START
            };
            return;
        }
        let d = ((dk.min(1 << 40) as i64) << 16) - phi + self.phi;
        *self = Predict {
            d1: d,
            d2: self.d1,
            phi,
            known: (self.known + 1).min(2),
        };
    }

    /// Ticks from the last event's to the next one's, as predicted.
    #[inline(always)]
    fn jump(&self) -> u64 {
        let step = match self.known {
            0 => return 0,
            1 => self.d1,
            _ => 2 * self.d1 - self.d2,
        };
        // The next s is s + step = tick − φ + step: its tick ⌊…⌋ + 1.
        let off = step - self.phi;
        if off < 0 {
            0
        } else {
            ((off >> 16) as u64 + 1).min(1 << 30)
        }
    }
}

#[cfg(test)]
pub(crate) static DIRECT: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);
#[cfg(test)]
pub(crate) static STEPS: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

/// The tick of the next accelerating event from the last one's (`k`, `z`,
/// `zz`): the smallest `k' ≥ k` with `x < z_{k'}²`. From the predicted
/// interval, corrected by Newton steps on `z² = x` (`z² − x` over `2z`
/// ticks) and single ticks; `None` after [`MAX_STEPS`] corrections.
#[inline(always)]
fn accel_walk(x: u128, k: u64, z: u128, zz: u128, jump: u64) -> Option<(u64, u128, u128)> {
    if x < zz {
        return Some((k, z, zz));
    }
    // Virtual times stay below 2³⁰ ticks (docs: limits) and jumps below
    // 2³⁰: every product below fits, so plain wrapping arithmetic is exact.
    if z >> 94 != 0 {
        return None;
    }
    let floor = k;
    // z_{k+j}² = z_k² + 2j·z_k + j².
    let mut zz = square_step(zz, z, jump, true);
    let mut z = z.wrapping_add(u128::from(jump) << 64);
    let mut k = k.wrapping_add(jump);
    let mut steps = 0;
    loop {
        steps += 1;
        #[cfg(test)]
        STEPS.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
        if steps > MAX_STEPS || z >> 94 != 0 {
            return None;
        }
        if x < zz {
            // Feasible; the answer unless k − 1 is too.
            if k == floor + 1 || z <= ONE {
                return Some((k, z, zz));
            }
            // z_{k−1}² = z_k² − 2z_k + 1.
            let prev = zz.wrapping_sub(2 * z - ONE);
            if x >= prev {
                return Some((k, z, zz));
            }
            // Back by (z² − x)/2z ≤ z − √x (never past the answer): one
            // tick at a time first, the estimate when that is not enough.
            let d = if steps < 3 {
                1
            } else {
                approx_div(zz - x, 2 * z)
                    .max(1)
                    .min(k - floor - 1)
                    .min(1 << 30)
            };
            zz = square_step(zz, z, d, false);
            z = z.wrapping_sub(u128::from(d) << 64);
            k -= d;
        } else {
            // Forward by (x − z²)/2z rounded up, after a single tick.
            let d = if steps < 3 {
                1
            } else {
                approx_div(x - zz, 2 * z).saturating_add(1).min(1 << 30)
            };
            zz = square_step(zz, z, d, true);
            z = z.wrapping_add(u128::from(d) << 64);
            k = k.wrapping_add(d);
        }
    }
}

/// The smallest `k` with `x < z_k²`, `z_k = k + origin`, by one square root
/// and exact checks.
fn accel_direct(x: u128, origin: i128) -> (u64, u128, u128) {
    #[cfg(test)]
    DIRECT.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
    // √x in Q64; k > √x − origin.
    let r = sqrt_shl(x, 64) as i128;
    let d = r.saturating_sub(origin);
    let mut k: u64 = if d < 0 {
        0
    } else {
        ((d >> 64) as u64).saturating_add(1)
    };
    // Exact fix-up: at most a tick or two either way.
    loop {
        match z_of(k, origin) {
            Some(z) if x < mul_shr(z, z, 64) => break,
            _ => k = k.saturating_add(1),
        }
        if k == u64::MAX {
            break;
        }
    }
    while k > 0 {
        match z_of(k - 1, origin) {
            Some(z) if x < mul_shr(z, z, 64) => k -= 1,
            _ => break,
        }
    }
    let z = z_of(k, origin).unwrap_or(ONE);
    (k, z, mul_shr(z, z, 64))
}

/// The deceleration's counterpart of [`accel_walk`]: the smallest `k' ≥ k`
/// where `w < 0` or `y > w²`, `w_{k+1} = w_k − 1`.
#[inline(always)]
fn decel_walk(y: u128, k: u64, w: i128, ww: u128, jump: u64) -> Option<(u64, i128, u128)> {
    let holds = |w: i128, ww: u128| w < 0 || y > ww;
    if holds(w, ww) {
        return Some((k, w, ww));
    }
    // As in `accel_walk`: w below 2⁹⁴ (w ≥ 0 here), exact wrapping steps.
    if w >> 94 != 0 {
        return None;
    }
    let floor = k;
    let (mut k, mut w, mut ww) = (k, w, ww);
    let mut d = jump;
    let mut steps = 0;
    loop {
        // Forward by d (w ≥ 0 and not holding here): (w − d)² = w² − 2dw + d².
        let wd = w.wrapping_sub((u128::from(d) << 64) as i128);
        if wd < 0 {
            // Past the virtual stop: the exact root decides.
            return None;
        }
        ww = square_step(ww, w as u128, d, false);
        w = wd;
        k = k.wrapping_add(d);
        steps += 1;
        #[cfg(test)]
        STEPS.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
        if steps > MAX_STEPS {
            return None;
        }
        if !holds(w, ww) {
            // Forward again: a tick, then by (w² − y)/2w ≤ w − √y (never
            // past the answer).
            d = if steps < 3 {
                1
            } else {
                approx_div(ww - y, 2 * w as u128).clamp(1, 1 << 30)
            };
            continue;
        }
        // Holds: the answer unless k − 1 holds too.
        loop {
            if k == floor + 1 {
                return Some((k, w, ww));
            }
            let wp = w + ONE as i128;
            let wwp = ww.wrapping_add(2 * w as u128 + ONE);
            if !holds(wp, wwp) {
                return Some((k, w, ww));
            }
            // Back: a tick, then by (y − w²)/2w, not past the floor.
            let back = if steps < 3 {
                1
            } else {
                approx_div(y - ww, 2 * (w as u128).max(ONE))
                    .max(1)
                    .min(k - floor - 1)
                    .min(1 << 30)
            };
            ww = square_step(ww, w as u128, back, true);
            w += (u128::from(back) << 64) as i128;
            k -= back;
            steps += 1;
            if steps > MAX_STEPS {
                return None;
            }
            if !holds(w, ww) {
                // Went too far back: forward from here.
                d = 1;
                break;
            }
        }
    }
}

/// The smallest `k` with `w_k < 0` or `y > w_k²`, `w_k = origin − k`.
fn decel_direct(y: u128, origin: i128) -> (u64, i128, u128) {
    #[cfg(test)]
    DIRECT.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
    let r = sqrt_shl(y, 64) as i128;
    let holds = |k: u64| {
        let w = origin.saturating_sub(i128::from(k) << 64);
        w < 0 || y > mul_shr(w as u128, w as u128, 64)
    };
    // w_k < √y ⟺ k > origin − √y.
    let d = origin.saturating_sub(r);
    let mut k: u64 = if d < 0 {
        0
    } else {
        ((d >> 64) as u64).saturating_add(1)
    };
    while !holds(k) && k < u64::MAX {
        k += 1;
    }
    while k > 0 && holds(k - 1) {
        k -= 1;
    }
    let w = origin.saturating_sub(i128::from(k) << 64);
    let ww = if w < 0 {
        0
    } else {
        mul_shr(w as u128, w as u128, 64)
    };
    (k, w, ww)
}

/// Step events at a fixed rate (the ЭМ-907's direct arcs): event `j` at
/// tick `Q(j·TICK/RATE)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FixedRate {
    tick_hz: u32,
    rate_hz: u32,
}

impl FixedRate {
    /// Events at `rate_hz` on a clock of `tick` (both non-zero).
    pub const fn new(tick: TickRate, rate_hz: u32) -> FixedRate {
        FixedRate {
            tick_hz: tick.hz,
            rate_hz: if rate_hz == 0 { 1 } else { rate_hz },
        }
    }

    /// The tick of event `j` (1-based): `Q(j·TICK/RATE)`.
    ///
    /// ```
    /// use core_nostd::step::{FixedRate, TickRate};
    /// let r = FixedRate::new(TickRate::TIMER, 3);
    /// assert_eq!(r.tick(1), 333_333);
    /// assert_eq!(r.tick(2), 666_667); // 666 666.67 rounds up
    /// let half = FixedRate::new(TickRate::new(1).unwrap(), 2);
    /// assert_eq!(half.tick(1), 1); // a tie, away from zero
    /// ```
    pub const fn tick(&self, j: u32) -> u64 {
        let num = 2 * j as u64 * self.tick_hz as u64 + self.rate_hz as u64;
        // rate_hz ≥ 1 by construction.
        match num.checked_div(2 * self.rate_hz as u64) {
            Some(t) => t,
            None => 0,
        }
    }
}

/// What `SYNC` reports: the step events since the previous `SYNC` or `ZERO`,
/// their `TSEQ`, and the length of the last run.
#[derive(Clone, Copy, Debug)]
pub struct Record {
    events: u64,
    crc: Crc32,
    /// `crc` before the last event, for [`Record::forget_last`].
    before: Crc32,
    /// The tick of the previous event of the current run.
    last: u64,
    /// Ticks of the last run that ended.
    run_ticks: u64,
}

impl Default for Record {
    fn default() -> Self {
        Self::new()
    }
}

impl Record {
    /// Nothing recorded.
    pub const fn new() -> Record {
        Record {
            events: 0,
            crc: Crc32::new(),
            before: Crc32::new(),
            last: 0,
            run_ticks: 0,
        }
    }

    /// Adds one event at `tick` of the current run.
    #[inline(always)]
    pub fn event(&mut self, event: StepEvent, tick: u64) {
        // Deltas of 2³² ticks or more are recorded modulo 2³².
        let delta = tick.wrapping_sub(self.last) as u32;
        self.last = tick;
        self.events += 1;
        self.before = self.crc;
        self.crc.push_u8_u32_le(event.bits(), delta);
    }

    /// Takes back the last event added: it was handed out but never
    /// issued (a reset came while it waited for its tick). Called at most
    /// once after an event; with nothing recorded it does nothing.
    ///
    /// ```
    /// use core_nostd::impulse::Impulses;
    /// use core_nostd::interleave::{ImpulsePoint, LinearBlock};
    /// use core_nostd::step::Record;
    /// let p = |x, z| ImpulsePoint { x: Impulses(x), z: Impulses(z) };
    /// let e: Vec<_> = LinearBlock::new(p(0, 0), p(2, -1)).unwrap().events().collect();
    /// let (mut one, mut two) = (Record::new(), Record::new());
    /// one.event(e[0], 10);
    /// two.event(e[0], 10);
    /// two.event(e[1], 25);
    /// assert_ne!(two.tseq(), one.tseq());
    /// two.forget_last();
    /// assert_eq!((two.events(), two.tseq()), (one.events(), one.tseq()));
    /// ```
    pub fn forget_last(&mut self) {
        if self.events > 0 {
            self.events -= 1;
            self.crc = self.before;
        }
    }

    /// The record of `events` events whose CRC ended in `crc`, the last
    /// run that ended `run_ticks` long; the next event starts a new run.
    /// What a step interrupt issued, kept apart from what was handed out
    /// ahead of it.
    pub const fn restore(events: u64, crc: Crc32, run_ticks: u64) -> Record {
        Record {
            events,
            crc,
            before: crc,
            last: 0,
            run_ticks,
        }
    }

    /// The CRC's state after the last event (what [`Record::restore`]
    /// takes).
    #[inline(always)]
    pub const fn crc(&self) -> Crc32 {
        self.crc
    }

    /// A run ended after `ticks`; the next event starts a new run.
    pub fn run_end(&mut self, ticks: u64) {
        self.last = 0;
        self.run_ticks = ticks;
    }

    /// Step events recorded.
    pub const fn events(&self) -> u64 {
        self.events
    }

    /// `TSEQ`.
    pub fn tseq(&self) -> u32 {
        self.crc.finish()
    }

    /// Ticks of the last run that ended (0 if none).
    pub const fn run_ticks(&self) -> u64 {
        self.run_ticks
    }
}

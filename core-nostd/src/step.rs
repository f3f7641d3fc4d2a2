//! Step events at their ticks: the timed generator a timer interrupt pulls
//! (`docs/motion.md`, SPEC §10).
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
//! 128-bit addition: `T_i = T_1 + (i − 1)·B`. In the ramps the time is a
//! square root, which the generator never takes per event: with `u = v/a`
//! the virtual time since the ramp's speed would have been zero,
//! `X = u² = u_entry² + 2s/a` grows by a constant per event, and event `i`
//! is before the half tick `k + ½` exactly when `X_i < z_k²`,
//! `z_k = k + ½ − T_ramp + u_entry`. Moving `k` by one changes `z_k²` by
//! `2z_k + 1`: additions again. The generator predicts the next tick from
//! the last interval and corrects it by single ticks; when that would take
//! more than [`MAX_WALK`] steps (the first events of a ramp from rest) it
//! takes the square root once, so no event costs more than one root.
//! The deceleration is the same with `w_k = T_stop − k − ½` counting down.
//!
//! Errors: every time is within 2⁻⁶⁰ tick of the exact value the profile
//! defines, apart from the profile's own rounding (see [`crate::plan`]).

use crate::crc32::Crc32;
use crate::interleave::{LinearBlock, StepEvent, StepEvents};
use crate::wide::{mul_shr, sqrt_shl};

/// One tick in Q64.64.
pub(crate) const ONE: u128 = 1 << 64;
/// Half a tick in Q64.64.
pub(crate) const HALF: u128 = 1 << 63;
/// A time this close below a half tick is taken as the tie and rounds up:
/// 2⁻³⁶ tick. Exact ties occur (a cruise at a round feed along an axis), the
/// formats carry far less error than this (about 2⁻⁵⁰ tick), and the
/// reference decides ties by the same rule (`docs/motion.md`).
pub(crate) const TIE: u128 = 1 << 28;

/// Single-tick corrections after a prediction before the generator takes a
/// square root instead.
pub const MAX_WALK: u32 = 4;

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
        TimedEvents {
            steps: self.events.events(),
            index: 0,
            block: *self,
            state: State::Start,
            tick: 0,
            end: self.end_tick(),
        }
    }
}

/// The generator's position inside the current phase.
#[derive(Clone, Copy, Debug)]
enum State {
    /// No event yet in this phase: the next one is placed directly.
    Start,
    /// Accelerating: `x` of the last event, the tick `k` found for it, its
    /// `z_k` (positive) and `⌊z_k²⌋`, and the last interval in ticks.
    Accel {
        x: u128,
        z: u128,
        zz: u128,
        gap: u64,
    },
    /// Cruising: the next event's time plus half a tick.
    Cruise { t: u128 },
    /// Decelerating: `y` of the last event, `w_k` for its tick, `⌊w_k²⌋`
    /// (meaningful while `w ≥ 0`), the last interval.
    Decel {
        y: u128,
        w: i128,
        ww: u128,
        gap: u64,
    },
}

/// The timed step events of a [`TimedBlock`].
#[derive(Clone, Debug)]
pub struct TimedEvents {
    steps: StepEvents,
    /// Events issued so far.
    index: u32,
    block: TimedBlock,
    state: State,
    /// The tick of the last event.
    tick: u64,
    /// The block's end, whole ticks.
    end: u64,
}

/// Which phase event `i` (1-based) belongs to.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phase {
    Accel,
    Cruise,
    Decel,
}

impl Iterator for TimedEvents {
    type Item = (StepEvent, u64);

    #[inline]
    fn next(&mut self) -> Option<(StepEvent, u64)> {
        let event = self.steps.next()?;
        self.index += 1;
        let i = self.index;
        let b = &self.block;
        let phase = if i <= b.accel_events {
            Phase::Accel
        } else if i <= b.cruise_end {
            Phase::Cruise
        } else {
            Phase::Decel
        };
        // A new phase starts from its own first event.
        let first = !matches!(
            (phase, self.state),
            (Phase::Accel, State::Accel { .. })
                | (Phase::Cruise, State::Cruise { .. })
                | (Phase::Decel, State::Decel { .. })
        );
        let tick = match phase {
            Phase::Cruise => {
                let t = if first {
                    b.cruise.first
                } else if let State::Cruise { t } = self.state {
                    t.saturating_add(b.cruise.per_event)
                } else {
                    b.cruise.first
                };
                self.state = State::Cruise { t };
                (t >> 64) as u64
            }
            Phase::Accel => self.accel(first),
            Phase::Decel => self.decel(first),
        };
        // A chord's last boundary may lie up to half a grid unit beyond its
        // rounded end: that event happens at the end.
        self.tick = tick.min(self.end);
        Some((event, self.tick))
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

impl TimedEvents {
    /// The tick of the next accelerating event: the smallest `k` with
    /// `x < z_k²`.
    fn accel(&mut self, first: bool) -> u64 {
        let ramp = self.block.accel;
        let (x, z, zz, gap) = match self.state {
            State::Accel { x, z, zz, gap } if !first => {
                (x.saturating_add(ramp.per_event), z, zz, gap)
            }
            _ => (ramp.first, 0, 0, 0),
        };
        let found = if first {
            None
        } else {
            accel_walk(x, self.tick, z, zz, gap)
        };
        let (k, z, zz) = match found {
            Some(v) => v,
            None => accel_direct(x, ramp.origin),
        };
        let gap = k.saturating_sub(self.tick);
        self.state = State::Accel { x, z, zz, gap };
        k
    }

    /// The tick of the next decelerating event: the smallest `k` with
    /// `w_k < 0` or `y > w_k²`.
    fn decel(&mut self, first: bool) -> u64 {
        let ramp = self.block.decel;
        let (y, w, ww, gap) = match self.state {
            State::Decel { y, w, ww, gap } if !first => {
                (y.saturating_sub(ramp.per_event), w, ww, gap)
            }
            _ => (ramp.first, 0, 0, 0),
        };
        let found = if first {
            None
        } else {
            decel_walk(y, self.tick, w, ww, gap)
        };
        let (k, w, ww) = match found {
            Some(v) => v,
            None => decel_direct(y, ramp.origin),
        };
        let gap = k.saturating_sub(self.tick);
        self.state = State::Decel { y, w, ww, gap };
        k
    }
}

/// From the last event's tick `k` (with `z`, `zz`), the next one's by the
/// last interval and single-tick corrections; `None` when that needs more
/// than [`MAX_WALK`] corrections.
#[inline]
fn accel_walk(x: u128, k: u64, z: u128, zz: u128, gap: u64) -> Option<(u64, u128, u128)> {
    if x < zz {
        return Some((k, z, zz));
    }
    // Jump by the last interval: z_{k+j}² = z_k² + 2j·z_k + j².
    let j = gap.clamp(1, 1 << 30);
    let j128 = u128::from(j);
    let mut zz = zz
        .checked_add((2 * j128).checked_mul(z)?)?
        .checked_add((j128 * j128) << 64)?;
    let mut z = z.checked_add(j128 << 64)?;
    let mut k = k + j;
    let mut walk = 0;
    if x < zz {
        // Back while the previous tick still satisfies x < z².
        // z_{k−1}² = z_k² − 2z_k + 1.
        while k > 1 && z > ONE {
            let prev = zz.checked_sub(2 * z - ONE)?;
            if x >= prev {
                break;
            }
            walk += 1;
            if walk > MAX_WALK {
                return None;
            }
            (k, z, zz) = (k - 1, z - ONE, prev);
        }
        // Never before the last event's tick (times do not decrease).
        Some((k, z, zz))
    } else {
        while x >= zz {
            walk += 1;
            if walk > MAX_WALK {
                return None;
            }
            zz = zz.checked_add((2 * z).checked_add(ONE)?)?;
            z = z.checked_add(ONE)?;
            k += 1;
        }
        Some((k, z, zz))
    }
}

#[cfg(test)]
pub(crate) static DIRECT: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

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

/// The deceleration's counterpart of [`accel_walk`]: `w_{k+1} = w_k − 1`,
/// `w_{k+1}² = w_k² − 2w_k + 1`; satisfied when `w < 0` or `y > w²`.
#[inline]
fn decel_walk(y: u128, k: u64, w: i128, ww: u128, gap: u64) -> Option<(u64, i128, u128)> {
    let holds = |w: i128, ww: u128| w < 0 || y > ww;
    if holds(w, ww) {
        return Some((k, w, ww));
    }
    // w ≥ 0 here. Jump by the last interval while w stays non-negative.
    let j = gap.clamp(1, 1 << 30);
    let j128 = i128::from(j);
    let wj = w.checked_sub(j128 << 64)?;
    if wj < 0 {
        return None;
    }
    // (w − j)² = w² − 2j·w + j², all terms non-negative.
    let two_jw = (2 * j as u128).checked_mul(w as u128)?;
    let mut ww = ww
        .checked_add((u128::from(j) * u128::from(j)) << 64)?
        .checked_sub(two_jw)?;
    let mut w = wj;
    let mut k = k + j;
    let mut walk = 0;
    if holds(w, ww) {
        // Back while the previous tick still holds: w_{k−1}² = w² + 2w + 1.
        loop {
            let wp = w + ONE as i128;
            let wwp = ww.checked_add(2 * w as u128 + ONE)?;
            if !holds(wp, wwp) {
                break;
            }
            walk += 1;
            if walk > MAX_WALK {
                return None;
            }
            (k, w, ww) = (k - 1, wp, wwp);
        }
        Some((k, w, ww))
    } else {
        while !holds(w, ww) {
            walk += 1;
            if walk > MAX_WALK {
                return None;
            }
            k += 1;
            if w < ONE as i128 {
                // The next w is negative: that tick holds.
                return Some((k, w - ONE as i128, 0));
            }
            ww = ww.checked_sub(2 * w as u128 - ONE)?;
            w -= ONE as i128;
        }
        Some((k, w, ww))
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
            last: 0,
            run_ticks: 0,
        }
    }

    /// Adds one event at `tick` of the current run.
    #[inline]
    pub fn event(&mut self, event: StepEvent, tick: u64) {
        // Deltas of 2³² ticks or more are recorded modulo 2³².
        let delta = tick.wrapping_sub(self.last) as u32;
        self.last = tick;
        self.events += 1;
        self.crc.push(event.bits());
        self.crc.update(&delta.to_le_bytes());
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

//! The simulated spindle and its encoder (`docs/threading.md`): a speed
//! with ripple and load dips, the encoder's counts at any time, and the
//! step events of synchronised passes placed in time by those counts.
//!
//! The speed is `ω(t) = ω₀·(1 + r·sin(2π·f·t))` less the dips, `f` the
//! nominal revolutions per second (a once-per-turn ripple, as a belt or an
//! unbalanced chuck gives), each dip taking a fraction `d` of `ω₀` from its
//! start for its length. The angle is that speed integrated in closed form,
//! so no error accumulates over any run; the counts are
//! `⌊angle · N⌋`, an index at every multiple of `N`.

use core_nostd::interleave::StepEvent;
use core_nostd::sync::{reference_count, SyncPass};

/// A load dip: the speed falls by `fraction` of the nominal speed from
/// `start` (s) for `length` (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dip {
    /// When it begins, seconds from power-on.
    pub start: f64,
    /// How long it lasts, seconds.
    pub length: f64,
    /// The part of the nominal speed it takes (0.1 = 10 %).
    pub fraction: f64,
}

/// A spindle turning forward with its encoder.
#[derive(Clone, Debug, PartialEq)]
pub struct Spindle {
    /// The nominal speed, revolutions per minute (above 0).
    pub rpm: f64,
    /// The ripple's amplitude, a fraction of the nominal speed (0.05 = ±5 %).
    pub ripple: f64,
    /// Load dips.
    pub dips: Vec<Dip>,
    /// Encoder counts per revolution.
    pub cpr: u32,
}

impl Spindle {
    /// Revolutions turned since power-on at time `t` (s).
    pub fn turns(&self, t: f64) -> f64 {
        let f = self.rpm / 60.0;
        let two_pi = std::f64::consts::TAU;
        // ∫ f·(1 + r·sin 2πft) dt = f·t + r·(1 − cos 2πft)/2π.
        let mut turns = f * t + self.ripple * (1.0 - (two_pi * f * t).cos()) / two_pi;
        for d in &self.dips {
            let overlap = (t.min(d.start + d.length) - d.start).max(0.0);
            turns -= f * d.fraction * overlap;
        }
        turns
    }

    /// The encoder's counts since power-on at time `t`.
    pub fn counts(&self, t: f64) -> i64 {
        (self.turns(t) * f64::from(self.cpr)).floor() as i64
    }

    /// The speed measured over the last `window` seconds before `t`, rev/min,
    /// from the counts as a board measures it.
    pub fn measured_rpm(&self, t: f64, window: f64) -> f64 {
        let n = (self.counts(t) - self.counts((t - window).max(0.0))) as f64;
        n / f64::from(self.cpr) / window.min(t).max(f64::MIN_POSITIVE) * 60.0
    }

    /// The first tick (of `tick_hz` a second) at or after `from` at which
    /// the counts have reached `target`; the speed stays above 0, so it
    /// exists.
    pub fn tick_of_count(&self, target: i64, from: u64, tick_hz: f64) -> u64 {
        let reached = |k: u64| self.counts(k as f64 / tick_hz) >= target;
        if reached(from) {
            return from;
        }
        let mut step = 1u64;
        let mut lo = from;
        while !reached(from + step) {
            lo = from + step;
            step *= 2;
        }
        let mut hi = from + step;
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if reached(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }
}

/// One step event of a synchronised pass as the spindle placed it: the
/// columns of `host-sim run --events`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PassEvent {
    /// The step clock's tick.
    pub tick: u64,
    /// The encoder's counts since power-on.
    pub counts: i64,
    /// The pass's count, `counts − reference`.
    pub count: i64,
    /// The X and Z registers after the event.
    pub x: i64,
    /// See `x`.
    pub z: i64,
    /// The event's STEP and DIR bits.
    pub event: StepEvent,
}

/// A pass run against the spindle: ready at tick `ready`, it waits for its
/// reference (an index at count 0, plus `start` counts) and issues each
/// event at the first tick its count has been reached. Returns the
/// reference and the events.
pub fn run_pass(
    spindle: &Spindle,
    pass: &SyncPass,
    start: u32,
    lead_in: u32,
    ready: u64,
    tick_hz: f64,
) -> (i64, Vec<PassEvent>) {
    let now = spindle.counts(ready as f64 / tick_hz);
    let reference = reference_count(now, 0, spindle.cpr, start, lead_in);
    let (mut x, mut z) = pass.start_registers();
    let mut tick = ready;
    let events = pass
        .events()
        .map(|(c, e)| {
            tick = spindle.tick_of_count(reference + c, tick, tick_hz);
            let (dx, dz) = e.moves();
            x += i64::from(dx);
            z += i64::from(dz);
            PassEvent {
                tick,
                counts: spindle.counts(tick as f64 / tick_hz),
                count: c,
                x,
                z,
                event: e,
            }
        })
        .collect();
    (reference, events)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_angle_is_the_speed_integrated() {
        let s = Spindle {
            rpm: 600.0,
            ripple: 0.05,
            dips: vec![Dip {
                start: 1.0,
                length: 0.5,
                fraction: 0.2,
            }],
            cpr: 4096,
        };
        // Whole turns of the ripple average out: 10 rev/s.
        assert!((s.turns(0.9) - 9.0).abs() < 1e-9);
        // The dip takes 0.2·10·0.5 = 1 turn.
        assert!((s.turns(2.0) - 19.0).abs() < 1e-9);
        assert_eq!(s.counts(2.0), 19 * 4096);
        let m = s.measured_rpm(0.9, 0.1);
        assert!((m - 600.0).abs() < 600.0 * 0.051, "{m}");
        let t = s.tick_of_count(4096 * 5, 0, 50_000.0);
        assert!(s.counts(t as f64 / 50_000.0) >= 4096 * 5);
        assert!(s.counts((t - 1) as f64 / 50_000.0) < 4096 * 5);
    }
}

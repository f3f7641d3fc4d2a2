//! Motion locked to the spindle (`docs/threading.md`): a synchronised pass
//! whose position is an exact function of the encoder counts, and its step
//! events, each at the count where a register changes.
//!
//! The progress along the lead axis is `s(c) = num(c) / den` with
//! `den = 8·K·N·C` (`K` the lead, `N` the counts per revolution, `C` the
//! lead-in, all integers), so that every piece of `docs/threading.md` §1 has
//! an integer numerator:
//!
//! | piece | `num(c)` |
//! |---|---|
//! | lead-in | `K²·(2c + C)²` |
//! | locked | `8·K²·C·c` |
//! | lead-out | `8·K·N·C·D − (2·D·N + K·C − 2·K·c)²` |
//!
//! An axis crosses its next rounding boundary `B` when
//! `|Δa|·s(c)/D ≥ σ·(B − a0)` (`>` past a boundary on the side towards
//! zero, as `Q` rounds ties away from zero). The count of the next event
//! is solved for piece by piece, in closed form: while locked it is a
//! quotient that follows by additions from one boundary to the next (`R`,
//! twice the distance to the boundary, grows by `2h`); in the lead-in a
//! ceiling square root, in the lead-out a floor square root, of exact
//! integers (256-bit products where they need them). The tests check every
//! event against the definition. The ranges ([`MAX_LEAD`], [`MAX_CPR`],
//! [`MAX_LEAD_IN`], [`MAX_TRAVEL`]) keep every intermediate in its type.

use crate::impulse::ImpulsePrice;
use crate::interleave::StepEvent;
use crate::length::{div_round_half_away, Length};
use crate::plan::Limits;
use crate::wide::{checked_divrem_i128, isqrt, udiv, U256};

/// The longest lead: 2³⁰ × 10⁻⁷ mm (107.37 mm per revolution).
pub const MAX_LEAD: i64 = 1 << 30;
/// The most counts per revolution an encoder may have.
pub const MAX_CPR: u32 = 1 << 16;
/// The longest lead-in, in counts.
pub const MAX_LEAD_IN: u32 = 1 << 30;
/// The longest travel of a pass along its lead axis: 2³⁵ × 10⁻⁷ mm
/// (3 435.97 mm).
pub const MAX_TRAVEL: i64 = 1 << 35;

/// Why a synchronised pass is refused before it starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SyncError {
    /// The pass does not travel along its lead axis (`D = 0`).
    NoTravel,
    /// An axis would move more than one impulse per count while locked:
    /// the encoder is too coarse for this lead and this impulse.
    TooCoarse {
        /// `'X'` or `'Z'`.
        axis: char,
    },
    /// The pass is shorter than its lead-in and lead-out, `u·C`: the travel
    /// it needs along the lead axis, rounded up to 10⁻⁷ mm.
    TooShort {
        /// The travel needed.
        needed: Length,
    },
    /// A lead, an encoder, a lead-in or a travel beyond the ranges of this
    /// module, or a lead-in that is odd or below 2.
    Range,
}

/// One synchronised pass (`docs/threading.md` §1), checked: its events
/// follow without any check that could fail.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncPass {
    /// Start and end, ångström, X on the radius: `[x, z]`.
    from: [i64; 2],
    delta: [i64; 2],
    price: [i64; 2],
    lead: i64,
    cpr: i64,
    lead_in: i64,
    travel: i64,
}

impl SyncPass {
    /// A pass from `from` to `to` (`(x radius, z)`) at `lead` per revolution
    /// along the lead axis, with `cpr` counts per revolution and a lead-in of
    /// `lead_in` counts (even, at least 2).
    pub fn new(
        from: (Length, Length),
        to: (Length, Length),
        prices: (ImpulsePrice, ImpulsePrice),
        lead: Length,
        cpr: u32,
        lead_in: u32,
    ) -> Result<SyncPass, SyncError> {
        let from = [from.0.as_angstrom(), from.1.as_angstrom()];
        let to = [to.0.as_angstrom(), to.1.as_angstrom()];
        let delta = [to[0] - from[0], to[1] - from[1]];
        let price = [prices.0.as_angstrom(), prices.1.as_angstrom()];
        let lead = lead.as_angstrom();
        let travel = delta[0].abs().max(delta[1].abs());
        if lead <= 0
            || lead > MAX_LEAD
            || cpr == 0
            || cpr > MAX_CPR
            || !(2..=MAX_LEAD_IN).contains(&lead_in)
            || !lead_in.is_multiple_of(2)
            || travel > MAX_TRAVEL
        {
            return Err(SyncError::Range);
        }
        if travel == 0 {
            return Err(SyncError::NoTravel);
        }
        let (cpr, c) = (i64::from(cpr), i64::from(lead_in));
        // Locked, an axis moves u·|Δa|/D per count: less than h, or
        // K·|Δa| < h·N·D (at h exactly, an axis passing from −h/2 to h/2
        // in one count would go from −1 to 1: Q rounds ties away from 0).
        for (i, axis) in [(0, 'X'), (1, 'Z')] {
            let moved = i128::from(lead) * i128::from(delta[i & 1].abs());
            if moved >= i128::from(price[i & 1]) * i128::from(cpr) * i128::from(travel) {
                return Err(SyncError::TooCoarse { axis });
            }
        }
        // D ≥ u·C, or D·N ≥ K·C.
        let needed = i128::from(lead) * i128::from(c);
        if i128::from(travel) * i128::from(cpr) < needed {
            let mm = ceil_div(needed, i128::from(cpr));
            return Err(SyncError::TooShort {
                needed: i64::try_from(mm)
                    .ok()
                    .and_then(Length::from_angstrom)
                    .ok_or(SyncError::Range)?,
            });
        }
        Ok(SyncPass {
            from,
            delta,
            price,
            lead,
            cpr,
            lead_in: c,
            travel,
        })
    }

    /// The first count of the lead-in: the pass is at rest at its start up
    /// to `−C/2` and moves from the next count on.
    pub const fn first_count(&self) -> i64 {
        -self.lead_in / 2
    }

    /// The first count at which the pass is at its end, `⌈D·N/K + C/2⌉`.
    pub const fn last_count(&self) -> i64 {
        let n = 2 * self.travel as i128 * self.cpr as i128 + (self.lead * self.lead_in) as i128;
        ceil_div(n, 2 * self.lead as i128) as i64
    }

    /// The lead-in and the lead-out's length along the lead axis, `u·C/2`,
    /// rounded up to 10⁻⁷ mm.
    pub fn lead_in_length(&self) -> Length {
        let l = ceil_div(
            i128::from(self.lead) * i128::from(self.lead_in),
            2 * i128::from(self.cpr),
        );
        Length::from_angstrom(l as i64).unwrap_or(Length::ZERO)
    }

    /// `8·K·N·C`, the denominator of the progress.
    #[cfg(test)]
    fn den(&self) -> i128 {
        8 * i128::from(self.lead) * i128::from(self.cpr) * i128::from(self.lead_in)
    }

    /// The numerator of the progress `s(c)` over [`Self::den`], in
    /// `0 ..= D·den`.
    #[cfg(test)]
    fn num(&self, c: i64) -> i128 {
        let (k, n, cc, d) = (
            i128::from(self.lead),
            i128::from(self.cpr),
            i128::from(self.lead_in),
            i128::from(self.travel),
        );
        let c = i128::from(c);
        if 2 * c <= -cc {
            0
        } else if 2 * c <= cc {
            let t = k * (2 * c + cc);
            t * t
        } else if 2 * k * c <= 2 * d * n - k * cc {
            8 * k * cc * (k * c)
        } else if 2 * k * c < 2 * d * n + k * cc {
            let t = 2 * d * n + k * cc - 2 * k * c;
            8 * k * n * cc * d - t * t
        } else {
            8 * k * n * cc * d
        }
    }

    /// The registers at the start, `(Q(x0/hX), Q(z0/hZ))`.
    pub fn start_registers(&self) -> (i64, i64) {
        (
            div_round_half_away(self.from[0], self.price[0]),
            div_round_half_away(self.from[1], self.price[1]),
        )
    }

    /// The registers at the end, `(Q(x1/hX), Q(z1/hZ))`.
    pub fn end_registers(&self) -> (i64, i64) {
        (
            div_round_half_away(self.from[0] + self.delta[0], self.price[0]),
            div_round_half_away(self.from[1] + self.delta[1], self.price[1]),
        )
    }

    /// The direction of axis `i` towards the end, −1 or 1 (`i` is 0 or 1;
    /// the mask keeps the indexing free of a bounds check).
    const fn sigma(&self, i: usize) -> i64 {
        if self.delta[i & 1] < 0 {
            -1
        } else {
            1
        }
    }

    /// Whether the boundary axis `i` crosses to leave register `k` lies on
    /// the side towards zero (`σ·B < 0`): it is passed strictly, as `Q`
    /// rounds a tie away from zero.
    const fn strict(&self, i: usize, k: i64) -> bool {
        let sigma = self.sigma(i);
        (2 * k + sigma) * sigma < 0
    }

    /// `R = σ·(2B − 2a0)`, twice the distance from the start to the
    /// boundary `B = (2k + σ)·h/2` that axis `i` crosses to leave register
    /// `k` towards its end (`σ` its direction); at least 0.
    fn boundary(&self, i: usize, k: i64) -> i128 {
        let sigma = i128::from(self.sigma(i));
        sigma
            * ((2 * i128::from(k) + sigma) * i128::from(self.price[i & 1])
                - 2 * i128::from(self.from[i & 1]))
    }

    /// Whether axis `i`, at register `k`, has left it for the next one
    /// towards the end at count `c`: the definition, which the closed forms
    /// of [`SyncEvents::next_count`] are checked against.
    #[cfg(test)]
    fn crossed(&self, i: usize, k: i64, c: i64) -> bool {
        let r = self.boundary(i, k);
        // |Δa|·s/D ≥ σ(B − a0)  ⇔  2·|Δa|·num ≥ R·D·den.
        let lhs = U256::mul(
            2 * self.delta[i & 1].unsigned_abs() as u128,
            self.num(c) as u128,
        );
        let rhs = U256::mul(r as u128 * self.travel as u128, self.den() as u128);
        if self.strict(i, k) {
            lhs > rhs
        } else {
            lhs >= rhs
        }
    }

    /// The step events of the pass, in order of their counts.
    pub fn events(&self) -> SyncEvents {
        let (x, z) = self.start_registers();
        let (x1, z1) = self.end_registers();
        let (k, n, cc, d) = (
            i128::from(self.lead),
            i128::from(self.cpr),
            i128::from(self.lead_in),
            i128::from(self.travel),
        );
        let mut e = SyncEvents {
            pass: *self,
            reg: [x, z],
            end: [x1, z1],
            next: [i64::MAX; 2],
            line: [(0, 0); 2],
            line_step: [(0, 0); 2],
            line_den: [1; 2],
            // Locked from C/2 to ⌊(2DN − KC)/2K⌋ (empty when D·N = K·C
            // leaves less than a count).
            lock: (
                self.lead_in / 2,
                checked_divrem_i128(2 * d * n - k * cc, 2 * k).map_or(0, |(q, _)| q) as i64,
            ),
        };
        for i in 0..2 {
            // The locked line crosses the boundary of register k where
            // 2·|Δa|·K·c ≥ R·D·N: R grows by 2h at each step, so the
            // quotient and remainder follow by additions.
            let den = 2 * i128::from(self.delta[i & 1].abs()) * k;
            if den > 0 {
                let r0 = self.boundary(i, e.reg[i & 1]) * d * n;
                let step = 2 * i128::from(self.price[i & 1]) * d * n;
                e.line_den[i & 1] = den;
                // R ≥ 0 and den > 0: plain division floors.
                let divrem = |v: i128| checked_divrem_i128(v, den).unwrap_or((0, 0));
                e.line[i & 1] = divrem(r0);
                e.line_step[i & 1] = divrem(step);
            }
        }
        let c0 = self.first_count();
        for i in 0..2 {
            e.next[i & 1] = e.next_count(i, c0);
        }
        e
    }
}

/// The step events of a [`SyncPass`]: `(count, event)`, counts ascending.
#[derive(Clone, Debug)]
pub struct SyncEvents {
    pass: SyncPass,
    reg: [i64; 2],
    end: [i64; 2],
    /// The count of each axis' next step, `i64::MAX` when it is at its end.
    next: [i64; 2],
    /// Per axis, `⌊R·D·N / (2·|Δa|·K)⌋` and its remainder for the current
    /// register: where the locked line leaves it.
    line: [(i128, i128); 2],
    /// What a step adds to [`Self::line`]: `2h·D·N` divided likewise.
    line_step: [(i128, i128); 2],
    /// `2·|Δa|·K` (1 for an axis that does not move).
    line_den: [i128; 2],
    /// The first and last counts of the locked piece.
    lock: (i64, i64),
}

impl SyncEvents {
    /// The least count after `after` at which axis `i` leaves its register,
    /// or `i64::MAX` when it is at its end.
    fn next_count(&self, i: usize, after: i64) -> i64 {
        if self.reg[i & 1] == self.end[i & 1] {
            return i64::MAX;
        }
        let k = self.reg[i & 1];
        let p = &self.pass;
        let strict = p.strict(i, k);
        // Locked, the pass is on the line, whose crossings follow by
        // additions: from a locked count, a crossing on the line is it.
        let (q, rem) = self.line[i & 1];
        let line = q as i64 + i64::from(rem > 0 || strict);
        if after >= self.lock.0 && line <= self.lock.1 {
            return line.max(after + 1);
        }
        let (kk, n, cc, d) = (
            i128::from(p.lead),
            i128::from(p.cpr),
            i128::from(p.lead_in),
            i128::from(p.travel),
        );
        let da = i128::from(p.delta[i & 1].abs());
        let r = p.boundary(i, k);
        // In the lead-in (m = c + C/2, num = 4·K²·m²) the axis has crossed
        // when |Δa|·K·m² ≥ R·D·N·C: the least m is a ceiling square root.
        if after < self.lock.0 {
            let x = (r * d * n * cc) as u128;
            let y = (da * kk) as u128;
            let (fl, rem) = udiv(x, y).unwrap_or((0, 0));
            // m² ≥ X: m² ≥ ⌈X⌉; m² > X: m² ≥ ⌊X⌋ + 1.
            let t = fl + u128::from(rem > 0 || strict);
            let m = ceil_sqrt(t);
            let c = m as i64 - self.lock.0;
            if c <= self.lock.0 {
                return c.max(after + 1);
            }
        }
        // Past the lead-in, a crossing on the line is it.
        if line <= self.lock.1 {
            return line.max(after + 1);
        }
        // In the lead-out (w = 2DN + KC − 2Kc, num = 8KNCD − w²) it has
        // crossed when w² ≤ V = 4·K·N·C·D·(2|Δa| − R)/|Δa| (w² < V past a
        // strict boundary): the greatest w is a square root.
        let prod = U256::mul((4 * kk * n * cc * d) as u128, (2 * da - r) as u128);
        let v = prod.div(da as u128);
        let exact = U256::mul(v, da as u128) == prod;
        // w² < V: w² ≤ ⌈V⌉ − 1, which is ⌊V⌋ − 1 when V is whole.
        let v = if strict && exact {
            v.saturating_sub(1)
        } else {
            v
        };
        let w = i128::from(isqrt(v));
        let top = 2 * d * n + kk * cc - w;
        let c = ceil_div(top, 2 * kk) as i64;
        // (`clamp` would check its bounds; the crossing lies between them.)
        c.max(after + 1).min(p.last_count().max(after + 1))
    }

    /// The registers after the events so far, `(X, Z)`.
    pub const fn registers(&self) -> (i64, i64) {
        (self.reg[0], self.reg[1])
    }
}

impl Iterator for SyncEvents {
    type Item = (i64, StepEvent);

    fn next(&mut self) -> Option<(i64, StepEvent)> {
        let c = self.next[0].min(self.next[1]);
        if c == i64::MAX {
            return None;
        }
        let mut bits = 0;
        for (i, step, neg) in [
            (0, StepEvent::X_STEP, StepEvent::X_NEG),
            (1, StepEvent::Z_STEP, StepEvent::Z_NEG),
        ] {
            if self.next[i & 1] == c {
                let sigma = self.pass.sigma(i);
                self.reg[i & 1] += sigma;
                let (dq, dr) = self.line_step[i & 1];
                let (q, r) = &mut self.line[i & 1];
                *q += dq;
                *r += dr;
                if *r >= self.line_den[i & 1] {
                    *r -= self.line_den[i & 1];
                    *q += 1;
                }
                bits |= step | if sigma < 0 { neg } else { 0 };
                self.next[i & 1] = self.next_count(i, c);
            }
        }
        Some((c, StepEvent::from_bits(bits)))
    }
}

/// The reference of a pass (`docs/threading.md` §1): the count, since the
/// encoder started, that is the pass's `c = 0`. It is an index (`index`,
/// the count at which one was seen, and every `cpr` counts from it) plus
/// the start angle in counts, `start`, taken as the first such count whose
/// lead-in begins after `now`, so that the pass waits at rest for it. With
/// the same `index` and `start`, every pass's reference is the same angle
/// of the spindle, whatever `now` and the lead-in are.
pub fn reference_count(now: i64, index: i64, cpr: u32, start: u32, lead_in: u32) -> i64 {
    let n = i64::from(cpr.max(1));
    let offset = i64::from(start) % n;
    // The least r = index + offset + j·N with r − C/2 > now.
    let first = index + offset;
    let need = now + i64::from(lead_in / 2) + 1;
    if first >= need {
        // Never before an index that has been seen.
        return first;
    }
    let j = (need - first + n - 1) / n;
    first + j * n
}

/// The start angle of a pass in counts, `Q(θ·N/360°)` modulo `N`, for an
/// angle in thousandths of a degree.
pub fn start_counts(milli_degrees: u32, cpr: u32) -> u32 {
    let n = u64::from(cpr.max(1));
    let a = u64::from(milli_degrees) % 360_000;
    // Q half away from zero of a non-negative value: ⌊(2aN + 360 000) / 720 000⌋.
    ((2 * a * n + 360_000) / 720_000 % n) as u32
}

/// The highest whole speed (rev/min) at which the spindle may turn for a
/// pass from `from` to `to` (`(x radius, z)`) at `lead` per revolution
/// (`docs/threading.md` §2): locked, no axis beyond its rate
/// (`VMAX_a·D/(K·|Δa|)`) nor beyond the drive's events per second
/// (`60·rate·h_a·D/(K·|Δa|)`), and the lead-in and lead-out within the
/// travel at the lead axis' acceleration (the least `AMAX_a·D/|Δa|`, whole
/// mm/s²). 0 when the pass does not travel along its lead axis.
pub fn highest_rpm(
    from: (Length, Length),
    to: (Length, Length),
    lead: Length,
    prices: (ImpulsePrice, ImpulsePrice),
    cpr: u32,
    limits: &Limits,
    rate_hz: u32,
) -> u32 {
    let delta = [
        (to.0.as_angstrom() - from.0.as_angstrom()).unsigned_abs(),
        (to.1.as_angstrom() - from.1.as_angstrom()).unsigned_abs(),
    ];
    let d = delta[0].max(delta[1]);
    let k = lead.as_angstrom().max(0).unsigned_abs();
    if d == 0 || k == 0 {
        return 0;
    }
    let price = [
        prices.0.as_angstrom().unsigned_abs(),
        prices.1.as_angstrom().unsigned_abs(),
    ];
    let mut best = u128::from(u32::MAX);
    let mut accel = u128::MAX;
    for a in 0..2 {
        if delta[a & 1] == 0 {
            continue;
        }
        let kd = u128::from(k) * u128::from(delta[a & 1]);
        let rate = u128::from(limits.rate(a).as_angstrom().unsigned_abs());
        let by_rate = udiv(rate * u128::from(d), kd).map_or(0, |(q, _)| q);
        let steps = udiv(
            60 * u128::from(rate_hz) * u128::from(price[a & 1]) * u128::from(d),
            kd,
        )
        .map_or(0, |(q, _)| q);
        best = best.min(by_rate).min(steps);
        let amax = u128::from(limits.accel(a).as_angstrom().unsigned_abs());
        accel = accel.min(
            udiv(
                amax * u128::from(d),
                u128::from(delta[a & 1]) * crate::length::ANGSTROM_PER_MM as u128,
            )
            .map_or(0, |(q, _)| q),
        );
    }
    let accel = u32::try_from(accel).unwrap_or(u32::MAX);
    let travel = Length::from_angstrom(d as i64).unwrap_or(Length::ZERO);
    let fits = max_rpm(lead, travel, cpr, accel);
    (best as u32).min(fits)
}

/// `⌈n/d⌉` for `n ≥ 0` and `d > 0` (0 for `d = 0`, which no caller
/// passes: a division that cannot panic).
const fn ceil_div(n: i128, d: i128) -> i128 {
    match checked_divrem_i128(n + d - 1, d) {
        Some((q, _)) => q,
        None => 0,
    }
}

/// The least `m` with `m² ≥ t`.
fn ceil_sqrt(t: u128) -> u64 {
    let s = isqrt(t);
    s + u64::from(u128::from(s) * u128::from(s) < t)
}

/// The lead-in of `docs/threading.md` §2: the least even count
/// `C ≥ K·n²·N / (3600·a)`, at least 2, for a lead `K`, a speed of `rpm`
/// revolutions per minute, `cpr` counts per revolution and a path
/// acceleration of `accel` mm/s²; `None` beyond [`MAX_LEAD_IN`] or for an
/// acceleration of 0.
pub fn lead_in_counts(lead: Length, rpm: u32, cpr: u32, accel: u32) -> Option<u32> {
    if accel == 0 || lead.as_angstrom() <= 0 {
        return None;
    }
    // K in 10⁻⁷ mm: C ≥ K·n²·N / (3600·a·10⁷).
    let num = lead.as_angstrom() as u128 * u128::from(rpm) * u128::from(rpm) * u128::from(cpr);
    let den = 3600 * u128::from(accel) * crate::length::ANGSTROM_PER_MM as u128;
    let (q, r) = udiv(num, den)?;
    let c = q + u128::from(r != 0);
    let c = c.max(2);
    let c = c + c % 2;
    u32::try_from(c).ok().filter(|&c| c <= MAX_LEAD_IN)
}

/// The highest whole speed (rev/min) whose lead-in fits a pass of `travel`
/// along its lead axis (`u·C ≤ D`, `docs/threading.md` §2), or 0 when none
/// does.
pub fn max_rpm(lead: Length, travel: Length, cpr: u32, accel: u32) -> u32 {
    let fits = |n: u32| match lead_in_counts(lead, n, cpr, accel) {
        Some(c) => {
            i128::from(lead.as_angstrom()) * i128::from(c)
                <= i128::from(travel.as_angstrom()) * i128::from(cpr)
        }
        None => false,
    };
    if !fits(0) {
        return 0;
    }
    let (mut lo, mut hi) = (0u32, 1u32 << 20);
    if fits(hi) {
        return hi;
    }
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    fn mm(s: &str) -> Length {
        Length::from_mm_str(s).unwrap()
    }

    fn h(s: &str) -> ImpulsePrice {
        ImpulsePrice::from_length(mm(s)).unwrap()
    }

    /// The events with the registers after each: `(count, X, Z)`.
    fn run(p: &SyncPass) -> Vec<(i64, i64, i64)> {
        let (mut x, mut z) = p.start_registers();
        p.events()
            .map(|(c, e)| {
                let (dx, dz) = e.moves();
                x += i64::from(dx);
                z += i64::from(dz);
                (c, x, z)
            })
            .collect()
    }

    #[test]
    fn locked_z_is_the_count_times_the_lead() {
        // Z from 2 to −20 at 1.5 mm per revolution, 4096 counts, h 0.01.
        let p = SyncPass::new(
            (mm("10"), mm("2")),
            (mm("10"), mm("-20")),
            (h("0.005"), h("0.01")),
            mm("1.5"),
            4096,
            2000,
        )
        .unwrap();
        let ev = run(&p);
        assert_eq!(ev.len(), 2200);
        assert_eq!(ev.last().map(|e| e.2), Some(-2000));
        // Locked from C/2 = 1000 to D·N/K − C/2 = 22·4096/1.5 − 1000.
        let lock = 1000..=59074;
        let mut locked = 0;
        for &(c, x, z) in &ev {
            assert_eq!(x, 2000);
            if lock.contains(&c) {
                // z = 2 − c·1.5/4096 mm, in 10⁻⁷ mm times 4096, over 0.01 mm.
                let want = div_round_half_away(20_000_000 * 4096 - c * 15_000_000, 4096 * 100_000);
                assert_eq!(z, want, "c={c}");
                locked += 1;
            }
        }
        assert!(locked > 1900, "{locked}");
    }

    #[test]
    fn counts_are_ascending_and_each_axis_steps_once_per_count() {
        let p = SyncPass::new(
            (mm("12"), mm("0")),
            (mm("10.5"), mm("-7.25")),
            (h("0.005"), h("0.01")),
            mm("2"),
            1000,
            400,
        )
        .unwrap();
        let ev: Vec<_> = p.events().collect();
        assert!(ev.windows(2).all(|w| w[0].0 < w[1].0));
        let xs = ev.iter().filter(|e| e.1.x_steps()).count();
        let zs = ev.iter().filter(|e| e.1.z_steps()).count();
        assert_eq!((xs, zs), (300, 725));
        assert!(ev.iter().all(|e| e.1.x_negative() == e.1.x_steps()));
    }

    /// Each event is at the least count where its axes cross, by the
    /// definition: crossed at its count, not at the count before.
    #[test]
    fn closed_forms_meet_the_definition() {
        let cases = [
            (
                (mm("10"), mm("2")),
                (mm("10"), mm("-20")),
                "1.5",
                4096,
                2000,
            ),
            (
                (mm("12"), mm("0")),
                (mm("10.5"), mm("-7.25")),
                "2",
                1000,
                400,
            ),
            (
                (mm("0.0025"), mm("-0.005")),
                (mm("3"), mm("0.005")),
                "0.75",
                360,
                6,
            ),
            (
                (mm("-1"), mm("1.000001")),
                (mm("1"), mm("-1.23")),
                "0.5",
                2048,
                5000,
            ),
        ];
        for (from, to, lead, cpr, c) in cases {
            let p = SyncPass::new(from, to, (h("0.005"), h("0.01")), mm(lead), cpr, c).unwrap();
            let (mut x, mut z) = p.start_registers();
            let mut checked = 0;
            for (count, e) in p.events() {
                for (i, k, steps) in [(0, x, e.x_steps()), (1, z, e.z_steps())] {
                    if steps {
                        assert!(p.crossed(i, k, count), "{from:?} {i} {k} {count}");
                        assert!(!p.crossed(i, k, count - 1), "{from:?} {i} {k} {count}");
                        checked += 1;
                    } else if (x, z) != p.end_registers()
                        && k != [p.end_registers().0, p.end_registers().1][i]
                    {
                        assert!(!p.crossed(i, k, count), "{from:?} {i} {k} {count}");
                    }
                }
                let (dx, dz) = e.moves();
                x += i64::from(dx);
                z += i64::from(dz);
            }
            assert_eq!((x, z), p.end_registers());
            assert!(checked > 0);
        }
    }

    #[test]
    fn every_pass_waits_for_the_same_angle() {
        // An index seen at count 1000, 4096 counts, a start at 90°.
        let quarter = start_counts(90_000, 4096);
        assert_eq!(quarter, 1024);
        assert_eq!(start_counts(360_000, 4096), 0);
        // 0.0439453125° per count: 45.5 counts' worth rounds half away.
        assert_eq!(start_counts(4_000, 4096), 46);
        for now in [0i64, 1500, 2024, 2025, 9000, 1_000_000] {
            for c in [2u32, 1000, 8190, 20_000] {
                let r = reference_count(now, 1000, 4096, quarter, c);
                assert_eq!((r - 1000 - 1024).rem_euclid(4096), 0, "{now} {c}");
                // The lead-in starts after now, and not a turn later.
                assert!(r - i64::from(c / 2) > now, "{now} {c}");
                assert!(r - 4096 - i64::from(c / 2) <= now || r == 2024, "{now} {c}");
            }
        }
    }

    #[test]
    fn the_highest_speed_is_the_least_of_the_limits() {
        let prices = (h("0.005"), h("0.01"));
        let l = Limits::DEFAULT; // X 1500, Z 3000 mm/min; 100, 150 mm/s².
        let at = |to: (&str, &str), lead: &str, rate: u32| {
            highest_rpm(
                (mm("10"), mm("2")),
                (mm(to.0), mm(to.1)),
                mm(lead),
                prices,
                4096,
                &l,
                rate,
            )
        };
        // Z's rate: 3000/1.5 = 2000 rpm (steps: 60·50 000·0.01/1.5 = 20 000;
        // the lead-in over 22 mm at 150 mm/s² allows about 2297).
        assert_eq!(at(("10", "-20"), "1.5", 50_000), 2000);
        // The drive: 60·2 000·0.01/1.5 = 800 rpm.
        assert_eq!(at(("10", "-20"), "1.5", 2_000), 800);
        // 2 mm of travel: the lead-in, about 60·√(150·2)/1.5 = 692.8 rpm.
        let n = at(("10", "0"), "1.5", 50_000);
        assert_eq!(n, max_rpm(mm("1.5"), mm("2"), 4096, 150));
        assert!((690..=693).contains(&n), "{n}");
        // A face thread along X: 1500/1.5 = 1000 rpm.
        assert_eq!(at(("30", "2"), "1.5", 50_000), 1000);
        // A taper 1:4 on the radius along Z: X at 1500/(1.5/4) = 4000,
        // so Z's 2000 still rules.
        assert_eq!(at(("15.5", "-20"), "1.5", 50_000), 2000);
        assert_eq!(at(("10", "2"), "1.5", 50_000), 0);
    }

    #[test]
    fn refusals() {
        let prices = (h("0.005"), h("0.01"));
        let o = (mm("0"), mm("0"));
        let new = |to, lead, cpr, c| SyncPass::new(o, to, prices, mm(lead), cpr, c);
        assert_eq!(new(o, "1", 4096, 2), Err(SyncError::NoTravel));
        // 41 mm of lead over 4096 counts is above 0.01 mm a count.
        assert_eq!(
            new((mm("0"), mm("-100")), "41", 4096, 2),
            Err(SyncError::TooCoarse { axis: 'Z' })
        );
        assert_eq!(
            new((mm("0"), mm("-100")), "40.96", 4096, 2),
            Err(SyncError::TooCoarse { axis: 'Z' })
        );
        assert!(new((mm("0"), mm("-100")), "40.959999", 4096, 2).is_ok());
        // A taper: X moves 0.6 of Z's travel at half of Z's price.
        assert_eq!(
            new((mm("60"), mm("-100")), "40", 4096, 2),
            Err(SyncError::TooCoarse { axis: 'X' })
        );
        // 1 mm of lead, 4096 counts, C = 8192: needs 2 mm.
        assert_eq!(
            new((mm("0"), mm("-1.999999")), "1", 4096, 8192),
            Err(SyncError::TooShort { needed: mm("2") })
        );
        assert!(new((mm("0"), mm("-2")), "1", 4096, 8192).is_ok());
        assert_eq!(
            new((mm("0"), mm("-2")), "1", 4096, 3),
            Err(SyncError::Range)
        );
    }

    #[test]
    fn lead_in_counts_by_hand() {
        // K = 1.5 mm, 600 rpm, 4096 counts, 500 mm/s²:
        // 1.5·600²·4096/(3600·500) = 1228.8 → 1230 (even).
        assert_eq!(lead_in_counts(mm("1.5"), 600, 4096, 500), Some(1230));
        assert_eq!(lead_in_counts(mm("1.5"), 0, 4096, 500), Some(2));
        // The highest speed for 22 mm of travel: C·1.5/4096 ≤ 22.
        let n = max_rpm(mm("1.5"), mm("22"), 4096, 500);
        let c = lead_in_counts(mm("1.5"), n, 4096, 500).unwrap();
        assert!(c as i64 * 15 <= 220 * 4096);
        let c1 = lead_in_counts(mm("1.5"), n + 1, 4096, 500).unwrap();
        assert!(c1 as i64 * 15 > 220 * 4096);
    }
}

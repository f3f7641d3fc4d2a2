//! LinuxCNC's threading cycle `G76` (`docs/threading.md` §5): the depth of
//! each pass and the moves of every pass, in exact integer geometry (X on
//! the radius, 10⁻⁷ mm), checked whole before the first move.
//!
//! A pass at depth `d` below the crest (`s` the sign of `I`, `σ` the sign
//! of `Z − z0`, `t = tan Q`):
//!
//! | move | to |
//! |---|---|
//! | rapid | `(x0 − s·(K − d), z0 + σ·d·t)`, the retract line beside the pass's start |
//! | rapid, or the entry taper | `(x0 + I + s·d, …)`, the cut's X |
//! | synchronised | `(x0 + I + s·d, Z − σ·(K − d)·t)` |
//! | rapid | back to the retract line |
//!
//! and after the last pass a rapid to `(x0, Z)`. Pass `n` cuts at
//! `d = J·n^(1/R)` while that is less than `K`, then one pass at `K`, then
//! `H` spring passes at `K`.

use crate::trig::{sin_cos_arcsec, ONE_Q62};
use crate::wide::isqrt;

/// The most roughing passes a cycle may have (`K` at `J·n^(1/R)`).
pub const MAX_PASSES: u32 = 1000;
/// The most spring passes.
pub const MAX_SPRING: u32 = 99;
/// The longest `P`, `I`, `J`, `K`, `E`: 10⁹ × 10⁻⁷ mm (100 mm).
pub const MAX_WORD: i64 = 1_000_000_000;
/// The largest compound angle `Q`, arc-seconds (60°).
pub const MAX_ANGLE: i64 = 60 * 3600;

/// The words of a `G76` block, converted: lengths in 10⁻⁷ mm with `I`,
/// `J`, `K` on the radius, the start and `Z` in the work system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct G76 {
    /// Where the tool stands when the cycle begins: the drive line's X
    /// (radius) and the thread's start Z.
    pub start: [i64; 2],
    /// `Z`: where the thread ends.
    pub z_end: i64,
    /// `P`: the pitch, the advance along Z per revolution.
    pub pitch: i64,
    /// `I`: the crest's offset from the drive line (negative outside).
    pub crest: i64,
    /// `J`: the first pass's depth, above 0.
    pub first: i64,
    /// `K`: the thread's full depth, above `J`.
    pub full: i64,
    /// `R`: the depth degression in 10⁻⁴ (10 000 constant depth, 20 000
    /// constant area), at least 10 000.
    pub degression: u32,
    /// `Q`: the compound slide angle, arc-seconds, 0 to [`MAX_ANGLE`].
    pub angle: i64,
    /// `H`: the spring passes at full depth.
    pub spring: u32,
    /// `E`: the taper's length along Z.
    pub taper: i64,
    /// `L`: which ends taper, 0 none, 1 entry, 2 exit, 3 both.
    pub ends: u8,
}

/// Why a `G76` is refused before anything moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum G76Error {
    /// `I` is 0: no crest to cut from.
    NoCrest,
    /// `J` not above 0.
    FirstDepth,
    /// `K` not above `J`.
    FullDepth,
    /// `P` not above 0.
    Pitch,
    /// `R` below 1.
    Degression,
    /// `Q` outside 0° to 60°.
    Angle,
    /// `H` above [`MAX_SPRING`].
    Spring,
    /// `L` not 0 to 3, or `E` below 0.
    Taper,
    /// A word beyond [`MAX_WORD`].
    Range,
    /// More than [`MAX_PASSES`] passes before the full depth.
    TooManyPasses,
    /// The thread along Z, less the compound shift `K·tan Q`, leaves no
    /// room for its tapers and a locked cut (`Z` equal to the start too).
    TooShort,
}

/// One move of the cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThreadMove {
    /// At the rapid rate to `[x, z]`.
    Rapid([i64; 2]),
    /// Locked to the spindle to `[x, z]`: `lead` the advance per
    /// revolution along the move's longer axis (`docs/threading.md` §1).
    Cut {
        /// The end point.
        to: [i64; 2],
        /// The lead along the lead axis, 10⁻⁷ mm per revolution.
        lead: i64,
    },
}

/// `n / d` rounded half away from zero (`d > 0`; 0 for `d` 0, which
/// the callers never pass).
fn round_div(n: i128, d: i128) -> i128 {
    let q = crate::wide::checked_divrem_i128(2 * n.abs() + d, 2 * d).map_or(0, |(q, _)| q);
    if n < 0 {
        -q
    } else {
        q
    }
}

/// `log₂ n` in Q64 (`n ≥ 1`), by the square-and-compare method: each
/// squaring of the mantissa gives one bit, truncated.
fn log2_q64(n: u32) -> u128 {
    let k = 31 - n.leading_zeros();
    // The mantissa n / 2^k in [1, 2), Q62.
    let mut m = u128::from(n) << (62 - k);
    let mut frac: u128 = 0;
    for i in 1..=64 {
        m = (m * m) >> 62;
        if m >= 2 << 62 {
            m >>= 1;
            frac |= 1 << (64 - i);
        }
    }
    (u128::from(k) << 64) | frac
}

/// `2^(2^−i)` in Q62 for `i` from 1 to 48, each the square root of the one
/// before (truncated), computed once at build time.
const ROOTS_OF_TWO: [u128; 48] = roots_of_two();

const fn roots_of_two() -> [u128; 48] {
    let mut t = [0u128; 48];
    let mut c = isqrt(2 << 124) as u128;
    let mut i = 0;
    while i < 48 {
        t[i] = c;
        c = isqrt(c << 62) as u128;
        i += 1;
    }
    t
}

/// `2^y` in Q62 for `y` in Q64 below 2⁶, from [`ROOTS_OF_TWO`]: 48 bits
/// of `y`'s fraction.
fn exp2_q62(y: u128) -> u128 {
    let whole = (y >> 64) as u32;
    let frac = y & ((1 << 64) - 1);
    let mut r: u128 = 1 << 62;
    for (i, c) in ROOTS_OF_TWO.iter().enumerate() {
        if frac & (1 << (63 - i)) != 0 {
            r = (r * c) >> 62;
        }
    }
    r << whole
}

/// `n^(10⁴/r)` in Q62: the depth factor of pass `n` at degression `r`
/// (10⁻⁴), within about 10⁻¹³ of it relatively (`n ≤ MAX_PASSES`).
pub fn depth_factor(n: u32, r: u32) -> u128 {
    let y = log2_q64(n) * 10_000 / u128::from(r.max(1));
    exp2_q62(y)
}

impl G76 {
    /// Checks the cycle: every pass and move follows without a check that
    /// could fail.
    pub fn check(&self) -> Result<(), G76Error> {
        let words = [self.pitch, self.crest, self.first, self.full, self.taper];
        if words.iter().any(|w| w.abs() > MAX_WORD)
            || self
                .start
                .iter()
                .chain([&self.z_end])
                .any(|v| v.abs() > 1 << 40)
        {
            return Err(G76Error::Range);
        }
        if self.crest == 0 {
            return Err(G76Error::NoCrest);
        }
        if self.first <= 0 {
            return Err(G76Error::FirstDepth);
        }
        if self.full <= self.first {
            return Err(G76Error::FullDepth);
        }
        if self.pitch <= 0 {
            return Err(G76Error::Pitch);
        }
        if self.degression < 10_000 {
            return Err(G76Error::Degression);
        }
        if !(0..=MAX_ANGLE).contains(&self.angle) {
            return Err(G76Error::Angle);
        }
        if self.spring > MAX_SPRING {
            return Err(G76Error::Spring);
        }
        if self.ends > 3 || self.taper < 0 {
            return Err(G76Error::Taper);
        }
        if self.depth(MAX_PASSES) < self.full {
            return Err(G76Error::TooManyPasses);
        }
        // Every pass is as long along Z: the thread less K·tan Q.
        let ends = self.tapered();
        let tapers = i64::from(ends & 1) + i64::from(ends >> 1);
        let length = (self.z_end - self.start[1]).abs() - self.shift(self.full);
        if length <= tapers * self.taper {
            return Err(G76Error::TooShort);
        }
        Ok(())
    }

    /// The depth of roughing pass `n` (from 1), `Q(J·n^(1/R))`.
    pub fn depth(&self, n: u32) -> i64 {
        let f = depth_factor(n, self.degression);
        round_div((self.first as i128) * (f as i128), 1 << 62) as i64
    }

    /// `Q(d·tan Q)`, the compound slide's shift along Z at depth `d`.
    fn shift(&self, d: i64) -> i64 {
        let (s, c) = sin_cos_arcsec(self.angle);
        if s == 0 {
            return 0;
        }
        round_div(i128::from(d) * i128::from(s), i128::from(c.max(1))) as i64
    }

    /// The depths of every pass: the roughing passes, the last at `K`,
    /// then the spring passes.
    pub fn depths(&self) -> impl Iterator<Item = i64> + '_ {
        let full = self.full;
        let mut n = 0;
        let mut done = false;
        core::iter::from_fn(move || {
            if done {
                return None;
            }
            n += 1;
            let d = self.depth(n);
            if d >= full || n >= MAX_PASSES {
                done = true;
                return Some(full);
            }
            Some(d)
        })
        .chain(core::iter::repeat_n(full, self.spring as usize))
    }

    /// The moves of the pass at depth `d`, in order (at most six).
    pub fn pass(&self, d: i64) -> Moves {
        let s = self.crest.signum();
        let sz = (self.z_end - self.start[1]).signum();
        let [x0, z0] = self.start;
        let k = self.full;
        let zs = z0 + sz * self.shift(d);
        let ze = self.z_end - sz * self.shift(k - d);
        let xr = x0 - s * (k - d);
        let xc = x0 + self.crest + s * d;
        let xt = xc - s * k;
        let e = self.taper;
        let ends = self.tapered();
        let mut m = Moves::new();
        m.push(ThreadMove::Rapid([xr, zs]));
        if ends & 1 != 0 {
            // The plunge to the taper's start at the taper's rate, as
            // LinuxCNC runs it: its lead is the taper's path per turn.
            m.push(ThreadMove::Cut {
                to: [xt, zs],
                lead: self.taper_path_lead(),
            });
            m.push(ThreadMove::Cut {
                to: [xc, zs + sz * e],
                lead: self.taper_lead(),
            });
        } else {
            m.push(ThreadMove::Rapid([xc, zs]));
        }
        if ends & 2 != 0 {
            m.push(ThreadMove::Cut {
                to: [xc, ze - sz * e],
                lead: self.pitch,
            });
            m.push(ThreadMove::Cut {
                to: [xt, ze],
                lead: self.taper_lead(),
            });
        } else {
            m.push(ThreadMove::Cut {
                to: [xc, ze],
                lead: self.pitch,
            });
        }
        m.push(ThreadMove::Rapid([xr, ze]));
        m
    }

    /// The ends that taper: `L`, or none when `E` is 0 (`E0 L3` cuts
    /// straight, as LinuxCNC does).
    const fn tapered(&self) -> u8 {
        if self.taper > 0 {
            self.ends
        } else {
            0
        }
    }

    /// The taper's lead along its longer axis, so that Z advances `P` a
    /// turn: `P` when `E ≥ K`, else `Q(P·K/E)` along X.
    fn taper_lead(&self) -> i64 {
        if self.taper >= self.full {
            self.pitch
        } else {
            round_div(
                i128::from(self.pitch) * i128::from(self.full),
                i128::from(self.taper),
            ) as i64
        }
    }

    /// The taper's path per turn, `Q(P·√(K² + E²)/E)`.
    fn taper_path_lead(&self) -> i64 {
        let (p, k, e) = (
            self.pitch as u128,
            self.full as u128,
            self.taper.max(1) as u128,
        );
        // ⌊(2√v + E)/2E⌋ with v = P²(K² + E²): ⌊2√v⌋ = isqrt(4v).
        let v = p * p * (k * k + e * e);
        crate::wide::udiv(u128::from(isqrt(4 * v)) + e, 2 * e).map_or(0, |(q, _)| q) as i64
    }

    /// The last move of the cycle: to the drive line at `Z`.
    pub fn end(&self) -> ThreadMove {
        ThreadMove::Rapid([self.start[0], self.z_end])
    }

    /// Every move of the cycle, in order.
    pub fn moves(&self) -> impl Iterator<Item = ThreadMove> + '_ {
        self.depths()
            .flat_map(move |d| self.pass(d).into_iter())
            .chain(core::iter::once(self.end()))
    }
}

/// A pass's moves, without allocation: up to six.
#[derive(Clone, Copy, Debug)]
pub struct Moves {
    items: [ThreadMove; 6],
    len: usize,
}

impl Moves {
    const fn new() -> Moves {
        Moves {
            items: [ThreadMove::Rapid([0, 0]); 6],
            len: 0,
        }
    }

    fn push(&mut self, m: ThreadMove) {
        if let Some(slot) = self.items.get_mut(self.len) {
            *slot = m;
            self.len += 1;
        }
    }

    /// The moves, in order.
    pub fn as_slice(&self) -> &[ThreadMove] {
        self.items.get(..self.len).unwrap_or(&[])
    }
}

impl IntoIterator for Moves {
    type Item = ThreadMove;
    type IntoIter = core::iter::Take<core::array::IntoIter<ThreadMove, 6>>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.into_iter().take(self.len)
    }
}

/// `1.0` in the Q62 the depth factor is given in.
pub const DEPTH_ONE: u128 = ONE_Q62 as u128;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_depth_factor_is_the_root() {
        for (n, r, want) in [
            (1u32, 10_000u32, 1.0f64),
            (4, 20_000, 2.0),
            (2, 20_000, core::f64::consts::SQRT_2),
            (27, 15_000, 9.0),
            (1000, 10_000, 1000.0),
            (7, 17_321, 7f64.powf(1.0 / 1.7321)),
        ] {
            let got = depth_factor(n, r) as f64 / DEPTH_ONE as f64;
            assert!(
                (got - want).abs() <= want * 1e-12,
                "{n}^(1/{r}): {got} against {want}"
            );
        }
    }

    fn cycle() -> G76 {
        G76 {
            start: [50_000_000, 20_000_000],
            z_end: -200_000_000,
            pitch: 15_000_000,
            crest: -10_000_000,
            first: 4_000_000,
            full: 9_000_000,
            degression: 10_000,
            angle: 0,
            spring: 1,
            taper: 0,
            ends: 0,
        }
    }

    #[test]
    fn constant_depth_passes_end_at_the_full_depth_then_spring() {
        let c = cycle();
        assert_eq!(c.check(), Ok(()));
        let d: [i64; 4] = [4_000_000, 8_000_000, 9_000_000, 9_000_000];
        assert!(c.depths().eq(d));
        // The first pass: retract X5.5, cut X3.6, from Z2 to Z−20.
        assert_eq!(
            c.pass(4_000_000).as_slice(),
            &[
                ThreadMove::Rapid([55_000_000, 20_000_000]),
                ThreadMove::Rapid([36_000_000, 20_000_000]),
                ThreadMove::Cut {
                    to: [36_000_000, -200_000_000],
                    lead: 15_000_000
                },
                ThreadMove::Rapid([55_000_000, -200_000_000]),
            ]
        );
        assert_eq!(
            c.moves().last(),
            Some(ThreadMove::Rapid([50_000_000, -200_000_000]))
        );
    }

    #[test]
    fn what_cannot_be_cut_is_refused() {
        let base = cycle();
        type Change = fn(&mut G76);
        let cases: [(Change, G76Error); 9] = [
            (|c| c.crest = 0, G76Error::NoCrest),
            (|c| c.first = 0, G76Error::FirstDepth),
            (|c| c.full = c.first, G76Error::FullDepth),
            (|c| c.pitch = 0, G76Error::Pitch),
            (|c| c.degression = 9_999, G76Error::Degression),
            (|c| c.angle = MAX_ANGLE + 1, G76Error::Angle),
            (|c| c.ends = 4, G76Error::Taper),
            (|c| c.first = 1, G76Error::TooManyPasses),
            (
                |c| {
                    c.taper = 120_000_000;
                    c.ends = 3
                },
                G76Error::TooShort,
            ),
        ];
        for (change, want) in cases {
            let mut c = base;
            change(&mut c);
            assert_eq!(c.check(), Err(want), "{c:?}");
        }
    }
}

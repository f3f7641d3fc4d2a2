//! Exact model of motion locked to the spindle: the progress of one
//! synchronised pass, its registers at each encoder count, its step events,
//! the refusals made before it and its lead-in. Integers and exact rationals
//! only, no floating point.
//!
//! Written from `docs/threading.md` §1–§3, `docs/impulses.md` §2 and
//! `docs/units.md` §2–§3 alone:
//!
//! - a pass goes from `P0 = (x0, z0)` to `P1 = (x1, z1)` (10⁻⁷ mm, X on the
//!   radius). The **lead axis** is Z when `|z1 − z0| ≥ |x1 − x0|`, else X, and
//!   `D` is the travel along it (so `D = max(|Δx|, |Δz|)`); `K` is the lead
//!   along that axis per revolution, `N` the counts per revolution, `u = K/N`
//!   the advance per count, `C` the lead-in in counts (even, at least 2);
//! - the progress `s(c)` is the table of §1: `0` up to `c = −C/2`, the
//!   parabola `u·(c + C/2)²/(2C)` up to `C/2`, the line `u·c` up to
//!   `D/u − C/2`, the parabola `D − u·(D/u + C/2 − c)²/(2C)` up to
//!   `D/u + C/2`, then `D`; the tool is at `P(c) = P0 + (P1 − P0)·s(c)/D`;
//! - the registers are `(Q(x(c)/h_X), Q(z(c)/h_Z))`, `Q` rounding half away
//!   from zero (`docs/impulses.md` §2.1–§2.2) ([`registers`]);
//! - a step event is a count at which a register changes, counting from
//!   `c = −C/2 + 1`; the events are listed with the registers after each
//!   ([`events`]);
//! - before the pass: no travel, an axis moving more than one impulse per
//!   count while locked (`u·|Δaxis|/D > h_axis`) or a pass shorter than its
//!   lead-in and lead-out (`D < u·C`) is refused ([`Refusal`]);
//! - the lead-in `C` is the least even whole number `≥ K·n²·N/(3600·a)`, at
//!   least 2 ([`lead_in_counts`]).
//!
//! # Exactness
//!
//! With `M = 2·C·N·K`, `M·s(c)` is a whole number `S(c)` on every piece:
//!
//! | counts | `S(c) = M·s(c)` |
//! |---|---|
//! | `c ≤ −C/2` | `0` |
//! | `−C/2 ≤ c ≤ C/2` | `K²·(c + C/2)²` |
//! | `C/2 ≤ c ≤ D/u − C/2` | `2·C·K²·c` |
//! | `D/u − C/2 ≤ c ≤ D/u + C/2` | `M·D − w²`, `w = D·N − K·(c − C/2)` |
//! | `c ≥ D/u + C/2` | `M·D` |
//!
//! (lead-out: `D/u + C/2 − c = w/K`, so `u·(w/K)²/(2C) = w²/(2CNK)`). The
//! piece is chosen by comparing integers: `c ≤ D/u − C/2` is
//! `K·(c + C/2) ≤ D·N`, `c < D/u + C/2` is `K·(c − C/2) < D·N`. Each piece
//! meets the next with the same value, so which one is taken at a boundary
//! does not matter. A register is then
//! `Q((a0·D·M + Δa·S(c)) / (h·D·M))`, an exact quotient of integers.
//!
//! # Range
//!
//! The inputs are asserted (panic outside) to lie in
//!
//! - `|x0|, |z0|, |x1|, |z1| ≤ 10^10` (1 m), so `D ≤ 2·10^10 < 2^35`;
//! - `1 ≤ hx, hz ≤ 10^7` (the device's prices are 10 … 10^7, `docs/units.md`
//!   §2.1);
//! - `1 ≤ lead ≤ 2^31`, `1 ≤ cpr ≤ 65 536`, `2 ≤ lead_in ≤ 2^24` and even.
//!
//! Then `M ≤ 2^72`, `S(c) ≤ D·M ≤ 2^107`, and every `S(c)` is computed in
//! `i128` (the lead-in's `(K·(c + C/2))² ≤ (K·C)² ≤ 2^110`, the lock's
//! `K·c ≤ D·N ≤ 2^51`). The register's numerator reaches about `2^143` and its
//! denominator `2^131`, beyond `i128`: they are held in a private 256-bit
//! sign-and-magnitude integer whose only division is the bit-by-bit long
//! division of `Q`. [`events`] evaluates every count of the pass, about
//! `D·N/K + C` of them, so its cost, not its arithmetic, is what limits it.
//!
//! Nothing here is shared with the controller's core: the crate does not
//! depend on it.

use crate::exact::q_div;

/// Largest coordinate magnitude accepted, 10⁻⁷ mm (1 m).
pub const COORD_MAX: i64 = 10_000_000_000;
/// Largest impulse price accepted, 10⁻⁷ mm (1 mm).
pub const PRICE_MAX: i64 = 10_000_000;
/// Largest lead accepted, 10⁻⁷ mm per revolution (about 214.7 mm).
pub const LEAD_MAX: i64 = 1 << 31;
/// Largest encoder resolution accepted, counts per revolution.
pub const CPR_MAX: i64 = 65_536;
/// Largest lead-in accepted, counts.
pub const LEAD_IN_MAX: i64 = 1 << 24;

/// One synchronised pass (docs/threading.md §1).
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    /// `P0`, X on the radius, 10⁻⁷ mm.
    pub x0: i64,
    /// `P0`, Z, 10⁻⁷ mm.
    pub z0: i64,
    /// `P1`, X on the radius, 10⁻⁷ mm.
    pub x1: i64,
    /// `P1`, Z, 10⁻⁷ mm.
    pub z1: i64,
    /// Impulse price of X (radius), 10⁻⁷ mm, > 0.
    pub hx: i64,
    /// Impulse price of Z, 10⁻⁷ mm, > 0.
    pub hz: i64,
    /// `K`, 10⁻⁷ mm per revolution along the lead axis, > 0.
    pub lead: i64,
    /// `N`, encoder counts per revolution, > 0.
    pub cpr: i64,
    /// `C`, the lead-in in counts, even, >= 2.
    pub lead_in: i64,
}

/// Why a pass is refused before it starts (docs/threading.md §1–§3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// D = 0: no travel along the lead axis
    NoTravel,
    /// D < u*C: the pass needs this travel (10⁻⁷ mm, exact value u*C rounded UP to a whole 10⁻⁷ mm) for its lead-in and lead-out
    TooShort {
        /// `⌈u·C⌉` = `⌈K·C/N⌉`, 10⁻⁷ mm.
        needed: i64,
    },
    /// an axis would move more than one impulse per count while locked: 'X' or 'Z'
    TooCoarse {
        /// `'X'` or `'Z'`.
        axis: char,
    },
}

// ---------------------------------------------------------------------------
// 256-bit integers, just enough for Q of a quotient
// ---------------------------------------------------------------------------

const LOW64: u128 = u64::MAX as u128;

/// An unsigned 256-bit integer `hi·2^128 + lo` (the derived order compares
/// `hi` first, then `lo`: the numeric order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct U256 {
    hi: u128,
    lo: u128,
}

impl U256 {
    const ZERO: U256 = U256 { hi: 0, lo: 0 };

    /// The full product `a·b`.
    fn product(a: u128, b: u128) -> U256 {
        let (a1, a0) = (a >> 64, a & LOW64);
        let (b1, b0) = (b >> 64, b & LOW64);
        let p00 = a0 * b0;
        let p01 = a0 * b1;
        let p10 = a1 * b0;
        let p11 = a1 * b1;
        // The bits 64…191 of the product, below 3·2^64 before their carry.
        let mid = (p00 >> 64) + (p01 & LOW64) + (p10 & LOW64);
        U256 {
            lo: (p00 & LOW64) | (mid << 64),
            hi: p11 + (p01 >> 64) + (p10 >> 64) + (mid >> 64),
        }
    }

    /// `self + o`; panics on overflow.
    fn add(self, o: U256) -> U256 {
        let (lo, carry) = self.lo.overflowing_add(o.lo);
        let hi = self
            .hi
            .checked_add(o.hi)
            .and_then(|h| h.checked_add(u128::from(carry)))
            .expect("256-bit overflow in the model");
        U256 { hi, lo }
    }

    /// `self − o`, for `self ≥ o`.
    fn sub(self, o: U256) -> U256 {
        assert!(self >= o, "negative 256-bit difference in the model");
        let (lo, borrow) = self.lo.overflowing_sub(o.lo);
        U256 {
            hi: self.hi - o.hi - u128::from(borrow),
            lo,
        }
    }

    /// `2·self`; panics on overflow.
    fn double(self) -> U256 {
        assert!(self.hi >> 127 == 0, "256-bit overflow in the model");
        U256 {
            hi: (self.hi << 1) | (self.lo >> 127),
            lo: self.lo << 1,
        }
    }

    /// The number of significant bits.
    fn bits(self) -> u32 {
        if self.hi != 0 {
            256 - self.hi.leading_zeros()
        } else {
            128 - self.lo.leading_zeros()
        }
    }

    fn bit(self, i: u32) -> bool {
        if i >= 128 {
            (self.hi >> (i - 128)) & 1 == 1
        } else {
            (self.lo >> i) & 1 == 1
        }
    }

    fn with_bit(self, i: u32) -> U256 {
        if i >= 128 {
            U256 {
                hi: self.hi | (1 << (i - 128)),
                lo: self.lo,
            }
        } else {
            U256 {
                hi: self.hi,
                lo: self.lo | (1 << i),
            }
        }
    }

    /// `⌊self / d⌋`, by long division one bit at a time.
    fn div(self, d: U256) -> U256 {
        assert!(d != U256::ZERO, "division by zero in the model");
        let mut q = U256::ZERO;
        let mut r = U256::ZERO;
        for i in (0..self.bits()).rev() {
            // r < d before the shift, so r < 2·d after it: no overflow while
            // d < 2^255, which `double` checks.
            r = r.double();
            if self.bit(i) {
                r.lo |= 1;
            }
            if r >= d {
                r = r.sub(d);
                q = q.with_bit(i);
            }
        }
        q
    }
}

/// A signed 256-bit integer as sign and magnitude.
#[derive(Clone, Copy, Debug)]
struct Wide {
    neg: bool,
    mag: U256,
}

/// `a·b`, exactly.
fn wide_mul(a: i128, b: i128) -> Wide {
    Wide {
        neg: (a < 0) != (b < 0),
        mag: U256::product(a.unsigned_abs(), b.unsigned_abs()),
    }
}

/// `a + b`, exactly.
fn wide_add(a: Wide, b: Wide) -> Wide {
    if a.neg == b.neg {
        Wide {
            neg: a.neg,
            mag: a.mag.add(b.mag),
        }
    } else if a.mag >= b.mag {
        Wide {
            neg: a.neg,
            mag: a.mag.sub(b.mag),
        }
    } else {
        Wide {
            neg: b.neg,
            mag: b.mag.sub(a.mag),
        }
    }
}

/// `Q(n / d)` for `d > 0`: `⌊(2|n| + d) / (2d)⌋` with the sign of `n`, which
/// rounds to the nearest integer and an exact half away from zero.
fn q_wide(n: Wide, d: U256) -> i128 {
    let q = n.mag.double().add(d).div(d.double());
    assert!(
        q.hi == 0 && q.lo <= i128::MAX as u128,
        "register out of range in the model"
    );
    let q = q.lo as i128;
    if n.neg {
        -q
    } else {
        q
    }
}

// ---------------------------------------------------------------------------
// The pass
// ---------------------------------------------------------------------------

fn assert_range(p: &Pass) {
    for (name, v) in [("x0", p.x0), ("z0", p.z0), ("x1", p.x1), ("z1", p.z1)] {
        assert!(
            v.abs() <= COORD_MAX,
            "{name} = {v} outside ±{COORD_MAX} (the model's range)"
        );
    }
    for (name, h) in [("hx", p.hx), ("hz", p.hz)] {
        assert!(
            (1..=PRICE_MAX).contains(&h),
            "{name} = {h} outside 1..={PRICE_MAX} (the model's range)"
        );
    }
    assert!(
        (1..=LEAD_MAX).contains(&p.lead),
        "lead = {} outside 1..={LEAD_MAX} (the model's range)",
        p.lead
    );
    assert!(
        (1..=CPR_MAX).contains(&p.cpr),
        "cpr = {} outside 1..={CPR_MAX} (the model's range)",
        p.cpr
    );
    assert!(
        (2..=LEAD_IN_MAX).contains(&p.lead_in) && p.lead_in % 2 == 0,
        "lead_in = {} is not an even number in 2..={LEAD_IN_MAX}",
        p.lead_in
    );
}

/// The pass's constants, as `i128`.
struct Geometry {
    x0: i128,
    z0: i128,
    dx: i128,
    dz: i128,
    hx: i128,
    hz: i128,
    /// `K`
    k: i128,
    /// `N`
    n: i128,
    /// `C`
    c: i128,
    /// `D`, the travel along the lead axis.
    d: i128,
}

impl Geometry {
    fn of(p: &Pass) -> Geometry {
        assert_range(p);
        let dx = i128::from(p.x1) - i128::from(p.x0);
        let dz = i128::from(p.z1) - i128::from(p.z0);
        // The lead axis is Z when |Δz| ≥ |Δx|, else X; D is its travel.
        let d = if dz.abs() >= dx.abs() {
            dz.abs()
        } else {
            dx.abs()
        };
        Geometry {
            x0: p.x0.into(),
            z0: p.z0.into(),
            dx,
            dz,
            hx: p.hx.into(),
            hz: p.hz.into(),
            k: p.lead.into(),
            n: p.cpr.into(),
            c: p.lead_in.into(),
            d,
        }
    }

    /// `M = 2·C·N·K`: `M·s(c)` is whole.
    fn m(&self) -> i128 {
        2 * self.c * self.n * self.k
    }

    /// `S(c) = M·s(c)` (module doc, "Exactness").
    fn progress(&self, c: i64) -> i128 {
        let (k, n, d) = (self.k, self.n, self.d);
        let half = self.c / 2;
        let c = i128::from(c);
        if c <= -half {
            // At rest at P0.
            0
        } else if c <= half {
            // Lead-in: u·(c + C/2)²/(2C) = K²·(c + C/2)² / M.
            let t = k * (c + half);
            t * t
        } else if k * (c + half) <= d * n {
            // Locked: u·c = 2·C·K²·c / M.
            2 * self.c * k * (k * c)
        } else if k * (c - half) < d * n {
            // Lead-out: D − u·(D/u + C/2 − c)²/(2C) = (M·D − w²) / M.
            let w = d * n - k * (c - half);
            self.m() * d - w * w
        } else {
            // At rest at P1.
            self.m() * d
        }
    }

    /// `Q(a(c)/h)` with `a(c) = a0 + Δa·S/(M·D)`.
    fn register(&self, a0: i128, da: i128, h: i128, s: i128) -> i64 {
        let num = wide_add(wide_mul(a0 * self.d, self.m()), wide_mul(da, s));
        let den = wide_mul(h * self.d, self.m()).mag;
        i64::try_from(q_wide(num, den)).expect("register out of i64")
    }

    fn registers(&self, c: i64) -> (i64, i64) {
        let s = self.progress(c);
        (
            self.register(self.x0, self.dx, self.hx, s),
            self.register(self.z0, self.dz, self.hz, s),
        )
    }
}

/// Registers (X, Z) = (Q(x(c)/hx), Q(z(c)/hz)) at count c (§1, §3), exact.
///
/// # Panics
/// If an input is outside the module's range, if the pass has no travel
/// (`D = 0`) or if it is too short for its lead-in and lead-out (`D < u·C`):
/// the table of §1 does not describe such a pass. A pass that is only too
/// coarse is evaluated.
pub fn registers(p: &Pass, c: i64) -> (i64, i64) {
    let g = Geometry::of(p);
    assert!(g.d > 0, "a pass without travel has no progress");
    assert!(
        g.d * g.n >= g.k * g.c,
        "a pass shorter than u·C has no progress"
    );
    g.registers(c)
}

/// The step events of the pass (§3): (c, X, Z) with the registers after each event, counts ascending,
/// starting from c = -C/2 + 1 and ending at the last count where a register changes.
/// Check order: NoTravel first, then TooCoarse (X checked before Z), then TooShort.
///
/// Every count from `−C/2 + 1` to the first count `≥ D/u + C/2` is
/// evaluated with [`registers`]; after it the tool rests at `P1`.
///
/// # Panics
/// If an input is outside the module's range, or if a register changes by
/// more than one impulse between two consecutive counts, or against the
/// direction of `P1`. §3 refuses `u·|Δaxis|/D = h_axis` too: then a
/// register could jump by two where the axis passes from `−h/2` to `+h/2`
/// in one count (`Q(−½) = −1`, `Q(½) = 1`; see the tests).
pub fn events(p: &Pass) -> Result<Vec<(i64, i64, i64)>, Refusal> {
    let g = Geometry::of(p);
    if g.d == 0 {
        return Err(Refusal::NoTravel);
    }
    // u·|Δa|/D ≥ h  ⇔  K·|Δa| ≥ h·N·D (all positive).
    for (axis, da, h) in [('X', g.dx, g.hx), ('Z', g.dz, g.hz)] {
        if da != 0 && g.k * da.abs() >= h * g.n * g.d {
            return Err(Refusal::TooCoarse { axis });
        }
    }
    // D < u·C  ⇔  D·N < K·C; the need is ⌈K·C/N⌉.
    if g.d * g.n < g.k * g.c {
        let needed = (g.k as u128 * g.c as u128).div_ceil(g.n as u128);
        return Err(Refusal::TooShort {
            needed: i64::try_from(needed).expect("need out of i64"),
        });
    }

    let half = p.lead_in / 2;
    // The first count c with c ≥ D/u + C/2 = D·N/K + C/2.
    let last = (g.d as u128 * g.n as u128).div_ceil(g.k as u128);
    let last = i64::try_from(last).expect("pass too long for i64 counts") + half;
    let sign_x = g.dx.signum() as i64;
    let sign_z = g.dz.signum() as i64;

    let mut out = Vec::new();
    let mut prev = g.registers(-half);
    for c in (-half + 1)..=last {
        let now = g.registers(c);
        let (sx, sz) = (now.0 - prev.0, now.1 - prev.1);
        assert!(
            sx.abs() <= 1 && sz.abs() <= 1,
            "a register changes by more than one impulse at count {c}: {prev:?} -> {now:?}"
        );
        assert!(
            (sx == 0 || sx == sign_x) && (sz == 0 || sz == sign_z),
            "a register steps away from P1 at count {c}: {prev:?} -> {now:?}"
        );
        if now != prev {
            out.push((c, now.0, now.1));
        }
        prev = now;
    }
    // Where the pass ends does not depend on the lead-in (§3).
    assert_eq!(
        prev,
        (
            q_div(p.x1.into(), p.hx.into()) as i64,
            q_div(p.z1.into(), p.hz.into()) as i64
        ),
        "the pass does not end on P1's registers"
    );
    Ok(out)
}

/// The lead-in of §2: least even C >= K·n²·N/(3600·a) (K in mm), at least 2.
/// lead in 10⁻⁷ mm, rpm a whole number of revolutions per minute, accel in whole mm/s² (> 0).
///
/// With `K` in 10⁻⁷ mm the bound is `lead·rpm²·cpr / (3600·accel·10^7)`,
/// taken exactly.
///
/// # Panics
/// If `lead` is outside `1..=2^31`, `rpm` outside `0..=10^6`, `cpr` outside
/// `1..=65 536`, `accel` is not positive, or the result exceeds `i64`.
pub fn lead_in_counts(lead: i64, rpm: i64, cpr: i64, accel: i64) -> i64 {
    assert!((1..=LEAD_MAX).contains(&lead), "lead {lead} out of range");
    assert!((0..=1_000_000).contains(&rpm), "rpm {rpm} out of range");
    assert!((1..=CPR_MAX).contains(&cpr), "cpr {cpr} out of range");
    assert!(accel > 0, "accel {accel} must be positive");
    // At most 2^31 · 10^12 · 2^16 < 2^88.
    let num = lead as u128 * (rpm as u128 * rpm as u128) * cpr as u128;
    let den = 3600 * accel as u128 * 10_000_000;
    let c = num.div_ceil(den);
    let c = (c + c % 2).max(2);
    i64::try_from(c).expect("lead-in out of i64")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::Ratio;

    // -- an independent evaluation of the table of §1 with `exact::Ratio` --

    fn le(a: Ratio, b: Ratio) -> bool {
        a.n * b.d <= b.n * a.d
    }

    fn travel(p: &Pass) -> i128 {
        let dx = (i128::from(p.x1) - i128::from(p.x0)).abs();
        let dz = (i128::from(p.z1) - i128::from(p.z0)).abs();
        if dz >= dx {
            dz
        } else {
            dx
        }
    }

    /// `s(c)` straight from the table, with `u = K/N` and `D/u` as rationals.
    fn table_s(p: &Pass, c: i64) -> Ratio {
        let d = Ratio::int(travel(p));
        let u = Ratio::new(p.lead.into(), p.cpr.into());
        let t = d / u;
        let cc = Ratio::int(p.lead_in.into());
        let half = cc.half();
        let two_c = cc.double();
        let c = Ratio::int(c.into());
        if le(c, Ratio::int(0) - half) {
            Ratio::int(0)
        } else if le(c, half) {
            let m = c + half;
            u * m * m / two_c
        } else if le(c, t - half) {
            u * c
        } else if le(c, t + half) {
            let r = t + half - c;
            d - u * r * r / two_c
        } else {
            d
        }
    }

    fn table_registers(p: &Pass, c: i64) -> (i64, i64) {
        let f = table_s(p, c) / Ratio::int(travel(p));
        let at = |a0: i64, a1: i64, h: i64| {
            let a = Ratio::int(a0.into()) + Ratio::int(i128::from(a1) - i128::from(a0)) * f;
            (a / Ratio::int(h.into())).round() as i64
        };
        (at(p.x0, p.x1, p.hx), at(p.z0, p.z1, p.hz))
    }

    /// The events from `table_registers`, the window found by comparing
    /// rationals.
    fn table_events(p: &Pass) -> Vec<(i64, i64, i64)> {
        let d = Ratio::int(travel(p));
        let u = Ratio::new(p.lead.into(), p.cpr.into());
        let end = d / u + Ratio::int(p.lead_in.into()).half();
        let mut out = Vec::new();
        let mut c = -p.lead_in / 2;
        let mut prev = table_registers(p, c);
        loop {
            c += 1;
            let now = table_registers(p, c);
            if now != prev {
                out.push((c, now.0, now.1));
            }
            prev = now;
            if le(end, Ratio::int(c.into())) {
                return out;
            }
        }
    }

    /// Whether `c` is in the locked piece: `C/2 ≤ c ≤ D/u − C/2`.
    fn locked(p: &Pass, c: i64) -> bool {
        let c = i128::from(c);
        let half = i128::from(p.lead_in / 2);
        c >= half && i128::from(p.lead) * (c + half) <= travel(p) * i128::from(p.cpr)
    }

    fn q(n: i128, d: i128) -> i64 {
        q_div(n, d) as i64
    }

    /// Events on X and on Z: (count, steps) of each axis.
    fn steps_per_axis(p: &Pass, ev: &[(i64, i64, i64)]) -> (i64, i64) {
        let mut prev = (q(p.x0.into(), p.hx.into()), q(p.z0.into(), p.hz.into()));
        let (mut nx, mut nz) = (0, 0);
        for &(_, x, z) in ev {
            nx += i64::from(x != prev.0);
            nz += i64::from(z != prev.1);
            prev = (x, z);
        }
        (nx, nz)
    }

    fn assert_ascending(ev: &[(i64, i64, i64)]) {
        assert!(
            ev.windows(2).all(|w| w[0].0 < w[1].0),
            "counts not ascending"
        );
    }

    /// A thread of 1.5 mm lead at Ø40, 20 mm towards −Z from an awkward z0.
    fn straight_z() -> Pass {
        Pass {
            x0: 200_000_000,
            z0: 12_345_678,
            x1: 200_000_000,
            z1: 12_345_678 - 200_000_000,
            hx: 50_000,
            hz: 100_000,
            lead: 15_000_000,
            cpr: 4096,
            lead_in: 1230,
        }
    }

    /// A gentle taper (Z leads): 10 mm down on the radius over 30 mm, 2 mm lead.
    fn taper() -> Pass {
        Pass {
            x0: 100_000_000,
            z0: 0,
            x1: 90_000_123,
            z1: -300_000_000,
            hx: 50_000,
            hz: 100_000,
            lead: 20_000_000,
            cpr: 4096,
            lead_in: 206,
        }
    }

    /// A face thread (X leads): from radius 15 mm to 5 mm, 1 mm lead.
    fn face() -> Pass {
        Pass {
            x0: 150_000_000,
            z0: -5_000_000,
            x1: 50_000_000,
            z1: -5_000_000,
            hx: 50_000,
            hz: 100_000,
            lead: 10_000_000,
            cpr: 4096,
            lead_in: 206,
        }
    }

    /// A taper steeper than 45° (X leads): 10 mm on the radius over 3 mm of Z.
    fn steep() -> Pass {
        Pass {
            z1: -35_000_000,
            ..face()
        }
    }

    // -- §2: the lead-in --

    #[test]
    fn lead_in_counts_by_hand() {
        // K = 1.5 mm, n = 600, N = 4096, a = 500:
        // 1.5 · 360 000 · 4096 / (3600 · 500) = 2 211 840 000 / 1 800 000
        // = 1228.8 → 1229 → even 1230.
        assert_eq!(lead_in_counts(15_000_000, 600, 4096, 500), 1230);
        // K = 2 mm, n = 300, N = 4096, a = 1000:
        // 2 · 90 000 · 4096 / 3 600 000 = 204.8 → 205 → 206.
        assert_eq!(lead_in_counts(20_000_000, 300, 4096, 1000), 206);
        // K = 1 mm, n = 600, N = 4096, a = 1000:
        // 360 000 · 4096 / 3 600 000 = 409.6 → 410, already even.
        assert_eq!(lead_in_counts(10_000_000, 600, 4096, 1000), 410);
        // K = 1 mm, n = 600, N = 1000, a = 100:
        // 360 000 · 1000 / 360 000 = 1000 exactly: no rounding up.
        assert_eq!(lead_in_counts(10_000_000, 600, 1000, 100), 1000);
        // K = 1 mm, n = 60, N = 999, a = 1: 3600 · 999 / 3600 = 999 exactly,
        // odd → 1000.
        assert_eq!(lead_in_counts(10_000_000, 60, 999, 1), 1000);
        // One more count of need past an exact even value: 1000 + ε → 1002.
        // K = 1 mm + 10⁻⁷ mm: 1.0000001 · 360 000 · 1000 / 360 000 = 1000.0001.
        assert_eq!(lead_in_counts(10_000_001, 600, 1000, 100), 1002);
        // K = 0.1 mm, n = 1, N = 4, a = 1000: 0.4 / 3 600 000 → 1 → at least 2.
        assert_eq!(lead_in_counts(1_000_000, 1, 4, 1000), 2);
        // A spindle at rest needs no lead-in but gets the least one.
        assert_eq!(lead_in_counts(15_000_000, 0, 4096, 500), 2);
    }

    #[test]
    fn lead_in_counts_is_the_least_even_bound() {
        let mut rng = Rng(0x5EED_0001);
        for _ in 0..2000 {
            let (k, n, cpr, a) = (
                rng.range(1, LEAD_MAX),
                rng.range(0, 10_000),
                rng.range(1, CPR_MAX),
                rng.range(1, 20_000),
            );
            let c = lead_in_counts(k, n, cpr, a);
            let need = |c: i64| {
                // C ≥ K·n²·N / (3600·a·10^7)
                c as u128 * 3600 * a as u128 * 10_000_000
                    >= k as u128 * (n * n) as u128 * cpr as u128
            };
            assert!(c >= 2 && c % 2 == 0 && need(c), "{k} {n} {cpr} {a}: {c}");
            assert!(c == 2 || !need(c - 2), "{k} {n} {cpr} {a}: {c} not least");
        }
    }

    // -- §1: the progress and the registers --

    #[test]
    fn registers_follow_the_table_at_every_count() {
        for p in [straight_z(), taper(), face(), steep(), short_but_enough()] {
            let half = p.lead_in / 2;
            let end = (travel(&p) * i128::from(p.cpr) / i128::from(p.lead)) as i64 + half;
            for c in (-half - 3)..=(end + 3) {
                assert_eq!(registers(&p, c), table_registers(&p, c), "{p:?} at {c}");
            }
        }
    }

    #[test]
    fn registers_rest_at_p0_before_and_at_p1_after() {
        let p = taper();
        let at_p0 = (q(p.x0.into(), p.hx.into()), q(p.z0.into(), p.hz.into()));
        let at_p1 = (q(p.x1.into(), p.hx.into()), q(p.z1.into(), p.hz.into()));
        assert_eq!(registers(&p, -p.lead_in / 2), at_p0);
        assert_eq!(registers(&p, -1_000_000_000), at_p0);
        assert_eq!(registers(&p, 1_000_000_000), at_p1);
        // Half-way through the lead-in, s = u·C/8 = 125 732.4: z = −0.0126 mm.
        assert_eq!(registers(&p, 0), (2000, -1));
    }

    /// The widest passes the module accepts: lock and lead-in against plain
    /// `i128` formulas, the lead-out by the point symmetry of a pass whose
    /// `D/u` is whole and whose ends are opposite (`P1 = −P0`).
    #[test]
    fn registers_are_exact_at_the_edges_of_the_range() {
        let k: i64 = 1 << 31;
        let n: i64 = 65_536;
        // D = 2^15 · 610 351, so D·N/K = 610 351 counts.
        let d: i64 = (1 << 15) * 610_351;
        let t: i64 = 610_351;
        let cc: i64 = 1 << 18;
        for (hx, hz, x0) in [(3, 7, -7_000_000_001), (1, PRICE_MAX, 9_999_990_784)] {
            let p = Pass {
                x0,
                z0: d / 2,
                x1: -x0,
                z1: -d / 2,
                hx,
                hz,
                lead: k,
                cpr: n,
                lead_in: cc,
            };
            assert_eq!(travel(&p), d.into());
            let (x0, z0, dx, dz) = (
                i128::from(p.x0),
                i128::from(p.z0),
                i128::from(p.x1 - p.x0),
                i128::from(p.z1 - p.z0),
            );
            let (k, n, cc, d, hx, hz) = (
                i128::from(k),
                i128::from(n),
                i128::from(cc),
                i128::from(d),
                i128::from(hx),
                i128::from(hz),
            );
            let half = cc / 2;
            // Lead-in: a = a0 + Δa·K·m² / (2·C·N·D), m = c + C/2.
            let lead_in = |c: i128| {
                let m = c + half;
                let den = 2 * cc * n * d;
                (
                    q(x0 * den + dx * k * m * m, den * hx),
                    q(z0 * den + dz * k * m * m, den * hz),
                )
            };
            // Lock: a = a0 + Δa·K·c / (N·D).
            let lock = |c: i128| {
                (
                    q(x0 * n * d + dx * k * c, n * d * hx),
                    q(z0 * n * d + dz * k * c, n * d * hz),
                )
            };
            let mut counts: Vec<i64> = (-half as i64..=half as i64).step_by(997).collect();
            counts.extend([-half as i64 + 1, half as i64 - 1, half as i64]);
            for &c in &counts {
                let r = registers(&p, c);
                assert_eq!(r, lead_in(c.into()), "lead-in at {c}");
                // The lead-out, mirrored: s(D/u − c) = D − s(c), and Q is odd.
                assert_eq!(registers(&p, t - c), (-r.0, -r.1), "lead-out at {}", t - c);
            }
            for c in (half as i64..=t - half as i64).step_by(4099) {
                assert_eq!(registers(&p, c), lock(c.into()), "lock at {c}");
            }
            assert_eq!(registers(&p, t + half as i64), (q(-x0, hx), q(-z0, hz)));
        }
    }

    // -- §3: the step events --

    #[test]
    fn a_straight_z_thread_locks_to_the_counts() {
        let p = straight_z();
        let ev = events(&p).unwrap();
        assert_ascending(&ev);
        let (k, n, z0, hz) = (
            i128::from(p.lead),
            i128::from(p.cpr),
            i128::from(p.z0),
            i128::from(p.hz),
        );
        let x = q(p.x0.into(), p.hx.into());
        // While locked the carriage is at z0 − c·K/N, at every count.
        let mut in_lock = 0;
        for c in p.lead_in / 2..60_000 {
            if locked(&p, c) {
                assert_eq!(registers(&p, c), (x, q(z0 * n - i128::from(c) * k, n * hz)));
            }
        }
        for &(c, ex, ez) in &ev {
            assert_eq!(ex, x, "X moves on a straight thread");
            if locked(&p, c) {
                in_lock += 1;
                assert_eq!(ez, q(z0 * n - i128::from(c) * k, n * hz), "at {c}");
            }
        }
        assert!(in_lock > 1900);
        // Z: Q(12 345 678 / 100 000) = 123 to Q(−187 654 322 / 100 000) = −1877.
        let nz = (q(p.z1.into(), hz) - q(z0, hz)).abs();
        assert_eq!(nz, 2000);
        assert_eq!(ev.len() as i64, nz);
        assert_eq!(steps_per_axis(&p, &ev), (0, 2000));
        assert_eq!(ev.last().map(|e| e.2), Some(-1877));
        assert!(ev.iter().all(|e| e.0 > -p.lead_in / 2));
    }

    #[test]
    fn a_taper_steps_each_axis_its_own_count() {
        let p = taper();
        let ev = events(&p).unwrap();
        assert_ascending(&ev);
        // X: Q(10^8 / 50 000) = 2000 to Q(90 000 123 / 50 000) = 1800; Z: 0 to −3000.
        assert_eq!(steps_per_axis(&p, &ev), (200, 3000));
        assert!(ev.len() >= 3000 && ev.len() <= 3200);
        let (k, n, d) = (i128::from(p.lead), i128::from(p.cpr), travel(&p));
        assert_eq!(d, 300_000_000, "Z leads");
        let (x0, dx, hx) = (i128::from(p.x0), i128::from(p.x1 - p.x0), i128::from(p.hx));
        let (z0, hz) = (i128::from(p.z0), i128::from(p.hz));
        for &(c, ex, ez) in &ev {
            if locked(&p, c) {
                let c = i128::from(c);
                assert_eq!(ez, q(z0 * n - c * k, n * hz));
                assert_eq!(ex, q(x0 * n * d + dx * k * c, n * d * hx));
            }
        }
        assert_eq!(ev, table_events(&p));
    }

    #[test]
    fn a_face_thread_leads_on_x() {
        for p in [face(), steep()] {
            let ev = events(&p).unwrap();
            assert_ascending(&ev);
            let (k, n, d) = (i128::from(p.lead), i128::from(p.cpr), travel(&p));
            assert_eq!(d, 100_000_000, "X leads");
            let (x0, hx) = (i128::from(p.x0), i128::from(p.hx));
            let (z0, dz, hz) = (i128::from(p.z0), i128::from(p.z1 - p.z0), i128::from(p.hz));
            let mut in_lock = 0;
            for &(c, ex, ez) in &ev {
                if locked(&p, c) {
                    in_lock += 1;
                    let c = i128::from(c);
                    // The cross slide is at x0 − c·K/N.
                    assert_eq!(ex, q(x0 * n - c * k, n * hx));
                    assert_eq!(ez, q(z0 * n * d + dz * k * c, n * d * hz));
                }
            }
            assert!(in_lock > 1900);
            // X: 3000 to 1000 impulses; Z: −50 (−0.5 mm) to −350 on the steep one.
            let nz = if p.z1 == p.z0 { 0 } else { 300 };
            assert_eq!(steps_per_axis(&p, &ev), (2000, nz));
        }
    }

    /// A pass of exactly `D = u·C`: lead-in straight into lead-out.
    fn short_but_enough() -> Pass {
        Pass {
            x0: 0,
            z0: 0,
            x1: 0,
            z1: -10_000,
            hx: 1500,
            hz: 1500,
            lead: 4_096_000,
            cpr: 4096,
            lead_in: 10,
        }
    }

    #[test]
    fn a_pass_of_exactly_u_c_has_events() {
        let p = short_but_enough();
        let ev = events(&p).unwrap();
        // Z: 0 to Q(−10 000 / 1500) = Q(−6.67) = −7, within counts −4 … 15.
        assert_eq!(steps_per_axis(&p, &ev), (0, 7));
        assert!(ev.iter().all(|e| (-4..=15).contains(&e.0)));
        assert_eq!(ev, table_events(&p));
    }

    /// The lead-in's events are the lead-out's mirrored, for a pass whose
    /// `D/u` is whole and whose registers are symmetric about its middle.
    #[test]
    fn the_lead_in_mirrors_the_lead_out() {
        // K = 1.5 mm, N = 4096, D = 9.375 mm: D·N/K = 25 600 counts.
        let straight = Pass {
            x0: 100_000_000,
            z0: 46_875_000,
            x1: 100_000_000,
            z1: -46_875_000,
            hx: 50_000,
            hz: 100_000,
            lead: 15_000_000,
            cpr: 4096,
            lead_in: 1230,
        };
        // Geometry only (the radius passes 0): both axes point-symmetric.
        let symmetric = Pass {
            x0: 30_025_000,
            x1: -30_025_000,
            ..straight
        };
        for p in [straight, symmetric] {
            let t = 25_600;
            assert_eq!(travel(&p) * 4096, 15_000_000 * i128::from(t));
            let half = p.lead_in / 2;
            let ev = events(&p).unwrap();
            let lead_in: Vec<_> = ev.iter().filter(|e| e.0 <= half).collect();
            let lead_out: Vec<_> = ev.iter().filter(|e| e.0 > t - half).collect();
            assert!(lead_in.len() > 10, "{}", lead_in.len());
            assert_eq!(lead_in.len(), lead_out.len());
            // The sum of the end registers: each register after a lead-out
            // event is that sum minus the register before its lead-in twin.
            let sum = (
                q(p.x0.into(), p.hx.into()) + q(p.x1.into(), p.hx.into()),
                q(p.z0.into(), p.hz.into()) + q(p.z1.into(), p.hz.into()),
            );
            for (a, b) in lead_in.iter().zip(lead_out.iter().rev()) {
                assert_eq!(b.0, t + 1 - a.0, "count of the twin of {a:?}");
                let before = registers(&p, a.0 - 1);
                assert_eq!((b.1, b.2), (sum.0 - before.0, sum.1 - before.1));
            }
        }
    }

    #[test]
    fn events_match_the_table_on_random_passes() {
        let mut rng = Rng(0xC0FF_EE00_0000_0001);
        let mut accepted = 0;
        let mut tried = 0;
        while accepted < 60 {
            tried += 1;
            assert!(tried < 10_000, "too few passes accepted");
            let coord = |rng: &mut Rng| rng.range(-20_000_000, 20_000_000);
            let (x0, z0) = (coord(&mut rng), coord(&mut rng));
            // Often a straight or a face thread.
            let x1 = if rng.range(0, 3) == 0 {
                x0
            } else {
                coord(&mut rng)
            };
            let z1 = if rng.range(0, 3) == 0 {
                z0
            } else {
                coord(&mut rng)
            };
            let prices = [10, 37, 1000, 5000, 12_345, 50_000, 100_000, 999_999];
            let hx = prices[rng.range(0, 7) as usize];
            let hz = prices[rng.range(0, 7) as usize];
            let cpr = rng.range(16, 512);
            let lead_in = 2 * rng.range(1, 50);
            let d = (z1 - z0).abs().max((x1 - x0).abs());
            let counts = rng.range(500, 5000);
            let lead = (d * cpr / counts).max(1);
            let p = Pass {
                x0,
                z0,
                x1,
                z1,
                hx,
                hz,
                lead,
                cpr,
                lead_in,
            };
            match events(&p) {
                Ok(ev) => {
                    accepted += 1;
                    assert_eq!(ev, table_events(&p), "{p:?}");
                    let nx = (q(x1.into(), hx.into()) - q(x0.into(), hx.into())).abs();
                    let nz = (q(z1.into(), hz.into()) - q(z0.into(), hz.into())).abs();
                    assert_eq!(steps_per_axis(&p, &ev), (nx, nz), "{p:?}");
                    assert_ascending(&ev);
                }
                Err(Refusal::NoTravel) => assert_eq!(d, 0),
                Err(Refusal::TooCoarse { .. } | Refusal::TooShort { .. }) => {}
            }
        }
    }

    // -- the refusals, and their order --

    #[test]
    fn no_travel_is_refused_first() {
        let p = Pass {
            x1: 200_000_000,
            z1: 12_345_678,
            lead: LEAD_MAX,
            ..straight_z()
        };
        assert_eq!(events(&p), Err(Refusal::NoTravel));
    }

    #[test]
    fn coarse_at_one_tenth_of_a_micron_past_the_impulse() {
        // h_Z = 0.01 mm at 4096 counts: K below 40.96 mm (§3).
        let p = Pass {
            x0: 0,
            z0: 0,
            x1: 0,
            z1: -50_000_000,
            hx: 50_000,
            hz: 100_000,
            lead: 409_600_001,
            cpr: 4096,
            lead_in: 2,
        };
        assert_eq!(events(&p), Err(Refusal::TooCoarse { axis: 'Z' }));
        // Equal is refused too (it could need two steps at one count).
        let p = Pass {
            lead: 409_600_000,
            ..p
        };
        assert_eq!(events(&p), Err(Refusal::TooCoarse { axis: 'Z' }));
        // Just below: at most one step at every locked count.
        let p = Pass {
            lead: 409_599_999,
            ..p
        };
        let ev = events(&p).unwrap();
        assert_eq!(ev.len(), 500);
        assert!(ev.windows(2).all(|w| w[0].0 < w[1].0));
    }

    #[test]
    fn coarse_checks_x_before_z_and_the_axis_that_does_not_lead() {
        // Δx = Δz = D = 1 mm: K·D = 5·10^13 > h·N·D = 4.096·10^13 on both axes.
        let both = Pass {
            x0: 20_000_000,
            z0: 0,
            x1: 10_000_000,
            z1: -10_000_000,
            hx: 1000,
            hz: 1000,
            lead: 5_000_000,
            cpr: 4096,
            lead_in: 2,
        };
        assert_eq!(events(&both), Err(Refusal::TooCoarse { axis: 'X' }));
        let z_only = Pass { hx: 2000, ..both };
        assert_eq!(events(&z_only), Err(Refusal::TooCoarse { axis: 'Z' }));
        // X does not lead (Δx = 0.1 mm over D = 1 mm): K·|Δx| = 5·10^12 against
        // hx·N·D = 4.096·10^12 at hx = 100, 5.038·10^12 at hx = 123.
        let follower = Pass {
            x0: 0,
            z0: 0,
            x1: 1_000_000,
            z1: -10_000_000,
            hx: 100,
            hz: 100_000,
            lead: 5_000_000,
            cpr: 4096,
            lead_in: 2,
        };
        assert_eq!(events(&follower), Err(Refusal::TooCoarse { axis: 'X' }));
        let fine = Pass {
            hx: 123,
            ..follower
        };
        let ev = events(&fine).unwrap();
        assert_eq!(steps_per_axis(&fine, &ev), (8130, 100));
    }

    #[test]
    fn too_short_needs_u_c_rounded_up() {
        // u·C = 15 000 000 · 1230 / 4096 = 4 504 394.53125 → 4 504 395.
        let base = Pass {
            x0: 0,
            z0: 0,
            x1: 0,
            z1: -4_504_394,
            hx: 50_000,
            hz: 100_000,
            lead: 15_000_000,
            cpr: 4096,
            lead_in: 1230,
        };
        assert_eq!(events(&base), Err(Refusal::TooShort { needed: 4_504_395 }));
        // The same length on X (a face thread) is as short.
        let face = Pass {
            x1: 4_504_394,
            z1: 0,
            ..base
        };
        assert_eq!(events(&face), Err(Refusal::TooShort { needed: 4_504_395 }));
        let enough = Pass {
            z1: -4_504_395,
            ..base
        };
        assert!(events(&enough).is_ok());
        // An exact need is not rounded: u = 1000, C = 10.
        let exact = Pass {
            z1: -9_999,
            lead: 4_096_000,
            lead_in: 10,
            ..base
        };
        assert_eq!(events(&exact), Err(Refusal::TooShort { needed: 10_000 }));
        // Too coarse is told before too short.
        let both = Pass { hz: 999, ..exact };
        assert_eq!(events(&both), Err(Refusal::TooCoarse { axis: 'Z' }));
    }

    // -- what the doc leaves open --

    /// §3 refuses `u·|Δaxis|/D > h_axis` and so allows equality, but with
    /// ties away from zero the bins of `Q` next to 0 are `(−1.5, −0.5]` and
    /// `[0.5, 1.5)`: an axis moving exactly `h` per count from `−h/2` to
    /// `+h/2` changes its register by 2 in one count.
    fn double_step() -> Pass {
        // u = 100 000 = h_Z, D·N/K = 21 counts, locked for c in 1 … 20.
        Pass {
            x0: 0,
            z0: 1_050_000,
            x1: 0,
            z1: -1_050_000,
            hx: 50_000,
            hz: 100_000,
            lead: 409_600_000,
            cpr: 4096,
            lead_in: 2,
        }
    }

    #[test]
    fn equal_coarseness_can_need_two_steps_at_one_count() {
        let p = double_step();
        assert_eq!(registers(&p, 10), (0, 1)); // z = +50 000: Q(0.5) = 1
        assert_eq!(registers(&p, 11), (0, -1)); // z = −50 000: Q(−0.5) = −1
    }

    #[test]
    fn equal_coarseness_is_refused() {
        assert_eq!(
            events(&double_step()),
            Err(Refusal::TooCoarse { axis: 'Z' })
        );
    }

    // -- the 256-bit arithmetic --

    #[test]
    fn wide_products_and_quotients() {
        let max = u128::MAX;
        // (2^128 − 1)² = 2^256 − 2^129 + 1.
        assert_eq!(U256::product(max, max), U256 { hi: max - 1, lo: 1 });
        let a = 0xDEAD_BEEF_0123_4567_89AB_CDEF_F00D_u128;
        let b = 0x1_2345_6789_ABCD_EF01_2345_u128;
        let ab = U256::product(a, b);
        assert_eq!(ab.div(U256 { hi: 0, lo: b }), U256 { hi: 0, lo: a });
        assert_eq!(ab.div(U256 { hi: 0, lo: a }), U256 { hi: 0, lo: b });
        assert_eq!(
            ab.add(U256 { hi: 0, lo: b - 1 })
                .div(U256 { hi: 0, lo: b })
                .lo,
            a
        );
        assert_eq!(
            ab.add(U256 { hi: 0, lo: b }).div(U256 { hi: 0, lo: b }).lo,
            a + 1
        );
        // Q against exact::q_div wherever i128 holds the operands.
        let mut rng = Rng(0xABCD_0042);
        for _ in 0..20_000 {
            let shift = rng.range(0, 60) as u32;
            let n = i128::from(rng.range(-(1 << 40), 1 << 40)) << shift;
            let m = i128::from(rng.range(-(1 << 30), 1 << 30));
            let d = i128::from(rng.range(1, 1 << 40)) << rng.range(0, 40);
            let half_tie = if rng.range(0, 3) == 0 { d / 2 } else { 0 };
            let wide = wide_add(wide_mul(n, 1), wide_mul(m, d));
            let wide = wide_add(wide, wide_mul(half_tie, 1));
            let narrow = n + m * d + half_tie;
            assert_eq!(
                q_wide(
                    wide,
                    U256 {
                        hi: 0,
                        lo: d as u128
                    }
                ),
                q_div(narrow, d),
                "{narrow} / {d}"
            );
        }
    }

    /// xorshift64*, so the tests need no generator crate.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        /// Uniform enough in `lo..=hi`.
        fn range(&mut self, lo: i64, hi: i64) -> i64 {
            lo + (self.next() % (hi - lo + 1) as u64) as i64
        }
    }
}

//! Arcs: by chords with residual carry (`docs/arcs.md` §1), and step by step
//! as the ЭМ-907's circular interpolator does (`docs/arcs.md` §2).
//!
//! Coordinates are exact [`Length`]s: X on the radius, Z. Angles lie in the
//! (Z to the right, X up) plane, `φ = atan2(X − Xc, Z − Zc)`; counter-clockwise
//! (G03) increases φ.
//!
//! # Chords
//! The approximation angle is `Δφ = 2·arccos(1 − σ/R)`, computed as
//! `4·atan2(√σ, √(2R − σ))` with [`crate::trig`], then taken in whole
//! arc-seconds: floor for finishing (no chord deviates more than σ), ceiling
//! for roughing. `n = ⌈sweep/Δφ⌉`; chord ends `1 … n−1` are the start vector
//! rotated by `i·Δφ` about the centre, chord `n` ends on the commanded end.
//! Each chord end is kept with 62 fractional bits of an ångström and quantized
//! with the carry rule, so the arc's impulses do not depend on how it is cut
//! into blocks.
//!
//! # Direct (ЭМ-907)
//! In impulses: `J`, `K` the unsigned distances from the centre to the start;
//! the arc must stay within one quadrant (as the ЭМ-907 requires): a full
//! circle, or a centre within half an impulse of the start, is refused. An
//! arc too short to issue an impulse is an empty motion, as a short `MOVE` is. Each step
//! moves X, Z or both in the fixed directions of that quadrant, choosing the
//! candidate nearest the circle by `|F|`, `F = (a·hx)² + (b·hz)² − R²`
//! (a, b the position relative to the centre in impulses, R from the start),
//! ties in the order diagonal, X, Z; an axis stops when it has issued its
//! impulses, so the arc ends exactly on the end point.

use crate::impulse::{ImpulsePrice, Impulses, RangeError, MAX_BLOCK_IMPULSES, MAX_POSITION};
use crate::interleave::{ImpulsePoint, StepEvent};
use crate::length::Length;
use crate::trig::{atan2, isqrt, sin_cos_arcsec};
use crate::wide::{checked_divrem_i128, divrem_u128};
use core::num::NonZeroU128;

/// The most chords one arc may be cut into.
pub const MAX_CHORDS: u32 = 10_000;

/// The largest radius mismatch accepted: 0.002 mm, in ångström.
const MISMATCH_ANGSTROM: u128 = 20_000;

/// Direction of travel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ArcDir {
    /// G02.
    Cw,
    /// G03.
    Ccw,
}

/// Why an arc was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ArcError {
    /// Impossible geometry (`ERR GEOMETRY`).
    Geometry(&'static str),
    /// Beyond the machine's limits (`ERR RANGE`).
    Range(&'static str),
}

/// Start, end and centre, as exact coordinates `[X radius, Z]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArcPoints {
    /// Start.
    pub start: [Length; 2],
    /// Commanded end.
    pub end: [Length; 2],
    /// Centre.
    pub centre: [Length; 2],
}

impl ArcPoints {
    /// Checks that start and end lie on one circle about the centre (radii
    /// not zero, apart by at most 0.002 mm).
    pub fn check_radii(&self) -> Result<(), ArcError> {
        radii(self).map(|_| ())
    }
}

/// Vectors from the centre, in ångström, and their checked radii.
struct Radii {
    u: [i64; 2],
    v: [i64; 2],
    /// Start radius · 2²⁰ Å.
    r0_q20: u128,
}

fn radii(p: &ArcPoints) -> Result<Radii, ArcError> {
    let d = |a: Length, b: Length| a.as_angstrom() - b.as_angstrom();
    // |coordinates| < 10¹² Å, so differences fit easily.
    let u = [d(p.start[0], p.centre[0]), d(p.start[1], p.centre[1])];
    let v = [d(p.end[0], p.centre[0]), d(p.end[1], p.centre[1])];
    let sq = |w: [i64; 2]| {
        let (x, z) = (i128::from(w[0]), i128::from(w[1]));
        (x * x + z * z) as u128
    };
    let (r0s, r1s) = (sq(u), sq(v));
    if r0s == 0 || r1s == 0 {
        return Err(ArcError::Geometry("zero radius"));
    }
    // R · 2²⁰ Å: exact for whole-ångström radii.
    let (r0, r1) = (u128::from(isqrt(r0s << 40)), u128::from(isqrt(r1s << 40)));
    if r0.abs_diff(r1) > MISMATCH_ANGSTROM << 20 {
        return Err(ArcError::Geometry(
            "start and end radii differ by more than 0.002 mm",
        ));
    }
    Ok(Radii { u, v, r0_q20: r0 })
}

/// The centre of an arc given by its radius (G-code `R`, lecture 13 method 3).
///
/// Sign convention (as on Fanuc and Haas lathes): `R > 0` takes the arc of at
/// most 180°, `R < 0` the longer one. For G03 (counter-clockwise) with
/// `R > 0` the centre lies left of the chord from start to end, seen in the
/// (Z to the right, X up) plane; G02 or a negative `R` takes the other side.
/// The centre is rounded once, to the nearest ångström (10⁻⁷ mm); the arc
/// then runs as if given by that centre.
///
/// ```
/// use core_nostd::arc::{centre_from_radius, ArcDir};
/// use core_nostd::length::Length;
/// let mm = |s| Length::from_mm_str(s).unwrap();
/// // Krylenko Fig. 22: G03 X12 Z-2.4 R2.4 from X7.2 Z0 (radii 3.6 → 6).
/// let c = centre_from_radius([mm("3.6"), mm("0")], [mm("6"), mm("-2.4")], mm("2.4"), ArcDir::Ccw).unwrap();
/// assert_eq!(c, [mm("3.6"), mm("-2.4")]);
/// ```
pub fn centre_from_radius(
    start: [Length; 2],
    end: [Length; 2],
    r: Length,
    dir: ArcDir,
) -> Result<[Length; 2], ArcError> {
    let a = |l: Length| i128::from(l.as_angstrom());
    let (dx, dz) = (a(end[0]) - a(start[0]), a(end[1]) - a(start[1]));
    let d2 = dx * dx + dz * dz;
    if d2 == 0 {
        return Err(ArcError::Geometry(
            "an R arc needs an end point apart from its start",
        ));
    }
    let rr = a(r);
    let h2 = 4 * rr * rr - d2;
    if h2 < 0 {
        return Err(ArcError::Geometry(
            "radius smaller than half the distance to the end point",
        ));
    }
    // Centre = midpoint ± (left normal of the chord)·√(4R² − d²)/(2d).
    let num = i128::from(isqrt((h2 as u128) << 40));
    let den = i128::from(isqrt((d2 as u128) << 40));
    let left = match (dir, rr > 0) {
        (ArcDir::Ccw, true) | (ArcDir::Cw, false) => 1,
        _ => -1,
    };
    // Left of (dz, dx) in the (Z, X) plane is (−dx, dz).
    let round = |n: i128, d: i128| -> Option<i64> {
        let (q, r) = checked_divrem_i128(n, d)?;
        let q = if 2 * r.unsigned_abs() >= d.unsigned_abs() {
            q + n.signum() * d.signum()
        } else {
            q
        };
        i64::try_from(q).ok()
    };
    let beyond = ArcError::Range("arc centre beyond 99999.999999 mm");
    let cx = round((a(start[0]) + a(end[0])) * den + left * dz * num, 2 * den).ok_or(beyond)?;
    let cz = round((a(start[1]) + a(end[1])) * den - left * dx * num, 2 * den).ok_or(beyond)?;
    Ok([
        Length::from_angstrom(cx).ok_or(beyond)?,
        Length::from_angstrom(cz).ok_or(beyond)?,
    ])
}

/// An arc cut into chords, ready to give its chord ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChordPlan {
    centre: [i64; 2],
    u: [i64; 2],
    end: [Length; 2],
    dir: ArcDir,
    dphi_arcsec: u32,
    n: u32,
}

impl ChordPlan {
    /// Plans the chords of an arc with chord tolerance `tol` (σ), rounding
    /// the approximation angle down when `finish`, up otherwise.
    pub fn new(p: &ArcPoints, dir: ArcDir, tol: Length, finish: bool) -> Result<Self, ArcError> {
        let r = radii(p)?;
        let sigma = tol.as_angstrom().unsigned_abs() as u128;
        if sigma == 0 {
            return Err(ArcError::Geometry("zero chord tolerance"));
        }
        // Δφ in turns (u128: 360° = 2⁶⁴ fits).
        let a = sigma << 20;
        let dphi_turn: u128 = if a >= 2 * r.r0_q20 {
            1 << 64
        } else {
            let b = 2 * r.r0_q20 - a;
            // Both below 2⁶³; scaled by 2⁶⁴ their roots keep 62+ bits.
            let y = isqrt(a << 64);
            let x = isqrt(b << 64);
            u128::from(atan2(i128::from(y), i128::from(x)).0) * 4
        };
        let exact = dphi_turn * 1_296_000; // arc-seconds · 2⁶⁴
        let dphi = if finish {
            exact >> 64
        } else {
            (exact + (1 << 64) - 1) >> 64
        }
        .min(1_296_000) as u32;
        if dphi == 0 {
            return Err(ArcError::Range("chord angle below one arc-second"));
        }
        // Sweep from the start vector to the end vector in the direction of travel.
        let (u, v) = (r.u, r.v);
        let (uz, ux, vz, vx) = (
            i128::from(u[1]),
            i128::from(u[0]),
            i128::from(v[1]),
            i128::from(v[0]),
        );
        let ccw_angle = atan2(uz * vx - ux * vz, uz * vz + ux * vx).0;
        let sweep: u128 = match (dir, ccw_angle) {
            (_, 0) => 1 << 64,
            (ArcDir::Ccw, a) => u128::from(a),
            (ArcDir::Cw, a) => (1u128 << 64) - u128::from(a),
        };
        let step = u128::from(dphi) << 64;
        // step ≥ 2⁶⁴: the division is defined.
        let n = match NonZeroU128::new(step) {
            Some(step) => divrem_u128(sweep * 1_296_000 + step.get() - 1, step).0,
            None => return Err(ArcError::Range("chord angle below one arc-second")),
        };
        if n > u128::from(MAX_CHORDS) {
            return Err(ArcError::Range("arc needs more than 10000 chords"));
        }
        Ok(ChordPlan {
            centre: [p.centre[0].as_angstrom(), p.centre[1].as_angstrom()],
            u,
            end: p.end,
            dir,
            dphi_arcsec: dphi,
            n: n as u32,
        })
    }

    /// Number of chords.
    pub const fn chords(&self) -> u32 {
        self.n
    }

    /// The approximation angle used, in whole arc-seconds.
    pub const fn dphi_arcsec(&self) -> u32 {
        self.dphi_arcsec
    }

    /// The impulse position at the end of chord `i` (1 … n) with the carry
    /// rule; chord `n` ends on the commanded end.
    pub fn chord_end(
        &self,
        i: u32,
        hx: ImpulsePrice,
        hz: ImpulsePrice,
    ) -> Result<ImpulsePoint, RangeError> {
        self.chord_point(i, hx, hz).map(|(p, _)| p)
    }

    /// The end of chord `i` (1 … n): its impulse position with the carry
    /// rule (of the point as computed, to 2⁻⁶² Å), and the point rounded half
    /// away from zero to the 10⁻⁷ mm grid, in ångström · 2³², as the planner
    /// times it (`docs/motion.md`; chord `n` ends exactly on the commanded
    /// end).
    pub fn chord_point(
        &self,
        i: u32,
        hx: ImpulsePrice,
        hz: ImpulsePrice,
    ) -> Result<(ImpulsePoint, [i128; 2]), RangeError> {
        if i >= self.n {
            let q = |l: Length| i128::from(l.as_angstrom()) << 32;
            return Ok((
                ImpulsePoint {
                    x: crate::impulse::quantize(self.end[0], hx)?,
                    z: crate::impulse::quantize(self.end[1], hz)?,
                },
                [q(self.end[0]), q(self.end[1])],
            ));
        }
        // i·Δφ < n·Δφ ≤ 10⁴ · 1 296 000″: fits.
        let (s, c) = sin_cos_arcsec(i64::from(i) * i64::from(self.dphi_arcsec));
        let s = match self.dir {
            ArcDir::Ccw => i128::from(s),
            ArcDir::Cw => -i128::from(s),
        };
        let c = i128::from(c);
        let (ux, uz) = (i128::from(self.u[0]), i128::from(self.u[1]));
        // Rotate (z, x) by the angle: z' = z·c − x·s, x' = z·s + x·c (Å·2⁶²).
        let z = (i128::from(self.centre[1]) << 62) + uz * c - ux * s;
        let x = (i128::from(self.centre[0]) << 62) + uz * s + ux * c;
        // Å·2⁶² to whole Å (half away from zero), as Å·2³².
        let q32 = |v: i128| {
            let m = ((v.unsigned_abs() + (1 << 61)) >> 62) as i128;
            (if v < 0 { -m } else { m }) << 32
        };
        Ok((
            ImpulsePoint {
                x: quantize_q62(x, hx)?,
                z: quantize_q62(z, hz)?,
            },
            [q32(x), q32(z)],
        ))
    }
}

/// `Q(p / h)` for a coordinate in ångström · 2⁶².
fn quantize_q62(p: i128, h: ImpulsePrice) -> Result<Impulses, RangeError> {
    let d = i128::from(h.as_angstrom()) << 62;
    // A price is at least 10 Å: d > 0.
    let Some((q, r)) = checked_divrem_i128(p, d) else {
        return Err(RangeError);
    };
    let n = if 2 * r.unsigned_abs() >= d.unsigned_abs() {
        q + p.signum()
    } else {
        q
    };
    if n.unsigned_abs() <= MAX_POSITION as u128 {
        Ok(Impulses(n as i32))
    } else {
        Err(RangeError)
    }
}

/// A direct (step-by-step) arc in impulses, validated: within one quadrant,
/// at most [`MAX_BLOCK_IMPULSES`] per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DirectArc {
    from: ImpulsePoint,
    to: ImpulsePoint,
    /// Start relative to the centre, impulses.
    a0: i64,
    b0: i64,
    j: u32,
    k: u32,
    hx2: i128,
    hz2: i128,
    /// Start radius in ångström · 2²⁰, for feed words.
    r_q20: u128,
    dir: ArcDir,
}

impl DirectArc {
    /// Converts an arc to the ЭМ-907's terms and checks it: `from` the
    /// current impulse position, the rest from the exact geometry.
    pub fn new(
        p: &ArcPoints,
        dir: ArcDir,
        from: ImpulsePoint,
        hx: ImpulsePrice,
        hz: ImpulsePrice,
    ) -> Result<Self, ArcError> {
        let r = radii(p)?;
        let range = |_| ArcError::Range("position beyond 999999999 impulses");
        let to = ImpulsePoint {
            x: crate::impulse::quantize(p.end[0], hx).map_err(range)?,
            z: crate::impulse::quantize(p.end[1], hz).map_err(range)?,
        };
        // J, K: |I|/hx and |K|/hz, rounded; the centre lies on the side of
        // the start the I/K vector points to.
        let ij = |d: i64, h: ImpulsePrice| -> Result<(i64, u32), ArcError> {
            let q = crate::impulse::quantize(
                Length::from_angstrom(d.unsigned_abs() as i64)
                    .ok_or(ArcError::Range("radius beyond range"))?,
                h,
            )
            .map_err(range)?;
            let m = q.get().unsigned_abs();
            Ok((if d < 0 { -i64::from(m) } else { i64::from(m) }, m))
        };
        // Centre relative to start = −u.
        let (cx, j) = ij(-r.u[0], hx)?;
        let (cz, k) = ij(-r.u[1], hz)?;
        let (a0, b0) = (-cx, -cz);
        let a1 = i64::from(to.x.get()) - (i64::from(from.x.get()) + cx);
        let b1 = i64::from(to.z.get()) - (i64::from(from.z.get()) + cz);
        let dx = i64::from(to.x.get()) - i64::from(from.x.get());
        let dz = i64::from(to.z.get()) - i64::from(from.z.get());
        if dx.unsigned_abs() > u64::from(MAX_BLOCK_IMPULSES)
            || dz.unsigned_abs() > u64::from(MAX_BLOCK_IMPULSES)
        {
            return Err(ArcError::Range("block beyond 1000000 impulses per axis"));
        }
        let quadrant = "a direct arc must stay within one quadrant";
        // A full circle spans four quadrants; a centre within half an impulse
        // of the start has none.
        if p.end == p.start || (j == 0 && k == 0) {
            return Err(ArcError::Geometry(quadrant));
        }
        // One quadrant: a and b keep their signs (zero allowed at an end).
        if a0.signum() * a1.signum() < 0 || b0.signum() * b1.signum() < 0 {
            return Err(ArcError::Geometry(quadrant));
        }
        let qa = if a0 != 0 { a0.signum() } else { a1.signum() };
        let qb = if b0 != 0 { b0.signum() } else { b1.signum() };
        // Counter-clockwise in (Z, X): X moves with sign(b), Z with −sign(a).
        let d = match dir {
            ArcDir::Ccw => 1,
            ArcDir::Cw => -1,
        };
        let agrees = |delta: i64, want: i64| delta == 0 || delta.signum() == want;
        if !agrees(dx, qb * d) || !agrees(dz, -qa * d) {
            return Err(ArcError::Geometry(quadrant));
        }
        let (hxa, hza) = (i128::from(hx.as_angstrom()), i128::from(hz.as_angstrom()));
        Ok(DirectArc {
            from,
            to,
            a0,
            b0,
            j,
            k,
            hx2: hxa * hxa,
            hz2: hza * hza,
            r_q20: r.r0_q20,
            dir,
        })
    }

    /// The ЭМ-907's `J` (X) and `K` (Z): unsigned distances from the centre
    /// to the start, in impulses.
    pub const fn jk(&self) -> (u32, u32) {
        (self.j, self.k)
    }

    /// Impulses issued on X and Z.
    pub const fn delta(&self) -> (i32, i32) {
        (self.to.x.0 - self.from.x.0, self.to.z.0 - self.from.z.0)
    }

    /// End position.
    pub const fn to(&self) -> ImpulsePoint {
        self.to
    }

    /// Direction.
    pub const fn dir(&self) -> ArcDir {
        self.dir
    }

    /// The ЭМ-907 feed word `F = S·10³/R` for a feed `s` (mm/min), R the
    /// start radius, rounded half away from zero.
    pub fn feed_word(&self, s: Length) -> u64 {
        feed_word(s, self.r_q20)
    }

    /// The step events, one at a time.
    pub fn events(&self) -> DirectSteps {
        let (dx, dz) = self.delta();
        DirectSteps {
            a: self.a0,
            b: self.b0,
            // F is zero at the start by the choice of R.
            f: 0,
            nx: dx.unsigned_abs(),
            nz: dz.unsigned_abs(),
            sx: if dx < 0 { -1 } else { 1 },
            sz: if dz < 0 { -1 } else { 1 },
            hx2: self.hx2,
            hz2: self.hz2,
        }
    }
}

/// `F = S·10³/R`, S in mm/min, R in ångström · 2²⁰; rounded half away from zero.
fn feed_word(s: Length, r_q20: u128) -> u64 {
    let s = s.as_angstrom().unsigned_abs() as u128; // 10⁻⁷ mm/min
    if r_q20 == 0 {
        return 0;
    }
    // S·1000/R with S and R in the same unit: (s·1000·2²⁰)/r_q20.
    let num = (s * 1000) << 20;
    match NonZeroU128::new(2 * r_q20) {
        Some(d) => divrem_u128(2 * num + r_q20, d).0 as u64,
        None => 0,
    }
}

/// The ЭМ-907 feed word of a linear block, `F = S·10³/l`, `l` the block's
/// length from its X (radius) and Z increments; `None` for an empty block.
///
/// ```
/// use core_nostd::{arc::linear_feed_word, length::Length};
/// let mm = |s| Length::from_mm_str(s).unwrap();
/// // 213 mm/min over a 3-4-5 block of 5 mm: 42 600.
/// assert_eq!(linear_feed_word(mm("213"), mm("3"), mm("-4")), Some(42_600));
/// ```
pub fn linear_feed_word(s: Length, dx: Length, dz: Length) -> Option<u64> {
    let (x, z) = (i128::from(dx.as_angstrom()), i128::from(dz.as_angstrom()));
    let l2 = (x * x + z * z) as u128;
    if l2 == 0 {
        return None;
    }
    Some(feed_word(s, u128::from(isqrt(l2 << 40))))
}

/// The step events of a [`DirectArc`].
#[derive(Clone, Debug)]
pub struct DirectSteps {
    a: i64,
    b: i64,
    /// `F(a, b)` relative to the start's, Å².
    f: i128,
    nx: u32,
    nz: u32,
    sx: i64,
    sz: i64,
    hx2: i128,
    hz2: i128,
}

impl Iterator for DirectSteps {
    type Item = StepEvent;

    fn next(&mut self) -> Option<StepEvent> {
        if self.nx == 0 && self.nz == 0 {
            return None;
        }
        // ΔF of one step: h²·(2a·s + 1) (s = ±1).
        let fx = self.hx2 * (2 * i128::from(self.a) * i128::from(self.sx) + 1);
        let fz = self.hz2 * (2 * i128::from(self.b) * i128::from(self.sz) + 1);
        let (cx, cz, cd) = (self.f + fx, self.f + fz, self.f + fx + fz);
        let (step_x, step_z) = match (self.nx > 0, self.nz > 0) {
            (true, true) => {
                let (d, x, z) = (cd.unsigned_abs(), cx.unsigned_abs(), cz.unsigned_abs());
                if d <= x && d <= z {
                    (true, true)
                } else if x <= z {
                    (true, false)
                } else {
                    (false, true)
                }
            }
            (true, false) => (true, false),
            _ => (false, true),
        };
        let mut bits = 0u8;
        if step_x {
            self.a += self.sx;
            self.f += fx;
            self.nx -= 1;
            bits |= StepEvent::X_STEP | if self.sx < 0 { StepEvent::X_NEG } else { 0 };
        }
        if step_z {
            self.b += self.sz;
            self.f += fz;
            self.nz -= 1;
            bits |= StepEvent::Z_STEP | if self.sz < 0 { StepEvent::Z_NEG } else { 0 };
        }
        Some(StepEvent::from_bits(bits))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn mm(s: &str) -> Length {
        Length::from_mm_str(s).unwrap()
    }

    fn pts(start: [&str; 2], end: [&str; 2], centre: [&str; 2]) -> ArcPoints {
        ArcPoints {
            start: [mm(start[0]), mm(start[1])],
            end: [mm(end[0]), mm(end[1])],
            centre: [mm(centre[0]), mm(centre[1])],
        }
    }

    const HX: ImpulsePrice = ImpulsePrice::DEFAULT_X;
    const HZ: ImpulsePrice = ImpulsePrice::DEFAULT_Z;

    fn ends(plan: &ChordPlan) -> Vec<ImpulsePoint> {
        (1..=plan.chords())
            .map(|i| plan.chord_end(i, HX, HZ).unwrap())
            .collect()
    }

    #[test]
    fn quarter_circle_by_hand() {
        // R10, σ 0.01: Δφ = 2·acos(0.999) = 18450.7″ → 18450″ finishing,
        // 18451″ roughing; 90° / Δφ = 17.56 → 18 chords.
        let p = pts(["0", "10"], ["10", "0"], ["0", "0"]);
        let fin = ChordPlan::new(&p, ArcDir::Ccw, mm("0.01"), true).unwrap();
        assert_eq!((fin.dphi_arcsec(), fin.chords()), (18_450, 18));
        let rough = ChordPlan::new(&p, ArcDir::Ccw, mm("0.01"), false).unwrap();
        assert_eq!(rough.dphi_arcsec(), 18_451);
        // The first chord end: R·(cos Δφ, sin Δφ) about the centre, in (Z, X).
        let e1 = fin.chord_end(1, HX, HZ).unwrap();
        let th = 18_450.0 / 206_264.806_247_096_36_f64;
        assert_eq!(e1.z.get(), (10.0 * libm::cos(th) / 0.01).round() as i32);
        assert_eq!(e1.x.get(), (10.0 * libm::sin(th) / 0.005).round() as i32);
        assert_eq!(
            ends(&fin).last().copied().unwrap(),
            ImpulsePoint {
                x: Impulses(2000),
                z: Impulses(0)
            }
        );
    }

    #[test]
    fn full_circle_closes() {
        for dir in [ArcDir::Ccw, ArcDir::Cw] {
            let p = pts(["12.345", "-3.21"], ["12.345", "-3.21"], ["2.345", "-3.21"]);
            let plan = ChordPlan::new(&p, dir, mm("0.005"), true).unwrap();
            let e = ends(&plan);
            assert_eq!(
                *e.last().unwrap(),
                ImpulsePoint {
                    x: Impulses(2469),
                    z: Impulses(-321)
                }
            );
            // Δφ = 2·acos(1 − 0.0005) = 13045.9″: ⌈1 296 000 / 13045⌉ = 100.
            assert_eq!((plan.dphi_arcsec(), plan.chords()), (13_045, 100));
        }
    }

    #[test]
    fn splitting_at_an_exact_chord_end_changes_nothing() {
        // Δφ = 1000″ divides 90°: the quarter points are exact chord ends.
        // σ = 0.000147 at R 50 gives Δφ = 2·acos(1 − σ/R) = 1000.3″.
        let sigma = mm("0.000147");
        let whole = pts(["0", "50"], ["0", "-50"], ["0", "0"]);
        let plan = ChordPlan::new(&whole, ArcDir::Ccw, sigma, true).unwrap();
        assert_eq!(plan.dphi_arcsec(), 1000);
        let first = ChordPlan::new(
            &pts(["0", "50"], ["50", "0"], ["0", "0"]),
            ArcDir::Ccw,
            sigma,
            true,
        )
        .unwrap();
        let second = ChordPlan::new(
            &pts(["50", "0"], ["0", "-50"], ["0", "0"]),
            ArcDir::Ccw,
            sigma,
            true,
        )
        .unwrap();
        let mut split = ends(&first);
        split.extend(ends(&second));
        assert_eq!(ends(&plan), split);
        assert_eq!(first.chords() + second.chords(), plan.chords());
    }

    #[test]
    fn radius_mismatch_limit_is_exact() {
        let ok = pts(["0", "5"], ["5.002", "0"], ["0", "0"]);
        assert!(ChordPlan::new(&ok, ArcDir::Ccw, mm("0.01"), true).is_ok());
        // 5.0020001 mm: a tenth of a nanometre beyond.
        let bad = ArcPoints {
            end: [Length::from_angstrom(50_020_001).unwrap(), Length::ZERO],
            ..ok
        };
        assert_eq!(
            ChordPlan::new(&bad, ArcDir::Ccw, mm("0.01"), true),
            Err(ArcError::Geometry(
                "start and end radii differ by more than 0.002 mm"
            ))
        );
        let zero = pts(["1", "1"], ["2", "2"], ["1", "1"]);
        assert_eq!(
            ChordPlan::new(&zero, ArcDir::Ccw, mm("0.01"), true),
            Err(ArcError::Geometry("zero radius"))
        );
        let many = pts(["0", "1000"], ["0", "1000"], ["0", "0"]);
        assert!(matches!(
            ChordPlan::new(&many, ArcDir::Ccw, mm("0.000001"), true),
            Err(ArcError::Range(_))
        ));
    }

    #[test]
    fn the_seed_sphere_block() {
        // Ø50 sphere, R 25: start 21.986134 above the axis and 11.9 right of
        // the centre, to the top. J4397 K1190, F = 35.5·10³/25 = 1420.
        let p = pts(["21.986134", "11.9"], ["25", "0"], ["0", "0"]);
        let from = ImpulsePoint {
            x: Impulses(4397),
            z: Impulses(1190),
        };
        let arc = DirectArc::new(&p, ArcDir::Ccw, from, HX, HZ).unwrap();
        assert_eq!(arc.jk(), (4397, 1190));
        assert_eq!(arc.delta(), (603, -1190));
        assert_eq!(arc.feed_word(mm("35.5")), 1420);
        assert!(DirectArc::new(&p, ArcDir::Cw, from, HX, HZ).is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Direct arcs end on the end point, move monotonically, and stay
        /// within two coarse impulses of the circle: the start register, J,
        /// K and the end register are each rounded, so the end may lie up to
        /// about 1.5 impulses per axis off the impulse circle, and the last
        /// steps are forced towards it.
        #[test]
        fn direct_steps_hug_the_circle(r_um in 1_000i64..100_000, a0 in 0.0f64..1.5, sweep in 0.05f64..1.5, ccw: bool) {
            let a1 = if ccw { (a0 + sweep).min(core::f64::consts::FRAC_PI_2 - 1e-4) } else { (a0 - sweep).max(0.0) };
            let r = r_um as f64 / 1000.0;
            let at = |a: f64| [
                Length::from_angstrom((r * libm::sin(a) * 1e4).round() as i64 * 1000).unwrap(),
                Length::from_angstrom((r * libm::cos(a) * 1e4).round() as i64 * 1000).unwrap(),
            ];
            let p = ArcPoints { start: at(a0), end: at(a1), centre: [Length::ZERO; 2] };
            let from = ImpulsePoint {
                x: crate::impulse::quantize(p.start[0], HX).unwrap(),
                z: crate::impulse::quantize(p.start[1], HZ).unwrap(),
            };
            let dir = if ccw { ArcDir::Ccw } else { ArcDir::Cw };
            let Ok(arc) = DirectArc::new(&p, dir, from, HX, HZ) else { return Ok(()); };
            let (mut x, mut z) = (i64::from(from.x.get()), i64::from(from.z.get()));
            let (j, k) = arc.jk();
            let (cx, cz) = (x - i64::from(j), z - i64::from(k));
            let r0 = libm::hypot(j as f64 * 0.005, k as f64 * 0.01);
            for e in arc.events() {
                if e.x_steps() { x += if e.x_negative() { -1 } else { 1 }; }
                if e.z_steps() { z += if e.z_negative() { -1 } else { 1 }; }
                let dev = (libm::hypot((x - cx) as f64 * 0.005, (z - cz) as f64 * 0.01) - r0).abs();
                prop_assert!(dev <= 0.02, "{dev}");
                prop_assert!(x >= cx && z >= cz);
            }
            prop_assert_eq!((x, z), (i64::from(arc.to().x.get()), i64::from(arc.to().z.get())));
        }
    }
}

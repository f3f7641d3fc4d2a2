//! Double-precision (f64) reference of arcs: arcs by chords (`ARC`) and the
//! ЭМ-907 circular interpolator (`ARC … MODE=DIRECT`).
//!
//! Written from `docs/arcs.md` §1–§2, `docs/impulses.md` §2–§3,
//! `docs/units.md` §1–§3, `docs/tapes.md` §1.1 (the feed word),
//! `docs/verification.md` §2 and the `ARC` command of `docs/protocol.md` §4
//! alone, independently of the controller's fixed-point core, so that the two
//! can be compared bit for bit. It extends the linear-block
//! reference of [`crate::impulse`] and shares its machine state
//! ([`RefMachine`]), its quantizer and its step interleaver.
//!
//! # Arcs by chords ([`RefMachine::arc`])
//!
//! * `S` is the current commanded point (exact), `C = S + (I, K)`, `E` the end
//!   point (absolute words; `X` is a diameter when `DIAM=1`, `I` and `K` are
//!   always radius values). `R0 = |S − C|`, `R1 = |E − C|`. `R0 = 0`, `R1 = 0`
//!   or `|R0 − R1| > 0.002 mm` is refused (`GEOMETRY`); the mismatch test is
//!   exact (integers), so `R0 = 5`, `R1 = 5.002` passes and anything above
//!   fails.
//! * Angles `φ = atan2(X − Xc, Z − Zc)` in the (Z right, X up) plane; CCW
//!   (G03) increases `φ`. The sweep is in `(0°, 360°]`; `E = S`, or `E` in the
//!   same direction from `C` as `S`, is a full circle.
//! * `Δφ_exact = 2·acos(max(1 − σ/R0, −1))` (`σ = TOL`) in arc-seconds,
//!   floored for finishing and ceiled for roughing, capped at 360°; `Δφ = 0`
//!   is refused (`RANGE`). It is evaluated as the equal
//!   `4·asin(√(σ/(2·R0)))`, which keeps its accuracy for small `σ/R0`
//!   (`1 − σ/R0` would lose the digits of `σ/R0` that decide the floor).
//! * `n = ⌈sweep/Δφ⌉` chords (`n > 10 000` refused, `RANGE`); chord ends
//!   `i = 1 … n−1` are `C + R0·(cos, sin)(φS ± i·Δφ)`, computed as the start
//!   vector `S − C` rotated by `±i·Δφ`; chord `n` ends exactly at `E`.
//! * Each chord end is quantized absolutely (`Q(P/h)`, ties away from zero)
//!   and each chord is interleaved as a linear block
//!   ([`crate::impulse::step_events`]). `SEQ` is the CRC-32 over all
//!   chords' step bytes in order. The commanded point becomes `E` exactly
//!   and the registers `Q(E/h)`, as after a linear block to `E`.
//!
//! ## Exact values and tie margins
//!
//! The decisions that could be exact are made exactly:
//!
//! * the sweep, when it is a multiple of 45° (only then can the angle between
//!   two vectors of whole half-nanometres be a rational number of
//!   arc-seconds: a rational tangent of a rational multiple of π is 0 or ±1),
//!   which is decided by integer cross and dot products;
//! * `Δφ_exact`, when it is a rational number of arc-seconds: 360° for
//!   `σ ≥ 2·R0` and, with `R0` a whole number of half-nanometres, 120°, 180°,
//!   240° for `σ/R0 = ½, 1, 3/2`;
//! * a chord end coordinate that is rational: the rotation angle is a
//!   multiple of 90°, or a multiple of 30°/60° where the irrational term has
//!   a zero factor (start vector on an axis), or an odd multiple of 45° whose
//!   two irrational terms cancel (the point lands on the centre's X or Z).
//!   Such a coordinate is quantized in integers of quarter-nanometres, ties
//!   included.
//!
//! Every other chord end is irrational: it is rounded to the nearest integer
//! without tie snapping and its distance `|frac − ½|` goes into
//! [`TieStats::min_distance`]. [`RefArc::dphi_margin`] and
//! [`RefArc::n_margin`] give the distance of `Δφ_exact` and of `sweep/Δφ` from
//! the nearest integer when they were computed in f64, and `f64::INFINITY`
//! when they were decided exactly.
//!
//! ## Chord error
//!
//! [`RefArc::max_chord_error_mm`] is the largest distance between the arc and
//! its chords (unquantized). Chords `1 … n−1` have both ends on the circle:
//! their error is the sagitta `R0·(1 − cos(Δφ/2))`. The last chord ends at
//! `E`, which may lie off that circle by up to 0.002 mm; the arc it
//! approximates is taken as the curve from its start to `E` whose radius goes
//! linearly with the angle from `R0` to `R1` (the circle itself when
//! `R1 = R0`), and the largest distance is found by sampling and a
//! golden-section refinement. For finishing passes the error is at most `TOL`
//! plus twice the radius mismatch.
//!
//! # ЭМ-907 circular interpolator ([`RefMachine::arc_direct`])
//!
//! * Same `S`, `C`, `E` and radius checks; `E = S` exactly (a full circle) is
//!   refused (`GEOMETRY`). `J = Q(|I|/hx)`, `K = Q(|K|/hz)` unsigned; the
//!   centre in impulses is `(PX + sgn(I)·J, PZ + sgn(K)·K)`; the end
//!   registers are `Q(E/h)`. `J = K = 0` (a centre within half an impulse) is
//!   refused (`GEOMETRY`).
//! * The arc must stay in one quadrant about the centre: with
//!   `(a, b) = (X − Xc, Z − Zc)` in impulses, `a0·a1 ≥ 0`, `b0·b1 ≥ 0`; the
//!   quadrant's signs `(qa, qb)` are those of the start, or of the end where
//!   the start's is 0. CCW moves X with `qb` and Z with `−qa`, CW the
//!   opposite; `ΔX`, `ΔZ` must be 0 or of those signs (`GEOMETRY`).
//! * Steps: each event takes, among diagonal (both counts left), X only and
//!   Z only, the one with the smallest `|F|` after it,
//!   `F = (a·hx)² + (b·hz)² − R²`, `R² = (a0·hx)² + (b0·hz)²`, earlier
//!   candidate on equal `|F|`. `F` is computed exactly in `i128` of nm².
//! * Feed word `F = S·10³/R` (`R = R0`, mm), rounded half away from zero,
//!   decided exactly in integers from the decimal feed and `R0²`.
//!
//! # Limits
//!
//! A chord or direct block over [`MAX_ARC_BLOCK_IMPULSES`] per axis, a
//! register beyond [`MAX_POSITION_IMPULSES`], or (as for linear blocks) a
//! coordinate beyond [`MAX_COORD_MM`] refuses the whole arc (`RANGE`); so does
//! a `TOL` of 0 or below (no angular step) and a feed of 0 or below. A
//! refused arc changes no state. The checks run in the order: word syntax,
//! end point range, geometry, then the range of the result.

use std::f64::consts::PI;
use std::fmt;

use crate::impulse::{
    parse_length_nm, quantize, register, step_events, RefMachine, TieStats, BIT_X_NEG, BIT_X_STEP,
    BIT_Z_NEG, BIT_Z_STEP, HALF_NM_PER_MM, MAX_COORD_MM,
};

/// A full turn in arc-seconds.
pub const FULL_TURN_ARCSEC: i64 = 1_296_000;
const HALF_TURN_ARCSEC: i64 = FULL_TURN_ARCSEC / 2;
const QUARTER_TURN_ARCSEC: i64 = FULL_TURN_ARCSEC / 4;
const EIGHTH_TURN_ARCSEC: i64 = FULL_TURN_ARCSEC / 8;

/// Largest accepted difference between the start and end radii, mm.
pub const RADIUS_MISMATCH_MM: f64 = crate::protocol::RADIUS_MISMATCH_MM;
/// [`RADIUS_MISMATCH_MM`] in half-nanometres.
const RADIUS_MISMATCH_HALF_NM: u128 = 4_000;

/// Largest number of chords of one arc.
pub const MAX_CHORDS: i64 = crate::protocol::CHORDS_MAX;

/// Largest number of impulses per axis of one chord or one direct arc.
pub const MAX_ARC_BLOCK_IMPULSES: i64 = crate::protocol::BLOCK_MAX;

/// Largest register value (absolute) an arc may reach.
pub const MAX_POSITION_IMPULSES: i64 = crate::protocol::REGISTER_MAX;

/// Half-nanometres per mm, as f64.
const HALF_NM_F: f64 = HALF_NM_PER_MM as f64;

/// One arc cut as chords.
#[derive(Clone, Debug, PartialEq)]
pub struct RefArc {
    /// Number of chords.
    pub n: u32,
    /// Approximation angle used, whole arc-seconds.
    pub dphi_arcsec: i64,
    /// Sweep of the arc, arc-seconds, in `(0, 1 296 000]`.
    pub sweep_arcsec: f64,
    /// Impulses `(nx, nz)` of each chord, in order.
    pub chords: Vec<(i64, i64)>,
    /// Impulses issued on X by the whole arc (signed, radius).
    pub nx: i64,
    /// Impulses issued on Z by the whole arc (signed).
    pub nz: i64,
    /// X register after the arc.
    pub px: i64,
    /// Z register after the arc.
    pub pz: i64,
    /// CRC-32 (IEEE/zlib) of the step bytes of all chords in order; 0 if none.
    pub seq: u32,
    /// Number of step events of all chords.
    pub events: u64,
    /// Rounding decisions of the chord ends and of the end point.
    pub quantizer_ties: TieStats,
    /// Rounding decisions of the interleaver inside the chords.
    pub interleave_ties: TieStats,
    /// Distance of `Δφ_exact` (arc-seconds) from the nearest integer, for the
    /// floor/ceiling decision; `f64::INFINITY` when decided exactly.
    pub dphi_margin: f64,
    /// Distance of `sweep/Δφ` from the nearest integer, for `n`;
    /// `f64::INFINITY` when decided exactly.
    pub n_margin: f64,
    /// Largest distance between the arc and its chords, mm.
    pub max_chord_error_mm: f64,
    /// The end of each chord (X radius, Z), as computed: the last one the
    /// commanded end.
    pub ends: Vec<[ChordCoord; 2]>,
}

/// A chord end coordinate as the reference computes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChordCoord {
    /// Exact, in quarter-nanometres (2.5·10⁻⁷ mm).
    Exact(i128),
    /// The centre's coordinate (exact, half-nanometres) plus an offset on
    /// the circle (half-nanometres, as a double-double `hi + lo`).
    OnCircle {
        /// The centre, half-nanometres.
        centre: i64,
        /// `R·cos`/`R·sin` term, half-nanometres: `[hi, lo]`.
        offset: [f64; 2],
    },
}

/// One arc run by the ЭМ-907 circular interpolator.
#[derive(Clone, Debug, PartialEq)]
pub struct RefDirect {
    /// `J`: unsigned X distance from the centre to the start, impulses.
    pub j: i64,
    /// `K`: unsigned Z distance from the centre to the start, impulses.
    pub k: i64,
    /// Impulses issued on X (signed, radius).
    pub nx: i64,
    /// Impulses issued on Z (signed).
    pub nz: i64,
    /// X register after the arc.
    pub px: i64,
    /// Z register after the arc.
    pub pz: i64,
    /// CRC-32 (IEEE/zlib) of the step bytes; 0 if none.
    pub seq: u32,
    /// Number of step events.
    pub events: u64,
    /// Worst `|√((a·hx)² + (b·hz)²) − R|` over the positions after each step, mm.
    pub max_radial_dev_mm: f64,
    /// Feed word `F = S·10³/R0`, if a feed was given.
    pub feed_word: Option<i64>,
    /// The ЭМ-907 block, e.g. `G03 X+600 Z-1190 J4397 K1190 F1420`.
    pub block: String,
}

/// The words of an ЭМ-907 circular block, in impulses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Em907Words {
    /// `Q(|I|/hx)`.
    pub j: i64,
    /// `Q(|K|/hz)`.
    pub k: i64,
    /// X increment `Q(Ex/hx) − PX`.
    pub dx: i64,
    /// Z increment `Q(Ez/hz) − PZ`.
    pub dz: i64,
}

/// Why an arc was refused. A refused arc changes no state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefArcError {
    /// A word is not `[+-]digits[.digits]` with at most 6 decimals.
    Syntax,
    /// Impossible geometry: zero radius, radius mismatch over 0.002 mm, or
    /// (direct mode) not within one quadrant in the commanded direction.
    Geometry,
    /// A result beyond what the machine holds: no angular step, too many
    /// chords, too long a block, a register or coordinate out of range.
    Range,
}

impl fmt::Display for RefArcError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RefArcError::Syntax => "malformed word",
            RefArcError::Geometry => "impossible arc geometry",
            RefArcError::Range => "arc result out of range",
        })
    }
}

impl std::error::Error for RefArcError {}

/// Feed word of an ЭМ-907 circular block: `F = S·10³/R`, `S` in mm/min, `R`
/// the arc radius in mm, rounded half away from zero.
///
/// The quotient is rounded by [`quantize`], so a decimal tie (e.g.
/// `S·10³/R = 1000.5`) rounds away from zero although its f64 value may sit
/// just below the half. [`RefMachine::arc_direct`] decides the word exactly
/// from the request's words instead.
///
/// # Panics
/// If `r_mm ≤ 0`, `s_mm_min < 0` or the quotient is not finite.
pub fn feed_word_circular(s_mm_min: f64, r_mm: f64) -> i64 {
    feed_word(s_mm_min, r_mm)
}

/// Feed word of an ЭМ-907 linear block: `F = S·10³/l`, `S` in mm/min, `l`
/// the block length in mm (the distance in (X radius, Z)), rounded half away
/// from zero as in [`feed_word_circular`].
///
/// # Panics
/// If `l_mm ≤ 0`, `s_mm_min < 0` or the quotient is not finite.
pub fn feed_word_linear(s_mm_min: f64, l_mm: f64) -> i64 {
    feed_word(s_mm_min, l_mm)
}

fn feed_word(s_mm_min: f64, len_mm: f64) -> i64 {
    assert!(
        len_mm > 0.0,
        "feed word: length must be positive, got {len_mm}"
    );
    assert!(
        s_mm_min >= 0.0,
        "feed word: feed must not be negative, got {s_mm_min}"
    );
    let v = s_mm_min * 1e3 / len_mm;
    quantize(v, &mut TieStats::new())
}

/// Text of an ЭМ-907 circular block: `G03 X+600 Z-1190 J4397 K1190 F1420`
/// (`G02` for CW; X and Z the signed impulse increments with an explicit
/// sign, a zero increment left out as on the seed's tapes; `J`, `K`
/// unsigned, `F` only when given).
pub fn em907_block_text(
    ccw: bool,
    dx: i64,
    dz: i64,
    j: i64,
    k: i64,
    feed_word: Option<i64>,
) -> String {
    let g = if ccw { "G03" } else { "G02" };
    let mut text = g.to_string();
    if dx != 0 {
        text.push_str(&format!(" X{dx:+}"));
    }
    if dz != 0 {
        text.push_str(&format!(" Z{dz:+}"));
    }
    text.push_str(&format!(" J{j} K{k}"));
    if let Some(f) = feed_word {
        text.push_str(&format!(" F{f}"));
    }
    text
}

/// Parsed words of an arc, all in exact half-nanometres.
#[derive(Clone, Debug)]
struct ArcWords {
    /// Start point `S` (X radius, Z).
    start: (i64, i64),
    /// Centre `C` (X radius, Z).
    centre: (i64, i64),
    /// End point `E` (X radius, Z).
    end: (i64, i64),
    /// `S − C` (X, Z).
    u: (i128, i128),
    /// `E − C` (X, Z).
    v: (i128, i128),
    /// `R0²`, half-nm².
    r0_sq: u128,
    /// `R1²`, half-nm².
    r1_sq: u128,
    /// `I` word, nm (radius).
    i_nm: i64,
    /// `K` word, nm.
    k_nm: i64,
}

fn word(w: &str) -> Result<i64, RefArcError> {
    parse_length_nm(w).ok_or(RefArcError::Syntax)
}

fn norm_sq(p: (i128, i128)) -> u128 {
    (p.0 * p.0 + p.1 * p.1) as u128
}

/// `|√a − √b| ≤ 0.002 mm`, decided exactly (`a`, `b` in half-nm²).
#[cfg(test)]
fn radii_match(a: u128, b: u128) -> bool {
    radii_within(a, b, RADIUS_MISMATCH_HALF_NM)
}

/// `|√a − √b| ≤ d`, decided exactly.
fn radii_within(a: u128, b: u128, d: u128) -> bool {
    let (big, small) = if a >= b { (a, b) } else { (b, a) };
    // √big − √small ≤ d  ⇔  big − small − d² ≤ 2d·√small.
    let diff = big - small;
    if diff <= d * d {
        return true;
    }
    let l = diff - d * d;
    // For a whole l ≥ 0: l ≤ √m ⇔ l ≤ ⌊√m⌋.
    l <= (4 * d * d * small).isqrt()
}

fn check_radii(w: &ArcWords, scale: u128) -> Result<(), RefArcError> {
    let d = RADIUS_MISMATCH_HALF_NM * scale;
    if w.r0_sq == 0 || w.r1_sq == 0 || !radii_within(w.r0_sq, w.r1_sq, d) {
        return Err(RefArcError::Geometry);
    }
    Ok(())
}

/// A value that is either known exactly or only as an f64 approximation.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Value<E> {
    Exact(E),
    Approx(f64),
}

/// Sweep of the arc in arc-seconds, in `(0, 1 296 000]`.
fn sweep_arcsec(u: (i128, i128), v: (i128, i128), ccw: bool) -> Value<i64> {
    // In the (Z, X) plane: CCW angle from u to v = atan2(u×v, u·v).
    let (ux, uz) = u;
    let (vx, vz) = v;
    let cross = uz * vx - ux * vz;
    let dot = uz * vz + ux * vx;
    let exact = if cross == 0 {
        Some(if dot > 0 { 0 } else { HALF_TURN_ARCSEC })
    } else if dot == 0 {
        Some(QUARTER_TURN_ARCSEC * cross.signum() as i64)
    } else if cross.abs() == dot.abs() {
        let a = if dot > 0 {
            EIGHTH_TURN_ARCSEC
        } else {
            3 * EIGHTH_TURN_ARCSEC
        };
        Some(a * cross.signum() as i64)
    } else {
        None
    };
    match exact {
        Some(theta) => {
            let s = if ccw { theta } else { -theta }.rem_euclid(FULL_TURN_ARCSEC);
            Value::Exact(if s == 0 { FULL_TURN_ARCSEC } else { s })
        }
        None => {
            let full = FULL_TURN_ARCSEC as f64;
            let theta = (cross as f64).atan2(dot as f64) * (648_000.0 / PI);
            let s = if ccw { theta } else { -theta };
            Value::Approx(if s > 0.0 { s } else { s + full })
        }
    }
}

/// `Δφ_exact` in arc-seconds for `σ` and `R0²` in half-nanometres.
fn dphi_exact(r0_sq: u128, sigma: i64) -> Value<i64> {
    if sigma <= 0 {
        // No angular step (a negative σ has none either).
        return Value::Exact(0);
    }
    let s = sigma as u128;
    if s * s >= 4 * r0_sq {
        // 1 − σ/R0 ≤ −1.
        return Value::Exact(FULL_TURN_ARCSEC);
    }
    let r = r0_sq.isqrt();
    if r * r == r0_sq {
        // Rational 1 − σ/R0: its arccos is a rational angle only at ½, 0, −½.
        if 2 * s == r {
            return Value::Exact(FULL_TURN_ARCSEC / 3);
        }
        if s == r {
            return Value::Exact(HALF_TURN_ARCSEC);
        }
        if 2 * s == 3 * r {
            return Value::Exact(2 * FULL_TURN_ARCSEC / 3);
        }
    }
    let ratio = sigma as f64 / (2.0 * (r0_sq as f64).sqrt());
    Value::Approx(4.0 * ratio.sqrt().min(1.0).asin() * (648_000.0 / PI))
}

/// `2·cos α` when it is rational (α in arc-seconds, `0 ≤ α < 360°`).
fn twice_cos_exact(alpha: i64) -> Option<i128> {
    match alpha {
        0 => Some(2),
        216_000 | 1_080_000 => Some(1),
        324_000 | 972_000 => Some(0),
        432_000 | 864_000 => Some(-1),
        648_000 => Some(-2),
        _ => None,
    }
}

/// A chord end: `C + rot(α)·(S − C)`, per axis (X, Z). Exact coordinates are
/// in quarter-nanometres, approximate ones in mm.
fn chord_end(w: &ArcWords, alpha: i64) -> (Value<i128>, Value<i128>) {
    let alpha = alpha.rem_euclid(FULL_TURN_ARCSEC);
    let (ux, uz) = w.u;
    let (cx, cz) = (w.centre.0 as i128, w.centre.1 as i128);
    let c2 = twice_cos_exact(alpha);
    let s2 = twice_cos_exact((alpha - QUARTER_TURN_ARCSEC).rem_euclid(FULL_TURN_ARCSEC));
    // Odd multiples of 45°: cos α = sc·√2/2, sin α = ss·√2/2.
    let diagonal = (alpha % QUARTER_TURN_ARCSEC == EIGHTH_TURN_ARCSEC).then(|| {
        let q = alpha / QUARTER_TURN_ARCSEC;
        let sc: i128 = if q == 0 || q == 3 { 1 } else { -1 };
        let ss: i128 = if q <= 1 { 1 } else { -1 };
        (sc, ss)
    });
    let signed = if alpha > HALF_TURN_ARCSEC {
        alpha - FULL_TURN_ARCSEC
    } else {
        alpha
    };
    let (sin, cos) = (signed as f64 * (PI / 648_000.0)).sin_cos();
    let (uxf, uzf) = (ux as f64, uz as f64);

    // Z = Cz + uz·cos α − ux·sin α.
    let z = if (uz == 0 || c2.is_some()) && (ux == 0 || s2.is_some()) {
        Value::Exact(2 * cz + uz * c2.unwrap_or(0) - ux * s2.unwrap_or(0))
    } else if diagonal.is_some_and(|(sc, ss)| uz * sc == ux * ss) {
        Value::Exact(2 * cz)
    } else {
        Value::Approx(cz as f64 / HALF_NM_F + (uzf * cos - uxf * sin) / HALF_NM_F)
    };
    // X = Cx + uz·sin α + ux·cos α.
    let x = if (uz == 0 || s2.is_some()) && (ux == 0 || c2.is_some()) {
        Value::Exact(2 * cx + uz * s2.unwrap_or(0) + ux * c2.unwrap_or(0))
    } else if diagonal.is_some_and(|(sc, ss)| uz * ss == -ux * sc) {
        Value::Exact(2 * cx)
    } else {
        Value::Approx(cx as f64 / HALF_NM_F + (uzf * sin + uxf * cos) / HALF_NM_F)
    };
    (x, z)
}

/// The offsets `(uz·sin α + ux·cos α, uz·cos α − ux·sin α)` of a chord end
/// from the centre, half-nanometres (X, Z), in double-double: the chord ends
/// the motion reference times (far more precise than the f64 ones the
/// impulse decisions above take, whose ties are decided apart).
fn chord_offset(w: &ArcWords, alpha: i64) -> ([f64; 2], [f64; 2]) {
    let (sin, cos) = crate::dd::sin_cos_arcsec(alpha);
    let (ux, uz) = (
        crate::dd::Dd::from_i128(w.u.0),
        crate::dd::Dd::from_i128(w.u.1),
    );
    let x = uz.times(sin).plus(ux.times(cos));
    let z = uz.times(cos).minus(ux.times(sin));
    ([x.hi, x.lo], [z.hi, z.lo])
}

/// The price in whole nanometres (prices have at most 6 decimals).
fn price_nm(h_mm: f64) -> i128 {
    (h_mm * 1e6).round() as i128
}

/// `Q` of an irrational value: nearest integer, no tie snapping; the
/// distance `|frac − ½|` is recorded.
fn quantize_irrational(v: f64, ties: &mut TieStats) -> i64 {
    let a = v.abs();
    let whole = a.floor();
    let frac = a - whole;
    ties.min_distance = ties.min_distance.min((frac - 0.5).abs());
    let m = whole as i64 + i64::from(frac >= 0.5);
    if v < 0.0 {
        -m
    } else {
        m
    }
}

/// `Q(P/h)` of a chord end coordinate, with the range checks.
fn quantize_coord(c: Value<i128>, h_mm: f64, ties: &mut TieStats) -> Result<i64, RefArcError> {
    let imp = match c {
        Value::Exact(p4) => {
            if p4.abs() > 2 * (MAX_COORD_MM * HALF_NM_PER_MM) as i128 {
                return Err(RefArcError::Range);
            }
            // P/h = p4 / (4q), q the price in nm.
            let den = 4 * price_nm(h_mm);
            let a = p4.abs();
            let (whole, rem) = (a / den, a % den);
            if 2 * rem == den {
                ties.exact_ties += 1;
            } else {
                let d = (2 * rem - den).abs() as f64 / (2 * den) as f64;
                ties.min_distance = ties.min_distance.min(d);
            }
            let m = (whole + i128::from(2 * rem >= den)) as i64;
            if p4 < 0 {
                -m
            } else {
                m
            }
        }
        Value::Approx(mm) => {
            if !mm.is_finite() || mm.abs() > MAX_COORD_MM as f64 {
                return Err(RefArcError::Range);
            }
            quantize_irrational(mm / h_mm, ties)
        }
    };
    check_position(imp)?;
    Ok(imp)
}

fn check_position(p: i64) -> Result<(), RefArcError> {
    if p.abs() > MAX_POSITION_IMPULSES {
        return Err(RefArcError::Range);
    }
    Ok(())
}

fn check_block(n: i64) -> Result<(), RefArcError> {
    if n.abs() > MAX_ARC_BLOCK_IMPULSES {
        return Err(RefArcError::Range);
    }
    Ok(())
}

/// Distance from `p` to the segment `a`–`b` (2-D).
fn distance_to_segment(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let d = (b.0 - a.0, b.1 - a.1);
    let w = (p.0 - a.0, p.1 - a.1);
    let len_sq = d.0 * d.0 + d.1 * d.1;
    let t = if len_sq > 0.0 {
        ((w.0 * d.0 + w.1 * d.1) / len_sq).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (w.0 - t * d.0).hypot(w.1 - t * d.1)
}

/// Largest distance between the arc and its chords, mm (see the module docs).
fn max_chord_error_mm(w: &ArcWords, n: i64, dphi: i64, sweep: f64, ccw: bool) -> f64 {
    let r0 = (w.r0_sq as f64).sqrt() / HALF_NM_F;
    let r1 = (w.r1_sq as f64).sqrt() / HALF_NM_F;
    let to_rad = PI / 648_000.0;
    let mut worst: f64 = 0.0;
    if n >= 2 {
        // R0·(1 − cos(Δφ/2)) = 2·R0·sin²(Δφ/4).
        let q = (dphi as f64 * to_rad / 4.0).sin();
        worst = 2.0 * r0 * q * q;
    }
    // The last chord: from the chord end n−1 (on the circle) to E.
    let dir = if ccw { 1.0 } else { -1.0 };
    let alpha = (n - 1) * dphi * if ccw { 1 } else { -1 };
    let (sin, cos) = (alpha.rem_euclid(FULL_TURN_ARCSEC) as f64 * to_rad).sin_cos();
    let (ux, uz) = (w.u.0 as f64 / HALF_NM_F, w.u.1 as f64 / HALF_NM_F);
    let a = (uz * cos - ux * sin, uz * sin + ux * cos); // (Z, X) from C
    let b = (w.v.1 as f64 / HALF_NM_F, w.v.0 as f64 / HALF_NM_F);
    let theta = (sweep - ((n - 1) * dphi) as f64) * to_rad;
    let psi0 = a.1.atan2(a.0);
    let dist = |t: f64| {
        let psi = psi0 + dir * t * theta;
        let r = r0 + t * (r1 - r0);
        distance_to_segment((r * psi.cos(), r * psi.sin()), a, b)
    };
    const SAMPLES: usize = 256;
    let mut best = (0usize, dist(0.0));
    for i in 1..=SAMPLES {
        let d = dist(i as f64 / SAMPLES as f64);
        if d > best.1 {
            best = (i, d);
        }
    }
    // Golden-section refinement around the best sample.
    let mut lo = best.0.saturating_sub(1) as f64 / SAMPLES as f64;
    let mut hi = (best.0 + 1).min(SAMPLES) as f64 / SAMPLES as f64;
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut m1 = hi - g * (hi - lo);
    let mut m2 = lo + g * (hi - lo);
    let (mut f1, mut f2) = (dist(m1), dist(m2));
    for _ in 0..80 {
        if f1 >= f2 {
            hi = m2;
            m2 = m1;
            f2 = f1;
            m1 = hi - g * (hi - lo);
            f1 = dist(m1);
        } else {
            lo = m1;
            m1 = m2;
            f1 = f2;
            m2 = lo + g * (hi - lo);
            f2 = dist(m2);
        }
    }
    worst.max(best.1).max(f1).max(f2)
}

/// `Q(2000·s_nm/√A)`: the circular feed word from the feed in nm/min and
/// `R0² = A` in half-nm², decided exactly.
fn feed_word_exact(s_nm: i64, r0_sq: u128) -> i64 {
    // S·10³/R0 with S = s_nm/10⁶ mm/min and R0 = √A/(2·10⁶) mm.
    let n = 2_000 * s_nm as u128;
    let four_n2 = 4 * n * n;
    let above = |m: u128| four_n2 >= (2 * m + 1) * (2 * m + 1) * r0_sq; // v ≥ m + ½
    let mut m = (n as f64 / (r0_sq as f64).sqrt()).round().max(0.0) as u128;
    while above(m) {
        m += 1;
    }
    while m > 0 && !above(m - 1) {
        m -= 1;
    }
    m as i64
}

impl RefMachine {
    fn arc_words(&self, x: &str, z: &str, i: &str, k: &str) -> Result<ArcWords, RefArcError> {
        let x_nm = word(x)?;
        let z_nm = word(z)?;
        let i_nm = word(i)?;
        let k_nm = word(k)?;
        // A diameter word in nm is the radius in half-nm.
        let end = (x_nm * if self.cfg.diam { 1 } else { 2 }, z_nm * 2);
        let limit = MAX_COORD_MM * HALF_NM_PER_MM;
        if end.0.abs() > limit || end.1.abs() > limit {
            return Err(RefArcError::Range);
        }
        let start = (self.cmd_x, self.cmd_z);
        let centre = (start.0 + 2 * i_nm, start.1 + 2 * k_nm);
        let u = ((start.0 - centre.0) as i128, (start.1 - centre.1) as i128);
        let v = ((end.0 - centre.0) as i128, (end.1 - centre.1) as i128);
        Ok(ArcWords {
            start,
            centre,
            end,
            u,
            v,
            r0_sq: norm_sq(u),
            r1_sq: norm_sq(v),
            i_nm,
            k_nm,
        })
    }

    /// `ARC X= Z= I= K= DIR= [TOL=] [PASS=]`: the arc by chords from the
    /// current commanded point. `x`, `z`, `i`, `k`, `tol` are the words as
    /// written in the request (`x` a diameter when `DIAM=1`; `i`, `k` the
    /// start-to-centre vector as radius values); `ccw` = `DIR=CCW` (G03);
    /// `rough` = `PASS=ROUGH`. A refused arc changes no state.
    #[allow(clippy::too_many_arguments)]
    pub fn arc(
        &mut self,
        x: &str,
        z: &str,
        i: &str,
        k: &str,
        ccw: bool,
        tol: &str,
        rough: bool,
    ) -> Result<RefArc, RefArcError> {
        self.arc_with_steps(x, z, i, k, ccw, tol, rough, &mut |_| {})
    }

    /// [`arc`](Self::arc), handing each chord's step bytes to `steps` in
    /// order (a chord without motion hands an empty slice). `steps` is only
    /// called once the arc is accepted.
    #[allow(clippy::too_many_arguments)]
    pub fn arc_with_steps(
        &mut self,
        x: &str,
        z: &str,
        i: &str,
        k: &str,
        ccw: bool,
        tol: &str,
        rough: bool,
        steps: &mut dyn FnMut(&[u8]),
    ) -> Result<RefArc, RefArcError> {
        let sigma = 2 * word(tol)?;
        let w = self.arc_words(x, z, i, k)?;
        check_radii(&w, self.length_scale)?;

        let (dphi, dphi_margin) = match dphi_exact(w.r0_sq, sigma) {
            Value::Exact(d) => (d, f64::INFINITY),
            Value::Approx(d) => {
                let step = if rough { d.ceil() } else { d.floor() };
                ((step as i64).min(FULL_TURN_ARCSEC), (d - d.round()).abs())
            }
        };
        if dphi == 0 {
            return Err(RefArcError::Range);
        }
        let sweep = sweep_arcsec(w.u, w.v, ccw);
        let (n, n_margin, sweep_f) = match sweep {
            Value::Exact(s) => ((s + dphi - 1) / dphi, f64::INFINITY, s as f64),
            Value::Approx(s) => {
                let q = s / dphi as f64;
                (q.ceil() as i64, (q - q.round()).abs(), s)
            }
        };
        if n > MAX_CHORDS {
            return Err(RefArcError::Range);
        }
        let n = n.max(1);

        let (hx, hz) = (self.cfg.hx_mm, self.cfg.hz_mm);
        let mut quantizer_ties = TieStats::new();
        let mut points = Vec::with_capacity(n as usize + 1);
        let mut ends = Vec::with_capacity(n as usize);
        points.push((self.px, self.pz));
        let sign = if ccw { 1 } else { -1 };
        for i in 1..n {
            let (cx, cz) = chord_end(&w, sign * i * dphi);
            points.push((
                quantize_coord(cx, hx, &mut quantizer_ties)?,
                quantize_coord(cz, hz, &mut quantizer_ties)?,
            ));
            let (ox, oz) = chord_offset(&w, sign * i * dphi);
            let coord = |c: Value<i128>, centre: i64, offset: [f64; 2]| match c {
                Value::Exact(q) => ChordCoord::Exact(q),
                Value::Approx(_) => ChordCoord::OnCircle { centre, offset },
            };
            ends.push([coord(cx, w.centre.0, ox), coord(cz, w.centre.1, oz)]);
        }
        ends.push([
            ChordCoord::Exact(2 * i128::from(w.end.0)),
            ChordCoord::Exact(2 * i128::from(w.end.1)),
        ]);
        let end = (
            register(w.end.0, hx, &mut quantizer_ties),
            register(w.end.1, hz, &mut quantizer_ties),
        );
        check_position(end.0)?;
        check_position(end.1)?;
        points.push(end);
        let chords: Vec<(i64, i64)> = points
            .windows(2)
            .map(|p| (p[1].0 - p[0].0, p[1].1 - p[0].1))
            .collect();
        for &(dx, dz) in &chords {
            check_block(dx)?;
            check_block(dz)?;
        }

        let mut interleave_ties = TieStats::new();
        let mut crc = crc32fast::Hasher::new();
        let mut events = 0u64;
        for p in points.windows(2) {
            let bytes = step_events(p[0], p[1], &mut interleave_ties);
            crc.update(&bytes);
            events += bytes.len() as u64;
            steps(&bytes);
        }
        let max_chord_error_mm = max_chord_error_mm(&w, n, dphi, sweep_f, ccw);

        let (nx, nz) = (end.0 - self.px, end.1 - self.pz);
        self.cmd_x = w.end.0;
        self.cmd_z = w.end.1;
        self.px = end.0;
        self.pz = end.1;
        Ok(RefArc {
            n: n as u32,
            dphi_arcsec: dphi,
            sweep_arcsec: sweep_f,
            chords,
            nx,
            nz,
            px: end.0,
            pz: end.1,
            seq: crc.finalize(),
            events,
            quantizer_ties,
            interleave_ties,
            dphi_margin,
            n_margin,
            max_chord_error_mm,
            ends,
        })
    }

    fn em907_convert(&self, w: &ArcWords) -> Em907Words {
        let mut ties = TieStats::new();
        let (hx, hz) = (self.cfg.hx_mm, self.cfg.hz_mm);
        let j = register(2 * w.i_nm.abs(), hx, &mut ties);
        let k = register(2 * w.k_nm.abs(), hz, &mut ties);
        let qx = register(w.end.0, hx, &mut ties);
        let qz = register(w.end.1, hz, &mut ties);
        Em907Words {
            j,
            k,
            dx: qx - self.px,
            dz: qz - self.pz,
        }
    }

    /// The ЭМ-907 words of an arc from the current point, without any
    /// geometry check and without changing state: `J = Q(|I|/hx)`,
    /// `K = Q(|K|/hz)` and the increments `Q(E/h) − P`.
    pub fn em907_words(
        &self,
        x: &str,
        z: &str,
        i: &str,
        k: &str,
    ) -> Result<Em907Words, RefArcError> {
        let w = self.arc_words(x, z, i, k)?;
        Ok(self.em907_convert(&w))
    }

    /// `ARC … MODE=DIRECT [F=]`: the arc by the ЭМ-907 circular interpolator
    /// (one quadrant at most). Words as for [`arc`](Self::arc); `feed` the
    /// feed word in mm/min. A refused arc changes no state.
    pub fn arc_direct(
        &mut self,
        x: &str,
        z: &str,
        i: &str,
        k: &str,
        ccw: bool,
        feed: Option<&str>,
    ) -> Result<RefDirect, RefArcError> {
        self.arc_direct_with_steps(x, z, i, k, ccw, feed, &mut |_| {})
    }

    /// [`arc_direct`](Self::arc_direct), handing the step bytes to `steps`
    /// (once, only if the arc is accepted).
    #[allow(clippy::too_many_arguments)]
    pub fn arc_direct_with_steps(
        &mut self,
        x: &str,
        z: &str,
        i: &str,
        k: &str,
        ccw: bool,
        feed: Option<&str>,
        steps: &mut dyn FnMut(&[u8]),
    ) -> Result<RefDirect, RefArcError> {
        let feed_nm = feed.map(word).transpose()?;
        let w = self.arc_words(x, z, i, k)?;
        check_radii(&w, self.length_scale)?;
        if w.end == w.start {
            return Err(RefArcError::Geometry);
        }
        let words = self.em907_convert(&w);
        if words.j == 0 && words.k == 0 {
            return Err(RefArcError::Geometry);
        }
        let (px0, pz0) = (self.px, self.pz);
        let (qx, qz) = (px0 + words.dx, pz0 + words.dz);
        let xc = px0 + w.i_nm.signum() * words.j;
        let zc = pz0 + w.k_nm.signum() * words.k;
        let (a0, b0) = (px0 - xc, pz0 - zc);
        let (a1, b1) = (qx - xc, qz - zc);
        if (a0 as i128) * (a1 as i128) < 0 || (b0 as i128) * (b1 as i128) < 0 {
            return Err(RefArcError::Geometry);
        }
        let qa = if a0 != 0 { a0.signum() } else { a1.signum() };
        let qb = if b0 != 0 { b0.signum() } else { b1.signum() };
        let (want_x, want_z) = if ccw { (qb, -qa) } else { (-qb, qa) };
        let agrees = |d: i64, want: i64| d == 0 || d.signum() == want;
        if !agrees(words.dx, want_x) || !agrees(words.dz, want_z) {
            return Err(RefArcError::Geometry);
        }
        check_position(qx)?;
        check_position(qz)?;
        check_block(words.dx)?;
        check_block(words.dz)?;
        if feed_nm.is_some_and(|f| f <= 0) {
            return Err(RefArcError::Range);
        }

        // F(a, b) in nm², exactly.
        let (hx_nm, hz_nm) = (price_nm(self.cfg.hx_mm), price_nm(self.cfg.hz_mm));
        let rho = |a: i64, b: i64| {
            let (xa, zb) = (a as i128 * hx_nm, b as i128 * hz_nm);
            xa * xa + zb * zb
        };
        let r2 = rho(a0, b0);
        let (sx, sz) = (words.dx.signum(), words.dz.signum());
        let (mut nx, mut nz) = (words.dx.abs(), words.dz.abs());
        let x_byte = BIT_X_STEP | if sx < 0 { BIT_X_NEG } else { 0 };
        let z_byte = BIT_Z_STEP | if sz < 0 { BIT_Z_NEG } else { 0 };
        let (mut a, mut b) = (a0, b0);
        let mut bytes = Vec::with_capacity((nx + nz) as usize);
        let mut worst_nm: f64 = 0.0;
        let r = (r2 as f64).sqrt();
        while nx + nz > 0 {
            let mut best: Option<(u128, i64, i64, u8)> = None;
            let candidates = [
                (nx > 0 && nz > 0, sx, sz, x_byte | z_byte),
                (nx > 0, sx, 0, x_byte),
                (nz > 0, 0, sz, z_byte),
            ];
            for (allowed, da, db, byte) in candidates {
                if !allowed {
                    continue;
                }
                let f = (rho(a + da, b + db) - r2).unsigned_abs();
                if best.is_none_or(|(bf, ..)| f < bf) {
                    best = Some((f, da, db, byte));
                }
            }
            let (f, da, db, byte) = best.expect("a step is always possible");
            a += da;
            b += db;
            nx -= da.abs();
            nz -= db.abs();
            bytes.push(byte);
            // |ρ − R| = |F| / (ρ + R), without cancellation.
            let rho_ab = (rho(a, b) as f64).sqrt();
            worst_nm = worst_nm.max(f as f64 / (rho_ab + r));
        }
        debug_assert_eq!((a, b), (a1, b1));

        let feed_word = feed_nm.map(|s| feed_word_exact(s, w.r0_sq));
        let block = em907_block_text(ccw, words.dx, words.dz, words.j, words.k, feed_word);
        steps(&bytes);
        self.cmd_x = w.end.0;
        self.cmd_z = w.end.1;
        self.px = qx;
        self.pz = qz;
        Ok(RefDirect {
            j: words.j,
            k: words.k,
            nx: words.dx,
            nz: words.dz,
            px: qx,
            pz: qz,
            seq: crc32fast::hash(&bytes),
            events: bytes.len() as u64,
            max_radial_dev_mm: worst_nm / 1e6,
            feed_word,
            block,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::impulse::{seq_crc, RefConfig};
    use proptest::prelude::*;

    const ARCSEC_PER_RAD: f64 = 206_264.806_247_096_36;

    fn machine() -> RefMachine {
        RefMachine::new(RefConfig::default())
    }

    fn machine_with(hx_mm: f64, hz_mm: f64, diam: bool) -> RefMachine {
        RefMachine::new(RefConfig { hx_mm, hz_mm, diam })
    }

    /// Exact `Q(n/d)`, round half away from zero: the exact model's.
    fn q_exact(n: i128, d: i128) -> i64 {
        crate::exact::q_div(n, d) as i64
    }

    /// A whole number of nanometres as a decimal word.
    fn w(nm: i64) -> String {
        let sign = if nm < 0 { "-" } else { "" };
        let a = nm.unsigned_abs();
        format!("{sign}{}.{:06}", a / 1_000_000, a % 1_000_000)
    }

    /// Net signed steps per axis of step bytes.
    fn net_steps(bytes: &[u8]) -> (i64, i64) {
        let (mut x, mut z) = (0, 0);
        for &b in bytes {
            assert_eq!(b & 0xF0, 0);
            if b & BIT_X_STEP != 0 {
                x += if b & BIT_X_NEG != 0 { -1 } else { 1 };
            } else {
                assert_eq!(b & BIT_X_NEG, 0);
            }
            if b & BIT_Z_STEP != 0 {
                z += if b & BIT_Z_NEG != 0 { -1 } else { 1 };
            } else {
                assert_eq!(b & BIT_Z_NEG, 0);
            }
        }
        (x, z)
    }

    /// Runs a chord arc, returning it with all its step bytes.
    #[allow(clippy::too_many_arguments)]
    fn arc_bytes(
        m: &mut RefMachine,
        x: &str,
        z: &str,
        i: &str,
        k: &str,
        ccw: bool,
        tol: &str,
        rough: bool,
    ) -> (RefArc, Vec<Vec<u8>>) {
        let mut chords = Vec::new();
        let arc = m
            .arc_with_steps(x, z, i, k, ccw, tol, rough, &mut |b| {
                chords.push(b.to_vec())
            })
            .unwrap_or_else(|e| panic!("arc refused: {e}"));
        (arc, chords)
    }

    #[test]
    fn quarter_circle_r10_tol_0_01_by_hand() {
        // S (X 0, Z 0), C (0, −10), E (X radius 10, Z −10): a CCW quarter, φS = 0.
        let mut m = machine();
        let (a, bytes) = arc_bytes(&mut m, "20", "-10", "0", "-10", true, "0.01", false);
        // Δφ = ⌊2·acos(0.999)·206264.806…″⌋ = ⌊18450.4229″⌋.
        let exact = 2.0 * 0.999f64.acos() * ARCSEC_PER_RAD;
        assert_eq!(exact.floor(), 18_450.0);
        assert_eq!(a.dphi_arcsec, 18_450);
        assert!(
            (a.dphi_margin - 0.422_878).abs() < 1e-5,
            "{}",
            a.dphi_margin
        );
        // Sweep 90° is exact; n = ⌈324000/18450⌉ = ⌈17.56⌉ = 18.
        assert_eq!(a.sweep_arcsec, 324_000.0);
        assert_eq!(a.n, 18);
        assert_eq!(a.n_margin, f64::INFINITY);
        assert_eq!(a.chords.len(), 18);
        // Chord end 1: X = 10·sin Δφ = 0.893289 mm = 178.658 imp → 179;
        // Z = −10 + 10·cos Δφ = −0.039978 mm = −3.998 imp → −4.
        assert_eq!(a.chords[0], (179, -4));
        // Chord end 2: 355.887 → 356, −15.959 → −16.
        assert_eq!(a.chords[1], (177, -12));
        // Chord end 17: 1997.483 → 1997, −949.843 → −950; then E (2000, −1000).
        assert_eq!(a.chords[17], (3, -50));
        assert_eq!((a.nx, a.nz, a.px, a.pz), (2_000, -1_000, 2_000, -1_000));
        assert_eq!(m.position(), (2_000, -1_000));
        assert_eq!(m.commanded_mm(), (10.0, -10.0));
        let sum = a.chords.iter().fold((0, 0), |s, c| (s.0 + c.0, s.1 + c.1));
        assert_eq!(sum, (2_000, -1_000));
        // Events and SEQ: the chords as linear blocks, in order.
        let all: Vec<u8> = bytes.concat();
        assert_eq!(bytes.len(), 18);
        assert_eq!(a.events, all.len() as u64);
        let lead: u64 = a
            .chords
            .iter()
            .map(|c| c.0.unsigned_abs().max(c.1.unsigned_abs()))
            .sum();
        assert_eq!(a.events, lead);
        assert_eq!(a.seq, seq_crc(&all));
        assert_eq!(net_steps(&all), (2_000, -1_000));
        for (c, b) in a.chords.iter().zip(&bytes) {
            assert_eq!(net_steps(b), *c);
        }
        // Chord error: sagitta 10·(1 − cos(18450″/2)) = 0.0099995 ≤ TOL.
        assert!(
            (a.max_chord_error_mm - 0.009_999_541_687).abs() < 1e-9,
            "{}",
            a.max_chord_error_mm
        );
        assert!(a.quantizer_ties.min_distance > 1e-3);
    }

    #[test]
    fn roughing_rounds_up_and_may_exceed_tol() {
        let mut m = machine();
        let a = m.arc("20", "-10", "0", "-10", true, "0.01", true).unwrap();
        assert_eq!(a.dphi_arcsec, 18_451);
        assert_eq!(a.n, 18);
        assert!(a.max_chord_error_mm > 0.01, "{}", a.max_chord_error_mm);
        assert!((a.max_chord_error_mm - 0.010_000_625_497).abs() < 1e-9);
        assert_eq!((a.px, a.pz), (2_000, -1_000));
    }

    #[test]
    fn asin_form_equals_acos_form() {
        for (r0_mm, tol_mm) in [(10.0, 0.01), (3.7, 0.08), (250.0, 0.001), (1.0, 0.3)] {
            let r0 = (r0_mm * HALF_NM_F) as u128;
            let sigma = (tol_mm * HALF_NM_F) as i64;
            let Value::Approx(d) = dphi_exact(r0 * r0, sigma) else {
                panic!("not approximate")
            };
            let acos_form = 2.0 * (1.0 - tol_mm / r0_mm).acos() * ARCSEC_PER_RAD;
            assert!((d - acos_form).abs() < 1e-6, "{d} vs {acos_form}");
        }
    }

    #[test]
    fn full_circle_closes_to_zero() {
        let mut m = machine();
        m.move_block(Some("37.123"), Some("-4.5678"), false);
        let start = m.position();
        let before = m.commanded_mm();
        let (a, bytes) = arc_bytes(
            &mut m, "37.123", "-4.5678", "-3.2", "-7.7", false, "0.01", false,
        );
        assert_eq!(a.sweep_arcsec, FULL_TURN_ARCSEC as f64);
        assert_eq!(a.n_margin, f64::INFINITY);
        assert_eq!(
            a.n as i64,
            (FULL_TURN_ARCSEC + a.dphi_arcsec - 1) / a.dphi_arcsec
        );
        assert_eq!((a.nx, a.nz), (0, 0));
        let sum = a.chords.iter().fold((0, 0), |s, c| (s.0 + c.0, s.1 + c.1));
        assert_eq!(sum, (0, 0));
        assert_eq!(net_steps(&bytes.concat()), (0, 0));
        assert!(a.events > 0);
        assert_eq!(m.position(), start);
        assert_eq!(m.commanded_mm(), before);
        // CCW too, and the chords go the other way round.
        let b = m
            .arc("37.123", "-4.5678", "-3.2", "-7.7", true, "0.01", false)
            .unwrap();
        assert_eq!((b.nx, b.nz, b.n), (0, 0, a.n));
        assert_ne!(b.seq, a.seq);
        assert_eq!(m.position(), start);
    }

    #[test]
    fn same_direction_end_is_a_full_circle() {
        // S (X 10, Z 0) radius; C (0, 0); E (X 10.001, Z 0): same direction, R1 − R0 = 0.001.
        let mut m = machine_with(0.001, 0.001, false);
        m.move_block(Some("10"), Some("0"), false);
        let a = m
            .arc("10.001", "0", "-10", "0", true, "0.05", false)
            .unwrap();
        assert_eq!(a.sweep_arcsec, FULL_TURN_ARCSEC as f64);
        assert_eq!((a.nx, a.nz), (1, 0));
        assert_eq!(m.position(), (10_001, 0));
    }

    /// The half circle from (X 20, Z −20) about (20, −30), CCW over (30, −30)
    /// to (20, −40), whole and split at its 90° chord end.
    fn split_half_circle(cfg: RefConfig, ccw: bool) {
        // TOL 0.038054 at R10: Δφ_exact = 36000.46″ → 36000″ = 10°, which divides 90°.
        let tol = "0.038054";
        // The 90° point: X radius 30 (CCW, over the top) or 10 (CW); its I.
        let im = if ccw { "-10" } else { "10" };
        let x_word = |radius: &str| -> String {
            let nm = parse_length_nm(radius).unwrap();
            w(if cfg.diam { 2 * nm } else { nm })
        };
        let top_word = x_word(if ccw { "30" } else { "10" });
        let start_word = x_word("20");
        let mut whole = RefMachine::new(cfg);
        whole.move_block(Some(&start_word), Some("-20"), false);
        let mut split = whole.clone();
        let (a, ab) = arc_bytes(&mut whole, &start_word, "-40", "0", "-10", ccw, tol, false);
        assert_eq!(a.dphi_arcsec, 36_000);
        assert_eq!(a.n, 18);
        assert_eq!(a.n_margin, f64::INFINITY);
        let (b1, bb1) = arc_bytes(&mut split, &top_word, "-30", "0", "-10", ccw, tol, false);
        let (b2, bb2) = arc_bytes(&mut split, &start_word, "-40", im, "0", ccw, tol, false);
        assert_eq!((b1.n, b2.n), (9, 9));
        let mut chords = b1.chords.clone();
        chords.extend(&b2.chords);
        assert_eq!(a.chords, chords);
        assert_eq!(ab.concat(), [bb1.concat(), bb2.concat()].concat());
        assert_eq!(ab, [bb1, bb2].concat());
        let mut crc = crc32fast::Hasher::new_with_initial_len(b1.seq, b1.events);
        crc.combine(&crc32fast::Hasher::new_with_initial_len(b2.seq, b2.events));
        assert_eq!(a.seq, crc.finalize());
        assert_eq!((a.nx, a.nz), (b1.nx + b2.nx, b1.nz + b2.nz));
        assert_eq!(whole.position(), split.position());
        assert_eq!(whole.commanded_mm(), split.commanded_mm());
        assert_eq!(whole, split);
    }

    #[test]
    fn splitting_a_half_circle_at_its_quarter_point() {
        split_half_circle(RefConfig::default(), true);
        split_half_circle(RefConfig::default(), false);
        split_half_circle(
            RefConfig {
                hx_mm: 0.003,
                hz_mm: 0.007,
                diam: false,
            },
            true,
        );
    }

    #[test]
    fn quadrant_point_ties_are_exact() {
        // HX 0.01, HZ 0.01, radius words. S (X 0.0125, Z 0.0125), C (0.0125, 0),
        // R0 = 0.0125 (a whole number of half-nm), TOL = R0/2 → Δφ = 120°
        // exactly; a CCW quarter to (X 0.025, Z 0) is one chord.
        let mut m = machine_with(0.01, 0.01, false);
        m.move_block(Some("0.0125"), Some("0.0125"), false);
        let a = m
            .arc("0.025", "0", "0", "-0.0125", true, "0.00625", false)
            .unwrap();
        assert_eq!(a.dphi_arcsec, 432_000);
        assert_eq!(a.dphi_margin, f64::INFINITY);
        assert_eq!(a.n, 1);
        // X 2.5 impulses: a tie, away from zero.
        assert_eq!((a.px, a.pz), (3, 0));
        assert_eq!(a.quantizer_ties.exact_ties, 1);

        // HX 0.005, HZ 0.01. C (X 0.1, Z −3.3), R0 = 10.0025, S at φ = 0, a CCW
        // half circle. TOL 2.929665 gives Δφ_exact = 324000.034″ → 90°, so the
        // chord end 1 is the quadrant point X = 10.1025 mm = 2020.5 impulses
        // exactly (in f64 10.1025/0.005 = 2020.4999999999998): it rounds to 2021.
        let mut m = machine_with(0.005, 0.01, false);
        m.move_block(Some("0.1"), Some("6.7025"), false);
        assert_eq!(m.position(), (20, 670));
        let (a, bytes) = arc_bytes(
            &mut m, "0.1", "-13.3025", "0", "-10.0025", true, "2.929665", false,
        );
        assert_eq!(a.dphi_arcsec, 324_000);
        assert!((a.dphi_margin - 0.0338).abs() < 1e-3, "{}", a.dphi_margin);
        assert_eq!(a.n, 2);
        assert_eq!(a.chords, vec![(2_001, -1_000), (-2_001, -1_000)]);
        assert_eq!(a.quantizer_ties.exact_ties, 1);
        assert_eq!(net_steps(&bytes.concat()), (0, -2_000));
        assert_eq!((a.px, a.pz), (20, -1_330));
        // Both chords have their ends on the circle (E is on it): sagitta of 90°.
        let sagitta = 10.0025 * (1.0 - std::f64::consts::FRAC_1_SQRT_2);
        assert!((a.max_chord_error_mm - sagitta).abs() < 1e-9);
    }

    #[test]
    fn exact_angular_steps() {
        // TOL = R0 → Δφ = 180° exactly; TOL ≥ 2·R0 → 360°.
        let mut m = machine();
        let a = m.arc("0", "-20", "0", "-10", true, "10", false).unwrap();
        assert_eq!((a.dphi_arcsec, a.n), (648_000, 1));
        assert_eq!(a.dphi_margin, f64::INFINITY);
        assert_eq!(a.chords, vec![(0, -2_000)]);
        assert!((a.max_chord_error_mm - 10.0).abs() < 1e-9);
        let mut m = machine();
        let a = m.arc("0", "0", "0", "-10", false, "20", true).unwrap();
        assert_eq!((a.dphi_arcsec, a.n), (FULL_TURN_ARCSEC, 1));
        assert_eq!(a.chords, vec![(0, 0)]);
        assert_eq!(a.events, 0);
        assert_eq!(a.seq, 0);
        assert!((a.max_chord_error_mm - 20.0).abs() < 1e-6);
        // σ = 1.5·R0 → 240°.
        let mut m = machine();
        let a = m.arc("0", "-20", "0", "-10", true, "15", false).unwrap();
        assert_eq!((a.dphi_arcsec, a.n), (864_000, 1));
    }

    #[test]
    fn eighth_turn_sweep_is_exact() {
        // S (X 0, Z 10) about C (0, 0) to E (X 7.071068, Z 7.071068): the end
        // is on the diagonal exactly (u×v = u·v), R1 = 10.0000003.
        let mut m = machine_with(0.001, 0.001, false);
        m.move_block(Some("0"), Some("10"), false);
        let a = m
            .arc("7.071068", "7.071068", "0", "-10", true, "0.01", false)
            .unwrap();
        assert_eq!(a.sweep_arcsec, 162_000.0);
        assert_eq!(a.n_margin, f64::INFINITY);
        assert_eq!(a.n as i64, (162_000 + a.dphi_arcsec - 1) / a.dphi_arcsec);
        let mut m = machine_with(0.001, 0.001, false);
        m.move_block(Some("0"), Some("10"), false);
        let a = m
            .arc("7.071068", "7.071068", "0", "-10", false, "0.01", false)
            .unwrap();
        assert_eq!(a.sweep_arcsec, (FULL_TURN_ARCSEC - 162_000) as f64);
        // One nanometre off the diagonal: computed in f64.
        let mut m = machine_with(0.001, 0.001, false);
        m.move_block(Some("0"), Some("10"), false);
        let a = m
            .arc("7.071069", "7.071068", "0", "-10", true, "0.01", false)
            .unwrap();
        assert!((a.sweep_arcsec - 162_000.0).abs() < 0.1);
        assert!(a.n_margin.is_finite());
    }

    #[test]
    fn radius_mismatch_0_002_accepted_0_0021_refused() {
        // S (X 0, Z 0), C (0, −5): R0 = 5; E on the Z line of C at X radius R1.
        let try_end = |x_radius: &str| {
            let mut m = machine_with(0.001, 0.001, false);
            let before = m.clone();
            let r = m.arc(x_radius, "-5", "0", "-5", true, "0.01", false);
            if r.is_err() {
                assert_eq!(m, before);
            }
            r.map(|a| a.n)
        };
        assert!(try_end("5.002").is_ok());
        assert!(try_end("4.998").is_ok());
        assert_eq!(try_end("5.0021"), Err(RefArcError::Geometry));
        assert_eq!(try_end("5.002001"), Err(RefArcError::Geometry));
        assert_eq!(try_end("4.997999"), Err(RefArcError::Geometry));
        // Off the axes: R1 = √(3.0012² + 4.0016²) = 5.002 exactly (5.002·(0.6, 0.8)).
        let mut m = machine_with(0.001, 0.001, false);
        assert!(m
            .arc("3.0012", "-0.9984", "0", "-5", true, "0.01", false)
            .is_ok());
        // √(3.0012² + 4.0017²) = 5.0020800… refused; √(3.0012² + 4.00159²) = 5.001992… accepted.
        let mut m = machine_with(0.001, 0.001, false);
        assert_eq!(
            m.arc("3.0012", "-0.9983", "0", "-5", true, "0.01", false),
            Err(RefArcError::Geometry)
        );
        let mut m = machine_with(0.001, 0.001, false);
        assert!(m
            .arc("3.0012", "-0.99841", "0", "-5", true, "0.01", false)
            .is_ok());
        // Exactly at the limit in integers, and one half-nanometre above it.
        assert!(radii_match(100_000_000_000_000, 100_080_016_000_000));
        assert!(!radii_match(100_000_000_000_000, 100_080_016_000_001));
        assert!(radii_match(100_080_016_000_000, 100_000_000_000_000));
    }

    #[test]
    fn refusals_change_nothing() {
        let mut m = machine();
        m.move_block(Some("12.3"), Some("-4.56"), false);
        let before = m.clone();
        let cases: [(&str, &str, &str, &str, &str, RefArcError); 9] = [
            ("x", "0", "1", "1", "0.01", RefArcError::Syntax),
            ("10", "0", "1", "1", "0.01.", RefArcError::Syntax),
            ("10", "0", "1", "1e1", "0.01", RefArcError::Syntax),
            // Zero radius, end at the centre.
            ("12.3", "-4.56", "0", "0", "0.01", RefArcError::Geometry),
            ("14.3", "-3.56", "1", "1", "0.01", RefArcError::Geometry),
            // No angular step: TOL 0 and negative.
            ("12.3", "-4.56", "1", "1", "0", RefArcError::Range),
            ("12.3", "-4.56", "1", "1", "-0.01", RefArcError::Range),
            // R 100, TOL 1 nm: Δφ = ⌊58.3″⌋, a full circle needs 22345 chords.
            ("12.3", "-4.56", "0", "100", "0.000001", RefArcError::Range),
            // End beyond the coordinate limit.
            ("12.3", "-1000000.01", "0", "1", "0.01", RefArcError::Range),
        ];
        for (x, z, i, k, tol, err) in cases {
            assert_eq!(
                m.arc(x, z, i, k, true, tol, false),
                Err(err),
                "{x} {z} {i} {k} {tol}"
            );
            assert_eq!(m, before);
        }
        // A chord over 1 000 000 impulses: a half circle of R 10 mm in one chord
        // at 0.000001 mm per impulse (20 000 000 impulses).
        let mut m = machine_with(0.000001, 0.000001, false);
        let before = m.clone();
        assert_eq!(
            m.arc("0", "-20", "0", "-10", true, "10", false),
            Err(RefArcError::Range)
        );
        assert_eq!(m, before);
        // A register beyond 999 999 999 impulses: a half circle to Z 1000.001 mm at 1 nm.
        let mut m = machine_with(0.000001, 0.000001, false);
        assert_eq!(
            m.arc("0", "1000.001", "0", "500.0005", true, "0.01", false),
            Err(RefArcError::Range)
        );
        assert_eq!(m, before);
        // A direct quarter of R 10 mm at 1 nm: 10 000 000 impulses per axis.
        let mut m = machine_with(0.000001, 0.000001, false);
        assert_eq!(
            m.arc_direct("10", "10", "0", "10", false, None),
            Err(RefArcError::Range)
        );
        // The same quarter at 0.01 mm is accepted.
        let mut m = machine_with(0.01, 0.01, false);
        let d = m.arc_direct("10", "10", "0", "10", false, None).unwrap();
        assert_eq!((d.nx, d.nz, d.px, d.pz), (1_000, 1_000, 1_000, 1_000));
    }

    #[test]
    fn em907_sphere_block() {
        // Ø50 sphere of the seed: HX 0.005, HZ 0.01, start (X radius 21.987, Z 100),
        // end (X radius 24.987, Z 88.1), centre (0, 88.1).
        let mut m = machine();
        m.move_block(Some("43.974"), Some("100"), false);
        let before = m.clone();
        let words = m.em907_words("49.974", "88.1", "-21.987", "-11.9").unwrap();
        assert_eq!(
            words,
            Em907Words {
                j: 4_397,
                k: 1_190,
                dx: 600,
                dz: -1_190
            }
        );
        assert_eq!(m, before);
        // S = 0.05 mm/rev · 710 rpm = 35.5 mm/min, R = 25 mm.
        assert_eq!(feed_word_circular(35.5, 25.0), 1_420);
        assert_eq!(
            em907_block_text(true, words.dx, words.dz, words.j, words.k, Some(1_420)),
            "G03 X+600 Z-1190 J4397 K1190 F1420"
        );
        assert_eq!(em907_block_text(false, 0, 5, 1, 2, None), "G02 Z+5 J1 K2");
        // The seed's radii differ by 0.014 mm: the ARC itself is refused.
        assert_eq!(
            m.arc_direct("49.974", "88.1", "-21.987", "-11.9", true, Some("35.5")),
            Err(RefArcError::Geometry)
        );
        assert_eq!(
            m.arc("49.974", "88.1", "-21.987", "-11.9", true, "0.01", false),
            Err(RefArcError::Geometry)
        );
        assert_eq!(m, before);
        // The same start with the end on the equator (X radius 25, Z 88.1):
        // R0 = 25.0008, R1 = 25, within 0.002 mm.
        let mut m = machine();
        m.move_block(Some("43.974"), Some("100.000"), false);
        let d = m
            .arc_direct("50", "88.1", "-21.987", "-11.9", true, Some("35.5"))
            .unwrap();
        assert_eq!((d.j, d.k, d.nx, d.nz), (4_397, 1_190, 603, -1_190));
        assert_eq!(d.feed_word, Some(1_420));
        assert_eq!(d.block, "G03 X+603 Z-1190 J4397 K1190 F1420");
        assert_eq!((d.px, d.pz), (5_000, 8_810));
    }

    #[test]
    fn feed_words() {
        assert_eq!(feed_word_circular(35.5, 25.0), 1_420);
        assert_eq!(feed_word_linear(100.0, 50.0), 2_000);
        assert_eq!(feed_word_linear(35.5, 12.5), 2_840);
        // Decimal ties round away from zero.
        assert_eq!(feed_word_linear(1.0005, 1.0), 1_001);
        assert_eq!(feed_word_linear(0.0025, 0.005), 500);
        assert_eq!(feed_word_linear(1.0, 3.0), 333);
        assert_eq!(feed_word_circular(2.0, 3.0), 667);
        // Exact decision from the words: S = 1.0005 mm/min, R0 = 1 mm (2·10⁶ half-nm).
        assert_eq!(feed_word_exact(1_000_500, 4_000_000_000_000), 1_001);
        assert_eq!(feed_word_exact(1_000_499, 4_000_000_000_000), 1_000);
        assert_eq!(feed_word_exact(35_500_000, 2_500_000_000_000_000), 1_420);
        // R0 = √2 mm: 1000/√2 = 707.1.
        assert_eq!(feed_word_exact(1_000_000, 8_000_000_000_000), 707);
    }

    #[test]
    fn direct_quarter_by_hand() {
        // HX = HZ = 0.01, radius words: S (X 0, Z 0.05), C (0, 0), E (X 0.05, Z 0), CCW.
        // R = 5 impulses. From (a, b) = (0, 5):
        // X (1,5) |F| 1; X (2,5) 4; D (3,4) 0; D (4,3) 0; D (5,2) 4; Z (5,1) 1; Z (5,0) 0.
        let mut m = machine_with(0.01, 0.01, false);
        m.move_block(Some("0"), Some("0.05"), false);
        let mut bytes = Vec::new();
        let d = m
            .arc_direct_with_steps("0.05", "0", "0", "-0.05", true, Some("10"), &mut |b| {
                bytes.extend_from_slice(b)
            })
            .unwrap();
        assert_eq!(bytes, vec![0x01, 0x01, 0x0B, 0x0B, 0x0B, 0x0A, 0x0A]);
        assert_eq!(d.seq, seq_crc(&bytes));
        assert_eq!(d.events, 7);
        assert_eq!((d.j, d.k, d.nx, d.nz, d.px, d.pz), (0, 5, 5, -5, 5, 0));
        // Worst: (2, 5) and (5, 2), √29 − 5 impulses.
        assert!((d.max_radial_dev_mm - (29f64.sqrt() - 5.0) * 0.01).abs() < 1e-12);
        // F = 10·10³/0.05 = 200000.
        assert_eq!(d.feed_word, Some(200_000));
        assert_eq!(d.block, "G03 X+5 Z-5 J0 K5 F200000");
        assert_eq!(m.position(), (5, 0));
        assert_eq!(m.commanded_mm(), (0.05, 0.0));
        // And back CW.
        let mut back = Vec::new();
        let d = m
            .arc_direct_with_steps("0", "0.05", "-0.05", "0", false, None, &mut |b| {
                back.extend_from_slice(b)
            })
            .unwrap();
        // From (5, 0): Z (5,1) |F| 1; Z (5,2) 4; D (4,3) 0; D (3,4) 0; D (2,5) 4;
        // X (1,5) 1; X (0,5) 0. X steps negative (0x05), Z positive (0x02).
        assert_eq!(back, vec![0x02, 0x02, 0x07, 0x07, 0x07, 0x05, 0x05]);
        assert_eq!((d.j, d.k, d.nx, d.nz), (5, 0, -5, 5));
        assert_eq!(d.block, "G02 X-5 Z+5 J5 K0");
        assert_eq!(m.position(), (0, 5));
    }

    #[test]
    fn direct_tie_takes_the_earlier_candidate() {
        // HX 0.001, HZ 0.004 (units of 0.001 mm: Z steps weigh 4). S (X 0.001,
        // Z 0.004) = (1, 1) about C (0, 0): R² = 1 + 16 = 17. E (X 0.004, Z 0) = (4, 0).
        // (1,1): D (2,0) −13, X (2,1) 3, Z (1,0) −16 → X.
        // (2,1): D (3,0) −8, X (3,1) 8, Z (2,0) −13 → D and X tie at 8: D (earlier).
        // (3,0): X (4,0) −1.
        let mut m = machine_with(0.001, 0.004, false);
        m.move_block(Some("0.001"), Some("0.004"), false);
        let mut bytes = Vec::new();
        let d = m
            .arc_direct_with_steps("0.004", "0", "-0.001", "-0.004", true, None, &mut |b| {
                bytes.extend_from_slice(b)
            })
            .unwrap();
        assert_eq!(bytes, vec![0x01, 0x0B, 0x01]);
        assert_eq!((d.j, d.k, d.nx, d.nz), (1, 1, 3, -1));
        assert_eq!(d.block, "G03 X+3 Z-1 J1 K1");
        // Worst at (3, 0): √17 − 3 units of 0.001 mm.
        assert!((d.max_radial_dev_mm - (17f64.sqrt() - 3.0) * 0.001).abs() < 1e-12);
    }

    #[test]
    fn direct_refuses_outside_one_quadrant() {
        let mut m = machine_with(0.01, 0.01, false);
        m.move_block(Some("0"), Some("0.05"), false);
        let before = m.clone();
        // CW from (0, 5) to (5, 0) goes round 270°.
        assert_eq!(
            m.arc_direct("0.05", "0", "0", "-0.05", false, None),
            Err(RefArcError::Geometry)
        );
        // A half circle crosses two quadrants.
        assert_eq!(
            m.arc_direct("0", "-0.05", "0", "-0.05", true, None),
            Err(RefArcError::Geometry)
        );
        // A full circle.
        assert_eq!(
            m.arc_direct("0", "0.05", "0", "-0.05", true, None),
            Err(RefArcError::Geometry)
        );
        // Radius mismatch.
        assert_eq!(
            m.arc_direct("0.06", "0", "0", "-0.05", true, None),
            Err(RefArcError::Geometry)
        );
        // Feed 0.
        assert_eq!(
            m.arc_direct("0.05", "0", "0", "-0.05", true, Some("0")),
            Err(RefArcError::Range)
        );
        assert_eq!(
            m.arc_direct("0.05", "0", "0", "-0.05", true, Some("fast")),
            Err(RefArcError::Syntax)
        );
        assert_eq!(m, before);
    }

    /// Coordinates in nm of the point at `deg` degrees on a circle of radius
    /// `r_nm` about `(cx, cz)`, rounded to the nanometre: (X radius, Z).
    fn on_circle(cx: i64, cz: i64, r_nm: i64, deg: f64) -> (i64, i64) {
        let (s, c) = deg.to_radians().sin_cos();
        (
            cx + (r_nm as f64 * s).round() as i64,
            cz + (r_nm as f64 * c).round() as i64,
        )
    }

    /// `n` impulses of price `h` in mm.
    fn a1_mm(n: i64, h: f64) -> f64 {
        n as f64 * h
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn finishing_chords_stay_within_tol(
            cx in -200_000_000i64..=200_000_000,
            cz in -300_000_000i64..=100_000_000,
            r_nm in 1_000_000i64..=150_000_000,
            start_deg in 0.0f64..360.0,
            sweep_deg in 0.5f64..360.0,
            ccw in any::<bool>(),
            tol_um in prop::sample::select(vec![1i64, 2, 5, 10, 20, 40, 80]),
            price in prop::sample::select(vec![(0.005, 0.01), (0.001, 0.001), (0.002, 0.005)]),
            diam in any::<bool>(),
        ) {
            let cfg = RefConfig { hx_mm: price.0, hz_mm: price.1, diam };
            let xw = |x_nm: i64| w(if diam { 2 * x_nm } else { x_nm });
            let (sx, sz) = on_circle(cx, cz, r_nm, start_deg);
            let end_deg = if ccw { start_deg + sweep_deg } else { start_deg - sweep_deg };
            let (ex, ez) = on_circle(cx, cz, r_nm, end_deg);
            let tol = w(tol_um * 1_000);
            let mut fin = RefMachine::new(cfg);
            fin.move_block(Some(&xw(sx)), Some(&w(sz)), false);
            let mut rough = fin.clone();
            let (i, k) = (w(cx - sx), w(cz - sz));
            let mut bytes = Vec::new();
            let a = fin
                .arc_with_steps(&xw(ex), &w(ez), &i, &k, ccw, &tol, false, &mut |b| {
                    bytes.extend_from_slice(b)
                })
                .unwrap();
            let r0 = (((sx - cx) as f64).powi(2) + ((sz - cz) as f64).powi(2)).sqrt() / 1e6;
            let r1 = (((ex - cx) as f64).powi(2) + ((ez - cz) as f64).powi(2)).sqrt() / 1e6;
            let tol_mm = tol_um as f64 / 1e3;
            prop_assert!(
                a.max_chord_error_mm <= tol_mm + 2.0 * (r1 - r0).abs() + 1e-12,
                "error {} > TOL {}", a.max_chord_error_mm, tol_mm
            );
            prop_assert!(a.max_chord_error_mm > 0.0);
            // The sweep is the requested one.
            let sweep = a.sweep_arcsec / 3600.0;
            prop_assert!((sweep - sweep_deg).abs() < 1e-3, "{sweep} vs {sweep_deg}");
            prop_assert_eq!(a.n as usize, a.chords.len());
            let sum = a.chords.iter().fold((0, 0), |s, c| (s.0 + c.0, s.1 + c.1));
            prop_assert_eq!(sum, (a.nx, a.nz));
            prop_assert_eq!(net_steps(&bytes), (a.nx, a.nz));
            prop_assert_eq!(a.seq, seq_crc(&bytes));
            prop_assert_eq!(a.events, bytes.len() as u64);
            // Registers end on Q(E/h), computed exactly.
            let qx = price_nm(price.0);
            let qz = price_nm(price.1);
            prop_assert_eq!((a.px, a.pz), (q_exact(ex as i128, qx), q_exact(ez as i128, qz)));
            prop_assert_eq!(fin.position(), (a.px, a.pz));
            // Every chord end lies within half an impulse (per axis) of the circle.
            let mut p = (a.px - a.nx, a.pz - a.nz);
            for (n, c) in a.chords.iter().enumerate() {
                p = (p.0 + c.0, p.1 + c.1);
                if n + 1 < a.chords.len() {
                    let (x, z) = (p.0 as f64 * price.0, p.1 as f64 * price.1);
                    let d = ((x - cx as f64 / 1e6).powi(2) + (z - cz as f64 / 1e6).powi(2)).sqrt();
                    prop_assert!((d - r0).abs() <= 0.5 * price.0.hypot(price.1) + 1e-9);
                }
            }
            prop_assert!(a.quantizer_ties.min_distance > 1e-9);

            // Roughing: Δφ rounded up, never more chords.
            let b = rough.arc(&xw(ex), &w(ez), &i, &k, ccw, &tol, true).unwrap();
            prop_assert!(b.dphi_arcsec >= a.dphi_arcsec);
            prop_assert!(b.dphi_arcsec <= a.dphi_arcsec + 1);
            prop_assert!(b.n <= a.n);
            prop_assert_eq!((b.px, b.pz), (a.px, a.pz));
        }

        #[test]
        fn splitting_at_an_exact_quarter_point(
            cx in -100_000_000i64..=100_000_000,
            cz in -100_000_000i64..=100_000_000,
            quarter in 0i64..4,
            ccw in any::<bool>(),
            price in prop::sample::select(vec![(0.005, 0.01), (0.001, 0.002), (0.003, 0.007)]),
            diam in any::<bool>(),
        ) {
            // R 10 mm, Δφ 10°: the quarter points are chord ends 9 of a half circle.
            let cfg = RefConfig { hx_mm: price.0, hz_mm: price.1, diam };
            let xw = |x_nm: i64| w(if diam { 2 * x_nm } else { x_nm });
            let r = 10_000_000i64;
            let dir = if ccw { 1.0 } else { -1.0 };
            let p0 = on_circle(cx, cz, r, 90.0 * quarter as f64);
            let p1 = on_circle(cx, cz, r, 90.0 * quarter as f64 + dir * 90.0);
            let p2 = on_circle(cx, cz, r, 90.0 * quarter as f64 + dir * 180.0);
            let ik = |p: (i64, i64)| (w(cx - p.0), w(cz - p.1));
            let mut whole = RefMachine::new(cfg);
            whole.move_block(Some(&xw(p0.0)), Some(&w(p0.1)), false);
            let mut split = whole.clone();
            let (i0, k0) = ik(p0);
            let (a, ab) = arc_bytes(&mut whole, &xw(p2.0), &w(p2.1), &i0, &k0, ccw, "0.038054", false);
            prop_assert_eq!((a.n, a.dphi_arcsec), (18, 36_000));
            let (b1, bb1) = arc_bytes(&mut split, &xw(p1.0), &w(p1.1), &i0, &k0, ccw, "0.038054", false);
            let (i1, k1) = ik(p1);
            let (b2, bb2) = arc_bytes(&mut split, &xw(p2.0), &w(p2.1), &i1, &k1, ccw, "0.038054", false);
            prop_assert_eq!([b1.chords.clone(), b2.chords.clone()].concat(), a.chords.clone());
            prop_assert_eq!(ab, [bb1, bb2].concat());
            prop_assert_eq!(whole.position(), split.position());
            prop_assert_eq!((a.nx, a.nz), (b1.nx + b2.nx, b1.nz + b2.nz));
        }

        #[test]
        fn direct_steps_follow_the_quadrant(
            cx in -100_000_000i64..=100_000_000,
            cz in -100_000_000i64..=100_000_000,
            r_nm in 1_000_000i64..=60_000_000,
            quarter in 0i64..4,
            t0 in 2.0f64..88.0,
            t1 in 2.0f64..88.0,
            price in prop::sample::select(vec![
                (0.005, 0.01), (0.001, 0.001), (0.002, 0.005), (0.01, 0.005), (0.01, 0.01),
            ]),
            diam in any::<bool>(),
            feed in prop::option::of(1i64..=2_000_000_000),
        ) {
            prop_assume!((t1 - t0).abs() >= 1.0);
            let cfg = RefConfig { hx_mm: price.0, hz_mm: price.1, diam };
            let xw = |x_nm: i64| w(if diam { 2 * x_nm } else { x_nm });
            let base = 90.0 * quarter as f64;
            let s = on_circle(cx, cz, r_nm, base + t0);
            let e = on_circle(cx, cz, r_nm, base + t1);
            let ccw = t1 > t0;
            let mut m = RefMachine::new(cfg);
            m.move_block(Some(&xw(s.0)), Some(&w(s.1)), false);
            let (px0, pz0) = m.position();
            let mut bytes = Vec::new();
            let feed_word = feed.map(w);
            let d = m
                .arc_direct_with_steps(
                    &xw(e.0), &w(e.1), &w(cx - s.0), &w(cz - s.1), ccw,
                    feed_word.as_deref(), &mut |b| bytes.extend_from_slice(b),
                )
                .unwrap();
            let (qx, qz) = (price_nm(price.0), price_nm(price.1));
            // Ends exactly on the end registers.
            let end = (q_exact(e.0 as i128, qx), q_exact(e.1 as i128, qz));
            prop_assert_eq!((d.px, d.pz), end);
            prop_assert_eq!(net_steps(&bytes), (d.nx, d.nz));
            prop_assert_eq!((px0 + d.nx, pz0 + d.nz), end);
            prop_assert_eq!(d.events, bytes.len() as u64);
            prop_assert_eq!(d.seq, seq_crc(&bytes));
            prop_assert_eq!(d.j, q_exact((cx - s.0).abs() as i128, qx));
            prop_assert_eq!(d.k, q_exact((cz - s.1).abs() as i128, qz));
            // Never leaves the quadrant; radial deviation within one impulse.
            let xc = px0 + (cx - s.0).signum() * d.j;
            let zc = pz0 + (cz - s.1).signum() * d.k;
            let sa = ((base + 45.0).to_radians().sin()).signum() as i64;
            let sb = ((base + 45.0).to_radians().cos()).signum() as i64;
            let r = (((px0 - xc) as f64 * price.0).powi(2)
                + ((pz0 - zc) as f64 * price.1).powi(2)).sqrt();
            let (mut a, mut b) = (px0 - xc, pz0 - zc);
            let mut worst: f64 = 0.0;
            for &byte in &bytes {
                let (dx, dz) = net_steps(&[byte]);
                a += dx;
                b += dz;
                prop_assert!(a * sa >= 0 && b * sb >= 0, "left the quadrant at ({a}, {b})");
                let rho = ((a as f64 * price.0).powi(2) + (b as f64 * price.1).powi(2)).sqrt();
                worst = worst.max((rho - r).abs());
            }
            prop_assert!((worst - d.max_radial_dev_mm).abs() <= 1e-9);
            // The end registers are off the impulse circle by the roundings of
            // PX, J and QX (per axis up to 1.5 impulses); along the way the
            // steps stay within about half an impulse of the circle or of that
            // end offset (observed: ≤ 0.499 impulse over 300 000 arcs).
            let h = price.0.max(price.1);
            let end_dev = (((a1_mm(d.px - xc, price.0)).powi(2)
                + (a1_mm(d.pz - zc, price.1)).powi(2)).sqrt() - r).abs();
            prop_assert!(end_dev <= 1.5 * price.0.hypot(price.1) + 1e-5, "end {end_dev} mm");
            prop_assert!(
                d.max_radial_dev_mm <= end_dev + 0.75 * h,
                "deviation {} mm, end {} mm", d.max_radial_dev_mm, end_dev
            );
            // Steps are monotone per axis.
            for &byte in &bytes {
                let (dx, dz) = net_steps(&[byte]);
                prop_assert!(dx * d.nx >= 0 && dz * d.nz >= 0);
            }
            if let Some(f) = feed {
                let r0 = (((cx - s.0) as f64).powi(2) + ((cz - s.1) as f64).powi(2)).sqrt() / 1e6;
                let fw = d.feed_word.unwrap();
                prop_assert_eq!(fw, feed_word_circular(f as f64 / 1e6, r0));
                let tail = format!(" F{fw}");
                prop_assert!(d.block.ends_with(&tail));
            } else {
                prop_assert!(d.feed_word.is_none());
            }
        }
    }
}

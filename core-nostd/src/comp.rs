//! Tool nose radius compensation over whole contours (G41/G42/G40).
//!
//! The rules are in `docs/compensation.md`; in short: the nose centre runs on
//! the programmed contour offset by the nose radius `r`, corners are closed by
//! intersecting the offset elements (inside corners), by tangent-line
//! intersection or a square-off (outside corners, `G451`) or by a transition
//! arc (`G450`), and the output is the theoretical tool tip (TTT): the nose
//! centre plus the tip vector of the `TIP` code. [`Contour`] keeps one
//! programmed element of look-ahead and nothing else.
//!
//! # Arithmetic
//! Coordinates are whole ångström (10⁻⁷ mm, `|v| < 10¹²`). Corner geometry is
//! computed relative to the programmed corner point, in ångström with 16
//! fractional bits, with unit vectors in Q62; every product fits `i128`, and
//! intersections far from the corner (beyond 2⁴⁰ Å) are treated as having no
//! intersection. A unit vector is within 2⁻⁶⁰ of exact, so a compensated
//! point carries far less than 10⁻³ Å of arithmetic error before it is
//! rounded, half away from zero, to the ångström grid. One exception: two
//! offset circles are intersected from their centres, and where they are
//! nearly tangent (an inside corner between two arcs turning by `θ`, little
//! more than the smooth limit) the point can move along them by the order
//! of 2⁻¹⁵/θ Å. A line and a circle are intersected from the corner, without
//! that loss (see `intersect`).
//!
//! ```
//! use core_nostd::comp::{Contour, Element, Tool};
//! use core_nostd::gcode::Compensation;
//! use core_nostd::length::Length;
//! # use core_nostd::comp::TipCode;
//! let mm = |s: &str| Length::from_mm_str(s).unwrap().as_angstrom();
//! let tool = Tool::new(Length::from_mm_str("0.4").unwrap(), TipCode::EXTERNAL_RIGHT);
//! let line = |from: [&str; 2], to: [&str; 2]| Element::line([mm(from[0]), mm(from[1])], [mm(to[0]), mm(to[1])], false, None);
//! let mut c = Contour::new();
//! // Krylenko Fig. 12 on the radius: the face Z0 up to X14, then the 45° taper.
//! c = c.block(&tool, Some(Compensation::Right), None, Some(line(["0", "0"], ["10", "0"]))).unwrap().0;
//! c = c.block(&tool, None, None, Some(line(["10", "0"], ["14", "0"]))).unwrap().0;
//! let (_, moves) = c.block(&tool, None, None, Some(line(["14", "0"], ["24", "-10"]))).unwrap();
//! // The face ends on the taper's offset: X = 14 − 0.4·(1 − tan 22.5°).
//! assert_eq!(moves[0].to, [137_656_854, 0]);
//! ```

use crate::arc::ArcDir;
use crate::gcode::{Compensation, Corner, CornerRound};
use crate::length::{Length, LENGTH_LIMIT};
use crate::trig::{atan2, isqrt, PI_Q61};
use crate::wide::checked_divrem_i128;

/// Fractional bits of an ångström in corner arithmetic.
const FRAC: u32 = 16;
/// 1 in Q62.
const ONE: i128 = 1 << 62;
/// A corner is smooth when `|sin θ| < 2⁻²²` (and `cos θ > 0`).
const SMOOTH_SIN: i64 = 1 << 40;
/// Intersections farther than 2⁴⁰ Å from the corner do not count.
const FAR: i64 = 1 << (40 + FRAC);
/// Fixed part of the slack by which an arc's compensated sweep may exceed
/// its programmed one, as a length along the offset circle: 2 Å (two steps of
/// the ångström grid, in ångström · 2¹⁶). Rounding each end of the
/// compensated arc to the grid moves it at most √2/2 Å along the arc. The
/// nose radius adds `r·2⁻²¹` (see [`sweep_slack`]).
const SWEEP_SLACK: i64 = 2 << FRAC;
/// `2⁶³/π` (2 935 890 503 282 001 226, rounded down): turns (2⁶⁴ = 360°) per
/// radian. An angle of `a` turns on a circle of radius `ρ` is `a·ρ·2π/2⁶⁴`
/// long, so it is at most `L` long exactly when `a·ρ ≤ L·TURNS_PER_RADIAN`.
const TURNS_PER_RADIAN: u64 = ((1 << 124) / PI_Q61) as u64;

/// A vector `(X, Z)`; its unit depends on use (ångström, ångström · 2¹⁶
/// relative to a corner, or Q62 for a unit vector). Every use stays below
/// 2⁶⁰ in magnitude; products are taken in `i128` by [`mul`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct V {
    x: i64,
    z: i64,
}

impl V {
    const ZERO: V = V { x: 0, z: 0 };

    const fn of(p: [i64; 2]) -> V {
        V { x: p[0], z: p[1] }
    }

    const fn add(self, o: V) -> V {
        V {
            x: self.x + o.x,
            z: self.z + o.z,
        }
    }

    const fn sub(self, o: V) -> V {
        V {
            x: self.x - o.x,
            z: self.z - o.z,
        }
    }

    /// Rotated by +90° in the (Z right, X up) plane: the left normal.
    const fn left(self) -> V {
        V {
            x: self.z,
            z: -self.x,
        }
    }
}

/// `a × b / 2⁶²` in the (Z, X) plane: Q62 for unit vectors.
const fn cross(a: V, b: V) -> i64 {
    ((mul(a.z, b.x) - mul(a.x, b.z)) >> 62) as i64
}

/// `a · b / 2⁶²`: Q62 for unit vectors.
const fn dot(a: V, b: V) -> i64 {
    ((mul(a.z, b.z) + mul(a.x, b.x)) >> 62) as i64
}

/// `a² + b²`, exact.
const fn norm2(v: V) -> i128 {
    mul(v.x, v.x) + mul(v.z, v.z)
}

/// The unit vector along `v` (not zero), Q62, within 2⁻⁶⁰.
#[inline(never)]
fn unit(v: V) -> V {
    let m = v.x.unsigned_abs().max(v.z.unsigned_abs());
    if m == 0 {
        return V::ZERO;
    }
    // Bring the larger component into [2⁶¹, 2⁶²).
    let shift = m.leading_zeros() as i32 - 2;
    let n = if shift >= 0 {
        V {
            x: v.x << shift,
            z: v.z << shift,
        }
    } else {
        V {
            x: v.x >> -shift,
            z: v.z >> -shift,
        }
    };
    // |n| < 2^62.5: the squares sum below 2¹²⁵.
    let len = i128::from(isqrt(norm2(n) as u128));
    if len == 0 {
        return V::ZERO;
    }
    V {
        x: div((n.x as i128) << 62, len) as i64,
        z: div((n.z as i128) << 62, len) as i64,
    }
}

/// `n / 2¹⁶` rounded half away from zero.
const fn round_frac(n: i64) -> i64 {
    let half = 1 << (FRAC - 1);
    if n >= 0 {
        (n + half) >> FRAC
    } else {
        -((-n + half) >> FRAC)
    }
}

/// Which side of the contour the tool is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum Side {
    Left,
    Right,
}

impl Side {
    fn of(c: Compensation) -> Option<Side> {
        match c {
            Compensation::Off => None,
            Compensation::Left => Some(Side::Left),
            Compensation::Right => Some(Side::Right),
        }
    }

    /// The unit normal to this side of the unit direction `t`.
    const fn normal(self, t: V) -> V {
        match self {
            Side::Left => t.left(),
            Side::Right => V { x: -t.z, z: t.x },
        }
    }

    /// +1 left, −1 right: the sign of a turn towards this side.
    const fn sign(self) -> i64 {
        match self {
            Side::Left => 1,
            Side::Right => -1,
        }
    }
}

/// The shape of a programmed element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Shape {
    /// A straight line; `rapid` for G00.
    Line {
        /// G00 rather than G01.
        rapid: bool,
    },
    /// An arc about `centre` (ångström, X radius, Z).
    Arc {
        /// Centre.
        centre: [i64; 2],
        /// Direction.
        dir: ArcDir,
    },
}

/// One programmed motion (a contour element), in ångström, X on the radius.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Element {
    /// Start point.
    pub from: [i64; 2],
    /// End point.
    pub to: [i64; 2],
    /// Line or arc.
    pub shape: Shape,
    /// The block's `N` number, to name it in refusals.
    pub n: Option<u32>,
}

impl Element {
    /// A line from `from` to `to`.
    pub const fn line(from: [i64; 2], to: [i64; 2], rapid: bool, n: Option<u32>) -> Element {
        Element {
            from,
            to,
            shape: Shape::Line { rapid },
            n,
        }
    }

    const fn rapid(&self) -> bool {
        matches!(self.shape, Shape::Line { rapid: true })
    }

    /// The unit direction of travel at `p` (a point of the element).
    fn tangent(&self, p: [i64; 2]) -> V {
        match self.shape {
            Shape::Line { .. } => unit(V::of(self.to).sub(V::of(self.from))),
            Shape::Arc { centre, dir } => {
                let r = V::of(p).sub(V::of(centre));
                match dir {
                    ArcDir::Ccw => unit(r.left()),
                    ArcDir::Cw => unit(V { x: -r.z, z: r.x }),
                }
            }
        }
    }

    /// The radius at `p` (ångström · 2¹⁶, below 2⁵⁸) and whether the tool
    /// is inside the circle; `None` for a line.
    fn radius(&self, p: [i64; 2], side: Side) -> Option<(i64, bool)> {
        let Shape::Arc { centre, dir } = self.shape else {
            return None;
        };
        let d = V::of(p).sub(V::of(centre));
        // R < 2^41.5 Å: R² · 2³² < 2¹¹⁵, R · 2¹⁶ < 2⁵⁸.
        let radius = isqrt((norm2(d) as u128) << (2 * FRAC)) as i64;
        let inside = matches!(
            (side, dir),
            (Side::Left, ArcDir::Ccw) | (Side::Right, ArcDir::Cw)
        );
        Some((radius, inside))
    }

    /// The offset radius at `p` (ångström · 2¹⁶): `R − r` when the tool is
    /// inside the circle, `R + r` otherwise; `None` for a line.
    fn offset_radius(&self, p: [i64; 2], side: Side, r: i64) -> Option<i64> {
        self.radius(p, side)
            .map(|(radius, inside)| if inside { radius - r } else { radius + r })
    }
}

/// A vector in ångström · 2¹⁶.
const fn shl(v: V) -> V {
    V {
        x: v.x << FRAC,
        z: v.z << FRAC,
    }
}

/// `r·n` for a Q62 unit `n` and `r` in ångström · 2¹⁶ (`|r| < 2⁶⁰`).
const fn off(n: V, r: i64) -> V {
    V {
        x: (mul(n.x, r) >> 62) as i64,
        z: (mul(n.z, r) >> 62) as i64,
    }
}

/// An offset element near a corner, relative to the corner: a line through
/// `a` along `t`, or a circle about `c` of radius `rho`. `n` is the tool-side
/// unit normal of the element at the corner (Q62); `s` is the circle's
/// programmed radius, negative when the tool is inside it (ångström · 2¹⁶).
#[derive(Clone, Copy, Debug)]
enum Offset {
    Line { a: V, t: V, n: V },
    Circle { c: V, rho: i64, s: i64, n: V },
}

/// `a · b`, exact. One shared
/// routine: 128-bit products inlined everywhere cost kilobytes of flash.
#[inline(never)]
const fn mul(a: i64, b: i64) -> i128 {
    (a as i128) * (b as i128)
}

/// `a / b` truncated; 0 where the quotient does not exist (callers have
/// excluded `b = 0`).
const fn div(a: i128, b: i128) -> i128 {
    match checked_divrem_i128(a, b) {
        Some((q, _)) => q,
        None => 0,
    }
}

/// The intersection of two offset elements nearest the origin, for the nose
/// radius `r` (ångström · 2¹⁶).
///
/// Inputs are relative to the corner: line points within `2r < 2⁴⁶`, unit
/// vectors in Q62, centres within 2⁴¹ Å (2⁵⁷ in these units) and radii
/// below 2⁵⁸. Under those bounds no product below exceeds 2¹²², so the
/// arithmetic is unchecked; quotients that could grow are bounded first.
///
/// A line and a circle are intersected through the corner's own quantities,
/// so that a corner turning by little (the two elements nearly tangent)
/// loses no precision: both offset elements pass within `2r` of the corner
/// `P`, and with `s` the circle's signed radius and `n` its normal at `P`,
/// its centre is `P − s·n` and its radius `|s + r|`, that is
/// `|X|² − r² + 2s(X·n − r) = 0` for `X` relative to `P`. On the offset line
/// `X = r·nₗ + u·t` (`nₗ ⟂ t`) this is `u² + 2s·w·u − s·r·|nₗ − n|² = 0` with
/// `w = t·n`: small terms computed from unit vectors, never a difference of
/// squares of radii. The two points carry a few units of 2⁻¹⁶ Å of error
/// whatever the angle between the elements.
#[inline(never)]
fn intersect(a: Offset, b: Offset, r: i64) -> Option<V> {
    let points = match (a, b) {
        (Offset::Line { a: a1, t: t1, .. }, Offset::Line { a: a2, t: t2, .. }) => {
            let w = a2.sub(a1);
            let den = i128::from(cross(t1, t2));
            if den == 0 {
                return None;
            }
            let s = div(mul(w.z, t2.x) - mul(w.x, t2.z), den);
            if s.abs() >= i128::from(FAR) {
                return None;
            }
            [Some(a1.add(off(t1, s as i64))), None]
        }
        (Offset::Line { a, t, n: nl }, Offset::Circle { s, n, .. })
        | (Offset::Circle { s, n, .. }, Offset::Line { a, t, n: nl }) => {
            // |s| < 2⁵⁸, |w| ≤ 2⁶²: s·w < 2¹²⁰; |nₗ − n| ≤ 2 (2⁶³ in Q62):
            // s·|d| < 2¹²¹, r·|d| < 2¹⁰⁸; the discriminant stays below 2¹¹⁷.
            let sw = (mul(s, dot(t, n)) >> 62) as i64;
            // |nₗ − n|² = |nₗ|² + |n|² − 2 nₗ·n, exact in Q124; an inside
            // corner is no reversal, so |nₗ − n| < 2 − 2⁻⁴⁶: below 2⁶³ in Q62.
            let cos = mul(nl.x, n.x) + mul(nl.z, n.z);
            let d = isqrt(((norm2(nl) - cos) + (norm2(n) - cos)) as u128) as i64;
            let sd = mul(s, d) >> 62;
            let rd = mul(r, d) >> 62;
            let disc = mul(sw, sw) + sd * rd;
            if disc < 0 {
                return None;
            }
            let root = isqrt(disc as u128) as i64;
            [
                Some(a.add(off(t, root - sw))),
                Some(a.add(off(t, -root - sw))),
            ]
        }
        (Offset::Circle { c: c1, rho: r1, .. }, Offset::Circle { c: c2, rho: r2, .. }) => {
            let d = c2.sub(c1);
            let dd = norm2(d);
            let dist = i128::from(isqrt(dd as u128));
            if dist == 0 {
                return None;
            }
            let along = div(mul(r1, r1) - mul(r2, r2) + dd, 2 * dist);
            if along.abs() > i128::from(r1) {
                return None;
            }
            let along = along as i64;
            let h = isqrt((mul(r1, r1) - mul(along, along)) as u128) as i64;
            let scaled = |v: V, k: i64| V {
                x: div(mul(v.x, k), dist) as i64,
                z: div(mul(v.z, k), dist) as i64,
            };
            let base = c1.add(scaled(d, along));
            let side = scaled(d.left(), h);
            [Some(base.add(side)), Some(base.sub(side))]
        }
    };
    let mut best: Option<(i128, V)> = None;
    for p in points.into_iter().flatten() {
        if p.x.abs() >= FAR || p.z.abs() >= FAR {
            continue;
        }
        let d = norm2(p);
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, p));
        }
    }
    best.map(|(_, p)| p)
}

/// Tool tip orientation code 0…9 (Fanuc/Haas convention, `docs/protocol.md` §4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TipCode(u8);

impl TipCode {
    /// An external right-hand turning tool.
    pub const EXTERNAL_RIGHT: TipCode = TipCode(3);

    /// A code from its digit, if 0…9.
    pub const fn new(code: u8) -> Option<TipCode> {
        if code <= 9 {
            Some(TipCode(code))
        } else {
            None
        }
    }

    /// The digit.
    pub const fn get(self) -> u8 {
        self.0
    }
}

/// The tool: nose radius and tip code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tool {
    r: i64,
    tip: [i64; 2],
}

impl Tool {
    /// A tool of nose radius `rn` (0 … 25 mm) and tip code `tip`.
    pub const fn new(rn: Length, tip: TipCode) -> Tool {
        let r = rn.as_angstrom();
        let tip = match tip.get() {
            1 => [r, r],
            2 => [r, -r],
            3 => [-r, -r],
            4 => [-r, r],
            5 => [0, r],
            6 => [r, 0],
            7 => [0, -r],
            8 => [-r, 0],
            _ => [0, 0],
        };
        Tool { r, tip }
    }

    /// The tip vector, nose centre to the theoretical tool tip, Å (X on the
    /// radius, Z): what the tip code places where.
    pub const fn tip_vector(&self) -> [i64; 2] {
        self.tip
    }

    /// The nose radius in ångström · 2¹⁶.
    const fn r(&self) -> i64 {
        self.r << FRAC
    }

    /// The TTT of a nose-centre point.
    const fn ttt(&self, p: [i64; 2]) -> [i64; 2] {
        [p[0] + self.tip[0], p[1] + self.tip[1]]
    }
}

/// What the tool does along one output block: a line, or an arc about the
/// tool-tip centre.
pub type MoveKind = Shape;

/// Which programmed block an output block belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Origin {
    /// The motion block before this one (sent one block late).
    Previous,
    /// The block before this one that asked for a chamfer or round (`,C`,
    /// `,R`) at its end: its move cut short and the chamfer or round, sent
    /// with this block.
    Waiting,
    /// A corner between the previous block and this one.
    Corner,
    /// This block.
    Current,
}

/// One output block: the theoretical tool tip moves from where the previous
/// block left it to `to` (ångström, X on the radius).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Move {
    /// End point of the TTT.
    pub to: [i64; 2],
    /// Line or arc.
    pub kind: MoveKind,
    /// The programmed block it comes from.
    pub origin: Origin,
}

/// The most blocks one element sends through compensation: the element
/// before it and three corner moves.
const STEP_MOVES: usize = 4;

/// The most blocks one request can send: with a corner's chamfer or round
/// (`,C`, `,R`), three elements (the move before cut short, the chamfer or
/// round, this block's move), each with its corner moves.
pub const MAX_MOVES: usize = 3 * STEP_MOVES;

/// The blocks a programmed block sends.
pub type Moves = heapless::Vec<Move, MAX_MOVES>;

/// Why a block was refused (`ERR GEOMETRY`); numbers are the blocks' `N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CompError {
    /// An arc with the tool inside whose radius is not larger than the nose
    /// radius.
    ConcaveRadius(Option<u32>),
    /// The compensated motion of block `.0` would reverse against the
    /// programmed one at its corner with block `.1`.
    TooShort(Option<u32>, Option<u32>),
    /// The offset elements of blocks `.0` and `.1` do not meet.
    NoCorner(Option<u32>, Option<u32>),
    /// G41/G42 first takes effect in an arc block.
    OnInArc(Option<u32>),
    /// G40 in an arc block.
    OffInArc(Option<u32>),
    /// G41 while G42 is on, or the reverse.
    SideChange(Option<u32>),
    /// A compensated point beyond the coordinate range.
    Range(Option<u32>),
    /// A chamfer or round (`,C`, `,R`) waits for the next move, which this
    /// block (`.1`) is not: after block `.0` comes a G01, G02 or G03
    /// move, without G40, G41 or G42.
    RoundNext(Option<u32>, Option<u32>),
    /// A chamfer or round asked for in a block that is not a G01, G02 or
    /// G03 move, or that switches compensation.
    RoundHere(Option<u32>),
    /// The chamfer or round between blocks `.0` and `.1` does not fit on
    /// them (or leaves one of them no length).
    RoundTooBig(Option<u32>, Option<u32>),
    /// Blocks `.0` and `.1` meet without a corner (they go on, or back,
    /// along the same direction): nothing to chamfer or round.
    RoundNoCorner(Option<u32>, Option<u32>),
    /// A chamfer (`,C`) where block `.0` or `.1` is an arc: a chamfer joins
    /// two lines (`,R` rounds arcs too).
    ChamferArc(Option<u32>, Option<u32>),
    /// After block `.0`'s right-angle chamfer or round (`G01 Z… I…`), block
    /// `.1` is not a `G01` along the other axis alone in the direction of
    /// the word's sign.
    RoundSquare(Option<u32>, Option<u32>),
}

/// The compensation state between blocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum State {
    /// No element waits.
    Idle,
    /// The start-up line waits for the element after it.
    Startup(Element),
    /// An element waits for its end corner; it starts at the nose-centre
    /// point `start`.
    Pending { e: Element, start: [i64; 2] },
}

/// A programmed element that waits for the next one, its end corner to be
/// chamfered or rounded by `size` (ångström).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Rounding {
    e: Element,
    chamfer: bool,
    size: i64,
    /// A right angle's (`G01 Z… I…`): the next move's axis (0 X, 1 Z)
    /// and whether it goes towards plus.
    square: Option<(u8, bool)>,
}

/// The contour engine: modal compensation and corner mode, at most one
/// element waiting for its corner to be chamfered or rounded, and at most
/// one waiting for its compensated end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Contour {
    mode: Compensation,
    corner: Corner,
    round: Option<Rounding>,
    state: State,
}

impl Default for Contour {
    fn default() -> Self {
        Self::new()
    }
}

impl Contour {
    /// Power-on: G40, G451.
    pub const fn new() -> Contour {
        Contour {
            mode: Compensation::Off,
            corner: Corner::Intersection,
            round: None,
            state: State::Idle,
        }
    }

    /// The modal compensation (G40, G41, G42).
    pub const fn mode(&self) -> Compensation {
        self.mode
    }

    /// The modal corner mode (G450, G451).
    pub const fn corner(&self) -> Corner {
        self.corner
    }

    /// Whether compensation is on or armed: the tool is not at the programmed
    /// point, or will leave it at the next motion.
    pub const fn active(&self) -> bool {
        !matches!(self.mode, Compensation::Off)
            || !matches!(self.state, State::Idle)
            || self.round.is_some()
    }

    /// The `N` of the block whose move waits for the next one to chamfer
    /// or round their corner, if one waits.
    pub const fn waiting(&self) -> Option<Option<u32>> {
        match self.round {
            Some(w) => Some(w.e.n),
            None => None,
        }
    }

    /// Whether a move waits for the next one to chamfer or round their
    /// corner (`,C`, `,R`): the next block must be a G01, G02 or G03 move.
    pub const fn rounding(&self) -> bool {
        self.round.is_some()
    }

    /// [`Contour::block`] with the block's corner chamfer or round (`,C`,
    /// `,R`; `round`); `n` is the block's `N`, for refusals. A move that asks for one waits for the next move;
    /// that one's block sends the first cut short, the chamfer or round,
    /// and itself from where they end, each through compensation as any
    /// element. Moves of the waiting block's share (the first two) are
    /// [`Origin::Waiting`]. `self` is not changed.
    #[inline(never)]
    pub fn rounded(
        &self,
        tool: &Tool,
        comp: Option<Compensation>,
        corner: Option<Corner>,
        motion: Option<Element>,
        round: Option<CornerRound>,
        n: Option<u32>,
    ) -> Result<(Contour, Moves), CompError> {
        let feeds = |e: &Element| !e.rapid();
        // The elements to compensate, and whether each is the waiting
        // block's (true) or this one's.
        let mut elements = heapless::Vec::<(Element, bool), 3>::new();
        let mut motion = motion;
        if let Some(w) = self.round {
            let e2 = match motion {
                Some(e2) if feeds(&e2) && comp.is_none() => e2,
                _ => return Err(CompError::RoundNext(w.e.n, n)),
            };
            if let Some((axis, plus)) = w.square {
                // Along that axis alone, that way, in a line.
                let d = [e2.to[0] - w.e.to[0], e2.to[1] - w.e.to[1]];
                let (along, across) = if axis == 0 {
                    (d[0], d[1])
                } else {
                    (d[1], d[0])
                };
                if !matches!(e2.shape, Shape::Line { .. })
                    || across != 0
                    || (along > 0) != plus
                    || along == 0
                {
                    return Err(CompError::RoundSquare(w.e.n, n));
                }
            }
            let (first, joint, rest) = round_corner(&w, &e2)?;
            for e in first.into_iter().chain([joint]) {
                let _ = elements.push((e, true));
            }
            motion = Some(rest);
        }
        let mut next_round = None;
        match (round, motion) {
            (None, Some(e)) => {
                let _ = elements.push((e, false));
            }
            (None, None) => {}
            (Some(r), Some(e)) if feeds(&e) && comp.is_none() => {
                let (chamfer, size, square) = match r {
                    CornerRound::Chamfer(c) => (true, c.as_angstrom(), None),
                    CornerRound::Round(r) => (false, r.as_angstrom(), None),
                    CornerRound::Square {
                        size,
                        chamfer,
                        next,
                        plus,
                    } => (chamfer, size.as_angstrom(), Some((next, plus))),
                };
                next_round = Some(Rounding {
                    e,
                    chamfer,
                    size,
                    square,
                });
            }
            (Some(_), _) => return Err(CompError::RoundHere(n)),
        }
        let mut c = Contour {
            round: None,
            ..*self
        };
        let mut moves = Moves::new();
        if elements.is_empty() {
            let (after, m) = c.block(tool, comp, corner, None)?;
            c = after;
            moves = m;
        }
        // Whose the element before the one compensated is: the block before
        // this request's, then the waiting block's.
        let mut before = Origin::Previous;
        for (i, &(e, waiting)) in elements.iter().enumerate() {
            let (words, corner_word) = if i == 0 { (comp, corner) } else { (None, None) };
            let (after, m) = c.block(tool, words, corner_word, Some(e))?;
            let own = if waiting {
                Origin::Waiting
            } else {
                Origin::Current
            };
            for mv in &m {
                let origin = match mv.origin {
                    Origin::Previous | Origin::Waiting => before,
                    Origin::Corner if !waiting => Origin::Corner,
                    Origin::Current | Origin::Corner => own,
                };
                push(&mut moves, mv.to, mv.kind, origin)?;
            }
            before = own;
            c = after;
        }
        c.round = next_round;
        Ok((c, moves))
    }

    /// Runs one block: its compensation and corner words and its motion
    /// (`None` for a block without one; with compensation on, a line that
    /// does not move counts as none). Returns the state after it
    /// and the TTT blocks it sends, or the refusal; `self` is not changed,
    /// so the caller commits only what it can also execute.
    #[inline(never)]
    pub fn block(
        &self,
        tool: &Tool,
        comp: Option<Compensation>,
        corner: Option<Corner>,
        motion: Option<Element>,
    ) -> Result<(Contour, Moves), CompError> {
        let n = motion.and_then(|e| e.n);
        let mode = comp.unwrap_or(self.mode);
        // With compensation on (or ending), a line that does not move is not
        // an element: it is passed over.
        let compensating = self.active() || Side::of(mode).is_some();
        let motion = motion
            .filter(|e| !(compensating && e.from == e.to && matches!(e.shape, Shape::Line { .. })));
        if let (Some(a), Some(b)) = (Side::of(self.mode), Side::of(mode)) {
            if a != b {
                return Err(CompError::SideChange(n));
            }
        }
        let mut next = Contour {
            mode,
            corner: corner.unwrap_or(self.corner),
            round: self.round,
            state: self.state,
        };
        let mut moves = Moves::new();
        let r = tool.r();
        let arc = matches!(
            motion,
            Some(Element {
                shape: Shape::Arc { .. },
                ..
            })
        );
        match (Side::of(mode), self.state) {
            (None, state) => {
                if arc && !matches!(state, State::Idle) {
                    return Err(CompError::OffInArc(n));
                }
                match state {
                    State::Idle => {}
                    State::Startup(s) => {
                        let side = Side::of(self.mode).unwrap_or(Side::Left);
                        let end = perpendicular(&s, s.to, side, r)?;
                        push(
                            &mut moves,
                            tool.ttt(end),
                            MoveKind::Line { rapid: s.rapid() },
                            Origin::Previous,
                        )?;
                    }
                    State::Pending { e, start } => {
                        let side = Side::of(self.mode).unwrap_or(Side::Left);
                        let end = perpendicular(&e, e.to, side, r)?;
                        check_direction(&e, start, end, None, side, r)?;
                        push(
                            &mut moves,
                            tool.ttt(end),
                            element_kind(&e, tool),
                            Origin::Previous,
                        )?;
                    }
                }
                if let Some(e) = motion {
                    // Compensation off: the block as programmed.
                    push(&mut moves, e.to, e.shape, Origin::Current)?;
                }
                next.state = State::Idle;
            }
            (Some(_), State::Idle) => {
                if let Some(e) = motion {
                    if arc {
                        return Err(CompError::OnInArc(n));
                    }
                    next.state = State::Startup(e);
                }
            }
            (Some(side), State::Startup(s)) => {
                if let Some(e) = motion {
                    check_concave(&e, side, r)?;
                    let start = perpendicular(&e, e.from, side, r)?;
                    push(
                        &mut moves,
                        tool.ttt(start),
                        MoveKind::Line { rapid: s.rapid() },
                        Origin::Previous,
                    )?;
                    next.state = State::Pending { e, start };
                }
            }
            (Some(side), State::Pending { e: e1, start }) => {
                if let Some(e2) = motion {
                    check_concave(&e2, side, r)?;
                    let c = corner_of(&e1, &e2, side, next.corner, r)?;
                    check_direction(&e1, start, c.end, e2.n, side, r)?;
                    push(
                        &mut moves,
                        tool.ttt(c.end),
                        element_kind(&e1, tool),
                        Origin::Previous,
                    )?;
                    for m in c.inserted.iter().flatten() {
                        let kind = match m.kind {
                            MoveKind::Line { .. } => MoveKind::Line {
                                rapid: e1.rapid() && e2.rapid(),
                            },
                            MoveKind::Arc { centre, dir } => MoveKind::Arc {
                                centre: tool.ttt(centre),
                                dir,
                            },
                        };
                        let from = moves.last().map(|l| l.to).unwrap_or(tool.ttt(c.end));
                        let to = tool.ttt(m.to);
                        if to != from {
                            push(&mut moves, to, kind, Origin::Corner)?;
                        }
                    }
                    next.state = State::Pending {
                        e: e2,
                        start: c.start,
                    };
                }
            }
        }
        Ok((next, moves))
    }
}

/// The element `e` offset by `r` (ångström · 2¹⁶) to `side`, relative to
/// its point `p` where its unit direction is `t`: a line through its
/// perpendicular offset point, a circle about the arc's centre.
#[inline(never)]
fn offset(e: &Element, p: [i64; 2], t: V, side: Side, r: i64) -> Offset {
    let n = side.normal(t);
    match (e.shape, e.radius(p, side)) {
        (Shape::Arc { centre, .. }, Some((radius, inside))) => Offset::Circle {
            c: shl(V::of(centre).sub(V::of(p))),
            rho: if inside { radius - r } else { radius + r },
            s: if inside { -radius } else { radius },
            n,
        },
        _ => Offset::Line { a: off(n, r), t, n },
    }
}

/// The waiting element `w.e` and the next one `e2` with their corner
/// chamfered or rounded (`docs/compensation.md` §8): the waiting element
/// cut short (`None` when nothing of it is left), the chamfer or round,
/// and `e2` from where that ends.
#[inline(never)]
fn round_corner(
    w: &Rounding,
    e2: &Element,
) -> Result<(Option<Element>, Element, Element), CompError> {
    let e1 = &w.e;
    let (n1, n2) = (e1.n, e2.n);
    let p = e1.to;
    let too_big = CompError::RoundTooBig(n1, n2);
    let at = |v: V| absolute(p, v, n2).map_err(|_| too_big);
    let (t1, t2) = (e1.tangent(p), e2.tangent(p));
    let s = cross(t1, t2);
    if s.abs() < SMOOTH_SIN {
        return Err(CompError::RoundNoCorner(n1, n2));
    }
    // The size in ångström · 2¹⁶ (at most 10¹² Å: below 2⁵⁶).
    let size = w.size << FRAC;
    let (end1, joint, start2) = if w.chamfer {
        if !matches!(e1.shape, Shape::Line { .. }) || !matches!(e2.shape, Shape::Line { .. }) {
            return Err(CompError::ChamferArc(n1, n2));
        }
        let a = at(off(t1, -size))?;
        let b = at(off(t2, size))?;
        (a, Element::line(a, b, false, n1), b)
    } else {
        // The round's centre: on the inside of the turn, the intersection
        // of the two elements offset by the radius (an inside corner of a
        // nose of that radius).
        let side = if s > 0 { Side::Left } else { Side::Right };
        let (o1, o2) = (offset(e1, p, t1, side, size), offset(e2, p, t2, side, size));
        for o in [o1, o2] {
            if let Offset::Circle { rho, .. } = o {
                if rho <= 0 {
                    return Err(too_big);
                }
            }
        }
        let x = intersect(o1, o2, size).ok_or(too_big)?;
        // Where the round touches an element: from the centre back along
        // the element's normal, or towards the arc's centre.
        let foot = |o: Offset| match o {
            Offset::Line { n, .. } => x.sub(off(n, size)),
            Offset::Circle { c, rho, s, .. } => {
                let radius = s.abs();
                let d = x.sub(c);
                c.add(V {
                    x: div(mul(d.x, radius), i128::from(rho)) as i64,
                    z: div(mul(d.z, radius), i128::from(rho)) as i64,
                })
            }
        };
        let (a, b) = (at(foot(o1))?, at(foot(o2))?);
        let centre = at(x)?;
        let dir = match side {
            Side::Left => ArcDir::Ccw,
            Side::Right => ArcDir::Cw,
        };
        (
            a,
            Element {
                from: a,
                to: b,
                shape: Shape::Arc { centre, dir },
                n: n1,
            },
            b,
        )
    };
    // Both points on their elements, the waiting one's after its start
    // (its start may be where a round before it ended), the next one's
    // before its end.
    if !on_element(e1, e1.from, end1) || !on_element(e2, start2, e2.to) || start2 == e2.to {
        return Err(too_big);
    }
    let first = (end1 != e1.from).then_some(Element { to: end1, ..*e1 });
    Ok((
        first,
        joint,
        Element {
            from: start2,
            ..*e2
        },
    ))
}

/// The turn from `a` to `b` about `centre` in the direction `dir`, in
/// turns (2⁶⁴ = 360°).
#[inline(never)]
fn sweep(centre: [i64; 2], dir: ArcDir, a: [i64; 2], b: [i64; 2]) -> u64 {
    let angle = |p: [i64; 2]| {
        let v = V::of(p).sub(V::of(centre));
        atan2(i128::from(v.x), i128::from(v.z)).0
    };
    match dir {
        ArcDir::Ccw => angle(b).wrapping_sub(angle(a)),
        ArcDir::Cw => angle(a).wrapping_sub(angle(b)),
    }
}

/// Whether the points `a` and `b` of `e` lie within its programmed extent
/// in this order (`a` at or before `b`).
fn on_element(e: &Element, a: [i64; 2], b: [i64; 2]) -> bool {
    match e.shape {
        Shape::Line { .. } => {
            let d = V::of(e.to).sub(V::of(e.from));
            let along = |q: [i64; 2]| {
                let v = V::of(q).sub(V::of(e.from));
                mul(v.x, d.x) + mul(v.z, d.z)
            };
            let (la, lb) = (along(a), along(b));
            0 <= la && la <= lb && lb <= norm2(d)
        }
        Shape::Arc { centre, dir } => {
            let whole = if e.from == e.to {
                u64::MAX
            } else {
                sweep(centre, dir, e.from, e.to)
            };
            let fa = if a == e.from {
                0
            } else {
                sweep(centre, dir, e.from, a)
            };
            let fb = if b == e.to {
                whole
            } else {
                sweep(centre, dir, e.from, b)
            };
            fa <= fb && fb <= whole
        }
    }
}

fn push(moves: &mut Moves, to: [i64; 2], kind: MoveKind, origin: Origin) -> Result<(), CompError> {
    moves
        .push(Move { to, kind, origin })
        .map_err(|_| CompError::Range(None))
}

/// The output kind of a compensated element: its TTT arc keeps the centre
/// shifted by the tip vector.
const fn element_kind(e: &Element, tool: &Tool) -> MoveKind {
    match e.shape {
        Shape::Line { rapid } => MoveKind::Line { rapid },
        Shape::Arc { centre, dir } => MoveKind::Arc {
            centre: tool.ttt(centre),
            dir,
        },
    }
}

/// Refuses an arc the nose cannot follow on the inside.
fn check_concave(e: &Element, side: Side, r: i64) -> Result<(), CompError> {
    for p in [e.from, e.to] {
        if e.offset_radius(p, side, r).is_some_and(|rho| rho <= 0) {
            return Err(CompError::ConcaveRadius(e.n));
        }
    }
    Ok(())
}

/// The perpendicular offset point of `e` at its point `p`, rounded.
fn perpendicular(e: &Element, p: [i64; 2], side: Side, r: i64) -> Result<[i64; 2], CompError> {
    absolute(p, off(side.normal(e.tangent(p)), r), e.n)
}

/// `origin + v` for `v` in ångström · 2¹⁶, rounded to the ångström grid and
/// checked against the coordinate range.
fn absolute(origin: [i64; 2], v: V, n: Option<u32>) -> Result<[i64; 2], CompError> {
    let lim = LENGTH_LIMIT.as_angstrom();
    // |o| ≤ 10¹² and |d| < 2⁶⁰ · 2⁻¹⁶: the sum fits.
    let one = |o: i64, d: i64| -> Result<i64, CompError> {
        let a = o + round_frac(d);
        if a.abs() > lim {
            return Err(CompError::Range(n));
        }
        Ok(a)
    };
    Ok([one(origin[0], v.x)?, one(origin[1], v.z)?])
}

/// The slack by which an arc's compensated sweep may exceed its programmed
/// one, as a length along the offset circle (ångström · 2¹⁶): [`SWEEP_SLACK`]
/// for rounding both ends to the grid, and `r·2⁻²¹` for the nose radius `r`
/// (ångström · 2¹⁶, at most 25 mm), twice the most a smooth corner moves the
/// arc's start (`r·sin θ`, `|sin θ| < 2⁻²²`). Below 2²⁴.
const fn sweep_slack(r: i64) -> i64 {
    SWEEP_SLACK.saturating_add(r >> 21)
}

/// Refuses an element whose compensated motion from `start` to `end` does not
/// keep its programmed direction: a line whose motion is not ahead along the
/// programmed direction, an arc whose compensated sweep is zero or longer than
/// the programmed sweep by more than [`sweep_slack`] along the offset circle
/// (the excess angle times the smaller of the offset radii at the arc's two
/// ends). `side` and `r` (ångström · 2¹⁶) are the tool's.
#[inline(never)]
fn check_direction(
    e: &Element,
    start: [i64; 2],
    end: [i64; 2],
    next: Option<u32>,
    side: Side,
    r: i64,
) -> Result<(), CompError> {
    let short = Err(CompError::TooShort(e.n, next));
    match e.shape {
        Shape::Line { .. } => {
            let d = V::of(e.to).sub(V::of(e.from));
            let c = V::of(end).sub(V::of(start));
            if mul(d.x, c.x) + mul(d.z, c.z) <= 0 {
                return short;
            }
        }
        Shape::Arc { centre, dir } => {
            let sweep = |a: [i64; 2], b: [i64; 2]| sweep(centre, dir, a, b);
            let full = e.from == e.to;
            let programmed = if full { u64::MAX } else { sweep(e.from, e.to) };
            let done = sweep(start, end);
            if start == end {
                if !full {
                    return short;
                }
            } else if full && done < 1 << 63 {
                return short;
            } else if done > programmed {
                // The excess as a length along the offset circle, on the
                // smaller of its radii (below 2⁵⁸, positive: concave arcs
                // were checked when they arrived); turns · 2⁶⁴ times
                // ångström · 2¹⁶ stays below 2¹²².
                let radius = |p| e.offset_radius(p, side, r).unwrap_or(0);
                let rho = radius(e.from).min(radius(e.to));
                let Ok(rho @ 1..) = u64::try_from(rho) else {
                    return short;
                };
                let excess = u128::from(done.wrapping_sub(programmed)) * u128::from(rho);
                // Below 2²⁴ · 2⁶².
                let slack =
                    u128::from(sweep_slack(r).unsigned_abs()) * u128::from(TURNS_PER_RADIAN);
                if excess > slack {
                    return short;
                }
            }
        }
    }
    Ok(())
}

/// How one corner is closed: where the first element ends, the moves
/// inserted (nose-centre points), where the second starts.
struct CornerPlan {
    end: [i64; 2],
    inserted: [Option<Move>; 3],
    start: [i64; 2],
}

#[inline(never)]
fn corner_of(
    e1: &Element,
    e2: &Element,
    side: Side,
    mode: Corner,
    r: i64,
) -> Result<CornerPlan, CompError> {
    let p = e1.to;
    let (n1, n2) = (e1.n, e2.n);
    let at = |v: V| absolute(p, v, n2);
    let (t1, t2) = (e1.tangent(p), e2.tangent(p));
    let (s, c) = (cross(t1, t2), dot(t1, t2));
    let a1 = off(side.normal(t1), r);
    let a2 = off(side.normal(t2), r);
    let line1 = matches!(e1.shape, Shape::Line { .. });
    let line2 = matches!(e2.shape, Shape::Line { .. });
    let straight = |v: V| -> Result<Option<Move>, CompError> {
        Ok(Some(Move {
            to: at(v)?,
            kind: MoveKind::Line { rapid: false },
            origin: Origin::Corner,
        }))
    };
    if s.abs() < SMOOTH_SIN && c > 0 {
        let end = at(a1)?;
        return Ok(CornerPlan {
            end,
            inserted: [None; 3],
            start: end,
        });
    }
    let reversal = s.abs() < SMOOTH_SIN;
    if !reversal && s * side.sign() > 0 {
        // Inside: intersect the offset elements.
        let x = intersect(offset(e1, p, t1, side, r), offset(e2, p, t2, side, r), r)
            .ok_or(CompError::NoCorner(n1, n2))?;
        let x = at(x)?;
        return Ok(CornerPlan {
            end: x,
            inserted: [None; 3],
            start: x,
        });
    }
    match mode {
        Corner::Arc => Ok(CornerPlan {
            end: at(a1)?,
            inserted: [
                Some(Move {
                    to: at(a2)?,
                    kind: MoveKind::Arc {
                        centre: p,
                        dir: match side {
                            Side::Left => ArcDir::Cw,
                            Side::Right => ArcDir::Ccw,
                        },
                    },
                    origin: Origin::Corner,
                }),
                None,
                None,
            ],
            start: at(a2)?,
        }),
        Corner::Intersection => {
            let (v1, v2) = if c >= 0 {
                // tan(θ/2) = sin θ / (1 + cos θ) ≤ 1.
                let l = div(mul(r, s.abs()), ONE + i128::from(c)) as i64;
                let v = a1.add(off(t1, l));
                (v, v)
            } else {
                (a1.add(off(t1, r)), a2.sub(off(t2, r)))
            };
            let mut inserted = [None; 3];
            let end = if line1 {
                at(v1)?
            } else {
                inserted[0] = straight(v1)?;
                at(a1)?
            };
            if v1 != v2 {
                inserted[1] = straight(v2)?;
            }
            let start = if line2 {
                at(v2)?
            } else {
                inserted[2] = straight(a2)?;
                at(a2)?
            };
            Ok(CornerPlan {
                end,
                inserted,
                start,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    const MM: i64 = 10_000_000;

    fn line(from: [i64; 2], to: [i64; 2]) -> Element {
        Element::line(from, to, false, None)
    }

    /// Runs blocks (element, corner) with compensation off; every move.
    fn corners(
        blocks: &[(Element, Option<CornerRound>)],
    ) -> Result<std::vec::Vec<Move>, CompError> {
        let tool = Tool::new(
            Length::ZERO,
            TipCode::new(0).unwrap_or(TipCode::EXTERNAL_RIGHT),
        );
        let mut c = Contour::new();
        let mut out = std::vec::Vec::new();
        for &(e, r) in blocks {
            let (next, moves) = c.rounded(&tool, None, None, Some(e), r, e.n)?;
            out.extend(moves.iter().copied());
            c = next;
        }
        Ok(out)
    }

    #[test]
    fn a_chamfer_cuts_both_lines_short_by_its_size() {
        let c = |mm: i64| Some(CornerRound::Chamfer(Length::from_angstrom(mm).unwrap()));
        // Up the face to X20 (radius), then along -Z: ,C2.
        let moves = corners(&[
            (line([0, 0], [20 * MM, 0]), c(2 * MM)),
            (line([20 * MM, 0], [20 * MM, -30 * MM]), None),
        ])
        .unwrap();
        let ends: std::vec::Vec<_> = moves.iter().map(|m| (m.to, m.origin)).collect();
        assert_eq!(
            ends,
            [
                ([18 * MM, 0], Origin::Waiting),
                ([20 * MM, -2 * MM], Origin::Waiting),
                ([20 * MM, -30 * MM], Origin::Current),
            ]
        );
    }

    #[test]
    fn a_round_between_lines_is_tangent_at_r_tan_half_the_turn() {
        let r = |mm: i64| Some(CornerRound::Round(Length::from_angstrom(mm).unwrap()));
        // A right angle: the tangent points R from the corner, the centre
        // R in from both lines.
        let moves = corners(&[
            (line([20 * MM, 0], [20 * MM, -30 * MM]), r(5 * MM)),
            (line([20 * MM, -30 * MM], [40 * MM, -30 * MM]), None),
        ])
        .unwrap();
        assert_eq!(moves.len(), 3);
        assert_eq!(moves[0].to, [20 * MM, -25 * MM]);
        assert_eq!(
            moves[1].kind,
            MoveKind::Arc {
                centre: [25 * MM, -25 * MM],
                dir: ArcDir::Cw
            }
        );
        assert_eq!(moves[1].to, [25 * MM, -30 * MM]);
        // A 45° taper after a turn along -Z: tan(22.5°)·R from the corner.
        let moves = corners(&[
            (line([20 * MM, 0], [20 * MM, -30 * MM]), r(4 * MM)),
            (line([20 * MM, -30 * MM], [30 * MM, -40 * MM]), None),
        ])
        .unwrap();
        let d = 4.0 * (std::f64::consts::PI / 8.0).tan() * 1e7;
        let expect = -30.0 * 1e7 + d;
        assert!(
            (moves[0].to[1] as f64 - expect).abs() <= 1.0,
            "{:?}",
            moves[0]
        );
        assert_eq!(moves[0].to[0], 20 * MM);
    }

    #[test]
    fn a_round_onto_an_arc_touches_it() {
        let r = Some(CornerRound::Round(Length::from_angstrom(2 * MM).unwrap()));
        // Along -Z at radius 20, then a convex arc of radius 10 about
        // (10, -30) up to (10, -40)... the arc turning right from the line.
        let arc = Element {
            from: [20 * MM, -30 * MM],
            to: [10 * MM, -40 * MM],
            shape: Shape::Arc {
                centre: [10 * MM, -30 * MM],
                dir: ArcDir::Cw,
            },
            n: None,
        };
        let moves = corners(&[(line([20 * MM, 0], [20 * MM, -30 * MM]), r), (arc, None)]);
        // That arc goes on smoothly from the line: no corner.
        assert_eq!(moves, Err(CompError::RoundNoCorner(None, None)));
        // An arc leaving the line at a corner: about (30, -30), from
        // (20, -30) down to (30, -40), turning left.
        let arc = Element {
            from: [20 * MM, -30 * MM],
            to: [30 * MM, -40 * MM],
            shape: Shape::Arc {
                centre: [20 * MM, -40 * MM],
                dir: ArcDir::Cw,
            },
            n: None,
        };
        let moves = corners(&[(line([20 * MM, 0], [20 * MM, -30 * MM]), r), (arc, None)]).unwrap();
        let MoveKind::Arc { centre, .. } = moves[1].kind else {
            panic!("{moves:?}")
        };
        let dist = |a: [i64; 2], b: [i64; 2]| ((a[0] - b[0]) as f64).hypot((a[1] - b[1]) as f64);
        let foot = moves[1].to;
        // On the arc, on the round, and the three centres in a line.
        assert!((dist(foot, [20 * MM, -40 * MM]) - 10.0 * 1e7).abs() <= 2.0);
        assert!((dist(foot, centre) - 2.0 * 1e7).abs() <= 2.0);
        assert!(
            (dist(centre, [20 * MM, -40 * MM])
                - dist(foot, [20 * MM, -40 * MM])
                - dist(foot, centre))
            .abs()
                <= 2.0
        );
        assert!((dist(moves[0].to, centre) - 2.0 * 1e7).abs() <= 2.0);
        assert_eq!(moves[2].to, [30 * MM, -40 * MM]);
    }

    #[test]
    fn corners_that_do_not_fit_or_follow_are_refused() {
        let c = |mm: i64| Some(CornerRound::Chamfer(Length::from_angstrom(mm).unwrap()));
        let first = line([20 * MM, 0], [20 * MM, -3 * MM]);
        let second = line([20 * MM, -3 * MM], [30 * MM, -3 * MM]);
        // Longer than the first line.
        assert_eq!(
            corners(&[(first, c(4 * MM)), (second, None)]),
            Err(CompError::RoundTooBig(None, None))
        );
        // As long as the second: nothing of it left.
        assert_eq!(
            corners(&[
                (first, c(MM)),
                (line([20 * MM, -3 * MM], [21 * MM, -3 * MM]), None)
            ]),
            Err(CompError::RoundTooBig(None, None))
        );
        // A rapid next, or a rapid asking.
        let rapid = Element::line(second.from, second.to, true, Some(7));
        assert_eq!(
            corners(&[(first, c(MM)), (rapid, None)]),
            Err(CompError::RoundNext(None, Some(7)))
        );
        assert_eq!(
            corners(&[(rapid, c(MM))]),
            Err(CompError::RoundHere(Some(7)))
        );
        // Compensation switched in the next block.
        let tool = Tool::new(Length::ZERO, TipCode::EXTERNAL_RIGHT);
        let (waiting, none) = Contour::new()
            .rounded(&tool, None, None, Some(first), c(MM), None)
            .unwrap();
        assert!(none.is_empty() && waiting.active() && waiting.rounding());
        assert_eq!(
            waiting.rounded(
                &tool,
                Some(Compensation::Right),
                None,
                Some(second),
                None,
                None
            ),
            Err(CompError::RoundNext(None, None))
        );
        // The chamfer fits exactly: the first line has nothing left.
        let moves = corners(&[(first, c(3 * MM)), (second, None)]).unwrap();
        assert_eq!(moves.len(), 2);
    }

    #[test]
    fn turns_per_radian_is_two_to_the_63_over_pi() {
        let exact = 2f64.powi(63) / core::f64::consts::PI;
        assert!((TURNS_PER_RADIAN as f64 - exact).abs() <= exact * f64::EPSILON);
    }

    /// The arc check's slack is a length along the offset circle: 2 Å plus
    /// `r·2⁻²¹`, the same on a 0.01 mm and on a 1000 mm offset radius.
    #[test]
    fn sweep_slack_is_a_length_whatever_the_radius() {
        let r = 2_000_000; // 0.2 mm
        let slack_a = 2.0 + r as f64 / f64::from(1 << 21);
        for rho in [100_000i64, 10_000_000, 10_000_000_000] {
            let big_r = rho + r;
            // Programmed: a quarter circle G03 from angle 0 (+Z) to 90° (+X);
            // G41 with G03 puts the tool inside, offset radius ρ.
            let e = Element {
                from: [0, big_r],
                to: [big_r, 0],
                shape: Shape::Arc {
                    centre: [0, 0],
                    dir: ArcDir::Ccw,
                },
                n: Some(7),
            };
            for excess in 0..8i64 {
                // Compensated: the quarter circle of radius ρ, its end moved
                // on by `excess` Å along the tangent.
                let end = [rho, -excess];
                let along = rho as f64 * (excess as f64 / rho as f64).atan();
                let got = check_direction(&e, [0, rho], end, Some(8), Side::Left, r << FRAC);
                if along <= slack_a - 1e-3 {
                    assert_eq!(got, Ok(()), "ρ {rho} Å, {along} Å past the end");
                } else if along > slack_a + 1e-3 {
                    assert_eq!(
                        got,
                        Err(CompError::TooShort(Some(7), Some(8))),
                        "ρ {rho} Å, {along} Å past the end"
                    );
                }
            }
            // Reversed by 5 Å: too short on every radius.
            let back = check_direction(&e, [0, rho], [-5, rho], None, Side::Left, r << FRAC);
            assert_eq!(back, Err(CompError::TooShort(Some(7), None)), "ρ {rho}");
        }
    }

    /// Issue 15: an R0.255 groove bored with a 0.2 mm nose (offset radius
    /// 0.055 mm, end point rounded) is cut, ending where the geometry says.
    #[test]
    fn concave_arc_slightly_larger_than_the_nose_is_cut() {
        let tool = Tool::new(Length::from_angstrom(2_000_000).unwrap(), TipCode(2));
        let mm = |x: f64, z: f64| [(x * 1e7).round() as i64, (z * 1e7).round() as i64];
        let line = |a, b| Element::line(a, b, false, None);
        let centre = mm(6.007, -9.306);
        let arc = Element {
            from: mm(6.262, -9.306),
            to: mm(6.232, -9.426),
            shape: Shape::Arc {
                centre,
                dir: ArcDir::Ccw,
            },
            n: Some(100),
        };
        let mut c = Contour::new();
        let blocks = [
            (Some(Compensation::Left), line(mm(11.0, 3.0), mm(11.0, 0.0))),
            (None, line(mm(11.0, 0.0), mm(6.262, 0.0))),
            (None, line(mm(6.262, 0.0), mm(6.262, -9.306))),
            (None, arc),
        ];
        for (comp, e) in blocks {
            c = c.block(&tool, comp, Some(Corner::Arc), Some(e)).unwrap().0;
        }
        let off = line(mm(6.232, -9.426), mm(5.232, -9.426));
        let (c, moves) = c
            .block(&tool, Some(Compensation::Off), None, Some(off))
            .unwrap();
        assert!(!c.active());
        // The nose centre ends on the offset circle, at the end point's
        // angle: centre + 0.055/0.255 · (0.225, −0.12); the tool tip is
        // (+r, −r) from it.
        let k = 0.055 / 0.255;
        let want = [6.007 + k * 0.225 + 0.2, -9.306 - k * 0.12 - 0.2];
        let m = moves[0];
        assert_eq!(m.origin, Origin::Previous);
        assert_eq!(
            m.kind,
            MoveKind::Arc {
                centre: [centre[0] + 2_000_000, centre[1] - 2_000_000],
                dir: ArcDir::Ccw
            }
        );
        for i in 0..2 {
            assert!(
                (m.to[i] as f64 - want[i] * 1e7).abs() <= 0.5 + 1e-3,
                "{m:?} {want:?}"
            );
        }
        assert_eq!(moves[1].to, off.to);
    }
}

//! Double-precision (f64) reference of the turning cycles' roughing: Fanuc's
//! `G71` (turning, passes along Z), `G72` (facing, passes along X) and `G73`
//! (pattern repeating).
//!
//! Written from `docs/cycles.md` §1–§3 (the forms, the start point, the
//! profile, the frame, the passes, the pockets, the pass along the profile,
//! `G73` in §3.6) and the block replies of `docs/protocol.md` §5 alone,
//! independently of the controller's fixed-point core, so that the two can be
//! compared move for move. It does not call the core crate.
//!
//! # Input and output
//!
//! * Every point is `(x, z)` with **`x` on the radius** (the board's frame:
//!   "exact integer geometry (10⁻⁷ mm, X on the radius)", the opening of
//!   `docs/cycles.md`); a program's diameters are
//!   halved by the caller, and so is the `U` allowance of the second block
//!   (`docs/cycles.md` §1.1: "`U` halved when it is a diameter"). The depth of
//!   cut and the retract are radii as written; `G73`'s relief `U` is a radius
//!   as written.
//! * [`Cycle`]: the start point `S`, the profile (its first point `A` and its
//!   elements: lines and arcs by end point, centre and direction, `G02`
//!   clockwise and `G03` counter-clockwise in the picture with Z to the right
//!   and X up), the allowances `(U/2, W)`, the depth of cut `Δd`, the retract
//!   `e` and the [`Kind`].
//! * [`roughing`] gives the moves the block `Q` answers with, as [`Move`]s:
//!   a rapid, a feed line or a feed arc, each with its end point (and an arc's
//!   centre). They run from `S` and end at `S`. The board's own roundings
//!   (crossings with lines to 10⁻⁷ mm, with arcs by an integer square root,
//!   §3.1) are not modelled: the model is exact to f64, and the moves are
//!   compared to 0.0001 mm.
//!
//! # The roughing of `G71` and `G72` (§3.1–§3.4)
//!
//! The work is done in the frame of §3.1: `d` the depth from `S` towards the
//! first point `A` (with its allowances) along X for `G71`, along Z for `G72`;
//! `c` along the cut, growing towards the point of the profile (with its
//! allowances) farthest from `S` along the cut; both 0 at `S`. The profile is
//! translated by the allowances, its arcs cut at their deepest, shallowest
//! (and, to check that the profile runs one way along the cut, their
//! extreme-`c`) points.
//!
//! 1. Passes at `d = k·Δd`, `k = 1, 2, …` while `d` is short of the deepest
//!    point of the profile.
//! 2. At each depth, the stock intervals: the open intervals of `c` in
//!    `[0, c_far]` where the profile lies deeper than `d` (or exactly at `d`,
//!    a flat the cut runs along), between its crossings of the line at depth
//!    `d`, from the start side outwards; in front of `A` the profile is read
//!    as starting on the start side at `A`'s depth.
//! 3. An interval beginning at `c = 0`: a rapid along the start side to depth
//!    `d`, a feed to its end. A pocket (any other interval): a rapid out to
//!    `d = 0`, across to the interval's start, down to `(k − 1)·Δd`, then a
//!    feed in to `d` and along it.
//! 4. After each cut a feed at 45°, back along the cut and out by
//!    `e' = min(e, the cut's length, d)` on both axes.
//! 5. After the pass's last cut: when that cut began on the start side, a
//!    rapid back along it to `c = 0` at the depth it retracted to; when it
//!    was a pocket (a pass of more cuts, or one whose only cut lies beyond
//!    stock standing between it and the start side), out to `d = 0` first,
//!    then to `c = 0`.
//! 6. Then the pass along the profile: a rapid along the start side to the
//!    depth of `A`, a rapid to `A` (when `A` is off the start side's line),
//!    each element of the profile with its allowances at the feed (one move
//!    per element, arcs as arcs), a rapid out to `d = 0` at the profile's end
//!    and a rapid to `S`.
//!
//! # `G73` (§3.6)
//!
//! Pass `j` of `n` is the profile moved by the allowances and by
//! `relief·(n − j)/(n − 1)` (each axis rounded half away from zero to
//! 10⁻⁷ mm; the relief 0 when `n = 1`): a rapid from `S` to its first point,
//! its elements at the feed (arcs with their centres moved alike), a rapid
//! back to `S`.
//!
//! # Readings of the text
//!
//! Where `docs/cycles.md` leaves a detail open, this model reads it so:
//!
//! * **Zero-length moves are left out.** §3.4 says so for the rapid to `A`
//!   ("to `A` when `A` is not on the start side's line"); the model applies
//!   the same to every move whose end is its start (within 10⁻⁹ mm): the
//!   descent of a first pass's pocket to the depth "cleared by the pass
//!   before" (0), the going out to the start depth when the tool is already
//!   there, the return to the start side after a retract that ended on its
//!   line, the rapid to the depth of `A` when the tool is already at it, a
//!   retract of `R0`.
//! * **"Deeper than `d`" is strict, and a touch is not a crossing.** A flat
//!   of the profile lying exactly at the pass's depth is not stock (the
//!   profile does not lie deeper there), so it ends the interval before it
//!   and a pocket may begin after it; a point where the profile only touches
//!   the line at depth `d` (a corner or the extreme of an arc exactly at
//!   `d`, deeper on both sides) is no crossing and does not split the
//!   interval ("the intervals of `c` between the profile's crossings").
//!   Depths are compared to 10⁻⁹ mm. §3.2's "What they leave above the
//!   profile is less than one depth of cut" does not decide the flat: such
//!   a flat is left exactly one depth of cut, as the deepest point is when it
//!   lies at a `k·Δd` (no pass runs there, next bullet), so the bound is read
//!   as "at most".
//! * **The last pass** runs at the last `k·Δd` strictly short of the deepest
//!   point: a `k·Δd` equal to it is not run ("while `d` is short of").
//! * **"Limited by the length of the cut and by `d`"**: `e' = min(e, L, d)`,
//!   `L` the length of the cut along `c` (a pocket's feed in not counted).
//! * **"Down to the depth cleared by the pass before"** is `(k − 1)·Δd`.
//! * **The return after a pass** is at its retracted depth only when the
//!   last cut began on the start side; after a pocket it goes out to the
//!   start depth first (§3.2).
//! * **The stock side.** `A` is taken with its allowances both for the side of
//!   the depth and for "`A` on `S`'s own line" (refused, 10⁻⁹ mm). The
//!   direction of `c` is that of the farthest point of the profile with its
//!   allowances (arc extremes included). Where the profile has not begun
//!   (`c` before `A`'s, an `A` in front of the start side's line) the stock
//!   reaches `A`'s depth (§3.2).
//! * **The profile must run one way along the cut** for `G71` and `G72`
//!   (`G73`'s passes follow the profile "up and down alike", §3.6): a piece that
//!   goes back along `c` by more than 10⁻⁹ mm is refused
//!   ([`CycleError::NotMonotone`]); walls along the depth axis are allowed.
//!
//! # Checks for the tests
//!
//! * [`Region`]: the part, "inside the profile plus its allowances": the
//!   region beyond the profile (deeper than it, along a depth axis), closed
//!   by lines along that axis from its two ends. [`Region::signed_distance`]
//!   is negative inside; [`Region::min_signed_distance`] is the least signed
//!   distance along a move (a penetration is found to 10⁻⁸ mm by a
//!   Lipschitz branch and bound; a move that stays outside reports its least
//!   sampled clearance, 0 or more).
//! * [`stock_left`]: the largest thickness of stock, measured along the depth
//!   axis, between the profile and the deepest point the passes' feed moves
//!   reached at each `c`.
//!
//! `tests/tests/cycles.rs` compares the model with the device and lists, as
//! ignored tests, the cases where the device reads these points otherwise.
//! * [`finishing_pass`] and [`split_final_pass`]: the pass along the profile
//!   as the profile moved by the allowances gives it, and where the pass
//!   begins in a list of moves.

use std::f64::consts::{FRAC_PI_2, TAU};

/// Distances taken as equal (mm).
const EPS: f64 = 1e-9;

/// A point: `x` on the radius, `z`, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pt {
    /// X, a radius.
    pub x: f64,
    /// Z.
    pub z: f64,
}

impl Pt {
    /// The point `(x, z)`, `x` a radius.
    pub const fn new(x: f64, z: f64) -> Pt {
        Pt { x, z }
    }

    /// The distance to `o`.
    pub fn dist(self, o: Pt) -> f64 {
        (self.x - o.x).hypot(self.z - o.z)
    }
}

impl std::ops::Add for Pt {
    type Output = Pt;

    /// The sum, axis by axis.
    fn add(self, o: Pt) -> Pt {
        Pt::new(self.x + o.x, self.z + o.z)
    }
}

/// An arc's direction in the picture with Z to the right and X up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArcDir {
    /// `G02`.
    Cw,
    /// `G03`.
    Ccw,
}

/// One element of a profile, from the end of the one before.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Element {
    /// A line to `end`.
    Line {
        /// End point.
        end: Pt,
    },
    /// An arc to `end` about `centre` (the radius that of its start).
    Arc {
        /// End point.
        end: Pt,
        /// Centre.
        centre: Pt,
        /// Direction.
        dir: ArcDir,
    },
}

impl Element {
    /// The end point.
    pub fn end(&self) -> Pt {
        match *self {
            Element::Line { end } | Element::Arc { end, .. } => end,
        }
    }

    /// The element translated by `by`.
    pub fn moved(&self, by: Pt) -> Element {
        match *self {
            Element::Line { end } => Element::Line { end: end + by },
            Element::Arc { end, centre, dir } => Element::Arc {
                end: end + by,
                centre: centre + by,
                dir,
            },
        }
    }
}

/// A profile: the first point `A` and the elements after it.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// The first point `A`.
    pub start: Pt,
    /// The elements, in order.
    pub elements: Vec<Element>,
}

impl Profile {
    /// The profile translated by `by` (arcs with their centres).
    pub fn moved(&self, by: Pt) -> Profile {
        Profile {
            start: self.start + by,
            elements: self.elements.iter().map(|e| e.moved(by)).collect(),
        }
    }

    /// The last point.
    pub fn end(&self) -> Pt {
        self.elements.last().map_or(self.start, Element::end)
    }
}

/// Which roughing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// `G71`: the depth along X, the passes along Z.
    Turning,
    /// `G72`: the depth along Z, the passes along X.
    Facing,
    /// `G73`: the profile cut `count` times, the first pass `relief` (X a
    /// radius, Z) beyond the last.
    Pattern {
        /// How far the first pass lies beyond the last (X a radius).
        relief: Pt,
        /// The count of passes, 1 or more.
        count: u32,
    },
}

/// A roughing cycle as the block `Q` runs it.
#[derive(Clone, Debug, PartialEq)]
pub struct Cycle {
    /// Which roughing.
    pub kind: Kind,
    /// The start point `S`.
    pub start: Pt,
    /// The profile as programmed.
    pub profile: Profile,
    /// The allowances: X on the radius (the second block's `U` halved), Z.
    pub allowance: Pt,
    /// The depth of cut `Δd` (a radius), `G71`/`G72`.
    pub depth: f64,
    /// The retract `e`, `G71`/`G72`.
    pub retract: f64,
}

/// How a move runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveKind {
    /// `G00`.
    Rapid,
    /// `G01`.
    Feed,
    /// `G02`.
    Cw,
    /// `G03`.
    Ccw,
}

impl MoveKind {
    /// The G code of the `DATA` line.
    pub fn code(self) -> &'static str {
        match self {
            MoveKind::Rapid => "G00",
            MoveKind::Feed => "G01",
            MoveKind::Cw => "G02",
            MoveKind::Ccw => "G03",
        }
    }

    /// A move at the feed (a line or an arc).
    pub fn is_feed(self) -> bool {
        self != MoveKind::Rapid
    }
}

/// One move of the roughing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// How it runs.
    pub kind: MoveKind,
    /// Where it ends.
    pub end: Pt,
    /// An arc's centre.
    pub centre: Option<Pt>,
}

/// Moves as the device's `DATA` lines print them (without `DATA `), each
/// from where the one before ends, the first from `start`.
pub fn texts(start: Pt, moves: &[Move]) -> Vec<String> {
    let mut at = start;
    moves
        .iter()
        .map(|m| {
            let t = m.text(at);
            at = m.end;
            t
        })
        .collect()
}

impl Move {
    /// The move as a `DATA` line prints it (without `DATA `), from `from`:
    /// X on the diameter, four decimals, an arc's `I`, `K` from its start.
    pub fn text(&self, from: Pt) -> String {
        let mut s = format!(
            "{} X{} Z{}",
            self.kind.code(),
            mm4(2.0 * self.end.x),
            mm4(self.end.z)
        );
        if let Some(c) = self.centre {
            s += &format!(" I{} K{}", mm4(c.x - from.x), mm4(c.z - from.z));
        }
        s
    }
}

/// `v` in mm with four decimals, rounded half away from zero (after a
/// rounding to 10⁻⁷ mm, as the device holds it); never `-0.0000`.
pub fn mm4(v: f64) -> String {
    let units = (v * 1e7).round() as i64;
    let q = (units.abs() + 500) / 1000;
    let sign = if units < 0 && q != 0 { "-" } else { "" };
    format!("{sign}{}.{:04}", q / 10_000, q % 10_000)
}

/// Why the model refuses a cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CycleError {
    /// The profile has no element that moves.
    NoMove,
    /// `A` (with its allowances) on `S`'s own line: no stock side.
    StartLine,
    /// A `G71`/`G72` profile that goes back along the cut.
    NotMonotone,
    /// A depth of cut of 0 or less.
    Depth,
    /// A negative retract.
    Retract,
    /// A `G73` count of 0.
    Count,
}

/// The roughing's moves, from `S` back to `S`.
pub fn roughing(cycle: &Cycle) -> Result<Vec<Move>, CycleError> {
    if profile_moves(&cycle.profile).is_empty() {
        return Err(CycleError::NoMove);
    }
    match cycle.kind {
        Kind::Turning => stock_removal(cycle, true),
        Kind::Facing => stock_removal(cycle, false),
        Kind::Pattern { relief, count } => pattern(cycle, relief, count),
    }
}

/// The pass along the profile: the profile moved by the allowances, each
/// element at the feed (from the profile's first point with its allowances).
pub fn finishing_pass(cycle: &Cycle) -> Vec<Move> {
    profile_moves(&cycle.profile.moved(cycle.allowance))
}

/// The index in `moves` of the first move of the last run of feed moves: the
/// pass along the profile of a `G71`/`G72`, the last pass of a `G73`.
pub fn split_final_pass(moves: &[Move]) -> usize {
    let Some(last) = moves.iter().rposition(|m| m.kind.is_feed()) else {
        return moves.len();
    };
    let mut i = last;
    while i > 0 && moves[i - 1].kind.is_feed() {
        i -= 1;
    }
    i
}

/// The feed moves along `p`, one per element that moves.
fn profile_moves(p: &Profile) -> Vec<Move> {
    let mut out = Vec::new();
    let mut at = p.start;
    for e in &p.elements {
        let end = e.end();
        let m = match *e {
            Element::Line { end } => Move {
                kind: MoveKind::Feed,
                end,
                centre: None,
            },
            Element::Arc { end, centre, dir } => Move {
                kind: match dir {
                    ArcDir::Cw => MoveKind::Cw,
                    ArcDir::Ccw => MoveKind::Ccw,
                },
                end,
                centre: Some(centre),
            },
        };
        if end.dist(at) > EPS {
            out.push(m);
        }
        at = end;
    }
    out
}

/// `G73`.
fn pattern(cycle: &Cycle, relief: Pt, count: u32) -> Result<Vec<Move>, CycleError> {
    if count == 0 {
        return Err(CycleError::Count);
    }
    let round7 = |v: f64| (v * 1e7).round() / 1e7;
    let n = f64::from(count);
    let mut out = Vec::new();
    let mut at = cycle.start;
    for j in 1..=count {
        let f = |r: f64| {
            if count == 1 {
                0.0
            } else {
                round7(r * (n - f64::from(j)) / (n - 1.0))
            }
        };
        let shift = cycle.allowance + Pt::new(f(relief.x), f(relief.z));
        let moved = cycle.profile.moved(shift);
        if moved.start.dist(at) > EPS {
            out.push(Move {
                kind: MoveKind::Rapid,
                end: moved.start,
                centre: None,
            });
        }
        out.extend(profile_moves(&moved));
        at = moved.end();
        if at.dist(cycle.start) > EPS {
            out.push(Move {
                kind: MoveKind::Rapid,
                end: cycle.start,
                centre: None,
            });
        }
        at = cycle.start;
    }
    Ok(out)
}

/// `G71` (`depth_x`) and `G72`.
fn stock_removal(cycle: &Cycle, depth_x: bool) -> Result<Vec<Move>, CycleError> {
    if cycle.depth.is_nan() || cycle.depth <= 0.0 {
        return Err(CycleError::Depth);
    }
    if cycle.retract.is_nan() || cycle.retract < 0.0 {
        return Err(CycleError::Retract);
    }
    let moved = cycle.profile.moved(cycle.allowance);
    let (frame, mut pieces) = frame_of(cycle.start, &moved, depth_x)?;
    monotone(&pieces)?;
    let a = frame.to(moved.start);
    // In front of A the stock reaches A's depth (docs/cycles.md §3.2): the
    // profile is read as starting on the start side at that depth.
    if a.c > EPS {
        pieces.insert(
            0,
            Piece::Line {
                a: V::new(0.0, a.d),
                b: a,
            },
        );
    }
    let c_far = pieces.iter().map(|p| p.b().c).fold(a.c, f64::max);
    let d_max = pieces.iter().map(|p| p.b().d).fold(a.d, f64::max);
    let dd = cycle.depth;
    let mut out = Emitter {
        frame,
        at: V::new(0.0, 0.0),
        moves: Vec::new(),
    };
    let mut k = 1u32;
    loop {
        let d = f64::from(k) * dd;
        if d >= d_max - EPS {
            break;
        }
        let cleared = f64::from(k - 1) * dd;
        let cuts = intervals(&pieces, d, c_far);
        for &(lo, hi) in &cuts {
            if lo <= EPS {
                out.rapid(V::new(0.0, d));
            } else {
                out.rapid(V::new(out.at.c, 0.0));
                out.rapid(V::new(lo, 0.0));
                out.rapid(V::new(lo, cleared));
                out.feed(V::new(lo, d));
            }
            out.feed(V::new(hi, d));
            let e = cycle.retract.min(hi - lo).min(d);
            out.feed(V::new(hi - e, d - e));
        }
        match cuts.last() {
            None => {}
            Some(&(lo, _)) if lo <= EPS => out.rapid(V::new(0.0, out.at.d)),
            Some(_) => {
                out.rapid(V::new(out.at.c, 0.0));
                out.rapid(V::new(0.0, 0.0));
            }
        }
        k += 1;
    }
    out.rapid(V::new(0.0, a.d));
    out.rapid(a);
    for m in profile_moves(&moved) {
        out.at = frame.to(m.end);
        out.moves.push(m);
    }
    out.rapid(V::new(out.at.c, 0.0));
    out.rapid(V::new(0.0, 0.0));
    Ok(out.moves)
}

/// Collects the moves of the passes, given in the frame.
struct Emitter {
    frame: Frame,
    at: V,
    moves: Vec<Move>,
}

impl Emitter {
    fn go(&mut self, kind: MoveKind, to: V) {
        if to.sub(self.at).len() <= EPS {
            return;
        }
        self.at = to;
        self.moves.push(Move {
            kind,
            end: self.frame.from(to),
            centre: None,
        });
    }

    fn rapid(&mut self, to: V) {
        self.go(MoveKind::Rapid, to);
    }

    fn feed(&mut self, to: V) {
        self.go(MoveKind::Feed, to);
    }
}

/// The open intervals of `c` in `[0, c_far]` where the profile lies deeper
/// than `d`, merged across points where it only touches `d`.
fn intervals(pieces: &[Piece], d: f64, c_far: f64) -> Vec<(f64, f64)> {
    let mut cs = vec![0.0, c_far];
    for p in pieces {
        cs.extend([p.a().c, p.b().c]);
        cs.extend(p.crossing(d));
    }
    cs.retain(|&c| (0.0..=c_far).contains(&c));
    cs.sort_by(f64::total_cmp);
    cs.dedup_by(|b, a| *b - *a <= EPS);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for w in cs.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        // Deeper than the pass, or a flat exactly at its depth, which the
        // cut runs along (docs/cycles.md §3.2).
        let deeper = depth_at(pieces, 0.5 * (lo + hi)).is_some_and(|p| p > d - EPS);
        if !deeper {
            continue;
        }
        match out.last_mut() {
            Some(last) if (last.1 - lo).abs() <= EPS && shallowest_at(pieces, lo) >= d - EPS => {
                last.1 = hi;
            }
            _ => out.push((lo, hi)),
        }
    }
    out
}

/// The profile's depth at `c`, from a piece that is not a wall along the
/// depth axis (`None` where the profile does not reach).
fn depth_at(pieces: &[Piece], c: f64) -> Option<f64> {
    pieces
        .iter()
        .filter(|p| !p.is_wall())
        .find(|p| {
            let (lo, hi) = p.c_range();
            lo - EPS <= c && c <= hi + EPS
        })
        .map(|p| p.depth_at(c))
}

/// The shallowest point of the profile at `c` (walls included).
fn shallowest_at(pieces: &[Piece], c: f64) -> f64 {
    pieces
        .iter()
        .filter(|p| {
            let (lo, hi) = p.c_range();
            lo - EPS <= c && c <= hi + EPS
        })
        .map(|p| {
            if p.is_wall() {
                p.a().d.min(p.b().d)
            } else {
                p.depth_at(c)
            }
        })
        .fold(f64::INFINITY, f64::min)
}

fn monotone(pieces: &[Piece]) -> Result<(), CycleError> {
    if pieces.iter().all(|p| p.b().c >= p.a().c - EPS) {
        Ok(())
    } else {
        Err(CycleError::NotMonotone)
    }
}

/// A vector of the frame: `c` along the cut, `d` the depth.
#[derive(Clone, Copy, Debug, PartialEq)]
struct V {
    c: f64,
    d: f64,
}

impl V {
    const fn new(c: f64, d: f64) -> V {
        V { c, d }
    }
    fn sub(self, o: V) -> V {
        V::new(self.c - o.c, self.d - o.d)
    }
    fn add(self, o: V) -> V {
        V::new(self.c + o.c, self.d + o.d)
    }
    fn scale(self, k: f64) -> V {
        V::new(self.c * k, self.d * k)
    }
    fn dot(self, o: V) -> f64 {
        self.c * o.c + self.d * o.d
    }
    fn cross(self, o: V) -> f64 {
        self.c * o.d - self.d * o.c
    }
    fn len(self) -> f64 {
        self.c.hypot(self.d)
    }
    fn angle(self) -> f64 {
        self.d.atan2(self.c)
    }
    fn polar(r: f64, t: f64) -> V {
        V::new(r * t.cos(), r * t.sin())
    }
}

/// The frame of §3.1: `S` at the origin, `d` along X (`depth_x`) or Z with
/// sign `sd`, `c` along the other axis with sign `sc`.
#[derive(Clone, Copy, Debug)]
struct Frame {
    s: Pt,
    depth_x: bool,
    sd: f64,
    sc: f64,
}

impl Frame {
    fn to(&self, p: Pt) -> V {
        let (dx, dz) = (p.x - self.s.x, p.z - self.s.z);
        if self.depth_x {
            V::new(self.sc * dz, self.sd * dx)
        } else {
            V::new(self.sc * dx, self.sd * dz)
        }
    }

    fn from(&self, v: V) -> Pt {
        if self.depth_x {
            Pt::new(self.s.x + self.sd * v.d, self.s.z + self.sc * v.c)
        } else {
            Pt::new(self.s.x + self.sc * v.c, self.s.z + self.sd * v.d)
        }
    }

    /// Whether counter-clockwise in (z, x) stays counter-clockwise in (c, d).
    fn keeps_orientation(&self) -> bool {
        let det = if self.depth_x {
            self.sc * self.sd
        } else {
            -self.sc * self.sd
        };
        det > 0.0
    }

    /// A move or element from `from` as a path of the frame.
    fn path(&self, from: Pt, to: Pt, arc: Option<(Pt, ArcDir)>) -> Piece {
        let (a, b) = (self.to(from), self.to(to));
        match arc {
            None => Piece::Line { a, b },
            Some((centre, dir)) => {
                let o = self.to(centre);
                let r = a.sub(o).len();
                let (t0, t1) = (a.sub(o).angle(), b.sub(o).angle());
                let ccw = (dir == ArcDir::Ccw) == self.keeps_orientation();
                let mut sweep = if ccw {
                    (t1 - t0).rem_euclid(TAU)
                } else {
                    -(t0 - t1).rem_euclid(TAU)
                };
                if sweep.abs() < 1e-12 {
                    sweep = if ccw { TAU } else { -TAU };
                }
                Piece::Arc {
                    a,
                    b,
                    o,
                    r,
                    t0,
                    sweep,
                }
            }
        }
    }
}

/// The frame of the roughing of `moved` (the profile with its allowances)
/// from `s`, and the profile's pieces in it (arcs cut at the quadrants).
fn frame_of(s: Pt, moved: &Profile, depth_x: bool) -> Result<(Frame, Vec<Piece>), CycleError> {
    if moved.elements.is_empty() {
        return Err(CycleError::NoMove);
    }
    let trial = Frame {
        s,
        depth_x,
        sd: 1.0,
        sc: 1.0,
    };
    let a = trial.to(moved.start);
    if a.d.abs() <= EPS {
        return Err(CycleError::StartLine);
    }
    let far = pieces(&trial, moved)
        .iter()
        .map(|p| p.b().c)
        .fold(a.c, |m, c| if c.abs() > m.abs() { c } else { m });
    let frame = Frame {
        sd: a.d.signum(),
        sc: if far < 0.0 { -1.0 } else { 1.0 },
        ..trial
    };
    let pieces = pieces(&frame, moved);
    if pieces.is_empty() {
        return Err(CycleError::NoMove);
    }
    Ok((frame, pieces))
}

/// The pieces of a profile in a frame: lines, and arcs cut where they reach
/// an extreme of `c` or `d`.
fn pieces(frame: &Frame, p: &Profile) -> Vec<Piece> {
    let mut out = Vec::new();
    let mut at = p.start;
    for e in &p.elements {
        let end = e.end();
        if end.dist(at) > EPS {
            let arc = match *e {
                Element::Line { .. } => None,
                Element::Arc { centre, dir, .. } => Some((centre, dir)),
            };
            out.extend(frame.path(at, end, arc).quadrants());
        }
        at = end;
    }
    out
}

/// A line or an arc of the frame.
#[derive(Clone, Copy, Debug)]
enum Piece {
    Line {
        a: V,
        b: V,
    },
    /// From `a` (at angle `t0` about `o`) by the signed `sweep` (positive
    /// counter-clockwise in (c, d)) to `b`.
    Arc {
        a: V,
        b: V,
        o: V,
        r: f64,
        t0: f64,
        sweep: f64,
    },
}

impl Piece {
    fn a(&self) -> V {
        match *self {
            Piece::Line { a, .. } | Piece::Arc { a, .. } => a,
        }
    }

    fn b(&self) -> V {
        match *self {
            Piece::Line { b, .. } | Piece::Arc { b, .. } => b,
        }
    }

    fn c_range(&self) -> (f64, f64) {
        let (a, b) = (self.a().c, self.b().c);
        (a.min(b), a.max(b))
    }

    /// A line along the depth axis.
    fn is_wall(&self) -> bool {
        let (lo, hi) = self.c_range();
        hi - lo <= EPS
    }

    fn length(&self) -> f64 {
        match *self {
            Piece::Line { a, b } => b.sub(a).len(),
            Piece::Arc { r, sweep, .. } => r * sweep.abs(),
        }
    }

    /// The point at the distance `s` along the piece.
    fn at(&self, s: f64) -> V {
        match *self {
            Piece::Line { a, b } => {
                let l = b.sub(a).len();
                if l <= 0.0 {
                    a
                } else {
                    a.add(b.sub(a).scale(s / l))
                }
            }
            Piece::Arc {
                o, r, t0, sweep, ..
            } => o.add(V::polar(r, t0 + sweep.signum() * s / r)),
        }
    }

    /// The arc cut at the quadrant points strictly inside it (a line whole).
    fn quadrants(self) -> Vec<Piece> {
        let Piece::Arc {
            a,
            b,
            o,
            r,
            t0,
            sweep,
        } = self
        else {
            return vec![self];
        };
        let axis = |k: i64| match k.rem_euclid(4) {
            0 => V::new(o.c + r, o.d),
            1 => V::new(o.c, o.d + r),
            2 => V::new(o.c - r, o.d),
            _ => V::new(o.c, o.d - r),
        };
        let mut cuts = Vec::new();
        if sweep > 0.0 {
            let mut k = (t0 / FRAC_PI_2).floor() as i64 + 1;
            while (k as f64) * FRAC_PI_2 < t0 + sweep - 1e-12 {
                if (k as f64) * FRAC_PI_2 > t0 + 1e-12 {
                    cuts.push(k);
                }
                k += 1;
            }
        } else {
            let mut k = (t0 / FRAC_PI_2).ceil() as i64 - 1;
            while (k as f64) * FRAC_PI_2 > t0 + sweep + 1e-12 {
                if (k as f64) * FRAC_PI_2 < t0 - 1e-12 {
                    cuts.push(k);
                }
                k -= 1;
            }
        }
        let mut out = Vec::new();
        let (mut from, mut t) = (a, t0);
        for k in cuts {
            let q = (k as f64) * FRAC_PI_2;
            let p = axis(k);
            out.push(Piece::Arc {
                a: from,
                b: p,
                o,
                r,
                t0: t,
                sweep: q - t,
            });
            from = p;
            t = q;
        }
        out.push(Piece::Arc {
            a: from,
            b,
            o,
            r,
            t0: t,
            sweep: t0 + sweep - t,
        });
        out
    }

    /// The depth at `c` (a piece that runs one way in `c` and `d`).
    fn depth_at(&self, c: f64) -> f64 {
        match *self {
            Piece::Line { a, b } => {
                if (b.c - a.c).abs() <= EPS {
                    a.d.min(b.d)
                } else {
                    a.d + (c - a.c) / (b.c - a.c) * (b.d - a.d)
                }
            }
            Piece::Arc {
                o, r, t0, sweep, ..
            } => {
                let side = (t0 + 0.5 * sweep).sin().signum();
                let w = (c - o.c).clamp(-r, r);
                o.d + side * (r * r - w * w).max(0.0).sqrt()
            }
        }
    }

    /// Where the piece crosses the depth `d` strictly between its ends (an
    /// end within 10⁻⁹ mm of `d` is its own crossing: the arc pieces end at
    /// their extremes, where a square root would magnify the rounding).
    fn crossing(&self, d: f64) -> Option<f64> {
        let (a, b) = (self.a(), self.b());
        let between = (a.d < d - EPS && b.d > d + EPS) || (a.d > d + EPS && b.d < d - EPS);
        if !between {
            return None;
        }
        Some(match *self {
            Piece::Line { .. } => a.c + (d - a.d) / (b.d - a.d) * (b.c - a.c),
            Piece::Arc {
                o, r, t0, sweep, ..
            } => {
                let side = (t0 + 0.5 * sweep).cos().signum();
                let w = d - o.d;
                o.c + side * (r * r - w * w).max(0.0).sqrt()
            }
        })
    }

    /// The angle `t` as an offset (0 … |sweep|) along the arc, if on it.
    fn offset_of(t0: f64, sweep: f64, t: f64) -> Option<f64> {
        let tol = 1e-10;
        let mut rel = if sweep >= 0.0 {
            (t - t0).rem_euclid(TAU)
        } else {
            (t0 - t).rem_euclid(TAU)
        };
        if rel > TAU - tol {
            rel -= TAU;
        }
        (rel >= -tol && rel <= sweep.abs() + tol).then(|| rel.clamp(0.0, sweep.abs()))
    }

    fn distance(&self, p: V) -> f64 {
        match *self {
            Piece::Line { a, b } => {
                let v = b.sub(a);
                let l2 = v.dot(v);
                let t = if l2 <= 0.0 {
                    0.0
                } else {
                    (p.sub(a).dot(v) / l2).clamp(0.0, 1.0)
                };
                p.sub(a.add(v.scale(t))).len()
            }
            Piece::Arc {
                a,
                b,
                o,
                r,
                t0,
                sweep,
            } => {
                let q = p.sub(o);
                if Piece::offset_of(t0, sweep, q.angle()).is_some() {
                    (q.len() - r).abs()
                } else {
                    p.sub(a).len().min(p.sub(b).len())
                }
            }
        }
    }

    /// Where `self` (as a path) meets `other`: distances along `self`.
    fn meets(&self, other: &Piece) -> Vec<f64> {
        let tol = 1e-10;
        let mut out = Vec::new();
        match (*self, *other) {
            (Piece::Line { a, b }, Piece::Line { a: p, b: q }) => {
                let (v, w) = (b.sub(a), q.sub(p));
                let den = v.cross(w);
                if den.abs() <= 1e-12 * v.len() * w.len() {
                    return out;
                }
                let t = p.sub(a).cross(w) / den;
                let u = p.sub(a).cross(v) / den;
                if (-tol..=1.0 + tol).contains(&t) && (-tol..=1.0 + tol).contains(&u) {
                    out.push(t.clamp(0.0, 1.0) * v.len());
                }
            }
            (
                Piece::Line { a, b },
                Piece::Arc {
                    o, r, t0, sweep, ..
                },
            ) => {
                for t in line_circle(a, b, o, r) {
                    let pt = a.add(b.sub(a).scale(t));
                    if Piece::offset_of(t0, sweep, pt.sub(o).angle()).is_some() {
                        out.push(t * b.sub(a).len());
                    }
                }
            }
            (
                Piece::Arc {
                    o, r, t0, sweep, ..
                },
                Piece::Line { a, b },
            ) => {
                for t in line_circle(a, b, o, r) {
                    let pt = a.add(b.sub(a).scale(t));
                    if let Some(off) = Piece::offset_of(t0, sweep, pt.sub(o).angle()) {
                        out.push(off * r);
                    }
                }
            }
            (
                Piece::Arc {
                    o, r, t0, sweep, ..
                },
                Piece::Arc {
                    o: o2,
                    r: r2,
                    t0: u0,
                    sweep: sw2,
                    ..
                },
            ) => {
                let dv = o2.sub(o);
                let dist = dv.len();
                if dist <= 1e-12 || dist > r + r2 + tol || dist < (r - r2).abs() - tol {
                    return out;
                }
                let along = (r * r - r2 * r2 + dist * dist) / (2.0 * dist);
                let h = (r * r - along * along).max(0.0).sqrt();
                let u = dv.scale(1.0 / dist);
                let n = V::new(-u.d, u.c);
                for sgn in [-1.0, 1.0] {
                    let pt = o.add(u.scale(along)).add(n.scale(sgn * h));
                    let on_other = Piece::offset_of(u0, sw2, pt.sub(o2).angle()).is_some();
                    if let (Some(off), true) =
                        (Piece::offset_of(t0, sweep, pt.sub(o).angle()), on_other)
                    {
                        out.push(off * r);
                    }
                }
            }
        }
        out
    }
}

/// The parameters `t` in `[0, 1]` (within 10⁻¹⁰) where the segment `a`–`b`
/// meets the circle about `o` of radius `r` (a tangency counted).
fn line_circle(a: V, b: V, o: V, r: f64) -> Vec<f64> {
    let v = b.sub(a);
    let w = a.sub(o);
    let qa = v.dot(v);
    if qa <= 0.0 {
        return Vec::new();
    }
    let qb = v.dot(w);
    let qc = w.dot(w) - r * r;
    let mut disc = qb * qb - qa * qc;
    if disc < 0.0 {
        if disc > -1e-12 * qa * r * r {
            disc = 0.0;
        } else {
            return Vec::new();
        }
    }
    let s = disc.sqrt();
    [(-qb - s) / qa, (-qb + s) / qa]
        .into_iter()
        .filter(|t| (-1e-10..=1.0 + 1e-10).contains(t))
        .map(|t| t.clamp(0.0, 1.0))
        .collect()
}

/// The depth axis of a [`Region`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// Along X (`G71`; the model's choice for `G73`).
    X,
    /// Along Z (`G72`).
    Z,
}

/// The part as the roughing must leave it: the region beyond the profile
/// moved by the allowances, seen from `S` along a depth axis, closed by lines
/// along that axis from the profile's two ends to beyond its deepest point.
/// Meaningful for a profile that runs one way along the other axis.
#[derive(Clone, Debug)]
pub struct Region {
    frame: Frame,
    profile: Vec<Piece>,
    boundary: Vec<Piece>,
    c_lo: f64,
    c_hi: f64,
    d_far: f64,
}

impl Region {
    /// The region of a cycle: along X for `G71` and `G73`, Z for `G72`.
    pub fn of(cycle: &Cycle) -> Result<Region, CycleError> {
        let axis = match cycle.kind {
            Kind::Facing => Axis::Z,
            _ => Axis::X,
        };
        Region::along(cycle, axis)
    }

    /// The region beyond the profile (with its allowances) along `axis`.
    pub fn along(cycle: &Cycle, axis: Axis) -> Result<Region, CycleError> {
        let moved = cycle.profile.moved(cycle.allowance);
        let (frame, profile) = frame_of(cycle.start, &moved, axis == Axis::X)?;
        monotone(&profile)?;
        let a = profile[0].a();
        let e = profile[profile.len() - 1].b();
        let d_far = profile.iter().map(|p| p.b().d).fold(a.d, f64::max) + 1.0;
        let mut boundary = profile.clone();
        let (p, q) = (V::new(e.c, d_far), V::new(a.c, d_far));
        boundary.push(Piece::Line { a: e, b: p });
        boundary.push(Piece::Line { a: p, b: q });
        boundary.push(Piece::Line { a: q, b: a });
        Ok(Region {
            frame,
            profile,
            boundary,
            c_lo: a.c,
            c_hi: e.c,
            d_far,
        })
    }

    fn inside(&self, p: V) -> bool {
        p.c > self.c_lo
            && p.c < self.c_hi
            && p.d < self.d_far
            && depth_at(&self.profile, p.c).is_some_and(|d| p.d > d)
    }

    fn sd(&self, p: V) -> f64 {
        let dist = self
            .boundary
            .iter()
            .map(|b| b.distance(p))
            .fold(f64::INFINITY, f64::min);
        if self.inside(p) {
            -dist
        } else {
            dist
        }
    }

    /// The signed distance of `p` from the region: negative inside.
    pub fn signed_distance(&self, p: Pt) -> f64 {
        self.sd(self.frame.to(p))
    }

    /// The least signed distance from the region along the move `m` from
    /// `from`: how deep it enters (negative), found to 10⁻⁸ mm; for a move
    /// that does not enter, its least sampled clearance (0 or more).
    pub fn min_signed_distance(&self, from: Pt, m: &Move) -> f64 {
        let arc = m.centre.map(|c| {
            let dir = if m.kind == MoveKind::Cw {
                ArcDir::Cw
            } else {
                ArcDir::Ccw
            };
            (c, dir)
        });
        let path = self.frame.path(from, m.end, arc);
        let len = path.length();
        let mut cuts = vec![0.0, len];
        for b in &self.boundary {
            cuts.extend(path.meets(b));
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|b, a| *b - *a <= 1e-12);
        let mut best = self.sd(path.at(0.0)).min(self.sd(path.at(len)));
        for w in cuts.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            if hi - lo <= 1e-12 {
                continue;
            }
            let samples: Vec<f64> = (1..8)
                .map(|i| self.sd(path.at(lo + (hi - lo) * f64::from(i) / 8.0)))
                .collect();
            let least = samples.iter().copied().fold(f64::INFINITY, f64::min);
            if least < -EPS {
                best = best.min(-self.penetration(&path, lo, hi, -least));
            } else {
                best = best.min(least);
            }
        }
        best
    }

    /// The greatest depth inside the region along `path` between `lo` and
    /// `hi` (a stretch inside it), by branch and bound on the 1-Lipschitz
    /// distance, to 10⁻⁸ mm.
    fn penetration(&self, path: &Piece, lo: f64, hi: f64, mut best: f64) -> f64 {
        let pen = |s: f64| -self.sd(path.at(s));
        let mut stack = vec![(lo, hi)];
        let mut budget = 1_000_000u32;
        while let Some((a, b)) = stack.pop() {
            let m = 0.5 * (a + b);
            let v = pen(m);
            best = best.max(v);
            budget = budget.saturating_sub(1);
            if v + 0.5 * (b - a) > best + 1e-8 && budget > 0 {
                stack.push((a, m));
                stack.push((m, b));
            }
        }
        best
    }
}

/// The stock the passes leave for the pass along the profile: over `c` from
/// the start side to the profile's farthest point, the largest thickness,
/// along the depth axis, between the profile (with its allowances) and the
/// deepest point any feed line of `passes` (run from `S`) reached at that
/// `c` (the start depth where none did). `passes` are the moves before the
/// pass along the profile ([`split_final_pass`]). Each feed line counts as
/// reaching `slack` further along `c` at both ends, at the depth of that end
/// (a line along the depth axis: at its deepest): 0 for exact moves, the
/// precision of the print for printed ones (a cut that ends on a steep part
/// of the profile printed 0.00005 mm short, or a pocket's cut shorter than
/// the print's step printed as a line of no length, would otherwise leave a
/// sliver much thicker than that). `G71` and `G72` only.
pub fn stock_left(cycle: &Cycle, passes: &[Move], slack: f64) -> Result<f64, CycleError> {
    let depth_x = match cycle.kind {
        Kind::Turning => true,
        Kind::Facing => false,
        Kind::Pattern { .. } => return Err(CycleError::NotMonotone),
    };
    let moved = cycle.profile.moved(cycle.allowance);
    let (frame, pieces) = frame_of(cycle.start, &moved, depth_x)?;
    monotone(&pieces)?;
    let c_far = pieces.iter().map(|p| p.b().c).fold(0.0, f64::max);
    let mut cuts = Vec::new();
    let mut at = frame.to(cycle.start);
    for m in passes {
        let to = frame.to(m.end);
        if m.kind == MoveKind::Feed {
            cuts.push((at, to));
        }
        at = to;
    }
    let cleared = |c: f64| {
        cuts.iter()
            .filter(|(a, b)| a.c.min(b.c) - slack <= c && c <= a.c.max(b.c) + slack)
            .map(|(a, b)| {
                if (b.c - a.c).abs() <= EPS {
                    // Along the depth axis: its deepest point.
                    return a.d.max(b.d);
                }
                let c = c.clamp(a.c.min(b.c), a.c.max(b.c));
                a.d + (c - a.c) / (b.c - a.c) * (b.d - a.d)
            })
            .fold(0.0, f64::max)
    };
    let mut cs = vec![0.0, c_far];
    for p in &pieces {
        cs.extend([p.a().c, p.b().c]);
    }
    for (a, b) in &cuts {
        cs.extend([a.c, b.c, a.c - slack, a.c + slack, b.c - slack, b.c + slack]);
    }
    cs.retain(|&c| (0.0..=c_far).contains(&c));
    cs.sort_by(f64::total_cmp);
    cs.dedup_by(|b, a| *b - *a <= EPS);
    let mut worst = 0.0f64;
    for w in cs.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        let step = (hi - lo) / 16.0;
        let near = (1e-7f64).min(step);
        let samples = [lo + near, hi - near]
            .into_iter()
            .chain((1..16).map(|i| lo + step * f64::from(i)));
        for c in samples {
            if let Some(p) = depth_at(&pieces, c) {
                worst = worst.max(p - cleared(c));
            }
        }
    }
    Ok(worst)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `docs/cycles.md` §9: the stepped shaft, radii.
    fn step_shaft() -> Cycle {
        Cycle {
            kind: Kind::Turning,
            start: Pt::new(15.0, 2.0),
            profile: Profile {
                start: Pt::new(10.0, 2.0),
                elements: vec![
                    Element::Line {
                        end: Pt::new(10.0, -10.0),
                    },
                    Element::Line {
                        end: Pt::new(13.0, -15.0),
                    },
                    Element::Line {
                        end: Pt::new(13.0, -25.0),
                    },
                ],
            },
            allowance: Pt::new(0.2, 0.1),
            depth: 1.5,
            retract: 0.5,
        }
    }

    #[test]
    fn the_worked_example_of_the_docs() {
        let c = step_shaft();
        let moves = roughing(&c).unwrap();
        let expected = [
            "G00 X27.0000 Z2.0000",
            "G01 X27.0000 Z-24.9000",
            "G01 X28.0000 Z-24.4000",
            "G00 X28.0000 Z2.0000",
            "G00 X24.0000 Z2.0000",
            "G01 X24.0000 Z-12.9000",
            "G01 X25.0000 Z-12.4000",
            "G00 X25.0000 Z2.0000",
            "G00 X21.0000 Z2.0000",
            "G01 X21.0000 Z-10.4000",
            "G01 X22.0000 Z-9.9000",
            "G00 X22.0000 Z2.0000",
            "G00 X20.4000 Z2.0000",
            "G00 X20.4000 Z2.1000",
            "G01 X20.4000 Z-9.9000",
            "G01 X26.4000 Z-14.9000",
            "G01 X26.4000 Z-24.9000",
            "G00 X30.0000 Z-24.9000",
            "G00 X30.0000 Z2.0000",
        ];
        assert_eq!(texts(c.start, &moves), expected);
        let region = Region::of(&c).unwrap();
        let mut at = c.start;
        for m in &moves {
            if m.kind.is_feed() {
                assert!(region.min_signed_distance(at, m) >= -1e-9, "{m:?}");
            }
            at = m.end;
        }
        let split = split_final_pass(&moves);
        assert_eq!(split, 14);
        assert_eq!(moves[split..17], finishing_pass(&c)[..]);
        let left = stock_left(&c, &moves[..split], 0.0).unwrap();
        // Just past the end of the cut at X24 (on the taper) the stock left
        // tends to one depth of cut; at the start it is 4.8 − 4.5.
        assert!(left <= 1.5 + 1e-6 && left > 1.49, "{left}");
        // Without the last pass the start is left 4.8 − 3.0 deep.
        assert!((stock_left(&c, &moves[..8], 0.0).unwrap() - 1.8).abs() < 1e-9);
        // A cut's end counted 0.1 further along: past the end of the cut at
        // X24 the stock is at most 3.0 − (4.5 − 0.06) deep.
        let left = stock_left(&c, &moves[..split], 0.1).unwrap();
        assert!((left - 1.44).abs() < 1e-6, "{left}");
    }

    #[test]
    fn a_move_into_the_part_is_found_to_its_depth() {
        let c = step_shaft();
        let region = Region::of(&c).unwrap();
        // The part with its allowances: radius below 10.2 to Z-9.9.
        let m = Move {
            kind: MoveKind::Feed,
            end: Pt::new(10.0, -5.0),
            centre: None,
        };
        let sd = region.min_signed_distance(Pt::new(10.0, 0.0), &m);
        assert!((sd + 0.2).abs() < 1e-7, "{sd}");
        // Along the profile: on it; outside: clear.
        let along = Move {
            kind: MoveKind::Feed,
            end: Pt::new(10.2, -9.9),
            centre: None,
        };
        assert!(region.min_signed_distance(Pt::new(10.2, 2.1), &along).abs() < 1e-9);
        assert!(region.signed_distance(Pt::new(12.0, -20.0)) < -0.9);
        assert!(region.signed_distance(Pt::new(14.0, -20.0)) > 0.7);
        // An arc of radius 10.1 about X46.5 Z-20 dipping 0.05 into the
        // cylinder of radius 13.2.
        let centre = Pt::new(23.25, -20.0);
        let x = 23.25 - (10.1f64 * 10.1 - 4.0).sqrt();
        let arc = Move {
            kind: MoveKind::Cw,
            end: Pt::new(x, -22.0),
            centre: Some(centre),
        };
        let sd = region.min_signed_distance(Pt::new(x, -18.0), &arc);
        assert!((sd + 0.05).abs() < 1e-7, "{sd}");
    }

    #[test]
    fn a_pocket_is_entered_from_above() {
        // S X40 Z2 (radius 20); A X20 Z2; a bump to X30 and a pocket at X24.
        let c = Cycle {
            kind: Kind::Turning,
            start: Pt::new(20.0, 2.0),
            profile: Profile {
                start: Pt::new(10.0, 2.0),
                elements: vec![
                    Element::Line {
                        end: Pt::new(10.0, -5.0),
                    },
                    Element::Line {
                        end: Pt::new(15.0, -10.0),
                    },
                    Element::Line {
                        end: Pt::new(12.0, -15.0),
                    },
                    Element::Line {
                        end: Pt::new(12.0, -20.0),
                    },
                    Element::Line {
                        end: Pt::new(18.0, -25.0),
                    },
                ],
            },
            allowance: Pt::new(0.0, 0.0),
            depth: 2.0,
            retract: 0.5,
        };
        let moves = roughing(&c).unwrap();
        let t = texts(c.start, &moves);
        // The pass at X28 (depth 6): up to the bump, then the pocket.
        let at = t.iter().position(|l| l == "G00 X28.0000 Z2.0000").unwrap();
        assert_eq!(
            t[at..at + 11],
            [
                "G00 X28.0000 Z2.0000",
                "G01 X28.0000 Z-9.0000",
                "G01 X29.0000 Z-8.5000",
                "G00 X40.0000 Z-8.5000",
                "G00 X40.0000 Z-11.6667",
                "G00 X32.0000 Z-11.6667",
                "G01 X28.0000 Z-11.6667",
                "G01 X28.0000 Z-21.6667",
                "G01 X29.0000 Z-21.1667",
                "G00 X40.0000 Z-21.1667",
                "G00 X40.0000 Z2.0000",
            ]
        );
        let split = split_final_pass(&moves);
        let left = stock_left(&c, &moves[..split], 0.0).unwrap();
        assert!(left <= 2.0 + 1e-6, "{left}");
    }

    #[test]
    fn facing_and_pattern_repeating() {
        let mut c = step_shaft();
        c.kind = Kind::Pattern {
            relief: Pt::new(3.0, 1.0),
            count: 3,
        };
        let moves = roughing(&c).unwrap();
        let t = texts(c.start, &moves);
        assert_eq!(t[0], "G00 X26.4000 Z3.1000");
        assert_eq!(t[5], "G00 X23.4000 Z2.6000");
        assert_eq!(t[10], "G00 X20.4000 Z2.1000");
        assert_eq!(t.len(), 15);
        assert_eq!(
            roughing(&Cycle {
                start: Pt::new(10.2, 5.0),
                kind: Kind::Turning,
                ..c
            }),
            Err(CycleError::StartLine)
        );
        // Facing: S X42 Z1; A X42 Z-10, X30, X20 Z-6, Z0; U0.4 W0.1, W1.5
        // R0.3. With the allowances A is X42.4 Z-9.9, 10.9 deep along Z.
        let c = Cycle {
            kind: Kind::Facing,
            start: Pt::new(21.0, 1.0),
            profile: Profile {
                start: Pt::new(21.0, -10.0),
                elements: vec![
                    Element::Line {
                        end: Pt::new(15.0, -10.0),
                    },
                    Element::Line {
                        end: Pt::new(10.0, -6.0),
                    },
                    Element::Line {
                        end: Pt::new(10.0, 0.0),
                    },
                ],
            },
            allowance: Pt::new(0.2, 0.1),
            depth: 1.5,
            retract: 0.3,
        };
        let t = texts(c.start, &roughing(&c).unwrap());
        assert_eq!(
            t[..4],
            [
                "G00 X42.0000 Z-0.5000",
                "G01 X20.4000 Z-0.5000",
                "G01 X21.0000 Z-0.2000",
                "G00 X42.0000 Z-0.2000",
            ]
        );
        // Depth 7.5 meets the taper 0.85 of the way along it.
        assert!(t.contains(&"G01 X21.9000 Z-6.5000".to_string()));
        assert_eq!(t.len(), 7 * 4 + 7);
        assert_eq!(
            t[28..],
            [
                "G00 X42.0000 Z-9.9000",
                "G00 X42.4000 Z-9.9000",
                "G01 X30.4000 Z-9.9000",
                "G01 X20.4000 Z-5.9000",
                "G01 X20.4000 Z0.1000",
                "G00 X20.4000 Z1.0000",
                "G00 X42.0000 Z1.0000",
            ]
        );
    }

    #[test]
    fn arcs_are_cut_at_their_quadrants() {
        let f = Frame {
            s: Pt::new(0.0, 0.0),
            depth_x: true,
            sd: 1.0,
            sc: 1.0,
        };
        // A half circle from (z 0, x 0) about (z 1, x 0), counter-clockwise
        // in (z, x): below the axis, through (1, −1), to (2, 0).
        let p = f.path(
            Pt::new(0.0, 0.0),
            Pt::new(0.0, 2.0),
            Some((Pt::new(0.0, 1.0), ArcDir::Ccw)),
        );
        let q = p.quadrants();
        assert_eq!(q.len(), 2);
        assert!(q[0].b().sub(V::new(1.0, -1.0)).len() < 1e-12);
        assert!((q[0].depth_at(0.5) + 0.75f64.sqrt()).abs() < 1e-12);
        assert!((q[1].crossing(-0.5).unwrap() - (1.0 + 0.75f64.sqrt())).abs() < 1e-12);
        assert_eq!(mm4(-0.00004), "0.0000");
        assert_eq!(mm4(2.00005), "2.0001");
        assert_eq!(mm4(-2.00005), "-2.0001");
    }
}

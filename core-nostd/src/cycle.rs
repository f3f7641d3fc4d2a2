//! Turning cycles: the roughing of `G71` (along Z) and `G72` (along X)
//! from a profile, in exact integer geometry (`docs/cycles.md`).
//!
//! A profile is the path `A → … → B` of the blocks `P` … `Q`: lines and
//! arcs, points in ångström (X on the radius, Z), translated by the
//! finishing allowances. Roughing works in a frame of its own, `(c, d)`:
//! `d` the depth into the stock from the start point `S` (along X for
//! `G71`, Z for `G72`), `c` the distance along the cut (Z for `G71`, X for
//! `G72`), both 0 at `S` and growing towards the profile. The stock to
//! remove at a depth `d` is where that depth lies above the profile: the
//! intervals of `c` between the profile's crossings of the line, read
//! from the start side, where the profile at the start (`A`) is deeper.
//! Every pass runs at a depth `k·Δd` short of the profile's deepest point;
//! its cuts end on the profile, never inside it, and what they leave is
//! less than one depth of cut, which the pass along the profile takes.

use crate::arc::ArcDir;
use crate::trig::isqrt;

/// The blocks a profile holds at most.
pub const PROFILE_BLOCKS: usize = 128;

/// One element of a profile: a line or an arc to `to`, points `[X, Z]` in
/// ångström (X on the radius).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment {
    /// Where it ends.
    pub to: [i64; 2],
    /// For an arc: its centre and direction.
    pub arc: Option<([i64; 2], ArcDir)>,
}

/// Which axis a roughing cycle cuts along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Along {
    /// `G71`: passes along Z, stepped in X.
    Z,
    /// `G72`: passes along X, stepped in Z.
    X,
}

/// Why a profile cannot be roughed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CycleError {
    /// The profile has no element.
    Empty,
    /// Its first point is not deeper than the start point (the stock lies
    /// on the wrong side).
    Start,
    /// The depth of cut is not above 0.
    Depth,
    /// A point beyond the machine's range.
    Range,
}

impl CycleError {
    /// What a refusal says.
    pub const fn as_str(self) -> &'static str {
        match self {
            CycleError::Empty => "the profile (P to Q) has no move",
            CycleError::Start => {
                "the profile's first point must lie inside the start point (the stock side): move the start point out"
            }
            CycleError::Depth => "the depth of cut must be above 0",
            CycleError::Range => "the profile lies beyond 99999.999999 mm",
        }
    }
}

/// The frame of a roughing: `(c, d)` from machine `[X, Z]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame {
    along: Along,
    start: [i64; 2],
    /// Signs of `c` and `d` along their machine axes.
    sc: i64,
    sd: i64,
}

impl Frame {
    /// `(c, d)` of a machine point.
    pub fn to_cd(&self, p: [i64; 2]) -> [i64; 2] {
        let (x, z) = (p[0] - self.start[0], p[1] - self.start[1]);
        match self.along {
            Along::Z => [self.sc * z, self.sd * x],
            Along::X => [self.sc * x, self.sd * z],
        }
    }

    /// The machine point of `(c, d)`.
    pub fn to_xz(&self, q: [i64; 2]) -> [i64; 2] {
        let (a, b) = (self.sc * q[0], self.sd * q[1]);
        match self.along {
            Along::Z => [self.start[0] + b, self.start[1] + a],
            Along::X => [self.start[0] + a, self.start[1] + b],
        }
    }

    /// Whether `(c, d)` keeps the sense of turn of `(Z, X)`.
    fn keeps_turn(&self) -> bool {
        let same = self.sc * self.sd > 0;
        match self.along {
            Along::Z => same,
            Along::X => !same,
        }
    }
}

/// A roughing move, in machine coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// A rapid to a point.
    Rapid([i64; 2]),
    /// A feed in a line to a point.
    Feed([i64; 2]),
    /// A feed along an arc of the profile to a point.
    Arc([i64; 2], [i64; 2], ArcDir),
}

/// `G73`'s passes: the profile (moved by the finishing allowances) cut
/// whole `passes` times, each pass moved further by a share of the relief
/// that shrinks from all of it on the first pass to none on the last
/// (`docs/cycles.md` §4).
#[derive(Clone, Copy, Debug)]
pub struct Pattern<'a> {
    /// The start point S, where each pass returns.
    pub start: [i64; 2],
    /// The profile's first point (work coordinates, X on the radius),
    /// moved by the allowances.
    pub first: [i64; 2],
    /// Its elements, moved alike.
    pub segments: &'a [Segment],
    /// The relief: how far the first pass lies beyond the last, X (on the
    /// radius) and Z.
    pub relief: [i64; 2],
    /// The count of passes, at least 1.
    pub passes: u32,
}

impl Pattern<'_> {
    /// How far pass `j` (1 to `passes`) lies from the profile with its
    /// allowances: `relief · (passes − j) / (passes − 1)`, rounded half
    /// away from zero to the ångström.
    pub fn offset(&self, j: u32) -> [i64; 2] {
        let n = i64::from(self.passes.max(1));
        let left = n - i64::from(j.clamp(1, self.passes.max(1)));
        let share = |r: i64| {
            if n == 1 {
                0
            } else {
                crate::length::div_round_half_away(r.saturating_mul(left), n - 1)
            }
        };
        [share(self.relief[0]), share(self.relief[1])]
    }

    /// Every move, in order: for each pass, at the rapid rate to the moved
    /// profile's first point, along it at the feed (its arcs as arcs), and
    /// at the rapid rate back to S.
    pub fn steps<E>(&self, out: &mut impl FnMut(Step) -> Result<(), E>) -> Result<(), E> {
        for j in 1..=self.passes.max(1) {
            let o = self.offset(j);
            let at = |p: [i64; 2]| [p[0].saturating_add(o[0]), p[1].saturating_add(o[1])];
            out(Step::Rapid(at(self.first)))?;
            for g in self.segments {
                out(match g.arc {
                    None => Step::Feed(at(g.to)),
                    Some((c, dir)) => Step::Arc(at(g.to), at(c), dir),
                })?;
            }
            out(Step::Rapid(self.start))?;
        }
        Ok(())
    }
}

/// A piece of a profile in the `(c, d)` frame, monotone in `d` (arcs are
/// cut at their deepest and shallowest points).
#[derive(Clone, Copy, Debug)]
struct Piece {
    from: [i64; 2],
    to: [i64; 2],
    /// For an arc piece: its centre and radius, and on which side of the
    /// centre (in `c`) it lies.
    arc: Option<([i64; 2], i64, bool)>,
}

/// The roughing of a profile: its frame, its pieces' extent, and the depths
/// of its passes.
#[derive(Clone, Debug)]
pub struct Roughing<'a> {
    frame: Frame,
    a: [i64; 2],
    segments: &'a [Segment],
    depth: i64,
    retract: i64,
    /// The deepest point of the profile, `d`.
    deepest: i64,
    /// The farthest `c` of the profile.
    farthest: i64,
}

impl<'a> Roughing<'a> {
    /// The roughing from start point `s` of the profile from `a` through
    /// `segments` (translated already), passes `depth` apart (> 0),
    /// retracting `retract` at 45° after each cut.
    pub fn new(
        along: Along,
        s: [i64; 2],
        a: [i64; 2],
        segments: &'a [Segment],
        depth: i64,
        retract: i64,
    ) -> Result<Roughing<'a>, CycleError> {
        let last = segments.last().ok_or(CycleError::Empty)?;
        if depth <= 0 {
            return Err(CycleError::Depth);
        }
        // The depth (u) and cut (v) coordinates of a point.
        let u = |p: &[i64; 2]| match along {
            Along::Z => p[0],
            Along::X => p[1],
        };
        let v = |p: &[i64; 2]| match along {
            Along::Z => p[1],
            Along::X => p[0],
        };
        let sd = (u(&a) - u(&s)).signum();
        if sd == 0 {
            return Err(CycleError::Start);
        }
        // The cut runs towards the profile's farthest point from S.
        let far = core::iter::once(a)
            .chain(segments.iter().map(|g| g.to))
            .max_by_key(|p| (v(p) - v(&s)).abs())
            .unwrap_or(last.to);
        let sc = match (v(&far) - v(&s)).signum() {
            0 => -1,
            v => v,
        };
        let frame = Frame {
            along,
            start: s,
            sc,
            sd,
        };
        let mut r = Roughing {
            frame,
            a,
            segments,
            depth,
            retract: retract.max(0),
            deepest: 0,
            farthest: 0,
        };
        let mut deepest = frame.to_cd(a)[1];
        let mut farthest = frame.to_cd(a)[0];
        r.pieces(|p| {
            for q in [p.from, p.to] {
                deepest = deepest.max(q[1]);
                farthest = farthest.max(q[0]);
            }
        });
        r.deepest = deepest;
        r.farthest = farthest;
        if frame.to_cd(a)[1] <= 0 {
            return Err(CycleError::Start);
        }
        Ok(r)
    }

    /// The frame.
    pub const fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The depths of the passes: `k·Δd` while short of the deepest point.
    pub fn levels(&self) -> impl Iterator<Item = i64> + '_ {
        (1..)
            .map(move |k: i64| k.saturating_mul(self.depth))
            .take_while(move |&d| d < self.deepest)
    }

    /// Calls `f` with every piece of the profile, in order, in the frame.
    fn pieces(&self, mut f: impl FnMut(Piece)) {
        let mut from = self.frame.to_cd(self.a);
        for g in self.segments {
            let to = self.frame.to_cd(g.to);
            match g.arc {
                None => f(Piece {
                    from,
                    to,
                    arc: None,
                }),
                Some((centre, dir)) => {
                    let c = self.frame.to_cd(centre);
                    let ccw = (dir == ArcDir::Ccw) == self.frame.keeps_turn();
                    split_arc(from, to, c, ccw, &mut f);
                }
            }
            from = to;
        }
    }

    /// The stock intervals `[c1, c2]` at depth `d`, in order from the start
    /// side, each ending on the profile (or at its farthest point).
    pub fn intervals(&self, d: i64, out: &mut impl FnMut(i64, i64)) {
        // The crossings of the line with the profile, sorted.
        let mut xs = heapless::Vec::<i64, { 4 * PROFILE_BLOCKS + 8 }>::new();
        self.pieces(|p| {
            let (d0, d1) = (p.from[1], p.to[1]);
            // Half-open: a crossing where the profile passes from one side
            // of d to the other (deeper meaning > d).
            if (d0 >= d) == (d1 >= d) {
                return;
            }
            let c = match p.arc {
                None => line_at(p.from, p.to, d),
                Some((centre, r, plus)) => {
                    let dd = i128::from(d - centre[1]);
                    let rr = i128::from(r);
                    let h = isqrt((rr * rr - dd * dd).max(0) as u128) as i64;
                    if plus {
                        centre[0] + h
                    } else {
                        centre[0] - h
                    }
                }
            };
            let _ = xs.push(c);
        });
        sort_small(&mut xs);
        // From the start side: stock where the profile is deeper.
        let mut cut = self.frame.to_cd(self.a)[1] >= d;
        let mut from = 0i64;
        for &c in &xs {
            if cut && c > from {
                out(from, c);
            }
            cut = !cut;
            from = c.max(0);
        }
        if cut && self.farthest > from {
            out(from, self.farthest);
        }
    }

    /// Every move of the roughing, in order: the passes, then the pass
    /// along the profile, then the return to the start point; `f` gets
    /// each (machine coordinates).
    pub fn steps(&self, f: &mut impl FnMut(Step)) {
        let fr = self.frame;
        let at = |c: i64, d: i64| fr.to_xz([c, d]);
        // Moves of no length are left out.
        let mut last = fr.start;
        let f = &mut |step: Step| {
            let to = match step {
                Step::Rapid(p) | Step::Feed(p) | Step::Arc(p, _, _) => p,
            };
            if to != last {
                last = to;
                f(step);
            }
        };
        let mut above = 0i64;
        for d in self.levels() {
            let mut first = true;
            let mut here = [0i64, above];
            let mut cuts = 0;
            // Whether the last cut was a pocket: stock may stand between it
            // and the start side at the depth it retracted to.
            let mut pocket = false;
            self.intervals(d, &mut |c1, c2| {
                cuts += 1;
                pocket = !(first && c1 == 0);
                if first && c1 == 0 {
                    // In from the start side at the depth of the pass.
                    if here != [0, d] {
                        f(Step::Rapid(at(0, d)));
                    }
                } else {
                    // A pocket: up to the start depth, across, down to the
                    // depth cleared by the pass before, in at the feed.
                    if here[1] != 0 {
                        f(Step::Rapid(at(here[0], 0)));
                    }
                    f(Step::Rapid(at(c1, 0)));
                    if above > 0 {
                        f(Step::Rapid(at(c1, above)));
                    }
                    f(Step::Feed(at(c1, d)));
                }
                first = false;
                f(Step::Feed(at(c2, d)));
                // Out at 45°, within what this cut cleared.
                let e = self.retract.min(c2 - c1).min(d);
                here = [c2 - e, d - e];
                if e > 0 {
                    f(Step::Feed(at(here[0], here[1])));
                }
            });
            // Back to the start side for the next pass.
            if cuts > 0 {
                if pocket && here[1] != 0 {
                    f(Step::Rapid(at(here[0], 0)));
                    here[1] = 0;
                }
                f(Step::Rapid(at(0, here[1])));
            }
            above = d;
        }
        // Along the profile: down the start side to its first point's
        // depth, to the point, then its elements at the feed.
        let first = fr.to_cd(self.a);
        f(Step::Rapid(at(0, first[1])));
        if first[0] != 0 {
            f(Step::Rapid(self.a));
        }
        for g in self.segments {
            match g.arc {
                None => f(Step::Feed(g.to)),
                Some((centre, dir)) => f(Step::Arc(g.to, centre, dir)),
            }
        }
        // Out of the stock, and back to the start point.
        let end = fr.to_cd(self.segments.last().map_or(self.a, |g| g.to));
        if end[1] != 0 {
            f(Step::Rapid(at(end[0], 0)));
        }
        f(Step::Rapid(fr.start));
    }
}

/// Where the line `p → q` is at depth `d` (`p[1] ≠ q[1]`), rounded to the
/// nearest ångström.
fn line_at(p: [i64; 2], q: [i64; 2], d: i64) -> i64 {
    let (dc, dd) = (i128::from(q[0] - p[0]), i128::from(q[1] - p[1]));
    let num = dc * i128::from(d - p[1]);
    // Rounded half away from zero; dd ≠ 0 (the caller's crossing).
    let den = dd;
    let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
    if den == 0 {
        return p[0];
    }
    let q2 = crate::wide::checked_divrem_i128(2 * num + if num >= 0 { den } else { -den }, 2 * den)
        .map_or(0, |(q, _)| q);
    p[0] + q2 as i64
}

/// Cuts the arc `from → to` about `c` (`ccw` in the frame) at its points
/// of extreme depth (where it crosses `c = centre's c`) into pieces, each
/// monotone in depth and on one side of the centre.
fn split_arc(from: [i64; 2], to: [i64; 2], c: [i64; 2], ccw: bool, f: &mut impl FnMut(Piece)) {
    let r2 = {
        let (a, b) = (i128::from(from[0] - c[0]), i128::from(from[1] - c[1]));
        a * a + b * b
    };
    let r = isqrt(r2 as u128) as i64;
    // The extreme points: straight below and above the centre in depth.
    let extremes = [[c[0], c[1] + r], [c[0], c[1] - r]];
    let v0 = [from[0] - c[0], from[1] - c[1]];
    let v1 = [to[0] - c[0], to[1] - c[1]];
    let sweep = sweep_of(v0, v1, ccw);
    let mut cuts: heapless::Vec<(i128, [i64; 2]), 2> = heapless::Vec::new();
    for e in extremes {
        let v = [e[0] - c[0], e[1] - c[1]];
        let a = sweep_of(v0, v, ccw);
        if a > 0 && a < sweep {
            let _ = cuts.push((a, e));
        }
    }
    if let [p, q] = cuts.as_mut_slice() {
        if q.0 < p.0 {
            core::mem::swap(p, q);
        }
    }
    let mut start = from;
    for (_, e) in cuts.iter().chain(core::iter::once(&(sweep, to))) {
        let mid_side = {
            // Which side of the centre the piece lies on: by its two ends.
            let s = start[0] - c[0] + e[0] - c[0];
            if s == 0 {
                // A half circle from top to bottom: the sweep's direction.
                let mid = mid_vector(
                    [start[0] - c[0], start[1] - c[1]],
                    [e[0] - c[0], e[1] - c[1]],
                    ccw,
                );
                mid[0] >= 0
            } else {
                s > 0
            }
        };
        f(Piece {
            from: start,
            to: *e,
            arc: Some((c, r, mid_side)),
        });
        start = *e;
    }
}

/// A direction halfway along the turn from `a` to `b` (`ccw`), scaled.
fn mid_vector(a: [i64; 2], b: [i64; 2], ccw: bool) -> [i64; 2] {
    // The perpendicular of the chord, on the side the turn passes.
    let chord = [b[0] - a[0], b[1] - a[1]];
    let left = [-chord[1], chord[0]];
    if ccw {
        [-left[0], -left[1]]
    } else {
        left
    }
}

/// A monotone measure of the turn from `a` to `b` (in `ccw` sense):
/// quadrants times 2⁶² plus the pseudo-angle within the quadrant; 0 for
/// `b` = `a`, a full turn for a closed circle.
fn sweep_of(a: [i64; 2], b: [i64; 2], ccw: bool) -> i128 {
    let pa = pseudo_angle(a, ccw);
    let pb = pseudo_angle(b, ccw);
    let full = 4i128 << 62;
    let s = (pb - pa).rem_euclid(full);
    if s == 0 && a != b {
        full
    } else if s == 0 {
        // The same point: a full circle.
        full
    } else {
        s
    }
}

/// The angle of `v` as a number growing with the turn (`ccw`): its
/// quadrant and, within it, the ratio of its components.
/// Sorts a few values in place (insertion sort: no bounds to check, no
/// panic path).
fn sort_small(v: &mut [i64]) {
    for i in 1..v.len() {
        let mut j = i;
        while j > 0 {
            match v.get_mut(j - 1..=j) {
                Some([p, q]) if *q < *p => core::mem::swap(p, q),
                _ => break,
            }
            j -= 1;
        }
    }
}

fn pseudo_angle(v: [i64; 2], ccw: bool) -> i128 {
    let (x, y) = (i128::from(v[0]), i128::from(if ccw { v[1] } else { -v[1] }));
    let one = 1i128 << 62;
    if y >= 0 && x > 0 {
        ratio(y, x + y)
    } else if x <= 0 && y > 0 {
        one + ratio(-x, y - x)
    } else if y <= 0 && x < 0 {
        2 * one + ratio(-y, -x - y)
    } else {
        3 * one + ratio(x, x - y)
    }
}

/// `num·2⁶²/den`, for `|num| ≤ |den| < 2⁴¹` (the product fits and the
/// quotient is at most 2⁶²); 0 for `den = 0`. One call of the shared
/// 128-bit division for the four quadrants.
#[inline(never)]
fn ratio(num: i128, den: i128) -> i128 {
    crate::wide::checked_divrem_i128(num.wrapping_mul(1i128 << 62), den).map_or(0, |(q, _)| q)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    const MM: i64 = 10_000_000;

    fn line(x: i64, z: i64) -> Segment {
        Segment {
            to: [x * MM / 10, z * MM / 10],
            arc: None,
        }
    }

    fn steps(r: &Roughing<'_>) -> Vec<Step> {
        let mut out = Vec::new();
        r.steps(&mut |s| out.push(s));
        out
    }

    /// An OD shaft of two diameters (radii 10 and 15 mm) from X40 (radius 20) Z2:
    /// passes at radius 19, 18, … 11 along Z to the shoulder.
    #[test]
    fn a_stepped_shaft_is_roughed_in_passes_that_end_on_the_profile() {
        let s = [20 * MM, 2 * MM];
        let a = [10 * MM, 2 * MM];
        let prof = [
            line(100, 0),
            line(100, -300),
            line(150, -300),
            line(150, -500),
            line(200, -500),
        ];
        let r = Roughing::new(Along::Z, s, a, &prof, MM, MM / 2).unwrap();
        let levels: Vec<i64> = r.levels().collect();
        assert_eq!(levels.len(), 9);
        let mut cuts = Vec::new();
        for d in r.levels() {
            r.intervals(d, &mut |c1, c2| cuts.push((d, c1, c2)));
        }
        // At radius 19 … 15 the cut ends at Z−50 (c = 52 mm; the pass at
        // 15 runs on the step's face, never below it), at 14 … 11 at the
        // shoulder Z−30 (c = 32 mm).
        for &(d, c1, c2) in &cuts {
            assert_eq!(c1, 0);
            let want = if d <= 5 * MM { 52 * MM } else { 32 * MM };
            assert_eq!(c2, want, "depth {d}");
        }
        let st = steps(&r);
        // Never deeper than the profile: every feed point on or above it.
        for s in &st {
            if let Step::Feed(p) = s {
                let (x, z) = (p[0], p[1]);
                // On a shoulder's wall counts as on the profile.
                let floor = if z >= -30 * MM {
                    10 * MM
                } else if z >= -50 * MM {
                    15 * MM
                } else {
                    20 * MM
                };
                assert!(x >= floor, "{s:?}");
            }
        }
        assert_eq!(st.last(), Some(&Step::Rapid(s)));
    }

    #[test]
    fn an_arc_is_crossed_where_its_circle_is() {
        // A quarter circle of radius 10 about (X0, Z−10) from X0 Z0 to
        // X10 Z−10 (G03: counter-clockwise with Z to the right, X up).
        let s = [15 * MM, MM];
        let a = [0, MM];
        let prof = [
            line(0, 0),
            Segment {
                to: [10 * MM, -10 * MM],
                arc: Some(([0, -10 * MM], ArcDir::Ccw)),
            },
            line(150, -100),
        ];
        let r = Roughing::new(Along::Z, s, a, &prof, MM, MM / 2).unwrap();
        let mut got = Vec::new();
        r.intervals(10 * MM, &mut |c1, c2| got.push((c1, c2)));
        // At radius 5: the circle at Z = −10 + √(100 − 25) = −1.339746 mm,
        // c = 1 − Z.
        assert_eq!(got.len(), 1);
        let z = -10.0 + (75.0f64).sqrt();
        let want = ((1.0 - z) * 1e7).round() as i64;
        assert!((got[0].1 - want).abs() <= 1, "{got:?} {want}");
    }
}

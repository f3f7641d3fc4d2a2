//! Double-precision (f64) reference of the corner chamfers and rounds `,C`
//! and `,R` of the Fanuc dialect, written from `docs/compensation.md` §9
//! (with the frame of §1 and the offset elements of §2–§3) alone,
//! independently of the controller's fixed-point core.
//!
//! # Frame
//!
//! Lengths in mm, points `(x, z)` with `x` on the radius. Geometry is drawn
//! in the plane with Z to the right and X up (§1); "counter-clockwise"
//! (`ccw`, `G03`) is the positive rotation of that picture. For a unit
//! direction `t` the left normal is `(x: t.z, z: −t.x)`; the turn from `t1`
//! to `t2` is to the left when `t1.z·t2.x − t1.x·t2.z > 0`. The tangent of an
//! arc at `p`, with `r = p − centre`, is `(x: r.z, z: −r.x)` when `ccw`, the
//! opposite when clockwise.
//!
//! # The corner ([`corner`])
//!
//! The corner point `P` is the end of the first element (the start of the
//! next). `t1` is the first element's direction at `P`, `t2` the next one's.
//!
//! * Parallel directions (`|t1 × t2| < 10⁻⁶`, tangent or reversing):
//!   [`RefCornerRefusal::NoCorner`].
//! * **Chamfer `c`**: both elements must be lines
//!   ([`RefCornerRefusal::ChamferArc`] otherwise). The first ends at
//!   `P − c·t1`, the chamfer runs to `P + c·t2`, the next line goes on from
//!   there.
//! * **Round `r`**: the centre is where the two elements, each offset by `r`
//!   towards the inside of the turn (a line: the parallel line; an arc: the
//!   circle about its centre of radius `R ∓ r`, `R − r` when the inside is
//!   the centre's side, refused when that is `≤ 0`), meet; of two
//!   intersections the one nearest `P`. The round touches each element at
//!   the foot of the perpendicular from its centre (on an arc: on the ray
//!   from the arc's centre through the round's centre, at radius `R`), and
//!   runs counter-clockwise when the turn is to the left, clockwise when to
//!   the right.
//! * [`RefCornerRefusal::TooBig`]: the chamfer or touch point on the first
//!   element is not between its start and `P` (for an arc: within its swept
//!   angle, in its direction), or the one on the next element is not after
//!   its start and strictly before its end; no intersection of the offset
//!   elements; an arc's offset radius `≤ 0`.
//!
//! # Model choices the document leaves open
//!
//! * Order of refusals: `ChamferArc` (a property of the words), then
//!   `NoCorner`, then `TooBig`. A size that is not finite and positive is
//!   `TooBig` (after the first two checks).
//! * Degenerate elements (a line of zero length, an arc of zero radius) have
//!   no direction: `NoCorner`.
//! * An arc's radius `R` is taken at the corner: `|P − centre|`.
//! * Positions along an element are compared as lengths with a tolerance of
//!   [`EPS`] = 10⁻⁹ mm: a touch point up to `EPS` outside the first element
//!   is on it, and when no more than `EPS` of the first element is left it
//!   is dropped (`None`); the next element must keep more than `EPS`. The
//!   core works on the 10⁻⁷ mm grid, so cases within ~10⁻⁷ mm of these
//!   limits are not meaningful comparisons.
//! * Nothing is rounded to the 10⁻⁷ mm grid.

/// Length tolerance (mm) for positions along an element.
pub const EPS: f64 = 1e-9;

/// Below this `|sin θ|` of the turn there is no corner.
const PARALLEL: f64 = 1e-6;

const TAU: f64 = std::f64::consts::TAU;

/// One programmed element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefElement {
    Line {
        from: (f64, f64),
        to: (f64, f64),
    },
    /// `ccw`: counter-clockwise in the plane drawn with Z to the right and X
    /// up (the direction of travel turns like the +90° rotation
    /// `(z, x) -> (−x, z)` of that picture).
    Arc {
        from: (f64, f64),
        to: (f64, f64),
        centre: (f64, f64),
        ccw: bool,
    },
}

/// The word on the first element: `,C c` or `,R r` (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefCorner {
    Chamfer(f64),
    Round(f64),
}

/// Why a corner cannot be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefCornerRefusal {
    /// The elements meet tangentially or reverse along one line.
    NoCorner,
    /// The chamfer or round does not fit on the two elements.
    TooBig,
    /// A chamfer with an arc on either side.
    ChamferArc,
}

/// A point or vector in (x, z) components.
#[derive(Clone, Copy, Debug, PartialEq)]
struct V {
    x: f64,
    z: f64,
}

impl V {
    fn of(p: (f64, f64)) -> V {
        V { x: p.0, z: p.1 }
    }
    fn pt(self) -> (f64, f64) {
        (self.x, self.z)
    }
    fn add(self, o: V) -> V {
        V {
            x: self.x + o.x,
            z: self.z + o.z,
        }
    }
    fn sub(self, o: V) -> V {
        V {
            x: self.x - o.x,
            z: self.z - o.z,
        }
    }
    fn scale(self, k: f64) -> V {
        V {
            x: self.x * k,
            z: self.z * k,
        }
    }
    fn dot(self, o: V) -> f64 {
        self.x * o.x + self.z * o.z
    }
    /// Positive when `o` is to the left of `self` (Z right, X up).
    fn cross(self, o: V) -> f64 {
        self.z * o.x - self.x * o.z
    }
    fn len(self) -> f64 {
        self.x.hypot(self.z)
    }
    fn unit(self) -> Option<V> {
        let l = self.len();
        (l > 0.0 && l.is_finite()).then(|| self.scale(1.0 / l))
    }
    /// Rotated by +90° in the (Z right, X up) picture: the left normal of a
    /// direction, the ccw tangent of a radius vector.
    fn left(self) -> V {
        V {
            x: self.z,
            z: -self.x,
        }
    }
    /// Angle in the picture, from +Z towards +X.
    fn angle(self) -> f64 {
        self.x.atan2(self.z)
    }
}

/// Angle swept from `a` to `b` about the origin in the given direction, in
/// `[0, 2π)`.
fn directed(a: V, b: V, ccw: bool) -> f64 {
    let d = if ccw {
        b.angle() - a.angle()
    } else {
        a.angle() - b.angle()
    };
    let d = d.rem_euclid(TAU);
    if d >= TAU {
        0.0
    } else {
        d
    }
}

/// An element in vector form, with its length and (for arcs) radius at the
/// corner.
#[derive(Clone, Copy, Debug)]
enum El {
    Line {
        from: V,
        to: V,
        t: V,
        len: f64,
    },
    Arc {
        from: V,
        to: V,
        c: V,
        ccw: bool,
        r: f64,
        sweep: f64,
    },
}

impl El {
    /// `radius_at`: the point whose distance to the centre is the radius.
    fn of(e: RefElement, radius_at: (f64, f64)) -> Option<El> {
        match e {
            RefElement::Line { from, to } => {
                let (from, to) = (V::of(from), V::of(to));
                let d = to.sub(from);
                Some(El::Line {
                    from,
                    to,
                    t: d.unit()?,
                    len: d.len(),
                })
            }
            RefElement::Arc {
                from,
                to,
                centre,
                ccw,
            } => {
                let (from, to, c) = (V::of(from), V::of(to), V::of(centre));
                let r = V::of(radius_at).sub(c).len();
                if !(r > 0.0 && r.is_finite()) {
                    return None;
                }
                let mut sweep = directed(from.sub(c), to.sub(c), ccw);
                if sweep == 0.0 {
                    sweep = TAU;
                }
                Some(El::Arc {
                    from,
                    to,
                    c,
                    ccw,
                    r,
                    sweep,
                })
            }
        }
    }

    fn length(&self) -> f64 {
        match *self {
            El::Line { len, .. } => len,
            El::Arc { r, sweep, .. } => r * sweep,
        }
    }

    /// Unit direction of travel at the point `p` (on the element's line or
    /// circle).
    fn dir_at(&self, p: V) -> Option<V> {
        match *self {
            El::Line { t, .. } => Some(t),
            El::Arc { c, ccw, .. } => {
                let tan = p.sub(c).left();
                tan.scale(if ccw { 1.0 } else { -1.0 }).unit()
            }
        }
    }

    /// Length along the element from its start to `q` (on its line or
    /// circle); a point up to [`EPS`] before the start of an arc comes out
    /// negative rather than wrapping round.
    fn position(&self, q: V) -> f64 {
        match *self {
            El::Line { from, t, .. } => q.sub(from).dot(t),
            El::Arc {
                from, c, ccw, r, ..
            } => {
                let a = directed(from.sub(c), q.sub(c), ccw);
                if (TAU - a) * r <= EPS {
                    (a - TAU) * r
                } else {
                    a * r
                }
            }
        }
    }

    /// The foot of the perpendicular from `q` on the element's line, or the
    /// point of its circle on the ray from its centre through `q`.
    fn foot(&self, q: V) -> Option<V> {
        match *self {
            El::Line { from, t, .. } => Some(from.add(t.scale(q.sub(from).dot(t)))),
            El::Arc { c, r, .. } => Some(c.add(q.sub(c).unit()?.scale(r))),
        }
    }

    /// The element offset by `d` towards the side `side` (+1 left, −1 right
    /// of travel), through the corner `p`.
    fn offset(&self, p: V, side: f64, d: f64) -> Option<Off> {
        match *self {
            El::Line { t, .. } => Some(Off::Line {
                p: p.add(t.left().scale(side * d)),
                t,
            }),
            El::Arc { c, ccw, r, .. } => {
                // The left of a ccw arc is its centre's side.
                let towards_centre = if ccw { side } else { -side };
                let rho = r - towards_centre * d;
                (rho > 0.0).then_some(Off::Circle { c, rho })
            }
        }
    }

    /// The element from `p` (on it) to its end.
    fn rest_after(&self, p: V) -> RefElement {
        match *self {
            El::Line { to, .. } => RefElement::Line {
                from: p.pt(),
                to: to.pt(),
            },
            El::Arc { to, c, ccw, .. } => RefElement::Arc {
                from: p.pt(),
                to: to.pt(),
                centre: c.pt(),
                ccw,
            },
        }
    }

    /// The element from its start to `p` (on it).
    fn part_before(&self, p: V) -> RefElement {
        match *self {
            El::Line { from, .. } => RefElement::Line {
                from: from.pt(),
                to: p.pt(),
            },
            El::Arc { from, c, ccw, .. } => RefElement::Arc {
                from: from.pt(),
                to: p.pt(),
                centre: c.pt(),
                ccw,
            },
        }
    }
}

/// An offset element, taken as its full line or circle.
#[derive(Clone, Copy, Debug)]
enum Off {
    Line { p: V, t: V },
    Circle { c: V, rho: f64 },
}

/// The intersection of two offset elements nearest `near`.
fn meet(a: Off, b: Off, near: V) -> Option<V> {
    let nearest = |p: V, q: V| {
        if p.sub(near).len() <= q.sub(near).len() {
            p
        } else {
            q
        }
    };
    match (a, b) {
        (Off::Line { p: p1, t: t1 }, Off::Line { p: p2, t: t2 }) => {
            let den = t1.cross(t2);
            if den == 0.0 {
                return None;
            }
            let s = p2.sub(p1).cross(t2) / den;
            Some(p1.add(t1.scale(s)))
        }
        (Off::Line { p, t }, Off::Circle { c, rho })
        | (Off::Circle { c, rho }, Off::Line { p, t }) => {
            let w = p.sub(c);
            let b = w.dot(t);
            let disc = b * b - (w.dot(w) - rho * rho);
            if disc < 0.0 {
                return None;
            }
            let h = disc.sqrt();
            Some(nearest(p.add(t.scale(-b - h)), p.add(t.scale(-b + h))))
        }
        (Off::Circle { c: c1, rho: r1 }, Off::Circle { c: c2, rho: r2 }) => {
            let u = c2.sub(c1);
            let d = u.len();
            if d == 0.0 || d > r1 + r2 || d < (r1 - r2).abs() {
                return None;
            }
            let u = u.scale(1.0 / d);
            let a = (d * d + r1 * r1 - r2 * r2) / (2.0 * d);
            let h = (r1 * r1 - a * a).max(0.0).sqrt();
            let base = c1.add(u.scale(a));
            let n = u.left();
            Some(nearest(base.add(n.scale(h)), base.sub(n.scale(h))))
        }
    }
}

/// The first element (which asks for `corner` at its end) and the next one
/// (starting where the first ends): the first cut short (None when nothing of
/// it is left), the chamfer (a Line) or the round (an Arc), and the next
/// element from where that ends.
pub fn corner(
    first: RefElement,
    next: RefElement,
    corner: RefCorner,
) -> Result<(Option<RefElement>, RefElement, RefElement), RefCornerRefusal> {
    use RefCornerRefusal::{ChamferArc, NoCorner, TooBig};

    let both_lines = matches!(
        (first, next),
        (RefElement::Line { .. }, RefElement::Line { .. })
    );
    if matches!(corner, RefCorner::Chamfer(_)) && !both_lines {
        return Err(ChamferArc);
    }

    let end_of = |e: &RefElement| match *e {
        RefElement::Line { to, .. } | RefElement::Arc { to, .. } => to,
    };
    let start_of = |e: &RefElement| match *e {
        RefElement::Line { from, .. } | RefElement::Arc { from, .. } => from,
    };
    let p = V::of(end_of(&first));
    let e1 = El::of(first, end_of(&first)).ok_or(NoCorner)?;
    let e2 = El::of(next, start_of(&next)).ok_or(NoCorner)?;
    let t1 = e1.dir_at(p).ok_or(NoCorner)?;
    let t2 = e2.dir_at(V::of(start_of(&next))).ok_or(NoCorner)?;
    let sin = t1.cross(t2);
    if sin.abs() < PARALLEL {
        return Err(NoCorner);
    }

    let size = match corner {
        RefCorner::Chamfer(c) | RefCorner::Round(c) => c,
    };
    if !(size > 0.0 && size.is_finite()) {
        return Err(TooBig);
    }

    // The touch (or chamfer) points, and the middle element.
    let (k1, k2, middle) = match corner {
        RefCorner::Chamfer(c) => {
            let a = p.sub(t1.scale(c));
            let b = p.add(t2.scale(c));
            (
                a,
                b,
                RefElement::Line {
                    from: a.pt(),
                    to: b.pt(),
                },
            )
        }
        RefCorner::Round(r) => {
            let side = if sin > 0.0 { 1.0 } else { -1.0 };
            let o1 = e1.offset(p, side, r).ok_or(TooBig)?;
            let o2 = e2.offset(p, side, r).ok_or(TooBig)?;
            let c = meet(o1, o2, p).ok_or(TooBig)?;
            let a = e1.foot(c).ok_or(TooBig)?;
            let b = e2.foot(c).ok_or(TooBig)?;
            (
                a,
                b,
                RefElement::Arc {
                    from: a.pt(),
                    to: b.pt(),
                    centre: c.pt(),
                    ccw: sin > 0.0,
                },
            )
        }
    };

    // The first element keeps [start, k1]; k1 must lie between its start and
    // the corner.
    let s1 = e1.position(k1);
    let len1 = e1.length();
    if !(s1 >= -EPS && s1 <= len1 + EPS) {
        return Err(TooBig);
    }
    // The next element keeps (k2, end], and must keep some length.
    let s2 = e2.position(k2);
    let len2 = e2.length();
    if !(s2 >= -EPS && len2 - s2 > EPS) {
        return Err(TooBig);
    }

    let first_cut = (s1 > EPS).then(|| e1.part_before(k1));
    Ok((first_cut, middle, e2.rest_after(k2)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const TOL: f64 = 1e-9;

    fn close(a: (f64, f64), b: (f64, f64)) -> bool {
        (a.0 - b.0).abs() < TOL && (a.1 - b.1).abs() < TOL
    }

    #[track_caller]
    fn assert_pt(a: (f64, f64), b: (f64, f64)) {
        assert!(close(a, b), "{a:?} != {b:?}");
    }

    #[track_caller]
    fn assert_el(a: RefElement, b: RefElement) {
        match (a, b) {
            (RefElement::Line { from: f1, to: t1 }, RefElement::Line { from: f2, to: t2 }) => {
                assert_pt(f1, f2);
                assert_pt(t1, t2);
            }
            (
                RefElement::Arc {
                    from: f1,
                    to: t1,
                    centre: c1,
                    ccw: w1,
                },
                RefElement::Arc {
                    from: f2,
                    to: t2,
                    centre: c2,
                    ccw: w2,
                },
            ) => {
                assert_pt(f1, f2);
                assert_pt(t1, t2);
                assert_pt(c1, c2);
                assert_eq!(w1, w2);
            }
            _ => panic!("{a:?} != {b:?}"),
        }
    }

    fn line(from: (f64, f64), to: (f64, f64)) -> RefElement {
        RefElement::Line { from, to }
    }

    fn arc(from: (f64, f64), to: (f64, f64), centre: (f64, f64), ccw: bool) -> RefElement {
        RefElement::Arc {
            from,
            to,
            centre,
            ccw,
        }
    }

    #[test]
    fn orientation_conventions() {
        // Left of +Z travel is +X.
        let t = V { x: 0.0, z: 1.0 };
        assert_eq!(t.left(), V { x: 1.0, z: 0.0 });
        // +Z then +X is a left turn.
        assert!(t.cross(V { x: 1.0, z: 0.0 }) > 0.0);
        // A ccw arc about the origin at (0, 1) (on +Z) travels towards +X.
        let e = El::of(arc((0.0, 1.0), (1.0, 0.0), (0.0, 0.0), true), (0.0, 1.0)).unwrap();
        assert_eq!(e.dir_at(V { x: 0.0, z: 1.0 }), Some(V { x: 1.0, z: 0.0 }));
        assert!((e.length() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    }

    #[test]
    fn round_on_a_right_angle() {
        // −Z along x = 10, then +X up the face: a right turn of 90°.
        let first = line((10.0, 0.0), (10.0, -30.0));
        let next = line((10.0, -30.0), (30.0, -30.0));
        let (a, r, b) = corner(first, next, RefCorner::Round(5.0)).unwrap();
        assert_el(a.unwrap(), line((10.0, 0.0), (10.0, -25.0)));
        assert_el(r, arc((10.0, -25.0), (15.0, -30.0), (15.0, -25.0), false));
        assert_el(b, line((15.0, -30.0), (30.0, -30.0)));

        // The same corner driven the other way turns left: ccw.
        let (a, r, b) = corner(
            line((30.0, -30.0), (10.0, -30.0)),
            line((10.0, -30.0), (10.0, 0.0)),
            RefCorner::Round(5.0),
        )
        .unwrap();
        assert_el(a.unwrap(), line((30.0, -30.0), (15.0, -30.0)));
        assert_el(r, arc((15.0, -30.0), (10.0, -25.0), (15.0, -25.0), true));
        assert_el(b, line((10.0, -25.0), (10.0, 0.0)));
    }

    #[test]
    fn round_on_a_45_degree_turn() {
        // −Z, then 45° up: direction (x, z) = (1, −1)/√2, a right turn.
        let first = line((0.0, 0.0), (0.0, -20.0));
        let next = line((0.0, -20.0), (10.0, -30.0));
        let r = 4.0;
        let l = r * (22.5f64.to_radians()).tan();
        assert!((l - r * (2f64.sqrt() - 1.0)).abs() < 1e-12);
        let h = l / 2f64.sqrt();
        let (a, round, b) = corner(first, next, RefCorner::Round(r)).unwrap();
        assert_el(a.unwrap(), line((0.0, 0.0), (0.0, -20.0 + l)));
        assert_el(
            round,
            arc((0.0, -20.0 + l), (h, -20.0 - h), (r, -20.0 + l), false),
        );
        assert_el(b, line((h, -20.0 - h), (10.0, -30.0)));
        // The centre is r from the next line x = −(z + 20).
        let RefElement::Arc { centre: c, .. } = round else {
            unreachable!()
        };
        let dist = (c.0 + c.1 + 20.0).abs() / 2f64.sqrt();
        assert!((dist - r).abs() < 1e-12);
    }

    #[test]
    fn chamfers() {
        let first = line((10.0, 0.0), (10.0, -30.0));
        let next = line((10.0, -30.0), (30.0, -30.0));
        let (a, c, b) = corner(first, next, RefCorner::Chamfer(2.0)).unwrap();
        assert_el(a.unwrap(), line((10.0, 0.0), (10.0, -28.0)));
        assert_el(c, line((10.0, -28.0), (12.0, -30.0)));
        assert_el(b, line((12.0, -30.0), (30.0, -30.0)));

        // Along a 45° next line the chamfer ends c/√2 on each axis.
        let next = line((10.0, -30.0), (20.0, -40.0));
        let h = 2.0 / 2f64.sqrt();
        let (a, c, b) = corner(first, next, RefCorner::Chamfer(2.0)).unwrap();
        assert_el(a.unwrap(), line((10.0, 0.0), (10.0, -28.0)));
        assert_el(c, line((10.0, -28.0), (10.0 + h, -30.0 - h)));
        assert_el(b, line((10.0 + h, -30.0 - h), (20.0, -40.0)));

        // A chamfer using all of the first element leaves nothing of it.
        let next = line((10.0, -30.0), (40.0, -60.0));
        let (a, c, _) = corner(first, next, RefCorner::Chamfer(30.0)).unwrap();
        assert_eq!(a, None);
        assert_el(
            c,
            line(
                (10.0, 0.0),
                (10.0 + 30.0 * 0.5f64.sqrt(), -30.0 - 30.0 * 0.5f64.sqrt()),
            ),
        );
    }

    /// −Z along x = 10 to (10, −20), then a ccw arc of R = 10 about
    /// (10, −30) up to (20, −30): it leaves the corner along +X, a right turn;
    /// the inside is outside the arc's circle (R + r).
    #[test]
    fn round_from_a_line_onto_an_arc() {
        let first = line((10.0, 0.0), (10.0, -20.0));
        let next = arc((10.0, -20.0), (20.0, -30.0), (10.0, -30.0), true);
        let r = 2.0;
        // Offset line x = 12 meets the circle of radius 12 about (10, −30)
        // at z = −30 + √140 (the nearer of the two).
        let zc = -30.0 + 140f64.sqrt();
        let c = (12.0, zc);
        let t2 = (
            10.0 + 10.0 * 2.0 / 12.0,
            -30.0 + 10.0 * 140f64.sqrt() / 12.0,
        );
        let (a, round, b) = corner(first, next, RefCorner::Round(r)).unwrap();
        assert_el(a.unwrap(), line((10.0, 0.0), (10.0, zc)));
        assert_el(round, arc((10.0, zc), t2, c, false));
        assert_el(b, arc(t2, (20.0, -30.0), (10.0, -30.0), true));

        // Driven backwards: the arc first (cw), then the line; a left turn.
        let first = arc((20.0, -30.0), (10.0, -20.0), (10.0, -30.0), false);
        let next = line((10.0, -20.0), (10.0, 0.0));
        let (a, round, b) = corner(first, next, RefCorner::Round(r)).unwrap();
        assert_el(a.unwrap(), arc((20.0, -30.0), t2, (10.0, -30.0), false));
        assert_el(round, arc(t2, (10.0, zc), c, true));
        assert_el(b, line((10.0, zc), (10.0, 0.0)));
    }

    #[test]
    fn round_onto_a_concave_arc() {
        // −Z, then a cw arc of R = 10 about (10, −10) leaving along +X: a
        // right turn, and the arc keeps turning right, so the inside is the
        // centre's side (R − r). Offset line x = 12 meets the circle of
        // radius 8 about (10, −10) at z = −10 − √60.
        let first = line((10.0, 0.0), (10.0, -20.0));
        let next = arc((10.0, -20.0), (20.0, -10.0), (10.0, -10.0), false);
        let zc = -10.0 - 60f64.sqrt();
        let t2 = (10.0 + 2.0 * 10.0 / 8.0, -10.0 - 60f64.sqrt() * 10.0 / 8.0);
        let (a, round, b) = corner(first, next, RefCorner::Round(2.0)).unwrap();
        assert_el(a.unwrap(), line((10.0, 0.0), (10.0, zc)));
        assert_el(round, arc((10.0, zc), t2, (12.0, zc), false));
        assert_el(b, arc(t2, (20.0, -10.0), (10.0, -10.0), false));
    }

    #[test]
    fn first_element_used_up() {
        let first = line((10.0, -25.0), (10.0, -30.0));
        let next = line((10.0, -30.0), (30.0, -30.0));
        let (a, r, _) = corner(first, next, RefCorner::Round(5.0)).unwrap();
        assert_eq!(a, None);
        assert_el(r, arc((10.0, -25.0), (15.0, -30.0), (15.0, -25.0), false));
    }

    #[test]
    fn refusals() {
        use RefCornerRefusal::*;
        let first = line((10.0, 0.0), (10.0, -30.0));
        let round = RefCorner::Round(2.0);
        let chamfer = RefCorner::Chamfer(2.0);

        // Straight on, and reversing along the same line.
        let on = line((10.0, -30.0), (10.0, -40.0));
        let back = line((10.0, -30.0), (10.0, -10.0));
        for c in [round, chamfer] {
            assert_eq!(corner(first, on, c), Err(NoCorner));
            assert_eq!(corner(first, back, c), Err(NoCorner));
        }
        // Tangent onto an arc (cw about (7, −30): leaves along −Z).
        let tangent = arc((10.0, -30.0), (4.0, -30.0), (7.0, -30.0), false);
        assert_eq!(corner(first, tangent, round), Err(NoCorner));

        // Chamfers with an arc on either side (even a real corner).
        let a = arc((10.0, -30.0), (20.0, -40.0), (10.0, -40.0), true);
        assert_eq!(corner(first, a, chamfer), Err(ChamferArc));
        let a1 = arc((20.0, -40.0), (10.0, -30.0), (10.0, -40.0), false);
        assert_eq!(corner(a1, back, chamfer), Err(ChamferArc));
        assert!(corner(first, a, round).is_ok());

        // Too big for the first element, or leaving the next none.
        let up = line((10.0, -30.0), (30.0, -30.0));
        assert_eq!(corner(first, up, RefCorner::Round(30.5)), Err(TooBig));
        assert_eq!(corner(first, up, RefCorner::Round(20.0)), Err(TooBig));
        assert!(corner(first, up, RefCorner::Round(19.9)).is_ok());
        assert_eq!(corner(first, up, RefCorner::Chamfer(30.5)), Err(TooBig));
        assert_eq!(corner(first, up, RefCorner::Chamfer(20.0)), Err(TooBig));
        assert!(corner(first, up, RefCorner::Chamfer(19.9)).is_ok());
        // Not a positive size.
        assert_eq!(corner(first, up, RefCorner::Round(0.0)), Err(TooBig));
        assert_eq!(corner(first, up, RefCorner::Chamfer(-1.0)), Err(TooBig));

        // −Z to (10, −20), then a cw arc of R = 3 about (10, −17) leaving
        // along +X: the inside is the centre's side, R − r.
        let first = line((10.0, 0.0), (10.0, -20.0));
        let concave = arc((10.0, -20.0), (13.0, -17.0), (10.0, -17.0), false);
        // r = 3: offset radius 0.
        assert_eq!(corner(first, concave, RefCorner::Round(3.0)), Err(TooBig));
        // r = 2: the offset circle (radius 1 about x = 10) misses x = 12.
        assert_eq!(corner(first, concave, RefCorner::Round(2.0)), Err(TooBig));

        // A first arc of 0.1 rad (length 1): cw about (10, −30), ending at
        // (10, −20) travelling −X; then +Z, a left turn (inside: away from
        // the arc's centre, R + r). The touch point is atan2(r, √(100 + 20r))
        // from the corner: 0.0099 rad for r = 0.1, 0.34 rad for r = 5.
        let up = line((10.0, -20.0), (10.0, 0.0));
        let first_arc = arc(
            (10.0 + 10.0 * 0.1f64.sin(), -30.0 + 10.0 * 0.1f64.cos()),
            (10.0, -20.0),
            (10.0, -30.0),
            false,
        );
        assert!(corner(first_arc, up, RefCorner::Round(0.1)).is_ok());
        assert_eq!(corner(first_arc, up, RefCorner::Round(5.0)), Err(TooBig));
    }

    /// Random corners: every round returned touches both elements
    /// tangentially, in their direction, at distance r from its centre.
    #[test]
    fn random_rounds_are_tangent() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let p = (5.0, -7.0);
        let mut made = 0;
        for _ in 0..20_000 {
            let pick = |rng: &mut ChaCha8Rng| -> (f64, f64) {
                (rng.random_range(-30.0..30.0), rng.random_range(-30.0..30.0))
            };
            let a = pick(&mut rng);
            let b = pick(&mut rng);
            let first = if rng.random_bool(0.5) {
                line(a, p)
            } else {
                let c = a;
                let r = V::of(p).sub(V::of(c)).len();
                let ang: f64 = rng.random_range(0.0..TAU);
                arc(
                    (c.0 + r * ang.sin(), c.1 + r * ang.cos()),
                    p,
                    c,
                    rng.random_bool(0.5),
                )
            };
            let next = if rng.random_bool(0.5) {
                line(p, b)
            } else {
                let c = b;
                let r = V::of(p).sub(V::of(c)).len();
                let ang: f64 = rng.random_range(0.0..TAU);
                arc(
                    p,
                    (c.0 + r * ang.sin(), c.1 + r * ang.cos()),
                    c,
                    rng.random_bool(0.5),
                )
            };
            let r = rng.random_range(0.01..10.0);
            let Ok((a, round, b)) = corner(first, next, RefCorner::Round(r)) else {
                continue;
            };
            made += 1;
            let RefElement::Arc {
                from: k1,
                to: k2,
                centre,
                ..
            } = round
            else {
                panic!("round not an arc")
            };
            let rd = El::of(round, k1).unwrap();
            let e1 = El::of(first, p).unwrap();
            let e2 = El::of(next, p).unwrap();
            for k in [k1, k2] {
                assert!((V::of(k).sub(V::of(centre)).len() - r).abs() < 1e-9);
            }
            let (k1, k2) = (V::of(k1), V::of(k2));
            let d1 = e1.dir_at(k1).unwrap();
            let d2 = e2.dir_at(k2).unwrap();
            assert!(
                d1.sub(rd.dir_at(k1).unwrap()).len() < 1e-7,
                "{first:?} {next:?} {r}"
            );
            assert!(
                d2.sub(rd.dir_at(k2).unwrap()).len() < 1e-7,
                "{first:?} {next:?} {r}"
            );
            if let Some(a) = a {
                assert_eq!(e1.part_before(k1), a);
            }
            assert_eq!(e2.rest_after(k2), b);
        }
        assert!(made > 1000, "{made}");
    }
}

//! Double-precision (f64) reference of the trihedral angle set-up (Lyakun &
//! Yurkevich, "Algorithm of the control program for milling a trihedral angle
//! on NC machines", `docs/calculators.md` §4), built from **vector geometry
//! only**.
//!
//! The production calculator follows the paper's order with spherical
//! trigonometry. This reference does not: it builds the corner as three unit
//! edge vectors `OA`, `OB`, `OC` in 3-D and derives every quantity from dot
//! and cross products, projections and 3×3 linear systems, so that the two
//! can be compared number for number. The closed forms of the paper and of
//! `docs/calculators.md` §4.2 appear only in the unit tests, as cross-checks.
//!
//! All angles are in **degrees** at the API, all lengths in the caller's unit
//! (mm on the machine). Vectors are `[x, y, z]`.
//!
//! # The corner and the paper's quantities, geometrically
//!
//! * Plane angles (ПУ) `AOB`, `BOC`, `COA`: the angles between the edges;
//!   `AOB` is the base face. [`Corner::from_plane_angles`] puts `OA` on `+x`,
//!   `OB` in the `xy` plane with `y > 0` and `OC` with `z > 0` (a
//!   right-handed corner, `OA·(OB×OC) > 0`).
//! * Linear angles (ЛУ) at the edges `AO`, `BO`, `CO`: the dihedral angles,
//!   i.e. the angle between the two perpendiculars to the edge drawn in its two
//!   faces ([`Corner::linear_angles_deg`]).
//! * `φ`: the paper's "slope of the cone inscribed in the trihedral", the
//!   cutter's plan angle. The inscribed cone touches the three **faces**; its
//!   axis `O'O` makes the same angle `φ` with each face, and `φ` is the cone's
//!   half-angle ([`Corner::phi_deg`]). This is *not* the cone whose axis makes
//!   equal angles with the three **edges** (the circumscribed cone,
//!   [`Corner::circumcone_axis`]); for a cube corner the two axes coincide,
//!   but the axis is 35.26439° from each face and 54.73561° from each edge,
//!   so the paper's `φ = 35.26439°` is the face angle of the inscribed cone.
//! * `σ_a`, `σ_b`, `σ_c`: the inscribed cone touches face `AOB` along the
//!   generator `OD` (`D` on `AB` in the paper's Fig. 1); `σ_a` is the angle
//!   `DOA` between edge `OA` and the tangency generator of either face at `OA`
//!   (both are equal), and likewise `σ_b`, `σ_c` ([`Corner::sigma_deg`]).
//! * The cross-section: when every edge rises from the vertex along the axis
//!   ([`Corner::edges_rise`]: each `σ_i < 90°`), a plane perpendicular to
//!   the axis cuts the corner in the triangle `ABC` of the paper's rows; its
//!   incircle has centre `O'` on the axis and radius `z·tan φ` at height `z`
//!   above the vertex. `α_i` is **half** the angle of that triangle at vertex
//!   `i` ([`Corner::alpha_deg`]); the central angles (ЦУ) `AO'B`, `BO'C`,
//!   `CO'A` are the angles at `O'` ([`Corner::central_angles_deg`]). Both are
//!   computed from the edges as seen along the axis (their projections
//!   across it), which extends them to corners with a descending edge
//!   (`α < 0` there; the central angles still sum to 360°).
//! * The paper's working frame ([`Corner::paper_frame`]): `Z` along the axis
//!   `O'O` (from the vertex into the corner), the tangency generator `OD` of
//!   the base face projecting onto `−X` (so the side `AB` of every row is the
//!   line `x = −r`), and `Y` along `AB` from `A` to `B`, i.e. `y_A < 0 < y_B`
//!   as the paper's row formulas have it. The vertex is the origin.
//! * The table set-up ([`Corner::table_setup`]): the base face lies on the
//!   table (`XY`) with `OC` up, `OA` at `E` from the `X` axis, the face in
//!   quadrant `k_v`; the rotation `P` (about `Z`, positive from `+X` to `+Y`)
//!   brings the horizontal projection of the axis onto `−X`, then the tilt
//!   (a rotation in the `XZ` plane, positive from `+X` to `+Z`) brings the
//!   axis to `+Z`, the spindle. The tilt comes out as `−(90° − φ)`, the
//!   paper's sign.
//!
//! # Findings recorded by the tests
//!
//! * With exact `σ_i`, the paper's `φ = arcsin r` (inradius of the triangle
//!   with tangent lengths `tan σ_i`) and its linear-angle formula (4) are exact;
//!   only its proportional `σ_i` (eq. 1–3) are approximate. With a
//!   descending edge (`σ_i > 90°`, `tan σ_i < 0`, `α_i < 0`) both come out
//!   negative, exact in magnitude; the paper's sixth test corner
//!   (151°, 2°, 150°) is one (`σ_a = 149.5°`).
//! * The paper's row formulas hold in [`Corner::paper_frame`] with `y_b > 0`
//!   (м.2's sign; м.1's `Y_BO = −r/tg α_b` is a slip) and with
//!   `x_c = −r·(sin γ_a − sin γ_b)/sin(γ_a − γ_b)` (м.1's sign). When the
//!   edges rise that value is always **positive**: `C` is the vertex opposite
//!   the side `x = −r`; м.2's unsigned `x_c` is the slip.
//! * After the paper's `P` and tilt, the machine coordinates equal the paper
//!   frame for `k_v = 2, 4` and are mirrored in `Y` for `k_v = 1, 3` (there the
//!   corner is the other hand: seen from the cutter, `A → B → C` turns the
//!   other way).
//! * The paper's check of `P` and of the tilt (indicator on face "AOC", moving
//!   along `Y`, `ΔX/ΔZ = tg φ`) holds for the **base face `AOB`**, the face
//!   whose tangency generator was put on `−X`.

/// A 3-D vector `[x, y, z]`.
pub type V3 = [f64; 3];

/// Index of edge `OA` (vertex `A`) in the arrays of this module.
pub const A: usize = 0;
/// Index of edge `OB` (vertex `B`).
pub const B: usize = 1;
/// Index of edge `OC` (vertex `C`).
pub const C: usize = 2;

/// Index of face `AOB` (the base) in the face arrays of this module.
pub const FACE_AOB: usize = 0;
/// Index of face `BOC`.
pub const FACE_BOC: usize = 1;
/// Index of face `COA`.
pub const FACE_COA: usize = 2;

fn dot(u: V3, v: V3) -> f64 {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

fn cross(u: V3, v: V3) -> V3 {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

fn add(u: V3, v: V3) -> V3 {
    [u[0] + v[0], u[1] + v[1], u[2] + v[2]]
}

fn sub(u: V3, v: V3) -> V3 {
    [u[0] - v[0], u[1] - v[1], u[2] - v[2]]
}

fn scale(k: f64, u: V3) -> V3 {
    [k * u[0], k * u[1], k * u[2]]
}

fn norm(u: V3) -> f64 {
    dot(u, u).sqrt()
}

fn normalize(u: V3) -> V3 {
    scale(1.0 / norm(u), u)
}

/// Component of `u` perpendicular to the unit vector `e`.
fn reject(u: V3, e: V3) -> V3 {
    sub(u, scale(dot(u, e), e))
}

/// Angle between two non-zero vectors, radians in `[0, π]`, by
/// `atan2(|u×v|, u·v)` (accurate near 0 and π, unlike `acos`).
fn angle(u: V3, v: V3) -> f64 {
    norm(cross(u, v)).atan2(dot(u, v))
}

/// Signed triple product `u·(v×w)`.
fn triple(u: V3, v: V3, w: V3) -> f64 {
    dot(u, cross(v, w))
}

/// Solution of the 3×3 system whose rows are `r[0..3]` and right-hand side
/// `b` (Cramer's rule with cross products); `None` when singular.
fn solve3(r: [V3; 3], b: V3) -> Option<V3> {
    let det = triple(r[0], r[1], r[2]);
    if det.abs() < 1e-14 {
        return None;
    }
    let x = add(
        add(
            scale(b[0], cross(r[1], r[2])),
            scale(b[1], cross(r[2], r[0])),
        ),
        scale(b[2], cross(r[0], r[1])),
    );
    Some(scale(1.0 / det, x))
}

/// Rotation about `+Z` by `deg` (positive from `+X` towards `+Y`).
fn rot_z(deg: f64, p: V3) -> V3 {
    let (s, c) = deg.to_radians().sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]]
}

/// Rotation in the `XZ` plane by `deg` (positive from `+X` towards `+Z`), `Y`
/// unchanged.
fn rot_xz(deg: f64, p: V3) -> V3 {
    let (s, c) = deg.to_radians().sin_cos();
    [c * p[0] - s * p[2], p[1], s * p[0] + c * p[2]]
}

/// `deg` wrapped into `(−180°, 180°]`.
fn wrap180(deg: f64) -> f64 {
    let w = (deg + 180.0).rem_euclid(360.0) - 180.0;
    if w <= -180.0 {
        w + 360.0
    } else {
        w
    }
}

/// A trihedral corner: three unit edge vectors from the vertex `O`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// Unit vectors along `OA`, `OB`, `OC` (indices [`A`], [`B`], [`C`]).
    pub edges: [V3; 3],
}

/// An orthonormal working frame: unit axes `x`, `y`, `z` expressed in the
/// corner's coordinates; a point `p` has the frame coordinates
/// `(p·x, p·y, p·z)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Unit `X` axis.
    pub x: V3,
    /// Unit `Y` axis.
    pub y: V3,
    /// Unit `Z` axis.
    pub z: V3,
}

impl Frame {
    /// Coordinates of the point `p` (corner coordinates) in this frame.
    pub fn coords(&self, p: V3) -> V3 {
        [dot(p, self.x), dot(p, self.y), dot(p, self.z)]
    }

    /// Whether `y = z × x` (a right-handed frame); the paper frame is
    /// left-handed for a right-handed corner.
    pub fn right_handed(&self) -> bool {
        triple(self.x, self.y, self.z) > 0.0
    }
}

/// The corner placed on the tilt-rotary table and set up for milling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableSetup {
    /// Quadrant `k_v` (1–4) of the `XY` plane holding the base face.
    pub kv: u8,
    /// `E`, degrees: the angle of ray `OA` from the `X` axis line (from `+X`
    /// for `k_v = 1, 4`, from `−X` for `k_v = 2, 3`), positive
    /// counter-clockwise.
    pub e_deg: f64,
    /// Unit edges `OA`, `OB`, `OC` as placed on the table before any motion:
    /// base face `AOB` in the `XY` plane, `OC` with `z > 0`.
    pub edges_on_table: [V3; 3],
    /// The inscribed cone's unit axis as placed on the table.
    pub axis_on_table: V3,
    /// `P`, degrees in `(−180°, 180°]`: the table rotation about `Z`
    /// (positive from `+X` to `+Y`) that turns the axis' horizontal projection
    /// onto `−X`.
    pub p_deg: f64,
    /// `P⁺`, degrees in `[0°, 360°)`: the same rotation for a table that only
    /// reads positive angles (`P⁺ = 0` for `P = 0`).
    pub p_positive_deg: f64,
    /// The tilt, degrees: the rotation in the `XZ` plane (positive from `+X`
    /// to `+Z`) that then brings the axis onto `+Z`; equals `−(90° − φ)`.
    pub tilt_deg: f64,
    /// Unit edges after the rotation and the tilt (machine axes, vertex at
    /// the origin).
    pub edges_machine: [V3; 3],
    /// The axis after the rotation and the tilt (`[0, 0, 1]` up to rounding).
    pub axis_machine: V3,
}

impl TableSetup {
    /// Machine coordinates of the point at `length` along edge `edge` from
    /// the vertex, after the set-up (vertex at the origin).
    pub fn edge_point(&self, edge: usize, length: f64) -> V3 {
        scale(length, self.edges_machine[edge])
    }
}

impl Corner {
    /// The corner with the given plane angles (degrees), base face `AOB`
    /// first: `OA = [1, 0, 0]`, `OB = [cos AOB, sin AOB, 0]`, and `OC` the
    /// unit vector with `OC·OA = cos COA`, `OC·OB = cos BOC`, `z > 0`.
    ///
    /// `None` unless each angle is in `(0°, 180°)`, their sum is below 360°
    /// and each is below the sum of the other two (strictly), i.e. unless
    /// `OC` exists off the base plane.
    pub fn from_plane_angles(aob_deg: f64, boc_deg: f64, coa_deg: f64) -> Option<Corner> {
        let all = [aob_deg, boc_deg, coa_deg];
        if all.iter().any(|&d| !(d > 0.0 && d < 180.0)) {
            return None;
        }
        if aob_deg + boc_deg + coa_deg >= 360.0
            || aob_deg >= boc_deg + coa_deg
            || boc_deg >= coa_deg + aob_deg
            || coa_deg >= aob_deg + boc_deg
        {
            return None;
        }
        let (s_ab, c_ab) = aob_deg.to_radians().sin_cos();
        let oa = [1.0, 0.0, 0.0];
        let ob = [c_ab, s_ab, 0.0];
        // OC·OA = x = cos COA; OC·OB = x·cos AOB + y·sin AOB = cos BOC.
        let x = coa_deg.to_radians().cos();
        let y = (boc_deg.to_radians().cos() - x * c_ab) / s_ab;
        let zz = 1.0 - x * x - y * y;
        if zz <= 0.0 {
            return None;
        }
        Some(Corner {
            edges: [oa, ob, [x, y, zz.sqrt()]],
        })
    }

    /// The corner spanned by three edge vectors (any lengths, either hand);
    /// `None` if they are (nearly) coplanar or one is zero.
    pub fn from_edges(oa: V3, ob: V3, oc: V3) -> Option<Corner> {
        if [oa, ob, oc]
            .iter()
            .any(|&e| !norm(e).is_finite() || norm(e) == 0.0)
        {
            return None;
        }
        let edges = [normalize(oa), normalize(ob), normalize(oc)];
        if triple(edges[0], edges[1], edges[2]).abs() < 1e-12 {
            return None;
        }
        Some(Corner { edges })
    }

    /// The same corner placed as [`Corner::from_plane_angles`] places it
    /// (`OA` on `+x`, `OB` in `xy` with `y > 0`, `OC` with `z > 0`), by
    /// expressing the edges in the frame `OA`, `OB ⟂ OA`, normal, mirrored if
    /// the corner is left-handed.
    pub fn standardized(&self) -> Corner {
        let [oa, ob, oc] = self.edges;
        let u1 = oa;
        let u2 = normalize(reject(ob, oa));
        let mut u3 = cross(u1, u2);
        if dot(oc, u3) < 0.0 {
            u3 = scale(-1.0, u3);
        }
        let local = |e: V3| [dot(e, u1), dot(e, u2), dot(e, u3)];
        Corner {
            edges: [local(oa), local(ob), local(oc)],
        }
    }

    /// `true` if `OA·(OB×OC) > 0`.
    pub fn right_handed(&self) -> bool {
        triple(self.edges[0], self.edges[1], self.edges[2]) > 0.0
    }

    /// Plane angles `[AOB, BOC, COA]`, degrees: the angles between the edges.
    pub fn plane_angles_deg(&self) -> [f64; 3] {
        let [oa, ob, oc] = self.edges;
        [
            angle(oa, ob).to_degrees(),
            angle(ob, oc).to_degrees(),
            angle(oc, oa).to_degrees(),
        ]
    }

    /// Unit normals of the faces `[AOB, BOC, COA]`, each pointing into the
    /// corner (towards the edge not in that face).
    pub fn inward_normals(&self) -> [V3; 3] {
        let [oa, ob, oc] = self.edges;
        let inward = |u: V3, v: V3, w: V3| {
            let n = normalize(cross(u, v));
            if dot(n, w) < 0.0 {
                scale(-1.0, n)
            } else {
                n
            }
        };
        [inward(oa, ob, oc), inward(ob, oc, oa), inward(oc, oa, ob)]
    }

    /// Linear angles (ЛУ) of the dihedral angles at the edges
    /// `[AO, BO, CO]`, degrees: at edge `e` between faces holding the other
    /// edges `f`, `g`, the angle between `f` and `g` with their components
    /// along `e` removed (the two perpendiculars to the edge in its faces).
    pub fn linear_angles_deg(&self) -> [f64; 3] {
        let e = self.edges;
        let at = |i: usize, j: usize, k: usize| {
            angle(reject(e[j], e[i]), reject(e[k], e[i])).to_degrees()
        };
        [at(A, B, C), at(B, C, A), at(C, A, B)]
    }

    /// Unit axis `O'O` of the inscribed cone (from the vertex into the
    /// corner): the solution of `n_AOB·a = n_BOC·a = n_COA·a = 1` (inward unit
    /// face normals), normalized — the direction at the same angle from the
    /// three faces.
    pub fn axis(&self) -> V3 {
        let n = self.inward_normals();
        normalize(solve3(n, [1.0, 1.0, 1.0]).expect("faces of a corner are independent"))
    }

    /// `φ`, degrees: the angle between the axis and each face, the
    /// inscribed cone's half-angle (the paper's cutter plan angle). Taken
    /// from face `AOB`; [`Corner::axis_face_angles_deg`] gives all three.
    pub fn phi_deg(&self) -> f64 {
        self.axis_face_angles_deg()[FACE_AOB]
    }

    /// Angles between the axis and the faces `[AOB, BOC, COA]`, degrees:
    /// `atan2(a·n, |a − (a·n)n|)`; all three equal `φ`.
    pub fn axis_face_angles_deg(&self) -> [f64; 3] {
        let a = self.axis();
        self.inward_normals()
            .map(|n| dot(a, n).atan2(norm(reject(a, n))).to_degrees())
    }

    /// Angles between the axis and the edges `[OA, OB, OC]`, degrees.
    pub fn axis_edge_angles_deg(&self) -> [f64; 3] {
        let a = self.axis();
        self.edges.map(|e| angle(a, e).to_degrees())
    }

    /// Unit axis of the circumscribed cone, the direction at the same angle
    /// from the three **edges**: the solution of `OA·a = OB·a = OC·a = 1`,
    /// normalized. Not the paper's axis unless the corner is symmetric.
    pub fn circumcone_axis(&self) -> V3 {
        normalize(solve3(self.edges, [1.0, 1.0, 1.0]).expect("edges of a corner are independent"))
    }

    /// Half-angle of the circumscribed cone, degrees: the angle between
    /// [`Corner::circumcone_axis`] and each edge (54.73561° for a cube
    /// corner).
    pub fn circumcone_half_angle_deg(&self) -> f64 {
        angle(self.circumcone_axis(), self.edges[A]).to_degrees()
    }

    /// Unit tangency generators of the inscribed cone in the faces
    /// `[AOB, BOC, COA]`: the axis projected onto each face (the paper's `OD`
    /// for the base face).
    pub fn tangency_generators(&self) -> [V3; 3] {
        let a = self.axis();
        self.inward_normals().map(|n| normalize(reject(a, n)))
    }

    /// `[σ_a, σ_b, σ_c]`, degrees: the angle between each edge and the
    /// tangency generator of a face holding it (`σ_a`, `σ_b` from face
    /// `AOB`, `σ_c` from face `BOC`).
    pub fn sigma_deg(&self) -> [f64; 3] {
        let t = self.tangency_generators();
        let e = self.edges;
        [
            angle(e[A], t[FACE_AOB]).to_degrees(),
            angle(e[B], t[FACE_AOB]).to_degrees(),
            angle(e[C], t[FACE_BOC]).to_degrees(),
        ]
    }

    /// The points where the lines of the edges meet the cross-section at
    /// unit height (the plane `p·axis = 1`): each edge scaled by
    /// `1/(e·axis)` (a negative scale for an edge that descends, see
    /// [`Corner::edges_rise`]).
    fn section_unit(&self) -> [V3; 3] {
        let a = self.axis();
        self.edges.map(|e| scale(1.0 / dot(e, a), e))
    }

    /// Whether every edge rises from the vertex along the axis
    /// (`e·axis > 0`, i.e. every `σ_i < 90°`, i.e. each plane angle exceeds
    /// the sum of the other two minus 180°). Only then does a plane
    /// perpendicular to the axis cut the corner in a bounded triangle `ABC`,
    /// so that the paper's rows, edge points and `α_i` as half-angles of
    /// that triangle make sense; otherwise the corner undercuts the cutter
    /// axis. (The paper's input rule "the smallest plane angle above a third
    /// of the sum of the other two" implies it.)
    pub fn edges_rise(&self) -> bool {
        let a = self.axis();
        self.edges.iter().all(|&e| dot(e, a) > 0.0)
    }

    /// Projections onto the plane perpendicular to the axis (the edges'
    /// directions as seen along the cutter axis).
    fn across_axis(&self, v: V3) -> V3 {
        reject(v, self.axis())
    }

    /// `[α_a, α_b, α_c]`, degrees: `90°` minus the angle, seen along the
    /// axis, between the edge and the tangency generator of a face holding
    /// it (`α_a`, `α_b` from face `AOB`, `α_c` from face `BOC`). When every
    /// edge rises this is half the angle of the cross-section triangle `ABC`
    /// at that vertex (the right triangle `O'DA`: the angle at `O'` is
    /// `90° − α_a`); an edge that descends gets a negative `α`. They sum to
    /// 90°.
    pub fn alpha_deg(&self) -> [f64; 3] {
        let t = self.tangency_generators();
        let e = self.edges;
        let at = |i: usize, face: usize| {
            90.0 - angle(self.across_axis(e[i]), self.across_axis(t[face])).to_degrees()
        };
        [at(A, FACE_AOB), at(B, FACE_AOB), at(C, FACE_BOC)]
    }

    /// Central angles (ЦУ) `[AO'B, BO'C, CO'A]`, degrees: the angles between
    /// the edges seen along the axis (their projections onto a plane
    /// perpendicular to it). When every edge rises these are the angles at
    /// the incircle centre `O'` of the cross-section between the rays to its
    /// vertices. The axis lies inside the corner, so they always sum to 360°.
    pub fn central_angles_deg(&self) -> [f64; 3] {
        let p = self.edges.map(|e| self.across_axis(e));
        let at = |i: usize, j: usize| angle(p[i], p[j]).to_degrees();
        [at(A, B), at(B, C), at(C, A)]
    }

    /// The paper's working frame: `z` the axis, `x` opposite the base face's
    /// tangency generator `OD` projected across the axis (so that `OD`
    /// projects onto `−X`), `y = ±z×x` chosen so that edge `OA` has `y < 0`
    /// (`AB` runs along `+Y`). Left-handed for a right-handed corner.
    pub fn paper_frame(&self) -> Frame {
        let z = self.axis();
        let t = self.tangency_generators()[FACE_AOB];
        let x = scale(-1.0, normalize(reject(t, z)));
        let mut y = cross(z, x);
        if dot(self.edges[A], y) > 0.0 {
            y = scale(-1.0, y);
        }
        Frame { x, y, z }
    }

    /// Paper-frame coordinates `[x, y, z]` of the point at `length` along
    /// edge `edge` from the vertex (the paper's `X_AO, Y_AO, Z_AO` etc. for
    /// `L_A`, `L_B`, `L_C`).
    pub fn edge_point(&self, edge: usize, length: f64) -> V3 {
        self.paper_frame().coords(scale(length, self.edges[edge]))
    }

    /// Height above the vertex along the axis of the point at `length` along
    /// edge `edge` (the paper's `Z_AO`, `Z_BO`, `Z_CO`).
    pub fn edge_height(&self, edge: usize, length: f64) -> f64 {
        length * dot(self.edges[edge], self.axis())
    }

    /// The row at height `z` above the vertex: paper-frame `[x, y]` of the
    /// points where the plane `Z = z` meets `OA`, `OB`, `OC` (the paper's
    /// `(x_a, y_a)_n`, `(x_b, y_b)_n`, `(x_c, y_c)_n` for `z = Z_n`). For an
    /// edge that descends ([`Corner::edges_rise`] false) the point is on the
    /// edge's line behind the vertex.
    pub fn row(&self, z: f64) -> [[f64; 2]; 3] {
        let f = self.paper_frame();
        self.section_unit().map(|p| {
            let q = f.coords(scale(z, p));
            [q[0], q[1]]
        })
    }

    /// Incircle radius of the row at height `z`: the distance in that plane
    /// from the axis to each face (`z·tan φ`, computed as the distance from
    /// the axis point to the base face's trace).
    pub fn row_inradius(&self, z: f64) -> f64 {
        let a = self.axis();
        let n = self.inward_normals()[FACE_AOB];
        // Point z·a on the axis; its distance to the plane of face AOB, taken
        // within the section plane: divide by the cosine of the angle between
        // the face normal and the section plane.
        let d = dot(scale(z, a), n);
        d / norm(reject(n, a))
    }

    /// Offset from a point of edge `edge` to the fillet of radius `r_f` left
    /// along it, in paper-frame coordinates: length `r_f·(1/sin(ЛУ/2) − 1)`
    /// (edge to the fillet's nearest line, in the bisecting plane of the
    /// dihedral), direction perpendicular to the edge in that plane, into the
    /// corner. Its `z` component is the height the fillet adds there.
    pub fn fillet_offset(&self, edge: usize, r_f: f64) -> V3 {
        let e = self.edges;
        let (j, k) = ((edge + 1) % 3, (edge + 2) % 3);
        let u = normalize(add(
            normalize(reject(e[j], e[edge])),
            normalize(reject(e[k], e[edge])),
        ));
        let half = 0.5 * self.linear_angles_deg()[edge].to_radians();
        let d = r_f * (1.0 / half.sin() - 1.0);
        self.paper_frame().coords(scale(d, u))
    }

    /// The corner placed on the table and set up (see the module docs).
    ///
    /// Placement: base face `AOB` on the `XY` plane, `OC` up. For `k_v = 1`,
    /// `3` the face runs counter-clockwise from `OA` (seen from `+Z`), for
    /// `k_v = 2, 4` clockwise — the two hands of a corner with the same plane
    /// angles. `OA` points at `E` (`k_v = 1, 4`) or `180° + E` (`k_v = 2, 3`).
    /// Then `P` and the tilt are found from the axis vector, not from a
    /// formula. `None` unless `k_v` is 1–4.
    pub fn table_setup(&self, kv: u8, e_deg: f64) -> Option<TableSetup> {
        let (mirror, base_deg) = match kv {
            1 => (false, 0.0),
            2 => (true, 180.0),
            3 => (false, 180.0),
            4 => (true, 0.0),
            _ => return None,
        };
        let std = self.standardized();
        let place = |e: V3| {
            let local = if mirror { [e[0], -e[1], e[2]] } else { e };
            rot_z(base_deg + e_deg, local)
        };
        let edges_on_table = std.edges.map(place);
        let placed = Corner {
            edges: edges_on_table,
        };
        let axis_on_table = placed.axis();
        let psi = axis_on_table[1].atan2(axis_on_table[0]).to_degrees();
        let p_deg = wrap180(180.0 - psi);
        let after_p = rot_z(p_deg, axis_on_table);
        let theta = after_p[2].atan2(after_p[0]).to_degrees();
        let tilt_deg = 90.0 - theta;
        let motion = |v: V3| rot_xz(tilt_deg, rot_z(p_deg, v));
        Some(TableSetup {
            kv,
            e_deg,
            edges_on_table,
            axis_on_table,
            p_deg,
            p_positive_deg: p_deg.rem_euclid(360.0),
            tilt_deg,
            edges_machine: edges_on_table.map(motion),
            axis_machine: motion(axis_on_table),
        })
    }

    /// The corner from two plane angles and the linear angle at their common
    /// edge `OB`: `AOB`, `BOC` and `ЛУ_BO` (degrees). Built with `OB` on
    /// `+x`, `OA` in `xy`, `OC = cos BOC·OB + sin BOC·(cos ЛУ·v + sin ЛУ·z)`,
    /// `v` the unit perpendicular to `OB` in face `AOB` towards `OA`; returned
    /// [`Corner::standardized`]. The third plane angle is
    /// `plane_angles_deg()[2]` (`COA`). `None` unless all three are in
    /// `(0°, 180°)`.
    pub fn from_two_plane_angles_and_linear(
        aob_deg: f64,
        boc_deg: f64,
        lin_bo_deg: f64,
    ) -> Option<Corner> {
        if [aob_deg, boc_deg, lin_bo_deg]
            .iter()
            .any(|&d| !(d > 0.0 && d < 180.0))
        {
            return None;
        }
        let ob = [1.0, 0.0, 0.0];
        let (s, c) = aob_deg.to_radians().sin_cos();
        let oa = [c, s, 0.0];
        let v = normalize(reject(oa, ob));
        let w = cross(ob, v);
        let (sl, cl) = lin_bo_deg.to_radians().sin_cos();
        let (sb, cb) = boc_deg.to_radians().sin_cos();
        let oc = add(scale(cb, ob), scale(sb, add(scale(cl, v), scale(sl, w))));
        Corner::from_edges(oa, ob, oc).map(|k| k.standardized())
    }

    /// The corner from the base plane angle `AOB` and the linear angles at
    /// its edges `ЛУ_AO`, `ЛУ_BO` (degrees): face `COA` is the plane through
    /// `OA` turned by `ЛУ_AO` from the base, face `BOC` the plane through `OB`
    /// turned by `ЛУ_BO`, and `OC` their line of intersection (cross product
    /// of their normals) on the side of both turned half-planes. `None` unless
    /// all three are in `(0°, 180°)`.
    pub fn from_plane_angle_and_two_linear(
        aob_deg: f64,
        lin_ao_deg: f64,
        lin_bo_deg: f64,
    ) -> Option<Corner> {
        if [aob_deg, lin_ao_deg, lin_bo_deg]
            .iter()
            .any(|&d| !(d > 0.0 && d < 180.0))
        {
            return None;
        }
        let z = [0.0, 0.0, 1.0];
        let oa = [1.0, 0.0, 0.0];
        let (s, c) = aob_deg.to_radians().sin_cos();
        let ob = [c, s, 0.0];
        // Half-plane of face COA: perpendicular to OA, turned from the base
        // face's perpendicular (towards OB) by ЛУ_AO.
        let turn = |edge: V3, other: V3, lin: f64| {
            let v = normalize(reject(other, edge));
            let (sl, cl) = lin.to_radians().sin_cos();
            add(scale(cl, v), scale(sl, z))
        };
        let wa = turn(oa, ob, lin_ao_deg);
        let wb = turn(ob, oa, lin_bo_deg);
        let mut oc = normalize(cross(cross(oa, wa), cross(ob, wb)));
        if dot(oc, z) < 0.0 {
            oc = scale(-1.0, oc);
        }
        // OC must lie on the turned half-plane of each face, not opposite.
        if dot(reject(oc, oa), wa) <= 0.0 || dot(reject(oc, ob), wb) <= 0.0 {
            return None;
        }
        Corner::from_edges(oa, ob, oc).map(|k| k.standardized())
    }

    /// The corner from its three linear angles `ЛУ_AO`, `ЛУ_BO`, `ЛУ_CO`
    /// (degrees), through the polar corner: the inward face normals
    /// `n_AOB`, `n_BOC`, `n_COA` form a corner whose plane angles are
    /// `180° − ЛУ` of the edge the two faces share; the edges are then the
    /// normals of the polar faces (`OB ∥ n_AOB × n_BOC`, …), each on the inward
    /// side of the face not holding it. `None` if the polar corner does not
    /// exist: each linear angle must be in `(0°, 180°)`, their sum above 180°
    /// and `ЛУ_i + ЛУ_j < 180° + ЛУ_k` for every `k`.
    pub fn from_linear_angles(lin_ao_deg: f64, lin_bo_deg: f64, lin_co_deg: f64) -> Option<Corner> {
        let polar =
            Corner::from_plane_angles(180.0 - lin_bo_deg, 180.0 - lin_co_deg, 180.0 - lin_ao_deg)?;
        let [q_aob, q_boc, q_coa] = polar.edges;
        let side = |v: V3, toward: V3| {
            let v = normalize(v);
            if dot(v, toward) < 0.0 {
                scale(-1.0, v)
            } else {
                v
            }
        };
        let oa = side(cross(q_coa, q_aob), q_boc);
        let ob = side(cross(q_aob, q_boc), q_coa);
        let oc = side(cross(q_boc, q_coa), q_aob);
        Corner::from_edges(oa, ob, oc).map(|k| k.standardized())
    }

    /// The corners with plane angles `AOB`, `BOC` and the inscribed cone's
    /// half-angle `φ` (degrees): every `COA` in the open range where the
    /// corner exists at which the vector `φ` ([`Corner::phi_deg`]) equals
    /// `phi_deg`, found by scanning that range in 4096 steps for sign changes
    /// and bisecting each to full precision. `φ` is not monotonic in `COA`
    /// in general, so there may be none, one or two solutions (a root closer
    /// than one scan step to another or to a maximum of `φ` can be missed).
    pub fn from_two_plane_angles_and_phi(aob_deg: f64, boc_deg: f64, phi_deg: f64) -> Vec<Corner> {
        let lo = (aob_deg - boc_deg).abs();
        let hi = (aob_deg + boc_deg)
            .min(360.0 - aob_deg - boc_deg)
            .min(180.0);
        let mut out = Vec::new();
        if hi.is_nan() || lo.is_nan() || hi <= lo {
            return out;
        }
        let f = |coa: f64| {
            Corner::from_plane_angles(aob_deg, boc_deg, coa).map(|k| k.phi_deg() - phi_deg)
        };
        const STEPS: usize = 4096;
        let at = |i: usize| lo + (hi - lo) * i as f64 / STEPS as f64;
        let mut prev: Option<(f64, f64)> = None;
        for i in 1..STEPS {
            let x = at(i);
            let Some(fx) = f(x) else {
                prev = None;
                continue;
            };
            if fx == 0.0 {
                out.extend(Corner::from_plane_angles(aob_deg, boc_deg, x));
            } else if let Some((px, pf)) = prev {
                if pf != 0.0 && (pf < 0.0) != (fx < 0.0) {
                    let (mut a, mut b, mut fa) = (px, x, pf);
                    for _ in 0..200 {
                        let m = 0.5 * (a + b);
                        if m <= a || m >= b {
                            break;
                        }
                        let fm = f(m).expect("inside the range");
                        if (fm < 0.0) == (fa < 0.0) {
                            a = m;
                            fa = fm;
                        } else {
                            b = m;
                        }
                    }
                    out.extend(Corner::from_plane_angles(aob_deg, boc_deg, 0.5 * (a + b)));
                }
            }
            prev = Some((x, fx));
        }
        out
    }
}

/// The third plane angle `COA`, degrees, of the corner with plane angles
/// `AOB`, `BOC` and the linear angle `ЛУ_BO` at their common edge (see
/// [`Corner::from_two_plane_angles_and_linear`]).
pub fn third_plane_angle_deg(aob_deg: f64, boc_deg: f64, lin_bo_deg: f64) -> Option<f64> {
    Corner::from_two_plane_angles_and_linear(aob_deg, boc_deg, lin_bo_deg)
        .map(|k| k.plane_angles_deg()[2])
}

/// Shift `(a, c)` of the part origin caused by tilting the table by
/// `tilt_deg` (rotation in the `XZ` plane, positive from `+X` to `+Z`), the
/// part origin being on the table surface at the rotary axis and the tilt
/// axis (parallel to `Y`) a distance `l` from the rotary axis towards `−X`
/// and `m` below the table surface: the origin moves to `T + R(−T)`,
/// `T = (−l, −m)`, and `(a, c) = (−Δx, Δz)` (the paper's eq. 6 with
/// `β = tilt`).
pub fn tilt_origin_shift(l: f64, m: f64, tilt_deg: f64) -> (f64, f64) {
    let t = [-l, 0.0, -m];
    let moved = add(t, rot_xz(tilt_deg, scale(-1.0, t)));
    (-moved[0], moved[2])
}

/// The table parameters `(L, m)` from the origin shift `(a, c)` measured at
/// the tilt `tilt_deg`: [`tilt_origin_shift`] is linear in `(L, m)`, so its
/// two columns (shifts for `(1, 0)` and `(0, 1)`) give a 2×2 system solved by
/// Cramer's rule. `None` at a tilt where it is singular (0°).
pub fn table_params_from_shift(a: f64, c: f64, tilt_deg: f64) -> Option<(f64, f64)> {
    let (a1, c1) = tilt_origin_shift(1.0, 0.0, tilt_deg);
    let (a2, c2) = tilt_origin_shift(0.0, 1.0, tilt_deg);
    let det = a1 * c2 - a2 * c1;
    if det.abs() < 1e-12 {
        return None;
    }
    Some(((a * c2 - a2 * c) / det, (a1 * c - a * c1) / det))
}

/// Machine position of a point `p` given in part coordinates (origin on the
/// table surface at the rotary axis) after the table rotation `p_deg` about
/// `Z` and the tilt `tilt_deg` about the tilt axis placed as in
/// [`tilt_origin_shift`] (`l` towards `−X`, `m` below the surface); the
/// machine origin is the part origin before any motion.
pub fn machine_position(p: V3, p_deg: f64, tilt_deg: f64, l: f64, m: f64) -> V3 {
    let t = [-l, 0.0, -m];
    let rotated = rot_z(p_deg, p);
    add(t, rot_xz(tilt_deg, sub(rotated, t)))
}

// The tests walk parallel per-edge arrays by the edge index.
#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Radians in one degree.
    const DEG: f64 = PI / 180.0;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
        assert!(close(a, b, tol), "{what}: {a} vs {b} (tol {tol})");
    }

    fn assert_v3(a: V3, b: V3, tol: f64, what: &str) {
        for i in 0..3 {
            assert!(close(a[i], b[i], tol), "{what}[{i}]: {a:?} vs {b:?}");
        }
    }

    /// Random valid plane angles, each at least `min` degrees and the corner
    /// at least `min` degrees away from every degenerate boundary.
    fn random_corner(rng: &mut ChaCha8Rng, min: f64) -> [f64; 3] {
        loop {
            let p = [
                rng.random_range(min..180.0 - min),
                rng.random_range(min..180.0 - min),
                rng.random_range(min..180.0 - min),
            ];
            let s = p[0] + p[1] + p[2];
            if s < 360.0 - min
                && p[0] < p[1] + p[2] - min
                && p[1] < p[2] + p[0] - min
                && p[2] < p[0] + p[1] - min
            {
                return p;
            }
        }
    }

    /// Spherical-trig closed forms (`docs/calculators.md` §4.2), for cross-checks only.
    fn spec_phi_sigma_alpha(p: [f64; 3]) -> (f64, [f64; 3], [f64; 3]) {
        let [aob, boc, coa] = p;
        let s = 0.5 * (aob + boc + coa);
        let sig = [s - boc, s - coa, s - aob];
        let sr = sig.map(|d| (d * DEG).sin());
        let tan2 = sr[0] * sr[1] * sr[2] / (s * DEG).sin();
        let phi = tan2.sqrt().atan() / DEG;
        let alpha = sig.map(|d| ((phi * DEG).sin() / (d * DEG).tan()).atan() / DEG);
        (phi, sig, alpha)
    }

    /// The paper's six test corners (plane angles, "Таблица тестирования").
    const PAPER_TESTS: [[f64; 3]; 6] = [
        [90.0, 90.0, 90.0],
        [115.0, 115.0, 115.0],
        [3.0, 3.0, 3.0],
        [2.0, 3.0, 4.0],
        [121.0, 118.0, 120.0],
        [151.0, 2.0, 150.0],
    ];

    #[test]
    fn cube_corner() {
        let k = Corner::from_plane_angles(90.0, 90.0, 90.0).unwrap();
        assert!(k.right_handed());
        assert_v3(k.edges[C], [0.0, 0.0, 1.0], 1e-15, "OC");
        let phi = k.phi_deg();
        assert_close(phi, 35.26439, 1e-5, "phi");
        assert_close(phi, (0.5f64).sqrt().atan() / DEG, 1e-12, "phi exact");
        for f in k.axis_face_angles_deg() {
            assert_close(f, phi, 1e-12, "axis-face");
        }
        for l in k.linear_angles_deg() {
            assert_close(l, 90.0, 1e-12, "dihedral");
        }
        for s in k.sigma_deg() {
            assert_close(s, 45.0, 1e-12, "sigma");
        }
        for a in k.alpha_deg() {
            assert_close(a, 30.0, 1e-12, "alpha");
        }
        for c in k.central_angles_deg() {
            assert_close(c, 120.0, 1e-12, "central");
        }
        // Axis = circumcone axis = (1,1,1)/√3, 54.73561° from each edge.
        let third = 1.0 / 3f64.sqrt();
        assert_v3(k.axis(), [third; 3], 1e-15, "axis");
        assert_v3(k.circumcone_axis(), [third; 3], 1e-15, "circum axis");
        assert_close(k.circumcone_half_angle_deg(), 54.73561, 1e-5, "circum");
        for t in k.axis_edge_angles_deg() {
            assert_close(t, 90.0 - phi, 1e-12, "axis-edge");
        }
    }

    #[test]
    fn regular_tetrahedron_corner() {
        let k = Corner::from_plane_angles(60.0, 60.0, 60.0).unwrap();
        for l in k.linear_angles_deg() {
            assert_close(l, 70.5288, 1e-4, "dihedral");
            assert_close(l, (1.0f64 / 3.0).acos() / DEG, 1e-12, "acos 1/3");
        }
        for s in k.sigma_deg() {
            assert_close(s, 30.0, 1e-12, "sigma");
        }
        // Inscribed cone of a regular tetrahedron corner: tan φ = 1/(2√2).
        assert_close(k.phi_deg(), (1.0 / 8f64.sqrt()).atan() / DEG, 1e-12, "phi");
        assert_close(k.phi_deg(), 19.47122, 1e-5, "phi value");
    }

    #[test]
    fn refuses_impossible_corners() {
        assert!(Corner::from_plane_angles(90.0, 90.0, 180.0).is_none());
        assert!(Corner::from_plane_angles(120.0, 120.0, 120.0).is_none());
        assert!(Corner::from_plane_angles(10.0, 20.0, 40.0).is_none());
        assert!(Corner::from_plane_angles(0.0, 20.0, 20.0).is_none());
        assert!(Corner::from_plane_angles(f64::NAN, 20.0, 20.0).is_none());
        assert!(Corner::from_edges([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]).is_none());
        assert!(Corner::from_plane_angles(90.0, 90.0, 90.0)
            .unwrap()
            .table_setup(5, 0.0)
            .is_none());
    }

    #[test]
    fn random_corners_self_consistent() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x7121_4ED2);
        for _ in 0..2000 {
            let p = random_corner(&mut rng, 1.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            for e in k.edges {
                assert_close(norm(e), 1.0, 1e-15, "unit");
            }
            let back = k.plane_angles_deg();
            for i in 0..3 {
                assert_close(back[i], p[i], 1e-12, "plane angle round trip");
            }
            assert!(k.right_handed());
            // Axis at the same angle φ from the three faces, inside the corner.
            let phi = k.phi_deg();
            assert!(phi > 0.0 && phi < 90.0);
            for f in k.axis_face_angles_deg() {
                assert_close(f, phi, 1e-11, "axis-face");
            }
            // The circumcone axis is at the same angle from the three edges.
            let ca = k.circumcone_axis();
            let t0 = angle(ca, k.edges[0]);
            for e in k.edges {
                assert_close(angle(ca, e), t0, 1e-12, "circum");
            }
            // σ: both faces at an edge give the same σ; σ_a + σ_b = AOB, etc.
            let t = k.tangency_generators();
            let s = k.sigma_deg();
            assert_close(
                angle(k.edges[A], t[FACE_COA]) / DEG,
                s[A],
                1e-9,
                "σ_a twice",
            );
            assert_close(
                angle(k.edges[B], t[FACE_BOC]) / DEG,
                s[B],
                1e-9,
                "σ_b twice",
            );
            assert_close(
                angle(k.edges[C], t[FACE_COA]) / DEG,
                s[C],
                1e-9,
                "σ_c twice",
            );
            assert_close(s[A] + s[B], p[0], 1e-9, "σa+σb");
            assert_close(s[B] + s[C], p[1], 1e-9, "σb+σc");
            assert_close(s[C] + s[A], p[2], 1e-9, "σc+σa");
            // α sum to 90°, central angles to 360°.
            let al = k.alpha_deg();
            assert_close(al.iter().sum::<f64>(), 90.0, 1e-9, "Σα");
            let ce = k.central_angles_deg();
            assert_close(ce.iter().sum::<f64>(), 360.0, 1e-9, "ΣЦУ");
            // Central angle AO'B = 180° − α_a − α_b (triangle with incentre).
            assert_close(ce[0], 180.0 - al[A] - al[B], 1e-9, "AO'B");
            // The standardized copy is the same corner.
            let st = k.standardized();
            for i in 0..3 {
                assert_v3(st.edges[i], k.edges[i], 1e-14, "standardized");
            }
        }
    }

    #[test]
    fn random_corners_match_spherical_closed_forms() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x5E_C11);
        for _ in 0..2000 {
            let p = random_corner(&mut rng, 1.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let (phi, sig, alpha) = spec_phi_sigma_alpha(p);
            assert_close(k.phi_deg(), phi, 1e-9, "spherical tan²φ");
            let s = k.sigma_deg();
            let a = k.alpha_deg();
            for i in 0..3 {
                assert_close(s[i], sig[i], 1e-9, "σ = s − opposite");
                assert_close(a[i], alpha[i], 1e-9, "tan α = sin φ / tan σ");
            }
            // The paper's φ = arcsin r, r the inradius of the triangle with
            // tangent lengths tan σ_i, is exact once σ_i are exact.
            let t = sig.map(|d| (d * DEG).tan());
            let pp = t[0] + t[1] + t[2];
            let (sa, sb, sc) = (t[1] + t[2], t[0] + t[2], t[0] + t[1]);
            let r = (pp * (pp - sa) * (pp - sb) * (pp - sc)).sqrt() / pp;
            // (With a descending edge one tan σ_i < 0, p < 0 and r comes out
            // negative: exact in magnitude.)
            assert_close(r.abs().asin() / DEG, k.phi_deg(), 1e-8, "arcsin r");
            assert_eq!(r > 0.0, k.edges_rise());
            // The paper's eq. (4) for the linear angles is exact with exact α.
            let lu = k.linear_angles_deg();
            let ph = phi * DEG;
            for i in 0..3 {
                let al = alpha[i] * DEG;
                let eq4 = 2.0 * (al.tan() / (ph.tan() / al.sin()).atan().cos()).atan() / DEG;
                // (Negative, of the right size, at a descending edge: α < 0.)
                assert_close(lu[i], eq4.abs(), 1e-8, "eq. 4");
                assert_eq!(eq4 > 0.0, sig[i] < 90.0);
                // and tan(ЛУ/2) = tan φ / sin σ.
                let half = (ph.tan() / (sig[i] * DEG).sin()).atan() / DEG;
                assert_close(lu[i], 2.0 * half, 1e-8, "tan(ЛУ/2)");
            }
            // Axis to each edge: cos θ_i = cos φ cos σ_i.
            let th = k.axis_edge_angles_deg();
            for i in 0..3 {
                let ct = ph.cos() * (sig[i] * DEG).cos();
                assert_close((th[i] * DEG).cos(), ct, 1e-12, "cos θ");
            }
        }
    }

    #[test]
    fn rows_and_edge_points_in_paper_frame() {
        let mut rng = ChaCha8Rng::seed_from_u64(0xF0A3);
        for n in 0..1000 {
            let p = random_corner(&mut rng, 2.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let f = k.paper_frame();
            // Orthonormal, left-handed for a right-handed corner.
            for (u, v) in [(f.x, f.y), (f.y, f.z), (f.z, f.x)] {
                assert_close(dot(u, v), 0.0, 1e-14, "orthogonal");
            }
            assert!(!f.right_handed());
            let phi = k.phi_deg() * DEG;
            let [sa, sb, sc] = k.sigma_deg().map(|d| d * DEG);
            let [aa, ab, _] = k.alpha_deg().map(|d| d * DEG);
            // The tangency generator OD of the base face projects onto −X.
            let od = f.coords(k.tangency_generators()[FACE_AOB]);
            assert!(od[0] < 0.0);
            assert_close(od[1], 0.0, 1e-14, "OD on XZ");
            assert_close(od[0] / od[2], -phi.tan(), 1e-12, "OD slope");
            // Rows: the paper's м.2 (y_b positive) and м.1's x_c sign.
            let z = 1.0 + n as f64 * 0.37;
            let r = z * phi.tan();
            assert_close(k.row_inradius(z), r, 1e-12 * z, "r_n");
            let row = k.row(z);
            let ga = 2.0 * (90.0 * DEG - ab);
            let gb = 2.0 * (aa - 90.0 * DEG);
            let xc = -r * (ga.sin() - gb.sin()) / (ga - gb).sin();
            let yc = (r + xc * ga.cos()) / ga.sin();
            let tol = 1e-9 * z;
            assert_close(row[A][0], -r, tol, "x_a");
            assert_close(row[A][1], -r / aa.tan(), tol, "y_a");
            assert_close(row[B][0], -r, tol, "x_b");
            assert_close(row[B][1], r / ab.tan(), tol, "y_b");
            assert_close(row[C][0], xc, tol, "x_c");
            assert_close(row[C][1], yc, tol, "y_c");
            if k.edges_rise() {
                assert!(row[C][0] > 0.0, "x_c is positive");
                assert!(row[A][1] < 0.0 && row[B][1] > 0.0);
            }
            // Edge points at lengths L: Z = L cos φ cos σ, r = Z tan φ, and
            // the point lies on the row at that height.
            for (i, s) in [(A, sa), (B, sb), (C, sc)] {
                let l = 10.0 + 3.0 * i as f64;
                let q = k.edge_point(i, l);
                let zz = l * phi.cos() * s.cos();
                assert_close(q[2], zz, 1e-11 * l, "Z_i");
                assert_close(k.edge_height(i, l), zz, 1e-11 * l, "edge_height");
                let rr = k.row(zz)[i];
                assert_close(q[0], rr[0], 1e-10 * l, "edge x");
                assert_close(q[1], rr[1], 1e-10 * l, "edge y");
            }
        }
    }

    fn paper_p(kv: u8, sigma_a: f64, e: f64) -> f64 {
        match kv {
            1 => 180.0 - (sigma_a + e),
            2 => sigma_a - e,
            3 => -(sigma_a + e),
            _ => -180.0 + (sigma_a - e),
        }
    }

    #[test]
    fn table_setup_matches_paper_rotation_and_tilt() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x7AB1E);
        for _ in 0..500 {
            let p = random_corner(&mut rng, 2.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let phi = k.phi_deg();
            let sa = k.sigma_deg()[A];
            let e = rng.random_range(-30.0..30.0);
            for kv in 1..=4u8 {
                let s = k.table_setup(kv, e).unwrap();
                // Base face on the table, OC up, the face on its side of OA.
                assert_close(s.edges_on_table[A][2], 0.0, 1e-15, "OA on table");
                assert_close(s.edges_on_table[B][2], 0.0, 1e-15, "OB on table");
                assert!(s.edges_on_table[C][2] > 0.0);
                let turn = cross(s.edges_on_table[A], s.edges_on_table[B])[2];
                assert_eq!(turn > 0.0, kv == 1 || kv == 3, "face side");
                // P: the paper's formula, modulo 360°.
                let d = wrap180(s.p_deg - paper_p(kv, sa, e));
                assert_close(d, 0.0, 1e-9, "P");
                assert!(s.p_deg > -180.0 && s.p_deg <= 180.0);
                assert!(s.p_positive_deg >= 0.0 && s.p_positive_deg < 360.0);
                assert_close(wrap180(s.p_positive_deg - s.p_deg), 0.0, 1e-12, "P⁺ ≡ P");
                // Tilt −(90° − φ); the axis ends on +Z.
                assert_close(s.tilt_deg, -(90.0 - phi), 1e-9, "tilt");
                assert_v3(s.axis_machine, [0.0, 0.0, 1.0], 1e-14, "axis vertical");
                // Machine coordinates vs the paper frame.
                let f = k.paper_frame();
                for i in 0..3 {
                    let pf = f.coords(k.edges[i]);
                    let want = if kv == 2 || kv == 4 {
                        pf
                    } else {
                        [pf[0], -pf[1], pf[2]]
                    };
                    assert_v3(s.edges_machine[i], want, 1e-12, "machine edges");
                    assert_v3(s.edge_point(i, 2.0), scale(2.0, want), 1e-12, "edge pt");
                }
                // The paper's indicator checks hold on the base face AOB: it
                // contains the Y direction and rises ΔX/ΔZ = tan φ.
                let placed = Corner {
                    edges: s.edges_machine,
                };
                let n = placed.inward_normals()[FACE_AOB];
                assert_close(n[1], 0.0, 1e-12, "AOB contains Y");
                assert_close((n[2] / n[0]).abs(), (phi * DEG).tan(), 1e-9, "|ΔX/ΔZ|");
            }
        }
        // P = 0 gives P⁺ = 0: a cube corner with k_v = 2, E = σ_a = 45°.
        let cube = Corner::from_plane_angles(90.0, 90.0, 90.0).unwrap();
        let s = cube.table_setup(2, 45.0).unwrap();
        assert_close(s.p_deg, 0.0, 1e-12, "P = 0");
        assert!(s.p_positive_deg.abs() < 1e-12 || (360.0 - s.p_positive_deg) < 1e-12);
    }

    #[test]
    fn inverse_two_plane_angles_and_linear() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x1AB);
        for _ in 0..2000 {
            let p = random_corner(&mut rng, 1.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let lu = k.linear_angles_deg();
            let back = Corner::from_two_plane_angles_and_linear(p[0], p[1], lu[B]).unwrap();
            let pa = back.plane_angles_deg();
            assert_close(pa[0], p[0], 1e-10, "AOB");
            assert_close(pa[1], p[1], 1e-10, "BOC");
            assert_close(pa[2], p[2], 1e-9, "COA");
            assert_close(
                third_plane_angle_deg(p[0], p[1], lu[B]).unwrap(),
                p[2],
                1e-9,
                "third",
            );
            assert_close(back.linear_angles_deg()[B], lu[B], 1e-9, "ЛУ_BO");
            for i in 0..3 {
                assert_v3(back.edges[i], k.edges[i], 1e-10, "same corner");
            }
        }
        // Cube: two right angles with a right dihedral → third right angle.
        assert_close(
            third_plane_angle_deg(90.0, 90.0, 90.0).unwrap(),
            90.0,
            1e-12,
            "cube",
        );
        assert!(third_plane_angle_deg(90.0, 0.0, 90.0).is_none());
    }

    #[test]
    fn inverse_plane_angle_and_two_linear() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x2AB);
        for _ in 0..2000 {
            let p = random_corner(&mut rng, 1.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let lu = k.linear_angles_deg();
            let back = Corner::from_plane_angle_and_two_linear(p[0], lu[A], lu[B]).unwrap();
            let pa = back.plane_angles_deg();
            for i in 0..3 {
                assert_close(pa[i], p[i], 1e-8, "plane angles");
            }
        }
    }

    #[test]
    fn inverse_three_linear_angles() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x3AB);
        for _ in 0..2000 {
            let p = random_corner(&mut rng, 1.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let lu = k.linear_angles_deg();
            let back = Corner::from_linear_angles(lu[A], lu[B], lu[C]).unwrap();
            let pa = back.plane_angles_deg();
            for i in 0..3 {
                assert_close(pa[i], p[i], 1e-8, "plane angles");
            }
            let lb = back.linear_angles_deg();
            for i in 0..3 {
                assert_close(lb[i], lu[i], 1e-8, "linear angles");
            }
        }
        let cube = Corner::from_linear_angles(90.0, 90.0, 90.0).unwrap();
        for a in cube.plane_angles_deg() {
            assert_close(a, 90.0, 1e-12, "cube");
        }
        // Linear angles summing to 180° or less make no corner.
        assert!(Corner::from_linear_angles(60.0, 60.0, 60.0).is_none());
    }

    #[test]
    fn inverse_two_plane_angles_and_phi() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x4AB);
        for _ in 0..100 {
            let p = random_corner(&mut rng, 3.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let sols = Corner::from_two_plane_angles_and_phi(p[0], p[1], k.phi_deg());
            assert!(!sols.is_empty());
            assert!(
                sols.iter()
                    .any(|s| close(s.plane_angles_deg()[2], p[2], 1e-8)),
                "{p:?} → {:?}",
                sols.iter()
                    .map(|s| s.plane_angles_deg()[2])
                    .collect::<Vec<_>>()
            );
            for s in &sols {
                assert_close(s.phi_deg(), k.phi_deg(), 1e-10, "φ");
            }
        }
        // Cube: AOB = BOC = 90°, φ = 35.26439° → COA = 90°, the only
        // solution (here tan φ = sin(COA/2), rising to 45° as COA → 180°).
        let sols = Corner::from_two_plane_angles_and_phi(90.0, 90.0, (0.5f64).sqrt().atan() / DEG);
        assert_eq!(sols.len(), 1);
        assert_close(sols[0].plane_angles_deg()[2], 90.0, 1e-9, "cube COA");
        assert!(Corner::from_two_plane_angles_and_phi(90.0, 90.0, 60.0).is_empty());
    }

    #[test]
    fn fillet_offset_geometry() {
        let mut rng = ChaCha8Rng::seed_from_u64(0x5AB);
        for _ in 0..500 {
            let p = random_corner(&mut rng, 2.0);
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            let f = k.paper_frame();
            let lu = k.linear_angles_deg();
            for i in 0..3 {
                let off = k.fillet_offset(i, 2.0);
                let d = 2.0 * (1.0 / (0.5 * lu[i] * DEG).sin() - 1.0);
                assert_close(norm(off), d, 1e-12, "length");
                // Perpendicular to the edge, in the plane of edge and axis,
                // equally far from both faces of the edge.
                let e = f.coords(k.edges[i]);
                assert_close(dot(off, e), 0.0, 1e-12, "⟂ edge");
                assert_close(triple(off, e, [0.0, 0.0, 1.0]), 0.0, 1e-12, "in plane");
                let n = k.inward_normals().map(|n| f.coords(n));
                let (f1, f2) = match i {
                    A => (FACE_AOB, FACE_COA),
                    B => (FACE_AOB, FACE_BOC),
                    _ => (FACE_BOC, FACE_COA),
                };
                assert_close(dot(off, n[f1]), dot(off, n[f2]), 1e-12, "bisector");
                // A fillet circle of radius 2 centred at d + 2 from the edge
                // along the bisector touches both faces.
                let centre = scale((d + 2.0) / d, off);
                assert_close(dot(centre, n[f1]), 2.0, 1e-11, "tangent");
                // Its height: d·sin θ_i (θ_i the axis–edge angle).
                let th = k.axis_edge_angles_deg()[i] * DEG;
                assert_close(off[2], d * th.sin(), 1e-12, "rise");
            }
        }
    }

    #[test]
    fn tilt_table_parameters() {
        // Eq. (6): a = L − R cos(Ψ + β), c = R sin(Ψ + β) − m.
        for (l, m) in [(0.0, 50.0), (30.0, 70.0), (120.0, 15.0)] {
            for beta in [-80.0, -54.73561, -35.0, 10.0, 90.0] {
                let (a, c) = tilt_origin_shift(l, m, beta);
                let psi = f64::atan2(m, l);
                let r = f64::hypot(l, m);
                let b = beta * DEG;
                assert_close(a, l - r * (psi + b).cos(), 1e-12, "a");
                assert_close(c, r * (psi + b).sin() - m, 1e-12, "c");
                let (l2, m2) = table_params_from_shift(a, c, beta).unwrap();
                assert_close(l2, l, 1e-9, "L back");
                assert_close(m2, m, 1e-9, "m back");
                // The origin moves by (−a, c).
                let o = machine_position([0.0; 3], 0.0, beta, l, m);
                assert_v3(o, [-a, 0.0, c], 1e-12, "origin");
            }
            // At 90°: L = (a + c)/2, m = (a − c)/2.
            let (a, c) = tilt_origin_shift(l, m, 90.0);
            assert_close(0.5 * (a + c), l, 1e-12, "L closed");
            assert_close(0.5 * (a - c), m, 1e-12, "m closed");
        }
        assert!(table_params_from_shift(1.0, 1.0, 0.0).is_none());
        // machine_position is the set-up's motion plus the origin shift.
        let k = Corner::from_plane_angles(100.0, 70.0, 80.0).unwrap();
        let s = k.table_setup(1, 5.0).unwrap();
        let v = [12.0, -7.0, 3.0];
        let (a, c) = tilt_origin_shift(40.0, 60.0, s.tilt_deg);
        let got = machine_position(
            add(v, scale(25.0, s.edges_on_table[C])),
            s.p_deg,
            s.tilt_deg,
            40.0,
            60.0,
        );
        let vertex = machine_position(v, s.p_deg, s.tilt_deg, 40.0, 60.0);
        assert_v3(
            sub(got, vertex),
            scale(25.0, s.edges_machine[C]),
            1e-12,
            "edge",
        );
        let rotated = rot_xz(s.tilt_deg, rot_z(s.p_deg, v));
        assert_v3(vertex, add(rotated, [-a, 0.0, c]), 1e-12, "vertex");
    }

    /// The paper's test table: equal plane angles give three central angles
    /// of 120° (the "119,9(9)" it prints per angle), every corner's true
    /// central angles sum to 360°; the proportional central angles of eq. (3)
    /// are exact only for the symmetric corners. Prints the vector values.
    #[test]
    fn paper_test_table() {
        for p in PAPER_TESTS {
            let k = Corner::from_plane_angles(p[0], p[1], p[2]).unwrap();
            for i in 0..3 {
                assert_close(k.plane_angles_deg()[i], p[i], 1e-12, "round trip");
            }
            let ce = k.central_angles_deg();
            assert_close(ce.iter().sum::<f64>(), 360.0, 1e-9, "ΣЦУ");
            let prop = p.map(|x| 360.0 * x / (p[0] + p[1] + p[2]));
            if p[0] == p[1] && p[1] == p[2] {
                for (c, q) in ce.iter().zip(prop) {
                    assert_close(*c, 120.0, 1e-9, "120°");
                    assert_close(*c, q, 1e-9, "proportional");
                }
            } else {
                let worst = (0..3).map(|i| (ce[i] - prop[i]).abs()).fold(0.0, f64::max);
                assert!(worst > 1e-3, "{p:?}: proportional by accident?");
            }
            let (phi, sig, _) = spec_phi_sigma_alpha(p);
            assert_close(k.phi_deg(), phi, 1e-9, "φ");
            for i in 0..3 {
                assert_close(k.sigma_deg()[i], sig[i], 1e-9, "σ");
            }
            println!(
                "{p:?}: φ={:.6} σ={:?} α={:?} ЛУ={:?} ЦУ={:?} ЦУ(eq.3)={:?} axis-edge={:?} \
                 circum={:.6} P(kv1..4,E=0)={:?} tilt={:.6}",
                k.phi_deg(),
                k.sigma_deg().map(|x| (x * 1e6).round() / 1e6),
                k.alpha_deg().map(|x| (x * 1e6).round() / 1e6),
                k.linear_angles_deg().map(|x| (x * 1e6).round() / 1e6),
                ce.map(|x| (x * 1e6).round() / 1e6),
                prop.map(|x| (x * 1e6).round() / 1e6),
                k.axis_edge_angles_deg().map(|x| (x * 1e6).round() / 1e6),
                k.circumcone_half_angle_deg(),
                [1u8, 2, 3, 4]
                    .map(|kv| (k.table_setup(kv, 0.0).unwrap().p_deg * 1e6).round() / 1e6),
                k.table_setup(1, 0.0).unwrap().tilt_deg,
            );
            // Rows at Z = 10 and edge points for L = 20, paper frame.
            let row = k.row(10.0);
            println!(
                "    row Z=10: r={:.6} A={:?} B={:?} C={:?}",
                k.row_inradius(10.0),
                row[A].map(|x| (x * 1e6).round() / 1e6),
                row[B].map(|x| (x * 1e6).round() / 1e6),
                row[C].map(|x| (x * 1e6).round() / 1e6)
            );
            println!(
                "    L=20: AO={:?} BO={:?} CO={:?}",
                k.edge_point(A, 20.0).map(|x| (x * 1e6).round() / 1e6),
                k.edge_point(B, 20.0).map(|x| (x * 1e6).round() / 1e6),
                k.edge_point(C, 20.0).map(|x| (x * 1e6).round() / 1e6)
            );
        }
    }
}

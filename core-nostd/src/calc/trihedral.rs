//! Milling a trihedral corner on a tilt-rotary table (Lyakun & Yurkevich):
//! the set-up from three plane angles.
//!
//! A trihedral corner with vertex `O` has the plane (face) angles `AOB`
//! (the base face, set on the table), `BOC` and `COA`, and a linear
//! (dihedral) angle at each edge `OA`, `OB`, `OC`. The paper tilts the part
//! so that the axis `O'O` of the cone inscribed in the corner is parallel to
//! the spindle; a cutter ground to the plan angle `φ` (the cone's
//! half-angle) then reaches every face. The calculation runs in the paper's
//! order:
//!
//! 1. [`Corner`]: the cone half-angle `φ`, the angles `σ_i` between each
//!    edge and the cone's tangent lines in its faces, the half-angles `α_i`
//!    of the row triangle at each edge, the linear angles, the central
//!    angles at `O'`.
//! 2. [`Setup`]: the points at the given lengths on the edges, the rows
//!    ([`Setup::row`]), `Z_min` with the fillet, the table's rotation `P`
//!    and tilt `−(90° − φ)`, the shift `(a, c)` of the tilt and the vertex
//!    in the program's frame; [`Setup::write_program`] writes the program.
//! 3. [`TableMeasurement`]: the table's parameters `L`, `m` from the two
//!    measurements of a roller, at tilt 0° and at tilt 90°.
//!
//! # Exact spherical trigonometry (`docs/calculators.md` §4.2)
//! With `s` the half-sum of the plane angles,
//! `σ_a = s − BOC`, `σ_b = s − COA`, `σ_c = s − AOB` (each edge's angle to
//! the tangent lines, equal in its two faces),
//! `tan²φ = sin σ_a·sin σ_b·sin σ_c / sin s` (the spherical in-radius; the
//! paper's `φ = arcsin r`, `r` the in-radius of the plane triangle with
//! tangent lengths `tan σ_i`, is the same number),
//! `tan α_i = sin φ / tan σ_i`, and the linear angle at edge `i`
//! `2·atan(tan φ / sin σ_i)` (the paper's eq. 4 gives it too, from the
//! exact `α_i`). The paper takes the central angles proportional to the
//! plane angles and gets `α_i` from that; it is exact only for symmetric
//! corners (a cube corner) and differs by up to degrees otherwise.
//! [`Corner::proportional`] keeps it for comparison; [`Corner::new`] is
//! exact.
//!
//! # Frame
//! The vertex frame has its origin at the vertex `O`, `+Z` along the cone
//! axis out of the corner (towards the tool), and `−X` towards the point
//! `D` where the cone touches the base face `AOB`. A section at height `Z`
//! is the row triangle `ABC` around the circle of radius `Z·tan φ`: side
//! `AB` lies on `x = −r`, `A` at `y < 0`, `B` at `y > 0`, `C` at `x > 0`
//! (seen from the tool, `A → B → C` runs clockwise).
//!
//! # Where the paper slips (`docs/errata.md` §3)
//! - `Y_BO = −r/tan α_b` for the edge point but `y_b = +r/tan α_b` for the
//!   rows: `B` is at `+Y` (the rows are right).
//! - `X_CO = −r·(sin γ_a − sin γ_b)/sin(γ_a − γ_b)` for the edge point but
//!   `x_c = +r·(…)` for the rows: the minus sign is right for both, and the
//!   value is positive (`x_c = r·cos(α_a − α_b)/sin α_c`); with the rows'
//!   sign the point is off the side `BC` that the paper's `y_c` puts it on.
//! - The positive-scale rotation `P⁺ = (180° − sign P·180°) + P` gives
//!   180° for `P = 0`; it is 0°.
//! - The table parameters: the paper solves its eq. (6) at 90° through an
//!   angle `ψ` (eq. 7, 8, an `arcsin` that loses the sign of `m`); at 90°
//!   eq. (6) is `a = L + m`, `c = L − m`, so `L = (a + c)/2`,
//!   `m = (a − c)/2`.
//!
//! # Decisions where the paper is silent
//! - A corner whose edge makes 90° or more with the tangent lines
//!   (`σ_i ≥ 90°`, e.g. the paper's own test corner 151°, 2°, 150°) has that
//!   edge at or below the vertex's level: the section is no triangle, and
//!   the method does not apply ([`TrihedralError::EdgeNotAboveVertex`]).
//! - `P` is brought into (−180°, 180°] before `P⁺` is taken.
//! - `Z_min` takes the fillet only when the point on `OC` is strictly the
//!   highest, as the paper's М01–М03 branch on `>`.
//! - The paper's own input rule (the least plane angle above a third of
//!   the other two) belongs to its proportional `α` only; two of the six
//!   corners of its test table break it (2°, 3°, 4° and 151°, 2°, 150°).
//! - The program's tilt is axis `B`, the rotation axis `C`; the vertex
//!   frame is set with `G52`; the edges are milled from their points to
//!   the vertex in the main program, the rows from the vertex outwards in
//!   the subprogram, each row closed `A → B → C → A`. A machine's own
//!   syntax is for the user to edit, as the paper says.
//!
//! All angles at the API are degrees, all lengths mm, all `f64`.

use core::fmt;

use libm::{asin, atan, atan2, cos, fabs, round, sin, sqrt, tan};

/// Degrees to radians.
const DEG: f64 = core::f64::consts::PI / 180.0;

/// The sine of an angle in degrees.
fn sind(deg: f64) -> f64 {
    sin(deg * DEG)
}

/// The cosine of an angle in degrees.
fn cosd(deg: f64) -> f64 {
    cos(deg * DEG)
}

/// The tangent of an angle in degrees.
fn tand(deg: f64) -> f64 {
    tan(deg * DEG)
}

/// `acos` in degrees, its argument clamped to [−1, 1] against rounding.
fn acosd(x: f64) -> f64 {
    libm::acos(x.clamp(-1.0, 1.0)) / DEG
}

/// A face of the corner, named by its plane angle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Face {
    /// The base face `AOB`, set on the table.
    Aob,
    /// The side face `BOC`.
    Boc,
    /// The side face `COA`.
    Coa,
}

/// An edge of the corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Edge {
    /// The edge `OA` (between faces `AOB` and `COA`).
    Oa,
    /// The edge `OB` (between faces `AOB` and `BOC`).
    Ob,
    /// The edge `OC` (between faces `BOC` and `COA`), the one that may
    /// carry a fillet from the side faces' pre-milling.
    Oc,
}

/// Why a corner or its set-up cannot be computed. Each names the input and
/// why ([`TrihedralError::as_str`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TrihedralError {
    /// A plane angle is not strictly between 0° and 180° (or not a number).
    FaceAngleOutOfRange(Face),
    /// A plane angle is not less than the sum of the other two.
    FaceAngleNotBelowOthers(Face),
    /// The three plane angles do not sum to less than 360°.
    FaceAngleSumTooLarge,
    /// A linear (dihedral) angle is not strictly between 0° and 180°.
    LinearAngleOutOfRange(Edge),
    /// The three linear angles do not sum to more than 180°.
    LinearAngleSumTooSmall,
    /// A linear angle plus 180° is not more than the other two together.
    LinearAngleTooSmall(Edge),
    /// Not exactly three of the six angles are given.
    AngleCount,
    /// Two plane angles and a linear angle not between them, or two linear
    /// angles and a plane angle not between them: two corners fit.
    AngleAmbiguous,
    /// An edge makes 90° or more with the cone's tangent lines (`σ ≥ 90°`):
    /// it does not rise above the vertex along the cone axis, and the
    /// corner cannot be milled this way.
    EdgeNotAboveVertex(Edge),
    /// The paper's proportional method needs each plane angle above a third
    /// of the other two (its `α` would be 0 or negative).
    ProportionalFaceTooSmall(Face),
    /// The row step `h` is not a positive length.
    RowStep,
    /// The number of rows is 0.
    RowCount,
    /// A milling length along an edge (`L_A`, `L_B`, `L_C`) is not a
    /// positive length.
    EdgeLength(Edge),
    /// The fillet radius `R_f` is negative or not a number.
    FilletRadius,
    /// The angle `E` of ray `OA` to the X axis is not within ±360°.
    OffsetAngle,
    /// A table parameter `L` or `m` is not a length.
    TableParameter,
    /// A vertex coordinate is not a length.
    VertexCoordinate,
    /// A measurement of the table is not a length.
    Measurement,
    /// The ball's radius is not above the fillet radius.
    BallRadius,
    /// The feed is not a positive number of mm/min.
    Feed,
    /// A program number is 0, above 9999, or both numbers are the same.
    ProgramNumber,
    /// A number of the program is not finite or not below 100 000.
    NumberOutOfRange,
    /// The writer refused the text.
    Write,
}

impl TrihedralError {
    /// A short, fixed description naming the input and why it is refused.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{Face, TrihedralError};
    /// assert_eq!(
    ///     TrihedralError::FaceAngleNotBelowOthers(Face::Boc).as_str(),
    ///     "plane angle BOC: not less than the sum of the other two"
    /// );
    /// ```
    pub const fn as_str(self) -> &'static str {
        use Edge::{Oa, Ob, Oc};
        use Face::{Aob, Boc, Coa};
        use TrihedralError as E;
        match self {
            E::FaceAngleOutOfRange(Aob) => "plane angle AOB: not between 0 and 180 deg",
            E::FaceAngleOutOfRange(Boc) => "plane angle BOC: not between 0 and 180 deg",
            E::FaceAngleOutOfRange(Coa) => "plane angle COA: not between 0 and 180 deg",
            E::FaceAngleNotBelowOthers(Aob) => {
                "plane angle AOB: not less than the sum of the other two"
            }
            E::FaceAngleNotBelowOthers(Boc) => {
                "plane angle BOC: not less than the sum of the other two"
            }
            E::FaceAngleNotBelowOthers(Coa) => {
                "plane angle COA: not less than the sum of the other two"
            }
            E::FaceAngleSumTooLarge => "plane angles: sum not below 360 deg",
            E::LinearAngleOutOfRange(Oa) => "linear angle at OA: not between 0 and 180 deg",
            E::LinearAngleOutOfRange(Ob) => "linear angle at OB: not between 0 and 180 deg",
            E::LinearAngleOutOfRange(Oc) => "linear angle at OC: not between 0 and 180 deg",
            E::LinearAngleSumTooSmall => "linear angles: sum not above 180 deg",
            E::LinearAngleTooSmall(Oa) => {
                "linear angle at OA: 180 deg more is not above the other two"
            }
            E::LinearAngleTooSmall(Ob) => {
                "linear angle at OB: 180 deg more is not above the other two"
            }
            E::LinearAngleTooSmall(Oc) => {
                "linear angle at OC: 180 deg more is not above the other two"
            }
            E::AngleCount => "corner angles: not exactly three given",
            E::AngleAmbiguous => "corner angles: the linear or plane angle is not between the other two, two corners fit",
            E::EdgeNotAboveVertex(Oa) => "plane angles: edge OA not above the vertex (sigma_a >= 90 deg)",
            E::EdgeNotAboveVertex(Ob) => "plane angles: edge OB not above the vertex (sigma_b >= 90 deg)",
            E::EdgeNotAboveVertex(Oc) => "plane angles: edge OC not above the vertex (sigma_c >= 90 deg)",
            E::ProportionalFaceTooSmall(Aob) => {
                "plane angle AOB: not above a third of the other two (proportional method)"
            }
            E::ProportionalFaceTooSmall(Boc) => {
                "plane angle BOC: not above a third of the other two (proportional method)"
            }
            E::ProportionalFaceTooSmall(Coa) => {
                "plane angle COA: not above a third of the other two (proportional method)"
            }
            E::RowStep => "row step h: not a positive length below 100000 mm",
            E::RowCount => "row count: zero",
            E::EdgeLength(Oa) => "length L_A: not a positive length below 100000 mm",
            E::EdgeLength(Ob) => "length L_B: not a positive length below 100000 mm",
            E::EdgeLength(Oc) => "length L_C: not a positive length below 100000 mm",
            E::FilletRadius => "fillet radius: negative or not below 100000 mm",
            E::OffsetAngle => "angle E: not within +-360 deg",
            E::TableParameter => "table L, m: not a length below 100000 mm",
            E::VertexCoordinate => "vertex x, y, z: not a length below 100000 mm",
            E::Measurement => "table measurement: not a length below 100000 mm",
            E::BallRadius => "ball radius: not above the fillet radius, or not below 100000 mm",
            E::Feed => "feed: not a positive number below 100000 mm/min",
            E::ProgramNumber => "program numbers: not 1-9999, or the same twice",
            E::NumberOutOfRange => "program: a number not below 100000",
            E::Write => "program: the writer refused the text",
        }
    }
}

impl fmt::Display for TrihedralError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The bound of every length input and every number written, mm or deg.
const LIMIT: f64 = 100_000.0;

/// A finite length of magnitude below [`LIMIT`].
fn is_length(x: f64) -> bool {
    fabs(x) < LIMIT
}

/// A positive length below [`LIMIT`].
fn is_positive_length(x: f64) -> bool {
    x > 0.0 && x < LIMIT
}

/// An angle strictly between 0° and 180° (NaN fails).
fn is_open_angle(deg: f64) -> bool {
    deg > 0.0 && deg < 180.0
}

/// The three plane angles of a corner, degrees, checked to form one: each
/// in (0°, 180°), each less than the sum of the other two, their sum below
/// 360°.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlaneAngles {
    aob: f64,
    boc: f64,
    coa: f64,
}

impl PlaneAngles {
    /// The plane angles `AOB` (the base face), `BOC`, `COA`, degrees.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{Face, PlaneAngles, TrihedralError};
    /// assert!(PlaneAngles::new(90.0, 90.0, 90.0).is_ok());
    /// assert_eq!(
    ///     PlaneAngles::new(30.0, 100.0, 60.0),
    ///     Err(TrihedralError::FaceAngleNotBelowOthers(Face::Boc))
    /// );
    /// assert_eq!(PlaneAngles::new(130.0, 120.0, 110.0), Err(TrihedralError::FaceAngleSumTooLarge));
    /// assert_eq!(
    ///     PlaneAngles::new(0.0, 90.0, 90.0),
    ///     Err(TrihedralError::FaceAngleOutOfRange(Face::Aob))
    /// );
    /// ```
    pub fn new(aob_deg: f64, boc_deg: f64, coa_deg: f64) -> Result<Self, TrihedralError> {
        let faces = [
            (Face::Aob, aob_deg),
            (Face::Boc, boc_deg),
            (Face::Coa, coa_deg),
        ];
        for (face, angle) in faces {
            if !is_open_angle(angle) {
                return Err(TrihedralError::FaceAngleOutOfRange(face));
            }
        }
        let sum = aob_deg + boc_deg + coa_deg;
        for (face, angle) in faces {
            if angle >= sum - angle {
                return Err(TrihedralError::FaceAngleNotBelowOthers(face));
            }
        }
        if sum >= 360.0 {
            return Err(TrihedralError::FaceAngleSumTooLarge);
        }
        Ok(PlaneAngles {
            aob: aob_deg,
            boc: boc_deg,
            coa: coa_deg,
        })
    }

    /// The corner with the three linear (dihedral) angles at `OA`, `OB`,
    /// `OC`, degrees, by the dual law of cosines
    /// `cos BOC = (cos A + cos B·cos C)/(sin B·sin C)`. They form a corner
    /// when each is in (0°, 180°), their sum exceeds 180° and each plus
    /// 180° exceeds the other two.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{PlaneAngles, TrihedralError};
    /// let p = PlaneAngles::from_linear_angles(90.0, 90.0, 90.0).unwrap();
    /// assert!((p.boc_deg() - 90.0).abs() < 1e-12);
    /// assert_eq!(
    ///     PlaneAngles::from_linear_angles(50.0, 60.0, 70.0),
    ///     Err(TrihedralError::LinearAngleSumTooSmall)
    /// );
    /// ```
    pub fn from_linear_angles(
        oa_deg: f64,
        ob_deg: f64,
        oc_deg: f64,
    ) -> Result<Self, TrihedralError> {
        let edges = [(Edge::Oa, oa_deg), (Edge::Ob, ob_deg), (Edge::Oc, oc_deg)];
        for (edge, angle) in edges {
            if !is_open_angle(angle) {
                return Err(TrihedralError::LinearAngleOutOfRange(edge));
            }
        }
        let sum = oa_deg + ob_deg + oc_deg;
        if sum <= 180.0 {
            return Err(TrihedralError::LinearAngleSumTooSmall);
        }
        for (edge, angle) in edges {
            if angle + 180.0 <= sum - angle {
                return Err(TrihedralError::LinearAngleTooSmall(edge));
            }
        }
        let side =
            |a: f64, b: f64, c: f64| acosd((cosd(a) + cosd(b) * cosd(c)) / (sind(b) * sind(c)));
        PlaneAngles::new(
            side(oc_deg, oa_deg, ob_deg),
            side(oa_deg, ob_deg, oc_deg),
            side(ob_deg, oc_deg, oa_deg),
        )
    }

    /// The plane angle `AOB` of the base face, degrees.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::PlaneAngles;
    /// assert_eq!(PlaneAngles::new(60.0, 70.0, 80.0).unwrap().aob_deg(), 60.0);
    /// ```
    pub const fn aob_deg(self) -> f64 {
        self.aob
    }

    /// The plane angle `BOC`, degrees.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::PlaneAngles;
    /// assert_eq!(PlaneAngles::new(60.0, 70.0, 80.0).unwrap().boc_deg(), 70.0);
    /// ```
    pub const fn boc_deg(self) -> f64 {
        self.boc
    }

    /// The plane angle `COA`, degrees.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::PlaneAngles;
    /// assert_eq!(PlaneAngles::new(60.0, 70.0, 80.0).unwrap().coa_deg(), 80.0);
    /// ```
    pub const fn coa_deg(self) -> f64 {
        self.coa
    }

    /// The paper's central angles `AO'B`, `BO'C`, `CO'A` (its eq. 3):
    /// each plane angle times `360°/(AOB + BOC + COA)`, degrees. They sum
    /// to 360° by construction, which is all the paper's "test table"
    /// checks; the exact ones are [`Corner::central_aob_deg`] and its
    /// siblings.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::PlaneAngles;
    /// let c = PlaneAngles::new(2.0, 3.0, 4.0).unwrap().proportional_central_angles_deg();
    /// assert_eq!(c, [80.0, 120.0, 160.0]);
    /// ```
    pub fn proportional_central_angles_deg(self) -> [f64; 3] {
        let k = 360.0 / (self.aob + self.boc + self.coa);
        [k * self.aob, k * self.boc, k * self.coa]
    }

    /// The half-sum `s`, and `σ_a = s − BOC`, `σ_b = s − COA`,
    /// `σ_c = s − AOB`, degrees; each `σ` in (0°, 180°) for a corner.
    fn sigmas(self) -> (f64, [f64; 3]) {
        let s = 0.5 * (self.aob + self.boc + self.coa);
        (s, [s - self.boc, s - self.coa, s - self.aob])
    }
}

/// Any three of a corner's six angles, degrees: plane angles `AOB`, `BOC`,
/// `COA` and linear (dihedral) angles at `OA`, `OB`, `OC`. [`solve`]
/// gives the plane angles in closed form when the three fix one corner.
///
/// [`solve`]: CornerAngles::solve
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CornerAngles {
    /// The plane angle `AOB` of the base face, degrees.
    pub aob_deg: Option<f64>,
    /// The plane angle `BOC`, degrees.
    pub boc_deg: Option<f64>,
    /// The plane angle `COA`, degrees.
    pub coa_deg: Option<f64>,
    /// The linear angle at edge `OA` (between faces `AOB` and `COA`), deg.
    pub at_oa_deg: Option<f64>,
    /// The linear angle at edge `OB` (between faces `AOB` and `BOC`), deg.
    pub at_ob_deg: Option<f64>,
    /// The linear angle at edge `OC` (between faces `BOC` and `COA`), deg.
    pub at_oc_deg: Option<f64>,
}

impl CornerAngles {
    /// The plane angles of the corner the three given angles fix:
    /// - three plane angles: checked ([`PlaneAngles::new`]);
    /// - three linear angles: the dual law of cosines
    ///   ([`PlaneAngles::from_linear_angles`]);
    /// - two plane angles and the linear angle at their common edge: the
    ///   law of cosines `cos BOC = cos AOB·cos COA + sin AOB·sin COA·cos A`;
    /// - two linear angles and the plane angle of the face between their
    ///   edges: the third linear angle by the dual law
    ///   `cos C = −cos A·cos B + sin A·sin B·cos AOB`, then as three
    ///   linear angles.
    ///
    /// Any other three (a plane or linear angle not between the other two)
    /// fit two corners or none: [`TrihedralError::AngleAmbiguous`].
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{CornerAngles, TrihedralError};
    /// // Base face 90°, side face COA 90°, a right angle between them at OA.
    /// let given = CornerAngles {
    ///     aob_deg: Some(90.0),
    ///     coa_deg: Some(90.0),
    ///     at_oa_deg: Some(90.0),
    ///     ..CornerAngles::default()
    /// };
    /// let p = given.solve().unwrap();
    /// assert!((p.boc_deg() - 90.0).abs() < 1e-12);
    /// let wrong = CornerAngles { aob_deg: Some(90.0), ..CornerAngles::default() };
    /// assert_eq!(wrong.solve(), Err(TrihedralError::AngleCount));
    /// ```
    pub fn solve(&self) -> Result<PlaneAngles, TrihedralError> {
        let faces = [
            (Face::Aob, self.aob_deg),
            (Face::Boc, self.boc_deg),
            (Face::Coa, self.coa_deg),
        ];
        let edges = [
            (Edge::Oa, self.at_oa_deg),
            (Edge::Ob, self.at_ob_deg),
            (Edge::Oc, self.at_oc_deg),
        ];
        let n_faces = faces.iter().filter(|(_, a)| a.is_some()).count();
        let n_edges = edges.iter().filter(|(_, a)| a.is_some()).count();
        if n_faces + n_edges != 3 {
            return Err(TrihedralError::AngleCount);
        }
        for (face, angle) in faces {
            if let Some(a) = angle {
                if !is_open_angle(a) {
                    return Err(TrihedralError::FaceAngleOutOfRange(face));
                }
            }
        }
        for (edge, angle) in edges {
            if let Some(a) = angle {
                if !is_open_angle(a) {
                    return Err(TrihedralError::LinearAngleOutOfRange(edge));
                }
            }
        }
        // The third side from two sides and the angle between them.
        let side = |b: f64, c: f64, a: f64| acosd(cosd(b) * cosd(c) + sind(b) * sind(c) * cosd(a));
        // The third angle from two angles and the side between them.
        let angle =
            |a: f64, b: f64, c: f64| acosd(-cosd(a) * cosd(b) + sind(a) * sind(b) * cosd(c));
        let s = self;
        match (
            s.aob_deg,
            s.boc_deg,
            s.coa_deg,
            s.at_oa_deg,
            s.at_ob_deg,
            s.at_oc_deg,
        ) {
            (Some(aob), Some(boc), Some(coa), None, None, None) => PlaneAngles::new(aob, boc, coa),
            (None, None, None, Some(oa), Some(ob), Some(oc)) => {
                PlaneAngles::from_linear_angles(oa, ob, oc)
            }
            // Faces AOB and COA meet at OA.
            (Some(aob), None, Some(coa), Some(oa), None, None) => {
                PlaneAngles::new(aob, side(aob, coa, oa), coa)
            }
            // Faces AOB and BOC meet at OB.
            (Some(aob), Some(boc), None, None, Some(ob), None) => {
                PlaneAngles::new(aob, boc, side(aob, boc, ob))
            }
            // Faces BOC and COA meet at OC.
            (None, Some(boc), Some(coa), None, None, Some(oc)) => {
                PlaneAngles::new(side(boc, coa, oc), boc, coa)
            }
            // Face AOB lies between edges OA and OB.
            (Some(aob), None, None, Some(oa), Some(ob), None) => {
                PlaneAngles::from_linear_angles(oa, ob, angle(oa, ob, aob))
            }
            // Face BOC lies between edges OB and OC.
            (None, Some(boc), None, None, Some(ob), Some(oc)) => {
                PlaneAngles::from_linear_angles(angle(ob, oc, boc), ob, oc)
            }
            // Face COA lies between edges OC and OA.
            (None, None, Some(coa), Some(oa), None, Some(oc)) => {
                PlaneAngles::from_linear_angles(oa, angle(oc, oa, coa), oc)
            }
            _ => Err(TrihedralError::AngleAmbiguous),
        }
    }
}

/// A point in a row's plane, mm, in the vertex frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Point2 {
    /// X, mm.
    pub x_mm: f64,
    /// Y, mm.
    pub y_mm: f64,
}

/// A point in space, mm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Point3 {
    /// X, mm.
    pub x_mm: f64,
    /// Y, mm.
    pub y_mm: f64,
    /// Z, mm.
    pub z_mm: f64,
}

/// One row: the section of the corner at height `z_mm` above the vertex,
/// the triangle `ABC` the cutter runs around, in the vertex frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Row {
    /// The row's height above the vertex, mm (`Z_n`).
    pub z_mm: f64,
    /// The point on edge `OA`: `(−r, −r/tan α_a)`, mm.
    pub a: Point2,
    /// The point on edge `OB`: `(−r, r/tan α_b)`, mm.
    pub b: Point2,
    /// The point on edge `OC`, mm (`x > 0`).
    pub c: Point2,
}

/// The corner's angles, degrees: what follows from the plane angles alone.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Corner {
    /// The plane angles it was computed from.
    pub plane: PlaneAngles,
    /// `φ`, the half-angle of the cone inscribed in the corner, degrees:
    /// the cutter's plan angle, and `90° − φ` the table's tilt.
    pub phi_deg: f64,
    /// `σ_a = s − BOC`: edge `OA`'s angle to the cone's tangent lines in
    /// faces `AOB` and `COA`, degrees.
    pub sigma_a_deg: f64,
    /// `σ_b = s − COA`, degrees.
    pub sigma_b_deg: f64,
    /// `σ_c = s − AOB`, degrees.
    pub sigma_c_deg: f64,
    /// `α_a`: half the row triangle's angle at `A`, degrees
    /// (`tan α_a = sin φ / tan σ_a`). `α_a + α_b + α_c = 90°`.
    pub alpha_a_deg: f64,
    /// `α_b`, half the row triangle's angle at `B`, degrees.
    pub alpha_b_deg: f64,
    /// `α_c`, half the row triangle's angle at `C`, degrees.
    pub alpha_c_deg: f64,
    /// The linear (dihedral) angle at edge `OA`, degrees.
    pub linear_oa_deg: f64,
    /// The linear angle at edge `OB`, degrees.
    pub linear_ob_deg: f64,
    /// The linear angle at edge `OC`, degrees.
    pub linear_oc_deg: f64,
    /// The central angle `AO'B` at the row's centre, degrees
    /// (`90° + α_c`).
    pub central_aob_deg: f64,
    /// The central angle `BO'C`, degrees (`90° + α_a`).
    pub central_boc_deg: f64,
    /// The central angle `CO'A`, degrees (`90° + α_b`).
    pub central_coa_deg: f64,
}

/// The edges whose `σ` is 90° or more, first of them.
fn check_edges_rise(sigma: [f64; 3]) -> Result<(), TrihedralError> {
    let edges = [Edge::Oa, Edge::Ob, Edge::Oc];
    for (edge, s) in edges.into_iter().zip(sigma) {
        if s.is_nan() || s >= 90.0 {
            return Err(TrihedralError::EdgeNotAboveVertex(edge));
        }
    }
    Ok(())
}

impl Corner {
    /// The corner by exact spherical trigonometry (`docs/calculators.md` §4.2).
    /// Refuses a corner with an edge not above the vertex along the cone
    /// axis (`σ ≥ 90°`).
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{Corner, PlaneAngles};
    /// let cube = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// assert!((cube.phi_deg - 35.26439).abs() < 5e-6);
    /// assert!((cube.alpha_a_deg - 30.0).abs() < 1e-12);
    /// assert!((cube.linear_oc_deg - 90.0).abs() < 1e-12);
    /// ```
    pub fn new(plane: PlaneAngles) -> Result<Self, TrihedralError> {
        let (s, sigma) = plane.sigmas();
        check_edges_rise(sigma)?;
        let [sa, sb, sc] = sigma;
        let tan2 = sind(sa) * sind(sb) * sind(sc) / sind(s);
        let phi = atan(sqrt(tan2)) / DEG;
        // tan α = sin φ / tan σ = sin φ·cos σ / sin σ.
        let alpha = |sg: f64| atan2(sind(phi) * cosd(sg), sind(sg)) / DEG;
        // tan(A/2) = tan φ / sin σ (the right spherical triangle I-D-A).
        let linear = |sg: f64| 2.0 * atan2(tand(phi), sind(sg)) / DEG;
        let (aa, ab, ac) = (alpha(sa), alpha(sb), alpha(sc));
        Ok(Corner {
            plane,
            phi_deg: phi,
            sigma_a_deg: sa,
            sigma_b_deg: sb,
            sigma_c_deg: sc,
            alpha_a_deg: aa,
            alpha_b_deg: ab,
            alpha_c_deg: ac,
            linear_oa_deg: linear(sa),
            linear_ob_deg: linear(sb),
            linear_oc_deg: linear(sc),
            central_aob_deg: 90.0 + ac,
            central_boc_deg: 90.0 + aa,
            central_coa_deg: 90.0 + ab,
        })
    }

    /// The paper's own method, for comparison only: central angles
    /// proportional to the plane angles (`k = 360°/ΣПУ`),
    /// `α_a = (180° − AOB' + BO'C − CO'A)/2` (and its siblings),
    /// `σ_i = (90° − α_i)/k` (which is `s − ` the opposite face, as exact),
    /// `φ = arcsin r` (exact), the linear angles by its eq. (4) from these
    /// `α`. Only `α`, the central angles, the linear angles and what
    /// depends on them (the `Y` of `A` and `B`, the point on `OC`) differ
    /// from [`Corner::new`], and only for corners that are not symmetric.
    /// Its domain is the paper's: each plane angle above a third of the
    /// other two.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{Corner, PlaneAngles};
    /// let p = PlaneAngles::new(60.0, 70.0, 80.0).unwrap();
    /// let paper = Corner::proportional(p).unwrap();
    /// let exact = Corner::new(p).unwrap();
    /// assert!((paper.phi_deg - exact.phi_deg).abs() < 1e-12);
    /// // α_a: the paper's 30°, exactly 29.005°.
    /// assert!((paper.alpha_a_deg - 30.0).abs() < 1e-12);
    /// assert!((exact.alpha_a_deg - 29.005037).abs() < 1e-6);
    /// ```
    pub fn proportional(plane: PlaneAngles) -> Result<Self, TrihedralError> {
        let k = 360.0 / (plane.aob + plane.boc + plane.coa);
        let (aob, boc, coa) = (k * plane.aob, k * plane.boc, k * plane.coa);
        let aa = (180.0 - aob + boc - coa) * 0.5;
        let ab = (180.0 - aob - boc + coa) * 0.5;
        let ac = (180.0 + aob - boc - coa) * 0.5;
        let faces = [(Face::Boc, aa), (Face::Coa, ab), (Face::Aob, ac)];
        for (face, alpha) in faces {
            if alpha.is_nan() || alpha <= 0.0 {
                return Err(TrihedralError::ProportionalFaceTooSmall(face));
            }
        }
        let (sa, sb, sc) = ((90.0 - aa) / k, (90.0 - ab) / k, (90.0 - ac) / k);
        // σ < 90°/k = ΣПУ/4 < 90° here, so every tangent is positive.
        let (ta, tb, tc) = (tand(sa), tand(sb), tand(sc));
        let (a, b, c) = (tb + tc, ta + tc, ta + tb);
        let p = ta + tb + tc;
        let r = sqrt(p * (p - a) * (p - b) * (p - c)) / p;
        let phi = asin(r.min(1.0)) / DEG;
        // Eq. (4): ЛУ = 2·atan(tan α / cos(atan(tan φ / sin α))).
        let linear = |alpha: f64| {
            let t = atan(tand(phi) / sind(alpha));
            2.0 * atan(tand(alpha) / cos(t)) / DEG
        };
        Ok(Corner {
            plane,
            phi_deg: phi,
            sigma_a_deg: sa,
            sigma_b_deg: sb,
            sigma_c_deg: sc,
            alpha_a_deg: aa,
            alpha_b_deg: ab,
            alpha_c_deg: ac,
            linear_oa_deg: linear(aa),
            linear_ob_deg: linear(ab),
            linear_oc_deg: linear(ac),
            central_aob_deg: aob,
            central_boc_deg: boc,
            central_coa_deg: coa,
        })
    }

    /// The row at height `z_mm` above the vertex (the paper's м.2, signs as
    /// decided in the module docs): `r = z·tan φ`, `A = (−r, −r/tan α_a)`,
    /// `B = (−r, r/tan α_b)`, `x_c = −r·(sin γ_a − sin γ_b)/sin(γ_a − γ_b)`,
    /// `y_c = (r + x_c·cos γ_a)/sin γ_a`, with `γ_a = 2(90° − α_b)`,
    /// `γ_b = 2(α_a − 90°)`.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{Corner, PlaneAngles};
    /// let cube = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// let row = cube.row(1.0);
    /// let r = 1.0 / 2f64.sqrt(); // tan φ
    /// assert!((row.a.x_mm + r).abs() < 1e-12 && (row.b.x_mm + r).abs() < 1e-12);
    /// assert!((row.b.y_mm - r * 3f64.sqrt()).abs() < 1e-12);
    /// assert!((row.c.x_mm - 2.0 * r).abs() < 1e-12 && row.c.y_mm.abs() < 1e-12);
    /// ```
    pub fn row(&self, z_mm: f64) -> Row {
        let r = z_mm * tand(self.phi_deg);
        let ga = 2.0 * (90.0 - self.alpha_b_deg);
        let gb = 2.0 * (self.alpha_a_deg - 90.0);
        let xc = -r * (sind(ga) - sind(gb)) / sind(ga - gb);
        let yc = (r + xc * cosd(ga)) / sind(ga);
        Row {
            z_mm,
            a: Point2 {
                x_mm: -r,
                y_mm: -r / tand(self.alpha_a_deg),
            },
            b: Point2 {
                x_mm: -r,
                y_mm: r / tand(self.alpha_b_deg),
            },
            c: Point2 { x_mm: xc, y_mm: yc },
        }
    }

    /// The point on an edge at `length_mm` from the vertex, in the vertex
    /// frame: `Z = L·cos φ·cos σ`, and `X`, `Y` those of the row at `Z`.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{Corner, Edge, PlaneAngles};
    /// let cube = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// let p = cube.edge_point(Edge::Oa, 10.0);
    /// // A cube's edges make arccos(1/√3) with its diagonal.
    /// assert!((p.z_mm - 10.0 / 3f64.sqrt()).abs() < 1e-12);
    /// let len = (p.x_mm * p.x_mm + p.y_mm * p.y_mm + p.z_mm * p.z_mm).sqrt();
    /// assert!((len - 10.0).abs() < 1e-12);
    /// ```
    pub fn edge_point(&self, edge: Edge, length_mm: f64) -> Point3 {
        let sigma = match edge {
            Edge::Oa => self.sigma_a_deg,
            Edge::Ob => self.sigma_b_deg,
            Edge::Oc => self.sigma_c_deg,
        };
        let z = length_mm * cosd(self.phi_deg) * cosd(sigma);
        let row = self.row(z);
        let p = match edge {
            Edge::Oa => row.a,
            Edge::Ob => row.b,
            Edge::Oc => row.c,
        };
        Point3 {
            x_mm: p.x_mm,
            y_mm: p.y_mm,
            z_mm: z,
        }
    }

    /// The height above the vertex of the far side of a ball of radius
    /// `radius_mm` laid in the corner, mm: `R·(1 + sin φ)/sin φ` (the
    /// paper's check of `z'`: `δz' = Z_ball − this − z'`).
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{Corner, PlaneAngles};
    /// let cube = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// // The ball's centre is √3·R from the cube's corner.
    /// assert!((cube.ball_far_side_mm(5.0) - 5.0 * (3f64.sqrt() + 1.0)).abs() < 1e-12);
    /// ```
    pub fn ball_far_side_mm(&self, radius_mm: f64) -> f64 {
        let s = sind(self.phi_deg);
        radius_mm * (1.0 + s) / s
    }
}

/// Which quadrant of the XY plane the base face `AOB` lies in (the paper's
/// `k_v`), the vertex taken as the origin and ray `OA` at angle `E` to X.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Quadrant {
    /// `k_v = 1`: `P = 180° − (σ_a + E)`.
    First,
    /// `k_v = 2`: `P = σ_a − E`.
    Second,
    /// `k_v = 3`: `P = −(σ_a + E)`.
    Third,
    /// `k_v = 4`: `P = −180° + (σ_a − E)`.
    Fourth,
}

impl Quadrant {
    /// The quadrant of the paper's `k_v`, 1 to 4; `None` otherwise.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::Quadrant;
    /// assert_eq!(Quadrant::from_number(3), Some(Quadrant::Third));
    /// assert_eq!(Quadrant::from_number(5), None);
    /// ```
    pub const fn from_number(k_v: u8) -> Option<Self> {
        match k_v {
            1 => Some(Quadrant::First),
            2 => Some(Quadrant::Second),
            3 => Some(Quadrant::Third),
            4 => Some(Quadrant::Fourth),
            _ => None,
        }
    }
}

/// A tilt-rotary table's parameters, mm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltRotaryTable {
    /// `L`: the distance between the tilt and the rotation axes, mm (0
    /// when they cross).
    pub axes_distance_mm: f64,
    /// `m`: the distance from the table's surface to the tilt axis, mm.
    pub surface_to_tilt_mm: f64,
}

/// The shift `(a, c)` of the program's origin along X and Z that a tilt
/// causes (the paper's eq. 6), mm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltShift {
    /// `a`, along X, mm.
    pub a_mm: f64,
    /// `c`, along Z, mm.
    pub c_mm: f64,
}

impl TiltRotaryTable {
    /// The shift of a tilt by `beta_deg` (eq. 5, 6): with `R = √(L² + m²)`
    /// and `tan Ψ = m/L`, `a = L − R·cos(Ψ + β)`, `c = R·sin(Ψ + β) − m`;
    /// computed as `a = L(1 − cos β) + m·sin β`,
    /// `c = L·sin β − m(1 − cos β)`, which needs no `Ψ` (the paper's
    /// `m/L` has no value at `L = 0`).
    ///
    /// ```
    /// use core_nostd::calc::trihedral::TiltRotaryTable;
    /// let t = TiltRotaryTable { axes_distance_mm: 100.0, surface_to_tilt_mm: 50.0 };
    /// let s = t.shift_for_tilt(90.0);
    /// assert!((s.a_mm - 150.0).abs() < 1e-12 && (s.c_mm - 50.0).abs() < 1e-12);
    /// let none = t.shift_for_tilt(0.0);
    /// assert_eq!((none.a_mm, none.c_mm), (0.0, 0.0));
    /// ```
    pub fn shift_for_tilt(&self, beta_deg: f64) -> TiltShift {
        let (l, m) = (self.axes_distance_mm, self.surface_to_tilt_mm);
        let (s, c) = (sind(beta_deg), cosd(beta_deg));
        TiltShift {
            a_mm: l * (1.0 - c) + m * s,
            c_mm: l * s - m * (1.0 - c),
        }
    }
}

/// The two measurements that give a table's parameters (the paper's last
/// section): a roller of known diameter clamped on the table, turned
/// parallel to Y, its axis found on a precise machine at tilt 0° and at
/// tilt 90°. All mm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableMeasurement {
    /// `Δx`: from the roller's axis to the table's rotation axis, mm.
    pub roller_to_rotation_axis_mm: f64,
    /// `Δz`: from the roller's axis to the table's surface, mm.
    pub roller_to_surface_mm: f64,
    /// `X₀`: the roller axis' X at tilt 0°, mm.
    pub x0_mm: f64,
    /// `Z₀`: the roller axis' Z at tilt 0°, mm.
    pub z0_mm: f64,
    /// `X₉₀`: the roller axis' X at tilt 90°, mm.
    pub x90_mm: f64,
    /// `Z₉₀`: the roller axis' Z at tilt 90°, mm.
    pub z90_mm: f64,
}

/// A table's parameters found from [`TableMeasurement`], with the shift
/// measured at 90°.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableParameters {
    /// The shift at tilt 90°: `a = (X₉₀ + Δz) − (X₀ + Δx)`,
    /// `c = (Z₉₀ − Δx) − (Z₀ + Δz)`, mm.
    pub shift_at_90: TiltShift,
    /// `L = (a + c)/2`, `m = (a − c)/2`, mm.
    pub table: TiltRotaryTable,
}

impl TableMeasurement {
    /// The table's `L` and `m` (eq. 6 at `β = 90°`: `a = L + m`,
    /// `c = L − m`).
    ///
    /// ```
    /// use core_nostd::calc::trihedral::{TableMeasurement, TiltRotaryTable};
    /// let m = TableMeasurement {
    ///     roller_to_rotation_axis_mm: 20.0,
    ///     roller_to_surface_mm: 15.0,
    ///     x0_mm: 120.0,
    ///     z0_mm: 65.0,
    ///     x90_mm: 265.0,
    ///     z90_mm: 135.0,
    /// };
    /// let p = m.solve().unwrap();
    /// assert_eq!((p.shift_at_90.a_mm, p.shift_at_90.c_mm), (140.0, 35.0));
    /// assert_eq!(p.table, TiltRotaryTable { axes_distance_mm: 87.5, surface_to_tilt_mm: 52.5 });
    /// ```
    pub fn solve(&self) -> Result<TableParameters, TrihedralError> {
        let all = [
            self.roller_to_rotation_axis_mm,
            self.roller_to_surface_mm,
            self.x0_mm,
            self.z0_mm,
            self.x90_mm,
            self.z90_mm,
        ];
        if !all.iter().all(|&x| is_length(x)) {
            return Err(TrihedralError::Measurement);
        }
        let (dx, dz) = (self.roller_to_rotation_axis_mm, self.roller_to_surface_mm);
        let a = (self.x90_mm + dz) - (self.x0_mm + dx);
        let c = (self.z90_mm - dx) - (self.z0_mm + dz);
        Ok(TableParameters {
            shift_at_90: TiltShift { a_mm: a, c_mm: c },
            table: TiltRotaryTable {
                axes_distance_mm: 0.5 * (a + c),
                surface_to_tilt_mm: 0.5 * (a - c),
            },
        })
    }
}

/// What the set-up needs besides the corner: the paper's inputs `h`, `КОН`,
/// `L_A`, `L_B`, `L_C`, `R_f`, `L`, `m`, `E`, `k_v` and the vertex `x, y, z`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Job {
    /// `h`: the step in Z between rows, and the first row's height above
    /// the vertex, mm.
    pub row_step_mm: f64,
    /// `КОН`: the number of rows, at heights `h, 2h, … КОН·h`.
    pub rows: u16,
    /// `L_A`: the length milled along edge `OA` to the vertex, mm.
    pub length_a_mm: f64,
    /// `L_B`: along edge `OB`, mm.
    pub length_b_mm: f64,
    /// `L_C`: along edge `OC`, mm.
    pub length_c_mm: f64,
    /// `R_f`: the radius of the fillet between the side faces (along `OC`)
    /// left by their pre-milling, mm; 0 for none.
    pub fillet_radius_mm: f64,
    /// The tilt-rotary table.
    pub table: TiltRotaryTable,
    /// `E`: the angle of ray `OA` to the X axis in the XY plane, degrees,
    /// negative clockwise; usually 0.
    pub oa_to_x_deg: f64,
    /// `k_v`: the quadrant the base face lies in.
    pub quadrant: Quadrant,
    /// The vertex in the part's (program's) frame before the table turns,
    /// mm.
    pub vertex: Point3,
}

/// The whole set-up: the corner, the table's angles, the edge points, the
/// start height and the vertex in the program's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Setup {
    /// The corner's angles.
    pub corner: Corner,
    /// `(X, Y, Z)_AO`: the point on edge `OA` at `L_A` from the vertex, in
    /// the vertex frame, mm.
    pub edge_a: Point3,
    /// `(X, Y, Z)_BO` at `L_B`, mm (`Y > 0`).
    pub edge_b: Point3,
    /// `(X, Y, Z)_CO` at `L_C`, mm (`X > 0`).
    pub edge_c: Point3,
    /// `Z_min`: the lowest start height above the vertex, mm: the highest
    /// edge point, plus `cos φ·R_f·(1 − sin(ЛУ_CO/2))/sin(ЛУ_CO/2)` when
    /// that is the point on `OC` (the paper's М01–М04).
    pub z_min_mm: f64,
    /// `P`: the table's rotation before the tilt, degrees, in
    /// (−180°, 180°].
    pub rotation_deg: f64,
    /// `P⁺`: the same rotation on a 0°…360° scale, degrees (0° for
    /// `P = 0`).
    pub rotation_positive_deg: f64,
    /// The table's tilt, `−(90° − φ)`, degrees.
    pub tilt_deg: f64,
    /// The shift `(a, c)` the tilt causes, mm.
    pub shift: TiltShift,
    /// The vertex after the rotation `P` (`X, Y, z`), mm:
    /// `X = x·cos P + y·sin P`, `Y = −x·sin P + y·cos P`.
    pub vertex_rotated: Point3,
    /// The vertex in the program's frame after the tilt (`x', Y, z'`), mm:
    /// `x' = X·sin φ − z·cos φ + a`, `z' = X·cos φ + z·sin φ + c` (axes
    /// turned by `+(90° − φ)`, old coordinates, then shifted by `(a, c)`).
    pub vertex_work: Point3,
    /// The start point `(x', Y, z' + Z_min)` in the program's frame, mm.
    pub start: Point3,
    /// `h`, mm.
    pub row_step_mm: f64,
    /// `КОН`.
    pub rows: u16,
    /// `R_f`, mm.
    pub fillet_radius_mm: f64,
}

impl Setup {
    /// The set-up of a corner for a job, in the paper's order. Pass
    /// [`Corner::new`] (exact) or, for comparison, [`Corner::proportional`].
    ///
    /// ```
    /// use core_nostd::calc::trihedral::*;
    /// let corner = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// let job = Job {
    ///     row_step_mm: 0.5,
    ///     rows: 10,
    ///     length_a_mm: 10.0,
    ///     length_b_mm: 10.0,
    ///     length_c_mm: 12.0,
    ///     fillet_radius_mm: 0.0,
    ///     table: TiltRotaryTable::default(),
    ///     oa_to_x_deg: 0.0,
    ///     quadrant: Quadrant::First,
    ///     vertex: Point3::default(),
    /// };
    /// let s = Setup::new(&corner, &job).unwrap();
    /// assert!((s.rotation_deg - 135.0).abs() < 1e-12);
    /// assert!((s.tilt_deg + 54.73561).abs() < 5e-6);
    /// assert!((s.z_min_mm - 12.0 / 3f64.sqrt()).abs() < 1e-12);
    /// ```
    pub fn new(corner: &Corner, job: &Job) -> Result<Self, TrihedralError> {
        if !is_positive_length(job.row_step_mm) {
            return Err(TrihedralError::RowStep);
        }
        if job.rows == 0 {
            return Err(TrihedralError::RowCount);
        }
        let lengths = [
            (Edge::Oa, job.length_a_mm),
            (Edge::Ob, job.length_b_mm),
            (Edge::Oc, job.length_c_mm),
        ];
        for (edge, length) in lengths {
            if !is_positive_length(length) {
                return Err(TrihedralError::EdgeLength(edge));
            }
        }
        if !(0.0..LIMIT).contains(&job.fillet_radius_mm) {
            return Err(TrihedralError::FilletRadius);
        }
        if job.oa_to_x_deg.is_nan() || fabs(job.oa_to_x_deg) > 360.0 {
            return Err(TrihedralError::OffsetAngle);
        }
        let t = job.table;
        if !(is_length(t.axes_distance_mm) && is_length(t.surface_to_tilt_mm)) {
            return Err(TrihedralError::TableParameter);
        }
        let v = job.vertex;
        if !(is_length(v.x_mm) && is_length(v.y_mm) && is_length(v.z_mm)) {
            return Err(TrihedralError::VertexCoordinate);
        }

        let edge_a = corner.edge_point(Edge::Oa, job.length_a_mm);
        let edge_b = corner.edge_point(Edge::Ob, job.length_b_mm);
        let edge_c = corner.edge_point(Edge::Oc, job.length_c_mm);

        // М01–М04: the highest edge point; the fillet only when it is on OC.
        let z_h = edge_a.z_mm.max(edge_b.z_mm);
        let z_min_mm = if edge_c.z_mm > z_h {
            let half = sind(0.5 * corner.linear_oc_deg);
            edge_c.z_mm + cosd(corner.phi_deg) * job.fillet_radius_mm * (1.0 - half) / half
        } else {
            z_h
        };

        let sa = corner.sigma_a_deg;
        let e = job.oa_to_x_deg;
        let p = match job.quadrant {
            Quadrant::First => 180.0 - (sa + e),
            Quadrant::Second => sa - e,
            Quadrant::Third => -(sa + e),
            Quadrant::Fourth => -180.0 + (sa - e),
        };
        let rotation_deg = wrap_half_turn(p);
        let rotation_positive_deg = if rotation_deg < 0.0 {
            rotation_deg + 360.0
        } else {
            rotation_deg
        };

        let phi = corner.phi_deg;
        let tilt_deg = -(90.0 - phi);
        let shift = t.shift_for_tilt(tilt_deg);
        let (sp, cp) = (sind(rotation_deg), cosd(rotation_deg));
        let vertex_rotated = Point3 {
            x_mm: v.x_mm * cp + v.y_mm * sp,
            y_mm: -v.x_mm * sp + v.y_mm * cp,
            z_mm: v.z_mm,
        };
        // Axes turned by +(90° − φ): cos(90° − φ) = sin φ, sin(90° − φ) = cos φ.
        let (sf, cf) = (sind(phi), cosd(phi));
        let big_x = vertex_rotated.x_mm;
        let vertex_work = Point3 {
            x_mm: big_x * sf - v.z_mm * cf + shift.a_mm,
            y_mm: vertex_rotated.y_mm,
            z_mm: big_x * cf + v.z_mm * sf + shift.c_mm,
        };
        let start = Point3 {
            z_mm: vertex_work.z_mm + z_min_mm,
            ..vertex_work
        };
        Ok(Setup {
            corner: *corner,
            edge_a,
            edge_b,
            edge_c,
            z_min_mm,
            rotation_deg,
            rotation_positive_deg,
            tilt_deg,
            shift,
            vertex_rotated,
            vertex_work,
            start,
            row_step_mm: job.row_step_mm,
            rows: job.rows,
            fillet_radius_mm: job.fillet_radius_mm,
        })
    }

    /// The paper's check of the vertex height `z'`: a ball of radius
    /// `ball_radius_mm` laid in the corner, the Z of its far side measured
    /// as `z_ball_mm` in the program's frame; the error is
    /// `δz' = Z_ball − R·(1 + sin φ)/sin φ − z'`, mm. The ball must be
    /// larger than the fillet (`R > R_f`), or the fillet holds it off the
    /// faces.
    ///
    /// ```
    /// # use core_nostd::calc::trihedral::*;
    /// # let corner = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// # let job = Job { row_step_mm: 0.5, rows: 10, length_a_mm: 10.0, length_b_mm: 10.0,
    /// #     length_c_mm: 10.0, fillet_radius_mm: 1.0, table: TiltRotaryTable::default(),
    /// #     oa_to_x_deg: 0.0, quadrant: Quadrant::First, vertex: Point3::default() };
    /// let s = Setup::new(&corner, &job).unwrap();
    /// let far = 5.0 * (3f64.sqrt() + 1.0); // a cube's corner, R 5 mm
    /// let dz = s.vertex_height_error_mm(far + 0.02, 5.0).unwrap();
    /// assert!((dz - 0.02).abs() < 1e-12);
    /// assert_eq!(s.vertex_height_error_mm(far, 1.0), Err(TrihedralError::BallRadius));
    /// ```
    pub fn vertex_height_error_mm(
        &self,
        z_ball_mm: f64,
        ball_radius_mm: f64,
    ) -> Result<f64, TrihedralError> {
        if !(ball_radius_mm > self.fillet_radius_mm && ball_radius_mm < LIMIT) {
            return Err(TrihedralError::BallRadius);
        }
        if !is_length(z_ball_mm) {
            return Err(TrihedralError::Measurement);
        }
        Ok(z_ball_mm - self.corner.ball_far_side_mm(ball_radius_mm) - self.vertex_work.z_mm)
    }

    /// Row `n` (1 to `КОН`) at `Z_n = n·h`; `None` for `n` 0 or above
    /// `КОН`.
    ///
    /// ```
    /// # use core_nostd::calc::trihedral::*;
    /// # let corner = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// # let job = Job { row_step_mm: 0.5, rows: 10, length_a_mm: 10.0, length_b_mm: 10.0,
    /// #     length_c_mm: 10.0, fillet_radius_mm: 0.0, table: TiltRotaryTable::default(),
    /// #     oa_to_x_deg: 0.0, quadrant: Quadrant::First, vertex: Point3::default() };
    /// let s = Setup::new(&corner, &job).unwrap();
    /// assert_eq!(s.row(4).map(|r| r.z_mm), Some(2.0));
    /// assert_eq!(s.row(0), None);
    /// assert_eq!(s.row(11), None);
    /// ```
    pub fn row(&self, n: u16) -> Option<Row> {
        if n == 0 || n > self.rows {
            return None;
        }
        Some(self.corner.row(f64::from(n) * self.row_step_mm))
    }

    /// The rows 1 to `КОН`, nearest the vertex first.
    ///
    /// ```
    /// # use core_nostd::calc::trihedral::*;
    /// # let corner = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// # let job = Job { row_step_mm: 0.5, rows: 10, length_a_mm: 10.0, length_b_mm: 10.0,
    /// #     length_c_mm: 10.0, fillet_radius_mm: 0.0, table: TiltRotaryTable::default(),
    /// #     oa_to_x_deg: 0.0, quadrant: Quadrant::First, vertex: Point3::default() };
    /// let s = Setup::new(&corner, &job).unwrap();
    /// assert_eq!(s.rows().count(), 10);
    /// assert_eq!(s.rows().last().map(|r| r.z_mm), Some(5.0));
    /// ```
    pub fn rows(&self) -> impl Iterator<Item = Row> + '_ {
        (1..=self.rows).map(|n| self.corner.row(f64::from(n) * self.row_step_mm))
    }

    /// Writes the program: a main program (table rotation and tilt, the
    /// approach to the start point, the local zero at the vertex, the edges
    /// milled to the vertex, the call of the rows) and the row subprogram
    /// (each row closed `A → B → C → A`, from the vertex outwards), ISO
    /// G-code between `%` lines. Millimetres with 3 decimals, degrees with
    /// 4, written through integers (no float formatting).
    ///
    /// ```
    /// # use core_nostd::calc::trihedral::*;
    /// # let corner = Corner::new(PlaneAngles::new(90.0, 90.0, 90.0).unwrap()).unwrap();
    /// # let job = Job { row_step_mm: 1.0, rows: 2, length_a_mm: 10.0, length_b_mm: 10.0,
    /// #     length_c_mm: 10.0, fillet_radius_mm: 0.0, table: TiltRotaryTable::default(),
    /// #     oa_to_x_deg: 0.0, quadrant: Quadrant::First, vertex: Point3::default() };
    /// let s = Setup::new(&corner, &job).unwrap();
    /// let mut text: heapless::String<2048> = heapless::String::new();
    /// s.write_program(&mut text, &ProgramOptions::default()).unwrap();
    /// assert!(text.contains("G0 C135.0000 (ROTATION P)\n"));
    /// assert!(text.contains("G0 B-54.7356 (TILT -(90-PHI))\n"));
    /// assert!(text.contains("M98 P1001 (ROWS)\n"));
    /// assert!(text.ends_with("M99\n%\n"));
    /// ```
    pub fn write_program<W: fmt::Write>(
        &self,
        w: &mut W,
        options: &ProgramOptions,
    ) -> Result<(), TrihedralError> {
        let o = options;
        if !(o.feed_mm_min > 0.0 && o.feed_mm_min < LIMIT) {
            return Err(TrihedralError::Feed);
        }
        let numbers_ok = |n: u16| (1..=9999).contains(&n);
        if !(numbers_ok(o.program_number) && numbers_ok(o.subprogram_number))
            || o.program_number == o.subprogram_number
        {
            return Err(TrihedralError::ProgramNumber);
        }
        let c = &self.corner;
        let mut out = Out { w };

        out.text("%\nO")?;
        out.int(o.program_number)?;
        out.text(" (TRIHEDRAL CORNER, LYAKUN-YURKEVICH)\n(AOB ")?;
        out.deg(c.plane.aob)?;
        out.text(" BOC ")?;
        out.deg(c.plane.boc)?;
        out.text(" COA ")?;
        out.deg(c.plane.coa)?;
        out.text(" DEG)\n(CUTTER PLAN ANGLE PHI ")?;
        out.deg(c.phi_deg)?;
        out.text(" DEG)\n(LINEAR ANGLES OA ")?;
        out.deg(c.linear_oa_deg)?;
        out.text(" OB ")?;
        out.deg(c.linear_ob_deg)?;
        out.text(" OC ")?;
        out.deg(c.linear_oc_deg)?;
        out.text(" DEG)\n(ZMIN ")?;
        out.mm(self.z_min_mm)?;
        out.text(" MM ABOVE THE VERTEX)\nG21 G90 G17 G40 G80\nG0 C")?;
        let rotation = if o.positive_rotation {
            self.rotation_positive_deg
        } else {
            self.rotation_deg
        };
        out.deg(rotation)?;
        out.text(" (ROTATION P)\nG0 B")?;
        out.deg(self.tilt_deg)?;
        out.text(" (TILT -(90-PHI))\nG0 X")?;
        out.mm(self.start.x_mm)?;
        out.text(" Y")?;
        out.mm(self.start.y_mm)?;
        out.text("\nG0 Z")?;
        out.mm(self.start.z_mm)?;
        out.text("\nG52 X")?;
        out.mm(self.vertex_work.x_mm)?;
        out.text(" Y")?;
        out.mm(self.vertex_work.y_mm)?;
        out.text(" Z")?;
        out.mm(self.vertex_work.z_mm)?;
        out.text(" (LOCAL ZERO AT THE VERTEX)\n")?;
        let edges = [
            ("OA", self.edge_a),
            ("OB", self.edge_b),
            ("OC", self.edge_c),
        ];
        for (name, p) in edges {
            out.text("(EDGE ")?;
            out.text(name)?;
            out.text(" TO THE VERTEX)\nG1 X")?;
            out.mm(p.x_mm)?;
            out.text(" Y")?;
            out.mm(p.y_mm)?;
            out.text(" Z")?;
            out.mm(p.z_mm)?;
            out.text(" F")?;
            out.feed(o.feed_mm_min)?;
            out.text("\nG1 X0.000 Y0.000 Z0.000\nG0 Z")?;
            out.mm(self.z_min_mm)?;
            out.text("\n")?;
        }
        out.text("M98 P")?;
        out.int(o.subprogram_number)?;
        out.text(" (ROWS)\nG0 Z")?;
        let top = self.z_min_mm.max(f64::from(self.rows) * self.row_step_mm);
        out.mm(top)?;
        out.text("\nG52 X0.000 Y0.000 Z0.000\nM30\nO")?;
        out.int(o.subprogram_number)?;
        out.text(" (TRIHEDRAL CORNER ROWS, H ")?;
        out.mm(self.row_step_mm)?;
        out.text(" MM)\n")?;
        let mut feed_written = false;
        for row in self.rows() {
            let corners = [row.a, row.b, row.c, row.a];
            for (i, p) in corners.iter().enumerate() {
                out.text("G1 X")?;
                out.mm(p.x_mm)?;
                out.text(" Y")?;
                out.mm(p.y_mm)?;
                if i == 0 {
                    out.text(" Z")?;
                    out.mm(row.z_mm)?;
                }
                if !feed_written {
                    out.text(" F")?;
                    out.feed(o.feed_mm_min)?;
                    feed_written = true;
                }
                out.text("\n")?;
            }
        }
        out.text("G1 X0.000 Y0.000\nM99\n%\n")
    }
}

/// Brings an angle into (−180°, 180°].
fn wrap_half_turn(deg: f64) -> f64 {
    let mut d = deg - 360.0 * round(deg / 360.0);
    if d <= -180.0 {
        d += 360.0;
    }
    if d > 180.0 {
        d -= 360.0;
    }
    d
}

/// How [`Setup::write_program`] writes the program.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ProgramOptions {
    /// The main program's number (`O`), 1 to 9999.
    pub program_number: u16,
    /// The row subprogram's number, 1 to 9999, not the main one's.
    pub subprogram_number: u16,
    /// The cutting feed, mm/min.
    pub feed_mm_min: f64,
    /// Write the rotation on the 0°…360° scale (`P⁺`) rather than `P`.
    pub positive_rotation: bool,
}

impl Default for ProgramOptions {
    /// O1000 with subprogram O1001, 100 mm/min, the signed rotation `P`.
    ///
    /// ```
    /// use core_nostd::calc::trihedral::ProgramOptions;
    /// assert_eq!(ProgramOptions::default().subprogram_number, 1001);
    /// ```
    fn default() -> Self {
        ProgramOptions {
            program_number: 1000,
            subprogram_number: 1001,
            feed_mm_min: 100.0,
            positive_rotation: false,
        }
    }
}

/// The program's text sink: numbers through integers, errors as
/// [`TrihedralError`].
struct Out<'a, W: fmt::Write> {
    w: &'a mut W,
}

impl<W: fmt::Write> Out<'_, W> {
    fn text(&mut self, s: &str) -> Result<(), TrihedralError> {
        self.w.write_str(s).map_err(|_| TrihedralError::Write)
    }

    fn int(&mut self, n: u16) -> Result<(), TrihedralError> {
        write!(self.w, "{n}").map_err(|_| TrihedralError::Write)
    }

    /// A length, 3 decimals.
    fn mm(&mut self, x: f64) -> Result<(), TrihedralError> {
        write_fixed(self.w, x, Decimals::Three)
    }

    /// An angle, 4 decimals.
    fn deg(&mut self, x: f64) -> Result<(), TrihedralError> {
        write_fixed(self.w, x, Decimals::Four)
    }

    /// A feed, 1 decimal.
    fn feed(&mut self, x: f64) -> Result<(), TrihedralError> {
        write_fixed(self.w, x, Decimals::One)
    }
}

/// How many decimals [`write_fixed`] writes.
#[derive(Clone, Copy)]
enum Decimals {
    One,
    Three,
    Four,
}

/// Writes `x` rounded half away from zero to a fixed number of decimals,
/// through integers: `round(x·10^k)` as an i64, its sign, its integer part
/// and its `k` decimals, zeros kept ("-12.300", "0.000": no "-0.000").
/// Refuses a value that is not finite or whose magnitude rounds to 100 000
/// or more, so the i64 holds it with room (|n| < 10⁹).
fn write_fixed<W: fmt::Write>(w: &mut W, x: f64, decimals: Decimals) -> Result<(), TrihedralError> {
    let (scale, width): (u64, usize) = match decimals {
        Decimals::One => (10, 1),
        Decimals::Three => (1000, 3),
        Decimals::Four => (10_000, 4),
    };
    // `scale` is at most 10⁴, exact in f64; u64 → f64 of it is exact.
    let scaled = round(x * scale as f64);
    // NaN and ±∞ fail this test too.
    if scaled.is_nan() || fabs(scaled) >= LIMIT * scale as f64 {
        return Err(TrihedralError::NumberOutOfRange);
    }
    // |scaled| < 10⁹: the cast is exact.
    let n = scaled as i64;
    let sign = if n < 0 { "-" } else { "" };
    let m = n.unsigned_abs();
    let (whole, frac) = (m / scale, m % scale);
    write!(w, "{sign}{whole}.{frac:0width$}").map_err(|_| TrihedralError::Write)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        fabs(a - b) <= tol
    }

    fn plane(aob: f64, boc: f64, coa: f64) -> PlaneAngles {
        match PlaneAngles::new(aob, boc, coa) {
            Ok(p) => p,
            Err(e) => panic!("{aob} {boc} {coa}: {e}"),
        }
    }

    fn exact(aob: f64, boc: f64, coa: f64) -> Corner {
        match Corner::new(plane(aob, boc, coa)) {
            Ok(c) => c,
            Err(e) => panic!("{aob} {boc} {coa}: {e}"),
        }
    }

    fn job() -> Job {
        Job {
            row_step_mm: 0.5,
            rows: 8,
            length_a_mm: 10.0,
            length_b_mm: 11.0,
            length_c_mm: 12.0,
            fillet_radius_mm: 0.0,
            table: TiltRotaryTable::default(),
            oa_to_x_deg: 0.0,
            quadrant: Quadrant::First,
            vertex: Point3::default(),
        }
    }

    fn setup(corner: &Corner, job: &Job) -> Setup {
        match Setup::new(corner, job) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        }
    }

    // --- 3-D helpers for the self-consistency checks -----------------------

    type V = [f64; 3];

    fn dot(u: V, v: V) -> f64 {
        u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    }

    fn cross(u: V, v: V) -> V {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    }

    fn angle_deg(u: V, v: V) -> f64 {
        acosd(dot(u, v) / sqrt(dot(u, u) * dot(v, v)))
    }

    fn v3(p: Point3) -> V {
        [p.x_mm, p.y_mm, p.z_mm]
    }

    fn v2(p: Point2, z: f64) -> V {
        [p.x_mm, p.y_mm, z]
    }

    /// The paper's only printed numbers: its "test table" of eq. (3). Each
    /// of its six triples gives central angles summing to 360° (its Δ of
    /// 2–3·10⁻⁶ is the calculator's last digit; f64 gives 0 within 10⁻¹²),
    /// equal triples give 120° each (printed "119,9(9)"), and 2°, 3°, 4°
    /// give 80°, 120°, 160°. The sum is 360° for any triple by eq. (3)
    /// itself, so the table cannot test the proportionality (1); the exact
    /// central angles (below) differ from it.
    #[test]
    fn paper_test_table() {
        let table: [([f64; 3], Option<[f64; 3]>); 6] = [
            ([90.0, 90.0, 90.0], Some([120.0, 120.0, 120.0])),
            ([115.0, 115.0, 115.0], Some([120.0, 120.0, 120.0])),
            ([3.0, 3.0, 3.0], Some([120.0, 120.0, 120.0])),
            ([2.0, 3.0, 4.0], Some([80.0, 120.0, 160.0])),
            ([121.0, 118.0, 120.0], None),
            ([151.0, 2.0, 150.0], None),
        ];
        for ([a, b, c], each) in table {
            let central = plane(a, b, c).proportional_central_angles_deg();
            let sum: f64 = central.iter().sum();
            assert!(close(sum, 360.0, 1e-12), "{a} {b} {c}: {sum}");
            if let Some(each) = each {
                for (got, want) in central.iter().zip(each) {
                    assert!(close(*got, want, 1e-12));
                }
            }
        }
        // The exact central angles of row 1-3 (symmetric) are the same 120°;
        // row 5 shows the proportional ones are off.
        for t in [90.0, 115.0, 3.0] {
            let c = exact(t, t, t);
            for got in [c.central_aob_deg, c.central_boc_deg, c.central_coa_deg] {
                assert!(close(got, 120.0, 1e-9));
            }
        }
        // Row 4 (2°, 3°, 4°): the paper's 80°, 120°, 160° are exactly
        // 104.472°, 113.284°, 142.244°; row 5 is off by 0.008°.
        let c = exact(2.0, 3.0, 4.0);
        let sum = c.central_aob_deg + c.central_boc_deg + c.central_coa_deg;
        assert!(close(sum, 360.0, 1e-9));
        assert!(close(c.central_aob_deg, 104.471_877_100, 1e-8));
        assert!(close(c.central_boc_deg, 113.283_732_236, 1e-8));
        assert!(close(c.central_coa_deg, 142.244_390_664, 1e-8));
        let c = exact(121.0, 118.0, 120.0);
        assert!(close(c.central_aob_deg, 121.328_912_654, 1e-8));
        assert!(close(121.0 * 360.0 / 359.0, 121.337_047_354, 1e-8));
        // Row 6 breaks the paper's own input rule (the least plane angle
        // above a third of the other two) and is not millable: edge OA
        // has σ_a = 149.5°, it runs below the vertex.
        assert_eq!(
            Corner::new(plane(151.0, 2.0, 150.0)),
            Err(TrihedralError::EdgeNotAboveVertex(Edge::Oa))
        );
        assert_eq!(
            Corner::proportional(plane(151.0, 2.0, 150.0)),
            Err(TrihedralError::ProportionalFaceTooSmall(Face::Boc))
        );
        // Rows 1-3 and 5 are in both methods' domain. Row 4 breaks the
        // paper's rule too (2° is not above (3° + 4°)/3: its proportional
        // α_c = 80° − 90° < 0), yet it is a millable corner.
        for [a, b, c] in [
            [90.0, 90.0, 90.0],
            [115.0, 115.0, 115.0],
            [3.0, 3.0, 3.0],
            [121.0, 118.0, 120.0],
        ] {
            assert!(Corner::new(plane(a, b, c)).is_ok());
            assert!(Corner::proportional(plane(a, b, c)).is_ok());
        }
        assert!(Corner::new(plane(2.0, 3.0, 4.0)).is_ok());
        assert_eq!(
            Corner::proportional(plane(2.0, 3.0, 4.0)),
            Err(TrihedralError::ProportionalFaceTooSmall(Face::Aob))
        );
    }

    #[test]
    fn cube_corner() {
        let c = exact(90.0, 90.0, 90.0);
        assert!(close(c.phi_deg, 35.26439, 5e-6));
        assert!(close(c.phi_deg, atan(1.0 / sqrt(2.0)) / DEG, 1e-12));
        for s in [c.sigma_a_deg, c.sigma_b_deg, c.sigma_c_deg] {
            assert!(close(s, 45.0, 1e-12));
        }
        for a in [c.alpha_a_deg, c.alpha_b_deg, c.alpha_c_deg] {
            assert!(close(a, 30.0, 1e-12));
        }
        for l in [c.linear_oa_deg, c.linear_ob_deg, c.linear_oc_deg] {
            assert!(close(l, 90.0, 1e-12));
        }
        // The paper's method is exact for a symmetric corner.
        let p = match Corner::proportional(c.plane) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        for (x, y) in [
            (p.phi_deg, c.phi_deg),
            (p.alpha_a_deg, c.alpha_a_deg),
            (p.alpha_b_deg, c.alpha_b_deg),
            (p.alpha_c_deg, c.alpha_c_deg),
            (p.linear_oa_deg, c.linear_oa_deg),
            (p.linear_oc_deg, c.linear_oc_deg),
        ] {
            assert!(close(x, y, 1e-12));
        }
        // Edge points: the cube's edges at 10 mm, mutually perpendicular.
        let s = setup(
            &c,
            &Job {
                length_b_mm: 10.0,
                length_c_mm: 10.0,
                ..job()
            },
        );
        let (a, b, cc) = (v3(s.edge_a), v3(s.edge_b), v3(s.edge_c));
        for e in [a, b, cc] {
            assert!(close(dot(e, e), 100.0, 1e-10));
            assert!(close(e[2], 10.0 / sqrt(3.0), 1e-12));
        }
        assert!(close(dot(a, b), 0.0, 1e-10));
        assert!(close(dot(b, cc), 0.0, 1e-10));
        assert!(close(dot(cc, a), 0.0, 1e-10));
        assert!(close(s.edge_b.y_mm, 10.0 / sqrt(2.0), 1e-12));
        assert!(close(s.edge_c.x_mm, 2.0 * 10.0 / sqrt(6.0), 1e-12));
        assert!(close(s.rotation_deg, 135.0, 1e-12));
        assert!(close(s.tilt_deg, -54.735_610_317, 1e-9));
    }

    /// For corners across the domain, the vertex frame's edges have the
    /// plane angles asked for, the dihedral angles between the face planes
    /// are the linear angles, each row point lies on its edge, and the
    /// paper's forms (φ = arcsin r, eq. 4, the γ form of `C`) agree with
    /// the closed ones.
    #[test]
    fn exact_corner_is_consistent_in_3d() {
        let triples = [
            [60.0, 70.0, 80.0],
            [121.0, 118.0, 120.0],
            [2.0, 3.0, 4.0],
            [100.0, 45.0, 70.0],
            [30.0, 100.0, 109.0],
            [150.0, 100.0, 100.0],
            [95.0, 92.0, 91.0],
        ];
        for [aob, boc, coa] in triples {
            let c = exact(aob, boc, coa);
            let s = setup(&c, &job());
            let (a, b, cc) = (v3(s.edge_a), v3(s.edge_b), v3(s.edge_c));
            assert!(close(angle_deg(a, b), aob, 1e-9), "{aob} {boc} {coa}");
            assert!(close(angle_deg(b, cc), boc, 1e-9), "{aob} {boc} {coa}");
            assert!(close(angle_deg(cc, a), coa, 1e-9), "{aob} {boc} {coa}");
            for (e, len) in [(a, 10.0), (b, 11.0), (cc, 12.0)] {
                assert!(close(sqrt(dot(e, e)), len, 1e-9));
            }
            assert!(s.edge_b.y_mm > 0.0 && s.edge_a.y_mm < 0.0 && s.edge_c.x_mm > 0.0);
            // Dihedral angles between the face planes, inside the corner.
            let dihedral = |e: V, f: V, g: V| angle_deg(cross(e, f), cross(e, g));
            assert!(close(dihedral(a, b, cc), c.linear_oa_deg, 1e-8));
            assert!(close(dihedral(b, a, cc), c.linear_ob_deg, 1e-8));
            assert!(close(dihedral(cc, a, b), c.linear_oc_deg, 1e-8));
            // The axis makes φ with every face: its normal at 90° − φ.
            let z = [0.0, 0.0, 1.0];
            for n in [cross(a, b), cross(b, cc), cross(cc, a)] {
                assert!(close(fabs(90.0 - angle_deg(n, z)), c.phi_deg, 1e-9));
            }
            // Row points lie on the edges.
            let row = c.row(3.0);
            for (p, e) in [(row.a, a), (row.b, b), (row.c, cc)] {
                let q = v2(p, 3.0);
                assert!(close(sqrt(dot(cross(q, e), cross(q, e))), 0.0, 1e-9));
                assert!(dot(q, e) > 0.0);
            }
            // α sum to 90°; the central angles to 360°.
            assert!(close(
                c.alpha_a_deg + c.alpha_b_deg + c.alpha_c_deg,
                90.0,
                1e-9
            ));
            // The paper's φ = arcsin r, r the in-radius of tangent lengths tan σ.
            let t = [
                tand(c.sigma_a_deg),
                tand(c.sigma_b_deg),
                tand(c.sigma_c_deg),
            ];
            let r = sqrt(t[0] * t[1] * t[2] / (t[0] + t[1] + t[2]));
            assert!(close(asin(r) / DEG, c.phi_deg, 1e-9));
            // Eq. (4) with the exact α gives the exact linear angles.
            for (alpha, lin) in [
                (c.alpha_a_deg, c.linear_oa_deg),
                (c.alpha_b_deg, c.linear_ob_deg),
                (c.alpha_c_deg, c.linear_oc_deg),
            ] {
                let t = atan(tand(c.phi_deg) / sind(alpha));
                assert!(close(2.0 * atan(tand(alpha) / cos(t)) / DEG, lin, 1e-9));
            }
            // x_c = r·cos(α_a − α_b)/sin α_c, y_c = r·sin(α_b − α_a)/sin α_c.
            let r3 = 3.0 * tand(c.phi_deg);
            let k = r3 / sind(c.alpha_c_deg);
            assert!(close(
                row.c.x_mm,
                k * cosd(c.alpha_a_deg - c.alpha_b_deg),
                1e-9
            ));
            assert!(close(
                row.c.y_mm,
                k * sind(c.alpha_b_deg - c.alpha_a_deg),
                1e-9
            ));
        }
    }

    /// The paper's proportional α against the exact one for an
    /// asymmetric corner: φ and σ agree, α and the linear angles do not,
    /// and the paper's edges no longer have the plane angles asked for.
    #[test]
    fn proportional_alpha_differs() {
        let p = plane(60.0, 70.0, 80.0);
        let e = exact(60.0, 70.0, 80.0);
        let q = match Corner::proportional(p) {
            Ok(q) => q,
            Err(err) => panic!("{err}"),
        };
        assert!(close(q.phi_deg, e.phi_deg, 1e-12));
        assert!(close(e.phi_deg, 22.843_281_555, 1e-8));
        assert!(close(q.sigma_a_deg, 35.0, 1e-12) && close(e.sigma_a_deg, 35.0, 1e-12));
        assert!(close(q.sigma_b_deg, 25.0, 1e-12) && close(q.sigma_c_deg, 45.0, 1e-12));
        // The paper: α = (30°, 47.143°, 12.857°); exact (29.005°, 39.778°, 21.217°).
        assert!(close(q.alpha_a_deg, 30.0, 1e-12));
        assert!(close(q.alpha_b_deg, 47.142_857_143, 1e-8));
        assert!(close(q.alpha_c_deg, 12.857_142_857, 1e-8));
        assert!(close(e.alpha_a_deg, 29.005_037_346, 1e-8));
        assert!(close(e.alpha_b_deg, 39.778_160_070, 1e-8));
        assert!(close(e.alpha_c_deg, 21.216_802_583, 1e-8));
        assert!(close(e.linear_oa_deg, 72.589_187_889, 1e-8));
        assert!(close(e.linear_ob_deg, 89.814_262_675, 1e-8));
        assert!(close(e.linear_oc_deg, 61.567_738_131, 1e-8));
        assert!(fabs(q.linear_oc_deg - e.linear_oc_deg) > 1.0);
        let s = setup(&q, &job());
        let (a, b, c) = (v3(s.edge_a), v3(s.edge_b), v3(s.edge_c));
        assert!(fabs(angle_deg(b, c) - 70.0) > 0.5);
        // Its edge points have the exact heights (same σ and φ), but not
        // the lengths asked for.
        let se = setup(&e, &job());
        assert!(close(s.edge_c.z_mm, se.edge_c.z_mm, 1e-12));
        assert!(fabs(sqrt(dot(c, c)) - 12.0) > 0.01);
        assert!(close(a[0], se.edge_a.x_mm, 1e-12));
    }

    #[test]
    fn mixed_angles_solve_in_closed_form() {
        let e = exact(60.0, 70.0, 80.0);
        let (oa, ob, oc) = (e.linear_oa_deg, e.linear_ob_deg, e.linear_oc_deg);
        let cases = [
            CornerAngles {
                aob_deg: Some(60.0),
                boc_deg: Some(70.0),
                coa_deg: Some(80.0),
                ..Default::default()
            },
            CornerAngles {
                at_oa_deg: Some(oa),
                at_ob_deg: Some(ob),
                at_oc_deg: Some(oc),
                ..Default::default()
            },
            CornerAngles {
                aob_deg: Some(60.0),
                coa_deg: Some(80.0),
                at_oa_deg: Some(oa),
                ..Default::default()
            },
            CornerAngles {
                aob_deg: Some(60.0),
                boc_deg: Some(70.0),
                at_ob_deg: Some(ob),
                ..Default::default()
            },
            CornerAngles {
                boc_deg: Some(70.0),
                coa_deg: Some(80.0),
                at_oc_deg: Some(oc),
                ..Default::default()
            },
            CornerAngles {
                aob_deg: Some(60.0),
                at_oa_deg: Some(oa),
                at_ob_deg: Some(ob),
                ..Default::default()
            },
            CornerAngles {
                boc_deg: Some(70.0),
                at_ob_deg: Some(ob),
                at_oc_deg: Some(oc),
                ..Default::default()
            },
            CornerAngles {
                coa_deg: Some(80.0),
                at_oa_deg: Some(oa),
                at_oc_deg: Some(oc),
                ..Default::default()
            },
        ];
        for given in cases {
            let p = match given.solve() {
                Ok(p) => p,
                Err(err) => panic!("{given:?}: {err}"),
            };
            assert!(close(p.aob_deg(), 60.0, 1e-9), "{given:?}");
            assert!(close(p.boc_deg(), 70.0, 1e-9), "{given:?}");
            assert!(close(p.coa_deg(), 80.0, 1e-9), "{given:?}");
        }
        let ambiguous = [
            CornerAngles {
                aob_deg: Some(60.0),
                boc_deg: Some(70.0),
                at_oa_deg: Some(oa),
                ..Default::default()
            },
            CornerAngles {
                aob_deg: Some(60.0),
                at_oa_deg: Some(oa),
                at_oc_deg: Some(oc),
                ..Default::default()
            },
        ];
        for given in ambiguous {
            assert_eq!(given.solve(), Err(TrihedralError::AngleAmbiguous));
        }
        let four = CornerAngles {
            at_oc_deg: Some(oc),
            ..cases[0]
        };
        assert_eq!(four.solve(), Err(TrihedralError::AngleCount));
        assert_eq!(
            CornerAngles::default().solve(),
            Err(TrihedralError::AngleCount)
        );
        let bad = CornerAngles {
            at_ob_deg: Some(180.0),
            ..cases[5]
        };
        assert_eq!(
            bad.solve(),
            Err(TrihedralError::LinearAngleOutOfRange(Edge::Ob))
        );
        let bad = CornerAngles {
            aob_deg: Some(f64::NAN),
            ..cases[2]
        };
        assert_eq!(
            bad.solve(),
            Err(TrihedralError::FaceAngleOutOfRange(Face::Aob))
        );
    }

    #[test]
    fn plane_angle_domain() {
        use TrihedralError as E;
        assert_eq!(
            PlaneAngles::new(0.0, 90.0, 90.0),
            Err(E::FaceAngleOutOfRange(Face::Aob))
        );
        assert_eq!(
            PlaneAngles::new(90.0, 180.0, 90.0),
            Err(E::FaceAngleOutOfRange(Face::Boc))
        );
        assert_eq!(
            PlaneAngles::new(90.0, 90.0, -5.0),
            Err(E::FaceAngleOutOfRange(Face::Coa))
        );
        assert_eq!(
            PlaneAngles::new(90.0, f64::NAN, 90.0),
            Err(E::FaceAngleOutOfRange(Face::Boc))
        );
        assert_eq!(
            PlaneAngles::new(f64::INFINITY, 90.0, 90.0),
            Err(E::FaceAngleOutOfRange(Face::Aob))
        );
        // Equal to the sum of the other two: a flat, degenerate corner.
        assert_eq!(
            PlaneAngles::new(100.0, 40.0, 60.0),
            Err(E::FaceAngleNotBelowOthers(Face::Aob))
        );
        assert_eq!(
            PlaneAngles::new(10.0, 40.0, 60.0),
            Err(E::FaceAngleNotBelowOthers(Face::Coa))
        );
        assert_eq!(
            PlaneAngles::new(120.0, 120.0, 120.0),
            Err(E::FaceAngleSumTooLarge)
        );
        assert_eq!(
            PlaneAngles::new(170.0, 100.0, 100.0),
            Err(E::FaceAngleSumTooLarge)
        );
        // A corner, but edge OC runs below the vertex (σ_c = 90° exactly, and more).
        assert_eq!(
            Corner::new(plane(30.0, 100.0, 110.0)),
            Err(E::EdgeNotAboveVertex(Edge::Oc))
        );
        assert_eq!(
            Corner::new(plane(20.0, 100.0, 110.0)),
            Err(E::EdgeNotAboveVertex(Edge::Oc))
        );
        assert_eq!(
            Corner::new(plane(170.0, 170.0, 10.0)),
            Err(E::EdgeNotAboveVertex(Edge::Ob))
        );
        // Linear angles.
        assert_eq!(
            PlaneAngles::from_linear_angles(60.0, 60.0, 60.0),
            Err(E::LinearAngleSumTooSmall)
        );
        assert_eq!(
            PlaneAngles::from_linear_angles(10.0, 100.0, 100.0),
            Err(E::LinearAngleTooSmall(Edge::Oa))
        );
        assert_eq!(
            PlaneAngles::from_linear_angles(90.0, 0.0, 90.0),
            Err(E::LinearAngleOutOfRange(Edge::Ob))
        );
        // The paper's own rule, only for its method.
        let p = plane(40.0, 70.0, 80.0);
        assert!(Corner::new(p).is_ok());
        assert_eq!(
            Corner::proportional(p),
            Err(E::ProportionalFaceTooSmall(Face::Aob))
        );
    }

    #[test]
    fn job_domain() {
        use TrihedralError as E;
        let c = exact(90.0, 90.0, 90.0);
        let j = job();
        let cases = [
            (
                Job {
                    row_step_mm: 0.0,
                    ..j
                },
                E::RowStep,
            ),
            (
                Job {
                    row_step_mm: f64::NAN,
                    ..j
                },
                E::RowStep,
            ),
            (Job { rows: 0, ..j }, E::RowCount),
            (
                Job {
                    length_a_mm: -1.0,
                    ..j
                },
                E::EdgeLength(Edge::Oa),
            ),
            (
                Job {
                    length_b_mm: 0.0,
                    ..j
                },
                E::EdgeLength(Edge::Ob),
            ),
            (
                Job {
                    length_c_mm: 1e6,
                    ..j
                },
                E::EdgeLength(Edge::Oc),
            ),
            (
                Job {
                    fillet_radius_mm: -0.1,
                    ..j
                },
                E::FilletRadius,
            ),
            (
                Job {
                    oa_to_x_deg: 400.0,
                    ..j
                },
                E::OffsetAngle,
            ),
            (
                Job {
                    oa_to_x_deg: f64::NAN,
                    ..j
                },
                E::OffsetAngle,
            ),
            (
                Job {
                    table: TiltRotaryTable {
                        axes_distance_mm: f64::INFINITY,
                        surface_to_tilt_mm: 0.0,
                    },
                    ..j
                },
                E::TableParameter,
            ),
            (
                Job {
                    vertex: Point3 {
                        x_mm: f64::NAN,
                        ..Point3::default()
                    },
                    ..j
                },
                E::VertexCoordinate,
            ),
        ];
        for (bad, want) in cases {
            assert_eq!(Setup::new(&c, &bad), Err(want));
        }
        let m = TableMeasurement {
            x90_mm: f64::NAN,
            ..TableMeasurement::default()
        };
        assert_eq!(m.solve(), Err(E::Measurement));
    }

    #[test]
    fn z_min_and_fillet() {
        let c = exact(90.0, 90.0, 90.0);
        // OC highest: the fillet adds cos φ·R·(1 − sin 45°)/sin 45°.
        let s = setup(
            &c,
            &Job {
                fillet_radius_mm: 2.0,
                ..job()
            },
        );
        let add = cosd(c.phi_deg) * 2.0 * (sqrt(2.0) - 1.0);
        assert!(close(s.z_min_mm, 12.0 / sqrt(3.0) + add, 1e-12));
        // OB highest: no fillet (it is on OC only).
        let s = setup(
            &c,
            &Job {
                fillet_radius_mm: 2.0,
                length_b_mm: 13.0,
                ..job()
            },
        );
        assert!(close(s.z_min_mm, 13.0 / sqrt(3.0), 1e-12));
        // Tie between OA and OC: the paper's strict ">" keeps OA, no fillet.
        let s = setup(
            &c,
            &Job {
                fillet_radius_mm: 2.0,
                length_a_mm: 12.0,
                ..job()
            },
        );
        assert!(close(s.z_min_mm, 12.0 / sqrt(3.0), 1e-12));
        // The ball check: a ball touching the three faces.
        let r = 3.0;
        let centre = r / sind(c.phi_deg);
        assert!(close(c.ball_far_side_mm(r), centre + r, 1e-12));
    }

    #[test]
    fn rotation_and_positive_scale() {
        let c = exact(90.0, 90.0, 90.0); // σ_a = 45°
        let cases = [
            (Quadrant::First, 0.0, 135.0, 135.0),
            (Quadrant::Second, 0.0, 45.0, 45.0),
            (Quadrant::Third, 0.0, -45.0, 315.0),
            (Quadrant::Fourth, 0.0, -135.0, 225.0),
            (Quadrant::Second, 45.0, 0.0, 0.0),
            (Quadrant::First, -45.0, 180.0, 180.0),
            (Quadrant::First, -100.0, -125.0, 235.0),
            (Quadrant::Third, 315.0, 0.0, 0.0),
        ];
        for (quadrant, e, p, p_pos) in cases {
            let s = setup(
                &c,
                &Job {
                    quadrant,
                    oa_to_x_deg: e,
                    ..job()
                },
            );
            assert!(
                close(s.rotation_deg, p, 1e-9),
                "{quadrant:?} {e}: {}",
                s.rotation_deg
            );
            assert!(
                close(s.rotation_positive_deg, p_pos, 1e-9),
                "{quadrant:?} {e}"
            );
        }
        assert_eq!(Quadrant::from_number(0), None);
        assert_eq!(Quadrant::from_number(1), Some(Quadrant::First));
        assert_eq!(Quadrant::from_number(4), Some(Quadrant::Fourth));
    }

    #[test]
    fn vertex_transform() {
        let c = exact(90.0, 90.0, 90.0);
        let table = TiltRotaryTable {
            axes_distance_mm: 30.0,
            surface_to_tilt_mm: 40.0,
        };
        let vertex = Point3 {
            x_mm: 10.0,
            y_mm: 20.0,
            z_mm: 5.0,
        };
        let s = setup(
            &c,
            &Job {
                table,
                vertex,
                quadrant: Quadrant::Second,
                ..job()
            },
        );
        // P = 45°: X = (10 + 20)/√2, Y = (20 − 10)/√2.
        let h = 1.0 / sqrt(2.0);
        assert!(close(s.vertex_rotated.x_mm, 30.0 * h, 1e-12));
        assert!(close(s.vertex_rotated.y_mm, 10.0 * h, 1e-12));
        assert!(close(s.vertex_rotated.z_mm, 5.0, 0.0));
        // (a, c) by eq. (5), (6) with Ψ.
        let beta = s.tilt_deg;
        let psi = atan2(40.0, 30.0) / DEG;
        let r = 50.0;
        assert!(close(s.shift.a_mm, 30.0 - r * cosd(psi + beta), 1e-12));
        assert!(close(s.shift.c_mm, r * sind(psi + beta) - 40.0, 1e-12));
        // Axes turned by +(90° − φ), old coordinates, then shifted.
        let t = 90.0 - c.phi_deg;
        let x = s.vertex_rotated.x_mm;
        assert!(close(
            s.vertex_work.x_mm,
            x * cosd(t) - 5.0 * sind(t) + s.shift.a_mm,
            1e-12
        ));
        assert!(close(
            s.vertex_work.z_mm,
            x * sind(t) + 5.0 * cosd(t) + s.shift.c_mm,
            1e-12
        ));
        assert!(close(s.vertex_work.y_mm, s.vertex_rotated.y_mm, 0.0));
        assert!(close(s.start.z_mm, s.vertex_work.z_mm + s.z_min_mm, 0.0));
        // L = 0 (crossing axes): no Ψ needed.
        let t0 = TiltRotaryTable {
            axes_distance_mm: 0.0,
            surface_to_tilt_mm: 40.0,
        };
        let sh = t0.shift_for_tilt(90.0);
        assert!(close(sh.a_mm, 40.0, 1e-12) && close(sh.c_mm, -40.0, 1e-12));
    }

    /// The table's parameters from the two measurements round-trip through
    /// eq. (6): a table with known L, m gives measurements whose solution is
    /// L, m again; the paper's eq. (7) with its ψ agrees where it applies.
    #[test]
    fn table_parameters_round_trip() {
        for (l, m) in [(87.5, 52.5), (0.0, 60.0), (120.0, 0.0), (35.0, 80.0)] {
            let t = TiltRotaryTable {
                axes_distance_mm: l,
                surface_to_tilt_mm: m,
            };
            let at90 = t.shift_for_tilt(90.0);
            let (dx, dz, x0, z0) = (20.0, 15.0, 120.0, 65.0);
            let meas = TableMeasurement {
                roller_to_rotation_axis_mm: dx,
                roller_to_surface_mm: dz,
                x0_mm: x0,
                z0_mm: z0,
                x90_mm: at90.a_mm + x0 + dx - dz,
                z90_mm: at90.c_mm + z0 + dz + dx,
            };
            let p = match meas.solve() {
                Ok(p) => p,
                Err(e) => panic!("{e}"),
            };
            assert!(close(p.table.axes_distance_mm, l, 1e-9));
            assert!(close(p.table.surface_to_tilt_mm, m, 1e-9));
            let (a, c) = (p.shift_at_90.a_mm, p.shift_at_90.c_mm);
            // Eq. (8)'s ψ = arcsin √((a − c)²/(2(a² + c²))), then eq. (7).
            let psi = asin(sqrt((a - c) * (a - c) / (2.0 * (a * a + c * c))));
            if l > 0.0 && fabs(cos(psi) - sin(psi)) > 1e-6 && m > 0.0 {
                assert!(close(a * cos(psi) / (cos(psi) + sin(psi)), l, 1e-9));
                assert!(close(c * sin(psi) / (cos(psi) - sin(psi)), m, 1e-9));
            }
        }
    }

    #[test]
    fn program_text() {
        let c = exact(90.0, 90.0, 90.0);
        let j = Job {
            row_step_mm: 1.0,
            rows: 2,
            length_a_mm: 10.0,
            length_b_mm: 10.0,
            length_c_mm: 10.0,
            ..job()
        };
        let s = setup(&c, &j);
        let mut text: heapless::String<4096> = heapless::String::new();
        assert_eq!(
            s.write_program(&mut text, &ProgramOptions::default()),
            Ok(())
        );
        let want = "%\n\
O1000 (TRIHEDRAL CORNER, LYAKUN-YURKEVICH)\n\
(AOB 90.0000 BOC 90.0000 COA 90.0000 DEG)\n\
(CUTTER PLAN ANGLE PHI 35.2644 DEG)\n\
(LINEAR ANGLES OA 90.0000 OB 90.0000 OC 90.0000 DEG)\n\
(ZMIN 5.774 MM ABOVE THE VERTEX)\n\
G21 G90 G17 G40 G80\n\
G0 C135.0000 (ROTATION P)\n\
G0 B-54.7356 (TILT -(90-PHI))\n\
G0 X0.000 Y0.000\n\
G0 Z5.774\n\
G52 X0.000 Y0.000 Z0.000 (LOCAL ZERO AT THE VERTEX)\n\
(EDGE OA TO THE VERTEX)\n\
G1 X-4.082 Y-7.071 Z5.774 F100.0\n\
G1 X0.000 Y0.000 Z0.000\n\
G0 Z5.774\n\
(EDGE OB TO THE VERTEX)\n\
G1 X-4.082 Y7.071 Z5.774 F100.0\n\
G1 X0.000 Y0.000 Z0.000\n\
G0 Z5.774\n\
(EDGE OC TO THE VERTEX)\n\
G1 X8.165 Y0.000 Z5.774 F100.0\n\
G1 X0.000 Y0.000 Z0.000\n\
G0 Z5.774\n\
M98 P1001 (ROWS)\n\
G0 Z5.774\n\
G52 X0.000 Y0.000 Z0.000\n\
M30\n\
O1001 (TRIHEDRAL CORNER ROWS, H 1.000 MM)\n\
G1 X-0.707 Y-1.225 Z1.000 F100.0\n\
G1 X-0.707 Y1.225\n\
G1 X1.414 Y0.000\n\
G1 X-0.707 Y-1.225\n\
G1 X-1.414 Y-2.449 Z2.000\n\
G1 X-1.414 Y2.449\n\
G1 X2.828 Y0.000\n\
G1 X-1.414 Y-2.449\n\
G1 X0.000 Y0.000\n\
M99\n\
%\n";
        assert_eq!(text.as_str(), want);
        // P⁺ on request; options checked.
        let mut text: heapless::String<4096> = heapless::String::new();
        let s3 = setup(
            &c,
            &Job {
                quadrant: Quadrant::Third,
                ..j
            },
        );
        let o = ProgramOptions {
            positive_rotation: true,
            ..ProgramOptions::default()
        };
        assert_eq!(s3.write_program(&mut text, &o), Ok(()));
        assert!(text.contains("G0 C315.0000 (ROTATION P)\n"));
        let mut sink: heapless::String<4096> = heapless::String::new();
        let bad = [
            ProgramOptions {
                feed_mm_min: 0.0,
                ..o
            },
            ProgramOptions {
                feed_mm_min: f64::NAN,
                ..o
            },
        ];
        for b in bad {
            assert_eq!(s.write_program(&mut sink, &b), Err(TrihedralError::Feed));
        }
        let bad = [
            ProgramOptions {
                program_number: 0,
                ..o
            },
            ProgramOptions {
                subprogram_number: 10_000,
                ..o
            },
            ProgramOptions {
                subprogram_number: 1000,
                ..o
            },
        ];
        for b in bad {
            assert_eq!(
                s.write_program(&mut sink, &b),
                Err(TrihedralError::ProgramNumber)
            );
        }
        // A writer that runs out of room.
        let mut small: heapless::String<64> = heapless::String::new();
        assert_eq!(s.write_program(&mut small, &o), Err(TrihedralError::Write));
    }

    #[test]
    fn fixed_point_writer() {
        let cases: [(f64, Decimals, &str); 10] = [
            (0.0, Decimals::Three, "0.000"),
            (-0.0, Decimals::Three, "0.000"),
            (-0.0004, Decimals::Three, "0.000"),
            (-0.0005, Decimals::Three, "-0.001"),
            (1.0005, Decimals::Three, "1.001"),
            (-12.3, Decimals::Three, "-12.300"),
            (35.264_389_682, Decimals::Four, "35.2644"),
            (99_999.999_4, Decimals::Three, "99999.999"),
            (100.04, Decimals::One, "100.0"),
            (-54.735_610_317, Decimals::Four, "-54.7356"),
        ];
        for (x, d, want) in cases {
            let mut s: heapless::String<32> = heapless::String::new();
            assert_eq!(write_fixed(&mut s, x, d), Ok(()));
            assert_eq!(s.as_str(), want);
        }
        for x in [
            99_999.999_5,
            -1e6,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
        ] {
            let mut s: heapless::String<32> = heapless::String::new();
            assert_eq!(
                write_fixed(&mut s, x, Decimals::Three),
                Err(TrihedralError::NumberOutOfRange)
            );
        }
        // A near-degenerate corner whose row points run far out: refused
        // when writing, not a panic.
        let c = exact(30.0, 100.0, 109.99);
        let s = setup(
            &c,
            &Job {
                rows: 3,
                row_step_mm: 10.0,
                ..job()
            },
        );
        let mut text: heapless::String<8192> = heapless::String::new();
        assert_eq!(
            s.write_program(&mut text, &ProgramOptions::default()),
            Err(TrihedralError::NumberOutOfRange)
        );
    }

    #[test]
    fn errors_name_the_input() {
        use TrihedralError as E;
        let all = [
            E::FaceAngleOutOfRange(Face::Aob),
            E::FaceAngleOutOfRange(Face::Boc),
            E::FaceAngleOutOfRange(Face::Coa),
            E::FaceAngleNotBelowOthers(Face::Aob),
            E::FaceAngleNotBelowOthers(Face::Boc),
            E::FaceAngleNotBelowOthers(Face::Coa),
            E::FaceAngleSumTooLarge,
            E::LinearAngleOutOfRange(Edge::Oa),
            E::LinearAngleOutOfRange(Edge::Ob),
            E::LinearAngleOutOfRange(Edge::Oc),
            E::LinearAngleSumTooSmall,
            E::LinearAngleTooSmall(Edge::Oa),
            E::LinearAngleTooSmall(Edge::Ob),
            E::LinearAngleTooSmall(Edge::Oc),
            E::AngleCount,
            E::AngleAmbiguous,
            E::EdgeNotAboveVertex(Edge::Oa),
            E::EdgeNotAboveVertex(Edge::Ob),
            E::EdgeNotAboveVertex(Edge::Oc),
            E::ProportionalFaceTooSmall(Face::Aob),
            E::ProportionalFaceTooSmall(Face::Boc),
            E::ProportionalFaceTooSmall(Face::Coa),
            E::RowStep,
            E::RowCount,
            E::EdgeLength(Edge::Oa),
            E::EdgeLength(Edge::Ob),
            E::EdgeLength(Edge::Oc),
            E::FilletRadius,
            E::OffsetAngle,
            E::TableParameter,
            E::VertexCoordinate,
            E::Measurement,
            E::BallRadius,
            E::Feed,
            E::ProgramNumber,
            E::NumberOutOfRange,
            E::Write,
        ];
        for (i, e) in all.iter().enumerate() {
            let mut s: heapless::String<128> = heapless::String::new();
            assert!(write!(s, "{e}").is_ok());
            assert_eq!(s.as_str(), e.as_str());
            assert!(e.as_str().contains(": "), "{e:?}");
            for other in all.get(i + 1..).unwrap_or(&[]) {
                assert_ne!(e.as_str(), other.as_str());
            }
        }
    }
}

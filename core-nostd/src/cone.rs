//! Taper corrections for a tool nose radius (Krylenko; the Nomura/MELDAS
//! table).
//!
//! For a taper at angle α between the axis and the generatrix (β = 90° − α)
//! and a nose radius r: `Xc = r·(1 − tan(β/2))`, `Zc = r·(1 − tan(α/2))`;
//! the Nomura table's `A = r·tan α·(1 − tan(α/2))` equals Xc, `B = Zc`,
//! `C = r·(1 + tan(α/2))`. Angles are read exactly (whole micro-arc-seconds)
//! and the tangents come from [`crate::trig`] in Q62, within 2⁻⁶⁰ (4 ulps;
//! the tests in this module show it): each value is within about 10⁻¹⁰ mm
//! of exact for r ≤ 25 mm (the half-angle is rounded to 2⁻⁶⁴ turn, the
//! radius is exact), so a printed 4-decimal figure is
//! wrong only if the exact value lies that close to a printing tie, which
//! [`ConeValue::near_tie`] reports.

use crate::length::Length;
use crate::trig::{sin_cos_raw, Turn, FULL_TURN_UAS};
use crate::wide::{checked_divrem_i128, divrem_i128};
use core::num::NonZeroU128;

/// Why an angle word was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AngleError {
    /// Not `digits[.digits]` or `D:M:S`, minutes or seconds not below 60,
    /// more than 6 decimals.
    Malformed,
    /// Not strictly between 0° and 90°.
    OutOfRange,
}

/// An angle held exactly, in micro-arc-seconds (10⁻⁶″).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Angle {
    uas: i64,
}

/// Micro-arc-seconds per degree.
const UAS_PER_DEG: i64 = 3_600_000_000;

/// `digits[.digits]` (at most `max_dec` decimals) as an integer scaled by
/// 10⁶; `None` if malformed.
fn decimal_e6(text: &str, max_int: usize) -> Option<i64> {
    let (int, frac) = match crate::text::split_once(text, b'.') {
        Some((i, f)) if !f.is_empty() => (i, f),
        Some(_) => return None,
        None => (text, ""),
    };
    if int.is_empty() || int.len() > max_int || frac.len() > 6 {
        return None;
    }
    if !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit()) {
        return None;
    }
    let i = int.bytes().fold(0i64, |n, b| n * 10 + i64::from(b - b'0'));
    let mut f = 0i64;
    for k in 0..6 {
        f = f * 10 + frac.as_bytes().get(k).map_or(0, |&b| i64::from(b - b'0'));
    }
    Some(i * 1_000_000 + f)
}

impl Angle {
    /// Parses decimal degrees (`45`, `2.8642`, up to 6 decimals) or
    /// degrees-minutes-seconds `D:M:S` (`2:51:51`; minutes and seconds below
    /// 60, seconds up to 6 decimals), exactly; a taper angle must lie strictly
    /// between 0° and 90°.
    ///
    /// ```
    /// use core_nostd::cone::Angle;
    /// // 54.26° = 54°15'36", exactly.
    /// assert_eq!(Angle::from_degrees_str("54.26"), Angle::from_degrees_str("54:15:36"));
    /// assert!(Angle::from_degrees_str("1:60:0").is_err());
    /// assert!(Angle::from_degrees_str("90").is_err());
    /// ```
    pub fn from_degrees_str(text: &str) -> Result<Angle, AngleError> {
        let text = text.strip_prefix('+').unwrap_or(text);
        let uas = if text.contains(':') {
            let (d, rest) = crate::text::split_once(text, b':').ok_or(AngleError::Malformed)?;
            let (m, s) = crate::text::split_once(rest, b':').ok_or(AngleError::Malformed)?;
            if s.contains(':') {
                return Err(AngleError::Malformed);
            }
            let whole = |p: &str| -> Option<i64> {
                if p.is_empty() || p.len() > 3 || !p.bytes().all(|b| b.is_ascii_digit()) {
                    return None;
                }
                Some(p.bytes().fold(0i64, |n, b| n * 10 + i64::from(b - b'0')))
            };
            let (d, m) = (
                whole(d).ok_or(AngleError::Malformed)?,
                whole(m).ok_or(AngleError::Malformed)?,
            );
            let s = decimal_e6(s, 2).ok_or(AngleError::Malformed)?;
            if m >= 60 || s >= 60_000_000 {
                return Err(AngleError::Malformed);
            }
            d * UAS_PER_DEG + m * 60_000_000 + s
        } else {
            // Decimal degrees: 10⁻⁶° = 3600 µas.
            decimal_e6(text, 3).ok_or(AngleError::Malformed)? * 3600
        };
        if uas <= 0 || uas >= 90 * UAS_PER_DEG {
            return Err(AngleError::OutOfRange);
        }
        Ok(Angle { uas })
    }

    /// The angle in micro-arc-seconds.
    pub const fn as_uas(self) -> i64 {
        self.uas
    }
}

/// A computed length in ångström · 2⁶² (far finer than it can be printed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConeValue(i128);

/// How near a printing tie a value may come before it is reported:
/// 10⁻² Å = 10⁻⁹ mm, far above the computation's error.
const NEAR_TIE: i128 = (1i128 << 62) / 100;

/// 0.0001 mm in ångström · 2⁶², the printed unit.
const UNIT: NonZeroU128 = match NonZeroU128::new(1000 << 62) {
    Some(u) => u,
    None => NonZeroU128::MIN,
};

impl ConeValue {
    /// The value in units of 0.0001 mm, rounded half away from zero (the
    /// printed figure).
    pub fn tenth_um(self) -> i64 {
        let unit = 1000i128 << 62;
        let (q, r) = divrem_i128(self.0, UNIT);
        let q = if 2 * r.abs() >= unit {
            q + self.0.signum()
        } else {
            q
        };
        q as i64
    }

    /// Whether the exact value may lie on the other side of a printing tie.
    pub fn near_tie(self) -> bool {
        let unit = 1000i128 << 62;
        let r = match divrem_i128(self.0, UNIT) {
            (_, r) if r < 0 => r + unit,
            (_, r) => r,
        };
        (r - unit / 2).abs() <= NEAR_TIE
    }

    /// Twice the value (the diameter figure).
    pub fn doubled(self) -> ConeValue {
        ConeValue(self.0 * 2)
    }
}

/// Krylenko's and Nomura's taper corrections.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cone {
    /// Xc on the radius (= Nomura A).
    pub xc: ConeValue,
    /// Zc (= Nomura B).
    pub zc: ConeValue,
    /// Nomura C.
    pub c: ConeValue,
}

/// tan(θ) for 0 ≤ θ < 90°, Q62.
fn tan_q62(a: Turn) -> i128 {
    let (s, c) = sin_cos_raw(a);
    match checked_divrem_i128(i128::from(s) << 62, i128::from(c)) {
        Some((q, _)) => q,
        None => 0,
    }
}

/// The corrections for taper angle `alpha` and nose radius `r`.
///
/// ```
/// use core_nostd::cone::{cone, Angle};
/// use core_nostd::length::Length;
/// // Krylenko: r 0.4, α 45° → Xc = Zc = 0.234 (0.2343 to four decimals).
/// let k = cone(Angle::from_degrees_str("45").unwrap(), Length::from_mm_str("0.4").unwrap());
/// assert_eq!((k.xc.tenth_um(), k.zc.tenth_um(), k.xc.doubled().tenth_um()), (2343, 2343, 4686));
/// ```
pub fn cone(alpha: Angle, r: Length) -> Cone {
    // Half an angle below 180°: halve its turn fraction (one rounding, 2⁻⁶⁴).
    let half_turn = |uas: i64| Turn(Turn::from_uas(uas).0 / 2);
    let ta = tan_q62(half_turn(alpha.uas));
    let tb = tan_q62(half_turn(90 * UAS_PER_DEG - alpha.uas));
    let one = 1i128 << 62;
    let r = i128::from(r.as_angstrom());
    Cone {
        xc: ConeValue(r * (one - tb)),
        zc: ConeValue(r * (one - ta)),
        c: ConeValue(r * (one + ta)),
    }
}

const _: () = assert!(FULL_TURN_UAS == 360 * UAS_PER_DEG);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_parse_exactly() {
        let uas = |s| Angle::from_degrees_str(s).map(Angle::as_uas);
        assert_eq!(uas("45"), Ok(45 * UAS_PER_DEG));
        assert_eq!(
            uas("2:51:51"),
            Ok(2 * UAS_PER_DEG + 51 * 60_000_000 + 51_000_000)
        );
        assert_eq!(uas("0.000001"), Ok(3600));
        assert_eq!(uas("89:59:59.999999"), Ok(90 * UAS_PER_DEG - 1));
        for bad in [
            "",
            ":",
            "1:2",
            "1:2:3:4",
            "-5",
            "45.1234567",
            "1e1",
            "1:60:0",
            "1:0:60",
            "a:b:c",
            "45.",
        ] {
            assert_eq!(uas(bad), Err(AngleError::Malformed), "{bad}");
        }
        for out in ["0", "90", "0:0:0", "90:0:0", "120"] {
            assert_eq!(uas(out), Err(AngleError::OutOfRange), "{out}");
        }
    }

    /// The tangent's error bound: 2⁻⁶⁰ (4 Q62 ulps) for angles up to 45°
    /// (these tests see at most 1 ulp), which is below 3·10⁻¹⁷ mm on any
    /// Xc, Zc or C for r ≤ 25 mm.
    const TAN_BOUND: i128 = 4;

    fn tan_deg(uas: i64) -> i128 {
        tan_q62(Turn::from_uas(uas))
    }

    #[test]
    fn tangent_within_its_bound_at_exact_values() {
        let one = 1i128 << 62;
        let root = |n: u128| i128::from(crate::trig::isqrt(n << 124));
        let deg = |d: i64| d * UAS_PER_DEG;
        // tan 45° = 1, tan 22.5° = √2 − 1, tan 30° = √3/3, tan 15° = 2 − √3;
        // the roots are floors, within one ulp.
        let cases = [
            (deg(45), one),
            (deg(45) / 2, root(2) - one),
            (deg(30), root(3) / 3),
            (deg(15), 2 * one - root(3)),
            (deg(0), 0),
        ];
        for (uas, exact) in cases {
            let e = (tan_deg(uas) - exact).abs();
            assert!(e <= TAN_BOUND, "{uas} µas: {e} ulps");
        }
    }

    proptest::proptest! {
        /// tan 2θ · (1 − tan²θ) = 2·tan θ for θ below 22.5°: with both
        /// tangents within the bound, the sides differ by at most 5 bounds.
        #[test]
        fn tangent_double_angle_identity(uas in 1i64..(45 * UAS_PER_DEG / 2)) {
            let one = 1i128 << 62;
            let t = tan_deg(uas);
            let t2 = tan_deg(2 * uas);
            let lhs = (t2 * (one - ((t * t) >> 62))) >> 62;
            let e = (lhs - 2 * t).abs();
            proptest::prop_assert!(e <= 5 * TAN_BOUND, "{uas}: {e} ulps");
        }
    }
}

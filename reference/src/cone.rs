//! Double-precision (f64) reference of the pendant's `CONE` calculator: the
//! tool-nose corrections for tapers (Krylenko's `Xc`, `Zc` and the Nomura
//! table's `A`, `B`, `C`).
//!
//! Written from `docs/compensation.md` §7.1–§7.2 (tapers, the Nomura table),
//! `docs/units.md` §3.3 (angles) and the `CONE` command and numbers of
//! `docs/protocol.md` §3–§4 alone, independently
//! of the controller's fixed-point core, so that the two can be compared
//! digit for digit.
//!
//! # The calculation ([`cone`])
//!
//! `CONE A=<angle> [RN=<mm>]` → `OK XC= ZC= XCD= NA= NB= NC=`, with
//! `α = A` the angle between the axis and the generatrix, `β = 90° − α`,
//! `r` the nose radius (`0 ≤ r ≤ 25` mm):
//!
//! * `XC = r·(1 − tan(β/2))`, `ZC = r·(1 − tan(α/2))`;
//! * `XCD = 2·XC` (Xc on the diameter), rounded on its own: the doubled exact
//!   value is printed, not twice the printed `XC`;
//! * `NA = XC` (the Nomura `A = r·tan(a)·(1 − tan(a/2))` is the same number:
//!   with `t = tan(α/2)` both are `2rt/(1 + t)`), `NB = ZC`,
//!   `NC = r·(1 + tan(α/2))`.
//!
//! # Angles ([`parse_angle_uas`])
//!
//! An angle word is decimal degrees, `[+]digits[.digits]` with at most six
//! decimals, or `D:M:S`, `D` and `M` whole numbers, `M < 60`, `S`
//! `digits[.digits]` with at most six decimals, `S < 60`. It is converted
//! exactly to whole micro-arc-seconds (1 µas = 10⁻⁶″; one degree is
//! 3 600 000 000 µas, so six decimals of a degree are a whole number of µas)
//! before any trigonometry; `β` is formed exactly as `324 000 000 000 µas − α`
//! and only then are `α/2` and `β/2` turned into f64 radians. The request is
//! refused unless `0 < A < 90°` strictly.
//!
//! # Output and tie margins
//!
//! Each value is printed in mm with exactly four decimals, rounded half away
//! from zero. The values are irrational for every accepted angle except
//! `r = 0`, so the reference and the fixed-point core can only print different
//! digits when the exact value lies within their combined error of a printing
//! tie (`x.xxxx5`); [`RefCone::min_tie_distance_mm`] is the smallest distance
//! from a printed value to its nearest tie, so that margin is visible.

use std::f64::consts::PI;

/// Micro-arc-seconds in one degree.
const UAS_PER_DEG: i64 = 3_600_000_000;
/// Micro-arc-seconds in one arc-minute.
const UAS_PER_MIN: i64 = 60_000_000;
/// Micro-arc-seconds in one arc-second.
const UAS_PER_SEC: i64 = 1_000_000;
/// 90° in micro-arc-seconds.
const UAS_90_DEG: i64 = 90 * UAS_PER_DEG;
/// Largest accepted nose radius, mm.
const RN_MAX_MM: f64 = 25.0;

/// Whole number from a non-empty run of ASCII digits; `None` when empty, when
/// it holds anything else, or when it does not fit an `i64`.
fn whole(digits: &str) -> Option<i64> {
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.bytes().try_fold(0i64, |acc, b| {
        acc.checked_mul(10)?.checked_add(i64::from(b - b'0'))
    })
}

/// `digits[.digits]` with at most six decimals, as a whole number of
/// millionths (`12.5` → 12 500 000).
fn millionths(word: &str) -> Option<i64> {
    let (int_part, frac_part) = match word.split_once('.') {
        Some((i, f)) => {
            if f.is_empty() || f.len() > 6 {
                return None;
            }
            (i, f)
        }
        None => (word, ""),
    };
    let int = whole(int_part)?;
    let frac = if frac_part.is_empty() {
        0
    } else {
        let padded = format!("{frac_part:0<6}");
        whole(&padded)?
    };
    int.checked_mul(1_000_000)?.checked_add(frac)
}

/// An angle word as whole micro-arc-seconds (1e-6″), converted exactly.
///
/// Accepts decimal degrees `[+]digits[.digits]` (at most six decimals) and
/// `D:M:S` (`D`, `M` whole, `M < 60`; `S` `digits[.digits]`, at most six
/// decimals, `S < 60`). Returns `None` for a malformed word (signs other than
/// a leading `+` on decimal degrees, exponents, empty fields, too many
/// decimals, minutes or seconds out of range, overflow). The range of the
/// angle itself (`0 < A < 90°`) is checked by [`cone`], not here.
pub fn parse_angle_uas(word: &str) -> Option<i64> {
    if word.contains(':') {
        let mut fields = word.split(':');
        let (d, m, s) = (fields.next()?, fields.next()?, fields.next()?);
        if fields.next().is_some() {
            return None;
        }
        let d = whole(d)?;
        let m = whole(m)?;
        let s = millionths(s)?; // in µas: millionths of an arc-second
        if m >= 60 || s >= 60 * UAS_PER_SEC {
            return None;
        }
        d.checked_mul(UAS_PER_DEG)?
            .checked_add(m * UAS_PER_MIN)?
            .checked_add(s)
    } else {
        let unsigned = word.strip_prefix('+').unwrap_or(word);
        // millionths of a degree; one of them is 3600 µas.
        millionths(unsigned)?.checked_mul(UAS_PER_DEG / 1_000_000)
    }
}

/// The `CONE` results, in mm, before printing.
#[derive(Clone, Debug, PartialEq)]
pub struct RefCone {
    /// Krylenko's `Xc = r·(1 − tan(β/2))` (on the radius).
    pub xc: f64,
    /// Krylenko's `Zc = r·(1 − tan(α/2))`.
    pub zc: f64,
    /// `2·Xc`, Xc on the diameter.
    pub xcd: f64,
    /// Nomura `A` (= `Xc`).
    pub na: f64,
    /// Nomura `B` (= `Zc`).
    pub nb: f64,
    /// Nomura `C = r·(1 + tan(α/2))`.
    pub nc: f64,
    /// Smallest distance (mm) from any of the six values to its nearest
    /// printing tie `x.xxxx5`.
    pub min_tie_distance_mm: f64,
}

/// f64 radians of a whole number of micro-arc-seconds.
fn uas_to_rad(uas: i64) -> f64 {
    // 180° = 648 000 000 000 µas.
    uas as f64 * (PI / 648_000_000_000.0)
}

/// A length printed in mm with exactly four decimals, rounded half away from
/// zero.
pub fn fmt_mm4(v: f64) -> String {
    let n = (v * 1e4).round() as i64; // `round` goes half away from zero
    let sign = if n < 0 { "-" } else { "" };
    let a = n.unsigned_abs();
    format!("{sign}{}.{:04}", a / 10_000, a % 10_000)
}

/// Distance (mm) from `v` to the nearest printing tie of four decimals.
fn tie_distance_mm(v: f64) -> f64 {
    let s = (v * 1e4).abs();
    ((s - s.floor()) - 0.5).abs() * 1e-4
}

/// The `CONE` calculator for the angle word `angle_word` (axis to generatrix)
/// and the nose radius `rn_mm`.
///
/// `None` when the request is refused (`ERR VALUE`): a malformed angle, an
/// angle not strictly between 0° and 90°, or a radius outside `0 ≤ r ≤ 25` mm
/// (or not a number).
pub fn cone(angle_word: &str, rn_mm: f64) -> Option<RefCone> {
    let alpha = parse_angle_uas(angle_word)?;
    if alpha <= 0 || alpha >= UAS_90_DEG {
        return None;
    }
    if !(0.0..=RN_MAX_MM).contains(&rn_mm) {
        return None;
    }
    let r = rn_mm;
    let beta = UAS_90_DEG - alpha; // exact
    let tan_half_alpha = (uas_to_rad(alpha) / 2.0).tan();
    let tan_half_beta = (uas_to_rad(beta) / 2.0).tan();

    let xc = r * (1.0 - tan_half_beta);
    let zc = r * (1.0 - tan_half_alpha);
    let xcd = 2.0 * xc;
    let (na, nb) = (xc, zc);
    let nc = r * (1.0 + tan_half_alpha);
    let min_tie_distance_mm = [xc, zc, xcd, na, nb, nc]
        .into_iter()
        .map(tie_distance_mm)
        .fold(f64::INFINITY, f64::min);
    Some(RefCone {
        xc,
        zc,
        xcd,
        na,
        nb,
        nc,
        min_tie_distance_mm,
    })
}

impl RefCone {
    /// The device's final reply line (without checksum), e.g.
    /// `OK XC=0.2343 ZC=0.2343 XCD=0.4686 NA=0.2343 NB=0.2343 NC=0.5657`.
    pub fn reply_line(&self) -> String {
        format!(
            "OK XC={} ZC={} XCD={} NA={} NB={} NC={}",
            fmt_mm4(self.xc),
            fmt_mm4(self.zc),
            fmt_mm4(self.xcd),
            fmt_mm4(self.na),
            fmt_mm4(self.nb),
            fmt_mm4(self.nc),
        )
    }
}

/// The Nomura (MELDAS 65SLC) nose correction table as printed in Krylenko's
/// appendix, corrected (`docs/compensation.md` §7.2, `docs/errata.md` §1.3;
/// 204 values): one row per kind
/// and nose radius, `A2` (2A, the diameter correction), `B` or `C`, then r,
/// then the values for a = 5°, 10°, … 85°, as printed.
pub const NOMURA_TABLE: &str = "\
A2 0.2 0.03 0.06 0.09 0.12 0.15 0.17 0.19 0.21 0.23 0.25 0.27 0.29 0.31 0.33 0.35 0.37 0.38
A2 0.4 0.07 0.13 0.19 0.24 0.29 0.34 0.38 0.43 0.47 0.51 0.55 0.59 0.62 0.66 0.69 0.73 0.77
A2 0.5 0.08 0.16 0.23 0.30 0.36 0.42 0.48 0.53 0.59 0.64 0.68 0.73 0.78 0.82 0.87 0.91 0.96
A2 0.8 0.13 0.26 0.37 0.48 0.58 0.68 0.77 0.85 0.94 1.02 1.10 1.17 1.25 1.32 1.39 1.46 1.53
B 0.2 0.19 0.18 0.17 0.16 0.16 0.15 0.14 0.13 0.12 0.11 0.10 0.08 0.07 0.06 0.05 0.03 0.02
B 0.4 0.38 0.37 0.35 0.33 0.31 0.29 0.27 0.25 0.23 0.21 0.19 0.17 0.15 0.12 0.09 0.06 0.03
B 0.5 0.48 0.46 0.43 0.41 0.39 0.37 0.34 0.32 0.29 0.27 0.24 0.21 0.18 0.15 0.12 0.08 0.04
B 0.8 0.77 0.73 0.69 0.66 0.62 0.59 0.55 0.51 0.47 0.43 0.38 0.34 0.29 0.24 0.19 0.13 0.07
C 0.2 0.21 0.22 0.23 0.24 0.24 0.25 0.26 0.27 0.28 0.29 0.30 0.32 0.33 0.34 0.35 0.37 0.38
C 0.4 0.42 0.43 0.45 0.47 0.49 0.51 0.53 0.55 0.57 0.59 0.61 0.63 0.65 0.68 0.71 0.74 0.77
C 0.5 0.52 0.54 0.57 0.59 0.61 0.63 0.66 0.68 0.71 0.73 0.76 0.79 0.82 0.85 0.88 0.92 0.96
C 0.8 0.83 0.87 0.91 0.94 0.98 1.01 1.05 1.09 1.13 1.17 1.22 1.26 1.31 1.36 1.41 1.47 1.53
";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn krylenko_example_r04_alpha45() {
        let c = cone("45", 0.4).expect("45° accepted");
        assert_eq!(fmt_mm4(c.xc), "0.2343");
        assert_eq!(fmt_mm4(c.zc), "0.2343");
        assert_eq!(fmt_mm4(c.xcd), "0.4686");
        // The seed prints 0.234 (0.468 on the diameter).
        assert!((c.xc - 0.234).abs() < 0.0005);
        assert!((c.xcd - 0.468).abs() < 0.001);
        assert_eq!(
            c.reply_line(),
            "OK XC=0.2343 ZC=0.2343 XCD=0.4686 NA=0.2343 NB=0.2343 NC=0.5657"
        );
        assert!(c.min_tie_distance_mm > 0.0 && c.min_tie_distance_mm <= 0.5e-4);
    }

    #[test]
    fn appendix_decimal_equals_dms_exactly() {
        let dec = parse_angle_uas("54.26").unwrap();
        let dms = parse_angle_uas("54:15:36").unwrap();
        assert_eq!(dec, 195_336_000_000);
        assert_eq!(dec, dms);
        assert_eq!(cone("54.26", 0.4), cone("54:15:36", 0.4));
    }

    #[test]
    fn dms_parses() {
        assert_eq!(
            parse_angle_uas("2:51:51"),
            Some(2 * UAS_PER_DEG + 51 * UAS_PER_MIN + 51 * UAS_PER_SEC)
        );
        assert!(cone("2:51:51", 0.4).is_some());
        assert_eq!(parse_angle_uas("0:0:0.000001"), Some(1));
        assert_eq!(parse_angle_uas("89:59:59.999999"), Some(UAS_90_DEG - 1));
        assert!(cone("0:0:0.000001", 0.4).is_some());
        assert!(cone("89:59:59.999999", 0.4).is_some());
        // Degrees are not bounded by the grammar: 60:00:00 is 60° exactly.
        assert_eq!(parse_angle_uas("60:00:00"), parse_angle_uas("60"));
    }

    #[test]
    fn decimal_degrees_parse() {
        assert_eq!(parse_angle_uas("45"), Some(45 * UAS_PER_DEG));
        assert_eq!(parse_angle_uas("+45"), Some(45 * UAS_PER_DEG));
        assert_eq!(
            parse_angle_uas("045.5"),
            Some(45 * UAS_PER_DEG + UAS_PER_DEG / 2)
        );
        assert_eq!(parse_angle_uas("0.000001"), Some(3600));
        assert_eq!(parse_angle_uas("2.8642"), Some(10_311_120_000));
    }

    #[test]
    fn malformed_or_out_of_range_angles_refused() {
        for w in [
            "0:60:00",
            "1:60:0",
            "1:0:60",
            "1:0:60.0",
            "45.1234567",
            "1:0:1.1234567",
            "1e1",
            ":",
            "1:2",
            "1:2:3:4",
            "1::3",
            "-5",
            "-1:0:0",
            "+1:0:0",
            "45.",
            ".5",
            "",
            "+",
            " 45",
            "45 ",
            "4 5",
            "1.5:0:0",
            "1:0.5:0",
            "99999999999999999999",
        ] {
            assert_eq!(parse_angle_uas(w), None, "{w:?} should be malformed");
            assert_eq!(cone(w, 0.4), None, "{w:?} should be refused");
        }
        for w in [
            "90",
            "0",
            "0.0",
            "0:0:0",
            "90:0:0",
            "89:60:0",
            "120",
            "90.000001",
        ] {
            assert_eq!(cone(w, 0.4), None, "{w:?} should be refused");
        }
    }

    #[test]
    fn nose_radius_range() {
        assert!(cone("45", 0.0).is_some());
        assert_eq!(
            cone("45", 0.0).unwrap().reply_line(),
            "OK XC=0.0000 ZC=0.0000 XCD=0.0000 NA=0.0000 NB=0.0000 NC=0.0000"
        );
        assert!(cone("45", 25.0).is_some());
        assert_eq!(cone("45", 25.000001), None);
        assert_eq!(cone("45", -0.1), None);
        assert_eq!(cone("45", f64::NAN), None);
    }

    #[test]
    fn nomura_a_is_krylenko_xc() {
        for deg in 1..90 {
            let c = cone(&deg.to_string(), 0.8).unwrap();
            let a = (deg as f64).to_radians();
            let nomura_a = 0.8 * a.tan() * (1.0 - (a / 2.0).tan());
            assert!((c.na - nomura_a).abs() < 1e-12, "{deg}°");
            assert_eq!(fmt_mm4(c.na), fmt_mm4(c.xc));
            assert_eq!(fmt_mm4(c.nb), fmt_mm4(c.zc));
        }
    }

    #[test]
    fn nomura_table_reproduced() {
        let mut count = 0;
        let mut worst = 0.0f64;
        for line in NOMURA_TABLE.lines() {
            let mut words = line.split_whitespace();
            let kind = words.next().unwrap();
            let r: f64 = words.next().unwrap().parse().unwrap();
            let values: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
            assert_eq!(values.len(), 17, "{line}");
            for (i, printed) in values.into_iter().enumerate() {
                let a = 5 * (i + 1);
                let c = cone(&a.to_string(), r).unwrap();
                let formula = match kind {
                    "A2" => c.xcd,
                    "B" => c.nb,
                    "C" => c.nc,
                    other => panic!("unknown row {other}"),
                };
                let dev = (printed - formula).abs();
                assert!(
                    dev <= 0.005 + 1e-9,
                    "{kind} r={r} a={a}: table {printed}, formula {formula}"
                );
                worst = worst.max(dev);
                count += 1;
            }
        }
        assert_eq!(count, 204);
        println!("largest deviation from the Nomura table: {worst:.6} mm");
    }

    #[test]
    fn tie_distance_and_rounding() {
        assert_eq!(fmt_mm4(0.00005), "0.0001");
        assert_eq!(fmt_mm4(-0.00005), "-0.0001");
        assert_eq!(fmt_mm4(1.23444), "1.2344");
        assert_eq!(fmt_mm4(-0.00001), "0.0000");
        assert!((tie_distance_mm(0.23435) - 0.0).abs() < 1e-12);
        assert!((tie_distance_mm(0.2343) - 0.5e-4).abs() < 1e-12);
        let c = cone("30", 0.5).unwrap();
        let expected = [c.xc, c.zc, c.xcd, c.na, c.nb, c.nc]
            .into_iter()
            .map(tie_distance_mm)
            .fold(f64::INFINITY, f64::min);
        assert_eq!(c.min_tie_distance_mm, expected);
    }
}

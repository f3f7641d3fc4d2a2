//! Exact decimal lengths.
//!
//! A [`Length`] stores an integer number of ångström (1 Å = 10⁻⁷ mm). A value
//! written with up to 6 decimals of a millimetre (1 nm) is a multiple of 10 Å,
//! so it is held exactly, and so is half of it: a diameter word becomes an
//! exact radius. Every operation that could leave the representable range is
//! checked and returns `None` or an error; nothing wraps and nothing panics.

use core::fmt;

/// Ångström per millimetre.
pub const ANGSTROM_PER_MM: i64 = 10_000_000;

/// The largest magnitude a length may have: just under 100 000 mm.
///
/// Coordinates and words beyond it are refused (`ERR VALUE` for a word,
/// `ERR RANGE` for a coordinate that an increment would carry beyond it).
pub const LENGTH_LIMIT: Length = Length {
    angstrom: 100_000 * ANGSTROM_PER_MM - 10,
};

/// Why a decimal length was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LengthError {
    /// Not of the form `[+-]digits[.digits]`.
    Malformed,
    /// More than 6 decimals.
    TooManyDecimals,
    /// Magnitude not below 100 000 mm.
    OutOfRange,
}

impl LengthError {
    /// A short, fixed description for replies and logs.
    pub const fn as_str(self) -> &'static str {
        match self {
            LengthError::Malformed => "not a length [+-]digits[.digits]",
            LengthError::TooManyDecimals => "more than 6 decimals",
            LengthError::OutOfRange => "beyond 99999.999999 mm",
        }
    }
}

impl fmt::Display for LengthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// An exact length in ångström (10⁻⁷ mm), signed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Length {
    angstrom: i64,
}

impl Length {
    /// Zero length.
    pub const ZERO: Length = Length { angstrom: 0 };

    /// A length from a raw count of ångström (10⁻⁷ mm), if within
    /// [`LENGTH_LIMIT`].
    ///
    /// ```
    /// use core_nostd::length::Length;
    /// assert_eq!(Length::from_angstrom(25_000).unwrap().to_string(), "0.0025");
    /// assert!(Length::from_angstrom(i64::MAX).is_none());
    /// ```
    #[inline(never)]
    pub const fn from_angstrom(angstrom: i64) -> Option<Length> {
        if angstrom.unsigned_abs() <= LENGTH_LIMIT.angstrom as u64 {
            Some(Length { angstrom })
        } else {
            None
        }
    }

    /// A whole number of micrometres (1 µm = 0.001 mm), if within the limit.
    ///
    /// ```
    /// use core_nostd::length::Length;
    /// assert_eq!(Length::from_um(5).unwrap(), Length::from_mm_str("0.005").unwrap());
    /// ```
    pub const fn from_um(um: i64) -> Option<Length> {
        match um.checked_mul(10_000) {
            Some(a) => Length::from_angstrom(a),
            None => None,
        }
    }

    /// Parses a decimal millimetre value `[+-]digits[.digits]` with at most 6
    /// decimals and magnitude below 100 000 mm. No exponents, no spaces.
    ///
    /// ```
    /// use core_nostd::length::{Length, LengthError};
    /// assert_eq!(Length::from_mm_str("-12.5").unwrap().as_angstrom(), -125_000_000);
    /// assert_eq!(Length::from_mm_str("+0.000001").unwrap().as_angstrom(), 10);
    /// assert_eq!(Length::from_mm_str("1.0000001"), Err(LengthError::TooManyDecimals));
    /// assert_eq!(Length::from_mm_str(".5"), Err(LengthError::Malformed));
    /// assert_eq!(Length::from_mm_str("100000"), Err(LengthError::OutOfRange));
    /// ```
    pub fn from_mm_str(text: &str) -> Result<Length, LengthError> {
        let bytes = text.as_bytes();
        let (negative, rest) = match bytes.split_first() {
            Some((b'-', rest)) => (true, rest),
            Some((b'+', rest)) => (false, rest),
            Some(_) => (false, bytes),
            None => return Err(LengthError::Malformed),
        };
        let (int_part, frac_part) = match rest.iter().position(|&b| b == b'.') {
            Some(dot) => {
                let (i, f) = rest.split_at(dot);
                let f = f.get(1..).unwrap_or(&[]);
                if f.is_empty() {
                    return Err(LengthError::Malformed);
                }
                (i, f)
            }
            None => (rest, &[][..]),
        };
        if int_part.is_empty() || !int_part.iter().all(u8::is_ascii_digit) {
            return Err(LengthError::Malformed);
        }
        if !frac_part.iter().all(u8::is_ascii_digit) {
            return Err(LengthError::Malformed);
        }
        if frac_part.len() > 6 {
            return Err(LengthError::TooManyDecimals);
        }
        // Integer part: skip leading zeros, then at most 5 significant digits.
        let mut mm: i64 = 0;
        for &d in int_part {
            mm = mm * 10 + i64::from(d - b'0');
            if mm >= 100_000 {
                return Err(LengthError::OutOfRange);
            }
        }
        let mut nm: i64 = 0;
        for i in 0..6 {
            let digit = frac_part.get(i).map_or(0, |&d| i64::from(d - b'0'));
            nm = nm * 10 + digit;
        }
        let angstrom = (mm * 1_000_000 + nm) * 10;
        Ok(Length {
            angstrom: if negative { -angstrom } else { angstrom },
        })
    }

    /// Parses a number of millimetres as G-code programs write it:
    /// `[+-]`, then digits with an optional point (`30.`, `2.5`) or a point
    /// and digits (`.5`), any count of decimals (read to the 30th),
    /// rounded once to the ångström half away from zero (exact up to 7
    /// decimals).
    ///
    /// ```
    /// use core_nostd::length::{Length, LengthError};
    /// let mm = |t| Length::from_gcode_mm(t).map(Length::as_angstrom);
    /// assert_eq!(mm("30."), Ok(300_000_000));
    /// assert_eq!(mm("-.5"), Ok(-5_000_000));
    /// assert_eq!(mm("0.00000005"), Ok(1));
    /// assert_eq!(mm("-0.00000004999"), Ok(0));
    /// assert_eq!(mm("-2.8918148932211922"), Ok(-28_918_149));
    /// assert_eq!(mm("1.00000004999999999999999999999999999"), Ok(10_000_000));
    /// assert_eq!(mm("."), Err(LengthError::Malformed));
    /// assert_eq!(mm("99999.99999995"), Err(LengthError::OutOfRange));
    /// ```
    pub fn from_gcode_mm(text: &str) -> Result<Length, LengthError> {
        from_gcode(text, 1, 7)
    }

    /// Parses a number of inches as G-code programs write it (the grammar
    /// of [`Length::from_gcode_mm`]): 25.4 mm each, rounded once to the
    /// ångström half away from zero (exact up to 6 decimals: 1 µin is
    /// 254 Å).
    ///
    /// ```
    /// use core_nostd::length::{Length, LengthError};
    /// let inch = |t| Length::from_gcode_inch(t).map(Length::as_angstrom);
    /// assert_eq!(inch("1."), Ok(254_000_000));
    /// assert_eq!(inch("-.000001"), Ok(-254));
    /// assert_eq!(inch("0.0000000019685"), Ok(0)); // 0.499999 Å
    /// assert_eq!(inch("0.000000001969"), Ok(1)); // 0.500126 Å
    /// assert_eq!(inch("3937.0078"), Ok(999_999_981_200));
    /// assert_eq!(inch("3937.008"), Err(LengthError::OutOfRange));
    /// ```
    pub fn from_gcode_inch(text: &str) -> Result<Length, LengthError> {
        from_gcode(text, 254, 6)
    }

    /// Half of a G-code number of millimetres (a diameter's radius),
    /// rounded once from the number as written, not from its rounding.
    ///
    /// ```
    /// use core_nostd::length::Length;
    /// let half = |t| Length::half_gcode_mm(t).map(Length::as_angstrom);
    /// assert_eq!(half("20."), Ok(100_000_000));
    /// assert_eq!(half("1.0000001"), Ok(5_000_001)); // 5 000 000.5 Å: away from 0
    /// assert_eq!(half("1.00000009"), Ok(5_000_000)); // 5 000 000.45 Å
    /// assert_eq!(half("-2.8918148932211922"), Ok(-14_459_074));
    /// ```
    pub fn half_gcode_mm(text: &str) -> Result<Length, LengthError> {
        from_gcode(text, 5, 6)
    }

    /// Half of a G-code number of inches, rounded once (127·10⁶ Å an
    /// inch's half).
    ///
    /// ```
    /// use core_nostd::length::Length;
    /// assert_eq!(Length::half_gcode_inch("1.").map(Length::as_angstrom), Ok(127_000_000));
    /// ```
    pub fn half_gcode_inch(text: &str) -> Result<Length, LengthError> {
        from_gcode(text, 127, 6)
    }

    /// The raw count of ångström (10⁻⁷ mm).
    pub const fn as_angstrom(self) -> i64 {
        self.angstrom
    }

    /// Sum, or `None` beyond [`LENGTH_LIMIT`].
    #[inline(never)]
    pub const fn checked_add(self, other: Length) -> Option<Length> {
        match self.angstrom.checked_add(other.angstrom) {
            Some(a) => Length::from_angstrom(a),
            None => None,
        }
    }

    /// Difference, or `None` beyond [`LENGTH_LIMIT`].
    #[inline(never)]
    pub const fn checked_sub(self, other: Length) -> Option<Length> {
        match self.angstrom.checked_sub(other.angstrom) {
            Some(a) => Length::from_angstrom(a),
            None => None,
        }
    }

    /// Twice the length (a radius written as a diameter), or `None` beyond
    /// [`LENGTH_LIMIT`].
    pub const fn checked_double(self) -> Option<Length> {
        self.checked_add(self)
    }

    /// Exactly half the length (a diameter read as a radius), or `None` when
    /// the half is not a whole number of ångström. Never `None` for a value
    /// parsed from a decimal with up to 6 decimals.
    ///
    /// ```
    /// use core_nostd::length::Length;
    /// let d = Length::from_mm_str("0.000001").unwrap();
    /// assert_eq!(d.exact_half().unwrap().as_angstrom(), 5);
    /// ```
    pub const fn exact_half(self) -> Option<Length> {
        if self.angstrom % 2 == 0 {
            Some(Length {
                angstrom: self.angstrom / 2,
            })
        } else {
            None
        }
    }

    /// Negated length (always representable: the limit is symmetric).
    pub const fn neg(self) -> Length {
        Length {
            angstrom: -self.angstrom,
        }
    }

    /// The value in units of 0.0001 mm, rounded half away from zero: the
    /// 4-decimal figure printed in replies.
    pub const fn round_to_tenth_um(self) -> i64 {
        div_round_half_away(self.angstrom, 1_000)
    }
}

/// `n / d` rounded half away from zero, for `d > 0`. Exact integer arithmetic;
/// `|n| ≤ i64::MAX` so nothing overflows.
pub(crate) const fn div_round_half_away(n: i64, d: i64) -> i64 {
    let (q, r) = match (n.checked_div(d), n.checked_rem(d)) {
        (Some(q), Some(r)) => (q, r),
        // d = 0 or i64::MIN / -1: excluded by the callers (d > 0).
        _ => return 0,
    };
    // |r| < d ≤ i64::MAX / 2 is not guaranteed, so compare |r| ≥ d − |r|.
    let ar = r.unsigned_abs();
    if ar >= d.unsigned_abs() - ar {
        if n < 0 {
            q - 1
        } else {
            q + 1
        }
    } else {
        q
    }
}

/// Prints millimetres with exactly 4 decimals, rounded half away from zero
/// (the reply format of the line protocol). A value that rounds to zero is
/// printed without a sign.
///
/// ```
/// use core_nostd::length::Length;
/// let l = |s| Length::from_mm_str(s).unwrap().to_string();
/// assert_eq!(l("27.53125"), "27.5313");
/// assert_eq!(l("-27.53125"), "-27.5313");
/// assert_eq!(l("-0.00004"), "0.0000");
/// assert_eq!(l("12"), "12.0000");
/// ```
impl fmt::Display for Length {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_mm4(f, self.round_to_tenth_um())
    }
}

/// Writes `angstrom` as an exact decimal of mm, without trailing zeros
/// (up to 7 decimals): what a request or a G-code word takes back
/// unchanged.
///
/// ```
/// use core_nostd::length::write_exact_mm;
/// let mut s = String::new();
/// write_exact_mm(&mut s, -1_250_000).unwrap();
/// assert_eq!(s, "-0.125");
/// ```
pub fn write_exact_mm<W: fmt::Write + ?Sized>(w: &mut W, angstrom: i64) -> fmt::Result {
    if angstrom < 0 {
        w.write_str("-")?;
    }
    let u = angstrom.unsigned_abs();
    write!(w, "{}", u / 10_000_000)?;
    let frac = u % 10_000_000;
    if frac != 0 {
        let mut digits = [b'0'; 7];
        let mut f = frac;
        for d in digits.iter_mut().rev() {
            *d = b'0' + (f % 10) as u8;
            f /= 10;
        }
        let len = 7 - digits.iter().rev().take_while(|&&d| d == b'0').count();
        w.write_str(".")?;
        w.write_str(core::str::from_utf8(digits.get(..len).unwrap_or(&[])).unwrap_or(""))?;
    }
    Ok(())
}

/// A G-code number without a unit (the grammar of [`Length::from_gcode_mm`])
/// times 10ᵉ, `e` ≤ 7, rounded once half away from zero: seconds or
/// milliseconds as microseconds (`e` 6 or 3). The rounded number, on its
/// own scale, is at most 99 999.999999: a number that rounds beyond it is
/// refused, as a length is.
///
/// ```
/// use core_nostd::length::{gcode_scaled, LengthError};
/// assert_eq!(gcode_scaled("1.5", 6), Ok(1_500_000));
/// assert_eq!(gcode_scaled("0.0000004999999", 6), Ok(0));
/// assert_eq!(gcode_scaled("-2.0005", 3), Ok(-2_001));
/// assert_eq!(gcode_scaled("99999.9999994", 6), Ok(99_999_999_999));
/// assert_eq!(gcode_scaled("99999.9999995", 6), Err(LengthError::OutOfRange));
/// assert_eq!(gcode_scaled("99999.9995", 3), Err(LengthError::OutOfRange));
/// ```
pub fn gcode_scaled(text: &str, e: u32) -> Result<i64, LengthError> {
    // ⌊99 999.999999 · 10ᵉ⌋ for e = 0 … 7.
    const MOST: [u64; 8] = [
        99_999,
        999_999,
        9_999_999,
        99_999_999,
        999_999_999,
        9_999_999_999,
        99_999_999_999,
        999_999_999_990,
    ];
    let e = e.min(7);
    let most = MOST.get(e as usize).copied().unwrap_or(0);
    let v = from_gcode(text, 1, e)?.as_angstrom();
    if v.unsigned_abs() > most {
        return Err(LengthError::OutOfRange);
    }
    Ok(v)
}

/// Writes a count of 0.0001 mm as `[-]int.dddd`.
pub(crate) fn write_mm4<W: fmt::Write + ?Sized>(w: &mut W, tenth_um: i64) -> fmt::Result {
    let sign = if tenth_um < 0 { "-" } else { "" };
    let a = tenth_um.unsigned_abs();
    write!(w, "{}{}.{:04}", sign, a / 10_000, a % 10_000)
}

/// A G-code number in a unit of `m·10ᵉ` ångström (millimetres: 1·10⁷,
/// inches: 254·10⁶): whole units exactly, the decimals `F` (d digits, at
/// most [`GCODE_DECIMALS`] read) as `F·m·10ᵉ⁻ᵈ`, rounded once half away
/// from zero when d > e.
fn from_gcode(text: &str, m: u64, e: u32) -> Result<Length, LengthError> {
    let (negative, int_part, frac_part) = split_decimal(text)?;
    let mut whole: u64 = 0;
    for &d in int_part {
        whole = whole * 10 + u64::from(d - b'0');
        if whole >= 100_000 {
            return Err(LengthError::OutOfRange);
        }
    }
    // Read to the 30th decimal (10⁻²³ mm; CAM posts print up to 17): the
    // digits after it are left out. `F·m < 2.6·10³²` fits in u128.
    let frac_part = frac_part.get(..GCODE_DECIMALS).unwrap_or(frac_part);
    let decimals = frac_part.len() as u32;
    let digits = frac_part
        .iter()
        .fold(0u128, |n, &d| n * 10 + u128::from(d - b'0'));
    let m = u128::from(m);
    let frac = if decimals <= e {
        digits * m * 10u128.pow(e - decimals)
    } else {
        // 10 … 10³⁰: never zero.
        let unit = core::num::NonZeroU128::new(10u128.pow(decimals - e))
            .unwrap_or(core::num::NonZeroU128::MIN);
        let (q, r) = crate::wide::divrem_u128(digits * m, unit);
        q + u128::from(2 * r >= unit.get())
    };
    let angstrom = u128::from(whole) * m * 10u128.pow(e) + frac;
    if angstrom > LENGTH_LIMIT.angstrom as u128 {
        return Err(LengthError::OutOfRange);
    }
    let angstrom = angstrom as i64;
    Ok(Length {
        angstrom: if negative { -angstrom } else { angstrom },
    })
}

/// The decimals of a G-code number that are read; later ones are left out.
pub const GCODE_DECIMALS: usize = 30;

/// Splits `[+-]digits[.digits]`, `digits.` or `.digits` into its sign,
/// integer digits and decimals (G-code numbers).
fn split_decimal(text: &str) -> Result<(bool, &[u8], &[u8]), LengthError> {
    let bytes = text.as_bytes();
    let (negative, rest) = match bytes.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, bytes),
    };
    let (int_part, frac_part) = match rest.iter().position(|&b| b == b'.') {
        Some(dot) => {
            let (i, f) = rest.split_at(dot);
            (i, f.get(1..).unwrap_or(&[]))
        }
        None => (rest, &[][..]),
    };
    let digits = |p: &[u8]| p.iter().all(u8::is_ascii_digit);
    if (int_part.is_empty() && frac_part.is_empty()) || !digits(int_part) || !digits(frac_part) {
        return Err(LengthError::Malformed);
    }
    Ok((negative, int_part, frac_part))
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

    #[test]
    fn parses_every_form() {
        let a = |s: &str| Length::from_mm_str(s).map(Length::as_angstrom);
        assert_eq!(a("0"), Ok(0));
        assert_eq!(a("-0"), Ok(0));
        assert_eq!(a("007.5"), Ok(75_000_000));
        assert_eq!(a("99999.999999"), Ok(999_999_999_990));
        assert_eq!(a("-99999.999999"), Ok(-999_999_999_990));
        assert_eq!(a("100000.0"), Err(LengthError::OutOfRange));
        assert_eq!(a("0000000000000000000000012"), Ok(120_000_000));
        assert_eq!(a("1."), Err(LengthError::Malformed));
        assert_eq!(a("1e3"), Err(LengthError::Malformed));
        assert_eq!(a("--1"), Err(LengthError::Malformed));
        assert_eq!(a("+"), Err(LengthError::Malformed));
        assert_eq!(a(""), Err(LengthError::Malformed));
        assert_eq!(a("1.2.3"), Err(LengthError::Malformed));
        assert_eq!(a(" 1"), Err(LengthError::Malformed));
        assert_eq!(a("0.1234567"), Err(LengthError::TooManyDecimals));
    }

    #[test]
    fn prints_four_decimals_half_away() {
        let p = |a: i64| Length::from_angstrom(a).unwrap().to_string();
        assert_eq!(p(500), "0.0001");
        assert_eq!(p(499), "0.0000");
        assert_eq!(p(-500), "-0.0001");
        assert_eq!(p(-499), "0.0000");
        assert_eq!(p(999_999_999_990), "100000.0000");
    }

    #[test]
    fn limits_are_checked() {
        assert!(LENGTH_LIMIT
            .checked_add(Length::from_angstrom(10).unwrap())
            .is_none());
        assert!(LENGTH_LIMIT
            .neg()
            .checked_sub(Length::from_angstrom(1).unwrap())
            .is_none());
        assert!(LENGTH_LIMIT.checked_double().is_none());
        assert_eq!(Length::from_angstrom(3).unwrap().exact_half(), None);
    }

    #[test]
    fn rounding_division() {
        assert_eq!(div_round_half_away(5, 10), 1);
        assert_eq!(div_round_half_away(-5, 10), -1);
        assert_eq!(div_round_half_away(4, 10), 0);
        assert_eq!(div_round_half_away(-15, 10), -2);
        assert_eq!(div_round_half_away(i64::MAX, 2), i64::MAX / 2 + 1);
        assert_eq!(div_round_half_away(i64::MIN + 1, 3), (i64::MIN + 1) / 3);
    }
}

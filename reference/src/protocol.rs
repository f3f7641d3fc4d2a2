//! What the line protocol promises, stated once for the oracles that check
//! the device against it: its limits, its error codes and the numbers its
//! requests carry (`docs/protocol.md` §2, §3, §5, §10, §11). Written from
//! those sections alone; the core's own list of error codes is checked
//! against [`ERROR_CODES`] by a test (`tests/tests/independence.rs`), so the
//! two cannot drift apart unnoticed.

/// The longest request line, terminator excluded (`docs/protocol.md` §2).
pub const LINE_MAX: usize = 120;

/// The most impulses one block (a line, a chord, a direct arc) may issue per
/// axis (`docs/protocol.md` §11).
pub const BLOCK_MAX: i64 = 1_000_000;

/// The largest magnitude of a position register, in impulses.
pub const REGISTER_MAX: i64 = 999_999_999;

/// The largest magnitude of a commanded coordinate (X on the radius, Z) in
/// ångström: 99 999.999999 mm.
pub const COORD_MAX_ANGSTROM: i64 = 999_999_999_990;

/// The most chords of one arc.
pub const CHORDS_MAX: i64 = 10_000;

/// The largest accepted difference between an arc's start and end radii, mm.
pub const RADIUS_MISMATCH_MM: f64 = 0.002;

/// Every error code the device may answer (`docs/protocol.md` §10), in the
/// order that section lists them: the eight of the required minimum, then
/// the extension `SESSION`.
pub const ERROR_CODES: [&str; 11] = [
    "CHECKSUM",
    "LINE_TOO_LONG",
    "EMPTY",
    "UNKNOWN",
    "SYNTAX",
    "VALUE",
    "RANGE",
    "GEOMETRY",
    "SESSION",
    "ESTOP",
    "ALARM",
];

/// How many of [`ERROR_CODES`] belong to the required minimum
/// (`docs/protocol.md` §1); the rest are extensions.
pub const REQUIRED_ERROR_CODES: usize = 8;

/// Why a decimal length is refused, in the order the checks apply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthRefusal {
    /// Not `[+-]digits[.digits]`.
    Malformed,
    /// More than 6 decimals.
    TooManyDecimals,
    /// Magnitude not below 100 000 mm.
    OutOfRange,
}

/// A request length (`docs/protocol.md` §3): `[+-]?[0-9]+(\.[0-9]{1,6})?`
/// with magnitude below 100 000 mm, as ångström.
pub fn parse_mm(text: &str) -> Result<i64, LengthRefusal> {
    let (negative, body) = if let Some(r) = text.strip_prefix('-') {
        (true, r)
    } else if let Some(r) = text.strip_prefix('+') {
        (false, r)
    } else {
        (false, text)
    };
    let (int, frac) = match body.split_once('.') {
        Some((i, f)) => (i, Some(f)),
        None => (body, None),
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(int) || frac.is_some_and(|f| !digits(f)) {
        return Err(LengthRefusal::Malformed);
    }
    let frac = frac.unwrap_or("");
    if frac.len() > 6 {
        return Err(LengthRefusal::TooManyDecimals);
    }
    let int = int.trim_start_matches('0');
    if int.len() > 5 {
        return Err(LengthRefusal::OutOfRange);
    }
    let mm: i64 = if int.is_empty() {
        0
    } else {
        int.parse().unwrap()
    };
    if mm >= 100_000 {
        return Err(LengthRefusal::OutOfRange);
    }
    let mut nm: i64 = 0;
    for i in 0..6 {
        nm = nm * 10 + frac.as_bytes().get(i).map_or(0, |d| i64::from(d - b'0'));
    }
    let a = (mm * 1_000_000 + nm) * 10;
    Ok(if negative { -a } else { a })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths() {
        assert_eq!(parse_mm("12.5"), Ok(125_000_000));
        assert_eq!(parse_mm("-0.000001"), Ok(-10));
        assert_eq!(parse_mm("+99999.999999"), Ok(COORD_MAX_ANGSTROM));
        assert_eq!(parse_mm("100000"), Err(LengthRefusal::OutOfRange));
        assert_eq!(parse_mm("1.0000001"), Err(LengthRefusal::TooManyDecimals));
        for bad in ["", ".5", "5.", "1e3", "--1", "1.2.3"] {
            assert_eq!(parse_mm(bad), Err(LengthRefusal::Malformed), "{bad:?}");
        }
    }
}

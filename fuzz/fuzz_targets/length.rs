//! Arbitrary UTF-8 into `Length::from_mm_str` and `Length::from_gcode_mm`.
//!
//! Checked against an independent reading of `[+-]?[0-9]+(\.[0-9]{1,6})?`
//! with magnitude below 100 000 mm (exact integer arithmetic):
//! - accepted exactly when the reference accepts, with exactly the same
//!   number of ångström; a refusal names the same reason (malformed before
//!   too many decimals before out of range);
//! - `to_string()` is the value in 0.0001 mm rounded half away from zero,
//!   and re-parses to within 0.00005 mm of the value;
//! - the G-code reading (`30.`, `.5`, any count of decimals (read to the 30th) rounded once to the
//!   ångström), in millimetres and in inches, agrees with its reference to
//!   the ångström and in its refusal,
//!   and equals the protocol's reading wherever that one accepts.
#![no_main]

use core_nostd::length::{Length, LengthError};
use fuzz_oracle::{mm4_of, parse_gcode_inch, parse_gcode_mm, parse_mm, LengthRefusal};
use libfuzzer_sys::fuzz_target;

fn refusal(e: LengthError) -> LengthRefusal {
    match e {
        LengthError::Malformed => LengthRefusal::Malformed,
        LengthError::TooManyDecimals => LengthRefusal::TooManyDecimals,
        LengthError::OutOfRange => LengthRefusal::OutOfRange,
    }
}

fuzz_target!(|text: &str| {
    let gcode = Length::from_gcode_mm(text).map(Length::as_angstrom);
    assert_eq!(
        gcode.map_err(refusal),
        parse_gcode_mm(text),
        "G-code number {text:?}"
    );
    assert_eq!(
        Length::from_gcode_inch(text)
            .map(Length::as_angstrom)
            .map_err(refusal),
        parse_gcode_inch(text),
        "G-code inches {text:?}"
    );
    if let Ok(l) = Length::from_mm_str(text) {
        assert_eq!(gcode, Ok(l.as_angstrom()), "{text:?}");
    }
    let got = Length::from_mm_str(text);
    let want = parse_mm(text);
    match (got, want) {
        (Ok(l), Ok(a)) => {
            assert_eq!(l.as_angstrom(), a, "{text:?}");
            let printed = l.to_string();
            assert_eq!(printed, mm4_of(a.into()), "{text:?}");
            if printed.trim_start_matches('-') == "100000.0000" {
                // From 99999.99995 mm up the 4-decimal figure rounds to
                // 100000.0000, one past the largest word (documented; see
                // tests/tests/fuzz_regressions.rs, `printed_length_at_the_limit`).
                // The figure itself is checked above.
                return;
            }
            let back = Length::from_mm_str(&printed)
                .unwrap_or_else(|e| panic!("{text:?} prints {printed:?}, which is refused: {e:?}"));
            assert!(
                (back.as_angstrom() - a).abs() <= 500,
                "{text:?} prints {printed:?}, which reads back {} Å away",
                back.as_angstrom() - a
            );
        }
        (Err(e), Err(r)) => assert_eq!(refusal(e), r, "{text:?}"),
        (got, want) => panic!("{text:?}: core {got:?}, reference {want:?}"),
    }
});

//! Arbitrary UTF-8 into the G-code block parser alone, at volume.
//!
//! Checked:
//! - `parse_block` agrees with an independent reading of the block grammar
//!   (same words, same values to the ångström, same refusal), in the ISO
//!   dialect and in Fanuc's, in millimetres and in inches;
//! - an accepted block written back canonically parses to the same block;
//! - `is_block` agrees with the reference.
//!
//! The `gcode` target sends the block lines through devices.
#![no_main]

mod block_grammar;

use block_grammar::{
    as_reference, as_reference_error, beyond_the_reference, canonical, names_a_code_beyond,
    names_a_corner,
};
use core_nostd::gcode::{is_block, parse, parse_block, Dialect, Units};
use fuzz_oracle::{reference_block, reference_block_in, reference_is_block};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|text: &str| {
    let parsed = parse_block(text);
    let reference = reference_block(text);
    if beyond_the_reference(&parsed, &reference)
        || names_a_code_beyond(text, false, false)
        || names_a_corner(text)
    {
        return;
    }
    for units in [Units::Mm, Units::Inch] {
        let fanuc = parse(text, Dialect::Fanuc, units).map_err(|l| l.error);
        let inch = units == Units::Inch;
        if beyond_the_reference(&fanuc, &reference_block_in(text, true, inch))
            || names_a_code_beyond(text, true, inch)
        {
            return;
        }
    }
    match (&parsed, &reference) {
        (Ok(b), Ok(r)) => {
            assert_eq!(as_reference(b), *r, "{text:?}");
            let again = canonical(r);
            assert_eq!(
                parse_block(&again).map(|b| as_reference(&b)),
                Ok(r.clone()),
                "{text:?} written back as {again:?}"
            );
        }
        (Err(e), Err(r)) => assert_eq!(as_reference_error(*e), *r, "{text:?}"),
        _ => panic!("{text:?}: core {parsed:?}, reference {reference:?}"),
    }
    assert_eq!(is_block(text), reference_is_block(text), "{text:?}");
    // The Fanuc dialect, in millimetres and in inches.
    for units in [Units::Mm, Units::Inch] {
        let fanuc = parse(text, Dialect::Fanuc, units).map_err(|l| l.error);
        let reference = reference_block_in(text, true, units == Units::Inch);
        match (&fanuc, &reference) {
            (Ok(b), Ok(r)) => assert_eq!(as_reference(b), *r, "Fanuc {text:?}"),
            (Err(e), Err(r)) => assert_eq!(as_reference_error(*e), *r, "Fanuc {text:?}"),
            _ => panic!("Fanuc {text:?}: core {fanuc:?}, reference {reference:?}"),
        }
    }
});

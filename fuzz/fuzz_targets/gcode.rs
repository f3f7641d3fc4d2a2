//! Block lines through the device as requests (the `block` target checks
//! the parser alone, against the reference).
//!
//! Checked:
//! - a block line sent to devices in four different states (power-on;
//!   moved with a fine X price; radius mode, G91 G01; G03 modal after an arc)
//!   gets exactly one final line, with the checks of `fuzz_oracle::request`
//!   (an `ERR` changes nothing, registers hold `Q(P/h)`, motion agrees);
//! - a block the parser refuses is refused by the device with the matching
//!   code (`SYNTAX` for word errors, `VALUE` for numbers and G codes);
//! - an accepted block leaves the commanded point at the block's end point in
//!   the modal distance mode (X a diameter when `DIAM=1`), except a block
//!   that switches G41/G42 on: nothing moves until the block after it.
#![no_main]

mod block_grammar;

use block_grammar::{beyond_the_reference, names_a_corner};
use core_nostd::gcode::{
    is_block, parse, parse_block, BlockError, Compensation, Dialect, Special, Units,
};
use core_nostd::protocol::Device;
use fuzz_oracle::{
    device_after, reference_block, reference_block_in, Checker, LIMIT_ANGSTROM, MAX_LINE,
};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

/// Devices in known states, with their modal distance mode (G91 = true).
fn preludes() -> &'static [(Device, bool)] {
    static P: OnceLock<Vec<(Device, bool)>> = OnceLock::new();
    P.get_or_init(|| {
        vec![
            (fuzz_oracle::fuzz_device(), false),
            (
                device_after(&[
                    "CFG HX=0.0025 TOL=0.02 PASS=ROUGH",
                    "MOVE X=12.345678 Z=-7.000005",
                ]),
                false,
            ),
            (
                device_after(&["CFG DIAM=0 HX=0.001 HZ=0.001", "G91 G01 X10 Z-3 F100"]),
                true,
            ),
            (
                device_after(&["G00 X10 Z10", "G01 X7.2 Z0 F200", "G03 X12 Z-2.4 R2.4"]),
                false,
            ),
        ]
    })
}

fuzz_target!(|text: &str| {
    let parsed = parse_block(text);
    let reference = reference_block(text);
    if beyond_the_reference(&parsed, &reference) || names_a_corner(text) {
        return;
    }
    for units in [Units::Mm, Units::Inch] {
        let fanuc = parse(text, Dialect::Fanuc, units).map_err(|l| l.error);
        if beyond_the_reference(
            &fanuc,
            &reference_block_in(text, true, units == Units::Inch),
        ) {
            return;
        }
    }
    let line = text.split(['\r', '\n']).next().unwrap_or("");
    if !is_block(line) {
        return;
    }
    let plain = line.len() <= MAX_LINE
        && !line.contains(['*', '~'])
        && line
            .bytes()
            .all(|b| b == b'\t' || (0x20..0x7F).contains(&b));
    let parsed = parse_block(line);
    for (prelude, incremental) in preludes() {
        let mut c = Checker::new(prelude.clone());
        let (x0, z0) = c.dev.session().commanded();
        let diam = c.dev.session().config().diam;
        let answer = c.line(line, false);
        if answer.skipped {
            continue;
        }
        let dev = &c.dev;
        if !plain {
            continue;
        }
        match (&parsed, answer.err()) {
            (Err(e), code) => {
                let want = match e {
                    BlockError::Value(..)
                    | BlockError::UnsupportedG(_)
                    | BlockError::UnsupportedM(_)
                    | BlockError::Cycle(_)
                    | BlockError::OtherDialect(..)
                    | BlockError::Range(..)
                    | BlockError::NoYAxis => "VALUE",
                    _ => "SYNTAX",
                };
                assert_eq!(code, Some(want), "{line:?} ({e:?}) -> {:?}", answer.lines);
            }
            (Ok(b), None) => {
                let inc = b.incremental.unwrap_or(*incremental);
                let arc_words = b.i.is_some() || b.k.is_some() || b.r.is_some();
                // G10's X and Z are an offset's.
                let moves = (b.x.is_some() || b.z.is_some() || arc_words)
                    && b.set_work.is_none()
                    && b.special.is_none();
                let end = |word: Option<core_nostd::length::Length>, now: i64, half: bool| {
                    word.map_or(now, |w| {
                        let w = w.as_angstrom();
                        let w = if half { w / 2 } else { w };
                        if inc {
                            now + w
                        } else {
                            w
                        }
                    })
                };
                let (x0, z0) = (x0.as_angstrom(), z0.as_angstrom());
                // Compensation switched on (all preludes have it off): the
                // start-up block's motion waits for the next block.
                let starting = b.compensation.is_some_and(|c| c != Compensation::Off);
                let none = b.x.is_none() && b.z.is_none();
                let want = if let Some(Special::Reference(_)) = b.special {
                    // To machine zero (nothing stored) on the axes named,
                    // all without a way point.
                    (
                        if none || b.x.is_some() { 0 } else { x0 },
                        if none || b.z.is_some() { 0 } else { z0 },
                    )
                } else if b.special == Some(Special::Machine) {
                    // A diameter is halved once from the number as written
                    // (the parser's `x_half`), not from its rounded value.
                    let x = if b.diameter.unwrap_or(diam) {
                        b.x_half
                    } else {
                        b.x
                    };
                    let at = |w: Option<core_nostd::length::Length>, now: i64| {
                        w.map_or(now, |w| w.as_angstrom())
                    };
                    (at(x, x0), at(b.z, z0))
                } else if moves && !starting {
                    (
                        end(
                            if b.diameter.unwrap_or(diam) {
                                b.x_half
                            } else {
                                b.x
                            },
                            x0,
                            false,
                        ),
                        end(b.z, z0, false),
                    )
                } else {
                    (x0, z0)
                };
                assert!(want.0.abs() <= LIMIT_ANGSTROM && want.1.abs() <= LIMIT_ANGSTROM);
                let (x, z) = dev.session().commanded();
                assert_eq!(
                    (x.as_angstrom(), z.as_angstrom()),
                    want,
                    "{line:?} -> {:?}",
                    answer.lines
                );
                if starting {
                    assert!(
                        !answer.lines.iter().any(|l| l.starts_with("DATA")),
                        "{line:?}: the start-up block moved at once: {:?}",
                        answer.lines
                    );
                }
            }
            (Ok(_), Some(_)) => {}
        }
    }
});

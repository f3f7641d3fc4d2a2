//! Arbitrary UTF-8 into the G-code block parser, and block lines through the
//! device as requests.
//!
//! Checked:
//! - `parse_block` agrees with an independent reading of the block grammar
//!   (same words, same values to the ångström, same refusal);
//! - an accepted block written back canonically parses to the same block;
//! - `is_block` agrees with the reference;
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

use core_nostd::gcode::{
    is_block, parse, parse_block, Block, BlockError, Compensation, Coolant, Corner, Dialect,
    FeedMode, LineKind, Motion, Plane, Special, Spindle, SpindleMode, Stop, ToolOffset, Units,
};
use core_nostd::length::LengthError;
use core_nostd::protocol::Device;
use fuzz_oracle::{
    device_after, exact_gcode_mm, reference_block, reference_block_in, reference_is_block, Checker,
    LengthRefusal, RefBlock, RefBlockError, LIMIT_ANGSTROM, MAX_LINE,
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

fn as_reference(b: &Block) -> RefBlock {
    let a = |l: Option<core_nostd::length::Length>| l.map(|l| l.as_angstrom());
    RefBlock {
        kind: match b.kind {
            LineKind::Words => 0,
            LineKind::TapeMark => 1,
            LineKind::Program => 2,
        },
        deleted: b.deleted,
        motion: b.motion.map(|m| match m {
            Motion::Rapid => 0,
            Motion::Linear => 1,
            Motion::ArcCw => 2,
            Motion::ArcCcw => 3,
        }),
        compensation: b.compensation.map(|c| match c {
            Compensation::Off => 40,
            Compensation::Left => 41,
            Compensation::Right => 42,
        }),
        distance: b.incremental.map(|i| if i { 91 } else { 90 }),
        plane: b.plane.map(|p| match p {
            Plane::Xy => 17,
            Plane::Zx => 18,
            Plane::Yz => 19,
        }),
        units: b.units.map(|u| match u {
            Units::Inch => 20,
            Units::Mm => 21,
        }),
        corner: b.corner.map(|c| match c {
            Corner::Arc => 450,
            Corner::Intersection => 451,
        }),
        xzikr: [a(b.x), a(b.z), a(b.i), a(b.k), a(b.r)],
        f: a(b.f),
        diameter: b.diameter.map(|d| if d { 7 } else { 8 }),
        arc_distance: b.arc_absolute.map(|a| if a { 901 } else { 911 }),
        feed_mode: b.feed_mode.map(|m| match m {
            FeedMode::PerMinute => 94,
            FeedMode::PerRev => 95,
        }),
        spindle_mode: b.spindle_mode.map(|m| match m {
            SpindleMode::Surface => 96,
            SpindleMode::Rpm => 97,
        }),
        dwell_us: b.dwell,
        s: a(b.s),
        clamp: a(b.clamp),
        tool: b.tool.map(|t| t.tool),
        offset: b.tool.and_then(|t| t.offset),
        from_u_w: [b.incremental_x, b.incremental_z],
        wcs: b.wcs,
        set_work: b.set_work.map(|w| (w.register, w.here)),
        tool_offset: b.tool_offset.map(|t| match t {
            ToolOffset::On(h) => (true, h),
            ToolOffset::Off => (false, None),
        }),
        tool_change: b.tool_change,
        position_offset: b.position_offset.map(|p| (p.times, p.register)),
        special: b.special.map(|s| match s {
            Special::Reference(n) => 280 + 20 * u16::from(n),
            Special::Store(n) => 281 + 20 * u16::from(n),
            Special::Machine => 530,
            Special::Shift => 920,
            Special::ClearShift(keep) => 921 + u16::from(keep),
            Special::RestoreShift => 923,
        }),
        m: [
            b.stop.map(|s| match s {
                Stop::Pause => 0,
                Stop::Optional => 1,
                Stop::End => 30,
            }),
            b.spindle.map(|s| match s {
                Spindle::Cw => 3,
                Spindle::Ccw => 4,
                Spindle::Off => 5,
            }),
            b.coolant.map(|c| match c {
                Coolant::Mist => 7,
                Coolant::Flood => 8,
                Coolant::Off => 9,
            }),
        ],
    }
}

fn as_reference_error(e: BlockError) -> RefBlockError {
    match e {
        BlockError::UnknownAddress(l) => RefBlockError::UnknownAddress(l),
        BlockError::Repeated(l) => RefBlockError::Repeated(l),
        BlockError::NotAWord => RefBlockError::NotAWord,
        BlockError::Comment => RefBlockError::Comment,
        BlockError::UnsupportedG(_) => RefBlockError::UnsupportedG,
        BlockError::UnsupportedM(_) => RefBlockError::UnsupportedM,
        BlockError::Cycle(_) => RefBlockError::Cycle,
        BlockError::OtherDialect(..) => RefBlockError::OtherDialect,
        BlockError::Form(_) => RefBlockError::Form,
        BlockError::Range(l, _) => RefBlockError::Range(l),
        BlockError::NoYAxis => RefBlockError::NoYAxis,
        BlockError::ProgramNumber => RefBlockError::ProgramNumber,
        BlockError::HostLanguage => RefBlockError::HostLanguage,
        BlockError::Value(l, e) => RefBlockError::Value(
            l,
            match e {
                LengthError::Malformed => LengthRefusal::Malformed,
                LengthError::TooManyDecimals => LengthRefusal::TooManyDecimals,
                LengthError::OutOfRange => LengthRefusal::OutOfRange,
            },
        ),
    }
}

/// Ångström as inches with 15 decimals (rounded half away from zero; read
/// back at 254 000 000 Å an inch it is within 10⁻⁶ Å of the value).
fn inch_15(angstrom: i64) -> String {
    let a = i128::from(angstrom.unsigned_abs()) * 10i128.pow(15);
    let q = a / 254_000_000 + i128::from(2 * (a % 254_000_000) >= 254_000_000);
    let sign = if angstrom < 0 { "-" } else { "" };
    let unit = 10i128.pow(15);
    let frac = format!("{:015}", q % unit);
    format!("{sign}{}.{}", q / unit, frac.trim_end_matches('0'))
}

/// The block written back in canonical form.
fn canonical(b: &RefBlock) -> String {
    match b.kind {
        1 => return "%".to_string(),
        2 => return "O1".to_string(),
        _ => {}
    }
    let mut words = Vec::new();
    for g in [
        b.motion,
        b.plane,
        b.units,
        b.compensation,
        b.distance,
        b.diameter,
        b.feed_mode,
        b.spindle_mode,
    ]
    .into_iter()
    .flatten()
    {
        words.push(format!("G{g:02}"));
    }
    if let Some(g) = b.corner {
        words.push(format!("G{g}"));
    }
    if let Some(g) = b.arc_distance {
        words.push(format!("G{}.{}", g / 10, g % 10));
    }
    if let Some(us) = b.dwell_us {
        words.push(format!("G04 P{}.{:06}", us / 1_000_000, us % 1_000_000));
    }
    // S and D are numbers without a unit, even under G20.
    if let Some(v) = b.s {
        words.push(format!("S{}", exact_gcode_mm(v)));
    }
    if let Some(v) = b.clamp {
        words.push(format!("D{}", exact_gcode_mm(v)));
    }
    if let Some(t) = b.tool {
        words.push(format!("T{t}"));
    }
    for m in b.m.into_iter().flatten() {
        words.push(format!("M{m}"));
    }
    if b.tool_change {
        words.push("M6".into());
    }
    if let Some(w) = b.wcs {
        words.push(format!("G{}", 54 + w));
    }
    if let Some((p, here)) = b.set_work {
        words.push(format!("G10 L{} P{p}", if here { 20 } else { 2 }));
    }
    if let Some(g) = b.special {
        words.push(format!("G{}.{}", g / 10, g % 10));
    }
    if let Some((times, register)) = b.position_offset {
        let g = match times {
            1 => 45,
            -1 => 46,
            2 => 47,
            _ => 48,
        };
        words.push(format!("G{g} D{register}"));
    }
    match b.tool_offset {
        Some((true, Some(h))) => words.push(format!("G43 H{h}")),
        Some((true, None)) => words.push("G43".into()),
        Some((false, _)) => words.push("G49".into()),
        None => {}
    }
    for (letter, v) in ['X', 'Z', 'I', 'K', 'R', 'F']
        .iter()
        .zip(b.xzikr.iter().chain([&b.f]))
    {
        if let Some(v) = v {
            let value = if b.units == Some(20) {
                inch_15(*v)
            } else {
                exact_gcode_mm(*v)
            };
            words.push(format!("{letter}{value}"));
        }
    }
    let line = words.join(" ");
    if b.deleted {
        format!("/{line}")
    } else {
        line
    }
}

/// A block the core reads and the reference's grammar does not know yet:
/// the codes and forms the core gained after the reference was written
/// (the planes G17/G19, path control, G80, gear ranges and the machine's
/// own M codes, the turning cycles, comments with any character, F0).
/// The two are not compared on it (docs/verification.md).
fn beyond_the_reference(
    core: &Result<Block, BlockError>,
    reference: &Result<RefBlock, RefBlockError>,
) -> bool {
    let Err(r) = reference else {
        return false;
    };
    let newer = matches!(
        r,
        RefBlockError::UnsupportedG
            | RefBlockError::UnsupportedM
            | RefBlockError::Cycle
            | RefBlockError::Comment
            | RefBlockError::Range(b'F')
    );
    // The core read past the code the reference stops at (and then
    // accepted the block, or refused something after it).
    newer && core.as_ref().err().map(|e| as_reference_error(*e)) != Some(*r)
}

fuzz_target!(|text: &str| {
    let parsed = parse_block(text);
    let reference = reference_block(text);
    if beyond_the_reference(&parsed, &reference) {
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

//! The block grammar as the fuzz targets compare it: the core's parsed
//! block as the reference's, a reference block written back canonically,
//! and what the reference cannot read (shared by `block` and `gcode`).

// Each target uses a part.
#![allow(dead_code)]

use core_nostd::gcode::{
    Block, BlockError, Compensation, Coolant, Corner, FeedMode, LineKind, Motion, Plane, Special,
    Spindle, SpindleMode, Stop, ToolOffset, Units,
};
use core_nostd::length::LengthError;
use fuzz_oracle::{exact_gcode_mm, reference_block_in, LengthRefusal, RefBlock, RefBlockError};

pub fn as_reference(b: &Block) -> RefBlock {
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
        // A tool's register (G10 L1/L10) as 100 + n.
        set_work: b
            .set_work
            .map(|w| (w.register + if w.tool { 100 } else { 0 }, w.here)),
        tool_offset: b.tool_offset.map(|t| match t {
            ToolOffset::On(h) => (true, h),
            ToolOffset::Off => (false, None),
        }),
        tool_change: b.tool_change,
        position_offset: b.position_offset.map(|p| (p.times, p.register)),
        nose_tool: b.nose_tool,
        special: b.special.map(|s| match s {
            Special::Reference(n) => 280 + 20 * u16::from(n),
            Special::Store(n) => 281 + 20 * u16::from(n),
            Special::Machine => 530,
            Special::Shift => 920,
            Special::ClearShift(keep) => 921 + u16::from(keep),
            Special::RestoreShift => 923,
            Special::Probe(mode) => mode.code(),
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

pub fn as_reference_error(e: BlockError) -> RefBlockError {
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
pub fn inch_15(angstrom: i64) -> String {
    let a = i128::from(angstrom.unsigned_abs()) * 10i128.pow(15);
    let q = a / 254_000_000 + i128::from(2 * (a % 254_000_000) >= 254_000_000);
    let sign = if angstrom < 0 { "-" } else { "" };
    let unit = 10i128.pow(15);
    let frac = format!("{:015}", q % unit);
    format!("{sign}{}.{}", q / unit, frac.trim_end_matches('0'))
}

/// The block written back in canonical form.
pub fn canonical(b: &RefBlock) -> String {
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
    if let Some(t) = b.nose_tool {
        words.push(format!("D{t}"));
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
    match b.set_work {
        // A tool's register is written 100 + n by the reference.
        Some((p, l10)) if p > 100 => {
            words.push(format!("G10 L{} P{}", if l10 { 10 } else { 1 }, p - 100))
        }
        Some((p, here)) => words.push(format!("G10 L{} P{p}", if here { 20 } else { 2 })),
        None => {}
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
pub fn beyond_the_reference(
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

/// Whether a line holds a comma before a `C` or `R` (blanks between),
/// anywhere (comments too: it only leaves more lines out): Fanuc's and
/// Haas' corner words `,C` and `,R`, which the reference's grammar does
/// not read (it refuses a comma as no word), and which the core reads in
/// the Fanuc dialect and refuses by name in the ISO one.
pub fn names_a_corner(text: &str) -> bool {
    let b = text.as_bytes();
    (0..b.len()).any(|i| {
        b[i] == b','
            && b[i + 1..]
                .iter()
                .find(|c| !matches!(c, b' ' | b'\t'))
                .is_some_and(|c| matches!(c.to_ascii_uppercase(), b'C' | b'R'))
    })
}

/// Whether a line names, anywhere (comments too: it only leaves more lines
/// out), a G code the reference does not read (it refuses it as newer than
/// itself: a turning cycle, `G64`'s tolerances, LinuxCNC's `G41.1`): such a
/// code can change how the words before it read (`P` a tolerance, `D` a
/// nose or a depth), and the reference stops before it, so the line is
/// beyond it whatever stands first.
pub fn names_a_code_beyond(text: &str, fanuc: bool, inch: bool) -> bool {
    let b = text.as_bytes();
    (0..b.len()).any(|i| {
        if !b[i].eq_ignore_ascii_case(&b'G') {
            return false;
        }
        // `i` is at an ASCII byte: `i + 1` is a char boundary. Spaces and
        // tabs may stand between the letter and its number.
        let number: String = text[i + 1..]
            .trim_start_matches([' ', '\t'])
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '.')
            .collect();
        !number.is_empty()
            && matches!(
                reference_block_in(&format!("G{number}"), fanuc, inch),
                Err(RefBlockError::UnsupportedG | RefBlockError::Cycle)
            )
    })
}

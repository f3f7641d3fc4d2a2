//! Which dialect a program is written in, when the command line leaves it
//! to the program (`--dialect auto`).
//!
//! A line is evidence for a dialect when the device's reader reads it in
//! that dialect and refuses it in the other as a word of the first (`U`,
//! `W`, `G98`, `G99`, `G50` are Fanuc's; `G7`, `G8`, `G91`, `G95`, `G90.1`
//! ISO's), or when it names a tool the other cannot (`T0101`). A line the
//! reader refuses in both says nothing; nor does a Fanuc cycle (`G90 X Z F`),
//! which ISO would read as a plain move: a program with only such lines is
//! no evidence, and is read as ISO, the power-on dialect, saying so.

use core_nostd::gcode::{is_block, parse, BlockError, Dialect, Units};

/// What `--dialect auto` found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Detected {
    /// Only this dialect's words, first seen on this line (from 1).
    Clear(Dialect, usize),
    /// Words of neither: read as ISO.
    None,
    /// Both: the first line of each (Fanuc, ISO).
    Mixed(usize, usize),
}

/// The dialect a program's lines speak.
pub fn detect(text: &str) -> Detected {
    let mut units = [Units::Mm; 2];
    let mut first = [None::<usize>; 2];
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim_end_matches('\r');
        if !is_block(line) {
            continue;
        }
        let iso = parse(line, Dialect::Iso, units[0]);
        let fanuc = parse(line, Dialect::Fanuc, units[1]);
        if let Ok(b) = &iso {
            units[0] = b.units.unwrap_or(units[0]);
        }
        if let Ok(b) = &fanuc {
            units[1] = b.units.unwrap_or(units[1]);
        }
        let speaks = |theirs: &Result<_, core_nostd::gcode::Located>, ours: Dialect| {
            theirs.as_ref().err().is_some_and(|e| {
                matches!(e.error, BlockError::OtherDialect(_, _, d) if d == ours)
                    || (ours == Dialect::Fanuc && e.error == tool_out_of_range())
            })
        };
        if fanuc.is_ok() && speaks(&iso, Dialect::Fanuc) {
            first[1].get_or_insert(i + 1);
        }
        if iso.is_ok() && speaks(&fanuc, Dialect::Iso) {
            first[0].get_or_insert(i + 1);
        }
    }
    match first {
        [None, None] => Detected::None,
        [Some(iso), None] => Detected::Clear(Dialect::Iso, iso),
        [None, Some(fanuc)] => Detected::Clear(Dialect::Fanuc, fanuc),
        [Some(iso), Some(fanuc)] => Detected::Mixed(fanuc, iso),
    }
}

/// ISO refuses a tool of more than two digits (`T0101`).
fn tool_out_of_range() -> BlockError {
    BlockError::Range(b'T', "names a tool 0 to 99")
}

/// The dialect for `--dialect` (`iso`, `fanuc` or `auto`) and a program's
/// text, with a line for the person saying what auto-detection chose; an
/// error for a mixed program or an unknown name.
pub fn choose(flag: &str, text: &str) -> Result<(Dialect, Option<String>), String> {
    match flag.to_ascii_lowercase().as_str() {
        "iso" => Ok((Dialect::Iso, None)),
        "fanuc" => Ok((Dialect::Fanuc, None)),
        "auto" => match detect(text) {
            Detected::Clear(d, line) => Ok((
                d,
                Some(format!(
                    "dialect: {} (line {line} is one of its words)",
                    d.as_str()
                )),
            )),
            Detected::None => Ok((
                Dialect::Iso,
                Some("dialect: ISO (no line is only one dialect's; --dialect fanuc to read it as Fanuc)".into()),
            )),
            Detected::Mixed(fanuc, iso) => Err(format!(
                "the program mixes dialects: line {fanuc} is Fanuc's, line {iso} ISO's; choose one with --dialect"
            )),
        },
        other => Err(format!("--dialect {other}: must be iso, fanuc or auto")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn programs_say_their_dialect() {
        let fanuc = "%\nO1000\nG21 G18 G99\nT0101\nG50 S2500\nG96 S180 M03\nG00 X30. Z2.\n";
        assert_eq!(detect(fanuc), Detected::Clear(Dialect::Fanuc, 3));
        assert_eq!(
            detect("G00 X10\nU2. W-1.\n"),
            Detected::Clear(Dialect::Fanuc, 2)
        );
        let iso = "G7 G18 G21\nG95 F.1\nG00 X20 Z2\n";
        assert_eq!(detect(iso), Detected::Clear(Dialect::Iso, 1));
        // A Fanuc turning cycle reads as a move in ISO: no evidence.
        assert_eq!(detect("G00 X20 Z2\nG90 X18 Z-20 F.2\n"), Detected::None);
        assert_eq!(detect("G99 F.1\nG95\n"), Detected::Mixed(1, 2));
        assert!(choose("auto", "G99 F.1\nG95\n")
            .unwrap_err()
            .contains("line 1"));
        assert_eq!(choose("Fanuc", "G95").unwrap().0, Dialect::Fanuc);
        assert!(choose("haas", "").is_err());
    }
}

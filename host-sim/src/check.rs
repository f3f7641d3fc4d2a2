//! `host-sim check`: every line of a G-code file the device would refuse,
//! with its line and column, before the program is sent; and the lines
//! where it will stop for the operator (a gear range, the machine's own M
//! codes), as warnings.
//!
//! The program is run through the in-process device exactly as `run` runs
//! it (the same lines, [`crate::program::program_lines`]), so what is
//! listed is exactly what `run` refuses: unknown addresses, malformed
//! numbers, unsupported codes, and geometry (an arc whose radii differ, a
//! move beyond the machine). Each refusal is placed at the column of the
//! word the device's reader names, where it names one.

use crate::program::{program_lines, run, Options};
use core_nostd::gcode::{is_block, parse, Dialect, Units};

/// One refused item.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Item {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1 (bytes).
    pub column: usize,
    /// What is wrong, as the device says it.
    pub what: String,
}

/// The items of a program's text in the ISO dialect, in order.
pub fn check(text: &str) -> Vec<Item> {
    check_in(text, Dialect::Iso)
}

/// The items of a program's text in `dialect`, in order: the lines `run`
/// refuses, each once, with the device's words.
///
/// A program with macros, subprograms or expressions is expanded first, as
/// the host does before streaming: what cannot be expanded is the one item
/// then; otherwise a block an expression wrote is named as written.
pub fn check_in(text: &str, dialect: Dialect) -> Vec<Item> {
    check_read(text, dialect, false)
}

/// As [`check_in`], X words read as radii from the start when `radius`
/// (LinuxCNC's G8, `run --radius`): the same reading as `run`'s.
pub fn check_read(text: &str, dialect: Dialect, radius: bool) -> Vec<Item> {
    let source: Vec<&str> = text.split('\n').collect();
    let lines = match program_lines(text, dialect) {
        Ok(lines) => lines,
        Err(e) => {
            return vec![Item {
                line: e.line,
                column: e.column,
                what: e.what,
            }]
        }
    };
    let report = run(
        text,
        Options {
            dialect,
            radius,
            optional_stop: false,
        },
    );
    // Where the reader places each line's first refusal, for its column.
    let mut columns: Vec<(usize, usize)> = Vec::new();
    let mut units = Units::Mm;
    for (i, line) in &lines {
        if line.trim().is_empty() || !is_block(line) {
            continue;
        }
        match parse(line, dialect, units) {
            Ok(b) => units = b.units.unwrap_or(units),
            Err(e) => columns.push((*i + 1, e.column)),
        }
    }
    let mut items: Vec<Item> = Vec::new();
    for (refused, &at) in report.refused.iter().zip(&report.refused_at) {
        let line = refused.line;
        // The device's words, without the protocol's code.
        let what = refused
            .reply
            .strip_prefix("ERR ")
            .and_then(|r| r.split_once(' '))
            .map_or(refused.reply.as_str(), |(_, w)| w)
            .to_string();
        let sent = lines.get(at).map(|(_, l)| l.as_str());
        let written = source
            .get(line - 1)
            .map(|l| l.strip_suffix('\r').unwrap_or(l));
        let what = match (sent, written) {
            (Some(s), Some(w)) if crate::program::device_text(w) != s => {
                format!("{what} (in `{s}`)")
            }
            _ => what,
        };
        let column = columns
            .iter()
            .find(|(l, _)| *l == line)
            .map_or_else(|| leading(written.unwrap_or("")), |(_, c)| *c);
        let item = Item { line, column, what };
        if !items.contains(&item) {
            items.push(item);
        }
    }
    items
}

/// Where a line's text begins (column from 1).
fn leading(line: &str) -> usize {
    line.len() - line.trim_start().len() + 1
}

/// What the file holds outside its program (a tape's leader and trailer,
/// [`crate::program::framing`]), and the lines where the program stops for
/// the operator: a gear range
/// (`M41`–`M44`) and the machine's own M codes (each does what the
/// machine's table says, `MCODE`; one not in it stops with a message);
/// and the probing blocks, which only the machine can run as they are.
pub fn warnings_in(text: &str, dialect: Dialect) -> Vec<Item> {
    let Ok(lines) = program_lines(text, dialect) else {
        return Vec::new();
    };
    let mut out: Vec<Item> = crate::program::framing(text)
        .notes()
        .into_iter()
        .map(|(line, what)| Item {
            line,
            column: 1,
            what,
        })
        .collect();
    let mut units = Units::Mm;
    for (i, line) in &lines {
        if line.trim().is_empty() || !is_block(line) {
            continue;
        }
        let Ok(b) = parse(line, dialect, units) else {
            continue;
        };
        units = b.units.unwrap_or(units);
        let column = line.find(['M', 'm']).map_or(1, |c| c + 1);
        if let Some(g) = b.gear {
            out.push(Item {
                line: i + 1,
                column,
                what: format!(
                    "M4{g}: the program stops for the gearbox to be shifted to range {g}"
                ),
            });
        }
        if let Some(core_nostd::gcode::Special::Probe(mode)) = b.special {
            let g = mode.code();
            out.push(Item {
                line: i + 1,
                column: line.find(['G', 'g']).map_or(1, |c| c + 1),
                what: format!(
                    "G{}.{}: probes on the machine, stopping where the probe changes; run and checked here as a feed move to its end",
                    g / 10,
                    g % 10
                ),
            });
        }
        if let Some(code) = b.machine_m {
            out.push(Item {
                line: i + 1,
                column,
                what: format!(
                    "M{:02}: the machine's own M code; it stops the program with a message unless the machine's table (MCODE) says otherwise",
                    code / 10
                ),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A probing program passes: its probing blocks are warnings (only the
    /// machine probes), run here as feed moves to their end, and what comes
    /// after them is checked from there.
    #[test]
    fn probing_blocks_are_warnings_and_run_to_their_end() {
        let program =
            "G21 G18 G90 G94\nG0 Z0\nG38.2 Z-60 F300\nG10 L20 P1 Z0\nG0 Z10\n  G38.5 X4\nM2\n";
        assert_eq!(check(program), [], "nothing refused");
        let w = warnings_in(program, Dialect::Iso);
        let at: Vec<(usize, usize)> = w.iter().map(|i| (i.line, i.column)).collect();
        assert_eq!(at, [(3, 1), (6, 3)], "{w:?}");
        assert!(
            w[0].what.starts_with("G38.2: probes on the machine"),
            "{w:?}"
        );
        assert!(w[1].what.starts_with("G38.5: "), "{w:?}");
        // Past the probe: a block beyond the range still refused, by line.
        let bad = check("G21 G18 G90 G94\nG38.2 Z-60 F300\nG02 X10 Z-70 R1\n");
        assert_eq!(bad.len(), 1, "{bad:?}");
        assert_eq!(bad[0].line, 3);
    }

    #[test]
    fn every_refused_line_is_listed_with_its_place() {
        let program = "%\r\nO1000 (SHAFT)\r\nN10 G18 G28.2\r\nN20 G00 X30. Z2. Y1\r\n\r\nN30 G01 X.5 F100\r\nMOVE X=1\r\nN40 Q5\r\n%\r\n";
        let items = check(program);
        let got: Vec<(usize, usize, &str)> = items
            .iter()
            .map(|i| (i.line, i.column, i.what.as_str()))
            .collect();
        assert_eq!(
            got,
            [
                (3, 9, "G28.2 not supported"),
                (4, 18, "Y a lathe has no Y axis: only Y0"),
                (7, 1, "not a G-code line"),
                (8, 5, "unknown address Q"),
            ]
        );
        assert!(check("G00 X1\nG02 X3 Z-1 R1 F100\n").is_empty());
        // What run refuses, check lists: a feed never set, an arc that
        // cannot be.
        let items = check("G01 X1\nG00 X1\nG02 X3 Z-10 R1 F100\n");
        let got: Vec<(usize, &str)> = items.iter().map(|i| (i.line, i.what.as_str())).collect();
        assert_eq!(
            got,
            [
                (1, "F not programmed: a feed move needs F (mm/min)"),
                (3, "radius smaller than half the distance to the end point"),
            ]
        );
        // Expanded first: a refused block of a loop is named once, as the
        // expression wrote it; what cannot be expanded is the one item.
        let looped = "#1 = 0\no1 while [#1 LT 3]\nG01 X[#1] Q[#1]\n#1 = [#1 + 1]\no1 endwhile\n";
        let items = check(looped);
        assert_eq!(items.len(), 3, "{items:?}");
        assert_eq!(
            (items[0].line, items[0].column, items[0].what.as_str()),
            (3, 8, "unknown address Q (in `G01 X0 Q0`)")
        );
        let items = check("o2 call\nG01 X1\n");
        assert_eq!(items.len(), 1);
        assert_eq!((items[0].line, items[0].column), (1, 1));
        assert!(items[0].what.contains("not defined"), "{items:?}");
        // A long comment, odd characters in it, a * in it: read as
        // nothing, by run and check alike; words longer than the device
        // takes are refused.
        let max = core_nostd::protocol::framing::MAX_LINE;
        let long = format!("G00 X1 ({}) (\u{e9}\u{12}*****)", "A".repeat(max));
        assert!(check(&long).is_empty(), "{:?}", check(&long));
        let words = format!("G00 X1{}", " N1".repeat(max / 3));
        assert_eq!(check(&words)[0].what, format!("longer than {max} bytes"));
        assert_eq!(
            check("G00 X1 \u{e9}")[0].what,
            "control or non-ASCII byte in request"
        );
    }

    #[test]
    fn the_example_programs_are_read_whole_in_the_dialect_they_speak() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
        let mut seen = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "nc") {
                let text = std::fs::read_to_string(&path).unwrap();
                let (dialect, _) = crate::dialect::choose("auto", &text).unwrap();
                assert_eq!(check_in(&text, dialect), [], "{}", path.display());
                let iso_named = path
                    .file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with("iso-"));
                if iso_named {
                    // An ISO program (LinuxCNC, grbl senders): read as Fanuc,
                    // its G94 is Fanuc's facing cycle, its G7 unknown.
                    assert_eq!(dialect, Dialect::Iso, "{}", path.display());
                    assert!(!check_in(&text, Dialect::Fanuc).is_empty());
                    seen += 1;
                    continue;
                }
                assert_eq!(dialect, Dialect::Fanuc, "{}", path.display());
                // Read as ISO, the Fanuc words are named (or the Fanuc
                // macro words, which LinuxCNC does not have).
                let iso = check_in(&text, Dialect::Iso);
                assert!(!iso.is_empty(), "{}", path.display());
                if text.contains("G99") {
                    assert!(
                        iso.iter()
                            .any(|i| i.what
                                == "G99 belongs to the FANUC dialect (OPT DIALECT=FANUC)"),
                        "{iso:?}"
                    );
                }
                seen += 1;
            }
        }
        assert!(seen >= 4);
    }

    #[test]
    fn inch_lines_are_read_in_inches() {
        // 3937.008 in is beyond the machine; in millimetres it is not.
        assert_eq!(check("G20\nX3937.008\nG21 X3937.008\n").len(), 1);
        assert_eq!(check("G20\nX3937.008\n")[0].line, 2);
    }
}

//! `host-sim check`: every line of a G-code file the device would refuse as
//! written, with its line and column, before the program is sent.
//!
//! Each line is read by the device's own reader (`core_nostd::gcode`), so
//! what is listed here is exactly what the device refuses at the word
//! level: unknown addresses, malformed numbers, unsupported G codes, lines
//! longer than the protocol's limit. A line's first item is listed (the
//! reader stops there); geometry (an arc whose radii differ, a move beyond
//! the machine) is the device's to judge when it runs.

use core_nostd::gcode::{is_block, parse, Dialect, Units};
use core_nostd::protocol::framing::MAX_LINE;

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

/// The items of a program's text in `dialect`, in order; each line read in
/// the unit (`G20`/`G21`) the lines before it left.
///
/// A program with macros, subprograms or expressions is expanded first, as
/// the host does before streaming: what cannot be expanded is the one item
/// then; otherwise the expanded blocks are checked, each at its source
/// line (a block an expression wrote is named as written, its column that
/// of the written block), every item once.
pub fn check_in(text: &str, dialect: Dialect) -> Vec<Item> {
    let source: Vec<&str> = text.split('\n').collect();
    let lines: Vec<(usize, String)> = if crate::expand::needs_expansion(text) {
        match crate::expand::expand(text, dialect) {
            Ok(lines) => lines.into_iter().map(|l| (l.source - 1, l.text)).collect(),
            Err(e) => {
                return vec![Item {
                    line: e.line,
                    column: e.column,
                    what: e.what,
                }]
            }
        }
    } else {
        source.iter().map(|l| l.to_string()).enumerate().collect()
    };
    let mut items: Vec<Item> = Vec::new();
    let mut units = Units::Mm;
    for (i, raw) in &lines {
        let i = *i;
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        let written = source.get(i).map(|l| l.strip_suffix('\r').unwrap_or(l));
        let expanded = written != Some(line);
        let mut item = |column, what: String| {
            let what = if expanded {
                format!("{what} (in `{line}`)")
            } else {
                what
            };
            let item = Item {
                line: i + 1,
                column,
                what,
            };
            if !items.contains(&item) {
                items.push(item);
            }
        };
        if line.trim().is_empty() {
            continue;
        }
        if line.len() > MAX_LINE {
            item(MAX_LINE + 1, format!("line longer than {MAX_LINE} bytes"));
            continue;
        }
        if let Some(at) = line.find(|c: char| !(c == '\t' || (' '..='~').contains(&c))) {
            item(at + 1, "not printable ASCII".to_string());
            continue;
        }
        if !is_block(line) {
            let at = line.len() - line.trim_start().len();
            item(at + 1, "not a G-code line".to_string());
            continue;
        }
        match parse(line, dialect, units) {
            Ok(b) => units = b.units.unwrap_or(units),
            Err(e) => item(e.column, e.error.to_string()),
        }
    }
    items
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!(check("G01 X1\nG02 X2 Z2 R1\n").is_empty());
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
        let long = format!("G01 X1 ({})", "A".repeat(MAX_LINE));
        assert_eq!(
            check(&long)[0].what,
            format!("line longer than {MAX_LINE} bytes")
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

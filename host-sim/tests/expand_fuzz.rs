//! The expansion of macros and subprograms on arbitrary programs made of
//! the words, operators and control lines it reads: it answers with blocks
//! or an error that names a line of the program, and never panics or runs
//! away.

use core_nostd::gcode::Dialect;
use host_sim::expand::expand;
use proptest::prelude::*;

const PIECES: &[&str] = &[
    "#1",
    "#2",
    "#100",
    "#<d>",
    "#<_g>",
    "#[#1]",
    "=",
    "[",
    "]",
    "+",
    "-",
    "*",
    "/",
    "**",
    " MOD ",
    " EQ ",
    " LT ",
    " AND ",
    "SIN[",
    "ATAN[1]/[",
    "SQRT[",
    "FIX[",
    "1",
    "2.5",
    "0",
    "-3",
    "G01 ",
    "X",
    "Z",
    "F",
    "N10 ",
    "GOTO 10",
    "IF ",
    "WHILE ",
    " DO1",
    "END1",
    "o1 ",
    "o<s> ",
    "sub",
    "endsub",
    "call ",
    "if ",
    "endif",
    "while ",
    "endwhile",
    "do",
    "repeat ",
    "endrepeat",
    "break",
    "continue",
    "return",
    "M98 P2000",
    " L2",
    "M99",
    "G65 P2000 A1",
    "O2000",
    "M30",
    "(c)",
    "; c",
    " ",
    "%",
];

fn program() -> impl Strategy<Value = String> {
    let line = prop::collection::vec(prop::sample::select(PIECES), 0..8).prop_map(|p| p.concat());
    prop::collection::vec(line, 0..12).prop_map(|l| l.join("\n"))
}

/// A block without its comments.
fn words(text: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in text.chars() {
        match c {
            ';' if depth == 0 => break,
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn any_program_expands_or_names_a_line_of_it(text in program(), fanuc: bool) {
        let dialect = if fanuc { Dialect::Fanuc } else { Dialect::Iso };
        let lines = text.lines().count().max(1);
        match expand(&text, dialect) {
            Ok(blocks) => {
                for b in &blocks {
                    prop_assert!(b.source >= 1 && b.source <= lines, "{b:?}");
                    // Tape marks and program numbers pass through as
                    // written (the device names what follows them).
                    let passed = b.text.trim_start().starts_with(['%', 'O', 'o', ':']);
                    prop_assert!(passed || !words(&b.text).contains('#'), "{b:?}");
                }
            }
            Err(e) => {
                prop_assert!(e.line >= 1 && e.line <= lines + 1, "{e}");
                prop_assert!(e.column >= 1, "{e}");
                prop_assert!(!e.what.is_empty());
            }
        }
    }
}

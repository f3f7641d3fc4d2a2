//! Host-side expansion of what the device does not read: parameters,
//! expressions, LinuxCNC o-word subroutines and control flow, Fanuc
//! subprograms (`M98`/`M99`) and custom macro B (`G65`, `IF`, `GOTO`,
//! `WHILE`/`DO`/`END`), turned into the plain blocks the device streams.
//!
//! The program is read whole first (subroutines and subprograms may be
//! defined after the code that calls them), then run as a controller would,
//! line by line, with `f64` arithmetic. What comes out:
//!
//! - a line that needs no expansion passes through byte for byte, comments
//!   included (`%`, the main program's `O1000`); blank lines are dropped;
//! - a line with `#` parameters or `[…]` expressions in its words is rebuilt
//!   from its words, separated by single spaces, its comments after them.
//!   A value from an expression, and any literal value other than a `G`,
//!   `M`, `N`, `T` or `O` code (kept as written), is written with at most 10
//!   decimals, trailing zeros trimmed, `-0` as `0` (`X12.5`, `Z-3`, `F0.2`);
//! - assignments and control-flow lines produce nothing; subroutine and
//!   subprogram bodies appear at their calls, with the source line of each
//!   block in the file;
//! - `M2` (`M02`) or `M30` ends the expansion after its block, followed by
//!   the tape's closing `%` if the file has one.
//!
//! Expressions (both dialects): numbers, `#n`, `#[expr]`, `##n`, unary `-`
//! and `+`, and binary operators by LinuxCNC's precedence, left to right
//! within a level: `**`; `*` `/` `MOD`; `+` `-`; `EQ NE GT GE LT LE`;
//! `AND OR XOR`. Comparisons give 1 or 0. Functions `SIN COS TAN ASIN ACOS`
//! (degrees), `ATAN[y]/[x]` (and `ATAN[y,x]`), `SQRT ABS ROUND FIX FUP EXP
//! LN`, `POW[a,b]`.
//!
//! The dialects differ where their controls do:
//!
//! | | LinuxCNC ([`Dialect::Iso`]) | Fanuc ([`Dialect::Fanuc`]) |
//! |---|---|---|
//! | unset parameter | reads as 0 | vacant: 0 in arithmetic; a word whose value is vacant is left out; `EQ`/`NE` tell vacant from 0 |
//! | named parameters | `#<name>` (case-insensitive), `#<_name>` global, others local to their call; reading an unset one is an error; `EXISTS[#<name>]`; `#<_current_tool>` (`#5400`) and `#<_selected_tool>` read-only, following the blocks' `T` and `M6` from 0 and −1 (no tool at the program's start) | none |
//! | locals | `#1`–`#30` saved around `oN call`, set from its arguments (the rest 0) | `#1`–`#33` fresh (vacant) for each `G65`, which maps A→#1 … Z→#26; `M98` shares its caller's |
//! | assignments | several on a line, with words; all take effect after the line is read | one per line, alone (`IF […] THEN #i = …` too) |
//! | `EQ`, `NE` | within 0.0001 | within 10⁻⁹ of the larger magnitude |
//! | `FIX`, `FUP` | floor, ceiling | toward zero, away from zero |
//! | `ATAN`, `ASIN` | −180° … 180°, −90° … 90° | 0° … 360°, 270° … 90° (the NAT bit 0 ranges) |
//! | `AND OR XOR` | logical | bitwise on whole numbers |
//! | `MOD` | not negative | the sign of the dividend |
//! | control flow | o-words: `sub`/`endsub`/`call`/`return`, `if`/`elseif`/`else`/`endif`, `while`/`endwhile`, `do`/`while`, `repeat`/`endrepeat`, `break`, `continue` | programs `O####` (`:####`), `M98 P… L…` (a `P` of 5 to 8 digits: the repeat count, then the program's 4, `P32000` three times O2000), `M99`, `G65 P… L…`, `IF […] GOTO n`, `GOTO n`, `WHILE […] DOm` … `ENDm`, `DOm` … `ENDm` |
//!
//! Refused, with line and column: anything the text does not define
//! (a subroutine or program not in the file, a `GOTO` without its `N`),
//! unmatched or crossed blocks, `M99 P`, `M99` in the main program, `M98`
//! with other words than `N P L`, `G65` argument specification II, `G66`/`G67`,
//! Fanuc alarm `#3000`, arithmetic without a finite result (division by
//! zero, `SQRT` of a negative, …), calls nested deeper than 16 and
//! expansions of more than 1 000 000 blocks (or ten times as many lines
//! run), which is how a loop that does not end is stopped.

use core_nostd::gcode::Dialect;
use std::collections::HashMap;
use std::fmt;

/// Most blocks an expansion may produce.
const MAX_BLOCKS: usize = 1_000_000;
/// Lines run per allowed block: a loop that emits nothing stops there.
const RUNS_PER_BLOCK: usize = 10;
/// Deepest nesting of calls (subroutines, subprograms, macros).
const MAX_DEPTH: usize = 16;
/// Parameters `#0` … `#5999`.
const PARAMS: usize = 6000;
/// LinuxCNC subroutine arguments and locals `#1` … `#30`.
const ISO_LOCALS: usize = 30;
/// Fanuc macro locals `#1` … `#33`.
const FANUC_LOCALS: usize = 33;
/// Most values and operators in one line's expressions (bounds recursion).
const MAX_TERMS: usize = 1000;
/// Deepest nesting of values in one another (`[`, functions, signs).
const MAX_NESTING: usize = 100;
/// LinuxCNC's tolerance of `EQ` and `NE`.
const ISO_EQUAL: f64 = 1e-4;
/// Fanuc `EQ` and `NE`, relative to the larger magnitude (at least 1).
const FANUC_EQUAL: f64 = 1e-9;
/// How close to a whole number a parameter number, count or target must be.
const WHOLE: f64 = 1e-6;
/// No link.
const NONE: usize = usize::MAX;

/// Letter runs that make a line the host's to expand.
const KEYWORDS: [&str; 18] = [
    "IF",
    "THEN",
    "GOTO",
    "WHILE",
    "DO",
    "END",
    "SUB",
    "ENDSUB",
    "CALL",
    "RETURN",
    "ELSEIF",
    "ELSE",
    "ENDIF",
    "ENDWHILE",
    "REPEAT",
    "ENDREPEAT",
    "BREAK",
    "CONTINUE",
];

/// One plain block of the expanded program and the source line (from 1) it
/// comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Line {
    /// The line of the source text (from 1) this block was read or
    /// computed from: for a subroutine's block, its line in the subroutine.
    pub source: usize,
    /// The block as the device reads it.
    pub text: String,
}

/// Why a program cannot be expanded: where (line and column from 1, bytes)
/// and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExpandError {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1 (bytes).
    pub column: usize,
    /// What is wrong.
    pub what: String,
}

impl ExpandError {
    fn new(line: usize, column: usize, what: impl Into<String>) -> Self {
        ExpandError {
            line,
            column,
            what: what.into(),
        }
    }
}

impl fmt::Display for ExpandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.what)
    }
}

impl std::error::Error for ExpandError {}

/// Whether a program uses anything the host must expand (a `#` parameter, a
/// `[` expression, an o-word (`o100 ...`, `O<name> call`), M98/M99, G65, or
/// Fanuc IF/WHILE/GOTO/DO/END), outside comments.
///
/// ```
/// use host_sim::expand::needs_expansion;
/// assert!(!needs_expansion("%\nO1000 (PART)\nG00 X30. Z2. (#1 here is a comment)\nM30\n%\n"));
/// assert!(needs_expansion("G01 X#1 Z-2."));
/// assert!(needs_expansion("M98 P2000 L2"));
/// ```
pub fn needs_expansion(text: &str) -> bool {
    text.lines().any(line_needs)
}

/// Expands a whole program into plain blocks.
///
/// ```
/// use core_nostd::gcode::Dialect;
/// use host_sim::expand::expand;
/// let lines = expand("#1 = 10\nG01 X[#1 * 2] Z-#1 F.2\nM30\n", Dialect::Fanuc).unwrap();
/// assert_eq!(lines[0].text, "G01 X20 Z-10 F0.2");
/// assert_eq!((lines[1].source, lines[1].text.as_str()), (3, "M30"));
/// ```
pub fn expand(text: &str, dialect: Dialect) -> Result<Vec<Line>, ExpandError> {
    expand_with_cap(text, dialect, MAX_BLOCKS)
}

/// [`expand`] with at most `cap` blocks out (and `cap` × 10 lines run).
fn expand_with_cap(text: &str, dialect: Dialect, cap: usize) -> Result<Vec<Line>, ExpandError> {
    let mut src = read(text, dialect)?;
    let plan = match dialect {
        Dialect::Iso => plan_iso(&mut src)?,
        Dialect::Fanuc => plan_fanuc(&src)?,
    };
    Run::new(&src, &plan, dialect, cap).run()
}

/// A number as the expanded program writes it: at most 10 decimals,
/// trailing zeros trimmed, a point only before decimals, no `-0`.
fn format_number(v: f64) -> String {
    let s = format!("{v:.10}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s.as_str()
    };
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// `v` as a whole number, if it is one (within [`WHOLE`]).
fn whole(v: f64) -> Option<i64> {
    let r = v.round();
    (v.is_finite() && (v - r).abs() <= WHOLE && r.abs() < 1e15).then_some(r as i64)
}

// ---------------------------------------------------------------------------
// Lenient scanning of a line's code (comments blanked), which never fails.

/// The line's bytes with comments blanked to spaces and everything from `;`
/// dropped (an unclosed `(` blanks the rest).
fn strip(line: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(line.len());
    let mut comment = false;
    for &b in line.as_bytes() {
        if comment {
            out.push(b' ');
            comment = b != b')';
            continue;
        }
        match b {
            b'(' => {
                comment = true;
                out.push(b' ');
            }
            b';' => break,
            _ => out.push(b),
        }
    }
    out
}

/// The number after a word's letter at `from` (spaces allowed before it).
fn word_number(b: &[u8], from: usize) -> Option<f64> {
    let rest = b.get(from..)?;
    let start = rest
        .iter()
        .take_while(|x| matches!(x, b' ' | b'\t'))
        .count();
    let digits = rest.get(start..)?;
    let n = digits
        .iter()
        .take_while(|x| x.is_ascii_digit() || **x == b'.')
        .count();
    std::str::from_utf8(digits.get(..n)?).ok()?.parse().ok()
}

/// Calls `f` with each letter run of the line's code (`<…>` names skipped)
/// and the number after a single letter; stops when `f` says so.
fn scan_words(line: &str, mut f: impl FnMut(&[u8], Option<f64>) -> bool) -> bool {
    let b = strip(line);
    let mut i = 0;
    while let Some(&c) = b.get(i) {
        if c == b'<' {
            i = b[i..]
                .iter()
                .position(|&x| x == b'>')
                .map_or(b.len(), |p| i + p + 1);
            continue;
        }
        if c.is_ascii_alphabetic() {
            let n = b[i..]
                .iter()
                .take_while(|x| x.is_ascii_alphabetic())
                .count();
            let run = &b[i..i + n];
            let value = if n == 1 { word_number(&b, i + 1) } else { None };
            if f(run, value) {
                return true;
            }
            i += n;
            continue;
        }
        i += 1;
    }
    false
}

/// Whether one line needs the host (see [`needs_expansion`]).
fn line_needs(line: &str) -> bool {
    if strip(line).iter().any(|&b| b == b'#' || b == b'[') {
        return true;
    }
    scan_words(line, |run, value| {
        if run.len() >= 2 {
            return KEYWORDS
                .iter()
                .any(|k| k.as_bytes().eq_ignore_ascii_case(run));
        }
        match (run.first().map(u8::to_ascii_uppercase), value) {
            (Some(b'M'), Some(v)) => v == 98.0 || v == 99.0,
            (Some(b'G'), Some(v)) => [65.0, 66.0, 66.1, 67.0].contains(&v),
            _ => false,
        }
    })
}

/// Whether a plain line ends the program (`M2`, `M02`, `M30`).
fn plain_end(line: &str) -> bool {
    scan_words(line, |run, value| {
        run.eq_ignore_ascii_case(b"M") && matches!(value, Some(v) if v == 2.0 || v == 30.0)
    })
}

/// A program number alone on its line (`O1000`, `:1000`, `O<name>`,
/// comments allowed): `Some(Some(number))`, `Some(None)` for a name.
fn program_number(line: &str) -> Option<Option<u64>> {
    let code = strip(line);
    let start = code
        .iter()
        .take_while(|x| matches!(x, b' ' | b'\t'))
        .count();
    let b = code.get(start..)?;
    let (number, rest) = match b {
        [b'O' | b'o', b'<', ..] => {
            let close = b.iter().position(|&x| x == b'>')?;
            (None, b.get(close + 1..)?)
        }
        [b'O' | b'o' | b':', d, ..] if d.is_ascii_digit() => {
            let n = b[1..].iter().take_while(|x| x.is_ascii_digit()).count();
            let number = std::str::from_utf8(&b[1..1 + n]).ok()?.parse().ok();
            (number, &b[1 + n..])
        }
        _ => return None,
    };
    rest.iter()
        .all(|x| matches!(x, b' ' | b'\t'))
        .then_some(number)
}

/// The sequence number a Fanuc line begins with (`N20 …`, `/N20 …`).
fn seq_number(line: &str) -> Option<u64> {
    let code = strip(line);
    let mut b = code.as_slice();
    let trim = |b: &[u8]| b.iter().take_while(|x| matches!(x, b' ' | b'\t')).count();
    b = &b[trim(b)..];
    if let [b'/', rest @ ..] = b {
        b = &rest[trim(rest)..];
    }
    match b {
        [b'N' | b'n', rest @ ..] => {
            let n = rest.iter().take_while(|x| x.is_ascii_digit()).count();
            std::str::from_utf8(&rest[..n]).ok()?.parse().ok()
        }
        _ => None,
    }
}

// ---------------------------------------------------------------------------
// Expressions.

/// A binary operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    Pow,
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

impl Op {
    /// Binding strength: `**` strongest, `AND OR XOR` weakest.
    const fn prec(self) -> u8 {
        match self {
            Op::Pow => 5,
            Op::Mul | Op::Div | Op::Mod => 4,
            Op::Add | Op::Sub => 3,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 2,
            Op::And | Op::Or | Op::Xor => 1,
        }
    }

    const fn name(self) -> &'static str {
        match self {
            Op::Pow => "**",
            Op::Mul => "*",
            Op::Div => "/",
            Op::Mod => "MOD",
            Op::Add => "+",
            Op::Sub => "-",
            Op::Eq => "EQ",
            Op::Ne => "NE",
            Op::Gt => "GT",
            Op::Ge => "GE",
            Op::Lt => "LT",
            Op::Le => "LE",
            Op::And => "AND",
            Op::Or => "OR",
            Op::Xor => "XOR",
        }
    }

    fn from_word(word: &str) -> Option<Op> {
        Some(match word.to_ascii_uppercase().as_str() {
            "MOD" => Op::Mod,
            "EQ" => Op::Eq,
            "NE" => Op::Ne,
            "GT" => Op::Gt,
            "GE" => Op::Ge,
            "LT" => Op::Lt,
            "LE" => Op::Le,
            "AND" => Op::And,
            "OR" => Op::Or,
            "XOR" => Op::Xor,
            _ => return None,
        })
    }
}

/// A function of one argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Func {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sqrt,
    Abs,
    Round,
    Fix,
    Fup,
    Exp,
    Ln,
}

impl Func {
    fn from_word(word: &str) -> Option<Func> {
        Some(match word.to_ascii_uppercase().as_str() {
            "SIN" => Func::Sin,
            "COS" => Func::Cos,
            "TAN" => Func::Tan,
            "ASIN" => Func::Asin,
            "ACOS" => Func::Acos,
            "ATAN" => Func::Atan,
            "SQRT" => Func::Sqrt,
            "ABS" => Func::Abs,
            "ROUND" => Func::Round,
            "FIX" => Func::Fix,
            "FUP" => Func::Fup,
            "EXP" => Func::Exp,
            "LN" => Func::Ln,
            _ => return None,
        })
    }

    /// Whether `word` names something written `NAME[…]`.
    fn known(word: &str) -> bool {
        Func::from_word(word).is_some()
            || word.eq_ignore_ascii_case("EXISTS")
            || word.eq_ignore_ascii_case("POW")
    }
}

/// A parameter: numbered (the number an expression) or named (lower case,
/// without spaces).
#[derive(Clone, Debug, PartialEq)]
enum Target {
    Num(Expr),
    Named(String),
}

/// An expression; columns are byte offsets in the line.
#[derive(Clone, Debug, PartialEq)]
enum Expr {
    Num(f64),
    /// A parameter read, at the `#`.
    Var(Box<Target>, usize),
    Neg(Box<Expr>),
    /// `[…]`: kept so that a vacant value stays vacant through it.
    Group(Box<Expr>),
    /// An operator and where its expression starts.
    Bin(Op, Box<Expr>, Box<Expr>, usize),
    /// A function and where its name starts.
    Call(Func, Box<Expr>, usize),
    Atan2(Box<Expr>, Box<Expr>, usize),
    Exists(String),
}

/// A value, and in Fanuc programs whether it is vacant (`#0`, an unset
/// variable).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Val {
    v: f64,
    vacant: bool,
}

const fn num(v: f64) -> Val {
    Val { v, vacant: false }
}

// ---------------------------------------------------------------------------
// Statements.

/// A word of a block: its letter (upper case), column and value.
#[derive(Clone, Debug, PartialEq)]
struct Word {
    letter: u8,
    at: usize,
    value: Value,
}

#[derive(Clone, Debug, PartialEq)]
enum Value {
    /// As written (sign and number) and its value.
    Literal(String, f64),
    Expr(Expr),
}

/// `#… = …`, at the `#`.
#[derive(Clone, Debug, PartialEq)]
struct Assign {
    target: Target,
    value: Expr,
    at: usize,
}

/// A line of words (some computed), and in LinuxCNC programs assignments.
#[derive(Clone, Debug, PartialEq)]
struct Block {
    deleted: bool,
    words: Vec<Word>,
    assigns: Vec<Assign>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OKind {
    Sub,
    EndSub,
    Call,
    Return,
    If,
    ElseIf,
    Else,
    EndIf,
    While,
    EndWhile,
    Do,
    /// The `while` that closes a `do` (found when the file is planned).
    DoWhile,
    Repeat,
    EndRepeat,
    Break,
    Continue,
}

impl OKind {
    fn from_word(word: &str) -> Option<OKind> {
        Some(match word.to_ascii_lowercase().as_str() {
            "sub" => OKind::Sub,
            "endsub" => OKind::EndSub,
            "call" => OKind::Call,
            "return" => OKind::Return,
            "if" => OKind::If,
            "elseif" => OKind::ElseIf,
            "else" => OKind::Else,
            "endif" => OKind::EndIf,
            "while" => OKind::While,
            "endwhile" => OKind::EndWhile,
            "do" => OKind::Do,
            "repeat" => OKind::Repeat,
            "endrepeat" => OKind::EndRepeat,
            "break" => OKind::Break,
            "continue" => OKind::Continue,
            _ => return None,
        })
    }

    const fn word(self) -> &'static str {
        match self {
            OKind::Sub => "sub",
            OKind::EndSub => "endsub",
            OKind::Call => "call",
            OKind::Return => "return",
            OKind::If => "if",
            OKind::ElseIf => "elseif",
            OKind::Else => "else",
            OKind::EndIf => "endif",
            OKind::While | OKind::DoWhile => "while",
            OKind::EndWhile => "endwhile",
            OKind::Do => "do",
            OKind::Repeat => "repeat",
            OKind::EndRepeat => "endrepeat",
            OKind::Break => "break",
            OKind::Continue => "continue",
        }
    }
}

/// A LinuxCNC o-word line: `o100 if [#1 GT 0]`, `o<cut> call [2] [3]`.
#[derive(Clone, Debug, PartialEq)]
struct OWord {
    /// `o100` or `o<name>` (lower case).
    label: String,
    kind: OKind,
    args: Vec<Expr>,
    at: usize,
}

/// What `IF […]` does when its condition holds.
#[derive(Clone, Debug, PartialEq)]
enum Then {
    Goto(Expr, usize),
    Assign(Assign),
}

/// What a line is.
#[derive(Clone, Debug, PartialEq)]
enum Stmt {
    /// Passed through as written; `end` when it holds `M2` or `M30`.
    Plain {
        end: bool,
    },
    /// `%`.
    Tape,
    /// A program number alone: `O1000`, `:1000`, `O<name>` (no number).
    Number(Option<u64>),
    Block(Block),
    /// A Fanuc assignment, alone on its line.
    Assign(Assign),
    O(OWord),
    If(Expr, Then),
    Goto(Expr, usize),
    While(Expr, u8),
    Do(u8),
    End(u8),
}

/// A non-blank line of the file.
struct Src<'a> {
    /// Line number, from 1.
    no: usize,
    text: &'a str,
    stmt: Stmt,
    /// Fanuc: the `N` number the line begins with, a `GOTO` target.
    seq: Option<u64>,
    /// The comments of a parsed line, for its rebuilt text.
    comments: Vec<String>,
}

/// Reads the file's non-blank lines.
fn read(text: &str, dialect: Dialect) -> Result<Vec<Src<'_>>, ExpandError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim_end_matches('\r');
        if line.trim().is_empty() {
            continue;
        }
        let no = i + 1;
        let mut comments = Vec::new();
        let stmt = if line.trim_start_matches([' ', '\t']).starts_with('%') {
            Stmt::Tape
        } else if let Some(n) = program_number(line) {
            Stmt::Number(n)
        } else if !line_needs(line) {
            Stmt::Plain {
                end: plain_end(line),
            }
        } else {
            let mut c = Cur::new(line, no, dialect);
            let stmt = match dialect {
                Dialect::Iso => parse_iso(&mut c)?,
                Dialect::Fanuc => parse_fanuc(&mut c)?,
            };
            comments = c.comments.iter().map(|s| s.to_string()).collect();
            stmt
        };
        let seq = match dialect {
            Dialect::Fanuc => seq_number(line),
            Dialect::Iso => None,
        };
        out.push(Src {
            no,
            text: line,
            stmt,
            seq,
            comments,
        });
    }
    Ok(out)
}

// ---------------------------------------------------------------------------
// Parsing one line.

/// A cursor over one line's bytes.
struct Cur<'a> {
    s: &'a str,
    b: &'a [u8],
    pos: usize,
    no: usize,
    dialect: Dialect,
    comments: Vec<&'a str>,
    terms: usize,
    nesting: usize,
}

impl<'a> Cur<'a> {
    fn new(s: &'a str, no: usize, dialect: Dialect) -> Self {
        Cur {
            s,
            b: s.as_bytes(),
            pos: 0,
            no,
            dialect,
            comments: Vec::new(),
            terms: 0,
            nesting: 0,
        }
    }

    fn err(&self, at: usize, what: impl Into<String>) -> ExpandError {
        ExpandError::new(self.no, at + 1, what)
    }

    fn slice(&self, from: usize, to: usize) -> &'a str {
        self.s.get(from..to).unwrap_or("")
    }

    fn rest(&self) -> &'a [u8] {
        self.b.get(self.pos..).unwrap_or(&[])
    }

    /// Skips spaces and comments (kept for the rebuilt line).
    fn skip(&mut self) -> Result<(), ExpandError> {
        while let Some(&c) = self.b.get(self.pos) {
            match c {
                b' ' | b'\t' | b'\r' => self.pos += 1,
                b'(' => {
                    let close = self
                        .rest()
                        .iter()
                        .position(|&b| b == b')')
                        .ok_or_else(|| self.err(self.pos, "comment not closed"))?;
                    self.comments
                        .push(self.slice(self.pos, self.pos + close + 1));
                    self.pos += close + 1;
                }
                b';' => {
                    self.comments.push(self.slice(self.pos, self.b.len()));
                    self.pos = self.b.len();
                }
                _ => break,
            }
        }
        Ok(())
    }

    fn peek(&self) -> Option<u8> {
        self.b.get(self.pos).copied()
    }

    fn peek_at(&self, k: usize) -> Option<u8> {
        self.b.get(self.pos + k).copied()
    }

    /// The run of letters at the cursor (not consumed).
    fn letters(&self) -> &'a str {
        let n = self
            .rest()
            .iter()
            .take_while(|b| b.is_ascii_alphabetic())
            .count();
        self.slice(self.pos, self.pos + n)
    }

    fn mark(&self) -> (usize, usize) {
        (self.pos, self.comments.len())
    }

    fn reset(&mut self, mark: (usize, usize)) {
        self.pos = mark.0;
        self.comments.truncate(mark.1);
    }

    fn at_end(&mut self) -> Result<bool, ExpandError> {
        self.skip()?;
        Ok(self.pos >= self.b.len())
    }

    /// What is at the cursor, for a message.
    fn show(&self) -> String {
        let run = self.letters();
        if !run.is_empty() {
            return run.to_string();
        }
        match self.s.get(self.pos..).and_then(|r| r.chars().next()) {
            Some(c) => format!("'{c}'"),
            None => "the end of the line".to_string(),
        }
    }

    /// Nothing but comments may follow.
    fn finish(&mut self) -> Result<(), ExpandError> {
        if self.at_end()? {
            Ok(())
        } else {
            Err(self.err(self.pos, format!("unexpected {}", self.show())))
        }
    }

    /// Counts a value or operator against [`MAX_TERMS`].
    fn term(&mut self) -> Result<(), ExpandError> {
        self.terms += 1;
        if self.terms > MAX_TERMS {
            return Err(self.err(
                self.pos,
                format!("more than {MAX_TERMS} values and operators on one line"),
            ));
        }
        Ok(())
    }

    /// Digits at the cursor as a whole number (consumed).
    fn digits(&mut self) -> Option<u64> {
        let n = self
            .rest()
            .iter()
            .take_while(|b| b.is_ascii_digit())
            .count();
        let v = self.slice(self.pos, self.pos + n).parse().ok()?;
        self.pos += n;
        Some(v)
    }

    /// The end of a number (digits with at most one point, at least one
    /// digit) starting at `from`.
    fn number_end(&self, from: usize) -> Option<usize> {
        let b = self.b.get(from..)?;
        let int = b.iter().take_while(|x| x.is_ascii_digit()).count();
        let mut end = int;
        let mut frac = 0;
        if b.get(int) == Some(&b'.') {
            frac = b[int + 1..]
                .iter()
                .take_while(|x| x.is_ascii_digit())
                .count();
            end = int + 1 + frac;
        }
        (int + frac > 0).then_some(from + end)
    }

    /// `]` closing the `[` at `open`.
    fn close(&mut self, open: usize) -> Result<(), ExpandError> {
        self.skip()?;
        if self.peek() == Some(b']') {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.err(
                self.pos,
                format!(
                    "expected ] to close the [ at column {}, found {}",
                    open + 1,
                    self.show()
                ),
            ))
        }
    }
}

/// An expression of operators; `open` is where it starts (for messages).
fn expr(c: &mut Cur, open: usize) -> Result<Expr, ExpandError> {
    binary(c, 1, open)
}

fn binary(c: &mut Cur, min: u8, open: usize) -> Result<Expr, ExpandError> {
    let mut lhs = operand(c)?;
    loop {
        c.skip()?;
        let Some((op, len)) = peek_op(c) else { break };
        if op.prec() < min {
            break;
        }
        c.term()?;
        c.pos += len;
        let rhs = binary(c, op.prec() + 1, open)?;
        lhs = Expr::Bin(op, Box::new(lhs), Box::new(rhs), open);
    }
    Ok(lhs)
}

fn peek_op(c: &Cur) -> Option<(Op, usize)> {
    Some(match c.peek()? {
        b'*' if c.peek_at(1) == Some(b'*') => (Op::Pow, 2),
        b'*' => (Op::Mul, 1),
        b'/' => (Op::Div, 1),
        b'+' => (Op::Add, 1),
        b'-' => (Op::Sub, 1),
        l if l.is_ascii_alphabetic() => {
            let run = c.letters();
            (Op::from_word(run)?, run.len())
        }
        _ => return None,
    })
}

/// A value: a number, a parameter, `[…]`, a function, or one of these
/// after `-` or `+`.
fn operand(c: &mut Cur) -> Result<Expr, ExpandError> {
    c.skip()?;
    c.term()?;
    c.nesting += 1;
    if c.nesting > MAX_NESTING {
        return Err(c.err(c.pos, format!("values nested more than {MAX_NESTING} deep")));
    }
    let value = nested(c);
    c.nesting -= 1;
    value
}

fn nested(c: &mut Cur) -> Result<Expr, ExpandError> {
    let at = c.pos;
    match c.peek() {
        Some(b'[') => {
            c.pos += 1;
            let e = expr(c, at)?;
            c.close(at)?;
            Ok(Expr::Group(Box::new(e)))
        }
        Some(b'#') => param(c).map(|t| Expr::Var(Box::new(t), at)),
        Some(b'-') => {
            c.pos += 1;
            Ok(Expr::Neg(Box::new(operand(c)?)))
        }
        Some(b'+') => {
            c.pos += 1;
            operand(c)
        }
        Some(d) if d.is_ascii_digit() || d == b'.' => {
            let end = c
                .number_end(at)
                .ok_or_else(|| c.err(at, "'.' is not a number"))?;
            let v = c
                .slice(at, end)
                .parse()
                .map_err(|_| c.err(at, "not a number"))?;
            c.pos = end;
            Ok(Expr::Num(v))
        }
        Some(l) if l.is_ascii_alphabetic() => function(c),
        Some(_) => Err(c.err(at, format!("unexpected {}", c.show()))),
        None => Err(c.err(at, "a value is missing")),
    }
}

/// A parameter after `#`: `#12`, `#<name>`, `#[expr]`, `##1`.
fn param(c: &mut Cur) -> Result<Target, ExpandError> {
    let at = c.pos;
    c.pos += 1;
    c.skip()?;
    match c.peek() {
        Some(b'<') => {
            if c.dialect == Dialect::Fanuc {
                return Err(c.err(at, "named parameters #<…> are LinuxCNC's"));
            }
            name(c).map(Target::Named)
        }
        Some(b'[' | b'#') => operand(c).map(Target::Num),
        Some(d) if d.is_ascii_digit() => {
            let n = c
                .digits()
                .ok_or_else(|| c.err(at, "parameter number too large"))?;
            Ok(Target::Num(Expr::Num(n as f64)))
        }
        _ => Err(c.err(at, "# must be followed by a number, <name> or [expression]")),
    }
}

/// `<name>` at the cursor: lower case, spaces removed.
fn name(c: &mut Cur) -> Result<String, ExpandError> {
    let open = c.pos;
    let close = c
        .rest()
        .iter()
        .position(|&b| b == b'>')
        .ok_or_else(|| c.err(open, "< without >"))?;
    let name: String = c
        .slice(open + 1, open + close)
        .chars()
        .filter(|ch| !ch.is_whitespace())
        .collect::<String>()
        .to_ascii_lowercase();
    if name.is_empty() {
        return Err(c.err(open, "an empty name <>"));
    }
    c.pos = open + close + 1;
    Ok(name)
}

/// `NAME[…]` at the cursor.
fn function(c: &mut Cur) -> Result<Expr, ExpandError> {
    let at = c.pos;
    let word = c.letters().to_ascii_uppercase();
    c.pos += word.len();
    c.skip()?;
    if c.peek() != Some(b'[') {
        let what = if Func::known(&word) {
            format!("{word} needs its argument in [ ]")
        } else {
            format!("{word} is not a value")
        };
        return Err(c.err(at, what));
    }
    let open = c.pos;
    c.pos += 1;
    match word.as_str() {
        "EXISTS" => {
            if c.dialect == Dialect::Fanuc {
                return Err(c.err(at, "EXISTS is LinuxCNC's"));
            }
            c.skip()?;
            if c.peek() != Some(b'#') {
                return Err(c.err(c.pos, "EXISTS takes a named parameter: EXISTS[#<name>]"));
            }
            c.pos += 1;
            c.skip()?;
            if c.peek() != Some(b'<') {
                return Err(c.err(c.pos, "EXISTS takes a named parameter: EXISTS[#<name>]"));
            }
            let n = name(c)?;
            c.close(open)?;
            Ok(Expr::Exists(n))
        }
        "POW" => {
            let a = expr(c, open)?;
            c.skip()?;
            if c.peek() != Some(b',') {
                return Err(c.err(c.pos, "POW takes two arguments: POW[a,b]"));
            }
            c.pos += 1;
            let b = expr(c, open)?;
            c.close(open)?;
            Ok(Expr::Bin(Op::Pow, Box::new(a), Box::new(b), at))
        }
        "ATAN" => {
            let y = expr(c, open)?;
            c.skip()?;
            if c.peek() == Some(b',') {
                c.pos += 1;
                let x = expr(c, open)?;
                c.close(open)?;
                return Ok(Expr::Atan2(Box::new(y), Box::new(x), at));
            }
            c.close(open)?;
            // ATAN[y]/[x]: a `/` followed by `[`.
            let spaces = |b: &[u8]| b.iter().take_while(|x| matches!(x, b' ' | b'\t')).count();
            let slash = c.pos + spaces(c.rest());
            if c.b.get(slash) == Some(&b'/') {
                let bracket = slash + 1 + spaces(c.b.get(slash + 1..).unwrap_or(&[]));
                if c.b.get(bracket) == Some(&b'[') {
                    c.pos = bracket + 1;
                    let x = expr(c, bracket)?;
                    c.close(bracket)?;
                    return Ok(Expr::Atan2(Box::new(y), Box::new(x), at));
                }
            }
            if c.dialect == Dialect::Iso {
                return Err(c.err(at, "ATAN takes two arguments: ATAN[y]/[x]"));
            }
            Ok(Expr::Call(Func::Atan, Box::new(y), at))
        }
        _ => {
            let f = Func::from_word(&word)
                .ok_or_else(|| c.err(at, format!("unknown function {word}")))?;
            let e = expr(c, open)?;
            c.close(open)?;
            Ok(Expr::Call(f, Box::new(e), at))
        }
    }
}

/// A word's value: a literal number (sign allowed) or an operand.
fn value(c: &mut Cur) -> Result<Value, ExpandError> {
    c.skip()?;
    let start = c.pos;
    let digits = match c.peek() {
        Some(b'+' | b'-') => start + 1,
        _ => start,
    };
    if let Some(end) = c.number_end(digits) {
        let text = c.slice(start, end);
        let v = text.parse().map_err(|_| c.err(start, "not a number"))?;
        c.term()?;
        c.pos = end;
        return Ok(Value::Literal(text.to_string(), v));
    }
    operand(c).map(Value::Expr)
}

/// A word at the cursor (a letter).
fn word(c: &mut Cur) -> Result<Word, ExpandError> {
    let at = c.pos;
    let run = c.letters();
    if run.len() > 1 && !Func::known(run.get(1..).unwrap_or("")) {
        return Err(c.err(at, format!("unexpected {}", run.to_ascii_uppercase())));
    }
    let letter = c.peek().unwrap_or(b' ').to_ascii_uppercase();
    c.pos += 1;
    let value = value(c)?;
    Ok(Word { letter, at, value })
}

/// `#… = …` at the cursor.
fn assignment(c: &mut Cur) -> Result<Assign, ExpandError> {
    let at = c.pos;
    let target = param(c)?;
    c.skip()?;
    if c.peek() != Some(b'=') {
        return Err(c.err(
            c.pos,
            "expected = after the parameter (a parameter is set with #… = value)",
        ));
    }
    c.pos += 1;
    c.skip()?;
    let open = c.pos;
    let value = expr(c, open)?;
    Ok(Assign { target, value, at })
}

/// Words and assignments to the end of the line.
fn block(c: &mut Cur, deleted: bool) -> Result<Block, ExpandError> {
    let mut b = Block {
        deleted,
        words: Vec::new(),
        assigns: Vec::new(),
    };
    while !c.at_end()? {
        match c.peek() {
            Some(b'#') if c.dialect == Dialect::Iso => b.assigns.push(assignment(c)?),
            Some(b'#') => {
                return Err(c.err(
                    c.pos,
                    "an assignment stands alone on its line in Fanuc programs",
                ))
            }
            Some(l) if l.is_ascii_alphabetic() => b.words.push(word(c)?),
            Some(b'[') if b.words.is_empty() && b.assigns.is_empty() => {
                return Err(c.err(
                    c.pos,
                    "unexpected '[': an expression follows an address letter (X[1+2]); a line that opens with '[' (a simulator's [BILLET) is not G-code",
                ))
            }
            _ => return Err(c.err(c.pos, format!("unexpected {}", c.show()))),
        }
    }
    if deleted && !b.assigns.is_empty() {
        return Err(c.err(
            0,
            "a block-deleted line (/) cannot set parameters: that depends on the switch at the machine",
        ));
    }
    Ok(b)
}

/// A LinuxCNC line.
fn parse_iso(c: &mut Cur) -> Result<Stmt, ExpandError> {
    c.skip()?;
    let deleted = c.peek() == Some(b'/');
    if deleted {
        c.pos += 1;
        c.skip()?;
    }
    let o = matches!(c.peek(), Some(b'o' | b'O'))
        && matches!(c.peek_at(1), Some(b'<' | b'[' | b'0'..=b'9'));
    if !o {
        return block(c, deleted).map(Stmt::Block);
    }
    let at = c.pos;
    if deleted {
        return Err(c.err(0, "an o-word line cannot be block-deleted (/)"));
    }
    c.pos += 1;
    let label = match c.peek() {
        Some(b'<') => format!("o<{}>", name(c)?),
        Some(b'[') => return Err(c.err(at, "indirect o-words o[…] are not supported")),
        _ => format!(
            "o{}",
            c.digits()
                .ok_or_else(|| c.err(at, "o-word number too large"))?
        ),
    };
    c.skip()?;
    let word = c.letters();
    let kind = OKind::from_word(word).ok_or_else(|| {
        c.err(
            c.pos,
            format!(
                "{label} needs a keyword (sub, endsub, call, return, if, elseif, else, endif, while, endwhile, do, repeat, endrepeat, break, continue), found {}",
                c.show()
            ),
        )
    })?;
    c.pos += word.len();
    let mut args = Vec::new();
    match kind {
        OKind::Call => {
            while !c.at_end()? {
                args.push(operand(c)?);
            }
        }
        OKind::If | OKind::ElseIf | OKind::While | OKind::Repeat => {
            if c.at_end()? {
                return Err(c.err(c.pos, format!("{label} {} needs a [value]", kind.word())));
            }
            args.push(operand(c)?);
        }
        OKind::EndSub | OKind::Return if !c.at_end()? => args.push(operand(c)?),
        _ => {}
    }
    c.finish()?;
    Ok(Stmt::O(OWord {
        label,
        kind,
        args,
        at,
    }))
}

/// `m` of `DOm`/`ENDm` at the cursor.
fn loop_number(c: &mut Cur, at: usize) -> Result<u8, ExpandError> {
    c.skip()?;
    match c.digits() {
        Some(m @ 1..=3) => Ok(m as u8),
        _ => Err(c.err(at, "DO and END take a number 1 to 3")),
    }
}

/// A Fanuc condition: `[…]`.
fn condition(c: &mut Cur, what: &str) -> Result<Expr, ExpandError> {
    c.skip()?;
    if c.peek() != Some(b'[') {
        return Err(c.err(c.pos, format!("{what} needs its condition in [ ]")));
    }
    operand(c)
}

/// A Fanuc line.
fn parse_fanuc(c: &mut Cur) -> Result<Stmt, ExpandError> {
    c.skip()?;
    let deleted = c.peek() == Some(b'/');
    if deleted {
        c.pos += 1;
        c.skip()?;
    }
    // A sequence number before a statement is its GOTO target only.
    let start = c.mark();
    if matches!(c.peek(), Some(b'N' | b'n')) && c.peek_at(1).is_some_and(|d| d.is_ascii_digit()) {
        c.pos += 1;
        c.digits();
        c.skip()?;
        let word = c.letters().to_ascii_uppercase();
        let statement = c.peek() == Some(b'#')
            || matches!(word.as_str(), "IF" | "GOTO" | "WHILE" | "DO" | "END");
        if !statement {
            c.reset(start);
        }
    }
    let at = c.pos;
    let word = c.letters().to_ascii_uppercase();
    let control =
        c.peek() == Some(b'#') || matches!(word.as_str(), "IF" | "GOTO" | "WHILE" | "DO" | "END");
    if !control {
        return block(c, deleted).map(Stmt::Block);
    }
    if deleted {
        return Err(c.err(
            0,
            "a block-deleted line (/) cannot hold a macro statement: that depends on the switch at the machine",
        ));
    }
    if c.peek() == Some(b'#') {
        let a = assignment(c)?;
        c.finish()?;
        return Ok(Stmt::Assign(a));
    }
    c.pos += word.len();
    let stmt = match word.as_str() {
        "IF" => {
            let cond = condition(c, "IF")?;
            c.skip()?;
            let then_at = c.pos;
            let then = c.letters().to_ascii_uppercase();
            c.pos += then.len();
            match then.as_str() {
                "GOTO" => Stmt::If(cond, Then::Goto(operand(c)?, then_at)),
                "THEN" => {
                    c.skip()?;
                    if c.peek() != Some(b'#') {
                        return Err(c.err(c.pos, "IF … THEN takes an assignment #i = …"));
                    }
                    Stmt::If(cond, Then::Assign(assignment(c)?))
                }
                _ => return Err(c.err(then_at, "IF [ ] needs GOTO n or THEN #i = …")),
            }
        }
        "GOTO" => Stmt::Goto(operand(c)?, at),
        "WHILE" => {
            let cond = condition(c, "WHILE")?;
            c.skip()?;
            let do_at = c.pos;
            if !c.letters().eq_ignore_ascii_case("DO") {
                return Err(c.err(do_at, "WHILE [ ] needs DO1, DO2 or DO3"));
            }
            c.pos += 2;
            Stmt::While(cond, loop_number(c, do_at)?)
        }
        "DO" => Stmt::Do(loop_number(c, at)?),
        _ => Stmt::End(loop_number(c, at)?),
    };
    c.finish()?;
    Ok(stmt)
}

// ---------------------------------------------------------------------------
// Planning: blocks matched, programs found.

/// A Fanuc program in the file.
struct Program {
    /// `O2000`, or "the main program" when it has no number.
    name: String,
    /// The line of its program number, if it has one.
    head: Option<usize>,
    /// Its first line to run and the line after its last.
    start: usize,
    end: usize,
    /// Sequence numbers to their first line.
    seqs: HashMap<u64, usize>,
}

/// What the file's structure says, before it runs.
struct Plan {
    /// Per line: where its block's other parts are (see `plan_iso`,
    /// `plan_fanuc`).
    links: Vec<[usize; 2]>,
    /// LinuxCNC: each subroutine's `sub` and `endsub` lines.
    subs: HashMap<String, (usize, usize)>,
    /// Fanuc: the main program first.
    programs: Vec<Program>,
    /// Fanuc: program numbers to programs.
    numbers: HashMap<u64, usize>,
    /// The `%` that closes the tape.
    closing: Option<usize>,
}

fn closing(src: &[Src]) -> Option<usize> {
    (1..src.len()).find(|&i| src[i].stmt == Stmt::Tape)
}

/// A block opened and not yet closed.
struct Open {
    label: String,
    kind: OKind,
    at: usize,
    no: usize,
    /// `if`: its branches so far; loops: their `break` and `continue` lines.
    parts: Vec<usize>,
    seen_else: bool,
}

/// Matches LinuxCNC o-words. Links: `sub` [endsub]; `if`, `elseif`,
/// `else` [next branch, endif]; `while` [endwhile]; `endwhile` [while];
/// `do` [closing while]; closing while [do]; `repeat` [endrepeat];
/// `endrepeat` [repeat]; `break`, `continue` [loop start, loop end].
fn plan_iso(src: &mut [Src]) -> Result<Plan, ExpandError> {
    let mut links = vec![[NONE; 2]; src.len()];
    let mut subs: HashMap<String, (usize, usize)> = HashMap::new();
    let mut stack: Vec<Open> = Vec::new();
    for i in 0..src.len() {
        let no = src[i].no;
        let (kind, label, at) = match &src[i].stmt {
            Stmt::O(o) => (o.kind, o.label.clone(), o.at),
            _ => continue,
        };
        let err = |what: String| ExpandError::new(no, at + 1, what);
        let open = |kind| Open {
            label: label.clone(),
            kind,
            at: i,
            no,
            parts: Vec::new(),
            seen_else: false,
        };
        match kind {
            OKind::Sub => {
                if let Some(top) = stack.last() {
                    return Err(err(format!(
                        "{label} sub inside {} {} (line {}): definitions cannot nest",
                        top.label,
                        top.kind.word(),
                        top.no
                    )));
                }
                stack.push(open(OKind::Sub));
            }
            OKind::EndSub => {
                let top = close(&mut stack, OKind::Sub, &label, "endsub", &err)?;
                links[top.at][0] = i;
                if let Some((first, _)) = subs.insert(label.clone(), (top.at, i)) {
                    return Err(ExpandError::new(
                        top.no,
                        1,
                        format!("{label} is defined twice (first on line {})", src[first].no),
                    ));
                }
            }
            OKind::Return => {
                if !stack
                    .iter()
                    .any(|s| s.kind == OKind::Sub && s.label == label)
                {
                    return Err(err(format!("{label} return outside {label} sub")));
                }
            }
            OKind::If => stack.push(open(OKind::If)),
            OKind::ElseIf | OKind::Else => {
                let word = kind.word();
                match stack.last_mut() {
                    Some(top) if top.kind == OKind::If && top.label == label && !top.seen_else => {
                        let last = top.parts.last().copied().unwrap_or(top.at);
                        links[last][0] = i;
                        top.parts.push(i);
                        top.seen_else = kind == OKind::Else;
                    }
                    Some(top) if top.kind == OKind::If && top.label == label => {
                        return Err(err(format!("{label} {word} after {label} else")));
                    }
                    _ => return Err(mismatch(&stack, &label, word, &err)),
                }
            }
            OKind::EndIf => {
                let top = close(&mut stack, OKind::If, &label, "endif", &err)?;
                let last = top.parts.last().copied().unwrap_or(top.at);
                links[last][0] = i;
                for &part in std::iter::once(&top.at).chain(&top.parts) {
                    links[part][1] = i;
                }
            }
            OKind::While => {
                if matches!(stack.last(), Some(top) if top.kind == OKind::Do && top.label == label)
                {
                    if let Stmt::O(o) = &mut src[i].stmt {
                        o.kind = OKind::DoWhile;
                    }
                    let top = close(&mut stack, OKind::Do, &label, "while", &err)?;
                    links[top.at][0] = i;
                    links[i][0] = top.at;
                    exits(&mut links, &top, i);
                } else {
                    stack.push(open(OKind::While));
                }
            }
            OKind::EndWhile => {
                let top = close(&mut stack, OKind::While, &label, "endwhile", &err)?;
                links[top.at][0] = i;
                links[i][0] = top.at;
                exits(&mut links, &top, i);
            }
            OKind::Do => stack.push(open(OKind::Do)),
            OKind::Repeat => stack.push(open(OKind::Repeat)),
            OKind::EndRepeat => {
                let top = close(&mut stack, OKind::Repeat, &label, "endrepeat", &err)?;
                links[top.at][0] = i;
                links[i][0] = top.at;
                exits(&mut links, &top, i);
            }
            OKind::Break | OKind::Continue => {
                let word = kind.word();
                let found = stack
                    .iter_mut()
                    .rev()
                    .take_while(|s| s.kind != OKind::Sub)
                    .find(|s| {
                        s.label == label
                            && matches!(s.kind, OKind::While | OKind::Do | OKind::Repeat)
                    });
                match found {
                    Some(l) => l.parts.push(i),
                    None => return Err(err(format!("{label} {word}: no {label} loop around it"))),
                }
            }
            OKind::Call | OKind::DoWhile => {}
        }
    }
    if let Some(top) = stack.last() {
        let end = match top.kind {
            OKind::Sub => "endsub",
            OKind::If => "endif",
            OKind::While => "endwhile",
            OKind::Do => "while",
            _ => "endrepeat",
        };
        return Err(ExpandError::new(
            top.no,
            1,
            format!(
                "{} {} has no {} {end}",
                top.label,
                top.kind.word(),
                top.label
            ),
        ));
    }
    Ok(Plan {
        links,
        subs,
        programs: Vec::new(),
        numbers: HashMap::new(),
        closing: closing(src),
    })
}

/// Pops the innermost block if it is `kind` with `label`.
fn close(
    stack: &mut Vec<Open>,
    kind: OKind,
    label: &str,
    word: &str,
    err: &dyn Fn(String) -> ExpandError,
) -> Result<Open, ExpandError> {
    match stack.last() {
        Some(top) if top.kind == kind && top.label == label => stack
            .pop()
            .ok_or_else(|| err(format!("{label} {word} closes nothing"))),
        _ => Err(mismatch(stack, label, word, err)),
    }
}

fn mismatch(
    stack: &[Open],
    label: &str,
    word: &str,
    err: &dyn Fn(String) -> ExpandError,
) -> ExpandError {
    match stack.last() {
        Some(top) => err(format!(
            "{label} {word} does not close {} {} (line {})",
            top.label,
            top.kind.word(),
            top.no
        )),
        None => err(format!("{label} {word} without its opening line")),
    }
}

/// Links a loop's `break` and `continue` lines to its start and end.
fn exits(links: &mut [[usize; 2]], top: &Open, end: usize) {
    for &e in &top.parts {
        links[e] = [top.at, end];
    }
}

/// Finds Fanuc programs (each from its `O` line to the next `O` or `%`),
/// their sequence numbers, and matches `WHILE`/`DO` with `END` (links:
/// `WHILE`, `DO` [END]; `END` [WHILE or DO]).
fn plan_fanuc(src: &[Src]) -> Result<Plan, ExpandError> {
    let n = src.len();
    let bound =
        |i: usize| matches!(src[i].stmt, Stmt::Number(_)) || (i > 0 && src[i].stmt == Stmt::Tape);
    let first = usize::from(n > 0 && src[0].stmt == Stmt::Tape);
    let head = (first < n && matches!(src[first].stmt, Stmt::Number(_))).then_some(first);
    let main_end = (head.map_or(first, |h| h + 1)..n)
        .find(|&i| bound(i))
        .unwrap_or(n);
    let label = |i: usize| match src[i].stmt {
        Stmt::Number(Some(number)) => Some(number),
        _ => None,
    };
    let mut programs = vec![Program {
        name: head
            .and_then(label)
            .map_or("the main program".to_string(), |p| format!("O{p}")),
        head,
        start: 0,
        end: main_end,
        seqs: HashMap::new(),
    }];
    let mut numbers = HashMap::new();
    if let Some(p) = head.and_then(label) {
        numbers.insert(p, 0);
    }
    for i in 0..n {
        if !matches!(src[i].stmt, Stmt::Number(_)) || Some(i) == head {
            continue;
        }
        let end = (i + 1..n).find(|&j| bound(j)).unwrap_or(n);
        let number = label(i);
        if let Some(p) = number {
            if let Some(&other) = numbers.get(&p) {
                let first: &Program = &programs[other];
                return Err(ExpandError::new(
                    src[i].no,
                    1,
                    format!(
                        "O{p} is in the file twice (first on line {})",
                        first.head.map_or(1, |h| src[h].no)
                    ),
                ));
            }
            numbers.insert(p, programs.len());
        }
        programs.push(Program {
            name: number.map_or("O<…>".to_string(), |p| format!("O{p}")),
            head: Some(i),
            start: i + 1,
            end,
            seqs: HashMap::new(),
        });
    }
    let mut links = vec![[NONE; 2]; n];
    for p in &mut programs {
        let mut stack: Vec<(u8, usize)> = Vec::new();
        for i in p.start..p.end {
            if let Some(s) = src[i].seq {
                p.seqs.entry(s).or_insert(i);
            }
            match src[i].stmt {
                Stmt::While(_, m) | Stmt::Do(m) => stack.push((m, i)),
                Stmt::End(m) => match stack.pop() {
                    Some((open, at)) if open == m => {
                        links[at][0] = i;
                        links[i][0] = at;
                    }
                    Some((open, at)) => {
                        return Err(ExpandError::new(
                            src[i].no,
                            1,
                            format!("END{m} does not close DO{open} (line {})", src[at].no),
                        ))
                    }
                    None => {
                        return Err(ExpandError::new(
                            src[i].no,
                            1,
                            format!("END{m} without DO{m}"),
                        ))
                    }
                },
                _ => {}
            }
        }
        if let Some((m, at)) = stack.pop() {
            return Err(ExpandError::new(
                src[at].no,
                1,
                format!("DO{m} has no END{m} in {}", p.name),
            ));
        }
    }
    Ok(Plan {
        links,
        subs: HashMap::new(),
        programs,
        numbers,
        closing: closing(src),
    })
}

// ---------------------------------------------------------------------------
// Running.

/// Fanuc local variables of one macro level, `#0` … `#33`.
type Locals = [Option<f64>; FANUC_LOCALS + 1];

/// A level of calls (the main program is the first).
#[derive(Default)]
struct Frame {
    /// The line after the call.
    ret: usize,
    /// Fanuc: the program running, and how many more times after this one.
    program: usize,
    remaining: u64,
    /// Fanuc `G65`: the arguments, to start each repetition with.
    args: Option<Box<Locals>>,
    /// LinuxCNC: the caller's `#1` … `#30`, its named locals, `repeat`
    /// counts by line.
    saved: Vec<Option<f64>>,
    named: HashMap<String, f64>,
    repeats: HashMap<usize, i64>,
}

/// Where a value is stored.
enum Slot {
    Num(usize),
    Named(String),
}

/// A word evaluated: letter, value (`None`: vacant), the literal as
/// written, column.
struct Done<'s> {
    letter: u8,
    value: Option<f64>,
    literal: Option<&'s str>,
    at: usize,
}

/// The state of a run.
struct Run<'a> {
    src: &'a [Src<'a>],
    plan: &'a Plan,
    dialect: Dialect,
    params: Vec<Option<f64>>,
    levels: Vec<Locals>,
    named: HashMap<String, f64>,
    main: Frame,
    calls: Vec<Frame>,
    out: Vec<Line>,
    cap: usize,
    runs: usize,
    done: bool,
    /// LinuxCNC's `#<_current_tool>` (`#5400`) and `#<_selected_tool>`:
    /// the tool in the turret's station and the last `T`, followed
    /// through the blocks put out (a run starts with none: 0 and −1).
    tool: [f64; 2],
}

/// LinuxCNC's predefined parameters the expansion keeps: read-only.
const TOOL_PARAMETERS: [&str; 2] = ["_current_tool", "_selected_tool"];

impl<'a> Run<'a> {
    fn new(src: &'a [Src<'a>], plan: &'a Plan, dialect: Dialect, cap: usize) -> Self {
        Run {
            src,
            plan,
            dialect,
            params: vec![None; PARAMS],
            levels: vec![[None; FANUC_LOCALS + 1]],
            named: HashMap::new(),
            main: Frame::default(),
            calls: Vec::new(),
            out: Vec::new(),
            cap,
            runs: 0,
            done: false,
            tool: [0.0, -1.0],
        }
    }

    fn frame(&self) -> &Frame {
        self.calls.last().unwrap_or(&self.main)
    }

    fn frame_mut(&mut self) -> &mut Frame {
        match self.calls.last_mut() {
            Some(f) => f,
            None => &mut self.main,
        }
    }

    fn run(mut self) -> Result<Vec<Line>, ExpandError> {
        let src = self.src;
        let max_runs = self.cap.saturating_mul(RUNS_PER_BLOCK);
        let mut pc = 0;
        while !self.done {
            let end = match self.dialect {
                Dialect::Iso => src.len(),
                Dialect::Fanuc => self
                    .plan
                    .programs
                    .get(self.frame().program)
                    .map_or(src.len(), |p| p.end),
            };
            if pc >= end {
                if self.calls.is_empty() {
                    self.finish()?;
                    break;
                }
                let (name, line) = match self.plan.programs.get(self.frame().program) {
                    Some(p) => (p.name.clone(), p.head.map_or(1, |h| src[h].no)),
                    None => ("the subprogram".to_string(), 1),
                };
                return Err(ExpandError::new(
                    line,
                    1,
                    format!("{name} ends without M99"),
                ));
            }
            self.runs += 1;
            if self.runs > max_runs {
                return Err(ExpandError::new(
                    src[pc].no,
                    1,
                    format!("more than {max_runs} lines run: a loop that does not end?"),
                ));
            }
            pc = self.step(pc)?;
        }
        Ok(self.out)
    }

    fn err(&self, pc: usize, at: usize, what: impl Into<String>) -> ExpandError {
        ExpandError::new(self.src[pc].no, at + 1, what)
    }

    fn emit(&mut self, pc: usize, text: String) -> Result<(), ExpandError> {
        if self.out.len() >= self.cap {
            return Err(self.err(
                pc,
                0,
                format!(
                    "more than {} expanded blocks: a loop that does not end?",
                    self.cap
                ),
            ));
        }
        if self.dialect == Dialect::Iso
            && text.bytes().any(|b| matches!(b, b'T' | b't' | b'M' | b'm'))
        {
            // `T` selects, `M6` puts the selected tool in (LinuxCNC).
            let (mut t, mut m6) = (None, false);
            scan_words(&text, |run, value| {
                match (run.first().map(u8::to_ascii_uppercase), run.len(), value) {
                    (Some(b'T'), 1, Some(n)) => t = Some(n),
                    (Some(b'M'), 1, Some(6.0)) => m6 = true,
                    _ => {}
                }
                false
            });
            if let Some(n) = t {
                self.tool[1] = n;
            }
            if m6 && self.tool[1] >= 0.0 {
                self.tool[0] = self.tool[1];
            }
        }
        self.out.push(Line {
            source: self.src[pc].no,
            text,
        });
        Ok(())
    }

    /// The program ends: the closing `%` follows.
    fn finish(&mut self) -> Result<(), ExpandError> {
        self.done = true;
        if let Some(c) = self.plan.closing {
            self.emit(c, self.src[c].text.to_string())?;
        }
        Ok(())
    }

    /// Runs line `pc`; the next line to run.
    fn step(&mut self, pc: usize) -> Result<usize, ExpandError> {
        let src = self.src;
        let line = &src[pc];
        let next = pc + 1;
        match &line.stmt {
            Stmt::Plain { end } => {
                self.emit(pc, line.text.to_string())?;
                if *end {
                    self.finish()?;
                }
                Ok(next)
            }
            Stmt::Tape if pc == 0 => {
                self.emit(pc, line.text.to_string())?;
                Ok(next)
            }
            Stmt::Tape => {
                self.finish()?;
                Ok(next)
            }
            Stmt::Number(_) => {
                let main = self.plan.programs.first().and_then(|p| p.head);
                if self.dialect == Dialect::Iso || main == Some(pc) {
                    self.emit(pc, line.text.to_string())?;
                }
                Ok(next)
            }
            Stmt::Block(b) => self.block(pc, b),
            Stmt::Assign(a) => {
                self.assign(pc, a)?;
                Ok(next)
            }
            Stmt::O(o) => self.oword(pc, o),
            Stmt::If(cond, then) => {
                if !self.truth(cond, pc)? {
                    return Ok(next);
                }
                match then {
                    Then::Goto(target, at) => self.goto(pc, target, *at),
                    Then::Assign(a) => {
                        self.assign(pc, a)?;
                        Ok(next)
                    }
                }
            }
            Stmt::Goto(target, at) => self.goto(pc, target, *at),
            Stmt::While(cond, _) => {
                if self.truth(cond, pc)? {
                    Ok(next)
                } else {
                    Ok(self.plan.links[pc][0] + 1)
                }
            }
            Stmt::Do(_) => Ok(next),
            Stmt::End(_) => Ok(self.plan.links[pc][0]),
        }
    }

    // --- values -----------------------------------------------------------

    /// A parameter number from a value.
    fn index(&self, v: f64, pc: usize, at: usize) -> Result<usize, ExpandError> {
        match whole(v) {
            Some(i) if (0..PARAMS as i64).contains(&i) => Ok(i as usize),
            Some(i) => Err(self.err(
                pc,
                at,
                format!("#{i}: parameters are #0 to #{}", PARAMS - 1),
            )),
            None => Err(self.err(
                pc,
                at,
                format!(
                    "#[{}]: a parameter number is a whole number",
                    format_number(v)
                ),
            )),
        }
    }

    fn read(&self, i: usize) -> Val {
        if self.dialect == Dialect::Iso && i == 5400 {
            return num(self.tool[0]);
        }
        let stored = if self.dialect == Dialect::Fanuc && (1..=FANUC_LOCALS).contains(&i) {
            self.levels.last().and_then(|l| l.get(i).copied().flatten())
        } else {
            self.params.get(i).copied().flatten()
        };
        Val {
            v: stored.unwrap_or(0.0),
            vacant: self.dialect == Dialect::Fanuc && stored.is_none(),
        }
    }

    fn named_get(&self, name: &str) -> Option<f64> {
        if self.dialect == Dialect::Iso {
            if let Some(i) = TOOL_PARAMETERS.iter().position(|&p| p == name) {
                return Some(self.tool[i]);
            }
        }
        if name.starts_with('_') {
            self.named.get(name).copied()
        } else {
            self.frame().named.get(name).copied()
        }
    }

    fn eval(&self, e: &Expr, pc: usize) -> Result<Val, ExpandError> {
        Ok(match e {
            Expr::Num(v) => num(*v),
            Expr::Var(t, at) => match &**t {
                Target::Num(ix) => {
                    let i = self.eval(ix, pc)?;
                    self.read(self.index(i.v, pc, *at)?)
                }
                Target::Named(name) => num(self
                    .named_get(name)
                    .ok_or_else(|| self.err(pc, *at, format!("#<{name}> is not defined")))?),
            },
            Expr::Neg(x) => {
                let v = self.eval(x, pc)?;
                Val {
                    v: -v.v,
                    vacant: v.vacant,
                }
            }
            Expr::Group(x) => self.eval(x, pc)?,
            Expr::Exists(name) => num(if self.named_get(name).is_some() {
                1.0
            } else {
                0.0
            }),
            Expr::Bin(op, a, b, at) => {
                let a = self.eval(a, pc)?;
                let b = self.eval(b, pc)?;
                num(self.binop(*op, a, b).map_err(|w| self.err(pc, *at, w))?)
            }
            Expr::Call(f, x, at) => {
                let x = self.eval(x, pc)?;
                num(self.func(*f, x.v).map_err(|w| self.err(pc, *at, w))?)
            }
            Expr::Atan2(y, x, at) => {
                let y = self.eval(y, pc)?.v;
                let x = self.eval(x, pc)?.v;
                let mut d = y.atan2(x).to_degrees();
                if self.dialect == Dialect::Fanuc && d < 0.0 {
                    d += 360.0;
                }
                num(finite(d, "ATAN").map_err(|w| self.err(pc, *at, w))?)
            }
        })
    }

    fn binop(&self, op: Op, a: Val, b: Val) -> Result<f64, String> {
        let fanuc = self.dialect == Dialect::Fanuc;
        let (x, y) = (a.v, b.v);
        let eq = || {
            if fanuc {
                if a.vacant || b.vacant {
                    return a.vacant && b.vacant;
                }
                (x - y).abs() <= FANUC_EQUAL * x.abs().max(y.abs()).max(1.0)
            } else {
                (x - y).abs() < ISO_EQUAL
            }
        };
        let flag = |t: bool| if t { 1.0 } else { 0.0 };
        let bits = |f: fn(i64, i64) -> i64| match (whole(x), whole(y)) {
            (Some(i), Some(j)) => Ok(f(i, j) as f64),
            _ => Err(format!(
                "{} needs whole numbers in Fanuc programs ({} {} {})",
                op.name(),
                format_number(x),
                op.name(),
                format_number(y)
            )),
        };
        let r = match op {
            Op::Pow => {
                if x < 0.0 && y.fract() != 0.0 {
                    return Err("** of a negative number to a fractional power".to_string());
                }
                x.powf(y)
            }
            Op::Mul => x * y,
            Op::Div if y == 0.0 => return Err("division by zero (/)".to_string()),
            Op::Div => x / y,
            Op::Mod if y == 0.0 => return Err("MOD by zero".to_string()),
            Op::Mod if fanuc => x % y,
            Op::Mod => {
                let m = x % y;
                if m < 0.0 {
                    m + y.abs()
                } else {
                    m
                }
            }
            Op::Add => x + y,
            Op::Sub => x - y,
            Op::Eq => flag(eq()),
            Op::Ne => flag(!eq()),
            Op::Gt => flag(x > y),
            Op::Ge => flag(x >= y),
            Op::Lt => flag(x < y),
            Op::Le => flag(x <= y),
            Op::And if fanuc => bits(|i, j| i & j)?,
            Op::Or if fanuc => bits(|i, j| i | j)?,
            Op::Xor if fanuc => bits(|i, j| i ^ j)?,
            Op::And => flag(x != 0.0 && y != 0.0),
            Op::Or => flag(x != 0.0 || y != 0.0),
            Op::Xor => flag((x != 0.0) != (y != 0.0)),
        };
        finite(r, op.name())
    }

    fn func(&self, f: Func, x: f64) -> Result<f64, String> {
        let fanuc = self.dialect == Dialect::Fanuc;
        let turn = |d: f64| if fanuc && d < 0.0 { d + 360.0 } else { d };
        let r = match f {
            Func::Sin => x.to_radians().sin(),
            Func::Cos => x.to_radians().cos(),
            Func::Tan => x.to_radians().tan(),
            Func::Asin | Func::Acos if !(-1.0..=1.0).contains(&x) => {
                let name = if f == Func::Asin { "ASIN" } else { "ACOS" };
                return Err(format!("{name} of {}: outside -1 to 1", format_number(x)));
            }
            Func::Asin => turn(x.asin().to_degrees()),
            Func::Acos => x.acos().to_degrees(),
            Func::Atan => turn(x.atan().to_degrees()),
            Func::Sqrt if x < 0.0 => {
                return Err(format!("SQRT of a negative number ({})", format_number(x)))
            }
            Func::Sqrt => x.sqrt(),
            Func::Abs => x.abs(),
            Func::Round => x.round(),
            Func::Fix if fanuc => x.trunc(),
            Func::Fix => x.floor(),
            Func::Fup if fanuc => {
                if x < 0.0 {
                    x.floor()
                } else {
                    x.ceil()
                }
            }
            Func::Fup => x.ceil(),
            Func::Exp => x.exp(),
            Func::Ln if x <= 0.0 => return Err(format!("LN of {}: not above 0", format_number(x))),
            Func::Ln => x.ln(),
        };
        let name = match f {
            Func::Tan => "TAN",
            Func::Exp => "EXP",
            _ => "the function",
        };
        finite(r, name)
    }

    fn truth(&self, cond: &Expr, pc: usize) -> Result<bool, ExpandError> {
        let v = self.eval(cond, pc)?;
        Ok(!v.vacant && v.v != 0.0)
    }

    fn slot(&self, t: &Target, pc: usize, at: usize) -> Result<Slot, ExpandError> {
        match t {
            Target::Num(ix) => {
                let v = self.eval(ix, pc)?;
                match self.index(v.v, pc, at)? {
                    0 => Err(self.err(pc, at, "#0 cannot be set")),
                    i => Ok(Slot::Num(i)),
                }
            }
            Target::Named(name) => Ok(Slot::Named(name.clone())),
        }
    }

    fn store(&mut self, slot: Slot, v: Val, pc: usize, at: usize) -> Result<(), ExpandError> {
        let value = (!v.vacant).then_some(v.v);
        match slot {
            Slot::Num(5400) if self.dialect == Dialect::Iso => {
                Err(self.err(pc, at, "#5400 is read-only: the program's T and M6 set it"))
            }
            Slot::Num(3000) if self.dialect == Dialect::Fanuc => {
                let message = self.src[pc].comments.join(" ");
                Err(self.err(
                    pc,
                    at,
                    format!(
                        "alarm {} raised by the program (#3000) {message}",
                        format_number(v.v)
                    )
                    .trim_end()
                    .to_string(),
                ))
            }
            Slot::Num(i) if self.dialect == Dialect::Fanuc && i <= FANUC_LOCALS => {
                if let Some(cell) = self.levels.last_mut().and_then(|l| l.get_mut(i)) {
                    *cell = value;
                }
                Ok(())
            }
            Slot::Num(i) => {
                if let Some(cell) = self.params.get_mut(i) {
                    *cell = value;
                }
                Ok(())
            }
            Slot::Named(name) if TOOL_PARAMETERS.contains(&name.as_str()) => Err(self.err(
                pc,
                at,
                format!("#<{name}> is read-only: the program's T and M6 set it"),
            )),
            Slot::Named(name) => {
                if name.starts_with('_') {
                    self.named.insert(name, v.v);
                } else {
                    self.frame_mut().named.insert(name, v.v);
                }
                Ok(())
            }
        }
    }

    fn assign(&mut self, pc: usize, a: &Assign) -> Result<(), ExpandError> {
        let slot = self.slot(&a.target, pc, a.at)?;
        let v = self.eval(&a.value, pc)?;
        self.store(slot, v, pc, a.at)
    }

    fn goto(&self, pc: usize, target: &Expr, at: usize) -> Result<usize, ExpandError> {
        let v = self.eval(target, pc)?.v;
        let n = whole(v)
            .and_then(|n| u64::try_from(n).ok())
            .ok_or_else(|| {
                self.err(
                    pc,
                    at,
                    format!("GOTO {}: not a sequence number", format_number(v)),
                )
            })?;
        let program = self.plan.programs.get(self.frame().program);
        program
            .and_then(|p| p.seqs.get(&n).copied())
            .ok_or_else(|| {
                let name = program.map_or("the program", |p| p.name.as_str());
                self.err(pc, at, format!("GOTO {n}: no line N{n} in {name}"))
            })
    }

    // --- blocks -----------------------------------------------------------

    fn block(&mut self, pc: usize, b: &'a Block) -> Result<usize, ExpandError> {
        let mut done = Vec::with_capacity(b.words.len());
        for w in &b.words {
            done.push(match &w.value {
                Value::Literal(text, v) => Done {
                    letter: w.letter,
                    value: Some(*v),
                    literal: Some(text.as_str()),
                    at: w.at,
                },
                Value::Expr(e) => {
                    let v = self.eval(e, pc)?;
                    Done {
                        letter: w.letter,
                        value: (!v.vacant).then_some(v.v),
                        literal: None,
                        at: w.at,
                    }
                }
            });
        }
        // LinuxCNC: every assignment of the line reads the old values.
        let mut sets = Vec::with_capacity(b.assigns.len());
        for a in &b.assigns {
            let slot = self.slot(&a.target, pc, a.at)?;
            sets.push((slot, self.eval(&a.value, pc)?, a.at));
        }
        let find = |letter: u8, code: f64| {
            done.iter()
                .find(|d| d.letter == letter && d.value == Some(code))
        };
        if let Some(g) = [66.0, 66.1, 67.0].iter().find_map(|&c| find(b'G', c)) {
            return Err(self.err(pc, g.at, "G66/G67 modal macro calls are not supported"));
        }
        let calls = [find(b'G', 65.0), find(b'M', 98.0), find(b'M', 99.0)];
        if let Some(w) = calls.iter().flatten().next() {
            if self.dialect == Dialect::Iso {
                return Err(self.err(
                    pc,
                    w.at,
                    "G65, M98 and M99 are expanded in Fanuc programs; LinuxCNC programs call o-word subroutines",
                ));
            }
            if b.deleted {
                return Err(self.err(
                    pc,
                    0,
                    "a block-deleted line (/) cannot call or return: that depends on the switch at the machine",
                ));
            }
            return match calls {
                [Some(_), ..] => self.g65(pc, &done),
                [None, Some(_), _] => self.m98(pc, &done),
                _ => self.m99(pc, &done),
            };
        }
        let computed =
            !b.assigns.is_empty() || b.words.iter().any(|w| matches!(w.value, Value::Expr(_)));
        if !computed {
            self.emit(pc, self.src[pc].text.to_string())?;
        } else {
            let words: Vec<String> = done
                .iter()
                .filter_map(|d| {
                    let v = d.value?;
                    let letter = char::from(d.letter);
                    Some(match d.literal {
                        Some(t) if b"GMNTO".contains(&d.letter) => format!("{letter}{t}"),
                        _ => format!("{letter}{}", format_number(v)),
                    })
                })
                .collect();
            if !words.is_empty() {
                let mut text = if b.deleted {
                    "/".to_string()
                } else {
                    String::new()
                };
                text.push_str(&words.join(" "));
                for c in &self.src[pc].comments {
                    text.push(' ');
                    text.push_str(c);
                }
                self.emit(pc, text)?;
            }
        }
        for (slot, v, at) in sets {
            self.store(slot, v, pc, at)?;
        }
        let end = [2.0, 30.0].iter().any(|&c| find(b'M', c).is_some());
        if end {
            self.finish()?;
        }
        Ok(pc + 1)
    }

    /// A count or number from a word: a whole number in `range`.
    fn whole_in(
        &self,
        pc: usize,
        d: &Done,
        range: std::ops::RangeInclusive<i64>,
        what: &str,
    ) -> Result<u64, ExpandError> {
        let v = d.value.unwrap_or(0.0);
        match whole(v) {
            Some(n) if range.contains(&n) => Ok(n.unsigned_abs()),
            _ => Err(self.err(
                pc,
                d.at,
                format!(
                    "{}{}: {what} is a whole number {} to {}",
                    char::from(d.letter),
                    format_number(v),
                    range.start(),
                    range.end()
                ),
            )),
        }
    }

    fn program(&self, pc: usize, p: &Done, number: u64) -> Result<usize, ExpandError> {
        self.plan
            .numbers
            .get(&number)
            .copied()
            .ok_or_else(|| self.err(pc, p.at, format!("O{number} is not defined in this file")))
    }

    /// `M98 P… L…`.
    fn m98(&mut self, pc: usize, done: &[Done]) -> Result<usize, ExpandError> {
        let mut p = None;
        let mut l = None;
        for d in done {
            match d.letter {
                b'N' => {}
                b'M' if d.value == Some(98.0) => {}
                b'P' => p = Some(d),
                b'L' => l = Some(d),
                _ => return Err(self.err(pc, d.at, "M98 takes P and L only here")),
            }
        }
        let p = p.ok_or_else(|| self.err(pc, 0, "M98 needs P, the program to call"))?;
        let value = self.whole_in(pc, p, 0..=99_999_999, "P")?;
        let (mut count, number) = if value >= 10_000 {
            (value / 10_000, value % 10_000)
        } else {
            (1, value)
        };
        if let Some(l) = l {
            if value >= 10_000 {
                return Err(self.err(
                    pc,
                    l.at,
                    "M98 gives its repeat count in P or in L, not both",
                ));
            }
            count = self.whole_in(pc, l, 0..=9999, "L")?;
        }
        let program = self.program(pc, p, number)?;
        if count == 0 {
            return Ok(pc + 1);
        }
        self.call(pc, program, count, None)
    }

    /// `G65 P… L… A… B…`.
    fn g65(&mut self, pc: usize, done: &[Done]) -> Result<usize, ExpandError> {
        let mut args: Locals = [None; FANUC_LOCALS + 1];
        let mut seen = [false; FANUC_LOCALS + 1];
        let (mut p, mut l) = (None, None);
        for d in done {
            match d.letter {
                b'N' => {}
                b'G' if d.value == Some(65.0) => {}
                b'P' => p = Some(d),
                b'L' => l = Some(d),
                letter => {
                    let i = argument(letter).ok_or_else(|| {
                        self.err(
                            pc,
                            d.at,
                            format!("{} is not a G65 argument", char::from(letter)),
                        )
                    })?;
                    if seen[i] {
                        return Err(self.err(
                            pc,
                            d.at,
                            "G65 argument specification II (a letter repeated) is not supported",
                        ));
                    }
                    seen[i] = true;
                    args[i] = d.value;
                }
            }
        }
        let p = p.ok_or_else(|| self.err(pc, 0, "G65 needs P, the macro to call"))?;
        let number = self.whole_in(pc, p, 0..=9999, "P")?;
        let count = match l {
            Some(l) => self.whole_in(pc, l, 0..=9999, "L")?,
            None => 1,
        };
        let program = self.program(pc, p, number)?;
        if count == 0 {
            return Ok(pc + 1);
        }
        self.call(pc, program, count, Some(Box::new(args)))
    }

    fn deeper(&self, pc: usize) -> Result<(), ExpandError> {
        if self.calls.len() >= MAX_DEPTH {
            return Err(self.err(pc, 0, format!("calls nested deeper than {MAX_DEPTH}")));
        }
        Ok(())
    }

    /// Enters Fanuc program `program`, `count` times.
    fn call(
        &mut self,
        pc: usize,
        program: usize,
        count: u64,
        args: Option<Box<Locals>>,
    ) -> Result<usize, ExpandError> {
        self.deeper(pc)?;
        if let Some(a) = &args {
            self.levels.push(**a);
        }
        self.calls.push(Frame {
            ret: pc + 1,
            program,
            remaining: count,
            args,
            ..Frame::default()
        });
        Ok(self.plan.programs.get(program).map_or(pc + 1, |p| p.start))
    }

    /// `M99`.
    fn m99(&mut self, pc: usize, done: &[Done]) -> Result<usize, ExpandError> {
        for d in done {
            match d.letter {
                b'N' => {}
                b'M' if d.value == Some(99.0) => {}
                b'P' => {
                    return Err(self.err(
                        pc,
                        d.at,
                        "M99 P (return to a sequence number) is not supported",
                    ))
                }
                _ => return Err(self.err(pc, d.at, "M99 takes no other words here")),
            }
        }
        let Some(frame) = self.calls.last_mut() else {
            return Err(self.err(pc, 0, "M99 in the main program loops forever"));
        };
        if frame.remaining > 1 {
            frame.remaining -= 1;
            let start = self
                .plan
                .programs
                .get(frame.program)
                .map_or(pc + 1, |p| p.start);
            if let (Some(a), Some(level)) = (&frame.args, self.levels.last_mut()) {
                *level = **a;
            }
            return Ok(start);
        }
        let ret = frame.ret;
        if frame.args.is_some() {
            self.levels.pop();
        }
        self.calls.pop();
        Ok(ret)
    }

    // --- o-words ----------------------------------------------------------

    fn oword(&mut self, pc: usize, o: &OWord) -> Result<usize, ExpandError> {
        let link = self.plan.links[pc];
        let next = pc + 1;
        let arg = |run: &Self| -> Result<Option<Val>, ExpandError> {
            o.args.first().map(|e| run.eval(e, pc)).transpose()
        };
        let holds =
            |run: &Self| -> Result<bool, ExpandError> { Ok(arg(run)?.is_some_and(|v| v.v != 0.0)) };
        match o.kind {
            // A definition is skipped where it stands.
            OKind::Sub => Ok(link[0] + 1),
            OKind::EndSub | OKind::Return => {
                let v = arg(self)?;
                self.named.insert(
                    "_value_returned".to_string(),
                    if v.is_some() { 1.0 } else { 0.0 },
                );
                if let Some(v) = v {
                    self.named.insert("_value".to_string(), v.v);
                }
                let Some(frame) = self.calls.pop() else {
                    return Err(self.err(
                        pc,
                        o.at,
                        format!("{} {} outside a call", o.label, o.kind.word()),
                    ));
                };
                for (i, v) in frame.saved.iter().enumerate() {
                    if let Some(cell) = self.params.get_mut(i + 1) {
                        *cell = *v;
                    }
                }
                Ok(frame.ret)
            }
            OKind::Call => self.call_sub(pc, o),
            OKind::If => {
                if holds(self)? {
                    Ok(next)
                } else {
                    self.branch(link[0])
                }
            }
            // Reached from the branch before: that branch ran.
            OKind::ElseIf | OKind::Else => Ok(link[1] + 1),
            OKind::EndIf | OKind::Do => Ok(next),
            OKind::While => {
                if holds(self)? {
                    Ok(next)
                } else {
                    Ok(link[0] + 1)
                }
            }
            OKind::EndWhile => Ok(link[0]),
            OKind::DoWhile => {
                if holds(self)? {
                    Ok(link[0] + 1)
                } else {
                    Ok(next)
                }
            }
            OKind::Repeat => {
                let v = arg(self)?.map_or(0.0, |v| v.v);
                let count = if v.is_finite() { v.trunc() as i64 } else { 0 };
                if count <= 0 {
                    return Ok(link[0] + 1);
                }
                self.frame_mut().repeats.insert(pc, count);
                Ok(next)
            }
            OKind::EndRepeat => {
                let start = link[0];
                let left = self.frame_mut().repeats.entry(start).or_insert(1);
                *left -= 1;
                if *left > 0 {
                    Ok(start + 1)
                } else {
                    Ok(next)
                }
            }
            OKind::Break => Ok(link[1] + 1),
            OKind::Continue => match self.src.get(link[0]).map(|s| &s.stmt) {
                // A while loop tests again at its top; do and repeat at the end.
                Some(Stmt::O(OWord {
                    kind: OKind::While, ..
                })) => Ok(link[0]),
                _ => Ok(link[1]),
            },
        }
    }

    /// After an `if` or `elseif` that did not hold: the branch that runs.
    fn branch(&mut self, mut at: usize) -> Result<usize, ExpandError> {
        loop {
            let Some(Src {
                stmt: Stmt::O(o), ..
            }) = self.src.get(at)
            else {
                return Ok(at.saturating_add(1));
            };
            match o.kind {
                OKind::ElseIf => {
                    let holds = match o.args.first() {
                        Some(e) => self.truth(e, at)?,
                        None => false,
                    };
                    if holds {
                        return Ok(at + 1);
                    }
                    self.runs += 1;
                    at = self.plan.links[at][0];
                }
                _ => return Ok(at + 1),
            }
        }
    }

    /// `oN call [a] [b] …`.
    fn call_sub(&mut self, pc: usize, o: &OWord) -> Result<usize, ExpandError> {
        let Some(&(start, _)) = self.plan.subs.get(&o.label) else {
            return Err(self.err(pc, o.at, format!("{} is not defined in this file", o.label)));
        };
        self.deeper(pc)?;
        if o.args.len() > ISO_LOCALS {
            return Err(self.err(
                pc,
                o.at,
                format!("{} call: more than {ISO_LOCALS} arguments", o.label),
            ));
        }
        let mut args = Vec::with_capacity(o.args.len());
        for e in &o.args {
            args.push(self.eval(e, pc)?.v);
        }
        let saved = self.params[1..=ISO_LOCALS].to_vec();
        for i in 0..ISO_LOCALS {
            self.params[i + 1] = Some(args.get(i).copied().unwrap_or(0.0));
        }
        self.calls.push(Frame {
            ret: pc + 1,
            saved,
            ..Frame::default()
        });
        Ok(start + 1)
    }
}

/// The local a `G65` argument letter sets (argument specification I).
fn argument(letter: u8) -> Option<usize> {
    Some(match letter {
        b'A' => 1,
        b'B' => 2,
        b'C' => 3,
        b'I' => 4,
        b'J' => 5,
        b'K' => 6,
        b'D' => 7,
        b'E' => 8,
        b'F' => 9,
        b'H' => 11,
        b'M' => 13,
        b'Q' => 17,
        b'R' => 18,
        b'S' => 19,
        b'T' => 20,
        b'U' => 21,
        b'V' => 22,
        b'W' => 23,
        b'X' => 24,
        b'Y' => 25,
        b'Z' => 26,
        _ => return None,
    })
}

/// `r`, or why the operation named `what` has no finite result.
fn finite(r: f64, what: &str) -> Result<f64, String> {
    if r.is_finite() {
        Ok(r)
    } else {
        Err(format!("{what} gives no finite number"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ISO: Dialect = Dialect::Iso;
    const FANUC: Dialect = Dialect::Fanuc;

    /// The expanded texts.
    fn texts(text: &str, dialect: Dialect) -> Vec<String> {
        match expand(text, dialect) {
            Ok(lines) => lines.into_iter().map(|l| l.text).collect(),
            Err(e) => panic!("{e}"),
        }
    }

    /// The expanded source lines.
    fn sources(text: &str, dialect: Dialect) -> Vec<usize> {
        expand(text, dialect)
            .unwrap()
            .into_iter()
            .map(|l| l.source)
            .collect()
    }

    fn refusal(text: &str, dialect: Dialect) -> ExpandError {
        match expand(text, dialect) {
            Ok(lines) => panic!("expanded: {lines:?}"),
            Err(e) => e,
        }
    }

    /// Refused on `line`, `column`, saying something containing `what`.
    #[track_caller]
    fn refused(text: &str, dialect: Dialect, line: usize, column: usize, what: &str) {
        let e = refusal(text, dialect);
        assert_eq!((e.line, e.column), (line, column), "{e}");
        assert!(e.what.contains(what), "{e}");
    }

    #[test]
    fn plain_program_passes_through_unchanged() {
        let text = "%\nO1000 (PART)\nG21 G18 G99\n\n  T0101 ; roughing\nG00 X30. Z2.\r\n\
                    G01 Z-40. F.2 (cut)\nG00 X32.\nM30\n%\n";
        assert!(!needs_expansion(text));
        for dialect in [ISO, FANUC] {
            assert_eq!(
                texts(text, dialect),
                [
                    "%",
                    "O1000 (PART)",
                    "G21 G18 G99",
                    "  T0101 ; roughing",
                    "G00 X30. Z2.",
                    "G01 Z-40. F.2 (cut)",
                    "G00 X32.",
                    "M30",
                    "%"
                ]
            );
            assert_eq!(sources(text, dialect), [1, 2, 3, 5, 6, 7, 8, 9, 10]);
        }
        assert_eq!(expand("", ISO), Ok(Vec::new()));
        assert_eq!(expand("\n  \n", FANUC), Ok(Vec::new()));
    }

    #[test]
    fn what_needs_expansion() {
        for text in [
            "#1 = 2",
            "G01 X[1 + 2]",
            "G01 X#<dia>",
            "o100 sub",
            "O100 CALL [2]",
            "O<part> call",
            "o<x> endsub",
            "N10 M98 P2000",
            "M099",
            "G65 P9010 A1.",
            "G66 P9010",
            "GOTO 10",
            "N20 GOTO10",
            "WHILE [1] DO1",
            "DO2",
            "END1",
        ] {
            assert!(needs_expansion(text), "{text}");
        }
        for text in [
            "G00 X1. (#1 and [2] and IF in a comment)",
            "G00 X1. ; M98 P2000 after a semicolon",
            "O1000",
            "O<call>",
            ":2000 (SUB)",
            "%",
            "M30",
            "G01 X1 Z2 M3 S500",
            "M9",
            "G50 S2000",
        ] {
            assert!(!needs_expansion(text), "{text}");
        }
    }

    #[test]
    fn numbers_are_written_with_ten_decimals_at_most() {
        assert_eq!(format_number(1.0 / 3.0), "0.3333333333");
        assert_eq!(format_number(-0.0), "0");
        assert_eq!(format_number(-1e-11), "0");
        assert_eq!(format_number(1e-11), "0");
        assert_eq!(format_number(2.50), "2.5");
        assert_eq!(format_number(-3.0), "-3");
        assert_eq!(format_number(12.5), "12.5");
        assert_eq!(format_number(0.2), "0.2");
        assert_eq!(format_number(100.0), "100");
        assert_eq!(format_number(2.0 / 3.0), "0.6666666667");
        assert_eq!(
            texts("G01 X[1/3] Z[0 * -1] F[2.50]\n", ISO),
            ["G01 X0.3333333333 Z0 F2.5"]
        );
        assert_eq!(texts("#1 = 0\nG01 Z-#1\n", FANUC), ["G01 Z0"]);
    }

    #[test]
    fn fanuc_words_from_parameters() {
        assert_eq!(
            texts("#1 = 10\nG01 X[#1 * 2] Z-#1 F.2\n", FANUC),
            ["G01 X20 Z-10 F0.2"]
        );
        // Codes keep their text; values are written as numbers; comments follow.
        assert_eq!(
            texts(
                "#24 = 12.5\nN0010 G01 T0101 X#24 Z-2. M03 S800 (FINISH)\n",
                FANUC
            ),
            ["N0010 G01 T0101 X12.5 Z-2 M03 S800 (FINISH)"]
        );
        // Indirect and nested references.
        assert_eq!(
            texts("#1 = 101\n#101 = 3.5\nG00 X#[#1] Z##1 U#[100 + 1]\n", FANUC),
            ["G00 X3.5 Z3.5 U3.5"]
        );
    }

    #[test]
    fn fanuc_subprogram_is_inlined_l_times() {
        let program = |call: &str| {
            format!(
                "%\nO1000 (MAIN)\n#1 = 2000\nG00 X30. Z2.\n{call}\nG00 X50.\nM30\n\nO2000 (SUB)\nG01 U-1. F.1\nG00 W1.\nM99\n%\n"
            )
        };
        let expected = [
            "%",
            "O1000 (MAIN)",
            "G00 X30. Z2.",
            "G01 U-1. F.1",
            "G00 W1.",
            "G01 U-1. F.1",
            "G00 W1.",
            "G00 X50.",
            "M30",
            "%",
        ];
        // P of 5 to 8 digits: the repeat count, then the program's four.
        for call in [
            "M98 P2000 L2",
            "M98 P22000",
            "M98 P00022000",
            "N50 M98 P2000 L2",
            "M98 P#1 L[1 + 1]",
        ] {
            let text = program(call);
            let lines = expand(&text, FANUC).unwrap();
            let got: Vec<_> = lines.iter().map(|l| l.text.as_str()).collect();
            assert_eq!(got, expected, "{call}");
            let sources: Vec<_> = lines.iter().map(|l| l.source).collect();
            assert_eq!(sources, [1, 2, 4, 10, 11, 10, 11, 6, 7, 13], "{call}");
        }
        let many = expand(&program("M98 P20002000"), FANUC).unwrap();
        assert_eq!(many.len(), 3 + 2000 * 2 + 3);
        // Once without L; a subprogram before the call's own line is found too.
        assert_eq!(
            texts("O1\nM98 P0002\nM30\nO0002\nG00 X1.\nM99\n", FANUC),
            ["O1", "G00 X1.", "M30"]
        );
        // L0 calls nothing; nested subprograms.
        assert_eq!(
            texts(
                "M98 P10 L0\nM98 P20\nM30\nO10\nG00 X10.\nM99\nO20\nG00 X20.\nM98 P10\nM99\n",
                FANUC
            ),
            ["G00 X20.", "G00 X10.", "M30"]
        );
    }

    #[test]
    fn fanuc_while_loop_steps() {
        let text = "#1 = 0\n\
                    WHILE [#1 LT 3] DO1\n\
                    G01 X[10 + #1 * 2] Z[-#1]\n\
                    #1 = #1 + 1\n\
                    END1\n\
                    M30\n";
        assert_eq!(
            texts(text, FANUC),
            ["G01 X10 Z0", "G01 X12 Z-1", "G01 X14 Z-2", "M30"]
        );
        assert_eq!(sources(text, FANUC), [3, 3, 3, 6]);
        // Nested loops, the inner with its own number.
        let nested = "#1 = 1\nWHILE [#1 LE 2] DO1\n#2 = 1\nWHILE [#2 LE 2] DO2\n\
                      G01 X#1 Z#2\n#2 = #2 + 1\nEND2\n#1 = #1 + 1\nEND1\n";
        assert_eq!(
            texts(nested, FANUC),
            ["G01 X1 Z1", "G01 X1 Z2", "G01 X2 Z1", "G01 X2 Z2"]
        );
        // Steps of 0.1 reach 1.0 in eleven blocks.
        let tenths = "#1 = 0\nWHILE [#1 LE 1.0] DO1\nG01 X#1\n#1 = #1 + 0.1\nEND1\n";
        let out = texts(tenths, FANUC);
        assert_eq!(out.len(), 11);
        assert_eq!((out[3].as_str(), out[10].as_str()), ("G01 X0.3", "G01 X1"));
    }

    #[test]
    fn fanuc_if_goto_skips_and_loops() {
        let skip = "#1 = 5\nIF [#1 GT 3] GOTO 20\nG00 X1.\nN20 G00 X2.\n\
                    IF [#1 LT 3] GOTO30\nG00 X3.\nN30 M30\nG00 X4.\n";
        assert_eq!(texts(skip, FANUC), ["N20 G00 X2.", "G00 X3.", "N30 M30"]);
        let back = "#1 = 0\nN10 G01 X#1\n#1 = #1 + 1\nIF [#1 LE 2] GOTO 10\nM30\n";
        assert_eq!(
            texts(back, FANUC),
            ["N10 G01 X0", "N10 G01 X1", "N10 G01 X2", "M30"]
        );
        // GOTO out of a loop; a computed target; IF … THEN.
        let out = "#1 = 0\nWHILE [1 EQ 1] DO1\n#1 = #1 + 1\nIF [#1 EQ 3] GOTO #1 * 0 + 99\n\
                   END1\nN99 G00 X#1\nIF [#1 NE 3] THEN #1 = 0\nIF [#1 EQ 3] THEN #1 = 7\nG00 Z#1\n";
        // `GOTO #1 * 0 + 99` reads the target `#1` only: the rest is refused.
        refused(out, FANUC, 4, 22, "unexpected '*'");
        let out = out.replace("GOTO #1 * 0 + 99", "GOTO [#1 * 0 + 99]");
        assert_eq!(texts(&out, FANUC), ["N99 G00 X3", "G00 Z7"]);
    }

    #[test]
    fn fanuc_g65_macro_with_arguments_and_locals_restored() {
        let text = "O1000\n\
                    #1 = 7.\n\
                    #2 = 8.\n\
                    G65 P9010 A1. B[2 * 1] Z-3.\n\
                    G00 X#1 Z#2\n\
                    M30\n\
                    O9010 (MACRO)\n\
                    G01 X#1 Z#2 F#9 W#26\n\
                    #1 = 99.\n\
                    #100 = #1 + 1\n\
                    M99\n";
        assert_eq!(
            texts(text, FANUC),
            ["O1000", "G01 X1 Z2 W-3", "G00 X7 Z8", "M30"]
        );
        // Common variables are shared; L repeats with the same arguments.
        let repeat = "#100 = 0\nG65 P9011 L3 A2.\nG00 X#100\nM30\nO9011\n\
                      #100 = #100 + #1\n#1 = 50\nM99\n";
        assert_eq!(texts(repeat, FANUC), ["G00 X6", "M30"]);
        // M98 inside a macro shares the macro's locals.
        let shared =
            "G65 P9012 A5.\nM30\nO9012\nM98 P9013\nG00 X#1\nM99\nO9013\n#1 = #1 + 1\nM99\n";
        assert_eq!(texts(shared, FANUC), ["G00 X6", "M30"]);
    }

    #[test]
    fn vacant_drops_the_word_in_fanuc_and_reads_zero_in_linuxcnc() {
        assert_eq!(texts("G00 X#100 Z1.\n", FANUC), ["G00 Z1"]);
        assert_eq!(texts("G00 X#100 Z1.\n", ISO), ["G00 X0 Z1"]);
        assert_eq!(texts("G00 X-#1 Z[#1]\n", FANUC), ["G00"]);
        // A line whose every word is vacant gives no block.
        assert_eq!(texts("X#1\nG00 X1.\n", FANUC), ["G00 X1."]);
        // Vacant stays vacant when copied; arithmetic makes it 0; EQ tells.
        let text = "#1 = #0\n#5 = #1 + #0\nIF [#1 EQ #0] THEN #2 = 1\n\
                    IF [#1 EQ 0] THEN #3 = 1\nIF [#5 EQ #0] THEN #4 = 1\n\
                    IF [#1 GE 0] THEN #6 = 1\nG00 X#2 Z#3 U[#1 + 1] W#4 F#5 S#6\n";
        assert_eq!(texts(text, FANUC), ["G00 X1 U1 F0 S1"]);
    }

    #[test]
    fn linuxcnc_sub_and_call_with_arguments() {
        let text = "o<cut> sub\n\
                    G01 X[#1 * 2] Z#2\n\
                    #1 = 100\n\
                    o<cut> endsub\n\
                    G00 X0 Z0\n\
                    o<cut> call [5] [-3]\n\
                    #1 = 4\n\
                    O<CUT> CALL [#1] [#1 + 1]\n\
                    G00 X#1 Z#3\n\
                    M2\n\
                    G00 X99\n";
        assert_eq!(
            texts(text, ISO),
            ["G00 X0 Z0", "G01 X10 Z-3", "G01 X8 Z5", "G00 X4 Z0", "M2"]
        );
        assert_eq!(sources(text, ISO), [5, 2, 2, 9, 10]);
        // A definition after the main body; numbered o-words.
        let after = "o100 call [2]\nG00 X#1\nM30\no100 sub\nG01 Z-#1\no100 endsub\n";
        assert_eq!(texts(after, ISO), ["G01 Z-2", "G00 X0", "M30"]);
    }

    #[test]
    fn linuxcnc_if_elseif_else() {
        let text = |v: u32| {
            format!(
                "#1 = {v}\no1 if [#1 EQ 1]\nG00 X1\no1 elseif [#1 EQ 2]\nG00 X2\n\
                 o1 elseif [#1 GE 2]\nG00 X22\no1 else\nG00 X3\no1 endif\nM2\n"
            )
        };
        assert_eq!(texts(&text(1), ISO), ["G00 X1", "M2"]);
        assert_eq!(texts(&text(2), ISO), ["G00 X2", "M2"]);
        assert_eq!(texts(&text(5), ISO), ["G00 X22", "M2"]);
        assert_eq!(texts(&text(0), ISO), ["G00 X3", "M2"]);
        // Without else, and nested.
        let nested = "#1 = 1\no1 if [#1]\no2 if [#1 GT 5]\nG00 X5\no2 endif\nG00 X1\no1 endif\n";
        assert_eq!(texts(nested, ISO), ["G00 X1"]);
    }

    #[test]
    fn linuxcnc_loops() {
        let while_ = "#1 = 0\no2 while [#1 LT 3]\nG01 X#1\n#1 = [#1 + 1]\no2 endwhile\n";
        assert_eq!(texts(while_, ISO), ["G01 X0", "G01 X1", "G01 X2"]);
        // do … while runs its body once although the condition never holds.
        let do_ = "#1 = 10\no3 do\nG01 X#1\n#1 = [#1 + 1]\no3 while [#1 LT 3]\n";
        assert_eq!(texts(do_, ISO), ["G01 X10"]);
        let do2 = "#1 = 0\no3 do\nG01 X#1\n#1 = [#1 + 1]\no3 while [#1 LT 3]\n";
        assert_eq!(texts(do2, ISO), ["G01 X0", "G01 X1", "G01 X2"]);
        let repeat = "#1 = 0\no4 repeat [3]\n#1 = [#1 + 1]\nG01 Z-#1\no4 endrepeat\n";
        assert_eq!(texts(repeat, ISO), ["G01 Z-1", "G01 Z-2", "G01 Z-3"]);
        assert_eq!(
            texts("o4 repeat [0]\nG01 Z1\no4 endrepeat\nG00 X0\n", ISO),
            ["G00 X0"]
        );
        let exits = "#1 = 0\no5 while [#1 LT 10]\n#1 = [#1 + 1]\no6 if [#1 EQ 2]\no5 continue\n\
                     o6 endif\no7 if [#1 EQ 4]\no5 break\no7 endif\nG01 X#1\no5 endwhile\nM2\n";
        assert_eq!(texts(exits, ISO), ["G01 X1", "G01 X3", "M2"]);
        let repeat_continue = "#1 = 0\no8 repeat [3]\n#1 = [#1 + 1]\no9 if [#1 EQ 2]\n\
                               o8 continue\no9 endif\nG01 X#1\no8 endrepeat\n";
        assert_eq!(texts(repeat_continue, ISO), ["G01 X1", "G01 X3"]);
        let do_continue = "#1 = 0\no1 do\n#1 = [#1 + 1]\no2 if [#1 EQ 1]\no1 continue\no2 endif\n\
                           G01 X#1\no1 while [#1 LT 3]\n";
        assert_eq!(texts(do_continue, ISO), ["G01 X2", "G01 X3"]);
    }

    #[test]
    fn linuxcnc_return_and_value() {
        let text = "o<r> sub\no10 if [#1 LT 0]\no<r> return [-1]\no10 endif\nG01 X#1\n\
                    o<r> endsub [1]\no<r> call [-5]\nG00 X#<_value>\no<r> call [5]\n\
                    G00 X#<_value> Z#<_value_returned>\n";
        assert_eq!(texts(text, ISO), ["G00 X-1", "G01 X5", "G00 X1 Z1"]);
    }

    #[test]
    fn linuxcnc_current_and_selected_tool_follow_t_and_m6() {
        // A run starts with no tool in: LinuxCNC's 0, and none selected.
        let change = "o<first> if [#<_current_tool> NE 2]\nG0 X150 Z300\nT02 M6\no<first> endif\n";
        let text = format!(
            "G00 X#<_current_tool> Z#<_selected_tool>\n{change}{change}\
             T3\nG00 X#5400 Z#<_Selected_Tool>\nM06\nG00 X#<_current_tool>\n"
        );
        assert_eq!(
            texts(&text, ISO),
            [
                "G00 X0 Z-1",
                "G0 X150 Z300",
                "T02 M6",
                "T3",
                "G00 X2 Z3",
                "M06",
                "G00 X3"
            ]
        );
        refused("#<_current_tool> = 4\n", ISO, 1, 1, "read-only");
        refused("#5400 = 4\n", ISO, 1, 1, "read-only");
        // A T in a comment selects nothing.
        assert_eq!(
            texts("(T5 M6)\nG00 X#<_current_tool>\n", ISO),
            ["(T5 M6)", "G00 X0"]
        );
    }

    #[test]
    fn linuxcnc_named_parameters_local_and_global() {
        let text = "o<s> sub\n#<a> = 3\n#<_g> = [#<_g> + 1]\nG01 X#<a> Z#<_G>\no<s> endsub\n\
                    #<a> = 1\n#<_g> = 10\no<s> call\nG00 X#<a> Z#<_g>\n";
        assert_eq!(texts(text, ISO), ["G01 X3 Z11", "G00 X1 Z11"]);
        assert_eq!(
            texts("#<Dia Meter> = 2\nG01 X#<diameter>\n", ISO),
            ["G01 X2"]
        );
        refused(
            "o<t> sub\nG01 X#<a>\no<t> endsub\n#<a> = 1\no<t> call\n",
            ISO,
            2,
            6,
            "#<a> is not defined",
        );
        assert_eq!(
            texts("#<a> = 1\nG01 X[EXISTS[#<a>]] Z[EXISTS[#<b>]]\n", ISO),
            ["G01 X1 Z0"]
        );
        refused("#<a> = 1\n", FANUC, 1, 1, "LinuxCNC's");
    }

    #[test]
    fn linuxcnc_assignments_take_effect_after_the_line() {
        assert_eq!(texts("#1=1\n#1=2 #2=#1\nG01 X#1 Z#2\n", ISO), ["G01 X2 Z1"]);
        assert_eq!(
            texts("#1 = 1\nG01 X#1 #1 = 5\nG01 X#1\n", ISO),
            ["G01 X1", "G01 X5"]
        );
        // Fanuc takes one assignment, alone.
        refused("#1 = 1 #2 = 2\n", FANUC, 1, 8, "unexpected '#'");
        refused("G01 X1 #1 = 2\n", FANUC, 1, 8, "alone on its line");
    }

    #[test]
    fn expressions_and_functions() {
        let line = |e: &str, d: Dialect| texts(&format!("G01 X[{e}]\n"), d).remove(0);
        for (e, v) in [
            ("1 + 2 * 3 ** 2", "19"),
            ("[1 + 2] * 3", "9"),
            ("2 ** 3 ** 2", "64"),
            ("10 - 4 - 3", "3"),
            ("8 / 4 / 2", "1"),
            ("7 MOD 3", "1"),
            ("-[2]", "-2"),
            ("--2", "2"),
            ("2 * 3 EQ 6 AND 1", "1"),
            ("1 LT 2 + 3", "1"),
            ("1 GT 2 OR 0", "0"),
            ("1 XOR 0", "1"),
            ("1 NE 1.00001", "0"),
            ("SIN[30]", "0.5"),
            ("COS[60]", "0.5"),
            ("TAN[45]", "1"),
            ("ASIN[1]", "90"),
            ("ACOS[0]", "90"),
            ("ATAN[1]/[1]", "45"),
            ("SQRT[16]", "4"),
            ("ABS[-2.5]", "2.5"),
            ("ROUND[2.5]", "3"),
            ("ROUND[-2.5]", "-3"),
            ("EXP[0]", "1"),
            ("LN[1]", "0"),
            ("POW[2,10]", "1024"),
            ("sqrt[9] + abs[-1]", "4"),
        ] {
            assert_eq!(line(e, ISO), format!("G01 X{v}"), "{e}");
        }
        // Where the dialects differ.
        for (e, iso, fanuc) in [
            ("FIX[-1.5]", "-2", "-1"),
            ("FUP[-1.5]", "-1", "-2"),
            ("FIX[1.5]", "1", "1"),
            ("FUP[1.2]", "2", "2"),
            ("-7 MOD 3", "2", "-1"),
            ("ATAN[-1]/[-1]", "-135", "225"),
            ("ASIN[-0.5]", "-30", "330"),
            ("6 AND 3", "1", "2"),
            ("6 OR 3", "1", "7"),
            ("0.1 + 0.2 EQ 0.3", "1", "1"),
            ("1 EQ 1.00001", "1", "0"),
        ] {
            assert_eq!(line(e, ISO), format!("G01 X{iso}"), "{e} ISO");
            assert_eq!(line(e, FANUC), format!("G01 X{fanuc}"), "{e} Fanuc");
        }
        assert_eq!(line("ATAN[1,1]", FANUC), "G01 X45");
        assert_eq!(line("ATAN[1]", FANUC), "G01 X45");
        refused("G01 X[ATAN[1]]\n", ISO, 1, 7, "ATAN takes two arguments");
        // A function as a word's value, without brackets around it.
        assert_eq!(texts("G01 XSIN[90] Z-ABS[2]\n", ISO), ["G01 X1 Z-2"]);
    }

    #[test]
    fn arithmetic_errors_name_the_operation_and_column() {
        refused(
            "G01 X1\nG01 X[10 / [2 - 2]]\n",
            ISO,
            2,
            6,
            "division by zero (/)",
        );
        refused("#1 = 0\n#2 = 5 / #1\n", FANUC, 2, 6, "division by zero");
        refused("G01 X[1 + [10 / 0]]\n", FANUC, 1, 11, "division by zero");
        refused("G01 X[1 MOD 0]\n", ISO, 1, 6, "MOD by zero");
        refused(
            "G01 X[2 + SQRT[-4]]\n",
            ISO,
            1,
            11,
            "SQRT of a negative number",
        );
        refused(
            "G01 X[ASIN[2]]\n",
            FANUC,
            1,
            7,
            "ASIN of 2: outside -1 to 1",
        );
        refused("G01 X[ACOS[-1.5]]\n", ISO, 1, 7, "ACOS");
        refused("G01 X[LN[0]]\n", ISO, 1, 7, "LN of 0");
        refused("G01 X[[-8] ** 0.5]\n", ISO, 1, 6, "** of a negative number");
        refused(
            "G01 X[EXP[1000]]\n",
            ISO,
            1,
            7,
            "EXP gives no finite number",
        );
        refused("G01 X[6.5 AND 1]\n", FANUC, 1, 6, "AND needs whole numbers");
        let e = refusal("\n\n#1 = 0\n#2 = [4 / #1]\n", FANUC);
        assert_eq!(e.to_string(), "4:6: division by zero (/)");
    }

    #[test]
    fn syntax_errors_say_where() {
        refused(
            "G01 X[1 + 2\n",
            ISO,
            1,
            12,
            "expected ] to close the [ at column 6",
        );
        refused("G01 X[FOO[1]]\n", ISO, 1, 7, "unknown function FOO");
        refused("G01 X[1 +]\n", ISO, 1, 10, "unexpected ']'");
        refused(
            "G21\n[BILLET X53.97 Z113\n",
            FANUC,
            2,
            1,
            "unexpected '[': an expression follows an address letter (X[1+2]); a line that opens with '[' (a simulator's [BILLET) is not G-code",
        );
        refused("G01 X#\n", ISO, 1, 6, "# must be followed by");
        refused("G01 X[1] (open\n", ISO, 1, 10, "comment not closed");
        refused("#1 2\n", ISO, 1, 4, "expected =");
        refused("#0 = 1\n", FANUC, 1, 1, "#0 cannot be set");
        refused("#6000 = 1\n", ISO, 1, 1, "parameters are #0 to #5999");
        refused("#[1.5] = 1\n", ISO, 1, 1, "whole number");
        refused("G01 X#<a\n", ISO, 1, 7, "< without >");
        refused(
            "o100\n#1 = 1\no100 frobnicate [#1]\n",
            ISO,
            3,
            6,
            "needs a keyword",
        );
        // Without anything to expand such a line is the device's to refuse.
        assert_eq!(texts("o100 frobnicate\n", ISO), ["o100 frobnicate"]);
        refused("o[1] call\n", ISO, 1, 1, "indirect o-words");
        refused(
            "IF [1] THEN G00 X1\n",
            FANUC,
            1,
            13,
            "THEN takes an assignment",
        );
        refused(
            "IF 1 GOTO 5\n",
            FANUC,
            1,
            4,
            "IF needs its condition in [ ]",
        );
        refused(
            "WHILE [1] DO4\nEND4\n",
            FANUC,
            1,
            11,
            "DO and END take a number 1 to 3",
        );
        refused("/#1 = 2\n", FANUC, 1, 1, "block-deleted");
        refused("/#1 = 2\n", ISO, 1, 1, "block-deleted");
        refused("G01 X[1] IF\n", ISO, 1, 10, "unexpected IF");
        // Non-ASCII text is read without trouble.
        assert_eq!(texts("G01 X[1 + 1] (größe)\n", ISO), ["G01 X2 (größe)"]);
        refused("G01 X[1 + ä]\n", ISO, 1, 11, "unexpected 'ä'");
        let long = format!("G01 X[{}1]\n", "1 + ".repeat(MAX_TERMS));
        // G01, the [ and 499 times `1 +`: the 500th 1 is the 1001st term.
        refused(&long, ISO, 1, 6 + 499 * 4 + 1, "more than 1000 values");
        // Deep nesting is read up to a limit, then refused, without
        // exhausting a thread's stack.
        let deep = |n: usize| format!("G01 X{}1{}\n", "[".repeat(n), "]".repeat(n));
        assert_eq!(texts(&deep(MAX_NESTING - 1), ISO), ["G01 X1"]);
        refused(
            &deep(MAX_NESTING + 5),
            ISO,
            1,
            5 + MAX_NESTING + 1,
            "nested more than 100",
        );
        let signs = format!("G01 X[{}1]\n", "-".repeat(MAX_NESTING - 2));
        assert_eq!(texts(&signs, ISO), ["G01 X1"]);
        let chain = format!("G01 X[{}1]\n", "1 + ".repeat(400));
        assert_eq!(texts(&chain, FANUC), ["G01 X401"]);
    }

    #[test]
    fn block_delete_is_kept_on_computed_lines() {
        assert_eq!(texts("/G01 X[1 + 1]\n", ISO), ["/G01 X2"]);
        assert_eq!(texts("/ G01 X1.\n", FANUC), ["/ G01 X1."]);
    }

    #[test]
    fn linuxcnc_o_word_structure_errors() {
        refused(
            "o<nope> call\n",
            ISO,
            1,
            1,
            "o<nope> is not defined in this file",
        );
        refused(
            "G00 X0\n  o7 call [1]\n",
            ISO,
            2,
            3,
            "o7 is not defined in this file",
        );
        refused(
            "G00 X0\no1 endif\n",
            ISO,
            2,
            1,
            "o1 endif without its opening line",
        );
        refused(
            "o1 if [1]\no2 endif\n",
            ISO,
            2,
            1,
            "o2 endif does not close o1 if (line 1)",
        );
        refused("o1 if [1]\nG00 X1\n", ISO, 1, 1, "o1 if has no o1 endif");
        refused(
            "o1 while [1]\no1 endif\n",
            ISO,
            2,
            1,
            "does not close o1 while",
        );
        refused("o1 do\nG00 X1\n", ISO, 1, 1, "o1 do has no o1 while");
        refused(
            "o1 if [1]\no1 else\no1 elseif [1]\no1 endif\n",
            ISO,
            3,
            1,
            "after o1 else",
        );
        refused("o1 break\n", ISO, 1, 1, "o1 break: no o1 loop around it");
        refused(
            "o1 while [1]\no2 continue\no1 endwhile\n",
            ISO,
            2,
            1,
            "o2 continue: no o2 loop around it",
        );
        refused("o1 return\n", ISO, 1, 1, "o1 return outside o1 sub");
        refused(
            "o1 if [1]\no2 sub\no2 endsub\no1 endif\n",
            ISO,
            2,
            1,
            "definitions cannot nest",
        );
        refused(
            "o2 sub\no2 endsub\no2 sub\no2 endsub\n",
            ISO,
            3,
            1,
            "o2 is defined twice (first on line 1)",
        );
        refused("o1 if\n", ISO, 1, 6, "o1 if needs a [value]");
    }

    #[test]
    fn fanuc_structure_errors() {
        refused(
            "G00 X1.\nM99\n",
            FANUC,
            2,
            1,
            "M99 in the main program loops forever",
        );
        refused(
            "M98 P2000\nM30\nO2000\nM99 P20\n",
            FANUC,
            4,
            5,
            "M99 P (return to a sequence number) is not supported",
        );
        refused(
            "M98 P2000 X1.\nM30\nO2000\nM99\n",
            FANUC,
            1,
            11,
            "M98 takes P and L only here",
        );
        refused(
            "M98 P3000\nM30\nO2000\nM99\n",
            FANUC,
            1,
            5,
            "O3000 is not defined in this file",
        );
        refused(
            "M98 P20002000 L2\nM30\nO2000\nM99\n",
            FANUC,
            1,
            15,
            "not both",
        );
        refused("M98 L2\n", FANUC, 1, 1, "M98 needs P");
        refused(
            "M98 P2000\nM30\nO2000\nG00 X1.\n",
            FANUC,
            3,
            1,
            "O2000 ends without M99",
        );
        refused(
            "GOTO 50\nN5 M30\n",
            FANUC,
            1,
            1,
            "GOTO 50: no line N50 in the main program",
        );
        refused(
            "M98 P2000\nN50 M30\nO2000\nGOTO 50\nM99\n",
            FANUC,
            4,
            1,
            "no line N50 in O2000",
        );
        refused(
            "WHILE [1] DO1\nEND2\n",
            FANUC,
            2,
            1,
            "END2 does not close DO1 (line 1)",
        );
        refused("END1\n", FANUC, 1, 1, "END1 without DO1");
        refused("WHILE [1] DO1\nG00 X1.\n", FANUC, 1, 1, "DO1 has no END1");
        refused(
            "O1\nM30\nO2\nM99\nO2\nM99\n",
            FANUC,
            5,
            1,
            "O2 is in the file twice",
        );
        refused(
            "G65 P9010 A1. A2.\nM30\nO9010\nM99\n",
            FANUC,
            1,
            15,
            "specification II",
        );
        refused(
            "G65 P9010 G01\nM30\nO9010\nM99\n",
            FANUC,
            1,
            11,
            "G is not a G65 argument",
        );
        refused("G66 P9010 A1.\n", FANUC, 1, 1, "G66/G67");
        refused(
            "M98 P2000\n",
            ISO,
            1,
            1,
            "LinuxCNC programs call o-word subroutines",
        );
        refused(
            "#3000 = 12 (TOOL MISSING)\n",
            FANUC,
            1,
            1,
            "alarm 12 raised by the program (#3000) (TOOL MISSING)",
        );
        refused(
            "/M98 P2000\nM30\nO2000\nM99\n",
            FANUC,
            1,
            1,
            "block-deleted",
        );
    }

    #[test]
    fn runaway_loops_stop_at_the_cap() {
        let e = expand_with_cap(
            "#1 = 0\nWHILE [1] DO1\nG01 X#1\n#1 = #1 + 1\nEND1\n",
            FANUC,
            100,
        )
        .unwrap_err();
        assert_eq!(
            (e.line, e.what.as_str()),
            (
                3,
                "more than 100 expanded blocks: a loop that does not end?"
            )
        );
        let e = expand_with_cap("o1 while [1]\nG01 X1\no1 endwhile\n", ISO, 50).unwrap_err();
        assert_eq!(
            e.what,
            "more than 50 expanded blocks: a loop that does not end?"
        );
        // A loop that emits nothing stops after ten lines run per allowed block.
        let e = expand_with_cap("N1 #1 = 1\nGOTO 1\n", FANUC, 100).unwrap_err();
        assert_eq!(
            e.what,
            "more than 1000 lines run: a loop that does not end?"
        );
        let e = expand_with_cap("o1 do\n#1 = 1\no1 while [1]\n", ISO, 10).unwrap_err();
        assert!(e.what.contains("more than 100 lines run"), "{e}");
        // Exactly the cap is fine.
        let ten = "o1 repeat [10]\nG01 X1\no1 endrepeat\n";
        assert_eq!(expand_with_cap(ten, ISO, 10).unwrap().len(), 10);
        assert!(expand_with_cap(ten, ISO, 9).is_err());
    }

    #[test]
    fn recursion_stops_at_depth_16() {
        refused(
            "o<r> sub\no<r> call\no<r> endsub\no<r> call\n",
            ISO,
            2,
            1,
            "calls nested deeper than 16",
        );
        refused(
            "M98 P2000\nM30\nO2000\nM98 P2000\nM99\n",
            FANUC,
            4,
            1,
            "calls nested deeper than 16",
        );
        refused(
            "G65 P1 A1.\nM30\nO1\nG65 P1\nM99\n",
            FANUC,
            4,
            1,
            "calls nested deeper than 16",
        );
        // Sixteen levels are allowed, seventeen are not.
        let countdown = |n: u32| {
            format!(
                "o<r> sub\no1 if [#1 GT 1]\no<r> call [#1 - 1]\no1 endif\nG01 X#1\no<r> endsub\no<r> call [{n}]\n"
            )
        };
        let out = texts(&countdown(16), ISO);
        assert_eq!(out.len(), 16);
        assert_eq!((out[0].as_str(), out[15].as_str()), ("G01 X1", "G01 X16"));
        refused(&countdown(17), ISO, 3, 1, "calls nested deeper than 16");
    }

    #[test]
    fn program_end_stops_expansion_and_closes_the_tape() {
        // M30 in a subprogram ends everything.
        let text = "%\nO1\nM98 P2\nG00 X9.\nM30\nO2\nG00 X1.\nM30\nM99\n%\n";
        assert_eq!(texts(text, FANUC), ["%", "O1", "G00 X1.", "M30", "%"]);
        // The main program running into the next program ends there.
        assert_eq!(
            texts("O1\nG00 X1.\nO2\nG00 X2.\nM99\n", FANUC),
            ["O1", "G00 X1."]
        );
        // A computed M30 ends the program too.
        assert_eq!(
            texts("%\n#1 = 30\nG00 X[1] M#1\nG00 X2\n%\n", ISO),
            ["%", "G00 X1 M30", "%"]
        );
        // Without M30 the closing % ends it.
        assert_eq!(texts("%\nG00 X1\n%\nG00 X2\n", ISO), ["%", "G00 X1", "%"]);
    }

    /// Every expanded line is one the device's reader takes.
    #[track_caller]
    fn device_reads(lines: &[String], dialect: Dialect) {
        use core_nostd::gcode::{parse, Units};
        for l in lines {
            assert!(parse(l, dialect, Units::Mm).is_ok(), "{l}");
        }
    }

    #[test]
    fn fanuc_grooving_macro_end_to_end() {
        let text = "%\n\
                    O1000 (GROOVES)\n\
                    G21 G18 G99\n\
                    T0303\n\
                    G97 S600 M03\n\
                    G65 P9100 X30. Z-10. U24. W2.\n\
                    G65 P9100 X30. Z-20. U26. W2.\n\
                    G00 X100. Z100.\n\
                    M30\n\
                    O9100 (GROOVE: X START DIA, Z POSITION, U BOTTOM DIA, W PECKS)\n\
                    G00 X#24 Z#26\n\
                    #1 = 1\n\
                    #2 = [#24 - #21] / #23\n\
                    WHILE [#1 LE #23] DO1\n\
                    G01 X[#24 - #1 * #2] F.05\n\
                    G00 X[#24 - #1 * #2 + 1.]\n\
                    #1 = #1 + 1\n\
                    END1\n\
                    G00 X#24\n\
                    M99\n\
                    %\n";
        assert!(needs_expansion(text));
        let out = texts(text, FANUC);
        assert_eq!(
            out,
            [
                "%",
                "O1000 (GROOVES)",
                "G21 G18 G99",
                "T0303",
                "G97 S600 M03",
                "G00 X30 Z-10",
                "G01 X27 F0.05",
                "G00 X28",
                "G01 X24 F0.05",
                "G00 X25",
                "G00 X30",
                "G00 X30 Z-20",
                "G01 X28 F0.05",
                "G00 X29",
                "G01 X26 F0.05",
                "G00 X27",
                "G00 X30",
                "G00 X100. Z100.",
                "M30",
                "%"
            ]
        );
        assert_eq!(
            sources(text, FANUC),
            [1, 2, 3, 4, 5, 11, 15, 16, 15, 16, 19, 11, 15, 16, 15, 16, 19, 8, 9, 21]
        );
        device_reads(&out, FANUC);
    }

    #[test]
    fn linuxcnc_facing_subroutine_end_to_end() {
        let text = "%\n\
                    (facing passes)\n\
                    G7 G18 G21 G95\n\
                    o<face> sub\n\
                    \x20 #<z> = #1\n\
                    \x20 o101 while [#<z> GT #2]\n\
                    \x20   #<z> = [#<z> - #3]\n\
                    \x20   o102 if [#<z> LT #2]\n\
                    \x20     #<z> = #2\n\
                    \x20   o102 endif\n\
                    \x20   G00 X[#4 + 2] Z#<z>\n\
                    \x20   G01 X0 F0.1\n\
                    \x20 o101 endwhile\n\
                    o<face> endsub\n\
                    G00 X52 Z2\n\
                    o<face> call [0] [-2.5] [1] [50]\n\
                    G00 X100 Z100\n\
                    M30\n\
                    %\n";
        let out = texts(text, ISO);
        assert_eq!(
            out,
            [
                "%",
                "(facing passes)",
                "G7 G18 G21 G95",
                "G00 X52 Z2",
                "G00 X52 Z-1",
                "    G01 X0 F0.1",
                "G00 X52 Z-2",
                "    G01 X0 F0.1",
                "G00 X52 Z-2.5",
                "    G01 X0 F0.1",
                "G00 X100 Z100",
                "M30",
                "%"
            ]
        );
        device_reads(&out, ISO);
    }
}

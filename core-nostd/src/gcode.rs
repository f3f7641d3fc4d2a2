//! G-code blocks: words parsed and checked, before any motion.
//!
//! A block is a line of address words: a letter followed by a number, with or
//! without spaces between words (`N10 G01 X27.532 Z0`, `G1X12.5`), letters in
//! either case. Comments in parentheses and everything after `;` are ignored.
//! Each address may appear once, except `G`, which may appear once per modal
//! group. Lines as CAM posts and machinists write them are read too:
//!
//! - numbers `30.`, `.5`, `+2`, with up to 15 decimals, rounded once to the
//!   ångström (10⁻⁷ mm) half away from zero;
//! - `%` (the tape mark a program begins and ends with) alone on its line;
//! - a program number alone on its line: `O1234`, `O<name>`, `:1234`
//!   (an `o<name>` followed by a word is a subroutine, expanded by the host);
//! - `/` at the start: block delete, skipped when the switch is on;
//! - `Y0` (lathe posts write it); any other `Y` is refused by name;
//! - `G20`/`G21` anywhere in a block reads all its lengths and its feed in
//!   inches (25.4 mm, rounded once to the ångström) or millimetres
//!   ([`parse_in`] takes the modal unit for blocks without one).
//!
//! | address | meaning | value |
//! |---|---|---|
//! | `N` | sequence number | kept to name the block in refusals |
//! | `G` | 00 01 02 03 (motion), 18 (ZX plane), 20 21 (inch, millimetres), 40 41 42 (nose compensation), 90 91 (absolute, incremental), 450 451 (outside corners: transition arc, intersection) | whole number |
//! | `X` | X end point: a diameter when `DIAM=1` | length |
//! | `Z` | Z end point | length |
//! | `Y` | only 0 | length |
//! | `I`, `K` | arc centre minus start point, radius values | length |
//! | `R` | arc radius: positive for an arc of at most 180°, negative for more | length |
//! | `F` | feed along the path, mm/min (modal) | length |
//! | `S`, `T`, `M` | speed, tool, miscellaneous | accepted, not acted on |

use crate::length::{Length, LengthError};
use core::fmt;

/// Motion modes (group 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Motion {
    /// G00, rapid positioning (interpolated as G01 on a step/dir machine).
    Rapid,
    /// G01.
    Linear,
    /// G02.
    ArcCw,
    /// G03.
    ArcCcw,
}

impl Motion {
    /// The G word as written in replies.
    pub const fn word(self) -> &'static str {
        match self {
            Motion::Rapid => "G00",
            Motion::Linear => "G01",
            Motion::ArcCw => "G02",
            Motion::ArcCcw => "G03",
        }
    }
}

/// Nose radius compensation modes (group 7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Compensation {
    /// G40, off.
    Off,
    /// G41, tool left of the contour.
    Left,
    /// G42, tool right of the contour.
    Right,
}

/// How compensation closes outside corners (group 18).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Corner {
    /// G450: a transition arc of the nose radius about the corner.
    Arc,
    /// G451: the offset elements (their tangents, for arcs) are intersected.
    Intersection,
}

/// What a line holds besides words.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LineKind {
    /// Address words (or nothing but comments).
    #[default]
    Words,
    /// `%`: the tape mark.
    TapeMark,
    /// A program number: `O1234`, `O<name>`, `:1234`.
    Program,
}

/// The unit of a block's lengths and feed (group 6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Units {
    /// G21: millimetres (power-on).
    #[default]
    Mm,
    /// G20: inches, 25.4 mm each; feeds in inches per minute.
    Inch,
}

/// One parsed block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Block {
    /// Words, the tape mark, or a program number.
    pub kind: LineKind,
    /// Block delete: the line began with `/`.
    pub deleted: bool,
    /// G00–G03 if given.
    pub motion: Option<Motion>,
    /// G40–G42 if given.
    pub compensation: Option<Compensation>,
    /// G90 (false) or G91 (true) if given.
    pub incremental: Option<bool>,
    /// G450 or G451 if given.
    pub corner: Option<Corner>,
    /// G18 given: the ZX plane, the only one a lathe has.
    pub plane_zx: bool,
    /// G20 or G21 if given; the block's lengths are read in it.
    pub units: Option<Units>,
    /// The sequence number, when written as a whole number below 2³².
    pub n: Option<u32>,
    /// X word.
    pub x: Option<Length>,
    /// Z word.
    pub z: Option<Length>,
    /// I word.
    pub i: Option<Length>,
    /// K word.
    pub k: Option<Length>,
    /// R word.
    pub r: Option<Length>,
    /// F word: the feed, mm/min.
    pub f: Option<Length>,
}

/// Why a block was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BlockError {
    /// An address letter this control does not know (`ERR SYNTAX`).
    UnknownAddress(u8),
    /// An address given twice, or two G words of one group (`ERR SYNTAX`).
    Repeated(u8),
    /// A letter without a number, or text that is not a word (`ERR SYNTAX`).
    NotAWord,
    /// An unclosed comment (`ERR SYNTAX`).
    Comment,
    /// A malformed or out-of-range number at an address (`ERR VALUE`).
    Value(u8, LengthError),
    /// A G code this control does not run (`ERR VALUE`): its code in
    /// tenths (G90.1 is 901), or `None` when the number is no G code.
    UnsupportedG(Option<u16>),
    /// A `Y` word other than 0: a lathe has no Y axis (`ERR VALUE`).
    NoYAxis,
    /// A program number with other words, or not at the line's start
    /// (`ERR SYNTAX`).
    ProgramNumber,
    /// An `o<name>` subroutine, loop or condition, which the host expands
    /// before streaming (`ERR SYNTAX`).
    HostLanguage,
}

impl BlockError {
    /// Whether the protocol answers it `ERR VALUE` (a number or a code
    /// this control does not take) rather than `ERR SYNTAX`.
    pub const fn is_value(&self) -> bool {
        matches!(
            self,
            BlockError::Value(..) | BlockError::UnsupportedG(_) | BlockError::NoYAxis
        )
    }
}

/// What a refusal says, naming the word: `unknown address Q`, `G71 canned
/// cycles not supported`, `X more than 15 decimals`.
impl fmt::Display for BlockError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BlockError::UnknownAddress(l) => write!(f, "unknown address {}", char::from(l)),
            BlockError::Repeated(l) => write!(f, "address given twice: {}", char::from(l)),
            BlockError::NotAWord => f.write_str("not an address word"),
            BlockError::Comment => f.write_str("unclosed comment"),
            BlockError::Value(l, why) => write!(f, "{} {why}", char::from(l)),
            BlockError::UnsupportedG(None) => f.write_str("G not a G code"),
            BlockError::UnsupportedG(Some(tenths)) => {
                let (whole, tenth) = (tenths / 10, tenths % 10);
                let why = match whole {
                    17 | 19 if tenth == 0 => "plane not supported: a lathe cuts in G18 (ZX)",
                    70..=76 if tenth == 0 => "canned cycles not supported",
                    _ => "not supported",
                };
                if tenth == 0 {
                    write!(f, "G{whole:02} {why}")
                } else {
                    write!(f, "G{whole}.{tenth} {why}")
                }
            }
            BlockError::NoYAxis => f.write_str("Y a lathe has no Y axis: only Y0"),
            BlockError::ProgramNumber => {
                f.write_str("a program number stands alone at a line's start: O")
            }
            BlockError::HostLanguage => {
                f.write_str("o-word subroutines, loops and conditions are expanded by the host")
            }
        }
    }
}

/// A refusal and the column (from 1, in bytes) of the word it names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Located {
    /// What is wrong.
    pub error: BlockError,
    /// Where it begins.
    pub column: usize,
}

/// Whether a request line is a G-code line: its first word is an address
/// letter directly followed by a number, or it begins with `%`, `/`, `(`,
/// `;`, `:` or `O<`.
///
/// ```
/// use core_nostd::gcode::is_block;
/// assert!(is_block("N10 G01 X12"));
/// assert!(is_block("x-1.5"));
/// assert!(is_block("X.5"));
/// assert!(is_block("%"));
/// assert!(is_block("(FACE)"));
/// assert!(is_block("O<part> (name)"));
/// assert!(!is_block("ZERO"));
/// assert!(!is_block("MOVE X=1"));
/// ```
pub fn is_block(line: &str) -> bool {
    let b = line.trim_start().as_bytes();
    match b {
        [b'%' | b'/' | b'(' | b';' | b':', ..] => true,
        [b'O' | b'o', b'<', ..] => true,
        [l, d, ..] => {
            l.is_ascii_alphabetic() && (d.is_ascii_digit() || matches!(d, b'+' | b'-' | b'.'))
        }
        _ => false,
    }
}

/// Parses a block.
///
/// ```
/// use core_nostd::gcode::{parse_block, Motion};
/// let b = parse_block("N9 G01X27.532 Z0 ; point 2").unwrap();
/// assert_eq!(b.motion, Some(Motion::Linear));
/// assert_eq!(b.x.unwrap().to_string(), "27.5320");
/// ```
pub fn parse_block(line: &str) -> Result<Block, BlockError> {
    parse_located(line).map_err(|l| l.error)
}

/// Parses a block whose lengths are in `units` unless it says otherwise
/// (a `G20` or `G21` anywhere in it applies to all of its words).
///
/// ```
/// use core_nostd::gcode::{parse_in, Units};
/// let b = parse_in("G01 X1. F10.", Units::Inch).unwrap();
/// assert_eq!(b.x.unwrap().to_string(), "25.4000");
/// assert_eq!(b.f.unwrap().to_string(), "254.0000");
/// let b = parse_in("X1. G21", Units::Inch).unwrap();
/// assert_eq!(b.x.unwrap().to_string(), "1.0000");
/// ```
pub fn parse_in(line: &str, units: Units) -> Result<Block, Located> {
    parse_with(line, units_word(line).unwrap_or(units))
}

/// Parses a block; a refusal says where.
///
/// ```
/// use core_nostd::gcode::{parse_located, BlockError};
/// let e = parse_located("G00 X30. Y5 Z2.").unwrap_err();
/// assert_eq!((e.error, e.column), (BlockError::NoYAxis, 10));
/// ```
pub fn parse_located(line: &str) -> Result<Block, Located> {
    parse_in(line, Units::Mm)
}

/// The unit a line's own `G20`/`G21` sets, if it has one: the first such
/// word outside comments and before any `;` (an unclosed comment ends the
/// search; the parser refuses the line anyway).
fn units_word(line: &str) -> Option<Units> {
    let bytes = line.as_bytes();
    let mut pos = 0;
    let mut found = None;
    while let Some(&c) = bytes.get(pos) {
        match c {
            b';' => break,
            b'(' => {
                let Some(close) = bytes.iter().skip(pos).position(|&b| b == b')') else {
                    break;
                };
                pos += close + 1;
            }
            b'G' | b'g' => {
                let n = bytes
                    .iter()
                    .skip(pos + 1)
                    .take_while(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.'))
                    .count();
                match line.get(pos + 1..pos + 1 + n).and_then(g_code) {
                    Some(200) if found.is_none() => found = Some(Units::Inch),
                    Some(210) if found.is_none() => found = Some(Units::Mm),
                    _ => {}
                }
                pos += 1 + n;
            }
            _ => pos += 1,
        }
    }
    found
}

fn parse_with(line: &str, units: Units) -> Result<Block, Located> {
    let mut block = Block::default();
    let mut seen = [false; 26];
    let bytes = line.as_bytes();
    let at = |error, pos: usize| Located {
        error,
        column: pos + 1,
    };
    let mut pos = bytes
        .iter()
        .take_while(|b| matches!(b, b' ' | b'\t'))
        .count();
    let start = pos;
    match bytes.get(pos..) {
        Some([b'%', ..]) => {
            block.kind = LineKind::TapeMark;
            pos += 1;
        }
        Some([b'/', ..]) => {
            block.deleted = true;
            pos += 1;
        }
        Some([b':', ..]) => {
            block.kind = LineKind::Program;
            pos = program_number(bytes, pos + 1).ok_or(at(BlockError::NotAWord, pos))?;
        }
        Some([b'O' | b'o', b'<', ..]) => {
            block.kind = LineKind::Program;
            let close = bytes
                .iter()
                .skip(pos)
                .position(|&b| b == b'>')
                .ok_or(at(BlockError::NotAWord, pos))?;
            let name = bytes.get(pos + 2..pos + close).unwrap_or(&[]);
            if name.is_empty()
                || !name
                    .iter()
                    .all(|b| b.is_ascii_alphanumeric() || b"_.-".contains(b))
            {
                return Err(at(BlockError::NotAWord, pos));
            }
            pos += close + 1;
        }
        Some([b'O' | b'o', d, ..]) if d.is_ascii_digit() => {
            block.kind = LineKind::Program;
            pos = program_number(bytes, pos + 1).ok_or(at(BlockError::NotAWord, pos))?;
        }
        _ => {}
    }
    while let Some(&c) = bytes.get(pos) {
        match c {
            b' ' | b'\t' => pos += 1,
            b';' => break,
            b'(' => {
                let close = bytes
                    .get(pos..)
                    .and_then(|rest| rest.iter().position(|&b| b == b')'))
                    .ok_or(at(BlockError::Comment, pos))?;
                pos += close + 1;
            }
            _ if block.kind != LineKind::Words => {
                // A tape mark or a program number stands alone.
                let error = if block.kind == LineKind::Program
                    && bytes.get(start + 1) == Some(&b'<')
                    && c.is_ascii_alphabetic()
                {
                    BlockError::HostLanguage
                } else if block.kind == LineKind::Program {
                    BlockError::ProgramNumber
                } else {
                    BlockError::NotAWord
                };
                return Err(at(error, pos));
            }
            _ if c.is_ascii_alphabetic() => {
                let letter = c.to_ascii_uppercase();
                let from = pos + 1;
                let mut end = from;
                while bytes
                    .get(end)
                    .is_some_and(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.'))
                {
                    end += 1;
                }
                let number = line.get(from..end).ok_or(at(BlockError::NotAWord, pos))?;
                if number.is_empty() {
                    return Err(at(BlockError::NotAWord, pos));
                }
                word(&mut block, &mut seen, letter, number, units).map_err(|e| at(e, pos))?;
                pos = end;
            }
            _ => return Err(at(BlockError::NotAWord, pos)),
        }
    }
    Ok(block)
}

/// The end of a program number's digits from `pos` (at least one).
fn program_number(bytes: &[u8], pos: usize) -> Option<usize> {
    let n = bytes
        .iter()
        .skip(pos)
        .take_while(|b| b.is_ascii_digit())
        .count();
    (n > 0).then_some(pos + n)
}

fn word(
    block: &mut Block,
    seen: &mut [bool; 26],
    letter: u8,
    number: &str,
    units: Units,
) -> Result<(), BlockError> {
    let length = || {
        match units {
            Units::Mm => Length::from_gcode_mm(number),
            Units::Inch => Length::from_gcode_inch(number),
        }
        .map_err(|e| BlockError::Value(letter, e))
    };
    if letter == b'G' {
        return g_word(block, number);
    }
    let slot = seen
        .get_mut(usize::from(letter - b'A'))
        .ok_or(BlockError::UnknownAddress(letter))?;
    if *slot {
        return Err(BlockError::Repeated(letter));
    }
    *slot = true;
    match letter {
        b'X' => block.x = Some(length()?),
        b'Z' => block.z = Some(length()?),
        b'I' => block.i = Some(length()?),
        b'K' => block.k = Some(length()?),
        b'R' => block.r = Some(length()?),
        b'N' => {
            Length::from_gcode_mm(number).map_err(|e| BlockError::Value(letter, e))?;
            block.n = number.parse().ok();
        }
        b'F' => block.f = Some(length()?),
        b'Y' => {
            // Only a written zero: `Y0`, `Y-0.000`.
            length()?;
            if number.bytes().any(|b| matches!(b, b'1'..=b'9')) {
                return Err(BlockError::NoYAxis);
            }
        }
        b'O' => return Err(BlockError::ProgramNumber),
        // Accepted and checked as numbers, not acted on.
        b'S' | b'T' | b'M' => {
            Length::from_gcode_mm(number).map_err(|e| BlockError::Value(letter, e))?;
        }
        _ => return Err(BlockError::UnknownAddress(letter)),
    }
    Ok(())
}

/// A G number as a code in tenths: `1`, `01`, `90.1`; `None` if it is no
/// G code (a sign, more than one decimal, more than 3 digits).
fn g_code(number: &str) -> Option<u16> {
    let (whole, tenth) = match number.split_once('.') {
        Some((w, t)) => (w, Some(t)),
        None => (number, None),
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(whole) || whole.len() > 3 || tenth.is_some_and(|t| t.len() != 1 || !digits(t)) {
        return None;
    }
    let value = |s: &str| s.bytes().fold(0u16, |n, b| n * 10 + u16::from(b - b'0'));
    Some(value(whole) * 10 + tenth.map_or(0, value))
}

fn g_word(block: &mut Block, number: &str) -> Result<(), BlockError> {
    let tenths = g_code(number).ok_or(BlockError::UnsupportedG(None))?;
    let unsupported = Err(BlockError::UnsupportedG(Some(tenths)));
    if tenths % 10 != 0 {
        return unsupported;
    }
    let code = tenths / 10;
    let repeated = Err(BlockError::Repeated(b'G'));
    match code {
        0..=3 => {
            if block.motion.is_some() {
                return repeated;
            }
            block.motion = Some(match code {
                0 => Motion::Rapid,
                1 => Motion::Linear,
                2 => Motion::ArcCw,
                _ => Motion::ArcCcw,
            });
        }
        40..=42 => {
            if block.compensation.is_some() {
                return repeated;
            }
            block.compensation = Some(match code {
                40 => Compensation::Off,
                41 => Compensation::Left,
                _ => Compensation::Right,
            });
        }
        90 | 91 => {
            if block.incremental.is_some() {
                return repeated;
            }
            block.incremental = Some(code == 91);
        }
        18 => {
            if block.plane_zx {
                return repeated;
            }
            block.plane_zx = true;
        }
        20 | 21 => {
            if block.units.is_some() {
                return repeated;
            }
            block.units = Some(if code == 20 { Units::Inch } else { Units::Mm });
        }
        450 | 451 => {
            if block.corner.is_some() {
                return repeated;
            }
            block.corner = Some(if code == 450 {
                Corner::Arc
            } else {
                Corner::Intersection
            });
        }
        _ => return unsupported,
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mm(s: &str) -> Option<Length> {
        Some(Length::from_mm_str(s).unwrap())
    }

    #[test]
    fn words_with_and_without_spaces() {
        let b = parse_block("N13 G02X17.2Z-17R2.6 (point 5) F0.1").unwrap();
        assert_eq!(b.motion, Some(Motion::ArcCw));
        assert_eq!((b.x, b.z, b.r), (mm("17.2"), mm("-17"), mm("2.6")));
        let b = parse_block("g91 g42 x+1.5").unwrap();
        assert_eq!(
            (b.incremental, b.compensation),
            (Some(true), Some(Compensation::Right))
        );
        assert_eq!(parse_block("").unwrap(), Block::default());
        let b = parse_block("N30 G450 G42").unwrap();
        assert_eq!((b.n, b.corner), (Some(30), Some(Corner::Arc)));
        assert_eq!(
            parse_block("G451").unwrap().corner,
            Some(Corner::Intersection)
        );
        assert_eq!(parse_block("N1.5").unwrap().n, None);
    }

    #[test]
    fn lines_as_cam_posts_and_machinists_write_them() {
        let b = parse_block("N10 G00 G18 G21 X30. Z2. Y0").unwrap();
        assert_eq!((b.x, b.z, b.n), (mm("30"), mm("2"), Some(10)));
        assert!(b.plane_zx);
        assert_eq!(b.units, Some(Units::Mm));
        let b = parse_block("x.5 z-.25 F+100").unwrap();
        assert_eq!((b.x, b.z, b.f), (mm("0.5"), mm("-0.25"), mm("100")));
        // Rounded once to the ångström, half away from zero.
        let b = parse_block("X1.00000005 Z-1.00000004999999").unwrap();
        assert_eq!(b.x.unwrap().as_angstrom(), 10_000_001);
        assert_eq!(b.z.unwrap().as_angstrom(), -10_000_000);
        for (line, kind) in [
            ("%", LineKind::TapeMark),
            ("  % (end)", LineKind::TapeMark),
            ("O1000 (SHAFT)", LineKind::Program),
            ("o<shaft_op10>", LineKind::Program),
            (":0042", LineKind::Program),
            ("(MSG, FACE THE PART)", LineKind::Words),
            ("; only a comment", LineKind::Words),
        ] {
            let b = parse_block(line).unwrap();
            assert_eq!(b.kind, kind, "{line}");
            assert_eq!((b.motion, b.x, b.z), (None, None, None), "{line}");
        }
        let b = parse_block("/N20 G01 X20.").unwrap();
        assert!(b.deleted);
        assert_eq!(b.x, mm("20"));
        assert!(
            !parse_block("N20 G01 X20. (a / in a comment)")
                .unwrap()
                .deleted
        );
        assert_eq!(parse_block("Y-0.000").unwrap(), Block::default());
    }

    #[test]
    fn refusals_say_where() {
        let at = |line: &str| {
            let e = parse_located(line).unwrap_err();
            (e.error, e.column)
        };
        assert_eq!(at("G00 X30. Y5 Z2."), (BlockError::NoYAxis, 10));
        assert_eq!(at("G17 G00 X1"), (BlockError::UnsupportedG(Some(170)), 1));
        assert_eq!(at("G20 X1 G21"), (BlockError::Repeated(b'G'), 8));
        assert_eq!(at("G18 G00 G18"), (BlockError::Repeated(b'G'), 9));
        assert_eq!(at("G90.1"), (BlockError::UnsupportedG(Some(901)), 1));
        assert_eq!(at("O1000 G00 X1"), (BlockError::ProgramNumber, 7));
        assert_eq!(at("G00 O1000"), (BlockError::ProgramNumber, 5));
        assert_eq!(at("o<sub> call"), (BlockError::HostLanguage, 8));
        assert_eq!(at("% G00"), (BlockError::NotAWord, 3));
        assert_eq!(at("O<bad name>"), (BlockError::NotAWord, 1));
        assert_eq!(at("X1 (open"), (BlockError::Comment, 4));
        assert_eq!(
            at("G01 X."),
            (BlockError::Value(b'X', LengthError::Malformed), 5)
        );
        assert_eq!(
            at("Z99999.99999995"),
            (BlockError::Value(b'Z', LengthError::OutOfRange), 1)
        );
    }

    #[test]
    fn refusals() {
        assert_eq!(parse_block("G01 X1 X2"), Err(BlockError::Repeated(b'X')));
        assert_eq!(parse_block("G01 G02"), Err(BlockError::Repeated(b'G')));
        assert_eq!(
            parse_block("G04 X1"),
            Err(BlockError::UnsupportedG(Some(40)))
        );
        assert_eq!(parse_block("G450 G451"), Err(BlockError::Repeated(b'G')));
        assert_eq!(parse_block("G1.5"), Err(BlockError::UnsupportedG(Some(15))));
        assert_eq!(parse_block("G-1"), Err(BlockError::UnsupportedG(None)));
        assert_eq!(parse_block("Q5"), Err(BlockError::UnknownAddress(b'Q')));
        assert_eq!(parse_block("G01 X"), Err(BlockError::NotAWord));
        assert_eq!(parse_block("G01 X1 $"), Err(BlockError::NotAWord));
        assert_eq!(parse_block("G01 (open"), Err(BlockError::Comment));
        assert!(matches!(
            parse_block("X1.1234567890123456"),
            Err(BlockError::Value(b'X', LengthError::TooManyGcodeDecimals))
        ));
        assert!(matches!(
            parse_block("Z--1"),
            Err(BlockError::Value(b'Z', _))
        ));
    }
}

//! G-code blocks: words parsed and checked, before any motion.
//!
//! A block is a line of address words: a letter followed by a number, with or
//! without spaces between words (`N10 G01 X27.532 Z0`, `G1X12.5`). Comments in
//! parentheses and everything after `;` are ignored. Each address may appear
//! once, except `G`, which may appear once per modal group.
//!
//! | address | meaning | value |
//! |---|---|---|
//! | `N` | sequence number | kept to name the block in refusals |
//! | `G` | 00 01 02 03 (motion), 40 41 42 (nose compensation), 90 91 (absolute, incremental), 450 451 (outside corners: transition arc, intersection) | whole number |
//! | `X` | X end point: a diameter when `DIAM=1` | length |
//! | `Z` | Z end point | length |
//! | `I`, `K` | arc centre minus start point, radius values | length |
//! | `R` | arc radius: positive for an arc of at most 180°, negative for more | length |
//! | `F` | feed along the path, mm/min (modal) | length |
//! | `S`, `T`, `M` | speed, tool, miscellaneous | accepted, not acted on |

use crate::length::{Length, LengthError};

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

/// One parsed block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Block {
    /// G00–G03 if given.
    pub motion: Option<Motion>,
    /// G40–G42 if given.
    pub compensation: Option<Compensation>,
    /// G90 (false) or G91 (true) if given.
    pub incremental: Option<bool>,
    /// G450 or G451 if given.
    pub corner: Option<Corner>,
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
    /// A G code this control does not run (`ERR VALUE`).
    UnsupportedG,
}

/// Whether a request line is a G-code block: its first word is an address
/// letter directly followed by a number.
///
/// ```
/// use core_nostd::gcode::is_block;
/// assert!(is_block("N10 G01 X12"));
/// assert!(is_block("x-1.5"));
/// assert!(!is_block("ZERO"));
/// assert!(!is_block("MOVE X=1"));
/// ```
pub fn is_block(line: &str) -> bool {
    let b = line.trim_start().as_bytes();
    matches!(b, [l, d, ..] if l.is_ascii_alphabetic() && (d.is_ascii_digit() || matches!(d, b'+' | b'-' | b'.')))
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
    let mut block = Block::default();
    let mut seen = [false; 26];
    let bytes = line.as_bytes();
    let mut pos = 0;
    while let Some(&c) = bytes.get(pos) {
        match c {
            b' ' | b'\t' => pos += 1,
            b';' => break,
            b'(' => {
                let close = bytes
                    .get(pos..)
                    .and_then(|rest| rest.iter().position(|&b| b == b')'))
                    .ok_or(BlockError::Comment)?;
                pos += close + 1;
            }
            _ if c.is_ascii_alphabetic() => {
                let letter = c.to_ascii_uppercase();
                let start = pos + 1;
                let mut end = start;
                while bytes
                    .get(end)
                    .is_some_and(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.'))
                {
                    end += 1;
                }
                let number = line.get(start..end).ok_or(BlockError::NotAWord)?;
                if number.is_empty() {
                    return Err(BlockError::NotAWord);
                }
                word(&mut block, &mut seen, letter, number)?;
                pos = end;
            }
            _ => return Err(BlockError::NotAWord),
        }
    }
    Ok(block)
}

fn word(
    block: &mut Block,
    seen: &mut [bool; 26],
    letter: u8,
    number: &str,
) -> Result<(), BlockError> {
    let length = || Length::from_mm_str(number).map_err(|e| BlockError::Value(letter, e));
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
            length()?;
            block.n = number.parse().ok();
        }
        b'F' => block.f = Some(length()?),
        // Accepted and checked as numbers, not acted on.
        b'S' | b'T' | b'M' => {
            length()?;
        }
        _ => return Err(BlockError::UnknownAddress(letter)),
    }
    Ok(())
}

fn g_word(block: &mut Block, number: &str) -> Result<(), BlockError> {
    if number.is_empty() || number.len() > 3 || !number.bytes().all(|b| b.is_ascii_digit()) {
        return Err(BlockError::UnsupportedG);
    }
    let code = number
        .bytes()
        .fold(0u16, |n, b| n * 10 + u16::from(b - b'0'));
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
        _ => return Err(BlockError::UnsupportedG),
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
    fn refusals() {
        assert_eq!(parse_block("G01 X1 X2"), Err(BlockError::Repeated(b'X')));
        assert_eq!(parse_block("G01 G02"), Err(BlockError::Repeated(b'G')));
        assert_eq!(parse_block("G04 X1"), Err(BlockError::UnsupportedG));
        assert_eq!(parse_block("G450 G451"), Err(BlockError::Repeated(b'G')));
        assert_eq!(parse_block("G1.5"), Err(BlockError::UnsupportedG));
        assert_eq!(parse_block("Q5"), Err(BlockError::UnknownAddress(b'Q')));
        assert_eq!(parse_block("G01 X"), Err(BlockError::NotAWord));
        assert_eq!(parse_block("G01 X1 $"), Err(BlockError::NotAWord));
        assert_eq!(parse_block("G01 (open"), Err(BlockError::Comment));
        assert!(matches!(
            parse_block("X1.1234567"),
            Err(BlockError::Value(b'X', _))
        ));
        assert!(matches!(
            parse_block("Z--1"),
            Err(BlockError::Value(b'Z', _))
        ));
    }
}

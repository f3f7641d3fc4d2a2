//! Punched tapes of the old controls: the АТПр-2М12's BCK-5 frames and the
//! ЭМ-907's ISO-7bit blocks, encoded and verified (Kosenko 1977, ch. III §2,
//! ch. IV §5, ch. VI; `docs/tapes.md` §2, §3).
//!
//! # BCK-5 (АТПр-2М12 with the «Салют-2М» control)
//! Five tracks: digits on tracks 1–4 (weights 1, 2, 4, 8), an address
//! letter is track 5 plus a digit, its *value* (Table 15, [`Bck5Letter`]):
//!
//! | Н | Е | Д | Т | К | П | Ш | С | В | Я |
//! |---|---|---|---|---|---|---|---|---|---|
//! | 0 | 1 | 2 | 3 | 4 | 5 | 6 | 7 | 8 | 9 |
//! | end of frame | carriage | cross slide | third axis | frame number | feed | spindle | tool | coolant | end of program |
//!
//! A frame ([`Bck5Frame`]), as the seed prints it one per line:
//!
//! `2К002Е212400Д630000П75Ш26Н` = check digit `2`, `К002` the frame number,
//! `Е212400` carriage, `Д630000` cross slide, `П75` feed, `Ш26` spindle,
//! `Н` end of frame.
//!
//! - **Check digit** (written before К): the sum of all digits and letter
//!   values of the frame, itself included, is a multiple of 10
//!   ([`Bck5Frame::expected_check`]). For the frame above the rest sums to
//!   58, so the check digit is 2.
//! - **Motion words** Е (the carriage, longitudinal, 0.01 mm impulses) and
//!   Д (the cross slide, 0.005 mm impulses), and Т (a third axis, read but
//!   not used on this lathe): a code digit, 1 plus, 2 minus, 4 added on the
//!   leading axis (the one with more impulses), then five impulse digits
//!   ([`MotionWord`]).
//! - **П feed** ([`Feed`]): `П75` rapid over 10 mm, `П54` up to 10 mm, else a
//!   code `ab` whose pulse frequency is `F_b·2^(a−3)` Hz (`F_1…F_4` = 43.4,
//!   50, 73, 122.5 Hz; `a` 0–7, `b` 1–4), the one nearest `n·S/0.6` Hz for
//!   `n` rpm and `S` mm/rev ([`FeedCode::nearest`]); `П00` none.
//! - **Ш spindle**: speed code (11, 12, 21, 22 within the gear range of
//!   Table 23) plus 04 clockwise (`Ш26`) or plus 40 counter-clockwise, `Ш00`
//!   stop. **С tool**: the tool block searched (`С01`, `С42`). **В
//!   coolant**: `В01` on, `В00` off. Each two digits, kept as printed.
//! - A frame ends with Н, the program's last frame with Я (`4К030Я`).
//! - **Tools** are delimited by С words: from a frame with a С word to the
//!   frame before the next one (or to Я). Every tool starts at and returns
//!   to its zero point, so on each axis the impulses of its frames close,
//!   `Σ+ + Σ− = 0` (Table 21). [`verify_bck5`] checks every check digit,
//!   the frame numbering and every tool's closure, and reports each failure.
//!
//! # ISO-7bit (16Б16Ф3 with the «Программатор ЭМ-907»)
//! ASCII on tracks 1–7, track 8 punched when that makes the number of holes
//! in the row even ([`iso7_parity`], [`iso7_row`]). The ЭМ-907 reads the 26
//! characters of [`EM907_CHARSET`]. A block ([`Iso7Block`], Table 31):
//! `N032 G03 X+600 Z-1190 I4397 K1190 F1420 S44` LF, words in the order
//! N G X Z I K F S T M; X the cross slide (0.005 mm impulses, on the
//! radius), Z the carriage (0.01 mm), both signed; I, K the arc centre's
//! distance from the start point along X and Z (or the thread pitch), in
//! impulses without sign; F the feed word `F = S·10³/l` ([`em907_feed_word`]),
//! `S = S₀·n` the contour feed in mm/min, `l = √(Δx² + Δz²)` the block's
//! length in mm for G01 and the arc's radius `R` for G02/G03.
//!
//! # Decisions where the seed is ambiguous
//! - Letters: Cyrillic capitals, and in ASCII ([`Alphabet::Latin`], for
//!   the line protocol) H→Н, E→Е, K→К, T→Т, C→С, B→В (look-alikes),
//!   D→Д and P→П (the seed's own spellings: its tape prints `D630000`, its
//!   frame 001 `P00`), W→Ш and R→Я (the faux-Cyrillic pairs; the seed prints
//!   Ш and Я only in Cyrillic). Either case. Whitespace is not on the tape
//!   and is skipped (the seed's table separates words by tabs); columns in
//!   errors count characters from 1, a tab as one.
//! - The frame number has one to three digits (the seed's last frame is
//!   `К32`); it is written with three.
//! - Words follow in the seed's order К Е Д Т П Ш С В; a word out of that
//!   order or repeated is an error.
//! - `П54` is the code `a = 5, b = 4` (490 Hz): the seed's "up to 10 mm"
//!   index is that feed code. A rapid move's length is its path length,
//!   `√(ΔЕ² + ΔД²)` in mm; exactly 10 mm is "up to 10 mm".
//! - The feed code follows `n·S/0.6` whichever axis leads (the seed's Table
//!   24: the same code moves the cross slide at half the feed).
//! - The leading axis is the one with more impulses, the carriage on a tie;
//!   the verifier does not check the flag (the seed's К010 lacks it).
//! - A С word starts a tool, С00 included; frames before the first С word,
//!   and after a Я, belong to no tool.
//! - The ЭМ-907's X-axis centre/pitch address is I (0x49, the holes the
//!   seed's table gives for its row "J"); [`Iso7Block::parse`] also reads
//!   the seed's spelling J, and I is written. `:` and `/` take N's place
//!   and are followed by the three digits of the number too. G is only
//!   written with X or Z, F in every G01–G03 block.
//!
//! # Seed slips (`docs/errata.md` §2)
//! - К000, К004, К007: check digits 0, 9, 8 printed; the frames as printed
//!   need 7, 8, 7. К004's 9 is in fact right for the frame meant: its
//!   `Д514800` (14 800 impulses, 74 mm) is `Д504800` (24 mm, Tables 21–22),
//!   and that one extra 1 also leaves tool 01 open on Д (Σ+ 40 368).
//! - К011: Е119550, the geometry (Table 21: 246 − 40.5 = 205.5 mm) gives
//!   Е120550; tool 01 does not close on Е. К021: Е218600, Table 21 gives
//!   251 − 80 = 171 mm, Е217100; tool 02 does not close on Е.
//! - К010 `Д100564` lacks the leading-axis 4 (`Д500564`, check digit 8).
//! - К015 `П54` for an 11.05 mm move (over 10 mm: `П75`, check digit 0).
//! - К021/К023 `Д624204`/`Д500604` close but are 28.98 mm where Table 21
//!   has 28.97 mm (24206, 606).
//! - Frame 001 in the text (`…П00Ш000IВ00Н`) drops the letter С of `С01`.
//! - Tables 21–22 carry К011's 19550 and К021's 18600 too (Table 22); Table
//!   21 prints Δy −20 for −90 mm (18000 impulses), y₁₃ −20.95 for 20.95,
//!   «Σ −20206» for 24206, and some signs of its Δ columns wrong; Table 20
//!   has 119.78, 90.26 and 70.5 where Table 21 (which the tape follows) has
//!   119.79, 90.3 and 60.5.
//! - ISO table: "5" and "6" printed with odd holes (0x37 without track 8),
//!   the row "J" is I, the row "." is `:`, the first row "K" is N.
//! - Table 31: N017 `F 80,50`, but `0.3·710·10³/26.5` = 8038 and the block's
//!   length is `√(2.5² + 26²)` = 26.12 mm, F = 8155; N002 `F 160` and N033
//!   `F 180` are 1159 and 1179 (1160, 1180 to three figures); the text
//!   calls N032 G02, the table G03 (G03 fits the geometry).

use core::fmt;

use crate::impulse::{quantize, ImpulsePrice};
use crate::length::Length;

// ───────────────────────────── errors ─────────────────────────────

/// What is wrong with a tape line or with a request to encode one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TapeError {
    /// A character the code does not have.
    UnknownCharacter,
    /// A BCK-5 frame that does not start with its check digit.
    MissingCheckDigit,
    /// No К after the check digit (BCK-5), no N, `:` or `/` (ISO).
    MissingNumber,
    /// A word with the wrong number of digits, or a sign where none belongs.
    WordLength,
    /// A word out of the format's order, or repeated.
    WordOrder,
    /// A motion word's code digit is not 0, 1, 2, 5 or 6, or is 0 with
    /// impulses.
    MotionCode,
    /// A П word that is not 00, 75 or a code `ab` with `a` 0–7, `b` 1–4.
    FeedCode,
    /// A BCK-5 frame that does not end with Н or Я.
    MissingEnd,
    /// Something after the frame's Н or Я.
    AfterEnd,
    /// A word the block needs is missing (X or Z with G, F with G01–G03).
    MissingWord,
    /// A value beyond its word's range (digits, impulses, frame number).
    WordRange,
    /// An ISO-7bit row with an odd number of holes.
    Parity,
    /// A feed, spindle speed or length that is not a positive finite number.
    NotPositive,
    /// A block that moves no axis.
    NoMotion,
    /// The writer refused the text.
    Write,
}

impl TapeError {
    /// A short, fixed description naming what is wrong (ASCII).
    ///
    /// ```
    /// use core_nostd::calc::tape::TapeError;
    /// assert_eq!(TapeError::WordLength.as_str(), "word: wrong number of digits");
    /// ```
    pub const fn as_str(self) -> &'static str {
        match self {
            TapeError::UnknownCharacter => "a character the code does not have",
            TapeError::MissingCheckDigit => "check digit: the frame does not start with a digit",
            TapeError::MissingNumber => "number: no K (BCK-5) or N, : or / (ISO) at the start",
            TapeError::WordLength => "word: wrong number of digits",
            TapeError::WordOrder => "word: out of order or repeated",
            TapeError::MotionCode => "motion word: code digit not 0, 1, 2, 5 or 6",
            TapeError::FeedCode => "feed word: not P00, P75 or ab with a 0-7, b 1-4",
            TapeError::MissingEnd => "frame end: no H (end of frame) or R (end of program)",
            TapeError::AfterEnd => "text after the end of the frame",
            TapeError::MissingWord => "word: missing (X or Z with G, F with G01-G03)",
            TapeError::WordRange => "word: value beyond its range",
            TapeError::Parity => "row: odd number of holes",
            TapeError::NotPositive => "feed, speed or length: not a positive number",
            TapeError::NoMotion => "block: moves no axis",
            TapeError::Write => "output: the writer refused the text",
        }
    }
}

impl fmt::Display for TapeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A tape line that could not be read: what and where.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParseError {
    /// What is wrong.
    pub error: TapeError,
    /// The character column where (from 1; a tab counts one, a Cyrillic
    /// letter one). One past the last character when something is missing
    /// at the end.
    pub column: u32,
}

impl ParseError {
    const fn at(error: TapeError, column: u32) -> ParseError {
        ParseError { error, column }
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "column {}: {}", self.column, self.error)
    }
}

// ───────────────────────────── reading ─────────────────────────────

/// Characters of a line with their columns, whitespace skipped.
struct Cursor<'a> {
    rest: core::str::Chars<'a>,
    /// Column of the last character taken (0 before the first).
    column: u32,
}

/// A run of decimal digits.
struct Digits {
    count: u32,
    /// The value, saturated at `u32::MAX`; meaningful while `count ≤ 9`.
    value: u32,
    /// Sum of the digits (saturating).
    sum: u32,
}

impl<'a> Cursor<'a> {
    fn new(line: &'a str) -> Self {
        Cursor {
            rest: line.chars(),
            column: 0,
        }
    }

    fn skip_space(&mut self) {
        loop {
            let mut probe = self.rest.clone();
            match probe.next() {
                Some(c) if c.is_whitespace() => {
                    self.rest = probe;
                    self.column = self.column.saturating_add(1);
                }
                _ => return,
            }
        }
    }

    fn peek(&mut self) -> Option<char> {
        self.skip_space();
        self.rest.clone().next()
    }

    fn bump(&mut self) -> Option<(u32, char)> {
        self.skip_space();
        let c = self.rest.next()?;
        self.column = self.column.saturating_add(1);
        Some((self.column, c))
    }

    /// The column one past the last character taken.
    fn end(&self) -> u32 {
        self.column.saturating_add(1)
    }

    fn digits(&mut self) -> Digits {
        let mut d = Digits {
            count: 0,
            value: 0,
            sum: 0,
        };
        while let Some(v) = self.peek().and_then(|c| c.to_digit(10)) {
            self.bump();
            d.count = d.count.saturating_add(1);
            d.value = d.value.saturating_mul(10).saturating_add(v);
            d.sum = d.sum.saturating_add(v);
        }
        d
    }
}

/// The sum of the decimal digits of `n`.
const fn digit_sum(mut n: u32) -> u32 {
    let mut s = 0;
    while n > 0 {
        s += n % 10;
        n /= 10;
    }
    s
}

// ───────────────────────────── BCK-5 ─────────────────────────────

/// How BCK-5 letters are written as text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Alphabet {
    /// The seed's Cyrillic letters: Н Е Д Т К П Ш С В Я.
    Cyrillic,
    /// ASCII for the line protocol: H E D T K P W C B R.
    Latin,
}

/// An address letter of the BCK-5 code (Kosenko Table 15).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Bck5Letter {
    /// Н (0): end of frame.
    EndOfFrame,
    /// Е (1): carriage motion (longitudinal, 0.01 mm impulses).
    Carriage,
    /// Д (2): cross-slide motion (0.005 mm impulses).
    Cross,
    /// Т (3): third-axis motion (not used on the АТПр-2М12).
    Third,
    /// К (4): frame number.
    Number,
    /// П (5): feed code.
    Feed,
    /// Ш (6): spindle speed and direction code.
    Spindle,
    /// С (7): tool change (the tool block searched).
    Tool,
    /// В (8): coolant.
    Coolant,
    /// Я (9): end of program.
    EndOfProgram,
}

impl Bck5Letter {
    /// The letter's digit value, which counts in the check sum.
    ///
    /// ```
    /// use core_nostd::calc::tape::Bck5Letter;
    /// assert_eq!(Bck5Letter::Number.value(), 4);
    /// assert_eq!(Bck5Letter::EndOfProgram.value(), 9);
    /// ```
    pub const fn value(self) -> u8 {
        match self {
            Bck5Letter::EndOfFrame => 0,
            Bck5Letter::Carriage => 1,
            Bck5Letter::Cross => 2,
            Bck5Letter::Third => 3,
            Bck5Letter::Number => 4,
            Bck5Letter::Feed => 5,
            Bck5Letter::Spindle => 6,
            Bck5Letter::Tool => 7,
            Bck5Letter::Coolant => 8,
            Bck5Letter::EndOfProgram => 9,
        }
    }

    /// The letter read from a character: the Cyrillic letter or its ASCII
    /// spelling (module docs), either case.
    ///
    /// ```
    /// use core_nostd::calc::tape::Bck5Letter;
    /// assert_eq!(Bck5Letter::from_char('Д'), Some(Bck5Letter::Cross));
    /// assert_eq!(Bck5Letter::from_char('D'), Some(Bck5Letter::Cross));
    /// assert_eq!(Bck5Letter::from_char('w'), Some(Bck5Letter::Spindle));
    /// assert_eq!(Bck5Letter::from_char('Ж'), None);
    /// ```
    pub const fn from_char(c: char) -> Option<Bck5Letter> {
        match c {
            'Н' | 'н' | 'H' | 'h' => Some(Bck5Letter::EndOfFrame),
            'Е' | 'е' | 'E' | 'e' => Some(Bck5Letter::Carriage),
            'Д' | 'д' | 'D' | 'd' => Some(Bck5Letter::Cross),
            'Т' | 'т' | 'T' | 't' => Some(Bck5Letter::Third),
            'К' | 'к' | 'K' | 'k' => Some(Bck5Letter::Number),
            'П' | 'п' | 'P' | 'p' => Some(Bck5Letter::Feed),
            'Ш' | 'ш' | 'W' | 'w' => Some(Bck5Letter::Spindle),
            'С' | 'с' | 'C' | 'c' => Some(Bck5Letter::Tool),
            'В' | 'в' | 'B' | 'b' => Some(Bck5Letter::Coolant),
            'Я' | 'я' | 'R' | 'r' => Some(Bck5Letter::EndOfProgram),
            _ => None,
        }
    }

    /// The letter as written in an alphabet.
    ///
    /// ```
    /// use core_nostd::calc::tape::{Alphabet, Bck5Letter};
    /// assert_eq!(Bck5Letter::Spindle.to_char(Alphabet::Cyrillic), 'Ш');
    /// assert_eq!(Bck5Letter::Spindle.to_char(Alphabet::Latin), 'W');
    /// ```
    pub const fn to_char(self, alphabet: Alphabet) -> char {
        match alphabet {
            Alphabet::Cyrillic => match self {
                Bck5Letter::EndOfFrame => 'Н',
                Bck5Letter::Carriage => 'Е',
                Bck5Letter::Cross => 'Д',
                Bck5Letter::Third => 'Т',
                Bck5Letter::Number => 'К',
                Bck5Letter::Feed => 'П',
                Bck5Letter::Spindle => 'Ш',
                Bck5Letter::Tool => 'С',
                Bck5Letter::Coolant => 'В',
                Bck5Letter::EndOfProgram => 'Я',
            },
            Alphabet::Latin => match self {
                Bck5Letter::EndOfFrame => 'H',
                Bck5Letter::Carriage => 'E',
                Bck5Letter::Cross => 'D',
                Bck5Letter::Third => 'T',
                Bck5Letter::Number => 'K',
                Bck5Letter::Feed => 'P',
                Bck5Letter::Spindle => 'W',
                Bck5Letter::Tool => 'C',
                Bck5Letter::Coolant => 'B',
                Bck5Letter::EndOfProgram => 'R',
            },
        }
    }

    /// Position in the seed's word order after К (0 for К and the ends).
    const fn rank(self) -> u8 {
        match self {
            Bck5Letter::Carriage => 1,
            Bck5Letter::Cross => 2,
            Bck5Letter::Third => 3,
            Bck5Letter::Feed => 4,
            Bck5Letter::Spindle => 5,
            Bck5Letter::Tool => 6,
            Bck5Letter::Coolant => 7,
            Bck5Letter::Number | Bck5Letter::EndOfFrame | Bck5Letter::EndOfProgram => 0,
        }
    }
}

/// The largest impulse count of a BCK-5 motion word (five digits).
pub const BCK5_MAX_IMPULSES: u32 = 99_999;

/// The largest BCK-5 frame number (three digits).
pub const BCK5_MAX_FRAME: u16 = 999;

/// A BCK-5 motion word (Е, Д or Т): direction, leading flag and impulses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MotionWord {
    /// 0 (no motion), 1, 2, 5 or 6.
    code: u8,
    /// At most [`BCK5_MAX_IMPULSES`]; 0 when `code` is 0.
    count: u32,
}

impl MotionWord {
    /// No motion: the word `000000`.
    pub const NONE: MotionWord = MotionWord { code: 0, count: 0 };

    /// A motion of `impulses` (signed, plus away from the chuck face and
    /// the spindle axis), marked leading or not; `None` beyond
    /// [`BCK5_MAX_IMPULSES`]. Zero impulses give [`MotionWord::NONE`].
    ///
    /// ```
    /// use core_nostd::calc::tape::MotionWord;
    /// let m = MotionWord::new(-30_000, true).unwrap();
    /// assert_eq!((m.code(), m.count()), (6, 30_000)); // 2 minus + 4 leading
    /// assert_eq!(MotionWord::new(121, false).unwrap().code(), 1);
    /// assert_eq!(MotionWord::new(0, true), Some(MotionWord::NONE));
    /// assert_eq!(MotionWord::new(100_000, false), None);
    /// ```
    pub const fn new(impulses: i32, leading: bool) -> Option<MotionWord> {
        let count = impulses.unsigned_abs();
        if count > BCK5_MAX_IMPULSES {
            return None;
        }
        if count == 0 {
            return Some(MotionWord::NONE);
        }
        let direction = if impulses > 0 { 1 } else { 2 };
        let code = if leading { direction + 4 } else { direction };
        Some(MotionWord { code, count })
    }

    /// The word's six digits read as a number (code digit first); `None`
    /// for a code digit not 0, 1, 2, 5, 6 or a code 0 with impulses.
    const fn from_word(word: u32) -> Option<MotionWord> {
        let code = word / 100_000;
        let count = word % 100_000;
        match code {
            0 if count == 0 => Some(MotionWord::NONE),
            1 | 2 | 5 | 6 => Some(MotionWord {
                code: code as u8,
                count,
            }),
            _ => None,
        }
    }

    /// The code digit: 0 none, 1 plus, 2 minus, +4 on the leading axis.
    pub const fn code(self) -> u8 {
        self.code
    }

    /// The number of impulses, without sign.
    pub const fn count(self) -> u32 {
        self.count
    }

    /// The signed number of impulses (plus for codes 1 and 5).
    ///
    /// ```
    /// use core_nostd::calc::tape::MotionWord;
    /// assert_eq!(MotionWord::new(-221, true).unwrap().impulses(), -221);
    /// ```
    pub const fn impulses(self) -> i32 {
        // count ≤ 99 999, so the conversion is exact.
        let n = self.count as i32;
        match self.code {
            2 | 6 => -n,
            _ => n,
        }
    }

    /// Whether the word marks its axis as leading.
    pub const fn is_leading(self) -> bool {
        self.code >= 4
    }

    /// The sum of the word's digits.
    const fn digit_sum(self) -> u32 {
        self.code as u32 + digit_sum(self.count)
    }
}

/// The base frequencies `F_1…F_4` of the feed codes, Hz (`b` = 1…4).
const fn feed_base_hz(b: u8) -> f64 {
    match b {
        1 => 43.4,
        2 => 50.0,
        3 => 73.0,
        _ => 122.5,
    }
}

/// A BCK-5 feed code `ab`: pulse frequency `F_b·2^(a−3)` Hz, `a` 0–7,
/// `b` 1–4.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FeedCode {
    a: u8,
    b: u8,
}

impl FeedCode {
    /// `П54`, the seed's index for a rapid move up to 10 mm (490 Hz).
    pub const APPROACH: FeedCode = FeedCode { a: 5, b: 4 };

    /// The code `ab`, if `a` is 0–7 and `b` 1–4.
    ///
    /// ```
    /// use core_nostd::calc::tape::FeedCode;
    /// assert_eq!(FeedCode::new(4, 4).unwrap().value(), 44);
    /// assert_eq!(FeedCode::new(8, 1), None);
    /// assert_eq!(FeedCode::new(7, 5), None); // П75 is the rapid index
    /// ```
    pub const fn new(a: u8, b: u8) -> Option<FeedCode> {
        if a <= 7 && b >= 1 && b <= 4 {
            Some(FeedCode { a, b })
        } else {
            None
        }
    }

    /// The code's two digits as a number, `10·a + b`.
    pub const fn value(self) -> u8 {
        self.a * 10 + self.b
    }

    /// The pulse frequency `F_b·2^(a−3)`, Hz.
    ///
    /// ```
    /// use core_nostd::calc::tape::FeedCode;
    /// assert_eq!(FeedCode::new(3, 1).unwrap().frequency_hz(), 43.4);
    /// assert_eq!(FeedCode::new(4, 4).unwrap().frequency_hz(), 245.0);
    /// assert_eq!(FeedCode::APPROACH.frequency_hz(), 490.0);
    /// ```
    pub fn frequency_hz(self) -> f64 {
        // a ≤ 7: 2^a ≤ 128, exact.
        feed_base_hz(self.b) * f64::from(1u32 << self.a) / 8.0
    }

    /// The code whose frequency is nearest `n·S/0.6` Hz, the impulse rate
    /// at which the carriage (0.01 mm) feeds `S` mm/rev at `n` rpm. On a
    /// tie of distances the lower code.
    ///
    /// ```
    /// use core_nostd::calc::tape::{FeedCode, FeedPerRev};
    /// // The seed's frames: 550 rpm at 0.25, 0.1 and 0.05 mm/rev.
    /// let at = |s| FeedCode::nearest(FeedPerRev { n_rpm: 550.0, s_mm_per_rev: s });
    /// assert_eq!(at(0.25).unwrap().value(), 44);
    /// assert_eq!(at(0.1).unwrap().value(), 41);
    /// assert_eq!(at(0.05).unwrap().value(), 31);
    /// ```
    ///
    /// # Errors
    /// [`TapeError::NotPositive`] for a speed or feed not finite and > 0.
    pub fn nearest(feed: FeedPerRev) -> Result<FeedCode, TapeError> {
        let target = feed.mm_per_min()? / 0.6;
        let mut best = FeedCode { a: 0, b: 1 };
        let mut best_distance = f64::INFINITY;
        let mut a = 0;
        while a <= 7 {
            let mut b = 1;
            while b <= 4 {
                let code = FeedCode { a, b };
                let distance = (code.frequency_hz() - target).abs();
                if distance < best_distance {
                    best = code;
                    best_distance = distance;
                }
                b += 1;
            }
            a += 1;
        }
        Ok(best)
    }
}

/// A feed per revolution at a spindle speed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FeedPerRev {
    /// Spindle speed `n`, rpm.
    pub n_rpm: f64,
    /// Feed `S₀`, mm per revolution.
    pub s_mm_per_rev: f64,
}

impl FeedPerRev {
    /// The feed per minute `S = S₀·n`, mm/min.
    ///
    /// ```
    /// use core_nostd::calc::tape::FeedPerRev;
    /// let f = FeedPerRev { n_rpm: 710.0, s_mm_per_rev: 0.05 };
    /// assert!((f.mm_per_min().unwrap() - 35.5).abs() < 1e-12);
    /// ```
    ///
    /// # Errors
    /// [`TapeError::NotPositive`] for a speed or feed not finite and > 0.
    pub fn mm_per_min(self) -> Result<f64, TapeError> {
        let s = self.n_rpm * self.s_mm_per_rev;
        if self.n_rpm > 0.0 && self.s_mm_per_rev > 0.0 && s.is_finite() {
            Ok(s)
        } else {
            Err(TapeError::NotPositive)
        }
    }
}

/// A П word.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Feed {
    /// `П00`: no feed (tool-change frames).
    Off,
    /// `П75`: rapid, over 10 mm.
    Rapid,
    /// A feed code, `П54` ([`FeedCode::APPROACH`]) included.
    Code(FeedCode),
}

impl Feed {
    /// The П word of two digits `00`–`99`, if the code has it.
    ///
    /// ```
    /// use core_nostd::calc::tape::{Feed, FeedCode};
    /// assert_eq!(Feed::from_code(75), Some(Feed::Rapid));
    /// assert_eq!(Feed::from_code(54), Some(Feed::Code(FeedCode::APPROACH)));
    /// assert_eq!(Feed::from_code(0), Some(Feed::Off));
    /// assert_eq!(Feed::from_code(45), None);
    /// ```
    pub const fn from_code(code: u8) -> Option<Feed> {
        match code {
            0 => Some(Feed::Off),
            75 => Some(Feed::Rapid),
            _ => match FeedCode::new(code / 10, code % 10) {
                Some(c) => Some(Feed::Code(c)),
                None => None,
            },
        }
    }

    /// The word's two digits as a number.
    pub const fn code(self) -> u8 {
        match self {
            Feed::Off => 0,
            Feed::Rapid => 75,
            Feed::Code(c) => c.value(),
        }
    }
}

/// How a BCK-5 frame ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameEnd {
    /// Н: end of frame.
    Frame,
    /// Я: end of program.
    Program,
}

/// One BCK-5 frame, as read from a line or made by [`Bck5Encoder`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bck5Frame {
    check: u8,
    number: u16,
    carriage: Option<MotionWord>,
    cross: Option<MotionWord>,
    third: Option<MotionWord>,
    feed: Option<Feed>,
    spindle: Option<u8>,
    tool: Option<u8>,
    coolant: Option<u8>,
    end: FrameEnd,
}

impl Bck5Frame {
    /// Reads one frame from a line: check digit, К and number, the words in
    /// the order Е Д Т П Ш С В, then Н or Я. Whitespace is skipped. The
    /// check digit is read, not judged: see [`Bck5Frame::check_ok`].
    ///
    /// ```
    /// use core_nostd::calc::tape::{Bck5Frame, TapeError};
    /// let f = Bck5Frame::parse("2K002E212400D630000П75Ш26Н").unwrap();
    /// assert_eq!(f.number(), 2);
    /// assert_eq!(f.carriage().unwrap().impulses(), -12_400);
    /// assert_eq!(f.cross().unwrap().impulses(), -30_000);
    /// assert!(f.cross().unwrap().is_leading());
    /// assert_eq!(f.spindle(), Some(26));
    /// assert!(f.check_ok());
    /// let e = Bck5Frame::parse("2K002E21240D630000Н").unwrap_err();
    /// assert_eq!((e.error, e.column), (TapeError::WordLength, 6));
    /// ```
    ///
    /// # Errors
    /// A [`ParseError`] naming the first thing wrong and its column.
    pub fn parse(line: &str) -> Result<Bck5Frame, ParseError> {
        let mut cur = Cursor::new(line);
        let check = match cur.bump() {
            Some((_, c)) if c.is_ascii_digit() => c as u8 - b'0',
            Some((column, c)) => {
                return Err(ParseError::at(
                    bck5_misplaced(c, TapeError::MissingCheckDigit),
                    column,
                ))
            }
            None => return Err(ParseError::at(TapeError::MissingCheckDigit, cur.end())),
        };
        let number_column = match cur.bump() {
            Some((column, c)) if matches!(Bck5Letter::from_char(c), Some(Bck5Letter::Number)) => {
                column
            }
            Some((column, c)) => {
                return Err(ParseError::at(
                    bck5_misplaced(c, TapeError::MissingNumber),
                    column,
                ))
            }
            None => return Err(ParseError::at(TapeError::MissingNumber, cur.end())),
        };
        let digits = cur.digits();
        if digits.count == 0 || digits.count > 3 {
            return Err(short_word(&mut cur, number_column, bck5_known));
        }
        let mut frame = Bck5Frame {
            check,
            // At most three digits: ≤ 999.
            number: digits.value as u16,
            carriage: None,
            cross: None,
            third: None,
            feed: None,
            spindle: None,
            tool: None,
            coolant: None,
            end: FrameEnd::Frame,
        };
        let mut rank = 0;
        loop {
            let Some((column, c)) = cur.bump() else {
                return Err(ParseError::at(TapeError::MissingEnd, cur.end()));
            };
            let Some(letter) = Bck5Letter::from_char(c) else {
                return Err(ParseError::at(
                    bck5_misplaced(c, TapeError::WordLength),
                    column,
                ));
            };
            let end = match letter {
                Bck5Letter::EndOfFrame => Some(FrameEnd::Frame),
                Bck5Letter::EndOfProgram => Some(FrameEnd::Program),
                _ => None,
            };
            if let Some(end) = end {
                frame.end = end;
                return match cur.bump() {
                    None => Ok(frame),
                    Some((column, c)) => Err(ParseError::at(
                        bck5_misplaced(c, TapeError::AfterEnd),
                        column,
                    )),
                };
            }
            if letter.rank() <= rank {
                return Err(ParseError::at(TapeError::WordOrder, column));
            }
            rank = letter.rank();
            let digits = cur.digits();
            let motion = matches!(
                letter,
                Bck5Letter::Carriage | Bck5Letter::Cross | Bck5Letter::Third
            );
            if digits.count != if motion { 6 } else { 2 } {
                return Err(short_word(&mut cur, column, bck5_known));
            }
            if motion {
                let m = MotionWord::from_word(digits.value)
                    .ok_or(ParseError::at(TapeError::MotionCode, column))?;
                match letter {
                    Bck5Letter::Carriage => frame.carriage = Some(m),
                    Bck5Letter::Cross => frame.cross = Some(m),
                    _ => frame.third = Some(m),
                }
                continue;
            }
            // Two digits: ≤ 99.
            let code = digits.value as u8;
            match letter {
                Bck5Letter::Feed => {
                    frame.feed = Some(
                        Feed::from_code(code).ok_or(ParseError::at(TapeError::FeedCode, column))?,
                    );
                }
                Bck5Letter::Spindle => frame.spindle = Some(code),
                Bck5Letter::Tool => frame.tool = Some(code),
                _ => frame.coolant = Some(code),
            }
        }
    }

    /// The check digit as written.
    pub const fn check(&self) -> u8 {
        self.check
    }

    /// The frame number (the digits after К).
    pub const fn number(&self) -> u16 {
        self.number
    }

    /// The Е word: carriage motion, 0.01 mm impulses.
    pub const fn carriage(&self) -> Option<MotionWord> {
        self.carriage
    }

    /// The Д word: cross-slide motion, 0.005 mm impulses.
    pub const fn cross(&self) -> Option<MotionWord> {
        self.cross
    }

    /// The Т word: third-axis motion.
    pub const fn third(&self) -> Option<MotionWord> {
        self.third
    }

    /// The П word.
    pub const fn feed(&self) -> Option<Feed> {
        self.feed
    }

    /// The Ш word: spindle speed code plus direction (04 clockwise, 40
    /// counter-clockwise), 00 stop.
    pub const fn spindle(&self) -> Option<u8> {
        self.spindle
    }

    /// The С word: the tool block searched.
    pub const fn tool(&self) -> Option<u8> {
        self.tool
    }

    /// The В word: coolant, 01 on, 00 off.
    pub const fn coolant(&self) -> Option<u8> {
        self.coolant
    }

    /// Н or Я.
    pub const fn end(&self) -> FrameEnd {
        self.end
    }

    /// The sum of every digit and letter value of the frame but its check
    /// digit (the seed's example: 58).
    ///
    /// ```
    /// use core_nostd::calc::tape::Bck5Frame;
    /// let f = Bck5Frame::parse("2K002E212400D630000П75Ш26Н").unwrap();
    /// assert_eq!(f.digit_sum(), 58);
    /// ```
    pub const fn digit_sum(&self) -> u32 {
        let mut s = Bck5Letter::Number.value() as u32 + digit_sum(self.number as u32);
        if let Some(m) = self.carriage {
            s += Bck5Letter::Carriage.value() as u32 + m.digit_sum();
        }
        if let Some(m) = self.cross {
            s += Bck5Letter::Cross.value() as u32 + m.digit_sum();
        }
        if let Some(m) = self.third {
            s += Bck5Letter::Third.value() as u32 + m.digit_sum();
        }
        if let Some(f) = self.feed {
            s += Bck5Letter::Feed.value() as u32 + digit_sum(f.code() as u32);
        }
        if let Some(c) = self.spindle {
            s += Bck5Letter::Spindle.value() as u32 + digit_sum(c as u32);
        }
        if let Some(c) = self.tool {
            s += Bck5Letter::Tool.value() as u32 + digit_sum(c as u32);
        }
        if let Some(c) = self.coolant {
            s += Bck5Letter::Coolant.value() as u32 + digit_sum(c as u32);
        }
        s + match self.end {
            FrameEnd::Frame => Bck5Letter::EndOfFrame.value() as u32,
            FrameEnd::Program => Bck5Letter::EndOfProgram.value() as u32,
        }
    }

    /// The check digit the frame needs: it makes the sum of all digits and
    /// letter values a multiple of 10.
    ///
    /// ```
    /// use core_nostd::calc::tape::Bck5Frame;
    /// // The seed's К004 is printed with 9; its sum needs 8.
    /// let f = Bck5Frame::parse("9K004E000000D514800П44H").unwrap();
    /// assert_eq!((f.check(), f.expected_check()), (9, 8));
    /// assert!(!f.check_ok());
    /// ```
    pub const fn expected_check(&self) -> u8 {
        ((10 - self.digit_sum() % 10) % 10) as u8
    }

    /// Whether the written check digit is the one the frame needs.
    pub const fn check_ok(&self) -> bool {
        self.check == self.expected_check()
    }

    /// Writes the frame in one of the alphabets, without whitespace and
    /// without a line end; [`fmt::Display`] writes it in Cyrillic.
    ///
    /// ```
    /// use core_nostd::calc::tape::{Alphabet, Bck5Frame};
    /// let f = Bck5Frame::parse("2К002Е212400Д630000П75Ш26Н").unwrap();
    /// let mut s = heapless::String::<64>::new();
    /// f.write(&mut s, Alphabet::Latin).unwrap();
    /// assert_eq!(s, "2K002E212400D630000P75W26H");
    /// ```
    ///
    /// # Errors
    /// The writer's error.
    pub fn write<W: fmt::Write + ?Sized>(&self, w: &mut W, alphabet: Alphabet) -> fmt::Result {
        let letter = |l: Bck5Letter| l.to_char(alphabet);
        write!(
            w,
            "{}{}{:03}",
            self.check,
            letter(Bck5Letter::Number),
            self.number
        )?;
        let motions = [
            (Bck5Letter::Carriage, self.carriage),
            (Bck5Letter::Cross, self.cross),
            (Bck5Letter::Third, self.third),
        ];
        for (l, m) in motions {
            if let Some(m) = m {
                write!(w, "{}{}{:05}", letter(l), m.code, m.count)?;
            }
        }
        let codes = [
            (Bck5Letter::Feed, self.feed.map(Feed::code)),
            (Bck5Letter::Spindle, self.spindle),
            (Bck5Letter::Tool, self.tool),
            (Bck5Letter::Coolant, self.coolant),
        ];
        for (l, c) in codes {
            if let Some(c) = c {
                write!(w, "{}{:02}", letter(l), c)?;
            }
        }
        w.write_char(letter(match self.end {
            FrameEnd::Frame => Bck5Letter::EndOfFrame,
            FrameEnd::Program => Bck5Letter::EndOfProgram,
        }))
    }
}

impl fmt::Display for Bck5Frame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write(f, Alphabet::Cyrillic)
    }
}

/// The error for a character `c` found where something else was expected:
/// [`TapeError::UnknownCharacter`] if the code has no such character.
fn bck5_misplaced(c: char, otherwise: TapeError) -> TapeError {
    if bck5_known(c) {
        otherwise
    } else {
        TapeError::UnknownCharacter
    }
}

/// A word of the wrong length at `column`, or the character the code does
/// not have (`known` false) that cut it short.
fn short_word(cur: &mut Cursor<'_>, column: u32, known: fn(char) -> bool) -> ParseError {
    match cur.peek() {
        // After `peek`, the cursor stands just before that character.
        Some(c) if !known(c) => ParseError::at(TapeError::UnknownCharacter, cur.end()),
        _ => ParseError::at(TapeError::WordLength, column),
    }
}

/// Whether the BCK-5 code has a character.
fn bck5_known(c: char) -> bool {
    c.is_ascii_digit() || Bck5Letter::from_char(c).is_some()
}

/// A BCK-5 motion axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Bck5Axis {
    /// Е, the carriage.
    Carriage,
    /// Д, the cross slide.
    Cross,
    /// Т, the third axis.
    Third,
}

impl Bck5Axis {
    /// The axis' letter.
    pub const fn letter(self) -> Bck5Letter {
        match self {
            Bck5Axis::Carriage => Bck5Letter::Carriage,
            Bck5Axis::Cross => Bck5Letter::Cross,
            Bck5Axis::Third => Bck5Letter::Third,
        }
    }
}

/// One failure found on a BCK-5 tape. [`fmt::Display`] writes it in ASCII.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Bck5Finding {
    /// A line that is not a frame.
    Unreadable {
        /// Line number (from 1, blank lines counted).
        line: u32,
        /// What and where.
        error: ParseError,
    },
    /// A frame whose check digit does not make its sum a multiple of 10.
    CheckDigit {
        /// Line number.
        line: u32,
        /// The frame number.
        frame: u16,
        /// The check digit written.
        found: u8,
        /// The check digit the frame needs.
        expected: u8,
    },
    /// A frame not numbered one after the frame before it.
    Numbering {
        /// Line number.
        line: u32,
        /// The frame number written.
        frame: u16,
        /// The number that follows the frame before.
        expected: u16,
    },
    /// A tool whose motions on an axis do not return to its zero point
    /// (one finding per axis: a tool open on two axes gives two).
    Closure {
        /// The tool (its С word), `None` for frames before the first С
        /// word or after Я.
        tool: Option<u8>,
        /// The tool's first frame number.
        first_frame: u16,
        /// The tool's last frame number.
        last_frame: u16,
        /// The axis that does not close.
        axis: Bck5Axis,
        /// Σ of the plus motions, impulses.
        plus: u64,
        /// Σ of the minus motions, impulses (without sign).
        minus: u64,
    },
}

impl fmt::Display for Bck5Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Bck5Finding::Unreadable { line, error } => write!(f, "line {line}: {error}"),
            Bck5Finding::CheckDigit {
                line,
                frame,
                found,
                expected,
            } => write!(
                f,
                "K{frame:03} (line {line}): check digit {found}, the frame's sum needs {expected}"
            ),
            Bck5Finding::Numbering {
                line,
                frame,
                expected,
            } => {
                write!(
                    f,
                    "K{frame:03} (line {line}): out of sequence, K{expected:03} expected"
                )
            }
            Bck5Finding::Closure {
                tool,
                first_frame,
                last_frame,
                axis,
                plus,
                minus,
            } => {
                match tool {
                    Some(t) => write!(f, "tool C{t:02}")?,
                    None => f.write_str("no tool")?,
                }
                write!(
                    f,
                    " (K{first_frame:03}-K{last_frame:03}): {} does not close, +{plus} -{minus}",
                    axis.letter().to_char(Alphabet::Latin)
                )
            }
        }
    }
}

/// What a verification went through.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bck5Summary {
    /// Lines read, blank ones included.
    pub lines: u32,
    /// Frames read (lines that parsed).
    pub frames: u32,
    /// Findings reported.
    pub findings: u32,
}

impl Bck5Summary {
    /// Whether nothing was found wrong.
    pub const fn is_clean(&self) -> bool {
        self.findings == 0
    }
}

/// Σ+ and Σ− of one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Balance {
    plus: u64,
    minus: u64,
}

impl Balance {
    fn add(&mut self, motion: Option<MotionWord>) {
        if let Some(m) = motion {
            let n = u64::from(m.count);
            if m.impulses() > 0 {
                self.plus = self.plus.saturating_add(n);
            } else {
                self.minus = self.minus.saturating_add(n);
            }
        }
    }
}

/// The frames of one tool so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Section {
    tool: Option<u8>,
    first: u16,
    last: u16,
    carriage: Balance,
    cross: Balance,
    third: Balance,
}

/// Verifies a BCK-5 tape fed one line at a time (a serial link's lines,
/// a file's), in constant memory: every frame's check digit and number,
/// every tool's closure. Each failure goes to the caller's `report` as it
/// is found; tools are judged when the next С word, Я or
/// [`Bck5Verifier::finish`] ends them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Bck5Verifier {
    summary: Bck5Summary,
    last_number: Option<u16>,
    section: Option<Section>,
}

impl Bck5Verifier {
    /// A verifier before the first line.
    pub const fn new() -> Self {
        Bck5Verifier {
            summary: Bck5Summary {
                lines: 0,
                frames: 0,
                findings: 0,
            },
            last_number: None,
            section: None,
        }
    }

    /// What has been read so far.
    pub const fn summary(&self) -> Bck5Summary {
        self.summary
    }

    /// Reads one line (without its line end). Blank lines are skipped.
    pub fn line<F: FnMut(Bck5Finding)>(&mut self, text: &str, mut report: F) {
        self.summary.lines = self.summary.lines.saturating_add(1);
        let line = self.summary.lines;
        if text.trim().is_empty() {
            return;
        }
        let frame = match Bck5Frame::parse(text) {
            Ok(frame) => frame,
            Err(error) => {
                self.emit(&mut report, Bck5Finding::Unreadable { line, error });
                // The next frame's number cannot be judged.
                self.last_number = None;
                return;
            }
        };
        self.accept(&frame, line, report);
    }

    /// Reads one frame already parsed (a line of its own: a serial link's
    /// request), as [`Bck5Verifier::line`] reads a line that parses.
    pub fn frame<F: FnMut(Bck5Finding)>(&mut self, frame: &Bck5Frame, report: F) {
        self.summary.lines = self.summary.lines.saturating_add(1);
        let line = self.summary.lines;
        self.accept(frame, line, report);
    }

    /// Checks a frame read on `line` and adds it to its tool.
    fn accept<F: FnMut(Bck5Finding)>(&mut self, frame: &Bck5Frame, line: u32, mut report: F) {
        self.summary.frames = self.summary.frames.saturating_add(1);
        if !frame.check_ok() {
            self.emit(
                &mut report,
                Bck5Finding::CheckDigit {
                    line,
                    frame: frame.number,
                    found: frame.check,
                    expected: frame.expected_check(),
                },
            );
        }
        if let Some(expected) = self.last_number.and_then(|n| n.checked_add(1)) {
            if frame.number != expected {
                self.emit(
                    &mut report,
                    Bck5Finding::Numbering {
                        line,
                        frame: frame.number,
                        expected,
                    },
                );
            }
        }
        self.last_number = Some(frame.number);

        if frame.tool.is_some() {
            self.close(&mut report);
        }
        let section = self.section.get_or_insert(Section {
            tool: frame.tool,
            first: frame.number,
            last: frame.number,
            carriage: Balance::default(),
            cross: Balance::default(),
            third: Balance::default(),
        });
        section.last = frame.number;
        section.carriage.add(frame.carriage);
        section.cross.add(frame.cross);
        section.third.add(frame.third);
        if frame.end == FrameEnd::Program {
            self.close(&mut report);
        }
    }

    /// Ends the tape: judges the last tool and returns what was read.
    pub fn finish<F: FnMut(Bck5Finding)>(mut self, mut report: F) -> Bck5Summary {
        self.close(&mut report);
        self.summary
    }

    fn emit<F: FnMut(Bck5Finding)>(&mut self, report: &mut F, finding: Bck5Finding) {
        self.summary.findings = self.summary.findings.saturating_add(1);
        report(finding);
    }

    /// Judges the current tool's closure and ends it.
    fn close<F: FnMut(Bck5Finding)>(&mut self, report: &mut F) {
        let Some(s) = self.section.take() else {
            return;
        };
        let axes = [
            (Bck5Axis::Carriage, s.carriage),
            (Bck5Axis::Cross, s.cross),
            (Bck5Axis::Third, s.third),
        ];
        for (axis, b) in axes {
            if b.plus != b.minus {
                self.emit(
                    report,
                    Bck5Finding::Closure {
                        tool: s.tool,
                        first_frame: s.first,
                        last_frame: s.last,
                        axis,
                        plus: b.plus,
                        minus: b.minus,
                    },
                );
            }
        }
    }
}

/// Verifies a whole BCK-5 tape, one frame per line, reporting every
/// failure to `report` ([`Bck5Verifier`] line by line).
///
/// ```
/// use core_nostd::calc::tape::{verify_bck5, Bck5Finding};
/// let tape = "5K001E000000D000000П00Ш00C01B00H\n\
///             2K002E212400D630000П75Ш26Н\n\
///             7K003E112400D530000П75Н\n\
///             3K004R";
/// let mut found = heapless::Vec::<Bck5Finding, 4>::new();
/// let summary = verify_bck5(tape.lines(), |f| { let _ = found.push(f); });
/// assert_eq!((summary.frames, summary.findings), (4, 0));
/// let bad = "5K001E000000D000000П00Ш00C01B00H\n3K002E212400D630000П75Ш26Н\n3K004R";
/// let summary = verify_bck5(bad.lines(), |f| { let _ = found.push(f); });
/// assert_eq!(summary.findings, 4); // K002's check digit, numbering, Е and Д open
/// ```
pub fn verify_bck5<'a, I, F>(lines: I, mut report: F) -> Bck5Summary
where
    I: IntoIterator<Item = &'a str>,
    F: FnMut(Bck5Finding),
{
    let mut v = Bck5Verifier::new();
    for line in lines {
        v.line(line, &mut report);
    }
    v.finish(report)
}

/// An axis increment: a length or a number of impulses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Travel {
    /// Impulses of the axis, issued as they are.
    Impulses(i32),
    /// Millimetres (on the radius for a cross slide), rounded with residual
    /// carry: the axis issues `Q(P/h)` minus what it has issued, `P` the sum
    /// of all travels so far, so rounding never accumulates and a path that
    /// closes in mm closes in impulses.
    Mm(Length),
}

/// An axis' commanded position and the impulses issued for it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Carry {
    commanded: Length,
    issued: i64,
}

impl Carry {
    /// The position after `travel` and the impulses it issues.
    fn advance(self, travel: Travel, price: ImpulsePrice) -> Result<(Carry, i64), TapeError> {
        match travel {
            Travel::Impulses(n) => {
                let n = i64::from(n);
                let len = n
                    .checked_mul(price.as_angstrom())
                    .and_then(Length::from_angstrom)
                    .and_then(|l| self.commanded.checked_add(l))
                    .ok_or(TapeError::WordRange)?;
                let issued = self.issued.checked_add(n).ok_or(TapeError::WordRange)?;
                Ok((
                    Carry {
                        commanded: len,
                        issued,
                    },
                    n,
                ))
            }
            Travel::Mm(d) => {
                let commanded = self.commanded.checked_add(d).ok_or(TapeError::WordRange)?;
                let issued = i64::from(
                    quantize(commanded, price)
                        .map_err(|_| TapeError::WordRange)?
                        .get(),
                );
                let n = issued
                    .checked_sub(self.issued)
                    .ok_or(TapeError::WordRange)?;
                Ok((Carry { commanded, issued }, n))
            }
        }
    }
}

/// How a BCK-5 move sets the feed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Bck5Feed {
    /// No П word: the feed of the frame before.
    Keep,
    /// `П00`.
    Off,
    /// Rapid: `П75` over 10 mm of path, `П54` up to 10 mm.
    Rapid,
    /// The code nearest this feed ([`FeedCode::nearest`]).
    PerRev(FeedPerRev),
}

/// One BCK-5 move: a frame with Е and Д words.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bck5Move {
    /// Е: the carriage (longitudinal, 0.01 mm impulses; plus away from the
    /// chuck face).
    pub carriage: Travel,
    /// Д: the cross slide (0.005 mm impulses on the radius; plus away from
    /// the spindle axis).
    pub cross: Travel,
    /// The П word.
    pub feed: Bck5Feed,
    /// A Ш word (0–99), if any.
    pub spindle: Option<u8>,
    /// A С word (0–99), if any: the tool block searched.
    pub tool: Option<u8>,
    /// A В word (0–99), if any.
    pub coolant: Option<u8>,
}

impl Bck5Move {
    /// A move with no Ш, С or В word.
    pub const fn new(carriage: Travel, cross: Travel, feed: Bck5Feed) -> Bck5Move {
        Bck5Move {
            carriage,
            cross,
            feed,
            spindle: None,
            tool: None,
            coolant: None,
        }
    }

    /// The seed's tool-change frame: no motion, `П00 Ш00 С<tool> В00`.
    pub const fn tool_change(tool: u8) -> Bck5Move {
        Bck5Move {
            carriage: Travel::Impulses(0),
            cross: Travel::Impulses(0),
            feed: Bck5Feed::Off,
            spindle: Some(0),
            tool: Some(tool),
            coolant: Some(0),
        }
    }
}

/// What one BCK-5 frame carries.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Bck5Block {
    /// A move (or a tool change, spindle or coolant command).
    Move(Bck5Move),
    /// The end of program: a frame of its number and Я.
    End,
}

/// 10 mm in cross-slide impulses (0.005 mm), the rapid-index threshold.
const RAPID_THRESHOLD_HALF_HUNDREDTHS: i64 = 2_000;

/// Numbers BCK-5 frames and gives them their words and check digits,
/// carrying each axis' rounding remainder from move to move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bck5Encoder {
    next_number: u16,
    carriage: Carry,
    cross: Carry,
}

impl Bck5Encoder {
    /// An encoder whose first frame is numbered `first_number`.
    pub const fn new(first_number: u16) -> Self {
        Bck5Encoder {
            next_number: first_number,
            carriage: Carry {
                commanded: Length::ZERO,
                issued: 0,
            },
            cross: Carry {
                commanded: Length::ZERO,
                issued: 0,
            },
        }
    }

    /// The next frame. The encoder moves on only when it succeeds.
    ///
    /// ```
    /// use core_nostd::calc::tape::*;
    /// use core_nostd::length::Length;
    /// let mm = |s| Travel::Mm(Length::from_mm_str(s).unwrap());
    /// let mut enc = Bck5Encoder::new(2);
    /// let mut m = Bck5Move::new(mm("-124"), mm("-150"), Bck5Feed::Rapid);
    /// m.spindle = Some(26);
    /// let frame = enc.frame(&Bck5Block::Move(m)).unwrap();
    /// let mut s = heapless::String::<64>::new();
    /// frame.write(&mut s, Alphabet::Latin).unwrap();
    /// assert_eq!(s, "2K002E212400D630000P75W26H");
    /// ```
    ///
    /// # Errors
    /// [`TapeError::WordRange`] for a frame number beyond 999, a move of
    /// more than 99 999 impulses, a Ш, С or В code beyond 99 or a position
    /// beyond ±99 999 mm; [`TapeError::NotPositive`] for a feed per rev
    /// not positive.
    pub fn frame(&mut self, block: &Bck5Block) -> Result<Bck5Frame, TapeError> {
        if self.next_number > BCK5_MAX_FRAME {
            return Err(TapeError::WordRange);
        }
        let mut frame = Bck5Frame {
            check: 0,
            number: self.next_number,
            carriage: None,
            cross: None,
            third: None,
            feed: None,
            spindle: None,
            tool: None,
            coolant: None,
            end: FrameEnd::Program,
        };
        let mut next = *self;
        if let Bck5Block::Move(m) = block {
            let (carriage, e) = self.carriage.advance(m.carriage, ImpulsePrice::DEFAULT_Z)?;
            let (cross, d) = self.cross.advance(m.cross, ImpulsePrice::DEFAULT_X)?;
            next.carriage = carriage;
            next.cross = cross;
            // The leading axis has more impulses; the carriage on a tie.
            let carriage_leads = e.unsigned_abs() >= d.unsigned_abs();
            frame.carriage = Some(bck5_motion(e, carriage_leads)?);
            frame.cross = Some(bck5_motion(d, !carriage_leads)?);
            frame.feed = match m.feed {
                Bck5Feed::Keep => None,
                Bck5Feed::Off => Some(Feed::Off),
                Bck5Feed::Rapid => {
                    // Path length in 0.005 mm units: a carriage impulse is two.
                    // |e|, |d| ≤ 99 999, so the squares cannot overflow.
                    let e2 = 2 * e;
                    let over_10_mm = e2 * e2 + d * d
                        > RAPID_THRESHOLD_HALF_HUNDREDTHS * RAPID_THRESHOLD_HALF_HUNDREDTHS;
                    Some(if over_10_mm {
                        Feed::Rapid
                    } else {
                        Feed::Code(FeedCode::APPROACH)
                    })
                }
                Bck5Feed::PerRev(f) => Some(Feed::Code(FeedCode::nearest(f)?)),
            };
            frame.spindle = two_digit_code(m.spindle)?;
            frame.tool = two_digit_code(m.tool)?;
            frame.coolant = two_digit_code(m.coolant)?;
            frame.end = FrameEnd::Frame;
        }
        frame.check = frame.expected_check();
        next.next_number = self.next_number.saturating_add(1);
        *self = next;
        Ok(frame)
    }
}

/// The motion word of `n` impulses.
fn bck5_motion(n: i64, leading: bool) -> Result<MotionWord, TapeError> {
    i32::try_from(n)
        .ok()
        .and_then(|n| MotionWord::new(n, leading))
        .ok_or(TapeError::WordRange)
}

/// A two-digit code, checked.
fn two_digit_code(code: Option<u8>) -> Result<Option<u8>, TapeError> {
    match code {
        Some(c) if c > 99 => Err(TapeError::WordRange),
        c => Ok(c),
    }
}

/// Encodes `blocks` as BCK-5 frames numbered from `first_number`, one per
/// line (each ended by `\n`), and returns how many were written.
///
/// ```
/// use core_nostd::calc::tape::*;
/// let blocks = [Bck5Block::Move(Bck5Move::tool_change(1)), Bck5Block::End];
/// let mut s = heapless::String::<128>::new();
/// assert_eq!(encode_bck5(&blocks, 1, Alphabet::Cyrillic, &mut s), Ok(2));
/// assert_eq!(s, "5К001Е000000Д000000П00Ш00С01В00Н\n5К002Я\n");
/// ```
///
/// # Errors
/// As [`Bck5Encoder::frame`] for the first block that fails (drive the
/// encoder yourself to know which); [`TapeError::Write`] if the writer
/// refuses.
pub fn encode_bck5<'a, I, W>(
    blocks: I,
    first_number: u16,
    alphabet: Alphabet,
    w: &mut W,
) -> Result<u16, TapeError>
where
    I: IntoIterator<Item = &'a Bck5Block>,
    W: fmt::Write + ?Sized,
{
    let mut encoder = Bck5Encoder::new(first_number);
    let mut written = 0u16;
    for block in blocks {
        let frame = encoder.frame(block)?;
        frame.write(w, alphabet).map_err(|_| TapeError::Write)?;
        w.write_char('\n').map_err(|_| TapeError::Write)?;
        written = written.saturating_add(1);
    }
    Ok(written)
}

// ───────────────────────────── ISO-7bit ─────────────────────────────

/// The characters the ЭМ-907 reads (the seed's Table 16, corrected):
/// `%` program start (with LF), `:` rewind stop, N block number, `/` block
/// skip, G X Z I K F S T M the addresses, LF end of block, `+` `-`, digits.
pub const EM907_CHARSET: [u8; 26] = *b"%:N/GXZIKFSTM\n+-0123456789";

/// The row punched for a 7-bit ASCII character: the character on tracks
/// 1–7, track 8 (bit 7) punched when that makes the holes even; `None` for
/// a byte beyond 7 bits.
///
/// ```
/// use core_nostd::calc::tape::iso7_parity;
/// assert_eq!(iso7_parity(b'5'), Some(0x35)); // 4 holes: no track 8
/// assert_eq!(iso7_parity(b'7'), Some(0xB7)); // 5 holes + track 8
/// assert_eq!(iso7_parity(b'I'), Some(0xC9));
/// assert_eq!(iso7_parity(0x80), None);
/// ```
pub const fn iso7_parity(c: u8) -> Option<u8> {
    if c >= 0x80 {
        None
    } else if c.count_ones() % 2 == 1 {
        Some(c | 0x80)
    } else {
        Some(c)
    }
}

/// Reads a punched row: the 7-bit character if its holes are even.
///
/// ```
/// use core_nostd::calc::tape::{iso7_row, TapeError};
/// assert_eq!(iso7_row(0xC9), Ok(b'I'));
/// // The seed's rows for "5" and "6": tracks 1, 2, 3, 5, 6, no track 8.
/// assert_eq!(iso7_row(0x37), Err(TapeError::Parity));
/// ```
///
/// # Errors
/// [`TapeError::Parity`] for an odd number of holes.
pub const fn iso7_row(row: u8) -> Result<u8, TapeError> {
    if row.count_ones().is_multiple_of(2) {
        Ok(row & 0x7F)
    } else {
        Err(TapeError::Parity)
    }
}

/// Whether the ЭМ-907 reads a character ([`EM907_CHARSET`]).
///
/// ```
/// use core_nostd::calc::tape::em907_reads;
/// assert!(em907_reads(b'I'));
/// assert!(!em907_reads(b'J'));
/// ```
pub fn em907_reads(c: u8) -> bool {
    EM907_CHARSET.contains(&c)
}

/// The ЭМ-907's feed word `F = S·10³/l`, rounded to the nearest whole:
/// `S` the contour feed in mm/min (`S₀·n`), `l` the block's length in mm
/// (G01) or the arc's radius `R` (G02, G03).
///
/// ```
/// use core_nostd::calc::tape::em907_feed_word;
/// // N032: 0.05 mm/rev at 710 rpm on R 25.
/// assert_eq!(em907_feed_word(0.05 * 710.0, 25.0), Ok(1420));
/// // N017 with the seed's l = 26.5 mm (it prints 8050).
/// assert_eq!(em907_feed_word(0.3 * 710.0, 26.5), Ok(8038));
/// ```
///
/// # Errors
/// [`TapeError::NotPositive`] for a feed or length not finite and > 0;
/// [`TapeError::WordRange`] outside 1–130 000.
pub fn em907_feed_word(s_mm_per_min: f64, length_mm: f64) -> Result<u32, TapeError> {
    if !(s_mm_per_min > 0.0 && s_mm_per_min.is_finite() && length_mm > 0.0 && length_mm.is_finite())
    {
        return Err(TapeError::NotPositive);
    }
    let f = libm::round(s_mm_per_min * 1000.0 / length_mm);
    if (1.0..=f64::from(EM907_MAX_WORD)).contains(&f) {
        // Whole and within 1…130 000: exact.
        Ok(f as u32)
    } else {
        Err(TapeError::WordRange)
    }
}

/// The largest X, Z, I, K or F word of the ЭМ-907.
pub const EM907_MAX_WORD: u32 = 130_000;

/// The most M words one [`Iso7Block`] holds.
pub const EM907_MAX_M_WORDS: usize = 6;

/// What stands in N's place at the start of an ISO block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BlockStart {
    /// `N`: a block.
    Number,
    /// `:`: the rewind stops here.
    RewindStop,
    /// `/`: skipped in the "with stop" and accelerated modes.
    Skip,
}

impl BlockStart {
    const fn to_char(self) -> char {
        match self {
            BlockStart::Number => 'N',
            BlockStart::RewindStop => ':',
            BlockStart::Skip => '/',
        }
    }
}

/// One ЭМ-907 block (Table 31): N G X Z I K F S T M, each optional but N.
/// [`fmt::Display`] writes it as punched, without spaces and without its
/// LF.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Iso7Block {
    start: BlockStart,
    number: u16,
    g: Option<u8>,
    x: Option<i32>,
    z: Option<i32>,
    i: Option<u32>,
    k: Option<u32>,
    f: Option<u32>,
    s: Option<u8>,
    t: Option<u16>,
    m: [u8; EM907_MAX_M_WORDS],
    m_len: u8,
}

impl Iso7Block {
    const fn empty(start: BlockStart, number: u16) -> Iso7Block {
        Iso7Block {
            start,
            number,
            g: None,
            x: None,
            z: None,
            i: None,
            k: None,
            f: None,
            s: None,
            t: None,
            m: [0; EM907_MAX_M_WORDS],
            m_len: 0,
        }
    }

    /// Reads a block from a line without its LF. Whitespace is skipped (the
    /// seed prints `G 03`, `F 1420`); J is read as I (the seed's spelling).
    /// Words: N (or `:`, `/`) and three digits; G two digits; X, Z a sign
    /// (absent: plus) and up to 130 000; I, K up to 130 000 without sign;
    /// F 1–130 000; S two digits; T three; M two, repeated up to
    /// [`EM907_MAX_M_WORDS`] times.
    ///
    /// ```
    /// use core_nostd::calc::tape::{Iso7Block, TapeError};
    /// let b = Iso7Block::parse("N032 G 03 X+600 Z-1190 J4397 K1190 F 1420 S 44").unwrap();
    /// assert_eq!((b.g(), b.x(), b.z(), b.i(), b.k(), b.f()),
    ///            (Some(3), Some(600), Some(-1190), Some(4397), Some(1190), Some(1420)));
    /// assert_eq!(b.to_string(), "N032G03X+600Z-1190I4397K1190F1420S44");
    /// let e = Iso7Block::parse("N017G01X+500Z-2600").unwrap_err();
    /// assert_eq!((e.error, e.column), (TapeError::MissingWord, 19));
    /// ```
    ///
    /// # Errors
    /// A [`ParseError`] naming the first thing wrong and its column.
    pub fn parse(line: &str) -> Result<Iso7Block, ParseError> {
        let mut cur = Cursor::new(line);
        let (start_column, start) = match cur.bump() {
            Some((col, 'N')) => (col, BlockStart::Number),
            Some((col, ':')) => (col, BlockStart::RewindStop),
            Some((col, '/')) => (col, BlockStart::Skip),
            Some((col, c)) => {
                return Err(ParseError::at(
                    iso7_misplaced(c, TapeError::MissingNumber),
                    col,
                ))
            }
            None => return Err(ParseError::at(TapeError::MissingNumber, cur.end())),
        };
        let digits = cur.digits();
        if digits.count != 3 {
            return Err(short_word(&mut cur, start_column, iso7_known));
        }
        // Three digits: ≤ 999.
        let mut block = Iso7Block::empty(start, digits.value as u16);
        let mut rank = 0u8;
        let mut g_column = 0;
        while let Some((column, c)) = cur.bump() {
            let letter = if c == 'J' { 'I' } else { c };
            let r = match letter {
                'G' => 1,
                'X' => 2,
                'Z' => 3,
                'I' => 4,
                'K' => 5,
                'F' => 6,
                'S' => 7,
                'T' => 8,
                'M' => 9,
                _ => {
                    return Err(ParseError::at(
                        iso7_misplaced(c, TapeError::WordOrder),
                        column,
                    ))
                }
            };
            if r < rank || (r == rank && r != 9) {
                return Err(ParseError::at(TapeError::WordOrder, column));
            }
            rank = r;
            let at = |e| ParseError::at(e, column);
            match letter {
                'X' | 'Z' => {
                    let negative = match cur.peek() {
                        Some('-') => true,
                        Some('+') => false,
                        _ => false,
                    };
                    if matches!(cur.peek(), Some('+' | '-')) {
                        cur.bump();
                    }
                    let v = iso7_number(&mut cur, column)?;
                    // ≤ 130 000: exact in i32.
                    let v = if negative { -(v as i32) } else { v as i32 };
                    if letter == 'X' {
                        block.x = Some(v);
                    } else {
                        block.z = Some(v);
                    }
                }
                'I' | 'K' | 'F' => {
                    if matches!(cur.peek(), Some('+' | '-')) {
                        return Err(at(TapeError::WordLength));
                    }
                    let v = iso7_number(&mut cur, column)?;
                    match letter {
                        'I' => block.i = Some(v),
                        'K' => block.k = Some(v),
                        _ if v == 0 => return Err(at(TapeError::WordRange)),
                        _ => block.f = Some(v),
                    }
                }
                _ => {
                    let width = if letter == 'T' { 3 } else { 2 };
                    let d = cur.digits();
                    if d.count != width {
                        return Err(short_word(&mut cur, column, iso7_known));
                    }
                    // Two or three digits: ≤ 999.
                    match letter {
                        'G' => {
                            block.g = Some(d.value as u8);
                            g_column = column;
                        }
                        'S' => block.s = Some(d.value as u8),
                        'T' => block.t = Some(d.value as u16),
                        _ => block = block.with_m(d.value as u8).map_err(at)?,
                    }
                }
            }
        }
        if let Some(g) = block.g {
            if block.x.is_none() && block.z.is_none() {
                return Err(ParseError::at(TapeError::MissingWord, g_column));
            }
            if matches!(g, 1..=3) && block.f.is_none() {
                return Err(ParseError::at(TapeError::MissingWord, cur.end()));
            }
        }
        Ok(block)
    }

    /// N, `:` or `/`.
    pub const fn start(&self) -> BlockStart {
        self.start
    }
    /// The block number.
    pub const fn number(&self) -> u16 {
        self.number
    }
    /// The G word.
    pub const fn g(&self) -> Option<u8> {
        self.g
    }
    /// The X word: cross-slide impulses (0.005 mm), signed.
    pub const fn x(&self) -> Option<i32> {
        self.x
    }
    /// The Z word: carriage impulses (0.01 mm), signed.
    pub const fn z(&self) -> Option<i32> {
        self.z
    }
    /// The I word (the seed's J): the arc centre's distance from the start
    /// along X, or the thread pitch across, impulses.
    pub const fn i(&self) -> Option<u32> {
        self.i
    }
    /// The K word: the arc centre's distance from the start along Z, or the
    /// thread pitch along, impulses.
    pub const fn k(&self) -> Option<u32> {
        self.k
    }
    /// The F word.
    pub const fn f(&self) -> Option<u32> {
        self.f
    }
    /// The S word (spindle speed code, Table 25).
    pub const fn s(&self) -> Option<u8> {
        self.s
    }
    /// The T word (tool position and correction, Table 26).
    pub const fn t(&self) -> Option<u16> {
        self.t
    }
    /// The M words in order.
    pub fn m(&self) -> &[u8] {
        self.m.get(..usize::from(self.m_len)).unwrap_or(&[])
    }

    /// The block with an S word (00–99).
    ///
    /// ```
    /// use core_nostd::calc::tape::Iso7Block;
    /// let b = Iso7Block::parse("N018G00Z+8200").unwrap().with_s(48).unwrap();
    /// assert_eq!(b.to_string(), "N018G00Z+8200S48");
    /// ```
    ///
    /// # Errors
    /// [`TapeError::WordRange`] beyond 99.
    pub const fn with_s(mut self, code: u8) -> Result<Iso7Block, TapeError> {
        if code > 99 {
            return Err(TapeError::WordRange);
        }
        self.s = Some(code);
        Ok(self)
    }

    /// The block with a T word (000–999).
    ///
    /// # Errors
    /// [`TapeError::WordRange`] beyond 999.
    pub const fn with_t(mut self, code: u16) -> Result<Iso7Block, TapeError> {
        if code > 999 {
            return Err(TapeError::WordRange);
        }
        self.t = Some(code);
        Ok(self)
    }

    /// The block with one more M word (00–99).
    ///
    /// ```
    /// use core_nostd::calc::tape::Iso7Block;
    /// let b = Iso7Block::parse("N036G00Z-1350T702").unwrap().with_m(6).unwrap();
    /// assert_eq!(b.to_string(), "N036G00Z-1350T702M06");
    /// ```
    ///
    /// # Errors
    /// [`TapeError::WordRange`] beyond 99 or beyond [`EM907_MAX_M_WORDS`]
    /// words.
    pub fn with_m(mut self, code: u8) -> Result<Iso7Block, TapeError> {
        if code > 99 {
            return Err(TapeError::WordRange);
        }
        let slot = self
            .m
            .get_mut(usize::from(self.m_len))
            .ok_or(TapeError::WordRange)?;
        *slot = code;
        self.m_len = self.m_len.saturating_add(1);
        Ok(self)
    }
}

impl fmt::Display for Iso7Block {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{:03}", self.start.to_char(), self.number)?;
        if let Some(g) = self.g {
            write!(f, "G{g:02}")?;
        }
        if let Some(x) = self.x {
            write!(f, "X{x:+}")?;
        }
        if let Some(z) = self.z {
            write!(f, "Z{z:+}")?;
        }
        if let Some(i) = self.i {
            write!(f, "I{i}")?;
        }
        if let Some(k) = self.k {
            write!(f, "K{k}")?;
        }
        if let Some(v) = self.f {
            write!(f, "F{v}")?;
        }
        if let Some(s) = self.s {
            write!(f, "S{s:02}")?;
        }
        if let Some(t) = self.t {
            write!(f, "T{t:03}")?;
        }
        for m in self.m() {
            write!(f, "M{m:02}")?;
        }
        Ok(())
    }
}

/// The value of an X, Z, I, K or F word whose letter is at `column`: 1 to
/// 6 digits worth at most [`EM907_MAX_WORD`].
fn iso7_number(cur: &mut Cursor<'_>, column: u32) -> Result<u32, ParseError> {
    let d = cur.digits();
    if d.count == 0 || d.count > 6 {
        Err(short_word(cur, column, iso7_known))
    } else if d.value > EM907_MAX_WORD {
        Err(ParseError::at(TapeError::WordRange, column))
    } else {
        Ok(d.value)
    }
}

/// Whether the ЭМ-907 reads a character (J as the seed's I).
fn iso7_known(c: char) -> bool {
    c == 'J' || (c.is_ascii() && em907_reads(c as u8))
}

/// The error for a character `c` found where something else was expected:
/// [`TapeError::UnknownCharacter`] if the ЭМ-907 has no such character.
fn iso7_misplaced(c: char, otherwise: TapeError) -> TapeError {
    if iso7_known(c) {
        otherwise
    } else {
        TapeError::UnknownCharacter
    }
}

/// The motion of one ЭМ-907 block.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Em907Motion {
    /// G00: rapid, no F.
    Rapid,
    /// G01 at a feed; F over the block's length.
    Linear(FeedPerRev),
    /// G02 (clockwise) or G03 at a feed; F over the radius.
    Arc {
        /// G02 if true, G03 if false.
        clockwise: bool,
        /// I: the centre's distance from the start point along X (0.005
        /// mm impulses; the sign is dropped).
        i: Travel,
        /// K: the centre's distance from the start point along Z (0.01 mm
        /// impulses; the sign is dropped).
        k: Travel,
        /// The feed.
        feed: FeedPerRev,
    },
}

/// One ЭМ-907 move.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Em907Move {
    /// X: the cross slide (0.005 mm impulses, on the radius).
    pub x: Travel,
    /// Z: the carriage (0.01 mm impulses).
    pub z: Travel,
    /// G00, G01, G02 or G03 and its feed.
    pub motion: Em907Motion,
}

/// Numbers ЭМ-907 blocks and gives them their words and F, carrying each
/// axis' rounding remainder from block to block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Em907Encoder {
    next_number: u16,
    x: Carry,
    z: Carry,
}

impl Em907Encoder {
    /// An encoder whose first block is numbered `first_number`.
    pub const fn new(first_number: u16) -> Self {
        Em907Encoder {
            next_number: first_number,
            x: Carry {
                commanded: Length::ZERO,
                issued: 0,
            },
            z: Carry {
                commanded: Length::ZERO,
                issued: 0,
            },
        }
    }

    /// The next block: N, G, X and Z (those that move), I and K (arcs), F
    /// (G01–G03). Add S, T and M with [`Iso7Block::with_s`] and its kin.
    /// The encoder moves on only when it succeeds.
    ///
    /// ```
    /// use core_nostd::calc::tape::*;
    /// use core_nostd::length::Length;
    /// let mm = |s| Travel::Mm(Length::from_mm_str(s).unwrap());
    /// // Table 31, N032: the sphere from point 32 to 33.
    /// let arc = Em907Move {
    ///     x: mm("3"),
    ///     z: mm("-11.9"),
    ///     motion: Em907Motion::Arc {
    ///         clockwise: false,
    ///         i: Travel::Impulses(4397),
    ///         k: Travel::Impulses(1190),
    ///         feed: FeedPerRev { n_rpm: 710.0, s_mm_per_rev: 0.05 },
    ///     },
    /// };
    /// let block = Em907Encoder::new(32).block(&arc)?.with_s(44)?;
    /// assert_eq!(block.to_string(), "N032G03X+600Z-1190I4397K1190F1420S44");
    /// # Ok::<(), TapeError>(())
    /// ```
    ///
    /// # Errors
    /// [`TapeError::WordRange`] for a block number beyond 999, a word
    /// beyond 130 000 or a position beyond ±99 999 mm;
    /// [`TapeError::NoMotion`] for a block that moves neither axis;
    /// [`TapeError::NotPositive`] for a feed not positive or an arc of
    /// radius 0.
    pub fn block(&mut self, mv: &Em907Move) -> Result<Iso7Block, TapeError> {
        if self.next_number > 999 {
            return Err(TapeError::WordRange);
        }
        let (x, dx) = self.x.advance(mv.x, ImpulsePrice::DEFAULT_X)?;
        let (z, dz) = self.z.advance(mv.z, ImpulsePrice::DEFAULT_Z)?;
        let dx = em907_signed(dx)?;
        let dz = em907_signed(dz)?;
        if dx == 0 && dz == 0 {
            return Err(TapeError::NoMotion);
        }
        let mut block = Iso7Block::empty(BlockStart::Number, self.next_number);
        block.x = (dx != 0).then_some(dx);
        block.z = (dz != 0).then_some(dz);
        let x_mm = f64::from(dx) * 0.005;
        let z_mm = f64::from(dz) * 0.01;
        match mv.motion {
            Em907Motion::Rapid => block.g = Some(0),
            Em907Motion::Linear(feed) => {
                block.g = Some(1);
                block.f = Some(em907_feed_word(
                    feed.mm_per_min()?,
                    libm::sqrt(x_mm * x_mm + z_mm * z_mm),
                )?);
            }
            Em907Motion::Arc {
                clockwise,
                i,
                k,
                feed,
            } => {
                block.g = Some(if clockwise { 2 } else { 3 });
                let i = em907_distance(i, ImpulsePrice::DEFAULT_X)?;
                let k = em907_distance(k, ImpulsePrice::DEFAULT_Z)?;
                block.i = Some(i);
                block.k = Some(k);
                let i_mm = f64::from(i) * 0.005;
                let k_mm = f64::from(k) * 0.01;
                block.f = Some(em907_feed_word(
                    feed.mm_per_min()?,
                    libm::sqrt(i_mm * i_mm + k_mm * k_mm),
                )?);
            }
        }
        self.x = x;
        self.z = z;
        self.next_number = self.next_number.saturating_add(1);
        Ok(block)
    }
}

/// A signed X or Z word, at most [`EM907_MAX_WORD`] either way.
fn em907_signed(n: i64) -> Result<i32, TapeError> {
    if n.unsigned_abs() > u64::from(EM907_MAX_WORD) {
        Err(TapeError::WordRange)
    } else {
        // |n| ≤ 130 000.
        Ok(n as i32)
    }
}

/// An I or K distance in impulses, without sign.
fn em907_distance(t: Travel, price: ImpulsePrice) -> Result<u32, TapeError> {
    let n = match t {
        Travel::Impulses(n) => n.unsigned_abs(),
        Travel::Mm(l) => quantize(l, price)
            .map_err(|_| TapeError::WordRange)?
            .get()
            .unsigned_abs(),
    };
    if n > EM907_MAX_WORD {
        Err(TapeError::WordRange)
    } else {
        Ok(n)
    }
}

/// Encodes `moves` as ЭМ-907 blocks numbered from `first_number`, one per
/// line (each ended by LF), and returns how many were written. The
/// program's `%` LF, if wanted, is the caller's to write first.
///
/// ```
/// use core_nostd::calc::tape::*;
/// use core_nostd::length::Length;
/// let mm = |s| Travel::Mm(Length::from_mm_str(s).unwrap());
/// let feed = FeedPerRev { n_rpm: 710.0, s_mm_per_rev: 0.05 };
/// let moves = [
///     Em907Move { x: mm("0"), z: mm("-30.1"), motion: Em907Motion::Linear(feed) },
///     Em907Move { x: mm("-85.62"), z: mm("0"), motion: Em907Motion::Rapid },
/// ];
/// let mut s = heapless::String::<64>::new();
/// assert_eq!(encode_iso7(&moves, 33, &mut s), Ok(2));
/// assert_eq!(s, "N033G01Z-3010F1179\nN034G00X-17124\n");
/// ```
///
/// # Errors
/// As [`Em907Encoder::block`] for the first move that fails;
/// [`TapeError::Write`] if the writer refuses.
pub fn encode_iso7<'a, I, W>(moves: I, first_number: u16, w: &mut W) -> Result<u16, TapeError>
where
    I: IntoIterator<Item = &'a Em907Move>,
    W: fmt::Write + ?Sized,
{
    let mut encoder = Em907Encoder::new(first_number);
    let mut written = 0u16;
    for mv in moves {
        let block = encoder.block(mv)?;
        writeln!(w, "{block}").map_err(|_| TapeError::Write)?;
        written = written.saturating_add(1);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;

    /// The seed's printed program (Kosenko, ch. IV §5, "Программа
    /// обработки валика"), verbatim: tabs, Latin look-alikes and all.
    const SEED_TAPE: &str = "\
0	K000	E000000	D000000	П00	Ш00	C00	B00	H
5	K001	E000000	D000000	П00	Ш00	C01	B00	H
2	K002	E212400	D630000	П75	Ш26			H
6	K003	E600221	D000000	П54			B01	H
9	K004	E000000	D514800	П44				H
5	K005	E500121	D000000	П54				H
4	K006	E000000	D600368					H
8	K007	E603070	D000000	П44				H
7	K008	E602980	D101404	П44				H
3	K009	E602000	D000000	П44				H
2	K010	E000000	D100564	П54				H
3	K011	E119550	D523600	П75	Ш00		B00	H
8	K012	E000000	D000000	П00	Ш00	C42	B00	H
0	K013	E618111	D218000	П75	Ш26		B01	H
3	K014	E000000	D600810	П41				H
3	K015	E000000	D502210	П54				H
8	K016	E605000	D000000	П75				H
1	K017	E000000	D601016	П41				H
1	K018	E000000	D501616	П54				H
1	K019	E523111	D116000	П75	Ш00		B00	H
3	K020	E000000	D000000	П00	Ш00	C02	B00	H
5	K021	E218600	D624204	П75	Ш26		B01	H
3	K022	E603800	D000000	П31				H
9	K023	E000000	D500604	П54				H
8	K024	E120900	D523600	П75	Ш00		B00	H
7	K025	E000000	D000000	П00	Ш00	C03	B00	H
4	K026	E213000	D625606	П75	Ш26		B01	H
8	K027	E602900	D000000	П31				H
4	K028	E000000	D500406	П54				H
1	K029	E115900	D525200	П75	Ш00		B00	H
4	K030	Я						
2	K031	Н						
1	K32	Н						";

    extern crate std;
    use std::string::{String, ToString};
    use std::vec::Vec;

    fn mm(s: &str) -> Length {
        Length::from_mm_str(s).unwrap()
    }

    /// A seed row as this module writes it: whitespace gone, every letter
    /// in Cyrillic.
    fn fold(row: &str) -> String {
        row.chars()
            .filter(|c| !c.is_whitespace())
            .map(|c| Bck5Letter::from_char(c).map_or(c, |l| l.to_char(Alphabet::Cyrillic)))
            .collect()
    }

    fn seed_row(number: usize) -> &'static str {
        SEED_TAPE.lines().nth(number).unwrap()
    }

    fn verify(tape: &str) -> (Vec<Bck5Finding>, Bck5Summary) {
        let mut found = Vec::new();
        let summary = verify_bck5(tape.lines(), |f| found.push(f));
        (found, summary)
    }

    fn text<T: fmt::Display>(t: T) -> String {
        let mut s = String::new();
        write!(s, "{t}").unwrap();
        s
    }

    fn frame_text(f: &Bck5Frame, alphabet: Alphabet) -> String {
        let mut s = String::new();
        f.write(&mut s, alphabet).unwrap();
        s
    }

    // ───────── BCK-5: letters, frames, check digits ─────────

    #[test]
    fn letter_values_are_table_15() {
        let table = [
            ('Н', 'H', 0),
            ('Е', 'E', 1),
            ('Д', 'D', 2),
            ('Т', 'T', 3),
            ('К', 'K', 4),
            ('П', 'P', 5),
            ('Ш', 'W', 6),
            ('С', 'C', 7),
            ('В', 'B', 8),
            ('Я', 'R', 9),
        ];
        for (cyr, lat, value) in table {
            let l = Bck5Letter::from_char(cyr).unwrap();
            assert_eq!(l.value(), value);
            assert_eq!(Bck5Letter::from_char(lat), Some(l));
            assert_eq!(Bck5Letter::from_char(lat.to_ascii_lowercase()), Some(l));
            assert_eq!(
                Bck5Letter::from_char(cyr.to_lowercase().next().unwrap()),
                Some(l)
            );
            assert_eq!(l.to_char(Alphabet::Cyrillic), cyr);
            assert_eq!(l.to_char(Alphabet::Latin), lat);
        }
        // Cyrillic Р (Er) is no BCK-5 letter, nor are the other Latin capitals.
        for c in [
            'Р', 'Ж', 'A', 'F', 'G', 'I', 'J', 'L', 'M', 'N', 'O', 'Q', 'S', 'U', 'V', 'X', 'Y',
            'Z',
        ] {
            assert_eq!(Bck5Letter::from_char(c), None, "{c}");
        }
    }

    #[test]
    fn seed_check_digit_example() {
        // «Пример: 2K002E2I2400D630000П75Ш26Н / 4 2I2I24 263 575626=58 /
        // К остатку 8 добавляем 2».
        let f = Bck5Frame::parse("2K002E212400D630000П75Ш26Н").unwrap();
        assert_eq!(f.digit_sum(), 58);
        assert_eq!(f.expected_check(), 2);
        assert!(f.check_ok());
        assert_eq!(f.carriage(), MotionWord::new(-12_400, false));
        assert_eq!(f.cross(), MotionWord::new(-30_000, true));
        assert_eq!(f.feed(), Some(Feed::Rapid));
        assert_eq!((f.spindle(), f.tool(), f.coolant()), (Some(26), None, None));
        assert_eq!(f.end(), FrameEnd::Frame);
        assert_eq!(text(f), "2К002Е212400Д630000П75Ш26Н");
        assert_eq!(
            frame_text(&f, Alphabet::Latin),
            "2K002E212400D630000P75W26H"
        );
        // The seed's OCR writes 1 as I: not a digit of the code.
        let e = Bck5Frame::parse("2K002E2I2400D630000П75Ш26Н").unwrap_err();
        assert_eq!(
            e,
            ParseError {
                error: TapeError::UnknownCharacter,
                column: 8
            }
        );
        let e = Bck5Frame::parse("2KOO2E212400D630000П75Ш26Н").unwrap_err();
        assert_eq!(
            e,
            ParseError {
                error: TapeError::UnknownCharacter,
                column: 3
            }
        );
    }

    #[test]
    fn every_seed_frame_parses_and_prints_back() {
        let mut n = 0;
        for (i, row) in SEED_TAPE.lines().enumerate() {
            let f = Bck5Frame::parse(row).unwrap_or_else(|e| panic!("{row}: {e}"));
            assert_eq!(usize::from(f.number()), i);
            if f.number() == 32 {
                // Printed «K32»: written back with three digits.
                assert_eq!(text(f), "1К032Н");
            } else {
                assert_eq!(text(f), fold(row));
            }
            n += 1;
        }
        assert_eq!(n, 33);
    }

    #[test]
    fn seed_check_digits_fail_exactly_at_k000_k004_k007() {
        let mut bad = Vec::new();
        for row in SEED_TAPE.lines() {
            let f = Bck5Frame::parse(row).unwrap();
            if !f.check_ok() {
                bad.push((f.number(), f.check(), f.expected_check()));
            }
        }
        assert_eq!(bad, [(0, 0, 7), (4, 9, 8), (7, 8, 7)]);
        // Frame sums as the seed's rule adds them (a few, by hand).
        let sum = |n| Bck5Frame::parse(seed_row(n)).unwrap().digit_sum();
        assert_eq!(sum(0), 33);
        assert_eq!(sum(1), 35);
        assert_eq!(sum(4), 42);
        assert_eq!(sum(7), 43);
        assert_eq!(sum(30), 16); // К030Я: 4 + 3 + 9
    }

    #[test]
    fn seed_tape_flags_k000_k004_k007_and_the_tools_of_k011_k021() {
        let (found, summary) = verify(SEED_TAPE);
        assert_eq!(
            summary,
            Bck5Summary {
                lines: 33,
                frames: 33,
                findings: 6
            }
        );
        assert_eq!(
            found,
            [
                Bck5Finding::CheckDigit {
                    line: 1,
                    frame: 0,
                    found: 0,
                    expected: 7
                },
                Bck5Finding::CheckDigit {
                    line: 5,
                    frame: 4,
                    found: 9,
                    expected: 8
                },
                Bck5Finding::CheckDigit {
                    line: 8,
                    frame: 7,
                    found: 8,
                    expected: 7
                },
                // Tool 01 (К001–К011): К011's Е119550 should be Е120550,
                // and К004's Д514800 is Д504800.
                Bck5Finding::Closure {
                    tool: Some(1),
                    first_frame: 1,
                    last_frame: 11,
                    axis: Bck5Axis::Carriage,
                    plus: 19_671,
                    minus: 20_671
                },
                Bck5Finding::Closure {
                    tool: Some(1),
                    first_frame: 1,
                    last_frame: 11,
                    axis: Bck5Axis::Cross,
                    plus: 40_368,
                    minus: 30_368
                },
                // Tool 02 (К020–К024): К021's Е218600 should be Е217100.
                Bck5Finding::Closure {
                    tool: Some(2),
                    first_frame: 20,
                    last_frame: 24,
                    axis: Bck5Axis::Carriage,
                    plus: 20_900,
                    minus: 22_400
                },
            ]
        );
        let lines: Vec<String> = found.iter().map(|f| text(*f)).collect();
        assert_eq!(
            lines,
            [
                "K000 (line 1): check digit 0, the frame's sum needs 7",
                "K004 (line 5): check digit 9, the frame's sum needs 8",
                "K007 (line 8): check digit 8, the frame's sum needs 7",
                "tool C01 (K001-K011): E does not close, +19671 -20671",
                "tool C01 (K001-K011): D does not close, +40368 -30368",
                "tool C02 (K020-K024): E does not close, +20900 -22400",
            ]
        );
        for l in &lines {
            assert!(l.is_ascii());
        }
    }

    /// Σ+ and Σ− per tool of a tape, Е then Д.
    fn tool_sums(tape: &str) -> Vec<(Option<u8>, Balance, Balance)> {
        let mut out: Vec<(Option<u8>, Balance, Balance)> = Vec::new();
        for row in tape.lines() {
            let f = Bck5Frame::parse(row).unwrap();
            if f.tool().is_some() || out.is_empty() {
                out.push((f.tool(), Balance::default(), Balance::default()));
            }
            let last = out.last_mut().unwrap();
            last.1.add(f.carriage());
            last.2.add(f.cross());
        }
        out
    }

    #[test]
    fn seed_tool_sums_are_table_21() {
        let b = |plus, minus| Balance { plus, minus };
        assert_eq!(
            tool_sums(SEED_TAPE),
            [
                (Some(0), b(0, 0), b(0, 0)),
                // Table 21: Σ +20671 + Σ −20671 (with 20550 on the way back),
                // Σ −30368 + Σ +30368 (with 4800 at К004, not 14800).
                (Some(1), b(19_671, 20_671), b(40_368, 30_368)),
                // Σ ±23111, Σ ±19826.
                (Some(42), b(23_111, 23_111), b(19_826, 19_826)),
                // Σ +20900 (the tape's Е218600 out), Σ ±24204 on the tape
                // (Table 21: 24206, and «Σ −20206», a slip).
                (Some(2), b(20_900, 22_400), b(24_204, 24_204)),
                // Σ ±15900, Σ ±25606.
                (Some(3), b(15_900, 15_900), b(25_606, 25_606)),
            ]
        );
    }

    #[test]
    fn seed_leading_flags_follow_the_larger_count_but_for_k010() {
        for row in SEED_TAPE.lines() {
            let f = Bck5Frame::parse(row).unwrap();
            let (Some(e), Some(d)) = (f.carriage(), f.cross()) else {
                continue;
            };
            if e.count() == 0 && d.count() == 0 {
                assert!(!e.is_leading() && !d.is_leading());
                continue;
            }
            let e_leads = e.count() >= d.count();
            let ok = e.is_leading() == e_leads && d.is_leading() != e_leads;
            assert_eq!(ok, f.number() != 10, "К{:03}", f.number());
        }
    }

    #[test]
    fn frame_001_reproduces_exactly() {
        let mut enc = Bck5Encoder::new(1);
        let f = enc
            .frame(&Bck5Block::Move(Bck5Move::tool_change(1)))
            .unwrap();
        assert_eq!(text(f), "5К001Е000000Д000000П00Ш00С01В00Н");
        assert_eq!(text(f), fold(seed_row(1)));
        assert_eq!(
            frame_text(&f, Alphabet::Latin),
            "5K001E000000D000000P00W00C01B00H"
        );
        // The text's own print «5K001E000000D000000P00Ш000IВ00H» lacks the
        // С: its digits sum to 33, not a multiple of 10.
        let e = Bck5Frame::parse("5K001E000000D000000P00Ш000IВ00H").unwrap_err();
        assert_eq!(
            e,
            ParseError {
                error: TapeError::UnknownCharacter,
                column: 27
            }
        );
        let without_c = Bck5Frame::parse("5K001E000000D000000P00Ш00B00H").unwrap();
        assert_eq!(without_c.digit_sum() + 5 + 1, 33);
        assert_eq!(f.digit_sum() + 5, 40);
    }

    #[test]
    fn check_digit_example_encodes_exactly() {
        let mut enc = Bck5Encoder::new(2);
        let mut m = Bck5Move::new(
            Travel::Impulses(-12_400),
            Travel::Impulses(-30_000),
            Bck5Feed::Rapid,
        );
        m.spindle = Some(26);
        let f = enc.frame(&Bck5Block::Move(m)).unwrap();
        assert_eq!(text(f), fold("2K002E212400D630000П75Ш26Н"));
        assert_eq!(f.check(), 2);
    }

    /// The seed's program as blocks, from Table 21's coordinates (mm), the
    /// feeds of Table 22 and the Ш/В words of the tape.
    fn seed_program_from_table_21() -> Vec<Bck5Block> {
        let rapid = Bck5Feed::Rapid;
        let keep = Bck5Feed::Keep;
        let feed = |s| {
            Bck5Feed::PerRev(FeedPerRev {
                n_rpm: 550.0,
                s_mm_per_rev: s,
            })
        };
        type Point = (&'static str, &'static str, Bck5Feed, Option<u8>, Option<u8>);
        let tools: [(u8, (&str, &str), Vec<Point>); 4] = [
            (
                1,
                ("246", "150"),
                Vec::from([
                    ("122", "0", rapid, Some(26), None),
                    ("119.79", "0", rapid, None, Some(1)),
                    ("119.79", "24", feed(0.25), None, None),
                    ("121", "24", rapid, None, None),
                    ("121", "22.16", keep, None, None),
                    ("90.3", "22.16", feed(0.25), None, None),
                    ("60.5", "29.18", feed(0.25), None, None),
                    ("40.5", "29.18", feed(0.25), None, None),
                    ("40.5", "32", rapid, None, None),
                    ("246", "150", rapid, Some(0), Some(0)),
                ]),
            ),
            (
                42,
                ("271", "115"),
                Vec::from([
                    ("89.89", "25", rapid, Some(26), Some(1)),
                    ("89.89", "20.95", feed(0.1), None, None),
                    ("89.89", "32", rapid, None, None),
                    ("39.89", "32", rapid, None, None),
                    ("39.89", "26.92", feed(0.1), None, None),
                    ("39.89", "35", rapid, None, None),
                    ("271", "115", rapid, Some(0), Some(0)),
                ]),
            ),
            (
                2,
                ("251", "150"),
                Vec::from([
                    ("80", "28.97", rapid, Some(26), Some(1)),
                    ("42", "28.97", feed(0.05), None, None),
                    ("42", "32", rapid, None, None),
                    ("251", "150", rapid, Some(0), Some(0)),
                ]),
            ),
            (
                3,
                ("251", "150"),
                Vec::from([
                    ("121", "21.97", rapid, Some(26), Some(1)),
                    ("92", "21.97", feed(0.05), None, None),
                    ("92", "24", rapid, None, None),
                    ("251", "150", rapid, Some(0), Some(0)),
                ]),
            ),
        ];
        let mut blocks = Vec::from([Bck5Block::Move(Bck5Move::tool_change(0))]);
        for (tool, (x0, y0), points) in tools {
            blocks.push(Bck5Block::Move(Bck5Move::tool_change(tool)));
            let (mut x, mut y) = (mm(x0), mm(y0));
            for (to_x, to_y, feed, spindle, coolant) in points {
                let (nx, ny) = (mm(to_x), mm(to_y));
                let mut m = Bck5Move::new(
                    Travel::Mm(nx.checked_sub(x).unwrap()),
                    Travel::Mm(ny.checked_sub(y).unwrap()),
                    feed,
                );
                m.spindle = spindle;
                m.coolant = coolant;
                blocks.push(Bck5Block::Move(m));
                (x, y) = (nx, ny);
            }
        }
        blocks.push(Bck5Block::End);
        blocks
    }

    #[test]
    fn seed_program_encodes_from_table_21_up_to_its_slips() {
        let blocks = seed_program_from_table_21();
        let mut out = String::new();
        assert_eq!(
            encode_bck5(&blocks, 0, Alphabet::Cyrillic, &mut out),
            Ok(31)
        );
        // The printed frames, but where the seed slipped.
        let corrected = [
            (0, "7К000Е000000Д000000П00Ш00С00В00Н"),
            // The frame the seed meant: 24 mm is 4800 impulses, and then
            // its check digit 9 is right.
            (4, "9К004Е000000Д504800П44Н"),
            (7, "7К007Е603070Д000000П44Н"),
            // The leading-axis 4 on the only moving axis.
            (10, "8К010Е000000Д500564П54Н"),
            // 246 − 40.5 = 205.5 mm back, not 195.5.
            (11, "1К011Е120550Д523600П75Ш00В00Н"),
            // 11.05 mm is over 10 mm.
            (15, "0К015Е000000Д502210П75Н"),
            // 251 − 80 = 171 mm; 150 − 28.97 = 121.03 mm.
            (21, "9К021Е217100Д624206П75Ш26В01Н"),
            (23, "7К023Е000000Д500606П54Н"),
        ];
        let mut lines = out.lines();
        for n in 0..=30 {
            let want = corrected
                .iter()
                .find(|(k, _)| *k == n)
                .map_or_else(|| fold(seed_row(n)), |(_, s)| String::from(*s));
            assert_eq!(lines.next(), Some(want.as_str()), "К{n:03}");
        }
        assert_eq!(lines.next(), None);
        // And the result verifies clean.
        let (found, summary) = verify(&out);
        assert_eq!(found, []);
        assert_eq!(summary.frames, 31);
    }

    #[test]
    fn seed_program_encodes_from_its_own_impulses() {
        // Read every move back from the printed tape and encode it again:
        // only the slips that do not concern the impulses differ.
        let mut enc = Bck5Encoder::new(0);
        for (n, row) in SEED_TAPE.lines().enumerate().take(31) {
            let f = Bck5Frame::parse(row).unwrap();
            let block = if f.end() == FrameEnd::Program {
                Bck5Block::End
            } else {
                let imp =
                    |m: Option<MotionWord>| Travel::Impulses(m.map_or(0, MotionWord::impulses));
                let feed = match f.feed() {
                    None => Bck5Feed::Keep,
                    Some(Feed::Off) => Bck5Feed::Off,
                    Some(Feed::Rapid) => Bck5Feed::Rapid,
                    Some(Feed::Code(c)) if c == FeedCode::APPROACH => Bck5Feed::Rapid,
                    Some(Feed::Code(c)) => {
                        // The seed's feeds at 550 rpm.
                        let s = match c.value() {
                            44 => 0.25,
                            41 => 0.1,
                            31 => 0.05,
                            v => panic!("{v}"),
                        };
                        Bck5Feed::PerRev(FeedPerRev {
                            n_rpm: 550.0,
                            s_mm_per_rev: s,
                        })
                    }
                };
                let mut m = Bck5Move::new(imp(f.carriage()), imp(f.cross()), feed);
                m.spindle = f.spindle();
                m.tool = f.tool();
                m.coolant = f.coolant();
                Bck5Block::Move(m)
            };
            let out = enc.frame(&block).unwrap();
            let same = text(out) == fold(row);
            assert_eq!(same, ![0, 4, 7, 10, 15].contains(&n), "К{n:03}: {out}");
        }
    }

    // ───────── BCK-5: feed codes ─────────

    #[test]
    fn feed_code_frequencies() {
        // F_1…F_4 at a = 3, as the seed's Table 24 prints them.
        let f = |a, b| FeedCode::new(a, b).unwrap().frequency_hz();
        assert_eq!(
            [f(3, 1), f(3, 2), f(3, 3), f(3, 4)],
            [43.4, 50.0, 73.0, 122.5]
        );
        assert_eq!(f(0, 1), 43.4 / 8.0);
        assert_eq!(f(7, 4), 1960.0);
        assert_eq!(f(4, 1), 86.8);
        assert_eq!(f(2, 4), 61.25);
        assert_eq!(f(5, 3), 292.0);
        assert_eq!(FeedCode::new(4, 4).unwrap().value(), 44);
        for a in 0..=9u8 {
            for b in 0..=9u8 {
                let valid = a <= 7 && (1..=4).contains(&b);
                assert_eq!(FeedCode::new(a, b).is_some(), valid);
                let word = Feed::from_code(a * 10 + b);
                let expected = valid || (a, b) == (0, 0) || (a, b) == (7, 5);
                assert_eq!(word.is_some(), expected, "{a}{b}");
                if let Some(w) = word {
                    assert_eq!(w.code(), a * 10 + b);
                }
            }
        }
    }

    #[test]
    fn feed_code_nearest() {
        let at = |n, s| {
            FeedCode::nearest(FeedPerRev {
                n_rpm: n,
                s_mm_per_rev: s,
            })
            .map(FeedCode::value)
        };
        // The seed: 0.25 mm/rev at 550 rpm code 44 (229 Hz: 245 is nearer
        // than 200), 0.1 code 41 (91.7 Hz: 86.8), 0.05 code 31 (45.8 Hz: 43.4).
        assert_eq!(at(550.0, 0.25), Ok(44));
        assert_eq!(at(550.0, 0.1), Ok(41));
        assert_eq!(at(550.0, 0.05), Ok(31));
        // Exactly on a frequency, and far outside the range.
        assert_eq!(at(600.0, 0.1225), Ok(34)); // 122.5 Hz
        assert_eq!(at(0.001, 0.001), Ok(1));
        assert_eq!(at(100_000.0, 10.0), Ok(74));
        // Nearest indeed: no code is closer than the one chosen.
        for n in [70.0, 140.0, 199.0, 398.0, 550.0, 1290.0, 1780.0] {
            for k in 1..=14 {
                let s = 0.05 * f64::from(k);
                let target = n * s / 0.6;
                let chosen = FeedCode::nearest(FeedPerRev {
                    n_rpm: n,
                    s_mm_per_rev: s,
                })
                .unwrap();
                for a in 0..=7 {
                    for b in 1..=4 {
                        let other = FeedCode::new(a, b).unwrap();
                        assert!(
                            (chosen.frequency_hz() - target).abs()
                                <= (other.frequency_hz() - target).abs()
                        );
                    }
                }
            }
        }
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(at(bad, 0.1), Err(TapeError::NotPositive));
            assert_eq!(at(550.0, bad), Err(TapeError::NotPositive));
        }
        assert_eq!(at(1e200, 1e200), Err(TapeError::NotPositive));
    }

    #[test]
    fn rapid_index_by_path_length() {
        let rapid = |e: i32, d: i32| {
            let mut enc = Bck5Encoder::new(1);
            let m = Bck5Move::new(Travel::Impulses(e), Travel::Impulses(d), Bck5Feed::Rapid);
            enc.frame(&Bck5Block::Move(m)).unwrap().feed()
        };
        let approach = Some(Feed::Code(FeedCode::APPROACH));
        // The seed: 2.21 mm (К003) and 1.21 mm (К005) П54; 50 mm (К016) П75.
        assert_eq!(rapid(-221, 0), approach);
        assert_eq!(rapid(121, 0), approach);
        assert_eq!(rapid(-5_000, 0), Some(Feed::Rapid));
        // 10 mm exactly is «up to 10 mm», on either axis or diagonally.
        assert_eq!(rapid(1_000, 0), approach);
        assert_eq!(rapid(0, -2_000), approach);
        assert_eq!(rapid(600, 1_600), approach); // 6 mm and 8 mm
        assert_eq!(rapid(1_001, 0), Some(Feed::Rapid));
        assert_eq!(rapid(0, 2_001), Some(Feed::Rapid));
        assert_eq!(rapid(600, 1_601), Some(Feed::Rapid));
        assert_eq!(rapid(99_999, 99_999), Some(Feed::Rapid));
    }

    // ───────── BCK-5: the encoder ─────────

    #[test]
    fn encoder_leading_axis_and_tie() {
        let frame = |e, d| {
            let m = Bck5Move::new(Travel::Impulses(e), Travel::Impulses(d), Bck5Feed::Keep);
            text(Bck5Encoder::new(13).frame(&Bck5Block::Move(m)).unwrap())
        };
        // К013: 18111 on Е against 18000 on Д: Е leads.
        assert_eq!(frame(-18_111, -18_000), "0К013Е618111Д218000Н");
        assert_eq!(frame(500, 500), "3К013Е500500Д100500Н");
        assert_eq!(frame(0, 0), "9К013Е000000Д000000Н");
        assert_eq!(frame(0, -7), "6К013Е000000Д600007Н");
    }

    #[test]
    fn encoder_carries_the_remainder() {
        // Kosenko's 0.013 mm on the cross slide: 2.6 impulses each; the
        // positions land on Q(k·2.6): 3, 5, 8, 10, 13.
        let mut enc = Bck5Encoder::new(1);
        let mut counts = Vec::new();
        for _ in 0..5 {
            let m = Bck5Move::new(Travel::Impulses(0), Travel::Mm(mm("0.013")), Bck5Feed::Keep);
            counts.push(
                enc.frame(&Bck5Block::Move(m))
                    .unwrap()
                    .cross()
                    .unwrap()
                    .impulses(),
            );
        }
        assert_eq!(counts, [3, 2, 3, 2, 3]);
        // Ties round away from zero: 0.005 on the carriage is half an impulse.
        let mut enc = Bck5Encoder::new(1);
        let half = |enc: &mut Bck5Encoder, s| {
            let m = Bck5Move::new(Travel::Mm(mm(s)), Travel::Impulses(0), Bck5Feed::Keep);
            enc.frame(&Bck5Block::Move(m))
                .unwrap()
                .carriage()
                .unwrap()
                .impulses()
        };
        assert_eq!(half(&mut enc, "0.005"), 1);
        assert_eq!(half(&mut enc, "0.005"), 0);
        assert_eq!(half(&mut enc, "-0.01"), -1);
        // Impulses issue as they are, and mm moves continue from there.
        let mut enc = Bck5Encoder::new(1);
        let mixed = |enc: &mut Bck5Encoder, t| {
            let m = Bck5Move::new(t, Travel::Impulses(0), Bck5Feed::Keep);
            enc.frame(&Bck5Block::Move(m))
                .unwrap()
                .carriage()
                .unwrap()
                .impulses()
        };
        assert_eq!(mixed(&mut enc, Travel::Mm(mm("0.004"))), 0);
        assert_eq!(mixed(&mut enc, Travel::Impulses(7)), 7);
        assert_eq!(mixed(&mut enc, Travel::Mm(mm("0.002"))), 1);
        assert_eq!(mixed(&mut enc, Travel::Mm(mm("-0.076"))), -8);
    }

    #[test]
    fn encoder_errors_leave_it_unchanged() {
        let mut enc = Bck5Encoder::new(998);
        let before = enc;
        let too_far = Bck5Move::new(
            Travel::Impulses(100_000),
            Travel::Impulses(0),
            Bck5Feed::Keep,
        );
        assert_eq!(
            enc.frame(&Bck5Block::Move(too_far)),
            Err(TapeError::WordRange)
        );
        let too_far = Bck5Move::new(Travel::Impulses(0), Travel::Mm(mm("500")), Bck5Feed::Keep);
        assert_eq!(
            enc.frame(&Bck5Block::Move(too_far)),
            Err(TapeError::WordRange)
        );
        let beyond = Bck5Move::new(Travel::Mm(mm("99999")), Travel::Impulses(0), Bck5Feed::Keep);
        assert!(enc.frame(&Bck5Block::Move(beyond)).is_err());
        let mut code = Bck5Move::tool_change(100);
        assert_eq!(enc.frame(&Bck5Block::Move(code)), Err(TapeError::WordRange));
        code.tool = Some(1);
        code.spindle = Some(200);
        assert_eq!(enc.frame(&Bck5Block::Move(code)), Err(TapeError::WordRange));
        code.spindle = None;
        code.coolant = Some(100);
        assert_eq!(enc.frame(&Bck5Block::Move(code)), Err(TapeError::WordRange));
        let bad_feed = Bck5Move::new(
            Travel::Impulses(5),
            Travel::Impulses(0),
            Bck5Feed::PerRev(FeedPerRev {
                n_rpm: 550.0,
                s_mm_per_rev: -0.1,
            }),
        );
        assert_eq!(
            enc.frame(&Bck5Block::Move(bad_feed)),
            Err(TapeError::NotPositive)
        );
        assert_eq!(enc, before);
        // 998, 999, then no more numbers.
        assert_eq!(enc.frame(&Bck5Block::End).unwrap().number(), 998);
        assert_eq!(enc.frame(&Bck5Block::End).unwrap().number(), 999);
        assert_eq!(enc.frame(&Bck5Block::End), Err(TapeError::WordRange));
        let mut enc = Bck5Encoder::new(u16::MAX);
        assert_eq!(enc.frame(&Bck5Block::End), Err(TapeError::WordRange));
    }

    #[test]
    fn encode_reports_the_writer() {
        let blocks = [Bck5Block::End, Bck5Block::End];
        let mut small = heapless::String::<8>::new();
        assert_eq!(
            encode_bck5(&blocks, 30, Alphabet::Latin, &mut small),
            Err(TapeError::Write)
        );
        let mut s = String::new();
        assert_eq!(encode_bck5(&blocks, 30, Alphabet::Latin, &mut s), Ok(2));
        assert_eq!(s, "4K030R\n3K031R\n");
        assert_eq!(encode_bck5(&[], 0, Alphabet::Latin, &mut s), Ok(0));
    }

    // ───────── BCK-5: reading errors ─────────

    #[test]
    fn parse_errors_name_what_and_where() {
        use TapeError::*;
        let cases: [(&str, TapeError, u32); 26] = [
            ("", MissingCheckDigit, 1),
            ("   ", MissingCheckDigit, 4),
            ("K001Н", MissingCheckDigit, 1),
            ("ЖK001Н", UnknownCharacter, 1),
            ("5", MissingNumber, 2),
            ("55K001Н", MissingNumber, 2),
            ("5E001Н", MissingNumber, 2),
            ("5!001Н", UnknownCharacter, 2),
            ("5K", WordLength, 2),
            ("5KН", WordLength, 2),
            ("5K0001Н", WordLength, 2),
            ("5K001", MissingEnd, 6),
            ("5K001E000000", MissingEnd, 13),
            ("5K001E00000Н", WordLength, 6),
            ("5K001E0000000Н", WordLength, 6),
            ("5K001П5Н", WordLength, 6),
            ("5K001Д000000E000000Н", WordOrder, 13),
            ("5K001П00П00Н", WordOrder, 9),
            ("5K001K001Н", WordOrder, 6),
            ("5K001E300000Н", MotionCode, 6),
            ("5K001E000121Н", MotionCode, 6),
            ("5K001П45Н", FeedCode, 6),
            ("5K001П80Н", FeedCode, 6),
            ("5K001НН", AfterEnd, 7),
            ("5K001Н7", AfterEnd, 7),
            ("5K001Н?", UnknownCharacter, 7),
        ];
        for (line, error, column) in cases {
            assert_eq!(
                Bck5Frame::parse(line),
                Err(ParseError { error, column }),
                "{line:?}"
            );
        }
        // Columns count characters, not bytes; a tab is one.
        assert_eq!(
            Bck5Frame::parse("5\tК001\tЕ00000\tН"),
            Err(ParseError {
                error: WordLength,
                column: 8
            })
        );
        assert_eq!(
            text(ParseError {
                error: MotionCode,
                column: 6
            }),
            "column 6: motion word: code digit not 0, 1, 2, 5 or 6"
        );
    }

    #[test]
    fn parse_reads_all_words_in_any_alphabet() {
        let f =
            Bck5Frame::parse(" 9 k 12 e 500121 d 100564 t 200007 p 31 w 62 c 42 b 01 r ").unwrap();
        assert_eq!(f.number(), 12);
        assert_eq!(f.carriage().map(MotionWord::impulses), Some(121));
        assert!(f.carriage().unwrap().is_leading());
        assert_eq!(f.cross().map(MotionWord::impulses), Some(564));
        assert_eq!(f.third().map(MotionWord::impulses), Some(-7));
        assert_eq!(f.feed(), Some(Feed::Code(FeedCode::new(3, 1).unwrap())));
        assert_eq!(
            (f.spindle(), f.tool(), f.coolant()),
            (Some(62), Some(42), Some(1))
        );
        assert_eq!(f.end(), FrameEnd::Program);
        assert_eq!(
            frame_text(&f, Alphabet::Latin),
            "9K012E500121D100564T200007P31W62C42B01R"
        );
        // A direction with no impulses is kept as written (it counts in the sum).
        let f = Bck5Frame::parse("3K001E100000Н").unwrap();
        assert_eq!(
            (
                f.carriage().unwrap().code(),
                f.carriage().unwrap().impulses()
            ),
            (1, 0)
        );
        assert!(f.check_ok());
        assert_eq!(text(f), "3К001Е100000Н");
    }

    // ───────── BCK-5: the verifier ─────────

    /// A frame body (from К on) with the check digit it needs in front.
    fn checked(body: &str) -> String {
        let mut s = String::from("0");
        s.push_str(body);
        let c = Bck5Frame::parse(&s).unwrap().expected_check();
        s.replace_range(..1, &c.to_string());
        s
    }

    #[test]
    fn verifier_reports_unreadable_lines_and_numbering() {
        let tape = [
            checked("K001E000000D000000П00Ш00C01B00H"),
            String::new(),
            checked("K002E212400D630000П75Ш26Н"),
            String::from("2K003E2124"),
            checked("K004E112400D530000П75Н"),
            checked("K006Я"),
            checked("K005Н"),
        ];
        let (found, summary) = verify(&tape.join("\n"));
        assert_eq!(
            summary,
            Bck5Summary {
                lines: 7,
                frames: 5,
                findings: 3
            }
        );
        assert_eq!(
            found,
            [
                Bck5Finding::Unreadable {
                    line: 4,
                    error: ParseError {
                        error: TapeError::WordLength,
                        column: 6
                    }
                },
                Bck5Finding::Numbering {
                    line: 6,
                    frame: 6,
                    expected: 5
                },
                Bck5Finding::Numbering {
                    line: 7,
                    frame: 5,
                    expected: 7
                },
            ]
        );
        assert_eq!(
            text(found[0]),
            "line 4: column 6: word: wrong number of digits"
        );
        assert_eq!(
            text(found[1]),
            "K006 (line 6): out of sequence, K005 expected"
        );
        assert!(!summary.is_clean());
    }

    #[test]
    fn verifier_judges_tools_at_c_words_ya_and_the_end() {
        // No tool yet, then tool 05 closing on Т, then tool 07 open at the end.
        let mut v = Bck5Verifier::new();
        let mut found = Vec::new();
        for body in [
            "K001E100005Н",
            "K002E000000D000000П00Ш00C05B00H",
            "K003T100010Н",
            "K004T200010Н",
            "K005E000000D000000П00Ш00C07B00H",
            "K006E200003Н",
        ] {
            v.line(&checked(body), |f| found.push(f));
        }
        let summary = v.finish(|f| found.push(f));
        assert_eq!(summary.findings, 2);
        assert_eq!(
            found,
            [
                Bck5Finding::Closure {
                    tool: None,
                    first_frame: 1,
                    last_frame: 1,
                    axis: Bck5Axis::Carriage,
                    plus: 5,
                    minus: 0
                },
                Bck5Finding::Closure {
                    tool: Some(7),
                    first_frame: 5,
                    last_frame: 6,
                    axis: Bck5Axis::Carriage,
                    plus: 0,
                    minus: 3
                },
            ]
        );
        assert_eq!(
            text(found[0]),
            "no tool (K001-K001): E does not close, +5 -0"
        );
        // Т counts like the others; after Я no tool.
        let (found, _) = verify(&[checked("K001T100010Я"), checked("K002D100004Н")].join("\n"));
        assert_eq!(found.len(), 2);
        assert!(matches!(
            found[0],
            Bck5Finding::Closure {
                axis: Bck5Axis::Third,
                last_frame: 1,
                ..
            }
        ));
        assert!(matches!(
            found[1],
            Bck5Finding::Closure {
                axis: Bck5Axis::Cross,
                tool: None,
                first_frame: 2,
                ..
            }
        ));
        // An empty tape, and one of blank lines.
        assert_eq!(verify("").1, Bck5Summary::default());
        assert!(verify("\n \n\t").1.is_clean());
    }

    // ───────── ISO-7bit ─────────

    #[test]
    fn em907_codes_are_even() {
        // Every character the ЭМ-907 reads, as it is punched (hex: track 8
        // is bit 7).
        let table: [(u8, u8); 26] = [
            (b'%', 0xA5),
            (b':', 0x3A),
            (b'N', 0x4E),
            (b'/', 0xAF),
            (b'G', 0x47),
            (b'X', 0xD8),
            (b'Z', 0x5A),
            (b'I', 0xC9),
            (b'K', 0x4B),
            (b'F', 0xC6),
            (b'S', 0x53),
            (b'T', 0xD4),
            (b'M', 0x4D),
            (b'\n', 0x0A),
            (b'+', 0x2B),
            (b'-', 0x2D),
            (b'0', 0x30),
            (b'1', 0xB1),
            (b'2', 0xB2),
            (b'3', 0x33),
            (b'4', 0xB4),
            (b'5', 0x35),
            (b'6', 0x36),
            (b'7', 0xB7),
            (b'8', 0xB8),
            (b'9', 0x39),
        ];
        for ((c, punched), listed) in table.iter().zip(EM907_CHARSET) {
            assert_eq!(*c, listed);
            assert_eq!(iso7_parity(*c), Some(*punched), "{}", *c as char);
            assert_eq!(punched.count_ones() % 2, 0);
            assert_eq!(iso7_row(*punched), Ok(*c));
            assert!(em907_reads(*c));
        }
        for c in 0..=0x7Fu8 {
            let p = iso7_parity(c).unwrap();
            assert_eq!(p & 0x7F, c);
            assert_eq!(iso7_row(p), Ok(c));
            assert_eq!(iso7_row(p ^ 0x80), Err(TapeError::Parity));
        }
        for c in 0x80..=0xFFu8 {
            assert_eq!(iso7_parity(c), None);
        }
        assert!(!em907_reads(b'J') && !em907_reads(b' ') && !em907_reads(b'x'));
    }

    #[test]
    fn seed_iso_table_as_printed() {
        // The seed's table of ISO-7bit codes, row by row as printed: its
        // label and the holes it shows (tracks 8…1).
        let printed: [(&str, u8); 26] = [
            ("%", 0xA5),
            (".", 0x3A),
            ("K", 0x4E),
            ("/", 0xAF),
            ("G", 0x47),
            ("x", 0xD8),
            ("Z", 0x5A),
            ("J", 0xC9),
            ("K", 0x4B),
            ("F", 0xC6),
            ("S", 0x53),
            ("T", 0xD4),
            ("M", 0x4D),
            ("LF", 0x0A),
            ("+", 0x2B),
            ("-", 0x2D),
            ("0", 0x30),
            ("1", 0xB1),
            ("2", 0xB2),
            ("3", 0x33),
            ("4", 0xB4),
            ("5", 0x37),
            ("6", 0x37),
            ("7", 0xB7),
            ("8", 0xB8),
            ("9", 0x39),
        ];
        let mut misprints = Vec::new();
        for ((label, row), right) in printed.iter().zip(EM907_CHARSET) {
            match iso7_row(*row) {
                Ok(c) if c == right => {}
                other => misprints.push((*label, other)),
            }
        }
        // "5" and "6" are printed with five holes and no track 8: odd.
        // Their codes are 0x35 and 0x36, four holes, no track 8.
        assert_eq!(
            misprints,
            [("5", Err(TapeError::Parity)), ("6", Err(TapeError::Parity))]
        );
        assert_eq!(iso7_parity(b'5'), Some(0x35));
        assert_eq!(iso7_parity(b'6'), Some(0x36));
        // The row labelled "J" is punched as I (J would be 0xCA).
        assert_eq!(iso7_row(0xC9), Ok(b'I'));
        assert_eq!(iso7_parity(b'J'), Some(0xCA));
        // Labels the seed misprints with the holes right: "." is ':', the
        // first "K" is N, "x" is X.
        assert_eq!(iso7_row(0x3A), Ok(b':'));
        assert_eq!(iso7_row(0x4E), Ok(b'N'));
        assert_eq!(iso7_row(0xD8), Ok(b'X'));
    }

    fn block(s: &str) -> Iso7Block {
        Iso7Block::parse(s).unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    #[test]
    fn seed_arc_block_from_its_inputs() {
        // Table 31, N032: ΔX = 3 mm (radius), ΔZ = −11.9 mm, J = 4397 and
        // K = 1190 impulses (the text), S₀ = 0.05 mm/rev at 710 rpm (S44).
        let arc = Em907Move {
            x: Travel::Mm(mm("3")),
            z: Travel::Mm(mm("-11.9")),
            motion: Em907Motion::Arc {
                clockwise: false,
                i: Travel::Impulses(4397),
                k: Travel::Impulses(1190),
                feed: FeedPerRev {
                    n_rpm: 710.0,
                    s_mm_per_rev: 0.05,
                },
            },
        };
        let b = Em907Encoder::new(32)
            .block(&arc)
            .unwrap()
            .with_s(44)
            .unwrap();
        assert_eq!(text(b), "N032G03X+600Z-1190I4397K1190F1420S44");
        // The seed's print, whose J is the I address.
        let printed = "N032 G 03 X+600 Z-1190 J4397 K1190 F 1420 S 44";
        assert_eq!(block(printed), b);
        assert_eq!(
            text(block(printed)).replace('I', "J"),
            printed.replace(' ', "")
        );
        // R from I and K: √(21.985² + 11.9²) = 24.999 mm; F = 35.5·10³/R.
        assert_eq!(em907_feed_word(35.5, 24.999), Ok(1420));
        // The same centre given in mm.
        let in_mm = Em907Move {
            motion: Em907Motion::Arc {
                clockwise: true,
                i: Travel::Mm(mm("-21.985")),
                k: Travel::Mm(mm("11.9")),
                feed: FeedPerRev {
                    n_rpm: 710.0,
                    s_mm_per_rev: 0.05,
                },
            },
            ..arc
        };
        assert_eq!(
            text(Em907Encoder::new(32).block(&in_mm).unwrap()),
            "N032G02X+600Z-1190I4397K1190F1420"
        );
    }

    #[test]
    fn seed_table_31_blocks() {
        let mut enc = Em907Encoder::new(1);
        let go = |enc: &mut Em907Encoder, x: &str, z: &str, motion| {
            enc.block(&Em907Move {
                x: Travel::Mm(mm(x)),
                z: Travel::Mm(mm(z)),
                motion,
            })
            .unwrap()
        };
        let feed = |s, n| FeedPerRev {
            n_rpm: n,
            s_mm_per_rev: s,
        };
        // N001: point 1 (X 100) to 2 (X 25.33) rapid, S42 T500 M03 M06 M07 M12.
        let n001 = go(&mut enc, "-74.67", "0", Em907Motion::Rapid);
        let n001 = n001.with_s(42).and_then(|b| b.with_t(500)).unwrap();
        let n001 = [3, 6, 7, 12]
            .iter()
            .fold(n001, |b, m| b.with_m(*m).unwrap());
        assert_eq!(text(n001), "N001G00X-14934S42T500M03M06M07M12");
        assert_eq!(block("N001 G 00 X-14934 S 42 T 500 M03 M06 M07 M 12"), n001);
        // N002: Z 203 → 58 at 0.3 mm/rev, 560 rpm: F = 168·10³/145 = 1159
        // (printed «F 160»; ΔZ printed −14,5).
        assert_eq!(
            text(go(
                &mut enc,
                "0",
                "-145",
                Em907Motion::Linear(feed(0.3, 560.0))
            )),
            "N002G01Z-14500F1159"
        );
        // N017: X 17.83 → 20.33, Z 145 → 119 at 0.3 mm/rev, 710 rpm:
        // l = √(2.5² + 26²) = 26.12 mm, F = 213·10³/26.12 = 8155 (printed
        // 8050; the seed's l = 26.5 would give 8038).
        let mut enc = Em907Encoder::new(17);
        assert_eq!(
            text(go(
                &mut enc,
                "2.5",
                "-26",
                Em907Motion::Linear(feed(0.3, 710.0))
            )),
            "N017G01X+500Z-2600F8155"
        );
        assert_eq!(em907_feed_word(0.3 * 710.0, 26.5), Ok(8038));
        // N018: Z 119 → 201 rapid, S48.
        assert_eq!(
            text(
                go(&mut enc, "0", "82", Em907Motion::Rapid)
                    .with_s(48)
                    .unwrap()
            ),
            "N018G00Z+8200S48"
        );
        // N033: Z −30.1 at 0.05 mm/rev, 710 rpm: F = 35.5·10³/30.1 = 1179
        // (printed «F 180»).
        let mut enc = Em907Encoder::new(33);
        assert_eq!(
            text(go(
                &mut enc,
                "0",
                "-30.1",
                Em907Motion::Linear(feed(0.05, 710.0))
            )),
            "N033G01Z-3010F1179"
        );
        // N036–N039: rapids and a tool change.
        let mut enc = Em907Encoder::new(36);
        let n036 = go(&mut enc, "0", "-13.5", Em907Motion::Rapid)
            .with_t(702)
            .and_then(|b| b.with_m(6))
            .unwrap();
        assert_eq!(text(n036), "N036G00Z-1350T702M06");
        assert_eq!(
            text(go(&mut enc, "-85.62", "0", Em907Motion::Rapid)),
            "N037G00X-17124"
        );
        // N038 is a G08 thread (read, not encoded here).
        let n038 = block("N038 G 08 Z-4000");
        assert_eq!((n038.g(), n038.z()), (Some(8), Some(-4000)));
        let mut enc = Em907Encoder::new(39);
        assert_eq!(
            text(go(&mut enc, "1.12", "0", Em907Motion::Rapid)),
            "N039G00X+224"
        );
        // The seed's other printed blocks read as they are.
        for printed in [
            "N002 G 01 Z-14500 F 160",
            "N017 G 01 X+500 Z-2600 F 8050",
            "N018 G 00 Z+8200 S 48",
            "N033 G 01 Z-3010 F 180",
            "N036 G 00 Z-1350 T 702 M06",
            "N037 G 00 X-17124",
            "N039 G 00 X+224",
        ] {
            let b = block(printed);
            assert_eq!(text(b), printed.replace(' ', ""));
        }
    }

    #[test]
    fn iso_block_words() {
        let b = block(":007G04X130000M00M01M02M03M05M30");
        assert_eq!(b.start(), BlockStart::RewindStop);
        assert_eq!(b.number(), 7);
        assert_eq!(b.x(), Some(130_000));
        assert_eq!(b.m(), [0, 1, 2, 3, 5, 30]);
        assert_eq!(text(b), ":007G04X+130000M00M01M02M03M05M30");
        assert_eq!(b.with_m(4), Err(TapeError::WordRange));
        let b = block("/010");
        assert_eq!((b.start(), b.g(), b.m()), (BlockStart::Skip, None, &[][..]));
        assert_eq!(text(b), "/010");
        let b = block("N011G06Z100K250S22T050");
        assert_eq!(
            (b.z(), b.k(), b.s(), b.t(), b.i(), b.f()),
            (Some(100), Some(250), Some(22), Some(50), None, None)
        );
        assert_eq!(text(b), "N011G06Z+100K250S22T050");
        assert_eq!(block("N001").with_s(100), Err(TapeError::WordRange));
        assert_eq!(block("N001").with_t(1000), Err(TapeError::WordRange));
        assert_eq!(block("N001").with_m(100), Err(TapeError::WordRange));
    }

    #[test]
    fn iso_parse_errors() {
        use TapeError::*;
        let cases: [(&str, TapeError, u32); 20] = [
            ("", MissingNumber, 1),
            ("G01", MissingNumber, 1),
            ("%", MissingNumber, 1),
            ("n001", UnknownCharacter, 1),
            ("N01", WordLength, 1),
            ("N0001", WordLength, 1),
            ("N001Y5", UnknownCharacter, 5),
            ("N001G1X5", WordLength, 5),
            ("N001X5G01", WordOrder, 7),
            ("N001X5X5", WordOrder, 7),
            ("N001G00X", WordLength, 8),
            ("N001G00X+1234567", WordLength, 8),
            ("N001G00X-130001", WordRange, 8),
            ("N001G02X1Z1I-5K5F1", WordLength, 12),
            ("N001G01X1F0", WordRange, 10),
            ("N001G01X1F130001", WordRange, 10),
            ("N001G00", MissingWord, 5),
            ("N001G01X1", MissingWord, 10),
            ("N001G00X1+", WordOrder, 10),
            ("N001M01M02M03M04M05M06M07", WordRange, 23),
        ];
        for (line, error, column) in cases {
            assert_eq!(
                Iso7Block::parse(line),
                Err(ParseError { error, column }),
                "{line:?}"
            );
        }
    }

    #[test]
    fn em907_feed_word_range() {
        assert_eq!(em907_feed_word(168.0, 145.0), Ok(1159));
        assert_eq!(em907_feed_word(0.5, 1000.0), Ok(1)); // 0.5 rounds up
        assert_eq!(em907_feed_word(0.4, 1000.0), Err(TapeError::WordRange));
        assert_eq!(em907_feed_word(130.0, 1.0), Ok(130_000));
        assert_eq!(em907_feed_word(130.001, 1.0), Err(TapeError::WordRange));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(em907_feed_word(bad, 1.0), Err(TapeError::NotPositive));
            assert_eq!(em907_feed_word(1.0, bad), Err(TapeError::NotPositive));
        }
    }

    #[test]
    fn em907_encoder_errors_leave_it_unchanged() {
        let mut enc = Em907Encoder::new(999);
        let before = enc;
        let mv = |x, z, motion| Em907Move { x, z, motion };
        let feed = FeedPerRev {
            n_rpm: 710.0,
            s_mm_per_rev: 0.05,
        };
        let none = Travel::Impulses(0);
        assert_eq!(
            enc.block(&mv(none, none, Em907Motion::Rapid)),
            Err(TapeError::NoMotion)
        );
        assert_eq!(
            enc.block(&mv(Travel::Impulses(130_001), none, Em907Motion::Rapid)),
            Err(TapeError::WordRange)
        );
        assert_eq!(
            enc.block(&mv(
                none,
                Travel::Impulses(5),
                Em907Motion::Linear(FeedPerRev { n_rpm: 0.0, ..feed })
            )),
            Err(TapeError::NotPositive)
        );
        let arc = |i, k| Em907Motion::Arc {
            clockwise: true,
            i,
            k,
            feed,
        };
        assert_eq!(
            enc.block(&mv(Travel::Impulses(5), none, arc(none, none))),
            Err(TapeError::NotPositive)
        );
        assert_eq!(
            enc.block(&mv(
                Travel::Impulses(5),
                none,
                arc(Travel::Impulses(-130_001), none)
            )),
            Err(TapeError::WordRange)
        );
        assert_eq!(enc, before);
        assert!(enc
            .block(&mv(Travel::Impulses(-130_000), none, Em907Motion::Rapid))
            .is_ok());
        assert_eq!(
            enc.block(&mv(Travel::Impulses(1), none, Em907Motion::Rapid)),
            Err(TapeError::WordRange)
        );
        let mut s = heapless::String::<4>::new();
        let moves = [mv(Travel::Impulses(1), none, Em907Motion::Rapid)];
        assert_eq!(encode_iso7(&moves, 1, &mut s), Err(TapeError::Write));
    }

    // ───────── errors ─────────

    #[test]
    fn every_error_has_an_ascii_text() {
        use TapeError::*;
        let all = [
            UnknownCharacter,
            MissingCheckDigit,
            MissingNumber,
            WordLength,
            WordOrder,
            MotionCode,
            FeedCode,
            MissingEnd,
            AfterEnd,
            MissingWord,
            WordRange,
            Parity,
            NotPositive,
            NoMotion,
            Write,
        ];
        let mut seen: Vec<&str> = Vec::new();
        for e in all {
            let s = e.as_str();
            assert!(s.is_ascii() && !s.is_empty());
            assert_eq!(text(e), s);
            assert!(!seen.contains(&s));
            seen.push(s);
        }
        assert_eq!(
            e_to_string(ParseError {
                error: Parity,
                column: 3
            }),
            "column 3: row: odd number of holes"
        );
    }

    fn e_to_string(e: ParseError) -> String {
        e.to_string()
    }

    proptest::proptest! {
        #[test]
        fn any_line_parses_or_fails_without_panic(line in "\\PC{0,40}") {
            let _ = Bck5Frame::parse(&line);
            let _ = Iso7Block::parse(&line);
            let mut v = Bck5Verifier::new();
            v.line(&line, |_| {});
            let _ = v.finish(|_| {});
        }

        #[test]
        fn tape_like_lines_never_panic(line in "[0-9KEDTPWCBHRКЕДТПШСВНЯNGXZIJFSM+\\-:/ \t]{0,40}") {
            if let Ok(f) = Bck5Frame::parse(&line) {
                // What reads back writes back to the same frame.
                proptest::prop_assert_eq!(Bck5Frame::parse(&text(f)), Ok(f));
                let mut latin = String::new();
                f.write(&mut latin, Alphabet::Latin).unwrap();
                proptest::prop_assert!(latin.is_ascii());
                proptest::prop_assert_eq!(Bck5Frame::parse(&latin), Ok(f));
            }
            if let Ok(b) = Iso7Block::parse(&line) {
                proptest::prop_assert_eq!(Iso7Block::parse(&text(b)), Ok(b));
            }
        }

        #[test]
        fn encoded_frames_always_check(e in -99_999i32..=99_999, d in -99_999i32..=99_999, s in 0.01f64..1.0, n in 10.0f64..2000.0) {
            let mut m = Bck5Move::new(Travel::Impulses(e), Travel::Impulses(d), Bck5Feed::PerRev(FeedPerRev { n_rpm: n, s_mm_per_rev: s }));
            m.spindle = Some(26);
            let f = Bck5Encoder::new(5).frame(&Bck5Block::Move(m)).unwrap();
            proptest::prop_assert!(f.check_ok());
            proptest::prop_assert_eq!(Bck5Frame::parse(&text(f)), Ok(f));
            proptest::prop_assert_eq!(f.carriage().map(MotionWord::impulses), Some(e));
            proptest::prop_assert_eq!(f.cross().map(MotionWord::impulses), Some(d));
        }
    }
}

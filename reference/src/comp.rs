//! Double-precision (f64) reference of tool-nose-radius compensation
//! (`G41`/`G42`/`G40`) on G-code contours.
//!
//! Written from `docs/units.md` §1, `docs/compensation.md` (the rule set of
//! §1–§6, followed rule by rule; the figures of §8 and the errata of
//! `docs/errata.md` §1) and the G-code blocks of `docs/protocol.md` §5 alone, independently of the controller's fixed-point
//! core, so that the two can be compared block by block. It does not call the
//! core crate.
//!
//! # Frame and numbers
//!
//! * Geometry is on the radius in the plane drawn with Z to the right and X
//!   up; a point is held as `(z, x)` and `G03` is counter-clockwise in that
//!   picture. The left normal of a direction `t = (tz, tx)` is `(−tx, tz)`,
//!   the right normal `(tx, −tz)`.
//! * Programmed points are exact: words are parsed to whole units of
//!   10⁻⁷ mm (a diameter word of at most 6 decimals halves without loss), so
//!   "end point equal to start point" and the radius checks of an `I`/`K` arc
//!   are decided in integers. Everything compensated is computed in f64 and
//!   not rounded, except where a rule speaks of rounding: a move whose two
//!   ends coincide after rounding to 10⁻⁷ mm is left out, and the printed
//!   text ([`RefBlock::text`]) rounds each point to 10⁻⁷ mm and then to four
//!   decimals, as the device does.
//!
//! # The state machine ([`RefContour`])
//!
//! Power-on: programmed and actual position `X0 Z0`, `G00 G90 G40 G451`.
//! [`RefContour::block`] runs one line and returns the theoretical-tool-tip
//! (TTT) blocks it releases; with compensation on these belong to the
//! previous element (one block of look-ahead). A refused line changes
//! nothing (the machine runs on a copy that is kept only on success).
//!
//! * Compensation off: a block with an `X` or `Z` word (and, for an arc, an
//!   `I`, `K` or `R` word) sends one TTT block to the programmed end point at
//!   once, even when it does not move (one `DATA` per motion block).
//! * `G41`/`G42` arms compensation; the first motion block that moves is the
//!   start-up block (it must be `G00`/`G01`). It is sent when the next
//!   element arrives, ending at `P + r·n2 + tip` (Fanuc type A), or, when a
//!   `G40` follows it directly, at `P + r·n + tip` with its own normal.
//! * With compensation active each element is held until the next element
//!   (or `G40`, or [`RefContour::finish`]) fixes its end through the corner
//!   rules of `docs/compensation.md`: smooth, inside (intersection of the full
//!   offset line/circle nearest to the programmed corner), outside `G451`
//!   (tangent vertex up to 90°, square-off beyond, arcs never lengthened) or
//!   `G450` (transition arc of radius `r` about the corner). Then the element
//!   and the corner's inserted moves are sent together.
//! * Blocks that do not move (no `X`/`Z`, an arc without `I`/`K`/`R`, or a
//!   line to its own start point) are passed over: they change only modal
//!   state.
//!
//! # Readings of the rule set
//!
//! Where `docs/compensation.md` leaves a detail open, this module reads it as
//! follows (the tests pin these readings):
//!
//! * `G450`/`G451` take effect for the corner that ends at the block holding
//!   them (the corner mode in force after a block's words is the one used for
//!   the corner between the pending element and that block's element).
//! * "Too short": a line is short when its compensated end, rounded to
//!   10⁻⁷ mm, equals its rounded start, or when `(end − start)·t ≤ 0`. An arc
//!   is short when its rounded compensated ends coincide (unless it was
//!   programmed as a full circle), or when its compensated sweep exceeds the
//!   programmed sweep by more than [`SWEEP_SLACK_MM`] `+ r·2⁻²¹` (2·10⁻⁷ mm
//!   plus `r·2⁻²¹`) of arc length on the offset circle, the excess angle
//!   taken on the smaller of the offset radii at the arc's two ends, as
//!   `docs/compensation.md` says. The slack is a length, whatever the arc's
//!   radius: it absorbs f64 noise, the core's rounding of both ends to
//!   10⁻⁷ mm (at most √2/2·10⁻⁷ mm along the arc each) and the start mismatch
//!   a smooth corner allows (below `r·2⁻²²`), none of which is a reversal.
//!   The start-up block itself is not checked (its direction is not the
//!   programmed one).
//! * A `G40` block with an `X` or `Z` word always sends its uncompensated
//!   move, even when the programmed point does not change. `G40` while only
//!   armed (no start-up block yet) just disarms; the motion of that block then
//!   runs uncompensated (an arc is allowed there).
//! * [`RefContour::finish`] never refuses: the pending element is sent as
//!   `G40` without motion would send it, without the too-short check.
//! * The concave-arc test uses both the start and the end radius of an
//!   `I`/`K` arc; an `R` arc has the radius of its word.
//! * An `R` arc whose chord is longer than `2·|R|` by more than 10⁻⁹ mm is
//!   refused; up to that it is a half circle. The `R` centre's distance from
//!   the chord comes from `4R² − chord²` taken exactly in (10⁻⁷ mm)² (so a
//!   half circle's centre is the chord's midpoint); the centre is not
//!   rounded to 10⁻⁷ mm (the core rounds it; the difference is below
//!   5·10⁻⁸ mm).
//! * `I`, `K` or `R` in a linear block, and `R` together with `I`/`K`, are
//!   refused (`SYNTAX`).
//! * An inside corner between a line and an arc is intersected from the
//!   corner (`line_circle`), not from the circle's centre: near a smooth
//!   corner the two offset elements are nearly tangent, and the centre-based
//!   form loses the intersection's position along them in the difference
//!   of two squared radii (by more than the arc check's slack on large arcs,
//!   or when the line is long). Two circles are still intersected from their
//!   centres.

use std::f64::consts::PI;
use std::fmt;
use std::ops::{Add, Mul, Neg, Sub};

/// Units of 10⁻⁷ mm per mm.
const UNITS_PER_MM: f64 = 1e7;
/// Millionths of a mm in a word are below this (|word| < 100 000 mm).
const MICRO_LIMIT: i64 = 100_000 * 1_000_000;
/// Largest commanded coordinate, in 10⁻⁷ mm (99 999.999999 mm).
const COORD_MAX_UNITS: i64 = 999_999_999_990;
/// Largest accepted difference of an arc's start and end radii, 10⁻⁷ mm.
const RADIUS_MISMATCH_UNITS: i128 = 20_000;
/// `2⁻²²`: the smooth-corner limit on `|sin θ|`.
const SMOOTH_SIN: f64 = 1.0 / 4_194_304.0;
/// Largest accepted nose radius, mm.
const RN_MAX_MM: f64 = 25.0;
/// Chord of an `R` arc may exceed `2·|R|` by this much (mm) and still be a
/// half circle.
const R_CHORD_SLACK_MM: f64 = 1e-9;

/// Fixed part of the slack (mm of arc length on the offset circle) by which
/// an arc's compensated sweep may exceed its programmed sweep before the arc
/// is too short for the nose: two steps of the 10⁻⁷ mm grid. `r·2⁻²¹` is
/// added to it ([`sweep_slack_mm`]).
pub const SWEEP_SLACK_MM: f64 = 2e-7;

/// The slack (mm of arc length on the offset circle, measured on the smaller
/// of the offset radii at the arc's two ends) by which an arc's compensated
/// sweep may exceed its programmed sweep, for nose radius `r_mm`:
/// [`SWEEP_SLACK_MM`]` + r·2⁻²¹`.
pub fn sweep_slack_mm(r_mm: f64) -> f64 {
    SWEEP_SLACK_MM + r_mm * 2.0 * SMOOTH_SIN
}

/// A point or direction in the (Z right, X up) plane, mm on the radius.
#[derive(Clone, Copy, Debug, PartialEq)]
struct V2 {
    z: f64,
    x: f64,
}

impl V2 {
    const ZERO: V2 = V2 { z: 0.0, x: 0.0 };

    fn new(z: f64, x: f64) -> Self {
        V2 { z, x }
    }

    fn dot(self, o: V2) -> f64 {
        self.z * o.z + self.x * o.x
    }

    /// `self × o`, positive when `o` is counter-clockwise (left) of `self`.
    fn cross(self, o: V2) -> f64 {
        self.z * o.x - self.x * o.z
    }

    fn len(self) -> f64 {
        self.z.hypot(self.x)
    }

    /// Rotated by +90° (the left normal of a direction).
    fn left(self) -> V2 {
        V2::new(-self.x, self.z)
    }

    fn unit(self) -> V2 {
        self * (1.0 / self.len())
    }

    /// The point rounded to whole 10⁻⁷ mm, `(x, z)`.
    fn rounded_units(self) -> (i64, i64) {
        (to_units(self.x), to_units(self.z))
    }
}

impl Add for V2 {
    type Output = V2;
    fn add(self, o: V2) -> V2 {
        V2::new(self.z + o.z, self.x + o.x)
    }
}

impl Sub for V2 {
    type Output = V2;
    fn sub(self, o: V2) -> V2 {
        V2::new(self.z - o.z, self.x - o.x)
    }
}

impl Mul<f64> for V2 {
    type Output = V2;
    fn mul(self, k: f64) -> V2 {
        V2::new(self.z * k, self.x * k)
    }
}

impl Neg for V2 {
    type Output = V2;
    fn neg(self) -> V2 {
        V2::new(-self.z, -self.x)
    }
}

/// mm → nearest whole 10⁻⁷ mm, ties away from zero.
fn to_units(v_mm: f64) -> i64 {
    (v_mm * UNITS_PER_MM).round() as i64
}

/// A programmed point in whole 10⁻⁷ mm, X on the radius.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct UPt {
    x: i64,
    z: i64,
}

impl UPt {
    fn mm(self) -> V2 {
        V2::new(self.z as f64 / UNITS_PER_MM, self.x as f64 / UNITS_PER_MM)
    }
}

/// Compensation settings (the `CFG` keys `RN`, `TIP`, `DIAM`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompSettings {
    /// Nose radius `r`, mm (`0 ≤ r ≤ 25`).
    pub rn_mm: f64,
    /// Tip orientation code `0 … 9` (`docs/protocol.md` §4, `CFG TIP`).
    pub tip: u8,
    /// X words (and printed X values) are diameters.
    pub diam: bool,
}

impl Default for CompSettings {
    /// The device's power-on settings: `RN=0.4 TIP=3 DIAM=1`.
    fn default() -> Self {
        CompSettings {
            rn_mm: 0.4,
            tip: 3,
            diam: true,
        }
    }
}

impl CompSettings {
    /// Checks the settings: `0 ≤ rn_mm ≤ 25` and `tip ≤ 9`.
    pub fn check(&self) -> Result<(), RefRefusal> {
        if !(0.0..=RN_MAX_MM).contains(&self.rn_mm) {
            return Err(RefRefusal::new(
                RefusalKind::Value,
                format!("RN {} outside 0 … {RN_MAX_MM} mm", self.rn_mm),
            ));
        }
        if self.tip > 9 {
            return Err(RefRefusal::new(
                RefusalKind::Value,
                format!("TIP {} is not a digit 0 … 9", self.tip),
            ));
        }
        Ok(())
    }

    /// The tip vector (nose centre to theoretical tool tip) of the `TIP`
    /// code, `(x, z)` in mm on the radius: 1 `(+r, +r)`, 2 `(+r, −r)`,
    /// 3 `(−r, −r)`, 4 `(−r, +r)`, 5 `(0, +r)`, 6 `(+r, 0)`, 7 `(0, −r)`,
    /// 8 `(−r, 0)`, 0 and 9 `(0, 0)`.
    pub fn tip_vector(&self) -> (f64, f64) {
        let r = self.rn_mm;
        match self.tip {
            1 => (r, r),
            2 => (r, -r),
            3 => (-r, -r),
            4 => (-r, r),
            5 => (0.0, r),
            6 => (r, 0.0),
            7 => (0.0, -r),
            8 => (-r, 0.0),
            _ => (0.0, 0.0),
        }
    }

    fn tip(&self) -> V2 {
        let (x, z) = self.tip_vector();
        V2::new(z, x)
    }
}

/// The motion of a block: `G00`, `G01`, `G02`, `G03`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefMotion {
    /// `G00`, rapid (compensated like `G01`, keeps its word).
    Rapid,
    /// `G01`, linear feed.
    Linear,
    /// `G02`, clockwise arc in the (Z right, X up) picture.
    Cw,
    /// `G03`, counter-clockwise arc.
    Ccw,
}

impl RefMotion {
    /// The G word as printed: `"G00"`, `"G01"`, `"G02"`, `"G03"`.
    pub fn word(&self) -> &'static str {
        match self {
            RefMotion::Rapid => "G00",
            RefMotion::Linear => "G01",
            RefMotion::Cw => "G02",
            RefMotion::Ccw => "G03",
        }
    }

    /// `G02` or `G03`.
    pub fn is_arc(&self) -> bool {
        matches!(self, RefMotion::Cw | RefMotion::Ccw)
    }
}

/// The corner mode for outside corners (modal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CornerMode {
    /// `G451` (power-on): tangent-line vertex up to 90°, square-off beyond.
    Intersection,
    /// `G450`: transition arc of radius `r` about the programmed corner.
    TransitionArc,
}

/// The side of the contour the tool is on, looking along the travel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompSide {
    /// `G41`.
    Left,
    /// `G42`.
    Right,
}

impl CompSide {
    /// `+1` left, `−1` right (the sign of a turn towards this side).
    fn sign(self) -> f64 {
        match self {
            CompSide::Left => 1.0,
            CompSide::Right => -1.0,
        }
    }

    fn word(self) -> &'static str {
        match self {
            CompSide::Left => "G41",
            CompSide::Right => "G42",
        }
    }
}

/// One theoretical-tool-tip block sent to the interpolator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefBlock {
    /// The block's motion word.
    pub motion: RefMotion,
    /// End point X, mm on the radius.
    pub x: f64,
    /// End point Z, mm.
    pub z: f64,
    /// Arc centre `(X radius, Z)` in mm for `G02`/`G03`, `None` for lines.
    pub centre: Option<(f64, f64)>,
}

/// A length in whole 10⁻⁷ mm printed with four decimals, rounded half away
/// from zero; a value that rounds to zero prints without a sign.
fn fmt_units4(u: i64) -> String {
    let q = (u.unsigned_abs() + 500) / 1000;
    let sign = if u < 0 && q > 0 { "-" } else { "" };
    format!("{sign}{}.{:04}", q / 10_000, q % 10_000)
}

/// Distance (mm) from `v` to the nearest four-decimal printing tie.
fn tie_distance_mm(v: f64) -> f64 {
    let s = (v * 1e4).abs();
    ((s - s.floor()) - 0.5).abs() * 1e-4
}

impl RefBlock {
    /// The `DATA` text as the device prints it: `G01 X27.5314 Z0.0000`, or
    /// for arcs `G03 X12.0000 Z-2.4000 I0.0000 K-2.4000`, `I`, `K` the centre
    /// minus this block's start point (radius values); X doubled when `diam`.
    ///
    /// `start` is the block's start point `(X radius, Z)` in mm, i.e. the end
    /// of the previous block. Points are rounded to 10⁻⁷ mm first (as the
    /// device does before printing), then to four decimals, half away from
    /// zero; `I`, `K` are the differences of the rounded centre and start.
    pub fn text(&self, start: (f64, f64), diam: bool) -> String {
        let xu = to_units(self.x);
        let x_printed = if diam { 2 * xu } else { xu };
        let mut s = format!(
            "{} X{} Z{}",
            self.motion.word(),
            fmt_units4(x_printed),
            fmt_units4(to_units(self.z))
        );
        if let Some((cx, cz)) = self.centre {
            let i = to_units(cx) - to_units(start.0);
            let k = to_units(cz) - to_units(start.1);
            s.push_str(&format!(" I{} K{}", fmt_units4(i), fmt_units4(k)));
        }
        s
    }

    /// The end point `(X radius, Z)`, mm.
    pub fn end(&self) -> (f64, f64) {
        (self.x, self.z)
    }
}

/// Distance in mm from the nearest four-decimal printing tie (`…x.xxxx5`)
/// over the printed numbers of `block` (X as printed, i.e. the diameter when
/// `diam`; Z; for arcs `I`, `K` = centre − `start`), so that a comparison can
/// excuse values that lie within rounding error of a tie.
pub fn tie_margin(block: &RefBlock, start: (f64, f64), diam: bool) -> f64 {
    let x = if diam { 2.0 * block.x } else { block.x };
    let mut m = tie_distance_mm(x).min(tie_distance_mm(block.z));
    if let Some((cx, cz)) = block.centre {
        m = m
            .min(tie_distance_mm(cx - start.0))
            .min(tie_distance_mm(cz - start.1));
    }
    m
}

/// The `DATA` texts of consecutive blocks, the first starting at `start`
/// `(X radius, Z)`.
pub fn block_texts(blocks: &[RefBlock], start: (f64, f64), diam: bool) -> Vec<String> {
    let mut from = start;
    blocks
        .iter()
        .map(|b| {
            let t = b.text(from, diam);
            from = b.end();
            t
        })
        .collect()
}

/// The error class of a refusal, as the device's `ERR` codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefusalKind {
    /// `ERR SYNTAX`: not a well-formed block (unknown word, repeated
    /// address, unclosed comment, conflicting G codes).
    Syntax,
    /// `ERR VALUE`: a malformed or out-of-range number or setting.
    Value,
    /// `ERR RANGE`: a commanded coordinate beyond 99 999.999999 mm.
    Range,
    /// `ERR GEOMETRY`: impossible geometry or a compensation rule broken.
    Geometry,
}

impl RefusalKind {
    /// The protocol's error code: `SYNTAX`, `VALUE`, `RANGE`, `GEOMETRY`.
    pub fn code(&self) -> &'static str {
        match self {
            RefusalKind::Syntax => "SYNTAX",
            RefusalKind::Value => "VALUE",
            RefusalKind::Range => "RANGE",
            RefusalKind::Geometry => "GEOMETRY",
        }
    }
}

/// Why a block was refused. A refused block changes no state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RefRefusal {
    /// The error class.
    pub kind: RefusalKind,
    /// Which rule, naming the block concerned by its `N` number when it has
    /// one (else by its text).
    pub reason: String,
}

impl RefRefusal {
    fn new(kind: RefusalKind, reason: String) -> Self {
        RefRefusal { kind, reason }
    }

    fn geometry(reason: String) -> Self {
        RefRefusal::new(RefusalKind::Geometry, reason)
    }

    fn syntax(reason: String) -> Self {
        RefRefusal::new(RefusalKind::Syntax, reason)
    }
}

impl fmt::Display for RefRefusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ERR {} {}", self.kind.code(), self.reason)
    }
}

impl std::error::Error for RefRefusal {}

// ---------------------------------------------------------------------------
// Parsing
// ---------------------------------------------------------------------------

/// A compensation-group G code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CompCode {
    Off,
    On(CompSide),
}

/// The words of one block, numbers as written in millionths of a mm.
#[derive(Clone, Debug, Default, PartialEq)]
struct Words {
    n: Option<u64>,
    motion: Option<RefMotion>,
    incremental: Option<bool>,
    comp: Option<CompCode>,
    corner: Option<CornerMode>,
    x: Option<i64>,
    z: Option<i64>,
    i: Option<i64>,
    k: Option<i64>,
    r: Option<i64>,
}

/// `[+-]digits[.digits]`, at most six decimals, magnitude below 100 000, as
/// whole millionths.
fn parse_micro(word: &str) -> Option<i64> {
    let (neg, rest) = match word.as_bytes().first() {
        Some(b'+') => (false, &word[1..]),
        Some(b'-') => (true, &word[1..]),
        _ => (false, word),
    };
    let (int_part, frac_part) = match rest.split_once('.') {
        Some((i, f)) => (i, f),
        None => (rest, ""),
    };
    let digits_ok = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if int_part.is_empty() || !digits_ok(int_part) || !digits_ok(frac_part) {
        return None;
    }
    if rest.contains('.') && (frac_part.is_empty() || frac_part.len() > 6) {
        return None;
    }
    let int: i64 = int_part.bytes().try_fold(0i64, |a, b| {
        a.checked_mul(10)?.checked_add(i64::from(b - b'0'))
    })?;
    let frac: i64 = format!("{frac_part:0<6}")
        .bytes()
        .fold(0i64, |a, b| a * 10 + i64::from(b - b'0'));
    let v = int.checked_mul(1_000_000)?.checked_add(frac)?;
    if v >= MICRO_LIMIT {
        return None;
    }
    Some(if neg { -v } else { v })
}

/// Unsigned whole number (`G`, `N`, `M`, `T` words).
fn parse_whole(word: &str) -> Option<u64> {
    if word.is_empty() || !word.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    word.bytes().try_fold(0u64, |a, b| {
        a.checked_mul(10)?.checked_add(u64::from(b - b'0'))
    })
}

/// The line without its comments: `( … )` (replaced by a space) and
/// everything from `;`.
fn strip_comments(line: &str) -> Result<String, RefRefusal> {
    let mut out = String::with_capacity(line.len());
    let mut in_paren = false;
    for ch in line.chars() {
        if in_paren {
            if ch == ')' {
                in_paren = false;
                out.push(' ');
            }
            continue;
        }
        match ch {
            '(' => in_paren = true,
            ';' => break,
            ')' => return Err(RefRefusal::syntax("')' without '('".into())),
            _ => out.push(ch),
        }
    }
    if in_paren {
        return Err(RefRefusal::syntax("comment not closed by ')'".into()));
    }
    Ok(out)
}

/// Parses one block into its words (syntax and value checks only).
fn parse_block(line: &str) -> Result<Words, RefRefusal> {
    let text = strip_comments(line)?;
    let mut w = Words::default();
    let mut seen: Vec<char> = Vec::new();
    let mut chars = text.char_indices().peekable();
    while let Some(&(pos, ch)) = chars.peek() {
        if ch == ' ' || ch == '\t' {
            chars.next();
            continue;
        }
        if !ch.is_ascii_alphabetic() {
            return Err(RefRefusal::syntax(format!(
                "{ch:?} where an address letter was expected"
            )));
        }
        let letter = ch.to_ascii_uppercase();
        chars.next();
        let start = pos + ch.len_utf8();
        let mut end = start;
        while let Some(&(p, c)) = chars.peek() {
            if c.is_ascii_digit() || c == '.' || c == '+' || c == '-' {
                end = p + c.len_utf8();
                chars.next();
            } else {
                break;
            }
        }
        let value = &text[start..end];
        if letter != 'G' {
            if seen.contains(&letter) {
                return Err(RefRefusal::syntax(format!("address {letter} repeated")));
            }
            seen.push(letter);
        }
        let bad_value = || {
            RefRefusal::new(
                RefusalKind::Value,
                format!("{letter}: malformed number {value:?}"),
            )
        };
        match letter {
            'G' => {
                let g = parse_whole(value).ok_or_else(bad_value)?;
                set_g(&mut w, g)?;
            }
            'N' => w.n = Some(parse_whole(value).ok_or_else(bad_value)?),
            'M' | 'T' => {
                parse_whole(value).ok_or_else(bad_value)?;
            }
            'F' | 'S' => {
                parse_micro(value).ok_or_else(bad_value)?;
            }
            'X' | 'Z' | 'I' | 'K' | 'R' => {
                let v = parse_micro(value).ok_or_else(bad_value)?;
                let slot = match letter {
                    'X' => &mut w.x,
                    'Z' => &mut w.z,
                    'I' => &mut w.i,
                    'K' => &mut w.k,
                    _ => &mut w.r,
                };
                *slot = Some(v);
            }
            _ => {
                return Err(RefRefusal::syntax(format!(
                    "unknown address {letter}{value}"
                )))
            }
        }
    }
    Ok(w)
}

/// Records one G code, at most one per group.
fn set_g(w: &mut Words, g: u64) -> Result<(), RefRefusal> {
    fn put<T>(slot: &mut Option<T>, v: T, g: u64) -> Result<(), RefRefusal> {
        if slot.is_some() {
            return Err(RefRefusal::syntax(format!(
                "G{g}: a second G code of the same group"
            )));
        }
        *slot = Some(v);
        Ok(())
    }
    match g {
        0 => put(&mut w.motion, RefMotion::Rapid, g),
        1 => put(&mut w.motion, RefMotion::Linear, g),
        2 => put(&mut w.motion, RefMotion::Cw, g),
        3 => put(&mut w.motion, RefMotion::Ccw, g),
        40 => put(&mut w.comp, CompCode::Off, g),
        41 => put(&mut w.comp, CompCode::On(CompSide::Left), g),
        42 => put(&mut w.comp, CompCode::On(CompSide::Right), g),
        90 => put(&mut w.incremental, false, g),
        91 => put(&mut w.incremental, true, g),
        450 => put(&mut w.corner, CornerMode::TransitionArc, g),
        451 => put(&mut w.corner, CornerMode::Intersection, g),
        _ => Err(RefRefusal::new(
            RefusalKind::Value,
            format!("G{g} is not supported"),
        )),
    }
}

// ---------------------------------------------------------------------------
// Elements
// ---------------------------------------------------------------------------

/// The circle of an arc element.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ArcGeom {
    /// Programmed centre, mm.
    centre: V2,
    /// Counter-clockwise (`G03`).
    ccw: bool,
    /// Start radius, mm.
    r0: f64,
    /// End radius, mm.
    r1: f64,
    /// Squared start radius in (10⁻⁷ mm)², exact.
    r0_sq: i128,
    /// Squared end radius in (10⁻⁷ mm)², exact.
    r1_sq: i128,
    /// Programmed sweep in `(0, 2π]`, radians.
    sweep: f64,
    /// Programmed as a full circle (end point equal to start point).
    full: bool,
}

/// A programmed element (a block that moves).
#[derive(Clone, Debug, PartialEq)]
struct Element {
    motion: RefMotion,
    /// `N10` when the block has an `N` word, else its text in quotes.
    label: String,
    start: V2,
    end: V2,
    arc: Option<ArcGeom>,
}

/// An offset element taken whole, for intersections.
#[derive(Clone, Copy, Debug)]
enum Offset {
    /// The line through `p` along `t`.
    Line { p: V2, t: V2 },
    /// The circle about `c` of radius `rho`.
    Circle { c: V2, rho: f64 },
}

impl Element {
    /// Unit direction of travel at the start.
    fn dir_start(&self) -> V2 {
        match &self.arc {
            None => (self.end - self.start).unit(),
            Some(a) => arc_tangent(a, self.start),
        }
    }

    /// Unit direction of travel at the end.
    fn dir_end(&self) -> V2 {
        match &self.arc {
            None => (self.end - self.start).unit(),
            Some(a) => arc_tangent(a, self.end),
        }
    }

    /// Whether the tool is inside the circle (on the centre's side).
    fn tool_inside(&self, side: CompSide) -> bool {
        match &self.arc {
            None => false,
            Some(a) => a.ccw == (side == CompSide::Left),
        }
    }

    /// The offset element at the start (`at_end == false`) or the end.
    fn offset(&self, side: CompSide, r: f64, at_end: bool) -> Offset {
        match &self.arc {
            None => {
                let t = self.dir_start();
                Offset::Line {
                    p: self.start + normal(t, side) * r,
                    t,
                }
            }
            Some(a) => {
                let big_r = if at_end { a.r1 } else { a.r0 };
                let rho = if self.tool_inside(side) {
                    big_r - r
                } else {
                    big_r + r
                };
                Offset::Circle { c: a.centre, rho }
            }
        }
    }
}

/// Unit tangent of an arc at a point on (or near) it.
fn arc_tangent(a: &ArcGeom, p: V2) -> V2 {
    let u = (p - a.centre).unit();
    if a.ccw {
        u.left()
    } else {
        -u.left()
    }
}

/// Unit normal to the tool's side of direction `t`.
fn normal(t: V2, side: CompSide) -> V2 {
    t.left() * side.sign()
}

/// Angle from `u` to `v` in the direction of the arc, in `(−π, π]` mapped to
/// `[0, 2π)`.
fn directed_angle(u: V2, v: V2, ccw: bool) -> f64 {
    let c = u.cross(v);
    let a = if ccw {
        c.atan2(u.dot(v))
    } else {
        (-c).atan2(u.dot(v))
    };
    if a < 0.0 {
        a + 2.0 * PI
    } else {
        a
    }
}

/// `|a − b| > d` for the square roots of the non-negative `a`, `b`, exact
/// when the numbers fit, in f64 otherwise.
fn roots_differ_by_more(a: i128, b: i128, d: i128) -> bool {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    // √hi − √lo > d ⇔ hi − lo − d² > 2d·√lo ⇔ m > 0 ∧ m² > 4d²·lo.
    roots_differ_exact(lo, hi, d)
        .unwrap_or_else(|| (hi as f64).sqrt() - (lo as f64).sqrt() > d as f64)
}

/// `√hi − √lo > d` in integers (`lo ≤ hi`), `None` on overflow.
fn roots_differ_exact(lo: i128, hi: i128, d: i128) -> Option<bool> {
    let m = hi.checked_sub(lo)?.checked_sub(d.checked_mul(d)?)?;
    if m <= 0 {
        return Some(false);
    }
    let lhs = m.checked_mul(m)?;
    let rhs = d.checked_mul(d)?.checked_mul(4)?.checked_mul(lo)?;
    Some(lhs > rhs)
}

// ---------------------------------------------------------------------------
// Corners
// ---------------------------------------------------------------------------

/// A move inserted at a corner, by its nose-centre end point.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Inserted {
    /// A straight move.
    Line(V2),
    /// A transition arc about `centre` (nose-centre frame).
    Arc { to: V2, centre: V2, ccw: bool },
}

/// How element 1 ends and element 2 starts at their junction (nose centre).
#[derive(Clone, Debug, PartialEq)]
struct Corner {
    end1: V2,
    inserted: Vec<Inserted>,
    start2: V2,
}

/// The intersection nearest to `p` of two offset lines or two offset circles.
fn intersect(o1: Offset, o2: Offset, p: V2) -> Option<V2> {
    let nearest = |a: V2, b: V2| {
        if (a - p).len() <= (b - p).len() {
            a
        } else {
            b
        }
    };
    match (o1, o2) {
        (Offset::Line { p: q1, t: t1 }, Offset::Line { p: q2, t: t2 }) => {
            let den = t1.cross(t2);
            if den == 0.0 {
                return None;
            }
            let a = (q2 - q1).cross(t2) / den;
            Some(q1 + t1 * a)
        }
        // A line and a circle meet through `line_circle`, from the corner.
        (Offset::Line { .. }, Offset::Circle { .. })
        | (Offset::Circle { .. }, Offset::Line { .. }) => None,
        (Offset::Circle { c: c1, rho: r1 }, Offset::Circle { c: c2, rho: r2 }) => {
            let d_vec = c2 - c1;
            let d = d_vec.len();
            if d == 0.0 {
                return None;
            }
            let e = d_vec * (1.0 / d);
            let a = (d * d + r1 * r1 - r2 * r2) / (2.0 * d);
            let mut h2 = r1 * r1 - a * a;
            if h2 < 0.0 {
                if h2 > -1e-14 * (r1 * r1 + r2 * r2) {
                    h2 = 0.0;
                } else {
                    return None;
                }
            }
            let h = h2.sqrt();
            let m = c1 + e * a;
            Some(nearest(m + e.left() * h, m - e.left() * h))
        }
    }
}

/// The intersection nearest the corner `p` of a line's offset (the line
/// along `t` through its perpendicular offset point at `p`) with the offset
/// circle of the arc `arc` at `p` (its end when `at_end`), computed from the
/// corner rather than from the circle's centre: with `s` the arc's radius,
/// negative when the tool is inside the circle, and `n` its normal at `p`,
/// the offset circle is `|X|² − r² + 2s(X·n − r) = 0` for `X` relative to
/// `p`, and on the offset line `X = r·nₗ + u·t` this is
/// `u² + 2s(t·n)u − s·r·|nₗ − n|² = 0`. No term is a difference of squared
/// radii, so nearly tangent elements (a corner turning by little) keep their
/// precision. The nearest point has the smaller `|u|`.
fn line_circle(p: V2, t: V2, arc: &Element, at_end: bool, side: CompSide, r: f64) -> Option<V2> {
    let a = arc.arc.as_ref()?;
    let big_r = if at_end { a.r1 } else { a.r0 };
    let s = if arc.tool_inside(side) { -big_r } else { big_r };
    let n = normal(arc_tangent(a, p), side);
    let nl = normal(t, side);
    let d = nl - n;
    let b = s * t.dot(n);
    let c = s * r * d.dot(d);
    let mut disc = b * b + c;
    if disc < 0.0 {
        // A line just touching the circle.
        if disc > -1e-14 * (b * b + c.abs()) {
            disc = 0.0;
        } else {
            return None;
        }
    }
    let root = disc.sqrt();
    let (u1, u2) = (-b - root, -b + root);
    let u = if u1.abs() <= u2.abs() { u1 } else { u2 };
    Some(p + nl * r + t * u)
}

/// Whether the compensated motion of `e` from `s` to `end` (nose centre)
/// keeps the programmed direction.
fn keeps_direction(e: &Element, s: V2, end: V2, side: CompSide, r: f64) -> bool {
    let same_point = s.rounded_units() == end.rounded_units();
    match &e.arc {
        None => !same_point && (end - s).dot(e.dir_start()) > 0.0,
        Some(a) => {
            if same_point {
                return a.full;
            }
            let comp = directed_angle(s - a.centre, end - a.centre, a.ccw);
            // The excess is measured on the smaller offset radius of the
            // arc's two ends.
            let rho = |at_end| match e.offset(side, r, at_end) {
                Offset::Circle { rho, .. } => rho,
                Offset::Line { .. } => a.r1,
            };
            let rho = rho(false).min(rho(true));
            comp > 0.0 && (comp - a.sweep) * rho <= sweep_slack_mm(r)
        }
    }
}

// ---------------------------------------------------------------------------
// The contour state machine
// ---------------------------------------------------------------------------

/// What compensation is holding back.
#[derive(Clone, Debug, PartialEq)]
enum Pending {
    /// Nothing: compensation off, or armed without a start-up block yet.
    None,
    /// The start-up block (linear), programmed from `start` to `end`.
    Startup {
        motion: RefMotion,
        start: V2,
        end: V2,
    },
    /// An element whose compensated (nose-centre) start is `from`.
    Element { e: Element, from: V2 },
}

/// The compensation state machine: modal state, programmed and actual
/// position, and the element held back for one block of look-ahead.
///
/// Power-on: programmed and actual position `X0 Z0`, `G00 G90 G40 G451`.
#[derive(Clone, Debug, PartialEq)]
pub struct RefContour {
    settings: CompSettings,
    motion: RefMotion,
    incremental: bool,
    corner: CornerMode,
    /// `Some` while compensation is armed or active.
    side: Option<CompSide>,
    /// Programmed contour point (exact).
    prog: UPt,
    /// Theoretical tool tip at the end of the last block sent, mm.
    ttt: V2,
    pending: Pending,
}

impl RefContour {
    /// A contour at power-on with the given settings. Settings outside their
    /// range make every block refused ([`CompSettings::check`]).
    pub fn new(settings: CompSettings) -> Self {
        RefContour {
            settings,
            motion: RefMotion::Rapid,
            incremental: false,
            corner: CornerMode::Intersection,
            side: None,
            prog: UPt { x: 0, z: 0 },
            ttt: V2::ZERO,
            pending: Pending::None,
        }
    }

    /// The settings in use.
    pub fn settings(&self) -> CompSettings {
        self.settings
    }

    /// The theoretical tool tip at the end of the last block sent,
    /// `(X radius, Z)` in mm: the start point of the next block sent.
    pub fn ttt_mm(&self) -> (f64, f64) {
        (self.ttt.x, self.ttt.z)
    }

    /// The programmed contour point, `(X radius, Z)` in mm.
    pub fn programmed_mm(&self) -> (f64, f64) {
        let p = self.prog.mm();
        (p.x, p.z)
    }

    /// The side compensation is armed or active on, `None` when off.
    pub fn side(&self) -> Option<CompSide> {
        self.side
    }

    /// Runs one G-code block line. `Ok` holds the TTT blocks sent by this
    /// line, which may belong to the previous element (one block of
    /// look-ahead); on `Err` nothing changes.
    pub fn block(&mut self, line: &str) -> Result<Vec<RefBlock>, RefRefusal> {
        self.settings.check()?;
        let words = parse_block(line)?;
        let mut next = self.clone();
        let mut out = Vec::new();
        next.run(&words, line, &mut out)?;
        *self = next;
        Ok(out)
    }

    /// [`RefContour::block`] with the blocks as `DATA` texts.
    pub fn block_text(&mut self, line: &str) -> Result<Vec<String>, RefRefusal> {
        let start = self.ttt_mm();
        let blocks = self.block(line)?;
        Ok(block_texts(&blocks, start, self.settings.diam))
    }

    /// End of program: a pending start-up block or element is ended as by a
    /// `G40` without motion (the element at its perpendicular offset point)
    /// and returned; compensation is then off. Never refuses.
    pub fn finish(&mut self) -> Vec<RefBlock> {
        let mut out = Vec::new();
        self.end_pending(&mut out);
        self.side = None;
        out
    }

    /// [`RefContour::finish`] with the blocks as `DATA` texts.
    pub fn finish_text(&mut self) -> Vec<String> {
        let start = self.ttt_mm();
        let blocks = self.finish();
        block_texts(&blocks, start, self.settings.diam)
    }

    fn r(&self) -> f64 {
        self.settings.rn_mm
    }

    /// Sends a TTT block to the nose-centre point `c` (plus the tip vector),
    /// an arc about the nose-centre `centre` when given.
    fn send(&mut self, out: &mut Vec<RefBlock>, motion: RefMotion, c: V2, centre: Option<V2>) {
        let tip = self.settings.tip();
        let to = c + tip;
        out.push(RefBlock {
            motion,
            x: to.x,
            z: to.z,
            centre: centre.map(|k| {
                let k = k + tip;
                (k.x, k.z)
            }),
        });
        self.ttt = to;
    }

    /// Sends an uncompensated block to the programmed point `p`.
    fn send_plain(
        &mut self,
        out: &mut Vec<RefBlock>,
        motion: RefMotion,
        p: V2,
        centre: Option<V2>,
    ) {
        out.push(RefBlock {
            motion,
            x: p.x,
            z: p.z,
            centre: centre.map(|k| (k.x, k.z)),
        });
        self.ttt = p;
    }

    /// Sends a compensated element from its nose-centre start to `end`.
    fn send_element(&mut self, out: &mut Vec<RefBlock>, e: &Element, end: V2) {
        let centre = e.arc.as_ref().map(|a| a.centre);
        self.send(out, e.motion, end, centre);
    }

    /// Ends whatever is pending at its perpendicular offset point (start-up
    /// blocks with their own normal), without the too-short check.
    fn end_pending(&mut self, out: &mut Vec<RefBlock>) {
        let r = self.r();
        match std::mem::replace(&mut self.pending, Pending::None) {
            Pending::None => {}
            Pending::Startup { motion, start, end } => {
                if let Some(side) = self.side {
                    let n = normal((end - start).unit(), side);
                    self.send(out, motion, end + n * r, None);
                }
            }
            Pending::Element { e, .. } => {
                if let Some(side) = self.side {
                    let a = e.end + normal(e.dir_end(), side) * r;
                    self.send_element(out, &e, a);
                }
            }
        }
    }

    /// The programmed end point of a block.
    fn target(&self, w: &Words) -> Result<UPt, RefRefusal> {
        let x_scale = if self.settings.diam { 5 } else { 10 };
        let axis = |word: Option<i64>, scale: i64, cur: i64, name: char| {
            let Some(v) = word else { return Ok(cur) };
            let v = v * scale;
            let p = if self.incremental { cur + v } else { v };
            if p.abs() > COORD_MAX_UNITS {
                return Err(RefRefusal::new(
                    RefusalKind::Range,
                    format!("{name}: coordinate beyond 99999.999999 mm"),
                ));
            }
            Ok(p)
        };
        Ok(UPt {
            x: axis(w.x, x_scale, self.prog.x, 'X')?,
            z: axis(w.z, 10, self.prog.z, 'Z')?,
        })
    }

    /// Builds the element of a motion block from the programmed point to
    /// `end`, checking the arc's own geometry.
    fn element(&self, w: &Words, end: UPt, label: String) -> Result<Element, RefRefusal> {
        let start = self.prog;
        let (s, e) = (start.mm(), end.mm());
        let motion = self.motion;
        if !motion.is_arc() {
            return Ok(Element {
                motion,
                label,
                start: s,
                end: e,
                arc: None,
            });
        }
        let ccw = motion == RefMotion::Ccw;
        let full = start == end;
        let arc = if let Some(r_word) = w.r {
            if full {
                return Err(RefRefusal::geometry(format!(
                    "block {label}: an R arc cannot be a full circle"
                )));
            }
            if r_word == 0 {
                return Err(RefRefusal::new(RefusalKind::Value, "R: zero radius".into()));
            }
            let big_r = r_word.unsigned_abs() as f64 / 1e6;
            let d = e - s;
            let chord = d.len();
            let r_units = i128::from(r_word.unsigned_abs()) * 10;
            // (2h)² = 4R² − chord², h the centre's distance from the chord,
            // exact in (10⁻⁷ mm)²: a half circle has its centre exactly on
            // the chord.
            let (dx, dz) = (i128::from(end.x - start.x), i128::from(end.z - start.z));
            let h2_4 = 4 * r_units * r_units - (dx * dx + dz * dz);
            let h = if h2_4 >= 0 {
                (h2_4 as f64).sqrt() / 2.0 / UNITS_PER_MM
            } else if chord / 2.0 - big_r <= R_CHORD_SLACK_MM {
                0.0
            } else {
                return Err(RefRefusal::geometry(format!(
                    "block {label}: end point farther than 2R from the start"
                )));
            };
            let sgn = if ccw == (r_word > 0) { 1.0 } else { -1.0 };
            let centre = s + d * 0.5 + d.left().unit() * (sgn * h);
            ArcGeom {
                centre,
                ccw,
                r0: big_r,
                r1: big_r,
                r0_sq: r_units * r_units,
                r1_sq: r_units * r_units,
                sweep: directed_angle(s - centre, e - centre, ccw),
                full: false,
            }
        } else {
            let c = UPt {
                x: start.x + w.i.unwrap_or(0) * 10,
                z: start.z + w.k.unwrap_or(0) * 10,
            };
            let sq = |p: UPt| {
                let (dx, dz) = (i128::from(p.x - c.x), i128::from(p.z - c.z));
                dx * dx + dz * dz
            };
            let (r0_sq, r1_sq) = (sq(start), sq(end));
            if r0_sq == 0 || r1_sq == 0 {
                return Err(RefRefusal::geometry(format!(
                    "block {label}: arc radius zero"
                )));
            }
            if roots_differ_by_more(r0_sq, r1_sq, RADIUS_MISMATCH_UNITS) {
                return Err(RefRefusal::geometry(format!(
                    "block {label}: end point not on its circle (radii differ by more than 0.002 mm)"
                )));
            }
            let centre = c.mm();
            let sweep = if full {
                2.0 * PI
            } else {
                let a = directed_angle(s - centre, e - centre, ccw);
                if a == 0.0 {
                    2.0 * PI
                } else {
                    a
                }
            };
            ArcGeom {
                centre,
                ccw,
                r0: (r0_sq as f64).sqrt() / UNITS_PER_MM,
                r1: (r1_sq as f64).sqrt() / UNITS_PER_MM,
                r0_sq,
                r1_sq,
                sweep,
                full,
            }
        };
        Ok(Element {
            motion,
            label,
            start: s,
            end: e,
            arc: Some(arc),
        })
    }

    /// Refuses a concave arc whose radius is not larger than the nose radius.
    fn check_concave(&self, e: &Element, side: CompSide) -> Result<(), RefRefusal> {
        let Some(a) = &e.arc else { return Ok(()) };
        if !e.tool_inside(side) {
            return Ok(());
        }
        let rn_u = i128::from(to_units(self.r()));
        let rn_sq = rn_u * rn_u;
        if a.r0_sq <= rn_sq || a.r1_sq <= rn_sq {
            return Err(RefRefusal::geometry(format!(
                "block {}: concave arc radius not larger than the nose radius",
                e.label
            )));
        }
        Ok(())
    }

    /// The corner between element 1 (pending) and element 2.
    fn corner(&self, e1: &Element, e2: &Element, side: CompSide) -> Result<Corner, RefRefusal> {
        let r = self.r();
        let t1 = e1.dir_end();
        let t2 = e2.dir_start();
        let p = e1.end;
        let a1 = p + normal(t1, side) * r;
        let a2 = p + normal(t2, side) * r;
        let cos = t1.dot(t2);
        let sin = t1.cross(t2);
        if cos > 0.0 && sin.abs() < SMOOTH_SIN {
            return Ok(Corner {
                end1: a1,
                inserted: Vec::new(),
                start2: a1,
            });
        }
        let reversal = cos < 0.0 && sin.abs() < SMOOTH_SIN;
        if !reversal && sin * side.sign() > 0.0 {
            let x = match (&e1.arc, &e2.arc) {
                (None, Some(_)) => line_circle(p, t1, e2, false, side, r),
                (Some(_), None) => line_circle(p, t2, e1, true, side, r),
                _ => intersect(e1.offset(side, r, true), e2.offset(side, r, false), p),
            };
            let x = x.ok_or_else(|| {
                RefRefusal::geometry(format!(
                    "the nose does not fit the corner between block {} and block {}",
                    e1.label, e2.label
                ))
            })?;
            return Ok(Corner {
                end1: x,
                inserted: Vec::new(),
                start2: x,
            });
        }
        let mut inserted = Vec::new();
        match self.corner {
            CornerMode::TransitionArc => {
                inserted.push(Inserted::Arc {
                    to: a2,
                    centre: p,
                    ccw: side == CompSide::Right,
                });
                Ok(Corner {
                    end1: a1,
                    inserted,
                    start2: a2,
                })
            }
            CornerMode::Intersection => {
                let (v1, v2) = if cos >= 0.0 {
                    let v = a1 + t1 * (r * sin.abs() / (1.0 + cos));
                    (v, v)
                } else {
                    (a1 + t1 * r, a2 - t2 * r)
                };
                let end1 = if e1.arc.is_some() {
                    inserted.push(Inserted::Line(v1));
                    a1
                } else {
                    v1
                };
                if v2 != v1 {
                    inserted.push(Inserted::Line(v2));
                }
                let start2 = if e2.arc.is_some() {
                    inserted.push(Inserted::Line(a2));
                    a2
                } else {
                    v2
                };
                Ok(Corner {
                    end1,
                    inserted,
                    start2,
                })
            }
        }
    }

    /// Sends the inserted moves of a corner, leaving out those of zero length
    /// after rounding.
    fn send_inserted(&mut self, out: &mut Vec<RefBlock>, ins: &[Inserted], both_rapid: bool) {
        let tip = self.settings.tip();
        for m in ins {
            let to = match m {
                Inserted::Line(to) | Inserted::Arc { to, .. } => *to,
            };
            if (to + tip).rounded_units() == self.ttt.rounded_units() {
                continue;
            }
            match m {
                Inserted::Line(to) => {
                    let motion = if both_rapid {
                        RefMotion::Rapid
                    } else {
                        RefMotion::Linear
                    };
                    self.send(out, motion, *to, None);
                }
                Inserted::Arc { to, centre, ccw } => {
                    let motion = if *ccw { RefMotion::Ccw } else { RefMotion::Cw };
                    self.send(out, motion, *to, Some(*centre));
                }
            }
        }
    }

    /// Runs a parsed block on `self` (a copy; the caller keeps it on `Ok`).
    fn run(&mut self, w: &Words, line: &str, out: &mut Vec<RefBlock>) -> Result<(), RefRefusal> {
        let label = match w.n {
            Some(n) => format!("N{n}"),
            None => format!("'{}'", line.trim()),
        };
        if let Some(m) = w.motion {
            self.motion = m;
        }
        if let Some(inc) = w.incremental {
            self.incremental = inc;
        }
        if let Some(c) = w.corner {
            self.corner = c;
        }
        let has_centre = w.i.is_some() || w.k.is_some() || w.r.is_some();
        if has_centre && !self.motion.is_arc() {
            return Err(RefRefusal::syntax(format!(
                "block {label}: I, K or R in a linear block"
            )));
        }
        if w.r.is_some() && (w.i.is_some() || w.k.is_some()) {
            return Err(RefRefusal::syntax(format!(
                "block {label}: R together with I or K"
            )));
        }
        let has_xz = w.x.is_some() || w.z.is_some();
        let is_motion = has_xz && (!self.motion.is_arc() || has_centre);
        let target = self.target(w)?;
        let elem = if is_motion {
            Some(self.element(w, target, label.clone())?)
        } else {
            None
        };
        let moves = match &elem {
            Some(e) => e.arc.is_some() || target != self.prog,
            None => false,
        };

        match w.comp {
            Some(CompCode::On(side)) => match self.side {
                Some(cur) if cur != side => {
                    return Err(RefRefusal::geometry(format!(
                        "block {label}: {} while {} is on (change sides through G40)",
                        side.word(),
                        cur.word()
                    )));
                }
                Some(_) => {}
                None => {
                    if is_motion && self.motion.is_arc() {
                        return Err(RefRefusal::geometry(format!(
                            "block {label}: compensation switched on in an arc block"
                        )));
                    }
                    self.side = Some(side);
                }
            },
            Some(CompCode::Off) => {
                if self.side.is_some() && self.pending != Pending::None {
                    if is_motion && self.motion.is_arc() {
                        return Err(RefRefusal::geometry(format!(
                            "block {label}: compensation switched off in an arc block"
                        )));
                    }
                    self.cancel(out)?;
                }
                self.side = None;
            }
            None => {}
        }

        let Some(side) = self.side else {
            // Compensation off: straight to the programmed point.
            if let Some(e) = elem {
                let centre = e.arc.as_ref().map(|a| a.centre);
                self.send_plain(out, e.motion, e.end, centre);
                self.prog = target;
            }
            return Ok(());
        };
        let Some(e2) = elem.filter(|_| moves) else {
            // Not an element: passed over.
            return Ok(());
        };
        let r = self.r();
        match std::mem::replace(&mut self.pending, Pending::None) {
            Pending::None => {
                if e2.arc.is_some() {
                    return Err(RefRefusal::geometry(format!(
                        "block {label}: compensation switched on in an arc block"
                    )));
                }
                self.pending = Pending::Startup {
                    motion: e2.motion,
                    start: e2.start,
                    end: e2.end,
                };
            }
            Pending::Startup { motion, end, .. } => {
                self.check_concave(&e2, side)?;
                let to = end + normal(e2.dir_start(), side) * r;
                self.send(out, motion, to, None);
                self.pending = Pending::Element { e: e2, from: to };
            }
            Pending::Element { e: e1, from } => {
                self.check_concave(&e2, side)?;
                let c = self.corner(&e1, &e2, side)?;
                if !keeps_direction(&e1, from, c.end1, side, r) {
                    return Err(short_refusal(&e1));
                }
                self.send_element(out, &e1, c.end1);
                let both_rapid = e1.motion == RefMotion::Rapid && e2.motion == RefMotion::Rapid;
                self.send_inserted(out, &c.inserted, both_rapid);
                self.pending = Pending::Element {
                    e: e2,
                    from: c.start2,
                };
            }
        }
        self.prog = target;
        Ok(())
    }

    /// `G40` while a start-up block or an element is pending: it ends at its
    /// perpendicular offset point (a start-up block with its own normal),
    /// after the too-short check of an element.
    fn cancel(&mut self, out: &mut Vec<RefBlock>) -> Result<(), RefRefusal> {
        if let (Pending::Element { e, from }, Some(side)) = (&self.pending, self.side) {
            let r = self.r();
            let end = e.end + normal(e.dir_end(), side) * r;
            if !keeps_direction(e, *from, end, side, r) {
                return Err(short_refusal(e));
            }
        }
        self.end_pending(out);
        Ok(())
    }
}

/// The refusal naming an element too short for the nose.
fn short_refusal(e: &Element) -> RefRefusal {
    RefRefusal::geometry(format!(
        "block {} too short for the nose radius (its compensated motion would reverse)",
        e.label
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn krylenko() -> CompSettings {
        CompSettings {
            rn_mm: 0.4,
            tip: 3,
            diam: true,
        }
    }

    /// Runs `prog` and `finish`, returning every DATA text in order.
    fn run(settings: CompSettings, prog: &[&str]) -> Vec<String> {
        let mut c = RefContour::new(settings);
        let mut out = Vec::new();
        for l in prog {
            match c.block_text(l) {
                Ok(t) => out.extend(t),
                Err(e) => panic!("{l}: {e}"),
            }
        }
        out.extend(c.finish_text());
        out
    }

    /// Position of `want` as a consecutive run inside `have`.
    fn find_run(have: &[String], want: &[String]) -> Option<usize> {
        have.windows(want.len()).position(|w| w == want)
    }

    fn s(v: &[&str]) -> Vec<String> {
        v.iter().map(|x| x.to_string()).collect()
    }

    /// The number after `letter` in a DATA text.
    fn num(text: &str, letter: char) -> f64 {
        text.split(' ')
            .find_map(|w| w.strip_prefix(letter))
            .and_then(|v| v.parse().ok())
            .unwrap_or(f64::NAN)
    }

    fn mm4(v: f64) -> String {
        fmt_units4(to_units(v))
    }

    const FIG12: [&str; 10] = [
        "G00 X20 Z5",
        "G42 G01 Z0",
        "X28",
        "X48 Z-10",
        "Z-46",
        "X68 Z-56",
        "X94",
        "X114 Z-66",
        "Z-80",
        "G40 X120",
    ];

    #[test]
    fn fig12_external_tapers() {
        let out = run(krylenko(), &FIG12);
        // Exact construction: Xc = Zc = r·(1 − tan 22.5°) on the radius.
        let zc = 0.4 * (1.0 - (PI / 8.0).tan());
        let xcd = 2.0 * zc;
        let want = vec![
            format!("G01 X{} Z0.0000", mm4(28.0 - xcd)),
            format!("G01 X48.0000 Z{}", mm4(-10.0 - zc)),
            format!("G01 X48.0000 Z{}", mm4(-46.0 - zc)),
            format!("G01 X{} Z-56.0000", mm4(68.0 - xcd)),
            format!("G01 X{} Z-56.0000", mm4(94.0 - xcd)),
            format!("G01 X114.0000 Z{}", mm4(-66.0 - zc)),
        ];
        assert_eq!(want[0], "G01 X27.5314 Z0.0000");
        assert_eq!(want[1], "G01 X48.0000 Z-10.2343");
        let at = find_run(&out, &want);
        assert!(at.is_some(), "{out:#?}");
        // Krylenko's printed figures, within 0.001 mm.
        let kr = [
            (27.532, 0.0),
            (48.0, -10.234),
            (48.0, -46.234),
            (67.532, -56.0),
            (93.532, -56.0),
            (114.0, -66.234),
        ];
        for (t, (x, z)) in want.iter().zip(kr) {
            assert!((num(t, 'X') - x).abs() <= 0.001, "{t}");
            assert!((num(t, 'Z') - z).abs() <= 0.001, "{t}");
        }
        // Whole output: the rapid, the start-up, the six, the last element
        // ending perpendicular and the cancel move.
        assert_eq!(
            out,
            [
                s(&["G00 X20.0000 Z5.0000", "G01 X19.2000 Z0.0000"]),
                want,
                s(&["G01 X114.0000 Z-80.4000", "G01 X120.0000 Z-80.0000"])
            ]
            .concat()
        );
    }

    const FIG17: [&str; 9] = [
        "G00 X90 Z5",
        "G41 G01 Z0",
        "X78",
        "X50 Z-14",
        "Z-34",
        "X28 Z-45",
        "X12",
        "Z-60",
        "G40 X10",
    ];

    #[test]
    fn fig17_internal_tapers() {
        let out = run(
            CompSettings {
                tip: 2,
                ..krylenko()
            },
            &FIG17,
        );
        let want = s(&[
            "G01 X78.4686 Z0.0000",
            "G01 X50.0000 Z-14.2343",
            "G01 X50.0000 Z-34.2343",
            "G01 X28.4686 Z-45.0000",
            "G01 X12.0000 Z-45.0000",
        ]);
        assert!(find_run(&out, &want).is_some(), "{out:#?}");
        let kr = [
            (78.468, 0.0),
            (50.0, -14.234),
            (50.0, -34.234),
            (28.468, -45.0),
            (12.0, -45.0),
        ];
        for (t, (x, z)) in want.iter().zip(kr) {
            assert!((num(t, 'X') - x).abs() <= 0.001, "{t}");
            assert!((num(t, 'Z') - z).abs() <= 0.001, "{t}");
        }
    }

    fn fig22(form_ik: bool) -> Vec<&'static str> {
        let arcs = if form_ik {
            [
                "G03 X12 Z-2 I0 K-2",
                "G02 X18 Z-17 I3 K0",
                "G03 X38 Z-21 I0 K-4",
            ]
        } else {
            ["G03 X12 Z-2 R2", "G02 X18 Z-17 R3", "G03 X38 Z-21 R4"]
        };
        vec![
            "G00 X0 Z2",
            "G42 G01 Z0",
            "X8",
            arcs[0],
            "G01 Z-14",
            arcs[1],
            "G01 X30",
            arcs[2],
            "G01 Z-30",
            "G40 X50",
        ]
    }

    #[test]
    fn fig22_arcs() {
        let want = s(&[
            "G01 X7.2000 Z0.0000",
            "G03 X12.0000 Z-2.4000 I0.0000 K-2.4000",
            "G01 X12.0000 Z-14.4000",
            "G02 X17.2000 Z-17.0000 I2.6000 K0.0000",
            "G01 X29.2000 Z-17.0000",
            "G03 X38.0000 Z-21.4000 I0.0000 K-4.4000",
        ]);
        let out_r = run(krylenko(), &fig22(false));
        assert!(find_run(&out_r, &want).is_some(), "{out_r:#?}");
        let out_ik = run(krylenko(), &fig22(true));
        assert_eq!(out_r, out_ik);

        // The radii of the compensated arcs, from the blocks themselves.
        let mut c = RefContour::new(krylenko());
        let mut radii = Vec::new();
        for l in fig22(false) {
            let start = c.ttt_mm();
            let Ok(blocks) = c.block(l) else {
                panic!("{l} refused")
            };
            let mut from = start;
            for b in blocks {
                if let Some((cx, cz)) = b.centre {
                    let r0 = (from.0 - cx).hypot(from.1 - cz);
                    let r1 = (b.x - cx).hypot(b.z - cz);
                    assert!((r0 - r1).abs() < 1e-12);
                    radii.push(r0);
                }
                from = b.end();
            }
        }
        assert_eq!(radii.len(), 3);
        for (r, want) in radii.iter().zip([2.4, 2.6, 4.4]) {
            assert!((r - want).abs() < 1e-12, "{r} vs {want}");
        }
    }

    #[test]
    fn r_sign_and_direction() {
        // Compensation off: the centre is where the R convention puts it.
        let mut c = RefContour::new(krylenko());
        c.block("G01 X8 Z0").unwrap_or_default();
        let b = c.block("G03 X12 Z-2 R2").unwrap_or_default();
        let (cx, cz) = b[0].centre.unwrap_or((f64::NAN, f64::NAN));
        assert!(
            (cx - 4.0).abs() < 1e-12 && (cz + 2.0).abs() < 1e-12,
            "{cx} {cz}"
        );
        let mut c = RefContour::new(krylenko());
        c.block("G01 X8 Z0").unwrap_or_default();
        let b = c.block("G03 X12 Z-2 R-2").unwrap_or_default();
        let (cx, cz) = b[0].centre.unwrap_or((f64::NAN, f64::NAN));
        assert!((cx - 6.0).abs() < 1e-12 && cz.abs() < 1e-12, "{cx} {cz}");
        assert_eq!(
            b[0].text((4.0, 0.0), true),
            "G03 X12.0000 Z-2.0000 I2.0000 K0.0000"
        );
        let mut c = RefContour::new(krylenko());
        c.block("G01 X12 Z-14").unwrap_or_default();
        let b = c.block("G02 X18 Z-17 R3").unwrap_or_default();
        let (cx, cz) = b[0].centre.unwrap_or((f64::NAN, f64::NAN));
        assert!((cx - 9.0).abs() < 1e-12 && (cz + 14.0).abs() < 1e-12);
    }

    fn refused(c: &mut RefContour, line: &str) -> RefRefusal {
        let before = c.clone();
        match c.block(line) {
            Ok(b) => panic!("{line} accepted: {b:?}"),
            Err(e) => {
                assert_eq!(*c, before, "{line} changed the state");
                e
            }
        }
    }

    fn fed(prog: &[&str]) -> RefContour {
        let mut c = RefContour::new(krylenko());
        for l in prog {
            if let Err(e) = c.block(l) {
                panic!("{l}: {e}");
            }
        }
        c
    }

    #[test]
    fn refuses_concave_arc_not_larger_than_nose() {
        // G42 with G02: the tool is inside.
        let mut c = fed(&["G00 X12 Z2", "G42 G01 Z0", "N20 Z-14"]);
        let e = refused(&mut c, "N30 G02 X12.8 Z-14.4 R0.4");
        assert_eq!(e.kind, RefusalKind::Geometry);
        assert!(
            e.reason.contains("N30") && e.reason.contains("concave"),
            "{e}"
        );
        let e = refused(&mut c, "N30 G02 X12.8 Z-14.4 I0.4 K0");
        assert!(e.reason.contains("concave"), "{e}");
        // R 0.5 > r: accepted.
        assert!(c.block("G02 X13 Z-14.5 R0.5").is_ok());
        // The same R0.4 arc convex (G42 with G03) is fine.
        let mut c = fed(&["G00 X12 Z2", "G42 G01 Z0", "Z-14"]);
        assert!(c.block("G03 X11.2 Z-14.4 R0.4").is_ok());
    }

    #[test]
    fn refuses_arc_switching() {
        let mut c = fed(&["G00 X20 Z5"]);
        let e = refused(&mut c, "N5 G41 G03 X12 Z0 R4");
        assert!(e.reason.contains("switched on"), "{e}");
        // Armed without motion, then an arc as start-up block.
        let mut c = fed(&["G00 X20 Z5", "G42"]);
        let e = refused(&mut c, "G02 X12 Z0 R5");
        assert!(e.reason.contains("switched on"), "{e}");
        // G40 in an arc block while an element is pending.
        let mut c = fed(&["G00 X8 Z2", "G42 G01 Z0", "X8 Z-5"]);
        let e = refused(&mut c, "G40 G03 X12 Z-7 R2");
        assert!(e.reason.contains("switched off"), "{e}");
        // G41 while G42 is on.
        let e = refused(&mut c, "G41 X10");
        assert!(e.reason.contains("G41 while G42"), "{e}");
        let e = refused(&mut c, "G41");
        assert!(e.reason.contains("G41 while G42"), "{e}");
    }

    #[test]
    fn refuses_end_point_off_its_circle() {
        let mut c = fed(&["G01 X8 Z0"]);
        let e = refused(&mut c, "G03 X12 Z-2 I0 K-2.003");
        assert!(e.reason.contains("not on its circle"), "{e}");
        // Radii 2.002 and √(4 + 0.002²) differ by less than 0.002: accepted.
        assert!(c.clone().block("G03 X12 Z-2 I0 K-2.002").is_ok());
        // Exactly 0.002 apart: accepted (5 → 5.002).
        let mut c = fed(&["G01 X10 Z0"]);
        assert!(c.clone().block("G02 X0 Z-5.002 I-5 K0").is_ok());
        let e = refused(&mut c, "G02 X0 Z-5.0021 I-5 K0");
        assert!(e.reason.contains("not on its circle"), "{e}");
    }

    /// A 45° taper of 0.05 mm on the radius between two inside corners
    /// (G42): each corner takes r·tan 22.5° ≈ 0.166 mm of it.
    const SHORT: [&str; 4] = ["G00 X48 Z2", "G42 G01 Z0", "Z-46", "N50 X48.1 Z-46.05"];

    #[test]
    fn refuses_short_segment_between_inside_corners() {
        let mut c = fed(&SHORT);
        let e = refused(&mut c, "N60 X94");
        assert_eq!(e.kind, RefusalKind::Geometry);
        assert!(
            e.reason.contains("N50") && e.reason.contains("too short"),
            "{e}"
        );
        // The element stays pending: an outside corner after it extends it
        // by as much as the first corner took (G451, 45°), so it is accepted.
        let out = c.block_text("N60 Z-60");
        let Ok(out) = out else { panic!("{out:?}") };
        assert_eq!(out.len(), 1);
        // And the result equals the one without the refused attempt.
        let mut fresh = fed(&SHORT);
        assert_eq!(fresh.block_text("N60 Z-60").ok(), Some(out));
        // Also refused by G40: the first corner alone reverses it.
        let mut c = fed(&SHORT);
        let e = refused(&mut c, "G40 X100");
        assert!(e.reason.contains("N50"), "{e}");
    }

    #[test]
    fn refused_block_leaves_state_unchanged() {
        let clean = run(krylenko(), &FIG12);
        // Each kind of bad line, inserted everywhere, changes nothing.
        let bad = [
            "G41 X60",
            "G02 X30 Z-3 R0.1",
            "X1.2.3",
            "Q5",
            "G40 G02 X50 Z-50 R10",
            "X48 Z-10 I1",
        ];
        for pos in 2..FIG12.len() {
            for b in bad {
                let mut c = RefContour::new(krylenko());
                let mut out = Vec::new();
                for (i, l) in FIG12.iter().enumerate() {
                    if i == pos {
                        let before = c.clone();
                        assert!(c.block(b).is_err(), "{b} at {pos}");
                        assert_eq!(c, before);
                    }
                    out.extend(c.block_text(l).unwrap_or_default());
                }
                out.extend(c.finish_text());
                assert_eq!(out, clean, "{b} at {pos}");
            }
        }
    }

    /// Face up to X20 then a 45° taper away from the tool side (outside for
    /// G42).
    const OUTSIDE45: [&str; 5] = ["G00 X0 Z2", "G42 G01 Z0", "X20", "X28 Z-4", "Z-10"];

    #[test]
    fn outside_corner_g451_vs_g450() {
        let r: f64 = 0.4;
        let tan = (PI / 8.0).tan();
        // G451: the face ends at the vertex V = A1 + r·tan(22.5°)·t1.
        let g451 = run(krylenko(), &OUTSIDE45);
        let v = format!("G01 X{} Z0.0000", mm4(2.0 * (10.0 + r * tan - r)));
        assert_eq!(g451[2], v, "{g451:#?}");
        // The taper starts there: no inserted move.
        assert!(g451[3].starts_with("G01 X28.0000"), "{g451:#?}");
        // G450: the face ends at A1, then a G03 arc of radius r about the
        // corner to A2, then the taper from A2.
        let mut prog = OUTSIDE45.to_vec();
        prog[1] = "G42 G450 G01 Z0";
        let g450 = run(krylenko(), &prog);
        assert_eq!(g450[2], "G01 X19.2000 Z0.0000");
        let h = r / 2f64.sqrt();
        let a2 = (10.0 + h - r, h - r); // TTT (x radius, z)
        assert_eq!(
            g450[3],
            format!(
                "G03 X{} Z{} I{} K{}",
                mm4(2.0 * a2.0),
                mm4(a2.1),
                mm4(0.0),
                mm4(-r)
            )
        );
        // Both corners (face→taper, taper→Z-10) are outside: one arc each.
        assert_eq!(g450.len(), g451.len() + 2);
        assert!(g450[5].starts_with("G03 "), "{g450:#?}");
        // G451 restores the vertex for a later corner.
        let mut c = fed(&["G00 X0 Z2", "G42 G450 G01 Z0", "X20"]);
        let out = c.block_text("G451 X28 Z-4").unwrap_or_default();
        assert_eq!(out, [v]);
    }

    #[test]
    fn square_off_sharp_outside_corner() {
        // Face up to X20 (t1 = +X), then back down at 135° (left turn, away
        // from the G42 side): square-off V1 = A1 + r·t1, V2 = A2 − r·t2.
        let out = run(
            krylenko(),
            &["G00 X0 Z2", "G42 G01 Z0", "X20", "X10 Z-5", "Z-10"],
        );
        let r: f64 = 0.4;
        let h = r / 2f64.sqrt();
        // V1 (nose centre) = (z 0.4, x 10.4) → TTT (0, 10).
        assert_eq!(out[2], "G01 X20.0000 Z0.0000");
        // V2 = A2 + r·(h, h)/r: A2 = (−h, 10 + h) → (0, 10 + 2h) → TTT.
        assert_eq!(
            out[3],
            format!("G01 X{} Z{}", mm4(2.0 * (10.0 + 2.0 * h - r)), mm4(-r))
        );
        // The taper then runs from V2.
        assert!(out[4].starts_with("G01 X10.0000 Z-"), "{out:#?}");
        // With G450 the same corner is one arc of 135°.
        let out = run(
            krylenko(),
            &["G00 X0 Z2", "G42 G450 G01 Z0", "X20", "X10 Z-5", "Z-10"],
        );
        assert_eq!(out[2], "G01 X19.2000 Z0.0000");
        assert!(out[3].starts_with("G03 "), "{out:#?}");
        assert!(out[4].starts_with("G01 X10.0000 Z-"), "{out:#?}");
    }

    #[test]
    fn arcs_are_not_lengthened() {
        // Face up to X20, then G03 turning 90° left (outside for G42) into a
        // convex arc: the face ends at V, a straight move V → A2 is inserted
        // and the arc starts at A2.
        let out = run(
            krylenko(),
            &[
                "G00 X0 Z2",
                "G42 G01 Z0",
                "X20",
                "G03 X16 Z-2 I-2 K0",
                "G01 X10",
            ],
        );
        assert_eq!(out[2], "G01 X20.0000 Z0.0000");
        assert_eq!(out[3], "G01 X20.0000 Z-0.4000");
        assert_eq!(out[4], "G03 X15.2000 Z-2.8000 I-2.4000 K0.0000");
        // Mirror: arc first (ending along −Z), then a 90° left turn down the
        // face (outside for G42), then an inside corner along −Z.
        let out = run(
            krylenko(),
            &[
                "G00 X0 Z2",
                "G42 G01 Z0",
                "X8",
                "G03 X12 Z-2 R2",
                "G01 X8",
                "Z-4",
            ],
        );
        // The arc ends at A1 (its perpendicular point), then a straight move
        // along its tangent to V; the face runs from V.
        assert_eq!(out[3], "G03 X12.0000 Z-2.4000 I0.0000 K-2.4000");
        assert_eq!(out[4], "G01 X12.0000 Z-2.8000");
        assert_eq!(out[5], "G01 X8.0000 Z-2.8000");
    }

    #[test]
    fn inside_corners_with_arcs() {
        // Line → concave arc (G42 with G02: tool inside, offset radius
        // 4.6): the line ends where its offset line x = 10.4 meets the
        // offset circle about (z 3, x 14), nearest the corner (z 0, x 10).
        let out = run(
            krylenko(),
            &[
                "G00 X20 Z5",
                "G42 G01 Z2",
                "Z0",
                "G02 X28 Z-2 I4 K3",
                "G01 X40",
            ],
        );
        let z_end = 3.0 - 8.2f64.sqrt();
        assert_eq!(out[2], format!("G01 X20.0000 Z{}", mm4(z_end - 0.4)));
        // The arc runs from there on radius 4.6 and ends perpendicular
        // before the face (smooth).
        assert_eq!(
            out[3],
            format!("G02 X27.2000 Z-2.0000 I{} K{}", mm4(3.6), mm4(3.0 - z_end))
        );
        // Convex arc → convex arc meeting in a valley (G42 with G03 twice,
        // right turn: inside): the two offset circles of radius 5.4 about
        // (z −3, x 6) and (z −9, x 6) meet at z −6, x 6 ± √20.16. (The line
        // before the first arc is an inside corner too.)
        let out = run(
            krylenko(),
            &[
                "G00 X20 Z5",
                "G42 G01 Z2",
                "Z0",
                "G03 X20 Z-6 I-4 K-3",
                "G03 X20 Z-12 I-4 K-3",
            ],
        );
        let x = 6.0 + 20.16f64.sqrt();
        let want = format!("G03 X{} Z-6.4000", mm4(2.0 * (x - 0.4)));
        assert!(out[3].starts_with(&want), "{out:#?}");
        // The second arc starts there: its I, K reach the same centre.
        assert_eq!(
            out[4],
            format!("G03 X19.8400 Z-12.6400 I{} K{}", mm4(6.0 - x), mm4(-3.0))
        );
    }

    #[test]
    fn zero_nose_radius_gives_the_programmed_contour() {
        let want = s(&[
            "G00 X0.0000 Z2.0000",
            "G01 X0.0000 Z0.0000",
            "G01 X8.0000 Z0.0000",
            "G03 X12.0000 Z-2.0000 I0.0000 K-2.0000",
            "G01 X12.0000 Z-14.0000",
            "G02 X18.0000 Z-17.0000 I3.0000 K0.0000",
            "G01 X30.0000 Z-17.0000",
            "G03 X38.0000 Z-21.0000 I0.0000 K-4.0000",
            "G01 X38.0000 Z-30.0000",
            "G01 X50.0000 Z-30.0000",
        ]);
        let zero = CompSettings {
            rn_mm: 0.0,
            ..krylenko()
        };
        assert_eq!(run(zero, &fig22(false)), want);
        // Outside corners (G450 arcs, G451 vertices) collapse onto the
        // programmed point too: inserted moves of zero length are left out.
        let fig12 = s(&[
            "G00 X20.0000 Z5.0000",
            "G01 X20.0000 Z0.0000",
            "G01 X28.0000 Z0.0000",
            "G01 X48.0000 Z-10.0000",
            "G01 X48.0000 Z-46.0000",
            "G01 X68.0000 Z-56.0000",
            "G01 X94.0000 Z-56.0000",
            "G01 X114.0000 Z-66.0000",
            "G01 X114.0000 Z-80.0000",
            "G01 X120.0000 Z-80.0000",
        ]);
        assert_eq!(run(zero, &FIG12), fig12);
        let mut prog = FIG12.to_vec();
        prog[1] = "G42 G450 G01 Z0";
        assert_eq!(run(zero, &prog), fig12);
        assert_eq!(run(zero, &fig22(true)), want);
    }

    #[test]
    fn tip_codes_shift_the_ttt() {
        // (x, z) tip vectors from docs/compensation.md, written out.
        let table: [(f64, f64); 10] = [
            (0.0, 0.0),
            (0.4, 0.4),
            (0.4, -0.4),
            (-0.4, -0.4),
            (-0.4, 0.4),
            (0.0, 0.4),
            (0.4, 0.0),
            (0.0, -0.4),
            (-0.4, 0.0),
            (0.0, 0.0),
        ];
        // Nose centre at the end of Fig. 12's face: (x 14 + 0.4·tan 22.5°,
        // z 0.4).
        let cx = 14.0 + 0.4 * (PI / 8.0).tan();
        for (tip, (dx, dz)) in table.iter().enumerate() {
            let settings = CompSettings {
                tip: tip as u8,
                ..krylenko()
            };
            assert_eq!(settings.tip_vector(), (*dx, *dz));
            let out = run(settings, &FIG12);
            assert_eq!(
                out[2],
                format!("G01 X{} Z{}", mm4(2.0 * (cx + dx)), mm4(0.4 + dz)),
                "TIP {tip}"
            );
            // Uncompensated blocks do not move with the tip.
            assert_eq!(out[0], "G00 X20.0000 Z5.0000");
            assert_eq!(
                out.last().map(String::as_str),
                Some("G01 X120.0000 Z-80.0000")
            );
        }
        let bad = CompSettings {
            tip: 10,
            ..krylenko()
        };
        assert!(RefContour::new(bad).block("G01 X1").is_err());
    }

    #[test]
    fn compensation_off_passes_programmed_points() {
        let out = run(
            krylenko(),
            &[
                "G0 X20 Z5",
                "G1 Z0",
                "X28",
                "G91 X2 Z-1",
                "G90 G02 X30 Z-3 R1",
            ],
        );
        assert_eq!(
            out,
            s(&[
                "G00 X20.0000 Z5.0000",
                "G01 X20.0000 Z0.0000",
                "G01 X28.0000 Z0.0000",
                "G01 X30.0000 Z-1.0000",
                "G02 X30.0000 Z-3.0000 I0.0000 K-1.0000",
            ])
        );
    }

    #[test]
    fn incremental_and_no_motion_blocks() {
        let clean = run(krylenko(), &FIG12);
        // Same contour in G91 increments (diameter increments on X).
        let inc = run(
            krylenko(),
            &[
                "G00 X20 Z5",
                "G91 G42 G01 Z-5",
                "X8",
                "X20 Z-10",
                "Z-36",
                "X20 Z-10",
                "X26",
                "X20 Z-10",
                "Z-14",
                "G40 X6",
            ],
        );
        assert_eq!(inc, clean);
        // No-motion lines in between pass without output or effect.
        let mut c = RefContour::new(krylenko());
        let mut out = Vec::new();
        for l in FIG12 {
            out.extend(c.block_text(l).unwrap_or_default());
            for extra in [
                "F0.2 S1200 M3",
                "(comment only)",
                "",
                "N99 T0303",
                "Z-1000 G02",
            ] {
                let before_out = c.block_text(extra);
                assert_eq!(before_out, Ok(vec![]), "{extra}");
                // The G02 modal change must not stick for the next line.
                c.block("G01").unwrap_or_default();
            }
        }
        out.extend(c.finish_text());
        assert_eq!(out, clean);
    }

    #[test]
    fn g40_without_motion_and_finish() {
        let mut c = fed(&["G00 X20 Z5", "G42 G01 Z0", "X28", "X48 Z-10"]);
        let out = c.block_text("G40").unwrap_or_default();
        // The taper ends at its perpendicular offset point.
        let h = 0.4 / 2f64.sqrt();
        assert_eq!(
            out,
            [format!(
                "G01 X{} Z{}",
                mm4(2.0 * (24.0 + h - 0.4)),
                mm4(-10.0 + h - 0.4)
            )]
        );
        assert_eq!(c.side(), None);
        // The next motion starts from there, uncompensated.
        assert_eq!(
            c.block_text("X60").unwrap_or_default(),
            ["G01 X60.0000 Z-10.0000"]
        );
        // finish() does the same as G40 without motion.
        let mut c = fed(&["G00 X20 Z5", "G42 G01 Z0", "X28", "X48 Z-10"]);
        assert_eq!(c.finish_text(), out);
        assert!(c.finish().is_empty());
        // A start-up block followed directly by G40 uses its own normal.
        let mut c = fed(&["G00 X20 Z5", "G42 G01 Z0"]);
        assert_eq!(
            c.block_text("G40 X30").unwrap_or_default(),
            ["G01 X20.0000 Z-0.4000", "G01 X30.0000 Z0.0000"]
        );
    }

    #[test]
    fn parses_words_loosely_and_refuses_bad_ones() {
        let packed = run(
            krylenko(),
            &[
                "g00x20z5",
                "N10G42G01Z0 (start)",
                "x28;face",
                "X48Z-10",
                "Z-46",
                "x68 z-56",
                "X94",
                "X114 Z-66",
                "Z-80",
                "G40X120",
            ],
        );
        assert_eq!(packed, run(krylenko(), &FIG12));
        let mut c = RefContour::new(krylenko());
        for (bad, kind) in [
            ("X1.2.3", RefusalKind::Value),
            ("X1e3", RefusalKind::Syntax),
            ("X", RefusalKind::Value),
            ("X1.1234567", RefusalKind::Value),
            ("X100000", RefusalKind::Value),
            ("Q5", RefusalKind::Syntax),
            ("X1 X2", RefusalKind::Syntax),
            ("G00 G01 X1", RefusalKind::Syntax),
            ("G40 G41", RefusalKind::Syntax),
            ("G17", RefusalKind::Value),
            ("G01 X1 (open", RefusalKind::Syntax),
            ("X1 R2", RefusalKind::Syntax),
            ("G02 X1 R2 I1", RefusalKind::Syntax),
            ("G02 X0 Z0 R2", RefusalKind::Geometry),
            ("G02 X0 Z-10 R2", RefusalKind::Geometry),
        ] {
            let e = refused(&mut c, bad);
            assert_eq!(e.kind, kind, "{bad}: {e}");
        }
        let mut c = fed(&["G91 G01 Z-99999.999999"]);
        let e = refused(&mut c, "Z-0.000001");
        assert_eq!(e.kind, RefusalKind::Range);
    }

    #[test]
    fn full_circle_and_tie_margin() {
        // A full convex circle (I/K, end = start) after a tangent line.
        let out = run(
            krylenko(),
            &[
                "G00 X20 Z2",
                "G42 G01 Z0",
                "Z-5",
                "G03 X20 Z-5 I-5 K0",
                "G01 Z-10",
            ],
        );
        assert_eq!(out[3], "G03 X20.0000 Z-5.4000 I-5.4000 K0.0000", "{out:#?}");
        let b = RefBlock {
            motion: RefMotion::Linear,
            x: 13.76569,
            z: 0.000049,
            centre: None,
        };
        // X (diameter 27.53138) is 0.00003 from the tie 27.53135; Z 0.000001.
        assert!((tie_margin(&b, (0.0, 0.0), true) - 1e-6).abs() < 1e-9);
        let b = RefBlock { z: 0.0, ..b };
        assert!((tie_margin(&b, (0.0, 0.0), true) - 3e-5).abs() < 1e-9);
        assert_eq!(fmt_units4(-1), "0.0000");
        assert_eq!(fmt_units4(-500), "-0.0001");
        assert_eq!(fmt_units4(499), "0.0000");
    }
}

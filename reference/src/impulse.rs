//! Double-precision (f64) reference model of the lathe controller's impulse rules.
//!
//! This module computes, for every linear block, the impulses each axis issues,
//! the axis positions in impulses and the interleaved step sequence with its
//! CRC-32 (`SEQ`), exactly as `docs/units.md` §1–§3, `docs/impulses.md`
//! §2–§3, `docs/verification.md` §2 and the `MOVE`, `CFG` and `ZERO` commands
//! of `docs/protocol.md` §4 define them. It is written from those pages
//! alone, independently of the controller's fixed-point core, so
//! that the two can be compared bit for bit: same impulse counts, same step
//! bytes, same `SEQ`.
//!
//! # Rules implemented
//!
//! * The impulse register of an axis at a point is `Q(P/h)`: `P` the exact
//!   commanded coordinate since program zero (X on the radius; a diameter word
//!   is halved exactly), `h` the axis price. A block issues
//!   `Q(P1/h) − Q(P0/h)`. `Q` rounds half away from zero. The residual carry
//!   of `docs/impulses.md` §1 is this closed form: nothing is lost between blocks.
//! * Step sequence of a block from `(a0, b0)` to `(a1, b1)`: the lead axis is
//!   the one with the larger `|Δ|` (X when equal). For `i = 1 … |Δlead|`,
//!   event `i` steps the lead axis once and puts the other axis at
//!   `b0 + Q(i·Δb/|Δlead|)`; it steps too when that value changed. One byte
//!   per event: bit0 X steps, bit1 Z steps, bit2 X steps negative, bit3 Z
//!   steps negative (a direction bit is 0 for an axis that does not step).
//!   `SEQ` is the CRC-32 (IEEE, as in zlib) of those bytes; an empty block has
//!   `SEQ` 0.
//! * Price change (`CFG HX=`/`HZ=`): the commanded coordinates (mm) are kept
//!   and each register is re-expressed as `Q(P/h_new)`; no motion is issued.
//!   A change of `DIAM` only changes how later X words are read.
//! * `ZERO`: commanded coordinates and both registers become 0.
//!
//! # Ties: how an exact tie is told apart from a near one
//!
//! `Q` needs to know whether a value is exactly `k + ½`. The values are
//! computed in f64, so the decision is made with a tolerance, and that
//! tolerance is derived here from the input granularity.
//!
//! Notation: `u = 2⁻⁵³` is the unit roundoff of f64.
//!
//! **Quantizer, `v = P/h`.** Lengths are decimals with at most 6 decimals, so
//! a diameter word halved is a whole number `p` of half-nanometres:
//! `P = p · 5·10⁻⁷ mm`. A price is `h = q · 10⁻⁶ mm` with `q ≥ 1` an integer.
//! Hence `v = p / (2q)`, a ratio of integers, and when it is not an exact tie
//! its distance to the nearest `k + ½` is `|p − (2k+1)q| / (2q) ≥ 1/(2q)`
//! impulses (`5·10⁻⁷/h` impulses, `h` in mm: 10⁻⁴ impulse at 0.005 mm,
//! 5·10⁻⁵ at 0.01 mm, 5·10⁻⁷ at a coarse 1 mm).
//!
//! The model keeps `p` as an exact integer (see below) and computes
//! `P_mm = p / 2·10⁶` (one rounding), takes `h_mm` as the f64 nearest to the
//! decimal price (one rounding) and divides (one rounding), so
//! `|v̂ − v| ≤ 3u·|v|(1 + O(u)) < 2⁻⁵¹·|v|`. The distance `d̂` of `v̂` to the
//! nearest half-integer is then taken without further rounding where it
//! matters (`|v̂| − ⌊|v̂|⌋` and the subtraction of ½ are exact for the
//! fractions near ½).
//!
//! The rule is: **exact tie ⇔ `d̂ ≤ τ·|v̂|` with `τ = 2⁻⁴⁴ ≈ 5.7·10⁻¹⁴`**.
//!
//! * An exact tie has `d̂ ≤ 2⁻⁵¹|v|`, which is below `τ|v̂|` by a factor of
//!   about 128, at every magnitude.
//! * A non-tie has `d̂ ≥ 1/(2q) − 2⁻⁵¹|v|`, which exceeds `τ|v̂|` as long as
//!   `|v|·q < 2⁴³/(1 + 2⁻⁷)`. Since `|v|·q = |P|·10⁶` with `P` in mm, the
//!   condition does not depend on the price: it holds for `|P| < 8.7·10⁶ mm`.
//!   The model refuses coordinates beyond [`MAX_COORD_MM`] (10⁶ mm), leaving
//!   a factor above 8 of margin. On a lathe (`|P| ≤ 1000 mm`, `h = 0.005`)
//!   the tolerance is at most 1.1·10⁻⁸ impulse, against a smallest non-tie
//!   distance of 10⁻⁴ impulse and an f64 error of at most 9·10⁻¹¹ impulse.
//!
//! A fixed relative tolerance such as 10⁻⁹ would not do: it exceeds the
//! non-tie distance `1/(2q)` as soon as `|P| > 500 mm` (a diameter word
//! `1200.004999` at 0.005 mm is 120000.4999 impulses and must round down).
//!
//! **Interleaver, `v = i·Δb/|Δlead|`.** With `L = |Δlead|`, `|Δb| ≤ L` and
//! `i ≤ L`, the numerator `i·Δb` is an exact integer in f64 and the division
//! is correctly rounded, so `|v̂ − v| ≤ u|v|`; an exact tie `k + ½` is
//! representable and therefore comes out exactly (`d̂ = 0`). A non-tie lies at
//! least `1/(2L)` from a tie, which exceeds `τ|v̂| + u|v|` (with `|v| ≤ L`)
//! while `L² < 2⁴³/(1 + 2⁻⁸)`, i.e. `L < 2.9·10⁶`. Blocks are limited to
//! [`MAX_BLOCK_IMPULSES`] = 2²¹ impulses, 16 times the machine's 130000.
//! The same [`quantize`] (same τ) serves both uses.
//!
//! Values that are not exact ties feed [`TieStats::min_distance`], so the
//! margin by which every rounding decision was made is visible.
//!
//! # Incremental words (`INC=1`) and accumulated error
//!
//! Summing increments into an f64 coordinate would break the argument above:
//! the error of a running f64 sum is bounded by the sizes of the partial sums,
//! not by the result, so it is not relative to `|v|`. Two blocks are enough:
//! Z `+1000.005` then `−1000` leaves `0.0049999999999954525` mm in f64, i.e.
//! 0.49999999999954525 impulse at 0.01 mm, a relative error of 9·10⁻¹³ > τ,
//! and the exact tie (0.5 → 1 impulse) would be rounded down to 0. Over tens
//! of thousands of blocks the bound `(N−1)u·Σ|xᵢ|` reaches hundredths of an
//! impulse. The model therefore keeps each commanded coordinate as an exact
//! integer number of half-nanometres (the input granularity; a diameter word
//! halved), so increments add without drift over any number of blocks, and
//! converts it to mm in f64 only where the rules are evaluated
//! (`P/h`, `Q`, the interleaver), which is where the error analysis applies.

use std::fmt;

/// Unit of the exact commanded coordinate: half-nanometres per mm.
pub(crate) const HALF_NM_PER_MM: i64 = 2_000_000;

/// Relative tolerance `τ = 2⁻⁴⁴` under which a value counts as an exact tie.
pub const TIE_TOLERANCE_REL: f64 = 1.0 / (1u64 << 44) as f64;

/// Largest commanded coordinate (absolute, mm) the model accepts; the tie
/// argument holds up to about 8.7·10⁶ mm.
pub const MAX_COORD_MM: i64 = 1_000_000;

/// Largest number of impulses the lead axis may move in one block; the tie
/// argument of the interleaver holds up to about 2.9·10⁶.
pub const MAX_BLOCK_IMPULSES: u64 = 1 << 21;

/// Step-event bit: X steps.
pub const BIT_X_STEP: u8 = 0x01;
/// Step-event bit: Z steps.
pub const BIT_Z_STEP: u8 = 0x02;
/// Step-event bit: X steps in the negative direction.
pub const BIT_X_NEG: u8 = 0x04;
/// Step-event bit: Z steps in the negative direction.
pub const BIT_Z_NEG: u8 = 0x08;

/// Machine settings the reference needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefConfig {
    /// Impulse price of X, mm per impulse on the radius.
    pub hx_mm: f64,
    /// Impulse price of Z, mm per impulse.
    pub hz_mm: f64,
    /// X words are diameters.
    pub diam: bool,
}

impl Default for RefConfig {
    fn default() -> Self {
        RefConfig {
            hx_mm: 0.005,
            hz_mm: 0.01,
            diam: true,
        }
    }
}

/// Statistics about how close the rounding decisions came to a tie (x.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TieStats {
    /// Values recognised as exact ties (rounded away from zero).
    pub exact_ties: u64,
    /// Smallest `|frac − 0.5|`, in impulses, over all values that were not
    /// exact ties; `f64::INFINITY` if none.
    pub min_distance: f64,
}

impl TieStats {
    /// No decisions recorded.
    pub fn new() -> Self {
        TieStats {
            exact_ties: 0,
            min_distance: f64::INFINITY,
        }
    }

    /// Adds the decisions recorded in `other`.
    pub fn merge(&mut self, other: &TieStats) {
        self.exact_ties += other.exact_ties;
        self.min_distance = self.min_distance.min(other.min_distance);
    }
}

impl Default for TieStats {
    fn default() -> Self {
        TieStats::new()
    }
}

/// The result of one linear block.
#[derive(Clone, Debug, PartialEq)]
pub struct RefBlock {
    /// Impulses issued by this block on X (signed, radius).
    pub nx: i64,
    /// Impulses issued by this block on Z (signed).
    pub nz: i64,
    /// X position in impulses after the block.
    pub px: i64,
    /// Z position in impulses after the block.
    pub pz: i64,
    /// CRC-32 (IEEE/zlib) of the block's step-event bytes; 0 for no events.
    pub seq: u32,
    /// Number of step events (= |Δlead|).
    pub events: u64,
    /// Rounding decisions of `Q(P/h)` at the end point.
    pub quantizer_ties: TieStats,
    /// Rounding decisions of `Q(i·Δb/|Δlead|)` inside the block.
    pub interleave_ties: TieStats,
}

/// Why a block was refused. A refused block changes no state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RefError {
    /// The word is not `[+-]digits[.digits]` with at most 6 decimals.
    Syntax {
        /// Axis letter of the word.
        axis: char,
        /// The word as given.
        word: String,
    },
    /// The commanded coordinate would exceed [`MAX_COORD_MM`].
    Range {
        /// Axis letter.
        axis: char,
    },
    /// The block would move an axis more than [`MAX_BLOCK_IMPULSES`].
    BlockTooLong {
        /// Axis letter.
        axis: char,
        /// Impulses the block would issue on that axis.
        impulses: i64,
    },
}

impl fmt::Display for RefError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RefError::Syntax { axis, word } => {
                write!(f, "{axis}: malformed length {word:?}")
            }
            RefError::Range { axis } => {
                write!(f, "{axis}: coordinate beyond {MAX_COORD_MM} mm")
            }
            RefError::BlockTooLong { axis, impulses } => write!(
                f,
                "{axis}: block of {impulses} impulses exceeds {MAX_BLOCK_IMPULSES}"
            ),
        }
    }
}

impl std::error::Error for RefError {}

/// Parses a length word `[+-]digits[.digits]` (at most 6 decimals, no
/// exponent) into an exact whole number of nanometres.
///
/// Returns `None` for a malformed word or a magnitude beyond
/// [`MAX_COORD_MM`] · 2 (a diameter word may be twice the radius limit).
pub fn parse_length_nm(word: &str) -> Option<i64> {
    let bytes = word.as_bytes();
    let (negative, rest) = match bytes.first() {
        Some(b'+') => (false, &bytes[1..]),
        Some(b'-') => (true, &bytes[1..]),
        _ => (false, bytes),
    };
    let (int_part, frac_part) = match rest.iter().position(|&c| c == b'.') {
        Some(dot) => (&rest[..dot], Some(&rest[dot + 1..])),
        None => (rest, None),
    };
    if int_part.is_empty() || !int_part.iter().all(u8::is_ascii_digit) {
        return None;
    }
    let limit_nm: i64 = 2 * MAX_COORD_MM * 1_000_000;
    let mut nm: i64 = 0;
    for &c in int_part {
        nm = nm.checked_mul(10)?.checked_add(i64::from(c - b'0'))?;
        if nm > limit_nm {
            return None;
        }
    }
    nm = nm.checked_mul(1_000_000)?;
    if let Some(frac) = frac_part {
        if frac.is_empty() || frac.len() > 6 || !frac.iter().all(u8::is_ascii_digit) {
            return None;
        }
        let mut scale = 100_000;
        for &c in frac {
            nm += i64::from(c - b'0') * scale;
            scale /= 10;
        }
    }
    if nm > limit_nm {
        return None;
    }
    Some(if negative { -nm } else { nm })
}

/// CRC-32 (IEEE, as in zlib) of step-event bytes: the `SEQ` value.
pub fn seq_crc(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

/// `Q` of `docs/impulses.md` §2.2 (round half away from zero) applied to an f64 number of
/// impulses. A value within `τ·|v|` of a half-integer (`τ` =
/// [`TIE_TOLERANCE_REL`]) is an exact tie: it is counted in
/// `ties.exact_ties` and rounded away from zero; for every other value its
/// distance to the nearest half-integer goes into `ties.min_distance`.
///
/// # Panics
/// If `v` is not finite or `|v| ≥ 2⁵²`.
pub fn quantize(v: f64, ties: &mut TieStats) -> i64 {
    assert!(
        v.is_finite() && v.abs() < 4_503_599_627_370_496.0,
        "quantize: {v} impulses is out of range"
    );
    let a = v.abs();
    let whole = a.floor();
    let frac = a - whole; // exact for |v| < 2^52
    let distance = (frac - 0.5).abs(); // exact whenever frac ≥ 1/4
    let up = if distance <= TIE_TOLERANCE_REL * a {
        ties.exact_ties += 1;
        true
    } else {
        ties.min_distance = ties.min_distance.min(distance);
        frac > 0.5
    };
    let magnitude = whole as i64 + i64::from(up);
    if v < 0.0 {
        -magnitude
    } else {
        magnitude
    }
}

/// Step-event bytes of a block from impulse position `from` to `to`, both
/// given as `(x, z)`, per `docs/impulses.md` §3. Rounding decisions of the interleaver are
/// recorded in `ties`.
///
/// # Panics
/// If the lead axis moves more than [`MAX_BLOCK_IMPULSES`].
pub fn step_events(from: (i64, i64), to: (i64, i64), ties: &mut TieStats) -> Vec<u8> {
    let dx = to.0 - from.0;
    let dz = to.1 - from.1;
    let x_leads = dx.unsigned_abs() >= dz.unsigned_abs();
    let (d_lead, d_other) = if x_leads { (dx, dz) } else { (dz, dx) };
    let (lead_step, lead_neg, other_step, other_neg) = if x_leads {
        (BIT_X_STEP, BIT_X_NEG, BIT_Z_STEP, BIT_Z_NEG)
    } else {
        (BIT_Z_STEP, BIT_Z_NEG, BIT_X_STEP, BIT_X_NEG)
    };
    let n = d_lead.unsigned_abs();
    assert!(
        n <= MAX_BLOCK_IMPULSES,
        "step_events: block of {n} impulses exceeds {MAX_BLOCK_IMPULSES}"
    );
    let lead_byte = if d_lead < 0 {
        lead_step | lead_neg
    } else {
        lead_step
    };
    let n_f = n as f64;
    let other_f = d_other as f64;
    let mut events = Vec::with_capacity(n as usize);
    let mut previous = 0i64;
    for i in 1..=n {
        // i·Δb is an exact integer in f64 (|i·Δb| ≤ 2^42); one rounding in the division.
        let b = quantize((i as f64 * other_f) / n_f, ties);
        let byte = match b - previous {
            0 => lead_byte,
            1 => lead_byte | other_step,
            -1 => lead_byte | other_step | other_neg,
            jump => unreachable!("interleaver jumped by {jump} impulses"),
        };
        previous = b;
        events.push(byte);
    }
    debug_assert_eq!(previous, if n == 0 { 0 } else { d_other });
    events
}

/// Normalises a price to the f64 nearest its decimal value (at most 6
/// decimals), which the tie argument assumes.
fn normalise_price(axis: char, h_mm: f64) -> f64 {
    assert!(
        h_mm.is_finite() && h_mm > 0.0,
        "{axis} price must be a positive number of mm, got {h_mm}"
    );
    let micro = h_mm * 1e6;
    let q = micro.round();
    assert!(
        (1.0..=1e12).contains(&q) && (micro - q).abs() <= 1e-6 * q,
        "{axis} price must be a decimal with at most 6 decimals, got {h_mm}"
    );
    q / 1e6
}

fn normalise_config(cfg: RefConfig) -> RefConfig {
    RefConfig {
        hx_mm: normalise_price('X', cfg.hx_mm),
        hz_mm: normalise_price('Z', cfg.hz_mm),
        diam: cfg.diam,
    }
}

/// `Q(P/h)` for a commanded coordinate held in half-nanometres.
pub(crate) fn register(p_half_nm: i64, h_mm: f64, ties: &mut TieStats) -> i64 {
    let p_mm = p_half_nm as f64 / HALF_NM_PER_MM as f64;
    quantize(p_mm / h_mm, ties)
}

/// The reference machine: commanded coordinates (X on the radius), impulse
/// registers and configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct RefMachine {
    pub(crate) cfg: RefConfig,
    /// Commanded X radius since program zero, exact, in half-nanometres.
    pub(crate) cmd_x: i64,
    /// Commanded Z since program zero, exact, in half-nanometres.
    pub(crate) cmd_z: i64,
    /// X register, impulses (`Q(cmd_x/hx)`).
    pub(crate) px: i64,
    /// Z register, impulses (`Q(cmd_z/hz)`).
    pub(crate) pz: i64,
    /// Lengths are this many times larger than the words say (1; see
    /// [`RefMachine::scaled`]).
    pub(crate) length_scale: u128,
}

impl RefMachine {
    /// A machine at program zero.
    ///
    /// # Panics
    /// If a price is not a positive decimal with at most 6 decimals.
    pub fn new(cfg: RefConfig) -> Self {
        RefMachine {
            cfg: normalise_config(cfg),
            cmd_x: 0,
            cmd_z: 0,
            px: 0,
            pz: 0,
            length_scale: 1,
        }
    }

    /// A machine whose words are read at `scale` times their size: a word
    /// of 1 nm stands for `1/scale` nm. Prices, tolerances and every
    /// coordinate are given scaled alike, so chord angles, chord counts and
    /// `Q(P/h)` are those of the unscaled arc; the arcs' radius mismatch
    /// limit (0.002 mm) is scaled with them. At scale 10 the 10⁻⁷ mm grid of
    /// compensated points becomes the nanometre grid of words.
    pub fn scaled(cfg: RefConfig, scale: u32) -> Self {
        RefMachine {
            length_scale: u128::from(scale.max(1)),
            ..RefMachine::new(cfg)
        }
    }

    /// Current settings (prices as the f64 nearest their decimal value).
    pub fn config(&self) -> RefConfig {
        self.cfg
    }

    /// Changes the settings. The commanded coordinates are kept and each
    /// register becomes `Q(P/h_new)`; no motion is issued.
    ///
    /// # Panics
    /// If a price is not a positive decimal with at most 6 decimals.
    pub fn set_config(&mut self, cfg: RefConfig) {
        self.set_config_with_ties(cfg);
    }

    /// [`set_config`](Self::set_config), returning the rounding decisions of
    /// re-expressing the registers.
    pub fn set_config_with_ties(&mut self, cfg: RefConfig) -> TieStats {
        let cfg = normalise_config(cfg);
        let mut ties = TieStats::new();
        self.px = register(self.cmd_x, cfg.hx_mm, &mut ties);
        self.pz = register(self.cmd_z, cfg.hz_mm, &mut ties);
        self.cfg = cfg;
        ties
    }

    /// `ZERO`: commanded coordinates and registers become 0.
    pub fn zero(&mut self) {
        self.cmd_x = 0;
        self.cmd_z = 0;
        self.px = 0;
        self.pz = 0;
    }

    /// `MOVE`: `x`/`z` are the words exactly as written in the request
    /// (`"-12.5"`, `"+0.000001"`, `"7"`); `None` = word omitted. X is a
    /// diameter when the configuration says so. `inc` = `INC=1`.
    ///
    /// # Panics
    /// If the block is refused (see [`try_move_block`](Self::try_move_block)).
    pub fn move_block(&mut self, x: Option<&str>, z: Option<&str>, inc: bool) -> RefBlock {
        match self.try_move_block(x, z, inc) {
            Ok(block) => block,
            Err(e) => panic!("MOVE refused: {e}"),
        }
    }

    /// `MOVE`, refusing malformed words, coordinates beyond [`MAX_COORD_MM`]
    /// and blocks longer than [`MAX_BLOCK_IMPULSES`]; a refused block changes
    /// no state.
    ///
    /// Only the axes whose word is present are quantized again (an omitted
    /// axis keeps its register and makes no rounding decision).
    pub fn try_move_block(
        &mut self,
        x: Option<&str>,
        z: Option<&str>,
        inc: bool,
    ) -> Result<RefBlock, RefError> {
        let limit = MAX_COORD_MM * HALF_NM_PER_MM;
        let target = |axis: char, word: &str, current: i64, half_nm_per_nm: i64| {
            let nm = parse_length_nm(word).ok_or_else(|| RefError::Syntax {
                axis,
                word: word.to_string(),
            })?;
            let half_nm = nm * half_nm_per_nm;
            let p = if inc { current + half_nm } else { half_nm };
            if p.abs() > limit {
                return Err(RefError::Range { axis });
            }
            Ok(p)
        };
        // A diameter word in nm is the radius in half-nm; a radius or Z word is twice that.
        let x_scale = if self.cfg.diam { 1 } else { 2 };
        let new_x = x.map(|w| target('X', w, self.cmd_x, x_scale)).transpose()?;
        let new_z = z.map(|w| target('Z', w, self.cmd_z, 2)).transpose()?;

        let mut quantizer_ties = TieStats::new();
        let px1 = match new_x {
            Some(p) => register(p, self.cfg.hx_mm, &mut quantizer_ties),
            None => self.px,
        };
        let pz1 = match new_z {
            Some(p) => register(p, self.cfg.hz_mm, &mut quantizer_ties),
            None => self.pz,
        };
        let nx = px1 - self.px;
        let nz = pz1 - self.pz;
        for (axis, n) in [('X', nx), ('Z', nz)] {
            if n.unsigned_abs() > MAX_BLOCK_IMPULSES {
                return Err(RefError::BlockTooLong { axis, impulses: n });
            }
        }

        let mut interleave_ties = TieStats::new();
        let bytes = step_events((self.px, self.pz), (px1, pz1), &mut interleave_ties);

        if let Some(p) = new_x {
            self.cmd_x = p;
        }
        if let Some(p) = new_z {
            self.cmd_z = p;
        }
        self.px = px1;
        self.pz = pz1;
        Ok(RefBlock {
            nx,
            nz,
            px: px1,
            pz: pz1,
            seq: seq_crc(&bytes),
            events: bytes.len() as u64,
            quantizer_ties,
            interleave_ties,
        })
    }

    /// `(PX, PZ)` in impulses.
    pub fn position(&self) -> (i64, i64) {
        (self.px, self.pz)
    }

    /// Commanded `(X radius, Z)` in half-nanometres, exact.
    pub fn commanded_half_nm(&self) -> (i64, i64) {
        (self.cmd_x, self.cmd_z)
    }

    /// Commanded `(X radius, Z)` in mm.
    pub fn commanded_mm(&self) -> (f64, f64) {
        (
            self.cmd_x as f64 / HALF_NM_PER_MM as f64,
            self.cmd_z as f64 / HALF_NM_PER_MM as f64,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn machine() -> RefMachine {
        RefMachine::new(RefConfig::default())
    }

    /// Exact `Q(n/d)`, round half away from zero, in integers: the exact
    /// model's.
    fn q_exact(n: i128, d: i128) -> i64 {
        crate::exact::q_div(n, d) as i64
    }

    /// A whole number of nanometres written as a decimal word.
    fn word(nm: i64) -> String {
        let sign = if nm < 0 { "-" } else { "" };
        let a = nm.unsigned_abs();
        format!("{sign}{}.{:06}", a / 1_000_000, a % 1_000_000)
    }

    /// Net signed steps per axis encoded in step-event bytes.
    fn net_steps(bytes: &[u8]) -> (i64, i64) {
        let mut x = 0;
        let mut z = 0;
        for &b in bytes {
            assert_eq!(b & 0xF0, 0, "unused bits set in {b:#04x}");
            if b & BIT_X_STEP != 0 {
                x += if b & BIT_X_NEG != 0 { -1 } else { 1 };
            } else {
                assert_eq!(b & BIT_X_NEG, 0, "X direction without step");
            }
            if b & BIT_Z_STEP != 0 {
                z += if b & BIT_Z_NEG != 0 { -1 } else { 1 };
            } else {
                assert_eq!(b & BIT_Z_NEG, 0, "Z direction without step");
            }
        }
        (x, z)
    }

    #[test]
    fn crc_check_value() {
        assert_eq!(seq_crc(b"123456789"), 0xCBF4_3926);
        assert_eq!(seq_crc(&[]), 0);
    }

    #[test]
    fn block_45_degrees() {
        // X diameter 0.03 → radius 0.015 mm = 3 impulses; Z −0.03 mm = −3 impulses.
        let mut m = machine();
        let b = m.move_block(Some("0.03"), Some("-0.03"), false);
        assert_eq!((b.nx, b.nz, b.px, b.pz), (3, -3, 3, -3));
        let mut t = TieStats::new();
        assert_eq!(step_events((0, 0), (3, -3), &mut t), vec![0x0B, 0x0B, 0x0B]);
        assert_eq!(t.exact_ties, 0);
        assert_eq!(b.events, 3);
        assert_eq!(b.seq, 0x8732_36B0);
    }

    #[test]
    fn block_2_to_1() {
        // Lead X, Δz = 2 over 4: Q(0.5)=1, Q(1)=1, Q(1.5)=2, Q(2)=2.
        let mut t = TieStats::new();
        let ev = step_events((0, 0), (4, 2), &mut t);
        assert_eq!(ev, vec![0x03, 0x01, 0x03, 0x01]);
        assert_eq!(t.exact_ties, 2);
        assert_eq!(t.min_distance, 0.5);
        assert_eq!(seq_crc(&ev), 0x6E19_7990);

        let mut t = TieStats::new();
        let ev = step_events((10, 10), (6, 8), &mut t);
        assert_eq!(ev, vec![0x0F, 0x05, 0x0F, 0x05]);
        assert_eq!(seq_crc(&ev), 0x881E_E5E1);

        // Lead Z (negative), X follows positive.
        let mut t = TieStats::new();
        let ev = step_events((0, 0), (2, -4), &mut t);
        assert_eq!(ev, vec![0x0B, 0x0A, 0x0B, 0x0A]);
        assert_eq!(seq_crc(&ev), 0xF8F3_ED1E);

        // Through the machine: X diameter 0.04 → 4 impulses, Z 0.02 → 2.
        let mut m = machine();
        let b = m.move_block(Some("0.04"), Some("0.02"), false);
        assert_eq!((b.nx, b.nz, b.events, b.seq), (4, 2, 4, 0x6E19_7990));
        assert_eq!(b.interleave_ties.exact_ties, 2);
    }

    #[test]
    fn block_3_to_1_is_not_a_tie() {
        let mut t = TieStats::new();
        let ev = step_events((0, 0), (3, 1), &mut t);
        assert_eq!(ev, vec![0x01, 0x03, 0x01]);
        assert_eq!(seq_crc(&ev), 0xA2A9_D070);
        assert_eq!(t.exact_ties, 0);
        assert!((t.min_distance - 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn empty_block() {
        let mut m = machine();
        let b = m.move_block(Some("0.001"), Some("0.004"), false);
        assert_eq!((b.nx, b.nz, b.events, b.seq), (0, 0, 0, 0));
        let b = m.move_block(None, None, false);
        assert_eq!((b.nx, b.nz, b.events, b.seq), (0, 0, 0, 0));
    }

    #[test]
    fn tie_at_diameter_0_005() {
        // Radius 0.0025 mm = 0.5 impulse at 0.005 → 1; −0.005 → −1.
        let mut m = machine();
        let b = m.move_block(Some("0.005"), None, false);
        assert_eq!((b.nx, b.px), (1, 1));
        assert_eq!(b.quantizer_ties.exact_ties, 1);
        assert_eq!(b.quantizer_ties.min_distance, f64::INFINITY);
        let b = m.move_block(Some("-0.005"), None, false);
        assert_eq!((b.nx, b.px), (-2, -1));
        assert_eq!(b.quantizer_ties.exact_ties, 1);
        assert_eq!(b.seq, seq_crc(&[0x05, 0x05]));
    }

    #[test]
    fn quantize_rounds_half_away_from_zero() {
        let mut t = TieStats::new();
        assert_eq!(quantize(2.5, &mut t), 3);
        assert_eq!(quantize(-2.5, &mut t), -3);
        assert_eq!(quantize(0.5, &mut t), 1);
        assert_eq!(quantize(-0.5, &mut t), -1);
        assert_eq!(t.exact_ties, 4);
        assert_eq!(quantize(2.4999, &mut t), 2);
        assert_eq!(quantize(-2.5001, &mut t), -3);
        assert_eq!(quantize(0.0, &mut t), 0);
        assert_eq!(quantize(-0.0, &mut t), 0);
        assert_eq!(quantize(7.0, &mut t), 7);
        assert_eq!(t.exact_ties, 4);
        assert!((t.min_distance - 1e-4).abs() < 1e-12);
    }

    #[test]
    fn near_tie_at_large_coordinate() {
        // Radius 600.0024995 mm = 120000.4999 impulses at 0.005: not a tie, rounds down.
        let mut m = machine();
        let b = m.move_block(Some("1200.004999"), None, false);
        assert_eq!(b.px, 120_000);
        assert_eq!(b.quantizer_ties.exact_ties, 0);
        assert!((b.quantizer_ties.min_distance - 1e-4).abs() < 1e-9);
        // 120000.5001 rounds up, 120000.5 is an exact tie and rounds up.
        let mut m = machine();
        assert_eq!(m.move_block(Some("1200.005001"), None, false).px, 120_001);
        let b = m.move_block(Some("1200.005"), None, false);
        assert_eq!(b.px, 120_001);
        assert_eq!(b.quantizer_ties.exact_ties, 1);
        let b = m.move_block(Some("-1200.005"), None, false);
        assert_eq!(b.px, -120_001);
    }

    #[test]
    fn seed_example() {
        // Z from 246 to 122 mm at 0.01 = −12400; X radius from 150 to 0 at 0.005 = −30000.
        let mut m = machine();
        let b = m.move_block(Some("300"), Some("246"), false);
        assert_eq!((b.nx, b.nz), (30_000, 24_600));
        let b = m.move_block(Some("0"), Some("122"), false);
        assert_eq!((b.nx, b.nz), (-30_000, -12_400));
        assert_eq!((b.px, b.pz), (0, 12_200));
        assert_eq!(b.events, 30_000);
        let mut t = TieStats::new();
        let ev = step_events((30_000, 24_600), (0, 12_200), &mut t);
        assert_eq!(b.seq, seq_crc(&ev));
        assert_eq!(net_steps(&ev), (-30_000, -12_400));
    }

    #[test]
    fn closed_path_sums_to_zero() {
        let mut m = machine();
        let path: [(Option<&str>, Option<&str>, bool); 12] = [
            (Some("27.532"), Some("0"), false),
            (Some("48"), Some("-10.234"), false),
            (None, Some("-46.234"), false),
            (Some("67.532"), Some("-56"), false),
            (Some("+0.000001"), Some("-0.000003"), true),
            (Some("0.1"), Some("0.2"), true),
            (Some("-0.3"), Some("0.0033"), true),
            (Some("93.532"), None, false),
            (Some("114"), Some("-66.234"), false),
            (Some("0.0025"), Some("-0.005"), true),
            (Some("7"), Some("+3.3333"), false),
            (Some("0"), Some("0"), false),
        ];
        let (mut sx, mut sz) = (0i64, 0i64);
        for (x, z, inc) in path {
            let b = m.move_block(x, z, inc);
            sx += b.nx;
            sz += b.nz;
        }
        assert_eq!((sx, sz), (0, 0));
        assert_eq!(m.position(), (0, 0));
        assert_eq!(m.commanded_mm(), (0.0, 0.0));
    }

    #[test]
    fn incremental_words_do_not_drift() {
        // Z +1000.005 then −1000 leaves exactly 0.005 mm = 0.5 impulse: a tie.
        let mut m = machine();
        m.move_block(None, Some("1000.005"), true);
        let b = m.move_block(None, Some("-1000"), true);
        assert_eq!(b.pz, 1);
        assert_eq!(b.quantizer_ties.exact_ties, 1);

        // 40000 increments of 0.005 mm at 0.01: every odd block ends on a tie.
        let mut m = machine();
        let mut ties = TieStats::new();
        for k in 1..=40_000i64 {
            let b = m.move_block(None, Some("0.005"), true);
            assert_eq!(b.pz, (k + 1) / 2, "block {k}");
            ties.merge(&b.quantizer_ties);
        }
        assert_eq!(ties.exact_ties, 20_000);
        // Whole numbers of impulses sit half an impulse from a tie (less f64 error).
        assert!((ties.min_distance - 0.5).abs() < 1e-9);
        assert_eq!(m.commanded_mm().1, 200.0);
        // And back in increments of 0.1 mm.
        for _ in 0..2_000 {
            m.move_block(None, Some("-0.1"), true);
        }
        assert_eq!(m.position(), (0, 0));
        assert_eq!(m.commanded_mm(), (0.0, 0.0));
    }

    #[test]
    fn price_change_re_expresses_registers() {
        let mut m = machine();
        m.move_block(Some("0.007"), Some("0.0125"), false);
        // X radius 0.0035 / 0.005 = 0.7 → 1; Z 0.0125 / 0.01 = 1.25 → 1.
        assert_eq!(m.position(), (1, 1));
        let ties = m.set_config_with_ties(RefConfig {
            hx_mm: 0.001,
            hz_mm: 0.005,
            diam: true,
        });
        // X 3.5 → 4, Z 2.5 → 3, both exact ties; no motion.
        assert_eq!(m.position(), (4, 3));
        assert_eq!(ties.exact_ties, 2);
        assert_eq!(m.commanded_mm(), (0.0035, 0.0125));
        let b = m.move_block(None, Some("0.0125"), false);
        assert_eq!((b.nx, b.nz, b.events), (0, 0, 0));
    }

    #[test]
    fn diam_change_only_affects_later_words() {
        let mut m = machine();
        m.move_block(Some("10"), None, false);
        assert_eq!(m.position().0, 1_000);
        m.set_config(RefConfig {
            diam: false,
            ..RefConfig::default()
        });
        assert_eq!(m.position().0, 1_000);
        let b = m.move_block(Some("10"), None, false);
        assert_eq!((b.nx, b.px), (1_000, 2_000));
        assert_eq!(m.commanded_mm().0, 10.0);
    }

    #[test]
    fn zero_resets() {
        let mut m = machine();
        m.move_block(Some("12.345"), Some("-6.789"), false);
        m.zero();
        assert_eq!(m.position(), (0, 0));
        assert_eq!(m.commanded_mm(), (0.0, 0.0));
        let b = m.move_block(None, Some("-0.01"), true);
        assert_eq!((b.nz, b.pz), (-1, -1));
    }

    #[test]
    fn parses_words() {
        assert_eq!(parse_length_nm("-12.5"), Some(-12_500_000));
        assert_eq!(parse_length_nm("+0.000001"), Some(1));
        assert_eq!(parse_length_nm("7"), Some(7_000_000));
        assert_eq!(parse_length_nm("007.010"), Some(7_010_000));
        assert_eq!(parse_length_nm("-0"), Some(0));
        for bad in [
            "",
            "+",
            "-",
            ".5",
            "5.",
            "1.0000001",
            "1e3",
            "1,5",
            " 1",
            "1 ",
            "--1",
            "0x10",
            "99999999999999999999",
        ] {
            assert_eq!(parse_length_nm(bad), None, "{bad:?}");
        }
        let mut m = machine();
        m.move_block(Some("1"), Some("1"), false);
        let before = m.clone();
        assert!(matches!(
            m.try_move_block(Some("1"), Some("x"), false),
            Err(RefError::Syntax { axis: 'Z', .. })
        ));
        assert!(matches!(
            m.try_move_block(None, Some("1000000.000001"), false),
            Err(RefError::Range { axis: 'Z' })
        ));
        assert!(matches!(
            m.try_move_block(None, Some("100000"), false),
            Err(RefError::BlockTooLong { axis: 'Z', .. })
        ));
        assert_eq!(m, before);
    }

    /// Three coordinates in nm for an axis of price `q` nm, often within a few
    /// nm of a multiple of `half_step` nm, small enough for any block between
    /// them to stay within [`MAX_BLOCK_IMPULSES`].
    fn coords_nm(q: i64, half_step: i64) -> impl Strategy<Value = [i64; 3]> {
        let range = (q * (MAX_BLOCK_IMPULSES as i64 / 4)).min(50_000_000);
        let kmax = range / half_step.max(1);
        let one = prop_oneof![
            -range..=range,
            (-kmax..=kmax, -2i64..=2).prop_map(move |(k, e)| k * half_step + e),
        ];
        [one.clone(), one.clone(), one]
    }

    /// (price X, price Z, diam, X coordinates, Z coordinates); prices in nm.
    fn scenario() -> impl Strategy<Value = (i64, i64, bool, [i64; 3], [i64; 3])> {
        let price = prop::sample::select(vec![
            1i64, 2, 5, 10, 25, 1_000, 2_500, 5_000, 10_000, 100_000,
        ]);
        (price.clone(), price, any::<bool>()).prop_flat_map(|(qx, qz, diam)| {
            // Half an impulse of X, written as the word: a diameter word doubles it.
            let x_half = if diam { qx } else { qx / 2 };
            (
                Just(qx),
                Just(qz),
                Just(diam),
                coords_nm(qx, x_half),
                coords_nm(qz, qz / 2),
            )
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn splitting_a_block_ends_in_the_same_place(
            (qx, qz, diam, [x0, xm, x1], [z0, zm, z1]) in scenario(),
            inc in any::<bool>(),
        ) {
            let cfg = RefConfig { hx_mm: qx as f64 / 1e6, hz_mm: qz as f64 / 1e6, diam };
            let mut whole = RefMachine::new(cfg);
            let mut split = RefMachine::new(cfg);
            whole.move_block(Some(&word(x0)), Some(&word(z0)), false);
            split.move_block(Some(&word(x0)), Some(&word(z0)), false);
            let (s0x, s0z) = whole.position();

            let a = if inc {
                whole.move_block(Some(&word(x1 - x0)), Some(&word(z1 - z0)), true)
            } else {
                whole.move_block(Some(&word(x1)), Some(&word(z1)), false)
            };
            let (b1, b2) = if inc {
                (
                    split.move_block(Some(&word(xm - x0)), Some(&word(zm - z0)), true),
                    split.move_block(Some(&word(x1 - xm)), Some(&word(z1 - zm)), true),
                )
            } else {
                (
                    split.move_block(Some(&word(xm)), Some(&word(zm)), false),
                    split.move_block(Some(&word(x1)), Some(&word(z1)), false),
                )
            };
            prop_assert_eq!(whole.position(), split.position());
            prop_assert_eq!((a.nx, a.nz), (b1.nx + b2.nx, b1.nz + b2.nz));

            // Registers agree with Q(P/h) computed exactly in integers.
            let half_nm_x = if diam { x1 } else { 2 * x1 };
            let exact = (
                q_exact(half_nm_x as i128, 2 * qx as i128),
                q_exact(z1 as i128, qz as i128),
            );
            prop_assert_eq!(whole.position(), exact);
            prop_assert_eq!(a.px - s0x, a.nx);
            prop_assert_eq!(a.pz - s0z, a.nz);
        }

        #[test]
        fn step_events_match_exact_interleaving(
            a0 in -1_000i64..=1_000, b0 in -1_000i64..=1_000,
            dx in -3_000i64..=3_000, dz in -3_000i64..=3_000,
        ) {
            let mut t = TieStats::new();
            let ev = step_events((a0, b0), (a0 + dx, b0 + dz), &mut t);
            prop_assert_eq!(ev.len() as i64, dx.abs().max(dz.abs()));
            prop_assert_eq!(net_steps(&ev), (dx, dz));
            let x_leads = dx.abs() >= dz.abs();
            let (dl, db) = if x_leads { (dx, dz) } else { (dz, dx) };
            let n = dl.abs();
            let mut prev = 0i64;
            let mut ties = 0u64;
            for (i, &byte) in ev.iter().enumerate() {
                let i = i as i64 + 1;
                let b = q_exact((i * db) as i128, n as i128);
                if (2 * i * db).rem_euclid(2 * n) == n { ties += 1; }
                let (lead_bit, other_bit) =
                    if x_leads { (BIT_X_STEP, BIT_Z_STEP) } else { (BIT_Z_STEP, BIT_X_STEP) };
                prop_assert!(byte & lead_bit != 0);
                prop_assert_eq!(byte & other_bit != 0, b != prev);
                prev = b;
            }
            prop_assert_eq!(t.exact_ties, ties);
            // A non-tie i·Δb/n lies at least 1/(2n) from a tie; f64 error ≤ 2⁻⁵³·|Δb|.
            prop_assert!(t.min_distance >= 1.0 / (2.0 * n as f64) - 1e-12);
        }
    }
}

//! G-code blocks: words parsed and checked, before any motion.
//!
//! A block is a line of address words: a letter followed by a number, with or
//! without spaces between words (`N10 G01 X27.532 Z0`, `G1X12.5`) and between
//! a letter and its number (`G0 X 2`, as LinuxCNC and Fanuc read it), letters
//! in either case. Comments in parentheses and everything after `;` are ignored.
//! Each address may appear once, except `G` and `M`, which may appear once
//! per modal group. Lines as CAM posts and machinists write them are read
//! too:
//!
//! - numbers `30.`, `.5`, `+2`, with any count of decimals (CAM posts print
//!   doubles: 16 and 17), rounded once to the ångström (10⁻⁷ mm) half away
//!   from zero;
//! - `%` (the tape mark a program begins and ends with) alone on its line;
//! - a program number alone on its line: `O1234`, `O<name>`, `:1234`
//!   (an `o<name>` followed by a word is a subroutine, expanded by the host);
//! - `/` at the start: block delete, skipped when the switch is on;
//! - `Y0` (lathe posts write it); any other `Y` is refused by name;
//! - `G20`/`G21` anywhere in a block reads all its lengths and its feed in
//!   inches (25.4 mm, rounded once to the ångström) or millimetres
//!   ([`parse`] takes the modal unit for blocks without one).
//!
//! Two dialects ([`Dialect`]) read the same lines differently where their
//! codes differ; a code of the other dialect is refused naming it.
//!
//! | address | meaning | value |
//! |---|---|---|
//! | `N` | sequence number | kept to name the block in refusals |
//! | `G` both | 00 01 02 03 (motion), 04 (dwell), 10 with L2 or L20 (a work offset), 18 (ZX plane), 20 21 (inch, millimetres), 40 41 42 (nose compensation), 96 97 (surface speed, rpm), 54 … 59 (work offsets), 450 451 (outside corners: transition arc, intersection) | code |
//! | `G` ISO | 7 8 (diameter, radius), 90 91 (absolute, incremental), 90.1 91.1 (arc centres absolute, from the start), 94 95 (feed per minute, per revolution), 43 49 (tool offsets on, off) | code |
//! | `G` Fanuc | 50 (with `S`: the spindle speed limit), 98 99 (feed per minute, per revolution) | code |
//! | `X` | X end point: a diameter when `DIAM=1`; in a Fanuc `G04`, seconds | length |
//! | `Z` | Z end point | length |
//! | `U`, `W` | Fanuc: X, Z increments (`U` in a `G04`: seconds) | length |
//! | `Y` | only 0 | length |
//! | `I`, `K` | arc centre minus start point (or the centre, under G90.1), radius values | length |
//! | `R` | arc radius: positive for an arc of at most 180°, negative for more | length |
//! | `F` | feed along the path, per minute or per revolution (modal) | length |
//! | `S` | spindle speed, rpm, or surface speed under G96 (m/min, ft/min under G20) | 0 … 99 999.999999 |
//! | `D` | ISO, with G96: the spindle speed limit, rpm | 0 … 99 999.999999 |
//! | `P` | with G04: the dwell, seconds (ISO) or milliseconds (Fanuc) | 0 … 99 999.999999 |
//! | `T` | ISO: the tool, 0 … 99; Fanuc: tool and offset register, `T0101` | whole number |
//! | `M` | 02 30 (end of program), 03 04 05 (spindle cw, ccw, stop), 06 (ISO: tool change), 07 08 09 (mist, flood, off) | code |
//! | `P`, `L` | with G10: the work offset 1 … 6 (ISO also 0, the one in effect) and L2 or L20 | whole number |
//! | `H` | ISO, with G43: the offset register | whole number |

use crate::length::{gcode_scaled, Length, LengthError};
use core::fmt;

/// The tool offset registers: `D`, `H` and `T` name 1 … this many.
pub const TOOL_REGISTERS: usize = 32;

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

/// The plane of arcs and nose compensation (group 2). A lathe cuts in
/// `G18`; posts for mills and lathes alike write `G17` in a header before
/// they select it, so `G17` and `G19` are taken as the modal plane and an
/// arc (or compensation) outside `G18` is refused naming the plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Plane {
    /// `G17`: XY.
    Xy,
    /// `G18`: ZX (power-on, a lathe's).
    #[default]
    Zx,
    /// `G19`: YZ.
    Yz,
}

impl Plane {
    /// The G word.
    pub const fn word(self) -> &'static str {
        match self {
            Plane::Xy => "G17",
            Plane::Zx => "G18",
            Plane::Yz => "G19",
        }
    }
}

/// Path control (group 13): how blocks join.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PathControl {
    /// `G61`: exact stop, at rest at the end of every block.
    ExactStop,
    /// `G61.1`: exact path. The device's path is always the programmed
    /// one; corners are taken at the junction speed the limits allow.
    ExactPath,
    /// `G64 [P]`: blending (power-on): corners at the speed a junction
    /// deviation allows, `P` if given (mm), else the limits' `JD`.
    #[default]
    Blend,
    /// `G64 P`: blending with the tolerance `P`.
    Tolerance(Length),
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

/// The G-code dialect a program is written in (`OPT DIALECT=`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Dialect {
    /// ISO 6983 as LinuxCNC and grbl read it: `G90`/`G91`, `G94`/`G95`,
    /// `G7`/`G8`, `G4 P` in seconds (power-on).
    #[default]
    Iso,
    /// Fanuc G-code system A, as Fanuc and Haas lathes read it: `U`/`W`
    /// incremental words, `G98`/`G99`, `G50 S`, `G04 P` in milliseconds,
    /// `T0101`.
    Fanuc,
}

impl Dialect {
    /// The word of `OPT DIALECT=`.
    pub const fn as_str(self) -> &'static str {
        match self {
            Dialect::Iso => "ISO",
            Dialect::Fanuc => "FANUC",
        }
    }
}

/// What the feed word means (ISO `G94`/`G95`, Fanuc `G98`/`G99`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FeedMode {
    /// Millimetres (inches) per minute (power-on).
    #[default]
    PerMinute,
    /// Millimetres (inches) per revolution of the spindle.
    PerRev,
}

/// What the spindle's `S` word means (`G96`/`G97`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SpindleMode {
    /// `G97`: revolutions per minute (power-on).
    #[default]
    Rpm,
    /// `G96`: constant surface speed, m/min (ft/min under `G20`).
    Surface,
}

/// Spindle commands (`M03`, `M04`, `M05`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Spindle {
    /// `M03`: clockwise, looking from the headstock to the tailstock.
    Cw,
    /// `M04`: counter-clockwise.
    Ccw,
    /// `M05`: stopped.
    Off,
}

/// Coolant commands (`M07`, `M08`, `M09`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Coolant {
    /// `M07`: mist.
    Mist,
    /// `M08`: flood.
    Flood,
    /// `M09`: off.
    Off,
}

/// Program stops (`M00`, `M01`, `M02`, `M30`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stop {
    /// `M00`: stop until cycle start.
    Pause,
    /// `M01`: stop until cycle start when the optional stop switch is on
    /// (`OPT OPTSTOP=1`).
    Optional,
    /// `M02`, `M30`: end of program.
    End,
}

/// The group-0 codes that move in machine coordinates or shift the work
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Special {
    /// `G28` (`.0 = 0`) or `G30` (`.0 = 1`): a rapid to the stored
    /// position, through the point of the block's `X`/`Z` (`U`/`W`) if
    /// given, and then on the given axes only.
    Reference(u8),
    /// `G28.1` (`.0 = 0`) or `G30.1` (`.0 = 1`): the current machine
    /// position is stored.
    Store(u8),
    /// `G53`: the block's `X`/`Z` are machine coordinates (G00 or G01).
    Machine,
    /// ISO `G92`, Fanuc `G50 X Z`: the work coordinates shifted so that
    /// the current point has the block's `X`/`Z`.
    Shift,
    /// `G92.1`, `G92.2`: the shift cleared (`G92.2` keeps it for `G92.3`).
    ClearShift(bool),
    /// `G92.3`: the shift kept by `G92.2` restored.
    RestoreShift,
    /// `G38.2`–`G38.5` (ISO): a straight feed move toward the block's
    /// `X`/`Z` that stops where the probe changes.
    Probe(ProbeMode),
}

/// How a probing move (`G38.2`–`G38.5`) stops and what it makes of no
/// change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ProbeMode {
    /// `G38.2`/`G38.3`: stops where the probe touches (becomes active);
    /// `G38.4`/`G38.5`: where it leaves (becomes inactive).
    pub toward: bool,
    /// `G38.2`/`G38.4`: reaching the end with no change is an error
    /// (grbl's alarm 5); `G38.3`/`G38.5` end there.
    pub must_change: bool,
}

impl ProbeMode {
    /// The code in tenths (382 … 385).
    pub const fn code(self) -> u16 {
        match (self.toward, self.must_change) {
            (true, true) => 382,
            (true, false) => 383,
            (false, true) => 384,
            (false, false) => 385,
        }
    }
}

/// Lecture 13's `G45`–`G48` (one block): each axis move of the block
/// lengthened or shortened by the offset of register `D` for that axis,
/// once or twice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PositionOffset {
    /// `G45` +1 (lengthened by one offset), `G46` −1, `G47` +2, `G48` −2.
    pub times: i8,
    /// The offset register, 1 … [`TOOL_REGISTERS`].
    pub register: u8,
}

/// A tool word: the tool, and in the Fanuc dialect its offset register.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ToolWord {
    /// The tool (turret station), 0 … 99.
    pub tool: u8,
    /// The offset register (Fanuc `T0101`: tool 01, register 01; `T5` is
    /// `T0505`); `None` in the ISO dialect, where `T` names the tool alone.
    pub offset: Option<u8>,
}

/// `G10 L2`/`L20`: a work offset register set from the block's `X`/`Z`;
/// (ISO) `G10 L1`/`L10`: a tool's geometry offset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SetWork {
    /// A work offset: 1 … 6, `G54` … `G59`; 0 (ISO): the system in effect
    /// once the block's own `G54`–`G59` is taken. A tool's: its register,
    /// 1 … 32.
    pub register: u8,
    /// `L20`, `L10`: so that the current point has the coordinates
    /// `X`/`Z` (with that tool's offset in effect, for `L10`); `L2`, `L1`:
    /// to them.
    pub here: bool,
    /// `L1`, `L10`: the register is a tool's.
    pub tool: bool,
}

/// LinuxCNC's `G41.1`/`G42.1 D L`: the nose given in the block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DynamicNose {
    /// The nose radius: half of `D`.
    pub radius: Length,
    /// LinuxCNC's orientation `L` (0 … 9).
    pub orientation: u8,
}

/// ISO `G43`/`G49`: the tool offsets on or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ToolOffset {
    /// `G43`, from register `H` or (`None`) the loaded tool's.
    On(Option<u8>),
    /// `G49`.
    Off,
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
    /// G90 (false) or G91 (true) if given (ISO).
    pub incremental: Option<bool>,
    /// G90.1 (true) or G91.1 (false) if given: arc centres absolute or from
    /// the start (ISO).
    pub arc_absolute: Option<bool>,
    /// G7 (true) or G8 (false) if given: X words are diameters or radii
    /// (ISO).
    pub diameter: Option<bool>,
    /// G450 or G451 if given.
    pub corner: Option<Corner>,
    /// G17, G18, G19 if given.
    pub plane: Option<Plane>,
    /// G61, G61.1, G64 if given.
    pub path: Option<PathControl>,
    /// G80: a canned cycle cancelled (the safety line of Haas and Fanuc
    /// programs; with no cycle modal it changes nothing).
    pub cancel_cycle: bool,
    /// M41–M44: the spindle gear range, 1 … 4.
    pub gear: Option<u8>,
    /// An M code the machine's table says what to do with (not one of
    /// the standard ones), and its code in tenths.
    pub machine_m: Option<u16>,
    /// G41.1/G42.1 (ISO): compensation with the nose in the block, `D`
    /// the nose diameter and `L` the orientation (LinuxCNC's dynamic
    /// compensation).
    pub dynamic_nose: Option<DynamicNose>,
    /// G41/G42 `D` (ISO, as LinuxCNC reads it): the tool whose nose
    /// compensates, 1 … 32 (0: the loaded tool's, as without `D`).
    pub nose_tool: Option<u8>,
    /// G20 or G21 if given; the block's lengths are read in it.
    pub units: Option<Units>,
    /// G94/G95 (ISO), G98/G99 (Fanuc) if given.
    pub feed_mode: Option<FeedMode>,
    /// G96/G97 if given.
    pub spindle_mode: Option<SpindleMode>,
    /// G04: the dwell, in microseconds (rounded half away from zero).
    pub dwell: Option<u64>,
    /// Fanuc `G50 S`: the spindle speed limit, rpm (ISO writes it as `D`
    /// in a `G96` block; both land here).
    pub clamp: Option<Length>,
    /// The sequence number, when written as a whole number below 2³².
    pub n: Option<u32>,
    /// X word (or X from a Fanuc `U`, which [`Block::incremental_x`] says).
    pub x: Option<Length>,
    /// Z word (or Z from a Fanuc `W`).
    pub z: Option<Length>,
    /// Half the X (or U) word, rounded once from the number as written:
    /// the radius when X is a diameter.
    pub x_half: Option<Length>,
    /// The X word was a Fanuc `U`: an increment.
    pub incremental_x: bool,
    /// The Z word was a Fanuc `W`: an increment.
    pub incremental_z: bool,
    /// I word.
    pub i: Option<Length>,
    /// K word.
    pub k: Option<Length>,
    /// R word.
    pub r: Option<Length>,
    /// F word: the feed, mm/min or mm/rev as the feed mode says.
    pub f: Option<Length>,
    /// S word: rpm, or the surface speed under G96 (unit-free number).
    pub s: Option<Length>,
    /// T word.
    pub tool: Option<ToolWord>,
    /// M03/M04/M05.
    pub spindle: Option<Spindle>,
    /// M07/M08/M09.
    pub coolant: Option<Coolant>,
    /// M00/M01/M02/M30.
    pub stop: Option<Stop>,
    /// G28, G30, G28.1, G30.1, G53, G92 (Fanuc G50 X Z), G38.2–G38.5.
    pub special: Option<Special>,
    /// G54–G59 if given: 0 … 5.
    pub wcs: Option<u8>,
    /// G10 L2/L20: the block's `X`/`Z` are an offset's, not an end point.
    pub set_work: Option<SetWork>,
    /// ISO G43/G49.
    pub tool_offset: Option<ToolOffset>,
    /// ISO M06: the tool named by `T` is put in.
    pub tool_change: bool,
    /// `G45`–`G48` with its `D`.
    pub position_offset: Option<PositionOffset>,
    /// A turning cycle (Fanuc dialect: `G70`, `G71`, `G72`) and its words.
    pub cycle: Option<CycleWords>,
    /// A single cycle of G-code system A (Fanuc dialect: `G90` turning,
    /// `G94` facing), modal; its end point in `X`/`U` and `Z`/`W`, its
    /// taper in `R`.
    pub single: Option<SingleCycle>,
    /// Fanuc and Haas `,C` or `,R`: a chamfer or a round at the corner
    /// where this block's move meets the next block's.
    pub round: Option<CornerRound>,
}

/// A corner chamfer or round asked for by a move's block (`,C`, `,R`;
/// Fanuc and Haas), inserted where the move meets the next one: the move
/// is cut short, the chamfer or the arc joins it to the next move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CornerRound {
    /// `,C`: a straight chamfer from this distance before the corner, along
    /// the move, to this distance after it, along the next.
    Chamfer(Length),
    /// `,R`: an arc of this radius tangent to both moves.
    Round(Length),
    /// Fanuc's and Haas' chamfer or round of a right angle, on a `G01`
    /// along one axis: `Z… I±i` or `X… K±k` (a chamfer of `i`, `k`),
    /// `Z… R±r` or `X… R±r` (a round of `r`). The next move must be a
    /// `G01` along the other axis alone, in the direction of the word's
    /// sign.
    Square {
        /// The chamfer's leg or the round's radius (above 0).
        size: Length,
        /// A chamfer (`I`, `K`), or a round (`R`).
        chamfer: bool,
        /// The axis of the next move: 0 X, 1 Z.
        next: u8,
        /// Whether the next move goes towards plus.
        plus: bool,
    },
}

/// The single cycles of G-code system A: one pass in, along, out and back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SingleCycle {
    /// `G90`: in along X at the rapid rate, the cut along Z, out along X,
    /// back along Z at the rapid rate.
    Turn,
    /// `G94`: in along Z, the cut along X, out along Z, back along X.
    Face,
}

/// The turning cycles the device runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CycleKind {
    /// `G70`: finishing along a held profile.
    Finish,
    /// `G71`: stock removal in turning (cuts along Z).
    Turn,
    /// `G72`: stock removal in facing (cuts along X).
    Face,
    /// `G73`: pattern repeating (the profile cut again and again, moved
    /// in from a relief to its allowances).
    Pattern,
    /// `G74`: face grooving and peck drilling (pecks along Z, grooves
    /// side by side along X).
    PeckFace,
    /// `G75`: grooving (pecks along X, grooves side by side along Z).
    PeckGroove,
}

impl CycleKind {
    /// Whether it is `G74` or `G75`, whose axis words are an end point.
    pub const fn pecks(self) -> bool {
        matches!(self, CycleKind::PeckFace | CycleKind::PeckGroove)
    }
}

/// A cycle block's own words (Fanuc and Haas forms): in a cycle block `U`
/// and `W` are allowances or a depth, not increments, and `P`, `Q` name the
/// profile's first and last blocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CycleWords {
    /// Which cycle.
    pub kind: CycleKind,
    /// `P`: the sequence number of the profile's first block.
    pub p: Option<u32>,
    /// `Q`: the sequence number of its last.
    pub q: Option<u32>,
    /// `U` as written (the first block of Fanuc's two: the depth of cut,
    /// a radius; the second: the X allowance, a diameter).
    pub u: Option<Length>,
    /// `W` as written (the Z allowance; `G72`'s first block: the depth).
    pub w: Option<Length>,
    /// `D`: Haas' depth of cut (a radius).
    pub d: Option<Length>,
    /// `R`: the retract (Fanuc's first block); `G74`/`G75`'s second
    /// block: the relief at the bottom.
    pub r: Option<Length>,
    /// `G74`/`G75`: the step along X, a radius (Haas `I`, Fanuc `P`).
    pub i: Option<Length>,
    /// `G74`/`G75`: the step along Z (Haas `K`, Fanuc `Q`). `G73` (Haas):
    /// the relief along X (`I`, a radius) and Z (`K`).
    pub k: Option<Length>,
    /// `G73`: the count of passes (Fanuc's first block `R`, Haas' `D`).
    pub passes: Option<u32>,
}

/// Why a block was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BlockError {
    /// An address letter this control does not know (`ERR SYNTAX`).
    UnknownAddress(u8),
    /// An address given twice, or two G (M) words of one group (`ERR SYNTAX`).
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
    /// An M code this control does not run (`ERR VALUE`), or `None` when
    /// the number is no M code.
    UnsupportedM(Option<u16>),
    /// A canned cycle (`G70`–`G76`; Fanuc's `G90`, `G92`, `G94`), by its
    /// code in tenths (`ERR VALUE`).
    Cycle(u16),
    /// A number outside what its address takes, or no number for it
    /// (`ERR VALUE`): the address and what it takes.
    Range(u8, &'static str),
    /// A word of the other dialect (`ERR VALUE`): its letter, its code
    /// in tenths for a G word, and the dialect it belongs to.
    OtherDialect(u8, u16, Dialect),
    /// Words that do not go together, or a word a code needs
    /// (`ERR SYNTAX`): what the rule is.
    Form(&'static str),
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
    /// The address the refusal is about, when it is about one word.
    pub const fn address(&self) -> Option<u8> {
        match *self {
            BlockError::UnknownAddress(a)
            | BlockError::Repeated(a)
            | BlockError::Value(a, _)
            | BlockError::Range(a, _)
            | BlockError::OtherDialect(a, ..) => Some(a),
            BlockError::NoYAxis => Some(b'Y'),
            BlockError::UnsupportedG(_) | BlockError::Cycle(_) => Some(b'G'),
            BlockError::UnsupportedM(_) => Some(b'M'),
            BlockError::NotAWord
            | BlockError::Comment
            | BlockError::Form(_)
            | BlockError::ProgramNumber
            | BlockError::HostLanguage => None,
        }
    }

    /// Whether the protocol answers it `ERR VALUE` (a number or a code
    /// this control does not take) rather than `ERR SYNTAX`.
    pub const fn is_value(&self) -> bool {
        matches!(
            self,
            BlockError::Value(..)
                | BlockError::UnsupportedG(_)
                | BlockError::UnsupportedM(_)
                | BlockError::Cycle(_)
                | BlockError::Range(..)
                | BlockError::OtherDialect(..)
                | BlockError::NoYAxis
        )
    }
}

/// A code in tenths as written: `G04`, `G90.1`.
struct Code(u8, u16);

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (whole, tenth) = (self.1 / 10, self.1 % 10);
        if tenth == 0 {
            write!(f, "{}{whole:02}", char::from(self.0))
        } else {
            write!(f, "{}{whole}.{tenth}", char::from(self.0))
        }
    }
}

/// What a refusal says, naming the word: `unknown address Q`, `G71 canned
/// cycles not supported`, `X beyond 99999.999999 mm`.
impl fmt::Display for BlockError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BlockError::UnknownAddress(l) => write!(f, "unknown address {}", char::from(l)),
            BlockError::Repeated(l) => write!(f, "address given twice: {}", char::from(l)),
            BlockError::NotAWord => f.write_str("not an address word"),
            BlockError::Comment => f.write_str("unclosed comment"),
            BlockError::Value(l, why) => write!(f, "{} {why}", char::from(l)),
            BlockError::UnsupportedG(None) => f.write_str("G not a G code"),
            BlockError::UnsupportedM(None) => f.write_str("M not an M code"),
            BlockError::UnsupportedG(Some(tenths)) => {
                let why = match tenths {
                    170 | 190 => "plane not supported: a lathe cuts in G18 (ZX)",
                    320 | 330 | 331 | 340 => "threading not supported",
                    _ => "not supported",
                };
                write!(f, "{} {why}", Code(b'G', tenths))
            }
            BlockError::UnsupportedM(Some(tenths)) => {
                let why = match tenths {
                    980 | 990 => "subprograms are expanded by the host",
                    _ => "not supported",
                };
                write!(f, "{} {why}", Code(b'M', tenths))
            }
            BlockError::OtherDialect(letter, tenths, dialect) => {
                if letter == b'G' || letter == b'M' {
                    write!(f, "{}", Code(letter, tenths))?;
                } else {
                    write!(f, "{}", char::from(letter))?;
                }
                let d = dialect.as_str();
                write!(f, " belongs to the {d} dialect (OPT DIALECT={d})")
            }
            BlockError::Cycle(tenths) => {
                write!(f, "{} canned cycles not supported", Code(b'G', tenths))
            }
            BlockError::Form(why) => f.write_str(why),
            BlockError::Range(l, why) => write!(f, "{} {why}", char::from(l)),
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
/// letter followed by a number (spaces and tabs between them allowed), or
/// it begins with `%`, `/`, `(`, `;`, `:` or `O<`.
///
/// ```
/// use core_nostd::gcode::is_block;
/// assert!(is_block("N10 G01 X12"));
/// assert!(is_block("x-1.5"));
/// assert!(is_block("X.5"));
/// assert!(is_block("G 0 X 2"));
/// assert!(is_block("%"));
/// assert!(is_block("(FACE)"));
/// assert!(is_block("O<part> (name)"));
/// assert!(!is_block("ZERO"));
/// assert!(!is_block("MOVE X=1"));
/// ```
pub fn is_block(line: &str) -> bool {
    let b = line.trim_start_matches([' ', '\t']).as_bytes();
    match b {
        [b'%' | b'/' | b'(' | b';' | b':', ..] => true,
        [b'O' | b'o', b'<', ..] => true,
        [l, rest @ ..] if l.is_ascii_alphabetic() => {
            let d = rest.get(after_blanks(rest, 0));
            d.is_some_and(|d| d.is_ascii_digit() || matches!(d, b'+' | b'-' | b'.'))
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
    parse_with(line, Dialect::Iso, units)
}

/// Parses a block of `dialect` whose lengths are in `units` unless it says
/// otherwise.
///
/// ```
/// use core_nostd::gcode::{parse, Dialect, FeedMode, Units};
/// let b = parse("G99 U-2. W.5 T0303", Dialect::Fanuc, Units::Mm).unwrap();
/// assert_eq!(b.feed_mode, Some(FeedMode::PerRev));
/// assert!(b.incremental_x && b.incremental_z);
/// assert_eq!(b.x.unwrap().to_string(), "-2.0000");
/// assert_eq!((b.tool.unwrap().tool, b.tool.unwrap().offset), (3, Some(3)));
/// assert_eq!(parse("G04 P1500", Dialect::Fanuc, Units::Mm).unwrap().dwell, Some(1_500_000));
/// assert_eq!(parse("G4 P1.5", Dialect::Iso, Units::Inch).unwrap().dwell, Some(1_500_000));
/// ```
pub fn parse(line: &str, dialect: Dialect, units: Units) -> Result<Block, Located> {
    parse_with(line, dialect, units)
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

/// What a line says about itself before its words are read: its own
/// `G20`/`G21` (the first outside comments and before any `;`) and whether
/// it holds a `G04` (whose `P`, and Fanuc `X`/`U`, are times). An unclosed
/// comment ends the scan; the parser refuses the line anyway.
#[derive(Clone, Copy, Default)]
struct Scan {
    units: Option<Units>,
    dwell: bool,
    /// `G45`–`G48`: `D` is an offset register (also in the Fanuc dialect).
    position_offset: bool,
    /// `G64`: `P` (and `Q`) are tolerances, mm.
    blend: bool,
    /// `G41.1`/`G42.1`: `D` is the nose diameter, `L` its orientation.
    dynamic: bool,
    /// `G70`–`G72` (Fanuc): the cycle's own words.
    cycle: Option<CycleKind>,
}

fn scan(line: &str) -> Scan {
    let bytes = line.as_bytes();
    let mut pos = 0;
    let mut found = Scan::default();
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
                let from = after_blanks(bytes, pos + 1);
                let n = number_len(bytes, from);
                match line.get(from..from + n).and_then(g_code) {
                    Some(200) if found.units.is_none() => found.units = Some(Units::Inch),
                    Some(210) if found.units.is_none() => found.units = Some(Units::Mm),
                    Some(40) => found.dwell = true,
                    Some(450 | 460 | 470 | 480) => found.position_offset = true,
                    Some(640) => found.blend = true,
                    Some(700) => found.cycle = Some(CycleKind::Finish),
                    Some(710) => found.cycle = Some(CycleKind::Turn),
                    Some(720) => found.cycle = Some(CycleKind::Face),
                    Some(730) => found.cycle = Some(CycleKind::Pattern),
                    Some(740) => found.cycle = Some(CycleKind::PeckFace),
                    Some(750) => found.cycle = Some(CycleKind::PeckGroove),
                    Some(411 | 421) => found.dynamic = true,
                    _ => {}
                }
                pos = from + n;
            }
            _ => pos += 1,
        }
    }
    found
}

/// The first byte from `pos` that is not a space or a tab: a word's
/// number may stand apart from its letter (`X 2`, as LinuxCNC and Fanuc
/// read it).
fn after_blanks(bytes: &[u8], pos: usize) -> usize {
    pos + bytes
        .iter()
        .skip(pos)
        .take_while(|b| matches!(b, b' ' | b'\t'))
        .count()
}

/// The bytes of a word's number from `pos`: digits, signs and points.
fn number_len(bytes: &[u8], pos: usize) -> usize {
    bytes
        .iter()
        .skip(pos)
        .take_while(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.'))
        .count()
}

/// A block being read: the words so far and what the checks at its end
/// need.
struct Reading {
    block: Block,
    seen: [bool; 26],
    dialect: Dialect,
    units: Units,
    dwell: bool,
    position_offset: bool,
    blend: bool,
    dynamic: bool,
    /// The cycle's words, while reading a cycle block (Fanuc).
    cycle: Option<CycleWords>,
    /// G64's `P` and `Q`, mm.
    tolerance: Option<Length>,
    /// The group-0 G code (G04, G50) and its column.
    once: Option<(u16, usize)>,
    /// The dwell time, µs.
    time: Option<u64>,
    /// `P` (not a time), `L`, `H`: whole numbers, and their columns.
    p: Option<(u32, usize)>,
    l: Option<(u32, usize)>,
    h: Option<(u32, usize)>,
    /// ISO `D` (spindle speed limit with G96) and its column.
    d: Option<(Length, usize)>,
}

fn parse_with(line: &str, dialect: Dialect, units: Units) -> Result<Block, Located> {
    let scanned = scan(line);
    let mut r = Reading {
        block: Block::default(),
        seen: [false; 26],
        dialect,
        units: scanned.units.unwrap_or(units),
        dwell: scanned.dwell,
        position_offset: scanned.position_offset,
        blend: scanned.blend,
        // G41.1/G42.1 are LinuxCNC's: in Fanuc's words a D before them is
        // no nose diameter (and they are refused as the other dialect's).
        dynamic: scanned.dynamic && dialect == Dialect::Iso,
        cycle: match (scanned.cycle, dialect) {
            (Some(kind), Dialect::Fanuc) => Some(CycleWords {
                kind,
                p: None,
                q: None,
                u: None,
                w: None,
                d: None,
                r: None,
                i: None,
                k: None,
                passes: None,
            }),
            _ => None,
        },
        tolerance: None,
        once: None,
        time: None,
        p: None,
        l: None,
        h: None,
        d: None,
    };
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
            r.block.kind = LineKind::TapeMark;
            pos += 1;
        }
        Some([b'/', ..]) => {
            r.block.deleted = true;
            pos += 1;
        }
        Some([b':', ..]) => {
            r.block.kind = LineKind::Program;
            pos = program_number(bytes, pos + 1).ok_or(at(BlockError::NotAWord, pos))?;
        }
        Some([b'O' | b'o', b'<', ..]) => {
            r.block.kind = LineKind::Program;
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
            r.block.kind = LineKind::Program;
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
            _ if r.block.kind != LineKind::Words => {
                // A tape mark or a program number stands alone.
                let error = if r.block.kind == LineKind::Program
                    && bytes.get(start + 1) == Some(&b'<')
                    && c.is_ascii_alphabetic()
                {
                    BlockError::HostLanguage
                } else if r.block.kind == LineKind::Program {
                    BlockError::ProgramNumber
                } else {
                    BlockError::NotAWord
                };
                return Err(at(error, pos));
            }
            b',' if r.block.kind == LineKind::Words => {
                // `,C` and `,R`: a corner's chamfer or round (Fanuc, Haas).
                let at_letter = after_blanks(bytes, pos + 1);
                let letter = bytes.get(at_letter).map(u8::to_ascii_uppercase);
                let from = after_blanks(bytes, at_letter + 1);
                let end = from + number_len(bytes, from);
                let number = line.get(from..end).unwrap_or("");
                let (Some(letter @ (b'C' | b'R')), false) = (letter, number.is_empty()) else {
                    return Err(at(BlockError::NotAWord, pos));
                };
                r.corner_word(letter, number).map_err(|e| at(e, pos))?;
                pos = end;
            }
            _ if c.is_ascii_alphabetic() => {
                let letter = c.to_ascii_uppercase();
                let from = after_blanks(bytes, pos + 1);
                let end = from + number_len(bytes, from);
                let number = line.get(from..end).ok_or(at(BlockError::NotAWord, pos))?;
                if number.is_empty() {
                    return Err(at(BlockError::NotAWord, pos));
                }
                r.word(letter, number, pos).map_err(|e| at(e, pos))?;
                pos = end;
            }
            _ => return Err(at(BlockError::NotAWord, pos)),
        }
    }
    r.finish().map_err(|(e, pos)| at(e, pos))
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

/// A number without a unit times 10ᵉ, rounded once: 0 to 99 999.999999.
fn unitless_scaled(letter: u8, number: &str, e: u32) -> Result<u64, BlockError> {
    let range = BlockError::Range(letter, "must be 0 to 99999.999999");
    match gcode_scaled(number, e) {
        Ok(v) => u64::try_from(v).map_err(|_| range),
        Err(LengthError::OutOfRange) => Err(range),
        Err(LengthError::Malformed) => Err(BlockError::Range(letter, "not a number")),
        Err(e) => Err(BlockError::Value(letter, e)),
    }
}

/// A sequence number (`P`, `Q` of a cycle): a whole number of at most
/// nine digits.
fn whole_number(letter: u8, number: &str) -> Result<u32, BlockError> {
    let digits = number.trim_start_matches('0');
    if number.is_empty() || !number.bytes().all(|b| b.is_ascii_digit()) || digits.len() > 9 {
        return Err(BlockError::Range(letter, "must be a sequence number"));
    }
    Ok(digits.bytes().fold(0, |n, b| n * 10 + u32::from(b - b'0')))
}

/// `G73`'s count of passes: a whole number from 1 to 999, `3` or `3.`
/// (`3.0`) as programs write it.
fn passes(letter: u8, number: &str) -> Result<u32, BlockError> {
    let whole = match crate::text::split_once(number, b'.') {
        Some((w, f)) if f.bytes().all(|b| b == b'0') => w,
        _ => number,
    };
    match whole_number(letter, whole) {
        Ok(n @ 1..=999) => Ok(n),
        _ => Err(BlockError::Range(letter, "a count of passes, 1 to 999")),
    }
}

/// A whole number of at most four digits (`P`, `L`, `H`).
fn whole(letter: u8, number: &str) -> Result<u32, BlockError> {
    let digits = number.trim_start_matches('0');
    if !number.bytes().all(|b| b.is_ascii_digit()) || digits.len() > 4 {
        return Err(BlockError::Range(letter, "must be a whole number"));
    }
    Ok(digits.bytes().fold(0, |n, b| n * 10 + u32::from(b - b'0')))
}

/// A dwell time in µs from seconds (`e` = 6) or milliseconds (`e` = 3).
fn dwell_us(letter: u8, number: &str, e: u32) -> Result<u64, BlockError> {
    unitless_scaled(letter, number, e)
}

/// A number without a unit (S, D), held on the length grid (10⁻⁷).
fn unitless(letter: u8, number: &str) -> Result<Length, BlockError> {
    let v = unitless_scaled(letter, number, 7)?;
    // At most 999 999 999 990: a length.
    Ok(i64::try_from(v)
        .ok()
        .and_then(Length::from_angstrom)
        .unwrap_or(Length::ZERO))
}

impl Reading {
    /// `,C` or `,R` and its number.
    fn corner_word(&mut self, letter: u8, number: &str) -> Result<(), BlockError> {
        if self.dialect != Dialect::Fanuc {
            return Err(BlockError::Form(
                ",C and ,R are Fanuc's and Haas' corners: OPT DIALECT=FANUC",
            ));
        }
        if self.block.round.is_some() {
            return Err(BlockError::Form("one corner a block: ,C or ,R"));
        }
        let size = match self.units {
            Units::Mm => Length::from_gcode_mm(number),
            Units::Inch => Length::from_gcode_inch(number),
        }
        .map_err(|e| BlockError::Value(letter, e))?;
        if size.as_angstrom() <= 0 {
            return Err(BlockError::Range(
                letter,
                if letter == b'C' {
                    "after a comma: a chamfer above 0"
                } else {
                    "after a comma: a radius above 0"
                },
            ));
        }
        self.block.round = Some(if letter == b'C' {
            CornerRound::Chamfer(size)
        } else {
            CornerRound::Round(size)
        });
        Ok(())
    }

    fn word(&mut self, letter: u8, number: &str, pos: usize) -> Result<(), BlockError> {
        let fanuc = self.dialect == Dialect::Fanuc;
        match letter {
            b'G' => return self.g_word(number, pos),
            b'M' => return self.m_word(number),
            _ => {}
        }
        let slot = self
            .seen
            .get_mut(usize::from(letter - b'A'))
            .ok_or(BlockError::UnknownAddress(letter))?;
        if *slot {
            return Err(BlockError::Repeated(letter));
        }
        *slot = true;
        let units = self.units;
        let length = || {
            match units {
                Units::Mm => Length::from_gcode_mm(number),
                Units::Inch => Length::from_gcode_inch(number),
            }
            .map_err(|e| BlockError::Value(letter, e))
        };
        if let Some(c) = self.cycle.as_mut().filter(|c| c.kind.pecks()) {
            // G74/G75: X, Z, U, W are the end point, read below; P and Q
            // are steps in the least input increment (0.001 mm, 0.0001
            // inch), I and K Haas' steps, R the first block's return or the
            // second's relief, D Haas' relief; S the spindle's speed for
            // the cut (the session takes it with M03/M04).
            match letter {
                b'X' | b'Z' | b'U' | b'W' | b'F' | b'N' | b'S' => {}
                b'I' | b'K' | b'D' | b'R' => {
                    let v = Some(length()?);
                    match letter {
                        b'I' => c.i = v,
                        b'K' => c.k = v,
                        b'D' => c.d = v,
                        _ => c.r = v,
                    }
                    return Ok(());
                }
                b'P' | b'Q' => {
                    if number.is_empty() || !number.bytes().all(|b| b.is_ascii_digit()) {
                        return Err(BlockError::Range(
                            letter,
                            "a step in the least increment, without a point (P2500: 2.5 mm)",
                        ));
                    }
                    let n = whole_number(letter, number)?;
                    let step = Length::from_angstrom(match units {
                        Units::Mm => i64::from(n) * 10_000,
                        Units::Inch => i64::from(n) * 25_400,
                    })
                    .ok_or(BlockError::Range(letter, "a step beyond 99999.999999 mm"))?;
                    if letter == b'P' {
                        c.i = Some(step);
                    } else {
                        c.k = Some(step);
                    }
                    return Ok(());
                }
                _ => {
                    return Err(BlockError::Form(
                        "a G74/G75 block takes X (U) Z (W) P Q R (Fanuc) or I K D (Haas), F and S",
                    ))
                }
            }
        } else if let Some(c) = &mut self.cycle {
            // A cycle's own words. In G73, U and W are a relief (first
            // block) or allowances (second), I and K Haas' relief, R
            // (Fanuc) and D (Haas) the count of passes.
            let pattern = c.kind == CycleKind::Pattern;
            if pattern && matches!(letter, b'R' | b'D') {
                c.passes = Some(passes(letter, number)?);
                return Ok(());
            }
            let slot = match letter {
                b'U' => Some(&mut c.u),
                b'W' => Some(&mut c.w),
                b'D' => Some(&mut c.d),
                b'R' => Some(&mut c.r),
                b'I' if pattern => Some(&mut c.i),
                b'K' if pattern => Some(&mut c.k),
                _ => None,
            };
            if let Some(slot) = slot {
                *slot = Some(length()?);
                return Ok(());
            }
            match letter {
                b'P' | b'Q' => {
                    let n = whole_number(letter, number)?;
                    if letter == b'P' {
                        c.p = Some(n);
                    } else {
                        c.q = Some(n);
                    }
                    return Ok(());
                }
                b'F' | b'N' => {}
                _ => {
                    return Err(BlockError::Form(if pattern {
                        "a G73 block takes U W R (Fanuc's first), P Q U W F, or Haas' P Q I K D U W F: S and T on their own line"
                    } else {
                        "a cycle block takes P Q U W D R F (G71/G72) or P Q F U W (G70): S and T on their own line"
                    }))
                }
            }
        }
        let b = &mut self.block;
        match letter {
            // The Fanuc dwell's X and U are seconds.
            b'X' | b'U' if fanuc && self.dwell => {
                if self.time.is_some() {
                    return Err(BlockError::Form("G04 takes one time: P, X or U"));
                }
                self.time = Some(dwell_us(letter, number, 6)?);
            }
            b'X' | b'U' => {
                if letter == b'U' && !fanuc {
                    return Err(BlockError::OtherDialect(b'U', 0, Dialect::Fanuc));
                }
                if b.x.is_some() {
                    return Err(BlockError::Form("X and U in one block"));
                }
                b.x = Some(length()?);
                b.x_half = Some(
                    match units {
                        Units::Mm => Length::half_gcode_mm(number),
                        Units::Inch => Length::half_gcode_inch(number),
                    }
                    .map_err(|e| BlockError::Value(letter, e))?,
                );
                b.incremental_x = letter == b'U';
            }
            b'Z' | b'W' => {
                if letter == b'W' && !fanuc {
                    return Err(BlockError::OtherDialect(b'W', 0, Dialect::Fanuc));
                }
                if b.z.is_some() {
                    return Err(BlockError::Form("Z and W in one block"));
                }
                b.z = Some(length()?);
                b.incremental_z = letter == b'W';
            }
            b'I' => b.i = Some(length()?),
            b'K' => b.k = Some(length()?),
            b'R' => b.r = Some(length()?),
            b'F' => b.f = Some(length()?),
            b'P' if self.dwell => {
                if self.time.is_some() {
                    return Err(BlockError::Form("G04 takes one time: P, X or U"));
                }
                // Fanuc's P counts milliseconds, ISO's seconds.
                self.time = Some(dwell_us(letter, number, if fanuc { 3 } else { 6 })?);
            }
            b'P' | b'Q' if self.blend => {
                let t = length()?;
                if t.as_angstrom() < 0 {
                    return Err(BlockError::Range(letter, "a tolerance is 0 or more"));
                }
                if letter == b'P' {
                    self.tolerance = Some(t);
                }
                // Q, LinuxCNC's naive-CAM tolerance (segments merged
                // into lines): this planner takes every short segment at
                // its own junction speed; read and checked, no merging.
            }
            b'P' => self.p = Some((whole(letter, number)?, pos)),
            b'L' if self.dynamic => {
                let l = whole(letter, number)?;
                if l > 9 {
                    return Err(BlockError::Range(b'L', "the orientation is 0 to 9"));
                }
                self.l = Some((l, pos));
            }
            b'L' => self.l = Some((whole(letter, number)?, pos)),
            b'H' if !fanuc => self.h = Some((whole(letter, number)?, pos)),
            b'S' => b.s = Some(unitless(letter, number)?),
            // ISO's spindle speed limit with G96; an offset register with
            // G45–G48 (checked with the whole block).
            // G41.1/G42.1: the nose's diameter, a length.
            b'D' if self.dynamic => self.d = Some((length()?, pos)),
            b'D' if !fanuc || self.position_offset => {
                self.d = Some((unitless(letter, number)?, pos))
            }
            b'T' => b.tool = Some(tool_word(number, self.dialect)?),
            b'N' => {
                Length::from_gcode_mm(number).map_err(|e| BlockError::Value(letter, e))?;
                b.n = number.parse().ok();
            }
            b'Y' => {
                // Only a written zero: `Y0`, `Y-0.000`.
                length()?;
                if number.bytes().any(|b| matches!(b, b'1'..=b'9')) {
                    return Err(BlockError::NoYAxis);
                }
            }
            b'O' => return Err(BlockError::ProgramNumber),
            _ => return Err(BlockError::UnknownAddress(letter)),
        }
        Ok(())
    }

    fn g_word(&mut self, number: &str, pos: usize) -> Result<(), BlockError> {
        let tenths = g_code(number).ok_or(BlockError::UnsupportedG(None))?;
        let fanuc = self.dialect == Dialect::Fanuc;
        let b = &mut self.block;
        let repeated = Err(BlockError::Repeated(b'G'));
        let other = |d| Err(BlockError::OtherDialect(b'G', tenths, d));
        fn set<T>(slot: &mut Option<T>, value: T) -> Result<(), BlockError> {
            if slot.is_some() {
                return Err(BlockError::Repeated(b'G'));
            }
            *slot = Some(value);
            Ok(())
        }
        match tenths {
            0 | 10 | 20 | 30 => set(
                &mut b.motion,
                match tenths {
                    0 => Motion::Rapid,
                    10 => Motion::Linear,
                    20 => Motion::ArcCw,
                    _ => Motion::ArcCcw,
                },
            ),
            400 | 410 | 420 => set(
                &mut b.compensation,
                match tenths {
                    400 => Compensation::Off,
                    410 => Compensation::Left,
                    _ => Compensation::Right,
                },
            ),
            170 | 180 | 190 => set(
                &mut b.plane,
                match tenths {
                    170 => Plane::Xy,
                    180 => Plane::Zx,
                    _ => Plane::Yz,
                },
            ),
            610 | 611 | 640 => set(
                &mut b.path,
                match tenths {
                    610 => PathControl::ExactStop,
                    611 => PathControl::ExactPath,
                    _ => PathControl::Blend,
                },
            ),
            800 => {
                if b.cancel_cycle {
                    return repeated;
                }
                b.cancel_cycle = true;
                Ok(())
            }
            411 | 421 if fanuc => other(Dialect::Iso),
            411 | 421 => set(
                &mut b.compensation,
                if tenths == 411 {
                    Compensation::Left
                } else {
                    Compensation::Right
                },
            )
            .map(|()| {
                b.dynamic_nose = Some(DynamicNose {
                    radius: Length::ZERO,
                    orientation: 0,
                })
            }),
            200 | 210 => set(
                &mut b.units,
                if tenths == 200 {
                    Units::Inch
                } else {
                    Units::Mm
                },
            ),
            4500 | 4510 => set(
                &mut b.corner,
                if tenths == 4500 {
                    Corner::Arc
                } else {
                    Corner::Intersection
                },
            ),
            960 | 970 => set(
                &mut b.spindle_mode,
                if tenths == 960 {
                    SpindleMode::Surface
                } else {
                    SpindleMode::Rpm
                },
            ),
            40 | 100 | 280 | 300 | 530 | 450 | 460 | 470 | 480 => {
                set(&mut self.once, (tenths, pos))
            }
            // Probing: LinuxCNC's and grbl's; a Fanuc lathe skips with G31.
            382..=385 if fanuc => other(Dialect::Iso),
            382..=385 => set(&mut self.once, (tenths, pos)),
            540..=590 if tenths % 10 == 0 => set(&mut b.wcs, ((tenths - 540) / 10) as u8),
            700 | 710 | 720 | 730 | 740 | 750 if fanuc => {
                if self.cycle.is_none() {
                    // Two cycles in one block.
                    return repeated;
                }
                Ok(())
            }
            700..=760 if tenths % 10 == 0 => Err(BlockError::Cycle(tenths)),
            // Fanuc system A.
            500 if fanuc => set(&mut self.once, (tenths, pos)),
            980 | 990 if fanuc => set(
                &mut b.feed_mode,
                if tenths == 980 {
                    FeedMode::PerMinute
                } else {
                    FeedMode::PerRev
                },
            ),
            900 if fanuc => set(&mut b.single, SingleCycle::Turn),
            940 if fanuc => set(&mut b.single, SingleCycle::Face),
            920 if fanuc => Err(BlockError::Cycle(tenths)),
            70 | 80 | 910 | 901 | 911 | 950 | 430 | 490 | 281 | 301 | 921 | 922 | 923 if fanuc => {
                other(Dialect::Iso)
            }
            430 => set(&mut b.tool_offset, ToolOffset::On(None)),
            490 => set(&mut b.tool_offset, ToolOffset::Off),
            // ISO.
            281 | 301 | 920..=923 => set(&mut self.once, (tenths, pos)),
            900 | 910 => set(&mut b.incremental, tenths == 910),
            901 | 911 => set(&mut b.arc_absolute, tenths == 901),
            70 | 80 => set(&mut b.diameter, tenths == 70),
            940 | 950 => set(
                &mut b.feed_mode,
                if tenths == 940 {
                    FeedMode::PerMinute
                } else {
                    FeedMode::PerRev
                },
            ),
            500 | 980 | 990 => other(Dialect::Fanuc),
            _ => Err(BlockError::UnsupportedG(Some(tenths))),
        }
    }

    fn m_word(&mut self, number: &str) -> Result<(), BlockError> {
        let tenths = g_code(number).ok_or(BlockError::UnsupportedM(None))?;
        let b = &mut self.block;
        let group = |slot: bool| {
            if slot {
                Err(BlockError::Repeated(b'M'))
            } else {
                Ok(())
            }
        };
        match tenths {
            0 | 10 | 20 | 300 => {
                group(b.stop.is_some())?;
                b.stop = Some(match tenths {
                    0 => Stop::Pause,
                    10 => Stop::Optional,
                    _ => Stop::End,
                });
            }
            30 | 40 | 50 => {
                group(b.spindle.is_some())?;
                b.spindle = Some(match tenths {
                    30 => Spindle::Cw,
                    40 => Spindle::Ccw,
                    _ => Spindle::Off,
                });
            }
            70 | 80 | 90 => {
                group(b.coolant.is_some())?;
                b.coolant = Some(match tenths {
                    70 => Coolant::Mist,
                    80 => Coolant::Flood,
                    _ => Coolant::Off,
                });
            }
            60 if self.dialect == Dialect::Fanuc => {
                return Err(BlockError::OtherDialect(b'M', 60, Dialect::Iso))
            }
            60 => {
                group(b.tool_change)?;
                b.tool_change = true;
            }
            410 | 420 | 430 | 440 => {
                group(b.gear.is_some())?;
                b.gear = Some(((tenths - 400) / 10) as u8);
            }
            // Subprograms: the host expands them.
            980 | 990 => return Err(BlockError::UnsupportedM(Some(tenths))),
            // Any other whole M code: the machine's own (a chip conveyor, a
            // tailstock, a collet), done as the machine's table says.
            _ if tenths % 10 == 0 && tenths <= 9990 => {
                group(b.machine_m.is_some())?;
                b.machine_m = Some(tenths);
            }
            _ => return Err(BlockError::UnsupportedM(Some(tenths))),
        }
        Ok(())
    }

    /// The checks that need the whole block.
    fn finish(mut self) -> Result<Block, (BlockError, usize)> {
        let b = &mut self.block;
        let motion_words =
            b.x.is_some() || b.z.is_some() || b.i.is_some() || b.k.is_some() || b.r.is_some();
        let once_at = self.once.map_or(0, |(_, at)| at);
        match self.once.map(|(code, _)| code) {
            Some(40) => {
                let Some(us) = self.time else {
                    return Err((BlockError::Form("G04 needs its time: P"), once_at));
                };
                if motion_words {
                    return Err((BlockError::Form("G04 takes no motion words"), once_at));
                }
                b.dwell = Some(us);
            }
            Some(100) => {
                let form = |why| Err((BlockError::Form(why), once_at));
                let iso = self.dialect == Dialect::Iso;
                let (here, tool) = match self.l.map(|(l, _)| l) {
                    Some(2) => (false, false),
                    Some(20) => (true, false),
                    Some(1) if iso => (false, true),
                    Some(10) if iso => (true, true),
                    _ if iso => {
                        return form("G10 needs L2 or L20 (a work offset), L1 or L10 (a tool's)")
                    }
                    _ => return form("G10 needs L2 or L20 (a work offset)"),
                };
                let register = match (tool, self.p) {
                    (true, Some((p @ 1..=32, _))) => p as u8,
                    (true, Some((_, at))) => {
                        return Err((BlockError::Range(b'P', "names a tool's register: 1 to 32"), at))
                    }
                    (true, None) => {
                        return form("G10 L1 and L10 need P: the tool's register, 1 to 32")
                    }
                    (false, Some((p @ 1..=6, _))) => p as u8,
                    // ISO (LinuxCNC, grbl): the system in effect.
                    (false, Some((0, _))) if iso => 0,
                    (false, Some((0, at))) => {
                        return Err((
                            BlockError::Range(
                                b'P',
                                "0 is Fanuc's external offset, which this control has not: 1 to 6 (G54 to G59)",
                            ),
                            at,
                        ))
                    }
                    (false, Some((_, at))) => {
                        return Err((BlockError::Range(b'P', "names G54 to G59: 1 to 6"), at))
                    }
                    (false, None) => {
                        return form("G10 needs P, the work offset: 1 to 6 (G54 to G59)")
                    }
                };
                if b.i.is_some() || b.k.is_some() || b.r.is_some() {
                    return form(if tool {
                        "G10 L1 and L10 take X and Z (a nose is set with TOOL R= TIP=)"
                    } else {
                        "G10 takes X and Z"
                    });
                }
                if b.incremental_x || b.incremental_z {
                    return form("G10 takes X and Z, not U and W");
                }
                b.set_work = Some(SetWork {
                    register,
                    here,
                    tool,
                });
                self.p = None;
                self.l = None;
            }
            Some(code @ (280 | 300)) => {
                if b.i.is_some() || b.k.is_some() || b.r.is_some() {
                    return Err((
                        BlockError::Form("G28 and G30 take X and Z (U and W): the way point"),
                        once_at,
                    ));
                }
                b.special = Some(Special::Reference(u8::from(code == 300)));
            }
            Some(code @ (281 | 301 | 921 | 922 | 923)) => {
                if motion_words {
                    return Err((
                        BlockError::Form("G28.1, G30.1 and G92.1 to G92.3 take no axis words"),
                        once_at,
                    ));
                }
                b.special = Some(match code {
                    281 => Special::Store(0),
                    301 => Special::Store(1),
                    923 => Special::RestoreShift,
                    _ => Special::ClearShift(code == 922),
                });
            }
            Some(code @ (450 | 460 | 470 | 480)) => {
                if b.i.is_some() || b.k.is_some() || b.r.is_some() {
                    return Err((
                        BlockError::Form("G45 to G48 move in a line: X and Z (U and W)"),
                        once_at,
                    ));
                }
                if b.x.is_none() && b.z.is_none() {
                    return Err((
                        BlockError::Form("G45 to G48 need X or Z (U or W): the move"),
                        once_at,
                    ));
                }
                let Some((d, at)) = self.d.take() else {
                    return Err((
                        BlockError::Form("G45 to G48 need D: the offset register"),
                        once_at,
                    ));
                };
                let Some(register) = register_word(d).filter(|&n| n >= 1) else {
                    return Err((
                        BlockError::Form("D (the offset register) must be 1 to 32"),
                        at,
                    ));
                };
                b.position_offset = Some(PositionOffset {
                    times: match code {
                        450 => 1,
                        460 => -1,
                        470 => 2,
                        _ => -2,
                    },
                    register,
                });
            }
            Some(code @ 382..=385) => {
                if b.i.is_some() || b.k.is_some() || b.r.is_some() {
                    return Err((
                        BlockError::Form("G38.2 to G38.5 probe in a line: X and Z"),
                        once_at,
                    ));
                }
                if b.x.is_none() && b.z.is_none() {
                    return Err((
                        BlockError::Form("G38.2 to G38.5 need X or Z: where the probing move ends"),
                        once_at,
                    ));
                }
                if b.motion.is_some() {
                    return Err((
                        BlockError::Form(
                            "G38.2 to G38.5 are a motion of their own: no G00 to G03 in the block",
                        ),
                        once_at,
                    ));
                }
                b.special = Some(Special::Probe(ProbeMode {
                    toward: code <= 383,
                    must_change: code == 382 || code == 384,
                }));
            }
            Some(530) => {
                if b.i.is_some() || b.k.is_some() || b.r.is_some() {
                    return Err((BlockError::Form("G53 moves in a line: X and Z"), once_at));
                }
                if b.incremental_x || b.incremental_z {
                    return Err((BlockError::Form("G53 takes X and Z, not U and W"), once_at));
                }
                b.special = Some(Special::Machine);
            }
            Some(_) => {
                // ISO G92, Fanuc G50: the coordinates shifted, and (Fanuc)
                // the spindle speed limit.
                let axes = b.x.is_some() || b.z.is_some();
                let fanuc = self.dialect == Dialect::Fanuc;
                if b.i.is_some()
                    || b.k.is_some()
                    || b.r.is_some()
                    || b.incremental_x
                    || b.incremental_z
                {
                    return Err((
                        BlockError::Form(if fanuc {
                            "G50 takes X and Z (the coordinates here) and S (the spindle speed limit)"
                        } else {
                            "G92 takes X and Z (the coordinates here)"
                        }),
                        once_at,
                    ));
                }
                if !axes && (!fanuc || b.s.is_none()) {
                    return Err((
                        BlockError::Form(if fanuc {
                            "G50 needs X and Z (the coordinates here) or S (the spindle speed limit)"
                        } else {
                            "G92 needs X or Z (the coordinates here)"
                        }),
                        once_at,
                    ));
                }
                if axes {
                    b.special = Some(Special::Shift);
                }
                if fanuc {
                    b.clamp = b.s.take();
                }
            }
            None => {}
        }
        if let Some(t) = self.tolerance {
            b.path = Some(PathControl::Tolerance(t));
        }
        b.cycle = self.cycle;
        if let Some(nose) = &mut b.dynamic_nose {
            let Some((d, _)) = self.d.take() else {
                return Err((
                    BlockError::Form("G41.1 and G42.1 need D: the nose diameter"),
                    0,
                ));
            };
            nose.radius = Length::from_angstrom(d.as_angstrom() / 2).unwrap_or(Length::ZERO);
            nose.orientation = self.l.take().map_or(0, |(l, _)| l as u8);
        }
        if let Some((_, at)) = self.p {
            return Err((
                BlockError::Form(
                    "P only with G04 (the dwell time), G10 (the register) or G64 (the tolerance)",
                ),
                at,
            ));
        }
        if let Some((_, at)) = self.l {
            return Err((BlockError::Form("L only with G10"), at));
        }
        match (self.h, b.tool_offset) {
            (Some((h, _)), Some(ToolOffset::On(_))) => {
                b.tool_offset = Some(ToolOffset::On(Some(h.min(255) as u8)))
            }
            (Some((_, at)), _) => return Err((BlockError::Form("H only with G43"), at)),
            _ => {}
        }
        if let Some((d, at)) = self.d {
            let surface = b.spindle_mode == Some(SpindleMode::Surface);
            let nose = matches!(
                b.compensation,
                Some(Compensation::Left | Compensation::Right)
            ) && self.dialect == Dialect::Iso;
            match (nose, surface) {
                (true, true) => {
                    return Err((
                        BlockError::Form(
                            "D with both G96 and G41/G42: write them in separate blocks",
                        ),
                        at,
                    ))
                }
                (true, false) => {
                    // A tool number: whole, one of the table's registers.
                    let Some(tool) = register_word(d) else {
                        return Err((
                            BlockError::Range(b'D', "with G41/G42 names a tool, 0 to 32"),
                            at,
                        ));
                    };
                    b.nose_tool = Some(tool);
                }
                (false, true) => b.clamp = Some(d),
                (false, false) => {
                    return Err((
                        BlockError::Form(
                            "D only with G41/G42 (the tool), G96 (the spindle speed limit) or G45 to G48 (the offset register)",
                        ),
                        at,
                    ))
                }
            }
        }
        Ok(self.block)
    }
}

/// A `D` word that names a register (or a tool) of the table: a whole
/// number 0 … [`TOOL_REGISTERS`] (the reader takes no sign on `D`).
fn register_word(d: Length) -> Option<u8> {
    let a = d.as_angstrom();
    let unit = crate::length::ANGSTROM_PER_MM;
    if a % unit != 0 || !(0..=TOOL_REGISTERS as i64).contains(&(a / unit)) {
        return None;
    }
    u8::try_from(a / unit).ok()
}

/// A `T` word: a whole number; Fanuc's `T0101` is tool 01 with offset
/// register 01, its `T5` tool 5 with register 5.
fn tool_word(number: &str, dialect: Dialect) -> Result<ToolWord, BlockError> {
    let digits = number.len();
    if digits == 0 || !number.bytes().all(|b| b.is_ascii_digit()) {
        return Err(BlockError::Range(b'T', "must be a whole number"));
    }
    let too_big = Err(BlockError::Range(
        b'T',
        match dialect {
            Dialect::Iso => "names a tool 0 to 99",
            Dialect::Fanuc => "is four digits at most: tool and offset register, T0101",
        },
    ));
    let value = number.bytes().try_fold(0u32, |n, b| {
        n.checked_mul(10)?.checked_add(u32::from(b - b'0'))
    });
    let Some(value) = value.filter(|&v| v <= 9999) else {
        return too_big;
    };
    let byte = |v: u32| u8::try_from(v).unwrap_or(0);
    match dialect {
        Dialect::Fanuc if digits <= 2 => Ok(ToolWord {
            tool: byte(value),
            offset: Some(byte(value)),
        }),
        Dialect::Fanuc => Ok(ToolWord {
            tool: byte(value / 100),
            offset: Some(byte(value % 100)),
        }),
        Dialect::Iso if value <= 99 => Ok(ToolWord {
            tool: byte(value),
            offset: None,
        }),
        Dialect::Iso => too_big,
    }
}

/// A G number as a code in tenths: `1`, `01`, `90.1`; `None` if it is no
/// G code (a sign, more than one decimal, more than 3 digits).
fn g_code(number: &str) -> Option<u16> {
    let (whole, tenth) = match crate::text::split_once(number, b'.') {
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

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

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
    fn g41_g42_d_names_the_tool_whose_nose_compensates() {
        let b = parse_block("g42 d1").unwrap();
        assert_eq!(
            (b.compensation, b.nose_tool),
            (Some(Compensation::Right), Some(1))
        );
        let b = parse_block("G41 D0 G01 X2").unwrap();
        assert_eq!(
            (b.compensation, b.nose_tool),
            (Some(Compensation::Left), Some(0))
        );
        assert_eq!(parse_block("G42").unwrap().nose_tool, None);
        // Inch or millimetre, D is a tool number.
        assert_eq!(
            parse_in("G20 G42 D32", Units::Mm).unwrap().nose_tool,
            Some(32)
        );
        let range = BlockError::Range(b'D', "with G41/G42 names a tool, 0 to 32");
        assert_eq!(parse_block("G42 D33"), Err(range));
        assert_eq!(parse_block("G42 D1.5"), Err(range));
        assert!(matches!(parse_block("G40 D1"), Err(BlockError::Form(_))));
        assert!(matches!(
            parse_block("G96 S100 G42 D1"),
            Err(BlockError::Form(_))
        ));
        // Fanuc's G41/G42 take the nose from the T word's register.
        let fanuc = parse("G42 D1", Dialect::Fanuc, Units::Mm).map_err(|l| l.error);
        assert_eq!(fanuc, Err(BlockError::UnknownAddress(b'D')));
    }

    #[test]
    fn a_number_may_stand_apart_from_its_letter() {
        let b = parse_block("G0 X 2 Z\t-3.5").unwrap();
        assert_eq!(b.motion, Some(Motion::Rapid));
        assert_eq!((b.x, b.z), (mm("2"), mm("-3.5")));
        assert_eq!(parse_block("G 1 X1").unwrap().motion, Some(Motion::Linear));
        // G 20 is read for the whole line, as G20 is.
        let b = parse_in("X 1 G 20", Units::Mm).unwrap();
        assert_eq!(b.x, mm("25.4"));
        let b = parse("G 4 P 1500", Dialect::Fanuc, Units::Mm).unwrap();
        assert_eq!(b.dwell, Some(1_500_000));
        // Within a number spaces are refused, at the digit left over.
        let e = parse_located("X1 2").unwrap_err();
        assert_eq!((e.error, e.column), (BlockError::NotAWord, 4));
        assert_eq!(parse_block("X Z1"), Err(BlockError::NotAWord));
        assert!(is_block("X 2") && is_block("g\t0") && !is_block("X ") && !is_block("X Z"));
    }

    #[test]
    fn lines_as_cam_posts_and_machinists_write_them() {
        let b = parse_block("N10 G00 G18 G21 X30. Z2. Y0").unwrap();
        assert_eq!((b.x, b.z, b.n), (mm("30"), mm("2"), Some(10)));
        assert_eq!(b.plane, Some(Plane::Zx));
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
        assert_eq!(at("G17 G00 X1 G19"), (BlockError::Repeated(b'G'), 12));
        assert_eq!(at("G20 X1 G21"), (BlockError::Repeated(b'G'), 8));
        assert_eq!(at("G18 G00 G18"), (BlockError::Repeated(b'G'), 9));
        assert_eq!(at("G90.2"), (BlockError::UnsupportedG(Some(902)), 1));
        assert_eq!(
            at("G97 S200 D3000"),
            (
                BlockError::Form(
                    "D only with G41/G42 (the tool), G96 (the spindle speed limit) or G45 to G48 (the offset register)"
                ),
                10
            )
        );
        assert_eq!(
            at("G01 U1"),
            (BlockError::OtherDialect(b'U', 0, Dialect::Fanuc), 5)
        );
        assert_eq!(at("G01 X1 G71"), (BlockError::Cycle(710), 8));
        // A D read left to right: LinuxCNC's G41.1 later in the line makes it
        // no nose diameter in Fanuc's words.
        let fanuc = |l: &str| parse(l, Dialect::Fanuc, Units::Mm).map_err(|e| e.error);
        assert_eq!(fanuc("G0 D2 G41.1"), Err(BlockError::UnknownAddress(b'D')));
        assert!(parse("G0 D2 G41.1", Dialect::Iso, Units::Mm).is_ok());
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
    fn the_two_dialects() {
        let fanuc = |line| parse(line, Dialect::Fanuc, Units::Mm);
        let b = fanuc("G50 S2500").unwrap();
        assert_eq!((b.clamp, b.s), (mm("2500"), None));
        let b = fanuc("N20 G96 S180 M03 G99 F.2 M8").unwrap();
        assert_eq!(b.spindle_mode, Some(SpindleMode::Surface));
        assert_eq!((b.s, b.f), (mm("180"), mm("0.2")));
        assert_eq!(
            (b.spindle, b.coolant, b.feed_mode),
            (
                Some(Spindle::Cw),
                Some(Coolant::Flood),
                Some(FeedMode::PerRev)
            )
        );
        let b = fanuc("G04 X1.5").unwrap();
        assert_eq!((b.dwell, b.x), (Some(1_500_000), None));
        assert_eq!(fanuc("G4U.25").unwrap().dwell, Some(250_000));
        let b = fanuc("T0100").unwrap().tool.unwrap();
        assert_eq!((b.tool, b.offset), (1, Some(0)));
        assert_eq!(fanuc("M30").unwrap().stop, Some(Stop::End));
        let refused = |line| fanuc(line).unwrap_err().error;
        let b = fanuc("G90 X20 W-5 R-1 F.2").unwrap();
        assert_eq!((b.single, b.motion), (Some(SingleCycle::Turn), None));
        assert_eq!(
            (b.x, b.z, b.incremental_z, b.r),
            (mm("20"), mm("-5"), true, mm("-1"))
        );
        assert_eq!(fanuc("G94 Z-1").unwrap().single, Some(SingleCycle::Face));
        // In the ISO dialect G90 and G94 keep their meaning.
        let iso = parse("G90 G94 X20", Dialect::Iso, Units::Mm).unwrap();
        assert_eq!((iso.single, iso.incremental), (None, Some(false)));
        assert_eq!(refused("G92 X20 Z-5 F1.5"), BlockError::Cycle(920));
        assert_eq!(
            refused("G91 X1"),
            BlockError::OtherDialect(b'G', 910, Dialect::Iso)
        );
        assert_eq!(refused("X1 U2"), BlockError::Form("X and U in one block"));
        assert_eq!(refused("W1 Z2"), BlockError::Form("Z and W in one block"));
        let b = fanuc("G50 X100 Z50").unwrap();
        assert_eq!(
            (b.special, b.x, b.clamp),
            (Some(Special::Shift), mm("100"), None)
        );
        let b = fanuc("G50 X100 S2000").unwrap();
        assert_eq!((b.special, b.clamp), (Some(Special::Shift), mm("2000")));
        assert!(matches!(refused("G50 U1"), BlockError::Form(_)));
        assert!(matches!(refused("G50"), BlockError::Form(_)));
        let b = fanuc("G28 U0 W0").unwrap();
        assert_eq!(b.special, Some(Special::Reference(0)));
        assert!(b.incremental_x && b.incremental_z);
        assert_eq!(
            fanuc("G30 U0").unwrap().special,
            Some(Special::Reference(1))
        );
        assert_eq!(refused("G28 G04 P1"), BlockError::Repeated(b'G'));
        assert!(matches!(refused("G28 U0 K1"), BlockError::Form(_)));
        assert_eq!(
            refused("G28.1"),
            BlockError::OtherDialect(b'G', 281, Dialect::Iso)
        );
        assert_eq!(fanuc("M00").unwrap().stop, Some(Stop::Pause));
        assert_eq!(fanuc("M1").unwrap().stop, Some(Stop::Optional));
        assert_eq!(refused("M00 M30"), BlockError::Repeated(b'M'));
        assert!(matches!(refused("G53 U1"), BlockError::Form(_)));
        assert_eq!(refused("G96 S100 D2000"), BlockError::UnknownAddress(b'D'));
        let iso = |line| parse(line, Dialect::Iso, Units::Mm);
        let b = iso("G7 G95 G90.1 G96 D2500 S200").unwrap();
        assert_eq!((b.diameter, b.arc_absolute), (Some(true), Some(true)));
        assert_eq!((b.clamp, b.s), (mm("2500"), mm("200")));
        assert_eq!(b.feed_mode, Some(FeedMode::PerRev));
        assert_eq!(iso("G8 G91.1").unwrap().arc_absolute, Some(false));
        assert_eq!(iso("G92 Z0").unwrap().special, Some(Special::Shift));
        assert!(matches!(iso("G92").unwrap_err().error, BlockError::Form(_)));
        assert!(matches!(
            iso("G92 S100").unwrap_err().error,
            BlockError::Form(_)
        ));
        let cleared = [
            ("G92.1", Special::ClearShift(false)),
            ("G92.2", Special::ClearShift(true)),
            ("G92.3", Special::RestoreShift),
            ("G28.1", Special::Store(0)),
            ("G30.1", Special::Store(1)),
            ("G28", Special::Reference(0)),
            ("G53 G01 X10 Z-3", Special::Machine),
        ];
        for (line, special) in cleared {
            assert_eq!(iso(line).unwrap().special, Some(special), "{line}");
        }
        // Probing: the four kinds, a straight move to X/Z of their own.
        for (line, toward, must_change) in [
            ("G38.2 Z-10 F50", true, true),
            ("G38.3 X5", true, false),
            ("G38.4 Z1", false, true),
            ("G38.5 X1 Z1", false, false),
        ] {
            let b = iso(line).unwrap();
            let mode = ProbeMode {
                toward,
                must_change,
            };
            assert_eq!(b.special, Some(Special::Probe(mode)), "{line}");
            assert_eq!(b.motion, None, "{line}: the motion mode stays");
            assert_eq!(
                u32::from(mode.code()),
                line[1..5].replace('.', "").parse::<u32>().unwrap()
            );
        }
        for line in ["G38.2", "G38.2 Z1 K1", "G01 G38.2 Z1", "G38.2 G28 Z1"] {
            assert!(iso(line).is_err(), "{line}");
        }
        assert_eq!(
            refused("G38.2 W1"),
            BlockError::OtherDialect(b'G', 382, Dialect::Iso),
            "a Fanuc lathe skips with G31"
        );
        assert!(matches!(
            iso("G28.1 X1").unwrap_err().error,
            BlockError::Form(_)
        ));
        assert_eq!(
            iso("G53 G92 X1").unwrap_err().error,
            BlockError::Repeated(b'G')
        );
        assert_eq!(
            iso("G99").unwrap_err().error,
            BlockError::OtherDialect(b'G', 990, Dialect::Fanuc)
        );
        assert_eq!(
            iso("G50 S2000").unwrap_err().error.to_string(),
            "G50 belongs to the FANUC dialect (OPT DIALECT=FANUC)"
        );
        assert_eq!(
            fanuc("G76 P010060 Q100 R.05")
                .unwrap_err()
                .error
                .to_string(),
            "G76 canned cycles not supported"
        );
        // G73 is LinuxCNC's chip-breaking drill in the ISO dialect.
        assert_eq!(
            iso("G73 X1 Z-5 R1 Q1").unwrap_err().error.to_string(),
            "G73 canned cycles not supported"
        );
        assert!(fanuc("G73 U1 W.5 R3").unwrap().cycle.is_some());
        assert_eq!(
            iso("M98 P1000").unwrap_err().error.to_string(),
            "M98 subprograms are expanded by the host"
        );
    }

    #[test]
    fn refusals() {
        assert_eq!(parse_block("G01 X1 X2"), Err(BlockError::Repeated(b'X')));
        assert_eq!(parse_block("G01 G02"), Err(BlockError::Repeated(b'G')));
        assert_eq!(
            parse_block("G04 X1"),
            Err(BlockError::Form("G04 needs its time: P"))
        );
        assert_eq!(
            parse_block("G04 P1 X1"),
            Err(BlockError::Form("G04 takes no motion words"))
        );
        assert_eq!(
            parse_block("P1"),
            Err(BlockError::Form(
                "P only with G04 (the dwell time), G10 (the register) or G64 (the tolerance)"
            ))
        );
        assert_eq!(parse_block("M1.5"), Err(BlockError::UnsupportedM(Some(15))));
        assert_eq!(parse_block("M13").map(|b| b.machine_m), Ok(Some(130)));
        assert_eq!(parse_block("M13 M16"), Err(BlockError::Repeated(b'M')));
        assert_eq!(parse_block("M42").map(|b| b.gear), Ok(Some(2)));
        assert_eq!(parse_block("M3 M4"), Err(BlockError::Repeated(b'M')));
        assert_eq!(
            parse_block("T101").unwrap_err().to_string(),
            "T names a tool 0 to 99"
        );
        assert_eq!(
            parse_block("T1.5").unwrap_err().to_string(),
            "T must be a whole number"
        );
        assert_eq!(
            parse_block("S-5").unwrap_err().to_string(),
            "S must be 0 to 99999.999999"
        );
        assert_eq!(
            parse_block("G4 P.").unwrap_err().to_string(),
            "P not a number"
        );
        assert_eq!(parse_block("G450 G451"), Err(BlockError::Repeated(b'G')));
        assert_eq!(parse_block("G1.5"), Err(BlockError::UnsupportedG(Some(15))));
        assert_eq!(parse_block("G-1"), Err(BlockError::UnsupportedG(None)));
        assert_eq!(parse_block("Q5"), Err(BlockError::UnknownAddress(b'Q')));
        assert_eq!(parse_block("G01 X"), Err(BlockError::NotAWord));
        assert_eq!(parse_block("G01 X1 $"), Err(BlockError::NotAWord));
        assert_eq!(parse_block("G01 (open"), Err(BlockError::Comment));
        // FreeCAD prints doubles: read, rounded once.
        assert_eq!(
            parse_block("X-2.8918148932211922").map(|b| b.x),
            Ok(Length::from_angstrom(-28_918_149))
        );
        assert!(matches!(
            parse_block("Z--1"),
            Err(BlockError::Value(b'Z', _))
        ));
    }
}

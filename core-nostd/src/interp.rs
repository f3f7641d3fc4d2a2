//! The interpreter's state between blocks: the modal G codes, the feed as
//! written, the spindle and the coolant; and what a block's feed and
//! spindle speed come to.
//!
//! The feed per revolution and the constant surface speed are open loop
//! until the spindle has an encoder: `G95`/`G99` move at `F·S` mm/min from
//! the commanded spindle speed, and `G96` sets that speed from the surface
//! speed at the tool's X where the block starts.

use crate::gcode::{
    Block, Coolant, Dialect, FeedMode, Motion, PathControl, Plane, Spindle, SpindleMode, ToolWord,
    Units,
};
use crate::length::{Length, LENGTH_LIMIT};
use crate::plan::Feed;
use crate::trig::PI_Q61;
use crate::wide::mul_div;

/// The modal state of the G-code path (compensation lives in the contour
/// engine, the diameter mode in the configuration's `DIAM`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Modal {
    /// G00–G03.
    pub motion: Motion,
    /// G91 (ISO).
    pub incremental: bool,
    /// G90.1: arc centres absolute (ISO); G91.1 (power-on): from the start.
    pub arc_absolute: bool,
    /// G20 / G21.
    pub units: Units,
    /// G94/G98 or G95/G99.
    pub feed_mode: FeedMode,
    /// The feed as written (read in the block's unit): mm/min or mm/rev;
    /// none after power-on.
    pub feed: Option<Length>,
    /// G17/G18/G19.
    pub plane: Plane,
    /// G61/G61.1/G64.
    pub path: PathControl,
}

impl Modal {
    /// Power-on: G00, G90, G91.1, G21, feed per minute, no feed.
    pub const POWER_ON: Modal = Modal {
        motion: Motion::Rapid,
        incremental: false,
        arc_absolute: false,
        units: Units::Mm,
        feed_mode: FeedMode::PerMinute,
        feed: None,
        plane: Plane::Zx,
        path: PathControl::Blend,
    };

    /// The state after `b`'s words.
    pub fn after(&self, b: &Block) -> Modal {
        Modal {
            motion: b.motion.unwrap_or(self.motion),
            incremental: b.incremental.unwrap_or(self.incremental),
            arc_absolute: b.arc_absolute.unwrap_or(self.arc_absolute),
            units: b.units.unwrap_or(self.units),
            feed_mode: b.feed_mode.unwrap_or(self.feed_mode),
            feed: b.f.or(self.feed),
            plane: b.plane.unwrap_or(self.plane),
            path: b.path.unwrap_or(self.path),
        }
    }
}

/// The spindle as programmed: direction, speed word and limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpindleState {
    /// M03/M04/M05.
    pub turning: Spindle,
    /// G96/G97.
    pub mode: SpindleMode,
    /// The last `S`: rpm under G97, the surface speed under G96 (m/min, or
    /// ft/min under G20); none after power-on.
    pub s: Option<Length>,
    /// The speed limit (Fanuc `G50 S`, ISO `G96 D`), rpm.
    pub clamp: Option<Length>,
}

/// Why a spindle speed or a feed cannot be had.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpeedError {
    /// Constant surface speed at X = 0 with no speed limit.
    SurfaceAtCentre,
    /// A feed per revolution while the spindle stands or has no speed.
    NotTurning,
    /// The feed outside 0.001 … 99 999.999999 mm/min (or none programmed).
    Feed,
}

impl SpeedError {
    /// What a refusal says.
    pub const fn as_str(self) -> &'static str {
        match self {
            SpeedError::SurfaceAtCentre => {
                "G96 surface speed at X0 needs a spindle speed limit (G50 S or G96 D)"
            }
            SpeedError::NotTurning => "per revolution needs the spindle turning (M03/M04 and S)",
            SpeedError::Feed => "must come to 0.001 to 99999.999999 mm/min",
        }
    }
}

impl SpindleState {
    /// Power-on: stopped, G97, no speed, no limit.
    pub const POWER_ON: SpindleState = SpindleState {
        turning: Spindle::Off,
        mode: SpindleMode::Rpm,
        s: None,
        clamp: None,
    };

    /// The state after `b`'s words.
    pub fn after(&self, b: &Block) -> SpindleState {
        SpindleState {
            turning: b.spindle.unwrap_or(self.turning),
            mode: b.spindle_mode.unwrap_or(self.mode),
            s: b.s.or(self.s),
            clamp: b.clamp.or(self.clamp),
        }
    }

    /// The commanded speed in rpm with the tool at `radius` (X on the
    /// radius), whether or not the spindle turns: `S` under G97, the
    /// surface speed's rpm under G96 (`units` that of `S`), each within
    /// the limit. `None` without an `S`.
    pub fn rpm(&self, radius: Length, units: Units) -> Result<Option<Length>, SpeedError> {
        let Some(s) = self.s else {
            return Ok(None);
        };
        let rpm = match self.mode {
            SpindleMode::Rpm => s,
            SpindleMode::Surface => match surface_rpm(s, units, radius) {
                Some(rpm) => rpm,
                None => return self.clamp.map(Some).ok_or(SpeedError::SurfaceAtCentre),
            },
        };
        Ok(Some(match self.clamp {
            Some(c) if c.as_angstrom() < rpm.as_angstrom() => c,
            _ => rpm,
        }))
    }

    /// The state with `top` (the spindle's top speed) as a limit too.
    pub fn within(&self, top: Option<Length>) -> SpindleState {
        let clamp = match (self.clamp, top) {
            (Some(c), Some(t)) => Some(c.min(t)),
            (c, t) => c.or(t),
        };
        SpindleState { clamp, ..*self }
    }

    /// The rpm while the spindle turns, else 0.
    pub fn running_rpm(&self, radius: Length, units: Units) -> Length {
        match (self.turning, self.rpm(radius, units)) {
            (Spindle::Off, _) | (_, Err(_) | Ok(None)) => Length::ZERO,
            (_, Ok(Some(rpm))) => rpm,
        }
    }
}

/// Revolutions per minute for surface speed `v` (m/min, ft/min under
/// `Inch`) at `radius`: `1000·v/(π·D)`, `D = 2·|radius|` in mm, rounded
/// half away from zero to 10⁻⁷ rpm; capped at 99 999.999999 (the largest
/// length). `None` at radius 0.
///
/// ```
/// use core_nostd::{gcode::Units, interp::surface_rpm, length::Length};
/// let l = |s| Length::from_mm_str(s).unwrap();
/// // 180 m/min on a 30 mm diameter: 1909.8593171… rpm.
/// assert_eq!(surface_rpm(l("180"), Units::Mm, l("15")).unwrap().as_angstrom(), 19_098_593_171);
/// assert_eq!(surface_rpm(l("180"), Units::Mm, Length::ZERO), None);
/// ```
pub fn surface_rpm(v: Length, units: Units, radius: Length) -> Option<Length> {
    let d = 2 * u128::from(radius.as_angstrom().unsigned_abs());
    if d == 0 {
        return None;
    }
    // m/min from ft/min: 0.3048 = 3048/10⁴.
    let per_10k: u128 = match units {
        Units::Mm => 10_000,
        Units::Inch => 3_048,
    };
    // rpm·10⁷ = 1000·v·10⁷·(per_10k/10⁴) / (π·D·10⁻⁷·10⁷), π = PI_Q61/2⁶¹;
    // twice the quotient, then halved with rounding.
    let num = 2 * 1_000 * 10_000_000 * u128::from(v.as_angstrom().unsigned_abs()) * per_10k;
    let den = PI_Q61 * d * 10_000;
    let twice = mul_div(num, 1 << 61, den);
    let cap = LENGTH_LIMIT.as_angstrom();
    let rpm = i64::try_from(twice.div_ceil(2)).map_or(cap, |r| r.min(cap));
    Length::from_angstrom(rpm)
}

/// The feed along the path of a block: `F` per minute, or `F·rpm` per
/// revolution (rounded half away from zero to 10⁻⁷ mm/min).
pub fn path_feed(
    modal: &Modal,
    spindle: &SpindleState,
    radius: Length,
) -> Result<Option<Feed>, SpeedError> {
    let Some(f) = modal.feed else {
        return Ok(None);
    };
    let per_min = match modal.feed_mode {
        FeedMode::PerMinute => f,
        FeedMode::PerRev => {
            let rpm = spindle.running_rpm(radius, modal.units).as_angstrom();
            if rpm == 0 {
                return Err(SpeedError::NotTurning);
            }
            // ⌊2·F·rpm/10⁷⌋, then halved rounding up: half away from zero.
            let f = u128::from(f.as_angstrom().unsigned_abs());
            let twice = mul_div(f, u128::from(rpm.unsigned_abs()), 5_000_000);
            i64::try_from(twice.div_ceil(2))
                .ok()
                .and_then(Length::from_angstrom)
                .ok_or(SpeedError::Feed)?
        }
    };
    Feed::new(per_min).map(Some).ok_or(SpeedError::Feed)
}

/// The auxiliary functions: the spindle, the coolant, the tool named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Aux {
    /// The spindle.
    pub spindle: SpindleState,
    /// M07/M08/M09.
    pub coolant: Coolant,
    /// The last `T` word.
    pub tool: Option<ToolWord>,
    /// The spindle gear range (`M41`–`M44`: 1 … 4), none until one is
    /// named.
    pub gear: Option<u8>,
}

impl Aux {
    /// Power-on: spindle stopped, coolant off, no tool named.
    pub const POWER_ON: Aux = Aux {
        spindle: SpindleState::POWER_ON,
        coolant: Coolant::Off,
        tool: None,
        gear: None,
    };

    /// The state after `b`'s words.
    pub fn after(&self, b: &Block) -> Aux {
        Aux {
            spindle: self.spindle.after(b),
            coolant: b.coolant.unwrap_or(self.coolant),
            tool: b.tool.or(self.tool),
            gear: b.gear.or(self.gear),
        }
    }

    /// What `RESET` and the end of a program leave: the spindle stopped
    /// and back to G97 (its `S` and limit kept), the coolant off, the tool
    /// kept.
    pub const fn stopped(&self) -> Aux {
        Aux {
            spindle: SpindleState {
                turning: Spindle::Off,
                mode: SpindleMode::Rpm,
                ..self.spindle
            },
            coolant: Coolant::Off,
            tool: self.tool,
            gear: self.gear,
        }
    }

    /// Whether going from `self` to `next` asks the axes to be at rest
    /// first: the spindle starts, stops, reverses, or changes its rpm
    /// under G97 while turning; the coolant switches. Under G96 the rpm
    /// follows X block by block without a stop.
    pub fn needs_rest(&self, next: &Aux) -> bool {
        let (a, b) = (&self.spindle, &next.spindle);
        let speed =
            a.mode != b.mode || (b.mode == SpindleMode::Rpm && (a.s != b.s || a.clamp != b.clamp));
        let spindle = a.turning != b.turning || (b.turning != Spindle::Off && speed);
        spindle || self.coolant != next.coolant
    }
}

pub use crate::gcode::TOOL_REGISTERS;

/// Work coordinate systems: `G54` … `G59`.
pub const WORK_SYSTEMS: usize = 6;

/// One offset register of the tool table (Fanuc layout; lecture 13's
/// offset registers): lengths on the radius for X.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ToolEntry {
    /// Geometry offset, X and Z.
    pub geometry: [Length; 2],
    /// Wear offset, X and Z.
    pub wear: [Length; 2],
    /// The nose radius and tip code (0 … 9), once set; without them nose
    /// compensation uses the configured ones.
    pub nose: Option<(Length, u8)>,
}

impl ToolEntry {
    /// Geometry plus wear, if within the length range.
    pub fn offset(&self) -> Option<[Length; 2]> {
        Some([
            self.geometry[0].checked_add(self.wear[0])?,
            self.geometry[1].checked_add(self.wear[1])?,
        ])
    }
}

/// What the machine does for one of its own M codes (`MCODE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MAction {
    /// Stop with a message, as `M00`: the operator does by hand what the
    /// old machine did, then presses cycle start (any code not in the
    /// table).
    Stop,
    /// Nothing: the machine has nothing to do for it (set so on purpose).
    Nothing,
    /// Switch user output `n` (1 … 4) on or off, at rest.
    Output(u8, bool),
    /// Wait at rest until user input `n` (1 … 4) reads the level given.
    Wait(u8, bool),
}

/// The M codes the machine's table can hold.
pub const MCODES: usize = 16;

/// The machine's M code table: each of its own M codes (M16, M31, …) and
/// what it does; a code not in it stops with a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MCodes {
    /// The code in tenths (M16 is 160) and its action; 0: an empty slot.
    entries: [(u16, MAction); MCODES],
}

impl Default for MCodes {
    fn default() -> Self {
        Self::new()
    }
}

impl MCodes {
    /// An empty table: every machine M code stops with a message.
    pub const fn new() -> MCodes {
        MCodes {
            entries: [(0, MAction::Stop); MCODES],
        }
    }

    /// What code `tenths` (M16 is 160) does.
    pub fn get(&self, tenths: u16) -> MAction {
        self.entries
            .iter()
            .find(|(c, _)| *c == tenths && tenths != 0)
            .map_or(MAction::Stop, |(_, a)| *a)
    }

    /// Sets what code `tenths` does (`Stop`, the default, clears it);
    /// false when the table is full.
    pub fn set(&mut self, tenths: u16, action: MAction) -> bool {
        for e in self.entries.iter_mut().filter(|(c, _)| *c == tenths) {
            *e = (0, MAction::Stop);
        }
        if action == MAction::Stop {
            return true;
        }
        match self.entries.iter_mut().find(|(c, _)| *c == 0) {
            Some(free) => {
                *free = (tenths, action);
                true
            }
            None => false,
        }
    }

    /// The codes set, with their actions.
    pub fn entries(&self) -> impl Iterator<Item = (u16, MAction)> + '_ {
        self.entries.iter().copied().filter(|(c, _)| *c != 0)
    }
}

/// The work offsets and the tool table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Offsets {
    /// `G54` … `G59`: where each system's zero lies in machine coordinates.
    pub work: [[Length; 2]; WORK_SYSTEMS],
    /// Registers 01 … 32.
    pub tools: [ToolEntry; TOOL_REGISTERS],
    /// ISO `G92`, Fanuc `G50 X Z`: added to every work system.
    pub shift: [Length; 2],
    /// The shift `G92.2` cleared, for `G92.3`.
    pub kept_shift: [Length; 2],
    /// The positions `G28` and `G30` return to, machine coordinates
    /// (machine zero until `G28.1`/`G30.1` store others).
    pub reference: [[Length; 2]; 2],
    /// The machine's own M codes (kept with the table).
    pub mcodes: MCodes,
    /// How G-code lines are read (`OPT`; kept with the table, as a
    /// control keeps its parameters and panel switches).
    pub reading: Reading,
    /// The machine's switches: which are wired, their level, the filter
    /// (`INPUT`; kept with the table).
    pub wiring: crate::inputs::InputConfig,
    /// The homing cycle's settings (`HOMING`; kept with the table).
    pub homing: crate::homing::HomingConfig,
}

/// How G-code lines are read: the dialect and the two panel switches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reading {
    /// The dialect (`OPT DIALECT=`).
    pub dialect: Dialect,
    /// Blocks starting with `/` are skipped (`OPT BDEL=1`).
    pub block_delete: bool,
    /// `M01` stops (`OPT OPTSTOP=1`).
    pub optional_stop: bool,
}

impl Reading {
    /// Power-on: ISO, both switches off.
    pub const DEFAULT: Reading = Reading {
        dialect: Dialect::Iso,
        block_delete: false,
        optional_stop: false,
    };

    /// As one value: bit 0 Fanuc, bit 1 block delete, bit 2 optional stop.
    pub const fn bits(self) -> u8 {
        (matches!(self.dialect, Dialect::Fanuc) as u8)
            | (self.block_delete as u8) << 1
            | (self.optional_stop as u8) << 2
    }

    /// The reading of [`Reading::bits`]; `None` beyond its three bits.
    pub const fn from_bits(b: u8) -> Option<Reading> {
        if b > 7 {
            return None;
        }
        Some(Reading {
            dialect: if b & 1 != 0 {
                Dialect::Fanuc
            } else {
                Dialect::Iso
            },
            block_delete: b & 2 != 0,
            optional_stop: b & 4 != 0,
        })
    }
}

impl Offsets {
    /// All zero, no nose set.
    pub const ZERO: Offsets = Offsets {
        work: [[Length::ZERO; 2]; WORK_SYSTEMS],
        tools: [ToolEntry {
            geometry: [Length::ZERO; 2],
            wear: [Length::ZERO; 2],
            nose: None,
        }; TOOL_REGISTERS],
        shift: [Length::ZERO; 2],
        kept_shift: [Length::ZERO; 2],
        reference: [[Length::ZERO; 2]; 2],
        mcodes: MCodes::new(),
        reading: Reading::DEFAULT,
        wiring: crate::inputs::InputConfig::NONE,
        homing: crate::homing::HomingConfig::NONE,
    };

    /// A register (1 … 32); `None` for 0 or beyond the table.
    pub fn register(&self, n: u8) -> Option<&ToolEntry> {
        self.tools.get(usize::from(n).checked_sub(1)?)
    }

    /// The tool's offset in effect: its register's geometry plus wear (zero
    /// without a register).
    pub fn tool_offset(&self, sel: &Selection) -> Option<[Length; 2]> {
        match self.register(sel.register) {
            Some(t) => t.offset(),
            None => Some([Length::ZERO; 2]),
        }
    }

    /// The machine coordinates of work zero with the shift and the tool's
    /// offset: machine = work + this, if within the length range.
    pub fn vector(&self, sel: &Selection) -> Option<[Length; 2]> {
        let work = self.work.get(usize::from(sel.wcs))?;
        let tool = self.tool_offset(sel)?;
        let sum = |a: usize| work[a].checked_add(tool[a])?.checked_add(self.shift[a]);
        Some([sum(0)?, sum(1)?])
    }
}

/// Which offsets are in effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Selection {
    /// 0 … 5: `G54` … `G59`.
    pub wcs: u8,
    /// The offset register in effect (0: none): Fanuc's `T0101`, ISO's
    /// `G43 H`.
    pub register: u8,
    /// The tool in the turret's working station: Fanuc's `T01..`, ISO's
    /// `T1 M06` (its register holds its nose).
    pub loaded: u8,
}

impl Selection {
    /// Power-on: `G54`, no offset register, no tool.
    pub const POWER_ON: Selection = Selection {
        wcs: 0,
        register: 0,
        loaded: 0,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::{parse, Dialect};

    fn l(s: &str) -> Length {
        Length::from_mm_str(s).unwrap()
    }

    fn block(line: &str) -> Block {
        parse(line, Dialect::Fanuc, Units::Mm).unwrap()
    }

    #[test]
    fn surface_speed_to_rpm() {
        // 1000·v/(π·D), against f64 well away from rounding ties.
        for (v, r) in [
            ("180", "15"),
            ("250", "0.5"),
            ("30", "400"),
            ("99999", "0.001"),
        ] {
            let want = 1000.0 * v.parse::<f64>().unwrap()
                / (core::f64::consts::PI * 2.0 * r.parse::<f64>().unwrap());
            let got = surface_rpm(l(v), Units::Mm, l(r)).unwrap().as_angstrom() as f64 / 1e7;
            assert!((got - want.min(99_999.999999)).abs() < 1e-7, "{v} {r}");
        }
        // 500 ft/min on a 2 in diameter: 954.93 rpm.
        let rpm = surface_rpm(l("500"), Units::Inch, l("25.4")).unwrap();
        assert_eq!(rpm.as_angstrom() / 100_000, 95_492);
    }

    #[test]
    fn clamp_and_centre() {
        let s = SpindleState::POWER_ON.after(&block("G96 S200 M03"));
        assert_eq!(
            s.rpm(Length::ZERO, Units::Mm),
            Err(SpeedError::SurfaceAtCentre)
        );
        let s = s.after(&block("G50 S2500"));
        assert_eq!(s.rpm(Length::ZERO, Units::Mm), Ok(Some(l("2500"))));
        assert_eq!(
            s.rpm(l("100"), Units::Mm).unwrap().unwrap().as_angstrom(),
            3_183_098_862
        );
        let s = s.after(&block("G97 S3000"));
        assert_eq!(s.rpm(l("100"), Units::Mm), Ok(Some(l("2500"))));
    }

    #[test]
    fn feed_per_revolution() {
        let m = Modal::POWER_ON.after(&block("G99 F0.25"));
        let s = SpindleState::POWER_ON.after(&block("S1200"));
        assert_eq!(path_feed(&m, &s, l("10")), Err(SpeedError::NotTurning));
        let s = s.after(&block("M04"));
        assert_eq!(
            path_feed(&m, &s, l("10")).unwrap().unwrap().mm_per_min(),
            l("300")
        );
        let m = m.after(&block("G98 F150"));
        assert_eq!(
            path_feed(&m, &s, l("10")).unwrap().unwrap().mm_per_min(),
            l("150")
        );
        let m = m.after(&block("G99 F99"));
        assert_eq!(path_feed(&m, &s, l("10")), Err(SpeedError::Feed));
    }

    #[test]
    fn offsets_add_up() {
        let mut o = Offsets::ZERO;
        o.work[1] = [l("10"), l("-200")];
        o.tools[2].geometry = [l("1.5"), l("-3")];
        o.tools[2].wear = [l("-0.01"), l("0.002")];
        let sel = Selection {
            wcs: 1,
            register: 3,
            loaded: 3,
        };
        assert_eq!(o.vector(&sel), Some([l("11.49"), l("-202.998")]));
        assert_eq!(
            o.vector(&Selection { register: 0, ..sel }),
            Some([l("10"), l("-200")])
        );
        assert_eq!(o.vector(&Selection { wcs: 6, ..sel }), None);
        o.work[1][0] = l("99999");
        o.tools[2].geometry[0] = l("99999");
        assert_eq!(o.vector(&sel), None);
    }

    #[test]
    fn what_asks_for_rest() {
        let m = Aux::POWER_ON;
        let on = m.after(&block("G97 S500 M03"));
        assert!(m.needs_rest(&on));
        assert!(on.needs_rest(&on.after(&block("S600"))));
        assert!(!on.needs_rest(&on.after(&block("S500 T0202"))));
        let css = on.after(&block("G96 S180"));
        assert!(on.needs_rest(&css));
        assert!(!css.needs_rest(&css.after(&block("S200"))));
        assert!(css.needs_rest(&css.after(&block("M08"))));
        assert!(!m.needs_rest(&m.after(&block("S900"))));
    }
}

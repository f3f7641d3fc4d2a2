//! The homing cycle's settings (`docs/inputs.md` §8): per axis which way
//! its switch lies, the machine position of the point the cycle ends at,
//! the travel from it; the cycle's rates and pull-off; the order of the
//! axes; whether the machine must be homed before it moves.
//!
//! An axis homes on its limit switch of the side it seeks (or on the one
//! switch wired for both ends): seek fast until the switch trips, pull
//! off, locate slowly until it trips again, pull off, and the machine
//! position there is the axis' home.

use crate::inputs::{Input, InputConfig};
use crate::length::Length;

/// One axis' homing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxisHoming {
    /// The axis homes.
    pub homes: bool,
    /// Which way its switch lies: -1 towards minus, +1 towards plus.
    pub dir: i8,
    /// The machine position at the end of the cycle (X on the radius).
    pub home: Length,
    /// How far the axis can go from one end of its travel to the other:
    /// the seek gives up beyond it.
    pub travel: Length,
    /// The play of its leadscrew, taken up at each reversal (X on the
    /// radius: the cross-slide's own).
    pub backlash: Length,
}

impl AxisHoming {
    /// Not homed; its switch towards plus (grbl's default).
    pub const NONE: AxisHoming = AxisHoming {
        homes: false,
        dir: 1,
        home: Length::ZERO,
        travel: Length::ZERO,
        backlash: Length::ZERO,
    };
}

/// The handwheel (a manual pulse generator, `docs/inputs.md` §11): which
/// axis it moves, by how many impulses per count, how fast.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Wheel {
    /// The axis it moves: 0 X, 1 Z; `None`: off.
    pub axis: Option<u8>,
    /// Impulses per count: 1, 10 or 100.
    pub scale: u8,
    /// Its feed, 10⁻³ mm/min.
    pub feed: u32,
}

impl Wheel {
    /// Power-on: off, ×1, 500 mm/min.
    pub const OFF: Wheel = Wheel {
        axis: None,
        scale: 1,
        feed: 500_000,
    };

    /// Whether every value is in range.
    pub fn valid(&self) -> bool {
        matches!(self.axis, None | Some(0 | 1))
            && matches!(self.scale, 1 | 10 | 100)
            && (1..=MAX_RATE).contains(&self.feed)
    }
}

/// The homing cycle's settings, with the soft limits and the handwheel's
/// (kept with the table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HomingConfig {
    /// X's and Z's.
    pub axes: [AxisHoming; 2],
    /// The seek's feed, 10⁻³ mm/min.
    pub seek: u32,
    /// The locating feed, 10⁻³ mm/min.
    pub locate: u32,
    /// How far the axis backs off the switch.
    pub pulloff: Length,
    /// Z homes before X (X first by default: the cross slide clear of the
    /// chuck before the carriage moves).
    pub z_first: bool,
    /// Nothing moves at power-on until the machine is homed (grbl's
    /// alarm 11).
    pub required: bool,
    /// Soft limits: once an axis is homed, motion that would leave its
    /// travel is refused before it starts (grbl's `$20`).
    pub soft: bool,
    /// With soft limits, a jog past the travel runs up to it instead of
    /// being refused (grblHAL's `$40`).
    pub jog_clip: bool,
    /// The handwheel.
    pub wheel: Wheel,
}

/// `n` mm, for the constants (within the length's limit).
const fn mm(n: i64) -> Length {
    match Length::from_angstrom(n * 10_000_000) {
        Some(l) => l,
        None => Length::ZERO,
    }
}

/// The longest travel and the farthest home, 10 m.
pub const MAX_LENGTH: Length = mm(10_000);
/// The longest pull-off, 100 mm.
pub const MAX_PULLOFF: Length = mm(100);

/// The most backlash an axis may be given (a worn leadscrew has 0.05 to
/// 0.3 mm).
pub const MAX_BACKLASH: Length = mm(5);
/// The fastest homing feed, 10⁻³ mm/min (20 m/min).
pub const MAX_RATE: u32 = 20_000_000;

impl HomingConfig {
    /// Power-on: no axis homed; seek 500 mm/min, locate 25 mm/min, pull
    /// off 1 mm (grbl's defaults), X first, not required.
    pub const NONE: HomingConfig = HomingConfig {
        axes: [AxisHoming::NONE; 2],
        seek: 500_000,
        locate: 25_000,
        pulloff: mm(1),
        z_first: false,
        required: false,
        soft: false,
        jog_clip: false,
        wheel: Wheel::OFF,
    };

    /// The axes homed (0 X, 1 Z), in the cycle's order.
    pub fn order(&self) -> impl Iterator<Item = usize> + '_ {
        let order = if self.z_first { [1, 0] } else { [0, 1] };
        order.into_iter().filter(|&a| self.axes[a & 1].homes)
    }

    /// Whether every value is in range (a record read back is checked).
    pub fn valid(&self) -> bool {
        let rate = |r: u32| (1..=MAX_RATE).contains(&r);
        rate(self.seek)
            && rate(self.locate)
            && self.pulloff > Length::ZERO
            && self.pulloff <= MAX_PULLOFF
            && self.wheel.valid()
            && self.axes.iter().all(|a| {
                (a.dir == 1 || a.dir == -1)
                    && a.home.as_angstrom().unsigned_abs() <= MAX_LENGTH.as_angstrom() as u64
                    && a.travel >= Length::ZERO
                    && a.travel <= MAX_LENGTH
                    && a.backlash >= Length::ZERO
                    && a.backlash <= MAX_BACKLASH
            })
    }
}

impl AxisHoming {
    /// The machine positions the axis may reach once homed: its travel
    /// from home, away from the switch.
    pub fn window(&self) -> Option<(Length, Length)> {
        let far = if self.dir > 0 {
            self.home.checked_sub(self.travel)?
        } else {
            self.home.checked_add(self.travel)?
        };
        Some(if far < self.home {
            (far, self.home)
        } else {
            (self.home, far)
        })
    }
}

/// The limit inputs of `axis` (0 X, 1 Z): (minus, plus).
pub const fn limit_inputs(axis: usize) -> (Input, Input) {
    if axis == 0 {
        (Input::LimitXMinus, Input::LimitXPlus)
    } else {
        (Input::LimitZMinus, Input::LimitZPlus)
    }
}

/// The switch `axis` homes on when it seeks towards `dir`: the limit of
/// that side if wired, else the axis' one switch for both ends (wired as
/// the minus side's); `None` when neither is wired.
pub fn home_switch(axis: usize, dir: i8, wiring: &InputConfig) -> Option<Input> {
    let (minus, plus) = limit_inputs(axis);
    let side = if dir > 0 { plus } else { minus };
    [side, minus]
        .into_iter()
        .find(|i| wiring.used & i.bit() != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_axis_homes_on_its_side_or_on_its_one_switch() {
        let mut w = InputConfig::NONE;
        assert_eq!(home_switch(0, 1, &w), None);
        w.used = Input::LimitXMinus.bit();
        // One switch for both ends, wired as X-.
        assert_eq!(home_switch(0, 1, &w), Some(Input::LimitXMinus));
        w.used |= Input::LimitXPlus.bit();
        assert_eq!(home_switch(0, 1, &w), Some(Input::LimitXPlus));
        assert_eq!(home_switch(0, -1, &w), Some(Input::LimitXMinus));
        assert_eq!(home_switch(1, 1, &w), None);
    }

    #[test]
    fn the_order_is_x_first_unless_z_first_and_skips_unhomed_axes() {
        let mut c = HomingConfig::NONE;
        assert_eq!(c.order().count(), 0);
        c.axes[0].homes = true;
        c.axes[1].homes = true;
        assert!(c.order().eq([0, 1]));
        c.z_first = true;
        assert!(c.order().eq([1, 0]));
        c.axes[0].homes = false;
        assert!(c.order().eq([1]));
    }

    #[test]
    fn directions_rates_and_lengths_have_their_bounds() {
        let mut c = HomingConfig::NONE;
        assert!(c.valid());
        c.axes[1].dir = 0;
        assert!(!c.valid(), "a side");
        c.axes[1].dir = -1;
        c.axes[1].travel = mm(10_001);
        assert!(!c.valid());
        c.axes[1].travel = mm(300);
        assert!(c.valid());
        c.seek = 0;
        assert!(!c.valid());
        c.seek = MAX_RATE + 1;
        assert!(!c.valid());
        c.seek = MAX_RATE;
        c.pulloff = Length::ZERO;
        assert!(!c.valid());
    }
}

//! What the board drives besides the axes: the spindle's run, direction
//! and speed, and the coolant.
//!
//! The speed is an analogue command through a PWM output (a VFD's 0–10 V
//! input behind an RC filter or an isolated PWM-to-voltage module): the
//! duty is the commanded rpm over the spindle's top speed (`AUX SMAX=`).
//! Open loop: the spindle is assumed to turn at what it is told.

use crate::gcode::{Coolant, Spindle};
use crate::length::Length;

/// The outputs' state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Outputs {
    /// Run and direction.
    pub spindle: Spindle,
    /// The commanded speed, 10⁻³ rpm (0 while stopped).
    pub rpm: u32,
    /// The rpm at full duty (`AUX SMAX`), 10⁻³ rpm; 0 when the speed is
    /// set on the machine by hand (the duty stays 0).
    pub top: u32,
    /// Mist or flood.
    pub coolant: Coolant,
}

impl Outputs {
    /// Power-on and after a reset: everything off.
    pub const OFF: Outputs = Outputs {
        spindle: Spindle::Off,
        rpm: 0,
        top: 0,
        coolant: Coolant::Off,
    };

    /// The PWM compare value for a timer `period` counts long: `rpm/top`
    /// of it, rounded half up, full at or above the top speed; 0 without
    /// a top speed or with the spindle stopped.
    ///
    /// ```
    /// use core_nostd::outputs::Outputs;
    /// use core_nostd::gcode::{Coolant, Spindle};
    /// let o = Outputs { spindle: Spindle::Cw, rpm: 1_000_000, top: 3_000_000, coolant: Coolant::Off };
    /// assert_eq!(o.compare(16_800), 5_600);
    /// assert_eq!(Outputs { spindle: Spindle::Off, ..o }.compare(16_800), 0);
    /// ```
    pub fn compare(&self, period: u32) -> u32 {
        if self.spindle == Spindle::Off || self.top == 0 {
            return 0;
        }
        let rpm = u64::from(self.rpm.min(self.top));
        let top = u64::from(self.top);
        // (2³² − 1)² + 2³¹ < 2⁶⁴; the quotient ≤ period.
        ((rpm * u64::from(period) + top / 2) / top) as u32
    }
}

/// An rpm as the outputs carry it: 10⁻³ rpm, rounded half away from zero
/// (a negative one is 0; above 4 294 967.295 rpm, the largest).
///
/// ```
/// use core_nostd::{length::Length, outputs::milli_rpm};
/// assert_eq!(milli_rpm(Length::from_angstrom(19_098_593_171).unwrap()), 1_909_859);
/// ```
pub fn milli_rpm(rpm: Length) -> u32 {
    let a = rpm.as_angstrom().max(0);
    u32::try_from((a + 5_000) / 10_000).unwrap_or(u32::MAX)
}

/// Writes 10⁻³ rpm as `1909.859`.
pub fn write_rpm<W: core::fmt::Write>(w: &mut W, milli: u32) -> core::fmt::Result {
    write!(w, "{}.{:03}", milli / 1000, milli % 1000)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_duty_is_the_share_of_the_top_speed_and_saturates() {
        let o = |rpm, top| Outputs {
            spindle: Spindle::Ccw,
            rpm,
            top,
            coolant: Coolant::Flood,
        };
        assert_eq!(o(0, 3_000_000).compare(16_800), 0);
        assert_eq!(o(3_000_000, 3_000_000).compare(16_800), 16_800);
        assert_eq!(o(9_000_000, 3_000_000).compare(16_800), 16_800);
        assert_eq!(o(1_500_000, 0).compare(16_800), 0);
        // 1 rpm of 3000 on 16 800 counts: 5.6 → 6.
        assert_eq!(o(1_000, 3_000_000).compare(16_800), 6);
        // The largest values do not overflow.
        assert_eq!(o(u32::MAX, u32::MAX).compare(u32::MAX), u32::MAX);
        assert_eq!(o(u32::MAX - 1, u32::MAX).compare(u32::MAX), u32::MAX - 1);
    }

    #[test]
    fn rpm_rounds_half_away_and_prints_three_decimals() {
        let l = |a| Length::from_angstrom(a).unwrap();
        assert_eq!(milli_rpm(l(4_999)), 0);
        assert_eq!(milli_rpm(l(5_000)), 1);
        assert_eq!(milli_rpm(l(-5_000)), 0);
        assert_eq!(milli_rpm(l(999_999_999_990)), 100_000_000);
        let mut s = heapless::String::<16>::new();
        write_rpm(&mut s, 1_909_859).unwrap();
        assert_eq!(s.as_str(), "1909.859");
        s.clear();
        write_rpm(&mut s, 7).unwrap();
        assert_eq!(s.as_str(), "0.007");
    }
}

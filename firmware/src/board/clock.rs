//! The timers' clocks, which the board's peripherals and the spindle's PWM
//! both divide.

/// TIM2's counter clock before its prescaler.
#[cfg(not(feature = "qemu"))]
pub const TIM2_CLK_HZ: u32 = 84_000_000;
#[cfg(feature = "qemu")]
pub const TIM2_CLK_HZ: u32 = 1_000_000_000;

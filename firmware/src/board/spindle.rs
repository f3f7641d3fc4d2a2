//! The spindle and coolant outputs, by register.
//!
//! | signal | pin | |
//! |---|---|---|
//! | spindle speed | PB6 (TIM4 CH1, AF2) | PWM ≈ 5 kHz, duty = rpm / `AUX SMAX` |
//! | spindle run | PB7 | high while it turns (`M03`, `M04`) |
//! | spindle direction | PB8 | high for counter-clockwise (`M04`) |
//! | flood coolant | PB9 | high for `M08` |
//! | mist coolant | PB10 | high for `M07` |
//!
//! The speed is an analogue command: a VFD's 0–10 V input behind a PWM to
//! voltage module (or an RC filter and an amplifier). The outputs switch
//! at rest between blocks; under `G96` the duty follows the speed each
//! block carries, at its start, from the step interrupt. A reset, a fault
//! and a panic drive every output low. Pull-downs on the board hold them
//! low while the MCU is in reset.

use core_nostd::gcode::{Coolant, Spindle as Turning};
use core_nostd::outputs::Outputs;
use stm32f4::stm32f405 as pac;

/// The PWM's period in counts of TIM4: 5 kHz from 84 MHz.
const PERIOD: u32 = 16_800;
/// TIM4's prescaler for about that (QEMU's timer clock is 1 GHz).
const PSC: u32 = (super::clock::TIM2_CLK_HZ / (5_000 * PERIOD)).saturating_sub(1);

const RUN: u32 = 7;
const CCW: u32 = 8;
const FLOOD: u32 = 9;
const MIST: u32 = 10;
/// The machine's user outputs 1 … 4 (`MCODE … DO=ON|OFF`): PB12 … PB15.
const USER_OUT: u32 = 12;
/// The user outputs' reset bits in BSRR.
const USER_OUT_LOW: u32 = 0b1111 << (USER_OUT + 16);

/// TIM4's PWM and the GPIOB pins.
pub struct Spindle {
    tim: pac::TIM4,
    now: Outputs,
}

impl Spindle {
    /// Sets up the pins (every output low) and the PWM (duty 0); takes
    /// TIM4. Clocks of GPIOB and TIM4 must be on.
    pub fn new(tim: pac::TIM4, gpiob: &pac::GPIOB) -> Spindle {
        all_low();
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        gpiob.afrl().modify(|_, w| unsafe { w.afrl6().bits(2) });
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        gpiob.moder().modify(|_, w| unsafe {
            w.moder6()
                .bits(0b10)
                .moder7()
                .bits(0b01)
                .moder8()
                .bits(0b01)
                .moder9()
                .bits(0b01)
                .moder10()
                .bits(0b01)
                .moder12()
                .bits(0b01)
                .moder13()
                .bits(0b01)
                .moder14()
                .bits(0b01)
                .moder15()
                .bits(0b01)
        });
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        tim.psc().write(|w| unsafe { w.bits(PSC) });
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        tim.arr().write(|w| unsafe { w.bits(PERIOD - 1) });
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        tim.ccr1().write(|w| unsafe { w.bits(0) });
        // PWM mode 1, preloaded: a new duty takes effect at the period's end.
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        tim.ccmr1_output()
            .modify(|_, w| unsafe { w.oc1m().bits(0b110).oc1pe().set_bit() });
        tim.ccer().modify(|_, w| w.cc1e().set_bit());
        tim.cr1().modify(|_, w| w.arpe().set_bit());
        tim.egr().write(|w| w.ug().set_bit());
        tim.cr1().modify(|_, w| w.cen().set_bit());
        Spindle {
            tim,
            now: Outputs::OFF,
        }
    }

    /// What the outputs command now.
    pub fn outputs(&self) -> Outputs {
        self.now
    }

    /// Switches everything (at rest).
    pub fn set(&mut self, o: &Outputs) {
        self.now = *o;
        self.duty();
        let on = |b: bool, pin: u32| if b { 1 << pin } else { 1 << (pin + 16) };
        let bits = on(o.spindle != Turning::Off, RUN)
            | on(o.spindle == Turning::Ccw, CCW)
            | on(o.coolant == Coolant::Flood, FLOOD)
            | on(o.coolant == Coolant::Mist, MIST);
        // SAFETY: one atomic BSRR write of this module's pins.
        unsafe { &*pac::GPIOB::ptr() }
            .bsrr()
            .write(|w| unsafe { w.bits(bits) });
    }

    /// A block starts with `rpm` (10⁻³ rpm): the duty follows.
    #[inline(always)]
    pub fn follow(&mut self, rpm: u32) {
        if rpm != self.now.rpm {
            self.now.rpm = rpm;
            self.duty();
        }
    }

    /// Everything low at once (a reset), the user outputs too.
    pub fn off(&mut self) {
        self.set(&Outputs {
            top: self.now.top,
            ..Outputs::OFF
        });
        // SAFETY: one atomic BSRR write of this module's pins.
        unsafe { &*pac::GPIOB::ptr() }
            .bsrr()
            .write(|w| unsafe { w.bits(USER_OUT_LOW) });
    }

    fn duty(&mut self) {
        let c = self.now.compare(PERIOD);
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        self.tim.ccr1().write(|w| unsafe { w.bits(c) });
    }
}

/// User output `n` (1 … 4) driven `on`; another `n` drives nothing (the
/// session accepts 1 … 4 only).
pub fn user_output(n: u8, on: bool) {
    let Some(pin) = n
        .checked_sub(1)
        .filter(|&i| i < 4)
        .map(|i| USER_OUT + u32::from(i))
    else {
        return;
    };
    let bit = if on { 1 << pin } else { 1 << (pin + 16) };
    // SAFETY: one atomic BSRR write of one of this module's pins.
    unsafe { (*pac::GPIOB::ptr()).bsrr().write(|w| w.bits(bit)) };
}

/// Every spindle, coolant and user output low, the PWM's duty 0, without the
/// driver (faults, panics).
pub fn all_low() {
    // SAFETY: one atomic BSRR write; a write of TIM4's compare register,
    // which nothing runs after a fault.
    unsafe {
        (*pac::GPIOB::ptr()).bsrr().write(|w| {
            w.bits(
                (1 << (RUN + 16))
                    | (1 << (CCW + 16))
                    | (1 << (FLOOD + 16))
                    | (1 << (MIST + 16))
                    | USER_OUT_LOW,
            )
        });
        (*pac::TIM4::ptr()).ccr1().write(|w| w.bits(0));
    }
}

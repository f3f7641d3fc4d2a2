//! Step/dir outputs: timed step events on four `embedded-hal` output pins.
//!
//! Each event comes with its tick (`crate::step`); the DIR pins of its axes
//! are set first and left to settle for the drive's set-up time, then on the
//! tick the STEP pins of the stepping axes rise together, stay high for the
//! pulse width, and fall. Events come one at a time; nothing is
//! materialised as a list.

use crate::interleave::StepEvent;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;

/// Timing of the step/dir outputs, validated (`DRIVE` in the protocol).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveTiming {
    rate_hz: u32,
    pulse_us: u32,
    setup_us: u32,
}

/// Why a drive timing was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TimingError {
    /// Rate outside 1 … 200 000 steps per second.
    Rate,
    /// Pulse width outside 1 … 1000 µs.
    Pulse,
    /// Direction set-up time above 1000 µs.
    Setup,
    /// The pulse does not fit in one step period.
    PulseTooLong,
}

impl DriveTiming {
    /// The highest step rate: 200 000 steps per second (a 5 µs period).
    pub const MAX_RATE_HZ: u32 = 200_000;
    /// Defaults that suit common step/dir drives: up to 50 000 step events
    /// per second, 5 µs pulse, 5 µs direction set-up.
    pub const DEFAULT: DriveTiming = DriveTiming {
        rate_hz: 50_000,
        pulse_us: 5,
        setup_us: 5,
    };

    /// A timing, checked: the pulse must end within one step period.
    ///
    /// ```
    /// use core_nostd::stepdir::{DriveTiming, TimingError};
    /// assert!(DriveTiming::new(20_000, 5, 5).is_ok());
    /// assert_eq!(DriveTiming::new(200_000, 5, 0), Err(TimingError::PulseTooLong));
    /// ```
    pub const fn new(rate_hz: u32, pulse_us: u32, setup_us: u32) -> Result<Self, TimingError> {
        if rate_hz == 0 || rate_hz > Self::MAX_RATE_HZ {
            return Err(TimingError::Rate);
        }
        if pulse_us == 0 || pulse_us > 1000 {
            return Err(TimingError::Pulse);
        }
        if setup_us > 1000 {
            return Err(TimingError::Setup);
        }
        // pulse_us ≤ 1000 and rate ≤ 200 000: the product fits in u32.
        if pulse_us * rate_hz >= 1_000_000 {
            return Err(TimingError::PulseTooLong);
        }
        Ok(DriveTiming {
            rate_hz,
            pulse_us,
            setup_us,
        })
    }

    /// Step events per second.
    pub const fn rate_hz(&self) -> u32 {
        self.rate_hz
    }
    /// STEP pulse width, µs.
    pub const fn pulse_us(&self) -> u32 {
        self.pulse_us
    }
    /// DIR set-up time before a step whose direction changed, µs.
    pub const fn setup_us(&self) -> u32 {
        self.setup_us
    }
}

impl Default for DriveTiming {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The clock step events are timed on: ticks of the device's
/// [`crate::step::TickRate`] since the current run began (a timer now; the
/// spindle encoder's counts when threading).
pub trait TickClock {
    /// A run begins: its tick 0 is now.
    fn start_run(&mut self);
    /// Waits until the run's clock reaches `tick` (returns at once when it
    /// has passed).
    fn wait_until(&mut self, tick: u64);
}

/// The four outputs of a two-axis step/dir interface.
pub struct StepDir<XS, XD, ZS, ZD> {
    x_step: XS,
    x_dir: XD,
    z_step: ZS,
    z_dir: ZD,
    /// The DIR levels last written (true: negative), unknown at first.
    dir: [Option<bool>; 2],
}

/// A pin failed; the outputs were driven low where possible.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PinError;

impl<XS, XD, ZS, ZD> StepDir<XS, XD, ZS, ZD>
where
    XS: OutputPin,
    XD: OutputPin,
    ZS: OutputPin,
    ZD: OutputPin,
{
    /// Takes the pins and drives both STEP lines low.
    pub fn new(x_step: XS, x_dir: XD, z_step: ZS, z_dir: ZD) -> Self {
        let mut s = StepDir {
            x_step,
            x_dir,
            z_step,
            z_dir,
            dir: [None; 2],
        };
        s.stop_outputs();
        s
    }

    /// Drives both STEP lines low (the safe state).
    pub fn stop_outputs(&mut self) {
        let _ = self.x_step.set_low();
        let _ = self.z_step.set_low();
    }

    /// Issues one step event at `tick` of the run: the DIR lines of the
    /// stepping axes first (when one changes, the drive's set-up time passes
    /// before the step, so DIR is written as early as possible: right after
    /// the event before), then, on the tick, the STEP lines rise together,
    /// stay high for the pulse width and fall. DIR high means negative. On a
    /// pin failure both STEP lines are driven low.
    #[inline(always)]
    pub fn issue<C: TickClock, D: DelayNs>(
        &mut self,
        event: StepEvent,
        tick: u64,
        timing: &DriveTiming,
        clock: &mut C,
        delay: &mut D,
    ) -> Result<(), PinError> {
        self.rise(event, tick, timing, clock, delay)?;
        delay.delay_us(timing.pulse_us);
        self.fall()
    }

    /// The first half of [`StepDir::issue`]: DIR, its set-up, the tick, the
    /// STEP lines high. The caller ends the pulse with [`StepDir::fall`] no
    /// sooner than the pulse width later, and may work meanwhile (a step
    /// interrupt pulls its next event). On a pin failure both STEP lines
    /// are driven low.
    #[inline(always)]
    pub fn rise<C: TickClock, D: DelayNs>(
        &mut self,
        event: StepEvent,
        tick: u64,
        timing: &DriveTiming,
        clock: &mut C,
        delay: &mut D,
    ) -> Result<(), PinError> {
        let result = self.rise_inner(event, tick, timing, clock, delay);
        if result.is_err() {
            self.stop_outputs();
        }
        result
    }

    /// Ends a pulse: both STEP lines low.
    #[inline(always)]
    pub fn fall(&mut self) -> Result<(), PinError> {
        let x = self.x_step.set_low();
        let z = self.z_step.set_low();
        match (x, z) {
            (Ok(()), Ok(())) => Ok(()),
            _ => Err(PinError),
        }
    }

    #[inline(always)]
    fn rise_inner<C: TickClock, D: DelayNs>(
        &mut self,
        event: StepEvent,
        tick: u64,
        timing: &DriveTiming,
        clock: &mut C,
        delay: &mut D,
    ) -> Result<(), PinError> {
        let mut changed = false;
        if event.x_steps() && self.dir[0] != Some(event.x_negative()) {
            self.x_dir
                .set_state(event.x_negative().into())
                .map_err(|_| PinError)?;
            self.dir[0] = Some(event.x_negative());
            changed = true;
        }
        if event.z_steps() && self.dir[1] != Some(event.z_negative()) {
            self.z_dir
                .set_state(event.z_negative().into())
                .map_err(|_| PinError)?;
            self.dir[1] = Some(event.z_negative());
            changed = true;
        }
        if changed {
            delay.delay_us(timing.setup_us);
        }
        clock.wait_until(tick);
        if event.x_steps() {
            self.x_step.set_high().map_err(|_| PinError)?;
        }
        if event.z_steps() {
            self.z_step.set_high().map_err(|_| PinError)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::impulse::Impulses;
    use crate::interleave::{ImpulsePoint, LinearBlock};
    use core::cell::RefCell;
    use embedded_hal::digital::ErrorType;
    use std::rc::Rc;
    use std::vec::Vec;

    /// (time ns, pin index, level) for every pin write.
    type Log = Rc<RefCell<(u64, Vec<(u64, usize, bool)>)>>;

    struct Pin(usize, Log);
    impl ErrorType for Pin {
        type Error = core::convert::Infallible;
    }
    impl OutputPin for Pin {
        fn set_low(&mut self) -> Result<(), Self::Error> {
            let mut l = self.1.borrow_mut();
            let t = l.0;
            l.1.push((t, self.0, false));
            Ok(())
        }
        fn set_high(&mut self) -> Result<(), Self::Error> {
            let mut l = self.1.borrow_mut();
            let t = l.0;
            l.1.push((t, self.0, true));
            Ok(())
        }
    }
    /// Virtual time in ns: delays advance it; the tick clock (1 µs ticks)
    /// waits by jumping to the tick when it lies ahead.
    struct Time(Log, u64);
    impl DelayNs for Time {
        fn delay_ns(&mut self, ns: u32) {
            self.0.borrow_mut().0 += u64::from(ns);
        }
    }
    impl TickClock for Time {
        fn start_run(&mut self) {
            self.1 = self.0.borrow().0;
        }
        fn wait_until(&mut self, tick: u64) {
            let mut l = self.0.borrow_mut();
            l.0 = l.0.max(self.1 + tick * 1000);
        }
    }

    const XS: usize = 0;
    const XD: usize = 1;
    const ZS: usize = 2;
    const ZD: usize = 3;

    type Outputs = StepDir<Pin, Pin, Pin, Pin>;

    /// Issues a block's events `period` µs apart through `issue`; returns
    /// every pin write.
    fn run_with(
        dx: i32,
        dz: i32,
        period: u64,
        mut issue: impl FnMut(&mut Outputs, StepEvent, u64, &mut Time, &mut Time),
    ) -> Vec<(u64, usize, bool)> {
        let log: Log = Rc::new(RefCell::new((0, Vec::new())));
        let mut sd = StepDir::new(
            Pin(XS, log.clone()),
            Pin(XD, log.clone()),
            Pin(ZS, log.clone()),
            Pin(ZD, log.clone()),
        );
        log.borrow_mut().1.clear();
        let p = |x, z| ImpulsePoint {
            x: Impulses(x),
            z: Impulses(z),
        };
        let block = LinearBlock::new(p(10, 10), p(10 + dx, 10 + dz)).unwrap();
        let mut time = Time(log.clone(), 0);
        let mut clock = Time(log.clone(), 0);
        clock.start_run();
        for (i, e) in block.events().enumerate() {
            let tick = (i as u64 + 1) * period;
            issue(&mut sd, e, tick, &mut clock, &mut time);
        }
        let out = log.borrow().1.clone();
        out
    }

    /// Issues a block's events `period` µs apart with [`StepDir::issue`].
    fn run(dx: i32, dz: i32, timing: DriveTiming, period: u64) -> Vec<(u64, usize, bool)> {
        run_with(dx, dz, period, |sd, e, tick, clock, time| {
            sd.issue(e, tick, &timing, clock, time).unwrap()
        })
    }

    #[test]
    fn pulses_on_their_ticks_and_dir_settles_first() {
        let timing = DriveTiming::new(20_000, 5, 8).unwrap();
        for (dx, dz) in [(7, -3), (-2, 9), (0, -4), (5, 0), (-6, -6)] {
            let log = run(dx, dz, timing, 50);
            // Rising edges per axis = impulses of the block.
            let rises = |pin| log.iter().filter(|e| e.1 == pin && e.2).count() as i32;
            assert_eq!((rises(XS), rises(ZS)), (dx.abs(), dz.abs()));
            // DIR written once per moving axis, before any step, at the right level,
            // and at least the set-up time before the first rising STEP edge.
            for (step, dir, d) in [(XS, XD, dx), (ZS, ZD, dz)] {
                let dirs: Vec<_> = log.iter().filter(|e| e.1 == dir).collect();
                if d == 0 {
                    assert!(dirs.is_empty());
                    continue;
                }
                assert_eq!(dirs.len(), 1);
                assert_eq!(dirs[0].2, d < 0);
                let first = log.iter().find(|e| e.1 == step && e.2).unwrap();
                assert!(first.0 >= dirs[0].0 + 8_000);
            }
            // Each pulse is high for 5 µs; rises on their ticks, 50 µs apart.
            for e in log.iter().filter(|e| e.2 && (e.1 == XS || e.1 == ZS)) {
                let fall = log
                    .iter()
                    .find(|f| f.1 == e.1 && !f.2 && f.0 >= e.0)
                    .unwrap();
                assert_eq!(fall.0 - e.0, 5_000);
            }
            let mut rise_times: Vec<u64> = log
                .iter()
                .filter(|e| e.2 && (e.1 == XS || e.1 == ZS))
                .map(|e| e.0)
                .collect();
            rise_times.dedup();
            assert_eq!(rise_times.len() as i32, dx.abs().max(dz.abs()));
            for (i, t) in rise_times.iter().enumerate() {
                assert_eq!(*t, (i as u64 + 1) * 50_000);
            }
        }
    }

    #[test]
    fn rise_and_fall_are_issue_in_two_halves() {
        let timing = DriveTiming::new(20_000, 5, 8).unwrap();
        let whole = run(4, -7, timing, 50);
        // The same events, the pulse ended by the caller 5 µs after the rise.
        let halves = run_with(4, -7, 50, |sd, e, tick, clock, time| {
            sd.rise(e, tick, &timing, clock, time).unwrap();
            time.delay_us(5);
            sd.fall().unwrap();
        });
        // Rises and DIR writes as `issue` makes them; every STEP line is
        // written low at each fall (a line already low stays low).
        let rises = |l: &[(u64, usize, bool)]| -> Vec<(u64, usize, bool)> {
            l.iter()
                .copied()
                .filter(|e| e.2 || e.1 == XD || e.1 == ZD)
                .collect()
        };
        assert_eq!(rises(&halves), rises(&whole));
        let falls = |l: &[(u64, usize, bool)]| -> Vec<(u64, usize)> {
            l.iter()
                .filter(|e| !e.2 && (e.1 == XS || e.1 == ZS))
                .map(|e| (e.0, e.1))
                .collect()
        };
        assert_eq!(falls(&halves), falls(&whole));
    }

    #[test]
    fn a_late_tick_steps_at_once() {
        // Events one tick apart cannot wait for the 8 µs set-up of the first.
        let timing = DriveTiming::new(20_000, 5, 8).unwrap();
        let log = run(3, 0, timing, 1);
        let rises: Vec<u64> = log
            .iter()
            .filter(|e| e.1 == XS && e.2)
            .map(|e| e.0)
            .collect();
        assert_eq!(rises, [8_000, 13_000, 18_000]);
    }

    #[test]
    fn timing_limits() {
        assert_eq!(DriveTiming::new(0, 5, 5), Err(TimingError::Rate));
        assert_eq!(DriveTiming::new(200_001, 1, 0), Err(TimingError::Rate));
        assert_eq!(DriveTiming::new(1000, 0, 5), Err(TimingError::Pulse));
        assert_eq!(DriveTiming::new(1000, 1001, 5), Err(TimingError::Pulse));
        assert_eq!(DriveTiming::new(1000, 5, 1001), Err(TimingError::Setup));
        assert_eq!(
            DriveTiming::new(1000, 1000, 0),
            Err(TimingError::PulseTooLong)
        );
        assert!(DriveTiming::new(1001, 999, 0).is_ok());
        assert!(DriveTiming::new(200_000, 4, 1000).is_ok());
    }
}

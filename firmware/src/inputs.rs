//! The machine's switches on the board (`docs/inputs.md`): sampled once a
//! millisecond, filtered ([`core_nostd::inputs::Filter`]), and a stopping
//! input (the E-stop, a limit, a drive's fault) acted on in the sampling
//! interrupt itself: the STEP outputs and the spindle and coolant go low
//! and the step interrupt is masked before anything else runs. The
//! real-time task then drops the motion as a reset does
//! ([`crate::motion`]), and thread mode tells the session, which locks.
//!
//! It uses the board only; the real-time task takes its stop
//! ([`take_stop`]), thread mode its changes ([`take_changed`]).
//!
//! The sampler runs at the supervisor's priority, above the step
//! interrupt. On the board the supervisor pends it every 1 ms, and an edge
//! on a stopping switch (the E-stop, a limit) pends it at once when no
//! filter is set ([`edge`]); under QEMU, which has no GPIO, every sample
//! comes from the test harness over USART2 ([`crate::board::Panel`]),
//! which raises a stopping switch's edge interrupt as the pin would.

use crate::board;
use core::sync::atomic::{AtomicBool, AtomicI32, AtomicU16, AtomicU8, Ordering};
use core_nostd::inputs::{Filter, Input, InputConfig, FAULTS, LIMITS};
use stm32f4::stm32f405::{Interrupt, NVIC};

/// The wiring thread mode last set: the inputs used, those inverted, the
/// filter.
static USED: AtomicU16 = AtomicU16::new(0);
static INVERT: AtomicU16 = AtomicU16::new(0);
static FILTER: AtomicU8 = AtomicU8::new(0);
/// The active inputs, filtered.
static ACTIVE: AtomicU16 = AtomicU16::new(0);
/// A stopping input acted; the real-time task has not yet dropped the
/// motion.
static STOPPED: AtomicBool = AtomicBool::new(false);
/// The filtered inputs changed since thread mode last looked.
static CHANGED: AtomicBool = AtomicBool::new(false);
/// The door opened or the hold button was pressed; cycle start was
/// pressed with the door closed: for the real-time task, as the bytes
/// 0x82 and 0x81 are.
static HOLD: AtomicBool = AtomicBool::new(false);
static RESUME: AtomicBool = AtomicBool::new(false);
/// A probing move is armed: 0 not, [`PROBE_TOUCH`] it stops where the
/// probe becomes active, [`PROBE_LEAVE`] where it becomes inactive.
static PROBE: AtomicU8 = AtomicU8::new(0);
const PROBE_TOUCH: u8 = 1;
const PROBE_LEAVE: u8 = 2;

/// The handwheel's edges counted and not yet taken by thread mode.
static WHEEL: AtomicI32 = AtomicI32::new(0);
/// The edges thread mode took short of a whole detent (thread mode only).
static WHEEL_PART: AtomicI32 = AtomicI32::new(0);

/// The inputs that stop everything at once.
const STOPS: u16 = Input::Estop.bit() | LIMITS | FAULTS;

/// Sets the wiring the sampler reads with (thread mode, after a request).
pub fn set_wiring(cfg: InputConfig) {
    USED.store(cfg.used, Ordering::Relaxed);
    INVERT.store(cfg.invert, Ordering::Relaxed);
    FILTER.store(cfg.filter, Ordering::Relaxed);
}

/// Arms the probe's stop for a probing move (`Some(touch)`), or disarms
/// it (thread mode).
pub fn arm_probe(stop_on: Option<bool>) {
    let v = match stop_on {
        None => 0,
        Some(true) => PROBE_TOUCH,
        Some(false) => PROBE_LEAVE,
    };
    PROBE.store(v, Ordering::Release);
}

fn wiring() -> InputConfig {
    InputConfig {
        used: USED.load(Ordering::Relaxed),
        invert: INVERT.load(Ordering::Relaxed),
        filter: FILTER.load(Ordering::Relaxed),
    }
}

/// The active inputs, filtered.
pub fn active() -> u16 {
    ACTIVE.load(Ordering::Acquire)
}

/// Whether the inputs changed since thread mode last looked (taken: it
/// tells the session).
pub fn take_changed() -> bool {
    CHANGED.swap(false, Ordering::AcqRel)
}

/// Whether the inputs changed and thread mode has not looked.
pub fn changed() -> bool {
    CHANGED.load(Ordering::Acquire)
}

/// The handwheel's whole detents turned since thread mode last took them
/// (signed), or `None` if none; a part of a detent waits for the rest.
pub fn take_wheel() -> Option<i32> {
    let edges = WHEEL.swap(0, Ordering::AcqRel);
    if edges == 0 {
        return None;
    }
    let all = WHEEL_PART.load(Ordering::Relaxed).saturating_add(edges);
    WHEEL_PART.store(all.rem_euclid(4), Ordering::Relaxed);
    let detents = all.div_euclid(4);
    (detents != 0).then_some(detents)
}

/// Whether the door or the hold button asks for a feed hold (taken).
pub fn take_hold() -> bool {
    HOLD.swap(false, Ordering::AcqRel)
}

/// Whether cycle start asks to resume (taken).
pub fn take_resume() -> bool {
    RESUME.swap(false, Ordering::AcqRel)
}

/// Whether the guard door is open: nothing resumes meanwhile.
pub fn door_open() -> bool {
    active() & Input::Door.bit() != 0
}

/// Whether a stopping input acted and the motion is still to be dropped
/// (taken: the real-time task drops it).
pub fn take_stop() -> bool {
    STOPPED.swap(false, Ordering::AcqRel)
}

/// Whether the inputs are filtered (a filter of 1 ms or more is set).
pub fn filtered() -> bool {
    FILTER.load(Ordering::Relaxed) != 0
}

/// An edge on a stopping switch (its EXTI interrupt, at the sampler's
/// priority): with no filter the pins are sampled at once (the sampler
/// pended, tail-chained after this); with one, the millisecond's samples
/// wait it out as before. The lines stay masked until the next
/// millisecond.
#[inline(always)]
pub fn edge() {
    board::edges_take();
    if !filtered() {
        NVIC::pend(board::SAMPLER_IRQ);
    }
}

/// The sampler's state: the filter, the wheel's counter as last read.
pub struct Sampler {
    filter: Filter,
    wheel_at: u16,
}

impl Default for Sampler {
    fn default() -> Self {
        Self::new()
    }
}

impl Sampler {
    /// Every input inactive.
    pub const fn new() -> Sampler {
        Sampler {
            filter: Filter::new(),
            wheel_at: 0,
        }
    }

    /// One sample of the pins (the sampling interrupt).
    #[inline(always)]
    pub fn sample(&mut self) {
        self.wheel(board::wheel_edges());
        self.sample_pins(board::input_pins());
    }

    /// The wheel's counter read (`edges`, modulo 2¹⁶): what it counted
    /// since the last sample goes to thread mode. A millisecond holds far
    /// fewer than 2¹⁵ edges of any hand-turned wheel.
    #[inline(always)]
    pub fn wheel(&mut self, edges: u16) {
        let by = edges.wrapping_sub(self.wheel_at) as i16;
        if by != 0 {
            self.wheel_at = edges;
            WHEEL.fetch_add(i32::from(by), Ordering::AcqRel);
        }
    }

    /// One sample of `pins` (bit set: the pin reads high): a stopping input
    /// that becomes active stops the outputs here and now; any change is
    /// handed to the real-time task and thread mode. Returns the inputs
    /// that changed.
    #[inline(always)]
    pub fn sample_pins(&mut self, pins: u16) -> u16 {
        let changed = self.filter.sample(&wiring(), pins);
        if changed == 0 {
            return 0;
        }
        let active = self.filter.state();
        let rose = changed & active;
        if rose & STOPS != 0 {
            stop_now();
        } else if changed & Input::Probe.bit() != 0 {
            // A probing move stops where the probe changes as it is armed
            // to, the spindle left turning.
            let touch = rose & Input::Probe.bit() != 0;
            let armed = PROBE.load(Ordering::Acquire);
            if (armed == PROBE_TOUCH && touch) || (armed == PROBE_LEAVE && !touch) {
                PROBE.store(0, Ordering::Release);
                stop_steps();
            }
        }
        ACTIVE.store(active, Ordering::Release);
        CHANGED.store(true, Ordering::Release);
        // The door and the buttons act as their bytes do, in the
        // real-time task.
        if rose & (Input::Door.bit() | Input::Hold.bit()) != 0 {
            HOLD.store(true, Ordering::Release);
            NVIC::pend(board::REALTIME_IRQ);
        } else if rose & Input::Start.bit() != 0 && active & Input::Door.bit() == 0 {
            RESUME.store(true, Ordering::Release);
            NVIC::pend(board::REALTIME_IRQ);
        }
        changed
    }
}

/// The outputs low, the step interrupt masked, the real-time task pended
/// to drop the motion.
#[inline(always)]
fn stop_now() {
    board::spindle::all_low();
    stop_steps();
}

/// The STEP outputs low, the step interrupt masked, the real-time task
/// pended to drop the motion.
#[inline(always)]
fn stop_steps() {
    board::step_outputs_low();
    NVIC::mask(Interrupt::TIM5);
    STOPPED.store(true, Ordering::Release);
    NVIC::pend(board::REALTIME_IRQ);
}

/// After the real-time task has stopped the step interrupt and dropped its
/// queue: it runs again for the next motion.
pub fn unmask_step() {
    // SAFETY: the step interrupt shares only RTIC resources and atomics,
    // its priority set by the scheduler at start; masking it was ours.
    unsafe { NVIC::unmask(Interrupt::TIM5) };
}

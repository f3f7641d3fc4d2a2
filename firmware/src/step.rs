//! The step interrupt: it takes the ready entries the prep put in the
//! queue and issues each step on its tick of TIM2; nothing else.
//!
//! Per step: the alarm (TIM5) fires one tick before the event (more when
//! the event's DIR changes: the drive's set-up time); the interrupt writes
//! the STEP lines low with the event's DIR lines in one write, waits for
//! the tick, raises the STEP lines, starts the pulse's end on SysTick
//! ([`pulse_end`]), notes how late it was, and arms the alarm for the
//! next entry, which it takes from the queue now. Marks (a run's start, a
//! block's start, a run's end) are passed on the way. No division, no
//! square root, no lock: the entry carries its tick and bits, the prep
//! keeps what `SYNC` and `STATUS` need.
//!
//! Unpaced under QEMU (the `qemu` feature without `qemu-paced`) it issues
//! everything it finds at once: QEMU's timers cost host time per wake-up,
//! and the ticks are compared through `SYNC`, not measured.
//!
//! | | |
//! |---|---|
//! | priority | below the supervisor, above the prep |
//! | work per step | about 50 instructions (`host-sim qemu-bench`) |
//! | longest entry | a run's end with the step before it |

use crate::board::spindle::Spindle;
use crate::board::{pins, ticks, Alarm, Pulse, PACED, PULSE_TIMER};
use core::sync::atomic::{AtomicBool, Ordering};
use core_nostd::interleave::StepEvent;
use core_nostd::prep::{Ready, ReadyQueue, ReadyRx};
use core_nostd::stepdir::DriveTiming;

/// The step armed for, taken from the queue.
#[derive(Clone, Copy, Debug)]
struct Next {
    /// TIM2's count at its tick.
    due: u32,
    /// STEP lines low and its DIR lines, then its STEP lines high.
    fall_dir: u32,
    rise: u32,
    /// The step, for a reset that drops it.
    event: StepEvent,
}

/// What the step interrupt owns.
pub struct StepIsr {
    rx: ReadyRx<'static>,
    alarm: Alarm,
    pulse: Pulse,
    spindle: Spindle,
    /// TIM2's count at the run's tick 0.
    origin: u32,
    /// The step armed for (taken from the queue, not issued yet).
    next: Option<Next>,
    /// When the STEP pulse in progress may end (TIM2 count).
    pulse_end: u32,
    /// Pulse width and DIR set-up, ticks.
    width: u32,
    setup: u32,
    /// Steps issued after their tick since power-on, and the most late.
    late: u32,
    worst: u32,
    /// A reset stopped it: it takes nothing until the reset is handled.
    stopped: bool,
}

/// Entries the step interrupt takes between two pends of the prep.
const REFILL: u32 = 64;

/// The ready queue between the prep (producer) and the step interrupt.
pub static READY: ReadyQueue = ReadyQueue::new();

/// Whether the step interrupt has nothing armed and nothing to do: the
/// prep pends it when it puts entries in.
static IDLE: AtomicBool = AtomicBool::new(true);

/// Whether the step interrupt waits for entries (the prep then pends it).
#[inline(always)]
pub fn is_idle() -> bool {
    IDLE.load(Ordering::Acquire)
}

/// Has the prep task fill the queue (EXTI0 is its interrupt).
#[inline(always)]
pub fn pend_prep() {
    rtic::pend(stm32f4::stm32f405::Interrupt::EXTI0);
}

/// Has the step interrupt look at the queue now.
#[inline(always)]
pub fn wake() {
    IDLE.store(false, Ordering::Release);
    cortex_m::peripheral::NVIC::pend(stm32f4::stm32f405::Interrupt::TIM5);
}

/// SysTick's interrupt: on the board the STEP pulse's end (both STEP
/// lines low); under paced QEMU the step interrupt's alarm; in the
/// `stall-test` build the supervisor's clock.
#[inline(always)]
pub fn systick() {
    #[cfg(feature = "stall-test")]
    return rtic::pend(stm32f4::stm32f405::Interrupt::TIM3);
    #[cfg(all(feature = "qemu", not(feature = "stall-test")))]
    return crate::board::alarm_fired();
    #[cfg(not(feature = "qemu"))]
    {
        Pulse::stop();
        pins::write(pins::FALL);
    }
}

/// A ready step's pin words, by its bits.
const RISE: [u32; 16] = words(false);
const FALL_DIR: [u32; 16] = words(true);

const fn words(fall_dir: bool) -> [u32; 16] {
    let mut t = [0; 16];
    let mut b = 0;
    while b < 16 {
        t[b] = if fall_dir {
            pins::fall_dir(b as u8)
        } else {
            pins::rise(b as u8)
        };
        b += 1;
    }
    t
}

impl StepIsr {
    /// Takes the queue's consumer end, the two timers and the spindle
    /// outputs; STEP lines low.
    pub fn new(rx: ReadyRx<'static>, alarm: Alarm, pulse: Pulse, spindle: Spindle) -> StepIsr {
        pins::write(pins::FALL);
        let mut s = StepIsr {
            rx,
            alarm,
            pulse,
            spindle,
            origin: 0,
            next: None,
            pulse_end: ticks(),
            width: 0,
            setup: 0,
            late: 0,
            worst: 0,
            stopped: false,
        };
        s.set_drive(&DriveTiming::DEFAULT);
        s
    }

    /// The drive's timing, at rest.
    pub fn set_drive(&mut self, drive: &DriveTiming) {
        // The count ticks at 1 µs: one more makes the width whole.
        self.width = drive.pulse_us() + 1;
        self.setup = drive.setup_us();
        self.pulse.set_width(self.width);
    }

    /// Answers the alarm, or a pend: issues what is due, passes the marks
    /// on the way, and arms the alarm for the next step, or goes idle.
    #[inline(always)]
    pub fn service(&mut self) {
        self.alarm.clear();
        if self.stopped {
            return;
        }
        loop {
            if let Some(n) = self.next {
                if PACED && (n.due.wrapping_sub(ticks()) as i32) > 1 {
                    // Early (an alarm longer than the longest): again.
                    self.arm(n.due.wrapping_sub(1));
                    return;
                }
                self.issue(n);
            }
            let Some(r) = self.rx.peek() else {
                self.next = None;
                if !PULSE_TIMER {
                    // No timer ends it: the pulse ends here, its width
                    // first.
                    if PACED {
                        while (ticks().wrapping_sub(self.pulse_end) as i32) < 0 {}
                    }
                    pins::write(pins::FALL);
                }
                IDLE.store(true, Ordering::Release);
                pend_prep();
                return;
            };
            self.rx.pop();
            // The prep refills every 64 entries taken.
            if self.rx.taken() % REFILL == 0 {
                pend_prep();
            }
            #[cfg(feature = "stall-test")]
            stall::maybe();
            match r {
                Ready::Step { tick, event, turns } => {
                    let due = self.origin.wrapping_add(tick);
                    let bits = event.bits() as usize & 15;
                    let n = Next {
                        due,
                        fall_dir: FALL_DIR[bits],
                        rise: RISE[bits],
                        event,
                    };
                    self.next = Some(n);
                    if PACED {
                        // One tick ahead, and the set-up time when DIR
                        // changes, but not before the pulse has ended.
                        let lead = if turns { self.setup + 1 } else { 1 };
                        let mut at = due.wrapping_sub(lead);
                        if (at.wrapping_sub(self.pulse_end) as i32) < 0 {
                            at = self.pulse_end;
                        }
                        if (at.wrapping_sub(ticks()) as i32) > 0 {
                            self.arm(at);
                            return;
                        }
                    }
                }
                Ready::RunStart => self.origin = ticks(),
                Ready::Block { rpm } => self.spindle.follow(rpm),
                Ready::RunEnd => {
                    // The last pulse ends (its width first).
                    if PACED {
                        while (ticks().wrapping_sub(self.pulse_end) as i32) < 0 {}
                    }
                    Pulse::stop();
                    pins::write(pins::FALL);
                }
            }
        }
    }

    /// Arms the alarm for TIM2's count `at`.
    #[inline(always)]
    fn arm(&mut self, at: u32) {
        self.alarm.arm(at.wrapping_sub(ticks()));
    }

    /// Issues the step armed for: the pulse before ends with this step's
    /// DIR set, the STEP lines rise on the tick, the pulse's end starts.
    #[inline(always)]
    fn issue(&mut self, n: Next) {
        pins::write(n.fall_dir);
        if PACED {
            while (ticks().wrapping_sub(n.due) as i32) < 0 {}
        }
        pins::write(n.rise);
        let rose = ticks();
        if PACED {
            if PULSE_TIMER {
                self.pulse.arm();
            }
            self.pulse_end = rose.wrapping_add(self.width);
            let late = rose.wrapping_sub(n.due);
            if late != 0 {
                self.late = self.late.wrapping_add(1);
                if late > self.worst {
                    self.worst = late;
                }
            }
        } else {
            pins::write(pins::FALL);
        }
        self.next = None;
    }

    /// Reset: outputs low at once, the alarm and the pulse stopped; it
    /// takes nothing until [`StepIsr::drop_queued`] and
    /// [`StepIsr::restart`].
    pub fn stop(&mut self) {
        self.stopped = true;
        self.alarm.stop();
        Pulse::stop();
        pins::write(pins::FALL);
        self.spindle.off();
    }

    /// After [`StepIsr::stop`]: the entries it had passed, and every
    /// entry not issued (the step armed for first), taken from the queue
    /// as the iterator goes.
    pub fn drop_queued(&mut self) -> (u32, impl Iterator<Item = Ready> + '_) {
        let passed = self.passed();
        let armed = self.next.take().map(|n| Ready::Step {
            tick: n.due.wrapping_sub(self.origin),
            event: n.event,
            turns: false,
        });
        let rx = &mut self.rx;
        (
            passed,
            armed
                .into_iter()
                .chain(core::iter::from_fn(move || rx.dequeue())),
        )
    }

    /// Takes entries again (a reset has been handled).
    pub fn restart(&mut self) {
        self.stopped = false;
        IDLE.store(true, Ordering::Release);
    }

    /// Entries passed: those taken from the queue, less the step armed
    /// for (not issued yet).
    pub fn passed(&self) -> u32 {
        self.rx.taken().wrapping_sub(u32::from(self.next.is_some()))
    }

    /// Whether it issues or waits to issue anything: entries queued, a
    /// step armed for.
    pub fn busy(&self) -> bool {
        self.next.is_some() || !self.rx.is_empty()
    }

    /// Steps issued after their tick since power-on, and the most late
    /// (ticks).
    pub fn lateness(&self) -> (u32, u32) {
        (self.late, self.worst)
    }

    /// The spindle and coolant outputs.
    pub fn spindle(&mut self) -> &mut Spindle {
        &mut self.spindle
    }
}

/// The supervisor's test: the step interrupt stalls at its 100th entry
/// (a busy loop, as a hung driver or a bug would leave it) and the
/// supervisor, above it, must stop the outputs; it reports when over
/// semihosting and ends QEMU.
#[cfg(feature = "stall-test")]
pub mod stall {
    use core::sync::atomic::{AtomicU32, Ordering};

    static ENTRIES: AtomicU32 = AtomicU32::new(0);
    static STALLED_AT: AtomicU32 = AtomicU32::new(0);

    /// Counts an entry; at the 100th, a step high, stalls for good.
    pub fn maybe() {
        if ENTRIES.fetch_add(1, Ordering::Relaxed) == 100 {
            crate::board::pins::write(super::RISE[0b11]);
            STALLED_AT.store(crate::board::ticks(), Ordering::Release);
            loop {
                core::hint::spin_loop();
            }
        }
    }

    /// The supervisor stopped the outputs for `why`: when, against the
    /// stall, and the STEP lines as they are; QEMU exits.
    pub fn report(why: core_nostd::watch::Verdict) {
        let now = crate::board::ticks();
        let at = STALLED_AT.load(Ordering::Acquire);
        // SAFETY: a read of GPIOC's output data register.
        let odr = unsafe { (*stm32f4::stm32f405::GPIOC::ptr()).odr().read().bits() };
        let mut line: heapless::String<160> = heapless::String::new();
        let _ = core::fmt::write(
            &mut line,
            format_args!(
                "supervisor: {why:?}; stalled at {at} us, outputs low at {now} us: {} us after; STEP lines {}\n",
                now.wrapping_sub(at),
                if odr & 0b101 == 0 { "low" } else { "HIGH" }
            ),
        );
        crate::log::host_print(&line);
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    }
}

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
//! | work per step | about 105 instructions (`host-sim qemu-bench`) |
//! | longest entry | a run's end with the step before it |

use crate::board::spindle::Spindle;
use crate::board::{pins, ticks, Alarm, Pulse, PACED, PULSE_TIMER};
use core::sync::atomic::{AtomicBool, Ordering};
use core_nostd::prep::{Ready, ReadyQueue, ReadyRx};
use core_nostd::stepdir::DriveTiming;

/// What the step interrupt owns.
pub struct StepIsr {
    rx: ReadyRx<'static>,
    alarm: Alarm,
    pulse: Pulse,
    spindle: Spindle,
    /// TIM2's count at the run's tick 0.
    origin: u32,
    /// A step is armed for (taken from the queue, not issued yet): TIM2's
    /// count at its tick, the STEP lines low with its DIR lines, its STEP
    /// lines high, and its entry's bits.
    armed: bool,
    due: u32,
    fall_dir: u32,
    rise: u32,
    /// Ticks ahead of a step whose DIR changes: the set-up time and one.
    lead_turn: u32,
    /// When the STEP pulse in progress may end (TIM2 count).
    pulse_end: u32,
    /// Pulse width, ticks.
    width: u32,
    /// Steps issued after their tick since power-on, and the most late.
    late: u32,
    worst: u32,
}

/// Entries the step interrupt takes between two pends of the prep.
const REFILL: u32 = 64;

/// The longest the step interrupt waits for a step's tick, ticks: the
/// DIR set-up time fits well within it; an alarm that comes earlier than
/// this (QEMU's) is armed again instead.
const SPIN_MAX: i32 = 64;

/// A step armed for this many ticks past its tick, with no alarm or
/// interrupt pending, was lost (under QEMU: [`StepIsr::overdue`]).
#[cfg(feature = "qemu")]
const OVERDUE: i32 = 50_000;

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

/// Has the prep task fill the queue (its interrupt: [`crate::board::PREP_IRQ`]).
#[inline(always)]
pub fn pend_prep() {
    rtic::pend(crate::board::PREP_IRQ);
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

/// A ready step's pin words by its bits: STEP lines low with its DIR
/// lines, then its STEP lines high.
const WORDS: [[u32; 2]; 16] = words();

const fn words() -> [[u32; 2]; 16] {
    let mut t = [[0; 2]; 16];
    let mut b = 0;
    while b < 16 {
        t[b] = [pins::fall_dir(b as u8), pins::rise(b as u8)];
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
            armed: false,
            due: 0,
            fall_dir: 0,
            rise: 0,
            lead_turn: 1,
            pulse_end: ticks(),
            width: 0,
            late: 0,
            worst: 0,
        };
        s.set_drive(&DriveTiming::DEFAULT);
        s
    }

    /// The drive's timing, at rest.
    pub fn set_drive(&mut self, drive: &DriveTiming) {
        // The count ticks at 1 µs: one more makes the width whole.
        self.width = drive.pulse_us() + 1;
        self.lead_turn = drive.setup_us() + 1;
        self.pulse.set_width(self.width);
    }

    /// Answers the alarm, or a pend: issues the step armed for when it is
    /// due, passes the marks that follow, and arms the alarm for the next
    /// step, or goes idle. One function, which the measurements call as
    /// the interrupt does.
    #[inline(never)]
    pub fn service(&mut self) {
        self.alarm.clear();
        // TIM2's count, read once a step: when the last step rose (or
        // when a mark was passed).
        let mut now = if self.armed {
            match self.issue() {
                Some(rose) => rose,
                None => return,
            }
        } else {
            ticks()
        };
        loop {
            let Some((w0, w1, taken)) = self.rx.take_words() else {
                self.idle();
                return;
            };
            // The prep refills every 64 entries taken.
            if taken % REFILL == 0 {
                pend_prep();
            }
            if w1 & Ready::KIND != 0 {
                self.mark(w0, w1);
                now = ticks();
                continue;
            }
            // A step: armed for, one tick ahead (and the set-up time when
            // its DIR changes), not before the pulse before has ended.
            let due = self.origin.wrapping_add(w0);
            let [fall_dir, rise] = WORDS[(w1 & Ready::BITS) as usize];
            (self.due, self.fall_dir, self.rise, self.armed) = (due, fall_dir, rise, true);
            if PACED {
                let lead = if w1 & Ready::TURNS != 0 {
                    self.lead_turn
                } else {
                    1
                };
                let mut at = due.wrapping_sub(lead);
                if (at.wrapping_sub(self.pulse_end) as i32) < 0 {
                    at = self.pulse_end;
                }
                if self.arm_at(at, now) {
                    return;
                }
                // Its alarm's time has passed already (the step interrupt
                // came late): the step goes now, after its DIR set-up time.
                if w1 & Ready::TURNS != 0 {
                    self.set_up_dir();
                }
            }
            now = match self.issue() {
                Some(rose) => rose,
                None => return,
            };
        }
    }

    /// A late step whose DIR changes: the DIR lines first, then the
    /// drive's set-up time before the STEP lines rise.
    #[cold]
    #[inline(never)]
    fn set_up_dir(&mut self) {
        pins::write(self.fall_dir);
        let ready = ticks().wrapping_add(self.lead_turn);
        while (ticks().wrapping_sub(ready) as i32) < 0 {}
    }

    /// Arms the alarm for TIM2's count `at`, unless it has come by `now`
    /// (read a little before: the alarm then fires a little after `at`,
    /// still ahead of the step); whether it armed. A wait beyond the
    /// alarm's longest fires early, at its longest: [`StepIsr::issue`]
    /// arms it again.
    #[inline(always)]
    fn arm_at(&mut self, at: u32, now: u32) -> bool {
        let wait = at.wrapping_sub(now) as i32;
        if wait <= 0 {
            return false;
        }
        self.alarm.arm(wait as u32);
        true
    }

    /// Nothing left in the queue: the pulse ends if no timer ends it, the
    /// prep is asked for more.
    #[inline(never)]
    fn idle(&mut self) {
        if !PULSE_TIMER {
            // Its width first.
            if PACED {
                while (ticks().wrapping_sub(self.pulse_end) as i32) < 0 {}
            }
            pins::write(pins::FALL);
        }
        IDLE.store(true, Ordering::Release);
        pend_prep();
    }

    /// A mark: a run's start (its tick 0 now), a block's start (the
    /// spindle's speed), a run's end (the last pulse ends).
    #[inline(never)]
    fn mark(&mut self, w0: u32, w1: u32) {
        match Ready::from_parts(w0, w1) {
            Ready::RunStart => self.origin = ticks(),
            Ready::Block { rpm } => self.spindle.follow(rpm),
            Ready::RunEnd => {
                if PACED {
                    while (ticks().wrapping_sub(self.pulse_end) as i32) < 0 {}
                }
                Pulse::stop();
                pins::write(pins::FALL);
            }
            Ready::Step { .. } => {}
        }
    }

    /// Issues the step armed for: the pulse before ends with this step's
    /// DIR set, the STEP lines rise on its tick, the pulse's end starts.
    /// Returns TIM2's count as they rose; or `None` when the alarm came
    /// well ahead of the tick (QEMU's alarm fires early, a wait beyond the
    /// alarm's longest fires at its longest) and is armed again.
    #[inline(always)]
    fn issue(&mut self) -> Option<u32> {
        #[cfg(feature = "stall-test")]
        stall::maybe();
        let due = self.due;
        pins::write(self.fall_dir);
        if PACED {
            loop {
                let wait = due.wrapping_sub(ticks()) as i32;
                if wait <= 0 {
                    break;
                }
                if wait > SPIN_MAX {
                    self.rearm(due);
                    return None;
                }
            }
        }
        pins::write(self.rise);
        let rose = ticks();
        self.armed = false;
        if !PACED {
            pins::write(pins::FALL);
            return Some(rose);
        }
        if PULSE_TIMER {
            self.pulse.arm();
        }
        self.pulse_end = rose.wrapping_add(self.width);
        let late = rose.wrapping_sub(due);
        if late != 0 {
            self.late_by(late);
        }
        Some(rose)
    }

    /// The alarm came well ahead of the step armed for, due at `due`:
    /// armed again one tick ahead of it.
    #[cold]
    #[inline(never)]
    fn rearm(&mut self, due: u32) {
        let now = ticks();
        if !self.arm_at(due.wrapping_sub(1), now) {
            // The tick came meanwhile: at once.
            cortex_m::peripheral::NVIC::pend(stm32f4::stm32f405::Interrupt::TIM5);
        }
    }

    /// A step went `late` ticks after its tick.
    #[inline(never)]
    fn late_by(&mut self, late: u32) {
        self.late = self.late.wrapping_add(1);
        self.worst = self.worst.max(late);
    }

    /// Reset: outputs low at once, the alarm and the pulse stopped (the
    /// caller holds the prep, which puts nothing in meanwhile); then
    /// [`StepIsr::drop_queued`] and [`StepIsr::restart`].
    pub fn stop(&mut self) {
        self.armed = false;
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
        // Counted as a dropped step (its bits do not matter there).
        let armed = self
            .armed
            .then(|| Ready::from_parts(self.due.wrapping_sub(self.origin), 0));
        self.armed = false;
        let rx = &mut self.rx;
        (
            passed,
            armed
                .into_iter()
                .chain(core::iter::from_fn(move || rx.dequeue())),
        )
    }

    /// Takes entries again (a reset has been handled): it waits for the
    /// prep's next.
    pub fn restart(&mut self) {
        IDLE.store(true, Ordering::Release);
    }

    /// Entries passed: those taken from the queue, less the step armed
    /// for (not issued yet).
    pub fn passed(&self) -> u32 {
        self.rx.taken().wrapping_sub(u32::from(self.armed))
    }

    /// Whether it issues or waits to issue anything: entries queued, a
    /// step armed for.
    pub fn busy(&self) -> bool {
        self.armed || !self.rx.is_empty()
    }

    /// TIM2's count at the step armed for, if one is.
    pub fn due(&self) -> Option<u32> {
        self.armed.then_some(self.due)
    }

    /// Under QEMU, from thread mode: a step armed for whose tick passed
    /// more than [`OVERDUE`] ticks ago while neither its alarm nor the
    /// interrupt is pending, that is an alarm the emulated timer lost. It
    /// is told on the host's log with the timer's registers and issued
    /// now (late, and counted so).
    ///
    /// And entries waiting while the step interrupt is idle and not
    /// pended, beyond a run's start that waits for its steps (a resume
    /// puts it before the prep has any): a wake-up lost. Told and woken.
    #[cfg(feature = "qemu")]
    pub fn overdue(&mut self, now: u32) -> bool {
        use cortex_m::peripheral::NVIC;
        use stm32f4::stm32f405::Interrupt;
        if NVIC::is_pending(Interrupt::TIM5) {
            return false;
        }
        if !self.armed {
            let waiting = self.rx.len();
            if !is_idle()
                || waiting == 0
                || (waiting == 1 && self.rx.peek() == Some(Ready::RunStart))
            {
                return false;
            }
            crate::log::host_print(format_args!(
                "step: wake-up lost: {waiting} entries at {now}\n"
            ));
            wake();
            return true;
        }
        if (now.wrapping_sub(self.due) as i32) <= OVERDUE {
            return false;
        }
        // SAFETY: reads of SysTick's and the SCB's registers.
        let (csr, cvr, rvr, icsr) = unsafe {
            let st = &*cortex_m::peripheral::SYST::PTR;
            let scb = &*cortex_m::peripheral::SCB::PTR;
            (st.csr.read(), st.cvr.read(), st.rvr.read(), scb.icsr.read())
        };
        // SysTick (the alarm) pending: it comes.
        if icsr & (1 << 26) != 0 {
            return false;
        }
        crate::log::host_print(format_args!(
            "step: alarm lost: due {} now {now} csr {csr:#x} cvr {cvr} rvr {rvr} icsr {icsr:#x}\n",
            self.due
        ));
        NVIC::pend(Interrupt::TIM5);
        true
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

/// The supervisor's test: the step interrupt stalls at its 100th step
/// (a busy loop with the STEP lines high, as a hung driver or a bug would
/// leave it) and the supervisor, above it, must stop the outputs; it
/// reports when over semihosting and ends QEMU.
#[cfg(feature = "stall-test")]
pub mod stall {
    use core::sync::atomic::{AtomicU32, Ordering};

    static ENTRIES: AtomicU32 = AtomicU32::new(0);
    static STALLED_AT: AtomicU32 = AtomicU32::new(0);

    /// Counts a step; at the 100th, the STEP lines high, stalls for good.
    pub fn maybe() {
        if ENTRIES.fetch_add(1, Ordering::Relaxed) == 100 {
            crate::board::pins::write(crate::board::pins::rise(0b11));
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
        crate::log::host_print(format_args!(
            "supervisor: {why:?}; stalled at {at} us, outputs low at {now} us: {} us after; STEP lines {}\n",
            now.wrapping_sub(at),
            if odr & 0b101 == 0 { "low" } else { "HIGH" }
        ));
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    }
}

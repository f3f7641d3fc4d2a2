//! The step interrupt: it issues the events of the shared stepper on the
//! STEP/DIR outputs at their ticks of TIM2, woken by TIM5 a little before
//! each, while the protocol runs in thread mode and queues what follows.
//!
//! Thread mode hands started motion over with [`start`], which waits while
//! the stepper is full: that wait is the flow control a streaming host
//! sees (its request is answered once the motion is taken). The stepper,
//! the outputs and the clocks live in one [`Mutex`]; thread mode holds it
//! only to hand over or read, the interrupt while it issues.
//!
//! Under QEMU (the `qemu` feature without `qemu-paced`) the interrupt is
//! pended at once and issues everything it holds without waiting for the
//! ticks: QEMU's timers cost host time per wake-up, and the ticks are
//! compared through `SYNC`, not measured.

#[cfg(not(feature = "qemu-paced"))]
use crate::board::TIM2_CLK_HZ;
use crate::board::{sleep_unless, CycleDelay, PortCPin, StepTimer};
use crate::spindle::Spindle;
use crate::supervisor;
use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicU8, Ordering};
use core_nostd::interleave::{ImpulsePoint, StepEvent};
use core_nostd::protocol::Realtime;
use core_nostd::step::Record;
#[cfg(not(feature = "qemu-paced"))]
use core_nostd::step::TickRate;
use core_nostd::stepdir::{DriveTiming, StepDir, TickClock};
use core_nostd::stepper::{Aborted, Item, Motion as State, Pulled, Stepper, AHEAD};
use critical_section::Mutex;
use stm32f4::stm32f405::{self as pac, interrupt, Interrupt};

/// Whether events wait for their ticks (always on the board).
const PACED: bool = cfg!(any(not(feature = "qemu"), feature = "qemu-paced"));

/// Ticks the alarm fires before an event, beyond the DIR set-up time: the
/// interrupt's entry and its own work. It then waits for the tick itself.
const LEAD: u64 = 3;

type Axes = StepDir<PortCPin, PortCPin, PortCPin, PortCPin>;

/// TIM5 as a one-shot alarm in ticks.
#[cfg(not(feature = "qemu-paced"))]
struct Alarm {
    tim: pac::TIM5,
}

#[cfg(not(feature = "qemu-paced"))]
impl Alarm {
    fn new(tim: pac::TIM5, _: &StepTimer) -> Alarm {
        let psc = TIM2_CLK_HZ / TickRate::TIMER.hz() - 1;
        tim.cr1().write(|w| w.urs().set_bit().opm().set_bit());
        tim.psc().write(|w| unsafe { w.bits(psc) });
        // Load the prescaler without an interrupt (URS).
        tim.egr().write(|w| w.ug().set_bit());
        tim.sr().write(|w| unsafe { w.bits(0) });
        tim.dier().write(|w| w.uie().set_bit());
        Alarm { tim }
    }

    /// Fires in `ticks` (at least 1).
    fn arm(&mut self, ticks: u64) {
        let t = ticks.clamp(1, 1 << 31) as u32;
        self.tim.cnt().write(|w| unsafe { w.bits(0) });
        self.tim.arr().write(|w| unsafe { w.bits(t) });
        self.tim.cr1().modify(|_, w| w.cen().set_bit());
    }

    fn stop(&mut self) {
        self.tim.cr1().modify(|_, w| w.cen().clear_bit());
        self.tim.sr().write(|w| unsafe { w.bits(0) });
    }
}

/// Under paced QEMU the alarm is SysTick, which pends the step interrupt:
/// QEMU 7.2's STM32 timer schedules its update at the current time plus
/// the absolute time of the hit, so a TIM5 alarm armed `t` after boot
/// fires about `t` late. TIM2's counter reads are right and still time the
/// events.
#[cfg(feature = "qemu-paced")]
struct Alarm {
    syst: cortex_m::peripheral::SYST,
    /// SysTick counts (core cycles) per tick, measured against TIM2.
    per_tick: u32,
}

#[cfg(feature = "qemu-paced")]
impl Alarm {
    fn new(tim5: pac::TIM5, clock: &StepTimer) -> Alarm {
        // TIM5 stays unused: its update is what QEMU schedules wrongly.
        let _ = tim5;
        // SAFETY: SysTick is used by nothing else in this firmware.
        let mut syst = unsafe { cortex_m::Peripherals::steal() }.SYST;
        syst.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        // Core cycles in 1000 ticks of TIM2.
        let t0 = clock.count();
        let v0 = cortex_m::peripheral::SYST::get_current();
        while clock.count().wrapping_sub(t0) < 1000 {}
        let v1 = cortex_m::peripheral::SYST::get_current();
        let cycles = v0.wrapping_sub(v1) & 0x00FF_FFFF;
        syst.disable_counter();
        Alarm {
            syst,
            per_tick: (cycles / 1000).max(1),
        }
    }

    fn arm(&mut self, ticks: u64) {
        let cycles = ticks
            .saturating_mul(u64::from(self.per_tick))
            .clamp(1, 0x00FF_FFFF);
        self.syst.set_reload(cycles as u32);
        self.syst.clear_current();
        self.syst.enable_interrupt();
        self.syst.enable_counter();
    }

    fn stop(&mut self) {
        self.syst.disable_interrupt();
        self.syst.disable_counter();
    }
}

#[cfg(feature = "qemu-paced")]
#[cortex_m_rt::exception]
fn SysTick() {
    // SAFETY: the alarm's own registers; the step interrupt re-arms it.
    let syst = unsafe { &*cortex_m::peripheral::SYST::PTR };
    unsafe { syst.csr.modify(|c| c & !0b11) };
    pac::NVIC::pend(Interrupt::TIM5);
}

/// What the interrupt owns.
struct Motion {
    stepper: Stepper<AHEAD>,
    axes: Axes,
    clock: StepTimer,
    alarm: Alarm,
    drive: DriveTiming,
    /// The next event, waiting for its tick.
    next: Option<(StepEvent, u64)>,
    /// The interrupt has work: an event waiting or items to pull.
    busy: bool,
    /// What a reset found, until the protocol reports it.
    aborted: Option<Aborted>,
    /// Events issued after their tick since power-on.
    late: u32,
    /// The TIM2 count at which the STEP pulse in progress may end.
    pulse_end: Option<u32>,
    /// The spindle and coolant outputs.
    spindle: Spindle,
}

/// A reset dropped the motion; what the protocol still hands over is
/// dropped too until it has handled the reset.
static ABORTING: AtomicBool = AtomicBool::new(false);

/// Real-time requests for thread mode: a status line (also after a hold or
/// a resume), and the protocol's part of a reset.
static WANTED: AtomicU8 = AtomicU8::new(0);
const WANT_STATUS: u8 = 1;
const WANT_RESET: u8 = 2;
/// When the byte a wanted status line answers arrived (TIM2 count).
static STATUS_ASKED: AtomicU32 = AtomicU32::new(0);
/// Cycle start (0x81) came since a program stop began waiting.
static CYCLE_START: AtomicBool = AtomicBool::new(false);

// The state itself lives in `.bss` (`singleton!`); an empty reference is
// all-zero, so this static adds no `.data` image to flash.
static MOTION: Mutex<RefCell<Option<&'static mut Motion>>> = Mutex::new(RefCell::new(None));

impl Motion {
    /// The registers of the steps issued: the stepper counts an event when
    /// it hands it out, and the one waiting for its tick is not issued yet.
    fn issued(&self) -> ImpulsePoint {
        let mut p = self.stepper.issued();
        if let Some((e, _)) = self.next {
            let (dx, dz) = e.moves();
            p.x.0 -= i32::from(dx);
            p.z.0 -= i32::from(dz);
        }
        p
    }

    /// Reset: outputs low, the motion dropped, the event waiting for its
    /// tick never issued (nor counted in the registers, nor in what `SYNC`
    /// reports); what was running.
    fn abort(&mut self) -> Aborted {
        let mut found = self.stepper.abort();
        if let Some((e, _)) = self.next.take() {
            found.done = found.done.saturating_sub(1);
            found.dropped = true;
            self.stepper.take_back(e);
        }
        self.alarm.stop();
        self.pulse_end = None;
        self.axes.stop_outputs();
        self.spindle.off();
        self.stepper.set_spindle(0);
        self.busy = false;
        supervisor::step_idle();
        found
    }

    /// Has the interrupt look at its work now, unless it already has work.
    fn wake(&mut self) {
        if !self.busy {
            self.busy = true;
            supervisor::step_due(self.clock.count());
            pac::NVIC::pend(Interrupt::TIM5);
        }
    }

    /// Ends the STEP pulse in progress, if any, once its width has passed
    /// (unpaced under QEMU at once).
    fn end_pulse(&mut self) {
        if let Some(end) = self.pulse_end.take() {
            if PACED {
                while (self.clock.count().wrapping_sub(end) as i32) < 0 {}
            }
            if self.axes.fall().is_err() {
                defmt::error!("step outputs failed");
            }
        }
    }

    /// Issues what is due, then arms the alarm for the next event or goes
    /// idle. A STEP pulse stays high while the next event is pulled, and
    /// ends before anything else touches the outputs.
    fn service(&mut self) {
        self.alarm.stop();
        loop {
            if let Some((event, tick)) = self.next {
                if PACED {
                    let now = self.clock.now();
                    let lead = u64::from(self.drive.setup_us()) + LEAD;
                    if now > tick {
                        self.late = self.late.wrapping_add(1);
                    }
                    if tick > now + lead {
                        self.end_pulse();
                        let wait = tick - now - lead;
                        self.alarm.arm(wait);
                        let wait = wait.min(i32::MAX as u64) as u32;
                        supervisor::step_due(self.clock.count().wrapping_add(wait));
                        return;
                    }
                }
                self.next = None;
                self.end_pulse();
                // Waits for the tick itself; a late one steps at once.
                if self
                    .axes
                    .rise(event, tick, &self.drive, &mut self.clock, &mut CycleDelay)
                    .is_err()
                {
                    defmt::error!("step outputs failed");
                }
                // The count ticks at 1 µs: one more makes the width whole.
                // The same reading moves the supervisor's deadline on.
                let rose = self.clock.count();
                supervisor::step_due(rose);
                self.pulse_end = Some(rose.wrapping_add(self.drive.pulse_us() + 1));
            }
            match self.stepper.pull() {
                None => {
                    self.end_pulse();
                    self.busy = false;
                    supervisor::step_idle();
                    return;
                }
                Some(Pulled::RunStart) => self.clock.start_run(),
                Some(Pulled::BlockStart(_)) => self.spindle.follow(self.stepper.spindle()),
                Some(Pulled::Step(event, tick)) => self.next = Some((event, tick)),
                Some(Pulled::RunEnd(_)) => {
                    self.end_pulse();
                    self.axes.stop_outputs();
                }
            }
        }
    }
}

/// Takes the step outputs, the run clock and the alarm, and enables the
/// step interrupt above the serial one.
pub fn install(clock: StepTimer, alarm: pac::TIM5, spindle: Spindle) {
    let axes = StepDir::new(PortCPin(0), PortCPin(1), PortCPin(2), PortCPin(3));
    let alarm = Alarm::new(alarm, &clock);
    let motion = Motion {
        stepper: Stepper::new(),
        axes,
        clock,
        alarm,
        drive: DriveTiming::default(),
        next: None,
        busy: false,
        aborted: None,
        late: 0,
        pulse_end: None,
        spindle,
    };
    critical_section::with(|cs| {
        if let Ok(mut m) = MOTION.borrow(cs).try_borrow_mut() {
            *m = cortex_m::singleton!(: Motion = motion);
        }
    });
    // SAFETY: priorities are set before the interrupts are enabled; both
    // handlers share state only through critical sections.
    unsafe {
        let mut core = cortex_m::Peripherals::steal();
        core.NVIC.set_priority(Interrupt::TIM5, 0x10);
        core.NVIC.set_priority(Interrupt::USART1, 0x20);
        pac::NVIC::unmask(Interrupt::TIM5);
    }
}

/// Runs `f` on the motion state in a critical section (`None` before
/// [`install`]).
fn with<R>(f: impl FnOnce(&mut Motion) -> R) -> Option<R> {
    critical_section::with(|cs| {
        MOTION
            .borrow(cs)
            .try_borrow_mut()
            .ok()
            .and_then(|mut m| m.as_mut().map(|m| f(m)))
    })
}

/// Hands started motion to the step interrupt, waiting while it is full
/// (`wait` runs before each sleep); hands it back only before [`install`].
/// After a reset, until the protocol has handled it, the motion is dropped.
#[allow(clippy::result_large_err)] // the item itself
pub fn start(item: Item, drive: &DriveTiming, mut wait: impl FnMut()) -> Result<(), Item> {
    let mut item = Some(item);
    loop {
        if ABORTING.load(Ordering::Acquire) {
            return Ok(());
        }
        let taken = with(|m| {
            if !m.stepper.has_room() {
                return false;
            }
            if let Some(i) = item.take() {
                // Room was checked: the push succeeds.
                let _ = m.stepper.push(i);
            }
            m.drive = *drive;
            m.wake();
            true
        });
        match (taken, item.take()) {
            (Some(true), _) => return Ok(()),
            (None, Some(i)) => return Err(i),
            (_, i) => item = i,
        }
        wait();
        sleep_unless(|| wanted() || with(|m| m.stepper.has_room()).unwrap_or(true));
    }
}

/// Whether everything handed over has been issued (a hold keeps what it
/// stopped until a resume or a reset).
pub fn drained() -> bool {
    with(|m| !m.busy && !m.stepper.pending() && m.next.is_none()).unwrap_or(true)
}

/// Whether the step interrupt runs the last block started in an open run
/// and needs the next one now.
///
/// Unpaced under QEMU the interrupt issues everything at once: nothing is
/// ever late, and blocks start by the window alone, as on the virtual clock.
pub fn hungry() -> bool {
    PACED && with(|m| m.stepper.hungry()).unwrap_or(false)
}

/// What the axes are doing.
pub fn motion() -> State {
    with(|m| match m.stepper.motion() {
        State::Idle if m.next.is_some() => State::Run,
        a => a,
    })
    .unwrap_or(State::Idle)
}

/// A real-time byte, from the serial interrupt: hold, resume and reset act
/// on the step interrupt's state at once; every one asks thread mode for
/// its line, but a hold and a resume on a grbl link (`quiet`: grbl answers
/// neither).
pub fn realtime(rt: Realtime, quiet: bool) {
    act(rt);
    if rt == Realtime::Resume {
        CYCLE_START.store(true, Ordering::Release);
    }
    if quiet && matches!(rt, Realtime::Hold | Realtime::Resume) {
        return;
    }
    if rt == Realtime::Reset {
        WANTED.fetch_or(WANT_RESET, Ordering::AcqRel);
    } else {
        // The first byte of those one status line answers sets the time.
        if WANTED.load(Ordering::Acquire) & WANT_STATUS == 0 {
            STATUS_ASKED.store(crate::board::ticks(), Ordering::Relaxed);
        }
        WANTED.fetch_or(WANT_STATUS, Ordering::AcqRel);
    }
}

/// Acts on a real-time command: hold, resume, or reset (the outputs low, the
/// motion dropped, what was running kept for the protocol's report).
pub fn act(rt: Realtime) {
    match rt {
        Realtime::Status => {}
        Realtime::Hold => {
            with(|m| m.stepper.hold());
        }
        Realtime::Resume => {
            with(|m| {
                if let Some(Pulled::RunStart) = m.stepper.resume() {
                    m.clock.start_run();
                }
                if !m.stepper.is_idle() {
                    m.wake();
                }
            });
        }
        Realtime::Reset => {
            with(|m| m.aborted = Some(m.abort()));
            ABORTING.store(true, Ordering::Release);
        }
    }
}

/// Takes a wanted status line, if one is wanted: the TIM2 count at which
/// the byte arrived.
pub fn take_status() -> Option<u32> {
    let w = WANTED.fetch_and(!WANT_STATUS, Ordering::AcqRel);
    (w & WANT_STATUS != 0).then(|| STATUS_ASKED.load(Ordering::Relaxed))
}

/// Whether the protocol has a reset to handle (taken: the request is
/// cleared).
pub fn take_reset() -> bool {
    WANTED.fetch_and(!WANT_RESET, Ordering::AcqRel) & WANT_RESET != 0
}

/// Forgets a cycle start that came before a program stop began to wait.
pub fn clear_cycle_start() {
    CYCLE_START.store(false, Ordering::Release);
}

/// Whether a program stop's wait is over: cycle start came, or a reset.
pub fn stop_ended() -> bool {
    CYCLE_START.load(Ordering::Acquire) || WANTED.load(Ordering::Acquire) & WANT_RESET != 0
}

/// Whether a real-time request waits for thread mode.
pub fn wanted() -> bool {
    WANTED.load(Ordering::Acquire) != 0
}

/// The protocol's side of a reset: what the step interrupt found running
/// (the reset itself happened when the byte arrived; a reset that did not
/// come through the serial interrupt happens now).
pub fn abort() -> Option<Aborted> {
    let found = with(|m| m.aborted.take().unwrap_or_else(|| m.abort()));
    ABORTING.store(false, Ordering::Release);
    found
}

/// Step events issued after their tick since power-on: the step interrupt
/// found the clock past the event's tick when it came to issue it.
pub fn late_events() -> u32 {
    with(|m| m.late).unwrap_or(0)
}

/// The registers of the steps issued.
pub fn issued() -> Option<ImpulsePoint> {
    with(|m| m.issued())
}

/// What the spindle and coolant outputs command now.
pub fn outputs() -> Option<core_nostd::outputs::Outputs> {
    with(|m| m.spindle.outputs())
}

/// Switches the spindle and coolant outputs, at rest: the blocks that
/// start from now on change the speed only.
pub fn set_outputs(o: &core_nostd::outputs::Outputs) {
    with(|m| {
        m.stepper.set_spindle(o.rpm);
        m.spindle.set(o);
    });
}

/// Sets them, at rest.
pub fn set_issued(registers: ImpulsePoint) {
    with(|m| m.stepper.set_issued(registers));
}

/// What was recorded since the last call; the record starts again.
pub fn take_record() -> Option<Record> {
    with(|m| m.stepper.take_record())
}

#[interrupt]
fn TIM5() {
    with(Motion::service);
}

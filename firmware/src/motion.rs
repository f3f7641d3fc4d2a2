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

use crate::board::{sleep_unless, CycleDelay, PortCPin, StepTimer, TIM2_CLK_HZ};
use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use core_nostd::interleave::{ImpulsePoint, StepEvent};
use core_nostd::protocol::Realtime;
use core_nostd::step::{Record, TickRate};
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
struct Alarm {
    tim: pac::TIM5,
}

impl Alarm {
    fn new(tim: pac::TIM5) -> Alarm {
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
}

/// A reset dropped the motion; what the protocol still hands over is
/// dropped too until it has handled the reset.
static ABORTING: AtomicBool = AtomicBool::new(false);

/// Real-time requests for thread mode: a status line (also after a hold or
/// a resume), and the protocol's part of a reset.
static WANTED: AtomicU8 = AtomicU8::new(0);
const WANT_STATUS: u8 = 1;
const WANT_RESET: u8 = 2;

static MOTION: Mutex<RefCell<Option<Motion>>> = Mutex::new(RefCell::new(None));

impl Motion {
    /// Issues what is due, then arms the alarm for the next event or goes
    /// idle.
    fn service(&mut self) {
        self.alarm.stop();
        loop {
            if let Some((event, tick)) = self.next {
                if PACED {
                    let now = self.clock.now();
                    let lead = u64::from(self.drive.setup_us()) + LEAD;
                    if tick > now + lead {
                        self.alarm.arm(tick - now - lead);
                        return;
                    }
                }
                self.next = None;
                // Waits for the tick itself; a late one steps at once.
                if self
                    .axes
                    .issue(event, tick, &self.drive, &mut self.clock, &mut CycleDelay)
                    .is_err()
                {
                    defmt::error!("step outputs failed");
                }
            }
            match self.stepper.pull() {
                None => {
                    self.busy = false;
                    return;
                }
                Some(Pulled::RunStart) => self.clock.start_run(),
                Some(Pulled::BlockStart(_)) => {}
                Some(Pulled::Step(event, tick)) => self.next = Some((event, tick)),
                Some(Pulled::RunEnd(_)) => self.axes.stop_outputs(),
            }
        }
    }
}

/// Takes the step outputs, the run clock and the alarm, and enables the
/// step interrupt above the serial one.
pub fn install(clock: StepTimer, alarm: pac::TIM5) {
    let axes = StepDir::new(PortCPin(0), PortCPin(1), PortCPin(2), PortCPin(3));
    let motion = Motion {
        stepper: Stepper::new(),
        axes,
        clock,
        alarm: Alarm::new(alarm),
        drive: DriveTiming::default(),
        next: None,
        busy: false,
        aborted: None,
    };
    critical_section::with(|cs| {
        if let Ok(mut m) = MOTION.borrow(cs).try_borrow_mut() {
            *m = Some(motion);
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
            .and_then(|mut m| m.as_mut().map(f))
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
            if !m.busy {
                m.busy = true;
                pac::NVIC::pend(Interrupt::TIM5);
            }
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
    with(|m| !m.busy && m.stepper.is_idle() && m.next.is_none()).unwrap_or(true)
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
/// its line.
pub fn realtime(rt: Realtime) {
    act(rt);
    let want = if rt == Realtime::Reset {
        WANT_RESET
    } else {
        WANT_STATUS
    };
    WANTED.fetch_or(want, Ordering::AcqRel);
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
                if !m.stepper.is_idle() && !m.busy {
                    m.busy = true;
                    pac::NVIC::pend(Interrupt::TIM5);
                }
            });
        }
        Realtime::Reset => {
            with(|m| {
                let found = m.stepper.abort();
                // The event waiting for its tick was counted, never issued.
                if let Some((e, _)) = m.next.take() {
                    let (dx, dz) = e.moves();
                    let mut p = m.stepper.issued();
                    p.x.0 -= i32::from(dx);
                    p.z.0 -= i32::from(dz);
                    m.stepper.set_issued(p);
                }
                m.alarm.stop();
                m.axes.stop_outputs();
                m.busy = false;
                m.aborted = Some(found);
            });
            ABORTING.store(true, Ordering::Release);
        }
    }
}

/// Takes a wanted status line, if one is wanted.
pub fn take_status() -> bool {
    WANTED.fetch_and(!WANT_STATUS, Ordering::AcqRel) & WANT_STATUS != 0
}

/// The real-time request thread mode has to answer next, if any: a reset
/// before a status line.
pub fn take_wanted() -> Option<Realtime> {
    let w = WANTED.load(Ordering::Acquire);
    if w & WANT_RESET != 0 {
        WANTED.fetch_and(!WANT_RESET, Ordering::AcqRel);
        Some(Realtime::Reset)
    } else if w & WANT_STATUS != 0 {
        WANTED.fetch_and(!WANT_STATUS, Ordering::AcqRel);
        Some(Realtime::Status)
    } else {
        None
    }
}

/// Whether a real-time request waits for thread mode.
pub fn wanted() -> bool {
    WANTED.load(Ordering::Acquire) != 0
}

/// The protocol's side of a reset: what the step interrupt found running
/// (the reset itself happened when the byte arrived; a reset that did not
/// come through the serial interrupt happens now).
pub fn abort() -> Option<Aborted> {
    let found = with(|m| match m.aborted.take() {
        Some(found) => found,
        None => {
            let found = m.stepper.abort();
            m.next = None;
            m.alarm.stop();
            m.axes.stop_outputs();
            m.busy = false;
            found
        }
    });
    ABORTING.store(false, Ordering::Release);
    found
}

/// The registers of the steps issued (the stepper counts an event when
/// it hands it out; the one waiting for its tick is not issued yet).
pub fn issued() -> Option<ImpulsePoint> {
    with(|m| {
        let mut p = m.stepper.issued();
        if let Some((e, _)) = m.next {
            let (dx, dz) = e.moves();
            p.x.0 -= i32::from(dx);
            p.z.0 -= i32::from(dz);
        }
        p
    })
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

//! Motion between the protocol and the step interrupt: the prep stage's
//! task, the real-time task, and what thread mode does with both, all on
//! the two shared resources: [`PrepStage`] (the stepper, the queue's
//! producer end) and [`StepIsr`] (the step interrupt's state). Each
//! operation locks what it needs, the prep before the step interrupt when
//! it needs both; a lock raises the priority to the resource's ceiling
//! only, never masks the supervisor.
//!
//! | task | priority | what it does |
//! |---|---|---|
//! | prep | below the step interrupt | fills the ready queue ([`PrepStage::fill`]) |
//! | real-time | above thread mode | hold, resume, reset, status as bytes arrive ([`realtime`]) |
//!
//! Thread mode hands started motion over with [`start`], which waits while
//! the stepper is full: that wait is the flow control a streaming host
//! sees (its request is answered once the motion is taken).

use crate::board::{self, PACED};
use crate::step::{self, StepIsr};
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicU8, Ordering};
use core_nostd::interleave::ImpulsePoint;
use core_nostd::outputs::Outputs;
use core_nostd::prep::{Prep, ReadyTx};
use core_nostd::protocol::Realtime;
use core_nostd::step::Record;
use core_nostd::stepdir::DriveTiming;
use core_nostd::stepper::{Aborted, AxesState, Item};
use rtic::Mutex;

/// The prep stage: the stepper with what it has prepared, and the ready
/// queue's producer end.
pub struct PrepStage {
    prep: Prep,
    tx: ReadyTx<'static>,
    /// The drive timing the step interrupt has.
    drive: DriveTiming,
    /// What a reset found, until the protocol reports it.
    aborted: Option<Aborted>,
}

impl PrepStage {
    /// Takes the queue's producer end; nothing started.
    pub fn new(tx: ReadyTx<'static>) -> PrepStage {
        PrepStage {
            prep: Prep::new(),
            tx,
            drive: DriveTiming::DEFAULT,
            aborted: None,
        }
    }

    /// The prep task: fills the ready queue, and wakes the step interrupt
    /// if it waits for entries.
    #[inline(always)]
    pub fn fill(&mut self) {
        let added = self.prep.fill(&mut self.tx);
        if added > 0 && step::is_idle() {
            step::wake();
        }
    }

    /// The prep and the producer end (measurements).
    pub fn parts(&mut self) -> (&mut Prep, &mut ReadyTx<'static>) {
        (&mut self.prep, &mut self.tx)
    }
}

use step::pend_prep;

/// A real-time byte: what it asks, whether the link answers it (grbl
/// answers neither a hold nor a resume), and when it arrived (TIM2 count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RtEvent {
    /// What it asks.
    pub rt: Realtime,
    /// Whether no `!` line answers it.
    pub quiet: bool,
    /// When it arrived.
    pub at: u32,
}

/// A reset dropped the motion; what the protocol still hands over is
/// dropped too until it has handled the reset.
static ABORTING: AtomicBool = AtomicBool::new(false);

/// Real-time requests for thread mode: a status line (also after a hold or
/// a resume), and the protocol's part of a reset.
static WANTED: AtomicU8 = AtomicU8::new(0);
const WANT_STATUS: u8 = 1;
const WANT_RESET: u8 = 2;
/// An input stopped the motion and thread mode has not taken the report
/// yet ([`Shared::abort`]).
static INPUT_STOP: AtomicBool = AtomicBool::new(false);
/// When the byte a wanted status line answers arrived (TIM2 count).
static STATUS_ASKED: AtomicU32 = AtomicU32::new(0);
/// Cycle start (0x81) came since a program stop began waiting.
static CYCLE_START: AtomicBool = AtomicBool::new(false);

/// The real-time task: acts on each real-time byte in the order they
/// came (hold, resume, reset on the motion at once), then asks thread
/// mode for its line: every one, but a hold and a resume on a grbl link
/// (`quiet`: grbl answers neither). The switches' stop, hold and resume
/// come first; `grbl`: the link speaks grbl (no line for the buttons).
pub fn realtime(
    next: impl FnMut() -> Option<RtEvent>,
    grbl: bool,
    prep: &mut impl Mutex<T = PrepStage>,
    step: &mut impl Mutex<T = StepIsr>,
) {
    if crate::inputs::take_stop() {
        // A switch stopped the outputs and masked the step interrupt: the
        // motion dropped now, as a reset drops it, and the step interrupt
        // free again for what comes after.
        act(Realtime::Reset, prep, step);
        crate::inputs::unmask_step();
        INPUT_STOP.store(true, Ordering::Release);
    }
    // The door, the hold and cycle-start buttons: as their bytes, a
    // status line asked but on a grbl link.
    for (taken, rt) in [
        (crate::inputs::take_hold(), Realtime::Hold),
        (crate::inputs::take_resume(), Realtime::Resume),
    ] {
        if taken {
            act(rt, prep, step);
            if rt == Realtime::Resume {
                CYCLE_START.store(true, Ordering::Release);
            }
            if !grbl {
                WANTED.fetch_or(WANT_STATUS, Ordering::AcqRel);
            }
        }
    }
    let mut next = next;
    while let Some(e) = next() {
        act(e.rt, prep, step);
        if e.rt == Realtime::Resume {
            CYCLE_START.store(true, Ordering::Release);
        }
        if e.quiet && matches!(e.rt, Realtime::Hold | Realtime::Resume) {
            continue;
        }
        if e.rt == Realtime::Reset {
            WANTED.fetch_or(WANT_RESET, Ordering::AcqRel);
        } else {
            // The first byte of those one status line answers sets the time.
            if WANTED.load(Ordering::Acquire) & WANT_STATUS == 0 {
                STATUS_ASKED.store(e.at, Ordering::Relaxed);
            }
            WANTED.fetch_or(WANT_STATUS, Ordering::AcqRel);
        }
    }
}

/// Acts on a real-time command: hold, resume, or reset (the outputs low, the
/// motion dropped, what was running kept for the protocol's report).
pub fn act(rt: Realtime, prep: &mut impl Mutex<T = PrepStage>, step: &mut impl Mutex<T = StepIsr>) {
    match rt {
        Realtime::Status => {}
        Realtime::Hold => prep.lock(|p| p.prep.hold()),
        // Nothing resumes while the guard door is open.
        Realtime::Resume if crate::inputs::door_open() => {}
        Realtime::Resume => {
            prep.lock(|p| {
                let _ = p.prep.resume(&mut p.tx);
            });
            pend_prep();
        }
        Realtime::Reset => {
            let found = reset(prep, step);
            prep.lock(|p| {
                p.aborted = Some(found);
                ABORTING.store(true, Ordering::Release);
            });
        }
    }
}

/// Reset: outputs low at once, then the queue dropped and the stepper's
/// registers and record put back to what was issued; what was running.
fn reset(prep: &mut impl Mutex<T = PrepStage>, step: &mut impl Mutex<T = StepIsr>) -> Aborted {
    // The prep first: it puts nothing in the queue while the step
    // interrupt stops and drops what it holds.
    prep.lock(|p| {
        let found = step.lock(|s| {
            s.stop();
            let (passed, dropped) = s.drop_queued();
            let found = p.prep.abort(passed, dropped);
            s.restart();
            found
        });
        p.prep.set_spindle(0);
        found
    })
}

/// Sleeps until an interrupt unless `ready` already holds
/// ([`board::sleep_unless`]). In the `qemu-paced` build the core does not
/// sleep while the step interrupt has work: QEMU wakes a sleeping core
/// only once the host runs its thread again, milliseconds later on a
/// loaded host, and the protocol must keep the planner fed in real time
/// (the board wakes in a dozen cycles).
pub fn sleep_unless(ready: impl FnMut() -> bool) {
    if cfg!(feature = "qemu-paced") && !step::is_idle() {
        return;
    }
    board::sleep_unless(ready);
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

/// Whether a reset waits for the protocol (not taken yet).
pub fn reset_waiting() -> bool {
    WANTED.load(Ordering::Acquire) & WANT_RESET != 0
}

/// Forgets a cycle start that came before a program stop began to wait.
pub fn clear_cycle_start() {
    CYCLE_START.store(false, Ordering::Release);
}

/// Whether a program stop's wait is over: cycle start came, a reset, or
/// a switch stopped everything.
pub fn stop_ended() -> bool {
    CYCLE_START.load(Ordering::Acquire) || reset_wanted()
}

/// Whether a reset, or a switch's stop, waits for thread mode.
pub fn reset_wanted() -> bool {
    WANTED.load(Ordering::Acquire) & WANT_RESET != 0 || ABORTING.load(Ordering::Acquire)
}

/// Whether a switch's stop dropped the motion and the session has not
/// taken it (through [`Shared::abort`]).
pub fn input_stop_unreported() -> bool {
    INPUT_STOP.load(Ordering::Acquire)
}

/// Whether a real-time request, or a change of the switches, waits for
/// thread mode.
pub fn wanted() -> bool {
    WANTED.load(Ordering::Acquire) != 0 || crate::inputs::changed()
}

/// The two resources, as thread mode holds them.
pub struct Shared<P, S> {
    /// The prep stage.
    pub prep: P,
    /// The step interrupt's state.
    pub step: S,
}

impl<P: Mutex<T = PrepStage>, S: Mutex<T = StepIsr>> Shared<P, S> {
    /// Hands started motion to the prep; hands it back while the stepper
    /// is full. After a reset, until the protocol has handled it, the
    /// motion is dropped.
    #[allow(clippy::result_large_err)] // the item itself
    pub fn try_start(&mut self, item: Item, drive: &DriveTiming) -> Result<(), Item> {
        if ABORTING.load(Ordering::Acquire) {
            return Ok(());
        }
        if self.prep.lock(|p| p.drive != *drive) {
            // At rest: a change of drive timing flushes.
            self.step.lock(|s| s.set_drive(drive));
            self.prep.lock(|p| p.drive = *drive);
        }
        // Asked again under the lock that pushes: a reset in the real-time
        // task (which takes the same lock) comes wholly before the push or
        // wholly after it. Asked only before it, a reset landing between
        // the two let this block run from the planner's point while the
        // registers stood where the reset stopped them.
        let pushed = self.prep.lock(|p| {
            if ABORTING.load(Ordering::Acquire) {
                return Ok(false);
            }
            p.prep.push(item).map(|()| true)
        })?;
        if pushed {
            pend_prep();
        }
        Ok(())
    }

    /// Whether the stepper has room for another item.
    pub fn has_room(&mut self) -> bool {
        self.prep.lock(|p| p.prep.has_room())
    }

    /// Whether everything handed over has been issued (a hold keeps what it
    /// stopped until a resume or a reset).
    pub fn drained(&mut self) -> bool {
        let step = &mut self.step;
        self.prep
            .lock(|p| !p.prep.pending() && !step.lock(|s| s.busy()))
    }

    /// Whether every block started in an open run has been prepared and
    /// taken by the step interrupt: the planner should start the next one
    /// now.
    ///
    /// Unpaced under QEMU the step interrupt issues everything at once:
    /// nothing is ever late, and blocks start by the window alone, as on
    /// the virtual clock.
    pub fn hungry(&mut self) -> bool {
        // The prep runs up to 254 events ahead: the planner is needed only
        // once the step interrupt has taken them all (it may hold the last
        // one for its tick), as when it pulled its events itself.
        PACED && step::READY.is_empty() && self.prep.lock(|p| p.prep.hungry())
    }

    /// What the axes are doing: the prep's view, and whether the step
    /// interrupt still issues what it prepared.
    pub fn motion(&mut self) -> AxesState {
        let step = &mut self.step;
        let (m, busy) = self
            .prep
            .lock(|p| (p.prep.motion(), step.lock(|s| s.busy())));
        match m {
            AxesState::Idle if busy => AxesState::Run,
            AxesState::Held if busy => AxesState::Braking,
            m => m,
        }
    }

    /// The registers of the steps issued.
    pub fn issued(&mut self) -> ImpulsePoint {
        let step = &mut self.step;
        self.prep.lock(|p| {
            let passed = step.lock(|s| s.passed());
            p.prep.issued(passed).registers()
        })
    }

    /// The backlash take-up steps issued, net, per axis.
    pub fn lash(&mut self) -> [i32; 2] {
        let step = &mut self.step;
        self.prep.lock(|p| {
            let passed = step.lock(|s| s.passed());
            p.prep.issued(passed).lash()
        })
    }

    /// Sets them, at rest.
    pub fn set_issued(&mut self, registers: ImpulsePoint) {
        let step = &mut self.step;
        self.prep.lock(|p| {
            let passed = step.lock(|s| s.passed());
            p.prep.set_issued(passed, registers);
        });
    }

    /// What was recorded since the last call, at rest; the record starts
    /// again.
    pub fn take_record(&mut self) -> Record {
        let step = &mut self.step;
        self.prep.lock(|p| {
            let passed = step.lock(|s| s.passed());
            p.prep.take_record(passed)
        })
    }

    /// Acts as a real-time byte would (the protocol's own hold and resume).
    pub fn act(&mut self, rt: Realtime) {
        act(rt, &mut self.prep, &mut self.step);
    }

    /// The protocol's side of a reset: what the step interrupt found
    /// running (the reset itself happened when the byte arrived; a reset
    /// that did not come through the real-time task happens now).
    pub fn abort(&mut self) -> Aborted {
        let found = match self.prep.lock(|p| p.aborted.take()) {
            Some(found) => found,
            None => reset(&mut self.prep, &mut self.step),
        };
        ABORTING.store(false, Ordering::Release);
        INPUT_STOP.store(false, Ordering::Release);
        found
    }

    /// Under QEMU: a step whose alarm was lost is issued now
    /// ([`StepIsr::overdue`]); elsewhere nothing.
    pub fn watch_step(&mut self) {
        #[cfg(feature = "qemu")]
        self.step.lock(|s| s.overdue(board::ticks()));
    }

    /// Steps issued after their tick since power-on, and the most late
    /// (ticks).
    pub fn lateness(&mut self) -> (u32, u32) {
        self.step.lock(|s| s.lateness())
    }

    /// What the spindle and coolant outputs command now.
    pub fn outputs(&mut self) -> Outputs {
        self.step.lock(|s| s.spindle().outputs())
    }

    /// Switches the spindle and coolant outputs, at rest: the blocks that
    /// start from now on change the speed only.
    pub fn set_outputs(&mut self, o: &Outputs) {
        self.prep.lock(|p| p.prep.set_spindle(o.rpm));
        self.step.lock(|s| s.spindle().set(o));
    }
}

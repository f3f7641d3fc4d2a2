//! The motion pipeline's last stages behind one front: blocks go into the
//! planner, start as the look-ahead window fills (or at a flush), and their
//! timed step events go to the outputs, recorded for `SYNC`.
//!
//! This is the virtual-clock device of `docs/motion.md`: block `k` starts
//! when `W − 1` blocks are queued behind it, or at a flush; it goes to the
//! [`Stepper`], which is drained at once into a [`StepSink`] with the
//! events' ticks: a sink on a board waits for each tick, one in a simulator
//! records it.

use crate::arc::DirectSteps;
use crate::impulse::{ImpulsePrice, Impulses};
use crate::interleave::{ImpulsePoint, LinearBlock, StepEvent};
use crate::plan::{Block, Feed, Limits, Planner, Point, Rates, WINDOW};
use crate::step::{FixedRate, Record, TickRate};
use crate::stepdir::DriveTiming;
use crate::stepper::{Aborted, AxesState, FixedRun, Item, Pulled, Stepper, AHEAD};
use crate::wide::{mul_div, sqrt_shl};

/// Blocks the queue holds.
pub const QUEUE: usize = WINDOW;

/// A stepper that runs in time beside the protocol (a board's step
/// interrupt): it takes started motion and issues it on its own clock,
/// while the planner queues what follows.
pub trait Background {
    /// Takes started motion, to be issued with the drive's timing, waiting
    /// while it is full: the request is answered once its motion is taken
    /// (the flow control a streaming host sees).
    fn start(&mut self, item: Item, drive: &DriveTiming);
    /// Waits until everything taken has been issued (through a hold, until
    /// the resume).
    fn drain(&mut self);
    /// The registers of the steps issued.
    fn issued(&mut self) -> ImpulsePoint;
    /// The backlash take-up steps issued, net, per axis (X, Z).
    fn lash(&mut self) -> [i32; 2];
    /// Sets them, at rest (`ZERO`, a price change).
    fn set_issued(&mut self, registers: ImpulsePoint);
    /// What was recorded since this was last called (`SYNC`); the record
    /// starts again.
    fn take_record(&mut self) -> Record;
    /// Feed hold.
    fn hold(&mut self);
    /// Resume after a hold.
    fn resume(&mut self);
    /// Reset: drops everything at once, outputs low; what was running.
    fn abort(&mut self) -> Aborted;
    /// What the axes are doing.
    fn motion(&mut self) -> AxesState;
    /// Whether it has issued every block started in an open run: block
    /// `k − 1` has ended and block `k` should start now.
    fn hungry(&mut self) -> bool;
    /// Blocks queued and not started, as the planner hands over the next
    /// one (for a status line while it waits for room).
    fn queued(&mut self, blocks: usize) {
        let _ = blocks;
    }
    /// The spindle speed its outputs command now, 10⁻³ rpm, if it drives
    /// a spindle.
    fn spindle(&mut self) -> Option<u32> {
        None
    }
}

/// Where started motion goes: issued at once through [`StepSink::step`]
/// (the virtual clock, the default), or to a [`Background`] stepper of the
/// sink's own that issues it in time (a board's step interrupt).
pub trait StepSink {
    /// Hands started motion to the sink's background stepper; hands it
    /// back, to be issued now through `step`, when it has none (the
    /// default).
    #[allow(clippy::result_large_err)] // the item itself
    fn start(&mut self, item: Item) -> Result<(), Item> {
        Err(item)
    }
    /// The sink's background stepper, if it has one.
    fn background(&mut self) -> Option<&mut dyn Background> {
        None
    }
    /// A run begins: its tick 0 is now.
    fn run_start(&mut self) {}
    /// A linear block starts; its events follow.
    fn block_start(&mut self, block: &LinearBlock) {
        let _ = block;
    }
    /// A step event at `tick` of the current run.
    fn step(&mut self, event: StepEvent, tick: u64);
    /// The run ended `ticks` after it began; the axes are at rest.
    fn run_end(&mut self, ticks: u64) {
        let _ = ticks;
    }
}

/// What the axes are doing (`STATUS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Blocks queued and not started.
    pub queued: usize,
    /// The registers of the steps issued.
    pub issued: ImpulsePoint,
    /// The speed now, Q64 (Å/tick)² (squared).
    pub speed2: u128,
    /// Running, holding or idle.
    pub motion: AxesState,
    /// The spindle speed commanded now (that of the block running, or set
    /// at rest since), 10⁻³ rpm.
    pub spindle: u32,
}

impl Status {
    /// The speed now in 10⁻⁴ mm/min on a clock of `tick`, rounded half up.
    pub fn speed(&self, tick: TickRate) -> i64 {
        speed(self.speed2, tick)
    }
}

/// A squared speed (Q64 (Å/tick)²) in 10⁻⁴ mm/min on a clock of `tick`,
/// rounded half up.
fn speed(speed2: u128, tick: TickRate) -> i64 {
    // √v² Å/tick · TICK ticks/s · 60 s/min / 1000 Å per 10⁻⁴ mm.
    let v = sqrt_shl(speed2, 64); // Q64 Å/tick
    let scaled = mul_div(v, 60 * u128::from(tick.hz()), 1000);
    i64::try_from(scaled.saturating_add(1 << 63) >> 64).unwrap_or(i64::MAX)
}

/// The planner, the run in progress and what has been issued.
#[derive(Clone, Debug)]
pub struct Machine {
    rates: Rates,
    planner: Planner<QUEUE>,
    /// Started motion, the record and the registers of the steps issued.
    stepper: Stepper<AHEAD>,
    /// Where the next queued block starts, Å·2³².
    point: Point,
    /// Blocks started with a short window because the stepper needed
    /// them (the host did not keep the queue filled), since the last
    /// `SYNC` or `ZERO`.
    starved: u32,
    /// The spindle speed the blocks queued from now on carry, 10⁻³ rpm.
    spindle: u32,
    /// How the blocks queued from now on join the block before: at the
    /// junction deviation given (Å; `None` the limits' `JD`), or at rest.
    join: Join,
    /// Each axis' backlash, impulses (`docs/motion.md` §7).
    backlash: [i32; 2],
    /// The take-up steps of the blocks queued so far, net, per axis: 0
    /// after a move towards minus, the backlash after one towards plus.
    lash: [i32; 2],
}

/// How a queued block joins the one before it (path control).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Join {
    /// At the speed the limits' junction deviation allows (`G64`).
    Blend,
    /// At the speed a junction deviation of this many ångström allows
    /// (`G64 P`).
    Deviation(u64),
    /// At rest (`G61`, exact stop).
    Stop,
}

impl Default for Machine {
    fn default() -> Self {
        Self::new()
    }
}

impl Machine {
    /// At rest at the origin, default limits on the device's timer.
    pub const fn new() -> Machine {
        Self::with_window(WINDOW)
    }

    /// As [`Machine::new`], looking `window` blocks ahead (1 … [`QUEUE`]).
    pub const fn with_window(window: usize) -> Machine {
        Machine {
            rates: Rates::DEFAULT,
            planner: Planner::new(window),
            stepper: Stepper::new(),
            point: [0, 0],
            starved: 0,
            spindle: 0,
            join: Join::Blend,
            backlash: [0, 0],
            lash: [0, 0],
        }
    }

    /// How the blocks queued from now on join the block before.
    pub fn set_join(&mut self, join: Join) {
        self.join = join;
    }

    /// Each axis' backlash (impulses, X then Z), taken up from the next
    /// reversal on.
    /// The motors stay where they are in their play: the next block
    /// towards plus takes up the difference.
    pub fn set_backlash(&mut self, impulses: [u32; 2]) {
        self.backlash = impulses.map(|b| i32::try_from(b).unwrap_or(i32::MAX));
    }

    /// The take-up steps of the blocks queued so far, net, per axis.
    pub const fn lash(&self) -> [i32; 2] {
        self.lash
    }

    /// The spindle speed commanded for the blocks queued from now on (10⁻³
    /// rpm, 0 stopped): each carries it to its start, where the output
    /// follows (under `G96` it changes block by block).
    pub fn set_spindle(&mut self, milli_rpm: u32) {
        self.spindle = milli_rpm;
    }

    /// Sets the spindle speed at rest, nothing queued (`M03 S…`): the
    /// output's now, and that of the blocks queued from now on.
    pub fn switch_spindle(&mut self, milli_rpm: u32) {
        self.spindle = milli_rpm;
        self.stepper.set_spindle(milli_rpm);
    }

    /// The limits in force.
    pub const fn limits(&self) -> &Limits {
        self.rates.limits()
    }

    /// The clock events are timed on.
    pub const fn tick(&self) -> TickRate {
        self.rates.tick()
    }

    /// New limits; the caller has flushed (they apply at rest).
    pub fn set_limits(&mut self, limits: Limits) {
        self.rates = Rates::new(limits, self.rates.tick()).with_rapid(self.rates.rapid());
    }

    /// The rapid override, percent: rapids queued from now on run at it.
    pub fn set_rapid_override(&mut self, percent: u8) {
        self.rates = self.rates.with_rapid(percent);
    }

    /// Where the axes are now and will be, at rest (after `ZERO` or a price
    /// change); the caller has flushed.
    pub fn set_position<S: StepSink>(
        &mut self,
        point: Point,
        registers: ImpulsePoint,
        sink: &mut S,
    ) {
        self.point = point;
        self.stepper.set_issued(registers);
        if let Some(b) = sink.background() {
            b.set_issued(registers);
        }
    }

    /// Queues the block from the current point to `to`, issuing `events` at
    /// prices `h` and `feed` (rapid when `None`); blocks start as the window
    /// fills. A block without length takes no time and issues nothing.
    pub fn queue<S: StepSink>(
        &mut self,
        to: Point,
        events: LinearBlock,
        feed: Option<Feed>,
        h: [ImpulsePrice; 2],
        sink: &mut S,
    ) {
        let from = self.point;
        self.point = to;
        let Some(block) = Block::new(from, to, events, feed, h, &self.rates) else {
            return;
        };
        self.take_up(events.delta(), h, sink);
        self.push_block(block.with_spindle(self.spindle), sink);
    }

    /// Before a block whose steps go `delta` (X, Z impulses): each axis it
    /// moves whose motor stands on the other side of its play turns
    /// through it first, in a block of its own (`docs/motion.md` §7).
    fn take_up<S: StepSink>(&mut self, delta: (i32, i32), h: [ImpulsePrice; 2], sink: &mut S) {
        let step = |d: i32, backlash: i32, lash: i32| match d {
            0 => 0,
            d if d > 0 => backlash.saturating_sub(lash),
            _ => 0i32.saturating_sub(lash),
        };
        let steps = [
            step(delta.0, self.backlash[0], self.lash[0]),
            step(delta.1, self.backlash[1], self.lash[1]),
        ];
        if steps == [0, 0] {
            return;
        }
        // On the grid from the origin: the take-up moves no point.
        let origin = ImpulsePoint {
            x: Impulses(0),
            z: Impulses(0),
        };
        let end = ImpulsePoint {
            x: Impulses(steps[0]),
            z: Impulses(steps[1]),
        };
        let q = |n: i32, h: ImpulsePrice| (i128::from(n) * i128::from(h.as_angstrom())) << 32;
        let Ok(events) = LinearBlock::new(origin, end) else {
            return;
        };
        let Some(block) = Block::new(
            [0, 0],
            [q(steps[0], h[0]), q(steps[1], h[1])],
            events,
            None,
            h,
            &self.rates,
        ) else {
            return;
        };
        self.push_block(block.with_spindle(self.spindle).as_takeup(), sink);
        self.lash[0] = self.lash[0].saturating_add(steps[0]);
        self.lash[1] = self.lash[1].saturating_add(steps[1]);
    }

    /// Plans `block` behind those queued; the first starts when the window
    /// is full.
    fn push_block<S: StepSink>(&mut self, block: Block, sink: &mut S) {
        if self.planner.window_full() {
            self.start_one(sink);
        }
        // The window is not full now: there is room.
        let deviation = match self.join {
            Join::Blend => Some(self.rates.limits().junction().as_angstrom().unsigned_abs()),
            Join::Deviation(d) => Some(d),
            Join::Stop => None,
        };
        let _ = self.planner.push_joined(block, &self.rates, deviation);
        if self.planner.window_full() {
            self.start_one(sink);
        } else {
            self.poll(sink);
        }
    }

    /// A real device's rule besides the window: when the stepper runs the
    /// last block started in an open run, the next queued block starts now
    /// with the window it has (counted as starved). Its plan still ends at
    /// rest by the end of what is queued.
    pub fn poll<S: StepSink>(&mut self, sink: &mut S) {
        if self.can_feed() && sink.background().is_some_and(|b| b.hungry()) {
            self.starved += u32::from(self.start_one(sink));
        }
    }

    /// Whether [`Machine::poll`] could start a block, were the stepper
    /// hungry.
    pub fn can_feed(&self) -> bool {
        self.planner.in_run() && self.planner.queued() > 0
    }

    /// The speed at the end of the block started last, 10⁻⁴ mm/min.
    pub fn speed(&self) -> i64 {
        speed(self.planner.exit2(), self.rates.tick())
    }

    /// Blocks started starved since the last `SYNC` or `ZERO`.
    pub const fn starved(&self) -> u32 {
        self.starved
    }

    /// A flush: every queued block starts in turn, the last one ends at
    /// rest, the run ends, and everything started has been issued.
    pub fn flush<S: StepSink>(&mut self, sink: &mut S) {
        while self.start_one(sink) {}
        if let Some(ticks) = self.planner.end_run() {
            self.start_item(Item::RunEnd(ticks), sink);
        }
        if let Some(b) = sink.background() {
            b.drain();
        }
    }

    /// Starts every queued block now and ends the run at rest after them,
    /// without waiting for them to be issued (a flush that returns).
    pub fn release<S: StepSink>(&mut self, sink: &mut S) {
        while self.start_one(sink) {}
        if let Some(ticks) = self.planner.end_run() {
            self.start_item(Item::RunEnd(ticks), sink);
        }
    }

    /// Blocks queued and not started.
    pub fn queued(&self) -> usize {
        self.planner.queued()
    }

    /// Whether blocks are queued with no run under way: they start with a
    /// full window, at a flush, or at [`Machine::release`].
    pub fn waiting(&self) -> bool {
        !self.planner.in_run() && self.planner.queued() > 0
    }

    /// A flush, then `events` at a fixed rate as a run of their own (the
    /// ЭМ-907's direct arc, within one quadrant: its steps go `delta`, at
    /// prices `h`), ending at point `end`.
    pub fn fixed_rate<S: StepSink>(
        &mut self,
        events: DirectSteps,
        delta: (i32, i32),
        h: [ImpulsePrice; 2],
        rate_hz: u32,
        end: Point,
        sink: &mut S,
    ) {
        // Within one quadrant each axis keeps its direction: its play is
        // taken up before the run.
        self.take_up(delta, h, sink);
        self.flush(sink);
        let rate = FixedRate::new(self.rates.tick(), rate_hz);
        self.start_item(Item::Fixed(FixedRun::new(rate, events)), sink);
        self.point = end;
    }

    /// `SYNC`: a flush, then what ran since the previous `SYNC` or `ZERO`;
    /// the record starts again.
    pub fn sync<S: StepSink>(&mut self, sink: &mut S) -> (Record, u32) {
        self.flush(sink);
        let own = self.stepper.take_record();
        let starved = core::mem::take(&mut self.starved);
        let record = match sink.background() {
            Some(b) => b.take_record(),
            None => own,
        };
        (record, starved)
    }

    /// Forgets what was recorded (`ZERO`); the caller has flushed.
    pub fn clear_record<S: StepSink>(&mut self, sink: &mut S) {
        self.stepper.clear_record();
        self.starved = 0;
        if let Some(b) = sink.background() {
            let _ = b.take_record();
        }
    }

    /// What the axes are doing.
    pub fn status<S: StepSink>(&self, sink: &mut S) -> Status {
        let queued = self.planner.queued();
        let (motion, issued, spindle) = match sink.background() {
            Some(b) => (
                b.motion(),
                b.issued(),
                b.spindle().unwrap_or(self.stepper.spindle()),
            ),
            None => (
                AxesState::Idle,
                self.stepper.issued(),
                self.stepper.spindle(),
            ),
        };
        let motion = match motion {
            AxesState::Idle if queued > 0 => AxesState::Run,
            m => m,
        };
        Status {
            queued,
            issued,
            speed2: self.planner.exit2(),
            motion,
            spindle,
        }
    }

    /// Feed hold (on a sink with a stepper of its own).
    pub fn hold<S: StepSink>(&mut self, sink: &mut S) {
        if let Some(b) = sink.background() {
            b.hold();
        }
    }

    /// Resume after a hold.
    pub fn resume<S: StepSink>(&mut self, sink: &mut S) {
        if let Some(b) = sink.background() {
            b.resume();
        }
    }

    /// Reset: everything queued and started is dropped at once; the
    /// registers keep the steps issued. Returns the block that was running
    /// and the registers.
    pub fn abort<S: StepSink>(&mut self, sink: &mut S) -> (Aborted, ImpulsePoint) {
        let queued = self.planner.queued() > 0;
        self.planner.clear();
        // The registers, and where the motors stand in their play: what
        // was issued of it.
        let (mut found, issued, lash) = match sink.background() {
            Some(b) => (b.abort(), b.issued(), b.lash()),
            None => (
                self.stepper.abort(),
                self.stepper.issued(),
                self.stepper.lash(),
            ),
        };
        found.dropped |= queued;
        self.stepper.set_issued(issued);
        self.stepper.set_lash(lash);
        self.lash = lash;
        (found, issued)
    }

    /// Forgets what was queued and started without issuing it anywhere
    /// (check mode's motion, which went nowhere), the registers and the
    /// motors' take-up as given.
    pub fn forget(&mut self, registers: ImpulsePoint, lash: [i32; 2]) {
        self.planner.clear();
        self.stepper.abort();
        self.stepper.set_issued(registers);
        self.stepper.set_lash(lash);
        self.lash = lash;
    }

    /// Where the next queued block starts from now on (after a reset: the
    /// registers' point).
    pub fn set_point(&mut self, point: Point) {
        self.point = point;
    }

    /// Starts the first queued block and issues its events; false when none
    /// is queued.
    fn start_one<S: StepSink>(&mut self, sink: &mut S) -> bool {
        let fresh = !self.planner.in_run();
        let Some(timed) = self.planner.start_block(&self.rates) else {
            return false;
        };
        if fresh {
            self.start_item(Item::RunStart, sink);
        }
        self.start_item(Item::Block(timed), sink);
        true
    }

    /// Hands started motion to the sink's stepper, or to this one's and
    /// issues it to `sink` at once.
    fn start_item<S: StepSink>(&mut self, item: Item, sink: &mut S) {
        let queued = self.planner.queued();
        if let Some(b) = sink.background() {
            b.queued(queued);
        }
        let Err(item) = sink.start(item) else {
            return;
        };
        // Drained after every item: there is always room.
        let _ = self.stepper.push(item);
        while let Some(p) = self.stepper.pull() {
            match p {
                Pulled::RunStart => sink.run_start(),
                Pulled::BlockStart(b) => sink.block_start(&b),
                Pulled::Step(e, tick) => sink.step(e, tick),
                Pulled::RunEnd(ticks) => sink.run_end(ticks),
            }
        }
    }
}

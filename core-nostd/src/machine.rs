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
use crate::impulse::ImpulsePrice;
use crate::interleave::{ImpulsePoint, LinearBlock, StepEvent};
use crate::plan::{Block, Feed, Limits, Planner, Point, Rates, WINDOW};
use crate::step::{FixedRate, Record, TickRate};
use crate::stepper::{Aborted, FixedRun, Item, Motion, Pulled, Stepper, AHEAD};
use crate::wide::{mul_div, sqrt_shl};

/// Blocks the queue holds.
pub const QUEUE: usize = WINDOW;

/// Where started motion goes: issued at once through [`StepSink::step`]
/// (the virtual clock, the default), or taken by a stepper of the sink's
/// own that issues it later (a board's step interrupt).
pub trait StepSink {
    /// Takes started motion for the sink's own stepper, waiting for room
    /// if it must; hands it back to be issued now through `step` (the
    /// default).
    #[allow(clippy::result_large_err)] // the item itself
    fn start(&mut self, item: Item) -> Result<(), Item> {
        Err(item)
    }
    /// Waits until the sink's own stepper has issued everything it took.
    fn drain(&mut self) {}
    /// The registers of the steps the sink's own stepper issued, if it has
    /// one.
    fn issued(&mut self) -> Option<ImpulsePoint> {
        None
    }
    /// Sets them, at rest.
    fn set_issued(&mut self, registers: ImpulsePoint) {
        let _ = registers;
    }
    /// What the sink's own stepper recorded since this was last called
    /// (`SYNC`), if it has one; the record starts again.
    fn take_record(&mut self) -> Option<Record> {
        None
    }
    /// Feed hold on the sink's own stepper; false when it has none (the
    /// virtual clock issues each block as it starts: nothing is moving
    /// when a hold arrives).
    fn hold(&mut self) -> bool {
        false
    }
    /// Resume after a hold, on the sink's own stepper.
    fn resume(&mut self) -> bool {
        false
    }
    /// Reset: the sink's own stepper drops everything at once; what it
    /// found running, if it has one.
    fn abort(&mut self) -> Option<Aborted> {
        None
    }
    /// What the sink's own stepper is doing, if it has one.
    fn motion(&mut self) -> Option<Motion> {
        None
    }
    /// Whether the sink's own stepper is running the last block started
    /// in an open run (or braking into the next one): it needs the next
    /// block now, window full or not.
    fn hungry(&mut self) -> bool {
        false
    }
    /// Blocks queued and not started, as the planner hands over the next
    /// one (a board reports it while it waits for room).
    fn queued(&mut self, blocks: usize) {
        let _ = blocks;
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
    pub motion: Motion,
}

impl Status {
    /// The speed now in 10⁻⁴ mm/min on a clock of `tick`, rounded half up.
    pub fn speed(&self, tick: TickRate) -> i64 {
        // √v² Å/tick · TICK ticks/s · 60 s/min / 1000 Å per 10⁻⁴ mm.
        let v = sqrt_shl(self.speed2, 64); // Q64 Å/tick
        let scaled = mul_div(v, 60 * u128::from(tick.hz()), 1000);
        i64::try_from(scaled.saturating_add(1 << 63) >> 64).unwrap_or(i64::MAX)
    }
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
        }
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
        self.rates = Rates::new(limits, self.rates.tick());
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
        sink.set_issued(registers);
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
        if self.planner.window_full() {
            self.start_one(sink);
        }
        // The window is not full now: there is room.
        let _ = self.planner.push(block, &self.rates);
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
        if self.planner.in_run() && self.planner.queued() > 0 && sink.hungry() {
            self.starved += u32::from(self.start_one(sink));
        }
    }

    /// Whether [`Machine::poll`] could start a block, were the stepper
    /// hungry.
    pub fn can_feed(&self) -> bool {
        self.planner.in_run() && self.planner.queued() > 0
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
        sink.drain();
    }

    /// A flush, then `events` at a fixed rate as a run of their own (the
    /// ЭМ-907's direct arc), ending at point `end`.
    pub fn fixed_rate<S: StepSink>(
        &mut self,
        events: DirectSteps,
        rate_hz: u32,
        end: Point,
        sink: &mut S,
    ) {
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
        (sink.take_record().unwrap_or(own), starved)
    }

    /// Forgets what was recorded (`ZERO`); the caller has flushed.
    pub fn clear_record<S: StepSink>(&mut self, sink: &mut S) {
        self.stepper.clear_record();
        self.starved = 0;
        let _ = sink.take_record();
    }

    /// What the axes are doing.
    pub fn status<S: StepSink>(&self, sink: &mut S) -> Status {
        let queued = self.planner.queued();
        let motion = sink.motion().unwrap_or(Motion::Idle);
        let motion = match motion {
            Motion::Idle if queued > 0 => Motion::Run,
            m => m,
        };
        Status {
            queued,
            issued: sink.issued().unwrap_or(self.stepper.issued()),
            speed2: self.planner.exit2(),
            motion,
        }
    }

    /// Feed hold (on a sink with a stepper of its own).
    pub fn hold<S: StepSink>(&mut self, sink: &mut S) {
        sink.hold();
    }

    /// Resume after a hold.
    pub fn resume<S: StepSink>(&mut self, sink: &mut S) {
        sink.resume();
    }

    /// Reset: everything queued and started is dropped at once; the
    /// registers keep the steps issued. Returns the block that was running
    /// and the registers.
    pub fn abort<S: StepSink>(&mut self, sink: &mut S) -> (Aborted, ImpulsePoint) {
        self.planner.clear();
        let found = sink.abort().unwrap_or(self.stepper.abort());
        let issued = sink.issued().unwrap_or(self.stepper.issued());
        self.stepper.set_issued(issued);
        (found, issued)
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
        sink.queued(self.planner.queued());
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

//! Started motion in order, pulled one step event at a time: the stage the
//! step interrupt runs (`docs/motion.md`).
//!
//! The planner starts blocks; a [`Stepper`] holds them, with the run
//! boundaries between them, and hands out their events with their ticks.
//! It keeps what `SYNC` and `STATUS` report of the steps actually issued:
//! the [`Record`] and the registers. The virtual-clock device drains it as
//! soon as a block starts; a board's timer interrupt pulls one event per
//! compare while the protocol queues the next blocks.

use crate::arc::DirectSteps;
use crate::impulse::Impulses;
use crate::interleave::{ImpulsePoint, LinearBlock, StepEvent};
use crate::plan::{profile, state_at, Block, Started};
use crate::step::{round_ticks, FixedRate, Record, TimedEvents};
use heapless::Deque;

/// Started items a stepper holds ahead of the one it is issuing.
pub const AHEAD: usize = 4;

/// Events at a fixed rate, a run of their own (the ЭМ-907's direct arc).
#[derive(Clone, Debug)]
pub struct FixedRun {
    rate: FixedRate,
    events: DirectSteps,
    /// Events issued so far.
    n: u32,
}

impl FixedRun {
    /// `events` at `rate`, event `j` at its tick `Q(j·TICK/RATE)`.
    pub const fn new(rate: FixedRate, events: DirectSteps) -> FixedRun {
        FixedRun { rate, events, n: 0 }
    }
}

/// One item of started motion.
#[derive(Clone, Debug)]
// A started block is the common item; boxing it is not an option here.
#[allow(clippy::large_enum_variant)]
pub enum Item {
    /// A run begins: its tick 0 is when its first event is due to be timed.
    RunStart,
    /// A planned block, timed in its run.
    Block(Started),
    /// A run at a fixed event rate, from rest to rest.
    Fixed(FixedRun),
    /// The run ends, this many ticks after it began.
    RunEnd(u64),
}

/// What the stepper hands out next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pulled {
    /// A run begins: its tick 0 is now.
    RunStart,
    /// A linear block's events follow.
    BlockStart(LinearBlock),
    /// A step event at its tick of the current run.
    Step(StepEvent, u64),
    /// The run ended after this many ticks; the axes are at rest.
    RunEnd(u64),
}

/// What the axes are doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AxesState {
    /// Nothing started waits or runs.
    Idle,
    /// Started motion runs or waits.
    Run,
    /// A feed hold decelerates the axes along the path.
    Braking,
    /// A feed hold has brought them to rest; motion waits for a resume.
    Held,
}

/// What a reset found running.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Aborted {
    /// Events of the block that was running that had been issued.
    pub done: u32,
    /// All its events.
    pub of: u32,
    /// Motion taken had not all been issued (a block running, items
    /// waiting, a hold braking or holding the rest of a block): the reset
    /// dropped some.
    pub dropped: bool,
}

/// What is being issued.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
enum Now {
    Idle,
    /// A block's events, with the block (or the part of it this timing
    /// covers) to time again after a hold.
    Timed(TimedEvents, Block),
    Fixed(FixedRun),
}

/// What waits for a resume where a hold stopped.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
enum Rest {
    /// Nothing: the hold stopped at the end of a block or at rest.
    Nothing,
    /// The rest of a block, and the exit speed² its plan gave it.
    Part(Block, u128),
    /// The rest of a fixed-rate run.
    Fixed(DirectSteps, FixedRate),
}

/// A feed hold's progress.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
enum Hold {
    Off,
    /// Decelerating: the speed² the current timing ends with, and what
    /// remains once it has ended at rest, if it does.
    Braking(u128, Option<Rest>),
    /// At rest.
    Held(Rest),
}

/// Started motion waiting and being issued, and what has been issued.
#[derive(Clone, Debug)]
pub struct Stepper<const R: usize> {
    ring: Deque<Item, R>,
    now: Now,
    record: Record,
    issued: ImpulsePoint,
    hold: Hold,
    /// A hold happened in this run: later blocks are timed again from the
    /// speed and time the run actually reached.
    retime: bool,
    /// A run is open.
    in_run: bool,
    /// When the timing issued last ends in its run (Q64 ticks), and its
    /// exit speed² (as it actually runs).
    end: u128,
    exit2: u128,
    /// The spindle speed of the block that started last, 10⁻³ rpm.
    spindle: u32,
    /// Backlash take-up steps issued, net, per axis: where each motor
    /// stands from its register (`docs/motion.md` §7).
    lash: [i32; 2],
    /// The event pulled last was a take-up's.
    last_takeup: bool,
}

impl<const R: usize> Default for Stepper<R> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const R: usize> Stepper<R> {
    /// Nothing started, registers at 0.
    pub const fn new() -> Self {
        Stepper {
            ring: Deque::new(),
            now: Now::Idle,
            record: Record::new(),
            issued: ImpulsePoint {
                x: Impulses(0),
                z: Impulses(0),
            },
            hold: Hold::Off,
            retime: false,
            in_run: false,
            end: 0,
            exit2: 0,
            spindle: 0,
            lash: [0, 0],
            last_takeup: false,
        }
    }

    /// The spindle speed commanded for the block that started last, or
    /// set at rest since (10⁻³ rpm): what a spindle output follows.
    pub const fn spindle(&self) -> u32 {
        self.spindle
    }

    /// Sets the spindle speed at rest (`M03 S…` between blocks).
    pub fn set_spindle(&mut self, milli_rpm: u32) {
        self.spindle = milli_rpm;
    }

    /// Whether another item fits.
    pub fn has_room(&self) -> bool {
        !self.ring.is_full()
    }

    /// Whether a run is open: started and not ended.
    pub fn in_run(&self) -> bool {
        self.in_run
    }

    /// Items waiting behind the one being issued.
    pub fn waiting(&self) -> usize {
        self.ring.len()
    }

    /// Whether nothing waits and nothing is being issued.
    pub fn is_idle(&self) -> bool {
        self.ring.is_empty() && matches!(self.now, Now::Idle)
    }

    /// Whether anything taken has not all been issued: items waiting, a
    /// block being issued, a hold braking, or held with the rest of a
    /// block or run to resume.
    pub fn pending(&self) -> bool {
        !self.is_idle()
            || match &self.hold {
                Hold::Off | Hold::Held(Rest::Nothing) => false,
                Hold::Braking(..) | Hold::Held(_) => true,
            }
    }

    /// What the axes are doing.
    pub fn motion(&self) -> AxesState {
        match self.hold {
            Hold::Braking(..) => AxesState::Braking,
            Hold::Held(_) => AxesState::Held,
            Hold::Off if self.is_idle() => AxesState::Idle,
            Hold::Off => AxesState::Run,
        }
    }

    /// Whether it has issued every block started in an open run (or
    /// brakes towards the next one): block `k − 1` has ended, the planner
    /// should start block `k` now, with the window it has.
    pub fn hungry(&self) -> bool {
        self.in_run
            && self.ring.is_empty()
            && matches!(self.now, Now::Idle)
            && !matches!(self.hold, Hold::Held(_))
    }

    /// Adds an item behind the others; a full stepper hands it back.
    #[allow(clippy::result_large_err)] // the item itself, as heapless does
    pub fn push(&mut self, item: Item) -> Result<(), Item> {
        self.ring.push_back(item)
    }

    /// The next thing to do: a run boundary, a block's start, or a step
    /// event with its tick (recorded and counted in the registers as it is
    /// handed out). `None` when nothing is started, or a hold holds it.
    #[inline(always)]
    pub fn pull(&mut self) -> Option<Pulled> {
        loop {
            match &mut self.now {
                Now::Timed(events, block) => match events.next() {
                    Some((e, tick)) => {
                        let takeup = block.takeup();
                        return Some(self.issue(e, tick, takeup));
                    }
                    None => {
                        self.now = Now::Idle;
                        if let Hold::Braking(_, Some(_)) = self.hold {
                            return Some(self.stopped());
                        }
                    }
                },
                Now::Fixed(run) => match run.events.next() {
                    Some(e) => {
                        run.n += 1;
                        let tick = run.rate.tick(run.n);
                        return Some(self.issue(e, tick, false));
                    }
                    None => {
                        let ticks = run.rate.tick(run.n);
                        let ended = run.n > 0;
                        self.now = Now::Idle;
                        if ended {
                            return Some(self.run_end(ticks));
                        }
                    }
                },
                Now::Idle => {
                    if matches!(self.hold, Hold::Held(_)) {
                        return None;
                    }
                    if !self.in_run && matches!(self.ring.front(), Some(Item::Block(_))) {
                        // A hold at rest ended the run before this block
                        // came, and a resume found nothing to take up:
                        // the block starts a run of its own, timed again
                        // from rest (its planned ticks count from a start
                        // that has passed).
                        (self.in_run, self.end, self.exit2) = (true, 0, 0);
                        self.retime = true;
                        return Some(Pulled::RunStart);
                    }
                    match self.ring.pop_front()? {
                        Item::RunStart => {
                            (self.in_run, self.end, self.exit2) = (true, 0, 0);
                            return Some(Pulled::RunStart);
                        }
                        Item::Block(s) => return Some(self.block(s)),
                        Item::Fixed(run) => {
                            if matches!(self.hold, Hold::Braking(..)) {
                                // A run of its own starts from rest: held
                                // before it.
                                self.hold = Hold::Held(Rest::Fixed(run.events, run.rate));
                                return None;
                            }
                            // A run of its own; one without events is nothing.
                            let mut peek = run.events.clone();
                            let empty = peek.next().is_none();
                            self.now = Now::Fixed(run);
                            if !empty {
                                self.in_run = true;
                                return Some(Pulled::RunStart);
                            }
                        }
                        Item::RunEnd(ticks) => {
                            // After a hold the run's own clock says when.
                            let ticks = if self.retime || !matches!(self.hold, Hold::Off) {
                                round_ticks(self.end)
                            } else {
                                ticks
                            };
                            self.retime = false;
                            if matches!(self.hold, Hold::Braking(..)) {
                                self.hold = Hold::Held(Rest::Nothing);
                            }
                            return Some(self.run_end(ticks));
                        }
                    }
                }
            }
        }
    }

    /// A started block begins: as planned, timed again after a hold, or
    /// as a hold's deceleration.
    fn block(&mut self, s: Started) -> Pulled {
        let planned_exit = s.timed.speeds2()[2];
        self.spindle = s.block.spindle();
        if let Hold::Braking(carry, _) = self.hold {
            self.brake(&s.block, 0, 0, carry, self.end, planned_exit);
        } else if self.retime {
            let e2 = self.exit2;
            let x2 = planned_exit.min(e2.saturating_add(s.block.two_al()));
            let timed = profile(&s.block, e2, x2, self.end);
            (self.end, self.exit2) = (timed.span_q64().1, x2);
            self.now = Now::Timed(timed.events(), s.block);
        } else {
            (self.end, self.exit2) = (s.timed.span_q64().1, planned_exit);
            self.now = Now::Timed(s.timed.events(), s.block);
        }
        Pulled::BlockStart(*s.block.events())
    }

    /// Times `block` from lead-axis distance `from` (the boundary of its
    /// `issued`-th event, or its start) as a hold's deceleration from
    /// speed² `v2` at `t`, at the block's own acceleration: through to its
    /// end, or to rest within it, the rest kept for a resume.
    fn brake(
        &mut self,
        block: &Block,
        from: u128,
        issued: u32,
        v2: u128,
        t: u128,
        planned_exit: u128,
    ) {
        let (skip, count) = block.span();
        let done = skip + issued;
        let len = block.lead_len();
        let left = skip + count - done;
        let through = block.part(from, len, done, left);
        let tal = through.two_al();
        let (timed, part, after) = if v2 > tal {
            let x2 = v2 - tal;
            (
                profile(&through, v2, x2, t),
                through,
                Hold::Braking(x2, None),
            )
        } else {
            // Rest where 2a·s = v², s from `from`.
            let stop = from.saturating_add(crate::wide::mul_div(len - from, v2, tal.max(1)));
            let k = through.events_upto(stop - from);
            let upto = block.part(from, stop, done, k).braking_to_rest(v2);
            let rest = block.part(stop, len, done + k, left - k);
            (
                profile(&upto, v2, 0, t),
                upto,
                Hold::Braking(0, Some(Rest::Part(rest, planned_exit))),
            )
        };
        (self.end, self.exit2) = (timed.span_q64().1, timed.speeds2()[2]);
        self.hold = after;
        self.now = Now::Timed(timed.events(), part);
    }

    /// A hold's deceleration has ended at rest: the run ends there.
    fn stopped(&mut self) -> Pulled {
        let rest = match core::mem::replace(&mut self.hold, Hold::Off) {
            Hold::Braking(_, Some(rest)) => rest,
            _ => Rest::Nothing,
        };
        self.hold = Hold::Held(rest);
        self.exit2 = 0;
        self.run_end(round_ticks(self.end))
    }

    fn run_end(&mut self, ticks: u64) -> Pulled {
        self.in_run = false;
        self.record.run_end(ticks);
        Pulled::RunEnd(ticks)
    }

    /// Feed hold: from the last event issued, the axes decelerate along
    /// the path at each block's own acceleration until they rest, and wait
    /// there for [`Stepper::resume`]. A fixed-rate run (which has no ramps)
    /// stops after its current event.
    pub fn hold(&mut self) {
        if !matches!(self.hold, Hold::Off) {
            return;
        }
        match &self.now {
            Now::Timed(events, block) => {
                let (timed, block, issued) = (*events.timed(), *block, events.done());
                // From the boundary of the last event issued (where the
                // axes stand at that event), at its time and speed.
                let (t, v2) = state_at(&block, &timed, issued);
                let from = if issued == 0 {
                    0
                } else {
                    block.boundary(issued)
                };
                self.brake(&block, from, issued, v2, t, timed.speeds2()[2]);
            }
            Now::Fixed(run) => {
                let rest = Rest::Fixed(run.events.clone(), run.rate);
                let ticks = run.rate.tick(run.n);
                self.now = Now::Idle;
                self.hold = Hold::Held(rest);
                if self.in_run {
                    let _ = self.run_end(ticks);
                }
            }
            Now::Idle => {
                if self.in_run && self.exit2 > 0 {
                    // Between blocks at speed: the next one decelerates.
                    self.hold = Hold::Braking(self.exit2, None);
                } else {
                    self.hold = Hold::Held(Rest::Nothing);
                    if self.in_run {
                        let _ = self.run_end(round_ticks(self.end));
                    }
                }
            }
        }
    }

    /// Resume after a hold: a new run from rest along the same path, the
    /// rest of the block where the hold stopped first. Later blocks are
    /// timed again from the speeds the run reaches (never above their
    /// plan). While the hold is still decelerating nothing changes.
    pub fn resume(&mut self) -> Option<Pulled> {
        // Only at rest: a resume while braking changes nothing (taking the
        // hold away then would drop the rest of the block it stopped).
        if !matches!(self.hold, Hold::Held(_)) {
            return None;
        }
        let Hold::Held(rest) = core::mem::replace(&mut self.hold, Hold::Off) else {
            return None;
        };
        (self.end, self.exit2) = (0, 0);
        match rest {
            Rest::Nothing => {
                // Rest at a block's end: what follows starts a new run.
                if self.ring.is_empty() || matches!(self.ring.front(), Some(Item::RunStart)) {
                    return None;
                }
            }
            // What is left of the block, unless nothing is.
            Rest::Part(block, planned_exit) if block.span().1 > 0 || block.lead_len() > 0 => {
                let x2 = planned_exit.min(block.two_al());
                let timed = profile(&block, 0, x2, 0);
                (self.end, self.exit2) = (timed.span_q64().1, x2);
                self.now = Now::Timed(timed.events(), block);
            }
            Rest::Part(..) => {}
            Rest::Fixed(events, rate) => {
                self.now = Now::Fixed(FixedRun::new(rate, events));
            }
        }
        self.retime = true;
        self.in_run = true;
        Some(Pulled::RunStart)
    }

    /// The item being issued, as a reset would report it: the events of
    /// its block handed out and all of them; a fixed-rate run's total is
    /// `None` (counting it walks its events: see [`Stepper::abort`]).
    pub fn running(&self) -> Option<(u32, Option<u32>)> {
        match &self.now {
            Now::Timed(events, block) => {
                let (skip, _) = block.span();
                let (nx, nz) = block.events().delta();
                Some((
                    skip + events.done(),
                    Some(nx.unsigned_abs().max(nz.unsigned_abs())),
                ))
            }
            Now::Fixed(run) => Some((run.n, None)),
            Now::Idle => None,
        }
    }

    /// Reset: drops everything started at once, the hold with it; the
    /// registers keep the steps issued. Reports the block that was running.
    pub fn abort(&mut self) -> Aborted {
        let dropped = self.pending();
        let aborted = match (&self.now, self.running()) {
            (Now::Fixed(run), _) => Aborted {
                done: run.n,
                of: run.n + run.events.clone().count() as u32,
                dropped,
            },
            (_, Some((done, Some(of)))) => Aborted { done, of, dropped },
            _ => Aborted {
                done: 0,
                of: 0,
                dropped,
            },
        };
        self.ring.clear();
        self.now = Now::Idle;
        self.hold = Hold::Off;
        (self.retime, self.in_run, self.end, self.exit2) = (false, false, 0, 0);
        aborted
    }

    /// Records an event and moves the registers by its steps (a take-up's
    /// move the motors' lash instead).
    #[inline(always)]
    fn issue(&mut self, e: StepEvent, tick: u64, takeup: bool) -> Pulled {
        self.record.event(e, tick);
        let (dx, dz) = e.moves();
        self.last_takeup = takeup;
        if takeup {
            self.lash[0] += i32::from(dx);
            self.lash[1] += i32::from(dz);
        } else {
            self.issued.x.0 += i32::from(dx);
            self.issued.z.0 += i32::from(dz);
        }
        Pulled::Step(e, tick)
    }

    /// The registers of the steps issued.
    pub const fn issued(&self) -> ImpulsePoint {
        self.issued
    }

    /// The take-up steps issued, net, per axis (X, Z).
    pub const fn lash(&self) -> [i32; 2] {
        self.lash
    }

    /// Sets them, at rest (a reset, check mode's end).
    pub fn set_lash(&mut self, lash: [i32; 2]) {
        self.lash = lash;
    }

    /// The registers and the take-up steps without `e`, the event last
    /// pulled and not yet issued (a board that waits for its tick).
    pub fn issued_before(&self, e: StepEvent) -> (ImpulsePoint, [i32; 2]) {
        let (dx, dz) = e.moves();
        let (mut issued, mut lash) = (self.issued, self.lash);
        if self.last_takeup {
            lash[0] -= i32::from(dx);
            lash[1] -= i32::from(dz);
        } else {
            issued.x.0 -= i32::from(dx);
            issued.z.0 -= i32::from(dz);
        }
        (issued, lash)
    }

    /// Takes back `e`, the event last pulled: it was never issued (a reset
    /// came while it waited for its tick). The registers and the record
    /// no longer count it. At most once after a pull.
    pub fn take_back(&mut self, e: StepEvent) {
        (self.issued, self.lash) = self.issued_before(e);
        self.record.forget_last();
    }

    /// Sets the registers, at rest (`ZERO`, a price change).
    pub fn set_issued(&mut self, registers: ImpulsePoint) {
        self.issued = registers;
    }

    /// The record of what was handed out, as it stands.
    pub const fn record(&self) -> &Record {
        &self.record
    }

    /// Replaces the record (a reset: what was issued, not what was handed
    /// out ahead of it).
    pub fn set_record(&mut self, record: Record) {
        self.record = record;
    }

    /// What ran since the record last started again; it starts again.
    pub fn take_record(&mut self) -> Record {
        core::mem::take(&mut self.record)
    }

    /// Forgets what was recorded (`ZERO`).
    pub fn clear_record(&mut self) {
        self.record = Record::new();
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::impulse::{quantize, ImpulsePrice};
    use crate::length::Length;
    use crate::plan::{q32, Block, Planner, Rates, WINDOW};
    use crate::stepper::AxesState;
    use std::vec::Vec;

    /// A block along Z from `from_um` to `to_um` (µm), rapid or at a feed
    /// (mm/min), started alone.
    fn z_block(from_um: i64, to_um: i64, feed: Option<&str>) -> Started {
        let rates = Rates::DEFAULT;
        let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
        let (a, b) = (
            Length::from_um(from_um).unwrap(),
            Length::from_um(to_um).unwrap(),
        );
        let at = |z| ImpulsePoint {
            x: Impulses(0),
            z: quantize(z, h[1]).unwrap(),
        };
        let events = LinearBlock::new(at(a), at(b)).unwrap();
        let feed = feed.map(|f| crate::plan::Feed::new(Length::from_mm_str(f).unwrap()).unwrap());
        let block = Block::new([0, q32(a)], [0, q32(b)], events, feed, h, &rates).unwrap();
        let mut p = Planner::<WINDOW>::new(WINDOW);
        p.push(block, &rates).unwrap();
        p.start_block(&rates).unwrap()
    }

    #[test]
    fn a_block_comes_out_as_its_events_with_the_run_around_it() {
        let started = z_block(0, -2_000, None);
        let t = *started.timed();
        let mut s = Stepper::<AHEAD>::new();
        assert!(s.is_idle());
        for item in [
            Item::RunStart,
            Item::Block(started),
            Item::RunEnd(t.end_tick()),
        ] {
            s.push(item).unwrap();
        }
        assert!(!s.is_idle());
        let pulled: Vec<Pulled> = core::iter::from_fn(|| s.pull()).collect();
        let want: Vec<Pulled> = [Pulled::RunStart, Pulled::BlockStart(*t.block())]
            .into_iter()
            .chain(t.events().map(|(e, k)| Pulled::Step(e, k)))
            .chain([Pulled::RunEnd(t.end_tick())])
            .collect();
        assert_eq!(pulled, want);
        assert_eq!(pulled.len(), 200 + 3);
        assert!(s.is_idle());
        // Registers follow the steps: 2 mm along −Z at 0.01 mm.
        assert_eq!(s.issued().z, Impulses(-200));
        assert_eq!(s.issued().x, Impulses(0));
        let r = s.take_record();
        assert_eq!(r.events(), 200);
        assert_eq!(r.run_ticks(), t.end_tick());
        let mut again = Record::new();
        for (e, k) in t.events() {
            again.event(e, k);
        }
        assert_eq!(r.tseq(), again.tseq());
        assert_eq!(s.take_record().events(), 0);
    }

    #[test]
    fn a_direct_arc_is_a_run_of_its_own_and_ends_on_its_end_point() {
        use crate::arc::{ArcDir, ArcPoints, DirectArc};
        use crate::step::TickRate;
        let mm = |s| Length::from_mm_str(s).unwrap();
        let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
        // A quarter circle of 5 mm about (0, −5), from (5, −5) to (0, −10).
        let points = ArcPoints {
            start: [mm("5"), mm("-5")],
            end: [mm("0"), mm("-10")],
            centre: [mm("0"), mm("-5")],
        };
        let from = ImpulsePoint {
            x: Impulses(1000),
            z: Impulses(-500),
        };
        let arc = DirectArc::new(&points, ArcDir::Ccw, from, h[0], h[1]).unwrap();
        let n = arc.events().count() as u32;
        let rate = FixedRate::new(TickRate::TIMER, 50_000);
        let mut s = Stepper::<AHEAD>::new();
        s.set_issued(from);
        s.push(Item::Fixed(FixedRun::new(rate, arc.events())))
            .unwrap();
        let pulled: Vec<Pulled> = core::iter::from_fn(|| s.pull()).collect();
        assert_eq!(pulled.first(), Some(&Pulled::RunStart));
        assert_eq!(pulled.last(), Some(&Pulled::RunEnd(rate.tick(n))));
        let ticks: Vec<u64> = pulled
            .iter()
            .filter_map(|p| match p {
                Pulled::Step(_, t) => Some(*t),
                _ => None,
            })
            .collect();
        assert_eq!(ticks.len() as u32, n);
        assert!(ticks.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(ticks[0], 20); // 1 µs ticks at 50 000 events/s
        assert_eq!(s.issued(), arc.to());
        assert!(s.is_idle());
    }

    #[test]
    fn a_full_stepper_hands_the_item_back() {
        let mut s = Stepper::<2>::new();
        s.push(Item::RunStart).unwrap();
        s.push(Item::RunEnd(0)).unwrap();
        assert!(!s.has_room());
        assert!(matches!(s.push(Item::RunEnd(7)), Err(Item::RunEnd(7))));
        assert_eq!(s.pull(), Some(Pulled::RunStart));
        assert!(s.has_room());
        assert_eq!(s.waiting(), 1);
    }

    /// Pulls everything there is to pull; the step events.
    fn steps(s: &mut Stepper<AHEAD>) -> Vec<(u8, u64)> {
        core::iter::from_fn(|| s.pull())
            .filter_map(|p| match p {
                Pulled::Step(e, t) => Some((e.bits(), t)),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_hold_decelerates_along_the_path_and_a_resume_ends_where_the_block_ends() {
        let started = z_block(0, -20_000, Some("1200"));
        let planned: Vec<(u8, u64)> = started
            .timed()
            .events()
            .map(|(e, t)| (e.bits(), t))
            .collect();
        assert_eq!(planned.len(), 2000);
        let mut s = Stepper::<AHEAD>::new();
        for item in [
            Item::RunStart,
            Item::Block(started),
            Item::RunEnd(started.timed().end_tick()),
        ] {
            s.push(item).unwrap();
        }
        let mut before = Vec::new();
        while before.len() < 1000 {
            if let Some(Pulled::Step(e, t)) = s.pull() {
                before.push((e.bits(), t));
            }
        }
        assert_eq!(before[..], planned[..1000]);
        s.hold();
        assert_eq!(s.motion(), AxesState::Braking);
        let braking = steps(&mut s);
        assert_eq!(s.motion(), AxesState::Held);
        // 20 mm/s at 150 mm/s² stops in 4/3 mm: 133 events of 0.01 mm.
        assert_eq!(braking.len(), 133);
        assert_eq!(s.issued().z, Impulses(-1133));
        // Each event is later than planned, and at the f64 time of the
        // deceleration from the last event before the hold.
        let (v, a) = (20.0f64, 150.0f64);
        let t_j = v / (2.0 * a) + (999.5 * 0.01) / v;
        for (m, &(bits, tick)) in braking.iter().enumerate() {
            assert_eq!(bits, planned[1000 + m].0);
            assert!(tick > planned[1000 + m].1);
            let ds = (m + 1) as f64 * 0.01;
            let t = t_j + (v - libm::sqrt(v * v - 2.0 * a * ds)) / a;
            let want = libm::round(t * 1e6) as i64;
            assert!(
                (tick as i64 - want).abs() <= 1,
                "event {m}: {tick} vs {want}"
            );
        }
        assert!(braking
            .windows(3)
            .all(|w| w[2].1 - w[1].1 >= w[1].1 - w[0].1));
        let r = s.take_record();
        assert_eq!(r.events(), 1133);
        // Resume: a new run from rest to the block's end.
        assert_eq!(s.resume(), Some(Pulled::RunStart));
        let after = steps(&mut s);
        assert_eq!(after.len(), 2000 - 1133);
        assert_eq!(s.issued().z, Impulses(-2000));
        let all: Vec<u8> = before
            .iter()
            .chain(&braking)
            .chain(&after)
            .map(|e| e.0)
            .collect();
        let want: Vec<u8> = planned.iter().map(|e| e.0).collect();
        assert_eq!(all, want);
        assert!(after.windows(2).all(|w| w[0].1 < w[1].1));
        assert_eq!(s.motion(), AxesState::Idle);
        // From rest where the hold stopped (4/3 mm after event 1000's
        // boundary): the next boundary after √(2s/a).
        let ds = 1133.5 * 0.01 - (999.5 * 0.01 + v * v / (2.0 * a));
        let t1 = libm::sqrt(2.0 * ds / a);
        assert!((after[0].1 as i64 - libm::round(t1 * 1e6) as i64).abs() <= 1);
    }

    #[test]
    fn a_resume_while_braking_changes_nothing() {
        let started = z_block(0, -20_000, Some("1200"));
        let mut s = Stepper::<AHEAD>::new();
        for item in [
            Item::RunStart,
            Item::Block(started),
            Item::RunEnd(started.timed().end_tick()),
        ] {
            s.push(item).unwrap();
        }
        let mut n = 0;
        while n < 500 {
            if let Some(Pulled::Step(..)) = s.pull() {
                n += 1;
            }
        }
        s.hold();
        assert_eq!(s.motion(), AxesState::Braking);
        assert_eq!(s.resume(), None);
        assert_eq!(s.motion(), AxesState::Braking);
        let braking = steps(&mut s);
        assert_eq!(s.motion(), AxesState::Held);
        assert_eq!(s.resume(), Some(Pulled::RunStart));
        let after = steps(&mut s);
        // Every event of the block, none lost.
        assert_eq!(500 + braking.len() + after.len(), 2000);
        assert_eq!(s.issued().z, Impulses(-2000));
    }

    #[test]
    fn a_reset_drops_everything_and_keeps_the_registers_of_the_steps_issued() {
        let started = z_block(0, -20_000, Some("1200"));
        let mut s = Stepper::<AHEAD>::new();
        for item in [Item::RunStart, Item::Block(started), Item::RunEnd(0)] {
            s.push(item).unwrap();
        }
        let mut n = 0;
        while n < 700 {
            if let Some(Pulled::Step(..)) = s.pull() {
                n += 1;
            }
        }
        assert_eq!(
            s.abort(),
            Aborted {
                done: 700,
                of: 2000,
                dropped: true
            }
        );
        assert!(s.is_idle());
        assert_eq!(s.pull(), None);
        assert_eq!(s.issued().z, Impulses(-700));
    }
}

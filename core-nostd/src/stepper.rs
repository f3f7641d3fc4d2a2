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
use crate::step::{FixedRate, Record, TimedBlock, TimedEvents};
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
    Block(TimedBlock),
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

/// What is being issued.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
enum Now {
    Idle,
    Timed(TimedEvents),
    Fixed(FixedRun),
}

/// Started motion waiting and being issued, and what has been issued.
#[derive(Clone, Debug)]
pub struct Stepper<const R: usize> {
    ring: Deque<Item, R>,
    now: Now,
    record: Record,
    issued: ImpulsePoint,
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
        }
    }

    /// Whether another item fits.
    pub fn has_room(&self) -> bool {
        !self.ring.is_full()
    }

    /// Items waiting behind the one being issued.
    pub fn waiting(&self) -> usize {
        self.ring.len()
    }

    /// Whether nothing waits and nothing is being issued.
    pub fn is_idle(&self) -> bool {
        self.ring.is_empty() && matches!(self.now, Now::Idle)
    }

    /// Adds an item behind the others; a full stepper hands it back.
    #[allow(clippy::result_large_err)] // the item itself, as heapless does
    pub fn push(&mut self, item: Item) -> Result<(), Item> {
        self.ring.push_back(item)
    }

    /// The next thing to do: a run boundary, a block's start, or a step
    /// event with its tick (recorded and counted in the registers as it is
    /// handed out). `None` when nothing is started.
    #[inline]
    pub fn pull(&mut self) -> Option<Pulled> {
        loop {
            match &mut self.now {
                Now::Timed(events) => match events.next() {
                    Some((e, tick)) => return Some(self.issue(e, tick)),
                    None => self.now = Now::Idle,
                },
                Now::Fixed(run) => match run.events.next() {
                    Some(e) => {
                        run.n += 1;
                        let tick = run.rate.tick(run.n);
                        return Some(self.issue(e, tick));
                    }
                    None => {
                        let ticks = run.rate.tick(run.n);
                        let ended = run.n > 0;
                        self.now = Now::Idle;
                        if ended {
                            self.record.run_end(ticks);
                            return Some(Pulled::RunEnd(ticks));
                        }
                    }
                },
                Now::Idle => match self.ring.pop_front()? {
                    Item::RunStart => return Some(Pulled::RunStart),
                    Item::Block(b) => {
                        self.now = Now::Timed(b.events());
                        return Some(Pulled::BlockStart(*b.block()));
                    }
                    Item::Fixed(run) => {
                        // A run of its own; one without events is nothing.
                        let mut peek = run.events.clone();
                        let empty = peek.next().is_none();
                        self.now = Now::Fixed(run);
                        if !empty {
                            return Some(Pulled::RunStart);
                        }
                    }
                    Item::RunEnd(ticks) => {
                        self.record.run_end(ticks);
                        return Some(Pulled::RunEnd(ticks));
                    }
                },
            }
        }
    }

    /// Records an event and moves the registers by its steps.
    #[inline(always)]
    fn issue(&mut self, e: StepEvent, tick: u64) -> Pulled {
        self.record.event(e, tick);
        let (dx, dz) = e.moves();
        self.issued.x.0 += i32::from(dx);
        self.issued.z.0 += i32::from(dz);
        Pulled::Step(e, tick)
    }

    /// The registers of the steps issued.
    pub const fn issued(&self) -> ImpulsePoint {
        self.issued
    }

    /// Sets the registers, at rest (`ZERO`, a price change).
    pub fn set_issued(&mut self, registers: ImpulsePoint) {
        self.issued = registers;
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
    use std::vec::Vec;

    fn timed(from_um: i64, to_um: i64) -> TimedBlock {
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
        let block = Block::new([0, q32(a)], [0, q32(b)], events, None, h, &rates).unwrap();
        let mut p = Planner::<WINDOW>::new(WINDOW);
        p.push(block, &rates).unwrap();
        p.start(&rates).unwrap()
    }

    #[test]
    fn a_block_comes_out_as_its_events_with_the_run_around_it() {
        let t = timed(0, -2_000);
        let mut s = Stepper::<AHEAD>::new();
        assert!(s.is_idle());
        for item in [Item::RunStart, Item::Block(t), Item::RunEnd(t.end_tick())] {
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
}

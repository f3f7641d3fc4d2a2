//! The prep stage: started motion turned into ready events ahead of the
//! step interrupt, as grbl's segment buffer and Klipper's step compression
//! do it.
//!
//! A [`Prep`] wraps the [`Stepper`]: everything that computes (a block's
//! start, its ramps with their exact ticks, a hold's braking, a resume,
//! `TSEQ` and the registers) happens here, outside the step interrupt, and
//! each event goes into a bounded single-producer/single-consumer queue as
//! a [`Ready`] entry: its tick, its STEP/DIR bits and the CRC state `TSEQ`
//! has after it. The step interrupt pops an entry, writes the pins, arms
//! its next alarm and keeps what it issued in an [`Issued`]: no division,
//! no square root, no plan, no lock.
//!
//! What the protocol reports is what was issued: `SYNC`'s record and the
//! `STATUS` registers come from the [`Issued`] side, and a reset drops the
//! entries not yet issued and puts the stepper's registers and record back
//! to those of the events actually issued ([`Prep::abort`]). A feed hold
//! acts on the stepper, so it takes effect after the entries already
//! prepared: they are on the path, and the braking starts from the last of
//! them.

use crate::crc32::Crc32;
use crate::interleave::{ImpulsePoint, StepEvent};
use crate::step::Record;
use crate::stepper::{Aborted, Item, Motion, Pulled, Stepper, AHEAD};
use heapless::spsc::Producer;

/// Slots of the ready queue, a power of two; it holds one fewer entry.
///
/// 255 events are 1.3 ms at 200 000 events a second, 5.1 ms at the
/// default 50 000: more than the prep's longest step of work (a hold's
/// braking, some 67 000 instructions, 0.4 ms at 168 MHz), which is what
/// the step interrupt must be able to go on through.
pub const READY_SLOTS: usize = 256;

/// One ready entry for the step interrupt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ready {
    /// A step event.
    Step(ReadyStep),
    /// A run begins: its tick 0 is when the step interrupt comes to this.
    RunStart,
    /// A block begins (or what is left of one after a resume): the
    /// spindle speed it carries (10⁻³ rpm), and as a reset would report
    /// it, its events issued before this entry and all of them.
    Block {
        /// The spindle speed, 10⁻³ rpm.
        rpm: u32,
        /// Its events issued before.
        done: u32,
        /// All its events.
        of: u32,
    },
    /// A fixed-rate run's events follow (its length is asked of the
    /// stepper at a reset: counting it walks its events).
    Fixed,
    /// The run ended, this many ticks after it began.
    RunEnd {
        /// Ticks of the run.
        ticks: u64,
    },
}

/// A step event ready to issue.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReadyStep {
    /// Its tick in its run, modulo 2³² (the step interrupt adds it to the
    /// run's origin on a 32-bit counter).
    pub tick: u32,
    /// The STEP and DIR bits.
    pub event: StepEvent,
    /// `TSEQ`'s CRC state after this event.
    pub crc: Crc32,
}

/// What the step interrupt has issued: the registers, the record `SYNC`
/// reports, and the block running as a reset reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Issued {
    registers: ImpulsePoint,
    events: u64,
    crc: Crc32,
    run_ticks: u64,
    /// Events of the running block issued, and all of them (`None`: a
    /// fixed-rate run).
    done: u32,
    of: Option<u32>,
}

impl Default for Issued {
    fn default() -> Self {
        Self::new()
    }
}

impl Issued {
    /// Nothing issued, registers at 0.
    pub const fn new() -> Issued {
        Issued {
            registers: ImpulsePoint {
                x: crate::impulse::Impulses(0),
                z: crate::impulse::Impulses(0),
            },
            events: 0,
            crc: Crc32::new(),
            run_ticks: 0,
            done: 0,
            of: Some(0),
        }
    }

    /// A step event was issued: additions and copies only.
    #[inline(always)]
    pub fn step(&mut self, s: &ReadyStep) {
        let (dx, dz) = s.event.moves();
        self.registers.x.0 = self.registers.x.0.wrapping_add(i32::from(dx));
        self.registers.z.0 = self.registers.z.0.wrapping_add(i32::from(dz));
        self.events = self.events.wrapping_add(1);
        self.crc = s.crc;
        self.done = self.done.wrapping_add(1);
    }

    /// A mark other than a step passed the step interrupt.
    #[inline(always)]
    pub fn mark(&mut self, r: &Ready) {
        match *r {
            Ready::Block { done, of, .. } => (self.done, self.of) = (done, Some(of)),
            Ready::Fixed => (self.done, self.of) = (0, None),
            Ready::RunEnd { ticks } => (self.run_ticks, self.done, self.of) = (ticks, 0, Some(0)),
            Ready::RunStart | Ready::Step(_) => {}
        }
    }

    /// Applies any entry (a step or a mark), as the step interrupt does.
    #[inline(always)]
    pub fn apply(&mut self, r: &Ready) {
        match r {
            Ready::Step(s) => self.step(s),
            other => self.mark(other),
        }
    }

    /// The registers of the steps issued.
    pub const fn registers(&self) -> ImpulsePoint {
        self.registers
    }

    /// Sets them, at rest (`ZERO`, a price change).
    pub fn set_registers(&mut self, registers: ImpulsePoint) {
        self.registers = registers;
    }

    /// The record of what was issued since it was last taken.
    pub const fn record(&self) -> Record {
        Record::restore(self.events, self.crc, self.run_ticks)
    }

    /// Takes the record (`SYNC`); it starts again.
    pub fn take_record(&mut self) -> Record {
        let r = self.record();
        (self.events, self.crc, self.run_ticks) = (0, Crc32::new(), 0);
        r
    }
}

/// The stepper and the work of preparing its events.
#[derive(Clone, Debug, Default)]
pub struct Prep {
    stepper: Stepper<AHEAD>,
}

impl Prep {
    /// Nothing started.
    pub const fn new() -> Prep {
        Prep {
            stepper: Stepper::new(),
        }
    }

    /// The stepper (what is started and handed out).
    pub const fn stepper(&self) -> &Stepper<AHEAD> {
        &self.stepper
    }

    /// Adds started motion behind the rest; a full stepper hands it back.
    #[allow(clippy::result_large_err)] // the item itself, as heapless does
    pub fn push(&mut self, item: Item) -> Result<(), Item> {
        self.stepper.push(item)
    }

    /// Whether another item fits.
    pub fn has_room(&self) -> bool {
        self.stepper.has_room()
    }

    /// Whether it has work it could prepare (something started, not held).
    pub fn is_idle(&self) -> bool {
        self.stepper.is_idle()
    }

    /// Prepares events into `out` until it is full or nothing is left to
    /// prepare (or a hold holds it); returns the entries added.
    pub fn fill(&mut self, out: &mut Producer<'_, Ready>) -> usize {
        let mut n = 0;
        // One pull makes at most two entries.
        while out.capacity() - out.len() >= 2 {
            let Some(p) = self.stepper.pull() else { break };
            n += self.put(p, out);
        }
        n
    }

    /// The entries of one pull: a run's start carries what it starts (the
    /// rest of a held block, a fixed-rate run).
    fn put(&mut self, p: Pulled, out: &mut Producer<'_, Ready>) -> usize {
        let first = match p {
            Pulled::Step(event, tick) => Ready::Step(ReadyStep {
                tick: tick as u32,
                event,
                crc: self.stepper.crc(),
            }),
            Pulled::BlockStart(_) => self.running(),
            Pulled::RunStart => Ready::RunStart,
            Pulled::RunEnd(ticks) => Ready::RunEnd { ticks },
        };
        // `fill` and `resume` leave room for two.
        let _ = out.enqueue(first);
        if p != Pulled::RunStart || self.stepper.running().is_none() {
            return 1;
        }
        let _ = out.enqueue(self.running());
        2
    }

    /// The mark of the item the stepper runs now.
    fn running(&self) -> Ready {
        match self.stepper.running() {
            Some((done, Some(of))) => Ready::Block {
                rpm: self.stepper.spindle(),
                done,
                of,
            },
            Some((_, None)) => Ready::Fixed,
            None => Ready::Block {
                rpm: self.stepper.spindle(),
                done: 0,
                of: 0,
            },
        }
    }

    /// Feed hold: from the last event prepared (those in the queue are on
    /// the path and go first), the axes brake along the path to rest.
    pub fn hold(&mut self) {
        self.stepper.hold();
    }

    /// Resume after a hold: its run's start goes into `out` (which needs
    /// room for two entries: false, and nothing done, when it has not).
    pub fn resume(&mut self, out: &mut Producer<'_, Ready>) -> bool {
        if out.capacity() - out.len() < 2 {
            return false;
        }
        if let Some(p) = self.stepper.resume() {
            self.put(p, out);
        }
        true
    }

    /// What the axes are doing, as far as the prep knows: the step
    /// interrupt may still be issuing what it prepared.
    pub fn motion(&self) -> Motion {
        self.stepper.motion()
    }

    /// Whether every block started in an open run has been prepared: the
    /// planner should start the next one now.
    pub fn hungry(&self) -> bool {
        self.stepper.hungry()
    }

    /// Reset, once the step interrupt has stopped: `dropped` are the
    /// entries it had not issued, in order, and `issued` what it had. The
    /// stepper drops everything; its registers and record become those of
    /// the events issued. Reports the block that was running at the step
    /// interrupt.
    pub fn abort(
        &mut self,
        issued: &mut Issued,
        dropped: impl IntoIterator<Item = Ready>,
    ) -> Aborted {
        // Steps dropped before the first mark: the rest of the item the
        // step interrupt was issuing, if the mark ends it.
        let (mut before, mut marked) = (0u32, false);
        for r in dropped {
            match r {
                Ready::Step(_) if !marked => before += 1,
                Ready::Step(_) => {}
                _ => marked = true,
            }
        }
        let prepared = self.stepper.abort();
        let found = match issued.of {
            Some(of) => Aborted {
                done: issued.done,
                of,
            },
            // A fixed-rate run: its events issued, dropped, and those the
            // stepper had not handed out if it was still in it.
            None => {
                let left = if marked {
                    0
                } else {
                    prepared.of.saturating_sub(prepared.done)
                };
                Aborted {
                    done: issued.done,
                    of: issued.done.saturating_add(before).saturating_add(left),
                }
            }
        };
        self.stepper.set_issued(issued.registers);
        self.stepper.set_record(issued.record());
        (issued.done, issued.of) = (0, Some(0));
        found
    }

    /// Sets the registers, at rest (`ZERO`, a price change).
    pub fn set_issued(&mut self, registers: ImpulsePoint) {
        self.stepper.set_issued(registers);
    }

    /// Takes the stepper's record: it starts again with the issued side's
    /// ([`Issued::take_record`]), at rest.
    pub fn take_record(&mut self) -> Record {
        self.stepper.take_record()
    }

    /// The spindle speed of the block that started last (10⁻³ rpm).
    pub fn spindle(&self) -> u32 {
        self.stepper.spindle()
    }

    /// Sets it at rest.
    pub fn set_spindle(&mut self, milli_rpm: u32) {
        self.stepper.set_spindle(milli_rpm);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::impulse::{quantize, ImpulsePrice, Impulses};
    use crate::interleave::LinearBlock;
    use crate::length::Length;
    use crate::plan::Started;
    use crate::plan::{q32, Block, Planner, Rates, WINDOW};
    use crate::step::{FixedRate, TickRate};
    use crate::stepper::FixedRun;
    use heapless::spsc::Queue;
    use std::vec::Vec;

    /// Blocks along Z through the points `um` (µm), at a feed (mm/min) or
    /// rapid, planned together and started: a run's items.
    fn run(um: &[i64], feed: Option<&str>) -> Vec<Item> {
        let rates = Rates::DEFAULT;
        let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
        let at = |z| ImpulsePoint {
            x: Impulses(0),
            z: quantize(z, h[1]).unwrap(),
        };
        let feed = feed.map(|f| crate::plan::Feed::new(Length::from_mm_str(f).unwrap()).unwrap());
        let mut p = Planner::<WINDOW>::new(WINDOW);
        for w in um.windows(2) {
            let (a, b) = (
                Length::from_um(w[0]).unwrap(),
                Length::from_um(w[1]).unwrap(),
            );
            let events = LinearBlock::new(at(a), at(b)).unwrap();
            let block = Block::new([0, q32(a)], [0, q32(b)], events, feed, h, &rates).unwrap();
            p.push(block, &rates).unwrap();
        }
        let mut items = std::vec![Item::RunStart];
        let started: Vec<Started> = core::iter::from_fn(|| p.start_block(&rates)).collect();
        items.extend(started.into_iter().map(Item::Block));
        items.push(Item::RunEnd(p.end_run().unwrap()));
        items
    }

    /// A queue of `N` slots, filled and emptied as the prep and the step
    /// interrupt do, items handed over as room allows; `at(k, prep)` runs
    /// before the k-th entry is issued. Returns the entries issued.
    fn issue<const N: usize>(
        items: &[Item],
        prep: &mut Prep,
        issued: &mut Issued,
        mut at: impl FnMut(usize, &mut Prep, &mut Issued) -> bool,
    ) -> Vec<Ready> {
        let mut q: Queue<Ready, N> = Queue::new();
        let (mut tx, mut rx) = q.split();
        let mut items = items.iter().cloned();
        let mut out = Vec::new();
        loop {
            while prep.has_room() {
                match items.next() {
                    Some(i) => prep.push(i).unwrap(),
                    None => break,
                }
            }
            prep.fill(&mut tx);
            let Some(r) = rx.dequeue() else { break };
            issued.apply(&r);
            out.push(r);
            if !at(out.len(), prep, issued) {
                let dropped: Vec<Ready> = core::iter::from_fn(|| rx.dequeue()).collect();
                let _ = prep.abort(issued, dropped);
                break;
            }
        }
        out
    }

    /// What the stepper alone hands out for the same items.
    fn pulled(items: &[Item]) -> (Vec<Pulled>, Stepper<AHEAD>) {
        let mut s = Stepper::<AHEAD>::new();
        let mut out = Vec::new();
        for i in items {
            s.push(i.clone()).unwrap();
            out.extend(core::iter::from_fn(|| s.pull()));
        }
        (out, s)
    }

    fn steps(entries: &[Ready]) -> Vec<(u8, u32)> {
        entries
            .iter()
            .filter_map(|r| match r {
                Ready::Step(s) => Some((s.event.bits(), s.tick)),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn the_ready_events_are_what_the_stepper_hands_out_ticks_tseq_and_registers() {
        let items = run(&[0, -3_000, -3_500, -9_000, -9_100, -20_000], None);
        let (want, mut stepper) = pulled(&items);
        let (mut prep, mut issued) = (Prep::new(), Issued::new());
        let got = issue::<16>(&items, &mut prep, &mut issued, |_, _, _| true);
        let want_steps: Vec<(u8, u32)> = want
            .iter()
            .filter_map(|p| match p {
                Pulled::Step(e, t) => Some((e.bits(), *t as u32)),
                _ => None,
            })
            .collect();
        assert_eq!(steps(&got), want_steps);
        assert_eq!(want_steps.len(), 2000);
        // Run and block marks in the same places.
        let got_marks: Vec<&str> = got
            .iter()
            .filter_map(|r| match r {
                Ready::RunStart => Some("start"),
                Ready::Block { .. } => Some("block"),
                Ready::RunEnd { .. } => Some("end"),
                _ => None,
            })
            .collect();
        let want_marks: Vec<&str> = want
            .iter()
            .filter_map(|p| match p {
                Pulled::RunStart => Some("start"),
                Pulled::BlockStart(_) => Some("block"),
                Pulled::RunEnd(_) => Some("end"),
                _ => None,
            })
            .collect();
        assert_eq!(got_marks, want_marks);
        assert_eq!(issued.registers(), stepper.issued());
        let (a, b) = (issued.take_record(), stepper.take_record());
        assert_eq!(
            (a.events(), a.tseq(), a.run_ticks()),
            (b.events(), b.tseq(), b.run_ticks())
        );
        assert_eq!(prep.take_record().tseq(), b.tseq());
        assert!(prep.is_idle());
    }

    #[test]
    fn each_step_carries_tseq_as_it_stands_after_it() {
        let items = run(&[0, -1_000], Some("600"));
        let (mut prep, mut issued) = (Prep::new(), Issued::new());
        let mut record = Record::new();
        let got = issue::<8>(&items, &mut prep, &mut issued, |_, _, _| true);
        for r in &got {
            if let Ready::Step(s) = r {
                // The tick in the run is below 2³² here.
                record.event(s.event, u64::from(s.tick));
                assert_eq!(s.crc, record.crc());
            }
        }
        assert_eq!(issued.record().tseq(), record.tseq());
    }

    #[test]
    fn a_hold_takes_effect_after_the_entries_prepared_and_a_resume_ends_on_the_path() {
        let items = run(&[0, -20_000], Some("1200"));
        let (mut prep, mut issued) = (Prep::new(), Issued::new());
        // The hold comes when 1000 entries have been issued; up to 31
        // more are prepared and go first.
        let mut q: Queue<Ready, 32> = Queue::new();
        let (mut tx, mut rx) = q.split();
        for i in &items {
            prep.push(i.clone()).unwrap();
        }
        let mut got = Vec::new();
        while got.len() < 1000 {
            prep.fill(&mut tx);
            let r = rx.dequeue().unwrap();
            issued.apply(&r);
            got.push(r);
        }
        let prepared = rx.len();
        assert!(prepared > 20);
        // The stepper alone, held after the same events.
        let mut s = Stepper::<AHEAD>::new();
        for i in &items {
            s.push(i.clone()).unwrap();
        }
        let mut alone = Vec::new();
        while alone.len() < 1000 + prepared {
            alone.push(s.pull().unwrap());
        }
        s.hold();
        alone.extend(core::iter::from_fn(|| s.pull()));
        prep.hold();
        loop {
            prep.fill(&mut tx);
            let Some(r) = rx.dequeue() else { break };
            issued.apply(&r);
            got.push(r);
        }
        assert_eq!(prep.motion(), Motion::Held);
        let alone_steps: Vec<(u8, u32)> = alone
            .iter()
            .filter_map(|p| match p {
                Pulled::Step(e, t) => Some((e.bits(), *t as u32)),
                _ => None,
            })
            .collect();
        assert_eq!(steps(&got), alone_steps);
        assert!(matches!(got.last(), Some(Ready::RunEnd { .. })));
        assert_eq!(issued.registers(), s.issued());
        // Resume: the rest of the block, then the run's end, on its point.
        assert!(prep.resume(&mut tx));
        assert_eq!(rx.dequeue(), Some(Ready::RunStart));
        let mark = rx.dequeue().unwrap();
        let before = steps(&got).len() as u32;
        assert_eq!(
            mark,
            Ready::Block {
                rpm: 0,
                done: before,
                of: 2000
            }
        );
        issued.apply(&mark);
        loop {
            prep.fill(&mut tx);
            let Some(r) = rx.dequeue() else { break };
            issued.apply(&r);
        }
        assert_eq!(issued.registers().z, Impulses(-2000));
        assert_eq!(prep.motion(), Motion::Idle);
    }

    #[test]
    fn a_hold_at_rest_keeps_what_is_started_after_it_until_the_resume() {
        let (mut prep, mut issued) = (Prep::new(), Issued::new());
        prep.hold();
        let mut q: Queue<Ready, 32> = Queue::new();
        let (mut tx, mut rx) = q.split();
        for i in run(&[0, -1_000], None) {
            prep.push(i).unwrap();
        }
        assert_eq!(prep.fill(&mut tx), 0);
        assert_eq!(prep.motion(), Motion::Held);
        assert!(prep.resume(&mut tx));
        loop {
            prep.fill(&mut tx);
            let Some(r) = rx.dequeue() else { break };
            issued.apply(&r);
        }
        assert_eq!(issued.registers().z, Impulses(-100));
    }

    #[test]
    fn a_reset_counts_only_the_events_issued() {
        let items = run(&[0, -2_000, -5_000], Some("1200"));
        let (want, _) = pulled(&items);
        let positions: Vec<i32> = want
            .iter()
            .filter_map(|p| match p {
                Pulled::Step(e, _) => Some(i32::from(e.moves().1)),
                _ => None,
            })
            .scan(0, |z, d| {
                *z += d;
                Some(*z)
            })
            .collect();
        for stop in [1usize, 150, 203, 204, 260, 501, 503] {
            let (mut prep, mut issued) = (Prep::new(), Issued::new());
            let mut found = None;
            let got = issue::<64>(&items, &mut prep, &mut issued, |k, p, i| {
                if k < stop {
                    return true;
                }
                found = Some(*i);
                let _ = p;
                false
            });
            let n = steps(&got).len();
            let z = if n == 0 { 0 } else { positions[n - 1] };
            assert_eq!(issued.registers().z, Impulses(z), "stop {stop}");
            assert_eq!(prep.stepper().issued().z, Impulses(z));
            // SYNC after the reset: the events issued and their TSEQ.
            let mut record = Record::new();
            for r in &got {
                if let Ready::Step(s) = r {
                    record.event(s.event, u64::from(s.tick));
                }
            }
            let r = prep.take_record();
            assert_eq!((r.events(), r.tseq()), (n as u64, record.tseq()));
            assert!(prep.is_idle());
            let _ = found;
        }
    }

    #[test]
    fn a_reset_reports_the_block_the_step_interrupt_was_issuing() {
        // Blocks of 200 and 300 events; the queue holds 63 entries, so the
        // prep is in the second block while the first still issues.
        let items = run(&[0, -2_000, -5_000], Some("1200"));
        for (stop, want) in [
            (2 + 150, Aborted { done: 150, of: 200 }),
            (2 + 180, Aborted { done: 180, of: 200 }),
            (2 + 200 + 1 + 40, Aborted { done: 40, of: 300 }),
        ] {
            let (mut prep, mut issued) = (Prep::new(), Issued::new());
            let mut q: Queue<Ready, 64> = Queue::new();
            let (mut tx, mut rx) = q.split();
            let mut items = items.iter().cloned();
            let mut k = 0;
            let found = loop {
                while prep.has_room() {
                    match items.next() {
                        Some(i) => prep.push(i).unwrap(),
                        None => break,
                    }
                }
                prep.fill(&mut tx);
                let r = rx.dequeue().unwrap();
                issued.apply(&r);
                k += 1;
                if k == stop {
                    let dropped: Vec<Ready> = core::iter::from_fn(|| rx.dequeue()).collect();
                    break prep.abort(&mut issued, dropped);
                }
            };
            assert_eq!(found, want, "stop {stop}");
        }
    }

    #[test]
    fn a_reset_in_a_fixed_rate_run_counts_its_events() {
        use crate::arc::{ArcDir, ArcPoints, DirectArc};
        let mm = |s| Length::from_mm_str(s).unwrap();
        let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
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
        for (stop, queue_holds_the_end) in [(40usize, false), (n as usize - 5, true)] {
            let (mut prep, mut issued) = (Prep::new(), Issued::new());
            prep.set_issued(from);
            issued.set_registers(from);
            let mut q: Queue<Ready, 32> = Queue::new();
            let (mut tx, mut rx) = q.split();
            prep.push(Item::Fixed(FixedRun::new(rate, arc.events())))
                .unwrap();
            let mut k = 0;
            let found = loop {
                prep.fill(&mut tx);
                let r = rx.dequeue().unwrap();
                issued.apply(&r);
                if let Ready::Step(_) = r {
                    k += 1;
                }
                if k == stop {
                    let dropped: Vec<Ready> = core::iter::from_fn(|| rx.dequeue()).collect();
                    assert_eq!(
                        dropped.iter().any(|r| matches!(r, Ready::RunEnd { .. })),
                        queue_holds_the_end
                    );
                    break prep.abort(&mut issued, dropped);
                }
            };
            assert_eq!(
                found,
                Aborted {
                    done: stop as u32,
                    of: n
                }
            );
        }
    }
}

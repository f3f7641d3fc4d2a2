//! The prep stage: started motion turned into ready events ahead of the
//! step interrupt, as grbl's segment buffer and Klipper's step compression
//! do it.
//!
//! A [`Prep`] wraps the [`Stepper`]: everything that computes (a block's
//! start, its ramps with their exact ticks, a hold's braking, a resume,
//! `TSEQ` and the registers) happens here, outside the step interrupt, and
//! each event goes into a bounded single-producer/single-consumer queue as
//! a [`Ready`] entry of 8 bytes: its tick and its STEP/DIR bits, or a mark
//! (a run's start and end, a block's start). The step interrupt pops an
//! entry, writes the pins, arms its next alarm and counts the entries it
//! has passed: no division, no square root, no plan, no lock.
//!
//! What the protocol reports is what was issued. The prep keeps, beside
//! each entry in the queue, what will have been issued once the step
//! interrupt has passed it (registers, `SYNC`'s record with `TSEQ`, the
//! block running): [`Prep::issued`] reads it from the step interrupt's
//! count. A reset drops the entries not yet passed and puts the stepper's
//! registers and record back to those of the events actually issued
//! ([`Prep::abort`]). A feed hold
//! acts on the stepper, so it takes effect after the entries already
//! prepared: they are on the path, and the braking starts from the last of
//! them.

use crate::crc32::Crc32;
use crate::interleave::{ImpulsePoint, StepEvent};
use crate::step::Record;
use crate::stepper::{Aborted, AxesState, Item, Pulled, Stepper, AHEAD};
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// Slots of the ready queue, a power of two; it holds one fewer entry.
///
/// 255 events are 1.3 ms at 200 000 events a second, 5.1 ms at the
/// default 50 000: more than the prep's longest step of work (a hold's
/// braking, some 67 000 instructions, 0.4 ms at 168 MHz), which is what
/// the step interrupt must be able to go on through.
pub const READY_SLOTS: usize = 256;

/// One ready entry for the step interrupt: 8 bytes. What `SYNC`,
/// `STATUS` and a reset need of it stays with the prep ([`Prep::issued`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ready {
    /// A step event at its tick in its run, modulo 2³² (the step
    /// interrupt adds it to the run's origin on a 32-bit counter).
    Step {
        /// The tick.
        tick: u32,
        /// The STEP and DIR bits.
        event: StepEvent,
        /// The DIR line of one of its stepping axes changes: the drive's
        /// set-up time goes before it.
        turns: bool,
    },
    /// A run begins: its tick 0 is when the step interrupt comes to this.
    RunStart,
    /// A block begins: the spindle speed it carries (10⁻³ rpm).
    Block {
        /// The spindle speed, 10⁻³ rpm.
        rpm: u32,
    },
    /// The run ended: the axes are at rest.
    RunEnd,
}

impl Ready {
    const STEP: u32 = 0;
    const RUN_START: u32 = 1 << 8;
    const BLOCK: u32 = 2 << 8;
    const RUN_END: u32 = 3 << 8;
    /// In an entry's second word ([`ReadyRx::take_words`]): not a step
    /// when any of these bits is set.
    pub const KIND: u32 = 0xFF00;
    /// In a step's second word: its DIR changes.
    pub const TURNS: u32 = 1 << 4;
    /// In a step's second word: its STEP and DIR bits.
    pub const BITS: u32 = 0x0F;

    /// An entry from its two words ([`ReadyRx::take_words`]).
    #[inline(always)]
    pub const fn from_parts(w0: u32, w1: u32) -> Ready {
        Self::from_words(w0, w1)
    }

    /// As two words: the tick or the speed, and the kind with the bits.
    #[inline(always)]
    const fn words(self) -> (u32, u32) {
        match self {
            Ready::Step { tick, event, turns } => (
                tick,
                Self::STEP | event.bits() as u32 | if turns { Self::TURNS } else { 0 },
            ),
            Ready::RunStart => (0, Self::RUN_START),
            Ready::Block { rpm } => (rpm, Self::BLOCK),
            Ready::RunEnd => (0, Self::RUN_END),
        }
    }

    #[inline(always)]
    const fn from_words(w0: u32, w1: u32) -> Ready {
        match w1 & 0xFF00 {
            Self::STEP => Ready::Step {
                tick: w0,
                event: StepEvent::from_bits(w1 as u8 & 0x0F),
                turns: w1 & Self::TURNS != 0,
            },
            Self::RUN_START => Ready::RunStart,
            Self::BLOCK => Ready::Block { rpm: w0 },
            _ => Ready::RunEnd,
        }
    }
}

/// The ready queue: [`READY_SLOTS`] slots of two words, a ring between
/// one producer (the prep) and one consumer (the step interrupt), both
/// lock-free: each side writes only its own index, the slots are
/// published by the producer's index (release) and freed by the
/// consumer's. Atomics only, so it can be a `static`; the index wraps with
/// a mask, no division.
pub struct ReadyQueue {
    slots: [[AtomicU32; 2]; READY_SLOTS],
    /// Entries taken (the consumer's), and entries put (the producer's),
    /// both since the queue was made, wrapping.
    head: AtomicU32,
    tail: AtomicU32,
    split: AtomicBool,
}

impl Default for ReadyQueue {
    fn default() -> Self {
        Self::new()
    }
}

impl ReadyQueue {
    /// An empty queue.
    pub const fn new() -> ReadyQueue {
        #[allow(clippy::declare_interior_mutable_const)] // only as a pattern to fill the array
        const SLOT: [AtomicU32; 2] = [AtomicU32::new(0), AtomicU32::new(0)];
        ReadyQueue {
            slots: [SLOT; READY_SLOTS],
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
            split: AtomicBool::new(false),
        }
    }

    /// Entries it can hold: two fewer than its slots, so that what was
    /// issued after the two entries taken last stays in the prep's
    /// history while the step interrupt holds the second for its tick
    /// (see [`Prep`]).
    pub const CAPACITY: u32 = READY_SLOTS as u32 - 2;

    /// Its two ends, once: later calls get `None`.
    pub fn split(&self) -> Option<(ReadyTx<'_>, ReadyRx<'_>)> {
        if self.split.swap(true, Ordering::AcqRel) {
            return None;
        }
        Some((ReadyTx { q: self }, ReadyRx { q: self }))
    }

    #[inline(always)]
    fn slot(&self, k: u32) -> &[AtomicU32; 2] {
        // READY_SLOTS is a power of two: the mask keeps the index in range.
        &self.slots[k as usize & (READY_SLOTS - 1)]
    }

    /// Entries in it.
    #[inline(always)]
    pub fn len(&self) -> u32 {
        self.tail
            .load(Ordering::Acquire)
            .wrapping_sub(self.head.load(Ordering::Acquire))
    }

    /// Whether it is empty.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Entries taken from it since it was made (wrapping): the step
    /// interrupt's progress, which a supervisor can watch.
    #[inline(always)]
    pub fn taken(&self) -> u32 {
        self.head.load(Ordering::Acquire)
    }
}

/// On a single-core microcontroller (bare-metal ARM: the Cortex-M4) the
/// two ends are the prep and the step interrupt on one core, which sees its
/// own memory accesses in program order: the compiler must keep the order,
/// no barrier instruction is needed. Elsewhere (threads on a host) the
/// atomics order them.
#[cfg(all(target_arch = "arm", target_os = "none"))]
const SINGLE_CORE_ACQUIRE: Ordering = Ordering::Relaxed;
#[cfg(all(target_arch = "arm", target_os = "none"))]
const SINGLE_CORE_RELEASE: Ordering = Ordering::Relaxed;
#[cfg(not(all(target_arch = "arm", target_os = "none")))]
const SINGLE_CORE_ACQUIRE: Ordering = Ordering::Acquire;
#[cfg(not(all(target_arch = "arm", target_os = "none")))]
const SINGLE_CORE_RELEASE: Ordering = Ordering::Release;

/// A compiler fence where [`SINGLE_CORE_ACQUIRE`] is relaxed.
#[inline(always)]
fn single_core_fence(order: Ordering) {
    if cfg!(all(target_arch = "arm", target_os = "none")) {
        core::sync::atomic::compiler_fence(order);
    }
}

/// The producer's end of a [`ReadyQueue`].
pub struct ReadyTx<'a> {
    q: &'a ReadyQueue,
}

impl ReadyTx<'_> {
    /// Whether an entry fits.
    #[inline(always)]
    pub fn ready(&self) -> bool {
        self.q.len() < ReadyQueue::CAPACITY
    }

    /// Entries in the queue.
    pub fn len(&self) -> u32 {
        self.q.len()
    }

    /// Whether the queue is empty.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Puts an entry behind the others; a full queue hands it back.
    #[inline(always)]
    pub fn enqueue(&mut self, r: Ready) -> Result<(), Ready> {
        if !self.ready() {
            return Err(r);
        }
        let tail = self.q.tail.load(Ordering::Relaxed);
        let (w0, w1) = r.words();
        let slot = self.q.slot(tail);
        slot[0].store(w0, Ordering::Relaxed);
        slot[1].store(w1, Ordering::Relaxed);
        self.q.tail.store(tail.wrapping_add(1), Ordering::Release);
        Ok(())
    }
}

/// The consumer's end of a [`ReadyQueue`].
pub struct ReadyRx<'a> {
    q: &'a ReadyQueue,
}

impl ReadyRx<'_> {
    /// The first entry, left in the queue.
    #[inline(always)]
    pub fn peek(&self) -> Option<Ready> {
        let head = self.q.head.load(Ordering::Relaxed);
        if self.q.tail.load(Ordering::Acquire) == head {
            return None;
        }
        let slot = self.q.slot(head);
        Some(Ready::from_words(
            slot[0].load(Ordering::Relaxed),
            slot[1].load(Ordering::Relaxed),
        ))
    }

    /// Frees the first entry (after [`ReadyRx::peek`] found one).
    #[inline(always)]
    pub fn pop(&mut self) {
        let head = self.q.head.load(Ordering::Relaxed);
        if self.q.tail.load(Ordering::Relaxed) != head {
            self.q.head.store(head.wrapping_add(1), Ordering::Release);
        }
    }

    /// Takes the first entry as its two words (a step: its tick, and its
    /// bits with [`Ready::TURNS`]; a mark has a bit of [`Ready::KIND`]
    /// set), with the count of entries taken after it: the step
    /// interrupt's way, which decodes only what it needs.
    #[inline(always)]
    pub fn take_words(&mut self) -> Option<(u32, u32, u32)> {
        let head = self.q.head.load(Ordering::Relaxed);
        if self.q.tail.load(SINGLE_CORE_ACQUIRE) == head {
            return None;
        }
        single_core_fence(Ordering::Acquire);
        let slot = self.q.slot(head);
        let (w0, w1) = (
            slot[0].load(Ordering::Relaxed),
            slot[1].load(Ordering::Relaxed),
        );
        let head = head.wrapping_add(1);
        single_core_fence(Ordering::Release);
        self.q.head.store(head, SINGLE_CORE_RELEASE);
        Some((w0, w1, head))
    }

    /// Takes the first entry.
    #[inline(always)]
    pub fn dequeue(&mut self) -> Option<Ready> {
        let r = self.peek()?;
        self.pop();
        Some(r)
    }

    /// Entries taken since the queue was made (wrapping).
    #[inline(always)]
    pub fn taken(&self) -> u32 {
        self.q.head.load(Ordering::Relaxed)
    }

    /// Entries in the queue.
    pub fn len(&self) -> u32 {
        self.q.len()
    }

    /// Whether the queue is empty.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }
}

/// What the step interrupt has issued once it has passed a given entry:
/// the registers, the record `SYNC` reports, and the block running as a
/// reset reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Issued {
    registers: ImpulsePoint,
    /// Backlash take-up steps issued, net, per axis.
    lash: [i32; 2],
    events: u64,
    crc: Crc32,
    run_ticks: u64,
    /// Events of the running block issued, and all of them (`u32::MAX`:
    /// a fixed-rate run, counted at a reset).
    done: u32,
    of: u32,
}

impl Default for Issued {
    fn default() -> Self {
        Self::new()
    }
}

/// `Issued::of` of a fixed-rate run.
const FIXED: u32 = u32::MAX;

impl Issued {
    /// Nothing issued, registers at 0.
    pub const fn new() -> Issued {
        Issued {
            registers: ImpulsePoint {
                x: crate::impulse::Impulses(0),
                z: crate::impulse::Impulses(0),
            },
            lash: [0, 0],
            events: 0,
            crc: Crc32::new(),
            run_ticks: 0,
            done: 0,
            of: 0,
        }
    }

    /// The registers of the steps issued.
    pub const fn registers(&self) -> ImpulsePoint {
        self.registers
    }

    /// The backlash take-up steps issued, net, per axis.
    pub const fn lash(&self) -> [i32; 2] {
        self.lash
    }

    /// The record of what was issued since it was last taken.
    pub const fn record(&self) -> Record {
        Record::restore(self.events, self.crc, self.run_ticks)
    }
}

/// The stepper, the work of preparing its events, and what the step
/// interrupt has issued after each entry still in the queue (or just
/// taken from it).
#[derive(Clone, Debug)]
pub struct Prep {
    stepper: Stepper<AHEAD>,
    /// What was issued after entry `k`, at `k mod READY_SLOTS`: written
    /// as the entry is pushed, read once the step interrupt has passed
    /// it. The queue holds fewer than `READY_SLOTS` entries, so the slot
    /// of the entry passed last is not written again until it passes the
    /// next one.
    history: [Issued; READY_SLOTS],
    /// Entries pushed since power-on (wrapping).
    pushed: u32,
    /// What was issued when the step interrupt had passed `base.0`
    /// entries and nothing had been pushed since (a reset, `ZERO`,
    /// `SYNC`).
    base: (u32, Issued),
    /// The DIR lines (negative) as the events prepared leave them, X
    /// and Z; unknown at first and after a reset.
    dirs: [Option<bool>; 2],
}

impl Default for Prep {
    fn default() -> Self {
        Self::new()
    }
}

impl Prep {
    /// Nothing started.
    pub const fn new() -> Prep {
        Prep {
            stepper: Stepper::new(),
            history: [Issued::new(); READY_SLOTS],
            pushed: 0,
            base: (0, Issued::new()),
            dirs: [None; 2],
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

    /// Whether nothing is started or being prepared (a hold keeps what it
    /// stopped).
    pub fn is_idle(&self) -> bool {
        self.stepper.is_idle()
    }

    /// Whether anything taken is still to be issued, a hold's rest
    /// included (see [`Stepper::pending`]).
    pub fn pending(&self) -> bool {
        self.stepper.pending()
    }

    /// Entries pushed since power-on (wrapping): the step interrupt has
    /// passed them all when its own count equals this.
    pub const fn pushed(&self) -> u32 {
        self.pushed
    }

    /// Prepares events into `out` until it is full or nothing is left to
    /// prepare (or a hold holds it); returns the entries added.
    pub fn fill(&mut self, out: &mut ReadyTx<'_>) -> usize {
        let mut n = 0;
        while out.ready() {
            let Some(p) = self.stepper.pull() else { break };
            self.put(p, out);
            n += 1;
        }
        n
    }

    /// The entry of one pull, and what will have been issued after it.
    fn put(&mut self, p: Pulled, out: &mut ReadyTx<'_>) {
        let entry = match p {
            Pulled::Step(event, tick) => {
                let mut turns = false;
                for (axis, steps, neg) in [
                    (0, event.x_steps(), event.x_negative()),
                    (1, event.z_steps(), event.z_negative()),
                ] {
                    if let (true, Some(dir)) = (steps, self.dirs.get_mut(axis)) {
                        turns |= *dir != Some(neg);
                        *dir = Some(neg);
                    }
                }
                Ready::Step {
                    tick: tick as u32,
                    event,
                    turns,
                }
            }
            Pulled::BlockStart(_) => Ready::Block {
                rpm: self.stepper.spindle(),
            },
            Pulled::RunStart => Ready::RunStart,
            Pulled::RunEnd(_) => Ready::RunEnd,
        };
        let s = &self.stepper;
        let record = s.record();
        let (done, of) = match s.running() {
            Some((done, of)) => (done, of.unwrap_or(FIXED)),
            None => (0, 0),
        };
        let after = Issued {
            registers: s.issued(),
            lash: s.lash(),
            events: record.events(),
            crc: record.crc(),
            run_ticks: record.run_ticks(),
            done,
            of,
        };
        if let Some(slot) = self.history.get_mut(self.pushed as usize % READY_SLOTS) {
            *slot = after;
        }
        self.pushed = self.pushed.wrapping_add(1);
        // The callers checked for room.
        let _ = out.enqueue(entry);
    }

    /// What was issued once the step interrupt has passed `passed`
    /// entries since power-on (its own count, at most [`Prep::pushed`]).
    pub fn issued(&self, passed: u32) -> Issued {
        if passed == self.base.0 {
            return self.base.1;
        }
        let k = passed.wrapping_sub(1) as usize % READY_SLOTS;
        self.history.get(k).copied().unwrap_or(self.base.1)
    }

    /// Feed hold: from the last event prepared (those in the queue are on
    /// the path and go first), the axes brake along the path to rest.
    pub fn hold(&mut self) {
        self.stepper.hold();
    }

    /// Resume after a hold: its run's start goes into `out` (false, and
    /// nothing done, when it has no room).
    pub fn resume(&mut self, out: &mut ReadyTx<'_>) -> bool {
        if !out.ready() {
            return false;
        }
        if let Some(p) = self.stepper.resume() {
            self.put(p, out);
        }
        true
    }

    /// What the axes are doing, as far as the prep knows: the step
    /// interrupt may still be issuing what it prepared.
    pub fn motion(&self) -> AxesState {
        self.stepper.motion()
    }

    /// Whether every block started in an open run has been prepared: the
    /// planner should start the next one now.
    pub fn hungry(&self) -> bool {
        self.stepper.hungry()
    }

    /// Reset, once the step interrupt has stopped: it had passed `passed`
    /// entries, and `dropped` are those it had not, in order (it has
    /// taken them all from the queue). The stepper
    /// drops everything; its registers and record become those of the
    /// events issued. Reports the block that was running at the step
    /// interrupt.
    pub fn abort(&mut self, passed: u32, dropped: impl IntoIterator<Item = Ready>) -> Aborted {
        let issued = self.issued(passed);
        // Steps dropped before the first mark: the rest of the item the
        // step interrupt was issuing, if the mark ends it.
        let (mut before, mut marked, mut steps) = (0u32, false, false);
        for r in dropped {
            match r {
                Ready::Step { .. } if !marked => (before, steps) = (before + 1, true),
                Ready::Step { .. } => steps = true,
                _ => marked = true,
            }
        }
        let prepared = self.stepper.abort();
        // Motion dropped: a step prepared and not issued, or what the
        // stepper had not prepared yet (items, a block, a hold's rest).
        let dropped = steps || prepared.dropped;
        let found = if issued.of != FIXED {
            Aborted {
                done: issued.done,
                of: issued.of,
                dropped,
            }
        } else {
            // A fixed-rate run: its events issued, dropped, and those the
            // stepper had not handed out if it was still in it.
            let left = if marked {
                0
            } else {
                prepared.of.saturating_sub(prepared.done)
            };
            Aborted {
                done: issued.done,
                of: issued.done.saturating_add(before).saturating_add(left),
                dropped,
            }
        };
        self.stepper.set_issued(issued.registers);
        self.stepper.set_lash(issued.lash);
        self.stepper.set_record(issued.record());
        // What the dropped entries would have set is unknown to the pins.
        self.dirs = [None; 2];
        // The step interrupt has taken every entry pushed: dropped ones
        // count as passed from now on.
        self.base = (
            self.pushed,
            Issued {
                done: 0,
                of: 0,
                ..issued
            },
        );
        found
    }

    /// Sets the registers, at rest (`ZERO`, a price change): the step
    /// interrupt has passed `passed` entries, all there were.
    pub fn set_issued(&mut self, passed: u32, registers: ImpulsePoint) {
        self.stepper.set_issued(registers);
        let mut base = self.issued(passed);
        base.registers = registers;
        self.base = (passed, base);
    }

    /// Takes the record of what was issued (`SYNC`), at rest: the step
    /// interrupt has passed `passed` entries, all there were. Both records
    /// start again.
    pub fn take_record(&mut self, passed: u32) -> Record {
        let _ = self.stepper.take_record();
        let mut base = self.issued(passed);
        let record = base.record();
        (base.events, base.crc, base.run_ticks) = (0, Crc32::new(), 0);
        self.base = (passed, base);
        record
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

    /// The prep and a queue of `N` slots filled and emptied as the step
    /// interrupt empties it, items handed over as room allows.
    struct Bench<'q, I: Iterator<Item = Item>> {
        prep: Prep,
        tx: ReadyTx<'q>,
        rx: ReadyRx<'q>,
        /// Entries the queue may hold here (fewer than it can).
        room: u32,
        items: I,
        /// Entries the step interrupt passed, and those it took.
        passed: u32,
        taken: Vec<Ready>,
    }

    impl<I: Iterator<Item = Item>> Bench<'_, I> {
        /// The step interrupt takes one entry, if there is one.
        fn issue(&mut self) -> Option<Ready> {
            while self.prep.has_room() {
                match self.items.next() {
                    Some(i) => self.prep.push(i).unwrap(),
                    None => break,
                }
            }
            // Only `room` entries: the prep stops where a smaller queue
            // would be full.
            while self.tx.len() < self.room {
                let before = self.tx.len();
                self.fill_one();
                if self.tx.len() == before {
                    break;
                }
            }
            let r = self.rx.dequeue()?;
            self.passed += 1;
            self.taken.push(r);
            Some(r)
        }

        /// The prep's work for one more entry.
        fn fill_one(&mut self) {
            if let Some(p) = self.prep.stepper.pull() {
                self.prep.put(p, &mut self.tx);
            }
        }

        fn issued(&self) -> Issued {
            self.prep.issued(self.passed)
        }

        /// A reset now.
        fn abort(&mut self) -> Aborted {
            let dropped: Vec<Ready> = core::iter::from_fn(|| self.rx.dequeue()).collect();
            let found = self.prep.abort(self.passed, dropped.iter().copied());
            self.passed += dropped.len() as u32;
            found
        }
    }

    fn bench<I: Iterator<Item = Item>>(q: &ReadyQueue, room: u32, items: I) -> Bench<'_, I> {
        let (tx, rx) = q.split().unwrap();
        Bench {
            prep: Prep::new(),
            tx,
            rx,
            room,
            items,
            passed: 0,
            taken: Vec::new(),
        }
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
                Ready::Step { tick, event, .. } => Some((event.bits(), *tick)),
                _ => None,
            })
            .collect()
    }

    fn pulled_steps(p: &[Pulled]) -> Vec<(u8, u32)> {
        p.iter()
            .filter_map(|p| match p {
                Pulled::Step(e, t) => Some((e.bits(), *t as u32)),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn the_ready_events_are_what_the_stepper_hands_out_and_what_was_issued_follows_them() {
        let items = run(&[0, -3_000, -3_500, -9_000, -9_100, -20_000], None);
        let (want, mut stepper) = pulled(&items);
        let q = ReadyQueue::new();
        let mut b = bench(&q, 15, items.iter().cloned());
        // After every entry: the registers and the record of the steps
        // taken so far, as a stepper that handed out only those has them.
        let mut alone = Stepper::<AHEAD>::new();
        let mut alone_items = items.iter().cloned();
        while let Some(r) = b.issue() {
            let p = loop {
                if let Some(p) = alone.pull() {
                    break p;
                }
                alone.push(alone_items.next().unwrap()).unwrap();
            };
            let kind = |r: &Ready| core::mem::discriminant(r);
            let turns = matches!(r, Ready::Step { turns: true, .. });
            let as_ready = match p {
                Pulled::Step(event, tick) => Ready::Step {
                    tick: tick as u32,
                    event,
                    turns,
                },
                Pulled::RunStart => Ready::RunStart,
                Pulled::BlockStart(_) => Ready::Block { rpm: 0 },
                Pulled::RunEnd(_) => Ready::RunEnd,
            };
            assert_eq!(kind(&r), kind(&as_ready));
            assert_eq!(r, as_ready);
            let i = b.issued();
            assert_eq!(i.registers(), alone.issued());
            let (x, y) = (i.record(), alone.record());
            assert_eq!(
                (x.events(), x.tseq(), x.run_ticks()),
                (y.events(), y.tseq(), y.run_ticks())
            );
        }
        assert_eq!(steps(&b.taken), pulled_steps(&want));
        assert_eq!(steps(&b.taken).len(), 2000);
        assert_eq!(b.issued().registers(), stepper.issued());
        let r = b.prep.take_record(b.passed);
        let w = stepper.take_record();
        assert_eq!(
            (r.events(), r.tseq(), r.run_ticks()),
            (w.events(), w.tseq(), w.run_ticks())
        );
        assert_eq!(b.issued().record().events(), 0);
        assert!(b.prep.is_idle());
    }

    #[test]
    fn a_hold_takes_effect_after_the_entries_prepared_and_a_resume_ends_on_the_path() {
        let items = run(&[0, -20_000], Some("1200"));
        let q = ReadyQueue::new();
        let mut b = bench(&q, 31, items.iter().cloned());
        // The hold comes when 1000 entries have been taken; up to 31 more
        // are prepared and go first.
        while b.passed < 1000 {
            b.issue().unwrap();
        }
        let prepared = b.rx.len();
        assert!(prepared > 20);
        // The stepper alone, held after the same entries.
        let mut s = Stepper::<AHEAD>::new();
        for i in &items {
            s.push(i.clone()).unwrap();
        }
        let mut alone = Vec::new();
        while alone.len() < 1000 + prepared as usize {
            alone.push(s.pull().unwrap());
        }
        s.hold();
        alone.extend(core::iter::from_fn(|| s.pull()));
        b.prep.hold();
        while b.issue().is_some() {}
        assert_eq!(b.prep.motion(), AxesState::Held);
        assert_eq!(steps(&b.taken), pulled_steps(&alone));
        assert_eq!(b.taken.last(), Some(&Ready::RunEnd));
        assert_eq!(b.issued().registers(), s.issued());
        assert_eq!(b.issued().record().tseq(), s.record().tseq());
        // Resume: the rest of the block, then the run's end, on its point.
        assert!(b.prep.resume(&mut b.tx));
        assert_eq!(b.issue(), Some(Ready::RunStart));
        while b.issue().is_some() {}
        assert_eq!(b.issued().registers().z, Impulses(-2000));
        assert_eq!(steps(&b.taken).len(), 2000);
        assert_eq!(b.prep.motion(), AxesState::Idle);
    }

    #[test]
    fn a_hold_at_rest_keeps_what_is_started_after_it_until_the_resume() {
        let q = ReadyQueue::new();
        let mut b = bench(&q, 31, run(&[0, -1_000], None).into_iter());
        b.prep.hold();
        assert_eq!(b.issue(), None);
        assert_eq!(b.prep.motion(), AxesState::Held);
        assert!(b.prep.resume(&mut b.tx));
        while b.issue().is_some() {}
        assert_eq!(b.issued().registers().z, Impulses(-100));
        assert_eq!(b.prep.motion(), AxesState::Idle);
    }

    #[test]
    fn a_reset_counts_only_the_events_issued() {
        let items = run(&[0, -2_000, -5_000], Some("1200"));
        let (want, _) = pulled(&items);
        let positions: Vec<i32> = pulled_steps(&want)
            .iter()
            .map(|&(bits, _)| i32::from(StepEvent::from_bits(bits).moves().1))
            .scan(0, |z, d| {
                *z += d;
                Some(*z)
            })
            .collect();
        for stop in [1u32, 150, 203, 204, 260, 501, 503] {
            let q = ReadyQueue::new();
            let mut b = bench(&q, 63, items.iter().cloned());
            while b.passed < stop {
                b.issue().unwrap();
            }
            let _ = b.abort();
            let n = steps(&b.taken).len();
            let z = if n == 0 { 0 } else { positions[n - 1] };
            assert_eq!(b.issued().registers().z, Impulses(z), "stop {stop}");
            assert_eq!(b.prep.stepper().issued().z, Impulses(z));
            // SYNC after the reset: the events issued and their TSEQ.
            let mut record = Record::new();
            for (bits, tick) in steps(&b.taken) {
                record.event(StepEvent::from_bits(bits), u64::from(tick));
            }
            let r = b.prep.take_record(b.passed);
            assert_eq!((r.events(), r.tseq()), (n as u64, record.tseq()));
            assert!(b.prep.is_idle());
            // The next run counts on from there.
            assert_eq!(b.prep.pushed(), b.passed);
        }
    }

    #[test]
    fn a_reset_reports_the_block_the_step_interrupt_was_issuing() {
        // Blocks of 200 and 300 events; the queue holds 63 entries, so the
        // prep is in the second block while the first still issues.
        let items = run(&[0, -2_000, -5_000], Some("1200"));
        for (stop, want) in [
            (
                2,
                Aborted {
                    done: 0,
                    of: 200,
                    dropped: true,
                },
            ),
            (
                2 + 150,
                Aborted {
                    done: 150,
                    of: 200,
                    dropped: true,
                },
            ),
            (
                2 + 180,
                Aborted {
                    done: 180,
                    of: 200,
                    dropped: true,
                },
            ),
            (
                2 + 200,
                Aborted {
                    done: 200,
                    of: 200,
                    dropped: true,
                },
            ),
            (
                2 + 200 + 1 + 40,
                Aborted {
                    done: 40,
                    of: 300,
                    dropped: true,
                },
            ),
            (
                2 + 200 + 1 + 300 + 1,
                Aborted {
                    done: 0,
                    of: 0,
                    dropped: false,
                },
            ),
        ] {
            let q = ReadyQueue::new();
            let mut b = bench(&q, 63, items.iter().cloned());
            while b.passed < stop {
                b.issue().unwrap();
            }
            assert_eq!(b.abort(), want, "stop {stop}");
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
            let q = ReadyQueue::new();
            let item = Item::Fixed(FixedRun::new(rate, arc.events()));
            let mut b = bench(&q, 31, core::iter::once(item));
            b.prep.set_issued(0, from);
            while steps(&b.taken).len() < stop {
                b.issue().unwrap();
            }
            let ends = {
                // What the queue holds, dropped by the reset.
                let mut q2 = Vec::new();
                while let Some(r) = b.rx.dequeue() {
                    q2.push(r);
                }
                let ends = q2.contains(&Ready::RunEnd);
                let found = b.prep.abort(b.passed, q2.iter().copied());
                b.passed += q2.len() as u32;
                assert_eq!(
                    found,
                    Aborted {
                        done: stop as u32,
                        of: n,
                        dropped: true
                    }
                );
                ends
            };
            assert_eq!(ends, queue_holds_the_end);
            assert_eq!(b.issued().registers(), {
                let mut p = from;
                for (bits, _) in steps(&b.taken) {
                    let (dx, dz) = StepEvent::from_bits(bits).moves();
                    p.x.0 += i32::from(dx);
                    p.z.0 += i32::from(dz);
                }
                p
            });
        }
    }

    #[test]
    fn the_ready_queue_holds_two_fewer_than_its_slots_and_wraps() {
        let q = ReadyQueue::new();
        let (mut tx, mut rx) = q.split().unwrap();
        assert!(q.split().is_none());
        let e = |k: u32| Ready::Step {
            tick: k,
            event: StepEvent::from_bits((k % 16) as u8),
            turns: k.is_multiple_of(3),
        };
        let mut next = 0u32;
        let mut put = 0u32;
        for round in 0..10u32 {
            while tx.enqueue(e(put)).is_ok() {
                put += 1;
            }
            assert_eq!(tx.len(), ReadyQueue::CAPACITY);
            assert_eq!(tx.enqueue(Ready::RunEnd), Err(Ready::RunEnd));
            for _ in 0..(100 + 13 * round) {
                assert_eq!(rx.dequeue(), Some(e(next)));
                next += 1;
            }
        }
        for r in [Ready::RunStart, Ready::Block { rpm: 7_000 }, Ready::RunEnd] {
            while rx.dequeue().is_some() {}
            tx.enqueue(r).unwrap();
            assert_eq!(rx.peek(), Some(r));
            rx.pop();
            assert!(rx.is_empty());
        }
    }

    /// Liveness of hold and resume, as a sender drives them: the blocks
    /// handed over eagerly, or only when the prep has prepared the last
    /// one (a late thread mode: the stepper stands between two blocks at
    /// speed); a hold after any entry, a cycle start at once (while it
    /// brakes: changes nothing) and again every 40 entries, as a sender
    /// repeats it. Every run ends with every step of the path issued in
    /// order and the axes at rest at its end; none waits forever; and no
    /// step is due before the step interrupt's clock, which a pause at
    /// rest moves on: a block that comes after a hold ended its run at
    /// rest starts a run of its own, its ticks counting from then.
    #[test]
    fn a_hold_after_any_entry_and_a_repeated_resume_always_finish_the_path() {
        // Cycle start; with the axes at rest (held, everything prepared
        // issued), a second of the operator's time first.
        fn resume(prep: &mut Prep, tx: &mut ReadyTx<'_>, clock: &mut u64) {
            if prep.motion() == AxesState::Held && tx.is_empty() {
                *clock += 1_000_000;
            }
            let _ = prep.resume(tx);
        }
        let items = run(&[0, -3_000, -3_500, -9_000, -9_100, -20_000], None);
        let (want, alone) = pulled(&items);
        let path: Vec<u8> = pulled_steps(&want).iter().map(|s| s.0).collect();
        let entries = want.len() as u32;
        for late in [false, true] {
            for hold_at in (0..entries + 3).step_by(5) {
                let q = ReadyQueue::new();
                let (mut tx, mut rx) = q.split().unwrap();
                let mut prep = Prep::new();
                let mut next = items.iter().cloned().peekable();
                let mut taken: Vec<Ready> = Vec::new();
                let mut rounds = 0u32;
                let mut since_resume = 0u32;
                let mut held = false;
                let (mut clock, mut origin) = (0u64, 0u64);
                loop {
                    rounds += 1;
                    assert!(
                        rounds < 100_000,
                        "stuck: late {late}, hold at {hold_at}, {} taken, {:?}",
                        taken.len(),
                        prep.motion()
                    );
                    // Thread mode: a run's start and its first block at
                    // once; the rest as room allows, or when hungry.
                    while let Some(i) = next.peek() {
                        if late && prep.stepper.in_run() && !prep.hungry() {
                            break;
                        }
                        if prep.push(i.clone()).is_err() {
                            break;
                        }
                        next.next();
                        if late {
                            break;
                        }
                    }
                    prep.fill(&mut tx);
                    match rx.dequeue() {
                        Some(r) => {
                            // The step interrupt's clock: a run starts
                            // now, a step waits for its tick and is never
                            // late.
                            match r {
                                Ready::RunStart => origin = clock,
                                Ready::Step { tick, .. } => {
                                    let due = origin + u64::from(tick);
                                    assert!(
                                        due >= clock,
                                        "late {late}, hold at {hold_at}: a step {} late",
                                        clock - due
                                    );
                                    clock = due;
                                }
                                _ => {}
                            }
                            taken.push(r);
                            since_resume += 1;
                        }
                        None if next.peek().is_none() && prep.is_idle() => break,
                        None => since_resume += 40,
                    }
                    if !held && taken.len() as u32 >= hold_at {
                        held = true;
                        prep.hold();
                        // Cycle start at once: while braking, nothing.
                        resume(&mut prep, &mut tx, &mut clock);
                        since_resume = 0;
                    }
                    if held && since_resume >= 40 {
                        since_resume = 0;
                        resume(&mut prep, &mut tx, &mut clock);
                    }
                }
                let bits: Vec<u8> = steps(&taken).iter().map(|s| s.0).collect();
                assert_eq!(bits, path, "late {late}, hold at {hold_at}");
                // Blocks and steps only inside a run, and a run's ticks
                // in order from its start.
                let mut open: Option<u32> = None;
                for (k, r) in taken.iter().enumerate() {
                    let at = std::format!("late {late}, hold at {hold_at}, entry {k}");
                    match *r {
                        Ready::RunStart => open = Some(0),
                        Ready::RunEnd => open = None,
                        Ready::Block { .. } => {
                            assert!(open.is_some(), "{at}: a block outside a run")
                        }
                        Ready::Step { tick, .. } => {
                            let last = open.expect("a step inside a run");
                            assert!(tick >= last, "{at}: tick {tick} before {last}");
                            open = Some(tick);
                        }
                    }
                }
                assert_eq!(prep.motion(), AxesState::Idle);
                assert_eq!(prep.stepper.issued(), alone.issued());
            }
        }
    }
}

//! Output blocks planned and checked before they run, the coordinate
//! arithmetic they share, and the step sink that hands them to the
//! machine.

use super::wire::*;
use crate::arc::{ArcDir, ArcPoints, ChordPlan};
use crate::crc32::Crc32;
use crate::impulse::{MAX_BLOCK_IMPULSES, MAX_POSITION};
use crate::interleave::{ImpulsePoint, LinearBlock, StepEvent};
use crate::length::Length;
use crate::machine::{Background, StepSink};
use crate::plan::{q32, Feed, Point};
use crate::protocol::io::Io;
use crate::stepdir::DriveTiming;
use crate::stepper::Item;
use core::fmt;

pub(super) const RANGE_POS_X: &str = "X position beyond 999999999 impulses";
pub(super) const RANGE_POS_Z: &str = "Z position beyond 999999999 impulses";
pub(super) const RANGE_BLOCK: &str = "block beyond 1000000 impulses per axis";
pub(super) const RANGE_POS: &str = "position beyond 999999999 impulses";
const _: () = assert!(MAX_POSITION == 999_999_999 && MAX_BLOCK_IMPULSES == 1_000_000);

/// One output block, planned and checked: ready to run without a check that
/// could fail.
pub(in crate::protocol) enum Planned {
    Line {
        block: LinearBlock,
        end: [Length; 2],
        rapid: bool,
        feed: Option<Feed>,
    },
    Arc {
        plan: ChordPlan,
        points: ArcPoints,
        dir: ArcDir,
        /// Registers after the last chord.
        to: ImpulsePoint,
        feed: Option<Feed>,
    },
}

impl Planned {
    /// The commanded point after it.
    pub(super) const fn end(&self) -> [Length; 2] {
        match self {
            Planned::Line { end, .. } => *end,
            Planned::Arc { points, .. } => points.end,
        }
    }

    /// The registers after it.
    pub(super) fn registers(&self) -> ImpulsePoint {
        match self {
            Planned::Line { block, .. } => block.to(),
            Planned::Arc { to, .. } => *to,
        }
    }
}

/// What a G-code block was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::protocol) enum Block {
    /// Run (moved or not).
    Run,
    /// Skipped by block delete.
    Skipped,
}

/// `NX= NZ= PX= PZ= SEQ=`: the impulses a request issued, the registers
/// after it, and the CRC of its step events.
pub(in crate::protocol) struct MotionSummary {
    from: ImpulsePoint,
    to: ImpulsePoint,
    seq: u32,
}

impl MotionSummary {
    pub(super) fn new(from: ImpulsePoint, to: ImpulsePoint, crc: &Crc32) -> Self {
        MotionSummary {
            from,
            to,
            seq: crc.finish(),
        }
    }
}

impl fmt::Display for MotionSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Registers stay within ±999 999 999: the differences fit in i32.
        write!(
            f,
            "NX={} NZ={} PX={} PZ={} SEQ={:08X}",
            self.to.x.get() - self.from.x.get(),
            self.to.z.get() - self.from.z.get(),
            self.to.x.get(),
            self.to.z.get(),
            self.seq
        )
    }
}

/// A point (Å) moved by the offsets.
pub(in crate::protocol) fn shifted(
    p: [i64; 2],
    off: [Length; 2],
) -> Result<[i64; 2], Refusal<'static>> {
    let add = |axis: usize| {
        Length::from_angstrom(p[axis])
            .and_then(|l| l.checked_add(off[axis]))
            .map(Length::as_angstrom)
            .ok_or(Refusal::Range(RANGE_OFFSET))
    };
    Ok([add(0)?, add(1)?])
}

/// A coordinate after a word: the word itself, or added to `now`.
pub(super) fn step(
    now: Length,
    word: Length,
    inc: bool,
    beyond: &'static str,
) -> Result<Length, Refusal<'static>> {
    if inc {
        now.checked_add(word).ok_or(Refusal::Range(beyond))
    } else {
        Ok(word)
    }
}

/// A work point in machine coordinates.
pub(super) fn to_machine(
    work: [Length; 2],
    off: [Length; 2],
) -> Result<[Length; 2], Refusal<'static>> {
    let add = |axis: usize| {
        work[axis]
            .checked_add(off[axis])
            .ok_or(Refusal::Range(RANGE_OFFSET))
    };
    Ok([add(0)?, add(1)?])
}

pub(super) const RANGE_OFFSET: &str = "position with its offsets beyond 99999.999999 mm";

/// A block's X word as a radius: half of it, rounded once from the number
/// as written, when it is a diameter.
pub(in crate::protocol) fn block_x(b: &crate::gcode::Block, diam: bool) -> Option<Length> {
    if diam {
        b.x_half
    } else {
        b.x
    }
}

/// An X word as a radius: halved when it is a diameter, refused when the
/// half is not exact.
pub(super) fn x_radius(word: Length, diam: bool) -> Result<Length, Refusal<'static>> {
    if diam {
        word.exact_half()
            .ok_or(Refusal::Value("X", "not an exact radius"))
    } else {
        Ok(word)
    }
}

/// `centre − start` in ångström: the I and K words of an arc.
pub(super) fn centre_minus(centre: [Length; 2], start: [Length; 2]) -> [i64; 2] {
    let d = |a: Length, b: Length| a.as_angstrom() - b.as_angstrom();
    [d(centre[0], start[0]), d(centre[1], start[1])]
}

/// Adds the step-event bytes of a block to a running CRC.
pub(crate) fn block_crc(block: &LinearBlock, mut crc: Crc32) -> Crc32 {
    for e in block.events() {
        crc.push(StepEvent::bits(e));
    }
    crc
}

/// LinuxCNC's lathe orientation (`G41.1 L`, its tool table's `Q`) as the
/// device's tip code: the same tips mirrored in X (its 2 is the device's
/// 3, its 6 the device's 8; 0 and 9 the nose centre).
pub(super) const fn linuxcnc_orientation(l: u8) -> u8 {
    match l {
        1 => 4,
        2 => 3,
        3 => 2,
        4 => 1,
        6 => 8,
        8 => 6,
        l => l,
    }
}

/// A commanded point as the planner takes it.
pub(in crate::protocol) fn point_q32(p: [Length; 2]) -> Point {
    [q32(p[0]), q32(p[1])]
}

/// The protocol's outputs as the motion pipeline's step sink.
pub(in crate::protocol) struct Sink<'a, I: Io> {
    io: &'a mut I,
    drive: DriveTiming,
}

impl<'a, I: Io> Sink<'a, I> {
    pub(super) fn new(io: &'a mut I, drive: DriveTiming) -> Self {
        Sink { io, drive }
    }
}

impl<I: Io> StepSink for Sink<'_, I> {
    fn start(&mut self, item: Item) -> Result<(), Item> {
        match self.io.background() {
            Some(b) => {
                b.start(item, &self.drive);
                Ok(())
            }
            None => Err(item),
        }
    }

    fn background(&mut self) -> Option<&mut dyn Background> {
        self.io.background()
    }

    fn run_start(&mut self) {
        self.io.run_start();
    }

    fn block_start(&mut self, block: &LinearBlock) {
        self.io.block_start(block);
    }

    #[inline(always)]
    fn step(&mut self, event: StepEvent, tick: u64) {
        self.io.step(event, tick, &self.drive);
    }

    fn run_end(&mut self, ticks: u64) {
        self.io.run_end(ticks);
    }
}

/// A point in ångström as lengths, or `ERR RANGE`.
pub(super) fn point(p: [i64; 2]) -> Result<[Length; 2], Refusal<'static>> {
    let beyond = Refusal::Range("compensated point beyond 99999.999999 mm");
    match (Length::from_angstrom(p[0]), Length::from_angstrom(p[1])) {
        (Some(x), Some(z)) => Ok([x, z]),
        _ => Err(beyond),
    }
}

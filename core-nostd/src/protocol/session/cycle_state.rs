//! Turning cycles on the session (`docs/cycles.md`): Fanuc's two-block and
//! Haas' one-block `G71` (turning) and `G72` (facing) roughing from a
//! profile held as it streams in, and `G70` finishing along it.
//!
//! The blocks `P` … `Q` that follow a roughing block are its profile: the
//! device holds them (each answered `HELD=`, nothing moves), checks them,
//! and when block `Q` arrives roughs the stock down to the profile plus
//! its allowances in one go, that block's reply summing the motion. A
//! profile block the cycle cannot take is refused naming it, and so is
//! every block after it up to `Q`: none of them runs, nothing has moved.
//! The profile stays held for `G70 P Q`, which runs its blocks as written
//! (feeds, nose compensation) and returns to its start point.

use super::wire::*;
use crate::cycle::{Segment, Step, PROFILE_BLOCKS};
use crate::gcode::{CycleKind, Motion, SingleCycle};
use crate::length::Length;

/// The retract until a first block sets one: 0.5 mm.
pub(super) const HALF_MM: Length = match Length::from_um(500) {
    Some(l) => l,
    None => Length::ZERO,
};

/// Bytes of profile text held (comments left out).
pub const ARENA: usize = 4096;

/// What the cycles keep between blocks.
#[derive(Clone, Debug)]
pub struct Cycles {
    /// Fanuc's first block: the depth of cut (`G71 U`, `G72 W`) and the
    /// retract (`R`), modal.
    pub(super) depth: Option<Length>,
    pub(super) retract: Length,
    /// Fanuc's first `G73` block: the relief, X (on the radius) and Z, and
    /// the count of passes, modal.
    pub(super) pattern: Option<([i64; 2], u32)>,
    pub(super) mode: Mode,
    /// The profile's blocks as text, end to end, and where each ends.
    pub(super) text: heapless::Vec<u8, ARENA>,
    pub(super) ends: heapless::Vec<u16, PROFILE_BLOCKS>,
    /// Its elements from its first point, in work coordinates (X on the
    /// radius), and that point.
    pub(super) segments: heapless::Vec<Segment, PROFILE_BLOCKS>,
    pub(super) first: [i64; 2],
    /// The point the profile was read from (its first block moves from it).
    pub(super) from: [i64; 2],
    /// The motion mode in force while it was read.
    pub(super) motion: Motion,
    /// `P` and `Q` of the profile held whole.
    pub(super) held: Option<(u32, u32)>,
    /// The single cycle in force (`G90`, `G94`), modal until a motion code.
    pub(super) single: Option<Single>,
    /// `G74`/`G75`: the return after each peck (Fanuc's first block `R`).
    pub(super) peck_return: Length,
}

/// A single cycle in force and its modal words: the end point's X (on the
/// radius) and Z in work coordinates, once given, and the taper `R`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::protocol) struct Single {
    pub(super) kind: SingleCycle,
    pub(super) x: Option<i64>,
    pub(super) z: Option<i64>,
    pub(super) taper: i64,
}

impl Single {
    /// A cycle selected without its words.
    pub(super) const fn selected(kind: SingleCycle) -> Single {
        Single {
            kind,
            x: None,
            z: None,
            taper: 0,
        }
    }
}

/// Whether blocks are being held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    Idle,
    /// A roughing's profile streams in.
    Holding(Pending),
    /// A refused profile: its blocks up to `Q` are refused too.
    Refusing(u32, u32),
}

/// A roughing waiting for its profile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Pending {
    pub(super) kind: CycleKind,
    pub(super) p: u32,
    pub(super) q: u32,
    /// Allowances: X (on the radius) and Z, Å.
    pub(super) allow: [i64; 2],
    pub(super) depth: i64,
    pub(super) retract: i64,
    pub(super) feed: Option<Length>,
    /// `G73`: the relief and the count of passes (0 for the others).
    pub(super) relief: [i64; 2],
    pub(super) passes: u32,
}

impl Default for Cycles {
    fn default() -> Self {
        Self::new()
    }
}

impl Cycles {
    /// Nothing held; a retract of 0.5 mm until a first block sets one.
    pub const fn new() -> Cycles {
        Cycles {
            depth: None,
            retract: HALF_MM,
            pattern: None,
            mode: Mode::Idle,
            text: heapless::Vec::new(),
            ends: heapless::Vec::new(),
            segments: heapless::Vec::new(),
            first: [0; 2],
            from: [0; 2],
            motion: Motion::Rapid,
            held: None,
            single: None,
            peck_return: TENTH_MM,
        }
    }

    /// Whether the blocks streaming in are a profile's (held, or refused
    /// with it).
    pub fn holding(&self) -> bool {
        !matches!(self.mode, Mode::Idle)
    }

    /// A reset: a profile being read is dropped (the one held whole
    /// stays).
    pub fn abandon(&mut self) {
        self.single = None;
        if self.holding() {
            self.mode = Mode::Idle;
            self.held = None;
            self.clear();
        }
    }

    pub(super) fn clear(&mut self) {
        self.text.clear();
        self.ends.clear();
        self.segments.clear();
    }

    /// The held blocks' texts, in order.
    pub(super) fn lines(&self) -> impl Iterator<Item = &str> {
        let mut start = 0usize;
        self.ends.iter().map(move |&end| {
            let line = self
                .text
                .get(start..usize::from(end))
                .and_then(|b| core::str::from_utf8(b).ok())
                .unwrap_or("");
            start = usize::from(end);
            line
        })
    }
}

pub(super) const fn refuse_profile(why: &'static str) -> Refusal<'static> {
    Refusal::Missing(why)
}

/// The return after each peck until a `G74 R`/`G75 R` sets one: 0.1 mm.
pub(super) const TENTH_MM: Length = match Length::from_angstrom(1_000_000) {
    Some(l) => l,
    None => Length::ZERO,
};

/// The most moves one `G74`/`G75` may make (its check runs them all).
pub const PECK_MOVES: u32 = 20_000;

/// A grooving cycle's geometry in work coordinates (X on the radius):
/// pecks along axis `u` from S to the end, grooves side by side along
/// axis `v`.
#[derive(Clone, Copy)]
pub(super) struct Pecks {
    pub(super) u: usize,
    pub(super) s: [i64; 2],
    pub(super) end: [i64; 2],
    pub(super) peck: i64,
    pub(super) shift: i64,
    pub(super) back: i64,
}

impl Pecks {
    pub(super) fn at(&self, u: i64, v: i64) -> [i64; 2] {
        if self.u == 0 {
            [u, v]
        } else {
            [v, u]
        }
    }

    pub(super) fn v(&self) -> usize {
        1 - self.u.min(1)
    }

    /// Pecks per groove and grooves.
    pub(super) fn counts(&self) -> (u64, u64) {
        let (u, v) = (self.u.min(1), self.v());
        let (du, dv) = (
            self.end[u].abs_diff(self.s[u]),
            self.end[v].abs_diff(self.s[v]),
        );
        let pecks = du.div_ceil(self.peck.unsigned_abs().max(1));
        let grooves = 1 + dv.div_ceil(self.shift.unsigned_abs().max(1));
        (pecks, grooves)
    }

    /// Every move, in order: each groove pecked to the end (in at the feed
    /// by the peck, back at the rapid rate by the return), out to S's
    /// level at the rapid rate, over to the next groove; last, back to S.
    pub(super) fn steps<E>(&self, out: &mut impl FnMut(Step) -> Result<(), E>) -> Result<(), E> {
        let (u, v) = (self.u.min(1), self.v());
        let (u0, u1) = (self.s[u], self.end[u]);
        let (v0, v1) = (self.s[v], self.end[v]);
        let du = (u1 - u0).signum();
        let dv = (v1 - v0).signum();
        let mut g = v0;
        loop {
            if g != v0 {
                out(Step::Rapid(self.at(u0, g)))?;
            }
            let mut d = u0;
            loop {
                let next = if (u1 - d).abs() <= self.peck {
                    u1
                } else {
                    d + du * self.peck
                };
                out(Step::Feed(self.at(next, g)))?;
                if next == u1 {
                    break;
                }
                if self.back > 0 {
                    let mut back = next - du * self.back;
                    if (back - u0) * du < 0 {
                        back = u0;
                    }
                    out(Step::Rapid(self.at(back, g)))?;
                }
                d = next;
            }
            out(Step::Rapid(self.at(u0, g)))?;
            if g == v1 {
                break;
            }
            g = if (v1 - g).abs() <= self.shift {
                v1
            } else {
                g + dv * self.shift
            };
        }
        if g != v0 {
            out(Step::Rapid(self.s))?;
        }
        Ok(())
    }
}

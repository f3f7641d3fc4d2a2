//! A cycle's moves: each planned from the work coordinates a cycle
//! computes, all checked before the first one runs, then run, each planned
//! again from where the one before left the machine (`G70`–`G75`, `G90`,
//! `G94`).

use super::*;
use crate::comp::{Move, MoveKind, Origin};
use crate::crc32::Crc32;
use crate::cycle::{Pattern, Roughing, Step};
use crate::interp::path_feed;
use crate::length::Length;

impl Session {
    /// Plans one roughing move (work coordinates, from `from`) from the
    /// machine's `cmd` and registers `pos`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn cycle_move<I: Io>(
        &self,
        step: Step,
        from: [i64; 2],
        modal: &crate::interp::Modal,
        spindle: &crate::interp::SpindleState,
        cmd: [Length; 2],
        pos: crate::interleave::ImpulsePoint,
        io: &mut I,
    ) -> Result<Planned, Refusal<'static>> {
        let off = self.offsets.vector(&self.sel).ok_or(Refusal::Range(
            "the offsets in effect add beyond 99999.999999 mm",
        ))?;
        let (to, kind, feeds) = match step {
            Step::Rapid(p) => (p, MoveKind::Line { rapid: true }, false),
            Step::Feed(p) => (p, MoveKind::Line { rapid: false }, true),
            Step::Arc(p, c, dir) => (
                p,
                MoveKind::Arc {
                    centre: shifted(c, off)?,
                    dir,
                },
                true,
            ),
        };
        let feed = if feeds {
            let x = Length::from_angstrom(from[0]).unwrap_or(Length::ZERO);
            let f = path_feed(modal, spindle, x).map_err(|e| Refusal::Value("F", e.as_str()))?;
            let f = f.ok_or(Refusal::Value(
                "F",
                "not programmed: a feed move needs F (mm/min)",
            ))?;
            Some(self.overridden(f, modal.feed_mode))
        } else {
            None
        };
        let m = Move {
            to: shifted(to, off)?,
            kind,
            origin: Origin::Current,
        };
        self.plan_move(cmd, pos, &m, feed, io)
    }

    /// The X and Z words of a cycle block as absolute work coordinates (X
    /// on the radius), from the start point `s`.
    pub(super) fn end_words(
        &self,
        b: &crate::gcode::Block,
        s: [i64; 2],
    ) -> Result<[Option<i64>; 2], Refusal<'static>> {
        let diam = b.diameter.unwrap_or(self.cfg.diam);
        let word = |w: Option<Length>, incremental: bool, from: i64| {
            w.map(|w| {
                if incremental {
                    add(from, w.as_angstrom())
                } else {
                    Ok(w.as_angstrom())
                }
            })
            .transpose()
        };
        Ok([
            word(block_x(b, diam), b.incremental_x, s[0])?,
            word(b.z, b.incremental_z, s[1])?,
        ])
    }

    /// Plans every move of a cycle from the start point `start` (work
    /// coordinates), each from where the one before would leave the
    /// machine, and runs none: a cycle is refused before it moves.
    pub(super) fn check_steps<I: Io>(
        &self,
        steps: &dyn CycleSteps,
        start: [i64; 2],
        modal: &crate::interp::Modal,
        spindle: &crate::interp::SpindleState,
        io: &mut I,
    ) -> Result<(), Refusal<'static>> {
        let (mut cmd, mut pos, mut last) = (self.cmd, self.pos, start);
        steps.each(&mut |step| {
            let p = self.cycle_move(step, last, modal, spindle, cmd, pos, io)?;
            (cmd, pos, last) = (p.end(), p.registers(), step_end(step));
            Ok(())
        })
    }

    /// Runs the moves [`Session::check_steps`] checked, each planned again
    /// from where the one before left the machine.
    pub(super) fn run_steps<I: Io>(
        &mut self,
        steps: &dyn CycleSteps,
        start: [i64; 2],
        modal: &crate::interp::Modal,
        spindle: &crate::interp::SpindleState,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<(), Refusal<'static>> {
        let mut last = start;
        steps.each(&mut |step| {
            let p = self.cycle_move(step, last, modal, spindle, self.cmd, self.pos, io)?;
            *crc = self.run_planned(&p, *crc, io);
            last = step_end(step);
            Ok(())
        })
    }
}

/// A cycle's moves in order: given once to the check, once to the run.
pub(super) trait CycleSteps {
    fn each(
        &self,
        f: &mut dyn FnMut(Step) -> Result<(), Refusal<'static>>,
    ) -> Result<(), Refusal<'static>>;
}

impl CycleSteps for Pecks {
    fn each(
        &self,
        f: &mut dyn FnMut(Step) -> Result<(), Refusal<'static>>,
    ) -> Result<(), Refusal<'static>> {
        self.steps(&mut |step| f(step))
    }
}

impl CycleSteps for Roughing<'_> {
    fn each(
        &self,
        f: &mut dyn FnMut(Step) -> Result<(), Refusal<'static>>,
    ) -> Result<(), Refusal<'static>> {
        let mut out = Ok(());
        self.steps(&mut |step| {
            if out.is_ok() {
                out = f(step);
            }
        });
        out
    }
}

impl CycleSteps for Pattern<'_> {
    fn each(
        &self,
        f: &mut dyn FnMut(Step) -> Result<(), Refusal<'static>>,
    ) -> Result<(), Refusal<'static>> {
        self.steps(&mut |step| f(step))
    }
}

impl CycleSteps for [Step; 4] {
    fn each(
        &self,
        f: &mut dyn FnMut(Step) -> Result<(), Refusal<'static>>,
    ) -> Result<(), Refusal<'static>> {
        self.iter().try_for_each(|&step| f(step))
    }
}

/// `from + by`, a coordinate a cycle computes, refused beyond the range of
/// a length.
pub(super) fn add(from: i64, by: i64) -> Result<i64, Refusal<'static>> {
    Length::from_angstrom(from.saturating_add(by))
        .map(Length::as_angstrom)
        .ok_or(Refusal::Range("the cycle's end beyond 99999.999999 mm"))
}

/// Where a step ends.
fn step_end(step: Step) -> [i64; 2] {
    match step {
        Step::Rapid(p) | Step::Feed(p) | Step::Arc(p, _, _) => p,
    }
}

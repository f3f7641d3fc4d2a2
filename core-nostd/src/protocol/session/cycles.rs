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

use super::cycle_moves::{add, CycleSteps};
use super::*;
use crate::arc::{centre_from_radius, ArcDir};
use crate::crc32::Crc32;
use crate::cycle::{Along, CycleError, Pattern, Roughing, Segment, Step, PROFILE_BLOCKS};
use crate::gcode::{parse, CycleKind, CycleWords, Motion, SingleCycle};
use crate::length::Length;
use crate::protocol::io::ErrorCode;

impl Session {
    /// `G74`/`G75`: Fanuc's first block sets the return after each peck;
    /// the second (and Haas' one block) pecks each groove to its end point
    /// and steps over to the next, every move checked before the first.
    fn peck_cycle<'a, I: Io>(
        &mut self,
        b: &crate::gcode::Block,
        c: CycleWords,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        let own = crate::gcode::Block {
            kind: b.kind,
            deleted: b.deleted,
            n: b.n,
            f: b.f,
            cycle: b.cycle,
            x: b.x,
            z: b.z,
            x_half: b.x_half,
            incremental_x: b.incremental_x,
            incremental_z: b.incremental_z,
            // The spindle started and the coolant switched on for the
            // cut, as Haas programs write `G75 … M08`: at rest before the
            // first peck.
            spindle: b.spindle.filter(|s| *s != Spindle::Off),
            coolant: b.coolant.filter(|c| *c != Coolant::Off),
            s: b.s,
            ..Default::default()
        };
        if *b != own {
            return Err(Refusal::Missing(
                "a grooving cycle block takes its own words, F, S, M03/M04 and M07/M08 only: put other M and G codes on their own line",
            ));
        }
        let aux = self.aux.after(b);
        let spindle = self.spindle_of(&aux, self.modal.units)?;
        let has_end = b.x.is_some() || b.z.is_some();
        if !has_end && c.i.is_none() && c.k.is_none() && c.d.is_none() && b.f.is_none() {
            if aux != self.aux {
                return Err(Refusal::Missing(
                    "G74/G75 with R alone sets the return: put S, M03/M04 and M07/M08 with the cut",
                ));
            }
            // Fanuc's first block: the return.
            let e = c.r.ok_or(Refusal::Missing(
                "G74/G75 R (the return after each peck), or the end point X (U), Z (W)",
            ))?;
            if e.as_angstrom() < 0 {
                return Err(Refusal::Value("R", "the return is 0 or more"));
            }
            self.cycles.peck_return = e;
            return Ok(Block::Run);
        }
        if !has_end {
            return Err(Refusal::Missing(
                "G74/G75 needs its end point: X (U), Z (W)",
            ));
        }
        if c.r.is_some_and(|r| r.as_angstrom() != 0) || c.d.is_some_and(|d| d.as_angstrom() != 0) {
            return Err(Refusal::Value(
                "R",
                "a relief at the bottom is not supported: R0 (D0) or none",
            ));
        }
        if let Some(f) = b.f {
            if f.as_angstrom() <= 0 {
                return Err(Refusal::Value("F", "the cycle's feed must be above 0"));
            }
        }
        let s = [self.prog[0].as_angstrom(), self.prog[1].as_angstrom()];
        let [x, z] = self.end_words(b, s)?;
        let end = [x.unwrap_or(s[0]), z.unwrap_or(s[1])];
        // G74 pecks along Z (the step K, Fanuc Q) and steps over along X
        // (I, P); G75 the other way round.
        let (u, peck, shift) = match c.kind {
            CycleKind::PeckFace => (1, c.k, c.i),
            _ => (0, c.i, c.k),
        };
        let v = 1 - u;
        if end[u] == s[u] {
            return Err(Refusal::Missing(match c.kind {
                CycleKind::PeckFace => "G74 needs a depth: its Z (W) away from the start point",
                _ => "G75 needs a depth: its X (U) away from the start point",
            }));
        }
        let peck = peck.map_or(end[u].abs_diff(s[u]) as i64, Length::as_angstrom);
        if peck <= 0 {
            return Err(Refusal::Value(
                if u == 1 { "Q" } else { "P" },
                "the peck must be above 0",
            ));
        }
        let shift = shift.map_or(0, Length::as_angstrom);
        if end[v] != s[v] && shift <= 0 {
            return Err(Refusal::Missing(match c.kind {
                CycleKind::PeckFace => "G74 to another X needs the step between grooves: P (I)",
                _ => "G75 to another Z needs the step between grooves: Q (K)",
            }));
        }
        let geom = Pecks {
            u,
            s,
            end,
            peck,
            shift: shift.max(1),
            back: self.cycles.peck_return.as_angstrom(),
        };
        let (pecks, grooves) = geom.counts();
        if grooves.saturating_mul(2 * pecks + 2) > u64::from(PECK_MOVES) {
            return Err(Refusal::Range("a grooving cycle of more than 20000 moves"));
        }
        let mut modal = self.modal;
        if b.f.is_some() {
            modal.feed = b.f;
        }
        self.check_steps(&geom, s, &modal, &spindle, io)?;
        self.take_aux(aux, io);
        self.run_steps(&geom, s, &modal, &spindle, crc, io)?;
        Ok(Block::Run)
    }

    /// A cycle block: `G71`/`G72` reads its profile from the blocks that
    /// follow (Fanuc's first block only sets the depth and the retract);
    /// `G70` finishes along the profile held.
    ///
    /// Its `F`, once the block is taken, is the feed in force from then
    /// on, as any block's `F` is.
    pub(super) fn cycle_block<'a, I: Io>(
        &mut self,
        b: &crate::gcode::Block,
        c: CycleWords,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        if let Some(f) = b.f {
            // Each form names its own feed (the roughing's, the
            // finishing's); a first block's is checked here.
            if f.as_angstrom() <= 0 && c.p.is_none() && c.q.is_none() && !c.kind.pecks() {
                return Err(Refusal::Value("F", "the cycle's feed must be above 0"));
            }
        }
        // A refused block leaves what the last request moved as it was.
        let kept = core::mem::replace(&mut self.last_moves, crate::comp::Moves::new());
        let taken = self.cycle_words(b, c, crc, io).inspect_err(|_| {
            self.last_moves = kept;
        })?;
        if let Some(f) = b.f {
            self.modal.feed = Some(f);
        }
        Ok(taken)
    }

    fn cycle_words<'a, I: Io>(
        &mut self,
        b: &crate::gcode::Block,
        c: CycleWords,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        if self.contour.active() {
            return Err(self.busy("a turning cycle"));
        }
        if c.kind.pecks() {
            return self.peck_cycle(b, c, crc, io);
        }
        if b.motion.is_some() || b.x.is_some() || b.z.is_some() || b.tool.is_some() {
            return Err(Refusal::Missing(
                "a cycle block takes no motion, axis or tool words: put them on their own line",
            ));
        }
        // Nothing else either: an M code, a spindle speed or a mode in the
        // block would otherwise pass unread.
        let own = crate::gcode::Block {
            kind: b.kind,
            deleted: b.deleted,
            n: b.n,
            f: b.f,
            cycle: b.cycle,
            ..Default::default()
        };
        if *b != own {
            return Err(Refusal::Missing(
                "a cycle block takes its own words and F only: put M, S and other G codes on their own line",
            ));
        }
        let diam = b.diameter.unwrap_or(self.cfg.diam);
        let radius = |l: Length| {
            let a = l.as_angstrom();
            if diam {
                crate::length::div_round_half_away(a, 2)
            } else {
                a
            }
        };
        if c.kind == CycleKind::Finish {
            return self.finish_cycle(b, c, crc, io).map(|()| Block::Run);
        }
        if c.kind == CycleKind::Pattern {
            return self.pattern_block(b, c, radius(c.u.unwrap_or(Length::ZERO)));
        }
        let (p, q) = match (c.p, c.q) {
            (None, None) => {
                // Fanuc's first block: the depth and the retract.
                let depth = match c.kind {
                    CycleKind::Face => c.w,
                    _ => c.u,
                };
                let other = match c.kind {
                    CycleKind::Face => c.u,
                    _ => c.w,
                };
                if c.d.is_some() || other.is_some() {
                    return Err(Refusal::Missing(
                        "the first of the two blocks takes the depth (G71 U, G72 W) and the retract R",
                    ));
                }
                let depth = depth.ok_or(Refusal::Missing(
                    "G71 U (G72 W) and R: the depth of cut and the retract, or P and Q",
                ))?;
                if depth.as_angstrom() <= 0 {
                    let word = match c.kind {
                        CycleKind::Face => "W",
                        _ => "U",
                    };
                    return Err(Refusal::Value(word, "the depth of cut must be above 0"));
                }
                if c.r.is_some_and(|r| r.as_angstrom() < 0) {
                    return Err(Refusal::Value("R", "the retract is 0 or more"));
                }
                self.cycles.depth = Some(depth);
                if let Some(r) = c.r {
                    self.cycles.retract = r;
                }
                return Ok(Block::Run);
            }
            (Some(p), Some(q)) => (p, q),
            _ => {
                return Err(Refusal::Missing(
                    "G71 and G72 need P and Q: the profile's blocks",
                ))
            }
        };
        let depth = c.d.or(self.cycles.depth).ok_or(Refusal::Missing(
            "no depth of cut: D, or G71 U (G72 W) and R in a block before",
        ))?;
        if depth.as_angstrom() <= 0 {
            return Err(Refusal::Value("D", "the depth of cut must be above 0"));
        }
        if let Some(f) = b.f {
            if f.as_angstrom() <= 0 {
                return Err(Refusal::Value("F", "the roughing feed must be above 0"));
            }
        }
        let allow = [c.u.map_or(0, radius), c.w.map_or(0, |w| w.as_angstrom())];
        let retract = match (c.d, c.r) {
            // Haas' one block: R1 selects type II roughing (the pockets),
            // which every roughing here is; the retract is the first
            // block's (or 0.5 mm).
            (Some(_), Some(r)) => {
                let one = match self.modal.units {
                    crate::gcode::Units::Mm => 10_000_000,
                    crate::gcode::Units::Inch => 254_000_000,
                };
                if r.as_angstrom() != one {
                    return Err(Refusal::Value(
                        "R",
                        "in Haas' one block R1 selects type II roughing (pockets), which every roughing is: R1 or none",
                    ));
                }
                self.cycles.retract
            }
            (_, r) => r.unwrap_or(self.cycles.retract),
        }
        .as_angstrom()
        .max(0);
        let pending = Pending {
            kind: c.kind,
            p,
            q,
            allow,
            depth: depth.as_angstrom(),
            retract,
            feed: b.f,
            relief: [0; 2],
            passes: 0,
        };
        self.hold_profile(pending);
        Ok(Block::Run)
    }

    /// `G73`: Fanuc's first block sets the relief (`U`, `W`, on the radius
    /// and along Z) and the count of passes (`R`); the second (`P Q U W
    /// F`), or Haas' one block (`P Q I K D U W F`), reads the profile.
    /// `u_allow` is the second block's `U` on the radius.
    fn pattern_block<'a>(
        &mut self,
        b: &crate::gcode::Block,
        c: CycleWords,
        u_allow: i64,
    ) -> Result<Block, Refusal<'a>> {
        let (p, q) = match (c.p, c.q) {
            (None, None) => {
                if c.i.is_some() || c.k.is_some() {
                    return Err(Refusal::Missing(
                        "the first of the two G73 blocks takes the relief U W and the count of passes R",
                    ));
                }
                let passes = c.passes.ok_or(Refusal::Missing(
                    "G73 U W R: the relief and the count of passes, or P and Q",
                ))?;
                let relief = [
                    c.u.map_or(0, Length::as_angstrom),
                    c.w.map_or(0, Length::as_angstrom),
                ];
                self.cycles.pattern = Some((relief, passes));
                return Ok(Block::Run);
            }
            (Some(p), Some(q)) => (p, q),
            _ => return Err(Refusal::Missing("G73 needs P and Q: the profile's blocks")),
        };
        if let Some(f) = b.f {
            if f.as_angstrom() <= 0 {
                return Err(Refusal::Value("F", "the roughing feed must be above 0"));
            }
        }
        let (relief, passes) = if c.i.is_some() || c.k.is_some() || c.passes.is_some() {
            let passes = c.passes.ok_or(Refusal::Missing(
                "G73 with I and K needs D: the count of passes",
            ))?;
            (
                [
                    c.i.map_or(0, Length::as_angstrom),
                    c.k.map_or(0, Length::as_angstrom),
                ],
                passes,
            )
        } else {
            self.cycles.pattern.ok_or(Refusal::Missing(
                "no relief: I K D, or G73 U W R in a block before",
            ))?
        };
        let pending = Pending {
            kind: CycleKind::Pattern,
            p,
            q,
            allow: [u_allow, c.w.map_or(0, Length::as_angstrom)],
            depth: 0,
            retract: 0,
            feed: b.f,
            relief,
            passes,
        };
        self.hold_profile(pending);
        Ok(Block::Run)
    }

    /// Starts holding the profile of `pending` from where the tool stands.
    fn hold_profile(&mut self, pending: Pending) {
        let cy = &mut self.cycles;
        cy.clear();
        cy.held = None;
        cy.from = [self.prog[0].as_angstrom(), self.prog[1].as_angstrom()];
        cy.motion = self.modal.motion;
        cy.mode = Mode::Holding(pending);
    }

    /// A block that streams in while a profile is held or refused.
    pub(super) fn profile_line<'a, I: Io>(
        &mut self,
        text: &str,
        io: &mut I,
    ) -> Result<(), Refusal<'a>> {
        self.last_moves = crate::comp::Moves::new();
        let pending = match self.cycles.mode {
            Mode::Idle => return Ok(()),
            Mode::Refusing(p, q) => {
                let n = parse(text, self.offsets.reading.dialect, self.modal.units)
                    .ok()
                    .and_then(|b| b.n);
                if n == Some(q) {
                    self.cycles.mode = Mode::Idle;
                }
                send_error_about(
                    io,
                    ErrorCode::Value,
                    Some(b'N'),
                    format_args!("N inside the profile (N{p} to N{q}) of a refused cycle: not run"),
                );
                return Ok(());
            }
            Mode::Holding(p) => p,
        };
        match self.hold(text, pending) {
            Ok(Some(count)) => {
                send_ok(
                    io,
                    Some(format_args!(
                        "NX=0 NZ=0 PX={} PZ={} SEQ=00000000 HELD={count}",
                        self.pos.x.get(),
                        self.pos.z.get()
                    )),
                );
                Ok(())
            }
            Ok(None) => {
                // Its last block: rough now.
                let start = self.pos;
                let mut crc = Crc32::new();
                match self.rough(pending, &mut crc, io) {
                    Ok(()) => {
                        self.cycles.mode = Mode::Idle;
                        self.cycles.held = Some((pending.p, pending.q));
                        let summary = MotionSummary::new(start, self.pos, &crc);
                        send_ok(io, Some(format_args!("{summary}")));
                        Ok(())
                    }
                    Err(e) => {
                        self.cycles.mode = Mode::Idle;
                        self.cycles.clear();
                        Err(e)
                    }
                }
            }
            Err(e) => {
                let n = parse(text, self.offsets.reading.dialect, self.modal.units)
                    .ok()
                    .and_then(|b| b.n);
                self.cycles.mode = if n == Some(pending.q) {
                    Mode::Idle
                } else {
                    Mode::Refusing(pending.p, pending.q)
                };
                self.cycles.clear();
                Err(e)
            }
        }
    }

    /// Holds one profile block: its element, its text. `Some(count)` while
    /// more are to come, `None` once block `Q` is in.
    fn hold(&mut self, text: &str, pending: Pending) -> Result<Option<usize>, Refusal<'static>> {
        let b = parse(text, self.offsets.reading.dialect, self.modal.units)
            .map_err(|l| Refusal::Block(l.error))?;
        let first = self.cycles.ends.is_empty();
        if first && b.n != Some(pending.p) {
            return Err(refuse_profile(
                "the profile must begin with the block numbered P",
            ));
        }
        let other = b.spindle.is_some()
            || b.coolant.is_some()
            || b.stop.is_some()
            || b.tool.is_some()
            || b.dwell.is_some()
            || b.special.is_some()
            || b.wcs.is_some()
            || b.set_work.is_some()
            || b.units.is_some()
            || b.cycle.is_some()
            || b.position_offset.is_some()
            || b.machine_m.is_some()
            || b.gear.is_some()
            || b.tool_change
            || b.tool_offset.is_some()
            || b.dynamic_nose.is_some()
            || b.nose_tool.is_some()
            || b.kind != crate::gcode::LineKind::Words;
        if b.round.is_some() {
            return Err(refuse_profile(
                "a profile block takes no ,C or ,R: write the chamfer or round as a block of its own",
            ));
        }
        if other {
            return Err(refuse_profile(
                "a profile block takes G00-G03, G40-G42, X Z U W I K R, F and S only",
            ));
        }
        // Its element.
        let diam = b.diameter.unwrap_or(self.cfg.diam);
        let cy = &mut self.cycles;
        let at = match cy.segments.last() {
            Some(g) => g.to,
            None if first => cy.from,
            None => cy.first,
        };
        let motion = b.motion.unwrap_or(cy.motion);
        let mut to = at;
        if let Some(x) = block_x(&b, diam) {
            let x = x.as_angstrom();
            to[0] = if b.incremental_x { at[0] + x } else { x };
        }
        if let Some(z) = b.z {
            let z = z.as_angstrom();
            to[1] = if b.incremental_z { at[1] + z } else { z };
        }
        let arc = match motion {
            Motion::Rapid | Motion::Linear => {
                if b.i.is_some() || b.k.is_some() || b.r.is_some() {
                    return Err(Refusal::Missing("I, K and R need G02 or G03"));
                }
                None
            }
            Motion::ArcCw | Motion::ArcCcw => {
                let dir = if motion == Motion::ArcCw {
                    ArcDir::Cw
                } else {
                    ArcDir::Ccw
                };
                let len = |a: i64| {
                    Length::from_angstrom(a)
                        .ok_or(Refusal::Range("the profile lies beyond 99999.999999 mm"))
                };
                let centre = match (b.i.is_some() || b.k.is_some(), b.r) {
                    (true, None) => [
                        at[0] + b.i.map_or(0, |i| i.as_angstrom()),
                        at[1] + b.k.map_or(0, |k| k.as_angstrom()),
                    ],
                    (false, Some(r)) => {
                        let c = centre_from_radius(
                            [len(at[0])?, len(at[1])?],
                            [len(to[0])?, len(to[1])?],
                            r,
                            dir,
                        )
                        .map_err(Refusal::from)?;
                        [c[0].as_angstrom(), c[1].as_angstrom()]
                    }
                    (true, Some(_)) => return Err(Refusal::Missing("give I and K or R, not both")),
                    (false, None) => return Err(Refusal::Missing("an arc needs I and K, or R")),
                };
                Some((centre, dir))
            }
        };
        cy.motion = motion;
        if first {
            // The first block goes to the profile's first point.
            cy.first = to;
        } else if to != at {
            cy.segments
                .push(Segment { to, arc })
                .map_err(|_| Refusal::Range("a profile of more than 128 blocks"))?;
        }
        // Its text, without comments.
        let mut paren = false;
        for &byte in text.as_bytes() {
            match byte {
                b';' if !paren => break,
                b'(' => paren = true,
                b')' if paren => paren = false,
                _ if paren => {}
                _ => cy
                    .text
                    .push(byte)
                    .map_err(|_| Refusal::Range("a profile of more than 4096 bytes"))?,
            }
        }
        let end = u16::try_from(cy.text.len()).unwrap_or(u16::MAX);
        cy.ends
            .push(end)
            .map_err(|_| Refusal::Range("a profile of more than 128 blocks"))?;
        if b.n == Some(pending.q) {
            Ok(None)
        } else {
            Ok(Some(cy.ends.len()))
        }
    }

    /// The roughing of the held profile: every move checked first, then
    /// run.
    fn rough<I: Io>(
        &mut self,
        pending: Pending,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<(), Refusal<'static>> {
        let cy = &self.cycles;
        if cy.segments.is_empty() {
            return Err(Refusal::Geometry(CycleError::Empty.as_str()));
        }
        // Translated by the allowances.
        let shift = |p: [i64; 2]| [p[0] + pending.allow[0], p[1] + pending.allow[1]];
        let mut moved = heapless::Vec::<Segment, PROFILE_BLOCKS>::new();
        for g in &cy.segments {
            let _ = moved.push(Segment {
                to: shift(g.to),
                arc: g.arc.map(|(c, d)| (shift(c), d)),
            });
        }
        // The feed: the cycle's F, else the one in force.
        let mut modal = self.modal;
        if pending.feed.is_some() {
            modal.feed = pending.feed;
        }
        let spindle = self.aux.spindle.within(self.top_speed(&self.aux));
        let s = cy.from;
        let (pattern, roughing);
        let steps: &dyn CycleSteps = if pending.kind == CycleKind::Pattern {
            pattern = Pattern {
                start: s,
                first: shift(cy.first),
                segments: &moved,
                relief: pending.relief,
                passes: pending.passes,
            };
            &pattern
        } else {
            let along = match pending.kind {
                CycleKind::Face => Along::X,
                _ => Along::Z,
            };
            roughing = Roughing::new(
                along,
                s,
                shift(cy.first),
                &moved,
                pending.depth,
                pending.retract,
            )
            .map_err(|e| Refusal::Geometry(e.as_str()))?;
            &roughing
        };
        self.check_steps(steps, s, &modal, &spindle, io)?;
        self.run_steps(steps, s, &modal, &spindle, crc, io)?;
        self.prog = [
            Length::from_angstrom(s[0]).unwrap_or(self.prog[0]),
            Length::from_angstrom(s[1]).unwrap_or(self.prog[1]),
        ];
        Ok(())
    }

    /// `G70 P Q [F]`: the held profile's blocks run as written, from where
    /// the tool stands, then back to that point.
    fn finish_cycle<I: Io>(
        &mut self,
        b: &crate::gcode::Block,
        c: CycleWords,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<(), Refusal<'static>> {
        if c.d.is_some() || c.r.is_some() {
            return Err(Refusal::Missing("G70 takes P and Q (and F)"));
        }
        if c.u.is_some_and(|u| u.as_angstrom() != 0) || c.w.is_some_and(|w| w.as_angstrom() != 0) {
            return Err(Refusal::Missing(
                "G70 finishes on the profile: its allowances are G71's and G72's U and W",
            ));
        }
        let (p, q) = (
            c.p.ok_or(Refusal::Missing("G70 needs P and Q"))?,
            c.q.ok_or(Refusal::Missing("G70 needs P and Q"))?,
        );
        if self.cycles.held != Some((p, q)) {
            return Err(Refusal::Missing(
                "G70 finishes the profile a G71, G72 or G73 held last: no such P and Q",
            ));
        }
        if let Some(f) = b.f {
            if f.as_angstrom() <= 0 {
                return Err(Refusal::Value("F", "the finishing feed must be above 0"));
            }
        }
        // Known before the first block moves (a refusal comes before
        // motion), from one reading of the held blocks: every feed move of
        // the profile has a feed.
        let mut feed =
            b.f.or(self.modal.feed)
                .is_some_and(|f| f.as_angstrom() != 0);
        let mut motion = self.modal.motion;
        let mut unfed = false;
        for line in self.cycles.lines() {
            if let Ok(pb) = parse(line, self.offsets.reading.dialect, self.modal.units) {
                if let Some(f) = pb.f {
                    feed = f.as_angstrom() != 0;
                }
                if let Some(m) = pb.motion {
                    motion = m;
                }
                unfed |= !feed && motion != Motion::Rapid && (pb.x.is_some() || pb.z.is_some());
            }
        }
        if unfed {
            return Err(Refusal::Value(
                "F",
                "not programmed: the profile's feed moves need G70 F or a feed in force",
            ));
        }
        if let Some(f) = b.f {
            self.modal.feed = Some(f);
        }
        let back = self.prog;
        let lines = self.cycles.ends.len();
        for k in 0..lines {
            // One block at a time from the held text (a copy: the session
            // runs it).
            let mut line = heapless::String::<{ crate::protocol::framing::MAX_LINE }>::new();
            if let Some(t) = self.cycles.lines().nth(k) {
                let _ = line.push_str(t);
            }
            self.gcode_block(&line, crc, io)?;
        }
        // Back to the start point: X first, then Z, at the rapid rate.
        if self.contour.active() {
            return self.compensated_return(back, crc, io);
        }
        let here = |p: [Length; 2]| [p[0].as_angstrom(), p[1].as_angstrom()];
        let (from, back) = (here(self.prog), here(back));
        let mut at = from;
        for to in [[back[0], from[1]], back] {
            if to == at {
                // Already there (no move of no length).
                continue;
            }
            at = to;
            let modal = self.modal;
            let spindle = self.aux.spindle;
            let plan = self.cycle_move(
                Step::Rapid(to),
                to,
                &modal,
                &spindle,
                self.cmd,
                self.pos,
                io,
            )?;
            *crc = self.run_planned(&plan, *crc, io);
        }
        self.prog = [
            Length::from_angstrom(back[0]).unwrap_or(self.prog[0]),
            Length::from_angstrom(back[1]).unwrap_or(self.prog[1]),
        ];
        Ok(())
    }

    /// `G70`'s return when its profile leaves `G41`/`G42` on (as Fanuc's
    /// programs do that cancel it after the cycle): the two rapids, X then
    /// Z, go through nose compensation as the blocks `G00 U…` and `G00 W…`
    /// would, the second waiting for the next block's corner; the motion
    /// mode stays the profile's.
    fn compensated_return<I: Io>(
        &mut self,
        back: [Length; 2],
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<(), Refusal<'static>> {
        let motion = self.modal.motion;
        // The X move leaves the programmed Z as it was: one reading of the
        // point before both.
        for (axis, (end, at)) in back.into_iter().zip(self.prog).enumerate() {
            let Some(d) = end.checked_sub(at) else {
                return Err(Refusal::Range("G70's start point beyond 99999.999999 mm"));
            };
            if d == Length::ZERO {
                continue;
            }
            let mut b = crate::gcode::Block {
                motion: Some(Motion::Rapid),
                ..crate::gcode::Block::default()
            };
            if axis == 0 {
                // `U`: the word as written (a diameter in G07) and its half.
                let word = if self.cfg.diam {
                    d.checked_add(d)
                } else {
                    Some(d)
                };
                let word =
                    word.ok_or(Refusal::Range("G70's start point beyond 99999.999999 mm"))?;
                (b.x, b.x_half, b.incremental_x) = (Some(word), Some(d), true);
            } else {
                (b.z, b.incremental_z) = (Some(d), true);
            }
            self.gcode_words(b, crc, io)?;
        }
        self.modal.motion = motion;
        Ok(())
    }
}

impl Session {
    /// A block under a single cycle: `G90`/`G94` with its end point, or a
    /// block of only `X`/`U`, `Z`/`W`, `R` and `F` while one is in force
    /// (`kind` None). From the start point S: in at the rapid rate (to the
    /// taper's start), the cut to the end point, out at the feed, back to S
    /// at the rapid rate; every move checked before the first one runs.
    pub(super) fn single_cycle<'a, I: Io>(
        &mut self,
        b: &crate::gcode::Block,
        kind: Option<SingleCycle>,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        let bare = crate::gcode::Block {
            kind: b.kind,
            n: b.n,
            x: b.x,
            z: b.z,
            x_half: b.x_half,
            incremental_x: b.incremental_x,
            incremental_z: b.incremental_z,
            r: b.r,
            f: b.f,
            feed_mode: b.feed_mode,
            single: b.single,
            deleted: b.deleted,
            ..Default::default()
        };
        if *b != bare {
            return Err(Refusal::Missing(
                "a G90/G94 block takes X (U), Z (W), R and F: put other words on their own line",
            ));
        }
        if self.contour.active() {
            return Err(self.busy("a single cycle"));
        }
        let mut single = match (kind, self.cycles.single) {
            // The same cycle again: its words stay in force.
            (Some(k), Some(s)) if s.kind == k => s,
            (Some(k), _) => Single::selected(k),
            (None, Some(s)) => s,
            (None, None) => return Err(Refusal::Missing("no single cycle in force")),
        };
        let modal = self.modal.after(b);
        if let Some(f) = b.f {
            if f.as_angstrom() <= 0 {
                return Err(Refusal::Value("F", "the cycle's feed must be above 0"));
            }
        }
        let s = [self.prog[0].as_angstrom(), self.prog[1].as_angstrom()];
        let [x, z] = self.end_words(b, s)?;
        single.x = x.or(single.x);
        single.z = z.or(single.z);
        if let Some(r) = b.r {
            single.taper = r.as_angstrom();
        }
        let e = [single.x.unwrap_or(s[0]), single.z.unwrap_or(s[1])];
        let steps = match single.kind {
            SingleCycle::Turn => [
                Step::Rapid([add(e[0], single.taper)?, s[1]]),
                Step::Feed(e),
                Step::Feed([s[0], e[1]]),
                Step::Rapid(s),
            ],
            SingleCycle::Face => [
                Step::Rapid([s[0], add(e[1], single.taper)?]),
                Step::Feed(e),
                Step::Feed([e[0], s[1]]),
                Step::Rapid(s),
            ],
        };
        self.last_moves = crate::comp::Moves::new();
        let spindle = self.aux.spindle.within(self.top_speed(&self.aux));
        self.check_steps(&steps, s, &modal, &spindle, io)?;
        self.modal = modal;
        self.cycles.single = Some(single);
        self.run_steps(&steps, s, &modal, &spindle, crc, io)?;
        Ok(Block::Run)
    }
}

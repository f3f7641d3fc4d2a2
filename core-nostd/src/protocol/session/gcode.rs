//! G-code blocks: read, checked against the modal state, then run.

use super::*;

/// Whether a line the reader took holds nothing but a sequence number and
/// comments.
fn number_only(text: &str) -> bool {
    let mut comment = false;
    for c in text.bytes() {
        match c {
            b';' if !comment => return true,
            b'(' => comment = true,
            b')' => comment = false,
            _ if comment => {}
            b'N' | b'n' | b'0'..=b'9' | b' ' | b'\t' => {}
            _ => return false,
        }
    }
    true
}

impl Session {
    /// Runs one G-code block in the session's modal state, through the
    /// contour engine (compensation off: the block itself).
    #[inline(never)]
    pub(super) fn gcode<'a, I: Io>(&mut self, text: &str, io: &mut I) -> Outcome<'a> {
        // Nothing runs while an input holds the machine locked.
        self.unlocked()?;
        let outcome = self.gcode_line(text, io);
        if let Err(Refusal::Travel(_)) = outcome {
            self.travel_alarm(io);
        }
        outcome
    }

    /// [`Session::gcode`] once unlocked.
    fn gcode_line<'a, I: Io>(&mut self, text: &str, io: &mut I) -> Outcome<'a> {
        if self.cycles.holding() {
            return self.profile_line(text, io);
        }
        let start = self.pos;
        let mut crc = Crc32::new();
        let done = self.gcode_block(text, &mut crc, io)?;
        let summary = MotionSummary::new(start, self.pos, &crc);
        match done {
            Block::Run => send_ok(io, Some(format_args!("{summary}"))),
            Block::Skipped => send_ok(io, Some(format_args!("{summary} SKIP=BDEL"))),
        }
        Ok(())
    }

    /// Runs one G-code block, its step events added to `crc`; answers
    /// nothing (its caller does: one line per request). What it was.
    pub(in crate::protocol) fn gcode_block<'a, I: Io>(
        &mut self,
        text: &str,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        let b = parse(text, self.offsets.reading.dialect, self.modal.units)
            .map_err(|l| Refusal::Block(l.error))?;
        if b.deleted && self.offsets.reading.block_delete {
            return Ok(Block::Skipped);
        }
        if self.contour.rounding() && number_only(text) {
            // Nothing but a sequence number or a comment (a sender that
            // splits `N80 G01 …` in two): it asks nothing of the corner
            // waiting, which waits on.
            return Ok(Block::Run);
        }
        if b.cycle.is_some() || b.single.is_some() {
            self.no_round(&b)?;
        }
        if let Some(cycle) = b.cycle {
            self.cycles.single = None;
            return self.cycle_block(&b, cycle, crc, io);
        }
        if let Some(kind) = b.single {
            if b.motion.is_some() {
                return Err(Refusal::Missing(
                    "G90/G94 and a motion code in one block: one of them",
                ));
            }
            if b.x.is_some() || b.z.is_some() {
                return self.single_cycle(&b, Some(kind), crc, io);
            }
            // Selected only (a header's `G90`): the block's other words
            // as any block's; nothing moves.
            let done = self.gcode_words(b, crc, io)?;
            self.cycles.single = Some(Single::selected(kind));
            return Ok(done);
        }
        if self.cycles.single.is_some() {
            if b.motion.is_some() || b.cancel_cycle || b.stop == Some(Stop::End) {
                // A motion code, G80 or the program's end ends the cycle.
                self.cycles.single = None;
            } else if b.x.is_some() || b.z.is_some() {
                self.no_round(&b)?;
                return self.single_cycle(&b, None, crc, io);
            }
        }
        self.gcode_words(b, crc, io)
    }

    /// Refuses a cycle's block while a move waits for its `,C`/`,R`
    /// corner, or that asks for one itself.
    fn no_round(&self, b: &crate::gcode::Block) -> Result<(), Refusal<'static>> {
        if let Some(n) = self.contour.waiting() {
            return Err(Refusal::Contour(crate::comp::CompError::RoundNext(n, b.n)));
        }
        if b.round.is_some() {
            return Err(Refusal::Contour(crate::comp::CompError::RoundHere(b.n)));
        }
        Ok(())
    }

    /// What refuses a request that needs the programmed point to be the
    /// tool's: nose compensation on, or a move waiting for its `,C`/`,R`
    /// corner.
    pub(super) fn busy(&self, what: &'static str) -> Refusal<'static> {
        match self.contour.waiting() {
            Some(n) => Refusal::Contour(crate::comp::CompError::RoundNext(n, None)),
            None => Refusal::Busy(what),
        }
    }

    /// A block's words, run (no cycle in it), in numbered steps in the order
    /// of the modal groups (RS274/NGC's order of execution, as grbl's
    /// `gc_execute_block`): steps 1 to 9 compute and check the whole block,
    /// step 10 commits it, so a refused block changes nothing.
    pub(super) fn gcode_words<'a, I: Io>(
        &mut self,
        b: crate::gcode::Block,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        // 1. Feed mode and feed (G94/G95, F).
        let modal = self.modal.after(&b);
        // F0 (a header's, before G95) is taken; a feed move then needs a
        // feed above 0.
        if let Some(f) = b.f.filter(|f| f.as_angstrom() != 0) {
            let (ok, why) = match modal.feed_mode {
                FeedMode::PerMinute => (
                    Feed::new(f).is_some(),
                    "must be 0.001 to 99999.999999 mm/min",
                ),
                FeedMode::PerRev => (f.as_angstrom() > 0, "must be above 0 mm/rev"),
            };
            if !ok {
                return Err(Refusal::Value("F", why));
            }
        }
        // 2. Spindle (S, M03–M05, G96/G97, G50/G92 S) within its top
        //    speed, coolant.
        let aux = self.aux.after(&b);
        let spindle = self.spindle_of(&aux, modal.units)?;
        // 3. Offsets: the work system (G54–G59, G10), the tool (T, G43/G49),
        //    G92 (G50) and its kin.
        let diam = b.diameter.unwrap_or(self.cfg.diam);
        let (sel, mut offsets) = self.offsets_after(&b, &aux, diam)?;
        let special = b.special;
        if special.is_some() && (self.contour.active() || b.compensation.is_some()) {
            return Err(self.busy("G28, G30, G38, G53 and G92 (G50) with nose compensation"));
        }
        // G92 (G50): the point here takes the block's coordinates.
        let mut prog = self.prog;
        let shift = offsets.shift;
        match special {
            Some(Special::Shift) => {
                // The point here in the block's work system as it stands
                // (never under nose compensation: refused above).
                let off = offsets.vector(&sel).ok_or(Refusal::Range(RANGE_OFFSET))?;
                let mut here = self.cmd;
                for (h, o) in here.iter_mut().zip(off) {
                    *h = h.checked_sub(o).ok_or(Refusal::Range(RANGE_OFFSET))?;
                }
                let words = [block_x(&b, diam), b.z];
                for ((s, p), w) in offsets.shift.iter_mut().zip(here).zip(words) {
                    if let Some(w) = w {
                        *s = s
                            .checked_add(p)
                            .and_then(|v| v.checked_sub(w))
                            .ok_or(Refusal::Range(RANGE_OFFSET))?;
                    }
                }
            }
            Some(Special::ClearShift(keep)) => {
                offsets.kept_shift = if keep { shift } else { [Length::ZERO; 2] };
                offsets.shift = [Length::ZERO; 2];
            }
            Some(Special::RestoreShift) => offsets.shift = offsets.kept_shift,
            Some(Special::Store(n)) => {
                if let Some(r) = offsets.reference.get_mut(usize::from(n)) {
                    *r = self.cmd;
                }
            }
            _ => {}
        }
        let off = offsets.vector(&sel).ok_or(Refusal::Range(
            "the offsets in effect add beyond 99999.999999 mm",
        ))?;
        // A block that ends nose compensation may take up a new tool
        // offset, as Fanuc's retract `G00 G40 X250. Z250. T0` does: the
        // element it finishes and the corner after it are the old offset's
        // and the old nose's, its own move (the lead-out) the new offset's.
        let leaving = self.contour.active()
            && b.compensation == Some(Compensation::Off)
            && sel.wcs == self.sel.wcs
            && b.set_work.is_none();
        if (sel != self.sel || b.set_work.is_some()) && self.contour.active() && !leaving {
            return Err(self.busy("a work or tool offset change"));
        }
        let off_before = if leaving {
            self.offsets
                .vector(&self.sel)
                .ok_or(Refusal::Range(RANGE_OFFSET))?
        } else {
            off
        };
        // The machine stays where it is when offsets change (a work system
        // selected or set, G92 and its kin, a tool's offset): the point
        // here is the same machine point in the new work coordinates, so an
        // axis the block does not name never moves, as in LinuxCNC and
        // grbl; a named axis takes the new offset up on its way. Under
        // nose compensation no offset changes (refused above) and the
        // programmed point is the contour's, not the tool's.
        let mut here = prog;
        if !self.contour.active() {
            for ((p, at), o) in here.iter_mut().zip(self.cmd).zip(off) {
                *p = at.checked_sub(o).ok_or(Refusal::Range(RANGE_OFFSET))?;
            }
        }
        if matches!(
            special,
            Some(Special::Shift | Special::ClearShift(_) | Special::RestoreShift)
        ) {
            // G92 and its kin name the point here anew.
            prog = here;
        }
        // 4. The end point: distance mode (G90/G91, U and W), diameter or
        //    radius (G07/G08), G45–G48.
        // Words are work coordinates; increments add to the programmed point.
        let mut target = here;
        let words = if b.set_work.is_some()
            || matches!(special, Some(s) if !matches!(s, Special::Reference(_) | Special::Probe(_)))
        {
            // G10's X and Z are an offset's, G53's machine coordinates,
            // G92's the point here.
            (None, None)
        } else {
            (b.x, b.z)
        };
        if words.0.is_some() {
            let radius = block_x(&b, diam).unwrap_or(Length::ZERO);
            let inc = modal.incremental || b.incremental_x;
            target[0] = step(here[0], radius, inc, "X beyond 99999.999999 mm")?;
        }
        if let Some(z) = words.1 {
            let inc = modal.incremental || b.incremental_z;
            target[1] = step(here[1], z, inc, "Z beyond 99999.999999 mm")?;
        }
        if let Some(po) = b.position_offset {
            target = self.position_offset(po, &modal, &offsets, words, target, &b)?;
        }
        let has_end = words.0.is_some() || words.1.is_some();
        let arc_words = b.i.is_some() || b.k.is_some() || b.r.is_some();
        // Fanuc's `G01 Z… I…`: a right angle's chamfer or round.
        let mut square = None;
        // 5. Plane (G17–G19) and motion mode (G00–G03): the element.
        if modal.plane != Plane::Zx {
            let arc = matches!(modal.motion, Motion::ArcCw | Motion::ArcCcw)
                && special.is_none()
                && (has_end || arc_words);
            let compensating = self.contour.active()
                || matches!(
                    b.compensation,
                    Some(Compensation::Left | Compensation::Right)
                );
            if arc || compensating {
                return Err(Refusal::Geometry(match modal.plane {
                    Plane::Xy => "in G17 (XY): a lathe turns arcs and compensates in G18 (ZX)",
                    _ => "in G19 (YZ): a lathe turns arcs and compensates in G18 (ZX)",
                }));
            }
        }
        let a = |p: [Length; 2]| [p[0].as_angstrom(), p[1].as_angstrom()];
        let shape = match modal.motion {
            // G28 and G30 move through their way point themselves.
            _ if special.is_some() => None,
            Motion::Rapid | Motion::Linear => {
                if arc_words {
                    square = Some(square_corner(
                        &b,
                        modal.motion,
                        self.offsets.reading.dialect,
                    )?);
                }
                has_end.then_some(Shape::Line {
                    rapid: modal.motion == Motion::Rapid,
                })
            }
            Motion::ArcCw | Motion::ArcCcw if has_end || arc_words => {
                // An arc starts where the tool is: it cannot take up a new
                // offset on the way.
                if !self.contour.active() && here != prog {
                    return Err(Refusal::Geometry(
                        "an arc cannot take up an offset change: move in a line first",
                    ));
                }
                let dir = if modal.motion == Motion::ArcCw {
                    ArcDir::Cw
                } else {
                    ArcDir::Ccw
                };
                let ik = b.i.is_some() || b.k.is_some();
                let centre = match (ik, b.r) {
                    (true, Some(_)) => return Err(Refusal::Missing("give I and K or R, not both")),
                    (false, None) => return Err(Refusal::Missing("an arc needs I and K, or R")),
                    (false, Some(r)) => centre_from_radius(here, target, r, dir)?,
                    (true, None) if modal.arc_absolute => match (b.i, b.k) {
                        (Some(i), Some(k)) => [i, k],
                        _ => return Err(Refusal::Missing("G90.1: an arc centre needs I and K")),
                    },
                    (true, None) => {
                        let beyond = "arc centre beyond 99999.999999 mm";
                        [
                            here[0]
                                .checked_add(b.i.unwrap_or(Length::ZERO))
                                .ok_or(Refusal::Range(beyond))?,
                            here[1]
                                .checked_add(b.k.unwrap_or(Length::ZERO))
                                .ok_or(Refusal::Range(beyond))?,
                        ]
                    }
                };
                ArcPoints {
                    start: here,
                    end: target,
                    centre,
                }
                .check_radii()?;
                Some(Shape::Arc {
                    centre: a(centre),
                    dir,
                })
            }
            Motion::ArcCw | Motion::ArcCcw => None,
        };
        let element = shape.map(|shape| Element {
            from: a(here),
            to: a(target),
            shape,
            n: b.n,
        });
        // 6. The non-modal moves: G28/G30, G53.
        // G28/G30 (through the way point) and G53: rapids, G53 also a feed,
        // in machine coordinates.
        let mut machine_path = heapless::Vec::<[Length; 2], 2>::new();
        match special {
            Some(Special::Reference(n)) => {
                let mut at = self.cmd;
                if has_end {
                    at = to_machine(target, off)?;
                    if at != self.cmd {
                        let _ = machine_path.push(at);
                    }
                }
                let stored = offsets.reference.get(usize::from(n)).copied().unwrap_or(at);
                let all = !has_end;
                let end = [
                    if all || words.0.is_some() {
                        stored[0]
                    } else {
                        at[0]
                    },
                    if all || words.1.is_some() {
                        stored[1]
                    } else {
                        at[1]
                    },
                ];
                let _ = machine_path.push(end);
            }
            Some(Special::Machine) => {
                if !matches!(modal.motion, Motion::Rapid | Motion::Linear) {
                    return Err(Refusal::Missing("G53 moves in G00 or G01"));
                }
                let mut end = self.cmd;
                if let Some(x) = block_x(&b, diam) {
                    end[0] = x;
                }
                if let Some(z) = b.z {
                    end[1] = z;
                }
                let _ = machine_path.push(end);
            }
            Some(Special::Probe(_)) => {
                if modal.feed_mode == FeedMode::PerRev {
                    return Err(Refusal::Missing(
                        "G38.2 to G38.5 probe at a feed per minute: G94 (G98) first",
                    ));
                }
                let end = to_machine(target, off)?;
                if end == self.cmd {
                    return Err(Refusal::Geometry(
                        "G38.2 to G38.5 end where the tool already is",
                    ));
                }
                let _ = machine_path.push(end);
            }
            _ => {}
        }
        let rapid = match special {
            Some(Special::Machine) => modal.motion == Motion::Rapid,
            Some(Special::Probe(_)) => false,
            _ => true,
        };
        let feeds = element.is_some_and(|e| !matches!(e.shape, Shape::Line { rapid: true }))
            || (!machine_path.is_empty() && !rapid);
        // Output blocks of the element held back by compensation run at its
        // feed; this block's own and the corners between, at this one's.
        if feeds && modal.feed.is_some_and(|f| f.as_angstrom() == 0) {
            return Err(Refusal::Value("F", "0: a feed move needs a feed above 0"));
        }
        let now = if feeds {
            path_feed(&modal, &spindle, here[0])
                .map_err(|e| Refusal::Value("F", e.as_str()))?
                .map(|f| self.overridden(f, modal.feed_mode))
        } else {
            None
        };
        // 7. Nose compensation (G40–G42, G41.1/G42.1, G450/G451).
        let dynamic_tool = match (b.dynamic_nose, b.nose_tool) {
            (Some(nose), _) => Some(Tool::new(
                nose.radius,
                TipCode::new(linuxcnc_orientation(nose.orientation)).unwrap_or(self.cfg.tip),
            )),
            // G41/G42 D: the named tool's nose (D0: the loaded tool's).
            (None, Some(0)) => None,
            (None, Some(d)) => Some(self.nose_of(&offsets, d)),
            // G40 too: the lead-out is the nose's that compensated.
            (None, _) => self.dynamic_tool,
        };
        let tool = dynamic_tool.unwrap_or_else(|| {
            if leaving {
                self.nose(&self.offsets, &self.sel)
            } else {
                self.nose(&offsets, &sel)
            }
        });
        let round = square.or(b.round);
        if round.is_some()
            && (b.stop.is_some() || b.gear.is_some() || b.machine_m.is_some() || b.dwell.is_some())
        {
            return Err(Refusal::Missing(
                ",C and ,R wait for the next move: M00-M02, M30, M41-M44, machine M codes and G04 on a line of their own",
            ));
        }
        let (contour, moves) = self
            .contour
            .rounded(&tool, b.compensation, b.corner, element, round, b.n)
            .map_err(Refusal::Contour)?;
        // The blocks in machine coordinates: the tip's path plus the offsets.
        let mut moves = moves;
        for m in moves.iter_mut() {
            // The lead-out of a block that ends compensation takes a new
            // offset up on the axes it names; an axis it leaves out keeps
            // the old one (it never moves by an offset change).
            let off = if m.origin == Origin::Current {
                [
                    if words.0.is_some() {
                        off[0]
                    } else {
                        off_before[0]
                    },
                    if words.1.is_some() {
                        off[1]
                    } else {
                        off_before[1]
                    },
                ]
            } else {
                off_before
            };
            m.to = shifted(m.to, off)?;
            if let MoveKind::Arc { centre, .. } = &mut m.kind {
                *centre = shifted(*centre, off)?;
            }
        }
        for to in &machine_path {
            // No element, no compensation: room for both.
            let _ = moves.push(Move {
                to: a(*to),
                kind: MoveKind::Line { rapid },
                origin: Origin::Current,
            });
        }
        if feeds && modal.feed.is_none() {
            return Err(Refusal::Value(
                "F",
                "not programmed: a feed move needs F (mm/min)",
            ));
        }
        // 8. Stops (M00, M01, M02/M30), checked against compensation.
        let end = b.stop == Some(Stop::End);
        if end && contour.active() {
            return Err(Refusal::Busy("M02/M30"));
        }
        let pause = match b.stop {
            Some(Stop::Pause) => true,
            Some(Stop::Optional) => self.offsets.reading.optional_stop,
            _ => false,
        };
        if pause && contour.active() {
            // The compensated path of the last element is not known yet.
            return Err(Refusal::Busy("M00/M01"));
        }
        // 9. Motion planned and checked whole.
        // Plan and check every block before the first one moves.
        let mut planned = heapless::Vec::<Planned, MAX_MOVES>::new();
        let mut cmd = self.cmd;
        let mut pos = self.pos;
        for m in &moves {
            // A corner belongs to the cut on either side of it: at this
            // block's feed, or the previous one's into a rapid.
            let feed = match m.origin {
                Origin::Previous => self.element_feed,
                Origin::Waiting => self.round_feed,
                Origin::Current => now,
                Origin::Corner => now.or(self.element_feed),
            };
            let p = self.plan_move(cmd, pos, m, feed, io)?;
            (cmd, pos) = (p.end(), p.registers());
            // As many plans as moves: never full.
            let _ = planned.push(p);
        }
        let join = match modal.path {
            PathControl::ExactStop => Join::Stop,
            PathControl::ExactPath | PathControl::Blend => Join::Blend,
            PathControl::Tolerance(t) if t.as_angstrom() <= 100_000_000 => {
                Join::Deviation(t.as_angstrom().unsigned_abs())
            }
            PathControl::Tolerance(_) => {
                return Err(Refusal::Value("P", "a G64 tolerance of 0 to 10 mm"))
            }
        };
        let machine_m = b
            .machine_m
            .map(|code| (code, self.offsets.mcodes.get(code)));
        // In grbl's check mode, and where only the path is wanted, a
        // probing block is a feed move to its end: nothing is probed.
        let probe = match special {
            Some(Special::Probe(mode)) if self.checking.is_none() && !self.probe_as_feed => {
                Some(mode)
            }
            _ => None,
        };
        if let Some(mode) = probe {
            if b.stop.is_some() || b.gear.is_some() || machine_m.is_some() {
                return Err(Refusal::Missing(
                    "G38.2 to G38.5 with M00 to M02, M30, M41 to M44 or a machine's M code: one block each",
                ));
            }
            self.probe_ready(mode, io)?;
        }
        if (b.gear.is_some() || machine_m.is_some()) && contour.active() {
            return Err(Refusal::Busy("a gear range or a machine's M code"));
        }
        // 10. Committed, in this order: path control (G61/G64), the gear
        //     range (M41–M44), the machine's own M code, the spindle and
        //     coolant, the motion, a stop or the program's end.
        // Nothing refuses the block from here on.
        self.machine.set_join(join);
        // A gear range, then the machine's own M code, at rest before the
        // spindle switches and the block moves.
        if let Some(range) = b.gear {
            self.machine.flush(&mut Sink::new(io, self.drive));
            let r = self
                .gears
                .get(usize::from(range).saturating_sub(1))
                .copied()
                .flatten();
            match r {
                Some(top) => send_message(
                    io,
                    format_args!("M4{range}: shift the gearbox to range {range} (up to {top} rpm), then cycle start"),
                ),
                None => send_message(
                    io,
                    format_args!("M4{range}: shift the gearbox to range {range}, then cycle start"),
                ),
            }
            self.program_stop(40 + u16::from(range), io);
        }
        if let Some((code, action)) = machine_m {
            let m = code / 10;
            match action {
                MAction::Stop => {
                    self.machine.flush(&mut Sink::new(io, self.drive));
                    send_message(
                        io,
                        format_args!(
                            "M{m:02}: the machine's own M code; do it by hand, then cycle start"
                        ),
                    );
                    self.program_stop(m, io);
                }
                MAction::Nothing => {}
                MAction::Output(n, on) => {
                    self.machine.flush(&mut Sink::new(io, self.drive));
                    io.user_output(n, on);
                }
                MAction::Wait(n, level) => {
                    self.machine.flush(&mut Sink::new(io, self.drive));
                    io.wait_input(n, level);
                }
            }
        }
        // The spindle and the coolant switch with the axes at rest, before
        // the block's motion (as LinuxCNC orders a block); a dwell waits
        // there too.
        if b.dwell.is_some() || b.tool_change {
            self.machine.flush(&mut Sink::new(io, self.drive));
        }
        let outputs = self.switch_aux(&aux, modal.units, io);
        if let Some(us) = b.dwell {
            io.dwell(us);
        }
        // The blocks carry the speed at their start (under G96 it follows
        // X block by block).
        self.machine.set_spindle(outputs.rpm);
        // The DATA lines write X as this block reads it.
        self.cfg.diam = diam;
        if let Some(mode) = probe {
            io.probe_arm(Some(mode.toward));
        }
        for p in &planned {
            *crc = self.run_planned(p, *crc, io);
        }
        if let Some(end) = machine_path.last() {
            self.prog = [
                end[0].checked_sub(off[0]).unwrap_or(end[0]),
                end[1].checked_sub(off[1]).unwrap_or(end[1]),
            ];
        } else if element.is_some() || has_end {
            self.prog = target;
        } else {
            self.prog = prog;
        }
        self.modal = modal;
        self.aux = aux;
        self.sel = sel;
        self.take_offsets(offsets);
        self.dynamic_tool = if contour.active() { dynamic_tool } else { None };
        self.contour = contour;
        self.last_moves = moves;
        if element.is_some() {
            // The feed of the element compensation holds, and of the one
            // waiting for its corner: a move that waits keeps its own, and
            // the one it sent on (its waiting predecessor's round) goes
            // to compensation with that one's.
            if contour.rounding() {
                if self.contour.rounding() {
                    self.element_feed = self.round_feed;
                }
                self.round_feed = now;
            } else {
                self.element_feed = now;
            }
        }
        if let Some(mode) = probe {
            self.probe_end(mode, io)?;
        }
        if pause {
            // At rest where the block ends, until cycle start.
            self.machine.flush(&mut Sink::new(io, self.drive));
            let code = if b.stop == Some(Stop::Pause) { 0 } else { 1 };
            self.program_stop(code, io);
        }
        if end {
            // The end of the program: at rest, spindle and coolant off, the
            // modes of power-on but for the motion mode, the unit and F.
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.modal = Modal {
                motion: self.modal.motion,
                units: self.modal.units,
                feed: self.modal.feed,
                ..Modal::POWER_ON
            };
            self.aux = self.aux.stopped();
            self.switch_outputs(self.outputs_for(&self.aux, self.modal.units), io);
        }
        Ok(Block::Run)
    }

    /// The spindle `aux` asks for, within its top speed, checked at the
    /// speed where the block starts: the programmed X, the diameter the
    /// tool cuts at (X0 of every work system is the spindle's axis;
    /// offsets move the slide, not the part).
    pub(super) fn spindle_of(
        &self,
        aux: &Aux,
        units: Units,
    ) -> Result<crate::interp::SpindleState, Refusal<'static>> {
        let spindle = aux.spindle.within(self.top_speed(aux));
        if aux.spindle.turning != Spindle::Off {
            spindle
                .rpm(self.prog[0], units)
                .map_err(|e| Refusal::Value("S", e.as_str()))?;
        }
        Ok(spindle)
    }

    /// Switches the spindle and the coolant to `aux` with the axes at rest
    /// (nothing waits if they do not change; a spindle that starts or
    /// changes speed gets up to it first); the outputs `aux` asks for.
    pub(super) fn switch_aux<I: Io>(&mut self, aux: &Aux, units: Units, io: &mut I) -> Outputs {
        let outputs = self.outputs_for(aux, units);
        if self.aux.needs_rest(aux) {
            self.machine.flush(&mut Sink::new(io, self.drive));
            let (was, now) = (self.outputs, outputs);
            self.switch_outputs(now, io);
            if now.spindle != Spindle::Off && (was.spindle != now.spindle || was.rpm != now.rpm) {
                io.dwell(self.spinup_us);
            }
        }
        outputs
    }

    /// A cycle block's spindle and coolant words taken, before its first
    /// move: switched at rest, then in force.
    pub(super) fn take_aux<I: Io>(&mut self, aux: Aux, io: &mut I) {
        let outputs = self.switch_aux(&aux, self.modal.units, io);
        self.machine.set_spindle(outputs.rpm);
        self.aux = aux;
    }
}

/// Fanuc's and Haas' right-angle chamfer or round on a `G01` along one
/// axis: `Z… I±i`, `X… K±k` (a chamfer), `Z… R±r`, `X… R±r` (a round),
/// the sign the way of the next move along the other axis.
fn square_corner(
    b: &crate::gcode::Block,
    motion: Motion,
    dialect: crate::gcode::Dialect,
) -> Result<crate::gcode::CornerRound, Refusal<'static>> {
    let arc = Refusal::Missing("I, K and R need G02 or G03");
    if dialect != crate::gcode::Dialect::Fanuc || motion != Motion::Linear {
        return Err(arc);
    }
    let form = Refusal::Missing(
        "a right angle's chamfer or round: G01 Z with I or R, G01 X with K or R, one word",
    );
    if b.round.is_some() {
        return Err(Refusal::Missing(
            "one corner a block: ,C or ,R, or I, K or R",
        ));
    }
    // The axis of the next move, and the word.
    let (next, word, chamfer) = match (b.x.is_some(), b.z.is_some(), b.i, b.k, b.r) {
        (false, true, Some(i), None, None) => (0, i, true),
        (true, false, None, Some(k), None) => (1, k, true),
        (false, true, None, None, Some(r)) => (0, r, false),
        (true, false, None, None, Some(r)) => (1, r, false),
        _ => return Err(form),
    };
    let size = if word.as_angstrom() < 0 {
        word.neg()
    } else {
        word
    };
    if size == Length::ZERO {
        return Err(Refusal::Value(
            if chamfer {
                if next == 0 {
                    "I"
                } else {
                    "K"
                }
            } else {
                "R"
            },
            "a chamfer or round above 0",
        ));
    }
    Ok(crate::gcode::CornerRound::Square {
        size,
        chamfer,
        next,
        plus: word.as_angstrom() > 0,
    })
}

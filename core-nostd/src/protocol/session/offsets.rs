//! Work offsets, the tool table and the positions they make: `ZERO`,
//! `TOOL`, `WORK`, `POS`, and the offsets a G-code block takes up.

use super::*;

impl Session {
    /// `ZERO [X=] [Z=]`: the current point becomes X, Z (0 when omitted) in
    /// program coordinates; nothing moves.
    #[inline(never)]
    pub(super) fn zero_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [x, z] = args.values();
        self.not_compensating("ZERO")?;
        let work = [
            match x {
                Some(v) => self.x_word(parse_length("X", v)?)?,
                None => Length::ZERO,
            },
            match z {
                Some(v) => parse_length("Z", v)?,
                None => Length::ZERO,
            },
        ];
        let cmd = to_machine(work, self.offset())?;
        let pos = ImpulsePoint {
            x: quantize(cmd[0], self.cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
            z: quantize(cmd[1], self.cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
        };
        self.machine.flush(&mut Sink::new(io, self.drive));
        let mut sink = Sink::new(io, self.drive);
        self.machine.clear_record(&mut sink);
        self.machine.set_position(point_q32(cmd), pos, &mut sink);
        self.cmd = cmd;
        self.prog = work;
        self.pos = pos;
        // The machinist has set where the carriage is: the machine
        // position is no longer the one homing found.
        self.lost = false;
        self.homed = [false; 2];
        send_ok(io, None);
        Ok(())
    }

    /// Lecture 13's `G45`–`G48`: each axis move the block names, from the
    /// programmed point to `target`, lengthened (shortened) by the
    /// register's offset for that axis (geometry plus wear; X on the
    /// radius), once or twice. A move of zero goes the offset's way, as if
    /// it were positive (Fanuc's rule).
    pub(super) fn position_offset(
        &self,
        po: crate::gcode::PositionOffset,
        modal: &Modal,
        offsets: &Offsets,
        words: (Option<Length>, Option<Length>),
        mut target: [Length; 2],
        b: &crate::gcode::Block,
    ) -> Result<[Length; 2], Refusal<'static>> {
        if !matches!(modal.motion, Motion::Rapid | Motion::Linear) {
            return Err(Refusal::Missing("G45 to G48 move in a line: G00 or G01"));
        }
        if self.contour.active() || b.compensation.is_some() {
            return Err(self.busy("G45 to G48 with nose compensation"));
        }
        let beyond = "G45 to G48: the move with its offset beyond 99999.999999 mm";
        let k = offsets
            .tools
            .get(usize::from(po.register).wrapping_sub(1))
            .and_then(|t| t.offset())
            .ok_or(Refusal::Range(beyond))?;
        let given = [words.0.is_some(), words.1.is_some()];
        for axis in 0..2 {
            let (Some(&on), Some(&k), Some(t), Some(&from)) = (
                given.get(axis),
                k.get(axis),
                target.get_mut(axis),
                self.prog.get(axis),
            ) else {
                continue;
            };
            if !on {
                continue;
            }
            let m = t.checked_sub(from).ok_or(Refusal::Range(beyond))?;
            let sign: i64 = if m < Length::ZERO { -1 } else { 1 };
            let delta = k
                .as_angstrom()
                .checked_mul(i64::from(po.times) * sign)
                .and_then(Length::from_angstrom)
                .ok_or(Refusal::Range(beyond))?;
            *t = t.checked_add(delta).ok_or(Refusal::Range(beyond))?;
        }
        Ok(target)
    }

    /// The tool selection and the offsets after a block's `G54`–`G59`,
    /// `T`, `M06`, `G43`/`G49` and `G10` words.
    #[inline(never)]
    pub(super) fn offsets_after(
        &self,
        b: &crate::gcode::Block,
        aux: &Aux,
        diam: bool,
    ) -> Result<(Selection, Offsets), Refusal<'static>> {
        let mut sel = self.sel;
        if let Some(w) = b.wcs {
            sel.wcs = w;
        }
        let beyond = "offset register beyond the table's 32";
        match self.offsets.reading.dialect {
            Dialect::Fanuc => {
                if let Some(t) = b.tool {
                    sel.loaded = t.tool;
                    sel.register = t.offset.unwrap_or(0);
                    if usize::from(sel.register) > TOOL_REGISTERS {
                        return Err(Refusal::Value("T", beyond));
                    }
                }
            }
            Dialect::Iso => {
                if b.tool_change {
                    sel.loaded = aux
                        .tool
                        .map(|t| t.tool)
                        .ok_or(Refusal::Missing("M06 needs the tool: T"))?;
                }
                match b.tool_offset {
                    Some(ToolOffset::On(h)) => {
                        sel.register = h.unwrap_or(sel.loaded);
                        if usize::from(sel.register) > TOOL_REGISTERS {
                            return Err(Refusal::Value("H", beyond));
                        }
                    }
                    Some(ToolOffset::Off) => sel.register = 0,
                    None => {}
                }
            }
        }
        let mut offsets = self.offsets;
        if let Some(set) = b.set_work.filter(|s| s.tool) {
            // G10 L1/L10: a tool's geometry; L10 so that the point here,
            // with that tool's offset in the work system in effect, has
            // the block's coordinates (machine = work + system + tool +
            // G92: the tool's geometry is what is left, less its wear).
            let values = [block_x(b, diam), b.z];
            let system = offsets
                .work
                .get(usize::from(sel.wcs))
                .copied()
                .unwrap_or([Length::ZERO; 2]);
            let shift = offsets.shift;
            let entry = usize::from(set.register)
                .checked_sub(1)
                .and_then(|i| offsets.tools.get_mut(i))
                .ok_or(Refusal::Value("P", "names a tool's register: 1 to 32"))?;
            for a in 0..2 {
                let Some(v) = values.get(a).copied().flatten() else {
                    continue;
                };
                let g = if set.here {
                    self.cmd[a & 1]
                        .checked_sub(system[a & 1])
                        .and_then(|p| p.checked_sub(shift[a & 1]))
                        .and_then(|p| p.checked_sub(entry.wear[a & 1]))
                        .and_then(|p| p.checked_sub(v))
                } else {
                    Some(v)
                };
                entry.geometry[a & 1] = g.ok_or(Refusal::Range(RANGE_OFFSET))?;
            }
            return Ok((sel, offsets));
        }
        if let Some(set) = b.set_work {
            // The tool's offset with the selection of this block.
            let tool = offsets
                .tool_offset(&sel)
                .ok_or(Refusal::Range(RANGE_OFFSET))?;
            let values = [block_x(b, diam), b.z];
            // P0: the system in effect after this block's G54–G59.
            let register = match set.register {
                0 => usize::from(sel.wcs),
                p => usize::from(p).saturating_sub(1),
            };
            let work = offsets
                .work
                .get_mut(register)
                .ok_or(Refusal::Value("P", "names G54 to G59: 1 to 6"))?;
            for (((w, v), at), off) in work.iter_mut().zip(values).zip(self.cmd).zip(tool) {
                let Some(v) = v else { continue };
                *w = if set.here {
                    // So that the tool's point has coordinate v.
                    at.checked_sub(off)
                        .and_then(|p| p.checked_sub(v))
                        .ok_or(Refusal::Range(RANGE_OFFSET))?
                } else {
                    v
                };
            }
        }
        Ok((sel, offsets))
    }

    /// The nose compensation uses: the register of the tool in effect
    /// (Fanuc: the offset register; ISO: the loaded tool's) when its nose
    /// is set, else the configured `RN` and `TIP`.
    pub(in crate::protocol) fn nose(&self, offsets: &Offsets, sel: &Selection) -> Tool {
        let register = match self.offsets.reading.dialect {
            Dialect::Fanuc => sel.register,
            Dialect::Iso => sel.loaded,
        };
        self.nose_of(offsets, register)
    }

    /// The nose of a register (ISO's `G41`/`G42 D`: a tool's), else the
    /// configured `RN` and `TIP`.
    pub(in crate::protocol) fn nose_of(&self, offsets: &Offsets, register: u8) -> Tool {
        match offsets.register(register).and_then(|t| t.nose) {
            Some((r, tip)) => Tool::new(r, TipCode::new(tip).unwrap_or(self.cfg.tip)),
            None => Tool::new(self.cfg.rn, self.cfg.tip),
        }
    }

    /// The tool table, the work offsets and the stored positions.
    pub fn offsets(&self) -> &Offsets {
        &self.offsets
    }

    /// Counts the changes of what a board keeps in flash (the table, the
    /// work offsets and the stored positions): a board saves when it moved.
    pub fn offsets_generation(&self) -> u32 {
        self.generation
    }

    /// The table, work offsets and stored positions kept from before the
    /// power cut (a board loads them at power-on, before any request).
    pub fn restore_offsets(&mut self, offsets: Offsets) {
        self.offsets = offsets;
        self.prog = self.work_point(self.cmd);
        self.power_on_homing();
        self.apply_backlash();
    }

    /// New offsets; what a board keeps of them changed or not.
    pub(super) fn take_offsets(&mut self, new: Offsets) {
        let kept = |o: &Offsets| {
            (
                o.work,
                o.tools,
                o.reference,
                o.mcodes,
                o.reading,
                o.wiring,
                o.homing,
            )
        };
        if kept(&new) != kept(&self.offsets) {
            self.generation = self.generation.wrapping_add(1);
        }
        self.offsets = new;
    }

    /// The offsets in effect (machine = work + this); always within range,
    /// as every change of them is checked.
    pub(super) fn offset(&self) -> [Length; 2] {
        self.offsets.vector(&self.sel).unwrap_or([Length::ZERO; 2])
    }

    /// A machine point in work coordinates, as far as the range allows.
    pub(super) fn work_point(&self, machine: [Length; 2]) -> [Length; 2] {
        let off = self.offset();
        [
            machine[0].checked_sub(off[0]).unwrap_or(machine[0]),
            machine[1].checked_sub(off[1]).unwrap_or(machine[1]),
        ]
    }

    /// `OK PX= PZ= X= Z= [MX= MZ=]`: the registers, the commanded point in
    /// work coordinates, and while offsets are in effect in machine
    /// coordinates too (X a diameter when `DIAM=1`).
    #[inline(never)]
    pub(super) fn pos_reply<I: Io>(&self, io: &mut I) {
        let work = self.work_point(self.cmd);
        let mut line = ReplyLine::new();
        let _ = write!(
            line,
            "OK PX={} PZ={} X=",
            self.pos.x.get(),
            self.pos.z.get()
        );
        let _ = self.write_x(&mut line, work[0]);
        let _ = write!(line, " Z={}", work[1]);
        if work != self.cmd {
            let _ = line.write_str(" MX=");
            let _ = self.write_x(&mut line, self.cmd[0]);
            let _ = write!(line, " MZ={}", self.cmd[1]);
        }
        io.send(line.finish());
    }

    /// An X value as the words read it: a diameter when `DIAM=1`.
    pub(super) fn write_x(&self, line: &mut ReplyLine, x: Length) -> fmt::Result {
        let factor = if self.cfg.diam { 2 } else { 1 };
        // |x| < 10¹² Å: doubling cannot overflow.
        write_mm4(line, div_round_half_away(x.as_angstrom() * factor, 1_000))
    }

    /// `TOOL N= [X=] [Z=] [WX=] [WZ=] [R=] [T=]`: an offset register of the
    /// tool table, set or reported: geometry and wear (X a diameter when
    /// `DIAM=1`), nose radius and tip code (`R=- T=-` until set).
    #[inline(never)]
    pub(super) fn tool_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [n, x, z, wx, wz, r, t] = args.values();
        if n.is_none() {
            return Err(Refusal::Missing("TOOL needs N, the register: 1 to 32"));
        }
        let n = match parse_count("N", n, 0)? {
            n @ 1..=32 => n as u8,
            _ => return Err(Refusal::Value("N", "must be 1 to 32")),
        };
        let mut offsets = self.offsets;
        let entry = offsets
            .tools
            .get_mut(usize::from(n) - 1)
            .ok_or(Refusal::Value("N", "must be 1 to 32"))?;
        if let Some(v) = x {
            entry.geometry[0] = self.x_word(parse_length("X", v)?)?;
        }
        if let Some(v) = z {
            entry.geometry[1] = parse_length("Z", v)?;
        }
        if let Some(v) = wx {
            entry.wear[0] = self.x_word(parse_length("WX", v)?)?;
        }
        if let Some(v) = wz {
            entry.wear[1] = parse_length("WZ", v)?;
        }
        if r.is_some() || t.is_some() {
            let (r0, t0) = entry.nose.unwrap_or((self.cfg.rn, self.cfg.tip.get()));
            let r = match r {
                Some(v) => parse_bounded("R", v, 0, MAX_NOSE_RADIUS_UM, "must be 0 to 25 mm")?,
                None => r0,
            };
            let t = match parse_count("T", t, u32::from(t0))? {
                t @ 0..=9 => t as u8,
                _ => return Err(Refusal::Value("T", "must be 0 to 9")),
            };
            entry.nose = Some((r, t));
        }
        let entry = *entry;
        let setting = x.is_some() || z.is_some() || wx.is_some() || wz.is_some();
        if setting || r.is_some() || t.is_some() {
            if offsets.vector(&self.sel).is_none() {
                return Err(Refusal::Range(RANGE_OFFSET));
            }
            let in_effect = n == self.sel.register || n == self.sel.loaded;
            if self.contour.active() && in_effect {
                return Err(self.busy("TOOL of the register in effect"));
            }
        }
        self.take_offsets(offsets);
        let mut line = ReplyLine::new();
        let _ = write!(line, "OK N={n} X=");
        let _ = self.write_x(&mut line, entry.geometry[0]);
        let _ = write!(line, " Z={} WX=", entry.geometry[1]);
        let _ = self.write_x(&mut line, entry.wear[0]);
        let _ = write!(line, " WZ={}", entry.wear[1]);
        let _ = match entry.nose {
            Some((r, t)) => write!(line, " R={r} T={t}"),
            None => line.write_str(" R=- T=-"),
        };
        io.send(line.finish());
        Ok(())
    }

    /// `WORK G=54…59 [X=] [Z=]`: a work offset, set or reported: where
    /// that system's zero lies in machine coordinates (X a diameter when
    /// `DIAM=1`).
    #[inline(never)]
    pub(super) fn work_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [g, x, z] = args.values();
        if g.is_none() {
            return Err(Refusal::Missing("WORK needs G, the system: 54 to 59"));
        }
        let g = match parse_count("G", g, 0)? {
            g @ 54..=59 => g as u8,
            _ => return Err(Refusal::Value("G", "must be 54 to 59")),
        };
        let mut offsets = self.offsets;
        let work = offsets
            .work
            .get_mut(usize::from(g) - 54)
            .ok_or(Refusal::Value("G", "must be 54 to 59"))?;
        if let Some(v) = x {
            work[0] = self.x_word(parse_length("X", v)?)?;
        }
        if let Some(v) = z {
            work[1] = parse_length("Z", v)?;
        }
        let work = *work;
        if x.is_some() || z.is_some() {
            if offsets.vector(&self.sel).is_none() {
                return Err(Refusal::Range(RANGE_OFFSET));
            }
            if self.contour.active() && g - 54 == self.sel.wcs {
                return Err(self.busy("WORK of the system in effect"));
            }
        }
        self.take_offsets(offsets);
        let mut line = ReplyLine::new();
        let _ = write!(line, "OK G={g} X=");
        let _ = self.write_x(&mut line, work[0]);
        let _ = write!(line, " Z={}", work[1]);
        io.send(line.finish());
        Ok(())
    }
}

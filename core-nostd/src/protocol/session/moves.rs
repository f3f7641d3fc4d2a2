//! Moves and arcs: `MOVE`, `ARC`, `CONE`, and the planned blocks every
//! motion request runs through (checked whole, then run).

use super::*;

impl Session {
    /// `CONE A= [RN=]`: Krylenko's Xc, Zc, Xc on the diameter and Nomura's
    /// A, B, C; `NEAR=` names any value within 10⁻⁹ mm of a printing tie.
    #[inline(never)]
    pub(super) fn cone_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [a, rn] = args.values();
        let a = a.ok_or(Refusal::Missing("CONE needs A"))?;
        let alpha = Angle::from_degrees_str(a).map_err(|e| {
            Refusal::Value(
                "A",
                match e {
                    AngleError::Malformed => "not degrees (45, 2.8642) or D:M:S (2:51:51)",
                    AngleError::OutOfRange => "must lie between 0 and 90 degrees",
                },
            )
        })?;
        let r = match rn {
            Some(v) => parse_bounded("RN", v, 0, MAX_NOSE_RADIUS_UM, "must be 0 to 25 mm")?,
            None => self.cfg.rn,
        };
        let k = cone(alpha, r);
        let xcd = k.xc.doubled();
        let values = [
            ("XC", k.xc),
            ("ZC", k.zc),
            ("XCD", xcd),
            ("NA", k.xc),
            ("NB", k.zc),
            ("NC", k.c),
        ];
        let mut line = ReplyLine::new();
        let _ = line.write_str("OK");
        for (key, v) in values {
            let _ = write!(line, " {key}=");
            let _ = write_mm4(&mut line, v.tenth_um());
        }
        let mut first = true;
        for (key, v) in values {
            if v.near_tie() {
                let _ = write!(line, "{}{key}", if first { " NEAR=" } else { "," });
                first = false;
            }
        }
        io.send(line.finish());
        Ok(())
    }

    #[inline(never)]
    pub(super) fn arc_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [x, z, i, k, dir, tol, pass, mode, feed] = args.values();
        self.not_compensating("ARC")?;
        let (Some(x), Some(z), Some(i), Some(k), Some(dir)) = (x, z, i, k, dir) else {
            return Err(Refusal::Missing("ARC needs X, Z, I, K and DIR"));
        };
        let dir = if dir.eq_ignore_ascii_case("CW") {
            ArcDir::Cw
        } else if dir.eq_ignore_ascii_case("CCW") {
            ArcDir::Ccw
        } else {
            return Err(Refusal::Value("DIR", "must be CW or CCW"));
        };
        let tol = match tol {
            Some(v) => parse_tol(v)?,
            None => self.cfg.tol,
        };
        let finish = match pass {
            Some(v) => parse_pass(v)? == Pass::Finish,
            None => self.cfg.pass == Pass::Finish,
        };
        let direct = match mode {
            None => false,
            Some(v) if v.eq_ignore_ascii_case("CHORD") => false,
            Some(v) if v.eq_ignore_ascii_case("DIRECT") => true,
            Some(_) => return Err(Refusal::Value("MODE", "must be CHORD or DIRECT")),
        };
        let feed = match feed {
            None => None,
            Some(v) => Some(parse_feed(v)?),
        };
        let end = to_machine(
            [self.x_word(parse_length("X", x)?)?, parse_length("Z", z)?],
            self.offset(),
        )?;
        let (di, dk) = (parse_length("I", i)?, parse_length("K", k)?);
        let beyond = Refusal::Range("arc centre beyond 99999.999999 mm");
        let centre = [
            self.cmd[0].checked_add(di).ok_or(beyond)?,
            self.cmd[1]
                .checked_add(dk)
                .ok_or(Refusal::Range("arc centre beyond 99999.999999 mm"))?,
        ];
        let points = ArcPoints {
            start: self.cmd,
            end,
            centre,
        };
        if direct {
            self.arc_direct(&points, dir, feed, io)
        } else {
            self.arc_chords(&points, dir, tol, finish, feed, io)
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn arc_chords<'a, I: Io>(
        &mut self,
        points: &ArcPoints,
        dir: ArcDir,
        tol: Length,
        finish: bool,
        feed: Option<Feed>,
        io: &mut I,
    ) -> Outcome<'a> {
        let plan = ChordPlan::new(points, dir, tol, finish)?;
        let n = plan.chords();
        self.check_chords(&plan, self.pos, io)?;
        let start = self.pos;
        let crc = self.run_chords(&plan, points, feed, io, true, Crc32::new());
        let at = self.pos;
        let dphi = plan.dphi_arcsec();
        // Degrees with 6 decimals, half away from zero: dphi·10⁶/3600 = dphi·2500/9.
        let micro_deg = (u64::from(dphi) * 5000 + 9) / 18;
        send_ok(
            io,
            Some(format_args!(
                "N={n} DPHI={}.{:06} {}",
                micro_deg / 1_000_000,
                micro_deg % 1_000_000,
                MotionSummary::new(start, at, &crc)
            )),
        );
        Ok(())
    }

    pub(super) fn arc_direct<'a, I: Io>(
        &mut self,
        points: &ArcPoints,
        dir: ArcDir,
        feed: Option<Feed>,
        io: &mut I,
    ) -> Outcome<'a> {
        let arc = DirectArc::new(points, dir, self.pos, self.cfg.hx, self.cfg.hz)?;
        let mut crc = Crc32::new();
        let mut events = 0u32;
        // Every point the arc passes, within the soft limits.
        let mut at = self.pos;
        let soft = self.offsets.homing.soft && self.homed != [false; 2];
        for e in arc.events() {
            crc.push(e.bits());
            events += 1;
            if soft {
                let step = |neg: bool| if neg { -1 } else { 1 };
                if e.x_steps() {
                    at.x = Impulses(at.x.get().saturating_add(step(e.x_negative())));
                }
                if e.z_steps() {
                    at.z = Impulses(at.z.get().saturating_add(step(e.z_negative())));
                }
                self.soft_check(at)?;
            }
        }
        let start = self.pos;
        self.cmd = points.end;
        self.prog = self.work_point(points.end);
        self.pos = arc.to();
        let rate = self.drive.rate_hz();
        let h = [self.cfg.hx, self.cfg.hz];
        self.machine.fixed_rate(
            arc.events(),
            arc.delta(),
            h,
            rate,
            point_q32(points.end),
            &mut Sink::new(io, self.drive),
        );
        let (dx, dz) = arc.delta();
        let (j, k) = arc.jk();
        let g = match dir {
            ArcDir::Cw => "G02",
            ArcDir::Ccw => "G03",
        };
        let mut line = ReplyLine::new();
        let _ = write!(line, "DATA {g}");
        if dx != 0 {
            let _ = write!(line, " X{dx:+}");
        }
        if dz != 0 {
            let _ = write!(line, " Z{dz:+}");
        }
        let _ = write!(line, " J{j} K{k}");
        if let Some(f) = feed {
            let _ = write!(line, " F{}", arc.feed_word(f.mm_per_min()));
        }
        io.send(line.finish());
        send_ok(
            io,
            Some(format_args!(
                "N={events} {}",
                MotionSummary::new(start, self.pos, &crc)
            )),
        );
        Ok(())
    }

    /// Plans one move from the commanded point `cmd` and registers `pos`,
    /// checking every block of it against the machine's limits.
    pub(in crate::protocol) fn plan_move<I: Io>(
        &self,
        cmd: [Length; 2],
        pos: ImpulsePoint,
        m: &Move,
        feed: Option<Feed>,
        io: &mut I,
    ) -> Result<Planned, Refusal<'static>> {
        let end = point(m.to)?;
        match m.kind {
            MoveKind::Line { rapid } => {
                let to = ImpulsePoint {
                    x: quantize(end[0], self.cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
                    z: quantize(end[1], self.cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
                };
                let block = LinearBlock::new(pos, to).map_err(|_| Refusal::Range(RANGE_BLOCK))?;
                self.soft_check(to)?;
                Ok(Planned::Line {
                    block,
                    end,
                    rapid,
                    feed,
                })
            }
            MoveKind::Arc { centre, dir } => {
                let points = ArcPoints {
                    start: cmd,
                    end,
                    centre: point(centre)?,
                };
                let plan =
                    ChordPlan::new(&points, dir, self.cfg.tol, self.cfg.pass == Pass::Finish)?;
                let to = self.check_chords(&plan, pos, io)?;
                Ok(Planned::Arc {
                    plan,
                    points,
                    dir,
                    to,
                    feed,
                })
            }
        }
    }

    /// Runs one planned move, sends its `DATA` line, and adds its step
    /// events to `crc`.
    pub(in crate::protocol) fn run_planned<I: Io>(
        &mut self,
        p: &Planned,
        mut crc: Crc32,
        io: &mut I,
    ) -> Crc32 {
        match *p {
            Planned::Line {
                block,
                end,
                rapid,
                feed,
            } => {
                crc = block_crc(&block, crc);
                self.cmd = end;
                self.pos = block.to();
                let h = [self.cfg.hx, self.cfg.hz];
                let feed = if rapid { None } else { feed };
                self.machine.queue(
                    point_q32(end),
                    block,
                    feed,
                    h,
                    &mut Sink::new(io, self.drive),
                );
                let word = if rapid { Motion::Rapid } else { Motion::Linear };
                self.send_block_data(io, word, None);
            }
            Planned::Arc {
                plan,
                points,
                dir,
                feed,
                ..
            } => {
                crc = self.run_chords(&plan, &points, feed, io, false, crc);
                let word = match dir {
                    ArcDir::Cw => Motion::ArcCw,
                    ArcDir::Ccw => Motion::ArcCcw,
                };
                self.send_block_data(io, word, Some(centre_minus(points.centre, points.start)));
            }
        }
        crc
    }

    /// `DATA G0n X… Z… [I… K…]` for the block just run (its end is the
    /// commanded point; X a diameter when DIAM=1).
    pub(super) fn send_block_data<I: Io>(&self, io: &mut I, motion: Motion, ik: Option<[i64; 2]>) {
        let factor = if self.cfg.diam { 2 } else { 1 };
        let x = div_round_half_away(self.cmd[0].as_angstrom() * factor, 1_000);
        let mut line = ReplyLine::new();
        let _ = write!(line, "DATA {} X", motion.word());
        let _ = write_mm4(&mut line, x);
        let _ = write!(line, " Z{}", self.cmd[1]);
        if let Some([i, k]) = ik {
            let _ = line.write_str(" I");
            let _ = write_mm4(&mut line, div_round_half_away(i, 1_000));
            let _ = line.write_str(" K");
            let _ = write_mm4(&mut line, div_round_half_away(k, 1_000));
        }
        io.send(line.finish());
    }

    /// The linear block from the registers to a commanded point.
    pub(super) fn linear_block(
        &self,
        target: [Length; 2],
    ) -> Result<LinearBlock, Refusal<'static>> {
        let to = ImpulsePoint {
            x: quantize(target[0], self.cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
            z: quantize(target[1], self.cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
        };
        LinearBlock::new(self.pos, to).map_err(|_| Refusal::Range(RANGE_BLOCK))
    }

    /// Checks every chord of a plan before the first one moves (a long
    /// check lets the transport answer its real-time requests meanwhile).
    pub(super) fn check_chords<I: Io>(
        &self,
        plan: &ChordPlan,
        from: ImpulsePoint,
        io: &mut I,
    ) -> Result<ImpulsePoint, Refusal<'static>> {
        let mut at = from;
        for i in 1..=plan.chords() {
            if i % CHORDS_PER_PAUSE == 0 {
                io.pause();
            }
            let to = plan
                .chord_end(i, self.cfg.hx, self.cfg.hz)
                .map_err(|_| Refusal::Range(RANGE_POS))?;
            LinearBlock::new(at, to).map_err(|_| Refusal::Range(RANGE_BLOCK))?;
            self.soft_check(to)?;
            at = to;
        }
        Ok(at)
    }

    /// Runs the chords of a checked plan, commits the end point, and returns
    /// the CRC of all their step events; `data` sends a `DATA I= NX= NZ=`
    /// line per chord.
    pub(super) fn run_chords<I: Io>(
        &mut self,
        plan: &ChordPlan,
        points: &ArcPoints,
        feed: Option<Feed>,
        io: &mut I,
        data: bool,
        mut crc: Crc32,
    ) -> Crc32 {
        let mut at = self.pos;
        let h = [self.cfg.hx, self.cfg.hz];
        for i in 1..=plan.chords() {
            let Ok((to, point)) = plan.chord_point(i, h[0], h[1]) else {
                break;
            };
            let Ok(block) = LinearBlock::new(at, to) else {
                break;
            };
            crc = block_crc(&block, crc);
            self.machine
                .queue(point, block, feed, h, &mut Sink::new(io, self.drive));
            if data {
                let (nx, nz) = block.delta();
                send_data(io, format_args!("I={i} NX={nx} NZ={nz}"));
            }
            at = to;
        }
        self.cmd = points.end;
        self.pos = at;
        crc
    }

    /// Refuses a command that would move or re-zero the machine behind the
    /// contour engine's back.
    pub(super) fn not_compensating(&self, what: &'static str) -> Result<(), Refusal<'static>> {
        if self.contour.active() {
            return Err(self.busy(what));
        }
        Ok(())
    }

    /// An X word as a radius (halved when DIAM=1).
    pub(super) fn x_word(&self, word: Length) -> Result<Length, Refusal<'static>> {
        x_radius(word, self.cfg.diam)
    }

    /// Queues a straight move to `target` (its block from the registers):
    /// the commanded point, the programmed point and the registers move
    /// there.
    pub(super) fn queue_line<I: Io>(
        &mut self,
        target: [Length; 2],
        block: LinearBlock,
        feed: Option<Feed>,
        io: &mut I,
    ) {
        self.cmd = target;
        self.prog = self.work_point(target);
        self.pos = block.to();
        let h = [self.cfg.hx, self.cfg.hz];
        self.machine.queue(
            point_q32(target),
            block,
            feed,
            h,
            &mut Sink::new(io, self.drive),
        );
    }

    #[inline(never)]
    pub(super) fn move_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [x, z, inc, feed] = args.values();
        self.not_compensating("MOVE")?;
        let feed = match feed {
            Some(v) => Some(parse_feed(v)?),
            None => None,
        };
        let inc = match inc {
            None => false,
            Some(v) => parse_flag("INC", v)?,
        };
        // Absolute words are work coordinates; increments add to where the
        // tool is.
        let off = self.offset();
        let mut target = self.cmd;
        if let Some(v) = x {
            let radius = self.x_word(parse_length("X", v)?)?;
            let from = if inc { self.cmd[0] } else { off[0] };
            target[0] = step(from, radius, true, "X beyond 99999.999999 mm")?;
        }
        if let Some(v) = z {
            let word = parse_length("Z", v)?;
            let from = if inc { self.cmd[1] } else { off[1] };
            target[1] = step(from, word, true, "Z beyond 99999.999999 mm")?;
        }
        let target = self.jog_clip(target);
        let block = self.linear_block(target)?;
        self.soft_check(block.to())?;
        let crc = block_crc(&block, Crc32::new());
        self.queue_line(target, block, feed, io);
        send_ok(
            io,
            Some(format_args!(
                "{}",
                MotionSummary::new(block.from(), block.to(), &crc)
            )),
        );
        Ok(())
    }
}

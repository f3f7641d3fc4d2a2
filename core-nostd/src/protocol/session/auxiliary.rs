//! The spindle, coolant, gear ranges, the machine's own M codes, user
//! outputs and program stops: `AUX`, `MCODE`, `GEAR`.

use super::*;

impl Session {
    /// A program stop at rest (`M00`, `M01`, a gear range, a machine's M
    /// code not in its table; `code` the M code): the board waits for
    /// cycle start, a grbl link holds at rest and goes on.
    pub(in crate::protocol) fn program_stop<I: Io>(&mut self, code: u16, io: &mut I) {
        if io.stop_holds() {
            // grbl: a hold at rest, answered now; what follows queues and
            // waits for cycle start.
            self.machine.hold(&mut Sink::new(io, self.drive));
        } else {
            if io.background().is_some() {
                let mut view = self.view(self.machine.speed());
                view.stop = Some(code);
                io.view(&view);
            } else {
                // Nothing moves while it waits: one line answers every
                // status byte.
                let st = self.machine.status(&mut Sink::new(io, self.drive));
                let mut view = self.view(0);
                (view.outputs.rpm, view.stop) = (st.spindle, Some(code));
                let record = super::realtime::record(&st, view);
                // The line a status byte gets while the program stops.
                io.status(&record, false);
                let mut line = status_line("!STATUS", &record);
                io.stop_status(line.finish());
            }
            io.program_stop(code);
        }
        self.share_view(io);
    }

    /// The spindle's top speed with `aux`'s gear range: `AUX SMAX` and the
    /// range's own, the lower.
    pub(in crate::protocol) fn top_speed(&self, aux: &Aux) -> Option<Length> {
        let gear = aux.gear.and_then(|g| {
            self.gears
                .get(usize::from(g).saturating_sub(1))
                .copied()
                .flatten()
        });
        match (self.top, gear) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// `OK SPINDLE= S= SMODE= LIMIT= COOLANT= T=`: the auxiliary
    /// functions as programmed; `S` the commanded rpm at the programmed X (0
    /// while stopped), `LIMIT` 0 when none is set, `T` as written in the
    /// dialect (`-` when none was named).
    #[inline(never)]
    pub(super) fn aux_reply<I: Io>(&self, io: &mut I) {
        let a = &self.aux;
        let spindle = match a.spindle.turning {
            Spindle::Cw => "CW",
            Spindle::Ccw => "CCW",
            Spindle::Off => "OFF",
        };
        let mode = match a.spindle.mode {
            SpindleMode::Rpm => "RPM",
            SpindleMode::Surface => "CSS",
        };
        let coolant = match a.coolant {
            Coolant::Mist => "MIST",
            Coolant::Flood => "FLOOD",
            Coolant::Off => "OFF",
        };
        let rpm = a
            .spindle
            .within(self.top_speed(a))
            .running_rpm(self.prog[0], self.modal.units);
        let limit = a.spindle.clamp.unwrap_or(Length::ZERO);
        let mut line = ReplyLine::new();
        let _ = write!(
            line,
            "OK SPINDLE={spindle} S={rpm} SMODE={mode} LIMIT={limit} COOLANT={coolant} T="
        );
        let _ = match a.tool {
            None => line.write_str("-"),
            Some(ToolWord {
                tool,
                offset: Some(o),
            }) => write!(line, "{tool:02}{o:02}"),
            Some(ToolWord { tool, offset: None }) => write!(line, "{tool}"),
        };
        let top = self.top.unwrap_or(Length::ZERO);
        let ms = self.spinup_us / 1_000;
        let _ = write!(line, " SMAX={top} SPINUP={}.{:03}", ms / 1_000, ms % 1_000);
        io.send(line.finish());
    }

    /// `AUX [SMAX=] [SPINUP=]`: the spindle's top speed (rpm at full PWM
    /// duty, 0 for none) and the wait after it starts or changes speed
    /// (seconds); with the auxiliary functions as programmed.
    pub(super) fn aux_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [smax, spinup] = args.values();
        let mut top = self.top;
        if let Some(v) = smax {
            let l = parse_amount("SMAX", v, 99_999_999, "must be 0 to 99999.999 rpm")?;
            top = (l > Length::ZERO).then_some(l);
        }
        let mut spinup_us = self.spinup_us;
        if let Some(v) = spinup {
            let l = parse_amount("SPINUP", v, 60_000, "must be 0 to 60 s")?;
            // Å of a second to whole ms, rounded half up.
            spinup_us = (l.as_angstrom().unsigned_abs() + 5_000) / 10_000 * 1_000;
        }
        if top != self.top {
            // What the spindle turns at changes with it: at rest.
            if self.aux.spindle.turning != Spindle::Off {
                self.aux
                    .spindle
                    .within(top)
                    .rpm(self.prog[0], self.modal.units)
                    .map_err(|e| Refusal::Value("SMAX", e.as_str()))?;
            }
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.top = top;
            self.switch_outputs(self.outputs_for(&self.aux, self.modal.units), io);
        }
        self.spinup_us = spinup_us;
        self.aux_reply(io);
        Ok(())
    }

    /// `MCODE [M=n DO=STOP|NONE|ON|OFF|HIGH|LOW [N=1..4]]`: what one of
    /// the machine's own M codes does — stop with a message (the default,
    /// and what `STOP` sets back), nothing, switch user output `N` on or
    /// off, or wait for user input `N` to read high or low. Alone: the
    /// table, a `DATA` line per code set. Kept with the tool table.
    #[inline(never)]
    pub(super) fn mcode_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [m, action, n] = args.values();
        if let Some(m) = m {
            let code = match m.parse::<u16>() {
                Ok(c @ 0..=999) if m.bytes().all(|b| b.is_ascii_digit()) => c,
                _ => return Err(Refusal::Value("M", "must be a whole M code 0 to 999")),
            };
            // The codes the device runs itself are not the machine's.
            if matches!(code, 0..=9 | 30 | 41..=44 | 98 | 99) {
                return Err(Refusal::Value(
                    "M",
                    "is one the device runs itself (M00-M09, M30, M41-M44, M98, M99)",
                ));
            }
            let n = match n {
                None => None,
                Some(v) => match v.parse::<u8>() {
                    Ok(k @ 1..=4) if v.len() == 1 => Some(k),
                    _ => {
                        return Err(Refusal::Value(
                            "N",
                            "must be 1 to 4 (a user output or input)",
                        ))
                    }
                },
            };
            let need_n =
                |n: Option<u8>| n.ok_or(Refusal::Missing("ON, OFF, HIGH and LOW need N: 1 to 4"));
            let action = match action.unwrap_or("STOP") {
                a if a.eq_ignore_ascii_case("STOP") => MAction::Stop,
                a if a.eq_ignore_ascii_case("NONE") => MAction::Nothing,
                a if a.eq_ignore_ascii_case("ON") => MAction::Output(need_n(n)?, true),
                a if a.eq_ignore_ascii_case("OFF") => MAction::Output(need_n(n)?, false),
                a if a.eq_ignore_ascii_case("HIGH") => MAction::Wait(need_n(n)?, true),
                a if a.eq_ignore_ascii_case("LOW") => MAction::Wait(need_n(n)?, false),
                _ => {
                    return Err(Refusal::Value(
                        "DO",
                        "must be STOP, NONE, ON, OFF, HIGH or LOW",
                    ))
                }
            };
            if matches!(action, MAction::Stop | MAction::Nothing) && n.is_some() {
                return Err(Refusal::Missing("N only with ON, OFF, HIGH or LOW"));
            }
            let mut offsets = self.offsets;
            if !offsets.mcodes.set(code * 10, action) {
                return Err(Refusal::Range("the table holds 16 M codes"));
            }
            self.take_offsets(offsets);
        } else if action.is_some() || n.is_some() {
            return Err(Refusal::Missing("DO and N need M: the code"));
        }
        let listing = m.is_none();
        let mut count = 0;
        for (code, action) in self.offsets.mcodes.entries() {
            count += 1;
            if !listing {
                continue;
            }
            let m = code / 10;
            match action {
                MAction::Stop => {}
                MAction::Nothing => send_data(io, format_args!("M{m:02} DO=NONE")),
                MAction::Output(n, on) => send_data(
                    io,
                    format_args!("M{m:02} DO={} N={n}", if on { "ON" } else { "OFF" }),
                ),
                MAction::Wait(n, high) => send_data(
                    io,
                    format_args!("M{m:02} DO={} N={n}", if high { "HIGH" } else { "LOW" }),
                ),
            }
        }
        send_ok(io, Some(format_args!("CODES={count}")));
        Ok(())
    }

    /// `GEAR [N=1..4 TOP=rpm]`: the top speed of a gear range (`M41` …
    /// `M44`; 0: the range adds no limit). Answered with the range in
    /// effect and every range's top.
    #[inline(never)]
    pub(super) fn gear_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [n, top] = args.values();
        match (n, top) {
            (Some(n), Some(top)) => {
                let slot = match n.parse::<usize>() {
                    Ok(k @ 1..=4) if n.len() == 1 => k - 1,
                    _ => return Err(Refusal::Value("N", "must be 1 to 4 (M41 to M44)")),
                };
                let l = parse_amount("TOP", top, 99_999_999, "must be 0 to 99999.999 rpm")?;
                if let Some(g) = self.gears.get_mut(slot) {
                    *g = (l > Length::ZERO).then_some(l);
                }
            }
            (None, None) => {}
            _ => {
                return Err(Refusal::Missing(
                    "GEAR sets a range with N and TOP together",
                ))
            }
        }
        let mut line = ReplyLine::new();
        let _ = match self.aux.gear {
            Some(g) => write!(line, "OK RANGE={g}"),
            None => line.write_str("OK RANGE=-"),
        };
        for (i, g) in self.gears.iter().enumerate() {
            let _ = write!(line, " G{}={}", i + 1, g.unwrap_or(Length::ZERO));
        }
        io.send(line.finish());
        Ok(())
    }

    /// The outputs for `aux` with the tool at the programmed X (`units`
    /// those of a surface speed).
    pub(super) fn outputs_for(&self, aux: &Aux, units: Units) -> Outputs {
        let rpm = aux
            .spindle
            .within(self.top_speed(aux))
            .running_rpm(self.prog[0], units);
        let rpm = if self.spindle_override == 100 {
            rpm
        } else {
            let scaled = Length::from_angstrom(div_round_half_away(
                rpm.as_angstrom() * i64::from(self.spindle_override),
                100,
            ))
            .unwrap_or(rpm);
            // Never above the spindle's top speed.
            self.top.map_or(scaled, |top| scaled.min(top))
        };
        Outputs {
            spindle: aux.spindle.turning,
            rpm: milli_rpm(rpm),
            top: self.top.map_or(0, milli_rpm),
            coolant: aux.coolant,
        }
    }

    /// Switches the spindle and coolant outputs, the axes at rest.
    pub(super) fn switch_outputs<I: Io>(&mut self, outputs: Outputs, io: &mut I) {
        self.outputs = outputs;
        self.machine.switch_spindle(outputs.rpm);
        io.outputs(&outputs);
        self.share_view(io);
    }
}

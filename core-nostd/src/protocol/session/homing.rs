//! The homing cycle (`docs/inputs.md` §8): `HOMING` sets it, `HOME` runs
//! it. Per axis, in the configured order: seek the switch, pull off,
//! locate it slowly, pull off, and the machine position there becomes the
//! axis' home. Its failures lock the machine with grbl's alarm numbers.

use super::*;
use crate::homing::{home_switch, HomingConfig, MAX_LENGTH, MAX_PULLOFF, MAX_RATE};
use crate::inputs::{write_names, Halt, Input};
use crate::plan::Feed;

/// How one homing move ended.
enum Ended {
    /// Its switch became active and the transport stopped it there.
    Tripped,
    /// It ran to its end.
    Ran,
}

/// Why the cycle stopped short.
enum Failed {
    /// An alarm of its own (grbl's number).
    Alarm(u8),
    /// Another switch stopped everything (the session has locked).
    Input,
}

/// A rate word in mm/min, kept in 10⁻³ mm/min.
pub(super) fn parse_homing_rate(key: &'static str, v: &str) -> Result<u32, Refusal<'static>> {
    let why = "must be 0.001 to 20000 mm/min, at most 3 decimals";
    let l = parse_rate(key, v, Refusal::Value(key, why))?;
    let a = l.as_angstrom();
    if a % 10_000 != 0 {
        return Err(Refusal::Value(key, why));
    }
    u32::try_from(a / 10_000)
        .ok()
        .filter(|r| (1..=MAX_RATE).contains(r))
        .ok_or(Refusal::Value(key, why))
}

/// A direction word: `+` or `-`, the side of the switch.
fn parse_dir(key: &'static str, v: &str) -> Result<i8, Refusal<'static>> {
    match v {
        "+" => Ok(1),
        "-" => Ok(-1),
        _ => Err(Refusal::Value(
            key,
            "must be + or - (the side of the axis' switch)",
        )),
    }
}

/// Which axes: `X`, `Z`, `XZ` (or `ZX`), `-` for none.
fn parse_axes(v: &str) -> Result<[bool; 2], Refusal<'static>> {
    match v {
        "-" => Ok([false, false]),
        "X" | "x" => Ok([true, false]),
        "Z" | "z" => Ok([false, true]),
        "XZ" | "ZX" | "xz" | "zx" => Ok([true, true]),
        _ => Err(Refusal::Value("AXES", "must be X, Z, XZ or -")),
    }
}

fn write_axes(line: &mut ReplyLine, axes: [bool; 2]) {
    let _ = line.write_str(match axes {
        [true, true] => "XZ",
        [true, false] => "X",
        [false, true] => "Z",
        [false, false] => "-",
    });
}

impl Session {
    /// The homing cycle's settings.
    pub const fn homing(&self) -> &HomingConfig {
        &self.offsets.homing
    }

    /// At power-on, with the settings loaded: locked until homed when the
    /// machine requires it.
    pub(super) fn power_on_homing(&mut self) {
        let h = self.offsets.homing;
        if h.required && h.order().next().is_some() {
            self.halt = Halt::HomingRequired;
            self.lost = true;
        }
    }

    /// `HOMING [AXES=] [DIRX=] [DIRZ=] [HOMEX=] [HOMEZ=] [TRAVELX=]
    /// [TRAVELZ=] [SEEK=] [LOCATE=] [PULLOFF=] [ORDER=XZ|ZX]
    /// [REQUIRED=0|1]`.
    pub(super) fn homing_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [axes, dir_x, dir_z, home_x, home_z, travel_x, travel_z, seek, locate, pulloff, order, required, soft, jog_clip] =
            args.values();
        let mut h = self.offsets.homing;
        if let Some(v) = axes {
            let [x, z] = parse_axes(v)?;
            h.axes[0].homes = x;
            h.axes[1].homes = z;
        }
        if let Some(v) = dir_x {
            h.axes[0].dir = parse_dir("DIRX", v)?;
        }
        if let Some(v) = dir_z {
            h.axes[1].dir = parse_dir("DIRZ", v)?;
        }
        let within = |key: &'static str, l: Length, why: &'static str| {
            if l.as_angstrom().unsigned_abs() <= MAX_LENGTH.as_angstrom() as u64 {
                Ok(l)
            } else {
                Err(Refusal::Value(key, why))
            }
        };
        if let Some(v) = home_x {
            let l = self.x_word(parse_length("HOMEX", v)?)?;
            h.axes[0].home = within("HOMEX", l, "must be within 10000 mm")?;
        }
        if let Some(v) = home_z {
            h.axes[1].home = within(
                "HOMEZ",
                parse_length("HOMEZ", v)?,
                "must be within 10000 mm",
            )?;
        }
        for (axis, key, v) in [(0, "TRAVELX", travel_x), (1, "TRAVELZ", travel_z)] {
            if let Some(v) = v {
                let why = "must be 0 to 10000 mm";
                let l = within(key, parse_length(key, v)?, why)?;
                if l < Length::ZERO {
                    return Err(Refusal::Value(key, why));
                }
                h.axes[axis & 1].travel = l;
            }
        }
        if let Some(v) = seek {
            h.seek = parse_homing_rate("SEEK", v)?;
        }
        if let Some(v) = locate {
            h.locate = parse_homing_rate("LOCATE", v)?;
        }
        if let Some(v) = pulloff {
            let l = parse_length("PULLOFF", v)?;
            if l <= Length::ZERO || l > MAX_PULLOFF {
                return Err(Refusal::Value("PULLOFF", "must be above 0, at most 100 mm"));
            }
            h.pulloff = l;
        }
        if let Some(v) = order {
            h.z_first = match v {
                "XZ" | "xz" => false,
                "ZX" | "zx" => true,
                _ => return Err(Refusal::Value("ORDER", "must be XZ or ZX")),
            };
        }
        if let Some(v) = required {
            h.required = parse_flag("REQUIRED", v)?;
        }
        if let Some(v) = soft {
            h.soft = parse_flag("SOFT", v)?;
        }
        if let Some(v) = jog_clip {
            h.jog_clip = parse_flag("JOGCLIP", v)?;
        }
        let mut offsets = self.offsets;
        offsets.homing = h;
        self.take_offsets(offsets);
        let mut line = ReplyLine::new();
        let _ = line.write_str("OK AXES=");
        write_axes(&mut line, [h.axes[0].homes, h.axes[1].homes]);
        let sign = |d: i8| if d < 0 { '-' } else { '+' };
        let _ = write!(
            line,
            " DIRX={} DIRZ={}",
            sign(h.axes[0].dir),
            sign(h.axes[1].dir)
        );
        let factor = if self.cfg.diam { 2 } else { 1 };
        let exact = |line: &mut ReplyLine, key: &str, angstrom: i64| {
            let _ = write!(line, " {key}=");
            let _ = crate::length::write_exact_mm(line, angstrom);
        };
        exact(&mut line, "HOMEX", h.axes[0].home.as_angstrom() * factor);
        exact(&mut line, "HOMEZ", h.axes[1].home.as_angstrom());
        exact(&mut line, "TRAVELX", h.axes[0].travel.as_angstrom());
        exact(&mut line, "TRAVELZ", h.axes[1].travel.as_angstrom());
        exact(&mut line, "SEEK", i64::from(h.seek) * 10_000);
        exact(&mut line, "LOCATE", i64::from(h.locate) * 10_000);
        exact(&mut line, "PULLOFF", h.pulloff.as_angstrom());
        let _ = write!(
            line,
            " ORDER={} REQUIRED={} SOFT={} JOGCLIP={}",
            if h.z_first { "ZX" } else { "XZ" },
            u8::from(h.required),
            u8::from(h.soft),
            u8::from(h.jog_clip)
        );
        io.send(line.finish());
        Ok(())
    }

    /// `HOME [AXES=X|Z|XZ]`: the homing cycle, of every axis that homes
    /// (or those named), in the configured order. Answers `OK MX= MZ=`
    /// (the machine position, X as `DIAM` reads it) once every axis is
    /// home.
    pub(super) fn home_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [axes] = args.values();
        if let Halt::Estop(_) | Halt::Fault = self.halt {
            return Err(Refusal::Halted(self.halt));
        }
        self.not_compensating("HOME")?;
        let h = self.offsets.homing;
        let named = match axes {
            None => [true, true],
            Some("-") => return Err(Refusal::Value("AXES", "must be X, Z or XZ")),
            Some(v) => parse_axes(v).map_err(|_| Refusal::Value("AXES", "must be X, Z or XZ"))?,
        };
        let mut any = false;
        for axis in 0..2 {
            if !named[axis & 1] {
                continue;
            }
            if !h.axes[axis & 1].homes {
                if axes.is_some() {
                    return Err(Refusal::Value(
                        "AXES",
                        "names an axis that does not home (HOMING AXES= sets which do)",
                    ));
                }
                continue;
            }
            any = true;
            if h.axes[axis & 1].travel <= Length::ZERO {
                return Err(Refusal::Value(
                    if axis == 0 { "TRAVELX" } else { "TRAVELZ" },
                    "is 0: HOMING sets the axis' travel, which the seek must not exceed",
                ));
            }
            if home_switch(axis, h.axes[axis & 1].dir, &self.offsets.wiring).is_none() {
                return Err(Refusal::Value(
                    "AXES",
                    "names an axis with no limit switch wired to home on (INPUT USED=)",
                ));
            }
        }
        if !any {
            return Err(Refusal::Missing(
                "no axis homes: HOMING AXES= sets which do, DIRX= DIRZ= the side of their switches",
            ));
        }
        if self.outputs != crate::outputs::Outputs::OFF {
            return Err(Refusal::Missing(
                "HOME with the spindle or coolant on: switch them off first (M05 M09)",
            ));
        }
        let Some(now) = io.inputs_now() else {
            return Err(Refusal::Missing("HOME needs a machine with switches"));
        };
        self.levels = now & self.offsets.wiring.used;
        // What is queued runs first; the cycle starts at rest.
        self.machine.flush(&mut Sink::new(io, self.drive));
        let before = self.halt;
        self.halt = Halt::None;
        for axis in h.order() {
            if !named[axis & 1] {
                continue;
            }
            match self.home_axis(axis, &h, io) {
                Ok(()) => {}
                Err(Failed::Input) => return Err(Refusal::Halted(self.halt)),
                Err(Failed::Alarm(code)) => {
                    self.lost = true;
                    let switch = home_switch(axis, h.axes[axis & 1].dir, &self.offsets.wiring);
                    let axis = if axis == 0 { "X" } else { "Z" };
                    self.lock(
                        Halt::Homing(code),
                        switch.map_or(0, Input::bit),
                        Some(axis),
                        io,
                    );
                    return Err(Refusal::Halted(self.halt));
                }
            }
        }
        // Homed: what an input stopped, or the power-on lock, is cleared;
        // the registers are where the carriage is again once every axis
        // that homes has.
        if h.order().all(|a| named[a & 1]) {
            self.lost = false;
        } else if before == Halt::HomingRequired {
            // Part of the machine homed: the rest still must be.
            self.halt = before;
        }
        let factor = if self.cfg.diam { 2 } else { 1 };
        let mut line = ReplyLine::new();
        let _ = line.write_str("OK MX=");
        let _ = crate::length::write_exact_mm(&mut line, self.cmd[0].as_angstrom() * factor);
        let _ = line.write_str(" MZ=");
        let _ = crate::length::write_exact_mm(&mut line, self.cmd[1].as_angstrom());
        io.send(line.finish());
        Ok(())
    }

    /// One axis: seek, pull off, locate, pull off, set.
    fn home_axis<I: Io>(
        &mut self,
        axis: usize,
        h: &HomingConfig,
        io: &mut I,
    ) -> Result<(), Failed> {
        let a = h.axes[axis & 1];
        let dir = a.dir;
        let Some(switch) = home_switch(axis, dir, &self.offsets.wiring) else {
            return Err(Failed::Alarm(9));
        };
        let toward = |l: Length| if dir > 0 { l } else { l.neg() };
        let away = |l: Length| if dir > 0 { l.neg() } else { l };
        // Already on the switch: off it first.
        if self.levels & switch.bit() != 0 {
            self.homing_move(axis, away(h.pulloff), h.locate, switch, io)?;
            if self.levels & switch.bit() != 0 {
                return Err(Failed::Alarm(8));
            }
        }
        // The seek: up to one and a half times the travel.
        let seek = a
            .travel
            .checked_add(a.travel.exact_half().unwrap_or(a.travel))
            .unwrap_or(a.travel);
        if let Ended::Ran = self.homing_move(axis, toward(seek), h.seek, switch, io)? {
            return Err(Failed::Alarm(9));
        }
        self.homing_move(axis, away(h.pulloff), h.locate, switch, io)?;
        if self.levels & switch.bit() != 0 {
            return Err(Failed::Alarm(8));
        }
        // Locate: slowly back onto it, within twice the pull-off.
        let again = h.pulloff.checked_double().unwrap_or(h.pulloff);
        if let Ended::Ran = self.homing_move(axis, toward(again), h.locate, switch, io)? {
            return Err(Failed::Alarm(9));
        }
        self.homing_move(axis, away(h.pulloff), h.locate, switch, io)?;
        if self.levels & switch.bit() != 0 {
            return Err(Failed::Alarm(8));
        }
        // The machine position here is the home.
        let mut cmd = self.cmd;
        cmd[axis & 1] = a.home;
        let price = if axis == 0 { self.cfg.hx } else { self.cfg.hz };
        let n = quantize(a.home, price).map_err(|_| Failed::Alarm(9))?;
        let mut pos = self.pos;
        if axis == 0 {
            pos.x = n;
        } else {
            pos.z = n;
        }
        let mut sink = Sink::new(io, self.drive);
        self.machine.clear_record(&mut sink);
        self.machine.set_position(point_q32(cmd), pos, &mut sink);
        self.cmd = cmd;
        self.pos = pos;
        self.prog = self.work_point(cmd);
        if let Some(homed) = self.homed.get_mut(axis) {
            *homed = true;
        }
        Ok(())
    }

    /// A G-code block was refused for leaving the travel: the program
    /// stops there as grbl's alarm 2 stops it (`!ALARM CODE=2`, locked
    /// until `UNLOCK`), so that a sender going on past a refused line moves
    /// nothing more. The motion queued before it runs on (it is within the
    /// travel, and a cut is not broken off); once it has, the spindle and
    /// the coolant stop, as grbl stops them at an alarm.
    pub(super) fn travel_alarm<I: Io>(&mut self, io: &mut I) {
        self.lock(Halt::Travel, 0, None, io);
        self.machine.flush(&mut Sink::new(io, self.drive));
        self.aux = self.aux.stopped();
        self.switch_outputs(self.outputs_for(&self.aux, self.modal.units), io);
    }

    /// Locks the machine with `halt`, nothing dropped (what was to move
    /// was refused before it moved): `!ALARM CODE= INPUT= [AXIS=] PX= PZ=`,
    /// the inputs `bits` and the axis concerned.
    pub(super) fn lock<I: Io>(&mut self, halt: Halt, bits: u16, axis: Option<&str>, io: &mut I) {
        self.halt = halt;
        io.alarm(halt.alarm());
        let mut line = ReplyLine::new();
        let _ = write!(line, "!ALARM CODE={} INPUT=", halt.alarm());
        let _ = write_names(&mut line, bits);
        if let Some(axis) = axis {
            let _ = write!(line, " AXIS={axis}");
        }
        let _ = write!(line, " PX={} PZ={}", self.pos.x.get(), self.pos.z.get());
        io.send(line.finish());
    }

    /// Refuses a point `to` (registers) outside the travel of an axis
    /// homed, with soft limits on (grbl's error 15, travel exceeded).
    pub(super) fn soft_check(&self, to: ImpulsePoint) -> Result<(), Refusal<'static>> {
        let h = &self.offsets.homing;
        if !h.soft {
            return Ok(());
        }
        let axes = [
            (
                to.x,
                self.cfg.hx,
                "X would leave its travel (soft limits: HOMING SOFT=, TRAVELX=)",
            ),
            (
                to.z,
                self.cfg.hz,
                "Z would leave its travel (soft limits: HOMING SOFT=, TRAVELZ=)",
            ),
        ];
        for ((a, homed), (n, price, why)) in h.axes.iter().zip(self.homed).zip(axes) {
            if !homed {
                continue;
            }
            let Some((lo, hi)) = a.window() else {
                continue;
            };
            // A register times its price is a machine position.
            let at = i64::from(n.get()) * price.as_angstrom();
            if at < lo.as_angstrom() || at > hi.as_angstrom() {
                return Err(Refusal::Travel(why));
            }
        }
        Ok(())
    }

    /// A jog's end (`MOVE`, grbl's `$J=`), with soft limits and `JOGCLIP=1`:
    /// each axis homed held within its travel, on the impulse grid inside
    /// it, so that what is left of the jog runs up to the limit.
    pub(super) fn jog_clip(&self, target: [Length; 2]) -> [Length; 2] {
        if !self.offsets.homing.jog_clip {
            return target;
        }
        self.clip_to_travel(target)
    }

    /// `target` with each homed axis kept within its travel, when soft
    /// limits are on: the first or last impulse within it.
    pub(super) fn clip_to_travel(&self, target: [Length; 2]) -> [Length; 2] {
        let h = &self.offsets.homing;
        if !h.soft {
            return target;
        }
        let mut t = target;
        let prices = [self.cfg.hx.as_angstrom(), self.cfg.hz.as_angstrom()];
        for (((at, a), homed), price) in t.iter_mut().zip(&h.axes).zip(self.homed).zip(prices) {
            let Some((lo, hi)) = a.window().filter(|_| homed && price > 0) else {
                continue;
            };
            // The first and the last impulse within the travel.
            let first = -(-lo.as_angstrom()).div_euclid(price) * price;
            let last = hi.as_angstrom().div_euclid(price) * price;
            let v = at.as_angstrom();
            let clipped = if v < first {
                first
            } else if v > last {
                last
            } else {
                continue;
            };
            *at = Length::from_angstrom(clipped).unwrap_or(*at);
        }
        t
    }

    /// Moves `axis` by `by` at `rate` (10⁻³ mm/min), stopping where
    /// `switch` becomes active (the transport stops the steps at once, as
    /// for a hard limit). Keeps the levels current.
    fn homing_move<I: Io>(
        &mut self,
        axis: usize,
        by: Length,
        rate: u32,
        switch: Input,
        io: &mut I,
    ) -> Result<Ended, Failed> {
        let mut target = self.cmd;
        target[axis & 1] = self.cmd[axis & 1].checked_add(by).ok_or(Failed::Alarm(9))?;
        let block = self.linear_block(target).map_err(|_| Failed::Alarm(9))?;
        let feed = Length::from_um(i64::from(rate)).and_then(Feed::new);
        self.queue_line(target, block, feed, io);
        let (_, rose) = self
            .watched_move_end(switch.bit(), io)
            .ok_or(Failed::Input)?;
        let tripped = rose & switch.bit() != 0;
        if tripped {
            // The transport stopped the steps on the switch's edge: the
            // registers keep the steps issued.
            let _ = self.drop_motion(io);
            return Ok(Ended::Tripped);
        }
        let issued = io.background().map(|b| b.issued());
        if issued.is_some_and(|p| p != block.to()) {
            // Stopped short with no switch: a reset.
            return Err(Failed::Alarm(6));
        }
        Ok(Ended::Ran)
    }
}

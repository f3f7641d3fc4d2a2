//! The handwheel (`docs/inputs.md` §11): a manual pulse generator's counts
//! move the selected axis by ×1, ×10 or ×100 impulses per count, with the
//! machine at rest (or moving for the wheel alone), within the travel.

use super::homing::parse_homing_rate;
use super::*;
use crate::homing::Wheel;
use crate::inputs::Halt;

impl Session {
    /// `WHEEL [AXIS=X|Z|-] [SCALE=1|10|100] [FEED=]`: which axis the wheel
    /// moves (`-`: none, the wheel does nothing), by how many impulses per
    /// count, at what feed (mm/min). Kept with the table. Answers
    /// `OK AXIS= SCALE= FEED=`.
    pub(super) fn wheel_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [axis, scale, feed] = args.values();
        let mut w = self.offsets.homing.wheel;
        if let Some(v) = axis {
            w.axis = match v {
                "X" | "x" => Some(0),
                "Z" | "z" => Some(1),
                "-" => None,
                _ => return Err(Refusal::Value("AXIS", "must be X, Z or -")),
            };
        }
        if let Some(v) = scale {
            w.scale = match v {
                "1" => 1,
                "10" => 10,
                "100" => 100,
                _ => return Err(Refusal::Value("SCALE", "must be 1, 10 or 100")),
            };
        }
        if let Some(v) = feed {
            w.feed = parse_homing_rate("FEED", v)?;
        }
        let mut offsets = self.offsets;
        offsets.homing.wheel = w;
        self.take_offsets(offsets);
        if w.axis.is_none() {
            self.wheeling = false;
        }
        let mut line = ReplyLine::new();
        let axis = match w.axis {
            Some(0) => "X",
            Some(_) => "Z",
            None => "-",
        };
        let _ = write!(line, "OK AXIS={axis} SCALE={} FEED=", w.scale);
        let _ = crate::length::write_exact_mm(&mut line, i64::from(w.feed) * 10_000);
        io.send(line.finish());
        Ok(())
    }

    /// A pendant's axis and scale selectors: the wheel's axis (0 X, 1 Z)
    /// and scale (1, 10, 100), kept as `WHEEL` keeps them; false, and
    /// nothing changed, for another value.
    pub fn wheel_select(&mut self, axis: u8, scale: u8) -> bool {
        let mut w = self.offsets.homing.wheel;
        w.axis = Some(axis);
        w.scale = scale;
        if !w.valid() {
            return false;
        }
        if w != self.offsets.homing.wheel {
            let mut offsets = self.offsets;
            offsets.homing.wheel = w;
            self.take_offsets(offsets);
        }
        true
    }

    /// The handwheel turned by `counts` (signed, since the last call).
    /// With an axis selected and the machine at rest, or moving only for
    /// the wheel, the axis moves by `counts` × the scale impulses (up to
    /// the travel's end once homed with soft limits), queued behind the
    /// wheel's earlier moves and started at once. Otherwise nothing moves,
    /// and the first counts so refused say why (`!WHEEL IGNORED=`) until
    /// the wheel moves the axis again.
    pub fn wheel<I: Io>(&mut self, counts: i32, io: &mut I) {
        let w: Wheel = self.offsets.homing.wheel;
        let Some(axis) = w.axis else {
            return;
        };
        if counts == 0 {
            return;
        }
        if let Err(why) = self.wheel_may_move(io) {
            self.wheel_ignore(why, counts, io);
            return;
        }
        let axis = usize::from(axis & 1);
        let price = [self.cfg.hx, self.cfg.hz][axis].as_angstrom();
        let by = i64::from(counts) * i64::from(w.scale) * price;
        let mut target = self.cmd;
        let Some(to) = Length::from_angstrom(self.cmd[axis].as_angstrom().saturating_add(by))
        else {
            self.wheel_ignore("RANGE", counts, io);
            return;
        };
        target[axis] = to;
        let target = self.clip_to_travel(target);
        if target == self.cmd {
            self.wheel_ignore("TRAVEL", counts, io);
            return;
        }
        let Ok(block) = self.linear_block(target) else {
            self.wheel_ignore("RANGE", counts, io);
            return;
        };
        self.wheel_ignored = false;
        let feed = Length::from_um(i64::from(w.feed)).and_then(Feed::new);
        self.queue_line(target, block, feed, io);
        self.release(io);
        self.wheeling = true;
    }

    /// Counts the wheel may not act on: the first of an episode says why
    /// (`!WHEEL IGNORED=<why> COUNTS=<n>`); the episode ends when the
    /// wheel moves the axis again.
    fn wheel_ignore<I: Io>(&mut self, why: &str, counts: i32, io: &mut I) {
        if !self.wheel_ignored {
            self.wheel_ignored = true;
            let mut line = ReplyLine::new();
            let _ = write!(line, "!WHEEL IGNORED={why} COUNTS={counts}");
            io.send(line.finish());
        }
    }

    /// Why the wheel may not move the axis now, in a word.
    fn wheel_may_move<I: Io>(&self, io: &mut I) -> Result<(), &'static str> {
        if self.halt != Halt::None {
            return Err("ALARM");
        }
        if self.checking.is_some() {
            return Err("CHECK");
        }
        if self.contour.active() {
            return Err("COMPENSATION");
        }
        let st = self.machine.status(&mut Sink::new(io, self.drive));
        match st.motion {
            Axes::Idle if st.queued == 0 || self.wheeling => Ok(()),
            Axes::Run if self.wheeling => Ok(()),
            Axes::Braking | Axes::Held => Err("HOLD"),
            _ => Err("RUN"),
        }
    }
}

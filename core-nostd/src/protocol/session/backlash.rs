//! Backlash compensation (`docs/motion.md` §7): each axis' play, kept
//! with the table, and given to the machine in impulses.

use super::*;
use crate::homing::MAX_BACKLASH;
use crate::impulse::ImpulsePrice;

impl Session {
    /// `BACKLASH [X=] [Z=]`: the play of each axis' leadscrew, mm (X on
    /// the radius: the cross-slide's own), 0 to 5; taken up at each
    /// reversal from the next block on. Kept with the table. Answers
    /// `OK X= Z=` and, per axis, the impulses it takes up
    /// (`NX= NZ=`).
    pub(super) fn backlash_command<'a, I: Io>(
        &mut self,
        args: &Args<'a>,
        io: &mut I,
    ) -> Outcome<'a> {
        let [x, z] = args.values();
        let mut h = self.offsets.homing;
        for (key, v, axis) in [("X", x, 0), ("Z", z, 1)] {
            let Some(v) = v else {
                continue;
            };
            let l = parse_length(key, v)?;
            if l < Length::ZERO || l > MAX_BACKLASH {
                return Err(Refusal::Value(key, "must be 0 to 5 mm"));
            }
            if let Some(a) = h.axes.get_mut(axis) {
                a.backlash = l;
            }
        }
        // What is queued runs with the play it was planned with.
        self.machine.flush(&mut Sink::new(io, self.drive));
        let mut offsets = self.offsets;
        offsets.homing = h;
        self.take_offsets(offsets);
        self.apply_backlash();
        let n = self.backlash_impulses();
        let mut line = ReplyLine::new();
        let _ = line.write_str("OK X=");
        let _ = crate::length::write_exact_mm(&mut line, h.axes[0].backlash.as_angstrom());
        let _ = line.write_str(" Z=");
        let _ = crate::length::write_exact_mm(&mut line, h.axes[1].backlash.as_angstrom());
        let _ = write!(line, " NX={} NZ={}", n[0], n[1]);
        io.send(line.finish());
        Ok(())
    }

    /// Each axis' backlash in its impulses, rounded half away from zero.
    pub(super) fn backlash_impulses(&self) -> [u32; 2] {
        let h = self.offsets.homing;
        let n = |a: usize, price: ImpulsePrice| {
            h.axes
                .get(a)
                .and_then(|axis| quantize(axis.backlash, price).ok())
                .map_or(0, |i| i.get().unsigned_abs())
        };
        [n(0, self.cfg.hx), n(1, self.cfg.hz)]
    }

    /// Gives the machine the backlash of the settings and prices in force
    /// (after `BACKLASH`, a price change, the table restored at power-on).
    pub(super) fn apply_backlash(&mut self) {
        let n = self.backlash_impulses();
        self.machine.set_backlash(n);
    }
}

//! Probing (`docs/inputs.md` §10): `G38.2`–`G38.5`, a straight feed move
//! toward the block's end that the transport stops where the probe
//! changes, as it stops a hard limit. Where it stopped is the result
//! (`!PROBE`, grbl's `PRB:`); its failures lock with grbl's alarm numbers.

use super::*;
use crate::gcode::ProbeMode;
use crate::inputs::{Halt, Input, ProbeResult};

impl Session {
    /// Where nothing reads a probe and the program's path is what is
    /// wanted (a host's run of a program): `on`, a probing block runs as a
    /// feed move to its end, as in grbl's check mode, and probes nothing.
    pub fn set_probe_as_feed(&mut self, on: bool) {
        self.probe_as_feed = on;
    }

    /// Where the last probing move ended, since power-on.
    pub const fn last_probe(&self) -> Option<ProbeResult> {
        self.probe
    }

    /// Before a probing block commits: the probe wired, on a machine that
    /// reads it, the axes at rest, and the probe in the state the move
    /// starts from (else grbl's alarm 4, and nothing moves).
    pub(super) fn probe_ready<I: Io>(
        &mut self,
        mode: ProbeMode,
        io: &mut I,
    ) -> Result<(), Refusal<'static>> {
        // What is queued runs first: the probe is read at rest.
        self.machine.flush(&mut Sink::new(io, self.drive));
        let Some(now) = io.inputs_now() else {
            return Err(Refusal::Missing(
                "G38.2 to G38.5 need a machine with switches (the probe)",
            ));
        };
        if self.offsets.wiring.used & Input::Probe.bit() == 0 {
            return Err(Refusal::Missing(
                "G38.2 to G38.5 need the probe wired: INPUT USED= with PROBE",
            ));
        }
        let now = now & self.offsets.wiring.used;
        let touching = now & Input::Probe.bit() != 0;
        if touching == mode.toward {
            self.lock(Halt::Probe(4), now & Input::Probe.bit(), None, io);
            return Err(Refusal::Halted(self.halt));
        }
        Ok(())
    }

    /// After a probing block's move is queued (the transport armed): waits
    /// for it, then makes where it stopped the commanded point and the
    /// result. A `G38.2`/`G38.4` that ran to its end with no change locks
    /// (alarm 5).
    pub(super) fn probe_end<I: Io>(
        &mut self,
        mode: ProbeMode,
        io: &mut I,
    ) -> Result<(), Refusal<'static>> {
        let end = self.pos;
        let ended = self.watched_move_end(0, io);
        io.probe_arm(None);
        let Some((now, _)) = ended else {
            return Err(Refusal::Halted(self.halt));
        };
        let changed = (now & Input::Probe.bit() != 0) == mode.toward;
        // The transport stopped the steps on the probe's edge: the
        // registers keep the steps issued, and the point is theirs.
        let (_, issued) = self.drop_motion(io);
        self.prog = self.work_point(self.cmd);
        if !changed && issued != end {
            // Stopped short with no change: a reset, which says so itself.
            return Ok(());
        }
        let at = self.cmd;
        self.probe = Some(ProbeResult { at, changed });
        io.probed(at, self.cfg.diam, changed);
        let factor = if self.cfg.diam { 2 } else { 1 };
        let mut line = ReplyLine::new();
        let _ = line.write_str("!PROBE MX=");
        let _ = crate::length::write_exact_mm(&mut line, at[0].as_angstrom() * factor);
        let _ = line.write_str(" MZ=");
        let _ = crate::length::write_exact_mm(&mut line, at[1].as_angstrom());
        let _ = write!(
            line,
            " PX={} PZ={} OK={}",
            self.pos.x.get(),
            self.pos.z.get(),
            u8::from(changed)
        );
        io.send(line.finish());
        if !changed && mode.must_change {
            self.lock(Halt::Probe(5), 0, None, io);
            return Err(Refusal::Halted(self.halt));
        }
        Ok(())
    }
}

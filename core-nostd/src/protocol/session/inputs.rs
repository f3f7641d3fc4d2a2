//! The machine's switches acted on (`docs/inputs.md`): the E-stop, a hard
//! limit and a drive's fault stop everything at once and lock the machine
//! until it is cleared; the door and the buttons hold and resume. `INPUT`
//! wires them; `UNLOCK` clears what they stopped.

use super::*;
use crate::inputs::{
    write_names, EstopStage, Halt, Input, InputConfig, FAULTS, LIMITS, MAX_FILTER,
};

/// Reads a list of input names (`ESTOP,X-,DOOR`, or `-` for none).
fn parse_names(key: &'static str, v: &str) -> Result<u16, Refusal<'static>> {
    if v == "-" || v.eq_ignore_ascii_case("NONE") {
        return Ok(0);
    }
    let (mut bits, mut rest) = (0, Some(v));
    while let Some(text) = rest {
        // `split_once`, not `str::split`: no slicing panic in the image.
        let (name, tail) = match crate::text::split_once(text, b',') {
            Some((name, tail)) => (name, Some(tail)),
            None => (text, None),
        };
        rest = tail;
        let input = Input::from_name(name).ok_or(Refusal::Value(
            key,
            "must list ESTOP, X-, X+, Z-, Z+, DOOR, HOLD, START, PROBE, FAULTX, FAULTZ (comma-separated) or -",
        ))?;
        bits |= input.bit();
    }
    Ok(bits)
}

impl Session {
    /// The inputs wired, for the board's filter.
    pub const fn wiring(&self) -> InputConfig {
        self.offsets.wiring
    }

    /// What an input stopped (grbl's alarm number), if anything.
    pub const fn alarm(&self) -> Option<u8> {
        match self.halt.alarm() {
            0 => None,
            code => Some(code),
        }
    }

    /// The board's inputs changed: `active` holds those active now,
    /// filtered. The E-stop, a limit or a drive's fault becoming active
    /// stops everything at once (the board has already stopped its
    /// outputs): the queued and started motion is dropped, the spindle and
    /// coolant are switched off, the program is abandoned as by a reset,
    /// and the machine is locked (`!ALARM CODE= INPUT= DONE= OF= PX= PZ=`).
    /// The door and the hold button hold the feed and cycle start resumes,
    /// as their bytes do: the transport acts on them at once (the door's
    /// level is kept here: nothing resumes while it is open).
    pub fn inputs<I: Io>(&mut self, active: u16, io: &mut I) {
        let active = active & self.offsets.wiring.used;
        let rose = active & !self.levels;
        let fell = self.levels & !active;
        self.levels = active;
        let estop = Input::Estop.bit();
        if rose & estop != 0 {
            self.halt_now(Halt::Estop(EstopStage::Pressed), estop, io);
        } else if fell & estop != 0 && self.halt == Halt::Estop(EstopStage::Pressed) {
            self.halt = Halt::Estop(EstopStage::Released);
        }
        if self.halt == Halt::None {
            if rose & LIMITS != 0 {
                self.halt_now(Halt::Limit, rose & LIMITS, io);
            } else if rose & FAULTS != 0 {
                self.halt_now(Halt::Fault, rose & FAULTS, io);
            }
        }
        // The door and the buttons are the transport's to act on at once,
        // as it acts on the hold and cycle-start bytes (a device without
        // motion in the background has nothing to hold).
        self.share_view(io);
    }

    /// Everything stopped at once by `halt`, which the inputs `bits` gave.
    fn halt_now<I: Io>(&mut self, halt: Halt, bits: u16, io: &mut I) {
        let (found, issued) = self.restart(io);
        self.halt = halt;
        // Stopped without braking, or with the drives unpowered: the
        // carriage may not be where the registers say.
        self.lost = true;
        io.alarm(halt.alarm());
        let mut line = ReplyLine::new();
        let _ = write!(line, "!ALARM CODE={} INPUT=", halt.alarm());
        let _ = write_names(&mut line, bits);
        super::realtime::write_dropped(&mut line, &found, issued);
        io.send(line.finish());
    }

    /// After a move the transport stops on a switch's edge (a homing
    /// move, a probing move): waits for it to end and reads the switches.
    /// A stopping switch other than `own` that became active meanwhile
    /// stops and locks as it would anywhere (`None`). Otherwise the levels
    /// become those read, and what is returned is the switches active now
    /// and those that became active.
    pub(super) fn watched_move_end<I: Io>(&mut self, own: u16, io: &mut I) -> Option<(u16, u16)> {
        self.machine.flush(&mut Sink::new(io, self.drive));
        let now = io.inputs_now().unwrap_or(0) & self.offsets.wiring.used;
        let rose = now & !self.levels;
        if rose & (Input::Estop.bit() | LIMITS | FAULTS) & !own != 0 {
            self.inputs(now, io);
            return None;
        }
        self.levels = now;
        Some((now, rose))
    }

    /// A reset moves an E-stop released on to `UNLOCK`.
    pub(super) fn reset_halt(&mut self) {
        if self.halt == Halt::Estop(EstopStage::Released) {
            self.halt = Halt::Estop(EstopStage::Reset);
        }
    }

    /// Refuses what would move or switch while an input holds the machine
    /// locked.
    pub(super) fn unlocked<'a>(&self) -> Outcome<'a> {
        match self.halt {
            Halt::None => Ok(()),
            halt => Err(Refusal::Halted(halt)),
        }
    }

    /// `UNLOCK`: clears what an input stopped, once its way back allows
    /// (`OK LOST=1` while the position may be lost: home or check it).
    pub(super) fn unlock_command<'a, I: Io>(&mut self, io: &mut I) -> Outcome<'a> {
        match self.halt {
            Halt::Estop(EstopStage::Pressed | EstopStage::Released) => {
                return Err(Refusal::Halted(self.halt))
            }
            Halt::Fault if self.levels & FAULTS != 0 => return Err(Refusal::Halted(self.halt)),
            _ => {}
        }
        self.halt = Halt::None;
        send_ok(io, Some(format_args!("LOST={}", u8::from(self.lost))));
        Ok(())
    }

    /// `INPUT [USED=] [INVERT=] [FILTER=]`: which inputs are wired, which
    /// of them read active low, and the filter in ms.
    pub(super) fn input_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [used, invert, filter] = args.values();
        let mut wiring = self.offsets.wiring;
        if let Some(v) = used {
            wiring.used = parse_names("USED", v)?;
        }
        if let Some(v) = invert {
            wiring.invert = parse_names("INVERT", v)?;
        }
        if let Some(v) = filter {
            wiring.filter = v
                .parse::<u8>()
                .ok()
                .filter(|&f| f <= MAX_FILTER)
                .ok_or(Refusal::Value("FILTER", "must be 0 to 100 (ms)"))?;
        }
        // Kept across power cycles with the table.
        let mut offsets = self.offsets;
        offsets.wiring = wiring;
        self.take_offsets(offsets);
        // An input no longer wired is no longer active.
        self.levels &= wiring.used;
        let mut line = ReplyLine::new();
        let _ = line.write_str("OK USED=");
        let _ = write_names(&mut line, wiring.used);
        let _ = line.write_str(" INVERT=");
        let _ = write_names(&mut line, wiring.invert);
        let _ = write!(line, " FILTER={}", wiring.filter);
        io.send(line.finish());
        Ok(())
    }
}

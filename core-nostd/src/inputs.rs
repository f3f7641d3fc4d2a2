//! The machine's switches (`docs/inputs.md`): which inputs there are, their
//! active level, the filter that turns sampled pin levels into the states
//! the controller acts on, and what a stopping input leaves to clear.
//!
//! Every input is one bit of a `u16`: the board reads its pins into the
//! bits of [`Input`], the [`Filter`] takes one sample per millisecond and
//! keeps a bit's state until the pin has read the other level for
//! `filter` samples in a row, so a glitch shorter than the filter does
//! nothing and a longer one acts.

/// One input: its bit in a `u16` of levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Input {
    /// The emergency stop (normally closed: it reads inactive while the
    /// loop is whole).
    Estop = 0,
    /// X's limit switch towards minus (or the one for both ends).
    LimitXMinus = 1,
    /// X's limit switch towards plus.
    LimitXPlus = 2,
    /// Z's limit switch towards minus (or the one for both ends).
    LimitZMinus = 3,
    /// Z's limit switch towards plus.
    LimitZPlus = 4,
    /// The guard door: open is a feed hold.
    Door = 5,
    /// The feed-hold button.
    Hold = 6,
    /// The cycle-start button.
    Start = 7,
    /// The probe or tool setter.
    Probe = 8,
    /// X's drive reports a fault.
    FaultX = 9,
    /// Z's drive reports a fault.
    FaultZ = 10,
}

/// How many inputs there are.
pub const INPUTS: usize = 11;

/// Every input, in the order of their bits.
pub const ALL: [Input; INPUTS] = [
    Input::Estop,
    Input::LimitXMinus,
    Input::LimitXPlus,
    Input::LimitZMinus,
    Input::LimitZPlus,
    Input::Door,
    Input::Hold,
    Input::Start,
    Input::Probe,
    Input::FaultX,
    Input::FaultZ,
];

/// The bits of every limit switch.
pub const LIMITS: u16 = Input::LimitXMinus.bit()
    | Input::LimitXPlus.bit()
    | Input::LimitZMinus.bit()
    | Input::LimitZPlus.bit();

/// The bits of both drives' faults.
pub const FAULTS: u16 = Input::FaultX.bit() | Input::FaultZ.bit();

/// The longest filter, in samples (ms).
pub const MAX_FILTER: u8 = 100;

impl Input {
    /// Its bit.
    pub const fn bit(self) -> u16 {
        1 << self as u8
    }

    /// The name the pendant protocol gives it (`INPUT USED=` lists them).
    pub const fn name(self) -> &'static str {
        match self {
            Input::Estop => "ESTOP",
            Input::LimitXMinus => "X-",
            Input::LimitXPlus => "X+",
            Input::LimitZMinus => "Z-",
            Input::LimitZPlus => "Z+",
            Input::Door => "DOOR",
            Input::Hold => "HOLD",
            Input::Start => "START",
            Input::Probe => "PROBE",
            Input::FaultX => "FAULTX",
            Input::FaultZ => "FAULTZ",
        }
    }

    /// The input a name names, without regard to case.
    pub fn from_name(name: &str) -> Option<Input> {
        ALL.iter()
            .copied()
            .find(|i| i.name().eq_ignore_ascii_case(name))
    }
}

/// Where a probing move (`G38.2`–`G38.5`) ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProbeResult {
    /// The machine position (X on the radius): the registers times their
    /// prices.
    pub at: [crate::length::Length; 2],
    /// The probe changed there (grbl's `:1`); otherwise the move ran to
    /// its end.
    pub changed: bool,
}

/// The inputs wired and how they read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputConfig {
    /// The inputs wired; the others read inactive whatever their pin.
    pub used: u16,
    /// The inputs active when their pin reads low (a switch to ground with
    /// the pull-up on, a normally-closed E-stop loop read as its break).
    pub invert: u16,
    /// Samples (ms) a level must hold before it counts, 0 … [`MAX_FILTER`]
    /// (0: the next sample).
    pub filter: u8,
}

impl InputConfig {
    /// Nothing wired: a machine without inputs behaves as before them.
    pub const NONE: InputConfig = InputConfig {
        used: 0,
        invert: 0,
        filter: 0,
    };

    /// The active inputs of a sample of pin levels (bit set: pin high).
    pub const fn active(&self, pins: u16) -> u16 {
        (pins ^ self.invert) & self.used
    }
}

impl Default for InputConfig {
    fn default() -> Self {
        Self::NONE
    }
}

/// The filtered state of every input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Filter {
    state: u16,
    /// Per input, the samples in a row that read other than its state.
    against: [u8; INPUTS],
}

impl Filter {
    /// Every input inactive.
    pub const fn new() -> Filter {
        Filter {
            state: 0,
            against: [0; INPUTS],
        }
    }

    /// The active inputs, filtered.
    pub const fn state(&self) -> u16 {
        self.state
    }

    /// Takes one sample of pin levels; returns the inputs whose filtered
    /// state changed with it.
    pub fn sample(&mut self, cfg: &InputConfig, pins: u16) -> u16 {
        let active = cfg.active(pins);
        let mut changed = 0;
        for (i, against) in self.against.iter_mut().enumerate() {
            let bit = 1u16 << i;
            if (active ^ self.state) & bit == 0 {
                *against = 0;
                continue;
            }
            *against = against.saturating_add(1);
            if *against > cfg.filter {
                *against = 0;
                changed |= bit;
            }
        }
        self.state ^= changed;
        changed
    }
}

/// Where an E-stop stands on its way back: released, then a reset, then
/// `UNLOCK`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstopStage {
    /// Pressed (the loop broken).
    Pressed,
    /// Released, no reset since.
    Released,
    /// Released and reset: `UNLOCK` goes on.
    Reset,
}

/// What an input stopped, until it is cleared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Halt {
    /// Nothing: requests run.
    None,
    /// The E-stop (grbl's alarm 10).
    Estop(EstopStage),
    /// A hard limit (alarm 1).
    Limit,
    /// A drive's fault (grblHAL's alarm 17).
    Fault,
    /// The homing cycle failed, grbl's alarm number: 6 a reset during it,
    /// 7 the door opened, 8 the pull-off left the switch pressed, 9 the
    /// switch not found within the travel.
    Homing(u8),
    /// Power-on with homing required, not yet homed (alarm 11).
    HomingRequired,
    /// A G-code block would have left the travel of an axis homed (soft
    /// limits, alarm 2): refused before it moved, the program stopped.
    Travel,
    /// A probing move failed, grbl's alarm number: 4 the probe was not in
    /// the state the move starts from, 5 it did not change within the
    /// move.
    Probe(u8),
}

impl Halt {
    /// grbl's alarm number (0: none).
    pub const fn alarm(self) -> u8 {
        match self {
            Halt::None => 0,
            Halt::Estop(_) => 10,
            Halt::Limit => 1,
            Halt::Fault => 17,
            Halt::Homing(code) => code,
            Halt::HomingRequired => 11,
            Halt::Travel => 2,
            Halt::Probe(code) => code,
        }
    }

    /// What the operator does next, for a refusal.
    pub const fn next_step(self) -> &'static str {
        match self {
            Halt::None => "nothing to clear",
            Halt::Estop(EstopStage::Pressed) => {
                "the E-stop is pressed: release it, reset, then UNLOCK"
            }
            Halt::Estop(EstopStage::Released) => "the E-stop was pressed: reset, then UNLOCK",
            Halt::Estop(EstopStage::Reset) => "the E-stop was pressed: UNLOCK to go on",
            Halt::Limit => "a hard limit stopped the axes: UNLOCK, then move off the switch",
            Halt::Fault => "a drive reported a fault: UNLOCK once it has cleared",
            Halt::Homing(6) => "a reset stopped the homing cycle: HOME again",
            Halt::Homing(7) => "the door opened during homing: close it, HOME again",
            Halt::Homing(8) => {
                "the pull-off left the switch pressed: check the switch and PULLOFF, HOME again"
            }
            Halt::Homing(_) => {
                "homing did not find the switch within the travel: check its wiring, HOME again"
            }
            Halt::HomingRequired => "the machine must be homed: HOME (UNLOCK moves it unhomed)",
            Halt::Travel => {
                "a block would have left the travel (soft limits): UNLOCK, then correct the program or its offsets"
            }
            Halt::Probe(4) => {
                "the probe was not in the state the probing move starts from: check it, UNLOCK"
            }
            Halt::Probe(_) => {
                "the probe did not change within the probing move: UNLOCK, then probe again nearer"
            }
        }
    }
}

/// Writes the names of the inputs of `bits`, comma-separated (`-` for
/// none).
pub fn write_names<W: core::fmt::Write>(out: &mut W, bits: u16) -> core::fmt::Result {
    if bits == 0 {
        return out.write_str("-");
    }
    let mut first = true;
    for i in ALL {
        if bits & i.bit() != 0 {
            if !first {
                out.write_str(",")?;
            }
            out.write_str(i.name())?;
            first = false;
        }
    }
    Ok(())
}

/// Writes the letters grblHAL's `Pn:` gives the active inputs, in its
/// order: `X`, `Z` a limit of the axis, then `H` the hold button, `S`
/// cycle start, `D` the door, `E` the E-stop, `F` a drive's fault
/// (grblHAL's motor fault; its `M` is a motor's warning, which these
/// drives do not give), `P` the probe.
pub fn write_letters<W: core::fmt::Write>(out: &mut W, active: u16) -> core::fmt::Result {
    const LETTERS: [(u16, char); 8] = [
        (Input::LimitXMinus.bit() | Input::LimitXPlus.bit(), 'X'),
        (Input::LimitZMinus.bit() | Input::LimitZPlus.bit(), 'Z'),
        (Input::Hold.bit(), 'H'),
        (Input::Start.bit(), 'S'),
        (Input::Door.bit(), 'D'),
        (Input::Estop.bit(), 'E'),
        (FAULTS, 'F'),
        (Input::Probe.bit(), 'P'),
    ];
    for (bits, letter) in LETTERS {
        if active & bits != 0 {
            out.write_char(letter)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const CFG: InputConfig = InputConfig {
        used: Input::Estop.bit() | Input::LimitXMinus.bit() | Input::Door.bit(),
        invert: Input::Estop.bit(),
        filter: 3,
    };

    #[test]
    fn a_glitch_shorter_than_the_filter_does_nothing() {
        let mut f = Filter::new();
        // The E-stop loop is whole (pin high, inverted: inactive); the
        // limit's pin low.
        let quiet = Input::Estop.bit();
        for _ in 0..10 {
            assert_eq!(f.sample(&CFG, quiet), 0);
        }
        // Three samples of a limit glitch: not longer than the filter.
        for _ in 0..3 {
            assert_eq!(f.sample(&CFG, quiet | Input::LimitXMinus.bit()), 0);
        }
        assert_eq!(f.sample(&CFG, quiet), 0);
        assert_eq!(f.state(), 0);
        // A glitch then quiet restarts the count.
        for _ in 0..3 {
            assert_eq!(f.sample(&CFG, quiet | Input::LimitXMinus.bit()), 0);
        }
        assert_eq!(
            f.sample(&CFG, quiet | Input::LimitXMinus.bit()),
            Input::LimitXMinus.bit(),
            "the fourth sample in a row acts"
        );
        assert_eq!(f.state(), Input::LimitXMinus.bit());
    }

    #[test]
    fn a_broken_estop_loop_is_active_and_unwired_inputs_never_are() {
        let mut f = Filter::new();
        let cfg = InputConfig { filter: 0, ..CFG };
        // Pin low: the loop is broken.
        assert_eq!(f.sample(&cfg, 0), Input::Estop.bit());
        // Every pin high: the E-stop releases, the door acts, the
        // unwired ones (hold, Z's limits, the faults) stay inactive.
        assert_eq!(
            f.sample(&cfg, u16::MAX),
            Input::Estop.bit() | Input::LimitXMinus.bit() | Input::Door.bit()
        );
        assert_eq!(f.state(), Input::LimitXMinus.bit() | Input::Door.bit());
    }

    #[test]
    fn letters_as_grbl_writes_them() {
        let mut s = heapless::String::<16>::new();
        write_letters(
            &mut s,
            Input::Estop.bit()
                | Input::LimitZPlus.bit()
                | Input::Door.bit()
                | Input::FaultX.bit()
                | Input::Probe.bit()
                | Input::Hold.bit(),
        )
        .unwrap();
        assert_eq!(s.as_str(), "ZHDEFP");
        for i in ALL {
            assert_eq!(Input::from_name(i.name()), Some(i));
        }
    }
}

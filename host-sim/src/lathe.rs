//! The simulated lathe behind `serve --machine FILE`: each axis' travel,
//! the switches its carriage trips from its own position, and the play of
//! its leadscrew (`examples/machine.toml` documents every field).
//!
//! The carriage follows the leadscrew's nut, which moves by the steps
//! issued times the impulse price (X on the radius: the cross-slide's
//! own travel); it starts where the registers put it, and setting the
//! registers (`ZERO`, homing) moves nothing. With backlash `b` the carriage lags the nut by up to `b`
//! after a reversal: it stays where it is until the nut has taken up the
//! play (`c ∈ [n − b, n]`). A switch at `at` towards minus is active while
//! the carriage is at or below `at` and releases above `at + hysteresis`;
//! one towards plus the other way round. A probe (a tool setter) is a
//! switch too, on the side its file gives; an input with switches on both
//! axes is active while any of them is.

use core_nostd::inputs::Input;
use serde::Deserialize;

/// The step clock, ticks per second.
const TICK_HZ: f64 = 1e6;

/// A nanometre, mm: how near a carriage at a switch's place counts as on it.
const EPS: f64 = 1e-6;

/// One switch on an axis.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Switch {
    /// The input it is wired to: `X-`, `X+`, `Z-`, `Z+` (`INPUT` names),
    /// or `PROBE` (a tool setter, a touch probe).
    pub input: String,
    /// The way it trips, `-` (at or below `at`) or `+` (at or above): a
    /// limit's is its name's; a probe's must be given.
    #[serde(default)]
    pub side: Option<String>,
    /// Where it trips, mm (machine coordinates, X on the radius).
    pub at: f64,
    /// How far back the carriage must go before it releases, mm.
    #[serde(default)]
    pub hysteresis: f64,
}

/// An axis' drive: what one impulse turns the leadscrew by, and how fast
/// it can follow the impulses.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Drive {
    /// The leadscrew's pitch, mm per turn (with `steps_per_rev`: the nut
    /// moves `pitch / steps_per_rev` per impulse; without them, by the
    /// controller's impulse price).
    #[serde(default)]
    pub pitch: Option<f64>,
    /// Impulses per turn of the leadscrew (the motor's steps times its
    /// microstepping times any gearing).
    #[serde(default)]
    pub steps_per_rev: Option<f64>,
    /// The most impulses per second the drive follows: two impulses closer
    /// together stall the motor; the second is lost and the drive raises
    /// its fault output (`FAULT X`/`FAULT Z` on the board, when wired)
    /// until the panel clears it (`FAULT X 0`).
    #[serde(default)]
    pub max_rate: Option<f64>,
}

impl Drive {
    /// How far the nut moves per impulse, mm, when the file says.
    pub fn step_mm(&self) -> Option<f64> {
        Some(self.pitch? / self.steps_per_rev?)
    }
}

/// One axis of the lathe.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    /// Where the carriage can go, mm, `[min, max]` (informative: the
    /// switches stop it, the ends are reported by `STATE?`).
    pub travel: Option<[f64; 2]>,
    /// The leadscrew's play, mm.
    #[serde(default)]
    pub backlash: f64,
    /// Its switches.
    #[serde(default, rename = "switch")]
    pub switches: Vec<Switch>,
    /// Its drive.
    #[serde(default)]
    pub drive: Drive,
}

/// The spindle's encoder.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EncoderFile {
    /// Counts per revolution (quadrature edges), an index once per turn.
    pub cpr: u32,
}

/// The spindle.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpindleFile {
    /// The motor's top speed, rev/min: a higher `S` turns it at this.
    #[serde(default)]
    pub max_rpm: Option<f64>,
    /// The speed's ripple once per turn, a fraction of it (0.02: ±2 %;
    /// 0 to 0.5), as a belt or an unbalanced chuck gives.
    #[serde(default)]
    pub ripple: f64,
    /// Its encoder, when one is fitted.
    #[serde(default)]
    pub encoder: Option<EncoderFile>,
}

/// The whole file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MachineFile {
    /// The cross-slide (on the radius).
    #[serde(default)]
    pub x: Axis,
    /// The carriage.
    #[serde(default)]
    pub z: Axis,
    /// The spindle.
    #[serde(default)]
    pub spindle: Option<SpindleFile>,
}

impl MachineFile {
    /// Reads a machine file; the error names the file's problem (TOML's
    /// own message, with its line, or the field that is wrong).
    pub fn parse(text: &str) -> Result<MachineFile, String> {
        let m: MachineFile = toml::from_str(text).map_err(|e| e.to_string())?;
        if let Some(sp) = &m.spindle {
            if let Some(top) = sp.max_rpm {
                if !(top.is_finite() && top > 0.0) {
                    return Err(format!("spindle.max_rpm: above 0, not {top}"));
                }
            }
            if !(sp.ripple.is_finite() && (0.0..=0.5).contains(&sp.ripple)) {
                return Err(format!("spindle.ripple: 0 to 0.5, not {}", sp.ripple));
            }
            if let Some(e) = &sp.encoder {
                if !(4..=1 << 20).contains(&e.cpr) {
                    return Err(format!(
                        "spindle.encoder.cpr: 4 to 1048576 counts a turn, not {}",
                        e.cpr
                    ));
                }
            }
        }
        for (name, axis, sides) in [("x", &m.x, ["X-", "X+"]), ("z", &m.z, ["Z-", "Z+"])] {
            if !(axis.backlash.is_finite() && (0.0..=5.0).contains(&axis.backlash)) {
                return Err(format!("{name}.backlash: 0 to 5 mm, not {}", axis.backlash));
            }
            let d = &axis.drive;
            if d.pitch.is_some() != d.steps_per_rev.is_some() {
                return Err(format!(
                    "{name}.drive: `pitch` and `steps_per_rev` go together"
                ));
            }
            for (field, v) in [
                ("pitch", d.pitch),
                ("steps_per_rev", d.steps_per_rev),
                ("max_rate", d.max_rate),
            ] {
                if let Some(v) = v {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(format!("{name}.drive.{field}: above 0, not {v}"));
                    }
                }
            }
            if let Some([lo, hi]) = axis.travel {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return Err(format!("{name}.travel: [min, max] with min < max"));
                }
            }
            for s in &axis.switches {
                let probe = s.input.eq_ignore_ascii_case("PROBE");
                if !probe && !sides.iter().any(|side| s.input.eq_ignore_ascii_case(side)) {
                    return Err(format!(
                        "{name}.switch input {:?}: {}, {} or PROBE",
                        s.input, sides[0], sides[1]
                    ));
                }
                match (s.side.as_deref(), probe) {
                    (Some("-" | "+"), true) | (None, false) => {}
                    (Some(side), false) if s.input.ends_with(side) => {}
                    (None, true) => {
                        return Err(format!(
                            "{name}.switch PROBE: `side` \"-\" or \"+\", the way it trips"
                        ))
                    }
                    (Some(side), _) => {
                        return Err(format!(
                            "{name}.switch {}: side {side:?} is not the way it trips",
                            s.input
                        ))
                    }
                }
                if !(s.at.is_finite() && s.hysteresis.is_finite() && s.hysteresis >= 0.0) {
                    return Err(format!(
                        "{name}.switch {}: `at` a position, `hysteresis` 0 or more",
                        s.input
                    ));
                }
            }
        }
        Ok(m)
    }
}

/// The lathe in motion: each carriage and the switches it holds active.
#[derive(Clone, Debug)]
pub struct Lathe {
    file: MachineFile,
    /// Where each carriage is, mm (X on the radius).
    carriage: [f64; 2],
    /// Where each nut is, mm.
    nut: [f64; 2],
    /// The carriages have been placed (at the first registers).
    started: bool,
    /// The switches active now.
    active: u16,
    /// The drives' faults raised (latched until cleared).
    fault: u16,
    /// Each axis' last impulse, ticks of its run.
    last: [Option<u64>; 2],
    /// The least and most each carriage has been at, mm.
    range: [[f64; 2]; 2],
    /// The spindle since its speed last changed: when (s), the turns
    /// before, and its motion since.
    turning: (f64, f64, crate::spindle::Spindle),
}

/// What the panel reads off the spindle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpindleNow {
    /// Its speed, rev/min: measured from the encoder's counts over the
    /// last 0.1 s when one is fitted, else the motor's own.
    pub rpm: f64,
    /// The encoder's counts since power-on, when one is fitted.
    pub counts: Option<i64>,
}

/// A spindle with no limits and no encoder (a file that gives none).
static NO_SPINDLE: SpindleFile = SpindleFile {
    max_rpm: None,
    ripple: 0.0,
    encoder: None,
};

/// The file's spindle, or one with no limits and no encoder.
fn file_spindle(file: &MachineFile) -> &SpindleFile {
    file.spindle.as_ref().unwrap_or(&NO_SPINDLE)
}

impl Lathe {
    /// The lathe of `file`, its nuts and carriages where the registers
    /// put them first.
    pub fn new(file: MachineFile) -> Lathe {
        let turning = (0.0, 0.0, Self::turning_at(file_spindle(&file), 0.0));
        Lathe {
            file,
            carriage: [0.0; 2],
            nut: [0.0; 2],
            started: false,
            active: 0,
            fault: 0,
            last: [None; 2],
            range: [[f64::INFINITY, f64::NEG_INFINITY]; 2],
            turning,
        }
    }

    /// The spindle's motion at `rpm` as the file's spindle turns it.
    fn turning_at(sp: &SpindleFile, rpm: f64) -> crate::spindle::Spindle {
        crate::spindle::Spindle {
            rpm: sp.max_rpm.map_or(rpm, |top| rpm.min(top)),
            ripple: sp.ripple,
            dips: Vec::new(),
            cpr: sp.encoder.as_ref().map_or(4096, |e| e.cpr),
        }
    }

    /// The spindle commanded to `rpm` (0: stopped) at `now` (s, the
    /// board's clock): it turns on from where it was.
    pub fn set_spindle(&mut self, rpm: f64, now: f64) {
        let next = Self::turning_at(file_spindle(&self.file), rpm);
        let (start, before, model) = &self.turning;
        if model.rpm == next.rpm {
            return;
        }
        let turns = before + model.turns((now - start).max(0.0));
        self.turning = (now, turns, next);
    }

    /// The spindle at `now` (s, the board's clock).
    pub fn spindle_at(&self, now: f64) -> SpindleNow {
        let (start, before, model) = &self.turning;
        let t = (now - start).max(0.0);
        let encoder = self.file.spindle.as_ref().and_then(|s| s.encoder.as_ref());
        match encoder {
            Some(e) => {
                let turns = before + model.turns(t);
                SpindleNow {
                    rpm: if t > 0.0 && model.rpm > 0.0 {
                        model.measured_rpm(t, 0.1)
                    } else {
                        0.0
                    },
                    counts: Some((turns * f64::from(e.cpr)).floor() as i64),
                }
            }
            None => SpindleNow {
                rpm: model.rpm,
                counts: None,
            },
        }
    }

    /// A step event issued at `tick` of its run: `steps` impulses per axis
    /// (−1, 0 or 1), `price` the controller's impulse prices (mm), which
    /// the nut moves by unless the axis' drive gives its own pitch. An
    /// impulse closer to the axis' last than its drive's `max_rate` allows
    /// is lost and raises the drive's fault. Returns the inputs active now.
    pub fn event(&mut self, steps: [i32; 2], tick: u64, price: [f64; 2]) -> u16 {
        let mut by = [0.0; 2];
        for (i, axis) in [&self.file.x, &self.file.z].into_iter().enumerate() {
            if steps[i] == 0 {
                continue;
            }
            let stalled = match (axis.drive.max_rate, self.last[i]) {
                // A tick before the last: a new run (after a reset, say)
                // whose start was not seen.
                (Some(rate), Some(last)) => tick >= last && ((tick - last) as f64) < TICK_HZ / rate,
                _ => false,
            };
            self.last[i] = Some(tick);
            if stalled {
                self.fault |= [Input::FaultX, Input::FaultZ][i].bit();
                continue;
            }
            by[i] = f64::from(steps[i]) * axis.drive.step_mm().unwrap_or(price[i]);
        }
        self.moved_by(by)
    }

    /// A run of motion begins: its ticks count from 0.
    pub fn run_start(&mut self) {
        self.last = [None; 2];
    }

    /// The panel cleared the drives' faults of `bits`.
    pub fn clear_fault(&mut self, bits: u16) {
        self.fault &= !bits;
        self.active &= !bits;
    }

    /// The least and most each carriage has been at, mm (X on the
    /// radius), `[[x_min, x_max], [z_min, z_max]]`.
    pub fn range(&self) -> [[f64; 2]; 2] {
        self.range
    }

    /// The file it follows.
    pub fn file(&self) -> &MachineFile {
        &self.file
    }

    /// The nuts moved to `nut` (mm, X on the radius): the carriages follow
    /// within their play; returns the switches active now.
    pub fn moved(&mut self, nut: [f64; 2]) -> u16 {
        self.nut = nut;
        let mut hit = 0;
        for (i, axis) in [&self.file.x, &self.file.z].into_iter().enumerate() {
            let c = &mut self.carriage[i];
            *c = if self.started {
                c.clamp(nut[i] - axis.backlash, nut[i])
            } else {
                nut[i]
            };
            let r = &mut self.range[i];
            *r = [r[0].min(*c), r[1].max(*c)];
            for s in &axis.switches {
                let Some(input) = core_nostd::inputs::Input::from_name(&s.input) else {
                    continue;
                };
                let bit = input.bit();
                let minus = match s.side.as_deref() {
                    Some(side) => side == "-",
                    None => matches!(input, Input::LimitXMinus | Input::LimitZMinus),
                };
                let was = self.active & bit != 0;
                // Within a nanometre: the nuts add up steps in floating
                // point, and a switch at a step's place trips on it.
                let now = if minus {
                    *c <= s.at + EPS || (was && *c <= s.at + s.hysteresis)
                } else {
                    *c >= s.at - EPS || (was && *c >= s.at - s.hysteresis)
                };
                if now {
                    hit |= bit;
                }
            }
        }
        self.active = hit | self.fault;
        self.started = true;
        self.active
    }

    /// The nuts moved by `by` (mm) from where they were.
    pub fn moved_by(&mut self, by: [f64; 2]) -> u16 {
        self.moved([self.nut[0] + by[0], self.nut[1] + by[1]])
    }

    /// Where the carriages are, mm (X on the radius).
    pub fn carriage(&self) -> [f64; 2] {
        self.carriage
    }

    /// The switches its carriages hold active.
    pub fn active(&self) -> u16 {
        self.active
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = r#"
[z]
travel = [-300.0, 5.0]
backlash = 0.1
[[z.switch]]
input = "Z+"
at = 2.0
hysteresis = 0.5
"#;

    #[test]
    fn a_switch_trips_at_its_place_and_releases_past_its_hysteresis() {
        let mut l = Lathe::new(MachineFile::parse(FILE).unwrap());
        let zp = Input::LimitZPlus.bit();
        assert_eq!(l.moved([0.0, 0.0]), 0);
        // Moving towards plus first, the carriage lags the nut by the play.
        assert_eq!(l.moved([0.0, 1.99]), 0);
        assert_eq!(l.moved([0.0, 2.05]), 0, "the carriage at 1.95");
        assert_eq!(l.moved([0.0, 2.2]), zp, "the carriage at 2.1");
        // Back by less than the hysteresis: still active; the carriage
        // follows the nut at once this way.
        assert_eq!(l.moved([0.0, 1.8]), zp);
        assert_eq!(l.carriage()[1], 1.8);
        // Reversing again, the carriage waits for the nut to take up the
        // play.
        assert_eq!(l.moved([0.0, 1.85]), zp);
        assert_eq!(l.carriage()[1], 1.8);
        assert_eq!(l.moved([0.0, 1.0]), 0, "released below 1.5");
    }

    /// The drive's pitch over its steps moves the nut, whatever the
    /// controller's price; impulses closer than its rate stall it: the
    /// impulse is lost and its fault stays raised until cleared.
    #[test]
    fn a_drive_moves_by_its_own_pitch_and_stalls_above_its_rate() {
        let file = "[x]\n[x.drive]\npitch = 4.0\nsteps_per_rev = 800\nmax_rate = 1000.0\n";
        let mut l = Lathe::new(MachineFile::parse(file).unwrap());
        let fx = Input::FaultX.bit();
        l.moved([0.0, 0.0]);
        // 0.01 mm the controller's price; the drive's 4/800 = 0.005 mm.
        for k in 0..10 {
            assert_eq!(l.event([1, 0], 1000 * k, [0.01, 0.01]), 0);
        }
        assert!((l.carriage()[0] - 0.05).abs() < 1e-12, "{:?}", l.carriage());
        // Z has no drive of its own: the controller's price.
        l.event([0, -1], 20_000, [0.01, 0.01]);
        assert!((l.carriage()[1] + 0.01).abs() < 1e-12);
        // 999 µs after the last: faster than 1000 impulses/s.
        assert_eq!(l.event([1, 0], 9999, [0.01, 0.01]), fx);
        assert!(
            (l.carriage()[0] - 0.05).abs() < 1e-12,
            "the impulse was lost"
        );
        // Latched while the motor turns on at its pace.
        assert_eq!(l.event([1, 0], 12_000, [0.01, 0.01]), fx);
        assert!((l.carriage()[0] - 0.055).abs() < 1e-12);
        l.clear_fault(fx);
        assert_eq!(l.event([1, 0], 14_000, [0.01, 0.01]), 0);
        // A new run counts its ticks from 0: no stall across runs.
        l.run_start();
        assert_eq!(l.event([1, 0], 0, [0.01, 0.01]), 0);
        let [lo, hi] = l.range()[0];
        assert!(lo == 0.0 && (hi - 0.065).abs() < 1e-12, "{lo} {hi}");
    }

    /// The spindle turns at the commanded speed up to its top; its encoder
    /// counts the turns on from where they were at each change.
    #[test]
    fn the_spindle_turns_up_to_its_top_and_its_encoder_counts() {
        let file = "[spindle]\nmax_rpm = 2000.0\n[spindle.encoder]\ncpr = 1000\n";
        let mut l = Lathe::new(MachineFile::parse(file).unwrap());
        assert_eq!(l.spindle_at(5.0).counts, Some(0), "stopped at power-on");
        l.set_spindle(600.0, 1.0);
        // 600 rpm = 10 rev/s: 1.5 s later, 15 turns.
        let now = l.spindle_at(2.5);
        assert_eq!(now.counts, Some(15_000));
        assert!((now.rpm - 600.0).abs() < 1.0, "{now:?}");
        // 3000 asked, 2000 the top: 33.33 rev/s from 15 turns on.
        l.set_spindle(3000.0, 2.5);
        let now = l.spindle_at(3.1);
        assert_eq!(now.counts, Some(15_000 + 20_000));
        assert!((now.rpm - 2000.0).abs() < 1.0, "{now:?}");
        l.set_spindle(0.0, 3.1);
        let now = l.spindle_at(9.0);
        assert_eq!((now.counts, now.rpm), (Some(35_000), 0.0));
        // Without an encoder the panel shows the motor's speed.
        let mut l = Lathe::new(MachineFile::parse("[spindle]\nmax_rpm = 1500.0\n").unwrap());
        l.set_spindle(1800.0, 0.0);
        assert_eq!(
            l.spindle_at(1.0),
            SpindleNow {
                rpm: 1500.0,
                counts: None
            }
        );
    }

    #[test]
    fn a_bad_file_is_refused_by_name() {
        for (text, why) in [
            ("[z]\nbacklash = -1\n", "z.backlash"),
            (
                "[x]\n[[x.switch]]\ninput = \"Z+\"\nat = 1\n",
                "x.switch input \"Z+\"",
            ),
            ("[z]\ntravel = [5.0, -5.0]\n", "z.travel"),
            (
                "[z]\n[[z.switch]]\ninput = \"PROBE\"\nat = 1\n",
                "z.switch PROBE: `side`",
            ),
            (
                "[z]\n[[z.switch]]\ninput = \"Z-\"\nside = \"+\"\nat = 1\n",
                "side \"+\" is not the way it trips",
            ),
            ("[y]\n", "unknown field `y`"),
            ("[z]\nbacklash = \"a lot\"\n", "invalid type"),
            (
                "[x.drive]\npitch = 5.0\n",
                "x.drive: `pitch` and `steps_per_rev`",
            ),
            ("[z.drive]\nmax_rate = 0\n", "z.drive.max_rate: above 0"),
            ("[z.drive]\nvolts = 48\n", "unknown field `volts`"),
            ("[spindle]\nripple = 0.9\n", "spindle.ripple: 0 to 0.5"),
            (
                "[spindle.encoder]\ncpr = 1\n",
                "spindle.encoder.cpr: 4 to 1048576",
            ),
            ("[spindle]\nmax_rpm = -5.0\n", "spindle.max_rpm: above 0"),
        ] {
            let e = MachineFile::parse(text).unwrap_err();
            assert!(e.contains(why), "{text:?}: {e}");
        }
    }
}

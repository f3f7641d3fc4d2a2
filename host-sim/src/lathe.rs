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
}

impl MachineFile {
    /// Reads a machine file; the error names the file's problem (TOML's
    /// own message, with its line, or the field that is wrong).
    pub fn parse(text: &str) -> Result<MachineFile, String> {
        let m: MachineFile = toml::from_str(text).map_err(|e| e.to_string())?;
        for (name, axis, sides) in [("x", &m.x, ["X-", "X+"]), ("z", &m.z, ["Z-", "Z+"])] {
            if !(axis.backlash.is_finite() && (0.0..=5.0).contains(&axis.backlash)) {
                return Err(format!("{name}.backlash: 0 to 5 mm, not {}", axis.backlash));
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
}

impl Lathe {
    /// The lathe of `file`, its nuts and carriages where the registers
    /// put them first.
    pub fn new(file: MachineFile) -> Lathe {
        Lathe {
            file,
            carriage: [0.0; 2],
            nut: [0.0; 2],
            started: false,
            active: 0,
        }
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
        self.active = hit;
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
        ] {
            let e = MachineFile::parse(text).unwrap_err();
            assert!(e.contains(why), "{text:?}: {e}");
        }
    }
}

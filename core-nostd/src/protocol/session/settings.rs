//! The session's configuration values (`CFG`) and their words.

use super::wire::*;
use crate::comp::TipCode;
use crate::impulse::ImpulsePrice;
use crate::length::Length;

/// The largest nose radius `CFG RN` accepts: 25 mm.
pub(super) const MAX_NOSE_RADIUS_UM: i64 = 25_000;
/// The chord tolerance range of `CFG TOL`: 0.000001 mm to 1 mm.
pub(super) const MAX_TOL_UM: i64 = 1_000;

/// Pass kind for arcs by chords: finishing rounds the chord angle down,
/// roughing up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pass {
    /// `FIN`: no chord deviates more than the tolerance.
    Finish,
    /// `ROUGH`: fewer, longer chords.
    Rough,
}

impl Pass {
    /// The protocol word.
    pub const fn as_str(self) -> &'static str {
        match self {
            Pass::Finish => "FIN",
            Pass::Rough => "ROUGH",
        }
    }
}

/// The session's configuration (`CFG`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// X impulse price, on the radius.
    pub hx: ImpulsePrice,
    /// Z impulse price.
    pub hz: ImpulsePrice,
    /// X words are diameters.
    pub diam: bool,
    /// Nose radius.
    pub rn: Length,
    /// Tool tip orientation.
    pub tip: TipCode,
    /// Chord tolerance for arcs that do not name their own.
    pub tol: Length,
    /// Pass kind for arcs that do not name their own.
    pub pass: Pass,
}

impl Config {
    /// Power-on defaults: 0.005/0.01 mm impulses, diameters, r 0.4 mm, tip 3,
    /// tolerance 0.01 mm, finishing.
    pub const DEFAULT: Config = Config {
        hx: ImpulsePrice::DEFAULT_X,
        hz: ImpulsePrice::DEFAULT_Z,
        diam: true,
        rn: match Length::from_um(400) {
            Some(l) => l,
            None => Length::ZERO,
        },
        tip: TipCode::EXTERNAL_RIGHT,
        tol: match Length::from_um(10) {
            Some(l) => l,
            None => Length::ZERO,
        },
        pass: Pass::Finish,
    };
}

impl Default for Config {
    fn default() -> Self {
        Config::DEFAULT
    }
}

pub(super) fn parse_tol(v: &str) -> Result<Length, Refusal<'static>> {
    let why = "must be over 0, at most 1 mm";
    let tol = parse_bounded("TOL", v, 0, MAX_TOL_UM, why)?;
    if tol == Length::ZERO {
        return Err(Refusal::Value("TOL", why));
    }
    Ok(tol)
}

pub(super) fn parse_pass(v: &str) -> Result<Pass, Refusal<'static>> {
    if v.eq_ignore_ascii_case("FIN") {
        Ok(Pass::Finish)
    } else if v.eq_ignore_ascii_case("ROUGH") {
        Ok(Pass::Rough)
    } else {
        Err(Refusal::Value("PASS", "must be FIN or ROUGH"))
    }
}

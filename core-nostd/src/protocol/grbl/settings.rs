//! grbl's `$` settings: where each lives on this controller, `$$`, `$n=`.

use super::front::*;
use super::report::*;
use super::translate::*;
use crate::inputs::{write_names, Input};
use crate::length::{write_exact_mm, Length};

/// A length as grbl prints its settings, with three decimals (more only
/// where the value has them).
fn write_mm3(l: &mut ReplyLine, angstrom: i64) {
    if angstrom % 10_000 == 0 {
        let um = angstrom / 10_000;
        let sign = if um < 0 { "-" } else { "" };
        let um = um.unsigned_abs();
        let _ = write!(l, "{sign}{}.{:03}", um / 1000, um % 1000);
    } else {
        let _ = write_exact_mm(l, angstrom);
    }
}
use crate::protocol::io::Io;
use crate::protocol::reply::ReplyLine;
use crate::protocol::request::{Command, Request};
use crate::protocol::session::Session;
use core::fmt::Write;

/// How `$$` writes a setting the session holds.
pub(super) type Show = fn(&Session, &mut ReplyLine);

/// Where a `$n` setting lives on this controller.
#[derive(Clone, Copy)]
pub(super) enum Place {
    /// A key of a pendant request, and how the session's value of it is
    /// written: `$110` is `LIMITS VX`.
    Request(Command, &'static str, Show),
    /// Steps per mm of an axis: one over the impulse price of `CFG`'s key.
    StepsPerMm(&'static str),
    /// Kept by the front for senders that write and read it back; it
    /// changes nothing on this machine (`Front::kept`, by index): a whole
    /// number up to 65535.
    Kept(usize),
    /// Only the value shown is accepted; another is refused with the
    /// reason (grbl's error 3, or the code given).
    Fixed(&'static [u8], u8, &'static str),
    /// `$10`, the status report's mask: bit 0 machine (1) or work (0)
    /// positions. Bit 1 (`Bf:`) is not reported.
    ReportMask,
    /// A key of a pendant request whose words grbl writes as numbers:
    /// `$n=i` sends the key the `i`-th word (`$450=1` is `OPT
    /// DIALECT=FANUC`). `$$` shows the number of the session's word.
    Choice(
        Command,
        &'static str,
        &'static [&'static str],
        fn(&Session) -> usize,
    ),
    /// A mask of grbl's over the switches' wiring (`INPUT`): each bit
    /// it knows stands for inputs; `used` sets which are wired (`$21`),
    /// else which read active low (`$5`, `$6`, `$14`). A bit it does not
    /// know is refused with the reason. Setting it also wires `wires`
    /// (`$6`: a grbl board always has its probe input, and setting how it
    /// reads is how a sender commissions it).
    Inputs {
        used: bool,
        bits: &'static [(u8, u16)],
        other: &'static str,
        wires: u16,
    },
    /// `$22`, grblHAL's homing mask: bit 0 the cycle on (`HOMING
    /// AXES=XZ`, else `-`), bit 1 single-axis commands (always on here),
    /// bit 2 homing required at power-on (`REQUIRED`).
    HomingCycle,
    /// `$23`, the homing direction mask: a bit set homes its axis
    /// towards minus (`HOMING DIRX= DIRZ=`): bit 0 X, bit 2 Z.
    HomingDirs,
}

/// The limit switches of X and of Z.
const LIMITS_X: u16 = Input::LimitXMinus.bit() | Input::LimitXPlus.bit();
const LIMITS_Z: u16 = Input::LimitZMinus.bit() | Input::LimitZPlus.bit();

/// One grbl setting: its number and where it lives.
#[derive(Clone, Copy)]
pub(super) struct Setting {
    pub(super) n: u16,
    pub(super) place: Place,
}

pub(super) const fn setting(n: u16, place: Place) -> Setting {
    Setting { n, place }
}

/// The settings `$$` lists, in grbl's order, and what `$n=` does to each.
/// Those that would change the machine's behaviour but have nothing on
/// this board to act on (inverted pins, limit and home switches) accept
/// only the value that leaves the machine as it is; the rest of grbl's
/// list is kept and read back.
pub(super) const SETTINGS: [Setting; 37] = [
    setting(
        0,
        Place::Request(Command::Drive, "PULSE", |s, l| {
            let _ = write!(l, "{}", s.drive().pulse_us());
        }),
    ),
    setting(1, Place::Kept(0)),
    setting(
        2,
        Place::Fixed(b"0", 3, "step pulses are not inverted on this board"),
    ),
    setting(
        3,
        Place::Fixed(b"0", 3, "set an axis' direction by wiring its DIR"),
    ),
    setting(
        4,
        Place::Fixed(b"0", 3, "this board has no stepper enable output"),
    ),
    // grblHAL's masks: $5 bit 0 X, bit 2 Z (a lathe has no Y).
    setting(
        5,
        Place::Inputs {
            used: false,
            bits: &[(0, LIMITS_X), (2, LIMITS_Z)],
            other: "bit 0 X, bit 2 Z: a lathe has no Y",
            wires: 0,
        },
    ),
    setting(
        6,
        Place::Inputs {
            used: false,
            bits: &[(0, Input::Probe.bit())],
            other: "0 or 1",
            wires: Input::Probe.bit(),
        },
    ),
    setting(10, Place::ReportMask),
    setting(
        11,
        Place::Request(Command::Limits, "JD", |s, l| {
            let _ = write!(l, "{}", s.machine().limits().junction());
        }),
    ),
    setting(
        12,
        Place::Request(Command::Cfg, "TOL", |s, l| {
            let _ = write!(l, "{}", s.config().tol);
        }),
    ),
    setting(13, Place::Fixed(b"0", 3, "reports are in mm")),
    // grblHAL's control inputs: bit 1 feed hold, 2 cycle start, 3 door,
    // 6 E-stop.
    setting(
        14,
        Place::Inputs {
            used: false,
            bits: &[
                (1, Input::Hold.bit()),
                (2, Input::Start.bit()),
                (3, Input::Door.bit()),
                (6, Input::Estop.bit()),
            ],
            other: "bits 1 hold, 2 cycle start, 3 door, 6 E-stop: this board has no reset, block delete, optional stop or probe-connected input",
            wires: 0,
        },
    ),
    setting(
        20,
        Place::Request(Command::Homing, "SOFT", |s, l| {
            let _ = write!(l, "{}", u8::from(s.homing().soft));
        }),
    ),
    setting(
        21,
        Place::Inputs {
            used: true,
            bits: &[(0, LIMITS_X | LIMITS_Z)],
            other: "0 or 1 (hard limits on all four switches; INPUT USED= wires fewer)",
            wires: 0,
        },
    ),
    setting(22, Place::HomingCycle),
    setting(23, Place::HomingDirs),
    setting(
        24,
        Place::Request(Command::Homing, "LOCATE", |s, l| {
            write_mm3(l, i64::from(s.homing().locate) * 10_000);
        }),
    ),
    setting(
        25,
        Place::Request(Command::Homing, "SEEK", |s, l| {
            write_mm3(l, i64::from(s.homing().seek) * 10_000);
        }),
    ),
    setting(26, Place::Kept(1)),
    setting(
        27,
        Place::Request(Command::Homing, "PULLOFF", |s, l| {
            write_mm3(l, s.homing().pulloff.as_angstrom());
        }),
    ),
    setting(
        30,
        Place::Request(Command::Aux, "SMAX", |s, l| {
            let _ = write!(l, "{}", s.spindle_top().unwrap_or(Length::ZERO));
        }),
    ),
    setting(
        31,
        Place::Fixed(b"0", 3, "the spindle output starts from 0 rpm"),
    ),
    setting(
        32,
        Place::Fixed(b"2", 3, "this is a lathe: grblHAL's lathe mode 2"),
    ),
    // grblHAL's jog soft limits: a jog past the travel runs up to it.
    setting(
        40,
        Place::Request(Command::Homing, "JOGCLIP", |s, l| {
            let _ = write!(l, "{}", u8::from(s.homing().jog_clip));
        }),
    ),
    setting(100, Place::StepsPerMm("HX")),
    setting(102, Place::StepsPerMm("HZ")),
    setting(
        110,
        Place::Request(Command::Limits, "VX", |s, l| {
            let _ = write!(l, "{}", s.machine().limits().rate(0));
        }),
    ),
    setting(
        112,
        Place::Request(Command::Limits, "VZ", |s, l| {
            let _ = write!(l, "{}", s.machine().limits().rate(1));
        }),
    ),
    setting(
        120,
        Place::Request(Command::Limits, "AX", |s, l| {
            let _ = write!(l, "{}", s.machine().limits().accel(0));
        }),
    ),
    setting(
        122,
        Place::Request(Command::Limits, "AZ", |s, l| {
            let _ = write!(l, "{}", s.machine().limits().accel(1));
        }),
    ),
    setting(
        130,
        Place::Request(Command::Homing, "TRAVELX", |s, l| {
            write_mm3(l, s.homing().axes[0].travel.as_angstrom());
        }),
    ),
    setting(
        132,
        Place::Request(Command::Homing, "TRAVELZ", |s, l| {
            write_mm3(l, s.homing().axes[1].travel.as_angstrom());
        }),
    ),
    setting(
        160,
        Place::Request(Command::Backlash, "X", |s, l| {
            write_mm3(l, s.homing().axes[0].backlash.as_angstrom());
        }),
    ),
    setting(
        162,
        Place::Request(Command::Backlash, "Z", |s, l| {
            write_mm3(l, s.homing().axes[1].backlash.as_angstrom());
        }),
    ),
    // This controller's own, in the range grblHAL leaves to no public
    // setting: how G-code lines are read, as `OPT` sets it.
    setting(
        450,
        Place::Choice(Command::Opt, "DIALECT", &["ISO", "FANUC"], |s| {
            usize::from(s.dialect() == crate::gcode::Dialect::Fanuc)
        }),
    ),
    setting(
        451,
        Place::Choice(Command::Opt, "BDEL", &["0", "1"], |s| {
            usize::from(s.block_delete())
        }),
    ),
    setting(
        452,
        Place::Choice(Command::Opt, "OPTSTOP", &["0", "1"], |s| {
            usize::from(s.optional_stop())
        }),
    ),
];

pub(super) fn settings<I: Io + ?Sized>(
    session: &mut Session,
    front: &Front,
    io: &mut Translate<'_, I>,
) {
    let cfg = *session.config();
    for s in SETTINGS {
        let mut l = ReplyLine::new();
        let _ = write!(l, "${}=", s.n);
        match s.place {
            Place::Request(_, _, show) => show(session, &mut l),
            Place::StepsPerMm(key) => {
                let h = if key == "HX" { cfg.hx } else { cfg.hz }.as_angstrom();
                // 10⁷/h steps per mm, to 3 decimals.
                let milli = crate::length::div_round_half_away(10_000_000_000, h.max(1));
                let _ = write!(l, "{}.{:03}", milli / 1000, milli % 1000);
            }
            Place::Kept(i) => {
                let _ = write!(l, "{}", front.kept.get(i).copied().unwrap_or(0));
            }
            Place::Fixed(v, _, _) => l.push_bytes(v),
            Place::ReportMask => {
                let _ = write!(l, "{}", u8::from(front.mpos));
            }
            Place::Choice(_, _, _, which) => {
                let _ = write!(l, "{}", which(session));
            }
            Place::HomingCycle => {
                let h = session.homing();
                let on = h.order().next().is_some();
                let mask = (u8::from(on) * 3) | (u8::from(h.required) << 2);
                let _ = write!(l, "{mask}");
            }
            Place::HomingDirs => {
                let h = session.homing();
                let mask = u8::from(h.axes[0].dir < 0) | u8::from(h.axes[1].dir < 0) << 2;
                let _ = write!(l, "{mask}");
            }
            Place::Inputs { used, bits, .. } => {
                let w = session.wiring();
                let field = if used { w.used } else { w.invert };
                let mask = bits
                    .iter()
                    .filter(|(_, inputs)| field & inputs != 0)
                    .fold(0u32, |m, (bit, _)| m | 1 << bit);
                let _ = write!(l, "{mask}");
            }
        }
        io.inner.send(finish(&mut l));
    }
}

/// Refuses a `$n=` with grbl's `code` and what is wrong.
pub(super) fn refuse_setting<I: Io + ?Sized>(
    io: &mut Translate<'_, I>,
    code: u8,
    n: u16,
    why: &[u8],
) {
    io.outcome = Some(Err(code));
    io.message = ReplyLine::new();
    let _ = write!(io.message, "${n}: ");
    io.message.push_bytes(why);
}

/// A whole number of at most 5 digits, or a decimal with up to 3 places,
/// in thousandths.
pub(super) fn parse_setting(v: &[u8], decimal: bool) -> Option<u32> {
    let (int, frac) = match v.iter().position(|&b| b == b'.') {
        Some(dot) if decimal => (v.get(..dot)?, v.get(dot + 1..)?),
        Some(_) => return None,
        None => (v, &b""[..]),
    };
    if int.is_empty() && frac.is_empty()
        || int.len() > 5
        || frac.len() > 3
        || !int.iter().chain(frac).all(u8::is_ascii_digit)
    {
        return None;
    }
    let digits = |d: &[u8]| d.iter().fold(0u32, |a, &b| a * 10 + u32::from(b - b'0'));
    let whole = digits(int);
    if !decimal {
        return (whole <= 65_535).then_some(whole);
    }
    let mut f = digits(frac);
    for _ in frac.len()..3 {
        f *= 10;
    }
    Some(whole * 1000 + f)
}

/// `$n=value`: the setting, or grbl's error for it.
pub(super) fn set<I: Io + ?Sized>(
    session: &mut Session,
    front: &mut Front,
    n: &[u8],
    v: &[u8],
    io: &mut Translate<'_, I>,
) {
    let number = core::str::from_utf8(n)
        .ok()
        .and_then(|t| t.parse::<u16>().ok());
    let Some(s) = SETTINGS.iter().find(|s| Some(s.n) == number).copied() else {
        io.outcome = Some(Err(3));
        io.message = ReplyLine::new();
        io.message
            .push_bytes(b"no such setting on this controller: $");
        io.message.push_bytes(n);
        return;
    };
    if v.first() == Some(&b'-') {
        return refuse_setting(io, 4, s.n, b"a negative value");
    }
    match s.place {
        Place::Request(command, key, _) => {
            // One word of printable ASCII, as in a request line.
            // A number, as grbl reads a setting's value.
            let word = core::str::from_utf8(v)
                .ok()
                .filter(|w| Length::from_gcode_mm(w).is_ok());
            let Some(word) = word else {
                return refuse_setting(io, 2, s.n, b"a number");
            };
            match Request::command(command, &[(key, word)]) {
                Ok(request) => session.request(&request, io),
                Err(_) => refuse_setting(io, 3, s.n, b"not a key of its request"),
            }
        }
        Place::StepsPerMm(key) => {
            // One over the steps: a price on the 10⁻⁷ mm grid.
            let steps = core::str::from_utf8(v)
                .ok()
                .and_then(|t| Length::from_gcode_mm(t).ok())
                .map(|l| l.as_angstrom())
                .filter(|&l| l > 0);
            let Some(steps) = steps else {
                return refuse_setting(io, 2, s.n, b"steps per mm above 0");
            };
            // h Å = 10⁷ Å / (steps / 10⁷).
            let steps = steps.unsigned_abs();
            let price = 100_000_000_000_000u64.checked_div(steps);
            let exact = 100_000_000_000_000u64.checked_rem(steps) == Some(0);
            let Some(price) = price.filter(|_| exact) else {
                return refuse_setting(
                    io,
                    3,
                    s.n,
                    b"one step must be a whole number of 0.0000001 mm",
                );
            };
            let mut price_mm = ReplyLine::new();
            let _ = crate::length::write_exact_mm(&mut price_mm, price as i64);
            let price_mm = core::str::from_utf8(price_mm.as_bytes()).unwrap_or("");
            match Request::command(Command::Cfg, &[(key, price_mm)]) {
                Ok(request) => session.request(&request, io),
                Err(_) => refuse_setting(io, 3, s.n, b"not a key of CFG"),
            }
        }
        Place::Kept(i) => match (parse_setting(v, false), front.kept.get_mut(i)) {
            (Some(value), Some(slot)) => {
                *slot = value;
                io.outcome = Some(Ok(()));
            }
            _ => refuse_setting(io, 2, s.n, b"a whole number up to 65535"),
        },
        Place::ReportMask => match parse_setting(v, false) {
            Some(m @ (0 | 1)) => {
                front.mpos = m == 1;
                io.outcome = Some(Ok(()));
            }
            _ => refuse_setting(
                io,
                3,
                s.n,
                b"0 (work position) or 1 (machine position); Bf: is not reported",
            ),
        },
        Place::Choice(command, key, words, _) => {
            let word = parse_setting(v, false)
                .and_then(|i| usize::try_from(i).ok())
                .and_then(|i| words.get(i));
            match word.map(|w| Request::command(command, &[(key, w)])) {
                Some(Ok(request)) => session.request(&request, io),
                Some(Err(_)) => refuse_setting(io, 3, s.n, b"not a key of its request"),
                None => {
                    io.outcome = Some(Err(3));
                    io.message = ReplyLine::new();
                    let _ = write!(
                        io.message,
                        "${}: 0 to {}",
                        s.n,
                        words.len().saturating_sub(1)
                    );
                    for (i, w) in words.iter().enumerate() {
                        let _ = write!(
                            io.message,
                            "{} {i} {key}={w}",
                            if i == 0 { ":" } else { "," }
                        );
                    }
                }
            }
        }
        Place::HomingCycle => {
            let Some(mask) = parse_setting(v, false).filter(|m| m & !7 == 0) else {
                return refuse_setting(
                    io,
                    3,
                    s.n,
                    b"bits 0 homing on, 1 single-axis $HX/$HZ, 2 homing required at power-on",
                );
            };
            let axes = if mask & 1 != 0 { "XZ" } else { "-" };
            let required = if mask & 4 != 0 { "1" } else { "0" };
            match Request::command(Command::Homing, &[("AXES", axes), ("REQUIRED", required)]) {
                Ok(request) => session.request(&request, io),
                Err(_) => refuse_setting(io, 3, s.n, b"not a key of HOMING"),
            }
        }
        Place::HomingDirs => {
            let Some(mask) = parse_setting(v, false).filter(|m| m & !5 == 0) else {
                return refuse_setting(io, 3, s.n, b"bit 0 X, bit 2 Z: a lathe has no Y");
            };
            let sign = |bit: u32| if mask & bit != 0 { "-" } else { "+" };
            match Request::command(Command::Homing, &[("DIRX", sign(1)), ("DIRZ", sign(4))]) {
                Ok(request) => session.request(&request, io),
                Err(_) => refuse_setting(io, 3, s.n, b"not a key of HOMING"),
            }
        }
        Place::Inputs {
            used,
            bits,
            other,
            wires,
        } => {
            let known = bits.iter().fold(0u32, |m, (bit, _)| m | 1 << bit);
            let Some(mask) = parse_setting(v, false).filter(|m| m & !known == 0) else {
                return refuse_setting(io, 3, s.n, other.as_bytes());
            };
            let w = session.wiring();
            let all = bits.iter().fold(0u16, |m, (_, inputs)| m | inputs);
            let chosen = bits
                .iter()
                .filter(|(bit, _)| mask & 1 << bit != 0)
                .fold(0u16, |m, (_, inputs)| m | inputs);
            let field = if used { w.used } else { w.invert };
            let mut names = ReplyLine::new();
            let _ = write_names(&mut names, field & !all | chosen);
            let names = core::str::from_utf8(names.as_bytes()).unwrap_or("-");
            let key = if used { "USED" } else { "INVERT" };
            let mut wired = ReplyLine::new();
            let _ = write_names(&mut wired, w.used | wires);
            let wired = core::str::from_utf8(wired.as_bytes()).unwrap_or("-");
            let words = [(key, names), ("USED", wired)];
            let words = if wires != 0 { &words[..] } else { &words[..1] };
            match Request::command(Command::Input, words) {
                Ok(request) => session.request(&request, io),
                Err(_) => refuse_setting(io, 3, s.n, b"not a key of INPUT"),
            }
        }
        Place::Fixed(only, code, why) => {
            let same = parse_setting(v, true).is_some_and(|x| Some(x) == parse_setting(only, true));
            if same {
                io.outcome = Some(Ok(()));
            } else {
                refuse_setting(io, code, s.n, why.as_bytes());
            }
        }
    }
}

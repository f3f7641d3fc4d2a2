//! grbl's `$` settings: where each lives on this controller, `$$`, `$n=`.

use super::front::*;
use super::report::*;
use super::translate::*;
use crate::protocol::io::Io;
use crate::protocol::reply::ReplyLine;
use crate::protocol::session::Session;
use core::fmt::Write;

/// The value of `KEY=` in a pendant reply line.
pub(super) fn value<'a>(line: &'a [u8], key: &[u8]) -> Option<&'a [u8]> {
    let mut words = line.split(|&b| b == b' ' || b == b'*');
    words.find_map(|w| w.strip_prefix(key).and_then(|rest| rest.strip_prefix(b"=")))
}

/// Where a `$n` setting lives on this controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Place {
    /// A key of a pendant request: `$110` is `LIMITS VX`.
    Request(&'static [u8], &'static [u8]),
    /// Steps per mm of an axis: one over the impulse price of `CFG`'s key.
    StepsPerMm(&'static [u8]),
    /// Kept by the front for senders that write and read it back; it
    /// changes nothing on this machine (`Front::kept`, by index). A decimal
    /// when `decimal`, else a whole number up to 65535.
    Kept(usize, bool),
    /// Only the value shown is accepted; another is refused with the
    /// reason (grbl's error 3, or the code given).
    Fixed(&'static [u8], u8, &'static str),
    /// `$10`, the status report's mask: bit 0 machine (1) or work (0)
    /// positions. Bit 1 (`Bf:`) is not reported.
    ReportMask,
}

/// One grbl setting: its number and where it lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
pub(super) const SETTINGS: [Setting; 30] = [
    setting(0, Place::Request(b"DRIVE", b"PULSE")),
    setting(1, Place::Kept(0, false)),
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
    setting(
        5,
        Place::Fixed(b"0", 3, "this board has no limit switch inputs"),
    ),
    setting(6, Place::Fixed(b"0", 3, "this board has no probe input")),
    setting(10, Place::ReportMask),
    setting(11, Place::Request(b"LIMITS", b"JD")),
    setting(12, Place::Request(b"CFG", b"TOL")),
    setting(13, Place::Fixed(b"0", 3, "reports are in mm")),
    setting(
        20,
        Place::Fixed(
            b"0",
            10,
            "soft limits need homing, which this board has not",
        ),
    ),
    setting(
        21,
        Place::Fixed(b"0", 3, "this board has no limit switch inputs"),
    ),
    setting(
        22,
        Place::Fixed(b"0", 3, "this board has no home switch inputs"),
    ),
    setting(23, Place::Kept(2, false)),
    setting(24, Place::Kept(3, true)),
    setting(25, Place::Kept(4, true)),
    setting(26, Place::Kept(5, false)),
    setting(27, Place::Kept(6, true)),
    setting(30, Place::Request(b"AUX", b"SMAX")),
    setting(
        31,
        Place::Fixed(b"0", 3, "the spindle output starts from 0 rpm"),
    ),
    setting(
        32,
        Place::Fixed(b"2", 3, "this is a lathe: grblHAL's lathe mode 2"),
    ),
    setting(100, Place::StepsPerMm(b"HX")),
    setting(102, Place::StepsPerMm(b"HZ")),
    setting(110, Place::Request(b"LIMITS", b"VX")),
    setting(112, Place::Request(b"LIMITS", b"VZ")),
    setting(120, Place::Request(b"LIMITS", b"AX")),
    setting(122, Place::Request(b"LIMITS", b"AZ")),
    setting(130, Place::Kept(7, true)),
    setting(132, Place::Kept(8, true)),
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
            Place::Request(command, key) => {
                let reply = query(session, io, command);
                l.push_bytes(value(reply.as_bytes(), key).unwrap_or(b"0"));
            }
            Place::StepsPerMm(key) => {
                let h = if key == b"HX" { cfg.hx } else { cfg.hz }.as_angstrom();
                // 10⁷/h steps per mm, to 3 decimals.
                let milli = crate::length::div_round_half_away(10_000_000_000, h.max(1));
                let _ = write!(l, "{}.{:03}", milli / 1000, milli % 1000);
            }
            Place::Kept(i, decimal) => {
                let v = front.kept.get(i).copied().unwrap_or(0);
                let _ = if decimal {
                    write!(l, "{}.{:03}", v / 1000, v % 1000)
                } else {
                    write!(l, "{v}")
                };
            }
            Place::Fixed(v, _, _) => l.push_bytes(v),
            Place::ReportMask => {
                let _ = write!(l, "{}", u8::from(front.mpos));
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
        Place::Request(command, key) => {
            let mut req = ReplyLine::new();
            req.push_bytes(command);
            req.push_bytes(b" ");
            req.push_bytes(key);
            req.push_bytes(b"=");
            req.push_bytes(v);
            let request = ReplyLine::clone(&req);
            session.handle_line(request.as_bytes(), io);
        }
        Place::StepsPerMm(key) => {
            // One over the steps: a price on the 10⁻⁷ mm grid.
            let steps = core::str::from_utf8(v)
                .ok()
                .and_then(|t| crate::length::Length::from_gcode_mm(t).ok())
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
            let mut req = ReplyLine::new();
            req.push_bytes(b"CFG ");
            req.push_bytes(key);
            req.push_bytes(b"=");
            let _ = crate::length::write_exact_mm(&mut req, price as i64);
            let request = ReplyLine::clone(&req);
            session.handle_line(request.as_bytes(), io);
        }
        Place::Kept(i, decimal) => match (parse_setting(v, decimal), front.kept.get_mut(i)) {
            (Some(value), Some(slot)) => {
                *slot = value;
                io.outcome = Some(Ok(()));
            }
            _ => refuse_setting(
                io,
                2,
                s.n,
                if decimal {
                    b"a number with up to 3 decimals"
                } else {
                    b"a whole number up to 65535"
                },
            ),
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

//! What the grbl front writes from typed values: status reports, error
//! numbers.

use super::front::*;
use crate::protocol::io::{ErrorCode, Refused, State, StatusRecord};
use crate::protocol::reply::ReplyLine;
use crate::protocol::session::Session;
use core::fmt::Write;

/// A line ended without a checksum, as grbl ends its lines.
pub(super) fn finish(line: &mut ReplyLine) -> &[u8] {
    line.push_bytes(b"\r\n");
    line.as_bytes()
}

/// Writes `Å` as mm with 4 decimals (X doubled when `diameter`).
pub(super) fn write_mm(line: &mut ReplyLine, angstrom: i64, diameter: bool) {
    let v = if diameter { 2 * angstrom } else { angstrom };
    let _ = crate::length::write_mm4(line, crate::length::div_round_half_away(v, 1_000));
}

/// What the grbl link shows of the session's machine state, beside the
/// status line: the work offset, the override, the mode.
#[derive(Clone, Copy, Debug)]
pub struct Extras {
    /// Work zero in machine coordinates, Å, X on the radius (`WCO:`).
    pub wco: [i64; 2],
    /// X as a diameter.
    pub diameter: bool,
    /// Feed, rapid and spindle overrides, percent.
    pub overrides: [u8; 3],
    /// A jog runs.
    pub jogging: bool,
    /// The alarm in force.
    pub alarm: Option<u8>,
    /// Check mode (`$C`).
    pub check: bool,
    /// Positions as machine coordinates (`MPos:`), else work (`WPos:`).
    pub mpos: bool,
}

impl Extras {
    /// Nothing to add (a pendant link).
    pub const NONE: Extras = Extras {
        wco: [0, 0],
        diameter: false,
        overrides: [100; 3],
        jogging: false,
        alarm: None,
        check: false,
        mpos: true,
    };

    /// The session's.
    pub fn of(session: &Session, front: &Front) -> Extras {
        let v = session
            .offsets()
            .vector(session.selection())
            .unwrap_or([crate::length::Length::ZERO; 2]);
        Extras {
            wco: [v[0].as_angstrom(), v[1].as_angstrom()],
            diameter: session.config().diam,
            overrides: [front.feed, front.rapid, front.spindle],
            jogging: front.jogging,
            alarm: front.alarm.or(session.alarm()),
            check: front.check,
            mpos: front.mpos,
        }
    }
}

/// A pendant status line (`STATUS`/`!STATUS`) as grbl's status report:
/// `<Run|MPos:X,0.0000,Z|FS:F,S|WCO:…|Ov:…|D:1>`.
pub fn status_report(record: &StatusRecord, extras: &Extras) -> ReplyLine {
    let mut line = ReplyLine::new();
    let at_rest = record.speed_mm4() == 0;
    let state: &[u8] = match (extras.alarm, record.state(), record.view.stop) {
        (Some(_), _, _) => b"Alarm",
        _ if extras.check => b"Check",
        (_, _, Some(_)) => b"Hold:0",
        (_, State::Hold, _) if at_rest => b"Hold:0",
        (_, State::Hold, _) => b"Hold:1",
        (_, State::Run, _) if extras.jogging => b"Jog",
        (_, State::Run, _) => b"Run",
        (_, State::Idle, _) => b"Idle",
    };
    line.push_bytes(b"<");
    line.push_bytes(state);
    let (x, z) = (record.x_mm4(), record.z_mm4());
    if extras.mpos {
        line.push_bytes(b"|MPos:");
        let _ = crate::length::write_mm4(&mut line, x);
        line.push_bytes(b",0.0000,");
        let _ = crate::length::write_mm4(&mut line, z);
    } else {
        // Work position: the machine's less the work offset.
        line.push_bytes(b"|WPos:");
        let wco = |a: i64, diameter| {
            let v = if diameter { 2 * a } else { a };
            crate::length::div_round_half_away(v, 1_000)
        };
        let _ = crate::length::write_mm4(&mut line, x - wco(extras.wco[0], extras.diameter));
        line.push_bytes(b",0.0000,");
        let _ = crate::length::write_mm4(&mut line, z - wco(extras.wco[1], false));
    }
    line.push_bytes(b"|FS:");
    let _ = crate::length::write_mm4(&mut line, record.speed_mm4());
    line.push_bytes(b",");
    let _ = crate::outputs::write_rpm(&mut line, record.view.outputs.rpm);
    if let Some(pins) = record.view.pins.filter(|&p| p != 0) {
        line.push_bytes(b"|Pn:");
        let _ = crate::inputs::write_letters(&mut line, pins);
    }
    line.push_bytes(b"|WCO:");
    write_mm(&mut line, extras.wco[0], extras.diameter);
    line.push_bytes(b",0.0000,");
    write_mm(&mut line, extras.wco[1], false);
    let [f, r, s] = extras.overrides;
    let _ = write!(line, "|Ov:{f},{r},{s}|D:{}>", u8::from(extras.diameter));
    line
}

/// The grbl error number of a refusal: expected command letter or bad
/// number format (1), undefined feed rate (22), unsupported command (20),
/// invalid target (33), line overflow (11), travel exceeded (15), locked
/// by an alarm (9), the E-stop (grblHAL's 50).
pub fn error_number(why: Refused) -> u8 {
    use ErrorCode as E;
    match why.code {
        E::Syntax | E::Checksum => 1,
        E::Value if why.about == Some(b'F') => 22,
        E::Unknown | E::Value | E::Empty | E::Session => 20,
        E::Geometry => 33,
        E::LineTooLong => 11,
        E::Range => 15,
        E::Alarm => 9,
        E::Estop => 50,
    }
}

/// `[PRB:x,0.0000,z:n]`: where the last probing move ended (machine
/// coordinates), `n` 1 when the probe changed there.
pub(super) fn probe_line(probe: Option<crate::inputs::ProbeResult>, diameter: bool) -> ReplyLine {
    let (at, changed) = probe.map_or(([crate::length::Length::ZERO; 2], false), |p| {
        (p.at, p.changed)
    });
    let mut l = ReplyLine::new();
    l.push_bytes(b"[PRB:");
    write_mm(&mut l, at[0].as_angstrom(), diameter);
    l.push_bytes(b",0.0000,");
    write_mm(&mut l, at[1].as_angstrom(), false);
    let _ = write!(l, ":{}]", u8::from(changed));
    let _ = finish(&mut l);
    l
}

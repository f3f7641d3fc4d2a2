//! The grbl 1.1 serial protocol, a second front over the same session, so
//! that the senders machinists already use (Universal Gcode Sender, bCNC,
//! CNCjs, ioSender) stream to the controller unchanged.
//!
//! It translates at the edge and interprets nothing twice: a G-code line
//! runs on the [`Session`] exactly as a pendant request does, and its
//! pendant reply becomes `ok` or `error:N` (with a `[MSG:…]` line that says
//! what and where); the session's status line becomes grbl's
//! `<Idle|MPos:…|FS:…|WCO:…|Ov:…>`; a reset's report becomes the banner.
//! The lathe is reported as grblHAL reports its lathe mode: `$32=2`,
//! `LATHE` among the options, X as a diameter in diameter mode (`G7` in
//! `$G`, `|D:1`) and Y always 0.
//!
//! What a grbl sender needs of the link: character counting against an RX
//! buffer of [`RX_BUFFER`] bytes (the board's serial ring holds 512), `?`,
//! `!`, `~` and Ctrl-X as real-time characters wherever they fall, 0x85
//! jog cancel and the feed overrides 0x90–0x94. Rapid and spindle
//! overrides are not implemented: their bytes are answered with a message
//! and change nothing.

use super::io::{Io, Realtime};
use super::reply::ReplyLine;
use super::request::{Command, Request};
use super::session::{Session, VERSION};
use core::fmt::Write;

mod front;
mod report;
mod settings;
mod translate;

pub use front::{dropped, Front, GrblRealtime, KEPT, KEPT_DEFAULT};
pub use report::{error_number, status_report, Extras};
pub use translate::Translate;

use report::*;
use settings::*;

/// The RX buffer a sender may fill by character counting (`$I`'s `OPT`).
pub const RX_BUFFER: usize = 128;
/// Planner blocks (`$I`'s `OPT`: the queue less one, as grbl counts).
pub const BLOCKS: usize = 63;
/// The welcome line after a reset.
pub const BANNER: &[u8] = b"\r\nGrbl 1.1h ['$' for help]\r\n";

/// `$#`: work offsets, the stored positions, the G92 shift.
fn offsets<I: Io + ?Sized>(session: &Session, io: &mut Translate<'_, I>) {
    let o = session.offsets();
    let diameter = session.config().diam;
    let mut put = |name: &[u8], p: [crate::length::Length; 2]| {
        let mut l = ReplyLine::new();
        l.push_bytes(b"[");
        l.push_bytes(name);
        l.push_bytes(b":");
        write_mm(&mut l, p[0].as_angstrom(), diameter);
        l.push_bytes(b",0.0000,");
        write_mm(&mut l, p[1].as_angstrom(), false);
        l.push_bytes(b"]");
        io.inner.send(finish(&mut l));
    };
    let names: [&[u8]; 6] = [b"G54", b"G55", b"G56", b"G57", b"G58", b"G59"];
    for (name, w) in names.iter().zip(o.work.iter()) {
        put(name, *w);
    }
    put(b"G28", o.reference[0]);
    put(b"G30", o.reference[1]);
    put(b"G92", o.shift);
    io.line(b"[TLO:0.0000]");
    let l = probe_line(session.last_probe(), diameter);
    io.inner.send(l.as_bytes());
}

/// `$G`: the modal state, grblHAL's lathe words included.
fn modes<I: Io + ?Sized>(session: &Session, io: &mut Translate<'_, I>) {
    use crate::gcode::{Coolant, FeedMode, Spindle, SpindleMode, Units};
    let m = session.modal();
    let aux = session.aux();
    let mut l = ReplyLine::new();
    let _ = write!(
        l,
        "[GC:G{} G{} {} G18 {} {} {} {} {} {} T{}",
        match m.motion {
            crate::gcode::Motion::Rapid => 0,
            crate::gcode::Motion::Linear => 1,
            crate::gcode::Motion::ArcCw => 2,
            crate::gcode::Motion::ArcCcw => 3,
        },
        54 + session.selection().wcs,
        if session.config().diam { "G7" } else { "G8" },
        if m.units == Units::Inch { "G20" } else { "G21" },
        if m.incremental { "G91" } else { "G90" },
        if m.feed_mode == FeedMode::PerRev {
            "G95"
        } else {
            "G94"
        },
        if aux.spindle.mode == SpindleMode::Surface {
            "G96"
        } else {
            "G97"
        },
        match aux.spindle.turning {
            Spindle::Cw => "M3",
            Spindle::Ccw => "M4",
            Spindle::Off => "M5",
        },
        match aux.coolant {
            Coolant::Mist => "M7",
            Coolant::Flood => "M8",
            Coolant::Off => "M9",
        },
        session.selection().loaded,
    );
    l.push_bytes(b" F");
    let _ = write!(l, "{}", m.feed.unwrap_or(crate::length::Length::ZERO));
    l.push_bytes(b" S");
    let _ = write!(
        l,
        "{}",
        aux.spindle.s.unwrap_or(crate::length::Length::ZERO)
    );
    l.push_bytes(b"]");
    io.inner.send(finish(&mut l));
}

/// `$J=…`: a jog as a `MOVE` in machine coordinates (G90 words are work
/// coordinates unless `G53`; G91 an increment; mm only; `F` required).
fn jog_line<I: Io + ?Sized>(
    session: &mut Session,
    words: &[u8],
    io: &mut Translate<'_, I>,
) -> bool {
    let refuse = |io: &mut Translate<'_, I>, code: u8, why: &[u8]| {
        io.outcome = Some(Err(code));
        io.message = ReplyLine::new();
        io.message.push_bytes(b"$J: ");
        io.message.push_bytes(why);
        false
    };
    let (mut inc, mut machine) = (false, false);
    let mut axes: [Option<crate::length::Length>; 2] = [None, None];
    let mut feed = None;
    let mut rest = words;
    while let Some((&first, tail)) = rest.split_first() {
        let letter = first.to_ascii_uppercase();
        let len = tail
            .iter()
            .position(|b| !(b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+')))
            .unwrap_or(tail.len());
        let (digits, after) = (
            tail.get(..len).unwrap_or(b""),
            tail.get(len..).unwrap_or(b""),
        );
        let number = core::str::from_utf8(digits).unwrap_or("");
        rest = after;
        match (letter, number) {
            (b' ', _) => continue,
            (b'G', "90") => inc = false,
            (b'G', "91") => inc = true,
            (b'G', "53") => machine = true,
            (b'G', "21") => {}
            (b'G', "20") => return refuse(io, 20, b"inches are not jogged here: G21"),
            (b'X' | b'Z' | b'F', n) => match crate::length::Length::from_gcode_mm(n) {
                Ok(v) if letter == b'X' => axes[0] = Some(v),
                Ok(v) if letter == b'Z' => axes[1] = Some(v),
                Ok(v) => feed = Some(v),
                Err(_) => return refuse(io, 2, b"bad number"),
            },
            _ => return refuse(io, 20, b"only X, Z, F, G20/G21, G90/G91, G53"),
        }
    }
    let Some(f) = feed else {
        return refuse(io, 22, b"F is required");
    };
    if axes == [None, None] {
        return refuse(io, 26, b"no axis word");
    }
    // `MOVE` takes work coordinates (as `POS` prints them): a G53 target
    // less the offsets in effect (X on the diameter when the words are
    // diameters).
    let wco = if machine && !inc {
        let w = Extras::of(session, &Front::new()).wco;
        [-w[0], -w[1]]
    } else {
        [0, 0]
    };
    let diameter = session.config().diam;
    let shifts = [if diameter { 2 * wco[0] } else { wco[0] }, wco[1]];
    // The values as a request line would give them, exact in mm.
    let mut text = [ReplyLine::new(), ReplyLine::new(), ReplyLine::new()];
    let values = [
        axes[0].map(|v| v.as_angstrom() + shifts[0]),
        axes[1].map(|v| v.as_angstrom() + shifts[1]),
        Some(f.as_angstrom()),
    ];
    for (t, v) in text.iter_mut().zip(values) {
        if let Some(v) = v {
            let _ = crate::length::write_exact_mm(t, v);
        }
    }
    let [x, z, feed] = text
        .each_ref()
        .map(|t| core::str::from_utf8(t.as_bytes()).unwrap_or(""));
    let mut args: heapless::Vec<(&'static str, &str), 4> = heapless::Vec::new();
    for (key, (given, value)) in ["X", "Z"].into_iter().zip(axes.iter().zip([x, z])) {
        if given.is_some() {
            let _ = args.push((key, value));
        }
    }
    if inc {
        let _ = args.push(("INC", "1"));
    }
    let _ = args.push(("F", feed));
    match Request::command(Command::Move, &args) {
        Ok(request) => session.request(&request, io),
        Err(_) => return refuse(io, 3, b"not a MOVE"),
    }
    io.outcome == Some(Ok(()))
}

/// Runs one line received in grbl mode. Returns whether the link goes
/// back to the pendant protocol (`$PENDANT`).
pub fn line<I: Io + ?Sized>(
    front: &mut Front,
    session: &mut Session,
    text: &[u8],
    io: &mut I,
) -> bool {
    let extras = Extras::of(session, front);
    let trimmed = trim(text);
    let upper = |i: usize| trimmed.get(i).map(u8::to_ascii_uppercase);
    let command = trimmed.first() == Some(&b'$');
    let jog = command && upper(1) == Some(b'J') && upper(2) == Some(b'=');
    if front.check && (jog || !command) && !trimmed.is_empty() {
        // Check mode: the line is read and checked, its motion goes
        // nowhere.
        let mut t = Translate::grbl(io, extras);
        t.dry = true;
        if jog {
            jog_line(session, trimmed.get(3..).unwrap_or(b""), &mut t);
        } else {
            session.handle_line(text, &mut t);
        }
        t.answer();
        return false;
    }
    let mut t = Translate::grbl(io, extras);
    if trimmed.first() == Some(&b'$') {
        t.outcome = Some(Ok(()));
        match (upper(1), trimmed.len()) {
            (None, _) => {
                t.line(b"[HLP:$$ $# $G $I $N $x=val $J=line $C $X $H $PENDANT ~ ! ? ctrl-x]")
            }
            (Some(b'$'), 2) => settings(session, front, &mut t),
            (Some(b'C'), 2) if front.check => {
                // As grbl: check mode ends with a reset (the banner).
                front.check = false;
                session.check_end();
                t.line(b"[MSG:Disabled]");
                realtime(front, session, GrblRealtime::Common(Realtime::Reset), io);
                return false;
            }
            (Some(b'C'), 2) => {
                if session.check_begin(&mut t) {
                    front.check = true;
                    t.line(b"[MSG:Enabled]");
                } else {
                    t.outcome = Some(Err(8));
                    t.message.push_bytes(b"$C only at rest with nothing queued");
                }
            }
            (Some(b'#'), 2) => offsets(session, &mut t),
            (Some(b'G'), 2) => modes(session, &mut t),
            (Some(b'I'), 2) => {
                let mut l = ReplyLine::new();
                let _ = write!(l, "[VER:1.1h.{VERSION}:lathe-retrofit]");
                t.inner.send(finish(&mut l));
                let mut l = ReplyLine::new();
                let _ = write!(l, "[OPT:VNM,{BLOCKS},{RX_BUFFER}]");
                t.inner.send(finish(&mut l));
                t.line(b"[NEWOPT:LATHE]");
                t.line(b"[FIRMWARE:lathe-retrofit]");
            }
            (Some(b'N'), 2) => {
                t.line(b"$N0=");
                t.line(b"$N1=");
            }
            (Some(b'X'), 2) if session.alarm() == Some(11) => {
                // Homing required at power-on: only `$H` clears it, as
                // grblHAL answers (`error:46`); the pendant's `UNLOCK`
                // is the operator's override.
                t.outcome = Some(Err(46));
                t.message = ReplyLine::new();
                t.message.push_bytes(
                    b"homing required: $H homes the machine ($22 bit 2 asks for it at power-on)",
                );
            }
            (Some(b'X'), 2) => {
                front.alarm = None;
                if session.alarm().is_some() {
                    // What an input stopped clears only once its way back
                    // allows (the E-stop released and reset).
                    if let Ok(request) = Request::command(Command::Unlock, &[]) {
                        session.request(&request, &mut t);
                    }
                }
                if t.outcome == Some(Ok(())) {
                    t.line(b"[MSG:Caution: Unlocked]");
                }
            }
            (Some(b'H'), 2 | 3) => {
                // `$H`, `$HX`, `$HZ`: the homing cycle (its failure is an
                // alarm, `ALARM:6`, `8` or `9`); home, the alarm of a reset
                // in motion is cleared as `$X` clears it.
                let axes = match upper(2) {
                    None => Some(None),
                    Some(b'X') => Some(Some("X")),
                    Some(b'Z') => Some(Some("Z")),
                    Some(_) => None,
                };
                match axes {
                    Some(_) if session.homing().order().next().is_none() => {
                        // grbl's error 5: homing not enabled.
                        t.outcome = Some(Err(5));
                        t.message.push_bytes(
                            b"homing is off: $22=1 turns it on, $23 sets the switches' sides, $130/$132 the travels",
                        );
                    }
                    Some(axes) => {
                        let named = [("AXES", axes.unwrap_or(""))];
                        let args: &[(&str, &str)] = if axes.is_some() { &named } else { &[] };
                        if let Ok(request) = Request::command(Command::Home, args) {
                            session.request(&request, &mut t);
                        }
                    }
                    None => {
                        t.outcome = Some(Err(3));
                        t.message.push_bytes(b"$HX or $HZ: a lathe has X and Z");
                    }
                }
                if t.outcome == Some(Ok(())) {
                    front.alarm = None;
                }
            }
            (Some(b'J'), _) if upper(2) == Some(b'=') => {
                if let Some(a) = front.alarm {
                    t.outcome = Some(Err(9));
                    let _ = write!(t.message, "alarm {a}: $X to unlock");
                } else if jog_line(session, trimmed.get(3..).unwrap_or(b""), &mut t) {
                    front.jogging = true;
                }
            }
            _ if trimmed.eq_ignore_ascii_case(b"$PENDANT") => {
                t.answer();
                front.on = false;
                return true;
            }
            _ => match trimmed.iter().position(|&b| b == b'=') {
                Some(eq)
                    if trimmed
                        .get(1..eq)
                        .is_some_and(|n| !n.is_empty() && n.iter().all(u8::is_ascii_digit)) =>
                {
                    let n = trimmed.get(1..eq).unwrap_or(b"");
                    let v = trim(trimmed.get(eq + 1..).unwrap_or(b""));
                    set(session, front, n, v, &mut t);
                }
                _ => {
                    t.outcome = Some(Err(3));
                    t.message.push_bytes(b"not a $ command of this controller");
                }
            },
        }
    } else if trimmed.is_empty() {
        t.outcome = Some(Ok(()));
    } else if let Some(a) = front.alarm {
        t.outcome = Some(Err(9));
        let _ = write!(t.message, "alarm {a}: $X to unlock");
    } else {
        front.jogging = false;
        session.handle_line(text, &mut t);
    }
    t.answer();
    false
}

fn trim(text: &[u8]) -> &[u8] {
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    let end = text
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(start, |e| e + 1);
    text.get(start..end).unwrap_or(&[])
}

/// Acts on a grbl real-time character.
pub fn realtime<I: Io + ?Sized>(
    front: &mut Front,
    session: &mut Session,
    rt: GrblRealtime,
    io: &mut I,
) {
    let extras = Extras::of(session, front);
    let mut t = Translate::grbl(io, extras);
    match rt {
        GrblRealtime::Common(Realtime::Status) => session.realtime(Realtime::Status, &mut t),
        GrblRealtime::Common(Realtime::Reset) => {
            t.statuses = false;
            session.realtime(Realtime::Reset, &mut t);
            // Motion answered `ok` and not all run (in motion, braking,
            // held with more to do, or queued) was dropped: the sender
            // hears it as an alarm, never as silence.
            let moving = session.reset_dropped_motion();
            front.jogging = false;
            front.cancel = false;
            (front.feed, front.rapid, front.spindle) = (100, 100, 100);
            session.set_feed_override(100);
            session.set_rapid_override(100);
            session.set_spindle_override(100, &mut t);
            if moving || t.reset == Some(true) {
                // Stopped at once in motion: a drive may have lost steps.
                front.alarm = Some(3);
                t.line(b"ALARM:3");
            }
            t.inner.send(BANNER);
            if front.alarm.or(session.alarm()).is_some() {
                t.line(b"[MSG:'$H'|'$X' to unlock]");
            }
        }
        GrblRealtime::Common(rt) => {
            t.statuses = false;
            session.realtime(rt, &mut t);
        }
        GrblRealtime::JogCancel => {
            if front.jogging {
                t.statuses = false;
                session.realtime(Realtime::Hold, &mut t);
                front.cancel = true;
            }
        }
        GrblRealtime::Feed(_) => {
            [front.feed, _, _] = rt.overrides([front.feed, front.rapid, front.spindle]);
            session.set_feed_override(front.feed);
        }
        GrblRealtime::Rapid(_) => {
            [_, front.rapid, _] = rt.overrides([front.feed, front.rapid, front.spindle]);
            session.set_rapid_override(front.rapid);
        }
        GrblRealtime::Spindle(_) => {
            [_, _, front.spindle] = rt.overrides([front.feed, front.rapid, front.spindle]);
            session.set_spindle_override(front.spindle, &mut t);
        }
        GrblRealtime::Unsupported(_) => {
            t.line(b"[MSG:spindle stop and coolant toggles are not implemented]")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::io::{StatusRecord, StatusView};

    /// X 10 mm on the diameter (1000 impulses of 0.005 mm on the radius),
    /// Z −5 mm (−500 of 0.01 mm), at `speed` (10⁻⁴ mm/min).
    fn record(motion: crate::stepper::AxesState, speed: i64) -> StatusRecord {
        use crate::interleave::ImpulsePoint;
        StatusRecord {
            motion,
            issued: ImpulsePoint {
                x: crate::impulse::Impulses(1000),
                z: crate::impulse::Impulses(-500),
            },
            queued: 3,
            view: StatusView {
                hx: 50_000,
                hz: 100_000,
                diam: true,
                speed,
                starved: 0,
                stop: None,
                outputs: crate::outputs::Outputs {
                    spindle: crate::gcode::Spindle::Cw,
                    rpm: 800_000,
                    top: 0,
                    coolant: crate::gcode::Coolant::Off,
                },
                pins: None,
                alarm: 0,
                lost: false,
            },
        }
    }

    #[test]
    fn a_status_record_becomes_a_report() {
        let extras = Extras {
            wco: [5_000_000, -1_200_000_000],
            diameter: true,
            overrides: [100; 3],
            jogging: false,
            alarm: None,
            check: false,
            mpos: true,
        };
        let r = status_report(&record(crate::stepper::AxesState::Run, 2_000_000), &extras);
        assert_eq!(
            r.as_bytes(),
            b"<Run|MPos:10.0000,0.0000,-5.0000|FS:200.0000,800.000|WCO:1.0000,0.0000,-120.0000|Ov:100,100,100|D:1>"
        );
        // The pendant's line says the same.
        let line = crate::protocol::session::status_line(
            "!STATUS",
            &record(crate::stepper::AxesState::Run, 2_000_000),
        );
        assert_eq!(
            line.as_bytes(),
            b"!STATUS STATE=RUN PX=1000 PZ=-500 X=10.0000 Z=-5.0000 V=200.0000 Q=3 STARVED=0 SPINDLE=CW S=800.000 COOLANT=OFF"
        );
        // Braking still moves; held is at rest whatever the last speed.
        let braking = status_report(&record(crate::stepper::AxesState::Braking, 5), &extras);
        assert!(braking.as_bytes().starts_with(b"<Hold:1|"));
        let held = status_report(&record(crate::stepper::AxesState::Held, 5), &extras);
        assert!(held.as_bytes().starts_with(b"<Hold:0|"));
    }

    #[test]
    fn a_work_position_is_the_machine_position_less_the_offset() {
        let extras = Extras {
            wco: [5_000_000, -1_200_000_000],
            diameter: true,
            overrides: [100; 3],
            jogging: false,
            alarm: None,
            check: false,
            mpos: false,
        };
        let idle = record(crate::stepper::AxesState::Idle, 0);
        let r = status_report(&idle, &extras);
        // X 10 on the diameter less 2·0.5 mm; Z −5 less −120.
        assert!(
            r.as_bytes()
                .starts_with(b"<Idle|WPos:9.0000,0.0000,115.0000|"),
            "{:?}",
            core::str::from_utf8(r.as_bytes())
        );
        let check = Extras {
            check: true,
            ..extras
        };
        assert!(status_report(&idle, &check)
            .as_bytes()
            .starts_with(b"<Check|"));
    }

    #[test]
    fn setting_values_are_read_as_grbl_writes_them() {
        assert_eq!(parse_setting(b"25", false), Some(25));
        assert_eq!(parse_setting(b"25.5", true), Some(25_500));
        assert_eq!(parse_setting(b".125", true), Some(125));
        assert_eq!(parse_setting(b"2.", true), Some(2_000));
        assert_eq!(parse_setting(b"2.5", false), None);
        assert_eq!(parse_setting(b"1.0001", true), None);
        assert_eq!(parse_setting(b"65536", false), None);
        assert_eq!(parse_setting(b"", false), None);
        assert_eq!(parse_setting(b"x", true), None);
    }
}

//! The homing cycle on the simulated machine (`docs/inputs.md` §8): a
//! lathe from a machine file behind the simulated board, its carriages
//! tripping their switches where the file puts them.

use host_sim::board::Board;
use host_sim::link::Client;
use std::path::PathBuf;
use std::time::Duration;
use tests::{ask, carriage};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The example lathe behind a board speaking the pendant protocol, its
/// four limit switches wired, radius mode.
fn lathe() -> (Board, Client) {
    let text = std::fs::read_to_string(root().join("examples/machine.toml")).expect("file");
    let (board, mut c) = tests::lathe_board(&text, SETUP, false);
    c.drain();
    (board, c)
}

/// Radius mode, the four limit switches wired.
const SETUP: &str = "CFG DIAM=0\nINPUT USED=X-,X+,Z-,Z+\n";

/// Reads a failed `HOME` of X on its plus switch: the alarm line of
/// `code`, then the request's `ERR ALARM` saying `why`.
fn homing_failed(c: &mut Client, code: u8, why: &str) {
    let alarm = c.read_line().expect("alarm");
    assert!(
        alarm.starts_with(&format!("!ALARM CODE={code} INPUT=X+ AXIS=X PX=")),
        "{alarm}"
    );
    let reply = c.read_reply().expect("reply");
    assert!(
        reply.last.starts_with(&format!("ERR ALARM {code}: {why}")),
        "{reply:?}"
    );
}

/// Homing twice from two different places ends with the carriages at the
/// same place, a pull-off short of their switches, and the machine
/// position there is the home set; the position is then no longer lost.
#[test]
fn homing_ends_at_the_same_place_wherever_it_starts() {
    let (board, mut c) = lathe();
    let set = ask(
        &mut c,
        "HOMING AXES=XZ HOMEX=70 HOMEZ=0 TRAVELX=77 TRAVELZ=405 SEEK=3000 LOCATE=300 PULLOFF=1",
    );
    assert!(set.is_ok(), "{set:?}");
    assert_eq!(set.value("ORDER"), Some("XZ"));
    let first = ask(&mut c, "HOME");
    assert_eq!(first.last, "OK MX=70 MZ=0", "{first:?}");
    let at_first = carriage(&board);
    // X's switch trips at 74 (the nut at 74.08, 0.08 of play), Z's at 4
    // (the nut at 4.15): home is a pull-off of 1 mm back from where the
    // slow approach tripped it.
    assert!((72.9..73.1).contains(&at_first.0), "{at_first:?}");
    assert!((3.1..3.2).contains(&at_first.1), "{at_first:?}");
    let pos = ask(&mut c, "STATUS");
    assert!(!pos.last.contains("LOST=1"), "{pos:?}");
    // Elsewhere, then home again.
    assert!(ask(&mut c, "MOVE X=20 Z=-150").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
    let second = ask(&mut c, "HOME");
    assert_eq!(second.last, "OK MX=70 MZ=0", "{second:?}");
    let at_second = carriage(&board);
    // The same place, within one impulse of each axis.
    assert!(
        (at_second.0 - at_first.0).abs() <= 0.0051,
        "{at_first:?} {at_second:?}"
    );
    assert!(
        (at_second.1 - at_first.1).abs() <= 0.0101,
        "{at_first:?} {at_second:?}"
    );
    // A move to the machine position 60 goes 10 mm from home.
    assert!(ask(&mut c, "MOVE X=60").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
    let moved = carriage(&board);
    assert!((at_second.0 - moved.0 - 10.0).abs() < 0.1, "{moved:?}");
}

/// Soft limits once homed: X homes to 70 towards plus with 77 mm of
/// travel, so X may reach −7 … 70. A move, a G-code block, an arc, a
/// canned cycle beyond are refused before anything moves (a grbl jog:
/// error 15, in the grbl test); within they run. A G-code block refused
/// stops the program with alarm 2 until unlocked. Setting the machine position by hand (`ZERO`) ends them.
#[test]
fn soft_limits_refuse_motion_beyond_the_travel_once_homed() {
    let (board, mut c) = lathe();
    let set = ask(
        &mut c,
        "HOMING AXES=X HOMEX=70 TRAVELX=77 SEEK=3000 LOCATE=300 PULLOFF=1 SOFT=1",
    );
    assert!(set.last.ends_with(" SOFT=1 JOGCLIP=0"), "{set:?}");
    // Not homed yet: nothing refused.
    assert!(ask(&mut c, "MOVE X=20").is_ok());
    assert!(ask(&mut c, "HOME").is_ok());
    let home = carriage(&board);
    for (request, axis) in [
        ("MOVE X=70.01", "X"),
        ("MOVE X=-7.5", "X"),
        ("G01 X71 F500", "X"),
        ("G01 X69 F500", ""),
        // A quarter circle from X69 Z0 to X60 Z-9 about X60 Z0 bulges to
        // X69 only; about X69 Z-9 (the other way) to X78: refused.
        ("G03 X60 Z-9 I-9 K0", ""),
        ("G00 X69 Z0", ""),
        ("G02 X60 Z-9 I0 K-9", ""),
        ("G00 X69 Z0", ""),
        ("G03 X78 Z-9 I0 K-9", "X"),
        // A canned cycle is checked whole before its first move: Fanuc's
        // G90 from X69 Z0, its cut at X75.
        ("OPT DIALECT=FANUC", ""),
        ("G90 X75 Z-5 F200", "X"),
        ("OPT DIALECT=ISO", ""),
    ] {
        let r = ask(&mut c, request);
        if axis.is_empty() {
            assert!(r.is_ok(), "{request}: {r:?}");
        } else {
            assert!(
                r.last
                    .starts_with(&format!("ERR RANGE {axis} would leave its travel")),
                "{request}: {r:?}"
            );
            if request.starts_with('G') {
                // A program's block: the program stops there (alarm 2)
                // until unlocked.
                let locked = ask(&mut c, "G00 X69 Z0");
                assert!(
                    locked
                        .last
                        .starts_with("ERR ALARM 2: a block would have left the travel"),
                    "{locked:?}"
                );
                assert_eq!(ask(&mut c, "UNLOCK").last, "OK LOST=0");
            }
        }
    }
    assert!(ask(&mut c, "SYNC").is_ok());
    let (x, _) = carriage(&board);
    // 1 mm short of home, the play (0.08) short again when it arrives
    // moving towards plus.
    assert!(
        (home.0 - 1.0 - x).abs() < 0.09,
        "at X69: {x} (home {home:?})"
    );
    // Jogs clipped (JOGCLIP=1, grblHAL's $40): a MOVE past the travel runs
    // up to it; a G-code block past it is still refused.
    let clip = ask(&mut c, "HOMING JOGCLIP=1");
    assert!(clip.last.ends_with(" SOFT=1 JOGCLIP=1"), "{clip:?}");
    let r = ask(&mut c, "MOVE X=75 F=3000");
    assert!(r.is_ok(), "{r:?}");
    assert_eq!(
        r.value("PX"),
        Some("14000"),
        "X at 70, the travel's end: {r:?}"
    );
    assert!(ask(&mut c, "MOVE X=60 F=3000").is_ok());
    let r = ask(&mut c, "MOVE X=80 Z=-1 F=3000");
    assert_eq!(r.value("PX"), Some("14000"), "X at 70 again: {r:?}");
    assert_eq!(
        r.value("PZ"),
        Some("-100"),
        "Z not homed, not clipped: {r:?}"
    );
    assert!(ask(&mut c, "SYNC").is_ok());
    assert!(
        (carriage(&board).0 - home.0).abs() < 0.09,
        "the carriage at home, no switch tripped"
    );
    // The spindle turning, a block past the travel: refused, and once the
    // motion before it has run the spindle stops, as at grbl's alarm 2.
    assert!(ask(&mut c, "M03 S300").is_ok());
    assert_ne!(board.state().spindle, 0, "turning");
    let r = ask(&mut c, "G01 X71 F500");
    assert!(
        r.last.starts_with("ERR RANGE X would leave its travel"),
        "{r:?}"
    );
    assert_eq!(board.state().spindle, 0, "stopped at the alarm");
    assert_eq!(ask(&mut c, "UNLOCK").last, "OK LOST=0");
    assert!(ask(&mut c, "MOVE X=69 Z=0 F=3000").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
    // Set by hand: the machine position is no longer homing's.
    assert!(ask(&mut c, "ZERO X=0").is_ok());
    assert!(ask(&mut c, "MOVE X=5").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
}

/// A seek that runs its whole length without its switch raises alarm 9
/// and locks the machine until it is unlocked (the position stays lost);
/// an axis with no switch wired is refused before anything moves.
#[test]
fn a_switch_not_found_within_the_travel_raises_alarm_9() {
    let (board, mut c) = lathe();
    // 10 mm of travel: the seek (15 mm) stops far short of 74.
    assert!(ask(&mut c, "HOMING AXES=X TRAVELX=10 SEEK=3000").is_ok());
    c.write_raw(b"HOME\n").expect("write");
    homing_failed(&mut c, 9, "homing did not find");
    let (x, _) = carriage(&board);
    assert!((14.9..15.1).contains(&x), "the whole seek ran: {x}");
    let refused = ask(&mut c, "MOVE X=0");
    assert!(refused.last.starts_with("ERR ALARM 9"), "{refused:?}");
    let unlocked = ask(&mut c, "UNLOCK");
    assert_eq!(unlocked.last, "OK LOST=1");
    assert!(ask(&mut c, "MOVE X=0").is_ok());
    // Z homes on a switch no longer wired: refused, nothing moves.
    assert!(ask(&mut c, "INPUT USED=X-,X+").is_ok());
    assert!(ask(&mut c, "HOMING AXES=XZ DIRZ=- TRAVELZ=405").is_ok());
    let before = carriage(&board);
    let refused = ask(&mut c, "HOME AXES=Z");
    assert!(
        refused.last.contains("no limit switch wired"),
        "{refused:?}"
    );
    assert_eq!(carriage(&board), before);
}

/// A grbl sender homes with grbl's settings: `$22` on, `$23` the sides,
/// `$24`/`$25` the rates, `$27` the pull-off, `$130`/`$132` the travels;
/// `$H` answers `ok` and the machine position is the home (0), `$HX`
/// homes X alone; a seek that finds nothing is `ALARM:9`, cleared by `$X`.
#[test]
fn a_grbl_sender_homes_with_grbls_settings() {
    let text = std::fs::read_to_string(root().join("examples/machine.toml")).expect("file");
    let (board, mut c) = tests::lathe_board(&text, SETUP, true);
    // A board greets the sender that opens its port.
    assert_eq!(c.read_line().expect("banner"), "");
    assert!(c.read_line().expect("banner").starts_with("Grbl 1.1h"));
    let say = tests::grbl_say;
    assert_eq!(
        say(&mut c, "$H"),
        [
            "[MSG:homing is off: $22=1 turns it on, $23 sets the switches' sides, \
             $130/$132 the travels]",
            "error:5"
        ]
    );
    for line in [
        "$22=1", "$23=0", "$24=300", "$25=3000", "$27=1", "$130=77", "$132=405",
    ] {
        assert_eq!(say(&mut c, line), ["ok"], "{line}");
    }
    assert_eq!(say(&mut c, "$H"), ["ok"]);
    let homed = carriage(&board);
    assert!((72.9..73.1).contains(&homed.0), "{homed:?}");
    c.write_raw(b"?").expect("status");
    let report = c.read_line().expect("report");
    assert!(
        report.starts_with("<Idle|MPos:0.0000,0.0000,0.0000|"),
        "{report}"
    );
    // Soft limits ($20): X may go from 0 down to -77; a jog beyond is
    // grbl's error 15, one within runs.
    assert_eq!(say(&mut c, "$20=1"), ["ok"]);
    let r = say(&mut c, "$J=G91 G21 X0.5 F500");
    assert_eq!(r.last().map(String::as_str), Some("error:15"), "{r:?}");
    assert_eq!(say(&mut c, "$J=G91 G21 X-0.5 F500"), ["ok"]);
    // $40=1 (grblHAL's jog soft limits): a jog past the travel runs up to
    // it, X back at 0.
    assert_eq!(say(&mut c, "$40=1"), ["ok"]);
    assert_eq!(say(&mut c, "$J=G91 G21 X2 F500"), ["ok"]);
    assert_eq!(say(&mut c, "G4 P0.1"), ["ok"]);
    c.write_raw(b"?").expect("status");
    let report = c.read_line().expect("report");
    assert!(report.contains("|MPos:0.0000,0.0000,0.0000|"), "{report}");
    assert_eq!(say(&mut c, "$40=0"), ["ok"]);
    // A program's block beyond: ALARM:2, its error, and the lines after
    // it refused until $X (grbl's soft-limit alarm; nothing moved).
    let r = say(&mut c, "G01 X1 F500");
    assert_eq!(
        r,
        [
            "ALARM:2",
            "[MSG:RANGE X would leave its travel (soft limits: HOMING SOFT=, TRAVELX=)]",
            "error:15"
        ]
    );
    let r = say(&mut c, "G01 X-1 F500");
    assert_eq!(r.last().map(String::as_str), Some("error:9"), "{r:?}");
    assert_eq!(say(&mut c, "$X"), ["[MSG:Caution: Unlocked]", "ok"]);
    assert_eq!(say(&mut c, "G01 X-1 F500"), ["ok"]);
    assert_eq!(say(&mut c, "$20=0"), ["ok"]);
    // X alone, from elsewhere.
    assert_eq!(say(&mut c, "G0 X-20"), ["ok"]);
    assert_eq!(say(&mut c, "$HX"), ["ok"]);
    assert!((carriage(&board).0 - homed.0).abs() <= 0.0051);
    // A travel too short for the switch: alarm 9.
    assert_eq!(say(&mut c, "$132=1"), ["ok"]);
    assert_eq!(say(&mut c, "G0 Z-50"), ["ok"]);
    let r = say(&mut c, "$HZ");
    assert_eq!(r.first().map(String::as_str), Some("ALARM:9"), "{r:?}");
    assert_eq!(r.last().map(String::as_str), Some("error:9"), "{r:?}");
    let r = say(&mut c, "G0 Z0");
    assert_eq!(r.last().map(String::as_str), Some("error:9"), "{r:?}");
    assert_eq!(say(&mut c, "$X"), ["[MSG:Caution: Unlocked]", "ok"]);
}

/// A reset during the seek stops it at once: alarm 6 (`!ALARM CODE=6`,
/// the request's `ERR ALARM 6`, then the reset's own `!RESET`), the
/// machine locked until homed again, which then succeeds.
#[test]
fn a_reset_during_homing_raises_alarm_6() {
    let (board, mut c) = lathe();
    // A slow seek: 77 mm from X0 at 600 mm/min on an 8× clock, about 1 s.
    assert!(ask(&mut c, "HOMING AXES=X TRAVELX=77 SEEK=600 LOCATE=300").is_ok());
    c.write_raw(b"HOME\n").expect("write");
    std::thread::sleep(Duration::from_millis(300));
    c.write_raw(&[0x18]).expect("reset");
    homing_failed(&mut c, 6, "a reset stopped the homing");
    let reset = c.read_line().expect("reset line");
    assert!(reset.starts_with("!RESET "), "{reset}");
    let (x, _) = carriage(&board);
    assert!(x > 1.0 && x < 70.0, "stopped part of the way: {x}");
    let status = ask(&mut c, "STATUS");
    assert!(status.last.contains(" ALARM=6"), "{status:?}");
    let again = ask(&mut c, "HOME");
    assert!(again.is_ok(), "{again:?}");
}

/// A pull-off shorter than the switch's hysteresis and the screw's play
/// (X's releases 0.2 mm back, with 0.08 of play) leaves it pressed: alarm
/// 8, after the seek found it; a longer pull-off then homes.
#[test]
fn a_pull_off_that_leaves_the_switch_pressed_raises_alarm_8() {
    let (board, mut c) = lathe();
    assert!(ask(
        &mut c,
        "HOMING AXES=X TRAVELX=77 SEEK=3000 LOCATE=300 PULLOFF=0.1"
    )
    .is_ok());
    c.write_raw(b"HOME\n").expect("write");
    homing_failed(&mut c, 8, "the pull-off left the switch pressed");
    let state = board.panel_line("STATE?").expect("state").expect("a line");
    assert!(state.contains(" IN=X "), "still on the switch: {state}");
    assert!(ask(&mut c, "HOMING PULLOFF=1").is_ok());
    let homed = ask(&mut c, "HOME");
    assert!(homed.is_ok(), "{homed:?}");
}

//! The machine's switches through the device: the E-stop, a hard limit and
//! a drive's fault stop and lock it, the door and the buttons hold and
//! resume, in the pendant protocol and as a grbl sender sees them.

use super::*;
use crate::inputs::Input;

const ESTOP: u16 = Input::Estop.bit();
const LIMIT_X: u16 = Input::LimitXMinus.bit();
const DOOR: u16 = Input::Door.bit();
const START: u16 = Input::Start.bit();
const FAULT_Z: u16 = Input::FaultZ.bit();

/// Every line as sent, without its terminator (grbl's have no `*HH`).
#[derive(Default)]
struct Raw(Vec<String>);

impl Io for Raw {
    fn send(&mut self, line: &[u8]) {
        let text = std::str::from_utf8(line).expect("ASCII");
        self.0.push(text.trim_end().to_string());
    }
}

fn raw(dev: &mut Device, bytes: &[u8]) -> Vec<String> {
    let mut io = Raw::default();
    dev.receive_bytes(bytes, &mut io);
    io.0
}

fn inputs(dev: &mut Device, active: u16) -> Vec<String> {
    let mut io = Raw::default();
    dev.inputs(active, &mut io);
    io.0
}

/// A device with the E-stop, X's limit, the door, cycle start and Z's
/// drive fault wired.
fn wired() -> Device {
    let mut dev = Device::new();
    let reply = ask1(
        &mut dev,
        "INPUT USED=ESTOP,X-,DOOR,START,FAULTZ INVERT=ESTOP FILTER=5",
    );
    assert_eq!(
        reply, "OK USED=ESTOP,X-,DOOR,START,FAULTZ INVERT=ESTOP FILTER=5",
        "the wiring as set"
    );
    dev
}

fn body(line: &str) -> &str {
    line.rsplit_once('*').map_or(line, |(b, _)| b)
}

#[test]
fn the_estop_drops_the_motion_and_locks_until_released_reset_and_unlocked() {
    let mut dev = wired();
    assert!(
        ask1(&mut dev, "STATUS").ends_with("PN=-"),
        "wired: PN= shown"
    );
    for m in ["M03 S500", "MOVE X=10 F=100", "SYNC", "MOVE Z=-5 F=100"] {
        assert!(ask1(&mut dev, m).starts_with("OK"), "{m}");
    }
    let out = inputs(&mut dev, ESTOP);
    let out: Vec<&str> = out.iter().map(|l| body(l)).collect();
    assert_eq!(
        out,
        ["!ALARM CODE=10 INPUT=ESTOP DONE=0 OF=0 PX=1000 PZ=0"],
        "the queued move dropped at once, the registers kept"
    );
    let status = ask1(&mut dev, "STATUS");
    assert!(
        status.starts_with("OK STATE=ESTOP PX=1000 PZ=0"),
        "{status}"
    );
    assert!(status.contains(" SPINDLE=OFF "), "spindle off: {status}");
    assert!(status.contains(" ALARM=10 LOST=1 PN=E"), "{status}");
    // Locked: nothing moves, nothing runs; what only reads answers.
    for request in ["MOVE X=1 F=100", "G01 X1 F100", "SYNC", "UNLOCK"] {
        let r = ask1(&mut dev, request);
        assert!(
            r.starts_with("ERR ESTOP the E-stop is pressed: release it, reset, then UNLOCK"),
            "{request}: {r}"
        );
    }
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=1000 PZ=0 X=10.0000 Z=0.0000",
        "the commanded point is the registers'"
    );
    // Released: still locked, a reset is next.
    assert!(inputs(&mut dev, 0).is_empty());
    let r = ask1(&mut dev, "UNLOCK");
    assert!(
        r.starts_with("ERR ESTOP the E-stop was pressed: reset, then UNLOCK"),
        "{r}"
    );
    let r = ask(&mut dev, &[0x18]);
    assert!(r[0].starts_with("!RESET DONE=0 OF=0"), "{r:?}");
    let r = ask1(&mut dev, "MOVE X=1 F=100");
    assert!(
        r.starts_with("ERR ESTOP the E-stop was pressed: UNLOCK to go on"),
        "{r}"
    );
    assert!(ask1(&mut dev, "UNLOCK").starts_with("OK LOST=1"));
    let status = ask1(&mut dev, "STATUS");
    assert!(status.starts_with("OK STATE=IDLE"), "{status}");
    assert!(status.ends_with("LOST=1 PN=-"), "the mark stays: {status}");
    assert!(ask1(&mut dev, "MOVE X=1 F=100").starts_with("OK NX=-900"));
    // Setting the machine zero again clears the mark.
    assert_eq!(ask1(&mut dev, "ZERO"), "OK");
    assert!(ask1(&mut dev, "STATUS").ends_with("COOLANT=OFF PN=-"));
}

#[test]
fn a_reset_while_the_estop_is_pressed_does_not_count() {
    let mut dev = wired();
    inputs(&mut dev, ESTOP);
    assert!(ask1(&mut dev, "RESET").starts_with("OK"));
    inputs(&mut dev, 0);
    let r = ask1(&mut dev, "UNLOCK");
    assert!(r.contains("reset, then UNLOCK"), "{r}");
    // The `RESET` request counts as the reset once released.
    assert!(ask1(&mut dev, "RESET").starts_with("OK"));
    assert!(ask1(&mut dev, "UNLOCK").starts_with("OK LOST=1"));
}

#[test]
fn a_hard_limit_alarms_and_unlock_clears_it() {
    let mut dev = wired();
    assert!(ask1(&mut dev, "MOVE X=-3 F=100").starts_with("OK"));
    let out = inputs(&mut dev, LIMIT_X);
    assert_eq!(
        body(&out[0]),
        "!ALARM CODE=1 INPUT=X- DONE=0 OF=0 PX=0 PZ=0"
    );
    let r = ask1(&mut dev, "G00 X5");
    assert!(
        r.starts_with("ERR ALARM 1: a hard limit stopped the axes"),
        "{r}"
    );
    // A second switch while locked adds nothing.
    assert!(inputs(&mut dev, LIMIT_X | FAULT_Z).is_empty());
    assert!(ask1(&mut dev, "STATUS").contains("STATE=ALARM"));
    inputs(&mut dev, LIMIT_X);
    assert!(ask1(&mut dev, "UNLOCK").starts_with("OK LOST=1"));
    // Moving off the switch: allowed once unlocked.
    assert!(ask1(&mut dev, "MOVE X=2 F=100").starts_with("OK"));
}

#[test]
fn a_drive_fault_unlocks_only_once_cleared() {
    let mut dev = wired();
    let out = inputs(&mut dev, FAULT_Z);
    assert!(
        body(&out[0]).starts_with("!ALARM CODE=17 INPUT=FAULTZ"),
        "{out:?}"
    );
    let r = ask1(&mut dev, "UNLOCK");
    assert!(
        r.starts_with("ERR ALARM 17: a drive reported a fault"),
        "{r}"
    );
    inputs(&mut dev, 0);
    assert!(ask1(&mut dev, "UNLOCK").starts_with("OK"));
}

#[test]
fn unwired_inputs_do_nothing_and_show_nothing() {
    let mut dev = Device::new();
    let before = ask1(&mut dev, "STATUS");
    assert!(!before.contains("PN="), "{before}");
    assert!(inputs(&mut dev, u16::MAX).is_empty());
    assert_eq!(ask1(&mut dev, "STATUS"), before);
    assert!(ask1(&mut dev, "MOVE X=1 F=100").starts_with("OK"));
}

#[test]
fn the_door_and_the_buttons_only_show_on_a_device_without_motion() {
    let mut dev = wired();
    // A device without motion in the background holds nothing: no line.
    assert!(inputs(&mut dev, DOOR).is_empty());
    assert!(ask1(&mut dev, "STATUS").ends_with("PN=D"));
    // The cycle-start byte with the door open resumes nothing (its status
    // line still answers it).
    let r = ask(&mut dev, &[0x81]);
    assert!(r[0].starts_with("!STATUS STATE=IDLE"), "{r:?}");
    assert!(inputs(&mut dev, START).is_empty());
    assert!(ask1(&mut dev, "STATUS").ends_with("PN=S"));
}

#[test]
fn bad_wiring_is_refused_by_name_and_changes_nothing() {
    let mut dev = wired();
    for (request, why) in [
        ("INPUT USED=ESTOP,LIMIT", "ERR VALUE USED must list"),
        ("INPUT INVERT=X-,,Z-", "ERR VALUE INVERT must list"),
        ("INPUT FILTER=101", "ERR VALUE FILTER must be 0 to 100 (ms)"),
        ("INPUT FILTER=-1", "ERR VALUE FILTER must be 0 to 100 (ms)"),
    ] {
        let r = ask1(&mut dev, request);
        assert!(r.starts_with(why), "{request}: {r}");
    }
    assert_eq!(
        ask1(&mut dev, "INPUT"),
        "OK USED=ESTOP,X-,DOOR,START,FAULTZ INVERT=ESTOP FILTER=5"
    );
    assert_eq!(
        ask1(&mut dev, "INPUT USED=-"),
        "OK USED=- INVERT=ESTOP FILTER=5"
    );
}

#[test]
fn a_grbl_sender_sees_alarms_pins_and_unlocks() {
    let mut dev = wired();
    raw(&mut dev, b"GRBL\r\n");
    let out = inputs(&mut dev, LIMIT_X);
    assert_eq!(out, ["ALARM:1"], "a hard limit as grbl tells it");
    let status = raw(&mut dev, b"?");
    assert!(
        status[0].starts_with("<Alarm|MPos:") && status[0].contains("|Pn:X|"),
        "{status:?}"
    );
    let r = raw(&mut dev, b"G0 X1\n");
    assert_eq!(r[1], "error:9", "{r:?}");
    let r = raw(&mut dev, b"$X\n");
    assert_eq!(r, ["[MSG:Caution: Unlocked]", "ok"]);
    assert_eq!(raw(&mut dev, b"G0 X1\n"), ["ok"]);
    // The E-stop: error 50 until released, reset and unlocked.
    inputs(&mut dev, 0);
    let out = inputs(&mut dev, ESTOP);
    assert_eq!(out, ["ALARM:10"]);
    let r = raw(&mut dev, b"$X\n");
    assert_eq!(
        r,
        [
            "[MSG:ESTOP the E-stop is pressed: release it, reset, then UNLOCK]",
            "error:50"
        ]
    );
    assert!(raw(&mut dev, b"?")[0].contains("|Pn:E|"));
    inputs(&mut dev, 0);
    let r = raw(&mut dev, &[0x18]);
    assert!(r.iter().any(|l| l == "[MSG:'$H'|'$X' to unlock]"), "{r:?}");
    assert_eq!(raw(&mut dev, b"$X\n"), ["[MSG:Caution: Unlocked]", "ok"]);
    assert!(raw(&mut dev, b"?")[0].starts_with("<Idle|"));
    // A drive's fault: grblHAL's alarm 17 and its letter F (its M is a
    // motor's warning).
    assert_eq!(inputs(&mut dev, FAULT_Z), ["ALARM:17"]);
    let status = raw(&mut dev, b"?");
    assert!(status[0].contains("|Pn:F|"), "{status:?}");
}

//! The homing cycle's settings and what the device refuses before any
//! motion (the cycle itself runs on a transport with switches: the
//! simulated board's lathe, `tests/tests/homing.rs`).

use super::*;
use crate::homing::HomingConfig;

#[test]
fn the_settings_are_kept_as_set_and_read_back_in_the_line() {
    let mut dev = Device::new();
    assert_eq!(
        ask1(&mut dev, "HOMING"),
        "OK AXES=- DIRX=+ DIRZ=+ HOMEX=0 HOMEZ=0 TRAVELX=0 TRAVELZ=0 SEEK=500 LOCATE=25 PULLOFF=1 \
         ORDER=XZ REQUIRED=0 SOFT=0 JOGCLIP=0",
        "power-on: grbl's rates and pull-off, no axis homed"
    );
    // X is a diameter at power-on: HOMEX=150 is 75 on the radius.
    let r = ask1(
        &mut dev,
        "HOMING AXES=XZ DIRZ=- HOMEX=150 HOMEZ=-2.5 TRAVELX=80 TRAVELZ=410 SEEK=1500.5 LOCATE=40 PULLOFF=2 ORDER=ZX REQUIRED=1",
    );
    assert_eq!(
        r,
        "OK AXES=XZ DIRX=+ DIRZ=- HOMEX=150 HOMEZ=-2.5 TRAVELX=80 TRAVELZ=410 SEEK=1500.5 LOCATE=40 \
         PULLOFF=2 ORDER=ZX REQUIRED=1 SOFT=0 JOGCLIP=0"
    );
    let h = *dev.session().homing();
    assert_eq!(h.axes[0].home.as_angstrom(), 75 * 10_000_000);
    assert_eq!(
        (h.seek, h.locate, h.z_first, h.required),
        (1_500_500, 40_000, true, true)
    );
    assert!(h.order().eq([1, 0]));
}

#[test]
fn bad_settings_are_refused_by_name_and_change_nothing() {
    let mut dev = Device::new();
    for (request, why) in [
        ("HOMING DIRX=up", "ERR VALUE DIRX must be + or -"),
        ("HOMING AXES=Y", "ERR VALUE AXES must be X, Z, XZ or -"),
        (
            "HOMING AXES=Z TRAVELZ=-5",
            "ERR VALUE TRAVELZ must be 0 to 10000 mm",
        ),
        (
            "HOMING SEEK=0",
            "ERR VALUE SEEK must be 0.001 to 20000 mm/min",
        ),
        (
            "HOMING LOCATE=0.0005",
            "ERR VALUE LOCATE must be 0.001 to 20000",
        ),
        (
            "HOMING SEEK=20000.001",
            "ERR VALUE SEEK must be 0.001 to 20000",
        ),
        ("HOMING PULLOFF=0", "ERR VALUE PULLOFF must be above 0"),
        (
            "HOMING PULLOFF=100.001",
            "ERR VALUE PULLOFF must be above 0",
        ),
        ("HOMING ORDER=XY", "ERR VALUE ORDER must be XZ or ZX"),
        ("HOMING REQUIRED=2", "ERR VALUE REQUIRED"),
        (
            "HOMING HOMEZ=10000.5",
            "ERR VALUE HOMEZ must be within 10000 mm",
        ),
    ] {
        let r = ask1(&mut dev, request);
        assert!(r.starts_with(why), "{request}: {r}");
    }
    assert_eq!(*dev.session().homing(), HomingConfig::NONE);
}

#[test]
fn home_is_refused_before_anything_moves_when_it_cannot_run() {
    let mut dev = Device::new();
    let r = ask1(&mut dev, "HOME");
    assert!(r.starts_with("ERR SYNTAX no axis homes"), "{r}");
    assert!(ask1(&mut dev, "HOMING AXES=Z DIRZ=-").starts_with("OK"));
    let r = ask1(&mut dev, "HOME");
    assert!(r.starts_with("ERR VALUE TRAVELZ is 0"), "{r}");
    assert!(ask1(&mut dev, "HOMING TRAVELZ=400").starts_with("OK"));
    let r = ask1(&mut dev, "HOME AXES=X");
    assert!(
        r.starts_with("ERR VALUE AXES names an axis that does not home"),
        "{r}"
    );
    let r = ask1(&mut dev, "HOME AXES=Y");
    assert!(r.starts_with("ERR VALUE AXES must be X, Z or XZ"), "{r}");
    let r = ask1(&mut dev, "HOME AXES=-");
    assert!(r.starts_with("ERR VALUE AXES must be X, Z or XZ"), "{r}");
    let r = ask1(&mut dev, "HOME");
    assert!(
        r.starts_with("ERR VALUE AXES names an axis with no limit switch wired"),
        "{r}"
    );
    // Wired, but the in-process device reads no switches.
    assert!(ask1(&mut dev, "INPUT USED=Z-").starts_with("OK"));
    let r = ask1(&mut dev, "HOME");
    assert!(
        r.starts_with("ERR SYNTAX HOME needs a machine with switches"),
        "{r}"
    );
    assert!(ask1(&mut dev, "M03 S500").starts_with("OK"));
    let r = ask1(&mut dev, "HOME");
    assert!(r.contains("spindle or coolant on"), "{r}");
}

/// What a grbl front sends, as it is.
struct Out(Vec<u8>);
impl Io for Out {
    fn send(&mut self, line: &[u8]) {
        self.0.extend_from_slice(line);
    }
}

#[test]
fn homing_required_locks_at_power_on_until_unlocked() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "HOMING AXES=X DIRX=- TRAVELX=80 REQUIRED=1").starts_with("OK"));
    // Power on with the settings as a board loads them from flash.
    let mut next = Device::new();
    next.restore_offsets(*dev.session().offsets());
    let status = ask1(&mut next, "STATUS");
    assert!(
        status.contains("STATE=ALARM") && status.contains(" ALARM=11"),
        "{status}"
    );
    assert!(status.contains(" LOST=1"), "{status}");
    let r = ask1(&mut next, "MOVE X=1");
    assert!(
        r.starts_with("ERR ALARM 11: the machine must be homed"),
        "{r}"
    );
    // A grbl sender's $X is refused as grblHAL refuses it (error 46):
    // only $H clears it there.
    let mut out = Out(Vec::new());
    next.set_grbl(true, &mut out);
    out.0.clear();
    next.receive_bytes(b"$X\n", &mut out);
    assert_eq!(
        String::from_utf8_lossy(&out.0),
        "[MSG:homing required: $H homes the machine ($22 bit 2 asks for it at power-on)]\r\nerror:46\r\n"
    );
    next.set_grbl(false, &mut out);
    assert_eq!(ask1(&mut next, "UNLOCK"), "OK LOST=1");
    assert!(ask1(&mut next, "MOVE X=1").starts_with("OK"));
    // Not required: power-on is unlocked.
    assert!(ask1(&mut next, "HOMING REQUIRED=0").starts_with("OK"));
    let mut third = Device::new();
    third.restore_offsets(*next.session().offsets());
    assert!(ask1(&mut third, "MOVE X=1").starts_with("OK"));
}

/// A probing block where nothing reads a probe (the in-process device) is
/// refused before it moves, and changes nothing.
#[test]
fn probing_needs_a_machine_that_reads_the_probe() {
    let mut dev = Device::new();
    let r = ask1(&mut dev, "G38.2 Z-10 F100");
    assert_eq!(
        r,
        "ERR SYNTAX G38.2 to G38.5 need a machine with switches (the probe)"
    );
    let status = ask1(&mut dev, "STATUS");
    assert!(status.contains(" PX=0 PZ=0 "), "{status}");
    assert_eq!(dev.session().last_probe(), None);
}

/// A grbl sender wires the probe with `$6` (how it reads): the wiring
/// gains PROBE, the other inputs kept.
#[test]
fn grbls_probe_setting_wires_the_probe() {
    let mut out = Out(Vec::new());
    let mut dev = Device::new();
    dev.receive_bytes(b"INPUT USED=X+\n", &mut out);
    dev.set_grbl(true, &mut out);
    dev.receive_bytes(b"$6=1\n", &mut out);
    let w = dev.session().offsets().wiring;
    let probe = crate::inputs::Input::Probe.bit();
    let x = crate::inputs::Input::LimitXPlus.bit();
    assert_eq!((w.used, w.invert), (x | probe, probe));
    dev.receive_bytes(b"$6=0\n", &mut out);
    let w = dev.session().offsets().wiring;
    assert_eq!((w.used, w.invert), (x | probe, 0));
}

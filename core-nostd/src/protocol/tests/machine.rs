//! The machine around the axes: spindle and coolant outputs, gear ranges,
//! the machine's own M codes, path control, the header words of real posts.

use super::*;

#[test]
fn spindle_speeds_that_cannot_be_had_are_refused_and_change_nothing() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    let before = state(&mut dev);
    for (line, want) in [
        (
            "G96 S180 M03",
            "ERR VALUE S G96 surface speed at X0 needs a spindle speed limit (G50 S or G96 D)",
        ),
        (
            "G99 G01 Z-1 F.1",
            "ERR VALUE F per revolution needs the spindle turning (M03/M04 and S)",
        ),
        (
            "G99 G01 Z-1 F0",
            "ERR VALUE F 0: a feed move needs a feed above 0",
        ),
        ("U1 X2", "ERR SYNTAX X and U in one block"),
        ("G01 X1 Y1 F1", "ERR VALUE Y a lathe has no Y axis: only Y0"),
        (
            "G91 X1",
            "ERR VALUE G91 belongs to the ISO dialect (OPT DIALECT=ISO)",
        ),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
        assert_eq!(state(&mut dev), before, "{line}");
    }
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=0.0000 COOLANT=OFF T=- SMAX=0.0000 SPINUP=0.000"
    );
    // S with M05: the feed per revolution still has no speed.
    ask1(&mut dev, "G99 S1000 M05");
    assert!(ask1(&mut dev, "G01 W-1. F.1").starts_with("ERR VALUE F per revolution"));
    ask1(&mut dev, "M04");
    let r = ask(&mut dev, b"G01 W-1. F.1\n");
    assert!(r[1].starts_with("OK NX=0 NZ=-100 "), "{r:?}");
}

#[test]
fn reset_stops_the_spindle_and_coolant_and_ctrl_x_forgets_them() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    ask(
        &mut dev,
        b"G00 X50 Z5\nG50 S2000\nG99 G96 S100 M04 M07 T0303 F.1\n",
    );
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=CCW S=636.6198 SMODE=CSS LIMIT=2000.0000 COOLANT=MIST T=0303 SMAX=0.0000 SPINUP=0.000"
    );
    ask1(&mut dev, "RESET");
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=2000.0000 COOLANT=OFF T=0303 SMAX=0.0000 SPINUP=0.000"
    );
    // The feed per revolution stays with its F, and needs the spindle.
    assert!(ask1(&mut dev, "G01 W-1.").starts_with("ERR VALUE F per revolution"));
    ask(&mut dev, b"\x18");
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=0.0000 COOLANT=OFF T=- SMAX=0.0000 SPINUP=0.000"
    );
    assert_eq!(ask1(&mut dev, "OPT"), "OK BDEL=0 DIALECT=FANUC OPTSTOP=0");
}

#[test]
fn surface_speed_is_taken_at_the_programmed_diameter_whatever_the_offsets() {
    let speed = |setup: &[&str]| {
        let mut dev = Device::new();
        ask1(&mut dev, "OPT DIALECT=FANUC");
        for line in setup {
            assert!(ask1(&mut dev, line).starts_with("OK"), "{line}");
        }
        for line in [
            "G50 S3000",
            "G96 S180 M03 G99",
            "G00 X30. Z2.",
            "G01 Z-10. F.2",
        ] {
            let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        }
        ask1(&mut dev, "AUX")
    };
    let plain = speed(&[]);
    // 180 m/min at Ø30: 1909.8593 rpm, at any tool or work offset.
    assert!(plain.contains(" S=1909.8593 "), "{plain:?}");
    let offset = speed(&["TOOL N=1 X=-20 Z=5", "WORK G=54 X=40", "T0101"]);
    let s = |aux: &str| {
        aux.split(' ')
            .find(|w| w.starts_with("S="))
            .unwrap()
            .to_string()
    };
    assert_eq!(s(&offset), s(&plain));
}

#[test]
fn the_spindle_and_coolant_outputs_follow_the_program_and_status_reports_them() {
    use crate::gcode::{Coolant, Spindle};
    use crate::outputs::Outputs;
    let mut dev = Device::new();
    let mut panel = Panel::default();
    let tell = |dev: &mut Device, panel: &mut Panel, line: &str| -> String {
        dev.receive_bytes(std::format!("{line}\n").as_bytes(), panel);
        panel.lines.out.pop().unwrap()
    };
    let out = |spindle, rpm, coolant| Outputs {
        spindle,
        rpm,
        top: 3_000_000,
        coolant,
    };
    assert_eq!(
        tell(&mut dev, &mut panel, "AUX SMAX=3000 SPINUP=1.5"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=0.0000 COOLANT=OFF T=- SMAX=3000.0000 SPINUP=1.500"
    );
    assert_eq!(panel.outputs, [out(Spindle::Off, 0, Coolant::Off)]);
    for (bad, why) in [
        (
            "AUX SMAX=100000",
            "ERR VALUE SMAX must be 0 to 99999.999 rpm",
        ),
        ("AUX SMAX=-1", "ERR VALUE SMAX must be 0 to 99999.999 rpm"),
        ("AUX SPINUP=61", "ERR VALUE SPINUP must be 0 to 60 s"),
        ("AUX SPINUP=x", "ERR VALUE SPINUP must be 0 to 60 s"),
        ("AUX SMAX=1e3", "ERR VALUE SMAX must be 0 to 99999.999 rpm"),
    ] {
        assert!(tell(&mut dev, &mut panel, bad).starts_with(why), "{bad}");
    }
    tell(&mut dev, &mut panel, "OPT DIALECT=FANUC");
    tell(&mut dev, &mut panel, "G50 S2500");
    tell(&mut dev, &mut panel, "G00 X30. Z2.");
    panel.outputs.clear();
    // 180 m/min at Ø30: 1909.859 rpm; the spindle gets up to speed first.
    tell(&mut dev, &mut panel, "G96 S180 M03");
    assert_eq!(panel.outputs, [out(Spindle::Cw, 1_909_859, Coolant::Off)]);
    assert_eq!(panel.dwells, [1_500_000]);
    let status = tell(&mut dev, &mut panel, "STATUS");
    assert!(
        status.ends_with(" SPINDLE=CW S=1909.859 COOLANT=OFF"),
        "{status}"
    );
    // The coolant switches alone: no spin-up wait.
    tell(&mut dev, &mut panel, "M08");
    assert_eq!(
        panel.outputs[1],
        out(Spindle::Cw, 1_909_859, Coolant::Flood)
    );
    assert_eq!(panel.dwells.len(), 1);
    // Under G96 the speed follows X block by block, with no stop: each
    // block carries the speed where it starts (Ø30, then Ø40: 1432.394).
    tell(&mut dev, &mut panel, "G99 G01 X40. F.2");
    tell(&mut dev, &mut panel, "X60. W-10.");
    tell(&mut dev, &mut panel, "SYNC");
    assert_eq!(panel.outputs.len(), 2);
    let status = tell(&mut dev, &mut panel, "STATUS");
    assert!(
        status.ends_with(" SPINDLE=CW S=1432.394 COOLANT=FLOOD"),
        "{status}"
    );
    // The top speed limits what is commanded, feed per revolution
    // included: 5000 rpm asked, 3000 turned.
    tell(&mut dev, &mut panel, "G50 S9000");
    tell(&mut dev, &mut panel, "G97 S5000 M04");
    assert_eq!(
        panel.outputs[2],
        out(Spindle::Ccw, 3_000_000, Coolant::Flood)
    );
    assert_eq!(panel.dwells, [1_500_000, 1_500_000]);
    assert!(tell(&mut dev, &mut panel, "AUX").starts_with("OK SPINDLE=CCW S=3000.0000 "));
    // A reset drops the outputs at once and forgets the G50 limit; the
    // top speed stays, and is a limit at X0 under G96.
    dev.receive_bytes(b"\x18", &mut panel);
    assert_eq!(panel.outputs[3], out(Spindle::Off, 0, Coolant::Off));
    tell(&mut dev, &mut panel, "G00 X0");
    tell(&mut dev, &mut panel, "G96 S100 M03");
    assert_eq!(panel.outputs[4], out(Spindle::Cw, 3_000_000, Coolant::Off));
    // Taking the top speed away would leave it without one: refused, and
    // nothing changes.
    assert_eq!(
        tell(&mut dev, &mut panel, "AUX SMAX=0"),
        "ERR VALUE SMAX G96 surface speed at X0 needs a spindle speed limit (G50 S or G96 D)"
    );
    assert_eq!(panel.outputs.len(), 5);
    assert!(tell(&mut dev, &mut panel, "STATUS").ends_with(" SPINDLE=CW S=3000.000 COOLANT=OFF"));
    // The end of the program switches everything off.
    tell(&mut dev, &mut panel, "M30");
    assert_eq!(panel.outputs[5], out(Spindle::Off, 0, Coolant::Off));
    assert!(tell(&mut dev, &mut panel, "STATUS").ends_with(" SPINDLE=OFF S=0.000 COOLANT=OFF"));
}

/// Header words of posts for mills and lathes alike: G17 as the plane
/// until G18, path control, G80, F0 before G95; each bad form refused by
/// name, nothing changed.
#[test]
fn header_words_real_programs_hold() {
    let mut dev = Device::new();
    for line in ["G17 G90 G21", "G80 G40 G64 P0.01", "G61.1", "G64", "F0"] {
        assert!(ask1(&mut dev, line).starts_with("OK"), "{line}");
    }
    assert!(ask(&mut dev, b"G00 X20 Z2\n")[1].starts_with("OK NX=2000 "));
    let before = state(&mut dev);
    for (line, want) in [
        (
            "G02 X24 Z0 R2 F100",
            "ERR GEOMETRY in G17 (XY): a lathe turns arcs and compensates in G18 (ZX)",
        ),
        (
            "G19 G42 G01 X24 F100",
            "ERR GEOMETRY in G19 (YZ): a lathe turns arcs and compensates in G18 (ZX)",
        ),
        (
            "G01 X24 Z0",
            "ERR VALUE F 0: a feed move needs a feed above 0",
        ),
        ("G64 P11", "ERR VALUE P a G64 tolerance of 0 to 10 mm"),
        ("G64 P-1", "ERR VALUE P a tolerance is 0 or more"),
        ("G61 G64", "ERR SYNTAX address given twice: G"),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
        assert_eq!(state(&mut dev), before, "{line}");
    }
    // In G18 the arc runs.
    let r = ask(&mut dev, b"G18 G02 X24 Z0 R2 F100\n");
    assert!(r.last().unwrap().starts_with("OK NX="), "{r:?}");
}

/// G61 joins blocks at rest; G64 P at the speed its tolerance allows (a
/// larger one, faster); G64 alone at the limits' JD.
#[test]
fn path_control_decides_how_blocks_join() {
    let corners = |mode: &str| {
        run_ticks(&[
            "G00 X0 Z0",
            mode,
            "G01 X10 Z-10 F2000",
            "X10 Z-20",
            "X20 Z-30",
            "X20 Z-40",
        ])
    };
    let exact = corners("G61");
    let blend = corners("G64");
    let loose = corners("G64 P1");
    let tight = corners("G64 P0.0001");
    assert!(
        exact > tight && tight > blend && blend > loose,
        "{exact} {tight} {blend} {loose}"
    );
    // Collinear blocks: exact stop brakes between them, blending does not.
    let straight = |mode: &str| run_ticks(&[mode, "G01 Z-10 F2000", "Z-20", "Z-30"]);
    assert!(straight("G61") > straight("G64"));
    assert_eq!(straight("G64"), straight("G61.1"));
}

/// M41–M44: a stop that names the range (the gearbox shifted by hand), the
/// range's top speed limiting the spindle.
#[test]
fn a_gear_range_stops_to_be_shifted_and_limits_the_speed() {
    let mut dev = Device::new();
    assert_eq!(
        ask1(&mut dev, "GEAR N=1 TOP=500"),
        "OK RANGE=- G1=500.0000 G2=0.0000 G3=0.0000 G4=0.0000"
    );
    let p = panel(&mut dev, "M41 S1000 M03");
    assert_eq!(p.stops, [41]);
    assert_eq!(
        p.lines.out[0],
        "DATA MSG M41: shift the gearbox to range 1 (up to 500.0000 rpm), then cycle start"
    );
    assert!(
        ask1(&mut dev, "AUX").contains(" S=500.0000 "),
        "{}",
        ask1(&mut dev, "AUX")
    );
    let p = panel(&mut dev, "M42");
    assert_eq!(p.stops, [42]);
    assert!(ask1(&mut dev, "AUX").contains(" S=1000.0000 "));
    assert!(ask1(&mut dev, "GEAR").starts_with("OK RANGE=2 "));
    for (line, want) in [
        (
            "GEAR N=5 TOP=100",
            "ERR VALUE N must be 1 to 4 (M41 to M44)",
        ),
        (
            "GEAR N=1",
            "ERR SYNTAX GEAR sets a range with N and TOP together",
        ),
        ("M41 M42", "ERR SYNTAX address given twice: M"),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
}

/// The machine's own M codes: one not in the table stops with a message
/// naming it, as M00; the table sets it to do nothing, switch a user output
/// or wait for a user input; bad forms refused, the table unchanged.
#[test]
fn machine_m_codes_do_what_the_table_says() {
    let mut dev = Device::new();
    let p = panel(&mut dev, "G00 X10 M16");
    assert_eq!(p.stops, [16]);
    assert_eq!(
        p.lines.out[0],
        "DATA MSG M16: the machine's own M code; do it by hand, then cycle start"
    );
    assert!(p.lines.out.last().unwrap().starts_with("OK NX="));
    assert_eq!(ask1(&mut dev, "MCODE M=16 DO=NONE"), "OK CODES=1");
    assert_eq!(ask1(&mut dev, "MCODE M=31 DO=ON N=2"), "OK CODES=2");
    assert_eq!(ask1(&mut dev, "MCODE M=33 DO=HIGH N=4"), "OK CODES=3");
    let list = ask(&mut dev, b"MCODE\n");
    assert_eq!(
        list,
        [
            "DATA M16 DO=NONE",
            "DATA M31 DO=ON N=2",
            "DATA M33 DO=HIGH N=4",
            "OK CODES=3"
        ]
    );
    let p = panel(&mut dev, "M16");
    assert!(p.stops.is_empty() && p.outputs.is_empty());
    let p = panel(&mut dev, "M31");
    assert_eq!(p.outputs, [(2, true)]);
    let p = panel(&mut dev, "M33");
    assert_eq!(p.waits, [(4, true)]);
    // Back to the default: a stop.
    assert_eq!(ask1(&mut dev, "MCODE M=16 DO=STOP"), "OK CODES=2");
    assert_eq!(panel(&mut dev, "M16").stops, [16]);
    let before = ask(&mut dev, b"MCODE\n");
    for (line, want) in [
        (
            "MCODE M=3 DO=NONE",
            "ERR VALUE M is one the device runs itself (M00-M09, M30, M41-M44, M98, M99)",
        ),
        (
            "MCODE M=16 DO=BLINK",
            "ERR VALUE DO must be STOP, NONE, ON, OFF, HIGH or LOW",
        ),
        (
            "MCODE M=16 DO=ON",
            "ERR SYNTAX ON, OFF, HIGH and LOW need N: 1 to 4",
        ),
        (
            "MCODE M=16 DO=ON N=5",
            "ERR VALUE N must be 1 to 4 (a user output or input)",
        ),
        (
            "MCODE M=16 DO=NONE N=1",
            "ERR SYNTAX N only with ON, OFF, HIGH or LOW",
        ),
        ("MCODE DO=NONE", "ERR SYNTAX DO and N need M: the code"),
        (
            "MCODE M=1000",
            "ERR VALUE M must be a whole M code 0 to 999",
        ),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert_eq!(ask(&mut dev, b"MCODE\n"), before);
    // The table holds 16.
    for m in 100..114 {
        assert!(ask1(&mut dev, &std::format!("MCODE M={m} DO=NONE")).starts_with("OK"));
    }
    assert_eq!(
        ask1(&mut dev, "MCODE M=200 DO=NONE"),
        "ERR RANGE the table holds 16 M codes"
    );
}

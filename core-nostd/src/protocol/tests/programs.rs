//! Programs as posts write them: dialects, inches, offsets and tools, the
//! axis a block does not name, what a board keeps in flash.

use super::*;

#[test]
fn a_posted_program_runs_line_by_line_and_names_what_it_cannot() {
    let mut dev = Device::new();
    let program = [
        "%",
        "O1000 (SHAFT 30 X 40)",
        "(MSG, CHECK THE STOCK)",
        "N5 G18 G21 G40",
        "N10 G00 X30. Z2. Y0",
        "N20 G01 Z-40. F120.",
        "/N30 X32.",
        "N40 X.5 ; facing down",
        "%",
    ];
    for line in program {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
    }
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=50 PZ=-4000 "));
    // With the block delete switch on, `/` blocks are skipped, and say so.
    assert_eq!(ask1(&mut dev, "OPT"), "OK BDEL=0 DIALECT=ISO OPTSTOP=0");
    assert_eq!(
        ask1(&mut dev, "OPT BDEL=1"),
        "OK BDEL=1 DIALECT=ISO OPTSTOP=0"
    );
    assert_eq!(
        ask1(&mut dev, "OPT OPTSTOP=1"),
        "OK BDEL=1 DIALECT=ISO OPTSTOP=1"
    );
    assert_eq!(
        ask1(&mut dev, "OPT OPTSTOP=2"),
        "ERR VALUE OPTSTOP must be 0 or 1"
    );
    let r = ask(&mut dev, b"/N50 X40.\n");
    assert_eq!(r.len(), 1);
    assert!(r[0].ends_with(" SEQ=00000000 SKIP=BDEL"), "{r:?}");
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=50 PZ=-4000 "));
    assert!(ask1(&mut dev, "OPT BDEL=2").starts_with("ERR VALUE BDEL"));
    for (line, want) in [
        (
            "G17 G02 X10 Z-5 R5 F100",
            "ERR GEOMETRY in G17 (XY): a lathe turns arcs and compensates in G18 (ZX)",
        ),
        ("G71 U1. R.5", "ERR VALUE G71 canned cycles not supported"),
        ("G90.2", "ERR VALUE G90.2 not supported"),
        ("G00 X1 Y2", "ERR VALUE Y a lathe has no Y axis: only Y0"),
        (
            "O1000 G00 X1",
            "ERR SYNTAX a program number stands alone at a line's start: O",
        ),
        (
            "o<sub> call",
            "ERR SYNTAX o-word subroutines, loops and conditions are expanded by the host",
        ),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=50 PZ=-4000 "));
}

#[test]
fn inch_programs_move_the_same_steps_as_their_millimetres() {
    let last =
        |dev: &mut Device, line: &str| ask(dev, std::format!("{line}\n").as_bytes()).pop().unwrap();
    let mut inch = Device::new();
    let mut mm = Device::new();
    // 1.25 in = 31.75 mm; 0.5 in/min = 12.7 mm/min; a G20 in a block reads
    // every word of it in inches, then stays.
    for (a, b) in [
        ("G00 X1.25 Z.1 G20", "G00 X31.75 Z2.54"),
        ("G01 Z-1.5 F.5", "G01 Z-38.1 F12.7"),
        ("G02 X1.75 Z-1.75 R.25", "G02 X44.45 Z-44.45 R6.35"),
        ("G91 X-.000001", "G91 X-0.0000254"),
        ("G21 G90 X20 Z0", "G90 X20 Z0"),
    ] {
        assert_eq!(last(&mut inch, a), last(&mut mm, b), "{a} / {b}");
    }
    assert_eq!(ask1(&mut inch, "POS"), ask1(&mut mm, "POS"));
    // Power-on and RESET are millimetres.
    last(&mut inch, "G20");
    ask1(&mut inch, "RESET");
    last(&mut inch, "G00 X10 Z0");
    assert!(ask1(&mut inch, "POS").starts_with("OK PX=1000 PZ=0 "));
    assert_eq!(
        last(&mut inch, "G20 X3937.008"),
        "ERR VALUE X beyond 99999.999999 mm"
    );
}

#[test]
fn a_fanuc_program_moves_as_its_iso_equivalent() {
    let run = |dev: &mut Device, program: &[&str]| {
        for line in program {
            let r = ask(dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        }
        (ask1(dev, "SYNC"), ask1(dev, "POS"), ask1(dev, "AUX"))
    };
    let mut fanuc = Device::new();
    assert_eq!(
        ask1(&mut fanuc, "OPT DIALECT=fanuc"),
        "OK BDEL=0 DIALECT=FANUC OPTSTOP=0"
    );
    // 180 m/min at Ø30: 1909.8593171 rpm (at Ø40, where it ends, 1432.3945); 0.2 mm/rev of it is
    // 381.9718634 mm/min. The spindle and coolant switch at rest, the
    // dwell waits at rest: the same runs in both.
    let a = run(
        &mut fanuc,
        &[
            "%",
            "O1000 (SHAFT)",
            "N10 G21 G18 G99",
            "N20 T0101",
            "N30 G50 S2500",
            "N40 G00 X30. Z2.",
            "N50 G96 S180 M03",
            "N60 M08",
            "N70 G01 Z-40. F.2",
            "N80 U2. W-1.",
            "N90 G04 P500",
            "N100 G00 X40. Z5.",
        ],
    );
    assert_eq!(
        a.2,
        "OK SPINDLE=CW S=1432.3945 SMODE=CSS LIMIT=2500.0000 COOLANT=FLOOD T=0101 SMAX=0.0000 SPINUP=0.000"
    );
    let mut iso = Device::new();
    let b = run(
        &mut iso,
        &[
            "G21 G18 G94 T1",
            "G00 X30. Z2.",
            "S1909.8593171 M03",
            "M08",
            "G01 Z-40. F381.9718634",
            "X32. Z-41.",
            "G4 P.5",
            "G00 X40. Z5.",
        ],
    );
    assert_eq!((&a.0, &a.1), (&b.0, &b.1));
    // The end of the program stops the spindle and the coolant.
    assert!(ask1(&mut fanuc, "N110 M05 M09 M30").starts_with("OK NX=0 NZ=0 "));
    assert_eq!(
        ask1(&mut fanuc, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=2500.0000 COOLANT=OFF T=0101 SMAX=0.0000 SPINUP=0.000"
    );
}

#[test]
fn iso_modes_of_a_block_apply_to_its_own_words() {
    let mut dev = Device::new();
    // G8: X a radius from this block on, in its DATA line too.
    let r = ask(&mut dev, b"G8 G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    assert!(ask1(&mut dev, "CFG").contains(" DIAM=0 "));
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=2000 PZ=100 "));
    let r = ask(&mut dev, b"G7 X10\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=1000 PZ=100 "));
    // G90.1: I and K are the centre, both needed; G91.1 from the start.
    assert_eq!(
        ask1(&mut dev, "G90.1 G02 X10 Z-4 I5"),
        "ERR SYNTAX G90.1: an arc centre needs I and K"
    );
    let a = ask(&mut dev, b"G90.1 G02 X10 Z-4 I5 K-1.5 F100\n");
    let mut other = Device::new();
    ask(&mut other, b"G00 X10 Z1\n");
    let b = ask(&mut other, b"G02 X10 Z-4 I0 K-2.5 F100\n");
    assert_eq!(a, b);
}

#[test]
fn work_and_tool_offsets_move_the_machine_not_the_program() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    // X values are diameters (DIAM=1), held on the radius.
    assert_eq!(
        ask1(&mut dev, "TOOL N=1 X=2 Z=-3 WX=-0.02 WZ=0.01"),
        "OK N=1 X=2.0000 Z=-3.0000 WX=-0.0200 WZ=0.0100 R=- T=-"
    );
    assert_eq!(
        ask1(&mut dev, "WORK G=54 Z=-100"),
        "OK G=54 X=0.0000 Z=-100.0000"
    );
    let r = ask(&mut dev, b"G00 X20. Z5.\n");
    assert_eq!(r[0], "DATA G00 X20.0000 Z-95.0000");
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=2000 PZ=-9500 X=20.0000 Z=5.0000 MX=20.0000 MZ=-95.0000"
    );
    // T0101 moves nothing; the next move takes its offsets up.
    assert!(ask1(&mut dev, "T0101").starts_with("OK NX=0 NZ=0 "));
    let r = ask(&mut dev, b"G00 X20. Z5.\n");
    assert_eq!(r[0], "DATA G00 X21.9800 Z-97.9900");
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=2198 PZ=-9799 X=20.0000 Z=5.0000 MX=21.9800 MZ=-97.9900"
    );
    // G10 L2 sets G55; G10 L20 so that the tool stands at Z0 in G54.
    ask1(&mut dev, "G10 L2 P2 X0 Z-50.");
    assert_eq!(ask1(&mut dev, "WORK G=55"), "OK G=55 X=0.0000 Z=-50.0000");
    let r = ask(&mut dev, b"G55 G00 Z0\n");
    assert_eq!(r[0], "DATA G00 X21.9800 Z-52.9900");
    ask1(&mut dev, "G54 G10 L20 P1 Z0");
    assert_eq!(ask1(&mut dev, "WORK G=54"), "OK G=54 X=0.0000 Z=-50.0000");
    // An arc cannot take up an offset change; a line can.
    ask1(&mut dev, "T0100");
    assert_eq!(
        ask1(&mut dev, "G02 X24. Z-2. R2. F100"),
        "ERR GEOMETRY an arc cannot take up an offset change: move in a line first"
    );
    assert!(ask1(&mut dev, "T0133").starts_with("ERR VALUE T offset register beyond"));
    let bad = [
        ("G10 L2 P7 X0", "ERR VALUE P names G54 to G59: 1 to 6"),
        (
            "G10 L20 P0 Z0",
            "ERR VALUE P 0 is Fanuc's external offset, which this control has not: 1 to 6 (G54 to G59)",
        ),
        (
            "G10 L3 P1 X0",
            "ERR SYNTAX G10 needs L2 or L20 (a work offset)",
        ),
        ("G10 L2 P1 U1", "ERR SYNTAX G10 takes X and Z, not U and W"),
        ("L2", "ERR SYNTAX L only with G10"),
        ("TOOL N=33", "ERR VALUE N must be 1 to 32"),
        ("TOOL N=1 T=12", "ERR VALUE T must be 0 to 9"),
        ("WORK G=60", "ERR VALUE G must be 54 to 59"),
    ];
    let before = ask1(&mut dev, "POS");
    for (line, want) in bad {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert_eq!(ask1(&mut dev, "POS"), before);
}

/// ISO `G10 L2`/`L20 P0` (LinuxCNC, grbl): the work system in effect, once
/// the block's own `G54`–`G59` is taken; what grbl senders' "zero" buttons
/// send (`G10 P0 L20 X0`).
#[test]
fn g10_p0_sets_the_work_system_in_effect() {
    let mut dev = Device::new();
    let r = ask(&mut dev, b"G00 X20 Z-4\n");
    assert_eq!(r[0], "DATA G00 X20.0000 Z-4.0000");
    // In G54: Z0 here.
    ask1(&mut dev, "G10 P0 L20 Z0");
    assert_eq!(ask1(&mut dev, "WORK G=54"), "OK G=54 X=0.0000 Z=-4.0000");
    // G56 taken first in the same block, then set: X10 here.
    ask1(&mut dev, "G56 G10 L20 P0 X10");
    assert_eq!(ask1(&mut dev, "WORK G=56"), "OK G=56 X=10.0000 Z=0.0000");
    assert_eq!(ask1(&mut dev, "WORK G=54"), "OK G=54 X=0.0000 Z=-4.0000");
    assert!(ask1(&mut dev, "POS").contains(" X=10.0000 Z=-4.0000"));
    // L2 P0: to the values, in G56 still.
    ask1(&mut dev, "G10 L2 P0 Z-7.5");
    assert_eq!(ask1(&mut dev, "WORK G=56"), "OK G=56 X=10.0000 Z=-7.5000");
}

/// ISO `G10 L1`/`L10` (LinuxCNC): a tool's geometry set to the block's
/// values, or so that the point here reads them with that tool's offset in
/// effect (a tool setter's touch-off in a program, after a `G38.2`); the
/// machine stays where it is. X is a diameter as the block reads it.
#[test]
fn g10_l1_and_l10_set_a_tools_geometry() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "G10 L1 P3 X4 Z-2").starts_with("OK"));
    let t3 = ask1(&mut dev, "TOOL N=3");
    assert!(t3.starts_with("OK N=3 X=4.0000 Z=-2.0000 "), "{t3}");
    ask(&mut dev, b"G00 X20 Z-4\n");
    assert!(ask1(&mut dev, "TOOL N=3 WZ=0.5").starts_with("OK"));
    ask(&mut dev, b"T3 M06 G43\n");
    // Z0 here with tool 3: its geometry is what is left, less its wear.
    assert!(ask1(&mut dev, "G10 L10 P3 Z0").starts_with("OK"));
    let t3 = ask1(&mut dev, "TOOL N=3");
    assert!(t3.starts_with("OK N=3 X=4.0000 Z=-4.5000 "), "{t3}");
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=2000 PZ=-400 X=16.0000 Z=0.0000 MX=20.0000 MZ=-4.0000"
    );
    // X30 (a diameter) here: the geometry is −10 on the diameter.
    assert!(ask1(&mut dev, "G10 L10 P3 X30").starts_with("OK"));
    assert!(ask1(&mut dev, "TOOL N=3").starts_with("OK N=3 X=-10.0000 Z=-4.5000 "));
    assert!(ask1(&mut dev, "POS").contains(" X=30.0000 Z=0.0000 MX=20.0000 MZ=-4.0000"));
    let before = ask1(&mut dev, "TOOL N=3");
    for (line, want) in [
        (
            "G10 L1 P33 X0",
            "ERR VALUE P names a tool's register: 1 to 32",
        ),
        ("G10 L10 X0", "ERR SYNTAX G10 L1 and L10 need P"),
        ("G10 L10 P3 R1 Z0", "ERR SYNTAX G10 L1 and L10 take X and Z"),
        (
            "G10 L3 P1 X0",
            "ERR SYNTAX G10 needs L2 or L20 (a work offset), L1 or L10 (a tool's)",
        ),
    ] {
        let r = ask1(&mut dev, line);
        assert!(r.starts_with(want), "{line}: {r}");
    }
    assert_eq!(ask1(&mut dev, "TOOL N=3"), before);
    // Fanuc's G10 sets its tool offsets otherwise: L1/L10 are refused.
    ask1(&mut dev, "OPT DIALECT=FANUC");
    assert_eq!(
        ask1(&mut dev, "G10 L1 P1 X0"),
        "ERR SYNTAX G10 needs L2 or L20 (a work offset)"
    );
}

/// Safety: an axis a block does not name never moves, whatever changed
/// the offsets before it (a work system set or selected, G92 and its kin,
/// a tool's offset), in both dialects; a named axis takes the new offset up.
#[test]
fn an_axis_the_block_does_not_name_never_moves() {
    for dialect in ["ISO", "FANUC"] {
        let mut dev = Device::new();
        ask1(&mut dev, &std::format!("OPT DIALECT={dialect}"));
        ask1(&mut dev, "TOOL N=1 X=2 Z=-3");
        // X 10 on the diameter, Z −5; then G54 moves by X4 (diameter) Z−2.
        ask(&mut dev, b"G00 X10 Z-5\n");
        ask1(&mut dev, "G10 L2 P1 X4 Z-2");
        let r = ask(&mut dev, b"G00 Z-6\n");
        assert_eq!(data_end(&r), "DATA G00 X10.0000 Z-8.0000", "{dialect}");
        // Selected anew: G55 is zero.
        ask(&mut dev, b"G55\n");
        let r = ask(&mut dev, b"G00 Z-3\n");
        assert_eq!(data_end(&r), "DATA G00 X10.0000 Z-3.0000", "{dialect}");
        // Set so that the tool stands at X20: X stays, then moves when named.
        ask1(&mut dev, "G10 L20 P2 X20");
        let r = ask(&mut dev, b"G01 Z-4 F100\n");
        assert_eq!(data_end(&r), "DATA G01 X10.0000 Z-4.0000", "{dialect}");
        let r = ask(&mut dev, b"G01 X18\n");
        assert_eq!(data_end(&r), "DATA G01 X8.0000 Z-4.0000", "{dialect}");
        // A tool's offset: X stays on a Z move, is taken up by an X move.
        let tool = if dialect == "ISO" {
            "T1 M06 G43"
        } else {
            "T0101"
        };
        ask(&mut dev, std::format!("{tool}\n").as_bytes());
        let r = ask(&mut dev, b"G00 Z-1\n");
        assert_eq!(data_end(&r), "DATA G00 X8.0000 Z-4.0000", "{dialect}");
        let r = ask(&mut dev, b"G00 X18\n");
        assert_eq!(data_end(&r), "DATA G00 X10.0000 Z-4.0000", "{dialect}");
        // G92 (Fanuc G50): the point here named anew, nothing moves; then
        // an incremental move goes from where the tool is.
        let shift = if dialect == "ISO" {
            "G92 X0 Z0"
        } else {
            "G50 X0 Z0"
        };
        let r = ask(&mut dev, std::format!("{shift}\n").as_bytes());
        assert!(r[0].starts_with("OK NX=0 NZ=0 "), "{dialect}: {r:?}");
        let inc = if dialect == "ISO" {
            "G91 G01 Z-2"
        } else {
            "G01 W-2"
        };
        let r = ask(&mut dev, std::format!("{inc}\n").as_bytes());
        assert_eq!(data_end(&r), "DATA G01 X10.0000 Z-6.0000", "{dialect}");
    }
}

#[test]
fn iso_tools_change_with_m6_and_offset_with_g43() {
    let mut dev = Device::new();
    ask1(&mut dev, "TOOL N=2 X=1 Z=0.5");
    assert_eq!(ask1(&mut dev, "M6"), "ERR SYNTAX M06 needs the tool: T");
    ask1(&mut dev, "T2 M6");
    // Without G43 the tool's offsets are not in effect (LinuxCNC's way).
    let r = ask(&mut dev, b"G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    ask1(&mut dev, "G43");
    let r = ask(&mut dev, b"G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X11.0000 Z1.5000");
    ask1(&mut dev, "G49");
    let r = ask(&mut dev, b"G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    assert_eq!(ask1(&mut dev, "H2"), "ERR SYNTAX H only with G43");
    assert!(ask1(&mut dev, "G43 H40").starts_with("ERR VALUE H offset register beyond"));
}

#[test]
fn what_a_board_keeps_in_flash_counts_its_changes() {
    let mut dev = Device::new();
    let g = |dev: &Device| dev.session().offsets_generation();
    let mut last = g(&dev);
    for (line, changes) in [
        ("TOOL N=3", false),
        ("TOOL N=3 X=1.5 R=0.4 T=2", true),
        ("TOOL N=3 X=1.5", false),
        ("WORK G=56 Z=-20", true),
        ("G10 L2 P2 X4", true),
        ("G55 G00 X10 Z2", false),
        ("G92 X0", false),
        ("G92.1", false),
        ("G28.1", true),
        ("G28.1", false),
        ("G00 X20", false),
        ("G30.1", true),
    ] {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        assert_eq!(g(&dev) != last, changes, "{line}");
        last = g(&dev);
    }
    // At power-on a board puts them back.
    let kept = *dev.session().offsets();
    let mut fresh = Device::new();
    let before = ask1(&mut fresh, "TOOL N=3");
    fresh.restore_offsets(kept);
    assert_ne!(ask1(&mut fresh, "TOOL N=3"), before);
    assert_eq!(ask1(&mut fresh, "TOOL N=3"), ask1(&mut dev, "TOOL N=3"));
    assert_eq!(ask1(&mut fresh, "WORK G=55"), ask1(&mut dev, "WORK G=55"));
}

#[test]
fn g45_to_g48_lengthen_and_shorten_the_move_by_an_offset_register() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    // X on the diameter: 1 mm is 0.5 on the radius.
    ask1(&mut dev, "TOOL N=5 X=1 Z=0.15 WZ=0.05");
    let last =
        |dev: &mut Device, line: &str| ask(dev, std::format!("{line}\n").as_bytes()).pop().unwrap();
    assert!(last(&mut dev, "G01 F100 W0").starts_with("OK"));
    let nz = |dev: &mut Device, line: &str| -> String {
        let r = ask(dev, std::format!("{line}\n").as_bytes());
        let last = r.last().unwrap().clone();
        last.split(' ').take(3).collect::<Vec<_>>().join(" ")
    };
    // Z's offset is geometry plus wear: 0.2 mm, 20 impulses of 0.01.
    for (line, want) in [
        ("G45 W-10. D5", "OK NX=0 NZ=-1020"),
        ("G46 W-10. D5", "OK NX=0 NZ=-980"),
        ("G47 W-10. D5", "OK NX=0 NZ=-1040"),
        ("G48 W-10. D5", "OK NX=0 NZ=-960"),
        // A move of zero goes the offset's way.
        ("G45 W0 D5", "OK NX=0 NZ=20"),
        ("G46 W0 D5", "OK NX=0 NZ=-20"),
        // U10 is 5 on the radius, with 0.5: 5.5, 1100 impulses of 0.005.
        ("G45 U10. D5", "OK NX=1100 NZ=0"),
        // Absolute words: the move from where the tool is.
        ("G46 X0 D5", "OK NX=-1000 NZ=0"),
        // One block only: the next move is as written.
        ("W-1.", "OK NX=0 NZ=-100"),
    ] {
        assert_eq!(nz(&mut dev, line), want, "{line}");
    }
    let before = state(&mut dev);
    for (line, why) in [
        (
            "G45 W-1.",
            "ERR SYNTAX G45 to G48 need D: the offset register",
        ),
        (
            "G45 W1. D33",
            "ERR SYNTAX D (the offset register) must be 1 to 32",
        ),
        (
            "G45 W1. D1.5",
            "ERR SYNTAX D (the offset register) must be 1 to 32",
        ),
        (
            "G45 D5",
            "ERR SYNTAX G45 to G48 need X or Z (U or W): the move",
        ),
        (
            "G45 W1. K1. D5",
            "ERR SYNTAX G45 to G48 move in a line: X and Z (U and W)",
        ),
        (
            "G45 G02 W1. D5",
            "ERR SYNTAX G45 to G48 move in a line: G00 or G01",
        ),
        ("G45 G28 W1. D5", "ERR SYNTAX address given twice: G"),
        ("G01 W1. D5", "ERR SYNTAX unknown address D"),
        ("G45 G41 W1. D5", "ERR"),
    ] {
        let got = last(&mut dev, line);
        assert!(got.starts_with(why), "{line}: {got}");
    }
    assert_eq!(state(&mut dev), before);
    // ISO: D is also G96's limit; with G45 it names the register.
    let mut iso = Device::new();
    ask1(&mut iso, "TOOL N=2 Z=-0.3");
    assert!(last(&mut iso, "G91 G00 Z0").starts_with("OK"));
    assert_eq!(nz(&mut iso, "G45 Z-5 D2"), "OK NX=0 NZ=-470");
    assert!(last(&mut iso, "G01 Z1 D2").starts_with(
        "ERR SYNTAX D only with G41/G42 (the tool), G96 (the spindle speed limit) or G45 to G48 (the offset register)"
    ));
}

//! Nose radius compensation through the protocol: contours, refusals that
//! name the block, corner modes, the nose of the tool in effect.

use super::*;

#[test]
fn krylenko_fig_22_from_a_g42_contour() {
    let mut dev = Device::new();
    let r = run_program(
        &mut dev,
        &[
            "G00 X0 Z5",
            "N1 G42 G01 Z0 F100",
            "N2 X8",
            "N3 G03 X12 Z-2 R2",
            "N4 G01 Z-14",
            "N5 G02 X18 Z-17 R3",
            "N6 G01 X30",
            "N7 G03 X38 Z-21 R4",
            "N8 G01 Z-30",
            "N9 G40 X45",
        ],
    );
    assert!(
        r.iter().all(|l| l.last().unwrap().starts_with("OK")),
        "{r:?}"
    );
    // The start-up block is sent with the block after it.
    assert_eq!(r[1].len(), 1);
    assert_eq!(
        data(&r),
        [
            "G00 X0.0000 Z5.0000",
            "G01 X-0.8000 Z0.0000",
            "G01 X7.2000 Z0.0000",
            "G03 X12.0000 Z-2.4000 I0.0000 K-2.4000",
            "G01 X12.0000 Z-14.4000",
            "G02 X17.2000 Z-17.0000 I2.6000 K0.0000",
            "G01 X29.2000 Z-17.0000",
            "G03 X38.0000 Z-21.4000 I0.0000 K-4.4000",
            "G01 X38.0000 Z-30.4000",
            "G01 X45.0000 Z-30.0000",
        ]
    );
    // After G40 the tool tip is at the programmed point again.
    assert!(ask1(&mut dev, "POS").ends_with("X=45.0000 Z=-30.0000"));
}

#[test]
fn compensation_refusals_name_the_block_and_change_nothing() {
    let prefix = ["CFG RN=0.8", "G00 X20 Z5", "G42 G01 Z0 F100", "N10 X40"];
    // (bad block, expected error, a good block to send after it)
    let cases: &[(&[&str], &str, &str, &str)] = &[
        // A concave arc of radius 0.5 with a 0.8 nose.
        (
            &[],
            "N20 G02 X41 Z-0.5 R0.5",
            "ERR GEOMETRY N20: concave",
            "N20 G01 Z-10",
        ),
        // Compensation switched off in an arc block.
        (
            &[],
            "N20 G40 G03 X44 Z-2 R2",
            "ERR GEOMETRY N20: compensation switched off",
            "N20 G01 Z-10",
        ),
        // Sides change only through G40.
        (
            &[],
            "N20 G41 G01 Z-10",
            "ERR GEOMETRY N20: change between G41 and G42",
            "N20 G01 Z-10",
        ),
        // A 0.2 mm chamfer between two inside corners, too short for the nose.
        (
            &["N20 G01 Z-10", "N30 X40.4 Z-10.2"],
            "N40 X60",
            "ERR GEOMETRY N30 too short for the nose radius: it reverses at its corner with N40",
            "N40 X42 Z-11",
        ),
        // An arc whose end is not on its circle.
        (
            &[],
            "N20 G03 X44 Z-2 I0 K-2.5",
            "ERR GEOMETRY start and end radii",
            "N20 G01 Z-10",
        ),
        // MOVE, ARC, ZERO and a new nose radius wait for G40.
        (
            &[],
            "MOVE X=1",
            "ERR GEOMETRY MOVE not allowed",
            "N20 G01 Z-10",
        ),
        (&[], "ZERO", "ERR GEOMETRY ZERO not allowed", "N20 G01 Z-10"),
        (
            &[],
            "CFG RN=0.4",
            "ERR GEOMETRY CFG RN or TIP not allowed",
            "N20 G01 Z-10",
        ),
    ];
    for &(more, bad, expected, good) in cases {
        let mut with = Device::new();
        let mut without = Device::new();
        for b in prefix.iter().chain(more) {
            for dev in [&mut with, &mut without] {
                assert!(
                    ask(dev, std::format!("{b}\n").as_bytes())
                        .last()
                        .unwrap()
                        .starts_with("OK"),
                    "{b}"
                );
            }
        }
        let r = ask(&mut with, std::format!("{bad}\n").as_bytes());
        assert_eq!(r.len(), 1, "{bad}: {r:?}");
        assert!(r[0].starts_with(expected), "{bad}: {r:?}");
        let after = [good, "N90 G01 X70", "N99 G40 X80 Z10"];
        assert_eq!(
            run_program(&mut with, &after),
            run_program(&mut without, &after),
            "{bad}"
        );
    }
}

#[test]
fn compensation_on_in_an_arc_block_is_refused() {
    let mut dev = Device::new();
    assert_eq!(ask(&mut dev, b"G00 X20 Z5\n").len(), 2);
    let r = ask(&mut dev, b"N5 G42 G03 X24 Z3 R2\n");
    assert_eq!(
        r,
        ["ERR GEOMETRY N5: compensation switched on in an arc block"]
    );
    // A G42 block without motion arms it; the next motion is the start-up.
    assert_eq!(ask(&mut dev, b"G42\n").len(), 1);
    let r = ask(&mut dev, b"N6 G03 X24 Z3 R2\n");
    assert_eq!(
        r,
        ["ERR GEOMETRY N6: compensation switched on in an arc block"]
    );
}

#[test]
fn corner_modes_and_tip_codes() {
    // An outside 90° corner (G42 along the face, then down the cylinder):
    // G451 squares it at the intersection, G450 rounds it with the nose radius.
    let program = |corner: &str, tip: &str| {
        let mut dev = Device::new();
        let setup = std::format!("CFG DIAM=0 TIP={tip}");
        let lines = [
            "G00 X20 Z5",
            corner,
            "G41 G01 X10 F100",
            "X10 Z-10",
            "X20",
            "G40 X30 Z-20",
        ];
        assert!(ask1(&mut dev, &setup).starts_with("OK"));
        data(&run_program(&mut dev, &lines))
    };
    let int = program("G451", "9");
    let arc = program("G450", "9");
    assert_eq!(int.len() + 1, arc.len(), "{int:?} {arc:?}");
    assert!(
        arc.iter()
            .any(|l| l.starts_with("G02") || l.starts_with("G03")),
        "{arc:?}"
    );
    // The tip code shifts every compensated point by the same vector.
    let shifted = program("G451", "1");
    assert_eq!(int.len(), shifted.len());
    let xz = |l: &str| -> (f64, f64) {
        let w: Vec<&str> = l.split(' ').collect();
        (w[1][1..].parse().unwrap(), w[2][1..].parse().unwrap())
    };
    for (a, b) in int.iter().zip(&shifted).skip(1).take(3) {
        let (p, q) = (xz(a), xz(b));
        assert!(
            (q.0 - p.0 - 0.4).abs() < 1e-9 && (q.1 - p.1 - 0.4).abs() < 1e-9,
            "{a} / {b}"
        );
    }
}

#[test]
fn reset_abandons_a_contour_whose_corner_cannot_be_cut() {
    let mut dev = Device::new();
    let program = [
        "CFG RN=0.8",
        "G00 X20 Z5",
        "G42 G01 Z0 F100",
        "N10 X40",
        "N20 Z-10",
        "N30 X40.4 Z-10.2",
    ];
    for b in program {
        assert!(
            ask(&mut dev, std::format!("{b}\n").as_bytes())
                .last()
                .unwrap()
                .starts_with("OK"),
            "{b}"
        );
    }
    // The chamfer is too short for the nose whatever comes next, G40 included.
    assert!(ask1(&mut dev, "N40 X60").starts_with("ERR GEOMETRY N30 too short"));
    assert!(ask1(&mut dev, "G40").starts_with("ERR GEOMETRY N30 too short"));
    assert!(ask1(&mut dev, "MOVE X=50").starts_with("ERR GEOMETRY MOVE not allowed"));
    let pos = ask1(&mut dev, "POS");
    assert_eq!(ask1(&mut dev, "RESET"), "OK");
    assert_eq!(ask1(&mut dev, "POS"), pos, "RESET moves nothing");
    assert!(ask1(&mut dev, "RESET 1").starts_with("ERR SYNTAX"));
    // Compensation is off: blocks run as written from where the tool is.
    let z = pos.rsplit_once(" Z=").unwrap().1;
    let r = ask(&mut dev, b"G01 X50\n");
    assert_eq!(r[0], std::format!("DATA G01 X50.0000 Z{z}"), "{r:?}");
    assert!(ask1(&mut dev, "MOVE X=50").starts_with("OK"));
}

#[test]
fn compensation_takes_the_nose_of_the_tool_in_effect() {
    let contour = [
        "G00 X20 Z5",
        "G42 G01 Z0 F100",
        "X28",
        "X48 Z-10",
        "Z-46",
        "G40 G00 X60",
    ];
    let data = |setup: &[&str], dialect: &str| {
        let mut dev = Device::new();
        ask1(&mut dev, &std::format!("OPT DIALECT={dialect}"));
        for l in setup {
            assert!(ask1(&mut dev, l).starts_with("OK"), "{l}");
        }
        let mut out = Vec::new();
        for l in contour {
            out.extend(ask(&mut dev, std::format!("{l}\n").as_bytes()));
        }
        out
    };
    let configured = data(&["CFG RN=0.8 TIP=2"], "ISO");
    let fanuc = data(&["TOOL N=5 R=0.8 T=2", "T0505"], "FANUC");
    let iso = data(&["TOOL N=5 R=0.8 T=2", "T5 M6"], "ISO");
    assert_eq!(fanuc, configured);
    assert_eq!(iso, configured);
    assert_ne!(data(&[], "ISO"), configured);
    // Offsets cannot change under compensation.
    let mut dev = Device::new();
    ask(&mut dev, b"G00 X20 Z5\nG42 G01 Z0 F100\n");
    assert_eq!(
        ask1(&mut dev, "G55 X28"),
        "ERR GEOMETRY a work or tool offset change not allowed while G41/G42 is on; cancel with G40 first"
    );
}

/// LinuxCNC's G41.1/G42.1: the nose in the block, its orientation mirrored
/// into the device's tip code; the same path as the table's nose.
#[test]
fn dynamic_compensation_takes_the_nose_from_the_block() {
    let contour = |setup: &str, on: &str| {
        let mut dev = Device::new();
        assert!(ask1(&mut dev, setup).starts_with("OK"));
        let mut out = Vec::new();
        for l in [
            "G00 X20 Z5",
            on,
            "X28",
            "X48 Z-10",
            "Z-30",
            "G40 G00 X60 Z5",
        ] {
            let r = ask(&mut dev, std::format!("{l}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{l}: {r:?}");
            out.extend(r);
        }
        out
    };
    let table = contour("CFG RN=0.4 TIP=3", "G42 G01 Z0 F100");
    let dynamic = contour("CFG RN=0 TIP=0", "G42.1 D0.8 L2 G01 Z0 F100");
    assert_eq!(table, dynamic);
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "G42.1 L2 G01 Z0 F100")
        .starts_with("ERR SYNTAX G41.1 and G42.1 need D: the nose diameter"));
}

/// Fanuc's and Haas' `,C` and `,R`: the move waits for the next one; what
/// cannot follow it is refused with nothing moved, and the next move sends
/// the first cut short, the chamfer, and itself.
#[test]
fn a_corner_waits_for_its_next_move_and_refusals_change_nothing() {
    let next = "ERR GEOMETRY N20: the ,C/,R of N10 needs a G01-G03 move next, no G40-G42";
    let mut dev = super::cycles::refusals_change_nothing(
        "N10 G01 X20. Z0 F100. ,C2.",
        &[
            ("N20 M05", next),
            ("N20 G00 Z-10.", next),
            ("N20 G90 X30. Z-20.", next),
            ("N20 G42 G01 Z-10.", next),
            ("N20 G04 P100", next),
            ("N20 M30", next),
            (
                "N20 G01 X10.",
                "ERR GEOMETRY N10 and N20 meet without a corner to chamfer or round",
            ),
            (
                "N20 G01 Z-1.",
                "ERR GEOMETRY the ,C/,R of N10 does not fit between it and N20",
            ),
            (
                "N20 G02 X30. Z-5. I5. K0",
                "ERR GEOMETRY a ,C joins two lines: N10 or N20 is an arc (,R rounds it)",
            ),
        ],
    );
    // A line of only a sequence number or a comment passes, the corner
    // still waiting (grbl senders send `N20` apart from its words).
    assert!(ask1(&mut dev, "N15").starts_with("OK NX=0 NZ=0 "));
    assert!(ask1(&mut dev, "(FINISH)").starts_with("OK NX=0 NZ=0 "));
    // The first line cut 2 mm short (X16 on the diameter), the chamfer,
    // the next line from its end; the waiting block's two at its feed.
    let r = ask(&mut dev, b"N20 G01 Z-10.\n");
    assert_eq!(
        r[..3],
        [
            "DATA G01 X16.0000 Z0.0000",
            "DATA G01 X20.0000 Z-2.0000",
            "DATA G01 X20.0000 Z-10.0000"
        ]
    );
    assert!(r[3].starts_with("OK NX=2000 NZ=-1000 "), "{r:?}");
    let origins: std::vec::Vec<_> = dev
        .session()
        .last_moves()
        .iter()
        .map(|m| m.origin)
        .collect();
    assert_eq!(
        origins,
        [
            crate::comp::Origin::Waiting,
            crate::comp::Origin::Waiting,
            crate::comp::Origin::Current
        ]
    );
}

/// Fanuc's and Haas' right-angle corner on a `G01` along one axis:
/// `Z… I±i` and `X… K±k` chamfer, `Z… R±r` and `X… R±r` round, exactly as
/// `,C` and `,R` of the same size; the next move must go along the other
/// axis alone the way of the word's sign, else it is refused with nothing
/// moved and the corner waits on; other forms are refused by name.
#[test]
fn a_right_angles_chamfer_and_round_are_i_k_and_r_on_a_one_axis_g01() {
    let head = ["G21 G18 G98", "G00 X20. Z2."];
    for (square, comma, next) in [
        ("G01 Z-10. I2. F100.", "G01 Z-10. F100. ,C2.", "X30."),
        ("G01 Z-10. I-1.5 F100.", "G01 Z-10. F100. ,C1.5", "X10."),
        ("G01 X30. K-1. F100.", "G01 X30. F100. ,C1.", "Z-8."),
        ("G01 X30. K2. F100.", "G01 X30. F100. ,C2.", "Z8."),
        ("G01 Z-10. R3. F100.", "G01 Z-10. F100. ,R3.", "X30."),
        ("G01 X30. R-2. F100.", "G01 X30. F100. ,R2.", "Z-8."),
        ("G01 W-12. R-1. F100.", "G01 W-12. F100. ,R1.", "U-6."),
    ] {
        let run = |corner: &str| {
            let mut program = std::vec::Vec::from(head);
            program.extend([corner, next]);
            let (mut dev, r) = fanuc_program(&program);
            (data(&r), ask1(&mut dev, "POS"))
        };
        let (a, a_pos) = run(square);
        let (b, b_pos) = run(comma);
        assert_eq!(a, b, "{square}");
        assert_eq!(a.len(), 4, "{a:?}");
        assert_eq!(a_pos, b_pos);
    }
    // The next move the other way, along both axes, along the same axis,
    // an arc, or a rapid: refused, nothing moved; then the right one runs.
    let wrong = "ERR GEOMETRY N20: after the I, K or R of N10 (a right angle's chamfer or round), a G01 along the other axis alone, the way of the word's sign";
    let mut dev = super::cycles::refusals_change_nothing(
        "N10 G01 Z-10. I2. F100.",
        &[
            ("N20 X-10.", wrong),
            ("N20 X30. Z-12.", wrong),
            ("N20 Z-20.", wrong),
            ("N20 G02 X10. Z-15. R5.", wrong),
            (
                "N20 G00 X30.",
                "ERR GEOMETRY N20: the ,C/,R of N10 needs a G01-G03 move next, no G40-G42",
            ),
        ],
    );
    let r = ask(&mut dev, b"N20 X30.\n");
    assert_eq!(
        r[..3],
        [
            "DATA G01 X0.0000 Z-8.0000",
            "DATA G01 X4.0000 Z-10.0000",
            "DATA G01 X30.0000 Z-10.0000"
        ],
        "{r:?}"
    );
    // Forms refused by name, nothing moved.
    let form = "ERR SYNTAX a right angle's chamfer or round: G01 Z with I or R, G01 X with K or R, one word";
    let _ = super::cycles::refusals_change_nothing(
        "G21 G18 G98",
        &[
            ("G01 X30. Z-12. I1. F100.", form),
            ("G01 X30. I1. F100.", form),
            ("G01 Z-12. K1. F100.", form),
            ("G01 Z-12. I1. K1. F100.", form),
            ("G01 Z-12. I1. R1. F100.", form),
            (
                "G01 Z-12. R0 F100.",
                "ERR VALUE R a chamfer or round above 0",
            ),
            ("G00 Z-12. I1.", "ERR SYNTAX I, K and R need G02 or G03"),
            (
                "G01 Z-12. I1. F100. ,C1.",
                "ERR SYNTAX one corner a block: ,C or ,R, or I, K or R",
            ),
        ],
    );
    // The ISO dialect has no such corner.
    let mut dev = Device::new();
    assert!(
        ask1(&mut dev, "G01 Z-12. I1. F100.").starts_with("ERR SYNTAX I, K and R need G02 or G03")
    );
}

/// Fanuc's retract `G00 G40 X… Z… T0`: the block that ends compensation
/// takes up the new tool offset on its own move, the lead-out; the element
/// it finishes and its corner keep the offset and the nose they were
/// compensated with. Any other offset change under compensation, and a
/// work system change even in the `G40` block, is still refused.
#[test]
fn the_block_that_ends_compensation_takes_up_a_new_tool_offset() {
    let run = |last: &[&str]| {
        let mut program = std::vec![
            "TOOL N=1 X=-20 Z=5 R=0.8 T=3",
            "TOOL N=2 X=-10 Z=2",
            "G21 G18 G98 T0101",
            "G00 X50. Z5.",
            "G42 G01 X20. Z0 F100.",
            "Z-30.",
            "X44.",
        ];
        program.extend_from_slice(last);
        let (mut dev, r) = fanuc_program(&program);
        (data(&r), ask1(&mut dev, "POS"))
    };
    let (kept, kept_pos) = run(&["G00 G40 X60. Z10."]);
    let (changed, changed_pos) = run(&["G00 G40 X60. Z10. T0202"]);
    let (cancelled, _) = run(&["G00 G40 X60. Z10. T0"]);
    // Up to the lead-out, the same moves: the old offset and nose.
    let n = kept.len();
    assert_eq!(changed.len(), n);
    assert_eq!(changed[..n - 1], kept[..n - 1]);
    assert_eq!(cancelled[..n - 1], kept[..n - 1]);
    // The lead-out ends at X60 Z10 plus each offset in effect: tool 1's
    // (-20, 5) as before, tool 2's (-10, 2), none after T0 (X on the
    // diameter, in TOOL and in the DATA lines).
    assert_eq!(kept[n - 1], "G00 X40.0000 Z15.0000");
    assert_eq!(changed[n - 1], "G00 X50.0000 Z12.0000");
    assert_eq!(cancelled[n - 1], "G00 X60.0000 Z10.0000");
    assert_ne!(kept_pos, changed_pos);
    // An axis the block leaves out keeps the old offset (Z: the programmed
    // Z-30 plus tool 1's 5) until a block names it.
    let (x_only, pos) = run(&["G00 G40 X60. T0202", "G00 Z10."]);
    assert_eq!(x_only[..n - 1], kept[..n - 1]);
    assert_eq!(x_only[n - 1], "G00 X50.0000 Z-25.0000");
    assert_eq!(x_only[n], "G00 X50.0000 Z12.0000");
    assert!(pos.contains(" X=60.0000 Z=10.0000"), "{pos}");
    // Still refused, and nothing moves: an offset change while the contour
    // goes on, and a work system change in the G40 block.
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    for line in [
        "TOOL N=1 X=-20 Z=5 R=0.8 T=3",
        "G21 G18 G98 T0101",
        "G00 X50. Z5.",
        "G42 G01 X20. Z0 F100.",
        "Z-30.",
    ] {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
    }
    let pos = ask1(&mut dev, "POS");
    for line in ["X44. T0202", "G00 G40 G55 X60. Z10."] {
        let r = ask1(&mut dev, line);
        assert!(
            r.starts_with("ERR") && r.contains("offset change"),
            "{line}: {r}"
        );
        assert_eq!(ask1(&mut dev, "POS"), pos);
    }
}

//! The turning cycles through the protocol: G90/G94, G71/G72 with G70,
//! G74/G75, and the refusals that come before their motion.

use super::*;

/// `G90` and `G94` of G-code system A (Fanuc dialect) move as the blocks
/// a programmer writes for them by hand: in at the rapid rate (to the
/// taper's start, X + 2R on the diameter), the cut, out at the feed, back
/// to the start at the rapid rate; X, Z and R modal, the cycle repeated by
/// an axis word alone until a motion code ends it.
#[test]
fn single_cycles_move_as_their_blocks_written_out() {
    let run = |program: &[&str]| {
        let mut dev = Device::new();
        assert_eq!(
            ask1(&mut dev, "OPT DIALECT=fanuc"),
            "OK BDEL=0 DIALECT=FANUC OPTSTOP=0"
        );
        let mut trace = Vec::new();
        for line in program {
            let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
            trace.push(r.last().unwrap().clone());
        }
        (ask1(&mut dev, "SYNC"), ask1(&mut dev, "POS"), trace)
    };
    let (sync, pos, trace) = run(&[
        "G21 G18 G98 G90",
        "G00 X50. Z5.",
        "G90 X40. W-25. F200.",
        "X35.",
        "Z-30. R-1.",
        "G94 X20. Z0 F100.",
        "Z-1.",
        "G00 X60.",
        "X70. Z10.",
        // G80 ends a cycle as a motion code does.
        "G90 X40. Z-5. F200.",
        "G80",
        "X50.",
    ]);
    let (sync_by_hand, pos_by_hand, _) = run(&[
        "G21 G18 G98",
        "G00 X50. Z5.",
        "G00 X40.",
        "G01 Z-20. F200.",
        "X50.",
        "G00 Z5.",
        "X35.",
        "G01 Z-20.",
        "X50.",
        "G00 Z5.",
        "X33.",
        "G01 X35. Z-30.",
        "X50.",
        "G00 Z5.",
        "Z0",
        "G01 X20. F100.",
        "Z5.",
        "G00 X50.",
        "Z-1.",
        "G01 X20.",
        "Z5.",
        "G00 X50.",
        "X60.",
        "X70. Z10.",
        "X40.",
        "G01 Z-5. F200.",
        "X70.",
        "G00 Z10.",
        "G80",
        "G00 X50.",
    ]);
    assert_eq!(pos, pos_by_hand);
    assert_eq!(sync, sync_by_hand);
    // A header's G90 selects the cycle without moving; the cycle blocks
    // move and come back to where they started.
    assert!(trace[0].starts_with("OK NX=0 NZ=0"), "{}", trace[0]);
    assert!(trace[2].starts_with("OK NX=0 NZ=0"), "{}", trace[2]);
}

/// A Fanuc-dialect device at `start`: each `(line, reply)` refused as
/// written, with no step event since and the position as before it.
pub(super) fn refusals_change_nothing(start: &str, cases: &[(&str, &str)]) -> Device {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    for line in ["G21 G18 G98", start] {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{r:?}");
    }
    ask1(&mut dev, "SYNC");
    let before = ask1(&mut dev, "POS");
    for &(line, want) in cases {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
        // No event since: the SYNC since the last one is empty.
        assert!(ask1(&mut dev, "SYNC").starts_with("OK EV=0 "), "{line}");
        assert_eq!(ask1(&mut dev, "POS"), before, "{line}");
    }
    dev
}

/// What a single cycle cannot take is refused before anything moves.
#[test]
fn single_cycle_refusals_change_nothing() {
    refusals_change_nothing(
        "G00 X50. Z5.",
        &[
        (
            "G90 G01 X40. Z-20. F100.",
            "ERR SYNTAX G90/G94 and a motion code in one block: one of them",
        ),
        (
            "G90 X40. Z-20. F100. M08",
            "ERR SYNTAX a G90/G94 block takes X (U), Z (W), R and F: put other words on their own line",
        ),
        ("G90 X40. Z-20.", "ERR VALUE F not programmed: a feed move needs F (mm/min)"),
        ],
    );
}

/// Fanuc's two-block `G71` roughs a stepped shaft as the manual draws it:
/// passes U deep (on the radius) from the start point, each cut to the
/// profile moved out by the allowances (U on the diameter, W along Z),
/// pulled off at 45° by R, back to the start's Z at the rapid rate; then
/// one pass along the moved profile and back to the start point. `G70`
/// then runs the profile's own blocks and returns, X first.
#[test]
fn g71_roughs_in_passes_and_g70_finishes_on_the_profile() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    let r = run_program(
        &mut dev,
        &[
            "G21 G18 G98",
            "G00 X40. Z2.",
            "G71 U2. R.5",
            "G71 P10 Q30 U.4 W.2 F300.",
            "N10 G00 X20.",
            "N20 G01 Z-30. F100.",
            "N30 X40.",
            "G70 P10 Q30",
        ],
    );
    for reply in &r {
        assert!(reply.last().unwrap().starts_with("OK"), "{reply:?}");
    }
    // The profile's blocks are held, not run, until Q.
    assert!(r[4].last().unwrap().ends_with("HELD=1"), "{:?}", r[4]);
    assert!(r[5].last().unwrap().ends_with("HELD=2"), "{:?}", r[5]);
    let mut want = std::vec!["G00 X40.0000 Z2.0000".to_string()];
    // Radii 18, 16, 14, 12: each to the shoulder at Z-30 + W.
    for x in [36, 32, 28, 24] {
        want.push(std::format!("G00 X{x}.0000 Z2.0000"));
        want.push(std::format!("G01 X{x}.0000 Z-29.8000"));
        want.push(std::format!("G01 X{}.0000 Z-29.3000", x + 1));
        want.push(std::format!("G00 X{}.0000 Z2.0000", x + 1));
    }
    // Along the profile moved by the allowances (X20 + U, Z + W), then
    // back to the start point.
    for m in [
        "G00 X20.4000 Z2.0000",
        "G00 X20.4000 Z2.2000",
        "G01 X20.4000 Z-29.8000",
        "G01 X40.4000 Z-29.8000",
        "G00 X40.0000 Z-29.8000",
        "G00 X40.0000 Z2.0000",
        // G70: the profile as written, then back.
        "G00 X20.0000 Z2.0000",
        "G01 X20.0000 Z-30.0000",
        "G01 X40.0000 Z-30.0000",
        "G00 X40.0000 Z2.0000",
    ] {
        want.push(m.to_string());
    }
    assert_eq!(data(&r), want);
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=4000 PZ=200 X=40.0000 Z=2.0000"
    );
}

/// A profile that turns `G42` on and leaves it on, as Fanuc's sample
/// programs write it (`G40` after the cycle): `G71` roughs on the tip's
/// path as always, and `G70` finishes on the compensated profile and
/// returns, X then Z, through compensation as the blocks written out by
/// hand would; compensation stays on until the `G40` block.
#[test]
fn g70_returns_through_compensation_when_its_profile_leaves_it_on() {
    let run = |program: &[&str]| {
        let (mut dev, r) = fanuc_program(program);
        (data(&r), ask1(&mut dev, "SYNC"), ask1(&mut dev, "POS"))
    };
    let head = [
        "CFG RN=0.8",
        "G21 G18 G98",
        "G00 X50. Z2.",
        "G71 U2. R.5",
        "G71 P10 Q30 U.4 W.2 F300.",
        "N10 G00 G42 X20.",
        "N20 G01 Z-30. F100.",
        "N30 X44.",
    ];
    let mut cycle = head.to_vec();
    cycle.extend(["G70 P10 Q30", "G00 G40 X60. Z10."]);
    let mut by_hand = head.to_vec();
    by_hand.extend([
        "G00 G42 X20.",
        "G01 Z-30. F100.",
        "X44.",
        "G00 U6.",
        "W32.",
        "G00 G40 X60. Z10.",
    ]);
    let (moves, sync, pos) = run(&cycle);
    let (moves_by_hand, sync_by_hand, pos_by_hand) = run(&by_hand);
    assert_eq!(moves, moves_by_hand);
    assert_eq!(sync, sync_by_hand);
    assert_eq!(pos, pos_by_hand);
    // The finish is compensated: the approach stops the nose (0.8 mm)
    // short of the face, and the shoulder ends short of the programmed
    // outside corner (X44 Z-30), where the nose turns around it.
    assert!(
        moves.contains(&"G00 X20.0000 Z1.2000".to_string()),
        "{moves:?}"
    );
    assert!(
        !moves.contains(&"G01 X44.0000 Z-30.0000".to_string()),
        "{moves:?}"
    );
    // Without G40 after the cycle, the end of the program is refused as
    // with any contour left on, and nothing moves.
    let mut open = head.to_vec();
    open.push("G70 P10 Q30");
    let (mut dev, _) = fanuc_program(&open);
    let pos = ask1(&mut dev, "POS");
    assert_eq!(
        ask1(&mut dev, "M30"),
        "ERR GEOMETRY M02/M30 not allowed while G41/G42 is on; cancel with G40 first"
    );
    assert_eq!(ask1(&mut dev, "POS"), pos);
}

/// A profile block the device refuses refuses the cycle: the blocks up to
/// Q are refused with it, nothing moves, and the program goes on after Q.
#[test]
fn a_refused_profile_refuses_its_cycle_and_nothing_moves() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    let r = run_program(
        &mut dev,
        &[
            "G21 G18 G98",
            "G00 X40. Z2.",
            "G71 U2. R.5",
            "G71 P10 Q30 U.4 W.2 F300.",
            "N10 G00 X20.",
            "N20 G01 Z-30. Q7",
            "N30 X40.",
            "G01 X42. F100.",
        ],
    );
    let last = |i: usize| r[i].last().unwrap().clone();
    assert!(last(5).starts_with("ERR"), "{:?}", r[5]);
    assert!(last(6).starts_with("ERR"), "{:?}", r[6]);
    assert!(last(7).starts_with("OK NX=200 NZ=0"), "{:?}", r[7]);
    assert_eq!(data(&r[2..7]), Vec::<String>::new());
}

/// A first block's words that belong to the other cycle are refused, and
/// what else a cycle block cannot take; RESET drops a profile being read.
#[test]
fn cycle_refusals_come_before_motion() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    let r = run_program(
        &mut dev,
        &[
            "G21 G18 G98",
            "G00 X40. Z2.",
            "G71 P10 Q30 D2. F300.",
            "N10 G00 X20.",
            "N20 G01 Z-30.",
            "N30 X40.",
        ],
    );
    for reply in &r {
        assert!(reply.last().unwrap().starts_with("OK"), "{reply:?}");
    }
    assert!(ask(&mut dev, b"G70 P10 Q30 F100.\n")
        .last()
        .unwrap()
        .starts_with("OK"));
    assert_eq!(
        ask1(&mut dev, "G71 U1. R.5 W1."),
        "ERR SYNTAX the first of the two blocks takes the depth (G71 U, G72 W) and the retract R"
    );
    assert_eq!(
        ask1(&mut dev, "G72 W0 R.5"),
        "ERR VALUE W the depth of cut must be above 0"
    );
    for line in [
        "G71 U1. R.5 M08",
        "G71 P1 Q2 D1. F.2 G99",
        "G70 P10 Q30 S500",
    ] {
        let want = if line.contains('S') {
            "ERR SYNTAX a cycle block takes P Q U W D R F (G71/G72) or P Q F U W (G70): S and T on their own line"
        } else {
            "ERR SYNTAX a cycle block takes its own words and F only: put M, S and other G codes on their own line"
        };
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert!(ask1(&mut dev, "AUX").contains("COOLANT=OFF"));
    // A profile being read, dropped by RESET: the next line runs.
    assert!(ask1(&mut dev, "G71 P1 Q2 D1. F100.").starts_with("OK"));
    assert!(ask1(&mut dev, "N1 G00 X20.").ends_with("HELD=1"));
    assert_eq!(ask1(&mut dev, "RESET"), "OK");
    let r = ask(&mut dev, b"G00 X42.\n");
    assert!(r.last().unwrap().starts_with("OK NX=200"), "{r:?}");
}

/// `G75` grooves and `G74` pecks as the blocks written out by hand: each
/// peck in at the feed, back by the return at the rapid rate, out of the
/// groove at the rapid rate, over by the step to the next groove, back to
/// the start point at the end. Fanuc's `P`/`Q` in the least increment,
/// Haas' `I`/`K` in millimetres, move alike.
#[test]
fn g74_and_g75_peck_as_their_blocks_written_out() {
    let run = |program: &[&str]| {
        let (mut dev, _) = fanuc_program(program);
        (ask1(&mut dev, "SYNC"), ask1(&mut dev, "POS"))
    };
    let fanuc = run(&[
        "G21 G18 G98",
        "G00 X42. Z-10.",
        "G75 R.5",
        "G75 X30. Z-14. P2500 Q2000 F50.",
        "G00 X0 Z2.",
        "G74 R1.",
        "G74 Z-12. Q5000 F80.",
    ]);
    let haas = run(&[
        "G21 G18 G98",
        "G00 X42. Z-10.",
        "G75 R.5",
        "G75 X30. Z-14. I2.5 K2. F50.",
        "G00 X0 Z2.",
        "G74 R1.",
        "G74 W-14. K5. F80.",
    ]);
    let mut by_hand = vec![
        "G21 G18 G98",
        "G00 X42. Z-10.",
        "G01 X37. F50.",
        "G00 X38.",
        "G01 X32.",
        "G00 X33.",
        "G01 X30.",
        "G00 X42.",
    ];
    for z in ["Z-12.", "Z-14."] {
        by_hand.extend([
            z, "G01 X37.", "G00 X38.", "G01 X32.", "G00 X33.", "G01 X30.", "G00 X42.",
        ]);
    }
    by_hand.extend([
        "Z-10.",
        "X0 Z2.",
        "G01 Z-3. F80.",
        "G00 Z-2.",
        "G01 Z-8.",
        "G00 Z-7.",
        "G01 Z-12.",
        "G00 Z2.",
    ]);
    let by_hand = run(&by_hand);
    assert_eq!(fanuc, by_hand);
    assert_eq!(haas, by_hand);
}

/// A grooving block that starts the spindle and the coolant (Haas'
/// `G75 … M08`) switches them at rest before its first peck: the same
/// events, times and outputs as the words on their own line before it.
#[test]
fn a_grooving_block_starts_the_spindle_and_the_coolant_before_it_cuts() {
    let run = |program: &[&str]| {
        let (mut dev, _) = fanuc_program(program);
        (
            ask1(&mut dev, "SYNC"),
            ask1(&mut dev, "POS"),
            ask1(&mut dev, "STATUS"),
        )
    };
    let head = ["G21 G18 G98", "G00 X42. Z-10.", "G75 R.5"];
    let mut within = head.to_vec();
    within.push("G75 X30. Z-14. P2500 Q2000 F50. S600 M03 M08");
    let mut before = head.to_vec();
    before.extend(["S600 M03 M08", "G75 X30. Z-14. P2500 Q2000 F50."]);
    let (a, b) = (run(&within), run(&before));
    assert_eq!(a, b);
    assert!(
        a.2.ends_with(" SPINDLE=CW S=600.000 COOLANT=FLOOD"),
        "{}",
        a.2
    );
    // Without them: not the same times (no spin-up before the pecks).
    let mut bare = head.to_vec();
    bare.push("G75 X30. Z-14. P2500 Q2000 F50.");
    assert_ne!(run(&bare).0, a.0);
}

/// What a grooving cycle cannot take is refused before anything moves.
#[test]
fn g74_and_g75_refusals_change_nothing() {
    refusals_change_nothing(
        "G00 X42. Z-10.",
        &[
            ("G75 Z-14. Q2000 F50.", "ERR SYNTAX G75 needs a depth: its X (U) away from the start point"),
            ("G75 X30. Z-14. P2500 F50.", "ERR SYNTAX G75 to another Z needs the step between grooves: Q (K)"),
            ("G75 X30. P2500 R.2 F50.", "ERR VALUE R a relief at the bottom is not supported: R0 (D0) or none"),
            ("G75 X30. P2500 F50. M05", "ERR SYNTAX a grooving cycle block takes its own words, F, S, M03/M04 and M07/M08 only: put other M and G codes on their own line"),
            ("G75 X30. P2500 F50. M09", "ERR SYNTAX a grooving cycle block takes its own words, F, S, M03/M04 and M07/M08 only: put other M and G codes on their own line"),
            ("G75 X30. P2500 F50. G04", "ERR SYNTAX a grooving cycle block takes its own words, F, S, M03/M04 and M07/M08 only: put other M and G codes on their own line"),
            ("G75 R1. M08", "ERR SYNTAX G74/G75 with R alone sets the return: put S, M03/M04 and M07/M08 with the cut"),
            ("G75 X30. P2500 F50. G96 S300 M03", "ERR SYNTAX a grooving cycle block takes its own words, F, S, M03/M04 and M07/M08 only: put other M and G codes on their own line"),
            ("G75 X10. P1 F50.", "ERR RANGE a grooving cycle of more than 20000 moves"),
            ("G75 X30. P2500", "ERR VALUE F not programmed: a feed move needs F (mm/min)"),
            ("G75 X30. P2.5 F50.", "ERR VALUE P a step in the least increment, without a point (P2500: 2.5 mm)"),
        ],
    );
}

/// `G73` cuts the profile whole, again and again: each pass at the rapid
/// rate to the profile's first point moved by the allowances and a share
/// of the relief (all of it on the first pass, none on the last), along
/// it at the cycle's feed, at the rapid rate back to the start point.
/// Fanuc's two blocks and Haas' one move as the passes written out by
/// hand, and `G70` then finishes on the profile held.
#[test]
fn g73_repeats_the_profile_as_its_passes_written_out() {
    let run = |program: &[&str]| {
        let mut dev = Device::new();
        ask1(&mut dev, "OPT DIALECT=fanuc");
        for line in program {
            let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        }
        (ask1(&mut dev, "SYNC"), ask1(&mut dev, "POS"))
    };
    let profile = [
        "N10 G00 X20. Z0",
        "N20 G01 Z-20. F100.",
        "N30 G02 X40. Z-30. I10. K0",
        "N40 G01 X48.",
        "G70 P10 Q40",
    ];
    let mut fanuc = vec![
        "G21 G18 G98",
        "G00 X50. Z2.",
        "G73 U3. W1. R3",
        "G73 P10 Q40 U.4 W.2 F200.",
    ];
    fanuc.extend(profile);
    let mut haas = vec![
        "G21 G18 G98",
        "G00 X50. Z2.",
        "G73 P10 Q40 I3. K1. D3. U.4 W.2 F200.",
    ];
    haas.extend(profile);
    // Passes 1 to 3 lie 3, 1.5 and 0 mm out in X (on the radius) and 1,
    // 0.5 and 0 mm in Z, beyond the allowances (0.2 mm a side, 0.2 in Z).
    let mut by_hand = vec!["G21 G18 G98", "G00 X50. Z2."];
    let passes = [
        [
            "G00 X26.4 Z1.2",
            "G01 Z-18.8 F200.",
            "G02 X46.4 Z-28.8 I10. K0",
            "G01 X54.4",
            "G00 X50. Z2.",
        ],
        [
            "G00 X23.4 Z.7",
            "G01 Z-19.3",
            "G02 X43.4 Z-29.3 I10. K0",
            "G01 X51.4",
            "G00 X50. Z2.",
        ],
        [
            "G00 X20.4 Z.2",
            "G01 Z-19.8",
            "G02 X40.4 Z-29.8 I10. K0",
            "G01 X48.4",
            "G00 X50. Z2.",
        ],
    ];
    for pass in &passes {
        by_hand.extend(pass);
    }
    by_hand.extend([
        "G00 X20. Z0",
        "G01 Z-20. F100.",
        "G02 X40. Z-30. I10. K0",
        "G01 X48.",
        "G00 X50.",
        "Z2.",
    ]);
    let by_hand = run(&by_hand);
    assert_eq!(run(&fanuc), by_hand);
    assert_eq!(run(&haas), by_hand);
}

/// What a `G73` block cannot take is refused naming it, and nothing
/// moves or is held.
#[test]
fn g73_refusals_change_nothing() {
    let mut dev = refusals_change_nothing(
        "G00 X50. Z2.",
        &[
        (
            "G73 P10 Q40 U.4 W.2 F200.",
            "ERR SYNTAX no relief: I K D, or G73 U W R in a block before",
        ),
        (
            "G73 U3. W1.",
            "ERR SYNTAX G73 U W R: the relief and the count of passes, or P and Q",
        ),
        ("G73 U3. W1. R0", "ERR VALUE R a count of passes, 1 to 999"),
        ("G73 U3. W1. R2.5", "ERR VALUE R a count of passes, 1 to 999"),
        (
            "G73 U3. R3 K1.",
            "ERR SYNTAX the first of the two G73 blocks takes the relief U W and the count of passes R",
        ),
        (
            "G73 P10 Q40 I3. K1. F200.",
            "ERR SYNTAX G73 with I and K needs D: the count of passes",
        ),
        ("G73 P10 I3. K1. D3", "ERR SYNTAX G73 needs P and Q: the profile's blocks"),
        (
            "G73 P10 Q40 I3. K1. D3 S500",
            "ERR SYNTAX a G73 block takes U W R (Fanuc's first), P Q U W F, or Haas' P Q I K D U W F: S and T on their own line",
        ),
        (
            "G73 P10 Q40 I3. K1. D3 M08",
            "ERR SYNTAX a cycle block takes its own words and F only: put M, S and other G codes on their own line",
        ),
        (
            "G70 P10 Q40",
            "ERR SYNTAX G70 finishes the profile a G71, G72 or G73 held last: no such P and Q",
        ),
        ],
    );
    // Nothing was held: a numbered block runs as itself.
    let r = ask(&mut dev, b"N10 G00 X48.\n");
    assert!(r.last().unwrap().starts_with("OK NX=-200"), "{r:?}");
    assert!(ask1(&mut dev, "AUX").contains("COOLANT=OFF"));
}

/// A cycle block's `F` is the feed in force once the block is taken, as
/// any block's is (a Haas program cuts its chamfer after a `G71` with the
/// roughing's feed); a refused block leaves the feed as it was.
#[test]
fn a_cycle_blocks_feed_stays_in_force() {
    let feed_of_next_cut = |program: &[&str]| {
        let mut dev = Device::new();
        ask1(&mut dev, "OPT DIALECT=fanuc");
        for line in program {
            ask(&mut dev, std::format!("{line}\n").as_bytes());
        }
        ask1(&mut dev, "SYNC");
        // 10 mm at the feed in force: its time tells the feed.
        let r = ask(&mut dev, b"G01 W-10.\n");
        let last = r.last().unwrap().clone();
        if !last.starts_with("OK") {
            return last;
        }
        ask1(&mut dev, "SYNC")
    };
    let by_hand = |f: &str| feed_of_next_cut(&["G21 G18 G98", "G00 X40. Z2.", f]);
    let shaft = [
        "G21 G18 G98",
        "G00 X40. Z2.",
        "G71 U2. R.5",
        "G71 P10 Q30 U.4 W.2 F300.",
        "N10 G00 X20.",
        "N20 G01 Z-30. F100.",
        "N30 X40.",
    ];
    let after = feed_of_next_cut(&shaft);
    assert_ne!(after, by_hand("F100."));
    assert_eq!(after, by_hand("F300."));
    // A first block's F, a grooving cycle's.
    assert_eq!(
        feed_of_next_cut(&["G21 G18 G98", "G00 X40. Z2.", "G71 U2. R.5 F250."]),
        by_hand("F250.")
    );
    assert_eq!(
        feed_of_next_cut(&["G21 G18 G98", "G00 X40. Z2.", "G75 X36. Z2. P1000 F80."]),
        by_hand("F80.")
    );
    // Refused: the feed stays unset, and the next cut is refused for it.
    assert_eq!(
        feed_of_next_cut(&["G21 G18 G98", "G00 X40. Z2.", "G71 U2. R.5 F0"]),
        "ERR VALUE F not programmed: a feed move needs F (mm/min)"
    );
    assert_eq!(
        feed_of_next_cut(&["G21 G18 G98", "G00 X40. Z2.", "G71 U2. R.5 F250. M08"]),
        "ERR VALUE F not programmed: a feed move needs F (mm/min)"
    );
}

/// Haas' one-block roughing reads `R1` as type II (the pockets), which
/// every roughing here is: the same moves as without it. Any other `R`
/// there is refused; a Fanuc second block's `R` is its retract.
#[test]
fn haas_r1_selects_the_pockets_every_roughing_follows() {
    let run = |cycle: &[&str]| {
        let mut dev = Device::new();
        ask1(&mut dev, "OPT DIALECT=fanuc");
        let mut last = String::new();
        let program = ["G21 G18 G98", "G00 X40. Z2."].iter().chain(cycle).chain(&[
            "N10 G00 X20.",
            "N20 G01 Z-10. F100.",
            "N25 X30. Z-15.",
            "N26 X24. Z-20.",
            "N30 X40.",
        ]);
        for line in program {
            last = ask(&mut dev, std::format!("{line}\n").as_bytes())
                .last()
                .unwrap()
                .clone();
        }
        (last, ask1(&mut dev, "SYNC"))
    };
    let plain = run(&["G71 P10 Q30 U.4 W.2 D2. F300."]);
    assert!(plain.0.starts_with("OK NX=0 NZ=0"), "{plain:?}");
    assert_eq!(run(&["G71 P10 Q30 U.4 W.2 D2. F300. R1"]), plain);
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    ask1(&mut dev, "G21 G18 G98");
    for line in ["G71 P10 Q30 D2. R2", "G71 P10 Q30 U.4 D2. F300. R.5"] {
        assert_eq!(
            ask1(&mut dev, line),
            "ERR VALUE R in Haas' one block R1 selects type II roughing (pockets), which every roughing is: R1 or none"
        );
    }
    // Nothing is held after it: a numbered block runs as itself.
    assert!(ask(&mut dev, b"N10 G00 X20.\n")
        .last()
        .unwrap()
        .starts_with("OK NX="));
    // Fanuc's second block: R is the retract (1 mm, not 0.5).
    let fanuc = |r: &str| run(&["G71 U2. R.5", &std::format!("G71 P10 Q30 U.4 W.2 F300.{r}")]);
    assert_eq!(fanuc(""), plain);
    assert_eq!(fanuc(" R.5"), plain);
    assert!(fanuc(" R1").0.starts_with("OK NX=0 NZ=0"));
    assert_ne!(fanuc(" R1"), plain);
}

//! Probing on the simulated machine (`docs/inputs.md` §10): `G38.2`–
//! `G38.5` on a lathe whose tool setter trips where its machine file puts
//! it; the move stops on the probe's edge and where it stopped is the
//! result, for the pendant protocol (`!PROBE`) and a grbl sender (`PRB:`).

use host_sim::board::Board;
use host_sim::link::{words_value, Client};
use tests::ask;

/// A lathe with 0.15 mm of play in Z and a tool setter the carriage
/// touches at Z −50 (machine coordinates) coming from plus.
const LATHE: &str = r#"
[x]
travel = [-2.0, 75.0]
backlash = 0.08
[[x.switch]]
input = "X+"
at = 74.0
[z]
travel = [-400.0, 5.0]
backlash = 0.15
[[z.switch]]
input = "PROBE"
side = "-"
at = -50.0
"#;

/// The lathe behind a board, radius mode, its limit and probe wired; the
/// link speaks grbl when `grbl`.
fn lathe(grbl: bool) -> (Board, Client) {
    let wiring = if grbl {
        // A grbl sender wires its probe with $6.
        "CFG DIAM=0\nINPUT USED=X+\n"
    } else {
        "CFG DIAM=0\nINPUT USED=X+,PROBE\n"
    };
    let (board, mut c) = tests::lathe_board(LATHE, wiring, grbl);
    c.drain();
    (board, c)
}

/// Sends `line` and reads to its `!PROBE` line (the block's `DATA`
/// lines come first).
fn probe_line(c: &mut Client, line: &str) -> String {
    c.write_raw(format!("{line}\n").as_bytes()).expect("write");
    loop {
        let l = c.read_line().expect("probe line");
        if l.starts_with("!PROBE") {
            // Without its `*HH`.
            return l.split('*').next().unwrap_or_default().to_string();
        }
        assert!(l.starts_with("DATA "), "{line}: {l}");
    }
}

/// A `!PROBE` line's value of `key` as a number.
fn num(line: &str, key: &str) -> f64 {
    words_value(line, key)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{key} in {line}"))
}

/// `G38.2` stops where the carriage touches the setter: the result is
/// that point, to the impulse, and the registers are there. `G38.4` back
/// off it stops where it leaves: later by the screw's play, which the
/// result shows. A `G38.3` that touches nothing runs to its end and says
/// so; a `G38.2` that touches nothing locks with alarm 5, one that starts
/// on the probe with alarm 4, nothing moved.
#[test]
fn a_probing_move_stops_where_the_probe_changes() {
    let (board, mut c) = lathe(false);
    // Towards the setter: it trips at Z −50 (Z's impulse 0.01 mm).
    let probe = probe_line(&mut c, "G38.2 Z-60 F200");
    assert!(probe.starts_with("!PROBE MX=0 MZ="), "{probe}");
    assert_eq!(words_value(&probe, "OK"), Some("1"), "{probe}");
    let mz = num(&probe, "MZ");
    assert!((-50.0..=-49.99).contains(&mz) || mz == -50.0, "{probe}");
    assert_eq!(num(&probe, "PZ"), mz * 100.0, "{probe}");
    let ok = c.read_reply().expect("reply");
    assert!(ok.is_ok(), "{ok:?}");
    assert_eq!(
        ok.value("PZ").map(str::to_string),
        words_value(&probe, "PZ").map(str::to_string)
    );
    assert!(
        (tests::carriage(&board).1 - mz).abs() < 1e-9,
        "the carriage is where it stopped"
    );
    // The program goes on from there: the point is the probe's.
    let status = ask(&mut c, "STATUS");
    assert_eq!(
        status.value("Z").map(|z| z.parse::<f64>().unwrap()),
        Some(mz),
        "{status:?}"
    );
    // Away from it: the carriage stands still until the nut has taken up
    // the 0.15 mm of play, then leaves the setter.
    let off = probe_line(&mut c, "G38.4 Z-40 F50");
    assert_eq!(words_value(&off, "OK"), Some("1"), "{off}");
    let left = num(&off, "MZ");
    assert!(
        (left - (mz + 0.15 + 0.01)).abs() < 0.0101,
        "left at {left}, touched at {mz}: {off}"
    );
    assert!(c.read_reply().expect("reply").is_ok());
    // Clear of it, a G38.3 that ends short of the setter: no change, no
    // alarm, the move ran to its end.
    assert!(ask(&mut c, "G00 Z0").is_ok());
    let short = probe_line(&mut c, "G38.3 Z-30 F300");
    assert_eq!(words_value(&short, "OK"), Some("0"), "{short}");
    assert_eq!(num(&short, "MZ"), -30.0, "{short}");
    assert!(c.read_reply().expect("reply").is_ok());
    // The same with G38.2: alarm 5, locked until UNLOCK.
    let short = probe_line(&mut c, "G38.2 Z-40 F300");
    assert_eq!(words_value(&short, "OK"), Some("0"), "{short}");
    let alarm = c.read_line().expect("alarm");
    assert!(alarm.starts_with("!ALARM CODE=5 "), "{alarm}");
    let r = c.read_reply().expect("reply");
    assert!(
        r.last.starts_with("ERR ALARM 5: the probe did not change"),
        "{r:?}"
    );
    assert!(ask(&mut c, "G00 Z0").last.starts_with("ERR ALARM 5"));
    assert!(ask(&mut c, "UNLOCK").is_ok());
    // On the setter already, a G38.2 towards it is alarm 4 and moves
    // nothing.
    assert!(ask(&mut c, "G00 Z-55").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
    let before = tests::carriage(&board).1;
    c.write_raw(b"G38.2 Z-60 F100\n").expect("write");
    let alarm = c.read_line().expect("alarm");
    assert!(alarm.starts_with("!ALARM CODE=4 INPUT=PROBE "), "{alarm}");
    let r = c.read_reply().expect("reply");
    assert!(r.last.starts_with("ERR ALARM 4"), "{r:?}");
    assert_eq!(tests::carriage(&board).1, before, "nothing moved");
    assert!(ask(&mut c, "UNLOCK").is_ok());
}

/// What a probing block needs is checked before anything moves.
#[test]
fn a_probing_block_is_refused_before_it_moves() {
    let (board, mut c) = lathe(false);
    for (line, why) in [
        (
            "G95 G38.2 Z-60 F0.1",
            "ERR SYNTAX G38.2 to G38.5 probe at a feed per minute",
        ),
        (
            "G38.2 Z0 F100",
            "ERR GEOMETRY G38.2 to G38.5 end where the tool already is",
        ),
        ("G38.2 F100", "ERR SYNTAX G38.2 to G38.5 need X or Z"),
        (
            "G01 G38.2 Z-10 F100",
            "ERR SYNTAX G38.2 to G38.5 are a motion of their own",
        ),
        ("G38.2 Z-10 M00 F100", "ERR SYNTAX G38.2 to G38.5 with M00"),
    ] {
        let r = ask(&mut c, line);
        assert!(r.last.starts_with(why), "{line}: {r:?}");
        assert_eq!(tests::carriage(&board).1, 0.0, "{line} moved nothing");
        assert!(ask(&mut c, "G94").is_ok());
    }
    // Not wired: refused, nothing moved.
    assert!(ask(&mut c, "INPUT USED=X+").is_ok());
    let r = ask(&mut c, "G38.2 Z-60 F100");
    assert!(
        r.last
            .starts_with("ERR SYNTAX G38.2 to G38.5 need the probe wired"),
        "{r:?}"
    );
    assert_eq!(tests::carriage(&board).1, 0.0);
}

/// A grbl sender probes as on grbl: `$6` (how the probe reads) wires it;
/// `[PRB:x,y,z:1]` (machine coordinates) before the block's `ok`, `$#`
/// repeats it; no contact is `ALARM:5`.
#[test]
fn a_grbl_sender_reads_prb() {
    let (_board, mut c) = lathe(true);
    let say = tests::grbl_say;
    let unwired = say(&mut c, "G38.2 Z-60 F200");
    assert_eq!(
        unwired.first().map(String::as_str),
        Some("[MSG:SYNTAX G38.2 to G38.5 need the probe wired: $6=0 (or $6=1, inverted) wires it]"),
        "{unwired:?}"
    );
    assert!(
        unwired.last().is_some_and(|l| l.starts_with("error:")),
        "{unwired:?}"
    );
    assert_eq!(say(&mut c, "$6=0"), ["ok"]);
    assert_eq!(
        say(&mut c, "G38.2 Z-60 F200"),
        ["[PRB:0.0000,0.0000,-50.0000:1]", "ok"]
    );
    let offsets = say(&mut c, "$#");
    assert!(
        offsets.contains(&"[PRB:0.0000,0.0000,-50.0000:1]".to_string()),
        "{offsets:?}"
    );
    assert_eq!(say(&mut c, "G0 Z0"), ["ok"]);
    let r = say(&mut c, "G38.2 Z-20 F300");
    assert_eq!(
        r.first().map(String::as_str),
        Some("[PRB:0.0000,0.0000,-20.0000:0]"),
        "{r:?}"
    );
    assert_eq!(r.get(1).map(String::as_str), Some("ALARM:5"), "{r:?}");
    assert_eq!(r.last().map(String::as_str), Some("error:9"), "{r:?}");
    assert_eq!(say(&mut c, "$X"), ["[MSG:Caution: Unlocked]", "ok"]);
}

/// A tool setter's touch-off in a program, as LinuxCNC writes it: probe
/// the setter with the tool, then `G10 L10` makes that point Z0 with the
/// tool's offset, written to its register. The simulated setter trips at
/// the carriage's place whatever the tool, so two tools touched off get
/// the same offset, the setter's machine Z.
#[test]
fn a_tool_setter_touch_off_writes_the_tools_offset() {
    let (_board, mut c) = lathe(false);
    // Clear of the setter: Z0 with no offset, then Z10 above it with
    // tool 1's.
    for (tool, before) in [(1, "G00 Z0"), (2, "G00 Z10")] {
        assert!(ask(&mut c, before).is_ok());
        assert!(ask(&mut c, &format!("T{tool} M06 G43")).is_ok());
        let touched = probe_line(&mut c, "G38.2 Z-60 F200");
        assert!(touched.ends_with(" OK=1"), "{touched}");
        assert!(c.read_reply().expect("reply").is_ok());
        assert!(ask(&mut c, &format!("G10 L10 P{tool} Z0")).is_ok());
        let pos = ask(&mut c, "POS");
        assert_eq!(pos.value("Z"), Some("0.0000"), "tool {tool}: {pos:?}");
    }
    let t1 = ask(&mut c, "TOOL N=1");
    let t2 = ask(&mut c, "TOOL N=2");
    assert_eq!(t1.value("Z"), Some("-50.0000"), "{t1:?}");
    assert_eq!(t2.value("Z"), t1.value("Z"), "{t2:?}");
}

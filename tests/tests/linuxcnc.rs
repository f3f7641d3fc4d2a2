//! The ISO dialect against LinuxCNC's standalone interpreter `rs274`
//! (Debian `linuxcnc-uspace`): for programs without cycles, the device's
//! path (`host-sim run --trace`: block end points and arc centres) equals
//! LinuxCNC's canonical moves (`STRAIGHT_TRAVERSE`, `STRAIGHT_FEED`,
//! `ARC_FEED`, plus the work and tool offsets it reports beside them) to
//! 0.0001 mm (0.0001 in for inch programs, the digits `rs274` prints), in
//! machine coordinates.
//!
//! With nose compensation the two differ by design at one place, the
//! entry move: LinuxCNC ends it with the imaginary tip on the programmed
//! point, the device with the nose touching the first element square to
//! its start (`docs/compensation.md`); those moves are compared by kind
//! only. LinuxCNC's orientation codes are the device's tip codes mirrored
//! in X (its `Q2` is `TIP=3`, its `Q3` `TIP=2`); outside corners are
//! compared under `G450` (LinuxCNC always rounds them with an arc).
//!
//! Skipped with a message where `rs274` is missing, except under CI (`CI`
//! set), where a missing `rs274` fails.

use core_nostd::gcode::Dialect;
use host_sim::program::Options;
use std::process::Command;
use tests::rs274::{self, args};

/// One canonical move: its G code, X on the radius and Z (mm), the arc
/// centre.
#[derive(Clone, Debug, PartialEq)]
struct Move {
    g: u8,
    x: f64,
    z: f64,
    centre: Option<(f64, f64)>,
}

/// A program for both, and what differs.
struct Peer {
    name: &'static str,
    /// The program as both read it.
    body: &'static str,
    /// Tool 1 for LinuxCNC's table: X and Z offsets (inches: the standalone
    /// interpreter's table unit), orientation; and the same tool for the
    /// device's `TOOL N=1` (X a diameter, mm), with the device's tip code.
    tool: Option<(&'static str, &'static str)>,
    /// The indices of the compensated entry moves.
    entry: &'static [usize],
    /// The indices of the moves after `G40` that name X only: LinuxCNC
    /// also moves Z there (back from the nose's point to the programmed
    /// one), the device never moves an axis the block does not name
    /// (`docs/compensation.md`); compared in X only.
    x_only: &'static [usize],
    /// Inch: compare to 0.0001 in.
    inch: bool,
}

/// r 0.4 mm = 0.8 mm across, in inches.
const D: &str = "D0.031496062992126";

/// Tool 2 in both tables, never loaded: a nose of r 0.8 mm (1.6 mm across,
/// in inches), tip 3 (LinuxCNC's Q2), for `G41`/`G42 D2`.
const TOOL2: &str = "X0 Z0 Q2 D0.062992125984252";
const TOOL2_DEVICE: &str = "TOOL N=2 X=0 Z=0 R=0.8 T=3";

const PEERS: &[Peer] = &[
    Peer {
        name: "tapers and arcs (I/K and R, more than 180°)",
        body: "G18 G21 G7 G90\nG00 X30 Z5\nG01 Z0 F100\nX40 Z-10\nZ-20\n\
               G03 X50 Z-25 I0 K-5\nG02 X60 Z-30 R5\nG01 X70 Z-40\n\
               G02 X70 Z-50 R-5.5\nG01 Z-60\nX80 Z-61.25\nG00 X100 Z10\nM2\n",
        tool: None,
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "LinuxCNC's lathe_test.ngc (G8, G64, a space between letter and number)",
        body: include_str!("../data/linuxcnc/lathe_test.ngc"),
        tool: None,
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "LinuxCNC's lathecomp.ngc (G42 D1, G41 D1 on the back side; radius words)",
        body: concat!("G8\n", include_str!("../data/linuxcnc/lathecomp.ngc")),
        tool: Some(("X0 Z0 Q2", "X=0 Z=0 R=0.4 T=3")),
        entry: &[9],
        x_only: &[15, 25],
        inch: true,
    },
    Peer {
        name:
            "a tool's offsets set by G10 L1 and by G10 L10 where the tool stands, reloaded by G43",
        body: "G18 G21 G8 G90\nG10 L1 P2 X1.5 Z-3\nT2 M6 G43\nG00 X10 Z5\nG01 Z-4 F100\n\
               G10 L10 P2 Z0 X7.25\nG43\nG01 X12 Z-2\nG00 X20 Z10\nM2\n",
        tool: None,
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "spaces and tabs between letters and numbers",
        body: "G 18 G21 G7 G90\nG00 X 30 Z\t5\nG01 Z -10 F 100\nG02 X 40 Z -15 R 5\n\
               G00 X 50 Z 5\nM 2\n",
        tool: None,
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "incremental words (G91)",
        body: "G18 G21 G7 G90\nG00 X20 Z2\nG91 G01 Z-12 F80\nX10 Z-5\n\
               G02 X8 Z-4 I0 K-4\nG03 X-4 Z-6 I-1 K-3\nG01 Z-3.333\nG90 G00 X60 Z5\nM2\n",
        tool: None,
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "inch (G20)",
        body: "G18 G20 G7 G90\nG00 X1. Z.1\nG01 Z-1.5 F5.\nG02 X1.5 Z-1.75 R.25\n\
               G01 X1.8125 Z-2.0625\nG03 X2.2125 Z-2.2625 I0 K-.2\nG00 X3. Z.5\nM2\n",
        tool: None,
        entry: &[],
        x_only: &[],
        inch: true,
    },
    Peer {
        name: "radius words (G8), arc centres absolute (G90.1)",
        body: "G18 G21 G8 G90\nG00 X10 Z1\nG90.1 G02 X10 Z-4 I5 K-1.5 F100\n\
               G91.1 G03 X14 Z-8 I0 K-4\nG01 X15.5 Z-9.25\nG00 X25 Z5\nM2\n",
        tool: None,
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "G42 external contour, r 0.4 (tip 3 / Q2)",
        body: "G18 G21 G7 G90 G40\nT1 M6\nG00 X20 Z5\nG42 G01 Z0 F100\nX28\nX48 Z-10\n\
               Z-46\nX68 Z-56\nX94\nG03 X104 Z-61 R5\nG01 Z-70\nG02 X114 Z-75 I5 K0\n\
               G01 X120\nG40 G00 X130 Z-70\nM2\n",
        tool: Some(("X0 Z0 Q2", "X=0 Z=0 R=0.4 T=3")),
        entry: &[1],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "G42 D2: the nose of tool 2 (r 0.8) while tool 1 (r 0.4) is loaded",
        body: "G18 G21 G7 G90 G40\nT1 M6\nG00 X20 Z5\nG42 D2 G01 Z0 F100\nX28\nX48 Z-10\n\
               Z-46\nG03 X58 Z-51 R5\nG01 X70\nG40 G00 X80 Z-40\nG00 X20 Z5\n\
               G42 G01 Z0\nX28\nX48 Z-10\nG40 G00 X80 Z0\nM2\n",
        tool: Some(("X0 Z0 Q2", "X=0 Z=0 R=0.4 T=3")),
        entry: &[1, 11],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "G41 bore, r 0.4 (tip 2 / Q3)",
        body: "G18 G21 G7 G90 G40\nT1 M6\nG00 X90 Z5\nG41 G01 Z0 F80\nX78\nX50 Z-14\nZ-34\n\
               X28 Z-45\nX12\nZ-60\nG40 G00 X10 Z-55\nM2\n",
        tool: Some(("X0 Z0 Q3", "X=0 Z=0 R=0.4 T=2")),
        entry: &[1],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "work offsets (G10 L2, L20; G54, G55) and tool offsets (G43, G49)",
        body: "G18 G21 G7 G90 G40\nG10 L2 P1 X0 Z-20\nG10 L2 P2 X2 Z-60\nT1 M6 G43\n\
               G00 X30 Z5\nG01 Z-10 F100\nG02 X40 Z-15 R5\nG01 X50\nG55 G00 X50 Z5\n\
               G01 Z-5\nG03 X40 Z-10 R5\nG49 G00 X60 Z10\nG10 L20 P2 X30 Z10\n\
               G00 X30 Z0\nG54 G43 G00 X20 Z2\nM2\n",
        tool: Some(("X0.05 Z-0.1 Q2", "X=2.54 Z=-2.54 R=0.4 T=3")),
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "G42 with work and tool offsets",
        body: "G18 G21 G7 G90 G40\nG10 L2 P1 X-1 Z-30\nT1 M6 G43\nG00 X20 Z5\n\
               G42 G01 Z0 F100\nX28\nX48 Z-10\nG02 X56 Z-14 R4\nG01 Z-30\n\
               G40 G00 X70 Z-25\nM2\n",
        tool: Some(("X0.05 Z-0.1 Q2", "X=2.54 Z=-2.54 R=0.4 T=3")),
        entry: &[1],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "machine coordinates (G53), reference returns (G28, G30, G28.1) and G92 shifts",
        body: "G18 G21 G7 G90 G40\nG10 L2 P1 X2 Z-20\nT1 M6 G43\nG00 X30 Z5\nG28.1\n\
               G00 X40 Z8\nG53 G00 X10 Z-3\nG01 X20 F200\nG53 G01 X12 Z-1\nG28 X50 Z10\n\
               G92 X0 Z0\nG00 X10 Z-5\nG01 Z-8\nG30\nG00 X6 Z-2\nG92.1\nG00 X20 Z2\n\
               G91 G28 X0\nG90 G00 X24 Z4\nG92 Z10\nG03 X30 Z7 R3\nG92.2\nG00 X30 Z0\nM2\n",
        tool: Some(("X0.05 Z-0.1 Q2", "X=2.54 Z=-2.54 R=0.4 T=3")),
        entry: &[],
        x_only: &[],
        inch: false,
    },
    Peer {
        name: "an axis the block does not name stays where it is after an offset change",
        body: "G18 G21 G7 G90 G40\nG00 X10 Z-5\nG10 L2 P1 X4 Z-2\nG00 Z-6\n\
               G10 L20 P1 X20\nG01 Z-10 F100\nG55\nG00 Z-3\nT1 M6 G43\nG00 X12 Z-1\n\
               G92 X5\nG00 Z0\nG92.1\nG00 Z2\nG10 L2 P2 Z7\nG00 X30\nG54\n\
               G01 Z1\nG10 L20 P1 Z3\nG91 G01 X2\nG90 G92 Z0\nG00 X8\nM2\n",
        tool: Some(("X0.05 Z-0.1 Q2", "X=2.54 Z=-2.54 R=0.4 T=3")),
        entry: &[],
        x_only: &[],
        inch: false,
    },
];

/// The numbers of a triple `a b c` inside a call's arguments.
fn triple(text: &str) -> Vec<f64> {
    text.split_whitespace()
        .map(|a| a.parse().unwrap())
        .collect()
}

/// LinuxCNC's canonical moves of a program, in mm and machine coordinates:
/// its positions plus the work offset (`SET_G5X_OFFSET`), the `G92` shift
/// (`SET_G92_OFFSET`) and the tool offset (`USE_TOOL_LENGTH_OFFSET`) in
/// effect. A traverse that does not move is left out: LinuxCNC sends the
/// way point of `G28`/`G30` even where the tool already is, the device
/// does not.
fn linuxcnc(name: &str, program: &str, tool: Option<&str>) -> Vec<Move> {
    // One directory per call: the tests run side by side.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("linuxcnc-peer-{}-{call}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ngc = dir.join("part.ngc");
    let tbl = dir.join("tool.tbl");
    let tool = tool.unwrap_or("X0 Z0 Q0");
    std::fs::write(&tbl, format!("T1 P1 {tool} {D}\nT2 P2 {TOOL2}\n")).unwrap();
    std::fs::write(&ngc, program).unwrap();
    let out = Command::new("rs274")
        .args(["-g", "-t"])
        .arg(&tbl)
        .arg(&ngc)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        text.contains("PROGRAM_END"),
        "{name}: rs274 stopped ({}):\n{text}{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let mut scale = 1.0;
    let (mut work, mut shift, mut offset) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    let mut last: Option<(f64, f64)> = None;
    let mut moves = Vec::new();
    for line in text.lines() {
        let Some(call) = line.split("N..... ").nth(1) else {
            continue;
        };
        let at = |x: f64, z: f64| {
            (
                x * scale + work[0] + shift[0] + offset[0],
                z * scale + work[1] + shift[1] + offset[1],
            )
        };
        if call.starts_with("USE_LENGTH_UNITS") {
            scale = if call.contains("INCHES") { 25.4 } else { 1.0 };
        } else if call.starts_with("SET_G5X_OFFSET") {
            let a = args(call);
            work = [a[1] * scale, a[3] * scale];
        } else if call.starts_with("SET_G92_OFFSET") {
            let a = args(call);
            shift = [a[0] * scale, a[2] * scale];
        } else if call.starts_with("USE_TOOL_LENGTH_OFFSET") {
            let inner = call.split_once('(').unwrap().1;
            let xyz = triple(inner.split(',').next().unwrap());
            offset = [xyz[0] * scale, xyz[2] * scale];
        } else if call.starts_with("STRAIGHT_TRAVERSE") || call.starts_with("STRAIGHT_FEED") {
            let a = args(call);
            let (x, z) = at(a[0], a[2]);
            let still = last.is_some_and(|(px, pz)| (px - x).abs() < 1e-9 && (pz - z).abs() < 1e-9);
            last = Some((x, z));
            if still && call.starts_with("STRAIGHT_TRAVERSE") {
                continue;
            }
            moves.push(Move {
                g: u8::from(call.starts_with("STRAIGHT_FEED")),
                x,
                z,
                centre: None,
            });
        } else if call.starts_with("ARC_FEED") {
            // XZ plane: Z end, X end, Z centre, X centre, turn (+1 G03).
            let a = args(call);
            let (x, z) = at(a[1], a[0]);
            last = Some((x, z));
            let centre = at(a[3], a[2]);
            moves.push(Move {
                g: if a[4] > 0.0 { 3 } else { 2 },
                x,
                z,
                centre: Some(centre),
            });
        }
    }
    moves
}

/// The device's path of the same program, exactly, in mm and machine
/// coordinates.
fn device(name: &str, program: &str, tool: Option<&str>) -> Vec<Move> {
    // LinuxCNC rounds outside corners with arcs.
    let text = format!("G450\n{program}");
    let options = Options {
        dialect: Dialect::Iso,
        radius: false,
        optional_stop: false,
    };
    let setup = tool.map(|t| format!("TOOL N=1 {t}"));
    let mut setup: Vec<&str> = setup.iter().map(String::as_str).collect();
    setup.push(TOOL2_DEVICE);
    let report = host_sim::program::run_with(&text, options, &setup);
    assert!(report.refused.is_empty(), "{name}: {:?}", report.refused);
    assert!(
        report.setup_refused.is_empty(),
        "{name}: {:?}",
        report.setup_refused
    );
    let mm = |a: i64| a as f64 / 1e7;
    report
        .path
        .iter()
        .map(|t| Move {
            g: t.g,
            x: mm(t.to[0]),
            z: mm(t.to[1]),
            centre: t.centre.map(|c| (mm(c[0]), mm(c[1]))),
        })
        .collect()
}

#[test]
fn the_iso_dialect_cuts_the_paths_linuxcnc_cuts() {
    let _one = rs274::one_at_a_time();
    if !rs274::available("the LinuxCNC comparison") {
        return;
    }
    let (mut agreed, mut moves) = (0, 0);
    for peer in PEERS {
        let theirs = linuxcnc(peer.name, peer.body, peer.tool.map(|t| t.0));
        let ours = device(peer.name, peer.body, peer.tool.map(|t| t.1));
        assert_eq!(
            ours.len(),
            theirs.len(),
            "{}:\n device {ours:#?}\n LinuxCNC {theirs:#?}",
            peer.name
        );
        let tol = if peer.inch { 0.0001 * 25.4 } else { 0.0001 } + 1e-9;
        for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
            let what = format!("{} move {i}: device {a:?}, LinuxCNC {b:?}", peer.name);
            assert_eq!(a.g, b.g, "{what}");
            if peer.entry.contains(&i) {
                continue;
            }
            let z_too = !peer.x_only.contains(&i);
            assert!(
                (a.x - b.x).abs() <= tol && (!z_too || (a.z - b.z).abs() <= tol),
                "{what}"
            );
            match (a.centre, b.centre) {
                (Some(c), Some(d)) => {
                    assert!(
                        (c.0 - d.0).abs() <= tol && (c.1 - d.1).abs() <= tol,
                        "{what}"
                    )
                }
                (None, None) => {}
                _ => panic!("{what}"),
            }
        }
        agreed += 1;
        moves += ours.len();
    }
    eprintln!(
        "LinuxCNC rs274 and the device agree on {agreed} of {} programs ({moves} moves)",
        PEERS.len()
    );
}

/// Where the device departs from LinuxCNC on purpose: after a tool offset
/// is taken into effect (`G43`), LinuxCNC takes it up on the next move on
/// every axis, named or not; the device never moves an axis the block
/// does not name (`docs/gcode.md`), and takes the offset up when the axis
/// is next named. Both then stand at the same machine point.
#[test]
fn a_tool_offset_is_taken_up_only_by_an_axis_the_block_names() {
    let _one = rs274::one_at_a_time();
    if !rs274::available("the LinuxCNC comparison") {
        return;
    }
    let body = "G18 G21 G7 G90 G40\nG00 X10 Z-5\nT1 M6 G43\nG00 Z-1\nG00 X10 Z-2\nM2\n";
    let theirs = linuxcnc("G43 then Z alone", body, Some("X0.05 Z-0.1 Q2"));
    let ours = device("G43 then Z alone", body, Some("X=2.54 Z=-2.54 R=0.4 T=3"));
    assert_eq!(theirs.len(), 3, "{theirs:?}");
    assert_eq!(ours.len(), 3, "{ours:?}");
    let near = |a: f64, b: f64| (a - b).abs() < 1e-4;
    // The Z-only move: LinuxCNC moves X by the tool's 1.27 mm (X0.05 in,
    // on the radius); the device leaves X at the 5 mm radius of X10.
    assert!(near(theirs[1].x, 5.0 + 1.27), "{theirs:?}");
    assert!(near(ours[1].x, 5.0), "{ours:?}");
    assert!(near(theirs[1].z, ours[1].z), "{theirs:?} {ours:?}");
    // Named again, X takes the offset up: the same machine point.
    assert!(near(theirs[2].x, ours[2].x) && near(theirs[2].z, ours[2].z));
    assert!(near(ours[2].x, 5.0 + 1.27), "{ours:?}");
}

/// LinuxCNC's own example `nc_files/lathe_pawn.ngc` (X on the radius, as
/// LinuxCNC's default G8): both cut the same 91 moves up to its line 95,
/// and both refuse that line, an arc whose end is 0.6447 mm from the
/// centre its `K-2.428` gives, 2.428 mm from its start. The example is
/// wrong there; the device refuses the same line, before it moves.
#[test]
fn linuxcncs_pawn_example_is_cut_alike_up_to_its_broken_arc() {
    let _one = rs274::one_at_a_time();
    if !rs274::available("the LinuxCNC comparison") {
        return;
    }
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/linuxcnc/lathe_pawn.ngc"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<&str> = text.split('\n').collect();
    assert!(
        lines[94].contains("G02 X5.058 Z-16.482 K-2.428"),
        "{}",
        lines[94]
    );
    // Up to the arc, ended there: the same path.
    let head = format!("G8\n{}\nM2\n", lines[..94].join("\n"));
    let theirs = linuxcnc("lathe_pawn.ngc to line 94", &head, None);
    let ours = device("lathe_pawn.ngc to line 94", &head, None);
    assert_eq!(
        ours.len(),
        theirs.len(),
        "device {ours:#?}\nLinuxCNC {theirs:#?}"
    );
    assert_eq!(ours.len(), 91);
    for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
        let near = |p: f64, q: f64| (p - q).abs() <= 0.0001 + 1e-9;
        let centres = match (a.centre, b.centre) {
            (Some(c), Some(d)) => near(c.0, d.0) && near(c.1, d.1),
            (c, d) => c.is_none() && d.is_none(),
        };
        assert!(
            a.g == b.g && near(a.x, b.x) && near(a.z, b.z) && centres,
            "move {i}: device {a:?}, LinuxCNC {b:?}"
        );
    }
    // The whole file: LinuxCNC stops at line 95, naming both radii.
    let dir = std::env::temp_dir().join(format!("pawn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tool.tbl"), "T1 P1 X0 Z0 Q0\n").unwrap();
    let out = Command::new("rs274")
        .current_dir(&dir)
        .args(["-g", "-t", "tool.tbl", path])
        .output()
        .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!said.contains("PROGRAM_END"), "{said}");
    assert!(
        said.contains("Radius to end of arc differs from radius to start")
            && said.contains("r1=2.4280 r2=0.6447")
            && said.contains("G02 X5.058 Z-16.482 K-2.428"),
        "{said}"
    );
    // The device refuses the same line first, and moves nothing for it.
    let options = Options {
        dialect: Dialect::Iso,
        radius: true,
        optional_stop: false,
    };
    let report = host_sim::program::run(&text, options);
    let first = report.refused.first().expect("a refusal");
    assert_eq!(first.line, 95, "{:?}", report.refused);
    assert!(
        first.reply.contains("start and end radii differ"),
        "{}",
        first.reply
    );
}

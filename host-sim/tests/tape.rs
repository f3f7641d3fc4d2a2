//! `host-sim tape encode` as a user runs it: the tapes it prints read back,
//! verify clean and add up to the program's moves; what they cannot hold is
//! named with its line.

use core_nostd::calc::tape::{iso7_parity, Bck5Frame, FrameEnd, Iso7Block};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_host-sim");

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn host_sim(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// Writes a program to a file of its own and encodes it.
fn encode_text(name: &str, program: &str, args: &[&str]) -> Output {
    let path = std::env::temp_dir().join(format!("tape-{}-{name}.nc", std::process::id()));
    std::fs::write(&path, program).unwrap();
    let mut all = vec!["tape", "encode", path.to_str().unwrap()];
    all.extend_from_slice(args);
    let out = host_sim(&all);
    std::fs::remove_file(&path).unwrap();
    out
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).unwrap()
}

/// `tape verify` on a listing: its exit status and report.
fn verify(listing: &str, name: &str) -> (i32, String) {
    let path = std::env::temp_dir().join(format!("tape-{}-{name}.tape", std::process::id()));
    std::fs::write(&path, listing).unwrap();
    let out = host_sim(&["tape", "verify", path.to_str().unwrap()]);
    std::fs::remove_file(&path).unwrap();
    (out.status.code().unwrap(), stdout(&out))
}

fn frames(listing: &str) -> Vec<Bck5Frame> {
    listing
        .lines()
        .map(|l| Bck5Frame::parse(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

/// Σ of (Е, Д) impulses over frames.
fn sums(frames: &[Bck5Frame]) -> (i64, i64) {
    frames.iter().fold((0, 0), |(e, d), f| {
        (
            e + i64::from(f.carriage().map_or(0, |m| m.impulses())),
            d + i64::from(f.cross().map_or(0, |m| m.impulses())),
        )
    })
}

#[test]
fn bck5_of_every_example_verifies_clean_and_ends_where_the_program_does() {
    // The end of each program on the radius (mm) and Z (mm), read off its
    // last motion block; the tape runs from the machine's zero.
    let ends = [
        ("fanuc-grooves.nc", 30.0, 10.0),
        ("krylenko-fig12.nc", 60.0, -80.0),
        ("krylenko-fig17.nc", 5.0, 10.0),
        ("krylenko-fig22.nc", 22.5, -30.0),
    ];
    for (file, x_radius, z) in ends {
        let path = root().join("examples").join(file);
        let out = host_sim(&["tape", "encode", path.to_str().unwrap(), "--format", "bck5"]);
        assert_eq!(out.status.code(), Some(0), "{file}: {}", stderr(&out));
        let listing = stdout(&out);
        let (code, report) = verify(&listing, file);
        assert_eq!(code, 0, "{file}: {report}\n{listing}");
        assert!(report.contains("findings    0"), "{report}");
        let f = frames(&listing);
        assert!(f.iter().all(Bck5Frame::check_ok));
        assert!(f
            .iter()
            .enumerate()
            .all(|(i, f)| usize::from(f.number()) == i));
        assert_eq!(f.last().unwrap().end(), FrameEnd::Program);
        // The frames before Я bring the tool back, one axis at a time (out
        // in X, along Z, in X: never diagonally across the part); up to them
        // the impulses add up to the program's end: 0.01 mm on Е, 0.005 mm
        // on Д.
        let n = f.len();
        let want = (
            (z / 0.01_f64).round() as i64,
            (x_radius / 0.005_f64).round() as i64,
        );
        let k = (1..=3)
            .find(|&k| sums(&f[..n - 1 - k]) == want)
            .unwrap_or_else(|| panic!("{file}: no end at {want:?}\n{listing}"));
        for back in &f[n - 1 - k..n - 1] {
            let (e, d) = (
                back.carriage().map_or(0, |m| m.impulses()),
                back.cross().map_or(0, |m| m.impulses()),
            );
            assert!(e == 0 || d == 0, "{file}: a diagonal return\n{listing}");
        }
        assert_eq!(sums(&f), (0, 0));
        assert!(
            stderr(&out).contains("returned to its start"),
            "{}",
            stderr(&out)
        );
    }
}

/// The seed's valik (Kosenko Tables 21–22) as a Fanuc program in
/// increments: W the carriage (Table 21's x), U the cross slide on the
/// diameter (twice Table 21's y), 550 rpm, feeds 0.25, 0.1 and 0.05 mm/rev.
const VALIK: &str = "\
G21 G18 G99
T0101
G00 W-124 U-300 S550 M03
W-2.21 M08
G01 U48 F0.25
G00 W1.21
U-3.68
G01 W-30.7 F0.25
W-29.8 U14.04
W-20
G00 U5.64
W205.5 U236 M05 M09
T4200
G00 W-181.11 U-180 M03 M08
G01 U-8.1 F0.1
G00 U22.1
W-50
G01 U-10.16 F0.1
G00 U16.16
W231.11 U160 M05 M09
T0202
G00 W-171 U-242.06 M03 M08
G01 W-38 F0.05
G00 U6.06
W209 U236 M05 M09
T0303
G00 W-130 U-256.06 M03 M08
G01 W-29 F0.05
G00 U4.06
W159 U252 M05 M09
M30
";

#[test]
fn the_seeds_valik_encodes_to_its_printed_frames_where_they_are_right() {
    let out = encode_text("valik", VALIK, &["--format", "bck5", "--dialect", "fanuc"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let listing = stdout(&out);
    let (code, report) = verify(&listing, "valik");
    assert_eq!(code, 0, "{report}\n{listing}");
    let lines: Vec<&str> = listing.lines().collect();
    // The seed's frames (its check-digit example К002 among them); К004
    // with 24 mm as Table 21 has it, where the seed printed Д514800.
    for want in [
        "7К000Е000000Д000000П00Ш00С00В00Н",
        "5К001Е000000Д000000П00Ш00С01В00Н",
        "2К002Е212400Д630000П75Ш26Н",
        "6К003Е600221Д000000П54В01Н",
        "9К004Е000000Д504800П44Н",
        "5К005Е500121Д000000П54Н",
        // К007 with the check digit it needs (the seed printed 8).
        "7К007Е603070Д000000П44Н",
        "7К008Е602980Д101404П44Н",
        "3К009Е602000Д000000П44Н",
        "1К011Е120550Д523600П75Ш00В00Н",
        "8К012Е000000Д000000П00Ш00С42В00Н",
        "0К013Е618111Д218000П75Ш26В01Н",
        "3К014Е000000Д600810П41Н",
        "1К017Е000000Д601016П41Н",
        "3К020Е000000Д000000П00Ш00С02В00Н",
        "3К022Е603800Д000000П31Н",
        "7К025Е000000Д000000П00Ш00С03В00Н",
        "8К027Е602900Д000000П31Н",
        "4К030Я",
    ] {
        let number: usize = want[3..6].parse().unwrap();
        assert_eq!(lines[number], want, "К{number:03}\n{listing}");
    }
    assert_eq!(lines.len(), 31);
    // No frame added: every tool of the valik returns by itself.
    assert!(!stderr(&out).contains("returned"), "{}", stderr(&out));
    assert!(stderr(&out).contains("gear range II: change gears A=53 B=81"));
}

#[test]
fn iso7_blocks_read_back_and_their_feed_is_s_times_1000_over_l() {
    // 0.05 mm/rev at 710 rpm (a speed of Table 25): S = 35.5 mm/min.
    let program = "G21 G18 G99\nT0101\nG97 S710 M03\nG00 X50 Z0\n\
                   G01 Z-30.1 F0.05\nG01 X56 Z-35\nG02 X66 Z-40 R5\nG00 X80\nM05\nM30\n";
    let out = encode_text("iso", program, &["--format", "iso7"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let listing = stdout(&out);
    let mut lines = listing.lines();
    assert_eq!(lines.next(), Some("%"));
    let blocks: Vec<Iso7Block> = lines.map(|l| Iso7Block::parse(l).unwrap()).collect();
    let s = 0.05 * 710.0;
    // N002: Z −30.1 mm = −3010 impulses at 0.01 mm.
    let n2 = blocks[1];
    assert_eq!((n2.g(), n2.x(), n2.z()), (Some(1), None, Some(-3010)));
    assert_eq!(n2.f(), Some((s * 1000.0 / 30.1_f64).round() as u32));
    assert_eq!(n2.f(), Some(1179));
    // N003: 3 mm on the radius (600 impulses at 0.005) and −4.9 mm.
    let n3 = blocks[2];
    assert_eq!((n3.x(), n3.z()), (Some(600), Some(-490)));
    let l = 3.0_f64.hypot(4.9);
    assert_eq!(n3.f(), Some((s * 1000.0 / l).round() as u32));
    // N004: the arc, R 5 clockwise from below its centre to its left: the
    // centre 5 mm out along X from the start, I 1000 impulses, K 0; F
    // over R.
    let n4 = blocks[3];
    assert_eq!((n4.g(), n4.x(), n4.z()), (Some(2), Some(1000), Some(-500)));
    assert_eq!((n4.i(), n4.k()), (Some(1000), Some(0)));
    assert_eq!(n4.f(), Some((s * 1000.0 / 5.0).round() as u32));
    // The moves add up to the end point: X 40 mm radius, Z −40 mm.
    let x: i32 = blocks.iter().filter_map(Iso7Block::x).sum();
    let z: i32 = blocks.iter().filter_map(Iso7Block::z).sum();
    assert_eq!((x, z), (8000, -4000));
    // Table 25: 710 rpm is S44 with the motor at 1400 rpm (M12); tool 1
    // is the front holder's T500.
    assert_eq!(blocks[0].s(), Some(44));
    assert_eq!(blocks[0].t(), Some(500));
    assert_eq!(blocks[0].m(), [3, 6, 12]);
    assert_eq!(blocks.last().unwrap().m(), [5, 30]);
    let (code, _) = verify(&listing, "iso");
    assert_eq!(code, 0);

    // The rows of holes read back to the same text, each with even holes.
    let punched = encode_text("iso-punch", program, &["--format", "iso7", "--punch"]);
    assert_eq!(punched.status.code(), Some(0));
    let rows = stdout(&punched);
    let text = host_sim::tape::read_rows(&rows).unwrap();
    assert_eq!(text, listing);
    for row in rows.lines().skip(1) {
        assert_eq!(row.matches('o').count() % 2, 0, "{row}");
        let byte = u8::from_str_radix(&row[..2], 16).unwrap();
        assert_eq!(iso7_parity(byte & 0x7F), Some(byte), "{row}");
    }
    // `%` is 0x25: three holes, so track 8 too.
    assert!(rows
        .lines()
        .nth(1)
        .unwrap()
        .starts_with("A5   o . o . . | o . o"));
}

#[test]
fn what_the_tape_cannot_hold_is_named_with_its_line_and_nothing_is_printed() {
    let cases: [(&str, &str, &str, &str); 5] = [
        (
            "G21 G18 G98\nT0101\nG00 X1100 Z0\nM30\n",
            "bck5",
            "line 3:",
            "110000 impulses",
        ),
        (
            "G21 G18 G98\nG00 X20 Z0\nG03 X20 Z-20 R10 F100\nM30\n",
            "iso7",
            "line 3:",
            "quadrant",
        ),
        (
            "G21 G18 G98\nT0101\nG00 X20 Z0\nG01 Z-20 F3000\nM30\n",
            "bck5",
            "line 4:",
            "feed codes",
        ),
        (
            "G21 G18 G98\nG00 X20 Z0\nG76 P010060 Q100 R.05\nM30\n",
            "bck5",
            "line 3:",
            "refused",
        ),
        (
            "G21 G18 G98\nT0909\nG00 X20 Z0\nM30\n",
            "iso7",
            "line 2:",
            "tool 9",
        ),
    ];
    for (i, (program, format, line, what)) in cases.iter().enumerate() {
        let out = encode_text(
            &format!("bad{i}"),
            program,
            &["--format", format, "--dialect", "fanuc"],
        );
        assert_eq!(out.status.code(), Some(1), "{program}");
        assert!(stdout(&out).is_empty(), "{}", stdout(&out));
        let e = stderr(&out);
        assert!(e.contains(line) && e.contains(what), "{program}: {e}");
    }
    // An unreadable file and bad arguments: 2.
    let out = host_sim(&["tape", "encode", "/nonexistent/part.nc", "--format", "bck5"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("cannot read"));
    let path = root().join("examples/krylenko-fig12.nc");
    let out = host_sim(&["tape", "encode", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--format"));
    let out = host_sim(&[
        "tape",
        "encode",
        path.to_str().unwrap(),
        "--format",
        "bck5",
        "--punch",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stdout(&out).is_empty());
}

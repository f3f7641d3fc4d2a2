//! LinuxCNC's `G76` against LinuxCNC's standalone interpreter `rs274`: for
//! random cycles (pitch, crest, depths, degression, compound angle, spring
//! passes, tapers, both directions along Z, inside and outside), every
//! move of `core_nostd::thread` equals `rs274`'s canonical move to 0.0001
//! mm, in order, rapid for rapid and synchronised for synchronised, with
//! the same advance per revolution along the path.
//!
//! Skipped with a message where `rs274` is missing, except under CI (`CI`
//! set), where a missing `rs274` fails.

use core_nostd::thread::{G76Error, ThreadMove, G76};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::process::Command;
use tests::rs274::{self, args};

/// A canonical move: rapid or fed, its end (X radius, Z, mm) and, when
/// synchronised, the path's advance per revolution.
#[derive(Clone, Copy, Debug)]
struct Move {
    rapid: bool,
    x: f64,
    z: f64,
    feed: f64,
}

/// `rs274`'s moves after the `G0` to the start.
fn linuxcnc(program: &str, call: usize) -> Vec<Move> {
    let dir = std::env::temp_dir().join(format!("g76-peer-{}-{call}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ngc = dir.join("thread.ngc");
    std::fs::write(&ngc, program).unwrap();
    let out = Command::new("rs274")
        .arg("-g")
        .arg(&ngc)
        .current_dir(&dir)
        .output()
        .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let mut moves = Vec::new();
    let mut feed = 0.0;
    for line in text.lines() {
        // `   16 N..... NAME(a, b, …)`
        let call = line.split_once("N..... ").map_or("", |(_, c)| c.trim());
        if call.starts_with("START_SPEED_FEED_SYNC(") {
            feed = args(call)[0];
        } else if call.starts_with("STRAIGHT_TRAVERSE(") || call.starts_with("STRAIGHT_FEED(") {
            let a = args(call);
            moves.push(Move {
                rapid: call.starts_with("STRAIGHT_TRAVERSE"),
                x: a[0],
                z: a[2],
                feed,
            });
        }
    }
    assert!(
        !moves.is_empty(),
        "rs274 ran nothing ({}):\n{program}\n{text}{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    // The first is the G0 to the start.
    moves.remove(0);
    moves
}

/// The core's moves, as canonical moves: a synchronised move's lead along
/// its longer axis turned into the advance along its path; lengths in
/// units of `unit` mm (1, or 25.4 for an inch program).
fn device(c: &G76, unit: f64) -> Vec<Move> {
    let scale = 1e7 * unit;
    let mut at = c.start;
    c.moves()
        .map(|m| {
            let (rapid, to, lead) = match m {
                ThreadMove::Rapid(to) => (true, to, 0),
                ThreadMove::Cut { to, lead } => (false, to, lead),
            };
            let (dx, dz) = ((to[0] - at[0]) as f64, (to[1] - at[1]) as f64);
            at = to;
            let along = dx.abs().max(dz.abs());
            let feed = if along > 0.0 {
                lead as f64 * dx.hypot(dz) / along / scale
            } else {
                0.0
            };
            Move {
                rapid,
                x: to[0] as f64 / scale,
                z: to[1] as f64 / scale,
                feed,
            }
        })
        .collect()
}

/// A length of `digits` decimals, in 10⁻⁷ mm, from mm.
fn mm(v: f64, digits: i32) -> i64 {
    let unit = 10f64.powi(digits);
    ((v * unit).round() / unit * 1e7).round() as i64
}

fn word(v: i64) -> String {
    format!("{:.4}", v as f64 / 1e7)
}

fn program(c: &G76) -> String {
    format!(
        "g21 g18\ns500 m3\ng0 x{} z{}\ng76 p{} z{} i{} j{} k{} r{:.4} q{:.1} h{} e{} l{}\nm2\n",
        word(c.start[0]),
        word(c.start[1]),
        word(c.pitch),
        word(c.z_end),
        word(c.crest),
        word(c.first),
        word(c.full),
        f64::from(c.degression) / 1e4,
        c.angle as f64 / 3600.0,
        c.spring,
        word(c.taper),
        c.ends,
    )
}

fn random_cycle(rng: &mut ChaCha8Rng) -> G76 {
    let z0 = mm(rng.random_range(-5.0..5.0), 4);
    let length = mm(rng.random_range(8.0..60.0), 4);
    let toward = if rng.random_bool(0.7) { -1 } else { 1 };
    let first = mm(rng.random_range(0.02..0.4), 4);
    let degression = match rng.random_range(0..4) {
        0 => 10_000,
        1 => 15_000,
        2 => 20_000,
        _ => rng.random_range(10_000..30_000),
    };
    let angle = match rng.random_range(0..3) {
        0 => 0,
        1 => 29 * 3600 + 1800,
        _ => rng.random_range(0..450) * 360,
    };
    let ends = rng.random_range(0..4u8);
    G76 {
        start: [mm(rng.random_range(2.0..30.0), 4), z0],
        z_end: z0 + toward * length,
        pitch: mm(rng.random_range(0.2..4.0), 4),
        crest: mm(rng.random_range(0.1..2.0), 4) * if rng.random_bool(0.7) { -1 } else { 1 },
        first,
        full: first + mm(rng.random_range(0.05..2.0), 4),
        degression,
        angle,
        spring: rng.random_range(0..4),
        // `E0` with an `L` cuts straight.
        taper: if ends == 0 || rng.random_bool(0.1) {
            0
        } else {
            mm(rng.random_range(0.2..4.0), 4)
        },
        ends,
    }
}

/// The core's cycle `c` against `rs274` on `program`, whose lengths are in
/// units of `unit` mm: to 0.0001 of them.
fn compare(c: &G76, program: &str, call: usize, unit: f64) {
    let theirs = linuxcnc(program, call);
    let ours = device(c, unit);
    assert_eq!(
        ours.len(),
        theirs.len(),
        "{program}moves: ours {ours:#?}\nrs274 {theirs:#?}"
    );
    for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
        let near = |p: f64, q: f64| (p - q).abs() <= 1e-4 + 1e-9;
        assert!(
            a.rapid == b.rapid && near(a.x, b.x) && near(a.z, b.z),
            "{program}move {i}: ours {a:?}, rs274 {b:?}"
        );
        if !a.rapid {
            assert!(
                near(a.feed, b.feed),
                "{program}move {i}: ours {a:?}, rs274 {b:?}"
            );
        }
    }
}

#[test]
fn the_g76_passes_are_linuxcncs() {
    let _one = rs274::one_at_a_time();
    if !rs274::available("the G76 comparison") {
        return;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(76);
    let (mut compared, mut moves, mut refused) = (0, 0, 0);
    // The corpus's cycles (latheeasystep's Test_Gewinde.ngc, LinuxCNC's
    // g76.ngc and g76only.ngc read in mm, X radius), then random ones.
    let corpus = [
        (
            15_000_000,
            -290_000_000,
            -4_600_000,
            900_000,
            9_200_000,
            15_000,
            1,
            0,
            0,
        ),
        (
            500_000, -5_000_000, -750_000, 150_000, 450_000, 20_000, 3, 0, 0,
        ),
        (
            500_000, -5_000_000, -750_000, 80_000, 450_000, 20_000, 3, 500_000, 2,
        ),
    ];
    let mut cycles: Vec<G76> = corpus
        .iter()
        .map(
            |&(pitch, z_end, crest, first, full, degression, spring, taper, ends)| G76 {
                start: [80_000_000, 20_000_000],
                z_end,
                pitch,
                crest,
                first,
                full,
                degression,
                angle: 29 * 3600 + 1800,
                spring,
                taper,
                ends,
            },
        )
        .collect();
    cycles.extend((0..60).map(|_| random_cycle(&mut rng)));
    for (call, c) in cycles.iter().enumerate() {
        match c.check() {
            Ok(()) => {
                compare(c, &program(c), call, 1.0);
                compared += 1;
                moves += c.moves().count();
            }
            Err(G76Error::TooShort | G76Error::TooManyPasses) => refused += 1,
            Err(e) => panic!("{c:?}: {e:?}"),
        }
    }
    eprintln!(
        "G76: {compared} cycles ({moves} moves) equal to rs274's; {refused} refused before a move"
    );
    assert!(compared >= 50, "only {compared} cycles compared");
}

/// A word's value as written in a block (`P1.5000` → 1.5), if it has it.
fn word_of(block: &str, letter: char) -> Option<f64> {
    let upper = block.to_ascii_uppercase();
    let at = upper.find(letter)?;
    let rest = &upper[at + 1..];
    let end = rest
        .find(|ch: char| !(ch.is_ascii_digit() || ch == '.' || ch == '-'))
        .unwrap_or(rest.len());
    rest[..end].parse().ok()
}

/// The `G76` lines of programs nobody here wrote, as written in their
/// files, from where each file stands the tool before them, in each file's
/// units and X mode: LinuxCNC's own `g76.ngc` and `g76only.ngc` (inch, X
/// on the radius, the second with an exit taper), latheeasystep's
/// `Test_Gewinde.ngc` and `Test_Gewinde_innen.ngc` (mm, X on the diameter,
/// outside and inside).
#[test]
fn the_corpus_g76_lines_cut_as_linuxcnc_cuts_them() {
    let _one = rs274::one_at_a_time();
    if !rs274::available("the G76 comparison") {
        return;
    }
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/data/");
    // (file, header, the tool's place before the cycle as the file's
    // moves leave it, inch, diameter)
    let cases = [
        ("linuxcnc/g76.ngc", "g20 g18", "g0 x.2 z.2", true, false),
        ("linuxcnc/g76only.ngc", "g20 g18", "g0z.2x.2", true, false),
        (
            "latheeasystep/Test_Gewinde.ngc",
            "G18 G7 G90 G21",
            "G0 X10.000 Z5.000",
            false,
            true,
        ),
        (
            "latheeasystep/Test_Gewinde_innen.ngc",
            "G18 G7 G90 G21",
            "G0 X8.160 Z5.000",
            false,
            true,
        ),
    ];
    for (call, (file, header, approach, inch, diameter)) in cases.into_iter().enumerate() {
        let text = std::fs::read_to_string(format!("{data}{file}")).unwrap();
        let line = text
            .lines()
            .find(|l| l.trim_start().to_ascii_uppercase().starts_with("G76"))
            .unwrap();
        let unit = if inch { 25.4 } else { 1.0 };
        let len = |v: f64| (v * unit * 1e7).round() as i64;
        let radius = |v: f64| len(if diameter { v / 2.0 } else { v });
        let w = |l: char| word_of(line, l);
        let a = |l: char| word_of(approach, l).unwrap();
        let c = G76 {
            start: [radius(a('X')), len(a('Z'))],
            z_end: len(w('Z').unwrap()),
            pitch: len(w('P').unwrap()),
            crest: radius(w('I').unwrap()),
            first: radius(w('J').unwrap()),
            full: radius(w('K').unwrap()),
            degression: (w('R').unwrap_or(1.0) * 1e4).round() as u32,
            angle: (w('Q').unwrap_or(0.0) * 3600.0).round() as i64,
            spring: w('H').unwrap_or(0.0) as u32,
            taper: len(w('E').unwrap_or(0.0)),
            ends: w('L').unwrap_or(0.0) as u8,
        };
        assert_eq!(c.check(), Ok(()), "{file}: {line}");
        let program = format!("{header}\ns500 m3\n{approach}\n{line}\nm2\n");
        compare(&c, &program, 100 + call, unit);
        eprintln!(
            "{file}: {line}: {} moves equal to rs274's",
            c.moves().count()
        );
    }
}

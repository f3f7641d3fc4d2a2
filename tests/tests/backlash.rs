//! Backlash compensation (`docs/motion.md` §7): the take-up blocks timed
//! against the reference event by event, the registers never counting
//! them, and the simulated lathe's carriage where the registers say after
//! a thousand reversals, a hold, a reset and a restart.

use host_sim::board::{Board, Pace};
use host_sim::device::LocalDevice;
use host_sim::link::Client;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tests::{ask, carriage, one, TimedPair};

/// A thousand reversals on both axes, feeds and rapids, some blocks on
/// one axis and some on both, with look-ahead: every event (the take-ups'
/// included) on the reference's tick, and the registers those of the
/// program's points alone.
#[test]
fn take_ups_are_timed_as_the_reference_and_the_registers_never_count_them() {
    let mut p = TimedPair::new().with_backlash(["0.08", "0.15"]);
    let mut rng = ChaCha8Rng::seed_from_u64(0xBAC1);
    let (mut x, mut z) = (0i64, 0i64);
    let mut reversals = 0;
    let (mut dir_x, mut dir_z) = (0i64, 0i64);
    let mut impulses = 0u64;
    let mut events = 0u64;
    while reversals < 1_000 {
        // Short strokes either way, off the impulse grid at times.
        let step = |rng: &mut ChaCha8Rng| {
            let mm = rng.random_range(1..=40) * 500_000i64;
            let off = if rng.random_bool(0.2) {
                rng.random_range(1..5_000) * 10
            } else {
                0
            };
            if rng.random_bool(0.5) {
                mm + off
            } else {
                -mm - off
            }
        };
        let (nx, nz) = match rng.random_range(0..3) {
            0 => (x + step(&mut rng), z),
            1 => (x, z + step(&mut rng)),
            _ => (x + step(&mut rng), z + step(&mut rng)),
        };
        let feed = match rng.random_range(0..3) {
            0 => None,
            1 => Some("600"),
            _ => Some("97.5"),
        };
        let before = p.registers;
        p.to(nx, nz, feed);
        let d = [p.registers[0] - before[0], p.registers[1] - before[1]];
        impulses += d[0].unsigned_abs().max(d[1].unsigned_abs());
        for (dir, d) in [(&mut dir_x, d[0]), (&mut dir_z, d[1])] {
            if d != 0 {
                reversals += i32::from(*dir == -d.signum());
                *dir = d.signum();
            }
        }
        (x, z) = (nx, nz);
        if rng.random_bool(0.05) {
            events += p.sync().0;
        }
    }
    events += p.sync().0;
    // The take-ups' events are there, beyond the program's own.
    assert!(
        events > impulses + 900 * 8,
        "{events} events, {impulses} impulses"
    );
}

/// With no play set nothing is taken up: the events are the program's own.
#[test]
fn no_play_no_take_up() {
    let mut p = TimedPair::new().with_backlash(["0", "0"]);
    p.to(10_000_000, -10_000_000, Some("300"));
    p.to(0, 0, None);
    p.to(10_000_000, -10_000_000, Some("300"));
    // 200 + 200 + 200 events: the longer axis' (X, 0.005 mm).
    assert_eq!(p.sync().0, 600);
}

/// Bad values are refused by name and change nothing.
#[test]
fn a_play_out_of_range_is_refused_by_name() {
    let mut dev = LocalDevice::recording();
    assert_eq!(one(&mut dev, "BACKLASH"), "OK X=0 Z=0 NX=0 NZ=0");
    for (bad, word) in [
        ("BACKLASH X=5.1", "X"),
        ("BACKLASH Z=-0.1", "Z"),
        ("BACKLASH X=0.1 Z=abc", "Z"),
    ] {
        let r = one(&mut dev, bad);
        assert!(r.starts_with(&format!("ERR VALUE {word}")), "{bad}: {r}");
    }
    assert_eq!(one(&mut dev, "BACKLASH"), "OK X=0 Z=0 NX=0 NZ=0");
    // X on the radius at 0.005 mm: 0.0125 mm is 2.5 impulses, 3 (half away).
    assert_eq!(
        one(&mut dev, "BACKLASH X=0.0125 Z=0.3"),
        "OK X=0.0125 Z=0.3 NX=3 NZ=30"
    );
}

fn lathe(pace: Pace) -> (Board, Client) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("examples/machine.toml")).expect("file");
    let (board, mut c) = tests::lathe_board_paced(&text, "CFG DIAM=0\n", false, pace);
    c.drain();
    (board, c)
}

/// Where the registers of the steps issued put the carriages, mm (X
/// radius at 0.005, Z at 0.01); `POS` agrees.
fn registers_mm(c: &mut Client) -> (f64, f64) {
    let [status, pos] = ["STATUS", "POS"].map(|r| {
        let reply = ask(c, r);
        let v = |k| reply.value(k).and_then(|v| v.parse::<f64>().ok()).expect(k);
        (v("PX") * 0.005, v("PZ") * 0.01)
    });
    assert_eq!(status, pos, "STATUS and POS");
    status
}

/// A zig-zag on the simulated lathe (play 0.08 mm on X, 0.15 on Z, as the
/// machine file has): with the play set, the carriage is where the
/// registers say after every stroke; without, it is off by the play.
#[test]
fn the_carriage_is_where_the_registers_say_after_a_thousand_reversals() {
    let (board, mut c) = lathe(Pace::Unpaced);
    // Without compensation: a stroke towards plus leaves Z behind.
    assert!(ask(&mut c, "MOVE X=1 Z=-3 F=2000").is_ok());
    assert!(ask(&mut c, "MOVE X=2 Z=-2 F=2000").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
    let off = carriage(&board);
    let (rx, rz) = registers_mm(&mut c);
    assert!((off.1 - (rz - 0.15)).abs() < 1e-9, "{off:?} vs {rz}");
    assert!((off.0 - (rx - 0.08)).abs() < 1e-9, "{off:?} vs {rx}");
    let set = ask(&mut c, "BACKLASH X=0.08 Z=0.15");
    assert_eq!(set.last, "OK X=0.08 Z=0.15 NX=16 NZ=15", "{set:?}");
    // The controller takes each motor as having last turned towards minus
    // (as at power-on): from an axis' first stroke that way on, it is
    // exact.
    let mut rng = ChaCha8Rng::seed_from_u64(27);
    let (mut x, mut z) = (2.0f64, -2.0f64);
    for i in 0..1_000 {
        // Alternately towards minus and plus, on one axis or both.
        let sign = if i % 2 == 0 { -1.0 } else { 1.0 };
        let dx = sign * f64::from(rng.random_range(1..200)) * 0.005;
        let dz = sign * f64::from(rng.random_range(1..200)) * 0.01;
        match rng.random_range(0..3) {
            0 => x += dx,
            1 => z += dz,
            _ => (x, z) = (x + dx, z + dz),
        }
        let f = if rng.random_bool(0.5) { " F=1500" } else { "" };
        let r = ask(&mut c, &format!("MOVE X={x:.3} Z={z:.2}{f}"));
        assert!(r.is_ok(), "{r:?}");
        if i % 97 == 0 || i == 999 {
            assert!(ask(&mut c, "SYNC").is_ok());
            let (cx, cz) = carriage(&board);
            let (rx, rz) = registers_mm(&mut c);
            // Once each axis has turned towards minus, it is exact.
            if i > 0 {
                assert!(
                    (cx - rx).abs() < 1e-9 && (cz - rz).abs() < 1e-9,
                    "stroke {i}: carriage {cx} {cz}, registers {rx} {rz}"
                );
            }
        }
    }
}

/// A program stopped by a hold and a resume, then a reset mid-stroke, then
/// run on from where the registers say: the carriage ends where they do.
#[test]
fn a_hold_a_reset_and_a_restart_leave_nothing_behind() {
    let (board, mut c) = lathe(Pace::Wall(1.0));
    assert!(ask(&mut c, "BACKLASH X=0.08 Z=0.15").is_ok());
    // Taken up towards minus on both axes first: the carriages exact.
    assert!(ask(&mut c, "MOVE X=-0.5 Z=-0.5 F=1000").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
    let strokes = |c: &mut Client, from: usize, n: usize| {
        for i in from..from + n {
            let (x, z) = if i % 2 == 0 { (2.0, -2.0) } else { (0.5, -3.5) };
            c.write_raw(format!("MOVE X={x} Z={z} F=300\n").as_bytes())
                .expect("write");
        }
    };
    strokes(&mut c, 0, 12);
    // A flush starts them (the window is longer than the program).
    c.write_raw(b"SYNC\n").expect("write");
    std::thread::sleep(Duration::from_millis(700));
    c.write_raw(&[0x82]).expect("hold");
    std::thread::sleep(Duration::from_millis(400));
    c.write_raw(&[0x81]).expect("resume");
    std::thread::sleep(Duration::from_millis(900));
    c.write_raw(b"\x18").expect("reset");
    // The replies to the strokes and the reset's notices: drained once the
    // axes rest.
    let deadline = Instant::now() + Duration::from_secs(30);
    std::thread::sleep(Duration::from_millis(500));
    c.drain();
    loop {
        assert!(Instant::now() < deadline, "the reset did not come to rest");
        let s = ask(&mut c, "STATUS");
        if s.value("Q") == Some("0") && s.value("STATE") != Some("RUN") {
            if s.value("STATE") == Some("ALARM") {
                assert!(ask(&mut c, "UNLOCK").is_ok());
            }
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let (cx, cz) = carriage(&board);
    let (rx, rz) = registers_mm(&mut c);
    // Stopped mid-stroke, maybe mid-take-up: within the play, no more.
    assert!((cx - rx).abs() <= 0.08 + 1e-9 && (cz - rz).abs() <= 0.15 + 1e-9);
    // Run on: the next strokes take up what remains.
    assert!(ask(&mut c, "MOVE X=1 Z=-1 F=1000").is_ok());
    assert!(ask(&mut c, "MOVE X=0 Z=-2 F=1000").is_ok());
    assert!(ask(&mut c, "SYNC").is_ok());
    let (cx, cz) = carriage(&board);
    let (rx, rz) = registers_mm(&mut c);
    assert!(
        (cx - rx).abs() < 1e-9 && (cz - rz).abs() < 1e-9,
        "carriage {cx} {cz}, registers {rx} {rz}"
    );
}

//! The handwheel on the simulated machine (`docs/inputs.md` §11): a lathe
//! from a machine file behind the simulated board, the wheel turned as an
//! operator turns it, in bursts while the carriage still moves.

use host_sim::board::Board;
use host_sim::link::Client;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tests::{ask, carriage};

fn lathe() -> (Board, Client) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("examples/machine.toml")).expect("file");
    let (board, mut c) = tests::lathe_board(&text, "CFG DIAM=0\nINPUT USED=X-,X+,Z-,Z+\n", false);
    c.drain();
    (board, c)
}

/// Waits for the axes to come to rest with nothing queued (`STATUS`, which
/// leaves the wheel's moves going), and returns the registers.
fn at_rest(c: &mut Client) -> (i64, i64) {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        assert!(Instant::now() < deadline, "the wheel's moves did not end");
        std::thread::sleep(Duration::from_millis(100));
        let s = ask(c, "STATUS");
        if s.last.contains("STATE=IDLE") && s.value("Q") == Some("0") {
            let v = |k| s.value(k).and_then(|v| v.parse().ok()).expect(k);
            return (v("PX"), v("PZ"));
        }
    }
}

/// Turned both ways in bursts, faster than the carriage follows: Z ends
/// exactly the counts' sum times the scale away, X never moves, and the
/// carriage is there (within the leadscrew's play).
#[test]
fn the_wheel_moves_z_by_exactly_its_counts_turned_in_bursts() {
    let (board, mut c) = lathe();
    let set = ask(&mut c, "WHEEL AXIS=Z SCALE=10 FEED=200");
    assert_eq!(set.last, "OK AXIS=Z SCALE=10 FEED=200", "{set:?}");
    let before = at_rest(&mut c);
    let start = carriage(&board);
    // Towards the chuck: Z's plus switch is 4 mm away.
    let turns = [-5, -3, -8, 2, -1, -1, -1, 6, -12, -4, 1, -7, -2, -2, 3, -9];
    for n in turns {
        board.wheel(n);
        std::thread::sleep(Duration::from_millis(15));
    }
    let sum: i32 = turns.iter().sum();
    let after = at_rest(&mut c);
    assert_eq!(after, (before.0, before.1 + i64::from(sum) * 10));
    let end = carriage(&board);
    assert_eq!(end.0, start.0, "X never moved");
    // 0.01 mm per Z impulse.
    let moved = end.1 - start.1;
    assert!(
        (moved - f64::from(sum) * 0.1).abs() < 0.31,
        "moved {moved} mm for {sum} counts × 10"
    );
    // A request ends the wheel's run; the wheel goes on from rest after it.
    assert!(ask(&mut c, "SYNC").is_ok());
    board.wheel(4);
    assert_eq!(
        at_rest(&mut c),
        (before.0, before.1 + i64::from(sum + 4) * 10)
    );
}

/// While a program's move runs, the wheel moves nothing and says so once;
/// the program's move ends exactly where it was sent.
#[test]
fn the_wheel_moves_nothing_while_a_program_runs() {
    let (_board, mut c) = lathe();
    assert!(ask(&mut c, "WHEEL AXIS=X SCALE=100").is_ok());
    let cut = ask(&mut c, "G01 Z-20 F300");
    assert!(cut.is_ok(), "{cut:?}");
    // A quiet link starts it; 4 s of motion.
    std::thread::sleep(Duration::from_millis(400));
    board_turns(&_board, &[3, 3]);
    let line = c.read_line().expect("the wheel's notice");
    assert_eq!(
        host_sim::link::words_value(&line, "IGNORED"),
        Some("RUN"),
        "{line}"
    );
    let sync = ask(&mut c, "SYNC");
    assert!(sync.is_ok(), "{sync:?}");
    let pos = ask(&mut c, "POS");
    assert_eq!(pos.value("PZ"), Some("-2000"), "{pos:?}");
    assert_eq!(pos.value("PX"), Some("0"), "{pos:?}");
}

fn board_turns(board: &Board, turns: &[i32]) {
    for &n in turns {
        board.wheel(n);
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Homed, with soft limits: the wheel runs X up to the end of its travel
/// and no farther, however far it is turned.
#[test]
fn the_wheel_stops_at_the_end_of_the_travel_once_homed() {
    let (_board, mut c) = lathe();
    let set = ask(
        &mut c,
        "HOMING AXES=X HOMEX=70 TRAVELX=77 SEEK=3000 LOCATE=300 PULLOFF=1 SOFT=1",
    );
    assert!(set.is_ok(), "{set:?}");
    assert!(ask(&mut c, "HOME").is_ok());
    assert!(ask(&mut c, "WHEEL AXIS=X SCALE=100 FEED=3000").is_ok());
    board_turns(&_board, &[-10]);
    // 1000 impulses of 0.005 mm: 5 mm below home.
    assert_eq!(at_rest(&mut c).0, 14_000 - 1_000);
    board_turns(&_board, &[40]);
    assert_eq!(at_rest(&mut c).0, 14_000, "up to the travel's end");
    // Turned on at the end: nothing moves, and the wheel says why once.
    board_turns(&_board, &[5]);
    let line = c.read_line().expect("the wheel's notice");
    let body = host_sim::link::check_reply_line(&line).expect("checksum");
    assert_eq!(body, "!WHEEL IGNORED=TRAVEL COUNTS=5");
    board_turns(&_board, &[-3]);
    assert_eq!(at_rest(&mut c).0, 14_000 - 300, "back from the end");
}

/// A pendant with its own selectors (the panel's `MPG`): the axis and
/// scale it selects are the wheel's, kept as `WHEEL` keeps them, and the
/// axis moves by the counts times that scale; a malformed line is refused
/// by name and turns nothing.
#[test]
fn a_pendant_with_its_own_selectors_moves_the_axis_it_selects() {
    let (board, mut c) = lathe();
    let before = at_rest(&mut c);
    assert_eq!(board.panel_line("MPG Z COUNTS=-7 SCALE=10"), Ok(None));
    assert_eq!(at_rest(&mut c), (before.0, before.1 - 70));
    let w = ask(&mut c, "WHEEL");
    assert_eq!(w.value("AXIS"), Some("Z"), "{w:?}");
    assert_eq!(w.value("SCALE"), Some("10"), "{w:?}");
    assert_eq!(board.panel_line("mpg x counts=3 scale=100"), Ok(None));
    assert_eq!(at_rest(&mut c), (before.0 + 300, before.1 - 70));
    for bad in [
        "MPG Y COUNTS=1 SCALE=1",
        "MPG X COUNTS=1 SCALE=5",
        "MPG X COUNTS=many SCALE=1",
        "MPG X SCALE=1",
    ] {
        let r = board.panel_line(bad);
        assert!(r.as_ref().is_err_and(|e| e.contains("MPG")), "{bad}: {r:?}");
    }
    assert_eq!(at_rest(&mut c), (before.0 + 300, before.1 - 70));
}

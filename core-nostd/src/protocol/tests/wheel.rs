//! The handwheel through the device (`docs/inputs.md` §11): its settings,
//! the distance it moves (counts × scale impulses, exactly), and when it
//! moves nothing.

use super::*;

fn wheel(dev: &mut Device, counts: i32) -> Vec<String> {
    let mut io = Lines::default();
    dev.wheel(counts, &mut io);
    io.out
}

/// The position registers, `(PX, PZ)`.
fn registers(dev: &mut Device) -> (i64, i64) {
    let pos = ask1(dev, "POS");
    (number(&pos, "PX"), number(&pos, "PZ"))
}

#[test]
fn the_wheel_settings_answer_and_refuse_a_bad_word_changing_nothing() {
    let mut dev = Device::new();
    assert_eq!(ask1(&mut dev, "WHEEL"), "OK AXIS=- SCALE=1 FEED=500");
    assert_eq!(
        ask1(&mut dev, "WHEEL AXIS=Z SCALE=100 FEED=1200.5"),
        "OK AXIS=Z SCALE=100 FEED=1200.5"
    );
    for (bad, word) in [
        ("WHEEL AXIS=Y", "AXIS"),
        ("WHEEL SCALE=5", "SCALE"),
        ("WHEEL FEED=0", "FEED"),
        ("WHEEL AXIS=X FEED=30000", "FEED"),
    ] {
        let r = ask1(&mut dev, bad);
        assert!(
            r.starts_with(&std::format!("ERR VALUE {word}")),
            "{bad}: {r}"
        );
    }
    assert_eq!(ask1(&mut dev, "WHEEL"), "OK AXIS=Z SCALE=100 FEED=1200.5");
    // Kept with the table: a device given the offsets has them.
    let mut next = Device::new();
    next.restore_offsets(*dev.session().offsets());
    assert_eq!(ask1(&mut next, "WHEEL"), "OK AXIS=Z SCALE=100 FEED=1200.5");
}

/// Each count moves the selected axis by the scale's impulses, whatever
/// point the tool was at (one off the impulse grid included), and the
/// other axis never.
#[test]
fn the_wheel_moves_its_axis_by_counts_times_scale_impulses() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG HX=0.005 HZ=0.01").starts_with("OK"));
    // Off: nothing moves and nothing is said.
    assert_eq!(wheel(&mut dev, 40), Vec::<String>::new());
    assert_eq!(registers(&mut dev), (0, 0));
    assert!(ask1(&mut dev, "WHEEL AXIS=Z SCALE=10").starts_with("OK"));
    assert_eq!(wheel(&mut dev, 7), Vec::<String>::new());
    assert_eq!(registers(&mut dev), (0, 70));
    wheel(&mut dev, -3);
    assert_eq!(registers(&mut dev), (0, 40));
    // Off the grid: Z at 0.0037 mm reads 0 impulses; 5 counts ×1 are 5.
    assert!(ask1(&mut dev, "MOVE X=1 Z=0.0037").starts_with("OK"));
    // Queued and not yet run: the wheel waits for it.
    assert_eq!(
        wheel(&mut dev, 5),
        std::vec!["!WHEEL IGNORED=RUN COUNTS=5".to_string()]
    );
    assert!(ask1(&mut dev, "SYNC").starts_with("OK"));
    let (px, pz) = registers(&mut dev);
    assert!(ask1(&mut dev, "WHEEL SCALE=1").starts_with("OK"));
    wheel(&mut dev, 5);
    assert_eq!(registers(&mut dev), (px, pz + 5));
    wheel(&mut dev, -5);
    assert_eq!(registers(&mut dev), (px, pz));
    // X by 100 impulses of 0.005 mm per count: 2 counts, 1 mm of radius.
    assert!(ask1(&mut dev, "WHEEL AXIS=X SCALE=100").starts_with("OK"));
    wheel(&mut dev, 2);
    assert_eq!(registers(&mut dev), (px + 200, pz));
    // The commanded point is where the wheel left it.
    let (x, z) = dev.session().commanded();
    // X=1 is a diameter: a radius of 0.5 mm, and 1 mm more.
    assert_eq!(x.as_angstrom(), 15_000_000, "{x:?}");
    assert_eq!(z.as_angstrom(), 37_000, "{z:?}");
}

/// Nose compensation on or a lock: the counts move nothing, and the first
/// of them says why, once, until the wheel moves the axis again.
#[test]
fn the_wheel_moves_nothing_while_compensating_or_locked_and_says_so_once() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "WHEEL AXIS=Z").starts_with("OK"));
    assert!(ask1(&mut dev, "CFG RN=0.8").starts_with("OK"));
    let comp = ask(&mut dev, b"G42 G01 X10 Z0 F100\n");
    assert!(comp.last().is_some_and(|l| l.starts_with("OK")), "{comp:?}");
    let before = registers(&mut dev);
    assert_eq!(
        wheel(&mut dev, 3),
        std::vec!["!WHEEL IGNORED=COMPENSATION COUNTS=3".to_string()]
    );
    assert_eq!(wheel(&mut dev, 3), Vec::<String>::new(), "said once");
    assert_eq!(registers(&mut dev), before);
    let off = ask(&mut dev, b"G40 G01 X12 Z2\n");
    assert!(off.last().is_some_and(|l| l.starts_with("OK")), "{off:?}");
    assert!(ask1(&mut dev, "SYNC").starts_with("OK"));
    let at = registers(&mut dev);
    assert_eq!(wheel(&mut dev, -2), Vec::<String>::new());
    assert_eq!(registers(&mut dev), (at.0, at.1 - 2));
}

/// Counts that would carry the axis beyond the lengths the device holds
/// move nothing and say so, once; the wheel goes on afterwards.
#[test]
fn counts_beyond_the_range_move_nothing_and_say_so() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "WHEEL AXIS=Z SCALE=100").starts_with("OK"));
    assert_eq!(
        wheel(&mut dev, i32::MAX),
        std::vec![std::format!("!WHEEL IGNORED=RANGE COUNTS={}", i32::MAX)]
    );
    assert_eq!(registers(&mut dev), (0, 0));
    assert_eq!(wheel(&mut dev, -1), Vec::<String>::new());
    assert_eq!(registers(&mut dev), (0, -100));
}

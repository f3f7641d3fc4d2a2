//! Motion in time: the device's timed step events against the f64
//! reference of `docs/motion.md`, event by event, and `SYNC` against the
//! reference's report.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tests::TimedPair;

#[test]
fn single_blocks_from_rest_to_rest() {
    let mut p = TimedPair::new();
    // Rapids and feeds, along each axis and across, long and short.
    let moves: [(i64, i64, Option<&str>); 8] = [
        (0, -1_000_000_000, None),
        (200_000_000, -1_000_000_000, Some("300")),
        (150_000_000, -980_000_000, Some("50.5")),
        (150_000_000, -979_990_000, Some("1200")),
        (0, 0, None),
        (12_345_670, -7_000_010, Some("123.456789")),
        (12_345_670, -7_000_010, Some("10")),
        (40_000_000, -7_000_010, Some("0.5")),
    ];
    for (x, z, f) in moves {
        p.to(x, z, f);
        p.sync();
    }
    assert!(p.time.ties().min_distance > 0.0);
}

#[test]
fn random_programs_with_look_ahead() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let mut p = TimedPair::new();
    let (mut x, mut z) = (0i64, 0i64);
    let feeds = ["20", "100", "250.5", "600", "1200", "3000", "99999"];
    let mut events = 0;
    for block in 0..3000 {
        // Mostly short blocks, some long ones and straight continuations.
        let (dx, dz) = match rng.random_range(0..10) {
            0 => (0, rng.random_range(-400..400) * 1_000_000),
            1..=3 => {
                // Continue in the same direction (a split line).
                (
                    rng.random_range(1..5) * 10_000,
                    -rng.random_range(1..5) * 10_000,
                )
            }
            _ => (
                rng.random_range(-300..300) * 10_000,
                rng.random_range(-600..300) * 10_000,
            ),
        };
        x = (x + dx).clamp(-2_000_000_000, 2_000_000_000);
        z = (z + dz).clamp(-5_000_000_000, 1_000_000_000);
        let feed = if rng.random_bool(0.2) {
            None
        } else {
            Some(feeds[rng.random_range(0..feeds.len())])
        };
        p.to(x, z, feed);
        if block % 500 == 499 {
            events += p.sync().0;
        }
    }
    events += p.sync().0;
    assert!(events > 100_000, "{events} events");
    let ties = p.time.ties();
    println!(
        "{events} events, min tie distance {:e} tick, {} exact ties",
        ties.min_distance, ties.exact_ties
    );
}

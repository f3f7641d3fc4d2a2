//! Arbitrary `G76` cycles (`docs/threading.md` §5) into
//! `core_nostd::thread`, over the whole of its ranges.
//!
//! - a cycle is accepted only when its words are within their ranges, as
//!   the docs rule them;
//! - every roughing depth is `J·n^(1/R)` computed in `f64` to within
//!   10⁻⁶ of it relatively (and 1 ångström), the depths never fall on
//!   the way to `K` (a tiny `J` may round two passes to one depth), and the spring passes repeat `K`;
//! - every move starts where the one before ended, every synchronised
//!   move travels and has a lead above 0, every cut lies between `K` above the
//!   crest (an entry taper's start) and the full depth, and the cycle ends on the drive line at `Z`.
#![no_main]

use arbitrary::Arbitrary;
use core_nostd::thread::{ThreadMove, G76, MAX_ANGLE, MAX_PASSES, MAX_SPRING, MAX_WORD};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Input {
    x0: i64,
    z0: i64,
    z_end: i64,
    pitch: i64,
    crest: i64,
    first: i64,
    full: i64,
    degression: u32,
    angle: i64,
    spring: u32,
    taper: i64,
    ends: u8,
    /// Keep the words small and valid most of the time.
    tame: bool,
}

fuzz_target!(|i: Input| {
    let wrap = |v: i64, m: i64| v.rem_euclid(2 * m + 1) - m;
    let c = if i.tame {
        let first = 1 + i.first.rem_euclid(5_000_000);
        G76 {
            start: [wrap(i.x0, 500_000_000), wrap(i.z0, 500_000_000)],
            z_end: wrap(i.z_end, 500_000_000),
            pitch: 1 + i.pitch.rem_euclid(50_000_000),
            crest: wrap(i.crest, 30_000_000),
            first,
            full: first + 1 + i.full.rem_euclid(30_000_000),
            degression: 10_000 + i.degression % 30_000,
            angle: i.angle.rem_euclid(MAX_ANGLE + 1),
            spring: i.spring % (MAX_SPRING + 1),
            taper: i.taper.rem_euclid(50_000_000),
            ends: i.ends % 4,
        }
    } else {
        G76 {
            start: [wrap(i.x0, 1 << 40), wrap(i.z0, 1 << 40)],
            z_end: wrap(i.z_end, 1 << 40),
            pitch: wrap(i.pitch, 2 * MAX_WORD),
            crest: wrap(i.crest, 2 * MAX_WORD),
            first: wrap(i.first, 2 * MAX_WORD),
            full: wrap(i.full, 2 * MAX_WORD),
            degression: i.degression,
            angle: wrap(i.angle, 2 * MAX_ANGLE),
            spring: i.spring % 200,
            taper: wrap(i.taper, 2 * MAX_WORD),
            ends: i.ends % 6,
        }
    };
    let words_ok = [c.pitch, c.crest, c.first, c.full, c.taper]
        .iter()
        .all(|w| w.abs() <= MAX_WORD)
        && c.crest != 0
        && c.first > 0
        && c.full > c.first
        && c.pitch > 0
        && c.degression >= 10_000
        && (0..=MAX_ANGLE).contains(&c.angle)
        && c.spring <= MAX_SPRING
        && c.ends <= 3
        && c.taper >= 0;
    let Ok(()) = c.check() else {
        return;
    };
    assert!(words_ok, "accepted out of range: {c:?}");

    // The depths.
    let r = f64::from(c.degression) / 1e4;
    let depths: Vec<i64> = c.depths().collect();
    let roughing = depths.len() - c.spring as usize;
    assert!(roughing >= 1 && roughing as u32 <= MAX_PASSES, "{c:?}");
    for (n, d) in depths.iter().take(roughing - 1).enumerate() {
        let want = c.first as f64 * ((n + 1) as f64).powf(1.0 / r);
        assert!(
            (*d as f64 - want).abs() <= want * 1e-6 + 1.0,
            "pass {}: {d} against {want}: {c:?}",
            n + 1
        );
        assert!(*d < c.full, "{c:?}");
    }
    assert!(
        depths.windows(2).take(roughing - 1).all(|w| w[0] <= w[1]),
        "{c:?}"
    );
    assert!(depths[roughing - 1..].iter().all(|&d| d == c.full), "{c:?}");

    // The moves.
    let s = c.crest.signum();
    let crest = c.start[0] + c.crest;
    let bottom = crest + s * c.full;
    let above = crest - s * c.full;
    let (lo, hi) = (above.min(bottom), above.max(bottom));
    let mut at = c.start;
    let mut last = None;
    for m in c.moves() {
        match m {
            ThreadMove::Rapid(to) => at = to,
            ThreadMove::Cut { to, lead } => {
                assert!(lead > 0, "{m:?}: {c:?}");
                assert!(to != at, "a cut that does not travel: {m:?}: {c:?}");
                assert!(
                    (lo..=hi).contains(&to[0]),
                    "{m:?} outside the thread: {c:?}"
                );
                at = to;
            }
        }
        last = Some(m);
    }
    assert_eq!(
        last,
        Some(ThreadMove::Rapid([c.start[0], c.z_end])),
        "{c:?}"
    );
});

//! Arcs through the device against the f64 reference: chords and direct
//! steps bit for bit, finishing chords within TOL as the reference measures
//! them, full circles closing, splitting at a chord end changing nothing.

use host_sim::compare::{Comparator, Scenario, Step};
use host_sim::device::LocalDevice;
use host_sim::link::{words_value, Transport};
use host_sim::scenario;
use proptest::prelude::*;

fn ask(dev: &mut LocalDevice, line: &str) -> host_sim::link::Reply {
    let r = Transport::request(dev, line).unwrap();
    assert!(r.is_ok(), "{line}: {}", r.last);
    r
}

fn int(r: &host_sim::link::Reply, key: &str) -> i64 {
    words_value(&r.last, key).unwrap().parse().unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random arc sessions: every chord, every direct step sequence, every
    /// refusal as the reference has it.
    #[test]
    fn arcs_equal_the_reference(seed in any::<u64>()) {
        let mut cmp = Comparator::new(LocalDevice::new()).unwrap();
        cmp.run(&scenario::random_arcs(seed, 40, 15), |_| {}).unwrap();
        let t = &cmp.tally;
        prop_assert!(t.mismatches.is_empty(), "{:?}", t.mismatches);
        prop_assert!(t.arcs + t.direct_arcs + t.refused_alike == 55);
        // Measured by the reference, not assumed.
        prop_assert!(t.worst_chord_error <= 1.0, "{}", t.worst_chord_error);
        // Rounded start, J/K and end put the end up to ~1.5 impulses per axis
        // off the impulse circle; the steps stay within half an impulse of
        // the circle or of that offset (about 1.75 impulses at worst).
        prop_assert!(t.worst_direct_deviation <= 2.0, "{}", t.worst_direct_deviation);
    }

    /// A full circle, in either direction, at any tolerance and pass, issues
    /// no net impulse and leaves the registers where they were.
    #[test]
    fn full_circles_close(x in -50_000i64..50_000, z in -50_000i64..50_000,
                          i in -20_000i64..20_000, k in -20_000i64..20_000,
                          ccw: bool, rough: bool, tol in 1usize..5) {
        prop_assume!(i.abs() + k.abs() > 200);
        let d = |v: i64| host_sim::scenario::nm_to_decimal(v * 1000);
        let mut dev = LocalDevice::new();
        let start = ask(&mut dev, &format!("MOVE X={} Z={}", d(2 * x), d(z)));
        let tol = ["0.001", "0.005", "0.01", "0.05", "0.1"][tol];
        let r = ask(&mut dev, &format!(
            "ARC X={} Z={} I={} K={} DIR={} TOL={tol} PASS={}",
            d(2 * x), d(z), d(i), d(k), if ccw { "CCW" } else { "CW" }, if rough { "ROUGH" } else { "FIN" }));
        prop_assert_eq!((int(&r, "NX"), int(&r, "NZ")), (0, 0));
        prop_assert_eq!((int(&r, "PX"), int(&r, "PZ")), (int(&start, "PX"), int(&start, "PZ")));
        let chords: i64 = r.data.len() as i64;
        prop_assert_eq!(chords, int(&r, "N"));
    }
}

/// A half circle cut at its 90° point into two quarter arcs gives the same
/// chord impulses and the same end, when Δφ divides 90° (the quarter point is
/// an exact chord end): σ 0.000147 at R 50 gives Δφ = 1000″.
#[test]
fn splitting_at_a_chord_end_changes_nothing() {
    let mut whole = LocalDevice::new();
    let mut split = LocalDevice::new();
    for dev in [&mut whole, &mut split] {
        ask(dev, "CFG DIAM=0 TOL=0.000147");
        ask(dev, "MOVE X=0 Z=50");
    }
    let w = ask(&mut whole, "ARC X=0 Z=-50 I=0 K=-50 DIR=CCW");
    let a = ask(&mut split, "ARC X=50 Z=0 I=0 K=-50 DIR=CCW");
    let b = ask(&mut split, "ARC X=0 Z=-50 I=-50 K=0 DIR=CCW");
    let chords = |r: &host_sim::link::Reply| -> Vec<String> {
        r.data
            .iter()
            .map(|l| l.split_once(" NX=").unwrap().1.to_owned())
            .collect()
    };
    let mut parts = chords(&a);
    parts.extend(chords(&b));
    assert_eq!(chords(&w), parts);
    assert_eq!(int(&w, "N"), 648);
    assert!(w.last.contains("DPHI=0.277778"));
    assert_eq!(
        (int(&w, "PX"), int(&w, "PZ")),
        (int(&b, "PX"), int(&b, "PZ"))
    );
}

/// The built-in arc scenarios of the main job agree with the reference.
#[test]
fn built_in_arc_scenarios() {
    let mut cmp = Comparator::new(LocalDevice::new()).unwrap();
    cmp.run(&scenario::krylenko_arcs(), |_| {}).unwrap();
    cmp.run(&scenario::random_arcs(7, 80, 30), |_| {}).unwrap();
    assert!(
        cmp.tally.mismatches.is_empty(),
        "{:?}",
        cmp.tally.mismatches
    );
    assert!(
        cmp.tally.refused_alike >= 2,
        "{} {} {}",
        cmp.tally.refused_alike,
        cmp.tally.arcs,
        cmp.tally.direct_arcs
    );
    assert!(cmp.tally.arcs >= 60 && cmp.tally.direct_arcs >= 20);
    // A hand-made arc session through the same engine.
    let by_hand = Scenario {
        name: "quarter".into(),
        steps: vec![
            Step::Cfg {
                hx: None,
                hz: None,
                diam: Some(false),
            },
            Step::to("0", "10"),
            Step::Arc {
                x: "10".into(),
                z: "0".into(),
                i: "0".into(),
                k: "-10".into(),
                ccw: true,
                tol: Some("0.01".into()),
                rough: Some(false),
                direct: false,
                feed: None,
            },
        ],
    };
    cmp.run(&by_hand, |_| {}).unwrap();
    assert!(cmp.tally.mismatches.is_empty());
}

//! The fixed-point core against the independent f64 reference, bit for bit,
//! and the carry rule's consequences: closed paths issue nothing, splitting a
//! block never moves where the axis ends.

use host_sim::compare::{Comparator, Scenario, Step};
use host_sim::device::LocalDevice;
use host_sim::link::{words_value, Transport};
use host_sim::scenario::nm_to_decimal;
use proptest::prelude::*;

/// A length word in nm: mostly small, sometimes near the 6-decimal grid's
/// ties, sometimes round.
fn word_nm(max_mm: i64) -> impl Strategy<Value = i64> {
    let max = max_mm * 1_000_000;
    prop_oneof![
        -max..max,
        (-max / 2_500..max / 2_500).prop_map(|k| k * 2_500),
        (-max / 5_000..max / 5_000).prop_map(|k| k * 5_000 + 2_500),
        (-max / 10_000..max / 10_000).prop_map(|k| k * 10_000),
    ]
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        12 => (proptest::option::weighted(0.85, word_nm(200)), proptest::option::weighted(0.85, word_nm(200)), any::<bool>(),
               proptest::option::weighted(0.7, 1_000u32..3_000_000_000))
            .prop_map(|(x, z, inc, f)| Step::Move {
                x: x.map(|v| nm_to_decimal(if inc { v / 10 } else { v })),
                z: z.map(|v| nm_to_decimal(if inc { v / 10 } else { v })),
                inc,
                feed: f.map(|f| nm_to_decimal(i64::from(f))),
            }),
        1 => Just(Step::Sync),
        1 => (prop_oneof![Just("0.005"), Just("0.001"), Just("0.0025"), Just("0.002")],
              prop_oneof![Just("0.01"), Just("0.005"), Just("0.001"), Just("0.0025")],
              any::<bool>())
            .prop_map(|(hx, hz, diam)| Step::Cfg { hx: Some(hx.into()), hz: Some(hz.into()), diam: Some(diam) }),
        1 => Just(Step::Zero),
    ]
}

fn reply_int(r: &host_sim::link::Reply, key: &str) -> i64 {
    words_value(&r.last, key)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{key} missing in {}", r.last))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Random sessions: every block's NX, NZ, PX, PZ and SEQ equal the
    /// reference's, and every SYNC's EV, T and TSEQ (the tick of every event).
    #[test]
    fn core_equals_reference(mut steps in proptest::collection::vec(step(), 1..40)) {
        steps.push(Step::Sync);
        let scenario = Scenario { name: "proptest".into(), steps };
        let mut cmp = Comparator::new(LocalDevice::new()).unwrap();
        cmp.run(&scenario, |_| {}).unwrap();
        prop_assert!(cmp.tally.mismatches.is_empty(), "{:?}", cmp.tally.mismatches);
        prop_assert_eq!(cmp.tally.blocks as usize, scenario.blocks());
    }

    /// A closed path, in any mix of absolute and incremental words, issues
    /// zero net impulses on each axis.
    #[test]
    fn closed_path_issues_nothing(points in proptest::collection::vec((word_nm(150), word_nm(150)), 1..30),
                                  inc in proptest::collection::vec(any::<bool>(), 30)) {
        let mut dev = LocalDevice::new();
        let start = Transport::request(&mut dev, "MOVE X=12.345 Z=-6.789").unwrap();
        prop_assert!(start.is_ok());
        let (mut x, mut z) = (12_345_000i64, -6_789_000i64);
        let (mut sx, mut sz) = (0i64, 0i64);
        let mut path = points.clone();
        path.push((x, z));
        for (i, &(px, pz)) in path.iter().enumerate() {
            let line = if inc[i % inc.len()] {
                format!("MOVE X={} Z={} INC=1", nm_to_decimal(px - x), nm_to_decimal(pz - z))
            } else {
                format!("MOVE X={} Z={}", nm_to_decimal(px), nm_to_decimal(pz))
            };
            let r = Transport::request(&mut dev, &line).unwrap();
            prop_assert!(r.is_ok(), "{}", r.last);
            sx += reply_int(&r, "NX");
            sz += reply_int(&r, "NZ");
            (x, z) = (px, pz);
        }
        prop_assert_eq!((sx, sz), (0, 0));
    }

    /// Splitting a block at any decimal point on it, or anywhere else, never
    /// changes where the axes end.
    #[test]
    fn splitting_never_moves_the_end(a in (word_nm(150), word_nm(150)), b in (word_nm(150), word_nm(150)),
                                     cuts in proptest::collection::vec((word_nm(150), word_nm(150)), 1..6)) {
        let line = |p: (i64, i64)| format!("MOVE X={} Z={}", nm_to_decimal(p.0), nm_to_decimal(p.1));
        let mut whole = LocalDevice::new();
        let mut split = LocalDevice::new();
        prop_assert!(Transport::request(&mut whole, &line(a)).unwrap().is_ok());
        prop_assert!(Transport::request(&mut split, &line(a)).unwrap().is_ok());
        let w = Transport::request(&mut whole, &line(b)).unwrap();
        let (mut sx, mut sz) = (0, 0);
        for &c in &cuts {
            let r = Transport::request(&mut split, &line(c)).unwrap();
            sx += reply_int(&r, "NX");
            sz += reply_int(&r, "NZ");
        }
        let s = Transport::request(&mut split, &line(b)).unwrap();
        sx += reply_int(&s, "NX");
        sz += reply_int(&s, "NZ");
        prop_assert_eq!((reply_int(&s, "PX"), reply_int(&s, "PZ")), (reply_int(&w, "PX"), reply_int(&w, "PZ")));
        prop_assert_eq!((sx, sz), (reply_int(&w, "NX"), reply_int(&w, "NZ")));
    }
}

#[test]
fn built_in_scenarios_match_the_reference() {
    let mut cmp = Comparator::new(LocalDevice::new()).unwrap();
    for s in [
        host_sim::scenario::table21(),
        host_sim::scenario::krylenko(),
        host_sim::scenario::random(42, 300),
    ] {
        cmp.run(&s, |_| {}).unwrap();
    }
    assert!(
        cmp.tally.mismatches.is_empty(),
        "{:?}",
        cmp.tally.mismatches
    );
    assert!(
        cmp.tally.exact_ties() > 50,
        "the random blocks include exact ties"
    );
    assert!(cmp.tally.min_tie_distance() > 1e-7);
}

/// The comparison engine does catch a wrong device: a device whose X price
/// differs from the reference's gives mismatches.
#[test]
fn a_wrong_device_is_caught() {
    let mut cmp = Comparator::new(LocalDevice::new()).unwrap();
    let r = Transport::request(cmp.link(), "CFG HX=0.0025").unwrap();
    assert!(r.is_ok());
    let mut moves = host_sim::scenario::krylenko();
    moves.steps.retain(|s| matches!(s, Step::Move { .. }));
    cmp.run(&moves, |_| {}).unwrap();
    // Every block that moves X disagrees; Z-only blocks still agree.
    let m = &cmp.tally.mismatches;
    assert!(m.len() > 20 && m.len() < moves.blocks(), "{}", m.len());
}

//! The CONE calculator: the Nomura (MELDAS 65SLC) table reproduced in all
//! 204 places, Krylenko's worked example, exact angle notations.

use host_sim::device::LocalDevice;
use host_sim::link::{words_value, Transport};
use reference::cone::NOMURA_TABLE;

fn cone(dev: &mut LocalDevice, a: &str, rn: &str) -> host_sim::link::Reply {
    let r = Transport::request(dev, &format!("CONE A={a} RN={rn}")).unwrap();
    assert!(r.is_ok(), "{a} {rn}: {}", r.last);
    r
}

fn mm(r: &host_sim::link::Reply, key: &str) -> f64 {
    words_value(&r.last, key).unwrap().parse().unwrap()
}

#[test]
fn nomura_table_in_all_204_places() {
    let mut dev = LocalDevice::new();
    let mut places = 0;
    let mut worst: f64 = 0.0;
    for row in NOMURA_TABLE.lines() {
        let mut w = row.split_whitespace();
        let (kind, rn) = (w.next().unwrap(), w.next().unwrap());
        for (i, printed) in w.enumerate() {
            let a = 5 * (i + 1);
            let r = cone(&mut dev, &a.to_string(), rn);
            // 2A is Xc on the diameter (XCD); NA itself is Xc.
            let value = match kind {
                "A2" => 2.0 * mm(&r, "NA"),
                "B" => mm(&r, "NB"),
                _ => mm(&r, "NC"),
            };
            let printed: f64 = printed.parse().unwrap();
            // Half a unit of the printed 0.01, plus the 4-decimal rounding of
            // the reply (doubled for 2A).
            let d = (value - printed).abs();
            worst = worst.max(d);
            assert!(
                d <= 0.005 + 0.0001 + 1e-9,
                "{kind} r{rn} a{a}: {value} vs {printed}"
            );
            // XCD is 2·Xc rounded once: within 0.0001 of twice the printed XC.
            assert!((mm(&r, "XCD") - 2.0 * mm(&r, "XC")).abs() <= 0.0001 + 1e-9);
            places += 1;
        }
    }
    assert_eq!(places, 204);
    assert!(worst > 0.0 && worst <= 0.0051, "{worst}");
}

#[test]
fn krylenko_example_and_notations() {
    let mut dev = LocalDevice::new();
    // r 0.4, α 45°: Xc = Zc = 0.234 (0.468 on the diameter) in the seed.
    let r = Transport::request(&mut dev, "CONE A=45").unwrap();
    assert_eq!(
        r.last,
        "OK XC=0.2343 ZC=0.2343 XCD=0.4686 NA=0.2343 NB=0.2343 NC=0.5657"
    );
    // 54.26° and 54°15'36" are the same angle, exactly.
    assert_eq!(
        cone(&mut dev, "54.26", "0.8").last,
        cone(&mut dev, "54:15:36", "0.8").last
    );
    for bad in ["0", "90", "-5", "1:60:0", "45.1234567", "1e1", "45:"] {
        let r = Transport::request(&mut dev, &format!("CONE A={bad}")).unwrap();
        assert!(r.last.starts_with("ERR VALUE A"), "{bad}: {}", r.last);
    }
}

/// Random angles in both notations and random nose radii: the device's reply
/// equals the f64 reference's, unless the reference finds a value within
/// 10⁻⁹ mm of a printing tie, where the device must say so (`NEAR=`).
#[test]
fn cone_equals_the_reference_on_random_angles() {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1977);
    let mut dev = LocalDevice::new();
    let mut near = 0;
    for n in 0..20_000 {
        // Whole micro-degrees or whole (fractional) arc-seconds.
        let (word, rn) = if n % 2 == 0 {
            let ud: u64 = rng.random_range(1..90_000_000);
            (
                format!("{}.{:06}", ud / 1_000_000, ud % 1_000_000),
                rng.random_range(0..=25_000_000u64),
            )
        } else {
            let s: u64 = rng.random_range(1..32_400_000); // hundredths of an arc-second
            let (d, rest) = (s / 360_000, s % 360_000);
            (
                format!(
                    "{d}:{}:{}.{:02}",
                    rest / 6000,
                    rest % 6000 / 100,
                    rest % 100
                ),
                rng.random_range(0..=25_000_000u64),
            )
        };
        let rn = format!("{}.{:06}", rn / 1_000_000, rn % 1_000_000);
        let expected = reference::cone::cone(&word, rn.parse().unwrap()).expect(&word);
        let got = Transport::request(&mut dev, &format!("CONE A={word} RN={rn}")).unwrap();
        if expected.min_tie_distance_mm < 1e-9 {
            near += 1;
            assert!(got.last.contains(" NEAR="), "{word} {rn}: {}", got.last);
        } else {
            assert_eq!(got.last, expected.reply_line(), "A={word} RN={rn}");
        }
    }
    assert!(near < 10, "{near}");
}

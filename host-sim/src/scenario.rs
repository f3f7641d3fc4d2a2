//! The built-in scenarios of the main job.
//!
//! - the closed tool paths of Kosenko's table 21 (lathe АТПр-2М12, carriage
//!   0.01 mm and cross slide 0.005 mm per impulse);
//! - the contours of Krylenko's parts (Fig. 12, 17, 22, 24) as plain moves;
//! - seeded random blocks: absolute and incremental words, diameters, values
//!   with up to 6 decimals, exact rounding ties, price and mode changes.

use crate::compare::{Scenario, Step};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One row of Kosenko's table 21, with the seed's axes renamed to ours: the
/// seed's `x` (carriage, 0.01 mm) is our Z, its `y` (cross slide on the
/// radius, 0.005 mm) is our X radius.
#[derive(Clone, Copy, Debug)]
pub struct Table21Row {
    /// The seed's point number.
    pub point: u32,
    /// Z coordinate, mm (the seed's `x`).
    pub z: &'static str,
    /// X radius, mm (the seed's `y`).
    pub x: &'static str,
    /// Z impulses of the move into this point as printed (`None`: no move printed).
    pub printed_nz: Option<i64>,
    /// X impulses of the move into this point as printed.
    pub printed_nx: Option<i64>,
}

const fn row(
    point: u32,
    z: &'static str,
    x: &'static str,
    printed_nz: Option<i64>,
    printed_nx: Option<i64>,
) -> Table21Row {
    Table21Row {
        point,
        z,
        x,
        printed_nz,
        printed_nx,
    }
}

/// Kosenko's table 21: four closed tool paths, each starting and ending at its
/// tool's reference point. The coordinates are the table's; where its
/// printed figures slip, the coordinate consistent with the rest of the row is
/// used and the slip is noted:
/// - point 1: ΔZ printed `12400` without its sign (the move is −12400);
/// - point 9: ΔX printed as 2.32 mm, the move is 32 − 29.18 = 2.82 mm (= the
///   printed 564 impulses);
/// - point 13: X printed as −20.95; the row's own Δ (−4.05 mm, −810) puts it at
///   +20.95;
/// - point 20 and 23: the millimetre columns lose or flip a sign; the impulse
///   columns are right;
/// - point 25: ΔX printed `25606` without its sign (the move is −25606);
/// - the third path's X check sum is printed Σ− = 20206, the moves give 24206.
pub const TABLE21_PATHS: [&[Table21Row]; 4] = [
    &[
        row(0, "246", "150", None, None),
        row(1, "122", "0", Some(12400), Some(-30000)),
        row(2, "119.79", "0", Some(-221), None),
        row(3, "119.79", "24", None, Some(4800)),
        row(4, "121", "24", Some(121), None),
        row(5, "121", "22.16", None, Some(-368)),
        row(6, "90.3", "22.16", Some(-3070), None),
        row(7, "60.5", "29.18", Some(-2980), Some(1404)),
        row(8, "40.5", "29.18", Some(-2000), None),
        row(9, "40.5", "32", None, Some(564)),
        row(10, "246", "150", Some(20550), Some(23600)),
    ],
    &[
        row(11, "271", "115", None, None),
        row(12, "89.89", "25", Some(-18111), Some(-18000)),
        row(13, "89.89", "20.95", None, Some(-810)),
        row(14, "89.89", "32", None, Some(2210)),
        row(15, "39.89", "32", Some(-5000), None),
        row(16, "39.89", "26.92", None, Some(-1016)),
        row(17, "39.89", "35", None, Some(1616)),
        row(18, "271", "115", Some(23111), Some(16000)),
    ],
    &[
        row(19, "251", "150", None, None),
        row(20, "80", "28.97", Some(-17100), Some(-24206)),
        row(21, "42", "28.97", Some(-3800), None),
        row(22, "42", "32", None, Some(606)),
        row(23, "251", "150", Some(20900), Some(23600)),
    ],
    &[
        row(24, "251", "150", None, None),
        row(25, "121", "21.97", Some(-13000), Some(25606)),
        row(26, "92", "21.97", Some(-2900), None),
        row(27, "92", "24", None, Some(406)),
        row(28, "251", "150", Some(15900), Some(25200)),
    ],
];

/// The check sums printed under each path of table 21: (Σ+ Z, Σ− Z, Σ+ X,
/// Σ− X), magnitudes as printed (the third path's Σ− X is a slip).
pub const TABLE21_PRINTED_SUMS: [(i64, i64, i64, i64); 4] = [
    (20671, 20671, 30368, 30368),
    (23111, 23111, 19826, 19826),
    (20900, 20900, 24206, 20206),
    (15900, 15900, 25606, 25606),
];

/// The first steps of a scenario: the default prices (0.005 mm on X,
/// 0.01 mm on Z), X words as diameters or radii, and the program zero.
fn from_zero(diam: bool) -> Vec<Step> {
    vec![
        Step::Cfg {
            hx: Some("0.005".into()),
            hz: Some("0.01".into()),
            diam: Some(diam),
        },
        Step::Zero,
    ]
}

/// Table 21 as a scenario: radius programming at 0.005/0.01 mm, each path
/// driven from its reference point through its points back to it.
pub fn table21() -> Scenario {
    let mut steps = from_zero(false);
    for path in TABLE21_PATHS {
        // To the reference point at the rapid rate, then the path at a feed.
        for (n, r) in path.iter().enumerate() {
            steps.push(if n == 0 {
                Step::to(r.x, r.z)
            } else {
                Step::feed_to(r.x, r.z, "250")
            });
        }
        steps.push(Step::Sync);
    }
    steps.push(Step::to("0", "0"));
    steps.push(Step::Sync);
    Scenario {
        name: "Kosenko table 21 (АТПр-2М12 tool paths)".into(),
        steps,
    }
}

/// Krylenko's part programs as plain moves (diameter words, compensated
/// points as printed, arcs replaced by their end points), each run from and
/// back to its approach point.
pub fn krylenko() -> Scenario {
    let programs: [&[(&str, &str)]; 4] = [
        // Fig. 12: external tapers, r 0.4.
        &[
            ("30", "10"),
            ("27.532", "0"),
            ("48", "-10.234"),
            ("48", "-46.234"),
            ("67.532", "-56"),
            ("93.532", "-56"),
            ("114", "-66.234"),
            ("114", "10"),
            ("30", "10"),
        ],
        // Fig. 17: internal tapers.
        &[
            ("88", "10"),
            ("78.468", "0"),
            ("50", "-14.234"),
            ("50", "-34.234"),
            ("28.468", "-45"),
            ("12", "-45"),
            ("12", "10"),
            ("88", "10"),
        ],
        // Fig. 22: arcs R2.4, R2.6, R4.4 (end points), line 12 at −14.4.
        &[
            ("10", "10"),
            ("7.2", "0"),
            ("12", "-2.4"),
            ("12", "-14.4"),
            ("17.2", "-17"),
            ("29.2", "-17"),
            ("38", "-21.4"),
            ("38", "10"),
            ("10", "10"),
        ],
        // Fig. 24: hemisphere, as printed.
        &[
            ("30", "10"),
            ("20.8", "0"),
            ("0", "-10.4"),
            ("0", "10"),
            ("30", "10"),
        ],
    ];
    let mut steps = from_zero(true);
    for program in programs {
        // Approach and retract at the rapid rate, the contour at F120.
        let last = program.len() - 1;
        for (n, &(x, z)) in program.iter().enumerate() {
            steps.push(if n == 0 || n >= last - 1 {
                Step::to(x, z)
            } else {
                Step::feed_to(x, z, "120")
            });
        }
        steps.push(Step::Sync);
    }
    steps.push(Step::to("0", "0"));
    steps.push(Step::Sync);
    Scenario {
        name: "Krylenko part contours (Fig. 12, 17, 22, 24) as moves".into(),
        steps,
    }
}

fn arc(x: &str, z: &str, i: &str, k: &str, ccw: bool) -> Step {
    Step::Arc {
        x: x.into(),
        z: z.into(),
        i: i.into(),
        k: k.into(),
        ccw,
        tol: None,
        rough: None,
        direct: false,
        feed: Some("80".into()),
    }
}

/// Krylenko's Fig. 22 and Fig. 24 programs with their arcs cut by chords
/// (`R` words turned into centres: G03 X12 Z-2.4 R2.4 about X3.6 Z-2.4 on the
/// radius, G02 X17.2 Z-17 R2.6 about X8.6 Z-14.4, G03 X38 Z-21.4 R4.4 about
/// X14.6 Z-21.4; Fig. 24's G03 X0 Z-10.4 R10.4 about X0 Z0), finishing at
/// 0.01 and 0.002 mm and roughing at 0.05 mm.
pub fn krylenko_arcs() -> Scenario {
    let mut steps = from_zero(true);
    for (tol, rough) in [("0.01", false), ("0.002", false), ("0.05", true)] {
        let with = |s: Step| match s {
            Step::Arc {
                x,
                z,
                i,
                k,
                ccw,
                feed,
                ..
            } => Step::Arc {
                x,
                z,
                i,
                k,
                ccw,
                tol: Some(tol.into()),
                rough: Some(rough),
                direct: false,
                feed,
            },
            other => other,
        };
        for s in [
            Step::to("10", "10"),
            Step::feed_to("7.2", "0", "80"),
            arc("12", "-2.4", "0", "-2.4", true),
            Step::feed_to("12", "-14.4", "80"),
            arc("17.2", "-17", "2.6", "0", false),
            Step::feed_to("29.2", "-17", "80"),
            arc("38", "-21.4", "0", "-4.4", true),
            Step::to("38", "10"),
            Step::to("30", "10"),
            Step::feed_to("20.8", "0", "80"),
            arc("0", "-10.4", "-10.4", "0", true),
            Step::to("0", "10"),
            Step::Sync,
        ] {
            steps.push(with(s));
        }
    }
    steps.push(Step::to("0", "0"));
    steps.push(Step::Sync);
    Scenario {
        name: "Krylenko Fig. 22, 24 with arcs by chords".into(),
        steps,
    }
}

/// Seeded random arcs: `chords` arcs cut by chords (full circles among
/// them, tolerances 0.001 … 0.1 mm, finishing and roughing, diameters and
/// radii, several impulse prices) and `direct` quadrant arcs for the direct
/// interpolator. Each arc starts from a move to its start point; end points
/// are the exact circle points rounded to 6 decimals, except every 40th,
/// which ends 3 µm off its circle and must be refused.
pub fn random_arcs(seed: u64, chords: usize, direct: usize) -> Scenario {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut steps = vec![Step::Zero];
    let tols = ["0.001", "0.002", "0.005", "0.01", "0.02", "0.05", "0.1"];
    let prices = [
        ("0.005", "0.01"),
        ("0.001", "0.002"),
        ("0.0025", "0.005"),
        ("0.01", "0.01"),
    ];
    for n in 0..chords + direct {
        let is_direct = n >= chords;
        if n % 50 == 0 {
            let (hx, hz) = prices[rng.random_range(0..prices.len())];
            steps.push(Step::Cfg {
                hx: Some(hx.into()),
                hz: Some(hz.into()),
                diam: Some(rng.random_bool(0.7)),
            });
        }
        let diam = steps.iter().rev().find_map(|s| match s {
            Step::Cfg { diam, .. } => *diam,
            _ => None,
        });
        let diam = diam.unwrap_or(true);
        // Centre (X radius, Z) and radius in nm; angles in radians.
        let cx: i64 = rng.random_range(-20_000_000..80_000_000);
        let cz: i64 = rng.random_range(-150_000_000..20_000_000);
        let r = rng.random_range(500_000..60_000_000) as f64;
        let (a0, a1, ccw) = if is_direct {
            let q = rng.random_range(0..4) as f64 * std::f64::consts::FRAC_PI_2;
            let (p, t) = (rng.random_range(0.0..1.5), rng.random_range(0.0..1.5));
            let ccw = rng.random_bool(0.5);
            let (lo, hi) = if p < t { (p, t) } else { (t, p) };
            if ccw {
                (q + lo, q + hi, true)
            } else {
                (q + hi, q + lo, false)
            }
        } else {
            let a0 = rng.random_range(0.0..std::f64::consts::TAU);
            let full = rng.random_bool(0.1);
            let sweep = if full {
                0.0
            } else {
                rng.random_range(0.05..6.2)
            };
            let ccw = rng.random_bool(0.5);
            (a0, if ccw { a0 + sweep } else { a0 - sweep }, ccw)
        };
        // On the circle, rounded to whole nm (written X words: even nm for radii).
        let at = |a: f64, r: f64| {
            let x = cx + (r * a.sin()).round() as i64;
            let z = cz + (r * a.cos()).round() as i64;
            (x, z)
        };
        let (sx, sz) = at(a0, r);
        // Every 40th arc ends 3 µm outside its circle: both sides must refuse it.
        let off = if n % 40 == 39 { 3_000.0 } else { 0.0 };
        let (ex, ez) = if (a1 - a0).abs() < 1e-12 && off == 0.0 {
            (sx, sz)
        } else {
            at(a1, r + off)
        };
        let word_x = |x: i64| nm_to_decimal(if diam { 2 * x } else { x });
        if n % 10 == 0 {
            steps.push(Step::Sync);
        }
        steps.push(Step::Move {
            x: Some(word_x(sx)),
            z: Some(nm_to_decimal(sz)),
            inc: false,
            feed: None,
        });
        steps.push(Step::Arc {
            x: word_x(ex),
            z: nm_to_decimal(ez),
            i: nm_to_decimal(cx - sx),
            k: nm_to_decimal(cz - sz),
            ccw,
            tol: Some(tols[rng.random_range(0..tols.len())].into()),
            rough: Some(rng.random_bool(0.3)),
            direct: is_direct,
            // The ЭМ-907 feed word of a direct arc, the path feed of chords
            // (or the rapid rate).
            feed: if rng.random_bool(if is_direct { 0.5 } else { 0.8 }) {
                Some(nm_to_decimal(rng.random_range(1_000_000..2_000_000_000)))
            } else {
                None
            },
        });
    }
    steps.push(Step::Sync);
    // Direct arcs take no TOL or PASS.
    for s in &mut steps {
        if let Step::Arc {
            direct: true,
            tol,
            rough,
            ..
        } = s
        {
            *tol = None;
            *rough = None;
        }
    }
    Scenario {
        name: format!("random arcs (seed {seed})"),
        steps,
    }
}

/// Formats a count of nanometres (10⁻⁶ mm) as an exact decimal, trailing
/// zeros dropped.
pub fn nm_to_decimal(nm: i64) -> String {
    let sign = if nm < 0 { "-" } else { "" };
    let a = nm.unsigned_abs();
    let (int, frac) = (a / 1_000_000, a % 1_000_000);
    if frac == 0 {
        format!("{sign}{int}")
    } else {
        let f = format!("{frac:06}");
        format!("{sign}{int}.{}", f.trim_end_matches('0'))
    }
}

/// Round feeds (mm/min) of the random scenario.
const FEEDS: [&str; 8] = ["50", "100", "120", "200", "250", "600", "1000", "2500"];

/// Prices the random scenario switches between, in nm (X on the radius).
const X_PRICES_NM: [i64; 5] = [5_000, 1_000, 2_500, 10_000, 2_000];
const Z_PRICES_NM: [i64; 5] = [10_000, 5_000, 1_000, 2_500, 2_000];

/// `n` seeded random blocks, with the configuration changes and program
/// zeros between them. The same seed gives the same scenario.
pub fn random(seed: u64, n: usize) -> Scenario {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut steps = from_zero(true);
    let (mut hx, mut hz, mut diam) = (5_000i64, 10_000i64, true);
    // Commanded coordinates in nm: X as a diameter (twice the radius, so an
    // odd count is a radius with half a nanometre), Z.
    let (mut cx, mut cz) = (0i64, 0i64);
    let mut blocks = 0;
    while blocks < n {
        let roll: u32 = rng.random_range(0..1000);
        if roll < 10 {
            let nhx = X_PRICES_NM[rng.random_range(0..X_PRICES_NM.len())];
            let nhz = Z_PRICES_NM[rng.random_range(0..Z_PRICES_NM.len())];
            let nd = rng.random_bool(0.7);
            // Radius words need an even diameter (odd only under DIAM=1).
            if !nd && cx % 2 != 0 {
                cx -= 1;
                steps.push(Step::Move {
                    x: Some(nm_to_decimal(cx)),
                    z: None,
                    inc: false,
                    feed: None,
                });
                blocks += 1;
            }
            steps.push(Step::Cfg {
                hx: Some(nm_to_decimal(nhx)),
                hz: Some(nm_to_decimal(nhz)),
                diam: Some(nd),
            });
            (hx, hz, diam) = (nhx, nhz, nd);
            continue;
        }
        if roll < 15 {
            steps.push(Step::Zero);
            (cx, cz) = (0, 0);
            continue;
        }
        let inc = rng.random_bool(0.3);
        // A target in the axis' written unit, like a part program's: mostly
        // near the current point, sometimes a long move across the envelope.
        let target = |rng: &mut ChaCha8Rng, now: i64, lo: i64, hi: i64, h: i64| -> i64 {
            let (nlo, nhi) = ((now - 10_000_000).max(lo), (now + 10_000_000).min(hi));
            match rng.random_range(0..20) {
                // An exact tie: an odd number of half impulses.
                0..=3 => rng.random_range(nlo / h..nhi / h) * h + h / 2,
                // A programmer's round value, 0.01 mm.
                4..=7 => rng.random_range(nlo / 10_000..nhi / 10_000) * 10_000,
                // Any value with 6 decimals.
                8..=11 => rng.random_range(nlo..nhi),
                // A long move anywhere.
                12 => rng.random_range(lo..hi),
                // A short move.
                _ => (now + rng.random_range(-2_000_000..2_000_000)).clamp(lo, hi),
            }
        };
        let x = if rng.random_bool(0.85) {
            let mut t = target(&mut rng, cx, -200_000_000, 200_000_000, 2 * hx);
            if !diam {
                t -= t.rem_euclid(2);
            }
            let w = if inc { t - cx } else { t };
            cx = t;
            Some(nm_to_decimal(if diam { w } else { w / 2 }))
        } else {
            None
        };
        let z = if rng.random_bool(0.85) {
            let t = target(&mut rng, cz, -300_000_000, 50_000_000, hz);
            let w = if inc { t - cz } else { t };
            cz = t;
            Some(nm_to_decimal(w))
        } else {
            None
        };
        // Feeds as programs write them, and rapids.
        let feed = match rng.random_range(0..10) {
            0..=1 => None,
            2..=5 => Some(FEEDS[rng.random_range(0..FEEDS.len())].to_string()),
            _ => Some(nm_to_decimal(rng.random_range(1_000_000..3_000_000_000))),
        };
        steps.push(Step::Move { x, z, inc, feed });
        blocks += 1;
        if blocks % 100 == 0 {
            steps.push(Step::Sync);
        }
    }
    steps.push(Step::Sync);
    Scenario {
        name: format!("random blocks (seed {seed})"),
        steps,
    }
}

/// The seed's BCK-5 tape (Kosenko Table 21, as printed) as `TAPE FRAME=`
/// requests: Latin look-alikes, whitespace dropped; then `TAPE END`.
pub fn tape_requests(listing: &str) -> Vec<String> {
    use core_nostd::calc::tape::{Alphabet, Bck5Letter};
    let latin = |c: char| Bck5Letter::from_char(c).map_or(c, |l| l.to_char(Alphabet::Latin));
    listing
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let frame: String = l
                .chars()
                .filter(|c| !c.is_whitespace())
                .map(latin)
                .collect();
            format!("TAPE FRAME={frame}")
        })
        .chain(std::iter::once("TAPE END".to_string()))
        .collect()
}

/// Every calculator request (`THREAD`, `WEAR`, `DEFLECT`, `TRI`, `TAPE`):
/// the seeds' examples, each input outside its domain, and the seed's
/// BCK-5 tape frame by frame. Two devices with the calculators answer it
/// with identical bytes.
pub fn calculator_session() -> Vec<u8> {
    let mut lines: Vec<String> = [
        "THREAD P=1.5",
        "THREAD P=2 MODE=G07 CROSS=1",
        "LIMITS VZ=1200",
        "THREAD P=1.5 MODE=G06",
        "LIMITS VZ=3000",
        "THREAD P=0",
        "THREAD P=1 MODE=G05",
        "THREAD",
        "WEAR D=40 L=120 S=0.2 U0=5 UR=8 Q=50 ALLOW=20 TOL=50 FULL=300 H=0.8 ALPHA=8",
        "WEAR D=40,30 L=120,50 S=0.15 UR=6 Q=200",
        "WEAR KM=1.5 UR=8 Q=3",
        "WEAR D=40 L=120 S=0.2 U0=5 UR=8 ALLOW=30 TOL=50",
        "WEAR D=40 L=120 S=0 UR=8",
        "WEAR D=40 L=120 S=0.2 UR=8 H=0.5",
        "DEFLECT D=29.8,21.8 L=100,150 T=0.5 HB=220 J=4000,3000,10000 DX=10",
        "DEFLECT D=29.8,21.8 L=100,150 T=0.5 HB=220 J=4000,3000,10000 DX=25 G=1",
        "DEFLECT D=60 L=500 T=1 C=120 X=0.9 J=5000,4000,8000 RED=VOL DX=50",
        "DEFLECT D=29.8 L=100 T=0.5 J=-1,3000,10000",
        "DEFLECT D=29.8,21.8 L=100 T=0.5 J=4000,3000,10000",
        "DEFLECT D=29.8 L=100 T=0 J=4000,3000,10000",
        "DEFLECT D=29.8 L=100 T=0.5 J=4000,3000",
        "DEFLECT D=29.8 L=100 T=0.5 J=4000,3000,10000 PHI=50",
        "TRI AOB=90 BOC=90 COA=90 ROWS=4 LEN=10,10,12",
        "TRI AOB=75 BOC=80 COA=95 H=0.25 ROWS=3 RF=0.5 TABLE=120,40 EA=30 KV=2 V=10,-5,2",
        "TRI AOB=75 BOC=80 OB=97.9824 ROWS=2 G=1",
        "TRI AOB=75 BOC=80 OC=73.785 ROWS=2",
        "TRI AOB=90 BOC=90 COA=90 PROP=1 ROWS=1",
        "TRI AOB=100 BOC=20 COA=30",
        "TRI AOB=90 BOC=90",
        "TRI AOB=190 BOC=90 COA=90",
        "TRI AOB=90 BOC=90 COA=90 KV=5",
        "TRI AOB=90 BOC=90 COA=90 ROWS=1001",
        "DEFLECT D=29.8 L=100 T=0.5 J=4000,3000,10000 DX=0.05",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    lines.extend(tape_requests(include_str!(
        "../../examples/kosenko-table21.bck5"
    )));
    lines.push("TAPE FRAME=5K001E000000D000000P00W00C01Q00H".into());
    lines.push("TAPE END".into());
    let mut s = Vec::new();
    for l in lines {
        s.extend_from_slice(l.as_bytes());
        s.extend_from_slice(b"\r\n");
    }
    s
}

/// A mixed session of raw request bytes: calculator (`CONE`), motion and
/// G-code requests (a compensated program),
/// bad input, binary garbage, an over-long line, wrong and right checksums,
/// every terminator. Two devices that speak the protocol alike answer it with
/// identical bytes.
pub fn mixed_session() -> Vec<u8> {
    let mut s: Vec<u8> = Vec::new();
    fn push(s: &mut Vec<u8>, l: &str) {
        s.extend_from_slice(l.as_bytes());
        s.extend_from_slice(b"\r\n");
    }
    let mut line = |l: &str| push(&mut s, l);
    line("VER");
    line("CFG");
    line("CONE A=45");
    line("CONE A=2:51:51 RN=0.8");
    line("CONE A=90");
    line("cfg hx=0.0025 tol=0.02 pass=rough");
    line("MOVE X=27.532 Z=0");
    line("MOVE X=48 Z=-10.234");
    line("move z=-0.005 inc=1");
    line("POS");
    line(&crate::link::with_checksum("MOVE X=93.532 Z=-56"));
    line("MOVE X=93.532 Z=-56*00");
    line("MOVE X=1*G1");
    line("MOVE X=12.1234567");
    line("MOVE X=1e3");
    line("MOVE Q=1");
    line("MOVE X=100000");
    line("MOVE Z=-99999");
    line("CFG TIP=12");
    line("FROB");
    line("");
    line("   ");
    line("ZERO 1");
    line("G90 G00 X30 Z10");
    line("G42 G01 X28 Z0");
    line("X48 Z-10");
    line("G40 X60");
    // Krylenko Fig. 22 as a G42 contour (arcs, corners, one block late),
    // a concave arc too small for the nose, RESET out of a stuck corner.
    for l in [
        "G00 X0 Z2",
        "N10 G42 G01 Z0",
        "N20 X8",
        "N30 G03 X12 Z-2 R2",
        "N40 G01 Z-14",
        "N50 G02 X18 Z-17 R3",
        "N55 G02 X18.5 Z-17.25 R0.3",
        "N60 G01 X30",
        "N70 G450 G03 X38 Z-21 I0 K-4",
        "N80 G01 X40 Z-22",
        "N90 X40.2 Z-22.05",
        "N100 Z-30",
        "RESET",
        "G40 G00 X60",
    ] {
        line(l);
    }
    line("CFG DIAM=0");
    line("MOVE X=0.0025 Z=0.005");
    line("POS");
    let mut long = "MOVE X=1 ".to_string();
    long.push_str(&"0".repeat(200));
    line(&long);
    line("POS");
    // A Fanuc program (surface speed, feed per revolution, a dwell), then
    // words of the other dialect.
    for l in [
        "CFG DIAM=1",
        "OPT DIALECT=FANUC",
        "%",
        "O1000 (SHAFT)",
        "G21 G18 G99",
        "T0101",
        "G50 S2500",
        "G00 X30. Z2.",
        "G96 S180 M03",
        "M08",
        "G01 Z-40. F.2",
        "U2. W-1.",
        "G04 P50",
        "G00 X40. Z5.",
        "AUX",
        "M05 M09 M30",
        "G91 X1",
        "SYNC",
        "OPT DIALECT=ISO",
        "G99 F1",
        "G95 G96 D3000 S200 M04",
        "G01 X20 F.1",
        "AUX",
        "M5 M2",
    ] {
        line(l);
    }
    let mut tail: Vec<u8> = b"\x00\xff\x1b[A\x7f\xfe\r\nPOS\rPOS\nPOS\r\n\n".to_vec();
    for l in ["CFG HX=0.005 DIAM=1", "MOVE X=0 Z=0", "ZERO", "POS"] {
        push(&mut tail, l);
    }
    s.extend_from_slice(&tail);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_are_exact() {
        assert_eq!(nm_to_decimal(0), "0");
        assert_eq!(nm_to_decimal(-1), "-0.000001");
        assert_eq!(nm_to_decimal(12_500_000), "12.5");
        assert_eq!(nm_to_decimal(-150_000_000), "-150");
    }

    #[test]
    fn random_is_reproducible_and_sized() {
        let a = random(7, 500);
        let b = random(7, 500);
        assert_eq!(a.steps, b.steps);
        assert_eq!(a.blocks(), 500);
        assert_ne!(random(8, 500).steps, a.steps);
    }
}

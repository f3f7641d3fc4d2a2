//! The pendant's `MOVE`, `CFG`, `ZERO` and `POS` replies against the exact
//! rational model (`reference::exact`), line for line.
//!
//! The model is written from `docs/impulses.md` §2–§3, `docs/units.md` §3 and
//! the commands of `docs/protocol.md` §4 alone and shares no arithmetic with
//! the product: exact rationals for lengths, `Q` in integers, the step events
//! straight from the definition and a CRC-32 of its own (its module docs say
//! how). This test drives seeded random sessions, small proptest sessions,
//! closed paths, split segments, ties and range refusals through both.
//!
//! Every reply line's `*HH` checksum (XOR of the bytes before `*`) is checked
//! too. The sessions are seeded and deterministic.

use host_sim::device::LocalDevice;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reference::exact::{crc32, xor_checksum, ExactMachine as Model, Ratio, MICRO};
use reference::protocol::{parse_mm, BLOCK_MAX};

/// Most impulses one block may issue per axis.
const BLOCK: i128 = BLOCK_MAX as i128;
/// Generated coordinates stay within this many mm (X radius and Z), so that
/// every word, absolute or incremental, stays below the 99999.999999 mm limit.
const COORD_LIMIT_UM: i128 = 49_999 * MICRO;

/// What the model expects as the final reply line (body before `*HH`).
#[derive(Debug, Clone, PartialEq, Eq)]
enum Expect {
    Ok(String),
    Err(&'static str),
}

#[derive(Debug, Default, Clone)]
struct Stats {
    requests: u64,
    moves: u64,
    inc_moves: u64,
    omitted_words: u64,
    range_errors: u64,
    cfg_changes: u64,
    diam_changes: u64,
    zeros: u64,
    step_events: u64,
    /// Block end points exactly half-way between impulses (per axis word).
    endpoint_ties: u64,
    /// Registers re-expressed by `CFG` exactly at a tie.
    cfg_ties: u64,
    /// Step events whose other-axis value was exactly at a tie.
    step_ties: u64,
}

impl Stats {
    fn add(&mut self, o: &Stats) {
        self.requests += o.requests;
        self.moves += o.moves;
        self.inc_moves += o.inc_moves;
        self.omitted_words += o.omitted_words;
        self.range_errors += o.range_errors;
        self.cfg_changes += o.cfg_changes;
        self.diam_changes += o.diam_changes;
        self.zeros += o.zeros;
        self.step_events += o.step_events;
        self.endpoint_ties += o.endpoint_ties;
        self.cfg_ties += o.cfg_ties;
        self.step_ties += o.step_ties;
    }
}

/// A `MOVE` on the model, counted.
fn model_move(
    m: &mut Model,
    x: Option<Ratio>,
    z: Option<Ratio>,
    inc: bool,
    st: &mut Stats,
) -> Expect {
    match m.mov(x, z, inc) {
        Ok(b) => {
            st.endpoint_ties += b.endpoint_ties;
            st.step_ties += b.step_ties;
            st.step_events += b.events.len() as u64;
            Expect::Ok(b.reply())
        }
        Err(_) => {
            st.range_errors += 1;
            Expect::Err("RANGE")
        }
    }
}

/// A `CFG` on the model, counted.
fn model_cfg(
    m: &mut Model,
    hx: Option<Ratio>,
    hz: Option<Ratio>,
    diam: Option<bool>,
    st: &mut Stats,
) -> Expect {
    match m.cfg(hx, hz, diam) {
        Ok(c) => {
            st.cfg_ties += c.ties;
            st.cfg_changes += u64::from(c.price_changed);
            st.diam_changes += u64::from(c.diam_changed);
            Expect::Ok(m.cfg_reply())
        }
        Err(_) => {
            st.range_errors += 1;
            Expect::Err("RANGE")
        }
    }
}

// ---------------------------------------------------------------------------
// Requests
// ---------------------------------------------------------------------------

/// A request of a session. Lengths are in micrometres (6 decimals of a mm).
/// `style` varies the spelling: bit0 lower case, bit1 `+` on positive
/// values, bit2 always 6 decimals, bit3 Z word first, bit4 `INC=1` first.
#[derive(Debug, Clone)]
enum Op {
    Move {
        x: Option<i128>,
        z: Option<i128>,
        inc: bool,
        style: u8,
    },
    Cfg {
        hx: Option<i128>,
        hz: Option<i128>,
        diam: Option<bool>,
        style: u8,
    },
    Zero,
    Pos,
}

/// A request length: `[+-]digits[.digits]`, at most 6 decimals.
fn fmt_len(um: i128, style: u8) -> String {
    let sign = if um < 0 {
        "-"
    } else if style & 2 != 0 {
        "+"
    } else {
        ""
    };
    let (i, f) = (um.abs() / MICRO, um.abs() % MICRO);
    if style & 4 != 0 {
        format!("{sign}{i}.{f:06}")
    } else if f == 0 {
        format!("{sign}{i}")
    } else {
        let digits = format!("{f:06}");
        format!("{sign}{i}.{}", digits.trim_end_matches('0'))
    }
}

impl Op {
    fn render(&self) -> String {
        let (words, style) = match *self {
            Op::Move { x, z, inc, style } => {
                let mut w = Vec::new();
                if let Some(x) = x {
                    w.push(format!("X={}", fmt_len(x, style)));
                }
                if let Some(z) = z {
                    w.push(format!("Z={}", fmt_len(z, style)));
                }
                if style & 8 != 0 {
                    w.reverse();
                }
                if inc {
                    if style & 16 != 0 {
                        w.insert(0, "INC=1".to_owned());
                    } else {
                        w.push("INC=1".to_owned());
                    }
                }
                w.insert(0, "MOVE".to_owned());
                (w, style)
            }
            Op::Cfg {
                hx,
                hz,
                diam,
                style,
            } => {
                let mut w = Vec::new();
                if let Some(h) = hx {
                    w.push(format!("HX={}", fmt_len(h, style)));
                }
                if let Some(h) = hz {
                    w.push(format!("HZ={}", fmt_len(h, style)));
                }
                if let Some(d) = diam {
                    w.push(format!("DIAM={}", u8::from(d)));
                }
                if style & 8 != 0 {
                    w.reverse();
                }
                w.insert(0, "CFG".to_owned());
                (w, style)
            }
            Op::Zero => (vec!["ZERO".to_owned()], 0),
            Op::Pos => (vec!["POS".to_owned()], 0),
        };
        let line = words.join(" ");
        if style & 1 != 0 {
            line.to_lowercase()
        } else {
            line
        }
    }
}

// ---------------------------------------------------------------------------
// Device against model
// ---------------------------------------------------------------------------

/// Checks a reply line's `*HH` and returns the part before it.
fn checked_body(line: &str) -> Result<&str, String> {
    let (body, hh) = line
        .rsplit_once('*')
        .ok_or_else(|| format!("reply without checksum: {line:?}"))?;
    let want = format!("{:02X}", xor_checksum(body.as_bytes()));
    if hh != want {
        return Err(format!(
            "reply checksum {hh:?}, the XOR of its bytes is {want}: {line:?}"
        ));
    }
    Ok(body)
}

/// The value of `KEY=` in a reply body.
fn field<'a>(body: &'a str, key: &str) -> &'a str {
    body.split(' ')
        .find_map(|w| w.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key}= in {body:?}"))
}

struct Session {
    dev: LocalDevice,
    model: Model,
    stats: Stats,
    log: Vec<String>,
}

impl Session {
    /// A session whose drives and limits allow every price the model
    /// draws: at 10 mm/min a 0.000001 mm price asks 166 667 step events a
    /// second, within the 200 000 the drives are set to. The exact model
    /// is about positions and impulses, not time.
    fn new() -> Self {
        let mut dev = LocalDevice::new();
        for line in ["DRIVE RATE=200000 PULSE=2 SETUP=1", "LIMITS VX=10 VZ=10"] {
            let replies = dev.request(line);
            assert!(
                replies.len() == 1 && replies[0].starts_with("OK"),
                "{line}: {replies:?}"
            );
        }
        Session {
            dev,
            model: Model::new(),
            stats: Stats::default(),
            log: Vec::new(),
        }
    }

    /// Sends one line and returns the body of its single reply line.
    fn send(&mut self, line: &str) -> Result<String, String> {
        self.stats.requests += 1;
        self.log.push(line.to_owned());
        let replies = self.dev.request(line);
        if replies.len() != 1 {
            return Err(self.context(&format!("expected one reply line, got {replies:?}")));
        }
        let body = checked_body(&replies[0]).map_err(|e| self.context(&e))?;
        Ok(body.to_owned())
    }

    /// The failure text: the message and the last requests of the session.
    fn context(&self, msg: &str) -> String {
        let from = self.log.len().saturating_sub(16);
        format!(
            "{msg}\nrequest #{} of the session; last requests:\n  {}",
            self.log.len(),
            self.log[from..].join("\n  ")
        )
    }

    fn compare(&self, got: &str, want: &Expect) -> Result<(), String> {
        let ok = match want {
            Expect::Ok(w) => got == w,
            Expect::Err(code) => {
                let head = format!("ERR {code}");
                got == head || got.starts_with(&(head + " "))
            }
        };
        if ok {
            Ok(())
        } else {
            Err(self.context(&format!(
                "reply differs from the model\n  device: {got}\n  model:  {want:?}"
            )))
        }
    }

    fn check_pos(&mut self) -> Result<(), String> {
        let got = self.send("POS")?;
        let want = self.model.pos_reply();
        self.compare(&got, &Expect::Ok(want))
    }

    /// Runs one request on both sides and compares; a `MOVE` is followed by
    /// a `POS`. Returns the device's reply body.
    fn step(&mut self, op: &Op) -> Result<String, String> {
        self.run(&op.render(), op)
    }

    /// Like [`Session::step`], with `line` the spelling of `op` sent.
    fn run(&mut self, line: &str, op: &Op) -> Result<String, String> {
        let got = self.send(line)?;
        let st = &mut self.stats;
        let want = match *op {
            Op::Move { x, z, inc, .. } => {
                st.moves += 1;
                st.inc_moves += u64::from(inc);
                st.omitted_words += u64::from(x.is_none()) + u64::from(z.is_none());
                let (x, z) = (x.map(Ratio::micro), z.map(Ratio::micro));
                model_move(&mut self.model, x, z, inc, st)
            }
            Op::Cfg { hx, hz, diam, .. } => {
                let (hx, hz) = (hx.map(Ratio::micro), hz.map(Ratio::micro));
                model_cfg(&mut self.model, hx, hz, diam, st)
            }
            Op::Zero => {
                st.zeros += 1;
                self.model.zero();
                Expect::Ok("OK".to_owned())
            }
            Op::Pos => Expect::Ok(self.model.pos_reply()),
        };
        self.compare(&got, &want)?;
        if matches!(op, Op::Move { .. }) {
            self.check_pos()?;
        }
        Ok(got)
    }
}

// ---------------------------------------------------------------------------
// Random sessions
// ---------------------------------------------------------------------------

/// Impulse prices used by the sessions, in micrometres.
const PRICES_UM: [i128; 21] = [
    1, 2, 5, 7, 10, 25, 100, 500, 1_000, 2_000, 2_500, 3_000, 5_000, 7_500, 10_000, 12_500, 20_000,
    50_000, 100_000, 333_333, 1_000_000,
];

fn price(rng: &mut ChaCha8Rng) -> i128 {
    PRICES_UM[rng.random_range(0..PRICES_UM.len())]
}

/// A word for one axis. `h` the axis price, `coord` its exact commanded
/// coordinate (radius for X), `p` its register, `doubled` whether the word is
/// a diameter. Aims at an exact tie, an exact impulse, a point near one, or
/// anywhere within the chosen span.
fn axis_word(
    rng: &mut ChaCha8Rng,
    h: Ratio,
    coord: Ratio,
    p: i128,
    doubled: bool,
    inc: bool,
) -> i128 {
    let r = rng.random_range(0..1000);
    let span: i128 = if r < 600 {
        30
    } else if r < 900 {
        1_000
    } else if r < 990 {
        8_000
    } else if r < 997 {
        60_000
    } else {
        // Just beyond what one block may issue.
        -1
    };
    let k = if span < 0 {
        let over = BLOCK + rng.random_range(1..100);
        p + if rng.random_bool(0.5) { over } else { -over }
    } else {
        p + rng.random_range(-span..=span)
    };
    let kind = rng.random_range(0..10);
    let target = match kind {
        // Exactly half-way: (2k+1)·h/2.
        0..=2 => (Ratio::int(2 * k + 1) * h).half(),
        // Exactly on an impulse.
        3 | 4 => Ratio::int(k) * h,
        // Within one impulse of one, to half a micrometre.
        5..=7 => {
            let hu = (h * Ratio::int(2 * MICRO)).round();
            Ratio::int(k) * h + Ratio::new(rng.random_range(-hu..=hu), 2 * MICRO)
        }
        // Anywhere near.
        _ => {
            let s = span.abs().max(1);
            let lo = (Ratio::int(p - s) * h).to_micro_trunc();
            let hi = (Ratio::int(p + s) * h).to_micro_trunc();
            Ratio::micro(rng.random_range(lo.min(hi)..=hi.max(lo)))
        }
    };
    let limit = Ratio::micro(COORD_LIMIT_UM);
    let target = if target.n * limit.d > limit.n * target.d {
        limit
    } else if -target.n * limit.d > limit.n * target.d {
        Ratio::micro(-COORD_LIMIT_UM)
    } else {
        target
    };
    let word = if inc { target - coord } else { target };
    let word = if doubled { word.double() } else { word };
    // A word has at most 6 decimals.
    word.to_micro_trunc()
}

fn random_op(rng: &mut ChaCha8Rng, m: &Model) -> Op {
    let r = rng.random_range(0..1000);
    if r < 860 {
        let inc = rng.random_bool(0.35);
        let (with_x, with_z) = match rng.random_range(0..100) {
            0 => (false, false),
            1..=12 => (true, false),
            13..=24 => (false, true),
            _ => (true, true),
        };
        let x = with_x.then(|| axis_word(rng, m.hx, m.cx, m.px, m.diam, inc));
        let z = with_z.then(|| axis_word(rng, m.hz, m.cz, m.pz, false, inc));
        let style = if rng.random_bool(0.8) {
            0
        } else {
            rng.random()
        };
        Op::Move { x, z, inc, style }
    } else if r < 930 {
        let (hx, hz) = match rng.random_range(0..3) {
            0 => (Some(price(rng)), None),
            1 => (None, Some(price(rng))),
            _ => (Some(price(rng)), Some(price(rng))),
        };
        let diam = rng.random_bool(0.2).then(|| rng.random_bool(0.5));
        Op::Cfg {
            hx,
            hz,
            diam,
            style: rng.random(),
        }
    } else if r < 975 {
        Op::Cfg {
            hx: None,
            hz: None,
            diam: Some(!m.diam),
            style: rng.random(),
        }
    } else if r < 985 {
        Op::Zero
    } else {
        Op::Pos
    }
}

fn run_random_session(seed: u64, len: usize) -> Result<Stats, String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut s = Session::new();
    for _ in 0..len {
        let op = random_op(&mut rng, &s.model);
        s.step(&op).map_err(|e| format!("seed {seed}: {e}"))?;
    }
    Ok(s.stats)
}

#[test]
fn random_sessions_match_the_exact_model() {
    let mut total = Stats::default();
    for seed in 0..48u64 {
        match run_random_session(0x5EED_0000 + seed, 300) {
            Ok(st) => total.add(&st),
            Err(e) => panic!("{e}"),
        }
    }
    println!("random sessions: {total:#?}");
    // The sessions must really exercise what they are meant to.
    assert!(total.moves > 10_000);
    assert!(total.endpoint_ties > 1_000, "{total:?}");
    assert!(total.step_ties > 1_000, "{total:?}");
    assert!(total.cfg_ties > 10, "{total:?}");
    assert!(total.cfg_changes > 300 && total.diam_changes > 300 && total.zeros > 50);
    assert!(total.range_errors > 10 && total.inc_moves > 3_000 && total.omitted_words > 1_000);
}

// ---------------------------------------------------------------------------
// Proptest: small sessions, shrinking to a minimal failing one
// ---------------------------------------------------------------------------

fn len_um() -> impl Strategy<Value = i128> {
    prop_oneof![
        4 => (-20_000i64..=20_000).prop_map(i128::from),
        // Multiples of 0.0025 mm: ties at many prices.
        3 => (-400i64..=400).prop_map(|k| i128::from(k) * 2_500),
        1 => (-3_000_000i64..=3_000_000).prop_map(i128::from),
    ]
}

fn price_um() -> impl Strategy<Value = i128> {
    prop::sample::select(vec![
        500i128, 1_000, 2_000, 2_500, 3_000, 5_000, 7_000, 10_000, 12_500, 50_000,
    ])
}

fn op_strategy() -> impl Strategy<Value = Op> {
    prop_oneof![
        8 => (
            prop::option::weighted(0.85, len_um()),
            prop::option::weighted(0.85, len_um()),
            any::<bool>(),
            any::<u8>(),
        )
            .prop_map(|(x, z, inc, style)| Op::Move { x, z, inc, style }),
        2 => (
            prop::option::of(price_um()),
            prop::option::of(price_um()),
            prop::option::of(any::<bool>()),
            any::<u8>(),
        )
            .prop_map(|(hx, hz, diam, style)| Op::Cfg { hx, hz, diam, style }),
        1 => Just(Op::Zero),
        1 => Just(Op::Pos),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 160,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(0x7E57_5EED),
        ..ProptestConfig::default()
    })]

    #[test]
    fn small_sessions_match_the_exact_model(ops in prop::collection::vec(op_strategy(), 1..40)) {
        let mut s = Session::new();
        for op in &ops {
            if let Err(e) = s.step(op) {
                return Err(TestCaseError::fail(e));
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Closed paths and split segments
// ---------------------------------------------------------------------------

#[test]
fn closed_paths_return_to_zero_with_zero_impulse_sums() {
    let mut moves = 0u64;
    for seed in 0..24u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(0xC105_ED00 + seed);
        let mut s = Session::new();
        let cfg = Op::Cfg {
            hx: Some(price(&mut rng)),
            hz: Some(price(&mut rng)),
            diam: Some(rng.random_bool(0.5)),
            style: 0,
        };
        s.step(&cfg).unwrap_or_else(|e| panic!("seed {seed}: {e}"));

        // A path from the program zero, absolute and incremental blocks,
        // back to zero by an absolute block.
        let (mut sx, mut sz) = (0i128, 0i128);
        let n = rng.random_range(5..60);
        for i in 0..=n {
            let op = if i == n {
                Op::Move {
                    x: Some(0),
                    z: Some(0),
                    inc: false,
                    style: 0,
                }
            } else {
                let inc = rng.random_bool(0.4);
                let m = &s.model;
                Op::Move {
                    x: Some(axis_word(&mut rng, m.hx, m.cx, m.px, m.diam, inc)),
                    z: Some(axis_word(&mut rng, m.hz, m.cz, m.pz, false, inc)),
                    inc,
                    style: 0,
                }
            };
            let body = s.step(&op).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            moves += 1;
            if body.starts_with("OK") {
                sx += field(&body, "NX").parse::<i128>().unwrap();
                sz += field(&body, "NZ").parse::<i128>().unwrap();
            }
            if i == n {
                assert_eq!(field(&body, "PX"), "0", "seed {seed}: {body}");
                assert_eq!(field(&body, "PZ"), "0", "seed {seed}: {body}");
            }
        }
        assert_eq!(
            (sx, sz),
            (0, 0),
            "seed {seed}: impulse sums of a closed path"
        );

        // A closed path of increments from wherever the axes are: the words
        // sum to zero, so do the impulses, and the registers come back.
        let start = Op::Move {
            x: Some(rng.random_range(-9_999_999..=9_999_999)),
            z: Some(rng.random_range(-9_999_999..=9_999_999)),
            inc: false,
            style: 0,
        };
        let body = s
            .step(&start)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        if !body.starts_with("OK") {
            continue;
        }
        let (px0, pz0) = (s.model.px, s.model.pz);
        let (mut wx, mut wz, mut sx, mut sz) = (0i128, 0i128, 0i128, 0i128);
        let n = rng.random_range(3..40);
        for i in 0..=n {
            let (x, z) = if i == n {
                (-wx, -wz)
            } else {
                let m = &s.model;
                (
                    axis_word(&mut rng, m.hx, m.cx, m.px, m.diam, true),
                    axis_word(&mut rng, m.hz, m.cz, m.pz, false, true),
                )
            };
            let op = Op::Move {
                x: Some(x),
                z: Some(z),
                inc: true,
                style: 0,
            };
            let body = s.step(&op).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            moves += 1;
            if body.starts_with("OK") {
                wx += x;
                wz += z;
                sx += field(&body, "NX").parse::<i128>().unwrap();
                sz += field(&body, "NZ").parse::<i128>().unwrap();
            } else {
                assert!(i < n, "seed {seed}: the closing block was refused: {body}");
            }
        }
        assert_eq!(
            (sx, sz),
            (0, 0),
            "seed {seed}: impulse sums of a closed path"
        );
        assert_eq!((s.model.px, s.model.pz), (px0, pz0), "seed {seed}");
    }
    println!("closed paths: {moves} blocks");
}

#[test]
fn splitting_a_segment_keeps_the_end_point() {
    for seed in 0..40u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(0x5B11_7000 + seed);
        let hx = price(&mut rng).max(500);
        let hz = price(&mut rng).max(500);
        let diam = rng.random_bool(0.5);
        let (x, z): (i128, i128) = (
            rng.random_range(-3_000_000..=3_000_000),
            rng.random_range(-3_000_000..=3_000_000),
        );
        let cfg = Op::Cfg {
            hx: Some(hx),
            hz: Some(hz),
            diam: Some(diam),
            style: 0,
        };
        let mut whole = Session::new();
        whole.step(&cfg).unwrap();
        let one = Op::Move {
            x: Some(x),
            z: Some(z),
            inc: false,
            style: 0,
        };
        let end = whole
            .step(&one)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));

        let mut split = Session::new();
        split.step(&cfg).unwrap();
        let pieces = rng.random_range(2..12);
        let (mut dx, mut dz) = (0i128, 0i128);
        let mut body = String::new();
        for i in 1..=pieces {
            // Uneven increments with up to 6 decimals that add up exactly.
            let (ix, iz) = if i == pieces {
                (x - dx, z - dz)
            } else {
                (
                    (x - dx) * rng.random_range(1..=9) / 10,
                    (z - dz) * rng.random_range(1..=9) / 10,
                )
            };
            dx += ix;
            dz += iz;
            let op = Op::Move {
                x: Some(ix),
                z: Some(iz),
                inc: true,
                style: 0,
            };
            body = split
                .step(&op)
                .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        }
        assert_eq!(
            (field(&body, "PX"), field(&body, "PZ")),
            (field(&end, "PX"), field(&end, "PZ")),
            "seed {seed}: split into {pieces} pieces"
        );
    }
}

// ---------------------------------------------------------------------------
// Ties, by hand
// ---------------------------------------------------------------------------

/// Parses a request length `[+-]digits[.digits]` into millionths of a mm.
fn parse_len(v: &str) -> i128 {
    let angstrom = parse_mm(v).unwrap_or_else(|e| panic!("{v}: {e:?}"));
    i128::from(angstrom / 10)
}

/// The model's view of a literal `MOVE` or `CFG` line.
fn parse_op(line: &str) -> Op {
    let mut words = line.split(' ');
    let cmd = words.next().unwrap();
    let (mut x, mut z, mut inc) = (None, None, false);
    let (mut hx, mut hz, mut diam) = (None, None, None);
    for w in words {
        let (k, v) = w.split_once('=').unwrap();
        match k {
            "X" => x = Some(parse_len(v)),
            "Z" => z = Some(parse_len(v)),
            "INC" => inc = v == "1",
            "HX" => hx = Some(parse_len(v)),
            "HZ" => hz = Some(parse_len(v)),
            "DIAM" => diam = Some(v == "1"),
            _ => panic!("{w}"),
        }
    }
    match cmd {
        "MOVE" => Op::Move {
            x,
            z,
            inc,
            style: 0,
        },
        "CFG" => Op::Cfg {
            hx,
            hz,
            diam,
            style: 0,
        },
        "ZERO" => Op::Zero,
        "POS" => Op::Pos,
        _ => panic!("{line}"),
    }
}

/// Sends a literal request, checks it against the model, returns the reply.
fn req(s: &mut Session, line: &str) -> String {
    s.run(line, &parse_op(line))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Sends a literal `MOVE`, checks it against the model and against the
/// literal counts `(NX, NZ)`, positions `(PX, PZ)` and step bytes.
fn lit(s: &mut Session, line: &str, n: (i128, i128), p: (i128, i128), steps: &[u8]) {
    let want = format!(
        "OK NX={} NZ={} PX={} PZ={} SEQ={:08X}",
        n.0,
        n.1,
        p.0,
        p.1,
        crc32(steps)
    );
    assert_eq!(req(s, line), want, "request {line:?}");
}

#[test]
fn crc_and_checksum_are_the_standard_ones() {
    assert_eq!(crc32(b""), 0);
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(xor_checksum(b"OK"), b'O' ^ b'K');
    assert!(checked_body("OK*04").is_ok());
    assert!(checked_body("OK*05").is_err());
    assert!(checked_body("OK*4").is_err());
}

#[test]
fn model_self_checks() {
    // The model's own arithmetic is tested in `reference::exact`; here, what
    // this test adds to it: spelling requests and reading them back.
    assert_eq!(fmt_len(-1_500_000, 0), "-1.5");
    assert_eq!(fmt_len(2_000_000, 2), "+2");
    assert_eq!(fmt_len(5, 4), "0.000005");
    for (um, style) in [(-1_500_000, 0), (2_000_000, 2), (5, 4), (-123_456_789, 6)] {
        assert_eq!(parse_len(&fmt_len(um, style)), um);
    }
    let mut m = Model::new();
    let mut st = Stats::default();
    let got = model_move(
        &mut m,
        Some(Ratio::micro(40_000)),
        Some(Ratio::micro(20_000)),
        false,
        &mut st,
    );
    assert_eq!(
        got,
        Expect::Ok(format!(
            "OK NX=4 NZ=2 PX=4 PZ=2 SEQ={:08X}",
            crc32(&[3, 1, 3, 1])
        ))
    );
    assert_eq!((st.step_events, st.step_ties), (4, 2));
}

#[test]
fn ties_round_away_from_zero() {
    // Power-on: HX 0.005 on the radius, HZ 0.01, X words are diameters.
    // X=0.005 is a radius of 0.0025 mm, exactly half an impulse.
    lit(&mut Session::new(), "MOVE X=0.005", (1, 0), (1, 0), &[0x01]);
    lit(
        &mut Session::new(),
        "MOVE X=-0.005",
        (-1, 0),
        (-1, 0),
        &[0x05],
    );
    lit(&mut Session::new(), "MOVE Z=0.005", (0, 1), (0, 1), &[0x02]);
    lit(
        &mut Session::new(),
        "MOVE Z=-0.015",
        (0, -2),
        (0, -2),
        &[0x0A; 2],
    );

    // The same ties in one session, the carry crossing zero.
    let s = &mut Session::new();
    lit(s, "MOVE X=0.005", (1, 0), (1, 0), &[0x01]);
    lit(s, "MOVE X=-0.005", (-2, 0), (-1, 0), &[0x05; 2]);
    lit(s, "MOVE X=0.015", (3, 0), (2, 0), &[0x01; 3]);
    lit(s, "MOVE Z=0.005", (0, 1), (2, 1), &[0x02]);
    lit(s, "MOVE Z=-0.015", (0, -3), (2, -2), &[0x0A; 3]);
    lit(s, "MOVE Z=0.025", (0, 5), (2, 3), &[0x02; 5]);
    // Increments reaching ties: radius 0.0075 − 0.01 = −0.0025, Z 0.035.
    let steps = [0x05, 0x07, 0x05];
    lit(s, "MOVE X=-0.02 Z=0.01 INC=1", (-3, 1), (-1, 4), &steps);
    assert_eq!(req(s, "POS"), "OK PX=-1 PZ=4 X=-0.0050 Z=0.0350");

    // A micrometre either side of the tie.
    let s = &mut Session::new();
    lit(s, "MOVE X=0.004999 Z=0.004999", (0, 0), (0, 0), &[]);
    lit(s, "MOVE X=0.005001 Z=0.005001", (1, 1), (1, 1), &[0x03]);
    lit(s, "MOVE X=-0.004999 Z=-0.004999", (-1, -1), (0, 0), &[0x0F]);
    lit(
        s,
        "MOVE X=-0.005001 Z=-0.005001",
        (-1, -1),
        (-1, -1),
        &[0x0F],
    );

    // Radius words.
    let s = &mut Session::new();
    req(s, "CFG DIAM=0");
    lit(s, "MOVE X=0.0025", (1, 0), (1, 0), &[0x01]);
    lit(s, "MOVE X=-0.0075", (-3, 0), (-2, 0), &[0x05; 3]);

    // The finest price: a diameter of 1 µm is half an impulse.
    let s = &mut Session::new();
    req(s, "CFG HX=0.000001 HZ=0.000001");
    lit(s, "MOVE X=0.000001", (1, 0), (1, 0), &[0x01]);
    lit(s, "MOVE X=-0.000001", (-2, 0), (-1, 0), &[0x05; 2]);
    assert_eq!(req(s, "POS"), "OK PX=-1 PZ=0 X=0.0000 Z=0.0000");

    // Ties inside a block: the other axis at Q(i·Δb/|Δlead|).
    let s = &mut Session::new();
    lit(
        s,
        "MOVE X=0.04 Z=0.02",
        (4, 2),
        (4, 2),
        &[0x03, 0x01, 0x03, 0x01],
    );
    lit(
        s,
        "MOVE X=0 Z=0",
        (-4, -2),
        (0, 0),
        &[0x0F, 0x05, 0x0F, 0x05],
    );
    lit(
        s,
        "MOVE X=0.01 Z=0.04",
        (1, 4),
        (1, 4),
        &[0x02, 0x03, 0x02, 0x02],
    );
    lit(
        s,
        "MOVE X=0 Z=0",
        (-1, -4),
        (0, 0),
        &[0x0A, 0x0F, 0x0A, 0x0A],
    );
    // Equal counts: X leads, every event diagonal.
    lit(s, "MOVE X=0.03 Z=-0.03", (3, -3), (3, -3), &[0x0B; 3]);

    // CFG re-expresses a register at a tie: radius 0.015 at HX 0.01 is 1.5.
    let s = &mut Session::new();
    lit(
        s,
        "MOVE X=0.03 Z=-0.015",
        (3, -2),
        (3, -2),
        &[0x0B, 0x01, 0x0B],
    );
    req(s, "CFG HX=0.01");
    assert_eq!(req(s, "POS"), "OK PX=2 PZ=-2 X=0.0300 Z=-0.0150");
    lit(s, "MOVE X=-0.03 INC=1", (-2, 0), (0, -2), &[0x05; 2]);
    // DIAM changes neither coordinates nor registers, only the X readout.
    req(s, "CFG DIAM=0");
    assert_eq!(req(s, "POS"), "OK PX=0 PZ=-2 X=0.0000 Z=-0.0150");
    lit(s, "MOVE X=0.015", (2, 0), (2, -2), &[0x01; 2]);
    req(s, "CFG DIAM=1");
    assert_eq!(req(s, "POS"), "OK PX=2 PZ=-2 X=0.0300 Z=-0.0150");
    lit(s, "MOVE X=-0.01 INC=1", (-1, 0), (1, -2), &[0x05]);
    req(s, "ZERO");
    assert_eq!(req(s, "POS"), "OK PX=0 PZ=0 X=0.0000 Z=0.0000");
}

// ---------------------------------------------------------------------------
// Range
// ---------------------------------------------------------------------------

/// Sends `line`, expects `ERR RANGE` (the model too), and checks that `POS`
/// and `CFG` read as before.
fn expect_range(s: &mut Session, line: &str) {
    let pos = s.send("POS").unwrap();
    let cfg = s.send("CFG").unwrap();
    let got = req(s, line);
    assert!(got.starts_with("ERR RANGE"), "{line:?} -> {got}");
    assert_eq!(s.send("POS").unwrap(), pos, "after {line:?}");
    assert_eq!(s.send("CFG").unwrap(), cfg, "after {line:?}");
}

#[test]
fn blocks_beyond_a_million_impulses_are_refused() {
    // Z at 0.01: 10000.01 mm is 1 000 001 impulses; 10000.005 is a tie that
    // rounds to 1 000 001.
    let s = &mut Session::new();
    expect_range(s, "MOVE Z=-10000.01");
    expect_range(s, "MOVE Z=10000.005");
    expect_range(s, "MOVE X=0.001 Z=10000.005");
    // X at 0.005 on the radius: a diameter of 10000.01 is 1 000 001.
    expect_range(s, "MOVE X=10000.01 Z=0.001");
    expect_range(s, "MOVE X=-10000.005");
    // After a refused block the next one starts from the unchanged state.
    lit(s, "MOVE X=0.005 Z=-0.005", (1, -1), (1, -1), &[0x0B]);
    expect_range(s, "MOVE Z=10000 INC=1");
    lit(s, "MOVE Z=0.005 INC=1", (0, 1), (1, 0), &[0x02]);

    // The finest price: one micrometre on the radius.
    let s = &mut Session::new();
    req(s, "CFG HX=0.000001 HZ=0.000001 DIAM=0");
    expect_range(s, "MOVE X=1.000001");
    expect_range(s, "MOVE X=-1.000001 Z=0.000003");
    expect_range(s, "MOVE Z=1.000001 INC=1");
    // Exactly a million is a block the machine takes.
    let got = req(s, "MOVE X=1");
    assert!(
        got.starts_with("OK NX=1000000 NZ=0 PX=1000000 PZ=0 SEQ="),
        "{got}"
    );
    expect_range(s, "MOVE X=-0.000001");
    expect_range(s, "MOVE X=1.000001 INC=1");

    // Positions beyond 999 999 999 impulses, reached by a change of price.
    let s = &mut Session::new();
    req(s, "CFG HX=1 HZ=1");
    lit(
        s,
        "MOVE X=2000 Z=999.999999",
        (1000, 1000),
        (1000, 1000),
        &[0x03; 1000],
    );
    // Radius 1000 mm is 10^9 impulses of 1 µm; DIAM is not changed either.
    expect_range(s, "CFG HX=0.000001 DIAM=0");
    // Radius 999.999999 mm is 999 999 999 impulses: held.
    lit(s, "MOVE X=1999.999998", (0, 0), (1000, 1000), &[]);
    req(s, "CFG HX=0.000001 HZ=0.000001");
    assert_eq!(
        req(s, "POS"),
        "OK PX=999999999 PZ=999999999 X=2000.0000 Z=1000.0000"
    );
    expect_range(s, "MOVE X=0.000002 INC=1");
    expect_range(s, "MOVE Z=0.000001 INC=1");
    lit(
        s,
        "MOVE X=-0.000002 Z=-0.000001 INC=1",
        (-1, -1),
        (999_999_998, 999_999_998),
        &[0x0F],
    );
}

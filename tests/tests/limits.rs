//! Every row of the Limits table of `docs/protocol.md`, through the device's
//! byte interface: each limit exactly at its boundary (accepted, with the exact
//! reply and effect checked) and one step beyond it (refused with exactly the
//! documented error code, with `POS`, `CFG`, `DRIVE` and the exact session
//! state unchanged and no motion issued).
//!
//! Rows: request line (120 bytes), length word (6 decimals, below 100 000 mm),
//! commanded coordinate after `INC=1`, position register (999 999 999
//! impulses), one block (1 000 000 impulses per axis: linear, one chord of an
//! arc, a direct arc), impulse prices, `RN`, `TOL`, `TIP`, `RATE`, `PULSE`,
//! `SETUP`, chords of one arc (10 000), chord angle (1″), arc radius mismatch
//! (0.002 mm), words per request.
//!
//! Expected step sequences (`SEQ`) and direct-arc step counts are computed
//! here from the documented rules, independently of the device.
//!
//! The chord angle row can only be checked at its boundary: with the smallest
//! tolerance (0.000001 mm) and the largest radius a request can express (an
//! `I`, `K` vector just under 100 000 mm on each axis), Δφ is still about
//! 1.55″, so no request reaches the `Δφ below 1″` refusal. The test checks that
//! bound and that such arcs run with Δφ = 1″.

use host_sim::device::LocalDevice;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------
// Talking to the device
// ---------------------------------------------------------------------------

/// The body of one reply line, after checking its `*HH` (XOR of the bytes
/// before the `*`).
fn checked(line: &str) -> String {
    let (body, sum) = line
        .rsplit_once('*')
        .unwrap_or_else(|| panic!("reply line without *HH: {line:?}"));
    assert_eq!(sum.len(), 2, "malformed checksum in {line:?}");
    let given = u8::from_str_radix(sum, 16).unwrap_or_else(|_| panic!("bad *HH in {line:?}"));
    let want = body.bytes().fold(0u8, |a, b| a ^ b);
    assert_eq!(given, want, "wrong checksum in {line:?}");
    assert!(line.len() <= 155, "reply line over 155 bytes: {line:?}");
    body.to_owned()
}

/// Sends one request (LF appended); returns the checked reply bodies.
fn send(dev: &mut LocalDevice, line: &str) -> Vec<String> {
    dev.request(line).iter().map(|l| checked(l)).collect()
}

/// Raw bytes in, checked reply bodies out (every line must end in CRLF).
fn feed(dev: &mut LocalDevice, bytes: &[u8]) -> Vec<String> {
    let out = String::from_utf8(dev.feed(bytes)).expect("replies are ASCII");
    assert!(out.is_empty() || out.ends_with("\r\n"), "{out:?}");
    out.split_terminator("\r\n").map(checked).collect()
}

/// A request answered by exactly one line; returns it.
fn one(dev: &mut LocalDevice, line: &str) -> String {
    let r = send(dev, line);
    assert_eq!(r.len(), 1, "{line}: {r:?}");
    r.into_iter().next().unwrap_or_default()
}

/// A request that must be answered with exactly `want` (one line).
fn expect(dev: &mut LocalDevice, line: &str, want: &str) {
    assert_eq!(one(dev, line), want, "reply to {line}");
}

/// The value of `KEY=` in a reply line.
fn word<'a>(line: &'a str, key: &str) -> &'a str {
    line.split(' ')
        .find_map(|w| w.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key}= in {line:?}"))
}

fn int(line: &str, key: &str) -> i64 {
    word(line, key)
        .parse()
        .unwrap_or_else(|_| panic!("{key} not an integer in {line:?}"))
}

/// What a refusal must leave untouched.
#[derive(Debug, PartialEq)]
struct State {
    pos: String,
    cfg: String,
    drive: String,
    /// The exact session (commanded coordinates to the ångström, registers,
    /// configuration, timing, modal state).
    session: String,
}

fn state(dev: &mut LocalDevice) -> State {
    let session = format!("{:?}", dev.device().session());
    State {
        pos: one(dev, "POS"),
        cfg: one(dev, "CFG"),
        drive: one(dev, "DRIVE"),
        session,
    }
}

/// `line` must draw exactly `ERR <code> …` (`code` may name the key, as in
/// `VALUE X`), change no state and issue no motion.
fn refused(dev: &mut LocalDevice, line: &str, code: &str) {
    let before = state(dev);
    let issued = dev.issued();
    let r = one(dev, line);
    let want = format!("ERR {code}");
    assert!(
        r == want || r.starts_with(&format!("{want} ")),
        "{line}: got {r:?}, documented {want}"
    );
    assert_eq!(dev.issued(), issued, "{line} issued motion");
    assert_eq!(state(dev), before, "{line} changed state");
}

/// A fresh device with `DIAM=0` (X words are radii) and the given prices,
/// its rapid rates slow enough for the finest price (`VMAX/h ≤ RATE`).
fn device(hx: &str, hz: &str) -> LocalDevice {
    let mut dev = LocalDevice::new();
    let r = one(&mut dev, "LIMITS VX=1 VZ=1");
    assert!(r.starts_with("OK "), "{r}");
    let r = one(&mut dev, &format!("CFG DIAM=0 HX={hx} HZ={hz}"));
    assert!(r.starts_with("OK "), "{r}");
    dev
}

// ---------------------------------------------------------------------------
// The documented rules, computed independently
// ---------------------------------------------------------------------------

/// `Q(p / h)`: rounding half away from zero, `h > 0`.
fn q(p: i128, h: i128) -> i128 {
    let (d, r) = (p / h, p % h);
    if 2 * r.abs() >= h {
        d + p.signum()
    } else {
        d
    }
}

/// A decimal mm value with at most 6 decimals, in nm.
fn nm(s: &str) -> i128 {
    let (neg, s) = match s.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    let (i, f) = s.split_once('.').unwrap_or((s, ""));
    assert!(f.len() <= 6, "{s}");
    let v = i.parse::<i128>().unwrap() * 1_000_000 + format!("{f:0<6}").parse::<i128>().unwrap();
    if neg {
        -v
    } else {
        v
    }
}

/// CRC-32 (IEEE, as zlib), fed byte by byte.
struct Crc(u32);

impl Crc {
    fn new() -> Self {
        Crc(!0)
    }
    fn push(&mut self, byte: u8) {
        let mut c = self.0 ^ u32::from(byte);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
        self.0 = c;
    }
    fn hex(&self) -> String {
        format!("{:08X}", !self.0)
    }
}

/// One step event byte: bit0 X steps, bit1 Z steps, bit2 X negative, bit3 Z
/// negative.
fn event(x: i64, z: i64) -> u8 {
    u8::from(x != 0) | u8::from(z != 0) << 1 | u8::from(x < 0) << 2 | u8::from(z < 0) << 3
}

/// The step events of a linear block of `dx`, `dz` impulses: the leading axis
/// (larger |Δ|, X when equal) steps every event, the other is at
/// `Q(i·Δb/|Δlead|)` after event `i`.
fn linear_events(dx: i64, dz: i64, crc: &mut Crc) {
    let x_leads = dx.abs() >= dz.abs();
    let (lead, other) = if x_leads { (dx, dz) } else { (dz, dx) };
    let n = lead.abs();
    let mut at = 0i128;
    for i in 1..=n {
        let next = q(i128::from(i) * i128::from(other), i128::from(n));
        let o = (next - at) as i64;
        at = next;
        let l = lead.signum();
        crc.push(if x_leads { event(l, o) } else { event(o, l) });
    }
}

fn linear_seq(dx: i64, dz: i64) -> String {
    let mut crc = Crc::new();
    linear_events(dx, dz, &mut crc);
    crc.hex()
}

/// The `OK` of a `MOVE`.
fn move_ok(nx: i64, nz: i64, px: i64, pz: i64) -> String {
    format!(
        "OK NX={nx} NZ={nz} PX={px} PZ={pz} SEQ={}",
        linear_seq(nx, nz)
    )
}

/// A direct arc as documented: from `(a, b)` impulses relative to the centre,
/// issuing `da` on X and `db` on Z, each step to the candidate with the
/// smallest `|F|`, `F = (a·hx)² + (b·hz)² − R²` (prices in Å, `r2` in Å²),
/// ties in the order both, X, Z; an axis stops when it has issued its
/// impulses. Returns the number of step events and their CRC.
fn direct_events(a: i64, b: i64, da: i64, db: i64, hx: i128, hz: i128, r2: i128) -> (u64, String) {
    let (sa, sb) = (da.signum(), db.signum());
    let (mut a, mut b) = (i128::from(a), i128::from(b));
    let (mut left_a, mut left_b) = (da.abs(), db.abs());
    let f = |a: i128, b: i128| ((a * hx).pow(2) + (b * hz).pow(2) - r2).abs();
    let mut crc = Crc::new();
    let mut n = 0u64;
    while left_a > 0 || left_b > 0 {
        let mut best: Option<(i128, i64, i64)> = None;
        for (x, z) in [(1, 1), (1, 0), (0, 1)] {
            if (x == 1 && left_a == 0) || (z == 1 && left_b == 0) {
                continue;
            }
            let v = f(a + i128::from(x * sa), b + i128::from(z * sb));
            if best.is_none_or(|(bv, _, _)| v < bv) {
                best = Some((v, x, z));
            }
        }
        let (_, x, z) = best.unwrap();
        a += i128::from(x * sa);
        b += i128::from(z * sb);
        left_a -= x;
        left_b -= z;
        crc.push(event(x * sa, z * sb));
        n += 1;
    }
    (n, crc.hex())
}

/// Δφ in arc-seconds, `2·arccos(1 − σ/R)`, evaluated as the equal
/// `4·atan2(√σ, √(2R − σ))`, which keeps its precision for tiny `σ/R`.
fn dphi_arcsec(sigma: f64, r: f64) -> f64 {
    4.0 * sigma.sqrt().atan2((2.0 * r - sigma).sqrt()) * 648_000.0 / PI
}

/// Δφ for `FIN` (rounded down), asserting the f64 value is clear of a whole
/// arc-second so the floor is certain.
fn fin_dphi(sigma: f64, r: f64) -> u64 {
    let d = dphi_arcsec(sigma, r);
    assert!(
        d.fract() > 0.01 && d.fract() < 0.99,
        "Δφ {d}″ too close to a whole second"
    );
    d.floor() as u64
}

/// `DPHI=` for a Δφ in whole arc-seconds: degrees with 6 decimals.
fn dphi_word(arcsec: u64) -> String {
    let micro = (arcsec * 5000 + 9) / 18; // arcsec·10⁶/3600, to nearest
    format!("{}.{:06}", micro / 1_000_000, micro % 1_000_000)
}

/// Checks the reply of an accepted chord arc: `n` `DATA I=` lines numbered
/// 1 … n, the `OK` totals equal to their sum and to the register change, the
/// end registers, `DPHI`, and `SEQ` over the chords' step events.
fn check_chord_arc(reply: &[String], n: usize, dphi: u64, start: (i64, i64), end: (i64, i64)) {
    assert_eq!(reply.len(), n + 1, "{:?}", reply.last());
    let ok = reply.last().unwrap();
    assert!(ok.starts_with("OK "), "{ok}");
    assert_eq!(int(ok, "N"), n as i64, "{ok}");
    assert_eq!(word(ok, "DPHI"), dphi_word(dphi), "{ok}");
    let mut crc = Crc::new();
    let (mut sx, mut sz) = (0, 0);
    for (i, d) in reply[..n].iter().enumerate() {
        assert!(d.starts_with("DATA "), "{d}");
        assert_eq!(int(d, "I"), i as i64 + 1, "{d}");
        let (nx, nz) = (int(d, "NX"), int(d, "NZ"));
        assert!(nx.abs() <= 1_000_000 && nz.abs() <= 1_000_000, "{d}");
        linear_events(nx, nz, &mut crc);
        sx += nx;
        sz += nz;
    }
    assert_eq!((int(ok, "PX"), int(ok, "PZ")), end, "{ok}");
    assert_eq!((int(ok, "NX"), int(ok, "NZ")), (sx, sz), "{ok}");
    assert_eq!((start.0 + sx, start.1 + sz), end, "{ok}");
    assert_eq!(word(ok, "SEQ"), crc.hex(), "{ok}");
}

/// A point on the circle of radius `r` about `(cx, cz)`, `arcsec` arc-seconds
/// from +Z towards +X (counter-clockwise), as 6-decimal words `(X, Z)`.
fn on_circle(cx: f64, cz: f64, r: f64, arcsec: f64) -> (String, String) {
    let t = arcsec * PI / 648_000.0;
    (
        format!("{:.6}", cx + r * t.sin()),
        format!("{:.6}", cz + r * t.cos()),
    )
}

// ---------------------------------------------------------------------------
// Request line: 120 bytes, terminator excluded → ERR LINE_TOO_LONG
// ---------------------------------------------------------------------------

/// `head`, spaces, `tail`: exactly `len` bytes.
fn padded(head: &str, tail: &str, len: usize) -> String {
    let s = format!("{head}{}{tail}", " ".repeat(len - head.len() - tail.len()));
    assert_eq!(s.len(), len);
    s
}

#[test]
fn request_line_of_120_bytes_runs_and_121_is_too_long_once() {
    let mut dev = LocalDevice::new();

    // 120 bytes: an ordinary request.
    let line = padded("MOVE X=10", "Z=-5", 120);
    assert_eq!(
        feed(&mut dev, format!("{line}\n").as_bytes()),
        [move_ok(1000, -500, 1000, -500)]
    );
    // 120 bytes including a checksum.
    let body = padded("MOVE X=20", "Z=-10", 117);
    let sum = body.bytes().fold(0u8, |a, b| a ^ b);
    let line = format!("{body}*{sum:02X}");
    assert_eq!(line.len(), 120);
    assert_eq!(
        feed(&mut dev, format!("{line}\r\n").as_bytes()),
        [move_ok(1000, -500, 2000, -1000)]
    );
    // 120 bytes of nothing valid: still read as one request.
    let junk = "A".repeat(120);
    let r = feed(&mut dev, format!("{junk}\n").as_bytes());
    assert_eq!(r.len(), 1, "{r:?}");
    assert!(r[0].starts_with("ERR UNKNOWN "), "{r:?}");

    // 121 bytes and more, with each terminator: one ERR LINE_TOO_LONG, the
    // rest of the line discarded (neither its first 120 bytes nor its tail
    // run), and the next request answered normally.
    let before = state(&mut dev);
    let pos = before.pos.clone();
    let long_tail = " MOVE X=50 Z=0".repeat(30);
    for terminator in ["\n", "\r", "\r\n"] {
        for tail in ["", " MOVE X=40", long_tail.as_str()] {
            let over = format!("{}5{tail}", padded("MOVE X=30", "Z=-15", 120));
            assert!(over.len() >= 121);
            let issued = dev.issued();
            let r = feed(&mut dev, format!("{over}{terminator}POS\r\n").as_bytes());
            assert_eq!(r.len(), 2, "{terminator:?} {tail:?}: {r:?}");
            assert!(r[0].starts_with("ERR LINE_TOO_LONG"), "{r:?}");
            assert!(r[0] == "ERR LINE_TOO_LONG" || r[0].starts_with("ERR LINE_TOO_LONG "));
            assert_eq!(r[1], pos);
            assert_eq!(dev.issued(), issued);
        }
    }
    assert_eq!(state(&mut dev), before);

    // The refusal comes at the 121st byte, not at the terminator.
    let over = format!("{}{}", padded("MOVE X=30", "Z=-15", 120), "0".repeat(300));
    for (i, b) in over.bytes().enumerate() {
        let r = feed(&mut dev, &[b]);
        if i == 120 {
            assert_eq!(r.len(), 1, "{r:?}");
            assert!(r[0].starts_with("ERR LINE_TOO_LONG"), "{r:?}");
        } else {
            assert!(r.is_empty(), "byte {}: {r:?}", i + 1);
        }
    }
    assert!(feed(&mut dev, b"\r\n").is_empty());
    assert_eq!(state(&mut dev), before);
}

// ---------------------------------------------------------------------------
// Length word: 6 decimals, magnitude < 100 000 mm → ERR VALUE <KEY>
// ---------------------------------------------------------------------------

#[test]
fn length_word_of_six_decimals_below_100000_mm() {
    let mut dev = device("1", "1");
    // The largest words on both axes, both signs.
    expect(
        &mut dev,
        "MOVE X=99999.999999 Z=-99999.999999",
        &move_ok(100_000, -100_000, 100_000, -100_000),
    );
    expect(
        &mut dev,
        "POS",
        "OK PX=100000 PZ=-100000 X=100000.0000 Z=-100000.0000",
    );
    // Taken exactly: the increment back lands on exactly 0, as a 1 nm price
    // shows; and the sixth decimal is one impulse at that price.
    expect(
        &mut dev,
        "MOVE X=-99999.999999 Z=+99999.999999 INC=1",
        &move_ok(-100_000, 100_000, 0, 0),
    );
    one(&mut dev, "CFG HX=0.000001 HZ=0.000001");
    expect(&mut dev, "POS", "OK PX=0 PZ=0 X=0.0000 Z=0.0000");
    expect(
        &mut dev,
        "MOVE X=0.000001 Z=-0.000001",
        &move_ok(1, -1, 1, -1),
    );
    // A diameter word at the limit is halved exactly.
    let mut d = LocalDevice::new();
    one(&mut d, "CFG HX=1");
    expect(
        &mut d,
        "MOVE X=99999.999999",
        &move_ok(50_000, 0, 50_000, 0),
    );

    // One step beyond: 7 decimals, or 100 000 mm.
    for (line, code) in [
        ("MOVE X=100000", "VALUE X"),
        ("MOVE X=100000.000000", "VALUE X"),
        ("MOVE X=-100000", "VALUE X"),
        ("MOVE Z=100000", "VALUE Z"),
        ("MOVE Z=-100000", "VALUE Z"),
        ("MOVE X=0.0000001", "VALUE X"),
        ("MOVE X=1.0000000", "VALUE X"),
        ("MOVE Z=-0.0000001", "VALUE Z"),
        ("MOVE Z=99999.9999990", "VALUE Z"),
        ("MOVE X=1 Z=100000", "VALUE Z"),
        ("ARC X=0 Z=0 I=100000 K=0 DIR=CW", "VALUE I"),
        ("ARC X=0 Z=0 I=0 K=-0.0000001 DIR=CW", "VALUE K"),
        ("ARC X=-100000 Z=0 I=1 K=0 DIR=CW", "VALUE X"),
        ("ARC X=0 Z=0.0000001 I=1 K=0 DIR=CW", "VALUE Z"),
        ("CFG RN=0.0000001", "VALUE RN"),
        ("CFG TOL=0.0000001", "VALUE TOL"),
    ] {
        refused(&mut dev, line, code);
        refused(&mut d, line, code);
    }
}

// ---------------------------------------------------------------------------
// Commanded coordinate after INC=1: |X radius|, |Z| ≤ 99 999.999999 mm → ERR RANGE
// ---------------------------------------------------------------------------

#[test]
fn commanded_coordinate_after_increments() {
    let mut dev = device("1", "1");
    expect(
        &mut dev,
        "MOVE X=99999.999998 Z=-99999.999998",
        &move_ok(100_000, -100_000, 100_000, -100_000),
    );
    // To the limit by increments: accepted.
    expect(
        &mut dev,
        "MOVE X=0.000001 Z=-0.000001 INC=1",
        &move_ok(0, 0, 100_000, -100_000),
    );
    // One nanometre beyond, on either axis: refused.
    refused(&mut dev, "MOVE X=0.000001 INC=1", "RANGE");
    refused(&mut dev, "MOVE Z=-0.000001 INC=1", "RANGE");
    refused(&mut dev, "MOVE X=0.000001 Z=0 INC=1", "RANGE");
    refused(&mut dev, "MOVE X=-1 Z=-0.000001 INC=1", "RANGE");
    refused(
        &mut dev,
        "MOVE X=99999.999999 Z=-99999.999999 INC=1",
        "RANGE",
    );
    // The accepted increment reached exactly ±99 999.999999: going back by
    // exactly that much lands on 0 to the nanometre.
    expect(
        &mut dev,
        "MOVE X=-99999.999999 Z=99999.999999 INC=1",
        &move_ok(-100_000, 100_000, 0, 0),
    );
    one(&mut dev, "CFG HX=0.000001 HZ=0.000001");
    expect(&mut dev, "POS", "OK PX=0 PZ=0 X=0.0000 Z=0.0000");

    // The same on the other side, X negative and Z positive.
    let mut dev = device("1", "1");
    one(&mut dev, "MOVE X=-99999.999999 Z=99999.999998");
    expect(
        &mut dev,
        "MOVE Z=0.000001 INC=1",
        &move_ok(0, 0, -100_000, 100_000),
    );
    refused(&mut dev, "MOVE X=-0.000001 INC=1", "RANGE");
    refused(&mut dev, "MOVE Z=0.000001 INC=1", "RANGE");
}

// ---------------------------------------------------------------------------
// Position register: ≤ 999 999 999 impulses → ERR RANGE
// ---------------------------------------------------------------------------

#[test]
fn position_register_of_999_999_999_impulses() {
    let mut dev = device("1", "1");
    expect(
        &mut dev,
        "MOVE X=999.999999 Z=-999.999999",
        &move_ok(1000, -1000, 1000, -1000),
    );
    // A price change re-expresses the registers exactly at the limit.
    expect(
        &mut dev,
        "CFG HX=0.000001 HZ=0.000001",
        "OK HX=0.0000 HZ=0.0000 DIAM=0 RN=0.4000 TIP=3 TOL=0.0100 PASS=FIN",
    );
    expect(
        &mut dev,
        "POS",
        "OK PX=999999999 PZ=-999999999 X=1000.0000 Z=-1000.0000",
    );
    // One impulse beyond, by a move on either axis.
    refused(&mut dev, "MOVE X=0.000001 INC=1", "RANGE");
    refused(&mut dev, "MOVE Z=-0.000001 INC=1", "RANGE");
    refused(&mut dev, "MOVE X=1000", "RANGE");
    refused(&mut dev, "MOVE Z=-1000", "RANGE");
    // To the limit by a move.
    expect(
        &mut dev,
        "MOVE X=-0.000001 Z=0.000001 INC=1",
        &move_ok(-1, 1, 999_999_998, -999_999_998),
    );
    expect(
        &mut dev,
        "MOVE X=999.999999 Z=-999.999999",
        &move_ok(1, -1, 999_999_999, -999_999_999),
    );
    refused(&mut dev, "MOVE X=1000 Z=-1000", "RANGE");

    // One impulse beyond by a price change: refused, the old price kept.
    let mut dev = device("1", "1");
    expect(
        &mut dev,
        "MOVE X=1000 Z=-1000",
        &move_ok(1000, -1000, 1000, -1000),
    );
    refused(&mut dev, "CFG HX=0.000001", "RANGE");
    refused(&mut dev, "CFG HZ=0.000001", "RANGE");
    refused(&mut dev, "CFG HX=0.000001 HZ=0.000001", "RANGE");
    // Half an impulse beyond rounds away from zero, to 1 000 000 000.
    let mut dev = LocalDevice::new();
    one(&mut dev, "LIMITS VX=1 VZ=1");
    one(&mut dev, "CFG HX=1");
    expect(&mut dev, "MOVE X=1999.999999", &move_ok(1000, 0, 1000, 0));
    refused(&mut dev, "CFG HX=0.000001", "RANGE");
    expect(&mut dev, "MOVE X=1999.999998", &move_ok(0, 0, 1000, 0));
    one(&mut dev, "CFG HX=0.000001");
    expect(&mut dev, "POS", "OK PX=999999999 PZ=0 X=2000.0000 Z=0.0000");
}

// ---------------------------------------------------------------------------
// One block: ≤ 1 000 000 impulses per axis → ERR RANGE
// ---------------------------------------------------------------------------

#[test]
fn one_linear_block_of_1_000_000_impulses_per_axis() {
    let mut dev = device("0.000001", "0.000001");
    let issued = dev.issued();
    expect(
        &mut dev,
        "MOVE X=1 Z=-1",
        &move_ok(1_000_000, -1_000_000, 1_000_000, -1_000_000),
    );
    // Queued; it runs at the flush: a million diagonal events.
    assert!(one(&mut dev, "SYNC").starts_with("OK EV=1000000 "));
    assert_eq!(dev.issued() - issued, 1_000_000);
    // One impulse more on either axis.
    refused(&mut dev, "MOVE X=-0.000001", "RANGE");
    refused(&mut dev, "MOVE Z=0.000001", "RANGE");
    refused(&mut dev, "MOVE X=2.000001 Z=-1", "RANGE");
    refused(&mut dev, "MOVE X=1 Z=-2.000001", "RANGE");
    refused(&mut dev, "MOVE X=-1.000001 Z=1.000001 INC=1", "RANGE");
    // A G-code block is a block too.
    refused(&mut dev, "G01 X-0.000001 F100", "RANGE");
}

#[test]
fn one_chord_of_an_arc_of_1_000_000_impulses_per_axis() {
    // A quarter circle of radius 1 mm cut into a single chord (Δφ > 90° with
    // TOL=0.7) at 1 nm prices: the chord moves 1 000 000 impulses on each axis.
    let sigma = 0.7;
    let dphi = fin_dphi(sigma, 1.0);
    assert!(dphi > 324_000 && dphi < 648_000);
    let mut dev = device("0.000001", "0.000001");
    let r = send(&mut dev, "ARC X=-1 Z=1 I=-1 K=0 DIR=CW TOL=0.7");
    check_chord_arc(&r, 1, dphi, (0, 0), (-1_000_000, 1_000_000));
    assert_eq!(r[0], "DATA I=1 NX=-1000000 NZ=1000000");
    let mut seq = Crc::new();
    for _ in 0..1_000_000 {
        seq.push(0b0111);
    }
    assert_eq!(word(&r[1], "SEQ"), seq.hex());
    expect(
        &mut dev,
        "POS",
        "OK PX=-1000000 PZ=1000000 X=-1.0000 Z=1.0000",
    );

    // Radius 1.000001 mm: the one chord moves 1 000 001 impulses per axis.
    assert!(dphi_arcsec(sigma, 1.000001) > 324_000.0);
    let mut dev = device("0.000001", "0.000001");
    refused(
        &mut dev,
        "ARC X=-1.000001 Z=1.000001 I=-1.000001 K=0 DIR=CW TOL=0.7",
        "RANGE",
    );
    // Only X beyond: start radius 1.000001 mm, end radius 1 mm (within the
    // mismatch), so Z moves 1 000 000 and X 1 000 001.
    refused(
        &mut dev,
        "ARC X=-1.000001 Z=1 I=-1.000001 K=0 DIR=CW TOL=0.7",
        "RANGE",
    );
}

#[test]
fn one_direct_arc_of_1_000_000_impulses_per_axis() {
    // The same quarter circle as one ЭМ-907 block: X −1 000 000, Z +1 000 000.
    let mut dev = device("0.000001", "0.000001");
    let r = send(&mut dev, "ARC X=-1 Z=1 I=-1 K=0 DIR=CW MODE=DIRECT");
    assert_eq!(r.len(), 2, "{r:?}");
    assert_eq!(r[0], "DATA G02 X-1000000 Z+1000000 J1000000 K0");
    // From (a, b) = (1 000 000, 0) about the centre, R = 1 mm = 10⁷ Å.
    let (n, seq) = direct_events(
        1_000_000,
        0,
        -1_000_000,
        1_000_000,
        10,
        10,
        10_000_000i128.pow(2),
    );
    assert_eq!(
        r[1],
        format!("OK N={n} NX=-1000000 NZ=1000000 PX=-1000000 PZ=1000000 SEQ={seq}")
    );
    expect(
        &mut dev,
        "POS",
        "OK PX=-1000000 PZ=1000000 X=-1.0000 Z=1.0000",
    );

    let mut dev = device("0.000001", "0.000001");
    refused(
        &mut dev,
        "ARC X=-1.000001 Z=1.000001 I=-1.000001 K=0 DIR=CW MODE=DIRECT",
        "RANGE",
    );
}

// ---------------------------------------------------------------------------
// Impulse prices HX, HZ: 0.000001 … 1 mm → ERR VALUE HX / HZ
// ---------------------------------------------------------------------------

#[test]
fn impulse_prices_from_0_000001_to_1_mm() {
    let mut dev = LocalDevice::new();
    // 1 nm per impulse needs rapid rates within 60 mm/min·RATE·h.
    refused(&mut dev, "CFG DIAM=0 HX=0.000001 HZ=1", "VALUE HX");
    assert!(one(&mut dev, "LIMITS VX=1 VZ=1").starts_with("OK "));
    expect(
        &mut dev,
        "CFG DIAM=0 HX=0.000001 HZ=1",
        "OK HX=0.0000 HZ=1.0000 DIAM=0 RN=0.4000 TIP=3 TOL=0.0100 PASS=FIN",
    );
    expect(&mut dev, "MOVE X=0.000007 Z=7", &move_ok(7, 7, 7, 7));
    expect(&mut dev, "MOVE X=0.000008 Z=7.5", &move_ok(1, 1, 8, 8));
    // Swapped: the registers re-expressed, then the same effect per axis.
    expect(
        &mut dev,
        "CFG HX=1 HZ=0.000001",
        "OK HX=1.0000 HZ=0.0000 DIAM=0 RN=0.4000 TIP=3 TOL=0.0100 PASS=FIN",
    );
    expect(&mut dev, "POS", "OK PX=0 PZ=7500000 X=0.0000 Z=7.5000");
    expect(
        &mut dev,
        "MOVE X=7 Z=7.500007",
        &move_ok(7, 7, 7, 7_500_007),
    );

    for key in ["HX", "HZ"] {
        for v in ["0", "-0.000001", "1.000001", "-1", "0.0000009"] {
            refused(&mut dev, &format!("CFG {key}={v}"), &format!("VALUE {key}"));
        }
    }
    // A CFG is applied whole or not at all.
    refused(&mut dev, "CFG HX=0.5 HZ=1.000001", "VALUE HZ");
    refused(&mut dev, "CFG HX=0 HZ=0.5", "VALUE HX");
}

// ---------------------------------------------------------------------------
// Nose radius RN: 0 … 25 mm → ERR VALUE RN
// ---------------------------------------------------------------------------

#[test]
fn nose_radius_from_0_to_25_mm() {
    let mut dev = LocalDevice::new();
    expect(
        &mut dev,
        "CFG RN=0",
        "OK HX=0.0050 HZ=0.0100 DIAM=1 RN=0.0000 TIP=3 TOL=0.0100 PASS=FIN",
    );
    refused(&mut dev, "CFG RN=-0.000001", "VALUE RN");
    expect(
        &mut dev,
        "CFG RN=25",
        "OK HX=0.0050 HZ=0.0100 DIAM=1 RN=25.0000 TIP=3 TOL=0.0100 PASS=FIN",
    );
    refused(&mut dev, "CFG RN=25.000001", "VALUE RN");
    refused(&mut dev, "CFG RN=-25", "VALUE RN");
    refused(&mut dev, "CFG TIP=2 RN=25.000001", "VALUE RN");
    expect(
        &mut dev,
        "CFG RN=24.999999",
        "OK HX=0.0050 HZ=0.0100 DIAM=1 RN=25.0000 TIP=3 TOL=0.0100 PASS=FIN",
    );
}

// ---------------------------------------------------------------------------
// Chord tolerance TOL: over 0, at most 1 mm → ERR VALUE TOL
// ---------------------------------------------------------------------------

#[test]
fn chord_tolerance_over_0_at_most_1_mm() {
    // A quarter circle of radius `r` from the origin, centre on −Z.
    let quarter = |r: &str| format!("ARC X={r} Z=-{r} I=0 K=-{r} DIR=CCW");
    let quarter_check = |dev: &mut LocalDevice, line: &str, sigma: f64, r: &str| {
        let rf: f64 = r.parse().unwrap();
        let dphi = fin_dphi(sigma, rf);
        let n = 324_000u64.div_ceil(dphi) as usize;
        let reply = send(dev, line);
        let (x, z) = (nm(r), -nm(r));
        check_chord_arc(
            &reply,
            n,
            dphi,
            (0, 0),
            (q(x, 5000) as i64, q(z, 10_000) as i64),
        );
    };

    let mut dev = LocalDevice::new();
    one(&mut dev, "CFG DIAM=0");
    // The smallest: configured, then used by an arc that names none.
    expect(
        &mut dev,
        "CFG TOL=0.000001",
        "OK HX=0.0050 HZ=0.0100 DIAM=0 RN=0.4000 TIP=3 TOL=0.0000 PASS=FIN",
    );
    quarter_check(&mut dev, &quarter("1"), 0.000001, "1");
    one(&mut dev, "ZERO");
    // The largest.
    expect(
        &mut dev,
        "CFG TOL=1",
        "OK HX=0.0050 HZ=0.0100 DIAM=0 RN=0.4000 TIP=3 TOL=1.0000 PASS=FIN",
    );
    quarter_check(&mut dev, &quarter("3"), 1.0, "3");
    one(&mut dev, "ZERO");
    // Named by the arc itself.
    quarter_check(
        &mut dev,
        &format!("{} TOL=0.000001", quarter("2")),
        0.000001,
        "2",
    );
    one(&mut dev, "ZERO");
    quarter_check(&mut dev, &format!("{} TOL=1", quarter("3")), 1.0, "3");

    for v in ["0", "-0.000001", "1.000001", "0.0000001", "-1"] {
        refused(&mut dev, &format!("CFG TOL={v}"), "VALUE TOL");
        refused(&mut dev, &format!("{} TOL={v}", quarter("1")), "VALUE TOL");
    }
}

// ---------------------------------------------------------------------------
// Tip code TIP: one digit 0 … 9 → ERR VALUE TIP
// ---------------------------------------------------------------------------

#[test]
fn tip_code_one_digit_0_to_9() {
    let mut dev = LocalDevice::new();
    expect(
        &mut dev,
        "CFG TIP=0",
        "OK HX=0.0050 HZ=0.0100 DIAM=1 RN=0.4000 TIP=0 TOL=0.0100 PASS=FIN",
    );
    refused(&mut dev, "CFG TIP=-1", "VALUE TIP");
    expect(
        &mut dev,
        "CFG TIP=9",
        "OK HX=0.0050 HZ=0.0100 DIAM=1 RN=0.4000 TIP=9 TOL=0.0100 PASS=FIN",
    );
    refused(&mut dev, "CFG TIP=10", "VALUE TIP");
    refused(&mut dev, "CFG TIP=09", "VALUE TIP");
    refused(&mut dev, "CFG RN=1 TIP=10", "VALUE TIP");
}

// ---------------------------------------------------------------------------
// DRIVE: RATE 1 … 200 000; PULSE 1 … 1000 with PULSE·RATE < 10⁶; SETUP 0 … 1000
// ---------------------------------------------------------------------------

#[test]
fn step_rate_from_1_to_200000() {
    let mut dev = LocalDevice::new();
    expect(&mut dev, "DRIVE", "OK RATE=50000 PULSE=5 SETUP=5");
    // The rapid rates need 1500/60/0.005 = 5000 events/s on X: no less.
    refused(&mut dev, "DRIVE RATE=4999", "VALUE RATE");
    expect(&mut dev, "DRIVE RATE=5000", "OK RATE=5000 PULSE=5 SETUP=5");
    refused(&mut dev, "LIMITS VX=1500.000001", "VALUE VX");
    // Slow rapids allow the slowest drives.
    assert!(one(&mut dev, "LIMITS VX=0.01 VZ=0.01").starts_with("OK "));
    expect(&mut dev, "DRIVE RATE=1", "OK RATE=1 PULSE=5 SETUP=5");
    refused(&mut dev, "DRIVE RATE=0", "VALUE RATE");
    expect(
        &mut dev,
        "DRIVE RATE=200000 PULSE=4",
        "OK RATE=200000 PULSE=4 SETUP=5",
    );
    refused(&mut dev, "DRIVE RATE=200001", "VALUE RATE");
    refused(&mut dev, "DRIVE RATE=200001 PULSE=1", "VALUE RATE");
    refused(&mut dev, "DRIVE RATE=0 PULSE=1", "VALUE RATE");
}

#[test]
fn pulse_width_from_1_to_1000_shorter_than_a_step_period() {
    let mut dev = LocalDevice::new();
    assert!(one(&mut dev, "LIMITS VX=0.01 VZ=0.01").starts_with("OK "));
    expect(&mut dev, "DRIVE PULSE=1", "OK RATE=50000 PULSE=1 SETUP=5");
    refused(&mut dev, "DRIVE PULSE=0", "VALUE PULSE");
    expect(
        &mut dev,
        "DRIVE RATE=999 PULSE=1000",
        "OK RATE=999 PULSE=1000 SETUP=5",
    );
    refused(&mut dev, "DRIVE PULSE=1001", "VALUE PULSE");
    refused(&mut dev, "DRIVE RATE=1 PULSE=1001", "VALUE PULSE");
    // PULSE·RATE: 999 999 accepted, 10⁶ and over refused.
    expect(
        &mut dev,
        "DRIVE RATE=111111 PULSE=9",
        "OK RATE=111111 PULSE=9 SETUP=5",
    );
    refused(&mut dev, "DRIVE RATE=111112", "VALUE PULSE");
    refused(&mut dev, "DRIVE PULSE=10", "VALUE PULSE");
    expect(
        &mut dev,
        "DRIVE RATE=99999 PULSE=10",
        "OK RATE=99999 PULSE=10 SETUP=5",
    );
    refused(&mut dev, "DRIVE RATE=100000", "VALUE PULSE");
    refused(&mut dev, "DRIVE RATE=1000 PULSE=1000", "VALUE PULSE");
    refused(&mut dev, "DRIVE RATE=200000 PULSE=5", "VALUE PULSE");
}

#[test]
fn dir_setup_from_0_to_1000() {
    let mut dev = LocalDevice::new();
    expect(&mut dev, "DRIVE SETUP=0", "OK RATE=50000 PULSE=5 SETUP=0");
    refused(&mut dev, "DRIVE SETUP=-1", "VALUE SETUP");
    expect(
        &mut dev,
        "DRIVE SETUP=1000",
        "OK RATE=50000 PULSE=5 SETUP=1000",
    );
    refused(&mut dev, "DRIVE SETUP=1001", "VALUE SETUP");
    refused(&mut dev, "DRIVE RATE=20000 SETUP=1001", "VALUE SETUP");
}

// ---------------------------------------------------------------------------
// Chords of one arc: 10 000 → ERR RANGE
// ---------------------------------------------------------------------------

#[test]
fn arc_of_10000_chords_runs_and_of_10001_is_refused() {
    // TOL 0.000001 mm: find a whole-mm radius whose Δφ (FIN) lets 10 000
    // chords sweep less than a full turn, clear of a whole arc-second.
    let sigma = 0.000001;
    let (r, dphi) = (5..200)
        .map(|r| (r, dphi_arcsec(sigma, f64::from(r))))
        .find(|&(_, d)| d < 129.0 && d > 50.0 && d.fract() > 0.05 && d.fract() < 0.95)
        .expect("a radius with 10 000 chords under a full turn");
    let dphi = dphi.floor() as u64;
    let rf = f64::from(r);

    for (chords, accepted) in [(10_000u64, true), (10_001, false)] {
        // The sweep half a Δφ short of `chords` whole angles: n = chords.
        let sweep = (chords as f64 - 0.5) * dphi as f64;
        assert!(sweep < 1_296_000.0);
        let (x, z) = on_circle(0.0, -rf, rf, sweep);
        let line = format!("ARC X={x} Z={z} I=0 K=-{r} DIR=CCW TOL=0.000001");
        let mut dev = device("0.005", "0.01");
        if accepted {
            let reply = send(&mut dev, &line);
            let end = (q(nm(&x), 5000) as i64, q(nm(&z), 10_000) as i64);
            check_chord_arc(&reply, chords as usize, dphi, (0, 0), end);
            let pos = one(&mut dev, "POS");
            assert_eq!((int(&pos, "PX"), int(&pos, "PZ")), end);
        } else {
            refused(&mut dev, &line, "RANGE");
        }
    }
}

// ---------------------------------------------------------------------------
// Chord angle Δφ: at least 1″ → ERR RANGE
// ---------------------------------------------------------------------------

#[test]
fn chord_angle_of_one_arc_second() {
    // Radius 99 999.999999 mm on Z, TOL 0.000001: Δφ floors to 1″.
    let sigma = 0.000001;
    let r = 99_999.999_999;
    assert_eq!(fin_dphi(sigma, r), 1);
    let (x, z) = on_circle(0.0, -r, r, 50.5);
    let mut dev = device("0.005", "0.01");
    let reply = send(
        &mut dev,
        &format!("ARC X={x} Z={z} I=0 K=-99999.999999 DIR=CCW TOL=0.000001"),
    );
    let end = (q(nm(&x), 5000) as i64, q(nm(&z), 10_000) as i64);
    check_chord_arc(&reply, 51, 1, (0, 0), end);

    // The largest radius a request can give (I and K just under 100 000 mm
    // each) with the smallest tolerance: Δφ ≈ 1.55″, still 1″ after the floor.
    // No request reaches a Δφ below 1″.
    let rmax = 99_999.999_999 * 2f64.sqrt();
    assert!(dphi_arcsec(sigma, rmax) > 1.5);
    assert_eq!(fin_dphi(sigma, rmax), 1);
    let c = -99_999.999_999;
    let (x, z) = on_circle(c, c, rmax, 45.0 * 3600.0 + 10.5);
    let mut dev = device("0.005", "0.01");
    let reply = send(
        &mut dev,
        &format!("ARC X={x} Z={z} I=-99999.999999 K=-99999.999999 DIR=CCW TOL=0.000001"),
    );
    let end = (q(nm(&x), 5000) as i64, q(nm(&z), 10_000) as i64);
    check_chord_arc(&reply, 11, 1, (0, 0), end);
    // Roughing rounds the same angle up, to 2″.
    let mut dev = device("0.005", "0.01");
    let reply = send(
        &mut dev,
        &format!("ARC X={x} Z={z} I=-99999.999999 K=-99999.999999 DIR=CCW TOL=0.000001 PASS=ROUGH"),
    );
    check_chord_arc(&reply, 6, 2, (0, 0), end);
}

// ---------------------------------------------------------------------------
// Arc radius mismatch: 0.002 mm → ERR GEOMETRY
// ---------------------------------------------------------------------------

#[test]
fn arc_radius_mismatch_of_0_002_mm() {
    // Start radius 10 mm (centre 10 mm down Z from the origin); end on +X from
    // the centre at 10 ± 0.002 mm: accepted; ± 0.002001 mm: refused.
    let sigma = 0.01;
    let dphi = fin_dphi(sigma, 10.0);
    let n = 324_000u64.div_ceil(dphi) as usize;
    for (end_x, ok) in [
        ("10.002", true),
        ("9.998", true),
        ("10.002001", false),
        ("9.997999", false),
    ] {
        for direct in [false, true] {
            let mode = if direct { " MODE=DIRECT" } else { "" };
            let line = format!("ARC X={end_x} Z=-10 I=0 K=-10 DIR=CCW{mode}");
            let mut dev = device("0.005", "0.01");
            if !ok {
                refused(&mut dev, &line, "GEOMETRY");
                continue;
            }
            let px = q(nm(end_x), 5000) as i64;
            let reply = send(&mut dev, &line);
            if direct {
                // (a, b) = (0, 1000) about the centre, R = 10 mm = 10⁸ Å.
                let (ev, seq) =
                    direct_events(0, 1000, px, -1000, 50_000, 100_000, 100_000_000i128.pow(2));
                assert_eq!(
                    reply,
                    [
                        format!("DATA G03 X+{px} Z-1000 J0 K1000"),
                        format!("OK N={ev} NX={px} NZ=-1000 PX={px} PZ=-1000 SEQ={seq}"),
                    ]
                );
            } else {
                check_chord_arc(&reply, n, dphi, (0, 0), (px, -1000));
            }
            let x4 = format!("{:.4}", end_x.parse::<f64>().unwrap());
            expect(
                &mut dev,
                "POS",
                &format!("OK PX={px} PZ=-1000 X={x4} Z=-10.0000"),
            );
        }
    }
}

// ---------------------------------------------------------------------------
// Words per request: as many as fit in 120 bytes
// ---------------------------------------------------------------------------

#[test]
fn words_per_request_as_many_as_fit_in_120_bytes() {
    // Every key of CFG, separated by runs of spaces and tabs, 120 bytes.
    let words = [
        "CFG",
        "HX=0.002",
        "HZ=0.004",
        "DIAM=0",
        "RN=0.8",
        "TIP=2",
        "TOL=0.02",
        "PASS=ROUGH",
    ];
    let bare: usize = words.iter().map(|w| w.len()).sum();
    let gaps = words.len() - 1;
    let fill = 120 - bare;
    let mut line = String::new();
    for (i, w) in words.iter().enumerate() {
        line.push_str(w);
        if i < gaps {
            let n = fill / gaps + usize::from(i < fill % gaps);
            line.push_str(&" \t".repeat(n).chars().take(n).collect::<String>());
        }
    }
    assert_eq!(line.len(), 120);
    let mut dev = LocalDevice::new();
    expect(
        &mut dev,
        &line,
        "OK HX=0.0020 HZ=0.0040 DIAM=0 RN=0.8000 TIP=2 TOL=0.0200 PASS=ROUGH",
    );

    // One byte more: the whole line is refused, nothing of it applied.
    let mut dev = LocalDevice::new();
    let before = state(&mut dev);
    let r = feed(&mut dev, format!("{line}\t\n").as_bytes());
    assert_eq!(r.len(), 1, "{r:?}");
    assert!(r[0].starts_with("ERR LINE_TOO_LONG"), "{r:?}");
    assert_eq!(state(&mut dev), before);
}

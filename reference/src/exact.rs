//! Exact model of the impulse rules and of the `MOVE`, `CFG`, `ZERO` and
//! `POS` replies: rationals and integers only, no floating point.
//!
//! Written from `docs/impulses.md` §2–§3, `docs/units.md` §3 and the
//! commands of `docs/protocol.md` §4 alone:
//!
//! - every length is an exact rational ([`Ratio`], an `i128` fraction kept in
//!   lowest terms); a request word with up to 6 decimals is `n / 10^6`, and an
//!   X diameter word is halved exactly to give the radius;
//! - the machine ([`ExactMachine`]) keeps the exact commanded coordinates
//!   `(X radius, Z)` since the last `ZERO`, the impulse prices `HX`, `HZ` and
//!   the `DIAM` mode;
//! - an axis register is `Q(P / h)`, `P` the exact commanded coordinate, `Q`
//!   rounding half away from zero in integer arithmetic ([`q_div`]), so a
//!   block issues `Q(P_k/h) − Q(P_{k−1}/h)` impulses (the residual carry);
//! - the step events of a block follow `docs/impulses.md` §3.1 straight from
//!   the definition ([`StepEvents`]): the leading axis is the one with the
//!   larger `|Δ|` (X when equal), event `i = 1 … |Δlead|` steps it once and
//!   puts the other axis at `b0 + Q(i·Δb/|Δlead|)`; one byte per event (bit0 X
//!   steps, bit1 Z steps, bit2 X negative, bit3 Z negative) and `SEQ` is the
//!   CRC-32 ([`Crc32`]: IEEE, reflected polynomial 0xEDB88320, as in zlib) of
//!   those bytes;
//! - `CFG HX=/HZ=` keeps the commanded coordinates and re-expresses each
//!   register as `Q(P / h_new)` without motion; `DIAM` only changes how later
//!   X words are read and how `POS` prints X; `ZERO` sets coordinates and
//!   registers to 0; a block of more than [`BLOCK_MAX`] impulses on an axis,
//!   or a register beyond [`REGISTER_MAX`], is `ERR RANGE`, and an error
//!   changes no state;
//! - `POS` prints the registers and the exact coordinates (X as a diameter
//!   when `DIAM=1`) with 4 decimals rounded half away from zero
//!   ([`fmt_mm4`]).
//!
//! Nothing here is shared with the controller's core: the crate does not
//! depend on it.

use crate::protocol::{BLOCK_MAX, REGISTER_MAX};
use std::ops::{Add, Div, Mul, Sub};

/// Denominator of a request length (6 decimals).
pub const MICRO: i128 = 1_000_000;

// ---------------------------------------------------------------------------
// Integers
// ---------------------------------------------------------------------------

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

/// `Q(n / d)`: `n / d` rounded to the nearest integer, exact halves away
/// from zero (`docs/impulses.md` §2.2).
///
/// # Panics
/// If `d` is 0.
pub fn q_div(n: i128, d: i128) -> i128 {
    assert!(d != 0, "division by zero in the model");
    let (n, d) = if d < 0 { (-n, -d) } else { (n, d) };
    let q = (2 * n.abs() + d) / (2 * d);
    if n < 0 {
        -q
    } else {
        q
    }
}

/// Whether `n / d` is exactly an integer plus one half.
pub fn is_half(n: i128, d: i128) -> bool {
    let d = d.abs();
    (2 * n) % d == 0 && ((2 * n) / d) % 2 != 0
}

// ---------------------------------------------------------------------------
// Rationals
// ---------------------------------------------------------------------------

/// An exact rational in lowest terms, denominator positive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ratio {
    /// Numerator.
    pub n: i128,
    /// Denominator, positive.
    pub d: i128,
}

impl Ratio {
    /// `n / d` in lowest terms.
    ///
    /// # Panics
    /// If `d` is 0.
    pub fn new(n: i128, d: i128) -> Self {
        assert!(d != 0, "zero denominator in the model");
        let (n, d) = if d < 0 { (-n, -d) } else { (n, d) };
        let g = gcd(n, d).max(1);
        Ratio { n: n / g, d: d / g }
    }
    /// A whole number.
    pub fn int(n: i128) -> Self {
        Ratio { n, d: 1 }
    }
    /// A request length given in millionths of a mm (`n / 10^6` mm).
    pub fn micro(n: i128) -> Self {
        Ratio::new(n, MICRO)
    }
    /// `self / 2`, exactly.
    pub fn half(self) -> Ratio {
        Ratio::new(self.n, self.d * 2)
    }
    /// `2 · self`.
    pub fn double(self) -> Ratio {
        Ratio::new(self.n * 2, self.d)
    }
    /// `Q(self)`: the nearest integer, halves away from zero.
    pub fn round(self) -> i128 {
        q_div(self.n, self.d)
    }
    /// Whether `self` is exactly an integer plus one half.
    pub fn is_half(self) -> bool {
        is_half(self.n, self.d)
    }
    /// Truncated towards zero to a whole number of millionths of a mm.
    pub fn to_micro_trunc(self) -> i128 {
        (self.n * MICRO) / self.d
    }
}

impl Add for Ratio {
    type Output = Ratio;
    fn add(self, o: Ratio) -> Ratio {
        Ratio::new(self.n * o.d + o.n * self.d, self.d * o.d)
    }
}

impl Sub for Ratio {
    type Output = Ratio;
    fn sub(self, o: Ratio) -> Ratio {
        Ratio::new(self.n * o.d - o.n * self.d, self.d * o.d)
    }
}

impl Mul for Ratio {
    type Output = Ratio;
    fn mul(self, o: Ratio) -> Ratio {
        Ratio::new(self.n * o.n, self.d * o.d)
    }
}

impl Div for Ratio {
    type Output = Ratio;
    /// # Panics
    /// If `o` is 0.
    fn div(self, o: Ratio) -> Ratio {
        Ratio::new(self.n * o.d, self.d * o.n)
    }
}

// ---------------------------------------------------------------------------
// Replies: lengths, checksums, CRC
// ---------------------------------------------------------------------------

/// A whole number of 0.0001 mm as a reply prints it: `[-]int.dddd`, no sign
/// on zero.
pub fn fmt_tenth_um(t: i128) -> String {
    let sign = if t < 0 { "-" } else { "" };
    let a = t.abs();
    format!("{sign}{}.{:04}", a / 10_000, a % 10_000)
}

/// A length as the pendant prints it (`docs/units.md` §3.2): mm, exactly 4
/// decimals, rounded half away from zero, no sign on a zero.
pub fn fmt_mm4(r: Ratio) -> String {
    fmt_tenth_um((r * Ratio::int(10_000)).round())
}

/// The line checksum `HH` of `*HH`: the XOR of all bytes.
pub fn xor_checksum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |a, b| a ^ b)
}

/// CRC-32 of every byte value, polynomial 0xEDB88320 (reflected), bit by bit.
const CRC_TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// CRC-32 (IEEE, reflected, as in zlib): `SEQ`, `TSEQ` and the CRC word of
/// a reliable request.
#[derive(Clone, Copy, Debug)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Crc32(0xFFFF_FFFF)
    }
}

impl Crc32 {
    /// A CRC over no bytes yet.
    pub fn new() -> Self {
        Crc32::default()
    }
    /// Adds one byte.
    pub fn push(&mut self, byte: u8) {
        // Table-driven: a fuzz oracle runs this for every step event, so it
        // avoids loops and compares that coverage instrumentation would trace.
        self.0 = CRC_TABLE[usize::from((self.0 as u8) ^ byte)] ^ (self.0 >> 8);
    }
    /// Adds bytes.
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.push(b);
        }
    }
    /// The finished CRC.
    pub fn finish(self) -> u32 {
        !self.0
    }
}

/// The CRC-32 of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(bytes);
    c.finish()
}

// ---------------------------------------------------------------------------
// Step events
// ---------------------------------------------------------------------------

/// The step events of a block issuing `dx`, `dz` impulses
/// (`docs/impulses.md` §3), one at a time and without allocation. Event `i`
/// steps the lead axis and the other axis exactly when `Q(i·D/L)` grew
/// (`D = |Δother| ≤ L = |Δlead|`), which it does by 0 or 1. The arithmetic
/// is exact in `u64` (`2·i·D + L < 2⁶⁴` for `L ≤ 2³¹`) and has no
/// data-dependent branch, so a fuzz oracle may run it for every event.
#[derive(Clone, Debug)]
pub struct StepEvents {
    lead: u8,
    other: u8,
    l: u64,
    d2: u64,
    two_l: u64,
    i: u64,
    prev: u64,
}

impl StepEvents {
    /// The events of a block moving `dx`, `dz` impulses.
    ///
    /// # Panics
    /// If an axis moves more than 2³¹ impulses.
    pub fn new(dx: i64, dz: i64) -> Self {
        assert!(
            dx.unsigned_abs() <= 1 << 31 && dz.unsigned_abs() <= 1 << 31,
            "block of {dx}, {dz} impulses"
        );
        // The byte of an axis step: bit0/bit1 step X/Z, bit2/bit3 their
        // negative direction.
        let bits = |x: bool, negative: bool| match (x, negative) {
            (true, false) => 0b0001u8,
            (true, true) => 0b0101,
            (false, false) => 0b0010,
            (false, true) => 0b1010,
        };
        let x_leads = dx.unsigned_abs() >= dz.unsigned_abs();
        let (lead, other) = if x_leads { (dx, dz) } else { (dz, dx) };
        let l = lead.unsigned_abs();
        StepEvents {
            lead: bits(x_leads, lead < 0),
            other: bits(!x_leads, other < 0),
            l,
            d2: 2 * other.unsigned_abs(),
            two_l: 2 * l.max(1),
            i: 0,
            prev: 0,
        }
    }

    /// The number of events, `|Δlead|`.
    pub fn total(&self) -> u64 {
        self.l
    }

    /// The next event's byte and whether its `i·Δb/|Δlead|` was exactly a
    /// half (a tie decided away from zero).
    pub fn next_with_tie(&mut self) -> Option<(u8, bool)> {
        if self.i == self.l {
            return None;
        }
        self.i += 1;
        let num = self.i * self.d2 + self.l;
        let now = num / self.two_l;
        let byte = self.lead | self.other.wrapping_mul(now.wrapping_sub(self.prev) as u8);
        self.prev = now;
        Some((byte, num.is_multiple_of(self.two_l)))
    }
}

impl Iterator for StepEvents {
    type Item = u8;

    fn next(&mut self) -> Option<u8> {
        self.next_with_tie().map(|(b, _)| b)
    }
}

/// The step event bytes of a block issuing `dx`, `dz` impulses; adds to
/// `ties` the events whose other-axis value was exactly at a tie.
pub fn step_sequence(dx: i64, dz: i64, ties: &mut u64) -> Vec<u8> {
    let mut events = StepEvents::new(dx, dz);
    let mut out = Vec::with_capacity(events.total() as usize);
    while let Some((byte, tie)) = events.next_with_tie() {
        *ties += u64::from(tie);
        out.push(byte);
    }
    out
}

// ---------------------------------------------------------------------------
// The machine
// ---------------------------------------------------------------------------

/// A block the machine ran.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactBlock {
    /// Impulses of the block, X (radius) and Z.
    pub nx: i128,
    /// Z impulses.
    pub nz: i128,
    /// Registers after it.
    pub px: i128,
    /// Z register after it.
    pub pz: i128,
    /// The step event bytes.
    pub events: Vec<u8>,
    /// Axis words whose end point was exactly half-way between impulses.
    pub endpoint_ties: u64,
    /// Events whose other-axis value was exactly at a tie.
    pub step_ties: u64,
}

impl ExactBlock {
    /// The `OK` line of a `MOVE` (without `*HH`).
    pub fn reply(&self) -> String {
        format!(
            "OK NX={} NZ={} PX={} PZ={} SEQ={:08X}",
            self.nx,
            self.nz,
            self.px,
            self.pz,
            crc32(&self.events)
        )
    }
}

/// A change of configuration the machine made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExactCfg {
    /// A price changed.
    pub price_changed: bool,
    /// `DIAM` changed.
    pub diam_changed: bool,
    /// Registers re-expressed by a new price exactly at a tie.
    pub ties: u64,
}

/// A request refused with `ERR RANGE`; nothing changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Range;

/// The session of `MOVE`, `CFG`, `ZERO` and `POS`, exactly.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExactMachine {
    /// X's price, on the radius, mm.
    pub hx: Ratio,
    /// Z's price, mm.
    pub hz: Ratio,
    /// X words are diameters.
    pub diam: bool,
    /// Exact commanded X, on the radius.
    pub cx: Ratio,
    /// Exact commanded Z.
    pub cz: Ratio,
    /// X register.
    pub px: i128,
    /// Z register.
    pub pz: i128,
}

impl Default for ExactMachine {
    fn default() -> Self {
        ExactMachine::new()
    }
}

impl ExactMachine {
    /// Power-on: HX 0.005, HZ 0.01, DIAM=1, at program zero.
    pub fn new() -> Self {
        ExactMachine {
            hx: Ratio::micro(5_000),
            hz: Ratio::micro(10_000),
            diam: true,
            cx: Ratio::int(0),
            cz: Ratio::int(0),
            px: 0,
            pz: 0,
        }
    }

    /// `MOVE X= Z= [INC=1]`, words as exact mm (`None`: the word is
    /// omitted; X a diameter when `DIAM=1`).
    pub fn mov(
        &mut self,
        x: Option<Ratio>,
        z: Option<Ratio>,
        inc: bool,
    ) -> Result<ExactBlock, Range> {
        let tx = match x {
            None => self.cx,
            Some(w) => {
                let r = if self.diam { w.half() } else { w };
                if inc {
                    self.cx + r
                } else {
                    r
                }
            }
        };
        let tz = match z {
            None => self.cz,
            Some(w) => {
                if inc {
                    self.cz + w
                } else {
                    w
                }
            }
        };
        let qx = tx / self.hx;
        let qz = tz / self.hz;
        let (px, pz) = (qx.round(), qz.round());
        let (nx, nz) = (px - self.px, pz - self.pz);
        let (block, register) = (i128::from(BLOCK_MAX), i128::from(REGISTER_MAX));
        if nx.abs() > block || nz.abs() > block || px.abs() > register || pz.abs() > register {
            return Err(Range);
        }
        let endpoint_ties =
            u64::from(x.is_some() && qx.is_half()) + u64::from(z.is_some() && qz.is_half());
        let mut step_ties = 0;
        // Within BLOCK_MAX, so within i64.
        let events = step_sequence(nx as i64, nz as i64, &mut step_ties);
        self.cx = tx;
        self.cz = tz;
        self.px = px;
        self.pz = pz;
        Ok(ExactBlock {
            nx,
            nz,
            px,
            pz,
            events,
            endpoint_ties,
            step_ties,
        })
    }

    /// `CFG [HX=] [HZ=] [DIAM=]`.
    pub fn cfg(
        &mut self,
        hx: Option<Ratio>,
        hz: Option<Ratio>,
        diam: Option<bool>,
    ) -> Result<ExactCfg, Range> {
        let hx = hx.unwrap_or(self.hx);
        let hz = hz.unwrap_or(self.hz);
        let diam = diam.unwrap_or(self.diam);
        let qx = self.cx / hx;
        let qz = self.cz / hz;
        let (px, pz) = (qx.round(), qz.round());
        let register = i128::from(REGISTER_MAX);
        if px.abs() > register || pz.abs() > register {
            return Err(Range);
        }
        let change = ExactCfg {
            price_changed: hx != self.hx || hz != self.hz,
            diam_changed: diam != self.diam,
            ties: u64::from(hx != self.hx && qx.is_half())
                + u64::from(hz != self.hz && qz.is_half()),
        };
        self.hx = hx;
        self.hz = hz;
        self.diam = diam;
        self.px = px;
        self.pz = pz;
        Ok(change)
    }

    /// The `OK` line of a `CFG` (without `*HH`): the prices and `DIAM` of the
    /// model, the other keys at their power-on values.
    pub fn cfg_reply(&self) -> String {
        format!(
            "OK HX={} HZ={} DIAM={} RN=0.4000 TIP=3 TOL=0.0100 PASS=FIN",
            fmt_mm4(self.hx),
            fmt_mm4(self.hz),
            u8::from(self.diam)
        )
    }

    /// `ZERO`: coordinates and registers become 0.
    pub fn zero(&mut self) {
        self.cx = Ratio::int(0);
        self.cz = Ratio::int(0);
        self.px = 0;
        self.pz = 0;
    }

    /// The `OK` line of a `POS` (without `*HH`).
    pub fn pos_reply(&self) -> String {
        let x = if self.diam { self.cx.double() } else { self.cx };
        format!(
            "OK PX={} PZ={} X={} Z={}",
            self.px,
            self.pz,
            fmt_mm4(x),
            fmt_mm4(self.cz)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn q_and_halves() {
        assert_eq!(q_div(1, 2), 1);
        assert_eq!(q_div(-1, 2), -1);
        assert_eq!(q_div(3, 2), 2);
        assert_eq!(q_div(-3, 2), -2);
        assert_eq!(q_div(49, 100), 0);
        assert_eq!(q_div(-51, 100), -1);
        assert_eq!(q_div(5, -2), -3);
        assert!(is_half(3, 2) && is_half(-3, 2) && !is_half(1, 1) && !is_half(1, 3));
    }

    #[test]
    fn printed_lengths_crc_and_checksum() {
        assert_eq!(fmt_mm4(Ratio::new(-1, 20_000)), "-0.0001");
        assert_eq!(fmt_mm4(Ratio::new(-49, 1_000_000)), "0.0000");
        assert_eq!(fmt_mm4(Ratio::micro(12_345_678_900)), "12345.6789");
        assert_eq!(crc32(b""), 0);
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(xor_checksum(b"OK"), b'O' ^ b'K');
    }

    #[test]
    fn step_events_by_the_rule() {
        let mut t = 0;
        assert_eq!(step_sequence(4, 2, &mut t), [0x03, 0x01, 0x03, 0x01]);
        assert_eq!(step_sequence(-4, -2, &mut t), [0x0F, 0x05, 0x0F, 0x05]);
        assert_eq!(step_sequence(1, 4, &mut t), [0x02, 0x03, 0x02, 0x02]);
        assert_eq!(step_sequence(-1, -4, &mut t), [0x0A, 0x0F, 0x0A, 0x0A]);
        assert_eq!(step_sequence(3, -3, &mut t), [0x0B, 0x0B, 0x0B]);
        assert!(step_sequence(0, 0, &mut t).is_empty());
        assert_eq!(t, 6);
        // Against the definition, with a division per event.
        for (dx, dz) in [(7i64, 3i64), (-5, 9), (12, -12), (1000, 1), (0, -6), (9, 0)] {
            let (lead, other) = if dx.abs() >= dz.abs() {
                (dx, dz)
            } else {
                (dz, dx)
            };
            let l = i128::from(lead.abs());
            let mut prev = 0;
            for (i, byte) in StepEvents::new(dx, dz).enumerate() {
                let b = q_div((i as i128 + 1) * i128::from(other), l);
                let steps = b != prev;
                prev = b;
                let (xs, zs) = if dx.abs() >= dz.abs() {
                    (true, steps)
                } else {
                    (steps, true)
                };
                let want = u8::from(xs)
                    | u8::from(zs) << 1
                    | u8::from(xs && dx < 0) << 2
                    | u8::from(zs && dz < 0) << 3;
                assert_eq!(byte, want, "{dx},{dz} event {}", i + 1);
            }
            assert_eq!(prev, i128::from(other));
        }
    }

    #[test]
    fn the_machine_rounds_ties_away_and_refuses_range() {
        let mut m = ExactMachine::new();
        // X=0.005 on the diameter is a radius of 0.0025: half an impulse.
        let b = m.mov(Some(Ratio::micro(5_000)), None, false).unwrap();
        assert_eq!(
            b.reply(),
            format!("OK NX=1 NZ=0 PX=1 PZ=0 SEQ={:08X}", crc32(&[1]))
        );
        assert_eq!(b.endpoint_ties, 1);
        assert_eq!(m.pos_reply(), "OK PX=1 PZ=0 X=0.0050 Z=0.0000");
        assert_eq!(
            m.mov(None, Some(Ratio::micro(-10_000_010_000)), false),
            Err(Range)
        );
        assert_eq!(m.pos_reply(), "OK PX=1 PZ=0 X=0.0050 Z=0.0000");
        m.cfg(Some(Ratio::micro(10_000)), None, Some(false))
            .unwrap();
        assert_eq!(
            m.cfg_reply(),
            "OK HX=0.0100 HZ=0.0100 DIAM=0 RN=0.4000 TIP=3 TOL=0.0100 PASS=FIN"
        );
        m.zero();
        assert_eq!(m.pos_reply(), "OK PX=0 PZ=0 X=0.0000 Z=0.0000");
    }
}

//! Structured sessions: requests built from the real command words and keys
//! (`MOVE`, `ARC` by chords and `MODE=DIRECT`, `CFG`, `DRIVE`, `ZERO [X Z]`,
//! `SESSION`, `POS`, `VER`, G-code blocks G00–G03 / G40 / G90 G91 with
//! X Z I K R, words apart or written together) with arbitrary numbers,
//! optionally in lower case, with an `@id` (new or a retry), a CRC word and a
//! `*HH` checksum, run one after another on one device.
//!
//! Besides the per-request checks of `fuzz_oracle::Checker::request` (reply
//! form, one final line, integrity words and retries, an `ERR` changes
//! nothing, registers hold `Q(P/h)` of the exact commanded point, reported
//! motion, `SEQ` and step events agree), a model of the session predicts:
//! - `MOVE`, `CFG`, `DRIVE`, `ZERO`, `SESSION`, `POS`, `VER`, linear G-code
//!   blocks: the exact outcome (which `ERR` code, or the exact `OK` line);
//! - `ARC` and arc blocks: the refusals that come before any geometry (which
//!   code), and on `OK` the commanded point is the request's end point
//!   (absolute or incremental, X halved when `DIAM=1`);
//! - an id without a CRC word, an id out of range, a numbered request before
//!   `SESSION TOKEN=`, an over-long or empty line: the code; the same id as
//!   the last one: the same final line, nothing runs.
//!
//! The device's commanded point, prices and registers must equal the model's
//! after every request.
#![no_main]

use arbitrary::Arbitrary;
use core_nostd::protocol::{NAME, VERSION};
use fuzz_oracle::{
    mm4_of, parse_mm, q, reference_block, reference_is_block, with_checksum, Checker,
    LIMIT_ANGSTROM, MAX_BLOCK, MAX_LINE, MAX_POSITION,
};
use libfuzzer_sys::fuzz_target;

const MAXP: i128 = MAX_POSITION as i128;
const MAXB: i128 = MAX_BLOCK as i128;

/// Numbers the pendant and the tests use, edges of every range, and
/// malformed ones.
const INTERESTING: &[&str] = &[
    "0",
    "-0",
    "+0",
    "0.0025",
    "-0.0025",
    "0.002499",
    "0.0025001",
    "0.005",
    "-0.005",
    "0.01",
    "0.000001",
    "-0.000001",
    "0.0000005",
    "0.000005",
    "0.000006",
    "99999.999999",
    "-99999.999999",
    "99999.99",
    "100000",
    "-100000",
    "5000",
    "-5000",
    "4999.9975",
    "5000.005",
    "10000",
    "1",
    "2",
    "0.4",
    "25",
    "25.000001",
    "1.000001",
    "12.345678",
    "-7.000005",
    "27.532",
    "-10.234",
    "93.532",
    "-56",
    "7.2",
    "-2.4",
    "2.6",
    "4.4",
    "10.4",
    "-21.986134",
    "11.9",
    "35.5",
    "0007.5",
    "0000000000000000000000012",
    "1e3",
    ".5",
    "1.",
    "--1",
    "+",
    "",
    "abc",
    "1.2.3",
    "1.0000001",
    "-99993",
    "99999",
    "1999999.999999",
    "0x10",
];

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Sign {
    None,
    Plus,
    Minus,
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Num {
    Interesting(u8),
    Decimal {
        sign: Sign,
        int: u32,
        int_digits: u8,
        frac: u32,
        frac_digits: u8,
    },
    /// A small multiple of a typical price.
    Impulses {
        sign: Sign,
        n: u16,
        price: u8,
    },
}

impl Num {
    fn text(self) -> String {
        let sign = |s: Sign| match s {
            Sign::None => "",
            Sign::Plus => "+",
            Sign::Minus => "-",
        };
        match self {
            Num::Interesting(i) => INTERESTING[usize::from(i) % INTERESTING.len()].into(),
            Num::Decimal {
                sign: s,
                int,
                int_digits,
                frac,
                frac_digits,
            } => {
                let int = u64::from(int) % 10u64.pow(u32::from(int_digits % 8));
                let fd = u32::from(frac_digits % 8);
                let mut t = format!("{}{int}", sign(s));
                if fd > 0 {
                    let f = u64::from(frac) % 10u64.pow(fd);
                    t.push_str(&format!(".{f:0width$}", width = fd as usize));
                }
                t
            }
            Num::Impulses { sign: s, n, price } => {
                // Whole and half impulses of the usual prices (ties included).
                let nm = [2_500i64, 5_000, 1_250, 500, 1, 3, 7][usize::from(price) % 7];
                let t = fuzz_oracle::exact_mm(i64::from(n) * nm * 10);
                format!("{}{t}", sign(s))
            }
        }
    }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum ArcMode {
    Default,
    Chord,
    Direct,
}

#[derive(Arbitrary, Debug, Clone)]
enum Req {
    Move {
        x: Option<Num>,
        z: Option<Num>,
        inc: Option<bool>,
        z_first: bool,
    },
    Arc {
        x: Num,
        z: Num,
        i: Num,
        k: Num,
        ccw: bool,
        mode: ArcMode,
        tol: Option<Num>,
        rough: Option<bool>,
        feed: Option<Num>,
    },
    Cfg {
        hx: Option<Num>,
        hz: Option<Num>,
        diam: Option<bool>,
        rn: Option<Num>,
        tip: Option<u8>,
        tol: Option<Num>,
        rough: Option<bool>,
    },
    Drive {
        rate: Option<u32>,
        pulse: Option<u16>,
        setup: Option<u16>,
    },
    Zero {
        x: Option<Num>,
        z: Option<Num>,
    },
    Session {
        token: Option<u64>,
    },
    Pos,
    Ver,
    Block {
        n: Option<u16>,
        motion: Option<u8>,
        compensation: Option<u8>,
        incremental: Option<bool>,
        x: Option<Num>,
        z: Option<Num>,
        i: Option<Num>,
        k: Option<Num>,
        r: Option<Num>,
        f: Option<Num>,
        compact: bool,
    },
}

#[derive(Arbitrary, Debug, Clone)]
struct Request {
    req: Req,
    lower: bool,
    /// A leading `@id` word.
    id: Option<u32>,
    /// Reuse the previous request's id (a retry).
    retry: bool,
    /// A ` ~CCCCCCCC` CRC word.
    crc: bool,
    /// A `*HH` checksum.
    checksum: bool,
    crlf: bool,
}

/// What the model knows of the session.
#[derive(Clone, Debug)]
struct Model {
    hx: i64,
    hz: i64,
    diam: bool,
    rn: i64,
    tip: u8,
    tol: i64,
    rough: bool,
    rate: u32,
    pulse: u32,
    setup: u32,
    cmd: [i64; 2],
    motion: u8,
    incremental: bool,
    /// A feed has been programmed (modal `F`).
    feed: bool,
    token: u32,
    /// The last request id the device took, and its final line.
    last: Option<(u32, String)>,
}

impl Model {
    const POWER_ON: Model = Model {
        hx: 50_000,
        hz: 100_000,
        diam: true,
        rn: 4_000_000,
        tip: 3,
        tol: 100_000,
        rough: false,
        rate: 50_000,
        pulse: 5,
        setup: 5,
        cmd: [0, 0],
        motion: 0,
        incremental: false,
        feed: false,
        token: 0,
        last: None,
    };

    fn pos(&self, cmd: [i64; 2], hx: i64, hz: i64) -> [i128; 2] {
        [q(cmd[0].into(), hx.into()), q(cmd[1].into(), hz.into())]
    }

    fn cfg_line(&self) -> String {
        format!(
            "OK HX={} HZ={} DIAM={} RN={} TIP={} TOL={} PASS={}",
            mm4_of(self.hx.into()),
            mm4_of(self.hz.into()),
            u8::from(self.diam),
            mm4_of(self.rn.into()),
            self.tip,
            mm4_of(self.tol.into()),
            if self.rough { "ROUGH" } else { "FIN" }
        )
    }
}

/// What the model expects of a request.
#[derive(Debug)]
enum Expect {
    /// This `ERR` code, nothing changes.
    Err(&'static str),
    /// This exact final line (`SEQ` aside), then this model.
    Ok(String, Box<Model>),
    /// An `ERR` of any code, or an `OK` that leaves this model.
    Either(Box<Model>),
    /// Refused, code not predicted.
    AnyErr,
    /// The remembered final line of the same id, nothing runs.
    Replay(String),
}

fn within(a: i64) -> bool {
    a.abs() <= LIMIT_ANGSTROM
}

/// The words of a request and the model's expectation.
fn build(req: &Req, m: &Model) -> (Vec<String>, Expect) {
    match req {
        Req::Move { x, z, inc, z_first } => {
            let mut w = vec!["MOVE".to_string()];
            let mut args = Vec::new();
            if let Some(x) = x {
                args.push(format!("X={}", x.text()));
            }
            if let Some(z) = z {
                args.push(format!("Z={}", z.text()));
            }
            if *z_first {
                args.reverse();
            }
            if let Some(i) = inc {
                args.push(format!("INC={}", u8::from(*i)));
            }
            w.extend(args);
            let inc = inc.unwrap_or(false);
            (w, expect_move(m, x.map(Num::text), z.map(Num::text), inc))
        }
        Req::Arc {
            x,
            z,
            i,
            k,
            ccw,
            mode,
            tol,
            rough,
            feed,
        } => {
            let mut w = vec![
                "ARC".to_string(),
                format!("X={}", x.text()),
                format!("Z={}", z.text()),
                format!("I={}", i.text()),
                format!("K={}", k.text()),
                format!("DIR={}", if *ccw { "CCW" } else { "CW" }),
            ];
            if let Some(t) = tol {
                w.push(format!("TOL={}", t.text()));
            }
            if let Some(r) = rough {
                w.push(format!("PASS={}", if *r { "ROUGH" } else { "FIN" }));
            }
            match mode {
                ArcMode::Default => {}
                ArcMode::Chord => w.push("MODE=CHORD".into()),
                ArcMode::Direct => w.push("MODE=DIRECT".into()),
            }
            if let Some(f) = feed {
                w.push(format!("F={}", f.text()));
            }
            // The checks in the order the command makes them.
            let tol_ok = tol
                .is_none_or(|t| parse_mm(&t.text()).is_ok_and(|a| (1..=10_000_000).contains(&a)));
            // A feed of 0.001 … 99 999.999999 mm/min, in either mode.
            let feed_ok = feed.is_none_or(|f| {
                parse_mm(&f.text()).is_ok_and(|a| (10_000..=999_999_999_990).contains(&a))
            });
            let words_ok = [x, z, i, k].iter().all(|n| parse_mm(&n.text()).is_ok());
            let expect = if !tol_ok || !feed_ok || !words_ok {
                Expect::Err("VALUE")
            } else {
                let mut next = m.clone();
                let xv = parse_mm(&x.text()).unwrap();
                next.cmd = [
                    if m.diam { xv / 2 } else { xv },
                    parse_mm(&z.text()).unwrap(),
                ];
                Expect::Either(Box::new(next))
            };
            (w, expect)
        }
        Req::Cfg {
            hx,
            hz,
            diam,
            rn,
            tip,
            tol,
            rough,
        } => {
            let mut w = vec!["CFG".to_string()];
            let t = |n: &Option<Num>| n.map(Num::text);
            let (hx, hz, rn, tol) = (t(hx), t(hz), t(rn), t(tol));
            for (key, v) in [("HX", &hx), ("HZ", &hz)] {
                if let Some(v) = v {
                    w.push(format!("{key}={v}"));
                }
            }
            if let Some(d) = diam {
                w.push(format!("DIAM={}", u8::from(*d)));
            }
            if let Some(v) = &rn {
                w.push(format!("RN={v}"));
            }
            if let Some(v) = tip {
                w.push(format!("TIP={v}"));
            }
            if let Some(v) = &tol {
                w.push(format!("TOL={v}"));
            }
            if let Some(r) = rough {
                w.push(format!("PASS={}", if *r { "ROUGH" } else { "FIN" }));
            }
            // Shuffle deterministically: keys may come in any order.
            if w.len() > 2 && hx.as_deref().is_some_and(|s| s.len() % 2 == 1) {
                w[1..].reverse();
            }
            (w, expect_cfg(m, hx, hz, *diam, rn, *tip, tol, *rough))
        }
        Req::Drive { rate, pulse, setup } => {
            let mut w = vec!["DRIVE".to_string()];
            if let Some(v) = rate {
                w.push(format!("RATE={v}"));
            }
            if let Some(v) = pulse {
                w.push(format!("PULSE={v}"));
            }
            if let Some(v) = setup {
                w.push(format!("SETUP={v}"));
            }
            let count = |v: Option<u32>, d: u32| match v {
                None => Some(d),
                Some(v) if v.to_string().len() <= 7 => Some(v),
                Some(_) => None,
            };
            let r = count(*rate, m.rate);
            let p = count(pulse.map(u32::from), m.pulse);
            let s = count(setup.map(u32::from), m.setup);
            let expect = match (r, p, s) {
                (None, _, _) => Expect::Err("VALUE"),
                (_, None, _) => Expect::Err("VALUE"),
                (_, _, None) => Expect::Err("VALUE"),
                (Some(r), Some(p), Some(s)) => {
                    if r == 0
                        || r > 200_000
                        || p == 0
                        || p > 1000
                        || s > 1000
                        || u64::from(p) * u64::from(r) >= 1_000_000
                        || too_fast(m.hx, m.hz, r)
                    {
                        Expect::Err("VALUE")
                    } else {
                        let mut next = m.clone();
                        (next.rate, next.pulse, next.setup) = (r, p, s);
                        Expect::Ok(format!("OK RATE={r} PULSE={p} SETUP={s}"), Box::new(next))
                    }
                }
            };
            (w, expect)
        }
        Req::Zero { x, z } => {
            let mut w = vec!["ZERO".to_string()];
            let (x, z) = (x.map(Num::text), z.map(Num::text));
            if let Some(v) = &x {
                w.push(format!("X={v}"));
            }
            if let Some(v) = &z {
                w.push(format!("Z={v}"));
            }
            let parse = |v: &Option<String>| v.as_deref().map_or(Ok(0), parse_mm);
            let expect = match (parse(&x), parse(&z)) {
                (Err(_), _) | (_, Err(_)) => Expect::Err("VALUE"),
                (Ok(xv), Ok(zv)) => {
                    let mut next = m.clone();
                    next.cmd = [if m.diam { xv / 2 } else { xv }, zv];
                    let p = m.pos(next.cmd, m.hx, m.hz);
                    if p.iter().any(|p| p.abs() > MAXP) {
                        Expect::Err("RANGE")
                    } else {
                        Expect::Ok("OK".into(), Box::new(next))
                    }
                }
            };
            (w, expect)
        }
        Req::Session { token } => {
            let mut w = vec!["SESSION".to_string()];
            let mut next = m.clone();
            let expect = match token {
                None => Expect::Ok(format!("OK TOKEN={}", m.token), Box::new(next)),
                Some(t) => {
                    w.push(format!("TOKEN={t}"));
                    match u32::try_from(*t) {
                        Ok(t) => {
                            next.token = t;
                            Expect::Ok(format!("OK TOKEN={t}"), Box::new(next))
                        }
                        Err(_) => Expect::Err("VALUE"),
                    }
                }
            };
            (w, expect)
        }
        Req::Pos => {
            let p = m.pos(m.cmd, m.hx, m.hz);
            let line = format!(
                "OK PX={} PZ={} X={} Z={}",
                p[0],
                p[1],
                mm4_of(i128::from(m.cmd[0]) * if m.diam { 2 } else { 1 }),
                mm4_of(m.cmd[1].into())
            );
            (vec!["POS".into()], Expect::Ok(line, Box::new(m.clone())))
        }
        Req::Ver => (
            vec!["VER".into()],
            Expect::Ok(
                format!("OK PROTO=1 NAME={NAME} VERSION={VERSION}"),
                Box::new(m.clone()),
            ),
        ),
        Req::Block {
            n,
            motion,
            compensation,
            incremental,
            x,
            z,
            i,
            k,
            r,
            f,
            compact,
        } => {
            let mut w = Vec::new();
            if let Some(n) = n {
                w.push(format!("N{n}"));
            }
            let motion = motion.map(|g| g % 4);
            // G41/G42 contours are the `contour` target's: here only G40.
            let compensation = compensation.map(|_| 40);
            for g in [motion, compensation, incremental.map(|i| 90 + u8::from(i))]
                .into_iter()
                .flatten()
            {
                w.push(format!("G{g:02}"));
            }
            let t = |n: &Option<Num>| n.map(Num::text);
            let words = [
                ('X', t(x)),
                ('Z', t(z)),
                ('I', t(i)),
                ('K', t(k)),
                ('R', t(r)),
                ('F', t(f)),
            ];
            for (letter, v) in &words {
                if let Some(v) = v {
                    w.push(format!("{letter}{v}"));
                }
            }
            if *compact && !w.is_empty() {
                w = vec![w.concat()];
            }
            // The words as the block grammar reads the line (numbers next to
            // each other may read differently from how they were written:
            // `Z0x10` is Z0 X10).
            let text = w.join(" ");
            let read = reference_block(&text)
                .ok()
                .filter(|_| reference_is_block(&text));
            let expect = match read {
                None => Expect::AnyErr,
                Some(b) if b.compensation.is_some_and(|c| c != 40) => Expect::AnyErr,
                // A feed of 0.001 … 99 999.999999 mm/min, checked first.
                // F0 is taken (a header's); a feed move then needs one.
                Some(b)
                    if b.f
                        .is_some_and(|f| f != 0 && !(10_000..=999_999_999_990).contains(&f)) =>
                {
                    Expect::Err("VALUE")
                }
                Some(b) => {
                    let v = b.xzikr;
                    let mut next = m.clone();
                    next.motion = b.motion.unwrap_or(m.motion);
                    next.incremental = b.distance.map_or(m.incremental, |d| d == 91);
                    next.feed = b.f.map_or(m.feed, |f| f != 0);
                    let has_end = v[0].is_some() || v[1].is_some();
                    let arc_words = v[2].is_some() || v[3].is_some() || v[4].is_some();
                    let end = |word: Option<i64>, now: i64| {
                        word.map_or(now, |w| if next.incremental { now + w } else { w })
                    };
                    // A diameter halved once, half away from zero.
                    let xr = v[0].map(|x| if m.diam { (x + x.signum()) / 2 } else { x });
                    let target = [end(xr, m.cmd[0]), end(v[1], m.cmd[1])];
                    if !within(target[0]) || !within(target[1]) {
                        Expect::Err("RANGE")
                    } else if next.motion < 2 && arc_words {
                        Expect::Err("SYNTAX")
                    } else if next.motion == 1 && has_end && !next.feed {
                        // A feed move before any F.
                        Expect::Err("VALUE")
                    } else {
                        if has_end || arc_words {
                            next.cmd = target;
                        }
                        if next.motion < 2 {
                            // A linear block: the outcome is predicted like MOVE.
                            let p0 = m.pos(m.cmd, m.hx, m.hz);
                            let p1 = m.pos(next.cmd, m.hx, m.hz);
                            if p1.iter().any(|p| p.abs() > MAXP)
                                || (p1[0] - p0[0]).abs() > MAXB
                                || (p1[1] - p0[1]).abs() > MAXB
                            {
                                Expect::Err("RANGE")
                            } else {
                                let line = format!(
                                    "OK NX={} NZ={} PX={} PZ={}",
                                    p1[0] - p0[0],
                                    p1[1] - p0[1],
                                    p1[0],
                                    p1[1]
                                );
                                Expect::Ok(line, Box::new(next))
                            }
                        } else {
                            Expect::Either(Box::new(next))
                        }
                    }
                }
            };
            (w, expect)
        }
    }
}

fn expect_move(m: &Model, x: Option<String>, z: Option<String>, inc: bool) -> Expect {
    let mut target = m.cmd;
    if let Some(x) = x {
        let Ok(v) = parse_mm(&x) else {
            return Expect::Err("VALUE");
        };
        let r = if m.diam { v / 2 } else { v };
        target[0] = if inc { m.cmd[0] + r } else { r };
        if !within(target[0]) {
            return Expect::Err("RANGE");
        }
    }
    if let Some(z) = z {
        let Ok(v) = parse_mm(&z) else {
            return Expect::Err("VALUE");
        };
        target[1] = if inc { m.cmd[1] + v } else { v };
        if !within(target[1]) {
            return Expect::Err("RANGE");
        }
    }
    let p0 = m.pos(m.cmd, m.hx, m.hz);
    let p1 = m.pos(target, m.hx, m.hz);
    if p1.iter().any(|p| p.abs() > MAXP) {
        return Expect::Err("RANGE");
    }
    let (nx, nz) = (p1[0] - p0[0], p1[1] - p0[1]);
    if nx.abs() > MAXB || nz.abs() > MAXB {
        return Expect::Err("RANGE");
    }
    let mut next = m.clone();
    next.cmd = target;
    Expect::Ok(
        format!("OK NX={nx} NZ={nz} PX={} PZ={}", p1[0], p1[1]),
        Box::new(next),
    )
}

/// Whether a rapid rate at its default (X 1500, Z 3000 mm/min) asks more
/// step events per second than `rate` at prices `hx`, `hz` (Å).
fn too_fast(hx: i64, hz: i64, rate: u32) -> bool {
    const VMAX: [i64; 2] = [1500 * 10_000_000, 3000 * 10_000_000]; // Å/min
    [hx, hz]
        .iter()
        .zip(VMAX)
        .any(|(&h, v)| v > 60 * h * i64::from(rate))
}

#[allow(clippy::too_many_arguments)]
fn expect_cfg(
    m: &Model,
    hx: Option<String>,
    hz: Option<String>,
    diam: Option<bool>,
    rn: Option<String>,
    tip: Option<u8>,
    tol: Option<String>,
    rough: Option<bool>,
) -> Expect {
    let mut next = m.clone();
    let bounded = |v: &str, lo: i64, hi: i64| parse_mm(v).ok().filter(|a| (lo..=hi).contains(a));
    if let Some(v) = hx {
        match bounded(&v, 10, 10_000_000) {
            Some(a) => next.hx = a,
            None => return Expect::Err("VALUE"),
        }
    }
    if let Some(v) = hz {
        match bounded(&v, 10, 10_000_000) {
            Some(a) => next.hz = a,
            None => return Expect::Err("VALUE"),
        }
    }
    if let Some(d) = diam {
        next.diam = d;
    }
    if let Some(v) = rn {
        match bounded(&v, 0, 250_000_000) {
            Some(a) => next.rn = a,
            None => return Expect::Err("VALUE"),
        }
    }
    if let Some(t) = tip {
        if t > 9 {
            return Expect::Err("VALUE");
        }
        next.tip = t;
    }
    if let Some(v) = tol {
        match bounded(&v, 1, 10_000_000) {
            Some(a) => next.tol = a,
            None => return Expect::Err("VALUE"),
        }
    }
    if let Some(r) = rough {
        next.rough = r;
    }
    let p = next.pos(next.cmd, next.hx, next.hz);
    if p.iter().any(|p| p.abs() > MAXP) {
        return Expect::Err("RANGE");
    }
    if too_fast(next.hx, next.hz, next.rate) {
        return Expect::Err("VALUE");
    }
    let line = next.cfg_line();
    Expect::Ok(line, Box::new(next))
}

/// ` ~CCCCCCCC` appended: the CRC-32 of everything before the `~`.
fn with_crc(body: &str) -> String {
    let mut c = fuzz_oracle::Crc32::default();
    for b in body.bytes().chain(*b" ") {
        c.push(b);
    }
    format!("{body} ~{:08X}", c.finish())
}

fuzz_target!(|requests: Vec<Request>| {
    let mut checker = Checker::new(fuzz_oracle::fuzz_device());
    let mut model = Model::POWER_ON;
    let mut prev_id = None;
    for r in requests.iter().take(64) {
        let (words, expect) = build(&r.req, &model);
        // A `KEY=` word without a value is a syntax error before any value
        // is looked at.
        let expect = if !matches!(r.req, Req::Block { .. })
            && words.iter().skip(1).any(|w| w.ends_with('='))
        {
            Expect::Err("SYNTAX")
        } else {
            expect
        };
        let mut body = words.join(" ");
        if r.lower {
            body = body.to_ascii_lowercase();
        }
        let empty = body.trim().is_empty();
        let is_session = words.first().is_some_and(|w| w == "SESSION");
        let id = if r.retry { prev_id.or(r.id) } else { r.id };
        if let Some(id) = id {
            body = format!("@{id} {body}");
            prev_id = Some(id);
        }
        if r.crc {
            body = with_crc(&body);
        }
        if r.checksum {
            body = with_checksum(&body);
        }
        let remembered = model.last.clone();
        let expect = if body.len() > MAX_LINE {
            Expect::Err("LINE_TOO_LONG")
        } else if id == Some(0) {
            Expect::Err("VALUE")
        } else if id.is_some() && !r.crc {
            Expect::Err("SYNTAX")
        } else if let Some((_, line)) = remembered.as_ref().filter(|(n, _)| Some(*n) == id) {
            Expect::Replay(line.clone())
        } else if id.is_some() && model.token == 0 && !is_session {
            Expect::Err("SESSION")
        } else if empty {
            Expect::Err("EMPTY")
        } else {
            expect
        };
        let answer = checker.line(&body, r.crlf);
        if answer.skipped {
            // An arc too long to run here: sent blank, nothing changed.
            continue;
        }
        let last = answer.last().to_string();
        let without_seq = last.split(" SEQ=").next().unwrap_or("").to_string();
        let taken = id.is_some_and(|n| n > 0) && r.crc && body.len() <= MAX_LINE;
        let mut record = taken;
        match expect {
            Expect::Err(code) => {
                assert_eq!(answer.err(), Some(code), "{body:?} -> {last:?}");
                record &= code != "SESSION";
            }
            Expect::AnyErr => assert!(answer.err().is_some(), "{body:?} -> {last:?}"),
            Expect::Ok(line, next) => {
                assert_eq!(without_seq, line, "{body:?}");
                model = *next;
            }
            Expect::Either(next) => {
                if answer.err().is_none() {
                    model = *next;
                }
            }
            Expect::Replay(line) => {
                assert!(answer.replay, "{body:?} not answered from memory");
                assert_eq!(last, line, "{body:?}");
            }
        }
        if record {
            model.last = Some((id.unwrap(), last.clone()));
        }
        if matches!(r.req, Req::Block { .. }) && answer.err().is_none() && !answer.replay {
            // A block that moved reports where it went, in the modal motion,
            // X as a diameter when DIAM=1 (arcs add I and K).
            if let [data, _] = &answer.lines[..] {
                let factor = if model.diam { 2 } else { 1 };
                let want = format!(
                    "DATA G{:02} X{} Z{}",
                    model.motion,
                    mm4_of(i128::from(model.cmd[0]) * factor),
                    mm4_of(model.cmd[1].into())
                );
                assert!(
                    *data == want || data.starts_with(&format!("{want} I")),
                    "{body:?} -> {data:?}, expected {want:?}"
                );
            }
        }
        let s = checker.dev.session();
        let (x, z) = s.commanded();
        assert_eq!(
            [x.as_angstrom(), z.as_angstrom()],
            model.cmd,
            "commanded point after {body:?} -> {last:?}"
        );
        let c = s.config();
        assert_eq!(
            (c.hx.as_angstrom(), c.hz.as_angstrom(), c.diam),
            (model.hx, model.hz, model.diam),
            "configuration after {body:?}"
        );
        let p = s.position();
        let want = model.pos(model.cmd, model.hx, model.hz);
        assert_eq!(
            [i128::from(p.x.get()), i128::from(p.z.get())],
            want,
            "registers after {body:?}"
        );
        assert!(want.iter().all(|p| p.abs() <= MAXP));
    }
});

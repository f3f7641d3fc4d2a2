//! A program streamed to a device in real time, as a host that keeps its
//! queue filled streams it: each request as soon as the previous one is
//! answered. On a board the step interrupt runs the started blocks while
//! the requests arrive; the device answers a request once its motion is
//! queued, so the host waits only when the queue is full.
//!
//! [`paced_proof`] streams one program to the firmware in paced QEMU (its
//! step interrupt on TIM2 ticks of virtual time) and to the in-process
//! device, and compares every reply and the final `SYNC`; then it holds,
//! resumes and resets the firmware in the middle of a run and checks the
//! registers against the positions of the steps the program issues.

use crate::device::LocalDevice;
use crate::link::{Client, LinkError, Reply, Transport};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::{Duration, Instant};

/// A program of `n` motion requests after `ZERO`, ending with `SYNC`:
/// feed moves (`MOVE … F=`, 300–3000 mm/min), rapids (`MOVE` without `F`)
/// and arcs by chords (`ARC … F=`), each 0.1–1.5 mm long, wandering near
/// the origin.
pub fn program(seed: u64, n: usize) -> Vec<String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut lines = vec!["ZERO".to_string()];
    // The commanded point in µm: X on the radius, Z.
    let (mut x, mut z) = (0i64, 0i64);
    let mm = |um: i64| {
        let sign = if um < 0 { "-" } else { "" };
        format!("{sign}{}.{:03}", um.abs() / 1000, um.abs() % 1000)
    };
    for _ in 0..n {
        let feed = rng.random_range(300..=3000);
        match rng.random_range(0..10) {
            0 | 1 => {
                // An arc by chords: radius 0.3–1.5 mm, a sweep of 20–120°.
                let r = rng.random_range(300.0..1500.0f64);
                let a = rng.random_range(0.0..std::f64::consts::TAU);
                let (i, k) = ((r * a.cos()).round(), (r * a.sin()).round());
                let (cx, cz) = (x as f64 + i, z as f64 + k);
                let sweep = rng.random_range(20.0..120.0f64).to_radians();
                let ccw = rng.random_bool(0.5);
                // The start as seen from the centre, turned by the sweep.
                let (sx, sz) = (-i, -k);
                let t = if ccw { sweep } else { -sweep };
                // Counter-clockwise in the (Z right, X up) plane.
                let ez = sz * t.cos() - sx * t.sin();
                let ex = sz * t.sin() + sx * t.cos();
                let (nx, nz) = ((cx + ex).round() as i64, (cz + ez).round() as i64);
                lines.push(format!(
                    "ARC X={} Z={} I={} K={} DIR={} F={feed}",
                    mm(2 * nx),
                    mm(nz),
                    mm(i as i64),
                    mm(k as i64),
                    if ccw { "CCW" } else { "CW" }
                ));
                (x, z) = (nx, nz);
            }
            roll => {
                let len = rng.random_range(100.0..1500.0f64);
                // Back towards the origin when far from it.
                let a = if x.abs() + z.abs() > 20_000 {
                    (-(x as f64)).atan2(-(z as f64))
                } else {
                    rng.random_range(0.0..std::f64::consts::TAU)
                };
                let (nx, nz) = (x + (len * a.sin()) as i64, z + (len * a.cos()) as i64);
                let f = if roll == 2 {
                    String::new()
                } else {
                    format!(" F={feed}")
                };
                lines.push(format!("MOVE X={} Z={}{f}", mm(2 * nx), mm(nz)));
                (x, z) = (nx, nz);
            }
        }
    }
    lines.push("SYNC".to_string());
    lines
}

/// The registers after each step event of `lines` run on the in-process
/// device (index 0: before the first), and the blocks' first events and
/// event counts.
pub struct Steps {
    /// Registers `(PX, PZ)` after `k` events.
    pub positions: Vec<(i64, i64)>,
    /// Each started block: the index of its first event, its events.
    pub blocks: Vec<(usize, u32)>,
    /// The in-process device's replies, one per request.
    pub replies: Vec<Reply>,
    /// Its `POS` final line after the program.
    pub pos: String,
}

/// Runs `lines` on the in-process device, keeping every event.
pub fn steps(lines: &[String]) -> Result<Steps, LinkError> {
    let mut dev = LocalDevice::recording();
    let mut replies = Vec::new();
    for l in lines {
        replies.push(Transport::request(&mut dev, l)?);
    }
    let pos = Transport::request(&mut dev, "POS")?.last;
    let starts: Vec<(usize, u32)> = dev
        .block_starts()
        .iter()
        .map(|(i, b)| {
            let (nx, nz) = b.delta();
            (*i, nx.unsigned_abs().max(nz.unsigned_abs()))
        })
        .collect();
    let mut positions = vec![(0i64, 0i64)];
    let (mut px, mut pz) = (0i64, 0i64);
    for e in dev.take_events() {
        let d = |step: u8, neg: u8| -> i64 {
            match (e.bits & step != 0, e.bits & neg != 0) {
                (false, _) => 0,
                (true, false) => 1,
                (true, true) => -1,
            }
        };
        px += d(1, 4);
        pz += d(2, 8);
        positions.push((px, pz));
    }
    Ok(Steps {
        positions,
        blocks: starts,
        replies,
        pos,
    })
}

/// Sends a real-time byte and reads its `!` line.
pub fn realtime(client: &mut Client, byte: u8) -> Result<String, LinkError> {
    client.write_raw(&[byte])?;
    loop {
        let l = client.read_line()?;
        if l.starts_with('!') {
            return Ok(l);
        }
    }
}

/// `(PX, PZ)` of a status or reset line.
pub fn registers(line: &str) -> Option<(i64, i64)> {
    let v = |k: &str| {
        crate::link::words_value(line, k)?
            .split('*')
            .next()?
            .parse()
            .ok()
    };
    Some((v("PX")?, v("PZ")?))
}

/// Polls status until the registers stand still; returns the last line.
fn until_at_rest(client: &mut Client) -> Result<String, LinkError> {
    let mut last = realtime(client, 0x80)?;
    loop {
        std::thread::sleep(Duration::from_millis(100));
        let now = realtime(client, 0x80)?;
        if registers(&now) == registers(&last) && now.contains("STATE=HOLD") {
            return Ok(now);
        }
        last = now;
    }
}

/// What [`paced_proof`] found.
#[derive(Debug)]
pub struct PacedReport {
    /// Requests streamed, and how long it took.
    pub requests: usize,
    pub seconds: f64,
    /// Replies that differ from the in-process device's (must be 0).
    pub mismatches: Vec<(usize, String, String)>,
    /// The final `SYNC`, from the firmware and in-process.
    pub sync: (String, String),
    /// Step events of the program.
    pub events: usize,
    /// The hold: registers where the axes came to rest, whether they are
    /// the position after some prefix of the program's events (which
    /// one), and the final `SYNC`/`POS` after the resume equal to the
    /// in-process ones.
    pub held_at: (i64, i64),
    pub held_prefix: Option<usize>,
    pub after_hold: (String, String),
    pub after_hold_expected: (String, String),
    /// The reset: its line, and whether `PX`, `PZ` are the position after
    /// `DONE` events of a block of `OF` events and after the `EV` events
    /// the next `SYNC` reports.
    pub reset_line: String,
    pub reset_consistent: bool,
}

impl PacedReport {
    /// Everything as it must be.
    pub fn passed(&self) -> bool {
        self.mismatches.is_empty()
            && self.sync.0 == self.sync.1
            && self.held_prefix.is_some()
            && self.after_hold == self.after_hold_expected
            && self.reset_consistent
    }
}

/// Streams `lines` (each request when the previous one is answered),
/// running `at(i)` before request `i`.
fn stream(
    client: &mut Client,
    lines: &[String],
    mut at: impl FnMut(usize, &mut Client) -> Result<(), LinkError>,
) -> Result<Vec<Reply>, LinkError> {
    let mut out = Vec::with_capacity(lines.len());
    for (i, l) in lines.iter().enumerate() {
        at(i, client)?;
        out.push(Transport::request(client, l)?);
    }
    Ok(out)
}

/// The streaming proof on a paced firmware: `boot` starts a fresh one and
/// connects to it.
pub fn paced_proof(
    mut boot: impl FnMut() -> Result<Client, LinkError>,
    seed: u64,
    n: usize,
) -> Result<PacedReport, LinkError> {
    let lines = program(seed, n);
    let local = steps(&lines)?;

    // 1. Streamed with the queue kept filled: the same replies, the same
    // final SYNC (every event on the same tick), nothing starved.
    let mut client = boot()?;
    let t0 = Instant::now();
    let got = stream(&mut client, &lines, |_, _| Ok(()))?;
    let seconds = t0.elapsed().as_secs_f64();
    let mismatches = got
        .iter()
        .zip(&local.replies)
        .enumerate()
        .filter(|(_, (g, w))| g != w)
        .map(|(i, (g, w))| (i, g.last.clone(), w.last.clone()))
        .collect();
    let sync = (
        got.last().map(|r| r.last.clone()).unwrap_or_default(),
        local
            .replies
            .last()
            .map(|r| r.last.clone())
            .unwrap_or_default(),
    );

    // 2. A hold in the middle of the run, then a resume.
    let mid = lines.len() / 2;
    let mut client = boot()?;
    let mut held = String::new();
    let rest = stream(&mut client, &lines, |i, c| {
        if i == mid {
            realtime(c, 0x82)?;
            held = until_at_rest(c)?;
            realtime(c, 0x81)?;
        }
        Ok(())
    })?;
    let held_at = registers(&held).unwrap_or_default();
    let held_prefix = local.positions.iter().position(|&p| p == held_at);
    let pos = Transport::request(&mut client, "POS")?;
    let after_hold = (
        rest.last()
            .map(|r| r.value("EV").unwrap_or("").to_string())
            .unwrap_or_default(),
        pos.last.clone(),
    );
    let after_hold_expected = (
        local
            .replies
            .last()
            .and_then(|r| r.value("EV"))
            .unwrap_or("")
            .to_string(),
        local.pos.clone(),
    );

    // 3. A reset in the middle of the run.
    let mut client = boot()?;
    for l in lines.iter().take(mid) {
        Transport::request(&mut client, l)?;
    }
    // Let the run go on a little, then stop it.
    std::thread::sleep(Duration::from_millis(50));
    let reset_line = realtime(&mut client, 0x18)?;
    let reset_consistent = match (
        registers(&reset_line),
        crate::link::words_value(&reset_line, "DONE").and_then(|v| v.parse::<usize>().ok()),
        crate::link::words_value(&reset_line, "OF").and_then(|v| v.parse::<u32>().ok()),
    ) {
        // Between two blocks nothing is running: the registers are a
        // block's start.
        (Some(p), Some(0), Some(0)) => local
            .blocks
            .iter()
            .any(|&(first, _)| local.positions.get(first) == Some(&p)),
        (Some(p), Some(done), Some(of)) => local.blocks.iter().any(|&(first, events)| {
            events == of && done <= of as usize && local.positions.get(first + done) == Some(&p)
        }),
        _ => false,
    };
    // What SYNC then reports counts the events issued, the one that was
    // waiting for its tick not among them: the registers are where those
    // events lead.
    let after = Transport::request(&mut client, "SYNC")?;
    let reset_consistent = reset_consistent
        && after
            .value("EV")
            .and_then(|v| v.parse::<usize>().ok())
            .is_some_and(|k| registers(&reset_line).as_ref() == local.positions.get(k));

    Ok(PacedReport {
        requests: lines.len(),
        seconds,
        mismatches,
        sync,
        events: local.positions.len() - 1,
        held_at,
        held_prefix,
        after_hold,
        after_hold_expected,
        reset_line,
        reset_consistent,
    })
}

/// A program at one event rate: `moves` collinear moves along −Z, each
/// 20 ms long at cruise, at the price 0.001 mm and `F = rate·0.06` mm/min
/// (`rate` events a second), accelerating at 5000 mm/s² from rest at the
/// start and to rest at the end.
pub fn rate_program(rate: u32, moves: usize) -> Vec<String> {
    let mut lines: Vec<String> = [
        "ZERO",
        "CFG HX=0.001 HZ=0.001 DIAM=0",
        "DRIVE RATE=200000",
        "LIMITS VX=6000 VZ=12000 AX=5000 AZ=5000",
    ]
    .map(String::from)
    .into();
    let feed = f64::from(rate) * 0.06;
    // 20 ms of events, in µm (one event per µm).
    let step_um = u64::from(rate) / 50;
    for k in 1..=moves as u64 {
        let um = k * step_um;
        lines.push(format!(
            "MOVE Z=-{}.{:03} F={feed:.3}",
            um / 1000,
            um % 1000
        ));
    }
    lines.push("SYNC".into());
    lines
}

/// What [`status_latency`] found.
#[derive(Debug)]
pub struct Latency {
    /// `LAT=` of every `!STATUS` line (µs from the byte to the line).
    pub samples: Vec<u32>,
    /// The final replies (the last is the `SYNC`).
    pub replies: Vec<String>,
}

impl Latency {
    /// The worst sample, and the median.
    pub fn worst_and_median(&self) -> (u32, u32) {
        let mut s = self.samples.clone();
        s.sort_unstable();
        (
            s.last().copied().unwrap_or(0),
            s.get(s.len() / 2).copied().unwrap_or(0),
        )
    }
}

/// Streams `lines` (each request when the previous one is answered) and
/// sends a status byte whenever `every` passes without a reply line, as a
/// sender polling its display does; collects the board's `LAT=`.
pub fn status_latency(
    client: &mut Client,
    lines: &[String],
    every: Duration,
    deadline: Duration,
) -> Result<Latency, LinkError> {
    let end = Instant::now() + deadline;
    client.set_timeout(every);
    let mut out = Latency {
        samples: Vec::new(),
        replies: Vec::new(),
    };
    for l in lines {
        let mut bytes = crate::link::with_checksum(l).into_bytes();
        bytes.extend_from_slice(b"\r\n");
        client.write_raw(&bytes)?;
        loop {
            if Instant::now() > end {
                return Err(LinkError::Timeout);
            }
            let line = match client.read_line() {
                Ok(line) => line,
                Err(LinkError::Timeout) => {
                    client.write_raw(&[0x80])?;
                    continue;
                }
                Err(e) => return Err(e),
            };
            let body = crate::link::check_reply_line(&line)?;
            if body.starts_with('!') {
                if let Some(v) = crate::link::words_value(body, "LAT") {
                    out.samples.push(v.parse().map_err(|_| {
                        LinkError::Io(std::io::Error::other(format!("bad LAT in {body:?}")))
                    })?);
                }
            } else if body.starts_with("OK") || body.starts_with("ERR") {
                out.replies.push(body.to_string());
                break;
            }
        }
    }
    Ok(out)
}

/// How late the firmware issued its events: `LATE=` (events after their
/// tick) and `WORST=` (ticks) of the last `timing:` line a QEMU build
/// writes to its log beside each `!STATUS` (the status line's format is
/// the protocol's).
pub fn lateness(log: &[u8]) -> Option<(u64, u64)> {
    let text = String::from_utf8_lossy(log);
    let line = text.rsplit("timing: ").next()?;
    let value = |k: &str| -> Option<u64> {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(k))?
            .trim_matches(|c: char| !c.is_ascii_digit())
            .parse()
            .ok()
    };
    Some((value("LATE=")?, value("WORST=")?))
}

/// What [`hold_and_resume`] found.
#[derive(Debug)]
pub struct HeldStream {
    /// The final `SYNC`'s events and `POS`, from the firmware.
    pub end: (String, String),
    /// The same from the in-process device (no hold).
    pub expected: (String, String),
    /// Where the hold came to rest.
    pub held: String,
}

/// Streams `lines` with a feed hold after half of them, waits until the
/// axes rest, resumes, and streams on; then `POS`. The events and the end
/// point must be the in-process device's (the hold retimes, it does not
/// move the path).
pub fn hold_and_resume(client: &mut Client, lines: &[String]) -> Result<HeldStream, LinkError> {
    let local = steps(lines)?;
    let mid = lines.len() / 2;
    let mut held = String::new();
    let got = stream(client, lines, |i, c| {
        if i == mid {
            realtime(c, 0x82)?;
            held = until_at_rest(c)?;
            realtime(c, 0x81)?;
        }
        Ok(())
    })?;
    let pos = Transport::request(client, "POS")?;
    let ev = |r: Option<&Reply>| r.and_then(|r| r.value("EV")).unwrap_or("").to_string();
    Ok(HeldStream {
        end: (ev(got.last()), pos.last),
        expected: (ev(local.replies.last()), local.pos),
        held,
    })
}

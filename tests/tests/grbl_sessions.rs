//! No line acknowledged and then dropped: random grbl sessions (G-code
//! lines, refused lines, `M0`, real-time bytes anywhere, overrides sent as
//! UTF-8, resets, quiet gaps) against the simulated board on the wall clock
//! and against the paced firmware in QEMU. Every line answered `ok` either
//! runs — the axes end where the last one acknowledged puts them — or is
//! reported lost by an alarm (`ALARM:3`) at the reset that dropped it.
//!
//! The sessions are drawn from a seed: `PROPTEST_RNG_SEED` when set (CI
//! fixes it, as for the property tests), else a new one each run, printed.
//! The QEMU part is skipped with a message where `qemu-system-arm` is
//! missing, except under CI.

use host_sim::link::{Client, LinkError};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::{Duration, Instant};

/// One step of a session.
#[derive(Clone, Debug)]
enum Step {
    /// A line that moves (absolute, its modes in it: a reset forgets them)
    /// to X (diameter) and Z, as a rapid or at a feed.
    Move { x: i32, z: i32, feed: Option<u32> },
    /// `M0`: answered, then a hold at rest until cycle start.
    Stop,
    /// A line refused by name (nothing moves).
    Bad,
    /// Real-time bytes, some of them inside the next line.
    Realtime(Vec<u8>),
    /// Ctrl-X.
    Reset,
    /// Nothing for a while: what is queued starts.
    Quiet(u64),
}

fn session(rng: &mut ChaCha8Rng, steps: usize) -> Vec<Step> {
    (0..steps)
        .map(|_| match rng.random_range(0..100) {
            0..=54 => Step::Move {
                x: rng.random_range(0..=40),
                z: -rng.random_range(0..=30),
                feed: rng.random_bool(0.6).then(|| rng.random_range(300..=3000)),
            },
            55..=61 => Step::Stop,
            62..=67 => Step::Bad,
            68..=85 => {
                let choices: [&[u8]; 7] = [
                    b"?",
                    b"!",
                    b"~",
                    &[0xC2, 0x91],
                    &[0x92],
                    &[0x96],
                    &[0xC2, 0x95],
                ];
                let n = rng.random_range(1..=3);
                Step::Realtime(
                    (0..n)
                        .flat_map(|_| choices[rng.random_range(0..choices.len())].to_vec())
                        .collect(),
                )
            }
            86..=90 => Step::Reset,
            _ => Step::Quiet(rng.random_range(30..=150)),
        })
        .collect()
}

/// What the sender knows.
struct Model {
    /// Where the last line acknowledged puts the axes (X diameter, Z), mm.
    at: (f64, f64),
    /// An alarm reported the motion since the last reset as possibly lost.
    alarms: usize,
    acknowledged: usize,
    refused: usize,
}

/// Reads lines until a final answer (`ok` or `error:N`); real-time bytes
/// pending are sent first. A hold that keeps the answer back (the queue is
/// full behind an `M0` or a `!`) is released with cycle start, as an
/// operator would.
fn answer(c: &mut Client, lines: &mut Vec<String>) -> Result<bool, LinkError> {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        match c.read_line() {
            Ok(l) if l == "ok" => return Ok(true),
            Ok(l) if l.starts_with("error:") => return Ok(false),
            Ok(l) => lines.push(l),
            Err(LinkError::Timeout) if Instant::now() < deadline => c.write_raw(b"~")?,
            Err(e) => return Err(e),
        }
    }
}

/// The state and position of a status report asked for now (reports
/// already on their way, answers to earlier `?`, are read first).
fn position(c: &mut Client, lines: &mut Vec<String>) -> Result<(String, (f64, f64)), LinkError> {
    c.set_timeout(Duration::from_millis(150));
    loop {
        match c.read_line() {
            Ok(l) => lines.push(l),
            Err(LinkError::Timeout) => break,
            Err(e) => return Err(e),
        }
    }
    c.set_timeout(Duration::from_secs(3));
    c.write_raw(b"?")?;
    loop {
        let l = c.read_line()?;
        if let Some(rest) = l.strip_prefix('<') {
            let p: Vec<f64> = rest
                .split("MPos:")
                .nth(1)
                .and_then(|s| s.split('|').next())
                .map(|s| s.split(',').filter_map(|v| v.parse().ok()).collect())
                .unwrap_or_default();
            let state = rest.split('|').next().unwrap_or("").to_string();
            return Ok((state, (p[0], p[2])));
        }
        lines.push(l);
    }
}

/// Runs `steps` and checks the property; what it saw, for the failure.
fn run(c: &mut Client, steps: &[Step]) -> Result<Model, String> {
    let err = |e: LinkError| e.to_string();
    let mut m = Model {
        at: (0.0, 0.0),
        alarms: 0,
        acknowledged: 0,
        refused: 0,
    };
    let mut lines = Vec::new();
    let mut pending_rt: Vec<u8> = Vec::new();
    let near = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6;
    for (i, step) in steps.iter().enumerate() {
        let line = match step {
            Step::Move { x, z, feed } => Some(match feed {
                Some(f) => format!("G21 G90 G01 X{x} Z{z} F{f}"),
                None => format!("G21 G90 G00 X{x} Z{z}"),
            }),
            Step::Stop => Some("M0".to_string()),
            Step::Bad => Some("G01 X5 Q7".to_string()),
            Step::Realtime(bytes) => {
                pending_rt.extend_from_slice(bytes);
                None
            }
            Step::Quiet(ms) => {
                std::thread::sleep(Duration::from_millis(*ms));
                None
            }
            Step::Reset => {
                c.write_raw(&[0x18]).map_err(err)?;
                let mut reset_lines = Vec::new();
                loop {
                    let l = c.read_line().map_err(err)?;
                    let end = l.starts_with("Grbl 1.1h");
                    reset_lines.push(l);
                    if end {
                        break;
                    }
                }
                // The lines of the reset: ALARM:3 first when it dropped
                // motion acknowledged, then the banner and the lock.
                let alarm = reset_lines.iter().any(|l| l == "ALARM:3");
                if alarm {
                    m.alarms += 1;
                    let _ = c.read_line().map_err(err)?; // [MSG:'$H'|'$X' to unlock]
                    c.write_raw(b"$X\n").map_err(err)?;
                    answer(c, &mut lines).map_err(err)?;
                    let (_, here) = position(c, &mut lines).map_err(err)?;
                    m.at = here;
                } else {
                    let (state, here) = position(c, &mut lines).map_err(err)?;
                    if !near(here, m.at) {
                        return Err(format!(
                            "step {i}: a reset without an alarm, the axes at {here:?} ({state}), \
                             the last line acknowledged ends at {:?}",
                            m.at
                        ));
                    }
                }
                None
            }
        };
        let Some(line) = line else { continue };
        // Real-time bytes go in the middle of the line.
        let mut bytes = line.clone().into_bytes();
        let cut = bytes.len() / 2;
        let tail = bytes.split_off(cut);
        bytes.extend_from_slice(&pending_rt);
        bytes.extend_from_slice(&tail);
        bytes.push(b'\n');
        pending_rt.clear();
        c.write_raw(&bytes).map_err(err)?;
        let ok = answer(c, &mut lines).map_err(err)?;
        match (step, ok) {
            (Step::Move { x, z, .. }, true) => {
                m.acknowledged += 1;
                m.at = (f64::from(*x), f64::from(*z));
            }
            (Step::Stop, true) => m.acknowledged += 1,
            (Step::Bad, false) => m.refused += 1,
            (s, ok) => return Err(format!("step {i}: {s:?} answered ok={ok}: {lines:?}")),
        }
    }
    // The end: cycle start until the axes rest where the last line
    // acknowledged puts them.
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        c.write_raw(b"~").map_err(err)?;
        std::thread::sleep(Duration::from_millis(200));
        let (state, here) = position(c, &mut lines).map_err(err)?;
        if state == "Idle" {
            if !near(here, m.at) {
                return Err(format!(
                    "the axes rest at {here:?}, the last line acknowledged ends at {:?}",
                    m.at
                ));
            }
            return Ok(m);
        }
        if Instant::now() > deadline {
            return Err(format!("never at rest: {state} at {here:?}"));
        }
    }
}

fn seed() -> u64 {
    std::env::var("PROPTEST_RNG_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            let s = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(1, |d| d.as_nanos() as u64);
            eprintln!("grbl sessions drawn from seed {s} (PROPTEST_RNG_SEED={s} repeats them)");
            s
        })
}

/// Drives `sessions` random sessions of `steps` each through `connect`.
fn check(
    name: &str,
    sessions: u64,
    steps: usize,
    mut connect: impl FnMut() -> Result<Client, LinkError>,
) {
    let base = seed();
    let mut totals = (0, 0, 0);
    for k in 0..sessions {
        let mut rng = ChaCha8Rng::seed_from_u64(base.wrapping_add(k));
        let steps = session(&mut rng, steps);
        let mut c = connect().expect("connect");
        match run(&mut c, &steps) {
            Ok(m) => {
                totals.0 += m.acknowledged;
                totals.1 += m.refused;
                totals.2 += m.alarms;
            }
            Err(e) => panic!("{name}, seed {}: {e}\n{steps:?}", base.wrapping_add(k)),
        }
    }
    eprintln!(
        "{name}: {sessions} sessions, {} lines acknowledged, {} refused, {} resets with ALARM:3; none dropped",
        totals.0, totals.1, totals.2
    );
}

#[test]
fn no_line_acknowledged_is_dropped_on_the_simulated_board() {
    struct Nowhere;
    impl core_nostd::protocol::Io for Nowhere {
        fn send(&mut self, _: &[u8]) {}
    }
    let mut boards = Vec::new();
    check("serve (wall clock ×4)", 6, 60, || {
        let mut device = core_nostd::protocol::Device::new();
        device.set_grbl(true, &mut Nowhere);
        let (path, board) = host_sim::board::serve_pty(device, host_sim::board::Pace::Wall(4.0))
            .map_err(LinkError::Io)?;
        boards.push(board);
        let mut c = Client::open(&path, Duration::from_secs(5))?;
        // The greeting.
        while !c.read_line()?.starts_with("Grbl 1.1h") {}
        c.set_timeout(Duration::from_secs(3));
        Ok(c)
    });
}

#[test]
fn no_line_acknowledged_is_dropped_on_the_firmware() {
    if !host_sim::qemu::qemu_or_skip() {
        return;
    }
    let elf = host_sim::qemu::build_firmware("qemu-paced").expect("firmware");
    let mut running = Vec::new();
    check("the paced firmware in QEMU", 2, 50, || {
        let mut q = host_sim::qemu::Qemu::boot_paced(&elf)?;
        let mut c = q.connect(Duration::from_secs(60))?;
        running.push(q);
        c.write_raw(b"GRBL\r\n")?;
        while !c.read_line()?.starts_with("Grbl 1.1h") {}
        c.set_timeout(Duration::from_secs(3));
        Ok(c)
    });
}

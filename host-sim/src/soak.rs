//! A long seeded session over a faulty link: the device's registers must end
//! equal to the reference's, with no corrupted request ever run.

use crate::compare::{block_matches, Step};
use crate::link::LinkError;
use crate::reliable::{ByteLink, FaultStats, ReliableSession, SessionStats, Shadow};
use crate::scenario::{self, nm_to_decimal};
use reference::impulse::{RefConfig, RefMachine};
use std::time::{Duration, Instant};

/// The outcome of a soak.
#[derive(Clone, Debug)]
pub struct SoakReport {
    /// Requests answered (retries not counted).
    pub requests: u64,
    /// Blocks compared with the reference.
    pub blocks: u64,
    /// Blocks whose reply differed from the reference.
    pub mismatches: u64,
    /// What the session did.
    pub session: SessionStats,
    /// Registers at the end, device and reference.
    pub device_end: (i64, i64),
    /// Registers at the end, reference.
    pub reference_end: (i64, i64),
    /// Wall time.
    pub elapsed: Duration,
}

impl SoakReport {
    /// Whether the soak passed: every block matched and the registers agree.
    pub fn passed(&self) -> bool {
        self.mismatches == 0 && self.device_end == self.reference_end
    }
}

fn shadow_of(r: &RefMachine, hx: &str, hz: &str) -> Shadow {
    let (x, z) = r.commanded_half_nm();
    Shadow {
        hx: hx.into(),
        hz: hz.into(),
        diam: r.config().diam,
        // X is the radius in half-nanometres: the diameter in nm.
        x_diameter: nm_to_decimal(x),
        z: nm_to_decimal(z / 2),
    }
}

/// Runs `blocks` seeded random blocks (with their price, mode and zero
/// changes) through a reliable session on `link`.
pub fn soak<L: ByteLink>(
    link: L,
    seed: u64,
    blocks: usize,
    timeout: Duration,
    mut progress: impl FnMut(u64),
) -> Result<(SoakReport, L), LinkError> {
    let started = Instant::now();
    let mut session = ReliableSession::new(link, timeout, 0x5EED_0000 ^ seed as u32 | 1)?;
    let mut reference = RefMachine::new(RefConfig::default());
    let (mut hx, mut hz) = ("0.005".to_string(), "0.01".to_string());
    let mut compared = 0u64;
    let mut mismatches = 0u64;
    for step in scenario::random(seed, blocks).steps {
        let reply = session.request(&step.request())?;
        match &step {
            Step::Cfg { hx: x, hz: z, diam } => {
                let mut cfg = reference.config();
                if let Some(v) = x {
                    cfg.hx_mm = v.parse().unwrap_or(f64::NAN);
                    hx = v.clone();
                }
                if let Some(v) = z {
                    cfg.hz_mm = v.parse().unwrap_or(f64::NAN);
                    hz = v.clone();
                }
                if let Some(d) = diam {
                    cfg.diam = *d;
                }
                reference.set_config(cfg);
                mismatches += u64::from(!reply.is_ok());
            }
            Step::Zero => {
                reference.zero();
                mismatches += u64::from(!reply.is_ok());
            }
            Step::Move { x, z, inc, .. } => {
                let expected = reference.move_block(x.as_deref(), z.as_deref(), *inc);
                compared += 1;
                mismatches += u64::from(!block_matches(&reply, &expected));
                progress(compared);
            }
            Step::Arc { .. } => {}
            // Motion runs; the times are the main job's to compare.
            Step::Sync => mismatches += u64::from(!reply.is_ok()),
        }
        session.shadow = shadow_of(&reference, &hx, &hz);
    }
    let pos = session.request("POS")?;
    let int = |k: &str| {
        pos.value(k)
            .and_then(|v| v.parse().ok())
            .unwrap_or(i64::MIN)
    };
    let report = SoakReport {
        requests: session.stats.requests,
        blocks: compared,
        mismatches,
        session: session.stats,
        device_end: (int("PX"), int("PZ")),
        reference_end: reference.position(),
        elapsed: started.elapsed(),
    };
    Ok((report, session.into_link()))
}

/// Prints a soak's report.
pub fn print_report(r: &SoakReport, faults: &FaultStats, executed_corrupted: Option<u64>) {
    println!(
        "faults injected: {} request lines and {} reply lines damaged ({} bit flips, {} drops, {} duplicates, {} noise bursts), {} device resets",
        faults.requests_damaged, faults.replies_damaged, faults.flips, faults.drops, faults.dups, faults.bursts, faults.resets
    );
    println!(
        "detected: {} corrupted reply lines dropped, {} stale replies dropped, {} retries, {} resets found and restored",
        r.session.corrupt_replies, r.session.stale_replies, r.session.retries, r.session.resets_detected
    );
    if let Some(n) = executed_corrupted {
        println!("corrupted requests run by the device: {n}");
    }
    println!(
        "{} requests, {} blocks compared, {} mismatches, {:.0} requests/s",
        r.requests,
        r.blocks,
        r.mismatches,
        r.requests as f64 / r.elapsed.as_secs_f64()
    );
    println!(
        "registers at the end: device PX={} PZ={}, reference PX={} PZ={}",
        r.device_end.0, r.device_end.1, r.reference_end.0, r.reference_end.1
    );
}

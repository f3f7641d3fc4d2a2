//! Bit-for-bit comparison of the device against the f64 reference.
//!
//! Every step of a scenario goes to the device over a [`Transport`] and to
//! the [`RefMachine`]; for every block the device's `NX`, `NZ`, `PX`, `PZ` and
//! `SEQ` must equal the reference's. The tally keeps how close the rounding
//! decisions came to a tie (SPEC §7), so the margin is visible.

use crate::link::{LinkError, Reply, Transport};
use crate::reference::{RefBlock, RefConfig, RefMachine, TieStats};
use std::fmt::Write as _;

/// One request of a scenario.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// `CFG` with the impulse prices and diameter mode (words as written).
    Cfg {
        /// `HX=`, mm.
        hx: Option<String>,
        /// `HZ=`, mm.
        hz: Option<String>,
        /// `DIAM=`.
        diam: Option<bool>,
    },
    /// `ZERO`.
    Zero,
    /// `MOVE`, words as written.
    Move {
        /// `X=` (a diameter when DIAM=1).
        x: Option<String>,
        /// `Z=`.
        z: Option<String>,
        /// `INC=1`.
        inc: bool,
    },
}

impl Step {
    /// An absolute move.
    pub fn to(x: impl Into<String>, z: impl Into<String>) -> Step {
        Step::Move {
            x: Some(x.into()),
            z: Some(z.into()),
            inc: false,
        }
    }

    /// The request line.
    pub fn request(&self) -> String {
        let mut line = String::new();
        match self {
            Step::Cfg { hx, hz, diam } => {
                line.push_str("CFG");
                if let Some(v) = hx {
                    let _ = write!(line, " HX={v}");
                }
                if let Some(v) = hz {
                    let _ = write!(line, " HZ={v}");
                }
                if let Some(d) = diam {
                    let _ = write!(line, " DIAM={}", u8::from(*d));
                }
            }
            Step::Zero => line.push_str("ZERO"),
            Step::Move { x, z, inc } => {
                line.push_str("MOVE");
                if let Some(v) = x {
                    let _ = write!(line, " X={v}");
                }
                if let Some(v) = z {
                    let _ = write!(line, " Z={v}");
                }
                if *inc {
                    line.push_str(" INC=1");
                }
            }
        }
        line
    }
}

/// A named list of steps.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Shown in the report.
    pub name: String,
    /// The requests, in order.
    pub steps: Vec<Step>,
}

impl Scenario {
    /// Number of `MOVE` steps.
    pub fn blocks(&self) -> usize {
        self.steps
            .iter()
            .filter(|s| matches!(s, Step::Move { .. }))
            .count()
    }
}

/// A difference between the device and the reference.
#[derive(Clone, Debug)]
pub struct Mismatch {
    /// Scenario name.
    pub scenario: String,
    /// Index of the step in its scenario.
    pub index: usize,
    /// The request sent.
    pub request: String,
    /// What the device replied (final line).
    pub device: String,
    /// What the reference expected.
    pub expected: String,
}

/// Running totals of a comparison.
#[derive(Clone, Debug, Default)]
pub struct Tally {
    /// Blocks compared.
    pub blocks: u64,
    /// Step events in those blocks.
    pub events: u64,
    /// Impulses issued, summed over axes, absolute.
    pub impulses: u64,
    /// Differences found.
    pub mismatches: Vec<Mismatch>,
    /// Ties of the quantizer `Q(P/h)`.
    pub quantizer: TieStats,
    /// Ties of the interleaver `Q(i·Δb/|Δlead|)`.
    pub interleave: TieStats,
}

impl Tally {
    /// The smallest distance to a rounding tie over all values that were not
    /// exact ties, in impulses.
    pub fn min_tie_distance(&self) -> f64 {
        self.quantizer
            .min_distance
            .min(self.interleave.min_distance)
    }

    /// Exact ties met, over both sources.
    pub fn exact_ties(&self) -> u64 {
        self.quantizer.exact_ties + self.interleave.exact_ties
    }

    /// The closing line of the main job.
    pub fn result_line(&self) -> String {
        format!(
            "RESULT: {} blocks compared bit-for-bit, {} mismatches, min tie distance {} impulses",
            self.blocks,
            self.mismatches.len(),
            format_distance(self.min_tie_distance())
        )
    }
}

/// A tie distance for the report.
pub fn format_distance(d: f64) -> String {
    if d.is_finite() {
        format!("{d:.3e}")
    } else {
        "none".into()
    }
}

/// Drives a device and the reference through the same steps.
pub struct Comparator<T: Transport> {
    link: T,
    reference: RefMachine,
    /// Totals so far.
    pub tally: Tally,
}

impl<T: Transport> Comparator<T> {
    /// Starts from power-on state on both sides. The device is brought there
    /// with `CFG` defaults and `ZERO`.
    pub fn new(mut link: T) -> Result<Self, LinkError> {
        for line in ["CFG HX=0.005 HZ=0.01 DIAM=1", "ZERO"] {
            let r = link.request(line)?;
            if !r.is_ok() {
                return Err(LinkError::Io(std::io::Error::other(format!(
                    "device refused {line:?}: {}",
                    r.last
                ))));
            }
        }
        Ok(Comparator {
            link,
            reference: RefMachine::new(RefConfig::default()),
            tally: Tally::default(),
        })
    }

    /// The link, for requests outside the comparison.
    pub fn link(&mut self) -> &mut T {
        &mut self.link
    }

    /// Runs every step of a scenario; `progress` is called after each block.
    pub fn run(
        &mut self,
        scenario: &Scenario,
        mut progress: impl FnMut(&Tally),
    ) -> Result<(), LinkError> {
        for (index, step) in scenario.steps.iter().enumerate() {
            self.step(&scenario.name, index, step)?;
            if matches!(step, Step::Move { .. }) {
                progress(&self.tally);
            }
        }
        Ok(())
    }

    /// Runs one step on both sides and compares.
    pub fn step(&mut self, scenario: &str, index: usize, step: &Step) -> Result<(), LinkError> {
        let request = step.request();
        let reply = self.link.request(&request)?;
        let mismatch = |expected: String, reply: &Reply| Mismatch {
            scenario: scenario.to_owned(),
            index,
            request: request.clone(),
            device: reply.last.clone(),
            expected,
        };
        match step {
            Step::Cfg { hx, hz, diam } => {
                let mut cfg = self.reference.config();
                if let Some(v) = hx {
                    cfg.hx_mm = parse_mm(v);
                }
                if let Some(v) = hz {
                    cfg.hz_mm = parse_mm(v);
                }
                if let Some(d) = diam {
                    cfg.diam = *d;
                }
                self.reference.set_config(cfg);
                let (px, pz) = self.reference.position();
                if !reply.is_ok() {
                    self.tally
                        .mismatches
                        .push(mismatch(format!("OK (PX={px} PZ={pz})"), &reply));
                }
            }
            Step::Zero => {
                self.reference.zero();
                if !reply.is_ok() {
                    self.tally.mismatches.push(mismatch("OK".into(), &reply));
                }
            }
            Step::Move { x, z, inc } => {
                let expected = self.reference.move_block(x.as_deref(), z.as_deref(), *inc);
                self.tally.blocks += 1;
                self.tally.events += expected.events;
                self.tally.impulses += expected.nx.unsigned_abs() + expected.nz.unsigned_abs();
                self.tally.quantizer.merge(&expected.quantizer_ties);
                self.tally.interleave.merge(&expected.interleave_ties);
                if !block_matches(&reply, &expected) {
                    self.tally
                        .mismatches
                        .push(mismatch(expected_line(&expected), &reply));
                }
            }
        }
        Ok(())
    }
}

fn parse_mm(v: &str) -> f64 {
    v.parse().unwrap_or(f64::NAN)
}

/// The reference's block as the device should print it.
pub fn expected_line(b: &RefBlock) -> String {
    format!(
        "OK NX={} NZ={} PX={} PZ={} SEQ={:08X}",
        b.nx, b.nz, b.px, b.pz, b.seq
    )
}

/// Whether a `MOVE` reply carries exactly the reference's values.
pub fn block_matches(reply: &Reply, b: &RefBlock) -> bool {
    let int = |k: &str| reply.value(k).and_then(|v| v.parse::<i64>().ok());
    reply.is_ok()
        && int("NX") == Some(b.nx)
        && int("NZ") == Some(b.nz)
        && int("PX") == Some(b.px)
        && int("PZ") == Some(b.pz)
        && reply
            .value("SEQ")
            .and_then(|v| u32::from_str_radix(v, 16).ok())
            == Some(b.seq)
        && reply.value("SEQ").map(str::len) == Some(8)
}

//! Independent models of the lathe retrofit controller's rules, written from
//! `docs/` alone (`docs/verification.md` §3): what the fixed-point core is
//! compared with, bit for bit. The crate does not depend on the core, and
//! must not: `core-nostd` is not among its dependencies, so nothing of it can
//! be named here, and CI checks that it stays so.
//!
//! - [`impulse`]: f64 model of impulses, registers, the interleaving of a
//!   block and its `SEQ` (`docs/impulses.md`), with exact ties recognised by
//!   an error bound;
//! - [`arc`]: f64 arcs by chords and the ЭМ-907 circular interpolator
//!   (`docs/arcs.md`), on the machine of [`impulse`];
//! - [`motion`]: the planner and step timer in double-double arithmetic
//!   (`docs/motion.md`);
//! - [`comp`]: f64 nose radius compensation of G41/G42 contours
//!   (`docs/compensation.md` §1–§6);
//! - [`cone`]: f64 taper corrections and the Nomura table
//!   (`docs/compensation.md` §7);
//! - [`corner`]: f64 corner chamfers and rounds `,C`/`,R`
//!   (`docs/compensation.md` §9);
//! - [`cycle`]: f64 roughing of the turning cycles `G71`, `G72` and `G73`,
//!   move for move, with the geometric checks of its passes
//!   (`docs/cycles.md` §1–§3);
//! - [`trihedral`]: the trihedral corner built from three edge vectors
//!   (`docs/calculators.md` §4);
//! - [`exact`]: exact rational model of `MOVE`, `CFG`, `ZERO` and `POS`, `Q`,
//!   the step rule and CRC-32, with no floating point at all;
//! - [`sync`]: exact model of motion locked to the spindle: the progress,
//!   registers and step events of a synchronised pass, its refusals and its
//!   lead-in (`docs/threading.md`), with no floating point;
//! - [`protocol`]: the protocol's limits, error codes and request numbers, for
//!   the oracles (`docs/protocol.md`).
//!
//! Modules import downwards only: `arc` and `motion` build on `impulse` and
//! the private double-double arithmetic `dd`; `exact` on `protocol`
//! (`tests/tests/module_cycles.rs` checks there is no cycle).

pub mod arc;
pub mod comp;
pub mod cone;
pub mod corner;
pub mod cycle;
mod dd;
pub mod exact;
pub mod impulse;
pub mod motion;
pub mod protocol;
pub mod sync;
pub mod trihedral;

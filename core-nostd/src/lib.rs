//! Fixed-point core of a lathe retrofit controller.
//!
//! `#![no_std]`, no allocation, no floating point in the motion path. It runs
//! unchanged on the STM32F405 firmware and inside the host simulator.
//!
//! # Layers
//! - [`length`]: exact decimal lengths ([`length::Length`], integer ångström,
//!   10⁻⁷ mm). Any value written with up to 6 decimals of a millimetre is held
//!   exactly, and so is half of it (diameter words become exact radii).
//! - [`impulse`]: impulse prices and the quantizer `Q(P/h)` that implements the
//!   1977 residual-carry rule in closed form.
//! - [`interleave`]: the step events of a linear block, produced one at a time
//!   with integer additions only, for a timer interrupt to pull.
//! - [`arc`]: arcs by chords with residual carry, and the direct
//!   step-by-step circular interpolator of the ЭМ-907.
//! - [`comp`]: tool nose radius compensation over G41/G42 contours.
//! - [`gcode`]: G-code blocks parsed and checked before any motion, in the
//!   ISO and the Fanuc dialect.
//! - [`interp`]: the interpreter's state between blocks (modal codes, feed,
//!   spindle, coolant, tool) and a block's feed and spindle speed.
//! - [`inputs`]: the machine's switches (E-stop, limits, door, buttons,
//!   probe, drive faults), their active level and filter.
//! - [`outputs`]: the spindle's run, direction and speed (a PWM duty)
//!   and the coolant, as the board drives them.
//! - [`calc`]: the seeds' other calculators (deflection, wear, threading
//!   speed, tapes, the trihedral-angle set-up), in `f64`.
//! - [`cone`]: taper corrections for a tool nose radius (Krylenko, Nomura).
//! - [`crc32`]: the CRC-32 that fingerprints a block's step sequence (`SEQ`).
//! - [`protocol`]: the pendant line protocol, bytes in, reply lines out.
//! - [`trig`]: fixed-point sine, cosine, atan2 and square root, with error
//!   bounds.
//! - [`plan`]: the velocity planner: limits, junctions, the look-ahead
//!   window, each block's trapezoid.
//! - [`step`]: the timed step generator: each event's tick, integer-only.
//! - [`stepper`]: started motion in order, pulled one event at a time (the
//!   stage the prep runs), with what has been handed out.
//! - [`prep`]: the prep stage: started motion turned into ready events
//!   (tick, pins, TSEQ) ahead of the step interrupt, which only issues
//!   them, and what it issued.
//! - [`sync`]: motion locked to the spindle: a threading pass as an exact
//!   function of the encoder counts, and its step events by count.
//! - [`thread`]: LinuxCNC's threading cycle `G76`: the depth of each pass
//!   and its moves, checked before the first.
//! - [`store`]: the tool table and work offsets as a record in two flash
//!   slots that a power cut during a write cannot break.
//! - [`machine`]: the planner and the stepper behind one front, as the
//!   virtual-clock device of `docs/motion.md`.
//! - [`stepdir`]: step/dir outputs on `embedded-hal` pins, paced by a timer.
//! - [`watch`]: the supervisor's judgement of a stalled step interrupt or
//!   main loop, for a board's watchdog.
//!
//! # Numeric conventions
//! | quantity | type | unit stored | overflow |
//! |---|---|---|---|
//! | length, coordinate | [`length::Length`] | i64 ångström (10⁻⁷ mm), `|v| < 100 000 mm` | `checked_*` → `None`; parse → `LengthError` |
//! | impulse price | [`impulse::ImpulsePrice`] | i64 ångström, 0.000001…1 mm | constructor → `None` |
//! | impulse position | [`impulse::Impulses`] | i32, `|n| ≤ 999 999 999` | [`impulse::quantize`] → `RangeError` |
//! | impulses in one block | [`interleave::LinearBlock`] | ≤ 1 000 000 per axis | constructor → `RangeError` |
//!
//! Rounding: `Q` rounds half away from zero everywhere (impulses, the
//! interleaver, and the 4-decimal millimetres printed in replies).
//! Inner loops take validated values and cannot fail: once a
//! [`interleave::LinearBlock`] exists, its events are produced without any
//! check that could fail.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod arc;
pub mod calc;
pub mod comp;
pub mod cone;
pub mod crc32;
pub mod cycle;
pub mod gcode;
pub mod homing;
pub mod impulse;
pub mod inputs;
pub mod interleave;
pub mod interp;
pub mod length;
pub mod machine;
pub mod outputs;
pub mod plan;
pub mod prep;
pub mod protocol;
pub mod step;
pub mod stepdir;
pub mod stepper;
pub mod store;
pub mod sync;
mod text;
pub mod thread;
pub mod trig;
pub mod watch;
mod wide;

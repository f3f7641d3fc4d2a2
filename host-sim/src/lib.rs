//! Host simulator of the lathe retrofit controller.
//!
//! The models the device is compared with are the crate `reference`, written
//! from `docs/` alone and independent of the fixed-point core
//! (`docs/verification.md` §3); this crate drives both and compares them.
//!
//! - [`device`]: the core's protocol handler in this process;
//! - [`board`]: the simulated board `serve` runs: the device behind a
//!   receiver, the axes on the wall clock and the protocol, as the firmware
//!   runs them; [`lathe`]: the machine behind it (`--machine FILE`), whose
//!   carriages trip its switches;
//! - [`link`]: the virtual serial link (a pseudo-terminal pair driven through
//!   the `serialport` crate) and the host side of the protocol;
//! - [`qemu`]: the firmware booted in QEMU, reached over its serial pty;
//! - [`compare`]: the bit-for-bit comparison of device replies against the
//!   reference;
//! - [`reliable`]: requests that survive a faulty link, and the fault
//!   injector; [`soak`]: long faulted sessions against the reference;
//! - [`table`]: what the calculators print: text, CSV or JSON;
//! - [`calculators`]: `thread-speed`, `trihedral`, `deflection`, `wear`;
//! - [`contour`]: random compensated contours and their block-by-block
//!   comparison with the reference;
//! - [`compensate`]: `host-sim compensate`, a G41/G42 program printed as the
//!   tool-tip program the device runs;
//! - [`check`]: `host-sim check`, every line of a G-code file the device
//!   would refuse, with its line and column;
//! - [`dialect`]: which dialect a program is written in, for `--dialect
//!   auto`;
//! - [`expand`]: macros, subprograms and parameters expanded to plain blocks;
//! - [`program`]: `host-sim run FILE`, a whole program through the
//!   in-process device in virtual time (cycle time, travel, tools,
//!   refusals, the path);
//! - [`plot`]: `host-sim plot FILE`, the program drawn as an SVG picture;
//! - [`tape`]: `host-sim tape encode FILE`, a program punched as a BCK-5
//!   or ISO-7bit tape;
//! - [`report`]: `host-sim run FILE --report OUT.html`, one HTML page of the
//!   run: its facts as tables, the picture, the speed along the path over
//!   time;
//! - [`scenario`]: the built-in scenarios of the main job;
//! - [`spindle`]: the simulated spindle and encoder (speed, ripple, load
//!   dips), and synchronised passes placed in time by its counts.

pub mod board;
pub mod calculators;
pub mod check;
pub mod compare;
pub mod compensate;
pub mod contour;
pub mod device;
pub mod dialect;
pub mod expand;
pub mod lathe;
pub mod link;
pub mod plot;
pub mod program;
pub mod qemu;
pub mod reliable;
pub mod report;
pub mod scenario;
pub mod send;
pub mod soak;
pub mod spindle;
pub mod stream;
pub mod table;
pub mod tape;

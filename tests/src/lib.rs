//! Cross-crate tests live in `tests/`; this library holds what they share
//! about the repository itself.
//!
//! - [`modules`]: the module-level import graph of a crate and its cycles
//!   (`tests/tests/module_cycles.rs`, `cargo run -p tests --bin
//!   module-graph -- <crate>/src`).

pub mod modules;

//! The seeds' other calculators: what a machinist on an old lathe works
//! out by hand from the same books (`docs/calculators.md`). Floating point (`f64`,
//! `libm`) is fine here: nothing of it moves an axis.

pub mod deflection;
pub mod tape;
pub mod thread;
pub mod trihedral;
pub mod wear;

//! The pendant line protocol (`docs/protocol.md`): transport-agnostic, bytes in,
//! reply lines out, bounded buffers.
//!
//! [`Device`] is what a transport owns: it frames received bytes into lines
//! ([`framing`]), checks them and runs them on its [`Session`], and hands every
//! reply line and every accepted motion block to an [`Io`].

#[cfg(feature = "calc")]
mod calc;
mod device;
pub mod framing;
pub mod grbl;
mod io;
pub mod reply;
pub mod request;
mod session;
mod words;

pub use device::Device;
pub use io::{
    ErrorCode, Io, Realtime, Refused, State, StatusRecord, StatusView, Timing, CHORDS_PER_PAUSE,
};
pub use session::{status_line, Config, Pass, Session, NAME, VERSION};

#[cfg(test)]
mod tests;

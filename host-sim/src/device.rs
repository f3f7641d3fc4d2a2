//! The in-process device: the core's protocol handler behind a byte API.

use core_nostd::interleave::LinearBlock;
use core_nostd::protocol::{Device, Io};
use core_nostd::stepdir::DriveTiming;

/// Collects reply bytes and the blocks the device ran.
#[derive(Default)]
struct Collect {
    out: Vec<u8>,
    blocks: Vec<LinearBlock>,
}

impl Io for Collect {
    fn send(&mut self, line: &[u8]) {
        self.out.extend_from_slice(line);
    }
    fn run_block(&mut self, block: &LinearBlock, _: &DriveTiming) {
        self.blocks.push(*block);
    }
}

/// The same protocol handler the firmware runs, in this process.
#[derive(Default)]
pub struct LocalDevice {
    dev: Device,
    blocks: Vec<LinearBlock>,
}

impl LocalDevice {
    /// A device at power-on.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds raw bytes; returns the raw reply bytes they produced.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<u8> {
        let mut io = Collect::default();
        self.dev.receive_bytes(bytes, &mut io);
        self.blocks.extend(io.blocks);
        io.out
    }

    /// Sends one request line (LF appended) and returns its reply lines,
    /// each with its `*HH` but without CRLF.
    pub fn request(&mut self, line: &str) -> Vec<String> {
        let mut bytes = line.as_bytes().to_vec();
        bytes.push(b'\n');
        let out = self.feed(&bytes);
        String::from_utf8_lossy(&out)
            .split_terminator("\r\n")
            .map(str::to_owned)
            .collect()
    }

    /// The blocks run since the last call (the motion the device issued).
    pub fn take_blocks(&mut self) -> Vec<LinearBlock> {
        std::mem::take(&mut self.blocks)
    }

    /// The underlying device (state inspection).
    pub fn device(&self) -> &Device {
        &self.dev
    }
}

//! The in-process device: the core's protocol handler behind a byte API,
//! with a virtual clock: every step event it issues is recorded with its
//! tick.

use core_nostd::interleave::{LinearBlock, StepEvent};
use core_nostd::protocol::{Device, Io};
use core_nostd::stepdir::DriveTiming;

/// One step event as issued: its byte (the `SEQ` layout) and its tick in
/// its run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Issued {
    /// bit0 X steps, bit1 Z steps, bit2 X negative, bit3 Z negative.
    pub bits: u8,
    /// Ticks since its run began.
    pub tick: u64,
    /// The run it belongs to, counted from 0 since power-on.
    pub run: u64,
}

/// Collects reply bytes and the events the device issued.
struct Collect<'a> {
    out: Vec<u8>,
    events: &'a mut Vec<Issued>,
    starts: &'a mut Vec<(usize, LinearBlock)>,
    runs: &'a mut u64,
}

impl Io for Collect<'_> {
    fn send(&mut self, line: &[u8]) {
        self.out.extend_from_slice(line);
    }
    fn step(&mut self, event: StepEvent, tick: u64, _: &DriveTiming) {
        self.events.push(Issued {
            bits: event.bits(),
            tick,
            run: *self.runs,
        });
    }
    fn run_end(&mut self, _: u64) {
        *self.runs += 1;
    }
    fn block_start(&mut self, block: &LinearBlock) {
        self.starts.push((self.events.len(), *block));
    }
}

/// The same protocol handler the firmware runs, in this process.
#[derive(Default)]
pub struct LocalDevice {
    dev: Device,
    events: Vec<Issued>,
    starts: Vec<(usize, LinearBlock)>,
    runs: u64,
    /// Keep the events issued (off: only count them).
    record: bool,
    issued: u64,
}

impl LocalDevice {
    /// A device at power-on; it counts the events it issues.
    pub fn new() -> Self {
        Self::default()
    }

    /// A device at power-on that keeps every event it issues, for
    /// [`LocalDevice::take_events`].
    pub fn recording() -> Self {
        LocalDevice {
            record: true,
            ..Self::default()
        }
    }

    /// Feeds raw bytes; returns the raw reply bytes they produced.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<u8> {
        let before = self.events.len();
        let mut io = Collect {
            out: Vec::new(),
            events: &mut self.events,
            starts: &mut self.starts,
            runs: &mut self.runs,
        };
        self.dev.receive_bytes(bytes, &mut io);
        let out = io.out;
        self.issued += (self.events.len() - before) as u64;
        if !self.record {
            self.events.clear();
            self.starts.clear();
        }
        out
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

    /// The events issued since the last call (kept by a recording device).
    pub fn take_events(&mut self) -> Vec<Issued> {
        self.starts.clear();
        std::mem::take(&mut self.events)
    }

    /// The blocks started since the last [`LocalDevice::take_events`], each
    /// with the index of its first event there.
    pub fn block_starts(&self) -> &[(usize, LinearBlock)] {
        &self.starts
    }

    /// Step events issued since power-on.
    pub fn issued(&self) -> u64 {
        self.issued
    }

    /// Runs ended since power-on.
    pub fn runs(&self) -> u64 {
        self.runs
    }

    /// The underlying device (state inspection).
    pub fn device(&self) -> &Device {
        &self.dev
    }
}

//! The in-process device: the core's protocol handler behind a byte API,
//! with a virtual clock: every step event it issues is recorded with its
//! tick.

use core_nostd::interleave::{LinearBlock, StepEvent};
use core_nostd::protocol::{Device, Io, Realtime};
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

/// The person at the machine, on the other end of the link the device
/// serves: a program stop (`M00`, `M01`) waits on them for cycle start.
pub trait Operator {
    /// Sends reply bytes now.
    fn write(&mut self, bytes: &[u8]);
    /// The next byte from the link, waiting for it; `None` when the link
    /// has ended.
    fn read(&mut self) -> Option<u8>;
}

/// Collects reply bytes and the events the device issued.
struct Collect<'a, 'o> {
    out: Vec<u8>,
    events: &'a mut Vec<Issued>,
    starts: &'a mut Vec<(usize, LinearBlock)>,
    runs: &'a mut u64,
    /// Who presses cycle start; without one it is pressed at once.
    operator: Option<&'o mut (dyn Operator + 'o)>,
    /// The status line of the program stop in progress.
    stop_line: Vec<u8>,
    /// Bytes that came while it waited, for after the request.
    later: Vec<u8>,
}

impl Io for Collect<'_, '_> {
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
    fn stop_status(&mut self, line: &[u8]) {
        self.stop_line = line.to_vec();
    }
    /// As the board: replies so far go out, status bytes are answered with
    /// the stop's line, cycle start (0x81) or a reset (Ctrl-X) ends the
    /// wait; every other byte waits its turn after the request, real-time
    /// ones too (answered then, as the board answers them after its
    /// wait).
    fn program_stop(&mut self, _: u16) {
        let Some(op) = self.operator.as_deref_mut() else {
            return;
        };
        op.write(&std::mem::take(&mut self.out));
        while let Some(b) = op.read() {
            match Realtime::from_byte(b) {
                Some(Realtime::Status) => op.write(&self.stop_line),
                Some(Realtime::Resume | Realtime::Reset) => {
                    self.later.push(b);
                    return;
                }
                _ => self.later.push(b),
            }
        }
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

    /// Feeds raw bytes; returns the raw reply bytes they produced. A
    /// program stop goes on at once, as if cycle start were pressed.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<u8> {
        self.serve(bytes, None)
    }

    /// As [`LocalDevice::feed`], a program stop waiting for `operator` to
    /// press cycle start (the replies before it written to them first).
    pub fn feed_operated(&mut self, bytes: &[u8], operator: &mut dyn Operator) -> Vec<u8> {
        self.serve(bytes, Some(operator))
    }

    fn serve<'o>(
        &mut self,
        bytes: &[u8],
        operator: Option<&'o mut (dyn Operator + 'o)>,
    ) -> Vec<u8> {
        self.with_io(operator, |dev, io| {
            dev.receive_bytes(bytes, io);
            while !io.later.is_empty() {
                let later = std::mem::take(&mut io.later);
                dev.receive_bytes(&later, io);
            }
        })
    }

    /// Runs `f` on the device with an [`Io`] that collects; returns the
    /// reply bytes and counts (or keeps) the events issued.
    fn with_io<'o>(
        &mut self,
        operator: Option<&'o mut (dyn Operator + 'o)>,
        f: impl FnOnce(&mut Device, &mut Collect<'_, 'o>),
    ) -> Vec<u8> {
        let before = self.events.len();
        let mut io = Collect {
            out: Vec::new(),
            events: &mut self.events,
            starts: &mut self.starts,
            runs: &mut self.runs,
            operator,
            stop_line: Vec::new(),
            later: Vec::new(),
        };
        f(&mut self.dev, &mut io);
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

    /// The link has been quiet: on a grbl link what is queued starts
    /// ([`Device::quiet`]); returns the reply bytes (none).
    pub fn quiet(&mut self) -> Vec<u8> {
        if !self.dev.waiting() {
            return Vec::new();
        }
        self.with_io(None, |dev, io| dev.quiet(io))
    }

    /// The switches changed: `active` the inputs active now, filtered
    /// ([`Device::inputs`]); returns the reply bytes (an `!ALARM` line).
    pub fn inputs(&mut self, active: u16) -> Vec<u8> {
        self.with_io(None, |dev, io| dev.inputs(active, io))
    }

    /// Switches the link to the grbl 1.1 protocol (or back); returns the
    /// banner it sends.
    pub fn set_grbl(&mut self, on: bool) -> Vec<u8> {
        self.with_io(None, |dev, io| dev.set_grbl(on, io))
    }

    /// The underlying device (state inspection).
    pub fn device(&self) -> &Device {
        &self.dev
    }
}

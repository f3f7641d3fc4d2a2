//! Cross-crate tests live in `tests/`; this library holds what several of
//! them share.
//!
//! - [`modules`]: the module-level import graph of a crate and its cycles
//!   (`tests/tests/module_cycles.rs`, `cargo run -p tests --bin
//!   module-graph -- <crate>/src`).
//! - [`rs274`]: LinuxCNC's `rs274` as a peer: whether it is here, the
//!   numbers of its canonical calls (`linuxcnc.rs`, `g76.rs`).
//! - [`last_x_z`]: where a program's last move naming X and Z ends (the
//!   tests that stream corpus programs through real senders).
//! - [`board_line`]: a firmware's reply line as the in-process device
//!   writes it (the QEMU tests).
//! - [`compare_events`]: the device's timed step events against the
//!   reference's, event by event; [`TimedPair`]: the in-process device and
//!   the references driven alike by `MOVE`s, compared at each `SYNC`.
//! - [`ask`], [`one`], [`units_word`]: a request over a link or to the
//!   in-process device, and a length as a request's word.

pub mod modules;
pub mod rs274;

/// A board's line as the in-process device writes it: a `!STATUS` line
/// without the board's own ` LAT= LATE=` (which must be there, numbers),
/// its checksum recomputed; every other line as it came, its line end
/// trimmed.
pub fn board_line(line: &str) -> String {
    let line = line.trim_end();
    let Some(body) = line.strip_prefix("!STATUS ") else {
        return line.to_string();
    };
    let body = body.rsplit_once('*').expect("a checksum").0;
    let (common, timing) = body.split_once(" LAT=").expect("LAT= on the board");
    let (lat, late) = timing.split_once(" LATE=").expect("LATE= on the board");
    assert!(
        lat.parse::<u32>().is_ok() && late.parse::<u32>().is_ok(),
        "{line}"
    );
    host_sim::link::with_checksum(&format!("!STATUS {common}"))
}

/// Where a program's last move naming both X and Z ends, as written (the
/// last line whose code, comments left out, has an `X` and a `Z` word):
/// where the carriage stands after a program that ends with such an
/// absolute move and no offset in force.
pub fn last_x_z(program: &str) -> Option<(f64, f64)> {
    let word = |line: &str, letter: char| -> Option<f64> {
        let code = line.split(['(', ';']).next().unwrap_or("");
        code.split_whitespace()
            .find_map(|w| w.strip_prefix(letter).and_then(|v| v.parse().ok()))
    };
    program
        .lines()
        .rev()
        .find_map(|l| Some((word(l, 'X')?, word(l, 'Z')?)))
}

/// A lathe of machine file `text` behind a simulated board that first
/// takes `setup` (pendant requests: its wiring, radius mode), speaking
/// grbl when `grbl`; the link to it, drained. The homing and probing
/// tests' machine.
pub fn lathe_board(
    text: &str,
    setup: &str,
    grbl: bool,
) -> (host_sim::board::Board, host_sim::link::Client) {
    lathe_board_paced(text, setup, grbl, host_sim::board::Pace::Wall(8.0))
}

/// As [`lathe_board`], the axes at `pace`.
pub fn lathe_board_paced(
    text: &str,
    setup: &str,
    grbl: bool,
    pace: host_sim::board::Pace,
) -> (host_sim::board::Board, host_sim::link::Client) {
    use core_nostd::protocol::{Device, Io};
    struct Nowhere;
    impl Io for Nowhere {
        fn send(&mut self, _: &[u8]) {}
    }
    let file = host_sim::lathe::MachineFile::parse(text).expect("the machine file parses");
    let mut device = Device::new();
    device.receive_bytes(setup.as_bytes(), &mut Nowhere);
    if grbl {
        device.set_grbl(true, &mut Nowhere);
    }
    let (path, board) = host_sim::board::serve_pty(device, pace).expect("pty");
    board.set_lathe(file);
    let c = host_sim::link::Client::open(&path, std::time::Duration::from_secs(30)).expect("open");
    (board, c)
}

/// The simulated lathe's carriages where they are (their own positions,
/// the leadscrew's play included), mm, from the panel's `STATE?`.
pub fn carriage(board: &host_sim::board::Board) -> (f64, f64) {
    let state = board.panel_line("STATE?").expect("state").expect("a line");
    let v = |k: &str| -> f64 {
        host_sim::link::words_value(&state, k)
            .and_then(|v| v.parse().ok())
            .expect(&state)
    };
    (v("X"), v("Z"))
}

/// Sends `line` on a grbl link and reads to its `ok` or `error:`, the
/// lines before included (a board's greeting, blank lines aside).
pub fn grbl_say(c: &mut host_sim::link::Client, line: &str) -> Vec<String> {
    c.write_raw(format!("{line}\n").as_bytes()).expect("write");
    let mut got = Vec::new();
    loop {
        let l = c.read_line().expect("line");
        let end = l == "ok" || l.starts_with("error:");
        if !l.is_empty() && !l.starts_with("Grbl 1.1h") {
            got.push(l);
        }
        if end {
            return got;
        }
    }
}

/// Sends `line` on a pendant link and reads its whole reply.
pub fn ask(c: &mut host_sim::link::Client, line: &str) -> host_sim::link::Reply {
    c.write_raw(format!("{line}\n").as_bytes()).expect("write");
    c.read_reply().expect("reply")
}

/// A request to the in-process device answered by one line: its body,
/// the checksum checked.
pub fn one(dev: &mut host_sim::device::LocalDevice, line: &str) -> String {
    let r = dev.request(line);
    assert_eq!(r.len(), 1, "{line}: {r:?}");
    host_sim::link::check_reply_line(&r[0])
        .expect("checksum")
        .to_owned()
}

/// A length in 10⁻⁷ mm as a request's word (`12.5`, `-0.0000001`).
pub fn units_word(units: i64) -> String {
    let sign = if units < 0 { "-" } else { "" };
    let a = units.unsigned_abs();
    format!("{sign}{}.{:07}", a / 10_000_000, a % 10_000_000)
        .trim_end_matches('0')
        .trim_end_matches('.')
        .to_string()
}

/// Event by event: bytes and ticks, ticks strictly increasing within a
/// block.
pub fn compare_events(
    got: &[host_sim::device::Issued],
    expected: &[reference::motion::TimedEvent],
) {
    assert_eq!(got.len(), expected.len(), "number of events");
    for (i, (g, e)) in got.iter().zip(expected).enumerate() {
        assert_eq!(
            (g.bits, g.tick),
            (e.byte, e.tick),
            "event {i}: device {g:?}, reference {e:?}"
        );
    }
    for w in expected.windows(2) {
        if w[0].block == w[1].block && w[0].run == w[1].run {
            assert!(w[1].tick > w[0].tick, "ticks within a block: {w:?}");
        }
    }
}

/// The in-process device (recording its events, `DIAM=0`) and the
/// references driven alike: the impulses (`RefMachine`), the motion in
/// time (`RefMotion`) and the backlash rule (`RefBacklash`, none unless
/// [`TimedPair::with_backlash`]).
pub struct TimedPair {
    /// The device.
    pub dev: host_sim::device::LocalDevice,
    imp: reference::impulse::RefMachine,
    /// The reference of motion in time.
    pub time: reference::motion::RefMotion,
    lash: reference::motion::RefBacklash,
    /// The registers of the program's points.
    pub registers: [i64; 2],
}

impl Default for TimedPair {
    fn default() -> Self {
        Self::new()
    }
}

impl TimedPair {
    /// At rest at the origin, the default limits, prices 0.005 (X radius)
    /// and 0.01 mm, no backlash.
    pub fn new() -> TimedPair {
        use reference::impulse::{RefConfig, RefMachine};
        use reference::motion::{MotionLimits, RefBacklash, RefMotion};
        let mut dev = host_sim::device::LocalDevice::recording();
        assert!(one(&mut dev, "CFG DIAM=0").starts_with("OK"));
        let cfg = RefConfig {
            diam: false,
            ..RefConfig::default()
        };
        TimedPair {
            dev,
            imp: RefMachine::new(cfg),
            time: RefMotion::new(MotionLimits::default(), [0.005, 0.01]),
            lash: RefBacklash::default(),
            registers: [0, 0],
        }
    }

    /// Sets the play (mm, X radius and Z) on both with `BACKLASH`, whose
    /// reply must give the impulses the reference takes up.
    pub fn with_backlash(mut self, backlash: [&str; 2]) -> TimedPair {
        let set = one(
            &mut self.dev,
            &format!("BACKLASH X={} Z={}", backlash[0], backlash[1]),
        );
        self.lash = reference::motion::RefBacklash::new(
            backlash.map(|b| b.parse().expect("a decimal")),
            [0.005, 0.01],
        );
        assert_eq!(
            set,
            format!(
                "OK X={} Z={} NX={} NZ={}",
                backlash[0], backlash[1], self.lash.play[0], self.lash.play[1]
            )
        );
        self
    }

    /// `MOVE` to a point (10⁻⁷ mm) at a feed (mm/min) or rapid; the
    /// reference takes up the play first where the rule says.
    pub fn to(&mut self, x: i64, z: i64, feed: Option<&str>) {
        let (wx, wz) = (units_word(x), units_word(z));
        let f = feed.map(|f| format!(" F={f}")).unwrap_or_default();
        let r = one(&mut self.dev, &format!("MOVE X={wx} Z={wz}{f}"));
        let b = self.imp.move_block(Some(&wx), Some(&wz), false);
        assert!(
            r.starts_with(&format!(
                "OK NX={} NZ={} PX={} PZ={}",
                b.nx, b.nz, b.px, b.pz
            )),
            "{r}"
        );
        let delta = [b.px - self.registers[0], b.pz - self.registers[1]];
        if let Some(steps) = self.lash.before(delta) {
            self.time.push_takeup(steps);
        }
        self.registers = [b.px, b.pz];
        self.time.push(
            reference::motion::Point::from_units(x, z),
            [b.px, b.pz],
            feed.map(|f| f.parse().expect("a feed")),
        );
    }

    /// `SYNC` on both, every event since the last one compared, and the
    /// registers (`POS`) and those of the steps issued (`STATUS`) those of
    /// the program's points; `(EV, T)`.
    pub fn sync(&mut self) -> (u64, u64) {
        let r = one(&mut self.dev, "SYNC");
        let want = self.time.sync();
        assert_eq!(
            r,
            format!(
                "OK EV={} T={} TSEQ={:08X} STARVED=0",
                want.ev, want.t, want.tseq
            )
        );
        compare_events(&self.dev.take_events(), &self.time.take_events());
        for ask in ["POS", "STATUS"] {
            let pos = one(&mut self.dev, ask);
            let reg = |k: &str| -> i64 {
                host_sim::link::words_value(&pos, k)
                    .and_then(|v| v.parse().ok())
                    .expect(k)
            };
            assert_eq!([reg("PX"), reg("PZ")], self.registers, "{pos}");
        }
        (want.ev, want.t)
    }
}

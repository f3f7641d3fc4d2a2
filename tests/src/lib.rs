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
//!   reference's, event by event.
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

//! The handler through its byte interface: every error code, state unchanged
//! after every error, and no input that panics it.

extern crate std;
use super::*;
use proptest::prelude::*;
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

mod backlash;
mod compensation;
mod cycles;
mod homing;
mod inputs;
mod machine;
mod programs;
mod requests;
mod wheel;

#[derive(Default)]
struct Lines {
    out: Vec<String>,
    blocks: usize,
}

impl Io for Lines {
    fn send(&mut self, line: &[u8]) {
        assert!(line.ends_with(b"\r\n"), "terminator");
        let text = std::str::from_utf8(line).expect("replies are ASCII");
        let text = text.strip_suffix("\r\n").unwrap_or(text);
        let (body, sum) = text.rsplit_once('*').expect("every reply has *HH");
        let xor = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(sum, std::format!("{xor:02X}"), "reply checksum of {text:?}");
        self.out.push(body.to_string());
    }
    fn step(&mut self, _: crate::interleave::StepEvent, _: u64, _: &crate::stepdir::DriveTiming) {
        self.blocks += 1;
    }
}

fn ask(dev: &mut Device, request: &[u8]) -> Vec<String> {
    let mut io = Lines::default();
    dev.receive_bytes(request, &mut io);
    io.out
}

/// The whole number of ` KEY=` in a reply line.
fn number(line: &str, key: &str) -> i64 {
    let at = line.find(&std::format!(" {key}=")).expect(key) + key.len() + 2;
    let rest = &line[at..];
    rest[..rest.find(' ').unwrap_or(rest.len())]
        .parse()
        .expect(key)
}

fn ask1(dev: &mut Device, request: &str) -> String {
    let mut r = ask(dev, std::format!("{request}\n").as_bytes());
    assert_eq!(r.len(), 1, "{request:?} -> {r:?}");
    r.remove(0)
}

/// Everything a request could change, as the device reports it.
fn state(dev: &mut Device) -> (String, String, String, String) {
    (
        ask1(dev, "POS"),
        ask1(dev, "CFG"),
        ask1(dev, "DRIVE"),
        ask1(dev, "LIMITS"),
    )
}

fn with_checksum(body: &str) -> String {
    let xor = body.bytes().fold(0u8, |a, b| a ^ b);
    std::format!("{body}*{xor:02X}")
}

/// A device moved away from zero with a non-default configuration.
fn busy_device() -> Device {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG HX=0.0025 TOL=0.02 PASS=ROUGH").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=12.345678 Z=-7.000005").starts_with("OK"));
    dev
}

/// Appends ` ~CCCCCCCC`, the CRC-32 of everything before the `~`.
fn with_crc(body: &str) -> String {
    let mut c = crate::crc32::Crc32::new();
    c.update(body.as_bytes());
    c.push(b' ');
    std::format!("{body} ~{:08X}", c.finish())
}

/// The DATA lines and the final line of each block of a program.
fn run_program(dev: &mut Device, program: &[&str]) -> Vec<Vec<String>> {
    program
        .iter()
        .map(|b| ask(dev, std::format!("{b}\n").as_bytes()))
        .collect()
}

/// A device in the Fanuc dialect that has taken every line of `program`
/// (each answered `OK`), and the replies.
fn fanuc_program(program: &[&str]) -> (Device, Vec<Vec<String>>) {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    let replies = run_program(&mut dev, program);
    for (line, reply) in program.iter().zip(&replies) {
        assert!(reply.last().unwrap().starts_with("OK"), "{line}: {reply:?}");
    }
    (dev, replies)
}

fn data(replies: &[Vec<String>]) -> Vec<String> {
    replies
        .iter()
        .flatten()
        .filter_map(|l| l.strip_prefix("DATA ").map(String::from))
        .collect()
}

/// The machine position of the last block's end, from its `DATA` line.
fn data_end(reply: &[String]) -> String {
    let data = reply.iter().find(|l| l.starts_with("DATA ")).cloned();
    data.unwrap_or_else(|| panic!("no DATA in {reply:?}"))
}

/// A board's view of the device: its replies, what it drives, its waits.
#[derive(Default)]
struct Panel {
    lines: Lines,
    outputs: Vec<crate::outputs::Outputs>,
    dwells: Vec<u64>,
}

impl Io for Panel {
    fn send(&mut self, line: &[u8]) {
        self.lines.send(line);
    }
    fn outputs(&mut self, outputs: &crate::outputs::Outputs) {
        self.outputs.push(*outputs);
    }
    fn dwell(&mut self, us: u64) {
        self.dwells.push(us);
    }
}

/// What a machine's M code and a program stop did, besides the replies.
#[derive(Default)]
struct MPanel {
    lines: Lines,
    outputs: Vec<(u8, bool)>,
    waits: Vec<(u8, bool)>,
    stops: Vec<u16>,
}

impl Io for MPanel {
    fn send(&mut self, line: &[u8]) {
        self.lines.send(line);
    }
    fn user_output(&mut self, n: u8, on: bool) {
        self.outputs.push((n, on));
    }
    fn wait_input(&mut self, n: u8, level: bool) {
        self.waits.push((n, level));
    }
    fn program_stop(&mut self, code: u16) {
        self.stops.push(code);
    }
}

fn panel(dev: &mut Device, line: &str) -> MPanel {
    let mut p = MPanel::default();
    dev.receive_bytes(std::format!("{line}\n").as_bytes(), &mut p);
    p
}

/// The run time `SYNC` reports of `lines`.
fn run_ticks(lines: &[&str]) -> u64 {
    let mut dev = Device::new();
    for l in lines {
        let r = ask(&mut dev, std::format!("{l}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{l}: {r:?}");
    }
    let sync = ask1(&mut dev, "SYNC");
    sync.split(" T=")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

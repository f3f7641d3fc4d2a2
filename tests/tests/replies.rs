//! The device's replies, byte for byte, as recorded in `tests/data/replies/`:
//! every example and corpus program through the pendant protocol (its
//! settings, its lines, then `SYNC`, whose `EV`, `T` and `TSEQ` sum up
//! every step event and its tick), the main job's built-in scenarios, the
//! mixed and calculator sessions, and a grbl sender's session.
//!
//! A change meant to leave the behaviour alone (moving code, typing the
//! requests) leaves every file as it is. A change of a reply on purpose
//! records them again (`REPLIES=record cargo test -p tests --test
//! replies`), and the diff shows what changed.

use host_sim::device::LocalDevice;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Requests and replies as a transcript: `> request`, then each reply
/// line as sent (its CR LF gone; a line that is not text shown escaped).
struct Transcript {
    text: String,
}

impl Transcript {
    fn new() -> Self {
        Transcript {
            text: String::new(),
        }
    }

    fn request(&mut self, req: &[u8]) {
        let _ = writeln!(self.text, "> {}", req.escape_ascii());
    }

    fn replies(&mut self, bytes: &[u8]) {
        for line in bytes.split_inclusive(|&b| b == b'\n') {
            let line = line.strip_suffix(b"\n").unwrap_or(line);
            let line = line.strip_suffix(b"\r").unwrap_or(line);
            match std::str::from_utf8(line) {
                Ok(s) if s.bytes().all(|b| (b' '..=b'~').contains(&b)) => {
                    let _ = writeln!(self.text, "{s}");
                }
                _ => {
                    let _ = writeln!(self.text, "{}", line.escape_ascii());
                }
            }
        }
    }
}

/// Feeds `session` line by line (each with its own terminator) to a
/// device at power-on.
fn pendant(session: &[u8]) -> String {
    let mut dev = LocalDevice::new();
    let mut t = Transcript::new();
    for line in session.split_inclusive(|&b| b == b'\n') {
        t.request(line.strip_suffix(b"\n").unwrap_or(line));
        let out = dev.feed(line);
        t.replies(&out);
    }
    t.text
}

/// A program as `host-sim run` sends it: its dialect chosen from the text,
/// diameters, every line, then `SYNC` and `STATUS`.
fn program(path: &Path) -> String {
    let bytes = std::fs::read(path).expect("program");
    let text = String::from_utf8_lossy(&bytes);
    let (dialect, _) = host_sim::dialect::choose("auto", &text).expect("dialect");
    let options = host_sim::program::Options {
        dialect,
        radius: false,
        optional_stop: false,
    };
    let mut session = Vec::new();
    let lines = match host_sim::program::program_lines(&text, dialect) {
        Ok(lines) => lines.into_iter().map(|(_, l)| l).collect(),
        Err(e) => vec![format!("; not expanded: {e}")],
    };
    for l in host_sim::program::run_settings(options)
        .into_iter()
        .chain(lines)
        .chain(["SYNC".to_string(), "STATUS".to_string()])
    {
        session.extend_from_slice(l.as_bytes());
        session.push(b'\n');
    }
    pendant(&session)
}

/// A grbl sender's session: each line waits for its answer, the link then
/// quiet (what starts the motion queued), as a streaming sender sees it.
fn grbl(lines: &[&[u8]]) -> String {
    let mut dev = LocalDevice::new();
    let mut t = Transcript::new();
    t.replies(&dev.set_grbl(true));
    for l in lines {
        t.request(l);
        let mut bytes = l.to_vec();
        if !matches!(bytes.as_slice(), [b'?' | b'!' | b'~' | 0x18 | 0x80..=0xff]) {
            bytes.push(b'\n');
        }
        let out = dev.feed(&bytes);
        t.replies(&out);
        let out = dev.quiet();
        t.replies(&out);
    }
    t.text
}

/// The grbl session: a sender's connect, settings, a program with its
/// status polls and overrides, errors, a hold and a resume, a reset.
const GRBL_SESSION: &[&[u8]] = &[
    b"$I",
    b"$$",
    b"$G",
    b"$#",
    b"?",
    b"$X",
    b"G21 G18 G90 G94",
    b"G00 X20 Z5",
    b"?",
    b"G01 Z-20 F200",
    b"\x91",
    b"?",
    b"\x90",
    b"G02 X30 Z-25 R5",
    b"G01 X32",
    b"$J=G91 X1 F100",
    b"\x85",
    b"!",
    b"?",
    b"~",
    b"G01 X40 Q3",
    b"G04 P0.5",
    b"M03 S800",
    b"M05",
    b"$100=400",
    b"$100",
    b"$999=1",
    b"G10 L20 P1 X0 Z0",
    b"$#",
    b"G54",
    b"$N",
    b"$C",
    b"G01 X10 F100",
    b"$C",
    b"\x18",
    b"$X",
    b"M30",
    b"?",
];

fn cases() -> Vec<(String, String)> {
    let root = root();
    let mut cases = Vec::new();
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in ["examples", "tests/data"] {
        collect(&root.join(dir), &mut files);
    }
    files.sort();
    for f in files {
        let name = f
            .strip_prefix(&root)
            .expect("under the root")
            .to_string_lossy()
            .replace(['/', '\\'], "__");
        cases.push((name, program(&f)));
    }
    for s in [
        host_sim::scenario::table21(),
        host_sim::scenario::krylenko(),
        host_sim::scenario::krylenko_arcs(),
        host_sim::scenario::random(7, 400),
        host_sim::scenario::random_arcs(7, 40, 40),
    ] {
        let mut session = Vec::new();
        for step in &s.steps {
            session.extend_from_slice(step.request().as_bytes());
            session.extend_from_slice(b"\r\n");
        }
        session.extend_from_slice(b"SYNC\r\n");
        let name = format!(
            "scenario__{}",
            s.name.replace(|c: char| !c.is_ascii_alphanumeric(), "-")
        );
        cases.push((name, pendant(&session)));
    }
    cases.push((
        "session__mixed".into(),
        pendant(&host_sim::scenario::mixed_session()),
    ));
    cases.push((
        "session__calculators".into(),
        pendant(&host_sim::scenario::calculator_session()),
    ));
    cases.push(("session__grbl".into(), grbl(GRBL_SESSION)));
    cases
}

/// The programs under `dir`: `.nc`, `.ngc`, `.gcode`.
fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            collect(&p, out);
        } else if p
            .extension()
            .is_some_and(|x| x == "nc" || x == "ngc" || x == "gcode")
        {
            out.push(p);
        }
    }
}

#[test]
fn every_reply_is_the_one_recorded() {
    let dir = root().join("tests/data/replies");
    let record = std::env::var("REPLIES").is_ok_and(|v| v == "record");
    let cases = cases();
    assert!(cases.len() > 40, "{} cases", cases.len());
    let mut failures = Vec::new();
    for (name, got) in &cases {
        let path = dir.join(format!("{name}.txt"));
        if record {
            std::fs::create_dir_all(&dir).expect("directory");
            std::fs::write(&path, got).expect("write");
            continue;
        }
        let want = std::fs::read_to_string(&path).unwrap_or_default();
        if &want != got {
            let at = want
                .lines()
                .zip(got.lines())
                .position(|(a, b)| a != b)
                .unwrap_or_else(|| want.lines().count().min(got.lines().count()));
            failures.push(format!(
                "{name}: line {}: recorded {:?}, now {:?}",
                at + 1,
                want.lines().nth(at).unwrap_or("(end)"),
                got.lines().nth(at).unwrap_or("(end)")
            ));
        }
    }
    // No recording left without its case.
    if !record {
        let names: Vec<String> = cases.iter().map(|(n, _)| format!("{n}.txt")).collect();
        for e in std::fs::read_dir(&dir).expect("recorded replies").flatten() {
            let n = e.file_name().to_string_lossy().into_owned();
            if !names.contains(&n) {
                failures.push(format!("{n}: recorded, no longer produced"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "replies changed:\n{}",
        failures.join("\n")
    );
}

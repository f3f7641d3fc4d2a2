//! The `host-sim` binary as a user runs it.

use std::io::{Read, Write};
use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_host-sim");

#[test]
fn serve_stdio_answers_requests() {
    let mut child = Command::new(BIN)
        .args(["serve", "--stdio"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"VER\nMOVE X=10 Z=-5\nPOS\nBOGUS\n")
        .unwrap();
    let mut out = String::new();
    child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut out)
        .unwrap();
    assert!(child.wait().unwrap().success());
    let lines: Vec<&str> = out.split_terminator("\r\n").collect();
    assert_eq!(lines.len(), 4, "{out:?}");
    assert!(lines[0].starts_with("OK PROTO=1 NAME=lathe-retrofit VERSION="));
    assert_eq!(
        lines[1],
        "OK NX=1000 NZ=-500 PX=1000 PZ=-500 SEQ=34F89895*2A"
    );
    assert!(lines[2].starts_with("OK PX=1000 PZ=-500 X=10.0000 Z=-5.0000*"));
    assert!(lines[3].starts_with("ERR UNKNOWN "));
}

#[test]
fn main_job_reports_a_result_line() {
    let out = Command::new(BIN)
        .args(["run", "--link", "local", "--blocks", "300", "--seed", "3"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let last = text.lines().last().unwrap();
    // The per-scenario lines add up to the RESULT line's count.
    let per_scenario: u64 = text
        .lines()
        .filter(|l| !l.starts_with("RESULT"))
        .filter_map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            t.windows(4).find_map(|w| match w {
                [n, "blocks", m, "events"] if m.parse::<u64>().is_ok() => n.parse::<u64>().ok(),
                _ => None,
            })
        })
        .sum();
    assert!(per_scenario > 300, "{text}");
    assert!(
        last.starts_with(&format!(
            "RESULT: {per_scenario} blocks compared bit-for-bit, 0 mismatches, min tie distance "
        )),
        "{last}"
    );
}

#[test]
fn bad_command_line_is_refused_clearly() {
    let out = Command::new(BIN)
        .args(["run", "--blocks", "0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--blocks"), "{err}");
    let out = Command::new(BIN)
        .args(["run", "--link", "carrier-pigeon"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

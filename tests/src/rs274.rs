//! LinuxCNC's standalone interpreter `rs274` as a peer: whether it is
//! here, and the numbers of its canonical calls.

use std::process::Command;

/// Whether `rs274` runs here. Where it is missing the comparison named
/// `what` is skipped with a message, except under CI (`CI` set), where a
/// missing `rs274` fails.
pub fn available(what: &str) -> bool {
    let found = Command::new("rs274").arg("-h").output().is_ok();
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs rs274 (apt-get install linuxcnc-uspace)"
        );
        eprintln!("rs274 not found: {what} is skipped");
    }
    found
}

/// The numbers inside a canonical call `NAME(…)`.
pub fn args(line: &str) -> Vec<f64> {
    let inner = line.split_once('(').unwrap().1.trim_end_matches(')');
    inner
        .split(',')
        .map(|a| a.trim().parse().unwrap())
        .collect()
}

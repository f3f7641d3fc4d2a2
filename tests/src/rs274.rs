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

/// Two `rs274` run side by side by the tests of one file were seen to die
/// (SIGBUS, or nothing printed) even each in its own working directory:
/// each test that runs it holds this for its whole length, one at a time.
static RS274: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Holds `rs274` for the caller until the guard is dropped.
pub fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    RS274.lock().unwrap_or_else(|e| e.into_inner())
}

//! `host-sim run FILE --report OUT.html` as a person runs it: the usual
//! text report and exit status, the page beside them with the same cycle
//! time, and an unwritable page named in the error.

use std::path::PathBuf;
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-run-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn run_writes_the_page_beside_its_text_report() {
    let program = scratch("part.nc");
    std::fs::write(
        &program,
        "%\nO0100\nG21 G18 G98\nT0101\nG00 X20. Z5.\nG01 Z-30. F300.\nG76 P010060 Q100 R.05\nG00 X40.\nM30\n%\n",
    )
    .unwrap();
    let page = scratch("part.html");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("run")
        .arg(&program)
        .arg("--report")
        .arg(&page)
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    // A refused line: exit status 1, named on stderr, as without the page.
    assert_eq!(out.status.code(), Some(1), "{stdout}{stderr}");
    assert!(stderr.contains(":7: ERR VALUE G76"), "{stderr}");
    let cycle = stdout
        .lines()
        .find_map(|l| l.strip_prefix("cycle time "))
        .and_then(|l| l.split(' ').next())
        .unwrap_or_else(|| panic!("{stdout}"));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains(&format!("<span id=\"cycle-time\">{cycle}</span>")),
        "{cycle}"
    );
    assert!(html.contains("<td class=\"n\">7</td><td>ERR VALUE G76"));
    assert!(stdout.contains(&format!("report: {}", page.display())));
    // The same text without the page.
    let plain = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("run")
        .arg(&program)
        .output()
        .unwrap();
    let plain_out = String::from_utf8(plain.stdout).unwrap();
    assert_eq!(plain.status.code(), Some(1));
    assert!(stdout.starts_with(&plain_out), "{plain_out}\n---\n{stdout}");

    // A page that cannot be written: an error naming it.
    let nowhere = scratch("no-such-dir").join("part.html");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("run")
        .arg(&program)
        .arg("--report")
        .arg(&nowhere)
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("cannot write the report {}", nowhere.display())),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(program.parent().unwrap());
}

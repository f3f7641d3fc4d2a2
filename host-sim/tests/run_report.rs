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

/// A program with canned cycles: the text report's `cycles:` line names
/// each kind with its count and lines, and the page lists every cycle
/// with its time; the times of a kind add up to the line's.
#[test]
fn run_reports_the_time_of_each_canned_cycle() {
    let program = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/fanuc-cycles.nc");
    // Its own page: the other test removes its directory when done.
    let page =
        std::env::temp_dir().join(format!("host-sim-run-cycles-{}.html", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("run")
        .arg(program)
        .arg("--report")
        .arg(&page)
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("cycles: "))
        .unwrap_or_else(|| panic!("{stdout}"));
    let ms = |t: &str| -> u64 {
        let (m, s) = t.split_once(':').unwrap();
        let (s, f) = s.split_once('.').unwrap();
        (m.parse::<u64>().unwrap() * 60 + s.parse::<u64>().unwrap()) * 1000
            + f.parse::<u64>().unwrap()
    };
    let html = std::fs::read_to_string(&page).unwrap();
    let rows: Vec<(usize, String, u64)> = html
        .lines()
        .filter(|l| l.contains("</td><td>") && l.matches("<td").count() == 4)
        .filter_map(|l| {
            let cells: Vec<&str> = l
                .split("<td")
                .skip(1)
                .map(|c| c.split('>').nth(1).unwrap().split('<').next().unwrap())
                .collect();
            Some((cells[0].parse().ok()?, cells[1].to_string(), ms(cells[3])))
        })
        .collect();
    for (kind, lines) in [
        ("single", "(4, lines 8, 9, 21, 22)"),
        ("roughing", "(2, lines 13, 26)"),
        ("finishing", "(2, lines 18, 31)"),
    ] {
        let at = line
            .find(&format!("{kind} "))
            .unwrap_or_else(|| panic!("{kind}: {line}"));
        let rest = &line[at + kind.len() + 1..];
        let (time, after) = rest.split_once(' ').unwrap();
        assert!(after.starts_with(lines), "{kind}: {line}");
        let mine: Vec<&(usize, String, u64)> = rows.iter().filter(|r| r.1 == kind).collect();
        let n: usize = lines[1..].split(',').next().unwrap().parse().unwrap();
        assert_eq!(mine.len(), n, "{kind}: {rows:?}");
        let sum: u64 = mine.iter().map(|r| r.2).sum();
        // Each row rounded up to the millisecond, as the line's total.
        assert!(
            sum >= ms(time) && sum <= ms(time) + mine.len() as u64,
            "{kind}: {sum} {time}"
        );
    }
    let _ = std::fs::remove_file(&page);
}

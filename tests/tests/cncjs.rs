//! CNCjs (npm `cncjs`, pinned in `tests/senders/cncjs`), the most common open
//! grbl web sender and one nobody here wrote, streams lathe programs to
//! `serve --pty --grbl`: its own server and Grbl controller code, driven
//! headless over socket.io by `tests/senders/cncjs/cncjs_run.js` as its web
//! page drives it, on 127.0.0.1 only.
//!
//! Skipped with a message where Node or the pinned CNCjs is missing (`npm ci`
//! in `tests/senders/cncjs`), except under CI (`CI` set), where that fails.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn sender_dir() -> PathBuf {
    root().join("tests/senders/cncjs")
}

/// Whether Node and the pinned CNCjs are here (CI installs them).
fn cncjs_available() -> bool {
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let installed = sender_dir()
        .join("node_modules/cncjs/package.json")
        .is_file();
    if !(node && installed) {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs Node and CNCjs (npm ci in tests/senders/cncjs)"
        );
        eprintln!(
            "Node or CNCjs not installed (npm ci in tests/senders/cncjs): the CNCjs test skipped"
        );
    }
    node && installed
}

/// A link CNCjs opens: `serve --pty --grbl` (the simulated board, motion
/// in real time), or the paced firmware in QEMU switched to grbl.
struct Link {
    path: String,
    _board: Option<host_sim::board::Board>,
    _qemu: Option<host_sim::qemu::Qemu>,
}

impl Link {
    fn path(&self) -> &str {
        &self.path
    }
}

/// A failed test on the firmware shows what QEMU and the firmware wrote
/// beside the link: the firmware's notes (`step: …`) and QEMU's own
/// messages, the text lines of the log.
impl Drop for Link {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            return;
        }
        if let Some(qemu) = &self._qemu {
            let log = qemu.log();
            let text: Vec<String> = log
                .split(|&b| b == b'\n')
                .filter(|l| !l.is_empty() && l.iter().all(|b| (0x20..0x7f).contains(b)))
                .map(|l| String::from_utf8_lossy(l).into_owned())
                .collect();
            let from = text.len().saturating_sub(40);
            eprintln!(
                "QEMU's log, its last text lines:\n{}",
                text[from..].join("\n")
            );
        }
    }
}

/// `serve --pty --grbl`: a fresh simulated board speaking grbl 1.1 on a
/// new pty, its motion in real time.
fn serve() -> Link {
    serve_at(1.0)
}

/// As [`serve`], the step clock `speed` times the wall clock's.
fn serve_at(speed: f64) -> Link {
    struct Nowhere;
    impl core_nostd::protocol::Io for Nowhere {
        fn send(&mut self, _: &[u8]) {}
    }
    let mut device = core_nostd::protocol::Device::new();
    device.set_grbl(true, &mut Nowhere);
    let (path, board) =
        host_sim::board::serve_pty(device, host_sim::board::Pace::Wall(speed)).expect("pty");
    Link {
        path,
        _board: Some(board),
        _qemu: None,
    }
}

/// The paced firmware in QEMU, its link switched to grbl (`None` where
/// QEMU is missing, outside CI).
fn firmware() -> Option<Link> {
    if !host_sim::qemu::qemu_or_skip() {
        return None;
    }
    let elf = host_sim::qemu::build_firmware("qemu-paced").expect("firmware");
    let mut qemu = host_sim::qemu::Qemu::boot_paced(&elf).expect("boot");
    {
        let mut c = qemu
            .connect(std::time::Duration::from_secs(30))
            .expect("connect");
        c.write_raw(b"GRBL\r\n").expect("switch");
        while !c.read_line().expect("banner").starts_with("Grbl 1.1h") {}
    }
    Some(Link {
        path: qemu.pty().to_string(),
        _board: None,
        _qemu: Some(qemu),
    })
}

/// Streams `program` through CNCjs to `port` with the harness's `options`;
/// what CNCjs saw. One at a time: each runs a CNCjs server, and the
/// machine's two cores are not enough for several in real time.
fn cncjs(port: &str, program: &Path, options: &[&str]) -> Value {
    static ONE: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = ONE.lock().unwrap_or_else(|e| e.into_inner());
    let out = Command::new("node")
        .arg(sender_dir().join("cncjs_run.js"))
        .arg(port)
        .arg(program)
        .args(["--timeout", "300"])
        .args(options)
        .output()
        .expect("node");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

/// A copy of iso-shaft.nc changed by `edit`, for the cases that need a
/// program stop or no program end; removed when dropped.
struct Variant(PathBuf);

impl Variant {
    fn of_iso_shaft(name: &str, edit: impl Fn(&str) -> String) -> Variant {
        let text = std::fs::read_to_string(root().join("examples/iso-shaft.nc")).expect("program");
        let path = std::env::temp_dir().join(format!("cncjs-{}-{name}.nc", std::process::id()));
        std::fs::write(&path, edit(&text)).expect("write the program");
        Variant(path)
    }
}

impl Drop for Variant {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// The lines of `program` that reach the controller: not blank, not a `%`
/// tape mark, not a comment alone.
fn gcode_lines(program: &Path) -> usize {
    std::fs::read_to_string(program)
        .expect("program")
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('%') && !l.starts_with('('))
        .count()
}

/// What a failed assertion shows: the run without its long lists.
fn summary(json: &Value) -> String {
    let mut short = json.clone();
    if let Some(o) = short.as_object_mut() {
        for key in ["rx", "read", "written"] {
            if let Some(list) = o.get(key).and_then(Value::as_array) {
                let tail: Vec<Value> = list.iter().rev().take(12).rev().cloned().collect();
                o.insert(
                    format!("{key} (last 12 of {})", list.len()),
                    Value::from(tail),
                );
                o.remove(key);
            }
        }
    }
    serde_json::to_string_pretty(&short).unwrap_or_default()
}

fn strings(json: &Value, key: &str) -> Vec<String> {
    json[key]
        .as_array()
        .unwrap_or_else(|| panic!("{key} in {}", summary(json)))
        .iter()
        .map(|v| v.as_str().unwrap_or_default().to_string())
        .collect()
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default()
}

fn actions<'a>(json: &'a Value, what: &'a str) -> impl Iterator<Item = &'a Value> + 'a {
    json["actions"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(move |a| a["what"] == what)
}

/// The job ran to its end as CNCjs sees it: every line acknowledged `ok`,
/// no `error:` or alarm, CNCjs ended the job itself (every line answered,
/// the machine Idle), and the tool is at the program's end point X60 Z20
/// (X as a diameter, as the program says).
fn check_finished(json: &Value, program: &Path) {
    let s = summary(json);
    assert_eq!(json["errors"], Value::Array(vec![]), "{s}");
    assert_eq!(json["alarms"], Value::Array(vec![]), "{s}");
    assert!(
        !strings(json, "read")
            .iter()
            .any(|l| l.starts_with("error:")),
        "{s}"
    );
    assert_eq!(json["finished"], true, "{s}");
    assert_eq!(json["timed_out"], false, "{s}");
    assert_eq!(json["not_done"], Value::Array(vec![]), "{s}");
    // CNCjs counts every line of the file, comments and `%` included, plus
    // the dwell it appends to wait for the planner; all were answered.
    let total = json["sender"]["total"].as_u64().expect("total");
    assert_eq!(total as usize, program_lines(program) + 1, "{s}");
    assert_eq!(json["sender"]["received"], total, "{s}");
    assert_eq!(json["sender"]["sent"], total, "{s}");
    // On the link: an `ok` for each G-code line, for the dwell and for `$$`
    // (and for each `$G` CNCjs polls).
    let ok = json["ok"].as_u64().expect("ok") as usize;
    assert!(ok >= gcode_lines(program) + 2, "{ok} oks: {s}");
    assert_eq!(json["state"], "Idle", "{s}");
    assert_eq!(
        strings(json, "states").last().map(String::as_str),
        Some("Idle"),
        "{s}"
    );
    assert_eq!(numbers(&json["mpos"]), [60.0, 0.0, 20.0], "{s}");
}

/// The non-blank lines of `program`, as CNCjs counts them.
fn program_lines(program: &Path) -> usize {
    std::fs::read_to_string(program)
        .expect("program")
        .lines()
        .filter(|l| !l.trim().is_empty())
        .count()
}

/// A corpus program's job ran to its end as CNCjs sees it: no error or
/// alarm, every line of the file sent and answered, CNCjs ended the job
/// itself, `Idle`, and the carriage at `want` (X diameter, Z), to 0.001 mm.
fn ended_at(json: &Value, name: &str, program: &Path, want: (f64, f64)) {
    let s = summary(json);
    assert_eq!(json["errors"], Value::Array(vec![]), "{name}: {s}");
    assert_eq!(json["alarms"], Value::Array(vec![]), "{name}: {s}");
    assert!(
        !strings(json, "read")
            .iter()
            .any(|l| l.starts_with("error:")),
        "{name}: {s}"
    );
    assert_eq!(json["finished"], true, "{name}: {s}");
    assert_eq!(json["timed_out"], false, "{name}: {s}");
    assert_eq!(json["not_done"], Value::Array(vec![]), "{name}: {s}");
    let total = json["sender"]["total"].as_u64().expect("total");
    assert_eq!(total as usize, program_lines(program) + 1, "{name}: {s}");
    assert_eq!(json["sender"]["received"], total, "{name}: {s}");
    assert_eq!(json["state"], "Idle", "{name}: {s}");
    let at = numbers(&json["mpos"]);
    assert!(
        at.len() == 3 && (at[0] - want.0).abs() < 1e-3 && (at[2] - want.1).abs() < 1e-3,
        "{name}: CNCjs sees the carriage at {at:?}, the program ends at {want:?}: {s}"
    );
}

#[test]
fn cncjs_streams_a_lathe_program_to_serve() {
    if !cncjs_available() {
        return;
    }
    let device = serve();
    let program = root().join("examples/iso-shaft.nc");
    // A jog first, as typed into CNCjs (its `gcode` command), then the program.
    let json = cncjs(device.path(), &program, &["--jog", "$J=G91 G21 Z-1 F300"]);
    check_finished(&json, &program);
    let s = summary(&json);
    assert_eq!(actions(&json, "jog").count(), 1, "{s}");
    // CNCjs read the settings it asks for on connecting, with its names.
    let read = strings(&json, "read");
    assert!(
        read.iter()
            .any(|l| l.starts_with("$100=200.000 (X-axis travel resolution")),
        "{s}"
    );
    assert_eq!(
        strings(&json, "workflow"),
        ["idle", "running", "idle"],
        "{s}"
    );
    assert_eq!(numbers(&json["ov"]), [100.0, 100.0, 100.0], "{s}");
}

/// CNCjs streams lathe programs nobody here wrote (two corpus programs,
/// one ending with `M2`, one with no end at all) to `serve`, its clock 20
/// times the wall's (23 and 27 minutes of motion): every line answered
/// `ok`, the job ended by CNCjs itself, `Idle`, and the carriage where the
/// program's last move ends.
#[test]
fn cncjs_streams_corpus_programs_to_serve() {
    if !cncjs_available() {
        return;
    }
    for name in [
        "nhsd-cnc-lathe/turn_two_diameters.nc",
        "liblathe/profile.gcode",
    ] {
        let program = root().join("tests/data").join(name);
        let text = std::fs::read_to_string(&program).expect("program");
        // Both end with an absolute move naming X and Z, no offset in
        // force: the carriage ends there.
        let want = tests::last_x_z(&text).expect("a last move");
        let device = serve_at(20.0);
        let json = cncjs(device.path(), &program, &[]);
        ended_at(&json, name, &program, want);
    }
}

/// Fanuc and Haas programs nobody here wrote (corpus programs that run to
/// their end in the Fanuc dialect, `tests/data/SOURCES.md`), streamed by
/// CNCjs to `serve` after one `$450=1` typed in its console, its clock 40
/// times the wall's: every line answered `ok`, the job ended by CNCjs
/// itself, `Idle`, and the carriage where `host-sim run --dialect fanuc`
/// ends the same program. Where a program stops for the operator (`M00`,
/// and `M01`, which CNCjs pauses at and resumes; a machine's own `M31`, which the
/// controller holds at with a message until Cycle Start), it goes on as the
/// operator says. Without `$450=1` the first Fanuc word is an error, named.
#[test]
fn cncjs_streams_fanuc_programs_to_serve_after_450() {
    if !cncjs_available() {
        return;
    }
    for name in [
        "hass-cnc-programs/Lathe-L8-Ex1.nc",
        "basic-cnc-lathe/t24.gcode",
        "enier290188-cnc/valve.nc",
        "enier290188-cnc/lathe_hp_2.nc",
    ] {
        let program = root().join("tests/data").join(name);
        let text = std::fs::read_to_string(&program).expect("program");
        let options = host_sim::program::Options {
            dialect: core_nostd::gcode::Dialect::Fanuc,
            radius: false,
            optional_stop: false,
        };
        let report = host_sim::program::run(&text, options);
        assert!(report.refused.is_empty(), "{name}: {:?}", report.refused);
        let end = report.path.last().expect("a move").to;
        let want = (end[0] as f64 * 2e-7, end[1] as f64 * 1e-7);
        let device = serve_at(40.0);
        let json = cncjs(
            device.path(),
            &program,
            &["--console", "$450=1", "--operator", "0.3"],
        );
        let s = summary(&json);
        assert_eq!(actions(&json, "console").count(), 1, "{name}: {s}");
        // Each stop for the operator the controller asked for was held and
        // answered with Cycle Start; CNCjs paused at each M00 and M01, and
        // was resumed.
        let own_m = text
            .lines()
            .filter(|l| l.contains("M31") || l.contains("M33"))
            .count();
        let m00 = text
            .lines()
            .filter(|l| l.contains("M00") || l.contains("M01"))
            .count();
        assert_eq!(actions(&json, "cyclestart").count(), own_m, "{name}: {s}");
        // (CNCjs may pause twice at one M00: once when it reads the line
        // ahead, once when Resume sends it.)
        assert!(actions(&json, "gcode:resume").count() >= m00, "{name}: {s}");
        ended_at(&json, name, &program, want);
    }
    // The same Haas program without the setting: ISO refuses its first
    // Fanuc word, and says how to read it.
    let program = root().join("tests/data/hass-cnc-programs/Lathe-L8-Ex1.nc");
    let device = serve_at(40.0);
    let json = cncjs(device.path(), &program, &[]);
    let read = strings(&json, "read");
    let s = summary(&json);
    let first = read.iter().position(|l| l.starts_with("error:"));
    let first = first.unwrap_or_else(|| panic!("no error without $450=1: {s}"));
    // Its first line read, `N5 G18 G40 G54 G80 G99`: CNCjs shows the
    // reason, then the error.
    assert_eq!(
        read.iter()
            .position(|l| l.starts_with("[MSG:"))
            .map(|i| &read[i]),
        Some(&"[MSG:VALUE G99 belongs to the FANUC dialect ($450=1)]".to_string()),
        "{s}"
    );
    assert!(
        read.iter().position(|l| l.starts_with("[MSG:")) < Some(first),
        "{s}"
    );
    assert_eq!(json["finished"], false, "{s}");
}

#[test]
fn cncjs_ends_a_program_without_m30() {
    if !cncjs_available() {
        return;
    }
    // CNCjs ends a job when every line is answered and the machine has been
    // Idle for half a second: the queued moves must run out without M2/M30.
    let program = Variant::of_iso_shaft("no-m30", |text| {
        text.lines()
            .filter(|l| l.trim() != "M30")
            .map(|l| format!("{l}\n"))
            .collect()
    });
    let device = serve();
    let json = cncjs(device.path(), &program.0, &[]);
    check_finished(&json, &program.0);
}

#[test]
fn cncjs_feed_override_clicks_change_ov_without_a_refused_line() {
    if !cncjs_available() {
        return;
    }
    let device = serve();
    let program = root().join("examples/iso-shaft.nc");
    // Two +10 % clicks, then one -10 %: on the wire C2 91, C2 91, C2 92.
    let json = cncjs(
        device.path(),
        &program,
        &["--override", "0.3s:+10,+10", "--override", "1.5s:-10"],
    );
    check_finished(&json, &program);
    let s = summary(&json);
    let clicks: Vec<f64> = actions(&json, "feedOverride")
        .filter_map(|a| a["t"].as_f64())
        .collect();
    assert_eq!(clicks.len(), 3, "{s}");
    // CNCjs shows each new value with its next status polls (every 250 ms),
    // as grbl reports an override at once: 120 % after the two clicks, then
    // 110 %.
    // The first time a value is shown after `t0`.
    let shown = |ov: [f64; 3], t0: f64| -> Option<f64> {
        json["ov_seen"]
            .as_array()?
            .iter()
            .filter(|o| o["t"].as_f64().is_some_and(|t| t > t0))
            .find(|o| numbers(&o["ov"]) == ov)
            .and_then(|o| o["t"].as_f64())
    };
    assert!(
        shown([100.0, 100.0, 100.0], 0.0).is_some_and(|t| t < clicks[0]),
        "{s}"
    );
    let up = shown([120.0, 100.0, 100.0], clicks[1]).unwrap_or(f64::INFINITY);
    let down = shown([110.0, 100.0, 100.0], clicks[2]).unwrap_or(f64::INFINITY);
    // Within a few of CNCjs' polls (more when the machine is loaded).
    assert!(up < clicks[1] + 2.0, "120 % at {up}: {s}");
    assert!(down < clicks[2] + 2.0, "110 % at {down}: {s}");
    assert_eq!(numbers(&json["ov"]), [110.0, 100.0, 100.0], "{s}");
    assert_eq!(
        strings(&json, "workflow"),
        ["idle", "running", "idle"],
        "{s}"
    );
}

#[test]
fn cncjs_feed_hold_and_cycle_start_in_the_middle_of_the_job() {
    if !cncjs_available() {
        return;
    }
    let device = serve();
    let program = root().join("examples/iso-shaft.nc");
    // Feed Hold two seconds into the job, Cycle Start a second after CNCjs
    // shows the machine held.
    let json = cncjs(
        device.path(),
        &program,
        &["--feedhold", "2s", "--hold-for", "1"],
    );
    check_finished(&json, &program);
    let s = summary(&json);
    let cycle_start: Vec<&Value> = actions(&json, "cyclestart").collect();
    assert_eq!(cycle_start.len(), 1, "{s}");
    assert_eq!(cycle_start[0]["hold_seen"], true, "{s}");
    assert_eq!(cycle_start[0]["state"], "Hold:0", "{s}");
    // Moving, held, moving again, then done.
    let states = strings(&json, "states");
    let run = states.iter().position(|x| x == "Run");
    let held = states.iter().position(|x| x == "Hold:0");
    let again = held.and_then(|h| states[h..].iter().position(|x| x == "Run"));
    assert!(run < held && run.is_some() && again.is_some(), "{s}");
    // The hold was the machine's, not the job's: CNCjs kept it running.
    assert_eq!(
        strings(&json, "workflow"),
        ["idle", "running", "idle"],
        "{s}"
    );
}

#[test]
fn cncjs_resumes_a_program_stopped_at_m0() {
    if !cncjs_available() {
        return;
    }
    // A stop to measure the roughed diameters before the finishing pass.
    let program = Variant::of_iso_shaft("m0", |text| {
        text.replace(
            "(FINISHING CONTOUR",
            "M0 (MEASURE THE ROUGHED DIAMETERS)\n(FINISHING CONTOUR",
        )
    });
    let device = serve();
    // CNCjs pauses the job at the M0 line; once it shows the machine held
    // there (Hold:0) the operator presses Resume, and CNCjs sends `~`.
    let json = cncjs(device.path(), &program.0, &["--resume-after", "1"]);
    check_finished(&json, &program.0);
    let s = summary(&json);
    let pauses = json["pauses"].as_array().expect("pauses");
    assert!(!pauses.is_empty(), "{s}");
    assert!(pauses.iter().all(|p| p["data"] == "M0"), "{s}");
    // CNCjs may pause twice on one M0 (read ahead, then sent), and is
    // resumed each time; at the M0 itself the machine showed Hold:0.
    assert_eq!(actions(&json, "gcode:resume").count(), pauses.len(), "{s}");
    assert!(
        actions(&json, "gcode:resume").any(|a| a["state"] == "Hold:0"),
        "{s}"
    );
    assert!(
        strings(&json, "states").iter().any(|x| x == "Hold:0"),
        "{s}"
    );
}

/// The paced firmware in QEMU: CNCjs streams the program with a stop to
/// measure (`M0`) and without `M30`, with a feed hold in the middle and
/// override clicks; every line answered, the job ended at X60 Z20.
#[test]
fn cncjs_streams_to_the_firmware_with_a_stop_a_hold_and_overrides() {
    if !cncjs_available() {
        return;
    }
    let Some(link) = firmware() else {
        return;
    };
    let program = Variant::of_iso_shaft("firmware", |text| {
        text.replace(
            "(FINISHING CONTOUR",
            "M0 (MEASURE THE ROUGHED DIAMETERS)\n(FINISHING CONTOUR",
        )
        .lines()
        .filter(|l| l.trim() != "M30")
        .map(|l| format!("{l}\n"))
        .collect()
    });
    let json = cncjs(
        link.path(),
        &program.0,
        &[
            "--resume-after",
            "1",
            "--feedhold",
            "3s",
            "--hold-for",
            "1",
            "--override",
            "1s:+10,+10",
        ],
    );
    check_finished(&json, &program.0);
    let s = summary(&json);
    let states = strings(&json, "states");
    let held = states.iter().position(|x| x == "Hold:0");
    let run_after = held.and_then(|h| states[h..].iter().position(|x| x == "Run"));
    assert!(held.is_some() && run_after.is_some(), "{s}");
    assert!(
        json["ov_seen"]
            .as_array()
            .is_some_and(|a| a.iter().any(|o| numbers(&o["ov"]) == [120.0, 100.0, 100.0])),
        "{s}"
    );
}

/// A tool setter's touch-off streamed by CNCjs to `serve` with a lathe
/// whose setter trips at machine Z −50: `$6=0` wires the probe, a fast and
/// a slow `G38.2` onto it, `G10 L20` makes Z0 there, a `G38.3` touches it
/// again at Z0. CNCjs reads a `[PRB:…:1]` at Z −50 for each of the three,
/// no error or alarm, and the carriage ends at Z20 in the work system set
/// (machine Z −30).
#[test]
fn cncjs_streams_a_tool_setter_touch_off() {
    if !cncjs_available() {
        return;
    }
    let device = serve_at(20.0);
    let lathe = "[z]\ntravel = [-400.0, 5.0]\nbacklash = 0.15\n\
                 [[z.switch]]\ninput = \"PROBE\"\nside = \"-\"\nat = -50.0\n";
    let file = host_sim::lathe::MachineFile::parse(lathe).expect("the lathe");
    device._board.as_ref().expect("a board").set_lathe(file);
    let program = std::env::temp_dir().join(format!("cncjs-setter-{}.nc", std::process::id()));
    std::fs::write(
        &program,
        "(tool setter touch-off)\n$6=0\nG21 G18 G90 G94\nG0 Z0\nG38.2 Z-60 F300\nG0 Z-45\n\
         G38.2 Z-60 F50\nG10 L20 P1 Z0\nG0 Z10\nG38.3 Z-3 F100\nG0 Z20\nM2\n",
    )
    .expect("write the program");
    let json = cncjs(device.path(), &program, &[]);
    ended_at(&json, "tool setter", &program, (0.0, -30.0));
    let probes: Vec<String> = strings(&json, "read")
        .into_iter()
        .filter(|l| l.starts_with("[PRB:"))
        .collect();
    assert_eq!(
        probes,
        ["[PRB:0.0000,0.0000,-50.0000:1]"; 3],
        "{}",
        summary(&json)
    );
    let _ = std::fs::remove_file(&program);
}

//! The `host-sim` binary as a user runs it.

use std::io::{Read, Write};
use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_host-sim");

/// `serve --dialect fanuc`: the board reads Fanuc from power-on, as one
/// that kept `OPT DIALECT=FANUC` (grbl `$450=1`) from before; a dialect it
/// has not is refused by name.
#[test]
fn serve_reads_the_dialect_it_is_given() {
    let run = |args: &[&str], input: &[u8]| {
        let mut child = Command::new(BIN)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        child.stdin.take().unwrap().write_all(input).unwrap();
        let out = child.wait_with_output().unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (ok, out, _) = run(
        &["serve", "--stdio", "--instant", "--dialect", "fanuc"],
        b"OPT\nG00 U4. W-2.\nPOS\n",
    );
    assert!(ok, "{out}");
    assert!(
        out.starts_with("OK BDEL=0 DIALECT=FANUC OPTSTOP=0*"),
        "{out}"
    );
    assert!(
        out.contains("\r\nOK PX=400 PZ=-200 X=4.0000 Z=-2.0000*"),
        "{out}"
    );
    let (ok, out, _) = run(&["serve", "--stdio", "--instant"], b"OPT\nG00 U4.\n");
    assert!(ok, "{out}");
    assert!(out.starts_with("OK BDEL=0 DIALECT=ISO OPTSTOP=0*"), "{out}");
    assert!(
        out.contains("ERR VALUE U belongs to the FANUC dialect"),
        "{out}"
    );
    let (ok, _, err) = run(&["serve", "--stdio", "--dialect", "haas"], b"");
    assert!(!ok);
    assert!(err.contains("invalid value 'haas' for '--dialect"), "{err}");
}

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

/// A machine file with a mistake is refused before anything is served,
/// naming the file and the field.
#[test]
fn serve_refuses_a_bad_machine_file_by_name() {
    let path = std::env::temp_dir().join(format!("lathe-bad-{}.toml", std::process::id()));
    std::fs::write(
        &path,
        "[z]\nbacklash = 0.1\n[[z.switch]]\ninput = \"X+\"\nat = 3\n",
    )
    .unwrap();
    let out = Command::new(BIN)
        .args(["serve", "--stdio", "--machine"])
        .arg(&path)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&path);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("lathe-bad-") && err.contains("z.switch input \"X+\": Z-, Z+ or PROBE"),
        "{err}"
    );
}

#[test]
fn compensate_prints_the_tool_tip_program_or_refuses_it() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/krylenko-fig12.nc");
    let out = Command::new(BIN)
        .args(["compensate", example, "--rn", "0.4", "--tip", "3"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("N20 G01 X27.5314 Z0.0000 ; point 2\n"),
        "{text}"
    );
    assert!(
        text.contains("N70 G01 X114.0000 Z-66.2343 ; point 7\n"),
        "{text}"
    );
    assert!(!text.contains("G42"), "{text}");

    // A bad program: nothing on stdout, the line and reason on stderr.
    let dir = std::env::temp_dir().join(format!("host-sim-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.nc");
    std::fs::write(
        &bad,
        "G00 X20 Z2\nG42 G01 Z0 F100\nX40\nG02 X41 Z-0.5 R0.36\nZ-10\n",
    )
    .unwrap();
    let out = Command::new(BIN)
        .args(["compensate", bad.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("line 4: ERR GEOMETRY this block: concave arc radius"),
        "{err}"
    );

    // Bad options are refused by the command line.
    let out = Command::new(BIN)
        .args(["compensate", example, "--tip", "12"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = Command::new(BIN)
        .args(["compensate", dir.join("missing.nc").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn check_lists_what_the_device_refuses_in_the_programs_dialect() {
    let dir = std::env::temp_dir().join(format!("host-sim-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let part = dir.join("part.nc");
    std::fs::write(
        &part,
        "%\nO1000\nG21 G18 G99\nT0101\nG50 S2500\nG96 S180 M03\nG00 X30. Z2.\n\
         G01 Z-40. F.2\nG19 G03 U2. W-1. R5.\nU2. W-1.\nG76 P010060 Q100 R.05\nM30\n%\n",
    )
    .unwrap();
    let run = |args: &[&str]| {
        let out = Command::new(BIN).args(args).output().unwrap();
        (out.status.code(), String::from_utf8(out.stdout).unwrap())
    };
    let p = part.to_str().unwrap();
    let (code, text) = run(&["check", p]);
    assert_eq!(code, Some(1));
    assert_eq!(
        text,
        format!(
            "{p}: dialect: FANUC (line 3 is one of its words)\n\
             {p}:9:1: in G19 (YZ): a lathe turns arcs and compensates in G18 (ZX)\n\
             {p}:11:1: G76 canned cycles not supported\n\
             {p}: 2 lines the device would refuse\n"
        )
    );
    // Read as ISO, the Fanuc words are named where they stand.
    let (code, text) = run(&["check", "--dialect", "iso", p]);
    assert_eq!(code, Some(1));
    assert!(
        text.contains(&format!("{p}:10:1: U belongs to the FANUC dialect")),
        "{text}"
    );
    let (code, text) = run(&["check", "--dialect", "haas", p]);
    assert_eq!((code, text.as_str()), (Some(2), ""));
    // A DNC file: DC2 before the first % and DC4 after the last are the
    // tape's, named as warnings; a line after the closing % is not run.
    std::fs::write(
        &part,
        "\u{12}%\nO1000\nG21 G18 G99\nG00 X30. Z2.\nM30\n%\u{14}\nG00 X999.\n",
    )
    .unwrap();
    let (code, text) = run(&["check", p]);
    assert_eq!(code, Some(0));
    assert_eq!(
        text,
        format!(
            "{p}: dialect: FANUC (line 3 is one of its words)\n\
             {p}:1:1: warning: the tape's leader before % is not read: DC2\n\
             {p}:6:1: warning: the tape's trailer after % is not read: DC4\n\
             {p}:7:1: warning: the program ends at its closing %: line 7 after it is not read\n\
             {p}: every line is one the device reads\n"
        )
    );
    let out = Command::new(BIN).args(["run", p]).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!(
            "{p}:1: note: the tape's leader before % is not read: DC2"
        )),
        "{err}"
    );
    std::fs::write(&part, "G21 G99\nT0101\nG95\n").unwrap();
    let out = Command::new(BIN).args(["check", p]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("the program mixes dialects: line 1 is Fanuc's, line 3 ISO's"),
        "{out:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn run_loads_a_tool_file_and_presses_cycle_start_at_a_stop() {
    let dir = std::env::temp_dir().join(format!("host-sim-tools-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (part, tools) = (dir.join("part.nc"), dir.join("tools.txt"));
    std::fs::write(
        &part,
        "%\nO1000\nG21 G18 G98\nT0101\nG00 X20. Z2.\nM00\nG01 Z-5. F100.\nG28 U0 W0\nM30\n%\n",
    )
    .unwrap();
    std::fs::write(
        &tools,
        "# register 1: the turning tool\nTOOL N=1 X=4 Z=-1.5 R=0.4 T=3\nWORK G=54 Z=-100\n",
    )
    .unwrap();
    let (p, t) = (part.to_str().unwrap(), tools.to_str().unwrap());
    let out = Command::new(BIN)
        .args(["run", p, "--tools", t, "--trace"])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    // Machine coordinates: X 20 + 4 (diameters), Z 2 - 100 - 1.5.
    assert_eq!(
        stdout,
        "G00 X24.0000 Z-99.5000\nG01 X24.0000 Z-106.5000\nG00 X0.0000 Z0.0000\n"
    );
    assert!(
        stderr.contains(&format!("{p}:6: M00 program stop: cycle start pressed")),
        "{stderr}"
    );
    std::fs::write(&tools, "TOOL N=1 X=4\n\nTOOL N=40 X=1\n").unwrap();
    let out = Command::new(BIN)
        .args(["run", p, "--tools", t])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("{t}:3: TOOL N=40 X=1: ERR VALUE N")),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn run_reports_a_program_and_traces_its_path() {
    for fig in ["12", "17", "22"] {
        let example = format!(
            "{}/../examples/krylenko-fig{fig}.nc",
            env!("CARGO_MANIFEST_DIR")
        );
        let out = Command::new(BIN).args(["run", &example]).output().unwrap();
        let text = String::from_utf8(out.stdout).unwrap();
        assert_eq!(out.status.code(), Some(0), "{text}");
        assert!(text.contains(" 0 refused\n"), "{text}");
        assert!(text.contains("\ncycle time "), "{text}");
        let tool = if fig == "17" { "T0202" } else { "T0101" };
        assert!(text.contains(&format!("tools: {tool} (line 6)")), "{text}");
    }
    // The trace: one block per line on stdout, the report on stderr.
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/krylenko-fig12.nc");
    let out = Command::new(BIN)
        .args(["run", example, "--trace"])
        .output()
        .unwrap();
    let trace = String::from_utf8(out.stdout).unwrap();
    assert!(
        trace.starts_with("G00 X30.0000 Z10.0000\nG00 X20.0000 Z2.0000\n"),
        "{trace}"
    );
    assert!(trace.contains("\nG01 X27.5314 Z0.0000\n"), "{trace}");
    assert!(trace.lines().all(|l| l.starts_with("G0")), "{trace}");
    // Options that need a program are refused without one.
    let out = Command::new(BIN).args(["run", "--trace"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// `run --machine`: the example machine (Z+ at machine Z 4) stops
/// fanuc-cycles.nc at its last rapid (line 32, `G00 X100. Z50.`) without a
/// work offset; with one the program stays within the switches, and with
/// the machine's play set as `BACKLASH` the carriages end on the
/// registers.
#[test]
fn run_on_a_machine_stops_at_a_switch_and_shows_the_play() {
    let dir = env!("CARGO_MANIFEST_DIR");
    let program = format!("{dir}/../examples/fanuc-cycles.nc");
    let machine = format!("{dir}/../examples/machine.toml");
    let run = |setup: Option<&str>| {
        let mut args = vec![
            "run".to_string(),
            program.clone(),
            "--machine".into(),
            machine.clone(),
        ];
        let tmp;
        if let Some(s) = setup {
            tmp = std::env::temp_dir().join(format!("machine-setup-{}.txt", s.len()));
            std::fs::write(&tmp, s).unwrap();
            args.extend(["--tools".to_string(), tmp.display().to_string()]);
        }
        let out = Command::new(BIN).args(&args).output().unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (code, out, err) = run(None);
    assert_eq!(code, Some(6), "{out}{err}");
    assert!(
        err.contains("fanuc-cycles.nc:32: limit Z+ tripped, the carriages at X18.0250 Z4.0000"),
        "{err}"
    );
    assert!(err.contains("; the board's alarm 1; "), "{err}");
    assert!(
        out.contains("fanuc-cycles.nc: 33 lines sent before it stopped, 0 refused"),
        "{out}"
    );
    assert!(
        err.contains("the program stopped there, 1 line not sent"),
        "{err}"
    );
    let (code, out, err) = run(Some("WORK G=54 Z=-100\n"));
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(
        out.contains("carriages went X -0.5000 to 49.9200, Z -135.0000 to 0.0000"),
        "{out}"
    );
    assert!(
        out.contains("carriages ended at X49.9200 Z-50.1500, the registers at X50.0000 Z-50.0000 (off by X-0.0800 Z-0.1500"),
        "{out}"
    );
    let (code, out, err) = run(Some("WORK G=54 Z=-100\nBACKLASH X=0.08 Z=0.15\n"));
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(
        out.contains(
            "carriages ended at X50.0000 Z-50.0000, the registers at X50.0000 Z-50.0000\n"
        ),
        "{out}"
    );
    // The program on a machine of `text` (a file named `name`): the exit
    // status and stderr.
    let on = |name: &str, text: &str| {
        let file = std::env::temp_dir().join(name);
        std::fs::write(&file, text).unwrap();
        let out = Command::new(BIN)
            .args(["run", &program, "--machine", &file.display().to_string()])
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    // A spindle slower than the program asks: warned of, by its line.
    let (_, err) = on("machine-slow-spindle.toml", "[spindle]\nmax_rpm = 500.0\n");
    assert!(
        err.contains("fanuc-cycles.nc:5: warning: S800 is above the spindle's top speed: it turns at 500 rpm"),
        "{err}"
    );
    // A machine file with a mistake is named, and nothing runs.
    let (code, err) = on("machine-bad.toml", "[z.drive]\npitch = 5.0\n");
    assert_ne!(code, Some(0));
    assert!(
        err.contains("z.drive: `pitch` and `steps_per_rev` go together"),
        "{err}"
    );
}

#[test]
fn run_expands_subprograms_and_names_what_it_cannot_expand() {
    let dir = std::env::temp_dir().join(format!("host-sim-expand-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let part = dir.join("part.nc");
    std::fs::write(
        &part,
        "%\nO1000\nG21 G18 G98\nG00 X40. Z2.\nM98 P2000 L3\nM30\nO2000\nG00 W-5.\nM99\n%\n",
    )
    .unwrap();
    let p = part.to_str().unwrap();
    let out = Command::new(BIN)
        .args(["run", p, "--trace"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "G00 X40.0000 Z2.0000\nG00 X40.0000 Z-3.0000\nG00 X40.0000 Z-8.0000\nG00 X40.0000 Z-13.0000\n"
    );
    std::fs::write(&part, "G21 G18 G98\nG00 X40. Z2.\nM98 P3000\nM30\n").unwrap();
    let out = Command::new(BIN).args(["run", p]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains(&format!("{p}:3:")), "{stderr}");
    assert!(stderr.contains("not defined"), "{stderr}");
    assert!(out.stdout.is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `send` against the in-process device on a pty, as a person runs it.
fn send(args: &[&str], program: &str) -> (Option<i32>, String, String) {
    let device = host_sim::link::PtyDevice::start().unwrap();
    let dir = std::env::temp_dir().join(format!("send-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let file = dir.join(format!("p{n}.nc"));
    std::fs::write(&file, program).unwrap();
    let out = Command::new(BIN)
        .args(["send", file.to_str().unwrap(), "--port", device.path()])
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn send_streams_a_program_and_says_where_it_ended() {
    let program = "G21 G90 G94\nG00 X20 Z2\nG01 Z-30 F300\nG00 X25\nM30\n";
    let (code, out, err) = send(&[], program);
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(out.contains("5 lines answered"), "{out}");
    // X25 on the diameter at 0.005 mm (radius), Z-30 at 0.01 mm.
    assert!(
        out.contains("board PX=2500 PZ=-3000, program PX=2500 PZ=-3000"),
        "{out}"
    );
    let (code, out, _) = send(&["--dry-run"], program);
    assert_eq!(code, Some(0));
    assert!(out.contains("dry run: the board accepts every line; nothing sent"));
}

#[test]
fn send_names_a_line_the_board_would_refuse_and_sends_nothing() {
    let program = "G21 G90 G94\nG01 X20 Z-5 F100\nG01 X20 Q7\nM30\n";
    let (code, out, err) = send(&[], program);
    assert_eq!(code, Some(1), "{out}{err}");
    assert!(err.contains(".nc:3: ERR "), "{err}");
    assert!(out.contains("nothing sent"), "{out}");
}

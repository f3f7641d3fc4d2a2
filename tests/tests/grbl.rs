//! The grbl 1.1 protocol: the controller as grbl senders see it, and a real
//! sender (grbl-streamer, from PyPI) streaming a lathe program by character
//! counting to `serve --grbl` and to the firmware in QEMU.

use host_sim::device::LocalDevice;
use host_sim::link::PtyDevice;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

fn text(dev: &mut LocalDevice, bytes: &[u8]) -> String {
    String::from_utf8_lossy(&dev.feed(bytes)).into_owned()
}

fn grbl_device() -> LocalDevice {
    let mut dev = LocalDevice::new();
    let banner = String::from_utf8_lossy(&dev.set_grbl(true)).into_owned();
    assert_eq!(banner, "\r\nGrbl 1.1h ['$' for help]\r\n");
    dev
}

#[test]
fn a_sender_reads_what_it_expects_of_grbl() {
    let mut dev = grbl_device();
    let info = text(&mut dev, b"$I\n");
    assert!(info.contains("[VER:1.1h."), "{info}");
    assert!(info.contains("[OPT:VNM,63,128]"), "{info}");
    assert!(info.contains("[NEWOPT:LATHE]"), "{info}");
    assert!(info.ends_with("ok\r\n"));
    let settings = text(&mut dev, b"$$\n");
    // Steps per mm are one over the impulse price: 0.005 mm on X (radius),
    // 0.01 mm on Z; lathe mode as grblHAL's $32=2.
    for want in [
        "$100=200.000\r\n",
        "$102=100.000\r\n",
        "$32=2\r\n",
        "$110=1500.0000\r\n",
    ] {
        assert!(settings.contains(want), "{want}: {settings}");
    }
    assert_eq!(text(&mut dev, b"$110=2000\n"), "ok\r\n");
    assert!(text(&mut dev, b"$$\n").contains("$110=2000.0000\r\n"));
    // A setting this board has nothing to act on is named and changes
    // nothing.
    let bad = text(&mut dev, b"$3=1\n");
    assert!(
        bad.starts_with("[MSG:$3: ") && bad.ends_with("error:3\r\n"),
        "{bad}"
    );
    assert!(text(&mut dev, b"$$\n").contains("$3=0\r\n"));
    let modes = text(&mut dev, b"$G\n");
    assert!(
        modes.starts_with("[GC:G0 G54 G7 G18 G21 G90 G94 G97 M5 M9"),
        "{modes}"
    );
    let offsets = text(&mut dev, b"$#\n");
    assert!(offsets.contains("[G54:0.0000,0.0000,0.0000]"), "{offsets}");
    assert!(offsets.contains("[PRB:"), "{offsets}");
    // No homing switches on these lathes: grbl's "homing not enabled".
    assert!(text(&mut dev, b"$H\n").ends_with("error:5\r\n"));
}

#[test]
fn g_code_lines_answer_ok_or_error_with_the_reason() {
    let mut dev = grbl_device();
    assert_eq!(text(&mut dev, b"G21 G90 G94\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"G01 X20 Z-5 F200\n"), "ok\r\n");
    let refused = text(&mut dev, b"G01 X20 Q7\n");
    assert!(
        refused.starts_with("[MSG:") && refused.contains('Q') && refused.ends_with("error:1\r\n"),
        "{refused}"
    );
    // A feed never set: grbl's error 22.
    let mut fresh = grbl_device();
    assert!(text(&mut fresh, b"G01 X5\n").ends_with("error:22\r\n"));
    // The refused line moved nothing: the status shows the programmed point
    // once the queue has run (M30 ends the program).
    assert_eq!(text(&mut dev, b"M30\n"), "ok\r\n");
    let status = text(&mut dev, b"?");
    assert!(
        status.starts_with("<Idle|MPos:20.0000,0.0000,-5.0000|FS:"),
        "{status}"
    );
    assert!(status.contains("|Ov:100,100,100|D:1>"), "{status}");
}

#[test]
fn real_time_characters_act_inside_a_line_and_reset_gives_the_banner() {
    let mut dev = grbl_device();
    // `?` in the middle of a line is answered at once; the line is intact.
    let out = text(&mut dev, b"G21 G9?0\n");
    assert!(out.starts_with("<Idle|"), "{out}");
    assert!(out.ends_with("ok\r\n"), "{out}");
    let reset = text(&mut dev, &[0x18]);
    assert!(reset.contains("Grbl 1.1h ['$' for help]"), "{reset}");
    // Feed override: 0x91 is +10 %, shown in the report.
    let _ = text(&mut dev, &[0x91, 0x91]);
    assert!(text(&mut dev, b"?").contains("|Ov:120,100,100|"));
    // The spindle stop and coolant toggles are not implemented: said, not
    // ignored.
    assert!(text(&mut dev, &[0x9E]).starts_with("[MSG:"));
}

#[test]
fn a_jog_moves_in_work_coordinates_and_pendant_requests_still_work() {
    let mut dev = grbl_device();
    assert_eq!(text(&mut dev, b"G10 L2 P1 X0 Z-100\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"$J=G90 G21 X10 Z5 F500\n"), "ok\r\n");
    assert!(text(&mut dev, b"$J=G91 X1\n").ends_with("error:22\r\n"));
    // Back to the pendant protocol: its requests, CRC words included.
    assert_eq!(text(&mut dev, b"$PENDANT\n"), "ok\r\n");
    let sync = text(&mut dev, b"SYNC\r\n");
    assert!(sync.starts_with("OK EV="), "{sync}");
    let pos = text(&mut dev, b"POS\r\n");
    // X10 on the diameter, Z5 in G54 whose zero is at Z-100.
    assert!(pos.starts_with("OK PX=1000 PZ=-9500 "), "{pos}");
    // `GRBL` switches again, with the banner.
    let again = text(&mut dev, b"GRBL\r\n");
    // The request's CRLF is one terminator: no empty grbl line after it.
    assert!(
        again.starts_with("OK GRBL=1*") && again.ends_with("Grbl 1.1h ['$' for help]\r\n"),
        "{again}"
    );
}

/// The run time `SYNC` reports of a long feed move, with `override_bytes`
/// sent first.
fn feed_time(override_bytes: &[u8]) -> f64 {
    run_time(override_bytes, b"G21 G90 G94 G01 Z-100 F100\n")
}

/// The run time of `line` after `override_bytes`.
fn run_time(override_bytes: &[u8], line: &[u8]) -> f64 {
    let mut dev = grbl_device();
    let _ = text(&mut dev, override_bytes);
    assert_eq!(text(&mut dev, line), "ok\r\n");
    assert_eq!(text(&mut dev, b"$PENDANT\n"), "ok\r\n");
    let sync = text(&mut dev, b"SYNC\r\n");
    let ticks: f64 = sync
        .split(" T=")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .expect(&sync);
    ticks / 1e6
}

#[test]
fn the_feed_override_scales_the_feed_of_what_is_read_after_it() {
    // 100 mm at F100 is a minute; at 150 % (five +10 % steps) two thirds of
    // it, within the ramps (150 mm/s² on Z: a few ms).
    let plain = feed_time(b"");
    let fast = feed_time(&[0x91; 5]);
    let slow = feed_time(&[0x92; 5]);
    assert!((plain - 60.0).abs() < 0.05, "{plain}");
    assert!((fast - 40.0).abs() < 0.05, "{fast}");
    assert!((slow - 120.0).abs() < 0.05, "{slow}");
    // 0x90 puts it back to 100 %.
    let back = feed_time(&[0x91, 0x91, 0x90]);
    assert!((back - plain).abs() < 1e-9);
}

#[test]
fn the_rapid_override_slows_the_rapids_queued_after_it() {
    // 100 mm along Z at the rapid rate 3000 mm/min (50 mm/s), 150 mm/s²:
    // L/v + v/a = 2.333 s; at 50 % 4.167 s, at 25 % 8.083 s.
    let rapid = |bytes: &[u8]| run_time(bytes, b"G21 G90 G00 Z-100\n");
    for (bytes, want) in [
        (&[][..], 2.0 + 50.0 / 150.0),
        (&[0x96][..], 4.0 + 25.0 / 150.0),
        (&[0x97][..], 8.0 + 12.5 / 150.0),
        (&[0x97, 0x95][..], 2.0 + 50.0 / 150.0),
    ] {
        let t = rapid(bytes);
        assert!((t - want).abs() < 0.005, "{bytes:x?}: {t} s, want {want}");
    }
    // Feeds are not rapids.
    assert!((feed_time(&[0x97]) - 60.0).abs() < 0.05);
}

#[test]
fn the_spindle_override_scales_the_speed_and_feeds_per_revolution() {
    let mut dev = grbl_device();
    assert_eq!(text(&mut dev, b"G21 G95 M03 S1000\n"), "ok\r\n");
    let _ = text(&mut dev, &[0x9A, 0x9A]);
    let status = text(&mut dev, b"?");
    assert!(status.contains("|Ov:100,100,120|"), "{status}");
    // The output turns at 1200 rpm at once (at rest).
    assert!(status.contains(",1200.000|"), "{status}");
    // F0.1 mm/rev at 1200 rpm: 120 mm/min, 100 mm in 50 s.
    let t = run_time(&[0x9A, 0x9A], b"G21 G95 M03 S1000 G01 Z-100 F0.1\n");
    assert!((t - 50.0).abs() < 0.05, "{t}");
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Whether python3 with grbl-streamer is here (CI installs it).
fn sender_available() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import grbl_streamer"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs python3 with grbl-streamer (pip install grbl-streamer)"
        );
        eprintln!("grbl-streamer not installed: the real-sender test skipped");
    }
    ok
}

/// Runs the sender on `port` with `program`; its JSON summary.
fn stream(port: &str, program: &Path) -> String {
    let out = Command::new("python3")
        .arg(root().join("tests/senders/grbl_streamer_run.py"))
        .arg(port)
        .arg(program)
        .output()
        .expect("python3");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

fn number(json: &str, key: &str) -> i64 {
    json.split(&format!("\"{key}\": "))
        .nth(1)
        .and_then(|s| s.split([',', '}']).next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("{key} in {json}"))
}

fn check_run(json: &str) {
    assert!(json.contains("\"errors\": []"), "{json}");
    assert!(json.contains("\"alarms\": []"), "{json}");
    assert!(json.contains("\"finished\": true"), "{json}");
    // Every line was answered `ok`, the buffer was filled by counting.
    assert_eq!(number(json, "processed"), number(json, "lines"), "{json}");
    assert!(number(json, "max_fill") >= 50, "{json}");
    // The program ends at X60 Z20.
    assert!(json.contains("\"position\": [60.0, 0.0, 20.0]"), "{json}");
}

#[test]
fn a_line_typed_alone_moves_once_the_link_is_quiet() {
    let mut local = LocalDevice::new();
    local.set_grbl(true);
    let device = PtyDevice::start_with(local).expect("pty");
    let mut c = host_sim::link::Client::open(device.path(), Duration::from_secs(5)).expect("open");
    c.write_raw(b"G21 G90 G94 G01 X10 Z-5 F200\n")
        .expect("line");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(200));
    c.write_raw(b"?").expect("status");
    let report = c.read_line().expect("report");
    assert!(
        report.starts_with("<Idle|MPos:10.0000,0.0000,-5.0000|"),
        "{report}"
    );
}

#[test]
fn a_real_grbl_sender_streams_a_program_to_serve() {
    if !sender_available() {
        return;
    }
    let mut local = LocalDevice::new();
    local.set_grbl(true);
    let device = PtyDevice::start_with(local).expect("pty");
    let json = stream(device.path(), &root().join("examples/iso-shaft.nc"));
    check_run(&json);
}

#[test]
fn a_real_grbl_sender_streams_to_the_firmware_with_a_hold_in_the_middle() {
    if !sender_available() || !host_sim::qemu::qemu_or_skip() {
        return;
    }
    let elf = host_sim::qemu::build_firmware("qemu-paced").expect("firmware");
    let mut qemu = host_sim::qemu::Qemu::boot_paced(&elf).expect("boot");
    // The board starts with the pendant protocol: one `GRBL` request
    // switches it (a sender's first `$` line would too).
    {
        let mut c = qemu.connect(Duration::from_secs(30)).expect("connect");
        c.write_raw(b"GRBL\r\n").expect("switch");
        let ok = c.read_line().expect("reply");
        assert!(ok.starts_with("OK GRBL=1"), "{ok}");
    }
    let json = stream(qemu.pty(), &root().join("examples/iso-shaft.nc"));
    check_run(&json);
    // The sender saw the program run and hold in time.
    for state in ["\"Run\"", "\"Hold:"] {
        assert!(json.contains(state), "{state}: {json}");
    }
    // A reset while the axes move: they stop at once, a drive may have
    // lost steps, so the board is locked until `$X`.
    let mut c = host_sim::link::Client::open(qemu.pty(), Duration::from_secs(10)).expect("open");
    c.write_raw(b"G91 G01 Z-20 F600\n").expect("move");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(500));
    c.write_raw(&[0x18]).expect("reset");
    let mut lines = Vec::new();
    while !lines.iter().any(|l: &String| l.starts_with("[MSG:'$H'")) {
        lines.push(c.read_line().expect("reset lines"));
    }
    assert_eq!(lines[0], "ALARM:3", "{lines:?}");
    assert!(
        lines.iter().any(|l| l.starts_with("Grbl 1.1h")),
        "{lines:?}"
    );
    c.write_raw(b"G01 Z0\n").expect("locked");
    assert!(c.read_line().expect("msg").starts_with("[MSG:alarm 3"));
    assert_eq!(c.read_line().expect("error"), "error:9");
    c.write_raw(b"$X\n").expect("unlock");
    assert_eq!(c.read_line().expect("msg"), "[MSG:Caution: Unlocked]");
    assert_eq!(c.read_line().expect("ok"), "ok");
    c.write_raw(b"?").expect("status");
    assert!(c.read_line().expect("report").starts_with("<Idle|"));
}

/// The firmware in QEMU, motion in time: a jog cancelled halfway stops
/// short, at rest, and the next jog goes on from there.
#[test]
fn a_jog_cancel_stops_the_firmware_short_at_rest() {
    if !host_sim::qemu::qemu_or_skip() {
        return;
    }
    let elf = host_sim::qemu::build_firmware("qemu-paced").expect("firmware");
    let mut qemu = host_sim::qemu::Qemu::boot_paced(&elf).expect("boot");
    let mut c = qemu.connect(Duration::from_secs(30)).expect("connect");
    c.write_raw(b"GRBL\r\n").expect("switch");
    assert!(c.read_line().expect("reply").starts_with("OK GRBL=1"));
    // The banner: an empty line, then its text.
    assert_eq!(c.read_line().expect("banner"), "");
    assert!(c.read_line().expect("banner").starts_with("Grbl 1.1h"));
    let z = |c: &mut host_sim::link::Client| -> f64 {
        c.write_raw(b"?").expect("status");
        let report = loop {
            let l = c.read_line().expect("report");
            if l.starts_with('<') {
                break l;
            }
        };
        assert!(report.starts_with("<Idle|"), "{report}");
        report
            .split("MPos:")
            .nth(1)
            .and_then(|s| s.split('|').next())
            .and_then(|s| s.split(',').nth(2))
            .and_then(|s| s.parse().ok())
            .expect(&report)
    };
    // 50 mm at 600 mm/min: 5 s; cancelled after about one.
    c.write_raw(b"$J=G91 G21 Z-50 F600\n").expect("jog");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(1000));
    c.write_raw(&[0x85]).expect("cancel");
    std::thread::sleep(Duration::from_millis(600));
    let stopped = z(&mut c);
    assert!(stopped < -2.0 && stopped > -20.0, "{stopped}");
    // The rest was dropped: the next jog starts from where it stopped.
    c.write_raw(b"$J=G91 G21 Z-1 F600\n").expect("jog");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(600));
    let after = z(&mut c);
    assert!(
        (after - (stopped - 1.0)).abs() < 1e-9,
        "{stopped} then {after}"
    );
}

/// grbl's standard settings: every one `$$` lists is accepted when it
/// leaves the machine as it is, kept and read back when it only informs a
/// sender, acted on when this board has it, and otherwise refused with
/// grbl's documented error, naming why.
#[test]
fn the_standard_settings_are_accepted_or_refused_with_their_error() {
    let mut dev = grbl_device();
    let all = text(&mut dev, b"$$\n");
    for n in [
        0, 1, 2, 3, 4, 5, 6, 10, 11, 12, 13, 14, 20, 21, 22, 23, 24, 25, 26, 27, 30, 31, 32, 100,
        102, 110, 112, 120, 122, 130, 132, 160, 162,
    ] {
        assert!(
            all.contains(&format!("\r\n${n}=")) || all.starts_with(&format!("${n}=")),
            "${n}: {all}"
        );
    }
    // Kept (or set through HOMING) and read back.
    for (line, back) in [
        ("$1=255", "$1=255\r\n"),
        ("$24=50.5", "$24=50.500\r\n"),
        ("$27=2", "$27=2.000\r\n"),
        ("$130=310", "$130=310.000\r\n"),
        ("$160=0.08", "$160=0.080\r\n"),
        ("$162=0.15", "$162=0.150\r\n"),
        ("$23=4", "$23=4\r\n"),
        ("$22=5", "$22=7\r\n"),
        ("$20=1", "$20=1\r\n"),
    ] {
        assert_eq!(
            text(&mut dev, format!("{line}\n").as_bytes()),
            "ok\r\n",
            "{line}"
        );
        assert!(text(&mut dev, b"$$\n").contains(back), "{line}");
    }
    // Acted on: steps per mm are one over the impulse price, the chord
    // tolerance is CFG TOL.
    assert_eq!(text(&mut dev, b"$100=160\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"$12=0.002\n"), "ok\r\n");
    let now = text(&mut dev, b"$$\n");
    assert!(now.contains("$100=160.000\r\n"), "{now}");
    assert!(now.contains("$12=0.0020\r\n"), "{now}");
    // Values the setting already has are accepted.
    for line in ["$2=0", "$13=0", "$21=0", "$32=2"] {
        assert_eq!(
            text(&mut dev, format!("{line}\n").as_bytes()),
            "ok\r\n",
            "{line}"
        );
    }
    // Refused with grbl's codes, nothing changed.
    for (line, code) in [
        ("$20=2", "error:20"),
        ("$21=2", "error:3"),
        ("$5=2", "error:3"),
        ("$14=1", "error:3"),
        ("$6=3", "error:3"),
        ("$22=8", "error:3"),
        ("$23=2", "error:3"),
        ("$27=0", "error:20"),
        ("$160=5.5", "error:20"),
        ("$13=1", "error:3"),
        ("$32=1", "error:3"),
        ("$100=1280", "error:3"),
        ("$1=-5", "error:4"),
        ("$24=fast", "error:2"),
        ("$10=2", "error:3"),
        ("$101=80", "error:3"),
    ] {
        let r = text(&mut dev, format!("{line}\n").as_bytes());
        assert!(
            r.starts_with("[MSG:") && r.ends_with(&format!("{code}\r\n")),
            "{line}: {r}"
        );
    }
    assert_eq!(text(&mut dev, b"$$\n"), now);
    // $10=0: work positions.
    assert_eq!(text(&mut dev, b"G10 L2 P1 Z-100\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"$10=0\n"), "ok\r\n");
    assert!(text(&mut dev, b"?").starts_with("<Idle|WPos:0.0000,0.0000,100.0000|"));
    assert_eq!(text(&mut dev, b"$10=1\n"), "ok\r\n");
    assert!(text(&mut dev, b"?").starts_with("<Idle|MPos:0.0000,0.0000,0.0000|"));
}

/// `$5`, `$6`, `$14` and `$21` as grblHAL numbers them set the switches'
/// wiring (`INPUT`): limit pins inverted per axis, the probe inverted, the
/// control inputs inverted ($6 wires the probe too), hard limits on; each is read back in `$$` and
/// in `INPUT`, and a bit this lathe has no input for is refused by name.
#[test]
fn a_sender_wires_the_switches_with_grbls_settings() {
    let mut dev = grbl_device();
    for line in ["$21=1", "$5=4", "$6=1", "$14=72"] {
        assert_eq!(
            text(&mut dev, format!("{line}\n").as_bytes()),
            "ok\r\n",
            "{line}"
        );
    }
    let all = text(&mut dev, b"$$\n");
    for back in ["$5=4\r\n", "$6=1\r\n", "$14=72\r\n", "$21=1\r\n"] {
        assert!(all.contains(back), "{back}: {all}");
    }
    // The pendant's view of the same wiring.
    let r = text(&mut dev, b"INPUT\n");
    assert_eq!(r, "ok\r\n", "a pendant request answers ok on a grbl link");
    assert_eq!(text(&mut dev, b"$PENDANT\n"), "ok\r\n");
    let r = text(&mut dev, b"INPUT\n");
    assert!(
        r.starts_with("OK USED=X-,X+,Z-,Z+,PROBE INVERT=ESTOP,Z-,Z+,DOOR,PROBE FILTER=0"),
        "{r}"
    );
    assert!(text(&mut dev, b"GRBL\n").contains("Grbl 1.1h"));
    // A Y bit, a reset input: refused, saying why; nothing changed.
    let r = text(&mut dev, b"$5=2\n");
    assert_eq!(
        r,
        "[MSG:$5: bit 0 X, bit 2 Z: a lathe has no Y]\r\nerror:3\r\n"
    );
    let r = text(&mut dev, b"$14=1\n");
    assert!(
        r.contains("no reset, block delete") && r.ends_with("error:3\r\n"),
        "{r}"
    );
    assert_eq!(text(&mut dev, b"$$\n"), all);
    // Hard limits off again: the other inputs stay as they were.
    assert_eq!(text(&mut dev, b"$21=0\n"), "ok\r\n");
    assert!(text(&mut dev, b"$$\n").contains("$21=0\r\n$22="));
}

/// `$450`–`$452`, this controller's own: the dialect G-code lines are read
/// in, block delete and the optional stop, as `OPT` sets them. A Fanuc
/// program that ISO refuses is read once `$450=1`.
#[test]
fn a_sender_switches_the_dialect_block_delete_and_optional_stop() {
    let mut dev = grbl_device();
    let all = text(&mut dev, b"$$\n");
    for want in ["$450=0\r\n", "$451=0\r\n", "$452=0\r\n"] {
        assert!(all.contains(want), "{want}: {all}");
    }
    // U is Fanuc's incremental X: ISO refuses it.
    let iso = text(&mut dev, b"G00 U4. W-2.\n");
    // The refusal names the way to Fanuc in a grbl sender's words.
    assert_eq!(
        iso,
        "[MSG:VALUE U belongs to the FANUC dialect ($450=1)]\r\nerror:20\r\n"
    );
    assert!(text(&mut dev, b"?").starts_with("<Idle|MPos:0.0000,0.0000,0.0000|"));
    assert_eq!(text(&mut dev, b"$450=1\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"G00 U4. W-2.\n"), "ok\r\n");
    let _ = text(&mut dev, b"G4 P0\n");
    let at = text(&mut dev, b"?");
    assert!(at.starts_with("<Idle|MPos:4.0000,0.0000,-2.0000|"), "{at}");
    assert_eq!(text(&mut dev, b"$451=1\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"$452=1\n"), "ok\r\n");
    let now = text(&mut dev, b"$$\n");
    for want in ["$450=1\r\n", "$451=1\r\n", "$452=1\r\n"] {
        assert!(now.contains(want), "{want}: {now}");
    }
    // A value with no word is refused by name, nothing changed.
    for (line, why) in [
        (
            "$450=2",
            "[MSG:$450: 0 to 1: 0 DIALECT=ISO, 1 DIALECT=FANUC]",
        ),
        ("$451=7", "[MSG:$451: 0 to 1: 0 BDEL=0, 1 BDEL=1]"),
        ("$452=on", "[MSG:$452: 0 to 1: 0 OPTSTOP=0, 1 OPTSTOP=1]"),
    ] {
        let r = text(&mut dev, format!("{line}\n").as_bytes());
        assert_eq!(r, format!("{why}\r\nerror:3\r\n"), "{line}");
    }
    assert_eq!(text(&mut dev, b"$$\n"), now);
    // A reset (Ctrl-X) keeps them, as grbl keeps its settings.
    let banner = text(&mut dev, &[0x18]);
    assert!(banner.contains("Grbl 1.1h"), "{banner}");
    assert_eq!(text(&mut dev, b"$$\n"), now);
    // Back to ISO: U is refused again.
    assert_eq!(text(&mut dev, b"$450=0\n"), "ok\r\n");
    assert!(text(&mut dev, b"G00 U4.\n").ends_with("($450=1)]\r\nerror:20\r\n"));
    // And in Fanuc, an ISO word names the way back.
    assert_eq!(text(&mut dev, b"$450=1\n"), "ok\r\n");
    let back = text(&mut dev, b"G95\n");
    assert!(
        back.ends_with("belongs to the ISO dialect ($450=0)]\r\nerror:20\r\n"),
        "{back}"
    );
}

/// The "zero" buttons of grbl senders: UGS and bCNC send `G10 P0 L20`
/// (the work system in effect), CNCjs `G10 L20 P1` (G54 by number): the
/// work position reads zero there, `$#` shows the offset.
#[test]
fn a_senders_zero_buttons_set_the_work_offset_in_effect() {
    let mut dev = grbl_device();
    assert_eq!(text(&mut dev, b"G21 G90 G00 X30 Z-12\n"), "ok\r\n");
    let _ = text(&mut dev, b"G4 P0\n");
    assert_eq!(text(&mut dev, b"G10 P0 L20 X0 Z0\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"$10=0\n"), "ok\r\n");
    let at = text(&mut dev, b"?");
    assert!(at.starts_with("<Idle|WPos:0.0000,0.0000,0.0000|"), "{at}");
    let offsets = text(&mut dev, b"$#\n");
    assert!(
        offsets.contains("[G54:30.0000,0.0000,-12.0000]"),
        "{offsets}"
    );
    // In G55, by number as CNCjs does; G54 stays.
    assert_eq!(text(&mut dev, b"G55\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"G10 L20 P2 Z5\n"), "ok\r\n");
    let offsets = text(&mut dev, b"$#\n");
    assert!(
        offsets.contains("[G54:30.0000,0.0000,-12.0000]"),
        "{offsets}"
    );
    assert!(
        offsets.contains("[G55:0.0000,0.0000,-17.0000]"),
        "{offsets}"
    );
}

/// `$C`: lines are read and checked as if run, a bad one refused as it
/// would be, nothing moves; leaving it resets (grbl's banner) with the
/// position where it was.
#[test]
fn check_mode_runs_nothing_and_reports_what_it_would_refuse() {
    let mut dev = grbl_device();
    assert_eq!(
        text(&mut dev, b"G21 G90 G00 X10 Z-5\nM30\n"),
        "ok\r\nok\r\n"
    );
    assert_eq!(text(&mut dev, b"$C\n"), "[MSG:Enabled]\r\nok\r\n");
    assert!(text(&mut dev, b"?").starts_with("<Check|MPos:10.0000,0.0000,-5.0000|"));
    assert_eq!(text(&mut dev, b"G01 X40 Z-50 F100\n"), "ok\r\n");
    // A probing block is checked as a feed move: no probe is read, no
    // PRB, no alarm (the in-process board has none).
    assert_eq!(text(&mut dev, b"G38.2 Z-60 F50\n"), "ok\r\n");
    assert_eq!(
        text(&mut dev, b"G38.2 Z-60 F50\n"),
        "[MSG:GEOMETRY G38.2 to G38.5 end where the tool already is]\r\nerror:33\r\n"
    );
    let refused = text(&mut dev, b"G02 X50 Z-60 I0 K3\n");
    assert!(refused.ends_with("error:33\r\n"), "{refused}");
    assert_eq!(text(&mut dev, b"M30\n"), "ok\r\n");
    let status = text(&mut dev, b"?");
    assert!(
        status.starts_with("<Check|MPos:10.0000,0.0000,-5.0000|"),
        "{status}"
    );
    let off = text(&mut dev, b"$C\n");
    assert!(off.starts_with("[MSG:Disabled]\r\n"), "{off}");
    assert!(off.contains("Grbl 1.1h"), "{off}");
    assert!(text(&mut dev, b"?").starts_with("<Idle|MPos:10.0000,0.0000,-5.0000|"));
    // The next line runs from there, for real.
    assert_eq!(text(&mut dev, b"G90 G00 X20\nM30\n"), "ok\r\nok\r\n");
    assert!(text(&mut dev, b"?").starts_with("<Idle|MPos:20.0000,0.0000,-5.0000|"));
}

/// What grbl drops: every byte above 0x7F that is not a real-time command
/// (CNCjs sends an override as UTF-8, `C2 91`), control bytes; and what a
/// reset drops: the line being received. A reset that drops motion answered
/// `ok` and not yet run says so with ALARM:3.
#[test]
fn bytes_that_are_not_commands_or_lines_are_dropped() {
    let mut dev = grbl_device();
    assert_eq!(text(&mut dev, b"G21 G90 G00 X1\n"), "ok\r\n");
    assert_eq!(text(&mut dev, &[0xC2, 0x91]), "");
    assert_eq!(text(&mut dev, b"G00 X2\n"), "ok\r\n");
    assert_eq!(text(&mut dev, b"G00\xC2\x84 X3\x07\n"), "ok\r\n");
    assert!(text(&mut dev, b"?").contains("|Ov:110,100,100|"));
    // `$`, a reset, then `G`: the `$` went with the reset (the motion
    // queued has run first: a reset that drops it raises ALARM:3).
    assert_eq!(text(&mut dev, b"M30\n"), "ok\r\n");
    let out = text(&mut dev, b"$\x18G\n");
    assert!(out.contains("Grbl 1.1h"), "{out}");
    assert!(out.ends_with("error:20\r\n"), "{out}");
    assert!(!out.contains("[GC:") && !out.contains("ALARM"), "{out}");
    // grbl 1.1 ends a line at CR and at LF: a CRLF is a line and an empty
    // one, each answered.
    assert_eq!(text(&mut dev, b"G00 X4\r\n"), "ok\r\nok\r\n");
    // Queued, not run: the reset drops it and says so.
    let out = text(&mut dev, &[0x18]);
    assert!(out.starts_with("ALARM:3\r\n"), "{out}");
    assert!(text(&mut dev, b"?").starts_with("<Alarm|MPos:3.0000,"));
}

/// Safety: after `G10 L2` moves the active work system, a block that names
/// only Z leaves X where it is (as LinuxCNC and grbl do).
#[test]
fn an_axis_left_out_of_a_block_stays_after_the_work_offset_changes() {
    let mut dev = grbl_device();
    let out = text(&mut dev, b"G90 G0 X10 Z-5\nG10 L2 P1 X4 Z-2\nG0 Z-6\nM30\n");
    assert_eq!(out, "ok\r\nok\r\nok\r\nok\r\n");
    let status = text(&mut dev, b"?");
    assert!(
        status.starts_with("<Idle|MPos:10.0000,0.0000,-8.0000|"),
        "{status}"
    );
}

/// A simulated board (`serve --pty`) on a pty, speaking grbl; the client
/// after its greeting.
fn board(pace: host_sim::board::Pace) -> (host_sim::board::Board, host_sim::link::Client) {
    struct Nowhere;
    impl core_nostd::protocol::Io for Nowhere {
        fn send(&mut self, _: &[u8]) {}
    }
    let mut device = core_nostd::protocol::Device::new();
    device.set_grbl(true, &mut Nowhere);
    let (path, board) = host_sim::board::serve_pty(device, pace).expect("pty");
    let mut c = host_sim::link::Client::open(&path, Duration::from_secs(10)).expect("open");
    // A board greets the sender that opens its port.
    assert_eq!(c.read_line().expect("banner"), "");
    assert!(c.read_line().expect("banner").starts_with("Grbl 1.1h"));
    (board, c)
}

/// The next status report (lines before it skipped).
fn report(c: &mut host_sim::link::Client) -> String {
    c.write_raw(b"?").expect("status");
    loop {
        let l = c.read_line().expect("report");
        if l.starts_with('<') {
            return l;
        }
    }
}

/// MPos X and Z of a report.
fn mpos(report: &str) -> (f64, f64) {
    let p: Vec<f64> = report
        .split("MPos:")
        .nth(1)
        .and_then(|s| s.split('|').next())
        .map(|s| s.split(',').map(|v| v.parse().expect(report)).collect())
        .expect(report);
    (p[0], p[2])
}

/// `M0` is answered at once, the board shows `Hold:0` once the motion
/// before it has ended, status is answered, the lines after it are
/// received and answered, and cycle start goes on with them.
#[test]
fn m0_is_answered_and_holds_until_cycle_start() {
    let (_board, mut c) = board(host_sim::board::Pace::Wall(1.0));
    c.write_raw(b"G21 G90 G00 X10\nM0\nG00 X20\n")
        .expect("lines");
    for _ in 0..3 {
        assert_eq!(c.read_line().expect("ok"), "ok");
    }
    let held = report(&mut c);
    assert!(held.starts_with("<Hold:0|"), "{held}");
    assert_eq!(mpos(&held), (10.0, 0.0));
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(mpos(&report(&mut c)), (10.0, 0.0));
    c.write_raw(b"~").expect("cycle start");
    std::thread::sleep(Duration::from_millis(800));
    let done = report(&mut c);
    assert!(done.starts_with("<Idle|"), "{done}");
    assert_eq!(mpos(&done), (20.0, 0.0));
}

/// On the wall clock a sender sees the run: the position moving, `Run`,
/// `Hold:1` braking then `Hold:0`, `Run` again after cycle start, `Idle` at
/// the end of a program that has no `M2` (the quiet link starts what it
/// queued and the run ends); a reset in motion raises `ALARM:3`.
#[test]
fn the_simulated_board_runs_in_real_time() {
    let (board, mut c) = board(host_sim::board::Pace::Wall(1.0));
    // 30 mm along Z at 600 mm/min: 3 s.
    c.write_raw(b"G21 G90 G01 Z-30 F600\n").expect("line");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(700));
    let first = report(&mut c);
    assert!(first.starts_with("<Run|"), "{first}");
    std::thread::sleep(Duration::from_millis(300));
    let second = report(&mut c);
    let (z1, z2) = (mpos(&first).1, mpos(&second).1);
    // 10 mm/s: about 3 mm in 0.3 s.
    assert!(z2 < z1 - 1.5 && z2 > z1 - 4.5, "{first} then {second}");
    c.write_raw(b"!").expect("hold");
    let braking = report(&mut c);
    assert!(braking.starts_with("<Hold:"), "{braking}");
    std::thread::sleep(Duration::from_millis(300));
    let held = report(&mut c);
    assert!(held.starts_with("<Hold:0|"), "{held}");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(mpos(&report(&mut c)), mpos(&held));
    c.write_raw(b"~").expect("resume");
    std::thread::sleep(Duration::from_millis(200));
    assert!(report(&mut c).starts_with("<Run|"));
    std::thread::sleep(Duration::from_millis(3000));
    let end = report(&mut c);
    assert!(end.starts_with("<Idle|"), "{end}");
    assert_eq!(mpos(&end), (0.0, -30.0));
    // A jog shows as such.
    c.write_raw(b"$J=G91 G21 Z-10 F600\n").expect("jog");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(300));
    assert!(report(&mut c).starts_with("<Jog|"));
    // A reset while the axes move: they stop at once, ALARM:3.
    c.write_raw(&[0x18]).expect("reset");
    let mut lines = Vec::new();
    while !lines.iter().any(|l: &String| l.starts_with("[MSG:'$H'")) {
        lines.push(c.read_line().expect("reset lines"));
    }
    assert_eq!(lines[0], "ALARM:3", "{lines:?}");
    let drift = board.drift();
    assert!(drift.runs >= 2, "{drift:?}");
    assert!(
        (drift.wall_s - drift.planned_s).abs() < 0.05 * drift.runs as f64,
        "{drift:?}"
    );
}

/// A program without `M2`/`M30`: once the link is quiet, every block
/// queued starts (a run under way included) and the board reports `Idle`
/// where the program ends, unpaced and on the wall clock.
#[test]
fn a_program_without_m2_runs_to_its_end() {
    for pace in [
        host_sim::board::Pace::Unpaced,
        host_sim::board::Pace::Wall(20.0),
    ] {
        let (_board, mut c) = board(pace);
        // More lines than the 64-block window: a run is under way when
        // the stream ends.
        for k in 1..=80 {
            c.write_raw(format!("G21 G90 G01 X{} Z-{}.5 F3000\n", k % 2, k).as_bytes())
                .expect("line");
            assert_eq!(c.read_line().expect("ok"), "ok", "{pace:?}");
        }
        std::thread::sleep(Duration::from_millis(1500));
        let end = report(&mut c);
        assert!(end.starts_with("<Idle|"), "{pace:?}: {end}");
        assert_eq!(mpos(&end), (0.0, -80.5), "{pace:?}");
    }
}

/// Lathe programs nobody here wrote (the corpus' ISO programs that run to
/// their end, `tests/data/SOURCES.md`) streamed by grbl-streamer to the
/// simulated board: every line `ok`, no error or alarm, and the carriage
/// at the program's last point.
#[test]
fn a_real_grbl_sender_streams_the_corpus_programs() {
    if !sender_available() {
        return;
    }
    for name in [
        "nhsd-cnc-lathe/turn_two_diameters.nc",
        "liblathe/profile.gcode",
    ] {
        let path = root().join("tests/data").join(name);
        let program = std::fs::read_to_string(&path).expect("program");
        // Both programs end with an absolute move naming X and Z, no
        // offset in force: the carriage ends there.
        let want = tests::last_x_z(&program).expect("a last move");
        let mut local = LocalDevice::new();
        local.set_grbl(true);
        let device = PtyDevice::start_with(local).expect("pty");
        let json = stream(device.path(), &path);
        assert!(json.contains("\"errors\": []"), "{name}: {json}");
        assert!(json.contains("\"alarms\": []"), "{name}: {json}");
        assert!(json.contains("\"finished\": true"), "{name}: {json}");
        assert_eq!(
            number(&json, "processed"),
            number(&json, "lines"),
            "{name}: {json}"
        );
        let at: Vec<f64> = json
            .split("\"position\": [")
            .nth(1)
            .and_then(|s| s.split(']').next())
            .map(|s| {
                s.split(',')
                    .map(|v| v.trim().parse().expect("number"))
                    .collect()
            })
            .expect("position");
        assert!(
            (at[0] - want.0).abs() < 1e-3 && (at[2] - want.1).abs() < 1e-3,
            "{name}: the sender ends at {at:?}, the program at {want:?}"
        );
    }
}

/// What the operator must do at a stop (shift the gearbox, do the
/// machine's own M code by hand) reaches a grbl sender as grbl's feedback
/// message before the `ok`, and a refusal's text as its `[MSG:…]` before
/// the error.
#[test]
fn a_stop_tells_the_operator_what_to_do_in_grbls_words() {
    let mut dev = grbl_device();
    assert_eq!(text(&mut dev, b"GEAR N=1 TOP=500\n"), "ok\r\n");
    assert_eq!(
        text(&mut dev, b"M41\n"),
        "[MSG:M41: shift the gearbox to range 1 (up to 500.0000 rpm), then cycle start]\r\nok\r\n"
    );
    assert_eq!(
        text(&mut dev, b"M16\n"),
        "[MSG:M16: the machine's own M code; do it by hand, then cycle start]\r\nok\r\n"
    );
    assert_eq!(
        text(&mut dev, b"G01 X10\n"),
        "[MSG:VALUE F not programmed: a feed move needs F (mm/min)]\r\nerror:22\r\n"
    );
}

/// The lines up to and including the first that `done` accepts.
fn lines_until(c: &mut host_sim::link::Client, done: impl Fn(&str) -> bool) -> Vec<String> {
    let mut lines = Vec::new();
    loop {
        let l = c.read_line().expect("a line");
        let end = done(&l);
        lines.push(l);
        if end {
            return lines;
        }
    }
}

/// Reads up to the alarm, which must be `ALARM:code`, then the status
/// report, which must be `Alarm` with `letter` among its `Pn:`; returns it.
fn alarm(c: &mut host_sim::link::Client, code: u8, letter: char) -> String {
    let lines = lines_until(c, |l| l.starts_with("ALARM:"));
    assert_eq!(
        lines.last().map(String::as_str),
        Some(format!("ALARM:{code}").as_str()),
        "{lines:?}"
    );
    let r = report(c);
    let pins = r.split("|Pn:").nth(1).and_then(|p| p.split('|').next());
    assert!(
        r.starts_with("<Alarm|") && pins.is_some_and(|p| p.contains(letter)),
        "{r}"
    );
    r
}

/// On the wall clock, the E-stop pressed mid-cut stops the carriage at
/// once where it is (the panel reads the same place), the spindle stops,
/// and a sender sees `ALARM:10`, `Alarm` with `Pn:E`, and `error:50`
/// until the button is released, a reset comes and `$X` unlocks; a limit
/// switch then stops a move with `ALARM:1`.
#[test]
fn the_estop_stops_a_cut_at_once_and_a_sender_sees_alarm_10() {
    use core_nostd::inputs::Input;
    let (board, mut c) = board(host_sim::board::Pace::Wall(1.0));
    c.write_raw(b"INPUT USED=ESTOP,Z+ INVERT=ESTOP FILTER=2\n")
        .expect("wiring");
    assert_eq!(c.read_line().expect("ok"), "ok");
    // 30 mm along Z at 600 mm/min: 3 s.
    c.write_raw(b"G21 G90 M3 S500\nG01 Z-30 F600\n")
        .expect("lines");
    assert_eq!(c.read_line().expect("ok"), "ok");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(1000));
    assert!(report(&mut c).starts_with("<Run|"));
    board.panel_line("ESTOP 1").expect("panel");
    let stopped = alarm(&mut c, 10, 'E');
    assert!(stopped.contains("|FS:0.0000,0.000|"), "{stopped}");
    let z = mpos(&stopped).1;
    assert!(z < -3.0 && z > -20.0, "stopped part of the way: {stopped}");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(mpos(&report(&mut c)), mpos(&stopped), "and stays");
    let state = board.panel_line("STATE?").expect("state").expect("a line");
    assert_eq!(state, format!("STATE X=0.0000 Z={z:.4} IN=E S=0.000"));
    // Locked: G-code and $X draw error 50 until released and reset.
    c.write_raw(b"G00 Z0\n").expect("line");
    let r = lines_until(&mut c, |l| l.starts_with("error"));
    assert_eq!(r.last().map(String::as_str), Some("error:50"), "{r:?}");
    board.panel_line("ESTOP 0").expect("panel");
    c.write_raw(b"$X\n").expect("unlock");
    let r = lines_until(&mut c, |l| l.starts_with("error") || l == "ok");
    assert_eq!(
        r,
        [
            "[MSG:ESTOP the E-stop was pressed: reset, then UNLOCK]",
            "error:50"
        ]
    );
    c.write_raw(&[0x18]).expect("reset");
    let r = lines_until(&mut c, |l| l.starts_with("[MSG:'$H'"));
    assert!(r.iter().any(|l| l.starts_with("Grbl 1.1h")), "{r:?}");
    c.write_raw(b"$X\n").expect("unlock");
    assert_eq!(
        lines_until(&mut c, |l| l == "ok"),
        ["[MSG:Caution: Unlocked]", "ok"]
    );
    // A feed back towards Z0 trips Z's plus limit on the way.
    c.write_raw(b"G01 Z0 F600\n").expect("line");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(150));
    board.panel(Input::LimitZPlus.bit());
    let tripped = alarm(&mut c, 1, 'Z');
    assert!(mpos(&tripped).1 < 0.0, "stopped short of Z0: {tripped}");
    c.write_raw(b"G00 Z0\n").expect("line");
    let r = lines_until(&mut c, |l| l.starts_with("error"));
    assert_eq!(r.last().map(String::as_str), Some("error:9"), "{r:?}");
    assert!(board.panel_line("LIMIT Y+ 1").is_err());
    assert!(board.panel_line("ESTOP on").is_err());
}

/// A simulated lathe behind the board (`serve --machine`): a jog towards
/// Z+ runs the carriage onto its limit switch, which stops it there at
/// once with `ALARM:1` and `Pn:Z`; unlocked, a jog the other way leaves the
/// switch, which releases past its hysteresis. The example machine file
/// is read as it is.
#[test]
fn the_simulated_carriage_trips_its_limit_switch() {
    let text = std::fs::read_to_string(root().join("examples/machine.toml")).expect("file");
    let file = host_sim::lathe::MachineFile::parse(&text).expect("the example parses");
    let (board, mut c) = board(host_sim::board::Pace::Wall(4.0));
    board.set_lathe(file);
    c.write_raw(b"$21=1\n").expect("hard limits");
    assert_eq!(c.read_line().expect("ok"), "ok");
    // Z+ trips at 4 mm: a 10 mm jog stops there.
    c.write_raw(b"$J=G91 G21 Z10 F1200\n").expect("jog");
    assert_eq!(c.read_line().expect("ok"), "ok");
    let tripped = alarm(&mut c, 1, 'Z');
    let z = mpos(&tripped).1;
    // The play of the screw: the carriage lags the nut by up to 0.15 mm.
    assert!(
        (4.0..=4.0 + 0.15 + 0.011).contains(&z),
        "stopped on the switch: {tripped}"
    );
    let state = board.panel_line("STATE?").expect("state").expect("a line");
    assert!(state.contains(" IN=Z "), "{state}");
    c.write_raw(b"$X\n").expect("unlock");
    assert_eq!(
        lines_until(&mut c, |l| l == "ok"),
        ["[MSG:Caution: Unlocked]", "ok"]
    );
    // Off the switch: 1 mm back releases it (hysteresis 0.3).
    c.write_raw(b"$J=G91 G21 Z-1 F600\n").expect("jog");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(400));
    let off = report(&mut c);
    assert!(off.starts_with("<Idle|") && !off.contains("Pn:"), "{off}");
    assert!((mpos(&off).1 - (z - 1.0)).abs() < 1e-9, "{off}");
}

/// On the wall clock the door opened mid-cut holds the feed at once, as
/// `!` does (grbl answers neither with a line); cycle start, the button or
/// `~`, resumes nothing while it is open; closed, the cycle-start button
/// resumes and the cut ends where it should.
#[test]
fn the_door_holds_until_closed_and_cycle_start_resumes() {
    use core_nostd::inputs::Input;
    let (board, mut c) = board(host_sim::board::Pace::Wall(1.0));
    c.write_raw(b"INPUT USED=DOOR,START\n").expect("wiring");
    assert_eq!(c.read_line().expect("ok"), "ok");
    c.write_raw(b"G21 G90 G01 Z-20 F600\n").expect("line");
    assert_eq!(c.read_line().expect("ok"), "ok");
    std::thread::sleep(Duration::from_millis(700));
    board.panel(Input::Door.bit());
    std::thread::sleep(Duration::from_millis(400));
    let held = report(&mut c);
    assert!(
        held.starts_with("<Hold:0|") && held.contains("|Pn:D|"),
        "{held}"
    );
    c.write_raw(b"~").expect("resume");
    board.panel_line("START").expect("panel");
    std::thread::sleep(Duration::from_millis(300));
    let still = report(&mut c);
    assert!(still.starts_with("<Hold:0|"), "{still}");
    assert_eq!(mpos(&still), mpos(&held));
    board.panel(0);
    board.panel_line("START").expect("panel");
    std::thread::sleep(Duration::from_millis(200));
    assert!(report(&mut c).starts_with("<Run|"));
    std::thread::sleep(Duration::from_millis(2000));
    let end = report(&mut c);
    assert!(end.starts_with("<Idle|"), "{end}");
    assert_eq!(mpos(&end), (0.0, -20.0));
}

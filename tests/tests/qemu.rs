//! The firmware booted in QEMU (`netduinoplus2`), reached over its USART1
//! pseudo-terminal with the `serialport` crate: it answers exactly as the
//! in-process device does, and its impulses equal the f64 reference's.
//!
//! Skipped with a message where `qemu-system-arm` is missing, except under CI
//! (`CI` set), where a missing QEMU fails.

use core_nostd::gcode::Dialect;
use host_sim::compare::Comparator;
use host_sim::device::LocalDevice;
use host_sim::link::{final_lines, Client};
use host_sim::qemu::{build_firmware, firmware_dir, qemu_or_skip, Qemu};
use host_sim::scenario;
use std::process::Command;
use std::time::Duration;
use tests::board_line;

/// The firmware built for QEMU, booted with instruction counting, and a
/// link to it.
fn booted() -> (Qemu, Client) {
    let elf = build_firmware("qemu").unwrap();
    let mut qemu = Qemu::boot(&elf, true).unwrap();
    let client = qemu.connect(Duration::from_secs(30)).unwrap();
    (qemu, client)
}

#[test]
fn firmware_answers_the_mixed_session_like_the_in_process_device() {
    if !qemu_or_skip() {
        return;
    }
    let session = scenario::mixed_session();
    let expected = LocalDevice::new().feed(&session);
    let (_qemu, mut client) = booted();
    // The whole session at once: the firmware must keep up through its
    // receive queue, with long blocks among the requests.
    client.write_raw(&session).unwrap();
    let got = client.read_finals(final_lines(&expected)).unwrap();
    assert_eq!(
        String::from_utf8_lossy(&got),
        String::from_utf8_lossy(&expected)
    );
}

/// Backlash compensation on the board: a zig-zag of requests and G-code
/// lines with the play set, the take-ups prepared and issued by the
/// firmware; every reply equal to the in-process device's, `SYNC`'s `EV`,
/// `T` and `TSEQ` (every event and its tick, the take-ups' included) and
/// the registers with them.
#[test]
fn backlash_take_ups_run_on_the_firmware_as_in_process() {
    if !qemu_or_skip() {
        return;
    }
    let mut session = String::new();
    for l in ["CFG DIAM=0", "BACKLASH X=0.08 Z=0.15", "BACKLASH"] {
        session.push_str(l);
        session.push_str("\r\n");
    }
    for i in 0..120 {
        let sign = if i % 2 == 0 { -1.0 } else { 1.0 };
        let (x, z) = (
            3.0 + sign * f64::from(i % 7 + 1) * 0.25,
            -5.0 + sign * f64::from(i % 5 + 1) * 0.4,
        );
        let line = match i % 4 {
            0 => format!("MOVE X={x:.3} Z={z:.3}"),
            1 => format!("MOVE X={x:.3} F=800"),
            2 => format!("G01 Z{z:.3} F250"),
            _ => format!("G00 X{x:.3} Z{z:.3}"),
        };
        session.push_str(&line);
        session.push_str("\r\n");
        if i % 30 == 29 {
            session.push_str("SYNC\r\nPOS\r\nSTATUS\r\n");
        }
    }
    session.push_str("BACKLASH X=0 Z=0\r\nMOVE X=0 Z=0\r\nSYNC\r\nPOS\r\n");
    let expected = LocalDevice::new().feed(session.as_bytes());
    let (_qemu, mut client) = booted();
    let got = host_sim::qemu::one_by_one(&mut client, session.as_bytes()).unwrap();
    let (got, expected) = (
        String::from_utf8_lossy(&got),
        String::from_utf8_lossy(&expected),
    );
    assert_eq!(got, expected);
    assert!(
        expected.contains("OK X=0.08 Z=0.15 NX=16 NZ=15"),
        "{expected}"
    );
}

#[test]
fn the_calculators_answer_on_the_board_as_in_process() {
    if !qemu_or_skip() {
        return;
    }
    // The one image: the controller with the calculators.
    let elf = build_firmware("qemu").unwrap();
    let mut qemu = Qemu::boot(&elf, true).unwrap();
    let mut client = qemu.connect(Duration::from_secs(30)).unwrap();
    let session = scenario::calculator_session();
    let expected = LocalDevice::new().feed(&session);
    // One request at a time: a DEFLECT table is long, the link's receive
    // queue is not.
    let got = host_sim::qemu::one_by_one(&mut client, &session).unwrap();
    assert_eq!(
        String::from_utf8_lossy(&got),
        String::from_utf8_lossy(&expected)
    );
    drop(qemu);
}

#[test]
fn firmware_impulses_equal_the_reference() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, client) = booted();
    let mut cmp = Comparator::new(client).unwrap();
    for s in [
        scenario::table21(),
        scenario::krylenko(),
        scenario::random(11, 400),
    ] {
        cmp.run(&s, |_| {}).unwrap();
    }
    assert!(
        cmp.tally.mismatches.is_empty(),
        "{:?}",
        cmp.tally.mismatches
    );
    assert_eq!(cmp.tally.blocks, 462);
}

#[test]
fn a_debug_panic_stops_and_exits_with_failure() {
    if !qemu_or_skip() {
        return;
    }
    let dir = firmware_dir();
    let target = dir.join("target");
    // The panic-check binary, debug or release, in the firmware's target
    // directory (only this binary: the other ELFs there are not touched).
    let build = |release: bool| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.current_dir(&dir).arg("build");
        if release {
            cmd.arg("--release");
        }
        cmd.args(["--features", "qemu,panic-check", "--bin", "panic_check"])
            .output()
            .unwrap()
    };
    let out = build(false);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let elf = target.join("thumbv7em-none-eabihf/debug/panic_check");
    let mut qemu = Qemu::boot_with(&elf, true, "null").unwrap();
    let status = qemu.wait_exit(Duration::from_secs(30)).expect("QEMU exits");
    assert_eq!(status.code(), Some(1), "{status}");

    // The same panic in a release build is refused at link time.
    let out = build(true);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("release_build_has_a_reachable_panic"));
}

/// One exchange at a time (a real-time byte is answered the moment it
/// arrives, ahead of bytes still queued): the firmware's lines equal the
/// in-process device's, but for the hold, which only the board can make.
#[test]
fn firmware_answers_real_time_bytes_like_the_in_process_device() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client) = booted();
    let mut local = LocalDevice::new();
    let mut exchange = |bytes: &[u8]| -> (Vec<String>, Vec<String>) {
        let want = String::from_utf8_lossy(&local.feed(bytes)).into_owned();
        let want: Vec<String> = want.split_terminator("\r\n").map(String::from).collect();
        client.write_raw(bytes).unwrap();
        let got = (0..want.len())
            .map(|_| board_line(client.read_line().unwrap().trim_end()))
            .collect();
        (got, want)
    };
    for step in [
        &b"SESSION TOKEN=9\n"[..],
        b"MOVE X=10 Z=-5 F=200\n",
        b"\x80",
        b"SYNC\n",
        b"G1 X20 Z-10 F300\n",
        b"\x80",
        b"\x18",
        b"POS\n",
        b"SESSION\n",
        b"MOVE X=1 Z=-1\n",
        b"SYNC\n",
    ] {
        let (got, want) = exchange(step);
        assert_eq!(got, want, "after {:?}", String::from_utf8_lossy(step));
    }
    // A hold at rest holds on the board (the virtual clock has nothing in
    // motion): a block queued meanwhile waits for the cycle start.
    let (got, _) = exchange(b"\x82");
    assert!(
        got[0].starts_with("!STATUS STATE=HOLD PX=100 PZ=-100 "),
        "{got:?}"
    );
    client.write_raw(b"MOVE X=2 Z=-2\nSTATUS\n").unwrap();
    assert!(client
        .read_line()
        .unwrap()
        .starts_with("OK NX=100 NZ=-100 PX=200 PZ=-200"));
    let status = client.read_line().unwrap();
    assert!(
        status.starts_with("OK STATE=HOLD PX=100 PZ=-100"),
        "{status}"
    );
    client.write_raw(b"\x81").unwrap();
    assert!(client.read_line().unwrap().starts_with("!STATUS STATE="));
    client.write_raw(b"SYNC\nPOS\n").unwrap();
    assert!(client.read_line().unwrap().starts_with("OK EV=100 "));
    assert!(client.read_line().unwrap().starts_with("OK PX=200 PZ=-200"));
}

/// The next line that is not a `DATA` line.
fn final_line(client: &mut Client) -> String {
    loop {
        let line = client.read_line().unwrap();
        if !line.starts_with("DATA") {
            return line.trim_end().to_string();
        }
    }
}

/// `M00` on the board: the axes come to rest, the reply waits for cycle
/// start (0x81), status bytes are answered meanwhile with `STOP=M00`; `M01`
/// passes with the optional stop switch off.
#[test]
fn a_program_stop_waits_for_cycle_start_on_the_board() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client) = booted();
    let ask = |client: &mut Client, line: &[u8], want: &str| {
        client.write_raw(line).unwrap();
        let got = final_line(client);
        assert!(got.starts_with(want), "{got} (wanted {want})");
    };
    ask(&mut client, b"G00 X10 Z-5\n", "OK NX=1000 NZ=-500 ");
    ask(&mut client, b"M01\n", "OK NX=0 NZ=0");
    client.write_raw(b"M00\n").unwrap();
    // Status lines while the block before it runs to its end, then the
    // stop; no reply to M00 meanwhile.
    let mut stopped = None;
    for _ in 0..50 {
        client.write_raw(b"\x80").unwrap();
        let status = final_line(&mut client);
        assert!(status.starts_with("!STATUS "), "{status}");
        if status.contains(" STOP=M00 ") {
            stopped = Some(status);
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = stopped.expect("STOP=M00 in a status line");
    assert!(
        status.starts_with("!STATUS STATE=IDLE PX=1000 PZ=-500 "),
        "{status}"
    );
    client.write_raw(b"\x80").unwrap();
    assert!(final_line(&mut client).contains(" STOP=M00 "));
    client.write_raw(b"\x81").unwrap();
    let mut two = [final_line(&mut client), final_line(&mut client)];
    two.sort();
    assert!(two[0].starts_with("!STATUS STATE=IDLE"), "{two:?}");
    assert!(two[1].starts_with("OK NX=0 NZ=0"), "{two:?}");
    client.write_raw(b"\x80").unwrap();
    let status = final_line(&mut client);
    assert!(!status.contains("STOP="), "{status}");
    ask(&mut client, b"G00 X0 Z0\n", "OK NX=-1000 NZ=500 PX=0 PZ=0");
}

/// The spindle and coolant outputs on the board: switched at rest, the
/// speed following X under `G96` block by block from the step interrupt,
/// everything off at a reset; status lines report what is driven.
#[test]
fn the_spindle_outputs_follow_the_program_on_the_board() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client) = booted();
    let ask = |client: &mut Client, line: &[u8]| -> String {
        client.write_raw(line).unwrap();
        let got = final_line(client);
        got.rsplit_once('*')
            .map_or(got.as_str(), |(b, _)| b)
            .to_string()
    };
    assert!(ask(&mut client, b"AUX SMAX=3000\n").ends_with(" SMAX=3000.0000 SPINUP=0.000"));
    for line in [
        "OPT DIALECT=FANUC",
        "G50 S2500",
        "G00 X30. Z2.",
        "G96 S180 M03 M08",
    ] {
        let got = ask(&mut client, format!("{line}\n").as_bytes());
        assert!(got.starts_with("OK"), "{line}: {got}");
    }
    let on = " SPINDLE=CW S=1909.859 COOLANT=FLOOD";
    assert!(ask(&mut client, b"STATUS\n").ends_with(on));
    let status = ask(&mut client, b"\x80");
    assert!(status.contains(&format!("{on} LAT=")), "{status}");
    // Ø30 to Ø40, then from Ø40: the speed where the last block started.
    for line in ["G99 G01 X40. F.2", "X60. W-10.", "SYNC"] {
        let got = ask(&mut client, format!("{line}\n").as_bytes());
        assert!(got.starts_with("OK"), "{line}: {got}");
    }
    let status = ask(&mut client, b"\x80");
    assert!(
        status.contains(" SPINDLE=CW S=1432.394 COOLANT=FLOOD LAT="),
        "{status}"
    );
    assert!(ask(&mut client, b"\x18").starts_with("!RESET "));
    let status = ask(&mut client, b"\x80");
    assert!(
        status.contains(" SPINDLE=OFF S=0.000 COOLANT=OFF LAT="),
        "{status}"
    );
}

/// The tool table, the work offsets, the stored positions, how lines are
/// read (`OPT`: the dialect, block delete, optional stop) and the
/// switches' wiring (`INPUT`) outlive a power cycle (QEMU's
/// `system_reset`; under QEMU the two flash slots are RAM that a reset
/// keeps); what a power cycle forgets, the `G92` shift, is forgotten.
#[test]
fn the_offsets_survive_a_power_cycle() {
    use host_sim::qemu::QemuLink;
    use host_sim::reliable::ByteLink;
    if !qemu_or_skip() {
        return;
    }
    let elf = build_firmware("qemu").unwrap();
    let mut link = QemuLink::boot(&elf).unwrap();
    let ask = |link: &mut QemuLink, line: &str| -> String {
        link.send(format!("{line}\n").as_bytes()).unwrap();
        loop {
            let got = link
                .recv_line(Duration::from_secs(20))
                .unwrap()
                .expect("a reply");
            let got = String::from_utf8(got).unwrap();
            if !got.starts_with("DATA") {
                return got
                    .rsplit_once('*')
                    .map_or(got.as_str(), |(b, _)| b)
                    .to_string();
            }
        }
    };
    let fresh = [ask(&mut link, "TOOL N=7"), ask(&mut link, "WORK G=55")];
    for set in [
        "TOOL N=7 X=4 Z=-1.5 WX=0.02 R=0.4 T=3",
        "WORK G=55 X=2 Z=-100",
        "G00 X10 Z5",
        "G28.1",
        "G92 X0 Z0",
        "OPT DIALECT=FANUC OPTSTOP=1",
        "INPUT USED=ESTOP,Z+,DOOR INVERT=DOOR FILTER=4",
        "BACKLASH X=0.05 Z=0.125",
    ] {
        assert!(ask(&mut link, set).starts_with("OK"), "{set}");
    }
    let set = [ask(&mut link, "TOOL N=7"), ask(&mut link, "WORK G=55")];
    assert_ne!(set, fresh);
    assert!(set[0].contains(" R=0.4000 T=3"), "{set:?}");
    // Where the tool is in work coordinates, G92 shifting them.
    assert!(ask(&mut link, "POS").contains(" X=0.0000 Z=0.0000"));
    assert!(link.reset_device().unwrap());
    std::thread::sleep(Duration::from_secs(1));
    let after = [ask(&mut link, "TOOL N=7"), ask(&mut link, "WORK G=55")];
    assert_eq!(after, set);
    assert_eq!(ask(&mut link, "OPT"), "OK BDEL=0 DIALECT=FANUC OPTSTOP=1");
    assert_eq!(
        ask(&mut link, "INPUT"),
        "OK USED=ESTOP,Z+,DOOR INVERT=DOOR FILTER=4"
    );
    assert_eq!(ask(&mut link, "BACKLASH"), "OK X=0.05 Z=0.125 NX=10 NZ=13");
    assert!(ask(&mut link, "OPT DIALECT=ISO").starts_with("OK"));
    // The stored position is back (G28 returns to X10 Z5 from here); the
    // shift is not (the position reads in machine coordinates again).
    assert!(ask(&mut link, "POS").starts_with("OK PX=0 PZ=0 X=0.0000 Z=0.0000"));
    assert!(ask(&mut link, "G28").starts_with("OK NX=1000 NZ=500 PX=1000 PZ=500"));
}

/// The example programs, as the host streams them (expanded first where
/// they use macros or subprograms), line by line to the firmware and to the
/// in-process device: every reply equal, none refused.
#[test]
fn the_example_programs_run_on_the_firmware_as_in_process() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client) = booted();
    let mut local = LocalDevice::new();
    let dir = format!("{}/../examples", env!("CARGO_MANIFEST_DIR"));
    let mut blocks = 0;
    for (name, setup) in [
        ("krylenko-fig12.nc", "CFG RN=0.4 TIP=3"),
        ("krylenko-fig17.nc", "CFG RN=0.4 TIP=2"),
        ("krylenko-fig22.nc", "CFG RN=0.4 TIP=3"),
        ("fanuc-grooves.nc", "CFG RN=0.4 TIP=3"),
        ("fanuc-cycles.nc", "CFG RN=0.4 TIP=3"),
        ("fanuc-corners.nc", "CFG RN=0.4 TIP=3"),
    ] {
        let text = std::fs::read_to_string(format!("{dir}/{name}")).unwrap();
        let lines: Vec<String> = if host_sim::expand::needs_expansion(&text) {
            host_sim::expand::expand(&text, Dialect::Fanuc)
                .unwrap()
                .into_iter()
                .map(|l| l.text)
                .collect()
        } else {
            text.lines().map(str::to_owned).collect()
        };
        let session = ["OPT DIALECT=FANUC", setup, "ZERO"]
            .into_iter()
            .map(str::to_owned)
            .chain(lines.into_iter().filter(|l| !l.trim().is_empty()))
            .chain(["SYNC".to_string()]);
        for line in session {
            let bytes = format!("{line}\n");
            let want = String::from_utf8_lossy(&local.feed(bytes.as_bytes())).into_owned();
            let want: Vec<&str> = want.split_terminator("\r\n").collect();
            client.write_raw(bytes.as_bytes()).unwrap();
            let got: Vec<String> = (0..want.len())
                .map(|_| client.read_line().unwrap().trim_end().to_string())
                .collect();
            assert_eq!(got, want, "{name}: {line}");
            let last = want.last().copied().unwrap_or("");
            assert!(last.starts_with("OK"), "{name}: {line} -> {last}");
            blocks += 1;
        }
    }
    eprintln!("{blocks} requests of the example programs answered alike, none refused");
}

/// The supervisor, above the step interrupt, catches it stalled (the
/// `stall-test` build stalls it at its 100th step, STEP lines high) and
/// drives the outputs low within 10 ms, in its own time.
#[test]
fn a_stalled_step_interrupt_is_stopped_by_the_supervisor_within_10_ms() {
    if !qemu_or_skip() {
        return;
    }
    let elf = build_firmware("stall-test").unwrap();
    let mut qemu = Qemu::boot(&elf, true).unwrap();
    let mut client = qemu.connect(Duration::from_secs(30)).unwrap();
    client.write_raw(b"MOVE Z=-10 F=1000\r\nSYNC\r\n").unwrap();
    let status = qemu.wait_exit(Duration::from_secs(60)).expect("QEMU exits");
    std::thread::sleep(Duration::from_millis(100));
    assert!(status.success(), "{status}");
    let log = String::from_utf8_lossy(&qemu.log()).to_string();
    let line = log
        .lines()
        .find_map(|l| l.split_once("supervisor: ").map(|(_, r)| r.to_string()))
        .unwrap_or_else(|| panic!("no supervisor line in {log:?}"));
    eprintln!("supervisor: {line}");
    assert!(line.starts_with("StepStalled"), "{line}");
    assert!(line.ends_with("STEP lines low"), "{line}");
    let after: u32 = line
        .split_once(": ")
        .and_then(|(_, r)| r.split(" us after").next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!(after <= 10_000, "{after} us after the stall");
}

//! The machine's switches on the firmware in QEMU (`docs/inputs.md`): QEMU
//! has no GPIO, so the test drives the pins through the panel port
//! (USART2), one sample of every pin's level at a time, and the firmware
//! filters them as it filters its pins every millisecond on the board.
//! Every line the firmware sends equals the in-process device's, given the
//! same requests and the same filtered inputs.

use core_nostd::inputs::Input;
use host_sim::device::LocalDevice;
use host_sim::link::Client;
use host_sim::qemu::{build_firmware, qemu_or_skip, Panel, Qemu};
use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};
use tests::board_line;

/// Pin levels: the E-stop loop whole (its pin high, read inverted), every
/// other pin low.
const QUIET: u16 = Input::Estop.bit();

/// The firmware of `feature` booted with its panel on a socket named
/// after `name` (instruction counting unless paced), the link to it, and
/// the panel.
///
/// A paced firmware runs in wall-clock time and the tests time it, so the
/// paced ones run one at a time: with two of them on two cores, each ran
/// at a third of its speed and a carriage was not where the test looked.
fn booted(name: &str, feature: &str) -> (Qemu, Client, Panel, Option<MutexGuard<'static, ()>>) {
    static PACED: Mutex<()> = Mutex::new(());
    let paced = feature.starts_with("qemu-paced");
    let one = paced.then(|| PACED.lock().unwrap_or_else(PoisonError::into_inner));
    let sock = std::env::temp_dir().join(format!("lathe-{name}-{}.sock", std::process::id()));
    let _ = std::fs::remove_file(&sock);
    let elf = build_firmware(feature).unwrap();
    let mut qemu = Qemu::boot_with_panel(&elf, !paced, &sock).unwrap();
    let client = qemu.connect(Duration::from_secs(30)).unwrap();
    let panel = Panel::connect(&sock).unwrap();
    (qemu, client, panel, one)
}

fn lines(bytes: &[u8]) -> Vec<String> {
    String::from_utf8_lossy(bytes)
        .split_terminator("\r\n")
        .map(String::from)
        .collect()
}

/// The firmware's next `n` lines.
fn read(client: &mut Client, n: usize) -> Vec<String> {
    (0..n)
        .map(|_| board_line(&client.read_line().expect("a line")))
        .collect()
}

/// Asks `STATUS` until its `PN=` reads `pn` (the samples sent before have
/// been filtered), then returns the line.
fn status_with(client: &mut Client, pn: &str) -> String {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        client.write_raw(b"STATUS\n").expect("status");
        let l = board_line(&client.read_line().expect("status"));
        if l.contains(&format!(" PN={pn}*")) || Instant::now() > deadline {
            return l;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The final line of a request (a block's `DATA` lines and the status
/// lines a test asked for by byte skipped).
fn ask(client: &mut Client, line: &str) -> String {
    client.write_raw(format!("{line}\n").as_bytes()).unwrap();
    loop {
        let l = board_line(&client.read_line().unwrap());
        if !l.starts_with("DATA") && !l.starts_with("!STATUS") {
            return l;
        }
    }
}

/// A switch the carriage passes: the harness follows the carriage while
/// `line` runs, asking for status by byte, and sets `pin` (one sample)
/// each time whether it reads active changes; `active(pz, was)` says
/// whether it does at `PZ=` (10⁻² mm), given what it read before.
struct Passed {
    /// The `!` lines the request sent (not `!STATUS`).
    reports: Vec<String>,
    /// The request's last line.
    last: String,
    /// How many times the pin became active.
    trips: usize,
    /// Whether it reads active at the end.
    active: bool,
}

fn follow(
    client: &mut Client,
    panel: &mut Panel,
    line: &str,
    pin: u16,
    active_at_start: bool,
    active: impl Fn(i64, bool) -> bool,
) -> Passed {
    client.write_raw(format!("{line}\n").as_bytes()).unwrap();
    let (mut now, mut trips, mut reports) = (active_at_start, 0, Vec::new());
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        assert!(Instant::now() < deadline, "{line} did not end");
        client.write_raw(b"\x80").unwrap();
        let l = board_line(&client.read_line().unwrap());
        if l.starts_with("DATA") {
            continue;
        }
        if !l.starts_with("!STATUS") {
            if l.starts_with('!') {
                reports.push(l);
                continue;
            }
            return Passed {
                reports,
                last: l,
                trips,
                active: now,
            };
        }
        let next = active(value(&l, "PZ"), now);
        if next != now {
            now = next;
            trips += usize::from(now);
            panel
                .sample(if now { QUIET | pin } else { QUIET }, 1)
                .unwrap();
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The whole number `key=` holds in a line (its `*HH` aside).
fn value(line: &str, key: &str) -> i64 {
    let body = line.rsplit_once('*').map_or(line, |(b, _)| b);
    host_sim::link::words_value(body, key)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{key} in {line}"))
}

#[test]
fn the_switches_stop_and_lock_the_firmware_as_in_process() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("switches", "qemu");
    let mut local = LocalDevice::new();
    let same = |client: &mut Client, local: &mut LocalDevice, bytes: &[u8]| {
        let want = lines(&local.feed(bytes));
        client.write_raw(bytes).unwrap();
        let got = read(client, want.len());
        assert_eq!(got, want, "after {:?}", String::from_utf8_lossy(bytes));
    };
    for request in [
        &b"INPUT USED=ESTOP,X-,DOOR,START,FAULTZ INVERT=ESTOP FILTER=3\n"[..],
        b"M03 S500\n",
        b"MOVE X=10 F=100\n",
        b"SYNC\n",
        b"MOVE Z=-5 F=100\n",
    ] {
        same(&mut client, &mut local, request);
    }
    panel.sample(QUIET, 10).unwrap();
    // A limit glitch of 3 samples: not longer than the 3 ms filter.
    panel.sample(QUIET | Input::LimitXMinus.bit(), 3).unwrap();
    panel.sample(QUIET, 5).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    same(&mut client, &mut local, b"STATUS\n");
    // The E-stop's loop breaks: 4 samples pass the filter; the queued
    // move is dropped, the registers kept, the machine locked.
    panel.sample(0, 4).unwrap();
    let want = lines(&local.inputs(Input::Estop.bit()));
    assert_eq!(
        want,
        [host_sim::link::with_checksum(
            "!ALARM CODE=10 INPUT=ESTOP DONE=0 OF=0 PX=1000 PZ=0"
        )]
    );
    assert_eq!(read(&mut client, 1), want);
    for request in [
        &b"STATUS\n"[..],
        b"MOVE X=1 F=100\n",
        b"G01 Z-1 F100\n",
        b"UNLOCK\n",
        b"POS\n",
    ] {
        same(&mut client, &mut local, request);
    }
    // Released: a reset, then UNLOCK.
    panel.sample(QUIET, 4).unwrap();
    assert!(local.inputs(0).is_empty());
    let status = status_with(&mut client, "-");
    assert!(status.starts_with("OK STATE=ESTOP"), "{status}");
    same(&mut client, &mut local, b"UNLOCK\n");
    same(&mut client, &mut local, b"\x18");
    for request in [
        &b"UNLOCK\n"[..],
        b"MOVE X=1 F=100\n",
        b"SYNC\n",
        b"STATUS\n",
    ] {
        same(&mut client, &mut local, request);
    }
    // Z's drive reports a fault: alarm 17 until it clears.
    let fault = QUIET | Input::FaultZ.bit();
    panel.sample(fault, 4).unwrap();
    let want = lines(&local.inputs(Input::FaultZ.bit()));
    assert_eq!(read(&mut client, 1), want);
    same(&mut client, &mut local, b"UNLOCK\n");
    panel.sample(QUIET, 4).unwrap();
    assert!(local.inputs(0).is_empty());
    status_with(&mut client, "-");
    same(&mut client, &mut local, b"UNLOCK\n");
    same(&mut client, &mut local, b"STATUS\n");
}

/// In real time (the paced build): the E-stop mid-cut stops the carriage
/// part of the way and it stays there; unlocked, a move to the end of the
/// cut lands exactly there.
#[test]
fn the_estop_stops_a_cut_mid_way_on_the_paced_firmware() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("estop-paced", "qemu-paced");
    assert!(ask(&mut client, "INPUT USED=ESTOP INVERT=ESTOP FILTER=2").starts_with("OK"));
    panel.sample(QUIET, 5).unwrap();
    // 30 mm of Z at 600 mm/min: 3 s; SYNC starts it and waits.
    let cut = ask(&mut client, "G01 Z-30 F600");
    assert!(cut.starts_with("OK"), "{cut}");
    client.write_raw(b"SYNC\n").unwrap();
    std::thread::sleep(Duration::from_millis(1200));
    client.write_raw(b"\x80").unwrap();
    let running = board_line(&client.read_line().unwrap());
    assert!(running.starts_with("!STATUS STATE=RUN"), "{running}");
    panel.sample(0, 3).unwrap();
    // The SYNC's wait ends with the motion; then the alarm.
    let sync = board_line(&client.read_line().unwrap());
    assert!(sync.starts_with("OK EV="), "{sync}");
    let alarm = board_line(&client.read_line().unwrap());
    assert!(alarm.starts_with("!ALARM CODE=10 INPUT=ESTOP "), "{alarm}");
    let pz = value(&alarm, "PZ");
    assert!((-2_500..=-500).contains(&pz), "part of the way: {alarm}");
    std::thread::sleep(Duration::from_millis(300));
    let stopped = ask(&mut client, "STATUS");
    assert!(
        stopped.starts_with(&format!("OK STATE=ESTOP PX=0 PZ={pz} ")),
        "{stopped}"
    );
    assert!(stopped.contains(" SPINDLE=OFF ") && stopped.contains(" LOST=1 PN=E"));
    panel.sample(QUIET, 3).unwrap();
    status_with(&mut client, "-");
    client.write_raw(b"\x18").unwrap();
    let reset = board_line(&client.read_line().unwrap());
    assert!(reset.starts_with("!RESET DONE=0 OF=0"), "{reset}");
    assert!(ask(&mut client, "UNLOCK").starts_with("OK LOST=1"));
    let moved = ask(&mut client, "G01 Z-30 F3000");
    assert!(
        moved.starts_with(&format!("OK NX=0 NZ={} ", -3_000 - pz)),
        "the rest of the cut, exactly: {moved}"
    );
    assert!(ask(&mut client, "SYNC").starts_with("OK EV="));
    assert!(ask(&mut client, "POS").starts_with("OK PX=0 PZ=-3000 "));
}

/// In real time (the paced build): the door opened mid-cut holds the feed
/// to rest; cycle start does nothing while it is open; closed, cycle start
/// resumes and the cut ends exactly where it should.
#[test]
fn the_door_holds_a_cut_until_closed_and_cycle_start_on_the_paced_firmware() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("door-paced", "qemu-paced");
    let line = |client: &mut Client| board_line(&client.read_line().unwrap());
    let door = Input::Door.bit();
    let start = Input::Start.bit();
    client
        .write_raw(b"INPUT USED=DOOR,START FILTER=1\n")
        .unwrap();
    assert!(line(&mut client).starts_with("OK USED=DOOR,START"));
    panel.sample(0, 3).unwrap();
    // 30 mm of Z at 600 mm/min: 3 s; SYNC starts it and waits.
    client.write_raw(b"G01 Z-30 F600\n").unwrap();
    while line(&mut client).starts_with("DATA") {}
    client.write_raw(b"SYNC\n").unwrap();
    std::thread::sleep(Duration::from_millis(800));
    panel.sample(door, 3).unwrap();
    let held = line(&mut client);
    assert!(held.starts_with("!STATUS STATE=HOLD"), "{held}");
    std::thread::sleep(Duration::from_millis(600));
    client.write_raw(b"\x80").unwrap();
    let rest = line(&mut client);
    assert!(
        rest.starts_with("!STATUS STATE=HOLD") && rest.contains(" V=0.0000 "),
        "{rest}"
    );
    // Cycle start, the door open: nothing.
    panel.sample(door | start, 3).unwrap();
    panel.sample(door, 3).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    client.write_raw(b"\x80").unwrap();
    let still = line(&mut client);
    let at = |l: &str| {
        l.split(" PZ=")
            .nth(1)
            .and_then(|s| s.split(' ').next())
            .map(String::from)
    };
    assert!(still.starts_with("!STATUS STATE=HOLD"), "{still}");
    assert_eq!(at(&still), at(&rest), "held where it came to rest");
    // Closed, then cycle start: the cut goes on to its end.
    panel.sample(0, 3).unwrap();
    panel.sample(start, 3).unwrap();
    panel.sample(0, 3).unwrap();
    let resumed = line(&mut client);
    assert!(resumed.starts_with("!STATUS STATE=RUN"), "{resumed}");
    let sync = line(&mut client);
    assert!(
        sync.starts_with("OK EV=3000 "),
        "every step of the cut: {sync}"
    );
    client.write_raw(b"POS\n").unwrap();
    assert!(line(&mut client).starts_with("OK PX=0 PZ=-3000 "));
}

/// The homing cycle on the paced firmware: the test is Z's switch, at
/// Z −20 mm of the registers before homing (−2000 impulses), releasing 0.2
/// mm above; it reads the registers from status bytes while `HOME` runs
/// and sets the pin as the carriage passes. The cycle seeks, pulls off,
/// locates and pulls off on its own, answers with the machine position
/// set, and the switch was tripped twice (seek and locate) without an
/// alarm.
#[test]
fn the_paced_firmware_homes_on_its_switch() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("homing-paced", "qemu-paced");
    assert!(ask(&mut client, "INPUT USED=Z- FILTER=0").starts_with("OK"));
    let set = ask(
        &mut client,
        "HOMING AXES=Z DIRZ=- HOMEZ=-1.5 TRAVELZ=30 SEEK=900 LOCATE=120 PULLOFF=0.5 SOFT=1",
    );
    assert!(set.starts_with("OK AXES=Z DIRX=+ DIRZ=-"), "{set}");
    // Not homed yet: soft limits refuse nothing.
    assert!(ask(&mut client, "MOVE Z=1").starts_with("OK"));
    assert!(ask(&mut client, "MOVE Z=0").starts_with("OK"));
    panel.sample(QUIET, 3).unwrap();
    // The switch reads active from −20 mm down, released from −19.8 mm
    // up (a switch's hysteresis).
    let home = follow(
        &mut client,
        &mut panel,
        "HOME",
        Input::LimitZMinus.bit(),
        false,
        |pz, was| if was { pz <= -1_980 } else { pz <= -2_000 },
    );
    let (last, trips, pressed) = (home.last, home.trips, home.active);
    assert!(home.reports.is_empty(), "{:?}", home.reports);
    assert_eq!(last, host_sim::link::with_checksum("OK MX=0 MZ=-1.5"));
    assert_eq!(trips, 2, "seek and locate");
    assert!(!pressed, "pulled off the switch");
    let pos = ask(&mut client, "POS");
    assert!(pos.starts_with("OK PX=0 PZ=-150 "), "{pos}");
    let status = ask(&mut client, "STATUS");
    assert!(
        status.starts_with("OK STATE=IDLE") && !status.contains("LOST"),
        "{status}"
    );
    // Homed with soft limits: the travel is Z −1.5 to 28.5. A request past
    // it is refused naming the axis; a program's block too, and the
    // program stops there (alarm 2) until unlocked.
    for request in ["MOVE Z=-1.6", "MOVE Z=28.6 F=900", "G01 Z-2 F500"] {
        let mut r = ask(&mut client, request);
        if request.starts_with('G') {
            // A program's block: the alarm first, as the board reports it.
            assert!(r.starts_with("!ALARM CODE=2 INPUT=- PX=0 PZ=-150"), "{r}");
            r = board_line(&client.read_line().unwrap());
        }
        assert!(
            r.starts_with("ERR RANGE Z would leave its travel"),
            "{request}: {r}"
        );
    }
    let locked = ask(&mut client, "G00 Z0");
    assert!(
        locked.starts_with("ERR ALARM 2: a block would have left the travel"),
        "{locked}"
    );
    assert!(ask(&mut client, "UNLOCK").starts_with("OK LOST=0"));
    assert!(ask(&mut client, "G01 Z28.5 F900").starts_with("OK"));
    // A jog clipped (JOGCLIP=1): it runs up to the travel's end.
    assert!(ask(&mut client, "HOMING JOGCLIP=1").contains(" SOFT=1 JOGCLIP=1"));
    let r = ask(&mut client, "MOVE Z=-5 F=900");
    assert_eq!(value(&r, "PZ"), -150, "clipped at Z −1.5: {r}");
    assert!(ask(&mut client, "SYNC").starts_with("OK"));
    let pos = ask(&mut client, "POS");
    assert!(pos.starts_with("OK PX=0 PZ=-150 "), "{pos}");
}

/// Reads a failed `HOME` of Z on its minus switch: the `!ALARM` line of
/// `code` (its words after `AXIS=Z` starting with `then`), then the
/// request's `ERR ALARM` saying `why`.
fn homing_failed(client: &mut Client, code: u8, why: &str, then: &str) {
    let mut got = Vec::new();
    let reply = loop {
        let l = board_line(&client.read_line().unwrap());
        if l.starts_with("ERR") || l.starts_with("OK") {
            break l;
        }
        got.push(l);
    };
    assert!(
        reply.starts_with(&format!("ERR ALARM {code}: {why}")),
        "{got:?} {reply}"
    );
    let alarm = format!("!ALARM CODE={code} INPUT=Z- AXIS=Z{then}");
    assert!(
        got.iter().any(|l| l.starts_with(&alarm)),
        "{alarm}: {got:?}"
    );
}

/// Homing's other failures on the paced firmware: a pull-off shorter than
/// the switch's hysteresis leaves it pressed (alarm 8, after the seek
/// found it), and a reset during the seek stops it part of the way (alarm
/// 6, then the reset's own `!RESET`); each locks the machine until it
/// homes again, which then succeeds.
#[test]
fn the_paced_firmware_raises_homings_alarms_8_and_6() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("homing-alarms", "qemu-paced");
    assert!(ask(&mut client, "INPUT USED=Z- FILTER=0").starts_with("OK"));
    let set = ask(
        &mut client,
        "HOMING AXES=Z DIRZ=- TRAVELZ=30 SEEK=900 LOCATE=120 PULLOFF=0.1",
    );
    assert!(set.starts_with("OK AXES=Z"), "{set}");
    panel.sample(QUIET, 3).unwrap();
    // The switch at −20 mm, releasing 0.2 mm above: more than the pull-off.
    let switch = |pz: i64, was: bool| if was { pz <= -1_980 } else { pz <= -2_000 };
    let home = follow(
        &mut client,
        &mut panel,
        "HOME",
        Input::LimitZMinus.bit(),
        false,
        switch,
    );
    assert!(
        home.last
            .starts_with("ERR ALARM 8: the pull-off left the switch pressed"),
        "{home:?}",
        home = (&home.reports, &home.last)
    );
    assert!(home.active, "still on the switch");
    assert!(
        home.reports
            .iter()
            .any(|l| l.starts_with("!ALARM CODE=8 INPUT=Z- AXIS=Z")),
        "{:?}",
        home.reports
    );
    assert!(ask(&mut client, "MOVE Z=0").starts_with("ERR ALARM 8"));
    // A longer pull-off homes (1 mm: well past the 0.2 mm hysteresis
    // however late the harness presses the pin on a loaded host).
    assert!(ask(&mut client, "HOMING PULLOFF=1").starts_with("OK"));
    let home = follow(
        &mut client,
        &mut panel,
        "HOME",
        Input::LimitZMinus.bit(),
        true,
        switch,
    );
    assert!(
        home.last.starts_with("OK MX=0 MZ=0"),
        "{:?}",
        (&home.reports, &home.last)
    );
    // A reset 300 ms into a seek of up to 45 mm at 900 mm/min (3 s).
    assert!(ask(&mut client, "MOVE Z=10 F=3000").starts_with("OK"));
    assert!(ask(&mut client, "SYNC").starts_with("OK"));
    client.write_raw(b"HOME\n").unwrap();
    std::thread::sleep(Duration::from_millis(300));
    client.write_raw(&[0x18]).unwrap();
    homing_failed(&mut client, 6, "a reset stopped the homing", "");
    let reset = board_line(&client.read_line().unwrap());
    assert!(reset.starts_with("!RESET "), "{reset}");
    let status = ask(&mut client, "STATUS");
    assert!(status.contains(" ALARM=6"), "{status}");
    let pz = value(&status, "PZ");
    assert!(
        (-1_900..900).contains(&pz),
        "stopped part of the way: {status}"
    );
}

/// A homing seek that runs its whole length without its switch: alarm 9,
/// the position lost, everything refused until unlocked.
#[test]
fn the_firmware_raises_alarm_9_when_homing_finds_no_switch() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("homing-alarm-9", "qemu");
    assert!(ask(&mut client, "INPUT USED=Z- FILTER=0").starts_with("OK"));
    assert!(ask(&mut client, "HOMING AXES=Z DIRZ=- TRAVELZ=2 SEEK=900").starts_with("OK"));
    panel.sample(QUIET, 3).unwrap();
    client.write_raw(b"HOME\n").unwrap();
    // The whole seek, 1.5 × 2 mm, ran.
    homing_failed(&mut client, 9, "homing did not find", " PX=0 PZ=-300");
    let refused = ask(&mut client, "MOVE Z=0");
    assert!(refused.starts_with("ERR ALARM 9"), "{refused}");
    assert!(ask(&mut client, "UNLOCK").starts_with("OK LOST=1"));
    assert!(ask(&mut client, "MOVE Z=0").starts_with("OK"));
}

/// Probing on the paced firmware: `G38.2` toward a probe the harness
/// presses once the carriage has gone 10 mm; the firmware stops the steps
/// on its edge (no alarm, the spindle left alone), reports where
/// (`!PROBE`) and the registers are there. `G38.4` back off stops where
/// the harness releases it. A touch-off then writes tool 1's offset.
#[test]
fn the_paced_firmware_stops_a_probing_move_on_the_probe() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("probe-paced", "qemu-paced");
    assert!(ask(&mut client, "INPUT USED=PROBE FILTER=0").starts_with("OK"));
    panel.sample(QUIET, 3).unwrap();
    // Sends `line` and follows the carriage: the probe reads pressed while
    // Z is at `at` (10⁻² mm) or below. Returns the `!PROBE` line and the
    // request's last line.
    let probe = |client: &mut Client, panel: &mut Panel, line: &str, at: i64, pressed: bool| {
        let passed = follow(client, panel, line, Input::Probe.bit(), pressed, |pz, _| {
            pz <= at
        });
        let [found]: [String; 1] = passed.reports.try_into().expect("one !PROBE line");
        assert!(found.starts_with("!PROBE"), "{found}");
        (found, passed.last)
    };
    let (touched, ok) = probe(&mut client, &mut panel, "G38.2 Z-30 F300", -1_000, false);
    assert!(touched.contains(" OK=1"), "{touched}");
    let pz = value(&touched, "PZ");
    // The harness presses it a status line late at most: within 1 mm.
    assert!((-1_100..=-1_000).contains(&pz), "{touched}");
    assert!(ok.starts_with("OK "), "{ok}");
    assert_eq!(value(&ok, "PZ"), pz, "the registers are where it stopped");
    let status = ask(&mut client, "STATUS");
    assert!(
        status.starts_with("OK STATE=IDLE") && !status.contains("ALARM"),
        "{status}"
    );
    // Back off: it releases above −10 mm.
    let (left, ok) = probe(&mut client, &mut panel, "G38.4 Z0 F120", -1_000, true);
    assert!(left.contains(" OK=1"), "{left}");
    let back = value(&left, "PZ");
    assert!((-999..=-900).contains(&back), "{left}");
    assert_eq!(value(&ok, "PZ"), back);
    // A tool setter's touch-off, as LinuxCNC writes it: tool 1 probes the
    // setter, then `G10 L10` makes that point Z0 with the tool's offset,
    // written to its register.
    assert!(ask(&mut client, "T1 M06 G43").starts_with("OK"));
    let (touched, ok) = probe(&mut client, &mut panel, "G38.2 Z-30 F300", -1_000, false);
    assert!(
        touched.contains(" OK=1") && ok.starts_with("OK "),
        "{touched} {ok}"
    );
    let pz = value(&touched, "PZ");
    assert!(ask(&mut client, "G10 L10 P1 Z0").starts_with("OK"));
    let pos = ask(&mut client, "POS");
    assert!(pos.contains(" Z=0.0000"), "{pos}");
    let tool = ask(&mut client, "TOOL N=1");
    let z = format!(" Z={}.{:04}", pz / 100, (pz % 100).abs() * 100);
    assert!(tool.contains(&z), "the setter's machine Z{z}: {tool}");
}

/// The handwheel on the firmware: the panel turns it in bursts (detents,
/// both ways) and the axis it selects ends exactly the detents' sum times
/// the scale away, the other axis unmoved; with no axis selected the
/// wheel moves nothing.
#[test]
fn the_firmware_moves_the_axis_the_wheel_selects_by_its_detents() {
    if !qemu_or_skip() {
        return;
    }
    let (_qemu, mut client, mut panel, _one) = booted("wheel", "qemu");
    panel.sample(QUIET, 3).unwrap();
    // No axis selected: nothing moves.
    panel.wheel(25).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    let pos = ask(&mut client, "POS");
    assert!(pos.starts_with("OK PX=0 PZ=0 "), "{pos}");
    let set = ask(&mut client, "WHEEL AXIS=Z SCALE=10 FEED=600");
    assert!(set.starts_with("OK AXIS=Z SCALE=10 FEED=600"), "{set}");
    let turns: [i16; 8] = [7, -3, 12, 1, -40, 5, 5, 400];
    for n in turns {
        panel.wheel(n).unwrap();
    }
    let sum: i64 = turns.iter().map(|&n| i64::from(n)).sum();
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        assert!(Instant::now() < deadline, "the wheel's moves did not end");
        let s = ask(&mut client, "STATUS");
        if s.starts_with("OK STATE=IDLE") && value(&s, "PZ") == sum * 10 {
            break s;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(value(&status, "PX"), 0, "{status}");
    // And no farther.
    std::thread::sleep(Duration::from_millis(300));
    let pos = ask(&mut client, "POS");
    assert!(
        pos.starts_with(&format!("OK PX=0 PZ={} ", sum * 10)),
        "{pos}"
    );
}

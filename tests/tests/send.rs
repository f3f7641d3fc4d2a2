//! `host-sim send`: a program streamed to a board as a machinist runs it,
//! through a reset, a hold and a faulty line, ending where the program
//! ends.

use core_nostd::gcode::Dialect;
use host_sim::link::{Client, PtyDevice};
use host_sim::program::Options;
use host_sim::reliable::{ByteLink, FaultInjector, Faults, LocalLink};
use host_sim::send::{board_settings, Key, Operator, Plan, Progress, Sender};
use std::time::{Duration, Instant};

const ISO: Options = Options {
    dialect: Dialect::Iso,
    radius: false,
    optional_stop: false,
};

/// A roughing program of many short passes, then a compensated finishing
/// contour with arcs: enough blocks that the queue holds motion when a
/// reset comes.
fn program() -> String {
    let mut p = String::from("G21 G18 G90 G94\nT1 M06\nG97 S800 M03\nM08\nG00 X42 Z2\n");
    for pass in 0..40 {
        let d = 40 - pass / 2;
        p += &format!(
            "G01 X{d} F300\nG01 Z-{} F400\nG00 X{}\nG00 Z2\n",
            20 + pass % 7,
            d + 2
        );
    }
    p += "G42 G01 X10 Z0 F200\nG01 Z-5\nG02 X20 Z-10 R5\nG01 X30\nG03 X36 Z-13 R3\nG01 Z-25\nG40 G00 X45\nM09\nM05\nM30\n";
    p
}

/// Presses keys at given answered-line counts or times, and keeps what it
/// saw.
#[derive(Default)]
struct Script {
    /// (after this many lines answered, or this long since the start, key).
    keys: Vec<(usize, Duration, Key)>,
    started: Option<Instant>,
    states: Vec<String>,
    said: Vec<String>,
    resume_after_hold: Option<Duration>,
    held_since: Option<Instant>,
    /// Cycle start this long after a program stop was first seen.
    resume_stop_after: Option<Duration>,
    stopped_since: Option<Instant>,
    stops: usize,
}

impl Operator for Script {
    fn key(&mut self, p: &Progress) -> Option<Key> {
        let t = self.started.get_or_insert_with(Instant::now).elapsed();
        if let (Some(wait), Some(_)) = (self.resume_stop_after, &p.stop) {
            let since = *self.stopped_since.get_or_insert_with(Instant::now);
            if since.elapsed() >= wait {
                self.stopped_since = None;
                self.stops += 1;
                return Some(Key::Resume);
            }
        }
        if let (Some(wait), Some(h)) = (self.resume_after_hold, self.held_since) {
            if p.state == "HOLD" && h.elapsed() >= wait {
                self.held_since = None;
                return Some(Key::Resume);
            }
        }
        let i = self
            .keys
            .iter()
            .position(|&(n, at, _)| p.acked >= n && t >= at)?;
        let key = self.keys.remove(i).2;
        if key == Key::Hold {
            self.held_since = Some(Instant::now());
        }
        Some(key)
    }
    fn show(&mut self, p: &Progress) {
        if self.states.last() != Some(&p.state) {
            self.states.push(p.state.clone());
        }
    }
    fn say(&mut self, text: &str) {
        self.said.push(text.to_owned());
    }
}

fn plan_for<L: ByteLink>(sender: &mut Sender<L>, text: &str, options: Options) -> Plan {
    plan_with(sender, text, options, &[])
}

fn plan_with<L: ByteLink>(
    sender: &mut Sender<L>,
    text: &str,
    options: Options,
    setup: &[(usize, &str)],
) -> Plan {
    let settings = board_settings(sender).expect("the board's settings");
    let plan = Plan::build(text, options, &settings, setup).expect("the model runs the program");
    assert!(plan.refused.is_empty(), "{:?}", plan.refused);
    plan
}

#[test]
fn a_reset_in_the_middle_restarts_the_program_and_it_ends_where_it_should() {
    let device = PtyDevice::start().expect("pty");
    let client = Client::open(device.path(), Duration::from_secs(5)).expect("open");
    let mut sender = Sender::new(client, Duration::from_millis(300), 77).expect("session");
    let text = program();
    let plan = plan_for(&mut sender, &text, ISO);
    assert!(plan.events() > 20_000, "{} events", plan.events());
    // The finishing contour's lines are compensated: a restart there goes
    // back to the line that began it.
    let g42 = plan
        .lines
        .iter()
        .position(|l| l.text.starts_with("G42"))
        .expect("G42");
    assert!(!plan.lines[g42].comp_before && plan.lines[g42 + 1].comp_before);

    // A hold and a cycle start (the in-process device has no motion in
    // progress to stop: they change nothing there), then a reset.
    let mut op = Script {
        keys: vec![
            (40, Duration::ZERO, Key::Hold),
            (45, Duration::ZERO, Key::Resume),
            (120, Duration::ZERO, Key::Reset),
        ],
        ..Script::default()
    };
    let report = sender.send(&plan, &mut op);
    assert!(report.halt.is_none(), "{:?}", report.halt);
    assert_eq!(report.resets, 1, "{:?}", op.said);
    assert_eq!(report.registers, Some(plan.end()));
    // The queued lines whose motion the reset dropped were sent again.
    assert!(report.requests > plan.lines.len() as u64);
    let said = op.said.join("\n");
    assert!(said.contains("restarting at line"), "{said}");
}

#[test]
fn a_restart_under_work_and_tool_offsets_goes_back_in_machine_coordinates() {
    let device = PtyDevice::start().expect("pty");
    let client = Client::open(device.path(), Duration::from_secs(5)).expect("open");
    let mut sender = Sender::new(client, Duration::from_millis(300), 83).expect("session");
    let text = program().replace("T1 M06\n", "T1 M06\nG43 H1\nG55\n");
    let setup = [
        (1, "WORK G=55 X=0 Z=-40"),
        (2, "TOOL N=1 X=1.5 Z=2.25 R=0.4 T=3"),
    ];
    let plan = plan_with(&mut sender, &text, ISO, &setup);
    let mut op = Script {
        keys: vec![(100, Duration::ZERO, Key::Reset)],
        ..Script::default()
    };
    let report = sender.send(&plan, &mut op);
    assert!(report.halt.is_none(), "{:?} {:?}", report.halt, op.said);
    assert_eq!(report.resets, 1);
    assert_eq!(report.registers, Some(plan.end()));
    // The offsets moved the program: machine = work + G55 (Z −40) + the
    // tool's offset (Z +2.25), so Z ends 37.75 mm lower than the same
    // program without them (0.01 mm impulses).
    let mut plain = Sender::new(LocalLink::new(), Duration::from_millis(50), 84).expect("session");
    let without = plan_for(&mut plain, &program(), ISO);
    assert_eq!(plan.end().1, without.end().1 - 3775);
}

#[test]
fn a_reset_inside_the_compensated_contour_goes_back_to_its_start() {
    let device = PtyDevice::start().expect("pty");
    let client = Client::open(device.path(), Duration::from_secs(5)).expect("open");
    let mut sender = Sender::new(client, Duration::from_millis(300), 78).expect("session");
    // The contour alone, long enough that the in-process queue has started
    // its blocks when the reset comes.
    let mut text = String::from("G21 G18 G90 G94\nG00 X50 Z2\n");
    for _ in 0..3 {
        text += "G42 G01 X10 Z0 F200\nG01 Z-5\nG02 X20 Z-10 R5\nG01 X30\nG03 X36 Z-13 R3\nG01 Z-25\nG40 G00 X50\nG00 Z2\n";
    }
    let plan = plan_for(&mut sender, &text, ISO);
    let second_g42 = plan
        .lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.text.starts_with("G42"))
        .nth(1)
        .map(|(i, _)| i)
        .expect("a second G42");
    let mut op = Script {
        // Inside the second contour: its lines are compensated.
        keys: vec![(second_g42 + 4, Duration::ZERO, Key::Reset)],
        ..Script::default()
    };
    let report = sender.send(&plan, &mut op);
    assert!(report.halt.is_none(), "{:?}", report.halt);
    assert_eq!(report.resets, 1);
    assert_eq!(report.registers, Some(plan.end()));
    let said = op.said.join("\n");
    let restart: usize = said
        .split("restarting at line ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .expect(&said);
    // Never inside a compensated stretch.
    let line = plan
        .lines
        .iter()
        .find(|l| l.source == restart)
        .expect("a program line");
    assert!(!line.comp_before, "restarted at line {restart}: {said}");
}

#[test]
fn an_abort_stops_at_rest_and_says_where() {
    let device = PtyDevice::start().expect("pty");
    let client = Client::open(device.path(), Duration::from_secs(5)).expect("open");
    let mut sender = Sender::new(client, Duration::from_millis(300), 85).expect("session");
    let plan = plan_for(&mut sender, &program(), ISO);
    let mut op = Script {
        keys: vec![(60, Duration::ZERO, Key::Abort)],
        ..Script::default()
    };
    let report = sender.send(&plan, &mut op);
    let Some(host_sim::send::Halt::Aborted(at)) = report.halt else {
        panic!("{:?}", report.halt);
    };
    // The board stands where the abort left it, short of the program's end.
    assert_eq!(report.registers, Some(at));
    assert_ne!(Some(plan.end()), report.registers);
    assert!(plan.positions.contains(&at));
}

#[test]
fn a_program_stop_waits_for_cycle_start_without_asking_again() {
    let device = PtyDevice::start().expect("pty");
    let client = Client::open(device.path(), Duration::from_secs(5)).expect("open");
    let mut sender = Sender::new(client, Duration::from_millis(200), 86).expect("session");
    let text = program().replace("G42 G01", "M00\nG42 G01");
    let plan = plan_for(&mut sender, &text, ISO);
    let mut op = Script {
        // Longer than the request timeout: the stop is not a lost reply.
        resume_stop_after: Some(Duration::from_millis(1500)),
        ..Script::default()
    };
    let report = sender.send(&plan, &mut op);
    assert!(report.halt.is_none(), "{:?}", report.halt);
    assert_eq!(op.stops, 1);
    assert_eq!(report.retries, 0);
    assert_eq!(report.registers, Some(plan.end()));
}

#[test]
fn a_faulty_line_loses_nothing() {
    let link = FaultInjector::new(
        LocalLink::new(),
        Faults {
            flip: 0.0005,
            drop: 0.0003,
            dup: 0.0003,
            noise: 0.0,
            reset: 0.0,
        },
        1977,
    );
    let mut sender = Sender::new(link, Duration::from_millis(30), 79).expect("session");
    let text = program();
    let plan = plan_for(&mut sender, &text, ISO);
    let report = sender.send(&plan, &mut Script::default());
    assert!(report.halt.is_none(), "{:?}", report.halt);
    assert_eq!(report.registers, Some(plan.end()));
    let faults = sender.link_mut().stats;
    assert!(faults.requests_damaged + faults.replies_damaged > 0);
    assert!(
        report.retries + report.dropped > 0,
        "damaged lines must have been noticed"
    );
}

#[test]
fn a_line_the_board_refuses_is_named_before_anything_moves() {
    let mut sender = Sender::new(LocalLink::new(), Duration::from_millis(50), 80).expect("session");
    let text = "G21 G90\nG01 X10 Z-5 F100\nG01 X10 Q7\nG00 X20\n";
    let settings = board_settings(&mut sender).expect("settings");
    let plan = Plan::build(text, ISO, &settings, &[]).expect("plan");
    assert_eq!(plan.refused.len(), 1, "{:?}", plan.refused);
    assert_eq!(plan.refused[0].line, 3);
    assert!(plan.refused[0].reply.starts_with("ERR"));
}

#[test]
fn the_model_takes_the_boards_settings_and_position() {
    let mut link = LocalLink::new();
    for req in [
        "CFG HX=0.001 HZ=0.002",
        "TOOL N=2 X=-1.25 Z=0.5",
        "MOVE X=12 Z=-3 F=500",
    ] {
        link.send(format!("{req}\r\n").as_bytes()).expect("send");
        let _ = link.recv_line(Duration::from_millis(50));
    }
    let mut sender = Sender::new(link, Duration::from_millis(50), 81).expect("session");
    let settings = board_settings(&mut sender).expect("settings");
    assert!(settings
        .iter()
        .any(|s| s.starts_with("CFG HX=0.0010 HZ=0.0020")));
    assert!(settings.iter().any(|s| s == "ZERO X=12.0000 Z=-3.0000"));
    let plan = Plan::build("G90 G01 X14 Z-4 F100\n", ISO, &settings, &[]).expect("plan");
    // From X12 (diameter) Z-3 at 0.001/0.002 mm: one mm of radius and
    // 0.5 mm of Z.
    assert_eq!(plan.positions[0], (6000, -1500));
    assert_eq!(plan.end(), (7000, -2000));
    let report = sender.send(&plan, &mut Script::default());
    assert!(report.halt.is_none(), "{:?}", report.halt);
    assert_eq!(report.registers, Some((7000, -2000)));
}

/// The firmware in QEMU, its step interrupt in time: a real program with
/// a hold, a resume and a reset while it cuts.
#[test]
fn the_firmware_holds_resumes_and_restarts_after_a_reset() {
    if !host_sim::qemu::qemu_or_skip() {
        return;
    }
    let elf = host_sim::qemu::build_firmware("qemu-paced").expect("firmware");
    let mut qemu = host_sim::qemu::Qemu::boot_paced(&elf).expect("boot");
    let client = qemu.connect(Duration::from_secs(60)).expect("connect");
    let mut sender = Sender::new(client, Duration::from_millis(1000), 82).expect("session");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("examples/krylenko-fig22.nc")).expect("example");
    let fanuc = Options {
        dialect: Dialect::Fanuc,
        ..ISO
    };
    let plan = plan_for(&mut sender, &text, fanuc);
    let mut op = Script {
        keys: vec![
            (0, Duration::from_secs(5), Key::Hold),
            (0, Duration::from_secs(10), Key::Reset),
        ],
        resume_after_hold: Some(Duration::from_millis(1500)),
        ..Script::default()
    };
    let report = sender.send(&plan, &mut op);
    assert!(report.halt.is_none(), "{:?} {:?}", report.halt, op.said);
    assert!(op.states.iter().any(|s| s == "HOLD"), "{:?}", op.states);
    assert_eq!(report.resets, 1, "{:?}", op.said);
    assert_eq!(report.registers, Some(plan.end()));
    assert_eq!(report.starved, Some(0));
}

/// The E-stop pressed while `send` streams to a board in real time: the
/// sender stops at once, says what stopped it and where the axes stand (on
/// the program's path), and sends nothing more.
#[test]
fn an_estop_stops_the_stream_and_says_where() {
    use core_nostd::inputs::Input;
    struct Nowhere;
    impl core_nostd::protocol::Io for Nowhere {
        fn send(&mut self, _: &[u8]) {}
    }
    let mut device = core_nostd::protocol::Device::new();
    device.receive_bytes(b"INPUT USED=ESTOP FILTER=0\n", &mut Nowhere);
    let (path, board) =
        host_sim::board::serve_pty(device, host_sim::board::Pace::Wall(4.0)).expect("pty");
    let client = Client::open(&path, Duration::from_secs(5)).expect("open");
    let mut sender = Sender::new(client, Duration::from_millis(300), 87).expect("session");
    let plan = plan_for(&mut sender, &program(), ISO);
    let board = std::sync::Arc::new(board);
    let presser = {
        let board = std::sync::Arc::clone(&board);
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(1500));
            board.panel(Input::Estop.bit());
        })
    };
    let mut op = Script::default();
    let report = sender.send(&plan, &mut op);
    presser.join().expect("pressed");
    let Some(host_sim::send::Halt::Stopped(s)) = &report.halt else {
        panic!("{:?}", report.halt);
    };
    assert_eq!((s.code, s.input.as_str()), (10, "ESTOP"));
    assert_eq!(report.registers, Some(s.at));
    assert_ne!(Some(plan.end()), report.registers);
    assert!(plan.positions.contains(&s.at), "on the program's path");
    let said = report
        .halt
        .as_ref()
        .map(ToString::to_string)
        .unwrap_or_default();
    assert!(
        said.contains("the E-stop stopped the board (alarm 10, input ESTOP)"),
        "{said}"
    );
}

//! `host-sim run --machine FILE` on a real program (nhsd-cnc-lathe's
//! turn_two_diameters.nc, a LinuxCNC wood-turning program): the lathe's
//! carriages follow the step events; a limit switch, a drive's stall or
//! the end of a travel stops the program at the line whose move reaches
//! it, found here independently from the path the plain run traced.

use core_nostd::gcode::Dialect;
use core_nostd::inputs::Input;
use host_sim::lathe::MachineFile;
use host_sim::program::{run_machine, run_setup, MachineRun, Options, Report};
use std::path::PathBuf;

const OPTIONS: Options = Options {
    dialect: Dialect::Iso,
    radius: false,
    optional_stop: false,
};

fn program() -> String {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/nhsd-cnc-lathe");
    std::fs::read_to_string(root.join("turn_two_diameters.nc")).expect("program")
}

fn on_machine(machine: &str, setup: &[(usize, &str)]) -> (Report, MachineRun) {
    let m = MachineFile::parse(machine).expect("machine file");
    run_machine(&program(), OPTIONS, setup, &m)
}

/// The line of the first move of the plain run's path whose end reaches
/// `at` mm on `axis` (from below when `up`), starting at machine 0, and
/// whether that move is a straight line.
fn first_reaching(axis: usize, at: f64, up: bool) -> (usize, bool) {
    let plain = run_setup(&program(), OPTIONS, &[]);
    assert!(plain.refused.is_empty(), "{:?}", plain.refused);
    let at = (at * 1e7) as i64;
    let mut from = [0i64; 2];
    for m in &plain.path {
        let crosses = if up {
            from[axis] < at && m.to[axis] >= at
        } else {
            from[axis] > at && m.to[axis] <= at
        };
        if crosses {
            return (m.line, m.g <= 1);
        }
        from = m.to;
    }
    panic!("no move reaches {at} Å on axis {axis}");
}

#[test]
fn a_limit_stops_the_program_at_the_line_whose_move_trips_it() {
    let (line, straight) = first_reaching(1, 600.0, true);
    assert!(straight, "the move to the switch is a line");
    let machine = r#"
[z]
travel = [-10.0, 700.0]
[[z.switch]]
input = "Z+"
at = 600.0
hysteresis = 0.5
"#;
    let (report, run) = on_machine(machine, &[]);
    assert!(report.refused.is_empty(), "{:?}", report.refused);
    let trip = run.trip.expect("the switch stops the program");
    assert_eq!(trip.inputs, Input::LimitZPlus.bit());
    assert_eq!(trip.line, Some(line), "{trip:?}");
    // The carriage is on the switch: within one impulse (0.01 mm) past.
    assert!(
        (600.0 - 1e-6..600.01 + 1e-6).contains(&trip.carriage[1]),
        "{trip:?}"
    );
    assert!(trip.alarm.contains("ALARM CODE=1"), "{}", trip.alarm);
    assert!(trip.alarm.contains("INPUT=Z+"), "{}", trip.alarm);
    assert!(trip.lines_left > 0);
    // Nothing past the switch: the carriage went no further.
    assert!(run.range[1][1] <= 600.01 + 1e-6, "{:?}", run.range);
}

#[test]
fn the_end_of_a_travel_without_a_switch_stops_the_program_too() {
    let (line, _) = first_reaching(1, 500.0, true);
    let (_, run) = on_machine("[z]\ntravel = [-10.0, 500.0]\n", &[]);
    let trip = run.trip.expect("the carriage runs into the end");
    assert_eq!(trip.inputs, 0);
    assert_eq!(trip.line, Some(line), "{trip:?}");
    assert!(trip.alarm.is_empty(), "no switch told the board: {trip:?}");
    assert!(trip.carriage[1] > 500.0 && trip.carriage[1] <= 500.01 + 1e-6);
}

#[test]
fn a_drive_too_slow_for_the_rapids_stalls_and_stops_the_program() {
    // 2 000 impulses/s: 1 200 mm/min at 0.01 mm; the rapids go faster.
    let machine = "[z]\n[z.drive]\nmax_rate = 2000.0\n";
    let (_, run) = on_machine(machine, &[]);
    let trip = run.trip.expect("the Z drive stalls");
    assert_eq!(trip.inputs, Input::FaultZ.bit());
    assert!(trip.line.is_some(), "{trip:?}");
    assert!(trip.alarm.contains("INPUT=FAULTZ"), "{}", trip.alarm);
    // A fast enough drive: no stall.
    let (_, run) = on_machine("[z]\n[z.drive]\nmax_rate = 200000.0\n", &[]);
    assert!(run.trip.is_none(), "{:?}", run.trip);
}

/// The leadscrews' play: without compensation the carriages end off the
/// registers by the play of each axis whose last move went towards plus
/// (and on them otherwise); with `BACKLASH` set to the play, exactly on
/// them. And the run without a machine file is the same run.
#[test]
fn the_play_shows_where_the_carriages_end_unless_taken_up() {
    let machine = "[x]\nbacklash = 0.08\n[z]\nbacklash = 0.15\n";
    let (report, run) = on_machine(machine, &[]);
    assert!(run.trip.is_none());
    let plain = run_setup(&program(), OPTIONS, &[]);
    assert_eq!(report, plain, "the lathe changes nothing the board does");
    let off = [
        run.carriage[0] - run.registers[0],
        run.carriage[1] - run.registers[1],
    ];
    let mut some = false;
    for (d, play) in off.iter().zip([0.08, 0.15]) {
        assert!(d.abs() < 1e-9 || (d + play).abs() < 1e-9, "{off:?}");
        some |= d.abs() > 1e-9;
    }
    assert!(
        some,
        "the program ends moving towards plus on an axis: {off:?}"
    );
    let (_, run) = on_machine(machine, &[(1, "BACKLASH X=0.08 Z=0.15")]);
    for a in 0..2 {
        assert!(
            (run.carriage[a] - run.registers[a]).abs() < 1e-9,
            "{:?} {:?}",
            run.carriage,
            run.registers
        );
    }
}

/// `serve --machine` with a spindle and its encoder: the panel's `STATE?`
/// gives the speed the encoder measures (the top, not the `S` above it)
/// and counts that advance at that speed, and stand still once stopped.
#[test]
fn the_panel_reads_the_spindle_by_its_encoder() {
    use host_sim::board::Pace;
    let file = "[spindle]\nmax_rpm = 2000.0\nripple = 0.02\n[spindle.encoder]\ncpr = 4096\n";
    let (board, mut c) = tests::lathe_board_paced(file, "", false, Pace::Unpaced);
    let read = |board: &host_sim::board::Board| {
        let state = board.panel_line("STATE?").expect("state").expect("a line");
        let v = |k: &str| -> f64 {
            host_sim::link::words_value(&state, k)
                .and_then(|v| v.parse().ok())
                .expect(&state)
        };
        (v("S"), v("ENC"), std::time::Instant::now())
    };
    assert_eq!(read(&board).0, 0.0);
    let r = tests::ask(&mut c, "M3 S3000");
    assert!(r.is_ok(), "{r:?}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (s, n0, t0) = read(&board);
    // The ripple (±2 %) within the encoder's 0.1 s window.
    assert!((s - 2000.0).abs() <= 2000.0 * 0.03, "S={s}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (_, n1, t1) = read(&board);
    let expected = 2000.0 / 60.0 * 4096.0 * (t1 - t0).as_secs_f64();
    assert!(
        ((n1 - n0) - expected).abs() <= expected * 0.1,
        "{n0} → {n1}, {expected} expected"
    );
    assert!(tests::ask(&mut c, "M5").is_ok());
    let (s, n2, _) = read(&board);
    std::thread::sleep(std::time::Duration::from_millis(100));
    let (_, n3, _) = read(&board);
    assert_eq!((s, n2), (0.0, n3), "stopped");
}

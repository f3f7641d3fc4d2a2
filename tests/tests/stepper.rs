//! A transport with a stepper of its own, as a board's step interrupt:
//! started motion is taken and issued later, a few events at a time while
//! requests keep arriving, and a full stepper makes the request wait. The
//! device must report exactly what the virtual clock reports: the same
//! replies, the same `SYNC` (`EV`, `T`, `TSEQ`), and `STATUS` registers
//! that are those of the steps actually issued.

use core_nostd::interleave::{ImpulsePoint, StepEvent};
use core_nostd::machine::Background;
use core_nostd::protocol::{Device, Io};
use core_nostd::step::Record;
use core_nostd::stepdir::DriveTiming;
use core_nostd::stepper::{Aborted, AxesState, Item, Pulled, Stepper, AHEAD};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The virtual clock: every event issued at once.
#[derive(Default)]
struct Now {
    lines: Vec<String>,
    events: Vec<(u8, u64)>,
}

impl Io for Now {
    fn send(&mut self, line: &[u8]) {
        self.lines.push(String::from_utf8_lossy(line).into_owned());
    }
    fn step(&mut self, event: StepEvent, tick: u64, _: &DriveTiming) {
        self.events.push((event.bits(), tick));
    }
}

/// A stepper of the transport's own, pulled only when the "interrupt"
/// runs: when a request must wait for room, and between requests.
struct Later {
    stepper: Stepper<AHEAD>,
    lines: Vec<String>,
    events: Vec<(u8, u64)>,
    /// Items a request had to wait for.
    waits: usize,
}

impl Later {
    fn new() -> Later {
        Later {
            stepper: Stepper::new(),
            lines: Vec::new(),
            events: Vec::new(),
            waits: 0,
        }
    }

    /// The step interrupt runs `n` times.
    fn run(&mut self, n: usize) {
        for _ in 0..n {
            match self.stepper.pull() {
                Some(Pulled::Step(e, tick)) => self.events.push((e.bits(), tick)),
                Some(_) => {}
                None => break,
            }
        }
    }
}

impl Io for Later {
    fn send(&mut self, line: &[u8]) {
        self.lines.push(String::from_utf8_lossy(line).into_owned());
    }
    fn background(&mut self) -> Option<&mut dyn Background> {
        Some(self)
    }
}

impl Background for Later {
    fn start(&mut self, item: Item, _: &DriveTiming) {
        while !self.stepper.has_room() {
            self.waits += 1;
            self.run(1);
        }
        // Room was made.
        self.stepper.push(item).unwrap();
    }
    fn drain(&mut self) {
        self.run(usize::MAX);
    }
    fn issued(&mut self) -> ImpulsePoint {
        self.stepper.issued()
    }
    fn lash(&mut self) -> [i32; 2] {
        self.stepper.lash()
    }
    fn set_issued(&mut self, registers: ImpulsePoint) {
        self.stepper.set_issued(registers);
    }
    fn take_record(&mut self) -> Record {
        self.stepper.take_record()
    }
    fn hold(&mut self) {
        self.stepper.hold();
    }
    fn resume(&mut self) {
        let _ = self.stepper.resume();
    }
    fn abort(&mut self) -> Aborted {
        self.stepper.abort()
    }
    fn motion(&mut self) -> AxesState {
        self.stepper.motion()
    }
    fn hungry(&mut self) -> bool {
        // Requests are not answered in time here: blocks start as on the
        // virtual clock.
        false
    }
}

fn request(dev: &mut Device, io: &mut impl Io, line: &str) {
    dev.receive_bytes(line.as_bytes(), io);
    dev.receive_bytes(b"\n", io);
}

/// `KEY=` of a reply line.
fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split(['*', ' '])
        .find_map(|w| w.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
}

fn mm(rng: &mut ChaCha8Rng, range: i64) -> String {
    let um = rng.random_range(-range..=range);
    format!("{}.{:03}", um / 1000, (um % 1000).abs()).replace("0.-", "-0.")
}

fn random_line(rng: &mut ChaCha8Rng) -> String {
    match rng.random_range(0..100) {
        0..=44 => {
            let f = if rng.random_bool(0.8) {
                format!(" F={}", rng.random_range(20..3000))
            } else {
                String::new()
            };
            format!("MOVE X={} Z={}{f}", mm(rng, 10_000), mm(rng, 10_000))
        }
        45..=59 => format!(
            "G01 X{} Z{} F{}",
            mm(rng, 10_000),
            mm(rng, 10_000),
            rng.random_range(50..2000)
        ),
        60..=67 => format!("G00 X{} Z{}", mm(rng, 10_000), mm(rng, 10_000)),
        // A full circle by chords from where the tool is (G91: the end is
        // the start), then absolute words again.
        68..=73 => format!("G91 G03 X0 Z0 I{} K0 F400", rng.random_range(1..=6)),
        74..=77 => "SYNC".into(),
        78..=85 => "STATUS".into(),
        86..=88 => "POS".into(),
        89 => "ZERO".into(),
        90 => "LIMITS AX=80".into(),
        91 => "LIMITS AX=100".into(),
        92 => "CFG HZ=0.005".into(),
        93 => "CFG HZ=0.01".into(),
        _ => format!(
            "MOVE X={} INC=1 F={}",
            mm(rng, 300),
            rng.random_range(100..600)
        ),
    }
}

/// The steps of `events` per axis.
fn steps(events: &[(u8, u64)]) -> (i64, i64) {
    events.iter().fold((0, 0), |(x, z), &(b, _)| {
        let d = |step: u8, neg: u8| match (b & step != 0, b & neg != 0) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => -1,
        };
        (x + d(1, 4), z + d(2, 8))
    })
}

fn int(line: &str, key: &str) -> i64 {
    field(line, key).unwrap().parse().unwrap()
}

#[test]
fn a_stepper_of_its_own_reports_what_the_virtual_clock_does() {
    let mut rng = ChaCha8Rng::seed_from_u64(1977);
    let (mut a, mut b) = (Device::new(), Device::new());
    let (mut now, mut later) = (Now::default(), Later::new());
    let (mut syncs, mut statuses, mut behind) = (0, 0, 0);
    // Events of the stepper compared with the virtual clock's so far.
    let mut checked = 0;
    for k in 0..3000 {
        let mut lines = vec![if k % 500 == 499 {
            "SYNC".to_string()
        } else {
            random_line(&mut rng)
        }];
        if lines[0].starts_with("G91") {
            lines.push("G90".into());
        }
        for line in lines {
            let (na, nb) = (now.lines.len(), later.lines.len());
            request(&mut a, &mut now, &line);
            request(&mut b, &mut later, &line);
            let (ra, rb) = (&now.lines[na..], &later.lines[nb..]);
            assert_eq!(ra.len(), rb.len(), "{line}: {ra:?} {rb:?}");
            // What the stepper issued is what the virtual clock issued,
            // so far.
            let n = later.events.len();
            assert_eq!(&now.events[checked..n], &later.events[checked..], "{line}");
            checked = n;
            for (x, y) in ra.iter().zip(rb) {
                if line != "STATUS" {
                    assert_eq!(x, y, "{line}");
                    continue;
                }
                // Where the axes are: the virtual clock has issued every
                // started block, the stepper as far as it has run.
                assert_eq!(field(x, "Q"), field(y, "Q"));
                assert_eq!(field(x, "STATE"), field(y, "STATE"));
                let (dx, dz) = steps(&now.events[n..]);
                assert_eq!(
                    (int(y, "PX"), int(y, "PZ")),
                    (int(x, "PX") - dx, int(x, "PZ") - dz),
                    "{y} vs {x}"
                );
                statuses += 1;
                behind += usize::from(n < now.events.len());
            }
            if line == "SYNC" {
                syncs += 1;
                assert_eq!(now.events.len(), later.events.len(), "events up to a SYNC");
            }
        }
        // The step interrupt runs a while between requests.
        later.run(rng.random_range(0..400));
    }
    request(&mut a, &mut now, "SYNC");
    request(&mut b, &mut later, "SYNC");
    assert_eq!(now.lines.last(), later.lines.last());
    assert_eq!(now.events, later.events);
    assert!(syncs >= 6, "{syncs} SYNCs compared");
    assert!(
        behind >= 20,
        "{behind} of {statuses} STATUS lines while the stepper was behind"
    );
    assert!(later.waits > 0, "no request ever waited for room");
    assert!(now.events.len() > 100_000, "{} events", now.events.len());
    println!(
        "{} events, {syncs} SYNC, {behind} of {statuses} STATUS while behind, {} waits",
        now.events.len(),
        later.waits
    );
}

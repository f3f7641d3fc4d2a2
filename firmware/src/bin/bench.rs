//! Instruction counts of the motion path on the Cortex-M4, under QEMU.
//!
//! Run by `host-sim qemu-bench` with `-icount shift=0`: every instruction
//! advances QEMU's virtual clock by 1 ns, and TIM2, free-running at QEMU's
//! 1 GHz timer clock with no prescaler, counts one tick per nanosecond; so a
//! difference of TIM2 counts is a count of instructions. Prints one line per
//! measurement and exits through semihosting.
#![no_std]
#![no_main]

use core::fmt::Write;
use core_nostd::cycle::{Along, Roughing, Segment, PROFILE_BLOCKS};
use core_nostd::impulse::Impulses;
use core_nostd::interleave::{ImpulsePoint, LinearBlock};
use core_nostd::protocol::{Device, Io};
use core_nostd::stepdir::{DriveTiming, StepDir, TickClock};
use cortex_m_rt::entry;
use embedded_hal::delay::DelayNs;
use firmware::board::{PortCPin, StepTimer};
use firmware::halt;
use firmware::step::StepIsr;

/// A line of text for the host.
struct Line(heapless::String<256>);

impl Line {
    fn print(args: core::fmt::Arguments<'_>) {
        let mut l = Line(heapless::String::new());
        let _ = l.0.write_fmt(args);
        let _ = l.0.push('\n');
        #[cfg(feature = "qemu")]
        firmware::log::host_print(format_args!("{}", l.0));
    }
}

/// No pacing and no pulse delays: what remains is the code's own cost.
struct Free;
impl TickClock for Free {
    fn start_run(&mut self) {}
    fn wait_until(&mut self, _: u64) {}
}
impl DelayNs for Free {
    fn delay_ns(&mut self, _: u32) {}
}

/// Replies are counted, not sent.
struct Quiet(u32);
impl Io for Quiet {
    fn send(&mut self, line: &[u8]) {
        self.0 = self.0.wrapping_add(line.len() as u32);
    }
}

fn measure(tim: &StepTimer, f: impl FnOnce()) -> u32 {
    let t0 = tim.count();
    f();
    tim.count().wrapping_sub(t0)
}

/// The contour engine per compensated block (Krylenko Fig. 22 and a taper),
/// and whole G-code requests with G42 on.
fn compensation(tim: &StepTimer) {
    use core_nostd::arc::ArcDir;
    use core_nostd::comp::TipCode;
    use core_nostd::comp::{Contour, Element, Shape, Tool};
    use core_nostd::gcode::Compensation;
    use core_nostd::length::Length;
    let um = |v: i64| v * 10_000;
    let p = |x: i64, z: i64| [um(x), um(z)];
    let line = |a, b| Element::line(a, b, false, None);
    let arc = |a, b, c, dir| Element {
        from: a,
        to: b,
        shape: Shape::Arc { centre: c, dir },
        n: None,
    };
    let contour = [
        line(p(0, 0), p(4_000, 0)),
        arc(p(4_000, 0), p(6_000, -2_000), p(4_000, -2_000), ArcDir::Ccw),
        line(p(6_000, -2_000), p(6_000, -14_000)),
        arc(
            p(6_000, -14_000),
            p(9_000, -17_000),
            p(9_000, -14_000),
            ArcDir::Cw,
        ),
        line(p(9_000, -17_000), p(15_000, -17_000)),
        arc(
            p(15_000, -17_000),
            p(19_000, -21_000),
            p(15_000, -21_000),
            ArcDir::Ccw,
        ),
        line(p(19_000, -21_000), p(19_000, -30_000)),
        line(p(19_000, -30_000), p(24_000, -35_000)),
        line(p(24_000, -35_000), p(24_000, -40_000)),
    ];
    let Some(rn) = Length::from_um(400) else {
        return;
    };
    let tool = Tool::new(rn, TipCode::EXTERNAL_RIGHT);
    let Ok((mut c, _)) = Contour::new().block(
        &tool,
        Some(Compensation::Right),
        None,
        Some(line(p(0, 2_000), p(0, 0))),
    ) else {
        return;
    };
    let mut worst = 0;
    let mut total = 0;
    for e in &contour {
        let mut next = None;
        let t = measure(tim, || next = c.block(&tool, None, None, Some(*e)).ok());
        let Some((n, _)) = next else { return };
        c = n;
        worst = worst.max(t);
        total += t;
    }
    Line::print(format_args!(
        "contour engine: {} instructions per compensated block on average, {worst} at most ({} blocks: lines, arcs, inside and outside corners)",
        total / contour.len() as u32,
        contour.len()
    ));
    let mut dev = Device::new();
    let mut quiet = Quiet(0);
    dev.receive_bytes(b"G00 X20 Z2\r\nG42 G01 Z0 F200\r\nX28\r\n", &mut quiet);
    let t = measure(tim, || dev.receive_bytes(b"X48 Z-10\r\n", &mut quiet));
    Line::print(format_args!(
        "G-code request with G42 (taper, its motion sent with the next block): {t} instructions"
    ));
    let t = measure(tim, || dev.receive_bytes(b"Z-10.5\r\n", &mut quiet));
    Line::print(format_args!(
        "G-code request with G42 (short cylinder, sends the 10 mm taper's 2 047 events): {t} instructions"
    ));
}

/// Pulls every timed event of `t` as the step interrupt will, in a frame
/// of its own (the planners of the caller's frame put its locals beyond
/// the reach of short offsets); returns the events.
#[inline(never)]
fn drain(t: &core_nostd::step::TimedBlock, sink: &mut u32) -> u32 {
    let mut n = 0u32;
    for (e, tick) in t.events() {
        *sink = sink
            .wrapping_add(u32::from(e.bits()))
            .wrapping_add(tick as u32);
        n += 1;
    }
    n
}

/// The planner and the timed step generator on blocks along Z at the
/// default limits (3000 mm/min, 150 mm/s², 0.01 mm per impulse).
#[inline(never)]
fn timed(tim: &StepTimer) -> Option<[core_nostd::plan::Started; 3]> {
    use core_nostd::impulse::{quantize, ImpulsePrice};
    use core_nostd::length::Length;
    use core_nostd::plan::{q32, Block, Feed, Planner, Rates, WINDOW};
    use core_nostd::stepper::{Item, Pulled, Stepper, AHEAD};
    let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
    let rates = Rates::DEFAULT;
    let mm = |um: i64| Length::from_um(um).unwrap_or(Length::ZERO);
    let at = |z: Length| ImpulsePoint {
        x: Impulses(0),
        z: quantize(z, h[1]).unwrap_or(Impulses(0)),
    };
    let block = |from_um: i64, to_um: i64| {
        let (a, b) = (mm(from_um), mm(to_um));
        let events = LinearBlock::new(at(a), at(b)).ok()?;
        Block::new([0, q32(a)], [0, q32(b)], events, None, h, &rates)
    };
    let mut sink = 0u32;
    let mut run = |t: &core_nostd::step::TimedBlock| {
        let mut n = 0u32;
        let c = measure(tim, || n = drain(t, &mut sink));
        (c, n.max(1))
    };
    // Ramps from and to rest: 5 mm from rest to rest (a triangle, the
    // interval changing fastest), and the ramps of a long rapid: 8 mm
    // accelerating from rest and 8 mm braking to rest around 400 mm of
    // cruise (3000 mm/min needs 8.3 mm at 150 mm/s²).
    let mut p = Planner::<WINDOW>::new(WINDOW);
    let b = block(0, -5_000)?;
    let _ = p.push(b, &rates);
    let t = p.start(&rates)?;
    let (c, n) = run(&t);
    Line::print(format_args!(
        "timed step events, 5 mm triangle from rest to rest: {n} events, {}.{:02} instructions per event",
        c / n,
        (c % n) * 100 / n
    ));
    let mut p = Planner::<WINDOW>::new(WINDOW);
    for (a, b) in [(0, -8_000), (-8_000, -408_000), (-408_000, -416_000)] {
        let b = block(a, b)?;
        let _ = p.push(b, &rates);
    }
    let (Some(sa), Some(sb), Some(sc)) = (
        p.start_block(&rates),
        p.start_block(&rates),
        p.start_block(&rates),
    ) else {
        return None;
    };
    let (ca, na) = run(sa.timed());
    let (cb, nb) = run(sb.timed());
    let (cc, nc) = run(sc.timed());
    let (c, n) = (ca.wrapping_add(cc), na.saturating_add(nc).max(1));
    Line::print(format_args!(
        "timed step events, ramps (8 mm from rest, 8 mm to rest): {n} events, {}.{:02} instructions per event",
        c / n,
        (c % n) * 100 / n
    ));
    Line::print(format_args!(
        "timed step events, cruise (400 mm at 3000 mm/min, 99.8 % cruise): {nb} events, {}.{:02} instructions per event ({sink})",
        cb / nb,
        (cb % nb) * 100 / nb
    ));
    let started = [sa, sb, sc];
    // A feed hold in the middle of the cruise: what acting on it costs
    // (the real-time task, at the prep's priority), and how soon the
    // events slow down.
    let mut s = Stepper::<AHEAD>::new();
    let _ = s.push(Item::RunStart);
    let _ = s.push(Item::Block(sb));
    let mut ticks = [0u64; 3];
    let mut pulled = 0u32;
    while pulled < 20_000 {
        if let Some(Pulled::Step(_, t)) = s.pull() {
            ticks = [ticks[1], ticks[2], t];
            pulled += 1;
        }
    }
    let cruise = ticks[2].saturating_sub(ticks[1]);
    let mut plain = s.clone();
    let c = measure(tim, || s.hold());
    // The event the interrupt has already armed goes at its tick; count the
    // events after the hold until one comes later than it would have
    // without the hold.
    let mut k = 0u32;
    while let (Some(p), Some(q)) = (s.pull(), plain.pull()) {
        if let (Pulled::Step(_, t), Pulled::Step(_, u)) = (p, q) {
            k += 1;
            if t > u {
                break;
            }
        }
    }
    Line::print(format_args!(
        "feed hold at cruise (3000 mm/min, 150 mm/s²): {c} instructions to act on it (real-time task, prep's priority; no longer in the receive interrupt); the events after it first leave the plan's 1 µs ticks at event {k} ({cruise} ticks apart)"
    ));
    // Planning: short blocks along a polygon (chords of a circle at F600),
    // the window full: making the block, its junction, queueing it and
    // starting the one 64 blocks before (backward pass, trapezoid, timing).
    let feed = Feed::new(mm(600_000));
    let mut p = Planner::<WINDOW>::new(WINDOW);
    let mut z = 0i64;
    let mut x = 0i64;
    let (mut total, mut count) = (0u32, 0u32);
    for k in 0..200i64 {
        let (dx, dz) = (((k * 37) % 11 - 5) * 100, -500);
        let (from, to) = ([mm(x), mm(z)], [mm(x + dx), mm(z + dz)]);
        let pt = |p: [Length; 2]| ImpulsePoint {
            x: quantize(p[0], h[0]).unwrap_or(Impulses(0)),
            z: quantize(p[1], h[1]).unwrap_or(Impulses(0)),
        };
        let Ok(events) = LinearBlock::new(pt(from), pt(to)) else {
            return None;
        };
        let c = measure(tim, || {
            if let Some(b) = Block::new(
                [q32(from[0]), q32(from[1])],
                [q32(to[0]), q32(to[1])],
                events,
                feed,
                h,
                &rates,
            ) {
                let _ = p.push(b, &rates);
            }
            if p.window_full() {
                let _ = p.start(&rates);
            }
        });
        if k >= WINDOW as i64 {
            total = total.wrapping_add(c);
            count += 1;
        }
        (x, z) = (x + dx, z + dz);
    }
    Line::print(format_args!(
        "planned block (made, queued, its window planned, started): {} instructions on average over {count}",
        total / count.max(1)
    ));
    Some(started)
}

fn arcs(tim: &StepTimer) {
    use core_nostd::arc::{ArcDir, ArcPoints, ChordPlan, DirectArc};
    use core_nostd::impulse::ImpulsePrice;
    use core_nostd::length::Length;
    let mm = |a: i64| Length::from_angstrom(a * 10_000).unwrap_or(Length::ZERO);
    let (hx, hz) = (ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z);
    // Full circle R 37.5 mm at σ 0.001 mm; quadrant R 60 mm for direct steps.
    let p = ArcPoints {
        start: [mm(37_500), mm(-20_000)],
        end: [mm(37_500), mm(-20_000)],
        centre: [mm(0), mm(-20_000)],
    };
    let mut plan = None;
    let t = measure(tim, || {
        plan = ChordPlan::new(&p, ArcDir::Ccw, mm(1), true).ok()
    });
    let Some(plan) = plan else { return };
    Line::print(format_args!(
        "chord plan: {t} instructions ({} chords)",
        plan.chords()
    ));
    let n = plan.chords();
    let mut acc = 0i32;
    let t = measure(tim, || {
        for i in 1..=n {
            if let Ok(e) = plan.chord_end(i, hx, hz) {
                acc = acc.wrapping_add(e.x.get());
            }
        }
    });
    Line::print(format_args!(
        "chord end: {} instructions per chord ({acc})",
        t / n.max(1)
    ));
    // The longest arc the protocol takes, checked whole before its first
    // chord moves: a semicircle of R 400 mm at σ 0.000005 mm, 9 970 chords.
    // The main loop's longest stretch without a heartbeat (the watchdog
    // supervisor allows 2 s).
    let long = ArcPoints {
        start: [mm(500_000), mm(-618_030)],
        end: [mm(500_000), mm(-1_418_030)],
        centre: [mm(500_000), mm(-1_018_030)],
    };
    let sigma = Length::from_angstrom(50).unwrap_or(Length::ZERO);
    let mut chords = 0;
    let t = measure(tim, || {
        if let Ok(plan) = ChordPlan::new(&long, ArcDir::Cw, sigma, true) {
            chords = plan.chords();
            for i in 1..=chords {
                if plan.chord_end(i, hx, hz).is_err() {
                    break;
                }
            }
        }
    });
    Line::print(format_args!(
        "whole-arc check of the longest arc: {t} instructions ({chords} chords)"
    ));
    let q = ArcPoints {
        start: [mm(0), mm(60_000)],
        end: [mm(60_000), mm(0)],
        centre: [mm(0), mm(0)],
    };
    let from = ImpulsePoint {
        x: Impulses(0),
        z: Impulses(6000),
    };
    let Ok(arc) = DirectArc::new(&q, ArcDir::Ccw, from, hx, hz) else {
        return;
    };
    let mut events = 0u32;
    let mut sink = 0u32;
    let t = measure(tim, || {
        for e in arc.events() {
            events += 1;
            sink = sink.wrapping_add(u32::from(e.bits()));
        }
    });
    Line::print(format_args!(
        "direct arc: {events} step events, {}.{:02} instructions per event ({sink})",
        t / events.max(1),
        (t % events.max(1)) * 100 / events.max(1)
    ));
}

/// The G-code reader alone: a CAM-style Fanuc program's blocks.
fn reader(tim: &StepTimer) {
    use core_nostd::gcode::{parse, Dialect, Units};
    const LINES: [&str; 8] = [
        "N100 G00 X30. Z2. M08",
        "N110 G96 S180 M03",
        "N120 G01 Z-12.25 F.2",
        "N130 X34.5 W-1.75 (CHAMFER)",
        "N140 G02 U6. W-3. R3.",
        "N150 G01 Z-40.",
        "N160 G28 U0 W0",
        "N170 T0202 M05 M09",
    ];
    let mut read = 0u32;
    let t = measure(tim, || {
        for line in LINES {
            read += u32::from(parse(line, Dialect::Fanuc, Units::Mm).is_ok());
        }
    });
    Line::print(format_args!(
        "G-code reader: {read} Fanuc blocks, {} instructions per block",
        t / 8
    ));
}

/// The calculators' requests, each in full: parsing, the f64 arithmetic
/// (soft double precision: the M4's FPU is single precision) and every
/// reply line.
fn calculators(tim: &StepTimer) {
    let mut dev = Device::new();
    for request in [
        &b"THREAD P=1.5\r\n"[..],
        b"WEAR D=40 L=120 S=0.2 U0=5 UR=8 Q=50 ALLOW=20 TOL=50 FULL=300 H=0.5 ALPHA=8\r\n",
        b"DEFLECT D=29.8,21.8 L=100,150 T=0.5 HB=220 J=4000,3000,10000 DX=10\r\n",
        b"DEFLECT D=29.8,21.8 L=100,150 T=0.5 HB=220 J=4000,3000,10000 DX=10 G=1\r\n",
        b"TRI AOB=90 BOC=90 COA=90 ROWS=10\r\n",
        b"TRI AOB=75 BOC=80 OB=97.9824 ROWS=10 G=1\r\n",
        b"TAPE FRAME=2K002E212400D630000P75W26H\r\n",
        b"TAPE END\r\n",
    ] {
        let mut quiet = Quiet(0);
        let t = measure(tim, || dev.receive_bytes(request, &mut quiet));
        let text = core::str::from_utf8(request).unwrap_or("?").trim_end();
        Line::print(format_args!(
            "calculator {text}: {t} instructions, {} reply bytes",
            quiet.0
        ));
    }
}

/// The roughing's passes of the staircase: the levels of 1 mm from the
/// start's radius (20 mm) short of the profile's deepest point (7 mm).
fn r_levels(segments: &[Segment]) -> u32 {
    let deepest = segments.iter().map(|g| g.to[0]).min().unwrap_or(0);
    ((200_000_000 - deepest - 1) / 10_000_000) as u32
}

/// Replies counted by kind: bytes, and the `DATA` lines (a cycle's
/// moves).
struct Moves {
    bytes: u32,
    moves: u32,
}
impl Io for Moves {
    fn send(&mut self, line: &[u8]) {
        self.bytes = self.bytes.wrapping_add(line.len() as u32);
        if line.starts_with(b"DATA G") {
            self.moves += 1;
        }
    }
}

/// The turning cycles (`G71` roughing, `G73` pattern repeating): each
/// profile block as it is held, and the block `Q` whose reply is the whole
/// roughing, every move planned and checked, then run (queued, its `SEQ`
/// over every event, the queue drained as it fills). The longest profile
/// is 128 blocks: a staircase of 63 steps.
fn cycles(tim: &StepTimer) {
    let mut quiet = Moves { bytes: 0, moves: 0 };
    let mut dev = Device::new();
    for line in [
        &b"OPT DIALECT=FANUC\r\n"[..],
        b"G21 G18 G98\r\n",
        b"G00 X40. Z2.\r\n",
        b"SYNC\r\n",
    ] {
        dev.receive_bytes(line, &mut quiet);
    }
    // Fanuc's two blocks, the stepped shaft of docs/cycles.md section 9.
    let rough = |dev: &mut Device, head: &[&[u8]], profile: &mut dyn Iterator<Item = Line>| {
        let mut quiet = Moves { bytes: 0, moves: 0 };
        for line in head {
            dev.receive_bytes(line, &mut quiet);
        }
        let (mut held, mut blocks, mut last) = (0u32, 0u32, 0u32);
        let mut lines = profile.peekable();
        while let Some(line) = lines.next() {
            let bytes = line.0.as_bytes();
            if lines.peek().is_none() {
                quiet.moves = 0;
                last = measure(tim, || dev.receive_bytes(bytes, &mut quiet));
            } else {
                held += measure(tim, || dev.receive_bytes(bytes, &mut quiet));
                blocks += 1;
            }
        }
        let moves = quiet.moves;
        dev.receive_bytes(b"SYNC\r\n", &mut quiet);
        (held / blocks.max(1), blocks + 1, last, moves)
    };
    let text = |t: &str| {
        let mut l = Line(heapless::String::new());
        let _ = l.0.push_str(t);
        let _ = l.0.push_str("\r\n");
        l
    };
    let (per_block, blocks, q, moves) = rough(
        &mut dev,
        &[b"G71 U2. R.5\r\n", b"G71 P10 Q30 U.4 W.2 F300.\r\n"],
        &mut ["N10 G00 X20.", "N20 G01 Z-30. F100.", "N30 X40."]
            .into_iter()
            .map(text),
    );
    Line::print(format_args!(
        "cycle G71 (stepped shaft, 4 passes and the pass along the profile): {per_block} instructions per held block ({blocks} blocks), block Q {q} instructions for {moves} moves, {} per pass",
        q / 5
    ));
    // The longest profile: 128 blocks, a staircase of 63 steps of 0.2 mm
    // on the radius and 1 mm along Z.
    let mut n = 0u32;
    let mut stairs = core::iter::from_fn(|| {
        n += 1;
        let mut l = Line(heapless::String::new());
        let k = n / 2;
        let _ = match n {
            1 => write!(l.0, "N10 G00 X14.\r\n"),
            128 => write!(l.0, "N20 G01 X40.\r\n"),
            _ if n.is_multiple_of(2) => write!(l.0, "G01 Z-{k}.\r\n"),
            _ => write!(l.0, "X{}.{}\r\n", 14 + (4 * k) / 10, (4 * k) % 10),
        };
        (n <= 128).then_some(l)
    });
    let (per_block, blocks, q, moves) = rough(
        &mut dev,
        &[b"G00 X40. Z2.\r\n", b"G71 P10 Q20 D1. U.4 W.2 F300.\r\n"],
        &mut stairs,
    );
    Line::print(format_args!(
        "cycle G71 (the longest profile, a staircase): {per_block} instructions per held block ({blocks} blocks), block Q {q} instructions for {moves} moves (their step events run through the device's own stepper)",
    ));
    // The passes' geometry alone: the same staircase (Å, X on the radius),
    // every move of the roughing computed once, as the check and the run
    // each do.
    let mut segments = heapless::Vec::<Segment, PROFILE_BLOCKS>::new();
    let mut at = [70_000_000i64, 0];
    for k in 1..=63i64 {
        at[1] = -k * 10_000_000;
        let _ = segments.push(Segment { to: at, arc: None });
        at[0] = 70_000_000 + k * 2_000_000;
        let _ = segments.push(Segment { to: at, arc: None });
    }
    at[0] = 200_000_000;
    let _ = segments.push(Segment { to: at, arc: None });
    let mut steps = 0u32;
    let t = measure(tim, || {
        if let Ok(r) = Roughing::new(
            Along::Z,
            [200_000_000, 20_000_000],
            [72_000_000, 2_000_000],
            &segments,
            10_000_000,
            5_000_000,
        ) {
            r.steps(&mut |_| steps += 1);
        }
    });
    let passes = r_levels(&segments);
    Line::print(format_args!(
        "cycle G71 geometry (the staircase, {} elements): {t} instructions for {steps} moves in {passes} passes, {} per pass, {} per move",
        segments.len(),
        t / passes.max(1),
        t / steps.max(1)
    ));
    let (per_block, blocks, q, moves) = rough(
        &mut dev,
        &[
            b"G00 X50. Z4.\r\n",
            b"G73 U3. W1. R3\r\n",
            b"G73 P10 Q40 U.4 W.2 F200.\r\n",
        ],
        &mut [
            "N10 G00 X20. Z0",
            "N20 G01 Z-20. F100.",
            "N30 G02 X40. Z-30. I10. K0",
            "N40 G01 X48.",
        ]
        .into_iter()
        .map(text),
    );
    Line::print(format_args!(
        "cycle G73 (3 passes of a line, an arc and a line): {per_block} instructions per held block ({blocks} blocks), block Q {q} instructions for {moves} moves, {} per pass",
        q / 3
    ));
}

#[entry]
fn main() -> ! {
    let mut b = firmware::boot();
    // Nothing interrupts the measurements: the alarm and the pends the
    // step interrupt's code makes stay pending.
    cortex_m::interrupt::disable();
    b.tim2.free_run();
    let tim = &b.tim2;

    let empty = measure(tim, || {});
    // Calibration: `asm::delay(n)` runs a known loop.
    let delay = measure(tim, || cortex_m::asm::delay(100_000)).wrapping_sub(empty);
    Line::print(format_args!(
        "calibration: delay(100000) = {delay} ticks, empty = {empty}"
    ));
    // What one peripheral register access costs in QEMU's count (it ends
    // a translation block, which is counted again): 1000 reads of TIM2.
    let reads = measure(tim, || {
        for _ in 0..1000 {
            core::hint::black_box(tim.count());
        }
    });
    Line::print(format_args!(
        "calibration: a peripheral register read counts {}.{} instructions under -icount (1000 reads: {reads})",
        reads / 1000,
        (reads % 1000) / 100
    ));

    let p = |x, z| ImpulsePoint {
        x: Impulses(x),
        z: Impulses(z),
    };
    let Ok(block) = LinearBlock::new(p(0, 0), p(100_000, -61_803)) else {
        halt()
    };
    let n = (block.events().len() as u32).max(1);

    let mut sink = 0u32;
    let t = measure(tim, || {
        for e in block.events() {
            sink = sink.wrapping_add(u32::from(e.bits()));
        }
    });
    Line::print(format_args!(
        "interleaver: {n} events, {t} instructions, {}.{:02} per event ({sink})",
        t / n,
        (t % n) * 100 / n
    ));

    reader(tim);

    let mut axes = StepDir::new(PortCPin(0), PortCPin(1), PortCPin(2), PortCPin(3));
    let timing = DriveTiming::DEFAULT;
    let t = measure(tim, || {
        for (i, e) in block.events().enumerate() {
            let _ = axes.issue(e, i as u64, &timing, &mut Free, &mut Free);
        }
    });
    Line::print(format_args!(
        "step/dir outputs (GPIO writes, no waits): {t} instructions, {}.{:02} per event",
        t / n,
        (t % n) * 100 / n
    ));

    requests(tim, &block, n);
    arcs(tim);
    receive(tim);
    let started = timed(tim);
    let Some((mut qtx, rx)) = firmware::step::READY.split() else {
        halt()
    };
    let mut isr = StepIsr::new(rx, b.alarm, b.pulse, b.spindle);
    if let Some(started) = started {
        step_interrupt(tim, &mut isr, &mut qtx, &started);
    }
    compensation(tim);
    calculators(tim);
    cycles(tim);
    threading(tim);
    thread_cycle(tim);
    switches(tim);
    finish()
}

/// A synchronised pass (`docs/threading.md`): the events of a 1.5 mm lead
/// thread 22 mm long along Z at 4096 counts per revolution, then of a
/// taper of the same lead, each event's count found by the prep. Reported
/// per event and per event of the lead-in alone.
fn threading(tim: &StepTimer) {
    use core_nostd::impulse::ImpulsePrice;
    use core_nostd::length::Length;
    use core_nostd::sync::SyncPass;
    let mm = |a: i64| Length::from_angstrom(a * 10_000).unwrap_or(Length::ZERO);
    let prices = (ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z);
    for (name, to) in [
        ("along Z", (mm(10_000), mm(-20_000))),
        ("taper 1:8", (mm(11_375), mm(-20_000))),
    ] {
        let Ok(pass) = SyncPass::new((mm(10_000), mm(2_000)), to, prices, mm(1_500), 4096, 2000)
        else {
            return;
        };
        let mut events = 0u32;
        let mut sink = 0i64;
        let t = measure(tim, || {
            for (c, e) in pass.events() {
                events += 1;
                sink = sink.wrapping_add(c).wrapping_add(i64::from(e.bits()));
            }
        });
        // The lead-in alone: its events are the ones before count C/2.
        let mut ramp = 0u32;
        let tr = measure(tim, || {
            for (c, _) in pass.events() {
                if c > 1000 {
                    break;
                }
                ramp += 1;
            }
        });
        Line::print(format_args!(
            "synchronised pass {name}: {events} events, {} instructions per event; lead-in {ramp} events, {} per event ({sink})",
            per(u64::from(t), u64::from(events)),
            per(u64::from(tr), u64::from(ramp.max(1))),
        ));
    }
}

/// LinuxCNC's `G76` (`docs/threading.md` §5): the check and every move of
/// latheeasystep's M30×1.5 thread (R1.5, Q29.5, one spring pass, 45°
/// tapers at both ends), per pass.
fn thread_cycle(tim: &StepTimer) {
    use core_nostd::thread::{ThreadMove, G76};
    let c = G76 {
        start: [150_000_000, 20_000_000],
        z_end: -290_000_000,
        pitch: 15_000_000,
        crest: -2_300_000,
        first: 450_000,
        full: 4_600_000,
        degression: 15_000,
        angle: 29 * 3600 + 1800,
        spring: 1,
        taper: 4_600_000,
        ends: 3,
    };
    let mut passes = 0u32;
    let mut moves = 0u32;
    let mut sink = 0i64;
    let t = measure(tim, || {
        if c.check().is_err() {
            return;
        }
        passes = c.depths().count() as u32;
        for m in c.moves() {
            moves += 1;
            let (ThreadMove::Rapid(to) | ThreadMove::Cut { to, .. }) = m;
            sink = sink.wrapping_add(to[0] ^ to[1]);
        }
    });
    Line::print(format_args!(
        "cycle G76 (M30x1.5, R1.5, Q29.5, tapers): {passes} passes, {moves} moves, {t} instructions, {} per pass ({sink})",
        per(u64::from(t), u64::from(passes.max(1))),
    ));
}

/// Hundredths, as `a.bc`.
struct Hundredths(u64);

impl core::fmt::Display for Hundredths {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}.{:02}", self.0 / 100, self.0 % 100)
    }
}

fn per(c: u64, n: u64) -> Hundredths {
    Hundredths((c * 100).checked_div(n).unwrap_or(0))
}

/// What one phase of the step interrupt cost: entries, steps, the
/// instructions of all its entries, and of the longest.
#[derive(Default)]
struct Phase {
    steps: u64,
    total: u64,
    worst: u32,
}

/// TIM2 counts 1 GHz here (one instruction, one count); the ready
/// entries' ticks are scaled to it, 16 counts a tick: each step still comes
/// after the step interrupt's work for the one before, and the waits
/// between them stay short.
const SCALE: u32 = 16;

/// Steps a phase runs at most.
const LONGEST: u64 = 6_000;

/// The prep and the bench's own queue between it and the scaling, in
/// static memory.
type Bench = (
    &'static mut core_nostd::prep::Prep,
    core_nostd::prep::ReadyTx<'static>,
    core_nostd::prep::ReadyRx<'static>,
);

/// Runs the step interrupt as its alarm would, each call when the step
/// it armed for is due, over everything the prep makes of `items`
/// (`hold_after`: a feed hold after so many steps, and the resume once
/// at rest). Returns the phases: before the hold, braking, after the
/// resume; and the prep's work per entry.
#[inline(never)]
fn run_isr(
    tim: &StepTimer,
    isr: &mut StepIsr,
    qtx: &mut core_nostd::prep::ReadyTx<'static>,
    (prep, tx, rx): &mut Bench,
    items: impl IntoIterator<Item = core_nostd::stepper::Item>,
    hold_after: Option<u64>,
) -> ([Phase; 3], (u64, u64), u32) {
    use core_nostd::prep::Ready;
    let mut items = items.into_iter();
    let mut phases: [Phase; 3] = Default::default();
    let mut phase = 0usize;
    let (mut prep_cost, mut prep_entries) = (0u64, 0u64);
    let mut hold_cost = 0u32;
    let mut steps = 0u64;
    // Whether each entry in the step interrupt's queue is a step.
    let mut kinds = heapless::Deque::<bool, 256>::new();
    loop {
        while prep.has_room() {
            match items.next() {
                Some(i) => {
                    let _ = prep.push(i);
                }
                None => break,
            }
        }
        // The prep's work, as its task does it, a few entries at a time
        // (the step interrupt would preempt it on the board).
        if rx.len() < 240 {
            let mut n = 0;
            let c = measure(tim, || n = prep.fill(tx));
            prep_cost += u64::from(c);
            prep_entries += n as u64;
        }
        // Scaled into the step interrupt's queue when it runs low: between
        // most entries the bench only waits.
        while qtx.len() < 32 || (qtx.ready() && !isr.busy()) {
            let Some(r) = rx.dequeue() else { break };
            let _ = kinds.push_back(matches!(r, Ready::Step { .. }));
            let r = match r {
                Ready::Step { tick, event, turns } => Ready::Step {
                    tick: tick.wrapping_mul(SCALE),
                    event,
                    turns,
                },
                other => other,
            };
            let _ = qtx.enqueue(r);
        }
        if !isr.busy() && rx.is_empty() {
            if phase == 1 && prep.motion() == core_nostd::stepper::AxesState::Held {
                // At rest: resume.
                phase = 2;
                let _ = prep.resume(tx);
                continue;
            }
            if prep.is_idle() {
                break;
            }
            continue;
        }
        // The alarm: when the step armed for is due.
        if let Some(due) = isr.due() {
            while (tim.count().wrapping_sub(due) as i32) < 0 {}
        }
        let before = isr.passed();
        let c = measure(tim, || isr.service());
        let passed = isr.passed().wrapping_sub(before);
        let mut issued = 0;
        for _ in 0..passed {
            issued += u64::from(kinds.pop_front().unwrap_or(false));
        }
        if let Some(p) = phases.get_mut(phase) {
            p.total += u64::from(c);
            // An entry that finds more than one step due was called late
            // by the bench itself (standing in for the prep, which the
            // step interrupt would preempt): not an entry of the board's.
            if issued <= 1 {
                p.worst = p.worst.max(c);
            }
            p.steps += issued;
        }
        steps += issued;
        if let (0, Some(h)) = (phase, hold_after) {
            if steps >= h {
                phase = 1;
                hold_cost = measure(tim, || prep.hold());
            }
        }
        if steps >= LONGEST {
            // Enough: a reset ends the phase.
            isr.stop();
            let (passed, dropped) = isr.drop_queued();
            let _ = prep.abort(passed, dropped.chain(core::iter::from_fn(|| rx.dequeue())));
            isr.restart();
            break;
        }
    }
    (phases, (prep_cost, prep_entries), hold_cost)
}

/// The step interrupt in every phase: cruise, ramps, block starts, hold
/// and resume; the prep's work per entry beside it.
#[inline(never)]
fn step_interrupt(
    tim: &StepTimer,
    isr: &mut StepIsr,
    qtx: &mut core_nostd::prep::ReadyTx<'static>,
    started: &[core_nostd::plan::Started; 3],
) {
    use core_nostd::prep::{Prep, ReadyQueue};
    use core_nostd::stepper::Item;
    static LOCAL: ReadyQueue = ReadyQueue::new();
    let (Some(prep), Some((tx, rx))) = (cortex_m::singleton!(: Prep = Prep::new()), LOCAL.split())
    else {
        return;
    };
    let bench = &mut (prep, tx, rx);
    let [sa, sb, sc] = started;
    let pulse = firmware::board::pulse_timer_cost(tim);
    let line = |what: &str, p: &Phase| {
        let steps = p.steps.max(1);
        Line::print(format_args!(
            "step interrupt, {what}: {} steps, {} instructions per step (+{pulse} for the board's pulse timer), {} at most in one entry",
            p.steps,
            per(p.total + steps * u64::from(pulse), steps),
            p.worst
        ));
    };
    let (ph, prep_cruise, _) = run_isr(
        tim,
        isr,
        qtx,
        bench,
        [Item::RunStart, Item::Block(*sb), Item::RunEnd(0)],
        None,
    );
    line("cruise", &ph[0]);
    let (ph, prep_ramps, _) = run_isr(
        tim,
        isr,
        qtx,
        bench,
        [
            Item::RunStart,
            Item::Block(*sa),
            Item::Block(*sc),
            Item::RunEnd(0),
        ],
        None,
    );
    line("ramps", &ph[0]);
    Line::print(format_args!(
        "prep per entry: cruise {} instructions, ramps {} (thread-mode figures, at the prep's priority)",
        per(prep_cruise.0, prep_cruise.1),
        per(prep_ramps.0, prep_ramps.1),
    ));
    // A hold 2000 steps into the cruise, braking to rest, and the resume.
    let (ph, _, hold) = run_isr(
        tim,
        isr,
        qtx,
        bench,
        [Item::RunStart, Item::Block(*sb), Item::RunEnd(0)],
        Some(2000),
    );
    line("hold (braking)", &ph[1]);
    line("resume", &ph[2]);
    Line::print(format_args!(
        "hold's re-timing in the prep: {hold} instructions"
    ));
    // Block starts: 200 short blocks of 10 steps each, run through.
    let (ph, _, _) = run_isr(tim, isr, qtx, bench, short_blocks(), None);
    line("block starts (200 blocks of 10 steps)", &ph[0]);
}

/// A run of 200 blocks of 0.1 mm along Z at F600, planned as a window
/// does, one item at a time.
fn short_blocks() -> impl Iterator<Item = core_nostd::stepper::Item> {
    use core_nostd::impulse::{quantize, ImpulsePrice};
    use core_nostd::length::Length;
    use core_nostd::plan::{q32, Block, Feed, Planner, Rates, WINDOW};
    use core_nostd::stepper::Item;
    let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
    let rates = Rates::DEFAULT;
    let mm = |um: i64| Length::from_um(um).unwrap_or(Length::ZERO);
    let feed = Feed::new(mm(600_000));
    let mut p = Planner::<WINDOW>::new(WINDOW);
    let (mut k, mut started, mut ended) = (0i64, false, false);
    core::iter::from_fn(move || {
        if !started {
            started = true;
            return Some(Item::RunStart);
        }
        while k < 200 && !p.window_full() {
            let (a, b) = (mm(-100 * k), mm(-100 * (k + 1)));
            k += 1;
            let at = |z: Length| ImpulsePoint {
                x: Impulses(0),
                z: quantize(z, h[1]).unwrap_or(Impulses(0)),
            };
            let events = LinearBlock::new(at(a), at(b)).ok()?;
            let block = Block::new([0, q32(a)], [0, q32(b)], events, feed, h, &rates)?;
            let _ = p.push(block, &rates);
        }
        if let Some(s) = p.start_block(&rates) {
            return Some(Item::Block(s));
        }
        if ended {
            return None;
        }
        ended = true;
        Some(Item::RunEnd(p.end_run().unwrap_or(0)))
    })
}

/// The receive interrupt per byte: a plain byte, a real-time byte, a
/// grbl real-time byte (the register reads measured apart).
fn receive(tim: &StepTimer) {
    use firmware::motion::RtEvent;
    use firmware::serial::Receiver;
    use heapless::spsc::Queue;
    static mut BYTES: Queue<u8, 512> = Queue::new();
    static mut RT: Queue<RtEvent, 16> = Queue::new();
    // SAFETY: the bench's own queues, split once here; nothing else
    // touches them.
    let (bytes, rt) = unsafe {
        (
            (*core::ptr::addr_of_mut!(BYTES)).split(),
            (*core::ptr::addr_of_mut!(RT)).split(),
        )
    };
    let (mut bytes_rx, mut rt_rx) = (bytes.1, rt.1);
    let mut r = Receiver::new(bytes.0, rt.0);
    let regs = measure(tim, || {
        let _ = core::hint::black_box(firmware::board::rx_ready());
        let _ = core::hint::black_box(firmware::board::rx_byte());
    });
    let mut worst = 0;
    for (what, byte, grbl) in [
        ("a plain byte", b'G', false),
        ("a status byte 0x80", 0x80, false),
        ("a reset 0x18", 0x18, false),
        ("a grbl '?'", b'?', true),
        ("a grbl jog cancel 0x85", 0x85, true),
    ] {
        firmware::serial::set_grbl(grbl);
        let c = measure(tim, || r.take(byte)) + regs;
        worst = worst.max(c);
        let _ = (bytes_rx.dequeue(), rt_rx.dequeue());
        Line::print(format_args!(
            "receive interrupt, {what}: {c} instructions (with the USART's registers)"
        ));
    }
    firmware::serial::set_grbl(false);
    Line::print(format_args!(
        "receive interrupt per byte, worst case: {worst} instructions"
    ));
}

/// Whole requests through the handler, in a frame of their own (the
/// device is large).
#[inline(never)]
fn requests(tim: &StepTimer, block: &LinearBlock, n: u32) {
    let _ = block;
    // The handler: a MOVE of the same block (parse, quantize, SEQ over every
    // event), then an empty MOVE for the per-request cost.
    let mut dev = Device::new();
    let mut quiet = Quiet(0);
    dev.receive_bytes(b"CFG DIAM=0\r\n", &mut quiet);
    let t = measure(tim, || {
        dev.receive_bytes(b"MOVE X=500 Z=-618.03\r\n", &mut quiet)
    });
    let t0 = measure(tim, || dev.receive_bytes(b"MOVE\r\n", &mut quiet));
    let per = t.saturating_sub(t0);
    Line::print(format_args!(
        "MOVE request: {t} instructions for {n} events, {}.{:02} per event (SEQ CRC), {t0} for an empty MOVE",
        per / n,
        (per % n) * 100 / n
    ));
    // The queued block runs at SYNC: planned, timed, TSEQ over every event.
    let t = measure(tim, || dev.receive_bytes(b"SYNC\r\n", &mut quiet));
    Line::print(format_args!(
        "SYNC running it: {t} instructions, {}.{:02} per timed event (with TSEQ)",
        t / n,
        (t % n) * 100 / n
    ));
    let t = measure(tim, || dev.receive_bytes(b"POS\r\n", &mut quiet));
    Line::print(format_args!("POS request: {t} instructions"));
    let t = measure(tim, || dev.receive_bytes(b"CONE A=45\r\n", &mut quiet));
    Line::print(format_args!("CONE request (A=45): {t} instructions"));
    let t = measure(tim, || {
        dev.receive_bytes(b"CONE A=2:51:51 RN=0.8\r\n", &mut quiet)
    });
    Line::print(format_args!("CONE request (A=2:51:51): {t} instructions"));
    let t = measure(tim, || {
        dev.receive_bytes(b"CFG HX=0.001 HZ=0.002 DIAM=1\r\n", &mut quiet)
    });
    Line::print(format_args!("CFG request: {t} instructions"));
}

/// Instructions as µs at 168 MHz (one a cycle), two decimals, cut off.
struct At168MHz(u32);

impl core::fmt::Display for At168MHz {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let centi_us = u64::from(self.0) * 100 / 168;
        write!(f, "{}.{:02}", centi_us / 100, centi_us % 100)
    }
}

/// The switches' sampler (the 1 ms interrupt's work): a sample that
/// changes nothing, and the one that stops everything, from the sample's
/// pin levels to the STEP outputs and the spindle low and the step
/// interrupt masked.
fn switches(tim: &StepTimer) {
    use core_nostd::inputs::{Input, InputConfig, LIMITS};
    firmware::inputs::set_wiring(InputConfig {
        used: Input::Estop.bit() | LIMITS | Input::Door.bit(),
        invert: Input::Estop.bit(),
        filter: 0,
    });
    let mut sampler = firmware::inputs::Sampler::new();
    let quiet = Input::Estop.bit();
    sampler.sample_pins(quiet);
    // A whole sample: the handwheel's counter read unchanged, the pins.
    let idle = measure(tim, || {
        sampler.wheel(core::hint::black_box(0));
        core::hint::black_box(sampler.sample_pins(core::hint::black_box(quiet)));
    });
    let stop = measure(tim, || {
        core::hint::black_box(sampler.sample_pins(core::hint::black_box(0)));
    });
    Line::print(format_args!(
        "switches' sample: {idle} instructions with nothing changed; an E-stop from its sample to the outputs low: at most {stop} instructions ({} us at 168 MHz)",
        At168MHz(stop)
    ));
    // The step interrupt was masked by the stop: free again; released.
    firmware::inputs::unmask_step();
    let _ = firmware::inputs::take_stop();
    sampler.sample_pins(quiet);
    // From the pin's edge: its EXTI interrupt (the lines masked, the
    // sample pended), then the sample that stops, tail-chained.
    let edge = measure(tim, || {
        firmware::inputs::edge();
        core::hint::black_box(sampler.sample_pins(core::hint::black_box(0)));
    });
    cortex_m::peripheral::NVIC::unpend(firmware::board::SAMPLER_IRQ);
    Line::print(format_args!(
        "stopping switch's edge to the outputs low (no filter): at most {edge} instructions ({} us at 168 MHz), plus the core's 12 cycles of interrupt entry and 6 of tail-chaining",
        At168MHz(edge)
    ));
    firmware::inputs::unmask_step();
    let _ = firmware::inputs::take_stop();
    firmware::board::edges_unmask();
}

/// Ends the run: QEMU exits.
fn finish() -> ! {
    #[cfg(feature = "qemu")]
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    halt()
}

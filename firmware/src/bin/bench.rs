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
use core_nostd::impulse::Impulses;
use core_nostd::interleave::{ImpulsePoint, LinearBlock};
use core_nostd::protocol::{Device, Io};
use core_nostd::stepdir::{DriveTiming, StepDir, TickClock};
use cortex_m_rt::entry;
use embedded_hal::delay::DelayNs;
use firmware::board::{PortCPin, StepTimer};
use firmware::halt;

/// A line of text for the host.
struct Line(heapless::String<256>);

impl Line {
    fn print(args: core::fmt::Arguments<'_>) {
        let mut l = Line(heapless::String::new());
        let _ = l.0.write_fmt(args);
        let _ = l.0.push('\n');
        #[cfg(feature = "qemu")]
        firmware::log::host_print(&l.0);
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
fn timed(tim: &StepTimer) {
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
    let Some(b) = block(0, -5_000) else { return };
    let _ = p.push(b, &rates);
    let Some(t) = p.start(&rates) else { return };
    let (c, n) = run(&t);
    Line::print(format_args!(
        "timed step events, 5 mm triangle from rest to rest: {n} events, {}.{:02} instructions per event",
        c / n,
        (c % n) * 100 / n
    ));
    let mut p = Planner::<WINDOW>::new(WINDOW);
    for (a, b) in [(0, -8_000), (-8_000, -408_000), (-408_000, -416_000)] {
        let Some(b) = block(a, b) else { return };
        let _ = p.push(b, &rates);
    }
    let (Some(sa), Some(sb), Some(sc)) = (
        p.start_block(&rates),
        p.start_block(&rates),
        p.start_block(&rates),
    ) else {
        return;
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
    // The step interrupt's own work per event, without its waits: pull from
    // the stepper (tick, TSEQ, registers; a block's start included) and
    // write STEP/DIR. Each event is measured alone: the average and the
    // worst.
    let work = |items: &[Item]| {
        let mut s = Stepper::<AHEAD>::new();
        let mut axes = StepDir::new(PortCPin(0), PortCPin(1), PortCPin(2), PortCPin(3));
        let timing = DriveTiming::DEFAULT;
        let (mut n, mut total, mut worst) = (0u32, 0u32, 0u32);
        for item in items {
            let _ = s.push(item.clone());
            loop {
                let mut stepped = None;
                let c = measure(tim, || {
                    while let Some(p) = s.pull() {
                        if let Pulled::Step(e, tick) = p {
                            let _ = axes.issue(e, tick, &timing, &mut Free, &mut Free);
                            stepped = Some(());
                            break;
                        }
                    }
                });
                if stepped.is_none() {
                    break;
                }
                n += 1;
                total = total.wrapping_add(c);
                worst = worst.max(c);
            }
        }
        (total, n, worst)
    };
    // Hundredths of instructions per event.
    let per = |c: u32, n: u32| (u64::from(c) * 100).checked_div(u64::from(n)).unwrap_or(0);
    let (c, n, w) = work(&[Item::RunStart, Item::Block(sb)]);
    let p = per(c, n);
    Line::print(format_args!(
        "step interrupt's work per event (pull, TSEQ, registers, STEP/DIR), cruise: {}.{:02} instructions, {w} at most",
        p / 100,
        p % 100
    ));
    let (c, n, w) = work(&[Item::RunStart, Item::Block(sa), Item::Block(sc)]);
    let p = per(c, n);
    Line::print(format_args!(
        "step interrupt's work per event, ramps: {}.{:02} instructions, {w} at most (a block's start included)",
        p / 100,
        p % 100
    ));
    // A feed hold in the middle of the cruise: what acting on the byte
    // costs (in the serial interrupt), and how soon the events slow down.
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
        "feed hold at cruise (3000 mm/min, 150 mm/s²): {c} instructions to act on it; the events after it first leave the plan's 1 µs ticks at event {k} ({cruise} ticks apart)"
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
            return;
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

#[entry]
fn main() -> ! {
    let mut b = firmware::boot();
    b.tim2.free_run();
    let tim = &b.tim2;

    let empty = measure(tim, || {});
    // Calibration: `asm::delay(n)` runs a known loop.
    let delay = measure(tim, || cortex_m::asm::delay(100_000)).wrapping_sub(empty);
    Line::print(format_args!(
        "calibration: delay(100000) = {delay} ticks, empty = {empty}"
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

    arcs(tim);
    timed(tim);
    compensation(tim);
    calculators(tim);
    finish()
}

/// Ends the run: QEMU exits.
fn finish() -> ! {
    #[cfg(feature = "qemu")]
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    halt()
}

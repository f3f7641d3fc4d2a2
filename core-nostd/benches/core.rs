//! Speed of the motion path: step events, quantizing a block, a whole MOVE,
//! planning and timing.

use core_nostd::crc32::Crc32;
use core_nostd::impulse::{quantize, ImpulsePrice, Impulses};
use core_nostd::interleave::{ImpulsePoint, LinearBlock};
use core_nostd::length::Length;
use core_nostd::plan::{q32, Block, Feed, Planner, Rates, WINDOW};
use core_nostd::protocol::{Device, Io};
use core_nostd::step::TimedBlock;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

fn interleaver(c: &mut Criterion) {
    let p = |x, z| ImpulsePoint {
        x: Impulses(x),
        z: Impulses(z),
    };
    let block = LinearBlock::new(p(-12_345, 500), p(87_655, -36_623)).unwrap();
    let n = block.events().len() as u64;
    let mut g = c.benchmark_group("interleaver");
    g.throughput(Throughput::Elements(n));
    g.bench_function("step events", |b| {
        b.iter(|| {
            let mut acc = 0u32;
            for e in black_box(&block).events() {
                acc = acc.wrapping_add(u32::from(black_box(e.bits())));
            }
            acc
        })
    });
    g.bench_function("step events + SEQ CRC", |b| {
        b.iter(|| {
            let mut crc = Crc32::new();
            for e in black_box(&block).events() {
                crc.push(e.bits());
            }
            crc.finish()
        })
    });
    g.finish();
}

fn quantizer(c: &mut Criterion) {
    // 1024 end points with 6 decimals, diameters halved exactly.
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % 600_000_000) as i64 - 300_000_000
    };
    let points: Vec<(Length, Length)> = (0..1024)
        .map(|_| {
            (
                Length::from_angstrom(next() * 5).unwrap(),
                Length::from_angstrom(next() * 10).unwrap(),
            )
        })
        .collect();
    let (hx, hz) = (ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z);
    let mut g = c.benchmark_group("quantizer");
    g.throughput(Throughput::Elements(points.len() as u64));
    g.bench_function("block end point (2 axes) + block check", |b| {
        b.iter(|| {
            let mut from = ImpulsePoint::default();
            let mut acc = 0i64;
            for &(x, z) in black_box(&points) {
                let to = ImpulsePoint {
                    x: quantize(x, hx).unwrap(),
                    z: quantize(z, hz).unwrap(),
                };
                if let Ok(block) = LinearBlock::new(from, to) {
                    acc += i64::from(block.delta().0);
                }
                from = to;
            }
            acc
        })
    });
    g.finish();
}

struct Sink(usize);
impl Io for Sink {
    fn send(&mut self, line: &[u8]) {
        self.0 += line.len();
    }
}

fn protocol(c: &mut Criterion) {
    let mut g = c.benchmark_group("protocol");
    let requests = b"MOVE X=27.532 Z=0\r\nMOVE X=48 Z=-10.234\r\n";
    g.throughput(Throughput::Elements(2));
    g.bench_function("MOVE request, short block", |b| {
        let mut dev = Device::new();
        let mut sink = Sink(0);
        b.iter(|| dev.receive_bytes(black_box(requests), &mut sink))
    });
    g.finish();
}

fn arcs(c: &mut Criterion) {
    use core_nostd::arc::{ArcDir, ArcPoints, ChordPlan, DirectArc};
    let mm = |s| Length::from_mm_str(s).unwrap();
    let (hx, hz) = (ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z);
    // A full circle of R 37.5 at σ 0.001: Δφ = 3010″, 431 chords.
    let p = ArcPoints {
        start: [mm("37.5"), mm("-20")],
        end: [mm("37.5"), mm("-20")],
        centre: [mm("0"), mm("-20")],
    };
    let plan = ChordPlan::new(&p, ArcDir::Ccw, mm("0.001"), true).unwrap();
    let n = plan.chords();
    let mut g = c.benchmark_group("arc");
    g.throughput(Throughput::Elements(u64::from(n)));
    g.bench_function("chord end (rotation + carry quantizer)", |b| {
        b.iter(|| {
            let mut acc = 0i64;
            for i in 1..=n {
                let e = black_box(&plan).chord_end(i, hx, hz).unwrap();
                acc += i64::from(e.x.get());
            }
            acc
        })
    });
    g.throughput(Throughput::Elements(1));
    g.bench_function("chord plan (radii, Δφ, sweep)", |b| {
        b.iter(|| ChordPlan::new(black_box(&p), ArcDir::Ccw, mm("0.001"), true).unwrap())
    });
    // A quadrant of R 60 for the direct interpolator: 12 000 + 6 000 steps.
    let q = ArcPoints {
        start: [mm("0"), mm("60")],
        end: [mm("60"), mm("0")],
        centre: [mm("0"), mm("0")],
    };
    let from = ImpulsePoint {
        x: Impulses(0),
        z: Impulses(6000),
    };
    let arc = DirectArc::new(&q, ArcDir::Ccw, from, hx, hz).unwrap();
    let events = arc.events().count() as u64;
    g.throughput(Throughput::Elements(events));
    g.bench_function("direct step event", |b| {
        b.iter(|| {
            let mut acc = 0u32;
            for e in black_box(&arc).events() {
                acc = acc.wrapping_add(u32::from(e.bits()));
            }
            acc
        })
    });
    g.finish();
}

/// The nose radius calculator and the contour engine.
fn compensation(c: &mut Criterion) {
    use core_nostd::arc::ArcDir;
    use core_nostd::comp::TipCode;
    use core_nostd::comp::{Contour, Element, Shape, Tool};
    use core_nostd::cone::{cone, Angle};
    use core_nostd::gcode::Compensation;
    let mut g = c.benchmark_group("compensation");
    let rn = Length::from_um(400).unwrap();
    g.bench_function("CONE corrections (exact angle, Q62 tangents)", |b| {
        let a = Angle::from_degrees_str("2:51:51").unwrap();
        b.iter(|| cone(black_box(a), black_box(rn)))
    });
    g.bench_function("CONE request", |b| {
        let mut dev = Device::new();
        let mut sink = Sink(0);
        b.iter(|| dev.receive_bytes(black_box(b"CONE A=2:51:51 RN=0.8\r\n"), &mut sink))
    });
    // Krylenko Fig. 22 on the radius, in ångström: a face, a convex arc, a
    // cylinder, a concave arc, a face, a convex arc, a cylinder.
    let mm = |v: f64| (v * 1e7).round() as i64;
    let p = |x: f64, z: f64| [mm(x), mm(z)];
    let line = |a, b| Element::line(a, b, false, None);
    let arc = |a, b, c, dir| Element {
        from: a,
        to: b,
        shape: Shape::Arc { centre: c, dir },
        n: None,
    };
    let contour = [
        line(p(0.0, 0.0), p(4.0, 0.0)),
        arc(p(4.0, 0.0), p(6.0, -2.0), p(4.0, -2.0), ArcDir::Ccw),
        line(p(6.0, -2.0), p(6.0, -14.0)),
        arc(p(6.0, -14.0), p(9.0, -17.0), p(9.0, -14.0), ArcDir::Cw),
        line(p(9.0, -17.0), p(15.0, -17.0)),
        arc(p(15.0, -17.0), p(19.0, -21.0), p(15.0, -21.0), ArcDir::Ccw),
        line(p(19.0, -21.0), p(19.0, -30.0)),
        // A 45° taper: an outside and an inside corner by intersection.
        line(p(19.0, -30.0), p(24.0, -35.0)),
        line(p(24.0, -35.0), p(24.0, -40.0)),
    ];
    let tool = Tool::new(rn, TipCode::EXTERNAL_RIGHT);
    let mut start = Contour::new();
    start = start
        .block(
            &tool,
            Some(Compensation::Right),
            None,
            Some(line(p(0.0, 2.0), p(0.0, 0.0))),
        )
        .unwrap()
        .0;
    g.throughput(Throughput::Elements(contour.len() as u64));
    g.bench_function(
        "contour engine, compensated block (lines, arcs, corners)",
        |b| {
            b.iter(|| {
                let mut c = start;
                let mut n = 0;
                for e in &contour {
                    let (next, moves) = c.block(&tool, None, None, Some(*black_box(e))).unwrap();
                    n += moves.len();
                    c = next;
                }
                n
            })
        },
    );
    // The whole request: parse, compensate, plan the chords, step events,
    // SEQ and DATA lines, for the same contour in G-code.
    let program: &[u8] = b"G42 G01 X0 Z0\r\nX8\r\nG03 X12 Z-2 R2\r\nG01 Z-14\r\nG02 X18 Z-17 R3\r\nG01 X30\r\nG03 X38 Z-21 R4\r\nG01 Z-30\r\nX48 Z-35\r\nZ-40\r\nG40 X60\r\nRESET\r\nG00 X0 Z2\r\n";
    g.throughput(Throughput::Elements(11));
    g.bench_function(
        "G-code request with G42 (whole request, motion included)",
        |b| {
            let mut dev = Device::new();
            let mut sink = Sink(0);
            dev.receive_bytes(b"G00 X0 Z2\r\n", &mut sink);
            b.iter(|| dev.receive_bytes(black_box(program), &mut sink))
        },
    );
    g.finish();
}

/// A rapid block along Z from `from_um` to `to_um` (µm), default prices.
fn z_block(from_um: i64, to_um: i64, rates: &Rates) -> Block {
    let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
    let (a, b) = (
        Length::from_um(from_um).unwrap(),
        Length::from_um(to_um).unwrap(),
    );
    let at = |z| ImpulsePoint {
        x: Impulses(0),
        z: quantize(z, h[1]).unwrap(),
    };
    let events = LinearBlock::new(at(a), at(b)).unwrap();
    Block::new([0, q32(a)], [0, q32(b)], events, None, h, rates).unwrap()
}

fn motion(c: &mut Criterion) {
    let rates = Rates::DEFAULT;
    let drain = |t: &TimedBlock| {
        let mut acc = 0u64;
        for (e, tick) in t.events() {
            acc = acc.wrapping_add(u64::from(e.bits())).wrapping_add(tick);
        }
        acc
    };
    // The ramps of a long rapid along Z at the default limits (3000 mm/min,
    // 150 mm/s²): 8 mm from rest and 8 mm to rest around 400 mm of cruise.
    let mut p = Planner::<WINDOW>::new(WINDOW);
    for (a, b) in [(0, -8_000), (-8_000, -408_000), (-408_000, -416_000)] {
        p.push(z_block(a, b, &rates), &rates).unwrap();
    }
    let (ta, tb, tc) = (
        p.start(&rates).unwrap(),
        p.start(&rates).unwrap(),
        p.start(&rates).unwrap(),
    );
    let mut g = c.benchmark_group("timed steps");
    g.throughput(Throughput::Elements(tb.events().len() as u64));
    g.bench_function("cruise event (400 mm at 3000 mm/min)", |b| {
        b.iter(|| drain(black_box(&tb)))
    });
    g.throughput(Throughput::Elements(
        (ta.events().len() + tc.events().len()) as u64,
    ));
    g.bench_function("ramp event (8 mm from rest, 8 mm to rest)", |b| {
        b.iter(|| drain(black_box(&ta)).wrapping_add(drain(black_box(&tc))))
    });
    g.finish();

    // Short feed blocks along a zigzag, the window full: making a block,
    // its junction, queueing it and starting the one 63 blocks ahead.
    let h = [ImpulsePrice::DEFAULT_X, ImpulsePrice::DEFAULT_Z];
    let feed = Feed::new(Length::from_mm_str("600").unwrap());
    let mut blocks = Vec::new();
    let (mut x, mut z) = (0i64, 0i64);
    for k in 0..1000i64 {
        let (dx, dz) = (((k * 37) % 11 - 5) * 100, -500);
        let um = |v| Length::from_um(v).unwrap();
        let (from, to) = ([um(x), um(z)], [um(x + dx), um(z + dz)]);
        let pt = |p: [Length; 2]| ImpulsePoint {
            x: quantize(p[0], h[0]).unwrap(),
            z: quantize(p[1], h[1]).unwrap(),
        };
        let events = LinearBlock::new(pt(from), pt(to)).unwrap();
        blocks.push((
            [q32(from[0]), q32(from[1])],
            [q32(to[0]), q32(to[1])],
            events,
        ));
        (x, z) = (x + dx, z + dz);
    }
    let mut g = c.benchmark_group("planner");
    g.throughput(Throughput::Elements(blocks.len() as u64));
    g.bench_function(
        "block made, queued, planned over its window, started",
        |b| {
            b.iter(|| {
                let mut p = Planner::<WINDOW>::new(WINDOW);
                let mut acc = 0u64;
                for &(from, to, events) in black_box(&blocks) {
                    let block = Block::new(from, to, events, feed, h, &rates).unwrap();
                    p.push(block, &rates).unwrap();
                    if p.window_full() {
                        acc = acc.wrapping_add(p.start(&rates).unwrap().end_tick());
                    }
                }
                acc
            })
        },
    );
    g.finish();
}

/// The G-code reader on lines as CAM posts and machinists write them.
fn reader(c: &mut Criterion) {
    use core_nostd::gcode::{parse, Dialect, Units};
    const FANUC: [&str; 8] = [
        "N100 G00 X30. Z2. M08",
        "N110 G96 S180 M03",
        "N120 G01 Z-12.25 F.2",
        "N130 X34.5 W-1.75 (CHAMFER)",
        "N140 G02 U6. W-3. R3.",
        "N150 G01 Z-40.",
        "N160 G28 U0 W0",
        "N170 T0202 M05 M09",
    ];
    const ISO: [&str; 8] = [
        "N100 G0 X30 Z2 M8",
        "N110 G96 D2500 S180 M3",
        "N120 G1 Z-12.25 F0.2",
        "N130 X34.5 Z-14 ; chamfer",
        "N140 G2 X40.5 Z-17 I0 K-3",
        "N150 G1 Z-40",
        "N160 G53 G0 X120 Z50",
        "N170 T2 M6 G43",
    ];
    let mut g = c.benchmark_group("reader");
    g.throughput(Throughput::Elements(8));
    for (name, lines, dialect) in [("Fanuc", FANUC, Dialect::Fanuc), ("ISO", ISO, Dialect::Iso)] {
        g.bench_function(format!("{name} lathe blocks"), |b| {
            b.iter(|| {
                let mut n = 0u32;
                for line in black_box(&lines) {
                    if let Ok(block) = parse(line, dialect, Units::Mm) {
                        n = n.wrapping_add(u32::from(block.x.is_some()));
                    }
                }
                n
            })
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    reader,
    interleaver,
    quantizer,
    protocol,
    arcs,
    compensation,
    motion
);
criterion_main!(benches);

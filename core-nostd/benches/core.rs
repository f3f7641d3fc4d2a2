//! Speed of the motion path: step events, quantizing a block, a whole MOVE.

use core_nostd::crc32::Crc32;
use core_nostd::impulse::{quantize, ImpulsePrice, Impulses};
use core_nostd::interleave::{ImpulsePoint, LinearBlock};
use core_nostd::length::Length;
use core_nostd::protocol::{Device, Io};
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

criterion_group!(
    benches,
    interleaver,
    quantizer,
    protocol,
    arcs,
    compensation
);
criterion_main!(benches);

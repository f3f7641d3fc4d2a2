//! Requests per second: the in-process device called directly, and through
//! the pseudo-terminal link with the serialport crate.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use host_sim::device::LocalDevice;
use host_sim::link::{Client, PtyDevice, Transport};
use reference::impulse::{RefConfig, RefMachine};
use std::time::Duration;

const MOVES: [&str; 4] = [
    "MOVE X=27.532 Z=0",
    "MOVE X=48 Z=-10.234",
    "MOVE X=48.001 Z=-10.2345",
    "MOVE X=27.5315 Z=0.0005",
];

fn link(c: &mut Criterion) {
    let mut g = c.benchmark_group("link");
    g.throughput(Throughput::Elements(MOVES.len() as u64));
    g.bench_function("in-process MOVE", |b| {
        let mut dev = LocalDevice::new();
        b.iter(|| {
            for m in MOVES {
                Transport::request(&mut dev, m).unwrap();
            }
        })
    });
    let device = PtyDevice::start().unwrap();
    let mut client = Client::open(device.path(), Duration::from_secs(5)).unwrap();
    g.bench_function("pty MOVE round trip", |b| {
        b.iter(|| {
            for m in MOVES {
                client.request(m).unwrap();
            }
        })
    });
    g.bench_function("f64 reference MOVE", |b| {
        let mut r = RefMachine::new(RefConfig::default());
        b.iter(|| {
            for m in MOVES {
                let w: Vec<&str> = m.split([' ', '=']).collect();
                r.move_block(Some(w[2]), Some(w[4]), false);
            }
        })
    });
    g.finish();
}

criterion_group!(benches, link);
criterion_main!(benches);

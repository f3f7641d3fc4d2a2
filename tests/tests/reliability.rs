//! The reliable link: corrupted requests never run, lost replies never make
//! an axis move twice, resets are found and repaired, and a long faulted
//! session ends with the device's registers equal to the reference's.

use host_sim::reliable::{frame, unframe, ByteLink, FaultInjector, Faults, LocalLink};
use host_sim::soak::soak;
use std::time::Duration;

fn exchange(link: &mut LocalLink, id: u32, request: &str) -> Vec<String> {
    let line = frame(id, request);
    link.intend(line.strip_suffix(b"\r\n").unwrap());
    link.send(&line).unwrap();
    let mut lines = Vec::new();
    while let Some(l) = link.recv_line(Duration::ZERO).unwrap() {
        lines.push(String::from_utf8(l).unwrap());
    }
    lines
}

fn final_text(lines: &[String]) -> String {
    let (_, text) = unframe(lines.last().unwrap().as_bytes()).unwrap();
    text
}

#[test]
fn a_lost_reply_never_moves_an_axis_twice() {
    let mut link = LocalLink::new();
    assert_eq!(
        final_text(&exchange(&mut link, 1, "SESSION TOKEN=9")),
        "OK TOKEN=9"
    );
    // The reply to id 2 is lost; the same line goes again.
    let first = exchange(&mut link, 2, "MOVE X=1 INC=1");
    let again = exchange(&mut link, 2, "MOVE X=1 INC=1");
    assert_eq!(first, again);
    assert_eq!(
        final_text(&exchange(&mut link, 3, "POS")),
        "OK PX=100 PZ=0 X=1.0000 Z=0.0000"
    );
    assert_eq!(link.executed_corrupted, 0);
}

#[test]
fn a_reset_is_refused_before_anything_runs() {
    let mut link = LocalLink::new();
    exchange(&mut link, 1, "SESSION TOKEN=9");
    exchange(&mut link, 2, "MOVE X=1 INC=1");
    link.reset_device().unwrap();
    let r = final_text(&exchange(&mut link, 2, "MOVE X=1 INC=1"));
    assert!(r.starts_with("ERR SESSION"), "{r}");
    assert_eq!(final_text(&exchange(&mut link, 3, "SESSION")), "OK TOKEN=0");
    // Plain requests still work after the reset: nothing moved.
    link.send(b"POS\r\n").unwrap();
    let pos = link.recv_line(Duration::ZERO).unwrap().unwrap();
    assert!(String::from_utf8(pos).unwrap().starts_with("OK PX=0 PZ=0 "));
}

#[test]
fn every_damaged_reply_is_recognised() {
    let mut link = LocalLink::new();
    exchange(&mut link, 1, "SESSION TOKEN=9");
    let lines = exchange(&mut link, 2, "MOVE X=12.5 Z=-3.25");
    let good = lines.last().unwrap().as_bytes().to_vec();
    let meant = unframe(&good).unwrap();
    // Damage is caught, or leaves exactly what was meant (two bit-5 flips can
    // swap the case of two hex digits: the same numbers, the same reply).
    let caught = |bad: &[u8]| unframe(bad).is_none_or(|got| got == meant);
    // Every single bit flip, and every pair of flips in the same bit of two
    // bytes (which the XOR alone cannot see).
    for i in 0..good.len() {
        for bit in 0..8 {
            let mut bad = good.clone();
            bad[i] ^= 1 << bit;
            assert!(unframe(&bad).is_none(), "flip {i}.{bit}");
            for j in i + 1..good.len() {
                let mut bad2 = bad.clone();
                bad2[j] ^= 1 << bit;
                assert!(caught(&bad2), "flips {i},{j}.{bit}");
            }
        }
        // A dropped byte, and a duplicated one.
        let mut dropped = good.clone();
        dropped.remove(i);
        assert!(unframe(&dropped).is_none(), "drop {i}");
        let mut dup = good.clone();
        dup.insert(i, good[i]);
        assert!(unframe(&dup).is_none(), "dup {i}");
    }
}

#[test]
fn a_faulted_session_ends_equal_to_the_reference() {
    let injector = FaultInjector::new(LocalLink::new(), Faults::HARSH, 5);
    let (report, link) = soak(injector, 5, 4_000, Duration::ZERO, |_| {}).unwrap();
    let f = link.stats;
    assert!(report.passed(), "{report:?}");
    assert_eq!(link.inner().executed_corrupted, 0);
    assert!(f.requests_damaged > 100 && f.replies_damaged > 100, "{f:?}");
    assert!(report.session.retries >= f.requests_damaged.min(f.replies_damaged));
    assert!(report.session.corrupt_replies > 0);
    assert_eq!(report.blocks, 4_000);
    // Resets injected were all found (two in a row are found as one).
    assert!(f.resets == 0 || report.session.resets_detected > 0);
}

#[test]
fn resets_are_repaired_from_the_hosts_record() {
    let faults = Faults {
        flip: 0.0,
        drop: 0.0,
        dup: 0.0,
        noise: 0.0,
        reset: 0.05,
    };
    let injector = FaultInjector::new(LocalLink::new(), faults, 11);
    let (report, link) = soak(injector, 11, 1_500, Duration::ZERO, |_| {}).unwrap();
    assert!(report.passed(), "{report:?}");
    assert!(link.stats.resets > 50, "{:?}", link.stats);
    assert!(report.session.resets_detected > 40);
}

//! Every event on time: the timed firmware in QEMU (`qemu-timed`: paced,
//! its core never sleeping, so that under `-icount` QEMU fires every timer
//! on its tick) streams 150 blocks at 200 000 events a second, with a
//! feed hold and a resume in the middle; the most late event it issued is
//! at most one tick after its tick, and the run ends where the in-process
//! device's does.
//!
//! Skipped with a message where `qemu-system-arm` is missing, except under CI
//! (`CI` set), where a missing QEMU fails.

use host_sim::qemu::{build_firmware, qemu_or_skip, Qemu};
use std::time::Duration;

#[test]
fn every_event_is_issued_within_a_tick_at_200000_events_a_second_through_a_hold() {
    if !qemu_or_skip() {
        return;
    }
    let elf = build_firmware("qemu-timed").unwrap();
    let lines = host_sim::stream::rate_program(200_000, 150);
    let mut q = Qemu::boot_paced_timed(&elf).unwrap();
    let mut c = q.connect(Duration::from_secs(60)).unwrap();
    let r = host_sim::stream::hold_and_resume(&mut c, &lines).unwrap();
    eprintln!("{r:#?}");
    assert_eq!(r.end, r.expected);
    assert!(r.held.contains("STATE=HOLD"), "{}", r.held);
    host_sim::stream::realtime(&mut c, 0x80).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    let (late, worst) = host_sim::stream::lateness(&q.log()).expect("a timing line");
    eprintln!("late events {late}, worst {worst} tick(s)");
    assert!(worst <= 1, "worst {worst} ticks late ({late} events late)");
}

//! The paced firmware in QEMU: its step interrupt issues every event on
//! its tick of TIM2 while the protocol answers, so the host must keep up
//! in real time. A test binary of its own: it runs alone, not beside the
//! other QEMU tests, which would take the host's cores from it.
//!
//! Skipped with a message where `qemu-system-arm` is missing, except under CI
//! (`CI` set), where a missing QEMU fails.

use host_sim::qemu::{build_firmware, qemu_or_skip, Qemu};
use std::time::Duration;

/// Done when of the step interrupt: a 500-request program (feeds, rapids,
/// arcs by chords) streamed to the paced firmware, its events on their
/// ticks of virtual time, answers as the in-process device does and ends
/// with its `SYNC`; a hold and a resume, and a reset, in the middle of the
/// run leave the registers on the program's steps.
#[test]
fn a_program_streamed_to_the_paced_firmware_ends_with_the_in_process_sync() {
    if !qemu_or_skip() {
        return;
    }
    let elf = build_firmware("qemu-paced").unwrap();
    let mut running = Vec::new();
    let report = host_sim::stream::paced_proof(
        || {
            let mut q = Qemu::boot_paced(&elf)?;
            let c = q.connect(Duration::from_secs(60))?;
            running.push(q);
            Ok(c)
        },
        2026,
        500,
    )
    .unwrap();
    eprintln!("{report:#?}");
    assert!(report.mismatches.is_empty(), "{:?}", report.mismatches);
    assert_eq!(report.sync.0, report.sync.1);
    assert!(report.sync.0.ends_with(" STARVED=0"), "{}", report.sync.0);
    assert!(report.held_prefix.is_some(), "held at {:?}", report.held_at);
    assert_eq!(report.after_hold, report.after_hold_expected);
    assert!(report.reset_consistent, "{}", report.reset_line);
}

//! Backlash compensation through the device (`docs/motion.md` §7): the
//! take-up's events counted by `SYNC`, never by the registers.

use super::*;

#[test]
fn a_reversal_takes_up_the_play_in_events_the_registers_do_not_count() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG HX=0.005 HZ=0.01 DIAM=0").starts_with("OK"));
    assert_eq!(
        ask1(&mut dev, "BACKLASH X=0.08 Z=0.15"),
        "OK X=0.08 Z=0.15 NX=16 NZ=15"
    );
    // X towards plus (16 to take up), Z towards minus (none at power-on):
    // 200 events of the block and 16 of the take-up.
    assert!(ask1(&mut dev, "MOVE X=1 Z=-1").starts_with("OK NX=200 NZ=-100 PX=200 PZ=-100"));
    let sync = ask1(&mut dev, "SYNC");
    assert_eq!(number(&sync, "EV"), 216, "{sync}");
    // On the same way: nothing more.
    assert!(ask1(&mut dev, "MOVE X=2 Z=-2").starts_with("OK"));
    assert_eq!(number(&ask1(&mut dev, "SYNC"), "EV"), 200);
    // Both reverse: one take-up of 16 and 15 together.
    assert!(ask1(&mut dev, "MOVE X=0 Z=0").starts_with("OK"));
    assert_eq!(number(&ask1(&mut dev, "SYNC"), "EV"), 400 + 16);
    let status = ask1(&mut dev, "STATUS");
    assert_eq!(
        (number(&status, "PX"), number(&status, "PZ")),
        (0, 0),
        "{status}"
    );
    // X alone: Z keeps its state (taken up towards plus).
    assert!(ask1(&mut dev, "MOVE X=1").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE Z=1").starts_with("OK"));
    assert_eq!(number(&ask1(&mut dev, "SYNC"), "EV"), 200 + 16 + 100);
    // The play set to none: the motors stay where they are, and the next
    // block of each turns back what they took up (16 and 15 together);
    // after that nothing more.
    assert!(ask1(&mut dev, "BACKLASH X=0 Z=0").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=0 Z=0").starts_with("OK"));
    assert_eq!(number(&ask1(&mut dev, "SYNC"), "EV"), 200 + 16);
    assert!(ask1(&mut dev, "MOVE X=1 Z=1").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=0 Z=0").starts_with("OK"));
    assert_eq!(number(&ask1(&mut dev, "SYNC"), "EV"), 400);
}

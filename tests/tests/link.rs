//! The protocol over the virtual serial link: a pseudo-terminal pair, the host
//! side opened by path with the `serialport` crate, as with real hardware.

use host_sim::compare::Comparator;
use host_sim::device::LocalDevice;
use host_sim::link::{final_lines, Client, PtyDevice, Transport};
use host_sim::scenario;
use std::time::Duration;

#[test]
fn scenarios_over_the_pty_match_the_reference() {
    let device = PtyDevice::start().unwrap();
    let client = Client::open(device.path(), Duration::from_secs(10)).unwrap();
    let mut cmp = Comparator::new(client).unwrap();
    for s in [
        scenario::table21(),
        scenario::krylenko(),
        scenario::random(5, 200),
    ] {
        cmp.run(&s, |_| {}).unwrap();
    }
    assert!(
        cmp.tally.mismatches.is_empty(),
        "{:?}",
        cmp.tally.mismatches
    );
    assert!(cmp.tally.blocks >= 262);
}

#[test]
fn mixed_session_bytes_are_identical_over_the_pty() {
    let session = scenario::mixed_session();
    let expected = LocalDevice::new().feed(&session);
    let requests = final_lines(&expected);
    assert!(requests >= 30, "{requests}");

    let device = PtyDevice::start().unwrap();
    let mut client = Client::open(device.path(), Duration::from_secs(10)).unwrap();
    client.write_raw(&session).unwrap();
    let got = client.read_finals(requests).unwrap();
    assert_eq!(
        String::from_utf8_lossy(&got),
        String::from_utf8_lossy(&expected)
    );
    // Every kind of refusal is in the session.
    let text = String::from_utf8_lossy(&expected);
    for code in [
        "CHECKSUM",
        "LINE_TOO_LONG",
        "EMPTY",
        "UNKNOWN",
        "SYNTAX",
        "VALUE",
        "RANGE",
    ] {
        assert!(text.contains(&format!("ERR {code} ")), "{code}");
    }
    // And the device ended at the program zero it was told.
    let r = client.request("POS").unwrap();
    assert_eq!(r.last, "OK PX=0 PZ=0 X=0.0000 Z=0.0000");
}

#[test]
fn a_corrupted_reply_is_detected() {
    assert!(host_sim::link::check_reply_line("OK*04").is_ok());
    assert!(host_sim::link::check_reply_line("OK*05").is_err());
    assert!(host_sim::link::check_reply_line("OJ*04").is_err());
    assert!(host_sim::link::check_reply_line("OK").is_err());
}

/// `serve` waits at a program stop for cycle start as the board does:
/// no reply to `M00` until 0x81, status bytes answered with `STOP=M00`
/// meanwhile, the requests sent during the wait run after it.
#[test]
fn a_program_stop_waits_for_cycle_start_over_the_pty() {
    let device = PtyDevice::start().unwrap();
    let mut client = Client::open(device.path(), Duration::from_secs(10)).unwrap();
    let body = |l: String| l.trim_end().rsplit_once('*').unwrap().0.to_string();
    client.write_raw(b"G00 X10 Z-5\nM00\nG00 X0\n").unwrap();
    assert!(body(client.read_line().unwrap()).starts_with("DATA G00"));
    assert!(body(client.read_line().unwrap()).starts_with("OK NX=1000 NZ=-500 "));
    // Nothing comes while it waits.
    client.set_timeout(Duration::from_millis(300));
    assert!(client.read_line().is_err());
    client.set_timeout(Duration::from_secs(10));
    client.write_raw(b"\x80").unwrap();
    assert_eq!(
        body(client.read_line().unwrap()),
        "!STATUS STATE=IDLE PX=1000 PZ=-500 X=10.0000 Z=-5.0000 V=0.0000 Q=0 STARVED=0 \
         SPINDLE=OFF S=0.000 COOLANT=OFF STOP=M00"
    );
    client.write_raw(b"\x81").unwrap();
    assert!(body(client.read_line().unwrap()).starts_with("OK NX=0 NZ=0 PX=1000 PZ=-500 "));
    assert!(body(client.read_line().unwrap()).starts_with("DATA G00 X0.0000"));
    assert!(body(client.read_line().unwrap()).starts_with("OK NX=-1000 NZ=0 PX=0 "));
    assert!(body(client.read_line().unwrap()).starts_with("!STATUS "));
    // A reset ends the wait too.
    client.write_raw(b"M00\n").unwrap();
    client.set_timeout(Duration::from_millis(300));
    assert!(client.read_line().is_err());
    client.set_timeout(Duration::from_secs(10));
    client.write_raw(b"\x18").unwrap();
    assert!(body(client.read_line().unwrap()).starts_with("OK NX=0 NZ=0 "));
    assert!(body(client.read_line().unwrap()).starts_with("!RESET DONE=0 OF=0 PX=0 PZ=-500"));
}

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

//! Arbitrary bytes into the line protocol handler.
//!
//! The input is cut into requests by an independent reading of the framing
//! rules (LF, CR, CRLF as one; an over-long line is one request, reported
//! once), and each request is fed to the device in turn. Checked for every
//! request (see `fuzz_oracle::request`): every reply line ASCII, at most 160
//! bytes, correct `*HH`, CRLF; exactly one final line; an `ERR` moves nothing
//! and leaves `POS`, `CFG`, `DRIVE` (and the whole session) as they were; the
//! registers always hold `Q(P/h)` of the commanded point; reported motion,
//! `SEQ` and step events agree. The whole input is also fed in one go to a
//! second device, which must answer byte for byte the same.
#![no_main]

use core_nostd::protocol::Device;
use fuzz_oracle::{request_ends, session, Collect};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut dev = Device::new();
    let answers = session(&mut dev, data);
    assert_eq!(answers.len(), request_ends(data).len());

    // The same bytes in one call: the same replies, and the same final state.
    let mut whole = Device::new();
    let mut io = Collect::default();
    whole.receive_bytes(data, &mut io);
    let split: Vec<&String> = answers.iter().flat_map(|a| a.lines.iter()).collect();
    let joined: Vec<&String> = io.lines.iter().collect();
    assert_eq!(split, joined);
    let finals = io.lines.iter().filter(|l| fuzz_oracle::is_final(l)).count();
    assert_eq!(finals, request_ends(data).len());
    assert_eq!(
        format!("{:?}", whole.session()),
        format!("{:?}", dev.session())
    );
});

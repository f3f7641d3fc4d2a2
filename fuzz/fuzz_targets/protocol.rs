//! Arbitrary bytes into the line protocol handler.
//!
//! The input is cut into requests by an independent reading of the framing
//! rules (LF, CR, CRLF as one; an over-long line is one request, reported
//! once), and each request is fed to the device in turn and checked (see
//! `fuzz_oracle::Checker::request`): every reply line ASCII, at most 160
//! bytes, correct `*HH`, CRLF; exactly one final line per request; `*HH`,
//! CRC words and `@id` retries as documented; an `ERR` moves nothing and
//! leaves `POS`, `CFG`, `DRIVE` (and the whole session) as they were; the
//! registers always hold `Q(P/h)` of the commanded point; reported motion,
//! `SEQ` and step events agree. The whole input is also fed in one go to a
//! second device, which must answer with the same lines and end in the same
//! state.
#![no_main]

use core_nostd::protocol::Device;
use fuzz_oracle::{is_final, requests, Checker, Collect};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut checker = Checker::new(Device::new());
    let answers = checker.feed(data);
    let framed = requests(data).len();
    assert_eq!(answers.len(), framed);

    let mut whole = Device::new();
    let mut io = Collect::default();
    whole.receive_bytes(data, &mut io);
    let finals = io.lines.iter().filter(|l| is_final(l)).count();
    assert_eq!(finals, framed, "final lines vs requests");
    let split: usize = answers.iter().map(|a| a.lines.len()).sum();
    assert_eq!(split, io.lines.len());
    assert_eq!(
        format!("{:?}", whole.session()),
        format!("{:?}", checker.dev.session())
    );
});

//! Arbitrary bytes into the line protocol handler.
//!
//! The input is cut into requests by an independent reading of the framing
//! rules (LF, CR, CRLF as one; an over-long line is one request, reported
//! once), and each request is fed to the device in turn and checked (see
//! `fuzz_oracle::Checker::request`): every reply line ASCII, at most 160
//! bytes, correct `*HH`, CRLF; exactly one final line per request, so as many
//! final lines as requests; `*HH`, CRC words and `@id` retries as
//! documented; an `ERR` moves nothing and leaves `POS`, `CFG`, `DRIVE`,
//! `SESSION` (and the whole session) as they were; the registers always hold
//! `Q(P/h)` of the commanded point; reported motion, `SEQ` and step events
//! agree; bytes after the last terminator produce no reply.
#![no_main]

use fuzz_oracle::{requests, Checker};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut checker = Checker::new(fuzz_oracle::fuzz_device());
    let answers = checker.feed(data);
    assert_eq!(answers.len(), requests(data).len());
});

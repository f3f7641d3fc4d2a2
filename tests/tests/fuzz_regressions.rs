//! Regression tests from fuzzing (`fuzz/`): findings of the fuzz targets,
//! minimised, and inputs of their corpora worth keeping as plain tests
//! (escaping and framing, long lines, integrity words, tricky numbers,
//! G-code words written together).
//!
//! A test under "Findings" fails until the behaviour it describes is fixed.

use core_nostd::gcode::parse_block;
use core_nostd::interleave::StepEvent;
use core_nostd::length::{Length, LengthError};
use core_nostd::protocol::{Device, Io};
use core_nostd::stepdir::DriveTiming;

/// Reply lines, each checked as the protocol promises: ASCII, at most 160
/// bytes, `*HH` correct, CRLF. Keeps the bodies (before `*`).
#[derive(Default)]
struct Replies {
    lines: Vec<String>,
    /// Step events issued.
    blocks: usize,
}

impl Io for Replies {
    fn send(&mut self, line: &[u8]) {
        assert!(line.is_ascii() && line.len() <= 160, "{line:?}");
        let text = std::str::from_utf8(line).unwrap();
        let text = text.strip_suffix("\r\n").expect("CRLF");
        let (body, sum) = text.rsplit_once('*').expect("*HH");
        let xor = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(sum, format!("{xor:02X}"), "checksum of {text:?}");
        self.lines.push(body.to_string());
    }
    fn step(&mut self, _: StepEvent, _: u64, _: &DriveTiming) {
        self.blocks += 1;
    }
}

fn ask(dev: &mut Device, bytes: &[u8]) -> Replies {
    let mut r = Replies::default();
    dev.receive_bytes(bytes, &mut r);
    r
}

/// The single final line of one request.
fn ask1(dev: &mut Device, line: &str) -> String {
    let r = ask(dev, format!("{line}\r\n").as_bytes());
    assert_eq!(r.lines.len(), 1, "{line:?} -> {:?}", r.lines);
    r.lines[0].clone()
}

fn finals(r: &Replies) -> usize {
    r.lines
        .iter()
        .filter(|l| *l == "OK" || l.starts_with("OK ") || l.starts_with("ERR "))
        .count()
}

/// Everything a request could change, as the device reports it.
fn state(dev: &Device) -> [String; 5] {
    let mut copy = dev.clone();
    ["POS", "CFG", "DRIVE", "SESSION", "LIMITS"].map(|q| ask1(&mut copy, q))
}

fn with_crc(body: &str) -> String {
    let mut c = core_nostd::crc32::Crc32::new();
    c.update(body.as_bytes());
    c.push(b' ');
    format!("{body} ~{:08X}", c.finish())
}

fn with_checksum(body: &str) -> String {
    let xor = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("{body}*{xor:02X}")
}

// ---------------------------------------------------------------------------
// Findings
// ---------------------------------------------------------------------------

/// Found by the `length` target: a length from 99 999.99995 mm up prints as
/// `100000.0000`. Lengths in replies are rounded half away from zero to 4
/// decimals (`docs/protocol.md` §3), so a coordinate within 0.00005 mm of the
/// ±100 000 mm limit prints one past the largest word a request may carry;
/// the product keeps this and documents it (`docs/protocol.md` §11).
/// Everything below that edge reads back to within 0.00005 mm.
#[test]
fn printed_length_at_the_limit() {
    for (text, printed) in [
        ("99999.99995", "100000.0000"),
        ("-99999.99995", "-100000.0000"),
        ("99999.999999", "100000.0000"),
    ] {
        let l = Length::from_mm_str(text).unwrap();
        assert_eq!(l.to_string(), printed);
        assert!(Length::from_mm_str(printed).is_err());
    }
    let l = Length::from_mm_str("99999.999949").unwrap();
    let back = Length::from_mm_str(&l.to_string()).unwrap();
    assert!((back.as_angstrom() - l.as_angstrom()).abs() <= 500);
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG DIAM=0 HZ=1").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE Z=99999.99995").starts_with("OK"));
    let pos = ask1(&mut dev, "POS");
    assert!(pos.ends_with(" Z=100000.0000"), "{pos}");
    assert!(ask1(&mut dev, "MOVE Z=100000.0000").starts_with("ERR VALUE Z"));
    assert_eq!(ask1(&mut dev, "POS"), pos);
}

/// Found by the `block` target: `G04 P99999.9999995` rounds to 100 000 s,
/// one past the largest dwell, and was taken while the same time written
/// back (`G04 P100000.000000`) was refused. A number without a unit is now
/// held to 99 999.999999 after rounding, as a length is; the refusal names
/// the word and changes nothing in the session.
#[test]
fn dwell_that_rounds_beyond_the_range() {
    use core_nostd::gcode::{parse, BlockError, Dialect, Units};
    let range = Err(BlockError::Range(b'P', "must be 0 to 99999.999999"));
    assert_eq!(parse_block("G04 P99999.999999500"), range);
    assert_eq!(parse_block("G04 P100000.000000"), range);
    let b = parse_block("G04 P99999.9999994").unwrap();
    assert_eq!(b.dwell, Some(99_999_999_999));
    // Fanuc's P is milliseconds: 99 999.9995 ms rounds to 100 000 ms.
    let fanuc = |t| parse(t, Dialect::Fanuc, Units::Mm).map_err(|l| l.error);
    assert_eq!(fanuc("G04 P99999.9995"), range);
    assert_eq!(fanuc("G04 P99999.9994").unwrap().dwell, Some(99_999_999));
    let mut dev = Device::new();
    let before = ask1(&mut dev, "POS");
    let reply = ask1(&mut dev, "G04 P99999.999999500");
    assert!(reply.starts_with("ERR VALUE"), "{reply}");
    assert!(reply.contains('P'), "{reply}");
    assert_eq!(ask1(&mut dev, "POS"), before);
}

// ---------------------------------------------------------------------------
// Corpus inputs kept as regression tests (all pass)
// ---------------------------------------------------------------------------

/// Framing: CR, LF and CRLF each end one request; binary bytes and an escape
/// sequence are one refused request; a line of exactly 120 bytes is a
/// request, one of 121 is reported once and discarded up to its terminator,
/// and the LF of its CRLF does not make an empty request.
#[test]
fn framing_and_long_lines() {
    let mut dev = Device::new();
    let r = ask(&mut dev, b"POS\rPOS\nPOS\r\n\x00\xff\x1b[A\x7f\xfe\r\n\r\n");
    assert_eq!(finals(&r), 5, "{:?}", r.lines);
    assert!(r.lines[3].starts_with("ERR SYNTAX"), "{:?}", r.lines);
    assert!(r.lines[4].starts_with("ERR EMPTY"), "{:?}", r.lines);

    // 120 bytes: a request (a value far beyond the limit, refused as such).
    let exact = format!("MOVE X=1 Z=1{}", "0".repeat(120 - 12));
    assert_eq!(exact.len(), 120);
    assert!(ask1(&mut dev, &exact).starts_with("ERR VALUE Z"));
    // 121 bytes, ended by CRLF, then a lone LF: over-long once, then empty.
    let over = format!("{exact}0");
    let r = ask(&mut dev, format!("{over}\r\n\nPOS\n").as_bytes());
    assert_eq!(finals(&r), 3, "{:?}", r.lines);
    assert!(r.lines[0].starts_with("ERR LINE_TOO_LONG"));
    assert!(r.lines[1].starts_with("ERR EMPTY"));
    assert!(r.lines[2].starts_with("OK PX=0 PZ=0 "));
    // A very long line ended by CR alone; its rest is discarded.
    let mut bytes = vec![b'M'; 5000];
    bytes.extend_from_slice(b"\rVER\r");
    let r = ask(&mut dev, &bytes);
    assert_eq!(finals(&r), 2, "{:?}", r.lines);
    assert!(r.lines[1].starts_with("OK PROTO=1 "));
    // Bytes after the last terminator are not a request yet.
    assert!(ask(&mut dev, b"POS").lines.is_empty());
    assert_eq!(ask(&mut dev, b"\n").lines.len(), 1);
}

/// The host simulator's mixed session: one final line per request, every
/// reply well formed.
#[test]
fn mixed_session_one_final_line_per_request() {
    let bytes = host_sim::scenario::mixed_session();
    let mut dev = Device::new();
    let r = ask(&mut dev, &bytes);
    // Requests as the framing sees them: terminators (CRLF once), plus one
    // per stretch beyond 120 bytes.
    let (mut expected, mut run, mut over, mut prev_cr) = (0, 0, false, false);
    for &b in &bytes {
        if b == b'\n' && prev_cr {
        } else if b == b'\r' || b == b'\n' {
            expected += usize::from(!over);
            (over, run) = (false, 0);
        } else if !over {
            run += 1;
            if run > 120 {
                expected += 1;
                over = true;
            }
        }
        prev_cr = b == b'\r';
    }
    assert_eq!(finals(&r), expected);
}

/// Integrity words: a `*HH` in the middle is malformed; a lower-case
/// checksum is accepted; a CRC-looking word that does not stand alone is part
/// of the request; a lone wrong CRC word refuses the line as a whole; a
/// right one is answered with id and CRC; the same id again repeats the
/// reply without running anything.
#[test]
fn checksums_crc_words_and_retries() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "move x=1*4").starts_with("ERR CHECKSUM malformed"));
    assert!(ask1(&mut dev, "MOVE X=1*00 Z=2").starts_with("ERR CHECKSUM"));
    let lower = with_checksum("pos").to_lowercase();
    assert!(ask1(&mut dev, &lower).starts_with("OK PX="));
    assert!(ask1(&mut dev, "MOVE X=1~DEADBEEF").starts_with("ERR VALUE X"));
    assert!(ask1(&mut dev, "MOVE X=1 ~DEADBEEF").starts_with("ERR CHECKSUM CRC"));

    assert!(ask1(&mut dev, &with_crc("@1 POS")).starts_with("ERR SESSION"));
    assert!(ask1(&mut dev, "SESSION TOKEN=77").starts_with("OK TOKEN=77"));
    // A window of one block: a MOVE issues its events before its reply.
    let mut dev = Device::with_window(1);
    assert!(ask1(&mut dev, "SESSION TOKEN=77").starts_with("OK TOKEN=77"));
    let request = with_checksum(&with_crc("@5 MOVE X=10 Z=-5"));
    let first = ask(&mut dev, format!("{request}\r\n").as_bytes());
    assert_eq!(first.blocks, 1000, "step events of the block");
    let before = state(&dev);
    let again = ask(&mut dev, format!("{request}\n").as_bytes());
    assert_eq!(again.lines, first.lines);
    assert_eq!(again.blocks, 0);
    assert_eq!(state(&dev), before);
    let body = first.lines[0].rsplit_once(" ~").unwrap().0;
    assert_eq!(body, "OK NX=1000 NZ=-500 PX=1000 PZ=-500 SEQ=34F89895 @5");
    // An id without a CRC word, and an id out of range: refused, unchanged.
    assert!(ask1(&mut dev, "@6 MOVE X=1").starts_with("ERR SYNTAX"));
    assert!(ask1(&mut dev, &with_crc("@4294967296 POS")).starts_with("ERR VALUE @"));
    assert_eq!(state(&dev), before);
}

/// Numbers at the edges: signs, leading zeros, the limit, ties, non-ASCII
/// digits, and the rounding of printed values.
#[test]
fn tricky_numbers() {
    let a = |s: &str| Length::from_mm_str(s).map(Length::as_angstrom);
    assert_eq!(a("-0"), Ok(0));
    assert_eq!(a("+0.000001"), Ok(10));
    assert_eq!(a("0000000000000000000000012"), Ok(120_000_000));
    assert_eq!(a("99999.999999"), Ok(999_999_999_990));
    assert_eq!(a("100000"), Err(LengthError::OutOfRange));
    assert_eq!(a("1000000.1234567"), Err(LengthError::TooManyDecimals));
    assert_eq!(a("1."), Err(LengthError::Malformed));
    assert_eq!(a("\u{663}"), Err(LengthError::Malformed));
    assert_eq!(a("1\u{a0}"), Err(LengthError::Malformed));
    let p = |s: &str| Length::from_mm_str(s).unwrap().to_string();
    assert_eq!(p("-0.00004"), "0.0000");
    assert_eq!(p("-0.00005"), "-0.0001");
    assert_eq!(p("99999.999949"), "99999.9999");

    let mut dev = Device::new();
    // Ties round away from zero: 0.0025 mm is half of a 0.005 mm impulse.
    assert!(ask1(&mut dev, "CFG DIAM=0").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=0.0025 Z=-0.005").starts_with("OK NX=1 NZ=-1 "));
    assert!(ask1(&mut dev, "MOVE X=-0.0025 Z=0.005").starts_with("OK NX=-2 NZ=2 "));
    assert!(ask1(&mut dev, "MOVE X=-0").starts_with("OK NX=1 NZ=0 PX=0 PZ=1 "));
    // Half a nanometre is a seventh decimal: too many for a request's
    // length; a G-code number takes any count, rounded once (here to 0).
    assert!(ask1(&mut dev, "MOVE Z=-0.0000005 INC=1").starts_with("ERR VALUE Z"));
    let r = ask(&mut dev, b"G91 G01 Z-0.0000000000000005 F100\n");
    assert!(r.lines[1].starts_with("OK NX=0 NZ=0 "), "{:?}", r.lines);
    assert!(ask1(&mut dev, "G90").starts_with("OK"));
    assert_eq!(ask1(&mut dev, "POS"), "OK PX=0 PZ=1 X=0.0000 Z=0.0050");
}

/// G-code words written together read by letters: `Z0x10` is Z0 X10, `G001`
/// is G01, `x-1.5` a block; a comment may hold any character, on the
/// device too (a UTF-8 letter, a tape control character), and is never
/// read; outside a comment a request must be printable ASCII.
#[test]
fn gcode_words_written_together() {
    let b = parse_block("N65488 Z0x10").unwrap();
    assert_eq!(b.z.unwrap().as_angstrom(), 0);
    assert_eq!(b.x.unwrap().as_angstrom(), 100_000_000);
    assert!(parse_block("G01 X1 (\u{e9})").is_ok());

    let mut dev = Device::new();
    let r = ask(&mut dev, b"N65488 Z0x10\n");
    assert_eq!(r.lines[0], "DATA G00 X10.0000 Z0.0000");
    assert!(r.lines[1].starts_with("OK NX=1000 NZ=0 "), "{:?}", r.lines);
    let r = ask(&mut dev, b"G001 X2 F100\n");
    assert_eq!(r.lines[0], "DATA G01 X2.0000 Z0.0000");
    assert!(ask1(&mut dev, "G1.5").starts_with("ERR VALUE"));
    let r = ask(&mut dev, "G01 X1 (\u{e9}) ; \u{12}*\n".as_bytes());
    assert_eq!(r.lines[0], "DATA G01 X1.0000 Z0.0000");
    assert!(r.lines[1].starts_with("OK NX=-100 "), "{:?}", r.lines);
    let before = state(&dev);
    assert!(ask1(&mut dev, "G01 X2 \u{e9}").starts_with("ERR SYNTAX"));
    assert!(ask1(&mut dev, "G42 G03 X20 R5").starts_with("ERR GEOMETRY"));
    assert_eq!(state(&dev), before);
}

/// Found by the `protocol` target: a turning cycle's block refused after a
/// move (a `G73` with no relief known, a `G71` with no depth) cleared the
/// session's record of what the last request moved, the one thing a
/// refusal may not change. And a refused block of a profile drops the
/// cycle whole (`docs/cycles.md` §2), which the target now allows.
#[test]
fn a_refused_cycle_block_changes_nothing() {
    let mut dev = Device::new();
    for line in ["OPT DIALECT=FANUC", "G21 G18 G98", "G00 X50. Z2."] {
        assert!(ask(&mut dev, format!("{line}\n").as_bytes())
            .lines
            .last()
            .unwrap()
            .starts_with("OK"));
    }
    let moved = dev.session().last_moves().clone();
    assert_eq!(moved.len(), 1);
    let before = state(&dev);
    for line in [
        "G73 P10 Q40 U.4 W.2 F200.",
        "G71 P10 Q40 U.4 W.2 F200.",
        "G73 U3. W1. R0",
        "G75 X40. Z-5. F100.",
        "G70 P1 Q2",
    ] {
        assert!(ask1(&mut dev, line).starts_with("ERR"), "{line}");
        assert_eq!(dev.session().last_moves(), &moved, "{line}");
        assert_eq!(state(&dev), before, "{line}");
    }
}

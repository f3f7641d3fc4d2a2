//! The handler through its byte interface: every error code, state unchanged
//! after every error, and no input that panics it.

extern crate std;
use super::*;
use proptest::prelude::*;
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

#[derive(Default)]
struct Lines {
    out: Vec<String>,
    blocks: usize,
}

impl Io for Lines {
    fn send(&mut self, line: &[u8]) {
        assert!(line.ends_with(b"\r\n"), "terminator");
        let text = std::str::from_utf8(line).expect("replies are ASCII");
        let text = text.strip_suffix("\r\n").unwrap_or(text);
        let (body, sum) = text.rsplit_once('*').expect("every reply has *HH");
        let xor = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(sum, std::format!("{xor:02X}"), "reply checksum of {text:?}");
        self.out.push(body.to_string());
    }
    fn step(&mut self, _: crate::interleave::StepEvent, _: u64, _: &crate::stepdir::DriveTiming) {
        self.blocks += 1;
    }
}

fn ask(dev: &mut Device, request: &[u8]) -> Vec<String> {
    let mut io = Lines::default();
    dev.receive_bytes(request, &mut io);
    io.out
}

fn ask1(dev: &mut Device, request: &str) -> String {
    let mut r = ask(dev, std::format!("{request}\n").as_bytes());
    assert_eq!(r.len(), 1, "{request:?} -> {r:?}");
    r.remove(0)
}

/// Everything a request could change, as the device reports it.
fn state(dev: &mut Device) -> (String, String, String, String) {
    (
        ask1(dev, "POS"),
        ask1(dev, "CFG"),
        ask1(dev, "DRIVE"),
        ask1(dev, "LIMITS"),
    )
}

fn with_checksum(body: &str) -> String {
    let xor = body.bytes().fold(0u8, |a, b| a ^ b);
    std::format!("{body}*{xor:02X}")
}

/// A device moved away from zero with a non-default configuration.
fn busy_device() -> Device {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG HX=0.0025 TOL=0.02 PASS=ROUGH").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=12.345678 Z=-7.000005").starts_with("OK"));
    dev
}

#[test]
fn every_error_code_is_reached_and_changes_nothing() {
    let mut long = String::from("MOVE X=1 ");
    while long.len() <= framing::MAX_LINE {
        long.push('0');
    }
    let cases: &[(&str, &str)] = &[
        ("MOVE X=1*00", "ERR CHECKSUM"),
        ("MOVE X=1*4", "ERR CHECKSUM"),
        ("MOVE X=1*ZZ", "ERR CHECKSUM"),
        (long.as_str(), "ERR LINE_TOO_LONG"),
        ("", "ERR EMPTY"),
        ("   \t ", "ERR EMPTY"),
        ("*00", "ERR EMPTY"),
        ("FLY X=1", "ERR UNKNOWN"),
        ("MOVE X1", "ERR SYNTAX"),
        ("MOVE Y=1", "ERR SYNTAX"),
        ("MOVE X=1 X=2", "ERR SYNTAX"),
        ("MOVE X= Z=1", "ERR SYNTAX"),
        ("POS X=1", "ERR SYNTAX"),
        ("ZERO now", "ERR SYNTAX"),
        ("VER 2", "ERR SYNTAX"),
        ("MOVE X=1\u{7f}", "ERR SYNTAX"),
        ("MOVE X=abc", "ERR VALUE X"),
        ("MOVE Z=1.0000001", "ERR VALUE Z"),
        ("MOVE Z=1e3", "ERR VALUE Z"),
        ("MOVE X=100000", "ERR VALUE X"),
        ("MOVE X=1 INC=2", "ERR VALUE INC"),
        ("CFG HX=0", "ERR VALUE HX"),
        ("CFG HZ=-0.01", "ERR VALUE HZ"),
        ("CFG HX=1.000001", "ERR VALUE HX"),
        ("CFG DIAM=2", "ERR VALUE DIAM"),
        ("CFG RN=-0.4", "ERR VALUE RN"),
        ("CFG RN=25.000001", "ERR VALUE RN"),
        ("CFG TIP=10", "ERR VALUE TIP"),
        ("CFG TOL=0", "ERR VALUE TOL"),
        ("CFG PASS=FAST", "ERR VALUE PASS"),
        ("CFG HX=0.001 PASS=FAST", "ERR VALUE PASS"),
        ("MOVE Z=-99999", "ERR RANGE"),
        ("MOVE X=99999.99 Z=-7", "ERR RANGE"),
        ("MOVE Z=-99993 INC=1", "ERR RANGE"),
        ("DRIVE RATE=0", "ERR VALUE RATE"),
        ("DRIVE RATE=200001", "ERR VALUE RATE"),
        ("DRIVE RATE=-5", "ERR VALUE RATE"),
        ("DRIVE RATE=10000 PULSE=100", "ERR VALUE PULSE"),
        ("DRIVE PULSE=0", "ERR VALUE PULSE"),
        ("DRIVE SETUP=1001", "ERR VALUE SETUP"),
        ("DRIVE SETUP=12345678", "ERR VALUE SETUP"),
        ("DRIVE HZ=5", "ERR SYNTAX"),
        ("ARC X=1 Z=1", "ERR SYNTAX"),
        ("G01 X1 X2", "ERR SYNTAX"),
        ("G01 Q5", "ERR SYNTAX"),
        ("G04 X1", "ERR SYNTAX G04 needs its time"),
        ("G04 P-1", "ERR VALUE P"),
        ("G99 F1", "ERR VALUE G99 belongs to the FANUC dialect"),
        ("OPT DIALECT=HAAS", "ERR VALUE DIALECT"),
        ("G01 X100000 F10", "ERR VALUE X"),
        ("G01 X30 I1", "ERR SYNTAX"),
        ("G02 X30 Z-7", "ERR SYNTAX"),
        ("G02 X30 Z-7 I1 R2", "ERR SYNTAX"),
        ("G03 X30 Z-7 R0.1", "ERR GEOMETRY"),
        ("G02 X12.345678 Z-7.000005 R3", "ERR GEOMETRY"),
        ("G42 G03 X30 Z-7 R5", "ERR GEOMETRY"),
        ("G450 G451", "ERR SYNTAX"),
        ("G91 X100000", "ERR VALUE X"),
        ("G91 X99999", "ERR RANGE"),
        ("G91 Z-99990", "ERR RANGE"),
        ("ARC X=30 Z=-7 I=0 K=5 DIR=UP", "ERR VALUE DIR"),
        ("ARC X=30 Z=-7 I=0 K=5 DIR=CW MODE=FAST", "ERR VALUE MODE"),
        ("ARC X=30 Z=-7 I=0 K=5 DIR=CW F=0", "ERR VALUE F"),
        ("MOVE X=1 F=0", "ERR VALUE F"),
        ("MOVE X=1 F=-1", "ERR VALUE F"),
        ("MOVE X=1 F=100.1234567", "ERR VALUE F"),
        ("MOVE X=1 F=100001", "ERR VALUE F"),
        ("G01 X1", "ERR VALUE F"),
        ("G01 X1 F0", "ERR VALUE F"),
        ("LIMITS VX=0", "ERR VALUE VX"),
        ("LIMITS VZ=-5", "ERR VALUE VZ"),
        ("LIMITS AX=9.999999", "ERR VALUE AX"),
        ("LIMITS AZ=100000.000001", "ERR VALUE AZ"),
        ("LIMITS JD=10.000001", "ERR VALUE JD"),
        ("LIMITS VX=100 VZ=99999", "ERR VALUE VZ"),
        ("LIMITS VX=1 QX=2", "ERR SYNTAX"),
        ("DRIVE RATE=1000", "ERR VALUE RATE"),
        ("SYNC NOW", "ERR SYNTAX"),
        ("STATUS 1", "ERR SYNTAX"),
        (
            "ARC X=30 Z=-7 I=0 K=5 DIR=CW MODE=DIRECT F=0",
            "ERR VALUE F",
        ),
        ("ARC X=30 Z=-7 I=0 K=5 DIR=CW TOL=2", "ERR VALUE TOL"),
        ("ARC X=30 Z=-7 I=0 K=0 DIR=CW", "ERR GEOMETRY"),
        ("ARC X=40 Z=-7 I=0 K=1 DIR=CW", "ERR GEOMETRY"),
        (
            "ARC X=12.345678 Z=-7.000005 I=0 K=999 DIR=CCW TOL=0.000001",
            "ERR RANGE",
        ),
        (
            "ARC X=12.345678 Z=-7.000005 I=-5 K=0 DIR=CCW MODE=DIRECT",
            "ERR GEOMETRY",
        ),
        (
            "ARC X=12.345678 Z=-7.000005 I=99999 K=0 DIR=CCW",
            "ERR RANGE",
        ),
        ("MOVE Z=-10007.01", "ERR RANGE"),
    ];
    for &(request, expected) in cases {
        let mut dev = busy_device();
        let before = state(&mut dev);
        let mut io = Lines::default();
        dev.receive_bytes(std::format!("{request}\r\n").as_bytes(), &mut io);
        assert_eq!(io.out.len(), 1, "{request:?} -> {:?}", io.out);
        assert!(
            io.out[0].starts_with(expected),
            "{request:?} -> {:?}, expected {expected}",
            io.out
        );
        assert_eq!(io.blocks, 0, "{request:?} moved an axis");
        assert_eq!(state(&mut dev), before, "{request:?} changed state");
    }
}

#[test]
fn range_of_increments_and_block_length() {
    // The coordinate limit: 99999.999999 mm is the last representable value.
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG DIAM=0 HZ=0.1").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE Z=99999.99").starts_with("OK NX=0 NZ=1000000 "));
    let before = state(&mut dev);
    assert!(ask1(&mut dev, "MOVE Z=0.01 INC=1").starts_with("ERR RANGE"));
    assert_eq!(state(&mut dev), before);
    assert!(ask1(&mut dev, "MOVE Z=0.009999 INC=1").starts_with("OK NX=0 NZ=0 "));
    // Exactly 1 000 000 impulses in a block: accepted; one more: refused.
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG DIAM=0").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=5000").starts_with("OK NX=1000000 "));
    assert!(ask1(&mut dev, "MOVE X=-0.005").starts_with("ERR RANGE"));
    assert!(ask1(&mut dev, "MOVE X=-0.0025").starts_with("ERR RANGE"));
    assert!(ask1(&mut dev, "MOVE X=-0.002499").starts_with("OK NX=-1000000 "));
    // A finer price that would put the register beyond 999 999 999: refused.
    assert!(ask1(&mut dev, "MOVE X=5000").starts_with("OK NX=1000000 "));
    let before = state(&mut dev);
    assert!(ask1(&mut dev, "CFG HX=0.000005").starts_with("ERR RANGE"));
    assert_eq!(state(&mut dev), before);
    // So fine a price needs a slow rapid rate: VX/HX within DRIVE RATE.
    assert!(ask1(&mut dev, "CFG HX=0.000006").starts_with("ERR VALUE HX"));
    assert!(ask1(&mut dev, "LIMITS VX=10").starts_with("OK VX=10.0000 "));
    assert!(ask1(&mut dev, "CFG HX=0.000006").starts_with("OK"));
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=833333333 "));
}

#[test]
fn replies_of_the_happy_path() {
    let mut dev = Device::new();
    assert_eq!(
        ask1(&mut dev, "ver"),
        std::format!("OK PROTO=1 NAME={NAME} VERSION={VERSION}")
    );
    assert_eq!(
        ask1(&mut dev, "CFG"),
        "OK HX=0.0050 HZ=0.0100 DIAM=1 RN=0.4000 TIP=3 TOL=0.0100 PASS=FIN"
    );
    assert_eq!(
        ask1(&mut dev, "cfg tip=2 rn=0.8 pass=rough tol=0.005"),
        "OK HX=0.0050 HZ=0.0100 DIAM=1 RN=0.8000 TIP=2 TOL=0.0050 PASS=ROUGH"
    );
    assert_eq!(
        ask1(&mut dev, &with_checksum("MOVE X=0.005 Z=-0.015")),
        "OK NX=1 NZ=-2 PX=1 PZ=-2 SEQ=42F8222A"
    );
    assert_eq!(ask1(&mut dev, "POS"), "OK PX=1 PZ=-2 X=0.0050 Z=-0.0150");
    assert_eq!(
        ask1(&mut dev, "move x=-0.005 inc=1"),
        "OK NX=-1 NZ=0 PX=0 PZ=-2 SEQ=A2681B02"
    );
    assert_eq!(
        ask1(&mut dev, "CFG DIAM=0"),
        "OK HX=0.0050 HZ=0.0100 DIAM=0 RN=0.8000 TIP=2 TOL=0.0050 PASS=ROUGH"
    );
    assert_eq!(ask1(&mut dev, "POS"), "OK PX=0 PZ=-2 X=0.0000 Z=-0.0150");
    assert_eq!(ask1(&mut dev, "ZERO"), "OK");
    assert_eq!(ask1(&mut dev, "POS"), "OK PX=0 PZ=0 X=0.0000 Z=0.0000");
    assert_eq!(
        ask1(&mut dev, "MOVE"),
        "OK NX=0 NZ=0 PX=0 PZ=0 SEQ=00000000"
    );
}

#[test]
fn arcs_by_chords_and_direct() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG DIAM=0").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE Z=10").starts_with("OK"));
    let r = ask(&mut dev, b"ARC X=10 Z=0 I=0 K=-10 DIR=CCW\n");
    // 18 chords of 5.125° (18450″), then the summary.
    assert_eq!(r.len(), 19, "{r:?}");
    let (mut nx, mut nz) = (0, 0);
    for (i, line) in r[..18].iter().enumerate() {
        let w: Vec<&str> = line.split(' ').collect();
        assert_eq!(w[0], "DATA");
        assert_eq!(w[1], std::format!("I={}", i + 1));
        nx += w[2].strip_prefix("NX=").unwrap().parse::<i32>().unwrap();
        nz += w[3].strip_prefix("NZ=").unwrap().parse::<i32>().unwrap();
    }
    assert_eq!((nx, nz), (2000, -1000));
    assert!(
        r[18].starts_with("OK N=18 DPHI=5.125000 NX=2000 NZ=-1000 PX=2000 PZ=0 SEQ="),
        "{}",
        r[18]
    );
    assert_eq!(ask1(&mut dev, "POS"), "OK PX=2000 PZ=0 X=10.0000 Z=0.0000");
    // A full circle back to the same point issues nothing in total.
    let r = ask(
        &mut dev,
        b"ARC X=10 Z=0 I=-10 K=0 DIR=CW TOL=0.1 PASS=ROUGH\n",
    );
    assert!(
        r.last()
            .unwrap()
            .starts_with("OK N=23 DPHI=16.219444 NX=0 NZ=0 PX=2000 PZ=0 "),
        "{r:?}"
    );
    // The ЭМ-907 block of the seed's Ø50 sphere (R25, to the top).
    assert!(ask1(&mut dev, "ZERO").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=21.986134 Z=11.9").starts_with("OK"));
    let r = ask(
        &mut dev,
        b"ARC X=25 Z=0 I=-21.986134 K=-11.9 DIR=CCW MODE=DIRECT F=35.5\n",
    );
    assert_eq!(r[0], "DATA G03 X+603 Z-1190 J4397 K1190 F1420");
    assert!(r[1].starts_with("OK N="), "{r:?}");
    assert!(r[1].contains(" NX=603 NZ=-1190 PX=5000 PZ=0 SEQ="), "{r:?}");
}

#[test]
fn gcode_blocks_run_in_modal_state() {
    let mut dev = Device::new();
    // Krylenko Fig. 22 as written (diameters), with its R arcs.
    let program = [
        ("G00 X10 Z10", "DATA G00 X10.0000 Z10.0000"),
        ("N9 G01 X7.2 Z0 F100 ; point 2", "DATA G01 X7.2000 Z0.0000"),
        (
            "G03 X12 Z-2.4 R2.4",
            "DATA G03 X12.0000 Z-2.4000 I0.0000 K-2.4000",
        ),
        ("G01 Z-14.4", "DATA G01 X12.0000 Z-14.4000"),
        (
            "G02 X17.2 Z-17 R2.6",
            "DATA G02 X17.2000 Z-17.0000 I2.6000 K0.0000",
        ),
        ("G01 X29.2", "DATA G01 X29.2000 Z-17.0000"),
        (
            "G03 X38 Z-21.4 R4.4",
            "DATA G03 X38.0000 Z-21.4000 I0.0000 K-4.4000",
        ),
        ("X40", "DATA G03 X40.0000 Z-21.4000 I0.0000 K0.0000"),
    ];
    for (i, (block, data)) in program.iter().enumerate().take(7) {
        let r = ask(&mut dev, std::format!("{block}\n").as_bytes());
        assert_eq!(r.len(), 2, "{block}: {r:?}");
        assert_eq!(r[0], *data, "block {i}");
        assert!(r[1].starts_with("OK NX="), "{r:?}");
    }
    // G03 stays modal: a block with only X and no centre is refused.
    assert!(ask1(&mut dev, program[7].0).starts_with("ERR SYNTAX"));
    // G91: increments; G90 back to absolute.
    assert!(ask(&mut dev, b"G91 G01 Z-1\n")[0].starts_with("DATA G01 X38.0000 Z-22.4000"));
    assert!(ask(&mut dev, b"G90 Z0\n")[0].starts_with("DATA G01 X38.0000 Z0.0000"));
    // A block with no motion words only changes the modal state.
    assert!(ask1(&mut dev, "N100 G01 M03 S500 T01").starts_with("OK NX=0 NZ=0 "));
}

#[test]
fn gcode_arcs_equal_arc_requests() {
    // The same arc as G03 with I/K, as G03 with R, and as ARC: same chords.
    let run = |setup: &str, arc: &str| {
        let mut dev = Device::new();
        for l in ["CFG DIAM=0 TOL=0.002", setup] {
            assert!(ask1(&mut dev, l).starts_with("OK"), "{l}");
        }
        let r = ask(&mut dev, std::format!("{arc}\n").as_bytes());
        let last = r.last().unwrap().clone();
        let keys: Vec<String> = last
            .split(' ')
            .filter(|w| {
                ["NX=", "NZ=", "PX=", "PZ=", "SEQ="]
                    .iter()
                    .any(|k| w.starts_with(k))
            })
            .map(String::from)
            .collect();
        (keys, ask1(&mut dev, "POS"))
    };
    let by_arc = run("MOVE X=14.6 Z=-17", "ARC X=19 Z=-21.4 I=0 K=-4.4 DIR=CCW");
    let by_ik = run("MOVE X=14.6 Z=-17", "G03 X19 Z-21.4 I0 K-4.4 F100");
    let by_r = run("MOVE X=14.6 Z=-17", "G03 X19 Z-21.4 R4.4 F100");
    assert_eq!(by_arc, by_ik);
    assert_eq!(by_arc, by_r);
    // The long way round with a negative R: 270° instead of 90°.
    let long = run("MOVE X=14.6 Z=-17", "G03 X19 Z-21.4 R-4.4 F100");
    assert_ne!(long.0, by_r.0);
    assert_eq!(long.1, by_r.1);
}

/// Appends ` ~CCCCCCCC`, the CRC-32 of everything before the `~`.
fn with_crc(body: &str) -> String {
    let mut c = crate::crc32::Crc32::new();
    c.update(body.as_bytes());
    c.push(b' ');
    std::format!("{body} ~{:08X}", c.finish())
}

#[test]
fn request_ids_make_retries_idempotent() {
    let mut dev = Device::new();
    let strip = |l: String| l.rsplit_once(" ~").unwrap().0.to_string();
    // No session yet: a numbered request is refused before it runs.
    assert!(ask1(&mut dev, &with_crc("@3 MOVE X=1 INC=1")).starts_with("ERR SESSION"));
    assert!(ask1(&mut dev, &with_crc("@4 SESSION TOKEN=77")).starts_with("OK TOKEN=77 @4"));
    let first = strip(ask1(&mut dev, &with_crc("@7 MOVE X=1 INC=1")));
    assert_eq!(first, "OK NX=100 NZ=0 PX=100 PZ=0 SEQ=E058315F @7");
    // The same id again: the remembered reply, no second motion.
    let mut io = Lines::default();
    dev.receive_bytes(
        std::format!("{}\n", with_crc("@7 MOVE X=1 INC=1")).as_bytes(),
        &mut io,
    );
    assert_eq!(io.out.len(), 1);
    assert_eq!(strip(io.out[0].clone()), first);
    assert_eq!(io.blocks, 0);
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=100 "));
    // A new id runs again.
    assert!(ask1(&mut dev, &with_crc("@8 MOVE X=1 INC=1")).starts_with("OK NX=100 NZ=0 PX=200 "));
    // Refusals are remembered too, and ids are checked.
    assert!(ask1(&mut dev, &with_crc("@9 MOVE X=abc")).starts_with("ERR VALUE X"));
    assert!(ask1(&mut dev, &with_crc("@9 MOVE X=1")).starts_with("ERR VALUE X"));
    assert!(ask1(&mut dev, &with_crc("@0 POS")).starts_with("ERR VALUE @"));
    assert!(ask1(&mut dev, &with_crc("@4294967296 POS")).starts_with("ERR VALUE @"));
    assert!(ask1(&mut dev, &with_crc("@x POS")).starts_with("ERR VALUE @"));
    // An id without a CRC word is refused: a broken line must not run.
    assert!(ask1(&mut dev, "@11 MOVE X=1 INC=1").starts_with("ERR SYNTAX"));
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=200 "));
    // G-code blocks take ids as well.
    let r = ask(
        &mut dev,
        std::format!("{}\n", with_crc("@10 G01 X4 F100")).as_bytes(),
    );
    assert!(r[0].starts_with("DATA G01 X4.0000 Z0.0000 @10 ~"), "{r:?}");
    assert!(r[1].contains(" @10 ~"));
}

#[test]
fn crc_words_guard_requests_and_replies() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "SESSION TOKEN=1").starts_with("OK"));
    let line = with_crc("@1 MOVE X=10 Z=-5");
    let reply = ask1(&mut dev, &with_checksum(&line));
    let (body, crc) = reply.rsplit_once(" ~").unwrap();
    let mut c = crate::crc32::Crc32::new();
    c.update(body.as_bytes());
    c.push(b' ');
    assert_eq!(crc, std::format!("{:08X}", c.finish()));
    assert!(body.starts_with("OK NX=1000 NZ=-500 PX=1000 PZ=-500 SEQ=34F89895 @1"));
    // Two flipped bits that the XOR cannot see: the CRC refuses the line.
    let before = state(&mut dev);
    // "10" → "01": the same bytes in another order, so the same XOR.
    let bad = line.replacen("MOVE X=10", "MOVE X=01", 1);
    let mut io = Lines::default();
    dev.receive_bytes(std::format!("{bad}\n").as_bytes(), &mut io);
    assert_eq!(io.out.len(), 1);
    assert!(io.out[0].starts_with("ERR CHECKSUM CRC"), "{:?}", io.out);
    assert_eq!(io.blocks, 0);
    assert_eq!(state(&mut dev), before);
    // A word that only looks like a CRC is part of the request.
    assert!(ask1(&mut dev, "MOVE X=1~0000").starts_with("ERR VALUE X"));
}

#[test]
fn session_token_and_zero_at_a_point() {
    let mut dev = Device::new();
    assert_eq!(ask1(&mut dev, "SESSION"), "OK TOKEN=0");
    assert_eq!(
        ask1(&mut dev, "SESSION TOKEN=4294967295"),
        "OK TOKEN=4294967295"
    );
    assert!(ask1(&mut dev, "SESSION TOKEN=4294967296").starts_with("ERR VALUE TOKEN"));
    assert!(ask1(&mut dev, "SESSION TOKEN=+1").starts_with("ERR VALUE TOKEN"));
    assert_eq!(ask1(&mut dev, "ZERO X=27.5325 Z=-0.015"), "OK");
    // 13.76625 / 0.005 = 2753.25 → 2753; −0.015 / 0.01 = −1.5 → −2.
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=2753 PZ=-2 X=27.5325 Z=-0.0150"
    );
    assert!(ask1(&mut dev, "ZERO Y=1").starts_with("ERR SYNTAX"));
}

#[test]
fn price_change_re_expresses_registers() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "MOVE X=10.01 Z=3.333").starts_with("OK NX=1001 NZ=333 "));
    assert_eq!(
        ask1(&mut dev, "CFG HX=0.001 HZ=0.002"),
        "OK HX=0.0010 HZ=0.0020 DIAM=1 RN=0.4000 TIP=3 TOL=0.0100 PASS=FIN"
    );
    // 5.005 mm / 0.001 = 5005; 3.333 / 0.002 = 1666.5 → 1667.
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=5005 PZ=1667 X=10.0100 Z=3.3330"
    );
}

#[test]
fn garbage_and_framing() {
    let mut dev = busy_device();
    let before = state(&mut dev);
    let r = ask(&mut dev, b"\x00\xff\xfe MOVE\n");
    assert_eq!(r.len(), 1);
    assert!(r[0].starts_with("ERR SYNTAX"));
    // CRLF is one terminator; a lone CR and a lone LF each end a line.
    let r = ask(&mut dev, b"POS\r\nPOS\rPOS\n");
    assert_eq!(r.len(), 3);
    // The rest of an over-long line is discarded up to its terminator.
    let mut long = std::vec![b'M'; 300];
    long.extend_from_slice(b"\r\nPOS\r\n");
    let r = ask(&mut dev, &long);
    assert_eq!(r.len(), 2);
    assert!(r[0].starts_with("ERR LINE_TOO_LONG"));
    assert!(r[1].starts_with("OK PX="));
    assert_eq!(state(&mut dev), before);
    // A lower-case checksum is accepted.
    let line = with_checksum("POS").to_lowercase().replace("pos", "POS");
    assert!(ask1(&mut dev, &line).starts_with("OK PX="));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Any bytes: no panic, exactly one final reply line per request line,
    /// and every reply well formed (checked by `Lines`).
    #[test]
    fn any_bytes_one_final_line_per_request(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let mut dev = busy_device();
        let mut io = Lines::default();
        dev.receive_bytes(&bytes, &mut io);
        // Count the requests the framing saw: terminators, CRLF counted once,
        // plus over-long stretches reported early.
        let mut expected = 0;
        let mut run = 0usize;
        let mut over = false;
        let mut prev_cr = false;
        // Real-time bytes are picked out wherever they fall, one `!` line
        // each.
        let mut realtime = 0;
        for &b in &bytes {
            if let Some(rt) = super::Realtime::from_byte(b) {
                realtime += 1;
                if rt == super::Realtime::Reset {
                    // A reset drops the line being received.
                    (run, over, prev_cr) = (0, false, false);
                }
                continue;
            }
            let is_cr = b == b'\r';
            if b == b'\n' && prev_cr {
            } else if b == b'\r' || b == b'\n' {
                if !over { expected += 1; }
                over = false;
                run = 0;
            } else if !over {
                run += 1;
                if run > framing::MAX_LINE { expected += 1; over = true; }
            }
            prev_cr = is_cr;
        }
        let finals = io.out.iter().filter(|l| l.starts_with("OK") || l.starts_with("ERR ")).count();
        let data = io.out.iter().filter(|l| l.starts_with("DATA ")).count();
        let bang = io.out.iter().filter(|l| l.starts_with('!')).count();
        prop_assert_eq!(finals + data + bang, io.out.len());
        prop_assert_eq!(finals, expected);
        prop_assert_eq!(bang, realtime);
    }

    /// Random printable requests built from protocol words never panic, and a
    /// refused one changes nothing.
    #[test]
    fn word_salad_errors_change_nothing(words in proptest::collection::vec(
        prop_oneof![
            Just("MOVE"), Just("CFG"), Just("POS"), Just("ZERO"), Just("VER"),
            Just("X=1.5"), Just("Z=-0.0000005"), Just("X=99999.999999"), Just("INC=1"),
            Just("HX=0.000001"), Just("HZ=1"), Just("DIAM=0"), Just("TIP=9"), Just("RN=0"),
            Just("="), Just("X=="), Just("*"), Just("Z=-"), Just("TOL=1.0000000"), Just("PASS=FIN"),
        ], 0..8)) {
        let mut dev = busy_device();
        let before = state(&mut dev);
        let line = words.join(" ");
        let reply = ask1(&mut dev, &line);
        if reply.starts_with("ERR") {
            prop_assert_eq!(state(&mut dev), before);
        }
    }
}

/// The DATA lines and the final line of each block of a program.
fn run_program(dev: &mut Device, program: &[&str]) -> Vec<Vec<String>> {
    program
        .iter()
        .map(|b| ask(dev, std::format!("{b}\n").as_bytes()))
        .collect()
}

fn data(replies: &[Vec<String>]) -> Vec<String> {
    replies
        .iter()
        .flatten()
        .filter_map(|l| l.strip_prefix("DATA ").map(String::from))
        .collect()
}

#[test]
fn krylenko_fig_22_from_a_g42_contour() {
    let mut dev = Device::new();
    let r = run_program(
        &mut dev,
        &[
            "G00 X0 Z5",
            "N1 G42 G01 Z0 F100",
            "N2 X8",
            "N3 G03 X12 Z-2 R2",
            "N4 G01 Z-14",
            "N5 G02 X18 Z-17 R3",
            "N6 G01 X30",
            "N7 G03 X38 Z-21 R4",
            "N8 G01 Z-30",
            "N9 G40 X45",
        ],
    );
    assert!(
        r.iter().all(|l| l.last().unwrap().starts_with("OK")),
        "{r:?}"
    );
    // The start-up block is sent with the block after it.
    assert_eq!(r[1].len(), 1);
    assert_eq!(
        data(&r),
        [
            "G00 X0.0000 Z5.0000",
            "G01 X-0.8000 Z0.0000",
            "G01 X7.2000 Z0.0000",
            "G03 X12.0000 Z-2.4000 I0.0000 K-2.4000",
            "G01 X12.0000 Z-14.4000",
            "G02 X17.2000 Z-17.0000 I2.6000 K0.0000",
            "G01 X29.2000 Z-17.0000",
            "G03 X38.0000 Z-21.4000 I0.0000 K-4.4000",
            "G01 X38.0000 Z-30.4000",
            "G01 X45.0000 Z-30.0000",
        ]
    );
    // After G40 the tool tip is at the programmed point again.
    assert!(ask1(&mut dev, "POS").ends_with("X=45.0000 Z=-30.0000"));
}

#[test]
fn compensation_refusals_name_the_block_and_change_nothing() {
    let prefix = ["CFG RN=0.8", "G00 X20 Z5", "G42 G01 Z0 F100", "N10 X40"];
    // (bad block, expected error, a good block to send after it)
    let cases: &[(&[&str], &str, &str, &str)] = &[
        // A concave arc of radius 0.5 with a 0.8 nose.
        (
            &[],
            "N20 G02 X41 Z-0.5 R0.5",
            "ERR GEOMETRY N20: concave",
            "N20 G01 Z-10",
        ),
        // Compensation switched off in an arc block.
        (
            &[],
            "N20 G40 G03 X44 Z-2 R2",
            "ERR GEOMETRY N20: compensation switched off",
            "N20 G01 Z-10",
        ),
        // Sides change only through G40.
        (
            &[],
            "N20 G41 G01 Z-10",
            "ERR GEOMETRY N20: change between G41 and G42",
            "N20 G01 Z-10",
        ),
        // A 0.2 mm chamfer between two inside corners, too short for the nose.
        (
            &["N20 G01 Z-10", "N30 X40.4 Z-10.2"],
            "N40 X60",
            "ERR GEOMETRY N30 too short for the nose radius: it reverses at its corner with N40",
            "N40 X42 Z-11",
        ),
        // An arc whose end is not on its circle.
        (
            &[],
            "N20 G03 X44 Z-2 I0 K-2.5",
            "ERR GEOMETRY start and end radii",
            "N20 G01 Z-10",
        ),
        // MOVE, ARC, ZERO and a new nose radius wait for G40.
        (
            &[],
            "MOVE X=1",
            "ERR GEOMETRY MOVE not allowed",
            "N20 G01 Z-10",
        ),
        (&[], "ZERO", "ERR GEOMETRY ZERO not allowed", "N20 G01 Z-10"),
        (
            &[],
            "CFG RN=0.4",
            "ERR GEOMETRY CFG RN or TIP not allowed",
            "N20 G01 Z-10",
        ),
    ];
    for &(more, bad, expected, good) in cases {
        let mut with = Device::new();
        let mut without = Device::new();
        for b in prefix.iter().chain(more) {
            for dev in [&mut with, &mut without] {
                assert!(
                    ask(dev, std::format!("{b}\n").as_bytes())
                        .last()
                        .unwrap()
                        .starts_with("OK"),
                    "{b}"
                );
            }
        }
        let r = ask(&mut with, std::format!("{bad}\n").as_bytes());
        assert_eq!(r.len(), 1, "{bad}: {r:?}");
        assert!(r[0].starts_with(expected), "{bad}: {r:?}");
        let after = [good, "N90 G01 X70", "N99 G40 X80 Z10"];
        assert_eq!(
            run_program(&mut with, &after),
            run_program(&mut without, &after),
            "{bad}"
        );
    }
}

#[test]
fn compensation_on_in_an_arc_block_is_refused() {
    let mut dev = Device::new();
    assert_eq!(ask(&mut dev, b"G00 X20 Z5\n").len(), 2);
    let r = ask(&mut dev, b"N5 G42 G03 X24 Z3 R2\n");
    assert_eq!(
        r,
        ["ERR GEOMETRY N5: compensation switched on in an arc block"]
    );
    // A G42 block without motion arms it; the next motion is the start-up.
    assert_eq!(ask(&mut dev, b"G42\n").len(), 1);
    let r = ask(&mut dev, b"N6 G03 X24 Z3 R2\n");
    assert_eq!(
        r,
        ["ERR GEOMETRY N6: compensation switched on in an arc block"]
    );
}

#[test]
fn corner_modes_and_tip_codes() {
    // An outside 90° corner (G42 along the face, then down the cylinder):
    // G451 squares it at the intersection, G450 rounds it with the nose radius.
    let program = |corner: &str, tip: &str| {
        let mut dev = Device::new();
        let setup = std::format!("CFG DIAM=0 TIP={tip}");
        let lines = [
            "G00 X20 Z5",
            corner,
            "G41 G01 X10 F100",
            "X10 Z-10",
            "X20",
            "G40 X30 Z-20",
        ];
        assert!(ask1(&mut dev, &setup).starts_with("OK"));
        data(&run_program(&mut dev, &lines))
    };
    let int = program("G451", "9");
    let arc = program("G450", "9");
    assert_eq!(int.len() + 1, arc.len(), "{int:?} {arc:?}");
    assert!(
        arc.iter()
            .any(|l| l.starts_with("G02") || l.starts_with("G03")),
        "{arc:?}"
    );
    // The tip code shifts every compensated point by the same vector.
    let shifted = program("G451", "1");
    assert_eq!(int.len(), shifted.len());
    let xz = |l: &str| -> (f64, f64) {
        let w: Vec<&str> = l.split(' ').collect();
        (w[1][1..].parse().unwrap(), w[2][1..].parse().unwrap())
    };
    for (a, b) in int.iter().zip(&shifted).skip(1).take(3) {
        let (p, q) = (xz(a), xz(b));
        assert!(
            (q.0 - p.0 - 0.4).abs() < 1e-9 && (q.1 - p.1 - 0.4).abs() < 1e-9,
            "{a} / {b}"
        );
    }
}

#[test]
fn reset_abandons_a_contour_whose_corner_cannot_be_cut() {
    let mut dev = Device::new();
    let program = [
        "CFG RN=0.8",
        "G00 X20 Z5",
        "G42 G01 Z0 F100",
        "N10 X40",
        "N20 Z-10",
        "N30 X40.4 Z-10.2",
    ];
    for b in program {
        assert!(
            ask(&mut dev, std::format!("{b}\n").as_bytes())
                .last()
                .unwrap()
                .starts_with("OK"),
            "{b}"
        );
    }
    // The chamfer is too short for the nose whatever comes next, G40 included.
    assert!(ask1(&mut dev, "N40 X60").starts_with("ERR GEOMETRY N30 too short"));
    assert!(ask1(&mut dev, "G40").starts_with("ERR GEOMETRY N30 too short"));
    assert!(ask1(&mut dev, "MOVE X=50").starts_with("ERR GEOMETRY MOVE not allowed"));
    let pos = ask1(&mut dev, "POS");
    assert_eq!(ask1(&mut dev, "RESET"), "OK");
    assert_eq!(ask1(&mut dev, "POS"), pos, "RESET moves nothing");
    assert!(ask1(&mut dev, "RESET 1").starts_with("ERR SYNTAX"));
    // Compensation is off: blocks run as written from where the tool is.
    let z = pos.rsplit_once(" Z=").unwrap().1;
    let r = ask(&mut dev, b"G01 X50\n");
    assert_eq!(r[0], std::format!("DATA G01 X50.0000 Z{z}"), "{r:?}");
    assert!(ask1(&mut dev, "MOVE X=50").starts_with("OK"));
}

/// A chord end exactly on a rounding boundary rounds away from zero: with
/// R = 0.02 mm and TOL = 0.01 mm, Δφ = 2·arccos(½) = 120° exactly, and the
/// first chord of a full circle from the top ends at Z − R/2, on the
/// boundary −875.5 of 0.01 mm impulses (cos 120° = −½ exactly).
#[test]
fn a_chord_end_on_a_rounding_boundary_rounds_away_from_zero() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "CFG HX=0.005 HZ=0.01 DIAM=0 TOL=0.01 PASS=FIN").starts_with("OK"));
    assert!(ask1(&mut dev, "MOVE X=21.255 Z=-8.725").starts_with("OK NX=4251 NZ=-873"));
    let r = ask(&mut dev, b"ARC X=21.255 Z=-8.725 I=0 K=-0.02 DIR=CCW\n");
    assert_eq!(r.len(), 4, "{r:?}");
    assert!(r[3].contains("DPHI=120.000000"), "{r:?}");
    // Z: −873 → −876 (−8.755 mm is −875.5 impulses); X: 21.27232 mm.
    assert_eq!(r[0], "DATA I=1 NX=3 NZ=-3");
}

#[test]
fn real_time_bytes_act_at_once_and_leave_the_line_around_them_whole() {
    let mut dev = Device::new();
    ask1(&mut dev, "MOVE X=10 Z=-5 F=200");
    // A status byte inside a request: its line first, the request after.
    let r = ask(&mut dev, b"PO\x80S\n");
    assert_eq!(r.len(), 2, "{r:?}");
    assert!(r[0].starts_with("!STATUS STATE=RUN PX=0 PZ=0"), "{r:?}");
    assert!(r[0].starts_with("!STATUS STATE=RUN PX=0 PZ=0 X=0.0000 Z=0.0000 V=0.0000 Q=1"));
    assert!(r[1].starts_with("OK PX=1000 PZ=-500"));
    // The same characters printable inside a comment or a CRC word are
    // text: `?`, `!`, `~` are not real-time bytes here.
    let r = ask(&mut dev, b"G1 X10 Z-5 (ok? yes! ~) F100\n");
    assert!(r.last().unwrap().starts_with("OK"), "{r:?}");
    // Hold and resume on the virtual clock: nothing moves in time, the
    // state stays as it was.
    let r = ask(&mut dev, b"\x82\x81");
    assert_eq!(r.len(), 2);
    assert!(
        r.iter().all(|l| l.starts_with("!STATUS STATE=RUN")),
        "{r:?}"
    );
}

#[test]
fn a_reset_byte_drops_the_queue_keeps_the_registers_and_ends_the_session() {
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "SESSION TOKEN=7").starts_with("OK"));
    ask1(&mut dev, "MOVE X=10 Z=-5 F=200");
    assert!(ask1(&mut dev, "SYNC").starts_with("OK EV=1000"));
    ask(&mut dev, b"G1 X20 Z-10 F300\n");
    let r = ask(&mut dev, b"\x18");
    // The queued block never started: nothing was running.
    assert_eq!(r.len(), 1);
    assert!(
        r[0].starts_with("!RESET DONE=0 OF=0 PX=1000 PZ=-500"),
        "{r:?}"
    );
    // The commanded point is where the steps are; the queue is empty.
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=1000 PZ=-500 X=10.0000 Z=-5.0000"
    );
    assert!(ask1(&mut dev, "SYNC").starts_with("OK EV=0"));
    // As after a power cycle: no feed, no session token.
    assert!(ask1(&mut dev, "G1 X30").starts_with("ERR VALUE F"));
    assert!(ask1(&mut dev, &with_crc("@5 POS")).starts_with("ERR SESSION"));
    assert_eq!(ask1(&mut dev, "SESSION"), "OK TOKEN=0");
}

#[test]
fn a_long_arc_check_pauses_for_the_transport_every_few_chords() {
    #[derive(Default)]
    struct Pauses {
        pauses: u32,
        last: String,
    }
    impl Io for Pauses {
        fn send(&mut self, line: &[u8]) {
            self.last = String::from_utf8_lossy(line).trim_end().to_string();
        }
        fn pause(&mut self) {
            self.pauses += 1;
        }
    }
    let chords = |reply: &str| -> u32 {
        let n = reply.split(' ').find_map(|w| w.strip_prefix("N="));
        n.unwrap().parse().unwrap()
    };
    let mut dev = Device::new();
    ask1(&mut dev, "CFG DIAM=0");
    ask1(&mut dev, "MOVE X=37.5");
    // A full circle, R 37.5 mm at σ 0.001 mm: the check pauses every
    // CHORDS_PER_PAUSE chords (and the chords themselves do not).
    let mut io = Pauses::default();
    dev.receive_bytes(b"ARC X=37.5 Z=0 I=-37.5 K=0 DIR=CW TOL=0.001\n", &mut io);
    let n = chords(&io.last);
    assert!(n > 400, "{}", io.last);
    assert_eq!(io.pauses, n / CHORDS_PER_PAUSE);
    // Through a session's numbered, CRC-checked requests the same.
    let mut io = Pauses::default();
    dev.receive_bytes(
        std::format!("{}\n", with_crc("@1 SESSION TOKEN=5")).as_bytes(),
        &mut io,
    );
    let mut io = Pauses::default();
    dev.receive_bytes(
        std::format!(
            "{}\n",
            with_crc("@2 ARC X=37.5 Z=0 I=-37.5 K=0 DIR=CW TOL=0.001")
        )
        .as_bytes(),
        &mut io,
    );
    assert!(io.last.starts_with("OK N="), "{}", io.last);
    assert_eq!(io.pauses, n / CHORDS_PER_PAUSE);
    // And a G-code arc of the same circle, half of it.
    ask1(&mut dev, "CFG TOL=0.001");
    let mut io = Pauses::default();
    dev.receive_bytes(b"G02 X-37.5 Z0 I-37.5 K0 F100\n", &mut io);
    assert!(io.last.starts_with("OK"), "{}", io.last);
    assert_eq!(io.pauses, n.div_ceil(2) / CHORDS_PER_PAUSE, "{}", io.pauses);
}

#[test]
fn a_posted_program_runs_line_by_line_and_names_what_it_cannot() {
    let mut dev = Device::new();
    let program = [
        "%",
        "O1000 (SHAFT 30 X 40)",
        "(MSG, CHECK THE STOCK)",
        "N5 G18 G21 G40",
        "N10 G00 X30. Z2. Y0",
        "N20 G01 Z-40. F120.",
        "/N30 X32.",
        "N40 X.5 ; facing down",
        "%",
    ];
    for line in program {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
    }
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=50 PZ=-4000 "));
    // With the block delete switch on, `/` blocks are skipped, and say so.
    assert_eq!(ask1(&mut dev, "OPT"), "OK BDEL=0 DIALECT=ISO OPTSTOP=0");
    assert_eq!(
        ask1(&mut dev, "OPT BDEL=1"),
        "OK BDEL=1 DIALECT=ISO OPTSTOP=0"
    );
    assert_eq!(
        ask1(&mut dev, "OPT OPTSTOP=1"),
        "OK BDEL=1 DIALECT=ISO OPTSTOP=1"
    );
    assert_eq!(
        ask1(&mut dev, "OPT OPTSTOP=2"),
        "ERR VALUE OPTSTOP must be 0 or 1"
    );
    let r = ask(&mut dev, b"/N50 X40.\n");
    assert_eq!(r.len(), 1);
    assert!(r[0].ends_with(" SEQ=00000000 SKIP=BDEL"), "{r:?}");
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=50 PZ=-4000 "));
    assert!(ask1(&mut dev, "OPT BDEL=2").starts_with("ERR VALUE BDEL"));
    for (line, want) in [
        (
            "G17 G02 X10 Z-5 R5 F100",
            "ERR GEOMETRY in G17 (XY): a lathe turns arcs and compensates in G18 (ZX)",
        ),
        ("G71 U1. R.5", "ERR VALUE G71 canned cycles not supported"),
        ("G90.2", "ERR VALUE G90.2 not supported"),
        ("G00 X1 Y2", "ERR VALUE Y a lathe has no Y axis: only Y0"),
        (
            "O1000 G00 X1",
            "ERR SYNTAX a program number stands alone at a line's start: O",
        ),
        (
            "o<sub> call",
            "ERR SYNTAX o-word subroutines, loops and conditions are expanded by the host",
        ),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=50 PZ=-4000 "));
}

#[test]
fn inch_programs_move_the_same_steps_as_their_millimetres() {
    let last =
        |dev: &mut Device, line: &str| ask(dev, std::format!("{line}\n").as_bytes()).pop().unwrap();
    let mut inch = Device::new();
    let mut mm = Device::new();
    // 1.25 in = 31.75 mm; 0.5 in/min = 12.7 mm/min; a G20 in a block reads
    // every word of it in inches, then stays.
    for (a, b) in [
        ("G00 X1.25 Z.1 G20", "G00 X31.75 Z2.54"),
        ("G01 Z-1.5 F.5", "G01 Z-38.1 F12.7"),
        ("G02 X1.75 Z-1.75 R.25", "G02 X44.45 Z-44.45 R6.35"),
        ("G91 X-.000001", "G91 X-0.0000254"),
        ("G21 G90 X20 Z0", "G90 X20 Z0"),
    ] {
        assert_eq!(last(&mut inch, a), last(&mut mm, b), "{a} / {b}");
    }
    assert_eq!(ask1(&mut inch, "POS"), ask1(&mut mm, "POS"));
    // Power-on and RESET are millimetres.
    last(&mut inch, "G20");
    ask1(&mut inch, "RESET");
    last(&mut inch, "G00 X10 Z0");
    assert!(ask1(&mut inch, "POS").starts_with("OK PX=1000 PZ=0 "));
    assert_eq!(
        last(&mut inch, "G20 X3937.008"),
        "ERR VALUE X beyond 99999.999999 mm"
    );
}

#[test]
fn a_fanuc_program_moves_as_its_iso_equivalent() {
    let run = |dev: &mut Device, program: &[&str]| {
        for line in program {
            let r = ask(dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        }
        (ask1(dev, "SYNC"), ask1(dev, "POS"), ask1(dev, "AUX"))
    };
    let mut fanuc = Device::new();
    assert_eq!(
        ask1(&mut fanuc, "OPT DIALECT=fanuc"),
        "OK BDEL=0 DIALECT=FANUC OPTSTOP=0"
    );
    // 180 m/min at Ø30: 1909.8593171 rpm (at Ø40, where it ends, 1432.3945); 0.2 mm/rev of it is
    // 381.9718634 mm/min. The spindle and coolant switch at rest, the
    // dwell waits at rest: the same runs in both.
    let a = run(
        &mut fanuc,
        &[
            "%",
            "O1000 (SHAFT)",
            "N10 G21 G18 G99",
            "N20 T0101",
            "N30 G50 S2500",
            "N40 G00 X30. Z2.",
            "N50 G96 S180 M03",
            "N60 M08",
            "N70 G01 Z-40. F.2",
            "N80 U2. W-1.",
            "N90 G04 P500",
            "N100 G00 X40. Z5.",
        ],
    );
    assert_eq!(
        a.2,
        "OK SPINDLE=CW S=1432.3945 SMODE=CSS LIMIT=2500.0000 COOLANT=FLOOD T=0101 SMAX=0.0000 SPINUP=0.000"
    );
    let mut iso = Device::new();
    let b = run(
        &mut iso,
        &[
            "G21 G18 G94 T1",
            "G00 X30. Z2.",
            "S1909.8593171 M03",
            "M08",
            "G01 Z-40. F381.9718634",
            "X32. Z-41.",
            "G4 P.5",
            "G00 X40. Z5.",
        ],
    );
    assert_eq!((&a.0, &a.1), (&b.0, &b.1));
    // The end of the program stops the spindle and the coolant.
    assert!(ask1(&mut fanuc, "N110 M05 M09 M30").starts_with("OK NX=0 NZ=0 "));
    assert_eq!(
        ask1(&mut fanuc, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=2500.0000 COOLANT=OFF T=0101 SMAX=0.0000 SPINUP=0.000"
    );
}

#[test]
fn spindle_speeds_that_cannot_be_had_are_refused_and_change_nothing() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    let before = state(&mut dev);
    for (line, want) in [
        (
            "G96 S180 M03",
            "ERR VALUE S G96 surface speed at X0 needs a spindle speed limit (G50 S or G96 D)",
        ),
        (
            "G99 G01 Z-1 F.1",
            "ERR VALUE F per revolution needs the spindle turning (M03/M04 and S)",
        ),
        (
            "G99 G01 Z-1 F0",
            "ERR VALUE F 0: a feed move needs a feed above 0",
        ),
        ("U1 X2", "ERR SYNTAX X and U in one block"),
        ("G01 X1 Y1 F1", "ERR VALUE Y a lathe has no Y axis: only Y0"),
        (
            "G91 X1",
            "ERR VALUE G91 belongs to the ISO dialect (OPT DIALECT=ISO)",
        ),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
        assert_eq!(state(&mut dev), before, "{line}");
    }
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=0.0000 COOLANT=OFF T=- SMAX=0.0000 SPINUP=0.000"
    );
    // S with M05: the feed per revolution still has no speed.
    ask1(&mut dev, "G99 S1000 M05");
    assert!(ask1(&mut dev, "G01 W-1. F.1").starts_with("ERR VALUE F per revolution"));
    ask1(&mut dev, "M04");
    let r = ask(&mut dev, b"G01 W-1. F.1\n");
    assert!(r[1].starts_with("OK NX=0 NZ=-100 "), "{r:?}");
}

#[test]
fn iso_modes_of_a_block_apply_to_its_own_words() {
    let mut dev = Device::new();
    // G8: X a radius from this block on, in its DATA line too.
    let r = ask(&mut dev, b"G8 G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    assert!(ask1(&mut dev, "CFG").contains(" DIAM=0 "));
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=2000 PZ=100 "));
    let r = ask(&mut dev, b"G7 X10\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    assert!(ask1(&mut dev, "POS").starts_with("OK PX=1000 PZ=100 "));
    // G90.1: I and K are the centre, both needed; G91.1 from the start.
    assert_eq!(
        ask1(&mut dev, "G90.1 G02 X10 Z-4 I5"),
        "ERR SYNTAX G90.1: an arc centre needs I and K"
    );
    let a = ask(&mut dev, b"G90.1 G02 X10 Z-4 I5 K-1.5 F100\n");
    let mut other = Device::new();
    ask(&mut other, b"G00 X10 Z1\n");
    let b = ask(&mut other, b"G02 X10 Z-4 I0 K-2.5 F100\n");
    assert_eq!(a, b);
}

#[test]
fn reset_stops_the_spindle_and_coolant_and_ctrl_x_forgets_them() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    ask(
        &mut dev,
        b"G00 X50 Z5\nG50 S2000\nG99 G96 S100 M04 M07 T0303 F.1\n",
    );
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=CCW S=636.6198 SMODE=CSS LIMIT=2000.0000 COOLANT=MIST T=0303 SMAX=0.0000 SPINUP=0.000"
    );
    ask1(&mut dev, "RESET");
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=2000.0000 COOLANT=OFF T=0303 SMAX=0.0000 SPINUP=0.000"
    );
    // The feed per revolution stays with its F, and needs the spindle.
    assert!(ask1(&mut dev, "G01 W-1.").starts_with("ERR VALUE F per revolution"));
    ask(&mut dev, b"\x18");
    assert_eq!(
        ask1(&mut dev, "AUX"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=0.0000 COOLANT=OFF T=- SMAX=0.0000 SPINUP=0.000"
    );
    assert_eq!(ask1(&mut dev, "OPT"), "OK BDEL=0 DIALECT=FANUC OPTSTOP=0");
}

#[test]
fn work_and_tool_offsets_move_the_machine_not_the_program() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    // X values are diameters (DIAM=1), held on the radius.
    assert_eq!(
        ask1(&mut dev, "TOOL N=1 X=2 Z=-3 WX=-0.02 WZ=0.01"),
        "OK N=1 X=2.0000 Z=-3.0000 WX=-0.0200 WZ=0.0100 R=- T=-"
    );
    assert_eq!(
        ask1(&mut dev, "WORK G=54 Z=-100"),
        "OK G=54 X=0.0000 Z=-100.0000"
    );
    let r = ask(&mut dev, b"G00 X20. Z5.\n");
    assert_eq!(r[0], "DATA G00 X20.0000 Z-95.0000");
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=2000 PZ=-9500 X=20.0000 Z=5.0000 MX=20.0000 MZ=-95.0000"
    );
    // T0101 moves nothing; the next move takes its offsets up.
    assert!(ask1(&mut dev, "T0101").starts_with("OK NX=0 NZ=0 "));
    let r = ask(&mut dev, b"G00 X20. Z5.\n");
    assert_eq!(r[0], "DATA G00 X21.9800 Z-97.9900");
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=2198 PZ=-9799 X=20.0000 Z=5.0000 MX=21.9800 MZ=-97.9900"
    );
    // G10 L2 sets G55; G10 L20 so that the tool stands at Z0 in G54.
    ask1(&mut dev, "G10 L2 P2 X0 Z-50.");
    assert_eq!(ask1(&mut dev, "WORK G=55"), "OK G=55 X=0.0000 Z=-50.0000");
    let r = ask(&mut dev, b"G55 G00 Z0\n");
    assert_eq!(r[0], "DATA G00 X21.9800 Z-52.9900");
    ask1(&mut dev, "G54 G10 L20 P1 Z0");
    assert_eq!(ask1(&mut dev, "WORK G=54"), "OK G=54 X=0.0000 Z=-50.0000");
    // An arc cannot take up an offset change; a line can.
    ask1(&mut dev, "T0100");
    assert_eq!(
        ask1(&mut dev, "G02 X24. Z-2. R2. F100"),
        "ERR GEOMETRY an arc cannot take up an offset change: move in a line first"
    );
    assert!(ask1(&mut dev, "T0133").starts_with("ERR VALUE T offset register beyond"));
    let bad = [
        ("G10 L2 P7 X0", "ERR VALUE P names G54 to G59: 1 to 6"),
        (
            "G10 L3 P1 X0",
            "ERR SYNTAX G10 needs L2 or L20 (a work offset)",
        ),
        ("G10 L2 P1 U1", "ERR SYNTAX G10 takes X and Z, not U and W"),
        ("L2", "ERR SYNTAX L only with G10"),
        ("TOOL N=33", "ERR VALUE N must be 1 to 32"),
        ("TOOL N=1 T=12", "ERR VALUE T must be 0 to 9"),
        ("WORK G=60", "ERR VALUE G must be 54 to 59"),
    ];
    let before = ask1(&mut dev, "POS");
    for (line, want) in bad {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert_eq!(ask1(&mut dev, "POS"), before);
}

/// The machine position of the last block's end, from its `DATA` line.
fn data_end(reply: &[String]) -> String {
    let data = reply.iter().find(|l| l.starts_with("DATA ")).cloned();
    data.unwrap_or_else(|| panic!("no DATA in {reply:?}"))
}

/// Safety: an axis a block does not name never moves, whatever changed
/// the offsets before it (a work system set or selected, G92 and its kin,
/// a tool's offset), in both dialects; a named axis takes the new offset up.
#[test]
fn an_axis_the_block_does_not_name_never_moves() {
    for dialect in ["ISO", "FANUC"] {
        let mut dev = Device::new();
        ask1(&mut dev, &std::format!("OPT DIALECT={dialect}"));
        ask1(&mut dev, "TOOL N=1 X=2 Z=-3");
        // X 10 on the diameter, Z −5; then G54 moves by X4 (diameter) Z−2.
        ask(&mut dev, b"G00 X10 Z-5\n");
        ask1(&mut dev, "G10 L2 P1 X4 Z-2");
        let r = ask(&mut dev, b"G00 Z-6\n");
        assert_eq!(data_end(&r), "DATA G00 X10.0000 Z-8.0000", "{dialect}");
        // Selected anew: G55 is zero.
        ask(&mut dev, b"G55\n");
        let r = ask(&mut dev, b"G00 Z-3\n");
        assert_eq!(data_end(&r), "DATA G00 X10.0000 Z-3.0000", "{dialect}");
        // Set so that the tool stands at X20: X stays, then moves when named.
        ask1(&mut dev, "G10 L20 P2 X20");
        let r = ask(&mut dev, b"G01 Z-4 F100\n");
        assert_eq!(data_end(&r), "DATA G01 X10.0000 Z-4.0000", "{dialect}");
        let r = ask(&mut dev, b"G01 X18\n");
        assert_eq!(data_end(&r), "DATA G01 X8.0000 Z-4.0000", "{dialect}");
        // A tool's offset: X stays on a Z move, is taken up by an X move.
        let tool = if dialect == "ISO" {
            "T1 M06 G43"
        } else {
            "T0101"
        };
        ask(&mut dev, std::format!("{tool}\n").as_bytes());
        let r = ask(&mut dev, b"G00 Z-1\n");
        assert_eq!(data_end(&r), "DATA G00 X8.0000 Z-4.0000", "{dialect}");
        let r = ask(&mut dev, b"G00 X18\n");
        assert_eq!(data_end(&r), "DATA G00 X10.0000 Z-4.0000", "{dialect}");
        // G92 (Fanuc G50): the point here named anew, nothing moves; then
        // an incremental move goes from where the tool is.
        let shift = if dialect == "ISO" {
            "G92 X0 Z0"
        } else {
            "G50 X0 Z0"
        };
        let r = ask(&mut dev, std::format!("{shift}\n").as_bytes());
        assert!(r[0].starts_with("OK NX=0 NZ=0 "), "{dialect}: {r:?}");
        let inc = if dialect == "ISO" {
            "G91 G01 Z-2"
        } else {
            "G01 W-2"
        };
        let r = ask(&mut dev, std::format!("{inc}\n").as_bytes());
        assert_eq!(data_end(&r), "DATA G01 X10.0000 Z-6.0000", "{dialect}");
    }
}

#[test]
fn iso_tools_change_with_m6_and_offset_with_g43() {
    let mut dev = Device::new();
    ask1(&mut dev, "TOOL N=2 X=1 Z=0.5");
    assert_eq!(ask1(&mut dev, "M6"), "ERR SYNTAX M06 needs the tool: T");
    ask1(&mut dev, "T2 M6");
    // Without G43 the tool's offsets are not in effect (LinuxCNC's way).
    let r = ask(&mut dev, b"G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    ask1(&mut dev, "G43");
    let r = ask(&mut dev, b"G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X11.0000 Z1.5000");
    ask1(&mut dev, "G49");
    let r = ask(&mut dev, b"G00 X10 Z1\n");
    assert_eq!(r[0], "DATA G00 X10.0000 Z1.0000");
    assert_eq!(ask1(&mut dev, "H2"), "ERR SYNTAX H only with G43");
    assert!(ask1(&mut dev, "G43 H40").starts_with("ERR VALUE H offset register beyond"));
}

#[test]
fn compensation_takes_the_nose_of_the_tool_in_effect() {
    let contour = [
        "G00 X20 Z5",
        "G42 G01 Z0 F100",
        "X28",
        "X48 Z-10",
        "Z-46",
        "G40 G00 X60",
    ];
    let data = |setup: &[&str], dialect: &str| {
        let mut dev = Device::new();
        ask1(&mut dev, &std::format!("OPT DIALECT={dialect}"));
        for l in setup {
            assert!(ask1(&mut dev, l).starts_with("OK"), "{l}");
        }
        let mut out = Vec::new();
        for l in contour {
            out.extend(ask(&mut dev, std::format!("{l}\n").as_bytes()));
        }
        out
    };
    let configured = data(&["CFG RN=0.8 TIP=2"], "ISO");
    let fanuc = data(&["TOOL N=5 R=0.8 T=2", "T0505"], "FANUC");
    let iso = data(&["TOOL N=5 R=0.8 T=2", "T5 M6"], "ISO");
    assert_eq!(fanuc, configured);
    assert_eq!(iso, configured);
    assert_ne!(data(&[], "ISO"), configured);
    // Offsets cannot change under compensation.
    let mut dev = Device::new();
    ask(&mut dev, b"G00 X20 Z5\nG42 G01 Z0 F100\n");
    assert_eq!(
        ask1(&mut dev, "G55 X28"),
        "ERR GEOMETRY a work or tool offset change not allowed while G41/G42 is on; cancel with G40 first"
    );
}

#[test]
fn what_a_board_keeps_in_flash_counts_its_changes() {
    let mut dev = Device::new();
    let g = |dev: &Device| dev.session().offsets_generation();
    let mut last = g(&dev);
    for (line, changes) in [
        ("TOOL N=3", false),
        ("TOOL N=3 X=1.5 R=0.4 T=2", true),
        ("TOOL N=3 X=1.5", false),
        ("WORK G=56 Z=-20", true),
        ("G10 L2 P2 X4", true),
        ("G55 G00 X10 Z2", false),
        ("G92 X0", false),
        ("G92.1", false),
        ("G28.1", true),
        ("G28.1", false),
        ("G00 X20", false),
        ("G30.1", true),
    ] {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        assert_eq!(g(&dev) != last, changes, "{line}");
        last = g(&dev);
    }
    // At power-on a board puts them back.
    let kept = *dev.session().offsets();
    let mut fresh = Device::new();
    let before = ask1(&mut fresh, "TOOL N=3");
    fresh.restore_offsets(kept);
    assert_ne!(ask1(&mut fresh, "TOOL N=3"), before);
    assert_eq!(ask1(&mut fresh, "TOOL N=3"), ask1(&mut dev, "TOOL N=3"));
    assert_eq!(ask1(&mut fresh, "WORK G=55"), ask1(&mut dev, "WORK G=55"));
}

#[test]
fn surface_speed_is_taken_at_the_programmed_diameter_whatever_the_offsets() {
    let speed = |setup: &[&str]| {
        let mut dev = Device::new();
        ask1(&mut dev, "OPT DIALECT=FANUC");
        for line in setup {
            assert!(ask1(&mut dev, line).starts_with("OK"), "{line}");
        }
        for line in [
            "G50 S3000",
            "G96 S180 M03 G99",
            "G00 X30. Z2.",
            "G01 Z-10. F.2",
        ] {
            let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        }
        ask1(&mut dev, "AUX")
    };
    let plain = speed(&[]);
    // 180 m/min at Ø30: 1909.8593 rpm, at any tool or work offset.
    assert!(plain.contains(" S=1909.8593 "), "{plain:?}");
    let offset = speed(&["TOOL N=1 X=-20 Z=5", "WORK G=54 X=40", "T0101"]);
    let s = |aux: &str| {
        aux.split(' ')
            .find(|w| w.starts_with("S="))
            .unwrap()
            .to_string()
    };
    assert_eq!(s(&offset), s(&plain));
}

/// A board's view of the device: its replies, what it drives, its waits.
#[derive(Default)]
struct Panel {
    lines: Lines,
    outputs: Vec<crate::outputs::Outputs>,
    dwells: Vec<u64>,
}

impl Io for Panel {
    fn send(&mut self, line: &[u8]) {
        self.lines.send(line);
    }
    fn outputs(&mut self, outputs: &crate::outputs::Outputs) {
        self.outputs.push(*outputs);
    }
    fn dwell(&mut self, us: u64) {
        self.dwells.push(us);
    }
}

#[test]
fn the_spindle_and_coolant_outputs_follow_the_program_and_status_reports_them() {
    use crate::gcode::{Coolant, Spindle};
    use crate::outputs::Outputs;
    let mut dev = Device::new();
    let mut panel = Panel::default();
    let tell = |dev: &mut Device, panel: &mut Panel, line: &str| -> String {
        dev.receive_bytes(std::format!("{line}\n").as_bytes(), panel);
        panel.lines.out.pop().unwrap()
    };
    let out = |spindle, rpm, coolant| Outputs {
        spindle,
        rpm,
        top: 3_000_000,
        coolant,
    };
    assert_eq!(
        tell(&mut dev, &mut panel, "AUX SMAX=3000 SPINUP=1.5"),
        "OK SPINDLE=OFF S=0.0000 SMODE=RPM LIMIT=0.0000 COOLANT=OFF T=- SMAX=3000.0000 SPINUP=1.500"
    );
    assert_eq!(panel.outputs, [out(Spindle::Off, 0, Coolant::Off)]);
    for (bad, why) in [
        (
            "AUX SMAX=100000",
            "ERR VALUE SMAX must be 0 to 99999.999 rpm",
        ),
        ("AUX SMAX=-1", "ERR VALUE SMAX must be 0 to 99999.999 rpm"),
        ("AUX SPINUP=61", "ERR VALUE SPINUP must be 0 to 60 s"),
        ("AUX SPINUP=x", "ERR VALUE SPINUP must be 0 to 60 s"),
        ("AUX SMAX=1e3", "ERR VALUE SMAX must be 0 to 99999.999 rpm"),
    ] {
        assert!(tell(&mut dev, &mut panel, bad).starts_with(why), "{bad}");
    }
    tell(&mut dev, &mut panel, "OPT DIALECT=FANUC");
    tell(&mut dev, &mut panel, "G50 S2500");
    tell(&mut dev, &mut panel, "G00 X30. Z2.");
    panel.outputs.clear();
    // 180 m/min at Ø30: 1909.859 rpm; the spindle gets up to speed first.
    tell(&mut dev, &mut panel, "G96 S180 M03");
    assert_eq!(panel.outputs, [out(Spindle::Cw, 1_909_859, Coolant::Off)]);
    assert_eq!(panel.dwells, [1_500_000]);
    let status = tell(&mut dev, &mut panel, "STATUS");
    assert!(
        status.ends_with(" SPINDLE=CW S=1909.859 COOLANT=OFF"),
        "{status}"
    );
    // The coolant switches alone: no spin-up wait.
    tell(&mut dev, &mut panel, "M08");
    assert_eq!(
        panel.outputs[1],
        out(Spindle::Cw, 1_909_859, Coolant::Flood)
    );
    assert_eq!(panel.dwells.len(), 1);
    // Under G96 the speed follows X block by block, with no stop: each
    // block carries the speed where it starts (Ø30, then Ø40: 1432.394).
    tell(&mut dev, &mut panel, "G99 G01 X40. F.2");
    tell(&mut dev, &mut panel, "X60. W-10.");
    tell(&mut dev, &mut panel, "SYNC");
    assert_eq!(panel.outputs.len(), 2);
    let status = tell(&mut dev, &mut panel, "STATUS");
    assert!(
        status.ends_with(" SPINDLE=CW S=1432.394 COOLANT=FLOOD"),
        "{status}"
    );
    // The top speed limits what is commanded, feed per revolution
    // included: 5000 rpm asked, 3000 turned.
    tell(&mut dev, &mut panel, "G50 S9000");
    tell(&mut dev, &mut panel, "G97 S5000 M04");
    assert_eq!(
        panel.outputs[2],
        out(Spindle::Ccw, 3_000_000, Coolant::Flood)
    );
    assert_eq!(panel.dwells, [1_500_000, 1_500_000]);
    assert!(tell(&mut dev, &mut panel, "AUX").starts_with("OK SPINDLE=CCW S=3000.0000 "));
    // A reset drops the outputs at once and forgets the G50 limit; the
    // top speed stays, and is a limit at X0 under G96.
    dev.receive_bytes(b"\x18", &mut panel);
    assert_eq!(panel.outputs[3], out(Spindle::Off, 0, Coolant::Off));
    tell(&mut dev, &mut panel, "G00 X0");
    tell(&mut dev, &mut panel, "G96 S100 M03");
    assert_eq!(panel.outputs[4], out(Spindle::Cw, 3_000_000, Coolant::Off));
    // Taking the top speed away would leave it without one: refused, and
    // nothing changes.
    assert_eq!(
        tell(&mut dev, &mut panel, "AUX SMAX=0"),
        "ERR VALUE SMAX G96 surface speed at X0 needs a spindle speed limit (G50 S or G96 D)"
    );
    assert_eq!(panel.outputs.len(), 5);
    assert!(tell(&mut dev, &mut panel, "STATUS").ends_with(" SPINDLE=CW S=3000.000 COOLANT=OFF"));
    // The end of the program switches everything off.
    tell(&mut dev, &mut panel, "M30");
    assert_eq!(panel.outputs[5], out(Spindle::Off, 0, Coolant::Off));
    assert!(tell(&mut dev, &mut panel, "STATUS").ends_with(" SPINDLE=OFF S=0.000 COOLANT=OFF"));
}

#[test]
fn g45_to_g48_lengthen_and_shorten_the_move_by_an_offset_register() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=FANUC");
    // X on the diameter: 1 mm is 0.5 on the radius.
    ask1(&mut dev, "TOOL N=5 X=1 Z=0.15 WZ=0.05");
    let last =
        |dev: &mut Device, line: &str| ask(dev, std::format!("{line}\n").as_bytes()).pop().unwrap();
    assert!(last(&mut dev, "G01 F100 W0").starts_with("OK"));
    let nz = |dev: &mut Device, line: &str| -> String {
        let r = ask(dev, std::format!("{line}\n").as_bytes());
        let last = r.last().unwrap().clone();
        last.split(' ').take(3).collect::<Vec<_>>().join(" ")
    };
    // Z's offset is geometry plus wear: 0.2 mm, 20 impulses of 0.01.
    for (line, want) in [
        ("G45 W-10. D5", "OK NX=0 NZ=-1020"),
        ("G46 W-10. D5", "OK NX=0 NZ=-980"),
        ("G47 W-10. D5", "OK NX=0 NZ=-1040"),
        ("G48 W-10. D5", "OK NX=0 NZ=-960"),
        // A move of zero goes the offset's way.
        ("G45 W0 D5", "OK NX=0 NZ=20"),
        ("G46 W0 D5", "OK NX=0 NZ=-20"),
        // U10 is 5 on the radius, with 0.5: 5.5, 1100 impulses of 0.005.
        ("G45 U10. D5", "OK NX=1100 NZ=0"),
        // Absolute words: the move from where the tool is.
        ("G46 X0 D5", "OK NX=-1000 NZ=0"),
        // One block only: the next move is as written.
        ("W-1.", "OK NX=0 NZ=-100"),
    ] {
        assert_eq!(nz(&mut dev, line), want, "{line}");
    }
    let before = state(&mut dev);
    for (line, why) in [
        (
            "G45 W-1.",
            "ERR SYNTAX G45 to G48 need D: the offset register",
        ),
        (
            "G45 W1. D33",
            "ERR SYNTAX D (the offset register) must be 1 to 32",
        ),
        (
            "G45 W1. D1.5",
            "ERR SYNTAX D (the offset register) must be 1 to 32",
        ),
        (
            "G45 D5",
            "ERR SYNTAX G45 to G48 need X or Z (U or W): the move",
        ),
        (
            "G45 W1. K1. D5",
            "ERR SYNTAX G45 to G48 move in a line: X and Z (U and W)",
        ),
        (
            "G45 G02 W1. D5",
            "ERR SYNTAX G45 to G48 move in a line: G00 or G01",
        ),
        ("G45 G28 W1. D5", "ERR SYNTAX address given twice: G"),
        ("G01 W1. D5", "ERR SYNTAX unknown address D"),
        ("G45 G41 W1. D5", "ERR"),
    ] {
        let got = last(&mut dev, line);
        assert!(got.starts_with(why), "{line}: {got}");
    }
    assert_eq!(state(&mut dev), before);
    // ISO: D is also G96's limit; with G45 it names the register.
    let mut iso = Device::new();
    ask1(&mut iso, "TOOL N=2 Z=-0.3");
    assert!(last(&mut iso, "G91 G00 Z0").starts_with("OK"));
    assert_eq!(nz(&mut iso, "G45 Z-5 D2"), "OK NX=0 NZ=-470");
    assert!(last(&mut iso, "G01 Z1 D2").starts_with(
        "ERR SYNTAX D only with G96 (the spindle speed limit) or G45 to G48 (the offset register)"
    ));
}

/// What a machine's M code and a program stop did, besides the replies.
#[derive(Default)]
struct MPanel {
    lines: Lines,
    outputs: Vec<(u8, bool)>,
    waits: Vec<(u8, bool)>,
    stops: Vec<u16>,
}

impl Io for MPanel {
    fn send(&mut self, line: &[u8]) {
        self.lines.send(line);
    }
    fn user_output(&mut self, n: u8, on: bool) {
        self.outputs.push((n, on));
    }
    fn wait_input(&mut self, n: u8, level: bool) {
        self.waits.push((n, level));
    }
    fn program_stop(&mut self, code: u16) {
        self.stops.push(code);
    }
}

fn panel(dev: &mut Device, line: &str) -> MPanel {
    let mut p = MPanel::default();
    dev.receive_bytes(std::format!("{line}\n").as_bytes(), &mut p);
    p
}

/// The run time `SYNC` reports of `lines`.
fn run_ticks(lines: &[&str]) -> u64 {
    let mut dev = Device::new();
    for l in lines {
        let r = ask(&mut dev, std::format!("{l}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{l}: {r:?}");
    }
    let sync = ask1(&mut dev, "SYNC");
    sync.split(" T=")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

/// Header words of posts for mills and lathes alike: G17 as the plane
/// until G18, path control, G80, F0 before G95; each bad form refused by
/// name, nothing changed.
#[test]
fn header_words_real_programs_hold() {
    let mut dev = Device::new();
    for line in ["G17 G90 G21", "G80 G40 G64 P0.01", "G61.1", "G64", "F0"] {
        assert!(ask1(&mut dev, line).starts_with("OK"), "{line}");
    }
    assert!(ask(&mut dev, b"G00 X20 Z2\n")[1].starts_with("OK NX=2000 "));
    let before = state(&mut dev);
    for (line, want) in [
        (
            "G02 X24 Z0 R2 F100",
            "ERR GEOMETRY in G17 (XY): a lathe turns arcs and compensates in G18 (ZX)",
        ),
        (
            "G19 G42 G01 X24 F100",
            "ERR GEOMETRY in G19 (YZ): a lathe turns arcs and compensates in G18 (ZX)",
        ),
        (
            "G01 X24 Z0",
            "ERR VALUE F 0: a feed move needs a feed above 0",
        ),
        ("G64 P11", "ERR VALUE P a G64 tolerance of 0 to 10 mm"),
        ("G64 P-1", "ERR VALUE P a tolerance is 0 or more"),
        ("G61 G64", "ERR SYNTAX address given twice: G"),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
        assert_eq!(state(&mut dev), before, "{line}");
    }
    // In G18 the arc runs.
    let r = ask(&mut dev, b"G18 G02 X24 Z0 R2 F100\n");
    assert!(r.last().unwrap().starts_with("OK NX="), "{r:?}");
}

/// G61 joins blocks at rest; G64 P at the speed its tolerance allows (a
/// larger one, faster); G64 alone at the limits' JD.
#[test]
fn path_control_decides_how_blocks_join() {
    let corners = |mode: &str| {
        run_ticks(&[
            "G00 X0 Z0",
            mode,
            "G01 X10 Z-10 F2000",
            "X10 Z-20",
            "X20 Z-30",
            "X20 Z-40",
        ])
    };
    let exact = corners("G61");
    let blend = corners("G64");
    let loose = corners("G64 P1");
    let tight = corners("G64 P0.0001");
    assert!(
        exact > tight && tight > blend && blend > loose,
        "{exact} {tight} {blend} {loose}"
    );
    // Collinear blocks: exact stop brakes between them, blending does not.
    let straight = |mode: &str| run_ticks(&[mode, "G01 Z-10 F2000", "Z-20", "Z-30"]);
    assert!(straight("G61") > straight("G64"));
    assert_eq!(straight("G64"), straight("G61.1"));
}

/// M41–M44: a stop that names the range (the gearbox shifted by hand), the
/// range's top speed limiting the spindle.
#[test]
fn a_gear_range_stops_to_be_shifted_and_limits_the_speed() {
    let mut dev = Device::new();
    assert_eq!(
        ask1(&mut dev, "GEAR N=1 TOP=500"),
        "OK RANGE=- G1=500.0000 G2=0.0000 G3=0.0000 G4=0.0000"
    );
    let p = panel(&mut dev, "M41 S1000 M03");
    assert_eq!(p.stops, [41]);
    assert_eq!(
        p.lines.out[0],
        "DATA MSG M41: shift the gearbox to range 1 (up to 500.0000 rpm), then cycle start"
    );
    assert!(
        ask1(&mut dev, "AUX").contains(" S=500.0000 "),
        "{}",
        ask1(&mut dev, "AUX")
    );
    let p = panel(&mut dev, "M42");
    assert_eq!(p.stops, [42]);
    assert!(ask1(&mut dev, "AUX").contains(" S=1000.0000 "));
    assert!(ask1(&mut dev, "GEAR").starts_with("OK RANGE=2 "));
    for (line, want) in [
        (
            "GEAR N=5 TOP=100",
            "ERR VALUE N must be 1 to 4 (M41 to M44)",
        ),
        (
            "GEAR N=1",
            "ERR SYNTAX GEAR sets a range with N and TOP together",
        ),
        ("M41 M42", "ERR SYNTAX address given twice: M"),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
}

/// The machine's own M codes: one not in the table stops with a message
/// naming it, as M00; the table sets it to do nothing, switch a user output
/// or wait for a user input; bad forms refused, the table unchanged.
#[test]
fn machine_m_codes_do_what_the_table_says() {
    let mut dev = Device::new();
    let p = panel(&mut dev, "G00 X10 M16");
    assert_eq!(p.stops, [16]);
    assert_eq!(
        p.lines.out[0],
        "DATA MSG M16: the machine's own M code; do it by hand, then cycle start"
    );
    assert!(p.lines.out.last().unwrap().starts_with("OK NX="));
    assert_eq!(ask1(&mut dev, "MCODE M=16 DO=NONE"), "OK CODES=1");
    assert_eq!(ask1(&mut dev, "MCODE M=31 DO=ON N=2"), "OK CODES=2");
    assert_eq!(ask1(&mut dev, "MCODE M=33 DO=HIGH N=4"), "OK CODES=3");
    let list = ask(&mut dev, b"MCODE\n");
    assert_eq!(
        list,
        [
            "DATA M16 DO=NONE",
            "DATA M31 DO=ON N=2",
            "DATA M33 DO=HIGH N=4",
            "OK CODES=3"
        ]
    );
    let p = panel(&mut dev, "M16");
    assert!(p.stops.is_empty() && p.outputs.is_empty());
    let p = panel(&mut dev, "M31");
    assert_eq!(p.outputs, [(2, true)]);
    let p = panel(&mut dev, "M33");
    assert_eq!(p.waits, [(4, true)]);
    // Back to the default: a stop.
    assert_eq!(ask1(&mut dev, "MCODE M=16 DO=STOP"), "OK CODES=2");
    assert_eq!(panel(&mut dev, "M16").stops, [16]);
    let before = ask(&mut dev, b"MCODE\n");
    for (line, want) in [
        (
            "MCODE M=3 DO=NONE",
            "ERR VALUE M is one the device runs itself (M00-M09, M30, M41-M44, M98, M99)",
        ),
        (
            "MCODE M=16 DO=BLINK",
            "ERR VALUE DO must be STOP, NONE, ON, OFF, HIGH or LOW",
        ),
        (
            "MCODE M=16 DO=ON",
            "ERR SYNTAX ON, OFF, HIGH and LOW need N: 1 to 4",
        ),
        (
            "MCODE M=16 DO=ON N=5",
            "ERR VALUE N must be 1 to 4 (a user output or input)",
        ),
        (
            "MCODE M=16 DO=NONE N=1",
            "ERR SYNTAX N only with ON, OFF, HIGH or LOW",
        ),
        ("MCODE DO=NONE", "ERR SYNTAX DO and N need M: the code"),
        (
            "MCODE M=1000",
            "ERR VALUE M must be a whole M code 0 to 999",
        ),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert_eq!(ask(&mut dev, b"MCODE\n"), before);
    // The table holds 16.
    for m in 100..114 {
        assert!(ask1(&mut dev, &std::format!("MCODE M={m} DO=NONE")).starts_with("OK"));
    }
    assert_eq!(
        ask1(&mut dev, "MCODE M=200 DO=NONE"),
        "ERR RANGE the table holds 16 M codes"
    );
}

/// LinuxCNC's G41.1/G42.1: the nose in the block, its orientation mirrored
/// into the device's tip code; the same path as the table's nose.
#[test]
fn dynamic_compensation_takes_the_nose_from_the_block() {
    let contour = |setup: &str, on: &str| {
        let mut dev = Device::new();
        assert!(ask1(&mut dev, setup).starts_with("OK"));
        let mut out = Vec::new();
        for l in [
            "G00 X20 Z5",
            on,
            "X28",
            "X48 Z-10",
            "Z-30",
            "G40 G00 X60 Z5",
        ] {
            let r = ask(&mut dev, std::format!("{l}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{l}: {r:?}");
            out.extend(r);
        }
        out
    };
    let table = contour("CFG RN=0.4 TIP=3", "G42 G01 Z0 F100");
    let dynamic = contour("CFG RN=0 TIP=0", "G42.1 D0.8 L2 G01 Z0 F100");
    assert_eq!(table, dynamic);
    let mut dev = Device::new();
    assert!(ask1(&mut dev, "G42.1 L2 G01 Z0 F100")
        .starts_with("ERR SYNTAX G41.1 and G42.1 need D: the nose diameter"));
}

/// `G90` and `G94` of G-code system A (Fanuc dialect) move as the blocks
/// a programmer writes for them by hand: in at the rapid rate (to the
/// taper's start, X + 2R on the diameter), the cut, out at the feed, back
/// to the start at the rapid rate; X, Z and R modal, the cycle repeated by
/// an axis word alone until a motion code ends it.
#[test]
fn single_cycles_move_as_their_blocks_written_out() {
    let run = |program: &[&str]| {
        let mut dev = Device::new();
        assert_eq!(
            ask1(&mut dev, "OPT DIALECT=fanuc"),
            "OK BDEL=0 DIALECT=FANUC OPTSTOP=0"
        );
        let mut trace = Vec::new();
        for line in program {
            let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
            trace.push(r.last().unwrap().clone());
        }
        (ask1(&mut dev, "SYNC"), ask1(&mut dev, "POS"), trace)
    };
    let (sync, pos, trace) = run(&[
        "G21 G18 G98 G90",
        "G00 X50. Z5.",
        "G90 X40. W-25. F200.",
        "X35.",
        "Z-30. R-1.",
        "G94 X20. Z0 F100.",
        "Z-1.",
        "G00 X60.",
        "X70. Z10.",
        // G80 ends a cycle as a motion code does.
        "G90 X40. Z-5. F200.",
        "G80",
        "X50.",
    ]);
    let (sync_by_hand, pos_by_hand, _) = run(&[
        "G21 G18 G98",
        "G00 X50. Z5.",
        "G00 X40.",
        "G01 Z-20. F200.",
        "X50.",
        "G00 Z5.",
        "X35.",
        "G01 Z-20.",
        "X50.",
        "G00 Z5.",
        "X33.",
        "G01 X35. Z-30.",
        "X50.",
        "G00 Z5.",
        "Z0",
        "G01 X20. F100.",
        "Z5.",
        "G00 X50.",
        "Z-1.",
        "G01 X20.",
        "Z5.",
        "G00 X50.",
        "X60.",
        "X70. Z10.",
        "X40.",
        "G01 Z-5. F200.",
        "X70.",
        "G00 Z10.",
        "G80",
        "G00 X50.",
    ]);
    assert_eq!(pos, pos_by_hand);
    assert_eq!(sync, sync_by_hand);
    // A header's G90 selects the cycle without moving; the cycle blocks
    // move and come back to where they started.
    assert!(trace[0].starts_with("OK NX=0 NZ=0"), "{}", trace[0]);
    assert!(trace[2].starts_with("OK NX=0 NZ=0"), "{}", trace[2]);
}

/// What a single cycle cannot take is refused before anything moves.
#[test]
fn single_cycle_refusals_change_nothing() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    for line in ["G21 G18 G98", "G00 X50. Z5."] {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{r:?}");
    }
    ask1(&mut dev, "SYNC");
    let before = ask1(&mut dev, "POS");
    for (line, want) in [
        (
            "G90 G01 X40. Z-20. F100.",
            "ERR SYNTAX G90/G94 and a motion code in one block: one of them",
        ),
        (
            "G90 X40. Z-20. F100. M08",
            "ERR SYNTAX a G90/G94 block takes X (U), Z (W), R and F: put other words on their own line",
        ),
        ("G90 X40. Z-20.", "ERR VALUE F not programmed: a feed move needs F (mm/min)"),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
        // No event since: the SYNC since the last one is empty.
        assert!(ask1(&mut dev, "SYNC").starts_with("OK EV=0 "), "{line}");
        assert_eq!(ask1(&mut dev, "POS"), before, "{line}");
    }
}

/// Fanuc's two-block `G71` roughs a stepped shaft as the manual draws it:
/// passes U deep (on the radius) from the start point, each cut to the
/// profile moved out by the allowances (U on the diameter, W along Z),
/// pulled off at 45° by R, back to the start's Z at the rapid rate; then
/// one pass along the moved profile and back to the start point. `G70`
/// then runs the profile's own blocks and returns, X first.
#[test]
fn g71_roughs_in_passes_and_g70_finishes_on_the_profile() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    let r = run_program(
        &mut dev,
        &[
            "G21 G18 G98",
            "G00 X40. Z2.",
            "G71 U2. R.5",
            "G71 P10 Q30 U.4 W.2 F300.",
            "N10 G00 X20.",
            "N20 G01 Z-30. F100.",
            "N30 X40.",
            "G70 P10 Q30",
        ],
    );
    for reply in &r {
        assert!(reply.last().unwrap().starts_with("OK"), "{reply:?}");
    }
    // The profile's blocks are held, not run, until Q.
    assert!(r[4].last().unwrap().ends_with("HELD=1"), "{:?}", r[4]);
    assert!(r[5].last().unwrap().ends_with("HELD=2"), "{:?}", r[5]);
    let mut want = std::vec!["G00 X40.0000 Z2.0000".to_string()];
    // Radii 18, 16, 14, 12: each to the shoulder at Z-30 + W.
    for x in [36, 32, 28, 24] {
        want.push(std::format!("G00 X{x}.0000 Z2.0000"));
        want.push(std::format!("G01 X{x}.0000 Z-29.8000"));
        want.push(std::format!("G01 X{}.0000 Z-29.3000", x + 1));
        want.push(std::format!("G00 X{}.0000 Z2.0000", x + 1));
    }
    // Along the profile moved by the allowances (X20 + U, Z + W), then
    // back to the start point.
    for m in [
        "G00 X20.4000 Z2.0000",
        "G00 X20.4000 Z2.2000",
        "G01 X20.4000 Z-29.8000",
        "G01 X40.4000 Z-29.8000",
        "G00 X40.0000 Z-29.8000",
        "G00 X40.0000 Z2.0000",
        // G70: the profile as written, then back.
        "G00 X20.0000 Z2.0000",
        "G01 X20.0000 Z-30.0000",
        "G01 X40.0000 Z-30.0000",
        "G00 X40.0000 Z2.0000",
    ] {
        want.push(m.to_string());
    }
    assert_eq!(data(&r), want);
    assert_eq!(
        ask1(&mut dev, "POS"),
        "OK PX=4000 PZ=200 X=40.0000 Z=2.0000"
    );
}

/// A profile block the device refuses refuses the cycle: the blocks up to
/// Q are refused with it, nothing moves, and the program goes on after Q.
#[test]
fn a_refused_profile_refuses_its_cycle_and_nothing_moves() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    let r = run_program(
        &mut dev,
        &[
            "G21 G18 G98",
            "G00 X40. Z2.",
            "G71 U2. R.5",
            "G71 P10 Q30 U.4 W.2 F300.",
            "N10 G00 X20.",
            "N20 G01 Z-30. Q7",
            "N30 X40.",
            "G01 X42. F100.",
        ],
    );
    let last = |i: usize| r[i].last().unwrap().clone();
    assert!(last(5).starts_with("ERR"), "{:?}", r[5]);
    assert!(last(6).starts_with("ERR"), "{:?}", r[6]);
    assert!(last(7).starts_with("OK NX=200 NZ=0"), "{:?}", r[7]);
    assert_eq!(data(&r[2..7]), Vec::<String>::new());
}

/// G70 knows before its first move that the profile's feed moves have no
/// feed; a first block's words that belong to the other cycle are refused;
/// RESET drops a profile being read.
#[test]
fn cycle_refusals_come_before_motion() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    let r = run_program(
        &mut dev,
        &[
            "G21 G18 G98",
            "G00 X40. Z2.",
            "G71 P10 Q30 D2. F300.",
            "N10 G00 X20.",
            "N20 G01 Z-30.",
            "N30 X40.",
        ],
    );
    for reply in &r {
        assert!(reply.last().unwrap().starts_with("OK"), "{reply:?}");
    }
    ask1(&mut dev, "SYNC");
    assert_eq!(
        ask1(&mut dev, "G70 P10 Q30"),
        "ERR VALUE F not programmed: the profile's feed moves need G70 F or a feed in force"
    );
    assert!(ask1(&mut dev, "SYNC").starts_with("OK EV=0 "));
    assert!(ask(&mut dev, b"G70 P10 Q30 F100.\n")
        .last()
        .unwrap()
        .starts_with("OK"));
    assert_eq!(
        ask1(&mut dev, "G71 U1. R.5 W1."),
        "ERR SYNTAX the first of the two blocks takes the depth (G71 U, G72 W) and the retract R"
    );
    assert_eq!(
        ask1(&mut dev, "G72 W0 R.5"),
        "ERR VALUE W the depth of cut must be above 0"
    );
    for line in [
        "G71 U1. R.5 M08",
        "G71 P1 Q2 D1. F.2 G99",
        "G70 P10 Q30 S500",
    ] {
        let want = if line.contains('S') {
            "ERR SYNTAX a cycle block takes P Q U W D R F (G71/G72) or P Q F U W (G70): S and T on their own line"
        } else {
            "ERR SYNTAX a cycle block takes its own words and F only: put M, S and other G codes on their own line"
        };
        assert_eq!(ask1(&mut dev, line), want, "{line}");
    }
    assert!(ask1(&mut dev, "AUX").contains("COOLANT=OFF"));
    // A profile being read, dropped by RESET: the next line runs.
    assert!(ask1(&mut dev, "G71 P1 Q2 D1. F100.").starts_with("OK"));
    assert!(ask1(&mut dev, "N1 G00 X20.").ends_with("HELD=1"));
    assert_eq!(ask1(&mut dev, "RESET"), "OK");
    let r = ask(&mut dev, b"G00 X42.\n");
    assert!(r.last().unwrap().starts_with("OK NX=200"), "{r:?}");
}

/// `G75` grooves and `G74` pecks as the blocks written out by hand: each
/// peck in at the feed, back by the return at the rapid rate, out of the
/// groove at the rapid rate, over by the step to the next groove, back to
/// the start point at the end. Fanuc's `P`/`Q` in the least increment,
/// Haas' `I`/`K` in millimetres, move alike.
#[test]
fn g74_and_g75_peck_as_their_blocks_written_out() {
    let run = |program: &[&str]| {
        let mut dev = Device::new();
        ask1(&mut dev, "OPT DIALECT=fanuc");
        for line in program {
            let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
            assert!(r.last().unwrap().starts_with("OK"), "{line}: {r:?}");
        }
        (ask1(&mut dev, "SYNC"), ask1(&mut dev, "POS"))
    };
    let fanuc = run(&[
        "G21 G18 G98",
        "G00 X42. Z-10.",
        "G75 R.5",
        "G75 X30. Z-14. P2500 Q2000 F50.",
        "G00 X0 Z2.",
        "G74 R1.",
        "G74 Z-12. Q5000 F80.",
    ]);
    let haas = run(&[
        "G21 G18 G98",
        "G00 X42. Z-10.",
        "G75 R.5",
        "G75 X30. Z-14. I2.5 K2. F50.",
        "G00 X0 Z2.",
        "G74 R1.",
        "G74 W-14. K5. F80.",
    ]);
    let mut by_hand = vec![
        "G21 G18 G98",
        "G00 X42. Z-10.",
        "G01 X37. F50.",
        "G00 X38.",
        "G01 X32.",
        "G00 X33.",
        "G01 X30.",
        "G00 X42.",
    ];
    for z in ["Z-12.", "Z-14."] {
        by_hand.extend([
            z, "G01 X37.", "G00 X38.", "G01 X32.", "G00 X33.", "G01 X30.", "G00 X42.",
        ]);
    }
    by_hand.extend([
        "Z-10.",
        "X0 Z2.",
        "G01 Z-3. F80.",
        "G00 Z-2.",
        "G01 Z-8.",
        "G00 Z-7.",
        "G01 Z-12.",
        "G00 Z2.",
    ]);
    let by_hand = run(&by_hand);
    assert_eq!(fanuc, by_hand);
    assert_eq!(haas, by_hand);
}

/// What a grooving cycle cannot take is refused before anything moves.
#[test]
fn g74_and_g75_refusals_change_nothing() {
    let mut dev = Device::new();
    ask1(&mut dev, "OPT DIALECT=fanuc");
    for line in ["G21 G18 G98", "G00 X42. Z-10."] {
        let r = ask(&mut dev, std::format!("{line}\n").as_bytes());
        assert!(r.last().unwrap().starts_with("OK"), "{r:?}");
    }
    ask1(&mut dev, "SYNC");
    let before = ask1(&mut dev, "POS");
    for (line, want) in [
        ("G75 Z-14. Q2000 F50.", "ERR SYNTAX G75 needs a depth: its X (U) away from the start point"),
        ("G75 X30. Z-14. P2500 F50.", "ERR SYNTAX G75 to another Z needs the step between grooves: Q (K)"),
        ("G75 X30. P2500 R.2 F50.", "ERR VALUE R a relief at the bottom is not supported: R0 (D0) or none"),
        ("G75 X30. P2500 F50. M08", "ERR SYNTAX a cycle block takes its own words and F only: put M, S and other G codes on their own line"),
        ("G75 X10. P1 F50.", "ERR RANGE a grooving cycle of more than 20000 moves"),
        ("G75 X30. P2500", "ERR VALUE F not programmed: a feed move needs F (mm/min)"),
        ("G75 X30. P2.5 F50.", "ERR VALUE P a step in the least increment, without a point (P2500: 2.5 mm)"),
    ] {
        assert_eq!(ask1(&mut dev, line), want, "{line}");
        assert!(ask1(&mut dev, "SYNC").starts_with("OK EV=0 "), "{line}");
        assert_eq!(ask1(&mut dev, "POS"), before, "{line}");
    }
}

#[test]
fn refusals_map_to_grbl_codes_by_what_they_are() {
    struct Out(Vec<u8>);
    impl Io for Out {
        fn send(&mut self, line: &[u8]) {
            self.0.extend_from_slice(line);
        }
    }
    let error = |line: &str| {
        let mut dev = Device::new();
        let mut out = Out(Vec::new());
        dev.set_grbl(true, &mut out);
        out.0.clear();
        dev.receive_bytes(line.as_bytes(), &mut out);
        let text = String::from_utf8(out.0).expect("text");
        text.lines()
            .find_map(|l| l.strip_prefix("error:"))
            .and_then(|n| n.parse::<u8>().ok())
    };
    // Undefined feed rate: a feed move under F0.
    assert_eq!(error("G01 X1 F0\n"), Some(22));
    // Invalid target: an arc whose radius cannot reach its end.
    assert_eq!(error("G02 X10 Z-10 R1\n"), Some(33));
    // Expected command letter: an address this control does not know.
    assert_eq!(error("G01 X1 Q3 F100\n"), Some(1));
    // Unsupported command: a G code it does not run, a word of the
    // other dialect (whose text names FANUC: not a feed's refusal).
    assert_eq!(error("G12 X1\n"), Some(20));
    assert_eq!(error("G01 U1 F100\n"), Some(20));
    assert_eq!(
        super::grbl::error_number(super::Refused {
            code: ErrorCode::Value,
            about: None
        }),
        20
    );
    assert_eq!(
        super::grbl::error_number(super::Refused {
            code: ErrorCode::Value,
            about: Some(b'F')
        }),
        22
    );
}

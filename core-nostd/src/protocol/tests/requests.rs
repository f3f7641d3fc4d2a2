//! Requests through the byte interface: every error code, state unchanged
//! after every error, replies, integrity words, retries, framing, real-time
//! bytes.

use super::*;

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

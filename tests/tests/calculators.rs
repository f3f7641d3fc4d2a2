//! The calculators' command-line front (`host_sim::calculators`): their
//! answers, their refusals, and the deflection-compensated pass as a
//! program the device runs from start to end.

use host_sim::calculators::{self, DeflectionJob, WearJob};
use host_sim::table::{Cell, Format};

fn value(r: &host_sim::table::Report, key: &str) -> Cell {
    r.values
        .iter()
        .find(|(f, _)| f.key == key)
        .map(|(_, c)| c.clone())
        .unwrap_or_else(|| panic!("no {key}"))
}

#[test]
fn thread_speed_answers_the_em907_rule_and_this_controllers_limit() {
    let r = calculators::thread_speed(1.5, None, false, 3000.0).unwrap();
    assert_eq!(value(&r, "em907_mode"), Cell::Text("G08".into()));
    // min(960, 1200/1.5) = 800 rpm; 3000 mm/min / 1.5 mm = 2000 rpm.
    assert_eq!(value(&r, "em907_n_max_rpm"), Cell::Num(800.0, 1));
    assert_eq!(value(&r, "n_max_rpm"), Cell::Num(2000.0, 1));
    let across = calculators::thread_speed(2.0, Some("G07"), true, 1500.0).unwrap();
    assert_eq!(value(&across, "em907_n_max_rpm"), Cell::Num(300.0, 1));
    assert!(across.render(Format::Json).contains("\"n_max_rpm\":750.0"));
    for (pitch, mode) in [
        (0.0, None),
        (-1.0, None),
        (1.0, Some("G05")),
        (1.0, Some("x")),
    ] {
        assert!(calculators::thread_speed(pitch, mode, false, 3000.0).is_err());
    }
}

#[test]
fn trihedral_prints_the_set_up_and_refuses_what_is_no_corner() {
    let angles = calculators::Angles {
        plane: [Some(90.0), Some(90.0), Some(90.0)],
        linear: [None; 3],
    };
    let job = calculators::TrihedralJob {
        step_mm: 0.5,
        rows: 4,
        lengths_mm: [10.0, 10.0, 12.0],
        fillet_mm: 0.0,
        table: [0.0, 0.0],
        e_deg: 0.0,
        quadrant: 1,
        vertex: [0.0; 3],
        proportional: false,
    };
    let (r, program) = calculators::trihedral(angles, &job).unwrap();
    // arctan(1/√2), the cube's.
    match value(&r, "phi_deg") {
        Cell::Num(phi, 5) => assert!((phi - 0.5f64.sqrt().atan().to_degrees()).abs() < 1e-12),
        other => panic!("{other:?}"),
    }
    assert_eq!(r.rows.len(), 4);
    assert!(program.contains("M98 P1001") && program.contains("M99"));
    let text = r.render(Format::Text);
    assert!(text.contains("cutter angle φ          35.26439°"), "{text}");
    let flat = calculators::Angles {
        plane: [Some(100.0), Some(20.0), Some(30.0)],
        ..angles
    };
    let e = calculators::trihedral(flat, &job).unwrap_err();
    assert!(e.contains("AOB"), "{e}");
    let e = calculators::trihedral(angles, &calculators::TrihedralJob { quadrant: 5, ..job })
        .unwrap_err();
    assert!(e.contains("quadrant"), "{e}");
}

/// The stepped shaft of the deflection examples: Ø29.8 × 100 and
/// Ø21.8 × 150 mm, 0.5 mm deep at 0.2 mm/rev into HB 220.
fn stepped_shaft() -> DeflectionJob {
    DeflectionJob {
        sections: vec![(29.8, 100.0), (21.8, 150.0)],
        equal_volume: false,
        modulus: 21_000.0,
        stiffness: [4000.0, 3000.0, 10_000.0],
        depth_mm: 0.5,
        feed_mm_rev: 0.2,
        hardness_hb: 220.0,
        approach_deg: 90.0,
        nose_mm: 1.0,
        force: None,
        step_mm: 10.0,
        rpm: 400.0,
    }
}

#[test]
fn the_deflection_compensated_pass_runs_on_the_device() {
    let job = stepped_shaft();
    let (r, program) = calculators::deflection(&job).unwrap();
    // Eq. 30: (29.8·100 + 21.8·150)/250 = 25 mm.
    assert_eq!(value(&r, "reduced_diameter_mm"), Cell::Num(25.0, 3));
    // Every 10 mm and both sides of the shoulder: 27 rows.
    assert_eq!(r.rows.len(), 27);
    let options = host_sim::program::Options {
        dialect: core_nostd::gcode::Dialect::Iso,
        radius: false,
        optional_stop: false,
    };
    let report = host_sim::program::run(&program, options);
    assert!(report.refused.is_empty(), "{:?}\n{program}", report.refused);
    assert!(report.feed_mm > 250.0, "{}", report.feed_mm);
    for bad in [
        DeflectionJob {
            depth_mm: 0.0,
            ..job.clone()
        },
        DeflectionJob {
            stiffness: [-1.0, 3000.0, 10_000.0],
            ..job.clone()
        },
        DeflectionJob {
            sections: vec![],
            ..job.clone()
        },
    ] {
        assert!(calculators::deflection(&bad).is_err());
    }
}

/// Fifty parts with a Ø40 × 120 mm surface at 0.2 mm/rev, 5 µm initial
/// and 8 µm/km relative wear.
fn batch_of_fifty() -> WearJob {
    WearJob {
        sections: vec![(40.0, 120.0)],
        feed_mm_rev: 0.2,
        initial_um: 5.0,
        rate_um_per_km: 8.0,
        parts: 50,
        resetting: Some((20.0, 50.0)),
        full_um: Some(300.0),
        flank: Some((0.8, 8.0)),
    }
}

#[test]
fn wear_counts_parts_and_refuses_an_allowance_beyond_half_the_tolerance() {
    let job = batch_of_fifty();
    let r = calculators::wear(&job).unwrap();
    // L = π·40·120/(10⁶·0.2) = 0.0753982 km per part; 50 parts: 5 + 8·L·50.
    let l = std::f64::consts::PI * 40.0 * 120.0 / 0.2e6;
    assert_eq!(value(&r, "path_km"), Cell::Num(l, 5));
    assert_eq!(value(&r, "wear_um"), Cell::Num(5.0 + 8.0 * l * 50.0, 2));
    // (20 − 5)/(8·L) = 24.87: 24 parts.
    assert_eq!(value(&r, "parts_between_resettings"), Cell::Int(24));
    let bad = WearJob {
        resetting: Some((30.0, 50.0)),
        ..job
    };
    assert!(calculators::wear(&bad).is_err());
}

#[test]
fn the_seeds_bck5_tape_fails_exactly_where_it_was_misprinted() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/kosenko-table21.bck5"
    ))
    .unwrap();
    let (r, findings) = calculators::tape_verify(&text);
    let found: Vec<String> = r
        .rows
        .iter()
        .map(|row| match &row[1] {
            Cell::Text(t) => t.clone(),
            other => panic!("{other:?}"),
        })
        .collect();
    // Check digits of K000, K004, K007; the closure of the tools whose
    // frames K011 (C01, both axes) and K021 (C02) break.
    assert_eq!(findings, 6, "{found:#?}");
    for (i, frame) in ["K000", "K004", "K007"].into_iter().enumerate() {
        assert!(
            found[i].starts_with(frame) && found[i].contains("check digit"),
            "{found:#?}"
        );
    }
    assert!(found[3].starts_with("tool C01 (K001-K011): E does not close"));
    assert!(found[4].starts_with("tool C01 (K001-K011): D does not close"));
    assert!(found[5].starts_with("tool C02 (K020-K024): E does not close"));
    // The same tape with those slips mended passes.
    let mended = text
        .replace("0\tK000", "7\tK000")
        .replace("D514800", "D504800")
        .replace("8\tK007", "7\tK007");
    let (_, left) = calculators::tape_verify(&mended);
    assert!(left < findings, "{left}");
    // A letter the code does not have is named with its column.
    let (r, n) = calculators::tape_verify("5K001E000000D000000P00W00C01Q00H\n");
    assert_eq!(n, 1);
    assert!(
        matches!(&r.rows[0][1], Cell::Text(t) if t.contains("column")),
        "{:?}",
        r.rows
    );
}

/// The reply lines of `requests` on the in-process device.
fn device_replies(requests: &str) -> Vec<String> {
    let bytes: Vec<u8> = requests
        .lines()
        .flat_map(|l| format!("{l}\r\n").into_bytes())
        .collect();
    let out = host_sim::device::LocalDevice::new().feed(&bytes);
    String::from_utf8(out)
        .unwrap()
        .lines()
        .map(|l| l.rsplit_once('*').map_or(l, |(body, _)| body).to_string())
        .collect()
}

/// The value of `key` in a reply line.
fn word<'a>(line: &'a str, key: &str) -> &'a str {
    line.split(' ')
        .find_map(|w| w.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key} in {line}"))
}

#[test]
fn the_pendant_answers_each_calculator_with_the_command_lines_figures() {
    let r = device_replies(
        "THREAD P=1.5\nLIMITS VZ=1200\nTHREAD P=1.5\nTHREAD P=2 MODE=G07 CROSS=1\n\
         WEAR D=40 L=120 S=0.2 U0=5 UR=8 Q=50 ALLOW=20 TOL=50 FULL=300 H=0.8 ALPHA=8\n\
         DEFLECT D=29.8,21.8 L=100,150 T=0.5 HB=220 J=4000,3000,10000 DX=10\n\
         TRI AOB=90 BOC=90 COA=90 ROWS=4 LEN=10,10,12",
    );
    // ЭМ-907: min(960, 1200/1.5) = 800 rpm; this controller: VZ/t.
    assert_eq!(
        r[0],
        "OK MODE=G08 WORD=600 CAP=960 NEM=800.0 V=3000.0 NMAX=2000.0"
    );
    assert_eq!(word(&r[2], "NMAX"), "800.0", "{}", r[2]);
    // Across: min(480, 600/2) = 300 rpm; VX 1500 / 2 = 750.
    assert_eq!(word(&r[3], "NEM"), "300.0");
    assert_eq!(word(&r[3], "NMAX"), "750.0");

    let l = std::f64::consts::PI * 40.0 * 120.0 / 0.2e6;
    assert_eq!(word(&r[4], "KM"), format!("{l:.5}"));
    assert_eq!(word(&r[4], "U"), format!("{:.2}", 5.0 + 8.0 * l * 50.0));
    assert_eq!(word(&r[4], "QR"), "24");
    // u = h·tan α.
    assert_eq!(
        word(&r[4], "HR"),
        format!("{:.4}", 0.8 * 8f64.to_radians().tan())
    );
    let cli = calculators::wear(&batch_of_fifty()).unwrap();
    assert_eq!(
        value(&cli, "parts_until_tool_change"),
        Cell::Int(word(&r[4], "QT").parse().unwrap())
    );

    // 27 stations, then the reduced diameter of eq. 30: 25 mm.
    let rows: Vec<&String> = r[5..]
        .iter()
        .take_while(|l| l.starts_with("DATA"))
        .collect();
    assert_eq!(rows.len(), 27);
    let ok = &r[5 + 27];
    assert_eq!(word(ok, "DRED"), "25.0000");
    assert_eq!(word(ok, "N"), "27");
    let (table, _) = calculators::deflection(&stepped_shaft()).unwrap();
    for (line, row) in rows.iter().zip(&table.rows) {
        let num = |c: &Cell| match c {
            Cell::Num(v, _) => *v,
            other => panic!("{other:?}"),
        };
        let device: f64 = word(line, "DS").parse().unwrap();
        assert!((device - num(&row[6])).abs() <= 0.5e-4, "{line} {row:?}");
        let error: f64 = word(line, "ERR").parse().unwrap();
        assert!((error - num(&row[3])).abs() <= 0.5e-4, "{line} {row:?}");
    }

    // The cube's corner: φ = arctan(1/√2), tilt −(90° − φ).
    let tri = &r[5 + 28..];
    let phi = 0.5f64.sqrt().atan().to_degrees();
    assert_eq!(word(&tri[0], "PHI"), format!("{phi:.5}"));
    assert_eq!(word(&tri[1], "TILT"), format!("{:.5}", phi - 90.0));
    assert_eq!(tri.iter().filter(|l| l.starts_with("DATA ROW=")).count(), 4);
    assert!(tri.last().unwrap().starts_with("OK AOB=90.00000"));
}

#[test]
fn the_pendant_refuses_what_no_calculator_takes_and_keeps_its_tape() {
    let r = device_replies(
        "THREAD P=0\nWEAR D=40 L=120 S=0.2 UR=8 ALLOW=30 TOL=50\n\
         DEFLECT D=29.8 L=100 T=0.5 J=-1,3000,10000\nTRI AOB=100 BOC=20 COA=30\n\
         TRI AOB=90 BOC=90\nTAPE FRAME=2K002E212400D630000P75W26H\n\
         TAPE FRAME=5K001E000000D000000P00W00C01Q00H\nTAPE FRAME=2K002E212400D630000P75W26H\n\
         DEFLECT D=29.8 L=100 T=0.5 J=4000,3000,10000 DX=0.05\nTRI AOB=90 BOC=90 COA=90 ROWS=1001",
    );
    assert!(r[0].starts_with("ERR VALUE THREAD pitch"), "{}", r[0]);
    assert!(r[1].starts_with("ERR VALUE WEAR allowed wear"), "{}", r[1]);
    assert!(
        r[2].starts_with("ERR VALUE DEFLECT headstock stiffness"),
        "{}",
        r[2]
    );
    // Three plane angles that make no corner: impossible geometry.
    assert!(r[3].starts_with("ERR GEOMETRY plane angle AOB"), "{}", r[3]);
    assert!(r[4].starts_with("ERR VALUE TRI corner angles"), "{}", r[4]);
    assert_eq!(r[5], "OK LINES=1 FRAMES=1 FINDINGS=0");
    // A letter BCK-5 does not have (Q), named with its column, not counted.
    assert_eq!(
        r[6],
        "ERR VALUE FRAME column 29: a character the code does not have"
    );
    // The second good frame repeats K002: the numbering finding, line 2.
    assert_eq!(r[7], "DATA K002 (line 2): out of sequence, K003 expected");
    assert_eq!(r[8], "OK LINES=2 FRAMES=2 FINDINGS=1");
    // A reply of more than a thousand lines is not made.
    assert_eq!(
        r[9],
        "ERR RANGE DEFLECT: more than 1000 stations, give a larger DX"
    );
    assert_eq!(r[10], "ERR VALUE ROWS must be 1 to 1000");
}

#[test]
fn the_seeds_bck5_tape_fails_on_the_pendant_exactly_where_it_was_misprinted() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/kosenko-table21.bck5"
    ))
    .unwrap();
    let requests = host_sim::scenario::tape_requests(&text).join("\n");
    let r = device_replies(&requests);
    let findings: Vec<&String> = r.iter().filter(|l| l.starts_with("DATA")).collect();
    assert_eq!(findings.len(), 6, "{findings:#?}");
    for (line, frame) in findings.iter().zip(["K000", "K004", "K007"]) {
        assert!(line.starts_with(&format!("DATA {frame} (")) && line.contains("check digit"));
    }
    assert!(findings[3].starts_with("DATA tool C01 (K001-K011): E does not close"));
    assert!(findings[4].starts_with("DATA tool C01 (K001-K011): D does not close"));
    assert!(findings[5].starts_with("DATA tool C02 (K020-K024): E does not close"));
    assert!(
        r.last().unwrap().ends_with("FINDINGS=6 END=1"),
        "{:?}",
        r.last()
    );
}

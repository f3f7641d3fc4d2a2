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

#[test]
fn the_deflection_compensated_pass_runs_on_the_device() {
    let job = DeflectionJob {
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
    };
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

#[test]
fn wear_counts_parts_and_refuses_an_allowance_beyond_half_the_tolerance() {
    let job = WearJob {
        sections: vec![(40.0, 120.0)],
        feed_mm_rev: 0.2,
        initial_um: 5.0,
        rate_um_per_km: 8.0,
        parts: 50,
        resetting: Some((20.0, 50.0)),
        full_um: Some(300.0),
        flank: Some((0.8, 8.0)),
    };
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

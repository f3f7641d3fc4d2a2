//! Nose radius compensation across the crates: Krylenko's Fig. 12, 17 and 22
//! from plain G41/G42 contours, the device against the f64 reference on
//! random contours and on concave arcs barely larger than the nose, and the
//! geometry of the nose itself: it touches every programmed element and never
//! enters the part.

use core_nostd::arc::ArcDir;
use core_nostd::comp::{MoveKind, Origin};
use host_sim::compensate::{compensate, Settings};
use host_sim::contour::{compare_contour, random_contours, ContourCase, ContourTally};
use host_sim::device::LocalDevice;
use host_sim::link::Transport;
use proptest::prelude::*;
use reference::comp::{CompSettings, RefContour};

/// The compensated blocks of a program through the device, as printed.
fn device_blocks(program: &str, rn: &str, tip: u8) -> Vec<String> {
    let mut dev = LocalDevice::new();
    for setting in [format!("CFG RN={rn} TIP={tip}"), "OPT DIALECT=FANUC".into()] {
        assert!(Transport::request(&mut dev, &setting).unwrap().is_ok());
    }
    let mut out = Vec::new();
    // Every line runs: the programs are Fanuc's, from `%` to `%`.
    for line in program.lines() {
        let r = Transport::request(&mut dev, line).unwrap();
        assert!(r.is_ok(), "{line}: {}", r.last);
        out.extend(
            r.data
                .iter()
                .map(|d| d.trim_start_matches("DATA ").to_string()),
        );
    }
    out
}

/// X and Z of a printed block (X as printed).
fn xz(block: &str) -> (f64, f64) {
    let word = |l: char| {
        block
            .split(' ')
            .find_map(|w| w.strip_prefix(l))
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap()
    };
    (word('X'), word('Z'))
}

/// Finds `expected` (X, Z as the seed prints them, diameters) as
/// consecutive blocks of `blocks`, each within 0.001 mm of the seed and
/// equal to `exact` (the construction) to the printed 0.0001 mm.
fn assert_seed(blocks: &[String], expected: &[(f64, f64)], exact: &[(f64, f64)]) {
    let found = (0..blocks.len()).find(|&s| {
        expected.iter().enumerate().all(|(i, e)| {
            blocks.get(s + i).is_some_and(|b| {
                let (x, z) = xz(b);
                (x - e.0).abs() <= 0.001 + 1e-9 && (z - e.1).abs() <= 0.001 + 1e-9
            })
        })
    });
    let s = found.unwrap_or_else(|| panic!("{expected:?} not in {blocks:#?}"));
    for (i, e) in exact.iter().enumerate() {
        let (x, z) = xz(&blocks[s + i]);
        assert!(
            (x - e.0).abs() < 0.00005 + 1e-9 && (z - e.1).abs() < 0.00005 + 1e-9,
            "{} is not the construction {e:?}",
            blocks[s + i]
        );
    }
}

fn example(name: &str) -> String {
    let path = format!("{}/../examples/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Krylenko's corrections for r = 0.4 and a 45° taper, from his formulas.
fn xc_zc() -> (f64, f64) {
    let r = 0.4;
    let t = (22.5f64).to_radians().tan();
    (r * (1.0 - t), r * (1.0 - t))
}

#[test]
fn fig_12_external_tapers_from_a_g42_contour() {
    let blocks = device_blocks(&example("krylenko-fig12.nc"), "0.4", 3);
    let (xc, zc) = xc_zc();
    assert_seed(
        &blocks,
        &[
            (27.532, 0.0),
            (48.0, -10.234),
            (48.0, -46.234),
            (67.532, -56.0),
            (93.532, -56.0),
            (114.0, -66.234),
        ],
        &[
            (28.0 - 2.0 * xc, 0.0),
            (48.0, -10.0 - zc),
            (48.0, -46.0 - zc),
            (68.0 - 2.0 * xc, -56.0),
            (94.0 - 2.0 * xc, -56.0),
            (114.0, -66.0 - zc),
        ],
    );
}

#[test]
fn fig_17_internal_tapers_from_a_g41_contour() {
    let blocks = device_blocks(&example("krylenko-fig17.nc"), "0.4", 2);
    let (xc, zc) = xc_zc();
    assert_seed(
        &blocks,
        &[
            (78.468, 0.0),
            (50.0, -14.234),
            (50.0, -34.234),
            (28.468, -45.0),
            (12.0, -45.0),
        ],
        &[
            (78.0 + 2.0 * xc, 0.0),
            (50.0, -14.0 - zc),
            (50.0, -34.0 - zc),
            (28.0 + 2.0 * xc, -45.0),
            (12.0, -45.0),
        ],
    );
}

#[test]
fn fig_22_arcs_from_a_g42_contour() {
    let blocks = device_blocks(&example("krylenko-fig22.nc"), "0.4", 3);
    // docs/errata.md §1.1: line 12 of the figure says Z-14, its own comment −14.4.
    let seed = [
        (7.2, 0.0),
        (12.0, -2.4),
        (12.0, -14.4),
        (17.2, -17.0),
        (29.2, -17.0),
        (38.0, -21.4),
    ];
    assert_seed(&blocks, &seed, &seed);
    let arcs: Vec<&String> = blocks
        .iter()
        .filter(|b| b.starts_with("G0") && !b.starts_with("G00") && !b.starts_with("G01"))
        .collect();
    assert_eq!(
        arcs,
        [
            "G03 X12.0000 Z-2.4000 I0.0000 K-2.4000",
            "G02 X17.2000 Z-17.0000 I2.6000 K0.0000",
            "G03 X38.0000 Z-21.4000 I0.0000 K-4.4000"
        ]
    );
    // `host-sim compensate` prints the same program with R words, the
    // corrected radii R2.4, R2.6 and R4.4 of the seed.
    let fanuc = Settings {
        dialect: core_nostd::gcode::Dialect::Fanuc,
        ..Settings::default()
    };
    let out = compensate(&example("krylenko-fig22.nc"), &fanuc).unwrap();
    for r in ["R2.4000", "R2.6000", "R4.4000"] {
        assert!(out.text.contains(r), "{r} in {}", out.text);
    }
    assert!(out.warnings.is_empty());
    assert!(
        out.text.contains("N20 G01 X7.2000 Z0.0000 ; point 2"),
        "{}",
        out.text
    );
    assert!(
        out.text.contains("T0101\nG50 S2500\nG96 S120 M03\n"),
        "{}",
        out.text
    );
    assert!(!out.text.contains("G42") && !out.text.contains("G40"));
}

#[test]
fn compensate_refuses_bad_programs_naming_the_line() {
    let program = "G00 X20 Z2\nN10 G42 G01 Z0\nN20 X40\nN30 G02 X41 Z-0.5 R0.36\nN40 Z-10\n";
    let e = compensate(program, &Settings::default()).unwrap_err();
    assert_eq!(e.line, 4);
    assert!(
        e.reason.starts_with("ERR GEOMETRY N30: concave arc radius"),
        "{e}"
    );
    let e = compensate("G01 X1..2\n", &Settings::default()).unwrap_err();
    assert_eq!(e.line, 1);
    assert!(e.reason.starts_with("ERR VALUE X"), "{e}");
    let bad_tool = Settings {
        rn: "-1".into(),
        ..Settings::default()
    };
    assert!(compensate("G01 X1\n", &bad_tool)
        .unwrap_err()
        .reason
        .starts_with("ERR VALUE RN"));
    // A program that ends with compensation on is finished, with a warning.
    let out = compensate("G00 X20 Z2\nG42 G01 Z0\nX40\nZ-10\n", &Settings::default()).unwrap();
    assert_eq!(out.warnings.len(), 1);
    assert!(
        out.text.trim_end().ends_with("G01 X40.0000 Z-10.4000"),
        "{}",
        out.text
    );
}

/// The device and the f64 reference print the same compensated blocks.
#[test]
fn device_matches_the_reference_on_random_contours() {
    let mut tally = ContourTally::default();
    for case in random_contours(1977, 2000) {
        let mut dev = LocalDevice::new();
        compare_contour(&mut dev, &case, &mut tally).unwrap();
    }
    assert!(
        tally.mismatches.is_empty(),
        "{:#?}",
        &tally.mismatches[..tally.mismatches.len().min(10)]
    );
    assert!(tally.compared > 20_000, "{tally:?}");
    // Refusals are rare with these contours, and both sides agree on them.
    assert!(tally.refused_alike < tally.programs / 10, "{tally:?}");
    println!(
        "{} programs, {} blocks, {} compensated blocks equal, {} refused alike, {} near ties, closest tie {:.3e} mm",
        tally.programs, tally.blocks, tally.compared, tally.refused_alike, tally.near_ties, tally.closest_tie_mm
    );
}

/// A programmed element or a nose-centre path piece, in mm (X radius, Z).
#[derive(Clone, Copy, Debug)]
enum Piece {
    Line([f64; 2], [f64; 2]),
    /// From, to, centre, counter-clockwise.
    Arc([f64; 2], [f64; 2], [f64; 2], bool),
}

fn angle(p: [f64; 2], c: [f64; 2]) -> f64 {
    (p[0] - c[0]).atan2(p[1] - c[1])
}

fn sweep(p: Piece) -> f64 {
    match p {
        Piece::Line(..) => 0.0,
        Piece::Arc(a, b, c, ccw) => {
            let s = angle(b, c) - angle(a, c);
            let s = if ccw { s } else { -s };
            let s = s.rem_euclid(std::f64::consts::TAU);
            if a == b {
                std::f64::consts::TAU
            } else {
                s
            }
        }
    }
}

/// The unit direction of travel at the start or the end of a piece,
/// `[X, Z]`.
fn tangent(p: Piece, at_end: bool) -> [f64; 2] {
    let v = match p {
        Piece::Line(a, b) => [b[0] - a[0], b[1] - a[1]],
        Piece::Arc(a, b, c, ccw) => {
            let q = if at_end { b } else { a };
            let r = [q[0] - c[0], q[1] - c[1]];
            // Counter-clockwise in the (Z right, X up) plane.
            if ccw {
                [r[1], -r[0]]
            } else {
                [-r[1], r[0]]
            }
        }
    };
    let l = v[0].hypot(v[1]);
    [v[0] / l, v[1] / l]
}

/// The length of a piece, mm.
fn length(p: Piece) -> f64 {
    match p {
        Piece::Line(a, b) => (b[0] - a[0]).hypot(b[1] - a[1]),
        Piece::Arc(a, _, c, _) => (a[0] - c[0]).hypot(a[1] - c[1]) * sweep(p),
    }
}

/// Points along a piece.
fn samples(p: Piece, n: usize) -> Vec<[f64; 2]> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            match p {
                Piece::Line(a, b) => [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])],
                Piece::Arc(a, _, c, ccw) => {
                    let r = ((a[0] - c[0]).powi(2) + (a[1] - c[1]).powi(2)).sqrt();
                    let s = sweep(p) * t * if ccw { 1.0 } else { -1.0 };
                    let phi = angle(a, c) + s;
                    [c[0] + r * phi.sin(), c[1] + r * phi.cos()]
                }
            }
        })
        .collect()
}

/// Distance from `q` to a finite element, and whether the nearest point is
/// inside the element (not one of its ends).
fn distance(q: [f64; 2], p: Piece) -> (f64, bool) {
    match p {
        Piece::Line(a, b) => {
            let (dx, dz) = (b[0] - a[0], b[1] - a[1]);
            let l2 = dx * dx + dz * dz;
            let t = (((q[0] - a[0]) * dx + (q[1] - a[1]) * dz) / l2).clamp(0.0, 1.0);
            let (px, pz) = (a[0] + t * dx, a[1] + t * dz);
            (
                ((q[0] - px).powi(2) + (q[1] - pz).powi(2)).sqrt(),
                t > 1e-9 && t < 1.0 - 1e-9,
            )
        }
        Piece::Arc(a, b, c, ccw) => {
            let r = ((a[0] - c[0]).powi(2) + (a[1] - c[1]).powi(2)).sqrt();
            let s = sweep(p);
            let off = angle(q, c) - angle(a, c);
            let off = if ccw { off } else { -off };
            let off = off.rem_euclid(std::f64::consts::TAU);
            if off <= s {
                let d = ((q[0] - c[0]).powi(2) + (q[1] - c[1]).powi(2)).sqrt();
                ((d - r).abs(), off > 1e-9 && off < s - 1e-9)
            } else {
                let da = ((q[0] - a[0]).powi(2) + (q[1] - a[1]).powi(2)).sqrt();
                let db = ((q[0] - b[0]).powi(2) + (q[1] - b[1]).powi(2)).sqrt();
                (da.min(db), false)
            }
        }
    }
}

/// The nose on random contours: the nose-centre path never comes nearer
/// than `r − 1 µm` to the programmed contour (the nose never enters the
/// part), and touches every programmed element at `r ± 1 µm` inside it.
#[test]
fn the_nose_touches_every_element_and_never_enters_the_part() {
    let mut checked = (0usize, 0usize, 0usize, 0usize);
    for case in random_contours(2026, 1000) {
        let r = case.rn_mm();
        let tip = match case.tip {
            1 => [r, r],
            2 => [r, -r],
            3 => [-r, -r],
            4 => [-r, r],
            5 => [0.0, r],
            6 => [r, 0.0],
            7 => [0.0, -r],
            8 => [-r, 0.0],
            _ => [0.0, 0.0],
        };
        let mut dev = LocalDevice::new();
        let cfg =
            Transport::request(&mut dev, &format!("CFG RN={} TIP={}", case.rn, case.tip)).unwrap();
        assert!(cfg.is_ok());
        let mm = |p: [i64; 2]| [p[0] as f64 * 1e-7, p[1] as f64 * 1e-7];
        let mut contour: Vec<Piece> = Vec::new();
        let mut path: Vec<Piece> = Vec::new();
        let mut at = [0.0, 0.0];
        let mut nose_at = [0.0, 0.0];
        let mut refused = false;
        for (i, line) in case.lines.iter().enumerate() {
            let before = dev.device().session().commanded();
            let prog_before = at;
            let r = Transport::request(&mut dev, line).unwrap();
            if !r.is_ok() {
                refused = true;
                break;
            }
            let _ = before;
            // The programmed element of this block (the test re-reads the
            // program: lines from the contour's first point to the G40).
            if let Some(piece) = programmed_piece(line, prog_before) {
                let end = match piece {
                    Piece::Line(_, b) | Piece::Arc(_, b, _, _) => b,
                };
                // Blocks 0 and 1 (approach and start-up) and the G40 retract
                // are not part of the contour.
                if i >= 2 && !line.contains("G40") {
                    contour.push(piece);
                }
                at = end;
            }
            for m in dev.device().session().last_moves() {
                let to = mm(m.to);
                let nose_to = [to[0] - tip[0], to[1] - tip[1]];
                // Compensated blocks: the element after the start-up, its
                // corners, up to the element before the G40 move.
                let compensated = i >= 2 && !(line.contains("G40") && m.origin == Origin::Current);
                let startup = i == 2 && m.origin == Origin::Previous;
                if compensated && !startup {
                    path.push(match m.kind {
                        MoveKind::Line { .. } => Piece::Line(nose_at, nose_to),
                        MoveKind::Arc { centre, dir } => {
                            let c = mm(centre);
                            Piece::Arc(
                                nose_at,
                                nose_to,
                                [c[0] - tip[0], c[1] - tip[1]],
                                dir == ArcDir::Ccw,
                            )
                        }
                    });
                }
                nose_at = nose_to;
            }
        }
        if refused {
            checked.2 += 1;
            continue;
        }
        // Never inside the part.
        for p in &path {
            for q in samples(*p, 64) {
                for e in &contour {
                    let (d, _) = distance(q, *e);
                    assert!(
                        d > r - 1e-3,
                        "nose centre {q:?} on {p:?} is {d} from {e:?} (r {r}) in {:#?}",
                        case.lines
                    );
                }
            }
        }
        // Touches every element the nose can reach, inside it: an inside
        // corner of turn θ keeps the nose r·tan(θ/2) away from the corner
        // along each element, so an element shorter than what its corners
        // take (with a margin for arcs) can only be touched at its extension.
        for (i, e) in contour.iter().enumerate() {
            let eaten = |a: Option<&Piece>, b: Option<&Piece>| match (a, b) {
                (Some(a), Some(b)) => {
                    let (t1, t2) = (tangent(*a, true), tangent(*b, false));
                    let cross = t1[1] * t2[0] - t1[0] * t2[1];
                    let dot = t1[0] * t2[0] + t1[1] * t2[1];
                    let theta = cross.atan2(dot);
                    // G42: a right turn (negative) is an inside corner.
                    if theta < 0.0 {
                        r * (-theta / 2.0).tan()
                    } else {
                        0.0
                    }
                }
                _ => 0.0,
            };
            let taken = eaten(i.checked_sub(1).and_then(|j| contour.get(j)), Some(e))
                + eaten(Some(e), contour.get(i + 1));
            if length(*e) < 1.5 * taken + 0.01 {
                checked.3 += 1;
                continue;
            }
            let touched = path.iter().any(|p| {
                samples(*p, 64).into_iter().any(|q| {
                    let (d, inside) = distance(q, *e);
                    inside && (d - r).abs() < 1e-3
                })
            });
            assert!(touched, "{e:?} not touched in {:#?}", case.lines);
            checked.1 += 1;
        }
        checked.0 += 1;
    }
    assert!(checked.0 > 900, "{checked:?}");
    assert!(checked.3 * 20 < checked.1, "{checked:?}");
    println!(
        "{} contours, {} elements touched, {} too short for their inside corners, {} programs refused",
        checked.0, checked.1, checked.3, checked.2
    );
}

/// The programmed element of a generated block from `from` (mm, radius):
/// the generator writes absolute X (diameter) and Z, and `R` or `I`/`K`.
fn programmed_piece(line: &str, from: [f64; 2]) -> Option<Piece> {
    let b = core_nostd::gcode::parse_block(line).ok()?;
    let mm = |l: core_nostd::length::Length| l.as_angstrom() as f64 * 1e-7;
    let to = [
        b.x.map_or(from[0], |x| mm(x) / 2.0),
        b.z.map_or(from[1], mm),
    ];
    if b.x.is_none() && b.z.is_none() {
        return None;
    }
    let arc = line.contains("G02") || line.contains("G03");
    if !arc {
        return Some(Piece::Line(from, to));
    }
    let ccw = line.contains("G03");
    let centre = if let Some(r) = b.r {
        // The short arc: centre left of the chord for G03.
        let r = mm(r);
        let (dx, dz) = (to[0] - from[0], to[1] - from[1]);
        let d = (dx * dx + dz * dz).sqrt();
        let h = (r * r - d * d / 4.0).max(0.0).sqrt();
        let s = if ccw { 1.0 } else { -1.0 };
        [
            (from[0] + to[0]) / 2.0 + s * dz / d * h,
            (from[1] + to[1]) / 2.0 - s * dx / d * h,
        ]
    } else {
        [from[0] + b.i.map_or(0.0, mm), from[1] + b.k.map_or(0.0, mm)]
    };
    Some(Piece::Arc(from, to, centre, ccw))
}

/// A millimetre value with four decimals, as the compensated blocks print it.
fn mm4(v: f64) -> String {
    let s = format!("{v:.4}");
    if s == "-0.0000" {
        "0.0000".into()
    } else {
        s
    }
}

/// Issue 15: an R0.255 groove bored with a 0.2 mm nose (offset radius
/// 0.055 mm) was refused as too short because the rounding of its offset end
/// point moved the end by more than a fixed angle. It is cut, on the offset
/// circle, as the geometry and the f64 reference say.
#[test]
fn concave_arc_just_larger_than_the_nose_is_cut() {
    let program = "G21 G18 G90 G40\nG00 X22 Z3\nN10 G41 G450 G01 Z0 F0.1\n\
                   N20 G01 X12.524 Z0.000\nN90 G01 X12.524 Z-9.306\n\
                   N100 G03 X12.464 Z-9.426 I-0.255 K0.000\nN110 G40 G00 X10.464\nM30\n";
    // The geometry, X on the radius: the arc's centre and end point, and
    // for each nose the TTT blocks of the end of the bore and of the arc.
    let (cx, cz) = (6.262 - 0.255, -9.306);
    let (ex, ez) = (12.464 / 2.0, -9.426);
    for rn in ["0.2", "0.254", "0.254999"] {
        let r: f64 = rn.parse().unwrap();
        let rho = 0.255 - r;
        // Tip code 2: the TTT is the nose centre plus (+r, −r) in (X, Z).
        let ttt = |x: f64, z: f64| (x + r, z - r);
        // The bore ends at its perpendicular offset point (a smooth corner).
        let (bx, bz) = ttt(6.262 - r, -9.306);
        // The arc ends on the offset circle at the end point's angle.
        let k = rho / 0.255;
        let (ax, az) = ttt(cx + k * (ex - cx), cz + k * (ez - cz));
        let (tcx, tcz) = ttt(cx, cz);
        let bore = format!("N90 G01 X{} Z{}", mm4(2.0 * bx), mm4(bz));
        let arc = format!(
            "N100 G03 X{} Z{} I{} K{}",
            mm4(2.0 * ax),
            mm4(az),
            mm4(tcx - bx),
            mm4(tcz - bz)
        );
        let settings = Settings {
            rn: rn.into(),
            tip: 2,
            diam: true,
            ..Settings::default()
        };
        let out = compensate(program, &settings).unwrap_or_else(|e| panic!("RN {rn}: {e}"));
        let lines: Vec<&str> = out.text.lines().collect();
        assert!(lines.contains(&bore.as_str()), "{bore} in {}", out.text);
        assert!(lines.contains(&arc.as_str()), "{arc} in {}", out.text);
        // The f64 reference prints the same blocks.
        let mut reference = RefContour::new(CompSettings {
            rn_mm: r,
            tip: 2,
            diam: true,
        });
        let mut printed = Vec::new();
        for line in program
            .lines()
            .filter(|l| l.starts_with('N') || l.starts_with("G00"))
        {
            printed.extend(reference.block_text(line).unwrap());
        }
        let tail = |b: &str| {
            b.split_once(' ')
                .map_or(String::new(), |(_, t)| t.to_string())
        };
        assert!(printed.contains(&tail(&bore)), "{bore} in {printed:?}");
        assert!(printed.contains(&tail(&arc)), "{arc} in {printed:?}");
    }
    // The published figures for the 0.2 mm nose (LinuxCNC 2.9 cuts the same).
    let out = compensate(
        program,
        &Settings {
            rn: "0.2".into(),
            tip: 2,
            diam: true,
            ..Settings::default()
        },
    )
    .unwrap();
    assert!(
        out.text.contains("N90 G01 X12.5240 Z-9.5060\n"),
        "{}",
        out.text
    );
    assert!(
        out.text
            .contains("N100 G03 X12.5111 Z-9.5319 I-0.0550 K0.0000\n"),
        "{}",
        out.text
    );
    // A nose as large as the arc cannot cut it.
    let e = compensate(
        program,
        &Settings {
            rn: "0.255".into(),
            tip: 2,
            diam: true,
            ..Settings::default()
        },
    )
    .unwrap_err();
    assert!(e.reason.contains("N100: concave arc radius"), "{e}");
}

/// A unit direction with rational components, as integer `[X, Z]` multiples
/// of `c`: one of the four axes or one of the eight images of `(a, b)` under
/// the symmetries of the square, `(a, b, c) = (m² − n², 2mn, m² + n²)`.
fn rational_direction(m: i64, n: i64, which: usize) -> ([i64; 2], i64) {
    let (a, b, c) = (m * m - n * n, 2 * m * n, m * m + n * n);
    let all = [
        [c, 0],
        [0, c],
        [-c, 0],
        [0, -c],
        [a, b],
        [b, a],
        [-a, b],
        [-b, a],
        [a, -b],
        [b, -a],
        [-a, -b],
        [-b, -a],
    ];
    (all[which % all.len()], c)
}

/// Whole micrometres as a millimetre word.
fn um(v: i64) -> String {
    format!("{:.3}", v as f64 / 1000.0)
}

/// A concave arc of radius `R = r + d` (µm), the tool inside it (`G41` with
/// `G03`, `G42` with `G02`), from and to points in rational directions from
/// its centre, so that both lie exactly on the circle: a tangent lead-in,
/// the arc (`I`/`K` or `R` form), an optional tangent lead-out, `G40`.
#[allow(clippy::too_many_arguments)]
fn concave_arc_case(
    (m, n): (i64, i64),
    from: usize,
    to: usize,
    d: i64,
    r_min: i64,
    left: bool,
    tip: u8,
    r_form: bool,
    lead_out: bool,
) -> ContourCase {
    let ((sx, sz), c) = {
        let (v, c) = rational_direction(m, n, from);
        ((v[0], v[1]), c)
    };
    let (e, _) = rational_direction(m, n, to);
    // R = k·c µm, at least r_min + d, and the nose radius r = R − d.
    let k = (r_min + d + c - 1) / c;
    let big_r = k * c;
    let r = big_r - d;
    let centre = [20_000i64, -10_000i64];
    let s = [centre[0] + k * sx, centre[1] + k * sz];
    let e = [centre[0] + k * e[0], centre[1] + k * e[1]];
    // The direction of travel of a G03 (G02) arc is its radius turned left
    // (right) in the (Z right, X up) plane: [X, Z] = [vz, −vx] for G03.
    let ccw = left;
    let tangent = |p: [i64; 2]| {
        let v = [p[0] - centre[0], p[1] - centre[1]];
        if ccw {
            [v[1], -v[0]]
        } else {
            [-v[1], v[0]]
        }
    };
    let (ts, te) = (tangent(s), tangent(e));
    let lead_in = [s[0] - ts[0], s[1] - ts[1]];
    let xz = |p: [i64; 2]| format!("X{} Z{}", um(2 * p[0]), um(p[1]));
    let g = if ccw { "G03" } else { "G02" };
    let shape = if r_form {
        // The sweep decides the sign of R: positive up to 180°.
        let angle = |p: [i64; 2]| ((p[0] - centre[0]) as f64).atan2((p[1] - centre[1]) as f64);
        let sweep = (if ccw {
            angle(e) - angle(s)
        } else {
            angle(s) - angle(e)
        })
        .rem_euclid(std::f64::consts::TAU);
        let sign = if sweep <= std::f64::consts::PI + 1e-9 {
            ""
        } else {
            "-"
        };
        format!("R{sign}{}", um(big_r))
    } else {
        format!("I{} K{}", um(centre[0] - s[0]), um(centre[1] - s[1]))
    };
    let mut lines = vec![
        format!("G00 {}", xz([centre[0] + 5_000, centre[1] + 5_000])),
        format!(
            "N1 {} G01 {} F200",
            if left { "G41" } else { "G42" },
            xz(lead_in)
        ),
        format!("N2 G01 {}", xz(s)),
        format!("N3 {g} {} {shape}", xz(e)),
    ];
    if lead_out {
        lines.push(format!("N4 G01 {}", xz([e[0] + te[0], e[1] + te[1]])));
    }
    lines.push(format!("N5 G40 G00 {}", xz(centre)));
    ContourCase {
        rn: um(r),
        tip,
        lines,
        feed: "200".into(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(10_000))]

    /// Concave arcs from 0.001 to 0.5 mm larger than the nose, at end angles
    /// all round the circle: the device cuts every one the f64 reference
    /// cuts, with the same blocks (end points and centres to 0.0001 mm).
    #[test]
    fn concave_arcs_barely_larger_than_the_nose_are_cut(
        m in 2i64..=12,
        n_raw in 0i64..11,
        from in 0usize..12,
        to_offset in 1usize..12,
        d in 1i64..=500,
        r_min in 10i64..=2_000,
        left in any::<bool>(),
        tip in 0u8..=9,
        r_form in any::<bool>(),
        lead_out in any::<bool>(),
    ) {
        let n = 1 + n_raw % (m - 1);
        let case = concave_arc_case(
            (m, n), from, (from + to_offset) % 12, d, r_min, left, tip, r_form, lead_out,
        );
        let mut tally = ContourTally::default();
        compare_contour(&mut LocalDevice::new(), &case, &mut tally).unwrap();
        prop_assert!(tally.mismatches.is_empty(), "{:?}: {:?}", case, tally.mismatches);
        prop_assert_eq!(tally.refused_alike, 0, "{:?}", case);
        // Every block of the program was answered and compared.
        prop_assert_eq!(tally.blocks, case.lines.len());
        prop_assert!(tally.compared >= case.lines.len(), "{:?}: {:?}", case, tally);
    }
}

/// Lines that meet arcs at inside corners turning by little (from below the
/// smooth limit of 2⁻²² rad up to 10⁻² rad), arcs of 0.25 mm to 1000 mm,
/// convex and concave: the offset elements are nearly tangent, and their
/// intersection must still be precise enough that the arc check (a few
/// 10⁻⁷ mm along the arc) passes. The device cuts them all, as the f64
/// reference does, with the same blocks.
#[test]
fn near_tangent_inside_corners_between_lines_and_arcs() {
    let mut tally = ContourTally::default();
    let add = |a: [i64; 2], b: [i64; 2]| [a[0] + b[0], a[1] + b[1]];
    let sub = |a: [i64; 2], b: [i64; 2]| [a[0] - b[0], a[1] - b[1]];
    // Coordinates in nm (10⁻⁶ mm, the finest a word can write).
    let nm = |v: i64| format!("{:.6}", v as f64 / 1e6);
    let xz = |p: [i64; 2]| format!("X{} Z{}", nm(2 * p[0]), nm(p[1]));
    // The turn of `a` to `b` in the (Z right, X up) plane: positive left.
    let cross = |a: [i64; 2], b: [i64; 2]| a[1] * b[0] - a[0] * b[1];
    for rn in [200_000i64, 400_000, 800_000] {
        for big_r in [
            250_000i64,
            500_000,
            1_000_000,
            10_000_000,
            100_000_000,
            1_000_000_000,
        ] {
            for ccw in [true, false] {
                // From the top of the circle (its X is 50 mm) to 53° on.
                let c = [50_000_000 - big_r, -100_000_000];
                let s = add(c, [big_r, 0]);
                let e = add(c, [3 * big_r / 5, if ccw { -4 } else { 4 } * big_r / 5]);
                // The direction of travel, as long as the radius.
                let tangent = |p: [i64; 2]| {
                    let v = sub(p, c);
                    if ccw {
                        [v[1], -v[0]]
                    } else {
                        [-v[1], v[0]]
                    }
                };
                let (ts, te) = (tangent(s), tangent(e));
                let along = |t: [i64; 2], len: i64| [t[0] * len / big_r, t[1] * len / big_r];
                let arc = format!(
                    "{} {} I{} K{}",
                    if ccw { "G03" } else { "G02" },
                    xz(e),
                    nm(c[0] - s[0]),
                    nm(c[1] - s[1])
                );
                for dev in [-20_000i64, -200, -20, -5, -1, 1, 5, 20, 200, 20_000] {
                    for len in [2_000_000i64, 10_000_000, 40_000_000] {
                        // Into the arc: a line from `dev` nm off the tangent;
                        // out of it: a line to `dev` nm off the tangent.
                        let lead_in = add(sub(s, along(ts, len)), [dev, 0]);
                        let lead_out = add(add(e, along(te, len)), [dev, 0]);
                        for out in [false, true] {
                            let turn = if out {
                                cross(te, sub(lead_out, e))
                            } else {
                                cross(sub(s, lead_in), ts)
                            };
                            // The tool on the inside of the corner.
                            let left = turn > 0;
                            if left == ccw && big_r <= rn {
                                continue;
                            }
                            let first = if out {
                                sub(s, along(ts, 2_000_000))
                            } else {
                                lead_in
                            };
                            let mut lines = vec![
                                format!("G00 {}", xz(add(first, [5_000_000, 5_000_000]))),
                                format!(
                                    "N1 {} G01 {} F200",
                                    if left { "G41" } else { "G42" },
                                    xz(first)
                                ),
                                format!("N2 G01 {}", xz(s)),
                                format!("N3 {arc}"),
                            ];
                            if out {
                                lines.push(format!("N4 G01 {}", xz(lead_out)));
                            }
                            lines.push(format!("N5 G40 G00 {}", xz(add(c, [0, 5_000_000]))));
                            for tip in [0, 3] {
                                let case = ContourCase {
                                    rn: nm(rn),
                                    tip,
                                    lines: lines.clone(),
                                    feed: "200".into(),
                                };
                                compare_contour(&mut LocalDevice::new(), &case, &mut tally)
                                    .unwrap();
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(
        tally.mismatches.is_empty(),
        "{} mismatches: {:#?}",
        tally.mismatches.len(),
        &tally.mismatches[..tally.mismatches.len().min(5)]
    );
    assert_eq!(tally.refused_alike, 0, "{tally:?}");
    assert!(tally.programs > 3_000, "{tally:?}");
}

/// Regressions the property tests found, kept as plain tests.
#[test]
fn arcs_whose_chords_end_on_rounding_boundaries_run_in_time() {
    let cases = [
        // The last chord of the G02 runs along X only (0.0000431 mm) but
        // issues the Z impulse its end's rounding tie gives: its event
        // comes at its end, and the chord takes the time of its length.
        ContourCase {
            rn: "0.040".into(),
            tip: 0,
            lines: [
                "G00 X50.000 Z-5.000",
                "N1 G42 G01 X39.342 Z-10.047 F200",
                "N2 G01 X39.718 Z-10.188",
                "N3 G02 X40.000 Z-10.235 I0.141 K0.188",
                "N4 G01 X40.470 Z-10.235",
                "N5 G40 G00 X40.000 Z-10.000",
            ]
            .map(String::from)
            .to_vec(),
            feed: "200".into(),
        },
        // A corner arc of 0.02 mm at TOL 0.01 mm: Δφ = 120° exactly, and
        // the first chord ends on a Z rounding boundary (cos 120° = −½).
        ContourCase {
            rn: "1.255".into(),
            tip: 1,
            lines: [
                "G00 X50.000 Z-5.000",
                "N1 G41 G01 X37.450 Z-8.725 F200",
                "N2 G01 X40.000 Z-8.725",
                "N3 G03 X37.690 Z-9.460 I0.000 K-1.275",
                "N5 G40 G00 X40.000 Z-10.000",
            ]
            .map(String::from)
            .to_vec(),
            feed: "200".into(),
        },
    ];
    for case in &cases {
        let mut tally = ContourTally::default();
        compare_contour(&mut LocalDevice::new(), case, &mut tally).unwrap();
        assert!(tally.mismatches.is_empty(), "{:?}", tally.mismatches);
        assert_eq!(tally.blocks, case.lines.len());
    }
}

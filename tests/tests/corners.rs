//! Fanuc's and Haas' corner chamfers and rounds (`,C`, `,R`): the contour
//! engine's fixed-point corners against the f64 reference written from
//! `docs/compensation.md` §9 (`reference::corner`), over random corners of
//! lines and arcs turning either way, every quadrant; then through the
//! device, a program that chamfers and rounds a shaft's corners, with and
//! without nose compensation.

use core_nostd::arc::ArcDir;
use core_nostd::comp::{CompError, Contour, Element, MoveKind, Origin, Shape, TipCode, Tool};
use core_nostd::gcode::CornerRound;
use core_nostd::length::Length;
use host_sim::device::LocalDevice;
use proptest::prelude::*;
use reference::corner::{corner, RefCorner, RefCornerRefusal, RefElement};

/// Ångström per mm.
const A: f64 = 1e7;

fn mm(p: [i64; 2]) -> (f64, f64) {
    (p[0] as f64 / A, p[1] as f64 / A)
}

fn grid(v: f64) -> i64 {
    (v * A).round() as i64
}

/// One random element meeting the corner `p` (ångström): a line of length
/// `len` mm along `angle`, or an arc of radius `radius` mm turning `sweep`
/// radians, whose direction at `p` is `angle`. `ends_at_p`: the element
/// ends at `p` (the first), else starts there (the next).
fn element(
    p: [i64; 2],
    angle: f64,
    arc: Option<(f64, f64, bool)>,
    len: f64,
    ends_at_p: bool,
) -> Element {
    // Directions as (x, z): angle measured in the (Z right, X up) picture.
    let (tx, tz) = (angle.sin(), angle.cos());
    let (px, pz) = (p[0] as f64, p[1] as f64);
    match arc {
        None => {
            let sign = if ends_at_p { -1.0 } else { 1.0 };
            let q = [
                grid((px / A) + sign * len * tx),
                grid((pz / A) + sign * len * tz),
            ];
            if ends_at_p {
                Element::line(q, p, false, None)
            } else {
                Element::line(p, q, false, None)
            }
        }
        Some((radius, sweep, left)) => {
            // The centre on the left of travel (ccw) or on the right (cw):
            // left of (tx, tz) in (Z right, X up) is (x: tz, z: -tx).
            let (nx, nz) = if left { (tz, -tx) } else { (-tz, tx) };
            let c = [grid(px / A + radius * nx), grid(pz / A + radius * nz)];
            let (cx, cz) = (c[0] as f64 / A, c[1] as f64 / A);
            let (rx, rz) = (px / A - cx, pz / A - cz);
            // Rotating (rz, rx) as a (Z, X) vector by `a` (positive: ccw).
            let rot = |a: f64| {
                let (s, co) = a.sin_cos();
                let z = rz * co - rx * s;
                let x = rz * s + rx * co;
                [grid(cx + x), grid(cz + z)]
            };
            // Travel ccw (left) turns positively: the start lies `sweep`
            // back, the end `sweep` on.
            let turn = if left { sweep } else { -sweep };
            let q = rot(if ends_at_p { -turn } else { turn });
            let dir = if left { ArcDir::Ccw } else { ArcDir::Cw };
            let (from, to) = if ends_at_p { (q, p) } else { (p, q) };
            Element {
                from,
                to,
                shape: Shape::Arc { centre: c, dir },
                n: None,
            }
        }
    }
}

fn as_ref(e: &Element) -> RefElement {
    match e.shape {
        Shape::Line { .. } => RefElement::Line {
            from: mm(e.from),
            to: mm(e.to),
        },
        Shape::Arc { centre, dir } => RefElement::Arc {
            from: mm(e.from),
            to: mm(e.to),
            centre: mm(centre),
            ccw: dir == ArcDir::Ccw,
        },
    }
}

/// The engine's corner: the points where the first ends, the joint ends,
/// the joint's centre if it is an arc, and the next ends; or its refusal.
type Points = ([(f64, f64); 3], Option<(f64, f64)>);

fn core_corner(e1: Element, e2: Element, c: CornerRound) -> Result<Points, CompError> {
    let tool = Tool::new(Length::ZERO, TipCode::EXTERNAL_RIGHT);
    let (waiting, _) = Contour::new().rounded(&tool, None, None, Some(e1), Some(c), None)?;
    let (_, moves) = waiting.rounded(&tool, None, None, Some(e2), None, None)?;
    let waiting_moves: Vec<_> = moves
        .iter()
        .filter(|m| m.origin == Origin::Waiting)
        .collect();
    let joint = waiting_moves.last().expect("a joint");
    // The first cut short, or nothing of it left.
    let first_end = match waiting_moves.as_slice() {
        [first, _] => mm(first.to),
        _ => mm(e1.from),
    };
    let centre = match joint.kind {
        MoveKind::Arc { centre, .. } => Some(mm(centre)),
        MoveKind::Line { .. } => None,
    };
    let last = moves.last().expect("the next move");
    assert_eq!(last.origin, Origin::Current);
    Ok(([first_end, mm(joint.to), mm(last.to)], centre))
}

fn ref_corner(e1: &Element, e2: &Element, c: CornerRound) -> Result<Points, RefCornerRefusal> {
    let size = |l: Length| l.as_angstrom() as f64 / A;
    let rc = match c {
        CornerRound::Chamfer(l)
        | CornerRound::Square {
            size: l,
            chamfer: true,
            ..
        } => RefCorner::Chamfer(size(l)),
        CornerRound::Round(l) | CornerRound::Square { size: l, .. } => RefCorner::Round(size(l)),
    };
    let (first, joint, rest) = corner(as_ref(e1), as_ref(e2), rc)?;
    let end = |e: &RefElement| match *e {
        RefElement::Line { to, .. } | RefElement::Arc { to, .. } => to,
    };
    let first_end = first.as_ref().map(end).unwrap_or(mm(e1.from));
    let centre = match joint {
        RefElement::Arc { centre, .. } => Some(centre),
        RefElement::Line { .. } => None,
    };
    Ok(([first_end, end(&joint), end(&rest)], centre))
}

fn same_refusal(core: CompError, reference: RefCornerRefusal) -> bool {
    matches!(
        (core, reference),
        (CompError::RoundNoCorner(..), RefCornerRefusal::NoCorner)
            | (CompError::RoundTooBig(..), RefCornerRefusal::TooBig)
            | (CompError::ChamferArc(..), RefCornerRefusal::ChamferArc)
    )
}

/// The grid's rounding of each point, and the engine's arithmetic within
/// it: 3·10⁻⁷ mm.
const CLOSE: f64 = 3e-7;

fn close(a: (f64, f64), b: (f64, f64)) -> bool {
    (a.0 - b.0).abs() <= CLOSE && (a.1 - b.1).abs() <= CLOSE
}

/// One random corner from the ranges the property test draws from.
fn draw(u: &mut impl FnMut() -> f64) -> (Element, Element, CornerRound) {
    let p = [grid(100.0 * u() - 50.0), grid(100.0 * u() - 50.0)];
    let a1 = std::f64::consts::TAU * u();
    let turn = (5.0 + 170.0 * u()) * if u() < 0.5 { 1.0 } else { -1.0 };
    let arc = |u: &mut dyn FnMut() -> f64| {
        (u() < 0.5).then(|| (2.0 + 58.0 * u(), 0.05 + 1.45 * u(), u() < 0.5))
    };
    let (arc1, arc2) = (arc(u), arc(u));
    let (len1, len2) = (0.5 + 39.5 * u(), 0.5 + 39.5 * u());
    let size = Length::from_angstrom(grid(0.05 + 7.95 * u())).unwrap();
    let e1 = element(p, a1, arc1, len1, true);
    let e2 = element(p, a1 + turn.to_radians(), arc2, len2, false);
    let c = if u() < 0.5 {
        CornerRound::Chamfer(size)
    } else {
        CornerRound::Round(size)
    };
    (e1, e2, c)
}

/// The random corners reach every outcome, often: chamfers and rounds
/// taken, rounds on arcs taken, and each refusal; on each the engine and
/// the reference agree.
#[test]
fn random_corners_cover_every_outcome() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut u = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut seen = std::collections::BTreeMap::<&str, usize>::new();
    for _ in 0..4000 {
        let (e1, e2, c) = draw(&mut u);
        let arcs =
            !matches!(e1.shape, Shape::Line { .. }) || !matches!(e2.shape, Shape::Line { .. });
        let what = match (core_corner(e1, e2, c), ref_corner(&e1, &e2, c)) {
            (Ok(_), Ok(_)) => match c {
                CornerRound::Chamfer(_) => "chamfer",
                CornerRound::Round(_) if arcs => "round with an arc",
                CornerRound::Round(_) => "round of lines",
                CornerRound::Square { .. } => "right angle",
            },
            (Err(e), Err(r)) if same_refusal(e, r) => match r {
                RefCornerRefusal::NoCorner => "no corner",
                RefCornerRefusal::TooBig => "too big",
                RefCornerRefusal::ChamferArc => "chamfer on an arc",
            },
            (core, reference) => panic!("{e1:?} {e2:?} {c:?}: {core:?} vs {reference:?}"),
        };
        *seen.entry(what).or_default() += 1;
    }
    for what in [
        "chamfer",
        "round with an arc",
        "round of lines",
        "too big",
        "chamfer on an arc",
    ] {
        assert!(
            seen.get(what).copied().unwrap_or(0) >= 100,
            "{what}: {seen:?}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn corners_equal_the_reference(
        px in -50.0f64..50.0, pz in -50.0f64..50.0,
        a1 in 0.0f64..std::f64::consts::TAU,
        turn in prop_oneof![5.0f64..175.0, -175.0f64..-5.0],
        arc1 in prop::option::of((2.0f64..60.0, 0.05f64..1.5, any::<bool>())),
        arc2 in prop::option::of((2.0f64..60.0, 0.05f64..1.5, any::<bool>())),
        len1 in 0.5f64..40.0, len2 in 0.5f64..40.0,
        size in 0.05f64..8.0,
        chamfer in any::<bool>(),
    ) {
        let p = [grid(px), grid(pz)];
        let a2 = a1 + turn.to_radians();
        let e1 = element(p, a1, arc1, len1, true);
        let e2 = element(p, a2, arc2, len2, false);
        let size = Length::from_angstrom(grid(size)).unwrap();
        let c = if chamfer { CornerRound::Chamfer(size) } else { CornerRound::Round(size) };
        let core = core_corner(e1, e2, c);
        let reference = ref_corner(&e1, &e2, c);
        match (core, reference) {
            (Ok((cp, cc)), Ok((rp, rc))) => {
                for (x, y) in cp.iter().zip(rp.iter()) {
                    prop_assert!(close(*x, *y), "{e1:?} {e2:?} {c:?}: core {cp:?} reference {rp:?}");
                }
                match (cc, rc) {
                    (Some(x), Some(y)) => prop_assert!(close(x, y), "centre {x:?} {y:?}"),
                    (None, None) => {}
                    _ => prop_assert!(false, "{e1:?} {e2:?} {c:?}: joints differ"),
                }
            }
            (Err(e), Err(r)) => prop_assert!(same_refusal(e, r), "{e1:?} {e2:?} {c:?}: {e:?} vs {r:?}"),
            (core, reference) => prop_assert!(false, "{e1:?} {e2:?} {c:?}: core {core:?}, reference {reference:?}"),
        }
    }
}

/// The DATA lines (without their checksum) a device sends for `lines`,
/// each of which it must take.
fn data_of(lines: &[&str]) -> Vec<String> {
    let mut dev = LocalDevice::new();
    let mut data = Vec::new();
    for l in lines {
        let r = dev.request(l);
        assert!(r.last().unwrap().starts_with("OK"), "{l}: {r:?}");
        data.extend(
            r.into_iter()
                .filter(|x| x.starts_with("DATA"))
                .map(|x| x.split('*').next().unwrap_or("").to_string()),
        );
    }
    data
}

/// A shaft's corners through the device, in the Fanuc dialect: the chamfer
/// on the face, a round into the shoulder, a chamfer on the shoulder's
/// edge; the moves as drawn, the round tangent. Under `G42` the device
/// compensates the corners as it does the same contour written out block
/// by block.
#[test]
fn a_program_with_corners_runs_as_drawn() {
    let head = [
        "OPT DIALECT=fanuc",
        "CFG RN=0.4 TIP=3",
        "G21 G18 G98",
        "G00 X20. Z2.",
    ];
    let with_corners = [
        "G01 Z0 F100.",
        "X40. ,C2.",
        "Z-30. ,R5.",
        "X60. ,C1.",
        "Z-50.",
    ];
    let drawn = [
        "G01 Z0 F100.",
        "X36.",
        "X40. Z-2.",
        "Z-25.",
        "G02 X50. Z-30. R5.",
        "G01 X58.",
        "X60. Z-31.",
        "Z-50.",
    ];
    let run = |g42: bool, body: &[&str]| {
        let mut lines: Vec<&str> = head.to_vec();
        if g42 {
            lines.push("G42 G01 X20. Z1. F100.");
        }
        lines.extend_from_slice(body);
        lines.push(if g42 { "G40 G00 X80." } else { "G00 X80." });
        data_of(&lines)
    };
    assert_eq!(
        run(false, &with_corners),
        [
            "DATA G00 X20.0000 Z2.0000",
            "DATA G01 X20.0000 Z0.0000",
            "DATA G01 X36.0000 Z0.0000",
            "DATA G01 X40.0000 Z-2.0000",
            "DATA G01 X40.0000 Z-25.0000",
            "DATA G02 X50.0000 Z-30.0000 I5.0000 K0.0000",
            "DATA G01 X58.0000 Z-30.0000",
            "DATA G01 X60.0000 Z-31.0000",
            "DATA G01 X60.0000 Z-50.0000",
            "DATA G00 X80.0000 Z-50.0000",
        ]
    );
    assert_eq!(run(false, &with_corners), run(false, &drawn));
    let compensated = run(true, &with_corners);
    assert_eq!(compensated, run(true, &drawn));
    // Compensated: the round's radius less the nose's.
    assert!(
        compensated
            .iter()
            .any(|l| l.contains("G02") && l.contains("I4.6000")),
        "{compensated:?}"
    );
}

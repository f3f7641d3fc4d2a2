//! The roughing of the turning cycles `G71`, `G72` and `G73` through the
//! in-process device, against the f64 reference written from
//! `docs/cycles.md` alone (`reference::cycle`): the `DATA` lines of the block
//! `Q`, move for move, on the worked example of `docs/cycles.md` §9, a pocket,
//! a bore, a facing, a pattern, and on random profiles. For each case:
//!
//! * (a) the device's moves are the reference's: the same count, each of the
//!   same kind, its end (and an arc's `I`, `K`) within 0.0001 mm as printed
//!   (X on the diameter);
//! * (b) no move of the device (feed or rapid; feeds only in `G73`) enters the part with its allowances
//!   (`reference::cycle::Region`) by more than 0.0001 mm;
//! * (c) `G71`/`G72`: the passes leave less than one depth of cut above the
//!   profile, measured along the depth axis (the supremum is one depth of cut,
//!   approached just past the end of a cut that ends on a slope, so the bound
//!   is `Δd` + 10⁻⁶; the printed cuts are counted 0.0001 mm longer, the
//!   print's precision); `G73`: the pass before the last lies
//!   `relief/(n − 1)` beyond the last;
//! * (d) the pass along the profile (the last pass of a `G73`) is the profile
//!   moved by the allowances, element for element, computed here from the
//!   program's own numbers.
//!
//! Random profiles are built in the frame of `docs/cycles.md` §3.1 (`c` along
//! the cut, `d` the depth) on a 0.001 mm grid (radius, so diameters on an even
//! 0.002 mm grid), then placed on the machine: outside turning and boring,
//! `G71` and `G72`, either direction along the cut; monotone profiles (type I)
//! and profiles with pockets (type II); arcs whose ends are lattice points of
//! one circle, so that the radius is exact. The first point `A` is the
//! deepest point, with a flat across the start side's line, so that every
//! pass has a cut from the start side, and the depth of cut is moved off the
//! depth of every flat; the cases outside that (a flat at a pass's depth, a
//! first point in front of the start side, a pass whose one cut is a
//! pocket) are the fixed tests at the end. `G73` profiles take
//! any shape that runs one way along the cut; their relief and allowance
//! along the cut are 0 when the profile has pockets (a pattern moved along
//! the cut enters a pocket's near wall, which the cycle does not forbid).

use host_sim::device::LocalDevice;
use host_sim::link::Transport;
use proptest::prelude::*;
use proptest::test_runner::Config;
use reference::cycle::{
    finishing_pass, mm4, roughing, split_final_pass, stock_left, texts, ArcDir, Axis, Cycle,
    Element, Kind, Move, MoveKind, Profile, Pt, Region,
};
use std::sync::OnceLock;

/// Points compared to this, mm (as printed, X on the diameter).
const TOL: f64 = 1e-4;

/// A `DATA` line of the block `Q`.
#[derive(Clone, Debug)]
struct Printed {
    text: String,
    kind: MoveKind,
    /// X as printed: a diameter.
    x: f64,
    z: f64,
    ik: Option<(f64, f64)>,
}

impl Printed {
    fn parse(line: &str) -> Printed {
        let text = line.trim_start_matches("DATA ").to_string();
        let mut words = text.split(' ');
        let kind = match words.next() {
            Some("G00") => MoveKind::Rapid,
            Some("G01") => MoveKind::Feed,
            Some("G02") => MoveKind::Cw,
            Some("G03") => MoveKind::Ccw,
            other => panic!("not a move: {line:?} ({other:?})"),
        };
        let word = |l: char| {
            text.split(' ')
                .find_map(|w| w.strip_prefix(l))
                .map(|v| v.parse::<f64>().unwrap())
        };
        let (i, k) = (word('I'), word('K'));
        Printed {
            kind,
            x: word('X').unwrap(),
            z: word('Z').unwrap(),
            ik: i.zip(k),
            text,
        }
    }

    /// The end point, X a radius.
    fn end(&self) -> Pt {
        Pt::new(self.x / 2.0, self.z)
    }

    /// As a reference move (the centre from the printed start).
    fn to_move(&self, from: Pt) -> Move {
        Move {
            kind: self.kind,
            end: self.end(),
            centre: self.ik.map(|(i, k)| Pt::new(from.x + i, from.z + k)),
        }
    }
}

/// Runs `lines` on a fresh device: every line must be answered `OK`, the
/// profile's blocks before `Q` with `HELD=`; returns the `DATA` lines of the
/// last (the block `Q`).
fn device(lines: &[String], profile_from: usize) -> Result<Vec<Printed>, String> {
    let mut dev = LocalDevice::new();
    let mut last = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let r = Transport::request(&mut dev, line).map_err(|e| e.to_string())?;
        if !r.is_ok() {
            return Err(format!("{line}: {}", r.last));
        }
        if i >= profile_from && i + 1 < lines.len() && r.value("HELD").is_none() {
            return Err(format!("{line}: not held: {}", r.last));
        }
        last = r.data;
    }
    Ok(last.iter().map(|l| Printed::parse(l)).collect())
}

/// (a): `dev` is `reference`, move for move.
fn same_moves(start: Pt, dev: &[Printed], reference: &[Move]) -> Result<(), String> {
    let mismatch = |why: String| {
        let d: Vec<&str> = dev.iter().map(|p| p.text.as_str()).collect();
        Err(format!(
            "{why}\ndevice ({}):\n  {}\nreference ({}):\n  {}",
            d.len(),
            d.join("\n  "),
            reference.len(),
            texts(start, reference).join("\n  ")
        ))
    };
    let mut from = start;
    for (i, (p, r)) in dev.iter().zip(reference).enumerate() {
        let near = |a: f64, b: f64| (a - b).abs() <= TOL + 1e-9;
        let mut ok = p.kind == r.kind && near(p.x, 2.0 * r.end.x) && near(p.z, r.end.z);
        match (p.ik, r.centre) {
            (None, None) => {}
            (Some((i, k)), Some(c)) => ok &= near(i, c.x - from.x) && near(k, c.z - from.z),
            _ => ok = false,
        }
        if !ok {
            return mismatch(format!(
                "move {i}: device {:?}, reference {:?}",
                p.text,
                r.text(from)
            ));
        }
        from = r.end;
    }
    if dev.len() != reference.len() {
        return mismatch(format!(
            "{} moves from the device, {} from the reference",
            dev.len(),
            reference.len()
        ));
    }
    Ok(())
}

/// The printed moves as the reference's, from `start`.
fn moves_of(start: Pt, dev: &[Printed]) -> Vec<Move> {
    let mut at = start;
    dev.iter()
        .map(|p| {
            let m = p.to_move(at);
            at = m.end;
            m
        })
        .collect()
}

/// (b): the least signed distance of the device's moves from the part, the
/// rapids' too when `rapids` (a rapid through the part is the worse fault;
/// `G73`'s straight returns to S are the programmer's to keep clear,
/// docs/cycles.md §3.6), and the move that has it.
fn deepest_entry(cycle: &Cycle, axis: Axis, dev: &[Printed], rapids: bool) -> (f64, String) {
    let region = Region::along(cycle, axis).expect("the region of a valid profile");
    let mut from = cycle.start;
    let mut worst = (f64::INFINITY, String::new());
    for (p, m) in dev.iter().zip(moves_of(cycle.start, dev)) {
        if rapids || m.kind.is_feed() {
            let sd = region.min_signed_distance(from, &m);
            if sd < worst.0 {
                worst = (sd, p.text.clone());
            }
        }
        from = m.end;
    }
    worst
}

/// A point in 0.001 mm: X a radius.
type Um = (i64, i64);

/// Millimetres with three decimals from 0.001 mm.
fn w3(v: i64) -> String {
    let sign = if v < 0 { "-" } else { "" };
    format!("{sign}{}.{:03}", v.abs() / 1000, v.abs() % 1000)
}

fn pt(p: Um) -> Pt {
    Pt::new(p.0 as f64 / 1000.0, p.1 as f64 / 1000.0)
}

/// One element of a case, on the machine (0.001 mm, X a radius).
#[derive(Clone, Copy, Debug)]
struct El {
    end: Um,
    /// An arc's centre and whether it is `G03`.
    arc: Option<(Um, bool)>,
}

#[derive(Clone, Copy, Debug)]
enum CaseKind {
    G71,
    G72,
    /// Relief (X a radius, Z) and count.
    G73(Um, u32),
}

/// A cycle as a program gives it, in 0.001 mm.
#[derive(Clone, Debug)]
struct Case {
    kind: CaseKind,
    start: Um,
    a: Um,
    els: Vec<El>,
    /// Allowances, X a radius.
    allow: Um,
    depth: i64,
    retract: i64,
    /// The depth axis of the part's region: X, or Z.
    axis: Axis,
}

impl Case {
    /// The program from `OPT DIALECT=FANUC` to the block `Q`, and the index
    /// of its first profile block.
    fn program(&self) -> (Vec<String>, usize) {
        let mut l = vec![
            "OPT DIALECT=FANUC".to_string(),
            "G21 G18 G98".to_string(),
            "G01 F250.".to_string(),
            format!("G00 X{} Z{}", w3(2 * self.start.0), w3(self.start.1)),
        ];
        let q = 10 * (self.els.len() + 1);
        let (u, w) = (w3(2 * self.allow.0), w3(self.allow.1));
        match self.kind {
            CaseKind::G71 => {
                l.push(format!("G71 U{} R{}", w3(self.depth), w3(self.retract)));
                l.push(format!("G71 P10 Q{q} U{u} W{w} F200."));
            }
            CaseKind::G72 => {
                l.push(format!("G72 W{} R{}", w3(self.depth), w3(self.retract)));
                l.push(format!("G72 P10 Q{q} U{u} W{w} F200."));
            }
            CaseKind::G73(relief, n) => {
                l.push(format!("G73 U{} W{} R{n}", w3(relief.0), w3(relief.1)));
                l.push(format!("G73 P10 Q{q} U{u} W{w} F200."));
            }
        }
        let first = l.len();
        l.push(format!("N10 G00 X{} Z{}", w3(2 * self.a.0), w3(self.a.1)));
        let mut at = self.a;
        for (i, e) in self.els.iter().enumerate() {
            let n = 10 * (i + 2);
            let (x, z) = (w3(2 * e.end.0), w3(e.end.1));
            l.push(match e.arc {
                None => format!("N{n} G01 X{x} Z{z}"),
                Some((c, ccw)) => format!(
                    "N{n} G0{} X{x} Z{z} I{} K{}",
                    if ccw { 3 } else { 2 },
                    w3(c.0 - at.0),
                    w3(c.1 - at.1)
                ),
            });
            at = e.end;
        }
        (l, first)
    }

    fn cycle(&self) -> Cycle {
        let elements = self
            .els
            .iter()
            .map(|e| match e.arc {
                None => Element::Line { end: pt(e.end) },
                Some((c, ccw)) => Element::Arc {
                    end: pt(e.end),
                    centre: pt(c),
                    dir: if ccw { ArcDir::Ccw } else { ArcDir::Cw },
                },
            })
            .collect();
        Cycle {
            kind: match self.kind {
                CaseKind::G71 => Kind::Turning,
                CaseKind::G72 => Kind::Facing,
                CaseKind::G73(r, n) => Kind::Pattern {
                    relief: pt(r),
                    count: n,
                },
            },
            start: pt(self.start),
            profile: Profile {
                start: pt(self.a),
                elements,
            },
            allowance: pt(self.allow),
            depth: self.depth as f64 / 1000.0,
            retract: self.retract as f64 / 1000.0,
        }
    }

    /// (d): the profile moved by the allowances, from the program's numbers:
    /// (kind, end, centre), in 0.001 mm.
    fn moved_profile(&self) -> Vec<(MoveKind, Um, Option<Um>)> {
        let mv = |p: Um| (p.0 + self.allow.0, p.1 + self.allow.1);
        self.els
            .iter()
            .map(|e| match e.arc {
                None => (MoveKind::Feed, mv(e.end), None),
                Some((c, ccw)) => (
                    if ccw { MoveKind::Ccw } else { MoveKind::Cw },
                    mv(e.end),
                    Some(mv(c)),
                ),
            })
            .collect()
    }

    fn describe(&self) -> String {
        self.program().0.join("\n")
    }
}

/// Runs a case through the device and the reference and makes the four
/// checks; returns the device's moves.
fn check(case: &Case) -> Result<Vec<Printed>, String> {
    let (lines, first) = case.program();
    let cycle = case.cycle();
    let fail = |why: String| format!("{why}\nprogram:\n{}", case.describe());
    let dev = device(&lines, first).map_err(|e| fail(format!("device refused: {e}")))?;
    let reference = roughing(&cycle).map_err(|e| fail(format!("reference refused: {e:?}")))?;
    // (a)
    same_moves(cycle.start, &dev, &reference).map_err(fail)?;
    // (b)
    let rapids = !matches!(case.kind, CaseKind::G73(..));
    let (sd, at) = deepest_entry(&cycle, case.axis, &dev, rapids);
    if sd < -TOL {
        return Err(fail(format!("{at} enters the part by {:.6} mm", -sd)));
    }
    // (d)
    let moves = moves_of(cycle.start, &dev);
    let split = split_final_pass(&moves);
    let last: Vec<&Printed> = dev[split..]
        .iter()
        .take_while(|p| p.kind.is_feed())
        .collect();
    let expected = case.moved_profile();
    let mut from = dev
        .get(split.wrapping_sub(1))
        .map_or(cycle.start, Printed::end);
    let on_profile = last.len() == expected.len()
        && last.iter().zip(&expected).all(|(p, (kind, end, centre))| {
            let near = |a: f64, b: i64| (a - b as f64 / 1000.0).abs() <= TOL + 1e-9;
            let ik_ok = match (p.ik, centre) {
                (None, None) => true,
                (Some((i, k)), Some(c)) => near(i + from.x, c.0) && near(k + from.z, c.1),
                _ => false,
            };
            from = p.end();
            p.kind == *kind && near(p.x / 2.0, end.0) && near(p.z, end.1) && ik_ok
        });
    if !on_profile {
        return Err(fail(format!(
            "the last pass is not the profile with its allowances: {:?} against {expected:?}",
            last.iter().map(|p| &p.text).collect::<Vec<_>>()
        )));
    }
    // (c)
    match case.kind {
        CaseKind::G71 | CaseKind::G72 => {
            let left =
                stock_left(&cycle, &moves[..split], TOL).map_err(|e| fail(format!("{e:?}")))?;
            if left > cycle.depth + 1e-6 {
                return Err(fail(format!(
                    "{left:.6} mm left for the pass along the profile, depth of cut {}",
                    cycle.depth
                )));
            }
        }
        CaseKind::G73(relief, n) if n > 1 => {
            // The first points of the last two passes.
            let starts: Vec<&Printed> = dev
                .iter()
                .zip(std::iter::once(None).chain(dev.iter().map(Some)))
                .filter(|(p, before)| {
                    p.kind == MoveKind::Rapid && before.is_none_or(|b| b.kind == MoveKind::Rapid)
                })
                .map(|(p, _)| p)
                .filter(|p| (p.end().dist(cycle.start)) > 1e-6)
                .collect();
            let (u, v) = (starts[starts.len() - 2], starts[starts.len() - 1]);
            let step = |r: i64| r as f64 / 1000.0 / f64::from(n - 1);
            let ok = ((u.x - v.x) / 2.0 - step(relief.0)).abs() <= TOL
                && ((u.z - v.z) - step(relief.1)).abs() <= TOL;
            if !ok {
                return Err(fail(format!(
                    "the pass before the last ({}) is not relief/(n-1) beyond the last ({})",
                    u.text, v.text
                )));
            }
        }
        CaseKind::G73(..) => {}
    }
    Ok(dev)
}

// ---------------------------------------------------------------------------
// Fixed examples.

fn line(x: i64, z: i64) -> El {
    El {
        end: (x, z),
        arc: None,
    }
}

fn arc(x: i64, z: i64, cx: i64, cz: i64, ccw: bool) -> El {
    El {
        end: (x, z),
        arc: Some(((cx, cz), ccw)),
    }
}

fn texts_of(dev: &[Printed]) -> Vec<&str> {
    dev.iter().map(|p| p.text.as_str()).collect()
}

/// `docs/cycles.md` §9: the device, the reference and the page agree.
#[test]
fn the_stepped_shaft_of_the_docs() {
    let case = Case {
        kind: CaseKind::G71,
        start: (15_000, 2_000),
        a: (10_000, 2_000),
        els: vec![
            line(10_000, -10_000),
            line(13_000, -15_000),
            line(13_000, -25_000),
        ],
        allow: (200, 100),
        depth: 1_500,
        retract: 500,
        axis: Axis::X,
    };
    let dev = check(&case).unwrap_or_else(|e| panic!("{e}"));
    let page =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/cycles.md")).unwrap();
    let block: Vec<&str> = page
        .lines()
        .skip_while(|l| !l.starts_with("OK NX=0 NZ=0 PX=3000 PZ=200 SEQ=00000000 HELD=3"))
        .skip(1)
        .take_while(|l| l.starts_with("DATA"))
        .map(|l| l.trim_start_matches("DATA "))
        .collect();
    assert_eq!(block.len(), 19, "docs/cycles.md §9's reply");
    assert_eq!(texts_of(&dev), block);
    let reference = roughing(&case.cycle()).unwrap();
    assert_eq!(texts(case.cycle().start, &reference), block);
}

/// A type II profile: a bump at X30, a pocket at X24 with a concave arc at
/// its bottom, from a bar of 40.
#[test]
fn a_pocket_is_cut_from_above_after_its_bump() {
    let case = Case {
        kind: CaseKind::G71,
        start: (20_000, 2_000),
        a: (10_000, 2_000),
        els: vec![
            line(10_000, -5_000),
            line(15_000, -10_000),
            line(13_000, -13_000),
            // R 5 about X16 Z-17: from 3 below and 4 before the centre to 3
            // below and 4 after, through the bottom X2·11.
            arc(13_000, -21_000, 16_000, -17_000, false),
            line(18_000, -25_000),
        ],
        allow: (200, 100),
        depth: 2_000,
        retract: 500,
        axis: Axis::X,
    };
    let dev = check(&case).unwrap_or_else(|e| panic!("{e}"));
    let t = texts_of(&dev);
    // The pass at depth 6 (X28): to the bump, out, across, down to the depth
    // of the pass before (X32), in at the feed, along the pocket.
    let at = t.iter().position(|l| *l == "G00 X28.0000 Z2.0000").unwrap();
    assert_eq!(
        t[at..at + 11],
        [
            "G00 X28.0000 Z2.0000",
            "G01 X28.0000 Z-8.7000",
            "G01 X29.0000 Z-8.2000",
            "G00 X40.0000 Z-8.2000",
            "G00 X40.0000 Z-11.7000",
            "G00 X32.0000 Z-11.7000",
            "G01 X28.0000 Z-11.7000",
            "G01 X28.0000 Z-21.5400",
            "G01 X29.0000 Z-21.0400",
            "G00 X40.0000 Z-21.0400",
            "G00 X40.0000 Z2.0000",
        ]
    );
    // The pass along the profile keeps the arc whole.
    assert!(t.contains(&"G02 X26.4000 Z-20.9000 I3.0000 K-4.0000"));
}

/// A bore: S X10 inside a bore stepping from X30 to X20, passes outwards.
#[test]
fn a_bore_is_roughed_outwards() {
    let case = Case {
        kind: CaseKind::G71,
        start: (5_000, 1_000),
        a: (15_000, 1_000),
        els: vec![
            line(15_000, -8_000),
            // A concave fillet R2 into the step.
            arc(13_000, -10_000, 13_000, -8_000, true),
            line(10_000, -10_000),
            line(10_000, -20_000),
        ],
        allow: (-150, 50),
        depth: 2_000,
        retract: 400,
        axis: Axis::X,
    };
    let dev = check(&case).unwrap_or_else(|e| panic!("{e}"));
    let t = texts_of(&dev);
    // A with its allowances: X29.7 (the bore's allowance is negative), Z1.05:
    // 9.85 deep from X10. Passes at X14 and X18 run the whole length (the
    // small bore, X19.7, is 4.85 deep), X22 ends on the face at Z-9.95, X26
    // on the fillet (radius 2 about X25.7 Z-7.95: Z-7.95 − √(4 − 0.15²)).
    // The retract goes back along Z and in towards the axis, X−0.8 Z+0.4.
    assert_eq!(
        t,
        [
            "G00 X14.0000 Z1.0000",
            "G01 X14.0000 Z-19.9500",
            "G01 X13.2000 Z-19.5500",
            "G00 X13.2000 Z1.0000",
            "G00 X18.0000 Z1.0000",
            "G01 X18.0000 Z-19.9500",
            "G01 X17.2000 Z-19.5500",
            "G00 X17.2000 Z1.0000",
            "G00 X22.0000 Z1.0000",
            "G01 X22.0000 Z-9.9500",
            "G01 X21.2000 Z-9.5500",
            "G00 X21.2000 Z1.0000",
            "G00 X26.0000 Z1.0000",
            "G01 X26.0000 Z-9.9444",
            "G01 X25.2000 Z-9.5444",
            "G00 X25.2000 Z1.0000",
            "G00 X29.7000 Z1.0000",
            "G00 X29.7000 Z1.0500",
            "G01 X29.7000 Z-7.9500",
            "G03 X25.7000 Z-9.9500 I-2.0000 K0.0000",
            "G01 X19.7000 Z-9.9500",
            "G01 X19.7000 Z-19.9500",
            "G00 X10.0000 Z-19.9500",
            "G00 X10.0000 Z1.0000",
        ]
    );
}

/// Facing and pattern repeating on the same part.
#[test]
fn a_facing_and_a_pattern() {
    let facing = Case {
        kind: CaseKind::G72,
        start: (21_000, 1_000),
        a: (21_000, -10_000),
        els: vec![
            line(15_000, -10_000),
            line(10_000, -6_000),
            arc(8_000, -4_000, 8_000, -6_000, false),
            line(8_000, 0),
        ],
        allow: (200, 100),
        depth: 1_500,
        retract: 300,
        axis: Axis::Z,
    };
    let dev = check(&facing).unwrap_or_else(|e| panic!("{e}"));
    let t = texts_of(&dev);
    assert_eq!(
        t[..4],
        [
            "G00 X42.0000 Z-0.5000",
            "G01 X16.4000 Z-0.5000",
            "G01 X17.0000 Z-0.2000",
            "G00 X42.0000 Z-0.2000",
        ]
    );
    let pattern = Case {
        kind: CaseKind::G73((3_000, 1_000), 3),
        start: (25_000, 5_000),
        a: (10_000, 2_000),
        els: vec![
            line(10_000, -5_000),
            arc(14_000, -9_000, 14_000, -5_000, false),
            line(14_000, -15_000),
            line(20_000, -20_000),
        ],
        allow: (200, 100),
        depth: 1_000,
        retract: 0,
        axis: Axis::X,
    };
    let dev = check(&pattern).unwrap_or_else(|e| panic!("{e}"));
    let t = texts_of(&dev);
    assert_eq!(t.len(), 3 * 6);
    assert_eq!(t[0], "G00 X26.4000 Z3.1000");
    assert_eq!(t[6], "G00 X23.4000 Z2.6000");
    assert_eq!(t[12], "G00 X20.4000 Z2.1000");
    assert_eq!(t[14], "G02 X28.4000 Z-8.9000 I4.0000 K0.0000");
    assert_eq!(t[17], "G00 X50.0000 Z5.0000");
}

// ---------------------------------------------------------------------------
// Random profiles.

/// Radii (0.001 mm) with many lattice points: products of primes 4k + 1.
const RADII: [i64; 8] = [325, 650, 1105, 1625, 2125, 3315, 4225, 5525];

/// The lattice points of each radius, by angle.
fn lattice() -> &'static Vec<Vec<Um>> {
    static L: OnceLock<Vec<Vec<Um>>> = OnceLock::new();
    L.get_or_init(|| {
        RADII
            .iter()
            .map(|&r| {
                let mut v = Vec::new();
                for c in -r..=r {
                    let d2 = r * r - c * c;
                    let d = (d2 as f64).sqrt().round() as i64;
                    if d * d == d2 {
                        v.push((c, d));
                        if d != 0 {
                            v.push((c, -d));
                        }
                    }
                }
                v
            })
            .collect()
    })
}

/// An element in the frame (`c`, `d`), 0.001 mm; an arc counter-clockwise
/// in (c, d) or not.
#[derive(Clone, Copy, Debug)]
struct FEl {
    end: Um,
    arc: Option<(Um, bool)>,
    /// Direction of the tangent along `d` where it is along `d`, at the
    /// start and at the end (a wall, an arc at an extreme of `c`).
    enter: Option<i64>,
    leave: Option<i64>,
}

/// Genes: (what, and three numbers).
type Gene = (u8, u32, u32, u32);

/// A profile from `a` in the frame, depths kept in `[lo, hi]`, running one
/// way along `c`; monotone in depth (shallower) unless `pockets`.
fn profile(a: Um, genes: &[Gene], lo: i64, hi: i64, pockets: bool) -> Vec<FEl> {
    let mut els: Vec<FEl> = Vec::new();
    let mut p = a;
    for &(what, x, y, z) in genes {
        let (x, y, z) = (i64::from(x), i64::from(y), i64::from(z));
        let down = pockets && y % 3 != 0;
        let leave = els.last().and_then(|e| e.leave);
        let el = match what % 4 {
            0 => Some(FEl {
                end: (p.0 + 300 + x % 6000, p.1),
                arc: None,
                enter: None,
                leave: None,
            }),
            1 => {
                let step = 300 + x % 4000;
                let d = if down {
                    (p.1 + step).min(hi)
                } else {
                    (p.1 - step).max(lo)
                };
                let s = (d - p.1).signum();
                (d != p.1 && leave.is_none()).then_some(FEl {
                    end: (p.0, d),
                    arc: None,
                    enter: Some(s),
                    leave: Some(s),
                })
            }
            2 => {
                let step = x % 5000;
                let d = if down {
                    (p.1 + step).min(hi)
                } else {
                    (p.1 - step).max(lo)
                };
                Some(FEl {
                    end: (p.0 + 300 + y % 5000, d),
                    arc: None,
                    enter: None,
                    leave: None,
                })
            }
            _ => {
                let r_i = (x % RADII.len() as i64) as usize;
                let r = RADII[r_i];
                let upper = y % 2 == 0;
                // The half (or, monotone, the quarter) run with c growing.
                let pts: Vec<Um> = lattice()[r_i]
                    .iter()
                    .copied()
                    .filter(|&(c, d)| {
                        if pockets {
                            if upper {
                                d >= 0
                            } else {
                                d <= 0
                            }
                        } else if upper {
                            c >= 0 && d >= 0
                        } else {
                            c <= 0 && d <= 0
                        }
                    })
                    .collect();
                let mut pts = pts;
                pts.sort_by_key(|v| v.0);
                let n = pts.len() as i64;
                let i = z % n;
                let rest = n - i - 1;
                if rest <= 0 {
                    None
                } else {
                    let j = i + 1 + (z / n) % rest;
                    let (v0, v1) = (pts[i as usize], pts[j as usize]);
                    let o = (p.0 - v0.0, p.1 - v0.1);
                    let end = (o.0 + v1.0, o.1 + v1.1);
                    let through = v0.0 < 0 && v1.0 > 0;
                    let deepest = if upper && through {
                        o.1 + r
                    } else {
                        p.1.max(end.1)
                    };
                    let shallowest = if !upper && through {
                        o.1 - r
                    } else {
                        p.1.min(end.1)
                    };
                    // Upper half: clockwise in (c, d), deeper at c = o.c;
                    // entering at c = o.c − r it goes deeper, leaving at
                    // o.c + r shallower. Lower half the other way.
                    let sgn = if upper { 1 } else { -1 };
                    let enter = (v0.1 == 0).then_some(sgn);
                    let el = FEl {
                        end,
                        arc: Some((o, !upper)),
                        enter,
                        leave: (v1.1 == 0).then_some(-sgn),
                    };
                    (v1.0 - v0.0 >= 100 && deepest <= hi && shallowest >= lo).then_some(el)
                }
            }
        };
        if let Some(e) = el {
            if e.end != p {
                // No wall straight back along a tangent along d.
                if !(leave.is_some() && e.enter.is_some() && leave != e.enter) {
                    p = e.end;
                    els.push(e);
                }
            }
        }
    }
    els
}

/// The parameters of a random case.
#[derive(Clone, Debug)]
struct Params {
    kind: u8,
    depth_x: bool,
    outside: bool,
    forward: bool,
    pockets: bool,
    deep: i64,
    flat: i64,
    behind: i64,
    depth: i64,
    retract: i64,
    allow: Um,
    margin: i64,
    sz: i64,
    relief: Um,
    count: u32,
}

fn params(kind: impl Strategy<Value = u8>) -> impl Strategy<Value = Params> {
    (
        (
            kind,
            any::<bool>(),
            any::<bool>(),
            any::<bool>(),
            any::<bool>(),
        ),
        (2_000i64..12_000, 1_500i64..6_000, 0i64..=500),
        (400i64..3_000, 0i64..1_000, any::<bool>()),
        (0i64..=500, 0i64..=300, 1_000i64..8_000, -5_000i64..5_000),
        (500i64..5_000, 0i64..3_000, 1u32..=6),
    )
        .prop_map(|(a, b, c, d, e)| Params {
            kind: a.0,
            depth_x: a.1,
            outside: a.2,
            forward: a.3,
            pockets: a.4,
            deep: b.0,
            flat: b.1,
            behind: b.2,
            depth: c.0,
            retract: if c.2 { c.1 } else { c.1 % 3 * 250 },
            allow: (d.0, d.1),
            margin: d.2,
            sz: d.3,
            relief: (e.0, e.1),
            count: e.2,
        })
}

/// Places a frame profile on the machine and makes the case.
fn build(p: &Params, genes: &[Gene]) -> Case {
    let g73 = p.kind == 2;
    // Frame: S at (0, 0); allowances and relief toward S (both ≥ 0 here).
    let (allow_f, relief_f) = if g73 && p.pockets {
        ((p.allow.0, 0), (p.relief.0, 0))
    } else {
        (p.allow, p.relief)
    };
    let (a, first, lo, hi) = if g73 {
        let lo = relief_f.0 + allow_f.0 + 1_000;
        let hi = lo + p.deep;
        let c0 = relief_f.1 + allow_f.1 + 500 + p.flat % 2_500;
        let d0 = if p.pockets {
            lo + (p.flat * 7) % p.deep
        } else {
            hi
        };
        ((c0, d0), None, lo, hi)
    } else {
        let a = (-p.behind, p.deep);
        let flat = FEl {
            end: (p.flat, p.deep),
            arc: None,
            enter: None,
            leave: None,
        };
        (a, Some(flat), 1_000, p.deep)
    };
    let mut els: Vec<FEl> = first.into_iter().collect();
    let from = els.last().map_or(a, |e| e.end);
    els.extend(profile(from, genes, lo, hi, p.pockets));
    if els.is_empty() {
        els.push(FEl {
            end: (a.0 + 2_000, a.1),
            arc: None,
            enter: None,
            leave: None,
        });
    }
    // A flat of the profile exactly at a pass's depth is read differently by
    // the device and the model (see `flat_at_a_pass_depth`): the depth of
    // cut is moved off every flat's depth.
    let mut depth = p.depth;
    let flats: Vec<i64> = std::iter::once(a)
        .chain(els.iter().map(|e| e.end))
        .collect::<Vec<_>>()
        .windows(2)
        .zip(&els)
        .filter(|(w, e)| e.arc.is_none() && w[0].1 == w[1].1 && w[0].0 != w[1].0)
        .map(|(w, _)| w[0].1 - allow_f.0)
        .collect();
    while flats.iter().any(|&d| d < hi - allow_f.0 && d % depth == 0) {
        depth += 1;
    }
    // The frame's signs: d grows away from S towards the stock; c along the
    // cut. Machine X a radius.
    let depth_x = if g73 { p.depth_x } else { p.kind == 0 };
    let (sd, sc) = (
        if p.outside { -1 } else { 1 },
        if p.forward { 1 } else { -1 },
    );
    let c_far = els.iter().map(|e| e.end.0).max().unwrap_or(0).max(a.0);
    let d_max = hi;
    // S: X far enough from the axis for every point to keep X ≥ 1 mm.
    let sx = if depth_x {
        if sd < 0 {
            d_max + p.margin
        } else {
            p.margin / 2
        }
    } else if sc < 0 {
        c_far + p.margin
    } else {
        p.margin / 2 + 500
    };
    let start = (sx, p.sz);
    let place = |v: Um| -> Um {
        if depth_x {
            (sx + sd * v.1, p.sz + sc * v.0)
        } else {
            (sx + sc * v.0, p.sz + sd * v.1)
        }
    };
    // Whether counter-clockwise in (c, d) is counter-clockwise in (z, x).
    let keeps = if depth_x { sc * sd > 0 } else { sc * sd < 0 };
    let toward_s = |v: Um| -> Um {
        // A frame shift toward S (−c, −d) on the machine.
        if depth_x {
            (-sd * v.0, -sc * v.1)
        } else {
            (-sc * v.1, -sd * v.0)
        }
    };
    let case_els = els
        .iter()
        .map(|e| El {
            end: place(e.end),
            arc: e.arc.map(|(o, ccw)| (place(o), ccw == keeps)),
        })
        .collect();
    Case {
        kind: match p.kind {
            0 => CaseKind::G71,
            1 => CaseKind::G72,
            _ => CaseKind::G73(toward_s(relief_f), p.count),
        },
        start,
        a: place(a),
        els: case_els,
        allow: toward_s(allow_f),
        depth,
        retract: p.retract,
        axis: if depth_x { Axis::X } else { Axis::Z },
    }
}

fn genes() -> impl Strategy<Value = Vec<Gene>> {
    prop::collection::vec(
        (any::<u8>(), any::<u32>(), any::<u32>(), any::<u32>()),
        1..10,
    )
}

fn cases(default: u32) -> Config {
    let cases = std::env::var("CYCLE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default);
    Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(cases(96))]

    /// `G71` and `G72`: turning, boring and facing either way, type I and II.
    #[test]
    fn roughing_matches_the_reference(p in params(0u8..2), g in genes()) {
        let case = build(&p, &g);
        if let Err(e) = check(&case) {
            return Err(TestCaseError::fail(e));
        }
    }
}

proptest! {
    #![proptest_config(cases(32))]

    /// `G73`: any profile that runs one way along the cut, 1 to 6 passes.
    #[test]
    fn pattern_repeating_matches_the_reference(p in params(Just(2u8)), g in genes()) {
        let case = build(&p, &g);
        if let Err(e) = check(&case) {
            return Err(TestCaseError::fail(e));
        }
    }
}

/// The checks can fail: a pass moved by 0.001 mm is not the reference's, a
/// cut 0.001 mm too deep enters the part, a pass left out leaves more than a
/// depth of cut, and a last pass off the allowances is not the profile.
#[test]
fn each_check_can_fail() {
    let case = Case {
        kind: CaseKind::G71,
        start: (15_000, 2_000),
        a: (10_000, 2_000),
        els: vec![
            line(10_000, -10_000),
            line(13_000, -15_000),
            line(13_000, -25_000),
        ],
        allow: (200, 100),
        depth: 1_500,
        retract: 500,
        axis: Axis::X,
    };
    let cycle = case.cycle();
    let (lines, first) = case.program();
    let dev = device(&lines, first).unwrap();
    let mut reference = roughing(&cycle).unwrap();
    assert!(same_moves(cycle.start, &dev, &reference).is_ok());
    // (a) The reference perturbed by 0.001 mm.
    reference[1].end.z -= 0.001;
    assert!(same_moves(cycle.start, &dev, &reference).is_err());
    // (b) The cut at X24 0.2 mm longer: 0.1 mm into the taper.
    let mut deeper = dev.clone();
    deeper[5] = Printed::parse("DATA G01 X24.0000 Z-13.1000");
    assert!(deepest_entry(&cycle, Axis::X, &deeper, true).0 < -TOL);
    let mut into = dev.clone();
    into[13] = Printed::parse("DATA G00 X20.3980 Z2.1000");
    into[14] = Printed::parse("DATA G01 X20.3980 Z-9.9000");
    assert!(deepest_entry(&cycle, Axis::X, &into, true).0 < -0.0009);
    // (c) Without the last pass (moves 8 … 11) 1.8 mm are left at the start.
    let moves = moves_of(cycle.start, &dev);
    let split = split_final_pass(&moves);
    let left = stock_left(&cycle, &moves[..split], TOL).unwrap();
    assert!(left <= cycle.depth + 1e-6);
    let fewer: Vec<Move> = moves[..8]
        .iter()
        .chain(&moves[12..split])
        .copied()
        .collect();
    assert!(stock_left(&cycle, &fewer, TOL).unwrap() > cycle.depth + 0.2);
    // (d) The last pass compared with a profile whose allowance differs.
    let off = Case {
        allow: (201, 100),
        ..case.clone()
    };
    let expected = off.moved_profile();
    let last = &dev[split..split + 3];
    assert_eq!(last.len(), expected.len());
    assert!(last
        .iter()
        .zip(&expected)
        .any(|(p, (_, end, _))| (p.x / 2.0 - end.0 as f64 / 1000.0).abs() > TOL));
    // The finishing pass the reference gives is the same as (d)'s.
    assert_eq!(finishing_pass(&cycle).len(), expected.len());
    assert_eq!(mm4(cycle.depth), "1.5000");
}

// ---------------------------------------------------------------------------
// Cases the random profiles stay clear of (no flat at a pass's depth, the
// first point the deepest and on or behind the start side's line, the first
// cut longer than the retract), where the reference first disagreed with
// the device. Two were faults of the device, fixed; two were readings of
// `docs/cycles.md` §3.2 the page left open, now settled there.

/// Runs a case that disagrees: panics with both lists while it does.
fn disagreement(case: &Case) {
    if let Err(e) = check(case) {
        panic!("{e}");
    }
}

/// A shoulder exactly at a pass's depth: S X30, A X20 (5 deep), a flat at X24
/// (3 deep, the second pass) from Z-5 to Z-10. The device cuts the pass at
/// X24 along the flat to Z-10, on the profile; docs/cycles.md §3.2 said "where
/// the profile lies deeper than `d`", which ends the cut at Z-5. The page now
/// says a flat at the pass's depth is cut along with it, and the reference
/// reads it so.
#[test]
fn flat_at_a_pass_depth() {
    disagreement(&Case {
        kind: CaseKind::G71,
        start: (15_000, 2_000),
        a: (10_000, 2_000),
        els: vec![
            line(10_000, -5_000),
            line(12_000, -5_000),
            line(12_000, -10_000),
            line(14_000, -10_000),
            line(14_000, -15_000),
        ],
        allow: (0, 0),
        depth: 1_500,
        retract: 500,
        axis: Axis::X,
    });
}

/// A cut no longer than the retract: the 45° retract ends on the start side's
/// line (X28 Z2), where the return to the start side would begin. The device
/// printed that return, `G00 X28.0000 Z2.0000`, a move of no length; moves of
/// no length are now left out (docs/cycles.md §3.2), as the reference does.
#[test]
fn return_of_no_length_after_a_retract_onto_the_start_line() {
    disagreement(&Case {
        kind: CaseKind::G71,
        start: (15_000, 2_000),
        a: (10_000, 2_000),
        els: vec![line(10_000, 1_500), line(14_000, 1_500)],
        allow: (0, 0),
        depth: 1_500,
        retract: 700,
        axis: Axis::X,
    });
}

/// A pocket deeper than the first point: S X40, A X25 (7.5 deep), a pocket
/// to X20 (10 deep). The pass at X24 has only the pocket's cut. Both the
/// device and the reference, following docs/cycles.md §3.2 as it read
/// ("after a pass with more than one cut, out to the start depth first"),
/// returned from the pocket at the depth it retracted to: `G00 X25.0000
/// Z2.0000` from Z-15.1667, a rapid through the bump at X32, inside the
/// part. Now a pass whose last cut is a pocket goes out to the start depth
/// first, and check (b) holds the rapids too. The device also printed two
/// moves of no length here.
#[test]
fn pocket_deeper_than_the_first_point() {
    disagreement(&Case {
        kind: CaseKind::G71,
        start: (20_000, 2_000),
        a: (12_500, 2_000),
        els: vec![
            line(12_500, -5_000),
            line(16_000, -8_000),
            line(10_000, -12_000),
            line(10_000, -15_000),
            line(19_000, -18_000),
        ],
        allow: (0, 0),
        depth: 2_000,
        retract: 500,
        axis: Axis::X,
    });
}

/// The first point in front of the start side: S X30 Z2, A X18 Z0 (with
/// W0.1, Z0.1), a chamfer to X20. The device cuts every pass from the start
/// side (Z2), the stock in front of A reaching A's depth; the page defined
/// the stock by the profile only, so the reference entered each pass as a
/// pocket at Z0.1, leaving what stood in front of A to the rapid to A. The
/// page now says the stock reaches A's depth in front of it.
#[test]
fn first_point_in_front_of_the_start_side() {
    disagreement(&Case {
        kind: CaseKind::G71,
        start: (15_000, 2_000),
        a: (9_000, 0),
        els: vec![
            line(10_000, -1_000),
            line(10_000, -10_000),
            line(13_000, -12_000),
        ],
        allow: (200, 100),
        depth: 1_500,
        retract: 500,
        axis: Axis::X,
    });
}

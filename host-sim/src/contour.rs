//! Compensated contours: random turning profiles, and the comparison of the
//! device's compensated blocks with the f64 reference, block by block.

use crate::link::{Reply, Transport};
use crate::scenario::nm_to_decimal;
use core_nostd::arc::ArcDir;
use core_nostd::comp::Shape;
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reference::arc::ChordCoord;
use reference::comp::{tie_margin, CompSettings, RefContour};
use reference::impulse::{RefConfig, RefMachine, TieStats};
use reference::motion::{MotionLimits, Point, RefMotion};

/// A compensated program and its tool.
#[derive(Clone, Debug, PartialEq)]
pub struct ContourCase {
    /// Nose radius, mm as written.
    pub rn: String,
    /// Tip code.
    pub tip: u8,
    /// The program: G-code blocks, diameters.
    pub lines: Vec<String>,
    /// Its feed, mm/min as written (the `F` of its start-up block).
    pub feed: String,
}

impl ContourCase {
    /// The nose radius in mm.
    pub fn rn_mm(&self) -> f64 {
        self.rn.parse().unwrap_or(0.0)
    }
}

/// Three decimals, as a programmer writes them.
fn mm3(v: f64) -> String {
    let s = format!("{v:.3}");
    if s == "-0.000" {
        "0.000".into()
    } else {
        s
    }
}

/// A random external turning profile under `G42`: a face up from near the
/// axis, then cylinders, faces up and down (grooves at least three nose
/// radii wide), tapers and arcs of either hand going towards the chuck, and
/// a `G40` retract. Elements are at least three nose radii long and concave
/// arcs at least twice the nose radius, so a well-behaved control cuts every
/// element; corner mode and tip code are random.
pub fn random_contour(rng: &mut impl Rng) -> ContourCase {
    let rn = [0.2, 0.4, 0.8, 1.2][rng.random_range(0..4usize)];
    let tip = rng.random_range(0..=9u8);
    let min = 3.0 * rn + 0.1;
    let mut lines = Vec::new();
    let mut x = rng.random_range(2.0..6.0f64);
    let mut z = 0.0f64;
    let corner = if rng.random_bool(0.5) { "G450" } else { "G451" };
    let feed = ["40", "80", "120.5", "200", "350"][rng.random_range(0..5usize)].to_string();
    lines.push(format!("G00 X{} Z{}", mm3(2.0 * x + 1.0), mm3(2.0)));
    lines.push(format!("N1 {corner} G42 G01 Z0 F{feed}"));
    x = (x + rng.random_range(min..min + 6.0)).min(40.0);
    let mut n = 2;
    lines.push(format!("N{n} X{}", mm3(2.0 * x)));
    let count = rng.random_range(4..14);
    let mut last_face = true;
    for _ in 0..count {
        n += 1;
        let kind = rng.random_range(0..5u8);
        let block = match kind {
            // Cylinder.
            0 => {
                z -= rng.random_range(min..min + 8.0);
                last_face = false;
                format!("G01 Z{}", mm3(z))
            }
            // Face up or down (not twice in a row: that is one face).
            1 if !last_face => {
                let up = x < 6.0 || rng.random_bool(0.6);
                let d = rng.random_range(min..min + 5.0);
                x = if up {
                    (x + d).min(60.0)
                } else {
                    (x - d).max(3.0)
                };
                last_face = true;
                format!("G01 X{}", mm3(2.0 * x))
            }
            // Taper.
            2 | 1 => {
                let dz = rng.random_range(min..min + 6.0);
                let dx = rng.random_range(0.5..5.0)
                    * if x < 8.0 || rng.random_bool(0.6) {
                        1.0
                    } else {
                        -1.0
                    };
                x = (x + dx).clamp(3.0, 60.0);
                z -= dz;
                last_face = false;
                format!("G01 X{} Z{}", mm3(2.0 * x), mm3(z))
            }
            // Arc of either hand, at most about 84°, R form or I/K form,
            // never turning back towards +Z (the part stays turnable).
            _ => {
                let dz = rng.random_range(min..min + 5.0);
                let dx = rng.random_range(0.5..4.0)
                    * if x < 8.0 || rng.random_bool(0.6) {
                        1.0
                    } else {
                        -1.0
                    };
                let (x1, z1) = ((x + dx).clamp(3.0, 60.0), z - dz);
                let chord = ((x1 - x).powi(2) + (z1 - z).powi(2)).sqrt();
                let r = (chord * rng.random_range(0.75..3.0)).max(2.0 * rn + 0.2);
                let h = (r * r - chord * chord / 4.0).max(0.0).sqrt();
                let (mx, mz) = ((x + x1) / 2.0, (z + z1) / 2.0);
                let (ux, uz) = ((x1 - x) / chord, (z1 - z) / chord);
                // The centre of the short arc: left of the chord for G03,
                // (−ux, uz) as (z, x) in the (Z, X) plane.
                let centre = |ccw: bool| {
                    let s = if ccw { 1.0 } else { -1.0 };
                    (mx + s * uz * h, mz - s * ux * h)
                };
                // Z never increases along the arc when both end tangents
                // point towards −Z: x ≥ centre for G03, ≤ for G02.
                let monotone = |ccw: bool| {
                    let (cx, _) = centre(ccw);
                    if ccw {
                        x >= cx && x1 >= cx
                    } else {
                        x <= cx && x1 <= cx
                    }
                };
                let first = rng.random_bool(0.5);
                let hand = [first, !first].into_iter().find(|&c| monotone(c));
                let g = |ccw: bool| if ccw { "G03" } else { "G02" };
                last_face = false;
                match hand {
                    // Neither hand keeps Z from increasing: a taper instead.
                    None => {
                        x = x1;
                        z = z1;
                        format!("G01 X{} Z{}", mm3(2.0 * x1), mm3(z1))
                    }
                    Some(ccw) if rng.random_bool(0.5) => {
                        x = x1;
                        z = z1;
                        format!("{} X{} Z{} R{}", g(ccw), mm3(2.0 * x1), mm3(z1), mm3(r))
                    }
                    Some(ccw) => {
                        // The centre to three decimals, and the end point moved
                        // onto the circle about it.
                        let (cx, cz) = centre(ccw);
                        let (ci, ck) = (
                            (cx * 1000.0).round() / 1000.0 - x,
                            (cz * 1000.0).round() / 1000.0 - z,
                        );
                        let (ccx, ccz) = (x + ci, z + ck);
                        let rr = (ci * ci + ck * ck).sqrt();
                        let (ex, ez) = (x1 - ccx, z1 - ccz);
                        let el = (ex * ex + ez * ez).sqrt();
                        let (ex1, ez1) = (ccx + ex * rr / el, ccz + ez * rr / el);
                        let (ex1, ez1) = (
                            (ex1 * 2000.0).round() / 2000.0,
                            (ez1 * 1000.0).round() / 1000.0,
                        );
                        x = ex1;
                        z = ez1;
                        format!(
                            "{} X{} Z{} I{} K{}",
                            g(ccw),
                            mm3(2.0 * ex1),
                            mm3(ez1),
                            mm3(ci),
                            mm3(ck)
                        )
                    }
                }
            }
        };
        lines.push(format!("N{n} {block}"));
        // Keep the programmed point what the words say (3 decimals).
        x = (2.0 * x * 1000.0).round() / 2000.0;
        z = (z * 1000.0).round() / 1000.0;
    }
    n += 1;
    lines.push(format!(
        "N{n} G01 Z{}",
        mm3(z - rng.random_range(min..min + 4.0))
    ));
    lines.push(format!("N{} G40 G00 X{}", n + 1, mm3(2.0 * x + 10.0)));
    ContourCase {
        rn: format!("{rn}"),
        tip,
        lines,
        feed,
    }
}

/// The outcome of comparing contours.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContourTally {
    /// Programs run.
    pub programs: usize,
    /// Blocks sent to the device.
    pub blocks: usize,
    /// Compensated blocks compared (DATA lines).
    pub compared: usize,
    /// Blocks both refused, with the same error code.
    pub refused_alike: usize,
    /// Printed values within 10⁻⁶ mm of a printing tie that printed
    /// differently (excused).
    pub near_ties: usize,
    /// The smallest distance to a printing tie among the compared blocks, mm.
    pub closest_tie_mm: f64,
    /// Position registers after a request checked against `Q(P/h)` of the
    /// reference's tool-tip point.
    pub positions: usize,
    /// Of those that differ, the point within 10⁻³ of a 10⁻⁷ mm rounding
    /// tie (excused).
    pub position_near_ties: usize,
    /// Disagreements, described.
    pub mismatches: Vec<String>,
    /// Step events whose ticks were compared (`SYNC` after each program).
    pub timed: u64,
    /// Rounding decisions of their ticks.
    pub ticks: TieStats,
}

/// Runs `case` on the device behind `link` and on the f64 reference; adds
/// the comparison to `tally`. The device is set up with `CFG` first and
/// left with compensation off.
pub fn compare_contour<T: Transport>(
    link: &mut T,
    case: &ContourCase,
    tally: &mut ContourTally,
) -> Result<(), crate::link::LinkError> {
    if tally.programs == 0 {
        tally.closest_tie_mm = f64::INFINITY;
        tally.ticks = TieStats::new();
    }
    tally.programs += 1;
    // Whatever ran before is not this program's.
    link.request("SYNC")?;
    let cfg = link.request(&format!(
        "CFG HX=0.005 HZ=0.01 DIAM=1 RN={} TIP={}",
        case.rn, case.tip
    ))?;
    if !cfg.is_ok() {
        tally.mismatches.push(format!("CFG refused: {}", cfg.last));
        return Ok(());
    }
    // Both start at the program zero, in the power-on modal state.
    link.request("RESET")?;
    link.request("ZERO")?;
    let mut motion = RefMotion::new(MotionLimits::default(), [0.005, 0.01]);
    // The compensated points to time, exactly (10⁻⁷ mm): those of the
    // core's contour engine, in a device of its own. They are the points the
    // device printed, which the contour reference checks to the printed
    // 10⁻⁴ mm above; what is compared here is their timing.
    let mut shadow = crate::device::LocalDevice::new();
    for l in [
        format!(
            "CFG HX=0.005 HZ=0.01 DIAM=1 TOL=0.01 PASS=FIN RN={} TIP={}",
            case.rn, case.tip
        ),
        "ZERO".into(),
    ] {
        shadow.request(&l);
    }
    run_contour(link, case, tally, &mut motion, &mut shadow)?;
    // Everything the program queued runs: its events and ticks.
    let dev = link.request("SYNC")?;
    let r = motion.sync();
    tally.timed += r.ev;
    let t = motion.ties();
    tally.ticks.exact_ties += t.exact_ties;
    tally.ticks.min_distance = tally.ticks.min_distance.min(t.min_distance);
    let want = format!("OK EV={} T={} TSEQ={:08X} STARVED=0", r.ev, r.t, r.tseq);
    if dev.last != want {
        tally.mismatches.push(format!(
            "SYNC after {}: device {}, reference {want}",
            case.lines.first().map_or("", String::as_str),
            dev.last
        ));
    }
    Ok(())
}

/// `Q(u/h)` of a coordinate in 10⁻⁷ mm.
fn q(u: i64, h: i64) -> i64 {
    let m = u.abs() / h + i64::from(2 * (u.abs() % h) >= h);
    if u < 0 {
        -m
    } else {
        m
    }
}

/// Queues a compensated block on the motion reference: the line from
/// `from` to `to`, or the chords of the arc about `centre` (10⁻⁷ mm, X
/// radius), cut as `docs/arcs.md` §1 says with the session's tolerance (0.01 mm,
/// finishing). The chords come from the reference's arc machine run at ten
/// times scale, where the 10⁻⁷ mm grid of compensated points is its
/// nanometre grid of words (Δφ, the chord count and `Q(P/h)` do not change
/// with the scale).
pub fn push_block(
    motion: &mut RefMotion,
    from: [i64; 2],
    to: [i64; 2],
    arc: Option<([i64; 2], bool)>,
    feed: Option<f64>,
) {
    let line = |motion: &mut RefMotion| {
        motion.push(
            Point::from_units(to[0], to[1]),
            [q(to[0], 50_000), q(to[1], 100_000)],
            feed,
        )
    };
    let Some((centre, ccw)) = arc else {
        return line(motion);
    };
    let mut m = RefMachine::scaled(
        RefConfig {
            hx_mm: 0.05,
            hz_mm: 0.1,
            diam: false,
        },
        10,
    );
    let w = nm_to_decimal;
    m.move_block(Some(&w(from[0])), Some(&w(from[1])), false);
    let (mut px, mut pz) = m.position();
    let chords = m.arc(
        &w(to[0]),
        &w(to[1]),
        &w(centre[0] - from[0]),
        &w(centre[1] - from[1]),
        ccw,
        "0.1",
        false,
    );
    let Ok(a) = chords else {
        // Refused here as on the device (the comparison of blocks says so).
        return line(motion);
    };
    for (end, &(nx, nz)) in a.ends.iter().zip(&a.chords) {
        (px, pz) = (px + nx, pz + nz);
        // Scaled quarter- and half-nanometres are quarter and half units.
        let c = |c: ChordCoord| match c {
            ChordCoord::Exact(v) => (v.div_euclid(4) as i64, [v.rem_euclid(4) as f64 / 4.0, 0.0]),
            ChordCoord::OnCircle { centre, offset } => (
                centre.div_euclid(2),
                [
                    centre.rem_euclid(2) as f64 / 2.0 + offset[0] / 2.0,
                    offset[1] / 2.0,
                ],
            ),
        };
        // Timed on the 10⁻⁷ mm grid (`docs/motion.md`).
        let (point, _) = Point::grid_rounded(c(end[0]), c(end[1]));
        motion.push(point, [px, pz], feed);
    }
}

fn run_contour<T: Transport>(
    link: &mut T,
    case: &ContourCase,
    tally: &mut ContourTally,
    motion: &mut RefMotion,
    shadow: &mut crate::device::LocalDevice,
) -> Result<(), crate::link::LinkError> {
    let feed: f64 = case.feed.parse().unwrap_or(f64::NAN);
    let at = &mut [0i64, 0];
    let mut reference = RefContour::new(CompSettings {
        rn_mm: case.rn_mm(),
        tip: case.tip,
        diam: true,
    });
    let mut from = (0.0, 0.0);
    for line in &case.lines {
        tally.blocks += 1;
        let dev: Reply = link.request(line)?;
        let refr = reference.block(line);
        shadow.request(line);
        let exact = shadow.device().session().last_moves().clone();
        match (dev.is_ok(), refr) {
            (true, Ok(blocks)) => {
                let data: Vec<&str> = dev
                    .data
                    .iter()
                    .map(|l| l.strip_prefix("DATA ").unwrap_or(l))
                    .collect();
                if data.len() != blocks.len() {
                    tally.mismatches.push(format!(
                        "{line}: device sent {data:?}, reference {} blocks",
                        blocks.len()
                    ));
                    return Ok(());
                }
                for ((d, b), m) in data.iter().zip(&blocks).zip(&exact) {
                    tally.compared += 1;
                    let speed = (b.motion.word() != "G00").then_some(feed);
                    let arc = match m.kind {
                        Shape::Arc { centre, dir } => Some((centre, dir == ArcDir::Ccw)),
                        Shape::Line { .. } => None,
                    };
                    push_block(motion, *at, m.to, arc, speed);
                    *at = m.to;
                    let margin = tie_margin(b, from, true);
                    tally.closest_tie_mm = tally.closest_tie_mm.min(margin);
                    let want = b.text(from, true);
                    if *d != want {
                        if margin < 1e-6 {
                            tally.near_ties += 1;
                        } else {
                            tally
                                .mismatches
                                .push(format!("{line}: device {d}, reference {want}"));
                        }
                    }
                    from = b.end();
                }
                // The registers hold Q(P/h) of the tool tip's point, P on
                // the 10⁻⁷ mm grid (docs/compensation.md), in integers.
                let (px, pz) = (dev.value("PX"), dev.value("PZ"));
                for (reg, p, h) in [(px, from.0, 50_000i64), (pz, from.1, 100_000)] {
                    let units = p * 1e7;
                    let a = units.round() as i64;
                    let q = a.abs() / h + i64::from(2 * (a.abs() % h) >= h);
                    let want = if a < 0 { -q } else { q };
                    tally.positions += 1;
                    if reg.and_then(|v| v.parse::<i64>().ok()) != Some(want) {
                        if ((units - units.floor()) - 0.5).abs() < 1e-3 {
                            tally.position_near_ties += 1;
                        } else {
                            tally.mismatches.push(format!(
                                "{line}: device {}, reference register {want}",
                                dev.last
                            ));
                        }
                    }
                }
            }
            (false, Err(e)) => {
                let code = dev.last.split_whitespace().nth(1).unwrap_or("");
                if code == e.kind.code() {
                    tally.refused_alike += 1;
                } else {
                    tally
                        .mismatches
                        .push(format!("{line}: device {}, reference {e}", dev.last));
                }
                // Both refused and changed nothing; the rest of this program
                // would only repeat the refusal at the next corner. The
                // waiting element cannot be finished: abandon the program.
                let reset = link.request("RESET")?;
                if !reset.is_ok() {
                    tally.mismatches.push(format!("RESET: {}", reset.last));
                }
                motion.flush();
                return Ok(());
            }
            (true, Err(e)) => {
                tally.mismatches.push(format!(
                    "{line}: device {}, reference refused: {e}",
                    dev.last
                ));
                return Ok(());
            }
            (false, Ok(_)) => {
                tally
                    .mismatches
                    .push(format!("{line}: device {}, reference accepted", dev.last));
                return Ok(());
            }
        }
    }
    Ok(())
}

/// `count` random contours from `seed`.
pub fn random_contours(seed: u64, count: usize) -> Vec<ContourCase> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count).map(|_| random_contour(&mut rng)).collect()
}

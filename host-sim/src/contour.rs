//! Compensated contours: random turning profiles, and the comparison of the
//! device's compensated blocks with the f64 reference, block by block.

use crate::link::{Reply, Transport};
use crate::reference_comp::{tie_margin, CompSettings, RefContour};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A compensated program and its tool.
#[derive(Clone, Debug, PartialEq)]
pub struct ContourCase {
    /// Nose radius, mm as written.
    pub rn: String,
    /// Tip code.
    pub tip: u8,
    /// The program: G-code blocks, diameters.
    pub lines: Vec<String>,
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
    lines.push(format!("G00 X{} Z{}", mm3(2.0 * x + 1.0), mm3(2.0)));
    lines.push(format!("N1 {corner} G42 G01 Z0"));
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
    }
    tally.programs += 1;
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
    link.request("G00 X0 Z0")?;
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
                for (d, b) in data.iter().zip(&blocks) {
                    tally.compared += 1;
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

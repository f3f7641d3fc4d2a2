//! `host-sim run FILE --report`: the HTML page of a run. Its picture is
//! the plot's, drawn where the program's points are; its speed chart,
//! read back through its own axis labels, stays within the commanded feed
//! and the rapid limits of `docs/motion.md` and reaches the feed on a long
//! straight move; its cycle time is `run`'s; a refused line is listed with
//! the device's reason.

use core_nostd::gcode::Dialect;
use host_sim::plot;
use host_sim::program::{self, minutes, Options};
use host_sim::report;

const FANUC: Options = Options {
    dialect: Dialect::Fanuc,
    radius: false,
    optional_stop: false,
};

/// Line 6 is a long straight feed (85 mm at F600), line 7 a 1 s dwell,
/// line 8 a feed across at F120, line 9 refused.
const PROGRAM: &str = "%\nO0100\nG21 G18 G98\nT0101\nG00 X20. Z5.\nG01 Z-80. F600.\n\
                       G04 P1000\nG01 X30. F120.\nG76 P010060 Q100 R.05\nG00 X40. Z5.\nM30\n%\n";

/// The points the program's blocks end on, (Z, X radius) mm, from the
/// power-on position.
const POINTS: [(f64, f64); 5] = [
    (0.0, 0.0),
    (5.0, 10.0),
    (-80.0, 10.0),
    (-80.0, 15.0),
    (5.0, 20.0),
];

/// `docs/motion.md`'s default rapid rates, mm/min: X (radius), Z.
const VX: f64 = 1500.0;
const VZ: f64 = 3000.0;

/// How far a sample may stand off its limit: one tick in a window of 200
/// (an interval at the rapid rate), and a pixel's rounding of the chart.
const TOL: f64 = 0.01;

/// The value of attribute `name` in an element's text.
fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let at = element.find(&key)? + key.len();
    let len = element[at..].find('"')?;
    Some(&element[at..at + len])
}

/// The SVG between `<figure id="{id}">` and its end.
fn figure<'a>(html: &'a str, id: &str) -> &'a str {
    let open = format!("<figure id=\"{id}\">");
    let at = html.find(&open).unwrap_or_else(|| panic!("no figure {id}")) + open.len();
    let len = html[at..].find("</figure>").unwrap();
    html[at..at + len].trim_start()
}

/// The polylines of a layer, in document order, their points in user
/// units.
fn polylines(svg: &str, layer: &str) -> Vec<Vec<(f64, f64)>> {
    svg.lines()
        .filter(|l| l.starts_with("<polyline ") && attr(l, "data-layer") == Some(layer))
        .map(|l| {
            attr(l, "points")
                .unwrap()
                .split(' ')
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

/// A chart's mapping read from its tick labels: numbers anchored in the
/// middle are the time axis (their x), numbers anchored at the end the
/// speed axis (their baseline 0.26 em below the tick).
struct Axes {
    t: (f64, f64),
    v: (f64, f64),
}

impl Axes {
    fn read(svg: &str) -> Axes {
        let mut t: Vec<(f64, f64)> = Vec::new();
        let mut v: Vec<(f64, f64)> = Vec::new();
        for l in svg.lines().filter(|l| l.starts_with("<text ")) {
            let content = &l[l.find('>').unwrap() + 1..l.rfind("</text>").unwrap()];
            let Ok(value) = content.parse::<f64>() else {
                continue;
            };
            let x: f64 = attr(l, "x").unwrap().parse().unwrap();
            let y: f64 = attr(l, "y").unwrap().parse().unwrap();
            let size: f64 = attr(l, "font-size").unwrap().parse().unwrap();
            match attr(l, "text-anchor") {
                Some("middle") => t.push((value, x)),
                Some("end") => v.push((value, y - (0.26 * size).round())),
                _ => {}
            }
        }
        assert!(t.len() >= 2 && v.len() >= 2, "axis labels: {t:?} {v:?}");
        let line = |p: &[(f64, f64)]| {
            let (a, b) = (p[0], p[p.len() - 1]);
            let per = (b.1 - a.1) / (b.0 - a.0);
            (a.0, a.1, per)
        };
        let (t0, x0, tp) = line(&t);
        let (v0, y0, vp) = line(&v);
        Axes {
            t: (x0 - t0 * tp, tp),
            v: (y0 - v0 * vp, vp),
        }
    }

    /// (s, mm/min) of a point in user units.
    fn at(&self, (x, y): (f64, f64)) -> (f64, f64) {
        ((x - self.t.0) / self.t.1, (y - self.v.0) / self.v.1)
    }

    /// Half a user unit, in mm/min.
    fn v_unit(&self) -> f64 {
        0.5 / self.v.1.abs()
    }

    fn t_unit(&self) -> f64 {
        0.5 / self.t.1.abs()
    }
}

fn build(text: &str) -> (String, program::Report) {
    report::build("part.nc", text, FANUC, &[], "").unwrap()
}

#[test]
fn the_page_holds_the_plot_of_the_programs_path() {
    let (html, _) = build(PROGRAM);
    // The picture `host-sim plot` draws, as it is.
    let paths = plot::trace(
        PROGRAM,
        &plot::Options {
            program: FANUC,
            zoom: None,
        },
        &[],
    );
    let picture = plot::render(&paths, "part.nc", None).unwrap();
    let svg = figure(&html, "plot");
    assert_eq!(svg, picture.svg);
    // Every vertex of the tool tip is one of the program's points, and
    // every point is drawn.
    let tr = picture.transform;
    let tol = 0.75 / tr.scale;
    let mut seen = [false; POINTS.len()];
    let mut vertices = 0;
    for layer in ["tip feed", "tip rapid"] {
        for line in polylines(svg, layer) {
            for p in line {
                let (z, r) = tr.to_mm(p.0, p.1);
                let i = POINTS
                    .iter()
                    .position(|q| (q.0 - z).abs() <= tol && (q.1 - r).abs() <= tol)
                    .unwrap_or_else(|| {
                        panic!(
                            "{layer} vertex Z{z} X{} is no point of the program",
                            2.0 * r
                        )
                    });
                seen[i] = true;
                vertices += 1;
            }
        }
    }
    assert!(vertices >= POINTS.len());
    assert_eq!(seen, [true; POINTS.len()]);
    // Rapids dashed, feeds solid.
    let dashed = |layer: &str| {
        svg.lines()
            .filter(|l| l.starts_with("<polyline ") && attr(l, "data-layer") == Some(layer))
            .all(|l| attr(l, "stroke-dasharray").is_some())
    };
    assert!(dashed("tip rapid") && !dashed("tip feed"));
}

/// The rapid limit of a straight move along the path (mm/min):
/// `min VMAX_a / |u_a|` over the axes that move (`docs/motion.md`).
fn rapid_limit(a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dz, dx) = (b.0 - a.0, b.1 - a.1);
    let l = dz.hypot(dx);
    let mut v = f64::INFINITY;
    if dx != 0.0 {
        v = v.min(VX * l / dx.abs());
    }
    if dz != 0.0 {
        v = v.min(VZ * l / dz.abs());
    }
    v
}

#[test]
fn the_speed_stays_within_the_limits_and_reaches_the_feed() {
    let (html, _) = build(PROGRAM);
    // The feeds on their own scale (the rapids are five times faster).
    let feeds = figure(&html, "speed-2");
    let axes = Axes::read(feeds);
    let lines: Vec<Vec<(f64, f64)>> = polylines(feeds, "speed feed")
        .into_iter()
        .map(|l| l.into_iter().map(|p| axes.at(p)).collect())
        .collect();
    assert_eq!(lines.len(), 2, "{lines:?}");
    let slack = |f: f64| f * TOL + axes.v_unit();
    for (line, f, length, accel) in [
        // 85 mm along Z at 600 mm/min; 5 mm on the radius at 120 mm/min.
        (&lines[0], 600.0, 85.0, 150.0),
        (&lines[1], 120.0, 5.0, 100.0),
    ] {
        let top = line.iter().map(|p| p.1).fold(0.0, f64::max);
        assert!(top <= f + slack(f), "F{f}: {top} mm/min");
        assert!(top >= f - slack(f), "F{f} not reached: {top} mm/min");
        assert!(line.iter().all(|p| p.1 >= -axes.v_unit()));
        // The move at F with its ramps: L/F plus v/a (half of each ramp's
        // time lost), from rest to rest; the line starts at its first
        // sample, two impulses (0.02 mm) from rest: 16 ms in.
        let span = line[line.len() - 1].0 - line[0].0;
        let v = f / 60.0;
        let expected = length / v + v / accel;
        assert!(
            (span - expected).abs() <= 0.02 + 2.0 * axes.t_unit(),
            "F{f}: {span} s, expected {expected} s"
        );
    }
    // The commanded feeds are drawn where their moves ran.
    let commanded: Vec<f64> = polylines(feeds, "commanded")
        .iter()
        .map(|l| axes.at(l[0]).1)
        .collect();
    assert_eq!(commanded.len(), 2, "{commanded:?}");
    assert!((commanded[0] - 600.0).abs() <= axes.v_unit() * 2.0);
    assert!((commanded[1] - 120.0).abs() <= axes.v_unit() * 2.0);
    // The dwell: 1 s at zero speed, between the two feeds.
    let dwell: Vec<(f64, f64)> = polylines(feeds, "dwell")
        .concat()
        .into_iter()
        .map(|p| axes.at(p))
        .collect();
    assert_eq!(dwell.len(), 2, "{dwell:?}");
    assert!((dwell[1].0 - dwell[0].0 - 1.0).abs() <= 2.0 * axes.t_unit());
    assert!(dwell.iter().all(|p| p.1.abs() <= axes.v_unit()));
    assert!(dwell[0].0 >= lines[0][lines[0].len() - 1].0 - 2.0 * axes.t_unit());
    assert!(dwell[1].0 <= lines[1][0].0 + 2.0 * axes.t_unit());

    // The rapids on the whole scale: each within its block's limit, the
    // long one along Z at its cruise.
    let all = figure(&html, "speed-1");
    let axes = Axes::read(all);
    let rapids: Vec<Vec<(f64, f64)>> = polylines(all, "speed rapid")
        .into_iter()
        .map(|l| l.into_iter().map(|p| axes.at(p)).collect())
        .collect();
    assert_eq!(rapids.len(), 2, "{rapids:?}");
    for (line, (a, b)) in rapids
        .iter()
        .zip([(POINTS[0], POINTS[1]), (POINTS[3], POINTS[4])])
    {
        let limit = rapid_limit(a, b);
        let top = line.iter().map(|p| p.1).fold(0.0, f64::max);
        assert!(
            top <= limit * (1.0 + TOL) + axes.v_unit(),
            "{top} > {limit}"
        );
        if a.0 - b.0 > 50.0 || b.0 - a.0 > 50.0 {
            assert!(
                top >= limit * (1.0 - TOL) - axes.v_unit(),
                "{top} < {limit}"
            );
        }
    }
    // Nothing in the chart is faster than the fastest rapid allows.
    let any = polylines(all, "speed feed")
        .concat()
        .into_iter()
        .map(|p| axes.at(p).1)
        .fold(0.0, f64::max);
    assert!(any <= 600.0 * (1.0 + TOL) + axes.v_unit());
}

#[test]
fn the_page_states_runs_facts_and_refusals() {
    let (html, report) = build(PROGRAM);
    // What `run` prints comes from this run.
    let run = program::run_setup(PROGRAM, FANUC, &[]);
    assert_eq!(report, run);
    let cycle = format!("<span id=\"cycle-time\">{}</span>", minutes(run.cycle_us()));
    assert!(html.contains(&cycle), "{cycle}");
    // The cycle: 85 mm at F600 and 5 mm at F120 take 11 s, the dwell 1 s,
    // the rapids at their limits 2.1 s (11.18 mm at 1677 mm/min, 85.15 mm
    // at 3005), and the ramps at most 0.7 s more (v/a per move).
    let rapids = 60.0
        * (125f64.sqrt() / rapid_limit(POINTS[0], POINTS[1])
            + 7250f64.sqrt() / rapid_limit(POINTS[3], POINTS[4]));
    let least = 12.0 + rapids;
    let cycle = run.cycle_us() as f64 / 1e6;
    assert!(cycle > least && cycle < least + 0.7, "{cycle} s");
    assert!(html.contains("<tr><th>dwelling</th><td class=\"n\">0:01.000</td></tr>"));
    assert!(html.contains(&format!("<td class=\"n\">{}</td>", run.events)));
    assert!(
        html.contains("<td class=\"n\">90.000 mm</td>"),
        "travel at feed"
    );
    // The refused line, with its number and the device's reason.
    assert!(
        html.contains(
            "<tr><td>part.nc</td><td class=\"n\">9</td><td>ERR VALUE G76 canned cycles not supported</td></tr>"
        ),
        "{html}"
    );
    assert!(html.contains("The device refused 1 line"));
    // The tool and its line.
    assert!(html.contains("<tr><td class=\"n\">4</td><td>T0101</td></tr>"));
    // Self-contained: nothing fetched, nothing run.
    for outside in ["<script", " src=", "<link", "url(", "http://", "https://"] {
        let inside_svg_ns = outside == "http://" && {
            html.matches("http://").count() == html.matches("http://www.w3.org/2000/svg").count()
        };
        assert!(!html.contains(outside) || inside_svg_ns, "{outside}");
    }
}

#[test]
fn the_examples_pages_agree_with_run() {
    for (name, text, feeds) in [
        (
            "krylenko-fig22",
            include_str!("../../examples/krylenko-fig22.nc"),
            // G96 S120 with G50 S2500 and F0.1 per revolution: at most
            // 2500 rpm, 250 mm/min.
            250.0,
        ),
        (
            "fanuc-grooves",
            include_str!("../../examples/fanuc-grooves.nc"),
            200.0,
        ),
    ] {
        let (html, report) = build(text);
        let run = program::run_setup(text, FANUC, &[]);
        assert_eq!(report.cycle_us(), run.cycle_us(), "{name}");
        assert!(html.contains(&format!(
            "<span id=\"cycle-time\">{}</span>",
            minutes(run.cycle_us())
        )));
        let all = figure(&html, "speed-1");
        let axes = Axes::read(all);
        let top = polylines(all, "speed feed")
            .concat()
            .into_iter()
            .map(|p| axes.at(p).1)
            .fold(0.0, f64::max);
        assert!(top <= feeds * (1.0 + TOL) + axes.v_unit(), "{name}: {top}");
        assert!(top >= feeds * (1.0 - TOL) - axes.v_unit(), "{name}: {top}");
    }
}

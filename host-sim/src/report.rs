//! `host-sim run FILE --report OUT.html`: one self-contained HTML page of
//! what running a program comes to, for reading before cutting: the facts
//! `run` prints as tables (cycle time, travel, step events, tools, program
//! stops, refused lines with the device's reason), the picture of
//! `host-sim plot`, and the speed along the path over time.
//!
//! The speed chart is read from the device's own timing: the blocks it
//! started and every step event with its tick ([`program::run_timed`]).
//! Within a block the events are one impulse of its lead axis apart
//! (`docs/motion.md`, step event times), so the path between two of them
//! is `h_lead / |u_lead|` long, `u` the block's direction: exact for a line
//! (its commanded ends), the arc's tangent at the chord's middle for a
//! chord. The speed of a window of events is that length times their
//! number over the ticks between the first and the last (1 MHz clock): a
//! block's first and last interval on their own (the speeds at its
//! junctions), the windows between them at least [`MIN_WINDOW_S`] long.
//! A tick's rounding moves a sample by one tick over its window: under
//! 0.05 % for a whole window, under 0.5 % for one interval (the axes'
//! default rapid rates give 5000 events a second, 200 ticks apart). Runs start and end at
//! rest; a dwell (`G04`, or the spindle getting up to speed) is a stretch
//! of zero speed; the time axis is the cycle time `run` prints (a program
//! stop's wait for cycle start is not in it).
//!
//! Each block of the path is matched to the program's block it comes from
//! (a line is one block; an arc's chords run up to the one that ends on the
//! arc's end impulse), which says whether it is a rapid and its commanded
//! feed. The page needs no script and no file besides itself.

use crate::plot::{
    self, bold, clipped, decimals, font, k, ki, label, multiples, nice_step, Axis, Canvas,
    PlotError, Rect, CENTRE, DASH, MARGIN, PANEL, STEPS, TIP, WIDTH, X_LABELS, Y_LABELS,
};
use crate::program::{self, div_round, minutes, Happening, Report, Timeline, Traced};
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, Pos, VPos};
use std::fmt::Write as _;

/// The shortest window of step events a speed sample is taken over, s
/// (longer for long programs: about 3000 windows over the cycle).
pub const MIN_WINDOW_S: f64 = 0.002;

/// A stretch of the speed chart drawn in one style: a rapid or a feed.
#[derive(Clone, Debug, PartialEq)]
pub struct Stretch {
    /// A `G00` rapid (else a feed).
    pub rapid: bool,
    /// (time s, speed mm/min), time increasing.
    pub points: Vec<(f64, f64)>,
}

/// The speed along the path over the cycle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Speeds {
    /// The speed, stretch by stretch.
    pub stretches: Vec<Stretch>,
    /// Dwells: from, to (s).
    pub dwells: Vec<[f64; 2]>,
    /// The commanded feed (mm/min) over the time its blocks ran (s).
    pub commanded: Vec<([f64; 2], f64)>,
    /// The end of the cycle, s.
    pub end: f64,
    /// The window the samples are taken over, s.
    pub window: f64,
}

impl Speeds {
    /// The fastest sample of the rapids, and of the feeds, mm/min.
    pub fn peaks(&self) -> [f64; 2] {
        let mut peak = [0.0f64; 2];
        for s in &self.stretches {
            let i = usize::from(!s.rapid);
            for (_, v) in &s.points {
                peak[i] = peak[i].max(*v);
            }
        }
        peak
    }
}

/// A program block as the speed chart needs it.
struct Element {
    from: [i64; 2],
    to: [i64; 2],
    centre: Option<[i64; 2]>,
    rapid: bool,
    feed: Option<f64>,
    /// The end in impulses (X on the radius, Z).
    end: [i64; 2],
}

fn elements(path: &[Traced], feeds: &[Option<f64>], price: [i64; 2]) -> Vec<Element> {
    let mut at = [0i64; 2];
    path.iter()
        .enumerate()
        .map(|(i, t)| {
            let e = Element {
                from: at,
                to: t.to,
                centre: t.centre,
                rapid: t.g == 0,
                feed: feeds.get(i).copied().flatten(),
                end: [div_round(t.to[0], price[0]), div_round(t.to[1], price[1])],
            };
            at = t.to;
            e
        })
        .collect()
}

/// The step events of one block, being gathered.
struct Open {
    rapid: bool,
    /// Path length per event, mm.
    ds: f64,
    ticks: Vec<u64>,
    /// The program block it belongs to, if known.
    element: Option<usize>,
}

/// Builds the speed chart's data from a timed run.
pub fn speeds(report: &Report, timeline: &Timeline) -> Speeds {
    let price = timeline.price;
    let els = elements(&report.path, &timeline.feeds, price);
    let total_s = report.cycle_us() as f64 / 1e6;
    let window = MIN_WINDOW_S.max(total_s / 3000.0);
    let w_ticks = (window * 1e6).round() as u64;
    let mut out = Speeds {
        window,
        end: total_s,
        ..Speeds::default()
    };
    // Element being run, and whether the run has drawn anything yet.
    let mut next = 0usize;
    let mut run_start = 0.0f64;
    let mut fresh_run = true;
    let mut open: Option<Open> = None;
    let mut current: Option<Stretch> = None;
    // When each element's events ran: first, last (s).
    let mut spans: Vec<Option<[f64; 2]>> = vec![None; els.len()];

    let finish = |open: Option<Open>,
                  current: &mut Option<Stretch>,
                  stretches: &mut Vec<Stretch>,
                  spans: &mut Vec<Option<[f64; 2]>>,
                  run_start: f64,
                  fresh_run: &mut bool| {
        let Some(b) = open else { return };
        let t = |tick: u64| run_start + tick as f64 / 1e6;
        if let (Some(e), Some(first), Some(last)) = (b.element, b.ticks.first(), b.ticks.last()) {
            let s = spans[e].get_or_insert([t(*first), t(*last)]);
            s[1] = t(*last);
        }
        // The first and the last interval on their own (the speed the
        // block starts and ends with: its junctions), windows of at least
        // `w_ticks` between them, a short tail joined to the one before.
        let n = b.ticks.len();
        let mut windows: Vec<(usize, usize)> = Vec::new();
        if n >= 2 {
            windows.push((0, 1));
        }
        if n >= 4 {
            let mut s = 1;
            let mut middle: Vec<(usize, usize)> = Vec::new();
            for i in 2..=n - 2 {
                if b.ticks[i] - b.ticks[s] >= w_ticks {
                    middle.push((s, i));
                    s = i;
                }
            }
            if s < n - 2 {
                match middle.last_mut() {
                    Some(w) => w.1 = n - 2,
                    None => middle.push((s, n - 2)),
                }
            }
            windows.extend(middle);
        }
        if n >= 3 {
            windows.push((n - 2, n - 1));
        }
        let samples: Vec<(f64, f64)> = windows
            .iter()
            .filter(|(a, e)| b.ticks[*e] > b.ticks[*a])
            .map(|&(a, e)| {
                let dt = (b.ticks[e] - b.ticks[a]) as f64 / 1e6;
                let v = (e - a) as f64 * b.ds / dt * 60.0;
                (t((b.ticks[a] + b.ticks[e]) / 2), v)
            })
            .collect();
        if samples.is_empty() {
            return;
        }
        match current {
            Some(c) if c.rapid == b.rapid => c.points.extend(samples),
            _ => {
                let mut points = Vec::new();
                if *fresh_run {
                    points.push((run_start, 0.0));
                }
                if let Some(mut c) = current.take() {
                    // Joined to the stretch before in the rapid's style:
                    // a feed's line holds the feed's samples only.
                    if !*fresh_run {
                        match (c.rapid, c.points.last()) {
                            (true, _) => c.points.push(samples[0]),
                            (false, Some(last)) => points.push(*last),
                            (false, None) => {}
                        }
                    }
                    stretches.push(c);
                }
                points.extend(samples);
                *current = Some(Stretch {
                    rapid: b.rapid,
                    points,
                });
            }
        }
        *fresh_run = false;
    };

    for h in &timeline.happenings {
        match *h {
            Happening::Block(block) => {
                finish(
                    open.take(),
                    &mut current,
                    &mut out.stretches,
                    &mut spans,
                    run_start,
                    &mut fresh_run,
                );
                let (f, t) = (block.from(), block.to());
                let (fi, ti) = (
                    [i64::from(f.x.0), i64::from(f.z.0)],
                    [i64::from(t.x.0), i64::from(t.z.0)],
                );
                // The program block it comes from: zero-length ones plan
                // nothing; a line is one block, an arc's last chord ends
                // on its end.
                while next < els.len() && els[next].from == els[next].to {
                    next += 1;
                }
                let element = (next < els.len()).then_some(next);
                let d = [ti[0] - fi[0], ti[1] - fi[1]];
                let lead = usize::from(d[1].abs() > d[0].abs());
                let dir: [f64; 2] = match element.map(|i| &els[i]) {
                    Some(e) => {
                        if e.centre.is_none() || ti == e.end {
                            next += 1;
                        }
                        match e.centre {
                            None => [(e.to[0] - e.from[0]) as f64, (e.to[1] - e.from[1]) as f64],
                            Some(c) => {
                                // The tangent at the chord's middle.
                                let m = [
                                    (fi[0] + ti[0]) as f64 / 2.0 * price[0] as f64 - c[0] as f64,
                                    (fi[1] + ti[1]) as f64 / 2.0 * price[1] as f64 - c[1] as f64,
                                ];
                                [m[1], -m[0]]
                            }
                        }
                    }
                    None => [(d[0] * price[0]) as f64, (d[1] * price[1]) as f64],
                };
                let n = dir[0].hypot(dir[1]);
                let u = if n > 0.0 { (dir[lead] / n).abs() } else { 0.0 };
                let ds = if u > 1e-9 {
                    price[lead] as f64 / 1e7 / u
                } else {
                    0.0
                };
                open = Some(Open {
                    rapid: element.is_some_and(|i| els[i].rapid),
                    ds,
                    ticks: Vec::new(),
                    element,
                });
            }
            Happening::Event { tick, .. } => {
                if let Some(b) = open.as_mut() {
                    b.ticks.push(tick);
                }
            }
            Happening::RunEnd(ticks) => {
                finish(
                    open.take(),
                    &mut current,
                    &mut out.stretches,
                    &mut spans,
                    run_start,
                    &mut fresh_run,
                );
                let end = run_start + ticks as f64 / 1e6;
                if let Some(mut c) = current.take() {
                    c.points.push((end, 0.0));
                    out.stretches.push(c);
                }
                run_start = end;
                fresh_run = true;
            }
            Happening::Dwell(us) => {
                let end = run_start + us as f64 / 1e6;
                out.dwells.push([run_start, end]);
                run_start = end;
            }
        }
    }
    finish(
        open.take(),
        &mut current,
        &mut out.stretches,
        &mut spans,
        run_start,
        &mut fresh_run,
    );
    out.stretches.extend(current);
    // The commanded feeds, joined where one block follows another at the
    // same feed.
    let joined = 2.0 * window;
    for (e, span) in els.iter().zip(&spans) {
        let (Some(f), Some(span)) = (e.feed, span) else {
            continue;
        };
        match out.commanded.last_mut() {
            Some((s, g)) if *g == f && span[0] - s[1] <= joined => s[1] = span[1],
            _ => out.commanded.push((*span, f)),
        }
    }
    out
}

// ---------------------------------------------------------------------------
// The chart.

const RAPID: RGBColor = RGBColor(90, 90, 90);
const FEED: RGBColor = TIP;
const COMMANDED: RGBColor = STEPS;
const DWELL: RGBColor = CENTRE;
const DOTS: &[u32] = &[3, 4];
/// The chart's plotting area, pixels.
const CHART_H: u32 = 300;
const TOP: u32 = 64;

/// A polyline with what one column `unit` wide draws kept: its first,
/// lowest, highest and last point, in order (a long program's samples
/// would otherwise overdraw each column many times).
fn thinned(points: &[(f64, f64)], unit: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(points.len());
    let mut column: Vec<(f64, f64)> = Vec::new();
    let flush = |column: &mut Vec<(f64, f64)>, out: &mut Vec<(f64, f64)>| {
        let (Some(first), Some(last)) = (column.first(), column.last()) else {
            return;
        };
        let lo = column
            .iter()
            .copied()
            .fold(*first, |a, p| if p.1 < a.1 { p } else { a });
        let hi = column
            .iter()
            .copied()
            .fold(*first, |a, p| if p.1 > a.1 { p } else { a });
        let (a, b) = if lo.0 <= hi.0 { (lo, hi) } else { (hi, lo) };
        for p in [*first, a, b, *last] {
            if out.last() != Some(&p) {
                out.push(p);
            }
        }
        column.clear();
    };
    let mut at = None;
    for p in points {
        let c = (p.0 / unit).floor() as i64;
        if at != Some(c) {
            flush(&mut column, &mut out);
            at = Some(c);
        }
        column.push(*p);
    }
    flush(&mut column, &mut out);
    out
}

/// A legend line: its text, colour, width (px), dash and layer.
type LegendEntry = (
    &'static str,
    RGBColor,
    u32,
    Option<&'static [u32]>,
    &'static str,
);

/// One speed chart up to `v_top` mm/min (what is faster is cut at the
/// top), titled `title`, with a line under it saying what it shows.
fn speed_chart(speeds: &Speeds, title: &str, what: &str, v_top: f64) -> Result<String, PlotError> {
    let height = TOP + CHART_H + X_LABELS + 2 * MARGIN + 8;
    let canvas = Canvas::new(WIDTH, height);
    let root = canvas.clone().into_drawing_area();
    let plot_w = WIDTH - PANEL - Y_LABELS - 2 * MARGIN;
    let t_end = speeds.end.max(1e-3);
    let t_step = nice_step(90.0 * t_end / f64::from(plot_w));
    let v_step = nice_step(45.0 * v_top / f64::from(CHART_H));
    let t_range = [0.0, t_end];
    let v_range = [0.0, v_top];
    let (td, vd) = (decimals(t_step), decimals(v_step));
    let t_fmt = |t: &f64| label(*t, td);
    let v_fmt = |v: &f64| label(*v, vd);
    let chart_area = root.clone().shrink(
        (0, ki(TOP as i32 - 24)),
        (k(WIDTH - PANEL), k(height - TOP + 24)),
    );
    let mut chart = plot::styled_chart(
        &chart_area,
        MARGIN + 24,
        (
            Axis {
                range: t_range,
                ticks: multiples(0.0, t_end, t_step),
            },
            "time (s)",
            &t_fmt,
        ),
        (
            Axis {
                range: v_range,
                ticks: multiples(0.0, v_top, v_step),
            },
            &v_fmt,
        ),
    )?;
    chart_area.draw(&Text::new(
        "speed along the path (mm/min)",
        (ki(MARGIN as i32), ki((MARGIN + 24) as i32 - 8)),
        font(14).pos(Pos::new(HPos::Left, VPos::Bottom)),
    ))?;
    let view = Rect {
        z: t_range,
        r: [0.0, v_top],
    };
    // A user unit of time (1/10 px).
    let unit = t_end / f64::from(k(plot_w));
    // The commanded feeds under the speed.
    canvas.pen("commanded", Some(DOTS));
    for (span, f) in &speeds.commanded {
        if *f <= v_top {
            chart.draw_series(LineSeries::new(
                [(span[0], *f), (span[1], *f)],
                COMMANDED.stroke_width(k(2)),
            ))?;
        }
    }
    // Their values, once per value and where there is room.
    let mut placed: Vec<(i32, i32, i32)> = Vec::new();
    let mut named: Vec<f64> = Vec::new();
    for (span, f) in &speeds.commanded {
        if *f > v_top || named.contains(f) || named.len() >= 24 {
            continue;
        }
        let text = format!("F {}", label(*f, if f.fract() == 0.0 { 0 } else { 1 }));
        let (x, y) = chart.backend_coord(&(span[0], *f));
        let w = ki(8 * text.chars().count() as i32 + 4);
        let (x, y) = (x + ki(2), y - ki(20));
        if placed
            .iter()
            .any(|(px, py, pw)| (y - py).abs() < ki(18) && x < px + pw && *px < x + w)
        {
            continue;
        }
        placed.push((x, y, w));
        named.push(*f);
        canvas.pen("commanded-label", None);
        root.draw(&Text::new(
            text,
            (x, y),
            font(12)
                .color(&COMMANDED)
                .pos(Pos::new(HPos::Left, VPos::Top)),
        ))?;
    }
    canvas.plain();
    // Dwells at zero speed.
    canvas.pen("dwell", None);
    for d in &speeds.dwells {
        chart.draw_series(LineSeries::new(
            [(d[0], 0.0), (d[1], 0.0)],
            DWELL.stroke_width(k(5)),
        ))?;
    }
    // The speed.
    for s in &speeds.stretches {
        let (class, dash, color) = if s.rapid {
            ("speed rapid", Some(DASH), RAPID)
        } else {
            ("speed feed", None, FEED)
        };
        canvas.pen(class, dash);
        for piece in clipped(&s.points, &view) {
            chart.draw_series(LineSeries::new(
                thinned(&piece, unit),
                color.stroke_width(k(2)),
            ))?;
        }
    }
    canvas.plain();
    root.draw(&Text::new(
        title.to_string(),
        (ki(MARGIN as i32), ki(12)),
        bold(17, &BLACK),
    ))?;
    root.draw(&Text::new(
        what.to_string(),
        (ki(MARGIN as i32), ki(34)),
        font(13),
    ))?;
    // The legend.
    let panel = root.clone().shrink(
        (ki((WIDTH - PANEL) as i32), ki(TOP as i32)),
        (k(PANEL), k(height - TOP)),
    );
    let x0 = ki(16);
    let mut y = ki(24);
    panel.draw(&Text::new(
        "Legend",
        (x0, y),
        bold(15, &BLACK).pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    y += ki(28);
    let entries: [LegendEntry; 4] = [
        ("feed (G01, G02, G03)", FEED, 2, None, "legend speed feed"),
        ("rapid (G00)", RAPID, 2, Some(DASH), "legend speed rapid"),
        (
            "commanded feed F (mm/min)",
            COMMANDED,
            2,
            Some(DOTS),
            "legend commanded",
        ),
        (
            "dwell: G04, spindle up to speed",
            DWELL,
            5,
            None,
            "legend dwell",
        ),
    ];
    for (name, color, width, dash, class) in entries {
        canvas.pen(class, dash);
        panel.draw(&PathElement::new(
            vec![(x0, y), (x0 + ki(44), y)],
            color.stroke_width(k(width)),
        ))?;
        canvas.plain();
        panel.draw(&Text::new(
            name.to_string(),
            (x0 + ki(54), y),
            font(13).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
        y += ki(22);
    }
    y += ki(8);
    let notes = [
        "speed: path length per time from the".to_string(),
        "step events' ticks (1 MHz clock): each".to_string(),
        "block's first and last interval, windows".to_string(),
        format!(
            "of {} ms between; X on the radius",
            label(speeds.window * 1e3, 0)
        ),
        "F per revolution: F × rpm (G97);".to_string(),
        "under G96 no F line (rpm follows X)".to_string(),
    ];
    for n in notes {
        panel.draw(&Text::new(
            n,
            (x0, y),
            font(12).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
        y += ki(18);
    }
    root.present()?;
    Ok(canvas.finish())
}

/// The speed charts: all motion, and when the rapids are much faster than
/// the feeds, the feeds again on their own scale.
pub fn speed_charts(speeds: &Speeds, title: &str) -> Result<Vec<String>, PlotError> {
    let [rapid, feed] = speeds.peaks();
    let f_max = speeds
        .commanded
        .iter()
        .map(|(_, f)| *f)
        .fold(feed, f64::max);
    let top = |v: f64| {
        let v = v.max(1.0) * 1.1;
        let step = nice_step(v / 8.0);
        (v / step).ceil() * step
    };
    let all = rapid.max(f_max);
    let mut charts = vec![speed_chart(
        speeds,
        &format!("{title}: speed along the path"),
        "as the device timed it, from its step events; rapids dashed, feeds solid, dwells at zero",
        top(all),
    )?];
    if f_max > 0.0 && rapid > 2.5 * f_max {
        charts.push(speed_chart(
            speeds,
            &format!("{title}: the feeds"),
            "the same, on the feeds' scale (rapids cut at the top)",
            top(f_max),
        )?);
    }
    Ok(charts)
}

// ---------------------------------------------------------------------------
// The page.

fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            '"' => out.push_str("&quot;"),
            c => out.push(c),
        }
    }
    out
}

const STYLE: &str =
    "body{font-family:sans-serif;margin:24px auto;max-width:1420px;color:#111;padding:0 12px}\
h1{font-size:22px;margin:0 0 4px}h2{font-size:18px;margin:28px 0 8px}\
p.what{color:#444;margin:0 0 12px}\
table{border-collapse:collapse;margin:0 0 8px}\
th,td{border:1px solid #ccc;padding:4px 10px;text-align:left;vertical-align:top}\
th{background:#f2f2f2}td.n{text-align:right;font-variant-numeric:tabular-nums}\
.refused{color:#b00000}.box{border:2px solid #b00000;padding:8px 12px;margin:12px 0;color:#b00000}\
.ok{border:2px solid #2a7a2a;padding:8px 12px;margin:12px 0;color:#2a7a2a}\
figure{margin:0 0 16px}svg{max-width:100%;height:auto;border:1px solid #ddd}";

/// What the page is made of: the run's report and timeline, and the
/// picture's paths.
pub struct Inputs<'a> {
    /// The file's name, for the title.
    pub title: &'a str,
    /// What `run` reports.
    pub report: &'a Report,
    /// The same run in time.
    pub timeline: &'a Timeline,
    /// The picture's paths (`plot::trace`).
    pub paths: &'a plot::Paths,
    /// The setup file's name, for its refusals.
    pub setup_name: &'a str,
}

/// The page.
pub fn page(inputs: &Inputs) -> Result<String, PlotError> {
    let r = inputs.report;
    let title = esc(inputs.title);
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>{title}: run report</title>\n<style>{STYLE}</style>\n</head>\n<body>\n\
         <h1>{title}: run report</h1>\n\
         <p class=\"what\">The program run through the controller's own protocol handler \
         in virtual time (the 1 MHz step clock), as <code>host-sim run</code> runs it; \
         X on the radius for travel and speed, as a diameter on the drawing.</p>\n"
    );
    if let Some(e) = &r.expand_error {
        let _ = writeln!(
            h,
            "<div class=\"box\">Nothing ran: the program's macros, subprograms or \
             expressions could not be expanded, line {}</div>\n</body>\n</html>",
            esc(&e.to_string())
        );
        return Ok(h);
    }
    let refusals = r.refused.len() + r.setup_refused.len();
    if refusals == 0 {
        h.push_str("<div class=\"ok\">The device accepted every line.</div>\n");
    } else {
        let _ = writeln!(
            h,
            "<div class=\"box\">The device refused {refusals} line{}: see <a href=\"#refused\">Refused lines</a>. \
             The rest ran, without them.</div>",
            if refusals == 1 { "" } else { "s" }
        );
    }
    // The facts `run` prints.
    h.push_str("<h2>Summary</h2>\n<table>\n");
    let row = |h: &mut String, what: &str, value: String| {
        let _ = writeln!(h, "<tr><th>{what}</th><td class=\"n\">{value}</td></tr>");
    };
    row(&mut h, "Blocks run", r.blocks.to_string());
    row(&mut h, "Lines refused", r.refused.len().to_string());
    row(
        &mut h,
        "Cycle time (m:ss.sss)",
        format!("<span id=\"cycle-time\">{}</span>", minutes(r.cycle_us())),
    );
    row(&mut h, "in motion", minutes(r.motion_us));
    row(&mut h, "dwelling", minutes(r.dwell_us));
    row(&mut h, "Travel at feed", format!("{:.3} mm", r.feed_mm));
    row(&mut h, "Travel at rapid", format!("{:.3} mm", r.rapid_mm));
    row(&mut h, "Step events", r.events.to_string());
    row(&mut h, "Program stops", r.stops.len().to_string());
    h.push_str("</table>\n");

    h.push_str("<h2>Tools</h2>\n");
    if r.tools.is_empty() {
        h.push_str("<p>No tool named.</p>\n");
    } else {
        h.push_str("<table>\n<tr><th>Line</th><th>Tool word</th></tr>\n");
        for (line, t) in &r.tools {
            let _ = writeln!(h, "<tr><td class=\"n\">{line}</td><td>{}</td></tr>", esc(t));
        }
        h.push_str("</table>\n");
    }
    if !r.cycles.is_empty() {
        h.push_str("<h2>Canned cycles</h2>\n<table>\n<tr><th>Line</th><th>Cycle</th><th>Moves</th><th>Time (m:ss.sss)</th></tr>\n");
        for c in &r.cycles {
            let _ = writeln!(
                h,
                "<tr><td class=\"n\">{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>",
                c.line,
                c.kind,
                c.moves.len(),
                c.us.map_or("not known".to_string(), minutes)
            );
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2>Program stops</h2>\n");
    if r.stops.is_empty() {
        h.push_str("<p>None.</p>\n");
    } else {
        h.push_str("<table>\n<tr><th>Line</th><th>Stop</th></tr>\n");
        for (line, code) in &r.stops {
            let _ = writeln!(
                h,
                "<tr><td class=\"n\">{line}</td><td>{} (cycle start pressed at once; the wait is not in the cycle time)</td></tr>",
                esc(code)
            );
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2 id=\"refused\">Refused lines</h2>\n");
    if refusals == 0 {
        h.push_str("<p>None.</p>\n");
    } else {
        h.push_str("<table class=\"refused\">\n<tr><th>File</th><th>Line</th><th>The device's reply</th></tr>\n");
        for x in &r.setup_refused {
            let (file, line) = if x.line == 0 {
                ("the run's settings".to_string(), String::new())
            } else {
                (esc(inputs.setup_name), x.line.to_string())
            };
            let _ = writeln!(
                h,
                "<tr><td>{file}</td><td class=\"n\">{line}</td><td>{}</td></tr>",
                esc(&x.reply)
            );
        }
        for x in &r.refused {
            let _ = writeln!(
                h,
                "<tr><td>{title}</td><td class=\"n\">{}</td><td>{}</td></tr>",
                x.line,
                esc(&x.reply)
            );
        }
        h.push_str("</table>\n");
    }

    h.push_str("<h2>The path</h2>\n<p class=\"what\">As <code>host-sim plot</code> draws it.</p>\n<figure id=\"plot\">\n");
    let picture = plot::render(inputs.paths, inputs.title, None)?;
    h.push_str(&picture.svg);
    h.push_str("</figure>\n");

    let speeds = speeds(r, inputs.timeline);
    h.push_str("<h2>Speed along the path</h2>\n");
    let _ = writeln!(
        h,
        "<p class=\"what\">The planner's trapezoids as the device timed them: from rest at the start \
         of each run, up to the commanded feed or the rapid rate at each axis' acceleration, \
         slowing for corners, to rest at the end. Time is the cycle time, {} in all.</p>",
        minutes(r.cycle_us())
    );
    for (i, svg) in speed_charts(&speeds, inputs.title)?.iter().enumerate() {
        let _ = writeln!(h, "<figure id=\"speed-{}\">", i + 1);
        h.push_str(svg);
        h.push_str("</figure>\n");
    }
    h.push_str("</body>\n</html>\n");
    Ok(h)
}

/// Runs a program and builds its page: what `run FILE --report` writes,
/// and the report it prints.
pub fn build(
    title: &str,
    text: &str,
    options: program::Options,
    setup: &[(usize, &str)],
    setup_name: &str,
) -> Result<(String, Report), PlotError> {
    let (report, timeline) = program::run_timed(text, options, setup);
    let paths = if report.expand_error.is_some() {
        plot::Paths::default()
    } else {
        plot::trace(
            text,
            &plot::Options {
                program: options,
                zoom: None,
            },
            setup,
        )
    };
    let html = page(&Inputs {
        title,
        report: &report,
        timeline: &timeline,
        paths: &paths,
        setup_name,
    })?;
    Ok((html, report))
}

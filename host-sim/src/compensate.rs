//! `host-sim compensate`: a G41/G42 program turned into the theoretical tool
//! tip program a control without nose compensation can run.
//!
//! Every line goes through the same protocol handler the firmware runs (the
//! in-process [`LocalDevice`]); the blocks it sends are printed as G-code in
//! place of the programmed motion. Lines the control does not interpret
//! (`T0101`, `G96 S120 M03`, `O1234`, `%`, comments) are kept as written, in
//! their place relative to the motion: a line after an element that waits
//! for its end corner is printed after that element.

use crate::device::LocalDevice;
use core_nostd::arc::ArcDir;
use core_nostd::comp::{MoveKind, Origin};
use core_nostd::gcode::{is_block, parse, Dialect, Units};
use std::fmt::Write as _;

/// Tool and format of a compensation run.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Nose radius in mm, as written (`0.4`).
    pub rn: String,
    /// Tip code 0–9.
    pub tip: u8,
    /// X words are diameters (at the start: `G7`/`G8` change it).
    pub diam: bool,
    /// The program's dialect.
    pub dialect: Dialect,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            rn: "0.4".into(),
            tip: 3,
            diam: true,
            dialect: Dialect::Iso,
        }
    }
}

/// A refused program: the line (1-based) and the device's reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CompensateError {
    /// Line number in the program, 0 for the settings.
    pub line: usize,
    /// The `ERR …` reply, without its checksum.
    pub reason: String,
}

impl std::fmt::Display for CompensateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line == 0 {
            write!(f, "settings: {}", self.reason)
        } else {
            write!(f, "line {}: {}", self.line, self.reason)
        }
    }
}

impl std::error::Error for CompensateError {}

/// The compensated program and what the run noticed.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Compensated {
    /// The program text, one block per line.
    pub text: String,
    /// Remarks for the programmer (not errors).
    pub warnings: Vec<String>,
}

/// The words of a source line that are kept on its compensated blocks.
#[derive(Clone, Debug, Default)]
struct Source {
    /// `N…`, if any.
    n: Option<String>,
    /// Other kept words (`F0.1`, `M08`), in order.
    words: Vec<String>,
    /// Comment text (`; point 2` or `(…)`), as written.
    comment: String,
    /// The arc was written in R form.
    r_form: bool,
}

/// Splits a block into address words and its comment. `None` if it is not
/// made of words (the device then says why).
fn words_of(line: &str) -> Option<(Vec<(char, String)>, String)> {
    let mut words = Vec::new();
    let mut comment = String::new();
    let mut chars = line.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        match c {
            ' ' | '\t' => {}
            ';' => {
                comment.push_str(line[i..].trim_end());
                break;
            }
            '(' => {
                let rest = &line[i..];
                let end = rest.find(')')? + 1;
                if !comment.is_empty() {
                    comment.push(' ');
                }
                comment.push_str(&rest[..end]);
                for _ in 1..rest[..end].chars().count() {
                    chars.next();
                }
            }
            c if c.is_ascii_alphabetic() => {
                let mut number = String::new();
                while let Some(&(_, d)) = chars.peek() {
                    if d.is_ascii_digit() || matches!(d, '+' | '-' | '.') {
                        number.push(d);
                        chars.next();
                    } else {
                        break;
                    }
                }
                if number.is_empty() {
                    return None;
                }
                words.push((c.to_ascii_uppercase(), number));
            }
            _ => return None,
        }
    }
    Some((words, comment))
}

/// A G word's code in tenths (`90.1` is 901), if it is one.
fn g_tenths(number: &str) -> Option<u16> {
    let (whole, tenth) = number.split_once('.').unwrap_or((number, "0"));
    Some(whole.parse::<u16>().ok()? * 10 + tenth.parse::<u16>().ok().filter(|t| *t < 10)?)
}

/// G codes of the geometry: motion, compensation, distance modes, corners
/// (which the printed blocks say in their own way), and the plane, unit and
/// diameter modes (which stay in the output, as the device reads them too).
fn is_geometry_g(tenths: u16) -> bool {
    is_restated_g(tenths) || matches!(tenths, 70 | 80 | 180 | 200 | 210)
}

/// G codes the printed blocks restate: they are absolute, with their own
/// motion code and arc centre from the start, and without compensation.
fn is_restated_g(tenths: u16) -> bool {
    matches!(
        tenths,
        0 | 10 | 20 | 30 | 400 | 410 | 420 | 900 | 910 | 901 | 911 | 4500 | 4510
    )
}

/// What kind of line this is for the control.
enum Line {
    /// Passed through as written.
    Foreign,
    /// Its geometry run by the device (the words given); the other words
    /// kept on its output.
    Block(Source, String),
}

fn classify(line: &str) -> Line {
    let Some((words, comment)) = words_of(line) else {
        // Not words at all (`%`, a program number): the reader has read it.
        return Line::Foreign;
    };
    let geometry = |(l, n): &(char, String)| match l {
        'X' | 'Z' | 'U' | 'W' | 'I' | 'K' | 'R' | 'Y' => true,
        'G' => g_tenths(n).is_some_and(is_geometry_g),
        _ => false,
    };
    if !words.iter().any(|w| geometry(w) && w.0 != 'Y') {
        return Line::Foreign;
    }
    let mut src = Source {
        comment,
        ..Source::default()
    };
    let mut device = Vec::new();
    for w in &words {
        let (l, n) = w;
        if *l == 'N' {
            src.n = Some(format!("N{n}"));
            device.push(format!("N{n}"));
            continue;
        }
        if geometry(w) {
            device.push(format!("{l}{n}"));
        }
        match l {
            'R' => src.r_form = true,
            'G' if g_tenths(n).is_some_and(is_restated_g) => {}
            'X' | 'Z' | 'U' | 'W' | 'I' | 'K' | 'Y' => {}
            _ => src.words.push(format!("{l}{n}")),
        }
    }
    Line::Block(src, device.join(" "))
}

/// A length with 4 decimals, half away from zero, from ångström: in
/// inches when `inch`.
fn len4(a: i64, inch: bool) -> String {
    if !inch {
        return mm4(a);
    }
    // 0.0001 in = 25 400 Å.
    let q = (a.unsigned_abs() + 12_700) / 25_400;
    let sign = if a < 0 && q != 0 { "-" } else { "" };
    format!("{sign}{}.{:04}", q / 10_000, q % 10_000)
}

/// Millimetres with 4 decimals, half away from zero, from ångström.
fn mm4(a: i64) -> String {
    let q = (a.unsigned_abs() + 500) / 1000;
    let sign = if a < 0 && q != 0 { "-" } else { "" };
    format!("{sign}{}.{:04}", q / 10_000, q % 10_000)
}

/// Compensates a program.
pub fn compensate(program: &str, settings: &Settings) -> Result<Compensated, CompensateError> {
    let mut dev = LocalDevice::new();
    let cfg = format!(
        "CFG RN={} TIP={} DIAM={}",
        settings.rn,
        settings.tip,
        u8::from(settings.diam)
    );
    let opt = format!("OPT DIALECT={}", settings.dialect.as_str());
    for request in [cfg, opt] {
        let reply = dev.request(&request);
        if let Some(err) = reply.iter().find(|l| l.starts_with("ERR")) {
            return Err(CompensateError {
                line: 0,
                reason: strip_sum(err),
            });
        }
    }
    // The unit lengths are read in, as the lines so far leave it.
    let mut units = Units::Mm;
    // The device refuses a feed move before any F; the printed program is
    // geometry, which no feed changes, so a program without F words is
    // compensated all the same (its own F words take over where given).
    dev.request("F1000");
    let mut out = Compensated::default();
    // The source whose motion waits for the next block, and the lines that
    // followed it.
    let mut waiting: Option<(Source, Vec<String>)> = None;
    let mut at = [0i64; 2];
    // Macros, subprograms and expressions are expanded first, as the host
    // does before streaming; each block keeps its source line.
    let lines: Vec<(usize, String)> = if crate::expand::needs_expansion(program) {
        crate::expand::expand(program, settings.dialect)
            .map_err(|e| CompensateError {
                line: e.line,
                reason: format!("column {}: {}", e.column, e.what),
            })?
            .into_iter()
            .map(|l| (l.source - 1, l.text))
            .collect()
    } else {
        program.lines().map(str::to_owned).enumerate().collect()
    };
    let last = lines.last().map_or(0, |(i, _)| i + 1);
    let ends = [(last, "G40".to_string())];
    for (n, (i, raw)) in lines.iter().chain(&ends).enumerate() {
        let i = *i;
        let end_of_program = n == lines.len();
        let line = raw.trim_end_matches('\r');
        // The unit and diameter mode of the output so far: a line's own
        // G20/G21 or G7/G8 applies from its own block on.
        let before = (units, dev.device().session().config().diam);
        if !end_of_program && !line.trim().is_empty() {
            // Every word is read as the device reads it, also those of the
            // lines only passed through.
            let refusal = |reason: String| CompensateError {
                line: i + 1,
                reason,
            };
            if !is_block(line) {
                return Err(refusal("ERR SYNTAX not a G-code line".into()));
            }
            match parse(line, settings.dialect, units) {
                Ok(b) => units = b.units.unwrap_or(units),
                Err(e) => {
                    let code = if e.error.is_value() {
                        "VALUE"
                    } else {
                        "SYNTAX"
                    };
                    return Err(refusal(format!("ERR {code} {}", e.error)));
                }
            }
        }
        if parse(line, settings.dialect, Units::Mm).is_ok_and(|b| b.round.is_some()) {
            return Err(CompensateError {
                line: i + 1,
                reason: "a ,C or ,R corner: compensate writes the compensated path of lines and arcs as programmed; run the program on the device, which rounds and compensates it".into(),
            });
        }
        let (src, geometry) = match classify(line) {
            Line::Foreign => {
                match &mut waiting {
                    Some((_, after)) => after.push(line.to_string()),
                    None => out.text.push_str(&format!("{line}\n")),
                }
                continue;
            }
            Line::Block(src, geometry) => (src, geometry),
        };
        if end_of_program && !dev.device().session().contour().active() {
            break;
        }
        let reply = dev.request(&geometry);
        if let Some(err) = reply.iter().find(|l| l.starts_with("ERR")) {
            return Err(CompensateError {
                line: i + 1,
                reason: strip_sum(err),
            });
        }
        if end_of_program {
            out.warnings.push(
                "the program ends with G41/G42 on: its last element ends square to its end point; \
                 end the contour with G40"
                    .into(),
            );
        }
        let moves = dev.device().session().last_moves().clone();
        for m in &moves {
            // The source line whose words go on this block; none for corners.
            let own: Option<&Source> = match m.origin {
                // A corner's: refused before the device reads it.
                Origin::Waiting => None,
                Origin::Previous => waiting.as_ref().map(|(s, _)| s),
                Origin::Corner => None,
                Origin::Current => Some(&src),
            };
            let mut text = String::new();
            if let Some(n) = own.and_then(|s| s.n.as_ref()) {
                let _ = write!(text, "{n} ");
            }
            let (units, diam) = if m.origin == Origin::Current {
                (units, dev.device().session().config().diam)
            } else {
                before
            };
            let inch = units == Units::Inch;
            let x = if diam { 2 * m.to[0] } else { m.to[0] };
            let g = match m.kind {
                MoveKind::Line { rapid: true } => "G00",
                MoveKind::Line { rapid: false } => "G01",
                MoveKind::Arc {
                    dir: ArcDir::Cw, ..
                } => "G02",
                MoveKind::Arc {
                    dir: ArcDir::Ccw, ..
                } => "G03",
            };
            let _ = write!(text, "{g} X{} Z{}", len4(x, inch), len4(m.to[1], inch));
            if let MoveKind::Arc { centre, dir } = m.kind {
                let (i, k) = (centre[0] - at[0], centre[1] - at[1]);
                if own.is_some_and(|s| s.r_form) {
                    let r = ((i as f64).hypot(k as f64)).round() as i64;
                    let long = sweep_over_half(at, m.to, centre, dir);
                    let _ = write!(text, " R{}", len4(if long { -r } else { r }, inch));
                } else {
                    let _ = write!(text, " I{} K{}", len4(i, inch), len4(k, inch));
                }
            }
            if let Some(s) = own {
                for w in &s.words {
                    let _ = write!(text, " {w}");
                }
                if !s.comment.is_empty() {
                    let _ = write!(text, " {}", s.comment);
                }
            }
            out.text.push_str(&text);
            out.text.push('\n');
            at = m.to;
            if m.origin == Origin::Previous {
                if let Some((_, after)) = waiting.take() {
                    for l in after {
                        out.text.push_str(&l);
                        out.text.push('\n');
                    }
                }
            }
        }
        let active = dev.device().session().contour().active();
        let moved = moves.iter().any(|m| m.origin == Origin::Current);
        if !moved && !end_of_program {
            let has_motion = line_has_motion(line);
            if active && has_motion {
                // Its motion comes with the next block.
                if let Some((_, after)) = waiting.take() {
                    for l in after {
                        out.text.push_str(&l);
                        out.text.push('\n');
                    }
                }
                waiting = Some((src, Vec::new()));
            } else {
                let kept = kept_line(&src);
                if !kept.is_empty() {
                    match &mut waiting {
                        Some((_, after)) => after.push(kept),
                        None => {
                            out.text.push_str(&kept);
                            out.text.push('\n');
                        }
                    }
                }
            }
        }
    }
    if let Some((_, after)) = waiting.take() {
        for l in after {
            out.text.push_str(&l);
            out.text.push('\n');
        }
    }
    Ok(out)
}

/// Whether a block names an end point or an arc (a motion, unless it does
/// not move).
fn line_has_motion(line: &str) -> bool {
    words_of(line).is_some_and(|(w, _)| {
        w.iter()
            .any(|(l, _)| matches!(l, 'X' | 'Z' | 'U' | 'W' | 'I' | 'K' | 'R'))
    })
}

/// A block without motion as it stays in the output: its words other than
/// compensation, corner and distance codes (`N5 M08`), or nothing.
fn kept_line(src: &Source) -> String {
    let mut parts: Vec<String> = Vec::new();
    if let Some(n) = &src.n {
        parts.push(n.clone());
    }
    parts.extend(src.words.iter().cloned());
    if !src.comment.is_empty() {
        parts.push(src.comment.clone());
    }
    if parts.iter().all(|p| p.starts_with('N')) {
        return String::new();
    }
    parts.join(" ")
}

/// Whether the arc from `a` to `b` about `c` in `dir` sweeps more than 180°.
fn sweep_over_half(a: [i64; 2], b: [i64; 2], c: [i64; 2], dir: ArcDir) -> bool {
    let ang = |p: [i64; 2]| ((p[0] - c[0]) as f64).atan2((p[1] - c[1]) as f64);
    let mut s = ang(b) - ang(a);
    if dir == ArcDir::Cw {
        s = -s;
    }
    let s = s.rem_euclid(std::f64::consts::TAU);
    s > std::f64::consts::PI || (a == b)
}

fn strip_sum(line: &str) -> String {
    line.rsplit_once('*')
        .map_or(line, |(body, _)| body)
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn numbers(text: &str) -> Vec<f64> {
        text.lines()
            .filter(|l| l.starts_with("G0"))
            .flat_map(|l| l.split(' ').skip(1))
            .filter_map(|w| w.get(1..)?.parse().ok())
            .collect()
    }

    #[test]
    fn fanuc_increments_become_absolute_words_and_other_words_stay() {
        let program = "G21 G99\nG00 X20 Z2\nG42 G01 Z0 F.1\nU8.\nG96 S150 W-10.\nG40 G00 X40\n";
        let fanuc = Settings {
            dialect: Dialect::Fanuc,
            ..Settings::default()
        };
        let out = compensate(program, &fanuc).unwrap();
        assert!(
            !out.text.contains('U') && !out.text.contains('W'),
            "{}",
            out.text
        );
        assert!(
            out.text
                .lines()
                .any(|l| l.starts_with("G01 X28.0000 Z-10.") && l.ends_with(" G96 S150")),
            "{}",
            out.text
        );
        // The same program in ISO words.
        let iso = "G21\nG00 X20 Z2\nG42 G01 Z0 F.1\nX28\nG96 S150 Z-10\nG40 G00 X40\n";
        assert_eq!(
            numbers(&out.text),
            numbers(&compensate(iso, &Settings::default()).unwrap().text)
        );
        // Read as ISO, its first Fanuc word is named.
        let e = compensate(program, &Settings::default()).unwrap_err();
        assert_eq!(
            (e.line, e.reason.as_str()),
            (
                1,
                "ERR VALUE G99 belongs to the FANUC dialect (OPT DIALECT=FANUC)"
            )
        );
    }

    #[test]
    fn parameters_and_subroutines_are_expanded_first() {
        let plain = "G21\nG00 X20 Z2\nG42 G01 Z0 F100\nX28\nX48 Z-10\nZ-30\nG40 G00 X60\n";
        let with_sub = "#<d> = 28\no10 sub\nX[#1] Z[#2]\no10 endsub\nG21\nG00 X20 Z2\n\
                        G42 G01 Z0 F100\nX#<d>\no10 call [48] [-10]\nZ-30\nG40 G00 X60\n";
        let a = compensate(plain, &Settings::default()).unwrap();
        let b = compensate(with_sub, &Settings::default()).unwrap();
        let blocks = |t: &str| -> Vec<String> {
            t.lines()
                .filter(|l| l.starts_with('G') || l.starts_with('X') || l.starts_with('Z'))
                .map(str::to_owned)
                .collect()
        };
        assert!(blocks(&a.text).len() >= 5, "{}", a.text);
        assert_eq!(blocks(&a.text), blocks(&b.text));
        let e = compensate("G00 X[1/0]\n", &Settings::default()).unwrap_err();
        assert_eq!(e.line, 1);
    }

    #[test]
    fn inch_programs_print_inches() {
        let inch =
            "G20\nG00 X1. Z.1\nG42 G01 Z0 F5.\nX1.5\nG02 X2. Z-.25 R.25\nG01 Z-1.\nG40 G00 X2.5\n";
        let mm = "G21\nG00 X25.4 Z2.54\nG42 G01 Z0 F127\nX38.1\nG02 X50.8 Z-6.35 R6.35\nG01 Z-25.4\nG40 G00 X63.5\n";
        let a = compensate(inch, &Settings::default()).unwrap();
        let b = compensate(mm, &Settings::default()).unwrap();
        assert!(a.text.starts_with("G20\n"), "{}", a.text);
        let (a, b) = (numbers(&a.text), numbers(&b.text));
        assert_eq!(a.len(), b.len());
        assert!(a.len() > 10);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y / 25.4).abs() <= 0.00005 + 1e-9, "{x} in, {y} mm");
        }
    }

    #[test]
    fn mm4_rounds_half_away() {
        assert_eq!(mm4(275_314_000), "27.5314");
        assert_eq!(mm4(-102_343_146), "-10.2343");
        assert_eq!(mm4(-500), "-0.0001");
        assert_eq!(mm4(-499), "0.0000");
        assert_eq!(mm4(0), "0.0000");
    }
}

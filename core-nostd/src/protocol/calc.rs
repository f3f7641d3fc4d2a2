//! The calculators of [`crate::calc`] as pendant requests: `THREAD`,
//! `WEAR`, `DEFLECT`, `TRI` and `TAPE` (`docs/protocol.md`). Numbers come
//! in with a length's syntax (at most 6 decimals, below 100 000) and go out
//! with a fixed number of decimals, rounded half away from zero; nothing
//! here moves an axis.

use super::io::Io;
use super::request::*;
use super::session::wire::{parse_flag, parse_length, send_data, send_ok, Outcome, Refusal};
use crate::calc::deflection::{self, write_fixed, DeflectionError, MAX_SECTIONS};
use crate::calc::tape::{Bck5Finding, Bck5Frame, Bck5Verifier};
use crate::calc::thread::{self, ThreadAxis, ThreadError, ThreadMode};
use crate::calc::trihedral::{self, TrihedralError};
use crate::calc::wear::{self, WearError};
use crate::plan::Limits;
use crate::text::split_once;
use core::fmt::{self, Write};

/// The most stations a `DEFLECT` answers and rows a `TRI` lists: a
/// thousand reply lines, about 7 s of the serial link at 115 200 baud.
pub(super) const MAX_LINES: u16 = 1000;

/// Sends one `DATA` line and lets the board show it is alive (a long
/// table outlasts the watchdog's patience for the main loop otherwise).
fn data<I: Io>(io: &mut I, words: fmt::Arguments<'_>) {
    send_data(io, words);
    io.pause();
}

/// A number with `decimals` digits after the point, rounded half away
/// from zero (the calculators' own [`write_fixed`]); a value too large
/// for that prints as `OVER`.
struct Fix(f64, u8);

impl fmt::Display for Fix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // `write_fixed` checks before it writes: on a refusal nothing is out.
        write_fixed(f, self.0, u32::from(self.1)).or_else(|_| f.write_str("OVER"))
    }
}

/// A number written as a length (mm syntax: sign, at most 6 decimals,
/// below 100 000), exactly converted.
fn number(key: &'static str, v: &str) -> Result<f64, Refusal<'static>> {
    Ok(parse_length(key, v)?.as_angstrom() as f64 / 1e7)
}

/// An optional number, `default` when absent.
fn number_or(key: &'static str, v: Option<&str>, default: f64) -> Result<f64, Refusal<'static>> {
    v.map_or(Ok(default), |v| number(key, v))
}

/// A required number.
fn required(
    key: &'static str,
    v: Option<&str>,
    missing: &'static str,
) -> Result<f64, Refusal<'static>> {
    number(key, v.ok_or(Refusal::Missing(missing))?)
}

/// A comma-separated list of numbers into `out`; how many there were.
fn list(key: &'static str, v: &str, out: &mut [f64]) -> Result<usize, Refusal<'static>> {
    let (mut n, mut rest) = (0, Some(v));
    while let Some(text) = rest {
        let (item, tail) = match split_once(text, b',') {
            Some((item, tail)) => (item, Some(tail)),
            None => (text, None),
        };
        let slot = out
            .get_mut(n)
            .ok_or(Refusal::Value(key, "has too many values"))?;
        *slot = number(key, item)?;
        (n, rest) = (n + 1, tail);
    }
    Ok(n)
}

/// Exactly `N` comma-separated numbers.
fn tuple<const N: usize>(key: &'static str, v: &str) -> Result<[f64; N], Refusal<'static>> {
    let mut out = [0.0; N];
    if list(key, v, &mut out)? != N {
        return Err(Refusal::Value(key, "has too few values"));
    }
    Ok(out)
}

/// An optional flag word: `0` or `1`, `0` when absent.
fn flag(key: &'static str, v: Option<&str>) -> Result<bool, Refusal<'static>> {
    v.map_or(Ok(false), |v| parse_flag(key, v))
}

/// The part's sections from `D=` and `L=` lists, from the headstock.
fn sections(
    d: Option<&str>,
    l: Option<&str>,
) -> Result<heapless::Vec<deflection::Section, MAX_SECTIONS>, Refusal<'static>> {
    let missing = "the part needs D= and L= (diameters and lengths, mm)";
    let (mut ds, mut ls) = ([0.0; MAX_SECTIONS], [0.0; MAX_SECTIONS]);
    let n = list("D", d.ok_or(Refusal::Missing(missing))?, &mut ds)?;
    if list("L", l.ok_or(Refusal::Missing(missing))?, &mut ls)? != n {
        return Err(Refusal::Value("L", "must give one length per diameter"));
    }
    let mut out = heapless::Vec::new();
    for (&d, &l) in ds.iter().zip(&ls).take(n) {
        let s = deflection::Section::new(d, l).map_err(|e| Refusal::Value("D", e.as_str()))?;
        out.push(s)
            .map_err(|_| Refusal::Value("D", "has too many values"))?;
    }
    Ok(out)
}

fn thread_refusal(e: ThreadError) -> Refusal<'static> {
    Refusal::Value("THREAD", e.as_str())
}

fn wear_refusal(e: WearError) -> Refusal<'static> {
    Refusal::Value("WEAR", e.as_str())
}

fn deflection_refusal(e: DeflectionError) -> Refusal<'static> {
    Refusal::Value("DEFLECT", e.as_str())
}

fn trihedral_refusal(e: TrihedralError) -> Refusal<'static> {
    use TrihedralError as E;
    match e {
        // Angles that make no corner: impossible geometry.
        E::FaceAngleNotBelowOthers(_)
        | E::FaceAngleSumTooLarge
        | E::LinearAngleSumTooSmall
        | E::LinearAngleTooSmall(_)
        | E::AngleAmbiguous
        | E::EdgeNotAboveVertex(_)
        | E::ProportionalFaceTooSmall(_) => Refusal::Geometry(e.as_str()),
        _ => Refusal::Value("TRI", e.as_str()),
    }
}

/// `THREAD P= [MODE=G06…G09] [CROSS=0|1]`: the ЭМ-907's speed limit for
/// the pitch and this controller's for the axis' rapid rate (`LIMITS`).
pub(super) fn thread_command<'a, I: Io>(
    args: &Args<'a>,
    limits: &Limits,
    io: &mut I,
) -> Outcome<'a> {
    let [p, mode, cross] = args.values();
    let pitch = required("P", p, "THREAD needs P= (the pitch, mm)")?;
    let cross = flag("CROSS", cross)?;
    let axis = if cross {
        ThreadAxis::Across
    } else {
        ThreadAxis::Longitudinal
    };
    let mode = match mode {
        None => thread::fastest_em907_mode(axis, pitch).map_err(thread_refusal)?,
        Some(m) => {
            let digits = m.strip_prefix(['G', 'g']).unwrap_or(m);
            let code = match digits {
                "6" | "06" => 6,
                "7" | "07" => 7,
                "8" | "08" => 8,
                "9" | "09" => 9,
                _ => return Err(Refusal::Value("MODE", "must be G06, G07, G08 or G09")),
            };
            ThreadMode::from_g_code(code).map_err(thread_refusal)?
        }
    };
    let em907 = thread::em907_max_speed_rpm(mode, axis, pitch).map_err(thread_refusal)?;
    let word = thread::em907_pitch_word(mode, axis, pitch).map_err(thread_refusal)?;
    let v = limits.rate(usize::from(!cross)).as_angstrom() as f64 / 1e7;
    let own = thread::max_speed_rpm(v, pitch).map_err(thread_refusal)?;
    send_ok(
        io,
        Some(format_args!(
            "MODE=G{:02} WORD={word} CAP={} NEM={} V={} NMAX={}",
            mode.g_code(),
            Fix(mode.speed_cap_rpm(), 0),
            Fix(em907, 1),
            Fix(v, 1),
            Fix(own, 1)
        )),
    );
    Ok(())
}

/// `WEAR (D= L= S= | KM=) UR= [U0=] [Q=] [ALLOW= TOL=] [FULL=] [H= ALPHA=]`.
pub(super) fn wear_command<'a, I: Io>(args: &Args<'a>, io: &mut I) -> Outcome<'a> {
    let [d, l, s, km, u0, ur, q, allow, tol, full, h, alpha] = args.values();
    let path = match km {
        Some(km) => wear::CuttingPath::from_km(number("KM", km)?).map_err(wear_refusal)?,
        None => {
            let parts = sections(d, l)?;
            let feed = required("S", s, "WEAR needs S= (the feed, mm/rev) or KM=")?;
            wear::CuttingPath::of_part(&parts, feed).map_err(wear_refusal)?
        }
    };
    let rate = wear::WearRate::new(
        number_or("U0", u0, 0.0)?,
        required("UR", ur, "WEAR needs UR= (the relative wear, um/km)")?,
    )
    .map_err(wear_refusal)?;
    let parts = match q {
        None => 1,
        Some(v) => match v.parse::<u32>() {
            Ok(n) if v.bytes().all(|b| b.is_ascii_digit()) => n,
            _ => return Err(Refusal::Value("Q", "must be a whole number of parts")),
        },
    };
    let between = match (allow, tol) {
        (None, None) => None,
        (Some(a), Some(t)) => Some(
            rate.parts_between_resettings(path, number("ALLOW", a)?, number("TOL", t)?)
                .map_err(wear_refusal)?,
        ),
        _ => return Err(Refusal::Missing("ALLOW= and TOL= go together")),
    };
    let until = match full {
        None => None,
        Some(u) => Some(
            rate.parts_until_tool_change(path, number("FULL", u)?)
                .map_err(wear_refusal)?,
        ),
    };
    let radial = match (h, alpha) {
        (None, None) => None,
        (Some(h), Some(a)) => Some(
            wear::radial_wear_from_flank_mm(number("H", h)?, number("ALPHA", a)?)
                .map_err(wear_refusal)?,
        ),
        _ => return Err(Refusal::Missing("H= and ALPHA= go together")),
    };
    let mut line = super::reply::ReplyLine::new();
    let _ = write!(
        line,
        "KM={} Q={parts} U={}",
        Fix(path.km(), 5),
        Fix(rate.wear_um(path, parts), 2)
    );
    if let Some(n) = between {
        let _ = write!(line, " QR={n}");
    }
    if let Some(n) = until {
        let _ = write!(line, " QT={n}");
    }
    if let Some(u) = radial {
        let _ = write!(line, " HR={}", Fix(u, 4));
    }
    send_ok(io, Some(format_args!("{}", Text(line.as_bytes()))));
    Ok(())
}

/// ASCII bytes written as text.
struct Text<'b>(&'b [u8]);

impl fmt::Display for Text<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(core::str::from_utf8(self.0).unwrap_or(""))
    }
}

/// Text written to it goes out as one `DATA` line per line of text.
struct DataLines<'i, I: Io> {
    io: &'i mut I,
    line: heapless::Vec<u8, 150>,
}

impl<'i, I: Io> DataLines<'i, I> {
    fn new(io: &'i mut I) -> Self {
        DataLines {
            io,
            line: heapless::Vec::new(),
        }
    }

    fn flush(&mut self) {
        if !self.line.is_empty() {
            data(self.io, format_args!("{}", Text(&self.line)));
            self.line.clear();
        }
    }
}

impl<I: Io> fmt::Write for DataLines<'_, I> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        for b in s.bytes() {
            if b == b'\n' {
                self.flush();
            } else if b != b'\r' {
                self.line.push(b).map_err(|_| fmt::Error)?;
            }
        }
        Ok(())
    }
}

/// `DEFLECT D= L= J=JH,JT,JS T= [S=] [HB=] [PHI=] [RN=] [C= X=] [E=]
/// [RED=LEN|VOL] [DX=] [G=0|1]`.
pub(super) fn deflect_command<'a, I: Io>(args: &Args<'a>, io: &mut I) -> Outcome<'a> {
    let [d, l, j, t, s, hb, phi, rn, c, x, e, red, dx, g] = args.values();
    let parts = sections(d, l)?;
    let reduction = match red {
        None => deflection::Reduction::LengthWeighted,
        Some(v) if v.eq_ignore_ascii_case("LEN") => deflection::Reduction::LengthWeighted,
        Some(v) if v.eq_ignore_ascii_case("VOL") => deflection::Reduction::EqualVolume,
        Some(_) => return Err(Refusal::Value("RED", "must be LEN or VOL")),
    };
    let modulus = number_or("E", e, deflection::STEEL_MODULUS_KGF_PER_MM2)?;
    let shaft = deflection::Shaft::new(&parts, reduction, modulus).map_err(deflection_refusal)?;
    let j = j.ok_or(Refusal::Missing(
        "DEFLECT needs J=JH,JT,JS (stiffness, kgf/mm)",
    ))?;
    let [jh, jt, js] = tuple::<3>("J", j)?;
    let stiffness = deflection::Stiffness::new(jh, jt, js).map_err(deflection_refusal)?;
    let depth = required("T", t, "DEFLECT needs T= (the depth of cut, mm)")?;
    let law = match (c, x) {
        (Some(c), Some(x)) => deflection::ForceLaw::new(number("C", c)?, number("X", x)?)
            .map_err(deflection_refusal)?,
        (None, None) => deflection::SteelForce::from_tables(
            deflection::ApproachAngle::from_degrees(number_or("PHI", phi, 90.0)?)
                .map_err(deflection_refusal)?,
            deflection::NoseRadius::from_mm(number_or("RN", rn, 1.0)?)
                .map_err(deflection_refusal)?,
        )
        .law(number_or("S", s, 0.2)?, number_or("HB", hb, 200.0)?)
        .map_err(deflection_refusal)?,
        _ => return Err(Refusal::Missing("C= and X= go together")),
    };
    let force = law.force_kgf(depth).map_err(deflection_refusal)?;
    let step = number_or("DX", dx, 10.0)?;
    if step > 0.0 && shaft.length_mm() / step > f64::from(MAX_LINES) {
        return Err(Refusal::Range(
            "DEFLECT: more than 1000 stations, give a larger DX",
        ));
    }
    let model = deflection::Deflection::new(stiffness, shaft, law);
    let generatrix = model.generatrix(depth, step).map_err(deflection_refusal)?;
    if flag("G", g)? {
        let mut out = DataLines::new(io);
        generatrix
            .write_gcode(&mut out, deflection::Direction::TowardHeadstock, 4)
            .map_err(deflection_refusal)?;
        out.flush();
    } else {
        for row in generatrix.rows() {
            data(
                io,
                format_args!(
                    "X={} Z={} SIG={} ERR={} COR={} D={} DS={}",
                    Fix(row.x_mm, 4),
                    Fix(row.z_mm, 4),
                    Fix(row.compliance_mm_per_kgf, 9),
                    Fix(row.error_mm, 4),
                    Fix(row.correction_mm, 4),
                    Fix(row.diameter_mm, 4),
                    Fix(row.set_diameter_mm, 4)
                ),
            );
        }
    }
    send_ok(
        io,
        Some(format_args!(
            "DRED={} C={} XP={} P={} N={}",
            Fix(shaft.reduced_diameter_mm(), 4),
            Fix(law.c_kgf(), 4),
            Fix(law.exponent(), 4),
            Fix(force, 3),
            generatrix.len()
        )),
    );
    Ok(())
}

/// `TRI [AOB=] [BOC=] [COA=] [OA=] [OB=] [OC=] [H=] [ROWS=] [LEN=] [RF=]
/// [TABLE=L,M] [EA=] [KV=] [V=X,Y,Z] [PROP=0|1] [G=0|1]`: three of the
/// six angles (degrees) fix the corner.
pub(super) fn tri_command<'a, I: Io>(args: &Args<'a>, io: &mut I) -> Outcome<'a> {
    let [aob, boc, coa, oa, ob, oc, h, rows, len, rf, table, ea, kv, v, prop, g] = args.values();
    let angle = |key, v: Option<&str>| v.map(|v| number(key, v)).transpose();
    let given = trihedral::CornerAngles {
        aob_deg: angle("AOB", aob)?,
        boc_deg: angle("BOC", boc)?,
        coa_deg: angle("COA", coa)?,
        at_oa_deg: angle("OA", oa)?,
        at_ob_deg: angle("OB", ob)?,
        at_oc_deg: angle("OC", oc)?,
    };
    let plane = given.solve().map_err(trihedral_refusal)?;
    let proportional = flag("PROP", prop)?;
    let corner = if proportional {
        trihedral::Corner::proportional(plane)
    } else {
        trihedral::Corner::new(plane)
    }
    .map_err(trihedral_refusal)?;
    let rows = match rows {
        None => 10,
        Some(v) => match v.parse::<u16>() {
            Ok(n) if v.bytes().all(|b| b.is_ascii_digit()) && n <= MAX_LINES => n,
            _ => return Err(Refusal::Value("ROWS", "must be 1 to 1000")),
        },
    };
    let lengths = len.map_or(Ok([10.0; 3]), |v| tuple::<3>("LEN", v))?;
    let [axes, surface] = table.map_or(Ok([0.0; 2]), |v| tuple::<2>("TABLE", v))?;
    let [vx, vy, vz] = v.map_or(Ok([0.0; 3]), |v| tuple::<3>("V", v))?;
    let quadrant = match kv {
        None => trihedral::Quadrant::from_number(1),
        Some(v) => v
            .parse::<u8>()
            .ok()
            .and_then(trihedral::Quadrant::from_number),
    }
    .ok_or(Refusal::Value("KV", "must be 1, 2, 3 or 4"))?;
    let job = trihedral::Job {
        row_step_mm: number_or("H", h, 0.5)?,
        rows,
        length_a_mm: lengths[0],
        length_b_mm: lengths[1],
        length_c_mm: lengths[2],
        fillet_radius_mm: number_or("RF", rf, 0.0)?,
        table: trihedral::TiltRotaryTable {
            axes_distance_mm: axes,
            surface_to_tilt_mm: surface,
        },
        oa_to_x_deg: number_or("EA", ea, 0.0)?,
        quadrant,
        vertex: trihedral::Point3 {
            x_mm: vx,
            y_mm: vy,
            z_mm: vz,
        },
    };
    let setup = trihedral::Setup::new(&corner, &job).map_err(trihedral_refusal)?;
    if flag("G", g)? {
        let mut out = DataLines::new(io);
        setup
            .write_program(&mut out, &trihedral::ProgramOptions::default())
            .map_err(trihedral_refusal)?;
        out.flush();
    } else {
        let c = &setup.corner;
        let deg = |v| Fix(v, 5);
        send_data(
            io,
            format_args!(
                "PHI={} SA={} SB={} SC={} AA={} AB={} AC={}",
                deg(c.phi_deg),
                deg(c.sigma_a_deg),
                deg(c.sigma_b_deg),
                deg(c.sigma_c_deg),
                deg(c.alpha_a_deg),
                deg(c.alpha_b_deg),
                deg(c.alpha_c_deg)
            ),
        );
        send_data(
            io,
            format_args!(
                "LOA={} LOB={} LOC={} ROT={} ROTP={} TILT={}",
                deg(c.linear_oa_deg),
                deg(c.linear_ob_deg),
                deg(c.linear_oc_deg),
                deg(setup.rotation_deg),
                deg(setup.rotation_positive_deg),
                deg(setup.tilt_deg)
            ),
        );
        let mm = |v| Fix(v, 4);
        for (edge, p) in [
            ("A", setup.edge_a),
            ("B", setup.edge_b),
            ("C", setup.edge_c),
        ] {
            send_data(
                io,
                format_args!(
                    "EDGE={edge} X={} Y={} Z={}",
                    mm(p.x_mm),
                    mm(p.y_mm),
                    mm(p.z_mm)
                ),
            );
        }
        send_data(
            io,
            format_args!(
                "ZMIN={} SHA={} SHC={} X0={} Y0={} Z0={}",
                mm(setup.z_min_mm),
                mm(setup.shift.a_mm),
                mm(setup.shift.c_mm),
                mm(setup.start.x_mm),
                mm(setup.start.y_mm),
                mm(setup.start.z_mm)
            ),
        );
        for (n, row) in setup.rows().enumerate() {
            data(
                io,
                format_args!(
                    "ROW={} Z={} XA={} YA={} XB={} YB={} XC={} YC={}",
                    n + 1,
                    mm(row.z_mm),
                    mm(row.a.x_mm),
                    mm(row.a.y_mm),
                    mm(row.b.x_mm),
                    mm(row.b.y_mm),
                    mm(row.c.x_mm),
                    mm(row.c.y_mm)
                ),
            );
        }
    }
    send_ok(
        io,
        Some(format_args!(
            "AOB={} BOC={} COA={} ROWS={rows}",
            Fix(plane.aob_deg(), 5),
            Fix(plane.boc_deg(), 5),
            Fix(plane.coa_deg(), 5)
        )),
    );
    Ok(())
}

/// `TAPE FRAME=<frame>` checks one BCK-5 frame (Latin look-alikes, no
/// spaces) and adds it to the tape read so far; `TAPE END` judges the last
/// tool and starts a new tape. Each finding is a `DATA` line; a frame that
/// cannot be read is refused (`ERR VALUE FRAME column …`).
pub(super) fn tape_command<'a, I: Io>(
    args: &Args<'a>,
    tape: &mut Bck5Verifier,
    io: &mut I,
) -> Outcome<'a> {
    if args.bare {
        let summary =
            core::mem::take(tape).finish(|f: Bck5Finding| send_data(io, format_args!("{f}")));
        send_ok(
            io,
            Some(format_args!(
                "LINES={} FRAMES={} FINDINGS={} END=1",
                summary.lines, summary.frames, summary.findings
            )),
        );
        return Ok(());
    }
    let [frame] = args.values();
    let frame = frame.ok_or(Refusal::Missing("TAPE needs FRAME=<frame> or END"))?;
    // A frame that cannot be read is refused and not counted: the tape so
    // far is unchanged.
    let frame = Bck5Frame::parse(frame).map_err(Refusal::Frame)?;
    tape.frame(&frame, |f: Bck5Finding| send_data(io, format_args!("{f}")));
    let summary = tape.summary();
    send_ok(
        io,
        Some(format_args!(
            "LINES={} FRAMES={} FINDINGS={}",
            summary.lines, summary.frames, summary.findings
        )),
    );
    Ok(())
}

//! The seeds' calculators as a person types them: `thread-speed`,
//! `trihedral`, `deflection`, `wear`. Each answer is a [`Report`]: a table
//! with units on the terminal, CSV or JSON for scripts. The arithmetic is
//! the core's (`core_nostd::calc`).

use crate::table::{field, Cell, Report};
use core_nostd::calc::{deflection, tape, thread, trihedral, wear};

/// What a calculator says when its input is outside its domain.
pub type CalcResult<T> = Result<T, String>;

/// `thread-speed PITCH [--mode G06…G09] [--cross] [--feed-limit MM/MIN]`.
pub fn thread_speed(
    pitch_mm: f64,
    mode: Option<&str>,
    cross: bool,
    feed_limit_mm_min: f64,
) -> CalcResult<Report> {
    let axis = if cross {
        thread::ThreadAxis::Across
    } else {
        thread::ThreadAxis::Longitudinal
    };
    let e = |e: thread::ThreadError| e.to_string();
    let mode = match mode {
        Some(m) => {
            let n: u16 = m
                .trim_start_matches(['G', 'g'])
                .parse()
                .map_err(|_| format!("mode: {m} is not G06, G07, G08 or G09"))?;
            thread::ThreadMode::from_g_code(n).map_err(e)?
        }
        None => thread::fastest_em907_mode(axis, pitch_mm).map_err(e)?,
    };
    let em907 = thread::em907_max_speed_rpm(mode, axis, pitch_mm).map_err(e)?;
    let word = thread::em907_pitch_word(mode, axis, pitch_mm).map_err(e)?;
    let own = thread::max_speed_rpm(feed_limit_mm_min, pitch_mm).map_err(e)?;
    let mut r = Report::new(&format!(
        "Threading speed limit, pitch {pitch_mm} mm, {}",
        if cross {
            "across (X)"
        } else {
            "longitudinal (Z)"
        }
    ));
    r.value("pitch_mm", "pitch", "mm", Cell::Num(pitch_mm, 4));
    r.value(
        "em907_mode",
        "ЭМ-907 mode",
        "",
        Cell::Text(format!("G{:02}", mode.g_code())),
    );
    r.value(
        "em907_pitch_word",
        "ЭМ-907 pitch word",
        "impulses",
        Cell::Int(i64::from(word)),
    );
    r.value(
        "em907_cap_rpm",
        "mode's speed cap",
        "rpm",
        Cell::Num(mode.speed_cap_rpm(), 0),
    );
    r.value(
        "em907_n_max_rpm",
        "ЭМ-907 n max",
        "rpm",
        Cell::Num(em907, 1),
    );
    r.value(
        "feed_limit_mm_min",
        "this axis' feed limit",
        "mm/min",
        Cell::Num(feed_limit_mm_min, 1),
    );
    r.value(
        "n_max_rpm",
        "this controller's n max",
        "rpm",
        Cell::Num(own, 1),
    );
    r.notes.push(
        "ЭМ-907: n max = min(cap, 1200/t) along, min(cap, 600/t) across (0.01/0.005 mm impulses); \
         this controller: the axis feed n·t within the axis' limit (LIMITS VZ, VX)."
            .into(),
    );
    Ok(r)
}

/// The angles given to `trihedral`: three plane angles, or a mix with
/// linear (dihedral) angles.
#[derive(Clone, Copy, Debug, Default)]
pub struct Angles {
    /// Plane angles AOB, BOC, COA, degrees.
    pub plane: [Option<f64>; 3],
    /// Linear angles at OA, OB, OC, degrees.
    pub linear: [Option<f64>; 3],
}

/// What `trihedral` needs besides the angles.
#[derive(Clone, Copy, Debug)]
pub struct TrihedralJob {
    /// Row step h, mm.
    pub step_mm: f64,
    /// Rows (КОН).
    pub rows: u16,
    /// Lengths milled along OA, OB, OC, mm.
    pub lengths_mm: [f64; 3],
    /// Fillet radius R_f, mm.
    pub fillet_mm: f64,
    /// Table parameters L and m, mm.
    pub table: [f64; 2],
    /// E, degrees.
    pub e_deg: f64,
    /// k_v, 1 to 4.
    pub quadrant: u8,
    /// The vertex in the part's frame, mm.
    pub vertex: [f64; 3],
    /// The paper's proportional method instead of the exact one.
    pub proportional: bool,
}

/// `trihedral`: the corner, the table's set-up, the rows; and the program.
pub fn trihedral(angles: Angles, job: &TrihedralJob) -> CalcResult<(Report, String)> {
    let e = |e: trihedral::TrihedralError| e.to_string();
    let given = trihedral::CornerAngles {
        aob_deg: angles.plane[0],
        boc_deg: angles.plane[1],
        coa_deg: angles.plane[2],
        at_oa_deg: angles.linear[0],
        at_ob_deg: angles.linear[1],
        at_oc_deg: angles.linear[2],
    };
    let plane = given.solve().map_err(e)?;
    let corner = if job.proportional {
        trihedral::Corner::proportional(plane)
    } else {
        trihedral::Corner::new(plane)
    }
    .map_err(e)?;
    let quadrant = trihedral::Quadrant::from_number(job.quadrant)
        .ok_or_else(|| format!("quadrant: {} is not 1, 2, 3 or 4", job.quadrant))?;
    let setup = trihedral::Setup::new(
        &corner,
        &trihedral::Job {
            row_step_mm: job.step_mm,
            rows: job.rows,
            length_a_mm: job.lengths_mm[0],
            length_b_mm: job.lengths_mm[1],
            length_c_mm: job.lengths_mm[2],
            fillet_radius_mm: job.fillet_mm,
            table: trihedral::TiltRotaryTable {
                axes_distance_mm: job.table[0],
                surface_to_tilt_mm: job.table[1],
            },
            oa_to_x_deg: job.e_deg,
            quadrant,
            vertex: trihedral::Point3 {
                x_mm: job.vertex[0],
                y_mm: job.vertex[1],
                z_mm: job.vertex[2],
            },
        },
    )
    .map_err(e)?;
    let mut r = Report::new(&format!(
        "Trihedral corner AOB {:.4}°, BOC {:.4}°, COA {:.4}° ({})",
        plane.aob_deg(),
        plane.boc_deg(),
        plane.coa_deg(),
        if job.proportional {
            "the paper's proportional method, for comparison"
        } else {
            "exact spherical trigonometry"
        }
    ));
    let c = &setup.corner;
    let deg = |r: &mut Report, key, label: &str, v: f64| r.value(key, label, "°", Cell::Num(v, 5));
    deg(&mut r, "phi_deg", "cutter angle φ", c.phi_deg);
    deg(&mut r, "sigma_a_deg", "σa", c.sigma_a_deg);
    deg(&mut r, "sigma_b_deg", "σb", c.sigma_b_deg);
    deg(&mut r, "sigma_c_deg", "σc", c.sigma_c_deg);
    deg(&mut r, "alpha_a_deg", "αa", c.alpha_a_deg);
    deg(&mut r, "alpha_b_deg", "αb", c.alpha_b_deg);
    deg(&mut r, "alpha_c_deg", "αc", c.alpha_c_deg);
    deg(
        &mut r,
        "linear_oa_deg",
        "linear angle at OA",
        c.linear_oa_deg,
    );
    deg(
        &mut r,
        "linear_ob_deg",
        "linear angle at OB",
        c.linear_ob_deg,
    );
    deg(
        &mut r,
        "linear_oc_deg",
        "linear angle at OC",
        c.linear_oc_deg,
    );
    deg(
        &mut r,
        "rotation_deg",
        "table rotation P",
        setup.rotation_deg,
    );
    deg(
        &mut r,
        "rotation_positive_deg",
        "table rotation P⁺",
        setup.rotation_positive_deg,
    );
    deg(&mut r, "tilt_deg", "table tilt", setup.tilt_deg);
    let mm = |r: &mut Report, key, label: &str, v: f64| r.value(key, label, "mm", Cell::Num(v, 3));
    for (edge, p, key) in [
        ("A", setup.edge_a, ["xa_mm", "ya_mm", "za_mm"]),
        ("B", setup.edge_b, ["xb_mm", "yb_mm", "zb_mm"]),
        ("C", setup.edge_c, ["xc_mm", "yc_mm", "zc_mm"]),
    ] {
        mm(&mut r, key[0], &format!("edge O{edge} end X"), p.x_mm);
        mm(&mut r, key[1], &format!("edge O{edge} end Y"), p.y_mm);
        mm(&mut r, key[2], &format!("edge O{edge} end Z"), p.z_mm);
    }
    mm(
        &mut r,
        "z_min_mm",
        "Z min (with the fillet)",
        setup.z_min_mm,
    );
    mm(&mut r, "shift_a_mm", "tilt shift a", setup.shift.a_mm);
    mm(&mut r, "shift_c_mm", "tilt shift c", setup.shift.c_mm);
    mm(&mut r, "start_x_mm", "start x'", setup.start.x_mm);
    mm(&mut r, "start_y_mm", "start Y", setup.start.y_mm);
    mm(&mut r, "start_z_mm", "start z'", setup.start.z_mm);
    r.columns = vec![
        field("row", "row", ""),
        field("z_mm", "Z", "mm"),
        field("xa_mm", "XA", "mm"),
        field("ya_mm", "YA", "mm"),
        field("xb_mm", "XB", "mm"),
        field("yb_mm", "YB", "mm"),
        field("xc_mm", "XC", "mm"),
        field("yc_mm", "YC", "mm"),
    ];
    for (n, row) in setup.rows().enumerate() {
        r.rows.push(vec![
            Cell::Int(n as i64 + 1),
            Cell::Num(row.z_mm, 3),
            Cell::Num(row.a.x_mm, 3),
            Cell::Num(row.a.y_mm, 3),
            Cell::Num(row.b.x_mm, 3),
            Cell::Num(row.b.y_mm, 3),
            Cell::Num(row.c.x_mm, 3),
            Cell::Num(row.c.y_mm, 3),
        ]);
    }
    let mut program = String::new();
    setup
        .write_program(&mut program, &trihedral::ProgramOptions::default())
        .map_err(|_| "the program: a coordinate beyond what a block can hold".to_string())?;
    Ok((r, program))
}

/// `deflection`: the shaft, the machine, the cut.
#[derive(Clone, Debug)]
pub struct DeflectionJob {
    /// Sections from the headstock: diameter and length, mm.
    pub sections: Vec<(f64, f64)>,
    /// Equal volume (eq. 31) instead of length-weighted (eq. 30).
    pub equal_volume: bool,
    /// Young's modulus, kgf/mm².
    pub modulus: f64,
    /// Headstock, tailstock and saddle stiffness, kgf/mm.
    pub stiffness: [f64; 3],
    /// The depth of cut, mm.
    pub depth_mm: f64,
    /// Feed, mm/rev.
    pub feed_mm_rev: f64,
    /// Hardness, HB.
    pub hardness_hb: f64,
    /// Approach angle φ, degrees (Table 8).
    pub approach_deg: f64,
    /// Nose radius, mm (Table 8).
    pub nose_mm: f64,
    /// Radial force coefficient and exponent given directly (C, x).
    pub force: Option<(f64, f64)>,
    /// Sampling step Δx, mm.
    pub step_mm: f64,
    /// The spindle speed the program turns at, rpm.
    pub rpm: f64,
}

/// `deflection`: the table of `x`, compliance, error, correction, and the
/// compensated pass as G-code.
pub fn deflection(job: &DeflectionJob) -> CalcResult<(Report, String)> {
    let e = |e: deflection::DeflectionError| e.to_string();
    let sections = sections(&job.sections)?;
    let reduction = if job.equal_volume {
        deflection::Reduction::EqualVolume
    } else {
        deflection::Reduction::LengthWeighted
    };
    let shaft = deflection::Shaft::new(&sections, reduction, job.modulus).map_err(e)?;
    let stiffness =
        deflection::Stiffness::new(job.stiffness[0], job.stiffness[1], job.stiffness[2])
            .map_err(e)?;
    let law = match job.force {
        Some((c, x)) => deflection::ForceLaw::new(c, x).map_err(e)?,
        None => deflection::SteelForce::from_tables(
            deflection::ApproachAngle::from_degrees(job.approach_deg).map_err(e)?,
            deflection::NoseRadius::from_mm(job.nose_mm).map_err(e)?,
        )
        .law(job.feed_mm_rev, job.hardness_hb)
        .map_err(e)?,
    };
    let d = deflection::Deflection::new(stiffness, shaft, law);
    let g = d.generatrix(job.depth_mm, job.step_mm).map_err(e)?;
    let mut r = Report::new(&format!(
        "Deflection between centres: depth {} mm, the part {} mm long",
        job.depth_mm,
        shaft.length_mm()
    ));
    r.value(
        "reduced_diameter_mm",
        "reduced diameter",
        "mm",
        Cell::Num(shaft.reduced_diameter_mm(), 3),
    );
    r.value(
        "force_c_kgf",
        "force coefficient C",
        "kgf",
        Cell::Num(law.c_kgf(), 4),
    );
    r.value(
        "force_x",
        "depth exponent x",
        "",
        Cell::Num(law.exponent(), 3),
    );
    r.value(
        "force_kgf",
        "radial force P at the depth",
        "kgf",
        Cell::Num(law.force_kgf(job.depth_mm).map_err(e)?, 2),
    );
    r.columns = vec![
        field("x_mm", "x", "mm"),
        field("z_mm", "Z", "mm"),
        field("compliance_mm_per_kgf", "Σ(x)", "mm/kgf"),
        field("error_mm", "error", "mm"),
        field("correction_mm", "depth to set", "mm"),
        field("diameter_mm", "Ø", "mm"),
        field("set_diameter_mm", "Ø to program", "mm"),
    ];
    for row in g.rows() {
        r.rows.push(vec![
            Cell::Num(row.x_mm, 1),
            Cell::Num(row.z_mm, 1),
            Cell::Num(row.compliance_mm_per_kgf, 7),
            Cell::Num(row.error_mm, 4),
            Cell::Num(row.correction_mm, 4),
            Cell::Num(row.diameter_mm, 3),
            Cell::Num(row.set_diameter_mm, 4),
        ]);
    }
    // A program ready to run: from 2 mm off the tailstock face and 1 mm
    // above the largest diameter, the pass toward the headstock at the
    // feed per revolution, then away.
    let top = job.sections.iter().map(|s| s.0).fold(0.0, f64::max) + 2.0;
    let first = g.rows().next_back().map_or(top, |row| row.set_diameter_mm);
    let mut program = format!(
        "%\nO2000 (PASS COMPENSATED FOR DEFLECTION, DEPTH {} MM)\nG21 G18 G90 G95 G40\n\
         G97 S{:.0} M03\nG00 X{top:.4} Z2.0000\nG00 X{first:.4}\nF{}\n",
        job.depth_mm, job.rpm, job.feed_mm_rev
    );
    g.write_gcode(&mut program, deflection::Direction::TowardHeadstock, 4)
        .map_err(e)?;
    let _ = std::fmt::Write::write_fmt(
        &mut program,
        format_args!("G00 X{top:.4}\nG00 Z2.0000\nM05\nM30\n%\n"),
    );
    Ok((r, program))
}

/// `wear`: the part's sections, the feed, the wear rate, the limits.
#[derive(Clone, Debug)]
pub struct WearJob {
    /// Surfaces cut per part: diameter and length, mm.
    pub sections: Vec<(f64, f64)>,
    /// Feed, mm/rev.
    pub feed_mm_rev: f64,
    /// Initial wear, µm.
    pub initial_um: f64,
    /// Relative wear, µm/km.
    pub rate_um_per_km: f64,
    /// Parts made.
    pub parts: u32,
    /// Allowed wear before a re-setting, µm, and the tolerance δ, µm.
    pub resetting: Option<(f64, f64)>,
    /// The wear at which the tool is changed, µm.
    pub full_um: Option<f64>,
    /// Flank wear h, mm, and the clearance angle, degrees.
    pub flank: Option<(f64, f64)>,
}

/// `wear`: the path, the wear after the parts, the parts between
/// re-settings and until the tool change, the radial wear from flank wear.
pub fn wear(job: &WearJob) -> CalcResult<Report> {
    let e = |e: wear::WearError| e.to_string();
    let sections = sections(&job.sections)?;
    let path = wear::CuttingPath::of_part(&sections, job.feed_mm_rev).map_err(e)?;
    let rate = wear::WearRate::new(job.initial_um, job.rate_um_per_km).map_err(e)?;
    let mut r = Report::new("Tool wear");
    r.value(
        "path_km",
        "cutting path per part",
        "km",
        Cell::Num(path.km(), 5),
    );
    r.value("parts", "parts", "", Cell::Int(i64::from(job.parts)));
    r.value(
        "wear_um",
        "wear after them",
        "µm",
        Cell::Num(rate.wear_um(path, job.parts), 2),
    );
    if let Some((allowed, tolerance)) = job.resetting {
        let q = rate
            .parts_between_resettings(path, allowed, tolerance)
            .map_err(e)?;
        r.value(
            "parts_between_resettings",
            "parts between re-settings",
            "",
            Cell::Int(i64::from(q)),
        );
    }
    if let Some(full) = job.full_um {
        let q = rate.parts_until_tool_change(path, full).map_err(e)?;
        r.value(
            "parts_until_tool_change",
            "parts until the tool change",
            "",
            Cell::Int(i64::from(q)),
        );
    }
    if let Some((h, alpha)) = job.flank {
        let u = wear::radial_wear_from_flank_mm(h, alpha).map_err(e)?;
        r.value(
            "radial_wear_mm",
            "radial wear from the flank wear",
            "mm",
            Cell::Num(u, 4),
        );
    }
    Ok(r)
}

/// Checked sections from (diameter, length) pairs, mm.
fn sections(pairs: &[(f64, f64)]) -> CalcResult<Vec<deflection::Section>> {
    pairs
        .iter()
        .map(|&(d, l)| deflection::Section::new(d, l))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())
}

/// `D:L` or `DxL` (mm) as a section.
pub fn parse_section(s: &str) -> Result<(f64, f64), String> {
    let (d, l) = s
        .split_once([':', 'x', 'X'])
        .ok_or_else(|| format!("section {s}: write DIAMETER:LENGTH in mm, e.g. 40:120"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .map_err(|_| format!("section {s}: {t} is not a number of mm"))
    };
    Ok((num(d)?, num(l)?))
}

/// `tape verify FILE`: a BCK-5 listing (one frame per line as the seed
/// prints them, Cyrillic or the Latin look-alikes) checked frame by frame
/// (check digits, numbering) and tool by tool (Σ+ + Σ− = 0 on each axis);
/// an ISO-7bit listing (blocks starting `N`) read block by block. The
/// report lists every finding; the count decides the exit status.
pub fn tape_verify(text: &str) -> (Report, usize) {
    let mut r = Report::new("Tape verification");
    r.columns = vec![field("line", "line", ""), field("finding", "finding", "")];
    let iso = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .is_some_and(|l| l.starts_with(['N', 'n', ':', '%']));
    let mut findings = 0usize;
    if iso {
        let mut blocks = 0;
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line == "%" {
                continue;
            }
            match tape::Iso7Block::parse(line) {
                Ok(_) => blocks += 1,
                Err(e) => {
                    findings += 1;
                    r.rows
                        .push(vec![Cell::Int(n as i64 + 1), Cell::Text(e.to_string())]);
                }
            }
        }
        r.value(
            "format",
            "format",
            "",
            Cell::Text("ISO-7bit (ЭМ-907)".into()),
        );
        r.value("blocks", "blocks read", "", Cell::Int(blocks));
    } else {
        let mut v = tape::Bck5Verifier::new();
        let mut rows = Vec::new();
        let mut push = |f: tape::Bck5Finding| {
            let line = match f {
                tape::Bck5Finding::Unreadable { line, .. }
                | tape::Bck5Finding::CheckDigit { line, .. }
                | tape::Bck5Finding::Numbering { line, .. } => i64::from(line),
                tape::Bck5Finding::Closure { .. } => 0,
            };
            let at = if line > 0 {
                Cell::Int(line)
            } else {
                Cell::Text("-".into())
            };
            rows.push(vec![at, Cell::Text(f.to_string())]);
        };
        for line in text.lines() {
            v.line(line, &mut push);
        }
        let summary = v.finish(&mut push);
        findings = summary.findings as usize;
        r.rows = rows;
        r.value(
            "format",
            "format",
            "",
            Cell::Text("BCK-5 (АТПр-2М12)".into()),
        );
        r.value(
            "frames",
            "frames read",
            "",
            Cell::Int(i64::from(summary.frames)),
        );
    }
    r.value("findings", "findings", "", Cell::Int(findings as i64));
    if findings == 0 {
        r.columns.clear();
    }
    (r, findings)
}

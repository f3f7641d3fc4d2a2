//! `host-sim`: the host simulator of the lathe retrofit controller.
//!
//! With no arguments it runs the main job: the built-in scenarios over the
//! virtual serial link against the f64 reference, bit for bit.

use clap::{Parser, Subcommand, ValueEnum};
use host_sim::compare::{format_distance, Comparator, Scenario, Tally};
use host_sim::device::LocalDevice;
use host_sim::link::{Client, LinkError, PtyDevice, Transport};
use host_sim::scenario;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::{Read, Write};
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "host-sim",
    version,
    about = "Host simulator of the lathe retrofit controller"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Compare the device with the f64 reference, bit for bit (the default);
    /// with a FILE, run that G-code program through the in-process device
    /// in virtual time and report its cycle time, travel, tool changes and
    /// refusals (with --report, also as an HTML page with the picture and
    /// the speed along the path over time).
    Run(RunArgs),
    /// Boot the firmware in QEMU and compare it with the f64 reference over
    /// its serial link.
    Qemu(QemuArgs),
    /// A long seeded session over a faulty link: bit flips, dropped and
    /// duplicated bytes, noise, device resets.
    Soak(SoakArgs),
    /// Count the firmware's instructions per step event and per request on
    /// the Cortex-M4, under QEMU -icount.
    QemuBench,
    /// Print a G41/G42 program as the tool-tip program the device runs
    /// (compensation done), ready for a control without it.
    Compensate {
        /// The G-code program.
        file: std::path::PathBuf,
        /// Nose radius in mm.
        #[arg(long, default_value = "0.4")]
        rn: String,
        /// Tip orientation code 0–9 (3: external right-hand tool, 2: boring
        /// bar; 0 and 9 program the nose centre).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(0..=9))]
        tip: u8,
        /// X words are radii, not diameters.
        #[arg(long)]
        radius: bool,
        /// The program's dialect: iso (LinuxCNC, grbl), fanuc (Fanuc/Haas
        /// G-code system A), or auto (from its words).
        #[arg(long, default_value = "auto")]
        dialect: String,
    },
    /// List every line of a G-code file the device would refuse (line,
    /// column, what); exit status 1 if there is any.
    Check {
        /// The G-code program.
        file: std::path::PathBuf,
        /// The program's dialect: iso (LinuxCNC, grbl), fanuc (Fanuc/Haas
        /// G-code system A), or auto (from its words).
        #[arg(long, default_value = "auto")]
        dialect: String,
        /// X words are radii at the start (as LinuxCNC's G8), not
        /// diameters: read as `run --radius` reads it.
        #[arg(long)]
        radius: bool,
    },
    /// Draw a G-code program as an SVG picture (Z to the right, X up, equal
    /// scale, X ticks as diameters): the part as programmed, the tool tip
    /// the device ran and the nose centre, rapids dashed, refused lines
    /// marked; exit status 1 if the device refused a line.
    Plot {
        /// The G-code program.
        file: std::path::PathBuf,
        /// The SVG file to write (default: FILE with the extension .svg;
        /// `-` for standard output).
        #[arg(short, long, value_name = "OUT.svg")]
        output: Option<std::path::PathBuf>,
        /// The program's dialect: iso (LinuxCNC, grbl), fanuc (Fanuc/Haas
        /// G-code system A), or auto (from its words).
        #[arg(long, default_value = "auto")]
        dialect: String,
        /// X words are radii at the start (as LinuxCNC's G8), not diameters.
        #[arg(long)]
        radius: bool,
        /// A file of setup requests sent before the program (`TOOL N=1
        /// X=-2.5 Z=1.2 R=0.4 T=3`, `WORK G=54 Z=-120`), as for `run`.
        #[arg(long, value_name = "FILE")]
        tools: Option<std::path::PathBuf>,
        /// Show only this window (mm, X a diameter), with the chords the
        /// device cut the arcs into and its impulse steps.
        #[arg(long, value_name = "Z0,X0,Z1,X1", allow_hyphen_values = true)]
        zoom: Option<host_sim::plot::Window>,
    },
    /// The highest spindle speed a thread can be cut at: the ЭМ-907's rule
    /// (modes G06–G09) and this controller's axis feed limit. Example:
    /// `host-sim thread-speed 1.5`, `host-sim thread-speed 2 --mode G07 --cross`.
    ThreadSpeed {
        /// The thread's pitch, mm.
        #[arg(value_name = "PITCH_MM")]
        pitch: f64,
        /// The ЭМ-907 mode: G06, G07, G08 or G09 (the pitch word ×1, ×2, ×4,
        /// ×8; capped at 240, 480, 960, 1920 rpm); default the fastest the
        /// pitch allows.
        #[arg(long)]
        mode: Option<String>,
        /// A thread across (X, 0.005 mm impulses) rather than along Z.
        #[arg(long)]
        cross: bool,
        /// The axis' feed limit for this controller's rule, mm/min (default
        /// the power-on LIMITS: VZ 3000, VX 1500).
        #[arg(long, value_name = "MM_PER_MIN")]
        feed_limit: Option<f64>,
        #[command(flatten)]
        out: host_sim::table::OutArgs,
    },
    /// Set up a trihedral corner on a tilt-rotary table (Lyakun & Yurkevich,
    /// exact spherical trigonometry): the cutter angle φ, the table's
    /// rotation and tilt, the edges, the rows, Z min; `--gcode` prints the
    /// program (a main program and a row subprogram). Example: `host-sim
    /// trihedral 90 90 90 --step 0.5 --rows 20 --lengths 10,10,12`.
    Trihedral {
        /// Plane angle AOB (the base face), degrees; `-` when not given (then
        /// a linear angle instead, `--linear`).
        #[arg(allow_hyphen_values = true)]
        aob: String,
        /// Plane angle BOC, degrees, or `-`.
        #[arg(allow_hyphen_values = true)]
        boc: String,
        /// Plane angle COA, degrees, or `-`.
        #[arg(allow_hyphen_values = true)]
        coa: String,
        /// Linear (dihedral) angles at OA, OB, OC in degrees, `-` for one not
        /// given: three angles in all fix the corner (e.g. `90 90 - --linear
        /// -,90,-`).
        #[arg(long, value_name = "OA,OB,OC")]
        linear: Option<String>,
        /// The step between rows in Z (h), mm.
        #[arg(long, default_value_t = 0.5)]
        step: f64,
        /// The number of rows (КОН).
        #[arg(long, default_value_t = 10)]
        rows: u16,
        /// The lengths milled along OA, OB, OC, mm.
        #[arg(long, value_name = "LA,LB,LC", default_value = "10,10,10")]
        lengths: String,
        /// The radius of the fillet along OC left by pre-milling, mm.
        #[arg(long, default_value_t = 0.0)]
        fillet: f64,
        /// The table's parameters L (tilt axis to the rotation axis) and m
        /// (table surface to the tilt axis), mm.
        #[arg(long, value_name = "L,M", default_value = "0,0")]
        table: String,
        /// E: the angle of ray OA to X, degrees.
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        e: f64,
        /// k_v: the quadrant of the base face, 1 to 4.
        #[arg(long, default_value_t = 1)]
        quadrant: u8,
        /// The vertex in the part's frame, mm.
        #[arg(
            long,
            value_name = "X,Y,Z",
            default_value = "0,0,0",
            allow_hyphen_values = true
        )]
        vertex: String,
        /// The paper's proportional central angles, for comparison only.
        #[arg(long)]
        proportional: bool,
        /// Print the program instead of the tables.
        #[arg(long)]
        gcode: bool,
        #[command(flatten)]
        out: host_sim::table::OutArgs,
    },
    /// Deflection of a part between centres and the "mirror image" pass
    /// (Kosenko eq. 16–31, Tables 7–9): x, compliance Σ(x), the error of an
    /// uncompensated pass, the depth and diameter to set; `--gcode` prints
    /// the compensated generatrix (Z0 at the tailstock face). Example:
    /// `host-sim deflection --section 29.8:100 --section 21.8:150 --depth 0.5
    /// --feed 0.2 --hardness 220 --stiffness 4000,3000,10000`.
    Deflection {
        /// A section from the headstock: DIAMETER:LENGTH, mm (repeat for a
        /// stepped shaft).
        #[arg(long = "section", value_name = "D:L", required = true)]
        sections: Vec<String>,
        /// The reduced diameter by equal volume (eq. 31: thickened on one
        /// side) rather than length-weighted (eq. 30).
        #[arg(long)]
        equal_volume: bool,
        /// Young's modulus, kgf/mm².
        #[arg(long, default_value_t = 21_000.0)]
        modulus: f64,
        /// Headstock, tailstock and saddle stiffness, kgf/mm.
        #[arg(long, value_name = "JH,JT,JS")]
        stiffness: String,
        /// The depth of cut t, mm.
        #[arg(long)]
        depth: f64,
        /// The feed S, mm/rev.
        #[arg(long, default_value_t = 0.2)]
        feed: f64,
        /// The steel's hardness, HB.
        #[arg(long, default_value_t = 200.0)]
        hardness: f64,
        /// The tool's approach angle φ, degrees (Table 8: 30, 45, 60, 75, 90).
        #[arg(long, default_value_t = 90.0)]
        approach: f64,
        /// The nose radius, mm (Table 8).
        #[arg(long, default_value_t = 1.0)]
        nose: f64,
        /// The radial force law P = C·t^x given directly, C in kgf, instead
        /// of from the tables.
        #[arg(long, value_name = "C,X")]
        force: Option<String>,
        /// The sampling step Δx, mm.
        #[arg(long, default_value_t = 10.0)]
        step: f64,
        /// The spindle speed the printed program turns at, rpm.
        #[arg(long, default_value_t = 400.0)]
        rpm: f64,
        /// Print the compensated pass as G-code instead of the table.
        #[arg(long)]
        gcode: bool,
        #[command(flatten)]
        out: host_sim::table::OutArgs,
    },
    /// Tool wear over a batch (Kosenko eq. 31–35): the cutting path per part,
    /// the wear after Q parts, the parts between re-settings and until the
    /// tool change, the radial wear from flank wear. Example: `host-sim wear
    /// --section 40:120 --feed 0.2 --initial 5 --rate 8 --parts 50
    /// --resetting 20,50`.
    Wear {
        /// A surface cut per part: DIAMETER:LENGTH, mm (repeat).
        #[arg(long = "section", value_name = "D:L", required = true)]
        sections: Vec<String>,
        /// The feed S, mm/rev.
        #[arg(long)]
        feed: f64,
        /// The initial wear u_initial, µm.
        #[arg(long, default_value_t = 0.0)]
        initial: f64,
        /// The relative wear u0, µm/km (Table 14).
        #[arg(long)]
        rate: f64,
        /// The parts Q made.
        #[arg(long, default_value_t = 1)]
        parts: u32,
        /// The wear allowed before a re-setting and the tolerance δ, µm.
        #[arg(long, value_name = "U,DELTA")]
        resetting: Option<String>,
        /// The wear at which the tool is changed, µm.
        #[arg(long, value_name = "U")]
        change_at: Option<f64>,
        /// The flank wear h (mm) and the clearance angle (degrees), for the
        /// radial wear u = h·tan α.
        #[arg(long, value_name = "H,ALPHA")]
        flank: Option<String>,
        #[command(flatten)]
        out: host_sim::table::OutArgs,
    },
    /// Punched tapes of the old controls. `verify FILE` checks a listing: a
    /// BCK-5 tape of the АТПр-2М12 (one frame per line as printed, e.g.
    /// `2K002E212400D630000П75Ш26Н`; Cyrillic letters or the Latin
    /// look-alikes, Ш as W and Я as R) for check digits, numbering and the
    /// closure of each tool (Σ+ + Σ− = 0), or an ISO-7bit tape of the
    /// ЭМ-907 (blocks starting N) block by block; it lists every failing
    /// frame and tool, exit status 1 if there is any. `encode FILE --format
    /// bck5|iso7` punches a G-code program as it runs on this device
    /// (machine coordinates, X on the radius): BCK-5 frames with check
    /// digits, Е in 0.01 mm and Д in 0.005 mm impulses, feed codes nearest
    /// S/0.6 Hz (S the feed, mm/min), Ш and В words, arcs as chords, each tool brought back to
    /// its start; or ЭМ-907 blocks (X 0.005 mm, Z 0.01 mm impulses, F =
    /// S·10³/l, arcs within one quadrant as G02/G03 with I, K). Set-up notes
    /// go to stderr; what the tape cannot hold is named with its line, exit
    /// status 1, and nothing is printed. Examples: `host-sim tape verify
    /// tape.bck5`, `host-sim tape encode part.nc --format bck5 > part.bck5`,
    /// `host-sim tape encode part.nc --format iso7 --punch`.
    Tape {
        /// What to do: `verify` or `encode`.
        #[arg(value_parser = ["verify", "encode"])]
        action: String,
        /// The tape listing (verify) or the G-code program (encode).
        file: std::path::PathBuf,
        /// encode: the tape, `bck5` (АТПр-2М12) or `iso7` (ЭМ-907).
        #[arg(long, value_parser = ["bck5", "iso7"])]
        format: Option<String>,
        /// encode, iso7: print each character as its row of holes (tracks 8
        /// to 1, track 8 the even parity, `|` the feed holes between tracks
        /// 3 and 4) instead of the text.
        #[arg(long)]
        punch: bool,
        /// encode, bck5: the largest distance of an arc's chords from the
        /// arc, mm (the control interpolates lines only).
        #[arg(long, value_name = "MM", default_value = "0.01")]
        chord: String,
        /// encode: the program's dialect: iso (LinuxCNC, grbl), fanuc
        /// (Fanuc/Haas G-code system A), or auto (from its words).
        #[arg(long, default_value = "auto")]
        dialect: String,
        /// encode: X words are radii at the start (as LinuxCNC's G8), not
        /// diameters.
        #[arg(long)]
        radius: bool,
        #[command(flatten)]
        out: host_sim::table::OutArgs,
    },
    /// Stream a G-code program to a board: a serial port (`--port
    /// /dev/ttyUSB0`), the pty of `serve --pty`, or the firmware in QEMU
    /// (`--qemu`). The program first runs on a model given the board's own
    /// settings, tool table and position (`--dry-run` stops there); then
    /// each line goes out as a reliable request with the board's queue kept
    /// filled, every reply checked against the model. Keys: `!`/h/space
    /// feed hold, `~`/c/r cycle start, q/Ctrl-C abort (hold to rest, then
    /// reset), x/Ctrl-X reset (the program restarts at the line that did
    /// not finish, the tool taken back along its path). Exit status 0 when
    /// every line ran, 1 when the program cannot run (a refused line, a
    /// reply not the model's), 3 when the link failed, 4 when aborted, 5
    /// when the board lost its position, 6 when a switch stopped it (the
    /// E-stop, a limit, a drive's fault).
    Send(SendArgs),
    /// Serve the in-process device for a terminal or another program.
    Serve {
        /// Serve on standard input and output.
        #[arg(long, conflicts_with = "pty")]
        stdio: bool,
        /// Serve on a new pseudo-terminal and print its path; standard
        /// input is then the machine's panel, a line each: `ESTOP 1|0`,
        /// `DOOR 1|0`, `PROBE 1|0`, `LIMIT X-|X+|Z-|Z+ 1|0`, `FAULT X|Z
        /// 1|0`, `HOLD`, `START`, `WHEEL n` (the handwheel turned by n
        /// detents), `MPG X|Z COUNTS=n SCALE=1|10|100` (a pendant with its
        /// own selectors), and `STATE?` (the carriage, the inputs, the
        /// spindle). Wire them first with the `INPUT` request.
        #[arg(long)]
        pty: bool,
        /// Speak the grbl 1.1 protocol from the start (for grbl senders:
        /// Universal Gcode Sender, bCNC, CNCjs); `$PENDANT` switches to the
        /// pendant protocol, its request `GRBL` back.
        #[arg(long)]
        grbl: bool,
        /// Issue the motion at once instead of on the wall clock (blocks
        /// start by the look-ahead window, every tick as on the virtual
        /// clock of `run`).
        #[arg(long, conflicts_with = "speed")]
        instant: bool,
        /// Run the step clock this many times as fast as the wall clock
        /// (default 1: real time, as a board runs).
        #[arg(long, value_name = "FACTOR", value_parser = parse_speed)]
        speed: Option<f64>,
        /// How the board reads G-code lines at power-on, as one that kept
        /// `OPT DIALECT=` (grbl `$450`) from before: iso or fanuc.
        #[arg(long, default_value = "iso", value_parser = ["iso", "fanuc"])]
        dialect: String,
        /// The lathe behind the board (TOML: each axis' travel, switches,
        /// leadscrew play and drive, the spindle and its encoder;
        /// `examples/machine.toml`): its
        /// carriages trip the switches as the steps move them, and a drive
        /// driven faster than it follows stalls and raises its fault.
        #[arg(long, value_name = "FILE")]
        machine: Option<std::path::PathBuf>,
    },
}

#[derive(clap::Args)]
struct SendArgs {
    /// The G-code program.
    file: std::path::PathBuf,
    /// The board's serial port (or the pty `serve --pty` printed).
    #[arg(long, value_name = "PATH", required_unless_present = "qemu")]
    port: Option<String>,
    /// Boot the firmware in QEMU (its step interrupt in virtual time) and
    /// send to it.
    #[arg(long, conflicts_with = "port")]
    qemu: bool,
    /// The program's dialect: iso (LinuxCNC, grbl), fanuc (Fanuc/Haas
    /// G-code system A), or auto (from its words).
    #[arg(long, default_value = "auto")]
    dialect: String,
    /// X words are radii at the start (as LinuxCNC's G8), not diameters.
    #[arg(long)]
    radius: bool,
    /// A file of setup requests sent before the program (`TOOL N=1
    /// X=-2.5 Z=1.2 R=0.4 T=3`, `WORK G=54 Z=-120`), as for `run`.
    #[arg(long, value_name = "FILE")]
    tools: Option<std::path::PathBuf>,
    /// The optional stop switch on: M01 stops as M00 does.
    #[arg(long)]
    optional_stop: bool,
    /// Check the whole program against the board's settings and stop
    /// there: nothing moves.
    #[arg(long)]
    dry_run: bool,
    /// How long to wait for a reply before asking again, ms.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(50..=60_000))]
    timeout_ms: u64,
    /// The feed the tool goes back along its path at after a reset,
    /// mm/min.
    #[arg(long, default_value = "250")]
    return_feed: String,
}

#[derive(clap::Args, Clone)]
struct ScenarioArgs {
    /// Seed of the random blocks.
    #[arg(long, default_value_t = 1977)]
    seed: u64,
    /// Number of random blocks.
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    blocks: u32,
}

#[derive(clap::Args, Clone)]
struct RunArgs {
    /// A G-code program to run (without it: the comparison).
    file: Option<std::path::PathBuf>,
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// How the host reaches the device.
    #[arg(long, value_enum, default_value_t = LinkKind::Pty)]
    link: LinkKind,
    /// The program's dialect: iso (LinuxCNC, grbl), fanuc (Fanuc/Haas
    /// G-code system A), or auto (from its words).
    #[arg(long, default_value = "auto", requires = "file")]
    dialect: String,
    /// X words are radii at the start (as LinuxCNC's G8), not diameters.
    #[arg(long, requires = "file")]
    radius: bool,
    /// Print every motion block the device ran, one per line, as G-code in
    /// machine coordinates (X a diameter, I/K from the block's start).
    #[arg(long, requires = "file")]
    trace: bool,
    /// A file of setup requests sent before the program, one per line
    /// (`TOOL N=1 X=-2.5 Z=1.2 R=0.4 T=3`, `WORK G=54 Z=-120`; `#` starts a
    /// comment): the tool table and the work offsets.
    #[arg(long, value_name = "FILE", requires = "file")]
    tools: Option<std::path::PathBuf>,
    /// The optional stop switch on: M01 stops as M00 does.
    #[arg(long, requires = "file")]
    optional_stop: bool,
    /// Also write one self-contained HTML page of the run (no scripts, no
    /// other files): the facts printed here as tables (cycle time, travel,
    /// step events, tools, program stops, refused lines with the device's
    /// reason), the picture `plot` draws, and the speed along the path over
    /// time as the device timed it (mm/min over s; rapids, feeds, the
    /// commanded F, dwells).
    #[arg(long, value_name = "OUT.html", requires = "file")]
    report: Option<std::path::PathBuf>,
    /// The lathe behind the board (TOML: each axis' travel, switches,
    /// leadscrew play and drive; `examples/machine.toml`): its inputs are
    /// wired, its carriages follow the step events and trip the switches
    /// from their own positions. A limit, a drive's stall or a carriage
    /// past the end of its travel stops the program there (exit status
    /// 6), naming the line and where the carriages were; otherwise the
    /// run says how far the carriages went and where they ended against
    /// the registers (the leadscrews' play not taken up shows there).
    #[arg(long, value_name = "FILE", requires = "file")]
    machine: Option<std::path::PathBuf>,
}

impl Default for RunArgs {
    fn default() -> Self {
        RunArgs {
            file: None,
            scenario: ScenarioArgs {
                seed: 1977,
                blocks: 10_000,
            },
            link: LinkKind::Pty,
            dialect: "auto".into(),
            radius: false,
            trace: false,
            tools: None,
            optional_stop: false,
            report: None,
            machine: None,
        }
    }
}

#[derive(clap::Args, Clone)]
struct SoakArgs {
    /// Blocks to run (with their price, mode and zero changes).
    #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u32).range(1..=100_000_000))]
    blocks: u32,
    /// Seed of the blocks and of the faults.
    #[arg(long, default_value_t = 1977)]
    seed: u64,
    /// Run against the firmware in QEMU instead of the in-process device.
    #[arg(long)]
    qemu: bool,
    /// No faults (a baseline for the speed).
    #[arg(long)]
    clean: bool,
}

#[derive(clap::Args, Clone)]
struct QemuArgs {
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// A firmware ELF built with the `qemu` feature (default: build it).
    #[arg(long)]
    elf: Option<std::path::PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum LinkKind {
    /// A pseudo-terminal pair, the host side opened with the serialport crate.
    Pty,
    /// Direct calls into the in-process device.
    Local,
}

/// `host-sim tape encode`: the tape on stdout, notes on stderr; exit 1
/// with every line the tape cannot hold (nothing printed then), 2 for a
/// file that cannot be read or bad arguments.
fn tape_encode(
    file: &std::path::Path,
    format: Option<&str>,
    punch: bool,
    chord: &str,
    dialect: &str,
    radius: bool,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let format = match format {
        Some("bck5") => host_sim::tape::Format::Bck5,
        Some("iso7") => host_sim::tape::Format::Iso7,
        _ => return Err("tape encode: --format bck5 or --format iso7".into()),
    };
    if punch && format == host_sim::tape::Format::Bck5 {
        return Err(
            "tape encode: --punch shows the rows of the ISO-7bit tape (--format iso7)".into(),
        );
    }
    let chord = core_nostd::length::Length::from_mm_str(chord)
        .ok()
        .filter(|l| l.as_angstrom() > 0)
        .ok_or_else(|| format!("--chord {chord}: not a positive number of mm"))?;
    let (program, dialect) = read_program(file, dialect)?;
    let job = host_sim::tape::Job {
        format,
        dialect,
        radius,
        chord,
        punch,
    };
    match host_sim::tape::encode(&program, &job) {
        Ok(tape) => {
            for n in &tape.notes {
                eprintln!("{}: {n}", file.display());
            }
            std::io::stdout().write_all(tape.text.as_bytes())?;
            Ok(ExitCode::SUCCESS)
        }
        Err(errors) => {
            for e in &errors {
                eprintln!("{}: {e}", file.display());
            }
            Ok(ExitCode::from(1))
        }
    }
}

/// Reads a G-code program and settles its dialect (`auto` from its words,
/// the reason on stderr).
fn read_program(
    file: &std::path::Path,
    dialect: &str,
) -> Result<(String, core_nostd::gcode::Dialect), Box<dyn std::error::Error>> {
    let f = file.display();
    let bytes = std::fs::read(file).map_err(|e| format!("cannot read {f}: {e}"))?;
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let (dialect, note) =
        host_sim::dialect::choose(dialect, &text).map_err(|e| format!("{f}: {e}"))?;
    if let Some(note) = note {
        eprintln!("{f}: {note}");
    }
    for (line, note) in host_sim::program::framing(&text).notes() {
        eprintln!("{f}:{line}: note: {note}");
    }
    Ok((text, dialect))
}

/// `host-sim compensate`: the program on stdout, remarks and refusals on
/// stderr; exit 1 when the program is refused (nothing is printed then).
fn compensate(
    file: &std::path::Path,
    rn: String,
    tip: u8,
    diam: bool,
    dialect: &str,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let (program, dialect) = read_program(file, dialect)?;
    let settings = host_sim::compensate::Settings {
        rn,
        tip,
        diam,
        dialect,
    };
    let program = host_sim::program::framing(&program).apply(&program);
    match host_sim::compensate::compensate(&program, &settings) {
        Ok(out) => {
            for w in &out.warnings {
                eprintln!("{}: {w}", file.display());
            }
            std::io::stdout().write_all(out.text.as_bytes())?;
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => {
            eprintln!("{}: {e}", file.display());
            Ok(ExitCode::from(1))
        }
    }
}

/// `host-sim plot`: the picture written to a file (or standard output),
/// refusals and remarks on stderr; exit 1 when the device refused a line
/// (the picture marks it).
fn plot(
    file: &std::path::Path,
    output: Option<std::path::PathBuf>,
    dialect: &str,
    radius: bool,
    tools: Option<&std::path::Path>,
    zoom: Option<host_sim::plot::Window>,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let f = file.display();
    let (text, dialect) = read_program(file, dialect)?;
    let setup_text = match tools {
        Some(path) => std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?,
        None => String::new(),
    };
    let setup = host_sim::program::setup_lines(&setup_text);
    let options = host_sim::plot::Options {
        program: host_sim::program::Options {
            dialect,
            radius,
            optional_stop: false,
        },
        zoom,
    };
    let paths = host_sim::plot::trace(&text, &options, &setup);
    if let Some(e) = &paths.expand_error {
        eprintln!("{f}:{e}");
        return Ok(ExitCode::from(1));
    }
    let setup_name = tools.map_or(String::new(), |p| p.display().to_string());
    for r in &paths.setup_refused {
        eprintln!("{setup_name}:{}: {}", r.line, r.reply);
    }
    for m in &paths.refused {
        eprintln!("{f}:{}: {}", m.line, m.reply);
    }
    for n in &paths.notes {
        eprintln!("{f}: {n}");
    }
    let picture = host_sim::plot::render(&paths, &f.to_string(), zoom)?;
    let out = output.unwrap_or_else(|| file.with_extension("svg"));
    if out.as_os_str() == "-" {
        std::io::stdout().write_all(picture.svg.as_bytes())?;
    } else {
        std::fs::write(&out, &picture.svg)
            .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        eprintln!(
            "{f}: {} blocks drawn, {} refused: {}",
            paths.tip.len(),
            paths.refused.len(),
            out.display()
        );
    }
    Ok(
        if paths.refused.is_empty() && paths.setup_refused.is_empty() {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(1)
        },
    )
}

fn check(
    file: &std::path::Path,
    dialect: &str,
    radius: bool,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let bytes = std::fs::read(file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    let text = String::from_utf8_lossy(&bytes);
    let (dialect, note) = host_sim::dialect::choose(dialect, &text)
        .map_err(|e| format!("{}: {e}", file.display()))?;
    if let Some(note) = note {
        println!("{}: {note}", file.display());
    }
    let items = host_sim::check::check_read(&text, dialect, radius);
    for i in &items {
        println!("{}:{}:{}: {}", file.display(), i.line, i.column, i.what);
    }
    for w in host_sim::check::warnings_in(&text, dialect) {
        println!(
            "{}:{}:{}: warning: {}",
            file.display(),
            w.line,
            w.column,
            w.what
        );
    }
    if items.is_empty() {
        println!("{}: every line is one the device reads", file.display());
        Ok(ExitCode::SUCCESS)
    } else {
        let n = items.len();
        let lines = if n == 1 { "line" } else { "lines" };
        println!("{}: {n} {lines} the device would refuse", file.display());
        Ok(ExitCode::from(1))
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command.unwrap_or(Command::Run(RunArgs::default())) {
        Command::Run(args) => run(&args),
        Command::Qemu(args) => run_qemu(&args),
        Command::QemuBench => qemu_bench(),
        Command::Soak(args) => run_soak(&args),
        Command::Compensate {
            file,
            rn,
            tip,
            radius,
            dialect,
        } => compensate(&file, rn, tip, !radius, &dialect),
        Command::Check {
            file,
            dialect,
            radius,
        } => check(&file, &dialect, radius),
        Command::Plot {
            file,
            output,
            dialect,
            radius,
            tools,
            zoom,
        } => plot(&file, output, &dialect, radius, tools.as_deref(), zoom),
        Command::ThreadSpeed {
            pitch,
            mode,
            cross,
            feed_limit,
            out,
        } => {
            let limit = feed_limit.unwrap_or(if cross { 1500.0 } else { 3000.0 });
            emit(
                host_sim::calculators::thread_speed(pitch, mode.as_deref(), cross, limit)
                    .map(|r| (r, String::new())),
                out,
                false,
            )
        }
        Command::Trihedral {
            aob,
            boc,
            coa,
            linear,
            step,
            rows,
            lengths,
            fillet,
            table,
            e,
            quadrant,
            vertex,
            proportional,
            gcode,
            out,
        } => emit(
            trihedral_args(
                &[aob, boc, coa],
                linear.as_deref(),
                &lengths,
                &table,
                &vertex,
            )
            .and_then(|(angles, lengths, table, vertex)| {
                host_sim::calculators::trihedral(
                    angles,
                    &host_sim::calculators::TrihedralJob {
                        step_mm: step,
                        rows,
                        lengths_mm: lengths,
                        fillet_mm: fillet,
                        table,
                        e_deg: e,
                        quadrant,
                        vertex,
                        proportional,
                    },
                )
            }),
            out,
            gcode,
        ),
        Command::Deflection {
            sections,
            equal_volume,
            modulus,
            stiffness,
            depth,
            feed,
            hardness,
            approach,
            nose,
            force,
            step,
            rpm,
            gcode,
            out,
        } => emit(
            (|| {
                let job = host_sim::calculators::DeflectionJob {
                    sections: sections
                        .iter()
                        .map(|s| host_sim::calculators::parse_section(s))
                        .collect::<Result<_, _>>()?,
                    equal_volume,
                    modulus,
                    stiffness: numbers::<3>("stiffness", &stiffness)?,
                    depth_mm: depth,
                    feed_mm_rev: feed,
                    hardness_hb: hardness,
                    approach_deg: approach,
                    nose_mm: nose,
                    force: force
                        .as_deref()
                        .map(|f| numbers::<2>("force", f).map(|[c, x]| (c, x)))
                        .transpose()?,
                    step_mm: step,
                    rpm,
                };
                host_sim::calculators::deflection(&job)
            })(),
            out,
            gcode,
        ),
        Command::Wear {
            sections,
            feed,
            initial,
            rate,
            parts,
            resetting,
            change_at,
            flank,
            out,
        } => emit(
            (|| {
                let job = host_sim::calculators::WearJob {
                    sections: sections
                        .iter()
                        .map(|s| host_sim::calculators::parse_section(s))
                        .collect::<Result<_, _>>()?,
                    feed_mm_rev: feed,
                    initial_um: initial,
                    rate_um_per_km: rate,
                    parts,
                    resetting: resetting
                        .as_deref()
                        .map(|r| numbers::<2>("resetting", r).map(|[u, d]| (u, d)))
                        .transpose()?,
                    full_um: change_at,
                    flank: flank
                        .as_deref()
                        .map(|f| numbers::<2>("flank", f).map(|[h, a]| (h, a)))
                        .transpose()?,
                };
                host_sim::calculators::wear(&job).map(|r| (r, String::new()))
            })(),
            out,
            false,
        ),
        Command::Tape {
            action,
            file,
            format,
            punch,
            chord,
            dialect,
            radius,
            out,
        } => {
            if action == "encode" {
                tape_encode(&file, format.as_deref(), punch, &chord, &dialect, radius)
            } else if format.is_some() || punch {
                Err("tape verify: --format and --punch are for tape encode".into())
            } else {
                match std::fs::read_to_string(&file) {
                    Ok(text) => {
                        let (report, findings) = host_sim::calculators::tape_verify(&text);
                        print!("{}", report.render(out.format()));
                        Ok(ExitCode::from(u8::from(findings > 0)))
                    }
                    Err(e) => Err(format!("cannot read {}: {e}", file.display()).into()),
                }
            }
        }
        Command::Send(args) => send_program(&args),
        Command::Serve {
            stdio: _,
            pty,
            grbl,
            instant,
            speed,
            dialect,
            machine,
        } => {
            let fanuc = dialect == "fanuc";
            let lathe = match machine {
                Some(path) => {
                    let text = std::fs::read_to_string(&path)
                        .map_err(|e| format!("cannot read {}: {e}", path.display()));
                    match text.and_then(|t| {
                        host_sim::lathe::MachineFile::parse(&t)
                            .map_err(|e| format!("{}: {e}", path.display()))
                    }) {
                        Ok(m) => Some(m),
                        Err(e) => {
                            eprintln!("host-sim: {e}");
                            return ExitCode::from(2);
                        }
                    }
                }
                None => None,
            };
            let pace = if instant {
                host_sim::board::Pace::Unpaced
            } else {
                host_sim::board::Pace::Wall(speed.unwrap_or(1.0))
            };
            if pty {
                serve_pty(grbl, fanuc, pace, lathe)
            } else {
                serve_stdio(grbl, fanuc, pace, lathe)
            }
        }
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("host-sim: {e}");
            ExitCode::from(2)
        }
    }
}

/// `--speed FACTOR`: a positive, finite factor.
fn parse_speed(v: &str) -> Result<f64, String> {
    match v.parse::<f64>() {
        Ok(f) if f.is_finite() && f > 0.0 && f <= 1e6 => Ok(f),
        _ => Err(format!("{v}: not a speed factor above 0 (up to 1000000)")),
    }
}

/// A device at power-on, speaking grbl from the start when asked (its
/// banner goes out when a sender opens the link), reading Fanuc when it
/// kept that from before.
fn board_device(grbl: bool, fanuc: bool) -> core_nostd::protocol::Device {
    struct Nowhere;
    impl core_nostd::protocol::Io for Nowhere {
        fn send(&mut self, _: &[u8]) {}
    }
    let mut device = core_nostd::protocol::Device::new();
    if fanuc {
        let mut kept = core_nostd::interp::Offsets::ZERO;
        kept.reading.dialect = core_nostd::gcode::Dialect::Fanuc;
        device.restore_offsets(kept);
    }
    device.set_grbl(grbl, &mut Nowhere);
    device
}

fn serve_stdio(
    grbl: bool,
    fanuc: bool,
    pace: host_sim::board::Pace,
    lathe: Option<host_sim::lathe::MachineFile>,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    if grbl {
        let mut out = std::io::stdout();
        out.write_all(core_nostd::protocol::grbl::BANNER)?;
        out.flush()?;
    }
    let mut stdin = std::io::stdin();
    let read = move |buf: &mut [u8]| loop {
        match stdin.read(buf) {
            Ok(n) => return Ok(Some(n)),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    };
    let board = host_sim::board::Board::serve(
        board_device(grbl, fanuc),
        pace,
        read,
        std::io::stdout(),
        false,
    );
    if let Some(m) = lathe {
        board.set_lathe(m);
    }
    board.wait();
    Ok(ExitCode::SUCCESS)
}

/// `host-sim send FILE`.
fn send_program(args: &SendArgs) -> Result<ExitCode, Box<dyn std::error::Error>> {
    use host_sim::send::{board_settings, Console, Halt, Plan, Sender};
    let file = &args.file;
    let f = file.display();
    let (text, dialect) = read_program(file, &args.dialect)?;
    let options = host_sim::program::Options {
        dialect,
        radius: args.radius,
        optional_stop: args.optional_stop,
    };
    let setup_text = match &args.tools {
        Some(path) => std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?,
        None => String::new(),
    };
    let setup = host_sim::program::setup_lines(&setup_text);
    let timeout = Duration::from_millis(args.timeout_ms);
    // Checked now, not at the first restart.
    if !core_nostd::length::Length::from_mm_str(&args.return_feed)
        .is_ok_and(|f| f.as_angstrom() >= 10_000 && f.as_angstrom() <= 999_999_990_000)
    {
        return Err(format!(
            "--return-feed {}: not a feed of 0.001 to 99999.999 mm/min",
            args.return_feed
        )
        .into());
    }
    let mut qemu = None;
    let client = if args.qemu {
        let elf = host_sim::qemu::build_firmware("qemu-paced")?;
        let q = qemu.insert(host_sim::qemu::Qemu::boot_paced(&elf)?);
        eprintln!("board: {} in QEMU, USART1 on {}", elf.display(), q.pty());
        q.connect(Duration::from_secs(60))?
    } else {
        let port = args.port.as_deref().unwrap_or_default();
        Client::open(port, timeout).map_err(|e| format!("cannot open {port}: {e}"))?
    };
    let token = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(1, |d| d.subsec_nanos() | 1);
    let halt = |h: Halt| -> Box<dyn std::error::Error> { h.to_string().into() };
    let mut sender = Sender::new(client, timeout, token).map_err(halt)?;
    sender.return_feed = args.return_feed.clone();
    let settings = board_settings(&mut sender).map_err(halt)?;
    let plan = Plan::build(&text, options, &settings, &setup).map_err(|e| format!("{f}: {e}"))?;
    let setup_name = args
        .tools
        .as_ref()
        .map_or(String::new(), |p| p.display().to_string());
    for r in &plan.setup_refused {
        eprintln!("{setup_name}:{}: {}", r.line, r.reply);
    }
    for r in &plan.refused {
        eprintln!("{f}:{}: {}", r.line, r.reply);
    }
    println!(
        "{f}: {} lines, {} step events, planned motion {}",
        plan.lines.len(),
        plan.events(),
        host_sim::program::minutes(plan.total_us)
    );
    if !plan.refused.is_empty() || !plan.setup_refused.is_empty() {
        println!("the board would refuse the lines above: nothing sent");
        return Ok(ExitCode::from(1));
    }
    if args.dry_run {
        println!("dry run: the board accepts every line; nothing sent");
        return Ok(ExitCode::SUCCESS);
    }
    let report = {
        let mut console = Console::new(plan.lines.len());
        sender.send(&plan, &mut console)
    };
    drop(qemu);
    println!(
        "{} lines answered in {:.1} s ({:.0} lines/s); starved {}; {} restarts after a reset, {} requests sent again, {} reply lines dropped",
        report.requests,
        report.seconds,
        report.requests as f64 / report.seconds.max(1e-9),
        report
            .starved
            .map_or("-".to_string(), |n| n.to_string()),
        report.resets,
        report.retries,
        report.dropped
    );
    if let Some((px, pz)) = report.registers {
        println!(
            "registers at the end: board PX={px} PZ={pz}, program PX={} PZ={}",
            report.expected.0, report.expected.1
        );
    }
    let code = match &report.halt {
        None if report.registers == Some(report.expected) => {
            println!("{f}: done");
            0
        }
        None => {
            println!("{f}: the board did not end where the program does");
            1
        }
        Some(h) => {
            eprintln!("{f}: {h}");
            match h {
                Halt::Refused(..) | Halt::Mismatch(..) => 1,
                Halt::Link(_) | Halt::Board(_) => 3,
                Halt::Aborted(_) => 4,
                Halt::PowerLost => 5,
                Halt::Stopped(_) => 6,
            }
        }
    };
    Ok(ExitCode::from(code))
}

fn serve_pty(
    grbl: bool,
    fanuc: bool,
    pace: host_sim::board::Pace,
    lathe: Option<host_sim::lathe::MachineFile>,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    let (path, board) = host_sim::board::serve_pty(board_device(grbl, fanuc), pace)?;
    if let Some(m) = lathe {
        board.set_lathe(m);
    }
    let clock = match pace {
        host_sim::board::Pace::Unpaced => "motion at once".to_string(),
        host_sim::board::Pace::Wall(1.0) => "motion in real time".to_string(),
        host_sim::board::Pace::Wall(f) => format!("motion at {f}× real time"),
    };
    println!("device on {path} (115200 8N1, {clock}); Ctrl-C ends");
    std::io::stdout().flush()?;
    // Standard input is the machine's panel: its switches, and STATE?.
    for line in std::io::stdin().lines() {
        let Ok(line) = line else { break };
        match board.panel_line(&line) {
            Ok(Some(answer)) => println!("{answer}"),
            Ok(None) => {}
            Err(e) => eprintln!("host-sim: panel: {e}"),
        }
        std::io::stdout().flush()?;
    }
    board.wait();
    Ok(ExitCode::SUCCESS)
}

/// `host-sim run FILE`: the report on stdout (the trace first, when asked),
/// exit 1 when the device refused a line.
fn run_program(
    file: &std::path::Path,
    args: &RunArgs,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    use host_sim::program::minutes;
    let (text, dialect) = read_program(file, &args.dialect)?;
    let f = file.display();
    let options = host_sim::program::Options {
        dialect,
        radius: args.radius,
        optional_stop: args.optional_stop,
    };
    let setup_text = match &args.tools {
        Some(path) => std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?,
        None => String::new(),
    };
    let setup = host_sim::program::setup_lines(&setup_text);
    let setup_name = args
        .tools
        .as_ref()
        .map_or(String::new(), |p| p.display().to_string());
    let machine = match &args.machine {
        Some(path) => {
            let t = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
            Some(
                host_sim::lathe::MachineFile::parse(&t)
                    .map_err(|e| format!("{}: {e}", path.display()))?,
            )
        }
        None => None,
    };
    if let Some(m) = &machine {
        if args.report.is_some() {
            return Err("--report and --machine: one at a time".into());
        }
        let (r, run) = host_sim::program::run_machine(&text, options, &setup, m);
        let name = args
            .machine
            .as_ref()
            .map_or(String::new(), |p| p.display().to_string());
        return Ok(machine_report(
            &f.to_string(),
            &name,
            &setup_name,
            &setup,
            &r,
            &run,
        ));
    }
    // With a page asked for, the run it shows is the one reported here.
    let (r, page) = match &args.report {
        Some(out) => {
            let (html, r) =
                host_sim::report::build(&f.to_string(), &text, options, &setup, &setup_name)?;
            (r, Some((out, html)))
        }
        None => (host_sim::program::run_setup(&text, options, &setup), None),
    };
    // The page is written after the text report, which comes first.
    let write_page = || -> Result<(), String> {
        match &page {
            Some((out, html)) => std::fs::write(out, html)
                .map_err(|e| format!("cannot write the report {}: {e}", out.display())),
            None => Ok(()),
        }
    };
    if args.trace {
        for block in &r.trace {
            println!("{block}");
        }
    }
    if let Some(e) = &r.expand_error {
        eprintln!("{f}:{e}");
        write_page()?;
        return Ok(ExitCode::from(1));
    }
    print_refused(&f.to_string(), &setup_name, &setup, &r);
    for (line, code) in &r.stops {
        eprintln!("{f}:{line}: {code} program stop: cycle start pressed");
    }
    let report = |s: String| {
        if args.trace {
            eprintln!("{s}");
        } else {
            println!("{s}");
        }
    };
    report(format!(
        "{f}: {} blocks run, {} refused",
        r.blocks,
        r.refused.len()
    ));
    report(format!(
        "cycle time {} (motion {}, dwells {})",
        minutes(r.cycle_us()),
        minutes(r.motion_us),
        minutes(r.dwell_us)
    ));
    report(format!(
        "travel: {:.3} mm at feed, {:.3} mm rapid; {} step events",
        r.feed_mm, r.rapid_mm, r.events
    ));
    if let Some(line) = cycles_line(&r.cycles) {
        report(line);
    }
    let tools: Vec<String> = r
        .tools
        .iter()
        .map(|(line, t)| format!("{t} (line {line})"))
        .collect();
    report(format!(
        "tools: {}",
        if tools.is_empty() {
            "none named".to_string()
        } else {
            tools.join(", ")
        }
    ));
    if let Some((out, html)) = &page {
        write_page()?;
        report(format!("report: {} ({} bytes)", out.display(), html.len()));
    }
    Ok(if r.refused.is_empty() && r.setup_refused.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// `run`'s line on the canned cycles: the time of each kind, how many ran
/// and on which lines (`cycles: roughing 0:41.250 (1, line 23), finishing
/// 0:12.004 (1, line 54)`); none when no cycle ran.
fn cycles_line(cycles: &[host_sim::program::CycleRun]) -> Option<String> {
    let mut kinds: Vec<(&str, Option<u64>, Vec<usize>)> = Vec::new();
    for c in cycles {
        let i = match kinds.iter().position(|k| k.0 == c.kind) {
            Some(i) => i,
            None => {
                kinds.push((c.kind, Some(0), Vec::new()));
                kinds.len() - 1
            }
        };
        let k = &mut kinds[i];
        k.1 = k.1.zip(c.us).map(|(a, b)| a + b);
        if k.2.last() != Some(&c.line) {
            k.2.push(c.line);
        }
    }
    if kinds.is_empty() {
        return None;
    }
    let parts: Vec<String> = kinds
        .iter()
        .map(|(kind, us, lines)| {
            let n = cycles.iter().filter(|c| c.kind == *kind).count();
            let mut at: Vec<String> = lines.iter().take(6).map(usize::to_string).collect();
            if lines.len() > 6 {
                at.push("…".into());
            }
            let word = if lines.len() == 1 { "line" } else { "lines" };
            let time = us.map_or("time not known".to_string(), host_sim::program::minutes);
            format!("{kind} {time} ({n}, {word} {})", at.join(", "))
        })
        .collect();
    Some(format!("cycles: {}", parts.join(", ")))
}

/// The setup requests and the program's lines the device refused, on
/// stderr, each with its file and line.
fn print_refused(
    f: &str,
    setup_name: &str,
    setup: &[(usize, &str)],
    r: &host_sim::program::Report,
) {
    for refused in &r.setup_refused {
        let request = setup
            .iter()
            .find(|(l, _)| *l == refused.line)
            .map_or("", |(_, q)| q);
        eprintln!(
            "{setup_name}:{}: {request}: {}",
            refused.line, refused.reply
        );
    }
    for refused in &r.refused {
        eprintln!("{f}:{}: {}", refused.line, refused.reply);
    }
}

/// `run --machine`'s report: the refused lines, then what the lathe met.
fn machine_report(
    f: &str,
    name: &str,
    setup_name: &str,
    setup: &[(usize, &str)],
    r: &host_sim::program::Report,
    run: &host_sim::program::MachineRun,
) -> ExitCode {
    use core_nostd::inputs::{Input, ALL};
    if let Some(e) = &r.expand_error {
        eprintln!("{f}:{e}");
        return ExitCode::from(1);
    }
    print_refused(f, setup_name, setup, r);
    // mm to 4 decimals, without a minus on a zero.
    let mm = |v: f64| format!("{:.4}", (v * 1e4).round() / 1e4 + 0.0);
    let at = |c: [f64; 2]| format!("X{} Z{}", mm(c[0]), mm(c[1]));
    if let Some((line, rpm, top)) = run.over_top {
        eprintln!(
            "{f}:{line}: warning: S{rpm} is above the spindle's top speed: it turns at {top} rpm"
        );
    }
    if let Some(t) = &run.trip {
        let what: Vec<String> = ALL
            .iter()
            .filter(|i| t.inputs & i.bit() != 0)
            .map(|i| match i {
                Input::FaultX => "the X drive stalled (FAULTX)".to_string(),
                Input::FaultZ => "the Z drive stalled (FAULTZ)".to_string(),
                i => format!("limit {} tripped", i.name()),
            })
            .collect();
        let what = if what.is_empty() {
            "a carriage ran past the end of its travel (no switch there: it would hit the stop)"
                .to_string()
        } else {
            what.join(", ")
        };
        let place = match t.line {
            Some(line) => format!("{f}:{line}"),
            None if t.event == 0 => format!("{f}: before the first line"),
            None => format!("{f}: at the end"),
        };
        // The alarm's number (its line's registers are what the board
        // had issued ahead on the virtual clock, not where it stopped).
        let code = host_sim::link::words_value(&t.alarm, "CODE")
            .map_or(String::new(), |c| format!("; the board's alarm {c}"));
        eprintln!(
            "{place}: {what}, the carriages at {} (machine mm, X on the radius){code}; the program stopped there, {} not sent",
            at(t.carriage),
            match t.lines_left {
                1 => "1 line".to_string(),
                n => format!("{n} lines"),
            }
        );
    }
    let [[x0, x1], [z0, z1]] = run.range;
    let ran = if run.trip.is_some() {
        "lines sent before it stopped"
    } else {
        "blocks run"
    };
    println!(
        "{f}: {} {ran}, {} refused on {name}",
        r.blocks,
        r.refused.len()
    );
    println!(
        "carriages went X {} to {}, Z {} to {} (machine mm, X on the radius)",
        mm(x0),
        mm(x1),
        mm(z0),
        mm(z1)
    );
    if run.trip.is_some() {
        // Stopped at once: the registers hold what the board had issued.
        return ExitCode::from(6);
    }
    let off = [
        run.carriage[0] - run.registers[0],
        run.carriage[1] - run.registers[1],
    ];
    let play = if off.iter().any(|d| d.abs() > 1e-6) {
        format!(
            " (off by X{} Z{}: the leadscrews' play not taken up, see BACKLASH, or a drive that lost steps)",
            mm(off[0]),
            mm(off[1])
        )
    } else {
        String::new()
    };
    println!(
        "carriages ended at {}, the registers at {}{play}",
        at(run.carriage),
        at(run.registers)
    );
    if r.refused.is_empty() && r.setup_refused.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

fn run(args: &RunArgs) -> Result<ExitCode, Box<dyn std::error::Error>> {
    if let Some(file) = &args.file {
        return run_program(file, args);
    }
    println!("Lathe retrofit controller: device against the f64 reference, bit for bit");
    match args.link {
        LinkKind::Pty => {
            let device = PtyDevice::start()?;
            println!(
                "link: in-process device on {} ({} 8N1, serialport)",
                device.path(),
                host_sim::link::BAUD
            );
            let client = Client::open(device.path(), Duration::from_secs(10))?;
            let code = compare_all(client, &args.scenario)?;
            drop(device);
            Ok(code)
        }
        LinkKind::Local => {
            println!("link: in-process device, direct calls");
            Ok(compare_all(LocalDevice::new(), &args.scenario)?)
        }
    }
}

fn run_qemu(args: &QemuArgs) -> Result<ExitCode, Box<dyn std::error::Error>> {
    println!("Lathe retrofit controller: firmware in QEMU against the f64 reference, bit for bit");
    let elf = match &args.elf {
        Some(p) => p.clone(),
        None => host_sim::qemu::build_firmware("qemu")?,
    };
    let mut qemu = host_sim::qemu::Qemu::boot(&elf, true)?;
    println!(
        "link: {} on netduinoplus2, USART1 on {} ({} 8N1, serialport)",
        elf.display(),
        qemu.pty(),
        host_sim::link::BAUD
    );
    let mut client = qemu.connect(Duration::from_secs(60))?;
    let n = 1000;
    let t0 = Instant::now();
    for _ in 0..n {
        let r = client.request("POS")?;
        if !r.is_ok() {
            return Err(format!("POS refused: {}", r.last).into());
        }
    }
    println!(
        "link: {:.0} request lines/s (POS round trips)",
        f64::from(n) / t0.elapsed().as_secs_f64()
    );
    let code = compare_all(client, &args.scenario)?;
    drop(qemu);
    let paced = paced_qemu(args.scenario.seed)?;
    let calculators = calculators_qemu()?;
    Ok(if paced && calculators {
        code
    } else {
        ExitCode::FAILURE
    })
}

/// The controller's one image in QEMU answers every
/// calculator request as the in-process device does.
fn calculators_qemu() -> Result<bool, Box<dyn std::error::Error>> {
    let elf = host_sim::qemu::build_firmware("qemu")?;
    let mut qemu = host_sim::qemu::Qemu::boot(&elf, true)?;
    let mut client = qemu.connect(Duration::from_secs(60))?;
    let session = host_sim::scenario::calculator_session();
    let expected = host_sim::device::LocalDevice::new().feed(&session);
    let got = host_sim::qemu::one_by_one(&mut client, &session)?;
    let requests = session.iter().filter(|&&b| b == b'\n').count();
    let lines = got.iter().filter(|&&b| b == b'\n').count();
    let equal = got == expected;
    println!(
        "calculators on the one image (THREAD, WEAR, DEFLECT, TRI, TAPE): {requests} requests, {lines} reply lines, {}",
        if equal {
            "identical to the in-process device"
        } else {
            "DIFFERENT from the in-process device"
        }
    );
    Ok(equal)
}

/// The step interrupt in time: a program streamed to the paced firmware
/// (events on their ticks of TIM2) as a host keeps the queue filled, then a
/// hold, a resume and a reset in the middle of a run.
fn paced_qemu(seed: u64) -> Result<bool, Box<dyn std::error::Error>> {
    let elf = host_sim::qemu::build_firmware("qemu-paced")?;
    let mut running = Vec::new();
    let n = 500;
    let r = host_sim::stream::paced_proof(
        || {
            let mut q = host_sim::qemu::Qemu::boot_paced(&elf)?;
            let c = q.connect(Duration::from_secs(60))?;
            running.push(q);
            Ok(c)
        },
        seed,
        n,
    )?;
    println!(
        "paced firmware: {} requests ({n} motion requests: feeds, rapids, arcs by chords), {} step events streamed in {:.1} s, {} replies differ from the in-process device",
        r.requests,
        r.events,
        r.seconds,
        r.mismatches.len()
    );
    println!("  SYNC firmware:   {}", r.sync.0);
    println!("  SYNC in-process: {}", r.sync.1);
    println!(
        "  feed hold mid-run: at rest on PX={} PZ={} = the program's position after {} events; after the resume {} / {} (in-process {} / {})",
        r.held_at.0,
        r.held_at.1,
        r.held_prefix.map_or("no".to_string(), |k| k.to_string()),
        r.after_hold.0,
        r.after_hold.1,
        r.after_hold_expected.0,
        r.after_hold_expected.1
    );
    println!(
        "  reset mid-run: {} ({})",
        r.reset_line,
        if r.reset_consistent {
            "the registers are the steps issued of that block"
        } else {
            "NOT the program's steps"
        }
    );
    let passed = r.passed() && r.sync.0.ends_with(" STARVED=0");
    println!("RESULT paced: {}", if passed { "pass" } else { "FAIL" });
    Ok(passed)
}

fn run_soak(args: &SoakArgs) -> Result<ExitCode, Box<dyn std::error::Error>> {
    use host_sim::reliable::{FaultInjector, Faults, LocalLink};
    let faults = if args.clean {
        Faults {
            flip: 0.0,
            drop: 0.0,
            dup: 0.0,
            noise: 0.0,
            reset: 0.0,
        }
    } else {
        Faults::HARSH
    };
    let bar = blocks_bar(u64::from(args.blocks));
    let (report, stats, corrupted) = if args.qemu {
        println!(
            "soak: firmware in QEMU over a faulty link, seed {}",
            args.seed
        );
        let elf = host_sim::qemu::build_firmware("qemu")?;
        let link = host_sim::qemu::QemuLink::boot(&elf)?;
        let injector = FaultInjector::new(link, faults, args.seed);
        let (report, link) = host_sim::soak::soak(
            injector,
            args.seed,
            args.blocks as usize,
            Duration::from_millis(300),
            |n| bar.set_position(n),
        )?;
        (report, link.stats, None)
    } else {
        println!(
            "soak: in-process device over a faulty link, seed {}",
            args.seed
        );
        let injector = FaultInjector::new(LocalLink::new(), faults, args.seed);
        let (report, link) = host_sim::soak::soak(
            injector,
            args.seed,
            args.blocks as usize,
            Duration::from_millis(1),
            |n| bar.set_position(n),
        )?;
        let corrupted = link.inner().executed_corrupted;
        (report, link.stats, Some(corrupted))
    };
    bar.finish_and_clear();
    host_sim::soak::print_report(&report, &stats, corrupted);
    let ok = report.passed() && corrupted.unwrap_or(0) == 0;
    println!(
        "SOAK: {} blocks, {} mismatches, registers {}",
        report.blocks,
        report.mismatches,
        if report.device_end == report.reference_end {
            "equal"
        } else {
            "DIFFER"
        }
    );
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The budgets `qemu-bench` holds the firmware to: the step interrupt's
/// instructions per step in every phase and in its longest entry, the
/// receive interrupt's per byte; the worst lateness of any event at
/// 200 000 events a second, ticks. The bench's figure a step has the
/// board's pulse timer in it already.
const STEP_PER_EVENT: f64 = 110.0;
const STEP_ENTRY: u64 = 400;
const RECEIVE_PER_BYTE: u64 = 300;
const WORST_LATE_TICKS: u64 = 1;
/// From a stopping switch's edge to the outputs low, instructions: within
/// one step period at the drives' default 50 000 steps a second (20 µs,
/// 3 360 cycles at 168 MHz), less the 18 cycles of the interrupts' entry
/// and tail-chaining.
const EDGE_TO_STOP: u64 = 3_360 - 18;

fn qemu_bench() -> Result<ExitCode, Box<dyn std::error::Error>> {
    // The bench of the timed build: its step interrupt runs paced, as on
    // the board.
    let elf = host_sim::qemu::build_firmware("qemu-timed")?;
    let bench = elf.with_file_name("bench");
    println!("Cortex-M4 instruction counts (QEMU netduinoplus2, -icount shift=0):");
    let lines = host_sim::qemu::icount_bench(&bench)?;
    let mut within = true;
    for line in &lines {
        println!("  {line}");
        within &= within_budget(line);
    }
    let latency = status_latency()?;
    let late = lateness_at_200k()?;
    println!(
        "budgets: step interrupt <= {STEP_PER_EVENT} instructions a step in every phase and <= {STEP_ENTRY} in any entry, receive interrupt <= {RECEIVE_PER_BYTE} a byte, a stopping switch's edge to the outputs low <= {EDGE_TO_STOP}, worst lateness <= {WORST_LATE_TICKS} tick: {}",
        if within && late { "within" } else { "EXCEEDED" }
    );
    Ok(if within && late && latency == ExitCode::SUCCESS {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// Whether a bench line is within its budget (lines without one are).
fn within_budget(line: &str) -> bool {
    let number_after = |key: &str| -> Option<f64> {
        let (before, _) = line.split_once(key)?;
        before.split_whitespace().last()?.parse().ok()
    };
    if line.starts_with("step interrupt,") {
        // "… N instructions per step (+P for the board's pulse timer)":
        // N counts P in.
        let per = number_after(" instructions per step").unwrap_or(f64::MAX);
        let entry = number_after(" at most in one entry").unwrap_or(f64::MAX);
        let ok = per <= STEP_PER_EVENT && entry <= STEP_ENTRY as f64;
        if !ok {
            println!("  OVER BUDGET: {line}");
        }
        return ok;
    }
    if line.starts_with("stopping switch's edge") {
        let most = number_after(" instructions (").unwrap_or(f64::MAX);
        let ok = most <= EDGE_TO_STOP as f64;
        if !ok {
            println!("  OVER BUDGET: {line}");
        }
        return ok;
    }
    if line.starts_with("receive interrupt per byte") {
        let worst = line
            .rsplit(": ")
            .next()
            .and_then(|r| r.split_whitespace().next())
            .and_then(|v| v.parse::<u64>().ok())
            .unwrap_or(u64::MAX);
        let ok = worst <= RECEIVE_PER_BYTE;
        if !ok {
            println!("  OVER BUDGET: {line}");
        }
        return ok;
    }
    true
}

/// Every event on time at 200 000 events a second, through block starts,
/// ramps, a hold and a resume: the timed firmware (under `-icount`, its
/// core never sleeping, so QEMU fires each timer on its tick) reports
/// the most late event it issued.
fn lateness_at_200k() -> Result<bool, Box<dyn std::error::Error>> {
    let elf = host_sim::qemu::build_firmware("qemu-timed")?;
    let lines = host_sim::stream::rate_program(200_000, 150);
    let mut q = host_sim::qemu::Qemu::boot_paced_timed(&elf)?;
    let mut c = q.connect(Duration::from_secs(60))?;
    let r = host_sim::stream::hold_and_resume(&mut c, &lines)?;
    host_sim::stream::realtime(&mut c, 0x80)?;
    std::thread::sleep(Duration::from_millis(200));
    let (late, worst) = host_sim::stream::lateness(&q.log()).unwrap_or((u64::MAX, u64::MAX));
    let same = r.end == r.expected;
    println!(
        "lateness at 200000 events/s with a hold and a resume (150 blocks): worst {worst} tick(s), {late} events late by a tick or more; held at {}; end {} / {} ({})",
        host_sim::stream::registers(&r.held)
            .map(|(x, z)| format!("PX={x} PZ={z}"))
            .unwrap_or_default(),
        r.end.0,
        r.end.1,
        if same { "as in-process" } else { "DIFFERENT from in-process" }
    );
    Ok(same && worst <= WORST_LATE_TICKS)
}

/// `!STATUS` answers while the step interrupt runs at rising event rates:
/// the paced firmware at 125 M instructions a second of virtual time, a
/// status byte whenever 20 ms pass without a reply line.
fn status_latency() -> Result<ExitCode, Box<dyn std::error::Error>> {
    let elf = host_sim::qemu::build_firmware("qemu-paced")?;
    println!(
        "Status latency while streaming (paced firmware, -icount shift=3: 125 M instructions/s; 150 blocks of 20 ms):"
    );
    println!(
        "  events/s   LAT worst   median   samples   final SYNC equal to the in-process device's"
    );
    let mut all_equal = true;
    for rate in [10_000u32, 25_000, 50_000, 100_000, 150_000, 200_000] {
        let lines = host_sim::stream::rate_program(rate, 150);
        let local = host_sim::stream::steps(&lines)?;
        let mut q = host_sim::qemu::Qemu::boot_paced_timed(&elf)?;
        let mut c = q.connect(Duration::from_secs(60))?;
        let got = host_sim::stream::status_latency(
            &mut c,
            &lines,
            Duration::from_millis(20),
            Duration::from_secs(300),
        )?;
        let (worst, median) = got.worst_and_median();
        let want = local.replies.last().map(|r| r.last.as_str());
        let equal = got.replies.last().map(String::as_str) == want;
        all_equal &= equal;
        host_sim::stream::realtime(&mut c, 0x80)?;
        std::thread::sleep(Duration::from_millis(100));
        let late =
            host_sim::stream::lateness(&q.log()).map_or("?".to_string(), |(_, w)| w.to_string());
        println!(
            "  {rate:>8}   {:>6.2} ms   {:>6.2} ms   {:>7}   {late:>11}   {}",
            f64::from(worst) / 1000.0,
            f64::from(median) / 1000.0,
            got.samples.len(),
            if equal {
                "yes".to_string()
            } else {
                format!("NO: {:?} vs {:?}", got.replies.last(), want)
            }
        );
    }
    Ok(if all_equal {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// A progress bar over `len` blocks.
fn blocks_bar(len: u64) -> ProgressBar {
    ProgressBar::new(len).with_style(
        ProgressStyle::with_template("  {bar:40} {pos}/{len} blocks {per_sec} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    )
}

/// Random G41/G42 programs in the main job.
const CONTOURS: usize = 300;

fn compare_all<T: Transport>(link: T, args: &ScenarioArgs) -> Result<ExitCode, LinkError> {
    let started = Instant::now();
    let mut cmp = Comparator::new(link)?;
    for s in [
        scenario::table21(),
        scenario::krylenko(),
        scenario::krylenko_arcs(),
        scenario::random_arcs(args.seed, 600, 200),
    ] {
        let before = cmp.tally.clone();
        cmp.run(&s, |_| {})?;
        report_scenario(&s, &before, &cmp.tally);
    }
    let random = scenario::random(args.seed, args.blocks as usize);
    let bar = blocks_bar(random.blocks() as u64);
    let before = cmp.tally.clone();
    let t0 = Instant::now();
    cmp.run(&random, |_| bar.inc(1))?;
    let random_time = t0.elapsed();
    bar.finish_and_clear();
    report_scenario(&random, &before, &cmp.tally);
    let t = &cmp.tally;
    let random_blocks = t.blocks - before.blocks;
    println!(
        "speed: {:.0} blocks/s, {:.2} M step events/s over the link (random part, {:.2} s)",
        random_blocks as f64 / random_time.as_secs_f64(),
        (t.events - before.events) as f64 / random_time.as_secs_f64() / 1e6,
        random_time.as_secs_f64()
    );
    println!(
        "ties: {} exact ties decided away from zero (quantizer {}, interleaver {})",
        t.exact_ties(),
        t.quantizer.exact_ties,
        t.interleave.exact_ties
    );
    println!(
        "margin: nearest non-tie {} impulses from a tie (quantizer {}, interleaver {})",
        format_distance(t.min_tie_distance()),
        format_distance(t.quantizer.min_distance),
        format_distance(t.interleave.min_distance)
    );
    println!(
        "arcs: {} by chords, {} direct, {} refused alike by device and reference",
        t.arcs, t.direct_arcs, t.refused_alike
    );
    println!(
        "arcs: worst finishing chord error {:.9} of TOL; worst direct-mode step {:.3} impulses off the circle (coarser axis)",
        t.worst_chord_error, t.worst_direct_deviation
    );
    println!(
        "arcs: nearest Δφ to a whole arc-second {}″, nearest sweep/Δφ to a whole number {}",
        format_distance(t.dphi_margin),
        format_distance(t.n_margin)
    );
    println!("{}", t.time_line());
    let machine_s: f64 = cmp.motion().profiles().iter().map(|p| p.duration_s).sum();
    println!(
        "time: {:.1} s ({:.1} h) of planned motion in {} blocks, longest SYNC run {} ticks",
        machine_s,
        machine_s / 3600.0,
        cmp.motion().profiles().len(),
        t.longest_run
    );
    for m in t.mismatches.iter().take(10) {
        println!(
            "MISMATCH {} step {}: {}\n  device:    {}\n  reference: {}",
            m.scenario, m.index, m.request, m.device, m.expected
        );
    }
    // Nose radius compensation last: it leaves its own configuration.
    let mut ct = host_sim::contour::ContourTally::default();
    let t0 = Instant::now();
    for case in host_sim::contour::random_contours(args.seed, CONTOURS) {
        host_sim::contour::compare_contour(cmp.link(), &case, &mut ct)?;
    }
    let contour_time = t0.elapsed();
    println!(
        "compensation: {} random G41/G42 programs, {} blocks, {:.0} blocks/s: {} compensated blocks printed alike, {} refused alike, {} near printing ties",
        ct.programs,
        ct.blocks,
        ct.blocks as f64 / contour_time.as_secs_f64(),
        ct.compared,
        ct.refused_alike,
        ct.near_ties
    );
    println!(
        "compensation: nearest printed value {:.1e} mm from a printing tie; {} position registers equal Q(P/h) of the reference ({} excused at a 1e-7 mm rounding tie)",
        ct.closest_tie_mm, ct.positions, ct.position_near_ties
    );
    println!(
        "compensation: {} step events timed alike ({} exact half-tick ties, nearest non-tie {} ticks from a tie)",
        ct.timed,
        ct.ticks.exact_ties,
        format_distance(ct.ticks.min_distance)
    );
    for m in ct.mismatches.iter().take(10) {
        println!("MISMATCH compensation: {m}");
    }
    let t = &cmp.tally;
    println!(
        "total: {} blocks, {} step events ({} timed), {} impulses in {:.2} s",
        t.blocks + ct.blocks as u64,
        t.events,
        t.timed + ct.timed,
        t.impulses,
        started.elapsed().as_secs_f64()
    );
    println!("{}", t.result_line());
    if !ct.mismatches.is_empty() {
        println!("RESULT: {} compensation mismatches", ct.mismatches.len());
        return Ok(ExitCode::FAILURE);
    }
    Ok(if t.mismatches.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn report_scenario(s: &Scenario, before: &Tally, after: &Tally) {
    println!(
        "{:<55} {:>6} blocks {:>10} events {:>3} mismatches",
        s.name,
        after.blocks - before.blocks,
        after.events - before.events,
        after.mismatches.len() - before.mismatches.len()
    );
}

/// Prints a calculator's answer (or its program with `--gcode`); a domain
/// error is named on standard error with exit status 1.
fn emit(
    result: Result<(host_sim::table::Report, String), String>,
    out: host_sim::table::OutArgs,
    program: bool,
) -> Result<ExitCode, Box<dyn std::error::Error>> {
    match result {
        Ok((report, gcode)) => {
            if program {
                print!("{gcode}");
            } else {
                print!("{}", report.render(out.format()));
            }
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => {
            eprintln!("host-sim: {e}");
            Ok(ExitCode::from(1))
        }
    }
}

/// `N` comma-separated numbers of option `what`.
fn numbers<const N: usize>(what: &str, text: &str) -> Result<[f64; N], String> {
    let values = text
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .map_err(|_| format!("--{what}: {t} is not a number"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    <[f64; N]>::try_from(values)
        .map_err(|v| format!("--{what}: {} numbers given, {N} wanted ({text})", v.len()))
}

/// Three angles or `-` each.
fn maybe_angles(what: &str, items: &[&str]) -> Result<[Option<f64>; 3], String> {
    let mut out = [None; 3];
    if items.len() != 3 {
        return Err(format!(
            "{what}: three angles wanted, `-` for one not given"
        ));
    }
    for (slot, t) in out.iter_mut().zip(items) {
        let t = t.trim();
        if t != "-" {
            *slot = Some(
                t.parse::<f64>()
                    .map_err(|_| format!("{what}: {t} is not an angle in degrees"))?,
            );
        }
    }
    Ok(out)
}

type TrihedralInputs = (host_sim::calculators::Angles, [f64; 3], [f64; 2], [f64; 3]);

fn trihedral_args(
    plane: &[String],
    linear: Option<&str>,
    lengths: &str,
    table: &str,
    vertex: &str,
) -> Result<TrihedralInputs, String> {
    let plane: Vec<&str> = plane.iter().map(String::as_str).collect();
    let angles = host_sim::calculators::Angles {
        plane: maybe_angles("plane angles", &plane)?,
        linear: match linear {
            Some(l) => maybe_angles("--linear", &l.split(',').collect::<Vec<_>>())?,
            None => [None; 3],
        },
    };
    Ok((
        angles,
        numbers::<3>("lengths", lengths)?,
        numbers::<2>("table", table)?,
        numbers::<3>("vertex", vertex)?,
    ))
}

#[cfg(test)]
mod tests {
    use super::within_budget;

    /// The bench's figure a step counts the pulse timer in: it is held to
    /// the budget as printed, not with the pulse timer added again.
    #[test]
    fn a_step_figure_is_held_to_the_budget_as_printed() {
        let line = |per: &str, entry: u32| {
            format!("step interrupt, cruise: 6000 steps, {per} instructions per step (+9 for the board's pulse timer), {entry} at most in one entry")
        };
        assert!(within_budget(&line("104.02", 132)));
        let edge = |n: u64| {
            format!("stopping switch's edge to the outputs low (no filter): at most {n} instructions (1.40 us at 168 MHz), plus the core's 12 cycles")
        };
        assert!(within_budget(&edge(236)));
        assert!(within_budget(&edge(3342)));
        assert!(!within_budget(&edge(3343)));
        assert!(within_budget(&line("110.00", 400)));
        assert!(!within_budget(&line("110.01", 132)));
        assert!(!within_budget(&line("104.02", 401)));
        assert!(within_budget(
            "receive interrupt per byte, worst case: 300 instructions"
        ));
        assert!(!within_budget(
            "receive interrupt per byte, worst case: 301 instructions"
        ));
        assert!(within_budget(
            "prep per entry: cruise 331.63 instructions, ramps 697.55"
        ));
    }
}

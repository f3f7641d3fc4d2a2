//! The session: configuration, commanded coordinates, position registers, and
//! the commands that act on them.
//!
//! Every command first computes its whole outcome from the current state and
//! only then commits it, so a refused request changes nothing.

use super::reply::{checksum, hex_digits, ReplyLine, REPLY_CAPACITY};
use super::words::{parse_args, ArgError, Words};
use super::{ErrorCode, Io, Realtime, StatusView, CHORDS_PER_PAUSE};
use crate::arc::{centre_from_radius, ArcDir, ArcError, ArcPoints, ChordPlan, DirectArc};
use crate::comp::{
    CompError, Contour, Element, Move, MoveKind, Moves, Origin, Shape, TipCode, Tool, MAX_MOVES,
};
use crate::cone::{cone, Angle, AngleError};
use crate::crc32::Crc32;
use crate::gcode::{
    is_block, parse, BlockError, Compensation, Coolant, Dialect, FeedMode, Motion, PathControl,
    Plane, Special, Spindle, SpindleMode, Stop, ToolOffset, ToolWord, Units,
};
use crate::impulse::{quantize, ImpulsePrice, Impulses, MAX_BLOCK_IMPULSES, MAX_POSITION};
use crate::interleave::{ImpulsePoint, LinearBlock, StepEvent};
use crate::interp::{path_feed, Aux, MAction, Modal, Offsets, Selection, TOOL_REGISTERS};
use crate::length::{div_round_half_away, write_mm4, Length, LengthError};
use crate::machine::{Background, Join, Machine, StepSink};
use crate::outputs::{milli_rpm, write_rpm, Outputs};
use crate::plan::{q32, Feed, Limits, LimitsError, Point, WINDOW};
use crate::stepdir::{DriveTiming, TimingError};
use crate::stepper::{Aborted, Item, Motion as Axes};
use core::fmt::{self, Write};

/// The device name reported by `VER`.
pub const NAME: &str = "lathe-retrofit";
/// The firmware version reported by `VER`.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The largest nose radius `CFG RN` accepts: 25 mm.
const MAX_NOSE_RADIUS_UM: i64 = 25_000;
/// The chord tolerance range of `CFG TOL`: 0.000001 mm to 1 mm.
const MAX_TOL_UM: i64 = 1_000;

/// Pass kind for arcs by chords: finishing rounds the chord angle down,
/// roughing up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pass {
    /// `FIN`: no chord deviates more than the tolerance.
    Finish,
    /// `ROUGH`: fewer, longer chords.
    Rough,
}

impl Pass {
    /// The protocol word.
    pub const fn as_str(self) -> &'static str {
        match self {
            Pass::Finish => "FIN",
            Pass::Rough => "ROUGH",
        }
    }
}

/// The session's configuration (`CFG`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// X impulse price, on the radius.
    pub hx: ImpulsePrice,
    /// Z impulse price.
    pub hz: ImpulsePrice,
    /// X words are diameters.
    pub diam: bool,
    /// Nose radius.
    pub rn: Length,
    /// Tool tip orientation.
    pub tip: TipCode,
    /// Chord tolerance for arcs that do not name their own.
    pub tol: Length,
    /// Pass kind for arcs that do not name their own.
    pub pass: Pass,
}

impl Config {
    /// Power-on defaults: 0.005/0.01 mm impulses, diameters, r 0.4 mm, tip 3,
    /// tolerance 0.01 mm, finishing.
    pub const DEFAULT: Config = Config {
        hx: ImpulsePrice::DEFAULT_X,
        hz: ImpulsePrice::DEFAULT_Z,
        diam: true,
        rn: match Length::from_um(400) {
            Some(l) => l,
            None => Length::ZERO,
        },
        tip: TipCode::EXTERNAL_RIGHT,
        tol: match Length::from_um(10) {
            Some(l) => l,
            None => Length::ZERO,
        },
        pass: Pass::Finish,
    };
}

impl Default for Config {
    fn default() -> Self {
        Config::DEFAULT
    }
}

/// The protocol state of one device.
#[derive(Clone, Debug)]
pub struct Session {
    pub(super) cfg: Config,
    /// Exact commanded X (radius) and Z in machine coordinates (since the
    /// machine zero: power-on or `ZERO`).
    pub(super) cmd: [Length; 2],
    /// Position registers; always `Q(cmd / price)` per axis.
    pub(super) pos: ImpulsePoint,
    /// Step/dir output timing.
    pub(super) drive: DriveTiming,
    /// Modal G-code state.
    pub(super) modal: Modal,
    /// The spindle, the coolant, the tool named.
    pub(super) aux: Aux,
    /// The dialect G-code lines are read in (`OPT DIALECT=`).
    pub(super) dialect: Dialect,
    /// Work offsets and the tool table.
    pub(super) offsets: Offsets,
    /// Which of them are in effect.
    pub(super) sel: Selection,
    /// The programmed contour point in work coordinates: where the last
    /// G-code block ended, as written. `cmd` less the offsets in effect,
    /// except while nose compensation is on or until the next move after an
    /// offset change.
    pub(super) prog: [Length; 2],
    /// Nose radius compensation.
    pub(super) contour: Contour,
    /// Feed override, percent (grbl's real-time 0x90–0x94): scales every
    /// G-code feed read from now on.
    pub(super) feed_override: u8,
    /// Spindle override, percent (grbl's 0x99–0x9D): scales the spindle
    /// speed commanded, and with it feeds per revolution.
    pub(super) spindle_override: u8,
    /// The blocks the last G-code request sent.
    pub(super) last_moves: Moves,
    /// The host's session token (`SESSION`); 0 after power-on.
    pub(super) token: u32,
    /// The block delete switch (`OPT BDEL=`): blocks that begin with `/`
    /// are skipped while it is on.
    pub(super) block_delete: bool,
    /// The optional stop switch: `M01` stops (`OPT OPTSTOP=`).
    pub(super) optional_stop: bool,
    /// Changes of the table, the work offsets and the stored positions.
    pub(super) generation: u32,
    /// Check mode (grbl's `$C`): the registers where it began, put back
    /// when it ends.
    pub(super) checking: Option<ImpulsePoint>,
    /// The last reset dropped motion answered and not all run.
    pub(super) reset_dropped: bool,
    /// The top speed of each gear range (`GEAR N= TOP=`), rpm.
    pub(super) gears: [Option<Length>; 4],
    /// The nose `G41.1`/`G42.1` gave, while its compensation is on.
    pub(super) dynamic_tool: Option<Tool>,
    /// The turning cycles: a profile held, their modal depth and retract.
    pub(super) cycles: super::cycles::Cycles,
    /// The id of the last request that carried one, and its final reply.
    pub(super) last_id: Option<u32>,
    pub(super) last_final: heapless::Vec<u8, REPLY_CAPACITY>,
    /// The planner, the run in progress, what has been issued.
    pub(super) machine: Machine,
    /// The feed of the last element given to the contour engine (the one
    /// it holds while compensation is on); `None` for a rapid.
    pub(super) element_feed: Option<Feed>,
    /// The spindle's top speed, rpm (`AUX SMAX`): the speed at full PWM
    /// duty and a limit of every commanded speed; none when the speed is
    /// set on the machine by hand.
    pub(super) top: Option<Length>,
    /// The wait after the spindle starts or changes speed at rest, µs
    /// (`AUX SPINUP`).
    pub(super) spinup_us: u64,
    /// The spindle and coolant outputs as last switched at rest.
    pub(super) outputs: Outputs,
    /// The BCK-5 tape read so far by `TAPE` requests.
    #[cfg(feature = "calc")]
    pub(super) tape: crate::calc::tape::Bck5Verifier,
}

impl Default for Session {
    fn default() -> Self {
        Self::new()
    }
}

/// Why a request was refused, before it is written out.
pub(super) enum Refusal<'a> {
    Checksum(u8),
    ChecksumForm,
    Control,
    Empty,
    Unknown(&'a str),
    Args(ArgError<'a>),
    NoArgs(&'static str),
    Value(&'static str, &'static str),
    Range(&'static str),
    Geometry(&'static str),
    Missing(&'static str),
    Block(BlockError),
    Contour(CompError),
    Busy(&'static str),
    Crc,
    NoSession,
    /// A BCK-5 tape frame that cannot be read (`TAPE`).
    #[cfg(feature = "calc")]
    Frame(crate::calc::tape::ParseError),
}

impl From<ArcError> for Refusal<'_> {
    fn from(e: ArcError) -> Self {
        match e {
            ArcError::Geometry(why) => Refusal::Geometry(why),
            ArcError::Range(why) => Refusal::Range(why),
        }
    }
}

impl<'a> From<ArgError<'a>> for Refusal<'a> {
    fn from(e: ArgError<'a>) -> Self {
        Refusal::Args(e)
    }
}

pub(super) type Outcome<'a> = Result<(), Refusal<'a>>;

impl Session {
    /// Power-on state: defaults, at program zero.
    pub const fn new() -> Self {
        Self::with_window(WINDOW)
    }

    /// As [`Session::new`], its planner looking `window` blocks ahead.
    pub const fn with_window(window: usize) -> Self {
        Session {
            cfg: Config::DEFAULT,
            cmd: [Length::ZERO; 2],
            pos: ImpulsePoint {
                x: Impulses(0),
                z: Impulses(0),
            },
            drive: DriveTiming::DEFAULT,
            modal: Modal::POWER_ON,
            aux: Aux::POWER_ON,
            dialect: Dialect::Iso,
            offsets: Offsets::ZERO,
            sel: Selection::POWER_ON,
            prog: [Length::ZERO; 2],
            contour: Contour::new(),
            feed_override: 100,
            spindle_override: 100,
            last_moves: Moves::new(),
            token: 0,
            block_delete: false,
            optional_stop: false,
            generation: 0,
            checking: None,
            reset_dropped: false,
            gears: [None; 4],
            dynamic_tool: None,
            cycles: super::cycles::Cycles::new(),
            last_id: None,
            last_final: heapless::Vec::new(),
            machine: Machine::with_window(window),
            element_feed: None,
            top: None,
            spinup_us: 0,
            outputs: Outputs::OFF,
            #[cfg(feature = "calc")]
            tape: crate::calc::tape::Bck5Verifier::new(),
        }
    }

    /// The motion pipeline: limits, queue, what has been issued.
    pub const fn machine(&self) -> &Machine {
        &self.machine
    }

    /// The configuration.
    pub const fn config(&self) -> &Config {
        &self.cfg
    }

    /// Step/dir output timing.
    pub const fn drive(&self) -> &DriveTiming {
        &self.drive
    }

    /// Position registers in impulses.
    pub const fn position(&self) -> ImpulsePoint {
        self.pos
    }

    /// The theoretical-tool-tip blocks the last G-code request sent, each
    /// with the programmed block it belongs to (what its `DATA` lines show).
    pub const fn last_moves(&self) -> &Moves {
        &self.last_moves
    }

    /// The contour engine's modal state.
    pub const fn contour(&self) -> &Contour {
        &self.contour
    }

    /// The modal G-code state (motion, distance, units, feed).
    pub const fn modal(&self) -> &Modal {
        &self.modal
    }

    /// The spindle, the coolant and the tool named, as programmed.
    pub const fn aux(&self) -> &Aux {
        &self.aux
    }

    /// Which work system, offset register and tool are in effect.
    pub const fn selection(&self) -> &Selection {
        &self.sel
    }

    /// The dialect G-code lines are read in.
    pub const fn dialect(&self) -> Dialect {
        self.dialect
    }

    /// Exact commanded coordinates `(X radius, Z)` in machine coordinates
    /// (since power-on or `ZERO`; the offsets in effect included).
    pub const fn commanded(&self) -> (Length, Length) {
        (self.cmd[0], self.cmd[1])
    }

    /// Runs one request line (terminator excluded) and answers it through
    /// `io`: exactly one final line, `OK …` or `ERR …`.
    ///
    /// A request that fails its `*HH` or `~CCCCCCCC` check is answered
    /// `ERR CHECKSUM` without the id and CRC words (nothing in it can be
    /// trusted). A request whose `@id` equals the last one's is not run
    /// again: its remembered final line is sent instead.
    pub fn handle_line<I: Io>(&mut self, line: &[u8], io: &mut I) {
        self.share_view(io);
        let (body, crc) = match check_integrity(line) {
            Ok(v) => v,
            Err(refusal) => return send_refusal(io, refusal),
        };
        let mut out = Suffixed {
            inner: io,
            id: None,
            crc,
            last: heapless::Vec::new(),
        };
        let body = match split_id(body) {
            // An id promises a retry; only a CRC-guarded request may be retried
            // (a line broken by noise must not run as its head).
            Ok((Some(_), _)) if !crc => {
                return send_refusal(
                    &mut out,
                    Refusal::Missing("a request with @id needs a ~CRC word"),
                )
            }
            Ok((id, rest)) => {
                out.id = id;
                rest
            }
            Err(refusal) => return send_refusal(&mut out, refusal),
        };
        if let Some(id) = out.id {
            if self.last_id == Some(id) {
                out.send_body(&self.last_final);
                return;
            }
            // After power-on no session token is set: a numbered request from
            // a session the device no longer remembers is refused, so the host
            // learns of the reset before anything runs.
            let session = Words::new(core::str::from_utf8(body).unwrap_or(""))
                .next()
                .is_some_and(|w| w.eq_ignore_ascii_case("SESSION"));
            if self.token == 0 && !session {
                return send_refusal(&mut out, Refusal::NoSession);
            }
        }
        if let Err(refusal) = self.run(body, &mut out) {
            send_refusal(&mut out, refusal);
        }
        if let Some(id) = out.id {
            self.last_id = Some(id);
            self.last_final = out.last;
        }
    }

    /// The calculators' requests (`THREAD`, `WEAR`, `DEFLECT`, `TRI`,
    /// `TAPE`); `None` for any other command.
    #[cfg(feature = "calc")]
    fn calc<'a, I: Io>(
        &mut self,
        command: &str,
        words: Words<'a>,
        io: &mut I,
    ) -> Option<Outcome<'a>> {
        use super::calc;
        let is = |name: &str| command.eq_ignore_ascii_case(name);
        Some(if is("THREAD") {
            calc::thread_command(words, self.machine.limits(), io)
        } else if is("WEAR") {
            calc::wear_command(words, io)
        } else if is("DEFLECT") {
            calc::deflect_command(words, io)
        } else if is("TRI") {
            calc::tri_command(words, io)
        } else if is("TAPE") {
            calc::tape_command(words, &mut self.tape, io)
        } else {
            return None;
        })
    }

    /// Without the calculators, no command is one of theirs.
    #[cfg(not(feature = "calc"))]
    fn calc<'a, I: Io>(&mut self, _: &str, _: Words<'a>, _: &mut I) -> Option<Outcome<'a>> {
        None
    }

    fn run<'a, I: Io>(&mut self, body: &'a [u8], io: &mut I) -> Outcome<'a> {
        let printable = |b: u8| b == b'\t' || (0x20..0x7F).contains(&b);
        if !body.iter().all(|&b| printable(b)) {
            // A G-code comment may hold any byte (a UTF-8 letter, a tape
            // control character); it is never read, so the line runs with
            // them replaced. Anywhere else they are refused.
            let words_start = body
                .iter()
                .position(|&b| printable(b) && b != b' ' && b != b'\t');
            let gcode = words_start
                .and_then(|i| body.get(i..))
                .and_then(|rest| core::str::from_utf8(rest.get(..2).unwrap_or(rest)).ok())
                .is_some_and(is_block);
            let only_in_comments = body
                .iter()
                .zip(in_comment(body))
                .all(|(&b, comment)| printable(b) || comment);
            if !gcode || !only_in_comments {
                return Err(Refusal::Control);
            }
            let mut clean = heapless::Vec::<u8, { super::framing::MAX_LINE }>::new();
            for &b in body {
                let _ = clean.push(if printable(b) { b } else { b'?' });
            }
            // Printable ASCII now: never fails.
            let text = core::str::from_utf8(&clean).map_err(|_| Refusal::Control)?;
            return self.gcode(text, io);
        }
        // Printable ASCII only from here on, so this never fails.
        let text = core::str::from_utf8(body).map_err(|_| Refusal::Control)?;
        let mut words = Words::new(text);
        let command = words.next().ok_or(Refusal::Empty)?;
        if is_block(text) {
            self.gcode(text, io)
        } else if command.eq_ignore_ascii_case("VER") {
            no_args(words, "VER")?;
            send_ok(
                io,
                Some(format_args!("PROTO=1 NAME={NAME} VERSION={VERSION}")),
            );
            Ok(())
        } else if command.eq_ignore_ascii_case("CFG") {
            self.cfg_command(words, io)
        } else if command.eq_ignore_ascii_case("ZERO") {
            self.zero_command(words, io)
        } else if command.eq_ignore_ascii_case("SESSION") {
            let [token] = parse_args(words, ["TOKEN"])?;
            if let Some(v) = token {
                self.token = match v.parse::<u32>() {
                    Ok(t) if v.bytes().all(|b| b.is_ascii_digit()) => t,
                    _ => return Err(Refusal::Value("TOKEN", "must be 0 to 4294967295")),
                };
            }
            send_ok(io, Some(format_args!("TOKEN={}", self.token)));
            Ok(())
        } else if command.eq_ignore_ascii_case("MOVE") {
            self.move_command(words, io)
        } else if command.eq_ignore_ascii_case("CONE") {
            self.cone_command(words, io)
        } else if command.eq_ignore_ascii_case("ARC") {
            self.arc_command(words, io)
        } else if let Some(outcome) = self.calc(command, words.clone(), io) {
            outcome
        } else if command.eq_ignore_ascii_case("DRIVE") {
            self.drive_command(words, io)
        } else if command.eq_ignore_ascii_case("MCODE") {
            self.mcode_command(words, io)
        } else if command.eq_ignore_ascii_case("GEAR") {
            self.gear_command(words, io)
        } else if command.eq_ignore_ascii_case("OPT") {
            let [bdel, dialect, optstop] = parse_args(words, ["BDEL", "DIALECT", "OPTSTOP"])?;
            let block_delete = match bdel {
                Some(v) => parse_flag("BDEL", v)?,
                None => self.block_delete,
            };
            let optional_stop = match optstop {
                Some(v) => parse_flag("OPTSTOP", v)?,
                None => self.optional_stop,
            };
            let dialect = match dialect {
                None => self.dialect,
                Some(v) if v.eq_ignore_ascii_case("ISO") => Dialect::Iso,
                Some(v) if v.eq_ignore_ascii_case("FANUC") => Dialect::Fanuc,
                Some(_) => return Err(Refusal::Value("DIALECT", "must be ISO or FANUC")),
            };
            (self.block_delete, self.dialect) = (block_delete, dialect);
            self.optional_stop = optional_stop;
            send_ok(
                io,
                Some(format_args!(
                    "BDEL={} DIALECT={} OPTSTOP={}",
                    u8::from(self.block_delete),
                    self.dialect.as_str(),
                    u8::from(self.optional_stop)
                )),
            );
            Ok(())
        } else if command.eq_ignore_ascii_case("LIMITS") {
            self.limits_command(words, io)
        } else if command.eq_ignore_ascii_case("SYNC") {
            no_args(words, "SYNC")?;
            let (r, starved) = self.machine.sync(&mut Sink::new(io, self.drive));
            send_ok(
                io,
                Some(format_args!(
                    "EV={} T={} TSEQ={:08X} STARVED={starved}",
                    r.events(),
                    r.run_ticks(),
                    r.tseq()
                )),
            );
            Ok(())
        } else if command.eq_ignore_ascii_case("STATUS") {
            no_args(words, "STATUS")?;
            self.status_reply(io, "OK");
            Ok(())
        } else if command.eq_ignore_ascii_case("RESET") {
            no_args(words, "RESET")?;
            // As the RESET key of a control: the program is abandoned where
            // it stands (a cycle's profile being read with it). What is queued runs to its end; a waiting element
            // is dropped.
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.cycles.abandon();
            // The programmed feed stays, as on the controls machinists know.
            self.modal = Modal {
                feed: self.modal.feed,
                feed_mode: self.modal.feed_mode,
                ..Modal::POWER_ON
            };
            self.aux = self.aux.stopped();
            self.switch_outputs(self.outputs_for(&self.aux, Units::Mm), io);
            self.contour = Contour::new();
            self.last_moves = Moves::new();
            self.prog = self.work_point(self.cmd);
            send_ok(io, None);
            Ok(())
        } else if command.eq_ignore_ascii_case("POS") {
            no_args(words, "POS")?;
            self.pos_reply(io);
            Ok(())
        } else if command.eq_ignore_ascii_case("TOOL") {
            self.tool_command(words, io)
        } else if command.eq_ignore_ascii_case("WORK") {
            self.work_command(words, io)
        } else if command.eq_ignore_ascii_case("AUX") {
            self.aux_command(words, io)
        } else {
            Err(Refusal::Unknown(command))
        }
    }

    /// `ZERO [X=] [Z=]`: the current point becomes X, Z (0 when omitted) in
    /// program coordinates; nothing moves.
    #[inline(never)]
    fn zero_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [x, z] = parse_args(words, ["X", "Z"])?;
        self.not_compensating("ZERO")?;
        let work = [
            match x {
                Some(v) => self.x_word(parse_length("X", v)?)?,
                None => Length::ZERO,
            },
            match z {
                Some(v) => parse_length("Z", v)?,
                None => Length::ZERO,
            },
        ];
        let cmd = to_machine(work, self.offset())?;
        let pos = ImpulsePoint {
            x: quantize(cmd[0], self.cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
            z: quantize(cmd[1], self.cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
        };
        self.machine.flush(&mut Sink::new(io, self.drive));
        let mut sink = Sink::new(io, self.drive);
        self.machine.clear_record(&mut sink);
        self.machine.set_position(point_q32(cmd), pos, &mut sink);
        self.cmd = cmd;
        self.prog = work;
        self.pos = pos;
        send_ok(io, None);
        Ok(())
    }

    #[inline(never)]
    fn cfg_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [hx, hz, diam, rn, tip, tol, pass] =
            parse_args(words, ["HX", "HZ", "DIAM", "RN", "TIP", "TOL", "PASS"])?;
        let mut cfg = self.cfg;
        if let Some(v) = hx {
            cfg.hx = parse_price("HX", v)?;
        }
        if let Some(v) = hz {
            cfg.hz = parse_price("HZ", v)?;
        }
        if let Some(v) = diam {
            cfg.diam = parse_flag("DIAM", v)?;
        }
        if rn.is_some() || tip.is_some() {
            self.not_compensating("CFG RN or TIP")?;
        }
        if let Some(v) = rn {
            cfg.rn = parse_bounded("RN", v, 0, MAX_NOSE_RADIUS_UM, "must be 0 to 25 mm")?;
        }
        if let Some(v) = tip {
            cfg.tip = match v.as_bytes() {
                [d @ b'0'..=b'9'] => TipCode::new(d - b'0'),
                _ => None,
            }
            .ok_or(Refusal::Value("TIP", "must be a digit 0 to 9"))?;
        }
        if let Some(v) = tol {
            cfg.tol = parse_tol(v)?;
        }
        if let Some(v) = pass {
            cfg.pass = parse_pass(v)?;
        }
        // A new price re-expresses the registers at the same commanded point.
        let pos = ImpulsePoint {
            x: quantize(self.cmd[0], cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
            z: quantize(self.cmd[1], cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
        };
        if let Some(axis) = self
            .machine
            .limits()
            .too_fast([cfg.hx, cfg.hz], self.drive.rate_hz())
        {
            let key = ["HX", "HZ"][axis & 1];
            return Err(Refusal::Value(
                key,
                "needs more step events than DRIVE RATE at the rapid rate",
            ));
        }
        if (cfg.hx, cfg.hz) != (self.cfg.hx, self.cfg.hz) {
            // New prices re-express the registers: at rest.
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.machine
                .set_position(point_q32(self.cmd), pos, &mut Sink::new(io, self.drive));
        }
        self.cfg = cfg;
        self.pos = pos;
        let c = &self.cfg;
        send_ok(
            io,
            Some(format_args!(
                "HX={} HZ={} DIAM={} RN={} TIP={} TOL={} PASS={}",
                c.hx.as_length(),
                c.hz.as_length(),
                u8::from(c.diam),
                c.rn,
                c.tip.get(),
                c.tol,
                c.pass.as_str()
            )),
        );
        Ok(())
    }

    /// `CONE A= [RN=]`: Krylenko's Xc, Zc, Xc on the diameter and Nomura's
    /// A, B, C; `NEAR=` names any value within 10⁻⁹ mm of a printing tie.
    #[inline(never)]
    fn cone_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [a, rn] = parse_args(words, ["A", "RN"])?;
        let a = a.ok_or(Refusal::Missing("CONE needs A"))?;
        let alpha = Angle::from_degrees_str(a).map_err(|e| {
            Refusal::Value(
                "A",
                match e {
                    AngleError::Malformed => "not degrees (45, 2.8642) or D:M:S (2:51:51)",
                    AngleError::OutOfRange => "must lie between 0 and 90 degrees",
                },
            )
        })?;
        let r = match rn {
            Some(v) => parse_bounded("RN", v, 0, MAX_NOSE_RADIUS_UM, "must be 0 to 25 mm")?,
            None => self.cfg.rn,
        };
        let k = cone(alpha, r);
        let xcd = k.xc.doubled();
        let values = [
            ("XC", k.xc),
            ("ZC", k.zc),
            ("XCD", xcd),
            ("NA", k.xc),
            ("NB", k.zc),
            ("NC", k.c),
        ];
        let mut line = ReplyLine::new();
        let _ = line.write_str("OK");
        for (key, v) in values {
            let _ = write!(line, " {key}=");
            let _ = write_mm4(&mut line, v.tenth_um());
        }
        let mut first = true;
        for (key, v) in values {
            if v.near_tie() {
                let _ = write!(line, "{}{key}", if first { " NEAR=" } else { "," });
                first = false;
            }
        }
        io.send(line.finish());
        Ok(())
    }

    #[inline(never)]
    fn arc_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [x, z, i, k, dir, tol, pass, mode, feed] = parse_args(
            words,
            ["X", "Z", "I", "K", "DIR", "TOL", "PASS", "MODE", "F"],
        )?;
        self.not_compensating("ARC")?;
        let (Some(x), Some(z), Some(i), Some(k), Some(dir)) = (x, z, i, k, dir) else {
            return Err(Refusal::Missing("ARC needs X, Z, I, K and DIR"));
        };
        let dir = if dir.eq_ignore_ascii_case("CW") {
            ArcDir::Cw
        } else if dir.eq_ignore_ascii_case("CCW") {
            ArcDir::Ccw
        } else {
            return Err(Refusal::Value("DIR", "must be CW or CCW"));
        };
        let tol = match tol {
            Some(v) => parse_tol(v)?,
            None => self.cfg.tol,
        };
        let finish = match pass {
            Some(v) => parse_pass(v)? == Pass::Finish,
            None => self.cfg.pass == Pass::Finish,
        };
        let direct = match mode {
            None => false,
            Some(v) if v.eq_ignore_ascii_case("CHORD") => false,
            Some(v) if v.eq_ignore_ascii_case("DIRECT") => true,
            Some(_) => return Err(Refusal::Value("MODE", "must be CHORD or DIRECT")),
        };
        let feed = match feed {
            None => None,
            Some(v) => Some(parse_feed(v)?),
        };
        let end = to_machine(
            [self.x_word(parse_length("X", x)?)?, parse_length("Z", z)?],
            self.offset(),
        )?;
        let (di, dk) = (parse_length("I", i)?, parse_length("K", k)?);
        let beyond = Refusal::Range("arc centre beyond 99999.999999 mm");
        let centre = [
            self.cmd[0].checked_add(di).ok_or(beyond)?,
            self.cmd[1]
                .checked_add(dk)
                .ok_or(Refusal::Range("arc centre beyond 99999.999999 mm"))?,
        ];
        let points = ArcPoints {
            start: self.cmd,
            end,
            centre,
        };
        if direct {
            self.arc_direct(&points, dir, feed, io)
        } else {
            self.arc_chords(&points, dir, tol, finish, feed, io)
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn arc_chords<'a, I: Io>(
        &mut self,
        points: &ArcPoints,
        dir: ArcDir,
        tol: Length,
        finish: bool,
        feed: Option<Feed>,
        io: &mut I,
    ) -> Outcome<'a> {
        let plan = ChordPlan::new(points, dir, tol, finish)?;
        let n = plan.chords();
        self.check_chords(&plan, self.pos, io)?;
        let start = self.pos;
        let crc = self.run_chords(&plan, points, feed, io, true, Crc32::new());
        let at = self.pos;
        let dphi = plan.dphi_arcsec();
        // Degrees with 6 decimals, half away from zero: dphi·10⁶/3600 = dphi·2500/9.
        let micro_deg = (u64::from(dphi) * 5000 + 9) / 18;
        send_ok(
            io,
            Some(format_args!(
                "N={n} DPHI={}.{:06} {}",
                micro_deg / 1_000_000,
                micro_deg % 1_000_000,
                MotionSummary::new(start, at, &crc)
            )),
        );
        Ok(())
    }

    fn arc_direct<'a, I: Io>(
        &mut self,
        points: &ArcPoints,
        dir: ArcDir,
        feed: Option<Feed>,
        io: &mut I,
    ) -> Outcome<'a> {
        let arc = DirectArc::new(points, dir, self.pos, self.cfg.hx, self.cfg.hz)?;
        let mut crc = Crc32::new();
        let mut events = 0u32;
        for e in arc.events() {
            crc.push(e.bits());
            events += 1;
        }
        let start = self.pos;
        self.cmd = points.end;
        self.prog = self.work_point(points.end);
        self.pos = arc.to();
        let rate = self.drive.rate_hz();
        self.machine.fixed_rate(
            arc.events(),
            rate,
            point_q32(points.end),
            &mut Sink::new(io, self.drive),
        );
        let (dx, dz) = arc.delta();
        let (j, k) = arc.jk();
        let g = match dir {
            ArcDir::Cw => "G02",
            ArcDir::Ccw => "G03",
        };
        let mut line = ReplyLine::new();
        let _ = write!(line, "DATA {g}");
        if dx != 0 {
            let _ = write!(line, " X{dx:+}");
        }
        if dz != 0 {
            let _ = write!(line, " Z{dz:+}");
        }
        let _ = write!(line, " J{j} K{k}");
        if let Some(f) = feed {
            let _ = write!(line, " F{}", arc.feed_word(f.mm_per_min()));
        }
        io.send(line.finish());
        send_ok(
            io,
            Some(format_args!(
                "N={events} {}",
                MotionSummary::new(start, self.pos, &crc)
            )),
        );
        Ok(())
    }

    /// Runs one G-code block in the session's modal state, through the
    /// contour engine (compensation off: the block itself).
    #[inline(never)]
    fn gcode<'a, I: Io>(&mut self, text: &str, io: &mut I) -> Outcome<'a> {
        if self.cycles.holding() {
            return self.profile_line(text, io);
        }
        let start = self.pos;
        let mut crc = Crc32::new();
        let done = self.gcode_block(text, &mut crc, io)?;
        let summary = MotionSummary::new(start, self.pos, &crc);
        match done {
            Block::Run => send_ok(io, Some(format_args!("{summary}"))),
            Block::Skipped => send_ok(io, Some(format_args!("{summary} SKIP=BDEL"))),
        }
        Ok(())
    }

    /// Runs one G-code block, its step events added to `crc`; answers
    /// nothing (its caller does: one line per request). What it was.
    pub(super) fn gcode_block<'a, I: Io>(
        &mut self,
        text: &str,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        let b = parse(text, self.dialect, self.modal.units).map_err(|l| Refusal::Block(l.error))?;
        if b.deleted && self.block_delete {
            return Ok(Block::Skipped);
        }
        if let Some(cycle) = b.cycle {
            self.cycles.single = None;
            return self.cycle_block(&b, cycle, crc, io);
        }
        if let Some(kind) = b.single {
            if b.motion.is_some() {
                return Err(Refusal::Missing(
                    "G90/G94 and a motion code in one block: one of them",
                ));
            }
            if b.x.is_some() || b.z.is_some() {
                return self.single_cycle(&b, Some(kind), crc, io);
            }
            // Selected only (a header's `G90`): the block's other words
            // as any block's; nothing moves.
            let done = self.gcode_words(b, crc, io)?;
            self.cycles.single = Some(super::cycles::Single::selected(kind));
            return Ok(done);
        }
        if self.cycles.single.is_some() {
            if b.motion.is_some() || b.cancel_cycle || b.stop == Some(Stop::End) {
                // A motion code, G80 or the program's end ends the cycle.
                self.cycles.single = None;
            } else if b.x.is_some() || b.z.is_some() {
                return self.single_cycle(&b, None, crc, io);
            }
        }
        self.gcode_words(b, crc, io)
    }

    /// A block's words, run (no cycle in it).
    fn gcode_words<'a, I: Io>(
        &mut self,
        b: crate::gcode::Block,
        crc: &mut Crc32,
        io: &mut I,
    ) -> Result<Block, Refusal<'a>> {
        let modal = self.modal.after(&b);
        // F0 (a header's, before G95) is taken; a feed move then needs a
        // feed above 0.
        if let Some(f) = b.f.filter(|f| f.as_angstrom() != 0) {
            let (ok, why) = match modal.feed_mode {
                FeedMode::PerMinute => (
                    Feed::new(f).is_some(),
                    "must be 0.001 to 99999.999999 mm/min",
                ),
                FeedMode::PerRev => (f.as_angstrom() > 0, "must be above 0 mm/rev"),
            };
            if !ok {
                return Err(Refusal::Value("F", why));
            }
        }
        let aux = self.aux.after(&b);
        // The spindle speed where the block starts: the programmed X, the
        // diameter the tool cuts at (X0 of every work system is the
        // spindle's axis; offsets move the slide, not the part); within
        // the spindle's top speed.
        let spindle = aux.spindle.within(self.top_speed(&aux));
        if aux.spindle.turning != Spindle::Off {
            spindle
                .rpm(self.prog[0], modal.units)
                .map_err(|e| Refusal::Value("S", e.as_str()))?;
        }
        let diam = b.diameter.unwrap_or(self.cfg.diam);
        let (sel, mut offsets) = self.offsets_after(&b, &aux, diam)?;
        let special = b.special;
        if special.is_some() && (self.contour.active() || b.compensation.is_some()) {
            return Err(Refusal::Busy(
                "G28, G30, G53 and G92 (G50) with nose compensation",
            ));
        }
        // G92 (G50): the point here takes the block's coordinates.
        let mut prog = self.prog;
        let shift = offsets.shift;
        match special {
            Some(Special::Shift) => {
                // The point here in the block's work system as it stands
                // (never under nose compensation: refused above).
                let off = offsets.vector(&sel).ok_or(Refusal::Range(RANGE_OFFSET))?;
                let mut here = self.cmd;
                for (h, o) in here.iter_mut().zip(off) {
                    *h = h.checked_sub(o).ok_or(Refusal::Range(RANGE_OFFSET))?;
                }
                let words = [block_x(&b, diam), b.z];
                for ((s, p), w) in offsets.shift.iter_mut().zip(here).zip(words) {
                    if let Some(w) = w {
                        *s = s
                            .checked_add(p)
                            .and_then(|v| v.checked_sub(w))
                            .ok_or(Refusal::Range(RANGE_OFFSET))?;
                    }
                }
            }
            Some(Special::ClearShift(keep)) => {
                offsets.kept_shift = if keep { shift } else { [Length::ZERO; 2] };
                offsets.shift = [Length::ZERO; 2];
            }
            Some(Special::RestoreShift) => offsets.shift = offsets.kept_shift,
            Some(Special::Store(n)) => {
                if let Some(r) = offsets.reference.get_mut(usize::from(n)) {
                    *r = self.cmd;
                }
            }
            _ => {}
        }
        let off = offsets.vector(&sel).ok_or(Refusal::Range(
            "the offsets in effect add beyond 99999.999999 mm",
        ))?;
        if (sel != self.sel || b.set_work.is_some()) && self.contour.active() {
            return Err(Refusal::Busy("a work or tool offset change"));
        }
        // The machine stays where it is when offsets change (a work system
        // selected or set, G92 and its kin, a tool's offset): the point
        // here is the same machine point in the new work coordinates, so an
        // axis the block does not name never moves, as in LinuxCNC and
        // grbl; a named axis takes the new offset up on its way. Under
        // nose compensation no offset changes (refused above) and the
        // programmed point is the contour's, not the tool's.
        let mut here = prog;
        if !self.contour.active() {
            for ((p, at), o) in here.iter_mut().zip(self.cmd).zip(off) {
                *p = at.checked_sub(o).ok_or(Refusal::Range(RANGE_OFFSET))?;
            }
        }
        if matches!(
            special,
            Some(Special::Shift | Special::ClearShift(_) | Special::RestoreShift)
        ) {
            // G92 and its kin name the point here anew.
            prog = here;
        }
        // Words are work coordinates; increments add to the programmed point.
        let mut target = here;
        let words = if b.set_work.is_some()
            || matches!(special, Some(s) if !matches!(s, Special::Reference(_)))
        {
            // G10's X and Z are an offset's, G53's machine coordinates,
            // G92's the point here.
            (None, None)
        } else {
            (b.x, b.z)
        };
        if words.0.is_some() {
            let radius = block_x(&b, diam).unwrap_or(Length::ZERO);
            let inc = modal.incremental || b.incremental_x;
            target[0] = step(here[0], radius, inc, "X beyond 99999.999999 mm")?;
        }
        if let Some(z) = words.1 {
            let inc = modal.incremental || b.incremental_z;
            target[1] = step(here[1], z, inc, "Z beyond 99999.999999 mm")?;
        }
        if let Some(po) = b.position_offset {
            target = self.position_offset(po, &modal, &offsets, words, target, &b)?;
        }
        let has_end = words.0.is_some() || words.1.is_some();
        let arc_words = b.i.is_some() || b.k.is_some() || b.r.is_some();
        if modal.plane != Plane::Zx {
            let arc = matches!(modal.motion, Motion::ArcCw | Motion::ArcCcw)
                && special.is_none()
                && (has_end || arc_words);
            let compensating = self.contour.active()
                || matches!(
                    b.compensation,
                    Some(Compensation::Left | Compensation::Right)
                );
            if arc || compensating {
                return Err(Refusal::Geometry(match modal.plane {
                    Plane::Xy => "in G17 (XY): a lathe turns arcs and compensates in G18 (ZX)",
                    _ => "in G19 (YZ): a lathe turns arcs and compensates in G18 (ZX)",
                }));
            }
        }
        let a = |p: [Length; 2]| [p[0].as_angstrom(), p[1].as_angstrom()];
        let shape = match modal.motion {
            // G28 and G30 move through their way point themselves.
            _ if special.is_some() => None,
            Motion::Rapid | Motion::Linear => {
                if arc_words {
                    return Err(Refusal::Missing("I, K and R need G02 or G03"));
                }
                has_end.then_some(Shape::Line {
                    rapid: modal.motion == Motion::Rapid,
                })
            }
            Motion::ArcCw | Motion::ArcCcw if has_end || arc_words => {
                // An arc starts where the tool is: it cannot take up a new
                // offset on the way.
                if !self.contour.active() && here != prog {
                    return Err(Refusal::Geometry(
                        "an arc cannot take up an offset change: move in a line first",
                    ));
                }
                let dir = if modal.motion == Motion::ArcCw {
                    ArcDir::Cw
                } else {
                    ArcDir::Ccw
                };
                let ik = b.i.is_some() || b.k.is_some();
                let centre = match (ik, b.r) {
                    (true, Some(_)) => return Err(Refusal::Missing("give I and K or R, not both")),
                    (false, None) => return Err(Refusal::Missing("an arc needs I and K, or R")),
                    (false, Some(r)) => centre_from_radius(here, target, r, dir)?,
                    (true, None) if modal.arc_absolute => match (b.i, b.k) {
                        (Some(i), Some(k)) => [i, k],
                        _ => return Err(Refusal::Missing("G90.1: an arc centre needs I and K")),
                    },
                    (true, None) => {
                        let beyond = "arc centre beyond 99999.999999 mm";
                        [
                            here[0]
                                .checked_add(b.i.unwrap_or(Length::ZERO))
                                .ok_or(Refusal::Range(beyond))?,
                            here[1]
                                .checked_add(b.k.unwrap_or(Length::ZERO))
                                .ok_or(Refusal::Range(beyond))?,
                        ]
                    }
                };
                ArcPoints {
                    start: here,
                    end: target,
                    centre,
                }
                .check_radii()?;
                Some(Shape::Arc {
                    centre: a(centre),
                    dir,
                })
            }
            Motion::ArcCw | Motion::ArcCcw => None,
        };
        let element = shape.map(|shape| Element {
            from: a(here),
            to: a(target),
            shape,
            n: b.n,
        });
        // G28/G30 (through the way point) and G53: rapids, G53 also a feed,
        // in machine coordinates.
        let mut machine_path = heapless::Vec::<[Length; 2], 2>::new();
        match special {
            Some(Special::Reference(n)) => {
                let mut at = self.cmd;
                if has_end {
                    at = to_machine(target, off)?;
                    if at != self.cmd {
                        let _ = machine_path.push(at);
                    }
                }
                let stored = offsets.reference.get(usize::from(n)).copied().unwrap_or(at);
                let all = !has_end;
                let end = [
                    if all || words.0.is_some() {
                        stored[0]
                    } else {
                        at[0]
                    },
                    if all || words.1.is_some() {
                        stored[1]
                    } else {
                        at[1]
                    },
                ];
                let _ = machine_path.push(end);
            }
            Some(Special::Machine) => {
                if !matches!(modal.motion, Motion::Rapid | Motion::Linear) {
                    return Err(Refusal::Missing("G53 moves in G00 or G01"));
                }
                let mut end = self.cmd;
                if let Some(x) = block_x(&b, diam) {
                    end[0] = x;
                }
                if let Some(z) = b.z {
                    end[1] = z;
                }
                let _ = machine_path.push(end);
            }
            _ => {}
        }
        let rapid = special != Some(Special::Machine) || modal.motion == Motion::Rapid;
        let feeds = element.is_some_and(|e| !matches!(e.shape, Shape::Line { rapid: true }))
            || (!machine_path.is_empty() && !rapid);
        // Output blocks of the element held back by compensation run at its
        // feed; this block's own and the corners between, at this one's.
        if feeds && modal.feed.is_some_and(|f| f.as_angstrom() == 0) {
            return Err(Refusal::Value("F", "0: a feed move needs a feed above 0"));
        }
        let now = if feeds {
            path_feed(&modal, &spindle, here[0])
                .map_err(|e| Refusal::Value("F", e.as_str()))?
                .map(|f| self.overridden(f, modal.feed_mode))
        } else {
            None
        };
        let dynamic_tool = match (b.dynamic_nose, b.compensation) {
            (Some(nose), _) => Some(Tool::new(
                nose.radius,
                TipCode::new(linuxcnc_orientation(nose.orientation)).unwrap_or(self.cfg.tip),
            )),
            // G40 too: the lead-out is the nose's that compensated.
            (None, _) => self.dynamic_tool,
        };
        let tool = dynamic_tool.unwrap_or_else(|| self.nose(&offsets, &sel));
        let (contour, moves) = self
            .contour
            .block(&tool, b.compensation, b.corner, element)
            .map_err(Refusal::Contour)?;
        // The blocks in machine coordinates: the tip's path plus the offsets.
        let mut moves = moves;
        for m in moves.iter_mut() {
            m.to = shifted(m.to, off)?;
            if let MoveKind::Arc { centre, .. } = &mut m.kind {
                *centre = shifted(*centre, off)?;
            }
        }
        for to in &machine_path {
            // No element, no compensation: room for both.
            let _ = moves.push(Move {
                to: a(*to),
                kind: MoveKind::Line { rapid },
                origin: Origin::Current,
            });
        }
        if feeds && modal.feed.is_none() {
            return Err(Refusal::Value(
                "F",
                "not programmed: a feed move needs F (mm/min)",
            ));
        }
        let end = b.stop == Some(Stop::End);
        if end && contour.active() {
            return Err(Refusal::Busy("M02/M30"));
        }
        let pause = match b.stop {
            Some(Stop::Pause) => true,
            Some(Stop::Optional) => self.optional_stop,
            _ => false,
        };
        if pause && contour.active() {
            // The compensated path of the last element is not known yet.
            return Err(Refusal::Busy("M00/M01"));
        }
        // Plan and check every block before the first one moves.
        let mut planned = heapless::Vec::<Planned, MAX_MOVES>::new();
        let mut cmd = self.cmd;
        let mut pos = self.pos;
        for m in &moves {
            // A corner belongs to the cut on either side of it: at this
            // block's feed, or the previous one's into a rapid.
            let feed = match m.origin {
                Origin::Previous => self.element_feed,
                Origin::Current => now,
                Origin::Corner => now.or(self.element_feed),
            };
            let p = self.plan_move(cmd, pos, m, feed, io)?;
            (cmd, pos) = (p.end(), p.registers());
            // As many plans as moves: never full.
            let _ = planned.push(p);
        }
        let join = match modal.path {
            PathControl::ExactStop => Join::Stop,
            PathControl::ExactPath | PathControl::Blend => Join::Blend,
            PathControl::Tolerance(t) if t.as_angstrom() <= 100_000_000 => {
                Join::Deviation(t.as_angstrom().unsigned_abs())
            }
            PathControl::Tolerance(_) => {
                return Err(Refusal::Value("P", "a G64 tolerance of 0 to 10 mm"))
            }
        };
        let machine_m = b
            .machine_m
            .map(|code| (code, self.offsets.mcodes.get(code)));
        if (b.gear.is_some() || machine_m.is_some()) && contour.active() {
            return Err(Refusal::Busy("a gear range or a machine's M code"));
        }
        // Nothing refuses the block from here on.
        self.machine.set_join(join);
        // A gear range, then the machine's own M code, at rest before the
        // spindle switches and the block moves.
        if let Some(range) = b.gear {
            self.machine.flush(&mut Sink::new(io, self.drive));
            let r = self
                .gears
                .get(usize::from(range).saturating_sub(1))
                .copied()
                .flatten();
            match r {
                Some(top) => send_data(
                    io,
                    format_args!("MSG M4{range}: shift the gearbox to range {range} (up to {top} rpm), then cycle start"),
                ),
                None => send_data(
                    io,
                    format_args!("MSG M4{range}: shift the gearbox to range {range}, then cycle start"),
                ),
            }
            self.program_stop(40 + u16::from(range), io);
        }
        if let Some((code, action)) = machine_m {
            let m = code / 10;
            match action {
                MAction::Stop => {
                    self.machine.flush(&mut Sink::new(io, self.drive));
                    send_data(
                        io,
                        format_args!("MSG M{m:02}: the machine's own M code; do it by hand, then cycle start"),
                    );
                    self.program_stop(m, io);
                }
                MAction::Nothing => {}
                MAction::Output(n, on) => {
                    self.machine.flush(&mut Sink::new(io, self.drive));
                    io.user_output(n, on);
                }
                MAction::Wait(n, level) => {
                    self.machine.flush(&mut Sink::new(io, self.drive));
                    io.wait_input(n, level);
                }
            }
        }
        // The spindle and the coolant switch with the axes at rest, before
        // the block's motion (as LinuxCNC orders a block); a dwell waits
        // there too.
        if self.aux.needs_rest(&aux) || b.dwell.is_some() || b.tool_change {
            self.machine.flush(&mut Sink::new(io, self.drive));
        }
        let outputs = self.outputs_for(&aux, modal.units);
        if self.aux.needs_rest(&aux) {
            let (was, now) = (self.outputs, outputs);
            self.switch_outputs(now, io);
            // A spindle that starts or changes speed gets up to it first.
            if now.spindle != Spindle::Off && (was.spindle != now.spindle || was.rpm != now.rpm) {
                io.dwell(self.spinup_us);
            }
        }
        if let Some(us) = b.dwell {
            io.dwell(us);
        }
        // The blocks carry the speed at their start (under G96 it follows
        // X block by block).
        self.machine.set_spindle(outputs.rpm);
        // The DATA lines write X as this block reads it.
        self.cfg.diam = diam;
        for p in &planned {
            *crc = self.run_planned(p, *crc, io);
        }
        if let Some(end) = machine_path.last() {
            self.prog = [
                end[0].checked_sub(off[0]).unwrap_or(end[0]),
                end[1].checked_sub(off[1]).unwrap_or(end[1]),
            ];
        } else if element.is_some() || has_end {
            self.prog = target;
        } else {
            self.prog = prog;
        }
        self.modal = modal;
        self.aux = aux;
        self.sel = sel;
        self.take_offsets(offsets);
        self.dynamic_tool = if contour.active() { dynamic_tool } else { None };
        self.contour = contour;
        self.last_moves = moves;
        if element.is_some() {
            self.element_feed = now;
        }
        if pause {
            // At rest where the block ends, until cycle start.
            self.machine.flush(&mut Sink::new(io, self.drive));
            let code = if b.stop == Some(Stop::Pause) { 0 } else { 1 };
            self.program_stop(code, io);
        }
        if end {
            // The end of the program: at rest, spindle and coolant off, the
            // modes of power-on but for the motion mode, the unit and F.
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.modal = Modal {
                motion: self.modal.motion,
                units: self.modal.units,
                feed: self.modal.feed,
                ..Modal::POWER_ON
            };
            self.aux = self.aux.stopped();
            self.switch_outputs(self.outputs_for(&self.aux, self.modal.units), io);
        }
        Ok(Block::Run)
    }

    /// A program stop at rest (`M00`, `M01`, a gear range, a machine's M
    /// code not in its table; `code` the M code): the board waits for
    /// cycle start, a grbl link holds at rest and goes on.
    pub(super) fn program_stop<I: Io>(&mut self, code: u16, io: &mut I) {
        if io.stop_holds() {
            // grbl: a hold at rest, answered now; what follows queues and
            // waits for cycle start.
            self.machine.hold(&mut Sink::new(io, self.drive));
        } else {
            if io.background().is_some() {
                let mut view = self.view(self.machine.speed());
                view.stop = Some(code);
                io.view(&view);
            } else {
                // Nothing moves while it waits: one line answers every
                // status byte.
                let st = self.machine.status(&mut Sink::new(io, self.drive));
                let mut view = self.view(0);
                (view.outputs.rpm, view.stop) = (st.spindle, Some(code));
                let mut line = status_line("!STATUS", st.motion, st.issued, st.queued, &view);
                io.stop_status(line.finish());
            }
            io.program_stop(code);
        }
        self.share_view(io);
    }

    /// The spindle's top speed with `aux`'s gear range: `AUX SMAX` and the
    /// range's own, the lower.
    pub(super) fn top_speed(&self, aux: &Aux) -> Option<Length> {
        let gear = aux.gear.and_then(|g| {
            self.gears
                .get(usize::from(g).saturating_sub(1))
                .copied()
                .flatten()
        });
        match (self.top, gear) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Lecture 13's `G45`–`G48`: each axis move the block names, from the
    /// programmed point to `target`, lengthened (shortened) by the
    /// register's offset for that axis (geometry plus wear; X on the
    /// radius), once or twice. A move of zero goes the offset's way, as if
    /// it were positive (Fanuc's rule).
    fn position_offset(
        &self,
        po: crate::gcode::PositionOffset,
        modal: &Modal,
        offsets: &Offsets,
        words: (Option<Length>, Option<Length>),
        mut target: [Length; 2],
        b: &crate::gcode::Block,
    ) -> Result<[Length; 2], Refusal<'static>> {
        if !matches!(modal.motion, Motion::Rapid | Motion::Linear) {
            return Err(Refusal::Missing("G45 to G48 move in a line: G00 or G01"));
        }
        if self.contour.active() || b.compensation.is_some() {
            return Err(Refusal::Busy("G45 to G48 with nose compensation"));
        }
        let beyond = "G45 to G48: the move with its offset beyond 99999.999999 mm";
        let k = offsets
            .tools
            .get(usize::from(po.register).wrapping_sub(1))
            .and_then(|t| t.offset())
            .ok_or(Refusal::Range(beyond))?;
        let given = [words.0.is_some(), words.1.is_some()];
        for axis in 0..2 {
            let (Some(&on), Some(&k), Some(t), Some(&from)) = (
                given.get(axis),
                k.get(axis),
                target.get_mut(axis),
                self.prog.get(axis),
            ) else {
                continue;
            };
            if !on {
                continue;
            }
            let m = t.checked_sub(from).ok_or(Refusal::Range(beyond))?;
            let sign: i64 = if m < Length::ZERO { -1 } else { 1 };
            let delta = k
                .as_angstrom()
                .checked_mul(i64::from(po.times) * sign)
                .and_then(Length::from_angstrom)
                .ok_or(Refusal::Range(beyond))?;
            *t = t.checked_add(delta).ok_or(Refusal::Range(beyond))?;
        }
        Ok(target)
    }

    /// The tool selection and the offsets after a block's `G54`–`G59`,
    /// `T`, `M06`, `G43`/`G49` and `G10` words.
    #[inline(never)]
    fn offsets_after(
        &self,
        b: &crate::gcode::Block,
        aux: &Aux,
        diam: bool,
    ) -> Result<(Selection, Offsets), Refusal<'static>> {
        let mut sel = self.sel;
        if let Some(w) = b.wcs {
            sel.wcs = w;
        }
        let beyond = "offset register beyond the table's 32";
        match self.dialect {
            Dialect::Fanuc => {
                if let Some(t) = b.tool {
                    sel.loaded = t.tool;
                    sel.register = t.offset.unwrap_or(0);
                    if usize::from(sel.register) > TOOL_REGISTERS {
                        return Err(Refusal::Value("T", beyond));
                    }
                }
            }
            Dialect::Iso => {
                if b.tool_change {
                    sel.loaded = aux
                        .tool
                        .map(|t| t.tool)
                        .ok_or(Refusal::Missing("M06 needs the tool: T"))?;
                }
                match b.tool_offset {
                    Some(ToolOffset::On(h)) => {
                        sel.register = h.unwrap_or(sel.loaded);
                        if usize::from(sel.register) > TOOL_REGISTERS {
                            return Err(Refusal::Value("H", beyond));
                        }
                    }
                    Some(ToolOffset::Off) => sel.register = 0,
                    None => {}
                }
            }
        }
        let mut offsets = self.offsets;
        if let Some(set) = b.set_work {
            // The tool's offset with the selection of this block.
            let tool = offsets
                .tool_offset(&sel)
                .ok_or(Refusal::Range(RANGE_OFFSET))?;
            let values = [block_x(b, diam), b.z];
            let register = usize::from(set.register).saturating_sub(1);
            let work = offsets
                .work
                .get_mut(register)
                .ok_or(Refusal::Value("P", "names G54 to G59: 1 to 6"))?;
            for (((w, v), at), off) in work.iter_mut().zip(values).zip(self.cmd).zip(tool) {
                let Some(v) = v else { continue };
                *w = if set.here {
                    // So that the tool's point has coordinate v.
                    at.checked_sub(off)
                        .and_then(|p| p.checked_sub(v))
                        .ok_or(Refusal::Range(RANGE_OFFSET))?
                } else {
                    v
                };
            }
        }
        Ok((sel, offsets))
    }

    /// The nose compensation uses: the register of the tool in effect
    /// (Fanuc: the offset register; ISO: the loaded tool's) when its nose
    /// is set, else the configured `RN` and `TIP`.
    pub(super) fn nose(&self, offsets: &Offsets, sel: &Selection) -> Tool {
        let register = match self.dialect {
            Dialect::Fanuc => sel.register,
            Dialect::Iso => sel.loaded,
        };
        match offsets.register(register).and_then(|t| t.nose) {
            Some((r, tip)) => Tool::new(r, TipCode::new(tip).unwrap_or(self.cfg.tip)),
            None => Tool::new(self.cfg.rn, self.cfg.tip),
        }
    }

    /// Plans one move from the commanded point `cmd` and registers `pos`,
    /// checking every block of it against the machine's limits.
    pub(super) fn plan_move<I: Io>(
        &self,
        cmd: [Length; 2],
        pos: ImpulsePoint,
        m: &Move,
        feed: Option<Feed>,
        io: &mut I,
    ) -> Result<Planned, Refusal<'static>> {
        let end = point(m.to)?;
        match m.kind {
            MoveKind::Line { rapid } => {
                let to = ImpulsePoint {
                    x: quantize(end[0], self.cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
                    z: quantize(end[1], self.cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
                };
                let block = LinearBlock::new(pos, to).map_err(|_| Refusal::Range(RANGE_BLOCK))?;
                Ok(Planned::Line {
                    block,
                    end,
                    rapid,
                    feed,
                })
            }
            MoveKind::Arc { centre, dir } => {
                let points = ArcPoints {
                    start: cmd,
                    end,
                    centre: point(centre)?,
                };
                let plan =
                    ChordPlan::new(&points, dir, self.cfg.tol, self.cfg.pass == Pass::Finish)?;
                let to = self.check_chords(&plan, pos, io)?;
                Ok(Planned::Arc {
                    plan,
                    points,
                    dir,
                    to,
                    feed,
                })
            }
        }
    }

    /// Runs one planned move, sends its `DATA` line, and adds its step
    /// events to `crc`.
    pub(super) fn run_planned<I: Io>(&mut self, p: &Planned, mut crc: Crc32, io: &mut I) -> Crc32 {
        match *p {
            Planned::Line {
                block,
                end,
                rapid,
                feed,
            } => {
                crc = block_crc(&block, crc);
                self.cmd = end;
                self.pos = block.to();
                let h = [self.cfg.hx, self.cfg.hz];
                let feed = if rapid { None } else { feed };
                self.machine.queue(
                    point_q32(end),
                    block,
                    feed,
                    h,
                    &mut Sink::new(io, self.drive),
                );
                let word = if rapid { Motion::Rapid } else { Motion::Linear };
                self.send_block_data(io, word, None);
            }
            Planned::Arc {
                plan,
                points,
                dir,
                feed,
                ..
            } => {
                crc = self.run_chords(&plan, &points, feed, io, false, crc);
                let word = match dir {
                    ArcDir::Cw => Motion::ArcCw,
                    ArcDir::Ccw => Motion::ArcCcw,
                };
                self.send_block_data(io, word, Some(centre_minus(points.centre, points.start)));
            }
        }
        crc
    }

    /// `DATA G0n X… Z… [I… K…]` for the block just run (its end is the
    /// commanded point; X a diameter when DIAM=1).
    fn send_block_data<I: Io>(&self, io: &mut I, motion: Motion, ik: Option<[i64; 2]>) {
        let factor = if self.cfg.diam { 2 } else { 1 };
        let x = div_round_half_away(self.cmd[0].as_angstrom() * factor, 1_000);
        let mut line = ReplyLine::new();
        let _ = write!(line, "DATA {} X", motion.word());
        let _ = write_mm4(&mut line, x);
        let _ = write!(line, " Z{}", self.cmd[1]);
        if let Some([i, k]) = ik {
            let _ = line.write_str(" I");
            let _ = write_mm4(&mut line, div_round_half_away(i, 1_000));
            let _ = line.write_str(" K");
            let _ = write_mm4(&mut line, div_round_half_away(k, 1_000));
        }
        io.send(line.finish());
    }

    /// The linear block from the registers to a commanded point.
    fn linear_block(&self, target: [Length; 2]) -> Result<LinearBlock, Refusal<'static>> {
        let to = ImpulsePoint {
            x: quantize(target[0], self.cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
            z: quantize(target[1], self.cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
        };
        LinearBlock::new(self.pos, to).map_err(|_| Refusal::Range(RANGE_BLOCK))
    }

    /// Checks every chord of a plan before the first one moves (a long
    /// check lets the transport answer its real-time requests meanwhile).
    fn check_chords<I: Io>(
        &self,
        plan: &ChordPlan,
        from: ImpulsePoint,
        io: &mut I,
    ) -> Result<ImpulsePoint, Refusal<'static>> {
        let mut at = from;
        for i in 1..=plan.chords() {
            if i % CHORDS_PER_PAUSE == 0 {
                io.pause();
            }
            let to = plan
                .chord_end(i, self.cfg.hx, self.cfg.hz)
                .map_err(|_| Refusal::Range(RANGE_POS))?;
            LinearBlock::new(at, to).map_err(|_| Refusal::Range(RANGE_BLOCK))?;
            at = to;
        }
        Ok(at)
    }

    /// Runs the chords of a checked plan, commits the end point, and returns
    /// the CRC of all their step events; `data` sends a `DATA I= NX= NZ=`
    /// line per chord.
    fn run_chords<I: Io>(
        &mut self,
        plan: &ChordPlan,
        points: &ArcPoints,
        feed: Option<Feed>,
        io: &mut I,
        data: bool,
        mut crc: Crc32,
    ) -> Crc32 {
        let mut at = self.pos;
        let h = [self.cfg.hx, self.cfg.hz];
        for i in 1..=plan.chords() {
            let Ok((to, point)) = plan.chord_point(i, h[0], h[1]) else {
                break;
            };
            let Ok(block) = LinearBlock::new(at, to) else {
                break;
            };
            crc = block_crc(&block, crc);
            self.machine
                .queue(point, block, feed, h, &mut Sink::new(io, self.drive));
            if data {
                let (nx, nz) = block.delta();
                send_data(io, format_args!("I={i} NX={nx} NZ={nz}"));
            }
            at = to;
        }
        self.cmd = points.end;
        self.pos = at;
        crc
    }

    /// Refuses a command that would move or re-zero the machine behind the
    /// contour engine's back.
    fn not_compensating(&self, what: &'static str) -> Result<(), Refusal<'static>> {
        if self.contour.active() {
            return Err(Refusal::Busy(what));
        }
        Ok(())
    }

    /// An X word as a radius (halved when DIAM=1).
    fn x_word(&self, word: Length) -> Result<Length, Refusal<'static>> {
        x_radius(word, self.cfg.diam)
    }

    #[inline(never)]
    fn drive_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [rate, pulse, setup] = parse_args(words, ["RATE", "PULSE", "SETUP"])?;
        let d = self.drive;
        let rate = parse_count("RATE", rate, d.rate_hz())?;
        let pulse = parse_count("PULSE", pulse, d.pulse_us())?;
        let setup = parse_count("SETUP", setup, d.setup_us())?;
        let drive = DriveTiming::new(rate, pulse, setup).map_err(|e| match e {
            TimingError::Rate => Refusal::Value("RATE", "must be 1 to 200000 steps/s"),
            TimingError::Pulse => Refusal::Value("PULSE", "must be 1 to 1000 us"),
            TimingError::Setup => Refusal::Value("SETUP", "must be 0 to 1000 us"),
            TimingError::PulseTooLong => Refusal::Value("PULSE", "longer than a step period"),
        })?;
        if self
            .machine
            .limits()
            .too_fast([self.cfg.hx, self.cfg.hz], drive.rate_hz())
            .is_some()
        {
            return Err(Refusal::Value(
                "RATE",
                "below what the rapid rates need (VX/HX, VZ/HZ)",
            ));
        }
        if drive != self.drive {
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.drive = drive;
        }
        send_ok(
            io,
            Some(format_args!(
                "RATE={} PULSE={} SETUP={}",
                self.drive.rate_hz(),
                self.drive.pulse_us(),
                self.drive.setup_us()
            )),
        );
        Ok(())
    }

    #[inline(never)]
    fn move_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [x, z, inc, feed] = parse_args(words, ["X", "Z", "INC", "F"])?;
        self.not_compensating("MOVE")?;
        let feed = match feed {
            Some(v) => Some(parse_feed(v)?),
            None => None,
        };
        let inc = match inc {
            None => false,
            Some(v) => parse_flag("INC", v)?,
        };
        // Absolute words are work coordinates; increments add to where the
        // tool is.
        let off = self.offset();
        let mut target = self.cmd;
        if let Some(v) = x {
            let radius = self.x_word(parse_length("X", v)?)?;
            let from = if inc { self.cmd[0] } else { off[0] };
            target[0] = step(from, radius, true, "X beyond 99999.999999 mm")?;
        }
        if let Some(v) = z {
            let word = parse_length("Z", v)?;
            let from = if inc { self.cmd[1] } else { off[1] };
            target[1] = step(from, word, true, "Z beyond 99999.999999 mm")?;
        }
        let block = self.linear_block(target)?;
        let crc = block_crc(&block, Crc32::new());
        self.cmd = target;
        self.prog = self.work_point(target);
        self.pos = block.to();
        let h = [self.cfg.hx, self.cfg.hz];
        self.machine.queue(
            point_q32(target),
            block,
            feed,
            h,
            &mut Sink::new(io, self.drive),
        );
        send_ok(
            io,
            Some(format_args!(
                "{}",
                MotionSummary::new(block.from(), block.to(), &crc)
            )),
        );
        Ok(())
    }

    /// `LIMITS [VX=] [VZ=] [AX=] [AZ=] [JD=]`: the motion limits, applied
    /// whole at rest, or reported.
    #[inline(never)]
    fn limits_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let keys = ["VX", "VZ", "AX", "AZ", "JD"];
        let values = parse_args(words, keys)?;
        let now = *self.machine.limits();
        let old = [
            now.rate(0),
            now.rate(1),
            now.accel(0),
            now.accel(1),
            now.junction(),
        ];
        let mut v = old;
        for ((slot, value), key) in v.iter_mut().zip(values).zip(keys) {
            if let Some(text) = value {
                *slot = parse_rate(key, text, Refusal::Value(key, "too large"))?;
            }
        }
        let limits = Limits::new([v[0], v[1]], [v[2], v[3]], v[4]).map_err(|e| match e {
            LimitsError::Rate(0) => {
                Refusal::Value("VX", "must be over 0, at most 99999.999999 mm/min")
            }
            LimitsError::Rate(_) => {
                Refusal::Value("VZ", "must be over 0, at most 99999.999999 mm/min")
            }
            LimitsError::Accel(0) => Refusal::Value("AX", "must be 10 to 99999.999999 mm/s2"),
            LimitsError::Accel(_) => Refusal::Value("AZ", "must be 10 to 99999.999999 mm/s2"),
            LimitsError::Junction => Refusal::Value("JD", "must be 0 to 10 mm"),
        })?;
        if let Some(axis) = limits.too_fast([self.cfg.hx, self.cfg.hz], self.drive.rate_hz()) {
            let key = ["VX", "VZ"][axis & 1];
            return Err(Refusal::Value(
                key,
                "needs more step events than DRIVE RATE",
            ));
        }
        if limits != now {
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.machine.set_limits(limits);
        }
        let l = self.machine.limits();
        send_ok(
            io,
            Some(format_args!(
                "VX={} VZ={} AX={} AZ={} JD={} TICK={} LOOKAHEAD={}",
                l.rate(0),
                l.rate(1),
                l.accel(0),
                l.accel(1),
                l.junction(),
                self.machine.tick().hz(),
                WINDOW
            )),
        );
        Ok(())
    }

    /// `STATUS`: where the axes are now (the steps issued), their speed and
    /// the blocks waiting.
    fn status_reply<I: Io>(&self, io: &mut I, prefix: &str) {
        let mut st = self.machine.status(&mut Sink::new(io, self.drive));
        if let (Some(registers), None) = (self.checking, io.background()) {
            // Check mode on the virtual clock: its motion went nowhere.
            (st.issued, st.motion, st.queued) = (registers, Axes::Idle, 0);
        }
        let mut view = self.view(st.speed(self.machine.tick()));
        view.outputs.rpm = st.spindle;
        let mut line = status_line(prefix, st.motion, st.issued, st.queued, &view);
        if prefix.starts_with('!') {
            if let Some(timing) = io.timing() {
                timing.write_to(&mut line);
            }
        }
        io.send(line.finish());
    }

    /// What a status line needs of the session, with the speed.
    fn view(&self, speed: i64) -> StatusView {
        StatusView {
            hx: self.cfg.hx.as_angstrom(),
            hz: self.cfg.hz.as_angstrom(),
            diam: self.cfg.diam,
            speed,
            starved: self.machine.starved(),
            stop: None,
            outputs: self.outputs,
        }
    }

    /// Hands the view to a transport that runs motion in the background
    /// (it answers a status byte itself while it waits); no work for one
    /// without.
    fn share_view<I: Io>(&self, io: &mut I) {
        if io.background().is_some() {
            let view = self.view(self.machine.speed());
            io.view(&view);
        }
    }

    /// A board's stepper needs the next block (`docs/motion.md`): starts
    /// it now if one is queued in the open run.
    pub fn poll<I: Io>(&mut self, io: &mut I) {
        self.machine.poll(&mut Sink::new(io, self.drive));
    }

    /// Whether the axes are at rest, held or with nothing to run (a
    /// device without motion in the background always is).
    pub fn held_or_idle<I: Io>(&self, io: &mut I) -> bool {
        if io.background().is_none() {
            return true;
        }
        let st = self.machine.status(&mut Sink::new(io, self.drive));
        matches!(st.motion, Axes::Idle | Axes::Held)
    }

    /// Whether the last reset dropped motion that had been answered and
    /// had not all run (blocks queued, the axes moving, braking, or held
    /// with more to do).
    pub const fn reset_dropped_motion(&self) -> bool {
        self.reset_dropped
    }

    /// Check mode begins (grbl's `$C`): lines go on through a transport
    /// that moves nothing, and the registers where it began are kept.
    /// Only at rest with nothing queued (false otherwise).
    pub fn check_begin<I: Io>(&mut self, io: &mut I) -> bool {
        let st = self.machine.status(&mut Sink::new(io, self.drive));
        if st.motion != Axes::Idle || st.queued > 0 {
            return false;
        }
        self.checking = Some(st.issued);
        true
    }

    /// Check mode ends: what its lines queued is forgotten and the
    /// registers are where it began; a reset follows (as grbl's).
    pub fn check_end(&mut self) {
        if let Some(registers) = self.checking.take() {
            self.machine.forget(registers);
        }
    }

    /// Starts the queued blocks now, the run ending at rest after them
    /// (the link has gone quiet: grbl plans with what it has).
    pub fn release<I: Io>(&mut self, io: &mut I) {
        self.machine.release(&mut Sink::new(io, self.drive));
    }

    /// Whether blocks are queued and not started (with or without a run
    /// under way): a quiet link releases them.
    pub fn waiting(&self) -> bool {
        self.machine.queued() > 0
    }

    /// Whether [`Session::poll`] could start a block.
    pub fn can_feed(&self) -> bool {
        self.machine.can_feed()
    }

    /// A real-time byte: acted on at once, answered by one line that
    /// starts with `!` (a request's reply never does).
    pub fn realtime<I: Io>(&mut self, rt: Realtime, io: &mut I) {
        match rt {
            Realtime::Status => {}
            Realtime::Hold => self.machine.hold(&mut Sink::new(io, self.drive)),
            Realtime::Resume => self.machine.resume(&mut Sink::new(io, self.drive)),
            Realtime::Reset => return self.reset(io),
        }
        self.status_reply(io, "!STATUS");
    }

    /// Ctrl-X: everything queued and started is dropped at once, the
    /// registers keep the steps issued and the commanded point becomes
    /// theirs; the session restarts as after a power cycle (modal state,
    /// feed, compensation, session token), the configuration, drive and
    /// limits kept. Answered `!RESET DONE= OF= PX= PZ=`: the events of the
    /// block that was running that were issued, of how many.
    fn reset<I: Io>(&mut self, io: &mut I) {
        let (found, issued) = self.drop_motion(io);
        self.reset_dropped = found.dropped;
        self.cycles.abandon();
        self.sel = Selection::POWER_ON;
        self.prog = self.work_point(self.cmd);
        self.modal = Modal::POWER_ON;
        self.aux = Aux::POWER_ON;
        // The board dropped its outputs with the motion; the session's
        // follow.
        self.switch_outputs(self.outputs_for(&self.aux, Units::Mm), io);
        self.token = 0;
        self.last_id = None;
        self.last_final.clear();
        let mut line = ReplyLine::new();
        let _ = write!(
            line,
            "!RESET DONE={} OF={} PX={} PZ={}",
            found.done,
            found.of,
            issued.x.get(),
            issued.z.get()
        );
        io.send(line.finish());
        self.share_view(io);
    }

    /// Everything queued and started dropped at once: the registers keep
    /// the steps issued and the commanded point becomes theirs; nothing
    /// waits for compensation.
    fn drop_motion<I: Io>(&mut self, io: &mut I) -> (Aborted, ImpulsePoint) {
        let (found, issued) = self.machine.abort(&mut Sink::new(io, self.drive));
        let cmd = [
            // A register times its price is a position the machine holds.
            Length::from_angstrom(i64::from(issued.x.get()) * self.cfg.hx.as_angstrom())
                .unwrap_or(Length::ZERO),
            Length::from_angstrom(i64::from(issued.z.get()) * self.cfg.hz.as_angstrom())
                .unwrap_or(Length::ZERO),
        ];
        self.machine.set_point(point_q32(cmd));
        self.cmd = cmd;
        self.pos = issued;
        self.contour = Contour::new();
        self.last_moves = Moves::new();
        self.element_feed = None;
        (found, issued)
    }

    /// A jog cancelled (grbl's 0x85), once held at rest: what is left of
    /// it is dropped; the modal state, the offsets and the session stay.
    pub fn cancel_motion<I: Io>(&mut self, io: &mut I) {
        self.drop_motion(io);
        self.prog = self.work_point(self.cmd);
        self.share_view(io);
    }

    /// Sets the feed override, percent (10 … 200).
    pub fn set_feed_override(&mut self, percent: u8) {
        self.feed_override = percent.clamp(10, 200);
    }

    /// `feed` under the overrides: the feed's, and per revolution the
    /// spindle's too (the spindle turns at the overridden speed).
    pub(super) fn overridden(&self, feed: Feed, mode: FeedMode) -> Feed {
        let spindle = if mode == FeedMode::PerRev {
            self.spindle_override
        } else {
            100
        };
        let percent = i64::from(self.feed_override) * i64::from(spindle);
        if percent == 10_000 {
            return feed;
        }
        let scaled = div_round_half_away(feed.mm_per_min().as_angstrom() * percent, 10_000);
        Length::from_angstrom(scaled)
            .and_then(Feed::new)
            .unwrap_or(feed)
    }

    /// Sets the rapid override, percent (grbl's 100, 50, 25): rapids
    /// queued from now on.
    pub fn set_rapid_override(&mut self, percent: u8) {
        self.machine.set_rapid_override(percent);
    }

    /// Sets the spindle override, percent (10 … 200): at once at rest,
    /// else with the blocks queued from now on.
    pub fn set_spindle_override<I: Io>(&mut self, percent: u8, io: &mut I) {
        self.spindle_override = percent.clamp(10, 200);
        let outputs = self.outputs_for(&self.aux, self.modal.units);
        if self.machine.waiting() || !self.held_or_idle(io) {
            self.machine.set_spindle(outputs.rpm);
        } else {
            self.switch_outputs(outputs, io);
        }
    }

    /// The tool table, the work offsets and the stored positions.
    pub fn offsets(&self) -> &Offsets {
        &self.offsets
    }

    /// Counts the changes of what a board keeps in flash (the table, the
    /// work offsets and the stored positions): a board saves when it moved.
    pub fn offsets_generation(&self) -> u32 {
        self.generation
    }

    /// The table, work offsets and stored positions kept from before the
    /// power cut (a board loads them at power-on, before any request).
    pub fn restore_offsets(&mut self, offsets: Offsets) {
        self.offsets = offsets;
        self.prog = self.work_point(self.cmd);
    }

    /// New offsets; what a board keeps of them changed or not.
    fn take_offsets(&mut self, new: Offsets) {
        let kept = |o: &Offsets| (o.work, o.tools, o.reference, o.mcodes);
        if kept(&new) != kept(&self.offsets) {
            self.generation = self.generation.wrapping_add(1);
        }
        self.offsets = new;
    }

    /// The offsets in effect (machine = work + this); always within range,
    /// as every change of them is checked.
    fn offset(&self) -> [Length; 2] {
        self.offsets.vector(&self.sel).unwrap_or([Length::ZERO; 2])
    }

    /// A machine point in work coordinates, as far as the range allows.
    fn work_point(&self, machine: [Length; 2]) -> [Length; 2] {
        let off = self.offset();
        [
            machine[0].checked_sub(off[0]).unwrap_or(machine[0]),
            machine[1].checked_sub(off[1]).unwrap_or(machine[1]),
        ]
    }

    /// `OK SPINDLE= S= SMODE= LIMIT= COOLANT= T=`: the auxiliary
    /// functions as programmed; `S` the commanded rpm at the programmed X (0
    /// while stopped), `LIMIT` 0 when none is set, `T` as written in the
    /// dialect (`-` when none was named).
    #[inline(never)]
    fn aux_reply<I: Io>(&self, io: &mut I) {
        let a = &self.aux;
        let spindle = match a.spindle.turning {
            Spindle::Cw => "CW",
            Spindle::Ccw => "CCW",
            Spindle::Off => "OFF",
        };
        let mode = match a.spindle.mode {
            SpindleMode::Rpm => "RPM",
            SpindleMode::Surface => "CSS",
        };
        let coolant = match a.coolant {
            Coolant::Mist => "MIST",
            Coolant::Flood => "FLOOD",
            Coolant::Off => "OFF",
        };
        let rpm = a
            .spindle
            .within(self.top_speed(a))
            .running_rpm(self.prog[0], self.modal.units);
        let limit = a.spindle.clamp.unwrap_or(Length::ZERO);
        let mut line = ReplyLine::new();
        let _ = write!(
            line,
            "OK SPINDLE={spindle} S={rpm} SMODE={mode} LIMIT={limit} COOLANT={coolant} T="
        );
        let _ = match a.tool {
            None => line.write_str("-"),
            Some(ToolWord {
                tool,
                offset: Some(o),
            }) => write!(line, "{tool:02}{o:02}"),
            Some(ToolWord { tool, offset: None }) => write!(line, "{tool}"),
        };
        let top = self.top.unwrap_or(Length::ZERO);
        let ms = self.spinup_us / 1_000;
        let _ = write!(line, " SMAX={top} SPINUP={}.{:03}", ms / 1_000, ms % 1_000);
        io.send(line.finish());
    }

    /// `AUX [SMAX=] [SPINUP=]`: the spindle's top speed (rpm at full PWM
    /// duty, 0 for none) and the wait after it starts or changes speed
    /// (seconds); with the auxiliary functions as programmed.
    fn aux_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [smax, spinup] = parse_args(words, ["SMAX", "SPINUP"])?;
        let mut top = self.top;
        if let Some(v) = smax {
            let l = parse_amount("SMAX", v, 99_999_999, "must be 0 to 99999.999 rpm")?;
            top = (l > Length::ZERO).then_some(l);
        }
        let mut spinup_us = self.spinup_us;
        if let Some(v) = spinup {
            let l = parse_amount("SPINUP", v, 60_000, "must be 0 to 60 s")?;
            // Å of a second to whole ms, rounded half up.
            spinup_us = (l.as_angstrom().unsigned_abs() + 5_000) / 10_000 * 1_000;
        }
        if top != self.top {
            // What the spindle turns at changes with it: at rest.
            if self.aux.spindle.turning != Spindle::Off {
                self.aux
                    .spindle
                    .within(top)
                    .rpm(self.prog[0], self.modal.units)
                    .map_err(|e| Refusal::Value("SMAX", e.as_str()))?;
            }
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.top = top;
            self.switch_outputs(self.outputs_for(&self.aux, self.modal.units), io);
        }
        self.spinup_us = spinup_us;
        self.aux_reply(io);
        Ok(())
    }

    /// `MCODE [M=n DO=STOP|NONE|ON|OFF|HIGH|LOW [N=1..4]]`: what one of
    /// the machine's own M codes does — stop with a message (the default,
    /// and what `STOP` sets back), nothing, switch user output `N` on or
    /// off, or wait for user input `N` to read high or low. Alone: the
    /// table, a `DATA` line per code set. Kept with the tool table.
    #[inline(never)]
    fn mcode_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [m, action, n] = parse_args(words, ["M", "DO", "N"])?;
        if let Some(m) = m {
            let code = match m.parse::<u16>() {
                Ok(c @ 0..=999) if m.bytes().all(|b| b.is_ascii_digit()) => c,
                _ => return Err(Refusal::Value("M", "must be a whole M code 0 to 999")),
            };
            // The codes the device runs itself are not the machine's.
            if matches!(code, 0..=9 | 30 | 41..=44 | 98 | 99) {
                return Err(Refusal::Value(
                    "M",
                    "is one the device runs itself (M00-M09, M30, M41-M44, M98, M99)",
                ));
            }
            let n = match n {
                None => None,
                Some(v) => match v.parse::<u8>() {
                    Ok(k @ 1..=4) if v.len() == 1 => Some(k),
                    _ => {
                        return Err(Refusal::Value(
                            "N",
                            "must be 1 to 4 (a user output or input)",
                        ))
                    }
                },
            };
            let need_n =
                |n: Option<u8>| n.ok_or(Refusal::Missing("ON, OFF, HIGH and LOW need N: 1 to 4"));
            let action = match action.unwrap_or("STOP") {
                a if a.eq_ignore_ascii_case("STOP") => MAction::Stop,
                a if a.eq_ignore_ascii_case("NONE") => MAction::Nothing,
                a if a.eq_ignore_ascii_case("ON") => MAction::Output(need_n(n)?, true),
                a if a.eq_ignore_ascii_case("OFF") => MAction::Output(need_n(n)?, false),
                a if a.eq_ignore_ascii_case("HIGH") => MAction::Wait(need_n(n)?, true),
                a if a.eq_ignore_ascii_case("LOW") => MAction::Wait(need_n(n)?, false),
                _ => {
                    return Err(Refusal::Value(
                        "DO",
                        "must be STOP, NONE, ON, OFF, HIGH or LOW",
                    ))
                }
            };
            if matches!(action, MAction::Stop | MAction::Nothing) && n.is_some() {
                return Err(Refusal::Missing("N only with ON, OFF, HIGH or LOW"));
            }
            let mut offsets = self.offsets;
            if !offsets.mcodes.set(code * 10, action) {
                return Err(Refusal::Range("the table holds 16 M codes"));
            }
            self.take_offsets(offsets);
        } else if action.is_some() || n.is_some() {
            return Err(Refusal::Missing("DO and N need M: the code"));
        }
        let listing = m.is_none();
        let mut count = 0;
        for (code, action) in self.offsets.mcodes.entries() {
            count += 1;
            if !listing {
                continue;
            }
            let m = code / 10;
            match action {
                MAction::Stop => {}
                MAction::Nothing => send_data(io, format_args!("M{m:02} DO=NONE")),
                MAction::Output(n, on) => send_data(
                    io,
                    format_args!("M{m:02} DO={} N={n}", if on { "ON" } else { "OFF" }),
                ),
                MAction::Wait(n, high) => send_data(
                    io,
                    format_args!("M{m:02} DO={} N={n}", if high { "HIGH" } else { "LOW" }),
                ),
            }
        }
        send_ok(io, Some(format_args!("CODES={count}")));
        Ok(())
    }

    /// `GEAR [N=1..4 TOP=rpm]`: the top speed of a gear range (`M41` …
    /// `M44`; 0: the range adds no limit). Answered with the range in
    /// effect and every range's top.
    #[inline(never)]
    fn gear_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [n, top] = parse_args(words, ["N", "TOP"])?;
        match (n, top) {
            (Some(n), Some(top)) => {
                let slot = match n.parse::<usize>() {
                    Ok(k @ 1..=4) if n.len() == 1 => k - 1,
                    _ => return Err(Refusal::Value("N", "must be 1 to 4 (M41 to M44)")),
                };
                let l = parse_amount("TOP", top, 99_999_999, "must be 0 to 99999.999 rpm")?;
                if let Some(g) = self.gears.get_mut(slot) {
                    *g = (l > Length::ZERO).then_some(l);
                }
            }
            (None, None) => {}
            _ => {
                return Err(Refusal::Missing(
                    "GEAR sets a range with N and TOP together",
                ))
            }
        }
        let mut line = ReplyLine::new();
        let _ = match self.aux.gear {
            Some(g) => write!(line, "OK RANGE={g}"),
            None => line.write_str("OK RANGE=-"),
        };
        for (i, g) in self.gears.iter().enumerate() {
            let _ = write!(line, " G{}={}", i + 1, g.unwrap_or(Length::ZERO));
        }
        io.send(line.finish());
        Ok(())
    }

    /// The outputs for `aux` with the tool at the programmed X (`units`
    /// those of a surface speed).
    fn outputs_for(&self, aux: &Aux, units: Units) -> Outputs {
        let rpm = aux
            .spindle
            .within(self.top_speed(aux))
            .running_rpm(self.prog[0], units);
        let rpm = if self.spindle_override == 100 {
            rpm
        } else {
            let scaled = Length::from_angstrom(div_round_half_away(
                rpm.as_angstrom() * i64::from(self.spindle_override),
                100,
            ))
            .unwrap_or(rpm);
            // Never above the spindle's top speed.
            self.top.map_or(scaled, |top| scaled.min(top))
        };
        Outputs {
            spindle: aux.spindle.turning,
            rpm: milli_rpm(rpm),
            top: self.top.map_or(0, milli_rpm),
            coolant: aux.coolant,
        }
    }

    /// Switches the spindle and coolant outputs, the axes at rest.
    fn switch_outputs<I: Io>(&mut self, outputs: Outputs, io: &mut I) {
        self.outputs = outputs;
        self.machine.switch_spindle(outputs.rpm);
        io.outputs(&outputs);
        self.share_view(io);
    }

    /// `OK PX= PZ= X= Z= [MX= MZ=]`: the registers, the commanded point in
    /// work coordinates, and while offsets are in effect in machine
    /// coordinates too (X a diameter when `DIAM=1`).
    #[inline(never)]
    fn pos_reply<I: Io>(&self, io: &mut I) {
        let work = self.work_point(self.cmd);
        let mut line = ReplyLine::new();
        let _ = write!(
            line,
            "OK PX={} PZ={} X=",
            self.pos.x.get(),
            self.pos.z.get()
        );
        let _ = self.write_x(&mut line, work[0]);
        let _ = write!(line, " Z={}", work[1]);
        if work != self.cmd {
            let _ = line.write_str(" MX=");
            let _ = self.write_x(&mut line, self.cmd[0]);
            let _ = write!(line, " MZ={}", self.cmd[1]);
        }
        io.send(line.finish());
    }

    /// An X value as the words read it: a diameter when `DIAM=1`.
    fn write_x(&self, line: &mut ReplyLine, x: Length) -> fmt::Result {
        let factor = if self.cfg.diam { 2 } else { 1 };
        // |x| < 10¹² Å: doubling cannot overflow.
        write_mm4(line, div_round_half_away(x.as_angstrom() * factor, 1_000))
    }

    /// `TOOL N= [X=] [Z=] [WX=] [WZ=] [R=] [T=]`: an offset register of the
    /// tool table, set or reported: geometry and wear (X a diameter when
    /// `DIAM=1`), nose radius and tip code (`R=- T=-` until set).
    #[inline(never)]
    fn tool_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [n, x, z, wx, wz, r, t] = parse_args(words, ["N", "X", "Z", "WX", "WZ", "R", "T"])?;
        if n.is_none() {
            return Err(Refusal::Missing("TOOL needs N, the register: 1 to 32"));
        }
        let n = match parse_count("N", n, 0)? {
            n @ 1..=32 => n as u8,
            _ => return Err(Refusal::Value("N", "must be 1 to 32")),
        };
        let mut offsets = self.offsets;
        let entry = offsets
            .tools
            .get_mut(usize::from(n) - 1)
            .ok_or(Refusal::Value("N", "must be 1 to 32"))?;
        if let Some(v) = x {
            entry.geometry[0] = self.x_word(parse_length("X", v)?)?;
        }
        if let Some(v) = z {
            entry.geometry[1] = parse_length("Z", v)?;
        }
        if let Some(v) = wx {
            entry.wear[0] = self.x_word(parse_length("WX", v)?)?;
        }
        if let Some(v) = wz {
            entry.wear[1] = parse_length("WZ", v)?;
        }
        if r.is_some() || t.is_some() {
            let (r0, t0) = entry.nose.unwrap_or((self.cfg.rn, self.cfg.tip.get()));
            let r = match r {
                Some(v) => parse_bounded("R", v, 0, MAX_NOSE_RADIUS_UM, "must be 0 to 25 mm")?,
                None => r0,
            };
            let t = match parse_count("T", t, u32::from(t0))? {
                t @ 0..=9 => t as u8,
                _ => return Err(Refusal::Value("T", "must be 0 to 9")),
            };
            entry.nose = Some((r, t));
        }
        let entry = *entry;
        let setting = x.is_some() || z.is_some() || wx.is_some() || wz.is_some();
        if setting || r.is_some() || t.is_some() {
            if offsets.vector(&self.sel).is_none() {
                return Err(Refusal::Range(RANGE_OFFSET));
            }
            let in_effect = n == self.sel.register || n == self.sel.loaded;
            if self.contour.active() && in_effect {
                return Err(Refusal::Busy("TOOL of the register in effect"));
            }
        }
        self.take_offsets(offsets);
        let mut line = ReplyLine::new();
        let _ = write!(line, "OK N={n} X=");
        let _ = self.write_x(&mut line, entry.geometry[0]);
        let _ = write!(line, " Z={} WX=", entry.geometry[1]);
        let _ = self.write_x(&mut line, entry.wear[0]);
        let _ = write!(line, " WZ={}", entry.wear[1]);
        let _ = match entry.nose {
            Some((r, t)) => write!(line, " R={r} T={t}"),
            None => line.write_str(" R=- T=-"),
        };
        io.send(line.finish());
        Ok(())
    }

    /// `WORK G=54…59 [X=] [Z=]`: a work offset, set or reported: where
    /// that system's zero lies in machine coordinates (X a diameter when
    /// `DIAM=1`).
    #[inline(never)]
    fn work_command<'a, I: Io>(&mut self, words: Words<'a>, io: &mut I) -> Outcome<'a> {
        let [g, x, z] = parse_args(words, ["G", "X", "Z"])?;
        if g.is_none() {
            return Err(Refusal::Missing("WORK needs G, the system: 54 to 59"));
        }
        let g = match parse_count("G", g, 0)? {
            g @ 54..=59 => g as u8,
            _ => return Err(Refusal::Value("G", "must be 54 to 59")),
        };
        let mut offsets = self.offsets;
        let work = offsets
            .work
            .get_mut(usize::from(g) - 54)
            .ok_or(Refusal::Value("G", "must be 54 to 59"))?;
        if let Some(v) = x {
            work[0] = self.x_word(parse_length("X", v)?)?;
        }
        if let Some(v) = z {
            work[1] = parse_length("Z", v)?;
        }
        let work = *work;
        if x.is_some() || z.is_some() {
            if offsets.vector(&self.sel).is_none() {
                return Err(Refusal::Range(RANGE_OFFSET));
            }
            if self.contour.active() && g - 54 == self.sel.wcs {
                return Err(Refusal::Busy("WORK of the system in effect"));
            }
        }
        self.take_offsets(offsets);
        let mut line = ReplyLine::new();
        let _ = write!(line, "OK G={g} X=");
        let _ = self.write_x(&mut line, work[0]);
        let _ = write!(line, " Z={}", work[1]);
        io.send(line.finish());
        Ok(())
    }
}

const RANGE_POS_X: &str = "X position beyond 999999999 impulses";
const RANGE_POS_Z: &str = "Z position beyond 999999999 impulses";
const RANGE_BLOCK: &str = "block beyond 1000000 impulses per axis";
const RANGE_POS: &str = "position beyond 999999999 impulses";
const _: () = assert!(MAX_POSITION == 999_999_999 && MAX_BLOCK_IMPULSES == 1_000_000);

/// One output block, planned and checked: ready to run without a check that
/// could fail.
pub(super) enum Planned {
    Line {
        block: LinearBlock,
        end: [Length; 2],
        rapid: bool,
        feed: Option<Feed>,
    },
    Arc {
        plan: ChordPlan,
        points: ArcPoints,
        dir: ArcDir,
        /// Registers after the last chord.
        to: ImpulsePoint,
        feed: Option<Feed>,
    },
}

impl Planned {
    /// The commanded point after it.
    pub(super) const fn end(&self) -> [Length; 2] {
        match self {
            Planned::Line { end, .. } => *end,
            Planned::Arc { points, .. } => points.end,
        }
    }

    /// The registers after it.
    pub(super) fn registers(&self) -> ImpulsePoint {
        match self {
            Planned::Line { block, .. } => block.to(),
            Planned::Arc { to, .. } => *to,
        }
    }
}

/// What a G-code block was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Block {
    /// Run (moved or not).
    Run,
    /// Skipped by block delete.
    Skipped,
}

/// `NX= NZ= PX= PZ= SEQ=`: the impulses a request issued, the registers
/// after it, and the CRC of its step events.
pub(super) struct MotionSummary {
    from: ImpulsePoint,
    to: ImpulsePoint,
    seq: u32,
}

impl MotionSummary {
    pub(super) fn new(from: ImpulsePoint, to: ImpulsePoint, crc: &Crc32) -> Self {
        MotionSummary {
            from,
            to,
            seq: crc.finish(),
        }
    }
}

impl fmt::Display for MotionSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Registers stay within ±999 999 999: the differences fit in i32.
        write!(
            f,
            "NX={} NZ={} PX={} PZ={} SEQ={:08X}",
            self.to.x.get() - self.from.x.get(),
            self.to.z.get() - self.from.z.get(),
            self.to.x.get(),
            self.to.z.get(),
            self.seq
        )
    }
}

/// `centre − start` in ångström: the I and K words of an arc.
/// A point (Å) moved by the offsets.
pub(super) fn shifted(p: [i64; 2], off: [Length; 2]) -> Result<[i64; 2], Refusal<'static>> {
    let add = |axis: usize| {
        Length::from_angstrom(p[axis])
            .and_then(|l| l.checked_add(off[axis]))
            .map(Length::as_angstrom)
            .ok_or(Refusal::Range(RANGE_OFFSET))
    };
    Ok([add(0)?, add(1)?])
}

/// A coordinate after a word: the word itself, or added to `now`.
fn step(
    now: Length,
    word: Length,
    inc: bool,
    beyond: &'static str,
) -> Result<Length, Refusal<'static>> {
    if inc {
        now.checked_add(word).ok_or(Refusal::Range(beyond))
    } else {
        Ok(word)
    }
}

/// A work point in machine coordinates.
fn to_machine(work: [Length; 2], off: [Length; 2]) -> Result<[Length; 2], Refusal<'static>> {
    let add = |axis: usize| {
        work[axis]
            .checked_add(off[axis])
            .ok_or(Refusal::Range(RANGE_OFFSET))
    };
    Ok([add(0)?, add(1)?])
}

const RANGE_OFFSET: &str = "position with its offsets beyond 99999.999999 mm";

/// An X word as a radius: halved when it is a diameter.
/// A block's X word as a radius: half of it, rounded once from the number
/// as written, when it is a diameter.
pub(super) fn block_x(b: &crate::gcode::Block, diam: bool) -> Option<Length> {
    if diam {
        b.x_half
    } else {
        b.x
    }
}

fn x_radius(word: Length, diam: bool) -> Result<Length, Refusal<'static>> {
    if diam {
        word.exact_half()
            .ok_or(Refusal::Value("X", "not an exact radius"))
    } else {
        Ok(word)
    }
}

fn centre_minus(centre: [Length; 2], start: [Length; 2]) -> [i64; 2] {
    let d = |a: Length, b: Length| a.as_angstrom() - b.as_angstrom();
    [d(centre[0], start[0]), d(centre[1], start[1])]
}

/// Adds the step-event bytes of a block to a running CRC.
pub(crate) fn block_crc(block: &LinearBlock, mut crc: Crc32) -> Crc32 {
    for e in block.events() {
        crc.push(StepEvent::bits(e));
    }
    crc
}

/// Checks a request's `*HH` and, if present, its `~CCCCCCCC` word (CRC-32 of
/// every byte before the `~`); returns the request without them and whether
/// the CRC word was there.
fn check_integrity(line: &[u8]) -> Result<(&[u8], bool), Refusal<'static>> {
    let body = strip_checksum(line)?;
    let Some(tilde) = body.iter().rposition(|&b| b == b'~') else {
        return Ok((body, false));
    };
    let (before, word) = body.split_at(tilde);
    let hex = word.get(1..).unwrap_or(&[]);
    // A CRC word stands alone at the end: after a space, eight hex digits.
    let alone = before.last().is_none_or(|&b| b == b' ' || b == b'\t');
    if !alone || hex.len() != 8 || !hex.iter().all(u8::is_ascii_hexdigit) {
        return Ok((body, false));
    }
    let given = hex
        .iter()
        .fold(0u32, |n, &b| n << 4 | u32::from(hex_value(b).unwrap_or(0)));
    let mut crc = Crc32::new();
    crc.update(before);
    if crc.finish() != given {
        return Err(Refusal::Crc);
    }
    Ok((before, true))
}

/// Splits off a leading `@id` word (1 … 4294967295).
fn split_id(body: &[u8]) -> Result<(Option<u32>, &[u8]), Refusal<'static>> {
    let start = body
        .iter()
        .position(|&b| b != b' ' && b != b'\t')
        .unwrap_or(body.len());
    let rest = body.get(start..).unwrap_or(&[]);
    let Some((b'@', after)) = rest.split_first() else {
        return Ok((None, body));
    };
    let end = after
        .iter()
        .position(|&b| b == b' ' || b == b'\t')
        .unwrap_or(after.len());
    let (digits, rest) = after.split_at(end);
    let bad = Refusal::Value("@", "request id must be 1 to 4294967295");
    if digits.is_empty() || digits.len() > 10 || !digits.iter().all(u8::is_ascii_digit) {
        return Err(bad);
    }
    let id = digits
        .iter()
        .fold(0u64, |n, &b| n * 10 + u64::from(b - b'0'));
    match u32::try_from(id) {
        Ok(id) if id > 0 => Ok((Some(id), rest)),
        _ => Err(bad),
    }
}

/// A status line: `<prefix> STATE= PX= PZ= X= Z= V= Q= STARVED=` (`docs/protocol.md`),
/// for `STATUS` and for the real-time status byte, which a transport may
/// answer itself while it waits for room.
pub fn status_line(
    prefix: &str,
    motion: Axes,
    issued: ImpulsePoint,
    queued: usize,
    view: &StatusView,
) -> ReplyLine {
    let state = match motion {
        Axes::Idle => "IDLE",
        Axes::Run => "RUN",
        Axes::Braking | Axes::Held => "HOLD",
    };
    let factor = if view.diam { 2 } else { 1 };
    // |registers| ≤ 999 999 999 and prices ≤ 10⁷ Å: within i64.
    let x = i64::from(issued.x.get()) * view.hx * factor;
    let z = i64::from(issued.z.get()) * view.hz;
    let mut line = ReplyLine::new();
    let _ = write!(
        line,
        "{prefix} STATE={state} PX={} PZ={} X=",
        issued.x.get(),
        issued.z.get()
    );
    let _ = write_mm4(&mut line, div_round_half_away(x, 1_000));
    let _ = line.write_str(" Z=");
    let _ = write_mm4(&mut line, div_round_half_away(z, 1_000));
    let _ = line.write_str(" V=");
    let speed = if motion == Axes::Held { 0 } else { view.speed };
    let _ = write_mm4(&mut line, speed);
    let _ = write!(line, " Q={queued} STARVED={}", view.starved);
    let o = &view.outputs;
    let spindle = match o.spindle {
        Spindle::Cw => "CW",
        Spindle::Ccw => "CCW",
        Spindle::Off => "OFF",
    };
    let _ = write!(line, " SPINDLE={spindle} S=");
    let _ = write_rpm(&mut line, o.rpm);
    let coolant = match o.coolant {
        Coolant::Mist => "MIST",
        Coolant::Flood => "FLOOD",
        Coolant::Off => "OFF",
    };
    let _ = write!(line, " COOLANT={coolant}");
    if let Some(code) = view.stop {
        // Waiting for cycle start after M00 or M01.
        let _ = write!(line, " STOP=M{code:02}");
    }
    line
}

/// Adds the request's id (` @n`) and CRC (` ~CCCCCCCC`) words to every reply
/// line, and remembers the final line for a repeated id.
struct Suffixed<'a, I: Io> {
    inner: &'a mut I,
    id: Option<u32>,
    crc: bool,
    last: heapless::Vec<u8, REPLY_CAPACITY>,
}

impl<I: Io> Suffixed<'_, I> {
    /// Sends a reply body (no `*HH`) with the suffix words.
    fn send_body(&mut self, body: &[u8]) {
        let mut line = ReplyLine::new();
        line.push_bytes(body);
        if let Some(id) = self.id {
            let _ = write!(line, " @{id}");
        }
        if self.crc {
            let mut crc = Crc32::new();
            crc.update(line.as_bytes());
            crc.push(b' ');
            let _ = write!(line, " ~{:08X}", crc.finish());
        }
        self.inner.send(line.finish());
    }
}

impl<I: Io> Io for Suffixed<'_, I> {
    fn send(&mut self, line: &[u8]) {
        // Every line the handler composes ends in `*HH\r\n`.
        let body = line.get(..line.len().saturating_sub(5)).unwrap_or(&[]);
        if body.starts_with(b"OK") || body.starts_with(b"ERR") {
            self.last.clear();
            let _ = self.last.extend_from_slice(body);
        }
        if self.id.is_none() && !self.crc {
            self.inner.send(line);
        } else {
            self.send_body(body);
        }
    }

    fn stop_status(&mut self, line: &[u8]) {
        self.inner.stop_status(line);
    }

    fn timing(&mut self) -> Option<super::Timing> {
        self.inner.timing()
    }

    fn stop_holds(&mut self) -> bool {
        self.inner.stop_holds()
    }
    crate::protocol::forward_io!();
}

/// LinuxCNC's lathe orientation (`G41.1 L`, its tool table's `Q`) as the
/// device's tip code: the same tips mirrored in X (its 2 is the device's
/// 3, its 6 the device's 8; 0 and 9 the nose centre).
const fn linuxcnc_orientation(l: u8) -> u8 {
    match l {
        1 => 4,
        2 => 3,
        3 => 2,
        4 => 1,
        6 => 8,
        8 => 6,
        l => l,
    }
}

/// Splits off and checks a trailing `*HH`; returns the bytes before it.
fn strip_checksum(line: &[u8]) -> Result<&[u8], Refusal<'static>> {
    // A `*` that is not the checksum's is inside a G-code comment, or the
    // request is malformed.
    let trailing =
        matches!(line, [.., b'*', h, l] if h.is_ascii_hexdigit() && l.is_ascii_hexdigit());
    let star = if trailing {
        line.iter().rposition(|&b| b == b'*')
    } else {
        let mut found = None;
        for ((i, &b), comment) in (0..).zip(line).zip(in_comment(line)) {
            if b == b'*' && !comment {
                found = Some(i);
            }
        }
        found
    };
    let Some(star) = star else {
        return Ok(line);
    };
    let Some((body, tail)) = line.split_at_checked(star) else {
        return Err(Refusal::ChecksumForm);
    };
    let given = match tail {
        [_, h, l] => match (hex_value(*h), hex_value(*l)) {
            (Some(h), Some(l)) => h << 4 | l,
            _ => return Err(Refusal::ChecksumForm),
        },
        _ => return Err(Refusal::ChecksumForm),
    };
    let expected = checksum(body);
    if given == expected {
        Ok(body)
    } else {
        Err(Refusal::Checksum(expected))
    }
}

/// For each byte of a line, whether it lies inside a G-code comment:
/// `( … )` (the parentheses included), or from `;` to the end.
fn in_comment(line: &[u8]) -> impl Iterator<Item = bool> + '_ {
    let mut paren = false;
    let mut rest = false;
    line.iter().map(move |&b| {
        if rest {
            return true;
        }
        if paren {
            paren = b != b')';
            return true;
        }
        match b {
            b'(' => paren = true,
            b';' => rest = true,
            _ => return false,
        }
        true
    })
}

fn hex_value(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'A'..=b'F' => Some(b - b'A' + 10),
        b'a'..=b'f' => Some(b - b'a' + 10),
        _ => None,
    }
}

fn no_args<'a>(mut words: Words<'a>, command: &'static str) -> Outcome<'a> {
    match words.next() {
        None => Ok(()),
        Some(_) => Err(Refusal::NoArgs(command)),
    }
}

pub(super) fn parse_length(key: &'static str, v: &str) -> Result<Length, Refusal<'static>> {
    Length::from_mm_str(v).map_err(|e| Refusal::Value(key, e.as_str()))
}

fn parse_price(key: &'static str, v: &str) -> Result<ImpulsePrice, Refusal<'static>> {
    ImpulsePrice::from_length(parse_length(key, v)?)
        .ok_or(Refusal::Value(key, "must be 0.000001 to 1 mm"))
}

fn parse_bounded(
    key: &'static str,
    v: &str,
    min_um: i64,
    max_um: i64,
    why: &'static str,
) -> Result<Length, Refusal<'static>> {
    let l = parse_length(key, v)?;
    let (lo, hi) = match (Length::from_um(min_um), Length::from_um(max_um)) {
        (Some(lo), Some(hi)) => (lo, hi),
        _ => return Err(Refusal::Value(key, why)),
    };
    if l >= lo && l <= hi {
        Ok(l)
    } else {
        Err(Refusal::Value(key, why))
    }
}

/// A quantity other than a length (rpm, seconds) written as one, 0 to
/// `max` millionths: anything else is refused with `why` alone.
fn parse_amount(
    key: &'static str,
    v: &str,
    max: i64,
    why: &'static str,
) -> Result<Length, Refusal<'static>> {
    Length::from_mm_str(v)
        .ok()
        .filter(|l| *l >= Length::ZERO && Length::from_um(max).is_some_and(|m| *l <= m))
        .ok_or(Refusal::Value(key, why))
}

/// An unsigned decimal count of at most 7 digits, or `default` when absent.
fn parse_count(key: &'static str, v: Option<&str>, default: u32) -> Result<u32, Refusal<'static>> {
    let Some(v) = v else {
        return Ok(default);
    };
    if v.is_empty() || v.len() > 7 || !v.bytes().all(|b| b.is_ascii_digit()) {
        return Err(Refusal::Value(key, "not a whole number"));
    }
    Ok(v.bytes().fold(0, |n, b| n * 10 + u32::from(b - b'0')))
}

/// A feed in mm/min: 0.001 … 99 999.999999, at most 6 decimals.
fn parse_feed(v: &str) -> Result<Feed, Refusal<'static>> {
    let range = Refusal::Value("F", "must be 0.001 to 99999.999999 mm/min");
    let f = parse_rate("F", v, range)?;
    Feed::new(f).ok_or(Refusal::Value("F", "must be 0.001 to 99999.999999 mm/min"))
}

/// A rate or acceleration word: a length's syntax, `range` when too large.
fn parse_rate(
    key: &'static str,
    v: &str,
    range: Refusal<'static>,
) -> Result<Length, Refusal<'static>> {
    Length::from_mm_str(v).map_err(|e| match e {
        LengthError::OutOfRange => range,
        e => Refusal::Value(key, e.as_str()),
    })
}

/// A commanded point as the planner takes it.
pub(super) fn point_q32(p: [Length; 2]) -> Point {
    [q32(p[0]), q32(p[1])]
}

/// The protocol's outputs as the motion pipeline's step sink.
pub(super) struct Sink<'a, I: Io> {
    io: &'a mut I,
    drive: DriveTiming,
}

impl<'a, I: Io> Sink<'a, I> {
    pub(super) fn new(io: &'a mut I, drive: DriveTiming) -> Self {
        Sink { io, drive }
    }
}

impl<I: Io> StepSink for Sink<'_, I> {
    fn start(&mut self, item: Item) -> Result<(), Item> {
        match self.io.background() {
            Some(b) => {
                b.start(item, &self.drive);
                Ok(())
            }
            None => Err(item),
        }
    }

    fn background(&mut self) -> Option<&mut dyn Background> {
        self.io.background()
    }

    fn run_start(&mut self) {
        self.io.run_start();
    }

    fn block_start(&mut self, block: &LinearBlock) {
        self.io.block_start(block);
    }

    #[inline(always)]
    fn step(&mut self, event: StepEvent, tick: u64) {
        self.io.step(event, tick, &self.drive);
    }

    fn run_end(&mut self, ticks: u64) {
        self.io.run_end(ticks);
    }
}

fn parse_tol(v: &str) -> Result<Length, Refusal<'static>> {
    let why = "must be over 0, at most 1 mm";
    let tol = parse_bounded("TOL", v, 0, MAX_TOL_UM, why)?;
    if tol == Length::ZERO {
        return Err(Refusal::Value("TOL", why));
    }
    Ok(tol)
}

fn parse_pass(v: &str) -> Result<Pass, Refusal<'static>> {
    if v.eq_ignore_ascii_case("FIN") {
        Ok(Pass::Finish)
    } else if v.eq_ignore_ascii_case("ROUGH") {
        Ok(Pass::Rough)
    } else {
        Err(Refusal::Value("PASS", "must be FIN or ROUGH"))
    }
}

pub(super) fn parse_flag(key: &'static str, v: &str) -> Result<bool, Refusal<'static>> {
    match v {
        "0" => Ok(false),
        "1" => Ok(true),
        _ => Err(Refusal::Value(key, "must be 0 or 1")),
    }
}

/// At most this much of a word from the request is echoed in an error.
const ECHO: usize = 16;

/// The printable start of a request word, for error texts.
fn echo(word: &str) -> &str {
    word.get(..ECHO.min(word.len())).unwrap_or("")
}

fn send_refusal<I: Io>(io: &mut I, refusal: Refusal<'_>) {
    use ErrorCode as E;
    match refusal {
        Refusal::Checksum(expected) => {
            let h = hex_digits(expected);
            send_error(
                io,
                E::Checksum,
                format_args!(
                    "mismatch, line sums to {}{}",
                    char::from(h[0]),
                    char::from(h[1])
                ),
            )
        }
        Refusal::Crc => send_error(io, E::Checksum, format_args!("CRC word mismatch")),
        Refusal::NoSession => send_error(
            io,
            E::Session,
            format_args!("no session token set (device reset); set SESSION TOKEN"),
        ),
        Refusal::ChecksumForm => send_error(
            io,
            E::Checksum,
            format_args!("malformed, expected *HH at the end"),
        ),
        Refusal::Control => send_error(
            io,
            E::Syntax,
            format_args!("control or non-ASCII byte in request"),
        ),
        Refusal::Empty => send_error(io, E::Empty, format_args!("empty request")),
        Refusal::Unknown(word) => {
            send_error(io, E::Unknown, format_args!("command {}", echo(word)))
        }
        Refusal::Args(ArgError::NotKeyValue(word)) => send_error(
            io,
            E::Syntax,
            format_args!("expected KEY=VALUE, got {}", echo(word)),
        ),
        Refusal::Args(ArgError::UnknownKey(key)) => {
            send_error(io, E::Syntax, format_args!("unknown key {}", echo(key)))
        }
        Refusal::Args(ArgError::Duplicate(key)) => {
            send_error(io, E::Syntax, format_args!("key {key} given twice"))
        }
        Refusal::NoArgs(command) => {
            send_error(io, E::Syntax, format_args!("{command} takes no arguments"))
        }
        Refusal::Value(key, why) => send_error(io, E::Value, format_args!("{key} {why}")),
        Refusal::Range(what) => send_error(io, E::Range, format_args!("{what}")),
        Refusal::Geometry(what) => send_error(io, E::Geometry, format_args!("{what}")),
        Refusal::Missing(what) => send_error(io, E::Syntax, format_args!("{what}")),
        Refusal::Busy(what) => send_error(
            io,
            E::Geometry,
            format_args!("{what} not allowed while G41/G42 is on; cancel with G40 first"),
        ),
        Refusal::Contour(e) => send_contour_refusal(io, e),
        #[cfg(feature = "calc")]
        Refusal::Frame(e) => send_error(io, E::Value, format_args!("FRAME {e}")),
        Refusal::Block(e) => {
            let code = if e.is_value() { E::Value } else { E::Syntax };
            send_error(io, code, format_args!("{e}"))
        }
    }
}

/// A block named by its `N` number, or by its place.
struct BlockName(Option<u32>, &'static str);

impl fmt::Display for BlockName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(n) => write!(f, "N{n}"),
            None => f.write_str(self.1),
        }
    }
}

fn send_contour_refusal<I: Io>(io: &mut I, e: CompError) {
    use ErrorCode as E;
    let this = |n| BlockName(n, "this block");
    let last = |n| BlockName(n, "the previous block");
    match e {
        CompError::ConcaveRadius(n) => send_error(
            io,
            E::Geometry,
            format_args!(
                "{}: concave arc radius not larger than the nose radius",
                this(n)
            ),
        ),
        CompError::TooShort(a, b) => send_error(
            io,
            E::Geometry,
            format_args!(
                "{} too short for the nose radius: it reverses at its corner with {}",
                last(a),
                this(b)
            ),
        ),
        CompError::NoCorner(a, b) => send_error(
            io,
            E::Geometry,
            format_args!(
                "the nose does not fit the corner of {} and {}",
                last(a),
                this(b)
            ),
        ),
        CompError::OnInArc(n) => send_error(
            io,
            E::Geometry,
            format_args!("{}: compensation switched on in an arc block", this(n)),
        ),
        CompError::OffInArc(n) => send_error(
            io,
            E::Geometry,
            format_args!("{}: compensation switched off in an arc block", this(n)),
        ),
        CompError::SideChange(n) => send_error(
            io,
            E::Geometry,
            format_args!("{}: change between G41 and G42 through G40", this(n)),
        ),
        CompError::Range(n) => send_error(
            io,
            E::Range,
            format_args!("{}: compensated point beyond 99999.999999 mm", this(n)),
        ),
    }
}

/// A point in ångström as lengths, or `ERR RANGE`.
fn point(p: [i64; 2]) -> Result<[Length; 2], Refusal<'static>> {
    let beyond = Refusal::Range("compensated point beyond 99999.999999 mm");
    match (Length::from_angstrom(p[0]), Length::from_angstrom(p[1])) {
        (Some(x), Some(z)) => Ok([x, z]),
        _ => Err(beyond),
    }
}

/// Sends `OK`, followed by the given words if any.
pub(crate) fn send_ok<I: Io>(io: &mut I, words: Option<fmt::Arguments<'_>>) {
    let mut line = ReplyLine::new();
    let _ = line.write_str("OK");
    if let Some(words) = words {
        let _ = write!(line, " {words}");
    }
    io.send(line.finish());
}

/// Sends `DATA` followed by the given words.
pub(crate) fn send_data<I: Io>(io: &mut I, words: fmt::Arguments<'_>) {
    let mut line = ReplyLine::new();
    let _ = write!(line, "DATA {words}");
    io.send(line.finish());
}

/// Sends `ERR <CODE> <text>`.
pub(crate) fn send_error<I: Io>(io: &mut I, code: ErrorCode, text: fmt::Arguments<'_>) {
    let mut line = ReplyLine::new();
    let _ = write!(line, "ERR {} {}", code.as_str(), text);
    io.send(line.finish());
}

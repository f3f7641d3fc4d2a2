//! The session: configuration, commanded coordinates, position registers, and
//! the commands that act on them.
//!
//! Every command first computes its whole outcome from the current state and
//! only then commits it, so a refused request changes nothing.

use super::io::{Io, Realtime, StatusRecord, StatusView, CHORDS_PER_PAUSE};
use super::reply::{ReplyLine, REPLY_CAPACITY};
use super::request::*;
use super::words::Words;
use crate::arc::{centre_from_radius, ArcDir, ArcPoints, ChordPlan, DirectArc};
use crate::comp::{
    Contour, Element, Move, MoveKind, Moves, Origin, Shape, TipCode, Tool, MAX_MOVES,
};
use crate::cone::{cone, Angle, AngleError};
use crate::crc32::Crc32;
use crate::gcode::{
    is_block, parse, Compensation, Coolant, Dialect, FeedMode, Motion, PathControl, Plane, Special,
    Spindle, SpindleMode, Stop, ToolOffset, ToolWord, Units,
};
use crate::impulse::{quantize, Impulses};
use crate::interleave::{ImpulsePoint, LinearBlock};
use crate::interp::{path_feed, Aux, MAction, Modal, Offsets, Selection, TOOL_REGISTERS};
use crate::length::{div_round_half_away, write_mm4, Length};
use crate::machine::{Join, Machine};
use crate::outputs::{milli_rpm, Outputs};
use crate::plan::{Feed, Limits, LimitsError, WINDOW};
use crate::stepdir::{DriveTiming, TimingError};
use crate::stepper::{Aborted, AxesState as Axes};
use core::fmt::{self, Write};

mod auxiliary;
mod backlash;
mod blocks;
mod configure;
mod cycle_moves;
mod cycle_state;
mod cycles;
mod gcode;
mod homing;
mod inputs;
mod moves;
mod offsets;
mod probe;
mod realtime;
mod settings;
mod wheel;
pub(super) mod wire;

pub(super) use blocks::block_crc;
pub use settings::{Config, Pass};
pub use wire::status_line;
pub(super) use wire::{parse_flag, parse_length, send_data, send_error, send_ok, Outcome, Refusal};

use blocks::*;
use cycle_state::*;
use settings::*;
use wire::*;

/// The device name reported by `VER`.
pub const NAME: &str = "lathe-retrofit";
/// The firmware version reported by `VER`.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

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
    /// Changes of the table, the work offsets and the stored positions.
    pub(super) generation: u32,
    /// Check mode (grbl's `$C`): the registers and the motors' take-up
    /// where it began, put back when it ends.
    pub(super) checking: Option<(ImpulsePoint, [i32; 2])>,
    /// The last reset dropped motion answered and not all run.
    pub(super) reset_dropped: bool,
    /// What runs is the handwheel's alone (its counts add to it); any
    /// request or block ends it.
    pub(super) wheeling: bool,
    /// The wheel's counts were refused and it said so (once until it moves
    /// the axis again).
    pub(super) wheel_ignored: bool,
    /// The top speed of each gear range (`GEAR N= TOP=`), rpm.
    pub(super) gears: [Option<Length>; 4],
    /// The nose `G41.1`/`G42.1` gave, while its compensation is on.
    pub(super) dynamic_tool: Option<Tool>,
    /// The turning cycles: a profile held, their modal depth and retract.
    pub(super) cycles: Cycles,
    /// The id of the last request that carried one, and its final reply.
    pub(super) last_id: Option<u32>,
    pub(super) last_final: heapless::Vec<u8, REPLY_CAPACITY>,
    /// The planner, the run in progress, what has been issued.
    pub(super) machine: Machine,
    /// The feed of the last element given to the contour engine (the one
    /// it holds while compensation is on); `None` for a rapid.
    pub(super) element_feed: Option<Feed>,
    /// The feed of the move waiting for its `,C`/`,R` corner.
    pub(super) round_feed: Option<Feed>,
    /// The spindle's top speed, rpm (`AUX SMAX`): the speed at full PWM
    /// duty and a limit of every commanded speed; none when the speed is
    /// set on the machine by hand.
    pub(super) top: Option<Length>,
    /// The wait after the spindle starts or changes speed at rest, µs
    /// (`AUX SPINUP`).
    pub(super) spinup_us: u64,
    /// The spindle and coolant outputs as last switched at rest.
    pub(super) outputs: Outputs,
    /// The active inputs, filtered, as the board last gave them.
    pub(super) levels: u16,
    /// What an input stopped, until it is cleared (`UNLOCK`).
    pub(super) halt: crate::inputs::Halt,
    /// The axes were stopped at once in motion: a drive may have lost
    /// steps, so the registers may no longer be where the carriage is.
    pub(super) lost: bool,
    /// Each axis has been homed since power-on (and its machine position
    /// not set by hand since): its soft limits apply.
    pub(super) homed: [bool; 2],
    /// Where the last probing move ended (grbl's `PRB:`).
    pub(super) probe: Option<crate::inputs::ProbeResult>,
    /// A probing block runs as a feed move to its end (where nothing
    /// reads a probe and the program's path is wanted: `host-sim run`,
    /// `check`, `plot`).
    pub(super) probe_as_feed: bool,
    /// The BCK-5 tape read so far by `TAPE` requests.
    #[cfg(feature = "calc")]
    pub(super) tape: crate::calc::tape::Bck5Verifier,
}

impl Default for Session {
    fn default() -> Self {
        Self::new()
    }
}

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
            offsets: Offsets::ZERO,
            sel: Selection::POWER_ON,
            prog: [Length::ZERO; 2],
            contour: Contour::new(),
            feed_override: 100,
            spindle_override: 100,
            last_moves: Moves::new(),
            token: 0,
            generation: 0,
            checking: None,
            reset_dropped: false,
            wheeling: false,
            wheel_ignored: false,
            gears: [None; 4],
            dynamic_tool: None,
            cycles: Cycles::new(),
            last_id: None,
            last_final: heapless::Vec::new(),
            machine: Machine::with_window(window),
            levels: 0,
            halt: crate::inputs::Halt::None,
            lost: false,
            homed: [false; 2],
            probe: None,
            probe_as_feed: false,
            element_feed: None,
            round_feed: None,
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

    /// Whether G-code lines streaming in are a turning cycle's profile
    /// (held, or refused with it): a refused one drops the cycle whole
    /// (`docs/cycles.md` §2).
    pub fn reading_profile(&self) -> bool {
        self.cycles.holding()
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

    /// The spindle's top speed, rpm (`AUX SMAX`); none when the speed is
    /// set on the machine by hand.
    pub const fn spindle_top(&self) -> Option<Length> {
        self.top
    }

    /// The dialect G-code lines are read in.
    pub const fn dialect(&self) -> Dialect {
        self.offsets.reading.dialect
    }

    /// Whether blocks starting with `/` are skipped (`OPT BDEL`).
    pub const fn block_delete(&self) -> bool {
        self.offsets.reading.block_delete
    }

    /// Whether `M01` stops (`OPT OPTSTOP`).
    pub const fn optional_stop(&self) -> bool {
        self.offsets.reading.optional_stop
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
                if self.last_final.starts_with(b"OK") {
                    out.inner.accepted();
                }
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
        let request = Request::parse(text)?;
        self.execute(&request, io)
    }

    /// Runs a request already parsed: a line's, or a front's own (grbl's
    /// `$n=` and `$J=`). Its refusal is answered here.
    pub fn request<I: Io>(&mut self, request: &Request<'_>, io: &mut I) {
        self.share_view(io);
        // Through the same wrapper as a line's (no id, no CRC word): one
        // copy of the session's code in the image, whichever way it runs.
        let mut out = Suffixed {
            inner: io,
            id: None,
            crc: false,
            last: heapless::Vec::new(),
        };
        if let Err(refusal) = self.execute(request, &mut out) {
            send_refusal(&mut out, refusal);
        }
    }

    /// Runs a request: one handler per command of the table.
    fn execute<'a, I: Io>(&mut self, request: &Request<'a>, io: &mut I) -> Outcome<'a> {
        let (command, args) = match request {
            Request::Block(text) => {
                self.wheeling = false;
                return self.gcode(text, io);
            }
            Request::Command(command, args) => (*command, args),
        };
        if !matches!(command, Command::Status | Command::Pos) {
            // The wheel's moves end with what the request queues.
            self.wheeling = false;
        }
        if matches!(command, Command::Move | Command::Arc | Command::Sync) {
            // Nothing moves while an input holds the machine locked.
            self.unlocked()?;
        }
        match command {
            Command::Ver => {
                send_ok(
                    io,
                    Some(format_args!("PROTO=1 NAME={NAME} VERSION={VERSION}")),
                );
                Ok(())
            }
            Command::Cfg => self.cfg_command(args, io),
            Command::Zero => self.zero_command(args, io),
            Command::Session => self.session_command(args, io),
            Command::Move => self.move_command(args, io),
            Command::Cone => self.cone_command(args, io),
            Command::Arc => self.arc_command(args, io),
            Command::Drive => self.drive_command(args, io),
            Command::Mcode => self.mcode_command(args, io),
            Command::Gear => self.gear_command(args, io),
            Command::Opt => self.opt_command(args, io),
            Command::Limits => self.limits_command(args, io),
            Command::Sync => {
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
            }
            Command::Status => {
                self.status_reply(io, "OK");
                Ok(())
            }
            Command::Reset => self.reset_command(io),
            Command::Unlock => self.unlock_command(io),
            Command::Homing => self.homing_command(args, io),
            Command::Wheel => self.wheel_command(args, io),
            Command::Backlash => self.backlash_command(args, io),
            Command::Home => self.home_command(args, io),
            Command::Input => self.input_command(args, io),
            Command::Pos => {
                self.pos_reply(io);
                Ok(())
            }
            Command::Tool => self.tool_command(args, io),
            Command::Work => self.work_command(args, io),
            Command::Aux => self.aux_command(args, io),
            Command::Thread | Command::Wear | Command::Deflect | Command::Tri | Command::Tape => {
                self.calc(command, args, io)
            }
        }
    }

    /// The calculators' requests (`THREAD`, `WEAR`, `DEFLECT`, `TRI`,
    /// `TAPE`).
    #[cfg(feature = "calc")]
    fn calc<'a, I: Io>(&mut self, command: Command, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        use super::calc;
        match command {
            Command::Thread => calc::thread_command(args, self.machine.limits(), io),
            Command::Wear => calc::wear_command(args, io),
            Command::Deflect => calc::deflect_command(args, io),
            Command::Tri => calc::tri_command(args, io),
            _ => calc::tape_command(args, &mut self.tape, io),
        }
    }

    /// Without the calculators no request is one of theirs (the parse
    /// refuses their names).
    #[cfg(not(feature = "calc"))]
    fn calc<'a, I: Io>(&mut self, command: Command, _: &Args<'a>, _: &mut I) -> Outcome<'a> {
        Err(Refusal::Unknown(command.spec().name()))
    }

    /// `SESSION [TOKEN=n]`: sets or reports the host's session token.
    fn session_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [token] = args.values();
        if let Some(v) = token {
            self.token = match v.parse::<u32>() {
                Ok(t) if v.bytes().all(|b| b.is_ascii_digit()) => t,
                _ => return Err(Refusal::Value("TOKEN", "must be 0 to 4294967295")),
            };
        }
        send_ok(io, Some(format_args!("TOKEN={}", self.token)));
        Ok(())
    }

    /// `OPT [BDEL=0|1] [DIALECT=ISO|FANUC] [OPTSTOP=0|1]`.
    fn opt_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [bdel, dialect, optstop] = args.values();
        let was = self.offsets.reading;
        let block_delete = match bdel {
            Some(v) => parse_flag("BDEL", v)?,
            None => was.block_delete,
        };
        let optional_stop = match optstop {
            Some(v) => parse_flag("OPTSTOP", v)?,
            None => was.optional_stop,
        };
        let dialect = match dialect {
            None => was.dialect,
            Some(v) if v.eq_ignore_ascii_case("ISO") => Dialect::Iso,
            Some(v) if v.eq_ignore_ascii_case("FANUC") => Dialect::Fanuc,
            Some(_) => return Err(Refusal::Value("DIALECT", "must be ISO or FANUC")),
        };
        let mut offsets = self.offsets;
        offsets.reading = crate::interp::Reading {
            dialect,
            block_delete,
            optional_stop,
        };
        // Kept across power cycles with the table.
        self.take_offsets(offsets);
        let now = self.offsets.reading;
        send_ok(
            io,
            Some(format_args!(
                "BDEL={} DIALECT={} OPTSTOP={}",
                u8::from(now.block_delete),
                now.dialect.as_str(),
                u8::from(now.optional_stop)
            )),
        );
        Ok(())
    }

    /// `RESET`: as the RESET key of a control, the program is abandoned
    /// where it stands (a cycle's profile being read with it). What is
    /// queued runs to its end; a waiting element is dropped.
    fn reset_command<'a, I: Io>(&mut self, io: &mut I) -> Outcome<'a> {
        self.reset_halt();
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
    }
}

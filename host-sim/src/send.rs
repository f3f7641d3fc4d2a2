//! `host-sim send`: a part program streamed to a board (or `serve --pty`,
//! or the firmware in QEMU) as a machinist runs it.
//!
//! Before anything moves, the program runs on a model: the in-process
//! device, given the board's own configuration, limits, tool table and work
//! offsets and put where the board stands. The model is the same core the
//! board runs, so it predicts every reply the board will give, every step
//! event each line issues and where each line starts; `--dry-run` stops
//! there. Then each line goes out as a reliable request (id and CRC word),
//! one behind the other so the board's queue stays filled; every reply is
//! checked against the model's, and a difference stops the program.
//!
//! Keys act at once as real-time bytes: hold, cycle start, abort (a hold to
//! rest, then a reset, so no step is lost), and reset. After a reset the
//! sender restarts the program the way a control's program restart does:
//! it finds from the board's event count the first line whose motion did
//! not finish (before a nose-compensated stretch, the line that began it),
//! restores the modal state the program had there (units, distance and
//! feed modes, feed, work system, tool and offset, spindle, coolant),
//! takes the tool back along the path it cut to that line's start, and
//! streams on from there. A reply lost on the line is asked for again
//! under the same id; a board that restarts without a reset report (power
//! lost) has lost its position: the sender stops and says so.

use crate::link::{words_value, LinkError, Reply};
use crate::program::Refused;
use crate::reliable::{frame, unframe, ByteLink};
use core_nostd::gcode::{is_block, parse, Coolant, Dialect, FeedMode, Spindle, SpindleMode, Units};
use core_nostd::protocol::Session;
use std::time::{Duration, Instant};

use crate::device::LocalDevice;

/// One program line as the model ran it.
#[derive(Clone, Debug)]
pub struct Line {
    /// Line of the file, from 1.
    pub source: usize,
    /// The request sent (the program's text, host-side expansion done).
    pub text: String,
    /// The final reply line the board must give (without its `*HH`).
    pub expect: String,
    /// Step events issued before this line's motion, since the start.
    pub before: u64,
    /// Step events issued once this line's motion has run.
    pub after: u64,
    /// Whether nose compensation was on or armed before this line.
    pub comp_before: bool,
    /// The requests that give a board at power-on modal state the state
    /// the program had before this line.
    pub restore: Vec<String>,
    /// The motion word (`G01`…) this line moves by when it names none.
    pub motion_word: Option<&'static str>,
    /// Planned time from the start to the end of this line's motion, µs.
    pub time_after_us: u64,
}

/// The program as the model ran it: what to send and what to expect.
#[derive(Clone, Debug, Default)]
pub struct Plan {
    /// Requests that set up the run (dialect, diameters, optional stop,
    /// the setup file), after the board's own settings.
    pub setup: Vec<String>,
    /// The program's lines.
    pub lines: Vec<Line>,
    /// Registers `(PX, PZ)` after `k` events since the start.
    pub positions: Vec<(i64, i64)>,
    /// The event index of each block's start.
    pub block_starts: Vec<u64>,
    /// The run's planned motion time, µs.
    pub total_us: u64,
    /// Lines the model refused: the board would refuse them too.
    pub refused: Vec<Refused>,
    /// Setup requests refused (line of the setup file; 0 for the run's own).
    pub setup_refused: Vec<Refused>,
    /// X impulse price and Z impulse price, ångström; diameters.
    prices: (i64, i64, bool),
    /// The program is in Fanuc's dialect.
    fanuc: bool,
}

/// What the board reports of itself, as requests that give the model the
/// same settings (`CFG …`, `DRIVE …`, `LIMITS …`, `AUX …`, `TOOL …`,
/// `WORK …`) and where it stands (`ZERO X= Z=`).
pub fn board_settings<L: ByteLink>(s: &mut Sender<L>) -> Result<Vec<String>, Halt> {
    let mut out = Vec::new();
    let ask = |s: &mut Sender<L>, q: &str| -> Result<Reply, Halt> {
        let r = s.request(q)?;
        if r.is_ok() {
            Ok(r)
        } else {
            Err(Halt::Board(format!("{q}: {}", r.last)))
        }
    };
    let keys = |r: &Reply, keys: &[&str]| -> String {
        keys.iter()
            .filter_map(|k| r.value(k).filter(|v| *v != "-").map(|v| format!("{k}={v}")))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let cfg = ask(s, "CFG")?;
    out.push(format!(
        "CFG {}",
        keys(&cfg, &["HX", "HZ", "DIAM", "RN", "TIP", "TOL", "PASS"])
    ));
    let drive = ask(s, "DRIVE")?;
    out.push(format!(
        "DRIVE {}",
        keys(&drive, &["RATE", "PULSE", "SETUP"])
    ));
    let limits = ask(s, "LIMITS")?;
    out.push(format!(
        "LIMITS {}",
        keys(&limits, &["VX", "VZ", "AX", "AZ", "JD"])
    ));
    let aux = ask(s, "AUX")?;
    out.push(format!("AUX {}", keys(&aux, &["SMAX", "SPINUP"])));
    for n in 1..=core_nostd::interp::TOOL_REGISTERS {
        let t = ask(s, &format!("TOOL N={n}"))?;
        out.push(format!(
            "TOOL {}",
            keys(&t, &["N", "X", "Z", "WX", "WZ", "R", "T"])
        ));
    }
    for g in 54..=59 {
        let w = ask(s, &format!("WORK G={g}"))?;
        out.push(format!("WORK {}", keys(&w, &["G", "X", "Z"])));
    }
    let pos = ask(s, "POS")?;
    let (x, z) = (pos.value("X").unwrap_or("0"), pos.value("Z").unwrap_or("0"));
    out.push(format!("ZERO X={x} Z={z}"));
    Ok(out)
}

/// A length in ångström as an exact decimal of mm (no trailing zeros).
fn exact_mm(a: i64) -> String {
    let mut s = String::new();
    let _ = core_nostd::length::write_exact_mm(&mut s, a);
    s
}

/// The requests that give a board after a reset (power-on modal state, no
/// offset register, spindle and coolant off) the state `s` holds.
pub fn restore_requests(s: &Session) -> Vec<String> {
    let m = s.modal();
    let aux = s.aux();
    let sel = s.selection();
    let iso = s.dialect() == Dialect::Iso;
    let mut out = Vec::new();
    let mut modes = vec![
        match m.units {
            Units::Mm => "G21",
            Units::Inch => "G20",
        }
        .to_string(),
        format!("G{}", 54 + sel.wcs),
    ];
    if iso {
        modes.push(if m.incremental { "G91" } else { "G90" }.into());
        modes.push(if m.arc_absolute { "G90.1" } else { "G91.1" }.into());
    }
    modes.push(
        match (m.feed_mode, iso) {
            (FeedMode::PerMinute, true) => "G94",
            (FeedMode::PerRev, true) => "G95",
            (FeedMode::PerMinute, false) => "G98",
            (FeedMode::PerRev, false) => "G99",
        }
        .into(),
    );
    if s.contour().corner() == core_nostd::gcode::Corner::Arc {
        modes.push("G450".into());
    }
    if let Some(f) = m.feed {
        modes.push(format!("F{}", exact_mm(f.as_angstrom())));
    }
    out.push(modes.join(" "));
    // The tool in the working station and its offset register.
    if iso {
        if sel.loaded > 0 {
            out.push(format!("T{} M06", sel.loaded));
        }
        if let Some(t) = aux.tool.filter(|t| t.tool != sel.loaded) {
            out.push(format!("T{}", t.tool));
        }
        if sel.register > 0 {
            out.push(format!("G43 H{}", sel.register));
        }
    } else if sel.loaded > 0 || sel.register > 0 {
        out.push(format!("T{:02}{:02}", sel.loaded, sel.register));
    }
    // The spindle: its limit, mode, speed and direction.
    let sp = &aux.spindle;
    if let (Some(c), false) = (sp.clamp, iso) {
        out.push(format!("G50 S{}", exact_mm(c.as_angstrom())));
    }
    if let Some(sv) = sp.s {
        let mut w = vec![
            match sp.mode {
                SpindleMode::Rpm => "G97".to_string(),
                SpindleMode::Surface => "G96".to_string(),
            },
            format!("S{}", exact_mm(sv.as_angstrom())),
        ];
        if let (Some(c), true, SpindleMode::Surface) = (sp.clamp, iso, sp.mode) {
            w.push(format!("D{}", exact_mm(c.as_angstrom())));
        }
        match sp.turning {
            Spindle::Cw => w.push("M03".into()),
            Spindle::Ccw => w.push("M04".into()),
            Spindle::Off => {}
        }
        out.push(w.join(" "));
    }
    match aux.coolant {
        Coolant::Mist => out.push("M07".into()),
        Coolant::Flood => out.push("M08".into()),
        Coolant::Off => {}
    }
    out
}

/// `line` with `word` put after its block-delete slash and `N` word.
fn with_motion_word(line: &str, word: &str) -> String {
    let t = line.trim_start();
    let (slash, rest) = match t.strip_prefix('/') {
        Some(r) => ("/", r.trim_start()),
        None => ("", t),
    };
    let n_end = if rest.starts_with(['N', 'n']) {
        1 + rest[1..]
            .find(|c: char| !c.is_ascii_digit() && c != '.')
            .unwrap_or(rest.len() - 1)
    } else {
        0
    };
    let (n, tail) = rest.split_at(n_end);
    let sep = if n.is_empty() { "" } else { " " };
    format!("{slash}{n}{sep}{word} {}", tail.trim_start())
}

fn final_line(lines: &[String]) -> String {
    let last = lines.last().map(String::as_str).unwrap_or("");
    last.rsplit_once('*').map_or(last, |(b, _)| b).to_owned()
}

/// Registers after every event of `events`, from `at`.
fn walk(at: &mut (i64, i64), events: &[crate::device::Issued], out: &mut Vec<(i64, i64)>) {
    for e in events {
        let d = |step: u8, neg: u8| -> i64 {
            match (e.bits & step != 0, e.bits & neg != 0) {
                (false, _) => 0,
                (true, false) => 1,
                (true, true) => -1,
            }
        };
        at.0 += d(1, 4);
        at.1 += d(2, 8);
        out.push(*at);
    }
}

impl Plan {
    /// Runs `text` on the model: the board's `settings` (from
    /// [`board_settings`]), the run's own settings, the `setup` requests
    /// (each with its line in the setup file), then the program, line by
    /// line.
    pub fn build(
        text: &str,
        options: crate::program::Options,
        settings: &[String],
        setup: &[(usize, &str)],
    ) -> Result<Plan, String> {
        let mut plan = Plan {
            fanuc: options.dialect == Dialect::Fanuc,
            ..Plan::default()
        };
        let mut dev = LocalDevice::recording();
        for s in settings {
            let r = final_line(&dev.request(s));
            if !r.starts_with("OK") {
                return Err(format!("the board's settings cannot be mirrored: {s}: {r}"));
            }
        }
        let own: Vec<String> = std::iter::once("RESET".to_string())
            .chain(crate::program::run_settings(options))
            .collect();
        for (line, req) in own
            .iter()
            .map(|s| (0, s.as_str()))
            .chain(setup.iter().copied())
        {
            let r = final_line(&dev.request(req));
            if r.starts_with("OK") {
                plan.setup.push(req.to_owned());
            } else {
                plan.setup_refused.push(Refused { line, reply: r });
            }
        }
        let start = dev.device().session().position();
        let mut at = (i64::from(start.x.get()), i64::from(start.z.get()));
        plan.positions.push(at);
        let cfg = dev.device().session().config();
        plan.prices = (
            cfg.hx.as_length().as_angstrom(),
            cfg.hz.as_length().as_angstrom(),
            cfg.diam,
        );
        let _ = dev.request("SYNC");
        dev.take_events();

        let lines: Vec<(usize, String)> = crate::program::program_lines(text, options.dialect)
            .map_err(|e| format!("{e}"))?
            .into_iter()
            .map(|(i, l)| (i + 1, l))
            .collect();
        let mut events = 0u64;
        for (source, raw) in lines {
            if raw.trim().is_empty() {
                continue;
            }
            if !is_block(&raw) {
                plan.refused.push(Refused {
                    line: source,
                    reply: "ERR SYNTAX not a G-code line".into(),
                });
                continue;
            }
            let session = dev.device().session();
            let comp_before = session.contour().active();
            let restore = restore_requests(session);
            let modal_motion = session.modal().motion;
            let units = session.modal().units;
            let dialect = session.dialect();
            let expect = final_line(&dev.request(&raw));
            if !expect.starts_with("OK") {
                plan.refused.push(Refused {
                    line: source,
                    reply: expect,
                });
                continue;
            }
            let _ = dev.request("SYNC");
            let starts: Vec<u64> = dev
                .block_starts()
                .iter()
                .map(|(i, _)| events + *i as u64)
                .collect();
            let issued = dev.take_events();
            walk(&mut at, &issued, &mut plan.positions);
            plan.block_starts.extend(starts);
            let before = events;
            events += issued.len() as u64;
            let motion_word = match parse(&raw, dialect, units) {
                Ok(b) if b.motion.is_none() && (b.x.is_some() || b.z.is_some()) => {
                    Some(modal_motion.word())
                }
                _ => None,
            };
            plan.lines.push(Line {
                source,
                text: raw,
                expect,
                before,
                after: events,
                comp_before,
                restore,
                motion_word,
                time_after_us: 0,
            });
        }
        plan.time(settings);
        Ok(plan)
    }

    /// The planned time at the end of each line's motion: the program run
    /// again as the board runs it, without a stop between lines.
    fn time(&mut self, settings: &[String]) {
        let mut dev = LocalDevice::recording();
        for s in settings.iter().chain(&self.setup) {
            let _ = dev.request(s);
        }
        let _ = dev.request("SYNC");
        dev.take_events();
        let mut n = 0u64;
        let (mut base, mut run, mut last) = (0u64, u64::MAX, 0u64);
        let mut next = 0usize;
        let ends: Vec<u64> = self.lines.iter().map(|l| l.after).collect();
        let mut times = vec![0u64; ends.len()];
        let lines: Vec<String> = self.lines.iter().map(|l| l.text.clone()).collect();
        let mut feed = |dev: &mut LocalDevice, req: &str| {
            let _ = dev.request(req);
            for e in dev.take_events() {
                if e.run != run {
                    base += last;
                    run = e.run;
                }
                last = e.tick;
                n += 1;
                while next < ends.len() && ends[next] <= n {
                    times[next] = base + last;
                    next += 1;
                }
            }
        };
        for l in &lines {
            feed(&mut dev, l);
        }
        feed(&mut dev, "SYNC");
        let total = base + last;
        for t in times.iter_mut().skip(next) {
            *t = total;
        }
        for (l, t) in self.lines.iter_mut().zip(times) {
            l.time_after_us = t;
        }
        self.total_us = total;
    }

    /// Step events of the whole program.
    pub fn events(&self) -> u64 {
        self.lines.last().map_or(0, |l| l.after)
    }

    /// The registers at the end.
    pub fn end(&self) -> (i64, i64) {
        *self.positions.last().unwrap_or(&(0, 0))
    }

    /// The points to go back through, from event `from` to event `to`
    /// (`to` ≤ `from`): the start of every block between, latest first,
    /// then the registers at `to`.
    pub fn retrace(&self, from: u64, to: u64) -> Vec<(i64, i64)> {
        let mut pts: Vec<(i64, i64)> = self
            .block_starts
            .iter()
            .rev()
            .filter(|&&s| s > to && s < from)
            .map(|&s| self.positions[s as usize])
            .collect();
        pts.push(self.positions[to as usize]);
        let mut at = self.positions[from as usize];
        pts.retain(|&p| {
            let keep = p != at;
            at = p;
            keep
        });
        // One move at least, if only on the spot: a move makes the
        // restored offsets the programmed point's, as the program had it.
        if pts.is_empty() {
            pts.push(at);
        }
        pts
    }

    /// A feed move to registers `p` at `feed` mm/min in machine
    /// coordinates (`G53`: whatever offsets are in effect).
    fn move_to(&self, p: (i64, i64), feed: &str) -> String {
        let (hx, hz, diam) = self.prices;
        let x = p.0 * hx * if diam { 2 } else { 1 };
        // Per minute: G94 in ISO, G98 in Fanuc's system A (whose G94 is a
        // facing cycle).
        let per_minute = if self.fanuc { "G98" } else { "G94" };
        format!(
            "G53 {per_minute} G01 X{} Z{} F{feed}",
            exact_mm(x),
            exact_mm(p.1 * hz)
        )
    }

    /// The line whose motion includes event `e` (the line running).
    fn line_at(&self, e: u64) -> usize {
        self.lines
            .partition_point(|l| l.after <= e)
            .min(self.lines.len().saturating_sub(1))
    }
}

/// A key of the person at the machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// Feed hold (0x82).
    Hold,
    /// Cycle start after a hold (0x81).
    Resume,
    /// Stop the program: a hold to rest, then a reset.
    Abort,
    /// Reset at once (Ctrl-X): the sender restarts the program.
    Reset,
}

/// Where the run stands, for the person and for a script.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    /// Program lines answered.
    pub acked: usize,
    /// Program lines.
    pub lines: usize,
    /// The line of the file running (by the board's position), from 1.
    pub running: usize,
    /// Registers, as the last status reported them.
    pub registers: (i64, i64),
    /// X (a diameter when `DIAM=1`) and Z, mm, as reported.
    pub x: String,
    /// See `x`.
    pub z: String,
    /// `IDLE`, `RUN` or `HOLD`.
    pub state: String,
    /// The speed, mm/min.
    pub speed: String,
    /// Planned motion time left, µs.
    pub remaining_us: u64,
    /// Resets the sender has recovered from.
    pub resets: u32,
    /// The program stop waiting for cycle start (`M00`, `M01`), if any.
    pub stop: Option<String>,
}

/// The person at the machine: keys, and what they are shown.
pub trait Operator {
    /// A key pressed since the last call, if any.
    fn key(&mut self, progress: &Progress) -> Option<Key>;
    /// The run has moved on.
    fn show(&mut self, progress: &Progress);
    /// Something the person should read (a restart, a stop).
    fn say(&mut self, text: &str);
}

/// Why streaming stopped before the end.
#[derive(Debug)]
pub enum Halt {
    /// The link failed or the board stopped answering.
    Link(LinkError),
    /// The board refused a request the sender needed.
    Board(String),
    /// The board refused a program line: its line and reply.
    Refused(usize, String),
    /// The board's reply differs from the model's.
    Mismatch(usize, String, String),
    /// The person aborted; the axes stopped at these registers.
    Aborted((i64, i64)),
    /// The board restarted without a reset report.
    PowerLost,
    /// A switch stopped the board (`!ALARM`): the E-stop, a limit, a
    /// drive's fault; it is locked until cleared.
    Stopped(Stopped),
}

/// What an `!ALARM` line told.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stopped {
    /// grbl's alarm number: 10 the E-stop, 1 a limit, 17 a drive's fault.
    pub code: u8,
    /// The inputs that tripped (`INPUT` names).
    pub input: String,
    /// Where the axes stopped: the registers.
    pub at: (i64, i64),
}

impl From<LinkError> for Halt {
    fn from(e: LinkError) -> Self {
        Halt::Link(e)
    }
}

impl std::fmt::Display for Halt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Halt::Link(e) => write!(f, "the link failed: {e}"),
            Halt::Board(s) => write!(f, "the board refused {s}"),
            Halt::Refused(l, r) => write!(f, "line {l}: the board refused it: {r}"),
            Halt::Mismatch(l, d, h) => write!(
                f,
                "line {l}: the board's reply differs from the program's model, streaming stopped: board `{d}`, model `{h}`"
            ),
            Halt::Aborted((px, pz)) => {
                write!(f, "aborted: the axes stopped at rest on PX={px} PZ={pz}")
            }
            Halt::PowerLost => write!(
                f,
                "the board restarted without a reset report (power lost?): where the axes stand is unknown; set the machine's position and run the program again"
            ),
            Halt::Stopped(s) => {
                let (what, clear) = match s.code {
                    10 => ("the E-stop", "release it, reset, then UNLOCK"),
                    1 => ("a limit switch", "UNLOCK and move off the switch"),
                    _ => ("a drive's fault", "UNLOCK once the drive is well"),
                };
                write!(
                    f,
                    "{what} stopped the board (alarm {}, input {}) with the axes at PX={} PZ={}: {clear}, check where the axes stand, and run the program again",
                    s.code, s.input, s.at.0, s.at.1
                )
            }
        }
    }
}

/// How streaming ended.
#[derive(Debug)]
pub struct SendReport {
    /// `None` when every line ran.
    pub halt: Option<Halt>,
    /// Program lines answered (those sent again after a restart too).
    pub requests: u64,
    /// Wall time streaming, s.
    pub seconds: f64,
    /// Blocks the board started short because the queue ran dry (the
    /// final `SYNC`'s `STARVED`, since the last restart).
    pub starved: Option<u64>,
    /// Registers at the end, board and model.
    pub registers: Option<(i64, i64)>,
    /// See `registers`.
    pub expected: (i64, i64),
    /// Resets recovered.
    pub resets: u32,
    /// Requests sent again.
    pub retries: u64,
    /// Reply lines dropped: damaged, or for an earlier request.
    pub dropped: u64,
}

/// Streams programs to one board.
pub struct Sender<L> {
    link: L,
    next_id: u32,
    token: u32,
    timeout: Duration,
    /// How often a status byte goes out while waiting.
    pub status_every: Duration,
    /// The feed the tool goes back along the path at after a reset, mm/min.
    pub return_feed: String,
    last_poll: Instant,
    busy_at: Option<Instant>,
    reset_seen: Option<(i64, i64)>,
    alarm_seen: Option<Stopped>,
    progress: Progress,
    retries: u64,
    dropped: u64,
    aborting: bool,
    /// Events of the program issued before the board's `SYNC` record began.
    base: u64,
    hint: u64,
}

/// Attempts of one request before the link is given up.
const ATTEMPTS: u32 = 50;

impl<L: ByteLink> Sender<L> {
    /// A sender on `link`: sets a session token on the board.
    pub fn new(link: L, timeout: Duration, token: u32) -> Result<Self, Halt> {
        let mut s = Sender {
            link,
            next_id: 1,
            token,
            timeout,
            status_every: Duration::from_millis(200),
            return_feed: "250".into(),
            last_poll: Instant::now(),
            busy_at: None,
            reset_seen: None,
            alarm_seen: None,
            progress: Progress::default(),
            retries: 0,
            dropped: 0,
            aborting: false,
            base: 0,
            hint: 0,
        };
        s.session()?;
        Ok(s)
    }

    /// The link.
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    fn session(&mut self) -> Result<(), Halt> {
        let r = self.request(&format!("SESSION TOKEN={}", self.token))?;
        if r.is_ok() {
            Ok(())
        } else {
            Err(Halt::Board(format!("SESSION: {}", r.last)))
        }
    }

    /// One request, answered intact (sent again under the same id while
    /// no answer comes and the board is not busy).
    pub fn request(&mut self, request: &str) -> Result<Reply, Halt> {
        self.exchange(request, &mut NoOperator, None)
    }

    fn exchange(
        &mut self,
        request: &str,
        op: &mut dyn Operator,
        plan: Option<&Plan>,
    ) -> Result<Reply, Halt> {
        let id = self.next_id;
        self.next_id = self.next_id.checked_add(1).unwrap_or(1);
        let line = frame(id, request);
        self.link.send(&line)?;
        let mut sent = Instant::now();
        let mut attempts = 1;
        let mut data = Vec::new();
        loop {
            self.tick(op, plan)?;
            match self.link.recv_line(Duration::from_millis(20))? {
                Some(l) if l.first() == Some(&b'!') => self.on_realtime(&l, plan, op),
                Some(l) => match unframe(&l) {
                    None => self.dropped += 1,
                    Some((got, _)) if got != id => self.dropped += 1,
                    Some((_, text)) if text.starts_with("DATA") => data.push(text),
                    Some((_, text)) => return Ok(Reply { data, last: text }),
                },
                None => {
                    let busy = self
                        .busy_at
                        .is_some_and(|t| t.elapsed() < self.timeout + self.status_every);
                    if sent.elapsed() > self.timeout && !busy {
                        if attempts >= ATTEMPTS {
                            return Err(Halt::Link(LinkError::Timeout));
                        }
                        attempts += 1;
                        self.retries += 1;
                        self.link.send(&line)?;
                        sent = Instant::now();
                    }
                }
            }
        }
    }

    /// Keys and status polls, between reply lines.
    fn tick(&mut self, op: &mut dyn Operator, plan: Option<&Plan>) -> Result<(), Halt> {
        if self.last_poll.elapsed() >= self.status_every {
            self.last_poll = Instant::now();
            self.link.send(&[0x80])?;
        }
        if plan.is_none() {
            return Ok(());
        }
        match op.key(&self.progress) {
            Some(Key::Hold) => self.link.send(&[0x82])?,
            Some(Key::Resume) => self.link.send(&[0x81])?,
            Some(Key::Reset) => self.link.send(&[0x18])?,
            Some(Key::Abort) if !self.aborting => {
                self.aborting = true;
                op.say("abort: feed hold, then a reset at rest");
                self.link.send(&[0x82])?;
            }
            _ => {}
        }
        if let Some(p) = self.reset_seen.filter(|_| self.aborting) {
            return Err(Halt::Aborted(p));
        }
        Ok(())
    }

    /// A `!STATUS`, `!RESET` or `!ALARM` line.
    fn on_realtime(&mut self, line: &[u8], plan: Option<&Plan>, op: &mut dyn Operator) {
        let text = String::from_utf8_lossy(line);
        let Ok(body) = crate::link::check_reply_line(&text) else {
            self.dropped += 1;
            return;
        };
        let reg = |k: &str| words_value(body, k).and_then(|v| v.parse::<i64>().ok());
        if body.starts_with("!RESET") {
            if let (Some(px), Some(pz)) = (reg("PX"), reg("PZ")) {
                self.reset_seen = Some((px, pz));
            }
            return;
        }
        if body.starts_with("!ALARM") {
            let code = words_value(body, "CODE").and_then(|v| v.parse().ok());
            if let (Some(code), Some(px), Some(pz)) = (code, reg("PX"), reg("PZ")) {
                let input = words_value(body, "INPUT").unwrap_or("").to_owned();
                op.say(&format!("alarm {code}: input {input}"));
                self.alarm_seen = Some(Stopped {
                    code,
                    input,
                    at: (px, pz),
                });
            }
            return;
        }
        if !body.starts_with("!STATUS") {
            return;
        }
        let state = words_value(body, "STATE").unwrap_or("").to_owned();
        let speed = words_value(body, "V").unwrap_or("").to_owned();
        // Moving, held, or waiting at a program stop: the request is
        // waiting its turn, not lost.
        if state != "IDLE" || words_value(body, "STOP").is_some() {
            self.busy_at = Some(Instant::now());
        }
        // At rest (held, or nothing running) the reset loses no step. A
        // device that reports no latency issues its blocks in no time
        // (`serve`): nothing is ever in motion there.
        let board = words_value(body, "LAT").is_some();
        let at_rest = state != "RUN" && speed.parse::<f64>().is_ok_and(|v| v == 0.0);
        if self.aborting && (at_rest || !board) {
            let _ = self.link.send(&[0x18]);
        }
        let p = &mut self.progress;
        p.stop = words_value(body, "STOP").map(str::to_owned);
        p.state = state;
        p.speed = speed;
        p.x = words_value(body, "X").unwrap_or("").to_owned();
        p.z = words_value(body, "Z").unwrap_or("").to_owned();
        if let (Some(px), Some(pz)) = (reg("PX"), reg("PZ")) {
            p.registers = (px, pz);
        }
        if let Some(plan) = plan {
            // The event the board stands at: the first at or after the last
            // found with these registers.
            let from = self.hint as usize;
            let window = plan.positions.len().min(from + 2_000_000);
            if let Some(k) = plan.positions[from.min(window)..window]
                .iter()
                .position(|&q| q == p.registers)
            {
                self.hint = (from + k) as u64;
            }
            let line = plan.line_at(self.hint);
            p.running = plan.lines.get(line).map_or(0, |l| l.source);
            let done = if line == 0 {
                0
            } else {
                plan.lines[line - 1].time_after_us
            };
            p.remaining_us = plan.total_us.saturating_sub(done);
        }
        op.show(&self.progress);
    }

    /// Streams `plan` (built by [`Plan::build`] for this board's settings).
    pub fn send(&mut self, plan: &Plan, op: &mut dyn Operator) -> SendReport {
        let started = Instant::now();
        let mut report = SendReport {
            halt: None,
            requests: 0,
            seconds: 0.0,
            starved: None,
            registers: None,
            expected: plan.end(),
            resets: 0,
            retries: 0,
            dropped: 0,
        };
        let r = self.stream(plan, op, &mut report);
        report.halt = r.err();
        if matches!(report.halt, Some(Halt::Aborted(_) | Halt::Stopped(_))) {
            // The reset (or the switch's stop, which acts as one) ended the
            // session: a new one, to ask where it stands.
            let _ = self.session();
        }
        if !matches!(report.halt, Some(Halt::Link(_) | Halt::PowerLost)) {
            if let Ok(pos) = self.exchange("POS", op, None) {
                let v = |k| pos.value(k).and_then(|v| v.parse().ok());
                if let (Some(px), Some(pz)) = (v("PX"), v("PZ")) {
                    report.registers = Some((px, pz));
                }
            }
        }
        report.seconds = started.elapsed().as_secs_f64();
        report.resets = self.progress.resets;
        report.retries = self.retries;
        report.dropped = self.dropped;
        report
    }

    fn must(&mut self, req: &str, op: &mut dyn Operator, plan: &Plan) -> Result<Reply, Halt> {
        let r = self.exchange(req, op, Some(plan))?;
        if r.is_ok() {
            Ok(r)
        } else {
            Err(Halt::Board(format!("{req}: {}", r.last)))
        }
    }

    fn stream(
        &mut self,
        plan: &Plan,
        op: &mut dyn Operator,
        report: &mut SendReport,
    ) -> Result<(), Halt> {
        self.progress.lines = plan.lines.len();
        for s in &plan.setup {
            self.must(s, op, plan)?;
        }
        self.must("SYNC", op, plan)?;
        self.base = 0;
        self.hint = 0;
        let mut next = 0usize;
        let mut prefix = None;
        loop {
            if let Some(s) = self.alarm_seen.take() {
                return Err(Halt::Stopped(s));
            }
            if self.reset_seen.is_some() {
                let j = self.restart(plan, next, op)?;
                next = j;
                prefix = plan.lines[j..].first().and_then(|l| l.motion_word);
                continue;
            }
            if next == plan.lines.len() {
                let r = self.exchange("SYNC", op, Some(plan))?;
                if self.reset_seen.is_some() || self.alarm_seen.is_some() {
                    continue;
                }
                if !r.is_ok() {
                    return Err(Halt::Board(format!("SYNC: {}", r.last)));
                }
                report.starved = r.value("STARVED").and_then(|v| v.parse().ok());
                return Ok(());
            }
            let line = &plan.lines[next];
            let text = match prefix.take() {
                Some(w) => with_motion_word(&line.text, w),
                None => line.text.clone(),
            };
            let r = self.exchange(&text, op, Some(plan))?;
            report.requests += 1;
            if let Some(s) = self.alarm_seen.take() {
                // Its motion, if any, was dropped with the rest.
                return Err(Halt::Stopped(s));
            }
            if r.last.starts_with("ERR SESSION") {
                if self.reset_seen.is_none() {
                    // Wait briefly for a reset report still on its way.
                    let t = Instant::now();
                    while self.reset_seen.is_none() && t.elapsed() < self.timeout {
                        match self.link.recv_line(Duration::from_millis(20))? {
                            Some(l) if l.first() == Some(&b'!') => {
                                self.on_realtime(&l, Some(plan), op)
                            }
                            _ => {}
                        }
                    }
                }
                if self.reset_seen.is_none() {
                    return Err(Halt::PowerLost);
                }
                continue;
            }
            if self.reset_seen.is_some() {
                // Answered, but its motion may have been dropped: the restart
                // decides from the events.
                next += 1;
                continue;
            }
            if !r.last.starts_with("OK") {
                let _ = self.exchange("SYNC", op, Some(plan));
                return Err(Halt::Refused(line.source, r.last));
            }
            if r.last != line.expect {
                let _ = self.link.send(&[0x82]);
                return Err(Halt::Mismatch(line.source, r.last, line.expect.clone()));
            }
            next += 1;
            self.progress.acked = next;
            op.show(&self.progress);
        }
    }

    /// After a reset: the session again, the line to restart from, the
    /// modal state there, the tool back along its path to that line's
    /// start. Returns the line to send next.
    fn restart(&mut self, plan: &Plan, sent: usize, op: &mut dyn Operator) -> Result<usize, Halt> {
        let Some(stood) = self.reset_seen.take() else {
            return Ok(sent);
        };
        if self.aborting {
            return Err(Halt::Aborted(stood));
        }
        self.must(&format!("SESSION TOKEN={}", self.token), op, plan)?;
        let r = self.must("SYNC", op, plan)?;
        let ev: u64 = r.value("EV").and_then(|v| v.parse().ok()).unwrap_or(0);
        // The events issued before the reset (the one waiting for its tick
        // is not counted): the registers must be where they lead.
        let e = self.base + ev;
        if plan.positions.get(e as usize) != Some(&stood) {
            return Err(Halt::Mismatch(
                plan.lines.get(plan.line_at(e)).map_or(0, |l| l.source),
                format!("reset at PX={} PZ={} after {e} events", stood.0, stood.1),
                format!(
                    "PX={} PZ={} after {e} events",
                    plan.positions.get(e as usize).map_or(0, |p| p.0),
                    plan.positions.get(e as usize).map_or(0, |p| p.1)
                ),
            ));
        }
        let unfinished = plan.lines.partition_point(|l| l.after <= e);
        let mut j = unfinished.min(sent);
        while j > 0 && j < plan.lines.len() && plan.lines[j].comp_before {
            j -= 1;
        }
        for s in &plan.setup {
            self.must(s, op, plan)?;
        }
        let target = plan.lines.get(j).map_or(plan.events(), |l| l.before);
        let source = plan.lines.get(j).map_or(0, |l| l.source);
        op.say(&format!(
            "reset at PX={} PZ={} ({e} of {} events): restarting at line {source}, the tool back along its path to where that line starts",
            stood.0,
            stood.1,
            plan.events()
        ));
        // The spindle and coolant as they were, then the tool back along its
        // path (machine coordinates, per minute), then the program's modes
        // again.
        let restore = plan.lines.get(j).map_or(&[][..], |l| &l.restore[..]);
        for s in restore {
            self.must(s, op, plan)?;
        }
        for p in plan.retrace(e, target) {
            let mv = plan.move_to(p, &self.return_feed);
            self.must(&mv, op, plan)?;
        }
        for s in restore {
            self.must(s, op, plan)?;
        }
        self.must("SYNC", op, plan)?;
        self.base = target;
        self.hint = target;
        self.progress.resets += 1;
        Ok(j)
    }
}

/// The key a byte from the keyboard stands for: `!`, `h` or space hold;
/// `~`, `c` or `r` resume; `q` or Ctrl-C abort; Ctrl-X or `x` reset.
pub fn key_of(byte: u8) -> Option<Key> {
    match byte {
        b'!' | b'h' | b'H' | b' ' => Some(Key::Hold),
        b'~' | b'c' | b'C' | b'r' | b'R' => Some(Key::Resume),
        b'q' | b'Q' | 0x03 => Some(Key::Abort),
        b'x' | b'X' | 0x18 => Some(Key::Reset),
        _ => None,
    }
}

/// The terminal: a progress bar, and keys that act at once (the terminal
/// in raw mode while it lasts, so Ctrl-C reaches the sender as an abort
/// rather than killing it with the machine running).
pub struct Console {
    bar: indicatif::ProgressBar,
    keys: std::sync::mpsc::Receiver<u8>,
    saved: Option<libc::termios>,
}

impl Console {
    /// A console for a program of `lines` lines.
    pub fn new(lines: usize) -> Console {
        let bar = indicatif::ProgressBar::new(lines as u64).with_style(
            indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} lines {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        let saved = raw_mode();
        let (tx, keys) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            use std::io::Read;
            let mut b = [0u8; 1];
            let mut stdin = std::io::stdin();
            while let Ok(1) = stdin.read(&mut b) {
                if tx.send(b[0]).is_err() {
                    break;
                }
            }
        });
        Console { bar, keys, saved }
    }
}

/// Standard input in raw mode if it is a terminal; its settings before.
fn raw_mode() -> Option<libc::termios> {
    // SAFETY: isatty and tcgetattr/tcsetattr read and write the termios
    // struct of file descriptor 0, owned by this process.
    unsafe {
        if libc::isatty(0) != 1 {
            return None;
        }
        let mut t: libc::termios = std::mem::zeroed();
        if libc::tcgetattr(0, &mut t) != 0 {
            return None;
        }
        let saved = t;
        t.c_lflag &= !(libc::ICANON | libc::ECHO | libc::ISIG);
        t.c_cc[libc::VMIN] = 1;
        t.c_cc[libc::VTIME] = 0;
        (libc::tcsetattr(0, libc::TCSANOW, &t) == 0).then_some(saved)
    }
}

impl Drop for Console {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
        if let Some(t) = self.saved {
            // SAFETY: restores the settings read in `raw_mode`.
            unsafe {
                libc::tcsetattr(0, libc::TCSANOW, &t);
            }
        }
    }
}

impl Operator for Console {
    fn key(&mut self, _: &Progress) -> Option<Key> {
        self.keys.try_iter().find_map(key_of)
    }

    fn show(&mut self, p: &Progress) {
        self.bar.set_position(p.acked as u64);
        self.bar.set_message(format!(
            "running line {} X{} Z{} {} F{} left {}{}",
            p.running,
            p.x,
            p.z,
            p.state,
            p.speed,
            crate::program::minutes(p.remaining_us),
            if p.resets > 0 {
                format!(" ({} restarts)", p.resets)
            } else {
                String::new()
            }
        ));
        if let Some(code) = &p.stop {
            self.bar
                .set_message(format!("{code} program stop: c for cycle start"));
        }
    }

    fn say(&mut self, text: &str) {
        if self.bar.is_hidden() {
            eprintln!("{text}");
        } else {
            self.bar.println(text);
        }
    }
}

/// No one at the machine.
struct NoOperator;

impl Operator for NoOperator {
    fn key(&mut self, _: &Progress) -> Option<Key> {
        None
    }
    fn show(&mut self, _: &Progress) {}
    fn say(&mut self, _: &str) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_lengths() {
        assert_eq!(exact_mm(0), "0");
        assert_eq!(exact_mm(-1_250_000), "-0.125");
        assert_eq!(exact_mm(123_456_789), "12.3456789");
    }

    #[test]
    fn motion_word_goes_after_slash_and_n() {
        assert_eq!(with_motion_word("X10 Z5", "G02"), "G02 X10 Z5");
        assert_eq!(with_motion_word("N120 X10", "G01"), "N120 G01 X10");
        assert_eq!(with_motion_word("/N5 Z-3", "G00"), "/N5 G00 Z-3");
    }
}

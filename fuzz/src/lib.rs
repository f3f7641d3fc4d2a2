//! Independent oracles shared by the fuzz targets.
//!
//! Nothing here calls the core's own helpers for what it checks: reply lines,
//! request framing, decimal lengths, `Q` (half away from zero), the step
//! interleaving rule of a linear block and the CRC-32 behind `SEQ` come from
//! the `reference` crate's exact models (`reference::exact`,
//! `reference::protocol`, written from `docs/impulses.md` and
//! `docs/protocol.md`; `docs/verification.md` §3), or are re-derived here
//! from `docs/protocol.md` with exact integer arithmetic.

use core_nostd::interleave::{LinearBlock, StepEvent};
use core_nostd::protocol::{Device, Io, Session};
use core_nostd::stepdir::DriveTiming;
use reference::exact::{fmt_tenth_um, StepEvents};

/// `Q(n/d)`, the CRC-32 and the line checksum of the exact model.
pub use reference::exact::{q_div as q, xor_checksum as xor, Crc32};
/// The request lengths and the error codes of `docs/protocol.md` §3, §10.
pub use reference::protocol::{parse_mm, LengthRefusal, ERROR_CODES};

/// The longest request line, terminator excluded (`docs/protocol.md` §2).
pub const MAX_LINE: usize = reference::protocol::LINE_MAX;
/// The longest reply line, `*HH` and CRLF included.
pub const MAX_REPLY: usize = 160;
/// The largest coordinate magnitude in ångström: 99 999.999999 mm.
pub const LIMIT_ANGSTROM: i64 = reference::protocol::COORD_MAX_ANGSTROM;
/// The largest impulse register magnitude.
pub const MAX_POSITION: i64 = reference::protocol::REGISTER_MAX;
/// The largest number of impulses per axis in one linear block.
pub const MAX_BLOCK: i64 = reference::protocol::BLOCK_MAX;

// ---------------------------------------------------------------------------
// Decimals
// ---------------------------------------------------------------------------

/// Ångström printed as the reply format: 4 decimals, half away from zero.
pub fn mm4_of(angstrom: i128) -> String {
    fmt_tenth_um(q(angstrom, 1_000))
}

/// Ångström (a multiple of 10) as an exact decimal with up to 6 decimals.
pub fn exact_mm(angstrom: i64) -> String {
    assert_eq!(angstrom % 10, 0, "not a whole nanometre: {angstrom}");
    exact_gcode_mm(angstrom)
}

/// Ångström as an exact decimal with up to 7 decimals (a G-code number).
pub fn exact_gcode_mm(angstrom: i64) -> String {
    let sign = if angstrom < 0 { "-" } else { "" };
    let a = angstrom.unsigned_abs();
    let frac = format!("{:07}", a % 10_000_000);
    let frac = frac.trim_end_matches('0');
    if frac.is_empty() {
        format!("{sign}{}", a / 10_000_000)
    } else {
        format!("{sign}{}.{frac}", a / 10_000_000)
    }
}

/// A request body with its `*HH` appended.
pub fn with_checksum(body: &str) -> String {
    format!("{body}*{:02X}", xor(body.as_bytes()))
}

// ---------------------------------------------------------------------------
// Framing
// ---------------------------------------------------------------------------

/// One request as the framing sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Framed {
    /// A line (terminator excluded).
    Line(Vec<u8>),
    /// A line that grew beyond 120 bytes; reported once, its rest discarded.
    TooLong,
}

/// Request framing per `docs/protocol.md` §2: LF, CR or CRLF (one terminator) end a
/// line; the 121st byte of a line makes it over-long, reported once, and
/// everything up to its terminator is discarded.
#[derive(Clone, Debug, Default)]
pub struct Framer {
    buf: Vec<u8>,
    over: bool,
    prev_cr: bool,
}

impl Framer {
    /// Takes one byte; returns the request it completes, if any.
    pub fn push(&mut self, b: u8) -> Option<Framed> {
        let prev_cr = std::mem::replace(&mut self.prev_cr, b == b'\r');
        if b == b'\n' && prev_cr {
            return None;
        }
        if b == b'\r' || b == b'\n' {
            let line = std::mem::take(&mut self.buf);
            return if std::mem::replace(&mut self.over, false) {
                None
            } else {
                Some(Framed::Line(line))
            };
        }
        if self.over {
            return None;
        }
        self.buf.push(b);
        if self.buf.len() > MAX_LINE {
            self.buf.clear();
            self.over = true;
            return Some(Framed::TooLong);
        }
        None
    }
}

/// The index of the byte that completes each request in `bytes` (from a
/// fresh framer), with the request.
pub fn requests(bytes: &[u8]) -> Vec<(usize, Framed)> {
    let mut f = Framer::default();
    without_realtime(bytes)
        .iter()
        .enumerate()
        .filter_map(|(i, &b)| f.push(b).map(|r| (i, r)))
        .collect()
}

/// The bytes without the real-time bytes (0x18, 0x80–0x82): the device acts
/// on those outside every request (its own tests check them), so the
/// request oracle takes the stream as the framing sees it.
pub fn without_realtime(bytes: &[u8]) -> Vec<u8> {
    bytes
        .iter()
        .copied()
        .filter(|&b| core_nostd::protocol::Realtime::from_byte(b).is_none())
        .collect()
}

// ---------------------------------------------------------------------------
// Request integrity and ids (the reliable-link extension)
// ---------------------------------------------------------------------------

/// What the integrity words of a request line say, read from the right:
/// `*HH` (XOR of the bytes before `*`), then an optional ` ~CCCCCCCC` word
/// standing alone at the end (CRC-32 of every byte before `~`), then an
/// optional leading `@id` word (1 … 4294967295).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Link {
    /// A wrong or malformed `*HH`, or a wrong CRC word: `ERR CHECKSUM`
    /// without id or CRC words.
    Corrupt,
    /// Integrity checked.
    Pass {
        /// The request without its integrity words and id.
        body: Vec<u8>,
        /// A CRC word was there (replies carry one too).
        crc: bool,
        /// The `@id` word.
        id: IdWord,
    },
}

/// The leading `@id` word of a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdWord {
    /// None.
    Absent,
    /// A valid id.
    Id(u32),
    /// `@` followed by anything but 1 … 4294967295.
    Invalid,
}

/// Reads the integrity words of a request line.
pub fn link(line: &[u8]) -> Link {
    let hex = |b: u8| (b as char).to_digit(16);
    let mut body = line;
    // The checksum's `*`: the last one when the line ends in `*HH`, else
    // the last one outside a comment (`( … )` or after `;`): a comment may
    // hold a `*` of its own.
    let ends_hh =
        matches!(line, [.., b'*', h, l] if h.is_ascii_hexdigit() && l.is_ascii_hexdigit());
    let star = if ends_hh {
        line.iter().rposition(|&b| b == b'*')
    } else {
        let (mut paren, mut rest, mut found) = (false, false, None);
        for (i, &b) in line.iter().enumerate() {
            if rest {
                break;
            }
            if paren {
                paren = b != b')';
                continue;
            }
            match b {
                b'(' => paren = true,
                b';' => rest = true,
                b'*' => found = Some(i),
                _ => {}
            }
        }
        found
    };
    if let Some(star) = star {
        let tail = &line[star + 1..];
        let given = match tail {
            [h, l] => match (hex(*h), hex(*l)) {
                (Some(h), Some(l)) => h * 16 + l,
                _ => return Link::Corrupt,
            },
            _ => return Link::Corrupt,
        };
        if given != u32::from(xor(&line[..star])) {
            return Link::Corrupt;
        }
        body = &line[..star];
    }
    let mut crc = false;
    if let Some(tilde) = body.iter().rposition(|&b| b == b'~') {
        let word = &body[tilde + 1..];
        let alone = tilde == 0 || matches!(body[tilde - 1], b' ' | b'\t');
        if alone && word.len() == 8 && word.iter().all(u8::is_ascii_hexdigit) {
            let given = u32::from_str_radix(std::str::from_utf8(word).unwrap(), 16).unwrap();
            let mut c = Crc32::default();
            for &b in &body[..tilde] {
                c.push(b);
            }
            if c.finish() != given {
                return Link::Corrupt;
            }
            crc = true;
            body = &body[..tilde];
        }
    }
    let trimmed = {
        let start = body
            .iter()
            .position(|&b| b != b' ' && b != b'\t')
            .unwrap_or(body.len());
        &body[start..]
    };
    let (id, rest) = match trimmed.split_first() {
        Some((b'@', after)) => {
            let end = after
                .iter()
                .position(|&b| b == b' ' || b == b'\t')
                .unwrap_or(after.len());
            let digits = &after[..end];
            let id = if !digits.is_empty()
                && digits.len() <= 10
                && digits.iter().all(u8::is_ascii_digit)
            {
                std::str::from_utf8(digits)
                    .unwrap()
                    .parse::<u64>()
                    .ok()
                    .and_then(|v| u32::try_from(v).ok())
                    .filter(|&v| v > 0)
            } else {
                None
            };
            match id {
                Some(id) => (IdWord::Id(id), &after[end..]),
                None => (IdWord::Invalid, body),
            }
        }
        _ => (IdWord::Absent, body),
    };
    Link::Pass {
        body: rest.to_vec(),
        crc,
        id,
    }
}

/// Strips and checks the suffix words a reply line carries for a request
/// with an id and/or a CRC word: ` @id`, then ` ~CCCCCCCC`, the CRC-32 of
/// every byte of the line before the `~`.
pub fn strip_suffix(body: &str, id: Option<u32>, crc: bool) -> String {
    let mut b = body;
    if crc {
        let (head, word) = b
            .rsplit_once(" ~")
            .unwrap_or_else(|| panic!("reply without CRC word: {body:?}"));
        assert!(
            word.len() == 8
                && word
                    .bytes()
                    .all(|c| c.is_ascii_digit() || (b'A'..=b'F').contains(&c)),
            "CRC word of {body:?}"
        );
        let mut c = Crc32::default();
        for &x in head.as_bytes() {
            c.push(x);
        }
        c.push(b' ');
        assert_eq!(word, format!("{:08X}", c.finish()), "reply CRC of {body:?}");
        b = head;
    }
    if let Some(id) = id {
        b = b
            .strip_suffix(&format!(" @{id}"))
            .unwrap_or_else(|| panic!("reply without @{id}: {body:?}"));
    }
    b.to_string()
}

// ---------------------------------------------------------------------------
// Replies and motion
// ---------------------------------------------------------------------------

/// Checks one reply line: ASCII, at most 160 bytes, `*HH` correct, CRLF.
/// Returns the body (before `*`).
pub fn check_reply_line(line: &[u8]) -> String {
    assert!(line.is_ascii(), "reply not ASCII: {line:?}");
    assert!(
        line.len() <= MAX_REPLY,
        "reply longer than {MAX_REPLY} bytes: {}",
        line.len()
    );
    let text = std::str::from_utf8(line).unwrap();
    let text = text
        .strip_suffix("\r\n")
        .unwrap_or_else(|| panic!("reply without CRLF: {text:?}"));
    assert!(
        !text.contains(['\r', '\n']),
        "terminator inside a reply: {text:?}"
    );
    let (body, sum) = text
        .rsplit_once('*')
        .unwrap_or_else(|| panic!("reply without *HH: {text:?}"));
    assert_eq!(
        sum,
        format!("{:02X}", xor(body.as_bytes())),
        "reply checksum of {text:?}"
    );
    assert!(
        body.bytes().all(|b| (0x20..0x7F).contains(&b)),
        "control byte in reply {body:?}"
    );
    body.to_string()
}

/// Checks the step events of a linear block against `docs/impulses.md`
/// §3.1, as the exact model's [`StepEvents`] gives them: the leading axis
/// (larger |Δ|, X on a tie) steps in every event; after event `i` the other
/// axis stands at `Q(i·Δb/|Δlead|)`; a direction bit is set only with its
/// step, and only for a negative step. `bytes` are the events issued for it.
pub fn check_linear_events(block: &LinearBlock, bytes: &[u8]) {
    let (dx, dz) = block.delta();
    assert!(i64::from(dx).abs() <= MAX_BLOCK && i64::from(dz).abs() <= MAX_BLOCK);
    let (from, to) = (block.from(), block.to());
    assert_eq!(
        (
            i64::from(to.x.get()) - i64::from(from.x.get()),
            i64::from(to.z.get()) - i64::from(from.z.get())
        ),
        (i64::from(dx), i64::from(dz))
    );
    let rule = StepEvents::new(dx.into(), dz.into());
    assert_eq!(
        bytes.len() as u64,
        rule.total(),
        "number of events of the block {dx},{dz}"
    );
    // The rule's events carry no data-dependent branch: this loop runs for
    // every step and is not what the fuzzer should steer by.
    let mut bad = 0u8;
    for (&b, expected) in bytes.iter().zip(rule.clone()) {
        bad |= b ^ expected;
    }
    if bad != 0 {
        // Slow path: find and name the first wrong event.
        for (k, (&b, expected)) in bytes.iter().zip(rule).enumerate() {
            assert_eq!(
                b,
                expected,
                "event {} of the block {dx},{dz}: {b:#06b}, the rule gives {expected:#06b}",
                k + 1
            );
        }
    }
}

/// Checks the step events of a direct arc: each event steps at least one
/// axis, each axis at most once, a direction bit only with its step; returns
/// the increments they add up to.
pub fn check_direct_events(bytes: &[u8]) -> (i32, i32) {
    // Count the events by byte value (no per-event branches), then check.
    let mut seen = [0i64; 256];
    for &b in bytes {
        seen[usize::from(b)] = seen[usize::from(b)].wrapping_add(1);
    }
    let (mut sx, mut sz) = (0i64, 0i64);
    for (b, &n) in seen.iter().enumerate().filter(|(_, &n)| n > 0) {
        assert_eq!(b & 0xF0, 0, "event byte {b:#04x}");
        assert!(b & 3 != 0, "direct arc event steps nothing");
        assert!(b & 4 == 0 || b & 1 != 0, "X direction bit without X step");
        assert!(b & 8 == 0 || b & 2 != 0, "Z direction bit without Z step");
        if b & 1 != 0 {
            sx += if b & 4 != 0 { -n } else { n };
        }
        if b & 2 != 0 {
            sz += if b & 8 != 0 { -n } else { n };
        }
    }
    assert!(sx.abs() <= MAX_BLOCK && sz.abs() <= MAX_BLOCK);
    (sx as i32, sz as i32)
}

/// Step events per request that are kept and checked one by one. An arc may
/// issue billions of steps (a circle of 50 m radius at 0.0001 mm per
/// impulse); beyond this budget only the `SEQ` and the increments are
/// checked, so one input cannot stall the fuzzer for minutes.
pub const EVENT_BUDGET: u64 = 5_000_000;

/// The fuzzed device: the look-ahead window is one block, so every block
/// starts, and issues its events, within the request that queues it.
pub fn fuzz_device() -> Device {
    Device::with_window(1)
}

/// An [`Io`] that checks and collects reply lines, and checks the motion it
/// is handed.
pub struct Collect {
    /// Reply bodies (before `*HH`), in order.
    pub lines: Vec<String>,
    /// Increments of every block and direct arc handed to the drive.
    pub moves: Vec<(i32, i32)>,
    /// CRC-32 of every step event handed to the drive.
    pub crc: Crc32,
    /// Events left to keep.
    pub budget: u64,
    /// Some motion was beyond the budget: not every event was checked.
    pub over_budget: bool,
    /// The events kept, and where each block's begin.
    bytes: Vec<u8>,
    blocks: Vec<(usize, LinearBlock)>,
    /// Signed steps of every event.
    sum: (i64, i64),
    /// The tick of the last event of the run.
    tick: Option<u64>,
}

impl Default for Collect {
    fn default() -> Self {
        Collect {
            lines: Vec::new(),
            moves: Vec::new(),
            crc: Crc32::default(),
            budget: EVENT_BUDGET,
            over_budget: false,
            bytes: Vec::new(),
            blocks: Vec::new(),
            sum: (0, 0),
            tick: None,
        }
    }
}

impl Collect {
    /// Checks the events against the blocks they came from and sets
    /// `moves`: one entry per block, and one for events of no block (a
    /// direct arc).
    pub fn finish(&mut self) {
        let mut direct = Vec::new();
        let mut at = 0;
        for (k, &(start, block)) in self.blocks.iter().enumerate() {
            let n = block.events().len();
            if start > at {
                direct.extend_from_slice(&self.bytes[at..start.min(self.bytes.len())]);
            }
            let end = start + n;
            if end > self.bytes.len() && self.over_budget {
                // Beyond the budget the events are not kept: only the
                // increments of these blocks are.
                self.moves.push(block.delta());
                at = self.bytes.len();
                continue;
            }
            let next = self.blocks.get(k + 1).map_or(usize::MAX, |b| b.0);
            assert!(end <= next, "a block's events cut short by the next block");
            if !self.over_budget {
                check_linear_events(&block, &self.bytes[start..end]);
            }
            self.moves.push(block.delta());
            at = end;
        }
        if at < self.bytes.len() {
            direct.extend_from_slice(&self.bytes[at..]);
        }
        if !direct.is_empty() {
            self.moves.push(check_direct_events(&direct));
        }
        if !self.over_budget {
            let total = self.moves.iter().fold((0i64, 0i64), |a, m| {
                (a.0 + i64::from(m.0), a.1 + i64::from(m.1))
            });
            assert_eq!(total, self.sum, "steps issued vs the blocks' increments");
        }
    }
}

impl Io for Collect {
    fn send(&mut self, line: &[u8]) {
        self.lines.push(check_reply_line(line));
    }
    fn block_start(&mut self, block: &LinearBlock) {
        self.blocks.push((self.bytes.len(), *block));
    }
    fn step(&mut self, event: StepEvent, tick: u64, _: &DriveTiming) {
        let b = event.bits();
        self.crc.push(b);
        let signed = |step: bool, neg: bool| i64::from(step) * if neg { -1 } else { 1 };
        self.sum.0 += signed(event.x_steps(), event.x_negative());
        self.sum.1 += signed(event.z_steps(), event.z_negative());
        if let Some(t) = self.tick {
            assert!(tick >= t, "ticks went back in a run: {t} then {tick}");
        }
        self.tick = Some(tick);
        if self.budget == 0 {
            self.over_budget = true;
        } else {
            self.budget -= 1;
            self.bytes.push(b);
        }
    }
    fn run_end(&mut self, _: u64) {
        self.tick = None;
    }
}

/// Whether a reply body is a final line.
pub fn is_final(body: &str) -> bool {
    body == "OK" || body.starts_with("OK ") || body.starts_with("ERR ")
}

/// The value of `KEY=` in a reply body.
pub fn value<'a>(body: &'a str, key: &str) -> Option<&'a str> {
    body.split(' ')
        .find_map(|w| w.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
}

fn int(body: &str, key: &str) -> Option<i64> {
    value(body, key).map(|v| {
        v.parse()
            .unwrap_or_else(|_| panic!("{key}= not an integer in {body:?}"))
    })
}

/// Everything a request could change, as the device reports it: the
/// `POS`, `CFG`, `DRIVE` and `SESSION` replies of a copy, and the whole
/// session state apart from the retry memory (the last request id and its
/// reply, which every numbered request updates, refused or not).
pub fn snapshot(s: &Session) -> [String; 5] {
    let ask = |req: &[u8]| {
        let mut copy = s.clone();
        let mut io = Collect::default();
        copy.handle_line(req, &mut io);
        assert_eq!(io.lines.len(), 1, "{:?} -> {:?}", req, io.lines);
        assert!(
            io.lines[0].starts_with("OK "),
            "{:?} -> {:?}",
            req,
            io.lines
        );
        io.lines.remove(0)
    };
    let debug = format!("{s:?}");
    let debug = match debug.find(", last_id:") {
        Some(at) => debug[..at].to_string(),
        None => debug,
    };
    [
        ask(b"POS"),
        ask(b"CFG"),
        ask(b"DRIVE"),
        ask(b"SESSION"),
        debug,
    ]
}

/// The session's registers hold `Q(P/h)` of its exact commanded point, within
/// the register range; the commanded point is within the length limit; and
/// `POS` reports exactly that.
pub fn check_position(s: &Session) {
    let (x, z) = s.commanded();
    let (x, z) = (x.as_angstrom(), z.as_angstrom());
    let p = s.position();
    let c = s.config();
    assert!(x.abs() <= LIMIT_ANGSTROM && z.abs() <= LIMIT_ANGSTROM);
    let (hx, hz) = (c.hx.as_angstrom(), c.hz.as_angstrom());
    assert!((10..=10_000_000).contains(&hx) && (10..=10_000_000).contains(&hz));
    let (px, pz) = (i64::from(p.x.get()), i64::from(p.z.get()));
    assert!(px.abs() <= MAX_POSITION, "PX={px}");
    assert!(pz.abs() <= MAX_POSITION, "PZ={pz}");
    assert_eq!(i128::from(px), q(x.into(), hx.into()), "PX vs Q(X/hx)");
    assert_eq!(i128::from(pz), q(z.into(), hz.into()), "PZ vs Q(Z/hz)");
    let factor = if c.diam { 2 } else { 1 };
    let machine = format!(
        "X={} Z={}",
        mm4_of(i128::from(x) * factor),
        mm4_of(z.into())
    );
    let mut copy = s.clone();
    let mut io = Collect::default();
    copy.handle_line(b"POS", &mut io);
    assert_eq!(io.lines.len(), 1, "POS");
    // With offsets in effect, X and Z are work coordinates and MX, MZ the
    // machine's.
    match io.lines[0].split_once(" MX=") {
        None => assert_eq!(io.lines[0], format!("OK PX={px} PZ={pz} {machine}"), "POS"),
        Some((head, tail)) => {
            assert!(
                head.starts_with(&format!("OK PX={px} PZ={pz} X=")),
                "POS {head}"
            );
            assert_eq!(format!("X={tail}").replace("MZ=", "Z="), machine, "POS");
        }
    }
}

/// The outcome of one request.
#[derive(Debug)]
pub struct Answer {
    /// Reply bodies (id and CRC words stripped), the final one last.
    pub lines: Vec<String>,
    /// Increments handed to the drive.
    pub moves: Vec<(i32, i32)>,
    /// The final line repeats a remembered reply (same `@id` again).
    pub replay: bool,
    /// The request was an arc too long to run here and was sent blank
    /// (see [`MAX_ARC_STEPS`]).
    pub skipped: bool,
}

/// The most steps an arc request may issue to be run by the fuzz targets.
/// An arc may legitimately issue billions of steps (a full circle of 50 m
/// radius at 0.0001 mm per impulse: 2.8·10⁹, several seconds of CRC even
/// natively); such requests are blanked before they reach the device.
pub const MAX_ARC_STEPS: u128 = 20_000_000;

/// An upper bound of the steps an `ARC` request or a G-code arc block could
/// issue on this session: a whole circle of the radius its `R` word or its
/// `I`/`K` vector gives, on both axes. 0 for anything else.
pub fn arc_steps_bound(s: &Session, line: &[u8]) -> u128 {
    let Link::Pass { body, .. } = link(line) else {
        return 0;
    };
    let Ok(text) = std::str::from_utf8(&body) else {
        return 0;
    };
    let mut r: u128 = 0;
    let abs = |v: &str| parse_mm(v).map_or(0, |a| a.unsigned_abs() as u128);
    if reference_is_block(text) {
        if let Ok(b) = reference_block(text) {
            let a = |v: Option<i64>| v.map_or(0, |a| a.unsigned_abs() as u128);
            r = a(b.xzikr[4]).max(a(b.xzikr[2]) + a(b.xzikr[3]));
        }
    } else {
        let mut words = text.split([' ', '\t']).filter(|w| !w.is_empty());
        if words.next().is_some_and(|w| w.eq_ignore_ascii_case("ARC")) {
            for w in words {
                if let Some((k, v)) = w.split_once('=') {
                    if k.eq_ignore_ascii_case("I") || k.eq_ignore_ascii_case("K") {
                        r += abs(v);
                    }
                }
            }
        }
    }
    let c = s.config();
    let h = c.hx.as_angstrom().min(c.hz.as_angstrom()).max(1) as u128;
    // Circumference < 7·r; each step moves one axis by one price.
    7 * r * 2 / h
}

impl Answer {
    /// The final line.
    pub fn last(&self) -> &str {
        self.lines.last().map(String::as_str).unwrap_or("")
    }
    /// The error code if refused.
    pub fn err(&self) -> Option<&str> {
        self.last()
            .strip_prefix("ERR ")
            .map(|r| r.split(' ').next().unwrap_or(""))
    }
}

/// A device and what the checks need to remember between its requests:
/// the framing state and the last request id with its final reply.
#[derive(Clone)]
pub struct Checker {
    /// The device under test.
    pub dev: Device,
    framer: Framer,
    last: Option<(u32, String)>,
}

impl Checker {
    /// Checks a device (which must be at a line boundary, with no request id
    /// remembered).
    pub fn new(dev: Device) -> Self {
        Checker {
            dev,
            framer: Framer::default(),
            last: None,
        }
    }

    /// Feeds any bytes, request by request as the framing sees them,
    /// checking each with [`Checker::request`]; bytes after the last request
    /// must produce nothing.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Answer> {
        let bytes = &without_realtime(bytes)[..];
        let mut out = Vec::new();
        let mut start = 0;
        for (i, &b) in bytes.iter().enumerate() {
            if let Some(r) = self.framer.push(b) {
                let chunk = &bytes[start..=i];
                start = i + 1;
                if let Framed::Line(line) = &r {
                    if arc_steps_bound(self.dev.session(), line) > MAX_ARC_STEPS {
                        // Blank the line (same bytes count, same framing):
                        // the device answers ERR EMPTY.
                        let mut blank = chunk.to_vec();
                        let n = blank.len();
                        blank[n - 1 - line.len()..n - 1].fill(b' ');
                        let mut a = self.request(&blank, &Framed::Line(vec![b' '; line.len()]));
                        a.skipped = true;
                        out.push(a);
                        continue;
                    }
                }
                out.push(self.request(chunk, &r));
            }
        }
        let mut io = Collect::default();
        self.dev.receive_bytes(&bytes[start..], &mut io);
        io.finish();
        assert!(
            io.lines.is_empty(),
            "reply without a request: {:?}",
            io.lines
        );
        assert!(io.moves.is_empty());
        out
    }

    /// Feeds one request line with a terminator; returns its answer.
    pub fn line(&mut self, line: &str, crlf: bool) -> Answer {
        let term = if crlf { "\r\n" } else { "\n" };
        let mut a = self.feed(format!("{line}{term}").as_bytes());
        assert_eq!(a.len(), 1, "{line:?} is not one request");
        a.remove(0)
    }

    /// Feeds bytes that complete exactly the request `framed` and checks the
    /// protocol's promises for it:
    /// - exactly one final line, last, after zero or more `DATA` lines;
    /// - a line with a wrong `*HH` or CRC word gets a bare `ERR CHECKSUM`;
    ///   otherwise replies carry the request's `@id` and, when it had a CRC
    ///   word, a correct CRC word of their own;
    /// - the same id again repeats the remembered final line and runs
    ///   nothing; an id needs a CRC word; a numbered request before a session
    ///   token is set gets `ERR SESSION`;
    /// - an `ERR` carries a known code, comes alone, moves nothing and changes
    ///   no state (`POS`, `CFG`, `DRIVE`, `SESSION` and the session as
    ///   before);
    /// - an `OK` with `NX NZ PX PZ SEQ` agrees with the motion handed to the
    ///   drive and with the registers; chords of `ARC` are numbered and add
    ///   up;
    /// - afterwards the registers hold `Q(P/h)` of the commanded point.
    pub fn request(&mut self, bytes: &[u8], framed: &Framed) -> Answer {
        let before = self.dev.clone();
        let snap = || snapshot(before.session());
        let start = before.session().position();
        let mut io = Collect::default();
        self.dev.receive_bytes(bytes, &mut io);
        io.finish();
        let shown = String::from_utf8_lossy(bytes);
        let finals = io.lines.iter().filter(|l| is_final(l)).count();
        assert_eq!(finals, 1, "{shown:?} -> {:?}", io.lines);
        assert!(
            is_final(io.lines.last().unwrap()),
            "{shown:?} -> {:?}",
            io.lines
        );

        // The integrity layer, and what it predicts.
        let verdict = match framed {
            Framed::TooLong => None,
            Framed::Line(l) => Some(link(l)),
        };
        let (id, crc) = match &verdict {
            Some(Link::Pass { id, crc, .. }) => (
                match id {
                    IdWord::Id(n) => Some(*n),
                    _ => None,
                },
                *crc,
            ),
            _ => (None, false),
        };
        // A numbered request without a CRC word is refused before the id is
        // taken: its replies carry neither.
        let suffix_id = if crc { id } else { None };
        let lines: Vec<String> = io
            .lines
            .iter()
            .map(|l| strip_suffix(l, suffix_id, crc))
            .collect();
        let last = lines.last().unwrap().clone();
        for l in &lines[..lines.len() - 1] {
            assert!(l.starts_with("DATA "), "{shown:?} -> {:?}", io.lines);
        }
        let mut replay = false;
        match &verdict {
            None => assert!(last.starts_with("ERR LINE_TOO_LONG "), "{last:?}"),
            Some(Link::Corrupt) => {
                assert!(last.starts_with("ERR CHECKSUM "), "{shown:?} -> {last:?}");
                assert_eq!(io.lines.len(), 1);
            }
            Some(Link::Pass { body, id, crc }) => match id {
                IdWord::Invalid => {
                    assert!(last.starts_with("ERR VALUE @"), "{shown:?} -> {last:?}")
                }
                IdWord::Id(_) if !crc => {
                    assert!(last.starts_with("ERR SYNTAX "), "{shown:?} -> {last:?}")
                }
                IdWord::Id(n) => {
                    if let Some((prev, reply)) = self.last.as_ref().filter(|(p, _)| p == n) {
                        // A retry: the remembered final line, nothing runs.
                        let _ = prev;
                        assert_eq!(lines.len(), 1, "{shown:?} -> {:?}", io.lines);
                        assert_eq!(last, *reply, "replay of @{n}");
                        assert!(io.moves.is_empty(), "replay of @{n} moved");
                        assert_eq!(
                            snap(),
                            snapshot(self.dev.session()),
                            "replay of @{n} changed state"
                        );
                        replay = true;
                    } else {
                        let first = body
                            .split(|&b| b == b' ' || b == b'\t')
                            .find(|w| !w.is_empty())
                            .unwrap_or(b"");
                        let no_token = snap()[3] == "OK TOKEN=0";
                        if no_token && !first.eq_ignore_ascii_case(b"SESSION") {
                            // Refused before it runs, and not remembered.
                            assert!(last.starts_with("ERR SESSION "), "{shown:?} -> {last:?}");
                        } else {
                            self.last = Some((*n, last.clone()));
                        }
                    }
                }
                IdWord::Absent => {}
            },
        }

        if let Some(rest) = last.strip_prefix("ERR ") {
            let code = rest.split(' ').next().unwrap_or("");
            assert!(ERROR_CODES.contains(&code), "unknown code in {last:?}");
            assert!(rest.len() > code.len() + 1, "ERR without text: {last:?}");
            assert_eq!(
                lines.len(),
                1,
                "DATA before ERR: {shown:?} -> {:?}",
                io.lines
            );
            assert!(
                io.moves.is_empty(),
                "refused request moved: {shown:?} -> {last:?}"
            );
            // A refused block of a turning cycle's profile drops the cycle
            // whole (docs/cycles.md section 2): the cycle's state is the one
            // thing it changes.
            let without_cycle = |mut s: [String; 5]| {
                if before.session().reading_profile() {
                    if let Some(at) = s[4].find(", cycles: Cycles {") {
                        s[4].truncate(at);
                    }
                }
                s
            };
            assert_eq!(
                without_cycle(snap()),
                without_cycle(snapshot(self.dev.session())),
                "refused request changed state: {shown:?} -> {last:?}"
            );
        } else if !replay {
            let at = self.dev.session().position();
            if let (Some(px), Some(pz)) = (int(&last, "PX"), int(&last, "PZ")) {
                assert_eq!(
                    (px, pz),
                    (i64::from(at.x.get()), i64::from(at.z.get())),
                    "{last:?}"
                );
            }
            if let (Some(nx), Some(nz)) = (int(&last, "NX"), int(&last, "NZ")) {
                let sum = io.moves.iter().fold((0i64, 0i64), |a, m| {
                    (a.0 + i64::from(m.0), a.1 + i64::from(m.1))
                });
                assert_eq!((nx, nz), sum, "{last:?} vs motion {:?}", io.moves);
                assert_eq!(
                    (nx, nz),
                    (
                        i64::from(at.x.get()) - i64::from(start.x.get()),
                        i64::from(at.z.get()) - i64::from(start.z.get())
                    ),
                    "{last:?} vs registers"
                );
            } else {
                assert!(io.moves.is_empty(), "motion without NX/NZ: {last:?}");
            }
            if let Some(seq) = value(&last, "SEQ").filter(|_| !io.over_budget) {
                assert_eq!(seq, format!("{:08X}", io.crc.finish()), "{last:?}");
            }
            if let Some(n) = int(&last, "N") {
                if value(&last, "DPHI").is_some() {
                    // Arc by chords: one DATA line per chord, numbered from
                    // 1; every chord with impulses is a block of motion (a
                    // chord without any is one only if it has a length).
                    assert_eq!(lines.len(), n as usize + 1, "{last:?}");
                    assert!(io.moves.len() <= n as usize, "{last:?}");
                    let mut moves = io.moves.iter().filter(|m| **m != (0, 0));
                    for (k, l) in lines.iter().take(n as usize).enumerate() {
                        let chord = l
                            .strip_prefix(&format!("DATA I={} ", k + 1))
                            .unwrap_or_else(|| panic!("chord line {l:?}"));
                        if chord != "NX=0 NZ=0" {
                            let m = moves.next().unwrap_or_else(|| panic!("{l:?} did not move"));
                            assert_eq!(chord, format!("NX={} NZ={}", m.0, m.1), "chord line");
                        }
                    }
                    assert!(moves.next().is_none(), "moves beyond the chord lines");
                }
            }
        }
        check_position(self.dev.session());
        Answer {
            lines,
            moves: io.moves,
            replay,
            skipped: false,
        }
    }
}

/// Runs request lines (terminator added) on a device, asserting they are
/// accepted: a prelude that puts a device in a known state.
pub fn device_after(lines: &[&str]) -> Device {
    let mut c = Checker::new(fuzz_device());
    for l in lines {
        let a = c.line(l, true);
        assert!(a.err().is_none(), "{l} -> {:?}", a.lines);
    }
    c.dev
}

// ---------------------------------------------------------------------------
// G-code blocks
// ---------------------------------------------------------------------------

/// A G-code block as the reference reading gives it: lengths in ångström.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RefBlock {
    /// 0 words, 1 the tape mark `%`, 2 a program number.
    pub kind: u8,
    /// The line began with `/`.
    pub deleted: bool,
    /// G00–G03.
    pub motion: Option<u8>,
    /// G40–G42.
    pub compensation: Option<u8>,
    /// G90 / G91.
    pub distance: Option<u8>,
    /// G18.
    pub plane: Option<u8>,
    /// G20 / G21.
    pub units: Option<u8>,
    /// G450 / G451.
    pub corner: Option<u16>,
    /// X, Z, I, K, R words.
    pub xzikr: [Option<i64>; 5],
    /// The F word (mm/min as a length, Å).
    pub f: Option<i64>,
    /// G7 / G8.
    pub diameter: Option<u8>,
    /// G90.1 / G91.1, in tenths.
    pub arc_distance: Option<u16>,
    /// G94 / G95.
    pub feed_mode: Option<u8>,
    /// G96 / G97.
    pub spindle_mode: Option<u8>,
    /// G4: the dwell's P in whole microseconds.
    pub dwell_us: Option<u64>,
    /// S, the number ×10⁷.
    pub s: Option<i64>,
    /// D with G96, the number ×10⁷.
    pub clamp: Option<i64>,
    /// T, the tool number.
    pub tool: Option<u8>,
    /// M codes by group: stop (0, 1, 30 for M2 and M30), spindle (3–5),
    /// coolant (7–9).
    pub m: [Option<u8>; 3],
    /// Fanuc: X came from a `U`, Z from a `W` (increments).
    pub from_u_w: [bool; 2],
    /// Fanuc: the offset register of the T word.
    pub offset: Option<u8>,
    /// G54 … G59 as 0 … 5.
    pub wcs: Option<u8>,
    /// G10 L2/L20 P: the register and whether L20; (ISO) G10 L1/L10 P: 100
    /// + the tool's register and whether L10.
    pub set_work: Option<(u8, bool)>,
    /// ISO G43 (true, with its H) / G49 (false).
    pub tool_offset: Option<(bool, Option<u8>)>,
    /// ISO M6.
    pub tool_change: bool,
    /// The group-0 codes that move in machine coordinates or shift the
    /// work coordinates, in tenths: G28, G30 (with their way point), G28.1,
    /// G30.1 (store), G53, G92 (Fanuc G50 X Z), G92.1, G92.2, G92.3.
    pub special: Option<u16>,
    /// G45–G48 (+1, −1, +2, −2) and D, the offset register.
    pub position_offset: Option<(i8, u8)>,
    /// ISO's G41/G42 D: the tool whose nose compensates.
    pub nose_tool: Option<u8>,
}

/// Why the reference reading refuses a block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefBlockError {
    /// Unknown address letter.
    UnknownAddress(u8),
    /// Address (or G group) given twice.
    Repeated(u8),
    /// Not a letter-number word.
    NotAWord,
    /// `(` without `)`.
    Comment,
    /// Bad number at an address.
    Value(u8, LengthRefusal),
    /// A G code the control does not run.
    UnsupportedG,
    /// An M code the control does not run.
    UnsupportedM,
    /// G70–G76.
    Cycle,
    /// A word of the Fanuc dialect.
    OtherDialect,
    /// Words that do not go together, or a missing dwell time.
    Form,
    /// A number without a unit (S, D, P, T) outside its range, or no
    /// number.
    Range(u8),
    /// `Y` other than zero.
    NoYAxis,
    /// A program number with other words, or an `O` word elsewhere.
    ProgramNumber,
    /// `o<name>` followed by a word.
    HostLanguage,
}

/// A G-code number of inches (the grammar of [`parse_gcode_mm`]), as
/// ångström at 254 000 000 an inch, rounded half away from zero, magnitude
/// at most 99 999.999999 mm after rounding.
pub fn parse_gcode_inch(text: &str) -> Result<i64, LengthRefusal> {
    // Read as if millimetres for the grammar and the decimals; the value
    // is then recomputed from the digits.
    let (negative, body) = match text.as_bytes().first() {
        Some(b'-') => (true, &text[1..]),
        Some(b'+') => (false, &text[1..]),
        _ => (false, text),
    };
    parse_gcode_mm(text)?;
    let (int, frac) = body.split_once('.').unwrap_or((body, ""));
    let frac = &frac[..frac.len().min(30)];
    let digits: i128 = format!("{int}{frac}0").parse::<i128>().unwrap() / 10;
    // inches · 254·10⁶ Å: digits·254 / 10^(d−6), or ·10^(6−d).
    let d = frac.len() as u32;
    let (num, den) = if d >= 6 {
        (digits * 254, 10i128.pow(d - 6))
    } else {
        (digits * 254 * 10i128.pow(6 - d), 1)
    };
    let a = num / den + i128::from(2 * (num % den) >= den);
    if a > 999_999_999_990 {
        return Err(LengthRefusal::OutOfRange);
    }
    Ok(if negative { -(a as i64) } else { a as i64 })
}

/// The unit a line's own `G20`/`G21` sets (true: inch): the first such
/// word outside comments, before any `;`.
/// The line's first `G20`/`G21` (true for inches), whether it holds a
/// `G4`, and whether a `G45`–`G48`, outside comments and before `;`.
fn reference_scan(line: &str) -> (Option<bool>, bool, bool) {
    let mut units = None;
    let mut dwell = false;
    let mut g45 = false;
    let mut in_comment = false;
    let chars: Vec<char> = line.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        i += 1;
        if in_comment {
            in_comment = c != ')';
            continue;
        }
        match c {
            '(' => in_comment = true,
            ';' => break,
            'G' | 'g' => {
                let mut number = String::new();
                while i < chars.len() && matches!(chars[i], ' ' | '\t') {
                    i += 1;
                }
                while i < chars.len() && (chars[i].is_ascii_digit() || "+-.".contains(chars[i])) {
                    number.push(chars[i]);
                    i += 1;
                }
                let (whole, tenth) = number.split_once('.').unwrap_or((&number, "0"));
                let ok = !whole.is_empty()
                    && whole.len() <= 3
                    && whole.bytes().all(|d| d.is_ascii_digit())
                    && tenth == "0";
                if ok && number.matches('.').count() <= 1 {
                    match whole.parse::<u16>() {
                        Ok(20) if units.is_none() => units = Some(true),
                        Ok(21) if units.is_none() => units = Some(false),
                        Ok(4) => dwell = true,
                        Ok(45..=48) => g45 = true,
                        _ => {}
                    }
                }
            }
            _ => {}
        }
    }
    (units, dwell, g45)
}

/// A G-code number of millimetres: `[+-]` then `d+`, `d+.`, `d+.d+` or
/// `.d+`, read to the 30th decimal, as ångström rounded half away from zero,
/// magnitude at most 99 999.999999 mm after rounding.
pub fn parse_gcode_mm(text: &str) -> Result<i64, LengthRefusal> {
    parse_gcode_scaled(text, 7)
}

/// A G-code number (the grammar of [`parse_gcode_mm`]) times 10^e, rounded
/// half away from zero; at most 5 integer digits, and after rounding at
/// most 99 999.999999 on the scale 10^e (999 999 999 990 for e = 7).
pub fn parse_gcode_scaled(text: &str, e: u32) -> Result<i64, LengthRefusal> {
    let (negative, body) = match text.as_bytes().first() {
        Some(b'-') => (true, &text[1..]),
        Some(b'+') => (false, &text[1..]),
        _ => (false, text),
    };
    let (int, frac) = body.split_once('.').unwrap_or((body, ""));
    let all_digits = |s: &str| s.chars().all(|c| c.is_ascii_digit());
    if (int.is_empty() && frac.is_empty()) || !all_digits(int) || !all_digits(frac) {
        return Err(LengthRefusal::Malformed);
    }
    // Read to the 30th decimal; later digits are left out.
    let frac = &frac[..frac.len().min(30)];
    let int = int.trim_start_matches('0');
    if int.len() > 5 {
        return Err(LengthRefusal::OutOfRange);
    }
    // value = digits / 10^decimals mm; in ångström ×10^e, as a fraction
    // num/den (the power of ten on one side only: within i128).
    let digits: i128 = format!("{int}{frac}0").parse::<i128>().unwrap() / 10;
    let d = frac.len() as u32;
    let (num, den) = if d >= e {
        (digits, 10i128.pow(d - e))
    } else {
        (digits * 10i128.pow(e - d), 1)
    };
    let (q, r) = (num / den, num % den);
    let a = if 2 * r >= den { q + 1 } else { q };
    // 99 999.999999 · 10^e, rounded down.
    if a * 1_000_000 > 99_999_999_999 * 10i128.pow(e) {
        return Err(LengthRefusal::OutOfRange);
    }
    Ok(if negative { -(a as i64) } else { a as i64 })
}

/// Reads a block per the `gcode` module docs: an optional line head (`%`,
/// `/`, a program number `O123`, `O<name>`, `:123`), then address words (a
/// letter and the run of `0-9 + - .` after it, spaces and tabs between the
/// two allowed), spaces and tabs between words optional, `( … )` comments, `;` ends the block; `N F X Y Z I K R`
/// once each with numbers that must be G-code lengths, `Y` zero; `S`, `D`
/// (only with G96) and `P` (only with G4, seconds) numbers of at least 0;
/// `T` a tool of at most two digits; `G` once per group (00–03, 18, 20–21,
/// 40–42, 90–91, 90.1–91.1, 7–8, 94–95, 96–97, 450–451; G4 a dwell that
/// needs P and takes no X Z I K R; G70–G76 cycles; G50, G98, G99 the Fanuc
/// dialect's), `M` once per group (2 30; 3 4 5; 7 8 9), codes of 1–3
/// digits and at most one decimal; `U`, `W` the Fanuc dialect's; a `G20`
/// anywhere in the line reads its lengths in inches.
pub fn reference_block(line: &str) -> Result<RefBlock, RefBlockError> {
    reference_block_in(line, false, false)
}

/// [`reference_block`] in the ISO dialect, or in the Fanuc dialect
/// (`docs/protocol.md`, Dialects): `U`/`W` increments (not with `X`/`Z`),
/// `G98`/`G99` feed modes, `G50` with `S` alone (the limit), `G04` with one
/// of `P` (ms), `X`, `U` (s), `T` of up to four digits (`T0101`: tool 01,
/// register 01; one or two digits: both the number), `G90`/`G92`/`G94`
/// cycles; `G7`, `G8`, `G91`, `G95`, `G90.1`, `G91.1` and `D` ISO's.
/// Lengths in inches when the line says `G20`, or says neither `G20` nor
/// `G21` and `modal_inch`.
pub fn reference_block_in(
    line: &str,
    fanuc: bool,
    modal_inch: bool,
) -> Result<RefBlock, RefBlockError> {
    let mut b = RefBlock::default();
    let mut seen = [false; 26];
    let (units, dwell, g45_line) = reference_scan(line);
    let mut g45 = None::<i8>;
    let inch = units.unwrap_or(modal_inch);
    // G4 given, its time (µs), and D (×10⁷), for the checks at the end.
    let mut g4 = false;
    let mut g50 = false;
    let mut g10 = false;
    // P (not a time), L, H: whole numbers.
    let (mut p, mut l, mut h) = (None::<u32>, None::<u32>, None::<u32>);
    let mut time: Option<u64> = None;
    let mut d: Option<i64> = None;
    let head = line.len() - line.trim_start_matches([' ', '\t']).len();
    let mut rest = &line[head..];
    let mut angle = false;
    if let Some(r) = rest.strip_prefix('%') {
        b.kind = 1;
        rest = r;
    } else if let Some(r) = rest.strip_prefix('/') {
        b.deleted = true;
        rest = r;
    } else if let Some(r) = rest.strip_prefix(':') {
        let n = r.chars().take_while(char::is_ascii_digit).count();
        if n == 0 {
            return Err(RefBlockError::NotAWord);
        }
        b.kind = 2;
        rest = &r[n..];
    } else if rest.starts_with("O<") || rest.starts_with("o<") {
        let Some((name, r)) = rest[2..].split_once('>') else {
            return Err(RefBlockError::NotAWord);
        };
        let ok = |c: char| c.is_ascii_alphanumeric() || "_.-".contains(c);
        if name.is_empty() || !name.chars().all(ok) {
            return Err(RefBlockError::NotAWord);
        }
        b.kind = 2;
        angle = true;
        rest = r;
    } else if (rest.starts_with('O') || rest.starts_with('o'))
        && rest[1..].starts_with(|c: char| c.is_ascii_digit())
    {
        let n = rest[1..].chars().take_while(char::is_ascii_digit).count();
        b.kind = 2;
        rest = &rest[1 + n..];
    }
    let mut chars = rest.char_indices().peekable();
    while let Some((at, c)) = chars.next() {
        match c {
            ' ' | '\t' => {}
            ';' => break,
            '(' => loop {
                match chars.next() {
                    Some((_, ')')) => break,
                    Some(_) => {}
                    None => return Err(RefBlockError::Comment),
                }
            },
            c if b.kind == 2 => {
                return Err(if angle && c.is_ascii_alphabetic() {
                    RefBlockError::HostLanguage
                } else {
                    RefBlockError::ProgramNumber
                })
            }
            _ if b.kind == 1 => return Err(RefBlockError::NotAWord),
            c if c.is_ascii_alphabetic() => {
                let letter = c.to_ascii_uppercase() as u8;
                // Spaces and tabs may stand between the letter and its
                // number.
                let mut from = at + 1;
                while let Some(&(i, ' ' | '\t')) = chars.peek() {
                    from = i + 1;
                    chars.next();
                }
                let mut end = from;
                while let Some(&(i, d)) = chars.peek() {
                    if d.is_ascii_digit() || matches!(d, '+' | '-' | '.') {
                        end = i + 1;
                        chars.next();
                    } else {
                        break;
                    }
                }
                let number = &rest[from..end];
                if number.is_empty() {
                    return Err(RefBlockError::NotAWord);
                }
                if letter == b'G' || letter == b'M' {
                    let (whole, tenth) = number.split_once('.').unwrap_or((number, ""));
                    let digits = |s: &str| !s.is_empty() && s.bytes().all(|d| d.is_ascii_digit());
                    let not_code = if letter == b'G' {
                        RefBlockError::UnsupportedG
                    } else {
                        RefBlockError::UnsupportedM
                    };
                    if !digits(whole)
                        || whole.len() > 3
                        || (number.contains('.') && (tenth.len() != 1 || !digits(tenth)))
                    {
                        return Err(not_code);
                    }
                    let code: u16 = whole.parse().map_err(|_| not_code)?;
                    let tenth: u16 = tenth.parse().unwrap_or(0);
                    if letter == b'M' {
                        let (group, value) = match (code, tenth) {
                            // M02 and M30 both end the program.
                            (2 | 30, 0) => (0, 30),
                            (0 | 1, 0) => (0, code as u8),
                            (3..=5, 0) => (1, code as u8),
                            (7..=9, 0) => (2, code as u8),
                            (6, 0) if fanuc => return Err(RefBlockError::OtherDialect),
                            (6, 0) => {
                                if b.tool_change {
                                    return Err(RefBlockError::Repeated(b'M'));
                                }
                                b.tool_change = true;
                                continue;
                            }
                            _ => return Err(RefBlockError::UnsupportedM),
                        };
                        if b.m[group].is_some() {
                            return Err(RefBlockError::Repeated(b'M'));
                        }
                        b.m[group] = Some(value);
                        continue;
                    }
                    fn put<T>(slot: &mut Option<T>, v: T) -> Result<(), RefBlockError> {
                        if slot.is_some() {
                            return Err(RefBlockError::Repeated(b'G'));
                        }
                        *slot = Some(v);
                        Ok(())
                    }
                    let group0 = g4 || g50 || g10 || b.special.is_some() || g45.is_some();
                    match (code, tenth) {
                        (28 | 30, 1) | (92, 1..=3) if fanuc => {
                            return Err(RefBlockError::OtherDialect)
                        }
                        (28 | 30, 1) | (92, 1..=3) => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            b.special = Some(code * 10 + tenth);
                        }
                        (90 | 91, 1) if fanuc => return Err(RefBlockError::OtherDialect),
                        (90 | 91, 1) => put(&mut b.arc_distance, code * 10 + 1)?,
                        // Probing (ISO; docs/inputs.md §10).
                        (38, 2..=5) if fanuc => return Err(RefBlockError::OtherDialect),
                        (38, 2..=5) => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            b.special = Some(code * 10 + tenth);
                        }
                        (_, 1..) => return Err(RefBlockError::UnsupportedG),
                        (50, _) if fanuc => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            g50 = true;
                        }
                        (10, _) => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            g10 = true;
                        }
                        (28 | 30 | 53, _) => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            b.special = Some(code * 10);
                        }
                        (45..=48, _) => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            g45 = Some(match code {
                                45 => 1,
                                46 => -1,
                                47 => 2,
                                _ => -2,
                            });
                        }
                        (54..=59, _) => put(&mut b.wcs, code as u8 - 54)?,
                        (43 | 49, _) if fanuc => return Err(RefBlockError::OtherDialect),
                        (43 | 49, _) => put(&mut b.tool_offset, (code == 43, None))?,
                        (98 | 99, _) if fanuc => put(&mut b.feed_mode, code as u8 - 4)?,
                        (90 | 92 | 94, _) if fanuc => return Err(RefBlockError::Cycle),
                        (92, _) => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            b.special = Some(920);
                        }
                        (7 | 8 | 91 | 95, _) if fanuc => return Err(RefBlockError::OtherDialect),
                        (450 | 451, _) => put(&mut b.corner, code)?,
                        (0..=3, _) => put(&mut b.motion, code as u8)?,
                        (18, _) => put(&mut b.plane, 18)?,
                        (20 | 21, _) => put(&mut b.units, code as u8)?,
                        (40..=42, _) => put(&mut b.compensation, code as u8)?,
                        (90 | 91, _) => put(&mut b.distance, code as u8)?,
                        (7 | 8, _) => put(&mut b.diameter, code as u8)?,
                        (94 | 95, _) => put(&mut b.feed_mode, code as u8)?,
                        (96 | 97, _) => put(&mut b.spindle_mode, code as u8)?,
                        (4, _) => {
                            if group0 {
                                return Err(RefBlockError::Repeated(b'G'));
                            }
                            g4 = true;
                        }
                        (70..=76, _) => return Err(RefBlockError::Cycle),
                        (50 | 98 | 99, _) => return Err(RefBlockError::OtherDialect),
                        _ => return Err(RefBlockError::UnsupportedG),
                    }
                    continue;
                }
                let idx = usize::from(letter - b'A');
                if seen[idx] {
                    return Err(RefBlockError::Repeated(letter));
                }
                seen[idx] = true;
                let value =
                    |v: Result<i64, LengthRefusal>| v.map_err(|e| RefBlockError::Value(letter, e));
                let length = || {
                    value(if inch {
                        parse_gcode_inch(number)
                    } else {
                        parse_gcode_mm(number)
                    })
                };
                // Numbers without a unit are 0 … 99 999.999999.
                let unitless = |e: u32| match parse_gcode_scaled(number, e) {
                    Ok(v) if v >= 0 => Ok(v),
                    Ok(_) | Err(LengthRefusal::OutOfRange | LengthRefusal::Malformed) => {
                        Err(RefBlockError::Range(letter))
                    }
                    Err(e) => Err(RefBlockError::Value(letter, e)),
                };
                match letter {
                    // The Fanuc dwell's X and U are seconds.
                    b'X' | b'U' if fanuc && dwell => {
                        if time.is_some() {
                            return Err(RefBlockError::Form);
                        }
                        time = Some(unitless(6)? as u64);
                    }
                    b'X' | b'U' | b'Z' | b'W' if fanuc => {
                        let axis = usize::from(matches!(letter, b'Z' | b'W'));
                        if b.xzikr[axis].is_some() {
                            return Err(RefBlockError::Form);
                        }
                        b.xzikr[axis] = Some(length()?);
                        b.from_u_w[axis] = matches!(letter, b'U' | b'W');
                    }
                    b'X' => b.xzikr[0] = Some(length()?),
                    b'Z' => b.xzikr[1] = Some(length()?),
                    b'I' => b.xzikr[2] = Some(length()?),
                    b'K' => b.xzikr[3] = Some(length()?),
                    b'R' => b.xzikr[4] = Some(length()?),
                    b'F' => b.f = Some(length()?),
                    b'Y' => {
                        length()?;
                        if number.contains(|c: char| ('1'..='9').contains(&c)) {
                            return Err(RefBlockError::NoYAxis);
                        }
                    }
                    b'N' => {
                        value(parse_gcode_mm(number))?;
                    }
                    b'S' => b.s = Some(unitless(7)?),
                    b'D' if !fanuc || g45_line => d = Some(unitless(7)?),
                    b'P' if dwell => {
                        if time.is_some() {
                            return Err(RefBlockError::Form);
                        }
                        // Seconds (Fanuc: milliseconds), as microseconds.
                        time = Some(unitless(if fanuc { 3 } else { 6 })? as u64);
                    }
                    b'P' | b'L' | b'H' if !(fanuc && letter == b'H') => {
                        let n = number.trim_start_matches('0');
                        if !number.bytes().all(|c| c.is_ascii_digit()) || n.len() > 4 {
                            return Err(RefBlockError::Range(letter));
                        }
                        let v = Some(n.parse().unwrap_or(0));
                        match letter {
                            b'P' => p = v,
                            b'L' => l = v,
                            _ => h = v,
                        }
                    }
                    b'T' if fanuc => {
                        let n = number.trim_start_matches('0');
                        if !number.bytes().all(|c| c.is_ascii_digit()) || n.len() > 4 {
                            return Err(RefBlockError::Range(b'T'));
                        }
                        let v: u16 = n.parse().unwrap_or(0);
                        let (tool, reg) = if number.len() <= 2 {
                            (v, v)
                        } else {
                            (v / 100, v % 100)
                        };
                        b.tool = Some(tool as u8);
                        b.offset = Some(reg as u8);
                    }
                    b'T' => {
                        let n = number.trim_start_matches('0');
                        if !number.bytes().all(|c| c.is_ascii_digit()) || n.len() > 2 {
                            return Err(RefBlockError::Range(b'T'));
                        }
                        b.tool = Some(n.parse().unwrap_or(0));
                    }
                    b'U' | b'W' => return Err(RefBlockError::OtherDialect),
                    b'O' => return Err(RefBlockError::ProgramNumber),
                    _ => return Err(RefBlockError::UnknownAddress(letter)),
                }
            }
            _ => return Err(RefBlockError::NotAWord),
        }
    }
    let motion_words = b.xzikr.iter().any(Option::is_some);
    if g4 {
        let Some(us) = time else {
            return Err(RefBlockError::Form);
        };
        if motion_words {
            return Err(RefBlockError::Form);
        }
        b.dwell_us = Some(us);
    }
    if g10 {
        // ISO's L1/L10: a tool's register, 1 … 32.
        let tool = !fanuc && matches!(l, Some(1 | 10));
        if !matches!(l, Some(2 | 20)) && !tool {
            return Err(RefBlockError::Form);
        }
        match p {
            Some(r @ 1..=32) if tool => b.set_work = Some((100 + r as u8, l == Some(10))),
            Some(_) if tool => return Err(RefBlockError::Range(b'P')),
            Some(r @ 1..=6) => b.set_work = Some((r as u8, l == Some(20))),
            // ISO: P0, the system in effect (docs/protocol.md §5.2); in
            // Fanuc the external offset, which the control has not.
            Some(0) if !fanuc => b.set_work = Some((0, l == Some(20))),
            Some(_) => return Err(RefBlockError::Range(b'P')),
            None => return Err(RefBlockError::Form),
        }
        if b.xzikr[2..].iter().any(Option::is_some) || b.from_u_w.contains(&true) {
            return Err(RefBlockError::Form);
        }
        (p, l) = (None, None);
    }
    let ikr = b.xzikr[2..].iter().any(Option::is_some);
    let axes = b.xzikr[0].is_some() || b.xzikr[1].is_some();
    let u_w = b.from_u_w.contains(&true);
    if let Some(times) = g45 {
        // G45–G48: a line move and the register D, 1 … 32.
        if ikr || !axes {
            return Err(RefBlockError::Form);
        }
        match d.take() {
            Some(v) if v % 10_000_000 == 0 && (1..=32).contains(&(v / 10_000_000)) => {
                b.position_offset = Some((times, (v / 10_000_000) as u8));
            }
            _ => return Err(RefBlockError::Form),
        }
    }
    match b.special {
        // G28, G30: X Z (U W) a way point, nothing else.
        Some(280 | 300) if ikr => return Err(RefBlockError::Form),
        Some(281 | 301 | 921 | 922 | 923) if motion_words => return Err(RefBlockError::Form),
        Some(530 | 920) if ikr || u_w => return Err(RefBlockError::Form),
        Some(920) if !axes => return Err(RefBlockError::Form),
        // G38.2–G38.5: a line to X/Z of its own, no motion code.
        Some(382..=385) if ikr || !axes || b.motion.is_some() => return Err(RefBlockError::Form),
        _ => {}
    }
    if g50 {
        // Fanuc: X Z set the coordinates here, S the spindle limit.
        if ikr || u_w || (!axes && b.s.is_none()) {
            return Err(RefBlockError::Form);
        }
        if axes {
            b.special = Some(920);
        }
        b.clamp = b.s.take();
    }
    if p.is_some() || l.is_some() {
        return Err(RefBlockError::Form);
    }
    match (h, b.tool_offset) {
        (Some(h), Some((true, _))) => b.tool_offset = Some((true, Some(h.min(255) as u8))),
        (Some(_), _) => return Err(RefBlockError::Form),
        _ => {}
    }
    if let Some(d) = d {
        // ISO's G41/G42 D: a tool number, 0 … 32; with G96 as well, D is
        // refused (which of the two it is would be a guess).
        let nose = matches!(b.compensation, Some(41 | 42)) && !fanuc;
        let surface = b.spindle_mode == Some(96);
        match (nose, surface) {
            (true, false) if d % 10_000_000 == 0 && d / 10_000_000 <= 32 => {
                b.nose_tool = Some((d / 10_000_000) as u8);
            }
            (true, false) => return Err(RefBlockError::Range(b'D')),
            (false, true) => b.clamp = Some(d),
            _ => return Err(RefBlockError::Form),
        }
    }
    Ok(b)
}

/// Whether a request line is a G-code block: its first word is an address
/// letter followed (spaces and tabs between allowed) by a digit, sign or
/// point.
pub fn reference_is_block(line: &str) -> bool {
    let t = line.trim_start_matches([' ', '\t']);
    let mut c = t.chars();
    match (c.next(), c.next()) {
        (Some('%' | '/' | '(' | ';' | ':'), _) => true,
        (Some('O' | 'o'), Some('<')) => true,
        (Some(l), Some(_)) if l.is_ascii_alphabetic() => {
            // Spaces and tabs may stand between the letter and its number.
            let after = &t[1..];
            let d = after.trim_start_matches([' ', '\t']).chars().next();
            d.is_some_and(|d| d.is_ascii_digit() || matches!(d, '+' | '-' | '.'))
        }
        _ => false,
    }
}

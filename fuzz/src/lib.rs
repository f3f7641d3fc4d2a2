//! Independent oracles shared by the fuzz targets.
//!
//! Nothing here calls the core's own helpers for what it checks: reply lines,
//! request framing, decimal lengths, `Q` (half away from zero), the step
//! interleaving rule of a linear block and the CRC-32 behind `SEQ` are all
//! re-derived from `PROTOCOL.md` and the module docs, with exact integer
//! arithmetic.

use core_nostd::arc::DirectArc;
use core_nostd::interleave::LinearBlock;
use core_nostd::protocol::{Device, Io, Session};
use core_nostd::stepdir::DriveTiming;

/// The longest request line, terminator excluded (PROTOCOL.md, Framing).
pub const MAX_LINE: usize = 120;
/// The longest reply line, `*HH` and CRLF included.
pub const MAX_REPLY: usize = 160;
/// The largest coordinate magnitude in ångström: 99 999.999999 mm.
pub const LIMIT_ANGSTROM: i64 = 999_999_999_990;
/// The largest impulse register magnitude.
pub const MAX_POSITION: i64 = 999_999_999;
/// The largest number of impulses per axis in one linear block.
pub const MAX_BLOCK: i64 = 1_000_000;
/// The error codes of PROTOCOL.md.
pub const ERROR_CODES: [&str; 8] = [
    "CHECKSUM",
    "LINE_TOO_LONG",
    "EMPTY",
    "UNKNOWN",
    "SYNTAX",
    "VALUE",
    "RANGE",
    "GEOMETRY",
];

// ---------------------------------------------------------------------------
// Exact arithmetic and decimals
// ---------------------------------------------------------------------------

/// `n / d` rounded half away from zero, `d > 0`.
pub fn q(n: i128, d: i128) -> i128 {
    assert!(d > 0);
    let m = (2 * n.abs() + d) / (2 * d);
    if n < 0 {
        -m
    } else {
        m
    }
}

/// Why a decimal length is refused, in the order the checks apply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthRefusal {
    /// Not `[+-]digits[.digits]`.
    Malformed,
    /// More than 6 decimals.
    TooManyDecimals,
    /// Magnitude not below 100 000 mm.
    OutOfRange,
}

/// A decimal millimetre value `[+-]?[0-9]+(\.[0-9]{1,6})?` with magnitude
/// below 100 000 mm, as ångström.
pub fn parse_mm(text: &str) -> Result<i64, LengthRefusal> {
    let (negative, body) = if let Some(r) = text.strip_prefix('-') {
        (true, r)
    } else if let Some(r) = text.strip_prefix('+') {
        (false, r)
    } else {
        (false, text)
    };
    let (int, frac) = match body.split_once('.') {
        Some((i, f)) => (i, Some(f)),
        None => (body, None),
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(int) || frac.is_some_and(|f| !digits(f)) {
        return Err(LengthRefusal::Malformed);
    }
    let frac = frac.unwrap_or("");
    if frac.len() > 6 {
        return Err(LengthRefusal::TooManyDecimals);
    }
    let int = int.trim_start_matches('0');
    if int.len() > 5 {
        return Err(LengthRefusal::OutOfRange);
    }
    let mm: i64 = if int.is_empty() { 0 } else { int.parse().unwrap() };
    if mm >= 100_000 {
        return Err(LengthRefusal::OutOfRange);
    }
    let mut nm: i64 = 0;
    for i in 0..6 {
        nm = nm * 10 + frac.as_bytes().get(i).map_or(0, |d| i64::from(d - b'0'));
    }
    let a = (mm * 1_000_000 + nm) * 10;
    Ok(if negative { -a } else { a })
}

/// A count of 0.0001 mm as `[-]int.dddd`.
pub fn mm4(tenth_um: i128) -> String {
    let sign = if tenth_um < 0 { "-" } else { "" };
    let a = tenth_um.abs();
    format!("{sign}{}.{:04}", a / 10_000, a % 10_000)
}

/// Ångström printed as the reply format: 4 decimals, half away from zero.
pub fn mm4_of(angstrom: i128) -> String {
    mm4(q(angstrom, 1_000))
}

/// Ångström (a multiple of 10) as an exact decimal with up to 6 decimals.
pub fn exact_mm(angstrom: i64) -> String {
    assert_eq!(angstrom % 10, 0, "not a whole nanometre: {angstrom}");
    let nm = angstrom / 10;
    let sign = if nm < 0 { "-" } else { "" };
    let a = nm.unsigned_abs();
    let frac = format!("{:06}", a % 1_000_000);
    let frac = frac.trim_end_matches('0');
    if frac.is_empty() {
        format!("{sign}{}", a / 1_000_000)
    } else {
        format!("{sign}{}.{frac}", a / 1_000_000)
    }
}

/// The protocol checksum: XOR of all bytes.
pub fn xor(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |a, b| a ^ b)
}

/// A request body with its `*HH` appended.
pub fn with_checksum(body: &str) -> String {
    format!("{body}*{:02X}", xor(body.as_bytes()))
}

/// CRC-32 (IEEE, reflected, as in zlib), bit by bit.
#[derive(Clone, Copy, Debug)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Crc32(0xFFFF_FFFF)
    }
}

impl Crc32 {
    /// Adds one byte.
    pub fn push(&mut self, byte: u8) {
        let mut c = self.0 ^ u32::from(byte);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
        self.0 = c;
    }
    /// The finished CRC.
    pub fn finish(self) -> u32 {
        !self.0
    }
}

// ---------------------------------------------------------------------------
// Framing
// ---------------------------------------------------------------------------

/// The index of the byte that completes each request the framing sees:
/// a terminator (LF, CR; CRLF counts once) ends a request, and the 121st byte
/// of a line ends an over-long one (the rest up to its terminator is
/// discarded and is not a request).
pub fn request_ends(bytes: &[u8]) -> Vec<usize> {
    let mut ends = Vec::new();
    let mut run = 0usize;
    let mut over = false;
    let mut prev_cr = false;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' && prev_cr {
            // Second half of CRLF.
        } else if b == b'\r' || b == b'\n' {
            if !over {
                ends.push(i);
            }
            over = false;
            run = 0;
        } else if !over {
            run += 1;
            if run > MAX_LINE {
                ends.push(i);
                over = true;
            }
        }
        prev_cr = b == b'\r';
    }
    ends
}

// ---------------------------------------------------------------------------
// Replies and motion
// ---------------------------------------------------------------------------

/// Checks one reply line: ASCII, at most 160 bytes, `*HH` correct, CRLF.
/// Returns the body (before `*`).
pub fn check_reply_line(line: &[u8]) -> String {
    assert!(line.is_ascii(), "reply not ASCII: {line:?}");
    assert!(line.len() <= MAX_REPLY, "reply longer than {MAX_REPLY} bytes: {}", line.len());
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

/// Checks the step events of a linear block against SPEC §2: the leading axis
/// (larger |Δ|, X on a tie) steps in every event; after event `i` the other
/// axis stands at `Q(i·Δb/|Δlead|)`; a direction bit is set only with its
/// step, and only for a negative step. Adds the event bytes to `crc`.
pub fn check_linear_events(block: &LinearBlock, crc: &mut Crc32) {
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
    let lead_is_x = dx.unsigned_abs() >= dz.unsigned_abs();
    let (lead, other) = if lead_is_x { (dx, dz) } else { (dz, dx) };
    let l = i128::from(lead.unsigned_abs());
    let mut other_at: i128 = 0;
    let mut i: i128 = 0;
    for e in block.events() {
        let b = e.bits();
        i += 1;
        assert_eq!(b & 0xF0, 0, "event byte {b:#04x}");
        let (lead_step, lead_neg, other_step, other_neg) = if lead_is_x {
            (b & 1 != 0, b & 4 != 0, b & 2 != 0, b & 8 != 0)
        } else {
            (b & 2 != 0, b & 8 != 0, b & 1 != 0, b & 4 != 0)
        };
        assert!(lead_step, "event {i} of {dx},{dz}: leading axis does not step");
        assert_eq!(lead_neg, lead < 0, "event {i} of {dx},{dz}: lead direction");
        let want = q(i * i128::from(other), l);
        let moved = want - other_at;
        assert!(moved.abs() <= 1, "event {i} of {dx},{dz}: other axis jumps");
        assert_eq!(other_step, moved != 0, "event {i} of {dx},{dz}: other step");
        assert_eq!(other_neg, moved < 0, "event {i} of {dx},{dz}: other direction");
        other_at = want;
        crc.push(b);
    }
    assert_eq!(i, l, "events of block {dx},{dz}");
    assert_eq!(other_at, i128::from(other));
}

/// Checks the step events of a direct arc: each event steps at least one
/// axis, each axis at most once, a direction bit only with its step, and the
/// steps add up to the arc's increments. Adds the event bytes to `crc`.
pub fn check_direct_events(arc: &DirectArc, crc: &mut Crc32) {
    let (dx, dz) = arc.delta();
    assert!(i64::from(dx).abs() <= MAX_BLOCK && i64::from(dz).abs() <= MAX_BLOCK);
    let (mut sx, mut sz) = (0i64, 0i64);
    for e in arc.events() {
        let b = e.bits();
        assert_eq!(b & 0xF0, 0, "event byte {b:#04x}");
        assert!(b & 3 != 0, "direct arc event steps nothing");
        assert!(b & 4 == 0 || b & 1 != 0, "X direction bit without X step");
        assert!(b & 8 == 0 || b & 2 != 0, "Z direction bit without Z step");
        if b & 1 != 0 {
            sx += if b & 4 != 0 { -1 } else { 1 };
        }
        if b & 2 != 0 {
            sz += if b & 8 != 0 { -1 } else { 1 };
        }
        crc.push(b);
    }
    assert_eq!((sx, sz), (i64::from(dx), i64::from(dz)), "direct arc steps");
}

/// An [`Io`] that checks and collects reply lines, and checks the motion it
/// is handed.
#[derive(Default)]
pub struct Collect {
    /// Reply bodies (before `*HH`), in order.
    pub lines: Vec<String>,
    /// Increments of every block and direct arc handed to the drive.
    pub moves: Vec<(i32, i32)>,
    /// CRC-32 of every step event handed to the drive.
    pub crc: Crc32,
}

impl Io for Collect {
    fn send(&mut self, line: &[u8]) {
        self.lines.push(check_reply_line(line));
    }
    fn run_block(&mut self, block: &LinearBlock, _: &DriveTiming) {
        check_linear_events(block, &mut self.crc);
        self.moves.push(block.delta());
    }
    fn run_direct(&mut self, arc: &DirectArc, _: &DriveTiming) {
        check_direct_events(arc, &mut self.crc);
        self.moves.push(arc.delta());
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
/// `POS`, `CFG` and `DRIVE` replies of a copy, and the whole session state.
pub fn snapshot(s: &Session) -> [String; 4] {
    let ask = |req: &[u8]| {
        let mut copy = s.clone();
        let mut io = Collect::default();
        copy.handle_line(req, &mut io);
        assert_eq!(io.lines.len(), 1, "{:?} -> {:?}", req, io.lines);
        assert!(io.lines[0].starts_with("OK "), "{:?} -> {:?}", req, io.lines);
        io.lines.remove(0)
    };
    [ask(b"POS"), ask(b"CFG"), ask(b"DRIVE"), format!("{s:?}")]
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
    let want = format!(
        "OK PX={px} PZ={pz} X={} Z={}",
        mm4_of(i128::from(x) * factor),
        mm4_of(z.into())
    );
    assert_eq!(snapshot(s)[0], want, "POS");
}

/// The outcome of one request.
#[derive(Debug)]
pub struct Answer {
    /// Reply bodies, the final one last.
    pub lines: Vec<String>,
    /// Increments handed to the drive.
    pub moves: Vec<(i32, i32)>,
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

/// Feeds bytes that hold exactly one request (as [`request_ends`] frames
/// them) and checks the protocol's promises for it:
/// - exactly one final line, last, after zero or more `DATA` lines;
/// - an `ERR` carries a known code, comes alone, moves nothing and changes
///   no state (`POS`, `CFG`, `DRIVE` and the whole session as before);
/// - an `OK` with `NX NZ PX PZ SEQ` agrees with the motion handed to the
///   drive and with the registers; chords of `ARC` are numbered and add up;
/// - afterwards the registers hold `Q(P/h)` of the commanded point.
pub fn request(dev: &mut Device, bytes: &[u8]) -> Answer {
    let before = dev.clone();
    let start = before.session().position();
    let mut io = Collect::default();
    dev.receive_bytes(bytes, &mut io);
    let finals = io.lines.iter().filter(|l| is_final(l)).count();
    assert_eq!(finals, 1, "{bytes:?} -> {:?}", io.lines);
    let last = io.lines.last().unwrap().clone();
    assert!(is_final(&last), "{bytes:?} -> {:?}", io.lines);
    for l in &io.lines[..io.lines.len() - 1] {
        assert!(l.starts_with("DATA "), "{bytes:?} -> {:?}", io.lines);
    }
    if let Some(rest) = last.strip_prefix("ERR ") {
        let code = rest.split(' ').next().unwrap_or("");
        assert!(ERROR_CODES.contains(&code), "unknown code in {last:?}");
        assert!(
            rest.len() > code.len() + 1,
            "ERR without text: {last:?}"
        );
        assert_eq!(io.lines.len(), 1, "DATA before ERR: {bytes:?} -> {:?}", io.lines);
        assert!(io.moves.is_empty(), "refused request moved: {bytes:?} -> {last:?}");
        assert_eq!(
            snapshot(before.session()),
            snapshot(dev.session()),
            "refused request changed state: {:?} -> {last:?}",
            String::from_utf8_lossy(bytes)
        );
    } else {
        let at = dev.session().position();
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
        if let Some(seq) = value(&last, "SEQ") {
            assert_eq!(seq, format!("{:08X}", io.crc.finish()), "{last:?}");
        }
        if let Some(n) = int(&last, "N") {
            if value(&last, "DPHI").is_some() {
                // Arc by chords: one DATA line per chord, numbered from 1.
                assert_eq!(n as usize, io.moves.len(), "{last:?}");
                assert_eq!(io.lines.len(), io.moves.len() + 1);
                for (k, (l, m)) in io.lines.iter().zip(&io.moves).enumerate() {
                    assert_eq!(
                        *l,
                        format!("DATA I={} NX={} NZ={}", k + 1, m.0, m.1),
                        "chord line"
                    );
                }
            }
        }
    }
    check_position(dev.session());
    Answer {
        lines: io.lines,
        moves: io.moves,
    }
}

/// Feeds any bytes, request by request as [`request_ends`] frames them,
/// checking every request with [`request`]; trailing bytes without a
/// terminator must produce nothing.
pub fn session(dev: &mut Device, bytes: &[u8]) -> Vec<Answer> {
    let mut out = Vec::new();
    let mut start = 0;
    for end in request_ends(bytes) {
        out.push(request(dev, &bytes[start..=end]));
        start = end + 1;
    }
    let mut io = Collect::default();
    dev.receive_bytes(&bytes[start..], &mut io);
    assert!(io.lines.is_empty(), "reply without a request: {:?}", io.lines);
    assert!(io.moves.is_empty());
    out
}

/// Runs request lines (terminator added) on a device, asserting they are
/// accepted: a prelude that puts a device in a known state.
pub fn device_after(lines: &[&str]) -> Device {
    let mut dev = Device::new();
    for l in lines {
        let a = request(&mut dev, format!("{l}\r\n").as_bytes());
        assert!(a.err().is_none(), "{l} -> {:?}", a.lines);
    }
    dev
}

// ---------------------------------------------------------------------------
// G-code blocks
// ---------------------------------------------------------------------------

/// A G-code block as the reference reading gives it: lengths in ångström.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RefBlock {
    /// G00–G03.
    pub motion: Option<u8>,
    /// G40–G42.
    pub compensation: Option<u8>,
    /// G90 / G91.
    pub distance: Option<u8>,
    /// X, Z, I, K, R words.
    pub xzikr: [Option<i64>; 5],
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
    /// A G code outside 00–03, 40–42, 90, 91.
    UnsupportedG,
}

/// Reads a block per the `gcode` module docs: address words (a letter and
/// the run of `0-9 + - .` after it), spaces and tabs between words optional,
/// `( … )` comments, `;` ends the block; `N F S T M X Z I K R` once each and
/// numbers that must be lengths; `G` once per group, 1–3 digits.
pub fn reference_block(line: &str) -> Result<RefBlock, RefBlockError> {
    let mut b = RefBlock::default();
    let mut seen = [false; 26];
    let mut chars = line.char_indices().peekable();
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
            c if c.is_ascii_alphabetic() => {
                let letter = c.to_ascii_uppercase() as u8;
                let mut end = at + 1;
                while let Some(&(i, d)) = chars.peek() {
                    if d.is_ascii_digit() || matches!(d, '+' | '-' | '.') {
                        end = i + 1;
                        chars.next();
                    } else {
                        break;
                    }
                }
                let number = &line[at + 1..end];
                if number.is_empty() {
                    return Err(RefBlockError::NotAWord);
                }
                if letter == b'G' {
                    if number.len() > 3 || !number.bytes().all(|d| d.is_ascii_digit()) {
                        return Err(RefBlockError::UnsupportedG);
                    }
                    let code: u8 = number.parse().map_err(|_| RefBlockError::UnsupportedG)?;
                    let slot = match code {
                        0..=3 => &mut b.motion,
                        40..=42 => &mut b.compensation,
                        90 | 91 => &mut b.distance,
                        _ => return Err(RefBlockError::UnsupportedG),
                    };
                    if slot.is_some() {
                        return Err(RefBlockError::Repeated(b'G'));
                    }
                    *slot = Some(code);
                    continue;
                }
                let idx = usize::from(letter - b'A');
                if seen[idx] {
                    return Err(RefBlockError::Repeated(letter));
                }
                seen[idx] = true;
                let slot = match letter {
                    b'X' => Some(0),
                    b'Z' => Some(1),
                    b'I' => Some(2),
                    b'K' => Some(3),
                    b'R' => Some(4),
                    b'N' | b'F' | b'S' | b'T' | b'M' => None,
                    _ => return Err(RefBlockError::UnknownAddress(letter)),
                };
                let v = parse_mm(number).map_err(|e| RefBlockError::Value(letter, e))?;
                if let Some(s) = slot {
                    b.xzikr[s] = Some(v);
                }
            }
            _ => return Err(RefBlockError::NotAWord),
        }
    }
    Ok(b)
}

/// Whether a request line is a G-code block: its first word is an address
/// letter directly followed by a digit, sign or point.
pub fn reference_is_block(line: &str) -> bool {
    let t = line.trim_start();
    let mut c = t.chars();
    matches!(
        (c.next(), c.next()),
        (Some(l), Some(d)) if l.is_ascii_alphabetic() && (d.is_ascii_digit() || matches!(d, '+' | '-' | '.'))
    )
}

//! The request line on the wire: its checks (`*HH`, `~CRC`, `@id`), the
//! argument parsers, and the replies and refusals as they are written.

use crate::arc::ArcError;
use crate::comp::CompError;
use crate::crc32::Crc32;
use crate::gcode::{BlockError, Coolant, Spindle};
use crate::impulse::ImpulsePrice;
use crate::length::{write_mm4, Length, LengthError};
use crate::protocol::io::{ErrorCode, Io, Refused, StatusRecord};
use crate::protocol::reply::{checksum, hex_digits, ReplyLine, REPLY_CAPACITY};
use crate::protocol::request::RequestError;
use crate::protocol::words::ArgError;

use crate::outputs::write_rpm;
use crate::plan::Feed;
use core::fmt::{self, Write};

/// Why a request was refused, before it is written out.
pub(in crate::protocol) enum Refusal<'a> {
    Checksum(u8),
    ChecksumForm,
    Control,
    Empty,
    Unknown(&'a str),
    Args(ArgError<'a>),
    NoArgs(&'static str),
    Value(&'static str, &'static str),
    Range(&'static str),
    /// A point beyond the travel of an axis homed (soft limits).
    Travel(&'static str),
    Geometry(&'static str),
    Missing(&'static str),
    Block(BlockError),
    Contour(CompError),
    Busy(&'static str),
    /// An input stopped the machine and it is not cleared.
    Halted(crate::inputs::Halt),
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

impl<'a> From<RequestError<'a>> for Refusal<'a> {
    fn from(e: RequestError<'a>) -> Self {
        match e {
            RequestError::Empty => Refusal::Empty,
            RequestError::Unknown(word) => Refusal::Unknown(word),
            RequestError::Args(e) => Refusal::Args(e),
            RequestError::NoArgs(form) => Refusal::NoArgs(form),
        }
    }
}

/// Checks a request's `*HH` and, if present, its `~CCCCCCCC` word (CRC-32 of
/// every byte before the `~`); returns the request without them and whether
/// the CRC word was there.
pub(super) fn check_integrity(line: &[u8]) -> Result<(&[u8], bool), Refusal<'static>> {
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
pub(super) fn split_id(body: &[u8]) -> Result<(Option<u32>, &[u8]), Refusal<'static>> {
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
pub fn status_line(prefix: &str, record: &StatusRecord) -> ReplyLine {
    let mut line = ReplyLine::new();
    let _ = write!(
        line,
        "{prefix} STATE={} PX={} PZ={} X=",
        match record.view.alarm {
            0 => record.state().as_str(),
            10 => "ESTOP",
            _ => "ALARM",
        },
        record.issued.x.get(),
        record.issued.z.get()
    );
    let _ = write_mm4(&mut line, record.x_mm4());
    let _ = line.write_str(" Z=");
    let _ = write_mm4(&mut line, record.z_mm4());
    let _ = line.write_str(" V=");
    let _ = write_mm4(&mut line, record.speed_mm4());
    let _ = write!(line, " Q={} STARVED={}", record.queued, record.view.starved);
    let o = &record.view.outputs;
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
    if let Some(code) = record.view.stop {
        // Waiting for cycle start after M00 or M01.
        let _ = write!(line, " STOP=M{code:02}");
    }
    if record.view.alarm != 0 {
        let _ = write!(line, " ALARM={}", record.view.alarm);
    }
    if record.view.lost {
        let _ = line.write_str(" LOST=1");
    }
    if let Some(pins) = record.view.pins {
        let _ = line.write_str(" PN=");
        if pins == 0 {
            let _ = line.write_str("-");
        }
        let _ = crate::inputs::write_letters(&mut line, pins);
    }
    line
}

/// Adds the request's id (` @n`) and CRC (` ~CCCCCCCC`) words to every reply
/// line, and remembers the final line for a repeated id.
pub(super) struct Suffixed<'a, I: Io> {
    pub(super) inner: &'a mut I,
    pub(super) id: Option<u32>,
    pub(super) crc: bool,
    pub(super) last: heapless::Vec<u8, REPLY_CAPACITY>,
}

impl<I: Io> Suffixed<'_, I> {
    /// Sends a reply body (no `*HH`) with the suffix words.
    pub(super) fn send_body(&mut self, body: &[u8]) {
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
        // The final line. This front wrote it; an `OK` is told to those
        // around it (a grbl front) as what it is (an `ERR` was, through
        // `Io::refused`).
        let ok = body.starts_with(b"OK");
        if ok {
            self.inner.accepted();
        }
        if ok || body.starts_with(b"ERR") {
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

    fn timing(&mut self) -> Option<crate::protocol::io::Timing> {
        self.inner.timing()
    }

    fn stop_holds(&mut self) -> bool {
        self.inner.stop_holds()
    }
    crate::protocol::io::forward_io!();
}

/// Splits off and checks a trailing `*HH`; returns the bytes before it.
pub(super) fn strip_checksum(line: &[u8]) -> Result<&[u8], Refusal<'static>> {
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
pub(super) fn in_comment(line: &[u8]) -> impl Iterator<Item = bool> + '_ {
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

pub(super) fn hex_value(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'A'..=b'F' => Some(b - b'A' + 10),
        b'a'..=b'f' => Some(b - b'a' + 10),
        _ => None,
    }
}

pub(in crate::protocol) fn parse_length(
    key: &'static str,
    v: &str,
) -> Result<Length, Refusal<'static>> {
    Length::from_mm_str(v).map_err(|e| Refusal::Value(key, e.as_str()))
}

pub(super) fn parse_price(key: &'static str, v: &str) -> Result<ImpulsePrice, Refusal<'static>> {
    ImpulsePrice::from_length(parse_length(key, v)?)
        .ok_or(Refusal::Value(key, "must be 0.000001 to 1 mm"))
}

pub(super) fn parse_bounded(
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
pub(super) fn parse_amount(
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
pub(super) fn parse_count(
    key: &'static str,
    v: Option<&str>,
    default: u32,
) -> Result<u32, Refusal<'static>> {
    let Some(v) = v else {
        return Ok(default);
    };
    if v.is_empty() || v.len() > 7 || !v.bytes().all(|b| b.is_ascii_digit()) {
        return Err(Refusal::Value(key, "not a whole number"));
    }
    Ok(v.bytes().fold(0, |n, b| n * 10 + u32::from(b - b'0')))
}

/// A feed in mm/min: 0.001 … 99 999.999999, at most 6 decimals.
pub(super) fn parse_feed(v: &str) -> Result<Feed, Refusal<'static>> {
    let range = Refusal::Value("F", "must be 0.001 to 99999.999999 mm/min");
    let f = parse_rate("F", v, range)?;
    Feed::new(f).ok_or(Refusal::Value("F", "must be 0.001 to 99999.999999 mm/min"))
}

/// A rate or acceleration word: a length's syntax, `range` when too large.
pub(super) fn parse_rate(
    key: &'static str,
    v: &str,
    range: Refusal<'static>,
) -> Result<Length, Refusal<'static>> {
    Length::from_mm_str(v).map_err(|e| match e {
        LengthError::OutOfRange => range,
        e => Refusal::Value(key, e.as_str()),
    })
}

pub(in crate::protocol) fn parse_flag(
    key: &'static str,
    v: &str,
) -> Result<bool, Refusal<'static>> {
    match v {
        "0" => Ok(false),
        "1" => Ok(true),
        _ => Err(Refusal::Value(key, "must be 0 or 1")),
    }
}

/// At most this much of a word from the request is echoed in an error.
pub(super) const ECHO: usize = 16;

/// The printable start of a request word, for error texts.
pub(super) fn echo(word: &str) -> &str {
    word.get(..ECHO.min(word.len())).unwrap_or("")
}

pub(super) fn send_refusal<I: Io>(io: &mut I, refusal: Refusal<'_>) {
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
        Refusal::Value(key, why) => {
            // A key of one letter is a word's address.
            let about = match key.as_bytes() {
                &[letter] => Some(letter),
                _ => None,
            };
            send_error_about(io, E::Value, about, format_args!("{key} {why}"))
        }
        Refusal::Range(what) | Refusal::Travel(what) => {
            send_error(io, E::Range, format_args!("{what}"))
        }
        Refusal::Geometry(what) => send_error(io, E::Geometry, format_args!("{what}")),
        Refusal::Missing(what) => send_error(io, E::Syntax, format_args!("{what}")),
        Refusal::Halted(halt @ crate::inputs::Halt::Estop(_)) => {
            send_error(io, E::Estop, format_args!("{}", halt.next_step()))
        }
        Refusal::Halted(halt) => send_error(
            io,
            E::Alarm,
            format_args!("{}: {}", halt.alarm(), halt.next_step()),
        ),
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
            send_error_about(io, code, e.address(), format_args!("{e}"))
        }
    }
}

/// A block named by its `N` number, or by its place.
pub(super) struct BlockName(Option<u32>, &'static str);

impl fmt::Display for BlockName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(n) => write!(f, "N{n}"),
            None => f.write_str(self.1),
        }
    }
}

pub(super) fn send_contour_refusal<I: Io>(io: &mut I, e: CompError) {
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
        CompError::RoundNext(a, b) => send_error(
            io,
            E::Geometry,
            format_args!(
                "{}: the ,C/,R of {} needs a G01-G03 move next, no G40-G42",
                this(b),
                last(a)
            ),
        ),
        CompError::RoundHere(n) => send_error(
            io,
            E::Geometry,
            format_args!("{}: ,C and ,R go on a G01-G03 move, no G40-G42", this(n)),
        ),
        CompError::RoundTooBig(a, b) => send_error(
            io,
            E::Geometry,
            format_args!(
                "the ,C/,R of {} does not fit between it and {}",
                last(a),
                this(b)
            ),
        ),
        CompError::RoundNoCorner(a, b) => send_error(
            io,
            E::Geometry,
            format_args!(
                "{} and {} meet without a corner to chamfer or round",
                last(a),
                this(b)
            ),
        ),
        CompError::RoundSquare(a, b) => send_error(
            io,
            E::Geometry,
            format_args!(
                "{}: after the I, K or R of {} (a right angle's chamfer or round), a G01 along the other axis alone, the way of the word's sign",
                this(b),
                last(a)
            ),
        ),
        CompError::ChamferArc(a, b) => send_error(
            io,
            E::Geometry,
            format_args!(
                "a ,C joins two lines: {} or {} is an arc (,R rounds it)",
                last(a),
                this(b)
            ),
        ),
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

/// Sends `DATA MSG <text>`, what the operator must do at a stop, told
/// first through [`Io::message`].
pub(crate) fn send_message<I: Io>(io: &mut I, text: fmt::Arguments<'_>) {
    let mut line = ReplyLine::new();
    let _ = write!(line, "DATA MSG ");
    let start = line.as_bytes().len();
    let _ = write!(line, "{text}");
    io.message(line.as_bytes().get(start..).unwrap_or(b""));
    io.send(line.finish());
}

/// Sends `ERR <CODE> <text>`.
pub(crate) fn send_error<I: Io>(io: &mut I, code: ErrorCode, text: fmt::Arguments<'_>) {
    send_error_about(io, code, None, text);
}

/// As [`send_error`], the refusal about the word `about` (its letter).
pub(crate) fn send_error_about<I: Io>(
    io: &mut I,
    code: ErrorCode,
    about: Option<u8>,
    text: fmt::Arguments<'_>,
) {
    io.refused(Refused { code, about });
    let mut line = ReplyLine::new();
    let _ = write!(line, "ERR {} {}", code.as_str(), text);
    io.send(line.finish());
}

/// A request's result: done (its replies sent), or why it was refused.
pub(in crate::protocol) type Outcome<'a> = Result<(), Refusal<'a>>;

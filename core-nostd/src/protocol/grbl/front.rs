//! The grbl front's own state and its real-time bytes.

use crate::protocol::io::Realtime;

/// A real-time character of grbl.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GrblRealtime {
    /// One of the pendant's real-time commands (`?`, `!`, `~`, Ctrl-X, and
    /// the pendant's own 0x80–0x82).
    Common(Realtime),
    /// 0x85: stop a jog and drop what is left of it.
    JogCancel,
    /// 0x90–0x94: feed override to 100 %, +10, −10, +1, −1.
    Feed(u8),
    /// 0x95–0x97: rapid override to 100, 50, 25 %.
    Rapid(u8),
    /// 0x99–0x9D: spindle override to 100 %, +10, −10, +1, −1.
    Spindle(u8),
    /// The spindle stop (0x9E) and coolant toggles (0xA0, 0xA1): not
    /// implemented.
    Unsupported(u8),
}

impl GrblRealtime {
    /// The feed, rapid and spindle overrides (percent) after this command:
    /// a transport that shows them before the protocol has acted on the
    /// byte computes them as the protocol will.
    pub const fn overrides(self, [feed, rapid, spindle]: [u8; 3]) -> [u8; 3] {
        match self {
            GrblRealtime::Feed(byte) => [stepped(feed, byte), rapid, spindle],
            GrblRealtime::Rapid(byte) => [
                feed,
                match byte {
                    0x95 => 100,
                    0x96 => 50,
                    _ => 25,
                },
                spindle,
            ],
            GrblRealtime::Spindle(byte) => [feed, rapid, stepped(spindle, byte - 0x09)],
            _ => [feed, rapid, spindle],
        }
    }

    /// The real-time command a byte is in grbl mode, if it is one.
    pub const fn from_byte(byte: u8) -> Option<GrblRealtime> {
        match byte {
            b'?' => Some(GrblRealtime::Common(Realtime::Status)),
            b'!' => Some(GrblRealtime::Common(Realtime::Hold)),
            b'~' => Some(GrblRealtime::Common(Realtime::Resume)),
            0x85 => Some(GrblRealtime::JogCancel),
            0x90..=0x94 => Some(GrblRealtime::Feed(byte)),
            0x95..=0x97 => Some(GrblRealtime::Rapid(byte)),
            0x99..=0x9D => Some(GrblRealtime::Spindle(byte)),
            0x9E | 0xA0 | 0xA1 => Some(GrblRealtime::Unsupported(byte)),
            _ => match Realtime::from_byte(byte) {
                Some(rt) => Some(GrblRealtime::Common(rt)),
                None => None,
            },
        }
    }
}

/// Whether a byte that is not a real-time command is dropped on a grbl
/// link rather than taken into the line: above 0x7F (grbl keeps only its
/// real-time commands there; CNCjs sends an override byte as UTF-8, `C2 91`)
/// and control bytes other than CR, LF and tab.
pub const fn dropped(byte: u8) -> bool {
    byte >= 0x80 || (byte < 0x20 && !matches!(byte, b'\r' | b'\n' | b'\t'))
}

/// The grbl front's own state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Front {
    /// Whether the link speaks grbl.
    pub on: bool,
    /// The alarm in force (`ALARM:3` after a reset in motion), until `$X`.
    pub alarm: Option<u8>,
    /// Feed override, percent (10 … 200).
    pub feed: u8,
    /// Rapid override, percent (100, 50, 25).
    pub rapid: u8,
    /// Spindle override, percent (10 … 200).
    pub spindle: u8,
    /// A jog runs; a jog cancel waits for the axes to come to rest.
    pub jogging: bool,
    /// A jog cancel came: drop the rest once at rest.
    pub cancel: bool,
    /// `$C`: lines are checked, nothing moves or switches.
    pub check: bool,
    /// `$10` bit 0: status reports give machine positions (else work).
    pub mpos: bool,
    /// The settings kept for senders (see `$$`).
    pub kept: [u32; KEPT],
}

impl Front {
    /// Power-on: the pendant protocol, no alarm, 100 %.
    pub const fn new() -> Front {
        Front {
            on: false,
            alarm: None,
            feed: 100,
            rapid: 100,
            spindle: 100,
            jogging: false,
            cancel: false,
            check: false,
            mpos: true,
            kept: KEPT_DEFAULT,
        }
    }
}

impl Default for Front {
    fn default() -> Self {
        Self::new()
    }
}

/// How many settings the front keeps.
pub const KEPT: usize = 2;

/// The kept settings at power-on, as grbl's defaults: `$1` 25 ms, `$26`
/// 250 ms.
pub const KEPT_DEFAULT: [u32; KEPT] = [25, 250];

/// An override stepped by its byte, as 0x90–0x94 step the feed's: 100 %,
/// +10, −10, +1, −1, within 10 … 200 %.
const fn stepped(percent: u8, byte: u8) -> u8 {
    let p = percent as i16;
    let next = match byte {
        0x90 => 100,
        0x91 => p + 10,
        0x92 => p - 10,
        0x93 => p + 1,
        _ => p - 1,
    };
    (if next < 10 {
        10
    } else if next > 200 {
        200
    } else {
        next
    }) as u8
}

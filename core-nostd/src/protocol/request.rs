//! The requests of the pendant protocol as typed values: one table of every
//! command, the keys it takes and the form `docs/protocol.md` gives it, and
//! the parse of a request line into a [`Request`] against that table.
//!
//! The parse is the one place a request's words are split and checked (the
//! command is one of the table's, every word is `KEY=VALUE` with a key the
//! command takes, no key twice, no word after a command that takes none).
//! What a value means (a length, a flag, a tool number) is for the command
//! that runs it: it can be refused only there, with the state it depends on.

use super::words::{match_args, Words};
use crate::gcode::is_block;
use crate::text::split_once;

pub use super::words::ArgError;

/// A command of the pendant protocol (a G-code block is not one: it is a
/// [`Request::Block`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    /// `VER`: the protocol, the device, its version.
    Ver,
    /// `CFG`: impulse prices, diameter mode, the nose, tolerance, pass.
    Cfg,
    /// `ZERO`: where the machine's zero is.
    Zero,
    /// `SESSION`: the host's session token.
    Session,
    /// `MOVE`: a straight move.
    Move,
    /// `CONE`: taper corrections for the nose radius.
    Cone,
    /// `ARC`: an arc by chords or step by step.
    Arc,
    /// `DRIVE`: the step/dir output timing.
    Drive,
    /// `MCODE`: what the machine's own M codes do.
    Mcode,
    /// `GEAR`: the top speed of each gear range.
    Gear,
    /// `OPT`: block delete, dialect, optional stop.
    Opt,
    /// `LIMITS`: rapid rates, accelerations, junction deviation.
    Limits,
    /// `SYNC`: run everything queued and report it.
    Sync,
    /// `STATUS`: where the machine is, without waiting.
    Status,
    /// `RESET`: abandon the program where it stands.
    Reset,
    /// `POS`: the position registers.
    Pos,
    /// `UNLOCK`: clear what an input stopped.
    Unlock,
    /// `INPUT`: the inputs wired, their level, the filter.
    Input,
    /// `HOMING`: the homing cycle's settings.
    Homing,
    /// `HOME`: the homing cycle.
    Home,
    /// `WHEEL`: the handwheel's axis, scale and feed.
    Wheel,
    /// `BACKLASH`: each axis' play, taken up at reversals.
    Backlash,
    /// `TOOL`: a row of the tool table.
    Tool,
    /// `WORK`: a work offset.
    Work,
    /// `AUX`: the spindle's top speed and spin-up wait.
    Aux,
    /// `THREAD`: the thread-cutting calculator.
    Thread,
    /// `WEAR`: the tool-wear calculator.
    Wear,
    /// `DEFLECT`: the deflection calculator.
    Deflect,
    /// `TRI`: the trihedral-corner calculator.
    Tri,
    /// `TAPE`: the BCK-5 tape verifier.
    Tape,
}

/// One row of the request table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Spec {
    /// The command it parses to.
    pub command: Command,
    /// A calculator's request (in the image with the `calc` feature).
    pub calc: bool,
    /// The command word (matched without regard to case), then the keys it
    /// takes, separated by spaces: every key is optional to the parse, and
    /// a command's handler reads their values in this order.
    pub words: &'static str,
}

/// The most keys one command takes.
pub const MAX_KEYS: usize = 16;

/// The forms that are one word alone instead of keys.
pub const BARE: [(Command, &str); 1] = [(Command::Tape, "TAPE END")];

const fn spec(command: Command, words: &'static str) -> Spec {
    Spec {
        command,
        calc: false,
        words,
    }
}

const fn calc(mut s: Spec) -> Spec {
    s.calc = true;
    s
}

/// Every request of the pendant protocol, in the order `docs/protocol.md`
/// gives them.
pub const REQUESTS: [Spec; 30] = [
    spec(Command::Ver, "VER"),
    spec(Command::Cfg, "CFG HX HZ DIAM RN TIP TOL PASS"),
    spec(Command::Cone, "CONE A RN"),
    spec(Command::Zero, "ZERO X Z"),
    spec(Command::Move, "MOVE X Z INC F"),
    spec(Command::Pos, "POS"),
    spec(Command::Arc, "ARC X Z I K DIR TOL PASS MODE F"),
    spec(Command::Drive, "DRIVE RATE PULSE SETUP"),
    spec(Command::Opt, "OPT BDEL DIALECT OPTSTOP"),
    spec(Command::Aux, "AUX SMAX SPINUP"),
    spec(Command::Tool, "TOOL N X Z WX WZ R T"),
    spec(Command::Work, "WORK G X Z"),
    spec(Command::Limits, "LIMITS VX VZ AX AZ JD"),
    spec(Command::Sync, "SYNC"),
    spec(Command::Status, "STATUS"),
    spec(Command::Reset, "RESET"),
    spec(Command::Unlock, "UNLOCK"),
    spec(Command::Input, "INPUT USED INVERT FILTER"),
    spec(
        Command::Homing,
        "HOMING AXES DIRX DIRZ HOMEX HOMEZ TRAVELX TRAVELZ SEEK LOCATE PULLOFF ORDER REQUIRED SOFT JOGCLIP",
    ),
    spec(Command::Home, "HOME AXES"),
    spec(Command::Wheel, "WHEEL AXIS SCALE FEED"),
    spec(Command::Backlash, "BACKLASH X Z"),
    spec(Command::Gear, "GEAR N TOP"),
    spec(Command::Mcode, "MCODE M DO N"),
    spec(Command::Session, "SESSION TOKEN"),
    calc(spec(Command::Thread, "THREAD P MODE CROSS")),
    calc(spec(
        Command::Wear,
        "WEAR D L S KM U0 UR Q ALLOW TOL FULL H ALPHA",
    )),
    calc(spec(
        Command::Deflect,
        "DEFLECT D L J T S HB PHI RN C X E RED DX G",
    )),
    calc(spec(
        Command::Tri,
        "TRI AOB BOC COA OA OB OC H ROWS LEN RF TABLE EA KV V PROP G",
    )),
    calc(spec(Command::Tape, "TAPE FRAME")),
];

impl Spec {
    /// The command word.
    pub fn name(&self) -> &'static str {
        split_once(self.words, b' ').map_or(self.words, |(name, _)| name)
    }

    /// Its keys, in the order their values are read.
    pub fn keys(&self) -> impl Iterator<Item = &'static str> + Clone {
        // Words, not `str::split`: its slicing would leave a panic path in
        // the board's image.
        Words::new(split_once(self.words, b' ').map_or("", |(_, keys)| keys))
    }

    /// The form of the word it takes alone (`TAPE END`), if any.
    pub fn bare(&self) -> Option<&'static str> {
        BARE.iter()
            .find(|(c, _)| *c == self.command)
            .map(|(_, form)| *form)
    }

    /// The word it takes alone (`END` of `TAPE END`).
    pub fn bare_word(&self) -> Option<&'static str> {
        self.bare().and_then(|form| Words::new(form).nth(1))
    }
}

impl Command {
    /// Its forms as `docs/protocol.md` writes them (for the page's test;
    /// nothing on the board reads them).
    pub const fn forms(self) -> &'static [&'static str] {
        match self {
            Command::Ver => &["VER"],
            Command::Cfg => &["CFG [HX=] [HZ=] [DIAM=0|1] [RN=] [TIP=0..9] [TOL=] [PASS=FIN|ROUGH]"],
            Command::Cone => &["CONE A= [RN=]"],
            Command::Zero => &["ZERO [X=] [Z=]"],
            Command::Move => &["MOVE [X=] [Z=] [INC=0|1] [F=]"],
            Command::Pos => &["POS"],
            Command::Arc => &["ARC X= Z= I= K= DIR=CW|CCW [TOL=] [PASS=FIN|ROUGH] [F=]",
            "ARC X= Z= I= K= DIR=CW|CCW MODE=DIRECT [F=]"],
            Command::Drive => &["DRIVE [RATE=] [PULSE=] [SETUP=]"],
            Command::Opt => &["OPT [BDEL=0|1] [DIALECT=ISO|FANUC] [OPTSTOP=0|1]"],
            Command::Aux => &["AUX [SMAX=] [SPINUP=]"],
            Command::Tool => &["TOOL N=1..32 [X=] [Z=] [WX=] [WZ=] [R=] [T=0..9]"],
            Command::Work => &["WORK G=54..59 [X=] [Z=]"],
            Command::Limits => &["LIMITS [VX=] [VZ=] [AX=] [AZ=] [JD=]"],
            Command::Sync => &["SYNC"],
            Command::Status => &["STATUS"],
            Command::Reset => &["RESET"],
            Command::Unlock => &["UNLOCK"],
            Command::Input => &["INPUT [USED=names|-] [INVERT=names|-] [FILTER=0..100]"],
            Command::Homing => &["HOMING [AXES=X|Z|XZ|-] [DIRX=+|-] [DIRZ=+|-] [HOMEX=] [HOMEZ=] [TRAVELX=] [TRAVELZ=] [SEEK=] [LOCATE=] [PULLOFF=] [ORDER=XZ|ZX] [REQUIRED=0|1] [SOFT=0|1] [JOGCLIP=0|1]"],
            Command::Home => &["HOME [AXES=X|Z|XZ]"],
            Command::Wheel => &["WHEEL [AXIS=X|Z|-] [SCALE=1|10|100] [FEED=]"],
            Command::Backlash => &["BACKLASH [X=] [Z=]"],
            Command::Gear => &["GEAR [N=1..4 TOP=]"],
            Command::Mcode => &["MCODE [M= [DO=STOP|NONE|ON|OFF|HIGH|LOW] [N=1..4]]"],
            Command::Session => &["SESSION [TOKEN=n]"],
            Command::Thread => &["THREAD P= [MODE=G06|G07|G08|G09] [CROSS=0|1]"],
            Command::Wear => &["WEAR (D= L= S= | KM=) UR= [U0=] [Q=] [ALLOW= TOL=] [FULL=] [H= ALPHA=]"],
            Command::Deflect => &["DEFLECT D= L= J=JH,JT,JS T= [S=] [HB=] [PHI=] [RN=] [C= X=] [E=] [RED=LEN|VOL] [DX=] [G=0|1]"],
            Command::Tri => &["TRI [AOB=] [BOC=] [COA=] [OA=] [OB=] [OC=] [H=] [ROWS=] [LEN=LA,LB,LC] [RF=] [TABLE=L,M] [EA=] [KV=] [V=X,Y,Z] [PROP=0|1] [G=0|1]"],
            Command::Tape => &["TAPE FRAME=<frame>", "TAPE END"],
        }
    }

    /// Its row of [`REQUESTS`].
    pub fn spec(self) -> &'static Spec {
        let row = REQUESTS.iter().find(|s| s.command == self);
        // Every command has a row (a test walks them all); VER's is the
        // first.
        row.unwrap_or(&REQUESTS[0])
    }
}

/// Why a request line is not a request (all `ERR` before anything runs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RequestError<'a> {
    /// Nothing but blanks.
    Empty,
    /// A command word no row of the table has.
    Unknown(&'a str),
    /// Its arguments do not match its keys.
    Args(ArgError<'a>),
    /// Words after a command (or form) that takes none.
    NoArgs(&'static str),
}

impl<'a> From<ArgError<'a>> for RequestError<'a> {
    fn from(e: ArgError<'a>) -> Self {
        RequestError::Args(e)
    }
}

/// The arguments of a command: the value of each of its keys, if given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Args<'a> {
    /// The command's keys, separated by spaces.
    keys: &'static str,
    values: [Option<&'a str>; MAX_KEYS],
    /// The command's bare word was given (`TAPE END`).
    pub bare: bool,
}

impl<'a> Args<'a> {
    fn of(spec: &Spec) -> Self {
        Args {
            keys: split_once(spec.words, b' ').map_or("", |(_, keys)| keys),
            values: [None; MAX_KEYS],
            bare: false,
        }
    }

    /// The values of the command's keys, in the table's order (`None` for
    /// a key not given): `N` is the number of its keys.
    pub fn values<const N: usize>(&self) -> [Option<&'a str>; N] {
        debug_assert_eq!(N, Words::new(self.keys).count(), "{}", self.keys);
        core::array::from_fn(|i| self.values.get(i).copied().flatten())
    }

    /// The keys given and their values, in the table's order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, &'a str)> + '_ {
        Words::new(self.keys)
            .zip(self.values)
            .filter_map(|(k, v)| Some((k, v?)))
    }
}

/// A request line as a typed value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
// A request lives on the stack for the one call that runs it (no heap
// to box its arguments in); the Block variant is the smaller.
#[allow(clippy::large_enum_variant)]
pub enum Request<'a> {
    /// A G-code block, run by the interpreter.
    Block(&'a str),
    /// A command of the table with its arguments.
    Command(Command, Args<'a>),
}

impl<'a> Request<'a> {
    /// Parses a request line (without its `*HH`, `~CRC` and `@id` words).
    pub fn parse(text: &'a str) -> Result<Self, RequestError<'a>> {
        let mut words = Words::new(text);
        let name = words.next().ok_or(RequestError::Empty)?;
        if is_block(text) {
            return Ok(Request::Block(text));
        }
        let spec = REQUESTS
            .iter()
            .find(|s| s.name().eq_ignore_ascii_case(name) && (cfg!(feature = "calc") || !s.calc))
            .ok_or(RequestError::Unknown(name))?;
        let mut args = Args::of(spec);
        if let (Some(form), Some(word)) = (spec.bare(), spec.bare_word()) {
            if words
                .clone()
                .next()
                .is_some_and(|w| w.eq_ignore_ascii_case(word))
            {
                words.next();
                if words.next().is_some() {
                    return Err(RequestError::NoArgs(form));
                }
                args.bare = true;
                return Ok(Request::Command(spec.command, args));
            }
        }
        if spec.keys().next().is_none() {
            if words.next().is_some() {
                return Err(RequestError::NoArgs(spec.name()));
            }
        } else {
            match_args(words, spec.keys(), &mut args.values)?;
        }
        Ok(Request::Command(spec.command, args))
    }

    /// A command with the values given (a front's own request: grbl's `$n=`
    /// and `$J=`), checked as a parsed line's would be.
    pub fn command(
        command: Command,
        values: &[(&'static str, &'a str)],
    ) -> Result<Self, RequestError<'a>> {
        let spec = command.spec();
        let mut args = Args::of(spec);
        for &(key, value) in values {
            let (_, slot) = spec
                .keys()
                .zip(0usize..)
                .find(|(k, _)| *k == key)
                .ok_or(ArgError::UnknownKey(key))?;
            match args.values.get_mut(slot) {
                Some(s @ None) => *s = Some(value),
                _ => return Err(ArgError::Duplicate(key).into()),
            }
        }
        Ok(Request::Command(command, args))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_command_has_one_row_and_fits() {
        for s in &REQUESTS {
            assert_eq!(s.command.spec(), s, "{}", s.name());
            assert!(s.keys().count() <= MAX_KEYS, "{}", s.name());
            assert_eq!(
                REQUESTS.iter().filter(|o| o.name() == s.name()).count(),
                1,
                "{}",
                s.name()
            );
        }
    }

    #[test]
    fn parses_commands_keys_and_blocks() {
        let Ok(Request::Command(Command::Move, args)) = Request::parse("move\tz=2 X=1") else {
            panic!("MOVE not parsed");
        };
        assert_eq!(args.values(), [Some("1"), Some("2"), None, None]);
        assert_eq!(
            args.iter().collect::<heapless::Vec<_, 4>>().as_slice(),
            [("X", "1"), ("Z", "2")]
        );
        assert_eq!(Request::parse("G01 X1"), Ok(Request::Block("G01 X1")));
        assert_eq!(Request::parse("  "), Err(RequestError::Empty));
        assert_eq!(Request::parse("FOO X=1"), Err(RequestError::Unknown("FOO")));
        assert_eq!(
            Request::parse("SYNC X=1"),
            Err(RequestError::NoArgs("SYNC"))
        );
        assert_eq!(
            Request::parse("MOVE X=1 Y=2"),
            Err(RequestError::Args(ArgError::UnknownKey("Y")))
        );
        assert_eq!(
            Request::parse("MOVE X="),
            Err(RequestError::Args(ArgError::NotKeyValue("X=")))
        );
        assert_eq!(
            Request::parse("MOVE =1"),
            Err(RequestError::Args(ArgError::NotKeyValue("=1")))
        );
        assert_eq!(
            Request::parse("MOVE X=1 x=2"),
            Err(RequestError::Args(ArgError::Duplicate("X")))
        );
    }

    #[cfg(feature = "calc")]
    #[test]
    fn a_bare_word_stands_alone() {
        let Ok(Request::Command(Command::Tape, args)) = Request::parse("TAPE end") else {
            panic!("TAPE END not parsed");
        };
        assert!(args.bare);
        assert_eq!(
            Request::parse("TAPE END X=1"),
            Err(RequestError::NoArgs("TAPE END"))
        );
        let Ok(Request::Command(Command::Tape, args)) = Request::parse("TAPE FRAME=1") else {
            panic!("TAPE FRAME= not parsed");
        };
        assert!(!args.bare);
    }

    #[test]
    fn a_fronts_request_is_checked_as_a_line() {
        let r = Request::command(Command::Limits, &[("VX", "500")]);
        assert_eq!(r, Request::parse("LIMITS VX=500"));
        assert_eq!(
            Request::command(Command::Limits, &[("Q", "1")]),
            Err(RequestError::Args(ArgError::UnknownKey("Q")))
        );
    }
}

//! Arbitrary UTF-8 into `Request::parse` alone, the request parser every
//! line of the pendant protocol goes through (`docs/protocol.md` §4).
//!
//! Checked against a reading written here from the page, sharing only the
//! table of commands and keys with the core:
//! - a line is a G-code block exactly when the oracle's reading of §5 says
//!   so, and then the request is the line itself;
//! - otherwise the first word (blanks are spaces and tabs) names a command
//!   of the table, without regard to case, or the line is refused as
//!   unknown (empty when there is no word);
//! - every other word is `KEY=VALUE` (both non-empty, split at the first
//!   `=`) with a key of the command, none twice; a command without keys
//!   takes no word, `TAPE END` none after `END`; the first violation is
//!   the one refused;
//! - a parsed request gives each key exactly the value its word gave, and
//!   writing it back out (`NAME KEY=VALUE …`) parses to the same request.
#![no_main]

use core_nostd::protocol::request::{ArgError, Command, Request, RequestError, Spec, REQUESTS};
use fuzz_oracle::reference_is_block;
use libfuzzer_sys::fuzz_target;

/// What the page says the line is.
#[derive(Debug, PartialEq)]
enum Expected<'a> {
    Block,
    Empty,
    Unknown(&'a str),
    NotKeyValue(&'a str),
    UnknownKey(&'a str),
    Duplicate(&'a str),
    NoArgs(&'a str),
    Command(Command, bool, Given<'a>),
}

/// The keys given and their values, in the table's order, without
/// allocation (the target runs at volume).
#[derive(Debug, PartialEq, Clone, Copy)]
struct Given<'a> {
    pairs: [(&'static str, &'a str); 16],
    len: usize,
}

impl<'a> Given<'a> {
    const NONE: Self = Given {
        pairs: [("", ""); 16],
        len: 0,
    };
    fn push(&mut self, key: &'static str, value: &'a str) {
        self.pairs[self.len] = (key, value);
        self.len += 1;
    }
    fn as_slice(&self) -> &[(&'static str, &'a str)] {
        &self.pairs[..self.len]
    }
}

fn expected(text: &str) -> Expected<'_> {
    let mut words = text.split([' ', '\t']).filter(|w| !w.is_empty());
    let Some(name) = words.next() else {
        return Expected::Empty;
    };
    if reference_is_block(text) {
        return Expected::Block;
    }
    let Some(spec): Option<&Spec> = REQUESTS
        .iter()
        .find(|s| s.name().eq_ignore_ascii_case(name))
    else {
        return Expected::Unknown(name);
    };
    let mut rest = words.clone().peekable();
    if let (Some(form), Some(bare)) = (spec.bare(), spec.bare_word()) {
        if rest.next().is_some_and(|w| w.eq_ignore_ascii_case(bare)) {
            return if rest.peek().is_some() {
                Expected::NoArgs(form)
            } else {
                Expected::Command(spec.command, true, Given::NONE)
            };
        }
    }
    let mut rest = words;
    if spec.keys().next().is_none() {
        return if rest.next().is_none() {
            Expected::Command(spec.command, false, Given::NONE)
        } else {
            Expected::NoArgs(spec.name())
        };
    }
    let mut given = Given::NONE;
    for word in rest {
        let Some(eq) = word.find('=') else {
            return Expected::NotKeyValue(word);
        };
        let (key, value) = (&word[..eq], &word[eq + 1..]);
        if key.is_empty() || value.is_empty() {
            return Expected::NotKeyValue(word);
        }
        let Some(k) = spec.keys().find(|k| k.eq_ignore_ascii_case(key)) else {
            return Expected::UnknownKey(key);
        };
        if given.as_slice().iter().any(|(g, _)| *g == k) {
            return Expected::Duplicate(k);
        }
        given.push(k, value);
    }
    // In the table's order, as the parse lists them.
    let mut ordered = Given::NONE;
    for k in spec.keys() {
        if let Some(&(k, v)) = given.as_slice().iter().find(|(g, _)| *g == k) {
            ordered.push(k, v);
        }
    }
    Expected::Command(spec.command, false, ordered)
}

fuzz_target!(|text: &str| {
    let got = Request::parse(text);
    let want = expected(text);
    let seen = match got {
        Ok(Request::Block(b)) => {
            assert_eq!(b, text);
            Expected::Block
        }
        Ok(Request::Command(c, args)) => {
            let mut given = Given::NONE;
            for (k, v) in args.iter() {
                given.push(k, v);
            }
            Expected::Command(c, args.bare, given)
        }
        Err(RequestError::Empty) => Expected::Empty,
        Err(RequestError::Unknown(w)) => Expected::Unknown(w),
        Err(RequestError::NoArgs(f)) => Expected::NoArgs(f),
        Err(RequestError::Args(ArgError::NotKeyValue(w))) => Expected::NotKeyValue(w),
        Err(RequestError::Args(ArgError::UnknownKey(k))) => Expected::UnknownKey(k),
        Err(RequestError::Args(ArgError::Duplicate(k))) => Expected::Duplicate(k),
    };
    assert_eq!(seen, want, "{text:?}");
    if let Ok(Request::Command(c, args)) = got {
        let spec = c.spec();
        let mut buf = [0u8; 1024];
        let mut len = 0;
        let mut put = |s: &str| {
            buf[len..len + s.len()].copy_from_slice(s.as_bytes());
            len += s.len();
        };
        put(spec.name());
        if args.bare {
            put(" ");
            put(spec.bare_word().unwrap_or(""));
        }
        for (k, v) in args.iter() {
            put(" ");
            put(k);
            put("=");
            put(v);
        }
        let line = core::str::from_utf8(&buf[..len]).unwrap();
        assert_eq!(
            Request::parse(line),
            got,
            "{text:?} written back as {line:?}"
        );
    }
});

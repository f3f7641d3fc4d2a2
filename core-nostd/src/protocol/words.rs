//! Splitting a request into its command word and `KEY=VALUE` arguments.

/// A request split into words, without allocation.
#[derive(Clone)]
pub(crate) struct Words<'a> {
    rest: &'a str,
}

impl<'a> Words<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        Words { rest: text }
    }
}

impl<'a> Iterator for Words<'a> {
    type Item = &'a str;
    fn next(&mut self) -> Option<&'a str> {
        let s = self.rest.trim_start_matches([' ', '\t']);
        if s.is_empty() {
            self.rest = s;
            return None;
        }
        let end = s.find([' ', '\t']).unwrap_or(s.len());
        // `end` is at an ASCII byte or the end: always a char boundary.
        let (word, rest) = s.split_at_checked(end).unwrap_or((s, ""));
        self.rest = rest;
        Some(word)
    }
}

/// Why the arguments of a command were refused (all `ERR SYNTAX`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ArgError<'a> {
    /// A word that is not `KEY=VALUE`.
    NotKeyValue(&'a str),
    /// A key the command does not take.
    UnknownKey(&'a str),
    /// A key given twice.
    Duplicate(&'static str),
}

/// Matches `KEY=VALUE` words against the keys a command takes (case-
/// insensitive). Slot `i` of the result holds the value of `keys[i]`.
pub(crate) fn parse_args<'a, const N: usize>(
    words: Words<'a>,
    keys: [&'static str; N],
) -> Result<[Option<&'a str>; N], ArgError<'a>> {
    let mut out = [None; N];
    match_args(words, &keys, &mut out)?;
    Ok(out)
}

/// [`parse_args`] for any number of keys (`out` as long as `keys`): one
/// copy of the matching, whatever the command.
#[inline(never)]
fn match_args<'a>(
    words: Words<'a>,
    keys: &[&'static str],
    out: &mut [Option<&'a str>],
) -> Result<(), ArgError<'a>> {
    for word in words {
        let (key, value) = match crate::text::split_once(word, b'=') {
            Some((k, v)) if !k.is_empty() && !v.is_empty() => (k, v),
            _ => return Err(ArgError::NotKeyValue(word)),
        };
        let slot = keys
            .iter()
            .position(|k| k.eq_ignore_ascii_case(key))
            .ok_or(ArgError::UnknownKey(key))?;
        match out.get_mut(slot) {
            Some(s @ None) => *s = Some(value),
            _ => return Err(ArgError::Duplicate(keys.get(slot).copied().unwrap_or(""))),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_on_spaces_and_tabs() {
        let mut w = Words::new("  MOVE\tX=1   Z=2 ");
        assert_eq!(w.next(), Some("MOVE"));
        assert_eq!(w.next(), Some("X=1"));
        assert_eq!(w.next(), Some("Z=2"));
        assert_eq!(w.next(), None);
    }

    #[test]
    fn matches_keys() {
        let r = parse_args(Words::new("z=2 X=1"), ["X", "Z", "INC"]);
        assert_eq!(r, Ok([Some("1"), Some("2"), None]));
        assert_eq!(
            parse_args(Words::new("X=1 x=2"), ["X"]),
            Err(ArgError::Duplicate("X"))
        );
        assert_eq!(
            parse_args(Words::new("Y=1"), ["X"]),
            Err(ArgError::UnknownKey("Y"))
        );
        assert_eq!(
            parse_args(Words::new("X="), ["X"]),
            Err(ArgError::NotKeyValue("X="))
        );
        assert_eq!(
            parse_args(Words::new("=1"), ["X"]),
            Err(ArgError::NotKeyValue("=1"))
        );
    }
}

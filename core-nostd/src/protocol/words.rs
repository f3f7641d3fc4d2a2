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
        let blank = |b: &u8| *b == b' ' || *b == b'\t';
        let Some(start) = self.rest.bytes().position(|b| !blank(&b)) else {
            self.rest = "";
            return None;
        };
        // `start` and `end` are at ASCII bytes or the end: char boundaries.
        let s = self.rest.get(start..)?;
        let end = s.bytes().position(|b| blank(&b)).unwrap_or(s.len());
        let (word, rest) = s.split_at_checked(end)?;
        self.rest = rest;
        Some(word)
    }
}

/// Why the arguments of a command were refused (all `ERR SYNTAX`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArgError<'a> {
    /// A word that is not `KEY=VALUE`.
    NotKeyValue(&'a str),
    /// A key the command does not take.
    UnknownKey(&'a str),
    /// A key given twice.
    Duplicate(&'static str),
}

/// Matches `KEY=VALUE` words against the keys a command takes (case-
/// insensitive): slot `i` of `out` gets the value of the `i`th key. One
/// copy of the matching, whatever the command.
#[inline(never)]
pub(crate) fn match_args<'a>(
    words: Words<'a>,
    keys: impl Iterator<Item = &'static str> + Clone,
    out: &mut [Option<&'a str>],
) -> Result<(), ArgError<'a>> {
    for word in words {
        let (key, value) = match crate::text::split_once(word, b'=') {
            Some((k, v)) if !k.is_empty() && !v.is_empty() => (k, v),
            _ => return Err(ArgError::NotKeyValue(word)),
        };
        // `zip(0..)`, not `enumerate`: no overflow check on the board.
        let (name, slot) = keys
            .clone()
            .zip(0usize..)
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .ok_or(ArgError::UnknownKey(key))?;
        match out.get_mut(slot) {
            Some(s @ None) => *s = Some(value),
            _ => return Err(ArgError::Duplicate(name)),
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
}

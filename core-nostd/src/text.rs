//! ASCII text helpers whose bounds checks the compiler can see through at
//! every optimisation level (the firmware links no reachable panic).

/// Splits `text` at the first `sep`, without it; `None` when there is none.
pub(crate) fn split_once(text: &str, sep: u8) -> Option<(&str, &str)> {
    let at = text.bytes().position(|b| b == sep)?;
    Some((text.get(..at)?, text.get(at + 1..)?))
}

#[cfg(test)]
mod tests {
    use super::split_once;

    #[test]
    fn splits_at_the_first_separator_only() {
        assert_eq!(split_once("X=1=2", b'='), Some(("X", "1=2")));
        assert_eq!(split_once("=", b'='), Some(("", "")));
        assert_eq!(split_once("12.5", b':'), None);
        assert_eq!(split_once("10:20:30", b':'), Some(("10", "20:30")));
    }
}

//! The request table (`core_nostd::protocol::request::REQUESTS`) and
//! `docs/protocol.md` say the same: every form the table gives is written
//! in the page, with the keys the command takes; every request of the
//! page's request tables is a command of the table, and parses; every
//! documented form, with a value for each of its keys, parses to its
//! command.

use core_nostd::protocol::request::{Request, REQUESTS};
use std::collections::BTreeSet;
use std::path::Path;

fn page() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/protocol.md");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The code spans of a Markdown text, `\|` read as `|`.
fn code_spans(text: &str) -> Vec<String> {
    let text = text.replace("\\|", "|");
    text.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// The keys a form names (`KEY=` words, wherever they stand).
fn keys_of(form: &str) -> BTreeSet<String> {
    let mut keys = BTreeSet::new();
    let bytes = form.as_bytes();
    for (i, _) in form.match_indices('=') {
        let start = bytes[..i]
            .iter()
            .rposition(|b| !(b.is_ascii_uppercase() || b.is_ascii_digit()))
            .map_or(0, |p| p + 1);
        if start < i && bytes[start].is_ascii_uppercase() {
            keys.insert(form[start..i].to_string());
        }
    }
    keys
}

/// The words of a form that stand alone (`TAPE END`'s `END`).
fn bare_words(form: &str) -> BTreeSet<String> {
    form.split_whitespace()
        .skip(1)
        .map(|w| w.trim_matches(|c| "[]()".contains(c)))
        .filter(|w| !w.is_empty() && !w.contains('=') && w.bytes().all(|b| b.is_ascii_uppercase()))
        .map(str::to_string)
        .collect()
}

/// A request line for a form: each key with a value, the bare words kept.
fn example(form: &str) -> String {
    let mut line = form.split_whitespace().next().unwrap_or("").to_string();
    for word in bare_words(form) {
        line.push(' ');
        line.push_str(&word);
    }
    for key in keys_of(form) {
        line.push_str(&format!(" {key}=1"));
    }
    line
}

#[test]
fn every_form_of_the_table_is_in_the_page_with_its_keys() {
    let spans: BTreeSet<String> = code_spans(&page()).into_iter().collect();
    for spec in &REQUESTS {
        let table: BTreeSet<String> = spec.keys().map(|k| k.to_string()).collect();
        let mut named = BTreeSet::new();
        for form in spec.command.forms() {
            assert!(
                spans.contains(*form),
                "docs/protocol.md does not write `{form}`"
            );
            assert_eq!(form.split_whitespace().next(), Some(spec.name()), "{form}");
            let keys = keys_of(form);
            assert!(
                keys.is_subset(&table),
                "`{form}` names keys {:?} that {} does not take",
                keys.difference(&table).collect::<Vec<_>>(),
                spec.name()
            );
            named.extend(keys);
            let bare = bare_words(form);
            let expected: BTreeSet<String> =
                spec.bare_word().iter().map(|w| w.to_string()).collect();
            assert!(
                bare.is_subset(&expected),
                "`{form}` has bare words {bare:?}"
            );
        }
        assert_eq!(
            named,
            table,
            "the forms of {} name other keys than it takes",
            spec.name()
        );
    }
}

#[test]
fn every_documented_form_parses_to_its_command() {
    for spec in &REQUESTS {
        for form in spec.command.forms() {
            // `WEAR (D= L= S= | KM=)`: either set, so one at a time.
            let line = example(&form.replace("| KM=", ""));
            match Request::parse(&line) {
                Ok(Request::Command(command, args)) => {
                    assert_eq!(command, spec.command, "{line}");
                    let given: BTreeSet<&str> = args.iter().map(|(k, _)| k).collect();
                    let wanted = keys_of(&form.replace("| KM=", ""));
                    let wanted: BTreeSet<&str> = wanted.iter().map(String::as_str).collect();
                    assert_eq!(given, wanted, "{line}");
                    assert_eq!(args.bare, !bare_words(form).is_empty(), "{line}");
                }
                other => panic!("`{line}` (from `{form}`) parsed to {other:?}"),
            }
            let lower = line.to_ascii_lowercase();
            assert!(
                matches!(Request::parse(&lower), Ok(Request::Command(c, _)) if c == spec.command),
                "`{lower}` is not {}",
                spec.name()
            );
        }
    }
}

#[test]
fn every_request_of_the_pages_tables_is_in_the_table() {
    let names: BTreeSet<&str> = REQUESTS.iter().map(|s| s.name()).collect();
    let mut seen: BTreeSet<String> = BTreeSet::new();
    // The rows of every table whose first column is headed `request`.
    let page = page();
    let mut rows = Vec::new();
    let mut in_table = false;
    for line in page.lines() {
        if line.starts_with("| request |") {
            in_table = true;
        } else if !line.starts_with('|') {
            in_table = false;
        } else if in_table && line.starts_with("| `") {
            rows.push(line);
        }
    }
    for row in rows {
        let Some(first) = code_spans(row).into_iter().next() else {
            continue;
        };
        let name = first.split_whitespace().next().unwrap_or("");
        assert!(
            names.contains(name),
            "docs/protocol.md has a request {name} no row of REQUESTS has"
        );
        let spec = REQUESTS.iter().find(|s| s.name() == name).unwrap();
        let table: BTreeSet<String> = spec.keys().map(|k| k.to_string()).collect();
        let keys = keys_of(&first);
        assert!(
            keys.is_subset(&table),
            "`{first}`: {keys:?} beyond {table:?}"
        );
        let line = example(&first.replace("| KM=", ""));
        assert!(
            matches!(Request::parse(&line), Ok(Request::Command(c, _)) if c == spec.command),
            "`{line}` does not parse"
        );
        seen.insert(name.to_string());
    }
    // The page's two request tables (section 4 and the calculators') hold
    // all but the commands it gives in their own sections.
    assert!(
        seen.len() >= 20,
        "only {} requests in the page's tables",
        seen.len()
    );
}

#[test]
fn a_command_the_table_lacks_is_unknown() {
    for line in ["HOMEX", "JOG X=1", "G", "MOVEX X=1", "VERS"] {
        assert!(
            !matches!(Request::parse(line), Ok(Request::Command(..))),
            "{line} parsed as a command"
        );
    }
}

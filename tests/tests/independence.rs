//! The references stand apart from the core (`docs/verification.md` §3.2):
//! nothing `reference` depends on, directly or through another crate, is
//! `core-nostd`. And where the two state the same fact, a list both keep,
//! they agree (§3.3): the protocol's error codes, in the core, in the
//! reference the oracles use, and in `docs/protocol.md` §10.

use core_nostd::protocol::ErrorCode;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// Every package `from` depends on (normal, build and dev dependencies,
/// transitively), read from `Cargo.lock`.
fn closure(lock: &str, from: &str) -> BTreeSet<String> {
    let mut deps: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for package in lock.split("[[package]]").skip(1) {
        let name = package
            .lines()
            .find_map(|l| l.strip_prefix("name = "))
            .map(|n| n.trim_matches('"').to_string())
            .expect("a package without a name");
        let mut list = Vec::new();
        if let Some(at) = package.find("dependencies = [") {
            for l in package[at..].lines().skip(1) {
                if l.starts_with(']') {
                    break;
                }
                // `"name"` or `"name version"`.
                let dep = l.trim().trim_end_matches(',').trim_matches('"');
                list.push(dep.split(' ').next().unwrap().to_string());
            }
        }
        deps.entry(name).or_default().extend(list);
    }
    assert!(deps.contains_key(from), "{from} is not in Cargo.lock");
    let mut seen = BTreeSet::new();
    let mut todo = vec![from.to_string()];
    while let Some(p) = todo.pop() {
        for d in deps.get(&p).into_iter().flatten() {
            if seen.insert(d.clone()) {
                todo.push(d.clone());
            }
        }
    }
    seen
}

#[test]
fn the_references_do_not_depend_on_the_core() {
    let lock = std::fs::read_to_string(root().join("Cargo.lock")).unwrap();
    let deps = closure(&lock, "reference");
    assert!(
        !deps.contains("core-nostd"),
        "reference depends on core-nostd: {deps:?}"
    );
    // The reading works: host-sim does depend on both.
    let host = closure(&lock, "host-sim");
    assert!(host.contains("core-nostd") && host.contains("reference"));
    let manifest = std::fs::read_to_string(root().join("reference/Cargo.toml")).unwrap();
    let declared: Vec<&str> = manifest
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .filter(|l| l.contains("core-nostd") || l.contains("core_nostd"))
        .collect();
    assert!(declared.is_empty(), "reference/Cargo.toml: {declared:?}");
}

/// The core's codes, every variant once; a variant added to the core and
/// not here stops this file from compiling (the `match` below).
const CORE: [ErrorCode; 11] = [
    ErrorCode::Checksum,
    ErrorCode::LineTooLong,
    ErrorCode::Empty,
    ErrorCode::Unknown,
    ErrorCode::Syntax,
    ErrorCode::Value,
    ErrorCode::Range,
    ErrorCode::Geometry,
    ErrorCode::Session,
    ErrorCode::Estop,
    ErrorCode::Alarm,
];

fn place(code: ErrorCode) -> usize {
    match code {
        ErrorCode::Checksum => 0,
        ErrorCode::LineTooLong => 1,
        ErrorCode::Empty => 2,
        ErrorCode::Unknown => 3,
        ErrorCode::Syntax => 4,
        ErrorCode::Value => 5,
        ErrorCode::Range => 6,
        ErrorCode::Geometry => 7,
        ErrorCode::Session => 8,
        ErrorCode::Estop => 9,
        ErrorCode::Alarm => 10,
    }
}

/// The upper-case words in backticks of a section of a page.
fn codes_in_section(page: &str, heading: &str) -> Vec<String> {
    let text = page
        .split("\n## ")
        .find(|s| s.starts_with(heading))
        .unwrap_or_else(|| panic!("no section {heading:?}"));
    text.split('`')
        .skip(1)
        .step_by(2)
        .filter(|w| !w.is_empty() && w.chars().all(|c| c.is_ascii_uppercase() || c == '_'))
        .map(str::to_string)
        .collect()
}

#[test]
fn the_error_codes_are_one_list() {
    for (i, c) in CORE.iter().enumerate() {
        assert_eq!(place(*c), i, "{c}");
    }
    let core: Vec<&str> = CORE.iter().map(|c| c.as_str()).collect();
    let reference = reference::protocol::ERROR_CODES;
    assert_eq!(core, reference, "the core's codes and the reference's");
    let page = std::fs::read_to_string(root().join("docs/protocol.md")).unwrap();
    assert_eq!(
        codes_in_section(&page, "10. Errors"),
        reference,
        "docs/protocol.md §10"
    );
    let minimum = codes_in_section(&page, "1. The required minimum");
    let n = reference::protocol::REQUIRED_ERROR_CODES;
    for code in &reference[..n] {
        assert!(minimum.contains(&code.to_string()), "§1 lacks {code}");
    }
    for code in &reference[n..] {
        assert!(
            !minimum.contains(&code.to_string()),
            "{code} is an extension"
        );
    }
}

//! The rules live in the repository (`docs/README.md` §3): nothing refers to
//! a document outside it, every citation `docs/<page>.md §N` names a page and
//! a section that exist, and every link of a Markdown page to a page of the
//! repository (and to a heading's anchor in it) finds its target.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Names of documents kept outside the repository, which nothing may cite.
/// Spelled in pieces so that this file does not cite them itself.
const OUTSIDE: [&str; 4] = [
    concat!("SPEC", ".md"),
    concat!("PROTOCOL", ".md"),
    concat!("../", "shared"),
    concat!("SPEC", " §"),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Whether a tracked path is left out of the checks: the corpus of
/// programs published by others is kept byte for byte, and installed
/// packages are not ours.
fn excluded(path: &str) -> bool {
    path.starts_with("tests/data/") || path.split('/').any(|p| p == "node_modules")
}

/// The files git tracks (relative to the root), else every file under the
/// root but build output and version control.
fn tracked_files() -> Vec<String> {
    let root = root();
    let out = Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(&root)
        .output();
    let mut files: Vec<String> = match out {
        Ok(o) if o.status.success() && !o.stdout.is_empty() => o
            .stdout
            .split(|&b| b == 0)
            .filter(|p| !p.is_empty())
            .map(|p| String::from_utf8_lossy(p).into_owned())
            .collect(),
        _ => {
            let mut all = Vec::new();
            walk(&root, &root, &mut all);
            all
        }
    };
    files.retain(|f| !excluded(f) && root.join(f).is_file());
    files.sort();
    files
}

fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name();
        let name = name.to_string_lossy();
        if p.is_dir() {
            if !matches!(
                name.as_ref(),
                ".git" | "target" | "node_modules" | "corpus" | "artifacts"
            ) {
                walk(root, &p, out);
            }
        } else {
            let rel = p.strip_prefix(root).unwrap().to_string_lossy();
            out.push(rel.replace('\\', "/"));
        }
    }
}

fn read(path: &str) -> String {
    String::from_utf8_lossy(&std::fs::read(root().join(path)).unwrap()).into_owned()
}

/// The section numbers of a page: every heading that begins with `N.`,
/// `N.M` …
fn sections(page: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in page.lines() {
        let Some(rest) = line.strip_prefix('#') else {
            continue;
        };
        let rest = rest.trim_start_matches('#');
        let Some(rest) = rest.strip_prefix(' ') else {
            continue;
        };
        let number: String = rest
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '.')
            .collect();
        let number = number.trim_end_matches('.');
        if !number.is_empty() && rest[number.len()..].starts_with(['.', ' ']) {
            out.insert(number.to_string());
        }
    }
    out
}

/// GitHub's anchors of a page's headings (`## 6. What `SYNC` reports` is
/// `6-what-sync-reports`), a repeated one numbered `-1`, `-2` ….
fn anchors(page: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    let mut fence = false;
    for line in page.lines() {
        if line.starts_with("```") {
            fence = !fence;
        }
        if fence || !line.starts_with('#') {
            continue;
        }
        let text = line.trim_start_matches('#').trim();
        let slug: String = text
            .to_lowercase()
            .chars()
            .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
            .map(|c| if c == ' ' { '-' } else { c })
            .collect();
        let n = seen.entry(slug.clone()).or_insert(0);
        out.insert(if *n == 0 {
            slug.clone()
        } else {
            format!("{slug}-{n}")
        });
        *n += 1;
    }
    out
}

/// A citation found in a file: the page as written, the section, the line.
#[derive(Debug)]
struct Citation {
    page: String,
    section: String,
    line: usize,
}

/// Every `page.md §N` (with `docs/` or not, the page in backticks or not),
/// and the sections listed after it (`§1, §2 and §3`, `§1–§3`).
fn citations(text: &str) -> Vec<Citation> {
    let mut out = Vec::new();
    for (no, line) in text.lines().enumerate() {
        let mut from = 0;
        while let Some(at) = line[from..].find(".md") {
            let end = from + at + 3;
            let name_start = line[..from + at]
                .rfind(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '/')))
                .map_or(0, |i| i + 1);
            let page = &line[name_start..end];
            from = end;
            let rest = line[end..].trim_start_matches('`');
            let Some(mut rest) = rest.strip_prefix(" §") else {
                continue;
            };
            loop {
                let number: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_digit() || *c == '.')
                    .collect();
                let number = number.trim_end_matches('.').to_string();
                if number.is_empty() {
                    break;
                }
                rest = &rest[number.len()..];
                out.push(Citation {
                    page: page.to_string(),
                    section: number,
                    line: no + 1,
                });
                // A list or a range of sections of the same page.
                let next = [", §", " and §", " or §", "–§", "-§", ", and §"]
                    .iter()
                    .find_map(|sep| rest.strip_prefix(sep));
                match next {
                    Some(r) => rest = r,
                    None => break,
                }
            }
        }
    }
    out
}

/// Markdown links `](target)` to a `.md` file, with their line.
fn md_links(text: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    for (no, line) in text.lines().enumerate() {
        let mut from = 0;
        while let Some(at) = line[from..].find("](") {
            let start = from + at + 2;
            let Some(len) = line[start..].find(')') else {
                break;
            };
            let target = &line[start..start + len];
            from = start + len;
            let file = target.split('#').next().unwrap_or("");
            if (file.ends_with(".md") || file.is_empty() && target.starts_with('#'))
                && !target.contains("://")
            {
                out.push((target.to_string(), no + 1));
            }
        }
    }
    out
}

/// `target` (relative to the directory of `from`) as a path from the root,
/// if it stays inside the repository.
fn resolve(from: &str, target: &str) -> Option<String> {
    let mut parts: Vec<&str> = from.split('/').collect();
    parts.pop();
    for p in target.split('/') {
        match p {
            "." | "" => {}
            ".." => {
                parts.pop()?;
            }
            _ => parts.push(p),
        }
    }
    Some(parts.join("/"))
}

#[test]
fn nothing_refers_to_a_document_outside_the_repository() {
    let mut found = Vec::new();
    for f in tracked_files() {
        for (no, line) in read(&f).lines().enumerate() {
            for n in OUTSIDE {
                if line.contains(n) {
                    found.push(format!("{f}:{}: {}", no + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "documents outside the repository are cited; cite docs/<page>.md §N instead:\n{}",
        found.join("\n")
    );
}

#[test]
fn every_citation_names_a_section_that_exists() {
    let files = tracked_files();
    let mut pages: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files
        .iter()
        .filter(|f| f.starts_with("docs/") && f.ends_with(".md"))
    {
        pages.insert(f.clone(), sections(&read(f)));
    }
    assert!(pages.len() >= 10, "docs/ holds {} pages", pages.len());
    for (page, s) in &pages {
        assert!(!s.is_empty(), "{page} has no numbered section");
    }
    let mut checked = 0;
    let mut bad = Vec::new();
    for f in &files {
        for c in citations(&read(f)) {
            // `docs/x.md`, or `x.md` from within docs/ (a page beside it)
            // and from anywhere else (the rules are all in docs/).
            let name = c.page.rsplit('/').next().unwrap();
            let page = format!("docs/{name}");
            if c.page.contains('/') && !c.page.ends_with(&page) {
                bad.push(format!(
                    "{f}:{}: {} §{}: only docs/ has numbered sections",
                    c.line, c.page, c.section
                ));
                continue;
            }
            match pages.get(&page) {
                None => bad.push(format!("{f}:{}: no page {page}", c.line)),
                Some(s) if !s.contains(&c.section) => bad.push(format!(
                    "{f}:{}: {page} has no §{} (it has §{})",
                    c.line,
                    c.section,
                    s.iter().cloned().collect::<Vec<_>>().join(", §")
                )),
                Some(_) => checked += 1,
            }
        }
    }
    assert!(
        bad.is_empty(),
        "citations of missing sections:\n{}",
        bad.join("\n")
    );
    assert!(checked > 100, "only {checked} citations found");
    println!("{checked} citations of docs/ sections checked");
}

#[test]
fn links_to_pages_and_headings_find_them() {
    let files = tracked_files();
    let mut bad = Vec::new();
    let mut checked = 0;
    for f in files.iter().filter(|f| f.ends_with(".md")) {
        for (target, line) in md_links(&read(f)) {
            let (file, anchor) = match target.split_once('#') {
                Some((file, a)) => (file, Some(a)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                Some(f.clone())
            } else {
                resolve(f, file)
            };
            let Some(path) = path.filter(|p| root().join(p).is_file()) else {
                bad.push(format!(
                    "{f}:{line}: {target}: no such file in the repository"
                ));
                continue;
            };
            if let Some(a) = anchor {
                if !anchors(&read(&path)).contains(a) {
                    bad.push(format!("{f}:{line}: {target}: no heading with that anchor"));
                    continue;
                }
            }
            checked += 1;
        }
    }
    assert!(bad.is_empty(), "broken links:\n{}", bad.join("\n"));
    println!("{checked} links checked");
}

#[test]
fn the_readers_read_what_they_should() {
    let page = "# T\n\n## 1. One\n### 1.2 Two `X`\n## 10. Ten (ext)\n```\n# not\n```\n## Plain\n";
    assert_eq!(
        sections(page).into_iter().collect::<Vec<_>>(),
        ["1", "1.2", "10"]
    );
    let a = anchors(page);
    for want in ["t", "1-one", "12-two-x", "10-ten-ext", "plain"] {
        assert!(a.contains(want), "{want} in {a:?}");
    }
    let c = citations(
        "see docs/impulses.md §2.3 and `docs/arcs.md` §1, §2 and §3; [units.md §3.1](units.md), x.md",
    );
    let got: Vec<_> = c
        .iter()
        .map(|c| format!("{} {}", c.page, c.section))
        .collect();
    assert_eq!(
        got,
        [
            "docs/impulses.md 2.3",
            "docs/arcs.md 1",
            "docs/arcs.md 2",
            "docs/arcs.md 3",
            "units.md 3.1"
        ]
    );
    assert_eq!(
        md_links("[a](units.md#1-axes) [b](https://x.md) [c](#x)"),
        [("units.md#1-axes".to_string(), 1), ("#x".to_string(), 1)]
    );
    assert_eq!(
        resolve("docs/a.md", "../README.md").as_deref(),
        Some("README.md")
    );
    assert_eq!(resolve("README.md", "../x.md"), None);
}

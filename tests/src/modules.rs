//! The module-level import graph of a crate's `src` tree, and its cycles.
//!
//! A module is a file (`a.rs` or `a/mod.rs` is `a`, `a/b.rs` is `a::b`, the
//! crate root `lib.rs` or `main.rs` is `crate`); inline modules (`mod tests
//! { … }`) belong to their file. An edge `a → b` is a path in `a` that names
//! something in `b`: `use crate::b::…`, `super::…`, `self::…`, a child
//! module's name at the head of a path (`b::Item`, `use b::…`), in a `use`
//! or anywhere in the code, `use` groups (`crate::{b::X, c::Y}`) expanded.
//! Comments, strings and `$crate` paths of macros are not read. A `mod b;`
//! declaration is not an edge. Code inside `#[cfg(test)]` modules, and files
//! named `tests.rs`, give *test* edges, kept apart: the layering is that of
//! the code the crate ships.
//!
//! Binaries are crates of their own: `src/bin/` is left out, and so is
//! `main.rs` when the tree also has a `lib.rs`.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// The crate root's module name.
pub const ROOT: &str = "crate";

/// Where an edge comes from: a file and a line (1-based).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Site {
    /// The file, relative to the `src` directory.
    pub file: PathBuf,
    /// The line of the path.
    pub line: usize,
}

/// The import graph of one crate.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    /// Every module, `crate` included.
    pub modules: BTreeSet<String>,
    /// Edges of the shipped code, with every place that makes them.
    pub edges: BTreeMap<(String, String), Vec<Site>>,
    /// Edges made only by test code.
    pub test_edges: BTreeMap<(String, String), Vec<Site>>,
}

impl Graph {
    /// Reads every module of the crate whose sources are in `src`.
    pub fn of_crate(src: &Path) -> io::Result<Graph> {
        let mut files = Vec::new();
        collect(src, src, &mut files)?;
        let has_lib = src.join("lib.rs").exists();
        let separate_crate =
            |f: &Path| f.starts_with("bin") || has_lib && f == Path::new("main.rs");
        files.retain(|f| !separate_crate(f));
        files.sort();
        let mut graph = Graph::default();
        let named: Vec<(PathBuf, String)> = files
            .into_iter()
            .map(|f| {
                let m = module_of(&f);
                (f, m)
            })
            .collect();
        graph.modules = named.iter().map(|(_, m)| m.clone()).collect();
        for (file, module) in &named {
            let text = fs::read_to_string(src.join(file))?;
            let test_file = file.file_name().is_some_and(|n| n == "tests.rs");
            for r in paths_in(&text) {
                let Some(target) = graph.resolve(module, r.inline_depth, &r.segments) else {
                    continue;
                };
                if &target == module {
                    continue;
                }
                let site = Site {
                    file: file.clone(),
                    line: r.line,
                };
                let map = if r.test || test_file {
                    &mut graph.test_edges
                } else {
                    &mut graph.edges
                };
                map.entry((module.clone(), target)).or_default().push(site);
            }
        }
        // An edge the shipped code makes is not also a test edge.
        let shipped: BTreeSet<_> = graph.edges.keys().cloned().collect();
        graph.test_edges.retain(|k, _| !shipped.contains(k));
        Ok(graph)
    }

    /// The module a path written in `module` (inside `inline_depth` inline
    /// modules of its file) names, if it names one of this crate's.
    fn resolve(&self, module: &str, inline_depth: usize, segments: &[String]) -> Option<String> {
        let head = segments.first()?;
        let (mut at, rest): (String, &[String]) = match head.as_str() {
            "crate" => (ROOT.to_string(), &segments[1..]),
            "self" => (module.to_string(), &segments[1..]),
            "super" => {
                let supers = segments.iter().take_while(|s| *s == "super").count();
                let mut at = module.to_string();
                // The first `super`s leave the inline modules, within the file.
                for _ in 0..supers.saturating_sub(inline_depth) {
                    at = parent(&at)?;
                }
                (at, &segments[supers..])
            }
            // A child module named at the head of a path.
            _ if self.modules.contains(&child(module, head)) => {
                (child(module, head), &segments[1..])
            }
            _ => return None,
        };
        for seg in rest {
            let next = child(&at, seg);
            if !self.modules.contains(&next) {
                break;
            }
            at = next;
        }
        Some(at)
    }

    /// The strongly connected components of more than one module: the
    /// cycles of the shipped code (`with_tests`: of the code and its tests).
    pub fn cycles(&self, with_tests: bool) -> Vec<Vec<String>> {
        let mut adj: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
        let edges = self
            .edges
            .keys()
            .chain(self.test_edges.keys().filter(|_| with_tests));
        for (a, b) in edges {
            adj.entry(a.as_str()).or_default().push(b.as_str());
        }
        let nodes: Vec<&str> = self.modules.iter().map(String::as_str).collect();
        let mut comps = tarjan(&nodes, &adj);
        comps.retain(|c| c.len() > 1);
        for c in &mut comps {
            c.sort();
        }
        comps.sort();
        comps
            .into_iter()
            .map(|c| c.into_iter().map(str::to_string).collect())
            .collect()
    }

    /// The edges between the modules of `component`, with their first site,
    /// one per line (`a -> b  (file:line)`).
    pub fn describe(&self, component: &[String], with_tests: bool) -> String {
        let inside = |a: &String, b: &String| component.contains(a) && component.contains(b);
        let mut out = String::new();
        let tagged = self.edges.iter().map(|e| (e, "")).chain(
            self.test_edges
                .iter()
                .filter(|_| with_tests)
                .map(|e| (e, " [test]")),
        );
        for (((a, b), sites), tag) in tagged {
            if inside(a, b) {
                let s = &sites[0];
                let more = if sites.len() > 1 {
                    format!(" and {} more", sites.len() - 1)
                } else {
                    String::new()
                };
                out += &format!(
                    "  {a} -> {b}  ({}:{}{more}){tag}\n",
                    s.file.display(),
                    s.line
                );
            }
        }
        out
    }
}

fn child(module: &str, name: &str) -> String {
    if module == ROOT {
        name.to_string()
    } else {
        format!("{module}::{name}")
    }
}

fn parent(module: &str) -> Option<String> {
    if module == ROOT {
        None
    } else {
        Some(
            module
                .rsplit_once("::")
                .map_or(ROOT.to_string(), |(p, _)| p.to_string()),
        )
    }
}

fn collect(src: &Path, dir: &Path, out: &mut Vec<PathBuf>) -> io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            collect(src, &path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path.strip_prefix(src).unwrap().to_path_buf());
        }
    }
    Ok(())
}

/// `a/b.rs` → `a::b`, `a/mod.rs` → `a`, `lib.rs`/`main.rs` → `crate`.
fn module_of(file: &Path) -> String {
    let mut parts: Vec<String> = file
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if parts.last().is_some_and(|l| l == "mod") {
        parts.pop();
    }
    if parts.len() == 1 && (parts[0] == "lib" || parts[0] == "main") {
        parts.clear();
    }
    if parts.is_empty() {
        ROOT.to_string()
    } else {
        parts.join("::")
    }
}

/// One path read from a file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PathRef {
    /// The segments, `crate`, `self` and `super` included.
    pub segments: Vec<String>,
    /// The line it starts on (1-based).
    pub line: usize,
    /// How many inline modules of the file it is written in.
    pub inline_depth: usize,
    /// Whether it is in a `#[cfg(test)]` module.
    pub test: bool,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Tok {
    Ident(String),
    /// `::`
    Sep,
    Open,
    Close,
    Comma,
    Star,
    Semi,
    /// `#[cfg(test)]`
    CfgTest,
    /// `$` (a macro's `$crate`)
    Dollar,
    Other(char),
}

/// Every path of `text` that begins with an identifier followed by `::`,
/// `use` groups expanded.
pub fn paths_in(text: &str) -> Vec<PathRef> {
    let toks = tokens(&strip(text));
    // Inline modules: (brace depth inside them, is test).
    let mut inline: Vec<(usize, bool)> = Vec::new();
    let mut depth = 0usize;
    let mut pending_test = false;
    let mut out = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        let (tok, line) = &toks[i];
        match tok {
            Tok::CfgTest => pending_test = true,
            Tok::Open => depth += 1,
            Tok::Close => {
                if inline.last().is_some_and(|&(d, _)| d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            Tok::Semi => pending_test = false,
            Tok::Ident(w) if w == "mod" => {
                if let (Some((Tok::Ident(_), _)), Some((Tok::Open, _))) =
                    (toks.get(i + 1), toks.get(i + 2))
                {
                    let test = pending_test || inline.last().is_some_and(|&(_, t)| t);
                    depth += 1;
                    inline.push((depth, test));
                    pending_test = false;
                    i += 3;
                    continue;
                }
            }
            Tok::Ident(w) if w == "fn" || w == "struct" || w == "impl" || w == "enum" => {
                pending_test = false;
            }
            Tok::Ident(_) => {
                let after_sep = i > 0 && matches!(toks[i - 1].0, Tok::Sep | Tok::Dollar);
                // `pub(in a::b)` restricts who sees an item: it names a
                // module without using anything in it.
                let visibility = i >= 3
                    && matches!(&toks[i - 1].0, Tok::Ident(w) if w == "in")
                    && toks[i - 2].0 == Tok::Other('(')
                    && matches!(&toks[i - 3].0, Tok::Ident(w) if w == "pub");
                if visibility {
                    let mut j = i;
                    while j < toks.len() && toks[j].0 != Tok::Other(')') {
                        j += 1;
                    }
                    i = j;
                    continue;
                }
                if !after_sep && matches!(toks.get(i + 1), Some((Tok::Sep, _))) {
                    let test = inline.last().is_some_and(|&(_, t)| t);
                    let mut trees = Vec::new();
                    let end = use_tree(&toks, i, Vec::new(), &mut trees);
                    for segments in trees {
                        out.push(PathRef {
                            segments,
                            line: *line,
                            inline_depth: inline.len(),
                            test,
                        });
                    }
                    i = end.max(i + 1);
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// Reads a use tree (or a plain path) from `toks[i]`, appending every full
/// path to `out`; returns the index after it.
fn use_tree(
    toks: &[(Tok, usize)],
    mut i: usize,
    prefix: Vec<String>,
    out: &mut Vec<Vec<String>>,
) -> usize {
    let mut path = prefix;
    loop {
        match toks.get(i).map(|t| &t.0) {
            Some(Tok::Ident(w)) => {
                if w == "self" && !path.is_empty() {
                    // `a::{self, …}` names `a`.
                } else {
                    path.push(w.clone());
                }
                i += 1;
            }
            Some(Tok::Star) => {
                i += 1;
                break;
            }
            Some(Tok::Open) => {
                i += 1;
                loop {
                    match toks.get(i).map(|t| &t.0) {
                        Some(Tok::Close) => return i + 1,
                        Some(Tok::Comma) => i += 1,
                        Some(Tok::Ident(_)) | Some(Tok::Star) | Some(Tok::Open) => {
                            i = use_tree(toks, i, path.clone(), out);
                        }
                        None => return i,
                        Some(_) => i += 1,
                    }
                }
            }
            _ => break,
        }
        if matches!(toks.get(i).map(|t| &t.0), Some(Tok::Sep)) {
            i += 1;
        } else {
            break;
        }
    }
    // `as name` ends the tree.
    if let Some((Tok::Ident(w), _)) = toks.get(i) {
        if w == "as" {
            i += 2;
        }
    }
    if !path.is_empty() {
        out.push(path);
    }
    i
}

fn tokens(code: &str) -> Vec<(Tok, usize)> {
    let chars: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut line = 1;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let w: String = chars[start..i].iter().collect();
            // `r#ident`
            out.push((Tok::Ident(w.trim_start_matches("r#").to_string()), line));
        } else if c == ':' && chars.get(i + 1) == Some(&':') {
            out.push((Tok::Sep, line));
            i += 2;
        } else if c == '#' && chars.get(i + 1) == Some(&'[') {
            let rest: String = chars[i..chars.len().min(i + 40)].iter().collect();
            let compact: String = rest.chars().filter(|c| !c.is_whitespace()).collect();
            if compact.starts_with("#[cfg(test)]") {
                out.push((Tok::CfgTest, line));
                // Skip to the closing bracket.
                while i < chars.len() && chars[i] != ']' {
                    i += 1;
                }
                i += 1;
            } else {
                out.push((Tok::Other('#'), line));
                i += 1;
            }
        } else {
            out.push((
                match c {
                    '{' => Tok::Open,
                    '}' => Tok::Close,
                    ',' => Tok::Comma,
                    '*' => Tok::Star,
                    ';' => Tok::Semi,
                    '$' => Tok::Dollar,
                    _ => Tok::Other(c),
                },
                line,
            ));
            i += 1;
        }
    }
    out
}

/// `text` with comments, string and character literals blanked (newlines
/// kept, so that lines still count).
pub fn strip(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let blank = |ch: char, out: &mut String| out.push(if ch == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            let mut nest = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    nest += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    nest -= 1;
                    out.push_str("  ");
                    i += 2;
                    if nest == 0 {
                        break;
                    }
                } else {
                    blank(c[i], &mut out);
                    i += 1;
                }
            }
        } else if let Some(hashes) = raw_string_start(&c, i) {
            // r"…", r#"…"#, br"…": up to the quote and as many hashes.
            let open = i + (c[i] == 'b') as usize + 1 + hashes + 1;
            for &ch in &c[i..open] {
                blank(ch, &mut out);
            }
            i = open;
            while i < c.len() {
                if c[i] == '"' && (0..hashes).all(|k| c.get(i + 1 + k) == Some(&'#')) {
                    for _ in 0..=hashes {
                        out.push(' ');
                    }
                    i += 1 + hashes;
                    break;
                }
                blank(c[i], &mut out);
                i += 1;
            }
        } else if c[i] == '"' {
            out.push(' ');
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    blank(c[i], &mut out);
                    i += 1;
                }
                if i < c.len() {
                    blank(c[i], &mut out);
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c[i] == '\'' {
            // A character literal ('x', '\n', '\u{..}'), else a lifetime.
            let end = if c.get(i + 1) == Some(&'\\') {
                (i + 3..c.len().min(i + 13)).find(|&k| c[k] == '\'')
            } else if c.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    for &ch in &c[i..=e] {
                        blank(ch, &mut out);
                    }
                    i = e + 1;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The number of `#` of a raw string starting at `i`, if one does.
fn raw_string_start(c: &[char], i: usize) -> Option<usize> {
    let prev_ident = i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
    if prev_ident {
        return None;
    }
    let mut k = i;
    if c.get(k) == Some(&'b') {
        k += 1;
    }
    if c.get(k) != Some(&'r') {
        return None;
    }
    k += 1;
    let mut hashes = 0;
    while c.get(k) == Some(&'#') {
        hashes += 1;
        k += 1;
    }
    (c.get(k) == Some(&'"')).then_some(hashes)
}

/// Tarjan's strongly connected components.
fn tarjan<'a>(nodes: &[&'a str], adj: &BTreeMap<&'a str, Vec<&'a str>>) -> Vec<Vec<&'a str>> {
    struct State<'a> {
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        on_stack: BTreeSet<&'a str>,
        stack: Vec<&'a str>,
        next: usize,
        comps: Vec<Vec<&'a str>>,
    }
    fn visit<'a>(v: &'a str, adj: &BTreeMap<&'a str, Vec<&'a str>>, s: &mut State<'a>) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on_stack.insert(v);
        for &w in adj.get(v).map(Vec::as_slice).unwrap_or(&[]) {
            if !s.index.contains_key(w) {
                visit(w, adj, s);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                comp.push(w);
                if w == v {
                    break;
                }
            }
            s.comps.push(comp);
        }
    }
    let mut s = State {
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        on_stack: BTreeSet::new(),
        stack: Vec::new(),
        next: 0,
        comps: Vec::new(),
    };
    for &n in nodes {
        if !s.index.contains_key(n) {
            visit(n, adj, &mut s);
        }
    }
    s.comps
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heads(text: &str) -> Vec<String> {
        paths_in(text)
            .into_iter()
            .map(|p| p.segments.join("::"))
            .collect()
    }

    #[test]
    fn paths_and_groups() {
        assert_eq!(
            heads("use crate::{a::{X, self}, b::Y as Z};\nuse super::*;"),
            ["crate::a::X", "crate::a", "crate::b::Y", "super"]
        );
        assert_eq!(
            heads("let x = crate::dd::Dd::from_i128(3); // crate::no\n\"crate::no\""),
            ["crate::dd::Dd::from_i128"]
        );
        assert_eq!(heads("$crate::x::y; std::fmt::Write"), ["std::fmt::Write"]);
        assert_eq!(
            heads("fn f<'a>(c: char) -> bool { c == '\"' && x::y() }"),
            ["x::y"]
        );
        assert_eq!(
            heads("r#\"crate::a\"# ; b\"crate::a\""),
            Vec::<String>::new()
        );
        // A visibility names a module without using it; a loop's range is
        // a use.
        assert_eq!(
            heads("pub(in crate::a) fn f() { for x in crate::b::g() {} }"),
            ["crate::b::g"]
        );
    }

    #[test]
    fn inline_and_test_modules() {
        let p = paths_in("use a::X;\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::b;\n}\nuse c::Y;");
        let seen: Vec<_> = p
            .iter()
            .map(|p| (p.segments.join("::"), p.line, p.inline_depth, p.test))
            .collect();
        assert_eq!(
            seen,
            [
                ("a::X".to_string(), 1, 0, false),
                ("super".to_string(), 4, 1, true),
                ("crate::b".to_string(), 5, 1, true),
                ("c::Y".to_string(), 7, 0, false),
            ]
        );
    }

    #[test]
    fn components() {
        let nodes = ["a", "b", "c", "d"];
        let mut adj = BTreeMap::new();
        adj.insert("a", vec!["b"]);
        adj.insert("b", vec!["a", "c"]);
        adj.insert("c", vec!["d"]);
        let mut comps: Vec<Vec<&str>> = tarjan(&nodes, &adj)
            .into_iter()
            .filter(|c| c.len() > 1)
            .collect();
        comps[0].sort();
        assert_eq!(comps, [vec!["a", "b"]]);
    }
}

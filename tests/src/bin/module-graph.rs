//! Lists the module-level import edges of a crate's `src` tree and its
//! cycles: `cargo run -p tests --bin module-graph -- core-nostd/src [--tests]`.
//! Exits with status 1 when the shipped code has a cycle (with `--tests`:
//! when the code and its tests have one).

use std::path::PathBuf;
use std::process::ExitCode;
use tests::modules::Graph;

fn main() -> ExitCode {
    let mut with_tests = false;
    let mut dirs = Vec::new();
    for a in std::env::args().skip(1) {
        match a.as_str() {
            "--tests" => with_tests = true,
            "-h" | "--help" => {
                println!("usage: module-graph SRC_DIR... [--tests]");
                return ExitCode::SUCCESS;
            }
            _ => dirs.push(PathBuf::from(a)),
        }
    }
    if dirs.is_empty() {
        eprintln!("usage: module-graph SRC_DIR... [--tests]");
        return ExitCode::from(2);
    }
    let mut cyclic = false;
    for dir in dirs {
        let g = match Graph::of_crate(&dir) {
            Ok(g) => g,
            Err(e) => {
                eprintln!("{}: {e}", dir.display());
                return ExitCode::from(2);
            }
        };
        println!("{}: {} modules", dir.display(), g.modules.len());
        let tagged = g.edges.iter().map(|e| (e, "")).chain(
            g.test_edges
                .iter()
                .filter(|_| with_tests)
                .map(|e| (e, " [test]")),
        );
        for (((a, b), sites), tag) in tagged {
            let s = &sites[0];
            println!("  {a} -> {b}  ({}:{}){tag}", s.file.display(), s.line);
        }
        let cycles = g.cycles(with_tests);
        if cycles.is_empty() {
            println!("{}: no cycle", dir.display());
        }
        for c in &cycles {
            cyclic = true;
            println!("{}: cycle among {}", dir.display(), c.join(", "));
            print!("{}", g.describe(c, with_tests));
        }
    }
    if cyclic {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

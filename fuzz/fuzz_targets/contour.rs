//! G41/G42 contours: sequences of G-code blocks built from the words of nose
//! radius compensation (`G40`–`G42`, `G450`/`G451`, `G00`–`G03`, `X Z I K R`,
//! `N`) with arbitrary numbers, a random nose radius and tip code, and
//! `RESET` now and then, on one device.
//!
//! Every request is checked by `fuzz_oracle::Checker` (one final line, an
//! `ERR` moves nothing and changes no state, registers hold `Q(P/h)` of the
//! commanded point, reported motion and step events agree). Besides: a
//! G-code block never answers `ERR UNKNOWN`, and `RESET` always succeeds and
//! leaves compensation off, so that `MOVE` is accepted again.
#![no_main]

use arbitrary::Arbitrary;
use fuzz_oracle::Checker;
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
struct Block {
    n: Option<u16>,
    comp: Option<u8>,
    corner: Option<bool>,
    motion: Option<u8>,
    x: Option<i32>,
    z: Option<i32>,
    ik: Option<(i32, i32)>,
    r: Option<i32>,
    reset: bool,
}

#[derive(Arbitrary, Debug)]
struct Program {
    rn: u16,
    tip: u8,
    blocks: Vec<Block>,
}

/// Thousandths of a millimetre as a word value, within ±500 mm.
fn mm(v: i32) -> String {
    let v = v % 500_000;
    let sign = if v < 0 { "-" } else { "" };
    let a = v.unsigned_abs();
    format!("{sign}{}.{:03}", a / 1000, a % 1000)
}

fuzz_target!(|p: Program| {
    let mut checker = Checker::new(fuzz_oracle::fuzz_device());
    let cfg = format!("CFG RN={} TIP={}", mm(i32::from(p.rn % 3000)), p.tip % 10);
    assert!(checker.line(&cfg, true).err().is_none());
    for b in p.blocks.iter().take(64) {
        if b.reset {
            let a = checker.line("RESET", true);
            assert!(a.err().is_none(), "RESET: {}", a.last());
            let a = checker.line("MOVE", true);
            assert!(a.err().is_none(), "MOVE after RESET: {}", a.last());
            continue;
        }
        let mut w = Vec::new();
        if let Some(n) = b.n {
            w.push(format!("N{n}"));
        }
        if let Some(c) = b.comp {
            w.push(format!("G{}", 40 + c % 3));
        }
        if let Some(c) = b.corner {
            w.push(if c { "G450".into() } else { "G451".into() });
        }
        if let Some(m) = b.motion {
            w.push(format!("G0{}", m % 4));
        }
        if let Some(x) = b.x {
            w.push(format!("X{}", mm(x)));
        }
        if let Some(z) = b.z {
            w.push(format!("Z{}", mm(z)));
        }
        if let Some((i, k)) = b.ik {
            w.push(format!("I{} K{}", mm(i), mm(k)));
        }
        if let Some(r) = b.r {
            w.push(format!("R{}", mm(r)));
        }
        if w.is_empty() {
            continue;
        }
        let line = w.join(" ");
        let a = checker.line(&line, true);
        assert!(
            !a.err().is_some_and(|e| e.starts_with("UNKNOWN")),
            "{line}: {}",
            a.last()
        );
    }
});

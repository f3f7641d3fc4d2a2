//! Arbitrary synchronised passes (`docs/threading.md`) into
//! `core_nostd::sync`, over the whole of its ranges.
//!
//! - a pass is accepted or refused as the exact reference (`reference::sync`)
//!   decides, for the same reason, when it lies within the reference's
//!   ranges;
//! - the events of an accepted pass come at strictly ascending counts after
//!   its first count and no later than its last, each moves every stepping
//!   axis one impulse towards its end, and the pass ends on the registers of
//!   its end point;
//! - when the pass has at most 20 000 counts, the events equal the
//!   reference's, count for count and register for register.
#![no_main]

use arbitrary::Arbitrary;
use core_nostd::impulse::ImpulsePrice;
use core_nostd::length::Length;
use core_nostd::sync::{SyncError, SyncPass, MAX_CPR, MAX_LEAD, MAX_LEAD_IN, MAX_TRAVEL};
use libfuzzer_sys::fuzz_target;
use reference::sync::{Pass, Refusal};

#[derive(Arbitrary, Debug)]
struct Input {
    x0: i64,
    z0: i64,
    dx: i64,
    dz: i64,
    hx: u32,
    hz: u32,
    lead: u64,
    cpr: u32,
    half: u32,
    /// Small values: passes short enough to compare with the reference.
    small: bool,
}

/// At most this many events are followed through.
const EVENTS: usize = 20_000;

fuzz_target!(|i: Input| {
    let wrap = |v: i64, m: i64| v.rem_euclid(2 * m + 1) - m;
    let (span, lead_max, cpr_max, half_max) = if i.small {
        (20_000_000, 20_000_000u64, 4096u32, 2000u32)
    } else {
        (MAX_TRAVEL, MAX_LEAD as u64, MAX_CPR, MAX_LEAD_IN / 2)
    };
    let x0 = wrap(i.x0, 10_000_000_000);
    let z0 = wrap(i.z0, 10_000_000_000);
    let (dx, dz) = (wrap(i.dx, span), wrap(i.dz, span));
    let hx = 10 + i64::from(i.hx % 9_999_991);
    let hz = 10 + i64::from(i.hz % 9_999_991);
    let lead = 1 + (i.lead % lead_max) as i64;
    let cpr = 1 + i.cpr % cpr_max;
    let lead_in = 2 * (1 + i.half % half_max);
    let len = |a: i64| Length::from_angstrom(a).unwrap();
    let price = |a: i64| ImpulsePrice::from_length(len(a)).unwrap();
    let pass = SyncPass::new(
        (len(x0), len(z0)),
        (len(x0 + dx), len(z0 + dz)),
        (price(hx), price(hz)),
        len(lead),
        cpr,
        lead_in,
    );
    let r = Pass {
        x0,
        z0,
        x1: x0 + dx,
        z1: z0 + dz,
        hx,
        hz,
        lead,
        cpr: i64::from(cpr),
        lead_in: i64::from(lead_in),
    };
    let in_reference = lead <= reference::sync::LEAD_MAX
        && i64::from(lead_in) <= reference::sync::LEAD_IN_MAX
        && hx <= reference::sync::PRICE_MAX
        && hz <= reference::sync::PRICE_MAX
        && [r.x0, r.z0, r.x1, r.z1]
            .iter()
            .all(|v| v.abs() <= reference::sync::COORD_MAX);
    let p = match pass {
        Ok(p) => p,
        Err(e) => {
            if in_reference {
                let want = reference::sync::events(&r).err();
                let same = match (e, want) {
                    (SyncError::NoTravel, Some(Refusal::NoTravel)) => true,
                    (SyncError::TooCoarse { axis: a }, Some(Refusal::TooCoarse { axis: b })) => {
                        a == b
                    }
                    (SyncError::TooShort { needed }, Some(Refusal::TooShort { needed: b })) => {
                        needed.as_angstrom() == b
                    }
                    // A need beyond any length (10⁵ mm) is out of range.
                    (SyncError::Range, Some(Refusal::TooShort { needed: b })) => {
                        b > core_nostd::length::LENGTH_LIMIT.as_angstrom()
                    }
                    _ => false,
                };
                assert!(same, "core {e:?}, reference {want:?}: {r:?}");
            }
            return;
        }
    };
    let (mut x, mut z) = p.start_registers();
    let (x1, z1) = p.end_registers();
    let mut last = p.first_count();
    let mut got = Vec::new();
    let mut all = true;
    for (n, (c, e)) in p.events().enumerate() {
        if n == EVENTS {
            all = false;
            break;
        }
        assert!(
            c > last && c <= p.last_count(),
            "count {c} after {last}: {r:?}"
        );
        last = c;
        let (ex, ez) = e.moves();
        assert!(ex != 0 || ez != 0, "{r:?}");
        assert!(
            i64::from(ex) == 0 || i64::from(ex) == (x1 - x).signum(),
            "{r:?}"
        );
        assert!(
            i64::from(ez) == 0 || i64::from(ez) == (z1 - z).signum(),
            "{r:?}"
        );
        x += i64::from(ex);
        z += i64::from(ez);
        got.push((c, x, z));
    }
    if all {
        assert_eq!((x, z), (x1, z1), "{r:?}");
        if in_reference && p.last_count() - p.first_count() <= 20_000 {
            let want = reference::sync::events(&r).expect("the reference accepts it");
            assert_eq!(got, want, "{r:?}");
        }
    }
});

//! The tool table, the work offsets, the stored reference positions, the
//! machine's M codes, how lines are read (dialect, block delete, optional
//! stop) and the switches' wiring as a record in two flash slots, so that
//! they survive a power cut, one during a write included.
//!
//! A record is whole 32-bit words: a magic word, a sequence number, the
//! payload's length, the payload, and last the CRC-32 of all before it. A
//! save goes to the slot that does not hold the newest whole record: it is
//! erased (all ones), the record is programmed word by word, and the CRC
//! word last. Until that word is in, the slot's CRC fails and a load takes
//! the other slot, whose record is the one before; once it is in, the new
//! record is whole and newer. Flash programming only clears bits, so a
//! word cut half-way is wrong, never right by chance (beyond the CRC's
//! 2⁻³²).
//!
//! A record whose values are out of their ranges is refused as a broken
//! one would be.

use crate::crc32::Crc32;
use crate::interp::{MAction, Offsets, Reading, ToolEntry, MCODES, TOOL_REGISTERS, WORK_SYSTEMS};
use crate::length::Length;

/// `LTO6`: the record of this layout (the table, the offsets, the
/// stored positions, the machine's M codes, how lines are read, the
/// switches' wiring, the homing cycle's settings, the backlash).
const MAGIC: u32 = u32::from_le_bytes(*b"LTO6");
/// `LTO5`: the layout before the backlash, still read (none).
const MAGIC_5: u32 = u32::from_le_bytes(*b"LTO5");
/// `LTO4`: the layout before the homing settings, still read (no axis
/// homed).
const MAGIC_4: u32 = u32::from_le_bytes(*b"LTO4");
/// `LTO3`: the layout before the wiring, still read (nothing wired).
const MAGIC_3: u32 = u32::from_le_bytes(*b"LTO3");
/// `LTO2`: the layout before the reading, still read (read as at
/// power-on: ISO, both switches off).
const MAGIC_2: u32 = u32::from_le_bytes(*b"LTO2");
/// `LTO1`: the layout before the M codes, still read (its M code table
/// empty).
const MAGIC_1: u32 = u32::from_le_bytes(*b"LTO1");

/// Lengths in the payload: work offsets (X, Z), per register geometry,
/// wear, nose radius (-1: none) and tip code, and the two stored
/// positions.
const LENGTHS: usize = WORK_SYSTEMS * 2 + TOOL_REGISTERS * 6 + 2 * 2;

/// Values after them in `LTO2`: per M code slot its code (tenths, 0
/// empty) and its action.
const MCODE_VALUES: usize = MCODES * 2;

/// The homing settings' values: their flags, seek, locate, pull-off, and
/// per axis home and travel.
const HOMING_VALUES: usize = 8;

/// Per axis its backlash.
const BACKLASH_VALUES: usize = 2;

/// Payload words: two per value, the reading's bits
/// ([`crate::interp::Reading::bits`]), the wiring, the homing and the
/// backlash last.
const PAYLOAD_WORDS: usize = (LENGTHS + MCODE_VALUES + 2 + HOMING_VALUES + BACKLASH_VALUES) * 2;
/// Those of an `LTO5` record.
const PAYLOAD_WORDS_5: usize = (LENGTHS + MCODE_VALUES + 2 + HOMING_VALUES) * 2;
/// Those of an `LTO4` record.
const PAYLOAD_WORDS_4: usize = (LENGTHS + MCODE_VALUES + 2) * 2;
/// Those of an `LTO3` record.
const PAYLOAD_WORDS_3: usize = (LENGTHS + MCODE_VALUES + 1) * 2;
/// Those of an `LTO2` record.
const PAYLOAD_WORDS_2: usize = (LENGTHS + MCODE_VALUES) * 2;
/// Those of an `LTO1` record.
const PAYLOAD_WORDS_1: usize = LENGTHS * 2;

/// Words of a whole record: magic, sequence, length, payload, CRC.
pub const RECORD_WORDS: usize = 3 + PAYLOAD_WORDS + 1;

/// An M code's action as a value: 1 nothing, 10 + n / 20 + n output `n`
/// off / on, 30 + n / 40 + n wait for input `n` low / high.
const fn action_value(a: MAction) -> i64 {
    match a {
        MAction::Stop => 0,
        MAction::Nothing => 1,
        MAction::Output(n, on) => (if on { 20 } else { 10 }) + n as i64,
        MAction::Wait(n, high) => (if high { 40 } else { 30 }) + n as i64,
    }
}

fn value_action(v: i64) -> Option<MAction> {
    let n = (v % 10) as u8;
    match v {
        1 => Some(MAction::Nothing),
        11..=14 | 21..=24 => Some(MAction::Output(n, v > 20)),
        31..=34 | 41..=44 => Some(MAction::Wait(n, v > 40)),
        _ => None,
    }
}

/// Two slots of flash, each erasable on its own and at least
/// [`RECORD_WORDS`] words long.
pub trait Flash {
    /// The word at `index` of `slot` (0 or 1).
    fn read(&mut self, slot: usize, index: usize) -> u32;
    /// Sets every word of `slot` to all ones.
    fn erase(&mut self, slot: usize);
    /// Programs the word at `index` of `slot`, which is erased (bits only
    /// go from 1 to 0).
    fn program(&mut self, slot: usize, index: usize, word: u32);
}

/// The values a record keeps (the shift of `G92` is not among them: as on
/// a Fanuc, it does not outlive a power cycle).
fn lengths(o: &Offsets) -> impl Iterator<Item = i64> + '_ {
    let work = o
        .work
        .iter()
        .flat_map(|w| w.iter().map(|l| l.as_angstrom()));
    let tools = o.tools.iter().flat_map(|t| {
        let (radius, tip) = match t.nose {
            Some((r, tip)) => (r.as_angstrom(), i64::from(tip)),
            None => (-1, -1),
        };
        [
            t.geometry[0].as_angstrom(),
            t.geometry[1].as_angstrom(),
            t.wear[0].as_angstrom(),
            t.wear[1].as_angstrom(),
            radius,
            tip,
        ]
    });
    let reference = o
        .reference
        .iter()
        .flat_map(|p| p.iter().map(|l| l.as_angstrom()));
    let mut slots = [(0i64, 0i64); MCODES];
    for (slot, (code, action)) in slots.iter_mut().zip(o.mcodes.entries()) {
        *slot = (i64::from(code), action_value(action));
    }
    let mcodes = slots.into_iter().flat_map(|(c, a)| [c, a]);
    let reading = core::iter::once(i64::from(o.reading.bits()));
    let w = o.wiring;
    let wiring =
        core::iter::once(i64::from(w.used) | i64::from(w.invert) << 16 | i64::from(w.filter) << 32);
    let h = o.homing;
    // Per axis: bit 0 it homes, bit 1 towards minus.
    let axis = |a: crate::homing::AxisHoming| i64::from(a.homes) | i64::from(a.dir < 0) << 1;
    let flags = axis(h.axes[0])
        | axis(h.axes[1]) << 2
        | i64::from(h.z_first) << 4
        | i64::from(h.required) << 5
        | i64::from(h.soft) << 6
        | i64::from(h.jog_clip) << 7
        // The wheel: bits 8-9 its axis (0 off, 1 X, 2 Z), 10-11 its scale
        // (0 ×1, 1 ×10, 2 ×100), from bit 12 its feed.
        | i64::from(h.wheel.axis.map_or(0, |a| a + 1)) << 8
        | i64::from(match h.wheel.scale {
            100 => 2u8,
            10 => 1,
            _ => 0,
        }) << 10
        | i64::from(h.wheel.feed) << 12;
    let homing = [
        flags,
        i64::from(h.seek),
        i64::from(h.locate),
        h.pulloff.as_angstrom(),
        h.axes[0].home.as_angstrom(),
        h.axes[1].home.as_angstrom(),
        h.axes[0].travel.as_angstrom(),
        h.axes[1].travel.as_angstrom(),
    ];
    let backlash = [
        h.axes[0].backlash.as_angstrom(),
        h.axes[1].backlash.as_angstrom(),
    ];
    work.chain(tools)
        .chain(reference)
        .chain(mcodes)
        .chain(reading)
        .chain(wiring)
        .chain(homing)
        .chain(backlash)
}

/// The words of the record of `offsets` with sequence number `seq`,
/// without its CRC.
fn body(offsets: &Offsets, seq: u32) -> impl Iterator<Item = u32> + '_ {
    let header = [MAGIC, seq, (PAYLOAD_WORDS * 4) as u32];
    let payload = lengths(offsets).flat_map(|v| {
        let v = v as u64;
        [v as u32, (v >> 32) as u32]
    });
    header.into_iter().chain(payload)
}

fn crc_of(words: impl Iterator<Item = u32>) -> u32 {
    let mut crc = Crc32::new();
    for w in words {
        crc.update(&w.to_le_bytes());
    }
    crc.finish()
}

/// The payload words of the layout a slot's record says it has.
fn layout<F: Flash>(flash: &mut F, slot: usize) -> Option<usize> {
    match (flash.read(slot, 0), flash.read(slot, 2)) {
        (MAGIC, n) if n == (PAYLOAD_WORDS * 4) as u32 => Some(PAYLOAD_WORDS),
        (MAGIC_5, n) if n == (PAYLOAD_WORDS_5 * 4) as u32 => Some(PAYLOAD_WORDS_5),
        (MAGIC_4, n) if n == (PAYLOAD_WORDS_4 * 4) as u32 => Some(PAYLOAD_WORDS_4),
        (MAGIC_3, n) if n == (PAYLOAD_WORDS_3 * 4) as u32 => Some(PAYLOAD_WORDS_3),
        (MAGIC_2, n) if n == (PAYLOAD_WORDS_2 * 4) as u32 => Some(PAYLOAD_WORDS_2),
        (MAGIC_1, n) if n == (PAYLOAD_WORDS_1 * 4) as u32 => Some(PAYLOAD_WORDS_1),
        _ => None,
    }
}

/// The sequence number of the whole record in `slot`, if it holds one.
fn sequence<F: Flash>(flash: &mut F, slot: usize) -> Option<u32> {
    let words = 3 + layout(flash, slot)? + 1;
    let crc = crc_of((0..words - 1).map(|i| flash.read(slot, i)));
    (crc == flash.read(slot, words - 1)).then(|| flash.read(slot, 1))
}

/// What a load found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Loaded {
    /// The offsets (all zero when no record was whole).
    pub offsets: Offsets,
    /// The record's sequence number (0: none).
    pub seq: u32,
}

/// The offsets of the newest whole record whose values are in range (the
/// other slot's when the newest one's are not), or all zero (power-on)
/// when there is none.
pub fn load<F: Flash>(flash: &mut F) -> Loaded {
    match current(flash) {
        Some((_, seq, offsets)) => Loaded { offsets, seq },
        None => Loaded {
            offsets: Offsets::ZERO,
            seq: 0,
        },
    }
}

/// The slot, sequence number and offsets of the record a load takes.
fn current<F: Flash>(flash: &mut F) -> Option<(usize, u32, Offsets)> {
    let slots = match (sequence(flash, 0), sequence(flash, 1)) {
        (Some(a), Some(b)) if b.wrapping_sub(a) as i32 > 0 => [Some((1, b)), Some((0, a))],
        (a, b) => [a.map(|a| (0, a)), b.map(|b| (1, b))],
    };
    slots
        .into_iter()
        .flatten()
        .find_map(|(slot, seq)| Some((slot, seq, decode(flash, slot)?)))
}

/// The offsets of the whole record in `slot`, if every value is in range.
fn decode<F: Flash>(flash: &mut F, slot: usize) -> Option<Offsets> {
    let words = layout(flash, slot);
    let with_mcodes = matches!(
        words,
        Some(PAYLOAD_WORDS | PAYLOAD_WORDS_5 | PAYLOAD_WORDS_4 | PAYLOAD_WORDS_3 | PAYLOAD_WORDS_2)
    );
    let with_reading = matches!(
        words,
        Some(PAYLOAD_WORDS | PAYLOAD_WORDS_5 | PAYLOAD_WORDS_4 | PAYLOAD_WORDS_3)
    );
    let with_wiring = matches!(
        words,
        Some(PAYLOAD_WORDS | PAYLOAD_WORDS_5 | PAYLOAD_WORDS_4)
    );
    let with_homing = matches!(words, Some(PAYLOAD_WORDS | PAYLOAD_WORDS_5));
    let with_backlash = words == Some(PAYLOAD_WORDS);
    let mut i = 3;
    let mut next = || {
        let lo = u64::from(flash.read(slot, i));
        let hi = u64::from(flash.read(slot, i + 1));
        i += 2;
        (hi << 32 | lo) as i64
    };
    let mut o = Offsets::ZERO;
    for w in o.work.iter_mut().flatten() {
        *w = Length::from_angstrom(next())?;
    }
    for t in o.tools.iter_mut() {
        let mut l = [Length::ZERO; 4];
        for v in l.iter_mut() {
            *v = Length::from_angstrom(next())?;
        }
        let nose = match (next(), next()) {
            (-1, -1) => None,
            (r, tip @ 0..=9) if (0..=250_000_000).contains(&r) => {
                Some((Length::from_angstrom(r)?, tip as u8))
            }
            _ => return None,
        };
        *t = ToolEntry {
            geometry: [l[0], l[1]],
            wear: [l[2], l[3]],
            nose,
        };
    }
    for p in o.reference.iter_mut().flatten() {
        *p = Length::from_angstrom(next())?;
    }
    if with_mcodes {
        for _ in 0..MCODES {
            let (code, action) = (next(), next());
            if code == 0 {
                continue;
            }
            let code = u16::try_from(code)
                .ok()
                .filter(|c| c % 10 == 0 && *c <= 9990)?;
            if !o.mcodes.set(code, value_action(action)?) {
                return None;
            }
        }
    }
    if with_reading {
        o.reading = u8::try_from(next()).ok().and_then(Reading::from_bits)?;
    }
    if with_wiring {
        let v = next();
        let inputs = (1i64 << crate::inputs::INPUTS) - 1;
        let filter = v >> 32;
        if v & !(inputs | inputs << 16 | 0xFF << 32) != 0
            || filter > i64::from(crate::inputs::MAX_FILTER)
        {
            return None;
        }
        o.wiring = crate::inputs::InputConfig {
            used: (v & 0xFFFF) as u16,
            invert: (v >> 16 & 0xFFFF) as u16,
            filter: filter as u8,
        };
    }
    if with_homing {
        let flags = next();
        if flags & !0xFFFF_FFFF_FFFF != 0 {
            return None;
        }
        let rate = |v: i64| u32::try_from(v).ok();
        let mut h = crate::homing::HomingConfig::NONE;
        for (i, a) in h.axes.iter_mut().enumerate() {
            let bits = flags >> (2 * i);
            a.homes = bits & 1 != 0;
            a.dir = if bits & 2 != 0 { -1 } else { 1 };
        }
        h.z_first = flags & 16 != 0;
        h.required = flags & 32 != 0;
        h.soft = flags & 64 != 0;
        h.jog_clip = flags & 128 != 0;
        h.wheel = crate::homing::Wheel {
            axis: match flags >> 8 & 3 {
                0 => None,
                a => Some(a as u8 - 1),
            },
            scale: match flags >> 10 & 3 {
                0 => 1,
                1 => 10,
                2 => 100,
                _ => return None,
            },
            feed: u32::try_from(flags >> 12).ok()?,
        };
        h.seek = rate(next())?;
        h.locate = rate(next())?;
        h.pulloff = Length::from_angstrom(next())?;
        h.axes[0].home = Length::from_angstrom(next())?;
        h.axes[1].home = Length::from_angstrom(next())?;
        h.axes[0].travel = Length::from_angstrom(next())?;
        h.axes[1].travel = Length::from_angstrom(next())?;
        if with_backlash {
            h.axes[0].backlash = Length::from_angstrom(next())?;
            h.axes[1].backlash = Length::from_angstrom(next())?;
        }
        if !h.valid() {
            return None;
        }
        o.homing = h;
    }
    Some(o)
}

/// Saves `offsets` as the record after `last` (the sequence number a load
/// or the previous save returned), into the slot that does not hold the
/// record a load takes now; returns the new sequence number.
pub fn save<F: Flash>(flash: &mut F, offsets: &Offsets, last: u32) -> u32 {
    let slot = match current(flash) {
        Some((0, ..)) => 1,
        _ => 0,
    };
    let seq = last.wrapping_add(1);
    flash.erase(slot);
    for (i, w) in body(offsets, seq).enumerate() {
        flash.program(slot, i, w);
    }
    // The CRC last: only now is the record whole.
    flash.program(slot, RECORD_WORDS - 1, crc_of(body(offsets, seq)));
    seq
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// NOR flash in RAM: erase to ones, programming only clears bits;
    /// `cut` words programmed before the power goes (the rest of the save
    /// does nothing).
    #[derive(Clone)]
    struct Nor {
        slots: [Vec<u32>; 2],
        cut: Option<usize>,
        erase_cut: bool,
    }

    impl Nor {
        fn new() -> Nor {
            Nor {
                slots: [
                    std::vec![0; RECORD_WORDS + 8],
                    std::vec![0; RECORD_WORDS + 8],
                ],
                cut: None,
                erase_cut: false,
            }
        }
        fn powered(&mut self) -> bool {
            match &mut self.cut {
                Some(0) => false,
                Some(n) => {
                    *n -= 1;
                    true
                }
                None => true,
            }
        }
    }

    impl Flash for Nor {
        fn read(&mut self, slot: usize, index: usize) -> u32 {
            self.slots[slot][index]
        }
        fn erase(&mut self, slot: usize) {
            if self.erase_cut {
                // Cut half-way through the erase: some words ones, the
                // rest as they were.
                let half = self.slots[slot].len() / 2;
                self.slots[slot][..half].fill(u32::MAX);
                self.cut = Some(0);
                return;
            }
            self.slots[slot].fill(u32::MAX);
        }
        fn program(&mut self, slot: usize, index: usize, word: u32) {
            if self.powered() {
                self.slots[slot][index] &= word;
            }
        }
    }

    fn l(mm: &str) -> Length {
        Length::from_mm_str(mm).unwrap()
    }

    fn table(k: i64) -> Offsets {
        let mut o = Offsets::ZERO;
        o.work[1] = [l("1.5"), Length::from_angstrom(-1_234_567 * k).unwrap()];
        o.tools[0].geometry = [l("-12.25"), Length::from_angstrom(30_000_001).unwrap()];
        o.tools[0].wear = [l("0.01"), Length::from_angstrom(k).unwrap()];
        o.tools[0].nose = Some((l("0.4"), 3));
        o.tools[31].nose = Some((l("25"), 9));
        o.reference[1] = [l("99999.999999"), l("-99999.999999")];
        o.shift = [l("7"), l("8")];
        o.mcodes.set(160, MAction::Output(2, true));
        o.mcodes.set(310, MAction::Wait(4, false));
        o.mcodes.set(260 + 10 * (k as u16 % 3), MAction::Nothing);
        o.reading = Reading::from_bits(k as u8 % 8).unwrap();
        o.wiring = crate::inputs::InputConfig {
            used: 0x7FF >> (k % 3),
            invert: 1 | (k as u16 % 4) << 9,
            filter: (k * 7 % 101) as u8,
        };
        o.homing.axes[0] = crate::homing::AxisHoming {
            homes: k % 2 == 1,
            dir: if k % 3 == 0 { -1 } else { 1 },
            home: Length::from_angstrom(-3_000_000 * k).unwrap(),
            travel: l("120.5"),
            backlash: Length::from_angstrom(100_000 * k).unwrap(),
        };
        o.homing.axes[1].homes = true;
        o.homing.axes[1].travel = l("400");
        o.homing.seek = 1_000 * k as u32;
        o.homing.pulloff = l("0.5");
        o.homing.z_first = k % 2 == 0;
        o.homing.required = k % 3 == 0;
        o.homing.soft = k % 4 == 1;
        o.homing.jog_clip = k % 2 == 0;
        o.homing.wheel = crate::homing::Wheel {
            axis: [None, Some(0), Some(1)][(k % 3) as usize],
            scale: [1, 10, 100][(k % 3) as usize],
            feed: 20_000_000 - k as u32,
        };
        o
    }

    /// Writes `table(k)` into `slot` as a record of an older layout,
    /// `magic`, holding its first `values` values with sequence number
    /// `seq`; checks that it loads with what that layout lacked as at
    /// power-on (`lacked`), then that `table(again)` saved over it loads in
    /// this layout, and returns that.
    fn older_layout(
        k: i64,
        (magic, values): (u32, usize),
        (slot, seq): (usize, u32),
        lacked: fn(&mut Offsets),
        again: i64,
    ) -> Offsets {
        let mut f = Nor::new();
        let mut o = table(k);
        write_old(&mut f, slot, magic, seq, lengths(&o).take(values));
        lacked(&mut o);
        assert_eq!(
            load(&mut f),
            Loaded {
                offsets: kept(&o),
                seq
            }
        );
        let next = save(&mut f, &table(again), seq);
        let got = load(&mut f);
        assert_eq!((got.offsets, got.seq), (kept(&table(again)), next));
        got.offsets
    }

    #[test]
    fn records_of_the_older_layouts_still_load() {
        // LTO1, as the firmware before the M codes wrote it: the lengths
        // only.
        older_layout(
            1,
            (MAGIC_1, LENGTHS),
            (0, 7),
            |o| {
                o.mcodes = crate::interp::MCodes::new();
                o.reading = Reading::DEFAULT;
                o.wiring = crate::inputs::InputConfig::NONE;
                o.homing = crate::homing::HomingConfig::NONE;
            },
            2,
        );
        // LTO2: the lengths and the M codes; read as at power-on, ISO with
        // both switches off. Saved again, the reading comes back.
        assert_eq!(table(7).reading.bits(), 7);
        let got = older_layout(
            7,
            (MAGIC_2, LENGTHS + MCODE_VALUES),
            (1, 9),
            |o| {
                o.reading = Reading::DEFAULT;
                o.wiring = crate::inputs::InputConfig::NONE;
                o.homing = crate::homing::HomingConfig::NONE;
            },
            5,
        );
        assert_eq!(got.reading.bits(), 5);
        // LTO3: up to the reading; nothing wired.
        let got = older_layout(
            4,
            (MAGIC_3, LENGTHS + MCODE_VALUES + 1),
            (0, 11),
            |o| {
                o.wiring = crate::inputs::InputConfig::NONE;
                o.homing = crate::homing::HomingConfig::NONE;
            },
            4,
        );
        assert_ne!(got.wiring, crate::inputs::InputConfig::NONE);
        // LTO4: up to the wiring; no axis homed.
        let got = older_layout(
            3,
            (MAGIC_4, LENGTHS + MCODE_VALUES + 2),
            (1, 12),
            |o| o.homing = crate::homing::HomingConfig::NONE,
            3,
        );
        assert!(got.homing.required);
        // LTO5: up to the homing; no backlash.
        let got = older_layout(
            5,
            (MAGIC_5, LENGTHS + MCODE_VALUES + 2 + HOMING_VALUES),
            (0, 14),
            |o| {
                for a in o.homing.axes.iter_mut() {
                    a.backlash = Length::ZERO;
                }
            },
            6,
        );
        assert_eq!(
            got.homing.axes[0].backlash,
            Length::from_mm_str("0.06").unwrap()
        );
    }

    #[test]
    fn a_backlash_beyond_5_mm_or_below_0_is_a_broken_record() {
        for bad in [50_000_001i64, -1] {
            let mut f = Nor::new();
            let seq = save(&mut f, &table(1), 0);
            save(&mut f, &table(2), seq);
            let last = RECORD_WORDS - 1;
            let at = last - 2;
            f.slots[1][at] = bad as u64 as u32;
            f.slots[1][at + 1] = ((bad as u64) >> 32) as u32;
            f.slots[1][last] = crc_of(f.slots[1][..last].iter().copied());
            assert_eq!(load(&mut f).offsets, kept(&table(1)), "{bad}");
        }
    }

    #[test]
    fn homing_settings_out_of_range_are_a_broken_record() {
        // The flags' word (a bit beyond them), the seek (0), the pull-off
        // (0), a travel beyond 10 m: each refused, the older record loads.
        for (index, bad) in [(0, 256i64), (1, 0), (3, 0), (6, 100_001_000_000)] {
            let mut f = Nor::new();
            let seq = save(&mut f, &table(1), 0);
            save(&mut f, &table(2), seq);
            let last = RECORD_WORDS - 1;
            let at = last - 2 * (HOMING_VALUES + BACKLASH_VALUES) + 2 * index;
            f.slots[1][at] = bad as u64 as u32;
            f.slots[1][at + 1] = ((bad as u64) >> 32) as u32;
            f.slots[1][last] = crc_of(f.slots[1][..last].iter().copied());
            assert_eq!(load(&mut f).offsets, kept(&table(1)), "{index} {bad}");
        }
    }

    #[test]
    fn a_wiring_beyond_its_inputs_or_filter_is_a_broken_record() {
        for bad in [1i64 << 11, 1 << 27, 101 << 32, 1 << 40] {
            let mut f = Nor::new();
            let seq = save(&mut f, &table(1), 0);
            save(&mut f, &table(2), seq);
            let last = RECORD_WORDS - 1;
            let at = last - 2 * (HOMING_VALUES + BACKLASH_VALUES) - 2;
            f.slots[1][at] = bad as u64 as u32;
            f.slots[1][at + 1] = ((bad as u64) >> 32) as u32;
            f.slots[1][last] = crc_of(f.slots[1][..last].iter().copied());
            assert_eq!(load(&mut f).offsets, kept(&table(1)), "{bad:#x}");
        }
    }

    #[test]
    fn a_reading_beyond_its_three_bits_is_a_broken_record() {
        let mut f = Nor::new();
        let seq = save(&mut f, &table(1), 0);
        let seq = save(&mut f, &table(2), seq);
        // The newer record (slot 1) with the reading's word set to 8 and
        // its CRC made whole: refused, the older one loads.
        let last = RECORD_WORDS - 1;
        f.slots[1][last - 2 * (HOMING_VALUES + BACKLASH_VALUES) - 4] = 8;
        f.slots[1][last] = crc_of(f.slots[1][..last].iter().copied());
        assert_eq!(sequence(&mut f, 1), Some(seq));
        assert_eq!(load(&mut f).offsets, kept(&table(1)));
    }

    /// Writes into `slot` a whole record of an older layout, `magic`, with
    /// sequence number `seq` and these values, as the firmware of that
    /// layout wrote it.
    fn write_old(
        f: &mut Nor,
        slot: usize,
        magic: u32,
        seq: u32,
        values: impl Iterator<Item = i64>,
    ) {
        let mut words = std::vec![magic, seq, 0];
        for v in values {
            words.extend([v as u64 as u32, ((v as u64) >> 32) as u32]);
        }
        words[2] = ((words.len() - 3) * 4) as u32;
        words.push(crc_of(words.iter().copied()));
        f.slots[slot][..words.len()].copy_from_slice(&words);
    }

    fn kept(o: &Offsets) -> Offsets {
        Offsets {
            shift: [Length::ZERO; 2],
            kept_shift: [Length::ZERO; 2],
            ..*o
        }
    }

    #[test]
    fn a_blank_or_foreign_flash_loads_power_on() {
        let mut f = Nor::new();
        assert_eq!(
            load(&mut f),
            Loaded {
                offsets: Offsets::ZERO,
                seq: 0
            }
        );
        f.slots[0].fill(u32::MAX);
        f.slots[1].fill(u32::MAX);
        assert_eq!(load(&mut f).seq, 0);
    }

    #[test]
    fn what_is_saved_loads_back_and_saves_alternate() {
        let mut f = Nor::new();
        let mut seq = load(&mut f).seq;
        for k in 1..=5 {
            seq = save(&mut f, &table(k), seq);
            assert_eq!(seq, k as u32);
            let got = load(&mut f);
            assert_eq!(
                got,
                Loaded {
                    offsets: kept(&table(k)),
                    seq
                }
            );
        }
        // Both slots hold whole records: the newer wins, and it lies in
        // the slot the last save wrote (5 is odd: slot 0).
        assert_eq!(sequence(&mut f, 0), Some(5));
        assert_eq!(sequence(&mut f, 1), Some(4));
    }

    #[test]
    fn a_power_cut_at_any_word_of_a_save_leaves_the_old_record_or_the_new() {
        let mut f = Nor::new();
        let mut seq = save(&mut f, &table(1), 0);
        seq = save(&mut f, &table(2), seq);
        let (old, new) = (kept(&table(2)), kept(&table(3)));
        let mut saw = [0; 2];
        for cut in 0..=RECORD_WORDS {
            let mut g = f.clone();
            g.cut = Some(cut);
            save(&mut g, &table(3), seq);
            g.cut = None;
            let got = load(&mut g);
            if cut < RECORD_WORDS {
                assert_eq!(got, Loaded { offsets: old, seq }, "cut after {cut} words");
                saw[0] += 1;
            } else {
                assert_eq!(
                    got,
                    Loaded {
                        offsets: new,
                        seq: seq + 1
                    }
                );
                saw[1] += 1;
            }
            // The next save after the cut goes on from what was loaded.
            let next = save(&mut g, &table(4), got.seq);
            assert_eq!(load(&mut g).offsets, kept(&table(4)));
            assert_eq!(next, got.seq + 1);
        }
        assert_eq!(saw, [RECORD_WORDS, 1]);
        // Cut during the erase.
        let mut g = f.clone();
        g.erase_cut = true;
        save(&mut g, &table(3), seq);
        assert_eq!(load(&mut g), Loaded { offsets: old, seq });
    }

    #[test]
    fn a_flipped_bit_or_a_value_out_of_range_is_refused() {
        let mut f = Nor::new();
        let seq = save(&mut f, &table(1), 0);
        let seq = save(&mut f, &table(2), seq);
        // Slot 1 holds the newest (seq 2): a bit cleared in it falls back.
        for index in [0, 1, 2, 3, 100, RECORD_WORDS - 1] {
            let mut g = f.clone();
            g.slots[1][index] ^= 1 << (index % 32);
            assert_eq!(load(&mut g).offsets, kept(&table(1)), "word {index}");
        }
        // A tip code of 10 with a CRC that fits: refused all the same.
        let mut g = f.clone();
        let tip_word = 3 + (WORK_SYSTEMS * 2 + 5) * 2;
        assert_eq!(g.slots[1][tip_word], 3);
        let mut words: Vec<u32> = (0..RECORD_WORDS - 1).map(|i| g.slots[1][i]).collect();
        words[tip_word] = 10;
        g.slots[1][tip_word] = 10;
        g.slots[1][RECORD_WORDS - 1] = crc_of(words.into_iter());
        assert_eq!(sequence(&mut g, 1), Some(seq));
        assert_eq!(
            load(&mut g),
            Loaded {
                offsets: kept(&table(1)),
                seq: seq - 1
            }
        );
    }
}

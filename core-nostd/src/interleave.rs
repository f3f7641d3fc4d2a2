//! Step-event interleaving of a linear block (`docs/impulses.md` §3.1, a decided rule).
//!
//! A block goes from impulse position `(a0, b0)` to `(a1, b1)`. The leading
//! axis is the one with the larger `|Δ|`, X when equal. For `i = 1 … |Δlead|`
//! event `i` steps the leading axis once and puts the other axis at
//! `b0 + Q(i·Δb/|Δlead|)` (`Q` half away from zero); the other axis steps in
//! that event when the value changed, never by more than one.
//!
//! [`StepEvents`] produces the events one at a time with integer additions and
//! comparisons only (no division, no multiplication), so a timer interrupt can
//! pull the next event in constant time. It is exact: with `L = |Δlead|`,
//! `D = |Δb|`, `Q(i·D/L) = ⌊(2iD + L) / 2L⌋`, and the iterator keeps the
//! remainder of that numerator modulo `2L`.

use crate::impulse::{Impulses, RangeError, MAX_BLOCK_IMPULSES};

/// One step event: which axes step and in which direction.
///
/// The byte layout is the one the `SEQ` CRC of the line protocol covers:
/// bit0 X steps, bit1 Z steps, bit2 X steps in the negative direction, bit3 Z
/// steps in the negative direction (a direction bit is 0 for an axis that does
/// not step).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepEvent(u8);

impl StepEvent {
    /// X steps.
    pub const X_STEP: u8 = 0b0001;
    /// Z steps.
    pub const Z_STEP: u8 = 0b0010;
    /// X steps towards negative.
    pub const X_NEG: u8 = 0b0100;
    /// Z steps towards negative.
    pub const Z_NEG: u8 = 0b1000;

    /// An event from its protocol byte (the caller keeps the layout).
    pub(crate) const fn from_bits(bits: u8) -> StepEvent {
        StepEvent(bits)
    }

    /// The protocol byte of the event.
    pub const fn bits(self) -> u8 {
        self.0
    }
    /// Whether X steps in this event.
    pub const fn x_steps(self) -> bool {
        self.0 & Self::X_STEP != 0
    }
    /// Whether Z steps in this event.
    pub const fn z_steps(self) -> bool {
        self.0 & Self::Z_STEP != 0
    }
    /// Whether an X step goes towards negative.
    pub const fn x_negative(self) -> bool {
        self.0 & Self::X_NEG != 0
    }
    /// Whether a Z step goes towards negative.
    pub const fn z_negative(self) -> bool {
        self.0 & Self::Z_NEG != 0
    }

    /// How the event moves the registers: −1, 0 or 1 impulse per axis.
    #[inline(always)]
    pub const fn moves(self) -> (i8, i8) {
        MOVES[(self.0 & 0x0F) as usize]
    }
}

/// [`StepEvent::moves`] by the event's four bits.
const MOVES: [(i8, i8); 16] = {
    let mut t = [(0i8, 0i8); 16];
    let mut b = 0;
    while b < 16 {
        let sx = if b & 4 != 0 { -1 } else { 1 };
        let sz = if b & 8 != 0 { -1 } else { 1 };
        t[b] = (
            if b & 1 != 0 { sx } else { 0 },
            if b & 2 != 0 { sz } else { 0 },
        );
        b += 1;
    }
    t
};

/// An impulse position of the two axes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImpulsePoint {
    /// X on the radius.
    pub x: Impulses,
    /// Z.
    pub z: Impulses,
}

/// A validated linear block between two impulse positions, at most
/// [`MAX_BLOCK_IMPULSES`] per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinearBlock {
    from: ImpulsePoint,
    to: ImpulsePoint,
}

impl LinearBlock {
    /// A block from `from` to `to`, or [`RangeError`] when an axis would move
    /// more than [`MAX_BLOCK_IMPULSES`].
    ///
    /// ```
    /// use core_nostd::impulse::Impulses;
    /// use core_nostd::interleave::{ImpulsePoint, LinearBlock};
    /// let p = |x, z| ImpulsePoint { x: Impulses(x), z: Impulses(z) };
    /// let b = LinearBlock::new(p(0, 0), p(2, -1)).unwrap();
    /// let bits: Vec<u8> = b.events().map(|e| e.bits()).collect();
    /// assert_eq!(bits, [0b1011, 0b0001]); // Z at Q(-1/2) = -1 already: ties step early
    /// assert!(LinearBlock::new(p(0, 0), p(1_000_001, 0)).is_err());
    /// ```
    pub fn new(from: ImpulsePoint, to: ImpulsePoint) -> Result<LinearBlock, RangeError> {
        let dx = i64::from(to.x.0) - i64::from(from.x.0);
        let dz = i64::from(to.z.0) - i64::from(from.z.0);
        if dx.unsigned_abs() > u64::from(MAX_BLOCK_IMPULSES)
            || dz.unsigned_abs() > u64::from(MAX_BLOCK_IMPULSES)
        {
            return Err(RangeError);
        }
        Ok(LinearBlock { from, to })
    }

    /// Start position.
    pub const fn from(&self) -> ImpulsePoint {
        self.from
    }

    /// End position.
    pub const fn to(&self) -> ImpulsePoint {
        self.to
    }

    /// Impulses issued on X (radius) and Z.
    pub const fn delta(&self) -> (i32, i32) {
        // Both within MAX_BLOCK_IMPULSES by construction.
        (self.to.x.0 - self.from.x.0, self.to.z.0 - self.from.z.0)
    }

    /// The step events, one at a time.
    pub fn events(&self) -> StepEvents {
        let (dx, dz) = self.delta();
        let (ax, az) = (dx.unsigned_abs(), dz.unsigned_abs());
        let lead_is_x = ax >= az;
        let (lead, other) = if lead_is_x { (ax, az) } else { (az, ax) };
        let x_bits = if dx < 0 {
            StepEvent::X_STEP | StepEvent::X_NEG
        } else {
            StepEvent::X_STEP
        };
        let z_bits = if dz < 0 {
            StepEvent::Z_STEP | StepEvent::Z_NEG
        } else {
            StepEvent::Z_STEP
        };
        let (lead_bits, other_bits) = if lead_is_x {
            (x_bits, z_bits)
        } else {
            (z_bits, x_bits)
        };
        StepEvents {
            remaining: lead,
            lead_bits,
            other_bits,
            twice_lead: 2 * lead,
            twice_other: 2 * other,
            rem: lead,
        }
    }
}

/// The step events of a [`LinearBlock`], produced with integer additions only.
#[derive(Clone, Debug)]
pub struct StepEvents {
    remaining: u32,
    lead_bits: u8,
    other_bits: u8,
    twice_lead: u32,
    twice_other: u32,
    /// `(2iD + L) mod 2L`, always `< 2L`.
    rem: u32,
}

impl StepEvents {
    /// The events after the first `done`, at most `count` of them: the
    /// rest of a block from where a hold stopped it (closed form, no
    /// iteration).
    pub fn part(mut self, done: u32, count: u32) -> StepEvents {
        let done = done.min(self.remaining);
        if done > 0 && self.twice_lead > 0 {
            let r = u64::from(self.rem) + u64::from(done) * u64::from(self.twice_other);
            // Below twice_lead: fits the u32.
            self.rem = (r % u64::from(self.twice_lead)) as u32;
        }
        self.remaining = (self.remaining - done).min(count);
        self
    }
}

impl Iterator for StepEvents {
    type Item = StepEvent;

    #[inline(always)]
    fn next(&mut self) -> Option<StepEvent> {
        if self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        // rem < 2L and 2D ≤ 2L ≤ 2·MAX_BLOCK_IMPULSES: no overflow in u32.
        self.rem += self.twice_other;
        let mut bits = self.lead_bits;
        if self.rem >= self.twice_lead {
            self.rem -= self.twice_lead;
            bits |= self.other_bits;
        }
        Some(StepEvent(bits))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.remaining as usize;
        (n, Some(n))
    }
}

impl ExactSizeIterator for StepEvents {}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    fn p(x: i32, z: i32) -> ImpulsePoint {
        ImpulsePoint {
            x: Impulses(x),
            z: Impulses(z),
        }
    }

    #[test]
    fn an_event_moves_the_registers_by_its_bits() {
        for b in 0u8..16 {
            let e = StepEvent(b);
            let d = |steps: bool, negative: bool| match (steps, negative) {
                (false, _) => 0,
                (true, false) => 1,
                (true, true) => -1,
            };
            assert_eq!(
                e.moves(),
                (
                    d(e.x_steps(), e.x_negative()),
                    d(e.z_steps(), e.z_negative())
                ),
                "{b:#06b}"
            );
        }
        assert_eq!(StepEvent(0b1011).moves(), (1, -1));
    }

    fn bits(from: ImpulsePoint, to: ImpulsePoint) -> Vec<u8> {
        LinearBlock::new(from, to)
            .unwrap()
            .events()
            .map(StepEvent::bits)
            .collect()
    }

    /// The rule written with a division per event, as `docs/impulses.md` §3.1 states it.
    fn by_definition(from: ImpulsePoint, to: ImpulsePoint) -> Vec<u8> {
        let (dx, dz) = (i64::from(to.x.0 - from.x.0), i64::from(to.z.0 - from.z.0));
        let lead_x = dx.abs() >= dz.abs();
        let (dl, db) = if lead_x { (dx, dz) } else { (dz, dx) };
        let l = dl.abs();
        let q = |n: i64, d: i64| {
            // Q(n/d), d > 0, half away from zero.
            let a = (2 * n.abs() + d) / (2 * d);
            if n < 0 {
                -a
            } else {
                a
            }
        };
        let mut out = Vec::new();
        let mut prev = 0;
        for i in 1..=l {
            let b = q(i * db, l);
            // (steps, negative) of the lead and the other axis.
            let lead = (true, dl < 0);
            let other = match b - prev {
                0 => (false, false),
                1 => (true, false),
                -1 => (true, true),
                _ => panic!("other axis jumped"),
            };
            prev = b;
            let (x, z) = if lead_x { (lead, other) } else { (other, lead) };
            out.push(u8::from(x.0) | u8::from(z.0) << 1 | u8::from(x.1) << 2 | u8::from(z.1) << 3);
        }
        out
    }

    #[test]
    fn diagonal_and_axis_blocks() {
        assert_eq!(bits(p(0, 0), p(3, 3)), [0b0011; 3]);
        assert_eq!(bits(p(0, 0), p(-3, -3)), [0b1111; 3]);
        assert_eq!(bits(p(5, 5), p(5, 7)), [0b0010; 2]);
        assert_eq!(bits(p(5, 5), p(2, 5)), [0b0101; 3]);
        assert!(bits(p(7, -7), p(7, -7)).is_empty());
    }

    #[test]
    fn ties_step_early_and_symmetrically() {
        // 1 over 2: i=1 gives 0.5, a tie, which steps (away from zero).
        assert_eq!(bits(p(0, 0), p(1, 2)), [0b0011, 0b0010]);
        assert_eq!(bits(p(0, 0), p(-1, 2)), [0b0111, 0b0010]);
        assert_eq!(bits(p(0, 0), p(1, -2)), [0b1011, 0b1010]);
        // 3 over 4: i·3/4 = 0.75, 1.5 (tie), 2.25, 3.
        assert_eq!(bits(p(0, 0), p(4, 3)), [0b0011, 0b0011, 0b0001, 0b0011]);
    }

    #[test]
    fn agrees_with_the_definition_exhaustively_small() {
        for dx in -12..=12 {
            for dz in -12..=12 {
                assert_eq!(
                    bits(p(100, -50), p(100 + dx, -50 + dz)),
                    by_definition(p(100, -50), p(100 + dx, -50 + dz)),
                    "dx={dx} dz={dz}"
                );
            }
        }
    }

    #[test]
    fn largest_block_counts_exactly() {
        let m = MAX_BLOCK_IMPULSES as i32;
        let b = LinearBlock::new(p(-m / 2, 0), p(m / 2, -(m - 1))).unwrap();
        let (mut nx, mut nz) = (0i64, 0i64);
        let mut n = 0u32;
        for e in b.events() {
            n += 1;
            nx += i64::from(e.x_steps());
            nz += i64::from(e.z_steps());
            assert!(!e.x_negative() && (e.z_negative() == e.z_steps()));
        }
        assert_eq!(
            (n, nx, nz),
            (MAX_BLOCK_IMPULSES, i64::from(m), i64::from(m - 1))
        );
    }
}

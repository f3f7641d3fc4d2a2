//! CRC-32 (IEEE 802.3, as in zlib): reflected polynomial `0xEDB88320`,
//! initial value and final XOR `0xFFFF_FFFF`. The table is built at compile
//! time (1 KiB of flash).

const TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

/// A running CRC-32.
///
/// ```
/// use core_nostd::crc32::Crc32;
/// let mut c = Crc32::new();
/// c.update(b"123456789");
/// assert_eq!(c.finish(), 0xCBF4_3926);
/// assert_eq!(Crc32::new().finish(), 0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crc32 {
    state: u32,
}

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A CRC over no bytes yet.
    pub const fn new() -> Self {
        Crc32 { state: 0xFFFF_FFFF }
    }

    /// Adds one byte.
    #[inline(always)]
    pub fn push(&mut self, byte: u8) {
        // The index is a u8: always within the 256-entry table.
        let idx = (self.state ^ u32::from(byte)) as u8;
        self.state = TABLE[idx as usize] ^ (self.state >> 8);
    }

    /// Adds a byte, then the four bytes of `v` little-endian first (one
    /// step event's record), the state kept in a register throughout.
    #[inline(always)]
    pub fn push_u8_u32_le(&mut self, byte: u8, v: u32) {
        let step = |s: u32, b: u32| TABLE[((s ^ b) & 0xFF) as usize] ^ (s >> 8);
        let mut s = step(self.state, u32::from(byte));
        s = step(s, v);
        s = step(s, v >> 8);
        s = step(s, v >> 16);
        s = step(s, v >> 24);
        self.state = s;
    }

    /// Adds bytes.
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.push(b);
        }
    }

    /// The CRC of the bytes so far.
    pub const fn finish(&self) -> u32 {
        self.state ^ 0xFFFF_FFFF
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_check_value_of_crc32() {
        let mut c = Crc32::new();
        c.update(b"123456789");
        assert_eq!(c.finish(), 0xCBF4_3926);
    }

    #[test]
    fn an_event_record_is_its_five_bytes() {
        for (byte, v) in [
            (0x0Fu8, 0xDEAD_BEEFu32),
            (0, 0),
            (0x05, 1),
            (0xFF, u32::MAX),
        ] {
            let (mut a, mut b) = (Crc32::new(), Crc32::new());
            a.update(b"prefix");
            b.update(b"prefix");
            a.push_u8_u32_le(byte, v);
            b.push(byte);
            b.update(&v.to_le_bytes());
            assert_eq!(a.finish(), b.finish(), "{byte:#x} {v:#x}");
        }
    }
}

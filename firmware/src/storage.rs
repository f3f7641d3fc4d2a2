//! The tool table, the work offsets, the stored reference positions, the
//! machine's M codes and the `OPT` switches
//! kept across power cuts, as [`core_nostd::store`] lays them out in two
//! slots: sectors 10 and 11 of the STM32F405's flash (128 KiB each, at
//! `0x080C_0000` and `0x080E_0000`, left out of the program by
//! `memory.x`). Under QEMU, whose flash cannot be written, the slots are
//! RAM that a system reset leaves as it was.
//!
//! A save runs when the offsets changed, the axes are at rest with nothing
//! queued, and (on the board) the serial line has been quiet for half a
//! second: erasing a sector stalls the core for about a second (up to two),
//! during which the watchdog is given 32 s and the supervisor stands aside,
//! and a byte arriving then is lost (USART1 holds one). The reliable
//! requests of the protocol recover from that; a host that streams set-up
//! lines while the machine is idle pauses after them.

use core_nostd::protocol::Device;
use core_nostd::store::{self, Flash, RECORD_WORDS};

/// What was saved or loaded last, and when the link last received a byte.
pub struct Storage {
    slots: Slots,
    seq: u32,
    generation: u32,
    last_byte: u32,
}

impl Storage {
    /// Loads the newest whole record into the device (power-on).
    pub fn load(flash: stm32f4::stm32f405::FLASH, device: &mut Device) -> Storage {
        let mut slots = Slots::new(flash);
        let loaded = store::load(&mut slots);
        if loaded.seq != 0 {
            defmt::info!("offsets: record {=u32} loaded", loaded.seq);
        }
        device.restore_offsets(loaded.offsets);
        Storage {
            slots,
            seq: loaded.seq,
            generation: device.session().offsets_generation(),
            last_byte: crate::board::ticks(),
        }
    }

    /// A byte arrived now.
    pub fn heard(&mut self) {
        self.last_byte = crate::board::ticks();
    }

    /// Saves the offsets if they changed and the machine and the line are
    /// quiet (`idle`: nothing running, queued or received).
    pub fn save_if_due(&mut self, device: &Device, idle: bool) {
        let generation = device.session().offsets_generation();
        if generation == self.generation || !idle {
            return;
        }
        let quiet = crate::board::ticks().wrapping_sub(self.last_byte);
        if !cfg!(feature = "qemu") && quiet < crate::board::TIM2_CLK_HZ / 2 {
            return;
        }
        let offsets = *device.session().offsets();
        let (slots, last) = (&mut self.slots, self.seq);
        self.seq = crate::supervisor::while_flashing(|| store::save(slots, &offsets, last));
        self.generation = generation;
        defmt::info!("offsets: record {=u32} saved", self.seq);
    }
}

#[cfg(not(feature = "qemu"))]
use flash::Slots;

#[cfg(not(feature = "qemu"))]
mod flash {
    use super::{Flash, RECORD_WORDS};
    use stm32f4::stm32f405::FLASH;

    /// Sector number and address of each slot.
    const SECTORS: [(u8, usize); 2] = [(10, 0x080C_0000), (11, 0x080E_0000)];
    /// The keys that unlock `FLASH_CR` (RM0090 §3.5.1).
    const KEYS: [u32; 2] = [0x4567_0123, 0xCDEF_89AB];

    /// The two sectors through the flash interface, 32 bits at a time
    /// (2.7–3.6 V).
    pub struct Slots {
        flash: FLASH,
    }

    impl Slots {
        pub fn new(flash: FLASH) -> Slots {
            Slots { flash }
        }

        /// Unlocked, idle, the error flags of an earlier operation cleared.
        fn ready(&mut self) {
            if self.flash.cr().read().lock().bit_is_set() {
                for key in KEYS {
                    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
                    self.flash.keyr().write(|w| unsafe { w.key().bits(key) });
                }
            }
            self.wait();
            // The error flags clear by writing ones.
            self.flash.sr().write(|w| {
                w.operr()
                    .clear_bit_by_one()
                    .wrperr()
                    .clear_bit_by_one()
                    .pgaerr()
                    .clear_bit_by_one()
                    .pgperr()
                    .clear_bit_by_one()
                    .pgserr()
                    .clear_bit_by_one()
            });
        }

        fn wait(&self) {
            while self.flash.sr().read().bsy().bit_is_set() {}
        }

        /// Waits for the end, locks, and says if it failed (the record's
        /// CRC then fails too, and a load keeps the other slot).
        fn done(&mut self) {
            self.wait();
            let sr = self.flash.sr().read();
            if sr.operr().bit_is_set()
                || sr.wrperr().bit_is_set()
                || sr.pgaerr().bit_is_set()
                || sr.pgperr().bit_is_set()
                || sr.pgserr().bit_is_set()
            {
                defmt::warn!("flash: operation failed, SR={=u32:#x}", sr.bits());
            }
            self.flash.cr().write(|w| w.lock().set_bit());
        }

        fn address(slot: usize, index: usize) -> Option<usize> {
            let (_, base) = SECTORS.get(slot)?;
            (index < RECORD_WORDS).then_some(base + 4 * index)
        }
    }

    impl Flash for Slots {
        fn read(&mut self, slot: usize, index: usize) -> u32 {
            match Slots::address(slot, index) {
                // SAFETY: an aligned word of a sector memory.x keeps out
                // of the program; flash is always mapped and readable.
                Some(a) => unsafe { core::ptr::read_volatile(a as *const u32) },
                None => 0,
            }
        }

        fn erase(&mut self, slot: usize) {
            let Some(&(sector, _)) = SECTORS.get(slot) else {
                return;
            };
            self.ready();
            // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
            self.flash
                .cr()
                .write(|w| unsafe { w.psize().psize32().ser().set_bit().snb().bits(sector) });
            self.flash.cr().modify(|_, w| w.strt().set_bit());
            self.done();
        }

        fn program(&mut self, slot: usize, index: usize, word: u32) {
            let Some(a) = Slots::address(slot, index) else {
                return;
            };
            self.ready();
            self.flash
                .cr()
                .write(|w| w.psize().psize32().pg().set_bit());
            // SAFETY: an aligned word of an erased storage sector, written
            // with programming enabled (RM0090 §3.6.4).
            unsafe { core::ptr::write_volatile(a as *mut u32, word) };
            self.done();
        }
    }
}

#[cfg(feature = "qemu")]
use ram::Slots;

#[cfg(feature = "qemu")]
mod ram {
    use super::{Flash, RECORD_WORDS};
    use core::cell::UnsafeCell;
    use core::mem::MaybeUninit;

    /// RAM outside `.bss`: a QEMU system reset leaves it as it was.
    #[link_section = ".uninit.STORAGE"]
    static SLOTS: Cell = Cell(UnsafeCell::new(MaybeUninit::uninit()));

    struct Cell(UnsafeCell<MaybeUninit<[[u32; RECORD_WORDS]; 2]>>);
    // SAFETY: only the one `Slots` (thread mode) touches it.
    unsafe impl Sync for Cell {}

    /// Two slots of RAM that behave as flash: erased to ones, programmed
    /// by clearing bits.
    pub struct Slots {
        words: &'static mut [[u32; RECORD_WORDS]; 2],
    }

    impl Slots {
        pub fn new(_: stm32f4::stm32f405::FLASH) -> Slots {
            // SAFETY: taken once, at power-on, with the flash interface
            // that `Board` hands out once; any bit pattern is a valid
            // `u32` array, whatever the RAM held.
            let words = unsafe { (*SLOTS.0.get()).assume_init_mut() };
            Slots { words }
        }
    }

    impl Flash for Slots {
        fn read(&mut self, slot: usize, index: usize) -> u32 {
            self.words
                .get(slot)
                .and_then(|s| s.get(index))
                .copied()
                .unwrap_or(0)
        }

        fn erase(&mut self, slot: usize) {
            if let Some(s) = self.words.get_mut(slot) {
                s.fill(u32::MAX);
            }
        }

        fn program(&mut self, slot: usize, index: usize, word: u32) {
            if let Some(w) = self.words.get_mut(slot).and_then(|s| s.get_mut(index)) {
                *w &= word;
            }
        }
    }
}

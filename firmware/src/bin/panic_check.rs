//! Raises a STEP output and panics: under QEMU a debug build must stop the
//! outputs and exit with a failure code; a release build must not link.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use embedded_hal::digital::OutputPin;
use firmware::board::PortCPin;
use firmware::halt;

#[entry]
fn main() -> ! {
    let _board = firmware::boot();
    let _ = PortCPin(0).set_high();
    // An index the optimiser cannot see through, so the bounds check stays.
    let table = [1u8, 2, 3];
    let i = core::hint::black_box(7usize);
    defmt::info!("unreachable: {=u8}", table[i]);
    halt()
}

//! STM32F405 firmware of the lathe retrofit controller.
//!
//! This build holds the protocol session in RAM and idles; the UART and the
//! step/dir outputs are wired in by the board support.
#![no_std]
#![no_main]

use core::panic::PanicInfo;
use core_nostd::protocol::Device;
use cortex_m_rt::entry;

static mut DEVICE: Device = Device::new();

#[entry]
fn main() -> ! {
    let device = unsafe { &mut *core::ptr::addr_of_mut!(DEVICE) };
    let _ = device.session();
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_: &PanicInfo) -> ! {
    cortex_m::asm::udf()
}

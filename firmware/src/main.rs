//! The controller: the pendant line protocol on USART1, step/dir outputs.
#![no_std]
#![no_main]

use core_nostd::protocol::Device;
use cortex_m_rt::entry;
use firmware::{board, Controller};

#[entry]
fn main() -> ! {
    let mut io = Controller::new(firmware::boot());
    let mut device = Device::new();
    defmt::info!(
        "{=str} {=str} ready, {=u32} Hz",
        core_nostd::protocol::NAME,
        core_nostd::protocol::VERSION,
        board::SYSCLK_HZ
    );
    loop {
        match io.board.receive() {
            Some(byte) => device.receive(byte, &mut io),
            None => board::sleep_unless(board::rx_pending),
        }
    }
}

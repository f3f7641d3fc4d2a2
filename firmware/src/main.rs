//! The controller: the pendant line protocol on USART1, step/dir outputs.
#![no_std]
#![no_main]

use core::mem::MaybeUninit;
use core_nostd::protocol::Device;
use cortex_m_rt::entry;
use firmware::{board, Controller};

/// How long a grbl link stays quiet before what it queued starts, µs.
const QUIET_US: u32 = 50_000;

#[entry]
fn main() -> ! {
    // The device (its look-ahead queue the largest part) in static memory,
    // where `size` counts it and the linker checks that it fits; the entry
    // hands it out as a `&'static mut` once.
    static mut DEVICE: MaybeUninit<Device> = MaybeUninit::uninit();
    let device: &'static mut Device = DEVICE.write(Device::new());
    let mut io = Controller::new(firmware::boot(), device);
    defmt::info!(
        "{=str} {=str} ready, {=u32} Hz",
        core_nostd::protocol::NAME,
        core_nostd::protocol::VERSION,
        board::SYSCLK_HZ
    );
    let mut heard = board::ticks();
    loop {
        firmware::supervisor::beat();
        // Real-time requests the serial interrupt acted on: the protocol's
        // part (the reset's report and session, a status line) first.
        if io.realtime(device) {
            io.grbl = device.grbl_extras();
            continue;
        }
        // The step interrupt runs the last block started: the next one
        // starts now, window full or not.
        let feed = device.can_feed() && firmware::motion::hungry();
        if feed || device.cancel_pending() {
            device.poll(&mut io);
        }
        match io.serial.receive() {
            Some(byte) => {
                heard = board::ticks();
                io.storage.heard();
                device.receive(byte, &mut io);
                // A line's end (it may have switched protocol, moved the
                // offsets or started a jog) or a grbl override: what a grbl
                // status report adds, looked at again; not at every byte.
                if matches!(byte, b'\n' | b'\r') || byte >= 0x80 {
                    io.grbl = device.grbl_extras();
                    firmware::board::set_grbl(io.grbl.is_some());
                }
            }
            None if feed => {}
            // A grbl link quiet for 50 ms: what it queued starts (no sleep
            // meanwhile; the wait is short).
            None if device.waiting() => {
                if board::ticks().wrapping_sub(heard) >= QUIET_US {
                    device.quiet(&mut io);
                }
            }
            None => {
                // Changed offsets go to flash once all is quiet.
                let idle = io.idle();
                let storage = &mut io.storage;
                storage.save_if_due(device, idle);
                board::sleep_unless(|| {
                    board::rx_pending()
                        || firmware::motion::wanted()
                        || (device.can_feed() && firmware::motion::hungry())
                })
            }
        }
    }
}

//! STM32F405 firmware of the lathe retrofit controller: the board layer.
//!
//! USART1 (115200 8N1) serves the pendant line protocol through the core's
//! handler, byte for byte as the host simulator's in-process device does.
//! Blocks start as the planner's window fills (or at a flush); each started
//! block's events are issued on the STEP/DIR outputs at their ticks of TIM2
//! (1 MHz) before the request that started it is answered. Received bytes
//! are queued by the USART1 interrupt while the axes move.
//!
//! Release builds contain no panic path: their panic handler calls a symbol
//! that does not exist, so the link fails if any panic survives optimisation.
//! Debug builds stop the step outputs first, log, and under QEMU exit with a
//! failure code.
#![no_std]

pub mod board;
pub mod log;

use board::{Board, CycleDelay, PortCPin};
use core_nostd::interleave::StepEvent;
use core_nostd::protocol::Io;
use core_nostd::stepdir::{DriveTiming, StepDir, TickClock};

/// The transport side of the device: UART out, step/dir outputs.
pub struct Controller {
    /// USART1 and the step timer.
    pub board: Board,
    axes: StepDir<PortCPin, PortCPin, PortCPin, PortCPin>,
}

impl Controller {
    /// Takes the board; STEP outputs start low.
    pub fn new(board: Board) -> Self {
        let axes = StepDir::new(PortCPin(0), PortCPin(1), PortCPin(2), PortCPin(3));
        Controller { board, axes }
    }
}

impl Io for Controller {
    fn send(&mut self, line: &[u8]) {
        self.board.send(line);
    }

    fn run_start(&mut self) {
        self.board.tim2.start_run();
    }

    #[inline]
    fn step(&mut self, event: StepEvent, tick: u64, drive: &DriveTiming) {
        if self
            .axes
            .issue(event, tick, drive, &mut self.board.tim2, &mut CycleDelay)
            .is_err()
        {
            defmt::error!("step outputs failed");
        }
    }

    fn run_end(&mut self, _ticks: u64) {
        self.axes.stop_outputs();
    }
}

/// Reset to running: takes the peripherals (once, at reset), starts the
/// logger and brings up clocks, pins, USART1 and the step timer.
pub fn boot() -> board::Board {
    // `take` succeeds once, at reset; there is no other caller.
    let Some(dp) = stm32f4::stm32f405::Peripherals::take() else {
        halt()
    };
    log::init();
    board::init(dp)
}

/// Stops here for good, outputs safe.
pub fn halt() -> ! {
    board::step_outputs_low();
    loop {
        cortex_m::asm::wfi();
    }
}

#[cfg(not(debug_assertions))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "Rust" {
        /// Never defined: referencing it fails the link of a release build
        /// that still has a reachable panic.
        fn release_build_has_a_reachable_panic() -> !;
    }
    // SAFETY: never linked; see above.
    unsafe { release_build_has_a_reachable_panic() }
}

#[cfg(debug_assertions)]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    // The axes first: no STEP pulse may stay high or follow.
    board::step_outputs_low();
    cortex_m::interrupt::disable();
    defmt::error!("panic: {}", defmt::Display2Format(info));
    #[cfg(feature = "qemu")]
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[defmt::panic_handler]
fn defmt_panic() -> ! {
    core::panic!("defmt panic")
}

//! STM32F405 firmware of the lathe retrofit controller: the board layer.
//!
//! USART1 (115200 8N1) serves the pendant line protocol through the core's
//! handler, byte for byte as the host simulator's in-process device does.
//! Blocks start as the planner's window fills (or at a flush) and go to the
//! step interrupt ([`motion`]), which issues their events on the STEP/DIR
//! outputs at their ticks of TIM2 (1 MHz) while the protocol goes on;
//! received bytes are queued by the USART1 interrupt meanwhile.
//!
//! Release builds contain no panic path: their panic handler calls a symbol
//! that does not exist, so the link fails if any panic survives optimisation.
//! Debug builds stop the step outputs first, log, and under QEMU exit with a
//! failure code.
#![no_std]

pub mod board;
pub mod log;
pub mod motion;
pub mod spindle;
pub mod storage;
pub mod supervisor;

use board::{Board, Serial};
use core_nostd::interleave::ImpulsePoint;
use core_nostd::machine::Background;
use core_nostd::protocol::{status_line, Io, Realtime, StatusView, Timing};
use core_nostd::step::Record;
use core_nostd::stepdir::DriveTiming;
use core_nostd::stepper::{Aborted, Item, Motion};

/// The transport side of the device: the serial line, and the step
/// interrupt that takes its motion.
pub struct Controller {
    /// USART1.
    pub serial: Serial,
    /// What a status line needs of the session, and the blocks queued.
    view: StatusView,
    queued: usize,
    /// When the status byte being answered arrived (TIM2 count).
    asked: Option<u32>,
    /// The offsets kept across power cuts.
    pub storage: storage::Storage,
    /// On a grbl link: what its status reports add.
    pub grbl: Option<core_nostd::protocol::grbl::Extras>,
}

impl Controller {
    /// Takes the board: the timers and the step outputs go to the step
    /// interrupt (STEP outputs low); the offsets kept in flash go to the
    /// device.
    pub fn new(board: Board, device: &mut core_nostd::protocol::Device) -> Self {
        let storage = storage::Storage::load(board.flash, device);
        motion::install(board.tim2, board.tim5, board.spindle);
        supervisor::start(board.watchdog);
        Controller {
            storage,
            grbl: None,
            serial: board.serial,
            view: StatusView {
                hx: 0,
                hz: 0,
                diam: true,
                speed: 0,
                starved: 0,
                stop: None,
                outputs: core_nostd::outputs::Outputs::OFF,
            },
            queued: 0,
            asked: None,
        }
    }

    /// Nothing runs or waits to run: the axes at rest, no block queued.
    pub fn idle(&self) -> bool {
        self.queued == 0 && motion::drained()
    }

    /// Answers what the serial interrupt left for thread mode through the
    /// protocol: a reset's report and new session first, else a status
    /// line. Returns whether there was anything.
    pub fn realtime(&mut self, device: &mut core_nostd::protocol::Device) -> bool {
        if motion::take_reset() {
            device.realtime(Realtime::Reset, self);
        } else if let Some(asked) = motion::take_status() {
            self.asked = Some(asked);
            device.realtime(Realtime::Status, self);
        } else {
            return false;
        }
        true
    }
}

/// The board's timing for a status line answering a byte that arrived at
/// TIM2 count `asked`.
fn timing(asked: u32) -> Timing {
    Timing {
        latency_us: board::ticks().wrapping_sub(asked),
        late_events: motion::late_events(),
    }
}

/// Sends the `!STATUS` line a real-time byte asked for, if one did, while
/// thread mode waits or works (it ends with `LAT= LATE=`, as the
/// protocol's).
fn answer_status(
    serial: &mut Serial,
    view: &StatusView,
    queued: usize,
    grbl: Option<&core_nostd::protocol::grbl::Extras>,
) {
    if let Some(asked) = motion::take_status() {
        let issued = motion::issued().unwrap_or_default();
        let view = StatusView {
            outputs: motion::outputs().unwrap_or(view.outputs),
            ..*view
        };
        let mut line = status_line("!STATUS", motion::motion(), issued, queued, &view);
        match grbl {
            Some(extras) => {
                let mut report = core_nostd::protocol::grbl::status_report(line.as_bytes(), extras);
                report.push_bytes(b"\r\n");
                serial.send(report.as_bytes());
            }
            None => {
                timing(asked).write_to(&mut line);
                serial.send(line.finish());
            }
        }
    }
}

impl Io for Controller {
    fn send(&mut self, line: &[u8]) {
        self.serial.send(line);
    }

    fn background(&mut self) -> Option<&mut dyn Background> {
        Some(self)
    }

    fn view(&mut self, view: &StatusView) {
        self.view = *view;
    }

    fn pause(&mut self) {
        supervisor::beat();
        answer_status(
            &mut self.serial,
            &self.view,
            self.queued,
            self.grbl.as_ref(),
        );
    }

    fn dwell(&mut self, us: u64) {
        // On TIM2's microseconds, whose 32 bits wrap: summed step by step.
        let mut left = if board::PACED { us } else { 0 };
        let mut last = board::ticks();
        while left > 0 {
            self.pause();
            let now = board::ticks();
            left = left.saturating_sub(u64::from(now.wrapping_sub(last)));
            last = now;
        }
    }

    fn program_stop(&mut self, _: u16) {
        motion::clear_cycle_start();
        while !motion::stop_ended() {
            self.pause();
            board::sleep_unless(|| motion::wanted() || motion::stop_ended());
        }
    }

    fn timing(&mut self) -> Option<Timing> {
        self.asked.take().map(timing)
    }

    fn outputs(&mut self, outputs: &core_nostd::outputs::Outputs) {
        motion::set_outputs(outputs);
    }
}

// The step interrupt's state exists from `Controller::new` on: its
// functions hand back nothing only before `motion::install`.
impl Background for Controller {
    fn start(&mut self, item: Item, drive: &DriveTiming) {
        let (serial, view, queued) = (&mut self.serial, self.view, self.queued);
        let grbl = self.grbl;
        let _ = motion::start(item, drive, || {
            answer_status(serial, &view, queued, grbl.as_ref())
        });
    }

    fn drain(&mut self) {
        while !motion::drained() {
            answer_status(
                &mut self.serial,
                &self.view,
                self.queued,
                self.grbl.as_ref(),
            );
            board::sleep_unless(|| motion::wanted() || motion::drained());
        }
    }

    fn issued(&mut self) -> ImpulsePoint {
        motion::issued().unwrap_or_default()
    }

    fn set_issued(&mut self, registers: ImpulsePoint) {
        motion::set_issued(registers);
    }

    fn take_record(&mut self) -> Record {
        motion::take_record().unwrap_or_default()
    }

    fn hold(&mut self) {
        motion::act(Realtime::Hold);
    }

    fn resume(&mut self) {
        motion::act(Realtime::Resume);
    }

    fn abort(&mut self) -> Aborted {
        motion::abort().unwrap_or(Aborted {
            done: 0,
            of: 0,
            dropped: false,
        })
    }

    fn motion(&mut self) -> Motion {
        motion::motion()
    }

    fn hungry(&mut self) -> bool {
        motion::hungry()
    }

    fn queued(&mut self, blocks: usize) {
        self.queued = blocks;
    }

    fn spindle(&mut self) -> Option<u32> {
        motion::outputs().map(|o| o.rpm)
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

/// A fault stops the steps; the watchdog then resets the board.
#[cortex_m_rt::exception]
unsafe fn HardFault(_: &cortex_m_rt::ExceptionFrame) -> ! {
    halt()
}

/// Stops here for good, outputs safe.
pub fn halt() -> ! {
    board::step_outputs_low();
    spindle::all_low();
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
    spindle::all_low();
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

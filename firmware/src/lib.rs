//! STM32F405 firmware of the lathe retrofit controller.
//!
//! USART1 (115200 8N1) serves the pendant line protocol through the core's
//! handler, byte for byte as the host simulator's in-process device does.
//! Blocks start as the planner's window fills (or at a flush); the prep
//! stage turns them into ready step events ahead of the step interrupt,
//! which issues them on the STEP/DIR outputs at their ticks of TIM2 (1 MHz)
//! while the protocol goes on.
//!
//! | module | role |
//! |---|---|
//! | [`board`] | registers: clocks, pins, USART1, the timers, the spindle outputs |
//! | [`step`] | the step interrupt's state and work |
//! | [`motion`] | the prep task, the real-time task, thread mode's motion |
//! | [`serial`] | the receive interrupt |
//! | [`inputs`] | the switches: sampled, filtered, a stop acted on at once |
//! | [`supervisor`] | the watchdog and its supervisor |
//! | [`storage`] | the offsets kept in flash |
//! | [`Controller`] | the protocol's transport in thread mode |
//!
//! The tasks and their priorities are in `main.rs` (RTIC). `→` says what a
//! module uses: `board` → nothing of ours; `step`, `supervisor`,
//! `storage`, `inputs` → `board`; `motion` → `step`, `board`, `inputs`;
//! `serial` → `board`, `motion`; the controller → all of them.
//!
//! Release builds contain no panic path: their panic handler calls a symbol
//! that does not exist, so the link fails if any panic survives optimisation.
//! Debug builds stop the step outputs first, log, and under QEMU exit with a
//! failure code.
#![no_std]

pub mod board;
pub mod inputs;
pub mod log;
pub mod motion;
pub mod serial;
pub mod step;
pub mod storage;
pub mod supervisor;

use board::Serial;
use core_nostd::interleave::ImpulsePoint;
use core_nostd::machine::Background;
use core_nostd::protocol::{status_line, Io, Realtime, StatusRecord, StatusView, Timing};
use core_nostd::step::Record;
use core_nostd::stepdir::DriveTiming;
use core_nostd::stepper::{Aborted, AxesState, Item};
use motion::{PrepStage, Shared};
use rtic::Mutex;
use step::StepIsr;

/// The transport side of the device in thread mode: the serial line, and
/// the motion it hands to the prep and the step interrupt.
pub struct Controller<P, S> {
    /// USART1.
    pub serial: Serial,
    /// Bytes the receive interrupt queued.
    pub bytes: serial::Bytes,
    /// The prep stage and the step interrupt.
    pub motion: Shared<P, S>,
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

impl<P: Mutex<T = PrepStage>, S: Mutex<T = StepIsr>> Controller<P, S> {
    /// The transport over the serial line, its byte queue, the offsets
    /// loaded, and the two motion resources.
    pub fn new(
        serial: Serial,
        bytes: serial::Bytes,
        storage: storage::Storage,
        prep: P,
        step: S,
    ) -> Self {
        Controller {
            storage,
            grbl: None,
            serial,
            bytes,
            motion: Shared { prep, step },
            view: StatusView {
                hx: 0,
                hz: 0,
                diam: true,
                speed: 0,
                starved: 0,
                stop: None,
                outputs: core_nostd::outputs::Outputs::OFF,
                pins: None,
                alarm: 0,
                lost: false,
            },
            queued: 0,
            asked: None,
        }
    }

    /// Nothing runs or waits to run: the axes at rest, no block queued.
    pub fn idle(&mut self) -> bool {
        self.queued == 0 && self.motion.drained()
    }

    /// Answers what the real-time task left for thread mode through the
    /// protocol: a reset's report and new session first, else a status
    /// line. Returns whether there was anything.
    pub fn realtime(&mut self, device: &mut core_nostd::protocol::Device) -> bool {
        if motion::take_reset() {
            device.realtime(Realtime::Reset, self);
        } else if inputs::take_changed() {
            device.inputs(inputs::active(), self);
            if motion::input_stop_unreported() {
                // The session did not stop for it (its wiring changed in
                // between): the motion dropped is reported as a reset's,
                // never silently.
                device.realtime(Realtime::Reset, self);
            }
        } else if let Some(detents) = inputs::take_wheel() {
            device.wheel(detents, self);
        } else if let Some(asked) = motion::take_status() {
            self.asked = Some(asked);
            device.realtime(Realtime::Status, self);
        } else {
            return false;
        }
        true
    }

    /// The board's timing for a status line answering a byte that arrived
    /// at TIM2 count `asked`.
    fn timing(&mut self, asked: u32) -> Timing {
        let (late, _worst) = self.motion.lateness();
        #[cfg(feature = "qemu")]
        report_lateness(late, _worst);
        Timing {
            latency_us: board::ticks().wrapping_sub(asked),
            late_events: late,
        }
    }

    /// Sends the `!STATUS` line a real-time byte asked for, if one did,
    /// while thread mode waits or works (it ends with `LAT= LATE=`, as the
    /// protocol's).
    fn answer_status(&mut self) {
        if let Some(asked) = motion::take_status() {
            let issued = self.motion.issued();
            let view = StatusView {
                outputs: self.motion.outputs(),
                ..self.view
            };
            let record = StatusRecord {
                motion: self.motion.motion(),
                issued,
                queued: self.queued,
                view,
            };
            match self.grbl.as_ref() {
                Some(extras) => {
                    let mut report = core_nostd::protocol::grbl::status_report(&record, extras);
                    report.push_bytes(b"\r\n");
                    self.serial.send(report.as_bytes());
                }
                None => {
                    let mut line = status_line("!STATUS", &record);
                    self.timing(asked).write_to(&mut line);
                    self.serial.send(line.finish());
                }
            }
        }
    }
}

/// Under QEMU the worst lateness goes to the host beside each status
/// line's (the line's own format is the protocol's): `timing: LATE= WORST=`.
#[cfg(feature = "qemu")]
fn report_lateness(late: u32, worst: u32) {
    log::host_print(format_args!("timing: LATE={late} WORST={worst}\n"));
}

impl<P: Mutex<T = PrepStage>, S: Mutex<T = StepIsr>> Io for Controller<P, S> {
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
        self.motion.watch_step();
        self.answer_status();
    }

    fn dwell(&mut self, us: u64) {
        // On TIM2's microseconds, whose 32 bits wrap: summed step by step.
        let mut left = if board::PACED { us } else { 0 };
        let mut last = board::ticks();
        // A reset or a switch's stop ends the wait too.
        while left > 0 && !motion::reset_wanted() {
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
            motion::sleep_unless(|| motion::wanted() || motion::stop_ended());
        }
    }

    fn user_output(&mut self, n: u8, on: bool) {
        board::spindle::user_output(n, on);
    }

    fn wait_input(&mut self, n: u8, level: bool) {
        // Until the input reads `level` or a reset comes, answering status.
        while board::user_input(n) != level && !motion::reset_wanted() {
            self.pause();
        }
    }

    fn timing(&mut self) -> Option<Timing> {
        self.asked
            .take()
            .map(|asked| Controller::timing(self, asked))
    }

    fn outputs(&mut self, outputs: &core_nostd::outputs::Outputs) {
        self.motion.set_outputs(outputs);
    }

    fn inputs_now(&mut self) -> Option<u16> {
        Some(inputs::active())
    }

    fn probe_arm(&mut self, stop_on: Option<bool>) {
        inputs::arm_probe(stop_on);
    }
}

impl<P: Mutex<T = PrepStage>, S: Mutex<T = StepIsr>> Background for Controller<P, S> {
    fn start(&mut self, item: Item, drive: &DriveTiming) {
        let mut item = item;
        loop {
            match self.motion.try_start(item, drive) {
                Ok(()) => return,
                Err(back) => item = back,
            }
            // Full: status lines meanwhile, then sleep until there is room.
            self.motion.watch_step();
            self.answer_status();
            let motion = &mut self.motion;
            motion::sleep_unless(|| motion::wanted() || motion.has_room());
            supervisor::beat();
        }
    }

    fn drain(&mut self) {
        while !self.motion.drained() {
            self.motion.watch_step();
            self.answer_status();
            let motion = &mut self.motion;
            motion::sleep_unless(|| motion::wanted() || motion.drained());
            supervisor::beat();
        }
    }

    fn issued(&mut self) -> ImpulsePoint {
        self.motion.issued()
    }

    fn lash(&mut self) -> [i32; 2] {
        self.motion.lash()
    }

    fn set_issued(&mut self, registers: ImpulsePoint) {
        self.motion.set_issued(registers);
    }

    fn take_record(&mut self) -> Record {
        self.motion.take_record()
    }

    fn hold(&mut self) {
        self.motion.act(Realtime::Hold);
    }

    fn resume(&mut self) {
        self.motion.act(Realtime::Resume);
    }

    fn abort(&mut self) -> Aborted {
        self.motion.abort()
    }

    fn motion(&mut self) -> AxesState {
        self.motion.motion()
    }

    fn hungry(&mut self) -> bool {
        self.motion.hungry()
    }

    fn queued(&mut self, blocks: usize) {
        self.queued = blocks;
    }

    fn spindle(&mut self) -> Option<u32> {
        Some(self.motion.outputs().rpm)
    }
}

/// A fault stops the steps; the watchdog then resets the board.
#[cortex_m_rt::exception]
// SAFETY: cortex-m-rt's signature for the handler; it only drives the outputs low and waits for the watchdog.
unsafe fn HardFault(_: &cortex_m_rt::ExceptionFrame) -> ! {
    halt()
}

/// Reset to running without the scheduler (the measurements): takes the
/// peripherals (once, at reset), starts the logger and brings up clocks,
/// pins, USART1 and the step timers.
pub fn boot() -> board::Board {
    // `take` succeeds once, at reset; there is no other caller.
    let (Some(dp), Some(cp)) = (
        stm32f4::stm32f405::Peripherals::take(),
        cortex_m::Peripherals::take(),
    ) else {
        halt()
    };
    log::init();
    board::init(dp, cp.SYST)
}

/// Stops here for good, outputs safe.
pub fn halt() -> ! {
    board::step_outputs_low();
    board::spindle::all_low();
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
    board::spindle::all_low();
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

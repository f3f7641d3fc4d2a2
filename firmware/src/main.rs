//! The controller: the pendant line protocol on USART1, step/dir outputs.
//!
//! Tasks by priority (RTIC 2, the stack resource policy: a task shares
//! state through resources, and a lock raises the priority only to the
//! resource's ceiling):
//!
//! | priority | task | bound to | timing contract |
//! |---|---|---|---|
//! | 5 | supervisor | TIM3, every 1 ms | judges and kicks the watchdog, pends the sampler; shares atomics only |
//! | 5 | inputs | EXTI2 (no switch on line 2), pended every 1 ms (under QEMU by the panel on USART2), and at once by a stopping switch's edge without a filter | samples and filters the switches; a stop drives the outputs low and masks the step interrupt at once |
//! | 5 | edges | EXTI0, EXTI1, EXTI4, EXTI9_5: the E-stop's and the limits' pins | masks the lines until the next millisecond, pends the sample when no filter is set |
//! | 4 | step | TIM5 (alarm), pended | pops a ready entry, writes the pins, arms the next alarm: about 105 instructions a step |
//! | 4 | pulse end | SysTick | STEP lines low: a few instructions (under paced QEMU SysTick is the step alarm) |
//! | 3 | prep | SPI1's vector, pended | fills the ready queue (255 entries) from the stepper |
//! | 2 | receive | USART1 | buffers a byte or queues a real-time byte: under 100 instructions |
//! | 1 | real-time | SPI2's vector, pended | hold, resume, reset, status request, in order |
//! | 0 | protocol | idle | parses, plans, answers; may run for 0.4 s (the longest arc's check) |
#![no_std]
#![no_main]

#[rtic::app(device = stm32f4::stm32f405, peripherals = true)]
mod app {
    use core::mem::MaybeUninit;
    use core_nostd::protocol::Device;
    use firmware::motion::{self, PrepStage, RtEvent};
    use firmware::serial::{self, RT_EVENTS, RX_BYTES};
    use firmware::step::{self, StepIsr};
    use firmware::supervisor::{self, Supervisor};
    use firmware::{board, storage, Controller};
    use heapless::spsc::{Consumer, Queue};

    /// How long a grbl link stays quiet before what it queued starts, µs.
    const QUIET_US: u32 = 50_000;

    #[shared]
    struct Shared {
        step: StepIsr,
        prep: PrepStage,
    }

    /// What thread mode takes at its start.
    pub struct Protocol {
        device: &'static mut Device,
        serial: board::Serial,
        bytes: serial::Bytes,
        storage: storage::Storage,
    }

    #[local]
    struct Local {
        protocol: Option<Protocol>,
        receiver: serial::Receiver,
        realtime: Consumer<'static, RtEvent>,
        supervisor: Supervisor,
        sampler: firmware::inputs::Sampler,
        panel: board::Panel,
    }

    #[init(local = [
        device: MaybeUninit<Device> = MaybeUninit::uninit(),
        rx: Queue<u8, RX_BYTES> = Queue::new(),
        rt: Queue<RtEvent, RT_EVENTS> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        firmware::log::init();
        let board = board::init(cx.device, cx.core.SYST);
        // The device (its look-ahead queue the largest part) in static
        // memory, where `size` counts it; handed out once.
        let device: &'static mut Device = cx.local.device.write(Device::new());
        let storage = storage::Storage::load(board.flash, device);
        let per_tick = board.alarm.per_tick();
        let Some((tx, rx)) = step::READY.split() else {
            firmware::halt()
        };
        let (bytes_in, bytes_out) = cx.local.rx.split();
        let (rt_in, rt_out) = cx.local.rt.split();
        defmt::info!(
            "{=str} {=str} ready, {=u32} Hz",
            core_nostd::protocol::NAME,
            core_nostd::protocol::VERSION,
            board::SYSCLK_HZ
        );
        (
            Shared {
                step: StepIsr::new(rx, board.alarm, board.pulse, board.spindle),
                prep: PrepStage::new(tx),
            },
            Local {
                protocol: Some(Protocol {
                    device,
                    serial: board.serial,
                    bytes: serial::Bytes::new(bytes_out),
                    storage,
                }),
                receiver: serial::Receiver::new(bytes_in, rt_in),
                realtime: rt_out,
                supervisor: supervisor::start(board.watchdog, per_tick),
                sampler: firmware::inputs::Sampler::new(),
                panel: board.panel,
            },
        )
    }

    /// The protocol: bytes to the device, motion to the prep.
    #[idle(shared = [step, prep], local = [protocol])]
    fn idle(cx: idle::Context) -> ! {
        // Handed over by `init`, taken once.
        let Some(Protocol {
            device,
            serial,
            bytes,
            storage,
        }) = cx.local.protocol.take()
        else {
            firmware::halt()
        };
        let mut io = Controller::new(serial, bytes, storage, cx.shared.prep, cx.shared.step);
        // The wiring kept in flash, for the switches' sampler.
        firmware::inputs::set_wiring(device.wiring());
        let mut heard = board::ticks();
        loop {
            supervisor::beat();
            // Real-time requests the real-time task acted on: the
            // protocol's part (the reset's report and session, a status
            // line) first.
            if io.realtime(device) {
                io.grbl = device.grbl_extras();
                continue;
            }
            // The prep has prepared the last block started: the next one
            // starts now, window full or not.
            let feed = device.can_feed() && io.motion.hungry();
            if feed || device.cancel_pending() {
                device.poll(&mut io);
            }
            match io.bytes.receive(&mut io.serial) {
                Some(byte) => {
                    heard = board::ticks();
                    io.storage.heard();
                    device.receive(byte, &mut io);
                    // A line's end (it may have switched protocol, moved
                    // the offsets or started a jog) or a grbl override:
                    // what a grbl status report adds, looked at again; not
                    // at every byte.
                    if matches!(byte, b'\n' | b'\r') || byte >= 0x80 {
                        io.grbl = device.grbl_extras();
                        serial::set_grbl(io.grbl.is_some());
                        firmware::inputs::set_wiring(device.wiring());
                    }
                }
                None if feed => {}
                // A jog cancel waits for the hold to come to rest: no sleep
                // meanwhile (the braking is short), so the rest is dropped
                // as soon as the axes stand, before a status byte can see
                // the hold.
                None if device.cancel_pending() => {}
                // A grbl link quiet for 50 ms: what it queued starts (no
                // sleep meanwhile; the wait is short).
                None if device.waiting() => {
                    if board::ticks().wrapping_sub(heard) >= QUIET_US {
                        device.quiet(&mut io);
                    }
                }
                None => {
                    // Changed offsets go to flash once all is quiet.
                    let idle = io.idle();
                    io.storage.save_if_due(device, idle);
                    let Controller { bytes, motion, .. } = &mut io;
                    motion.watch_step();
                    motion::sleep_unless(|| {
                        bytes.pending()
                            || motion::wanted()
                            || (device.can_feed() && motion.hungry())
                    });
                }
            }
        }
    }

    /// The supervisor: every 1 ms, above everything.
    #[task(binds = TIM3, priority = 5, local = [supervisor])]
    fn supervise(cx: supervise::Context) {
        cx.local.supervisor.check();
    }

    /// The switches' sample: every 1 ms from the supervisor, at once on a
    /// stopping switch's edge (`board::SAMPLER_IRQ`).
    #[task(binds = EXTI2, priority = 5, local = [sampler])]
    fn sample_inputs(cx: sample_inputs::Context) {
        cx.local.sampler.sample();
    }

    /// The E-stop's edge (PA0).
    #[task(binds = EXTI0, priority = 5)]
    fn edge_estop(_: edge_estop::Context) {
        firmware::inputs::edge();
    }

    /// X−'s edge (PA1).
    #[task(binds = EXTI1, priority = 5)]
    fn edge_x_minus(_: edge_x_minus::Context) {
        firmware::inputs::edge();
    }

    /// X+'s edge (PA4).
    #[task(binds = EXTI4, priority = 5)]
    fn edge_x_plus(_: edge_x_plus::Context) {
        firmware::inputs::edge();
    }

    /// Z−'s and Z+'s edges (PA5, PA6).
    #[task(binds = EXTI9_5, priority = 5)]
    fn edge_z(_: edge_z::Context) {
        firmware::inputs::edge();
    }

    /// The test harness's panel under QEMU: each sample it completes is
    /// sampled at once (the board has no such port).
    #[task(binds = USART2, priority = 5, local = [panel])]
    fn panel(cx: panel::Context) {
        match cx.local.panel.receive() {
            board::PanelSample::None => {}
            // Without a filter the edge's own interrupt samples, as on
            // the board; with one, the sample is the millisecond's.
            board::PanelSample::Edge if !firmware::inputs::filtered() => {}
            board::PanelSample::Edge | board::PanelSample::Sample => {
                rtic::pend(board::SAMPLER_IRQ);
            }
        }
    }

    /// The step interrupt: its alarm, or a pend when entries arrive.
    #[task(binds = TIM5, priority = 4, shared = [step])]
    fn step_alarm(mut cx: step_alarm::Context) {
        cx.shared.step.lock(|s| s.service());
    }

    /// The end of a STEP pulse (the board), the step alarm (paced QEMU).
    #[task(binds = SysTick, priority = 4)]
    fn systick(_: systick::Context) {
        step::systick();
    }

    /// The prep stage: fills the ready queue (SPI1's vector,
    /// `board::PREP_IRQ`).
    #[task(binds = SPI1, priority = 3, shared = [prep])]
    fn prep_stage(mut cx: prep_stage::Context) {
        cx.shared.prep.lock(|p| p.fill());
    }

    /// The receive interrupt: buffers bytes.
    #[task(binds = USART1, priority = 2, local = [receiver])]
    fn receive(cx: receive::Context) {
        cx.local.receiver.receive();
    }

    /// Real-time bytes, in order (SPI2's vector, `board::REALTIME_IRQ`).
    #[task(binds = SPI2, priority = 1, shared = [prep, step], local = [realtime])]
    fn realtime(cx: realtime::Context) {
        let rx = cx.local.realtime;
        let (mut prep, mut step) = (cx.shared.prep, cx.shared.step);
        motion::realtime(
            || serial::next_realtime(rx),
            serial::grbl(),
            &mut prep,
            &mut step,
        );
    }
}

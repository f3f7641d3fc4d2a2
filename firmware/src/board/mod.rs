//! The board: clocks, pins, USART1, the step clock and the step
//! interrupt's two timers, by register. Nothing here knows a task.
//!
//! | signal | pin | |
//! |---|---|---|
//! | USART1 TX / RX | PA9 / PA10 (AF7) | 115200 8N1 |
//! | X STEP / X DIR | PC0 / PC1 | push-pull |
//! | Z STEP / Z DIR | PC2 / PC3 | push-pull |
//! | spindle and coolant | PB6 … PB10 | [`spindle`] |
//! | E-stop, X−, X+, Z−, Z+ | PA0, PA1, PA4, PA5, PA6 | inputs, pull-up ([`input_pins`]); either edge interrupts (EXTI0, EXTI1, EXTI4, EXTI9_5: [`STOP_LINES`]) |
//! | door, feed hold | PA7, PA8 | inputs, pull-up |
//! | cycle start, probe | PC4, PC5 | inputs, pull-up |
//! | X fault, Z fault | PB0, PB1 | inputs, pull-up |
//! | handwheel A / B | PC6 / PC7 (TIM8 CH1 / CH2, AF3) | quadrature, pull-up ([`wheel_edges`]) |
//! | the test harness's panel (`qemu` builds) | USART2 | [`Panel`] |
//!
//! Two configurations. The real board runs from an 8 MHz crystal through the
//! PLL at 168 MHz (APB2 84 MHz, APB1 42 MHz, timers 84 MHz). QEMU 7.2's
//! `netduinoplus2` emulates no RCC ready bits, so the `qemu` build stays on
//! the 16 MHz HSI and waits for nothing; QEMU's timers count at 1 GHz.

use core::convert::Infallible;
use core_nostd::interleave::StepEvent;
use core_nostd::step::TickRate;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, OutputPin};
use stm32f4::stm32f405::{self as pac, Interrupt};

mod clock;
pub mod spindle;

/// Whether the last reset came from the watchdog (the flags are cleared).
fn was_reset_by_watchdog(rcc: &pac::RCC) -> bool {
    let by_watchdog = rcc.csr().read().wdgrstf().bit_is_set();
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
    by_watchdog
}

/// Core clock.
#[cfg(not(feature = "qemu"))]
pub const SYSCLK_HZ: u32 = 168_000_000;
#[cfg(feature = "qemu")]
pub const SYSCLK_HZ: u32 = 16_000_000;

/// USART1's bus clock (APB2).
#[cfg(not(feature = "qemu"))]
const PCLK2_HZ: u32 = 84_000_000;
#[cfg(feature = "qemu")]
const PCLK2_HZ: u32 = 16_000_000;

pub use clock::TIM2_CLK_HZ;

const BAUD: u32 = 115_200;

/// Brings up clocks, pins, USART1 and TIM2, and readies TIM5 and SysTick
/// for the step interrupt. Returns the board's devices; their interrupts
/// are the caller's to enable.
pub fn init(dp: pac::Peripherals, syst: cortex_m::peripheral::SYST) -> Board {
    clocks(&dp);
    let rcc = &dp.RCC;
    rcc.ahb1enr().modify(|_, w| {
        w.gpioaen()
            .set_bit()
            .gpioben()
            .set_bit()
            .gpiocen()
            .set_bit()
    });
    rcc.apb2enr().modify(|_, w| w.usart1en().set_bit());
    rcc.apb1enr().modify(|_, w| {
        w.tim2en()
            .set_bit()
            .tim3en()
            .set_bit()
            .tim4en()
            .set_bit()
            .tim5en()
            .set_bit()
    });

    // PA9, PA10: alternate function 7, PA10 pulled up.
    let gpioa = &dp.GPIOA;
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    gpioa
        .afrh()
        .modify(|_, w| unsafe { w.afrh9().bits(7).afrh10().bits(7) });
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    gpioa
        .moder()
        .modify(|_, w| unsafe { w.moder9().bits(0b10).moder10().bits(0b10) });
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    gpioa
        .pupdr()
        .modify(|_, w| unsafe { w.pupdr10().bits(0b01) });

    // PC0..PC3: outputs, low.
    let gpioc = &dp.GPIOC;
    gpioc.bsrr().write(|w| {
        w.br0()
            .set_bit()
            .br1()
            .set_bit()
            .br2()
            .set_bit()
            .br3()
            .set_bit()
    });
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    gpioc.moder().modify(|_, w| unsafe {
        w.moder0()
            .bits(0b01)
            .moder1()
            .bits(0b01)
            .moder2()
            .bits(0b01)
            .moder3()
            .bits(0b01)
    });

    // PC8..PC11: the user inputs 1 … 4, pulled down (unwired reads low).
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    gpioc.moder().modify(|_, w| unsafe {
        w.moder8()
            .bits(0)
            .moder9()
            .bits(0)
            .moder10()
            .bits(0)
            .moder11()
            .bits(0)
    });
    // SAFETY: as above.
    gpioc.pupdr().modify(|_, w| unsafe {
        w.pupdr8()
            .bits(0b10)
            .pupdr9()
            .bits(0b10)
            .pupdr10()
            .bits(0b10)
            .pupdr11()
            .bits(0b10)
    });

    // The switches: inputs (their reset mode), pulled up, so a switch to
    // ground reads low when closed.
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    gpioa.pupdr().modify(|_, w| unsafe {
        w.pupdr0()
            .bits(0b01)
            .pupdr1()
            .bits(0b01)
            .pupdr4()
            .bits(0b01)
            .pupdr5()
            .bits(0b01)
            .pupdr6()
            .bits(0b01)
            .pupdr7()
            .bits(0b01)
            .pupdr8()
            .bits(0b01)
    });
    // SAFETY: as above.
    gpioc.pupdr().modify(|_, w| unsafe {
        w.pupdr4()
            .bits(0b01)
            .pupdr5()
            .bits(0b01)
            .pupdr6()
            .bits(0b01)
            .pupdr7()
            .bits(0b01)
    });
    // SAFETY: as above.
    dp.GPIOB
        .pupdr()
        .modify(|_, w| unsafe { w.pupdr0().bits(0b01).pupdr1().bits(0b01) });
    // The stopping switches' edges (E-stop, limits) as interrupts: EXTI
    // lines 0, 1, 4, 5, 6 on port A (SYSCFG's reset mapping), both edges,
    // since the active level is a setting.
    let exti = &dp.EXTI;
    // SAFETY: bits of the lines this board uses, RM0090 §12.3.
    exti.rtsr()
        .modify(|r, w| unsafe { w.bits(r.bits() | STOP_LINES) });
    // SAFETY: as above.
    exti.ftsr()
        .modify(|r, w| unsafe { w.bits(r.bits() | STOP_LINES) });
    // SAFETY: writing 1 clears a pending line; as above.
    exti.pr().write(|w| unsafe { w.bits(STOP_LINES) });
    edges_unmask();
    #[cfg(not(feature = "qemu"))]
    wheel_counter(&dp.RCC, gpioc, dp.TIM8);
    #[cfg(feature = "qemu")]
    let panel = Panel::start(&dp.RCC, dp.USART2);
    #[cfg(not(feature = "qemu"))]
    let panel = Panel {};

    let usart = dp.USART1;
    // Both boards give a divider well below 2^16.
    let brr = ((PCLK2_HZ + BAUD / 2) / BAUD) as u16;
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    usart.brr().write(|w| unsafe { w.bits(brr) });
    usart.cr1().write(|w| {
        w.ue()
            .set_bit()
            .te()
            .set_bit()
            .re()
            .set_bit()
            .rxneie()
            .set_bit()
    });

    let mut tim2 = StepTimer { tim: dp.TIM2 };
    tim2.count_ticks();
    let (alarm, pulse) = step_timers(dp.TIM5, syst, &tim2);
    if was_reset_by_watchdog(&dp.RCC) {
        defmt::warn!("the watchdog reset the board");
    }
    Board {
        serial: Serial { usart },
        tim2,
        alarm,
        pulse,
        spindle: spindle::Spindle::new(dp.TIM4, &dp.GPIOB),
        watchdog: Watchdog {
            iwdg: dp.IWDG,
            tim3: dp.TIM3,
            dbgmcu: dp.DBGMCU,
        },
        flash: dp.FLASH,
        panel,
    }
}

#[cfg(not(feature = "qemu"))]
fn clocks(dp: &pac::Peripherals) {
    let rcc = &dp.RCC;
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    while rcc.cr().read().hserdy().bit_is_clear() {}
    // 168 MHz needs 5 wait states at 3.3 V.
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    dp.FLASH.acr().modify(|_, w| unsafe {
        w.latency()
            .bits(5)
            .prften()
            .set_bit()
            .icen()
            .set_bit()
            .dcen()
            .set_bit()
    });
    // 8 MHz / 8 × 336 / 2 = 168 MHz; USB 336 / 7 = 48 MHz.
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    rcc.pllcfgr().write(|w| unsafe {
        w.pllsrc()
            .set_bit()
            .pllm()
            .bits(8)
            .plln()
            .bits(336)
            .pllp()
            .bits(0b00)
            .pllq()
            .bits(7)
    });
    rcc.cr().modify(|_, w| w.pllon().set_bit());
    while rcc.cr().read().pllrdy().bit_is_clear() {}
    // AHB /1, APB1 /4 (42 MHz), APB2 /2 (84 MHz), system clock from the PLL.
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    rcc.cfgr().modify(|_, w| unsafe {
        w.hpre()
            .bits(0)
            .ppre1()
            .bits(0b101)
            .ppre2()
            .bits(0b100)
            .sw()
            .bits(0b10)
    });
    while rcc.cfgr().read().sws().bits() != 0b10 {}
}

#[cfg(feature = "qemu")]
fn clocks(_: &pac::Peripherals) {
    // HSI 16 MHz from reset; QEMU 7.2 would hang on any ready-bit wait.
}

/// USART1 and the timers of the step outputs.
pub struct Board {
    /// USART1.
    pub serial: Serial,
    /// The run clock of the step events.
    pub tim2: StepTimer,
    /// The step interrupt's alarm (TIM5, stopped).
    pub alarm: Alarm,
    /// The STEP pulse's end (SysTick, stopped).
    pub pulse: Pulse,
    /// The spindle and coolant outputs (low).
    pub spindle: spindle::Spindle,
    /// The watchdog and its supervisor's timer (not started).
    pub watchdog: Watchdog,
    /// The flash interface, for the offsets kept across power cuts.
    pub flash: pac::FLASH,
    /// Where the switches' samples come from under QEMU.
    pub panel: Panel,
}

/// The handwheel's quadrature counter: TIM8 in encoder mode on PC6 / PC7
/// (AF3), counting every edge of both channels (four per detent), each
/// channel filtered over 8 samples at its timer clock / 128 (APB2's
/// timers run at 168 MHz: a glitch under 6 µs counts nothing, and edges
/// up to about 150 kHz count, far above a hand-turned wheel's few kHz).
#[cfg(not(feature = "qemu"))]
fn wheel_counter(rcc: &pac::RCC, gpioc: &pac::GPIOC, tim: pac::TIM8) {
    rcc.apb2enr().modify(|_, w| w.tim8en().set_bit());
    // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
    gpioc
        .afrl()
        .modify(|_, w| unsafe { w.afrl6().bits(3).afrl7().bits(3) });
    // SAFETY: as above.
    gpioc
        .moder()
        .modify(|_, w| unsafe { w.moder6().bits(0b10).moder7().bits(0b10) });
    // SAFETY: as above: TI1 and TI2 as inputs, filter fDTS/32 × 8 (fDTS
    // the timer clock / 4, CKD below).
    tim.ccmr1_input().write(|w| unsafe {
        w.cc1s()
            .bits(0b01)
            .cc2s()
            .bits(0b01)
            .ic1f()
            .bits(0b1111)
            .ic2f()
            .bits(0b1111)
    });
    tim.cr1().write(|w| w.ckd().div4());
    tim.smcr().write(|w| w.sms().encoder_mode_3());
    // SAFETY: as above: the full 16-bit range.
    tim.arr().write(|w| unsafe { w.bits(0xFFFF) });
    tim.cr1().modify(|_, w| w.cen().set_bit());
}

/// The handwheel's edges counted so far, modulo 2¹⁶ (four per detent).
/// Under QEMU, which models no encoder, what the panel's wheel samples
/// added.
#[inline(always)]
pub fn wheel_edges() -> u16 {
    #[cfg(feature = "qemu")]
    {
        PANEL_WHEEL.load(core::sync::atomic::Ordering::Acquire)
    }
    #[cfg(not(feature = "qemu"))]
    {
        // SAFETY: a read of the counter, which only the timer writes.
        unsafe { (*pac::TIM8::ptr()).cnt().read().bits() as u16 }
    }
}

/// The switches' pin levels as the bits of `core_nostd::inputs::Input`
/// (set: the pin reads high): PA0 E-stop, PA1 X−, PA4 X+, PA5 Z−, PA6 Z+,
/// PA7 door, PA8 feed hold, PC4 cycle start, PC5 probe, PB0 X's fault, PB1
/// Z's fault. Under QEMU, which has no GPIO, the last sample the panel
/// gave.
#[inline(always)]
pub fn input_pins() -> u16 {
    #[cfg(feature = "qemu")]
    {
        PANEL_PINS.load(core::sync::atomic::Ordering::Acquire)
    }
    #[cfg(not(feature = "qemu"))]
    {
        // SAFETY: reads of the input registers, which nothing writes.
        let (a, b, c) = unsafe {
            (
                (*pac::GPIOA::ptr()).idr().read().bits(),
                (*pac::GPIOB::ptr()).idr().read().bits(),
                (*pac::GPIOC::ptr()).idr().read().bits(),
            )
        };
        ((a & 0b11) | ((a >> 4) & 0b1_1111) << 2 | ((c >> 4) & 0b11) << 7 | (b & 0b11) << 9) as u16
    }
}

/// The EXTI lines of the stopping switches: PA0 E-stop, PA1 X−, PA4 X+,
/// PA5 Z−, PA6 Z+. (The drive faults on PB0/PB1 would need lines 0 and 1,
/// the E-stop's and X−'s: they are sampled every millisecond.)
pub const STOP_LINES: u32 = 1 << 0 | 1 << 1 | 1 << 4 | 1 << 5 | 1 << 6;

/// The vectors of the tasks pended by software: interrupts of peripherals
/// this board leaves off (SPI1, SPI2), so that EXTI lines 0 and 1 are the
/// switches'.
pub const PREP_IRQ: Interrupt = Interrupt::SPI1;
/// See [`PREP_IRQ`]: the real-time task.
pub const REALTIME_IRQ: Interrupt = Interrupt::SPI2;
/// The switches' sampler: EXTI line 2's vector (no switch is on line 2, its
/// line stays masked). Its number is below USART2's, so that under QEMU a
/// sample the panel completes is taken before the panel's next byte, as
/// every millisecond's is on the board.
pub const SAMPLER_IRQ: Interrupt = Interrupt::EXTI2;

/// An edge on a stopping switch (its EXTI interrupt): the lines' pending
/// bits cleared and the lines masked until the next millisecond's sample
/// ([`edges_unmask`]), so that a chattering contact costs at most one
/// extra sample a millisecond.
#[inline(always)]
pub fn edges_take() {
    // SAFETY: the EXTI's mask and pending registers, written only here, in
    // `edges_unmask` and at init, all at the sampler's priority or before
    // the tasks start.
    let exti = unsafe { &*pac::EXTI::ptr() };
    // SAFETY: bits of the lines this board uses.
    exti.imr()
        .modify(|r, w| unsafe { w.bits(r.bits() & !STOP_LINES) });
    // SAFETY: writing 1 clears a pending line.
    exti.pr().write(|w| unsafe { w.bits(STOP_LINES) });
}

/// The stopping switches' edges interrupt again (every millisecond, before
/// the sample).
#[inline(always)]
pub fn edges_unmask() {
    // SAFETY: as in `edges_take`.
    let exti = unsafe { &*pac::EXTI::ptr() };
    // SAFETY: bits of the lines this board uses.
    exti.imr()
        .modify(|r, w| unsafe { w.bits(r.bits() | STOP_LINES) });
}

/// The last sample the panel gave (`qemu` builds).
#[cfg(feature = "qemu")]
static PANEL_PINS: core::sync::atomic::AtomicU16 = core::sync::atomic::AtomicU16::new(0);
/// The handwheel's edges the panel gave, modulo 2¹⁶ (`qemu` builds).
#[cfg(feature = "qemu")]
static PANEL_WHEEL: core::sync::atomic::AtomicU16 = core::sync::atomic::AtomicU16::new(0);

/// The test harness's panel under QEMU: USART2 receives samples of the
/// switches' pin levels, two bytes each (the first with bit 7 set and pins
/// 0–6, the second with pins 7–13). A sample with pin 13 set is the
/// handwheel's instead: bits 0–12 the detents it turned, signed (two's
/// complement). The board reads its pins and its counter instead.
pub struct Panel {
    #[cfg(feature = "qemu")]
    usart: pac::USART2,
    #[cfg(feature = "qemu")]
    low: Option<u8>,
}

impl Panel {
    #[cfg(feature = "qemu")]
    fn start(rcc: &pac::RCC, usart: pac::USART2) -> Panel {
        rcc.apb1enr().modify(|_, w| w.usart2en().set_bit());
        usart
            .cr1()
            .write(|w| w.ue().set_bit().re().set_bit().rxneie().set_bit());
        Panel { usart, low: None }
    }

    /// USART2's interrupt: takes a received byte; whether it completed a
    /// sample (then [`input_pins`] gives it), and whether that raised a
    /// stopping switch's edge interrupt.
    #[inline(always)]
    pub fn receive(&mut self) -> PanelSample {
        #[cfg(feature = "qemu")]
        {
            let sr = self.usart.sr().read();
            if sr.rxne().bit_is_clear() && sr.ore().bit_is_clear() {
                return PanelSample::None;
            }
            let b = self.usart.dr().read().bits() as u8;
            if b & 0x80 != 0 {
                self.low = Some(b & 0x7F);
                return PanelSample::None;
            }
            let Some(low) = self.low.take() else {
                return PanelSample::None;
            };
            let pins = u16::from(low) | u16::from(b) << 7;
            if pins & 1 << 13 != 0 {
                // 13 bits, signed: four edges a detent, as the counter's.
                let detents = ((pins << 3) as i16) >> 3;
                let edges = (detents as u16).wrapping_mul(4);
                let was = PANEL_WHEEL.load(core::sync::atomic::Ordering::Acquire);
                PANEL_WHEEL.store(
                    was.wrapping_add(edges),
                    core::sync::atomic::Ordering::Release,
                );
            } else {
                let was = PANEL_PINS.swap(pins, core::sync::atomic::Ordering::AcqRel);
                // QEMU models no GPIO, and its EXTI raises nothing on a
                // software trigger: a stopping switch's change is its
                // line's interrupt pended, as the pin's edge would.
                let changed = was ^ pins;
                let mut edge = false;
                for (bits, irq) in [
                    (1 << 0, Interrupt::EXTI0),
                    (1 << 1, Interrupt::EXTI1),
                    (1 << 2, Interrupt::EXTI4),
                    (1 << 3 | 1 << 4, Interrupt::EXTI9_5),
                ] {
                    if changed & bits != 0 {
                        pac::NVIC::pend(irq);
                        edge = true;
                    }
                }
                if edge {
                    return PanelSample::Edge;
                }
            }
            PanelSample::Sample
        }
        #[cfg(not(feature = "qemu"))]
        PanelSample::None
    }
}

/// What a byte from the test harness's panel came to ([`Panel::receive`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PanelSample {
    /// Nothing yet (the first byte of a sample, or none).
    None,
    /// A sample: the millisecond's sample is due.
    Sample,
    /// A sample in which a stopping switch changed: its edge interrupt is
    /// pended, which samples at once when no filter is set.
    Edge,
}

/// What [`crate::supervisor::start`] takes.
pub struct Watchdog {
    /// The independent watchdog.
    pub iwdg: pac::IWDG,
    /// The supervisor's timer (enabled, not configured).
    pub tim3: pac::TIM3,
    /// Debug freeze of both.
    pub dbgmcu: pac::DBGMCU,
}

/// USART1: replies out, request bytes in through its interrupt.
pub struct Serial {
    usart: pac::USART1,
}

impl Serial {
    /// Sends bytes, waiting for the transmitter each time.
    pub fn send(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while self.usart.sr().read().txe().bit_is_clear() {}
            // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
            self.usart.dr().write(|w| unsafe { w.bits(u16::from(b)) });
        }
    }

    /// Takes received bytes again after [`rx_pause`].
    pub fn rx_resume(&mut self) {
        self.usart.cr1().modify(|_, w| w.rxneie().set_bit());
        // SAFETY: the line's handler shares only its queue and atomics;
        // its priority was set before the scheduler started.
        unsafe { pac::NVIC::unmask(Interrupt::USART1) };
    }
}

/// The received byte, if USART1 holds one (from its interrupt).
#[inline(always)]
pub fn rx_byte() -> Option<u8> {
    // SAFETY: read-only status access, and the data register, which only
    // the line's interrupt reads.
    let usart = unsafe { &*pac::USART1::ptr() };
    let sr = usart.sr().read();
    (sr.rxne().bit_is_set() || sr.ore().bit_is_set()).then(|| usart.dr().read().bits() as u8)
}

/// Whether USART1 holds a received byte.
#[inline(always)]
pub fn rx_ready() -> bool {
    // SAFETY: read-only status access.
    let sr = unsafe { &*pac::USART1::ptr() }.sr().read();
    sr.rxne().bit_is_set() || sr.ore().bit_is_set()
}

/// Stops taking received bytes (its queue is full): the byte stays in
/// USART1 until [`Serial::rx_resume`]. The NVIC line is masked too: QEMU
/// 7.2 keeps the USART's interrupt raised while RXNE is set, whatever
/// RXNEIE says.
pub fn rx_pause() {
    // SAFETY: a read-modify-write of CR1 from the line's own interrupt,
    // the only writer besides `rx_resume`, which runs only once this has
    // masked the interrupt.
    unsafe { &*pac::USART1::ptr() }
        .cr1()
        .modify(|_, w| w.rxneie().clear_bit());
    pac::NVIC::mask(Interrupt::USART1);
}

/// Sleeps until an interrupt unless `ready` already holds; no wake-up is
/// lost between the check and the sleep.
/// The check runs with every interrupt masked (the one global critical
/// section left, a few instructions long): an interrupt that comes then
/// still wakes the core, and is taken as soon as the check is over.
///
/// In the `qemu-timed` build the core never sleeps: QEMU's virtual time
/// then advances by the instructions run (`-icount`), and a timer fires
/// on its tick instead of when the host wakes QEMU up (tens of
/// microseconds to milliseconds late). (The `qemu-paced` build's own
/// rule is [`crate::motion::sleep_unless`].)
pub fn sleep_unless(mut ready: impl FnMut() -> bool) {
    if cfg!(feature = "qemu-timed") {
        return;
    }
    cortex_m::interrupt::free(|_| {
        if !ready() {
            cortex_m::asm::wfi();
        }
    });
}

/// TIM2's count: microseconds, free-running (it wraps after 71 minutes).
#[inline(always)]
pub fn ticks() -> u32 {
    // SAFETY: a read of the counter, which nothing else writes after init.
    unsafe { &*pac::TIM2::ptr() }.cnt().read().bits()
}

/// TIM2 as the step clock: a free-running 32-bit counter at the device's
/// tick rate (1 MHz); runs are timed from its count at their start.
pub struct StepTimer {
    tim: pac::TIM2,
}

impl StepTimer {
    /// The timer's counter.
    #[inline(always)]
    pub fn count(&self) -> u32 {
        self.tim.cnt().read().bits()
    }

    /// Counts freely at the device's tick rate.
    fn count_ticks(&mut self) {
        let psc = TIM2_CLK_HZ / TickRate::TIMER.hz() - 1;
        self.start(psc);
    }

    /// Runs the counter freely at the undivided timer clock (measurements).
    pub fn free_run(&mut self) {
        self.start(0);
    }

    fn start(&mut self, psc: u32) {
        self.tim.cr1().modify(|_, w| w.cen().clear_bit());
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        self.tim.psc().write(|w| unsafe { w.bits(psc) });
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        self.tim.arr().write(|w| unsafe { w.bits(u32::MAX) });
        self.tim.egr().write(|w| w.ug().set_bit());
        self.tim.dier().modify(|_, w| w.uie().clear_bit());
        self.tim.cr1().modify(|_, w| w.cen().set_bit());
    }
}

/// The longest alarm, ticks (under QEMU within SysTick's 24 bits at up
/// to 1000 cycles a tick); a longer wait is armed again when it fires.
const ALARM_MAX_TICKS: u32 = if cfg!(feature = "qemu") {
    16_000
} else {
    1 << 30
};

/// The step interrupt's alarm: one-shot, in ticks of TIM2. On the board
/// TIM5; under paced QEMU SysTick, which pends the step interrupt: QEMU
/// 7.2's STM32 timers do not schedule a one-shot update right.
pub struct Alarm {
    #[cfg(not(feature = "qemu"))]
    tim: pac::TIM5,
    #[cfg(feature = "qemu")]
    syst: cortex_m::peripheral::SYST,
    /// Alarm counts per tick of TIM2.
    per_tick: u32,
}

/// The STEP pulse's end: SysTick on the board; none under QEMU, where
/// the step interrupt ends the pulse when it comes to the next step.
pub struct Pulse {
    #[cfg(not(feature = "qemu"))]
    syst: cortex_m::peripheral::SYST,
    #[cfg(not(feature = "qemu"))]
    per_tick: u32,
}

/// What the board's pulse timer adds to a step, in instructions (under
/// QEMU, where SysTick is the alarm, measured on the same writes to it
/// with its interrupt masked): the step interrupt starts it, its own
/// interrupt stops it and writes the STEP lines low.
pub fn pulse_timer_cost(clock: &StepTimer) -> u32 {
    let t0 = clock.count();
    // SAFETY: SysTick's and SCB's registers, as `Pulse::arm`, then as the
    // pulse's end does; the bench runs with interrupts masked.
    unsafe {
        (*cortex_m::peripheral::SCB::PTR).icsr.write(1 << 25);
        (*cortex_m::peripheral::SYST::PTR).cvr.write(0);
        (*cortex_m::peripheral::SYST::PTR).csr.write(SYST_OFF);
        (*cortex_m::peripheral::SYST::PTR).csr.write(SYST_OFF);
    }
    pins::write(pins::FALL);
    let t1 = clock.count();
    let t2 = clock.count();
    t1.wrapping_sub(t0).saturating_sub(t2.wrapping_sub(t1))
}

/// Whether a timer ends each STEP pulse (the board).
pub const PULSE_TIMER: bool = !cfg!(feature = "qemu");

/// Core cycles per tick of TIM2: known on the board, measured under QEMU.
///
/// QEMU runs both clocks on the host's time, and the host may stop QEMU
/// for milliseconds between any two instructions; its SysTick also reads
/// 0 until QEMU has loaded it, some time after it was started, and while
/// a wrap waits to be handled. So each reading of the two clocks is taken
/// within one tick of TIM2 and with SysTick running, a window of 1000
/// ticks lies between two readings, a window with a wrap in it is not
/// used, and the ratio is the median of five windows.
fn cycles_per_tick(syst: &mut cortex_m::peripheral::SYST, clock: &StepTimer) -> u32 {
    use cortex_m::peripheral::syst::SystClkSource;
    syst.set_clock_source(SystClkSource::Core);
    syst.disable_interrupt();
    if !cfg!(feature = "qemu") {
        return SYSCLK_HZ / TickRate::TIMER.hz();
    }
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();
    // Both clocks read together: TIM2's count and SysTick's, or none.
    let reading = || {
        let a = clock.count();
        let v = cortex_m::peripheral::SYST::get_current();
        let b = clock.count();
        (b.wrapping_sub(a) <= 1 && v != 0).then_some((a, v))
    };
    let mut ratios = [0u32; 5];
    let mut n = 0;
    let mut tries = 0;
    while n < ratios.len() && tries < 200 {
        tries += 1;
        let Some((t0, v0)) = reading() else { continue };
        while clock.count().wrapping_sub(t0) < 1000 {}
        let Some((t1, v1)) = reading() else { continue };
        let dt = t1.wrapping_sub(t0);
        // SysTick counts down: a window with a wrap (or a stop) in it
        // reads no lower at its end. 50 ms stays well inside one wrap at
        // any clock QEMU gives the core.
        if v1 >= v0 || dt > 50_000 {
            continue;
        }
        if let (Some(r), Some(ratio)) = (ratios.get_mut(n), (v0 - v1).checked_div(dt)) {
            *r = ratio;
            n += 1;
        }
    }
    syst.disable_counter();
    let found = ratios.get_mut(..n).unwrap_or_default();
    found.sort_unstable();
    // QEMU 7.2 runs the netduinoplus2's core (SysTick's clock) at 168 MHz:
    // its count per tick if nothing could be measured.
    found.get(n / 2).copied().unwrap_or(168).max(1)
}

/// SysTick's control bits: ENABLE, TICKINT, the core clock; or only the
/// clock (stopped).
const SYST_ON: u32 = 0b111;
const SYST_OFF: u32 = 0b100;

/// Makes the two step timers: TIM5 and SysTick on the board, SysTick as
/// the alarm under QEMU.
fn step_timers(
    tim5: pac::TIM5,
    mut syst: cortex_m::peripheral::SYST,
    clock: &StepTimer,
) -> (Alarm, Pulse) {
    let per_tick = cycles_per_tick(&mut syst, clock);
    #[cfg(not(feature = "qemu"))]
    {
        let psc = TIM2_CLK_HZ / TickRate::TIMER.hz() - 1;
        // SAFETY (all the writes below): TIM5's own registers, raw values
        // of fields the reference manual documents.
        tim5.cr1().write(|w| unsafe { w.bits(Alarm::CR1) });
        tim5.psc().write(|w| unsafe { w.bits(psc) });
        // Load the prescaler without an interrupt (URS).
        tim5.egr().write(|w| w.ug().set_bit());
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        tim5.sr().write(|w| unsafe { w.bits(0) });
        tim5.dier().write(|w| w.uie().set_bit());
        (
            Alarm {
                tim: tim5,
                per_tick: 1,
            },
            Pulse { syst, per_tick },
        )
    }
    #[cfg(feature = "qemu")]
    {
        // TIM5 stays unused.
        let _ = tim5;
        // At most what keeps the longest alarm within SysTick's 24 bits.
        let per_tick = (per_tick - per_tick / 16).clamp(1, 0x00FF_FFFF / ALARM_MAX_TICKS);
        (Alarm { syst, per_tick }, Pulse {})
    }
}

impl Alarm {
    #[cfg(not(feature = "qemu"))]
    const CR1: u32 = 0b1100; // URS, OPM

    /// The longest wait it takes, ticks: a longer one fires early, at this.
    pub const LONGEST: u32 = ALARM_MAX_TICKS;

    /// Its counts per tick of TIM2.
    pub fn per_tick(&self) -> u32 {
        self.per_tick
    }

    /// Fires in `ticks` (1 at least).
    #[inline(always)]
    pub fn arm(&mut self, ticks: u32) {
        #[cfg(not(feature = "qemu"))]
        let t = ticks.min(ALARM_MAX_TICKS);
        // Within SysTick's 24 bits: `per_tick` is bounded for it.
        #[cfg(feature = "qemu")]
        let t = ticks.min(ALARM_MAX_TICKS) * self.per_tick;
        // SAFETY: TIM5's own registers: the period, and CR1 with the bits
        // of `step_timers` and CEN. One-pulse mode leaves the counter at 0
        // when it fires (`stop` clears it too).
        #[cfg(not(feature = "qemu"))]
        {
            // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
            self.tim.arr().write(|w| unsafe { w.bits(t) });
            // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
            self.tim.cr1().write(|w| unsafe { w.bits(Self::CR1 | 1) });
        }
        // SAFETY: SysTick's own registers (24 bits of reload). Its clock
        // against TIM2 is measured, not known: `per_tick` is a sixteenth
        // short, it fires early, and the step interrupt waits for the rest.
        #[cfg(feature = "qemu")]
        unsafe {
            self.syst.rvr.write(t);
            self.syst.cvr.write(0);
            self.syst.csr.write(SYST_ON);
        }
    }

    /// Its interrupt is being answered.
    #[inline(always)]
    pub fn clear(&mut self) {
        // SAFETY: writing 0 clears the update flag.
        #[cfg(not(feature = "qemu"))]
        self.tim.sr().write(|w| unsafe { w.bits(0) });
    }

    /// Stops it.
    pub fn stop(&mut self) {
        // SAFETY: as in `arm`, without CEN; the counter back to 0, the
        // flag cleared.
        #[cfg(not(feature = "qemu"))]
        {
            self.tim.cr1().write(|w| unsafe { w.bits(Self::CR1) });
            // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
            self.tim.cnt().write(|w| unsafe { w.bits(0) });
            // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
            self.tim.sr().write(|w| unsafe { w.bits(0) });
        }
        // SAFETY: SysTick's control register.
        #[cfg(feature = "qemu")]
        unsafe {
            self.syst.csr.write(SYST_OFF)
        };
    }
}

/// SysTick's interrupt under paced QEMU: the alarm fired; SysTick stops
/// and the step interrupt runs.
#[cfg(feature = "qemu")]
pub fn alarm_fired() {
    // SAFETY: SysTick's control register, which only the alarm writes.
    unsafe { (*cortex_m::peripheral::SYST::PTR).csr.write(SYST_OFF) };
    pac::NVIC::pend(Interrupt::TIM5);
}

impl Pulse {
    /// The pulse lasts `ticks` ticks from [`Pulse::arm`].
    pub fn set_width(&mut self, ticks: u32) {
        #[cfg(not(feature = "qemu"))]
        self.syst
            .set_reload((ticks.max(1) * self.per_tick).min(0x00FF_FFFF));
        let _ = ticks;
    }

    /// Starts the pulse's time; an end of the pulse before that is still
    /// pending is forgotten (it would end this one early).
    #[inline(always)]
    pub fn arm(&mut self) {
        // SAFETY: SysTick's own registers: a write clears the current
        // value; CSR with the bits above. ICSR's PENDSTCLR only clears
        // SysTick's pending state.
        #[cfg(not(feature = "qemu"))]
        unsafe {
            (*cortex_m::peripheral::SCB::PTR).icsr.write(1 << 25);
            self.syst.cvr.write(0);
            self.syst.csr.write(SYST_ON);
        }
    }

    /// Stops it (from its own interrupt, or a reset).
    #[inline(always)]
    pub fn stop() {
        // SAFETY: SysTick's control register, which only the step
        // interrupt and this one (at its priority) write.
        #[cfg(not(feature = "qemu"))]
        unsafe {
            (*cortex_m::peripheral::SYST::PTR).csr.write(SYST_OFF)
        }
    }
}

/// The STEP and DIR pins in one word of GPIOC's BSRR: X STEP PC0, X DIR
/// PC1, Z STEP PC2, Z DIR PC3 (DIR high: negative).
pub mod pins {
    use super::StepEvent;

    /// Both STEP lines low.
    pub const FALL: u32 = (1 << 16) | (1 << 18);

    /// The STEP lines of an event high.
    pub const fn rise(bits: u8) -> u32 {
        let mut w = 0;
        if bits & StepEvent::X_STEP != 0 {
            w |= 1 << 0;
        }
        if bits & StepEvent::Z_STEP != 0 {
            w |= 1 << 2;
        }
        w
    }

    /// The STEP lines low and the DIR lines of an event's stepping axes
    /// as it needs them.
    pub const fn fall_dir(bits: u8) -> u32 {
        let mut w = FALL;
        if bits & StepEvent::X_STEP != 0 {
            w |= if bits & StepEvent::X_NEG != 0 {
                1 << 1
            } else {
                1 << 17
            };
        }
        if bits & StepEvent::Z_STEP != 0 {
            w |= if bits & StepEvent::Z_NEG != 0 {
                1 << 3
            } else {
                1 << 19
            };
        }
        w
    }

    /// One write of GPIOC's BSRR: atomic, only the bits set change.
    #[inline(always)]
    pub fn write(word: u32) {
        // SAFETY: BSRR writes are atomic and touch only the pins whose
        // bits are set; these pins belong to the step interrupt.
        unsafe {
            (*stm32f4::stm32f405::GPIOC::ptr())
                .bsrr()
                .write(|w| w.bits(word))
        };
    }
}

/// Whether time is kept: on the board and in `qemu-paced`; a plain `qemu`
/// build issues steps and passes dwells as fast as the core runs.
pub const PACED: bool = cfg!(any(not(feature = "qemu"), feature = "qemu-paced"));

/// Busy-wait delays counted in core cycles.
pub struct CycleDelay;

impl DelayNs for CycleDelay {
    fn delay_ns(&mut self, ns: u32) {
        let cycles = (u64::from(ns) * u64::from(SYSCLK_HZ)).div_ceil(1_000_000_000);
        cortex_m::asm::delay(u32::try_from(cycles).unwrap_or(u32::MAX));
    }
}

/// One pin of GPIOC, driven through its set/reset register.
pub struct PortCPin(pub u8);

impl ErrorType for PortCPin {
    type Error = Infallible;
}

impl OutputPin for PortCPin {
    #[inline(always)]
    fn set_low(&mut self) -> Result<(), Infallible> {
        // SAFETY: BSRR writes are atomic and touch only this pin.
        let gpioc = unsafe { &*pac::GPIOC::ptr() };
        gpioc
            .bsrr()
            .write(|w| unsafe { w.bits(1u32 << (16 + u32::from(self.0 & 15))) });
        Ok(())
    }

    #[inline(always)]
    fn set_high(&mut self) -> Result<(), Infallible> {
        // SAFETY: as above.
        let gpioc = unsafe { &*pac::GPIOC::ptr() };
        gpioc
            .bsrr()
            .write(|w| unsafe { w.bits(1u32 << u32::from(self.0 & 15)) });
        Ok(())
    }
}

/// Drives every STEP output low at once, without needing the driver (panics).
pub fn step_outputs_low() {
    // SAFETY: a single atomic BSRR write.
    let gpioc = unsafe { &*pac::GPIOC::ptr() };
    gpioc.bsrr().write(|w| w.br0().set_bit().br2().set_bit());
}

/// User input `n` (1 … 4, PC8 … PC11) reads high; another `n` reads low.
pub fn user_input(n: u8) -> bool {
    let Some(pin) = n
        .checked_sub(1)
        .filter(|&i| i < 4)
        .map(|i| 8 + u32::from(i))
    else {
        return false;
    };
    // SAFETY: a read of GPIOC's input register, which nothing else writes.
    unsafe { (*pac::GPIOC::ptr()).idr().read().bits() & (1 << pin) != 0 }
}

//! The board: clocks, pins, USART1 and the step clock, by register.
//!
//! | signal | pin | |
//! |---|---|---|
//! | USART1 TX / RX | PA9 / PA10 (AF7) | 115200 8N1 |
//! | X STEP / X DIR | PC0 / PC1 | push-pull |
//! | Z STEP / Z DIR | PC2 / PC3 | push-pull |
//! | spindle and coolant | PB6 … PB10 | [`crate::spindle`] |
//!
//! Two configurations. The real board runs from an 8 MHz crystal through the
//! PLL at 168 MHz (APB2 84 MHz, APB1 42 MHz, timers 84 MHz). QEMU 7.2's
//! `netduinoplus2` emulates no RCC ready bits, so the `qemu` build stays on
//! the 16 MHz HSI and waits for nothing; QEMU's timers count at 1 GHz.

use core::cell::RefCell;
use core::convert::Infallible;
use core::sync::atomic::{AtomicBool, Ordering};
use core_nostd::step::TickRate;
use core_nostd::stepdir::TickClock;
use critical_section::Mutex;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, OutputPin};
use heapless::Deque;
use stm32f4::stm32f405::{self as pac, interrupt, Interrupt};

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

/// TIM2's counter clock before its prescaler.
#[cfg(not(feature = "qemu"))]
pub const TIM2_CLK_HZ: u32 = 84_000_000;
#[cfg(feature = "qemu")]
pub const TIM2_CLK_HZ: u32 = 1_000_000_000;

const BAUD: u32 = 115_200;

/// Bytes received and not yet handled. When it is full the receive interrupt
/// leaves the next byte in the UART and masks itself until the main loop has
/// made room, so nothing is dropped by this side.
static RX: Mutex<RefCell<Deque<u8, 512>>> = Mutex::new(RefCell::new(Deque::new()));
static RX_PAUSED: AtomicBool = AtomicBool::new(false);
/// The link speaks grbl (thread mode sets it as the protocol switches).
static GRBL: AtomicBool = AtomicBool::new(false);

/// Tells the serial interrupt which real-time bytes the link has.
pub fn set_grbl(on: bool) {
    GRBL.store(on, Ordering::Relaxed);
}

/// Brings up clocks, pins, USART1 and TIM2. Returns the board's devices.
pub fn init(dp: pac::Peripherals) -> Board {
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
    gpioa
        .afrh()
        .modify(|_, w| unsafe { w.afrh9().bits(7).afrh10().bits(7) });
    gpioa
        .moder()
        .modify(|_, w| unsafe { w.moder9().bits(0b10).moder10().bits(0b10) });
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

    let usart = dp.USART1;
    // Both boards give a divider well below 2^16.
    let brr = ((PCLK2_HZ + BAUD / 2) / BAUD) as u16;
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

    // SAFETY: the handler only touches the critical-section-protected queue
    // and atomics.
    unsafe {
        pac::NVIC::unmask(Interrupt::USART1);
    }
    let mut tim2 = StepTimer {
        tim: dp.TIM2,
        origin: 0,
        low: 0,
        high: 0,
    };
    tim2.count_ticks();
    if crate::supervisor::was_reset_by_watchdog(&dp.RCC) {
        defmt::warn!("the watchdog reset the board");
    }
    Board {
        serial: Serial { usart },
        tim2,
        tim5: dp.TIM5,
        spindle: crate::spindle::Spindle::new(dp.TIM4, &dp.GPIOB),
        watchdog: Watchdog {
            iwdg: dp.IWDG,
            tim3: dp.TIM3,
            dbgmcu: dp.DBGMCU,
        },
        flash: dp.FLASH,
    }
}

#[cfg(not(feature = "qemu"))]
fn clocks(dp: &pac::Peripherals) {
    let rcc = &dp.RCC;
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    while rcc.cr().read().hserdy().bit_is_clear() {}
    // 168 MHz needs 5 wait states at 3.3 V.
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
    /// The step interrupt's alarm (enabled, not configured).
    pub tim5: pac::TIM5,
    /// The spindle and coolant outputs (low).
    pub spindle: crate::spindle::Spindle,
    /// The watchdog and its supervisor's timer (not started).
    pub watchdog: Watchdog,
    /// The flash interface, for the offsets kept across power cuts.
    pub flash: pac::FLASH,
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
            self.usart.dr().write(|w| unsafe { w.bits(u16::from(b)) });
        }
    }

    /// The next received byte, if any; re-arms reception after a pause.
    pub fn receive(&mut self) -> Option<u8> {
        let byte = critical_section::with(|cs| {
            RX.borrow(cs)
                .try_borrow_mut()
                .ok()
                .and_then(|mut q| q.pop_front())
        });
        if byte.is_none() && RX_PAUSED.swap(false, Ordering::AcqRel) {
            self.usart.cr1().modify(|_, w| w.rxneie().set_bit());
            // SAFETY: the handler shares only the protected queue and atomics.
            unsafe { pac::NVIC::unmask(Interrupt::USART1) };
        }
        byte
    }
}

/// Sleeps until an interrupt unless `ready` already holds; no wake-up is
/// lost between the check and the sleep.
pub fn sleep_unless(ready: impl Fn() -> bool) {
    cortex_m::interrupt::free(|_| {
        if !ready() {
            cortex_m::asm::wfi();
        }
    });
    crate::supervisor::beat();
}

/// Whether bytes are waiting.
pub fn rx_pending() -> bool {
    critical_section::with(|cs| RX.borrow(cs).try_borrow().is_ok_and(|q| !q.is_empty()))
}

#[interrupt]
fn USART1() {
    // SAFETY: read-only status access and the data register; this handler is
    // the only reader of DR.
    let usart = unsafe { &*pac::USART1::ptr() };
    let sr = usart.sr().read();
    if sr.rxne().bit_is_set() || sr.ore().bit_is_set() {
        let full =
            critical_section::with(|cs| RX.borrow(cs).try_borrow().map_or(true, |q| q.is_full()));
        if full {
            // Leave the byte in DR; stop asking until there is room. The NVIC
            // line is masked too: QEMU 7.2 keeps the USART's interrupt raised
            // while RXNE is set, whatever RXNEIE says.
            usart.cr1().modify(|_, w| w.rxneie().clear_bit());
            pac::NVIC::mask(Interrupt::USART1);
            RX_PAUSED.store(true, Ordering::Release);
        } else {
            let byte = usart.dr().read().bits() as u8;
            // Real-time bytes act here, ahead of every queued byte. On a
            // grbl link `?`, `!`, `~` are real-time too; its jog cancel
            // holds here and, with the overrides, goes on in the queue to
            // the protocol.
            if GRBL.load(Ordering::Relaxed) {
                use core_nostd::protocol::grbl::GrblRealtime;
                match GrblRealtime::from_byte(byte) {
                    Some(GrblRealtime::Common(rt)) => {
                        drop_received_on_reset(rt);
                        return crate::motion::realtime(rt, true);
                    }
                    Some(GrblRealtime::JogCancel) => {
                        crate::motion::realtime(core_nostd::protocol::Realtime::Hold, true)
                    }
                    _ => {}
                }
            } else if let Some(rt) = core_nostd::protocol::Realtime::from_byte(byte) {
                drop_received_on_reset(rt);
                return crate::motion::realtime(rt, false);
            }
            critical_section::with(|cs| {
                if let Ok(mut q) = RX.borrow(cs).try_borrow_mut() {
                    let _ = q.push_back(byte);
                }
            });
        }
    }
}

/// A reset drops the bytes received before it and not yet read, with the
/// line they began (as grbl empties its receive buffer).
fn drop_received_on_reset(rt: core_nostd::protocol::Realtime) {
    if rt == core_nostd::protocol::Realtime::Reset {
        critical_section::with(|cs| {
            if let Ok(mut q) = RX.borrow(cs).try_borrow_mut() {
                q.clear();
            }
        });
    }
}

/// TIM2's count: microseconds, free-running (it wraps after 71 minutes).
pub fn ticks() -> u32 {
    // SAFETY: a read of the counter, which nothing else writes after init.
    unsafe { &*pac::TIM2::ptr() }.cnt().read().bits()
}

/// TIM2 as the step clock: a free-running 32-bit counter at the device's
/// tick rate (1 MHz), extended to 64 bits while a run waits on it.
pub struct StepTimer {
    tim: pac::TIM2,
    /// The counter at the run's start.
    origin: u32,
    /// Ticks of the run as last read: `high + low`.
    low: u32,
    high: u64,
}

impl StepTimer {
    /// The timer's counter.
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
        self.tim.psc().write(|w| unsafe { w.bits(psc) });
        self.tim.arr().write(|w| unsafe { w.bits(u32::MAX) });
        self.tim.egr().write(|w| w.ug().set_bit());
        self.tim.dier().modify(|_, w| w.uie().clear_bit());
        self.tim.cr1().modify(|_, w| w.cen().set_bit());
    }

    /// Ticks since the run began; read at least once every 2³² ticks (71
    /// minutes) while a run waits, which every wait does.
    pub(crate) fn now(&mut self) -> u64 {
        let c = self.count().wrapping_sub(self.origin);
        if c < self.low {
            self.high += 1 << 32;
        }
        self.low = c;
        self.high + u64::from(c)
    }
}

impl TickClock for StepTimer {
    fn start_run(&mut self) {
        self.origin = self.count();
        self.low = 0;
        self.high = 0;
    }

    /// Under QEMU the steps drive no motor; unless `qemu-paced` is set they
    /// are issued as fast as the core runs (QEMU's timer follows host time).
    #[cfg(all(feature = "qemu", not(feature = "qemu-paced")))]
    fn wait_until(&mut self, _tick: u64) {}

    #[cfg(any(not(feature = "qemu"), feature = "qemu-paced"))]
    fn wait_until(&mut self, tick: u64) {
        while self.now() < tick {}
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

//! The watchdog: the independent watchdog (IWDG, on its own 32 kHz LSI
//! clock) resets the board unless the supervisor kicks it, and the
//! supervisor kicks it only while the step interrupt and the main loop are
//! alive ([`core_nostd::watch`]). When either stalls it drives the step
//! outputs low, masks every interrupt and waits for the reset.
//!
//! | | |
//! |---|---|
//! | watchdog timeout | 100 ms nominal (LSI 17–47 kHz: 68–188 ms) |
//! | supervisor | TIM3 update, every 1 ms, the highest priority |
//! | step interrupt waiting without taking an entry | more than 2 ms: stalled |
//! | main loop without a heartbeat | more than 2 s: stalled |
//!
//! The supervisor shares only atomics and reads the step interrupt's
//! progress from its queue: it preempts the step interrupt, which runs
//! under no global critical section, and never waits on a lock. QEMU 7.2
//! models no IWDG, so `qemu` builds leave the supervisor stopped, but for
//! the `stall-test` build, which stalls the step interrupt on purpose and
//! shows the supervisor stop the outputs ([`crate::step`]).

use crate::board::{step_outputs_low, Watchdog};
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use core_nostd::watch::{StepSeen, Verdict, Watch};
use stm32f4::stm32f405::{self as pac, Interrupt};

/// The main loop's heartbeat.
static BEAT: AtomicU32 = AtomicU32::new(0);
/// A flash erase or write is under way (the core stalls on it).
static FLASHING: AtomicBool = AtomicBool::new(false);

/// Whether this build runs the supervisor.
const SUPERVISED: bool = cfg!(any(not(feature = "qemu"), feature = "stall-test"));

/// The main loop is alive.
#[inline(always)]
pub fn beat() {
    BEAT.fetch_add(1, Ordering::Relaxed);
}

/// The supervisor's timer, the watchdog, and its memory.
pub struct Supervisor {
    tim3: pac::TIM3,
    iwdg: pac::IWDG,
    watch: Option<Watch>,
}

/// Starts the watchdog and readies the supervisor's timer (its interrupt
/// is the scheduler's to enable). From here on a stall resets the board.
/// `per_tick`: the alarm's counts per tick (the `stall-test` build's
/// clock for the supervisor).
pub fn start(watchdog: Watchdog, per_tick: u32) -> Supervisor {
    let _ = per_tick;
    #[cfg(feature = "stall-test")]
    stall_clock(per_tick);
    let Watchdog { iwdg, tim3, dbgmcu } = watchdog;
    if SUPERVISED {
        // A core halted by a debugger halts the watchdog too.
        dbgmcu
            .apb1_fz()
            .modify(|_, w| w.dbg_iwdg_stop().set_bit().dbg_tim3_stop().set_bit());
        if !cfg!(feature = "qemu") {
            iwdg.kr().write(|w| w.key().start());
            watchdog_timeout(&iwdg, false);
        }
        // An update every 1 ms: TIM3 at 10 kHz on the board; undivided
        // under QEMU, whose timers keep their period only so.
        let (psc, arr) = if cfg!(feature = "qemu") {
            (0, crate::board::TIM2_CLK_HZ / 1_000 - 1)
        } else {
            (crate::board::TIM2_CLK_HZ / 10_000 - 1, 9)
        };
        // SAFETY: TIM3's own registers, raw values of documented fields.
        tim3.psc().write(|w| unsafe { w.bits(psc) });
        tim3.arr().write(|w| unsafe { w.bits(arr) });
        tim3.cr1().write(|w| w.urs().set_bit());
        tim3.egr().write(|w| w.ug().set_bit());
        // SAFETY: raw bits of fields the reference manual (RM0090) documents, values in their range.
        tim3.sr().write(|w| unsafe { w.bits(0) });
        tim3.dier().write(|w| w.uie().set_bit());
        tim3.cr1().modify(|_, w| w.cen().set_bit());
    }
    Supervisor {
        tim3,
        iwdg,
        watch: None,
    }
}

/// The `stall-test` build: QEMU's TIM3 does not keep its period, so
/// SysTick, unused by an unpaced build, pends the supervisor every 1 ms,
/// above the step interrupt.
#[cfg(feature = "stall-test")]
fn stall_clock(per_tick: u32) {
    use cortex_m::peripheral::scb::SystemHandler;
    // SAFETY: an unpaced build never arms its alarm, SysTick: this is its
    // only user. Its priority goes above the supervisor's (RTIC's 5:
    // 0xB0), set after the scheduler has set the bound ones.
    unsafe {
        let mut p = cortex_m::Peripherals::steal();
        p.SCB.set_priority(SystemHandler::SysTick, 0xA0);
        p.SYST.set_reload((per_tick * 1000).min(0x00FF_FFFF));
        p.SYST.clear_current();
        p.SYST.enable_interrupt();
        p.SYST.enable_counter();
    }
}

/// The watchdog's timeout: 100 ms (LSI / 8 = 4 kHz, 400 counts), or 32 s
/// (LSI / 256, 4095 counts) while the flash stalls the core; fed.
fn watchdog_timeout(iwdg: &pac::iwdg::RegisterBlock, long: bool) {
    // The supervisor's feed would lock the registers again half-way: with
    // every interrupt masked for these few writes.
    cortex_m::interrupt::free(|_| {
        iwdg.kr().write(|w| w.key().unlock());
        if long {
            iwdg.pr().write(|w| w.pr().divide_by256());
            // SAFETY: a reload value within the register's 12 bits.
            iwdg.rlr().write(|w| unsafe { w.rl().bits(4095) });
        } else {
            iwdg.pr().write(|w| w.pr().divide_by8());
            // SAFETY: as above.
            iwdg.rlr().write(|w| unsafe { w.rl().bits(400) });
        }
        while iwdg.sr().read().pvu().bit_is_set() || iwdg.sr().read().rvu().bit_is_set() {}
        iwdg.kr().write(|w| w.key().feed());
    });
}

/// Runs a flash operation that stalls the core for up to seconds (the axes
/// at rest): the watchdog waits 32 s meanwhile and the supervisor stands
/// aside; both resume as before when it ends.
pub fn while_flashing<T>(operation: impl FnOnce() -> T) -> T {
    if cfg!(feature = "qemu") {
        return operation();
    }
    // SAFETY: the watchdog's registers, written with interrupts masked so
    // that the supervisor's feed cannot come between.
    let iwdg = unsafe { &*pac::IWDG::ptr() };
    FLASHING.store(true, Ordering::Release);
    watchdog_timeout(iwdg, true);
    let out = operation();
    watchdog_timeout(iwdg, false);
    beat();
    FLASHING.store(false, Ordering::Release);
    out
}

impl Supervisor {
    /// The supervisor's interrupt: judges, then kicks the watchdog or
    /// stops everything.
    pub fn check(&mut self) {
        // SAFETY: writing 0 clears TIM3's update flag.
        self.tim3.sr().write(|w| unsafe { w.bits(0) });
        // The switches' sample, every 1 ms, at this priority; their edges
        // interrupt again.
        crate::board::edges_unmask();
        pac::NVIC::pend(crate::board::SAMPLER_IRQ);
        let now = crate::board::ticks();
        let beat = BEAT.load(Ordering::Relaxed);
        if FLASHING.load(Ordering::Acquire) {
            // The core stood still in the flash operation: watch afresh after.
            self.watch = None;
            self.iwdg.kr().write(|w| w.key().feed());
            return;
        }
        let step = StepSeen {
            waiting: pac::NVIC::is_pending(Interrupt::TIM5)
                || pac::NVIC::is_active(Interrupt::TIM5),
            taken: crate::step::READY.taken(),
        };
        let watch = self.watch.get_or_insert(Watch::new(now, beat));
        match watch.check(now, step, beat) {
            Verdict::Alive => {
                self.iwdg.kr().write(|w| w.key().feed());
            }
            stalled => stop(stalled),
        }
    }
}

/// Outputs low, nothing else runs, the watchdog resets the board.
fn stop(why: Verdict) -> ! {
    cortex_m::interrupt::disable();
    step_outputs_low();
    crate::board::spindle::all_low();
    defmt::error!("watchdog: {}", why);
    #[cfg(feature = "stall-test")]
    crate::step::stall::report(why);
    loop {
        cortex_m::asm::nop();
    }
}

//! The watchdog: the independent watchdog (IWDG, on its own 32 kHz LSI
//! clock) resets the board unless a supervisor interrupt kicks it, and the
//! supervisor kicks it only while the step interrupt and the main loop are
//! alive ([`core_nostd::watch`]). When either stalls it drives the step
//! outputs low, masks every interrupt and waits for the reset.
//!
//! | | |
//! |---|---|
//! | watchdog timeout | 100 ms nominal (LSI 17–47 kHz: 68–188 ms) |
//! | supervisor | TIM3 update, every 10 ms, above the step interrupt |
//! | step interrupt late by | more than 10 ms: stalled |
//! | main loop without a heartbeat | more than 2 s: stalled |
//!
//! The supervisor shares only atomics: it preempts the step interrupt and
//! never waits on the motion's lock. QEMU 7.2 models neither the IWDG nor a
//! timer whose period stays true, so `qemu` builds leave both stopped.

use crate::board::step_outputs_low;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use core_nostd::watch::{Verdict, Watch};
use stm32f4::stm32f405::{self as pac, interrupt, Interrupt};

/// The raw TIM2 count by which the step interrupt must run next.
static STEP_DUE: AtomicU32 = AtomicU32::new(0);
/// Whether the step interrupt has work (an alarm armed or a hand-over
/// pending).
static STEP_WAITED_ON: AtomicBool = AtomicBool::new(false);
/// The main loop's heartbeat.
static BEAT: AtomicU32 = AtomicU32::new(0);
/// A flash erase or write is under way (the core stalls on it).
static FLASHING: AtomicBool = AtomicBool::new(false);

/// The step interrupt must run by the raw TIM2 count `due`.
#[inline(always)]
pub fn step_due(due: u32) {
    STEP_DUE.store(due, Ordering::Relaxed);
    STEP_WAITED_ON.store(true, Ordering::Release);
}

/// The step interrupt has no work.
#[inline(always)]
pub fn step_idle() {
    STEP_WAITED_ON.store(false, Ordering::Release);
}

/// The main loop is alive.
#[inline(always)]
pub fn beat() {
    BEAT.fetch_add(1, Ordering::Relaxed);
}

/// Starts the watchdog and its supervisor (not under QEMU, which models
/// neither). From here on a stall resets the board.
pub fn start(watchdog: crate::board::Watchdog) {
    let crate::board::Watchdog { iwdg, tim3, dbgmcu } = watchdog;
    if cfg!(feature = "qemu") {
        return;
    }
    // A core halted by a debugger halts the watchdog too.
    dbgmcu
        .apb1_fz()
        .modify(|_, w| w.dbg_iwdg_stop().set_bit().dbg_tim3_stop().set_bit());
    iwdg.kr().write(|w| w.key().start());
    watchdog_timeout(&iwdg, false);

    // TIM3 at 10 kHz, an update every 1000 counts.
    let psc = crate::board::TIM2_CLK_HZ / 10_000 - 1;
    tim3.psc().write(|w| unsafe { w.bits(psc) });
    tim3.arr().write(|w| unsafe { w.bits(99) });
    tim3.cr1().write(|w| w.urs().set_bit());
    tim3.egr().write(|w| w.ug().set_bit());
    tim3.sr().write(|w| unsafe { w.bits(0) });
    tim3.dier().write(|w| w.uie().set_bit());
    tim3.cr1().modify(|_, w| w.cen().set_bit());
    // SAFETY: the handler shares only atomics; its priority is set before
    // it is unmasked.
    unsafe {
        let mut core = cortex_m::Peripherals::steal();
        core.NVIC.set_priority(Interrupt::TIM3, 0x00);
        pac::NVIC::unmask(Interrupt::TIM3);
    }
}

/// The watchdog's timeout: 100 ms (LSI / 8 = 4 kHz, 400 counts), or 32 s
/// (LSI / 256, 4095 counts) while the flash stalls the core; fed.
fn watchdog_timeout(iwdg: &pac::iwdg::RegisterBlock, long: bool) {
    // The supervisor's feed would lock the registers again half-way.
    cortex_m::interrupt::free(|_| {
        iwdg.kr().write(|w| w.key().unlock());
        if long {
            iwdg.pr().write(|w| w.pr().divide_by256());
            iwdg.rlr().write(|w| unsafe { w.rl().bits(4095) });
        } else {
            iwdg.pr().write(|w| w.pr().divide_by8());
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

/// Whether the last reset came from the watchdog (the flags are cleared).
pub fn was_reset_by_watchdog(rcc: &pac::RCC) -> bool {
    let by_watchdog = rcc.csr().read().wdgrstf().bit_is_set();
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
    by_watchdog
}

#[interrupt]
fn TIM3() {
    static mut WATCH: Option<Watch> = None;
    // SAFETY: this handler's own timer, and read-only access to TIM2's
    // counter and a write-only key of the watchdog.
    let (tim3, tim2, iwdg) =
        unsafe { (&*pac::TIM3::ptr(), &*pac::TIM2::ptr(), &*pac::IWDG::ptr()) };
    tim3.sr().write(|w| unsafe { w.bits(0) });
    let now = tim2.cnt().read().bits();
    let beat = BEAT.load(Ordering::Relaxed);
    let due = STEP_WAITED_ON
        .load(Ordering::Acquire)
        .then(|| STEP_DUE.load(Ordering::Relaxed));
    if FLASHING.load(Ordering::Acquire) {
        // The core stood still in the flash operation: watch afresh after.
        *WATCH = None;
        iwdg.kr().write(|w| w.key().feed());
        return;
    }
    let watch = WATCH.get_or_insert(Watch::new(now, beat));
    match watch.check(now, due, beat) {
        Verdict::Alive => {
            iwdg.kr().write(|w| w.key().feed());
        }
        stalled => stop(stalled),
    }
}

/// Outputs low, nothing else runs, the watchdog resets the board.
fn stop(why: Verdict) -> ! {
    cortex_m::interrupt::disable();
    step_outputs_low();
    defmt::error!("watchdog: {}", why);
    loop {
        cortex_m::asm::nop();
    }
}

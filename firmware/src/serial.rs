//! The serial line's receive interrupt: it only buffers bytes and hands
//! real-time bytes to their own task ([`crate::motion::realtime`]), in
//! order, with the time they arrived.
//!
//! | | |
//! |---|---|
//! | priority | below the prep, above the real-time task |
//! | work per byte | under 100 instructions (`host-sim qemu-bench`) |

use crate::board::{self, ticks};
use core::sync::atomic::{AtomicBool, Ordering};
use core_nostd::protocol::grbl::GrblRealtime;
use core_nostd::protocol::Realtime;
use heapless::spsc::{Consumer, Producer};
use stm32f4::stm32f405::Interrupt;

/// Bytes received and not yet handled by the protocol. When it is full
/// the receive interrupt leaves the next byte in the UART and masks
/// itself until the protocol has made room: nothing is dropped here.
pub const RX_BYTES: usize = 512;

/// A real-time byte: what it asks, whether the link answers it (grbl
/// answers neither a hold nor a resume), and when it arrived (TIM2 count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RtEvent {
    /// What it asks.
    pub rt: Realtime,
    /// Whether no `!` line answers it.
    pub quiet: bool,
    /// When it arrived.
    pub at: u32,
}

/// Real-time bytes waiting for their task; a reset that finds it full is
/// kept here.
pub const RT_EVENTS: usize = 16;
static RESET_LOST: AtomicBool = AtomicBool::new(false);

/// The receive interrupt paused itself (its queue was full).
static PAUSED: AtomicBool = AtomicBool::new(false);
/// The link speaks grbl (thread mode sets it as the protocol switches).
static GRBL: AtomicBool = AtomicBool::new(false);

/// Tells the receive interrupt which real-time bytes the link has.
pub fn set_grbl(on: bool) {
    GRBL.store(on, Ordering::Relaxed);
}

/// The receive interrupt's ends of its two queues.
pub struct Receiver {
    /// Bytes for the protocol.
    pub bytes: Producer<'static, u8>,
    /// Real-time bytes for their task.
    pub realtime: Producer<'static, RtEvent>,
}

impl Receiver {
    /// USART1's receive interrupt: buffers the byte, or hands a real-time
    /// byte to its task (a grbl jog cancel goes on to the protocol too).
    #[inline(always)]
    pub fn receive(&mut self) {
        if !board::rx_ready() {
            return;
        }
        if !self.bytes.ready() {
            board::rx_pause();
            PAUSED.store(true, Ordering::Release);
            return;
        }
        if let Some(byte) = board::rx_byte() {
            self.take(byte);
        }
    }

    /// What the receive interrupt does with a byte it read.
    #[inline(always)]
    pub fn take(&mut self, byte: u8) {
        let (rt, quiet, forward) = if GRBL.load(Ordering::Relaxed) {
            match GrblRealtime::from_byte(byte) {
                Some(GrblRealtime::Common(rt)) => (Some(rt), true, false),
                Some(GrblRealtime::JogCancel) => (Some(Realtime::Hold), true, true),
                _ => (None, false, true),
            }
        } else {
            match Realtime::from_byte(byte) {
                Some(rt) => (Some(rt), false, false),
                None => (None, false, true),
            }
        };
        if let Some(rt) = rt {
            let event = RtEvent {
                rt,
                quiet,
                at: ticks(),
            };
            if self.realtime.enqueue(event).is_err() && rt == Realtime::Reset {
                RESET_LOST.store(true, Ordering::Release);
            }
            rtic::pend(Interrupt::EXTI1);
        }
        if forward {
            // Room was checked.
            let _ = self.bytes.enqueue(byte);
        }
    }
}

/// Thread mode's end of the byte queue.
pub struct Bytes {
    bytes: Consumer<'static, u8>,
}

impl Bytes {
    /// Takes the consumer end.
    pub fn new(bytes: Consumer<'static, u8>) -> Bytes {
        Bytes { bytes }
    }

    /// The next received byte, if any; takes bytes again after a pause.
    pub fn receive(&mut self, serial: &mut board::Serial) -> Option<u8> {
        let byte = self.bytes.dequeue();
        if byte.is_none() && PAUSED.swap(false, Ordering::AcqRel) {
            serial.rx_resume();
        }
        byte
    }

    /// Whether bytes are waiting.
    pub fn pending(&self) -> bool {
        self.bytes.ready()
    }
}

/// The real-time task's end: the next byte to act on (a reset the queue
/// had no room for first).
pub fn next_realtime(rx: &mut Consumer<'static, RtEvent>) -> Option<RtEvent> {
    if RESET_LOST.swap(false, Ordering::AcqRel) {
        return Some(RtEvent {
            rt: Realtime::Reset,
            quiet: false,
            at: ticks(),
        });
    }
    rx.dequeue()
}

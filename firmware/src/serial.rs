//! The serial line's receive interrupt: it only buffers bytes and hands
//! real-time bytes to their own task ([`crate::motion::realtime`]), in
//! order, with the time they arrived.
//!
//! | | |
//! |---|---|
//! | priority | below the prep, above the real-time task |
//! | work per byte | under 100 instructions (`host-sim qemu-bench`) |

use crate::board::{self, ticks};
use crate::motion::RtEvent;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use core_nostd::protocol::grbl::GrblRealtime;
use core_nostd::protocol::Realtime;
use heapless::spsc::{Consumer, Producer};

/// Bytes received and not yet handled by the protocol. When it is full
/// the receive interrupt leaves the next byte in the UART and masks
/// itself until the protocol has made room: nothing is dropped here.
pub const RX_BYTES: usize = 512;

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

/// Whether the link speaks grbl (which answers no hold or resume).
pub fn grbl() -> bool {
    GRBL.load(Ordering::Relaxed)
}

/// A reset came: the bytes put in the queue before it are dropped unread
/// ([`DROP_TO`] counts them), as grbl empties its receive buffer.
static FLUSH: AtomicBool = AtomicBool::new(false);
/// Bytes the receive interrupt had put in the queue when the last reset
/// came (wrapping).
static DROP_TO: AtomicU32 = AtomicU32::new(0);

/// The receive interrupt's ends of its two queues.
pub struct Receiver {
    /// Bytes for the protocol.
    bytes: Producer<'static, u8>,
    /// Real-time bytes for their task.
    realtime: Producer<'static, RtEvent>,
    /// Bytes put in the queue since power-on (wrapping).
    put: u32,
}

impl Receiver {
    /// The producer ends of the byte queue and of the real-time queue.
    pub fn new(bytes: Producer<'static, u8>, realtime: Producer<'static, RtEvent>) -> Receiver {
        Receiver {
            bytes,
            realtime,
            put: 0,
        }
    }

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
            if rt == Realtime::Reset {
                // What came before the reset goes with it, the line being
                // received too (the protocol drops its part at the reset).
                DROP_TO.store(self.put, Ordering::Relaxed);
                FLUSH.store(true, Ordering::Release);
            }
            let event = RtEvent {
                rt,
                quiet,
                at: ticks(),
            };
            if self.realtime.enqueue(event).is_err() && rt == Realtime::Reset {
                RESET_LOST.store(true, Ordering::Release);
            }
            rtic::pend(crate::board::REALTIME_IRQ);
        }
        if forward {
            // Room was checked.
            let _ = self.bytes.enqueue(byte);
            self.put = self.put.wrapping_add(1);
        }
    }
}

/// Thread mode's end of the byte queue.
pub struct Bytes {
    bytes: Consumer<'static, u8>,
    /// Bytes taken from the queue since power-on (wrapping).
    got: u32,
    /// After a reset: the count of bytes put before it, until those are
    /// dropped.
    drop_to: Option<u32>,
}

impl Bytes {
    /// Takes the consumer end.
    pub fn new(bytes: Consumer<'static, u8>) -> Bytes {
        Bytes {
            bytes,
            got: 0,
            drop_to: None,
        }
    }

    /// The next received byte, if any; takes bytes again after a pause.
    /// Nothing while a reset waits for the protocol (the bytes after it
    /// belong to the new session), and never a byte that came before a
    /// reset.
    pub fn receive(&mut self, serial: &mut board::Serial) -> Option<u8> {
        if crate::motion::reset_waiting() {
            return None;
        }
        loop {
            let Some(byte) = self.bytes.dequeue() else {
                if PAUSED.swap(false, Ordering::AcqRel) {
                    serial.rx_resume();
                }
                return None;
            };
            let k = self.got;
            self.got = k.wrapping_add(1);
            // Looked at after the byte is taken: a reset that came before
            // this byte was put drops it.
            if FLUSH.swap(false, Ordering::Acquire) {
                self.drop_to = Some(DROP_TO.load(Ordering::Relaxed));
            }
            if let Some(to) = self.drop_to {
                // Byte `k` came before the reset when it is below `to`
                // (the two are at most a queue apart).
                if (to.wrapping_sub(k) as i32) > 0 {
                    continue;
                }
                self.drop_to = None;
            }
            return Some(byte);
        }
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

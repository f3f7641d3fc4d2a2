//! The defmt global logger: an RTT up channel on the board (read by a debug
//! probe), semihosting writes to the host's standard output under QEMU.
//!
//! Unlike the stock transports it never panics: a frame started while another
//! is open (only a fault handler could do that, since a frame holds a critical
//! section) is dropped.

use core::sync::atomic::{AtomicU8, Ordering};

static DEPTH: AtomicU8 = AtomicU8::new(0);
static mut RESTORE: critical_section::RestoreState = critical_section::RestoreState::invalid();
static mut ENCODER: defmt::Encoder = defmt::Encoder::new();

#[defmt::global_logger]
struct Logger;

// SAFETY: acquire/release pair up as defmt requires; the statics are touched
// only with interrupts disabled by the outermost acquire.
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        // SAFETY: paired with `release` below.
        let restore = unsafe { critical_section::acquire() };
        if DEPTH.load(Ordering::Relaxed) > 0 {
            DEPTH.store(2, Ordering::Relaxed);
            // SAFETY: the nested section is released at once; the outer holds.
            unsafe { critical_section::release(restore) };
            return;
        }
        DEPTH.store(1, Ordering::Relaxed);
        // SAFETY: interrupts are off.
        unsafe {
            RESTORE = restore;
            (*core::ptr::addr_of_mut!(ENCODER)).start_frame(sink::write);
        }
    }

    unsafe fn flush() {}

    unsafe fn release() {
        match DEPTH.load(Ordering::Relaxed) {
            1 => {
                // SAFETY: interrupts are off since acquire.
                unsafe {
                    (*core::ptr::addr_of_mut!(ENCODER)).end_frame(sink::write);
                    DEPTH.store(0, Ordering::Relaxed);
                    critical_section::release(RESTORE);
                }
            }
            // The nested frame ends; the outer one goes on.
            2 => DEPTH.store(1, Ordering::Relaxed),
            _ => {}
        }
    }

    unsafe fn write(bytes: &[u8]) {
        if DEPTH.load(Ordering::Relaxed) == 1 {
            // SAFETY: interrupts are off since acquire.
            unsafe { (*core::ptr::addr_of_mut!(ENCODER)).write(bytes, sink::write) };
        }
    }
}

/// Prepares the transport.
pub fn init() {
    sink::init();
}

/// Writes a line of text to the host's standard output (QEMU
/// semihosting), formatted here: at most 256 bytes of it.
#[cfg(feature = "qemu")]
pub fn host_print(args: core::fmt::Arguments) {
    let mut line: heapless::String<256> = heapless::String::new();
    let _ = core::fmt::write(&mut line, args);
    sink::write(line.as_bytes());
}

#[cfg(feature = "qemu")]
mod sink {
    use core::sync::atomic::{AtomicUsize, Ordering};

    static STDOUT: AtomicUsize = AtomicUsize::new(usize::MAX);

    pub fn init() {
        // SYS_OPEN ":tt" for writing ("w" is mode 4) is the host's stdout.
        let name = b":tt\0";
        // SAFETY: a semihosting call with a valid, NUL-terminated name.
        let handle = unsafe { cortex_m_semihosting::syscall!(OPEN, name.as_ptr(), 4usize, 3usize) };
        STDOUT.store(handle, Ordering::Relaxed);
    }

    /// Writes bytes to the host's standard output.
    pub fn write(bytes: &[u8]) {
        let handle = STDOUT.load(Ordering::Relaxed);
        if handle != usize::MAX {
            // SAFETY: SYS_WRITE reads `len` bytes from a valid slice.
            unsafe {
                cortex_m_semihosting::syscall!(WRITE, handle, bytes.as_ptr(), bytes.len());
            }
        }
    }
}

#[cfg(not(feature = "qemu"))]
mod sink {
    //! A SEGGER RTT control block with one up channel, non-blocking: bytes
    //! that do not fit are dropped.
    use core::cell::UnsafeCell;
    use core::sync::atomic::{AtomicUsize, Ordering};

    const SIZE: usize = 1024;

    #[repr(C)]
    struct Channel {
        name: *const u8,
        buffer: *mut u8,
        size: usize,
        write: AtomicUsize,
        read: AtomicUsize,
        flags: usize,
    }

    #[repr(C)]
    pub struct ControlBlock {
        id: [u8; 16],
        max_up: usize,
        max_down: usize,
        up: Channel,
    }

    struct Buffer(UnsafeCell<[u8; SIZE]>);
    // SAFETY: written only inside the logger's critical section.
    unsafe impl Sync for Buffer {}
    // SAFETY: the control block is read by the probe and written only inside
    // the logger's critical section.
    unsafe impl Sync for ControlBlock {}

    static BUFFER: Buffer = Buffer(UnsafeCell::new([0; SIZE]));

    #[no_mangle]
    static _SEGGER_RTT: ControlBlock = ControlBlock {
        id: *b"SEGGER RTT\0\0\0\0\0\0",
        max_up: 1,
        max_down: 0,
        up: Channel {
            name: c"defmt".as_ptr().cast(),
            buffer: BUFFER.0.get().cast(),
            size: SIZE,
            write: AtomicUsize::new(0),
            read: AtomicUsize::new(0),
            flags: 0,
        },
    };

    pub fn init() {}

    pub fn write(bytes: &[u8]) {
        let ch = &_SEGGER_RTT.up;
        let mut w = ch.write.load(Ordering::Acquire);
        let r = ch.read.load(Ordering::Acquire);
        for &b in bytes {
            let next = if w + 1 >= SIZE { 0 } else { w + 1 };
            if next == r || w >= SIZE {
                break;
            }
            // SAFETY: w < SIZE, checked above.
            unsafe { ch.buffer.add(w).write_volatile(b) };
            w = next;
        }
        ch.write.store(w, Ordering::Release);
    }
}

//! The firmware in QEMU: build the ELF, boot it on `netduinoplus2` with USART1
//! on a pseudo-terminal, and reach it with the same [`Client`] as a board.
//!
//! Facts of QEMU 7.2 this relies on: the firmware's `qemu` build runs on the
//! HSI (no RCC ready bits are emulated); USART1 is the first `-serial`; bytes
//! sent before the firmware has enabled its UART are lost, so the host
//! repeats `VER` until the device answers; semihosting carries the defmt log
//! and the exit code of a failed debug build.

use crate::link::{check_reply_line, Client, LinkError};
use std::io::{self, BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The QEMU binary.
pub const QEMU: &str = "qemu-system-arm";

/// The firmware crate's directory.
pub fn firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware")
}

/// Whether QEMU can be started here.
pub fn qemu_available() -> bool {
    Command::new(QEMU)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// For tests: whether QEMU is here. Where it is not, a note on standard
/// error and `false` (the test is skipped), but under CI (`CI` set) a
/// missing QEMU is a failure.
pub fn qemu_or_skip() -> bool {
    if qemu_available() {
        return true;
    }
    assert!(std::env::var_os("CI").is_none(), "CI needs {QEMU}");
    eprintln!("{QEMU} not found: QEMU test skipped");
    false
}

fn other(msg: String) -> LinkError {
    LinkError::Io(io::Error::other(msg))
}

/// Builds the firmware for QEMU (release, `--features <features>`) if it is
/// not up to date, and returns the controller ELF's path; the `bench` ELF
/// lies beside it.
///
/// Every feature set builds in the firmware's one target directory, so the
/// dependencies (the PAC, RTIC's macros) are compiled once, not once per
/// feature set: a build per directory took about 400 MB each. Cargo writes
/// every feature set's binaries to the same path, so the build and a copy
/// of its ELFs to `target/images/<features>/` happen under a file lock
/// (tests build in parallel threads and processes), and the copy is renamed
/// into place whole, so a QEMU booting the previous copy never reads half.
pub fn build_firmware(features: &str) -> Result<PathBuf, LinkError> {
    let dir = firmware_dir();
    let target_dir = dir.join("target");
    let images = target_dir.join("images").join(features.replace(',', "+"));
    std::fs::create_dir_all(&images).map_err(|e| other(format!("{}: {e}", images.display())))?;
    let lock_path = target_dir.join("images/.lock");
    let lock = std::fs::File::create(&lock_path)
        .map_err(|e| other(format!("{}: {e}", lock_path.display())))?;
    lock.lock()
        .map_err(|e| other(format!("{}: {e}", lock_path.display())))?;
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(&dir)
        .args(["build", "--release", "--features", features])
        .status()
        .map_err(|e| other(format!("cargo for the firmware: {e}")))?;
    if !status.success() {
        return Err(other(format!("firmware build failed ({status})")));
    }
    let built = target_dir.join("thumbv7em-none-eabihf/release");
    for name in ["firmware", "bench"] {
        let part = images.join(format!(".{name}.part"));
        std::fs::copy(built.join(name), &part)
            .and_then(|_| std::fs::rename(&part, images.join(name)))
            .map_err(|e| other(format!("{name} ELF into {}: {e}", images.display())))?;
    }
    drop(lock);
    Ok(images.join("firmware"))
}

/// Sends `requests` (raw lines, each ended by LF) one at a time, each after
/// the final line of the one before, and returns every reply line: for
/// requests whose replies outrun the link's receive queue (long tables).
pub fn one_by_one(client: &mut Client, requests: &[u8]) -> Result<Vec<u8>, LinkError> {
    let mut got = Vec::new();
    for line in requests.split_inclusive(|&b| b == b'\n') {
        client.write_raw(line)?;
        got.extend(client.read_finals(1)?);
    }
    Ok(got)
}

/// A running QEMU with the firmware.
pub struct Qemu {
    child: Child,
    pty: String,
    log: Arc<Mutex<Vec<u8>>>,
}

impl Qemu {
    /// Boots `elf`; `icount` makes instruction counts deterministic
    /// (`-icount shift=0`: one instruction, one nanosecond of virtual time).
    pub fn boot(elf: &Path, icount: bool) -> Result<Qemu, LinkError> {
        Self::boot_with(elf, icount, "pty")
    }

    /// Boots a paced build (`qemu-paced`): virtual time is the host's, and
    /// the step interrupt issues its events on their ticks of it.
    pub fn boot_paced(elf: &Path) -> Result<Qemu, LinkError> {
        Self::boot_icount(elf, None, "pty", "none")
    }

    /// Boots a paced build with the core's speed fixed: virtual time runs
    /// with the host's while the CPU sleeps and advances 8 ns per
    /// instruction while it works (`-icount shift=3`: 125 million
    /// instructions a second, what the board's 168 MHz core with flash
    /// wait states sustains), so time spent in code is the board's.
    pub fn boot_paced_timed(elf: &Path) -> Result<Qemu, LinkError> {
        Self::boot_icount(elf, Some("shift=3"), "pty", "none")
    }

    /// Boots `elf` with USART1 on a pty and the QEMU monitor on a unix
    /// socket (for `system_reset`).
    pub fn boot_monitor(elf: &Path, socket: &Path) -> Result<Qemu, LinkError> {
        let monitor = format!("unix:{},server,nowait", socket.display());
        Self::boot_full(elf, true, "pty", &monitor)
    }

    /// Boots `elf` (`icount` as [`Qemu::boot`], or paced) with USART1 on a
    /// pty and USART2, the switches' panel, on a unix socket that
    /// [`Panel::connect`] opens.
    pub fn boot_with_panel(elf: &Path, icount: bool, socket: &Path) -> Result<Qemu, LinkError> {
        let panel = format!("unix:{},server=on,wait=off", socket.display());
        let icount = icount.then_some("shift=0,sleep=off");
        Self::boot_args(elf, icount, "pty", "none", &["-serial", &panel])
    }

    /// Boots `elf` with USART1 on `serial` (`pty` or `null`).
    pub fn boot_with(elf: &Path, icount: bool, serial: &str) -> Result<Qemu, LinkError> {
        Self::boot_full(elf, icount, serial, "none")
    }

    fn boot_full(elf: &Path, icount: bool, serial: &str, monitor: &str) -> Result<Qemu, LinkError> {
        Self::boot_icount(elf, icount.then_some("shift=0,sleep=off"), serial, monitor)
    }

    fn boot_icount(
        elf: &Path,
        icount: Option<&str>,
        serial: &str,
        monitor: &str,
    ) -> Result<Qemu, LinkError> {
        Self::boot_args(elf, icount, serial, monitor, &[])
    }

    fn boot_args(
        elf: &Path,
        icount: Option<&str>,
        serial: &str,
        monitor: &str,
        more: &[&str],
    ) -> Result<Qemu, LinkError> {
        let mut cmd = Command::new(QEMU);
        cmd.args([
            "-machine",
            "netduinoplus2",
            "-display",
            "none",
            "-monitor",
            monitor,
            "-serial",
            serial,
            "-semihosting-config",
            "enable=on,target=native",
        ]);
        cmd.args(more);
        if let Some(icount) = icount {
            cmd.args(["-icount", icount]);
        }
        cmd.arg("-kernel").arg(elf);
        cmd.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd
            .spawn()
            .map_err(|e| other(format!("{QEMU}: {e} (is it installed?)")))?;
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| other("no stdout".into()))?;
        let stderr = child
            .stderr
            .take()
            .ok_or_else(|| other("no stderr".into()))?;
        let log = Arc::new(Mutex::new(Vec::new()));
        let (tx, rx) = mpsc::channel();
        // QEMU names the pty on stdout; what follows there is the
        // semihosting log.
        let out_log = Arc::clone(&log);
        let tx_out = tx.clone();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(stdout);
            let mut line = Vec::new();
            if reader.read_until(b'\n', &mut line).is_ok() {
                let text = String::from_utf8_lossy(&line);
                if let Some(p) = text.split("redirected to ").nth(1) {
                    let path = p.split_whitespace().next().unwrap_or("").to_owned();
                    let _ = tx_out.send(path);
                } else if let Ok(mut l) = out_log.lock() {
                    l.extend_from_slice(&line);
                }
            }
            let mut buf = [0u8; 1024];
            while let Ok(n) = reader.read(&mut buf) {
                if n == 0 {
                    break;
                }
                if let Ok(mut l) = out_log.lock() {
                    l.extend_from_slice(&buf[..n]);
                }
            }
        });
        let err_log = Arc::clone(&log);
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if let Some(p) = line.split("redirected to ").nth(1) {
                    let _ = tx.send(p.split_whitespace().next().unwrap_or("").to_owned());
                } else if let Ok(mut l) = err_log.lock() {
                    l.extend_from_slice(line.as_bytes());
                    l.push(b'\n');
                }
            }
        });
        let pty = if serial != "pty" {
            String::new()
        } else {
            match rx.recv_timeout(Duration::from_secs(10)) {
                Ok(p) if !p.is_empty() => p,
                _ => {
                    let _ = child.kill();
                    return Err(other("QEMU did not report its serial pty".into()));
                }
            }
        };
        Ok(Qemu { child, pty, log })
    }

    /// The host end of USART1.
    pub fn pty(&self) -> &str {
        &self.pty
    }

    /// Opens the link and waits until the firmware answers.
    pub fn connect(&mut self, timeout: Duration) -> Result<Client, LinkError> {
        let mut client = Client::open(&self.pty, Duration::from_millis(300))?;
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            if let Some(status) = self.child.try_wait()? {
                return Err(other(format!("QEMU exited early ({status})")));
            }
            client.write_raw(b"\r\nVER\r\n")?;
            let mut answered = false;
            while let Ok(line) = client.read_line() {
                if check_reply_line(&line).is_ok_and(|b| b.starts_with("OK PROTO=1")) {
                    answered = true;
                }
            }
            if answered {
                break;
            }
            if Instant::now() > deadline {
                return Err(LinkError::Timeout);
            }
        }
        client.drain();
        client.set_timeout(timeout);
        Ok(client)
    }

    /// Whatever QEMU and the firmware wrote besides the pty (the defmt
    /// frames and QEMU's own messages).
    pub fn log(&self) -> Vec<u8> {
        self.log.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// Waits for QEMU to exit by itself (a semihosting exit), up to `timeout`.
    pub fn wait_exit(&mut self, timeout: Duration) -> Option<std::process::ExitStatus> {
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            if let Ok(Some(s)) = self.child.try_wait() {
                return Some(s);
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        None
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs the `bench` firmware under `-icount shift=0` and returns its report
/// lines (instruction counts of the motion path on the Cortex-M4).
pub fn icount_bench(bench_elf: &Path) -> Result<Vec<String>, LinkError> {
    let mut q = Qemu::boot_with(bench_elf, true, "null")?;
    let status = q
        .wait_exit(Duration::from_secs(120))
        .ok_or(LinkError::Timeout)?;
    // Let the reader thread take the last bytes.
    std::thread::sleep(Duration::from_millis(100));
    if !status.success() {
        return Err(other(format!("bench firmware failed ({status})")));
    }
    let log = q.log();
    Ok(String::from_utf8_lossy(&log)
        .split('\n')
        .map(|l| l.trim_start_matches(|c: char| !c.is_ascii_graphic()))
        .filter(|l| l.contains(": ") && !l.chars().any(|c| c.is_control() || c == '\u{FFFD}'))
        .map(str::to_owned)
        .collect())
}

/// The firmware in QEMU as a byte link that can be power-cycled (QEMU's
/// `system_reset` through its monitor socket).
pub struct QemuLink {
    qemu: Qemu,
    client: Client,
    monitor: std::os::unix::net::UnixStream,
    /// Resets done.
    pub resets: u64,
}

impl QemuLink {
    /// Boots the firmware with a monitor socket and opens its UART.
    pub fn boot(elf: &Path) -> Result<QemuLink, LinkError> {
        let sock = std::env::temp_dir().join(format!("lathe-qemu-{}.sock", std::process::id()));
        let _ = std::fs::remove_file(&sock);
        let mut qemu = Qemu::boot_monitor(elf, &sock)?;
        let client = qemu.connect(Duration::from_secs(30))?;
        let mut monitor = None;
        for _ in 0..100 {
            if let Ok(m) = std::os::unix::net::UnixStream::connect(&sock) {
                monitor = Some(m);
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let monitor = monitor.ok_or_else(|| other("no QEMU monitor socket".into()))?;
        Ok(QemuLink {
            qemu,
            client,
            monitor,
            resets: 0,
        })
    }

    /// QEMU and the firmware's log.
    pub fn qemu(&self) -> &Qemu {
        &self.qemu
    }
}

impl crate::reliable::ByteLink for QemuLink {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.client.write_raw(bytes)
    }

    fn recv_line(&mut self, timeout: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        crate::reliable::ByteLink::recv_line(&mut self.client, timeout)
    }

    fn reset_device(&mut self) -> Result<bool, LinkError> {
        use std::io::Write;
        self.monitor.write_all(b"system_reset\n")?;
        self.monitor.flush()?;
        self.resets += 1;
        Ok(true)
    }
}

/// The switches' panel of a firmware booted with
/// [`Qemu::boot_with_panel`]: each sample of the pin levels goes to USART2
/// as two bytes (pins 0–6 with bit 7 set, then pins 7–13); the firmware
/// filters the samples as it filters its pins' every millisecond. A sample
/// with pin 13 set is the handwheel's count instead ([`Panel::wheel`]).
pub struct Panel(std::os::unix::net::UnixStream);

impl Panel {
    /// Opens the panel's socket (QEMU listens on it).
    pub fn connect(socket: &Path) -> Result<Panel, LinkError> {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            match std::os::unix::net::UnixStream::connect(socket) {
                Ok(s) => return Ok(Panel(s)),
                Err(e) if Instant::now() > deadline => {
                    return Err(other(format!("{}: {e}", socket.display())))
                }
                Err(_) => std::thread::sleep(Duration::from_millis(20)),
            }
        }
    }

    /// The handwheel turned by `detents` (−4096 … 4095): one sample with
    /// pin 13 set, bits 0–12 the count.
    pub fn wheel(&mut self, detents: i16) -> Result<(), LinkError> {
        if !(-4096..4096).contains(&detents) {
            return Err(other(format!(
                "{detents} detents: a panel sample holds -4096 to 4095"
            )));
        }
        self.sample(1 << 13 | (detents as u16 & 0x1FFF), 1)
    }

    /// Sends `n` samples of `pins` (bit set: the pin reads high).
    pub fn sample(&mut self, pins: u16, n: usize) -> Result<(), LinkError> {
        use std::io::Write as _;
        let one = [0x80 | (pins & 0x7F) as u8, ((pins >> 7) & 0x7F) as u8];
        for _ in 0..n {
            self.0.write_all(&one)?;
        }
        self.0.flush()?;
        Ok(())
    }
}

//! The simulated board: the device served as the firmware serves it, its
//! motion issued on the wall clock.
//!
//! Three parts, as on the board (`firmware/`):
//! - the **receiver** (the serial interrupt) reads the link, acts on the
//!   real-time bytes the moment they arrive (hold, resume, reset on the
//!   axes at once; a status line asked of the protocol) and queues every
//!   other byte;
//! - the **axes** (the step interrupt) take started motion and issue each
//!   step event when its tick of the 1 MHz step clock comes, scaled by
//!   [`Pace`]: `Wall(1.0)` is real time, `Wall(10.0)` ten times as fast,
//!   [`Pace::Unpaced`] issues at once (what the QEMU build without pacing
//!   does: blocks start by the window alone, every tick as on the virtual
//!   clock);
//! - the **protocol** (thread mode) takes the queued bytes through the
//!   core's [`Device`], hands started motion to the axes (waiting for room,
//!   which is the flow control a sender sees) and answers a status byte
//!   while it waits.
//!
//! A grbl sender therefore sees `Run`, `Hold`, `Jog`, the position moving
//! and the buffer draining as on a board, and a feed hold, a resume or a
//! reset act between two step events.

use core_nostd::interleave::{ImpulsePoint, StepEvent};
use core_nostd::machine::Background;
use core_nostd::outputs::Outputs;
use core_nostd::protocol::grbl::{self, Extras, GrblRealtime};
use core_nostd::protocol::{status_line, Device, Io, Realtime, StatusRecord, StatusView};
use core_nostd::step::Record;
use core_nostd::stepdir::DriveTiming;
use core_nostd::stepper::{Aborted, AxesState, Item, Pulled, Stepper, AHEAD};
use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicU16, AtomicU8, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How the step clock runs against the wall clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pace {
    /// Tick `t` of a run is issued `t / (1 MHz · factor)` after the run
    /// began: 1.0 is real time.
    Wall(f64),
    /// Every event at once; blocks start by the look-ahead window, as on
    /// the virtual clock.
    Unpaced,
}

/// How long a grbl link stays quiet before what it queued starts (as the
/// board's 50 ms).
const QUIET: Duration = Duration::from_millis(50);

/// The step clock's rate, ticks per second.
const TICK_HZ: f64 = 1_000_000.0;

/// What the axes own (the step interrupt's state).
struct Axes {
    stepper: Stepper<AHEAD>,
    /// The next event, waiting for its tick.
    next: Option<(StepEvent, u64)>,
    /// When tick 0 of the current run was.
    run_start: Instant,
    /// The axes have work: an event waiting or items to pull.
    busy: bool,
    /// What a reset found, until the protocol reports it.
    aborted: Option<Aborted>,
    /// The spindle and coolant outputs.
    outputs: Outputs,
    /// Runs ended, with the wall time each took against its ticks.
    drift: Drift,
    /// The user outputs a machine's M code switches, 1 … 4.
    user_outputs: [bool; 4],
    /// The user inputs a machine's M code waits for (nothing wired: low).
    user_inputs: [bool; 4],
    /// The lathe whose carriages the axes move (`--machine FILE`), and the
    /// impulse prices (Å; X on the radius) that place them.
    lathe: Option<crate::lathe::Lathe>,
    prices: (i64, i64),
    /// The registers the lathe's nuts last followed: the steps issued
    /// since move them (registers set at rest do not).
    lathe_seen: ImpulsePoint,
    /// When the board started: the lathe's spindle turns on this clock.
    born: Instant,
}

/// How far the wall clock ran from the step clock over the runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Drift {
    /// Runs ended.
    pub runs: u64,
    /// Their ticks in all, as seconds of the step clock (scaled by the
    /// pace).
    pub planned_s: f64,
    /// The wall time from each run's start to its last event, in all.
    pub wall_s: f64,
    /// The latest any event was issued after its due time, seconds.
    pub worst_late_s: f64,
}

struct Shared {
    axes: Mutex<Axes>,
    /// The axes have work (or the serve ends).
    work: Condvar,
    /// Something the protocol may wait for changed (room, the end of the
    /// motion, a real-time request).
    changed: Condvar,
    pace: Pace,
    /// Real-time requests for the protocol.
    wanted: AtomicU8,
    /// Cycle start came since a program stop began to wait.
    cycle_start: AtomicBool,
    /// A reset dropped the motion; what the protocol hands over is dropped
    /// too until it has handled the reset.
    aborting: AtomicBool,
    /// The link speaks grbl (the receiver picks its real-time bytes).
    grbl: AtomicBool,
    /// The serve ends.
    stop: AtomicBool,
    /// grbl's overrides and jog cancel, in order, for the protocol to act
    /// on ahead of the lines queued before them.
    commands: Mutex<Vec<u8>>,
    /// The simulated machine's switches: the inputs active now
    /// (`core_nostd::inputs`), filtered.
    panel: AtomicU16,
    /// The inputs wired, as the session last had them: the E-stop, limits
    /// and drive faults stop the axes at once, the door and the buttons
    /// hold and resume them.
    wired: AtomicU16,
    /// A probing move is armed: 0 not, 1 it stops where the probe becomes
    /// active, 2 where it becomes inactive.
    probe: AtomicU8,
    /// X's and Z's impulse prices (Å) and whether X reads as a diameter, as
    /// the session last had them (for the panel's `STATE?`).
    prices: Mutex<(i64, i64, bool)>,
    /// The handwheel's counts not yet handed to the protocol.
    wheel: AtomicI32,
    /// A pendant's selectors set and not yet handed over: axis + 1, and
    /// the scale from bit 8 (0: none).
    wheel_select: AtomicU16,
}

/// What the panel reads off the simulated machine (`STATE?`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PanelState {
    /// The registers of the steps issued: where the carriage is.
    pub issued: ImpulsePoint,
    /// X's and Z's impulse prices, Å.
    pub prices: (i64, i64),
    /// X reads as a diameter.
    pub diam: bool,
    /// The active inputs.
    pub inputs: u16,
    /// The spindle's speed, 10⁻³ rpm (0: stopped).
    pub spindle: u32,
    /// Where the lathe's carriages are, mm (X on the radius), the play of
    /// the leadscrews in it, when a machine file is behind the board.
    pub carriage: Option<[f64; 2]>,
    /// The spindle encoder's counts since power-on, when the machine file
    /// fits one.
    pub encoder: Option<i64>,
}

impl PanelState {
    /// `STATE X= Z= IN= S= [ENC=]`: the carriage (mm, X a diameter when
    /// the session reads one; the lathe's, play included, with a machine
    /// file), the active inputs (grbl's letters, `-` for none), the
    /// spindle (rpm: the commanded speed, or with a machine file the
    /// speed its spindle turns at, measured by its encoder when it has
    /// one), and the encoder's counts since power-on.
    pub fn line(&self) -> String {
        let mm = |n: i32, price: i64| n as f64 * price as f64 / 1e7;
        let [x, z] = self.carriage.unwrap_or([
            mm(self.issued.x.0, self.prices.0),
            mm(self.issued.z.0, self.prices.1),
        ]);
        let x = x * if self.diam { 2.0 } else { 1.0 };
        let mut letters = String::new();
        let _ = core_nostd::inputs::write_letters(&mut letters, self.inputs);
        if letters.is_empty() {
            letters.push('-');
        }
        let encoder = self.encoder.map_or(String::new(), |n| format!(" ENC={n}"));
        format!(
            "STATE X={x:.4} Z={z:.4} IN={letters} S={:.3}{encoder}",
            f64::from(self.spindle) / 1000.0
        )
    }
}

const WANT_STATUS: u8 = 1;
const WANT_RESET: u8 = 2;
const WANT_BANNER: u8 = 4;
const WANT_COMMAND: u8 = 8;
const WANT_INPUTS: u8 = 16;
const WANT_WHEEL: u8 = 32;

impl Shared {
    fn axes(&self) -> MutexGuard<'_, Axes> {
        self.axes.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A real-time byte from the receiver: hold, resume and reset act on
    /// the axes at once; each asks the protocol for its line but a hold and
    /// a resume on a grbl link (grbl answers neither).
    fn realtime(&self, rt: Realtime, quiet: bool) {
        self.act(rt);
        if rt == Realtime::Resume {
            self.cycle_start.store(true, Ordering::Release);
        }
        if !(quiet && matches!(rt, Realtime::Hold | Realtime::Resume)) {
            let want = if rt == Realtime::Reset {
                WANT_RESET
            } else {
                WANT_STATUS
            };
            self.wanted.fetch_or(want, Ordering::AcqRel);
        }
        self.changed.notify_all();
    }

    fn act(&self, rt: Realtime) {
        let mut a = self.axes();
        self.act_locked(&mut a, rt);
    }

    /// [`Shared::act`] with the axes at hand. Nothing resumes while the
    /// guard door is open.
    fn act_locked(&self, a: &mut Axes, rt: Realtime) {
        let door = core_nostd::inputs::Input::Door.bit();
        if rt == Realtime::Resume
            && self.panel.load(Ordering::Acquire) & self.wired.load(Ordering::Acquire) & door != 0
        {
            return;
        }
        match rt {
            Realtime::Status => {}
            Realtime::Hold => a.stepper.hold(),
            Realtime::Resume => {
                if let Some(Pulled::RunStart) = a.stepper.resume() {
                    a.run_start = Instant::now();
                }
                if !a.stepper.is_idle() {
                    a.busy = true;
                    self.work.notify_all();
                }
            }
            Realtime::Reset => {
                let found = abort(a);
                a.aborted = Some(found);
                self.aborting.store(true, Ordering::Release);
            }
        }
    }

    /// The switches changed: a stopping input that became active stops
    /// the axes at once, as the board's input interrupt does (the
    /// protocol then reports it and locks the session).
    fn panel(&self, active: u16) {
        let mut a = self.axes();
        self.panel_locked(&mut a, active);
    }

    /// [`Shared::panel`] with the axes at hand.
    fn panel_locked(&self, a: &mut Axes, active: u16) {
        use core_nostd::inputs::{Input, FAULTS, LIMITS};
        let before = self.panel.swap(active, Ordering::AcqRel);
        let wired = self.wired.load(Ordering::Acquire);
        let rose = active & !before & wired;
        let probe = (active ^ before) & wired & Input::Probe.bit() != 0;
        let touch = rose & Input::Probe.bit() != 0;
        let armed = match self.probe.load(Ordering::Acquire) {
            1 => probe && touch,
            2 => probe && !touch,
            _ => false,
        };
        if armed {
            self.probe.store(0, Ordering::Release);
        }
        if armed || rose & (Input::Estop.bit() | LIMITS | FAULTS) != 0 {
            if a.aborted.is_none() {
                let found = abort(a);
                a.aborted = Some(found);
            }
            self.aborting.store(true, Ordering::Release);
        } else {
            // The door and the buttons, as their bytes (a status line
            // asked, but on a grbl link).
            let rt = if rose & (Input::Door.bit() | Input::Hold.bit()) != 0 {
                Some(Realtime::Hold)
            } else if rose & Input::Start.bit() != 0 {
                Some(Realtime::Resume)
            } else {
                None
            };
            if let Some(rt) = rt {
                self.act_locked(a, rt);
                if rt == Realtime::Resume {
                    self.cycle_start.store(true, Ordering::Release);
                }
                if !self.grbl.load(Ordering::Acquire) {
                    self.wanted.fetch_or(WANT_STATUS, Ordering::AcqRel);
                }
            }
        }
        if active != before {
            self.wanted.fetch_or(WANT_INPUTS, Ordering::AcqRel);
            self.changed.notify_all();
        }
    }

    /// An event was issued: the lathe's carriages follow, and the switches
    /// they hold change with them (the panel's own switches kept).
    fn carriage_moved(&self, a: &mut Axes, tick: u64) {
        // Every event passes here: nothing to work out without a lathe.
        if a.lathe.is_none() {
            return;
        }
        let p = motor_of(a);
        let seen = std::mem::replace(&mut a.lathe_seen, p);
        let (hx, hz) = a.prices;
        let Some(lathe) = a.lathe.as_mut() else {
            return;
        };
        let before = lathe.active();
        let steps = [p.x.0 - seen.x.0, p.z.0 - seen.z.0];
        let now = lathe.event(steps, tick, [hx as f64 / 1e7, hz as f64 / 1e7]);
        if now != before {
            let panel = self.panel.load(Ordering::Acquire) & !before | now;
            self.panel_locked(a, panel);
        }
    }

    fn take(&self, want: u8) -> bool {
        self.wanted.fetch_and(!want, Ordering::AcqRel) & want != 0
    }

    fn drained(&self) -> bool {
        let a = self.axes();
        !a.busy && !a.stepper.pending() && a.next.is_none()
    }
}

/// Reset on the axes: everything dropped, the event waiting for its tick
/// never issued; what was running.
fn abort(a: &mut Axes) -> Aborted {
    let mut found = a.stepper.abort();
    if let Some((e, _)) = a.next.take() {
        found.done = found.done.saturating_sub(1);
        found.dropped = true;
        a.stepper.take_back(e);
    }
    a.busy = false;
    a.outputs = Outputs::OFF;
    a.user_outputs = [false; 4];
    a.stepper.set_spindle(0);
    spindle_follows(a);
    found
}

/// The lathe's spindle turns as the outputs now command it.
fn spindle_follows(a: &mut Axes) {
    let on = a.outputs.spindle != core_nostd::gcode::Spindle::Off;
    let rpm = if on {
        f64::from(a.outputs.rpm) / 1000.0
    } else {
        0.0
    };
    let now = a.born.elapsed().as_secs_f64();
    if let Some(lathe) = a.lathe.as_mut() {
        lathe.set_spindle(rpm, now);
    }
}

/// The axes' thread: issues what is due, sleeps until the next tick.
fn axes_thread(shared: Arc<Shared>) {
    let mut a = shared.axes();
    loop {
        if shared.stop.load(Ordering::Acquire) {
            return;
        }
        if let Some((event, tick)) = a.next {
            if let Pace::Wall(factor) = shared.pace {
                let due = a.run_start + Duration::from_secs_f64(tick as f64 / (TICK_HZ * factor));
                let now = Instant::now();
                if due > now {
                    // Sleep in steps of at most 2 ms: a real-time byte may
                    // change what is due meanwhile.
                    let wait = (due - now).min(Duration::from_millis(2));
                    a = shared
                        .work
                        .wait_timeout(a, wait)
                        .unwrap_or_else(|e| e.into_inner())
                        .0;
                    continue;
                }
                let late = (now - due).as_secs_f64();
                if late > a.drift.worst_late_s {
                    a.drift.worst_late_s = late;
                }
            }
            let _ = event;
            a.next = None;
            shared.carriage_moved(&mut a, tick);
        }
        match a.stepper.pull() {
            None => {
                a.busy = false;
                shared.changed.notify_all();
                a = shared.work.wait(a).unwrap_or_else(|e| e.into_inner());
            }
            Some(Pulled::RunStart) => {
                a.run_start = Instant::now();
                if let Some(lathe) = a.lathe.as_mut() {
                    lathe.run_start();
                }
            }
            Some(Pulled::BlockStart(_)) => {
                let rpm = a.stepper.spindle();
                if a.outputs.spindle != core_nostd::gcode::Spindle::Off {
                    a.outputs.rpm = rpm;
                    spindle_follows(&mut a);
                }
                // Room for the next item: the protocol may go on.
                shared.changed.notify_all();
            }
            Some(Pulled::Step(event, tick)) => a.next = Some((event, tick)),
            Some(Pulled::RunEnd(ticks)) => {
                if let Pace::Wall(factor) = shared.pace {
                    a.drift.runs += 1;
                    a.drift.planned_s += ticks as f64 / (TICK_HZ * factor);
                    a.drift.wall_s += a.run_start.elapsed().as_secs_f64();
                }
                shared.changed.notify_all();
            }
        }
    }
}

/// The protocol's side (thread mode): the link's writer and what a status
/// line needs.
struct Protocol<W: Write> {
    shared: Arc<Shared>,
    out: W,
    view: StatusView,
    queued: usize,
    grbl: Option<Extras>,
}

impl<W: Write> Protocol<W> {
    fn write(&mut self, bytes: &[u8]) {
        // A sender that has gone away loses the reply, as on a wire.
        let _ = self.out.write_all(bytes);
        let _ = self.out.flush();
    }

    /// Sends the status line a real-time byte asked for, if one did.
    fn answer_status(&mut self) {
        if !self.shared.take(WANT_STATUS) {
            return;
        }
        let (motion, issued, outputs) = {
            let a = self.shared.axes();
            (motion_of(&a), issued_of(&a), a.outputs)
        };
        let view = StatusView {
            outputs,
            ..self.view
        };
        let record = StatusRecord {
            motion,
            issued,
            queued: self.queued,
            view,
        };
        match self.grbl {
            Some(mut extras) => {
                // Overrides received and not yet acted on, as they will be.
                let pending = self
                    .shared
                    .commands
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .clone();
                for byte in pending {
                    if let Some(rt) = GrblRealtime::from_byte(byte) {
                        extras.overrides = rt.overrides(extras.overrides);
                    }
                }
                let mut report = grbl::status_report(&record, &extras);
                report.push_bytes(b"\r\n");
                self.write(report.as_bytes());
            }
            None => {
                let mut line = status_line("!STATUS", &record);
                let bytes = line.finish().to_vec();
                self.write(&bytes);
            }
        }
    }

    /// Waits until `done` holds, answering status bytes meanwhile; a reset
    /// ends the wait too.
    fn wait_for(&mut self, done: impl Fn(&Shared) -> bool) {
        loop {
            self.answer_status();
            if done(&self.shared)
                || self.shared.aborting.load(Ordering::Acquire)
                || self.shared.stop.load(Ordering::Acquire)
            {
                return;
            }
            let a = self.shared.axes();
            let _ = self
                .shared
                .changed
                .wait_timeout(a, Duration::from_millis(5))
                .unwrap_or_else(|e| e.into_inner());
        }
    }
}

/// What the axes are doing (an event waiting for its tick is running).
fn motion_of(a: &Axes) -> AxesState {
    match a.stepper.motion() {
        AxesState::Idle if a.next.is_some() => AxesState::Run,
        m => m,
    }
}

/// The registers of the steps issued and the backlash take-up steps
/// issued: the event waiting for its tick is not.
fn issued_and_lash(a: &Axes) -> (ImpulsePoint, [i32; 2]) {
    match a.next {
        Some((e, _)) => a.stepper.issued_before(e),
        None => (a.stepper.issued(), a.stepper.lash()),
    }
}

/// The registers of the steps issued.
fn issued_of(a: &Axes) -> ImpulsePoint {
    issued_and_lash(a).0
}

/// Where the motors stand: the registers and the take-up steps.
fn motor_of(a: &Axes) -> ImpulsePoint {
    let (mut p, lash) = issued_and_lash(a);
    p.x.0 += lash[0];
    p.z.0 += lash[1];
    p
}

impl<W: Write> Io for Protocol<W> {
    fn send(&mut self, line: &[u8]) {
        self.write(line);
    }

    fn background(&mut self) -> Option<&mut dyn Background> {
        Some(self)
    }

    fn view(&mut self, view: &StatusView) {
        self.view = *view;
        *self.shared.prices.lock().unwrap_or_else(|e| e.into_inner()) =
            (view.hx, view.hz, view.diam);
        self.shared.axes().prices = (view.hx, view.hz);
    }

    fn pause(&mut self) {
        self.answer_status();
    }

    fn dwell(&mut self, us: u64) {
        let Pace::Wall(factor) = self.shared.pace else {
            return;
        };
        let end = Instant::now() + Duration::from_secs_f64(us as f64 / (TICK_HZ * factor));
        self.wait_for(|_| Instant::now() >= end);
    }

    fn program_stop(&mut self, _: u16) {
        self.shared.cycle_start.store(false, Ordering::Release);
        self.wait_for(|s| s.cycle_start.load(Ordering::Acquire));
    }

    fn user_output(&mut self, n: u8, on: bool) {
        if let Some(o) = self
            .shared
            .axes()
            .user_outputs
            .get_mut(usize::from(n).saturating_sub(1))
        {
            *o = on;
        }
    }

    fn wait_input(&mut self, n: u8, level: bool) {
        let n = usize::from(n).saturating_sub(1);
        self.wait_for(|s| s.axes().user_inputs.get(n) == Some(&level));
    }

    fn outputs(&mut self, outputs: &Outputs) {
        let mut a = self.shared.axes();
        a.stepper.set_spindle(outputs.rpm);
        a.outputs = *outputs;
        spindle_follows(&mut a);
    }

    fn inputs_now(&mut self) -> Option<u16> {
        Some(self.shared.panel.load(Ordering::Acquire))
    }

    fn probe_arm(&mut self, stop_on: Option<bool>) {
        let v = match stop_on {
            None => 0,
            Some(true) => 1,
            Some(false) => 2,
        };
        self.shared.probe.store(v, Ordering::Release);
    }
}

impl<W: Write> Background for Protocol<W> {
    fn start(&mut self, item: Item, _: &DriveTiming) {
        let mut item = Some(item);
        loop {
            if self.shared.aborting.load(Ordering::Acquire) {
                return;
            }
            {
                let mut a = self.shared.axes();
                if a.stepper.has_room() {
                    if let Some(i) = item.take() {
                        let _ = a.stepper.push(i);
                    }
                    a.busy = true;
                    self.shared.work.notify_all();
                    return;
                }
            }
            self.wait_for(|s| s.axes().stepper.has_room());
        }
    }

    fn drain(&mut self) {
        self.wait_for(Shared::drained);
    }

    fn issued(&mut self) -> ImpulsePoint {
        issued_of(&self.shared.axes())
    }

    fn lash(&mut self) -> [i32; 2] {
        issued_and_lash(&self.shared.axes()).1
    }

    fn set_issued(&mut self, registers: ImpulsePoint) {
        let mut a = self.shared.axes();
        a.stepper.set_issued(registers);
        // The registers set at rest: the lathe's nuts stay where they are.
        a.lathe_seen = motor_of(&a);
    }

    fn take_record(&mut self) -> Record {
        self.shared.axes().stepper.take_record()
    }

    fn hold(&mut self) {
        self.shared.act(Realtime::Hold);
    }

    fn resume(&mut self) {
        self.shared.act(Realtime::Resume);
    }

    fn abort(&mut self) -> Aborted {
        let mut a = self.shared.axes();
        let found = a.aborted.take().unwrap_or_else(|| abort(&mut a));
        self.shared.aborting.store(false, Ordering::Release);
        found
    }

    fn motion(&mut self) -> AxesState {
        motion_of(&self.shared.axes())
    }

    fn hungry(&mut self) -> bool {
        matches!(self.shared.pace, Pace::Wall(_)) && self.shared.axes().stepper.hungry()
    }

    fn queued(&mut self, blocks: usize) {
        self.queued = blocks;
    }

    fn spindle(&mut self) -> Option<u32> {
        Some(self.shared.axes().outputs.rpm)
    }
}

/// What the receiver hands the protocol.
enum Received {
    Byte(u8),
    /// A reset came here in the stream: what was received before it is
    /// dropped (as the board empties its receive ring).
    Reset,
    /// A sender opened the link (a board resets and greets it).
    Opened,
    /// The link ended.
    Closed,
}

/// The receiver (the serial interrupt): real-time bytes act at once;
/// everything else is queued for the protocol. `read` returns `Ok(None)`
/// when nothing came within its timeout, `Err` while no sender has the
/// link open.
fn receive(
    shared: &Shared,
    mut read: impl FnMut(&mut [u8]) -> std::io::Result<Option<usize>>,
    to_protocol: &Sender<Received>,
) {
    let mut buf = [0u8; 512];
    let mut open = false;
    while !shared.stop.load(Ordering::Acquire) {
        let n = match read(&mut buf) {
            Ok(Some(0)) => {
                let _ = to_protocol.send(Received::Closed);
                return;
            }
            Ok(Some(n)) => n,
            Ok(None) => {
                if !open {
                    open = true;
                    let _ = to_protocol.send(Received::Opened);
                }
                continue;
            }
            Err(_) => {
                open = false;
                std::thread::sleep(Duration::from_millis(5));
                continue;
            }
        };
        if !open {
            open = true;
            let _ = to_protocol.send(Received::Opened);
        }
        for &byte in &buf[..n] {
            if shared.grbl.load(Ordering::Acquire) {
                match GrblRealtime::from_byte(byte) {
                    Some(GrblRealtime::Common(rt)) => {
                        if rt == Realtime::Reset {
                            let _ = to_protocol.send(Received::Reset);
                        }
                        shared.realtime(rt, true);
                        continue;
                    }
                    Some(rt) => {
                        // The overrides and jog cancel act ahead of the
                        // lines before them (a jog cancel holds at once).
                        if rt == GrblRealtime::JogCancel {
                            shared.realtime(Realtime::Hold, true);
                        }
                        shared
                            .commands
                            .lock()
                            .unwrap_or_else(|e| e.into_inner())
                            .push(byte);
                        shared.wanted.fetch_or(WANT_COMMAND, Ordering::AcqRel);
                        shared.changed.notify_all();
                        continue;
                    }
                    None => {}
                }
            } else if let Some(rt) = Realtime::from_byte(byte) {
                if rt == Realtime::Reset {
                    let _ = to_protocol.send(Received::Reset);
                }
                shared.realtime(rt, false);
                continue;
            }
            if to_protocol.send(Received::Byte(byte)).is_err() {
                return;
            }
        }
    }
}

/// The board's protocol loop (thread mode, `firmware/src/main.rs`).
fn protocol_loop<W: Write>(
    mut device: Device,
    io: &mut Protocol<W>,
    bytes: &Receiver<Received>,
    greet: bool,
) -> Device {
    let mut heard = Instant::now();
    let shared = Arc::clone(&io.shared);
    let mut closed = false;
    loop {
        shared.wired.store(device.wiring().used, Ordering::Release);
        // An input changed: the axes have already stopped if it stops them.
        if shared.take(WANT_INPUTS) {
            device.inputs(shared.panel.load(Ordering::Acquire), io);
            io.grbl = device.grbl_extras();
            continue;
        }
        // The handwheel turned: what it counted since.
        if shared.take(WANT_WHEEL) {
            let select = shared.wheel_select.swap(0, Ordering::AcqRel);
            if select != 0 {
                // The panel's selectors: axis + 1 in the low byte, scale above.
                let _ = device.wheel_select((select & 0xFF) as u8 - 1, (select >> 8) as u8);
            }
            device.wheel(shared.wheel.swap(0, Ordering::AcqRel), io);
            continue;
        }
        // Real-time requests the receiver acted on: the protocol's part.
        if shared.take(WANT_RESET) {
            shared
                .commands
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .clear();
            // A reset drops what was received before it with the line.
            loop {
                match bytes.try_recv() {
                    Ok(Received::Byte(_) | Received::Opened) => {}
                    Ok(Received::Reset) | Err(mpsc::TryRecvError::Empty) => break,
                    Ok(Received::Closed) | Err(mpsc::TryRecvError::Disconnected) => {
                        closed = true;
                        break;
                    }
                }
            }
            device.realtime(Realtime::Reset, io);
            io.grbl = device.grbl_extras();
            continue;
        }
        if shared.take(WANT_STATUS) {
            device.realtime(Realtime::Status, io);
            continue;
        }
        if shared.take(WANT_BANNER) {
            io.write(grbl::BANNER);
            continue;
        }
        if shared.take(WANT_COMMAND) {
            let commands =
                std::mem::take(&mut *shared.commands.lock().unwrap_or_else(|e| e.into_inner()));
            for byte in commands {
                device.receive(byte, io);
            }
            io.grbl = device.grbl_extras();
            continue;
        }
        let feed = device.can_feed() && Background::hungry(io);
        if feed || device.cancel_pending() {
            device.poll(io);
        }
        if closed {
            // The link ended (stdin closed): what was started runs to its
            // end, or to a hold, then the serve ends.
            device.quiet(io);
            io.wait_for(|s| s.drained() || motion_of(&s.axes()) == AxesState::Held);
            return device;
        }
        let wait = if feed {
            Duration::ZERO
        } else {
            Duration::from_millis(2)
        };
        match bytes.recv_timeout(wait) {
            Ok(Received::Byte(byte)) => {
                heard = Instant::now();
                device.receive(byte, io);
                if matches!(byte, b'\n' | b'\r') || byte >= 0x80 {
                    io.grbl = device.grbl_extras();
                    shared.grbl.store(device.grbl(), Ordering::Release);
                }
            }
            Ok(Received::Opened) => {
                if greet && device.grbl() {
                    shared.wanted.fetch_or(WANT_BANNER, Ordering::AcqRel);
                }
            }
            // A reset already handled with the bytes before it.
            Ok(Received::Reset) => {}
            Ok(Received::Closed) | Err(RecvTimeoutError::Disconnected) => closed = true,
            Err(RecvTimeoutError::Timeout) => {
                // A grbl link quiet for a moment: what it queued starts.
                if device.waiting() && heard.elapsed() >= QUIET {
                    device.quiet(io);
                }
            }
        }
        if shared.stop.load(Ordering::Acquire) {
            return device;
        }
    }
}

/// A simulated board serving a link: the receiver, the axes and the
/// protocol, each on its thread.
pub struct Board {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
    protocol: Option<JoinHandle<Device>>,
}

impl Board {
    /// Serves `device` on a link read by `read` (see [`Pace`]) and written
    /// by `write`. A grbl link greets a sender that opens it with the
    /// banner when `greet` (a board resets as its port opens).
    pub fn serve<W: Write + Send + 'static>(
        device: Device,
        pace: Pace,
        read: impl FnMut(&mut [u8]) -> std::io::Result<Option<usize>> + Send + 'static,
        write: W,
        greet: bool,
    ) -> Board {
        let shared = Arc::new(Shared {
            axes: Mutex::new(Axes {
                stepper: Stepper::new(),
                next: None,
                run_start: Instant::now(),
                busy: false,
                aborted: None,
                outputs: Outputs::OFF,
                drift: Drift::default(),
                user_outputs: [false; 4],
                user_inputs: [false; 4],
                lathe: None,
                lathe_seen: ImpulsePoint::default(),
                prices: (50_000, 100_000),
                born: Instant::now(),
            }),
            work: Condvar::new(),
            changed: Condvar::new(),
            pace,
            wanted: AtomicU8::new(0),
            cycle_start: AtomicBool::new(false),
            aborting: AtomicBool::new(false),
            grbl: AtomicBool::new(device.grbl()),
            stop: AtomicBool::new(false),
            commands: Mutex::new(Vec::new()),
            panel: AtomicU16::new(0),
            wired: AtomicU16::new(0),
            probe: AtomicU8::new(0),
            prices: Mutex::new((50_000, 100_000, true)),
            wheel: AtomicI32::new(0),
            wheel_select: AtomicU16::new(0),
        });
        let (tx, rx) = mpsc::channel();
        let axes = {
            let s = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("board-axes".into())
                .spawn(move || axes_thread(s))
                .expect("a thread for the axes")
        };
        let receiver = {
            let s = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("board-receive".into())
                .spawn(move || receive(&s, read, &tx))
                .expect("a thread for the receiver")
        };
        let protocol = {
            let s = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("board-protocol".into())
                .spawn(move || {
                    let mut io = Protocol {
                        grbl: device.grbl_extras(),
                        shared: s,
                        out: write,
                        view: StatusView {
                            hx: 0,
                            hz: 0,
                            diam: true,
                            speed: 0,
                            starved: 0,
                            stop: None,
                            outputs: Outputs::OFF,
                            pins: None,
                            alarm: 0,
                            lost: false,
                        },
                        queued: 0,
                    };
                    protocol_loop(device, &mut io, &rx, greet)
                })
                .expect("a thread for the protocol")
        };
        Board {
            shared,
            threads: vec![axes, receiver],
            protocol: Some(protocol),
        }
    }

    /// The simulated machine's switches: `active` the inputs active now
    /// (bits of `core_nostd::inputs::Input`, as the board's filter gives
    /// them).
    pub fn panel(&self, active: u16) {
        self.shared.panel(active);
    }

    /// The handwheel turned by `counts` (signed); the protocol takes them
    /// on its next round, with any turned meanwhile.
    pub fn wheel(&self, counts: i32) {
        self.shared.wheel.fetch_add(counts, Ordering::AcqRel);
        self.shared.wanted.fetch_or(WANT_WHEEL, Ordering::AcqRel);
    }

    /// A pendant with its own selectors: the wheel's axis (0 X, 1 Z) and
    /// scale (1, 10, 100) set, then turned by `counts`.
    pub fn mpg(&self, axis: u8, scale: u8, counts: i32) {
        let select = u16::from(axis + 1) | u16::from(scale) << 8;
        self.shared.wheel_select.store(select, Ordering::Release);
        self.wheel(counts);
    }

    /// Puts the lathe of `file` behind the axes: from now on its
    /// carriages follow the steps issued and trip its switches.
    pub fn set_lathe(&self, file: crate::lathe::MachineFile) {
        let mut a = self.shared.axes();
        let p = issued_of(&a);
        let (hx, hz) = a.prices;
        let mm = |n: i32, h: i64| n as f64 * h as f64 / 1e7;
        let mut lathe = crate::lathe::Lathe::new(file);
        let active = lathe.moved([mm(p.x.0, hx), mm(p.z.0, hz)]);
        a.lathe = Some(lathe);
        a.lathe_seen = motor_of(&a);
        spindle_follows(&mut a);
        let panel = self.shared.panel.load(Ordering::Acquire) | active;
        self.shared.panel_locked(&mut a, panel);
    }

    /// The switches as the panel last set them.
    pub fn inputs(&self) -> u16 {
        self.shared.panel.load(Ordering::Acquire)
    }

    /// What the panel reads off the machine.
    pub fn state(&self) -> PanelState {
        let (issued, mut spindle, carriage, now) = {
            let a = self.shared.axes();
            let now = a.born.elapsed().as_secs_f64();
            (
                issued_of(&a),
                a.outputs.rpm,
                a.lathe.as_ref().map(crate::lathe::Lathe::carriage),
                a.lathe.as_ref().map(|l| l.spindle_at(now)),
            )
        };
        // The lathe's spindle as it turns (measured by its encoder).
        if let Some(now) = now {
            spindle = (now.rpm * 1000.0).round() as u32;
        }
        let (hx, hz, diam) = *self.shared.prices.lock().unwrap_or_else(|e| e.into_inner());
        PanelState {
            issued,
            prices: (hx, hz),
            diam,
            inputs: self.inputs(),
            spindle,
            carriage,
            encoder: now.and_then(|n| n.counts),
        }
    }

    /// One line of the panel (`serve --pty`'s standard input): `ESTOP
    /// 1|0`, `DOOR 1|0`, `PROBE 1|0`, `LIMIT X-|X+|Z-|Z+ 1|0`, `FAULT X|Z
    /// 1|0`, `HOLD` and `START` (a press: on, then off), `WHEEL n` (the
    /// handwheel turned by `n` counts), `MPG X|Z COUNTS=n SCALE=1|10|100`
    /// (a pendant with its own selectors), and `STATE?`.
    /// Returns what to print (`STATE?`'s line), or why the line is not one.
    pub fn panel_line(&self, line: &str) -> Result<Option<String>, String> {
        use core_nostd::inputs::Input;
        let words: Vec<&str> = line.split_whitespace().collect();
        let upper: Vec<String> = words.iter().map(|w| w.to_ascii_uppercase()).collect();
        let u: Vec<&str> = upper.iter().map(String::as_str).collect();
        let level = |w: Option<&&str>| match w {
            Some(&"1") => Ok(true),
            Some(&"0") => Ok(false),
            _ => Err(format!("{line:?}: the level must be 1 or 0")),
        };
        let (input, on) = match u.as_slice() {
            [] => return Ok(None),
            ["STATE?"] => return Ok(Some(self.state().line())),
            ["MPG", axis, rest @ ..] => {
                let axis = match *axis {
                    "X" => 0,
                    "Z" => 1,
                    _ => return Err(format!("{line:?}: MPG takes X or Z")),
                };
                let (mut counts, mut scale) = (None, None);
                for w in rest {
                    match w.split_once('=') {
                        Some(("COUNTS", n)) => counts = n.parse::<i32>().ok(),
                        Some(("SCALE", s @ ("1" | "10" | "100"))) => scale = s.parse::<u8>().ok(),
                        _ => return Err(format!("{line:?}: MPG X|Z COUNTS=n SCALE=1|10|100")),
                    }
                }
                let (Some(counts), Some(scale)) = (counts, scale) else {
                    return Err(format!("{line:?}: MPG X|Z COUNTS=n SCALE=1|10|100"));
                };
                self.mpg(axis, scale, counts);
                return Ok(None);
            }
            ["WHEEL", n] => {
                let counts = n
                    .parse()
                    .map_err(|_| format!("{line:?}: WHEEL takes a whole count, as -12 or 40"))?;
                self.wheel(counts);
                return Ok(None);
            }
            ["HOLD"] | ["START"] => {
                let i = if u[0] == "HOLD" { Input::Hold } else { Input::Start };
                let was = self.inputs();
                self.panel(was | i.bit());
                // A press lasts longer than any filter the board reads.
                std::thread::sleep(Duration::from_millis(20));
                self.panel(self.inputs() & !i.bit());
                return Ok(None);
            }
            ["ESTOP", ..] => (Input::Estop, level(u.get(1))?),
            ["DOOR", ..] => (Input::Door, level(u.get(1))?),
            ["PROBE", ..] => (Input::Probe, level(u.get(1))?),
            ["LIMIT", side, ..] => (
                match *side {
                    "X-" => Input::LimitXMinus,
                    "X+" => Input::LimitXPlus,
                    "Z-" => Input::LimitZMinus,
                    "Z+" => Input::LimitZPlus,
                    _ => return Err(format!("{line:?}: LIMIT takes X-, X+, Z- or Z+")),
                },
                level(u.get(2))?,
            ),
            ["FAULT", axis, ..] => (
                match *axis {
                    "X" => Input::FaultX,
                    "Z" => Input::FaultZ,
                    _ => return Err(format!("{line:?}: FAULT takes X or Z")),
                },
                level(u.get(2))?,
            ),
            _ => {
                return Err(format!(
                    "{line:?}: not a panel line (ESTOP, DOOR, PROBE 1|0; LIMIT X-|X+|Z-|Z+ 1|0; FAULT X|Z 1|0; HOLD; START; WHEEL n; MPG X|Z COUNTS=n SCALE=1|10|100; STATE?)"
                ))
            }
        };
        if !on && matches!(input, Input::FaultX | Input::FaultZ) {
            // A drive the lathe's own rate stalled: its fault clears too.
            if let Some(lathe) = self.shared.axes().lathe.as_mut() {
                lathe.clear_fault(input.bit());
            }
        }
        let was = self.inputs();
        self.panel(if on {
            was | input.bit()
        } else {
            was & !input.bit()
        });
        Ok(None)
    }

    /// How the step clock kept to the wall clock so far.
    pub fn drift(&self) -> Drift {
        self.shared.axes().drift
    }

    /// Serves until the link ends (stdin closed); then stops the axes.
    pub fn wait(mut self) -> Option<Device> {
        let device = self.protocol.take().and_then(|p| p.join().ok());
        self.finish();
        device
    }

    fn finish(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        self.shared.work.notify_all();
        self.shared.changed.notify_all();
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }

    /// Stops serving.
    pub fn stop(mut self) -> Option<Device> {
        self.shared.stop.store(true, Ordering::Release);
        self.shared.work.notify_all();
        self.shared.changed.notify_all();
        let device = self.protocol.take().and_then(|p| p.join().ok());
        self.finish();
        device
    }
}

impl Drop for Board {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        self.shared.work.notify_all();
        self.shared.changed.notify_all();
        if let Some(p) = self.protocol.take() {
            let _ = p.join();
        }
        self.finish();
    }
}

/// A simulated board on a new pseudo-terminal: its path, and the board.
/// Nothing holds the slave end open: a sender that opens it is greeted as
/// a board greets it after the reset its port's opening causes.
pub fn serve_pty(device: Device, pace: Pace) -> std::io::Result<(String, Board)> {
    use serialport::{SerialPort, TTYPort};
    let (mut master, slave) = TTYPort::pair().map_err(std::io::Error::other)?;
    let path = slave
        .name()
        .ok_or_else(|| std::io::Error::other("pty without a name"))?;
    drop(slave);
    master
        .set_timeout(Duration::from_millis(20))
        .map_err(std::io::Error::other)?;
    let writer = master.try_clone_native().map_err(std::io::Error::other)?;
    let read = move |buf: &mut [u8]| match master.read(buf) {
        // A pty master reads 0 only while no slave is open.
        Ok(0) => Err(std::io::Error::other("no sender")),
        Ok(n) => Ok(Some(n)),
        Err(e) if e.kind() == std::io::ErrorKind::TimedOut => Ok(None),
        Err(e) => Err(e),
    };
    let board = Board::serve(device, pace, read, PtyWriter(writer), true);
    Ok((path, board))
}

/// The master end of a pty as the link's writer; a write while no sender
/// has the link open is lost, as on a wire.
struct PtyWriter(serialport::TTYPort);

impl Write for PtyWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self.0.write(buf) {
            Ok(n) => Ok(n),
            Err(_) => Ok(buf.len()),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        let _ = self.0.flush();
        Ok(())
    }
}

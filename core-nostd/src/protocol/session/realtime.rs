//! What runs alongside the requests: polling the motion, status lines,
//! the real-time commands (hold, resume, reset), overrides, check mode.

use super::*;

impl Session {
    /// `STATUS`: where the axes are now (the steps issued), their speed and
    /// the blocks waiting.
    pub(super) fn status_reply<I: Io>(&self, io: &mut I, prefix: &str) {
        let mut st = self.machine.status(&mut Sink::new(io, self.drive));
        if let (Some((registers, _)), None) = (self.checking, io.background()) {
            // Check mode on the virtual clock: its motion went nowhere.
            (st.issued, st.motion, st.queued) = (registers, Axes::Idle, 0);
        }
        let mut view = self.view(st.speed(self.machine.tick()));
        view.outputs.rpm = st.spindle;
        let record = record(&st, view);
        let realtime = prefix.starts_with('!');
        io.status(&record, realtime);
        let mut line = status_line(prefix, &record);
        if realtime {
            if let Some(timing) = io.timing() {
                timing.write_to(&mut line);
            }
        }
        io.send(line.finish());
    }

    /// What a status line needs of the session, with the speed.
    pub(super) fn view(&self, speed: i64) -> StatusView {
        StatusView {
            hx: self.cfg.hx.as_angstrom(),
            hz: self.cfg.hz.as_angstrom(),
            diam: self.cfg.diam,
            speed,
            starved: self.machine.starved(),
            stop: None,
            outputs: self.outputs,
            pins: (self.offsets.wiring.used != 0).then_some(self.levels),
            alarm: self.halt.alarm(),
            lost: self.lost,
        }
    }

    /// Hands the view to a transport that runs motion in the background
    /// (it answers a status byte itself while it waits); no work for one
    /// without.
    pub(super) fn share_view<I: Io>(&self, io: &mut I) {
        if io.background().is_some() {
            let view = self.view(self.machine.speed());
            io.view(&view);
        }
    }

    /// A board's stepper needs the next block (`docs/motion.md`): starts
    /// it now if one is queued in the open run.
    pub fn poll<I: Io>(&mut self, io: &mut I) {
        self.machine.poll(&mut Sink::new(io, self.drive));
    }

    /// Whether the axes are at rest, held or with nothing to run (a
    /// device without motion in the background always is).
    pub fn held_or_idle<I: Io>(&self, io: &mut I) -> bool {
        if io.background().is_none() {
            return true;
        }
        let st = self.machine.status(&mut Sink::new(io, self.drive));
        matches!(st.motion, Axes::Idle | Axes::Held)
    }

    /// Whether the last reset dropped motion that had been answered and
    /// had not all run (blocks queued, the axes moving, braking, or held
    /// with more to do).
    pub const fn reset_dropped_motion(&self) -> bool {
        self.reset_dropped
    }

    /// Check mode begins (grbl's `$C`): lines go on through a transport
    /// that moves nothing, and the registers where it began are kept.
    /// Only at rest with nothing queued (false otherwise).
    pub fn check_begin<I: Io>(&mut self, io: &mut I) -> bool {
        let st = self.machine.status(&mut Sink::new(io, self.drive));
        if st.motion != Axes::Idle || st.queued > 0 {
            return false;
        }
        self.checking = Some((st.issued, self.machine.lash()));
        true
    }

    /// Check mode ends: what its lines queued is forgotten and the
    /// registers are where it began; a reset follows (as grbl's).
    pub fn check_end(&mut self) {
        if let Some((registers, lash)) = self.checking.take() {
            self.machine.forget(registers, lash);
        }
    }

    /// Starts the queued blocks now, the run ending at rest after them
    /// (the link has gone quiet: grbl plans with what it has).
    pub fn release<I: Io>(&mut self, io: &mut I) {
        self.machine.release(&mut Sink::new(io, self.drive));
    }

    /// Whether blocks are queued and not started (with or without a run
    /// under way): a quiet link releases them.
    pub fn waiting(&self) -> bool {
        self.machine.queued() > 0
    }

    /// Whether [`Session::poll`] could start a block.
    pub fn can_feed(&self) -> bool {
        self.machine.can_feed()
    }

    /// A real-time byte: acted on at once, answered by one line that
    /// starts with `!` (a request's reply never does).
    pub fn realtime<I: Io>(&mut self, rt: Realtime, io: &mut I) {
        match rt {
            Realtime::Status => {}
            Realtime::Hold => self.machine.hold(&mut Sink::new(io, self.drive)),
            // Not while the guard door is open.
            Realtime::Resume if self.levels & crate::inputs::Input::Door.bit() != 0 => {}
            Realtime::Resume => self.machine.resume(&mut Sink::new(io, self.drive)),
            Realtime::Reset => return self.reset(io),
        }
        self.status_reply(io, "!STATUS");
    }

    /// Ctrl-X: everything queued and started is dropped at once, the
    /// registers keep the steps issued and the commanded point becomes
    /// theirs; the session restarts as after a power cycle (modal state,
    /// feed, compensation, session token), the configuration, drive and
    /// limits kept. Answered `!RESET DONE= OF= PX= PZ=`: the events of the
    /// block that was running that were issued, of how many.
    pub(super) fn reset<I: Io>(&mut self, io: &mut I) {
        let (found, issued) = self.restart(io);
        self.reset_halt();
        io.reset_done(found.of > 0);
        let mut line = ReplyLine::new();
        let _ = line.write_str("!RESET");
        write_dropped(&mut line, &found, issued);
        io.send(line.finish());
        self.share_view(io);
    }

    /// Everything dropped at once and the session restarted as after a
    /// power cycle (a reset's, an input's stop): what was dropped, and the
    /// registers.
    pub(super) fn restart<I: Io>(&mut self, io: &mut I) -> (Aborted, ImpulsePoint) {
        let (found, issued) = self.drop_motion(io);
        self.reset_dropped = found.dropped;
        self.cycles.abandon();
        self.sel = Selection::POWER_ON;
        self.prog = self.work_point(self.cmd);
        self.modal = Modal::POWER_ON;
        self.aux = Aux::POWER_ON;
        // The board dropped its outputs with the motion; the session's
        // follow.
        self.switch_outputs(self.outputs_for(&self.aux, Units::Mm), io);
        self.token = 0;
        self.last_id = None;
        self.last_final.clear();
        (found, issued)
    }

    /// Everything queued and started dropped at once: the registers keep
    /// the steps issued and the commanded point becomes theirs; nothing
    /// waits for compensation.
    pub(super) fn drop_motion<I: Io>(&mut self, io: &mut I) -> (Aborted, ImpulsePoint) {
        let (found, issued) = self.machine.abort(&mut Sink::new(io, self.drive));
        let cmd = [
            // A register times its price is a position the machine holds.
            Length::from_angstrom(i64::from(issued.x.get()) * self.cfg.hx.as_angstrom())
                .unwrap_or(Length::ZERO),
            Length::from_angstrom(i64::from(issued.z.get()) * self.cfg.hz.as_angstrom())
                .unwrap_or(Length::ZERO),
        ];
        self.machine.set_point(point_q32(cmd));
        self.cmd = cmd;
        self.pos = issued;
        self.contour = Contour::new();
        self.last_moves = Moves::new();
        self.element_feed = None;
        self.round_feed = None;
        (found, issued)
    }

    /// A jog cancelled (grbl's 0x85), once held at rest: what is left of
    /// it is dropped; the modal state, the offsets and the session stay.
    pub fn cancel_motion<I: Io>(&mut self, io: &mut I) {
        self.drop_motion(io);
        self.prog = self.work_point(self.cmd);
        self.share_view(io);
    }

    /// Sets the feed override, percent (10 … 200).
    pub fn set_feed_override(&mut self, percent: u8) {
        self.feed_override = percent.clamp(10, 200);
    }

    /// `feed` under the overrides: the feed's, and per revolution the
    /// spindle's too (the spindle turns at the overridden speed).
    pub(in crate::protocol) fn overridden(&self, feed: Feed, mode: FeedMode) -> Feed {
        let spindle = if mode == FeedMode::PerRev {
            self.spindle_override
        } else {
            100
        };
        let percent = i64::from(self.feed_override) * i64::from(spindle);
        if percent == 10_000 {
            return feed;
        }
        let scaled = div_round_half_away(feed.mm_per_min().as_angstrom() * percent, 10_000);
        Length::from_angstrom(scaled)
            .and_then(Feed::new)
            .unwrap_or(feed)
    }

    /// Sets the rapid override, percent (grbl's 100, 50, 25): rapids
    /// queued from now on.
    pub fn set_rapid_override(&mut self, percent: u8) {
        self.machine.set_rapid_override(percent);
    }

    /// Sets the spindle override, percent (10 … 200): at once at rest,
    /// else with the blocks queued from now on.
    pub fn set_spindle_override<I: Io>(&mut self, percent: u8, io: &mut I) {
        self.spindle_override = percent.clamp(10, 200);
        let outputs = self.outputs_for(&self.aux, self.modal.units);
        if self.machine.waiting() || !self.held_or_idle(io) {
            self.machine.set_spindle(outputs.rpm);
        } else {
            self.switch_outputs(outputs, io);
        }
    }
}

/// ` DONE= OF= PX= PZ=`: what a stop at once found running (the events of
/// the block issued, of how many) and the registers (`!RESET`, `!ALARM`).
pub(super) fn write_dropped(line: &mut ReplyLine, found: &Aborted, issued: ImpulsePoint) {
    let _ = write!(
        line,
        " DONE={} OF={} PX={} PZ={}",
        found.done,
        found.of,
        issued.x.get(),
        issued.z.get()
    );
}

/// A status record of what the machine reports, with the session's view.
pub(super) fn record(st: &crate::machine::Status, view: StatusView) -> StatusRecord {
    StatusRecord {
        motion: st.motion,
        issued: st.issued,
        queued: st.queued,
        view,
    }
}

//! The supervisor's judgement: whether the step interrupt and the main loop
//! are alive, from what each leaves behind.
//!
//! A board kicks its hardware watchdog from a periodic supervisor interrupt
//! only while [`Watch::check`] says [`Verdict::Alive`]; otherwise it drives
//! the step outputs low and lets the watchdog reset it. The inputs are:
//! - whether the step interrupt is waiting (pending or running), and how
//!   many entries of its queue it has taken: waiting without taking one
//!   for longer than [`STEP_GRACE_TICKS`] is a stall (its longest entry is
//!   a few microseconds; nothing of lower priority holds it off longer);
//! - a heartbeat the main loop advances on every pass and every wake-up
//!   from sleep. A sleeping main loop is woken by the supervisor's own
//!   interrupt, so only a main loop stuck in work stops beating.
//!
//! Ticks are a free-running 32-bit counter at [`crate::step::TickRate`]'s
//! 1 MHz, compared with wrapping arithmetic (71 minutes around).

/// How long the step interrupt may wait (pending or running) without
/// taking an entry of its queue.
pub const STEP_GRACE_TICKS: u32 = 2_000;

/// How long the main loop may work on one request without a heartbeat:
/// planning the longest arc the protocol accepts takes well under this.
pub const MAIN_GRACE_TICKS: u32 = 2_000_000;

/// What the supervisor found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// Both alive: kick the watchdog.
    Alive,
    /// The step interrupt has waited this many ticks without progress.
    StepStalled(u32),
    /// The main loop has not beaten for this many ticks.
    MainStalled(u32),
}

/// The step interrupt as the supervisor sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepSeen {
    /// Its interrupt is pending or running.
    pub waiting: bool,
    /// Entries it has taken from its queue (wrapping).
    pub taken: u32,
}

/// The supervisor's memory between checks: the last heartbeat seen and
/// when it changed, and since when the step interrupt has waited with
/// the same entries taken.
#[derive(Debug, Clone, Copy)]
pub struct Watch {
    beat: u32,
    beat_at: u32,
    step: Option<(u32, u32)>,
}

impl Watch {
    /// Starts watching at `now` with the heartbeat as it is.
    pub const fn new(now: u32, beat: u32) -> Watch {
        Watch {
            beat,
            beat_at: now,
            step: None,
        }
    }

    /// Judges at `now`: the step interrupt as seen, and the main loop's
    /// heartbeat.
    pub fn check(&mut self, now: u32, step: StepSeen, beat: u32) -> Verdict {
        if !step.waiting {
            self.step = None;
        } else {
            match self.step {
                Some((taken, since)) if taken == step.taken => {
                    let waited = now.wrapping_sub(since);
                    if waited > STEP_GRACE_TICKS {
                        return Verdict::StepStalled(waited);
                    }
                }
                _ => self.step = Some((step.taken, now)),
            }
        }
        if beat != self.beat {
            self.beat = beat;
            self.beat_at = now;
            return Verdict::Alive;
        }
        let quiet = now.wrapping_sub(self.beat_at);
        if quiet > MAIN_GRACE_TICKS {
            return Verdict::MainStalled(quiet);
        }
        Verdict::Alive
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDLE: StepSeen = StepSeen {
        waiting: false,
        taken: 0,
    };

    fn waiting(taken: u32) -> StepSeen {
        StepSeen {
            waiting: true,
            taken,
        }
    }

    #[test]
    fn an_idle_step_interrupt_and_a_beating_main_loop_are_alive() {
        let mut w = Watch::new(0, 0);
        for k in 1..1000u32 {
            assert_eq!(w.check(k * 1_000, IDLE, k), Verdict::Alive);
        }
    }

    #[test]
    fn a_step_interrupt_that_takes_entries_is_alive_whenever_it_is_seen_waiting() {
        let mut w = Watch::new(0, 0);
        for k in 1..1000u32 {
            assert_eq!(w.check(k * 1_000, waiting(k), k), Verdict::Alive);
        }
    }

    #[test]
    fn the_step_interrupt_may_wait_up_to_its_grace() {
        let mut w = Watch::new(0, 0);
        assert_eq!(w.check(1_000, waiting(7), 1), Verdict::Alive);
        assert_eq!(
            w.check(1_000 + STEP_GRACE_TICKS, waiting(7), 2),
            Verdict::Alive
        );
        assert_eq!(
            w.check(1_001 + STEP_GRACE_TICKS, waiting(7), 3),
            Verdict::StepStalled(STEP_GRACE_TICKS + 1)
        );
        // Seen idle in between: a new wait.
        let mut w = Watch::new(0, 0);
        assert_eq!(w.check(1_000, waiting(7), 1), Verdict::Alive);
        assert_eq!(w.check(2_000, IDLE, 2), Verdict::Alive);
        assert_eq!(w.check(3_500, waiting(7), 3), Verdict::Alive);
        assert_eq!(w.check(5_000, waiting(7), 4), Verdict::Alive);
    }

    #[test]
    fn a_wait_across_the_wrap_is_measured() {
        let mut w = Watch::new(u32::MAX - 100, 0);
        assert_eq!(w.check(u32::MAX - 50, waiting(3), 1), Verdict::Alive);
        assert_eq!(w.check(5_000, waiting(3), 2), Verdict::StepStalled(5_051));
    }

    #[test]
    fn a_main_loop_without_a_heartbeat_stalls_after_its_grace() {
        let mut w = Watch::new(100, 7);
        assert_eq!(w.check(100 + MAIN_GRACE_TICKS, IDLE, 7), Verdict::Alive);
        assert_eq!(
            w.check(101 + MAIN_GRACE_TICKS, IDLE, 7),
            Verdict::MainStalled(MAIN_GRACE_TICKS + 1)
        );
        // A beat starts the grace again.
        assert_eq!(w.check(102 + MAIN_GRACE_TICKS, IDLE, 8), Verdict::Alive);
        assert_eq!(w.check(102 + 2 * MAIN_GRACE_TICKS, IDLE, 8), Verdict::Alive);
    }

    #[test]
    fn a_stalled_step_interrupt_is_found_even_while_the_main_loop_beats() {
        let mut w = Watch::new(0, 0);
        assert_eq!(w.check(1_000, waiting(9), 1), Verdict::Alive);
        assert_eq!(w.check(50_000, waiting(9), 2), Verdict::StepStalled(49_000));
    }
}

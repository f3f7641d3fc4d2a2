//! The supervisor's judgement: whether the step interrupt and the main loop
//! are alive, from what each leaves behind.
//!
//! A board kicks its hardware watchdog from a periodic supervisor interrupt
//! only while [`Watch::check`] says [`Verdict::Alive`]; otherwise it drives
//! the step outputs low and lets the watchdog reset it. The inputs are:
//! - the tick by which the step interrupt must next run (`None` while it has
//!   no work): an alarm armed for an event, or a hand-over that pended it;
//! - a heartbeat the main loop advances on every pass and every wake-up
//!   from sleep. A sleeping main loop is woken by the supervisor's own
//!   interrupt, so only a main loop stuck in work stops beating.
//!
//! Ticks are a free-running 32-bit counter at [`crate::step::TickRate`]'s
//! 1 MHz, compared with wrapping arithmetic (71 minutes around).

/// How late the step interrupt may run behind the tick it was due at.
pub const STEP_GRACE_TICKS: u32 = 10_000;

/// How long the main loop may work on one request without a heartbeat:
/// planning the longest arc the protocol accepts takes well under this.
pub const MAIN_GRACE_TICKS: u32 = 2_000_000;

/// What the supervisor found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// Both alive: kick the watchdog.
    Alive,
    /// The step interrupt is this many ticks past its due tick.
    StepStalled(u32),
    /// The main loop has not beaten for this many ticks.
    MainStalled(u32),
}

/// The supervisor's memory between checks: the last heartbeat seen and
/// when it changed.
#[derive(Debug, Clone, Copy)]
pub struct Watch {
    beat: u32,
    beat_at: u32,
}

impl Watch {
    /// Starts watching at `now` with the heartbeat as it is.
    pub const fn new(now: u32, beat: u32) -> Watch {
        Watch { beat, beat_at: now }
    }

    /// Judges at `now`: the step interrupt's due tick (`None` when it has
    /// no work) and the main loop's heartbeat.
    pub fn check(&mut self, now: u32, step_due: Option<u32>, beat: u32) -> Verdict {
        if let Some(due) = step_due {
            // A due tick in the future reads as a negative lateness.
            let late = now.wrapping_sub(due) as i32;
            if late > STEP_GRACE_TICKS as i32 {
                return Verdict::StepStalled(late as u32);
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

    #[test]
    fn an_idle_step_interrupt_and_a_beating_main_loop_are_alive() {
        let mut w = Watch::new(0, 0);
        for k in 1..1000u32 {
            assert_eq!(w.check(k * 10_000, None, k), Verdict::Alive);
        }
    }

    #[test]
    fn the_step_interrupt_may_run_late_up_to_its_grace() {
        let mut w = Watch::new(0, 0);
        let due = 5_000;
        assert_eq!(
            w.check(due + STEP_GRACE_TICKS, Some(due), 1),
            Verdict::Alive
        );
        assert_eq!(
            w.check(due + STEP_GRACE_TICKS + 1, Some(due), 2),
            Verdict::StepStalled(STEP_GRACE_TICKS + 1)
        );
    }

    #[test]
    fn a_due_tick_ahead_is_not_late_even_across_the_wrap() {
        let mut w = Watch::new(u32::MAX - 100, 0);
        // Due 2^31 − 1 ticks ahead, the longest alarm.
        let now = u32::MAX - 50;
        assert_eq!(
            w.check(now, Some(now.wrapping_add(i32::MAX as u32)), 1),
            Verdict::Alive
        );
        // Overdue across the wrap.
        let due = u32::MAX - 20_000;
        assert_eq!(w.check(5, Some(due), 2), Verdict::StepStalled(20_006));
    }

    #[test]
    fn a_main_loop_without_a_heartbeat_stalls_after_its_grace() {
        let mut w = Watch::new(100, 7);
        assert_eq!(w.check(100 + MAIN_GRACE_TICKS, None, 7), Verdict::Alive);
        assert_eq!(
            w.check(101 + MAIN_GRACE_TICKS, None, 7),
            Verdict::MainStalled(MAIN_GRACE_TICKS + 1)
        );
        // A beat starts the grace again.
        assert_eq!(w.check(102 + MAIN_GRACE_TICKS, None, 8), Verdict::Alive);
        assert_eq!(w.check(102 + 2 * MAIN_GRACE_TICKS, None, 8), Verdict::Alive);
    }

    #[test]
    fn a_stalled_step_interrupt_is_found_even_while_the_main_loop_beats() {
        let mut w = Watch::new(0, 0);
        assert_eq!(
            w.check(50_000, Some(1_000), 1),
            Verdict::StepStalled(49_000)
        );
    }
}

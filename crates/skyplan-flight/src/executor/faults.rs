//! Link-loss, hold and return-to-launch bookkeeping of the executor core.

use super::interface::{
    Command, CommandKind, Event, FailsafeAction, FlightState, Target, Telemetry, VehicleMode,
};
use super::report::{ExecutorConfig, Failure, Note, Output};

/// A commanded hold awaiting the vehicle's confirmation.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PendingHold {
    pub(crate) reason: String,
    pub(crate) state: FlightState,
    pub(crate) since_s: f64,
    pub(crate) last_send_s: f64,
    pub(crate) confirmed: bool,
}

/// Link-loss, hold and return-to-launch bookkeeping, shared by both executors.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Faults {
    /// The link is lost (waiting for it): the state then.
    pub(crate) lost: Option<FlightState>,
    /// A hold was commanded.
    pub(crate) hold: Option<PendingHold>,
    /// The landing is a return to launch, with this LANDING budget (seconds).
    pub(crate) rtl_budget_s: Option<f64>,
}

impl Faults {
    /// Confirms a pending hold from an accepted ack or the reported mode.
    pub(crate) fn observe(&mut self, event: &Event) {
        if let Some(h) = &mut self.hold
            && matches!(
                event,
                Event::Ack {
                    command: CommandKind::Hold,
                    accepted: Ok(())
                } | Event::Mode(VehicleMode::Hold)
            )
        {
            h.confirmed = true;
        }
    }

    /// A lost link: `Some(failure)` ends the flight now; `None` waits for the link.
    pub(crate) fn link_lost(
        &mut self,
        state: FlightState,
        silent_s: f64,
        c: &ExecutorConfig,
        out: &mut Output,
    ) -> Option<Failure> {
        if let Some(lost_in) = self.lost {
            return (silent_s > c.link_regain_wait_s).then_some(Failure::LinkLost {
                state: lost_in,
                silent_s,
            });
        }
        match c.failsafe {
            Some(action) if !matches!(state, FlightState::Manual | FlightState::Arming) => {
                self.lost = Some(state);
                out.notes.push(Note::LinkLost {
                    state,
                    silent_s,
                    wait_s: c.link_regain_wait_s,
                    action,
                });
                None
            }
            _ => Some(Failure::LinkLost { state, silent_s }),
        }
    }

    /// The link came back: the reason and action to stop the flight with, if it was lost.
    pub(crate) fn link_regained(
        &mut self,
        silent_s: f64,
        c: &ExecutorConfig,
        out: &mut Output,
    ) -> Option<(String, FailsafeAction)> {
        let state = self.lost.take()?;
        let action = c.failsafe.unwrap_or(FailsafeAction::Land);
        out.notes.push(Note::LinkRegained { silent_s, action });
        Some((
            format!("link lost in {state} for {silent_s:.1} s; --failsafe {action} on its return"),
            action,
        ))
    }

    /// The LANDING budget: longer for a return to launch.
    pub(crate) fn landing_budget_s(&self, c: &ExecutorConfig) -> f64 {
        self.rtl_budget_s.unwrap_or(c.landing_timeout_s)
    }

    /// Starts a return to launch from `t` toward the launch point `home`.
    pub(crate) fn start_rtl(&mut self, c: &ExecutorConfig, t: Option<&Telemetry>, home: &Target) {
        let far_m = t.map_or(0.0, |t| {
            (home.north_m - t.north_m).hypot(home.east_m - t.east_m)
        });
        // Climbing to RTL_ALT (at 1 m/s, slower than any autopilot's default) and descending
        // from it at the landing rate.
        let alt_m = t.map_or(0.0, Telemetry::alt_m);
        let rtl_alt_s = c.rtl_alt_m.map_or(0.0, |rtl_m| {
            (rtl_m - alt_m).max(0.0) + rtl_m.max(alt_m) / c.landing_descent_m_s.max(0.1)
        });
        self.rtl_budget_s = Some(
            c.landing_timeout_s + c.leg_timeout_base_s + c.leg_timeout_per_m_s * far_m + rtl_alt_s,
        );
    }

    /// Drives a pending hold: `Err(reason)` when unconfirmed too long (land instead), the
    /// failure once confirmed, else the commands to repeat.
    pub(crate) fn step_hold(
        &mut self,
        now_s: f64,
        c: &ExecutorConfig,
        out: &mut Output,
    ) -> Option<Result<Failure, String>> {
        let h = self.hold.as_mut()?;
        if h.confirmed {
            return Some(Ok(Failure::Held {
                reason: h.reason.clone(),
                state: h.state,
            }));
        }
        if now_s - h.since_s > c.hold_confirm_s {
            let reason = format!(
                "{}; the hold was not confirmed within {:.0} s, landing instead",
                h.reason, c.hold_confirm_s
            );
            self.hold = None;
            return Some(Err(reason));
        }
        if now_s - h.last_send_s >= c.retry_s || now_s < h.last_send_s {
            h.last_send_s = now_s;
            out.commands.push(Command::Hold);
        }
        None
    }
}

//! A plan's trajectory as the reference a flight follows (`fly --trajectory`).

use crate::runner::ReferenceSource;
use skyplan_flight::reference::{Reference, Setpoint};
use skyplan_plan::trajectory::Trajectory;
use std::sync::Arc;

/// A trajectory (north/east/up about the home) as a [`Reference`] (north/east/down).
#[derive(Debug, Clone)]
pub struct TrajectoryReference(pub Trajectory);

fn down([n, e, u]: [f64; 3]) -> [f64; 3] {
    [n, e, -u]
}

impl Reference for TrajectoryReference {
    fn duration_s(&self) -> f64 {
        self.0.duration_s()
    }

    fn setpoint(&self, t_s: f64) -> Setpoint {
        let s = self.0.state_at(t_s);
        Setpoint {
            point_ned: down(s.point_neu),
            vel_ned_m_s: down(s.vel_neu_m_s),
            accel_ned_m_s2: down(s.accel_neu_m_s2),
            yaw_rad: s.yaw_rad,
        }
    }
}

/// The reference of each plan's trajectory: what `fly --trajectory` flies. A plan without one
/// (a request without `trajectory`) is refused.
pub fn from_plan() -> ReferenceSource {
    ReferenceSource::FromPlan(Arc::new(|plan| {
        plan.trajectory
            .as_ref()
            .map(|t| Arc::new(TrajectoryReference(t.trajectory.clone())) as Arc<dyn Reference>)
            .ok_or_else(|| "the plan has no trajectory: ask for one (trajectory true)".to_string())
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_plan::{PlanRequest, Session, World};

    #[test]
    fn setpoints_are_the_trajectory_turned_to_north_east_down() {
        let mut session = Session::new(World::fcnd_city());
        let plan = session
            .plan(&PlanRequest {
                trajectory: Some(true),
                goal_ne: Some([60.0, 40.0]),
                ..Default::default()
            })
            .unwrap();
        let t = plan.trajectory.unwrap().trajectory;
        let r = TrajectoryReference(t.clone());
        assert_eq!(r.duration_s(), t.duration_s());
        for k in 0..=20 {
            let time = t.duration_s() * f64::from(k) / 20.0;
            let (s, p) = (t.state_at(time), r.setpoint(time));
            assert_eq!(
                p.point_ned,
                [s.point_neu[0], s.point_neu[1], -s.point_neu[2]]
            );
            assert_eq!(p.vel_ned_m_s[2], -s.vel_neu_m_s[2]);
            assert_eq!(p.accel_ned_m_s2[0], s.accel_neu_m_s2[0]);
            assert_eq!(p.yaw_rad, s.yaw_rad);
        }
        assert_eq!(r.setpoint(0.0).point_ned, [0.0, 0.0, -5.0]);
    }
}

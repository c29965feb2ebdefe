//! A plan's trajectory as the reference a flight follows (`fly --trajectory`).

use crate::runner::ReferenceSource;
use skyplan_flight::executor::{Rereference, Target};
use skyplan_flight::reference::{Reference, Setpoint};
use skyplan_plan::PlanFailure;
use skyplan_plan::trajectory::{self as tj, FreeSpace, GridLayer, Limits, Trajectory};
use skyplan_replan::bench::SharedReplanner;
use skyplan_world3::{Aabb, Neu};
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

/// The map's free space (as the first trajectory saw it) less the cells the replanner learned,
/// which stand as columns at every altitude.
struct LessLearned {
    map: Arc<dyn FreeSpace + Send + Sync>,
    learned: GridLayer,
}

impl LessLearned {
    fn flat(&self, mut p: Neu) -> Neu {
        p[2] = self.learned.alt_m();
        p
    }
}

impl FreeSpace for LessLearned {
    fn box_is_free(&self, b: &Aabb) -> bool {
        self.map.box_is_free(b)
            && self.learned.box_is_free(&Aabb {
                min: self.flat(b.min),
                max: self.flat(b.max),
            })
    }

    fn segment_is_free(&self, a: Neu, b: Neu) -> bool {
        self.map.segment_is_free(a, b) && self.learned.segment_is_free(self.flat(a), self.flat(b))
    }
}

/// How a flight by a trajectory is replanned: each route the replanner finds becomes a
/// trajectory from the state of the one being flown at the switch ([`tj::plan_from`]), within
/// `limits`, in the first trajectory's free space less the learned cells.
pub fn rereference(
    replanner: &SharedReplanner,
    limits: Limits,
) -> Result<Rereference, PlanFailure> {
    let map = replanner
        .0
        .lock()
        .map_err(|_| PlanFailure::internal("the replanner failed before the flight".to_string()))?
        .trajectory_space()?;
    let replanner = replanner.clone();
    Ok(Arc::new(move |s: &Setpoint, targets: &[Target]| {
        let start = tj::State {
            t_s: 0.0,
            point_neu: down(s.point_ned),
            vel_neu_m_s: down(s.vel_ned_m_s),
            accel_neu_m_s2: down(s.accel_ned_m_s2),
            yaw_rad: s.yaw_rad,
        };
        let alt_m = start.point_neu[2];
        let learned = replanner
            .0
            .lock()
            .map_err(|_| "the replanner failed".to_string())?
            .learned_grid_at(alt_m)
            .ok_or_else(|| format!("the replanner has no layer at {alt_m:.1} m"))?;
        let free = LessLearned {
            map: Arc::clone(&map),
            learned: GridLayer::new(learned, alt_m),
        };
        let route: Vec<Neu> = targets
            .iter()
            .map(|t| [t.north_m, t.east_m, t.alt_m])
            .collect();
        let traj = tj::plan_from(&start, &route, &free, &limits, &tj::Options::default())
            .map_err(|e| e.to_string())?;
        Ok(Arc::new(TrajectoryReference(traj)) as Arc<dyn Reference>)
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

//! Where a trajectory passes the points of its route: the times, how close it comes and how fast
//! it flies each leg — what an uploaded mission (waypoints with per-leg speeds) can keep of it.

use crate::Trajectory;
use skyplan_world3::{Neu, distance_m};

/// The trajectory at one point of its route.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pass {
    /// When the trajectory is closest to the point (in route order), seconds from its start.
    pub t_s: f64,
    /// How far from the point it passes then, metres (a corner it rounds: > 0).
    pub miss_m: f64,
    /// The highest horizontal speed on the way from the previous pass to this one, m/s (0 for
    /// the first point).
    pub peak_ground_speed_m_s: f64,
}

/// Time step of the search, seconds.
const STEP_S: f64 = 0.02;

impl Trajectory {
    /// The passes of `route` (`[north_m, east_m, alt_m]` points, the route the trajectory was
    /// made through), in order: the times `t₀ ≤ t₁ ≤ …` that minimise the sum of the distances
    /// from the trajectory at `tₖ` to point `k` (a dynamic programme over samples 0.02 s apart,
    /// so a route that comes back near an earlier point is not confused by it).
    ///
    /// ```
    /// use skyplan_trajectory::{plan, GridLayer, Limits, Options};
    /// use skyplan_cspace::Grid2;
    /// let free = GridLayer::new(Grid2::from_ascii(&(".".repeat(80) + "\n").repeat(80))?, 10.0);
    /// let route = [[1.0, 1.0, 10.0], [60.0, 1.0, 10.0], [60.0, 60.0, 10.0]];
    /// let traj = plan(&route, &free, &Limits::default(), &Options::default())?;
    /// let passes = traj.passes(&route);
    /// assert_eq!(passes.len(), 3);
    /// assert!(passes[0].t_s == 0.0 && passes[2].t_s == traj.duration_s());
    /// // In open space it cuts the corner wide, near the speed limit.
    /// assert!(passes[1].miss_m > 10.0 && passes[1].peak_ground_speed_m_s > 9.0);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn passes(&self, route: &[Neu]) -> Vec<Pass> {
        let total_s = self.duration_s();
        let n = ((total_s / STEP_S).ceil() as usize).max(1);
        let states: Vec<_> = (0..=n)
            .map(|i| self.state_at(total_s * i as f64 / n as f64))
            .collect();
        if route.is_empty() {
            return Vec::new();
        }
        // best[i]: the least sum of distances for points 0..=k with point k at sample i; from[k][i]:
        // where point k−1 is then.
        let dist = |k: usize, i: usize| distance_m(states[i].point_neu, route[k]);
        let mut best: Vec<f64> = (0..=n).map(|i| dist(0, i)).collect();
        let mut from: Vec<Vec<u32>> = Vec::with_capacity(route.len());
        from.push(Vec::new());
        for k in 1..route.len() {
            let (mut run_min, mut run_at) = (f64::INFINITY, 0u32);
            let mut next = vec![0.0; n + 1];
            let mut back = vec![0u32; n + 1];
            for i in 0..=n {
                if best[i] < run_min {
                    (run_min, run_at) = (best[i], i as u32);
                }
                next[i] = run_min + dist(k, i);
                back[i] = run_at;
            }
            best = next;
            from.push(back);
        }
        let mut at = vec![0usize; route.len()];
        let last = route.len() - 1;
        at[last] = (0..=n)
            .min_by(|&a, &b| best[a].total_cmp(&best[b]))
            .unwrap_or(n);
        for k in (1..route.len()).rev() {
            at[k - 1] = from[k][at[k]] as usize;
        }
        let ground = |i: usize| {
            let v = states[i].vel_neu_m_s;
            v[0].hypot(v[1])
        };
        (0..route.len())
            .map(|k| {
                let i = at[k];
                let start = if k == 0 { i } else { at[k - 1] };
                Pass {
                    t_s: states[i].t_s,
                    miss_m: dist(k, i),
                    peak_ground_speed_m_s: (start..=i).map(ground).fold(0.0, f64::max),
                }
            })
            .collect()
    }
}

//! What the trajectory tests share: the dense check against independent truth.

use skyplan_trajectory::Trajectory;
use skyplan_world3::Neu;

/// The norm of a vector.
pub fn norm(v: Neu) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Samples `traj` so densely that consecutive points are ≤ 1 cm apart (at its proven speed
/// bound): every point free by `is_free`, speed, acceleration, climb and descent within the
/// limits at every sample.
pub fn dense_check_free_and_within_limits(traj: &Trajectory, is_free: &dyn Fn(Neu) -> bool) {
    let lim = traj.limits;
    let dt = 0.01 / traj.bounds.speed_m_s.max(1e-3);
    let total = traj.duration_s();
    let n = (total / dt).ceil() as usize;
    for i in 0..=n {
        let s = traj.state_at(total * i as f64 / n as f64);
        assert!(
            is_free(s.point_neu),
            "{}: point {:?} at t {} s is not free",
            traj.method.name(),
            s.point_neu,
            s.t_s
        );
        assert!(norm(s.vel_neu_m_s) <= lim.max_speed_m_s * (1.0 + 1e-9));
        assert!(norm(s.accel_neu_m_s2) <= lim.max_accel_m_s2 * (1.0 + 1e-9));
        assert!(s.vel_neu_m_s[2] <= lim.max_climb_m_s * (1.0 + 1e-9));
        assert!(-s.vel_neu_m_s[2] <= lim.max_descent_m_s * (1.0 + 1e-9));
    }
}

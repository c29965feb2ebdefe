//! Minimum-jerk quintic Bézier pieces in the corridor (one quadratic programme per axis,
//! clarabel), and the time allocation that makes the limits tight.

use crate::check::piece_bounds;
use crate::{CorridorCell, Limits, Piece, Region};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use skyplan_world3::{Aabb, Neu, distance_m};
use std::time::Instant;

/// Control points per piece (quintic).
const K: usize = 6;

/// `∫₀¹ Bᵢ² Bⱼ²` for the quadratic Bernstein basis (the jerk curve's degree).
const M2: [[f64; 3]; 3] = [
    [1.0 / 5.0, 1.0 / 10.0, 1.0 / 30.0],
    [1.0 / 10.0, 2.0 / 15.0, 1.0 / 10.0],
    [1.0 / 30.0, 1.0 / 10.0, 1.0 / 5.0],
];

/// The jerk Hessian of one piece of unit duration: `D3ᵀ M2 D3` with `D3` the third difference.
fn jerk_hessian() -> [[f64; K]; K] {
    let d3 = [
        [-1.0, 3.0, -3.0, 1.0, 0.0, 0.0],
        [0.0, -1.0, 3.0, -3.0, 1.0, 0.0],
        [0.0, 0.0, -1.0, 3.0, -3.0, 1.0],
    ];
    let mut h = [[0.0; K]; K];
    for (i, hi) in h.iter_mut().enumerate() {
        for (j, hij) in hi.iter_mut().enumerate() {
            let mut s = 0.0;
            for a in 0..3 {
                for b in 0..3 {
                    s += d3[a][i] * M2[a][b] * d3[b][j];
                }
            }
            *hij = s;
        }
    }
    h
}

/// Why a solve failed.
enum SolveError {
    /// No curve meets the corridor and the limits on control points at these durations.
    Infeasible,
    /// Anything else, in a sentence.
    Other(String),
}

/// Rows of `A x + s = b`, in cone order: equalities, then inequalities.
#[derive(Default)]
struct Rows {
    i: Vec<usize>,
    j: Vec<usize>,
    v: Vec<f64>,
    b: Vec<f64>,
}

impl Rows {
    fn push(&mut self, terms: &[(usize, f64)], rhs: f64) {
        let row = self.b.len();
        for &(j, v) in terms {
            self.i.push(row);
            self.j.push(j);
            self.v.push(v);
        }
        self.b.push(rhs);
    }
}

/// The problem: `D` moving axes, `x[(p·K + k)·D + d]` the control point `k` of piece `p` on
/// axis `d` (shifted so the start is the origin).
struct Problem<'a> {
    lo: Vec<[f64; 3]>,
    hi: Vec<[f64; 3]>,
    goal: [f64; 3],
    times: &'a [f64],
    dims: usize,
    lim: &'a Limits,
    /// Bounds of each join (the point between piece `p` and `p + 1`), shifted like `lo`/`hi`.
    joints: Option<Vec<([f64; 3], [f64; 3])>>,
    /// A feasible place for each join (in both of its boxes and its bounds), shifted.
    start_joins: Vec<[f64; 3]>,
    /// Solve by the banded active-set method first (clarabel when it cannot).
    active_set: bool,
    /// A previous solution's `[position, velocity, acceleration]` at each join, shifted.
    warm: Option<Vec<[Neu; 3]>>,
    /// How far inside each box the active-set method keeps the control points, metres.
    hair: f64,
    /// The velocity and acceleration at the start (zero: at rest).
    moving: Moving,
}

/// A start in motion: velocity and acceleration `[north, east, up]`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Moving {
    pub vel: Neu,
    pub accel: Neu,
}

impl Moving {
    fn at_rest(&self) -> bool {
        *self == Self::default()
    }
}

impl Problem<'_> {
    fn var(&self, p: usize, k: usize, d: usize) -> usize {
        (p * K + k) * self.dims + d
    }

    /// The objective: jerk² integrated over every piece (scaled by the mean duration⁵).
    fn hessian(&self) -> CscMatrix<f64> {
        let n = self.times.len();
        let h = jerk_hessian();
        let (mut pi, mut pj, mut pv) = (Vec::new(), Vec::new(), Vec::new());
        for (p, w) in self.weights().into_iter().enumerate() {
            for d in 0..self.dims {
                for (i, hi) in h.iter().enumerate() {
                    for (j, &hij) in hi.iter().enumerate().skip(i) {
                        if hij != 0.0 {
                            pi.push(self.var(p, i, d));
                            pj.push(self.var(p, j, d));
                            pv.push(hij * w);
                        }
                    }
                }
            }
        }
        let nv = n * K * self.dims;
        CscMatrix::new_from_triplets(nv, nv, pi, pj, pv)
    }

    /// The start's state (rest, or the motion given), rest at the goal and C² joins.
    fn equalities(&self, rows: &mut Rows) {
        let n = self.times.len();
        let l = n - 1;
        let t0 = self.times[0];
        for d in 0..self.dims {
            let x = |p, k| self.var(p, k, d);
            // A quintic's velocity at 0 is 5 (c1 − c0) / T, its acceleration 20 (c2 − 2c1 + c0) / T².
            rows.push(&[(x(0, 0), 1.0)], 0.0);
            rows.push(
                &[(x(0, 1), 1.0), (x(0, 0), -1.0)],
                self.moving.vel[d] * t0 / 5.0,
            );
            rows.push(
                &[(x(0, 2), 1.0), (x(0, 1), -2.0), (x(0, 0), 1.0)],
                self.moving.accel[d] * t0 * t0 / 20.0,
            );
            rows.push(&[(x(l, 5), 1.0)], self.goal[d]);
            rows.push(&[(x(l, 5), 1.0), (x(l, 4), -1.0)], 0.0);
            rows.push(&[(x(l, 5), 1.0), (x(l, 4), -2.0), (x(l, 3), 1.0)], 0.0);
            for p in 0..l {
                let (ta, tc) = (self.times[p], self.times[p + 1]);
                rows.push(&[(x(p, 5), 1.0), (x(p + 1, 0), -1.0)], 0.0);
                let (ua, uc) = (1.0 / ta, 1.0 / tc);
                rows.push(
                    &[
                        (x(p, 5), ua),
                        (x(p, 4), -ua),
                        (x(p + 1, 1), -uc),
                        (x(p + 1, 0), uc),
                    ],
                    0.0,
                );
                let (qa, qc) = (ua * ua, uc * uc);
                rows.push(
                    &[
                        (x(p, 5), qa),
                        (x(p, 4), -2.0 * qa),
                        (x(p, 3), qa),
                        (x(p + 1, 2), -qc),
                        (x(p + 1, 1), 2.0 * qc),
                        (x(p + 1, 0), -qc),
                    ],
                    0.0,
                );
            }
            // A box flat along this axis (a stretch hemmed in on both sides): points fixed.
            for p in 0..n {
                if self.hi[p][d] - self.lo[p][d] < 1e-6 {
                    for k in 0..K {
                        rows.push(&[(x(p, k), 1.0)], 0.5 * (self.lo[p][d] + self.hi[p][d]));
                    }
                }
            }
        }
    }

    /// The corridor (a hair inside each box, so the solver's tolerance stays in it) and the
    /// climb and descent limits on the vertical velocity's control points.
    fn inequalities(&self, rows: &mut Rows) {
        for p in 0..self.times.len() {
            for d in 0..self.dims {
                let (lo, hi) = (self.lo[p][d], self.hi[p][d]);
                if hi - lo < 1e-6 {
                    continue;
                }
                let hair = CLARABEL_HAIR_M.min((hi - lo) / 4.0);
                for k in 0..K {
                    rows.push(&[(self.var(p, k, d), 1.0)], hi - hair);
                    rows.push(&[(self.var(p, k, d), -1.0)], -(lo + hair));
                }
            }
            if let Some(j) = self.joints.as_ref().and_then(|j| j.get(p)) {
                for d in 0..self.dims {
                    let (lo, hi) = (j.0[d].max(self.lo[p][d]), j.1[d].min(self.hi[p][d]));
                    if hi - lo > 1e-6 {
                        rows.push(&[(self.var(p, 5, d), 1.0)], hi);
                        rows.push(&[(self.var(p, 5, d), -1.0)], -lo);
                    }
                }
            }
            if self.dims == 3 {
                let c = 5.0 / self.times[p];
                for k in 0..K - 1 {
                    let (up, now) = (self.var(p, k + 1, 2), self.var(p, k, 2));
                    rows.push(&[(up, c), (now, -c)], self.lim.max_climb_m_s);
                    rows.push(&[(up, -c), (now, c)], self.lim.max_descent_m_s);
                }
            }
        }
    }

    /// Each piece's weight in the objective: `(mean duration / duration)⁵`.
    fn weights(&self) -> Vec<f64> {
        let n = self.times.len();
        let mean = self.times.iter().sum::<f64>() / n as f64;
        self.times.iter().map(|&t| (mean / t).powi(5)).collect()
    }

    /// The jerk objective at `x` (the quantity both solvers minimise).
    #[cfg(test)]
    fn objective(&self, x: &[f64]) -> f64 {
        let h = jerk_hessian();
        let w = self.weights();
        let mut total = 0.0;
        for (p, wp) in w.iter().enumerate() {
            for d in 0..self.dims {
                for (i, hi) in h.iter().enumerate() {
                    for (j, hij) in hi.iter().enumerate() {
                        total += wp * hij * x[self.var(p, i, d)] * x[self.var(p, j, d)];
                    }
                }
            }
        }
        total
    }

    /// Every axis by [`crate::active_set`], or `None` when one of them cannot be.
    fn solve_active_set(&self) -> Option<Vec<f64>> {
        let n = self.times.len();
        let w = self.weights();
        let h = jerk_hessian();
        let mut x = vec![0.0; n * K * self.dims];
        for d in 0..self.dims {
            let joint_bounds = self.joints.as_ref().map(|joints| {
                joints
                    .iter()
                    .enumerate()
                    .map(|(p, j)| {
                        let (lo, hi) = (j.0[d].max(self.lo[p][d]), j.1[d].min(self.hi[p][d]));
                        if hi - lo > 1e-6 {
                            (lo, hi)
                        } else {
                            (f64::NEG_INFINITY, f64::INFINITY)
                        }
                    })
                    .collect()
            });
            let axis = crate::active_set::AxisProblem {
                times: self.times,
                lo: self.lo.iter().map(|b| b[d]).collect(),
                hi: self.hi.iter().map(|b| b[d]).collect(),
                goal: self.goal[d],
                joint_bounds,
                start_joins: self.start_joins.iter().map(|q| q[d]).collect(),
                climb: (self.dims == 3 && d == 2)
                    .then_some((self.lim.max_climb_m_s, self.lim.max_descent_m_s)),
                hair: self.hair,
                warm: self
                    .warm
                    .as_ref()
                    .map(|w| w.iter().map(|s| [s[0][d], s[1][d], s[2][d]]).collect()),
            };
            let cps = axis.solve(&w, &h)?;
            for (p, c) in cps.iter().enumerate() {
                for (k, &v) in c.iter().enumerate() {
                    x[self.var(p, k, d)] = v;
                }
            }
        }
        Some(x)
    }

    fn solve(&self, deadline: Instant) -> Result<Vec<f64>, SolveError> {
        // The banded active-set method is written for a start at rest.
        if self.active_set
            && self.moving.at_rest()
            && let Some(x) = self.solve_active_set()
        {
            return Ok(x);
        }
        self.solve_clarabel(deadline)
    }

    fn solve_clarabel(&self, deadline: Instant) -> Result<Vec<f64>, SolveError> {
        let nv = self.times.len() * K * self.dims;
        let mut rows = Rows::default();
        self.equalities(&mut rows);
        let n_eq = rows.b.len();
        self.inequalities(&mut rows);
        let n_ineq = rows.b.len() - n_eq;
        let cones = [
            SupportedConeT::ZeroConeT(n_eq),
            SupportedConeT::NonnegativeConeT(n_ineq),
        ];
        let m = rows.b.len();
        let a_mat = CscMatrix::new_from_triplets(m, nv, rows.i, rows.j, rows.v);
        let left = deadline
            .saturating_duration_since(Instant::now())
            .as_secs_f64();
        if left <= 0.0 {
            return Err(SolveError::Other(OUT_OF_TIME.into()));
        }
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .time_limit(left)
            // Millimetre-level accuracy is plenty: the result is clamped into its boxes and
            // every guarantee is checked again from the final pieces.
            .tol_gap_abs(1e-6)
            .tol_gap_rel(1e-6)
            .tol_feas(1e-7)
            .iterative_refinement_enable(false)
            .presolve_enable(false)
            .build()
            .map_err(|e| SolveError::Other(format!("solver settings: {e}")))?;
        let q = vec![0.0; nv];
        let mut solver = DefaultSolver::new(&self.hessian(), &q, &a_mat, &rows.b, &cones, settings)
            .map_err(|e| SolveError::Other(format!("the solver refused the problem: {e}")))?;
        solver.solve();
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => Ok(solver.solution.x.clone()),
            SolverStatus::MaxTime => Err(SolveError::Other(OUT_OF_TIME.into())),
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                Err(SolveError::Infeasible)
            }
            other => Err(SolveError::Other(format!(
                "the solver ended with {}",
                status_words(other)
            ))),
        }
    }
}

/// The reason given when the budget runs out.
pub(crate) const OUT_OF_TIME: &str = "the time budget ran out";

fn status_words(s: SolverStatus) -> &'static str {
    match s {
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            "no solution in the corridor"
        }
        SolverStatus::MaxIterations => "too many iterations",
        SolverStatus::NumericalError | SolverStatus::InsufficientProgress => "a numerical failure",
        _ => "no solution",
    }
}

/// How far inside its box the active-set method keeps each control point, metres: its
/// rounding stays inside the box, so the final clamp into the box never moves a point.
const HAIR_M: f64 = 1e-5;

/// The same for clarabel, whose feasibility tolerance is 1e-7: a start or goal on a box's face
/// must stay within it.
const CLARABEL_HAIR_M: f64 = 1e-7;

/// How far a join may move from where the shape put it when the durations change, metres.
const JOINT_SLACK_M: f64 = 0.5;

/// Durations at the limit speed on every stretch (the climb and descent limits included): the
/// first solve only finds the shape.
fn shape_times(cells: &[CorridorCell], lim: &Limits) -> Vec<f64> {
    floored(
        cells
            .iter()
            .map(|c| distance_m(c.from, c.to) / crate::leg_speed_m_s(c.from, c.to, lim))
            .collect(),
    )
}

/// No piece much shorter in time than the typical one: the jerk weights go as 1/T⁵, and short
/// stretches (left by splitting near obstacles) would make the problem badly conditioned.
fn floored(times: Vec<f64>) -> Vec<f64> {
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let floor = 0.2 * sorted[sorted.len() / 2];
    times.into_iter().map(|t| t.max(floor)).collect()
}

/// The radius of the circle through three points (infinite when they are collinear).
fn circumradius(a: Neu, b: Neu, c: Neu) -> f64 {
    let (ab, bc, ca) = (distance_m(a, b), distance_m(b, c), distance_m(c, a));
    let u = [0, 1, 2].map(|k| b[k] - a[k]);
    let v = [0, 1, 2].map(|k| c[k] - a[k]);
    let cross = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let twice_area = crate::bezier::norm(cross);
    if twice_area <= 1e-12 * (ab * bc).max(1e-12) {
        f64::INFINITY
    } else {
        ab * bc * ca / (2.0 * twice_area)
    }
}

/// Durations from a speed profile along the shape's joins: at each join the speed a turn of
/// its radius allows at half the acceleration limit, then forward and backward passes with
/// half the acceleration limit from rest at both ends; each piece lasts its length over its
/// mean speed.
fn profile_times(points: &[Neu], lim: &Limits, start_speed_m_s: f64) -> Vec<f64> {
    let n = points.len() - 1; // pieces
    let a = 0.5 * lim.max_accel_m_s2;
    let lens: Vec<f64> = points.windows(2).map(|w| distance_m(w[0], w[1])).collect();
    let mut v: Vec<f64> = (0..=n)
        .map(|i| {
            if i == 0 {
                return start_speed_m_s;
            }
            if i == n {
                return 0.0;
            }
            let leg = crate::leg_speed_m_s(points[i - 1], points[i], lim)
                .min(crate::leg_speed_m_s(points[i], points[i + 1], lim));
            leg.min((a * circumradius(points[i - 1], points[i], points[i + 1])).sqrt())
        })
        .collect();
    for i in 1..=n {
        v[i] = v[i].min((v[i - 1] * v[i - 1] + 2.0 * a * lens[i - 1]).sqrt());
    }
    // The start's speed is given: the backward pass slows the rest, not the start.
    for i in (1..n).rev() {
        v[i] = v[i].min((v[i + 1] * v[i + 1] + 2.0 * a * lens[i]).sqrt());
    }
    if start_speed_m_s == 0.0 {
        v[0] = v[0].min((v[1] * v[1] + 2.0 * a * lens[0]).sqrt());
    }
    floored(
        (0..n)
            .map(|i| {
                let mean = 0.5 * (v[i] + v[i + 1]);
                if mean > 1e-9 {
                    lens[i] / mean
                } else {
                    2.0 * (lens[i] / a).sqrt()
                }
            })
            .collect(),
    )
}

/// How much slower each piece must be flown for its bounds to meet the limits (1 = tight).
fn ratios(pieces: &[Piece], lim: &Limits) -> Vec<f64> {
    pieces
        .iter()
        .map(|p| {
            let b = piece_bounds(&p.control_points_neu, p.duration_s);
            [
                b.speed_m_s / lim.max_speed_m_s,
                b.climb_m_s / lim.max_climb_m_s,
                b.descent_m_s / lim.max_descent_m_s,
                (b.accel_m_s2 / lim.max_accel_m_s2).sqrt(),
                (b.jerk_m_s3 / lim.max_jerk_m_s3).cbrt(),
            ]
            .into_iter()
            .fold(0.0, f64::max)
        })
        .collect()
}

/// The pieces for given durations, from one solve per moving axis.
#[allow(clippy::too_many_arguments)]
fn shape(
    cells: &[CorridorCell],
    planar: bool,
    times: &[f64],
    lim: &Limits,
    joints: Option<&[Neu]>,
    warm: Option<&[Piece]>,
    deadline: Instant,
    moving: Moving,
) -> Result<Vec<Piece>, SolveError> {
    let n = cells.len();
    let start = cells[0].from;
    let goal = cells[n - 1].to;
    let dims = if planar { 2 } else { 3 };
    let shifted = |v: [f64; 3]| [0, 1, 2].map(|d| v[d] - start[d]);
    let problem = Problem {
        lo: cells.iter().map(|c| shifted(c.region.min)).collect(),
        hi: cells.iter().map(|c| shifted(c.region.max)).collect(),
        goal: shifted(goal),
        times,
        dims,
        lim,
        joints: joints.map(|j| {
            j.iter()
                .map(|&q| {
                    let q = shifted(q);
                    (q.map(|v| v - JOINT_SLACK_M), q.map(|v| v + JOINT_SLACK_M))
                })
                .collect()
        }),
        start_joins: match joints {
            Some(j) => j.iter().map(|&q| shifted(q)).collect(),
            None => cells[..n - 1].iter().map(|c| shifted(c.to)).collect(),
        },
        active_set: true,
        warm: Some(match warm {
            Some(pieces) => pieces[1..]
                .iter()
                .map(|p| {
                    let c = &p.control_points_neu;
                    let t = p.duration_s;
                    [
                        shifted(c[0]),
                        [0, 1, 2].map(|d| 5.0 * (c[1][d] - c[0][d]) / t),
                        [0, 1, 2].map(|d| 20.0 * (c[2][d] - 2.0 * c[1][d] + c[0][d]) / (t * t)),
                    ]
                })
                .collect(),
            // No solution yet: the route's joins, moving along the route at the pace the
            // durations give (the chord over the two pieces around the join).
            None => (0..n - 1)
                .map(|p| {
                    let (a, b) = (cells[p].from, cells[p + 1].to);
                    let t = times[p] + times[p + 1];
                    [
                        shifted(cells[p].to),
                        [0, 1, 2].map(|d| (b[d] - a[d]) / t),
                        [0.0; 3],
                    ]
                })
                .collect(),
        }),
        hair: HAIR_M,
        moving,
    };
    let x = problem.solve(deadline)?;
    let mut ctrl = vec![[start; K]; n];
    for (p, c) in ctrl.iter_mut().enumerate() {
        for (k, point) in c.iter_mut().enumerate() {
            for d in 0..dims {
                point[d] = (x[problem.var(p, k, d)] + start[d])
                    .clamp(cells[p].region.min[d], cells[p].region.max[d]);
            }
        }
    }
    // Exact joins (in both boxes) and exact rest at the ends.
    for p in 0..n - 1 {
        let both = intersect(&cells[p].region, &cells[p + 1].region);
        let joint = [0, 1, 2]
            .map(|a| (0.5 * (ctrl[p][5][a] + ctrl[p + 1][0][a])).clamp(both.min[a], both.max[a]));
        ctrl[p][5] = joint;
        ctrl[p + 1][0] = joint;
    }
    // The start's state exactly (see `equalities`), and rest at the goal.
    let t0 = times[0];
    ctrl[0][0] = start;
    ctrl[0][1] = [0, 1, 2].map(|d| start[d] + moving.vel[d] * t0 / 5.0);
    ctrl[0][2] =
        [0, 1, 2].map(|d| 2.0 * ctrl[0][1][d] - start[d] + moving.accel[d] * t0 * t0 / 20.0);
    for k in 0..3 {
        ctrl[n - 1][5 - k] = goal;
    }
    Ok(ctrl
        .into_iter()
        .zip(cells)
        .zip(times)
        .map(|((c, cell), &t)| Piece {
            duration_s: t,
            control_points_neu: c.to_vec(),
            region: Region::of_box(&cell.region),
        })
        .collect())
}

fn intersect(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb {
        min: [0, 1, 2].map(|k| a.min[k].max(b.min[k])),
        max: [0, 1, 2].map(|k| a.max[k].min(b.max[k])),
    }
}

/// Scales every duration by one factor so the tightest limit is exactly met.
fn scale_to_limits(mut pieces: Vec<Piece>, lim: &Limits) -> Vec<Piece> {
    let s = ratios(&pieces, lim).into_iter().fold(0.0, f64::max) * (1.0 + 1e-9);
    if s > 0.0 && s.is_finite() {
        for p in &mut pieces {
            p.duration_s *= s;
        }
    }
    pieces
}

fn total(pieces: &[Piece]) -> f64 {
    pieces.iter().map(|p| p.duration_s).sum()
}

/// Minimum-jerk pieces in the corridor with durations tight to the limits, or why not.
pub(crate) fn minimum_jerk(
    cells: &[CorridorCell],
    planar: bool,
    lim: &Limits,
    deadline: Instant,
    rounds: u32,
) -> Result<Vec<Piece>, String> {
    if cells.is_empty() {
        return Err("the corridor is empty".into());
    }
    // 1. The shape, at the limit speed everywhere.
    let times = shape_times(cells, lim);
    let rest = Moving::default();
    let first = match shape(cells, planar, &times, lim, None, None, deadline, rest) {
        Ok(p) => p,
        Err(SolveError::Infeasible) => return Err("no curve met the corridor".into()),
        Err(SolveError::Other(why)) => return Err(why),
    };
    // 2. Durations from a speed profile along it; the joins stay near the shape's.
    let mut points: Vec<Neu> = first.iter().map(|p| p.control_points_neu[0]).collect();
    points.push(cells[cells.len() - 1].to);
    let joints: Vec<Neu> = points[1..points.len() - 1].to_vec();
    let times = profile_times(&points, lim, 0.0);
    let shaped = shape(
        cells,
        planar,
        &times,
        lim,
        Some(&joints),
        Some(&first),
        deadline,
        rest,
    )
    .or_else(|_| shape(cells, planar, &times, lim, None, None, deadline, rest));
    let mut best = scale_to_limits(first, lim);
    if let Ok(p) = shaped {
        let p = scale_to_limits(p, lim);
        if total(&p) < total(&best) {
            best = p;
        }
    }
    // 3. Shorten the pieces that are slower than they need be; keep the result if the whole
    // is faster once scaled to the limits again.
    let mut misses = 0;
    let mut current = best.clone();
    for _ in 0..rounds {
        if Instant::now() >= deadline || misses >= 2 {
            break;
        }
        let r = ratios(&current, lim);
        let times = floored(
            current
                .iter()
                .zip(&r)
                .map(|(p, &ri)| p.duration_s * ri.clamp(0.25, 1.0).powf(0.7))
                .collect(),
        );
        let Ok(next) = shape(
            cells,
            planar,
            &times,
            lim,
            Some(&joints),
            Some(&current),
            deadline,
            rest,
        ) else {
            break;
        };
        current = scale_to_limits(next, lim);
        if total(&current) < total(&best) * 0.999 {
            best = current.clone();
            misses = 0;
        } else {
            misses += 1;
        }
    }
    Ok(best)
}

/// The longest duration up to `t_s` (shortened by 15 % steps) for which the first piece's
/// control points fixed by the start's motion stay in its box: `c1 = p + v T / 5` and
/// `c2 = p + 2 v T / 5 + a T² / 20` (a long first piece would carry them out of it).
fn first_piece_fits(cell: &CorridorCell, planar: bool, moving: Moving, t_s: f64) -> f64 {
    let (p, b) = (cell.from, &cell.region);
    let dims = if planar { 2 } else { 3 };
    let fits = |t: f64| {
        (0..dims).all(|d| {
            let (v, a) = (moving.vel[d], moving.accel[d]);
            [v * t / 5.0, 2.0 * v * t / 5.0 + a * t * t / 20.0]
                .iter()
                .all(|dx| (b.min[d] + HAIR_M..=b.max[d] - HAIR_M).contains(&(p[d] + dx)))
        })
    };
    let mut t = t_s;
    for _ in 0..40 {
        if fits(t) {
            return t;
        }
        t *= 0.85;
    }
    t
}

/// Minimum-jerk pieces in the corridor from a start in motion (`vel`, `accel`), or why not.
///
/// One common time factor cannot scale such pieces to the limits (it would scale the start's
/// velocity too), so the durations come from a speed profile starting at the start's speed,
/// and each piece whose bounds break a limit is flown slower (its duration times its ratio),
/// until every piece holds or the rounds or the time run out.
pub(crate) fn minimum_jerk_from(
    cells: &[CorridorCell],
    planar: bool,
    lim: &Limits,
    deadline: Instant,
    vel: Neu,
    accel: Neu,
) -> Result<Vec<Piece>, String> {
    /// Rounds of slowing the pieces that break a limit.
    const ROUNDS: usize = 16;
    if cells.is_empty() {
        return Err("the corridor is empty".into());
    }
    let moving = Moving { vel, accel };
    let mut points: Vec<Neu> = cells.iter().map(|c| c.from).collect();
    points.push(cells[cells.len() - 1].to);
    let mut times = profile_times(&points, lim, crate::bezier::norm(vel));
    let mut why = String::from("the time budget ran out");
    for _ in 0..ROUNDS {
        if Instant::now() >= deadline {
            return Err(why);
        }
        times[0] = first_piece_fits(&cells[0], planar, moving, times[0]);
        let pieces = match shape(cells, planar, &times, lim, None, None, deadline, moving) {
            Ok(p) => p,
            Err(SolveError::Infeasible) => {
                return Err("no curve from the start's motion met the corridor".into());
            }
            Err(SolveError::Other(e)) => return Err(e),
        };
        let r = ratios(&pieces, lim);
        let worst = r.iter().copied().fold(0.0, f64::max);
        if worst <= 1.0 {
            return Ok(pieces);
        }
        why = format!(
            "a piece still broke a limit by a factor {worst:.3} after {ROUNDS} rounds of slowing"
        );
        // The pieces over a limit, and less so their neighbours (a piece's bounds depend on
        // the joins it shares), are slowed.
        let grow: Vec<f64> = (0..r.len())
            .map(|i| {
                let own = r[i].max(1.0).powi(2) * if r[i] > 1.0 { 1.05 } else { 1.0 };
                let near = [i.wrapping_sub(1), i + 1]
                    .iter()
                    .filter_map(|&j| r.get(j))
                    .fold(1.0_f64, |m, &rj| m.max(rj.max(1.0).sqrt()));
                own.max(near)
            })
            .collect();
        for (t, g) in times.iter_mut().zip(grow) {
            *t *= g;
        }
    }
    Err(why)
}

#[cfg(test)]
mod tests {
    use super::*;

    use skyplan_testkit::XorShift;

    /// A random walk of `n` stretches with a box grown a random amount around each.
    fn corridor(seed: u64, n: usize, planar: bool) -> Vec<CorridorCell> {
        let mut rng = XorShift::new(seed);
        let mut at = [0.0, 0.0, 20.0];
        (0..n)
            .map(|_| {
                let step = [
                    40.0 * rng.unit() - 20.0,
                    40.0 * rng.unit() - 20.0,
                    if planar { 0.0 } else { 10.0 * rng.unit() - 5.0 },
                ];
                let to = [0, 1, 2].map(|k| at[k] + step[k]);
                let grow: [f64; 6] = std::array::from_fn(|_| {
                    let g = 6.0 * rng.unit() - 1.0;
                    g.max(0.0)
                });
                let region = Aabb {
                    min: [0, 1, 2].map(|k| at[k].min(to[k]) - grow[k]),
                    max: [0, 1, 2].map(|k| at[k].max(to[k]) + grow[3 + k]),
                };
                let cell = CorridorCell {
                    from: at,
                    to,
                    region,
                };
                at = to;
                cell
            })
            .collect()
    }

    fn problem<'a>(
        cells: &[CorridorCell],
        planar: bool,
        times: &'a [f64],
        lim: &'a Limits,
        active_set: bool,
    ) -> Problem<'a> {
        let start = cells[0].from;
        let shifted = |v: [f64; 3]| [0, 1, 2].map(|d| v[d] - start[d]);
        Problem {
            lo: cells.iter().map(|c| shifted(c.region.min)).collect(),
            hi: cells.iter().map(|c| shifted(c.region.max)).collect(),
            goal: shifted(cells[cells.len() - 1].to),
            times,
            dims: if planar { 2 } else { 3 },
            lim,
            joints: None,
            start_joins: cells[..cells.len() - 1]
                .iter()
                .map(|c| shifted(c.to))
                .collect(),
            active_set,
            warm: None,
            hair: HAIR_M,
            moving: Moving::default(),
        }
    }

    /// The banded active-set solver finds clarabel's minimum, inside the corridor.
    #[test]
    fn active_set_matches_clarabel_on_random_corridors() {
        let lim = Limits::default();
        let deadline = Instant::now() + std::time::Duration::from_secs(60);
        let mut solved = 0;
        for seed in 0..60u64 {
            let planar = seed % 3 != 0;
            let n = 2 + (seed as usize * 7) % 40;
            let cells = corridor(seed, n, planar);
            let mut rng = XorShift::new(seed + 99);
            // Long enough in 3D for the climb limits to hold at rest at every join.
            let times: Vec<f64> = cells
                .iter()
                .map(|c| {
                    let climb = 5.0 * (c.to[2] - c.from[2]).abs() / lim.max_descent_m_s;
                    (1.0 + 3.0 * rng.unit()).max(climb * 1.01)
                })
                .collect();
            let reference = problem(&cells, planar, &times, &lim, false);
            // The oracle itself may stop short on an ill-conditioned draw: such a seed is not
            // compared (the count below bounds how many).
            let Ok(x_ref) = reference.solve_clarabel(deadline) else {
                continue;
            };
            let ours = problem(&cells, planar, &times, &lim, true);
            let Some(x) = ours.solve_active_set() else {
                continue;
            };
            solved += 1;
            // The active-set method keeps 10 µm inside the boxes, clarabel 0.1 µm: the optima
            // differ by that much.
            let (f, f_ref) = (ours.objective(&x), reference.objective(&x_ref));
            assert!(
                f <= f_ref * (1.0 + 1e-4) + 1e-9,
                "seed {seed}: objective {f} against clarabel's {f_ref}"
            );
            for p in 0..n {
                for k in 0..K {
                    for d in 0..ours.dims {
                        let v = x[ours.var(p, k, d)];
                        assert!(
                            v >= ours.lo[p][d] - 1e-6 && v <= ours.hi[p][d] + 1e-6,
                            "seed {seed}: piece {p} point {k} axis {d} at {v} outside [{}, {}]",
                            ours.lo[p][d],
                            ours.hi[p][d]
                        );
                    }
                }
            }
            // And no better than the true minimum (clarabel's, to its tolerance).
            assert!(
                f >= f_ref * (1.0 - 1e-4) - 1e-9,
                "seed {seed}: {f} below {f_ref}"
            );
        }
        assert!(
            solved >= 50,
            "the active-set method solved only {solved} of 60"
        );
    }
}

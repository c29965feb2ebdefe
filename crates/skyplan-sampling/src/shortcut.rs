//! Shortcutting for 3D paths, as independent passes (OMPL's `PathSimplifier`): every new segment
//! is re-checked exactly with the collision checker, a change is kept only if the path gets no
//! longer, and the first and last points never move.
//!
//! ```
//! use skyplan_map::colliders::ObstacleBox;
//! use skyplan_sampling::shortcut::reduce_vertices;
//! use skyplan_world3::{BoxWorld3, WorldSpec};
//! let tower = ObstacleBox { north_m: 50.0, east_m: 50.0, up_m: 20.0, half_north_m: 10.0, half_east_m: 10.0, half_up_m: 20.0 };
//! let spec = WorldSpec { safety_m: 2.0, min_alt_m: 0.0, max_alt_m: 50.0, margin_bounds_m: 40.0 };
//! let world = BoxWorld3::new(&[tower], &spec)?;
//! // A detour with a needless corner on the free side.
//! let path = vec![[10.0, 10.0, 5.0], [20.0, 12.0, 5.0], [30.0, 10.0, 5.0], [90.0, 10.0, 5.0]];
//! assert_eq!(reduce_vertices(&world, &path), vec![[10.0, 10.0, 5.0], [90.0, 10.0, 5.0]]);
//! # Ok::<(), skyplan_world3::WorldError>(())
//! ```

use crate::{CollisionChecker, Neu};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use skyplan_world3::{distance_m, lerp, path_length_m};

/// Greedy vertex reduction: from each kept vertex, jump to the farthest later vertex it sees by
/// a free segment. Returns the path unchanged if nothing could be removed.
pub fn reduce_vertices(checker: &impl CollisionChecker, path: &[Neu]) -> Vec<Neu> {
    let mut out = dedup(path);
    if out.len() < 3 {
        return out;
    }
    let mut kept = vec![out[0]];
    let mut i = 0;
    while i + 1 < out.len() {
        let mut next = i + 1;
        for j in (i + 2..out.len()).rev() {
            let old_m = path_length_m(&out[i..=j]);
            if distance_m(out[i], out[j]) <= old_m && checker.segment_is_free(out[i], out[j]) {
                next = j;
                break;
            }
        }
        kept.push(out[next]);
        i = next;
    }
    if path_length_m(&kept) <= path_length_m(&out) {
        out = kept;
    }
    out
}

/// Random shortcuts: `attempts` times, pick two points along the path (by arc length) on
/// different segments and replace what lies between them by the straight segment if it is free
/// and shorter. Returns the new path and whether it changed.
pub fn random_shortcuts(
    checker: &impl CollisionChecker,
    path: &[Neu],
    rng: &mut ChaCha8Rng,
    attempts: usize,
) -> (Vec<Neu>, bool) {
    let mut path = dedup(path);
    let mut changed = false;
    for _ in 0..attempts {
        if path.len() < 3 {
            break;
        }
        let seg_count = path.len() - 1;
        let i = rng.random_range(0..seg_count);
        let j = rng.random_range(0..seg_count);
        let (i, j) = (i.min(j), i.max(j));
        if i == j {
            continue;
        }
        let (ti, tj): (f64, f64) = (rng.random(), rng.random());
        let a = lerp(path[i], path[i + 1], ti);
        let b = lerp(path[j], path[j + 1], tj);
        // New path: path[..=i], a, b, path[j+1..].
        let mut candidate: Vec<Neu> = path[..=i].to_vec();
        candidate.push(a);
        candidate.push(b);
        candidate.extend_from_slice(&path[j + 1..]);
        let candidate = dedup(&candidate);
        if path_length_m(&candidate) >= path_length_m(&path) {
            continue;
        }
        // Re-check the three new segments exactly (the outer two lie on old segments, but
        // rounding in `lerp` may move them off by an ulp).
        let free = checker.segment_is_free(path[i], a)
            && checker.segment_is_free(a, b)
            && checker.segment_is_free(b, path[j + 1]);
        if free {
            path = candidate;
            changed = true;
        }
    }
    (path, changed)
}

/// The passes in order: reduce vertices, then up to 8 rounds of random shortcuts + vertex
/// reduction while a round still gains more than 0.1 %. The result
/// is free wherever the input was (every new segment is checked), never longer, and keeps the
/// first and last points.
pub fn simplify(
    checker: &impl CollisionChecker,
    path: &[Neu],
    rng: &mut ChaCha8Rng,
    attempts: usize,
) -> Vec<Neu> {
    let mut out = reduce_vertices(checker, path);
    // Rounds of random shortcuts while they still shorten the path by more than 0.1 %.
    for _ in 0..8 {
        let before_m = path_length_m(&out);
        let (shortcut, changed) = random_shortcuts(checker, &out, rng, attempts);
        out = reduce_vertices(checker, &shortcut);
        if !changed || path_length_m(&out) > before_m * 0.999 {
            break;
        }
    }
    if path_length_m(&out) <= path_length_m(path) {
        out
    } else {
        path.to_vec()
    }
}

/// The path without consecutive repeated points.
fn dedup(path: &[Neu]) -> Vec<Neu> {
    let mut out: Vec<Neu> = Vec::with_capacity(path.len());
    for &p in path {
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    out
}

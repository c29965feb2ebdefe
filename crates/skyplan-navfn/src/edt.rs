//! The exact Euclidean distance transform of Felzenszwalb and Huttenlocher ("Distance Transforms
//! of Sampled Functions", 2012): two passes of a 1D lower-envelope-of-parabolas transform, linear
//! in the number of cells.

use skyplan_cspace::Grid2;

/// Stand-in for "no obstacle in this line" inside the transform (squared cells).
const FAR: f64 = 1e20;

/// For every cell, the Euclidean distance in cells from its centre to the centre of the nearest
/// blocked cell: 0 on obstacles, `f64::INFINITY` everywhere on a grid without obstacles. The
/// grid's border is not an obstacle. Exact: squared distances are integers, computed exactly.
///
/// ```
/// use skyplan_cspace::Grid2;
/// use skyplan_navfn::distance_transform;
/// let grid = Grid2::from_ascii("#...\n....\n....")?;
/// let d = distance_transform(&grid);
/// assert_eq!(d[0], 0.0);
/// assert_eq!(d[3], 3.0);                 // row 0, col 3
/// assert_eq!(d[2 * 4 + 3], 13f64.sqrt()); // row 2, col 3: √(2² + 3²)
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn distance_transform(grid: &Grid2) -> Vec<f64> {
    let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
    let mut squared: Vec<f64> = grid
        .blocked_cells()
        .iter()
        .map(|&b| if b { 0.0 } else { FAR })
        .collect();
    let longest = rows.max(cols);
    let mut scratch = Scratch::new(longest);
    // Columns first (along rows index), then rows.
    let mut line = vec![0.0; longest];
    for col in 0..cols {
        for row in 0..rows {
            line[row] = squared[row * cols + col];
        }
        scratch.transform(&line[..rows]);
        for row in 0..rows {
            squared[row * cols + col] = scratch.out[row];
        }
    }
    for row in 0..rows {
        let slice = &mut squared[row * cols..(row + 1) * cols];
        scratch.transform(slice);
        slice.copy_from_slice(&scratch.out[..cols]);
    }
    squared
        .into_iter()
        .map(|s| {
            if s >= FAR / 2.0 {
                f64::INFINITY
            } else {
                s.sqrt()
            }
        })
        .collect()
}

/// Buffers of the 1D transform.
struct Scratch {
    /// Locations of the parabolas in the lower envelope.
    v: Vec<usize>,
    /// Boundaries between them.
    z: Vec<f64>,
    /// The transformed line.
    out: Vec<f64>,
}

impl Scratch {
    fn new(n: usize) -> Self {
        Self {
            v: vec![0; n],
            z: vec![0.0; n + 1],
            out: vec![0.0; n],
        }
    }

    /// `out[q] = min_p (q − p)² + f[p]`.
    fn transform(&mut self, f: &[f64]) {
        let n = f.len();
        if n == 0 {
            return;
        }
        let (v, z) = (&mut self.v, &mut self.z);
        let mut k = 0usize;
        v[0] = 0;
        z[0] = f64::NEG_INFINITY;
        z[1] = f64::INFINITY;
        for q in 1..n {
            let qf = q as f64;
            loop {
                let p = v[k] as f64;
                let s = ((f[q] + qf * qf) - (f[v[k]] + p * p)) / (2.0 * qf - 2.0 * p);
                if s <= z[k] && k > 0 {
                    k -= 1;
                    continue;
                }
                if s <= z[k] {
                    // k == 0: the new parabola replaces the first one.
                    v[0] = q;
                    z[0] = f64::NEG_INFINITY;
                    z[1] = f64::INFINITY;
                } else {
                    k += 1;
                    v[k] = q;
                    z[k] = s;
                    z[k + 1] = f64::INFINITY;
                }
                break;
            }
        }
        k = 0;
        for q in 0..n {
            let qf = q as f64;
            while z[k + 1] < qf {
                k += 1;
            }
            let p = v[k] as f64;
            self.out[q] = (qf - p) * (qf - p) + f[v[k]];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use skyplan_cspace::GridFrame;

    fn brute(grid: &Grid2) -> Vec<f64> {
        (0..grid.len())
            .map(|i| {
                let a = grid.cell(i);
                (0..grid.len())
                    .filter(|&j| grid.blocked_cells()[j])
                    .map(|j| {
                        let b = grid.cell(j);
                        let dr = f64::from(a.row) - f64::from(b.row);
                        let dc = f64::from(a.col) - f64::from(b.col);
                        (dr * dr + dc * dc).sqrt()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]
        #[test]
        fn matches_brute_force(rows in 1u32..20, cols in 1u32..20, density in 0.0f64..0.5, seed in any::<u64>()) {
            // A simple LCG so that sparse and empty grids both occur.
            let mut state = seed | 1;
            let blocked: Vec<bool> = (0..rows * cols).map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 11) as f64 / (1u64 << 53) as f64) < density
            }).collect();
            let grid = Grid2::new(rows, cols, blocked, GridFrame::default()).unwrap();
            prop_assert_eq!(distance_transform(&grid), brute(&grid));
        }
    }
}

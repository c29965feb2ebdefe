//! Reproducible random workspaces.

use crate::ImageMapError;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_cspace::{Cell, Grid2, GridFrame};

/// A `rows × cols` grid whose cells are blocked independently with probability `density`,
/// reproducible from `seed` (ChaCha8) on every platform.
///
/// ```
/// let a = skyplan_imagemap::random_workspace(10, 20, 0.3, 7)?;
/// let b = skyplan_imagemap::random_workspace(10, 20, 0.3, 7)?;
/// assert_eq!(a, b);
/// assert_eq!((a.rows(), a.cols()), (10, 20));
/// # Ok::<(), skyplan_imagemap::ImageMapError>(())
/// ```
pub fn random_workspace(
    rows: u32,
    cols: u32,
    density: f64,
    seed: u64,
) -> Result<Grid2, ImageMapError> {
    if !(0.0..=1.0).contains(&density) {
        return Err(ImageMapError::BadParameter {
            name: "density",
            value: density,
            expected: "a probability in [0, 1]",
        });
    }
    if rows == 0 || cols == 0 {
        return Err(ImageMapError::BadParameter {
            name: "size",
            value: f64::from(rows.min(cols)),
            expected: "at least 1 × 1 cells",
        });
    }
    if u64::from(rows) * u64::from(cols) > skyplan_cspace::MAX_CELLS as u64 {
        return Err(skyplan_cspace::GridError::TooLarge {
            rows: rows.into(),
            cols: cols.into(),
        }
        .into());
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let blocked = (0..rows as usize * cols as usize)
        .map(|_| rng.random::<f64>() < density)
        .collect();
    Ok(Grid2::new(rows, cols, blocked, GridFrame::default())?)
}

/// Up to `count` distinct free cells of `grid` drawn uniformly, reproducible from `seed` (fewer
/// if the grid has fewer free cells).
///
/// ```
/// let grid = skyplan_imagemap::random_workspace(8, 8, 0.2, 1)?;
/// let cells = skyplan_imagemap::draw_free_cells(&grid, 2, 1);
/// assert_eq!(cells.len(), 2);
/// assert!(cells.iter().all(|&c| !grid.is_blocked(c)) && cells[0] != cells[1]);
/// # Ok::<(), skyplan_imagemap::ImageMapError>(())
/// ```
pub fn draw_free_cells(grid: &Grid2, count: usize, seed: u64) -> Vec<Cell> {
    let mut free: Vec<usize> = (0..grid.len())
        .filter(|&i| !grid.blocked_cells()[i])
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_ce11_5eed_ce11);
    let n = count.min(free.len());
    for k in 0..n {
        let j = rng.random_range(k..free.len());
        free.swap(k, j);
    }
    free[..n].iter().map(|&i| grid.cell(i)).collect()
}

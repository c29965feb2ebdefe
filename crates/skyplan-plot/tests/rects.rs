//! The merged rectangles cover exactly the blocked cells.

use skyplan_cspace::{Grid2, GridFrame};
use skyplan_plot::{CellRect, blocked_rects};

/// A small deterministic generator (no dependency needed).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
}

fn check_exact_cover(grid: &Grid2, rects: &[CellRect]) {
    let cols = grid.cols() as usize;
    let mut covered = vec![0_u8; grid.len()];
    for r in rects {
        assert!(r.rows >= 1 && r.cols >= 1, "{r:?}");
        assert!(
            r.row + r.rows <= grid.rows() && r.col + r.cols <= grid.cols(),
            "{r:?}"
        );
        for row in r.row..r.row + r.rows {
            for col in r.col..r.col + r.cols {
                covered[row as usize * cols + col as usize] += 1;
            }
        }
    }
    for (i, (&c, &b)) in covered.iter().zip(grid.blocked_cells()).enumerate() {
        assert_eq!(c, u8::from(b), "cell {i}: covered {c} times, blocked {b}");
    }
}

#[test]
fn random_grids_are_covered_exactly_once() {
    let mut rng = Lcg(7);
    for case in 0..200 {
        let rows = 1 + (rng.next() % 12) as u32;
        let cols = 1 + (rng.next() % 12) as u32;
        let density = rng.next() % 100;
        let mut blocked: Vec<bool> = (0..rows * cols)
            .map(|_| rng.next() % 100 < density)
            .collect();
        // Some grids with stacked identical runs, as buildings make.
        if case % 3 == 0 {
            for r in 1..rows as usize {
                if rng.next().is_multiple_of(2) {
                    let (prev, this) = blocked.split_at_mut(r * cols as usize);
                    this[..cols as usize].copy_from_slice(&prev[(r - 1) * cols as usize..]);
                }
            }
        }
        let grid = Grid2::new(rows, cols, blocked, GridFrame::default()).unwrap();
        check_exact_cover(&grid, &blocked_rects(&grid));
    }
}

#[test]
fn buildings_become_one_rectangle_each() {
    let grid = Grid2::from_ascii(
        "........\n\
         .###..#.\n\
         .###..#.\n\
         .###....\n\
         ......##",
    )
    .unwrap();
    let rects = blocked_rects(&grid);
    check_exact_cover(&grid, &rects);
    assert_eq!(
        rects,
        vec![
            CellRect {
                row: 1,
                col: 1,
                rows: 3,
                cols: 3
            },
            CellRect {
                row: 1,
                col: 6,
                rows: 2,
                cols: 1
            },
            CellRect {
                row: 4,
                col: 6,
                rows: 1,
                cols: 2
            },
        ]
    );
    let empty = Grid2::new(0, 5, vec![], GridFrame::default()).unwrap();
    assert!(blocked_rects(&empty).is_empty());
    let full = Grid2::new(300, 200, vec![true; 60_000], GridFrame::default()).unwrap();
    assert_eq!(
        blocked_rects(&full),
        vec![CellRect {
            row: 0,
            col: 0,
            rows: 300,
            cols: 200
        }]
    );
}

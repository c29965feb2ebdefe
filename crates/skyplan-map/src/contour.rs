//! Contour lines of a field sampled on a regular grid (marching squares), for drawing the
//! ground of a DEM as contours in a top view.

/// Heights sampled on a regular grid: `values[i * east_n + j]` at `origin_ne + (i, j) ·
/// step_m` (NaN where unknown).
#[derive(Debug, Clone, PartialEq)]
pub struct GroundGrid {
    /// North and east of sample (0, 0), metres.
    pub origin_ne: [f64; 2],
    /// Spacing of the samples, metres.
    pub step_m: f64,
    /// Samples along north.
    pub north_n: usize,
    /// Samples along east.
    pub east_n: usize,
    /// Row-major heights (rows run north), metres.
    pub values: Vec<f64>,
}

/// The line segments, `[[north, east]; 2]` in metres, where the bilinear surface through the
/// grid's samples crosses `level` (marching squares; a saddle cell is split by its centre's
/// value). Cells with an unknown corner are left out.
///
/// ```
/// use skyplan_map::contour::{GroundGrid, contour_segments};
/// // A plane rising to the east, 1 m per metre: the 2.5 m contour is the line east = 2.5.
/// let values = (0..5 * 5).map(|k| (k % 5) as f64).collect();
/// let g = GroundGrid { origin_ne: [0.0, 0.0], step_m: 1.0, north_n: 5, east_n: 5, values };
/// let segs = contour_segments(&g, 2.5);
/// assert_eq!(segs.len(), 4);
/// assert!(segs.iter().flatten().all(|p| (p[1] - 2.5).abs() < 1e-12));
/// ```
pub fn contour_segments(g: &GroundGrid, level: f64) -> Vec<[[f64; 2]; 2]> {
    let mut out = Vec::new();
    if g.north_n < 2 || g.east_n < 2 || g.values.len() < g.north_n * g.east_n {
        return out;
    }
    let at = |i: usize, j: usize| g.values[i * g.east_n + j];
    let pos = |i: f64, j: f64| [g.origin_ne[0] + i * g.step_m, g.origin_ne[1] + j * g.step_m];
    for i in 0..g.north_n - 1 {
        for j in 0..g.east_n - 1 {
            // Corners counter-clockwise from (i, j): their grid coordinates and values.
            let c = [(i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j)];
            let v = c.map(|(a, b)| at(a, b));
            if v.iter().any(|x| !x.is_finite()) {
                continue;
            }
            // Where the level crosses each edge k (corner k to corner k + 1).
            let mut cross: [Option<[f64; 2]>; 4] = [None; 4];
            for k in 0..4 {
                let (p, q) = (v[k], v[(k + 1) % 4]);
                if (p < level) != (q < level) {
                    let t = (level - p) / (q - p);
                    let (a, b) = (c[k], c[(k + 1) % 4]);
                    cross[k] = Some(pos(
                        a.0 as f64 + (b.0 as f64 - a.0 as f64) * t,
                        a.1 as f64 + (b.1 as f64 - a.1 as f64) * t,
                    ));
                }
            }
            let hits: Vec<(usize, [f64; 2])> = cross
                .iter()
                .enumerate()
                .filter_map(|(k, x)| x.map(|p| (k, p)))
                .collect();
            match hits.len() {
                2 => out.push([hits[0].1, hits[1].1]),
                4 => {
                    // A saddle: pair the crossings so the centre's side stays connected.
                    let centre = v.iter().sum::<f64>() / 4.0;
                    let low_first = v[0] < level;
                    // Corners 0 and 2 on one side, 1 and 3 on the other: if the centre is on
                    // corner 0's side, 0 and 2 join through it and the contour cuts off
                    // corners 1 (edges 0, 1) and 3 (edges 2, 3); else it cuts off 0 and 2.
                    let pairs = if (centre < level) == low_first {
                        [(0, 1), (2, 3)]
                    } else {
                        [(3, 0), (1, 2)]
                    };
                    for (a, b) in pairs {
                        if let (Some(p), Some(q)) = (cross[a], cross[b]) {
                            out.push([p, q]);
                        }
                    }
                }
                _ => {}
            }
        }
    }
    out
}

/// Contour levels over heights `lo..=hi`: about `count` of them, on a 1-2-5 step; returns the
/// step and the levels (none if the range is empty or not finite).
///
/// ```
/// let (step, levels) = skyplan_map::contour::contour_levels(-147.0, 304.0, 12.0);
/// assert_eq!(step, 50.0);
/// assert_eq!(levels, [-100.0, -50.0, 0.0, 50.0, 100.0, 150.0, 200.0, 250.0, 300.0]);
/// ```
pub fn contour_levels(lo: f64, hi: f64, count: f64) -> (f64, Vec<f64>) {
    if !(lo.is_finite() && hi.is_finite() && hi > lo && count > 0.0) {
        return (0.0, Vec::new());
    }
    let raw = (hi - lo) / count;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * p);
    let mut levels = Vec::new();
    let mut k = (lo / step).ceil();
    while k * step <= hi {
        let v = k * step;
        levels.push(if v == 0.0 { 0.0 } else { v });
        k += 1.0;
    }
    (step, levels)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cone: every contour point lies on its circle, and the circle is closed (each end
    /// shared by two segments).
    #[test]
    fn cone_contours_are_circles() {
        let n = 81;
        let values = (0..n * n)
            .map(|k| {
                let (i, j) = ((k / n) as f64 - 40.0, (k % n) as f64 - 40.0);
                100.0 - i.hypot(j)
            })
            .collect();
        let g = GroundGrid {
            origin_ne: [-40.0, -40.0],
            step_m: 1.0,
            north_n: n,
            east_n: n,
            values,
        };
        for level in [70.5, 85.25, 99.0] {
            let segs = contour_segments(&g, level);
            assert!(!segs.is_empty());
            let r = 100.0 - level;
            for p in segs.iter().flatten() {
                // Linear interpolation along cell edges: within a small fraction of a cell.
                assert!((p[0].hypot(p[1]) - r).abs() < 0.1, "{p:?} off radius {r}");
            }
            let mut ends: Vec<[i64; 2]> = segs
                .iter()
                .flatten()
                .map(|p| p.map(|x| (x * 1e6).round() as i64))
                .collect();
            ends.sort();
            for w in ends.chunks(2) {
                assert_eq!(w[0], w[1], "an open end at {:?}", w[0]);
            }
        }
        // Levels off the field give nothing.
        assert!(contour_segments(&g, 150.0).is_empty());
    }

    /// A saddle cell: the centre's side stays connected.
    #[test]
    fn saddles_join_through_the_centre() {
        // Corners 0 and 2 high, 1 and 3 low; centre high (mean 1.25 > level 1).
        let g = GroundGrid {
            origin_ne: [0.0, 0.0],
            step_m: 1.0,
            north_n: 2,
            east_n: 2,
            values: vec![2.0, 0.0, 0.5, 2.5],
        };
        let segs = contour_segments(&g, 1.0);
        assert_eq!(segs.len(), 2);
        // Each segment cuts off one low corner: (0, 1) at east 1 and (1, 0) at north 1.
        for s in &segs {
            let near_01 = s.iter().all(|p| p[0] <= 0.5 + 1e-9 || p[1] >= 0.5 - 1e-9)
                && s.iter().any(|p| p[1] > 0.5);
            let near_10 = s.iter().all(|p| p[0] >= 0.5 - 1e-9 || p[1] <= 0.5 + 1e-9)
                && s.iter().any(|p| p[0] > 0.5);
            assert!(near_01 || near_10, "{s:?}");
        }
        // NaN corners leave the cell out.
        let holed = GroundGrid {
            values: vec![2.0, f64::NAN, 0.5, 2.5],
            ..g
        };
        assert!(contour_segments(&holed, 1.0).is_empty());
    }
}

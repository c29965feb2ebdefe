//! Heat maps of a scalar field over a grid (a cost map, a distance or cost-to-go field) with a
//! route, as PNG bytes drawn pixel by pixel: NORTH up, EAST right, one square per cell.

use crate::PlotError;
use skyplan_cspace::Cell;

/// What a heat map shows. `values` and `blocked` are row-major with row 0 the SOUTHERN row.
#[derive(Debug, Clone)]
pub struct Heatmap<'a> {
    /// Rows (north extent).
    pub rows: u32,
    /// Columns (east extent).
    pub cols: u32,
    /// One value per cell; non-finite values (unreachable cells) are drawn light grey.
    pub values: &'a [f64],
    /// Obstacles, drawn black.
    pub blocked: &'a [bool],
    /// The route, drawn as a white line through cell centres.
    pub path: &'a [Cell],
    /// Start cell (green square).
    pub start: Option<Cell>,
    /// Goal cell (red square).
    pub goal: Option<Cell>,
}

/// Finite values scaled linearly to `0..=255` (smallest → 0, largest → 255); `None` for
/// non-finite values.
///
/// ```
/// let n = skyplan_plot::normalise_0_255(&[2.0, 4.0, 6.0, f64::INFINITY]);
/// assert_eq!(n, vec![Some(0), Some(128), Some(255), None]);
/// ```
pub fn normalise_0_255(values: &[f64]) -> Vec<Option<u8>> {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let span = hi - lo;
    values
        .iter()
        .map(|&v| {
            v.is_finite().then(|| {
                if span > 0.0 {
                    (255.0 * (v - lo) / span).round() as u8
                } else {
                    0
                }
            })
        })
        .collect()
}

/// Viridis, sampled at five points and interpolated linearly: dark blue (low) to yellow (high).
fn viridis(level: u8) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = f64::from(level) / 255.0 * 4.0;
    let k = (t.floor() as usize).min(3);
    let f = t - k as f64;
    let mut out = [0u8; 3];
    for (c, o) in out.iter_mut().enumerate() {
        *o = (STOPS[k][c] + f * (STOPS[k + 1][c] - STOPS[k][c])).round() as u8;
    }
    out
}

const OBSTACLE: [u8; 3] = [0, 0, 0];
const NO_VALUE: [u8; 3] = [200, 200, 200];
const ROUTE: [u8; 3] = [255, 255, 255];
const START: [u8; 3] = [0, 200, 0];
const GOAL: [u8; 3] = [230, 0, 0];

/// Renders a heat map whose longer edge is about `max_edge_px` pixels (at least one pixel per
/// cell; a grid larger than that is sampled at pixel centres), as PNG bytes.
///
/// ```
/// use skyplan_cspace::Cell;
/// use skyplan_plot::{render_heatmap_png, Heatmap};
/// let values = [0.0, 1.0, 2.0, 1.0, f64::INFINITY, 3.0];
/// let blocked = [false, false, false, false, true, false];
/// let map = Heatmap { rows: 2, cols: 3, values: &values, blocked: &blocked,
///     path: &[Cell::new(0, 0), Cell::new(0, 1)], start: Some(Cell::new(0, 0)), goal: None };
/// let png = render_heatmap_png(&map, 300)?;
/// assert_eq!(&png[1..4], b"PNG");
/// # Ok::<(), skyplan_plot::PlotError>(())
/// ```
pub fn render_heatmap_png(map: &Heatmap<'_>, max_edge_px: u32) -> Result<Vec<u8>, PlotError> {
    let n = map.rows as usize * map.cols as usize;
    if n == 0 || map.values.len() != n || map.blocked.len() != n {
        return Err(PlotError::BadScene {
            what: "a heat map needs one value and one obstacle flag per cell of a non-empty grid",
        });
    }
    let max_edge_px = max_edge_px.clamp(crate::MIN_SIZE_PX, crate::MAX_SIZE_PX);
    let long_cells = map.rows.max(map.cols);
    // Pixels per cell (≥ 1 when the grid is small), or cells per pixel when it is large.
    let px_per_cell = (f64::from(max_edge_px) / f64::from(long_cells)).clamp(1e-9, 64.0);
    let px_per_cell = if px_per_cell >= 1.0 {
        px_per_cell.floor()
    } else {
        px_per_cell
    };
    let width = ((f64::from(map.cols) * px_per_cell).round() as u32).max(1);
    let height = ((f64::from(map.rows) * px_per_cell).round() as u32).max(1);
    let levels = normalise_0_255(map.values);
    let mut rgb = vec![0u8; width as usize * height as usize * 3];
    for py in 0..height {
        // Image rows go down, grid rows go north: the top pixel row is the northern edge.
        let row = ((f64::from(height - 1 - py) + 0.5) / px_per_cell) as usize;
        let row = row.min(map.rows as usize - 1);
        for px in 0..width {
            let col = (((f64::from(px) + 0.5) / px_per_cell) as usize).min(map.cols as usize - 1);
            let i = row * map.cols as usize + col;
            let color = if map.blocked[i] {
                OBSTACLE
            } else {
                levels[i].map_or(NO_VALUE, viridis)
            };
            let o = (py as usize * width as usize + px as usize) * 3;
            rgb[o..o + 3].copy_from_slice(&color);
        }
    }
    let to_px = |c: Cell| {
        (
            (f64::from(c.col) + 0.5) * px_per_cell,
            f64::from(height) - (f64::from(c.row) + 0.5) * px_per_cell,
        )
    };
    let radius = (px_per_cell * 0.2).clamp(1.0, 4.0);
    let mut paint = |x: f64, y: f64, r: f64, color: [u8; 3]| {
        let (x0, x1) = ((x - r).floor().max(0.0) as i64, (x + r).ceil() as i64);
        let (y0, y1) = ((y - r).floor().max(0.0) as i64, (y + r).ceil() as i64);
        for yy in y0..y1.min(i64::from(height)) {
            for xx in x0..x1.min(i64::from(width)) {
                let (dx, dy) = (xx as f64 + 0.5 - x, yy as f64 + 0.5 - y);
                if dx * dx + dy * dy <= r * r {
                    let o = (yy as usize * width as usize + xx as usize) * 3;
                    rgb[o..o + 3].copy_from_slice(&color);
                }
            }
        }
    };
    for w in map.path.windows(2) {
        let ((ax, ay), (bx, by)) = (to_px(w[0]), to_px(w[1]));
        let steps = ((bx - ax).hypot(by - ay) * 2.0).ceil().max(1.0) as usize;
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            paint(ax + t * (bx - ax), ay + t * (by - ay), radius, ROUTE);
        }
    }
    let marker = (px_per_cell * 0.8).max(6.0);
    if let Some(c) = map.start {
        let (x, y) = to_px(c);
        paint(x, y, marker, START);
    }
    if let Some(c) = map.goal {
        let (x, y) = to_px(c);
        paint(x, y, marker, GOAL);
    }
    encode_rgb_png(&rgb, width, height)
}

fn encode_rgb_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>, PlotError> {
    let mut out = Vec::with_capacity(rgb.len() / 8);
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let enc_err = |e: png::EncodingError| PlotError::Encode(e.to_string());
    let mut writer = encoder.write_header().map_err(enc_err)?;
    writer.write_image_data(rgb).map_err(enc_err)?;
    writer.finish().map_err(enc_err)?;
    Ok(out)
}

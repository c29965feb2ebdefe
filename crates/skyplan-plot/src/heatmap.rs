//! Heat maps of a scalar field over a grid (a cost map, a distance or cost-to-go field) with a
//! route, as PNG bytes, in the frame of the plan picture: title, NORTH/EAST axes in metres with
//! ticks, and a legend holding the colour scale (its caption says what is measured, in which
//! units), the obstacles, the route, the start and the goal.

use crate::draw::draw;
use crate::layout::{LegendEntry, LegendKind, layout_with};
use crate::text::TextMode;
use crate::{PlotError, Scene};
use plotters::prelude::*;
use skyplan_cspace::{Cell, Grid2};

/// What a heat map shows. `values` is row-major with row 0 the SOUTHERN row, one per cell of
/// `grid` (whose frame places the cells in metres and whose blocked cells are drawn black).
#[derive(Debug, Clone)]
pub struct Heatmap<'a> {
    /// Title above the plot.
    pub title: String,
    /// The grid: its frame (metres) and its blocked cells.
    pub grid: &'a Grid2,
    /// One value per cell; non-finite values (unreachable cells) are drawn light grey.
    pub values: &'a [f64],
    /// What the colours measure, with units, for the colour scale: `"distance to goal (m)"`.
    pub measure: &'a str,
    /// The route, through cell centres.
    pub path: &'a [Cell],
    /// Start cell.
    pub start: Option<Cell>,
    /// Goal cell.
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
pub(crate) fn viridis(level: u8) -> [u8; 3] {
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

/// Levels shown in the colour scale, highest first.
const SCALE_LEVELS: [u8; 6] = [255, 204, 153, 102, 51, 0];

/// The legend entries of the colour scale: its caption, a swatch per level labelled with its
/// value, and "no value" when some cells have none.
fn scale_entries(values: &[f64], measure: &str) -> Vec<LegendEntry> {
    let (lo, hi) = values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let mut v = vec![LegendEntry {
        kind: LegendKind::Caption,
        text: measure.to_string(),
    }];
    if lo <= hi {
        let decimals = if hi - lo >= 20.0 { 0 } else { 2 };
        let levels: &[u8] = if hi > lo { &SCALE_LEVELS } else { &[0] };
        v.extend(levels.iter().map(|&level| LegendEntry {
            kind: LegendKind::Heat(level),
            text: format!("{:.decimals$}", lo + f64::from(level) / 255.0 * (hi - lo)),
        }));
    }
    if values.iter().any(|v| !v.is_finite()) {
        v.push(LegendEntry {
            kind: LegendKind::NoValue,
            text: "no value (unreachable)".into(),
        });
    }
    v
}

/// Renders a heat map as a PNG `edge_px` pixels high and 1.25 times as wide (the legend with
/// the colour scale beside the plot; edges clamped to
/// [`MIN_SIZE_PX`](crate::MIN_SIZE_PX)..=[`MAX_SIZE_PX`](crate::MAX_SIZE_PX)), framed as the plan
/// picture is.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_plot::{render_heatmap_png, Heatmap};
/// let grid = Grid2::from_ascii("...\n.#.")?;
/// let values = [0.0, 1.0, 2.0, 1.0, f64::INFINITY, 3.0];
/// let map = Heatmap { title: "field".into(), grid: &grid, values: &values,
///     measure: "distance (cells)", path: &[Cell::new(0, 0), Cell::new(0, 1)],
///     start: Some(Cell::new(0, 0)), goal: None };
/// let png = render_heatmap_png(&map, 300)?;
/// assert_eq!(&png[1..4], b"PNG");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn render_heatmap_png(map: &Heatmap<'_>, edge_px: u32) -> Result<Vec<u8>, PlotError> {
    let grid = map.grid;
    if grid.is_empty() || map.values.len() != grid.len() {
        return Err(PlotError::BadScene {
            what: "a heat map needs one value per cell of a non-empty grid",
        });
    }
    let centre = |c: Cell| grid.center_ne(c);
    let path_ne: Vec<(f64, f64)> = map.path.iter().map(|&c| centre(c)).collect();
    let scene = Scene {
        title: map.title.clone(),
        grid,
        raw_path_ne: &path_ne,
        start_ne: map.start.map(centre),
        goal_ne: map.goal.map(centre),
        ..Scene::of_grid(grid)
    };
    let height = edge_px.clamp(crate::MIN_SIZE_PX, crate::MAX_SIZE_PX);
    let width = (height + height / 4).min(crate::MAX_SIZE_PX);
    let layout = layout_with(
        &scene,
        width,
        height,
        Some(scale_entries(map.values, map.measure)),
    )?;
    let levels = normalise_0_255(map.values);
    let mut rgb = vec![255_u8; width as usize * height as usize * 3];
    {
        let backend = BitMapBackend::<plotters::backend::RGBPixel>::with_buffer_and_format(
            &mut rgb,
            (width, height),
        )
        .map_err(|e| PlotError::Draw(e.to_string()))?;
        let root = backend.into_drawing_area();
        draw(
            &root,
            &scene,
            &layout,
            TextMode::Glyphs,
            Some(&levels),
            None,
        )?;
        root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
    }
    encode_rgb_png(&rgb, width, height)
}

/// 8-bit RGB pixels as PNG bytes.
pub(crate) fn encode_rgb_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>, PlotError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    /// The picture is drawn where the plan picture's layout puts it: each cell's colour at the
    /// pixel `pixel_of_ne` gives for its centre, in metres of the grid's frame, with the colour
    /// scale, obstacles, route, start and goal in the legend.
    #[test]
    fn cells_are_where_the_axes_say_with_their_scale_colour() {
        // 4 × 6 cells of 2 m, origin (north 100, east 50); one blocked cell at row 1, col 2.
        let mut blocked = vec![false; 24];
        blocked[6 + 2] = true;
        let frame = skyplan_cspace::GridFrame {
            origin_north_m: 100.0,
            origin_east_m: 50.0,
            cell_m: 2.0,
        };
        let grid = Grid2::new(4, 6, blocked, frame).unwrap();
        let values: Vec<f64> = (0..24)
            .map(|i| if i == 23 { f64::INFINITY } else { f64::from(i) })
            .collect();
        let map = Heatmap {
            title: "test field".into(),
            grid: &grid,
            values: &values,
            measure: "distance (cells)",
            path: &[Cell::new(0, 0), Cell::new(0, 1)],
            start: Some(Cell::new(0, 0)),
            goal: Some(Cell::new(3, 0)),
        };
        let (w, h, rgb) = decode(&render_heatmap_png(&map, 800).unwrap());
        assert_eq!((w, h), (1000, 800));
        let scene = Scene {
            title: map.title.clone(),
            raw_path_ne: &[(101.0, 51.0), (101.0, 53.0)],
            start_ne: Some((101.0, 51.0)),
            goal_ne: Some((107.0, 51.0)),
            ..Scene::of_grid(&grid)
        };
        let entries = scale_entries(&values, map.measure);
        let l = layout_with(&scene, w, h, Some(entries.clone())).unwrap();
        // Axes in metres of the frame.
        assert_eq!(l.east_range_m().0, 50.0);
        assert_eq!(l.north_range_m().0, 100.0);
        let at = |north: f64, east: f64| {
            let (x, y) = l.pixel_of_ne(north, east);
            let i = (y as usize * w as usize + x as usize) * 3;
            [rgb[i], rgb[i + 1], rgb[i + 2]]
        };
        // Row 1, col 2 (north 103, east 55) is blocked: black.
        assert_eq!(at(103.0, 55.0), [0, 0, 0]);
        // Row 2, col 4 holds value 16 of 0..=22: level round(255 · 16 / 22) = 185.
        assert_eq!(at(105.0, 59.0), viridis(185));
        // Row 3, col 3 (value 21 → 243) and the unreachable last cell (grey).
        assert_eq!(at(107.0, 57.0), viridis(243));
        assert_eq!(at(107.0, 61.0), [200, 200, 200]);
        // The colour scale: its caption, six levels from 22 down to 0 (a span ≥ 20: whole
        // numbers), "no value".
        let texts: Vec<&str> = entries.iter().map(|e| e.text.as_str()).collect();
        assert_eq!(
            texts,
            [
                "distance (cells)",
                "22",
                "18",
                "13",
                "9",
                "4",
                "0",
                "no value (unreachable)"
            ]
        );
        // The legend also names the obstacles (drawn black), the route, start and goal.
        let kinds: Vec<LegendKind> = l.legend.entries.iter().map(|e| e.kind).collect();
        for k in [
            LegendKind::HeatBlocked,
            LegendKind::Raw,
            LegendKind::Start,
            LegendKind::Goal,
            LegendKind::Caption,
        ] {
            assert!(kinds.contains(&k), "{k:?} missing from {kinds:?}");
        }
    }
}

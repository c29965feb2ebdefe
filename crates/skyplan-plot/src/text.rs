//! Text: the embedded font, measuring, and labels placed by their baseline.
//!
//! plotters' `ab_glyph` rasteriser draws every glyph from the pen position without its left side
//! bearing, so whole strings come out unevenly spaced ("obstacl e"). For raster output each glyph
//! is therefore drawn on its own, moved right by its bearing read from the font's `hmtx` table.
//! SVG output keeps whole strings and lets the viewer lay them out.

use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::register_font;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::PlotError;

/// Family under which the embedded DejaVu Sans is registered with plotters.
pub(crate) const FAMILY: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

/// Height of capitals and digits, as a fraction of the plotters font size
/// (DejaVu Sans: 1493 units of the 2384-unit ascent + descent that ab_glyph scales to the size).
pub(crate) const CAP: f64 = 1493.0 / 2384.0;
/// Depth of descenders, as a fraction of the font size.
pub(crate) const DESCENT: f64 = 483.0 / 2384.0;

/// Registers the font once; later calls are free.
pub(crate) fn ensure_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok =
        *REGISTERED.get_or_init(|| register_font(FAMILY, FontStyle::Normal, FONT_BYTES).is_ok());
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// Sub-pixel precision of measurements: text is measured at this many times its size.
const FINE: f64 = 16.0;

/// Advance width of a string at `size`, pixels (fractional).
pub(crate) fn text_width(text: &str, size: f64) -> f64 {
    let fine = (FAMILY, size * FINE)
        .into_font()
        .box_size(text)
        .map(|(w, _)| f64::from(w));
    fine.unwrap_or(text.chars().count() as f64 * 0.6 * size * FINE) / FINE
}

/// How text reaches the backend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TextMode {
    /// Whole strings (SVG: the viewer lays them out).
    Strings,
    /// One glyph at a time with its side bearing (raster backends).
    Glyphs,
}

/// Vertical placement of a label relative to its anchor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum VAlign {
    /// The tops of capitals at the anchor.
    Top,
    /// Capitals centred on the anchor.
    Middle,
    /// The baseline at the anchor.
    Baseline,
}

/// One line of text.
pub(crate) struct Label<'a> {
    pub text: &'a str,
    pub size: f64,
    pub at: (i32, i32),
    pub h: HPos,
    pub v: VAlign,
    /// Rotated to read bottom to top (the anchor's `h` then runs along the vertical).
    pub vertical: bool,
}

/// An axis tick from `from` to `to` in `color`, and its value `text` anchored at `at` by `anchor`.
pub(crate) fn draw_tick<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    mode: TextMode,
    ([from, to, at], color): ([(i32, i32); 3], RGBColor),
    (text, size): (&str, f64),
    (h, v): (HPos, VAlign),
) -> Result<(), PlotError> {
    root.draw(&PathElement::new(vec![from, to], color))
        .map_err(|e| PlotError::Draw(e.to_string()))?;
    let label = Label {
        text,
        size,
        at,
        h,
        v,
        vertical: false,
    };
    draw_label(root, mode, &label)
}

/// Draws a label on the whole-picture area.
pub(crate) fn draw_label<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    mode: TextMode,
    label: &Label,
) -> Result<(), PlotError> {
    let size = label.size;
    // Distance from the anchor to the baseline, across the text direction.
    let to_baseline = match label.v {
        VAlign::Top => CAP * size,
        VAlign::Middle => 0.5 * CAP * size,
        VAlign::Baseline => 0.0,
    };
    let (ax, ay) = (f64::from(label.at.0), f64::from(label.at.1));
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::Draw(e.to_string());
    match mode {
        TextMode::Strings => {
            // plotters' SVG writes `font-size` = size / 1.24 and puts the baseline 0.76 em below a
            // top-anchored point. Scale the size so that the em matches the raster one
            // (DejaVu: 2048 of the 2384 units that ab_glyph fits into the size).
            let em = size * 2048.0 / 2384.0;
            let top_to_baseline = 0.76 * em;
            let base = TextStyle::from((FAMILY, em * 1.24).into_font())
                .color(&BLACK)
                .pos(Pos::new(label.h, VPos::Top));
            let (style, at) = if label.vertical {
                let x = ax + to_baseline - top_to_baseline;
                (base.transform(FontTransform::Rotate270), (x, ay))
            } else {
                (base, (ax, ay + to_baseline - top_to_baseline))
            };
            let at = (at.0.round() as i32, at.1.round() as i32);
            root.draw(&Text::new(label.text.to_string(), at, style))
                .map_err(err)
        }
        TextMode::Glyphs => {
            let width = text_width(label.text, size);
            let start = match label.h {
                HPos::Left => 0.0,
                HPos::Center => -0.5 * width,
                HPos::Right => -width,
            };
            // plotters' rasteriser puts the baseline half a size below a top-left anchor.
            let half = 0.5 * size;
            let style = TextStyle::from((FAMILY, size).into_font())
                .color(&BLACK)
                .pos(Pos::new(HPos::Left, VPos::Top));
            let style = if label.vertical {
                style.transform(FontTransform::Rotate270)
            } else {
                style
            };
            let metrics = metrics();
            let mut prefix = String::with_capacity(label.text.len());
            for c in label.text.chars() {
                let pen = text_width(&prefix, size);
                prefix.push(c);
                if c.is_whitespace() {
                    continue;
                }
                let bearing = metrics
                    .map_or(0.0, |m| m.lsb_units(c) * size / m.height_units)
                    .floor();
                let along = (start + pen).round() + bearing;
                let at = if label.vertical {
                    (ax + to_baseline - half, ay - along)
                } else {
                    (ax + along, ay + to_baseline - half)
                };
                let at = (at.0.round() as i32, at.1.round() as i32);
                root.draw(&Text::new(c.to_string(), at, style.clone()))
                    .map_err(err)?;
            }
            Ok(())
        }
    }
}

/// The few TrueType tables needed for left side bearings.
struct Metrics {
    data: &'static [u8],
    /// Ascent − descent in font units: ab_glyph scales this to the font size.
    height_units: f64,
    hmtx: usize,
    n_hmetrics: usize,
    /// Offset of the format-4 `cmap` subtable.
    cmap4: usize,
}

fn metrics() -> Option<&'static Metrics> {
    static METRICS: OnceLock<Option<Metrics>> = OnceLock::new();
    METRICS.get_or_init(|| Metrics::parse(FONT_BYTES)).as_ref()
}

fn u16_at(d: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes([*d.get(at)?, *d.get(at + 1)?]))
}

fn u32_at(d: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes([
        *d.get(at)?,
        *d.get(at + 1)?,
        *d.get(at + 2)?,
        *d.get(at + 3)?,
    ]))
}

impl Metrics {
    fn parse(data: &'static [u8]) -> Option<Self> {
        let n_tables = usize::from(u16_at(data, 4)?);
        let table = |tag: &[u8; 4]| -> Option<usize> {
            (0..n_tables)
                .map(|i| 12 + 16 * i)
                .find(|&rec| data.get(rec..rec + 4) == Some(tag))
                .and_then(|rec| {
                    let off = u32_at(data, rec + 8)?;
                    usize::try_from(off).ok()
                })
        };
        let hhea = table(b"hhea")?;
        let ascent = f64::from(u16_at(data, hhea + 4)? as i16);
        let descent = f64::from(u16_at(data, hhea + 6)? as i16);
        let n_hmetrics = usize::from(u16_at(data, hhea + 34)?);
        let hmtx = table(b"hmtx")?;
        let cmap = table(b"cmap")?;
        let n_sub = usize::from(u16_at(data, cmap + 2)?);
        let cmap4 = (0..n_sub).find_map(|i| {
            let rec = cmap + 4 + 8 * i;
            let (platform, encoding) = (u16_at(data, rec)?, u16_at(data, rec + 2)?);
            let sub = cmap + usize::try_from(u32_at(data, rec + 4)?).ok()?;
            let unicode = (platform == 3 && encoding == 1) || platform == 0;
            (unicode && u16_at(data, sub)? == 4).then_some(sub)
        })?;
        Some(Self {
            data,
            height_units: ascent - descent,
            hmtx,
            n_hmetrics,
            cmap4,
        })
    }

    /// Glyph id of a character (0 when the font lacks it).
    fn glyph(&self, c: char) -> u16 {
        let Ok(c) = u16::try_from(u32::from(c)) else {
            return 0;
        };
        let (d, sub) = (self.data, self.cmap4);
        let lookup = || -> Option<u16> {
            let seg_x2 = usize::from(u16_at(d, sub + 6)?);
            let ends = sub + 14;
            let starts = ends + seg_x2 + 2;
            let deltas = starts + seg_x2;
            let ranges = deltas + seg_x2;
            let seg =
                (0..seg_x2 / 2).find(|&i| u16_at(d, ends + 2 * i).is_some_and(|end| c <= end))?;
            let start = u16_at(d, starts + 2 * seg)?;
            if c < start {
                return None;
            }
            let delta = u16_at(d, deltas + 2 * seg)?;
            let range = usize::from(u16_at(d, ranges + 2 * seg)?);
            if range == 0 {
                return Some(c.wrapping_add(delta));
            }
            let g = u16_at(d, ranges + 2 * seg + range + 2 * usize::from(c - start))?;
            (g != 0).then(|| g.wrapping_add(delta))
        };
        lookup().unwrap_or(0)
    }

    /// Left side bearing of a character, font units.
    fn lsb_units(&self, c: char) -> f64 {
        let g = usize::from(self.glyph(c));
        let at = if g < self.n_hmetrics {
            self.hmtx + 4 * g + 2
        } else {
            self.hmtx + 4 * self.n_hmetrics + 2 * (g - self.n_hmetrics)
        };
        u16_at(self.data, at).map_or(0.0, |v| f64::from(v as i16))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_dejavu_metrics() {
        let m = metrics().expect("font tables");
        assert_eq!(m.height_units, 2384.0);
        // DejaVu Sans: 'l' and '.' have wide bearings, 'A' almost none.
        assert_eq!(m.lsb_units('l'), 193.0);
        assert_eq!(m.lsb_units('.'), 219.0);
        assert_eq!(m.lsb_units('A'), 16.0);
        assert_eq!(m.glyph('\u{10000}'), 0);
    }
}

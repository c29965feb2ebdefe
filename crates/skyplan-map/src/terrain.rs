//! Terrain: digital elevation models (DEMs) read from bytes, and routes that keep a height
//! above the ground.
//!
//! * [`parse_dem`] reads a GeoTIFF (one band of elevations in metres, placed by its
//!   `ModelPixelScale`/`ModelTiepoint` tags in WGS84 longitude/latitude, EPSG:4326, or in a WGS84
//!   UTM zone, EPSG:326xx/327xx) or an SRTM `.hgt` tile (placed by its name, `N37W122.hgt`). What
//!   cannot be placed exactly (another datum or projection, a rotated raster) is refused.
//! * A [`Dem`] gives the ground's height above mean sea level anywhere it covers, by bilinear
//!   interpolation between its samples (each sample is the height at its pixel's centre, as GDAL
//!   and rasterio read them).
//! * A [`Terrain`] is a DEM placed about a map's home: heights above the ground under home, and
//!   [`Terrain::follow`], which lifts a horizontal route to keep at least a given height above the
//!   ground everywhere along it (not only at the waypoints), climbing and descending no steeper
//!   than the vehicle can.
//!
//! The guarantee rests on one bound: on each stretch of route (at most half a DEM pixel long),
//! the highest the bilinear ground reaches, found exactly (along a line inside one pixel cell the
//! surface is a quadratic). The route is lifted above those bounds, and
//! [`Terrain::check_clearance`] re-checks the lifted route against them.
//!
//! ```
//! use skyplan_frames::{LocalFrame, Lla};
//! use skyplan_map::terrain::{Dem, Terrain};
//! // A 3 × 3 tile of 1° × 1° … here 0.01° pixels rising 10 m per pixel eastwards.
//! let dem = Dem::geographic(3, 3, vec![0.0, 10.0, 20.0, 0.0, 10.0, 20.0, 0.0, 10.0, 20.0],
//!                           [-122.41, 37.81], [0.01, 0.01])?;
//! assert!((dem.elevation_amsl_m(37.80, -122.395)? - 15.0).abs() < 1e-9);
//! let frame = LocalFrame::new(Lla { lat_deg: 37.80, lon_deg: -122.40, alt_m: 0.0 })?;
//! let terrain = Terrain::new(dem, frame)?;
//! assert!((terrain.home_ground_amsl_m() - 10.0).abs() < 1e-6);
//! // 300 m east and back, 30 m above the ground.
//! let route = terrain.follow(&[[0.0, 0.0], [0.0, 300.0]], 30.0, [0.3, 0.15])?;
//! terrain.check_clearance(&route, 30.0)?;
//! assert!(route.last().unwrap()[2] > 30.0); // the ground rose towards the east
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use skyplan_frames::{FrameError, Lla, LocalFrame, Ned};

/// Most samples a DEM may hold (100 million: 400 MB as 32-bit floats).
pub const MAX_DEM_SAMPLES: u64 = 100_000_000;

/// Largest DEM file read, bytes: [`MAX_DEM_SAMPLES`] samples of up to 8 bytes (readers check a
/// file's size against it before reading it).
pub const MAX_DEM_BYTES: u64 = MAX_DEM_SAMPLES * 8;
/// Added to each stretch's highest ground: the stretch is straight in local metres, and a
/// geographic raster's pixel coordinates bend by micrometres over half a pixel.
const BOUND_PAD_M: f64 = 0.01;

/// How far a [`Column`]'s footprint reaches past its cell's corners, metres: a cell's edges,
/// straight in the DEM's grid, bow by far less in the local frame.
pub const COLUMN_PAD_M: f64 = 0.1;

/// Most columns [`Terrain::columns`] makes.
pub const MAX_COLUMNS: usize = 2_000_000;

/// The ground under one DEM cell, as a box: a local rectangle and the highest the ground
/// reaches in it ([`Terrain::columns`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    /// `[south, north]` edges, metres north of home.
    pub north_m: [f64; 2],
    /// `[west, east]` edges, metres east of home.
    pub east_m: [f64; 2],
    /// The highest ground in it, metres above the ground under home.
    pub top_m: f64,
}
/// The SRTM void value.
const HGT_VOID: i16 = -32768;

/// Why a DEM was refused or a height could not be given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TerrainError {
    /// The file is not a DEM this reader can place.
    #[error("{field}: {message}")]
    Format {
        /// The tag, key or part of the file concerned.
        field: String,
        /// What was expected and what was found.
        message: String,
    },
    /// A position the DEM does not cover.
    #[error(
        "the terrain does not cover lat {lat_deg:.6}, lon {lon_deg:.6}{what} (it covers lat {lat_min:.6} to {lat_max:.6}, lon {lon_min:.6} to {lon_max:.6})"
    )]
    NotCovered {
        /// Latitude, degrees.
        lat_deg: f64,
        /// Longitude, degrees.
        lon_deg: f64,
        /// What lies there (for example `, the goal`), or empty.
        what: String,
        /// The DEM's extent, degrees (approximate for UTM rasters).
        lat_min: f64,
        /// See `lat_min`.
        lat_max: f64,
        /// See `lat_min`.
        lon_min: f64,
        /// See `lat_min`.
        lon_max: f64,
    },
    /// A sample the interpolation needs is missing (a void).
    #[error("the terrain has no data at lat {lat_deg:.6}, lon {lon_deg:.6} (a void in the DEM)")]
    Void {
        /// Latitude, degrees.
        lat_deg: f64,
        /// Longitude, degrees.
        lon_deg: f64,
    },
    /// A route point below the required height above the ground.
    #[error(
        "the route is {clearance_m:.2} m above the ground at N {north_m:.1} m, E {east_m:.1} m; at least {required_m:.2} m was asked for"
    )]
    TooLow {
        /// Where, metres north of home.
        north_m: f64,
        /// Where, metres east of home.
        east_m: f64,
        /// Height above the ground's upper bound there.
        clearance_m: f64,
        /// The height asked for.
        required_m: f64,
    },
    /// A bad argument (a negative height, an empty route).
    #[error("{0}")]
    Argument(String),
    /// A position the local frame cannot convert.
    #[error(transparent)]
    Frame(#[from] FrameError),
}

fn format_err(field: &str, message: impl Into<String>) -> TerrainError {
    TerrainError::Format {
        field: field.to_string(),
        message: message.into(),
    }
}

/// How a DEM's pixel grid lies on the Earth. Sample `(row, col)` is at
/// `origin + (col · step_x, −row · step_y)`: rows run south (or down the northing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Georef {
    /// WGS84 longitude/latitude: `origin` is `[lon, lat]` of sample (0, 0), steps in degrees.
    Geographic {
        /// `[lon_deg, lat_deg]` of the first sample's centre.
        origin: [f64; 2],
        /// `[lon, lat]` pixel size, degrees (both positive).
        step: [f64; 2],
    },
    /// WGS84 UTM: `origin` is `[easting, northing]` of sample (0, 0), steps in metres.
    Utm {
        /// Zone number, 1..=60.
        zone: u8,
        /// Northern hemisphere.
        north: bool,
        /// `[easting_m, northing_m]` of the first sample's centre.
        origin: [f64; 2],
        /// `[easting, northing]` pixel size, metres (both positive).
        step: [f64; 2],
    },
}

/// A digital elevation model: heights above mean sea level at the centres of a grid of pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct Dem {
    rows: usize,
    cols: usize,
    /// Row-major heights, metres; NaN where the DEM has no data.
    values: Vec<f32>,
    georef: Georef,
}

impl Dem {
    /// A DEM in WGS84 longitude/latitude from row-major heights (row 0 the northernmost),
    /// `origin` `[lon, lat]` of sample (0, 0), `step` `[lon, lat]` in degrees. NaN marks voids.
    pub fn geographic(
        rows: usize,
        cols: usize,
        values: Vec<f32>,
        origin: [f64; 2],
        step: [f64; 2],
    ) -> Result<Dem, TerrainError> {
        Dem::new(rows, cols, values, Georef::Geographic { origin, step })
    }

    /// A DEM from its parts, checked: at least 2 × 2 samples, positive finite steps, and a
    /// geographic extent within ±90° / ±180°.
    pub fn new(
        rows: usize,
        cols: usize,
        values: Vec<f32>,
        georef: Georef,
    ) -> Result<Dem, TerrainError> {
        if rows < 2 || cols < 2 {
            return Err(format_err(
                "size",
                format!("a DEM needs at least 2 × 2 samples, this one has {cols} × {rows}"),
            ));
        }
        if values.len() != rows * cols {
            return Err(format_err(
                "size",
                format!("{} samples for {cols} × {rows} pixels", values.len()),
            ));
        }
        let (origin, step) = match georef {
            Georef::Geographic { origin, step } | Georef::Utm { origin, step, .. } => {
                (origin, step)
            }
        };
        if !(step.iter().all(|s| s.is_finite() && *s > 0.0) && origin.iter().all(|o| o.is_finite()))
        {
            return Err(format_err(
                "ModelPixelScale",
                "pixel sizes must be positive and finite, with a finite origin",
            ));
        }
        if let Georef::Geographic { .. } = georef {
            let lon_max = origin[0] + step[0] * (cols - 1) as f64;
            let lat_min = origin[1] - step[1] * (rows - 1) as f64;
            if origin[0] < -180.5 || lon_max > 180.5 || origin[1] > 90.5 || lat_min < -90.5 {
                return Err(format_err(
                    "ModelTiepoint",
                    format!(
                        "the raster spans lon {:.4} to {lon_max:.4}, lat {lat_min:.4} to {:.4}: not longitude/latitude in degrees (swapped, or projected coordinates with a geographic key?)",
                        origin[0], origin[1]
                    ),
                ));
            }
        }
        if let Georef::Utm { zone, .. } = georef
            && !(1..=60).contains(&zone)
        {
            return Err(format_err(
                "ProjectedCSTypeGeoKey",
                "UTM zone out of 1..=60",
            ));
        }
        Ok(Dem {
            rows,
            cols,
            values,
            georef,
        })
    }

    /// Rows (north to south) and columns (west to east).
    pub fn size(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }

    /// How the grid lies on the Earth.
    pub fn georef(&self) -> Georef {
        self.georef
    }

    /// The sample at `(row, col)`, metres above mean sea level (`None` for a void or outside).
    pub fn sample(&self, row: usize, col: usize) -> Option<f64> {
        (row < self.rows && col < self.cols)
            .then(|| self.values[row * self.cols + col])
            .filter(|v| v.is_finite())
            .map(f64::from)
    }

    /// Lowest and highest sample, metres (voids left out; `None` if all are voids).
    pub fn range_m(&self) -> Option<(f64, f64)> {
        let mut it = self.values.iter().filter(|v| v.is_finite());
        let first = f64::from(*it.next()?);
        Some(it.fold((first, first), |(lo, hi), &v| {
            (lo.min(f64::from(v)), hi.max(f64::from(v)))
        }))
    }

    /// Continuous pixel coordinates `(x = col, y = row)` of a position: samples at integers.
    fn pixel(&self, lat_deg: f64, lon_deg: f64) -> Result<(f64, f64), TerrainError> {
        match self.georef {
            Georef::Geographic { origin, step } => Ok((
                (lon_deg - origin[0]) / step[0],
                (origin[1] - lat_deg) / step[1],
            )),
            Georef::Utm {
                zone,
                north,
                origin,
                step,
            } => {
                let u = skyplan_frames::utm_from_lla_in_zone(lat_deg, lon_deg, zone)?;
                if u.north != north {
                    return Err(self.not_covered(lat_deg, lon_deg, ""));
                }
                Ok((
                    (u.easting_m - origin[0]) / step[0],
                    (origin[1] - u.northing_m) / step[1],
                ))
            }
        }
    }

    /// The DEM's extent in degrees: `[lat_min, lat_max, lon_min, lon_max]` over the samples'
    /// centres (UTM rasters: of the four corners, approximate).
    pub fn extent_deg(&self) -> [f64; 4] {
        let (w, h) = ((self.cols - 1) as f64, (self.rows - 1) as f64);
        match self.georef {
            Georef::Geographic { origin, step } => [
                origin[1] - step[1] * h,
                origin[1],
                origin[0],
                origin[0] + step[0] * w,
            ],
            Georef::Utm {
                zone,
                north,
                origin,
                step,
            } => {
                let letter = if north { 'N' } else { 'M' };
                let corners: Vec<(f64, f64)> = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
                    .iter()
                    .filter_map(|&(x, y)| {
                        utm::wsg84_utm_to_lat_lon(
                            origin[0] + x * step[0],
                            origin[1] - y * step[1],
                            zone,
                            letter,
                        )
                        .ok()
                    })
                    .collect();
                // (lat, lon) pairs: their box is [lat_min, lat_max, lon_min, lon_max].
                pixel_box(&corners)
            }
        }
    }

    /// Latitude and longitude of pixel position `(x = col, y = row)`, degrees.
    fn lla_of_pixel(&self, x: f64, y: f64) -> Result<(f64, f64), TerrainError> {
        match self.georef {
            Georef::Geographic { origin, step } => {
                Ok((origin[1] - y * step[1], origin[0] + x * step[0]))
            }
            Georef::Utm {
                zone,
                north,
                origin,
                step,
            } => utm::wsg84_utm_to_lat_lon(
                origin[0] + x * step[0],
                origin[1] - y * step[1],
                zone,
                if north { 'N' } else { 'M' },
            )
            .map_err(|_| {
                TerrainError::Argument(format!(
                    "pixel ({x}, {y}) of the DEM is not a position in UTM zone {zone}"
                ))
            }),
        }
    }

    fn not_covered(&self, lat_deg: f64, lon_deg: f64, what: &str) -> TerrainError {
        let [lat_min, lat_max, lon_min, lon_max] = self.extent_deg();
        TerrainError::NotCovered {
            lat_deg,
            lon_deg,
            what: what.to_string(),
            lat_min,
            lat_max,
            lon_min,
            lon_max,
        }
    }

    /// Whether pixel position `(x, y)` is inside the samples' hull (half a pixel of slack at
    /// the edges, as the pixels' own extent reaches).
    fn covers(&self, x: f64, y: f64) -> bool {
        x >= -0.5 && y >= -0.5 && x <= self.cols as f64 - 0.5 && y <= self.rows as f64 - 0.5
    }

    /// Height above mean sea level at a position, metres: bilinear between the four samples
    /// around it (clamped to the edge samples in the outer half pixel).
    pub fn elevation_amsl_m(&self, lat_deg: f64, lon_deg: f64) -> Result<f64, TerrainError> {
        let (x, y) = self.pixel(lat_deg, lon_deg)?;
        if !self.covers(x, y) {
            return Err(self.not_covered(lat_deg, lon_deg, ""));
        }
        let x = x.clamp(0.0, (self.cols - 1) as f64);
        let y = y.clamp(0.0, (self.rows - 1) as f64);
        let (c0, r0) = (
            (x.floor() as usize).min(self.cols - 2),
            (y.floor() as usize).min(self.rows - 2),
        );
        let (fx, fy) = (x - c0 as f64, y - r0 as f64);
        let s = |r: usize, c: usize| {
            self.sample(r, c)
                .ok_or(TerrainError::Void { lat_deg, lon_deg })
        };
        let top = s(r0, c0)? * (1.0 - fx) + s(r0, c0 + 1)? * fx;
        let bottom = s(r0 + 1, c0)? * (1.0 - fx) + s(r0 + 1, c0 + 1)? * fx;
        Ok(top * (1.0 - fy) + bottom * fy)
    }

    /// The highest the interpolated ground reaches along the straight pixel-space segment
    /// `p → q` (`None` if it crosses a void): the segment is cut where it crosses cell edges;
    /// in each cell the bilinear surface along a line is a quadratic in the line's parameter,
    /// whose maximum is at an end or at its vertex.
    fn max_on_segment(&self, p: (f64, f64), q: (f64, f64)) -> Option<f64> {
        self.extreme_on_segment(p, q, 1.0, [0.0, 0.0])
    }

    /// The lowest the interpolated ground reaches along the pixel-space segment `p → q`.
    fn min_on_segment(&self, p: (f64, f64), q: (f64, f64)) -> Option<f64> {
        self.extreme_on_segment(p, q, -1.0, [0.0, 0.0]).map(|v| -v)
    }

    /// The highest `sign ×` ground less the line from `line[0]` at `p` to `line[1]` at `q`
    /// along `p → q` (`sign` ±1): with a flat line, the ground's extreme; with a route's
    /// altitudes (AMSL), how far the ground reaches above the route.
    fn extreme_on_segment(
        &self,
        p: (f64, f64),
        q: (f64, f64),
        sign: f64,
        line: [f64; 2],
    ) -> Option<f64> {
        let slope = line[1] - line[0];
        let clamp = |(x, y): (f64, f64)| {
            (
                x.clamp(0.0, (self.cols - 1) as f64),
                y.clamp(0.0, (self.rows - 1) as f64),
            )
        };
        let (p, q) = (clamp(p), clamp(q));
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        let mut ts = vec![0.0, 1.0];
        for (a, d) in [(p.0, dx), (p.1, dy)] {
            if d.abs() > 1e-12 {
                let (lo, hi) = if d > 0.0 { (a, a + d) } else { (a + d, a) };
                let mut k = lo.floor() + 1.0;
                while k < hi {
                    ts.push((k - a) / d);
                    k += 1.0;
                }
            }
        }
        ts.sort_by(f64::total_cmp);
        let mut best = f64::NEG_INFINITY;
        for w in ts.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            let mid = (t0 + t1) / 2.0;
            let c0 = ((p.0 + dx * mid).floor().max(0.0) as usize).min(self.cols - 2);
            let r0 = ((p.1 + dy * mid).floor().max(0.0) as usize).min(self.rows - 2);
            let z00 = sign * self.sample(r0, c0)?;
            let z01 = sign * self.sample(r0, c0 + 1)?;
            let z10 = sign * self.sample(r0 + 1, c0)?;
            let z11 = sign * self.sample(r0 + 1, c0 + 1)?;
            let (u0, v0) = (p.0 - c0 as f64, p.1 - r0 as f64);
            let k = z00 - z01 - z10 + z11;
            // f(t) = z00 + (z01 − z00)·u + (z10 − z00)·v + k·u·v, u = u0 + dx·t, v = v0 + dy·t.
            let f = |t: f64| {
                let (u, v) = (u0 + dx * t, v0 + dy * t);
                z00 + (z01 - z00) * u + (z10 - z00) * v + k * u * v - line[0] - slope * t
            };
            best = best.max(f(t0)).max(f(t1));
            let c2 = k * dx * dy;
            if c2 < 0.0 {
                let b = (z01 - z00) * dx + (z10 - z00) * dy + k * (u0 * dy + v0 * dx) - slope;
                let t = -b / (2.0 * c2);
                if t > t0 && t < t1 {
                    best = best.max(f(t));
                }
            }
        }
        Some(best)
    }
}

/// Reads a DEM: a GeoTIFF (by its magic bytes) or an SRTM `.hgt` tile (placed by `name`, e.g.
/// `N37W122.hgt`; 1201² or 3601² big-endian 16-bit samples).
pub fn parse_dem(name: &str, bytes: &[u8]) -> Result<Dem, TerrainError> {
    if bytes.starts_with(b"II") || bytes.starts_with(b"MM") {
        parse_geotiff(bytes)
    } else {
        parse_hgt(name, bytes)
    }
}

/// Reads an SRTM `.hgt` tile; `name` (a path or file name) gives its south-west corner.
pub fn parse_hgt(name: &str, bytes: &[u8]) -> Result<Dem, TerrainError> {
    let n = match bytes.len() {
        l if l == 1201 * 1201 * 2 => 1201,
        l if l == 3601 * 3601 * 2 => 3601,
        l => {
            return Err(format_err(
                "size",
                format!(
                    "{l} bytes is neither a GeoTIFF nor an SRTM tile (1201 × 1201 or 3601 × 3601 samples of 2 bytes)"
                ),
            ));
        }
    };
    let stem = name
        .rsplit(['/', '\\'])
        .next()
        .unwrap_or(name)
        .split('.')
        .next()
        .unwrap_or("")
        .to_ascii_uppercase();
    let bad_name = || {
        format_err(
            "file name",
            format!(
                "an SRTM tile is placed by its name, like N37W122.hgt (south-west corner); got {}",
                crate::shown(name)
            ),
        )
    };
    let b = stem.as_bytes();
    if b.len() != 7 || !matches!(b[0], b'N' | b'S') || !matches!(b[3], b'E' | b'W') {
        return Err(bad_name());
    }
    let lat: f64 = stem[1..3].parse().map_err(|_| bad_name())?;
    let lon: f64 = stem[4..7].parse().map_err(|_| bad_name())?;
    let lat = if b[0] == b'S' { -lat } else { lat };
    let lon = if b[3] == b'W' { -lon } else { lon };
    if lat.abs() > 89.0 || lon.abs() > 180.0 {
        return Err(bad_name());
    }
    let values = bytes
        .chunks_exact(2)
        .map(|c| match i16::from_be_bytes([c[0], c[1]]) {
            HGT_VOID => f32::NAN,
            v => f32::from(v),
        })
        .collect();
    let step = 1.0 / (n - 1) as f64;
    Dem::geographic(n, n, values, [lon, lat + 1.0], [step, step])
}

/// GeoTIFF keys read (GeoTIFF 1.0 §6).
const GT_MODEL_TYPE: u16 = 1024;
const GT_RASTER_TYPE: u16 = 1025;
const GEOGRAPHIC_TYPE: u16 = 2048;
const GEOG_ANGULAR_UNITS: u16 = 2054;
const PROJECTED_CS_TYPE: u16 = 3072;
const VERTICAL_UNITS: u16 = 4099;

/// Reads a single-band GeoTIFF of elevations in metres.
pub fn parse_geotiff(bytes: &[u8]) -> Result<Dem, TerrainError> {
    use tiff::decoder::{Decoder, DecodingResult, Limits};
    use tiff::tags::Tag;
    let tiff_err = |field: &str| {
        let field = field.to_string();
        move |e: tiff::TiffError| format_err(&field, e.to_string())
    };
    let mut limits = Limits::default();
    limits.decoding_buffer_size = (MAX_DEM_SAMPLES * 8) as usize;
    let mut dec = Decoder::new(std::io::Cursor::new(bytes))
        .map_err(tiff_err("TIFF header"))?
        .with_limits(limits);
    let (cols, rows) = dec.dimensions().map_err(tiff_err("ImageWidth"))?;
    if u64::from(cols) * u64::from(rows) > MAX_DEM_SAMPLES {
        return Err(format_err(
            "ImageWidth",
            format!(
                "{cols} × {rows} samples is more than the {MAX_DEM_SAMPLES} a DEM may have; crop it (gdal_translate -projwin)"
            ),
        ));
    }
    match dec.colortype().map_err(tiff_err("SamplesPerPixel"))? {
        tiff::ColorType::Gray(_) => {}
        _ => {
            return Err(format_err(
                "SamplesPerPixel",
                "a DEM has one band of elevations; this image has colour or several bands",
            ));
        }
    }
    if dec
        .find_tag(Tag::Unknown(34264))
        .map_err(tiff_err("ModelTransformation"))?
        .is_some()
    {
        return Err(format_err(
            "ModelTransformation",
            "rotated or sheared rasters are not supported; warp it north-up (gdalwarp)",
        ));
    }
    // A tag the file must have, or an error naming it.
    let mut required = |tag: Tag, field: &str, missing: &str| {
        dec.find_tag(tag)
            .map_err(tiff_err(field))?
            .ok_or_else(|| format_err(field, missing))
    };
    let not_georeferenced = "missing: the image is not georeferenced (a plain TIFF, or a world file beside it, which is not read)";
    let mut numbers = |tag: Tag, field: &str| {
        required(tag, field, not_georeferenced)?
            .into_f64_vec()
            .map_err(tiff_err(field))
    };
    let scale = numbers(Tag::ModelPixelScaleTag, "ModelPixelScale")?;
    let tie = numbers(Tag::ModelTiepointTag, "ModelTiepoint")?;
    if scale.len() < 2 || tie.len() < 6 {
        return Err(format_err(
            "ModelTiepoint",
            "expected a pixel scale of 3 values and a tie point of 6",
        ));
    }
    let keys = required(
        Tag::GeoKeyDirectoryTag,
        "GeoKeyDirectory",
        "missing: the coordinate system is not given",
    )?
    .into_u16_vec()
    .map_err(tiff_err("GeoKeyDirectory"))?;
    let key = |id: u16| -> Option<u16> {
        keys.get(4..)?
            .chunks_exact(4)
            .find(|k| k[0] == id && k[1] == 0)
            .map(|k| k[3])
    };
    // Pixel-is-area (the default): the tie point is a pixel's corner; pixel-is-point: its centre.
    let half = if key(GT_RASTER_TYPE) == Some(2) {
        0.0
    } else {
        0.5
    };
    let (ti, tj, tx, ty) = (tie[0], tie[1], tie[3], tie[4]);
    let (sx, sy) = (scale[0], scale[1]);
    // Centre of sample (0, 0).
    let origin = [tx - (ti - half) * sx, ty + (tj - half) * sy];
    let step = [sx, sy];
    let georef = match key(GT_MODEL_TYPE) {
        Some(2) => {
            match key(GEOGRAPHIC_TYPE) {
                Some(4326) => {}
                other => {
                    return Err(format_err(
                        "GeographicTypeGeoKey",
                        format!(
                            "only WGS84 (EPSG:4326) longitude/latitude is read, this file has {}; reproject it (gdalwarp -t_srs EPSG:4326)",
                            other.map_or("none".to_string(), |c| format!("EPSG:{c}"))
                        ),
                    ));
                }
            }
            if let Some(u) = key(GEOG_ANGULAR_UNITS)
                && u != 9102
            {
                return Err(format_err(
                    "GeogAngularUnitsGeoKey",
                    format!("only degrees (9102) are read, this file has {u}"),
                ));
            }
            Georef::Geographic { origin, step }
        }
        Some(1) => match key(PROJECTED_CS_TYPE) {
            Some(c @ 32601..=32660) => Georef::Utm {
                zone: (c - 32600) as u8,
                north: true,
                origin,
                step,
            },
            Some(c @ 32701..=32760) => Georef::Utm {
                zone: (c - 32700) as u8,
                north: false,
                origin,
                step,
            },
            other => {
                return Err(format_err(
                    "ProjectedCSTypeGeoKey",
                    format!(
                        "only WGS84 UTM zones (EPSG:326xx, 327xx) are read, this file has {}; reproject it (gdalwarp -t_srs EPSG:326xx)",
                        other.map_or("a user-defined projection".to_string(), |c| format!(
                            "EPSG:{c}"
                        ))
                    ),
                ));
            }
        },
        other => {
            return Err(format_err(
                "GTModelTypeGeoKey",
                format!(
                    "expected 1 (projected) or 2 (geographic), found {}",
                    other.map_or("none".to_string(), |m| m.to_string())
                ),
            ));
        }
    };
    if let Some(u) = key(VERTICAL_UNITS)
        && u != 9001
    {
        return Err(format_err(
            "VerticalUnitsGeoKey",
            format!("elevations must be in metres (9001), this file has unit {u}"),
        ));
    }
    let nodata: Option<f64> = dec
        .find_tag(Tag::GdalNodata)
        .map_err(tiff_err("GDAL_NODATA"))?
        .and_then(|v| v.into_string().ok())
        .and_then(|s| s.trim_matches(char::from(0)).trim().parse().ok());
    let data = dec.read_image().map_err(tiff_err("image data"))?;
    let values: Vec<f32> = match data {
        DecodingResult::U8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::U32(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::F32(v) => v,
        DecodingResult::F64(v) => v.into_iter().map(|x| x as f32).collect(),
        _ => {
            return Err(format_err(
                "BitsPerSample",
                "expected 8-, 16- or 32-bit integers or 32-/64-bit floats",
            ));
        }
    };
    let values = values
        .into_iter()
        .map(|v| match nodata {
            Some(nd) if (f64::from(v) - nd).abs() < 1e-6 * nd.abs().max(1.0) => f32::NAN,
            _ => v,
        })
        .collect();
    Dem::new(rows as usize, cols as usize, values, georef)
}

/// A DEM placed about a map's home: heights above the ground under home.
#[derive(Debug, Clone)]
pub struct Terrain {
    dem: Dem,
    frame: LocalFrame,
    home_ground_amsl_m: f64,
}

/// The steepest a route may climb and descend: `[climb, descent]`, metres of height per metre
/// flown horizontally (the vertical rate limits over the horizontal speed).
pub type Slopes = [f64; 2];

impl Terrain {
    /// Places `dem` about `frame`'s home, which must lie on it.
    pub fn new(dem: Dem, frame: LocalFrame) -> Result<Terrain, TerrainError> {
        let home = frame.home();
        let home_ground_amsl_m = dem
            .elevation_amsl_m(home.lat_deg, home.lon_deg)
            .map_err(|e| match e {
                TerrainError::NotCovered { .. } => {
                    dem.not_covered(home.lat_deg, home.lon_deg, ", the map's home")
                }
                e => e,
            })?;
        Ok(Terrain {
            dem,
            frame,
            home_ground_amsl_m,
        })
    }

    /// The DEM.
    pub fn dem(&self) -> &Dem {
        &self.dem
    }

    /// The ground's height above mean sea level under home, metres.
    pub fn home_ground_amsl_m(&self) -> f64 {
        self.home_ground_amsl_m
    }

    fn lla(&self, ne: [f64; 2]) -> Result<Lla, TerrainError> {
        Ok(self.frame.lla_from_ned(Ned {
            north_m: ne[0],
            east_m: ne[1],
            down_m: 0.0,
        })?)
    }

    /// Pixel coordinates of a local point, or why the DEM does not cover it.
    fn pixel_ne(&self, ne: [f64; 2]) -> Result<(f64, f64), TerrainError> {
        let lla = self.lla(ne)?;
        let (x, y) = self.dem.pixel(lla.lat_deg, lla.lon_deg)?;
        if !self.dem.covers(x, y) {
            return Err(self.dem.not_covered(lla.lat_deg, lla.lon_deg, ""));
        }
        Ok((x, y))
    }

    /// The ground's height above the ground under home at a local point, metres.
    pub fn ground_m(&self, north_m: f64, east_m: f64) -> Result<f64, TerrainError> {
        let lla = self.lla([north_m, east_m])?;
        Ok(self.dem.elevation_amsl_m(lla.lat_deg, lla.lon_deg)? - self.home_ground_amsl_m)
    }

    /// The pixel positions of the corners of the local rectangle `north` × `east`, in order
    /// around it; a corner off the DEM is named (`what` says whose rectangle it is).
    fn rect_pixels(
        &self,
        north: [f64; 2],
        east: [f64; 2],
        what: &str,
    ) -> Result<[(f64, f64); 4], TerrainError> {
        let corners = [
            [north[0], east[0]],
            [north[0], east[1]],
            [north[1], east[1]],
            [north[1], east[0]],
        ];
        let mut px = [(0.0, 0.0); 4];
        for (slot, c) in px.iter_mut().zip(corners) {
            *slot = self.pixel_ne(c).map_err(|e| match e {
                TerrainError::NotCovered { .. } => self
                    .lla(c)
                    .map(|l| {
                        self.dem.not_covered(
                            l.lat_deg,
                            l.lon_deg,
                            &format!(", the corner N {:.1} m, E {:.1} m of {what}", c[0], c[1]),
                        )
                    })
                    .unwrap_or(e),
                e => e,
            })?;
        }
        Ok(px)
    }

    /// A lower bound of the ground (above home) over the local rectangle `north` × `east`
    /// (metres): the lowest sample of every DEM cell the rectangle's pixel box touches, with a
    /// pixel of slack (bilinear interpolation never goes below its corners). `None` if the DEM
    /// has no sample there.
    pub fn min_ground_m_in(&self, north: [f64; 2], east: [f64; 2]) -> Option<f64> {
        self.ground_range_m_in(north, east).map(|r| r[0])
    }

    /// Bounds `[lowest, highest]` of the ground (above home) over the local rectangle `north` ×
    /// `east` (metres): the lowest and highest samples of every DEM cell the rectangle's pixel
    /// box touches, with a pixel of slack (bilinear interpolation stays between its corners).
    /// `None` if the DEM has no sample there.
    pub fn ground_range_m_in(&self, north: [f64; 2], east: [f64; 2]) -> Option<[f64; 2]> {
        let corners = [
            [north[0], east[0]],
            [north[0], east[1]],
            [north[1], east[0]],
            [north[1], east[1]],
        ];
        let px: Vec<(f64, f64)> = corners
            .iter()
            .filter_map(|&c| {
                let l = self.lla(c).ok()?;
                self.dem.pixel(l.lat_deg, l.lon_deg).ok()
            })
            .collect();
        if px.len() < 4 {
            return None;
        }
        let (cols, rows) = (self.dem.cols as f64, self.dem.rows as f64);
        let lo = |v: f64, n: f64| (v.floor() - 1.0).clamp(0.0, n - 1.0) as usize;
        let hi = |v: f64, n: f64| (v.ceil() + 1.0).clamp(0.0, n - 1.0) as usize;
        let [x0, x1, y0, y1] = pixel_box(&px);
        if x1 < -1.0 || y1 < -1.0 || x0 > cols || y0 > rows {
            return None;
        }
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for r in lo(y0, rows)..=hi(y1, rows) {
            for c in lo(x0, cols)..=hi(x1, cols) {
                if let Some(v) = self.dem.sample(r, c) {
                    low = low.min(v);
                    high = high.max(v);
                }
            }
        }
        low.is_finite().then_some([
            low - self.home_ground_amsl_m,
            high - self.home_ground_amsl_m,
        ])
    }

    /// The lowest and highest the ground (above home) reaches over the local rectangle `north`
    /// × `east`, exactly (to [`BOUND_PAD_M`]): inside one DEM cell the bilinear surface has no
    /// peak or pit, so over the rectangle it is extreme on the rectangle's edges or at a
    /// sample inside it. Errors if the DEM does not cover the rectangle or has a void there.
    pub fn ground_extremes_m_in(
        &self,
        north: [f64; 2],
        east: [f64; 2],
    ) -> Result<[f64; 2], TerrainError> {
        let px = self.rect_pixels(north, east, "the rectangle")?;
        let void = || {
            let l = self.lla([north[0], east[0]]).unwrap_or(self.frame.home());
            TerrainError::Void {
                lat_deg: l.lat_deg,
                lon_deg: l.lon_deg,
            }
        };
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..4 {
            let (p, q) = (px[k], px[(k + 1) % 4]);
            low = low.min(self.dem.min_on_segment(p, q).ok_or_else(void)?);
            high = high.max(self.dem.max_on_segment(p, q).ok_or_else(void)?);
        }
        let (cols, rows) = (self.dem.cols, self.dem.rows);
        let [x0, x1, y0, y1] = pixel_box(&px);
        let c0 = x0.ceil().max(0.0) as usize;
        let r0 = y0.ceil().max(0.0) as usize;
        let c1 = (x1.floor().max(0.0) as usize).min(cols - 1);
        let r1 = (y1.floor().max(0.0) as usize).min(rows - 1);
        for r in r0..=r1 {
            for c in c0..=c1 {
                let (lat_deg, lon_deg) = self.dem.lla_of_pixel(c as f64, r as f64)?;
                let p = self.frame.ned_from_lla(Lla {
                    lat_deg,
                    lon_deg,
                    alt_m: 0.0,
                })?;
                if (north[0]..=north[1]).contains(&p.north_m)
                    && (east[0]..=east[1]).contains(&p.east_m)
                {
                    let v = self
                        .dem
                        .sample(r, c)
                        .ok_or(TerrainError::Void { lat_deg, lon_deg })?;
                    low = low.min(v);
                    high = high.max(v);
                }
            }
        }
        Ok([
            low - BOUND_PAD_M - self.home_ground_amsl_m,
            high + BOUND_PAD_M - self.home_ground_amsl_m,
        ])
    }

    /// The ground under the local rectangle `north` × `east` as columns, for planners that
    /// see obstacles as boxes: each DEM cell (the square between four samples) that meets the
    /// rectangle is split alike along both axes into sub-cells about `size_m` across, and each
    /// sub-cell is a column reaching up to the highest the bilinear ground gets in it (at one
    /// of its corners: along each pixel axis the surface is linear). A column's footprint is
    /// the local bounding rectangle of its sub-cell (padded by [`COLUMN_PAD_M`]), so together
    /// the columns cover the ground under the whole rectangle: a point above every column it
    /// stands in is above the ground there.
    /// Errors if the DEM does not cover the rectangle, has a void in it, or it takes more than
    /// [`MAX_COLUMNS`] columns.
    pub fn columns(
        &self,
        north: [f64; 2],
        east: [f64; 2],
        size_m: f64,
    ) -> Result<Vec<Column>, TerrainError> {
        let px = self.rect_pixels(north, east, "the flight volume")?;
        // The pixel box of a local rectangle can bulge a little past its corners' (UTM grids
        // turn against true north): one cell of slack on each side, clamped to the DEM.
        let (cols, rows) = (self.dem.cols, self.dem.rows);
        let [x0, x1, y0, y1] = pixel_box(&px);
        let c0 = ((x0.floor() - 1.0).max(0.0) as usize).min(cols - 2);
        let c1 = ((x1.ceil() + 1.0).max(0.0) as usize).min(cols - 1);
        let r0 = ((y0.floor() - 1.0).max(0.0) as usize).min(rows - 2);
        let r1 = ((y1.ceil() + 1.0).max(0.0) as usize).min(rows - 1);
        let cells = (c1 - c0) * (r1 - r0);
        // Sub-cells about `size_m` across (each DEM cell split alike along both axes), as
        // many as fit under MAX_COLUMNS.
        let pixel_m = 2.0 * self.stretch_m();
        let mut split = if size_m.is_finite() && size_m > 0.0 {
            ((pixel_m / size_m).ceil() as usize).clamp(1, 64)
        } else {
            1
        };
        while split > 1 && cells * split * split > MAX_COLUMNS {
            split -= 1;
        }
        let count = cells * split * split;
        if count > MAX_COLUMNS {
            return Err(TerrainError::Argument(format!(
                "the flight volume covers {cells} cells of the DEM, more than {MAX_COLUMNS}; use a coarser DEM or a smaller map"
            )));
        }
        // Local positions of the sub-cells' corners, row by row.
        let w = (c1 - c0) * split + 1;
        let h = (r1 - r0) * split + 1;
        let mut ne = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (lat_deg, lon_deg) = self.dem.lla_of_pixel(
                    c0 as f64 + x as f64 / split as f64,
                    r0 as f64 + y as f64 / split as f64,
                )?;
                let p = self.frame.ned_from_lla(Lla {
                    lat_deg,
                    lon_deg,
                    alt_m: 0.0,
                })?;
                ne.push([p.north_m, p.east_m]);
            }
        }
        let mut out = Vec::with_capacity(count);
        let f = split as f64;
        for r in r0..r1 {
            for c in c0..c1 {
                let mut z = [[0.0; 2]; 2];
                for (dr, row) in z.iter_mut().enumerate() {
                    for (dc, v) in row.iter_mut().enumerate() {
                        *v = self.dem.sample(r + dr, c + dc).ok_or_else(|| {
                            let (lat_deg, lon_deg) = self
                                .dem
                                .lla_of_pixel((c + dc) as f64, (r + dr) as f64)
                                .unwrap_or((f64::NAN, f64::NAN));
                            TerrainError::Void { lat_deg, lon_deg }
                        })?;
                    }
                }
                let bilinear = |u: f64, v: f64| {
                    (z[0][0] * (1.0 - u) + z[0][1] * u) * (1.0 - v)
                        + (z[1][0] * (1.0 - u) + z[1][1] * u) * v
                };
                for j in 0..split {
                    for i in 0..split {
                        let quad = [(j, i), (j, i + 1), (j + 1, i), (j + 1, i + 1)];
                        let at = |&(b, a): &(usize, usize)| {
                            ne[((r - r0) * split + b) * w + (c - c0) * split + a]
                        };
                        let lo_n = quad.iter().map(|q| at(q)[0]).fold(f64::INFINITY, f64::min);
                        let hi_n = quad
                            .iter()
                            .map(|q| at(q)[0])
                            .fold(f64::NEG_INFINITY, f64::max);
                        let lo_e = quad.iter().map(|q| at(q)[1]).fold(f64::INFINITY, f64::min);
                        let hi_e = quad
                            .iter()
                            .map(|q| at(q)[1])
                            .fold(f64::NEG_INFINITY, f64::max);
                        if hi_n < north[0] - COLUMN_PAD_M
                            || lo_n > north[1] + COLUMN_PAD_M
                            || hi_e < east[0] - COLUMN_PAD_M
                            || lo_e > east[1] + COLUMN_PAD_M
                        {
                            continue;
                        }
                        // Over an axis-aligned square of one cell the bilinear surface is
                        // highest at a corner.
                        let top = quad
                            .iter()
                            .map(|&(b, a)| bilinear(a as f64 / f, b as f64 / f))
                            .fold(f64::NEG_INFINITY, f64::max);
                        out.push(Column {
                            north_m: [lo_n - COLUMN_PAD_M, hi_n + COLUMN_PAD_M],
                            east_m: [lo_e - COLUMN_PAD_M, hi_e + COLUMN_PAD_M],
                            top_m: top + BOUND_PAD_M - self.home_ground_amsl_m,
                        });
                    }
                }
            }
        }
        Ok(out)
    }

    /// Height above mean sea level of a point `alt_m` above home, metres.
    pub fn amsl_m(&self, alt_m: f64) -> f64 {
        alt_m + self.home_ground_amsl_m
    }

    /// Half a pixel in metres at home (the longest stretch one ground bound covers).
    fn stretch_m(&self) -> f64 {
        let half = match self.dem.georef {
            Georef::Utm { step, .. } => step[0].min(step[1]),
            Georef::Geographic { step, .. } => {
                let lat = self.frame.home().lat_deg.to_radians();
                (step[1] * 110_574.0).min(step[0] * 111_320.0 * lat.cos())
            }
        } / 2.0;
        half.max(0.05)
    }

    /// Walks a horizontal polyline in pieces at most half a pixel long: `visit(leg, t0, t1,
    /// p, q)` for each, with the leg's index, the piece's parameters along the leg and its ends
    /// in pixel coordinates.
    fn walk(
        &self,
        route_ne: &[[f64; 2]],
        mut visit: impl FnMut(usize, f64, f64, (f64, f64), (f64, f64)) -> Result<(), TerrainError>,
    ) -> Result<(), TerrainError> {
        let step = self.stretch_m();
        for (leg, w) in route_ne.windows(2).enumerate() {
            let (a, b) = (w[0], w[1]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            let n = (len / step).ceil().max(1.0) as usize;
            let at = |t: f64| [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
            let mut prev = self.pixel_ne(at(0.0))?;
            for k in 1..=n {
                let (t0, t1) = ((k - 1) as f64 / n as f64, k as f64 / n as f64);
                let p = at(t1);
                let cur = self.pixel_ne(p).map_err(|e| match e {
                    TerrainError::NotCovered { .. } => self
                        .lla(p)
                        .map(|l| {
                            self.dem.not_covered(
                                l.lat_deg,
                                l.lon_deg,
                                &format!(", on the route at N {:.1} m, E {:.1} m", p[0], p[1]),
                            )
                        })
                        .unwrap_or(e),
                    e => e,
                })?;
                visit(leg, t0, t1, prev, cur)?;
                prev = cur;
            }
        }
        Ok(())
    }

    /// A void met at local point `ne`.
    fn void_at(&self, ne: [f64; 2]) -> TerrainError {
        let l = self.lla(ne).unwrap_or(self.frame.home());
        TerrainError::Void {
            lat_deg: l.lat_deg,
            lon_deg: l.lon_deg,
        }
    }

    /// The stretches of a horizontal polyline (each at most half a pixel long) with an upper
    /// bound of the ground above home on each: `(start distance, end distance, bound)`, plus
    /// the distances of the polyline's own vertices.
    fn stretches(&self, route_ne: &[[f64; 2]]) -> Result<(Vec<[f64; 3]>, Vec<f64>), TerrainError> {
        let mut corners = vec![0.0];
        for w in route_ne.windows(2) {
            let len = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            corners.push(corners[corners.len() - 1] + len);
        }
        let mut out = Vec::new();
        self.walk(route_ne, |leg, t0, t1, p, q| {
            let bound = self
                .dem
                .max_on_segment(p, q)
                .map(|m| m + BOUND_PAD_M)
                .ok_or_else(|| self.void_at(route_ne[leg]))?;
            let (s0, len) = (corners[leg], corners[leg + 1] - corners[leg]);
            out.push([
                s0 + len * t0,
                s0 + len * t1,
                bound - self.home_ground_amsl_m,
            ]);
            Ok(())
        })?;
        Ok((out, corners))
    }

    /// Lifts the horizontal route `route_ne` (`[north_m, east_m]` points) to stay at least
    /// `agl_m` above the ground everywhere along it, climbing no steeper than `slopes[0]` and
    /// descending no steeper than `slopes[1]` (metres per metre). Returns `[north_m, east_m,
    /// alt_m]` points (altitude above home): the route's own vertices plus the points where the
    /// altitude changes slope. The profile hugs the lowest such altitude to within a few metres.
    pub fn follow(
        &self,
        route_ne: &[[f64; 2]],
        agl_m: f64,
        slopes: Slopes,
    ) -> Result<Vec<[f64; 3]>, TerrainError> {
        if route_ne.is_empty() {
            return Err(TerrainError::Argument("the route is empty".into()));
        }
        if !(agl_m.is_finite() && agl_m >= 0.0) {
            return Err(TerrainError::Argument(format!(
                "alt_agl_m: {agl_m} must be a height of 0 m or more above the ground"
            )));
        }
        if !slopes.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(TerrainError::Argument(
                "climb and descent slopes must be positive".into(),
            ));
        }
        if route_ne.len() == 1 {
            let [n, e] = route_ne[0];
            return Ok(vec![[n, e, self.ground_m(n, e)? + agl_m]]);
        }
        let (pieces, corners) = self.stretches(route_ne)?;
        // Nodes at the pieces' ends; each node at least as high as both pieces beside it.
        let m = pieces.len();
        let s: Vec<f64> = std::iter::once(0.0)
            .chain(pieces.iter().map(|p| p[1]))
            .collect();
        let mut a = vec![f64::NEG_INFINITY; m + 1];
        for (i, p) in pieces.iter().enumerate() {
            let need = p[2] + agl_m;
            a[i] = a[i].max(need);
            a[i + 1] = a[i + 1].max(need);
        }
        let [up, down] = slopes;
        // Climb early enough (backwards), descend no faster than allowed (forwards).
        for j in (0..m).rev() {
            a[j] = a[j].max(a[j + 1] - up * (s[j + 1] - s[j]));
        }
        for j in 1..=m {
            a[j] = a[j].max(a[j - 1] - down * (s[j] - s[j - 1]));
        }
        let anchors = simplify(&s, &a, slopes, 2.0);
        // The output: every route vertex and every anchor, in order along the route.
        let alt_at = |d: f64| -> f64 {
            let k = anchors
                .partition_point(|&i| s[i] <= d)
                .clamp(1, anchors.len() - 1);
            let (i, j) = (anchors[k - 1], anchors[k]);
            if s[j] == s[i] {
                a[i].max(a[j])
            } else {
                a[i] + (a[j] - a[i]) * (d - s[i]) / (s[j] - s[i])
            }
        };
        let mut stops: Vec<(f64, Option<usize>)> = corners
            .iter()
            .enumerate()
            .map(|(i, &d)| (d, Some(i)))
            .chain(anchors.iter().map(|&i| (s[i], None)))
            .collect();
        stops.sort_by(|x, y| x.0.total_cmp(&y.0).then(y.1.is_some().cmp(&x.1.is_some())));
        stops.dedup_by(|x, y| (x.0 - y.0).abs() < 1e-6);
        let point_at = |d: f64| -> [f64; 2] {
            let k = corners
                .partition_point(|&c| c <= d)
                .clamp(1, corners.len() - 1);
            let (c0, c1) = (corners[k - 1], corners[k]);
            let (p, q) = (route_ne[k - 1], route_ne[k]);
            let t = if c1 > c0 {
                ((d - c0) / (c1 - c0)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            [p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t]
        };
        Ok(stops
            .into_iter()
            .map(|(d, corner)| {
                let [n, e] = corner.map_or_else(|| point_at(d), |i| route_ne[i]);
                [n, e, alt_at(d)]
            })
            .collect())
    }

    /// Checks, independently of [`Terrain::follow`], that the 3D polyline `route` (altitudes
    /// above home) stays at least `agl_m` above the ground everywhere along it, exactly: on
    /// each piece of half a pixel inside one DEM cell the ground less the route's straight
    /// altitude is a quadratic, whose maximum is at an end or at its vertex.
    pub fn check_clearance(&self, route: &[[f64; 3]], agl_m: f64) -> Result<(), TerrainError> {
        if route.len() == 1 {
            let g = self.ground_m(route[0][0], route[0][1])?;
            return check_one(route[0], route[0][2] - g, agl_m);
        }
        let ne: Vec<[f64; 2]> = route.iter().map(|p| [p[0], p[1]]).collect();
        let home = self.home_ground_amsl_m;
        self.walk(&ne, |leg, t0, t1, p, q| {
            let (a, b) = (route[leg], route[leg + 1]);
            let alt = |t: f64| a[2] + (b[2] - a[2]) * t + home;
            // How far the ground reaches above the route less the height asked for, at most.
            let over = self
                .dem
                .extreme_on_segment(p, q, 1.0, [alt(t0) - agl_m, alt(t1) - agl_m])
                .ok_or_else(|| self.void_at([a[0], a[1]]))?
                + BOUND_PAD_M;
            let t = (t0 + t1) / 2.0;
            let at = [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, 0.0];
            check_one(at, agl_m - over, agl_m)
        })
    }
}

/// The box `[x_min, x_max, y_min, y_max]` of `(x, y)` pairs (pixel positions, or lat/lon).
fn pixel_box(px: &[(f64, f64)]) -> [f64; 4] {
    let f = |g: fn(&(f64, f64)) -> f64, min: bool| {
        px.iter().map(g).fold(
            if min {
                f64::INFINITY
            } else {
                f64::NEG_INFINITY
            },
            if min { f64::min } else { f64::max },
        )
    };
    [
        f(|p| p.0, true),
        f(|p| p.0, false),
        f(|p| p.1, true),
        f(|p| p.1, false),
    ]
}

fn check_one(at: [f64; 3], clearance_m: f64, required_m: f64) -> Result<(), TerrainError> {
    if clearance_m < required_m - 1e-6 {
        Err(TerrainError::TooLow {
            north_m: at[0],
            east_m: at[1],
            clearance_m,
            required_m,
        })
    } else {
        Ok(())
    }
}

/// The nodes to keep of the profile `(s, a)`: greedily, from each kept node, the farthest node
/// whose straight line stays on or above every node between (so above every piece's bound),
/// within the slopes, and at most `slack_m` above any node between.
fn simplify(s: &[f64], a: &[f64], [up, down]: Slopes, slack_m: f64) -> Vec<usize> {
    const WINDOW: usize = 4096;
    let n = s.len();
    let mut keep = vec![0];
    let mut i = 0;
    while i + 1 < n {
        // The slopes a line from node i may take, narrowed by each node it passes over: at or
        // above the node (within 1e-9 m), at most `slack_m` above it, and within the limits.
        let (mut lo, mut hi) = (-down, up);
        let mut best = i + 1;
        for j in i + 1..n.min(i + WINDOW) {
            let ds = s[j] - s[i];
            if ds <= 1e-9 {
                if (a[j] - a[i]).abs() <= 1e-9 {
                    best = j;
                    continue;
                }
                break;
            }
            let m = (a[j] - a[i]) / ds;
            if m >= lo - 1e-12 && m <= hi + 1e-12 {
                best = j;
            }
            lo = lo.max((a[j] - 1e-9 - a[i]) / ds);
            hi = hi.min((a[j] + slack_m - a[i]) / ds);
            if lo > hi + 1e-12 {
                break;
            }
        }
        keep.push(best);
        i = best;
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(lat: f64, lon: f64) -> LocalFrame {
        LocalFrame::new(Lla {
            lat_deg: lat,
            lon_deg: lon,
            alt_m: 0.0,
        })
        .unwrap()
    }

    /// A hilly synthetic DEM: sines on a 200 × 200 grid of 0.0005° pixels.
    fn hills() -> Dem {
        let (rows, cols) = (200, 200);
        let v = (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f32, (i % cols) as f32);
                100.0 + 40.0 * (r / 13.0).sin() * (c / 17.0).cos() + 0.3 * c
            })
            .collect();
        Dem::geographic(rows, cols, v, [-84.30, 36.60], [0.0005, 0.0005]).unwrap()
    }

    #[test]
    fn bilinear_hits_samples_and_midpoints() {
        let d = hills();
        let (lon0, lat0) = (-84.30, 36.60);
        for (r, c) in [(0, 0), (10, 20), (199, 199), (57, 3)] {
            let (lat, lon) = (lat0 - r as f64 * 0.0005, lon0 + c as f64 * 0.0005);
            let got = d.elevation_amsl_m(lat, lon).unwrap();
            assert!((got - d.sample(r, c).unwrap()).abs() < 1e-6, "{r} {c}");
        }
        let mid = d
            .elevation_amsl_m(lat0 - 10.5 * 0.0005, lon0 + 20.5 * 0.0005)
            .unwrap();
        let avg = [(10, 20), (10, 21), (11, 20), (11, 21)]
            .iter()
            .map(|&(r, c)| d.sample(r, c).unwrap())
            .sum::<f64>()
            / 4.0;
        assert!((mid - avg).abs() < 1e-6);
        assert!(matches!(
            d.elevation_amsl_m(36.7, -84.3),
            Err(TerrainError::NotCovered { .. })
        ));
    }

    /// Every point of a rectangle stands in a column at least as high as the ground there,
    /// and the columns are no higher than the cells' samples (geographic and UTM grids).
    #[test]
    fn columns_cover_the_ground_from_above() {
        let utm = {
            let (rows, cols) = (120, 150);
            let v = (0..rows * cols)
                .map(|i| {
                    let (r, c) = ((i / cols) as f32, (i % cols) as f32);
                    300.0 + 60.0 * (r / 9.0).sin() * (c / 11.0).cos()
                })
                .collect();
            let georef = Georef::Utm {
                zone: 16,
                north: true,
                origin: [741_000.0, 4_051_000.0],
                step: [30.0, 30.0],
            };
            Dem::new(rows, cols, v, georef).unwrap()
        };
        let cases = [
            (
                hills(),
                frame(36.55, -84.25),
                [-900.0, 1200.0],
                [-700.0, 1500.0],
            ),
            (
                utm,
                frame(36.555, -84.28),
                [-1000.0, 800.0],
                [-600.0, 900.0],
            ),
        ];
        for (dem, f, north, east) in cases {
            let t = Terrain::new(dem, f).unwrap();
            let cols = t.columns(north, east, 10.0).unwrap();
            assert!(cols.len() > 100, "{} columns", cols.len());
            let mut rng = 0x2545_f491_4f6c_dd1du64;
            let mut unit = || {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng >> 11) as f64 / (1u64 << 53) as f64
            };
            let mut slack = f64::INFINITY;
            for _ in 0..5000 {
                let p = [
                    north[0] + (north[1] - north[0]) * unit(),
                    east[0] + (east[1] - east[0]) * unit(),
                ];
                let g = t.ground_m(p[0], p[1]).unwrap();
                let top = cols
                    .iter()
                    .filter(|c| {
                        (c.north_m[0]..=c.north_m[1]).contains(&p[0])
                            && (c.east_m[0]..=c.east_m[1]).contains(&p[1])
                    })
                    .map(|c| c.top_m)
                    .fold(f64::NEG_INFINITY, f64::max);
                assert!(top >= g, "at {p:?}: column top {top} under the ground {g}");
                slack = slack.min(top - g);
            }
            // Tight somewhere: the columns are the ground's own heights, not a coarse bound.
            assert!(slack < 0.5, "closest column is {slack} m above the ground");
            // Split finer, the columns hug the ground closer: never higher on average.
            let coarse = t.columns(north, east, 1e9).unwrap();
            let mean = |c: &[Column]| {
                c.iter()
                    .map(|c| c.top_m * (c.north_m[1] - c.north_m[0]) * (c.east_m[1] - c.east_m[0]))
                    .sum::<f64>()
                    / c.iter()
                        .map(|c| (c.north_m[1] - c.north_m[0]) * (c.east_m[1] - c.east_m[0]))
                        .sum::<f64>()
            };
            assert!(coarse.len() < cols.len());
            assert!(
                mean(&cols) < mean(&coarse),
                "{} vs {}",
                mean(&cols),
                mean(&coarse)
            );
            let (lo, hi) = t.dem().range_m().unwrap();
            for c in &cols {
                let amsl = t.amsl_m(c.top_m);
                assert!(amsl >= lo && amsl <= hi + 0.02, "{amsl} outside {lo}..{hi}");
            }
        }
        // The ground's extremes over rectangles against dense samples.
        let t = Terrain::new(hills(), frame(36.55, -84.25)).unwrap();
        for (north, east) in [
            ([10.0, 13.0], [-4.0, 2.0]),
            ([-300.0, -120.0], [250.0, 700.0]),
            ([500.0, 500.5], [500.0, 640.0]),
        ] {
            let [lo, hi] = t.ground_extremes_m_in(north, east).unwrap();
            let (mut dlo, mut dhi) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..=200 {
                for j in 0..=200 {
                    let n = north[0] + (north[1] - north[0]) * i as f64 / 200.0;
                    let e = east[0] + (east[1] - east[0]) * j as f64 / 200.0;
                    let g = t.ground_m(n, e).unwrap();
                    dlo = dlo.min(g);
                    dhi = dhi.max(g);
                }
            }
            assert!(lo <= dlo && dlo - lo < 0.1, "low {lo} vs sampled {dlo}");
            assert!(hi >= dhi && hi - dhi < 0.1, "high {hi} vs sampled {dhi}");
        }
        let t = Terrain::new(hills(), frame(36.55, -84.25)).unwrap();
        assert!(matches!(
            t.columns([0.0, 50_000.0], [0.0, 10.0], 10.0),
            Err(TerrainError::NotCovered { .. })
        ));
    }

    #[test]
    fn followed_routes_clear_the_densely_sampled_ground() {
        let d = hills();
        let t = Terrain::new(d.clone(), frame(36.55, -84.25)).unwrap();
        let routes: [&[[f64; 2]]; 4] = [
            &[[0.0, 0.0], [3000.0, 2500.0]],
            // Repeated points: legs of no length.
            &[
                [0.0, 0.0],
                [0.0, 0.0],
                [500.0, 500.0],
                [500.0, 500.0],
                [-800.0, 900.0],
            ],
            &[
                [-4000.0, -3500.0],
                [0.0, 0.0],
                [3500.0, -1000.0],
                [4000.0, 4000.0],
            ],
            &[[100.0, 100.0], [101.0, 100.0]],
        ];
        for (k, route) in routes.iter().enumerate() {
            for agl in [0.0, 12.5, 60.0] {
                let out = t.follow(route, agl, [0.3, 0.15]).unwrap();
                t.check_clearance(&out, agl).unwrap();
                // Dense samples every 0.5 m against the bilinear ground itself.
                let mut worst = f64::INFINITY;
                let mut excess = f64::NEG_INFINITY;
                for w in out.windows(2) {
                    let len = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
                    let n = (len / 0.5).ceil().max(1.0) as usize;
                    for i in 0..=n {
                        let u = i as f64 / n as f64;
                        let p: Vec<f64> =
                            (0..3).map(|c| w[0][c] + (w[1][c] - w[0][c]) * u).collect();
                        let clearance = p[2] - t.ground_m(p[0], p[1]).unwrap();
                        worst = worst.min(clearance);
                        excess = excess.max(clearance);
                    }
                    // Slopes within the limits.
                    if len > 1e-9 {
                        let slope = (w[1][2] - w[0][2]) / len;
                        assert!(
                            (-0.15 - 1e-9..=0.3 + 1e-9).contains(&slope),
                            "route {k}: slope {slope}"
                        );
                    }
                }
                assert!(worst >= agl - 1e-6, "route {k} agl {agl}: {worst}");
                // Route vertices are kept, in order.
                for v in route.iter() {
                    assert!(
                        out.iter()
                            .any(|p| (p[0] - v[0]).abs() < 1e-9 && (p[1] - v[1]).abs() < 1e-9)
                    );
                }
                assert!(excess.is_finite());
            }
        }
    }

    #[test]
    fn a_route_off_the_dem_is_refused_naming_where() {
        let t = Terrain::new(hills(), frame(36.55, -84.25)).unwrap();
        let e = t
            .follow(&[[0.0, 0.0], [20_000.0, 0.0]], 30.0, [0.3, 0.15])
            .unwrap_err();
        assert!(e.to_string().contains("on the route at N"), "{e}");
        let e = Terrain::new(hills(), frame(37.5, -84.25)).unwrap_err();
        assert!(e.to_string().contains("the map's home"), "{e}");
    }

    #[test]
    fn a_route_too_low_is_found() {
        let t = Terrain::new(hills(), frame(36.55, -84.25)).unwrap();
        let mut out = t
            .follow(&[[0.0, 0.0], [2000.0, 0.0]], 30.0, [0.3, 0.15])
            .unwrap();
        let k = out.len() / 2;
        out[k][2] -= 5.0;
        assert!(matches!(
            t.check_clearance(&out, 30.0),
            Err(TerrainError::TooLow { .. })
        ));
    }

    #[test]
    fn hgt_names_and_sizes() {
        let bytes = vec![0u8; 1201 * 1201 * 2];
        let d = parse_hgt("tiles/N36W085.hgt", &bytes).unwrap();
        assert_eq!(d.size(), (1201, 1201));
        assert!(matches!(d.georef(), Georef::Geographic { origin, .. } if origin == [-85.0, 37.0]));
        assert!(
            parse_hgt("dem.hgt", &bytes)
                .unwrap_err()
                .to_string()
                .contains("N37W122")
        );
        assert!(
            parse_hgt("N36W085.hgt", &bytes[..100])
                .unwrap_err()
                .to_string()
                .contains("100 bytes")
        );
        let mut void = bytes.clone();
        void[0] = 0x80;
        void[1] = 0x00;
        let d = parse_hgt("S01E010.hgt", &void).unwrap();
        assert_eq!(d.sample(0, 0), None);
        assert!(matches!(
            d.elevation_amsl_m(0.0, 10.0),
            Err(TerrainError::Void { .. })
        ));
    }

    #[test]
    fn garbage_is_refused_without_panicking() {
        for bytes in [&b"II*\0garbage"[..], b"MM\0*", b"", b"not a dem"] {
            assert!(parse_dem("x.tif", bytes).is_err());
        }
    }
}

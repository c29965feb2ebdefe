//! The FCND `colliders.csv` format.
//!
//! ```text
//! lat0 37.792480, lon0 -122.397450
//! posX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ
//! -310.2389,-439.2315,85.5,5,5,85.5
//! ```
//! `posX` is north, `posY` east, `posZ` up, all in metres about the home; the half sizes are
//! non-negative. The header line is optional (a numeric line 2 is read as a box).

use crate::{ParseError, numbered_lines, shown};

/// The geodetic home of a map: the origin of its local NED frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeodeticHome {
    /// Latitude in degrees (WGS84), in [-90, 90].
    pub lat_deg: f64,
    /// Longitude in degrees (WGS84), in [-180, 180].
    pub lon_deg: f64,
}

/// An axis-aligned obstacle box in the local frame (north, east, up), centre and half sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObstacleBox {
    /// Centre, metres north of home.
    pub north_m: f64,
    /// Centre, metres east of home.
    pub east_m: f64,
    /// Centre, metres above home.
    pub up_m: f64,
    /// Half extent along north, metres (≥ 0).
    pub half_north_m: f64,
    /// Half extent along east, metres (≥ 0).
    pub half_east_m: f64,
    /// Half extent along up, metres (≥ 0).
    pub half_up_m: f64,
}

impl ObstacleBox {
    /// A box from the six numbers of a `colliders.csv` row, in the file's column order: centre
    /// north, east, up, then half sizes north, east, up (metres).
    pub fn from_row(
        [north_m, east_m, up_m, half_north_m, half_east_m, half_up_m]: [f64; 6],
    ) -> Self {
        Self {
            north_m,
            east_m,
            up_m,
            half_north_m,
            half_east_m,
            half_up_m,
        }
    }
    /// Height of the top face above home, metres.
    pub fn top_m(&self) -> f64 {
        self.up_m + self.half_up_m
    }
    /// Height of the bottom face above home, metres.
    pub fn bottom_m(&self) -> f64 {
        self.up_m - self.half_up_m
    }

    /// The box grown by `margin_m` on every side (the obstacle a vehicle keeping `margin_m`
    /// away must avoid), as its lowest and highest corners `[north, east, up]`: the one
    /// definition of "grown by the margin" the grid, the 3D world, the roadmap and the pictures
    /// share, so they agree to the last bit.
    ///
    /// ```
    /// use skyplan_map::colliders::ObstacleBox;
    /// let b = ObstacleBox::from_row([10.0, 20.0, 5.0, 2.0, 3.0, 5.0]);
    /// assert_eq!(b.grown(1.0), ([7.0, 16.0, -1.0], [13.0, 24.0, 11.0]));
    /// ```
    pub fn grown(&self, margin_m: f64) -> ([f64; 3], [f64; 3]) {
        (
            [
                self.north_m - self.half_north_m - margin_m,
                self.east_m - self.half_east_m - margin_m,
                self.up_m - self.half_up_m - margin_m,
            ],
            [
                self.north_m + self.half_north_m + margin_m,
                self.east_m + self.half_east_m + margin_m,
                self.up_m + self.half_up_m + margin_m,
            ],
        )
    }

    /// Whether the box grown by `margin_m` meets the horizontal plane at `alt_m` (open interval:
    /// a plane that only touches its grown top or bottom face flies clear).
    ///
    /// ```
    /// use skyplan_map::colliders::ObstacleBox;
    /// let b = ObstacleBox::from_row([0.0, 0.0, 10.0, 1.0, 1.0, 10.0]); // 0 to 20 m
    /// assert!(b.meets_altitude(24.0, 5.0) && !b.meets_altitude(25.0, 5.0));
    /// ```
    pub fn meets_altitude(&self, alt_m: f64, margin_m: f64) -> bool {
        self.top_m() + margin_m > alt_m && self.bottom_m() - margin_m < alt_m
    }
}

/// A parsed colliders map: a home and at least one box.
#[derive(Debug, Clone, PartialEq)]
pub struct CollidersMap {
    /// The geodetic home from line 1.
    pub home: GeodeticHome,
    /// The obstacle boxes, in file order.
    pub boxes: Vec<ObstacleBox>,
}

/// The column names of a colliders file, in order.
pub const COLUMNS: [&str; 6] = [
    "posX",
    "posY",
    "posZ",
    "halfSizeX",
    "halfSizeY",
    "halfSizeZ",
];

/// Parses the text of a `colliders.csv` file.
///
/// Rejects a missing or garbled home line, a wrong column count, non-numbers, NaN or infinite
/// values, negative half sizes and a map without boxes. Blank lines are skipped; CRLF is accepted.
///
/// ```
/// use skyplan_map::colliders::parse_colliders;
/// let err = parse_colliders("lat0 37.7, lon0 -122.3\n1,2,3,4,-5,6\n").unwrap_err();
/// assert_eq!((err.line, err.column), (2, Some(5)));
/// assert!(err.to_string().contains("halfSizeY"));
/// ```
pub fn parse_colliders(text: &str) -> Result<CollidersMap, ParseError> {
    let mut lines = numbered_lines(text);
    let home = match lines.next() {
        Some((_, first)) => parse_home(first)?,
        None => {
            return Err(ParseError::new(
                1,
                None,
                "home line",
                "the file is empty; expected `lat0 <deg>, lon0 <deg>` on line 1",
            ));
        }
    };
    let mut boxes = Vec::new();
    for (line_no, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        if line_no == 2 && looks_like_header(line) {
            check_header(line)?;
            continue;
        }
        boxes.push(parse_box(line_no, line)?);
    }
    if boxes.is_empty() {
        return Err(ParseError::new(
            0,
            None,
            "obstacles",
            "the map holds no obstacle boxes; expected rows `posX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ` after the header",
        ));
    }
    Ok(CollidersMap { home, boxes })
}

/// Parses hidden obstacles: boxes in the colliders format whose `lat0/lon0` line must be
/// `map_home` (the boxes are placed in the map's frame). The error is the parse error, or why
/// the homes differ.
pub fn parse_hidden(text: &str, map_home: &GeodeticHome) -> Result<Vec<ObstacleBox>, String> {
    let hidden = parse_colliders(text).map_err(|e| e.to_string())?;
    let same = (hidden.home.lat_deg - map_home.lat_deg).abs() < 1e-9
        && (hidden.home.lon_deg - map_home.lon_deg).abs() < 1e-9;
    if !same {
        return Err(format!(
            "line 1: its home lat0 {}, lon0 {} is not the map's home lat0 {}, lon0 {} (hidden obstacles are placed in the map's frame: write the map's home on line 1)",
            hidden.home.lat_deg, hidden.home.lon_deg, map_home.lat_deg, map_home.lon_deg
        ));
    }
    Ok(hidden.boxes)
}

fn parse_home(line: &str) -> Result<GeodeticHome, ParseError> {
    const WANT: &str = "expected `lat0 <deg>, lon0 <deg>`";
    let parts: Vec<&str> = line.split(',').collect();
    if parts.len() != 2 {
        return Err(ParseError::new(
            1,
            None,
            "home line",
            format!("{WANT}, found {}", shown(line)),
        ));
    }
    let lat_deg = parse_home_field(parts[0], "lat0", 1, 90.0)?;
    let lon_deg = parse_home_field(parts[1], "lon0", 2, 180.0)?;
    Ok(GeodeticHome { lat_deg, lon_deg })
}

fn parse_home_field(part: &str, key: &str, column: usize, limit: f64) -> Result<f64, ParseError> {
    let mut words = part.split_whitespace();
    let (Some(found_key), Some(value), None) = (words.next(), words.next(), words.next()) else {
        return Err(ParseError::new(
            1,
            Some(column),
            key,
            format!("expected `{key} <degrees>`, found {}", shown(part.trim())),
        ));
    };
    if found_key != key {
        return Err(ParseError::new(
            1,
            Some(column),
            key,
            format!("expected the key `{key}`, found {}", shown(found_key)),
        ));
    }
    let deg = parse_finite(value).map_err(|what| {
        ParseError::new(
            1,
            Some(column),
            key,
            format!("expected {what} degrees, found {}", shown(value)),
        )
    })?;
    if deg.abs() > limit {
        return Err(ParseError::new(
            1,
            Some(column),
            key,
            format!("expected degrees within ±{limit}, found {deg}"),
        ));
    }
    Ok(deg)
}

fn looks_like_header(line: &str) -> bool {
    let first = line.split(',').next().unwrap_or("").trim();
    first.parse::<f64>().is_err()
}

fn check_header(line: &str) -> Result<(), ParseError> {
    let names: Vec<&str> = line.split(',').map(str::trim).collect();
    for (i, want) in COLUMNS.iter().enumerate() {
        let found = names.get(i).copied().unwrap_or("");
        if !found.eq_ignore_ascii_case(want) {
            return Err(ParseError::new(
                2,
                Some(i + 1),
                "header",
                format!(
                    "expected the header `{}`; column {} should be `{want}`, found {}",
                    COLUMNS.join(","),
                    i + 1,
                    shown(found)
                ),
            ));
        }
    }
    if names.len() != COLUMNS.len() {
        return Err(ParseError::new(
            2,
            Some(COLUMNS.len() + 1),
            "header",
            format!("expected {} columns, found {}", COLUMNS.len(), names.len()),
        ));
    }
    Ok(())
}

/// Largest |position| or half size of a box, metres: a map reaches 1000 km from its home at most.
pub const MAX_EXTENT_M: f64 = 1.0e6;

fn parse_box(line_no: usize, line: &str) -> Result<ObstacleBox, ParseError> {
    let fields: Vec<&str> = line.split(',').collect();
    if fields.len() != COLUMNS.len() {
        return Err(ParseError::new(
            line_no,
            Some(fields.len().min(COLUMNS.len() + 1)),
            "row",
            format!(
                "expected {} comma-separated numbers ({}), found {} field(s)",
                COLUMNS.len(),
                COLUMNS.join(","),
                fields.len()
            ),
        ));
    }
    let mut v = [0.0_f64; 6];
    for (i, (field, name)) in fields.iter().zip(COLUMNS).enumerate() {
        let token = field.trim();
        v[i] = parse_finite(token).map_err(|what| {
            ParseError::new(
                line_no,
                Some(i + 1),
                name,
                format!("expected {what} metres, found {}", shown(token)),
            )
        })?;
        if v[i].abs() > MAX_EXTENT_M {
            return Err(ParseError::new(
                line_no,
                Some(i + 1),
                name,
                format!(
                    "expected metres within ±{MAX_EXTENT_M} (1000 km of the home), found {}",
                    shown(token)
                ),
            ));
        }
        if i >= 3 && v[i] < 0.0 {
            return Err(ParseError::new(
                line_no,
                Some(i + 1),
                name,
                format!("expected a half size ≥ 0 metres, found {}", v[i]),
            ));
        }
    }
    Ok(ObstacleBox::from_row(v))
}

/// Parses a finite float; the error says what kind of number was expected.
pub(crate) fn parse_finite(token: &str) -> Result<f64, &'static str> {
    match token.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err("a finite number (not NaN or infinity) of"),
        Err(_) => Err("a number of"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HOME: &str = "lat0 37.792480, lon0 -122.397450\n";
    const HEADER: &str = "posX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n";

    fn err(text: &str) -> ParseError {
        parse_colliders(text).expect_err("input should be rejected")
    }

    #[test]
    fn a_box_a_thousand_km_away_is_refused_naming_line_and_field() {
        let e = err(&format!("{HOME}{HEADER}1,2,3,4,5,6\n1e308,0,10,5,5,5\n"));
        assert_eq!((e.line, e.column, e.field.as_str()), (4, Some(1), "posX"));
        assert!(e.message.contains("within ±1000000"), "{e}");
        let e = err(&format!("{HOME}{HEADER}0,0,0,5,2e6,5\n"));
        assert_eq!(
            (e.line, e.column, e.field.as_str()),
            (3, Some(5), "halfSizeY")
        );
        let ok = parse_colliders(&format!("{HOME}{HEADER}-1e6,1e6,0,5,5,5\n")).unwrap();
        assert_eq!(ok.boxes[0].north_m, -1e6);
    }

    #[test]
    fn parses_home_header_and_boxes_with_crlf() {
        let text = format!("{HOME}{HEADER}1,2,3,4,5,6\r\n\r\n-1.5,2e1,0,0,0,0\r\n");
        let map = parse_colliders(&text).unwrap();
        assert_eq!(
            map.home,
            GeodeticHome {
                lat_deg: 37.79248,
                lon_deg: -122.39745
            }
        );
        assert_eq!(map.boxes.len(), 2);
        assert_eq!(map.boxes[1].east_m, 20.0);
        assert_eq!(map.boxes[0].bottom_m(), -3.0);
    }

    #[test]
    fn header_is_optional() {
        let map = parse_colliders(&format!("{HOME}1,2,3,4,5,6\n")).unwrap();
        assert_eq!(map.boxes.len(), 1);
    }

    #[test]
    fn rejects_each_kind_of_bad_input_at_the_right_place() {
        let cases: Vec<(String, usize, Option<usize>, &str)> = vec![
            (String::new(), 1, None, "empty"),
            (
                "latitude 37, lon0 -122\n1,2,3,4,5,6\n".into(),
                1,
                Some(1),
                "lat0",
            ),
            (
                "lat0 37\n1,2,3,4,5,6\n".into(),
                1,
                None,
                "lat0 <deg>, lon0 <deg>",
            ),
            (
                "lat0 95, lon0 -122\n1,2,3,4,5,6\n".into(),
                1,
                Some(1),
                "±90",
            ),
            (
                "lat0 37, lon0 abc\n1,2,3,4,5,6\n".into(),
                1,
                Some(2),
                "a number",
            ),
            (
                format!("{HOME}posX,posY,posZ,halfSizeX,halfSizeY\n1,2,3,4,5,6\n"),
                2,
                Some(6),
                "should be `halfSizeZ`",
            ),
            (
                format!("{HOME}{HEADER}1,2,3,4,5\n"),
                3,
                Some(5),
                "6 comma-separated",
            ),
            (
                format!("{HOME}{HEADER}1,2,3,4,5,6,7\n"),
                3,
                Some(7),
                "found 7",
            ),
            (format!("{HOME}{HEADER}1,2,x,4,5,6\n"), 3, Some(3), "posZ"),
            (
                format!("{HOME}{HEADER}1,2,3,NaN,5,6\n"),
                3,
                Some(4),
                "finite",
            ),
            (
                format!("{HOME}{HEADER}1,inf,3,4,5,6\n"),
                3,
                Some(2),
                "finite",
            ),
            (format!("{HOME}{HEADER}1,2,3,4,5,-6\n"), 3, Some(6), "≥ 0"),
            (format!("{HOME}{HEADER}"), 0, None, "no obstacle boxes"),
        ];
        for (text, line, column, needle) in cases {
            let e = err(&text);
            assert_eq!((e.line, e.column), (line, column), "{text:?} -> {e}");
            assert!(
                e.to_string().contains(needle),
                "{text:?} -> {e} should mention {needle}"
            );
        }
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_arbitrary_text(text in "\\PC{0,200}") {
            let _ = parse_colliders(&text);
        }

        #[test]
        fn never_panics_on_near_valid_text(rows in proptest::collection::vec("[-0-9.,eEnaif ]{0,30}", 0..6)) {
            let text = format!("{HOME}{HEADER}{}", rows.join("\n"));
            let _ = parse_colliders(&text);
        }
    }
}

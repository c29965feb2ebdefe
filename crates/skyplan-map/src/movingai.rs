//! MovingAI / GPPC benchmark formats (<https://movingai.com/benchmarks/formats.html>).
//!
//! A `.map` file is `type octile`, `height H`, `width W`, `map`, then `H` rows of `W` characters;
//! `.`, `G` and `S` are passable, `@`, `O`, `T` and `W` are blocked. A `.scen` file is `version 1`
//! followed by tab-separated rows `bucket map width height start_x start_y goal_x goal_y
//! optimal_length`, where x is the column and y the row, counted from the top-left.

use crate::{ParseError, colliders::parse_finite, numbered_lines, shown};

/// A MovingAI grid: `passable[y * width + x]`, row 0 at the top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MovingAiMap {
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// Row-major passability, row 0 first.
    pub passable: Vec<bool>,
}

/// One scenario (query) of a `.scen` file.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// 1-based line of the scenario in its file.
    pub line: usize,
    /// Difficulty bucket (roughly optimal length / 4).
    pub bucket: u32,
    /// Map file name as written in the scenario.
    pub map: String,
    /// Start column.
    pub start_x: usize,
    /// Start row.
    pub start_y: usize,
    /// Goal column.
    pub goal_x: usize,
    /// Goal row.
    pub goal_y: usize,
    /// Published optimal octile length without corner cutting.
    pub optimal_length: f64,
}

const HEADER_KEYS: [&str; 4] = ["type", "height", "width", "map"];

/// Parses a MovingAI `.map` file.
///
/// ```
/// let text = "type octile\nheight 2\nwidth 3\nmap\n.@.\n..T\n";
/// let map = skyplan_map::movingai::parse_map(text)?;
/// assert_eq!((map.width, map.height), (3, 2));
/// assert_eq!(map.passable, vec![true, false, true, true, true, false]);
/// # Ok::<(), skyplan_map::ParseError>(())
/// ```
pub fn parse_map(text: &str) -> Result<MovingAiMap, ParseError> {
    let mut lines = numbered_lines(text);
    let mut width = 0usize;
    let mut height = 0usize;
    for key in HEADER_KEYS {
        let Some((no, line)) = lines.next() else {
            return Err(ParseError::new(
                0,
                None,
                key,
                format!("the file ends before the `{key}` header line"),
            ));
        };
        let mut words = line.split_whitespace();
        let found = words.next().unwrap_or("");
        if found != key {
            return Err(ParseError::new(
                no,
                Some(1),
                key,
                format!("expected the header `{key}`, found {}", shown(line)),
            ));
        }
        let value = words.next();
        match key {
            "type" if value != Some("octile") => {
                return Err(ParseError::new(
                    no,
                    Some(6),
                    key,
                    format!("expected `type octile`, found {}", shown(line)),
                ));
            }
            "height" | "width" => {
                let n = value
                    .and_then(|v| v.parse::<usize>().ok())
                    .filter(|&n| n > 0 && n <= 1 << 15);
                let Some(n) = n else {
                    return Err(ParseError::new(
                        no,
                        Some(key.len() + 2),
                        key,
                        format!(
                            "expected a whole number of cells in 1..=32768, found {}",
                            shown(line)
                        ),
                    ));
                };
                if key == "height" {
                    height = n
                } else {
                    width = n
                }
            }
            _ => {}
        }
    }
    // Capacity bounded by the text itself: a lying header cannot make us allocate gigabytes.
    let mut passable = Vec::with_capacity((width * height).min(text.len()));
    for y in 0..height {
        let Some((no, row)) = lines.next() else {
            return Err(ParseError::new(
                0,
                None,
                "map rows",
                format!("expected {height} rows, found {y}"),
            ));
        };
        if row.chars().count() != width {
            return Err(ParseError::new(
                no,
                None,
                "map row",
                format!("expected {width} characters, found {}", row.chars().count()),
            ));
        }
        for (x, c) in row.chars().enumerate() {
            passable.push(match c {
                '.' | 'G' | 'S' => true,
                '@' | 'O' | 'T' | 'W' => false,
                other => {
                    return Err(ParseError::new(
                        no,
                        Some(x + 1),
                        "map cell",
                        format!("expected one of `.GS@OTW`, found {other:?}"),
                    ));
                }
            });
        }
    }
    Ok(MovingAiMap {
        width,
        height,
        passable,
    })
}

/// Parses a MovingAI `.scen` file (version 1).
///
/// ```
/// let text = "version 1\n0\tm.map\t3\t2\t0\t0\t2\t1\t2.41421356\n";
/// let scen = skyplan_map::movingai::parse_scen(text)?;
/// assert_eq!(scen[0].goal_x, 2);
/// # Ok::<(), skyplan_map::ParseError>(())
/// ```
pub fn parse_scen(text: &str) -> Result<Vec<Scenario>, ParseError> {
    let mut lines = numbered_lines(text);
    match lines.next() {
        Some((_, l))
            if l.split_whitespace().eq(["version", "1"])
                || l.split_whitespace().eq(["version", "1.0"]) => {}
        Some((_, l)) => {
            return Err(ParseError::new(
                1,
                Some(1),
                "version",
                format!("expected `version 1`, found {}", shown(l)),
            ));
        }
        None => {
            return Err(ParseError::new(
                1,
                None,
                "version",
                "the file is empty; expected `version 1`",
            ));
        }
    }
    const NAMES: [&str; 9] = [
        "bucket",
        "map",
        "width",
        "height",
        "start_x",
        "start_y",
        "goal_x",
        "goal_y",
        "optimal_length",
    ];
    let mut out = Vec::new();
    for (no, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split('\t').map(str::trim).collect();
        if f.len() != NAMES.len() {
            return Err(ParseError::new(
                no,
                None,
                "scenario",
                format!(
                    "expected {} tab-separated fields ({}), found {}",
                    NAMES.len(),
                    NAMES.join(" "),
                    f.len()
                ),
            ));
        }
        let int = |i: usize| {
            f[i].parse::<usize>().map_err(|_| {
                ParseError::new(
                    no,
                    Some(i + 1),
                    NAMES[i],
                    format!("expected a whole number, found {}", shown(f[i])),
                )
            })
        };
        let bucket = int(0)?;
        let (sx, sy, gx, gy) = (int(4)?, int(5)?, int(6)?, int(7)?);
        let optimal_length = parse_finite(f[8]).map_err(|what| {
            ParseError::new(
                no,
                Some(9),
                NAMES[8],
                format!("expected {what} cells, found {}", shown(f[8])),
            )
        })?;
        out.push(Scenario {
            line: no,
            bucket: u32::try_from(bucket).unwrap_or(u32::MAX),
            map: f[1].to_string(),
            start_x: sx,
            start_y: sy,
            goal_x: gx,
            goal_y: gy,
            optimal_length,
        });
    }
    Ok(out)
}

/// A map as the text of a MovingAI `.map` file (`type octile`; `.` free, `@` blocked), which
/// [`parse_map`] reads back to the same map.
///
/// ```
/// use skyplan_map::movingai::{parse_map, to_map_text};
/// let text = "type octile\nheight 2\nwidth 3\nmap\n.@.\n..@\n";
/// assert_eq!(to_map_text(&parse_map(text)?), text);
/// # Ok::<(), skyplan_map::ParseError>(())
/// ```
pub fn to_map_text(map: &MovingAiMap) -> String {
    let mut out = format!(
        "type octile\nheight {}\nwidth {}\nmap\n",
        map.height, map.width
    );
    out.reserve(map.passable.len() + map.height);
    for row in map.passable.chunks(map.width.max(1)) {
        out.extend(row.iter().map(|&p| if p { '.' } else { '@' }));
        out.push('\n');
    }
    out
}

/// Scenarios as the text of a MovingAI `.scen` file (`version 1`, tab-separated rows, lengths
/// with 8 decimals as published), for a map of `width` × `height`; [`parse_scen`] reads it back.
///
/// ```
/// use skyplan_map::movingai::{parse_scen, to_scen_text};
/// let text = "version 1\n0\tm.map\t3\t2\t0\t0\t2\t1\t2.41421356\n";
/// assert_eq!(to_scen_text(&parse_scen(text)?, 3, 2), text);
/// # Ok::<(), skyplan_map::ParseError>(())
/// ```
pub fn to_scen_text(scenarios: &[Scenario], width: usize, height: usize) -> String {
    let mut out = String::from("version 1\n");
    for s in scenarios {
        out.push_str(&format!(
            "{}\t{}\t{width}\t{height}\t{}\t{}\t{}\t{}\t{:.8}\n",
            s.bucket, s.map, s.start_x, s.start_y, s.goal_x, s.goal_y, s.optimal_length
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_errors_name_the_place() {
        let e = parse_map("type octile\nheight 2\nwidth 2\nmap\n..\n.x\n").unwrap_err();
        assert_eq!((e.line, e.column), (6, Some(2)));
        let e = parse_map("type octile\nheight 2\nwidth 2\nmap\n..\n").unwrap_err();
        assert!(e.to_string().contains("expected 2 rows, found 1"), "{e}");
        let e = parse_map("type octile\nheight two\nwidth 2\nmap\n").unwrap_err();
        assert_eq!(e.line, 2);
        let e = parse_map("type octile\nheight 1\nwidth 3\nmap\n..\n").unwrap_err();
        assert!(e.to_string().contains("expected 3 characters"), "{e}");
    }

    #[test]
    fn scen_errors_name_the_place() {
        let e = parse_scen("version 1\n0\tm\t1\t1\t0\t0\t0\tz\t1\n").unwrap_err();
        assert_eq!((e.line, e.column, e.field.as_str()), (2, Some(8), "goal_y"));
        let e = parse_scen("version 2\n").unwrap_err();
        assert_eq!(e.line, 1);
    }

    proptest::proptest! {
        #[test]
        fn parsers_never_panic(text in "\\PC{0,200}") {
            let _ = parse_map(&text);
            let _ = parse_scen(&text);
        }
    }
}

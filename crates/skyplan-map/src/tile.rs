//! Big test worlds: a colliders map copied K × K ([`tile`]) and the colliders text writer
//! ([`to_colliders_csv`]) that [`parse_colliders`](crate::colliders::parse_colliders) reads back
//! identically.

use crate::colliders::{COLUMNS, CollidersMap};
use std::fmt::Write;

/// The map copied `times × times` times: copy `(i, j)` (`0 ≤ i, j < times`) is shifted
/// `i · pitch_m` north and `j · pitch_m` east; copy `(0, 0)` is the map itself and the home is
/// unchanged. Boxes are in copy order (row of copies by row), each copy in the map's order.
///
/// `times` below 1 counts as 1. The result holds `times² ×` the boxes, so the caller bounds
/// `times`. With `pitch_m` at least the map's extent the copies do not overlap (overlap is
/// allowed). A non-finite `pitch_m` counts as 0.
///
/// ```
/// use skyplan_map::colliders::parse_colliders;
/// use skyplan_map::tile;
/// let map = parse_colliders("lat0 37.7, lon0 -122.4\n10,20,5,2,3,5\n")?;
/// let big = tile(&map, 3, 1000.0);
/// assert_eq!(big.boxes.len(), 9);
/// assert_eq!(big.home, map.home);
/// assert_eq!((big.boxes[5].north_m, big.boxes[5].east_m), (1010.0, 2020.0)); // copy (1, 2)
/// # Ok::<(), skyplan_map::ParseError>(())
/// ```
pub fn tile(map: &CollidersMap, times: u32, pitch_m: f64) -> CollidersMap {
    let times = times.max(1);
    let pitch_m = if pitch_m.is_finite() { pitch_m } else { 0.0 };
    let mut boxes = Vec::with_capacity(map.boxes.len() * times as usize * times as usize);
    for i in 0..times {
        for j in 0..times {
            let (dn, de) = (f64::from(i) * pitch_m, f64::from(j) * pitch_m);
            boxes.extend(map.boxes.iter().map(|b| {
                let mut b = *b;
                b.north_m += dn;
                b.east_m += de;
                b
            }));
        }
    }
    CollidersMap {
        home: map.home,
        boxes,
    }
}

/// The text of a `colliders.csv` file for `map`: the home line, the header, one line per box.
/// Numbers are written in Rust's shortest round-trip form, so
/// [`parse_colliders`](crate::colliders::parse_colliders) returns a map with bit-identical numbers.
///
/// ```
/// use skyplan_map::colliders::parse_colliders;
/// use skyplan_map::to_colliders_csv;
/// let map = parse_colliders("lat0 37.79248, lon0 -122.39745\n-310.2389,-439.2315,85.5,5,5,85.5\n")?;
/// let text = to_colliders_csv(&map);
/// assert_eq!(
///     text,
///     "lat0 37.79248, lon0 -122.39745\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n-310.2389,-439.2315,85.5,5,5,85.5\n"
/// );
/// assert_eq!(parse_colliders(&text)?, map);
/// # Ok::<(), skyplan_map::ParseError>(())
/// ```
pub fn to_colliders_csv(map: &CollidersMap) -> String {
    let mut text = String::with_capacity(64 + 48 * map.boxes.len());
    // Writing to a String cannot fail.
    let _ = writeln!(text, "lat0 {}, lon0 {}", map.home.lat_deg, map.home.lon_deg);
    text.push_str(&COLUMNS.join(","));
    text.push('\n');
    for b in &map.boxes {
        let _ = writeln!(
            text,
            "{},{},{},{},{},{}",
            b.north_m, b.east_m, b.up_m, b.half_north_m, b.half_east_m, b.half_up_m
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colliders::{GeodeticHome, ObstacleBox, parse_colliders};
    use proptest::prelude::*;

    fn bits(map: &CollidersMap) -> Vec<u64> {
        let mut v = vec![map.home.lat_deg.to_bits(), map.home.lon_deg.to_bits()];
        for b in &map.boxes {
            v.extend(
                [
                    b.north_m,
                    b.east_m,
                    b.up_m,
                    b.half_north_m,
                    b.half_east_m,
                    b.half_up_m,
                ]
                .map(f64::to_bits),
            );
        }
        v
    }

    fn finite() -> impl Strategy<Value = f64> {
        prop_oneof![
            -1e6f64..1e6,
            // Every bit pattern the parser accepts (finite, within the map's extent).
            (-crate::colliders::MAX_EXTENT_M..=crate::colliders::MAX_EXTENT_M)
                .prop_map(|x| x * 0.5f64.powi(60)),
            any::<f64>().prop_filter("finite, within the extent", |x| {
                x.abs() <= crate::colliders::MAX_EXTENT_M
            }),
            Just(-0.0),
            Just(f64::MIN_POSITIVE),
            Just(5e-324),
        ]
    }

    fn map() -> impl Strategy<Value = CollidersMap> {
        (
            -90.0f64..=90.0,
            -180.0f64..=180.0,
            proptest::collection::vec(
                (
                    finite(),
                    finite(),
                    finite(),
                    finite().prop_map(f64::abs),
                    finite().prop_map(f64::abs),
                    finite().prop_map(f64::abs),
                ),
                1..20,
            ),
        )
            .prop_map(|(lat_deg, lon_deg, boxes)| CollidersMap {
                home: GeodeticHome { lat_deg, lon_deg },
                boxes: boxes
                    .into_iter()
                    .map(|(n, e, u, hn, he, hu)| ObstacleBox::from_row([n, e, u, hn, he, hu]))
                    .collect(),
            })
    }

    proptest! {
        #[test]
        fn written_maps_read_back_bit_identical(map in map()) {
            let back = parse_colliders(&to_colliders_csv(&map)).expect("written text parses");
            prop_assert_eq!(bits(&back), bits(&map));
        }

        #[test]
        fn tiles_are_shifted_copies(map in map(), times in 0u32..4, pitch in -50.0f64..2000.0) {
            let big = tile(&map, times, pitch);
            let k = times.max(1) as usize;
            let n = map.boxes.len();
            prop_assert_eq!(big.boxes.len(), k * k * n);
            prop_assert_eq!(big.home, map.home);
            for (idx, b) in big.boxes.iter().enumerate() {
                let (copy, orig) = (idx / n, &map.boxes[idx % n]);
                let (i, j) = ((copy / k) as f64, (copy % k) as f64);
                prop_assert_eq!(b.north_m, orig.north_m + i * pitch);
                prop_assert_eq!(b.east_m, orig.east_m + j * pitch);
                prop_assert_eq!(
                    (b.up_m, b.half_north_m, b.half_east_m, b.half_up_m),
                    (orig.up_m, orig.half_north_m, orig.half_east_m, orig.half_up_m)
                );
            }
        }
    }

    #[test]
    fn one_tile_is_the_map_and_the_city_round_trips() {
        let city = parse_colliders(include_str!("../../../data/colliders.csv")).expect("city");
        assert_eq!(tile(&city, 1, 1000.0), city);
        assert_eq!(tile(&city, 0, f64::NAN), city);
        let big = tile(&city, 3, 1000.0);
        let back = parse_colliders(&to_colliders_csv(&big)).expect("tiled city parses");
        assert_eq!(bits(&back), bits(&big));
        assert_eq!(back.boxes.len(), 9 * city.boxes.len());
    }
}

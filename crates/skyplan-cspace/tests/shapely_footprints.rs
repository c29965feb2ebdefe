//! The footprint rasteriser against shapely (GEOS): on random concave polygons with holes, a
//! cell is blocked exactly when shapely's `polygon.distance(cell box) < margin` for a polygon
//! whose band holds the altitude. Shapely's distance is exact (its `buffer` only approximates
//! the disc), so every cell is compared; cells within 1e-9 m of the margin are left out. The
//! same for no-fly zones (exclusion polygons and circles grown by the margin, inclusion
//! polygons and circles shrunk by it).

use skyplan_cspace::{Grid2, GridSpec};
use skyplan_map::colliders::GeodeticHome;
use skyplan_map::footprints::{Footprint, FootprintMap};
use std::io::Write;
use std::process::{Command, Stdio};

/// The Python that has shapely: `SKYPLAN_PYTHON` (set by `.ci/run` to its virtual environment),
/// else `python3`.
fn python() -> String {
    std::env::var("SKYPLAN_PYTHON").unwrap_or_else(|_| "python3".to_string())
}

const SCRIPT: &str = r#"
import sys
import numpy as np
import shapely
from shapely import wkt
lines = sys.stdin.read().split("\n")
n0, e0, c, rows, cols, margin = lines[0].split()
n0, e0, c, margin = float(n0), float(e0), float(c), float(margin)
rows, cols = int(rows), int(cols)
polys = [wkt.loads(l) for l in lines[1:] if l.strip()]
r, k = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
# Cells as boxes in (east, north) = (x, y).
boxes = shapely.box(e0 + k * c, n0 + r * c, e0 + (k + 1) * c, n0 + (r + 1) * c).ravel()
best = np.full(boxes.shape, np.inf)
for p in polys:
    best = np.minimum(best, shapely.distance(p, boxes))
out = np.where(np.abs(best - margin) < 1e-9, "?", np.where(best < margin, "1", "0"))
sys.stdout.write("".join(out.tolist()))
"#;

struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn star(rng: &mut Rng, centre: [f64; 2], r_min: f64, r_max: f64, n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|k| {
            let a = (k as f64 + 0.8 * rng.unit()) / n as f64 * std::f64::consts::TAU;
            let r = r_min + (r_max - r_min) * rng.unit();
            [centre[0] + r * a.sin(), centre[1] + r * a.cos()]
        })
        .collect()
}

fn random_map(seed: u64) -> FootprintMap {
    let mut rng = Rng(seed | 1);
    let footprints = (0..15)
        .map(|i| {
            let centre = [80.0 * rng.unit(), 80.0 * rng.unit()];
            let n = 3 + (rng.unit() * 20.0) as usize;
            let mut rings = vec![star(&mut rng, centre, 5.0, 16.0, n)];
            if rng.unit() < 0.7 {
                let holes = 3 + (rng.unit() * 8.0) as usize;
                rings.push(star(&mut rng, centre, 1.0, 4.5, holes));
            }
            let min_height_m = if rng.unit() < 0.25 { 40.0 } else { 0.0 };
            Footprint {
                feature: i,
                rings,
                min_height_m,
                height_m: min_height_m + 5.0 + 30.0 * rng.unit(),
            }
        })
        .collect();
    FootprintMap {
        home: GeodeticHome {
            lat_deg: 37.7925,
            lon_deg: -122.3975,
        },
        footprints,
        default_heights: 0,
    }
}

fn wkt(f: &Footprint) -> String {
    // shapely's x is east, y north.
    let ring = |r: &Vec<[f64; 2]>| {
        let pts: Vec<String> = r
            .iter()
            .chain(r.first())
            .map(|p| format!("{:.17} {:.17}", p[1], p[0]))
            .collect();
        format!("({})", pts.join(", "))
    };
    let rings: Vec<String> = f.rings.iter().map(ring).collect();
    format!("POLYGON ({})", rings.join(", "))
}

#[test]
#[ignore = "needs SKYPLAN_PYTHON with shapely (.ci/run's virtual environment has it)"]
fn rasteriser_matches_shapely_distance() {
    let (mut compared, mut skipped, mut blocked) = (0usize, 0usize, 0usize);
    for seed in 1..=8u64 {
        let map = random_map(seed * 104_729);
        let margin_m = [0.5, 1.0, 2.5, 4.0][seed as usize % 4];
        let cell_m = [1.0, 0.5, 2.0, 0.7][(seed as usize / 2) % 4];
        let spec = GridSpec {
            alt_m: 20.0,
            safety_m: margin_m,
            cell_m,
        };
        let grid = Grid2::from_footprints(&map, spec).unwrap();
        let f = grid.frame();
        let mut input = format!(
            "{} {} {} {} {} {}\n",
            f.origin_north_m,
            f.origin_east_m,
            f.cell_m,
            grid.rows(),
            grid.cols(),
            margin_m
        );
        for fp in map
            .footprints
            .iter()
            .filter(|fp| fp.meets_altitude(spec.alt_m, margin_m))
        {
            input.push_str(&wkt(fp));
            input.push('\n');
        }
        let want = run_python(SCRIPT, &input);
        assert_eq!(want.len(), grid.len());
        for (i, w) in want.bytes().enumerate() {
            let got = grid.blocked_cells()[i];
            match w {
                b'?' => skipped += 1,
                b'1' | b'0' => {
                    assert_eq!(
                        got,
                        w == b'1',
                        "seed {seed}: cell {:?} (margin {margin_m} m, cell {cell_m} m)",
                        grid.cell(i)
                    );
                    compared += 1;
                    blocked += usize::from(got);
                }
                _ => panic!("unexpected output from python"),
            }
        }
    }
    println!(
        "compared {compared} cells with shapely ({blocked} blocked), {skipped} on the margin left out"
    );
    assert!(compared > 100_000 && blocked > 10_000 && skipped < compared / 1000);
}

/// No-fly zones against shapely: each line is `kind wkt` with kind `ex` (exclusion polygon:
/// `distance < margin`), `exc r` (exclusion circle, the WKT its centre: `distance < r +
/// margin`), `in` (inclusion polygon: blocked when the box is not inside the polygon or its
/// boundary is closer than the margin), `inc r` (inclusion circle: blocked when the box's
/// farthest point, `hausdorff_distance` to the centre, exceeds `r − margin`).
const ZONE_SCRIPT: &str = r#"
import sys
import numpy as np
import shapely
from shapely import wkt
lines = sys.stdin.read().split("\n")
n0, e0, c, rows, cols, margin = lines[0].split()
n0, e0, c, margin = float(n0), float(e0), float(c), float(margin)
rows, cols = int(rows), int(cols)
r, k = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
boxes = shapely.box(e0 + k * c, n0 + r * c, e0 + (k + 1) * c, n0 + (r + 1) * c).ravel()
blocked = np.zeros(boxes.shape, bool)
unsure = np.zeros(boxes.shape, bool)
def mark(d, limit, beyond):
    global blocked, unsure
    unsure |= np.abs(d - limit) < 1e-9
    blocked |= (d > limit) if beyond else (d < limit)
for line in lines[1:]:
    if not line.strip():
        continue
    kind, rest = line.split(" ", 1)
    if kind in ("exc", "inc"):
        radius, rest = rest.split(" ", 1)
        radius = float(radius)
    g = wkt.loads(rest)
    if kind == "ex":
        mark(shapely.distance(g, boxes), margin, False)
    elif kind == "exc":
        mark(shapely.distance(g, boxes), radius + margin, False)
    elif kind == "in":
        mark(shapely.distance(g.boundary, boxes), margin, False)
        blocked |= ~shapely.contains(g, boxes)
    elif kind == "inc":
        # From a point, the Hausdorff distance is the box's farthest point (a corner).
        mark(shapely.hausdorff_distance(g, boxes), radius - margin, True)
out = np.where(unsure, "?", np.where(blocked, "1", "0"))
sys.stdout.write("".join(out.tolist()))
"#;

/// Runs `script` on `input`; its one output character per cell.
fn run_python(script: &str, input: &str) -> String {
    let mut child = Command::new(python())
        .args(["-c", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("run python (set SKYPLAN_PYTHON to a Python with shapely)");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "python failed");
    String::from_utf8(out.stdout).unwrap()
}

#[test]
#[ignore = "needs SKYPLAN_PYTHON with shapely (.ci/run's virtual environment has it)"]
fn zones_match_shapely_distance() {
    use skyplan_cspace::GridFrame;
    use skyplan_map::nofly::{Zone, ZoneShape};
    let (mut compared, mut skipped, mut blocked) = (0usize, 0usize, 0usize);
    for seed in 1..=8u64 {
        let map = random_map(seed * 7_919);
        let margin_m = [0.5, 1.0, 2.5, 4.0][seed as usize % 4];
        let cell_m = [1.0, 0.5, 2.0, 0.7][(seed as usize / 2) % 4];
        let spec = GridSpec {
            alt_m: 20.0,
            safety_m: margin_m,
            cell_m,
        };
        let mut zones = Vec::new();
        let mut input = String::new();
        for (i, fp) in map.footprints.iter().enumerate() {
            let band = (fp.min_height_m, fp.height_m);
            let (shape, line) = if i % 3 == 0 {
                let (centre, radius_m) = (fp.rings[0][0], 2.0 + (fp.height_m % 9.0));
                let point = format!("POINT ({:.17} {:.17})", centre[1], centre[0]);
                (
                    ZoneShape::Circle { centre, radius_m },
                    format!("exc {radius_m:.17} {point}"),
                )
            } else {
                (
                    ZoneShape::Polygon(fp.rings.clone()),
                    format!("ex {}", wkt(fp)),
                )
            };
            let z = Zone {
                feature: i,
                shape,
                floor_m: band.0,
                ceiling_m: band.1,
                inclusion: false,
                start_unix_s: None,
                end_unix_s: None,
            };
            if z.meets_altitude(spec.alt_m, margin_m) {
                input.push_str(&line);
                input.push('\n');
            }
            zones.push(z);
        }
        // An inclusion boundary: a big star polygon, or a circle.
        let mut rng = Rng(seed * 31 + 7);
        let (shape, line) = if seed % 2 == 0 {
            let ring = star(&mut rng, [40.0, 40.0], 30.0, 55.0, 9);
            let f = Footprint {
                feature: 99,
                rings: vec![ring.clone()],
                min_height_m: 0.0,
                height_m: 1.0,
            };
            (ZoneShape::Polygon(vec![ring]), format!("in {}", wkt(&f)))
        } else {
            let radius_m = 40.0 + 10.0 * rng.unit();
            (
                ZoneShape::Circle {
                    centre: [40.0, 45.0],
                    radius_m,
                },
                format!("inc {radius_m:.17} POINT (45 40)"),
            )
        };
        input.push_str(&line);
        input.push('\n');
        zones.push(Zone {
            feature: 99,
            shape,
            floor_m: 0.0,
            ceiling_m: f64::INFINITY,
            inclusion: true,
            start_unix_s: None,
            end_unix_s: None,
        });
        let frame = GridFrame {
            origin_north_m: -20.0,
            origin_east_m: -20.0,
            cell_m,
        };
        let n = (120.0 / cell_m) as u32;
        let mut grid = Grid2::new(n, n, vec![false; (n * n) as usize], frame).unwrap();
        grid.block_zones(&zones, spec).unwrap();
        let header = format!("{} {} {} {n} {n} {margin_m}\n", -20.0, -20.0, cell_m);
        let want = run_python(ZONE_SCRIPT, &(header + &input));
        assert_eq!(want.len(), grid.len());
        for (i, w) in want.bytes().enumerate() {
            let got = grid.blocked_cells()[i];
            match w {
                b'?' => skipped += 1,
                b'1' | b'0' => {
                    assert_eq!(
                        got,
                        w == b'1',
                        "seed {seed}: cell {:?} (margin {margin_m} m, cell {cell_m} m)",
                        grid.cell(i)
                    );
                    compared += 1;
                    blocked += usize::from(got);
                }
                _ => panic!("unexpected output from python"),
            }
        }
    }
    println!(
        "zones: compared {compared} cells with shapely ({blocked} blocked), {skipped} on the margin left out"
    );
    assert!(compared > 100_000 && blocked > 20_000 && compared - blocked > 20_000);
    assert!(skipped < compared / 1000);
}

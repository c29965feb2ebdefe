//! Footprint prisms against shapely (GEOS): on random concave footprints with holes and height
//! bands, a point, a segment or a box is blocked exactly when, for some prism, its part inside
//! the prism's band grown by the margin is within the margin of the polygon by shapely's exact
//! `distance`. The indexed world and the brute-force checker are both compared; cases within
//! 1e-9 m of the margin are left out.

use skyplan_map::footprints::Footprint;
use skyplan_testkit::XorShift;
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, WorldSpec};
use std::io::Write;
use std::process::{Command, Stdio};

/// The Python that has shapely: `SKYPLAN_PYTHON` (set by `.ci/run` to its virtual environment),
/// else `python3`.
fn python() -> String {
    std::env::var("SKYPLAN_PYTHON").unwrap_or_else(|_| "python3".to_string())
}

/// Reads `margin` then one polygon per line (`floor top WKT`), then queries (`p x y z`,
/// `s x y z x y z`, `b x0 y0 z0 x1 y1 z1`, in north/east/up); prints per query `1` (blocked),
/// `0` (free) or `?` (within 1e-9 m of the margin).
const SCRIPT: &str = r#"
import sys
import shapely
from shapely import wkt
from shapely.geometry import LineString, Point, box
lines = [l for l in sys.stdin.read().split("\n") if l.strip()]
margin = float(lines[0])
polys, out = [], []
for l in lines[1:]:
    if l.startswith("POLY"):
        _, floor, top, text = l.split(" ", 3)
        polys.append((float(floor) - margin, float(top) + margin, wkt.loads(text)))
        continue
    kind, *v = l.split()
    v = [float(x) for x in v]
    verdict = "0"
    for lo, hi, poly in polys:
        if kind == "p":
            if not lo <= v[2] <= hi:
                continue
            d = poly.distance(Point(v[1], v[0]))
        elif kind == "b":
            if v[5] < lo or v[2] > hi:
                continue
            d = poly.distance(box(v[1], v[0], v[4], v[3]))
        else:
            a, b = v[:3], v[3:]
            if a[2] == b[2]:
                if not lo <= a[2] <= hi:
                    continue
                t0, t1 = 0.0, 1.0
            else:
                ta, tb = (lo - a[2]) / (b[2] - a[2]), (hi - a[2]) / (b[2] - a[2])
                t0, t1 = max(0.0, min(ta, tb)), min(1.0, max(ta, tb))
                if t0 > t1:
                    continue
            at = lambda t: (a[1] + (b[1] - a[1]) * t, a[0] + (b[0] - a[0]) * t)
            p, q = at(t0), at(t1)
            d = poly.distance(Point(p) if p == q else LineString([p, q]))
        if abs(d - margin) < 1e-9:
            verdict = "?"
        elif d < margin and verdict != "?":
            verdict = "1"
            break
    out.append(verdict)
sys.stdout.write("".join(out))
"#;

/// A star-shaped ring of `n` vertices about `centre`, radii in `[r0, r1)`.
fn ring(rng: &mut XorShift, centre: [f64; 2], r0: f64, r1: f64, n: usize) -> Vec<[f64; 2]> {
    let mut angles: Vec<f64> = (0..n).map(|_| rng.unit() * std::f64::consts::TAU).collect();
    angles.sort_by(f64::total_cmp);
    angles.dedup_by(|a, b| (*a - *b).abs() < 0.05);
    let mut out = Vec::with_capacity(angles.len());
    for a in angles {
        let r = r0 + (r1 - r0) * rng.unit();
        out.push([centre[0] + r * a.cos(), centre[1] + r * a.sin()]);
    }
    out
}

fn footprints(seed: u64) -> Vec<Footprint> {
    let mut rng = XorShift::new(seed);
    let mut out = Vec::new();
    while out.len() < 12 {
        let centre = [10.0 + 80.0 * rng.unit(), 10.0 + 80.0 * rng.unit()];
        let n = 4 + (rng.unit() * 14.0) as usize;
        let outer = ring(&mut rng, centre, 6.0, 15.0, n);
        if outer.len() < 3 {
            continue;
        }
        let mut rings = vec![outer];
        if rng.unit() < 0.6 {
            let n = 3 + (rng.unit() * 6.0) as usize;
            let hole = ring(&mut rng, centre, 1.5, 4.0, n);
            if hole.len() >= 3 {
                rings.push(hole);
            }
        }
        let floor = if rng.unit() < 0.3 {
            25.0 * rng.unit()
        } else {
            0.0
        };
        out.push(Footprint {
            feature: out.len(),
            rings,
            min_height_m: floor,
            height_m: floor + 5.0 + 40.0 * rng.unit(),
        });
    }
    out
}

fn wkt(f: &Footprint) -> String {
    let rings: Vec<String> = (f.rings.iter())
        .map(|r| {
            let pts: Vec<String> = (r.iter().chain(r.first()))
                .map(|p| format!("{:.17} {:.17}", p[1], p[0]))
                .collect();
            format!("({})", pts.join(", "))
        })
        .collect();
    format!("POLYGON ({})", rings.join(", "))
}

enum Query {
    Point(Neu),
    Segment(Neu, Neu),
    Box(Aabb),
}

#[test]
#[ignore = "needs SKYPLAN_PYTHON with shapely (.ci/run's virtual environment has it)"]
fn prisms_match_shapely() {
    let (mut compared, mut skipped) = (0usize, 0usize);
    let mut blocked = [0usize; 3];
    for seed in 1..=6u64 {
        let fs = footprints(seed * 7919);
        let margin_m = [0.5, 2.0, 3.5][seed as usize % 3];
        let spec = WorldSpec {
            safety_m: margin_m,
            ..WorldSpec::default()
        };
        let bounds = Aabb {
            min: [-20.0, -20.0, 0.0],
            max: [120.0, 120.0, 80.0],
        };
        let world = BoxWorld3::with_footprints(&[], &fs, &spec, bounds).unwrap();
        let brute = world.brute_force();
        let mut rng = XorShift::new(seed);
        let mut at = |lo: f64, hi: f64| lo + (hi - lo) * rng.unit();
        let mut queries = Vec::new();
        for k in 0..900 {
            let p = [at(0.0, 100.0), at(0.0, 100.0), at(0.0, 70.0)];
            queries.push(match k % 3 {
                0 => Query::Point(p),
                1 => {
                    // Short and long, level and climbing segments.
                    let reach = if k % 2 == 0 { 15.0 } else { 80.0 };
                    let climb = if k % 5 == 0 { 0.0 } else { at(-30.0, 30.0) };
                    let q = [
                        (p[0] + at(-reach, reach)).clamp(0.0, 100.0),
                        (p[1] + at(-reach, reach)).clamp(0.0, 100.0),
                        (p[2] + climb).clamp(0.0, 70.0),
                    ];
                    Query::Segment(p, q)
                }
                _ => Query::Box(Aabb {
                    min: p,
                    max: [
                        p[0] + at(0.0, 6.0),
                        p[1] + at(0.0, 6.0),
                        p[2] + at(0.0, 4.0),
                    ],
                }),
            });
        }
        let mut input = format!("{margin_m}\n");
        for f in &fs {
            input += &format!("POLY {} {} {}\n", f.min_height_m, f.height_m, wkt(f));
        }
        let v = |p: Neu| format!("{:.17} {:.17} {:.17}", p[0], p[1], p[2]);
        for q in &queries {
            input += &match q {
                Query::Point(p) => format!("p {}\n", v(*p)),
                Query::Segment(a, b) => format!("s {} {}\n", v(*a), v(*b)),
                Query::Box(b) => format!("b {} {}\n", v(b.min), v(b.max)),
            };
        }
        let mut child = Command::new(python())
            .args(["-c", SCRIPT])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("python with shapely (set SKYPLAN_PYTHON)");
        child
            .stdin
            .take()
            .unwrap()
            .write_all(input.as_bytes())
            .unwrap();
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success(), "the shapely script failed");
        let verdicts = String::from_utf8(out.stdout).unwrap();
        assert_eq!(verdicts.len(), queries.len());
        for (q, want) in queries.iter().zip(verdicts.chars()) {
            if want == '?' {
                skipped += 1;
                continue;
            }
            let want_blocked = want == '1';
            let (kind, indexed, brute_force) = match q {
                Query::Point(p) => (0, !world.is_free(*p), !brute.is_free(*p)),
                Query::Segment(a, b) => (
                    1,
                    !world.segment_is_free(*a, *b),
                    !brute.segment_is_free(*a, *b),
                ),
                Query::Box(b) => (2, !world.box_is_free(b), !brute.box_is_free(b)),
            };
            assert_eq!(
                (indexed, brute_force),
                (want_blocked, want_blocked),
                "seed {seed}, margin {margin_m} m: query {}",
                match q {
                    Query::Point(p) => format!("point {}", v(*p)),
                    Query::Segment(a, b) => format!("segment {} to {}", v(*a), v(*b)),
                    Query::Box(b) => format!("box {} to {}", v(b.min), v(b.max)),
                }
            );
            compared += 1;
            blocked[kind] += usize::from(want_blocked);
        }
    }
    // Both verdicts are common, so the comparison means something.
    eprintln!(
        "{compared} compared, {skipped} skipped, blocked (points, segments, boxes) {blocked:?}"
    );
    assert!(
        compared >= 5000 && skipped < 10,
        "{compared} compared, {skipped} skipped"
    );
    for (kind, n) in ["points", "segments", "boxes"].iter().zip(blocked) {
        assert!(
            (150..1650).contains(&n),
            "{n} of 1800 {kind} blocked: the sample does not test both sides"
        );
    }
}

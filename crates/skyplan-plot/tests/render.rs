//! Renders small synthetic scenes and checks the pictures pixel by pixel.

use skyplan_cspace::{Grid2, GridFrame};
use skyplan_map::colliders::ObstacleBox;
use skyplan_plot::{
    MAX_SIZE_PX, PlotError, PlotFormat, Scene, layout, render, render_png, render_svg,
};

const ROWS: u32 = 40;
const COLS: u32 = 60;
const FRAME: GridFrame = GridFrame {
    origin_north_m: -20.0,
    origin_east_m: -30.0,
    cell_m: 1.0,
};

/// Blocked blocks (rows, cols, half-open) with an obstacle in the middle of each, as a planner
/// would see them with a 3 m margin.
const BLOCKS: [((u32, u32), (u32, u32)); 2] = [((25, 35), (5, 20)), ((3, 12), (40, 55))];
const MARGIN_M: f64 = 3.0;

struct Fixture {
    grid: Grid2,
    obstacles: Vec<ObstacleBox>,
    raw: Vec<(f64, f64)>,
    pruned: Vec<(f64, f64)>,
}

fn fixture() -> Fixture {
    let mut blocked = vec![false; (ROWS * COLS) as usize];
    let mut obstacles = Vec::new();
    for &((r0, r1), (c0, c1)) in &BLOCKS {
        for r in r0..r1 {
            for c in c0..c1 {
                blocked[(r * COLS + c) as usize] = true;
            }
        }
        let north = |r: u32| FRAME.origin_north_m + f64::from(r);
        let east = |c: u32| FRAME.origin_east_m + f64::from(c);
        obstacles.push(ObstacleBox {
            north_m: 0.5 * (north(r0) + north(r1)),
            east_m: 0.5 * (east(c0) + east(c1)),
            up_m: 10.0,
            half_north_m: 0.5 * f64::from(r1 - r0) - MARGIN_M,
            half_east_m: 0.5 * f64::from(c1 - c0) - MARGIN_M,
            half_up_m: 10.0,
        });
    }
    let grid = Grid2::new(ROWS, COLS, blocked, FRAME).unwrap();
    // A staircase from the south-west to the north-east, through free space.
    let mut raw = vec![(-15.5, -25.5)];
    while raw.len() < 30 {
        let (n, e) = *raw.last().unwrap();
        raw.push(if raw.len() % 3 == 0 {
            (n + 1.0, e)
        } else {
            (n + 1.0, e + 1.0)
        });
    }
    let pruned = vec![raw[0], raw[15], raw[29]];
    Fixture {
        grid,
        obstacles,
        raw,
        pruned,
    }
}

fn scene(f: &Fixture) -> Scene<'_> {
    Scene {
        title: "synthetic at 5 m, margin 3 m".into(),
        grid: &f.grid,
        obstacles: &f.obstacles,
        footprints: &[],
        raw_path_ne: &f.raw,
        pruned_path_ne: &f.pruned,
        start_ne: f.pruned.first().copied(),
        goal_ne: f.pruned.last().copied(),
        graph_ne: &[],
        connectors_ne: &[],
        flight: None,
        zones: &[],
        fleet: &[],
    }
}

struct Image {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Image {
    fn decode(bytes: &[u8]) -> Self {
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().expect("a valid PNG header");
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).expect("valid PNG data");
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        buf.truncate(info.buffer_size());
        Self {
            width: info.width,
            height: info.height,
            rgb: buf,
        }
    }

    fn at(&self, (x, y): (i32, i32)) -> [u8; 3] {
        assert!(x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height);
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

fn is_white(p: [u8; 3]) -> bool {
    p == [255, 255, 255]
}
fn is_grey(p: [u8; 3], lo: u8, hi: u8) -> bool {
    let (min, max) = (*p.iter().min().unwrap(), *p.iter().max().unwrap());
    max - min <= 12 && (lo..=hi).contains(&min)
}
fn is_green(p: [u8; 3]) -> bool {
    p[1] > 130 && p[0] < 80 && p[2] < 120
}
fn is_red(p: [u8; 3]) -> bool {
    p[0] > 180 && p[1] < 80 && p[2] < 80
}
fn is_blue(p: [u8; 3]) -> bool {
    p[2] > 150 && p[0] < 80 && p[1] < 140
}

/// Centre of a cell, (north, east).
fn cell_ne(row: u32, col: u32) -> (f64, f64) {
    (
        FRAME.origin_north_m + f64::from(row) + 0.5,
        FRAME.origin_east_m + f64::from(col) + 0.5,
    )
}

#[test]
fn png_has_the_size_and_the_colours_where_the_layout_says() {
    let f = fixture();
    let scene = scene(&f);
    let (w, h) = (640, 480);
    let img = Image::decode(&render_png(&scene, w, h).unwrap());
    assert_eq!((img.width, img.height), (w, h));
    let l = layout(&scene, w, h).unwrap();
    let px = |(n, e): (f64, f64)| l.pixel_of_ne(n, e);

    // Configuration space only (inside the margin ring) is light grey, obstacles dark grey.
    for &((r0, r1), (c0, c1)) in &BLOCKS {
        assert!(
            is_grey(img.at(px(cell_ne(r0, c0))), 180, 235),
            "margin corner {:?}",
            img.at(px(cell_ne(r0, c0)))
        );
        assert!(is_grey(
            img.at(px(cell_ne(r1 - 1, (c0 + c1) / 2))),
            180,
            235
        ));
        let mid = cell_ne((r0 + r1) / 2, (c0 + c1) / 2);
        assert!(
            is_grey(img.at(px(mid)), 60, 130),
            "obstacle {:?}",
            img.at(px(mid))
        );
    }
    // Free space far from everything is white (or a faint grid line).
    let free = img.at(px(cell_ne(2, 2)));
    assert!(
        is_white(free) || is_grey(free, 220, 254),
        "free space {free:?}"
    );
    // Start green, goal red, a pruned waypoint segment blue, the raw path orange somewhere.
    assert!(
        is_green(img.at(px(f.pruned[0]))),
        "start {:?}",
        img.at(px(f.pruned[0]))
    );
    assert!(
        is_red(img.at(px(f.pruned[2]))),
        "goal {:?}",
        img.at(px(f.pruned[2]))
    );
    let (a, b) = (f.pruned[0], f.pruned[1]);
    let on_segment = (0.6 * a.0 + 0.4 * b.0, 0.6 * a.1 + 0.4 * b.1);
    assert!(
        is_blue(img.at(px(on_segment))),
        "pruned path {:?}",
        img.at(px(on_segment))
    );
    let orange = img
        .rgb
        .chunks_exact(3)
        .filter(|p| p[0] > 230 && (100..160).contains(&p[1]) && p[2] < 60)
        .count();
    assert!(orange > 20, "orange pixels: {orange}");
}

#[test]
fn north_is_up_east_is_right_and_scales_are_equal() {
    // A single blocked cell in the north-west corner of a wide grid.
    let (rows, cols) = (10, 20);
    let mut blocked = vec![false; rows * cols];
    blocked[(rows - 1) * cols] = true;
    let frame = GridFrame {
        origin_north_m: 100.0,
        origin_east_m: -50.0,
        cell_m: 2.0,
    };
    let grid = Grid2::new(rows as u32, cols as u32, blocked, frame).unwrap();
    let scene = Scene::of_grid(&grid);
    let (w, h) = (500, 500);
    let l = layout(&scene, w, h).unwrap();
    let (x0, y0, pw, ph) = l.plot_area();
    // Equal scales: a 40 m × 20 m grid is twice as wide as high.
    let (e0, e1) = l.east_range_m();
    let (n0, n1) = l.north_range_m();
    assert_eq!((e0, n0), (-50.0, 100.0));
    let (east_scale, north_scale) = ((e1 - e0) / f64::from(pw - 1), (n1 - n0) / f64::from(ph - 1));
    assert!(
        (east_scale / north_scale - 1.0).abs() < 1e-9,
        "{east_scale} vs {north_scale}"
    );
    assert!(
        (f64::from(pw - 1) / f64::from(ph - 1) - 2.0).abs() < 0.02,
        "{pw} × {ph}"
    );
    assert!(e1 >= -10.0 && e1 - (-10.0) < l.metres_per_px());

    let img = Image::decode(&render_png(&scene, w, h).unwrap());
    // The blocked cell covers the top-left corner of the plot area, nothing else is grey.
    let cell_px = (2.0 / l.metres_per_px()) as i32;
    assert!(cell_px > 10);
    assert!(is_grey(
        img.at((x0 + cell_px / 2, y0 + cell_px / 2)),
        180,
        235
    ));
    let y1 = y0 + ph as i32 - 1;
    let x1 = x0 + pw as i32 - 1;
    for corner in [
        (x0 + cell_px / 2, y1 - cell_px / 2),
        (x1 - cell_px / 2, y0 + cell_px / 2),
    ] {
        let p = img.at(corner);
        assert!(is_white(p) || is_grey(p, 225, 254), "{corner:?}: {p:?}");
    }
    // Pixels left of and below the plot area (axis labels) are not part of the map.
    assert!(!is_grey(img.at((x0 - 3, y0 + cell_px / 2)), 180, 235));
}

#[test]
fn svg_is_a_document_with_labels_title_legend_and_paths() {
    let f = fixture();
    let scene = scene(&f);
    let svg = render_svg(&scene, 800, 600).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..80]);
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains(r#"width="800" height="600""#));
    let texts = svg_texts(&svg);
    for label in [
        "EAST (m)",
        "NORTH (m)",
        "synthetic at 5 m, margin 3 m",
        "obstacle + safety margin",
        "obstacle",
        "grid path (30 points)",
        "waypoints (3 points)",
        "start",
        "goal",
    ] {
        assert!(
            texts.contains(&label),
            "missing text {label:?} in {texts:?}"
        );
    }
    for element in ["<polyline", "<rect", "<circle", "<polygon"] {
        assert!(svg.contains(element), "no {element}");
    }
    // Every opened element is closed.
    assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
    // Merged rectangles: two blocked blocks and two obstacles (plus background, frame, legend).
    assert!(
        svg.matches("<rect").count() < 20,
        "{} rects",
        svg.matches("<rect").count()
    );
}

/// The contents of the text elements (plotters writes each on its own line).
fn svg_texts(svg: &str) -> Vec<&str> {
    let mut lines = svg.lines();
    let mut texts = Vec::new();
    while let Some(line) = lines.next() {
        if line.starts_with("<text") {
            texts.push(lines.next().unwrap_or_default());
        }
    }
    texts
}

#[test]
fn render_dispatches_on_the_format() {
    let f = fixture();
    let scene = scene(&f);
    let png = render(&scene, PlotFormat::Png, 300, 200).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = render(&scene, PlotFormat::Svg, 300, 200).unwrap();
    assert!(String::from_utf8(svg).unwrap().starts_with("<svg"));
    assert_eq!(PlotFormat::from_path("a/b/plan.Svg"), Some(PlotFormat::Svg));
    assert_eq!(PlotFormat::from_path("plan.png"), Some(PlotFormat::Png));
    assert_eq!(PlotFormat::from_path("plan"), None);
    assert_eq!(PlotFormat::from_extension("PNG"), Some(PlotFormat::Png));
    assert_eq!(PlotFormat::Svg.extension(), "svg");
}

#[test]
fn rejects_bad_sizes_and_non_finite_points() {
    let f = fixture();
    let scene = scene(&f);
    for (w, h) in [(0, 100), (199, 400), (400, MAX_SIZE_PX + 1)] {
        assert_eq!(
            render_png(&scene, w, h).unwrap_err(),
            PlotError::BadSize {
                width: w,
                height: h
            }
        );
    }
    let nan = [(f64::NAN, 0.0)];
    let bad = Scene {
        raw_path_ne: &nan,
        ..scene.clone()
    };
    assert!(matches!(
        render_svg(&bad, 400, 300),
        Err(PlotError::BadScene { .. })
    ));
    let bad_frame = Grid2::new(
        1,
        1,
        vec![true],
        GridFrame {
            cell_m: 0.0,
            ..FRAME
        },
    )
    .unwrap();
    let bad = Scene {
        grid: &bad_frame,
        ..scene
    };
    assert!(
        render_png(&bad, 400, 300)
            .unwrap_err()
            .to_string()
            .contains("cell size")
    );
}

#[test]
fn empty_scene_and_points_outside_the_grid_still_render() {
    let grid = Grid2::new(0, 0, vec![], FRAME).unwrap();
    let path = [(0.0, 0.0), (10.0, 5.0)];
    let empty = Scene::of_grid(&grid);
    Image::decode(&render_png(&empty, 300, 300).unwrap());
    let f = fixture();
    let outside = Scene {
        goal_ne: Some((500.0, 500.0)),
        raw_path_ne: &path,
        ..scene(&f)
    };
    let l = layout(&outside, 400, 400).unwrap();
    assert!(l.north_range_m().1 > 500.0 && l.east_range_m().1 > 500.0);
    let img = Image::decode(&render_png(&outside, 400, 400).unwrap());
    assert!(is_red(img.at(l.pixel_of_ne(500.0, 500.0))));
}

#[test]
fn tick_labels_do_not_crowd() {
    let f = fixture();
    let scene = scene(&f);
    for (w, h) in [(200, 200), (640, 480), (1600, 400), (3000, 3000)] {
        let l = layout(&scene, w, h).unwrap();
        assert!(
            l.east_ticks_m().len() >= 2 && l.east_ticks_m().len() <= 12,
            "{w}x{h}: {:?}",
            l.east_ticks_m()
        );
        assert!(
            l.north_ticks_m().len() >= 2 && l.north_ticks_m().len() <= 12,
            "{w}x{h}: {:?}",
            l.north_ticks_m()
        );
        let xs: Vec<i32> = l
            .east_ticks_m()
            .iter()
            .map(|&e| l.pixel_of_ne(0.0, e).0)
            .collect();
        assert!(xs.windows(2).all(|p| p[1] - p[0] >= 30), "{w}x{h}: {xs:?}");
    }
}

/// A flight over its plan: the hidden box dark red where it stands, the learned cells and the
/// replanned route and the track drawn where the layout puts them, all four in the legend.
#[test]
fn flight_layers_are_drawn_where_they_are_and_named_in_the_legend() {
    let f = fixture();
    let hidden = [ObstacleBox {
        north_m: 5.0,
        east_m: -15.0,
        up_m: 10.0,
        half_north_m: 2.0,
        half_east_m: 2.0,
        half_up_m: 10.0,
    }];
    let learned = [(5.0, -18.0)];
    // The replanned route runs due east along N -10, the track due north along E 20: far from
    // everything else drawn.
    let replanned = [vec![(-10.0, -25.0), (-10.0, 0.0)]];
    let track = [(-15.0, 20.0), (15.0, 20.0)];
    let layers = skyplan_plot::FlightLayers {
        hidden: &hidden,
        learned_ne: &learned,
        replanned_ne: &replanned,
        track_ne: &track,
        track_alt_m: &[],
    };
    let mut s = scene(&f);
    s.flight = Some(&layers);
    let (w, h) = (800, 600);
    let img = Image::decode(&render_png(&s, w, h).unwrap());
    let l = layout(&s, w, h).unwrap();
    let px = |(n, e): (f64, f64)| l.pixel_of_ne(n, e);
    let hidden_px = img.at(px((5.0, -15.0)));
    assert!(
        hidden_px[0] > 120 && hidden_px[1] < 60 && hidden_px[2] < 70,
        "hidden box {hidden_px:?}"
    );
    let learned_px = img.at(px(learned[0]));
    assert!(
        learned_px[0] > 200 && learned_px[2] > 120 && learned_px[1] < 100,
        "learned cell {learned_px:?}"
    );
    let route_px = img.at(px((-10.0, -12.0)));
    assert!(
        route_px[2] > 170 && route_px[0] > 110 && route_px[1] < 100,
        "replanned route {route_px:?}"
    );
    let track_px = img.at(px((0.0, 20.0)));
    assert!(track_px.iter().all(|&c| c < 60), "track {track_px:?}");
    // Where nothing of the flight is drawn, the picture is what it was without it.
    let plain = Image::decode(&render_png(&scene(&f), w, h).unwrap());
    assert!(is_white(plain.at(px((0.0, 20.0)))));
    let svg = render_svg(&s, w, h).unwrap();
    for label in [
        "hidden obstacles (1)",
        "learned cells (1)",
        "replanned routes (1)",
        "flown track",
    ] {
        assert!(svg.contains(label), "legend lacks {label}");
    }
}

/// An exclusion square (with a hole) and an inclusion circle in free space, away from the
/// fixture's blocks and route.
fn zones() -> Vec<skyplan_map::nofly::Zone> {
    use skyplan_map::nofly::{Zone, ZoneShape};
    let square = |n0: f64, n1: f64, e0: f64, e1: f64| vec![[n0, e0], [n0, e1], [n1, e1], [n1, e0]];
    vec![
        Zone {
            feature: 0,
            shape: ZoneShape::Polygon(vec![
                square(-4.0, 2.0, 5.0, 20.0),
                square(-2.0, 0.0, 10.0, 14.0),
            ]),
            floor_m: 0.0,
            ceiling_m: 120.0,
            inclusion: false,
            start_unix_s: None,
            end_unix_s: None,
        },
        Zone {
            feature: 1,
            shape: ZoneShape::Circle {
                centre: [-12.0, -5.0],
                radius_m: 4.0,
            },
            floor_m: 0.0,
            ceiling_m: f64::INFINITY,
            inclusion: true,
            start_unix_s: None,
            end_unix_s: None,
        },
    ]
}

#[test]
fn zones_are_hatched_outlined_and_labelled_with_their_bands() {
    let f = fixture();
    let z = zones();
    let scene = Scene {
        zones: &z,
        ..scene(&f)
    };
    let (w, h) = (900, 600);
    let img = Image::decode(&render_png(&scene, w, h).unwrap());
    let l = layout(&scene, w, h).unwrap();
    let px = |n: f64, e: f64| l.pixel_of_ne(n, e);
    // The red pixels among those of a region (north, east ranges), sampled every pixel.
    let red_share = |(n0, n1): (f64, f64), (e0, e1): (f64, f64)| {
        let ((x0, y1), (x1, y0)) = (px(n0, e0), px(n1, e1));
        let (mut red, mut all) = (0, 0);
        for y in y0..=y1 {
            for x in x0..=x1 {
                all += 1;
                red += usize::from(is_red(img.at((x, y))));
            }
        }
        red as f64 / all as f64
    };
    // Inside the exclusion square, off its hole and edges: hatched (diagonal lines every 7 px:
    // some red, mostly not).
    let hatched = red_share((-3.5, -2.5), (6.0, 9.0));
    assert!((0.05..0.6).contains(&hatched), "{hatched}");
    let hatched = red_share((0.5, 1.5), (15.0, 19.0));
    assert!((0.05..0.6).contains(&hatched), "{hatched}");
    // Its hole and the free space east of it: no hatching.
    assert_eq!(red_share((-1.6, -0.4), (10.4, 13.6)), 0.0);
    assert_eq!(red_share((-3.0, 1.0), (21.0, 24.0)), 0.0);
    // Its outline (the western edge) is red.
    assert!(is_red(img.at(px(-1.0, 5.0))), "{:?}", img.at(px(-1.0, 5.0)));
    // The inclusion circle: a green outline, not hatched inside.
    assert!(
        is_green(img.at(px(-12.0, -1.0))),
        "{:?}",
        img.at(px(-12.0, -1.0))
    );
    assert!(is_green(img.at(px(-8.0, -5.0))));
    assert_eq!(red_share((-14.0, -10.0), (-7.0, -3.0)), 0.0);
    assert!(is_white(img.at(px(-12.0, -5.0))));
    // The labels give each zone's number and band; the inclusion says so.
    let svg = render_svg(&scene, w, h).unwrap();
    let texts = svg_texts(&svg);
    assert!(
        texts.iter().any(|t| t.contains("zone 0, 0–120 m")),
        "{texts:?}"
    );
    assert!(
        texts.iter().any(|t| t.contains("zone 1 inside, from 0 m")),
        "{texts:?}"
    );
    // Without zones, the same region is not red at all.
    let plain_scene = Scene {
        zones: &[],
        ..scene
    };
    let plain = Image::decode(&render_png(&plain_scene, w, h).unwrap());
    let ((x0, y1), (x1, y0)) = (px(-3.5, 6.0), px(-2.5, 9.0));
    assert!((y0..=y1).all(|y| (x0..=x1).all(|x| !is_red(plain.at((x, y))))));
}

#[test]
fn footprints_are_drawn_as_polygons_with_their_courtyards_open() {
    use skyplan_map::footprints::Footprint;
    let grid = Grid2::new(ROWS, COLS, vec![false; (ROWS * COLS) as usize], FRAME).unwrap();
    // A square building with a courtyard, and a triangle (north, east).
    let building = Footprint {
        feature: 0,
        rings: vec![
            vec![[-15.0, -25.0], [-15.0, 5.0], [15.0, 5.0], [15.0, -25.0]],
            vec![[-5.0, -15.0], [5.0, -15.0], [5.0, -5.0], [-5.0, -5.0]],
        ],
        min_height_m: 0.0,
        height_m: 30.0,
    };
    let triangle = Footprint {
        feature: 1,
        rings: vec![vec![[-10.0, 10.0], [-10.0, 25.0], [10.0, 10.0]]],
        min_height_m: 0.0,
        height_m: 30.0,
    };
    let footprints = [building, triangle];
    let scene = Scene {
        footprints: &footprints,
        ..Scene::of_grid(&grid)
    };
    let (w, h) = (600, 420);
    let img = Image::decode(&render_png(&scene, w, h).unwrap());
    let l = layout(&scene, w, h).unwrap();
    let dark = |n: f64, e: f64| is_grey(img.at(l.pixel_of_ne(n, e)), 80, 110);
    let white = |n: f64, e: f64| is_white(img.at(l.pixel_of_ne(n, e)));
    // Probes off the tick lines (multiples of 5 m).
    assert!(dark(-11.3, -11.3) && dark(12.3, 1.3), "the building's ring");
    assert!(
        white(1.3, -11.3) && white(-3.7, -6.3),
        "the courtyard stays open"
    );
    assert!(dark(-8.3, 12.3), "inside the triangle");
    assert!(white(8.3, 23.3), "beyond the triangle's long side");
    assert!(white(18.3, 1.3) && white(1.3, 28.3), "outside");
    let svg = render_svg(&scene, w, h).unwrap();
    assert!(svg.contains("obstacle"), "the legend names the buildings");
}

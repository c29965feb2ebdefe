//! Axis conventions of image maps (the classic bug is swapped or flipped axes), map_server modes
//! and thresholds, and PNG/PGM decoding, on images built here pixel by pixel.

use skyplan_cspace::Cell;
use skyplan_imagemap::{
    MapMode, MapYaml, OCC_FREE, OCC_OCCUPIED, OCC_UNKNOWN, decode_image, image_map, image_map_with,
    occupancy,
};

const W: u32 = 6;
const H: u32 = 4;

/// The test picture, top row first as in the file: an L-shaped black obstacle in the TOP-LEFT
/// corner (three pixels), a mid-grey (unknown) pixel in the BOTTOM-RIGHT corner, white elsewhere.
fn picture() -> Vec<u8> {
    let mut gray = vec![255u8; (W * H) as usize];
    for (x, y) in [(0, 0), (1, 0), (0, 1)] {
        gray[y * W as usize + x] = 0;
    }
    gray[3 * W as usize + 5] = 128;
    gray
}

fn encode_png(gray: &[u8], color: png::ColorType, depth: png::BitDepth) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, W, H);
        enc.set_color(color);
        enc.set_depth(depth);
        let mut writer = enc.write_header().unwrap();
        let data: Vec<u8> = match (color, depth) {
            (png::ColorType::Grayscale, png::BitDepth::Eight) => gray.to_vec(),
            (png::ColorType::Grayscale, png::BitDepth::Sixteen) => {
                gray.iter().flat_map(|&g| [g, g]).collect()
            }
            (png::ColorType::Rgb, _) => gray.iter().flat_map(|&g| [g, g, g]).collect(),
            (png::ColorType::Rgba, _) => gray.iter().flat_map(|&g| [g, g, g, 255]).collect(),
            _ => unreachable!(),
        };
        writer.write_image_data(&data).unwrap();
    }
    out
}

fn pgm_p5(gray: &[u8]) -> Vec<u8> {
    let mut out = format!("P5\n# a comment\n{W} {H}\n255\n").into_bytes();
    out.extend_from_slice(gray);
    out
}

fn pgm_p2(gray: &[u8]) -> Vec<u8> {
    let mut out = format!("P2\n{W} {H}\n255\n");
    for row in gray.chunks(W as usize) {
        let line: Vec<String> = row.iter().map(u8::to_string).collect();
        out.push_str(&line.join(" "));
        out.push('\n');
    }
    out.into_bytes()
}

fn meta() -> MapYaml {
    MapYaml::parse("image: test.png\nresolution: 0.5\norigin: [-1.0, 2.0, 0.0]\n").unwrap()
}

#[test]
fn top_left_pixel_is_the_north_west_cell_in_every_format() {
    let gray = picture();
    let files = [
        (
            "png gray8",
            encode_png(&gray, png::ColorType::Grayscale, png::BitDepth::Eight),
        ),
        (
            "png gray16",
            encode_png(&gray, png::ColorType::Grayscale, png::BitDepth::Sixteen),
        ),
        (
            "png rgb",
            encode_png(&gray, png::ColorType::Rgb, png::BitDepth::Eight),
        ),
        (
            "png rgba",
            encode_png(&gray, png::ColorType::Rgba, png::BitDepth::Eight),
        ),
        ("pgm P5", pgm_p5(&gray)),
        ("pgm P2", pgm_p2(&gray)),
    ];
    for (name, bytes) in files {
        let raster = decode_image(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((raster.width, raster.height), (W, H), "{name}");
        let map = image_map(&raster, &meta()).unwrap();
        let grid = &map.grid;
        // 4 rows (north) × 6 columns (east): the image's height is the grid's rows.
        assert_eq!((grid.rows(), grid.cols()), (H, W), "{name}");
        let blocked: Vec<Cell> = (0..grid.len())
            .map(|i| grid.cell(i))
            .filter(|&c| grid.is_blocked(c))
            .collect();
        // The L: image (x 0, y 0), (1, 0), (0, 1) → rows 3, 3, 2 (north), cols 0, 1, 0 (west);
        // the unknown pixel (5, 3) → row 0 (south), col 5 (east), blocked as unknown.
        assert_eq!(
            blocked,
            vec![
                Cell::new(0, 5),
                Cell::new(2, 0),
                Cell::new(3, 0),
                Cell::new(3, 1)
            ],
            "{name}"
        );
        assert_eq!(map.unknown_cells, 1, "{name}");
        // Frame: origin x = east −1 m, y = north 2 m at the lower-left corner; 0.5 m pixels.
        assert_eq!(
            grid.center_ne(Cell::new(3, 0)),
            (2.0 + 3.5 * 0.5, -1.0 + 0.25)
        );
        assert_eq!(grid.cell_at_ne(2.1, 1.9), Some(Cell::new(0, 5))); // south-east corner
        assert_eq!(grid.cell_at_ne(3.9, -0.9), Some(Cell::new(3, 0))); // north-west corner
        // Occupancy in grid order: row 0 is the BOTTOM image row.
        assert_eq!(map.occupancy[5], OCC_UNKNOWN);
        assert_eq!(map.occupancy[3 * W as usize], OCC_OCCUPIED);
        assert_eq!(map.occupancy[0], OCC_FREE);
    }
}

#[test]
fn unknown_cells_can_be_free() {
    let raster = decode_image(&pgm_p5(&picture())).unwrap();
    let map = image_map_with(&raster, &meta(), true).unwrap();
    assert_eq!(map.grid.blocked_count(), 3);
}

#[test]
fn thresholds_negate_and_modes_follow_map_server() {
    // Grey levels and their occupancy probability occ = 1 − g/255.
    let gray = vec![0u8, 50, 89, 90, 128, 204, 205, 255];
    let raster = skyplan_imagemap::Raster {
        width: 8,
        height: 1,
        gray: gray.clone(),
        alpha: None,
    };
    let mut m = MapYaml::bare(1.0);
    // Trinary, occupied if occ > 0.65 (g < 89.25), free if occ < 0.196 (g > 205.02).
    assert_eq!(
        occupancy(&raster, &m),
        vec![100, 100, 100, -1, -1, -1, -1, 0]
    );
    // Scale: between the thresholds, rint((occ − 0.196) / 0.454 · 100).
    m.mode = MapMode::Scale;
    let occ = |g: f64| (((1.0 - g / 255.0) - 0.196) / (0.65 - 0.196) * 100.0).round() as i8;
    assert_eq!(
        occupancy(&raster, &m),
        vec![
            100,
            100,
            100,
            occ(90.0),
            occ(128.0),
            occ(204.0),
            occ(205.0),
            0
        ]
    );
    // Negate: white is occupied.
    m.mode = MapMode::Trinary;
    m.negate = true;
    // occ = g/255: 50/255 = 0.19608 is not below 0.196, 204/255 = 0.8 is above 0.65.
    assert_eq!(
        occupancy(&raster, &m),
        vec![0, -1, -1, -1, -1, 100, 100, 100]
    );
    // Raw: the grey level is the occupancy, above 100 unknown.
    m.mode = MapMode::Raw;
    assert_eq!(occupancy(&raster, &m), vec![0, 50, 89, 90, -1, -1, -1, -1]);
}

#[test]
fn yaml_errors_name_the_field() {
    let cases = [
        ("resolution: 1\norigin: [0, 0, 0]", "image: missing"),
        ("image: a.png\norigin: [0, 0, 0]", "resolution: missing"),
        ("image: a.png\nresolution: 1", "origin: missing"),
        (
            "image: a.png\nresolution: 0\norigin: [0, 0, 0]",
            "resolution: expected",
        ),
        (
            "image: a.png\nresolution: 1\norigin: [0, 0, 0, 0]",
            "origin: expected [x, y, yaw]",
        ),
        (
            "image: a.png\nresolution: 1\norigin: [0, 0, 0.5]",
            "origin: yaw 0.5 rad",
        ),
        (
            "image: a.png\nresolution: 1\norigin: [0, 0, 0]\nnegate: 2",
            "negate: expected 0 or 1",
        ),
        (
            "image: a.png\nresolution: 1\norigin: [0, 0, 0]\nmode: fancy",
            "mode: expected trinary",
        ),
        (
            "image: a.png\nresolution: 1\norigin: [0, 0, 0]\nfree_thresh: 1.5",
            "free_thresh: expected",
        ),
        (
            "image: a.png\nresolution: 1\norigin: [0, 0, 0]\nfree_thresh: 0.9",
            "free_thresh: 0.9 is above",
        ),
        ("image: [unclosed", "yaml: "),
        ("", "image: missing"),
    ];
    for (text, expected) in cases {
        let err = MapYaml::parse(text).unwrap_err().to_string();
        assert!(err.starts_with(expected), "{text:?}: {err}");
    }
    // negate may be written as a boolean too, and unknown keys are ignored.
    let m =
        MapYaml::parse("image: a.png\nresolution: 1\norigin: [0, 0, 0]\nnegate: true\nextra: 1")
            .unwrap();
    assert!(m.negate);
}

#[test]
fn malformed_images_are_refused_with_the_part_named() {
    let cases: [(&[u8], &str); 6] = [
        (b"", "not a PNG or PGM"),
        (b"GIF89a", "not a PNG or PGM"),
        (b"P5\n2 x\n255\n", "PGM height"),
        (b"P5\n2 2\n255\n\x00", "PGM pixels: expected 4 bytes"),
        (b"P2\n2 1\n3\n1 9", "PGM pixels: value 9 exceeds maxval 3"),
        (b"P5\n0 3\n255\n", "the image is empty"),
    ];
    for (bytes, expected) in cases {
        let err = decode_image(bytes).unwrap_err().to_string();
        assert!(err.starts_with(expected), "{bytes:?}: {err}");
    }
    let truncated = &encode_png(&picture(), png::ColorType::Grayscale, png::BitDepth::Eight)[..40];
    assert!(
        decode_image(truncated)
            .unwrap_err()
            .to_string()
            .starts_with("PNG: ")
    );
}

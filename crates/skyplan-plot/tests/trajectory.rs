//! A plan's trajectory in its picture: the curve coloured by speed over the map, the speed and
//! acceleration panel under it, and nothing changed for a plan without one.

use skyplan_plan::{Plan, PlanRequest, PlannerId, Session, World};
use skyplan_plot::plan_picture::{PictureKind, plan_picture};
use skyplan_plot::{PlotFormat, speed_color};

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
        buf.truncate(info.buffer_size());
        Self {
            width: info.width,
            height: info.height,
            rgb: buf,
        }
    }

    /// Pixels (x, y) of rows `rows` within `tol` (per channel) of `color`.
    fn find(&self, color: [u8; 3], tol: u8, rows: std::ops::Range<u32>) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for y in rows {
            for x in 0..self.width {
                let i = (y as usize * self.width as usize + x as usize) * 3;
                let p = &self.rgb[i..i + 3];
                if p.iter().zip(color).all(|(&a, b)| a.abs_diff(b) <= tol) {
                    out.push((x, y));
                }
            }
        }
        out
    }
}

fn plans(planner: Option<PlannerId>) -> (Session, Plan, Plan) {
    let mut session = Session::new(World::fcnd_city());
    let request = PlanRequest {
        goal_ne: Some([60.0, 40.0]),
        planner,
        ..Default::default()
    };
    let plain = session.plan(&request).expect("a plan");
    let traced = session
        .plan(&PlanRequest {
            trajectory: Some(true),
            ..request
        })
        .expect("a plan with a trajectory");
    assert!(plain.trajectory.is_none() && traced.trajectory.is_some());
    (session, plain, traced)
}

/// The fastest speed of the plan's trajectory samples and its speed limit, m/s.
fn peak_and_limit(plan: &Plan) -> (f64, f64) {
    let report = plan.trajectory.as_ref().unwrap();
    let peak = (report.samples.iter())
        .map(|r| (r[4] * r[4] + r[5] * r[5] + r[6] * r[6]).sqrt())
        .fold(0.0, f64::max);
    (peak, report.trajectory.limits.max_speed_m_s)
}

fn picture(session: &Session, plan: &Plan, format: PlotFormat) -> Vec<u8> {
    plan_picture(session.world(), plan, &PictureKind::Scene(format), None).expect("a picture")
}

#[test]
fn the_trajectory_is_drawn_by_speed_over_the_map_with_a_panel_under_it() {
    let (session, plain, traced) = plans(None);
    let plain_png = Image::decode(&picture(&session, &plain, PlotFormat::Png));
    let traced_png = Image::decode(&picture(&session, &traced, PlotFormat::Png));
    assert_eq!(traced_png.width, plain_png.width);
    assert!(
        traced_png.height > plain_png.height + 200,
        "{} px tall, {} without the trajectory",
        traced_png.height,
        plain_png.height
    );
    let map_rows = 0..plain_png.height;
    let strip_rows = plain_png.height..traced_png.height;

    // The route reaches the speed limit: its colour (the scale's fast end) is along the route
    // on the map, well beyond the legend's sample of the scale (a few columns of it).
    let (peak, limit) = peak_and_limit(&traced);
    assert!(peak > 0.97 * limit && peak <= limit * 1.001, "{peak} m/s");
    let fast = speed_color(peak, limit);
    let on_map = traced_png.find(fast, 6, map_rows.clone());
    assert!(
        on_map.len() > 100,
        "{} fast pixels on the map",
        on_map.len()
    );
    let (ys, xs): (Vec<u32>, Vec<u32>) = on_map.iter().map(|&(x, y)| (y, x)).unzip();
    let spread = |v: &[u32]| v.iter().max().unwrap() - v.iter().min().unwrap();
    assert!(
        spread(&xs) > 15 && spread(&ys) > 15,
        "the fast colour runs along a diagonal route"
    );
    assert!(plain_png.find(fast, 6, map_rows).is_empty());
    // Both ends of the scale are in the speed panel: the vehicle starts and ends at rest.
    let slow = speed_color(0.0, limit);
    assert!(traced_png.find(slow, 6, strip_rows.clone()).len() > 10);
    assert!(traced_png.find(fast, 6, strip_rows.clone()).len() > 10);
    // The limits' dashed lines are the strip's red.
    assert!(traced_png.find([222, 30, 30], 0, strip_rows).len() > 200);
}

#[test]
fn the_svg_names_the_panel_axes_the_limits_and_the_duration() {
    let (session, _, traced) = plans(None);
    let svg = String::from_utf8(picture(&session, &traced, PlotFormat::Svg)).unwrap();
    let duration = traced.trajectory.as_ref().unwrap().duration_s;
    for text in [
        "SPEED (m/s)",
        "ACCELERATION (m/s²)",
        "TIME (s)",
        "speed limit 10.0 m/s",
        "acceleration limit 4.0 m/s²",
        "trajectory, speed 0 → 10.0 m/s (limit)",
        &format!("trajectory {duration:.1} s"),
    ] {
        assert!(svg.contains(text), "{text:?} missing");
    }
}

#[test]
fn a_3d_plan_shows_its_trajectory_in_the_top_view_and_the_panel() {
    let (session, plain, traced) = plans(Some(PlannerId::Prm));
    let plain_png = Image::decode(&picture(&session, &plain, PlotFormat::Png));
    let traced_png = Image::decode(&picture(&session, &traced, PlotFormat::Png));
    assert_eq!(traced_png.width, plain_png.width);
    assert!(traced_png.height > plain_png.height + 200);
    let (peak, limit) = peak_and_limit(&traced);
    let fast = speed_color(peak, limit);
    assert!(traced_png.find(fast, 6, 0..plain_png.height).len() > 100);
    assert!(plain_png.find(fast, 6, 0..plain_png.height).is_empty());
}

#[test]
fn without_a_trajectory_the_picture_is_the_same_bytes() {
    for planner in [None, Some(PlannerId::Prm)] {
        let (session, plain, traced) = plans(planner);
        let mut untraced = traced.clone();
        untraced.trajectory = None;
        for format in [PlotFormat::Png, PlotFormat::Svg] {
            let a = picture(&session, &plain, format);
            let b = picture(&session, &untraced, format);
            assert!(a == b, "{planner:?} {format:?}: the pictures differ");
            assert_ne!(a, picture(&session, &traced, format));
        }
    }
}

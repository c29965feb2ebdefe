//! With the `clap` feature: the value parsers and help headings of the command-line options
//! derived from [`PlanRequest`](crate::PlanRequest) and [`CostmapOptions`](crate::CostmapOptions),
//! for front ends built on `clap`.

/// Help heading of the grid-path options.
pub const GRID: &str = "Grid paths";
/// Help heading of the navigation functions' options.
pub const NAVFN: &str = "Navigation functions (wavefront, costmap)";
/// Help heading of the 3D planners' options.
pub const THREE_D: &str = "3D planners (prm, lazy-prm, rrt-connect, rrt-star, voxel)";

/// A finite number.
///
/// ```
/// assert_eq!(skyplan_plan::cli::finite("-2.5"), Ok(-2.5));
/// assert!(skyplan_plan::cli::finite("inf").is_err());
/// ```
pub fn finite(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("expected a finite number, found {s:?}")),
    }
}

/// Two finite numbers typed as `A,B`.
///
/// ```
/// assert_eq!(skyplan_plan::cli::pair("12.5, -40"), Ok([12.5, -40.0]));
/// assert!(skyplan_plan::cli::pair("12.5").unwrap_err().contains("two comma-separated numbers"));
/// ```
pub fn pair(s: &str) -> Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [a, b] = parts[..] else {
        return Err(format!(
            "expected two comma-separated numbers like `12.5,-40`, found {s:?}"
        ));
    };
    let num = |t: &str| finite(t).map_err(|e| format!("{e} in {s:?}"));
    Ok([num(a)?, num(b)?])
}

impl clap::ValueEnum for crate::PlannerId {
    fn value_variants<'a>() -> &'a [Self] {
        crate::PlannerId::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let info = self.info();
        Some(clap::builder::PossibleValue::new(info.name).help(info.summary))
    }
}

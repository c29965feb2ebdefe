//! How front ends read typed values: the value parsers and help headings of the command-line
//! options (with the `clap` feature, [`PlanRequest`](crate::PlanRequest) and
//! [`CostmapOptions`](crate::CostmapOptions) are `clap` arguments and [`PlannerId`](crate::PlannerId)
//! a `clap` value), and the text of a targets file.

/// Help heading of the grid-path options.
pub const GRID: &str = "Grid paths";
/// Help heading of the navigation functions' options.
pub const NAVFN: &str = "Navigation functions (wavefront, costmap)";
/// Help heading of the trajectory options.
pub const TRAJECTORY: &str = "Trajectories (any planner)";
/// Help heading of the 3D planners' options, naming them from the registry.
pub fn three_d() -> &'static str {
    static HEADING: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
        let names = crate::PlannerId::names_where(|p| p.info().dims == 3);
        format!("3D planners ({names})")
    });
    &HEADING
}

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

/// A latitude,longitude in degrees: latitude in [-90, 90], longitude in [-180, 180].
///
/// ```
/// assert_eq!(skyplan_plan::cli::lat_lon("37.79,-122.39"), Ok([37.79, -122.39]));
/// assert!(skyplan_plan::cli::lat_lon("97.8,-122.4").unwrap_err().contains("latitude in [-90, 90]"));
/// ```
pub fn lat_lon(s: &str) -> Result<[f64; 2], String> {
    match pair(s)? {
        [lat, lon] if (-90.0..=90.0).contains(&lat) && (-180.0..=180.0).contains(&lon) => {
            Ok([lat, lon])
        }
        [lat, lon] => Err(format!(
            "expected latitude in [-90, 90] and longitude in [-180, 180], found {lat},{lon}"
        )),
    }
}

/// A targets file's text: one `N,E` per line (metres north,east), `#` starts a comment; an
/// error names the line.
///
/// ```
/// let text = "# patrol\n10,20\n\n-5.5, 3  # the gate\n";
/// assert_eq!(skyplan_plan::cli::targets_text(text), Ok(vec![[10.0, 20.0], [-5.5, 3.0]]));
/// assert!(skyplan_plan::cli::targets_text("1,2\n3\n").unwrap_err().starts_with("line 2: "));
/// assert!(skyplan_plan::cli::targets_text("# none\n").is_err());
/// ```
pub fn targets_text(text: &str) -> Result<Vec<[f64; 2]>, String> {
    let mut targets = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if !line.is_empty() {
            targets.push(pair(line).map_err(|e| format!("line {}: {e}", k + 1))?);
        }
    }
    if targets.is_empty() {
        return Err("no targets (expected one N,E per line)".into());
    }
    Ok(targets)
}

#[cfg(feature = "clap")]
impl clap::ValueEnum for crate::PlannerId {
    fn value_variants<'a>() -> &'a [Self] {
        crate::PlannerId::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let info = self.info();
        Some(clap::builder::PossibleValue::new(info.name).help(info.summary))
    }
}

/// A planning message in the command line's words: each request key (`alt_m`, `goal_alt_m`, …)
/// becomes the option a user types (`--alt-m`, `--goal-alt-m`), and a message about the
/// planner (`planner ch: …`, `not used by planner jps`) names `--planner`. The table is the
/// command line's own options, derived from [`PlanRequest`](crate::PlanRequest), so the CLI
/// and the API can never disagree about a name.
///
/// ```
/// use skyplan_plan::cli::in_cli_words;
/// assert_eq!(in_cli_words("alt_m -5: expected a number from 0 to 10000 m"),
///            "--alt-m -5: expected a number from 0 to 10000 m");
/// assert_eq!(in_cli_words("goal_alt_m is not used by planner jps: it needs a planner that uses it (prm)"),
///            "--goal-alt-m is not used by --planner jps: it needs a planner that uses it (prm)");
/// assert_eq!(in_cli_words("planner ch: the deadline passed"), "--planner ch: the deadline passed");
/// assert_eq!(in_cli_words("sample_hz is used only with a trajectory: ask for one (trajectory true)"),
///            "--sample-hz is used only with a trajectory: ask for one (--trajectory)");
/// assert!(in_cli_words("raise the limit (max_memory)").ends_with("(--max-memory)"));
/// ```
#[cfg(feature = "clap")]
pub fn in_cli_words(message: &str) -> String {
    use clap::Args;
    use std::collections::HashMap;
    use std::sync::LazyLock;
    static FLAGS: LazyLock<HashMap<String, String>> = LazyLock::new(|| {
        let command = crate::PlanRequest::augment_args(clap::Command::new("plan"));
        command
            .get_arguments()
            .filter_map(|a| Some((a.get_id().to_string(), format!("--{}", a.get_long()?))))
            .filter(|(key, _)| key.contains('_'))
            // The session's memory limit (`Limits`), an option of every command that plans.
            .chain([("max_memory".to_string(), "--max-memory".to_string())])
            // The zones' file, read by the CLI into the request's text.
            .chain([("no_fly".to_string(), "--no-fly".to_string())])
            .collect()
    });
    let mut out = String::with_capacity(message.len() + 8);
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        match FLAGS.get(word.as_str()) {
            Some(flag) if !out.ends_with('-') => out.push_str(flag),
            _ => out.push_str(word),
        }
        word.clear();
    };
    for ch in message.chars() {
        if ch.is_ascii_alphanumeric() || ch == '_' {
            word.push(ch);
        } else {
            flush(&mut word, &mut out);
            out.push(ch);
        }
    }
    flush(&mut word, &mut out);
    if out.starts_with("planner ") {
        out.insert_str(0, "--");
    }
    out.replace("by planner ", "by --planner ")
        .replace("(trajectory true)", "(--trajectory)")
}

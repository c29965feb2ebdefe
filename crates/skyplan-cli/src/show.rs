//! `--show`: the workspace, the distance matrix and the path as text; the terminal prompt for a
//! start or goal on grid maps without defaults; progress bars.

use crate::exit::{Classify, Kind, Result, bad_input};
use crate::report::Human;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use skyplan_cspace::{Cell, Grid2};
use skyplan_navfn::{FieldMetric, show};
use skyplan_search::MoveModel;
use std::io::{BufRead, Write};

/// Prints the workspace (with the wavefront field's unreachable cells), the distance matrix and
/// the path on standard output.
pub fn print(grid: &Grid2, start: Cell, goal: Cell, path: &[Cell], model: MoveModel, steps: bool) {
    print_to(Human::Stdout, grid, start, goal, path, model, steps);
}

/// As [`print`], on the stream `to` (standard error when standard output carries a document).
pub fn print_to(
    to: Human,
    grid: &Grid2,
    start: Cell,
    goal: Cell,
    path: &[Cell],
    model: MoveModel,
    steps: bool,
) {
    let metric = if steps {
        FieldMetric::Steps
    } else {
        FieldMetric::Length
    };
    match show::picture(grid, start, goal, path, model, metric) {
        Ok(text) => to.print(&text),
        Err(why) => eprintln!("--show: {why} (use --plot)"),
    }
}

/// A progress bar of `len` steps (`None`: a spinner) in `template`'s style, drawn on `target`.
pub fn progress(template: &str, len: Option<u64>, target: ProgressDrawTarget) -> ProgressBar {
    let style =
        ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar());
    ProgressBar::with_draw_target(len, target).with_style(style.progress_chars("=> "))
}

/// A spinner with `message` and the elapsed time on a terminal's stderr (hidden elsewhere),
/// for work that takes a while without steps to count: a contraction hierarchy or a table
/// being built, RRT* spending its time limit.
pub fn spinner(message: String) -> ProgressBar {
    if !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return ProgressBar::hidden();
    }
    let bar = progress(
        "{spinner} {msg} ({elapsed})",
        None,
        ProgressDrawTarget::stderr(),
    )
    .with_message(message);
    bar.enable_steady_tick(std::time::Duration::from_millis(150));
    bar
}

/// Asks on the terminal until the answer is a free cell on the map.
pub fn ask_position(grid: &Grid2, which: &str) -> Result<[f64; 2]> {
    let extent = {
        let f = grid.frame();
        format!(
            "north {:.2}..{:.2} m, east {:.2}..{:.2} m",
            f.origin_north_m,
            f.origin_north_m + f64::from(grid.rows()) * f.cell_m,
            f.origin_east_m,
            f.origin_east_m + f64::from(grid.cols()) * f.cell_m
        )
    };
    let stdin = std::io::stdin();
    loop {
        eprint!("{which} as N,E metres ({extent}): ");
        let _ = std::io::stderr().flush();
        let mut line = String::new();
        let read = stdin.lock().read_line(&mut line).or_exit(Kind::Runtime)?;
        if read == 0 {
            return Err(bad_input(format!("no {which} given (end of input)")));
        }
        match skyplan_plan::cli::pair(line.trim()) {
            Err(e) => eprintln!("  {e}; try again"),
            Ok([n, e]) => match grid.cell_at_ne(n, e) {
                Some(c) if !grid.is_blocked(c) => return Ok([n, e]),
                Some(_) => eprintln!("  N {n} m, E {e} m is at an obstacle; try again"),
                None => eprintln!("  N {n} m, E {e} m is off the map; try again"),
            },
        }
    }
}

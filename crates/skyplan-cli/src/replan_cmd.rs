//! Replanning in flight, the CLI's side: `--replanner`, the flight picture, and `bench --replan`
//! (the flights are `skyplan_flyer::runner`'s).

use crate::exit::Result;
use skyplan_flyer::runner::Flight;
use skyplan_map::colliders::ObstacleBox;
use skyplan_plan::World;
use skyplan_replan::ReplannerKind;
use skyplan_replan::bench::ScenarioSpec;

/// `--replanner`: which search replans when the sensor finds the route blocked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ReplannerArg {
    /// D* Lite: one search kept and repaired across replans.
    DstarLite,
    /// JPS from scratch on the known and learned grid at every replan.
    Scratch,
    /// Never replan: fly the first route whatever the sensor sees.
    Off,
}

impl ReplannerArg {
    pub fn kind(self) -> Option<ReplannerKind> {
        match self {
            ReplannerArg::DstarLite => Some(ReplannerKind::DStarLite),
            ReplannerArg::Scratch => Some(ReplannerKind::Scratch),
            ReplannerArg::Off => None,
        }
    }

    /// The `--replanner` spelling.
    pub fn name(self) -> &'static str {
        self.kind().map_or("off", ReplannerKind::name)
    }
}

/// `skyplan bench --replan N`: N seeded flights per replanner, one row each, progress on stderr.
pub fn bench(world: &World, spec: &ScenarioSpec, speedup: f64) -> Result<String> {
    // The `\r` progress line only on a terminal: redirected stderr gets no control characters.
    let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let table = skyplan_flyer::runner::replan_bench(world, spec, speedup, |kind, k, n| {
        if terminal {
            eprint!("\rbench --replan: {kind} flight {k}/{n}   ")
        }
    })?;
    if terminal {
        eprintln!();
    }
    Ok(table)
}

/// `fly --plot`: the first plan's picture with what the flight added — hidden buildings, the
/// cells the vehicle learned, every replanned route and the flown track.
pub fn flight_picture(
    world: &World,
    kind: &crate::picture::PictureKind,
    flight: &Flight,
    hidden: &[ObstacleBox],
    zones: &[skyplan_map::nofly::Zone],
) -> Result<Vec<u8>> {
    let (learned, track) = (flight.learned_ne(), flight.track_ne());
    let track_alt_m: Vec<f64> = flight.log.iter().map(|r| r.alt_m).collect();
    let layers = skyplan_plot::FlightLayers {
        hidden,
        learned_ne: &learned,
        replanned_ne: &flight.replanned,
        track_ne: &track,
        track_alt_m: &track_alt_m,
    };
    crate::picture::render(world, &flight.plan, kind, Some(&layers), zones)
}

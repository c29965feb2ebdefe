//! `skyplan serve`: the planning API over HTTP and the live-view page (skyplan-server).

use crate::args::ServeArgs;
use crate::exit::{Result, runtime};
use skyplan_server::ServerConfig;
use std::time::Duration;

pub fn run(args: ServeArgs) -> Result<()> {
    let limits = crate::args::limits(None);
    let mut world = crate::world_load::load_world(args.map.as_deref(), &args.grid, 1, &limits)?;
    if let Some(path) = &args.terrain {
        world = crate::world_load::with_terrain(world, path)?;
    }
    // Opened once here so that a bad address or database fails the command, not each request.
    skyplan_server::open_airspace(&args.airspace)
        .map_err(|e| runtime(format!("--airspace {}: {e}", args.airspace)))?;
    let no_fly = match &args.no_fly {
        Some(path) => {
            let text = crate::files::read_text(path)?;
            // Checked here so that the error names the file.
            skyplan_map::nofly::parse_no_fly(&text)
                .map_err(|e| crate::exit::bad_input(format!("{}: {e}", path.display())))?;
            Some(text)
        }
        None => None,
    };
    let mut config = ServerConfig {
        timeout: Duration::from_millis(args.timeout_ms),
        airspace: args.airspace.clone(),
        no_fly,
        ..ServerConfig::default()
    };
    if let Some(n) = args.max_concurrent {
        config.max_concurrent = usize::from(n);
    }
    if let Some(n) = args.queue_depth {
        config.queue_depth = Some(n as usize);
    }
    let (name, workers, queue, budget_ms, airspace) = (
        world.name().to_string(),
        config.max_concurrent,
        config.effective_queue_depth(),
        args.timeout_ms,
        args.airspace.clone(),
    );
    skyplan_server::run(world, config, args.bind, |addr| {
        println!(
            "skyplan serve: http://{addr}/ ({name}; {workers} concurrent plans, {queue} more queued, {budget_ms} ms per request; airspace {airspace}; Ctrl-C stops)"
        );
    })
    .map_err(|e| runtime(format!("serve on {}: {e}", args.bind)))
}

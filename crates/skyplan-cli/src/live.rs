//! `fly --view ADDR` and `fly --record FILE.mcap`: the live view (skyplan-server's page) and the
//! MCAP recording of a flight — the events are `skyplan_server::live::Live`'s; this starts the
//! view, opens the recording (a temporary file beside the target, renamed when the flight ends)
//! and says where they are. `sim --view ADDR` publishes the simulator's state the same way.

use crate::exit::{Classify, Kind, Result, bad_input, runtime};
use crate::files::{Target, output_target};
use skyplan_plan::World;
use skyplan_server::{Recorder, ViewServer};
use std::fs::File;
use std::path::{Path, PathBuf};

/// Where a flight's events go, and the recording's target and temporary file.
#[derive(Default)]
pub struct Live {
    pub events: skyplan_server::live::Live<File>,
    record: Option<(PathBuf, PathBuf)>,
}

impl Live {
    /// Starts the view server and opens the recording, before anything flies.
    pub fn start(world: &World, view: Option<&str>, record: Option<&Path>) -> Result<Self> {
        let server = match view {
            Some(addr) => {
                let server = ViewServer::start(world.clone(), addr)
                    .map_err(|e| bad_input(format!("--view {addr}: {e}")))?;
                println!("view       http://{}/ (the live view)", server.addr());
                Some(server)
            }
            None => None,
        };
        let (recorder, record) = match record {
            Some(path) => {
                let Target::File(target) = output_target("--record", path)? else {
                    return Err(bad_input(
                        "--record: a recording needs a file, not standard output",
                    ));
                };
                let tmp = target.with_extension(format!("mcap.{}.tmp", std::process::id()));
                let file = File::create(&tmp)
                    .map_err(|e| runtime(format!("--record {}: {e}", tmp.display())))?;
                let recorder =
                    Recorder::new(file, world).map_err(|e| runtime(format!("--record: {e}")))?;
                (Some(recorder), Some((target, tmp)))
            }
            None => (None, None),
        };
        Ok(Live {
            events: skyplan_server::live::Live::new(server, recorder),
            record,
        })
    }

    /// Closes the recording (renamed into place) and says where it is; a live view keeps
    /// serving for a moment so that open pages see the end of the flight.
    pub fn finish(self) -> Result<()> {
        if let (Some(recorder), Some((target, tmp))) = (self.events.finish(), self.record) {
            recorder
                .finish()
                .map_err(|e| runtime(format!("--record: {e}")))?;
            std::fs::rename(&tmp, &target).or_exit(Kind::Runtime)?;
            println!("wrote      flight recording {} (MCAP)", target.display());
        }
        Ok(())
    }
}

//! File access for the CLI: reading inputs with their names in errors; outputs checked before
//! anything is planned, then written atomically (a temporary file beside the target, renamed).

use crate::exit::{Classify, Kind, Result, bad_input};
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Reads a text file; a missing or unreadable file is bad input.
pub fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path)
        .with_context(|| format!("cannot read {}", path.display()))
        .or_exit(Kind::BadInput)
}

/// Reads a binary file; a missing or unreadable file is bad input.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path)
        .with_context(|| format!("cannot read {}", path.display()))
        .or_exit(Kind::BadInput)
}

/// What a `--preprocess` file holds, told by its header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Saved {
    /// A JPS+ table (with landmarks when saved by this version).
    JpsPlus,
    /// A contraction hierarchy.
    Hierarchy,
    /// A first-move table.
    FirstMove,
    /// A subgoal graph (its contraction hierarchy).
    Subgoal,
    /// None of them.
    Unknown,
}

impl Saved {
    /// The planner that keeps this kind of preprocessing.
    pub fn planner(self) -> Option<skyplan_plan::PlannerId> {
        use skyplan_plan::PlannerId;
        match self {
            Saved::JpsPlus => Some(PlannerId::JpsPlus),
            Saved::Hierarchy => Some(PlannerId::Ch),
            Saved::FirstMove => Some(PlannerId::FirstMove),
            Saved::Subgoal => Some(PlannerId::Subgoal),
            Saved::Unknown => None,
        }
    }
}

/// What `--preprocess FILE` names when the file is none of the kinds (for error messages).
pub const NOT_SAVED: &str = "not a saved JPS+ table, contraction hierarchy, subgoal graph or first-move table (save one with --save-preprocess)";

/// Opens the `--preprocess` file `path` (a contraction hierarchy, subgoal graph, JPS+ table or
/// first-move table) and tells which it is, by its header; errors name the option and the file.
pub fn open_preprocess(path: &Path) -> Result<(std::io::BufReader<std::fs::File>, Saved)> {
    let shown = path.display();
    let file = std::fs::File::open(path)
        .map_err(|e| bad_input(format!("--preprocess {shown}: cannot open: {e}")))?;
    let mut input = std::io::BufReader::new(file);
    let head = std::io::BufRead::fill_buf(&mut input)
        .map_err(|e| bad_input(format!("--preprocess {shown}: cannot read: {e}")))?;
    let kind = if head.starts_with(skyplan_search::first_move_file::MAGIC) {
        Saved::FirstMove
    } else if head.starts_with(skyplan_search::ch_file::MAGIC) {
        Saved::Hierarchy
    } else if head.starts_with(skyplan_search::subgoal_file::MAGIC) {
        Saved::Subgoal
    } else if head.starts_with(skyplan_search::table_file::MAGIC) {
        Saved::JpsPlus
    } else {
        Saved::Unknown
    };
    Ok((input, kind))
}

/// A map's name and text: the file, or the bundled FCND city map, named `bundled_name`.
pub fn map_text(map: Option<&Path>, bundled_name: &str) -> Result<(String, String)> {
    Ok(match map {
        Some(path) => (path.display().to_string(), read_text(path)?),
        None => (
            bundled_name.to_string(),
            skyplan_plan::FCND_CITY_CSV.to_string(),
        ),
    })
}

/// Where an output goes: standard output for `-`, else the file the path names (a symlink is
/// followed to its target, so the link survives).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    Stdout,
    File(PathBuf),
}

/// Checks an output path before anything is planned: `-` is standard output; a regular file or
/// a path that does not exist yet (in an existing directory) is written; anything else — a
/// device, a FIFO, a socket, a directory — is refused (exit 2) and left untouched.
pub fn output_target(option: &str, path: &Path) -> Result<Target> {
    if path.as_os_str() == "-" {
        return Ok(Target::Stdout);
    }
    let resolved = match std::fs::canonicalize(path) {
        Ok(p) => p,
        Err(_) => path.to_path_buf(),
    };
    match std::fs::metadata(&resolved) {
        Ok(m) if m.is_file() => Ok(Target::File(resolved)),
        Ok(m) => Err(bad_input(format!(
            "{option} {}: {}; skyplan writes only regular files (or - for standard output)",
            path.display(),
            not_a_file(&m)
        ))),
        Err(_) => {
            let dir = match resolved.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            if dir.is_dir() {
                Ok(Target::File(resolved))
            } else {
                Err(bad_input(format!(
                    "{option} {}: the directory {} does not exist",
                    path.display(),
                    dir.display()
                )))
            }
        }
    }
}

/// What a path that is not a regular file is, for a refusal.
fn not_a_file(m: &std::fs::Metadata) -> &'static str {
    if m.is_dir() {
        "a directory"
    } else {
        "not a regular file (a device, FIFO or socket)"
    }
}

/// Writes `bytes` to a checked target: standard output, or atomically to the file (a temporary
/// file beside it, then a rename), so a reader never sees a half-written file.
pub fn write_target(target: &Target, bytes: &[u8]) -> Result<()> {
    match target {
        Target::Stdout => match std::io::stdout().write_all(bytes) {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => crate::exit_closed_stdout(),
            other => other
                .context("writing to standard output")
                .or_exit(Kind::Runtime),
        },
        Target::File(path) => write_atomic(path, bytes),
    }
}

/// Writes `bytes` to `path` atomically: a temporary file beside it, then a rename, so a reader
/// never sees a half-written file and a failure leaves any previous file intact.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Streams `write`'s output to `path` atomically (buffered), as [`write_atomic`] writes bytes.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    // The rename would put a regular file in place of a device, FIFO, socket or directory
    // (as root, even /dev/null): refused whatever the caller checked before.
    if let Ok(m) = std::fs::metadata(path)
        && !m.is_file()
    {
        return Err(bad_input(format!(
            "{}: {}; skyplan writes only regular files (or - for standard output)",
            path.display(),
            not_a_file(&m)
        )));
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
    let result = (|| -> anyhow::Result<()> {
        let f = std::fs::File::create(&tmp)
            .with_context(|| format!("cannot create {}", tmp.display()))?;
        let mut out = std::io::BufWriter::new(f);
        write(&mut out).with_context(|| format!("cannot write {}", tmp.display()))?;
        out.into_inner()
            .map_err(|e| e.into_error())
            .and_then(|f| f.sync_all())
            .with_context(|| format!("cannot flush {}", tmp.display()))?;
        std::fs::rename(&tmp, path)
            .with_context(|| format!("cannot move {} to {}", tmp.display(), path.display()))?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
        .with_context(|| format!("writing {}", path.display()))
        .or_exit(Kind::Runtime)
}

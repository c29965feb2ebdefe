//! File access for the CLI: reading inputs with their names in errors, atomic writes.

use crate::exit::{Classify, Kind, Result};
use anyhow::Context;
use std::io::Write;
use std::path::Path;

/// The FCND city map, compiled into the binary so that `skyplan plan` works anywhere.
pub const BUNDLED_COLLIDERS: &str = include_str!("../../../data/colliders.csv");
/// How the bundled map is named in messages and metadata.
pub const BUNDLED_NAME: &str = "colliders.csv (bundled FCND city map)";

/// Reads a text file; a missing or unreadable file is bad input.
pub fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path)
        .with_context(|| format!("cannot read {}", path.display()))
        .or_exit(Kind::BadInput)
}

/// Writes `bytes` to `path` atomically: a temporary file beside it, then a rename, so a reader
/// never sees a half-written file and a failure leaves any previous file intact.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
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
        let mut f = std::fs::File::create(&tmp)
            .with_context(|| format!("cannot create {}", tmp.display()))?;
        f.write_all(bytes)
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        f.sync_all()
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

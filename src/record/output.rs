//! Output files that a reader never sees half-written: data goes to `NAME.partial` and is renamed
//! to `NAME` when finished — also when a run stops early, since what it wrote is then complete
//! as far as it goes (the metrics say whether the run was).

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// The temporary name beside `path`.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".partial");
    path.with_file_name(name)
}

/// Checks, before a simulation starts, that `path` can be created (its folder exists and is
/// writable), so a long run does not fail at its end.
pub fn check_writable(path: &Path) -> Result<()> {
    let probe = partial_path(path);
    std::fs::File::create(&probe).with_context(|| {
        format!(
            "cannot write {}: check that its folder exists and is writable",
            path.display()
        )
    })?;
    std::fs::remove_file(&probe).ok();
    Ok(())
}

/// Moves the finished temporary file to its final name.
pub fn commit(path: &Path) -> Result<()> {
    std::fs::rename(partial_path(path), path)
        .with_context(|| format!("cannot move the finished file to {}", path.display()))
}

/// Writes `contents` to `path` through the temporary name.
pub fn write_atomically(path: &Path, contents: &[u8]) -> Result<()> {
    std::fs::write(partial_path(path), contents)
        .with_context(|| format!("cannot write {}", path.display()))?;
    commit(path)
}

/// Writes `value` as JSON to `path`, if there is one, through the temporary name; names it.
pub fn write_json(path: Option<&Path>, value: &impl serde::Serialize) -> Result<Option<PathBuf>> {
    let Some(path) = path else { return Ok(None) };
    write_atomically(path, serde_json::to_string_pretty(value)?.as_bytes())?;
    Ok(Some(path.to_path_buf()))
}

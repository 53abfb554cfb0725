//! Output files that a reader never sees half-written, and that never replace what they should
//! not: data goes to `NAME.partial` and is renamed to `NAME` when finished — also when a run stops
//! early, since what it wrote is then complete as far as it goes (the metrics say whether the run
//! was). A symlink is followed (its target is written, the link stays); a device or FIFO is
//! written straight through (a rename would replace the node with a file). An output that is an
//! input, or another output, is refused before anything is written ([`check_distinct`]).

use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// `path` with its symlinks followed, also a dangling one (whose target is then created).
fn followed(path: &Path) -> PathBuf {
    let mut path = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&path) {
            Ok(meta) if meta.file_type().is_symlink() => match std::fs::read_link(&path) {
                Ok(target) => path = path.parent().unwrap_or(Path::new("")).join(target),
                Err(_) => break,
            },
            _ => break,
        }
    }
    path
}

/// True if `path` is a device, FIFO or socket: written through, never renamed over.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// The name `path`'s data is written to: the temporary name beside the file it names (a
/// symlink's target), or the device or FIFO itself.
pub fn partial_path(path: &Path) -> PathBuf {
    let path = followed(path);
    if is_special(&path) {
        return path;
    }
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".partial");
    path.with_file_name(name)
}

/// Checks, before a simulation starts, that `path` can be created (its folder exists and is
/// writable, it is not a folder), so a long run does not fail at its end.
pub fn check_writable(path: &Path) -> Result<()> {
    let target = followed(path);
    if target.is_dir() {
        bail!("cannot write {}: it is a folder", path.display());
    }
    if is_special(&target) {
        // opening a FIFO would wait for its reader; a device is checked when written
        return Ok(());
    }
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

/// Creates the folder `path` (with its parents) that a command writes its files into, or says
/// which folder and why not: `what` is the option that named it.
pub fn create_folder(path: &Path, what: &str) -> Result<()> {
    if path.exists() && !path.is_dir() {
        bail!(
            "{what} {}: it is a file, and a folder is expected here; name a folder",
            path.display()
        );
    }
    std::fs::create_dir_all(path)
        .with_context(|| format!("{what} {}: cannot create this folder", path.display()))
}

/// Moves the finished temporary file to its final name (a device or FIFO has none).
pub fn commit(path: &Path) -> Result<()> {
    let target = followed(path);
    if is_special(&target) {
        return Ok(());
    }
    std::fs::rename(partial_path(path), &target)
        .with_context(|| format!("cannot move the finished file to {}", path.display()))
}

/// Writes `contents` to `path` through the temporary name ([`write_streamed`]); a write that
/// fails (a full disk) names the file and leaves no temporary behind.
pub fn write_atomically(path: &Path, contents: &[u8]) -> Result<()> {
    write_streamed(path, |out| Ok(std::io::Write::write_all(out, contents)?))
}

/// Streams a file to `path` through the temporary name: `write` fills a buffered writer, which
/// is flushed and renamed into place; a write that fails (a full disk) names the file and leaves
/// no temporary behind.
pub fn write_streamed(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<()>,
) -> Result<()> {
    let partial = partial_path(path);
    let written = std::fs::File::create(&partial)
        .map_err(anyhow::Error::from)
        .and_then(|file| {
            let mut out = std::io::BufWriter::new(file);
            write(&mut out)?;
            let file = out.into_inner().map_err(|e| e.into_error())?;
            file.sync_all().or_else(|e| {
                // a device or FIFO cannot be synced, and need not be
                if is_special(&partial) { Ok(()) } else { Err(e) }
            })?;
            Ok(())
        });
    if let Err(e) = written {
        if !is_special(&partial) {
            std::fs::remove_file(&partial).ok();
        }
        return Err(e).with_context(|| format!("cannot write {}", path.display()));
    }
    commit(path)
}

/// Writes `value` as JSON to `path`, if there is one, through the temporary name; names it.
pub fn write_json(path: Option<&Path>, value: &impl serde::Serialize) -> Result<Option<PathBuf>> {
    let Some(path) = path else { return Ok(None) };
    write_atomically(path, serde_json::to_string_pretty(value)?.as_bytes())?;
    Ok(Some(path.to_path_buf()))
}

/// What identifies a file, through any path to it: its device and inode if it exists, else its
/// folder's canonical path and its name. None for a character device (`/dev/null`), which any
/// number of outputs may share.
fn identity(path: &Path) -> Option<(u64, u64, PathBuf)> {
    use std::os::unix::fs::{FileTypeExt, MetadataExt};
    let path = followed(path);
    match std::fs::metadata(&path) {
        Ok(meta) if meta.file_type().is_char_device() => None,
        Ok(meta) => Some((meta.dev(), meta.ino(), PathBuf::new())),
        Err(_) => {
            let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
            let folder = folder.unwrap_or(Path::new("."));
            let folder = folder.canonicalize().unwrap_or(folder.to_path_buf());
            Some((0, 0, folder.join(path.file_name()?)))
        }
    }
}

/// Refuses, before anything is written, an output that is one of the `inputs` or another of the
/// `outputs` — the same file through any path (a symlink, `..`, a hard link).
pub fn check_distinct<'a, 'b>(
    outputs: impl IntoIterator<Item = (&'static str, &'a Path)>,
    inputs: impl IntoIterator<Item = (&'static str, &'b Path)>,
) -> Result<()> {
    let inputs: Vec<_> = inputs
        .into_iter()
        .filter(|(_, p)| p.exists())
        .filter_map(|(what, p)| Some((what, p, identity(p)?)))
        .collect();
    let mut seen: Vec<(&str, &Path, (u64, u64, PathBuf))> = Vec::new();
    for (what, path) in outputs {
        let Some(id) = identity(path) else { continue };
        if let Some((input, file, _)) = inputs.iter().find(|(_, _, i)| *i == id) {
            bail!(
                "{what} {}: it is the {input} {}, which this command reads; name another file",
                path.display(),
                file.display()
            );
        }
        if let Some((other, file, _)) = seen.iter().find(|(_, _, i)| *i == id) {
            bail!(
                "{what} {}: it is the same file as the {other} {}; name another file",
                path.display(),
                file.display()
            );
        }
        seen.push((what, path, id));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_output_folder_that_is_a_file_is_named_in_the_error() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("taken");
        std::fs::write(&file, "x").unwrap();
        let e = create_folder(&file, "--output").unwrap_err().to_string();
        assert!(
            e.starts_with("--output ") && e.contains("taken: it is a file"),
            "{e}"
        );
        let nested = dir.path().join("a/b");
        create_folder(&nested, "--output").unwrap();
        create_folder(&nested, "--output").unwrap();
        assert!(nested.is_dir());
        let under_file = file.join("sub");
        let e = format!("{:#}", create_folder(&under_file, "--output").unwrap_err());
        assert!(e.contains("taken/sub: cannot create this folder"), "{e}");
    }

    #[test]
    fn an_output_that_is_an_input_or_another_output_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("terrain.toml");
        std::fs::write(&input, "x").unwrap();
        let link = dir.path().join("link.csv");
        std::os::unix::fs::symlink(&input, &link).unwrap();
        let via_dots = dir.path().join("sub/../terrain.toml");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let new = dir.path().join("new.csv");
        let inputs = [("terrain", input.as_path())];
        for clash in [&input, &link, &via_dots] {
            let e = check_distinct([("--trajectory", clash.as_path())], inputs).unwrap_err();
            assert!(e.to_string().contains("it is the terrain"), "{e}");
        }
        let e = check_distinct(
            [("--trajectory", new.as_path()), ("--metrics", &new)],
            inputs,
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("the same file as the --trajectory"),
            "{e}"
        );
        let null = Path::new("/dev/null");
        check_distinct([("--trajectory", null), ("--metrics", null)], inputs).unwrap();
        check_distinct([("--trajectory", new.as_path())], inputs).unwrap();
    }

    #[test]
    fn a_symlink_is_written_through_and_a_device_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.json");
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_atomically(&link, b"{}").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"{}");
        write_atomically(Path::new("/dev/null"), b"{}").unwrap();
        let e = write_atomically(Path::new("/dev/full"), b"{}").unwrap_err();
        assert!(format!("{e:#}").contains("cannot write /dev/full"), "{e:#}");
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::metadata("/dev/full")
                .unwrap()
                .file_type()
                .is_char_device()
        );
    }
}

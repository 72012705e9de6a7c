//! Reports: readable timelines, JSON objects and CSV tables, each written whole or not at all.

pub mod fit;
pub mod joint;
pub mod plan;
pub mod plot;
pub mod regions;
mod simulate;

pub use simulate::{simulation_json, timeline, write_trajectory_csv};

use std::io::Write;
use std::path::Path;

/// Write a file through a temporary sibling and a rename, so a failure never leaves half a
/// file behind. A symbolic link is followed (the file it points to is replaced, the link
/// stays); a special file (a named pipe, a device such as `/dev/stdout` or `/dev/full`) is
/// written directly, once the whole content is ready, never replaced by a plain file.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let target = output_target(path)?;
    if let Ok(meta) = std::fs::metadata(&target) {
        if meta.is_dir() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the output is a directory",
            ));
        }
        if !meta.is_file() {
            let mut buf = Vec::new();
            fill(&mut buf)?;
            let mut f = std::fs::OpenOptions::new().write(true).open(&target)?;
            f.write_all(&buf)?;
            return f.flush();
        }
    }
    let name = target.file_name().ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "output path has no file name",
        )
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = target.with_file_name(tmp_name);
    let result = (|| {
        let mut file = std::io::BufWriter::new(
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&tmp)?,
        );
        fill(&mut file)?;
        file.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        // Checked again just before the rename: never rename onto something that became a
        // special file or a link in the meantime.
        match std::fs::symlink_metadata(&target) {
            Ok(m) if !m.is_file() => Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the output changed into a link or special file while it was written",
            )),
            _ => std::fs::rename(&tmp, &target),
        }
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The file an output path really names: a symbolic link resolved to the file it points to
/// (which need not exist yet), anything else as given.
pub fn output_target(path: &Path) -> std::io::Result<std::path::PathBuf> {
    let mut target = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&target) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&target)?;
                target = match target.parent() {
                    Some(dir) => dir.join(link),
                    None => link,
                };
            }
            _ => return Ok(target),
        }
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        "too many levels of symbolic links",
    ))
}

/// The canonical form of a path that may not exist yet (its directory canonicalised, links
/// followed), to tell whether two paths name the same file.
pub fn canonical(path: &Path) -> std::path::PathBuf {
    let target = output_target(path).unwrap_or_else(|_| path.to_path_buf());
    if let Ok(c) = std::fs::canonicalize(&target) {
        return c;
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    match (std::fs::canonicalize(&dir), target.file_name()) {
        (Ok(d), Some(n)) => d.join(n),
        _ => target,
    }
}

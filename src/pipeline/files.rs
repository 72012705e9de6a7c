//! Which files a command reads: a directory's recordings, and each release once.

use std::path::{Path, PathBuf};

/// The file endings a directory's recordings may have: the CSV family, MCAP, HDF5 (DeepLabCut,
/// SLEAP), Tracker projects and Kinovea XML; the content decides the format.
pub const RECORDING_EXTENSIONS: [&str; 8] =
    ["csv", "mcap", "txt", "tsv", "h5", "hdf5", "trk", "xml"];

/// Recordings in a directory: files with a recording extension, sorted, and the notes to show.
/// Without a given format, a file whose format cannot be told from its start (a `notes.txt`)
/// is not a recording: it is skipped with a note and the rest are fitted.
pub fn directory_files(
    dir: &Path,
    format_given: bool,
) -> anyhow::Result<(Vec<PathBuf>, Vec<String>)> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| anyhow::anyhow!("{}: cannot list: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .filter(|p| {
            !p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with('.'))
        })
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| RECORDING_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
        })
        .collect();
    files.sort();
    let mut notes = Vec::new();
    if !format_given {
        files.retain(|f| match crate::data::detect(f) {
            Err(e @ crate::data::DataError::UnknownFormat { .. }) => {
                notes.push(format!("skipped, not a recording: {e}"));
                false
            }
            _ => true,
        });
    }
    if files.is_empty() {
        anyhow::bail!(
            "{}: no recordings (.{}) in this directory",
            dir.display(),
            RECORDING_EXTENSIONS.join(", .")
        );
    }
    Ok((files, notes))
}

/// A file's device and inode, or its path as given where it cannot be looked at.
type FileId = Result<(u64, u64), PathBuf>;

/// The identity of a file: its device and inode (any spelling, link or `..` of one file gives
/// the same), or, where the file cannot be opened, its path as given (the read names it).
fn file_id(path: &Path) -> FileId {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path)
        .map(|m| (m.dev(), m.ino()))
        .map_err(|_| path.to_owned())
}

/// One release per file: a release whose files are those of an earlier one (`A` and
/// `DIR/./A`, a link to `A` in the directory, the same Tracker pair twice) is dropped with a
/// note, so no recording is counted twice.
pub fn once_each(paths: Vec<Vec<PathBuf>>) -> (Vec<Vec<PathBuf>>, Vec<String>) {
    let mut seen: Vec<(Vec<FileId>, String)> = Vec::new();
    let mut kept = Vec::new();
    let mut notes = Vec::new();
    for p in paths {
        let id: Vec<_> = p.iter().map(|f| file_id(f)).collect();
        let name = release_name(&p);
        match seen.iter().find(|(other, _)| *other == id) {
            Some((_, first)) => {
                notes.push(format!(
                    "{name} is {first} again (the same file): counted once"
                ));
            }
            None => {
                seen.push((id, name));
                kept.push(p);
            }
        }
    }
    (kept, notes)
}

/// A release's name in messages and the table: its files joined by commas.
pub fn release_name(files: &[PathBuf]) -> String {
    files
        .iter()
        .map(|f| f.display().to_string())
        .collect::<Vec<_>>()
        .join(",")
}

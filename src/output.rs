//! Writing files whole, and never over an input.
//!
//! Every command that writes a file (`convert`, `synth`, `simulate --out`, every `--plot`) goes
//! through this module, which sits below `data` and `report` so that both can use it:
//! - [`write_atomic`] writes through a temporary sibling (created exclusively, random name) and
//!   a rename, so a failure never leaves half a file; the temporary is registered so that
//!   [`remove_temporaries_on_signal`] can delete it when the process is interrupted (SIGINT,
//!   SIGTERM, SIGHUP). `-` is the standard output.
//! - [`TempDir`] is a temporary directory removed on drop and on those signals.
//! - [`refuse_input`] is the one check that an output names none of the command's inputs: the
//!   same file through a symbolic link, `..`, a hard link or another letter case on a
//!   case-insensitive file system counts as the same file.
//! - [`refuse_same_output`] is the one check that no two outputs of a command name one file,
//!   by the same rule.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files and directories this process created and is using now, removed by the
/// signal handler.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// An output that would replace one of the command's inputs.
#[derive(Debug, thiserror::Error)]
#[error("the output {} is the input {}: refusing to overwrite an input", output.display(), input.display())]
pub struct OutputIsInput {
    /// The output path as given.
    pub output: PathBuf,
    /// The input path as given, which names the same file.
    pub input: PathBuf,
}

/// Refuse an output path that names the same file as any of `inputs`. Called by every command
/// before it reads or computes anything, for every path it will write.
pub fn refuse_input<P: AsRef<Path>>(output: &Path, inputs: &[P]) -> Result<(), OutputIsInput> {
    for input in inputs {
        if same_file(output, input.as_ref()) {
            return Err(OutputIsInput {
                output: output.to_owned(),
                input: input.as_ref().to_owned(),
            });
        }
    }
    Ok(())
}

/// Two outputs of one command that name the same file.
#[derive(Debug, thiserror::Error)]
#[error("{first} {} and {second} {} name the same file: give each output its own file", first_path.display(), second_path.display())]
pub struct SameOutput {
    /// The first output's flag (`--plot`).
    pub first: String,
    /// The first output's path as given.
    pub first_path: PathBuf,
    /// The second output's flag.
    pub second: String,
    /// The second output's path as given.
    pub second_path: PathBuf,
}

/// Refuse two outputs of one command that name the same file (by [`refuse_input`]'s rule:
/// links, `..`, letter case), each given as its flag and path: one would silently replace the
/// other. Called by a command before it reads or computes anything, with every output it
/// will write.
pub fn refuse_same_output(outputs: &[(&str, &Path)]) -> Result<(), SameOutput> {
    for (i, (first, a)) in outputs.iter().enumerate() {
        if let Some((second, b)) = outputs[i + 1..].iter().find(|(_, b)| same_file(a, b)) {
            return Err(SameOutput {
                first: (*first).to_owned(),
                first_path: a.to_path_buf(),
                second: (*second).to_owned(),
                second_path: b.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Whether two paths name one file. When both exist, their device and inode decide (links of
/// either kind, `..`, letter case); otherwise the canonical paths do (an output that does not
/// exist yet cannot be an existing input, except through a dangling link into it).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    canonical(a) == canonical(b)
}

/// Ask for a handler that removes the temporary files and directories being written when the
/// process receives SIGINT, SIGTERM or SIGHUP, then exits with code 130. Without it an
/// interrupted `synth` of a large recording would leave its hidden temporary file behind, and
/// `bench --read` its directory of recordings. The handler (a thread of its own) is installed
/// once, just before the first temporary is created: a run that writes none, such as a fit
/// printing its report, starts no thread for it. A library user's process that never asks
/// keeps its own signal handling.
pub fn remove_temporaries_on_signal() {
    HANDLER_WANTED.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// Whether [`remove_temporaries_on_signal`] was asked for.
static HANDLER_WANTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Install the signal handler, once, if it was asked for: called before a temporary is created.
fn install_handler_if_wanted() {
    if !HANDLER_WANTED.load(std::sync::atomic::Ordering::Relaxed) {
        return;
    }
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // An error here means another handler is installed (a library user's): keep theirs.
        let _ = ctrlc::set_handler(|| {
            let list = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
            for path in list.iter() {
                // Only what this process created is listed: a file, or a directory whole.
                match std::fs::symlink_metadata(path) {
                    Ok(m) if m.is_dir() => {
                        let _ = std::fs::remove_dir_all(path);
                    }
                    _ => {
                        let _ = std::fs::remove_file(path);
                    }
                }
            }
            std::process::exit(130);
        });
    });
}

/// Whether an output path means the standard output: `-`.
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Whether an output path writes to the standard output: `-`, or the file it is open on
/// (`/dev/stdout`, `/proc/self/fd/1`, the file stdout was redirected to). A command writing
/// there says what it wrote on stderr instead, so the output stays whole.
pub fn names_stdout(path: &Path) -> bool {
    if is_stdout(path) {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(a), Ok(b)) = (std::fs::metadata(path), std::fs::metadata("/dev/stdout")) {
            return a.dev() == b.dev() && a.ino() == b.ino();
        }
    }
    false
}

/// Write a file through a temporary sibling and a rename, so a failure never leaves half a
/// file behind. The temporary is created exclusively (it never opens a file that exists) under
/// a random name (`.NAME.XXXXXX.tmp` beside the output), and only that file, which this
/// process created, is removed when writing fails or a signal comes. A symbolic link is
/// followed (the file it points to is replaced, the link stays); `-` is the standard output,
/// and a special file (a named pipe, a device such as `/dev/stdout` or `/dev/full`) is written
/// directly, once the whole content is ready, never replaced by a plain file.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    if is_stdout(path) {
        let mut buf = Vec::new();
        fill(&mut buf)?;
        let mut out = std::io::stdout().lock();
        out.write_all(&buf)?;
        return out.flush();
    }
    // Through the path itself first: `/dev/stdout` is a link to `/proc/self/fd/1`, whose
    // target (`pipe:[...]`) only the kernel can follow.
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.is_dir() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the output is a directory",
            ));
        }
        if !meta.is_file() {
            let mut buf = Vec::new();
            fill(&mut buf)?;
            let mut f = open_special(path, &meta)?;
            f.write_all(&buf)?;
            return f.flush();
        }
    }
    let target = output_target(path)?;
    let name = target.file_name().ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "output path has no file name",
        )
    })?;
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    prefix.push(".");
    // Created with O_EXCL under a fresh random name (retried if taken), then registered for
    // the signal handler: a name that existed is never ours to remove.
    install_handler_if_wanted();
    let tmp = tempfile::Builder::new()
        .prefix(&prefix)
        .suffix(".tmp")
        .make_in(&dir, |p| {
            // Created and listed under the list's lock: the signal handler takes the lock
            // first, so a signal between the creation and the listing (a killed `synth` left
            // its temporary once in seven loaded test runs) waits for the listing and removes it.
            let mut list = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
            let f = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(p)?;
            list.push(p.to_owned());
            Ok(f)
        })?;
    let tmp_path = tmp.path().to_owned();
    let result = (|| {
        let mut w = std::io::BufWriter::new(tmp.as_file());
        fill(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        // Checked again just before the rename: never rename onto something that became a
        // special file or a link in the meantime.
        match std::fs::symlink_metadata(&target) {
            Ok(m) if !m.is_file() => Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the output changed into a link or special file while it was written",
            )),
            _ => Ok(()),
        }
    })();
    // On failure the temporary is dropped, which removes it (it is ours).
    let result = result.and_then(|()| tmp.persist(&target).map(drop).map_err(|e| e.error));
    register(&tmp_path, false);
    result
}

/// Open a special file for writing. A named pipe is opened without waiting for a reader
/// (a pipe nobody reads held the command in `open` for ever) and then written to as usual.
fn open_special(path: &Path, meta: &std::fs::Metadata) -> std::io::Result<std::fs::File> {
    use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
    use std::os::unix::io::AsRawFd;
    if !meta.file_type().is_fifo() {
        return std::fs::OpenOptions::new().write(true).open(path);
    }
    let f = std::fs::OpenOptions::new()
        .write(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| {
            if e.raw_os_error() == Some(libc::ENXIO) {
                // Not BrokenPipe: that is a reader gone, which ends a command quietly.
                std::io::Error::other("the output is a named pipe that nobody reads")
            } else {
                e
            }
        })?;
    // Blocking again for the writes, as to any pipe.
    // SAFETY: fcntl on a descriptor this function owns, with flags it read from it.
    let fd = f.as_raw_fd();
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 || unsafe { libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(f)
}

/// A temporary directory (random name, created exclusively under the system's temporary
/// directory) that is removed with everything in it when dropped, and by the signal handler
/// ([`remove_temporaries_on_signal`]) when the process is interrupted.
pub struct TempDir {
    dir: Option<tempfile::TempDir>,
    path: PathBuf,
}

impl TempDir {
    /// A new directory named `PREFIX` and random characters.
    pub fn new(prefix: &str) -> std::io::Result<TempDir> {
        install_handler_if_wanted();
        // Created and listed under the list's lock, as a file in [`write_atomic`].
        let mut list = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
        let dir = tempfile::Builder::new().prefix(prefix).tempdir()?;
        let path = dir.path().to_owned();
        list.push(path.clone());
        drop(list);
        Ok(TempDir {
            dir: Some(dir),
            path,
        })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        drop(self.dir.take());
        register(&self.path, false);
    }
}

/// Add or remove a temporary file or directory in the list the signal handler cleans up.
fn register(tmp: &Path, add: bool) {
    let mut list = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
    if add {
        list.push(tmp.to_owned());
    } else if let Some(k) = list.iter().position(|p| p == tmp) {
        list.swap_remove(k);
    }
}

/// The file an output path really names: a symbolic link resolved to the file it points to
/// (which need not exist yet), anything else as given.
pub fn output_target(path: &Path) -> std::io::Result<PathBuf> {
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
fn canonical(path: &Path) -> PathBuf {
    let target = output_target(path).unwrap_or_else(|_| path.to_path_buf());
    if let Ok(c) = std::fs::canonicalize(&target) {
        return c;
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    match (std::fs::canonicalize(&dir), target.file_name()) {
        (Ok(d), Some(n)) => d.join(n),
        _ => target,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("appell-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("scene.toml"), "x").unwrap();
        dir
    }

    #[test]
    fn every_spelling_of_an_input_is_refused() {
        let dir = scratch("spell");
        let input = dir.join("scene.toml");
        std::os::unix::fs::symlink(&input, dir.join("link.toml")).unwrap();
        std::fs::hard_link(&input, dir.join("hard.toml")).unwrap();
        for out in [
            dir.join("scene.toml"),
            dir.join("sub/../scene.toml"),
            dir.join("./scene.toml"),
            dir.join("link.toml"),
            dir.join("hard.toml"),
        ] {
            assert!(refuse_input(&out, &[&input]).is_err(), "{}", out.display());
        }
        // A new file, or another existing one, is fine.
        assert!(refuse_input(&dir.join("new.csv"), &[&input]).is_ok());
        std::fs::write(dir.join("other.csv"), "y").unwrap();
        assert!(refuse_input(&dir.join("other.csv"), &[&input]).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_written_file_leaves_no_temporary_registered() {
        let dir = scratch("tmp");
        let out = dir.join("out.csv");
        write_atomic(&out, |w| w.write_all(b"a")).unwrap();
        let failed = write_atomic(&dir.join("bad.csv"), |_| Err(std::io::Error::other("no")));
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&out).unwrap(), b"a");
        assert!(!dir.join("bad.csv").exists());
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(left.is_empty());
        let list = TEMPORARIES.lock().unwrap();
        assert!(!list.iter().any(|p| p.starts_with(&dir)));
        drop(list);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

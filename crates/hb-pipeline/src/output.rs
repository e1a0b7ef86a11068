//! Writing result files atomically: all or nothing, even when the user presses Ctrl-C.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Errors of writing a result file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The path names a folder, not a file.
    #[error("{} is a folder; give a file name", .0.display())]
    IsAFolder(PathBuf),
    /// The folder the file would be written into does not exist.
    #[error("the folder {} does not exist", .0.display())]
    NoSuchFolder(PathBuf),
    /// No temporary file could be created in the folder.
    #[error("cannot create a file in {}", folder.display())]
    Create {
        /// The folder.
        folder: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Writing the file, or renaming it into place, failed.
    #[error("cannot write {}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
}

/// Temporary files (and folders) being written; removed by [`remove_partial_files`] on an
/// interrupt.
static PARTIAL: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file (and folder, with what it holds) still being written. Called
/// from the binary's Ctrl-C handler before it exits, so that an interrupt leaves neither a
/// partial file nor a stray temporary.
pub fn remove_partial_files() {
    if let Ok(mut files) = PARTIAL.lock() {
        for f in files.drain(..) {
            if f.is_dir() {
                let _ = std::fs::remove_dir_all(f);
            } else {
                let _ = std::fs::remove_file(f);
            }
        }
    }
}

/// Registers a temporary file or folder for [`remove_partial_files`] (until
/// [`untrack`]ed).
pub fn track(path: &Path) {
    if let Ok(mut files) = PARTIAL.lock() {
        files.push(path.to_owned());
    }
}

/// Forgets a temporary file or folder that was renamed into place or removed.
pub fn untrack(path: &Path) {
    if let Ok(mut files) = PARTIAL.lock() {
        files.retain(|f| f != path);
    }
}

/// Checks that the folder `path` would be written into exists, before any work is done.
pub fn check_output_path(path: &Path) -> Result<(), OutputError> {
    if path.is_dir() {
        return Err(OutputError::IsAFolder(path.to_owned()));
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(OutputError::NoSuchFolder(parent.to_owned()));
    }
    Ok(())
}

/// Where a result named `path` is written, and how: the file a symbolic link names (followed
/// through a chain of links; the links stay), and whether it is written in place (`true`: an
/// existing file that is neither a regular file nor a folder, such as `/dev/null` or a named
/// pipe, which a temporary file renamed over it would replace) rather than through a temporary
/// file renamed into place.
pub fn output_target(path: &Path) -> (PathBuf, bool) {
    let mut target = path.to_owned();
    // At most as many links as the system follows itself.
    for _ in 0..40 {
        match std::fs::symlink_metadata(&target) {
            Ok(m) if m.file_type().is_symlink() => match std::fs::read_link(&target) {
                Ok(link) if link.is_absolute() => target = link,
                Ok(link) => {
                    let folder = target.parent().map_or_else(PathBuf::new, Path::to_owned);
                    target = folder.join(link);
                }
                Err(_) => break,
            },
            _ => break,
        }
    }
    let in_place = std::fs::metadata(&target).is_ok_and(|m| !m.is_file() && !m.is_dir());
    (target, in_place)
}

/// Writes a file through a temporary file in the same folder, renamed into place only when
/// complete: a failure or an interruption leaves no partial file under `path`. A symbolic link
/// is written through (the file it names is replaced, the link kept), and a device or named
/// pipe (`/dev/null`) is written in place ([`output_target`]).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), OutputError> {
    let (target, in_place) = output_target(path);
    let path = target.as_path();
    check_output_path(path)?;
    if in_place {
        return std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .and_then(|file| {
                let mut buf = std::io::BufWriter::new(file);
                write(&mut buf)?;
                buf.flush()
            })
            .map_err(|source| OutputError::Write {
                path: path.to_owned(),
                source,
            });
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".hbid-partial-");
    // An ordinary file's permissions (0o666 less the umask), not the temporary file's owner-only.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder
        .tempfile_in(parent)
        .map_err(|source| OutputError::Create {
            folder: parent.to_owned(),
            source,
        })?;
    let tmp_path = tmp.path().to_owned();
    track(&tmp_path);
    let result = (|| -> std::io::Result<()> {
        {
            let mut buf = std::io::BufWriter::new(tmp.as_file_mut());
            write(&mut buf)?;
            buf.flush()?;
        }
        tmp.persist(path).map_err(|e| e.error)?;
        Ok(())
    })();
    untrack(&tmp_path);
    result.map_err(|source| OutputError::Write {
        path: path.to_owned(),
        source,
    })
}

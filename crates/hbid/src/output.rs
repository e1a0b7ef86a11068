//! Writing result files atomically: all or nothing, even when the user presses Ctrl-C.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files being written; removed by [`remove_partial_files`] on an interrupt.
static PARTIAL: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file still being written. Called from the binary's Ctrl-C handler
/// before it exits, so that an interrupt leaves neither a partial file nor a stray temporary.
pub fn remove_partial_files() {
    if let Ok(mut files) = PARTIAL.lock() {
        for f in files.drain(..) {
            let _ = std::fs::remove_file(f);
        }
    }
}

fn track(path: &Path, add: bool) {
    if let Ok(mut files) = PARTIAL.lock() {
        if add {
            files.push(path.to_owned());
        } else {
            files.retain(|f| f != path);
        }
    }
}

use anyhow::{Context, bail};

/// Checks that the folder `path` would be written into exists, before any work is done.
pub fn check_output_path(path: &Path) -> anyhow::Result<()> {
    if path.is_dir() {
        bail!("--out {} is a folder; give a file name", path.display());
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        bail!("the folder {} of --out does not exist", parent.display());
    }
    Ok(())
}

/// Writes a file through a temporary file in the same folder, renamed into place only when
/// complete: a failure or an interruption leaves no partial file under `path`.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> anyhow::Result<()> {
    check_output_path(path)?;
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
        .with_context(|| format!("cannot create a file in {}", parent.display()))?;
    let tmp_path = tmp.path().to_owned();
    track(&tmp_path, true);
    let result = (|| -> anyhow::Result<()> {
        {
            let mut buf = std::io::BufWriter::new(tmp.as_file_mut());
            write(&mut buf).with_context(|| format!("cannot write {}", path.display()))?;
            buf.flush()
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        tmp.persist(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(())
    })();
    track(&tmp_path, false);
    result
}

//! What every test module of the command runs it with: the `hbid` of this build, and a scratch
//! folder of its own per module and test.
use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs this build's `hbid` with `args`.
pub fn hbid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hbid"))
        .args(args)
        .output()
        .expect("hbid runs")
}

/// [`hbid`] with `--quiet` first (no progress bars on stderr).
pub fn hbid_quiet(args: &[&str]) -> Output {
    let mut quiet = vec!["--quiet"];
    quiet.extend_from_slice(args);
    hbid(&quiet)
}

/// The folder `hbid-{module}-{process}-{name}` under the temporary folder, made if missing.
pub fn scratch(module: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hbid-{module}-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

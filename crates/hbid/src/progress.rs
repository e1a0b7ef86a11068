//! Progress bars on stderr, hidden off a terminal and with `--quiet`.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar for one stage.
pub struct Progress(ProgressBar);

impl Progress {
    /// A bar of `len` steps named `stage`.
    pub fn new(stage: &str, len: u64, quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(
            Some(len),
            if quiet {
                ProgressDrawTarget::hidden()
            } else {
                ProgressDrawTarget::stderr()
            },
        );
        bar.set_style(
            ProgressStyle::with_template("{prefix:>10} [{bar:30}] {pos}/{len} ({elapsed})")
                .expect("a valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(stage.to_owned());
        Self(bar)
    }

    /// A spinner for a stage of unknown length.
    pub fn spinner(stage: &str, quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(
            None,
            if quiet {
                ProgressDrawTarget::hidden()
            } else {
                ProgressDrawTarget::stderr()
            },
        );
        bar.set_style(
            ProgressStyle::with_template("{spinner} {prefix} ({elapsed})").expect("a valid template"),
        );
        bar.set_prefix(stage.to_owned());
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        Self(bar)
    }

    /// Sets the position.
    pub fn set(&self, pos: u64) {
        self.0.set_position(pos);
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl Drop for Progress {
    /// A bar never outlives its stage, even when the stage fails.
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

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
            ProgressStyle::with_template("{spinner} {prefix} {msg} ({elapsed})").expect("a valid template"),
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

/// The stages of a command, shown on a spinner as they go and, with `--timings`, listed with
/// their wall times on stderr at the end.
pub struct Stages {
    bar: Progress,
    current: Option<(&'static str, std::time::Instant)>,
    done: Vec<(&'static str, std::time::Duration)>,
    timings: bool,
}

impl Stages {
    /// Starts the spinner of `command`.
    pub fn new(command: &str, quiet: bool, timings: bool) -> Self {
        Self {
            bar: Progress::spinner(command, quiet),
            current: None,
            done: Vec::new(),
            timings,
        }
    }

    /// Ends the current stage (if any) and starts `name`.
    pub fn start(&mut self, name: &'static str) {
        self.end();
        self.bar.0.set_message(name);
        self.current = Some((name, std::time::Instant::now()));
    }

    fn end(&mut self) {
        if let Some((name, t)) = self.current.take() {
            self.done.push((name, t.elapsed()));
        }
    }

    /// Ends the last stage, clears the spinner and, with `--timings`, prints the stages' times.
    pub fn finish(mut self) {
        self.end();
        self.bar.finish();
        if self.timings {
            let total: std::time::Duration = self.done.iter().map(|(_, d)| *d).sum();
            for (name, d) in &self.done {
                eprintln!("{name:>12} {:>9.3} s", d.as_secs_f64());
            }
            eprintln!("{:>12} {:>9.3} s", "total", total.as_secs_f64());
        }
    }
}

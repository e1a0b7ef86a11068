//! Progress bars on stderr, hidden off a terminal and with `--quiet`.

use hb_pipeline::{Notice, Observer, Spelling, Stage};
use hb_record::prepare::Note;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar for one stage.
pub struct Progress(ProgressBar);

impl Progress {
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
    /// The last per mille of the current stage shown.
    shown: usize,
    done: Vec<(&'static str, std::time::Duration)>,
    timings: bool,
}

impl Stages {
    /// Starts the spinner of `command`.
    pub fn new(command: &str, quiet: bool, timings: bool) -> Self {
        Self {
            bar: Progress::spinner(command, quiet),
            current: None,
            shown: usize::MAX,
            done: Vec::new(),
            timings,
        }
    }

    /// Ends the current stage (if any) and starts `name`.
    pub fn start(&mut self, name: &'static str) {
        self.end();
        self.bar.0.set_message(name);
        self.current = Some((name, std::time::Instant::now()));
        self.shown = usize::MAX;
    }

    /// Shows progress within the current stage (redrawn at most once per mille).
    pub fn progress(&mut self, done: usize, total: usize) {
        let mille = done.saturating_mul(1000) / total.max(1);
        if let Some((name, _)) = self.current
            && mille != self.shown
        {
            self.shown = mille;
            self.bar.0.set_message(format!("{name} {done}/{total}"));
        }
    }

    /// Prints a line on stderr without garbling the spinner.
    pub fn print(&self, line: &str) {
        self.bar.0.suspend(|| eprintln!("{line}"));
    }

    fn end(&mut self) {
        if let Some((name, t)) = self.current.take() {
            self.done.push((name, t.elapsed()));
        }
    }

    /// Ends the last stage, clears the spinner and, with `--timings`, prints the stages' times.
    pub fn finish(&mut self) {
        self.end();
        self.bar.finish();
        if self.timings {
            let total: std::time::Duration = self.done.iter().map(|(_, d)| *d).sum();
            for (name, d) in &std::mem::take(&mut self.done) {
                eprintln!("{name:>12} {:>9.3} s", d.as_secs_f64());
            }
            eprintln!("{:>12} {:>9.3} s", "total", total.as_secs_f64());
        }
    }
}

/// The command line's observer of a run: the stages on a spinner (and their times with
/// `--timings`), notices printed on stderr as `note:` or `warning:` with the options spelled as
/// the command line spells them.
pub struct Console {
    stages: Stages,
    /// Time stamps of the record being read replaced by their grid time so far, and those of
    /// them not printed.
    repairs: (usize, usize),
    /// The record they are of, when it is one of several.
    repaired: Option<String>,
}

/// The time-stamp repairs the console prints one by one; the rest are counted in one note (a
/// logger that stamps one row in 500 late has hundreds in a long record).
const REPAIRS_SHOWN: usize = 5;

impl Console {
    /// The observer of `command`.
    pub fn new(command: &str, quiet: bool, timings: bool) -> Self {
        Self {
            stages: Stages::new(command, quiet, timings),
            repairs: (0, 0),
            repaired: None,
        }
    }

    /// Ends the run's display (and prints the times with `--timings`).
    pub fn finish(mut self) {
        self.held_repairs();
        self.stages.finish();
    }

    /// The note of the repairs not printed, if any.
    fn held_repairs(&mut self) {
        let held = std::mem::take(&mut self.repairs.1);
        if held > 0 {
            let of = self
                .repaired
                .as_ref()
                .map(|r| format!("{r}: "))
                .unwrap_or_default();
            self.stages.print(&format!(
                "note: {of}{held} more time stamp(s) replaced by their grid times ({} in all; Python's `read` lists every one in `time_repairs`)",
                self.repairs.0
            ));
        }
    }
}

impl Drop for Console {
    /// The count of the repairs not printed is printed also when the command fails (before its
    /// error).
    fn drop(&mut self) {
        self.held_repairs();
    }
}

impl Observer for Console {
    fn stage(&mut self, stage: Stage) {
        self.held_repairs();
        // Each record read (identify reads several) has its repairs counted on their own.
        if stage == Stage::Read {
            self.repairs = (0, 0);
        }
        self.stages.start(stage.name());
    }

    fn progress(&mut self, done: usize, total: usize) {
        self.stages.progress(done, total);
    }

    fn notice(&mut self, notice: &Notice) {
        if let Notice::Record(Note::TimeRepaired(_)) = notice.inner() {
            self.repaired = match notice {
                Notice::InRecord { record, .. } => Some(record.clone()),
                _ => None,
            };
            self.repairs.0 += 1;
            if self.repairs.0 > REPAIRS_SHOWN {
                self.repairs.1 += 1;
                return;
            }
        } else {
            self.held_repairs();
        }
        let kind = if notice.is_warning() { "warning" } else { "note" };
        self.stages.print(&format!(
            "{kind}: {}",
            Spelling::CommandLine.render(&notice.to_string())
        ));
    }
}

//! The wall time of each stage of `cargo xtask reproduce`, with a spinner while it runs: what the
//! reproduction and its sections (`double_pendulum`) time and report.

use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Wall time of each stage, for the report.
#[derive(Default)]
pub(crate) struct Timings {
    done: Vec<(&'static str, Duration)>,
    current: Option<(&'static str, Instant, ProgressBar)>,
}

impl Timings {
    /// Ends the current stage, if any, and starts `name` with a spinner on stderr (nothing if
    /// `name` is already running).
    pub(crate) fn start(&mut self, name: &'static str) {
        if self
            .current
            .as_ref()
            .is_some_and(|(current, ..)| *current == name)
        {
            return;
        }
        self.end();
        let bar = ProgressBar::new_spinner();
        bar.set_style(ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("valid template"));
        bar.set_message(name);
        bar.enable_steady_tick(Duration::from_millis(120));
        self.current = Some((name, Instant::now(), bar));
    }

    /// Ends the current stage and records its wall time.
    pub(crate) fn end(&mut self) {
        if let Some((name, start, bar)) = self.current.take() {
            let took = start.elapsed();
            bar.finish_and_clear();
            eprintln!("{name:<28} {:>8.3} s", took.as_secs_f64());
            self.done.push((name, took));
        }
    }

    /// Ends the current stage with the outcome of its work: an error names the stage.
    pub(crate) fn finish<T, E>(&mut self, outcome: Result<T, E>) -> anyhow::Result<T>
    where
        anyhow::Error: From<E>,
    {
        match outcome {
            Ok(value) => {
                self.end();
                Ok(value)
            }
            Err(e) => {
                let name = self.current.take().map_or("", |(name, ..)| name);
                Err(anyhow::Error::from(e).context(format!("stage '{name}'")))
            }
        }
    }

    /// Runs `work` as a stage and records its wall time.
    pub(crate) fn stage<T>(
        &mut self,
        name: &'static str,
        work: impl FnOnce() -> anyhow::Result<T>,
    ) -> anyhow::Result<T> {
        self.start(name);
        let outcome = work();
        self.finish(outcome)
    }

    /// The stages ended so far, in order, with their wall times.
    pub(crate) fn done(&self) -> &[(&'static str, Duration)] {
        &self.done
    }
}

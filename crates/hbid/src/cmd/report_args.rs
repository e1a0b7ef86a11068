//! The options of `hbid report` and what its two reports (of one coordinate, `super::report`; of
//! a system or a saved model, `super::report_system`) share: the console that keeps the notices
//! for the report's text.

use std::path::PathBuf;

use clap::Args;
use hb_pipeline::pipeline::Method;
use hb_pipeline::{Notice, Observer};

use super::identify::IdentifyArgs;
use crate::progress::Console;

/// Options of `hbid report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(flatten)]
    pub identify: IdentifyArgs,
    /// Folder of the report (created if missing; README.md, figures and the models go there).
    #[arg(long)]
    pub out: PathBuf,
    /// Drive periods simulated for each model's Poincaré section and Lyapunov exponent (a record
    /// of one coordinate; the report of a system or a saved model runs each model 300 periods
    /// after 100 of transient).
    #[arg(long, default_value_t = 2000)]
    pub validation_periods: usize,
    /// A saved model or system (`hbid identify --save-model`, JSON or binary) to report against
    /// the record instead of identifying one: its equations' coefficients and fit, its free run
    /// against the record coordinate by coordinate (`hbid compare`'s), its phase portraits and
    /// Poincaré sections beside the record's, and its valid prediction time. A system's columns
    /// are its own names unless --coords names them.
    #[arg(long, value_name = "PATH", conflicts_with_all = ["terms", "method", "basis", "select", "refine", "tie"])]
    pub model: Option<PathBuf>,
    /// Whether --method was given: the report then identifies by that method alone (by both
    /// otherwise).
    #[arg(skip)]
    pub method_given: bool,
}

impl ReportArgs {
    /// The methods the report identifies by, in its order: the one given, or both.
    pub fn methods(&self) -> Vec<Method> {
        if self.method_given {
            vec![self.identify.method]
        } else {
            vec![Method::Upo, Method::Windowed]
        }
    }
}

/// The console, and the notices kept for the report's text.
pub(super) struct Kept {
    pub(super) console: Console,
    pub(super) notices: Vec<Notice>,
}

impl Observer for Kept {
    fn stage(&mut self, stage: hb_pipeline::Stage) {
        self.console.stage(stage);
    }

    fn progress(&mut self, done: usize, total: usize) {
        self.console.progress(done, total);
    }

    fn notice(&mut self, notice: &Notice) {
        self.console.notice(notice);
        self.notices.push(notice.clone());
    }
}

//! What a run tells its front end as it goes: the stage that starts, progress within it, and
//! notices about the record and the fit. One trait, [`Observer`], for all of it; the command line
//! draws progress bars and prints notes, Python collects the notes, a test ignores them (`()`).

use std::fmt;

use circle_signal::Measured;
use hb_drive::DriveEstimate;
use hb_record::prepare::Note;

use crate::pipeline::DriftFit;

/// A stage of a run, reported as it starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Stage {
    /// Reading the record's file.
    Read,
    /// Estimating the drive's period.
    Drive,
    /// The delay (average mutual information).
    Delay,
    /// False nearest neighbours.
    Embed,
    /// Close returns or windows.
    Segments,
    /// The drift of an integrated velocity or acceleration record.
    Drift,
    /// Assembling the stacked system.
    Assemble,
    /// Selecting terms.
    Select,
    /// Least squares.
    Solve,
    /// The held-out share of the fit.
    HeldOut,
    /// The bootstrap.
    Bootstrap,
    /// Simulating.
    Simulate,
    /// Comparing a simulation with a record.
    Compare,
    /// Refining a model by its free run's error.
    Refine,
}

impl Stage {
    /// A short name for progress displays and timings.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Read => "read",
            Stage::Drive => "drive",
            Stage::Delay => "delay",
            Stage::Embed => "embed",
            Stage::Segments => "segments",
            Stage::Drift => "drift",
            Stage::Assemble => "assemble",
            Stage::Select => "select",
            Stage::Solve => "solve",
            Stage::HeldOut => "held-out",
            Stage::Bootstrap => "bootstrap",
            Stage::Simulate => "simulate",
            Stage::Compare => "compare",
            Stage::Refine => "refine",
        }
    }
}

/// Something done to the record, or found in it or in the fit, that a user should hear of.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Notice {
    /// A note of the record's preparation (grid, gaps, wrapping, spikes, integration).
    Record(Note),
    /// A note of the preparation of one column of a record of several coordinates (its
    /// spikes), named by the column's name.
    Column {
        /// The coordinate's name.
        column: String,
        /// The note.
        note: Note,
    },
    /// The drive's period estimated from the record.
    DriveEstimated(DriveEstimate),
    /// No drive: the windows are counted in periods of the free oscillation.
    FreePeriod {
        /// Its measured mean period, in samples.
        samples: f64,
        /// The whole number of samples used per period.
        used: usize,
    },
    /// No periodic drive: the windows' unit as given (a window is `window_periods` of them).
    WindowUnit {
        /// Samples per unit.
        samples: usize,
        /// Its length in the record's time unit.
        length: f64,
        /// Whether the record has measured drives (then no periodic one is missed).
        measured_drive: bool,
    },
    /// The record resampled onto a whole number of samples per period.
    Resampled {
        /// Samples per period as read.
        from: f64,
        /// Samples per period after.
        to: usize,
    },
    /// The drift of an integrated record, found by the model.
    Drift {
        /// What was measured.
        measured: Measured,
        /// What the fit found.
        fit: DriftFit,
        /// Samples per period (to give the slope per period).
        samples_per_period: usize,
    },
    /// The bootstrap gave no intervals; the coefficients and standard errors stand.
    NoIntervals(String),
    /// The fit's warning (too little explained, or not a description of the record).
    Warning(String),
    /// A comparison runs through the record's first rows, which a logger stamped before it
    /// settled to its rate, at their own stamps (an identification leaves them out).
    UnevenStart(hb_record::input::Unsettled),
    /// A velocity or acceleration record integrated for a saved model's free run, with the
    /// constants its equation holds best with ([`crate::integrated`]).
    Integrated {
        /// What the record measured.
        measured: Measured,
        /// The constants found, piece by piece, and the pieces left out.
        integration: crate::integrated::Integration,
    },
    /// A notice of one of several records read together (`identify` on several files), named by
    /// its file.
    InRecord {
        /// The record's name (its file's path).
        record: String,
        /// The notice.
        notice: Box<Notice>,
    },
}

impl Notice {
    /// Whether this is a warning (something left wrong, or a result not to trust) rather than a
    /// plain note.
    pub fn is_warning(&self) -> bool {
        match self {
            Notice::Record(note) | Notice::Column { note, .. } => note.is_warning(),
            Notice::Warning(_) => true,
            Notice::InRecord { notice, .. } => notice.is_warning(),
            _ => false,
        }
    }

    /// The notice itself, apart from the record it is of ([`Notice::InRecord`]).
    pub fn inner(&self) -> &Notice {
        match self {
            Notice::InRecord { notice, .. } => notice.inner(),
            other => other,
        }
    }
}

/// The text of the notice, without `note:` or `warning:`. Options are named as
/// [`crate::options::Spelling::render`] reads them.
impl fmt::Display for Notice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Notice::Column { column, note } => {
                // The column's name in place of the note's own count of coordinates.
                let note = note.of_coordinate(0);
                write!(f, "{column}: ")?;
                fmt::Display::fmt(&Notice::Record(note), f)
            }
            Notice::Record(note) => {
                write!(f, "{note}")?;
                match note {
                    // Runs of an angle's samples can be a motion too fast for the sampling
                    // (a whirling double pendulum's), which a repair would cut.
                    Note::Spikes {
                        repaired: false,
                        found,
                        domain: circle_signal::Domain::Circle,
                        ..
                    } if found.windows(2).any(|w| w[1].index == w[0].index + 1) => {
                        f.write_str(
                            "; if they are errors and not the motion, run with «repair=True» to replace them",
                        )?;
                    }
                    Note::Spikes { repaired: false, .. } => {
                        f.write_str("; run with «repair=True» to replace them")?;
                    }
                    Note::Spikes {
                        repaired: true,
                        policy: hb_record::prepare::SpikePolicy::RepairFew,
                        ..
                    } => f.write_str("; run with «no_repair=True» to keep them")?,
                    _ => {}
                }
                Ok(())
            }
            Notice::DriveEstimated(e) => write!(
                f,
                "drive period estimated from the record: {:.9} ± {:.2e} (frequency {:.9} ± {:.2e})",
                e.period,
                e.period_uncertainty,
                e.frequency(),
                e.frequency_uncertainty()
            ),
            Notice::FreePeriod { samples, used } => write!(
                f,
                "no drive: windows in periods of the free oscillation, {samples:.2} samples ({used} used)"
            ),
            Notice::WindowUnit {
                samples,
                length,
                measured_drive,
            } => {
                write!(
                    f,
                    "no periodic drive: the windows' unit is {samples} samples ({length} in the record's time unit)"
                )?;
                if !measured_drive {
                    f.write_str(
                        "; with windows in the record's time a periodic drive is not looked for, and no term in \
                         it is fitted: for one, give «drive_period» or «drive_frequency» instead (windows then in \
                         its periods, «window_periods»)",
                    )?;
                }
                Ok(())
            }
            Notice::Resampled { from, to } => write!(
                f,
                "{from:.6} samples per period: resampled (band-limited) to {to}"
            ),
            Notice::Drift {
                fit,
                samples_per_period,
                ..
            } => {
                let pieces: Vec<String> = fit
                    .pieces
                    .iter()
                    .map(|d| {
                        format!(
                            "slope {:.3e} per period, offset {:.3e}",
                            d.slope * *samples_per_period as f64,
                            d.offset
                        )
                    })
                    .collect();
                write!(
                    f,
                    "the drift of the integrated record that the model explains best ({}): unexplained {:.2e} before, \
                     {:.2e} after",
                    pieces.join("; "),
                    fit.unexplained_before,
                    fit.unexplained_after
                )
            }
            Notice::NoIntervals(why) => write!(f, "no bootstrap intervals: {why}"),
            Notice::UnevenStart(run) => write!(
                f,
                "the first {} rows ({} to {}, t = {} to {}) are {:.2} to {:.2} steps of {} apart, stamped before the \
                 logger settled to its rate: the free run starts at the first row and passes them at their own \
                 stamps (the measured drives interpolated over them), the rows after them on the grid; the ranges \
                 count them as the record's first rows («skip_unsettled» leaves them out, as an identification does)",
                run.samples.len(),
                run.first,
                run.last,
                run.from,
                run.to,
                run.shortest / run.step,
                run.longest / run.step,
                significant(run.step, 6)
            ),
            Notice::Warning(w) => f.write_str(w),
            Notice::InRecord { record, notice } => write!(f, "{record}: {notice}"),
            Notice::Integrated {
                measured,
                integration,
            } => {
                let pieces = &integration.pieces;
                let shown: Vec<String> = pieces
                    .iter()
                    .take(3)
                    .map(|p| match measured {
                        Measured::Acceleration => format!(
                            "samples {}..{}: velocity {:+.4e}, offset {:+.4e} (unexplained {:.2e})",
                            p.start, p.end, p.velocity, p.offset, p.unexplained
                        ),
                        _ => format!(
                            "samples {}..{}: offset {:+.4e} (unexplained {:.2e})",
                            p.start, p.end, p.offset, p.unexplained
                        ),
                    })
                    .collect();
                let more = if pieces.len() > 3 {
                    format!("; {} more piece(s)", pieces.len() - 3)
                } else {
                    String::new()
                };
                write!(
                    f,
                    "the {measured} record integrated to the displacement, each piece's constants those the model's \
                     equation holds best with: {}{more}",
                    shown.join("; ")
                )?;
                if let Some(&(start, end)) = integration.left_out.first() {
                    write!(
                        f,
                        "; {} piece(s) of fewer than {} samples left out as gaps (the first {start}..{end})",
                        integration.left_out.len(),
                        crate::integrated::MIN_SAMPLES
                    )?;
                }
                Ok(())
            }
        }
    }
}

/// `v` to `digits` significant digits, in the shortest text that reads back as that.
fn significant(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(digits - 1 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// Hears of a run as it goes. Every method has an empty default: implement what you show.
pub trait Observer {
    /// A stage starts.
    fn stage(&mut self, _stage: Stage) {}
    /// Progress within the current stage: `done` of `total` steps.
    fn progress(&mut self, _done: usize, _total: usize) {}
    /// Something done or found.
    fn notice(&mut self, _notice: &Notice) {}
}

/// Hears nothing.
impl Observer for () {}

/// Passes on what `inner` hears of one of several records, each notice named by the record
/// ([`Notice::InRecord`]).
pub(crate) struct OfRecord<'a> {
    /// The record's name.
    pub record: &'a str,
    /// The observer of the run.
    pub inner: &'a mut dyn Observer,
}

impl Observer for OfRecord<'_> {
    fn stage(&mut self, stage: Stage) {
        self.inner.stage(stage);
    }
    fn progress(&mut self, done: usize, total: usize) {
        self.inner.progress(done, total);
    }
    fn notice(&mut self, notice: &Notice) {
        self.inner.notice(&Notice::InRecord {
            record: self.record.to_owned(),
            notice: Box::new(notice.clone()),
        });
    }
}

/// Keeps every notice, in order (what the Python package hands back).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Notices(pub Vec<Notice>);

impl Observer for Notices {
    fn notice(&mut self, notice: &Notice) {
        self.0.push(notice.clone());
    }
}

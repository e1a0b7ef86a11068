//! Plain windows of a record: segments that need not be periodic, for the weak form.

use std::ops::Range;

use circle_signal::{Domain, OrbitSource, SampleClock, Segment};

use crate::error::UpoError;

/// Windows of `k` forcing periods laid over the whole record, periodic or not.
///
/// Window `i` starts at sample `i · step` and spans `L = k P` samples plus the closing sample
/// `start + L`, for every `i` with `start + L < N` (the closing sample is part of the window: the
/// weak form integrates over the closed interval `[0, k T]`). With `step = k P` the windows are
/// consecutive; a smaller step makes them overlap. The default step is one forcing period `P`, so
/// with the default `k = 3` every sample (but those near the ends) lies in three windows.
///
/// The windows are not orbits: their [`Segment::error`] is the distance, in the [`Domain`], between
/// the closing sample and the first one — how far the window is from closing — and only informs;
/// the weak form does not need it to be small.
///
/// Build with [`Windows::builder`] (or [`Windows::new`] for the defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Windows {
    clock: SampleClock,
    samples_per_period: usize,
    periods: usize,
    step: usize,
    domain: Domain,
}

/// Builder of [`Windows`]; [`build`](Self::build) validates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowsBuilder {
    clock: SampleClock,
    periods: usize,
    step: Option<usize>,
    domain: Domain,
}

impl Windows {
    /// Default window length `k`, in forcing periods. Longer windows reach lower frequencies
    /// (harmonic `j` of a window is `j / k` times the forcing frequency) and, on the measurements of
    /// `docs/accuracy.md`, three periods gave smaller errors than two with and without noise, while
    /// four gave no further gain with noise; see `docs/identification.md`.
    pub const DEFAULT_PERIODS: usize = 3;

    /// A builder with the required clock (whole `P` samples per forcing period) and the defaults: windows of
    /// [`DEFAULT_PERIODS`](Self::DEFAULT_PERIODS) forcing periods, a step of one forcing period
    /// (`P` samples), [`Domain::Circle`].
    pub fn builder(clock: &SampleClock) -> WindowsBuilder {
        WindowsBuilder {
            clock: *clock,
            periods: Self::DEFAULT_PERIODS,
            step: None,
            domain: Domain::default(),
        }
    }

    /// The windows with all defaults but the required clock.
    pub fn new(clock: &SampleClock) -> Result<Self, UpoError> {
        Self::builder(clock).build()
    }

    /// The clock the windows are cut on.
    pub fn clock(&self) -> &SampleClock {
        &self.clock
    }

    /// Samples per forcing period `P`.
    pub fn samples_per_period(&self) -> usize {
        self.samples_per_period
    }

    /// Window length `k` in forcing periods.
    pub fn periods(&self) -> usize {
        self.periods
    }

    /// Samples in a window, closing sample excluded: `k P`.
    pub fn len(&self) -> usize {
        self.periods * self.samples_per_period
    }

    /// Always false: a window has at least two samples (kept for the `len` convention).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Samples between the starts of consecutive windows.
    pub fn step(&self) -> usize {
        self.step
    }

    /// The domain of the signal, and so the metric of [`Segment::error`].
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// Number of windows in a record of `samples` samples.
    pub fn count(&self, samples: usize) -> usize {
        let l = self.len();
        if samples <= l {
            0
        } else {
            // Starts 0, s, 2s, .. with start + L <= samples − 1.
            (samples - 1 - l) / self.step + 1
        }
    }

    /// The windows of a record in pieces: `pieces` are the ranges of `signal` that hold samples
    /// (sorted, disjoint; what lies between them, such as the NaN of a gap, is never read). Each
    /// piece is cut on its own, from its first sample, so that no window spans the space between
    /// two; pieces shorter than a window are skipped. Window starts index `signal`.
    ///
    /// Errors when no piece holds a window (naming the longest), a sample of a piece is not
    /// finite, or the pieces are out of order or out of bounds.
    pub fn windows_pieces(&self, signal: &[f64], pieces: &[Range<usize>]) -> Result<Vec<Segment>, UpoError> {
        crate::check_pieces(signal, pieces)?;
        let l = self.len();
        let longest = pieces.iter().map(Range::len).max().unwrap_or(0);
        if longest <= l {
            return Err(UpoError::TooShort {
                len: longest,
                needed: l + 1,
                period: self.periods,
            });
        }
        let mut segments = Vec::new();
        for piece in pieces.iter().filter(|r| r.len() > l) {
            for s in self.windows(&signal[piece.clone()])? {
                segments.push(Segment::new(
                    piece.start + s.start(),
                    s.period(),
                    &self.clock,
                    s.error(),
                    signal.len(),
                )?);
            }
        }
        Ok(segments)
    }

    /// The windows of `signal`.
    ///
    /// Errors when the record is shorter than one window and its closing sample (`k P + 1`
    /// samples) or holds a non-finite sample.
    pub fn windows(&self, signal: &[f64]) -> Result<Vec<Segment>, UpoError> {
        let l = self.len();
        if signal.len() <= l {
            return Err(UpoError::TooShort {
                len: signal.len(),
                needed: l + 1,
                period: self.periods,
            });
        }
        if let Some((index, &value)) = signal.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(UpoError::NonFinite { index, value });
        }
        (0..self.count(signal.len()))
            .map(|i| {
                let start = i * self.step;
                Segment::new(
                    start,
                    self.periods,
                    &self.clock,
                    self.domain.distance(signal[start + l], signal[start]),
                    signal.len(),
                )
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(UpoError::from)
    }
}

impl WindowsBuilder {
    /// Window length `k >= 1` in forcing periods.
    pub fn periods(mut self, periods: usize) -> Self {
        self.periods = periods;
        self
    }

    /// Samples between the starts of consecutive windows, `>= 1` (`k P` for consecutive windows,
    /// less for overlapping ones, more to skip parts of the record).
    pub fn step(mut self, step: usize) -> Self {
        self.step = Some(step);
        self
    }

    /// The domain of the signal, and so the metric of [`Segment::error`]: [`Domain::Circle`] for
    /// a wrapped angle, [`Domain::Line`] on the line.
    pub fn domain(mut self, domain: Domain) -> Self {
        self.domain = domain;
        self
    }

    /// Validates: a clock with whole `P` (at least 2), `k >= 1`, `step >= 1`, and `k P` without
    /// overflow.
    pub fn build(self) -> Result<Windows, UpoError> {
        let samples_per_period = self.clock.require_whole()?;
        if self.periods == 0 {
            return Err(UpoError::InvalidCount {
                name: "window periods",
                value: 0,
                why: "must be at least 1",
            });
        }
        self.periods
            .checked_mul(samples_per_period)
            .and_then(|l| l.checked_add(1))
            .ok_or(UpoError::InvalidCount {
                name: "window periods",
                value: self.periods,
                why: "k P overflows",
            })?;
        let step = self.step.unwrap_or(samples_per_period);
        if step == 0 {
            return Err(UpoError::InvalidCount {
                name: "window step",
                value: 0,
                why: "must be at least 1 sample",
            });
        }
        Ok(Windows {
            clock: self.clock,
            samples_per_period,
            periods: self.periods,
            step,
            domain: self.domain,
        })
    }
}

impl OrbitSource for Windows {
    type Error = UpoError;

    fn clock(&self) -> &SampleClock {
        &self.clock
    }

    fn segments(&self, signal: &[f64]) -> Result<Vec<Segment>, UpoError> {
        self.windows(signal)
    }
}

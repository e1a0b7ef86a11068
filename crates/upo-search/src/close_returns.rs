//! The close-return search: parameters, metric, and the scan over periods.

use crate::catalogue::{Catalogue, group};
use crate::error::UpoError;
use crate::metric::{AnyCircle, Distance, Line, WrappedCircle};
use circle_signal::{Domain, OrbitSource, SampleClock, Segment};
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::ops::Range;

/// Close-return search for unstable periodic orbits (paper section 3.2), validated parameters.
///
/// With delay vectors `S(n) = (x_n, x_{n+Td}, …, x_{n+(d−1)Td})`, `P` samples per forcing period and
/// the absolute tolerance `ε = e · span`, there is a period-`k` close return at `n` when
/// `|S(n + kP) − S(n)| < ε` (max norm over components, in the [`Domain`]). Every index involved must
/// exist: `n + kP + (d − 1) Td < N`. A maximal run of consecutive passing `n` is one passage near an
/// orbit and gives at most one [`Segment`], at the `n` of least error (the earliest on a tie). That
/// segment is dropped when it already closes at a proper divisor `j` of `k` at the same `n`
/// (`|S(n + jP) − S(n)| < ε`): it is a repetition of a shorter orbit.
///
/// Build with [`CloseReturns::builder`] (or [`CloseReturns::new`] for the defaults).
#[derive(Debug, Clone, PartialEq)]
pub struct CloseReturns {
    clock: SampleClock,
    samples_per_period: usize,
    delay: usize,
    tolerance: f64,
    max_period: usize,
    dimension: usize,
    domain: Domain,
}

/// Builder of [`CloseReturns`]; [`build`](Self::build) validates.
#[derive(Debug, Clone, PartialEq)]
pub struct CloseReturnsBuilder {
    clock: SampleClock,
    delay: usize,
    tolerance: f64,
    max_period: usize,
    dimension: usize,
    domain: Domain,
}

impl CloseReturns {
    /// Default tolerance `e`: 3 % of the span of the data (the paper's choice).
    pub const DEFAULT_TOLERANCE: f64 = 0.03;
    /// Default longest period `k_max`, in forcing periods (the paper searched 1 to 16).
    pub const DEFAULT_MAX_PERIOD: usize = 16;
    /// Default embedding dimension `d` (the paper's choice for the pendulum).
    pub const DEFAULT_DIMENSION: usize = 2;

    /// A builder with the required clock (whole `P` samples per forcing period) and `delay` (`Td`, in samples,
    /// usually the first minimum of the average mutual information) and the defaults:
    /// tolerance [`DEFAULT_TOLERANCE`](Self::DEFAULT_TOLERANCE), periods
    /// `1..=`[`DEFAULT_MAX_PERIOD`](Self::DEFAULT_MAX_PERIOD), dimension
    /// [`DEFAULT_DIMENSION`](Self::DEFAULT_DIMENSION), domain [`Domain::Circle`].
    pub fn builder(clock: &SampleClock, delay: usize) -> CloseReturnsBuilder {
        CloseReturnsBuilder {
            clock: *clock,
            delay,
            tolerance: Self::DEFAULT_TOLERANCE,
            max_period: Self::DEFAULT_MAX_PERIOD,
            dimension: Self::DEFAULT_DIMENSION,
            domain: Domain::default(),
        }
    }

    /// The search with all defaults but the required clock and `Td`.
    pub fn new(clock: &SampleClock, delay: usize) -> Result<Self, UpoError> {
        Self::builder(clock, delay).build()
    }

    /// The clock the segments are cut on.
    pub fn clock(&self) -> &SampleClock {
        &self.clock
    }

    /// Samples per forcing period `P`.
    pub fn samples_per_period(&self) -> usize {
        self.samples_per_period
    }

    /// Embedding delay `Td` in samples.
    pub fn delay(&self) -> usize {
        self.delay
    }

    /// Tolerance `e` as a fraction of the span of the data.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Longest period searched, `k_max`, in forcing periods.
    pub fn max_period(&self) -> usize {
        self.max_period
    }

    /// Embedding dimension `d`.
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The domain of the signal, and so the metric.
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// Samples a record needs for period `k`: `k P + (d − 1) Td + 1` (`None` on overflow).
    pub fn needed_len(&self, period: usize) -> Option<usize> {
        period
            .checked_mul(self.samples_per_period)?
            .checked_add((self.dimension - 1).checked_mul(self.delay)?)?
            .checked_add(1)
    }

    /// The absolute tolerance `ε = e · span` for `signal`: `span = 2π` for [`Domain::Circle`],
    /// `max − min` of the record for [`Domain::Line`].
    ///
    /// Errors on an empty record, a non-finite sample, or a constant record on the line.
    pub fn absolute_tolerance(&self, signal: &[f64]) -> Result<f64, UpoError> {
        Ok(self.scan_input(signal)?.tolerance)
    }

    /// The recurrence error `|S(start + kP) − S(start)|` of the delay vector at `start` for period
    /// `period` (`k`), in this search's metric and dimension.
    ///
    /// Errors when `period` is zero, an index is out of the record, or a sample involved is not
    /// finite.
    pub fn return_error(&self, signal: &[f64], start: usize, period: usize) -> Result<f64, UpoError> {
        if period == 0 {
            return Err(UpoError::InvalidCount {
                name: "period",
                value: 0,
                why: "must be at least 1",
            });
        }
        let needed =
            self.needed_len(period)
                .and_then(|n| n.checked_add(start))
                .ok_or(UpoError::InvalidCount {
                    name: "start",
                    value: start,
                    why: "index overflows",
                })?;
        if signal.len() < needed {
            return Err(UpoError::TooShort {
                len: signal.len(),
                needed,
                period,
            });
        }
        let lag = period * self.samples_per_period;
        for c in 0..self.dimension {
            for i in [start + c * self.delay, start + c * self.delay + lag] {
                if !signal[i].is_finite() {
                    return Err(UpoError::NonFinite {
                        index: i,
                        value: signal[i],
                    });
                }
            }
        }
        Ok(match self.domain {
            Domain::Circle => self.error_at(signal, start, lag, AnyCircle),
            Domain::Line => self.error_at(signal, start, lag, Line),
        })
    }

    /// The close-return segments of `signal`, ordered by period, then start.
    ///
    /// Errors when the record is shorter than [`needed_len`](Self::needed_len)`(k_max)`, holds a
    /// non-finite sample, or (linear metric) is constant.
    pub fn search(&self, signal: &[f64]) -> Result<Vec<Segment>, UpoError> {
        let input = self.scan_input(signal)?;
        Ok(match (self.domain, input.within_pi) {
            (Domain::Circle, true) => self.scan(signal, input.tolerance, WrappedCircle),
            (Domain::Circle, false) => self.scan(signal, input.tolerance, AnyCircle),
            (Domain::Line, _) => self.scan(signal, input.tolerance, Line),
        })
    }

    /// The search and the catalogue of distinct orbits among its segments (see [`Catalogue`]).
    pub fn catalogue(&self, signal: &[f64]) -> Result<Catalogue, UpoError> {
        let input = self.scan_input(signal)?;
        let (p, k_max, eps) = (self.samples_per_period, self.max_period, input.tolerance);
        Ok(match (self.domain, input.within_pi) {
            (Domain::Circle, true) => group(
                signal,
                self.scan(signal, eps, WrappedCircle),
                p,
                k_max,
                eps,
                WrappedCircle,
            ),
            (Domain::Circle, false) => group(
                signal,
                self.scan(signal, eps, AnyCircle),
                p,
                k_max,
                eps,
                AnyCircle,
            ),
            (Domain::Line, _) => group(signal, self.scan(signal, eps, Line), p, k_max, eps, Line),
        })
    }

    /// The close-return segments of a record in pieces: `pieces` are the ranges of `signal` that
    /// hold samples (sorted, disjoint; what lies between them, such as the NaN of a gap, is never
    /// read), and no segment spans the space between two. Pieces too short for the longest period
    /// are skipped; the tolerance is relative to the span of all pieces together. Segment starts
    /// index `signal`; the order is by period, then start.
    ///
    /// Errors as [`search`](Self::search) does when no piece is long enough (naming the longest),
    /// and on pieces out of order or out of bounds.
    pub fn search_pieces(&self, signal: &[f64], pieces: &[Range<usize>]) -> Result<Vec<Segment>, UpoError> {
        let input = self.pieces_input(signal, pieces)?;
        Ok(match (self.domain, input.within_pi) {
            (Domain::Circle, true) => self.scan_pieces(signal, pieces, input.tolerance, WrappedCircle)?,
            (Domain::Circle, false) => self.scan_pieces(signal, pieces, input.tolerance, AnyCircle)?,
            (Domain::Line, _) => self.scan_pieces(signal, pieces, input.tolerance, Line)?,
        })
    }

    /// [`search_pieces`](Self::search_pieces) and the catalogue of distinct orbits among its
    /// segments: an orbit met in two pieces is one orbit.
    pub fn catalogue_pieces(&self, signal: &[f64], pieces: &[Range<usize>]) -> Result<Catalogue, UpoError> {
        let input = self.pieces_input(signal, pieces)?;
        let (p, k_max, eps) = (self.samples_per_period, self.max_period, input.tolerance);
        Ok(match (self.domain, input.within_pi) {
            (Domain::Circle, true) => group(
                signal,
                self.scan_pieces(signal, pieces, eps, WrappedCircle)?,
                p,
                k_max,
                eps,
                WrappedCircle,
            ),
            (Domain::Circle, false) => group(
                signal,
                self.scan_pieces(signal, pieces, eps, AnyCircle)?,
                p,
                k_max,
                eps,
                AnyCircle,
            ),
            (Domain::Line, _) => group(
                signal,
                self.scan_pieces(signal, pieces, eps, Line)?,
                p,
                k_max,
                eps,
                Line,
            ),
        })
    }

    /// The close-return segments of a system's record of several coordinates on one grid, in
    /// pieces as [`search_pieces`](Self::search_pieces) takes them: a return is close when the
    /// delay vectors of every coordinate return, its error the largest over the coordinates and
    /// delays of the distance (paper eq. 19 on the circle, each coordinate's own) — the state of
    /// the whole system returns, not one coordinate's projection of it. On the line each
    /// coordinate's distance is measured against its own span (the tolerance is the fraction of
    /// each span), reported in the first's. One coordinate is [`search_pieces`](Self::search_pieces).
    ///
    /// Errors as [`search_pieces`](Self::search_pieces) does, for any coordinate, and coordinates
    /// of different lengths.
    pub fn search_system_pieces(
        &self,
        coordinates: &[&[f64]],
        pieces: &[Range<usize>],
    ) -> Result<Vec<Segment>, UpoError> {
        let Some((&first, _)) = coordinates.split_first() else {
            return Err(UpoError::InvalidCount {
                name: "coordinates",
                value: 0,
                why: "must be at least 1",
            });
        };
        if coordinates.len() == 1 {
            return self.search_pieces(first, pieces);
        }
        if let Some(other) = coordinates.iter().find(|c| c.len() != first.len()) {
            return Err(UpoError::TooShort {
                len: other.len(),
                needed: first.len(),
                period: self.max_period,
            });
        }
        let mut scales = Vec::with_capacity(coordinates.len());
        let mut eps = 0.0;
        for (c, x) in coordinates.iter().enumerate() {
            let input = self.pieces_input(x, pieces)?;
            if c == 0 {
                eps = input.tolerance;
            }
            // Each coordinate's distance in units of the first's tolerance.
            scales.push(eps / input.tolerance);
        }
        let needed = self.needed()?;
        let (p, lag_of) = (self.samples_per_period, |k: usize| k * self.samples_per_period);
        let reach = (self.dimension - 1) * self.delay;
        let error_at = |n: usize, lag: usize| -> f64 {
            let mut e: f64 = 0.0;
            for (x, &scale) in coordinates.iter().zip(&scales) {
                for c in 0..self.dimension {
                    let i = n + c * self.delay;
                    let d = match self.domain {
                        Domain::Circle => circle_signal::circle_distance(x[i + lag], x[i]),
                        Domain::Line => (x[i + lag] - x[i]).abs(),
                    };
                    e = e.max(d * scale);
                }
            }
            e
        };
        let mut segments = Vec::new();
        for piece in pieces.iter().filter(|r| r.len() >= needed) {
            let found: Vec<Vec<Segment>> = (1..=self.max_period)
                .into_par_iter()
                .map(|k| {
                    let lag = lag_of(k);
                    let count = piece.len() - lag - reach;
                    let mut run = Run {
                        best: None,
                        segments: Vec::new(),
                    };
                    let emit = |out: &mut Vec<Segment>, (start, error): (usize, f64)| {
                        let repeated = (1..k)
                            .filter(|&j| k.is_multiple_of(j))
                            .any(|j| error_at(start, j * p) < eps);
                        if !repeated && let Ok(s) = Segment::new(start, k, &self.clock, error, first.len()) {
                            out.push(s);
                        }
                    };
                    let err: Vec<f64> = (piece.start..piece.start + count)
                        .map(|n| error_at(n, lag))
                        .collect();
                    run.feed(piece.start, &err, eps, &emit);
                    if let Some(last) = run.best.take() {
                        emit(&mut run.segments, last);
                    }
                    run.segments
                })
                .collect();
            segments.extend(found.into_iter().flatten());
        }
        segments.sort_by_key(|s| (s.period(), s.start()));
        Ok(segments)
    }

    /// Every piece long enough scanned on its own, the segments moved to the record's indices and
    /// sorted by period, then start.
    fn scan_pieces<D: Distance>(
        &self,
        signal: &[f64],
        pieces: &[Range<usize>],
        eps: f64,
        dist: D,
    ) -> Result<Vec<Segment>, UpoError> {
        let needed = self.needed()?;
        let mut segments = Vec::new();
        for piece in pieces.iter().filter(|r| r.len() >= needed) {
            for s in self.scan(&signal[piece.clone()], eps, dist) {
                segments.push(Segment::new(
                    piece.start + s.start(),
                    s.period(),
                    &self.clock,
                    s.error(),
                    signal.len(),
                )?);
            }
        }
        segments.sort_by_key(|s| (s.period(), s.start()));
        Ok(segments)
    }

    /// Validates the pieces and finds the absolute tolerance over all of them.
    fn pieces_input(&self, signal: &[f64], pieces: &[Range<usize>]) -> Result<InputScan, UpoError> {
        crate::check_pieces(signal, pieces)?;
        let needed = self.needed()?;
        let longest = pieces.iter().map(Range::len).max().unwrap_or(0);
        if longest < needed {
            return Err(UpoError::TooShort {
                len: longest,
                needed,
                period: self.max_period,
            });
        }
        self.span(pieces.iter().flat_map(|r| r.clone().map(|i| (i, signal[i]))))
    }

    /// Samples the longest period needs, `k_max P + (d − 1) Td + 1`.
    fn needed(&self) -> Result<usize, UpoError> {
        self.needed_len(self.max_period).ok_or(UpoError::InvalidCount {
            name: "max_period",
            value: self.max_period,
            why: "k_max P + (d - 1) Td overflows",
        })
    }

    /// Validates the record and finds the absolute tolerance.
    fn scan_input(&self, signal: &[f64]) -> Result<InputScan, UpoError> {
        let needed = self.needed()?;
        if signal.len() < needed {
            return Err(UpoError::TooShort {
                len: signal.len(),
                needed,
                period: self.max_period,
            });
        }
        self.span(signal.iter().copied().enumerate())
    }

    /// The tolerance from the span of `samples` (index, value), which must be finite.
    fn span(&self, samples: impl Iterator<Item = (usize, f64)>) -> Result<InputScan, UpoError> {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (index, value) in samples {
            if !value.is_finite() {
                return Err(UpoError::NonFinite { index, value });
            }
            lo = lo.min(value);
            hi = hi.max(value);
        }
        let span = match self.domain {
            Domain::Circle => TAU,
            Domain::Line => hi - lo,
        };
        // max − min of finite values can overflow to infinity: the tolerance would be useless.
        if !(span.is_finite() && span > 0.0) {
            return Err(UpoError::ConstantSignal { value: lo });
        }
        Ok(InputScan {
            tolerance: self.tolerance * span,
            within_pi: lo >= -PI && hi <= PI,
        })
    }

    /// All periods, in parallel; one block buffer per worker.
    fn scan<D: Distance>(&self, x: &[f64], eps: f64, dist: D) -> Vec<Segment> {
        let per_period: Vec<Vec<Segment>> = (1..=self.max_period)
            .into_par_iter()
            .map_init(Vec::new, |err, k| self.scan_period(x, k, eps, dist, err))
            .collect();
        per_period.concat()
    }

    /// One period `k`, block by block, in passes over each block that the compiler vectorizes:
    /// `err[n] = |S(n + kP) − S(n)|` one component at a time (a running max), then a scan of `err`
    /// that skips chunks with no value below `ε` outside a run.
    fn scan_period<D: Distance>(
        &self,
        x: &[f64],
        k: usize,
        eps: f64,
        dist: D,
        err: &mut Vec<f64>,
    ) -> Vec<Segment> {
        let lag = k * self.samples_per_period;
        let reach = (self.dimension - 1) * self.delay;
        // Validated: x.len() ≥ k_max P + reach + 1, so count ≥ 1.
        let count = x.len() - lag - reach;
        let mut run = Run {
            best: None,
            segments: Vec::new(),
        };
        let emit = |segments: &mut Vec<Segment>, (start, error): (usize, f64)| {
            let repeated = (1..k)
                .filter(|&j| k.is_multiple_of(j))
                .any(|j| self.error_at(x, start, j * self.samples_per_period, dist) < eps);
            if !repeated {
                segments.push(Segment::new(start, k, &self.clock, error, x.len()).expect(
                    "a close return closes inside the record on the search's clock (checked by `count`)",
                ));
            }
        };
        let mut b0 = 0;
        while b0 < count {
            let b1 = (b0 + BLOCK).min(count);
            let len = b1 - b0;
            // err[i] = max_c dist(x[n + c Td + kP], x[n + c Td]), n = b0 + i, component by component.
            err.clear();
            err.extend(
                x[b0 + lag..b1 + lag]
                    .iter()
                    .zip(&x[b0..b1])
                    .map(|(&a, &b)| dist.between(a, b)),
            );
            for c in 1..self.dimension {
                let o = b0 + c * self.delay;
                for (e, (&a, &b)) in err
                    .iter_mut()
                    .zip(x[o + lag..o + lag + len].iter().zip(&x[o..o + len]))
                {
                    let v = dist.between(a, b);
                    // `max` without its NaN handling (no NaN here) and without a branch, so that
                    // it vectorizes.
                    *e = if v > *e { v } else { *e };
                }
            }
            let mut chunks = err.chunks_exact(CHUNK);
            let mut base = b0;
            for chunk in &mut chunks {
                // An integer sum of comparisons: a reduction the compiler vectorizes.
                let below: usize = chunk.iter().map(|&v| usize::from(v < eps)).sum();
                if below > 0 || run.best.is_some() {
                    run.feed(base, chunk, eps, &emit);
                }
                base += CHUNK;
            }
            run.feed(base, chunks.remainder(), eps, &emit);
            b0 = b1;
        }
        if let Some(found) = run.best {
            emit(&mut run.segments, found);
        }
        run.segments
    }

    /// `max_c dist(x[n + c Td + lag], x[n + c Td])`; indices must exist.
    fn error_at<D: Distance>(&self, x: &[f64], n: usize, lag: usize, dist: D) -> f64 {
        (0..self.dimension)
            .map(|c| {
                let i = n + c * self.delay;
                dist.between(x[i + lag], x[i])
            })
            .fold(0.0, f64::max)
    }
}

/// The state of the scan of one period: the best `(n, error)` of the current run, if in one.
struct Run {
    best: Option<(usize, f64)>,
    segments: Vec<Segment>,
}

impl Run {
    /// Feeds `err[n]` for `n = base, base + 1, …`.
    #[inline]
    fn feed<F>(&mut self, base: usize, err: &[f64], eps: f64, emit: &F)
    where
        F: Fn(&mut Vec<Segment>, (usize, f64)),
    {
        for (i, &e) in err.iter().enumerate() {
            if e < eps {
                if self.best.is_none_or(|(_, b)| e < b) {
                    self.best = Some((base + i, e));
                }
            } else if let Some(found) = self.best.take() {
                emit(&mut self.segments, found);
            }
        }
    }
}

/// Values of `err` tested at once before the scan looks at them one by one.
const CHUNK: usize = 16;

/// Samples per block of the scan: the block's errors (16 KiB) and the samples it reads stay in cache.
const BLOCK: usize = 2048;

/// What one pass over the input finds.
struct InputScan {
    tolerance: f64,
    within_pi: bool,
}

impl CloseReturnsBuilder {
    /// Tolerance `e` as a fraction of the span of the data, in `(0, 0.5)`.
    pub fn tolerance(mut self, fraction: f64) -> Self {
        self.tolerance = fraction;
        self
    }

    /// Longest period `k_max` (at least 1): periods `1..=k_max` are searched.
    pub fn max_period(mut self, k_max: usize) -> Self {
        self.max_period = k_max;
        self
    }

    /// Embedding dimension `d` (at least 1).
    pub fn dimension(mut self, d: usize) -> Self {
        self.dimension = d;
        self
    }

    /// The domain of the signal, and so the metric: [`Domain::Circle`] for a wrapped angle,
    /// [`Domain::Line`] for a displacement.
    pub fn domain(mut self, domain: Domain) -> Self {
        self.domain = domain;
        self
    }

    /// Validates and builds.
    pub fn build(self) -> Result<CloseReturns, UpoError> {
        if !(self.tolerance > 0.0 && self.tolerance < 0.5) {
            return Err(UpoError::InvalidTolerance {
                value: self.tolerance,
            });
        }
        let samples_per_period = self.clock.require_whole()?;
        for (name, value) in [
            ("delay", self.delay),
            ("max_period", self.max_period),
            ("dimension", self.dimension),
        ] {
            if value == 0 {
                return Err(UpoError::InvalidCount {
                    name,
                    value,
                    why: "must be at least 1",
                });
            }
        }
        let search = CloseReturns {
            clock: self.clock,
            samples_per_period,
            delay: self.delay,
            tolerance: self.tolerance,
            max_period: self.max_period,
            dimension: self.dimension,
            domain: self.domain,
        };
        if search.needed_len(search.max_period).is_none() {
            return Err(UpoError::InvalidCount {
                name: "max_period",
                value: search.max_period,
                why: "k_max P + (d - 1) Td overflows",
            });
        }
        Ok(search)
    }
}

impl OrbitSource for CloseReturns {
    type Error = UpoError;

    fn clock(&self) -> &SampleClock {
        &self.clock
    }

    fn segments(&self, signal: &[f64]) -> Result<Vec<Segment>, UpoError> {
        self.search(signal)
    }
}

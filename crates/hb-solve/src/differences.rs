//! Pointwise identification from finite differences: the classic peer of harmonic balance.

use circle_signal::{Segment, unwrap_into, wrap};
use faer::{Col, Mat};
use hb_basis::{Basis, Domain};

use crate::error::{AssemblyError, LstsqError, SolveError};
use crate::method::Assembly;
use crate::params::IdentifyParams;
use crate::signals::Signals;
use crate::system::{Block, LinearSystem};
use crate::system::{Layout, layout};
use hb_model::{Column, PositionFactor};
use hb_model::{Forcing, Harmonics};

/// The equation of motion at every sample, with `x'` and `x''` from fourth-order central
/// differences of the (unwrapped) record: what most identification tools do, and the peer the
/// harmonic-balance methods are measured against (`docs/accuracy.md`).
///
/// On a segment of `L` samples and its closing one, sample `n` gives the row
/// `Σ_i λ_i g_i(x_n, x'_n, t_n) = −x''_n` (any term: its factors evaluated at the sample) for every `n` of `start .. start + L` whose stencil
/// `n − 2 ..= n + 2` lies in the record, with
/// `x'_n = (−x_{n+2} + 8 x_{n+1} − 8 x_{n−1} + x_{n−2}) / 12h` and
/// `x''_n = (−x_{n+2} + 16 x_{n+1} − 30 x_n + 16 x_{n−1} − x_{n−2}) / 12h²`; the measured drive `p`
/// is its sample at `n`. Differences amplify
/// noise by `1/h` and `1/h²`: the method is exact only in the limit of fine sampling and no noise.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FiniteDifferences;

impl Assembly for FiniteDifferences {
    fn name(&self) -> &'static str {
        "differences"
    }

    /// Not used: the rows are samples, not harmonics.
    fn default_harmonics(&self) -> Harmonics {
        Harmonics::DEFAULT
    }

    fn assemble(
        &self,
        basis: &dyn Basis,
        signals: &Signals<'_>,
        segments: &[Segment],
        params: &IdentifyParams,
    ) -> Result<LinearSystem, SolveError> {
        let layout = layout(basis, signals, segments, params)?;
        let Layout {
            domain, ref columns, ..
        } = layout;
        if let Some(i) = layout.terms.iter().position(|t| !t.coupling.is_empty()) {
            return Err(SolveError::Assembly(AssemblyError::TermNotSupported {
                term: layout.term_names[i].clone(),
                by: "the finite differences (a term in another coordinate or an acceleration: use the weak form)",
            }));
        }
        let signal = signals.own();
        let clock = params.clock();
        let h = clock.step();
        let w = clock.drive_angular_frequency();
        // The rows of each segment: its samples whose stencil lies in the record.
        let spans: Vec<(usize, usize)> = segments
            .iter()
            .map(|s| (s.start().max(2), s.closing().min(signal.len().saturating_sub(2))))
            .collect();
        let rows: usize = spans.iter().map(|&(a, b)| b.saturating_sub(a)).sum();
        if rows <= columns.len() {
            return Err(SolveError::Lstsq(LstsqError::TooFewOrbits {
                found: segments.len(),
                needed: segments.len() + 1,
            }));
        }
        let mut matrix = Mat::<f64>::zeros(rows, columns.len());
        let mut rhs = Col::<f64>::zeros(rows);
        let mut blocks = Vec::with_capacity(segments.len());
        let mut phi = vec![0.0; basis.len()];
        let mut y = Vec::new();
        let mut r = 0;
        for (index, (segment, &(lo, hi))) in segments.iter().zip(&spans).enumerate() {
            let first_row = r;
            // The stencil's samples, unwrapped on the circle so that x' sees no jump of 2π.
            let stretch = &signal[lo.saturating_sub(2)..(hi + 2).min(signal.len())];
            match domain {
                Domain::Circle => unwrap_into(stretch, &mut y),
                Domain::Line => {
                    y.clear();
                    y.extend_from_slice(stretch);
                }
            }
            for n in lo..hi {
                let k = n + 2 - lo;
                let d1 = (-y[k + 2] + 8.0 * y[k + 1] - 8.0 * y[k - 1] + y[k - 2]) / (12.0 * h);
                let d2 =
                    (-y[k + 2] + 16.0 * y[k + 1] - 30.0 * y[k] + 16.0 * y[k - 1] - y[k - 2]) / (12.0 * h * h);
                let (s, c) = (w * clock.time(n)).sin_cos();
                let x = match domain {
                    Domain::Circle => wrap(y[k]),
                    Domain::Line => y[k],
                };
                basis.eval(x, &mut phi);
                for (col, &column) in columns.iter().enumerate() {
                    matrix[(r, col)] = match column {
                        Column::Damping => d1,
                        Column::Auto(i) => phi[i],
                        Column::CosT(i) => c * phi[i],
                        Column::SinT(i) => s * phi[i],
                        Column::ForcingCos => c,
                        Column::ForcingSin => s,
                        Column::Stiffness => y[k],
                        Column::Product(t) => {
                            let position = match t.position {
                                PositionFactor::One => 1.0,
                                PositionFactor::Basis(i) => phi[i],
                                PositionFactor::Linear => y[k],
                            };
                            // The measured drive, when a term has it (checked by the layout).
                            let p = t
                                .drive
                                .measured_index()
                                .and_then(|d| signals.drive(d))
                                .map_or(f64::NAN, |p| p[n]);
                            t.drive.eval(w * clock.time(n), p) * position * t.velocity.eval(d1)
                        }
                    };
                }
                rhs[r] = -d2
                    - match params.form().forcing() {
                        Forcing::Known { cos, sin } => cos * c + sin * s,
                        _ => 0.0,
                    };
                if !rhs[r].is_finite() || (0..columns.len()).any(|col| !matrix[(r, col)].is_finite()) {
                    return Err(SolveError::Assembly(AssemblyError::NonFiniteRow {
                        segment: index,
                        start: segment.start(),
                        row: r - first_row,
                    }));
                }
                r += 1;
            }
            blocks.push(Block {
                segment: *segment,
                first_row,
                rows: r - first_row,
                harmonics: 0,
                winding: 0,
                rotation_rate: 0.0,
                group: None,
            });
        }
        Ok(LinearSystem::from_parts(matrix, rhs, layout.term_names(), blocks))
    }
}

//! Gaussian noise on a measured angle: an estimate of its level, and the correction of the bias
//! it puts into the trigonometric terms (see [`NoiseCorrection`]).

use circle_signal::unwrap;
use hb_basis::{Basis, Domain, FourierPlan};

use hb_model::{Column, PositionFactor, VelocityFactor, columns, term_names};

use crate::error::{AssemblyError, SolveError};
use crate::params::{IdentifyParams, NoiseCorrection};
use crate::system::LinearSystem;
use hb_model::form::column_families;

/// The band of the noise estimate: frequencies from this fraction of the Nyquist frequency up to
/// the Nyquist frequency.
pub const NOISE_BAND_START: f64 = 0.8;

/// Shortest record [`estimate_noise_sigma`] accepts.
pub const NOISE_ESTIMATE_MIN_LEN: usize = 64;

/// Estimates the standard deviation `σ` of white measurement noise on a record from its highest
/// frequencies.
///
/// The record (unwrapped first on the circle) is detrended by its least-squares line, tapered by
/// `w_n = sin⁴(π (n + ½) / N)`, and transformed; white noise of variance `σ²` gives every bin
/// `E|X_j|² = σ² Σ w_n²`, so `σ̂² = mean |X_j|² / Σ w_n²` over the bins from
/// [`NOISE_BAND_START`] times the Nyquist frequency up to (not including) it.
///
/// The estimate assumes that the motion itself has no power in that band, i.e. that the record is
/// sampled well above the motion's bandwidth. On the paper's pendulum sampled 25 times per forcing
/// period the noise-free record reads as `σ̂ ≈ 1e-5` rad there, so estimates above about `1e-4`
/// rad are the noise's; below that the correction `e^{k²σ²/2}` is 1 to within `1e-8` anyway. A
/// coarser sampling puts some of the motion into the band and overestimates `σ`.
///
/// Errors: fewer than [`NOISE_ESTIMATE_MIN_LEN`] samples, or a non-finite sample.
pub fn estimate_noise_sigma(signal: &[f64], domain: Domain) -> Result<f64, SolveError> {
    let n = signal.len();
    if n < NOISE_ESTIMATE_MIN_LEN {
        return Err(SolveError::Assembly(AssemblyError::RecordTooShort {
            what: "the noise estimate",
            len: n,
            needed: NOISE_ESTIMATE_MIN_LEN,
        }));
    }
    if let Some((index, &value)) = signal.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SolveError::Assembly(AssemblyError::NonFiniteRecordSample {
            index,
            value,
        }));
    }
    let mut y = match domain {
        Domain::Circle => unwrap(signal),
        Domain::Line => signal.to_vec(),
    };
    // Least-squares line through (n, y_n), centred abscissa.
    let mid = (n - 1) as f64 / 2.0;
    let mean = y.iter().sum::<f64>() / n as f64;
    let (sxy, sxx) = y.iter().enumerate().fold((0.0, 0.0), |(sxy, sxx), (i, &v)| {
        let d = i as f64 - mid;
        (sxy + d * (v - mean), sxx + d * d)
    });
    let slope = sxy / sxx;
    let mut taper_energy = 0.0;
    for (i, v) in y.iter_mut().enumerate() {
        let s = (std::f64::consts::PI * (i as f64 + 0.5) / n as f64).sin();
        let w = s.powi(4);
        taper_energy += w * w;
        *v = (*v - mean - slope * (i as f64 - mid)) * w;
    }
    let mut plan = FourierPlan::new(n)?;
    let spectrum = plan.transform(&y)?;
    let nyquist = n / 2;
    let first = ((NOISE_BAND_START * nyquist as f64).ceil() as usize).max(1);
    let bins = &spectrum.bins()[first..nyquist];
    let power = bins.iter().map(|b| b.norm_sqr()).sum::<f64>() / bins.len() as f64;
    Ok((power / taper_energy).sqrt())
}

/// The order `k` of a basis function that is a single harmonic `a cos(kx) + b sin(kx)`, `k >= 1`,
/// found from its spectrum on a grid of the circle; `None` for anything else (hats, constants).
pub(crate) fn harmonic_order<B: Basis + ?Sized>(basis: &B, i: usize) -> Result<Option<usize>, SolveError> {
    const GRID: usize = 256;
    let mut phi = vec![0.0; basis.len()];
    let values: Vec<f64> = (0..GRID)
        .map(|g| {
            basis.eval(
                -std::f64::consts::PI + std::f64::consts::TAU * g as f64 / GRID as f64,
                &mut phi,
            );
            phi[i]
        })
        .collect();
    if values.iter().any(|v| !v.is_finite()) {
        return Ok(None);
    }
    let mut plan = FourierPlan::new(GRID)?;
    let spectrum = plan.transform(&values)?;
    let amplitude: Vec<f64> = spectrum.bins().iter().map(|b| b.norm()).collect();
    let top = amplitude.iter().copied().fold(0.0_f64, f64::max);
    if top == 0.0 {
        return Ok(None);
    }
    let mut significant = amplitude
        .iter()
        .enumerate()
        .filter(|&(_, &a)| a > 1e-9 * top)
        .map(|(m, _)| m);
    // One mode, well below the grid's Nyquist frequency so that it cannot be an alias.
    Ok(match (significant.next(), significant.next()) {
        (Some(m), None) if (1..GRID / 4).contains(&m) => Some(m),
        _ => None,
    })
}

/// The factors `e^{k²σ²/2}` of each column of a model on `basis` (1 for the columns that hold no
/// function of the angle).
pub(crate) fn column_factors<B: Basis + ?Sized>(
    basis: &B,
    params: &IdentifyParams,
    sigma: f64,
) -> Result<Vec<f64>, SolveError> {
    let names = basis.names();
    let terms = columns(basis, params.form())?;
    let layout = column_families(&terms);
    let mut orders = vec![None; names.len()];
    let mut factors = Vec::with_capacity(layout.len());
    for (term, column) in terms.iter().zip(layout) {
        let i = match column {
            Column::Auto(i) | Column::CosT(i) | Column::SinT(i) => i,
            Column::Damping | Column::ForcingCos | Column::ForcingSin | Column::Stiffness => {
                factors.push(1.0);
                continue;
            }
            Column::Product(t) => {
                if !t.coupling.is_empty() {
                    return Err(SolveError::Assembly(AssemblyError::NoiseCorrectionUnavailable {
                        term: term_names(basis, params.form()).swap_remove(factors.len()),
                        why: "the correction rescales functions of the own angle alone; a term in another \
                              coordinate or an acceleration is not a rescaling",
                    }));
                }
                match t.velocity {
                    // x' is linear in the data: its noise is independent of that of x at the same
                    // instant (stationary noise), so E[φ(x + n) (x' + n')] = E[φ(x + n)] x'.
                    VelocityFactor::One | VelocityFactor::Linear => {}
                    VelocityFactor::Sign
                    | VelocityFactor::Quadratic
                    | VelocityFactor::Cubic
                    | VelocityFactor::Square => {
                        return Err(SolveError::Assembly(AssemblyError::NoiseCorrectionUnavailable {
                            term: term.name(&names),
                            why: "the bias of a nonlinear function of x' under noise on the angle depends on \
                                  the noise of the velocity series, not a rescaling; identify without the \
                                  correction",
                        }));
                    }
                }
                match t.position {
                    PositionFactor::Basis(i) => i,
                    PositionFactor::One | PositionFactor::Linear => {
                        factors.push(1.0);
                        continue;
                    }
                }
            }
        };
        if basis.domain() != Domain::Circle {
            return Err(SolveError::Assembly(AssemblyError::NoiseCorrectionUnavailable {
                term: names[i].clone(),
                why: "the correction is for an angle on the circle; on the line the bias of a \
                      function of the displacement is not a rescaling",
            }));
        }
        let k = match orders[i] {
            Some(k) => k,
            None => {
                let k = harmonic_order(basis, i)?.ok_or_else(|| {
                    SolveError::Assembly(AssemblyError::NoiseCorrectionUnavailable {
                        term: names[i].clone(),
                        why: "it is not a single harmonic cos(kx) or sin(kx) of the angle, so its bias \
                          under noise is not a rescaling; use the harmonic basis",
                    })
                })?;
                orders[i] = Some(k);
                k
            }
        };
        let kf = k as f64;
        factors.push((0.5 * kf * kf * sigma * sigma).exp());
    }
    Ok(factors)
}

/// The longest run of finite samples of `signal` (the first of the longest; empty if none).
fn longest_finite_run(signal: &[f64]) -> &[f64] {
    let mut best = 0..0;
    let mut start = 0;
    for (i, v) in signal.iter().enumerate() {
        if !v.is_finite() {
            start = i + 1;
        } else if i + 1 - start > best.len() {
            best = start..i + 1;
        }
    }
    &signal[best]
}

/// Applies the params' [`NoiseCorrection`] to an assembled system of `basis` on `signal`. An
/// estimated `σ` of a record with gaps (NaN between its pieces, which the segments never reach)
/// comes from its longest piece.
pub fn correct_noise<B: Basis + ?Sized>(
    basis: &B,
    signal: &[f64],
    params: &IdentifyParams,
    system: &mut LinearSystem,
) -> Result<(), SolveError> {
    let sigma = match params.noise_correction() {
        NoiseCorrection::None => return Ok(()),
        NoiseCorrection::Given { sigma } => sigma,
        NoiseCorrection::Estimated => estimate_noise_sigma(longest_finite_run(signal), basis.domain())?,
    };
    for (c, factor) in column_factors(basis, params, sigma)?.into_iter().enumerate() {
        if !factor.is_finite() {
            return Err(SolveError::InvalidParameter {
                name: "noise sigma",
                value: sigma,
                why: "so large that the correction factor overflows",
            });
        }
        if factor != 1.0 {
            system.scale_column(c, factor);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hb_basis::{Harmonic, Hat, Polynomial};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn orders_of_basis_functions() {
        let h = Harmonic::new(3).unwrap();
        let orders: Vec<_> = (0..6).map(|i| harmonic_order(&h, i).unwrap()).collect();
        assert_eq!(orders, [Some(1), Some(1), Some(2), Some(2), Some(3), Some(3)]);
        let hat = Hat::new(8).unwrap();
        assert_eq!(harmonic_order(&hat, 2).unwrap(), None);
        // The line is refused before any order is looked for.
        let clock = circle_signal::SampleClock::nondimensional(25).unwrap();
        let params = IdentifyParams::builder(clock).build().unwrap();
        assert!(matches!(
            column_factors(&Polynomial::new(2).unwrap(), &params, 0.1),
            Err(SolveError::Assembly(
                AssemblyError::NoiseCorrectionUnavailable { .. }
            ))
        ));
        assert!(matches!(
            column_factors(&hat, &params, 0.1),
            Err(SolveError::Assembly(
                AssemblyError::NoiseCorrectionUnavailable { .. }
            ))
        ));
        // x', then (cos t, sin t, 1) times cos x, sin x, cos 2x, sin 2x.
        let f = column_factors(&Harmonic::new(2).unwrap(), &params, 0.2).unwrap();
        assert_eq!(f.len(), 13);
        assert_eq!(f[0], 1.0);
        assert!((f[1] - (0.02f64).exp()).abs() < 1e-15);
        assert!((f[12] - (0.08f64).exp()).abs() < 1e-15);
    }

    /// A smooth whirling-and-swinging angle, wrapped, with white noise of known σ.
    fn noisy(sigma: f64, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, sigma).unwrap();
        (0..20_000)
            .map(|n| {
                let t = n as f64 * std::f64::consts::TAU / 25.0;
                let x = 0.3 * t + 1.5 * (0.5 * t).sin() + 0.4 * (1.3 * t + 0.2).cos();
                circle_signal::wrap(x + noise.sample(&mut rng))
            })
            .collect()
    }

    #[test]
    fn the_longest_finite_run() {
        let nan = f64::NAN;
        assert_eq!(longest_finite_run(&[1.0, nan, 2.0, 3.0, nan, 4.0]), &[2.0, 3.0]);
        assert_eq!(longest_finite_run(&[1.0, 2.0, nan, 3.0, 4.0]), &[1.0, 2.0]);
        assert_eq!(longest_finite_run(&[nan, f64::INFINITY]), &[] as &[f64]);
        assert_eq!(longest_finite_run(&[5.0]), &[5.0]);
    }

    #[test]
    fn estimates_the_noise_level() {
        for (sigma, seed) in [(0.01, 1), (0.05, 2), (0.2, 3)] {
            let est = estimate_noise_sigma(&noisy(sigma, seed), Domain::Circle).unwrap();
            // About 2000 bins of a chi-squared: a relative spread near 1 / sqrt(2000).
            assert!((est / sigma - 1.0).abs() < 0.05, "sigma {sigma}: {est}");
        }
        assert!(estimate_noise_sigma(&noisy(0.0, 4), Domain::Circle).unwrap() < 1e-8);
        assert!(matches!(
            estimate_noise_sigma(&[0.0; 10], Domain::Line),
            Err(SolveError::Assembly(AssemblyError::RecordTooShort {
                len: 10,
                ..
            }))
        ));
        let mut x = noisy(0.1, 5);
        x[7] = f64::NAN;
        assert!(matches!(
            estimate_noise_sigma(&x, Domain::Circle),
            Err(SolveError::Assembly(AssemblyError::NonFiniteRecordSample {
                index: 7,
                ..
            }))
        ));
    }
}

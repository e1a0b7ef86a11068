//! `simulate`: the base-excited pendulum or the two-well Duffing oscillator sampled as a rig
//! records it, composed from `pendulum_sim`'s systems, frame and encoder with the options and
//! defaults of `hbid simulate` (the file-only ones, printed decimals and the truth file, aside).

use std::f64::consts::TAU;

use hb_basis::{Harmonic, Polynomial};
use hb_solve::{Forcing, ModelForm};
use numpy::PyArray1;
use pendulum_sim::observe::{AngleRange, Encoder, Gaps};
use pendulum_sim::{
    Duffing, InFrame, Pendulum, RecordFrame, SecondOrderSystem, SimError, SimulationConfig, Tolerances,
    Trajectory, TrueCoefficients, simulate as integrate,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::Kind;
use crate::options::{Failure, bad, fail};

/// The system chosen, with its parameters checked.
#[derive(Debug, Clone, Copy)]
enum System {
    Pendulum(Pendulum),
    Duffing(Duffing),
}

/// The options of a simulation (those of `hbid simulate`).
#[derive(Debug)]
pub struct Rig {
    system: String,
    f: Option<f64>,
    c: Option<f64>,
    r: Option<f64>,
    a: Option<f64>,
    b: Option<f64>,
    forcing: String,
    x0: f64,
    v0: f64,
    rtol: f64,
    drive_frequency: Option<f64>,
    sample_rate: Option<f64>,
    samples_per_period: Option<usize>,
    samples: Option<usize>,
    duration: Option<f64>,
    transient_periods: Option<usize>,
    phase: f64,
    time_origin: String,
    counts: Option<u32>,
    raw_counts: bool,
    zero_offset: Option<f64>,
    bit_errors: Option<f64>,
    angle_range: Option<String>,
    noise: Option<f64>,
    seed: u64,
    unwrapped: bool,
    gaps: Option<(usize, usize)>,
}

impl Rig {
    /// The defaults of `simulate` (the paper's data set) with `samples`, `noise` and `seed`.
    pub fn paper(samples: Option<usize>, noise: Option<f64>, seed: u64) -> Self {
        Self {
            system: "pendulum".to_owned(),
            f: None,
            c: None,
            r: None,
            a: None,
            b: None,
            forcing: "drive".to_owned(),
            x0: 0.1,
            v0: 0.0,
            rtol: 1e-10,
            drive_frequency: None,
            sample_rate: None,
            samples_per_period: None,
            samples,
            duration: None,
            transient_periods: None,
            phase: 0.0,
            time_origin: "drive".to_owned(),
            counts: None,
            raw_counts: false,
            zero_offset: None,
            bit_errors: None,
            angle_range: None,
            noise,
            seed,
            unwrapped: false,
            gaps: None,
        }
    }
}

fn sim(argument: &'static str) -> impl FnOnce(SimError) -> Failure {
    move |e| (Kind::Options, format!("{argument}: {}", crate::errors::chain(&e)))
}

impl Rig {
    fn driven(&self) -> Result<bool, Failure> {
        match self.forcing.as_str() {
            "drive" => Ok(true),
            "none" => Ok(false),
            other => Err(bad(format!("forcing='{other}': expected 'drive' or 'none'"))),
        }
    }

    fn system(&self) -> Result<System, Failure> {
        let driven = self.driven()?;
        if !driven && self.f.is_some() {
            return Err(bad("f is the drive's amplitude: not with forcing='none'"));
        }
        let drive = |default: f64| if driven { self.f.unwrap_or(default) } else { 0.0 };
        Ok(match self.system.as_str() {
            "pendulum" => {
                if self.a.is_some() || self.b.is_some() {
                    return Err(bad(
                        "a and b are the Duffing oscillator's stiffnesses (system='duffing')",
                    ));
                }
                let (f, c, r) = Pendulum::PAPER;
                System::Pendulum(
                    Pendulum::new(drive(f), self.c.unwrap_or(c), self.r.unwrap_or(r))
                        .map_err(fail(Kind::Options))?,
                )
            }
            "duffing" => {
                if self.r.is_some() {
                    return Err(bad("r is the pendulum's frequency ratio (system='pendulum')"));
                }
                let encoder_options = [
                    ("counts", self.counts.is_some()),
                    ("raw_counts", self.raw_counts),
                    ("zero_offset", self.zero_offset.is_some()),
                    ("bit_errors", self.bit_errors.is_some()),
                    ("angle_range", self.angle_range.is_some()),
                ];
                if let Some((name, _)) = encoder_options.iter().find(|(_, set)| *set) {
                    return Err(bad(format!(
                        "{name} is an angle encoder's: system='pendulum' only (the Duffing displacement takes noise)"
                    )));
                }
                let (c, a, b, f) = Duffing::TWO_WELL;
                System::Duffing(
                    Duffing::new(
                        self.c.unwrap_or(c),
                        self.a.unwrap_or(a),
                        self.b.unwrap_or(b),
                        drive(f),
                    )
                    .map_err(fail(Kind::Options))?,
                )
            }
            other => return Err(bad(format!("system='{other}': expected 'pendulum' or 'duffing'"))),
        })
    }

    /// The record's frame, the simulation's configuration and the time stamps' origin.
    fn timing(&self) -> Result<(RecordFrame, SimulationConfig, bool, f64), Failure> {
        let frame = match self.drive_frequency {
            None => RecordFrame::nondimensional(),
            Some(hz) => RecordFrame::nondimensional()
                .with_drive_frequency(hz)
                .map_err(sim("drive_frequency"))?,
        };
        let mut config = SimulationConfig::paper();
        if let Some(hz) = self.drive_frequency {
            config = config
                .with_forcing_period(1.0 / hz)
                .map_err(sim("drive_frequency"))?;
        }
        match (self.sample_rate, self.samples_per_period) {
            (Some(_), Some(_)) => return Err(bad("sample_rate and samples_per_period both set: give one")),
            (Some(_), None) if self.drive_frequency.is_none() => {
                return Err(bad("sample_rate needs drive_frequency (time in seconds)"));
            }
            (Some(rate), None) => {
                if !(rate.is_finite() && rate > 0.0) {
                    return Err(bad(format!("sample_rate={rate}: must be positive and finite")));
                }
                config = config.with_sample_step(1.0 / rate).map_err(sim("sample_rate"))?;
            }
            (None, Some(p)) => {
                config = config
                    .with_samples_per_period(p)
                    .map_err(sim("samples_per_period"))?
            }
            (None, None) => {}
        }
        let step = config.sample_step();
        let samples = match (self.samples, self.duration) {
            (Some(_), Some(_)) => return Err(bad("samples and duration both set: give one")),
            (Some(n), None) => n,
            (None, Some(d)) => samples_in(d, step)?,
            (None, None) => config.samples(),
        };
        let driven = self.driven()?;
        let transient = self
            .transient_periods
            .unwrap_or(if driven { config.transient_periods() } else { 0 });
        if !self.phase.is_finite() {
            return Err(bad(format!("phase={}: must be finite", self.phase)));
        }
        let mut fraction = self.phase.rem_euclid(TAU) / TAU;
        if fraction >= 1.0 {
            fraction = 0.0;
        }
        let first_sample = match self.time_origin.as_str() {
            "drive" => false,
            "first-sample" | "first_sample" => true,
            other => {
                return Err(bad(format!(
                    "time_origin='{other}': expected 'drive' or 'first-sample'"
                )));
            }
        };
        let tolerances = Tolerances::relative(self.rtol).map_err(sim("rtol"))?;
        let config = config
            .with_samples(samples)
            .map_err(sim("samples"))?
            .with_transient_periods(transient)
            .with_initial(self.x0, self.v0)
            .map_err(sim("x0, v0"))?
            .with_phase(fraction)
            .map_err(sim("phase"))?
            .with_tolerances(tolerances);
        Ok((frame, config, first_sample, TAU * fraction))
    }

    /// The encoder, `None` for an ideal one (the angle is then only wrapped).
    fn encoder(&self) -> Result<Option<Encoder>, Failure> {
        if self.raw_counts && self.counts.is_none() {
            return Err(bad("raw_counts needs counts"));
        }
        if self.bit_errors.is_some() && self.counts.is_none() {
            return Err(bad(
                "bit_errors needs counts (bit errors are errors of the count)",
            ));
        }
        if self.unwrapped && self.raw_counts {
            return Err(bad("raw_counts gives counts in [0, N): not with unwrapped"));
        }
        if self.angle_range.is_some() && (self.unwrapped || self.raw_counts) {
            return Err(bad(
                "angle_range is where a wrapped angle lies: not with unwrapped or raw_counts",
            ));
        }
        let positive = match self.angle_range.as_deref() {
            None | Some("signed") => false,
            Some("positive") => true,
            Some(other) => {
                return Err(bad(format!(
                    "angle_range='{other}': expected 'signed' or 'positive'"
                )));
            }
        };
        let any = self.noise.is_some()
            || self.counts.is_some()
            || self.zero_offset.is_some()
            || self.bit_errors.is_some()
            || self.angle_range.is_some();
        if !any {
            return Ok(None);
        }
        let mut e = Encoder::seeded(self.seed);
        if let Some(sigma) = self.noise {
            e = e.with_noise(sigma).map_err(sim("noise"))?;
        }
        if let Some(n) = self.counts {
            e = e.with_counts(n).map_err(sim("counts"))?;
        }
        if let Some(offset) = self.zero_offset {
            e = e.with_zero_offset(offset).map_err(sim("zero_offset"))?;
        }
        if let Some(rate) = self.bit_errors {
            e = e.with_bit_errors(rate).map_err(sim("bit_errors"))?;
        }
        if positive {
            e = e.with_range(AngleRange::Positive);
        }
        Ok(Some(e))
    }
}

/// The samples in `duration` at step `step`: `duration / step` rounded down, a ratio within
/// 1e-9 of a whole number taken as that number (as `hbid simulate --duration`).
fn samples_in(duration: f64, step: f64) -> Result<usize, Failure> {
    if !(duration.is_finite() && duration > 0.0) {
        return Err(bad(format!("duration={duration}: must be positive and finite")));
    }
    let ratio = duration / step;
    let whole = ratio.round();
    let n = if (ratio - whole).abs() <= 1e-9 * ratio.max(1.0) {
        whole
    } else {
        ratio.floor()
    };
    if n < 1.0 {
        return Err(bad(format!(
            "duration={duration} is shorter than one sample step ({step})"
        )));
    }
    if n > usize::MAX as f64 {
        return Err(bad(format!("duration={duration}: too many samples")));
    }
    Ok(n as usize)
}

fn run<S: SecondOrderSystem>(system: &S, config: &SimulationConfig) -> Result<Trajectory, Failure> {
    integrate(system, config).map_err(fail(Kind::Simulation))
}

/// What a simulation gives back.
pub struct Simulated {
    /// The time stamps.
    pub t: Vec<f64>,
    /// The angle or displacement.
    pub x: Vec<f64>,
    v: Vec<f64>,
    columns: [&'static str; 3],
    truth: Vec<(String, f64)>,
    forcing_period: f64,
    sample_step: f64,
}

/// Simulates a rig's record, as `hbid simulate` writes it.
#[pyfunction]
#[pyo3(signature = (
    *, system="pendulum".to_owned(), f=None, c=None, r=None, a=None, b=None, forcing="drive".to_owned(), x0=0.1, v0=0.0,
    rtol=1e-10, drive_frequency=None, sample_rate=None, samples_per_period=None, samples=None,
    duration=None, transient_periods=None, phase=0.0, time_origin="drive".to_owned(), counts=None,
    raw_counts=false, zero_offset=None, bit_errors=None, angle_range=None, noise=None, seed=0,
    unwrapped=false, gaps=None
))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    system: String,
    f: Option<f64>,
    c: Option<f64>,
    r: Option<f64>,
    a: Option<f64>,
    b: Option<f64>,
    forcing: String,
    x0: f64,
    v0: f64,
    rtol: f64,
    drive_frequency: Option<f64>,
    sample_rate: Option<f64>,
    samples_per_period: Option<usize>,
    samples: Option<usize>,
    duration: Option<f64>,
    transient_periods: Option<usize>,
    phase: f64,
    time_origin: String,
    counts: Option<u32>,
    raw_counts: bool,
    zero_offset: Option<f64>,
    bit_errors: Option<f64>,
    angle_range: Option<String>,
    noise: Option<f64>,
    seed: u64,
    unwrapped: bool,
    gaps: Option<(usize, usize)>,
) -> PyResult<Bound<'py, PyDict>> {
    let rig = Rig {
        system,
        f,
        c,
        r,
        a,
        b,
        forcing,
        x0,
        v0,
        rtol,
        drive_frequency,
        sample_rate,
        samples_per_period,
        samples,
        duration,
        transient_periods,
        phase,
        time_origin,
        counts,
        raw_counts,
        zero_offset,
        bit_errors,
        angle_range,
        noise,
        seed,
        unwrapped,
        gaps,
    };
    let out = py.detach(|| run_rig(&rig)).map_err(crate::raise)?;
    let dict = PyDict::new(py);
    dict.set_item("columns", out.columns.to_vec())?;
    dict.set_item("truth", out.truth)?;
    dict.set_item("forcing_period", out.forcing_period)?;
    dict.set_item("sample_step", out.sample_step)?;
    dict.set_item("t", PyArray1::from_vec(py, out.t))?;
    dict.set_item("x", PyArray1::from_vec(py, out.x))?;
    dict.set_item("v", PyArray1::from_vec(py, out.v))?;
    Ok(dict)
}

/// Simulates the record of `rig`.
pub fn run_rig(rig: &Rig) -> Result<Simulated, Failure> {
    let system = rig.system()?;
    let (frame, config, first_sample, first_phase) = rig.timing()?;
    let encoder = rig.encoder()?;
    let gaps = match rig.gaps {
        Some((k, len)) => Some(Gaps::new(k, len).map_err(sim("gaps"))?.seeded(rig.seed)),
        None => None,
    };
    let samples = config.samples();
    let kept = match &gaps {
        Some(g) => Some(g.kept(samples).map_err(sim("gaps"))?),
        None => None,
    };
    let in_seconds = rig.drive_frequency.is_some();
    let traj = match (system, in_seconds) {
        (System::Pendulum(p), false) => run(&p, &config)?,
        (System::Pendulum(p), true) => run(&InFrame::new(p, frame), &config)?,
        (System::Duffing(d), false) => run(&d, &config)?,
        (System::Duffing(d), true) => run(&InFrame::new(d, frame), &config)?,
    };
    let x: Vec<f64> = match (system, encoder) {
        (System::Pendulum(_), None) if rig.unwrapped => traj.theta.clone(),
        (System::Pendulum(_), None) => traj.theta.iter().map(|&x| circle_signal::wrap(x)).collect(),
        (System::Pendulum(_), Some(e)) if rig.raw_counts => e
            .observe_counts(&traj.theta)
            .ok_or_else(|| bad("raw_counts needs counts"))?
            .into_iter()
            .map(f64::from)
            .collect(),
        (System::Pendulum(_), Some(e)) if rig.unwrapped => e.observe_continuous(&traj.theta),
        (System::Pendulum(_), Some(e)) => e.observe(&traj.theta),
        (System::Duffing(_), None) => traj.theta.clone(),
        (System::Duffing(_), Some(e)) => e.observe_continuous(&traj.theta),
    };
    let h = config.sample_step();
    let stamps: Vec<f64> = if first_sample {
        (0..traj.len()).map(|n| n as f64 * h).collect()
    } else {
        traj.t.clone()
    };
    let columns = match system {
        System::Duffing(_) => ["t", "x", "v"],
        System::Pendulum(_) if rig.raw_counts => ["t", "count", "omega"],
        System::Pendulum(_) => ["t", "theta", "omega"],
    };
    let keep = |n: &usize| kept.as_ref().is_none_or(|k| k[*n]);
    let pick = |values: &[f64]| -> Vec<f64> { (0..samples).filter(keep).map(|n| values[n]).collect() };
    let truth = truth(system, frame, first_sample, first_phase, encoder)?;
    Ok(Simulated {
        t: pick(&stamps),
        x: pick(&x),
        v: pick(&traj.omega),
        columns,
        truth,
        forcing_period: config.forcing_period(),
        sample_step: h,
    })
}

/// The equation the record satisfies, in the identification's form and term names and the
/// record's time unit (what `hbid simulate --truth` writes as its coefficients).
fn truth(
    system: System,
    frame: RecordFrame,
    first_sample: bool,
    first_phase: f64,
    encoder: Option<Encoder>,
) -> Result<Vec<(String, f64)>, Failure> {
    let offset = encoder.map_or(0.0, |e| e.zero_offset());
    let at_zero = if first_sample { first_phase } else { 0.0 };
    let frame = frame
        .with_phase(at_zero)
        .and_then(|f| f.with_offset(offset))
        .map_err(fail(Kind::Simulation))?;
    let basis_error = fail(Kind::Simulation);
    let (known, layout) = match system {
        System::Pendulum(p) => (
            p.coefficients(&frame).map_err(fail(Kind::Simulation))?,
            hb_solve::term_names(&Harmonic::new(1).map_err(basis_error)?, &ModelForm::parametric()),
        ),
        System::Duffing(d) => (
            d.coefficients(&frame).map_err(fail(Kind::Simulation))?,
            hb_solve::term_names(
                &Polynomial::new(3).map_err(basis_error)?,
                &ModelForm::parametric().with_forcing(Forcing::Identified),
            ),
        ),
    };
    Ok(layout
        .into_iter()
        .map(|name| {
            let value = known.iter().find(|(n, _)| *n == name).map_or(0.0, |(_, v)| *v);
            (name, value)
        })
        .collect())
}

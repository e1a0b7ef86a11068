//! `hbid simulate`: a forced oscillator sampled as a rig records it.
//!
//! The simulation, the time frame and every encoder effect are `pendulum_sim`'s
//! ([`InFrame`], [`Encoder`], [`Gaps`]); this module only composes them from the options, checks
//! the combinations and writes the record and the truth.

use std::f64::consts::TAU;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use hb_basis::{Harmonic, Polynomial};
use hb_solve::{Forcing, ModelForm};
use npyz::WriterBuilder;
use pendulum_sim::observe::{AngleRange, Encoder, Gaps};
use pendulum_sim::{
    DriveHarmonic, DriveHarmonics, Duffing, InFrame, Losses, Pendulum, RecordFrame, SecondOrderSystem,
    SimulationConfig, Tolerances, Trajectory, TrueCoefficients, simulate_with_progress,
};
use serde::Serialize;

use crate::progress::Progress;

/// The simulated system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SystemArg {
    /// The base-excited pendulum x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0 (columns t,theta,omega).
    Pendulum,
    /// The two-well Duffing oscillator x'' + c x' + a x + b x³ = f cos(t) (columns t,x,v; never wrapped).
    Duffing,
}

/// Whether the system is driven.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DriveArg {
    /// Driven with amplitude --f.
    Drive,
    /// A free decay: f = 0.
    None,
}

/// The interval of a wrapped angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RangeArg {
    /// [−π, π).
    Signed,
    /// [0, 2π).
    Positive,
}

/// Where the time stamps count from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TimeOriginArg {
    /// The drive's phase zero at the start of the integration: the drive is sin(2π f_drive t) (or
    /// sin(t)) at the written stamps, whatever --phase.
    Drive,
    /// The first sample, as a data acquisition's clock: stamps n·h from 0, and the drive has the
    /// phase --phase at t = 0.
    FirstSample,
}

const SYSTEM: &str = "System";
const TIME: &str = "Time and sampling";
const ENCODER: &str = "Encoder (pendulum only)";
const NOISE: &str = "Noise and seed";
const OUTPUT: &str = "Output";

/// Options of `hbid simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The system.
    #[arg(long, value_enum, default_value_t = SystemArg::Pendulum, help_heading = SYSTEM)]
    system: SystemArg,
    /// Forcing amplitude f [default: 1.52 for the pendulum, 0.3 for the Duffing oscillator].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    f: Option<f64>,
    /// Damping c [default: 0.03 for the pendulum, 0.25 for the Duffing oscillator].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    c: Option<f64>,
    /// Pendulum: frequency ratio r (the stiffness is 1/r²) [default: 0.8333].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    r: Option<f64>,
    /// Duffing: linear stiffness a (negative for two wells) [default: -1].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    a: Option<f64>,
    /// Duffing: cubic stiffness b [default: 1].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    b: Option<f64>,
    /// Dry (Coulomb) friction μ: the term μ sign(x') in the model's time (at rest the body sticks
    /// while the other forces stay within μ).
    #[arg(long, value_name = "MU", allow_hyphen_values = true, help_heading = SYSTEM)]
    friction: Option<f64>,
    /// Quadratic (air) drag d: the term d x'|x'| in the model's time.
    #[arg(long, value_name = "D", allow_hyphen_values = true, help_heading = SYSTEM)]
    drag: Option<f64>,
    /// Cubic damping c3: the term c3 x'^3 in the model's time.
    #[arg(long, value_name = "C", allow_hyphen_values = true, help_heading = SYSTEM)]
    cubic_damping: Option<f64>,
    /// A harmonic of the drive, K:RATIO[:PHASE] (repeatable): harmonic K (2 to 16) with amplitude
    /// RATIO times f and phase PHASE radians [default: 0], added to the pendulum's base acceleration
    /// sin(t) as RATIO sin(K t + PHASE), or to the Duffing forcing cos(t) as RATIO cos(K t + PHASE).
    #[arg(long, value_name = "K:RATIO[:PHASE]", help_heading = SYSTEM)]
    drive_harmonic: Vec<String>,
    /// `drive`, or `none` for a free decay (f = 0; the time unit stays the one --drive-frequency sets).
    #[arg(long, value_enum, default_value_t = DriveArg::Drive, help_heading = SYSTEM)]
    forcing: DriveArg,
    /// Initial angle (or displacement) at the start of the integration.
    #[arg(long, visible_alias = "x0", default_value_t = 0.1, allow_hyphen_values = true, help_heading = SYSTEM)]
    theta0: f64,
    /// Initial velocity at the start of the integration, in the record's time unit.
    #[arg(long, visible_alias = "v0", default_value_t = 0.0, allow_hyphen_values = true, help_heading = SYSTEM)]
    omega0: f64,
    /// Relative tolerance of the integrator (the absolute one is rtol/10).
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true, help_heading = SYSTEM)]
    rtol: f64,

    /// Drive frequency in Hz: time in seconds, the model's time τ = 2π·f_drive·t, velocities in per
    /// second. Without it, time is the model's own (drive period 2π).
    #[arg(long, value_name = "HZ", allow_hyphen_values = true, help_heading = TIME)]
    drive_frequency: Option<f64>,
    /// Sample rate in Hz, any ratio to the drive (needs --drive-frequency; instead of
    /// --samples-per-period).
    #[arg(long, value_name = "HZ", allow_hyphen_values = true, help_heading = TIME)]
    sample_rate: Option<f64>,
    /// Samples per forcing period, a whole number [default: 25].
    #[arg(long, help_heading = TIME)]
    samples_per_period: Option<usize>,
    /// Samples written, before --gaps removes any [default: 30000].
    #[arg(long, help_heading = TIME)]
    samples: Option<usize>,
    /// Length of the record in its time unit instead of --samples: duration/step samples, rounded down.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, help_heading = TIME)]
    duration: Option<f64>,
    /// Forcing periods integrated and dropped before the first sample [default: 200; 0 with --forcing none].
    #[arg(long, help_heading = TIME)]
    transient_periods: Option<usize>,
    /// Drive phase (radians) of the first sample: the first sample is that far into a drive period.
    #[arg(long, value_name = "RAD", default_value_t = 0.0, allow_hyphen_values = true, help_heading = TIME)]
    phase: f64,
    /// Where the time stamps count from.
    #[arg(long, value_enum, default_value_t = TimeOriginArg::Drive, help_heading = TIME)]
    time_origin: TimeOriginArg,

    /// Encoder counts per revolution: the angle is reported to the nearest count, count·2π/N.
    #[arg(long, value_name = "N", help_heading = ENCODER)]
    counts: Option<u32>,
    /// Write the integer counts in [0, N) instead of radians (column `count`; needs --counts).
    #[arg(long, help_heading = ENCODER)]
    raw_counts: bool,
    /// The encoder's zero is this far (radians) from the bottom: it reports θ − offset.
    #[arg(long, value_name = "RAD", allow_hyphen_values = true, help_heading = ENCODER)]
    zero_offset: Option<f64>,
    /// Probability per sample of a bit error: a spike of ±2^k counts, k drawn from {6, 7, 8, 9}, sign
    /// either way (needs --counts of at least 1024; seeded by --seed).
    #[arg(long, value_name = "RATE", allow_hyphen_values = true, help_heading = ENCODER)]
    bit_errors: Option<f64>,
    /// Interval of the wrapped angle: signed [-π, π) or positive [0, 2π) [default: signed].
    #[arg(long, value_enum, help_heading = ENCODER)]
    angle_range: Option<RangeArg>,
    /// Standard deviation of Gaussian noise on the angle (radians) or displacement, before the
    /// counts; the velocity stays clean.
    #[arg(long, value_name = "SIGMA", allow_hyphen_values = true, help_heading = NOISE)]
    noise: Option<f64>,
    /// Seed of the noise, the bit errors and the gaps (ChaCha8).
    #[arg(long, default_value_t = 0, help_heading = NOISE)]
    seed: u64,
    /// Write the continuous angle instead of wrapping it (with --counts: the multi-turn count·2π/N).
    #[arg(long, help_heading = OUTPUT)]
    unwrapped: bool,

    /// Drop K runs of LEN consecutive samples at seeded random places (never the first or last
    /// sample; runs never touch): K:LEN, e.g. 3:50.
    #[arg(long, value_name = "K:LEN", help_heading = OUTPUT)]
    gaps: Option<String>,
    /// Print the time stamps with N decimals (as a data acquisition does).
    #[arg(long, value_name = "N", help_heading = OUTPUT)]
    time_decimals: Option<usize>,
    /// Print the angle (or displacement) and velocity with N decimals (counts stay whole).
    #[arg(long, value_name = "N", help_heading = OUTPUT)]
    decimals: Option<usize>,
    /// Also write the true equation as JSON: its coefficients in the identification's form and
    /// the record's time unit, with the drive, sampling and encoder settings.
    #[arg(long, value_name = "FILE.json", help_heading = OUTPUT)]
    truth: Option<PathBuf>,
    /// Also write the drive p(t) as a fourth column `p`: the forcing as it enters the equation, in
    /// the record's time unit (the pendulum's f·a(t), a(t) its base acceleration with its
    /// harmonics, the factor of cos x; the Duffing oscillator's f·(cos t + harmonics)), so that
    /// its term (`p*cos(x)` of the pendulum, `p` of the Duffing oscillator) has the coefficient
    /// −1: the measured drive of `hbid identify --forcing-col p`. Printed like the angle.
    #[arg(long, help_heading = OUTPUT)]
    write_drive: bool,
    /// Output file: `.npy` (samples × 3, or × 4 with --write-drive; f8, the numbers the CSV would
    /// hold) or CSV (anything else).
    #[arg(long, help_heading = OUTPUT)]
    out: PathBuf,
}

/// Decimals beyond which printing gains nothing an f64 holds.
const MAX_DECIMALS: usize = 30;

/// The system chosen, with its parameters checked.
#[derive(Debug, Clone, Copy)]
enum System {
    Pendulum(Pendulum),
    Duffing(Duffing),
}

impl System {
    fn from_args(args: &SimulateArgs) -> anyhow::Result<Self> {
        if args.forcing == DriveArg::None && args.f.is_some() {
            bail!("--f is the drive's amplitude: not with --forcing none");
        }
        let drive = |default: f64| match args.forcing {
            DriveArg::Drive => args.f.unwrap_or(default),
            DriveArg::None => 0.0,
        };
        let losses = losses(args)?;
        let harmonics = drive_harmonics(args)?;
        Ok(match args.system {
            SystemArg::Pendulum => {
                if args.a.is_some() || args.b.is_some() {
                    bail!("--a and --b are the Duffing oscillator's stiffnesses (--system duffing)");
                }
                let (f, c, r) = Pendulum::PAPER;
                Self::Pendulum(
                    Pendulum::new(drive(f), args.c.unwrap_or(c), args.r.unwrap_or(r))?
                        .with_losses(losses)
                        .with_drive_harmonics(harmonics),
                )
            }
            SystemArg::Duffing => {
                if args.r.is_some() {
                    bail!("--r is the pendulum's frequency ratio (--system pendulum)");
                }
                let encoder_options = [
                    ("--counts", args.counts.is_some()),
                    ("--raw-counts", args.raw_counts),
                    ("--zero-offset", args.zero_offset.is_some()),
                    ("--bit-errors", args.bit_errors.is_some()),
                    ("--angle-range", args.angle_range.is_some()),
                ];
                if let Some((flag, _)) = encoder_options.iter().find(|(_, set)| *set) {
                    bail!(
                        "{flag} is an angle encoder's: --system pendulum only (the Duffing displacement takes --noise)"
                    );
                }
                let (c, a, b, f) = Duffing::TWO_WELL;
                Self::Duffing(
                    Duffing::new(
                        args.c.unwrap_or(c),
                        args.a.unwrap_or(a),
                        args.b.unwrap_or(b),
                        drive(f),
                    )?
                    .with_losses(losses)
                    .with_drive_harmonics(harmonics),
                )
            }
        })
    }

    fn name(&self) -> &'static str {
        match self {
            Self::Pendulum(_) => "pendulum",
            Self::Duffing(_) => "duffing",
        }
    }

    /// The equation in the model's own time, with the rig's terms that are present.
    fn equation(&self) -> String {
        let (losses, harmonics) = match self {
            Self::Pendulum(p) => (*p.losses(), *p.drive_harmonics()),
            Self::Duffing(d) => (*d.losses(), *d.drive_harmonics()),
        };
        let mut dissipation = String::from("c x'");
        for (present, term) in [
            (losses.friction() != 0.0, " + mu sign(x')"),
            (losses.drag() != 0.0, " + d x'|x'|"),
            (losses.cubic_damping() != 0.0, " + c3 x'^3"),
        ] {
            if present {
                dissipation.push_str(term);
            }
        }
        let with_harmonics = !harmonics.is_none();
        match (self, with_harmonics) {
            (Self::Pendulum(_), false) => format!("x'' + {dissipation} + (1/r^2) sin x - f sin(t) cos x = 0"),
            (Self::Pendulum(_), true) => format!(
                "x'' + {dissipation} + (1/r^2) sin x - f [sin(t) + sum_k ratio_k sin(k t + phase_k)] cos x = 0"
            ),
            (Self::Duffing(_), false) => format!("x'' + {dissipation} + a x + b x^3 = f cos(t)"),
            (Self::Duffing(_), true) => {
                format!("x'' + {dissipation} + a x + b x^3 = f [cos(t) + sum_k ratio_k cos(k t + phase_k)]")
            }
        }
    }
}

/// The losses of the options, each checked.
fn losses(args: &SimulateArgs) -> anyhow::Result<Losses> {
    let mut losses = Losses::none();
    if let Some(mu) = args.friction {
        losses = losses.with_friction(mu).context("--friction")?;
    }
    if let Some(d) = args.drag {
        losses = losses.with_drag(d).context("--drag")?;
    }
    if let Some(c3) = args.cubic_damping {
        losses = losses.with_cubic_damping(c3).context("--cubic-damping")?;
    }
    Ok(losses)
}

/// The harmonics of the drive, from every `--drive-harmonic K:RATIO[:PHASE]`.
fn drive_harmonics(args: &SimulateArgs) -> anyhow::Result<DriveHarmonics> {
    if args.forcing == DriveArg::None && !args.drive_harmonic.is_empty() {
        bail!("--drive-harmonic is a harmonic of the drive: not with --forcing none");
    }
    let list = args
        .drive_harmonic
        .iter()
        .map(|text| parse_harmonic(text))
        .collect::<anyhow::Result<Vec<_>>>()?;
    DriveHarmonics::new(&list).context("--drive-harmonic")
}

/// `K:RATIO[:PHASE]`.
fn parse_harmonic(text: &str) -> anyhow::Result<DriveHarmonic> {
    let parts: Vec<&str> = text.split(':').map(str::trim).collect();
    if !(2..=3).contains(&parts.len()) {
        bail!("--drive-harmonic '{text}': expected K:RATIO[:PHASE], e.g. 2:0.1 or 3:0.05:1.2");
    }
    let k = parts[0]
        .parse::<u32>()
        .map_err(|_| anyhow::anyhow!("--drive-harmonic '{text}': '{}' is not a whole number", parts[0]))?;
    let number = |s: &str| {
        s.parse::<f64>()
            .map_err(|_| anyhow::anyhow!("--drive-harmonic '{text}': '{s}' is not a number"))
    };
    let ratio = number(parts[1])?;
    let phase = match parts.get(2) {
        Some(p) => number(p)?,
        None => 0.0,
    };
    DriveHarmonic::new(k, ratio, phase).with_context(|| format!("--drive-harmonic '{text}'"))
}

/// The record's time: its frame relative to the model's, and the sampling.
#[derive(Debug, Clone)]
struct Timing {
    /// `None` for the model's own time.
    drive_frequency: Option<f64>,
    /// `τ = rate · t` during the simulation.
    frame: RecordFrame,
    config: SimulationConfig,
    /// The drive's phase at the first sample, radians in `[0, 2π)`.
    first_phase: f64,
}

impl Timing {
    fn from_args(args: &SimulateArgs) -> anyhow::Result<Self> {
        let frame = match args.drive_frequency {
            None => RecordFrame::nondimensional(),
            Some(hz) => RecordFrame::nondimensional()
                .with_drive_frequency(hz)
                .context("--drive-frequency")?,
        };
        let period = match args.drive_frequency {
            None => TAU,
            Some(hz) => 1.0 / hz,
        };
        let mut config = SimulationConfig::paper();
        if args.drive_frequency.is_some() {
            config = config.with_forcing_period(period).context("--drive-frequency")?;
        }
        match (args.sample_rate, args.samples_per_period) {
            (Some(_), Some(_)) => bail!("--sample-rate and --samples-per-period both set: give one"),
            (Some(_), None) if args.drive_frequency.is_none() => {
                bail!("--sample-rate needs --drive-frequency (time in seconds)")
            }
            (Some(rate), None) => {
                if !(rate.is_finite() && rate > 0.0) {
                    bail!("--sample-rate {rate}: must be positive and finite");
                }
                config = config
                    .with_sample_step(1.0 / rate)
                    .with_context(|| format!("--sample-rate {rate}"))?;
            }
            (None, Some(p)) => config = config.with_samples_per_period(p)?,
            (None, None) => {}
        }
        let step = config.sample_step();
        let samples = match (args.samples, args.duration) {
            (Some(_), Some(_)) => bail!("--samples and --duration both set: give one"),
            (Some(n), None) => n,
            (None, Some(d)) => samples_in(d, step)?,
            (None, None) => config.samples(),
        };
        let transient = args.transient_periods.unwrap_or(match args.forcing {
            DriveArg::Drive => config.transient_periods(),
            DriveArg::None => 0,
        });
        if !args.phase.is_finite() {
            bail!("--phase {}: must be finite", args.phase);
        }
        let mut fraction = args.phase.rem_euclid(TAU) / TAU;
        if fraction >= 1.0 {
            fraction = 0.0;
        }
        let config = config
            .with_samples(samples)?
            .with_transient_periods(transient)
            .with_initial(args.theta0, args.omega0)?
            .with_phase(fraction)?
            .with_tolerances(Tolerances::relative(args.rtol)?);
        Ok(Self {
            drive_frequency: args.drive_frequency,
            frame,
            config,
            first_phase: TAU * fraction,
        })
    }

    /// The time stamps to write.
    fn stamps(&self, traj: &Trajectory, origin: TimeOriginArg) -> Vec<f64> {
        match origin {
            TimeOriginArg::Drive => traj.t.clone(),
            TimeOriginArg::FirstSample => {
                let h = self.config.sample_step();
                (0..traj.len()).map(|n| n as f64 * h).collect()
            }
        }
    }
}

/// The samples in `duration` at step `step`: `duration / step` rounded down, a ratio within
/// 1e-9 of a whole number taken as that number (60 s at 500 Hz is 30000 samples).
fn samples_in(duration: f64, step: f64) -> anyhow::Result<usize> {
    if !(duration.is_finite() && duration > 0.0) {
        bail!("--duration {duration}: must be positive and finite");
    }
    let ratio = duration / step;
    let whole = ratio.round();
    let n = if (ratio - whole).abs() <= 1e-9 * ratio.max(1.0) {
        whole
    } else {
        ratio.floor()
    };
    if n < 1.0 {
        bail!("--duration {duration} is shorter than one sample step ({step})");
    }
    if n > usize::MAX as f64 {
        bail!("--duration {duration}: too many samples");
    }
    Ok(n as usize)
}

/// `K:LEN`.
fn parse_gaps(text: &str) -> anyhow::Result<Gaps> {
    let (k, len) = text
        .split_once(':')
        .ok_or_else(|| anyhow::anyhow!("--gaps '{text}': expected K:LEN, e.g. 3:50"))?;
    let number = |s: &str| {
        s.trim()
            .parse::<usize>()
            .map_err(|_| anyhow::anyhow!("--gaps '{text}': '{s}' is not a whole number"))
    };
    Gaps::new(number(k)?, number(len)?).with_context(|| format!("--gaps '{text}'"))
}

/// The encoder of the options, `None` for an ideal one (the angle is then only wrapped).
fn encoder(args: &SimulateArgs) -> anyhow::Result<Option<Encoder>> {
    if args.raw_counts && args.counts.is_none() {
        bail!("--raw-counts needs --counts");
    }
    if args.bit_errors.is_some() && args.counts.is_none() {
        bail!("--bit-errors needs --counts (bit errors are errors of the count)");
    }
    if args.unwrapped && args.raw_counts {
        bail!("--raw-counts writes counts in [0, N): not with --unwrapped");
    }
    if args.angle_range.is_some() && (args.unwrapped || args.raw_counts) {
        bail!("--angle-range is where a wrapped angle lies: not with --unwrapped or --raw-counts");
    }
    let any = args.noise.is_some()
        || args.counts.is_some()
        || args.zero_offset.is_some()
        || args.bit_errors.is_some()
        || args.angle_range.is_some();
    if !any {
        return Ok(None);
    }
    let mut e = Encoder::seeded(args.seed);
    if let Some(sigma) = args.noise {
        e = e.with_noise(sigma).context("--noise")?;
    }
    if let Some(n) = args.counts {
        e = e.with_counts(n).context("--counts")?;
    }
    if let Some(offset) = args.zero_offset {
        e = e.with_zero_offset(offset).context("--zero-offset")?;
    }
    if let Some(rate) = args.bit_errors {
        e = e.with_bit_errors(rate).context("--bit-errors")?;
    }
    if args.angle_range == Some(RangeArg::Positive) {
        e = e.with_range(AngleRange::Positive);
    }
    Ok(Some(e))
}

fn check_decimals(flag: &str, decimals: Option<usize>) -> anyhow::Result<()> {
    match decimals {
        Some(n) if n > MAX_DECIMALS => bail!("--{flag} {n}: at most {MAX_DECIMALS}"),
        _ => Ok(()),
    }
}

/// A folder that exists and no folder in the file's place.
fn check_truth_path(path: &Path, out: &Path) -> anyhow::Result<()> {
    if path == out {
        bail!("--truth and --out name the same file");
    }
    if path.is_dir() {
        bail!("--truth {} is a folder; give a file name", path.display());
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        bail!("the folder {} of --truth does not exist", parent.display());
    }
    Ok(())
}

/// The angle (or displacement) column as written.
enum Reported {
    Values(Vec<f64>),
    Counts(Vec<u32>),
}

pub fn run(args: &SimulateArgs, quiet: bool) -> anyhow::Result<()> {
    let system = System::from_args(args)?;
    let timing = Timing::from_args(args)?;
    let encoder = encoder(args)?;
    let gaps = args
        .gaps
        .as_deref()
        .map(|g| parse_gaps(g).map(|g| g.seeded(args.seed)))
        .transpose()?;
    check_decimals("decimals", args.decimals)?;
    check_decimals("time-decimals", args.time_decimals)?;
    let step = timing.config.sample_step();
    if let Some(n) = args.time_decimals {
        // Stamps rounded to n decimals keep increasing only if the step is at least 10^-n.
        let resolution = 10f64.powi(-i32::try_from(n)?);
        if step < resolution * (1.0 - 1e-9) {
            bail!("--time-decimals {n} cannot tell apart samples {step} apart");
        }
    }
    let samples = timing.config.samples();
    let kept = match &gaps {
        Some(g) => Some(g.kept(samples).context("--gaps")?),
        None => None,
    };
    crate::output::check_output_path(&args.out)?;
    if let Some(truth) = &args.truth {
        check_truth_path(truth, &args.out)?;
    }

    let bar = Progress::new("simulate", samples as u64, quiet);
    let traj = match (system, timing.drive_frequency) {
        (System::Pendulum(p), None) => run_sim(&p, &timing.config, &bar)?,
        (System::Pendulum(p), Some(_)) => run_sim(&InFrame::new(p, timing.frame), &timing.config, &bar)?,
        (System::Duffing(d), None) => run_sim(&d, &timing.config, &bar)?,
        (System::Duffing(d), Some(_)) => run_sim(&InFrame::new(d, timing.frame), &timing.config, &bar)?,
    };
    bar.finish();

    let reported = match (system, encoder) {
        (System::Pendulum(_), None) if args.unwrapped => Reported::Values(traj.theta.clone()),
        (System::Pendulum(_), None) => {
            Reported::Values(traj.theta.iter().map(|&x| circle_signal::wrap(x)).collect())
        }
        (System::Pendulum(_), Some(e)) if args.raw_counts => Reported::Counts(
            e.observe_counts(&traj.theta)
                .context("--raw-counts needs --counts")?,
        ),
        (System::Pendulum(_), Some(e)) if args.unwrapped => {
            Reported::Values(e.observe_continuous(&traj.theta))
        }
        (System::Pendulum(_), Some(e)) => Reported::Values(e.observe(&traj.theta)),
        (System::Duffing(_), None) => Reported::Values(traj.theta.clone()),
        (System::Duffing(_), Some(e)) => Reported::Values(e.observe_continuous(&traj.theta)),
    };
    let stamps = timing.stamps(&traj, args.time_origin);
    let drive = args.write_drive.then(|| {
        // The drive in the record's frame: rate² times the system's, at the system's time.
        let (frame, rate) = (timing.frame, timing.frame.rate());
        traj.t
            .iter()
            .map(|&t| {
                let tau = frame.system_time(t);
                rate * rate
                    * match system {
                        System::Pendulum(p) => p.drive(tau),
                        System::Duffing(d) => d.drive(tau),
                    }
            })
            .collect::<Vec<f64>>()
    });
    let columns: [&'static str; 3] = match (system, &reported) {
        (System::Duffing(_), _) => ["t", "x", "v"],
        (System::Pendulum(_), Reported::Counts(_)) => ["t", "count", "omega"],
        (System::Pendulum(_), Reported::Values(_)) => ["t", "theta", "omega"],
    };
    let keep = |n: usize| kept.as_ref().is_none_or(|k| k[n]);
    let rows = (0..samples).filter(|&n| keep(n)).count();
    let columns_written: Vec<&'static str> = columns
        .iter()
        .copied()
        .chain(drive.is_some().then_some("p"))
        .collect();
    let record = Written {
        columns: &columns_written,
        stamps: &stamps,
        reported: &reported,
        velocity: &traj.omega,
        drive: drive.as_deref(),
    };
    write_record(args, &record, &keep, rows)?;

    if let Some(path) = &args.truth {
        let truth = truth(args, system, &timing, encoder, gaps, rows, columns_written)?;
        let text = serde_json::to_string_pretty(&truth)?;
        crate::output::write_atomically(path, |w: &mut dyn Write| writeln!(w, "{text}"))
            .context("--truth")?;
    }
    Ok(())
}

fn run_sim<S: SecondOrderSystem>(
    system: &S,
    config: &SimulationConfig,
    bar: &Progress,
) -> anyhow::Result<Trajectory> {
    Ok(simulate_with_progress(system, config, |done, _| {
        bar.set(done as u64)
    })?)
}

/// `v` printed with `decimals`, or in the shortest form that reads back as `v`.
fn text(v: f64, decimals: Option<usize>) -> String {
    match decimals {
        Some(d) => format!("{v:.d$}"),
        None => v.to_string(),
    }
}

/// `v` as a reader of its printed form gets it.
fn printed(v: f64, decimals: Option<usize>) -> f64 {
    match decimals {
        Some(d) => format!("{v:.d$}").parse().unwrap_or(v),
        None => v,
    }
}

/// The columns of a simulated record, as written.
struct Written<'a> {
    /// Their names: time, value, velocity, and `p` with a drive.
    columns: &'a [&'a str],
    stamps: &'a [f64],
    reported: &'a Reported,
    velocity: &'a [f64],
    /// The drive, with --write-drive.
    drive: Option<&'a [f64]>,
}

fn write_record(
    args: &SimulateArgs,
    record: &Written<'_>,
    keep: &dyn Fn(usize) -> bool,
    rows: usize,
) -> anyhow::Result<()> {
    let Written {
        columns,
        stamps,
        reported,
        velocity,
        drive,
    } = *record;
    let npy = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    let (td, vd) = (args.time_decimals, args.decimals);
    if npy {
        return crate::output::write_atomically(&args.out, |w: &mut dyn Write| {
            let mut writer = npyz::WriteOptions::<f64>::new()
                .default_dtype()
                .shape(&[rows as u64, columns.len() as u64])
                .writer(w)
                .begin_nd()?;
            for n in (0..stamps.len()).filter(|&n| keep(n)) {
                let x = match reported {
                    Reported::Values(x) => printed(x[n], vd),
                    Reported::Counts(k) => f64::from(k[n]),
                };
                writer.extend([printed(stamps[n], td), x, printed(velocity[n], vd)])?;
                if let Some(p) = drive {
                    writer.push(&printed(p[n], vd))?;
                }
            }
            writer.finish()
        })
        .map_err(Into::into);
    }
    crate::output::write_atomically(&args.out, |w: &mut dyn Write| {
        writeln!(w, "{}", columns.join(","))?;
        for n in (0..stamps.len()).filter(|&n| keep(n)) {
            let x = match reported {
                Reported::Values(x) => text(x[n], vd),
                Reported::Counts(k) => k[n].to_string(),
            };
            write!(w, "{},{x},{}", text(stamps[n], td), text(velocity[n], vd))?;
            match drive {
                Some(p) => writeln!(w, ",{}", text(p[n], vd))?,
                None => writeln!(w)?,
            }
        }
        Ok(())
    })
    .map_err(Into::into)
}

/// Coefficients as a JSON object in the identification's column order.
#[derive(Debug)]
struct Ordered(Vec<(String, f64)>);

impl Serialize for Ordered {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

/// The truth file: the equation the record satisfies, in the identification's form.
#[derive(Debug, Serialize)]
struct Truth {
    format: &'static str,
    version: u32,
    system: &'static str,
    /// The equation in the model's own time, and its parameters.
    equation: String,
    parameters: serde_json::Value,
    forcing: &'static str,
    /// How `hbid identify` reads the record by default: signal, basis, forcing terms, column.
    identify: IdentifyHint,
    /// `x'' + Σ c_i g_i = 0` in the record's time unit and coordinate, every term of the layout.
    coefficients: Ordered,
    time_unit: &'static str,
    /// Hz, `None` for the model's own time.
    drive_frequency: Option<f64>,
    forcing_period: f64,
    /// `dτ/dt`: the drive's angular frequency in the record's time unit.
    time_scale: f64,
    /// The drive's phase (radians) at the record's `t = 0`: the drive term is `sin(W t + phase)`
    /// (pendulum) or `cos(W t + phase)` (Duffing).
    drive_phase_at_zero: f64,
    /// The drive's phase (radians) at the first sample.
    drive_phase_at_first_sample: f64,
    time_origin: &'static str,
    first_sample_time: f64,
    sample_step: f64,
    sample_rate: f64,
    samples_per_period: f64,
    samples_simulated: usize,
    rows: usize,
    columns: Vec<&'static str>,
    transient_periods: usize,
    initial: [f64; 2],
    noise_sigma: f64,
    encoder: Option<EncoderInfo>,
    gaps: Option<GapsInfo>,
    seed: u64,
    time_decimals: Option<usize>,
    decimals: Option<usize>,
}

#[derive(Debug, Serialize)]
struct IdentifyHint {
    signal: &'static str,
    basis: &'static str,
    forcing: &'static str,
    angle_column: &'static str,
    /// Terms of the true equation beyond the layout of `basis` and `forcing` (a rig's losses and
    /// drive harmonics), listed after it in `coefficients`.
    extra_terms: Vec<String>,
}

#[derive(Debug, Serialize)]
struct EncoderInfo {
    counts: Option<u32>,
    zero_offset: f64,
    bit_error_rate: f64,
    bit_error_bits: [u32; 4],
    angle_range: &'static str,
    raw_counts: bool,
    unwrapped: bool,
}

#[derive(Debug, Serialize)]
struct GapsInfo {
    count: usize,
    length: usize,
    /// First dropped sample of each gap, counted in the simulated samples.
    starts: Vec<usize>,
}

fn truth(
    args: &SimulateArgs,
    system: System,
    timing: &Timing,
    encoder: Option<Encoder>,
    gaps: Option<Gaps>,
    rows: usize,
    columns: Vec<&'static str>,
) -> anyhow::Result<Truth> {
    let offset = encoder.map_or(0.0, |e| e.zero_offset());
    let at_zero = match args.time_origin {
        TimeOriginArg::Drive => 0.0,
        TimeOriginArg::FirstSample => timing.first_phase,
    };
    let frame = timing.frame.with_phase(at_zero)?.with_offset(offset)?;
    let (known, layout, parameters, mut hint) = match system {
        System::Pendulum(p) => (
            p.coefficients(&frame)?,
            hb_solve::term_names(&Harmonic::new(1)?, &ModelForm::parametric()),
            serde_json::to_value(p)?,
            IdentifyHint {
                signal: "circle",
                basis: "harmonic:1",
                forcing: "none",
                angle_column: columns[1],
                extra_terms: Vec::new(),
            },
        ),
        System::Duffing(d) => (
            d.coefficients(&frame)?,
            hb_solve::term_names(
                &Polynomial::new(3)?,
                &ModelForm::parametric().with_forcing(Forcing::Identified),
            ),
            serde_json::to_value(d)?,
            IdentifyHint {
                signal: "line",
                basis: "poly:3",
                forcing: "identified",
                angle_column: columns[1],
                extra_terms: Vec::new(),
            },
        ),
    };
    // Every term of the layout, then the rig's terms beyond it in the order of the equation.
    let mut coefficients: Vec<(String, f64)> = layout
        .iter()
        .map(|name| {
            let value = known.iter().find(|(n, _)| n == name).map_or(0.0, |(_, v)| *v);
            (name.clone(), value)
        })
        .collect();
    for (name, value) in known.into_iter().filter(|(n, _)| !layout.contains(n)) {
        hint.extra_terms.push(name.clone());
        coefficients.push((name, value));
    }
    let config = &timing.config;
    let step = config.sample_step();
    let first_sample_time = match args.time_origin {
        TimeOriginArg::Drive => config.sample_time(0),
        TimeOriginArg::FirstSample => 0.0,
    };
    let range = match args.angle_range {
        Some(RangeArg::Positive) => "positive",
        _ => "signed",
    };
    let (sigma, encoder_info) = match system {
        System::Pendulum(_) => (
            encoder.map_or(0.0, |e| e.sigma()),
            Some(EncoderInfo {
                counts: encoder.and_then(|e| e.counts()),
                zero_offset: offset,
                bit_error_rate: encoder.map_or(0.0, |e| e.bit_error_rate()),
                bit_error_bits: Encoder::BIT_ERROR_BITS,
                angle_range: range,
                raw_counts: args.raw_counts,
                unwrapped: args.unwrapped,
            }),
        ),
        System::Duffing(_) => (encoder.map_or(0.0, |e| e.sigma()), None),
    };
    let gaps = match gaps {
        Some(g) => Some(GapsInfo {
            count: g.count(),
            length: g.length(),
            starts: g.starts(config.samples())?,
        }),
        None => None,
    };
    Ok(Truth {
        format: "hbid-truth",
        version: 1,
        system: system.name(),
        equation: system.equation(),
        parameters,
        forcing: match args.forcing {
            DriveArg::Drive => "drive",
            DriveArg::None => "none",
        },
        identify: hint,
        coefficients: Ordered(coefficients),
        time_unit: if timing.drive_frequency.is_some() {
            "s"
        } else {
            "nondimensional"
        },
        drive_frequency: timing.drive_frequency,
        forcing_period: config.forcing_period(),
        time_scale: timing.frame.rate(),
        drive_phase_at_zero: at_zero,
        drive_phase_at_first_sample: timing.first_phase,
        time_origin: match args.time_origin {
            TimeOriginArg::Drive => "drive",
            TimeOriginArg::FirstSample => "first-sample",
        },
        first_sample_time,
        sample_step: step,
        sample_rate: 1.0 / step,
        samples_per_period: config.forcing_period() / step,
        samples_simulated: config.samples(),
        rows,
        columns,
        transient_periods: config.transient_periods(),
        initial: config.initial(),
        noise_sigma: sigma,
        encoder: encoder_info,
        gaps,
        seed: args.seed,
        time_decimals: args.time_decimals,
        decimals: args.decimals,
    })
}

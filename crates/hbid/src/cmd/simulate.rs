//! `hbid simulate`: a forced oscillator sampled as a rig records it. The rig is the
//! application layer's ([`hb_pipeline::simulate`]); this module holds the arguments and writes
//! the files.

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use hb_pipeline::compare::Values;
use hb_pipeline::simulate::{
    DriveKind, GapsText, HarmonicText, Numbers, RangeKind, SystemKind, TimeOrigin, TorqueText, check_outputs,
    write_truth,
};
use hb_pipeline::{ColumnList, CompareOptions, CompareRequest, OptionError, Rig, SimulateOptions, Source};

use crate::progress::Console;

/// The simulated system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SystemArg {
    /// The base-excited pendulum x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0 (columns t,theta,omega).
    Pendulum,
    /// The two-well Duffing oscillator x'' + c x' + a x + b x³ = f cos(t) (columns t,x,v; never wrapped).
    Duffing,
    /// The double pendulum whose pivot is shaken horizontally like the pendulum's, whirling
    /// (columns t,theta1,theta2,omega1,omega2: the links' absolute angles; p with --write-drive).
    DoublePendulum,
    /// The double pendulum driven by a torque at each joint like a robot arm (DFKI's design A.0),
    /// time in seconds (columns t,q1,q2,v1,v2,tau1,tau2: q2 the elbow angle relative to link 1,
    /// the torques in N m).
    Arm,
    /// Two two-well Duffing oscillators coupled by a spring on a base shaken by a seeded
    /// synthetic acceleration (columns t,x1,x2,v1,v2,a: a the base's acceleration; never wrapped).
    CoupledDuffing,
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
const SYSTEMS: &str = "Systems of two coordinates";
const TIME: &str = "Time and sampling";
const ENCODER: &str = "Encoder (angles: each of a system's with its own stream of the seed)";
const NOISE: &str = "Noise and seed";
const OUTPUT: &str = "Output";
const MODEL: &str = "A saved model under a record's input";

/// Options of `hbid simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The system.
    #[arg(long, value_enum, default_value_t = SystemArg::Pendulum, help_heading = SYSTEM)]
    system: SystemArg,
    /// Forcing amplitude f [default: 1.52 for the pendulum, 0.3 for the Duffing oscillator, 0.6
    /// for the double pendulum (the pivot's acceleration is −f sin t)].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    f: Option<f64>,
    /// Damping c [default: 0.03 for the pendulum, 0.25 for the Duffing oscillator]; of link 1 or
    /// oscillator 1 of a system [default: 0.05 for the double pendulum, 0.25 for the coupled
    /// oscillators].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    c: Option<f64>,
    /// Pendulum: frequency ratio r (the stiffness is 1/r²) [default: 0.8333]; double pendulum:
    /// ω² = g/(l1 Ω²) = 1/r² [default: ω² = 0.8].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    r: Option<f64>,
    /// Duffing: linear stiffness a (negative for two wells) [default: -1]; a1 of the coupled
    /// oscillators [default: -1].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEM)]
    a: Option<f64>,
    /// Duffing: cubic stiffness b [default: 1]; b1 of the coupled oscillators [default: 1].
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
    /// RATIO times f and phase PHASE radians [default: 0], added to the pendulum's (or the double
    /// pendulum's) base acceleration sin(t) as RATIO sin(K t + PHASE), or to the Duffing forcing
    /// cos(t) as RATIO cos(K t + PHASE).
    #[arg(long, value_name = "K:RATIO[:PHASE]", help_heading = SYSTEM)]
    drive_harmonic: Vec<HarmonicText>,
    /// `drive`, or `none` for a free decay (f = 0; the time unit stays the one --drive-frequency sets).
    #[arg(long, value_enum, visible_alias = "forcing", default_value_t = DriveArg::Drive, help_heading = SYSTEM)]
    drive: DriveArg,
    /// Double pendulum and coupled oscillators: the damping c2 of link 2 or oscillator 2 [default:
    /// 0.05 for the double pendulum, 0.2 for the coupled oscillators].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEMS)]
    c2: Option<f64>,
    /// Double pendulum: the mass ratio μ = m2/(m1+m2), in [0, 1) [default: 0.5].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEMS)]
    mu: Option<f64>,
    /// Double pendulum: the length ratio λ = l2/l1 [default: 1].
    #[arg(long, value_name = "LAMBDA", allow_hyphen_values = true, help_heading = SYSTEMS)]
    length_ratio: Option<f64>,
    /// Arm: a sinusoidal torque at the shoulder, A:OMEGA[:PHASE] (repeatable, added): the torque
    /// A sin(OMEGA t + PHASE) in N m, OMEGA in rad/s, PHASE in rad [default: 0]; `none` for a
    /// passive joint [default: 0.4:10, DFKI's record 00].
    #[arg(long, value_name = "A:OMEGA[:PHASE]", allow_hyphen_values = true, help_heading = SYSTEMS)]
    torque1: Vec<TorqueText>,
    /// Arm: a sinusoidal torque at the elbow, as --torque1 [default: 0.8:10:1.5707963267948966,
    /// 0.8 cos 10t].
    #[arg(long, value_name = "A:OMEGA[:PHASE]", allow_hyphen_values = true, help_heading = SYSTEMS)]
    torque2: Vec<TorqueText>,
    /// Arm: the joints' viscous friction b1,b2 in N m s/rad [default: 0.001,0.001, published].
    #[arg(long, value_name = "B1,B2", allow_hyphen_values = true, help_heading = SYSTEMS)]
    joint_damping: Option<Numbers>,
    /// Arm: the joints' dry (Coulomb) friction cf1,cf2 in N m, cf sign(q') (a joint at rest sticks
    /// while the torque on it stays within cf) [default: 0.093,0.078, published; 0,0 for none].
    #[arg(long, value_name = "CF1,CF2", allow_hyphen_values = true, help_heading = SYSTEMS)]
    joint_friction: Option<Numbers>,
    /// Coupled oscillators: linear stiffness a2 of oscillator 2 [default: -0.8].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEMS)]
    a2: Option<f64>,
    /// Coupled oscillators: cubic stiffness b2 of oscillator 2 [default: 1.2].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEMS)]
    b2: Option<f64>,
    /// Coupled oscillators: the coupling spring's stiffness k, the force k (x1 − x2) [default: 0.3].
    #[arg(long, value_name = "K", allow_hyphen_values = true, help_heading = SYSTEMS)]
    coupling: Option<f64>,
    /// Coupled oscillators: the coupling spring's cubic part k3, the force k3 (x1 − x2)³
    /// [default: 0.05].
    #[arg(long, value_name = "K3", allow_hyphen_values = true, help_heading = SYSTEMS)]
    coupling_cubic: Option<f64>,
    /// Coupled oscillators: the mass ratio m2/m1 [default: 1].
    #[arg(long, allow_hyphen_values = true, help_heading = SYSTEMS)]
    mass_ratio: Option<f64>,
    /// Coupled oscillators: the seed of the base's acceleration, 0.3 sin t + 0.15 sin(√2 t + 1) +
    /// 0.1 sin(φ t + 2) plus band-limited noise of rms 0.03 (written as column a) [default: 1].
    #[arg(long, help_heading = SYSTEMS)]
    drive_seed: Option<u64>,
    /// A system's initial coordinates Q1,Q2 at the start of the integration [default: 2,0 for the
    /// double pendulum, 0,0 for the arm, 1,-0.9 for the coupled oscillators].
    #[arg(long, value_name = "Q1,Q2", allow_hyphen_values = true, help_heading = SYSTEMS)]
    q0: Option<Numbers>,
    /// A system's initial velocities V1,V2 in the record's time unit [default: 0,0].
    #[arg(long, value_name = "V1,V2", allow_hyphen_values = true, help_heading = SYSTEMS)]
    dq0: Option<Numbers>,

    /// Initial angle (or displacement) at the start of the integration.
    #[arg(long, visible_alias = "theta0", default_value_t = 0.1, allow_hyphen_values = true, help_heading = SYSTEM)]
    x0: f64,
    /// Initial velocity at the start of the integration, in the record's time unit.
    #[arg(long, visible_alias = "omega0", default_value_t = 0.0, allow_hyphen_values = true, help_heading = SYSTEM)]
    v0: f64,
    /// Relative tolerance of the integrator (the absolute one is rtol/10).
    #[arg(long, default_value_t = pendulum_sim::Tolerances::DEFAULT_RTOL, allow_hyphen_values = true, help_heading = SYSTEM)]
    rtol: f64,

    /// Drive frequency in Hz: time in seconds, the model's time τ = 2π·f_drive·t, velocities in per
    /// second (of the coupled oscillators: the frequency of the drive's first tone). Without it,
    /// time is the model's own (drive period 2π). The arm's time is seconds already.
    #[arg(long, value_name = "HZ", allow_hyphen_values = true, help_heading = TIME)]
    drive_frequency: Option<f64>,
    /// Sample rate in Hz, any ratio to the drive (needs --drive-frequency; instead of
    /// --samples-per-period); the arm's sampling [default: 500].
    #[arg(long, value_name = "HZ", allow_hyphen_values = true, help_heading = TIME)]
    sample_rate: Option<f64>,
    /// Samples per forcing period, a whole number [default: 25; 64 for the double pendulum, 32 for
    /// the coupled oscillators].
    #[arg(long, help_heading = TIME)]
    samples_per_period: Option<usize>,
    /// Samples written, before --gaps removes any [default: 30000; 5000 for the arm].
    #[arg(long, help_heading = TIME)]
    samples: Option<usize>,
    /// Length of the record in its time unit instead of --samples: duration/step samples, rounded down.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, help_heading = TIME)]
    duration: Option<f64>,
    /// Forcing periods integrated and dropped before the first sample [default: 200; 0 with --forcing
    /// none]. The arm starts at t = 0.
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
    /// Seed of the noise, the bit errors, the gaps and the jitter (ChaCha8).
    #[arg(long, default_value_t = 0, help_heading = NOISE)]
    seed: u64,
    /// Write the continuous angle instead of wrapping it (with --counts: the multi-turn count·2π/N).
    #[arg(long, help_heading = OUTPUT)]
    unwrapped: bool,

    /// Drop K runs of LEN consecutive samples at seeded random places (never the first or last
    /// sample; runs never touch): K:LEN, e.g. 3:50.
    #[arg(long, value_name = "K:LEN", help_heading = OUTPUT)]
    gaps: Option<GapsText>,
    /// Gaussian jitter of the written time stamps, its standard deviation in the record's time unit
    /// (seconds with --drive-frequency): a logger's clock read early or late; the samples are
    /// those of the grid's instants (seeded by --seed).
    #[arg(long, value_name = "SIGMA", allow_hyphen_values = true, help_heading = OUTPUT)]
    jitter: Option<f64>,
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
    /// −1: the measured drive of `hbid identify --forcing-col p`. Printed like the angle. The
    /// double pendulum's p is f sin(t) times rate² (its terms p*cos(theta1), p*cos(theta2)); the
    /// arm's torques and the coupled oscillators' base acceleration are written always.
    #[arg(long, help_heading = OUTPUT)]
    write_drive: bool,
    /// Output file: `.npy` (samples × columns: 3, or 4 with --write-drive, for one coordinate; f8,
    /// the numbers the CSV would hold) or CSV (anything else).
    #[arg(long, help_heading = OUTPUT)]
    out: PathBuf,

    /// Simulate this saved model (from `hbid identify --save-model`) instead of a built-in system,
    /// over the grid of the record --input, driven by its measured drive (--drive-col) or by the
    /// model's own drive on the record's clock; writes t,x,v at every sample of the record, piece
    /// by piece between gaps, each piece from the state whose free run best matches its first
    /// --init samples (or, with --init 0, from --x0, --v0 for a model of one coordinate, --q0, --dq0
    /// for a system of several); pieces no longer than --init are not run.
    /// A record's first rows stamped before its logger settled to its rate are run at their own
    /// stamps, as `hbid compare` runs them. Takes no option of a built-in system.
    #[arg(long, value_name = "MODEL", requires = "input", help_heading = MODEL)]
    model: Option<PathBuf>,
    /// The record whose input drives --model (text or .npy, read as by `hbid identify`).
    #[arg(long, value_name = "RECORD", requires = "model", help_heading = MODEL)]
    input: Option<PathBuf>,
    /// The input's time column, by header name or 1-based position.
    #[arg(long, value_name = "NAME|N", help_heading = MODEL)]
    time_col: Option<String>,
    /// The input's measured output column (angle or displacement), by header name or 1-based
    /// position: its first samples set the initial state.
    #[arg(long, value_name = "NAME|N", help_heading = MODEL)]
    angle_col: Option<String>,
    /// A saved system's coordinates: the input's columns, as `hbid compare --coords` takes them
    /// (by the model's names in any order, NAME=COLUMN, or alone in the order of its coordinates)
    /// [default: the columns it was identified from].
    #[arg(long, value_name = "A,B[,..]", conflicts_with = "angle_col", help_heading = MODEL)]
    coords: Option<ColumnList>,
    /// The input's sampling step, for a record without a time column.
    #[arg(long, allow_hyphen_values = true, help_heading = MODEL)]
    dt: Option<f64>,
    /// The input's measured drive p(t), for a model with terms in p (by header name or 1-based
    /// position); read between samples from the C¹ cubic spline through them.
    #[arg(long, value_name = "NAME|N[,..]", help_heading = MODEL)]
    drive_col: Option<ColumnList>,
    /// Leave out every row of the input with a missing value in a column read (an empty cell,
    /// NA, NaN, ...), as if the logger had not written it: a gap, where the run starts again.
    #[arg(long, help_heading = MODEL)]
    skip_missing: bool,
    /// Replace the input's isolated time-stamp glitches and every encoder spike (each listed),
    /// as `hbid compare --repair` does.
    #[arg(long, help_heading = MODEL)]
    repair: bool,
    /// Samples of the input that set the initial state of each piece [default: one period of the
    /// model's drive, at most a tenth of the record, at least 8]; 0 starts from --x0, --v0.
    #[arg(long, value_name = "N", help_heading = MODEL)]
    init: Option<usize>,
}

impl From<SystemArg> for SystemKind {
    fn from(a: SystemArg) -> Self {
        match a {
            SystemArg::Pendulum => SystemKind::Pendulum,
            SystemArg::Duffing => SystemKind::Duffing,
            SystemArg::DoublePendulum => SystemKind::DoublePendulum,
            SystemArg::Arm => SystemKind::Arm,
            SystemArg::CoupledDuffing => SystemKind::CoupledDuffing,
        }
    }
}

impl From<DriveArg> for DriveKind {
    fn from(a: DriveArg) -> Self {
        match a {
            DriveArg::Drive => DriveKind::Drive,
            DriveArg::None => DriveKind::None,
        }
    }
}

impl From<RangeArg> for RangeKind {
    fn from(a: RangeArg) -> Self {
        match a {
            RangeArg::Signed => RangeKind::Signed,
            RangeArg::Positive => RangeKind::Positive,
        }
    }
}

impl From<TimeOriginArg> for TimeOrigin {
    fn from(a: TimeOriginArg) -> Self {
        match a {
            TimeOriginArg::Drive => TimeOrigin::Drive,
            TimeOriginArg::FirstSample => TimeOrigin::FirstSample,
        }
    }
}

impl SimulateArgs {
    /// The application layer's options.
    pub fn options(&self) -> SimulateOptions {
        SimulateOptions {
            system: self.system.into(),
            f: self.f,
            c: self.c,
            c2: self.c2,
            r: self.r,
            a: self.a,
            b: self.b,
            a2: self.a2,
            b2: self.b2,
            coupling: self.coupling,
            coupling_cubic: self.coupling_cubic,
            mass_ratio: self.mass_ratio,
            drive_seed: self.drive_seed,
            mu: self.mu,
            length_ratio: self.length_ratio,
            torque1: self.torque1.clone(),
            torque2: self.torque2.clone(),
            joint_damping: self.joint_damping.clone(),
            joint_friction: self.joint_friction.clone(),
            friction: self.friction,
            drag: self.drag,
            cubic_damping: self.cubic_damping,
            drive_harmonic: self.drive_harmonic.clone(),
            drive: self.drive.into(),
            x0: self.x0,
            v0: self.v0,
            q0: self.q0.clone(),
            dq0: self.dq0.clone(),
            rtol: self.rtol,
            drive_frequency: self.drive_frequency,
            sample_rate: self.sample_rate,
            samples_per_period: self.samples_per_period,
            samples: self.samples,
            duration: self.duration,
            transient_periods: self.transient_periods,
            phase: self.phase,
            time_origin: self.time_origin.into(),
            counts: self.counts,
            raw_counts: self.raw_counts,
            zero_offset: self.zero_offset,
            bit_errors: self.bit_errors,
            angle_range: self.angle_range.map(Into::into),
            noise: self.noise,
            seed: self.seed,
            unwrapped: self.unwrapped,
            gaps: self.gaps,
            jitter: self.jitter,
            time_decimals: self.time_decimals,
            decimals: self.decimals,
            write_drive: self.write_drive,
        }
    }
}

/// `--model`: the saved model run under the input's measured drive.
fn run_model(args: &SimulateArgs, model: &Path, input: &Path, quiet: bool) -> anyhow::Result<()> {
    let model = hb_pipeline::read_model(model)?;
    // The system's state first: the request's own checks would name the library's x0 and v0.
    check_system_state(args, model.coordinates())?;
    let request = model_request(args)?;
    check_outputs(Some(&args.out), None)?;
    let mut console = Console::new("simulate", quiet, false);
    let run = hb_pipeline::model_run(&model, Source::Path(input), &request, &mut console)?;
    console.finish();
    if let Some(why) = &run.stopped {
        eprintln!("warning: {why}; its later samples are NaN");
    }
    run.write(&args.out)?;
    Ok(())
}

/// A saved system's state with `--init 0`: both of `--q0` and `--dq0`, as many of each, one per
/// coordinate of its `n` (the run's own checks would name the library's x0 and v0, one
/// coordinate's options here).
fn check_system_state(args: &SimulateArgs, n: usize) -> anyhow::Result<()> {
    if args.init != Some(0) {
        return Ok(());
    }
    match (&args.q0, &args.dq0) {
        (Some(_), None) => {
            return Err(
                OptionError::new("dq0", "give the initial velocities with «q0», one per coordinate").into(),
            );
        }
        (None, Some(_)) => {
            return Err(
                OptionError::new("q0", "give the initial positions with «dq0», one per coordinate").into(),
            );
        }
        (Some(q), Some(v)) if q.0.len() != v.0.len() => {
            return Err(OptionError::value(
                "dq0",
                v,
                format!(
                    "give as many initial velocities as positions («q0»: {})",
                    q.0.len()
                ),
            )
            .into());
        }
        _ => {}
    }
    if n > 1 {
        for (option, given) in [("q0", &args.q0), ("dq0", &args.dq0)] {
            match given {
                None => {
                    return Err(OptionError::new(
                        option,
                        format!(
                            "«init» 0 runs the system from «q0» and «dq0»: give both, one value per coordinate ({n})"
                        ),
                    )
                    .into());
                }
                Some(values) if values.0.len() != n => {
                    return Err(OptionError::value(
                        option,
                        values,
                        format!("give one value per coordinate of the system ({n})"),
                    )
                    .into());
                }
                Some(_) => {}
            }
        }
    }
    Ok(())
}

/// The request of a model's run: the input's options, the initial state's, and no option of a
/// built-in system.
fn model_request(args: &SimulateArgs) -> anyhow::Result<CompareRequest> {
    if let Some(name) = args.options().rig_settings().first() {
        return Err(OptionError::sentence(name.as_str(), hb_pipeline::simulate::MODEL_TAKES_NO_RIG).into());
    }
    if args.truth.is_some() {
        return Err(OptionError::sentence(
            "truth",
            "is the equation of a built-in system: a saved «model» has none to write",
        )
        .into());
    }
    let given = args.init == Some(0);
    hb_pipeline::simulate::check_model_state(&args.options(), given)?;
    Ok(CompareRequest::new(CompareOptions {
        time_col: args.time_col.clone(),
        angle_col: args.angle_col.clone(),
        coords: args.coords.clone(),
        dt: args.dt,
        drive_col: args.drive_col.clone(),
        skip_missing: args.skip_missing,
        repair: args.repair,
        init: args.init.filter(|&n| n > 0),
        // A system's state by --q0, --dq0; one coordinate's by --x0, --v0.
        x0: given.then(|| args.q0.clone().map_or(args.x0.into(), |q| Values(q.0))),
        v0: given.then(|| args.dq0.clone().map_or(args.v0.into(), |v| Values(v.0))),
        rtol: args.rtol,
        ..CompareOptions::default()
    })?)
}

pub fn run(args: &SimulateArgs, quiet: bool) -> anyhow::Result<()> {
    if let (Some(model), Some(input)) = (&args.model, &args.input) {
        return run_model(args, model, input, quiet);
    }
    for (name, given) in [
        ("time_col", args.time_col.is_some()),
        ("angle_col", args.angle_col.is_some()),
        ("coords", args.coords.is_some()),
        ("dt", args.dt.is_some()),
        ("drive_col", args.drive_col.is_some()),
        ("init", args.init.is_some()),
        ("skip_missing", args.skip_missing),
        ("repair", args.repair),
    ] {
        if given {
            return Err(
                OptionError::sentence(name, "reads the record of «input», for a saved «model»").into(),
            );
        }
    }
    let rig = Rig::new(args.options())?;
    check_outputs(Some(&args.out), args.truth.as_deref())?;
    let mut console = Console::new("simulate", quiet, false);
    // Written as it is simulated: a record of any length in memory that does not grow with it.
    hb_pipeline::simulate::simulate_to(&rig, &args.out, &mut console)?;
    console.finish();
    if let Some(path) = &args.truth {
        write_truth(&rig.truth()?, path)?;
    }
    Ok(())
}

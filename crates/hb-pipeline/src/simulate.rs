//! The simulate request: a forced oscillator sampled as a rig records it, as `hbid simulate` and
//! Python's `hbid.simulate` make it (defaults: the paper's data set).
//!
//! The simulation, the time frame and every encoder effect are `pendulum_sim`'s
//! ([`InFrame`], [`Encoder`], [`Gaps`]); this module only composes them from the options
//! ([`SimulateOptions`] → [`Rig`], every combination checked), runs it ([`simulate`]) and writes
//! the record and its true equation ([`Simulation::write`], [`Simulation::truth`]).

use std::f64::consts::TAU;
use std::fmt;
use std::io::Write;
use std::path::Path;
use std::str::FromStr;

use hb_basis::{Harmonic, Polynomial};
use hb_model::TrueEquation;
use hb_model::{Forcing, ModelForm};
use npyz::WriterBuilder;
use pendulum_sim::observe::{AngleRange, Encoder, Gaps};
use pendulum_sim::{
    DriveHarmonic, DriveHarmonics, Duffing, InFrame, Losses, Pendulum, RecordFrame, SecondOrderSystem,
    SimulationConfig, Tolerances, Trajectory, simulate_with_progress,
};
use serde::{Deserialize, Serialize};

use crate::error::RunError;
use crate::observe::{Observer, Stage};
use crate::options::{OptionError, chain, from_object, optional_text, text};
use crate::output::{OutputError, check_output_path, write_atomically};

/// A value of an option that names one of a few choices.
macro_rules! choice {
    ($(#[$doc:meta])* $name:ident { $($(#[$vdoc:meta])* $variant:ident = $text:literal),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum $name {
            $($(#[$vdoc])* $variant),+
        }

        impl $name {
            /// Every value, in order.
            pub const ALL: &'static [$name] = &[$($name::$variant),+];

            /// The name of the value.
            pub fn name(self) -> &'static str {
                match self {
                    $($name::$variant => $text),+
                }
            }
        }

        impl FromStr for $name {
            type Err = String;

            fn from_str(s: &str) -> Result<Self, String> {
                Self::ALL
                    .iter()
                    .copied()
                    .find(|v| v.name() == s.trim())
                    .ok_or_else(|| {
                        let names: Vec<&str> = Self::ALL.iter().map(|v| v.name()).collect();
                        format!("unknown value '{}': {}", s.trim(), names.join(" or "))
                    })
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

choice!(
    /// The simulated system.
    SystemKind {
        /// The base-excited pendulum `x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0` (columns
        /// `t,theta,omega`).
        Pendulum = "pendulum",
        /// The two-well Duffing oscillator `x'' + c x' + a x + b x³ = f cos(t)` (columns `t,x,v`;
        /// never wrapped).
        Duffing = "duffing",
    }
);

choice!(
    /// Whether the system is driven.
    DriveKind {
        /// Driven with amplitude `f`.
        Drive = "drive",
        /// A free decay: `f = 0`.
        None = "none",
    }
);

choice!(
    /// The interval of a wrapped angle.
    RangeKind {
        /// `[−π, π)`.
        Signed = "signed",
        /// `[0, 2π)`.
        Positive = "positive",
    }
);

choice!(
    /// Where the time stamps count from.
    TimeOrigin {
        /// The drive's phase zero at the start of the integration: the drive is
        /// `sin(2π f_drive t)` (or `sin(t)`) at the written stamps, whatever the phase.
        Drive = "drive",
        /// The first sample, as a data acquisition's clock: stamps `n·h` from 0, and the drive
        /// has the phase `phase` at `t = 0`.
        FirstSample = "first-sample",
    }
);

/// A harmonic of the drive as text, `K:RATIO[:PHASE]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicText(pub DriveHarmonic);

impl FromStr for HarmonicText {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let parts: Vec<&str> = text.split(':').map(str::trim).collect();
        if !(2..=3).contains(&parts.len()) {
            return Err("expected K:RATIO[:PHASE], e.g. 2:0.1 or 3:0.05:1.2".to_owned());
        }
        let k = parts[0]
            .parse::<u32>()
            .map_err(|_| format!("'{}' is not a whole number", parts[0]))?;
        let number = |s: &str| s.parse::<f64>().map_err(|_| format!("'{s}' is not a number"));
        let ratio = number(parts[1])?;
        let phase = match parts.get(2) {
            Some(p) => number(p)?,
            None => 0.0,
        };
        DriveHarmonic::new(k, ratio, phase)
            .map(HarmonicText)
            .map_err(|e| e.to_string())
    }
}

impl fmt::Display for HarmonicText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.0.k(), self.0.ratio(), self.0.phase())
    }
}

/// Gaps as text, `K:LEN`: K runs of LEN samples dropped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GapsText(pub Gaps);

impl FromStr for GapsText {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (k, len) = text
            .split_once(':')
            .ok_or_else(|| "expected K:LEN, e.g. 3:50".to_owned())?;
        let number = |s: &str| {
            s.trim()
                .parse::<usize>()
                .map_err(|_| format!("'{}' is not a whole number", s.trim()))
        };
        Gaps::new(number(k)?, number(len)?)
            .map(GapsText)
            .map_err(|e| e.to_string())
    }
}

impl fmt::Display for GapsText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.0.count(), self.0.length())
    }
}

/// Every option of `hbid simulate`, by the names of the command line (`_` for `-`) and of
/// Python's keyword arguments, with their defaults (the paper's data set: 30000 samples, 25 per
/// drive period 2π, after 200 periods, the angle wrapped into `[−π, π)`). Checked by
/// [`Rig::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SimulateOptions {
    /// The system.
    #[serde(with = "text")]
    pub system: SystemKind,
    /// Drive amplitude `f` (default 1.52 for the pendulum, 0.3 for the Duffing oscillator).
    pub f: Option<f64>,
    /// Damping `c` (default 0.03 for the pendulum, 0.25 for the Duffing oscillator).
    pub c: Option<f64>,
    /// Pendulum: frequency ratio `r`, stiffness `1/r²` (default 0.8333).
    pub r: Option<f64>,
    /// Duffing: linear stiffness `a` (default −1).
    pub a: Option<f64>,
    /// Duffing: cubic stiffness `b` (default 1).
    pub b: Option<f64>,
    /// Dry friction `μ sign(x')` in the model's time.
    pub friction: Option<f64>,
    /// Quadratic drag `d x'|x'|` in the model's time.
    pub drag: Option<f64>,
    /// Cubic damping `c3 x'^3` in the model's time.
    pub cubic_damping: Option<f64>,
    /// Harmonics of the drive, `K:RATIO[:PHASE]` each.
    #[serde(with = "text_list")]
    pub drive_harmonic: Vec<HarmonicText>,
    /// `drive`, or `none` for a free decay.
    #[serde(with = "text")]
    pub drive: DriveKind,
    /// Initial position at the start of the integration.
    pub x0: f64,
    /// Initial velocity at the start of the integration, in the record's time unit.
    pub v0: f64,
    /// Relative tolerance of the integrator (the absolute one is `rtol/10`).
    pub rtol: f64,
    /// Drive frequency in Hz: time in seconds. Without it, the model's own time (drive period 2π).
    pub drive_frequency: Option<f64>,
    /// Sample rate in Hz, any ratio to the drive (needs `drive_frequency`).
    pub sample_rate: Option<f64>,
    /// Samples per drive period, a whole number (default 25).
    pub samples_per_period: Option<usize>,
    /// Samples kept, before gaps remove any (default 30000).
    pub samples: Option<usize>,
    /// The record's length in its time unit instead of `samples`.
    pub duration: Option<f64>,
    /// Drive periods integrated and dropped first (default 200; 0 for a free decay).
    pub transient_periods: Option<usize>,
    /// Drive phase (radians) of the first sample.
    pub phase: f64,
    /// Where the time stamps count from.
    #[serde(with = "text")]
    pub time_origin: TimeOrigin,
    /// Encoder counts per revolution.
    pub counts: Option<u32>,
    /// Give the integer counts in `[0, N)` instead of radians.
    pub raw_counts: bool,
    /// The encoder's zero this far (radians) from the bottom.
    pub zero_offset: Option<f64>,
    /// Probability per sample of a bit error of the count.
    pub bit_errors: Option<f64>,
    /// `signed` `[−π, π)` or `positive` `[0, 2π)`.
    #[serde(with = "optional_text")]
    pub angle_range: Option<RangeKind>,
    /// Standard deviation of Gaussian noise on the angle or displacement.
    pub noise: Option<f64>,
    /// Seed of the noise, the bit errors and the gaps.
    pub seed: u64,
    /// The continuous angle instead of the wrapped one.
    pub unwrapped: bool,
    /// Gaps, `K:LEN`: K runs of LEN samples dropped at seeded places.
    #[serde(with = "optional_text")]
    pub gaps: Option<GapsText>,
    /// Time stamps printed with this many decimals.
    pub time_decimals: Option<usize>,
    /// Angle (or displacement) and velocity printed with this many decimals.
    pub decimals: Option<usize>,
    /// Also write the drive `p(t)` as a fourth column `p`.
    pub write_drive: bool,
}

/// A list of values read from texts (or one text).
mod text_list {
    use super::*;
    use serde::{Deserializer, Serializer};
    use serde_json::Value;

    pub fn serialize<T: fmt::Display, S: Serializer>(values: &[T], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(values.iter().map(ToString::to_string))
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<Vec<T>, D::Error>
    where
        T: FromStr,
        T::Err: fmt::Display,
        D: Deserializer<'de>,
    {
        let items = match Value::deserialize(d)? {
            Value::Null => Vec::new(),
            Value::String(s) => vec![s],
            Value::Array(items) => items
                .into_iter()
                .map(|v| match v {
                    Value::String(s) => Ok(s),
                    other => Err(serde::de::Error::custom(format!(
                        "expected a text, found {other}"
                    ))),
                })
                .collect::<Result<_, _>>()?,
            other => {
                return Err(serde::de::Error::custom(format!(
                    "expected a list of texts, found {other}"
                )));
            }
        };
        items
            .iter()
            .map(|s| s.parse().map_err(serde::de::Error::custom))
            .collect()
    }
}

impl Default for SimulateOptions {
    fn default() -> Self {
        Self {
            system: SystemKind::Pendulum,
            f: None,
            c: None,
            r: None,
            a: None,
            b: None,
            friction: None,
            drag: None,
            cubic_damping: None,
            drive_harmonic: Vec::new(),
            drive: DriveKind::Drive,
            x0: 0.1,
            v0: 0.0,
            rtol: 1e-10,
            drive_frequency: None,
            sample_rate: None,
            samples_per_period: None,
            samples: None,
            duration: None,
            transient_periods: None,
            phase: 0.0,
            time_origin: TimeOrigin::Drive,
            counts: None,
            raw_counts: false,
            zero_offset: None,
            bit_errors: None,
            angle_range: None,
            noise: None,
            seed: 0,
            unwrapped: false,
            gaps: None,
            time_decimals: None,
            decimals: None,
            write_drive: false,
        }
    }
}

/// Why an option of a built-in system is refused with a saved model, after the option's name.
pub const MODEL_TAKES_NO_RIG: &str = "is an option of a built-in system: a saved model («model») takes only the input's options, «x0», «v0» and «rtol»";

/// With a saved model the initial state is fitted to the input's first samples unless `init` is 0
/// (`state_given`): an `x0` or `v0` set away from its default without it would be ignored, and
/// is refused instead.
pub fn check_model_state(rig: &SimulateOptions, state_given: bool) -> Result<(), OptionError> {
    let d = SimulateOptions::default();
    if !state_given && (rig.x0 != d.x0 || rig.v0 != d.v0) {
        let name = if rig.x0 != d.x0 { "x0" } else { "v0" };
        return Err(OptionError::sentence(
            name,
            "sets the state of a saved «model» with «init=0» only (otherwise the state is fitted to the input's \
             first samples)",
        ));
    }
    Ok(())
}

impl SimulateOptions {
    /// The options of a built-in system set away from their defaults (every option but `x0`,
    /// `v0` and `rtol`): what a saved model's run under a record's input (`hbid simulate --model`)
    /// does not take.
    pub fn rig_settings(&self) -> Vec<String> {
        let (Ok(serde_json::Value::Object(now)), Ok(serde_json::Value::Object(default))) =
            (serde_json::to_value(self), serde_json::to_value(Self::default()))
        else {
            return Vec::new();
        };
        now.into_iter()
            .filter(|(k, v)| !matches!(k.as_str(), "x0" | "v0" | "rtol") && default.get(k) != Some(v))
            .map(|(k, _)| k)
            .collect()
    }
}

/// Decimals beyond which printing gains nothing an `f64` holds.
const MAX_DECIMALS: usize = 30;

/// The system chosen, with its parameters checked.
#[derive(Debug, Clone, Copy)]
pub enum System {
    /// The pendulum.
    Pendulum(Pendulum),
    /// The Duffing oscillator.
    Duffing(Duffing),
}

impl System {
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

    /// The drive as it enters the equation at the system's time `tau`.
    fn drive(&self, tau: f64) -> f64 {
        match self {
            System::Pendulum(p) => p.drive(tau),
            System::Duffing(d) => d.drive(tau),
        }
    }
}

/// A simulated rig, every option checked: the system, the record's time and sampling, the encoder
/// and the gaps.
#[derive(Debug, Clone)]
pub struct Rig {
    options: SimulateOptions,
    system: System,
    /// `τ = rate · t` during the simulation.
    frame: RecordFrame,
    config: SimulationConfig,
    /// The drive's phase at the first sample, radians in `[0, 2π)`.
    first_phase: f64,
    encoder: Option<Encoder>,
    gaps: Option<Gaps>,
}

/// Wraps a library error as the error of `option`.
fn on<E: std::error::Error>(option: &'static str) -> impl Fn(E) -> OptionError {
    move |e| OptionError::new(option, chain(&e))
}

impl Rig {
    /// Checks `options`, alone and together.
    pub fn new(options: SimulateOptions) -> Result<Self, OptionError> {
        let system = Self::system(&options)?;
        let (frame, config, first_phase) = Self::timing(&options)?;
        let encoder = Self::encoder(&options)?;
        let gaps = options.gaps.map(|g| g.0.seeded(options.seed));
        for (name, decimals) in [
            ("decimals", options.decimals),
            ("time_decimals", options.time_decimals),
        ] {
            if let Some(n) = decimals
                && n > MAX_DECIMALS
            {
                return Err(OptionError::value(name, n, format!("at most {MAX_DECIMALS}")));
            }
        }
        let step = config.sample_step();
        if let Some(n) = options.time_decimals {
            // Stamps rounded to n decimals keep increasing only if the step is at least 10^-n.
            let resolution = 10f64.powi(i32::try_from(n).unwrap_or(i32::MAX));
            if step * resolution < 1.0 - 1e-9 {
                return Err(OptionError::value(
                    "time_decimals",
                    n,
                    format!("cannot tell apart samples {step} apart"),
                ));
            }
        }
        if let Some(g) = &gaps {
            g.kept(config.samples()).map_err(on("gaps"))?;
        }
        Ok(Self {
            options,
            system,
            frame,
            config,
            first_phase,
            encoder,
            gaps,
        })
    }

    /// A rig from a JSON object of option names (Python's keyword arguments), unknown names
    /// refused.
    pub fn from_json(value: serde_json::Value) -> Result<Self, OptionError> {
        Self::new(from_object(value)?)
    }

    /// The options as given.
    pub fn options(&self) -> &SimulateOptions {
        &self.options
    }

    /// The system.
    pub fn system_kind(&self) -> System {
        self.system
    }

    /// The simulation's configuration (sampling, transient, tolerances).
    pub fn config(&self) -> &SimulationConfig {
        &self.config
    }

    fn system(o: &SimulateOptions) -> Result<System, OptionError> {
        if o.drive == DriveKind::None && o.f.is_some() {
            return Err(OptionError::sentence(
                "f",
                "is the drive's amplitude: not with «drive=none»",
            ));
        }
        if o.drive == DriveKind::None && !o.drive_harmonic.is_empty() {
            return Err(OptionError::sentence(
                "drive_harmonic",
                "is a harmonic of the drive: not with «drive=none»",
            ));
        }
        let amplitude = |default: f64| match o.drive {
            DriveKind::Drive => o.f.unwrap_or(default),
            DriveKind::None => 0.0,
        };
        let mut losses = Losses::none();
        if let Some(mu) = o.friction {
            losses = losses.with_friction(mu).map_err(on("friction"))?;
        }
        if let Some(d) = o.drag {
            losses = losses.with_drag(d).map_err(on("drag"))?;
        }
        if let Some(c3) = o.cubic_damping {
            losses = losses.with_cubic_damping(c3).map_err(on("cubic_damping"))?;
        }
        let list: Vec<DriveHarmonic> = o.drive_harmonic.iter().map(|h| h.0).collect();
        let harmonics = DriveHarmonics::new(&list).map_err(on("drive_harmonic"))?;
        Ok(match o.system {
            SystemKind::Pendulum => {
                if o.a.is_some() || o.b.is_some() {
                    let name = if o.a.is_some() { "a" } else { "b" };
                    return Err(OptionError::sentence(
                        name,
                        "is a stiffness of the Duffing oscillator («system=duffing»)",
                    ));
                }
                let (f, c, r) = Pendulum::PAPER;
                System::Pendulum(
                    Pendulum::new(amplitude(f), o.c.unwrap_or(c), o.r.unwrap_or(r))
                        .map_err(on("system"))?
                        .with_losses(losses)
                        .with_drive_harmonics(harmonics),
                )
            }
            SystemKind::Duffing => {
                if o.r.is_some() {
                    return Err(OptionError::sentence(
                        "r",
                        "is the pendulum's frequency ratio («system=pendulum»)",
                    ));
                }
                let encoder_options = [
                    ("counts", o.counts.is_some()),
                    ("raw_counts", o.raw_counts),
                    ("zero_offset", o.zero_offset.is_some()),
                    ("bit_errors", o.bit_errors.is_some()),
                    ("angle_range", o.angle_range.is_some()),
                ];
                if let Some((name, _)) = encoder_options.iter().find(|(_, set)| *set) {
                    return Err(OptionError::sentence(
                        *name,
                        "is an angle encoder's: «system=pendulum» only (the Duffing displacement takes «noise»)",
                    ));
                }
                let (c, a, b, f) = Duffing::TWO_WELL;
                System::Duffing(
                    Duffing::new(o.c.unwrap_or(c), o.a.unwrap_or(a), o.b.unwrap_or(b), amplitude(f))
                        .map_err(on("system"))?
                        .with_losses(losses)
                        .with_drive_harmonics(harmonics),
                )
            }
        })
    }

    fn timing(o: &SimulateOptions) -> Result<(RecordFrame, SimulationConfig, f64), OptionError> {
        let frame = match o.drive_frequency {
            None => RecordFrame::nondimensional(),
            Some(hz) => RecordFrame::nondimensional()
                .with_drive_frequency(hz)
                .map_err(|e| OptionError::checked("drive_frequency", hz, &e))?,
        };
        let mut config = SimulationConfig::paper();
        if let Some(hz) = o.drive_frequency {
            config = config
                .with_drive_period(1.0 / hz)
                .map_err(|e| OptionError::checked("drive_frequency", hz, &e))?;
        }
        match (o.sample_rate, o.samples_per_period) {
            (Some(_), Some(_)) => {
                return Err(OptionError::sentence(
                    "sample_rate",
                    "and «samples_per_period» both set: give one",
                ));
            }
            (Some(_), None) if o.drive_frequency.is_none() => {
                return Err(OptionError::sentence(
                    "sample_rate",
                    "needs «drive_frequency» (time in seconds)",
                ));
            }
            (Some(rate), None) => {
                if !(rate.is_finite() && rate > 0.0) {
                    return Err(OptionError::value(
                        "sample_rate",
                        rate,
                        "must be positive and finite",
                    ));
                }
                config = config
                    .with_sample_step(1.0 / rate)
                    .map_err(|e| OptionError::checked("sample_rate", rate, &e))?;
            }
            (None, Some(p)) => {
                config = config
                    .with_samples_per_period(p)
                    .map_err(|e| OptionError::checked("samples_per_period", p, &e))?;
            }
            (None, None) => {}
        }
        let step = config.sample_step();
        let samples = match (o.samples, o.duration) {
            (Some(_), Some(_)) => {
                return Err(OptionError::sentence(
                    "samples",
                    "and «duration» both set: give one",
                ));
            }
            (Some(n), None) => n,
            (None, Some(d)) => samples_in(d, step)?,
            (None, None) => config.samples(),
        };
        let transient = o.transient_periods.unwrap_or(match o.drive {
            DriveKind::Drive => config.transient_periods(),
            DriveKind::None => 0,
        });
        if !o.phase.is_finite() {
            return Err(OptionError::value("phase", o.phase, "must be finite"));
        }
        let mut fraction = o.phase.rem_euclid(TAU) / TAU;
        if fraction >= 1.0 {
            fraction = 0.0;
        }
        let config = config
            .with_samples(samples)
            .map_err(|e| OptionError::checked("samples", samples, &e))?
            .with_transient_periods(transient)
            .with_initial(o.x0, o.v0)
            .map_err(|e| OptionError::new("x0", e))?
            .with_phase(fraction)
            .map_err(|e| OptionError::checked("phase", o.phase, &e))?
            .with_tolerances(
                Tolerances::relative(o.rtol).map_err(|e| OptionError::checked("rtol", o.rtol, &e))?,
            );
        Ok((frame, config, TAU * fraction))
    }

    /// The encoder of the options, `None` for an ideal one (the angle is then only wrapped).
    fn encoder(o: &SimulateOptions) -> Result<Option<Encoder>, OptionError> {
        if o.raw_counts && o.counts.is_none() {
            return Err(OptionError::sentence("raw_counts", "needs «counts»"));
        }
        if o.bit_errors.is_some() && o.counts.is_none() {
            return Err(OptionError::sentence(
                "bit_errors",
                "needs «counts» (bit errors are errors of the count)",
            ));
        }
        if o.unwrapped && o.raw_counts {
            return Err(OptionError::sentence(
                "raw_counts",
                "writes counts in [0, N): not with «unwrapped»",
            ));
        }
        if o.angle_range.is_some() && (o.unwrapped || o.raw_counts) {
            return Err(OptionError::sentence(
                "angle_range",
                "is where a wrapped angle lies: not with «unwrapped» or «raw_counts»",
            ));
        }
        let any = o.noise.is_some()
            || o.counts.is_some()
            || o.zero_offset.is_some()
            || o.bit_errors.is_some()
            || o.angle_range.is_some();
        if !any {
            return Ok(None);
        }
        let mut e = Encoder::seeded(o.seed);
        if let Some(sigma) = o.noise {
            e = e.with_noise(sigma).map_err(on("noise"))?;
        }
        if let Some(n) = o.counts {
            e = e.with_counts(n).map_err(on("counts"))?;
        }
        if let Some(offset) = o.zero_offset {
            e = e.with_zero_offset(offset).map_err(on("zero_offset"))?;
        }
        if let Some(rate) = o.bit_errors {
            e = e.with_bit_errors(rate).map_err(on("bit_errors"))?;
        }
        if o.angle_range == Some(RangeKind::Positive) {
            e = e.with_range(AngleRange::Positive);
        }
        Ok(Some(e))
    }
}

/// The samples in `duration` at step `step`: `duration / step` rounded down, a ratio within
/// 1e-9 of a whole number taken as that number (60 s at 500 Hz is 30000 samples).
fn samples_in(duration: f64, step: f64) -> Result<usize, OptionError> {
    if !(duration.is_finite() && duration > 0.0) {
        return Err(OptionError::value(
            "duration",
            duration,
            "must be positive and finite",
        ));
    }
    let ratio = duration / step;
    let whole = ratio.round();
    let n = if (ratio - whole).abs() <= 1e-9 * ratio.max(1.0) {
        whole
    } else {
        ratio.floor()
    };
    if n < 1.0 {
        return Err(OptionError::value(
            "duration",
            duration,
            format!("is shorter than one sample step ({step})"),
        ));
    }
    if n > usize::MAX as f64 {
        return Err(OptionError::value("duration", duration, "too many samples"));
    }
    Ok(n as usize)
}

/// The angle (or displacement) column as recorded.
#[derive(Debug, Clone, PartialEq)]
pub enum Reported {
    /// Radians (or the displacement).
    Values(Vec<f64>),
    /// Encoder counts.
    Counts(Vec<u32>),
}

/// A simulated record: every sample simulated, and which of them the record keeps (gaps).
#[derive(Debug, Clone)]
pub struct Simulation {
    rig: Rig,
    /// The time stamps, as written (before printing with `time_decimals`).
    pub t: Vec<f64>,
    /// The angle (or displacement, or counts) as recorded.
    pub x: Reported,
    /// The clean velocity, in the record's time unit.
    pub v: Vec<f64>,
    /// The drive `p(t)` as it enters the equation, in the record's time unit.
    pub drive: Vec<f64>,
    /// Whether each sample is kept (`false` inside a gap).
    pub kept: Vec<bool>,
}

/// Simulates `rig`; `observer` hears the progress in samples.
pub fn simulate(rig: &Rig, observer: &mut dyn Observer) -> Result<Simulation, RunError> {
    observer.stage(Stage::Simulate);
    let config = &rig.config;
    let samples = config.samples();
    let mut progress = |done: usize, total: usize| observer.progress(done, total);
    let traj = match (rig.system, rig.options.drive_frequency) {
        (System::Pendulum(p), None) => run(&p, config, &mut progress)?,
        (System::Pendulum(p), Some(_)) => run(&InFrame::new(p, rig.frame), config, &mut progress)?,
        (System::Duffing(d), None) => run(&d, config, &mut progress)?,
        (System::Duffing(d), Some(_)) => run(&InFrame::new(d, rig.frame), config, &mut progress)?,
    };
    let o = &rig.options;
    let x = match (rig.system, rig.encoder) {
        (System::Pendulum(_), None) if o.unwrapped => Reported::Values(traj.theta.clone()),
        (System::Pendulum(_), None) => {
            Reported::Values(traj.theta.iter().map(|&x| circle_signal::wrap(x)).collect())
        }
        (System::Pendulum(_), Some(e)) if o.raw_counts => Reported::Counts(
            e.observe_counts(&traj.theta)
                .ok_or_else(|| OptionError::sentence("raw_counts", "needs «counts»"))?,
        ),
        (System::Pendulum(_), Some(e)) if o.unwrapped => Reported::Values(e.observe_continuous(&traj.theta)),
        (System::Pendulum(_), Some(e)) => Reported::Values(e.observe(&traj.theta)),
        (System::Duffing(_), None) => Reported::Values(traj.theta.clone()),
        (System::Duffing(_), Some(e)) => Reported::Values(e.observe_continuous(&traj.theta)),
    };
    let t = match o.time_origin {
        TimeOrigin::Drive => traj.t.clone(),
        TimeOrigin::FirstSample => {
            let h = config.sample_step();
            (0..traj.len()).map(|n| n as f64 * h).collect()
        }
    };
    // The drive in the record's frame: rate² times the system's, at the system's time.
    let rate = rig.frame.rate();
    let drive = traj
        .t
        .iter()
        .map(|&t| rate * rate * rig.system.drive(rig.frame.system_time(t)))
        .collect();
    let kept = match &rig.gaps {
        Some(g) => g.kept(samples).map_err(on("gaps"))?,
        None => vec![true; samples],
    };
    Ok(Simulation {
        rig: rig.clone(),
        t,
        x,
        v: traj.omega,
        drive,
        kept,
    })
}

fn run<S: SecondOrderSystem>(
    system: &S,
    config: &SimulationConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Trajectory, RunError> {
    Ok(simulate_with_progress(system, config, progress)?)
}

/// `v` printed with `decimals`, or in the shortest form that reads back as `v`.
fn printed_text(v: f64, decimals: Option<usize>) -> String {
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

impl Simulation {
    /// The rig simulated.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// The columns written: time, value, velocity, and `p` with `write_drive`.
    pub fn columns(&self) -> Vec<&'static str> {
        let mut columns = match (self.rig.system, &self.x) {
            (System::Duffing(_), _) => vec!["t", "x", "v"],
            (System::Pendulum(_), Reported::Counts(_)) => vec!["t", "count", "omega"],
            (System::Pendulum(_), Reported::Values(_)) => vec!["t", "theta", "omega"],
        };
        if self.rig.options.write_drive {
            columns.push("p");
        }
        columns
    }

    /// Rows of the record (samples kept).
    pub fn rows(&self) -> usize {
        self.kept.iter().filter(|&&k| k).count()
    }

    /// The record's rows as they are written, each `[t, x, v]` (and `p`), numbers as a reader of
    /// the printed text gets them.
    pub fn table(&self) -> Vec<Vec<f64>> {
        let (td, vd) = (self.rig.options.time_decimals, self.rig.options.decimals);
        (0..self.t.len())
            .filter(|&n| self.kept[n])
            .map(|n| {
                let x = match &self.x {
                    Reported::Values(x) => printed(x[n], vd),
                    Reported::Counts(k) => f64::from(k[n]),
                };
                let mut row = vec![printed(self.t[n], td), x, printed(self.v[n], vd)];
                if self.rig.options.write_drive {
                    row.push(printed(self.drive[n], vd));
                }
                row
            })
            .collect()
    }

    /// Writes the record atomically: `.npy` (rows × columns, `f8`) or CSV (anything else).
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let npy = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("npy"));
        let (td, vd) = (self.rig.options.time_decimals, self.rig.options.decimals);
        let columns = self.columns();
        if npy {
            let table = self.table();
            return write_atomically(path, |w: &mut dyn Write| {
                let mut writer = npyz::WriteOptions::<f64>::new()
                    .default_dtype()
                    .shape(&[table.len() as u64, columns.len() as u64])
                    .writer(w)
                    .begin_nd()?;
                for row in &table {
                    writer.extend(row.iter().copied())?;
                }
                writer.finish()
            });
        }
        write_atomically(path, |w: &mut dyn Write| {
            writeln!(w, "{}", columns.join(","))?;
            for n in (0..self.t.len()).filter(|&n| self.kept[n]) {
                let x = match &self.x {
                    Reported::Values(x) => printed_text(x[n], vd),
                    Reported::Counts(k) => k[n].to_string(),
                };
                write!(
                    w,
                    "{},{x},{}",
                    printed_text(self.t[n], td),
                    printed_text(self.v[n], vd)
                )?;
                if self.rig.options.write_drive {
                    writeln!(w, ",{}", printed_text(self.drive[n], vd))?;
                } else {
                    writeln!(w)?;
                }
            }
            Ok(())
        })
    }

    /// The true equation the record satisfies, in the identification's form and the record's time
    /// unit, with the drive, sampling and encoder settings.
    pub fn truth(&self) -> Result<Truth, RunError> {
        truth(&self.rig, self.rows(), self.columns())
    }
}

/// Checks where a simulation and its truth will be written, before any work.
pub fn check_outputs(out: Option<&Path>, truth: Option<&Path>) -> Result<(), RunError> {
    if let Some(out) = out {
        check_output_path(out)?;
    }
    if let Some(truth) = truth {
        if Some(truth) == out {
            return Err(OptionError::sentence("truth", "and «out» name the same file").into());
        }
        check_output_path(truth).map_err(|e| OptionError::new("truth", e))?;
    }
    Ok(())
}

/// Coefficients as a JSON object in the identification's column order.
#[derive(Debug, Clone, PartialEq)]
pub struct Ordered(pub Vec<(String, f64)>);

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

/// The truth file: the equation a simulated record satisfies, in the identification's form.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Truth {
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
    pub coefficients: Ordered,
    time_unit: &'static str,
    /// Hz, `None` for the model's own time.
    drive_frequency: Option<f64>,
    forcing_period: f64,
    /// `dτ/dt`: the drive's angular frequency in the record's time unit.
    time_scale: f64,
    /// The drive's phase (radians) at the record's `t = 0`.
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

#[derive(Debug, Clone, PartialEq, Serialize)]
struct IdentifyHint {
    signal: &'static str,
    basis: &'static str,
    forcing: &'static str,
    angle_column: &'static str,
    /// Terms of the true equation beyond the layout of `basis` and `forcing` (a rig's losses and
    /// drive harmonics), listed after it in `coefficients`.
    extra_terms: Vec<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
struct EncoderInfo {
    counts: Option<u32>,
    zero_offset: f64,
    bit_error_rate: f64,
    bit_error_bits: [u32; 4],
    angle_range: &'static str,
    raw_counts: bool,
    unwrapped: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
struct GapsInfo {
    count: usize,
    length: usize,
    /// First dropped sample of each gap, counted in the simulated samples.
    starts: Vec<usize>,
}

fn truth(rig: &Rig, rows: usize, columns: Vec<&'static str>) -> Result<Truth, RunError> {
    let o = &rig.options;
    let encoder = rig.encoder;
    let offset = encoder.map_or(0.0, |e| e.zero_offset());
    let at_zero = match o.time_origin {
        TimeOrigin::Drive => 0.0,
        TimeOrigin::FirstSample => rig.first_phase,
    };
    let frame = rig.frame.with_phase(at_zero)?.with_offset(offset)?;
    let (known, layout, parameters, mut hint) = match rig.system {
        System::Pendulum(p) => (
            p.equation(&frame)?.named(),
            hb_model::term_names(
                &Harmonic::new(1).map_err(hb_solve::SolveError::from)?,
                &ModelForm::parametric(),
            ),
            serde_json::to_value(p).map_err(|e| OptionError::new("system", e))?,
            IdentifyHint {
                signal: "circle",
                basis: "harmonic:1",
                forcing: "none",
                angle_column: columns[1],
                extra_terms: Vec::new(),
            },
        ),
        System::Duffing(d) => (
            d.equation(&frame)?.named(),
            hb_model::term_names(
                &Polynomial::new(3).map_err(hb_solve::SolveError::from)?,
                &ModelForm::parametric().with_forcing(Forcing::Identified),
            ),
            serde_json::to_value(d).map_err(|e| OptionError::new("system", e))?,
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
    let config = &rig.config;
    let step = config.sample_step();
    let first_sample_time = match o.time_origin {
        TimeOrigin::Drive => config.sample_time(0),
        TimeOrigin::FirstSample => 0.0,
    };
    let range = match o.angle_range {
        Some(RangeKind::Positive) => "positive",
        _ => "signed",
    };
    let sigma = encoder.map_or(0.0, |e| e.sigma());
    let encoder_info = match rig.system {
        System::Pendulum(_) => Some(EncoderInfo {
            counts: encoder.and_then(|e| e.counts()),
            zero_offset: offset,
            bit_error_rate: encoder.map_or(0.0, |e| e.bit_error_rate()),
            bit_error_bits: Encoder::BIT_ERROR_BITS,
            angle_range: range,
            raw_counts: o.raw_counts,
            unwrapped: o.unwrapped,
        }),
        System::Duffing(_) => None,
    };
    let gaps = match rig.gaps {
        Some(g) => Some(GapsInfo {
            count: g.count(),
            length: g.length(),
            starts: g.starts(config.samples()).map_err(on("gaps"))?,
        }),
        None => None,
    };
    Ok(Truth {
        format: "hbid-truth",
        version: 1,
        system: rig.system.name(),
        equation: rig.system.equation(),
        parameters,
        forcing: o.drive.name(),
        identify: hint,
        coefficients: Ordered(coefficients),
        time_unit: if o.drive_frequency.is_some() {
            "s"
        } else {
            "nondimensional"
        },
        drive_frequency: o.drive_frequency,
        forcing_period: config.drive_period(),
        time_scale: rig.frame.rate(),
        drive_phase_at_zero: at_zero,
        drive_phase_at_first_sample: rig.first_phase,
        time_origin: o.time_origin.name(),
        first_sample_time,
        sample_step: step,
        sample_rate: 1.0 / step,
        samples_per_period: config.drive_period() / step,
        samples_simulated: config.samples(),
        rows,
        columns,
        transient_periods: config.transient_periods(),
        initial: config.initial(),
        noise_sigma: sigma,
        encoder: encoder_info,
        gaps,
        seed: o.seed,
        time_decimals: o.time_decimals,
        decimals: o.decimals,
    })
}

/// Writes `truth` as JSON, atomically.
pub fn write_truth(truth: &Truth, path: &Path) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(truth).map_err(|e| OptionError::new("truth", e))?;
    Ok(write_atomically(path, |w: &mut dyn Write| writeln!(w, "{text}"))?)
}

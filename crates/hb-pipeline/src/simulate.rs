//! The simulate request: a forced oscillator sampled as a rig records it, as `hbid simulate` and
//! Python's `hbid.simulate` make it (defaults: the paper's data set).
//!
//! The simulation, the time frame and every encoder effect are `pendulum_sim`'s
//! ([`InFrame`], [`Encoder`], [`Gaps`], [`Jitter`]); this module only composes them from the
//! options ([`SimulateOptions`] → [`Rig`], every combination checked), runs it ([`simulate`]) and
//! writes the record and its true equation ([`Simulation::write`], [`Simulation::truth`]).
//!
//! Besides the one-coordinate pendulum and Duffing oscillator, three systems of two coordinates
//! ([`SystemKind`]): the base-excited double pendulum, the torque-driven arm and two coupled
//! Duffing oscillators. Their records hold every coordinate, then every velocity, then the drives
//! that are measured inputs; each angle has its own encoder of the same settings, drawing from its
//! own stream of the seed, so that the coordinates' errors differ while a seed gives one record.
//! Their true equations are the simulator's (`normalised_equations`), read into the record's names
//! and frame by `pendulum_sim::truth::system_equations`, never written here.

use std::f64::consts::{FRAC_PI_2, TAU};
use std::fmt;
use std::io::Write;
use std::ops::ControlFlow;
use std::path::Path;
use std::str::FromStr;

use circle_signal::Domain;
use hb_basis::{Harmonic, Polynomial};
use hb_model::{Forcing, ModelForm, Names};
use npyz::WriterBuilder;
use pendulum_sim::TrueEquation;
use pendulum_sim::observe::{AngleRange, Encoder, EncoderReader, Gaps, Jitter};
use pendulum_sim::{
    ArmParameters, BaseAcceleration, CoupledDuffing, DoublePendulum, DriveHarmonic, DriveHarmonics, Duffing,
    InFrame, Losses, MultiConfig, MultiState, MultiSystem, Pendulum, RecordFrame, SimError, SimulationConfig,
    Sinusoid, SyntheticDrive, Tolerances, Torque, TorqueDoublePendulum, simulate_while,
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
        /// The double pendulum whose pivot is shaken horizontally like the paper's pendulum
        /// (`pendulum_sim::DoublePendulum`), the absolute angles of its links from the hanging
        /// position (columns `t,theta1,theta2,omega1,omega2`, and `p` with `write_drive`).
        DoublePendulum = "double-pendulum",
        /// The double pendulum driven by a torque at each joint like a robot arm, the DFKI
        /// acrobot/pendubot (`pendulum_sim::TorqueDoublePendulum`), in seconds: the shoulder angle
        /// and the elbow angle relative to link 1 (columns `t,q1,q2,v1,v2,tau1,tau2`).
        Arm = "arm",
        /// Two two-well Duffing oscillators coupled by a spring on a shaken base
        /// (`pendulum_sim::CoupledDuffing`), the base's acceleration measured (columns
        /// `t,x1,x2,v1,v2,a`; never wrapped).
        CoupledDuffing = "coupled-duffing",
    }
);

impl SystemKind {
    /// The number of coordinates.
    pub fn coordinates(self) -> usize {
        match self {
            Self::Pendulum | Self::Duffing => 1,
            Self::DoublePendulum | Self::Arm | Self::CoupledDuffing => 2,
        }
    }

    /// Whether the coordinates are angles (on the circle) rather than positions on the line.
    pub fn domain(self) -> Domain {
        match self {
            Self::Duffing | Self::CoupledDuffing => Domain::Line,
            _ => Domain::Circle,
        }
    }

    /// The names of the record's columns: the coordinates, their velocities, and the drives the
    /// record may hold (written always for a measured input, with `write_drive` otherwise).
    fn column_names(
        self,
    ) -> (
        &'static [&'static str],
        &'static [&'static str],
        &'static [&'static str],
    ) {
        match self {
            Self::Pendulum => (&["theta"], &["omega"], &["p"]),
            Self::Duffing => (&["x"], &["v"], &["p"]),
            Self::DoublePendulum => (&["theta1", "theta2"], &["omega1", "omega2"], &["p"]),
            Self::Arm => (&["q1", "q2"], &["v1", "v2"], &["tau1", "tau2"]),
            Self::CoupledDuffing => (&["x1", "x2"], &["v1", "v2"], &["a"]),
        }
    }

    /// Whether the drives are measured inputs, written always (the arm's torques, the coupled
    /// oscillators' base acceleration).
    fn measured_input(self) -> bool {
        matches!(self, Self::Arm | Self::CoupledDuffing)
    }
}

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

/// A sinusoidal torque as text, `A:OMEGA[:PHASE]`: `A sin(OMEGA t + PHASE)` in N m, `OMEGA` in
/// rad/s, `PHASE` in radians (default 0); or `none` for no torque.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorqueText(pub Option<Sinusoid>);

impl FromStr for TorqueText {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        if text.trim() == "none" {
            return Ok(Self(None));
        }
        let parts: Vec<&str> = text.split(':').map(str::trim).collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(
                "expected A:OMEGA[:PHASE] (N m, rad/s, rad), e.g. 0.4:10 or 0.8:10:1.5708, or none"
                    .to_owned(),
            );
        }
        let number = |s: &str| s.parse::<f64>().map_err(|_| format!("'{s}' is not a number"));
        let phase = match parts.get(2) {
            Some(p) => number(p)?,
            None => 0.0,
        };
        Sinusoid::new(number(parts[0])?, number(parts[1])?, phase)
            .map(|s| Self(Some(s)))
            .map_err(|e| e.to_string())
    }
}

impl fmt::Display for TorqueText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            None => f.write_str("none"),
            Some(s) => write!(f, "{}:{}:{}", s.amplitude(), s.angular_frequency(), s.phase()),
        }
    }
}

/// Numbers as text, `A,B,...` (from Python also a list of numbers, or one number).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Numbers(pub Vec<f64>);

impl FromStr for Numbers {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        text.split(',')
            .map(|s| {
                s.trim().parse::<f64>().map_err(|_| {
                    format!(
                        "'{}' is not a number (expected numbers separated by commas)",
                        s.trim()
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Self)
    }
}

impl fmt::Display for Numbers {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let texts: Vec<String> = self.0.iter().map(ToString::to_string).collect();
        f.write_str(&texts.join(","))
    }
}

impl Serialize for Numbers {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Numbers {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde_json::Value;
        let number = |v: &Value| {
            v.as_f64()
                .ok_or_else(|| serde::de::Error::custom(format!("expected a number, found {v}")))
        };
        match Value::deserialize(d)? {
            Value::String(s) => s.parse().map_err(serde::de::Error::custom),
            Value::Array(items) => items.iter().map(number).collect::<Result<_, _>>().map(Self),
            v @ Value::Number(_) => Ok(Self(vec![number(&v)?])),
            other => Err(serde::de::Error::custom(format!(
                "expected numbers (a list, or a text such as '1,0'), found {other}"
            ))),
        }
    }
}

/// Every option of `hbid simulate`, by the names of the command line (`_` for `-`) and of
/// Python's keyword arguments, with their defaults (the paper's data set: 30000 samples, 25 per
/// drive period 2π, after 200 periods, the angle wrapped into `[−π, π)`). Checked by
/// [`Rig::new`]; an option of one system set for another is refused, naming the systems it
/// belongs to.
///
/// The systems of two coordinates default to: the double pendulum whirling
/// (`DoublePendulum::WHIRLING`) from rest at `(2, 0)`, 30000 samples at 64 per drive period after
/// 200 periods; the arm with DFKI design A.0's published parameters (its dry friction on), the
/// torques of the DFKI record 00 (`0.4 sin 10t` at the shoulder, `0.8 cos 10t` at the elbow), from
/// rest hanging, 5000 samples at 500 Hz from `t = 0`; the coupled oscillators
/// (`CoupledDuffing::TWO_WELLS`) shaken by the built-in drive of seed 1 from rest at `(1, −0.9)`,
/// 30000 samples at 32 per period 2π of the drive's first tone after 200 of them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SimulateOptions {
    /// The system.
    #[serde(with = "text")]
    pub system: SystemKind,
    /// Drive amplitude `f` (default 1.52 for the pendulum, 0.3 for the Duffing oscillator, 0.6
    /// for the double pendulum).
    pub f: Option<f64>,
    /// Damping `c` (default 0.03 for the pendulum, 0.25 for the Duffing oscillator); of link 1
    /// or oscillator 1 of a system (default 0.05 for the double pendulum, 0.25 for the coupled
    /// oscillators).
    pub c: Option<f64>,
    /// Damping `c2` of link 2 or oscillator 2 (default 0.05 for the double pendulum, 0.2 for the
    /// coupled oscillators).
    pub c2: Option<f64>,
    /// Pendulum: frequency ratio `r`, stiffness `1/r²` (default 0.8333); double pendulum: `ω² =
    /// 1/r²` (default `ω² = 0.8`).
    pub r: Option<f64>,
    /// Duffing: linear stiffness `a` (default −1; −1 for oscillator 1 of the coupled ones).
    pub a: Option<f64>,
    /// Duffing: cubic stiffness `b` (default 1; 1 for oscillator 1 of the coupled ones).
    pub b: Option<f64>,
    /// Coupled oscillators: linear stiffness `a2` of oscillator 2 (default −0.8).
    pub a2: Option<f64>,
    /// Coupled oscillators: cubic stiffness `b2` of oscillator 2 (default 1.2).
    pub b2: Option<f64>,
    /// Coupled oscillators: the coupling spring's stiffness `k` (default 0.3).
    pub coupling: Option<f64>,
    /// Coupled oscillators: the coupling spring's cubic part `k3` (default 0.05).
    pub coupling_cubic: Option<f64>,
    /// Coupled oscillators: the mass ratio `m2/m1` (default 1).
    pub mass_ratio: Option<f64>,
    /// Coupled oscillators: the seed of the built-in base acceleration (default 1).
    pub drive_seed: Option<u64>,
    /// Double pendulum: the mass ratio `μ = m2/(m1+m2)` (default 0.5).
    pub mu: Option<f64>,
    /// Double pendulum: the length ratio `λ = l2/l1` (default 1).
    pub length_ratio: Option<f64>,
    /// Arm: the torque at the shoulder, sinusoids `A:OMEGA[:PHASE]` (N m, rad/s, rad) added, or
    /// `none` (default `0.4:10`).
    #[serde(with = "text_list")]
    pub torque1: Vec<TorqueText>,
    /// Arm: the torque at the elbow (default `0.8:10:π/2`, `0.8 cos 10t`).
    #[serde(with = "text_list")]
    pub torque2: Vec<TorqueText>,
    /// Arm: the viscous friction of the joints `b1,b2` in N m s/rad (default the published
    /// 0.001,0.001).
    pub joint_damping: Option<Numbers>,
    /// Arm: the dry friction of the joints `cf1,cf2` in N m (default the published 0.093,0.078;
    /// `0,0` for none).
    pub joint_friction: Option<Numbers>,
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
    /// A system's initial coordinates at the start of the integration, one per coordinate.
    pub q0: Option<Numbers>,
    /// A system's initial velocities, one per coordinate, in the record's time unit (default
    /// at rest).
    pub dq0: Option<Numbers>,
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
    /// Gaussian jitter of the written time stamps (standard deviation in the record's time unit);
    /// the samples are those of the grid's instants.
    pub jitter: Option<f64>,
    /// Time stamps printed with this many decimals.
    pub time_decimals: Option<usize>,
    /// Angle (or displacement) and velocity printed with this many decimals.
    pub decimals: Option<usize>,
    /// Also write the drive `p(t)` as a column `p` (the arm's and the coupled oscillators' drives
    /// are written always).
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
            c2: None,
            r: None,
            a: None,
            b: None,
            a2: None,
            b2: None,
            coupling: None,
            coupling_cubic: None,
            mass_ratio: None,
            drive_seed: None,
            mu: None,
            length_ratio: None,
            torque1: Vec::new(),
            torque2: Vec::new(),
            joint_damping: None,
            joint_friction: None,
            friction: None,
            drag: None,
            cubic_damping: None,
            drive_harmonic: Vec::new(),
            drive: DriveKind::Drive,
            x0: 0.1,
            v0: 0.0,
            q0: None,
            dq0: None,
            rtol: pendulum_sim::Tolerances::DEFAULT_RTOL,
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
            jitter: None,
            time_decimals: None,
            decimals: None,
            write_drive: false,
        }
    }
}

/// Why an option of a built-in system is refused with a saved model, after the option's name.
pub const MODEL_TAKES_NO_RIG: &str = "is an option of a built-in system: a saved model («model») takes only the input's options, «x0», «v0» (a system's «q0», «dq0») and «rtol»";

/// With a saved model the initial state is fitted to the input's first samples unless `init` is 0
/// (`state_given`): an `x0` or `v0` set away from its default without it would be ignored, and
/// is refused instead.
pub fn check_model_state(rig: &SimulateOptions, state_given: bool) -> Result<(), OptionError> {
    let d = SimulateOptions::default();
    let set = [
        ("x0", rig.x0 != d.x0),
        ("v0", rig.v0 != d.v0),
        ("q0", rig.q0.is_some()),
        ("dq0", rig.dq0.is_some()),
    ];
    if let Some(&(name, _)) = set.iter().find(|(_, set)| *set)
        && !state_given
    {
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
    /// `v0`, `q0`, `dq0` and `rtol`): what a saved model's run under a record's input (`hbid simulate --model`)
    /// does not take.
    pub fn rig_settings(&self) -> Vec<String> {
        let (Ok(serde_json::Value::Object(now)), Ok(serde_json::Value::Object(default))) =
            (serde_json::to_value(self), serde_json::to_value(Self::default()))
        else {
            return Vec::new();
        };
        now.into_iter()
            .filter(|(k, v)| {
                !matches!(k.as_str(), "x0" | "v0" | "q0" | "dq0" | "rtol") && default.get(k) != Some(v)
            })
            .map(|(k, _)| k)
            .collect()
    }
}

/// Decimals beyond which printing gains nothing an `f64` holds.
const MAX_DECIMALS: usize = 30;

/// The system chosen, with its parameters checked.
#[derive(Debug, Clone)]
pub enum System {
    /// The pendulum.
    Pendulum(Pendulum),
    /// The Duffing oscillator.
    Duffing(Duffing),
    /// The base-excited double pendulum.
    DoublePendulum(DoublePendulum),
    /// The torque-driven double pendulum.
    Arm(TorqueDoublePendulum),
    /// The coupled Duffing oscillators.
    CoupledDuffing(CoupledDuffing),
}

impl System {
    fn name(&self) -> &'static str {
        match self {
            Self::Pendulum(_) => "pendulum",
            Self::Duffing(_) => "duffing",
            Self::DoublePendulum(_) => "double-pendulum",
            Self::Arm(_) => "arm",
            Self::CoupledDuffing(_) => "coupled-duffing",
        }
    }

    /// The equation in the model's own time, with the rig's terms that are present.
    fn equation(&self) -> String {
        let (losses, harmonics) = match self {
            Self::Pendulum(p) => (*p.losses(), *p.drive_harmonics()),
            Self::Duffing(d) => (*d.losses(), *d.drive_harmonics()),
            Self::DoublePendulum(p) => {
                let text = "theta1'' + mu lambda theta2'' cos(theta1-theta2) + mu lambda theta2'^2 sin(theta1-theta2) \
                        + omega2 sin theta1 - f sin(t) cos theta1 + c1 theta1' = 0; theta2'' + (1/lambda) theta1'' \
                        cos(theta1-theta2) - (1/lambda) theta1'^2 sin(theta1-theta2) + (omega2/lambda) sin theta2 \
                        - (f/lambda) sin(t) cos theta2 + c2 theta2' = 0 (omega2 = 1/r^2)";
                return if p.drive_harmonics().is_none() {
                    text.to_owned()
                } else {
                    text.replace("f sin(t)", "f [sin(t) + sum_k ratio_k sin(k t + phase_k)]")
                        .replace(
                            "(f/lambda) sin(t)",
                            "(f/lambda) [sin(t) + sum_k ratio_k sin(k t + phase_k)]",
                        )
                };
            }
            Self::Arm(_) => {
                return "M(q) q'' + C(q, q') q' - G(q) + b q' + cf sign(q') = tau, in seconds, q1 the shoulder angle \
                        from hanging and q2 the elbow angle relative to link 1 (DFKI's model with sign(q') for \
                        atan(100 q'))"
                    .to_owned();
            }
            Self::CoupledDuffing(_) => {
                return "x1'' + c1 x1' + a1 x1 + b1 x1^3 + k (x1 - x2) + k3 (x1 - x2)^3 + a(t) = 0; x2'' + c2 x2' \
                        + a2 x2 + b2 x2^3 - (k/rho) (x1 - x2) - (k3/rho) (x1 - x2)^3 + a(t) = 0 (a the base's \
                        acceleration, rho = m2/m1)"
                    .to_owned();
            }
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
            (_, false) => format!("x'' + {dissipation} + a x + b x^3 = f cos(t)"),
            (_, true) => {
                format!("x'' + {dissipation} + a x + b x^3 = f [cos(t) + sum_k ratio_k cos(k t + phase_k)]")
            }
        }
    }

    /// The system of several coordinates, if it is one.
    fn multi(&self) -> Option<&dyn MultiSystem> {
        match self {
            Self::Pendulum(_) | Self::Duffing(_) => None,
            Self::DoublePendulum(p) => Some(p),
            Self::Arm(a) => Some(a),
            Self::CoupledDuffing(d) => Some(d),
        }
    }

    /// The drives as they enter the equations, in the record's frame `frame` (the system's time
    /// `frame.system_time(t)`), at the time `t`, into `out`: a drive that is an acceleration (a base's, or
    /// the forcing of the Duffing oscillator) is `rate²` times the system's, the arm's torques
    /// are in N m at seconds already.
    fn drives_at(&self, frame: &RecordFrame, t: f64, out: &mut Vec<f64>) {
        out.clear();
        let rate2 = frame.rate() * frame.rate();
        let tau = frame.system_time(t);
        match self {
            Self::Pendulum(p) => out.push(rate2 * p.drive(tau)),
            Self::Duffing(d) => out.push(rate2 * d.drive(tau)),
            Self::DoublePendulum(p) => out.push(rate2 * p.drive(tau)),
            Self::Arm(a) => out.extend(a.torques().iter().map(|torque| torque.at(t))),
            Self::CoupledDuffing(d) => out.push(rate2 * d.drive().at(tau)),
        }
    }

    /// The parameters, as the simulator serialises them.
    fn parameters(&self) -> Result<serde_json::Value, serde_json::Error> {
        match self {
            Self::Pendulum(p) => serde_json::to_value(p),
            Self::Duffing(d) => serde_json::to_value(d),
            Self::DoublePendulum(p) => serde_json::to_value(p),
            Self::Arm(a) => serde_json::to_value(a),
            Self::CoupledDuffing(d) => serde_json::to_value(d),
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
    /// The encoder of the angle, or of each angle from its own stream of the seed.
    encoder: Option<Encoder>,
    gaps: Option<Gaps>,
    jitter: Option<Jitter>,
    /// The initial state of a system of several coordinates.
    initial: Option<MultiState>,
}

/// Wraps a library error as the error of `option`.
fn on<E: std::error::Error>(option: &'static str) -> impl Fn(E) -> OptionError {
    move |e| OptionError::new(option, chain(&e))
}

/// A library's check of a parameter as the error of the option that set it (`names`: the
/// library's name of each parameter and the option's), other errors as the system's.
fn parameter(names: &'static [(&'static str, &'static str)]) -> impl Fn(SimError) -> OptionError {
    move |e| match e {
        SimError::InvalidParameter { name, value, why } => match names.iter().find(|(n, _)| *n == name) {
            Some((_, option)) => OptionError::value(*option, value, why),
            None => OptionError::new("system", chain(&e)),
        },
        e => OptionError::new("system", chain(&e)),
    }
}

/// The double pendulum's defaults: from rest with link 1 at 2 rad, as
/// `DoublePendulum::whirling` is documented, 64 samples per drive period (no angle moves more than
/// 0.45 rad between samples).
const DOUBLE_PENDULUM_START: [f64; 2] = [2.0, 0.0];
const DOUBLE_PENDULUM_SAMPLES_PER_PERIOD: usize = 64;
/// The coupled oscillators' defaults: from rest at `(1, −0.9)`, as `CoupledDuffing::two_wells` is
/// documented; 32 samples per period `2π` of the drive's first tone, about 7 per period of the
/// fastest part of its noise (angular frequency 3).
const COUPLED_DUFFING_START: [f64; 2] = [1.0, -0.9];
const COUPLED_DUFFING_SAMPLES_PER_PERIOD: usize = 32;
const COUPLED_DUFFING_DRIVE_SEED: u64 = 1;
/// The arm's defaults, those of DFKI's records: from rest hanging, 5000 samples at 500 Hz, the
/// torques of record 00 (`0.4 sin 10t` at the shoulder, `0.8 cos 10t` at the elbow).
const ARM_SAMPLE_RATE: f64 = 500.0;
const ARM_SAMPLES: usize = 5000;
const ARM_TORQUES: [(f64, f64, f64); 2] = [(0.4, 10.0, 0.0), (0.8, 10.0, FRAC_PI_2)];

/// The systems an option set away from its default belongs to, and what it is; an option of
/// one system set for another is refused, naming those it belongs to.
fn check_belongs(o: &SimulateOptions) -> Result<(), OptionError> {
    use SystemKind::{Arm, CoupledDuffing, DoublePendulum, Duffing, Pendulum};
    let d = SimulateOptions::default();
    const PERIODIC: &[SystemKind] = &[Pendulum, Duffing, DoublePendulum, CoupledDuffing];
    const ANGLES: &[SystemKind] = &[Pendulum, DoublePendulum, Arm];
    const ONE: &[SystemKind] = &[Pendulum, Duffing];
    const SYSTEMS: &[SystemKind] = &[DoublePendulum, Arm, CoupledDuffing];
    let encoder = "an angle encoder's, for a pendulum only (also «system=double-pendulum» or «system=arm»): a \
                   displacement takes «noise»";
    let table: [(&str, bool, &[SystemKind], &str); 32] = [
        (
            "f",
            o.f.is_some(),
            &[Pendulum, Duffing, DoublePendulum],
            "the periodic drive's amplitude",
        ),
        (
            "c",
            o.c.is_some(),
            PERIODIC,
            "a damping in the model's time (the arm's is «joint_damping»)",
        ),
        (
            "c2",
            o.c2.is_some(),
            &[DoublePendulum, CoupledDuffing],
            "the damping of link 2 or oscillator 2",
        ),
        (
            "r",
            o.r.is_some(),
            &[Pendulum, DoublePendulum],
            "the pendulum's frequency ratio",
        ),
        (
            "a",
            o.a.is_some(),
            &[Duffing, CoupledDuffing],
            "a stiffness of the Duffing oscillator",
        ),
        (
            "b",
            o.b.is_some(),
            &[Duffing, CoupledDuffing],
            "a stiffness of the Duffing oscillator",
        ),
        (
            "a2",
            o.a2.is_some(),
            &[CoupledDuffing],
            "a stiffness of the coupled Duffing oscillator 2",
        ),
        (
            "b2",
            o.b2.is_some(),
            &[CoupledDuffing],
            "a stiffness of the coupled Duffing oscillator 2",
        ),
        (
            "coupling",
            o.coupling.is_some(),
            &[CoupledDuffing],
            "the coupling spring's stiffness",
        ),
        (
            "coupling_cubic",
            o.coupling_cubic.is_some(),
            &[CoupledDuffing],
            "the coupling spring's cubic part",
        ),
        (
            "mass_ratio",
            o.mass_ratio.is_some(),
            &[CoupledDuffing],
            "the coupled oscillators' mass ratio",
        ),
        (
            "drive_seed",
            o.drive_seed.is_some(),
            &[CoupledDuffing],
            "the seed of the built-in base acceleration",
        ),
        (
            "mu",
            o.mu.is_some(),
            &[DoublePendulum],
            "the double pendulum's mass ratio m2/(m1+m2)",
        ),
        (
            "length_ratio",
            o.length_ratio.is_some(),
            &[DoublePendulum],
            "the double pendulum's length ratio",
        ),
        (
            "torque1",
            !o.torque1.is_empty(),
            &[Arm],
            "a torque at a joint of the arm",
        ),
        (
            "torque2",
            !o.torque2.is_empty(),
            &[Arm],
            "a torque at a joint of the arm",
        ),
        (
            "joint_damping",
            o.joint_damping.is_some(),
            &[Arm],
            "the viscous friction of the arm's joints",
        ),
        (
            "joint_friction",
            o.joint_friction.is_some(),
            &[Arm],
            "the dry friction of the arm's joints",
        ),
        (
            "friction",
            o.friction.is_some(),
            ONE,
            "a loss of a system of one coordinate",
        ),
        (
            "drag",
            o.drag.is_some(),
            ONE,
            "a loss of a system of one coordinate",
        ),
        (
            "cubic_damping",
            o.cubic_damping.is_some(),
            ONE,
            "a loss of a system of one coordinate",
        ),
        (
            "drive_harmonic",
            !o.drive_harmonic.is_empty(),
            &[Pendulum, Duffing, DoublePendulum],
            "a harmonic of a periodic drive",
        ),
        (
            "drive",
            o.drive != d.drive,
            &[Pendulum, Duffing, DoublePendulum],
            "the periodic drive's switch",
        ),
        (
            "x0",
            o.x0 != d.x0,
            ONE,
            "the initial state of one coordinate (a system's is «q0»)",
        ),
        (
            "v0",
            o.v0 != d.v0,
            ONE,
            "the initial state of one coordinate (a system's is «dq0»)",
        ),
        (
            "q0",
            o.q0.is_some(),
            SYSTEMS,
            "the initial state of a system (one coordinate's is «x0»)",
        ),
        (
            "dq0",
            o.dq0.is_some(),
            SYSTEMS,
            "the initial state of a system (one coordinate's is «v0»)",
        ),
        (
            "drive_frequency",
            o.drive_frequency.is_some(),
            PERIODIC,
            "the time scale of a periodic drive (the arm's time is seconds)",
        ),
        (
            "samples_per_period",
            o.samples_per_period.is_some(),
            PERIODIC,
            "the sampling of a periodic drive (the arm's is «sample_rate»)",
        ),
        (
            "transient_periods",
            o.transient_periods.is_some(),
            PERIODIC,
            "drive periods dropped first (the arm starts at rest at t = 0)",
        ),
        (
            "phase",
            o.phase != d.phase,
            PERIODIC,
            "the drive's phase at the first sample",
        ),
        (
            "raw_counts",
            o.raw_counts,
            &[Pendulum],
            "the one angle's counts in one column",
        ),
    ];
    for (name, set, systems, what) in table {
        if set && !systems.contains(&o.system) {
            let names: Vec<String> = systems.iter().map(|s| format!("«system={}»", s.name())).collect();
            let list = match names.split_last() {
                Some((last, [])) => last.clone(),
                Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                None => String::new(),
            };
            return Err(OptionError::sentence(name, format!("is {what} ({list})")));
        }
    }
    for (name, set) in [
        ("counts", o.counts.is_some()),
        ("zero_offset", o.zero_offset.is_some()),
        ("bit_errors", o.bit_errors.is_some()),
        ("angle_range", o.angle_range.is_some()),
    ] {
        if set && !ANGLES.contains(&o.system) {
            return Err(OptionError::sentence(name, format!("is {encoder}")));
        }
    }
    Ok(())
}

/// Two numbers of an option, or the defaults.
fn pair(name: &'static str, given: &Option<Numbers>, default: [f64; 2]) -> Result<[f64; 2], OptionError> {
    match given {
        None => Ok(default),
        Some(Numbers(v)) => match v.as_slice() {
            &[a, b] => Ok([a, b]),
            _ => Err(OptionError::value(
                name,
                Numbers(v.clone()),
                "give two numbers, one per coordinate or joint",
            )),
        },
    }
}

/// An arm's torque: the sinusoids given, or the default.
fn torque(name: &'static str, given: &[TorqueText], default: (f64, f64, f64)) -> Result<Torque, OptionError> {
    if given.is_empty() {
        let (a, w, phase) = default;
        return Torque::sinusoid(a, w, phase).map_err(on(name));
    }
    let sinusoids: Vec<Sinusoid> = given.iter().filter_map(|t| t.0).collect();
    if sinusoids.is_empty() {
        return Ok(Torque::None);
    }
    if sinusoids.len() != given.len() {
        return Err(OptionError::sentence(
            name,
            "none is no torque: not with sinusoids",
        ));
    }
    Ok(Torque::Sinusoids(sinusoids))
}

impl Rig {
    /// Checks `options`, alone and together.
    pub fn new(options: SimulateOptions) -> Result<Self, OptionError> {
        let system = Self::system(&options)?;
        let (frame, config, first_phase) = Self::timing(&options)?;
        let encoder = Self::encoder(&options)?;
        let initial = Self::initial(&options)?;
        let gaps = options.gaps.map(|g| g.0.seeded(options.seed));
        let jitter = options
            .jitter
            .map(|sigma| Jitter::new(sigma).map(|j| j.seeded(options.seed)))
            .transpose()
            .map_err(on("jitter"))?;
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
            jitter,
            initial,
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
    pub fn system_kind(&self) -> &System {
        &self.system
    }

    /// The simulation's configuration (sampling, transient, tolerances).
    pub fn config(&self) -> &SimulationConfig {
        &self.config
    }

    fn system(o: &SimulateOptions) -> Result<System, OptionError> {
        check_belongs(o)?;
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
                let (f, c, r) = Pendulum::PAPER;
                System::Pendulum(
                    Pendulum::new(amplitude(f), o.c.unwrap_or(c), o.r.unwrap_or(r))
                        .map_err(on("system"))?
                        .with_losses(losses)
                        .with_drive_harmonics(harmonics),
                )
            }
            SystemKind::Duffing => {
                let (c, a, b, f) = Duffing::TWO_WELL;
                System::Duffing(
                    Duffing::new(o.c.unwrap_or(c), o.a.unwrap_or(a), o.b.unwrap_or(b), amplitude(f))
                        .map_err(on("system"))?
                        .with_losses(losses)
                        .with_drive_harmonics(harmonics),
                )
            }
            SystemKind::DoublePendulum => {
                let (mu, lambda, omega2, f, c1, c2) = DoublePendulum::WHIRLING;
                let omega2 = match o.r {
                    None => omega2,
                    Some(r) if r.is_finite() && r > 0.0 => 1.0 / (r * r),
                    Some(r) => return Err(OptionError::value("r", r, "must be positive and finite")),
                };
                let names = &[
                    ("mu", "mu"),
                    ("lambda", "length_ratio"),
                    ("omega2", "r"),
                    ("f", "f"),
                    ("c1", "c"),
                    ("c2", "c2"),
                ];
                // The model allows μ = 1 (a massless first link, its mass matrix singular with the
                // links in line); a simulation would stop where they come in line.
                if o.mu == Some(1.0) {
                    return Err(OptionError::value(
                        "mu",
                        1.0,
                        "must lie in [0, 1): at 1 the first link has no mass and the links in line cannot be moved",
                    ));
                }
                System::DoublePendulum(
                    DoublePendulum::new(
                        o.mu.unwrap_or(mu),
                        o.length_ratio.unwrap_or(lambda),
                        omega2,
                        amplitude(f),
                        o.c.unwrap_or(c1),
                        o.c2.unwrap_or(c2),
                    )
                    .map_err(parameter(names))?
                    .with_drive_harmonics(harmonics),
                )
            }
            SystemKind::Arm => {
                let published = ArmParameters::DFKI_A0;
                let [b1, b2] = pair("joint_damping", &o.joint_damping, [published.b1, published.b2])?;
                let [cf1, cf2] = pair(
                    "joint_friction",
                    &o.joint_friction,
                    [published.cf1, published.cf2],
                )?;
                let names = &[
                    ("b1", "joint_damping"),
                    ("b2", "joint_damping"),
                    ("cf1", "joint_friction"),
                    ("cf2", "joint_friction"),
                ];
                let arm = TorqueDoublePendulum::new(ArmParameters {
                    b1,
                    b2,
                    cf1,
                    cf2,
                    ..published
                })
                .map_err(parameter(names))?;
                System::Arm(arm.with_torques(
                    torque("torque1", &o.torque1, ARM_TORQUES[0])?,
                    torque("torque2", &o.torque2, ARM_TORQUES[1])?,
                ))
            }
            SystemKind::CoupledDuffing => {
                let (c, a, b, k, k3) = CoupledDuffing::TWO_WELLS;
                let names = &[
                    ("c1", "c"),
                    ("c2", "c2"),
                    ("a1", "a"),
                    ("a2", "a2"),
                    ("b1", "b"),
                    ("b2", "b2"),
                    ("k", "coupling"),
                    ("k3", "coupling_cubic"),
                    ("mass ratio", "mass_ratio"),
                ];
                let drive =
                    SyntheticDrive::incommensurate(o.drive_seed.unwrap_or(COUPLED_DUFFING_DRIVE_SEED));
                System::CoupledDuffing(
                    CoupledDuffing::new(
                        [o.c.unwrap_or(c[0]), o.c2.unwrap_or(c[1])],
                        [o.a.unwrap_or(a[0]), o.a2.unwrap_or(a[1])],
                        [o.b.unwrap_or(b[0]), o.b2.unwrap_or(b[1])],
                        o.coupling.unwrap_or(k),
                        o.coupling_cubic.unwrap_or(k3),
                        BaseAcceleration::Synthetic(drive),
                    )
                    .and_then(|d| d.with_mass_ratio(o.mass_ratio.unwrap_or(1.0)))
                    .map_err(parameter(names))?,
                )
            }
        })
    }

    /// The initial state of a system of several coordinates (`None` for one coordinate, whose
    /// state is `x0`, `v0`).
    fn initial(o: &SimulateOptions) -> Result<Option<MultiState>, OptionError> {
        let start = match o.system {
            SystemKind::Pendulum | SystemKind::Duffing => return Ok(None),
            SystemKind::DoublePendulum => DOUBLE_PENDULUM_START,
            SystemKind::Arm => [0.0; 2],
            SystemKind::CoupledDuffing => COUPLED_DUFFING_START,
        };
        let q = pair("q0", &o.q0, start)?;
        let v = pair("dq0", &o.dq0, [0.0; 2])?;
        let names = &[("initial coordinate", "q0"), ("initial velocity", "dq0")];
        MultiState::new(&q, &v).map(Some).map_err(parameter(names))
    }

    fn timing(o: &SimulateOptions) -> Result<(RecordFrame, SimulationConfig, f64), OptionError> {
        if o.system == SystemKind::Arm {
            return Self::arm_timing(o);
        }
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
            (None, None) => {
                let own = match o.system {
                    SystemKind::DoublePendulum => Some(DOUBLE_PENDULUM_SAMPLES_PER_PERIOD),
                    SystemKind::CoupledDuffing => Some(COUPLED_DUFFING_SAMPLES_PER_PERIOD),
                    _ => None,
                };
                if let Some(p) = own {
                    config = config
                        .with_samples_per_period(p)
                        .map_err(|e| OptionError::checked("samples_per_period", p, &e))?;
                }
            }
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

    /// The arm's time and sampling: seconds from `t = 0`, the first sample the initial state (no
    /// drive period, so no transient and no phase), at `sample_rate` (default 500 Hz).
    fn arm_timing(o: &SimulateOptions) -> Result<(RecordFrame, SimulationConfig, f64), OptionError> {
        let rate = o.sample_rate.unwrap_or(ARM_SAMPLE_RATE);
        if !(rate.is_finite() && rate > 0.0) {
            return Err(OptionError::value(
                "sample_rate",
                rate,
                "must be positive and finite",
            ));
        }
        // The configuration's drive period is a unit of nothing here: a second.
        let config = SimulationConfig::paper()
            .with_drive_period(1.0)
            .and_then(|c| c.with_sample_step(1.0 / rate))
            .map_err(|e| OptionError::checked("sample_rate", rate, &e))?;
        let samples = match (o.samples, o.duration) {
            (Some(_), Some(_)) => {
                return Err(OptionError::sentence(
                    "samples",
                    "and «duration» both set: give one",
                ));
            }
            (Some(n), None) => n,
            (None, Some(d)) => samples_in(d, config.sample_step())?,
            (None, None) => ARM_SAMPLES,
        };
        let config = config
            .with_samples(samples)
            .map_err(|e| OptionError::checked("samples", samples, &e))?
            .with_transient_periods(0)
            .with_phase(0.0)
            .map_err(|e| OptionError::checked("phase", 0.0, &e))?
            .with_tolerances(
                Tolerances::relative(o.rtol).map_err(|e| OptionError::checked("rtol", o.rtol, &e))?,
            );
        Ok((RecordFrame::nondimensional(), config, 0.0))
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
    /// The time stamps, as written (jittered with `jitter`; before printing with
    /// `time_decimals`).
    pub t: Vec<f64>,
    /// Each coordinate as recorded (the angle, displacement or counts; one for a system of one
    /// coordinate).
    pub coordinates: Vec<Reported>,
    /// Each coordinate's clean velocity, in the record's time unit.
    pub velocities: Vec<Vec<f64>>,
    /// Each drive as it enters the equations, in the record's time unit, written or not
    /// ([`Simulation::columns`] says): `p(t)` of a system of one coordinate or of the double
    /// pendulum, the arm's torques `tau1`, `tau2`, the coupled oscillators' base acceleration `a`.
    pub drives: Vec<Vec<f64>>,
    /// Whether each sample is kept (`false` inside a gap).
    pub kept: Vec<bool>,
}

/// One cell of a coordinate's column as recorded: a number (radians or the displacement), or an
/// encoder's count.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Cell {
    Value(f64),
    Count(u32),
}

impl Cell {
    /// The number a reader of the printed cell gets.
    fn number(self, decimals: Option<usize>) -> f64 {
        match self {
            Self::Value(v) => printed(v, decimals),
            Self::Count(k) => f64::from(k),
        }
    }

    /// The cell as printed, onto `out`.
    fn print(self, decimals: Option<usize>, out: &mut String) {
        use std::fmt::Write as _;
        // Writing to a String cannot fail.
        let _ = match (self, decimals) {
            (Self::Value(v), Some(d)) => write!(out, "{v:.d$}"),
            (Self::Value(v), None) => write!(out, "{v}"),
            (Self::Count(k), _) => write!(out, "{k}"),
        };
    }
}

/// How a coordinate's simulated value becomes its column: as it is, wrapped, or through its
/// encoder (wrapped into its range, every turn kept, or the count).
enum Report {
    AsIs,
    Wrapped,
    Encoded(EncoderReader),
    Continuous(EncoderReader),
    Counts(EncoderReader),
}

impl Report {
    /// Coordinate `c`'s report of the rig's record.
    fn new(rig: &Rig, c: usize) -> Self {
        let o = &rig.options;
        match (&rig.system, rig.encoder) {
            (System::Pendulum(_), None) if o.unwrapped => Self::AsIs,
            (System::Pendulum(_), None) => Self::Wrapped,
            (System::Pendulum(_), Some(e)) if o.raw_counts => Self::Counts(e.reader()),
            (System::Pendulum(_), Some(e)) if o.unwrapped => Self::Continuous(e.reader()),
            (System::Pendulum(_), Some(e)) => Self::Encoded(e.reader()),
            (System::Duffing(_), None) => Self::AsIs,
            (System::Duffing(_), Some(e)) => Self::Continuous(e.reader()),
            (_, encoder) => {
                let wrapped = o.system.domain() == Domain::Circle && !o.unwrapped;
                // Each coordinate's encoder draws from its own stream of the seed.
                match (encoder.map(|e| e.with_stream(c as u64)), wrapped) {
                    (None, true) => Self::Wrapped,
                    (None, false) => Self::AsIs,
                    (Some(e), true) => Self::Encoded(e.reader()),
                    (Some(e), false) => Self::Continuous(e.reader()),
                }
            }
        }
    }

    /// The column's cell of the next sample, whose simulated value is `x`.
    fn cell(&mut self, x: f64) -> Cell {
        match self {
            Self::AsIs => Cell::Value(x),
            Self::Wrapped => Cell::Value(circle_signal::wrap(x)),
            Self::Encoded(r) => Cell::Value(r.observe(x)),
            Self::Continuous(r) => Cell::Value(r.observe_continuous(x)),
            Self::Counts(r) => Cell::Count(r.observe_count(x).expect("checked: «raw_counts» needs «counts»")),
        }
    }
}

/// One sample of a simulated record, as [`each_sample`] gives it.
struct Sample<'a> {
    /// Whether the record keeps it (`false` inside a gap).
    kept: bool,
    /// The time stamp as written (jittered; before printing).
    stamp: f64,
    /// Each coordinate's cell.
    coordinates: &'a [Cell],
    /// Each coordinate's clean velocity.
    velocities: &'a [f64],
    /// Each drive as it enters the equations.
    drives: &'a [f64],
}

/// Simulates `rig` and gives each sample to `sample` in order, holding none: the one way a
/// simulated record is made, whether it is kept ([`simulate`]) or written as it comes
/// ([`simulate_to`]). A sample that breaks ends the simulation there (a writer that failed).
/// `observer` hears the progress in samples.
fn each_sample(
    rig: &Rig,
    observer: &mut dyn Observer,
    mut sample: impl FnMut(&Sample<'_>) -> ControlFlow<()>,
) -> Result<(), RunError> {
    observer.stage(Stage::Simulate);
    let config = &rig.config;
    let samples = config.samples();
    let o = &rig.options;
    let starts = match &rig.gaps {
        Some(g) => g.starts(samples).map_err(on("gaps"))?,
        None => Vec::new(),
    };
    let gap = rig.gaps.map_or(0, |g| g.length());
    let mut next_gap = starts.iter().copied().peekable();
    let mut jitter = rig.jitter.map(|j| j.stamps());
    let step = config.sample_step();
    let coordinates = rig.coordinates();
    let mut reports: Vec<Report> = (0..coordinates).map(|c| Report::new(rig, c)).collect();
    let (mut cells, mut drives) = (Vec::with_capacity(coordinates), Vec::new());
    let mut one = |n: usize, t: f64, q: &[f64], v: &[f64]| {
        let stamp = match o.time_origin {
            TimeOrigin::Drive => t,
            TimeOrigin::FirstSample => n as f64 * step,
        };
        let stamp = jitter.as_mut().map_or(stamp, |j| j.stamp(stamp));
        cells.clear();
        cells.extend(reports.iter_mut().zip(q).map(|(r, &x)| r.cell(x)));
        // The drives at the instants the samples were taken, in the simulation's frame.
        rig.system.drives_at(&rig.frame, t, &mut drives);
        while next_gap.next_if(|&start| start + gap <= n).is_some() {}
        let kept = next_gap.peek().is_none_or(|&start| n < start);
        sample(&Sample {
            kept,
            stamp,
            coordinates: &cells,
            velocities: v,
            drives: &drives,
        })
    };
    let mut progress = |done: usize, total: usize| observer.progress(done, total);
    match (&rig.system, &rig.initial) {
        (System::Pendulum(_) | System::Duffing(_), _) => {
            let mut each = |n: usize, t: f64, x: f64, v: f64| one(n, t, &[x], &[v]);
            match (&rig.system, o.drive_frequency) {
                (System::Pendulum(p), None) => simulate_while(p, config, &mut progress, &mut each)?,
                (System::Pendulum(p), Some(_)) => {
                    simulate_while(&InFrame::new(*p, rig.frame), config, &mut progress, &mut each)?;
                }
                (System::Duffing(d), None) => simulate_while(d, config, &mut progress, &mut each)?,
                (System::Duffing(d), Some(_)) => {
                    simulate_while(&InFrame::new(*d, rig.frame), config, &mut progress, &mut each)?;
                }
                _ => unreachable!("a system of one coordinate"),
            }
        }
        (system, Some(initial)) => {
            let system = system.multi().expect("a system of several coordinates");
            let multi = MultiConfig::from_sampling(config.clone(), initial.clone());
            pendulum_sim::multi::simulate_while(
                &InFrame::new(system, rig.frame),
                &multi,
                &mut progress,
                one,
            )?;
        }
        (_, None) => unreachable!("a system of several coordinates has its initial state"),
    }
    Ok(())
}

/// Simulates `rig`; `observer` hears the progress in samples. The whole record is kept (see
/// [`simulate_to`] for a record written as it is made, of any length).
pub fn simulate(rig: &Rig, observer: &mut dyn Observer) -> Result<Simulation, RunError> {
    let samples = rig.config.samples();
    let coordinates = rig.coordinates();
    let counts = rig.writes_counts();
    // The memory of every column (times, positions, velocities, a drive, what is kept) asked
    // for first: a record too long for it is an error, not an abort.
    // (Times, positions, velocities, what is kept, and two drives, the arm's.)
    pendulum_sim::reserve_series(2 * coordinates + 4, samples)?;
    let mut t = Vec::with_capacity(samples);
    let mut reported: Vec<Reported> = (0..coordinates)
        .map(|_| {
            if counts {
                Reported::Counts(Vec::with_capacity(samples))
            } else {
                Reported::Values(Vec::with_capacity(samples))
            }
        })
        .collect();
    let mut velocities = vec![Vec::with_capacity(samples); coordinates];
    let mut drives: Vec<Vec<f64>> = Vec::new();
    let mut kept = Vec::with_capacity(samples);
    each_sample(rig, observer, |s| {
        t.push(s.stamp);
        for (column, &cell) in reported.iter_mut().zip(s.coordinates) {
            match (column, cell) {
                (Reported::Values(x), Cell::Value(v)) => x.push(v),
                (Reported::Counts(x), Cell::Count(k)) => x.push(k),
                _ => unreachable!("a column is counts or values throughout"),
            }
        }
        for (column, &v) in velocities.iter_mut().zip(s.velocities) {
            column.push(v);
        }
        drives.resize_with(s.drives.len(), || Vec::with_capacity(samples));
        for (column, &p) in drives.iter_mut().zip(s.drives) {
            column.push(p);
        }
        kept.push(s.kept);
        ControlFlow::Continue(())
    })?;
    Ok(Simulation {
        rig: rig.clone(),
        t,
        coordinates: reported,
        velocities,
        drives,
        kept,
    })
}

/// Simulates `rig` and writes its record to `path` as it is made, in memory that does not grow
/// with the record: the file [`Simulation::write`] writes of [`simulate`]'s record, byte for byte,
/// written atomically (nothing at `path` unless the whole record is). Returns the rows written.
/// `observer` hears the progress in samples.
///
/// Errors: the simulation's (the file is not written) and the file's. A failure to write (a
/// full disk) stops the simulation at that row: a record of 10^8 samples is not integrated to
/// its end first.
pub fn simulate_to(rig: &Rig, path: &Path, observer: &mut dyn Observer) -> Result<usize, RunError> {
    let rows = rig.rows()?;
    let columns = rig.columns();
    let (time_decimals, decimals) = (rig.options.time_decimals, rig.options.decimals);
    let drives = rig.writes_drives();
    let mut failed: Option<RunError> = None;
    let written = write_atomically(path, |w: &mut dyn Write| {
        let mut out = Out::begin(w, path, rows, &columns)?;
        let mut error: Option<std::io::Error> = None;
        // A row that cannot be written (a full disk) ends the simulation there, not at its end.
        let result = each_sample(rig, observer, |s| {
            if !s.kept {
                return ControlFlow::Continue(());
            }
            let drives: &[f64] = if drives { s.drives } else { &[] };
            let cells = std::iter::once((Cell::Value(s.stamp), time_decimals))
                .chain(s.coordinates.iter().map(|&c| (c, decimals)))
                .chain(
                    s.velocities
                        .iter()
                        .chain(drives)
                        .map(|&v| (Cell::Value(v), decimals)),
                );
            match out.row(cells) {
                Ok(()) => ControlFlow::Continue(()),
                Err(e) => {
                    error = Some(e);
                    ControlFlow::Break(())
                }
            }
        });
        if let Err(e) = result {
            failed = Some(e);
            return Err(std::io::Error::other("the simulation failed"));
        }
        if let Some(e) = error {
            return Err(e);
        }
        out.finish()
    });
    match (failed, written) {
        (Some(e), _) => Err(e),
        (None, Err(e)) => Err(e.into()),
        (None, Ok(())) => Ok(rows),
    }
}

/// A record's file being written: `.npy` (rows × columns, `f8`) or CSV (anything else).
enum Out<'w> {
    Npy(npyz::NpyWriter<f64, &'w mut dyn Write>),
    Csv { w: &'w mut dyn Write, line: String },
}

impl<'w> Out<'w> {
    /// Begins the file of `rows` rows of `columns` at `path` (its header) on `w`.
    fn begin(w: &'w mut dyn Write, path: &Path, rows: usize, columns: &[&str]) -> std::io::Result<Self> {
        if is_npy(path) {
            return Ok(Self::Npy(
                npyz::WriteOptions::<f64>::new()
                    .default_dtype()
                    .shape(&[rows as u64, columns.len() as u64])
                    .writer(w)
                    .begin_nd()?,
            ));
        }
        writeln!(w, "{}", columns.join(","))?;
        Ok(Self::Csv {
            w,
            line: String::new(),
        })
    }

    /// Writes a row of cells, each with its decimals: the number a reader of the printed cell
    /// gets (`.npy`), or the printed cell (CSV).
    fn row(&mut self, cells: impl Iterator<Item = (Cell, Option<usize>)>) -> std::io::Result<()> {
        match self {
            Self::Npy(writer) => writer.extend(cells.map(|(c, d)| c.number(d))),
            Self::Csv { w, line } => {
                line.clear();
                for (i, (c, d)) in cells.enumerate() {
                    if i > 0 {
                        line.push(',');
                    }
                    c.print(d, line);
                }
                line.push('\n');
                w.write_all(line.as_bytes())
            }
        }
    }

    /// Ends the file.
    fn finish(self) -> std::io::Result<()> {
        match self {
            Self::Npy(writer) => writer.finish(),
            Self::Csv { .. } => Ok(()),
        }
    }
}

/// Whether `path` names a `.npy` file (CSV otherwise).
fn is_npy(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// `v` as a reader of its printed form (with `decimals`, or the shortest that reads back as `v`)
/// gets it.
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

    /// The columns written: time, the coordinates, their velocities, and the drives that are
    /// written (`t,theta,omega` and `p` with `write_drive` for the pendulum, `count` for `theta`
    /// with `raw_counts`; `t,x,v[,p]`; `t,theta1,theta2,omega1,omega2[,p]`;
    /// `t,q1,q2,v1,v2,tau1,tau2`; `t,x1,x2,v1,v2,a`).
    pub fn columns(&self) -> Vec<&'static str> {
        self.rig.columns()
    }

    /// Rows of the record (samples kept).
    pub fn rows(&self) -> usize {
        self.kept.iter().filter(|&&k| k).count()
    }

    /// The cells of sample `n`: the time stamp, each coordinate, each velocity and each drive
    /// written.
    fn cells(&self, n: usize) -> impl Iterator<Item = (Cell, Option<usize>)> + '_ {
        let (td, vd) = (self.rig.options.time_decimals, self.rig.options.decimals);
        let drives: &[Vec<f64>] = if self.rig.writes_drives() {
            &self.drives
        } else {
            &[]
        };
        std::iter::once((Cell::Value(self.t[n]), td))
            .chain(self.coordinates.iter().map(move |x| match x {
                Reported::Values(x) => (Cell::Value(x[n]), vd),
                Reported::Counts(k) => (Cell::Count(k[n]), vd),
            }))
            .chain(
                self.velocities
                    .iter()
                    .chain(drives)
                    .map(move |v| (Cell::Value(v[n]), vd)),
            )
    }

    /// The record's rows as they are written, each `[t, x, v]` (and `p`; a system's coordinates,
    /// velocities and drives in the order of [`Simulation::columns`]), numbers as a reader of the
    /// printed text gets them.
    pub fn table(&self) -> Vec<Vec<f64>> {
        (0..self.t.len())
            .filter(|&n| self.kept[n])
            .map(|n| self.cells(n).map(|(c, d)| c.number(d)).collect())
            .collect()
    }

    /// The record's columns as they are written (in the order of [`Simulation::columns`]), each
    /// the numbers a reader of the printed text gets: [`table`](Self::table) by column, without a
    /// vector per row.
    pub fn table_columns(&self) -> Vec<Vec<f64>> {
        let rows = self.rows();
        let mut columns = vec![Vec::with_capacity(rows); self.columns().len()];
        for n in (0..self.t.len()).filter(|&n| self.kept[n]) {
            for (column, (c, d)) in columns.iter_mut().zip(self.cells(n)) {
                column.push(c.number(d));
            }
        }
        columns
    }

    /// Writes the record atomically: `.npy` (rows × columns, `f8`) or CSV (anything else).
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let columns = self.columns();
        write_atomically(path, |w: &mut dyn Write| {
            let mut out = Out::begin(w, path, self.rows(), &columns)?;
            for n in (0..self.t.len()).filter(|&n| self.kept[n]) {
                out.row(self.cells(n))?;
            }
            out.finish()
        })
    }

    /// The true equation the record satisfies, in the identification's form and the record's time
    /// unit, with the drive, sampling and encoder settings; for a system of several coordinates
    /// one equation per coordinate.
    pub fn truth(&self) -> Result<Truth, RunError> {
        truth(&self.rig, self.rows(), self.columns())
    }
}

impl Rig {
    /// The coordinates simulated.
    fn coordinates(&self) -> usize {
        self.initial.as_ref().map_or(1, MultiState::coordinates)
    }

    /// Whether the coordinate's column holds the encoder's counts.
    fn writes_counts(&self) -> bool {
        matches!(self.system, System::Pendulum(_)) && self.encoder.is_some() && self.options.raw_counts
    }

    /// Whether the drives are written: always for a measured input, with `write_drive` otherwise.
    fn writes_drives(&self) -> bool {
        self.options.write_drive || self.options.system.measured_input()
    }

    /// The columns of the record (see [`Simulation::columns`]).
    pub fn columns(&self) -> Vec<&'static str> {
        let (coordinates, velocities, drives) = self.options.system.column_names();
        let mut columns = vec!["t"];
        if self.writes_counts() {
            columns.push("count");
        } else {
            columns.extend(coordinates);
        }
        columns.extend(velocities);
        if self.writes_drives() {
            columns.extend(drives);
        }
        columns
    }

    /// The rows of the record: the samples less those in gaps.
    pub fn rows(&self) -> Result<usize, RunError> {
        let samples = self.config.samples();
        Ok(match &self.gaps {
            Some(g) => {
                g.starts(samples).map_err(on("gaps"))?;
                samples - g.count() * g.length()
            }
            None => samples,
        })
    }

    /// The true equations of the record (see [`Simulation::truth`]).
    pub fn truth(&self) -> Result<Truth, RunError> {
        truth(self, self.rows()?, self.columns())
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

impl Ordered {
    /// Whether there are none (a system of several coordinates has its coefficients per
    /// equation).
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

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

/// The true equations of a system of several coordinates: for each coordinate, by its name in
/// the record, the coefficients of `q'' + Σ c_i g_i = 0` in the record's names and time unit,
/// written as `{"theta1": {"coefficients": {...}}, ...}`.
#[derive(Debug, Clone, PartialEq)]
pub struct Equations(pub Vec<(String, Ordered)>);

impl Equations {
    /// The coefficients of the equation of the coordinate `name`.
    pub fn of(&self, name: &str) -> Option<&Ordered> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, c)| c)
    }
}

impl Serialize for Equations {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        #[derive(Serialize)]
        struct One<'a> {
            coefficients: &'a Ordered,
        }
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, coefficients) in &self.0 {
            map.serialize_entry(name, &One { coefficients })?;
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
    /// `drive` or `none` for a periodic drive, `measured` for a drive written as a column.
    forcing: &'static str,
    /// How `hbid identify` reads the record: by default (signal, basis, forcing terms, column),
    /// or for a system the options that identify its equations.
    identify: Hint,
    /// `x'' + Σ c_i g_i = 0` in the record's time unit and coordinate, every term of the layout
    /// (a system of one coordinate).
    #[serde(skip_serializing_if = "Ordered::is_empty")]
    pub coefficients: Ordered,
    /// The equation of each coordinate (a system of several).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equations: Option<Equations>,
    time_unit: &'static str,
    /// Hz, `None` for the model's own time (and for the arm, in seconds with no periodic drive).
    drive_frequency: Option<f64>,
    /// The drive's period in the record's time unit (`None` for the arm).
    forcing_period: Option<f64>,
    /// `dτ/dt`: the drive's angular frequency in the record's time unit.
    time_scale: f64,
    /// The drive's phase (radians) at the record's `t = 0`.
    drive_phase_at_zero: Option<f64>,
    /// The drive's phase (radians) at the first sample.
    drive_phase_at_first_sample: Option<f64>,
    time_origin: &'static str,
    first_sample_time: f64,
    sample_step: f64,
    sample_rate: f64,
    samples_per_period: Option<f64>,
    samples_simulated: usize,
    rows: usize,
    columns: Vec<&'static str>,
    transient_periods: usize,
    initial: Initial,
    noise_sigma: f64,
    encoder: Option<EncoderInfo>,
    gaps: Option<GapsInfo>,
    /// The standard deviation of the time stamps' jitter.
    #[serde(skip_serializing_if = "Option::is_none")]
    jitter: Option<f64>,
    seed: u64,
    time_decimals: Option<usize>,
    decimals: Option<usize>,
}

/// The initial state: `[x0, v0]` of one coordinate, `{"q": [...], "v": [...]}` of a system.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
enum Initial {
    One([f64; 2]),
    System(MultiState),
}

/// How `hbid identify` reads the record.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
enum Hint {
    One(IdentifyHint),
    System(SystemHint),
}

#[derive(Debug, Clone, PartialEq, Serialize)]
struct IdentifyHint {
    signal: &'static str,
    basis: &'static str,
    forcing: &'static str,
    angle_column: &'static str,
    /// The angle's unit when it is not radians (an encoder's raw counts: `counts:N`).
    #[serde(skip_serializing_if = "Option::is_none")]
    angle_unit: Option<String>,
    /// Terms of the true equation beyond the layout of `basis` and `forcing` (a rig's losses and
    /// drive harmonics), listed after it in `coefficients`.
    extra_terms: Vec<String>,
}

/// The options of `hbid identify` (and Python's `hbid.identify`) that identify a system's true
/// equations from its record: its coordinates, their domain, the measured drives, the time scale
/// of a drive in seconds, the windows' length where no periodic drive sets it, and the true
/// equations' terms; `args` spells them for the command line.
#[derive(Debug, Clone, PartialEq, Serialize)]
struct SystemHint {
    coords: String,
    signal: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    drive_col: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    drive_frequency: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    drive_period: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    window: Option<f64>,
    terms: String,
    args: Vec<String>,
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
    /// The stream of the seed each angle's encoder draws from, in the order of the coordinates
    /// (a system of several).
    #[serde(skip_serializing_if = "Option::is_none")]
    streams: Option<Vec<u64>>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
struct GapsInfo {
    count: usize,
    length: usize,
    /// First dropped sample of each gap, counted in the simulated samples.
    starts: Vec<usize>,
}

/// Windows of the identification of a system without a periodic drive: three periods of the
/// slowest torque (the arm), or of the base acceleration's first tone (the coupled oscillators),
/// in the record's time unit.
const HINT_WINDOW_PERIODS: f64 = 3.0;

/// The coefficients, identification hint and equations of a system of one coordinate.
fn one_truth(
    system: &System,
    frame: &RecordFrame,
    columns: &[&'static str],
) -> Result<(Hint, Ordered), RunError> {
    let (known, layout, mut hint) = match system {
        System::Pendulum(p) => (
            p.equation(frame)?.named(),
            hb_model::term_names(
                &Harmonic::new(1).map_err(hb_solve::SolveError::from)?,
                &ModelForm::parametric(),
            ),
            IdentifyHint {
                signal: "circle",
                basis: "harmonic:1",
                forcing: "none",
                angle_column: columns[1],
                angle_unit: None,
                extra_terms: Vec::new(),
            },
        ),
        System::Duffing(d) => (
            d.equation(frame)?.named(),
            hb_model::term_names(
                &Polynomial::new(3).map_err(hb_solve::SolveError::from)?,
                &ModelForm::parametric().with_forcing(Forcing::Identified),
            ),
            IdentifyHint {
                signal: "line",
                basis: "poly:3",
                forcing: "identified",
                angle_column: columns[1],
                angle_unit: None,
                extra_terms: Vec::new(),
            },
        ),
        _ => unreachable!("a system of one coordinate"),
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
    Ok((Hint::One(hint), Ordered(coefficients)))
}

/// The equations of a system of several coordinates in the record's names and `frame`, read from
/// the simulator's (`normalised_equations`), and the options that identify them.
fn system_truth(rig: &Rig, frame: &RecordFrame) -> Result<(Hint, Equations), RunError> {
    let o = &rig.options;
    let kind = o.system;
    let (coordinates, _, drives) = kind.column_names();
    // The double pendulum's drive is a function of the drive's phase, whether written or not.
    let measured: &[&str] = if kind.measured_input() { drives } else { &[] };
    let names = Names::new(coordinates.iter().copied(), measured.iter().copied())
        .map_err(|e| OptionError::new("system", e))?;
    let normalised = match &rig.system {
        System::DoublePendulum(p) => p.normalised_equations(),
        System::Arm(a) => a.normalised_equations(),
        System::CoupledDuffing(d) => d.normalised_equations(),
        _ => unreachable!("a system of several coordinates"),
    };
    let equations = pendulum_sim::truth::system_equations(&normalised, &names, frame)?;
    let free = o.drive == DriveKind::None;
    // A passive joint's torque (--torque1 none) is a column of zeros: a term in it fits nothing.
    let passive = |drive: &hb_model::DriveFactor| match (&rig.system, drive) {
        (System::Arm(a), hb_model::DriveFactor::Measured(k)) => {
            matches!(a.torques().get(usize::from(*k)), Some(Torque::None))
        }
        _ => false,
    };
    let mut lists = Vec::new();
    for (name, equation) in coordinates.iter().zip(&equations) {
        // A free decay has no drive's phase to balance: its drive terms (all 0) are left out.
        let list = equation.terms();
        let terms: Vec<String> = (0..list.len())
            .filter(|&i| !(free && equation.values()[i] == 0.0 && list.terms()[i].drive.needs_phase()))
            .filter(|&i| !passive(&list.terms()[i].drive))
            .map(|i| list.name(i))
            .collect();
        lists.push(format!("{name}: {}", terms.join(", ")));
    }
    let window = match &rig.system {
        System::Arm(a) => {
            let slowest = a
                .torques()
                .iter()
                .filter_map(|t| match t {
                    Torque::Sinusoids(s) => s
                        .iter()
                        .map(|s| s.angular_frequency().abs())
                        .filter(|&w| w > 0.0)
                        .reduce(f64::min),
                    _ => None,
                })
                .reduce(f64::min);
            Some(slowest.map_or(1.0, |w| HINT_WINDOW_PERIODS * TAU / w))
        }
        System::CoupledDuffing(_) => Some(HINT_WINDOW_PERIODS * rig.frame.drive_period()),
        _ => None,
    };
    // Columns as NAME=POSITION: the header's names on a CSV, the positions on a `.npy`.
    let written = rig.columns();
    let by_position = |names: &[&str]| {
        names
            .iter()
            .map(|n| match written.iter().position(|c| c == n) {
                Some(i) => format!("{n}={}", i + 1),
                None => (*n).to_owned(),
            })
            .collect::<Vec<_>>()
            .join(",")
    };
    let hint = SystemHint {
        coords: by_position(coordinates),
        signal: match kind.domain() {
            Domain::Circle => "circle",
            Domain::Line => "line",
        },
        drive_col: {
            // The drives a term reads (not a passive joint's).
            let read: Vec<&str> = measured
                .iter()
                .enumerate()
                .filter(|&(k, _)| !passive(&hb_model::DriveFactor::Measured(k as u8)))
                .map(|(_, &d)| d)
                .collect();
            (!read.is_empty()).then(|| by_position(&read))
        },
        // A free decay's time unit is its record's: no drive to give.
        drive_frequency: if kind.measured_input() || free {
            None
        } else {
            o.drive_frequency
        },
        drive_period: (free && kind == SystemKind::DoublePendulum).then_some("none"),
        window,
        terms: lists.join("; "),
        args: Vec::new(),
    };
    let mut args = vec![
        "--coords".to_owned(),
        hint.coords.clone(),
        "--signal".to_owned(),
        hint.signal.to_owned(),
    ];
    if let Some(d) = &hint.drive_col {
        args.extend(["--drive-col".to_owned(), d.clone()]);
    }
    if let Some(hz) = hint.drive_frequency {
        args.extend(["--drive-frequency".to_owned(), hz.to_string()]);
    }
    if let Some(p) = hint.drive_period {
        args.extend(["--drive-period".to_owned(), p.to_owned()]);
    }
    if let Some(w) = hint.window {
        args.extend(["--window".to_owned(), w.to_string()]);
    }
    args.extend(["--terms".to_owned(), hint.terms.clone()]);
    let named = coordinates
        .iter()
        .zip(&equations)
        .map(|(name, e)| ((*name).to_owned(), Ordered(e.named())))
        .collect();
    Ok((Hint::System(SystemHint { args, ..hint }), Equations(named)))
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
    let (hint, coefficients, equations) = match &rig.system {
        System::Pendulum(_) | System::Duffing(_) => {
            let (mut hint, coefficients) = one_truth(&rig.system, &frame, &columns)?;
            if let (Hint::One(h), true) = (&mut hint, rig.writes_counts()) {
                h.angle_unit = encoder.and_then(|e| e.counts()).map(|n| format!("counts:{n}"));
            }
            (hint, coefficients, None)
        }
        _ => {
            let (hint, equations) = system_truth(rig, &frame)?;
            (hint, Ordered(Vec::new()), Some(equations))
        }
    };
    let parameters = rig
        .system
        .parameters()
        .map_err(|e| OptionError::new("system", e))?;
    let config = &rig.config;
    let step = config.sample_step();
    let periodic = o.system != SystemKind::Arm;
    let first_sample_time = match o.time_origin {
        TimeOrigin::Drive => config.sample_time(0),
        TimeOrigin::FirstSample => 0.0,
    };
    let range = match o.angle_range {
        Some(RangeKind::Positive) => "positive",
        _ => "signed",
    };
    let sigma = encoder.map_or(0.0, |e| e.sigma());
    let coordinates = o.system.coordinates();
    let encoder_info = (o.system.domain() == Domain::Circle).then(|| EncoderInfo {
        counts: encoder.and_then(|e| e.counts()),
        zero_offset: offset,
        bit_error_rate: encoder.map_or(0.0, |e| e.bit_error_rate()),
        bit_error_bits: Encoder::BIT_ERROR_BITS,
        angle_range: range,
        raw_counts: o.raw_counts,
        unwrapped: o.unwrapped,
        streams: (coordinates > 1).then(|| (0..coordinates as u64).collect()),
    });
    let gaps = match rig.gaps {
        Some(g) => Some(GapsInfo {
            count: g.count(),
            length: g.length(),
            starts: g.starts(config.samples()).map_err(on("gaps"))?,
        }),
        None => None,
    };
    let forcing = if o.system.measured_input() {
        "measured"
    } else {
        o.drive.name()
    };
    Ok(Truth {
        format: "hbid-truth",
        version: 1,
        system: rig.system.name(),
        equation: rig.system.equation(),
        parameters,
        forcing,
        identify: hint,
        coefficients,
        equations,
        time_unit: if o.drive_frequency.is_some() || !periodic {
            "s"
        } else {
            "nondimensional"
        },
        drive_frequency: o.drive_frequency,
        forcing_period: periodic.then(|| config.drive_period()),
        time_scale: rig.frame.rate(),
        drive_phase_at_zero: periodic.then_some(at_zero),
        drive_phase_at_first_sample: periodic.then_some(rig.first_phase),
        time_origin: o.time_origin.name(),
        first_sample_time,
        sample_step: step,
        sample_rate: 1.0 / step,
        samples_per_period: periodic.then(|| config.drive_period() / step),
        samples_simulated: config.samples(),
        rows,
        columns,
        transient_periods: config.transient_periods(),
        initial: match &rig.initial {
            Some(state) => Initial::System(state.clone()),
            None => Initial::One(config.initial()),
        },
        noise_sigma: sigma,
        encoder: encoder_info,
        gaps,
        jitter: rig.jitter.map(|j| j.sigma()),
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

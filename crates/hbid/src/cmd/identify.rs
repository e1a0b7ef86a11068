//! `hbid identify`: the equation of motion by harmonic balance.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use hb_basis::{BasisKind, Harmonic, Hat, Polynomial};
use hb_solve::{
    Forcing, Harmonics, IdentifiedModel, IdentifyParams, LstsqSolver, ModelForm, QrSolver, SampleClock,
    SvdSolver, identify,
};
use upo_search::{CloseReturns, Metric};

use super::data::{Data, InputArgs, Signal};

/// Identification method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// The paper's: harmonic balance over unstable periodic orbits found by close returns.
    Upo,
}

/// Least-squares solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// Column-pivoted QR.
    Qr,
    /// Thin SVD.
    Svd,
}

/// External forcing terms cos(t), sin(t) (the d_1 p(t) of the paper's eq. 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ForcingArg {
    /// No external forcing term.
    None,
    /// Identify the coefficients of cos(t) and sin(t).
    Identified,
}

/// Options of `hbid identify`.
#[derive(Debug, Args)]
pub struct IdentifyArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Identification method.
    #[arg(long, value_enum, default_value_t = Method::Upo)]
    pub method: Method,
    /// Basis of the unknown functions: harmonic:K (cos kx, sin kx, k = 1..K), hat:N (N periodic hats), poly:D
    /// (x .. x^D). Default: harmonic:1 on the circle, poly:3 on the line.
    #[arg(long)]
    pub basis: Option<String>,
    /// Harmonics per orbit (default: all j with j/k <= 3 forcing harmonics for a period-k orbit).
    #[arg(long)]
    pub harmonics: Option<usize>,
    /// Least-squares solver.
    #[arg(long, value_enum, default_value_t = SolverArg::Qr)]
    pub solver: SolverArg,
    /// Close-return tolerance as a fraction of the span of the data, in (0, 0.5).
    #[arg(long, default_value_t = 0.03, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Longest orbit period searched, in forcing periods.
    #[arg(long, default_value_t = 16)]
    pub max_period: usize,
    /// Dimension of the delay vectors of the close-return search.
    #[arg(long, default_value_t = 2)]
    pub dim: usize,
    /// Delay in samples (default: the first minimum of the average mutual information).
    #[arg(long)]
    pub delay: Option<usize>,
    /// External forcing terms (default: none on the circle, identified on the line).
    #[arg(long, value_enum)]
    pub forcing: Option<ForcingArg>,
    /// Leave out the parametric terms cos(t)*B and sin(t)*B.
    #[arg(long)]
    pub no_parametric: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Save the identified model: JSON if the name ends in .json, compact binary otherwise.
    #[arg(long, value_name = "PATH")]
    pub save_model: Option<PathBuf>,
}

/// Parses `harmonic:K`, `hat:N` or `poly:D`.
pub fn parse_basis(text: &str) -> anyhow::Result<BasisKind> {
    let (kind, n) = text
        .split_once(':')
        .ok_or_else(|| anyhow::anyhow!("--basis '{text}': expected harmonic:K, hat:N or poly:D"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--basis '{text}': '{n}' is not a whole number"))?;
    let basis = match kind.trim() {
        "harmonic" => BasisKind::from(Harmonic::new(n)?),
        "hat" => BasisKind::from(Hat::new(n)?),
        "poly" => BasisKind::from(Polynomial::new(n)?),
        other => bail!("--basis '{text}': unknown basis '{other}' (harmonic, hat or poly)"),
    };
    Ok(basis)
}

/// Everything but the data: basis, parameters and solver, checked before any work.
pub struct Setup {
    pub basis: BasisKind,
    pub basis_name: String,
    pub params: IdentifyParams,
    pub solver: Box<dyn LstsqSolver>,
}

impl IdentifyArgs {
    pub fn setup(&self, data: &Data) -> anyhow::Result<Setup> {
        let basis_name = self.basis.clone().unwrap_or_else(|| match data.signal {
            Signal::Circle => "harmonic:1".to_owned(),
            Signal::Line => "poly:3".to_owned(),
        });
        let basis = parse_basis(&basis_name)?;
        let forcing = match self.forcing.unwrap_or(match data.signal {
            Signal::Circle => ForcingArg::None,
            Signal::Line => ForcingArg::Identified,
        }) {
            ForcingArg::None => Forcing::None,
            ForcingArg::Identified => Forcing::Identified,
        };
        let form = ModelForm {
            parametric: !self.no_parametric,
            ..ModelForm::parametric()
        }
        .with_forcing(forcing);
        let harmonics = match self.harmonics {
            Some(0) => bail!("--harmonics must be at least 1"),
            Some(m) => Harmonics::Fixed(m),
            None => Harmonics::ForcingCap(3.0),
        };
        let clock = SampleClock::new(self.input.forcing_period, data.p)?.with_start_time(data.t0)?;
        let params = IdentifyParams::builder(clock)
            .form(form)
            .harmonics(harmonics)
            .build()?;
        let solver: Box<dyn LstsqSolver> = match self.solver {
            SolverArg::Qr => Box::new(QrSolver::default()),
            SolverArg::Svd => Box::new(SvdSolver::default()),
        };
        Ok(Setup {
            basis,
            basis_name,
            params,
            solver,
        })
    }

    fn close_returns(&self, data: &Data, delay: usize) -> anyhow::Result<CloseReturns> {
        Ok(CloseReturns::builder(data.p, delay)
            .tolerance(self.tolerance)
            .max_period(self.max_period)
            .dimension(self.dim)
            .metric(match data.signal {
                Signal::Circle => Metric::Circle,
                Signal::Line => Metric::Linear,
            })
            .build()?)
    }
}

pub fn run(args: &IdentifyArgs) -> anyhow::Result<()> {
    if let Some(path) = &args.save_model {
        crate::output::check_output_path(path).context("--save-model")?;
    }
    let data = args.input.load()?;
    let setup = args.setup(&data)?;
    // Check the search's options before the embedding work.
    args.close_returns(&data, args.delay.unwrap_or(1))?;
    let delay = match args.delay {
        Some(d) => d,
        None => super::embed::ami(&data.x, super::embed::metric_for(data.signal, None), 16, 40)?.1,
    };
    let segments = args.close_returns(&data, delay)?.search(&data.x)?;
    let model = identify(
        setup.basis,
        &data.x,
        &segments,
        &setup.params,
        setup.solver.as_ref(),
    )
    .map_err(|e| anyhow::anyhow!("{e}"))
    .with_context(|| {
        format!(
            "{} orbit segments found at tolerance {}",
            segments.len(),
            args.tolerance
        )
    })?;
    if let Some(path) = &args.save_model {
        save_model(&model, path)?;
    }
    let method = "upo";
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&json(&model, method, &setup.basis_name))?
        );
    } else {
        print_table(&model, method, &setup.basis_name);
    }
    Ok(())
}

/// Saves a model as JSON (`.json`) or compact binary (anything else), atomically.
pub fn save_model(model: &IdentifiedModel, path: &std::path::Path) -> anyhow::Result<()> {
    let json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let bytes = if json {
        model.to_json()?.into_bytes()
    } else {
        model.to_bytes()?
    };
    crate::output::write_atomically(path, |w| w.write_all(&bytes))
}

/// The JSON report of an identification.
pub fn json(model: &IdentifiedModel, method: &str, basis: &str) -> serde_json::Value {
    let values: serde_json::Map<String, serde_json::Value> = model
        .coefficients()
        .iter()
        .map(|c| (c.name.clone(), c.value.into()))
        .collect();
    let errors: serde_json::Map<String, serde_json::Value> = model
        .coefficients()
        .iter()
        .map(|c| (c.name.clone(), c.std_error.into()))
        .collect();
    let summary = model.summary();
    serde_json::json!({
        "method": method,
        "basis": basis,
        "coefficients": values,
        "std_errors": errors,
        "orbits_used": summary.map(|s| s.segments),
        "rows": summary.map(|s| s.rows),
        "condition_number": summary.map(|s| s.condition),
        "residual_rms": summary.map(|s| s.residual_rms),
    })
}

fn print_table(model: &IdentifiedModel, method: &str, basis: &str) {
    println!("method {method}, basis {basis}");
    if let Some(s) = model.summary() {
        println!(
            "{} orbit segments ({} whirling), {} equations, {} unknowns, solver {}",
            s.segments, s.whirling_segments, s.rows, s.unknowns, s.solver
        );
        println!(
            "condition number {:.3e}, residual RMS {:.3e}",
            s.condition, s.residual_rms
        );
    }
    println!();
    println!("{:<18} {:>14} {:>12}", "term", "coefficient", "std. error");
    for c in model.coefficients() {
        println!("{:<18} {:>14.6} {:>12.2e}", c.name, c.value, c.std_error);
    }
}

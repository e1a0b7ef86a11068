//! `hbid upos`: unstable periodic orbits by close returns.

use std::collections::BTreeMap;

use clap::Args;
use upo_search::{Catalogue, CloseReturns, Metric};

use super::data::{InputArgs, Signal};

/// Options of `hbid upos`.
#[derive(Debug, Args)]
pub struct UposArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Close-return tolerance as a fraction of the span of the data (2π for an angle), in (0, 0.5).
    #[arg(long, default_value_t = 0.03, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Longest period searched, in forcing periods.
    #[arg(long, default_value_t = 16)]
    pub max_period: usize,
    /// Dimension of the delay vectors compared.
    #[arg(long, default_value_t = 2)]
    pub dim: usize,
    /// Delay in samples (default: the first minimum of the average mutual information, 16 boxes).
    #[arg(long)]
    pub delay: Option<usize>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &UposArgs, quiet: bool) -> anyhow::Result<()> {
    let bar = crate::progress::Progress::spinner("orbits", quiet);
    let data = args.input.load()?;
    let metric = match data.signal {
        Signal::Circle => Metric::Circle,
        Signal::Line => Metric::Linear,
    };
    let build = |delay: usize| {
        CloseReturns::builder(data.p, delay)
            .tolerance(args.tolerance)
            .max_period(args.max_period)
            .dimension(args.dim)
            .metric(metric)
            .build()
    };
    // Check the options before any work.
    build(args.delay.unwrap_or(1))?;
    let delay = match args.delay {
        Some(d) => d,
        None => super::embed::ami(&data.x, super::embed::metric_for(data.signal, None), 16, 40)?.1,
    };
    let search = build(delay)?;
    let catalogue = search.catalogue(&data.x)?;
    bar.finish();
    if args.json {
        println!("{}", serde_json::to_string(&json(&catalogue))?);
    } else {
        println!("{}", data.summary());
        print_table(&catalogue, delay, search.absolute_tolerance(&data.x)?);
    }
    Ok(())
}

fn json(catalogue: &Catalogue) -> serde_json::Value {
    let counts = catalogue.counts();
    let by_period: BTreeMap<String, usize> = counts
        .iter()
        .map(|c| (c.period.to_string(), c.segments))
        .collect();
    let distinct: BTreeMap<String, usize> = counts.iter().map(|c| (c.period.to_string(), c.orbits)).collect();
    serde_json::json!({
        "segments": catalogue.segments().len(),
        "by_period": by_period,
        "distinct_orbits": catalogue.orbits().len(),
        "distinct_by_period": distinct,
        "orbits": catalogue.segments().iter().map(|s| serde_json::json!({
            "period": s.period, "start": s.start, "error": s.error,
        })).collect::<Vec<_>>(),
    })
}

fn print_table(catalogue: &Catalogue, delay: usize, epsilon: f64) {
    println!("delay {delay}, tolerance ε = {epsilon:.4}");
    println!("{:>7}  {:>9}  {:>15}", "period", "segments", "distinct orbits");
    for c in catalogue.counts() {
        println!("{:>7}  {:>9}  {:>15}", c.period, c.segments, c.orbits);
    }
    println!(
        "{:>7}  {:>9}  {:>15}",
        "all",
        catalogue.segments().len(),
        catalogue.orbits().len()
    );
}

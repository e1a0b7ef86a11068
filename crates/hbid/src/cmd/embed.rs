//! `hbid embed`: the delay (first minimum of the average mutual information) and the embedding
//! dimension (false nearest neighbours).

use anyhow::Context;
use clap::{Args, ValueEnum};
use embedding::{
    AmiCurve, AmiParams, FnnParams, FnnResult, Metric, average_mutual_information, false_nearest_neighbours,
};

use super::data::{InputArgs, Signal};

/// The distance between samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MetricArg {
    /// Circle distance |wrap(a - b)|: the right one for a wrapped angle.
    Circle,
    /// Plain differences, as classic tools do.
    Linear,
}

impl From<MetricArg> for Metric {
    fn from(m: MetricArg) -> Self {
        match m {
            MetricArg::Circle => Metric::Circle,
            MetricArg::Linear => Metric::Linear,
        }
    }
}

/// Options of `hbid embed`.
#[derive(Debug, Args)]
pub struct EmbedArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Largest lag of the average mutual information.
    #[arg(long, default_value_t = 40)]
    pub max_lag: usize,
    /// Equal boxes of the mutual-information histogram.
    #[arg(long, default_value_t = 16)]
    pub bins: usize,
    /// Largest embedding dimension tested by false nearest neighbours.
    #[arg(long, default_value_t = 8)]
    pub max_dim: usize,
    /// Distance between samples (default: circle for --signal circle, linear for --signal line).
    #[arg(long, value_enum)]
    pub metric: Option<MetricArg>,
    /// Theiler window: neighbours closer in time than this many samples are not counted.
    #[arg(long, default_value_t = 0)]
    pub theiler: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The metric of a signal kind unless one is given.
pub fn metric_for(signal: Signal, given: Option<MetricArg>) -> Metric {
    match (given, signal) {
        (Some(m), _) => m.into(),
        (None, Signal::Circle) => Metric::Circle,
        (None, Signal::Line) => Metric::Linear,
    }
}

/// The AMI curve and its first minimum, the default delay of every later stage.
pub fn ami(x: &[f64], metric: Metric, bins: usize, max_lag: usize) -> anyhow::Result<(AmiCurve, usize)> {
    let params = AmiParams::new(metric).with_bins(bins)?.with_max_lag(max_lag)?;
    let curve = average_mutual_information(x, &params)?;
    let delay = curve
        .delay()
        .context("choose the delay with --delay, or raise --max-lag")?;
    Ok((curve, delay))
}

pub fn run(args: &EmbedArgs, quiet: bool) -> anyhow::Result<()> {
    if args.bins < 2 {
        anyhow::bail!("--bins {} must be at least 2", args.bins);
    }
    if args.max_dim == 0 {
        anyhow::bail!("--max-dim must be at least 1");
    }
    let bar = crate::progress::Progress::spinner("embed", quiet);
    let data = args.input.load()?;
    let metric = metric_for(data.signal, args.metric);
    let (curve, delay) = ami(&data.x, metric, args.bins, args.max_lag)?;
    let params = FnnParams::new(metric, delay)?
        .with_max_dim(args.max_dim)?
        .with_theiler_window(args.theiler);
    let fnn = false_nearest_neighbours(&data.x, &params)?;
    bar.finish();
    if args.json {
        println!("{}", serde_json::to_string(&json(&curve, delay, &fnn))?);
    } else {
        println!("{}", data.summary());
        print_table(&curve, delay, &fnn, metric);
    }
    Ok(())
}

fn json(curve: &AmiCurve, delay: usize, fnn: &FnnResult) -> serde_json::Value {
    serde_json::json!({
        "delay": delay,
        "ami": curve.values,
        "fnn": fnn.levels.iter().map(|l| l.fraction()).collect::<Vec<_>>(),
        "embedding_dimension": fnn.minimum_dimension(),
    })
}

fn print_table(curve: &AmiCurve, delay: usize, fnn: &FnnResult, metric: Metric) {
    println!("metric: {metric:?}");
    println!("delay (first minimum of the average mutual information): {delay}");
    match fnn.minimum_dimension() {
        Some(d) => println!(
            "embedding dimension (false neighbours below {}): {d}",
            fnn.fraction_threshold
        ),
        None => println!(
            "embedding dimension: none up to {} (false neighbours stay above {})",
            fnn.levels.len(),
            fnn.fraction_threshold
        ),
    }
    println!();
    println!("{:>5}  {:>10}", "lag", "AMI (nats)");
    for (lag, v) in curve.values.iter().enumerate() {
        let mark = if lag == delay { "  <- first minimum" } else { "" };
        println!("{lag:>5}  {v:>10.4}{mark}");
    }
    println!();
    println!("{:>5}  {:>14}", "dim", "false fraction");
    for level in &fnn.levels {
        println!("{:>5}  {:>14.4}", level.dim, level.fraction());
    }
}

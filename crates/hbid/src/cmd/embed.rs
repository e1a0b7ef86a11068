//! `hbid embed`: the delay (first minimum of the average mutual information) and the embedding
//! dimension (false nearest neighbours).

use clap::Args;
use embedding::{AmiCurve, AmiParams, Domain, FnnParams, FnnResult, false_nearest_neighbours};

use super::data::{InputArgs, ami, domain_parser};

/// Options of `hbid embed`.
#[derive(Debug, Args)]
pub struct EmbedArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Largest lag of the average mutual information (default: two forcing periods, at least 40).
    #[arg(long)]
    pub max_lag: Option<usize>,
    /// Equal boxes of the mutual-information histogram.
    #[arg(long, default_value_t = 16)]
    pub bins: usize,
    /// Largest embedding dimension tested by false nearest neighbours.
    #[arg(long, default_value_t = 8)]
    pub max_dim: usize,
    /// Distance between samples: circle (|wrap(a - b)|, the right one for a wrapped angle) or
    /// linear (plain differences, as classic tools do). Default: that of --signal.
    #[arg(long, value_parser = domain_parser(true))]
    pub metric: Option<Domain>,
    /// Theiler window: neighbours closer in time than this many samples are not counted.
    #[arg(long, default_value_t = 0)]
    pub theiler: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
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
    let metric = args.metric.unwrap_or(data.domain);
    let max_lag = args
        .max_lag
        .unwrap_or_else(|| hb_pipeline::pipeline::EmbedOptions::default().max_lag(data.p));
    let (curve, delay) = ami(
        data.longest(),
        &AmiParams::new(metric)
            .with_bins(args.bins)?
            .with_max_lag(max_lag)?,
    )?;
    let params = FnnParams::new(metric, delay)?
        .with_max_dim(args.max_dim)?
        .with_theiler_window(args.theiler);
    let fnn = false_nearest_neighbours(data.longest(), &params)?;
    bar.finish();
    if args.json {
        println!(
            "{}",
            serde_json::to_string(&hb_pipeline::json::embedding(&curve, delay, &fnn))?
        );
    } else {
        println!("{}", data.summary());
        print_table(&curve, delay, &fnn, metric);
    }
    Ok(())
}

fn print_table(curve: &AmiCurve, delay: usize, fnn: &FnnResult, metric: Domain) {
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

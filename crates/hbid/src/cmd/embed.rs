//! `hbid embed`: the delay (first minimum of the average mutual information) and the embedding
//! dimension (false nearest neighbours).

use clap::Args;
use embedding::{AmiCurve, AmiParams, Domain, FnnParams, FnnResult};
use hb_pipeline::{EmbedReport, EmbedRequest};

use super::data::InputArgs;
use crate::progress::Console;

/// Options of `hbid embed`.
#[derive(Debug, Args)]
pub struct EmbedArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Largest lag of the average mutual information (default: two forcing periods, at least 40).
    #[arg(long)]
    pub max_lag: Option<usize>,
    /// Equal boxes of the mutual-information histogram.
    #[arg(long, default_value_t = AmiParams::DEFAULT_BINS)]
    pub bins: usize,
    /// Largest embedding dimension tested by false nearest neighbours.
    #[arg(long, default_value_t = FnnParams::DEFAULT_MAX_DIM)]
    pub max_dim: usize,
    /// Distance between samples: circle (|wrap(a - b)|, the right one for a wrapped angle) or
    /// linear (plain differences, as classic tools do). Default: that of --signal.
    #[arg(long, value_parser = super::data::choice::<Domain>(&["circle", "line", "linear"]))]
    pub metric: Option<Domain>,
    /// Theiler window: neighbours closer in time than this many samples are not counted.
    #[arg(long, default_value_t = 0)]
    pub theiler: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl EmbedArgs {
    /// The application layer's request.
    pub fn request(&self) -> EmbedRequest {
        EmbedRequest {
            record: self.input.options(),
            max_lag: self.max_lag,
            bins: self.bins,
            max_dim: self.max_dim,
            metric: self.metric,
            theiler: self.theiler,
        }
    }
}

pub fn run(args: &EmbedArgs, quiet: bool) -> anyhow::Result<()> {
    let request = args.request();
    request.check()?;
    let mut console = Console::new("embed", quiet, false);
    let report: EmbedReport = hb_pipeline::embed(args.input.source()?, &request, &mut console)?;
    console.finish();
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("{}", report.record.summary);
        print_table(&report.ami, report.delay, &report.fnn, report.metric);
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

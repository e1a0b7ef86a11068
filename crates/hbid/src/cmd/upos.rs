//! `hbid upos`: unstable periodic orbits by close returns.

use clap::Args;
use hb_pipeline::UposRequest;
use upo_search::Catalogue;

use super::data::{InputArgs, SearchArgs};
use crate::progress::Console;

/// Options of `hbid upos`.
#[derive(Debug, Args)]
pub struct UposArgs {
    #[command(flatten)]
    pub input: InputArgs,
    #[command(flatten)]
    pub search: SearchArgs,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &UposArgs, quiet: bool) -> anyhow::Result<()> {
    let request = UposRequest {
        record: args.input.options(),
        orbits: args.search.options(),
    };
    request.check()?;
    let mut console = Console::new("orbits", quiet, false);
    let report = hb_pipeline::upos(args.input.source()?, &request, &mut console)?;
    console.finish();
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("{}", report.record.summary);
        print_table(&report.catalogue, report.delay, report.catalogue.tolerance());
    }
    Ok(())
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

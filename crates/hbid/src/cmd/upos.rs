//! `hbid upos`: unstable periodic orbits by close returns.

use clap::Args;
use upo_search::Catalogue;

use super::data::{InputArgs, SearchArgs};

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
    let bar = crate::progress::Progress::spinner("orbits", quiet);
    let data = args.input.load()?;
    let delay = args.search.delay(&data)?;
    let search = args.search.close_returns(&data, delay)?;
    let catalogue = search.catalogue_pieces(&data.x, &data.pieces)?;
    bar.finish();
    if args.json {
        println!(
            "{}",
            serde_json::to_string(&hb_pipeline::json::orbits(&catalogue))?
        );
    } else {
        println!("{}", data.summary());
        print_table(&catalogue, delay, catalogue.tolerance());
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

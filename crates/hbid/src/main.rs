//! `hbid`: identify the equation of motion of a forced oscillator from a measured record.
#![allow(clippy::print_stderr, clippy::print_stdout)]

mod cmd;
mod progress;

pub use hbid::{input, output};

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Identify the equation of motion of a forced, possibly whirling, oscillator from a record of
/// its angle (or displacement), knowing only the forcing frequency.
#[derive(Debug, Parser)]
#[command(name = "hbid", version, about)]
struct Cli {
    /// No progress bars.
    #[arg(long, global = true)]
    quiet: bool,
    /// Print the wall time of each stage on stderr at the end (identify).
    #[arg(long, global = true)]
    timings: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate the base-excited pendulum and write CSV t,theta,omega (defaults: the paper's data set).
    Simulate(cmd::simulate::SimulateArgs),
    /// Choose the delay (average mutual information) and check the embedding dimension (false nearest neighbours).
    Embed(cmd::embed::EmbedArgs),
    /// Find unstable periodic orbits by close returns.
    Upos(cmd::upos::UposArgs),
    /// Identify the equation of motion by harmonic balance.
    Identify(cmd::identify::IdentifyArgs),
    /// Embed, find orbits, identify and validate, and write a Markdown report with figures.
    Report(cmd::report::ReportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Ctrl-C: remove whatever is half-written (results are only renamed into place when
    // complete), then exit with the conventional status of an interrupt.
    let _ = ctrlc::set_handler(|| {
        output::remove_partial_files();
        eprintln!("interrupted: no output written");
        std::process::exit(130);
    });
    let result = match &cli.command {
        Command::Simulate(args) => cmd::simulate::run(args, cli.quiet),
        Command::Embed(args) => cmd::embed::run(args, cli.quiet),
        Command::Upos(args) => cmd::upos::run(args, cli.quiet),
        Command::Identify(args) => cmd::identify::run(args, cli.quiet, cli.timings),
        Command::Report(args) => {
            cmd::report::check_out(&args.out).and_then(|()| cmd::report::run(args, cli.quiet))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

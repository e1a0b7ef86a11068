//! `hbid`: identify the equation of motion of a forced oscillator from a measured record.
#![allow(clippy::print_stderr, clippy::print_stdout)]

mod cmd;
#[cfg(test)]
mod parity;
mod progress;

use hb_pipeline::output;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

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
    /// Simulate the base-excited pendulum, a two-well Duffing oscillator or a system of two coordinates as a rig records it (defaults: the paper's data set).
    ///
    /// The pendulum x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0 is written as CSV t,theta,omega
    /// (t,count,omega with --raw-counts), the Duffing oscillator x'' + c x' + a x + b x³ = f cos(t)
    /// as t,x,v; a file ending in .npy gets the same numbers as a samples × 3 f8 array. Without
    /// options this is the paper's data set: 30000 samples, 25 per drive period 2π, after 200
    /// periods, the angle wrapped into [-π, π).
    ///
    /// Systems of two coordinates (--system): the base-excited double pendulum
    /// (t,theta1,theta2,omega1,omega2: absolute angles), the torque-driven arm in seconds
    /// (t,q1,q2,v1,v2,tau1,tau2: q2 the elbow angle relative to link 1, the torques written as
    /// drive columns) and two coupled Duffing oscillators on a shaken base (t,x1,x2,v1,v2,a: a the
    /// base's acceleration). Each angle has its own encoder of the same settings, from its own
    /// stream of --seed; --gaps drops the same rows of every column; --truth writes each
    /// coordinate's equation under "equations" and the `hbid identify` options that identify them
    /// under "identify" (columns as NAME=POSITION: they read the CSV and the .npy alike).
    ///
    /// Time: with --drive-frequency HZ the record is in seconds (the model's time is
    /// τ = 2π·f_drive·t, the drive has period 1/f_drive s, velocities are per second); the sample
    /// step is 1/--sample-rate (any ratio to the drive) or the drive period over
    /// --samples-per-period. Stamps are the integration's time (the drive is sin(2π f_drive t) at
    /// them) or, with --time-origin first-sample, n·h from 0 with the drive at phase --phase.
    ///
    /// Encoder (angles): the encoder sees θ − --zero-offset, adds --noise, rounds to the nearest
    /// of --counts per revolution, adds --bit-errors, and reports count·2π/N in --angle-range (or
    /// the count itself with --raw-counts). --gaps drops runs of samples; --time-decimals and
    /// --decimals print as a data acquisition does. --truth writes the equation the record
    /// satisfies in the identification's form x'' + Σ c_i g_i = 0, in the record's time unit
    /// (damping × 2π f_drive, stiffness and drive × (2π f_drive)²), term names as
    /// `hbid identify` prints them.
    Simulate(Box<cmd::simulate::SimulateArgs>),
    /// Choose the delay (average mutual information) and check the embedding dimension (false nearest neighbours).
    Embed(cmd::embed::EmbedArgs),
    /// Find unstable periodic orbits by close returns.
    Upos(cmd::upos::UposArgs),
    /// Identify the equation of motion by harmonic balance.
    Identify(cmd::identify::IdentifyArgs),
    /// Embed, find orbits, identify (by both methods, or the one --method gives) and validate, and write a Markdown report with figures.
    Report(cmd::report::ReportArgs),
    /// Run a saved model freely under a record's measured input and score it against the record's measured output.
    ///
    /// The model starts each range (and each piece after a gap) from the state whose free run
    /// best matches the range's first --init samples, is driven by the record's drive column (a
    /// model with terms in p) or its own drive on the record's clock, and is scored on the samples
    /// after them: RMSE in the record's unit, NRMSE (RMSE over the measured output's standard
    /// deviation) and fit % = 100 (1 - |y - y_sim| / |y - mean(y)|). Friction terms stick at rest
    /// as in every simulation.
    Compare(cmd::compare::CompareArgs),
}

fn main() -> ExitCode {
    // Parsed from the matches, so that what the user gave (not a default) can be told.
    let parsed = Cli::command().try_get_matches().and_then(|matches| {
        let mut cli = Cli::from_arg_matches(&matches)?;
        if let Command::Report(args) = &mut cli.command {
            args.method_given = matches
                .subcommand_matches("report")
                .is_some_and(|m| m.value_source("method") == Some(clap::parser::ValueSource::CommandLine));
        }
        Ok(cli)
    });
    let cli = match parsed {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                e.exit();
            }
            // The error itself, without clap's usage lines and hint: one message, as every other
            // error of the command line.
            let text = e.render().to_string();
            eprintln!("{}", text.split("\n\n").next().unwrap_or(&text).trim_end());
            return ExitCode::from(2);
        }
    };
    // Standard output that cannot be written (a full disk, a reader that has closed its pipe):
    // `print!` panics on it. That is said in one line, after removing whatever is half-written
    // (nothing, for a closed pipe, whose reader asked for no more: the status a shell gives a
    // process a pipe's signal stopped), never as a panic's backtrace.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let text = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(why) = text.strip_prefix("failed printing to stdout: ") {
            output::remove_partial_files();
            if why.contains("Broken pipe") {
                std::process::exit(141);
            }
            eprintln!("error: cannot write the standard output: {why}");
            std::process::exit(1);
        }
        default_hook(info);
    }));
    // Ctrl-C, and a termination or hang-up (a job scheduler's kill, a closed terminal): remove
    // whatever is half-written (results are only renamed into place when complete), then exit
    // with the conventional status of an interrupt.
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
        Command::Compare(args) => cmd::compare::run(args, cli.quiet),
        Command::Report(args) => {
            cmd::report::check_out(&args.out).and_then(|()| cmd::report::run(args, cli.quiet))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Library messages name options as the command line and Python both read them;
            // here they are spelled as the command line writes them.
            eprintln!(
                "error: {}",
                hb_pipeline::Spelling::CommandLine.render(&message(&e))
            );
            ExitCode::FAILURE
        }
    }
}

/// The error and every cause behind it, joined by `: `, each cause left out when the text before
/// already holds it.
fn message(error: &anyhow::Error) -> String {
    message_of(error.as_ref())
}

/// [`message`] of any error: it and the chain of its sources.
pub(crate) fn message_of(error: &(dyn std::error::Error + 'static)) -> String {
    let mut text = String::new();
    for cause in std::iter::successors(Some(error), |e| e.source()) {
        let part = cause.to_string();
        if text.contains(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    text
}

//! Prints the tables of `docs/embedding.md` for the paper's data set:
//!
//! ```text
//! cargo run --release -p embedding --example paper_table [path/to/paper_dataset.csv]
//! ```
#![allow(clippy::print_stdout)]

use std::time::Instant;

use embedding::{AmiParams, Domain, FnnParams, average_mutual_information, false_nearest_neighbours};

/// TISEAN `false_nearest` at delay 5, ratio 10, no Theiler window, d = 1..6.
const CLASSIC_FNN: [f64; 6] = [1.000, 0.776, 0.196, 0.033, 0.014, 0.008];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/fixtures/paper_dataset.csv"
        )
        .to_owned()
    });
    let theta = read_theta(&path)?;
    println!("{} samples from {path}\n", theta.len());

    let clock = Instant::now();
    let lin = average_mutual_information(&theta, &AmiParams::new(Domain::Line))?;
    let ami_time = clock.elapsed();
    let circ = average_mutual_information(&theta, &AmiParams::new(Domain::Circle))?;
    println!("| lag | I linear (nats) | I circle (nats) |");
    println!("| --- | --- | --- |");
    for lag in 0..=15 {
        println!("| {lag} | {:.4} | {:.4} |", lin.values[lag], circ.values[lag]);
    }
    let delay = lin.delay()?;
    println!(
        "\nfirst minimum: linear {delay}, circle {} (paper: 5; AMI of 41 lags in {:.1} ms)\n",
        circ.delay()?,
        ami_time.as_secs_f64() * 1e3
    );

    // Defaults (Kennel's two tests), then TISEAN's rule (ratio test only, neighbours farther
    // than R_A / R_tol left out), for both metrics.
    let mut rows = Vec::new();
    for metric in [Domain::Line, Domain::Circle] {
        let defaults = FnnParams::new(metric, delay)?;
        let tisean = defaults
            .with_attractor_threshold(None)?
            .with_neighbour_cutoff(Some(0.1))?;
        for (rule, params) in [("defaults", defaults), ("TISEAN rule", tisean)] {
            let clock = Instant::now();
            let r = false_nearest_neighbours(&theta, &params)?;
            println!(
                "{metric:?}, {rule}: R_A = {:.4}, minimum dimension {:?}, d = 1..8 in {:.2} s",
                r.attractor_size,
                r.minimum_dimension(),
                clock.elapsed().as_secs_f64()
            );
            rows.push(r);
        }
    }
    println!();
    println!(
        "| d | linear, defaults | linear, TISEAN rule | circle, defaults | circle, TISEAN rule | TISEAN | paper |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for d in 1..=8 {
        let f: Vec<String> = rows
            .iter()
            .map(|r| format!("{:.4}", r.levels[d - 1].fraction()))
            .collect();
        let classic = CLASSIC_FNN
            .get(d - 1)
            .map_or(String::new(), |v| format!("{v:.3}"));
        let paper = if d == 4 { "d_E = 4" } else { "" };
        println!("| {d} | {} | {classic} | {paper} |", f.join(" | "));
    }
    println!();
    println!("| d | linear: ratio test | linear: size test | circle: ratio test | circle: size test |");
    println!("| --- | --- | --- | --- | --- |");
    for d in 1..=8 {
        let (l, c) = (&rows[0].levels[d - 1], &rows[2].levels[d - 1]);
        println!(
            "| {d} | {} | {} | {} | {} |",
            l.ratio_false, l.size_false, c.ratio_false, c.size_false
        );
    }
    Ok(())
}

fn read_theta(path: &str) -> Result<Vec<f64>, Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string(path)?;
    let mut theta = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let field = line.split(',').nth(1).ok_or("a row without a theta column")?;
        theta.push(field.trim().parse()?);
    }
    Ok(theta)
}

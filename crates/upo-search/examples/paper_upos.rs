//! Close returns and distinct orbits of a wrapped-angle record, as a Markdown table.
//!
//! ```text
//! cargo run --release -p upo-search --example paper_upos -- [CSV] [P] [TD] [E] [D] [KMAX]
//! ```
//!
//! Defaults: the paper's data set (`shared/fixtures/paper_dataset.csv`, columns `t,theta`, `#`
//! comments), P = 25, Td = 5, e = 0.03, d = 2, k_max = 16. The angle is the second column.
#![allow(clippy::print_stdout)]

use std::time::Instant;
use upo_search::CloseReturns;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().cloned().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/fixtures/paper_dataset.csv"
        )
        .to_owned()
    });
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.to_owned());
    let p: usize = arg(1, "25").parse()?;
    let td: usize = arg(2, "5").parse()?;
    let e: f64 = arg(3, "0.03").parse()?;
    let d: usize = arg(4, "2").parse()?;
    let k_max: usize = arg(5, "16").parse()?;

    let text = std::fs::read_to_string(&path)?;
    let mut theta = Vec::new();
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
    {
        let field = line.split(',').nth(1).ok_or("expected two columns")?;
        theta.push(field.trim().parse::<f64>()?);
    }

    let search = CloseReturns::builder(&upo_search::SampleClock::nondimensional(p)?, td)
        .tolerance(e)
        .max_period(k_max)
        .dimension(d)
        .build()?;
    let segments = search.search(&theta)?;
    let cat = search.catalogue(&theta)?;
    assert_eq!(cat.segments(), segments.as_slice());
    // Best of 20 (the first call also starts the thread pool).
    let best_of = |f: &dyn Fn()| {
        (0..20)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let search_time = best_of(&|| {
        std::hint::black_box(search.search(&theta).ok());
    });
    let total_time = best_of(&|| {
        std::hint::black_box(search.catalogue(&theta).ok());
    });

    println!(
        "{} samples, P = {p}, Td = {td}, d = {d}, e = {e} (ε = {:.4} rad), periods 1..={k_max}\n",
        theta.len(),
        cat.tolerance()
    );
    println!("| period | segments | distinct orbits | least error (rad) |");
    println!("| ---: | ---: | ---: | ---: |");
    for c in cat.counts() {
        let least = cat
            .segments()
            .iter()
            .filter(|s| s.period() == c.period)
            .map(|s| s.error())
            .fold(f64::INFINITY, f64::min);
        let least = if least.is_finite() {
            format!("{least:.4}")
        } else {
            "-".to_owned()
        };
        println!("| {} | {} | {} | {least} |", c.period, c.segments, c.orbits);
    }
    let counts = cat.counts();
    println!(
        "| total | {} | {} | |",
        counts.iter().map(|c| c.segments).sum::<usize>(),
        counts.iter().map(|c| c.orbits).sum::<usize>()
    );
    println!(
        "\nsearch {:.2} ms; search + catalogue {:.2} ms (best of 20)",
        search_time * 1e3,
        total_time * 1e3
    );
    Ok(())
}

#![allow(missing_docs, clippy::print_stdout)]
use circle_signal::{Domain, SpikeParams, find_spikes_in_place};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let bytes = std::fs::read(&args[1]).unwrap();
    let mut x: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    for v in &mut x {
        *v = circle_signal::wrap(*v);
    }
    let reps: usize = args.get(2).map_or(5, |s| s.parse().unwrap());
    let p = SpikeParams::new();
    let mut times = vec![];
    let mut count = 0;
    let mut sum = 0.0;
    for _ in 0..reps {
        let t = Instant::now();
        let s = find_spikes_in_place(&mut x, Domain::Circle, &p).unwrap();
        times.push(t.elapsed().as_secs_f64());
        count = s.as_slice().len();
        sum = s
            .as_slice()
            .iter()
            .map(|s| s.index as f64 + s.replacement)
            .sum::<f64>();
    }

    times.sort_by(f64::total_cmp);
    println!(
        "{}: {} spikes (check {sum:.12e}), median {:.4} s, min {:.4}",
        args[1],
        count,
        times[reps / 2],
        times[0]
    );
}

//! The grid fit on time columns as a reader would hand them over: either any finite numbers, or
//! a clock `t0 + n · dt` written with a number of decimals, with gaps, glitches (off the grid,
//! repeated, backwards, swapped) and jitter where the fuzzer puts them.
#![no_main]

use hb_record::input::Record;
use hbid_fuzz::fit_and_check;
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
enum Event {
    /// Skip this many samples (mod 10 000).
    Gap(u16),
    /// Move the stamp by this fraction of a step.
    Off(f32),
    /// The previous stamp again.
    Repeat,
    /// Swap with the next stamp.
    Swap,
    /// Set the stamp to any number.
    Any(f64),
    /// Start the clock again from this time.
    Reset(f64),
}

#[derive(Arbitrary, Debug)]
enum Stamps {
    /// Any numbers (non-finite ones become 0: readers never hand them over).
    Raw(Vec<f64>),
    /// A clock.
    Clock {
        t0: f64,
        dt: f64,
        /// Written with this many decimals (mod 20); none when 20 or more.
        decimals: u8,
        /// Samples (mod 2 000).
        n: u16,
        /// Events at samples, in order.
        events: Vec<(u16, Event)>,
    },
}

fn stamps(s: &Stamps) -> Vec<f64> {
    match s {
        Stamps::Raw(t) => t.iter().map(|&v| if v.is_finite() { v } else { 0.0 }).collect(),
        Stamps::Clock {
            t0,
            dt,
            decimals,
            n,
            events,
        } => {
            let n = usize::from(*n % 2000);
            let mut k = 0.0f64;
            let mut t = Vec::with_capacity(n);
            let mut events = events.iter().peekable();
            for i in 0..n {
                let mut stamp = t0 + k * dt;
                while let Some((_, event)) = events.next_if(|(at, _)| usize::from(*at) <= i) {
                    match *event {
                        Event::Gap(g) => {
                            k += f64::from(g % 10_000);
                            stamp = t0 + k * dt;
                        }
                        Event::Off(f) => stamp += f64::from(f) * dt,
                        Event::Repeat => stamp = t.last().copied().unwrap_or(stamp),
                        Event::Swap => {}
                        Event::Any(v) => stamp = v,
                        Event::Reset(v) => {
                            k = 0.0;
                            stamp = t0 + v;
                        }
                    }
                }
                t.push(stamp);
                k += 1.0;
            }
            for (at, event) in events {
                if let (Event::Swap, i) = (event, usize::from(*at)) {
                    if i + 1 < t.len() {
                        t.swap(i, i + 1);
                    }
                }
            }
            if decimals % 32 < 20 {
                let k = usize::from(decimals % 32);
                // Only where the decimals change anything: printing 1e300 exactly is slow.
                for v in t.iter_mut().filter(|v| v.abs() < 1e17) {
                    *v = format!("{v:.k$}").parse().unwrap_or(*v);
                }
            }
            t.iter().map(|&v| if v.is_finite() { v } else { 0.0 }).collect()
        }
    }
}

fuzz_target!(|input: (Stamps, bool, bool)| {
    let (s, repair, with_lines) = input;
    let t = stamps(&s);
    let n = t.len();
    let record = Record {
        theta: (0..n).map(|i| i as f64).collect(),
        // As a text reader numbers lines, after a header and with a comment line.
        lines: with_lines.then(|| (0..n as u64).map(|i| i + 2 + u64::from(i > 10)).collect()),
        t,
        drive: None,
    };
    fit_and_check(record, repair);
});

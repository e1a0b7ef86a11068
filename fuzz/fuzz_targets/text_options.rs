//! Text with every read option: time and angle columns by name (parsed as the command line parses
//! them, or any name) or by position (any, 0 included), a sampling step (any number), and the
//! grid fit with or without repair. The text is built from cells the fuzzer picks (numbers in
//! every notation, names, quotes) and separators, so that most inputs get past the first row.
#![no_main]

use hb_record::input::{Column, ReadOptions, read_bytes};
use hbid_fuzz::{check_error, check_record, fit_and_check, line_count};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
enum Choice {
    /// Parsed as the command line parses a column option.
    Parsed(String),
    /// One of the names records use.
    Known(u8),
    /// Any position, 0 and past the last column included.
    Position(usize),
}

const NAMES: [&str; 8] = ["t", "theta", "x", "angle", "time", "omega", "", "\"t\""];

impl Choice {
    fn column(&self) -> Option<Column> {
        match self {
            Choice::Parsed(s) => s.parse().ok(),
            Choice::Known(i) => Some(Column::Name(NAMES[*i as usize % NAMES.len()].to_owned())),
            Choice::Position(p) => Some(Column::Position(*p)),
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Cell {
    Name(u8),
    Integer(i64),
    Float(f64),
    /// A number with this many decimals (mod 20), as a logger writes it.
    Fixed(f64, u8),
    Exponent(f64),
    /// A decimal comma.
    Comma(f64, u8),
    Quoted(Box<Cell>),
    Text(String),
}

impl Cell {
    fn write(&self, out: &mut String) {
        match self {
            Cell::Name(i) => out.push_str(NAMES[*i as usize % NAMES.len()]),
            Cell::Integer(v) => out.push_str(&v.to_string()),
            Cell::Float(v) => out.push_str(&v.to_string()),
            Cell::Fixed(v, k) => out.push_str(&format!("{v:.*}", usize::from(k % 20))),
            Cell::Exponent(v) => out.push_str(&format!("{v:e}")),
            Cell::Comma(v, k) => out.push_str(&format!("{v:.*}", usize::from(k % 20)).replacen('.', ",", 1)),
            Cell::Quoted(c) => {
                out.push('"');
                c.write(out);
                out.push('"');
            }
            Cell::Text(s) => out.push_str(s),
        }
    }
}

#[derive(Arbitrary, Debug)]
struct Input {
    time: Option<Choice>,
    angle: Option<Choice>,
    dt: Option<f64>,
    /// The separator of each row: `,` `;` ` ` `\t` or a run of white space.
    separators: Vec<u8>,
    rows: Vec<Vec<Cell>>,
    /// Line ends and comment lines.
    crlf: bool,
    comments: Vec<u16>,
}

const SEPARATORS: [&str; 6] = [",", ";", " ", "\t", "  \t ", " , "];

fn text(input: &Input) -> String {
    let mut out = String::new();
    let end = if input.crlf { "\r\n" } else { "\n" };
    for (r, row) in input.rows.iter().enumerate() {
        if input.comments.contains(&(r as u16)) {
            out.push_str("# comment");
            out.push_str(end);
        }
        let s = input
            .separators
            .get(r)
            .or(input.separators.first())
            .copied()
            .unwrap_or(0);
        let separator = SEPARATORS[s as usize % SEPARATORS.len()];
        for (c, cell) in row.iter().enumerate() {
            if c > 0 {
                out.push_str(separator);
            }
            cell.write(&mut out);
        }
        out.push_str(end);
    }
    out
}

fuzz_target!(|input: Input| {
    let options = ReadOptions {
        time: input.time.as_ref().and_then(Choice::column),
        angle: input.angle.as_ref().and_then(Choice::column),
        dt: input.dt,
        drive: None,
    };
    let text = text(&input);
    let lines = line_count(text.as_bytes());
    match read_bytes(text.as_bytes(), &options) {
        Ok(record) => {
            check_record(&record, Some(lines));
            // Unwrapped angles read as times too: the fit takes any finite column.
            let swapped = hb_record::input::Record {
                t: record.theta.clone(),
                theta: record.t.clone(),
                lines: record.lines.clone(),
                drive: None,
            };
            fit_and_check(swapped, true);
        }
        Err(e) => check_error(&e, lines, 0),
    }
});

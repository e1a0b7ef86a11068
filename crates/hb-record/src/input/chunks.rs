//! A record file read a chunk of rows at a time: a long record in memory that does not grow with
//! it.
//!
//! Each chunk is read by the same reader as a whole file ([`super::read_bytes`]): an `.npy`
//! chunk is its rows under a header of their own shape, a text chunk its lines after the file's
//! own lines before its first row of data (comments, the header), so that columns, separators and
//! names are found as in the whole file. Chunks overlap: each begins with the last `keep` rows of
//! the one before. What a chunk's reading names by place is then placed in the file
//! ([`Chunk::relocate`]): a line of text by the file's count, a sample of an array by its row.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use super::{InputError, Location, ReadOptions, Record, read_up_to};

/// A record file read in chunks of rows; see the module docs.
#[derive(Debug)]
pub struct Chunks {
    path: PathBuf,
    options: ReadOptions,
    source: Source,
    /// Rows delivered so far (the next chunk's new rows start here).
    rows: usize,
    /// Bytes of the file read so far.
    bytes: u64,
    /// A text's lines of the chunk delivered last, in `held_text` (an `.npy`'s rows are read
    /// again).
    held: Vec<HeldLine>,
    held_text: Vec<u8>,
    done: bool,
}

#[derive(Debug)]
enum Source {
    Npy {
        file: File,
        /// Where the rows start.
        offset: u64,
        /// Rows in the file.
        rows: usize,
        /// Columns, and bytes per row.
        cols: usize,
        row_bytes: usize,
        /// The element type as the header writes it (`'<f8'`).
        descr: String,
    },
    Text {
        reader: BufReader<File>,
        /// The file's lines before its first row of data, each chunk's first lines.
        prefix: Vec<u8>,
        /// How many lines that is.
        prefix_lines: u64,
        /// Lines of the file read so far.
        line: u64,
    },
}

/// One chunk: its rows as a record, where they sit in the file, and whether it is the last.
#[derive(Debug)]
pub struct Chunk {
    /// The rows, read as a file of them would be (times of a record without a time column
    /// counted from the file's first row).
    pub record: Record,
    /// The file's row (from 0, rows of data only) of the record's first sample.
    pub first_row: usize,
    /// How many of its first rows the chunk before held too.
    pub repeated: usize,
    /// Whether no row follows.
    pub last: bool,
    /// For text: the line of the file (from 1) each line of the chunk's own text (prefix
    /// included) stands for, to relocate what names a line.
    lines: Option<Vec<u64>>,
}

impl Chunk {
    /// `at`, a place the conditioning of [`Chunk::record`] names, as a place in the file: a
    /// sample of an array counted from the file's first row (a line of text is the file's
    /// already: the record's lines are).
    pub fn relocate(&self, at: Location) -> Location {
        match at {
            Location::Sample(n) => Location::Sample(n + self.first_row),
            line => line,
        }
    }

    /// `at`, a place the reading of the chunk's own bytes names, as a place in the file.
    fn relocate_read(&self, at: Location) -> Location {
        match (at, &self.lines) {
            (Location::Line(n), Some(lines)) => {
                Location::Line(lines.get((n as usize).saturating_sub(1)).copied().unwrap_or(n))
            }
            (at, _) => self.relocate(at),
        }
    }
}

/// Whether a file is read in chunks ([`Chunks::open`]) or only whole.
#[derive(Debug)]
pub enum Opened {
    /// In chunks.
    Chunks(Box<Chunks>),
    /// Whole only, and why (an `.npy` in Fortran order, standard input).
    Whole(&'static str),
}

impl Chunks {
    /// Opens `path` to be read in chunks with `options`; [`Opened::Whole`] for a file that can
    /// only be read whole.
    ///
    /// Errors: the options' ([`ReadOptions::validate`]), a file that cannot be opened, an
    /// `.npy` header that cannot be read.
    pub fn open(path: &Path, options: &ReadOptions) -> Result<Opened, InputError> {
        options.validate()?;
        if path == Path::new("-") {
            return Ok(Opened::Whole("standard input is read whole"));
        }
        let io = |source| InputError::Io {
            path: path.to_owned(),
            source,
        };
        if path.is_dir() {
            return Err(InputError::IsFolder {
                path: path.to_owned(),
            });
        }
        // Chunks are read where they lie in the file: a pipe (a named one, a shell's `<(…)`) has
        // no places to go back to. Asked before opening it, which waits for a pipe's writer.
        if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
            return Ok(Opened::Whole(
                "a pipe or device, not a regular file, is read whole",
            ));
        }
        let mut file = File::open(path).map_err(io)?;
        let mut magic = [0u8; 6];
        let n = read_up_to(&mut file, &mut magic).map_err(io)?;
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        let source = if n == 6 && &magic == b"\x93NUMPY" {
            match npy_source(file).map_err(|e| match e {
                Header::Io(source) => io(source),
                Header::Bad(why) => InputError::Npy { why },
                Header::Input(e) => e,
            })? {
                Some(s) => s,
                None => return Ok(Opened::Whole("an .npy array in Fortran order is read whole")),
            }
        } else {
            // A text whose lines end in CR alone (the reader's other line end) is one line to a
            // reader of lines ending in LF: read whole.
            let mut head = vec![0u8; 1 << 16];
            let got = read_up_to(&mut file, &mut head).map_err(io)?;
            file.seek(SeekFrom::Start(0)).map_err(io)?;
            let head = &head[..got];
            if memchr::memchr(b'\n', head).is_none() && memchr::memchr(b'\r', head).is_some() {
                return Ok(Opened::Whole("a text whose lines end in CR alone is read whole"));
            }
            Source::Text {
                reader: BufReader::with_capacity(1 << 20, file),
                prefix: Vec::new(),
                prefix_lines: 0,
                line: 0,
            }
        };
        Ok(Opened::Chunks(Box::new(Self {
            path: path.to_owned(),
            options: options.clone(),
            source,
            rows: 0,
            bytes: 0,
            held: Vec::new(),
            held_text: Vec::new(),
            done: false,
        })))
    }

    /// The bytes of the file read so far (with the rows delivered, an estimate of a text's
    /// rows from its size).
    pub fn bytes_read(&self) -> u64 {
        self.bytes
    }

    /// The rows of the file, where its format says (an `.npy`'s header); `None` for text.
    pub fn total_rows(&self) -> Option<usize> {
        match &self.source {
            Source::Npy { rows, .. } => Some(*rows),
            Source::Text { .. } => None,
        }
    }

    /// The next chunk: the last `keep` rows of the chunk before (fewer for the first) and then
    /// `rows` new ones (fewer at the end of the file); `None` when every row was delivered.
    ///
    /// Errors: the file's reading, and the reader's on the chunk's rows (their places in the
    /// file, not in the chunk).
    pub fn next_chunk(&mut self, rows: usize, keep: usize) -> Result<Option<Chunk>, InputError> {
        if self.done {
            return Ok(None);
        }
        let io = |source| InputError::Io {
            path: self.path.clone(),
            source,
        };
        let (bytes, first_row, repeated, lines, last) = match &mut self.source {
            Source::Npy {
                file,
                offset,
                rows: total,
                cols,
                row_bytes,
                descr,
            } => {
                // The rows repeated are read again.
                let repeated = keep.min(self.rows);
                let first_row = self.rows - repeated;
                let new = rows.min(*total - self.rows);
                if new == 0 && self.rows > 0 {
                    self.done = true;
                    return Ok(None);
                }
                let count = repeated + new;
                let mut bytes = npy_header(descr, count, *cols);
                let start = bytes.len();
                bytes.resize(start + count * *row_bytes, 0);
                file.seek(SeekFrom::Start(*offset + (first_row * *row_bytes) as u64))
                    .map_err(io)?;
                file.read_exact(&mut bytes[start..]).map_err(io)?;
                self.rows += new;
                self.bytes = *offset + (self.rows * *row_bytes) as u64;
                let last = self.rows == *total;
                (bytes, first_row, repeated, None, last)
            }
            Source::Text {
                reader,
                prefix,
                prefix_lines,
                line,
            } => {
                // The lines of the last `keep` rows of data held (and any comment among them),
                // after the file's prefix; then lines up to `rows` more rows of data, read in
                // blocks.
                let mut counted = 0;
                let mut from = self.held.len();
                while from > 0 && counted < keep {
                    from -= 1;
                    if self.held[from].data {
                        counted += 1;
                    }
                }
                while from < self.held.len() && self.held[from].line <= *prefix_lines {
                    from += 1;
                }
                let held_until = self.held.last().map_or(0, |h| h.line);
                let mut bytes = Vec::with_capacity(prefix.len() + 64 * (rows + keep));
                bytes.extend_from_slice(prefix);
                let mut lines: Vec<u64> = (1..=*prefix_lines).collect();
                let mut held = Vec::with_capacity(rows + keep);
                if let Some(first) = self.held.get(from) {
                    let shift = bytes.len() as isize - first.start as isize;
                    bytes.extend_from_slice(&self.held_text[first.start..]);
                    for h in &self.held[from..] {
                        lines.push(h.line);
                        held.push(HeldLine {
                            start: (h.start as isize + shift) as usize,
                            ..*h
                        });
                    }
                }
                // The chunk before's text is not needed past its rows repeated.
                self.held_text = Vec::new();
                self.held = Vec::new();
                let (mut data_rows, mut new_lines) = (0, 0);
                while data_rows < rows {
                    let block = reader.fill_buf().map_err(io)?;
                    if block.is_empty() {
                        break;
                    }
                    let mut used = 0;
                    while data_rows < rows && used < block.len() {
                        let rest = &block[used..];
                        let Some(end) = memchr::memchr(b'\n', rest) else {
                            // A line that goes on past the block: read on.
                            break;
                        };
                        *line += 1;
                        data_rows +=
                            usize::from(push_line(&mut bytes, &mut held, &mut lines, *line, &rest[..=end]));
                        new_lines += 1;
                        used += end + 1;
                    }
                    if used == 0 {
                        // No line end in the block: the line is longer than the buffer, or the
                        // file's last line has none.
                        let mut text = Vec::new();
                        let n = reader.read_until(b'\n', &mut text).map_err(io)?;
                        self.bytes += n as u64;
                        if !text.ends_with(b"\n") {
                            text.push(b'\n');
                        }
                        *line += 1;
                        data_rows += usize::from(push_line(&mut bytes, &mut held, &mut lines, *line, &text));
                        new_lines += 1;
                        continue;
                    }
                    self.bytes += used as u64;
                    reader.consume(used);
                }
                let last = reader.fill_buf().map_err(io)?.is_empty();
                if new_lines == 0 && self.rows > 0 {
                    self.done = true;
                    return Ok(None);
                }
                self.held = held;
                (bytes, held_until as usize, 0, Some(lines), last)
            }
        };
        self.done = last;
        let mut chunk = Chunk {
            record: Record::default(),
            first_row,
            repeated,
            last,
            lines,
        };
        let record = super::read_valid(&bytes, &self.options)
            .map_err(|e| e.relocated(&|at| chunk.relocate_read(at)))?;
        chunk.record = record;
        // A text chunk's lines as the file's; the rows it repeats are those of the lines held
        // (`held_until`, passed as `first_row` above); its prefix, from the first chunk, the lines
        // before the first row of data (comments, the header).
        if let (Some(own), Some(map)) = (chunk.record.lines.as_mut(), chunk.lines.as_ref()) {
            for n in own.iter_mut() {
                *n = map.get((*n as usize).saturating_sub(1)).copied().unwrap_or(*n);
            }
        }
        if let Source::Text {
            prefix, prefix_lines, ..
        } = &mut self.source
        {
            let held_until = chunk.first_row as u64;
            let own = chunk.record.lines.as_deref().unwrap_or(&[]);
            let repeated = own.iter().take_while(|&&n| n <= held_until).count();
            if self.rows == 0
                && prefix.is_empty()
                && let Some(&first_data) = own.first()
            {
                let before = first_data - 1;
                let mut at = 0;
                for _ in 0..before {
                    at += memchr::memchr(b'\n', &bytes[at..]).map_or(bytes.len() - at, |i| i + 1);
                }
                *prefix = bytes[..at].to_vec();
                *prefix_lines = before;
            }
            if own.len() == repeated && self.rows > 0 {
                // Only blank lines or comments after the rows delivered.
                self.done = true;
                return Ok(None);
            }
            chunk.repeated = repeated;
            chunk.first_row = self.rows - repeated;
            self.rows += own.len() - repeated;
            // The chunk's lines are held until the next call says how many rows it repeats.
        }
        if matches!(self.source, Source::Text { .. }) {
            self.held_text = bytes;
        }
        // Times of a record without a time column from the file's first row.
        if let Some(dt) = self.options.dt {
            // The chunk's first row of data (a text's found above from its lines).
            let first = chunk.first_row;
            for (i, t) in chunk.record.t.iter_mut().enumerate() {
                *t = (first + i) as f64 * dt;
            }
        }
        Ok(Some(chunk))
    }
}

/// A line of text held: its number in the file, where it starts in the text held, and whether it
/// holds a row of data.
#[derive(Debug, Clone, Copy)]
struct HeldLine {
    line: u64,
    start: usize,
    data: bool,
}

/// Appends line number `line` (its `text`, ending in LF) to a chunk's `bytes`, its index `held`
/// and its `lines`; whether it holds a row of data.
fn push_line(
    bytes: &mut Vec<u8>,
    held: &mut Vec<HeldLine>,
    lines: &mut Vec<u64>,
    line: u64,
    text: &[u8],
) -> bool {
    let data = !is_blank_or_comment(text);
    held.push(HeldLine {
        line,
        start: bytes.len(),
        data,
    });
    lines.push(line);
    bytes.extend_from_slice(text);
    data
}

/// Whether a line holds no row of data for the reader: blank, or a comment (`#`).
fn is_blank_or_comment(line: &[u8]) -> bool {
    let text = line.trim_ascii();
    text.is_empty() || text.starts_with(b"#")
}

enum Header {
    Io(std::io::Error),
    Bad(String),
    Input(InputError),
}

/// An `.npy` file's rows: where they start, their number, width and element type; `None` for
/// an array in Fortran order (its rows are not contiguous).
fn npy_source(mut file: File) -> Result<Option<Source>, Header> {
    let mut head = [0u8; 12];
    let n = read_up_to(&mut file, &mut head).map_err(Header::Io)?;
    if n < 10 {
        return Err(Header::Bad("the header is cut short".into()));
    }
    let (len, at) = match head[6] {
        1 => (u16::from_le_bytes([head[8], head[9]]) as usize, 10),
        2 | 3 if n >= 12 => (
            u32::from_le_bytes([head[8], head[9], head[10], head[11]]) as usize,
            12,
        ),
        v => return Err(Header::Bad(format!("format version {v} is not supported"))),
    };
    let size = file.metadata().map_err(Header::Io)?.len();
    if (at + len) as u64 > size {
        return Err(Header::Bad("the header is longer than the file".into()));
    }
    let mut header = vec![0u8; at + len];
    file.seek(SeekFrom::Start(0)).map_err(Header::Io)?;
    file.read_exact(&mut header).map_err(Header::Io)?;
    super::npy::check_header(&header).map_err(Header::Input)?;
    let parsed = npyz::NpyHeader::from_reader(&mut &header[..]).map_err(|e| Header::Bad(e.to_string()))?;
    if parsed.order() == npyz::Order::Fortran {
        return Ok(None);
    }
    let shape = parsed.shape();
    let (rows, cols) = match shape {
        [r] => (*r as usize, 1),
        [r, c] => (*r as usize, *c as usize),
        _ => {
            return Err(Header::Bad(format!(
                "an array of {} dimensions is not a record",
                shape.len()
            )));
        }
    };
    let dtype = parsed.dtype();
    let item = dtype
        .num_bytes()
        .ok_or_else(|| Header::Bad("the element type has no fixed size".into()))?;
    let row_bytes = item
        .checked_mul(cols.max(1))
        .ok_or_else(|| Header::Bad("shape overflows".into()))?;
    let payload = size - (at + len) as u64;
    if (payload as u128) < rows as u128 * row_bytes as u128 || row_bytes == 0 {
        return Err(Header::Bad(format!(
            "the header announces {rows} rows of {row_bytes} bytes, the file holds {payload} bytes after it"
        )));
    }
    Ok(Some(Source::Npy {
        file,
        offset: (at + len) as u64,
        rows,
        cols,
        row_bytes,
        descr: dtype.descr(),
    }))
}

/// A format 1.0 `.npy` header for `rows` rows of `cols` elements of type `descr` (as a header
/// writes it, quotes included), padded to 64 bytes.
fn npy_header(descr: &str, rows: usize, cols: usize) -> Vec<u8> {
    let mut dict = format!("{{'descr': {descr}, 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    let total = 10 + dict.len() + 1;
    dict.extend(std::iter::repeat_n(' ', total.next_multiple_of(64) - total));
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out
}

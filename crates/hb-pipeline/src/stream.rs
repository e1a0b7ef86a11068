//! Identification of a long record read in chunks: memory that does not grow with the record.
//!
//! The file is read [`CHUNK_ROWS`] rows at a time ([`hb_record::input::Chunks`]), each chunk
//! beginning with the last rows of the one before. Each chunk is conditioned as a record of its
//! own (time stamps fitted to its grid, spikes, resampling), on the clock the first chunk found
//! (a given drive, or the first chunk's estimate of it, or its free period); its windows are
//! those of the whole record's lattice (every window's step from the record's first sample) that
//! start in the chunk's own stretch, between the middles of its overlaps with its neighbours, so
//! each window is taken once, from the chunk that holds it with room on both sides. Each chunk's
//! rows are assembled and compressed by groups of windows at once
//! ([`Identifier::systems_grouped`]); the fit, its held-out share and the bootstrap work from
//! those blocks. A record without gaps, spikes or resampling gives the windows and the rows of
//! an identification in memory, so the same coefficients to rounding (each chunk's grid is
//! fitted to its own stamps: 10^7 samples agree to 1e-10 of the largest coefficient,
//! `docs/scale.md`). After a gap the windows start on the lattice, not at the piece's first
//! sample; a resampled record's chunks are each resampled from their own first sample.
//!
//! What the whole record decides is decided by the first chunk: the drive's estimate
//! (`drive_frequency=auto`) or the free period, and the check that a coupled model's mass matrix
//! can be solved (at the first chunk's states). The chunks' notes are merged: the spikes and the
//! rows written twice of each chunk's own stretch into one note each, the gaps counted from the
//! record's pieces, the grid's note the worst chunk's, any other note told once.

use std::ops::Range;
use std::path::Path;

use circle_signal::Segment;
use circle_signal::Spike;
use hb_record::input::{Chunks, Location, Opened};
use hb_record::prepare::{Data, Note, PeriodSource};
use hb_solve::identifier::Identifier;
use hb_solve::{LinearSystem, MAX_BLOCKS, Signals};

use crate::drive::DriveSpec;
use crate::error::RunError;
use crate::identify::{Assembled, IdentifyReport, IdentifyRequest, States, finish, windows_found};
use crate::observe::{Notice, Observer, Stage};
use crate::options::OptionError;
use crate::pipeline::{Method, Record};
use crate::record::{RecordSummary, condition_read, on_clock};
use circle_signal::Measured;

/// New rows of a file per chunk: about 2 · 10^6 (tens of megabytes per column in memory).
pub const CHUNK_ROWS: usize = 1 << 21;

/// Files at least this large (256 MiB) are read in chunks by default.
pub const STREAM_BYTES: u64 = 256 << 20;

/// Samples of room a chunk keeps on each side of its windows for the conditioning of its
/// samples to be the whole record's there (the spike search looks a few hundred samples about a
/// sample; the grid fit's running medians less).
pub const CONDITIONING_MARGIN: usize = 4096;

/// Whether [`crate::identify`] reads `path` in chunks for `request`: as the option `stream`
/// says, or (not given) for a file of at least [`STREAM_BYTES`] whose identification can be
/// streamed. A stream asked for on a request that cannot be streamed is an error naming what
/// stands in the way.
pub(crate) fn streams(path: &Path, request: &IdentifyRequest) -> Result<bool, RunError> {
    let asked = request.options().stream;
    if asked == Some(false) {
        return Ok(false);
    }
    let why_not = if request.options().method == Method::Upo {
        Some("the paper's method («method=upo») searches the whole record for its orbits")
    } else if request.options().record.measured != Measured::Displacement {
        Some("an integrated record's drift is fitted over the whole record («measured»)")
    } else if request.options().refine {
        Some("the refinement («refine») runs the model over the whole record")
    } else if request.options().record.bridge_gaps > 0 {
        Some("a gap is bridged («bridge_gaps») within one chunk's reading, not across two")
    } else if request.options().record.skip_missing {
        Some(
            "rows with a missing value are left out («skip_missing») of a file read whole: chunks overlap by rows",
        )
    } else if path == Path::new("-") {
        Some("standard input is read whole")
    } else {
        None
    };
    match (asked, why_not) {
        (Some(true), Some(why)) => {
            Err(OptionError::new("stream", format!("cannot read the record in chunks: {why}")).into())
        }
        (Some(true), None) => Ok(true),
        (_, Some(_)) => Ok(false),
        (_, None) => Ok(std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.len() >= STREAM_BYTES)),
    }
}

/// Identifies the record of the file `path` read in chunks, as `request` asks (see the module
/// docs); `observer` hears the reading's progress (bytes of the file read) and every notice, the
/// chunks' merged.
pub fn identify_streamed(
    path: &Path,
    request: &IdentifyRequest,
    observer: &mut dyn Observer,
) -> Result<IdentifyReport, RunError> {
    streamed_in(path, request, observer, CHUNK_ROWS)
}

/// [`identify_streamed`] in chunks of `chunk_rows` new rows (at least four overlaps').
fn streamed_in(
    path: &Path,
    request: &IdentifyRequest,
    observer: &mut dyn Observer,
    chunk_rows: usize,
) -> Result<IdentifyReport, RunError> {
    let options = &request.options().record;
    options.check()?;
    let name = path.display().to_string();
    let read_error = |source| RunError::Read {
        name: name.clone(),
        source: Box::new(source),
        coords: options.coords.is_some(),
    };
    let mut chunks = match Chunks::open(path, &options.read_options()?).map_err(read_error)? {
        Opened::Chunks(c) => *c,
        Opened::Whole(why) => {
            return Err(
                OptionError::new("stream", format!("cannot read the record in chunks: {why}")).into(),
            );
        }
    };
    observer.stage(Stage::Read);
    let total_rows = chunks.total_rows();
    let file_bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let n = request.equations();
    let mut merged = Merged::default();
    let mut parts: Vec<Vec<LinearSystem>> = (0..n).map(|_| Vec::new()).collect();
    let read = Reading {
        request,
        name: &name,
        read_error: &read_error,
        chunk_rows,
        file_bytes,
        total_rows,
    };
    // The first chunk fixes the clock, the windows and the overlap; then each chunk's windows
    // are assembled while the next one is read and conditioned.
    let Some((first, mut stream)) = read.first(&mut chunks, &mut merged)? else {
        return Err(read_error(hb_record::input::InputError::Empty));
    };
    observer.progress(
        chunks.bytes_read() as usize,
        (file_bytes as usize).max(chunks.bytes_read() as usize),
    );
    let mut current = first;
    let mut first_data: Option<Data> = None;
    loop {
        let (assembled, next) = rayon::join(
            || stream.assemble(request, &current),
            || read.next(&mut chunks, &mut merged, &stream),
        );
        let (systems, count, setups) = assembled?;
        for (part, system) in parts.iter_mut().zip(systems) {
            part.push(system);
        }
        stream.segments += count;
        if stream.setups.is_none() {
            stream.setups = setups;
        }
        observer.progress(
            chunks.bytes_read() as usize,
            (file_bytes as usize).max(chunks.bytes_read() as usize),
        );
        let Some(chunk) = next? else {
            if first_data.is_none() {
                first_data = Some(current.data);
            }
            break;
        };
        // The first chunk's record is kept: its clock, kind of drive and states are the
        // record's (the others are let go as their windows are assembled).
        let done = std::mem::replace(&mut current, chunk);
        if first_data.is_none() {
            first_data = Some(done.data);
        }
    }
    let mut s = stream;
    let first = first_data.expect("the first chunk's record");
    merged.tell(observer);
    let Some(setups) = s.setups.take() else {
        return Err(OptionError::new(
            "window_periods",
            format!(
                "no window of {} samples fits the record's pieces: shorten the windows",
                s.window_len + 1
            ),
        )
        .into());
    };
    observer.stage(Stage::Assemble);
    let mut systems = Vec::with_capacity(n);
    for part in parts {
        let mut system = LinearSystem::joined(part).map_err(|e| s.identify_error(request, None, e))?;
        // More windows than the record's length promised (a text file's rows are estimated):
        // compressed again, so the blocks stay within their bound.
        let blocks = system.blocks().len();
        if blocks > MAX_BLOCKS {
            system = system
                .compressed(blocks.div_ceil(MAX_BLOCKS))
                .map_err(|e| s.identify_error(request, None, e))?;
        }
        systems.push(system);
    }
    let k = request.options().window_periods;
    let found = windows_found(&first, k, s.segments);
    let summary = RecordSummary::of(&Data {
        clock: first.clock,
        p: first.p,
        x: Vec::new(),
        pieces: merged.global_pieces.clone(),
        domain: first.domain,
        drive: first.drive.clone(),
        resampled_from: first.resampled_from,
        others: Vec::new(),
        drives: Vec::new(),
        velocities: Vec::new(),
        bridged: Vec::new(),
    });
    let coordinates = first.coordinates();
    finish(
        request,
        Assembled {
            setups,
            systems,
            found,
            segments: s.segments,
            delay: None,
            drift: None,
            record: summary,
            resampled: first.resampled_from.is_some(),
            states: Some(States {
                data: &first,
                coordinates,
                x: &first.x,
            }),
        },
        observer,
    )
}

/// A chunk's rows: each equation's compressed system, how many windows, and the setups (none
/// when no window starts in the chunk's stretch).
type ChunkRows = (Vec<LinearSystem>, usize, Option<Vec<Identifier>>);

/// What a chunk's conditioning found that its stretch decides: its spikes and rows written
/// twice, and its grid as fitted (time of sample 0, step, pieces) for its gaps.
struct Held {
    spikes: Vec<(Option<String>, Note)>,
    duplicates: Vec<Note>,
    raw: (f64, f64),
    raw_pieces: Vec<Range<usize>>,
}

/// A chunk read and conditioned, on the record's clock, with its stretch.
struct Prepared {
    data: Data,
    /// Its stretch, in raw stamps (`None`: the record's end).
    stretch: (Option<f64>, Option<f64>),
}

/// What reading a chunk needs of the run.
struct Reading<'a> {
    request: &'a IdentifyRequest,
    name: &'a str,
    read_error: &'a (dyn Fn(hb_record::input::InputError) -> RunError + Sync),
    chunk_rows: usize,
    file_bytes: u64,
    total_rows: Option<usize>,
}

impl Reading<'_> {
    /// Reads and conditions the first chunk, and finds the clock, the windows and the overlap
    /// from it.
    fn first(
        &self,
        chunks: &mut Chunks,
        merged: &mut Merged,
    ) -> Result<Option<(Prepared, Stream)>, RunError> {
        let Some(chunk) = chunks.next_chunk(self.chunk_rows, 0).map_err(self.read_error)? else {
            return Ok(None);
        };
        let t = chunk.record.t.clone();
        let rows_done = chunk.first_row + t.len();
        let last = chunk.last;
        let (grid, held) = self.condition(chunk.record, chunk.first_row, merged)?;
        let (data, period) = on_clock(grid, self.request.drive(), merged)?;
        let rows = self.total_rows.unwrap_or_else(|| {
            // A text's rows, estimated from the bytes of the first chunk's.
            let read = chunks.bytes_read().max(1) as f64;
            (self.file_bytes as f64 / read * rows_done as f64).ceil() as usize
        });
        let found_on_first = match self.request.drive() {
            DriveSpec::Auto(_) => Some(
                "the drive's period was estimated on the first {rows} rows, the record being read in chunks \
                 («stream»): its error grows into the drive's phase over the whole record and leaks into the \
                 drive terms' coefficients; give «drive_frequency», or estimate it on the record read whole \
                 («no_stream»)",
            ),
            DriveSpec::Free => Some(
                "the free oscillation's period, the windows' unit, was found on the first {rows} rows, the record \
                 being read in chunks («stream»): a decaying oscillation's period changes over the record; give \
                 the windows' length («window»), or read the record whole («no_stream»)",
            ),
            _ => None,
        };
        if let Some(text) = found_on_first
            && !last
        {
            merged.hold(&Notice::Warning(text.replace("{rows}", &rows_done.to_string())));
        }
        let stream = Stream::new(self.request, &data, period, held.raw, rows)?;
        let stretch = (None, stream.stretch_end(&t, rows_done, last));
        merged.add(held, &data, &stream, stretch);
        Ok(Some((Prepared { data, stretch }, stream)))
    }

    /// Reads and conditions the next chunk on the first one's clock; `None` after the last.
    fn next(
        &self,
        chunks: &mut Chunks,
        merged: &mut Merged,
        stream: &Stream,
    ) -> Result<Option<Prepared>, RunError> {
        let keep = stream.keep;
        let Some(chunk) = chunks
            .next_chunk(self.chunk_rows.max(4 * keep), keep)
            .map_err(self.read_error)?
        else {
            return Ok(None);
        };
        // The chunk's own stretch: from the middle of its overlap with the chunk before to the
        // middle of the next one's with it, in the time of the raw stamps.
        let t = &chunk.record.t;
        let from = (chunk.repeated > 0)
            .then(|| t.get(chunk.repeated - chunk.repeated / 2).copied())
            .flatten();
        let stretch = (from, stream.stretch_end(t, chunk.first_row + t.len(), chunk.last));
        let (grid, held) = self.condition(chunk.record, chunk.first_row, merged)?;
        let (mut data, _) = on_clock(grid, stream.later, &mut ())?;
        // On the first chunk's period, the first chunk's kind of drive (a free oscillation's
        // model has no drive terms, whatever period its windows are cut by).
        data.drive = stream.drive.clone();
        stream.check(&data)?;
        merged.add(held, &data, stream, stretch);
        Ok(Some(Prepared { data, stretch }))
    }

    /// A chunk's `record` (its first row `first_row` of the file) conditioned; its notes of
    /// spikes and of rows written twice held with its grid as fitted until its stretch is known,
    /// its other notices merged.
    fn condition(
        &self,
        record: hb_record::input::Record,
        first_row: usize,
        merged: &mut Merged,
    ) -> Result<(hb_record::prepare::GridData, Held), RunError> {
        let mut hears = Hears {
            merged,
            spikes: Vec::new(),
            duplicates: Vec::new(),
        };
        let grid = condition_read(
            record,
            &self.request.options().record,
            self.name.to_owned(),
            &mut hears,
            &|at| relocate(first_row, at),
        )?;
        let held = Held {
            spikes: hears.spikes,
            duplicates: hears.duplicates,
            raw: (grid.t0, grid.dt),
            raw_pieces: grid.pieces.clone(),
        };
        Ok((grid, held))
    }
}

/// A place a chunk's conditioning names, in the file: a sample by the file's row (a line of
/// text is the file's already).
fn relocate(first_row: usize, at: Location) -> Location {
    match at {
        Location::Sample(n) => Location::Sample(n + first_row),
        line => line,
    }
}

/// What the first chunk fixed for the rest.
struct Stream {
    /// The period's source for the later chunks: the first one's period as given.
    later: DriveSpec,
    /// What the first chunk found the period by (every chunk's record says it).
    drive: hb_record::prepare::DriveFound,
    /// The record's grid after resampling: the time of its sample 0 and its step.
    t0: f64,
    h: f64,
    /// Samples per period.
    p: usize,
    /// The windows: length (samples, the closing one not counted), step, periods.
    window_len: usize,
    window_step: usize,
    /// Rows each chunk repeats of the one before.
    keep: usize,
    /// Consecutive windows compressed together.
    group: usize,
    /// Windows taken so far.
    segments: usize,
    /// The first chunk's setups (their clock is the record's).
    setups: Option<Vec<Identifier>>,
    /// The raw grid's time of sample 0 and step (before resampling), for the spikes' indices.
    raw: (f64, f64),
}

impl Stream {
    fn new(
        request: &IdentifyRequest,
        data: &Data,
        period: PeriodSource,
        raw: (f64, f64),
        rows: usize,
    ) -> Result<Self, RunError> {
        let windows = request.windows().windows(&Record::from_data(data)?)?;
        let (h, p) = (data.clock.step(), data.p);
        let later = match period {
            PeriodSource::Windows(unit) => DriveSpec::Windows(unit),
            _ => DriveSpec::Period(data.clock.drive_period()),
        };
        // A window and the conditioning's room on each side, in rows of the file.
        let rows_per_sample = h / raw.1;
        let window_rows = ((windows.len() + 1) as f64 * rows_per_sample).ceil() as usize;
        let keep = 2 * (window_rows + 2 + CONDITIONING_MARGIN);
        // The group from the windows the whole record holds (`rows`: an .npy's are in its
        // header, a text's estimated from the first chunk's bytes per row).
        let expected = (rows as f64 / rows_per_sample / windows.step() as f64).ceil() as usize;
        Ok(Self {
            later,
            drive: data.drive.clone(),
            t0: data.clock.start_time(),
            h,
            p,
            window_len: windows.len(),
            window_step: windows.step(),
            keep,
            group: expected.div_ceil(MAX_BLOCKS).max(1),
            segments: 0,
            setups: None,
            raw,
        })
    }

    /// Where the stretch of a chunk whose raw stamps are `t` ends (`rows_done` rows of the file
    /// read with it): the next chunk repeats `r` rows and its stretch starts at its
    /// `r − r/2`-th, this one's `len − r/2`-th; `None` for the last chunk.
    fn stretch_end(&self, t: &[f64], rows_done: usize, last: bool) -> Option<f64> {
        let r = self.keep.min(rows_done);
        (!last)
            .then(|| {
                t.get(t.len().saturating_sub(r / 2).min(t.len().saturating_sub(1)))
                    .copied()
            })
            .flatten()
    }

    /// A chunk's windows assembled and compressed: each equation's system, how many windows,
    /// and the setups (none when no window starts in its stretch).
    fn assemble(&self, request: &IdentifyRequest, chunk: &Prepared) -> Result<ChunkRows, RunError> {
        let data = &chunk.data;
        let segments = self.windows(request, data, chunk.stretch)?;
        if segments.is_empty() {
            return Ok((Vec::new(), 0, None));
        }
        let n = request.equations();
        let coordinates = data.coordinates();
        let drives: Vec<&[f64]> = data.drives.iter().map(Vec::as_slice).collect();
        let setups = (0..n)
            .map(|i| {
                request
                    .equation_spec(data, request.options().method, i)?
                    .setup(&data.clock)
                    .map_err(RunError::from)
            })
            .collect::<Result<Vec<_>, RunError>>()?;
        let signals = (0..n)
            .map(|i| {
                Signals::system(coordinates.clone(), i)
                    .and_then(|sig| sig.with_drives(drives.clone()))
                    .map_err(|e| self.identify_error(request, Some(i), e))
            })
            .collect::<Result<Vec<_>, RunError>>()?;
        // A record of fewer windows than the regression's bound keeps its rows, as read whole.
        let systems = if self.group == 1 {
            Identifier::systems(&setups, &signals, &segments)
        } else {
            Identifier::systems_grouped(&setups, &signals, &segments, self.group)
        }
        .map_err(|e| self.identify_error(request, None, e))?;
        Ok((systems, segments.len(), Some(setups)))
    }

    /// That a later chunk is on the first one's clock.
    fn check(&self, data: &Data) -> Result<(), RunError> {
        if data.p != self.p || ((data.clock.step() - self.h) / self.h).abs() > 1e-6 {
            return Err(OptionError::new(
                "stream",
                format!(
                    "the record's sampling changes from one chunk to another ({} samples per period in steps of {} \
                     from t = {}, the first chunk's {} in steps of {}): read it whole («no_stream»)",
                    data.p,
                    data.clock.step(),
                    data.clock.start_time(),
                    self.p,
                    self.h
                ),
            )
            .into());
        }
        Ok(())
    }

    /// The windows of the record's lattice in `data` (a chunk's) that start in its stretch
    /// `(from, to)` (raw stamps; `None`: the record's end).
    fn windows(
        &self,
        request: &IdentifyRequest,
        data: &Data,
        (from, to): (Option<f64>, Option<f64>),
    ) -> Result<Vec<Segment>, RunError> {
        let base = ((data.clock.start_time() - self.t0) / self.h).round() as i64;
        let step = self.window_step as i64;
        let l = self.window_len;
        let periods = request.options().window_periods;
        let half = 0.5 * self.h;
        let mut out = Vec::new();
        for piece in &data.pieces {
            // The first start on the lattice in the piece.
            let offset = (base + piece.start as i64).rem_euclid(step);
            let mut j = piece.start + if offset == 0 { 0 } else { (step - offset) as usize };
            while j + l < piece.end {
                let t = data.clock.time(j);
                if from.is_none_or(|f| t >= f - half) && to.is_none_or(|e| t < e - half) {
                    let error = data.domain.distance(data.x[j + l], data.x[j]);
                    out.push(
                        Segment::new(j, periods, &data.clock, error, data.x.len())
                            .map_err(crate::pipeline::PipelineError::from)?,
                    );
                }
                j += self.window_step;
            }
        }
        Ok(out)
    }

    fn identify_error(
        &self,
        request: &IdentifyRequest,
        i: Option<usize>,
        source: hb_solve::SolveError,
    ) -> RunError {
        let found = format!("{} windows so far", self.segments);
        RunError::Identify {
            found: match i {
                Some(i) if request.equations() > 1 => {
                    format!("{found}, the equation of {}", request.names().coordinates()[i])
                }
                _ => found,
            },
            source,
        }
    }
}

/// The chunks' notices merged: each told once, the spikes and gaps of every chunk's own
/// stretch gathered into one note each.
#[derive(Default)]
struct Merged {
    /// Notices told, by their text.
    told: Vec<String>,
    /// Spikes per coordinate (the column's name for a system's), by the raw grid's index from
    /// the record's first sample, and whether repaired.
    spikes: Vec<(Option<String>, Note, Vec<Spike>)>,
    /// Notices held back to be told after the reading (the first chunk's, in order).
    later: Vec<Notice>,
    /// The record's pieces, grid indices from its first sample.
    global_pieces: Vec<Range<usize>>,
    /// The record's pieces on its grid as fitted (before any resampling), for its gaps.
    record_pieces: Vec<Range<usize>>,
    /// The rows written twice, merged.
    duplicated: Option<Note>,
}

impl Merged {
    /// Adds the pieces of `data` (a chunk's) within its stretch to the record's.
    fn pieces(&mut self, data: &Data, s: &Stream, stretch: (Option<f64>, Option<f64>)) {
        let base = ((data.clock.start_time() - s.t0) / s.h).round() as i64;
        add_pieces(
            &mut self.global_pieces,
            &data.pieces,
            |j| data.clock.time(j),
            s.h,
            base,
            stretch,
        );
    }

    /// Adds the pieces of a chunk's grid as fitted (`raw`: its time of sample 0 and step; before
    /// any resampling) within its stretch to the record's, for its gaps: counted in the samples
    /// of the record's grid, as a record read whole counts them.
    fn raw_pieces(
        &mut self,
        pieces: &[Range<usize>],
        raw: (f64, f64),
        s: &Stream,
        stretch: (Option<f64>, Option<f64>),
    ) {
        let base = ((raw.0 - s.raw.0) / s.raw.1).round() as i64;
        add_pieces(
            &mut self.record_pieces,
            pieces,
            |j| raw.0 + j as f64 * raw.1,
            raw.1,
            base,
            stretch,
        );
    }

    /// Adds a chunk's `held` findings and the pieces of its `data` within its `stretch`.
    fn add(&mut self, held: Held, data: &Data, s: &Stream, stretch: (Option<f64>, Option<f64>)) {
        self.spikes(held.spikes, held.raw, s.raw, stretch);
        self.duplicates(held.duplicates, stretch);
        self.pieces(data, s, stretch);
        self.raw_pieces(&held.raw_pieces, held.raw, s, stretch);
    }

    /// A notice told once, by its text; of the chunks' grid notes, whose numbers differ from
    /// chunk to chunk, one: the first chunk's, or a later one's that is a warning where the first
    /// is not (the first chunk decides what the record's stamps are printed with, as the whole
    /// record does: a later chunk's larger stamps print with fewer decimals).
    fn hold(&mut self, notice: &Notice) {
        if let Notice::Record(Note::Grid(new)) = notice
            && let Some(Notice::Record(Note::Grid(old))) = self
                .later
                .iter_mut()
                .find(|n| matches!(n, Notice::Record(Note::Grid(_))))
        {
            if new.is_warning() && !old.is_warning() {
                *old = new.clone();
            }
            return;
        }
        let text = format!("{notice:?}");
        if !self.told.contains(&text) {
            self.told.push(text);
            self.later.push(notice.clone());
        }
    }

    /// Adds a chunk's rows written twice, those whose stamps are in its stretch (`from`, `to`):
    /// each row counted once, from the first chunk's place of the first.
    fn duplicates(&mut self, notes: Vec<Note>, (from, to): (Option<f64>, Option<f64>)) {
        for note in notes {
            let Note::DuplicateRows { first, times, .. } = note else {
                continue;
            };
            let mine: Vec<f64> = times
                .into_iter()
                .filter(|&t| from.is_none_or(|f| t >= f) && to.is_none_or(|e| t < e))
                .collect();
            if mine.is_empty() {
                continue;
            }
            match &mut self.duplicated {
                Some(Note::DuplicateRows { count, times, .. }) => {
                    *count += mine.len();
                    times.extend(mine);
                }
                _ => {
                    self.duplicated = Some(Note::DuplicateRows {
                        first,
                        count: mine.len(),
                        times: mine,
                    })
                }
            }
        }
    }

    /// Adds a chunk's spikes notes: the spikes in its stretch (raw stamps), indexed in the raw
    /// grid from the record's first sample (`raw`, the chunk's raw grid; `record`, the first
    /// chunk's).
    fn spikes(
        &mut self,
        notes: Vec<(Option<String>, Note)>,
        raw: (f64, f64),
        record: (f64, f64),
        (from, to): (Option<f64>, Option<f64>),
    ) {
        let half = 0.5 * raw.1;
        for (column, note) in notes {
            let Note::Spikes {
                coordinate,
                found,
                repaired,
                ..
            } = &note
            else {
                continue;
            };
            let mine: Vec<Spike> = found
                .iter()
                .filter_map(|s| {
                    let t = raw.0 + s.index as f64 * raw.1;
                    let inside = from.is_none_or(|f| t >= f - half) && to.is_none_or(|e| t < e - half);
                    inside.then(|| Spike {
                        index: ((t - record.0) / record.1).round().max(0.0) as usize,
                        ..*s
                    })
                })
                .collect();
            if mine.is_empty() {
                continue;
            }
            let slot = self.spikes.iter_mut().find(|(c, n, _)| {
                *c == column
                    && matches!(n, Note::Spikes { coordinate: k, repaired: r, .. } if k == coordinate && r == repaired)
            });
            match slot {
                Some((_, _, all)) => all.extend(mine),
                None => {
                    // Indexed on the record's grid now: named by its times.
                    let mut note = note.clone();
                    if let Note::Spikes { grid, .. } = &mut note {
                        *grid = Some(record);
                    }
                    self.spikes.push((column, note, mine));
                }
            }
        }
    }

    /// Tells `observer` what was held back: the spikes of every chunk and the gaps.
    fn tell(&mut self, observer: &mut dyn Observer) {
        for (column, note, found) in std::mem::take(&mut self.spikes) {
            let Note::Spikes {
                coordinate,
                repaired,
                domain,
                policy,
                grid,
                ..
            } = note
            else {
                continue;
            };
            let note = Note::Spikes {
                coordinate,
                found,
                repaired,
                domain,
                policy,
                grid,
            };
            observer.notice(&match column {
                Some(column) => Notice::Column { column, note },
                None => Notice::Record(note),
            });
        }
        if let Some(note) = self.duplicated.take() {
            observer.notice(&Notice::Record(note));
        }
        let gaps = self.record_pieces.len().saturating_sub(1);
        if gaps > 0 {
            let missing = self.record_pieces.windows(2).map(|w| w[1].start - w[0].end).sum();
            observer.notice(&Notice::Record(Note::Gaps { gaps, missing }));
        }
        for notice in std::mem::take(&mut self.later) {
            observer.notice(&notice);
        }
    }
}

/// Appends `pieces` (a chunk's, on a grid of step `h` whose sample 0 is `base` steps after the
/// record's, `time` of each sample) within `(from, to)` (raw stamps) to `into` (the record's,
/// indices from its first sample), a piece that goes on from the chunk before joined to it (a
/// grid resampled on its own may be off the chunk before's by a fraction of a step, so the
/// chunk's first index by one; within a chunk its pieces are apart by the samples missing, one
/// at least).
fn add_pieces(
    into: &mut Vec<Range<usize>>,
    pieces: &[Range<usize>],
    time: impl Fn(usize) -> f64,
    h: f64,
    base: i64,
    (from, to): (Option<f64>, Option<f64>),
) {
    let half = 0.5 * h;
    let inside = |j: usize| {
        let t = time(j);
        from.is_none_or(|f| t >= f - half) && to.is_none_or(|e| t < e - half)
    };
    let mut first = true;
    for piece in pieces {
        let (mut a, mut b) = (piece.start, piece.end);
        while a < b && !inside(a) {
            a += 1;
        }
        while b > a && !inside(b - 1) {
            b -= 1;
        }
        if a == b {
            continue;
        }
        let (ga, gb) = (
            (base + a as i64).max(0) as usize,
            (base + b as i64).max(0) as usize,
        );
        let slack = usize::from(first);
        first = false;
        match into.last_mut() {
            Some(last) if last.end + slack >= ga => last.end = last.end.max(gb),
            _ => into.push(ga..gb),
        }
    }
}

/// The notices of the first chunk's clock (the drive estimated, the period found, the
/// resampling), held as any other.
impl Observer for Merged {
    fn notice(&mut self, notice: &Notice) {
        self.hold(notice);
    }
}

/// A chunk's observer: its notices merged into [`Merged`], its spikes held until its grid is
/// known.
struct Hears<'a> {
    merged: &'a mut Merged,
    /// The chunk's spikes notes, with the column's name for a system's.
    spikes: Vec<(Option<String>, Note)>,
    /// Its notes of rows written twice.
    duplicates: Vec<Note>,
}

impl Observer for Hears<'_> {
    fn notice(&mut self, notice: &Notice) {
        let (column, note) = match notice {
            Notice::Record(note) => (None, note),
            Notice::Column { column, note } => (Some(column.clone()), note),
            other => {
                self.merged.hold(other);
                return;
            }
        };
        match note {
            // Counted from the record's pieces after the reading.
            Note::Gaps { .. } => {}
            Note::Spikes { .. } => self.spikes.push((column, note.clone())),
            Note::DuplicateRows { .. } => self.duplicates.push(note.clone()),
            _ => self.merged.hold(notice),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::IdentifyOptions;
    use crate::observe::Notices;
    use crate::record::Source;
    use crate::simulate::{Rig, simulate_to};
    use std::path::PathBuf;

    fn record(name: &str, rig: serde_json::Value) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("hb-pipeline-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        simulate_to(&Rig::from_json(rig).unwrap(), &path, &mut ()).unwrap();
        path
    }

    fn request(options: serde_json::Value) -> IdentifyRequest {
        let mut o: IdentifyOptions = crate::options::from_object(options).unwrap();
        o.bootstrap = 50;
        IdentifyRequest::new(o).unwrap()
    }

    /// In memory, and in chunks of `rows`: the two reports and the streamed run's notices.
    fn both(
        path: &Path,
        request: &IdentifyRequest,
        rows: usize,
    ) -> (IdentifyReport, IdentifyReport, Notices) {
        let whole = crate::identify::identify(Source::Path(path), request, &mut ()).unwrap();
        let mut notices = Notices::default();
        let streamed = streamed_in(path, request, &mut notices, rows).unwrap();
        (whole, streamed, notices)
    }

    fn values(r: &IdentifyReport) -> Vec<f64> {
        r.equations[0]
            .identification
            .model
            .coefficients()
            .iter()
            .map(|c| c.value)
            .collect()
    }

    /// Coefficients equal to `rel` of the largest (a coefficient whose truth is 0 comes out at
    /// rounding's size).
    fn same(a: &IdentifyReport, b: &IdentifyReport, rel: f64) -> bool {
        let (a, b) = (values(a), values(b));
        let scale = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        a.iter().zip(&b).all(|(u, v)| (u - v).abs() <= rel * scale)
    }

    #[test]
    fn a_record_in_chunks_is_the_record_in_memory() {
        for name in ["paper.npy", "paper.csv"] {
            // Chunks of at least four overlaps (8 348 rows): four of them.
            let path = record(name, serde_json::json!({"samples": 120_000}));
            let (whole, streamed, _) = both(&path, &request(serde_json::json!({})), 30_000);
            assert_eq!(whole.segments, streamed.segments, "{name}");
            // The first chunk's grid fitted to its own stamps: the record's origin to rounding.
            let (a, b) = (&whole.record, &streamed.record);
            assert!(
                (a.start - b.start).abs() <= 1e-14 * a.start.abs(),
                "{name}: {} vs {}",
                a.start,
                b.start
            );
            assert_eq!(
                (a.samples, a.step, a.samples_per_period, &a.pieces),
                (b.samples, b.step, b.samples_per_period, &b.pieces)
            );
            assert!(
                same(&whole, &streamed, 1e-10),
                "{name}: {:?} vs {:?}",
                values(&whole),
                values(&streamed)
            );
            let e = &streamed.equations[0].identification;
            assert_eq!(e.model.summary().unwrap().segments, whole.segments);
            assert!(e.intervals.is_some() && e.quality.held_out.is_some());
        }
    }

    /// Gaps of one sample are gaps in chunks too: the pieces and the samples are the record's
    /// read whole (a chunk's pieces one sample apart were joined as if they went on).
    #[test]
    fn gaps_of_one_sample_in_chunks_are_the_records() {
        let path = record(
            "one-sample-gaps.npy",
            serde_json::json!({"samples": 120_000, "gaps": "6:1", "seed": 5}),
        );
        let (whole, streamed, notices) = both(&path, &request(serde_json::json!({})), 30_000);
        assert_eq!(whole.record.pieces.len(), 7);
        assert_eq!(
            (whole.record.samples, &whole.record.pieces),
            (streamed.record.samples, &streamed.record.pieces)
        );
        assert!(
            notices
                .0
                .iter()
                .any(|n| matches!(n, Notice::Record(Note::Gaps { gaps: 6, missing: 6 }))),
            "{notices:?}"
        );
    }

    #[test]
    fn a_rig_s_record_in_chunks_has_its_gaps_spikes_and_resampling() {
        // Seconds, 500 Hz under a 1.3 Hz drive (resampled), a 4096-count encoder with bit
        // errors, gaps: each chunk resampled on its own grid.
        let path = record(
            "rig.csv",
            serde_json::json!({"samples": 120_000, "sample_rate": 500.0, "drive_frequency": 1.3,
                "counts": 4096, "bit_errors": 2e-4, "gaps": "3:40", "seed": 3}),
        );
        let request = request(serde_json::json!({"drive_frequency": "1.3"}));
        let (whole, streamed, notices) = both(&path, &request, 30_000);
        assert_eq!(whole.record.pieces.len(), streamed.record.pieces.len());
        // Each chunk resampled on its own grid: a sample more or less where two meet.
        assert!(whole.record.samples.abs_diff(streamed.record.samples) <= 4);
        assert!(whole.record.resampled_from.is_some());
        let (a, b) = (
            &whole.equations[0].identification.model,
            &streamed.equations[0].identification.model,
        );
        for (x, y) in a.coefficients().iter().zip(b.coefficients()) {
            assert!(
                (x.value - y.value).abs() <= x.std_error.max(y.std_error),
                "{}: {} ± {} vs {} ± {}",
                x.name,
                x.value,
                x.std_error,
                y.value,
                y.std_error
            );
        }
        // One note of the gaps and one of the spikes, their samples the file's.
        let gaps: Vec<&Notice> = notices
            .0
            .iter()
            .filter(|n| matches!(n, Notice::Record(Note::Gaps { .. })))
            .collect();
        assert_eq!(gaps.len(), 1);
        assert!(
            matches!(gaps[0], Notice::Record(Note::Gaps { gaps: 3, .. })),
            "{gaps:?}"
        );
        let mut memory = Notices::default();
        crate::identify::identify(Source::Path(&path), &request, &mut memory).unwrap();
        let spikes = |n: &Notices| -> Vec<usize> {
            n.0.iter()
                .filter_map(|n| match n {
                    Notice::Record(Note::Spikes { found, .. }) => Some(found.iter().map(|s| s.index)),
                    _ => None,
                })
                .flatten()
                .collect()
        };
        let (m, s) = (spikes(&memory), spikes(&notices));
        assert!(!m.is_empty());
        assert_eq!(m, s);
        // A drive estimated on the first chunk only is warned of.
        let auto = super::tests::request(serde_json::json!({"drive_frequency": "auto"}));
        let mut told = Notices::default();
        streamed_in(&path, &auto, &mut told, 30_000).unwrap();
        assert!(
            told.0
                .iter()
                .any(|n| matches!(n, Notice::Warning(w) if w.contains("first") && w.contains("stream"))),
            "{told:?}"
        );
    }

    #[test]
    fn a_system_in_chunks_is_the_system_in_memory() {
        // The whirling double pendulum, its physical library: both equations from chunks.
        let rig = serde_json::json!({"system": "double-pendulum", "samples": 150_000});
        let truth = crate::simulate::simulate(&Rig::from_json(rig.clone()).unwrap(), &mut ())
            .unwrap()
            .truth()
            .unwrap();
        let hint = serde_json::to_value(&truth).unwrap()["identify"].clone();
        let path = record("dp.npy", rig);
        let request = request(serde_json::json!({
            "coords": hint["coords"], "signal": hint["signal"], "terms": hint["terms"]
        }));
        let (whole, streamed, _) = both(&path, &request, 40_000);
        assert_eq!(whole.segments, streamed.segments);
        assert_eq!(streamed.equations.len(), 2);
        for (a, b) in whole.equations.iter().zip(&streamed.equations) {
            let (a, b) = (
                a.identification.model.coefficients(),
                b.identification.model.coefficients(),
            );
            let scale = a.iter().fold(0.0_f64, |m, c| m.max(c.value.abs()));
            for (x, y) in a.iter().zip(b) {
                assert!(
                    (x.value - y.value).abs() <= 1e-10 * scale,
                    "{}: {} vs {}",
                    x.name,
                    x.value,
                    y.value
                );
            }
        }
    }

    #[test]
    fn a_free_decay_in_chunks_is_the_free_decay_in_memory() {
        // No drive: the windows' unit is the free oscillation's period, found on the first
        // chunk (and warned of); every chunk's model is the free model's.
        let path = record(
            "free.npy",
            serde_json::json!({"drive": "none", "x0": 2.5, "c": 2e-6, "drive_frequency": 2.0,
                "sample_rate": 100.0, "samples": 120_000}),
        );
        let request = request(serde_json::json!({"forcing": "none"}));
        let (whole, streamed, notices) = both(&path, &request, 30_000);
        assert_eq!(values(&whole).len(), values(&streamed).len());
        // The first chunk's period (the record read whole finds it on the longest piece).
        assert!(
            same(&whole, &streamed, 1e-3),
            "{:?} vs {:?}",
            values(&whole),
            values(&streamed)
        );
        assert!(
            notices
                .0
                .iter()
                .any(|n| matches!(n, Notice::Warning(w) if w.contains("free oscillation"))),
            "{notices:?}"
        );
    }

    #[test]
    fn rows_written_twice_are_counted_once() {
        // Rows written twice, some in the overlaps of chunks of 30 000 new rows (the first
        // chunk's rows 0..30 000, the next ones repeating 8 348): one note, as read whole.
        let text = std::fs::read_to_string(record("twice-src.csv", serde_json::json!({"samples": 120_000})))
            .unwrap();
        let mut lines: Vec<&str> = text.lines().collect();
        for row in [29_000, 27_000, 12_000, 60_500, 90_000] {
            let line = lines[row + 1];
            lines.insert(row + 1, line);
        }
        let path = std::env::temp_dir()
            .join(format!("hb-pipeline-stream-{}", std::process::id()))
            .join("twice.csv");
        std::fs::write(&path, lines.join("\n")).unwrap();
        let request = request(serde_json::json!({}));
        let (whole, streamed, notices) = both(&path, &request, 30_000);
        let mut memory = Notices::default();
        crate::identify::identify(Source::Path(&path), &request, &mut memory).unwrap();
        let twice = |n: &Notices| -> Vec<(String, usize)> {
            n.0.iter()
                .filter_map(|n| match n {
                    Notice::Record(Note::DuplicateRows { first, count, .. }) => {
                        Some((first.to_string(), *count))
                    }
                    _ => None,
                })
                .collect()
        };
        assert_eq!(twice(&memory), vec![("line 12003".to_owned(), 5)]);
        assert_eq!(twice(&notices), twice(&memory));
        assert!(same(&whole, &streamed, 1e-10));
    }

    #[test]
    fn what_cannot_be_streamed_is_named() {
        let path = record("short.npy", serde_json::json!({"samples": 3_000}));
        for (options, word) in [
            (serde_json::json!({"stream": true, "method": "upo"}), "upo"),
            (serde_json::json!({"stream": true, "refine": true}), "refine"),
        ] {
            let e = crate::identify::identify(Source::Path(&path), &request(options), &mut ()).unwrap_err();
            assert!(
                e.to_string().contains("stream") && e.to_string().contains(word),
                "{e}"
            );
        }
        // A bad cell in a later chunk: the file's line.
        let text = std::fs::read_to_string(record("bad.csv", serde_json::json!({"samples": 3_000}))).unwrap();
        let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
        lines[2500] = lines[2500].replacen(',', ",x", 1);
        let bad = std::env::temp_dir()
            .join(format!("hb-pipeline-stream-{}", std::process::id()))
            .join("bad2.csv");
        std::fs::write(&bad, lines.join("\n")).unwrap();
        let e = streamed_in(&bad, &request(serde_json::json!({})), &mut (), 1_000).unwrap_err();
        assert!(e.to_string().contains("line 2501"), "{e}");
    }
}

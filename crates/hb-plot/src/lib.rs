//! The figures of the reports (`hbid report`, `cargo xtask reproduce`, `cargo xtask benchmarks`):
//! every one is a scatter or a set of lines, drawn by plotters into a PNG (or SVG) file.
//!
//! A figure is a plain value ([`Figure`] of [`Series`]); [`Figure::save`] draws it. A wrapped angle
//! is never joined across ±π: a line breaks where it jumps by more than its
//! [`Style::Line::break_above`].
//!
//! # Example
//!
//! ```
//! use hb_plot::{BLUE, Figure, Series, Style};
//!
//! let dir = std::env::temp_dir().join("hb-plot-doc");
//! std::fs::create_dir_all(&dir)?;
//! let figure = Figure {
//!     title: "a sine",
//!     x_label: "t",
//!     y_label: "x",
//!     series: vec![Series {
//!         label: "sin t",
//!         points: (0..100).map(|n| (n as f64 * 0.1, (n as f64 * 0.1).sin())).collect(),
//!         style: Style::Line { break_above: 3.0 },
//!         color: BLUE,
//!     }],
//!     x_range: None,
//!     y_range: None,
//! };
//! figure.save(&dir.join("sine.svg"))?;
//! assert!(std::fs::metadata(dir.join("sine.svg"))?.len() > 0);
//!
//! // A file that cannot be written is an error that names it.
//! let nowhere = dir.join("no/such/folder/sine.svg");
//! match figure.save(&nowhere) {
//!     Err(hb_plot::PlotError::Draw { path, .. }) => assert_eq!(path, nowhere),
//!     other => panic!("{other:?}"),
//! }
//!
//! // Two panels side by side on common axes: the sine beside its double.
//! let double = Figure {
//!     title: "twice",
//!     series: vec![Series {
//!         label: "",
//!         points: (0..100).map(|n| (n as f64 * 0.1, 2.0 * (n as f64 * 0.1).sin())).collect(),
//!         style: Style::Dots(1),
//!         color: BLUE,
//!     }],
//!     ..figure
//! };
//! let sine = Figure {
//!     series: vec![Series {
//!         label: "",
//!         points: (0..100).map(|n| (n as f64 * 0.1, (n as f64 * 0.1).sin())).collect(),
//!         style: Style::Dots(1),
//!         color: BLUE,
//!     }],
//!     ..double
//! };
//! hb_plot::save_row(&[sine, double], &dir.join("row.svg"))?;
//! assert!(std::fs::metadata(dir.join("row.svg"))?.len() > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

use std::path::{Path, PathBuf};

use plotters::prelude::*;
/// Colours of series, re-exported so that users of these helpers need no plotters of their own.
pub use plotters::style::RGBColor;

/// Errors of drawing a figure.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// The plotting backend failed to draw the figure or to write its file.
    #[error("drawing {}", path.display())]
    Draw {
        /// The figure's file.
        path: PathBuf,
        /// The backend's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

/// A backend's error, boxed.
type BackendError = Box<dyn std::error::Error + Send + Sync>;

/// A figure's file format, by the extension of its name (in any case).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// `.png`.
    Png,
    /// `.svg`.
    Svg,
}

impl Format {
    /// The format of a figure written to `path`; `None` for a name that is neither `.png` nor
    /// `.svg` (in any case), which no figure is written to.
    ///
    /// ```
    /// use hb_plot::Format;
    /// use std::path::Path;
    ///
    /// assert_eq!(Format::of(Path::new("a.SVG")), Some(Format::Svg));
    /// assert_eq!(Format::of(Path::new("a.png")), Some(Format::Png));
    /// assert_eq!(Format::of(Path::new("a.jpg")), None);
    /// ```
    pub fn of(path: &Path) -> Option<Self> {
        let e = path.extension()?.to_str()?;
        if e.eq_ignore_ascii_case("svg") {
            Some(Self::Svg)
        } else if e.eq_ignore_ascii_case("png") {
            Some(Self::Png)
        } else {
            None
        }
    }
}

/// One series of a figure.
#[derive(Debug)]
pub struct Series<'a> {
    /// Legend text (empty: no legend entry).
    pub label: &'a str,
    /// The points.
    pub points: Vec<(f64, f64)>,
    /// How they are drawn.
    pub style: Style,
    /// Their colour.
    pub color: RGBColor,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy)]
pub enum Style {
    /// Dots of this radius (pixels).
    Dots(u32),
    /// A polyline; a jump in x or y larger than the break threshold starts a new piece (so a
    /// wrapped angle is not joined across ±π).
    Line {
        /// The jump that breaks the line.
        break_above: f64,
    },
}

/// A 2-D figure.
#[derive(Debug)]
pub struct Figure<'a> {
    /// Title.
    pub title: &'a str,
    /// Label of the x axis.
    pub x_label: &'a str,
    /// Label of the y axis.
    pub y_label: &'a str,
    /// What is drawn.
    pub series: Vec<Series<'a>>,
    /// Range of x (default: the data's, padded by 5 %).
    pub x_range: Option<(f64, f64)>,
    /// Range of y (default: the data's, padded by 5 %).
    pub y_range: Option<(f64, f64)>,
}

fn extent<'a, S: std::borrow::Borrow<Series<'a>>>(
    series: &[S],
    pick: impl Fn(&(f64, f64)) -> f64,
) -> (f64, f64) {
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.borrow().points.iter().map(&pick))
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-9);
    (lo - pad, hi + pad)
}

fn split_line(points: &[(f64, f64)], threshold: f64) -> Vec<Vec<(f64, f64)>> {
    let mut pieces = vec![Vec::new()];
    for w in points.windows(2) {
        pieces.last_mut().expect("one piece").push(w[0]);
        if (w[1].0 - w[0].0).abs() > threshold || (w[1].1 - w[0].1).abs() > threshold {
            pieces.push(Vec::new());
        }
    }
    if let Some(&p) = points.last() {
        pieces.last_mut().expect("one piece").push(p);
    }
    pieces
}

/// The size of one figure (one panel) in pixels.
const PANEL: (u32, u32) = (900, 650);
/// The size of each panel of a row ([`save_row`]).
const ROW_PANEL: (u32, u32) = (640, 600);

/// The ranges of a chart's axes: `(x0, x1)` and `(y0, y1)`.
type Ranges = ((f64, f64), (f64, f64));

/// Draws `panels` side by side, each in its own chart, into `path` (`.png` or `.svg`, by
/// extension), each panel 640×600 pixels. The panels share their axes: a range a panel does not
/// give is the extent of every panel's data, so that the panels can be read against each other.
pub fn save_row(panels: &[Figure<'_>], path: &Path) -> Result<(), PlotError> {
    let all: Vec<&Series<'_>> = panels.iter().flat_map(|f| &f.series).collect();
    let x = extent(&all, |p| p.0);
    let y = extent(&all, |p| p.1);
    let ranges: Vec<Ranges> = panels
        .iter()
        .map(|f| (f.x_range.unwrap_or(x), f.y_range.unwrap_or(y)))
        .collect();
    let size = (ROW_PANEL.0 * panels.len().max(1) as u32, ROW_PANEL.1);
    fn draw<DB: DrawingBackend>(
        root: DrawingArea<DB, plotters::coord::Shift>,
        panels: &[Figure<'_>],
        ranges: &[Ranges],
    ) -> Result<(), BackendError>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(area_error::<DB>)?;
        let areas = root.split_evenly((1, panels.len().max(1)));
        for ((panel, area), &(x, y)) in panels.iter().zip(&areas).zip(ranges) {
            panel.draw_in(area, x, y)?;
        }
        root.present().map_err(area_error::<DB>)?;
        Ok(())
    }
    let svg = Format::of(path) == Some(Format::Svg);
    let drawn = if svg {
        draw(SVGBackend::new(path, size).into_drawing_area(), panels, &ranges)
    } else {
        draw(
            BitMapBackend::new(path, size).into_drawing_area(),
            panels,
            &ranges,
        )
    };
    drawn.map_err(|source| PlotError::Draw {
        path: path.to_owned(),
        source,
    })
}

/// A drawing area's error, boxed.
fn area_error<DB: DrawingBackend>(e: DrawingAreaErrorKind<DB::ErrorType>) -> BackendError
where
    DB::ErrorType: 'static,
{
    Box::new(e)
}

impl Figure<'_> {
    /// Draws the figure into `path` (`.png` or `.svg`, by extension), 900×650 pixels.
    pub fn save(&self, path: &Path) -> Result<(), PlotError> {
        let svg = Format::of(path) == Some(Format::Svg);
        let drawn = if svg {
            self.draw(SVGBackend::new(path, PANEL).into_drawing_area())
        } else {
            self.draw(BitMapBackend::new(path, PANEL).into_drawing_area())
        };
        drawn.map_err(|source| PlotError::Draw {
            path: path.to_owned(),
            source,
        })
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<(), BackendError>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(area_error::<DB>)?;
        let x = self.x_range.unwrap_or_else(|| extent(&self.series, |p| p.0));
        let y = self.y_range.unwrap_or_else(|| extent(&self.series, |p| p.1));
        self.draw_in(&root, x, y)?;
        root.present().map_err(area_error::<DB>)?;
        Ok(())
    }

    /// Draws the chart into `root` (already filled) on the ranges `x` and `y`.
    fn draw_in<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
    ) -> Result<(), BackendError>
    where
        DB::ErrorType: 'static,
    {
        let err = area_error::<DB>;
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, ("sans-serif", 24))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        for s in &self.series {
            let color = s.color;
            let anno = match s.style {
                Style::Dots(r) => chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, r, color.filled())))
                    .map_err(err)?,
                Style::Line { break_above } => {
                    let pieces = split_line(&s.points, break_above);
                    chart
                        .draw_series(
                            pieces
                                .into_iter()
                                .map(|piece| PathElement::new(piece, color.stroke_width(2))),
                        )
                        .map_err(err)?
                }
            };
            if !s.label.is_empty() {
                anno.label(s.label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3)));
            }
        }
        if self.series.iter().any(|s| !s.label.is_empty()) {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(err)?;
        }
        Ok(())
    }
}

/// The palette of the reports: blue.
pub const BLUE: RGBColor = RGBColor(31, 119, 180);
/// Orange.
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
/// Red.
pub const RED: RGBColor = RGBColor(214, 39, 40);
/// Grey.
pub const GREY: RGBColor = RGBColor(120, 120, 120);
/// Green.
pub const GREEN: RGBColor = RGBColor(44, 160, 44);
/// Purple.
pub const PURPLE: RGBColor = RGBColor(148, 103, 189);
/// Black.
pub const INK: RGBColor = RGBColor(0, 0, 0);

/// Adds a figure (file name, caption) to a report's list.
pub fn add_figure(figures: &mut Vec<(String, String)>, name: impl Into<String>, caption: impl Into<String>) {
    figures.push((name.into(), caption.into()));
}

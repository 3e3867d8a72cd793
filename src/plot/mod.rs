//! Figures drawn from what a run recorded, as PNG or SVG (chosen by the
//! output file's extension), with one look for all of them: the font, the
//! colours each source of data keeps from figure to figure, the sizes, the
//! chart with its axes and the legend column. `tactile` is the paper's
//! Fig. 7 (and Fig. 9 on a simulated cell), `regrasp` its Fig. 11,
//! `campaign` its Section IV-A experiment as distributions, `fusion` its
//! Fig. 12.
//!
//! The text is drawn with a TrueType font read at run time (DejaVu Sans,
//! Debian's `fonts-dejavu-core`, which `scripts/setup` installs), so that
//! neither fontconfig nor a system font service is needed.

pub mod bench;
pub mod campaign;
pub mod fusion;
pub mod regrasp;
pub mod tactile;

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::{
    BitMapBackend, Cartesian2d, ChartBuilder, ChartContext, Circle, DrawingArea,
    DrawingAreaErrorKind, DrawingBackend, IntoDrawingArea, IntoFont, PathElement, RGBColor,
    Rectangle, SVGBackend, Text,
};
use plotters::style::{Color, FontStyle, register_font};

use crate::geometry::LineInSensor;

/// Where the font is looked for, in order: `CABLECELL_FONT` if set, then
/// where Debian's `fonts-dejavu-core` puts DejaVu Sans (and where some
/// other distributions do).
const FONT_PATHS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// The environment variable naming another TrueType font to use.
pub const FONT_VARIABLE: &str = "CABLECELL_FONT";

/// The font family every figure's text uses (plotters' default family,
/// so axis labels need not name it).
pub const FONT: &str = "sans-serif";

/// A figure's size, pixels (PNG) or points (SVG).
pub const SIZE: (u32, u32) = (1000, 620);

/// Text sizes: the title, axis descriptions and the legend, tick labels.
pub const TITLE_SIZE: u32 = 24;
pub const LABEL_SIZE: u32 = 18;
pub const TICK_SIZE: u32 = 15;

/// Each source of data keeps its colour in every figure.
pub mod colour {
    use plotters::prelude::RGBColor;

    pub const VISION: RGBColor = RGBColor(31, 119, 180);
    pub const TACTILE_LINEAR: RGBColor = RGBColor(255, 127, 14);
    pub const TACTILE_QUADRATIC: RGBColor = RGBColor(44, 160, 44);
    pub const TACTILE_RIDGE: RGBColor = RGBColor(148, 103, 189);
    pub const FUSED: RGBColor = RGBColor(214, 39, 40);
    pub const TRUTH: RGBColor = RGBColor(90, 90, 90);
    /// Regions drawn behind the data (the pad's extent).
    pub const REGION: RGBColor = RGBColor(235, 235, 235);
    /// The taxels of a tactile map (the paper's blue circles); no other
    /// filled circle has this colour, so a figure's taxels can be counted.
    pub const TAXEL: RGBColor = RGBColor(65, 105, 225);
    /// The paper's centroids (eq. 5 / 6).
    pub const CENTROID: RGBColor = RGBColor(20, 20, 20);
    /// The pose a grasp aims at, and the paper's reference values.
    pub const TARGET: RGBColor = RGBColor(0, 0, 0);
    /// One colour per grasp, the trial grasp first (ColorBrewer's Set1);
    /// cycled past the sixth.
    pub const GRASPS: [RGBColor; 6] = [
        RGBColor(228, 26, 28),
        RGBColor(55, 126, 184),
        RGBColor(77, 175, 74),
        RGBColor(152, 78, 163),
        RGBColor(255, 127, 0),
        RGBColor(166, 86, 40),
    ];
    /// One colour per campaign policy (ColorBrewer's Dark2); cycled.
    pub const POLICIES: [RGBColor; 6] = [
        RGBColor(27, 158, 119),
        RGBColor(217, 95, 2),
        RGBColor(117, 112, 179),
        RGBColor(231, 41, 138),
        RGBColor(102, 166, 30),
        RGBColor(230, 171, 2),
    ];

    /// The `i`-th colour of `palette`, cycled.
    pub fn nth(palette: &[RGBColor], i: usize) -> RGBColor {
        palette[i % palette.len()]
    }
}

/// The background every figure is drawn on.
pub const BACKGROUND: RGBColor = RGBColor(255, 255, 255);

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// No TrueType font was found to write the figure's text with:
    /// install `fonts-dejavu-core` (`scripts/setup` does), or name a font
    /// file in `CABLECELL_FONT`.
    #[error(
        "no font to draw text with: install fonts-dejavu-core or set {FONT_VARIABLE} to a .ttf file ({reason})"
    )]
    NoFont { reason: String },
    /// The output's extension says neither PNG nor SVG.
    #[error("{}: a figure is written as .png or .svg", path.display())]
    Format { path: PathBuf },
    /// The figure could not be drawn or written (the folder missing or
    /// not writable, say).
    #[error("{}: cannot draw the figure: {message}", path.display())]
    Draw { path: PathBuf, message: String },
    /// There is nothing to draw.
    #[error("nothing to draw: {0}")]
    Empty(String),
    /// The pad's geometry the figure is drawn with is not physical (a
    /// recording's pitch or threshold out of range).
    #[error("cannot place the taxels: {source}")]
    Config {
        #[source]
        source: crate::perception::tactile::FitError,
    },
}

/// The output formats, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
}

impl Format {
    /// The format `path`'s extension names.
    pub fn of(path: &Path) -> Result<Self, PlotError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("svg") => Ok(Format::Svg),
            _ => Err(PlotError::Format {
                path: path.to_owned(),
            }),
        }
    }
}

/// A figure: whatever draws itself on any plotters backend.
pub trait Figure {
    /// Draws on `area`; drawing errors come back as their text.
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>;

    /// Width and height, pixels: [`SIZE`] unless the figure needs more.
    fn size(&self) -> (u32, u32) {
        SIZE
    }
}

/// A drawing error as text, whatever the backend.
pub fn drawing_error<E: std::error::Error + Send + Sync>(error: DrawingAreaErrorKind<E>) -> String {
    error.to_string()
}

/// Draws `figure` into `path`, PNG or SVG by its extension, at its size.
pub fn save(figure: &impl Figure, path: &Path) -> Result<(), PlotError> {
    let format = Format::of(path)?;
    register_the_font()?;
    let failed = |message: String| PlotError::Draw {
        path: path.to_owned(),
        message,
    };
    match format {
        Format::Png => {
            let area = BitMapBackend::new(path, figure.size()).into_drawing_area();
            area.fill(&BACKGROUND)
                .map_err(drawing_error)
                .map_err(failed)?;
            figure.draw(&area).map_err(failed)?;
            area.present().map_err(drawing_error).map_err(failed)
        }
        Format::Svg => {
            let area = SVGBackend::new(path, figure.size()).into_drawing_area();
            area.fill(&BACKGROUND)
                .map_err(drawing_error)
                .map_err(failed)?;
            figure.draw(&area).map_err(failed)?;
            area.present().map_err(drawing_error).map_err(failed)
        }
    }
}

/// Around every chart, and the room for its tick labels and axis
/// descriptions below and left of it, pixels.
const CHART_MARGIN: u32 = 16;
const X_LABEL_AREA: u32 = 48;
const Y_LABEL_AREA: u32 = 64;

/// A chart with f64 axes, as every figure draws.
pub type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A chart's ranges, axis descriptions and tick labels.
pub struct Axes<'f> {
    pub x: Range<f64>,
    pub y: Range<f64>,
    pub x_desc: &'f str,
    pub y_desc: &'f str,
    pub x_label: &'f dyn Fn(&f64) -> String,
    pub y_label: &'f dyn Fn(&f64) -> String,
    /// At most this many ticks along x.
    pub x_ticks: usize,
}

/// The pad's plane in the paper's sensor frame (Figs. 7, 9, 11): half a
/// pitch beyond the pad on every side, the pad shaded; with the pad's and
/// the view's half sides, mm, that lines are clipped to.
pub struct PadChart<'a, DB: DrawingBackend> {
    pub chart: Chart<'a, DB>,
    pub pad_mm: f64,
    pub view_mm: f64,
}

impl<'a, DB: DrawingBackend> PadChart<'a, DB> {
    pub fn on(
        area: &'a DrawingArea<DB, Shift>,
        pitch_mm: f64,
        label: &dyn Fn(&f64) -> String,
    ) -> Result<Self, String> {
        let pad_mm = crate::perception::tactile::PAD_HALF_SIDE_PITCH * pitch_mm;
        let view_mm = pad_mm + 0.5 * pitch_mm;
        let mut chart = chart(
            area,
            &Axes {
                x: -view_mm..view_mm,
                y: -view_mm..view_mm,
                x_desc: "x in the sensor frame, towards c35 (mm)",
                y_desc: "y, towards c13 (mm)",
                x_label: label,
                y_label: label,
                x_ticks: 10,
            },
        )?;
        chart
            .draw_series([Rectangle::new(
                [(-pad_mm, -pad_mm), (pad_mm, pad_mm)],
                colour::REGION.filled(),
            )])
            .map_err(drawing_error)?;
        Ok(Self {
            chart,
            pad_mm,
            view_mm,
        })
    }
}

/// A tick label in whole millimetres (or any whole unit).
pub fn whole(value: &f64) -> String {
    format!("{value:.0}")
}

/// The chart of `axes` on `area`, its mesh drawn in the common style.
pub fn chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    axes: &Axes<'_>,
) -> Result<Chart<'a, DB>, String> {
    let mut chart = ChartBuilder::on(area)
        .margin(CHART_MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(axes.x.clone(), axes.y.clone())
        .map_err(drawing_error)?;
    chart
        .configure_mesh()
        .x_desc(axes.x_desc)
        .y_desc(axes.y_desc)
        .x_labels(axes.x_ticks)
        .x_label_formatter(axes.x_label)
        .y_label_formatter(axes.y_label)
        .axis_desc_style((FONT, LABEL_SIZE))
        .label_style((FONT, TICK_SIZE))
        .light_line_style(colour::REGION.mix(0.6))
        .draw()
        .map_err(drawing_error)?;
    Ok(chart)
}

/// A part of a figure, in pixels.
pub type Area<DB> = DrawingArea<DB, Shift>;

/// `area` below `title`, split into the chart's part on the left, whose
/// plotting area [`chart`] makes square, and a column for the legend on
/// the right: a figure in the pad's plane with equal x and y ranges then
/// shows a millimetre as long across as up.
pub fn titled_square<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<(Area<DB>, Area<DB>), String> {
    let below = area
        .titled(title, (FONT, TITLE_SIZE).into_font())
        .map_err(drawing_error)?;
    let (_, height) = below.dim_in_pixel();
    Ok(below.split_horizontally(height + Y_LABEL_AREA - X_LABEL_AREA))
}

/// How a legend entry's sample is drawn.
#[derive(Debug, Clone, Copy)]
pub enum Sample {
    Line {
        colour: RGBColor,
        width: u32,
    },
    Dashed {
        colour: RGBColor,
        width: u32,
    },
    /// An outline: filled circles of a colour are the data's alone.
    Ring {
        colour: RGBColor,
    },
    /// A dot the data's size.
    Dot {
        colour: RGBColor,
    },
    Patch {
        colour: RGBColor,
    },
    /// Text only (a heading, a note).
    None,
}

/// One row of a legend; its label may span several lines (`\n`).
pub struct LegendEntry {
    pub sample: Sample,
    pub label: String,
}

impl LegendEntry {
    pub fn new(sample: Sample, label: impl Into<String>) -> Self {
        Self {
            sample,
            label: label.into(),
        }
    }
}

/// Height of a legend's text line, pixels.
const LEGEND_LINE: i32 = LABEL_SIZE as i32 + 7;

/// `entries` down `area` from its top left, each sample left of its label.
pub fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<(), String> {
    let (x, text_x) = (8, 50);
    let (width, _) = area.dim_in_pixel();
    // DejaVu Sans averages about half an em a character.
    let columns = ((width.saturating_sub(text_x as u32 + 8)) as f64 / (0.5 * LABEL_SIZE as f64))
        .max(10.0) as usize;
    let mut y = CHART_MARGIN as i32 + 4;
    for entry in entries {
        let middle = (y + LEGEND_LINE / 2 - 3, x + 16);
        let (mid_y, mid_x) = middle;
        let line = [(x, mid_y), (x + 32, mid_y)];
        let drawn = match entry.sample {
            Sample::Line { colour, width } => {
                area.draw(&PathElement::new(line, colour.stroke_width(width)))
            }
            Sample::Dashed { colour, width } => area.draw(&DashedPathElement::new(
                line,
                8,
                5,
                colour.stroke_width(width),
            )),
            Sample::Ring { colour } => {
                area.draw(&Circle::new((mid_x, mid_y), 7, colour.stroke_width(2)))
            }
            Sample::Dot { colour } => area.draw(&Circle::new((mid_x, mid_y), 5, colour.filled())),
            Sample::Patch { colour } => area.draw(&Rectangle::new(
                [(x + 4, mid_y - 8), (x + 28, mid_y + 8)],
                colour.mix(0.8).filled(),
            )),
            Sample::None => Ok(()),
        };
        drawn.map_err(drawing_error)?;
        for text in entry.label.lines().flat_map(|line| wrap(line, columns)) {
            area.draw(&Text::new(
                text,
                (text_x, y),
                (FONT, LABEL_SIZE).into_font(),
            ))
            .map_err(drawing_error)?;
            y += LEGEND_LINE;
        }
        y += 6;
    }
    Ok(())
}

/// `text` broken at spaces into lines of at most `columns` characters
/// (a longer word stands alone), the later ones indented.
fn wrap(text: &str, columns: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if line.chars().count() + 1 + word.chars().count() <= columns => {
                line.push(' ');
                line.push_str(word);
            }
            Some(_) => lines.push(format!("   {word}")),
            None => lines.push(word.to_owned()),
        }
    }
    lines
}

/// The stretch of `line` within the square |x|, |y| ≤ `half_mm` (a
/// chart's view, or the pad), as its two ends; `None` if it misses it.
/// plotters does not clip what it draws to the chart.
pub fn line_in_square(line: &LineInSensor, half_mm: f64) -> Option<[(f64, f64); 2]> {
    let (sin, cos) = line.alpha_rad.sin_cos();
    let start = (-sin * line.n_mm, cos * line.n_mm);
    let (mut low, mut high) = (f64::NEG_INFINITY, f64::INFINITY);
    for (p, d) in [(start.0, cos), (start.1, sin)] {
        if d.abs() < 1e-12 {
            if p.abs() > half_mm {
                return None;
            }
            continue;
        }
        let (a, b) = ((-half_mm - p) / d, (half_mm - p) / d);
        low = low.max(a.min(b));
        high = high.min(a.max(b));
    }
    let at = |t: f64| (start.0 + t * cos, start.1 + t * sin);
    (low < high).then(|| [at(low), at(high)])
}

/// Reads the font once per process and gives it to plotters (which keeps
/// it for the process's life, as a `'static` slice).
fn register_the_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let from_variable = std::env::var_os(FONT_VARIABLE).map(PathBuf::from);
            let candidates: Vec<PathBuf> = from_variable
                .into_iter()
                .chain(FONT_PATHS.iter().map(PathBuf::from))
                .collect();
            let (path, bytes) = candidates
                .iter()
                .find_map(|path| Some((path, std::fs::read(path).ok()?)))
                .ok_or_else(|| {
                    let looked: Vec<String> =
                        candidates.iter().map(|p| p.display().to_string()).collect();
                    format!("looked at {}", looked.join(", "))
                })?;
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            register_font(FONT, FontStyle::Normal, bytes)
                .map_err(|_| format!("{} is not a TrueType font", path.display()))
        })
        .clone()
        .map_err(|reason| PlotError::NoFont { reason })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_chooses_the_format() {
        assert_eq!(Format::of(Path::new("a/b.png")).unwrap(), Format::Png);
        assert_eq!(Format::of(Path::new("b.SVG")).unwrap(), Format::Svg);
        let error = Format::of(Path::new("b.pdf")).unwrap_err();
        assert!(error.to_string().contains(".png or .svg"), "{error}");
        assert!(Format::of(Path::new("b")).is_err());
    }

    #[test]
    fn long_labels_wrap_at_spaces() {
        assert_eq!(wrap("short", 20), ["short"]);
        assert_eq!(
            wrap("trial grasp, the pad's fit: n +1.00 mm", 20),
            ["trial grasp, the", "   pad's fit: n", "   +1.00 mm"]
        );
    }

    #[test]
    fn a_line_is_clipped_to_the_square() {
        let across = line_in_square(&LineInSensor::new(0.0, 2.0), 5.0).unwrap();
        assert_eq!(across, [(-5.0, 2.0), (5.0, 2.0)]);
        assert!(line_in_square(&LineInSensor::new(0.0, 6.0), 5.0).is_none());
        let up = line_in_square(&LineInSensor::new(std::f64::consts::FRAC_PI_2, 1.0), 5.0).unwrap();
        assert!((up[0].0 + 1.0).abs() < 1e-9 && (up[1].0 + 1.0).abs() < 1e-9);
        assert!((up[0].1.abs() - 5.0).abs() < 1e-9);
        // The diagonal meets the corners.
        let diagonal =
            line_in_square(&LineInSensor::new(std::f64::consts::FRAC_PI_4, 0.0), 5.0).unwrap();
        assert!((diagonal[0].0 + 5.0).abs() < 1e-9 && (diagonal[1].1 - 5.0).abs() < 1e-9);
    }
}

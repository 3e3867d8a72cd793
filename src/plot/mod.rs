//! Figures drawn from what a run recorded, as PNG or SVG (chosen by the
//! output file's extension), with one look for all of them: the font, the
//! colours each source of data keeps from figure to figure, the sizes.
//! `fusion` is the paper's Fig. 12.
//!
//! The text is drawn with a TrueType font read at run time (DejaVu Sans,
//! Debian's `fonts-dejavu-core`, which `scripts/setup` installs), so that
//! neither fontconfig nor a system font service is needed.

pub mod fusion;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::{
    BitMapBackend, DrawingArea, DrawingAreaErrorKind, DrawingBackend, IntoDrawingArea, RGBColor,
    SVGBackend,
};
use plotters::style::{FontStyle, register_font};

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
}

/// A drawing error as text, whatever the backend.
pub fn drawing_error<E: std::error::Error + Send + Sync>(error: DrawingAreaErrorKind<E>) -> String {
    error.to_string()
}

/// Draws `figure` into `path`, PNG or SVG by its extension, at [`SIZE`].
pub fn save(figure: &impl Figure, path: &Path) -> Result<(), PlotError> {
    let format = Format::of(path)?;
    register_the_font()?;
    let failed = |message: String| PlotError::Draw {
        path: path.to_owned(),
        message,
    };
    match format {
        Format::Png => {
            let area = BitMapBackend::new(path, SIZE).into_drawing_area();
            area.fill(&BACKGROUND)
                .map_err(drawing_error)
                .map_err(failed)?;
            figure.draw(&area).map_err(failed)?;
            area.present().map_err(drawing_error).map_err(failed)
        }
        Format::Svg => {
            let area = SVGBackend::new(path, SIZE).into_drawing_area();
            area.fill(&BACKGROUND)
                .map_err(drawing_error)
                .map_err(failed)?;
            figure.draw(&area).map_err(failed)?;
            area.present().map_err(drawing_error).map_err(failed)
        }
    }
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
}

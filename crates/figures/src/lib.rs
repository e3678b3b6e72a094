//! The only plotters user: [`FigureSpec`] to SVG, PNG and a raw RGB buffer,
//! plus the figure's data series as CSV (what snapshots and `xtask diff` pin).
//!
//! Everything here is deterministic: one embedded font (DejaVu Sans, see
//! `assets/LICENSE-DejaVu.txt`), no system font lookup, axis ranges computed
//! from the data with fixed padding, fixed colour palette, no clock.

mod csv;
mod draw;
mod range;

use plotters::prelude::*;
use rig_types::FigureSpec;

pub use csv::series_csv;

/// Width and height of every rendered figure, pixels.
pub const SIZE_PX: (u32, u32) = (900, 600);

/// What went wrong turning a figure spec into a picture. `id` is the
/// figure's file stem; the producing stage is the one to fix.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The spec is malformed (e.g. a series whose x and y lengths differ):
    /// fix the stage that filled the [`FigureSpec`].
    #[error("figure {id}: invalid spec: {reason}")]
    Spec { id: String, reason: String },
    /// plotters failed while drawing.
    #[error("figure {id}: {reason}")]
    Draw { id: String, reason: String },
    /// Encoding the bitmap as PNG failed (temporary file IO or encoder).
    #[error("figure {id}: PNG encoding: {reason}")]
    Png { id: String, reason: String },
}

type Result<T> = std::result::Result<T, FigureError>;

/// The embedded font; registered once under the family name plotters uses
/// for `"sans-serif"`, so layout and bitmap text never consult the system.
static FONT_TTF: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

fn ensure_font() -> std::result::Result<(), String> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok =
        *REGISTERED.get_or_init(|| plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_TTF).is_ok());
    if ok { Ok(()) } else { Err("the embedded DejaVu Sans font could not be parsed".into()) }
}

fn prepare(spec: &FigureSpec) -> Result<draw::Plan> {
    ensure_font().map_err(|reason| FigureError::Draw { id: spec.id.clone(), reason })?;
    draw::Plan::new(spec).map_err(|reason| FigureError::Spec { id: spec.id.clone(), reason })
}

/// SVG text of the figure (text stays text: the viewer's sans-serif font renders it).
pub fn render_svg(spec: &FigureSpec) -> Result<String> {
    let plan = prepare(spec)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE_PX).into_drawing_area();
        draw::draw(&root, spec, &plan).map_err(|e| FigureError::Draw { id: spec.id.clone(), reason: e.to_string() })?;
    }
    Ok(svg)
}

/// Raw RGB8 pixels (row-major, `SIZE_PX.0 * SIZE_PX.1 * 3` bytes): what
/// snapshots hash, because PNG bytes depend on the encoder version.
pub fn render_rgb(spec: &FigureSpec) -> Result<Vec<u8>> {
    let plan = prepare(spec)?;
    let mut buf = vec![0u8; (SIZE_PX.0 * SIZE_PX.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE_PX).into_drawing_area();
        draw::draw(&root, spec, &plan).map_err(|e| FigureError::Draw { id: spec.id.clone(), reason: e.to_string() })?;
    }
    Ok(buf)
}

/// PNG bytes of the figure.
///
/// plotters only encodes PNG when saving to a path (its `image` dependency is
/// not re-exported), so the pixels of [`render_rgb`] are blitted into a file
/// backend in a private temporary directory and read back.
pub fn render_png(spec: &FigureSpec) -> Result<Vec<u8>> {
    let rgb = render_rgb(spec)?;
    let png_err = |reason: String| FigureError::Png { id: spec.id.clone(), reason };
    let dir = tempfile::tempdir().map_err(|e| png_err(format!("creating a temporary directory: {e}")))?;
    let path = dir.path().join("figure.png");
    {
        let mut backend = BitMapBackend::new(&path, SIZE_PX);
        backend.blit_bitmap((0, 0), SIZE_PX, &rgb).map_err(|e| png_err(e.to_string()))?;
        backend.present().map_err(|e| png_err(e.to_string()))?;
    }
    std::fs::read(&path).map_err(|e| png_err(format!("reading {}: {e}", path.display())))
}

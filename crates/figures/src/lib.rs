//! The only plotters user: [`FigureSpec`] to SVG, PNG and a raw RGB buffer,
//! plus the figure's data series as CSV (what snapshots and `xtask diff` pin).
//!
//! Everything here is deterministic: one embedded font (DejaVu Sans, see
//! `assets/LICENSE-DejaVu.txt`), no system font lookup, axis ranges computed
//! from the data with fixed padding, one colour-blind-safe palette (Okabe–Ito),
//! no clock. Besides single figures: multi-panel [`Sheet`]s (log-x panels, whose
//! ticks come from one place, `log_axis`; one shared legend), marker shapes,
//! shaded bands and hatched heat-map regions.

mod csv;
mod draw;
mod glyph;
mod log_axis;
mod png_io;
mod range;

use plotters::prelude::*;
use rig_types::{AxisScale, FigureSpec, Sheet};

pub use csv::{series_csv, sheet_csv};
pub use png_io::{PngSettings, decode_png, encode_png};

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
    /// Encoding or decoding a PNG failed.
    #[error("figure {id}: PNG: {reason}")]
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
    prepare_scaled(spec, &spec.id, AxisScale::Linear)
}

fn prepare_scaled(spec: &FigureSpec, id: &str, x_scale: AxisScale) -> Result<draw::Plan> {
    ensure_font().map_err(|reason| FigureError::Draw { id: id.to_string(), reason })?;
    draw::Plan::new(spec, x_scale).map_err(|reason| FigureError::Spec { id: id.to_string(), reason })
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

/// PNG bytes of the figure ([`render_rgb`] encoded with [`PngSettings::default`]).
pub fn render_png(spec: &FigureSpec) -> Result<Vec<u8>> {
    let rgb = render_rgb(spec)?;
    encode_png(SIZE_PX, &rgb, PngSettings::default()).map_err(|reason| FigureError::Png { id: spec.id.clone(), reason })
}

/// Pixel size of a rendered sheet (it grows with its panel grid).
pub fn sheet_size_px(sheet: &Sheet) -> (u32, u32) {
    draw::sheet_size(sheet)
}

fn prepare_sheet(sheet: &Sheet) -> Result<Vec<draw::Plan>> {
    if sheet.panels.is_empty() {
        return Err(FigureError::Spec { id: sheet.id.clone(), reason: "a sheet needs at least one panel".into() });
    }
    sheet
        .panels
        .iter()
        .enumerate()
        .map(|(i, p)| prepare_scaled(&p.spec, &format!("{} panel {}", sheet.id, i + 1), p.x_scale))
        .collect()
}

/// SVG text of a multi-panel sheet.
pub fn render_sheet_svg(sheet: &Sheet) -> Result<String> {
    let plans = prepare_sheet(sheet)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, sheet_size_px(sheet)).into_drawing_area();
        draw::draw_sheet(&root, sheet, &plans)
            .map_err(|e| FigureError::Draw { id: sheet.id.clone(), reason: e.to_string() })?;
    }
    Ok(svg)
}

/// Raw RGB8 pixels of a sheet, [`sheet_size_px`] in size.
pub fn render_sheet_rgb(sheet: &Sheet) -> Result<Vec<u8>> {
    let plans = prepare_sheet(sheet)?;
    let size = sheet_size_px(sheet);
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw::draw_sheet(&root, sheet, &plans)
            .map_err(|e| FigureError::Draw { id: sheet.id.clone(), reason: e.to_string() })?;
    }
    Ok(buf)
}

/// PNG bytes of a sheet.
pub fn render_sheet_png(sheet: &Sheet) -> Result<Vec<u8>> {
    let rgb = render_sheet_rgb(sheet)?;
    encode_png(sheet_size_px(sheet), &rgb, PngSettings::default())
        .map_err(|reason| FigureError::Png { id: sheet.id.clone(), reason })
}

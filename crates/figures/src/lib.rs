//! The only plotters user: [`FigureSpec`] to SVG and PNG, plus the data series
//! as CSV for snapshots.

use rig_types::FigureSpec;

#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("figure {id}: {reason}")]
    Draw { id: String, reason: String },
}

/// SVG text of the figure. Not written yet.
pub fn render_svg(spec: &FigureSpec) -> Result<String, FigureError> {
    Err(FigureError::Draw { id: spec.id.clone(), reason: "not implemented".into() })
}

/// PNG bytes of the figure. Not written yet.
pub fn render_png(spec: &FigureSpec) -> Result<Vec<u8>, FigureError> {
    Err(FigureError::Draw { id: spec.id.clone(), reason: "not implemented".into() })
}

/// The figure's data series as CSV text. Not written yet.
pub fn series_csv(spec: &FigureSpec) -> String {
    let _ = spec;
    String::new()
}

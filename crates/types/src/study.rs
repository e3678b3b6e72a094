//! What a study hands its stage to write: tables, figures, its markdown page
//! and its diagnosis (schema of ../shared/spec/diagnosis.md), in a fixed
//! order. One type for every study of a real data set (LAVI, slider); the
//! diagnosis' JSON value type is the study's (rig-types carries serde only).

use crate::{FigureSpec, Table};

/// Everything a study's stage writes, in a fixed order.
#[derive(Debug, Default)]
pub struct StudyOutput<D> {
    /// (path under the out dir, table).
    pub tables: Vec<(String, Table)>,
    pub figures: Vec<FigureSpec>,
    /// `<study>.md`.
    pub markdown: String,
    /// `<study>-diagnosis.json`.
    pub diagnosis: D,
}

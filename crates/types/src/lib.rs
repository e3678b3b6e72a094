//! Plain data shared by every rig-lab crate; serde (and toml, for
//! [`pipeline_toml`]) only, no behaviour beyond
//! trivial accessors, the unit conversions ([`units`]), the sensor model
//! ([`sensor`]: encoder quantisation and the speed differentiators, the one
//! home every crate that reads or simulates an encoder uses), the bracketed
//! scalar minimiser every fitting crate shares ([`minimize`]), the one
//! forward-selection engine every rig's study selects with ([`select`]),
//! `total_cmp`'s order as integer keys ([`order`]) and the typed reading of a
//! pipeline.toml text for code the DAG does not run ([`pipeline_toml`]).
//! Units are in field names (`_rad_s`, `_nm`, `_v`).

mod campaign;
pub mod contract;
pub mod cpu;
mod figure;
pub mod linear;
pub mod minimize;
pub mod order;
mod params;
pub mod pipeline_toml;
pub mod select;
pub mod sensor;
mod study;
mod table;
pub mod thesis;
mod trajectory;
pub mod units;

pub use campaign::{Campaign, RigInfo, Run, RunData, RunKind};
pub use figure::{
    AxisScale, FigureSpec, Heatmap, MarkerShape, Panel, Series, SeriesStyle, Sheet, band, figure, series,
};
pub use params::{
    DriveParams, Effect, FrictionLaw, HarmonicFriction, ModelKind, MotorParams, RigParams, RunInput, ThesisFriction,
};
pub use study::StudyOutput;
pub use table::{Table, fmt_fixed};
pub use trajectory::Trajectory;

//! The workspace's one linear least-squares solver, `rig_types::linear`,
//! under the name the estimation and the diagnosis have always used: it moved
//! to `rig-types` so that calibration (which the estimation depends on)
//! solves there too. Its errors become [`crate::EstimateError`] by `?`.

pub use rig_types::linear::*;

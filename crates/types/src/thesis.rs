//! The chapter's published tables as plain data (what `rig_ingest::thesis`
//! reads from data/thesis/*.csv and `rig_calibrate` recomputes and audits),
//! each number kept with its printed precision.

use serde::{Deserialize, Serialize};

/// A number as printed: its value and how many decimals were printed
/// (`0.30` → 2; `0.37e-3` → 5; `7850` → 0), so "equal at printed precision"
/// can be decided.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Printed {
    pub value: f64,
    pub decimals: i32,
}

impl Printed {
    /// One unit of the last printed digit.
    pub fn unit(&self) -> f64 {
        10f64.powi(-self.decimals)
    }
}

/// A row of a parameter table (Tables 4.1, 4.4, 4.5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamRow {
    pub symbol: String,
    pub description: String,
    pub value: Printed,
    /// As printed (e.g. `mm`, `GPa`, `kgm^2`).
    pub unit: String,
}

/// Table 4.2; `trial` is `1`…`4` or `mean`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecayRow {
    pub trial: String,
    pub x1_rad: Printed,
    pub x2_rad: Printed,
    pub log_decrement: Printed,
    pub damping_ratio: Printed,
    pub damped_hz: Printed,
    pub natural_hz: Printed,
}

/// Table 4.3; torque and angle are empty on the mean row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StiffnessRow {
    pub trial: String,
    pub torque_nm: Option<Printed>,
    pub angle_rad: Option<Printed>,
    pub k_se_nm_rad: Printed,
    pub rel_error_pct: Printed,
}

/// Table 4.6; weight and voltage are empty on the mean row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForceRow {
    pub trial: String,
    pub weight_n: Option<Printed>,
    pub voltage_mv: Option<Printed>,
    pub factor_mv_per_n: Printed,
}

/// Table 4.7.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrictionRow {
    pub symbol: String,
    pub description: String,
    pub value: Printed,
    /// `=` or `<=` (the μ_neg row prints "≤ 0").
    pub setpoint_relation: String,
    pub setpoint_rpm: Printed,
}

/// Table 4.8.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PeakRow {
    pub peak: String,
    pub freq_hz: Printed,
    pub freq_rad_s: Printed,
}

/// A scalar result or statement of the text (equations.csv).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Statement {
    pub id: String,
    pub symbol: String,
    pub value: Printed,
    pub unit: String,
    #[serde(rename = "where")]
    pub location: String,
    pub statement: String,
}

/// An operating point a figure caption labels (labelled-operating-points.csv).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LabelledPoint {
    pub figure: String,
    pub panel: String,
    pub motor_rpm: f64,
    pub frict_n: f64,
    /// `vibrating` or `quiet`.
    pub label: String,
    /// `numerical` or `experimental`.
    pub source: String,
}

/// Every table of the chapter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThesisTables {
    pub table_4_1: Vec<ParamRow>,
    pub table_4_2: Vec<DecayRow>,
    pub table_4_3: Vec<StiffnessRow>,
    pub table_4_4: Vec<ParamRow>,
    pub table_4_5: Vec<ParamRow>,
    pub table_4_6: Vec<ForceRow>,
    pub table_4_7: Vec<FrictionRow>,
    pub table_4_8: Vec<PeakRow>,
    pub statements: Vec<Statement>,
    pub labelled_points: Vec<LabelledPoint>,
}

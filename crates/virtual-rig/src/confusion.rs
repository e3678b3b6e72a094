//! The confusion experiment: many seeded hidden-effect campaigns, each
//! diagnosed blind by a caller-supplied function (this crate does not depend
//! on the diagnosis), summarised as a confusion matrix and parameter errors.

use crate::{Hidden, Protocol, draw_truth, generate};
use rig_types::{Campaign, Table, fmt_fixed};
use std::collections::BTreeMap;

/// What a blind diagnosis returned for one campaign: verdict and parameters (JSON keys).
pub type Verdict = (String, BTreeMap<String, f64>);

/// One diagnosed draw.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    pub class: &'static str,
    pub seed: u64,
    pub hidden: Hidden,
    /// `Err` carries the diagnosis error text (counted as a wrong verdict).
    pub result: Result<Verdict, String>,
}

impl Outcome {
    pub fn expected(&self) -> &'static str {
        self.hidden.id()
    }
    pub fn verdict(&self) -> &str {
        match &self.result {
            Ok((v, _)) => v,
            Err(_) => "error",
        }
    }
    pub fn correct(&self) -> bool {
        self.verdict() == self.expected()
    }
}

/// Runs `draws` campaigns per class (seeds base_seed + 1000·class + draw),
/// in a fixed order; `diagnose` is called on each generated campaign.
pub fn run_confusion(
    draws: usize,
    protocol: &Protocol,
    base_seed: u64,
    diagnose: impl Fn(&Campaign) -> Result<Verdict, String>,
) -> Vec<Outcome> {
    let max_rpm = protocol.op_points.iter().map(|p| p.0).fold(0.0, f64::max);
    let mut out = Vec::new();
    for (ci, class) in Hidden::CLASSES.iter().enumerate() {
        for j in 0..draws {
            let seed = base_seed + 1000 * ci as u64 + j as u64;
            let truth = draw_truth(class, max_rpm, seed);
            let result = generate(&format!("virtual-{class}-{j}"), &truth, protocol, seed)
                .map_err(|e| e.to_string())
                .and_then(|c| diagnose(&c));
            out.push(Outcome { class, seed, hidden: truth.hidden, result });
        }
    }
    out
}

/// All verdict ids a diagnosis can return, in the matrix's column order.
pub const VERDICTS: [&str; 8] = [
    "none",
    "normal_force_modulation",
    "angle_periodic_friction",
    "velocity_weakening_friction",
    "viscous_brake_friction",
    "drive_voltage_limit",
    "unexplained",
    "error",
];

/// Rows: hidden class; columns: verdicts (counts), then the accuracy.
pub fn confusion_table(outcomes: &[Outcome]) -> Table {
    let mut cols = vec!["hidden_class".to_string(), "expected".to_string()];
    cols.extend(VERDICTS.iter().map(|v| v.to_string()));
    cols.push("accuracy".into());
    let mut t = Table::new(cols);
    for class in Hidden::CLASSES {
        let rows: Vec<&Outcome> = outcomes.iter().filter(|o| o.class == class).collect();
        if rows.is_empty() {
            continue;
        }
        let mut r = vec![class.to_string(), rows[0].expected().to_string()];
        for v in VERDICTS {
            r.push(rows.iter().filter(|o| o.verdict() == v).count().to_string());
        }
        let acc = rows.iter().filter(|o| o.correct()).count() as f64 / rows.len() as f64;
        r.push(fmt_fixed(acc, 2));
        t.push(r);
    }
    t
}

/// One row per (draw, true parameter) of correctly diagnosed draws: truth,
/// estimate, relative error.
pub fn params_table(outcomes: &[Outcome]) -> Table {
    let mut t = Table::new(["hidden_class", "seed", "param", "truth", "estimate", "relative_error"]);
    for o in outcomes {
        let Ok((v, est)) = &o.result else { continue };
        if v != o.expected() {
            continue;
        }
        for (k, truth) in o.hidden.params() {
            let e = est.get(k).copied().unwrap_or(f64::NAN);
            t.push([
                o.class.to_string(),
                o.seed.to_string(),
                k.to_string(),
                fmt_fixed(truth, 4),
                fmt_fixed(e, 4),
                fmt_fixed((e - truth) / truth, 4),
            ]);
        }
    }
    t
}

/// Tolerance on the relative error of each parameter that the hidden-effect
/// tests require (stated once; confusion.md prints it).
pub fn tolerance(param: &str) -> f64 {
    match param {
        "order" => 0.0,
        "frequency_hz" => 0.01,
        "mu_kinetic" | "mu_static" | "limit_v" => 0.05,
        "amplitude_ratio" => 0.15,
        "stribeck_speed_rad_s" | "viscous_per_rad_s" => 0.2,
        _ => 0.1,
    }
}

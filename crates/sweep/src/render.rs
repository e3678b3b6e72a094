//! CSV tables of sweeps: one row per point, chains in their fixed order.

use crate::continuation::{ChainResult, MapSlice};
use rig_types::{Table, fmt_fixed};

use rig_types::units::RAD_S_TO_RPM;

const COLUMNS: [&str; 13] = [
    "direction",
    "motor_rpm",
    "normal_force_n",
    "rotor_rpm_min",
    "rotor_rpm_max",
    "rotor_rpm_mean",
    "severity_half",
    "severity_full",
    "regime",
    "cycles",
    "clusters",
    "decided_by",
    "note",
];

fn push_chain(t: &mut Table, c: &ChainResult) {
    for o in &c.points {
        let mut row = vec![
            c.direction.as_str().to_string(),
            fmt_fixed(o.point.motor_rpm, 2),
            fmt_fixed(o.point.normal_force_n, 3),
        ];
        match &o.result {
            // Simulated speeds are exact (no encoder): two decimals of rpm; severities to 0.001.
            Ok(k) => row.extend([
                fmt_fixed(k.min_rad_s * RAD_S_TO_RPM, 2),
                fmt_fixed(k.max_rad_s * RAD_S_TO_RPM, 2),
                fmt_fixed(k.mean_rad_s * RAD_S_TO_RPM, 2),
                fmt_fixed(k.severity_half, 3),
                fmt_fixed(k.severity_full, 3),
                k.regime.label(),
                k.cycles.to_string(),
                k.clusters.to_string(),
                k.decided_by.clone(),
                String::new(),
            ]),
            Err(e) => {
                row.extend(std::iter::repeat_n(String::new(), 5));
                row.extend(["not converged".to_string(), String::new(), String::new(), String::new(), e.clone()]);
            }
        }
        t.push(row);
    }
}

/// The map table: chains in index order (row by row of friction, up then down).
pub fn map_table(map: &MapSlice) -> Table {
    let mut t = Table::new(COLUMNS);
    for c in &map.chains {
        push_chain(&mut t, c);
    }
    t
}

/// A bifurcation diagram's table (its chains in order: up, then down).
pub fn chain_table(chains: &[ChainResult]) -> Table {
    let mut t = Table::new(COLUMNS);
    for c in chains {
        push_chain(&mut t, c);
    }
    t
}

//! Free-run comparison: the baseline rig model simulated for every operating
//! point (rig_model::simulate at the recording's sample times) and reduced to
//! the same steady-state features as the measurement (stick-slip or not,
//! rotor speed min/max, stick-slip fundamental, motor-speed dip).

use crate::DiagnoseOptions;
use crate::report::Features;
use crate::select::steady_features;
use rig_model::SimOptions;
use rig_types::{Campaign, RigParams, RunInput, RunKind};

/// Features of the free-run simulation of each operating point (campaign
/// order); `None` where the integrator failed (non-convergence is data).
pub fn simulate_features(c: &Campaign, p: &RigParams, opts: &DiagnoseOptions) -> Vec<Option<Features>> {
    use rayon::prelude::*;
    let ops: Vec<_> = c.runs_of("operating_point").collect();
    ops.par_iter()
        .map(|run| {
            let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else { return None };
            let input = RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s };
            let t = &run.data.time_s;
            let tr = rig_model::simulate(p, &input, t, &SimOptions::default()).ok()?;
            let from = t.partition_point(|&x| x < ramp_s + opts.settle_s);
            Some(steady_features(
                &t[from..],
                &tr.rotor_speed_rad_s[from..],
                &tr.motor_speed_rad_s[from..],
                motor_rpm_setpoint * 2.0 * std::f64::consts::PI / 60.0,
                opts.slip_speed_rad_s,
            ))
        })
        .collect()
}

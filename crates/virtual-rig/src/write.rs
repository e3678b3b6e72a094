//! Writes a campaign folder in the `rig-campaign/1` format (campaign.toml + runs/*.csv).

use crate::VirtualRigError;
use rig_types::{Campaign, RunKind};
use std::fmt::Write as _;
use std::path::Path;

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> VirtualRigError + '_ {
    move |source| VirtualRigError::Io { path: path.to_path_buf(), source }
}

/// Writes `c` to `dir` (created if needed). Numbers are printed at the
/// precision of the shipped campaign: time 4 decimals, volts 3, mV 2.
pub fn write_campaign(dir: &Path, c: &Campaign) -> Result<(), VirtualRigError> {
    let runs_dir = dir.join("runs");
    std::fs::create_dir_all(&runs_dir).map_err(io(&runs_dir))?;
    let mut toml = String::new();
    let _ = writeln!(toml, "format = \"rig-campaign/1\"\nname = {:?}\ndescription = {:?}\n", c.name, c.description);
    let _ = writeln!(
        toml,
        "[rig]\nencoder_ticks_per_rev = {}\nbrake_disc_radius_m = {}\nsupply_voltage_v = {:?}\nsample_rate_hz = {:?}\n",
        c.rig.encoder_ticks_per_rev, c.rig.brake_disc_radius_m, c.rig.supply_voltage_v, c.rig.sample_rate_hz
    );
    for r in &c.runs {
        let _ = writeln!(
            toml,
            "[[runs]]\nid = {:?}\nkind = {:?}\nfile = {:?}",
            r.id,
            r.kind.name(),
            r.file.display().to_string()
        );
        match r.kind {
            RunKind::ForceCalibration { load_n } => {
                let _ = writeln!(toml, "load_n = {load_n:?}");
            }
            RunKind::StaticTwist { torque_nm } => {
                let _ = writeln!(toml, "torque_nm = {torque_nm:?}");
            }
            RunKind::VoltageStep { voltage_v } => {
                let _ = writeln!(toml, "voltage_v = {voltage_v:?}");
            }
            RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } => {
                let _ = writeln!(
                    toml,
                    "motor_rpm_setpoint = {motor_rpm_setpoint:?}\nnormal_force_n = {normal_force_n:?}\nramp_s = {ramp_s:?}"
                );
            }
        }
        toml.push('\n');
        let d = &r.data;
        let mut cols: Vec<&str> = vec!["time_s"];
        if d.motor_voltage_v.is_some() {
            cols.push("motor_voltage_v");
        }
        if d.motor_ticks.is_some() {
            cols.push("motor_ticks");
        }
        if d.rotor_ticks.is_some() {
            cols.push("rotor_ticks");
        }
        if d.brake_force_mv.is_some() {
            cols.push("brake_force_mv");
        }
        let mut csv = cols.join(",");
        csv.push('\n');
        for k in 0..d.time_s.len() {
            let _ = write!(csv, "{:.4}", d.time_s[k]);
            if let Some(v) = &d.motor_voltage_v {
                let _ = write!(csv, ",{:.3}", v[k]);
            }
            if let Some(v) = &d.motor_ticks {
                let _ = write!(csv, ",{}", v[k]);
            }
            if let Some(v) = &d.rotor_ticks {
                let _ = write!(csv, ",{}", v[k]);
            }
            if let Some(v) = &d.brake_force_mv {
                let _ = write!(csv, ",{:.2}", v[k]);
            }
            csv.push('\n');
        }
        let path = dir.join(&r.file);
        std::fs::write(&path, csv).map_err(io(&path))?;
    }
    let path = dir.join("campaign.toml");
    std::fs::write(&path, toml).map_err(io(&path))
}

//! Campaign folders (`rig-campaign/1`, ../shared/spec/recording-format.md) and
//! thesis tables to typed data, with polars; validates before it returns.
//!
//! [`read_campaign`] returns the whole [`Campaign`] or an [`IngestError`]
//! naming the file, the line and the rule — nothing is half-loaded, and it
//! writes nothing. It enforces every rule of the format:
//!
//! **campaign.toml**
//! - valid TOML; `format` is exactly `"rig-campaign/1"`; `name` present and
//!   not blank; `description` optional (empty when absent);
//! - `[rig]` present with `encoder_ticks_per_rev` (integer > 0),
//!   `brake_disc_radius_m`, `supply_voltage_v`, `sample_rate_hz` (finite, > 0);
//! - at least one `[[runs]]`; each has `id` (`[a-z0-9-]+`, unique), `kind`
//!   (one of the four kinds; others are refused), `file`, and exactly its
//!   kind's metadata keys;
//! - `file` is relative, not absolute, has no `..`, exists, is a regular file
//!   and lies inside the campaign folder also after resolving symlinks.
//!
//! **Metadata** (finite numbers; TOML integers are accepted as numbers). The
//! spec allows zero "only where the kind allows it"; this reader's reading:
//! - `force_calibration`: `load_n >= 0` (zero load is a tare run, the offset);
//! - `static_twist`: `torque_nm > 0` (a zero or negative torque gives no
//!   stiffness point in the thesis' one-directional static test, Table 4.3);
//! - `voltage_step`: `voltage_v != 0` (no step) and `|voltage_v| <= supply_voltage_v`
//!   (the drive saturates there); negative steps are allowed;
//! - `operating_point`: `motor_rpm_setpoint > 0`, `normal_force_n >= 0`
//!   (zero: brake open), `ramp_s >= 0` (zero: a step reference).
//!
//! **Direction** ("positive in the drive direction"): an operating point
//! drives forward (its set-point is positive) and a voltage step the way of
//! its voltage's sign, so neither encoder may run more than one revolution
//! the other way; the first such row is refused (a reversed encoder).
//!
//! **Unknown keys are refused** everywhere (top level, `[rig]`, each run):
//! a typo such as `lod_n` must not silently drop a value.
//!
//! **Each run's CSV**
//! - UTF-8; a header row (line 1) naming exactly the kind's columns, each
//!   once, in any order; at least one data row; no empty line; every row has
//!   as many cells as the header (no quoting: cells are plain numbers);
//! - every cell is a number: no missing cell, no text, no NaN or infinity;
//! - `time_s` starts at exactly 0 ("Every run starts at time_s = 0") and is
//!   strictly increasing (a repeated time is refused);
//! - encoder columns (`motor_ticks`, `rotor_ticks`) are written as integer
//!   literals: `1.5` is refused, and so are `1.0` and `1e3` — counts come out
//!   of the acquisition as integers, and a float spelling means the column
//!   went through floating-point processing. The spec's "zero at the start
//!   of the run" is *not* enforced: a static-twist run starts with the shaft
//!   already twisted, counted from the unloaded position (the shipped
//!   campaign's `twist-1` starts at 70);
//! - values are physically possible for the rig ("physically possible" of the
//!   metadata rule, applied to the samples): no signal exceeds what the rig's
//!   supply can produce. `|motor_voltage_v| <= 1.05 · supply_voltage_v` (the
//!   drive saturates at ± the supply; 5 % for measurement noise), and
//!   `|brake_force_mv| <= 1000 · supply_voltage_v` (the force sensor's
//!   amplifier cannot output more than the supply it runs on: 24 000 mV at
//!   24 V; the shipped campaign peaks at ~9 100 mV). A sample of 1e308 mV is
//!   refused with its line.
//!
//! Rules are checked in the order above and the first broken one is
//! reported (campaign.toml entirely before any CSV; runs in file order).
//! Within a CSV: header, empty lines, then the earliest faulty row (cell
//! count, missing/text/non-finite cell, leftmost column first; a row with too
//! many cells is reported first), then time. Error lines are 1-based; the
//! CSV header is line 1.
//!
//! [`lavi::read_lavi`] reads the real UFRJ/LAVI stick-slip recording with the
//! same CSV rules (without the start-at-zero rule); [`slider::read_slider_folder`]
//! reads a spring–slider folder (`runs/k<k>-v<V>.csv`) with them too.

mod columns;
mod error;
pub mod lavi;
mod manifest;
pub mod slider;
pub mod thesis;

pub use error::IngestError;
pub use manifest::FORMAT;

use columns::{ColValues, TimeStart, read_numeric_csv};
use rig_types::{Campaign, Run, RunData, RunKind};
use std::path::Path;

/// Reads and validates a whole campaign folder (`<dir>/campaign.toml` and the
/// CSV of every run), in campaign.toml order.
///
/// Errors name the file (joined to `dir`), the line and the broken rule; see
/// the crate docs for the rules and how the spec was read.
pub fn read_campaign(dir: &Path) -> Result<Campaign, IngestError> {
    let manifest = manifest::read_manifest(dir)?;
    let mut runs = Vec::with_capacity(manifest.runs.len());
    for entry in manifest.runs {
        let spec = manifest::kind_spec(&entry.kind);
        let values = read_numeric_csv(&entry.resolved, spec.columns, TimeStart::Zero)?;
        let mut data = RunData::default();
        for (col, v) in spec.columns.iter().zip(values) {
            match (col.name, v) {
                ("time_s", ColValues::Float(x)) => data.time_s = x,
                ("motor_voltage_v", ColValues::Float(x)) => data.motor_voltage_v = Some(x),
                ("brake_force_mv", ColValues::Float(x)) => data.brake_force_mv = Some(x),
                ("motor_ticks", ColValues::Count(x)) => data.motor_ticks = Some(x),
                ("rotor_ticks", ColValues::Count(x)) => data.rotor_ticks = Some(x),
                (name, _) => unreachable!("column {name} of kind {} has no RunData field", spec.name),
            }
        }
        check_plausible(&entry.resolved, &data, manifest.rig.supply_voltage_v)?;
        check_direction(&entry.resolved, &entry.kind, &data, manifest.rig.encoder_ticks_per_rev)?;
        runs.push(Run { id: entry.id, kind: entry.kind, file: entry.file, data });
    }
    Ok(Campaign { name: manifest.name, description: manifest.description, rig: manifest.rig, runs })
}

/// Headroom over the supply for a measured armature voltage (noise on a saturated drive).
pub const VOLTAGE_MARGIN: f64 = 1.05;
/// Largest force-sensor output per volt of supply, mV/V (the amplifier runs on the supply).
pub const FORCE_MV_PER_SUPPLY_V: f64 = 1000.0;

/// The physical-range rule of the samples (crate docs): the first sample out
/// of range, with its CSV line (data row i is line i + 2).
fn check_plausible(file: &Path, data: &RunData, supply_v: f64) -> Result<(), IngestError> {
    let limits = [
        ("motor_voltage_v", data.motor_voltage_v.as_deref(), VOLTAGE_MARGIN * supply_v, "V", "the drive's supply"),
        (
            "brake_force_mv",
            data.brake_force_mv.as_deref(),
            FORCE_MV_PER_SUPPLY_V * supply_v,
            "mV",
            "what a sensor on the rig's supply can output",
        ),
    ];
    for (name, values, limit, unit, why) in limits {
        if let Some(i) = values.and_then(|v| v.iter().position(|x| x.abs() > limit)) {
            let x = values.expect("found in it")[i];
            return Err(IngestError::rule(
                file,
                Some(i + 2),
                format!(
                    "{name} = {} {unit} is physically impossible: |{name}| must be <= {} {unit} ({why}, supply_voltage_v = {})",
                    show(x),
                    show(limit),
                    show(supply_v)
                ),
            ));
        }
    }
    Ok(())
}

/// The direction rule (crate docs): encoder counts are positive in the drive
/// direction, so a run the drive turns one way cannot run a whole revolution
/// the other. An operating point's set-point is positive (forward); a voltage
/// step turns the way of its voltage's sign. The first row more than one
/// revolution against that direction is refused (a reversed encoder, or a
/// record of the other direction without its counts negated): read as it is,
/// its PI gains come out with the wrong sign and the diagnosis is wrong.
fn check_direction(file: &Path, kind: &RunKind, data: &RunData, ticks_per_rev: u32) -> Result<(), IngestError> {
    let (sign, why) = match *kind {
        RunKind::OperatingPoint { motor_rpm_setpoint, .. } => {
            (1, format!("motor_rpm_setpoint = {} rpm drives it forward", show(motor_rpm_setpoint)))
        }
        RunKind::VoltageStep { voltage_v } if voltage_v < 0.0 => {
            (-1, format!("voltage_v = {} V drives it backward", show(voltage_v)))
        }
        RunKind::VoltageStep { voltage_v } => (1, format!("voltage_v = {} V drives it forward", show(voltage_v))),
        _ => return Ok(()),
    };
    let rev = i64::from(ticks_per_rev);
    for (name, counts) in [("motor_ticks", &data.motor_ticks), ("rotor_ticks", &data.rotor_ticks)] {
        let Some(counts) = counts else { continue };
        if let Some(i) = counts.iter().position(|&c| sign * c < -rev) {
            return Err(IngestError::rule(
                file,
                Some(i + 2),
                format!(
                    "{name} = {} is more than one revolution ({rev} counts) against the drive direction: encoder \
                     counts are positive in the drive direction and {why} (a reversed encoder's counts must be negated)",
                    counts[i]
                ),
            ));
        }
    }
    Ok(())
}

/// A number for a message: plain up to six decimals, scientific when huge or tiny.
fn show(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e6).contains(&x.abs()) {
        return format!("{x:e}");
    }
    let s = format!("{x:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

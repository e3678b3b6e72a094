//! The truths the battery's cases hide: the base rig a class needs, one
//! class alone, two at once, a ladder's size.

use super::{Case, Group};
use crate::{Hidden, Protocol, Truth, draw_hidden, draw_rig, draw_stick_slip_rig, ids};

pub(super) fn max_rpm(p: &Protocol) -> f64 {
    p.op_points.iter().map(|x| x.0).fold(0.0, f64::max)
}

/// The effect-free rig a case with `class` hidden is built on: a rig that
/// stick-slips ([`draw_stick_slip_rig`]) for the stick-slipping nulls, for
/// static friction aging (only a stick shows it) and for the structural
/// faults (their free-run signature is in the stick-slip cycle), else
/// [`draw_rig`]'s.
pub(super) fn base_rig(class: &str, seed: u64, protocol: &Protocol) -> Truth {
    if class == ids::NONE || class == ids::STATIC_FRICTION_AGING || ids::STRUCTURAL.contains(&class) {
        draw_stick_slip_rig(seed, protocol).unwrap_or_else(|| {
            panic!("no rig drawn from seed {seed} stick-slips under this protocol: it needs slow, loaded points")
        })
    } else {
        draw_rig(seed)
    }
}

/// `per` cases of each class of `classes` hidden alone, on the rig it needs
/// ([`base_rig`]), ids `<prefix>-<class>-<j>`, seeds `seed0 + k` in order.
pub(super) fn alone(
    classes: &[&str],
    group: Group,
    prefix: &str,
    per: usize,
    seed0: u64,
    protocol: &Protocol,
) -> Vec<Case> {
    let max_rpm = max_rpm(protocol);
    let mut cases = Vec::new();
    for class in classes {
        for j in 0..per {
            let s = seed0 + cases.len() as u64;
            let base = base_rig(class, s, protocol);
            let h = draw_hidden(class, base.mu_kinetic(), max_rpm, s);
            cases.push(Case {
                id: format!("{prefix}-{class}-{j}"),
                group,
                seed: s,
                truth: base.with_hidden(vec![h]),
                rung: None,
            });
        }
    }
    cases
}

/// A case with two hidden effects, the second drawn with its own seed, on
/// the rig the second needs ([`base_rig`]).
pub(super) fn compound(
    id: &str,
    group: Group,
    seed: u64,
    effects: [&str; 2],
    max_rpm: f64,
    protocol: &Protocol,
) -> Case {
    let base = base_rig(effects[1], seed, protocol);
    let mu_k = base.mu_kinetic();
    let a = draw_hidden(effects[0], mu_k, max_rpm, seed);
    let b = draw_hidden(effects[1], mu_k, max_rpm, seed.wrapping_add(0x5151_5151));
    Case { id: id.to_string(), group, seed, truth: base.with_hidden(vec![a, b]), rung: None }
}

/// The vocabulary effect `effect` at ladder size `size` (see [`ladder`]);
/// its other parameters (frequency, order, Stribeck speed) drawn as usual.
pub(super) fn ladder_hidden(effect: &str, size: f64, base: &Truth, max_rpm: f64, seed: u64) -> Hidden {
    let mu_k = base.mu_kinetic();
    match draw_hidden(effect, mu_k, max_rpm, seed) {
        Hidden::NormalForceModulation { frequency_hz, .. } => {
            Hidden::NormalForceModulation { amplitude_ratio: size, frequency_hz }
        }
        Hidden::AnglePeriodicFriction { order, .. } => Hidden::AnglePeriodicFriction { amplitude_ratio: size, order },
        Hidden::VelocityWeakening { stribeck_speed_rad_s, .. } => {
            Hidden::VelocityWeakening { mu_static: mu_k * (1.0 + size), mu_kinetic: mu_k, stribeck_speed_rad_s }
        }
        Hidden::ViscousBrake { .. } => Hidden::ViscousBrake { mu_kinetic: mu_k, viscous_per_rad_s: mu_k * size / 10.0 },
        Hidden::DriveVoltageLimit { .. } => {
            let m = &base.truth_motor();
            let back_emf_v = rig_types::units::rpm_to_rad_s(m.0 * m.1 * max_rpm);
            Hidden::DriveVoltageLimit { limit_v: size * back_emf_v }
        }
        other => other,
    }
}

impl Truth {
    /// (k_e in V·s/rad, gear ratio n) of the drawn motor.
    fn truth_motor(&self) -> (f64, f64) {
        (self.params.motor.voltage_constant_v_s_rad, self.params.motor.gear_ratio)
    }
}

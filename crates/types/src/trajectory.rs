//! A simulated (or reconstructed) time history of the rig at given sample times.

use serde::{Deserialize, Serialize};

/// All channels have `time_s.len()` entries. Angles are cumulative, zero at t = 0.
/// "Motor side" means the shaft end driven by the gearbox output (where the
/// motor encoder sits); speeds are at the shaft, not at the motor armature.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    pub time_s: Vec<f64>,
    /// Rotor 1 angle φ1.
    pub rotor_angle_rad: Vec<f64>,
    /// Rotor 1 speed Ω1.
    pub rotor_speed_rad_s: Vec<f64>,
    /// Motor-side shaft angle φ2.
    pub motor_angle_rad: Vec<f64>,
    /// Motor-side shaft speed Ω2.
    pub motor_speed_rad_s: Vec<f64>,
    /// Armature current i.
    pub current_a: Vec<f64>,
    /// Armature voltage V applied by the drive (or imposed, for a voltage step).
    pub voltage_v: Vec<f64>,
    /// Friction torque T1 of the brake on rotor 1 (positive opposes positive Ω1).
    pub friction_torque_nm: Vec<f64>,
    /// True where rotor 1 is in the stick phase.
    pub stuck: Vec<bool>,
}

impl Trajectory {
    pub fn len(&self) -> usize {
        self.time_s.len()
    }
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The eight numeric channels, time first, in declaration order (all but `stuck`).
    pub fn numeric_channels(&self) -> [&Vec<f64>; 8] {
        [
            &self.time_s,
            &self.rotor_angle_rad,
            &self.rotor_speed_rad_s,
            &self.motor_angle_rad,
            &self.motor_speed_rad_s,
            &self.current_a,
            &self.voltage_v,
            &self.friction_torque_nm,
        ]
    }

    /// [`Trajectory::numeric_channels`], mutable.
    pub fn numeric_channels_mut(&mut self) -> [&mut Vec<f64>; 8] {
        [
            &mut self.time_s,
            &mut self.rotor_angle_rad,
            &mut self.rotor_speed_rad_s,
            &mut self.motor_angle_rad,
            &mut self.motor_speed_rad_s,
            &mut self.current_a,
            &mut self.voltage_v,
            &mut self.friction_torque_nm,
        ]
    }
}

//! The rig equations' piecewise-affine form, for the exact steps (module
//! `exact`): the regions where the right-hand side of [`System::rhs`] is
//! affine in the state, the switching functions between them, and the
//! matrix M of ż = M z inside one.

use super::{
    CUR, Drive, INT, MOTOR_FRICTION_SATURATED, MOTOR_FRICTION_SPEED_RAD_S, Mode, PHI1, PHI2, Region, System, W1, W2,
};
use crate::dopri::Vector;
use crate::exact::{AUG, Mat, ONE, TIME};
use crate::friction::{RAD_S_TO_RPM, slip_mu_affine, thesis_segment};
use rig_types::{FrictionLaw, ModelKind};

impl System<'_> {
    /// The affine region of (mode, t, y), or `None` where the right-hand side
    /// is not affine there: effects or harmonic friction present (but for the
    /// friction extension's break-away terms alone, which leave the motion
    /// the plain model's and change only the stick mode's event, and for
    /// effects through the contact alone while the brake is open,
    /// [`System::open_contact_only`]), the Stribeck
    /// law in slip, the rig model's motor friction off its saturated branch
    /// (|n Ω2| < [`MOTOR_FRICTION_SATURATED`] rad/s), the thermal state.
    #[inline(always)]
    pub fn region(&self, mode: Mode, t: f64, y: &Vector) -> Option<Region> {
        if !(self.plain || self.static_extension_only || self.open_contact_only)
            || !self.linear_shaft
            || self.fade.is_some()
            || self.current_limit_a.is_some()
        {
            return None;
        }
        let (saturation, ramping) = match self.drive {
            Drive::Voltage { .. } => (0, false),
            Drive::Pi { .. } => {
                let d = &self.p.drive;
                let raw = self.pi_raw(t, y).1;
                let sat = if raw > d.limit_v {
                    1
                } else if raw < -d.limit_v {
                    -1
                } else {
                    0
                };
                (sat, self.ramping(t))
            }
        };
        let motor_friction = match self.kind {
            ModelKind::Thesis => 0,
            ModelKind::Rig => {
                let x = self.gear * y[W2] / MOTOR_FRICTION_SPEED_RAD_S;
                if x.abs() < MOTOR_FRICTION_SATURATED {
                    return None;
                }
                x.signum() as i8
            }
        };
        let (friction_segment, friction_sign) = match (self.kind, mode) {
            _ if !self.brake_closed() => (0, 0),
            (ModelKind::Rig, Mode::Stick | Mode::Continuous) => (0, 0),
            (ModelKind::Rig, Mode::Slip { sign }) => (slip_mu_affine(&self.p.friction, y[W1].abs())?.0, sign as i8),
            (ModelKind::Thesis, _) => match &self.p.friction {
                FrictionLaw::Thesis(f) => (thesis_segment(f, y[W1]).0, 0),
                law if y[W1] != 0.0 => (slip_mu_affine(law, y[W1].abs())?.0, y[W1].signum() as i8),
                _ => return None,
            },
        };
        Some(Region { mode, saturation, motor_friction, friction_segment, friction_sign, ramping })
    }

    /// Switching functions of the piecewise-affine right-hand side: where one
    /// changes sign (> 0 against ≤ 0) the region changes with a kink (voltage
    /// clamp at ±limit; the segment ends of the friction lookup). Unused slots
    /// are 1. The motor friction's saturation is not a kink (tanh is smooth)
    /// and is not listed.
    pub fn switching(&self, mode: Mode, t: f64, y: &Vector) -> [f64; 5] {
        let mut s = [1.0; 5];
        if let Drive::Pi { .. } = self.drive {
            let d = &self.p.drive;
            let raw = self.pi_raw(t, y).1;
            s[0] = raw - d.limit_v;
            s[1] = raw + d.limit_v;
        }
        if !self.brake_closed() {
            return s;
        }
        // The conversion thesis_segment uses, so that the signs agree with its segments.
        let rpm = y[W1] * RAD_S_TO_RPM;
        match (self.kind, mode, &self.p.friction) {
            // Segment ends of the thesis lookup: 0, the static and the dynamic set-point.
            (ModelKind::Thesis, _, FrictionLaw::Thesis(f)) => {
                s[2] = rpm;
                s[3] = rpm - f.static_setpoint_rpm;
                s[4] = rpm - f.dynamic_setpoint_rpm;
            }
            // A symmetric law in the thesis model switches with the sign of Ω1.
            (ModelKind::Thesis, _, _) => s[2] = rpm,
            // The thesis lookup at |Ω1| in rig-model slip (Ω1 = 0 is the slip event).
            (ModelKind::Rig, Mode::Slip { .. }, FrictionLaw::Thesis(f)) => {
                s[3] = rpm.abs() - f.static_setpoint_rpm;
                s[4] = rpm.abs() - f.dynamic_setpoint_rpm;
            }
            _ => {}
        }
        s
    }

    /// M of ż = M z, z = [φ1 φ2 Ω1 Ω2 i ∫e t 1], in `region`: the terms of
    /// [`System::rhs`] with every switch fixed by the region (the unit test
    /// `affine_matrix_reproduces_rhs_and_output_shortcuts_are_exact` holds the two to the same equations).
    /// `y` is any state of the region (it fixes the friction segment).
    pub fn affine_matrix(&self, r: &Region, y: &Vector) -> Mat {
        let p = self.p;
        let m = &p.motor;
        let mut a = [[0.0; AUG]; AUG];
        // dt/dt = 1, d1/dt = 0.
        a[TIME][ONE] = 1.0;
        // Reference r(t) = r1 t + r0 and the error e = r − Ω2, as a row over z.
        let mut e = [0.0; AUG];
        e[W2] = -1.0;
        match self.drive {
            Drive::Voltage { voltage_v } => {
                // V constant, the PI integral frozen.
                a[CUR][ONE] = voltage_v * self.inv_inductance;
            }
            Drive::Pi { setpoint_rad_s, ramp_s, t_start_s } => {
                if r.ramping {
                    e[TIME] = setpoint_rad_s / ramp_s;
                    e[ONE] = -setpoint_rad_s * t_start_s / ramp_s;
                } else {
                    e[ONE] = setpoint_rad_s;
                }
                let d = &p.drive;
                // V = kp e + ki ∫e (linear) or ±limit (clamped); d∫e/dt = e + (V − raw)/(ki T_t).
                let mut raw = e.map(|x| d.kp_v_s_rad * x);
                raw[INT] += d.ki_v_rad;
                let v = if r.saturation == 0 {
                    raw
                } else {
                    let mut v = [0.0; AUG];
                    v[ONE] = f64::from(r.saturation) * d.limit_v;
                    v
                };
                for j in 0..AUG {
                    a[INT][j] = if d.ki_v_rad == 0.0 { e[j] } else { e[j] + (v[j] - raw[j]) * self.inv_ki_tracking };
                    a[CUR][j] = v[j] * self.inv_inductance;
                }
            }
        }
        // Eq. 4-6a: L di/dt = V − R i − n k_e Ω2.
        a[CUR][CUR] -= m.resistance_ohm * self.inv_inductance;
        a[CUR][W2] -= self.ke_shaft * self.inv_inductance;
        // Shaft torque T_s as a row over z.
        let mut ts = [0.0; AUG];
        ts[PHI2] = p.shaft_stiffness_nm_rad;
        ts[PHI1] = -p.shaft_stiffness_nm_rad;
        if self.kind == ModelKind::Rig {
            ts[W2] = p.shaft_damping_nm_s_rad;
            ts[W1] = -p.shaft_damping_nm_s_rad;
        }
        // Eq. 4-7 second row: n² J_m Ω̇2 = n(k_T i − T_f) − n² C_m Ω2 − T_s.
        let tf = match self.kind {
            ModelKind::Thesis => m.friction_torque_nm,
            ModelKind::Rig => m.friction_torque_nm * f64::from(r.motor_friction),
        };
        a[PHI2][W2] = 1.0;
        for j in 0..AUG {
            a[W2][j] = -ts[j] * self.inv_j_motor;
        }
        a[W2][CUR] += self.gear * m.torque_constant_nm_a * self.inv_j_motor;
        a[W2][W2] -= self.cm_shaft * self.inv_j_motor;
        a[W2][ONE] -= self.gear * tf * self.inv_j_motor;
        if r.mode == Mode::Stick {
            return a;
        }
        // Eq. 4-7 first row: J1 Ω̇1 = T_s − C Ω1 (thesis) − T1, T1 = f0 + f1 Ω1 in the segment.
        let nr = self.n0 * p.brake_disc_radius_m;
        let (f0, f1) = match (self.kind, r.mode) {
            _ if !self.brake_closed() => (0.0, 0.0),
            (ModelKind::Rig, Mode::Slip { sign }) => {
                let (_, mu0, mu1) = slip_mu_affine(&p.friction, y[W1].abs()).expect("region holds an affine law");
                (sign * mu0 * nr, mu1 * nr)
            }
            (ModelKind::Rig, _) => (0.0, 0.0),
            (ModelKind::Thesis, _) => match &p.friction {
                FrictionLaw::Thesis(f) => {
                    let (_, mu0, mu1) = thesis_segment(f, y[W1]);
                    (mu0 * nr, mu1 * nr)
                }
                law => {
                    let (_, mu0, mu1) = slip_mu_affine(law, y[W1].abs()).expect("region holds an affine law");
                    (f64::from(r.friction_sign) * mu0 * nr, mu1 * nr)
                }
            },
        };
        let absolute_damping =
            p.rotor_damping_nm_s_rad + if self.kind == ModelKind::Thesis { p.shaft_damping_nm_s_rad } else { 0.0 };
        a[PHI1][W1] = 1.0;
        for j in 0..AUG {
            a[W1][j] = ts[j] * self.inv_j1;
        }
        a[W1][W1] -= (absolute_damping + f1) * self.inv_j1;
        a[W1][ONE] -= f0 * self.inv_j1;
        a
    }
}

#[cfg(test)]
mod tests {
    use super::super::VoltageIn;
    use super::*;
    use rig_types::{DriveParams, MotorParams, RigParams};

    fn params(kind: ModelKind, friction: FrictionLaw) -> RigParams {
        RigParams {
            kind,
            rotor_inertia_kgm2: 0.0298,
            shaft_stiffness_nm_rad: 0.271,
            shaft_damping_nm_s_rad: 0.0176,
            rotor_damping_nm_s_rad: 0.0,
            motor: MotorParams {
                inertia_kgm2: 4.698e-4,
                inductance_h: 8.437e-4,
                resistance_ohm: 0.526,
                torque_constant_nm_a: 0.126,
                voltage_constant_v_s_rad: 0.0588,
                friction_torque_nm: 0.1,
                speed_regulation_nm_s_rad: 1.784e-4,
                gear_ratio: if kind == ModelKind::Rig { 8.0 } else { 1.0 },
            },
            drive: DriveParams { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 24.0 },
            friction,
            brake_disc_radius_m: 0.062,
            effects: vec![],
            harmonic: None,
        }
    }

    /// The affine form M z of every region equals rhs() at states spread over
    /// the region (all switches, both kinds, every affine law, ramp and hold):
    /// the exact propagator integrates the same equations as Dormand–Prince.
    #[test]
    fn affine_matrix_reproduces_rhs_and_output_shortcuts_are_exact() {
        let thesis = crate::friction::tests::table_4_7();
        let laws = [
            FrictionLaw::Coulomb { mu_static: 0.5, mu_kinetic: 0.35 },
            FrictionLaw::Viscous { mu_static: 0.5, mu_kinetic: 0.3, viscous_per_rad_s: 0.02 },
            FrictionLaw::Thesis(thesis),
        ];
        let mut checked = 0;
        let mut regions = Vec::new();
        let mut constant_friction = Vec::new();
        for kind in [ModelKind::Rig, ModelKind::Thesis] {
            for law in &laws {
                let p = params(kind, law.clone());
                for drive in [
                    Drive::Pi { setpoint_rad_s: 4.2, ramp_s: 2.0, t_start_s: 0.5 },
                    Drive::Pi { setpoint_rad_s: -3.0, ramp_s: 0.0, t_start_s: 0.0 },
                    Drive::Voltage { voltage_v: 7.0 },
                ] {
                    for n0 in [0.0, 15.0] {
                        let sys = System::new(&p, drive, n0);
                        for k in 0..400u32 {
                            // A deterministic spread of states: speeds through every lookup
                            // segment and both signs, integrals through both clamps.
                            let x = f64::from(k);
                            let w1 =
                                [0.0, 0.003, -0.02, 0.02, 0.3, -1.5][k as usize % 6] * (1.0 + 0.1 * (x * 0.37).sin());
                            let y = [
                                0.3 * (x * 1.3).sin(),
                                0.5 + 0.4 * (x * 0.7).cos(),
                                w1,
                                if k % 3 == 0 { -2.5 } else { 2.5 + 2.0 * (x * 0.9).sin() },
                                2.0 * (x * 0.51).cos(),
                                4.0 * (x * 0.23).sin(),
                                0.0,
                            ];
                            let t = 0.5 + 3.0 * (x * 0.11).sin().abs();
                            for mode in
                                [Mode::Continuous, Mode::Stick, Mode::Slip { sign: 1.0 }, Mode::Slip { sign: -1.0 }]
                            {
                                let legal = match (kind, mode) {
                                    (ModelKind::Thesis, Mode::Continuous) => true,
                                    (ModelKind::Thesis, _) => false,
                                    (_, Mode::Continuous) => n0 == 0.0,
                                    (_, Mode::Stick) => n0 > 0.0 && w1 == 0.0,
                                    (_, Mode::Slip { sign }) => n0 > 0.0 && sign * w1 >= 0.0,
                                };
                                let Some(r) = sys.region(mode, t, &y).filter(|_| legal) else { continue };
                                let y = if mode == Mode::Stick { [0.0, y[1], 0.0, y[3], y[4], y[5], 0.0] } else { y };
                                let m = sys.affine_matrix(&r, &y);
                                let mut z = [0.0; AUG];
                                z[..6].copy_from_slice(&y[..6]);
                                (z[TIME], z[ONE]) = (t, 1.0);
                                let f = sys.rhs(mode, t, &y);
                                let f = [f[0], f[1], f[2], f[3], f[4], f[5], 1.0, 0.0];
                                for i in 0..AUG {
                                    let mz: f64 = (0..AUG).map(|j| m[i][j] * z[j]).sum();
                                    let scale: f64 = (0..AUG).map(|j| (m[i][j] * z[j]).abs()).sum::<f64>().max(1e-300);
                                    assert!(
                                        (mz - f[i]).abs() <= 1e-12 * scale,
                                        "{kind:?} {law:?} {drive:?} N {n0} {mode:?} {r:?} row {i}: {mz} vs {}",
                                        f[i]
                                    );
                                }
                                // The output shortcuts of the exact path give the same bits.
                                let v = sys.voltage(t, &y).0;
                                match sys.voltage_in(&r) {
                                    VoltageIn::Constant(c) => assert_eq!(v.to_bits(), c.to_bits(), "{r:?}"),
                                    VoltageIn::Unclamped => {
                                        assert_eq!(
                                            v.to_bits(),
                                            sys.pi_unclamped_of_v(sys.reference_rad_s(t), y[W2], y[INT]).to_bits(),
                                            "{r:?}"
                                        )
                                    }
                                }
                                if sys.friction_torque_constant_in(&r) {
                                    let f = sys.friction_torque_nm(mode, t, &y);
                                    let key = (kind, law.clone(), drive, n0.to_bits(), r);
                                    match constant_friction.iter().find(|(k, _)| *k == key) {
                                        Some((_, f0)) => assert_eq!(f.to_bits(), f64::to_bits(*f0), "{key:?}"),
                                        None => constant_friction.push((key, f)),
                                    }
                                }
                                if !regions.contains(&r) {
                                    regions.push(r);
                                }
                                checked += 1;
                            }
                        }
                    }
                }
            }
        }
        // Constant friction was checked across states of one region, on both kinds.
        assert!(constant_friction.len() > 20, "{}", constant_friction.len());
        // Every kind of switch was visited: clamps, motor friction signs, lookup segments, the ramp.
        assert!(checked > 2000, "{checked}");
        for probe in [
            |r: &Region| r.saturation == 1,
            |r: &Region| r.saturation == -1,
            |r: &Region| r.motor_friction == -1,
            |r: &Region| r.friction_segment == 1,
            |r: &Region| r.friction_segment == 2,
            |r: &Region| r.friction_segment == 3,
            |r: &Region| r.friction_sign == -1,
            |r: &Region| r.ramping,
            |r: &Region| r.mode == Mode::Stick,
        ] {
            assert!(regions.iter().any(probe), "{regions:?}");
        }
    }
}

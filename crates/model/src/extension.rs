//! The diagnosis' data-driven friction extension ([`rig_types::Effect::FrictionExtension`]):
//! the library of state and history signals the simulator carries for it, and
//! the factors it applies to the slip and break-away friction coefficients.
//!
//! # The signal library (what the physics of a dry contact suggests)
//!
//! | signal | symbol | acts on | physics |
//! |---|---|---|---|
//! | `slip_speed_rad_s` | \|Ω1\| | μ in slip, × (1 + a_v \|Ω1\|) | rate dependence the vocabulary's Stribeck and viscous laws do not have (lubricant film, flash heating) |
//! | `breakaway_transient` | exp(−t_slip/τ_b) | μ in slip, × (1 + a_b e^{−t_slip/τ_b}) | a friction memory after break-away: the contact's state relaxes over τ_b (rate-and-state friction, Rice & Ruina 1983, in its time form) |
//! | `static_level` | 1 | μs, × (1 + c_0) | the break-away level itself: a static coefficient off the calibrated one |
//! | `log_dwell` | ln(1 + t_stick/τ_d) | μs, × (1 + c_d ln(1 + t_stick/τ_d)) | contact ageing: the real contact area creeps under load while stuck (Dieterich 1972, Rabinowicz 1958) |
//!
//! t_slip, the time since the last break-away, and t_stick, the age of the
//! stuck contact, are one state: the model's seventh state (the pad state of
//! `BrakeFade` / `StaticFrictionAging`, which the extension cannot be combined
//! with), growing at the rate of time in both modes and reset to 0 at every
//! stick/slip event. τ_b = [`BREAKAWAY_TIME_S`], τ_d = [`DWELL_TIME_S`] are
//! fixed (the library's scales, not fitted), so every coefficient enters the
//! friction linearly and can be fitted by least squares.
//!
//! Heat (friction power integrated with a decay) and slid distance (wear,
//! run-in) would need further states; the pad state carries one. Both are in
//! the virtual rig's effects outside the vocabulary (`BrakeFade`); the
//! diagnosis' residual signature (teacher-forced) still names slid angle and
//! friction power when the residual follows them.

use rig_types::Effect;

/// τ_b of the break-away transient, s: a fraction of the shortest stick-slip
/// period the rig shows (2-6 s), long against the differentiator's ±20 ms.
pub const BREAKAWAY_TIME_S: f64 = 0.25;

/// τ_d of the dwell-time logarithm, s (the ageing law's cut-off time; the
/// virtual rig's ageing draws τ in 0.05-0.5 s, this is the library's own choice).
pub const DWELL_TIME_S: f64 = 0.1;

/// The extension's coefficients, summed over every `FrictionExtension` of a model.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Extension {
    pub slip_speed_per_rad_s: f64,
    pub breakaway_transient: f64,
    pub static_level: f64,
    pub dwell_per_efold: f64,
}

impl Extension {
    /// The extension of `effects`, `None` without one.
    pub fn of(effects: &[Effect]) -> Option<Self> {
        let mut out = None;
        for e in effects {
            if let Effect::FrictionExtension {
                slip_speed_per_rad_s,
                breakaway_transient,
                static_level,
                dwell_per_efold,
            } = *e
            {
                let x: &mut Extension = out.get_or_insert_with(Extension::default);
                x.slip_speed_per_rad_s += slip_speed_per_rad_s;
                x.breakaway_transient += breakaway_transient;
                x.static_level += static_level;
                x.dwell_per_efold += dwell_per_efold;
            }
        }
        out
    }

    /// Factor on the slip coefficient at slip speed |Ω1| and `age_s` since
    /// break-away (never below 0: friction does not push).
    ///
    /// A zero `breakaway_transient` skips its `exp`: the term is then 0 × a
    /// number in (0, 1], ±0, and adding ±0 to 1 + a_v|Ω1| (never −0) leaves
    /// it, so the factor is the same to the bit (the ageing law's free-run
    /// fit, whose slip coefficients are 0, evaluates it on every slip
    /// right-hand side).
    #[inline]
    pub fn slip_factor(&self, speed_abs_rad_s: f64, age_s: f64) -> f64 {
        let speed = 1.0 + self.slip_speed_per_rad_s * speed_abs_rad_s;
        if self.breakaway_transient == 0.0 {
            return speed.max(0.0);
        }
        (speed + self.breakaway_transient * (-age_s.max(0.0) / BREAKAWAY_TIME_S).exp()).max(0.0)
    }

    /// Factor on the static coefficient after `age_s` stuck (never below 0).
    #[inline]
    pub fn static_factor(&self, age_s: f64) -> f64 {
        (1.0 + self.static_level + self.dwell_per_efold * (age_s.max(0.0) / DWELL_TIME_S).ln_1p()).max(0.0)
    }
}

/// The library's signals at one state, in the order of the module's table:
/// what a fit regresses the relative friction error on (slip signals for a
/// slip sample, static signals for a break-away).
pub fn slip_signals(speed_abs_rad_s: f64, since_breakaway_s: f64) -> [f64; 2] {
    [speed_abs_rad_s, (-since_breakaway_s.max(0.0) / BREAKAWAY_TIME_S).exp()]
}

/// [`slip_signals`]' counterpart for a break-away after `dwell_s` stuck.
pub fn static_signals(dwell_s: f64) -> [f64; 2] {
    [1.0, (dwell_s.max(0.0) / DWELL_TIME_S).ln_1p()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_coefficients_leave_friction_alone_and_signals_match_the_factors() {
        let e = Extension::of(&[Effect::FrictionExtension {
            slip_speed_per_rad_s: 0.0,
            breakaway_transient: 0.0,
            static_level: 0.0,
            dwell_per_efold: 0.0,
        }])
        .expect("extension");
        assert_eq!(e.slip_factor(3.0, 0.1), 1.0);
        assert_eq!(e.static_factor(2.0), 1.0);
        let e = Extension {
            slip_speed_per_rad_s: 0.01,
            breakaway_transient: 0.2,
            static_level: 0.1,
            dwell_per_efold: 0.03,
        };
        let s = slip_signals(2.0, 0.5);
        assert!((e.slip_factor(2.0, 0.5) - (1.0 + 0.01 * s[0] + 0.2 * s[1])).abs() < 1e-15);
        let d = static_signals(1.0);
        assert!((e.static_factor(1.0) - (1.0 + 0.1 * d[0] + 0.03 * d[1])).abs() < 1e-15);
        assert!(Extension::of(&[]).is_none());
    }
}

//! From one `operating_point` recording to the signals the diagnosis compares:
//! encoder angles and zero-lag speeds, calibrated friction force, the PI
//! reference, the usable slip samples and the sensor noise measured in the data.

use crate::{DiagnoseError, DiagnoseOptions};
use rig_types::sensor::{force_n, half_window_samples, ticks_to_rad};
use rig_types::{Campaign, Run, RunKind};

/// Force-sensor calibration used to turn mV into N (the sensor model's, one definition).
pub use rig_types::sensor::ForceCal;

/// One operating-point run as the diagnosis sees it. All vectors have `time_s.len()` entries.
#[derive(Debug, Clone)]
pub struct RunSignals {
    pub id: String,
    /// The cross-validation fold in which this run is held out.
    pub fold: usize,
    pub setpoint_rad_s: f64,
    pub normal_force_n: f64,
    pub ramp_s: f64,
    pub time_s: Vec<f64>,
    pub rotor_angle_rad: Vec<f64>,
    pub rotor_speed_rad_s: Vec<f64>,
    pub motor_angle_rad: Vec<f64>,
    pub motor_speed_rad_s: Vec<f64>,
    pub voltage_v: Vec<f64>,
    /// Calibrated friction force on the pads, N (positive opposes positive Ω1).
    pub friction_force_n: Vec<f64>,
    /// Samples where rotor 1 certainly slips (speed above threshold, no stuck
    /// sample within the speed window): the friction there is μ·N, not a reaction.
    pub slip_idx: Vec<usize>,
    /// Observed friction coefficient sign(Ω1)·F/N0 at `slip_idx` (empty when N0 = 0).
    pub mu_obs: Vec<f64>,
    /// White sensor noise (standard deviation) of the force and voltage channels,
    /// from first differences: σ² = var(x[k+1] − x[k]) / 2 (smooth signal at 500 Hz).
    pub force_noise_n: f64,
    pub voltage_noise_v: f64,
    /// First sample of the steady state (after ramp + settle time).
    pub steady_from: usize,
    /// The drive fits' closed form of this run's PI recursion
    /// ([`crate::drive::Prepared`]), built on the first fit that reads the
    /// run and shared by every fold and selection step after it: the fields
    /// above must not change once a drive fit has read them (`Default` for a
    /// run built by hand).
    pub drive: std::sync::OnceLock<crate::drive::Prepared>,
}

impl RunSignals {
    /// PI reference: linear ramp 0 → set-point over `ramp_s` (recording-format.md protocol).
    pub fn reference_rad_s(&self, t_s: f64) -> f64 {
        if self.ramp_s <= 0.0 { self.setpoint_rad_s } else { self.setpoint_rad_s * (t_s / self.ramp_s).min(1.0) }
    }
}

/// Zero-lag speed from cumulative angle: the plain centred difference of
/// the sensor model (`rig_types::sensor`, one definition), under the name the
/// diagnosis's modules use.
pub use rig_types::sensor::central_difference_rad_s as centred_speed;

/// Noise standard deviation of a smooth signal plus white noise, from first differences.
/// The median absolute difference (scaled for a Gaussian) keeps rare jumps
/// (stick/slip transitions) from inflating it.
pub fn diff_noise(x: &[f64]) -> f64 {
    if x.len() < 3 {
        return 0.0;
    }
    let mut d: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    // The element a sort by `total_cmp` puts at the middle, found in linear
    // time (the same value, bit for bit; the full sort of every run's 20 000
    // differences was 7 % of a battery campaign's diagnosis in `perf`).
    let mid = d.len() / 2;
    let (_, &mut med, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    // For d ~ N(0, 2σ²): median |d| = 0.6745·√2·σ.
    med / (0.6745 * std::f64::consts::SQRT_2)
}

/// Stratified folds: the runs ranked by (set-point, normal force, campaign
/// order) and dealt round-robin, so runs of one condition (the highest set
/// speed, say) land in different folds and every condition is in training
/// and test sets alike.
pub fn stratified_folds(conditions: &[(f64, f64)], folds: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..conditions.len()).collect();
    order.sort_by(|&a, &b| {
        conditions[a].0.total_cmp(&conditions[b].0).then(conditions[a].1.total_cmp(&conditions[b].1)).then(a.cmp(&b))
    });
    let mut fold = vec![0; conditions.len()];
    for (rank, &i) in order.iter().enumerate() {
        fold[i] = rank % folds.max(1);
    }
    fold
}

/// Builds the signals of every operating-point run (campaign order), each
/// with its cross-validation fold ([`stratified_folds`]).
/// How the force sensor's mV are read as newtons.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorLaw {
    /// The calibration line (rig-calibrate; thesis §4.1).
    Line(ForceCal),
    /// mV = a + b·F + c·F² ([`crate::channels::force_parabola`]), used when the
    /// force-sensor linearity check rejects the line: F is the root of the
    /// parabola on the branch through the calibration loads.
    Parabola([f64; 3]),
}

impl SensorLaw {
    pub fn force_n(&self, mv: &[f64]) -> Vec<f64> {
        match *self {
            SensorLaw::Line(cal) => force_n(mv, cal),
            SensorLaw::Parabola(abc) => rig_types::sensor::force_n_parabola(mv, abc),
        }
    }
}

/// Whether `run` is an operating point with the brake open
/// (`normal_force_n = 0`, which `rig-campaign/1` allows): its force channel
/// gives no friction coefficient (Eq. 4-10: μ = F/N has no N), so it has no
/// slip samples and no per-run friction parameter (a modulation's phase) can
/// be fitted on it.
pub fn brake_open(run: &Run) -> bool {
    matches!(run.kind, RunKind::OperatingPoint { normal_force_n, .. } if normal_force_n <= 0.0)
}

/// The signals of `c`'s operating points with the brake applied, in campaign
/// order, with their folds: the friction selection's units
/// ([`PreparedRuns::friction_units`] of [`prepare_units`], which also keeps
/// the runs with the brake open for the drive channel).
pub fn prepare_runs(c: &Campaign, cal: SensorLaw, opts: &DiagnoseOptions) -> Result<Vec<RunSignals>, DiagnoseError> {
    prepare_of(c, cal, opts, |r| !brake_open(r), None)
}

/// Every operating point of a campaign as the diagnosis' channels read it,
/// split by what each channel can learn from a run (the one home of that
/// rule). The runs with the brake applied come first, in campaign order,
/// with the folds [`prepare_runs`] gives them; the runs with the brake open
/// ([`brake_open`]) follow, in campaign order, dealt over the same number
/// of folds by the same stratification among themselves (so a fold's
/// held-out drive runs include open ones when there are enough).
///
/// - **Friction** ([`PreparedRuns::friction_units`]): the braked runs. A run
///   with the brake open has no friction coefficient (Eq. 4-10: μ = F/N has
///   no N), so no slip sample, no per-run phase, no break-away; the friction
///   fits, the selection's units and folds, the slip-force and break-away
///   checks and the extension read only these.
/// - **Drive** ([`PreparedRuns::drive_units`]): every operating point. The
///   teacher-forced PI loop (`drive`: V = clamp(kp·e + ki·∫e, ±Vmax), e =
///   Ω_ref − Ω2, rig-model's drive; the thesis names the loop in §4.1) reads
///   only the reference, the measured motor speed and the voltage, none of
///   which needs the brake: a run with the brake open is the motor under its
///   loop turning an unloaded rotor, the cleanest look the campaign has at
///   the drive.
#[derive(Debug, Clone)]
pub struct PreparedRuns {
    runs: Vec<RunSignals>,
    braked: usize,
}

impl PreparedRuns {
    /// The friction channel's runs (the brake applied, campaign order): the
    /// forward selection's units.
    pub fn friction_units(&self) -> &[RunSignals] {
        &self.runs[..self.braked]
    }

    /// The drive channel's runs: [`PreparedRuns::friction_units`] first,
    /// then the runs with the brake open.
    pub fn drive_units(&self) -> &[RunSignals] {
        &self.runs
    }

    /// The runs with the brake open alone (campaign order).
    pub fn brake_open_units(&self) -> &[RunSignals] {
        &self.runs[self.braked..]
    }
}

/// Every operating point of `c` prepared ([`PreparedRuns`]).
pub fn prepare_units(c: &Campaign, cal: SensorLaw, opts: &DiagnoseOptions) -> Result<PreparedRuns, DiagnoseError> {
    let mut runs = prepare_runs(c, cal, opts)?;
    let braked = runs.len();
    runs.extend(prepare_of(c, cal, opts, brake_open, Some(opts.folds.min(braked)))?);
    Ok(PreparedRuns { runs, braked })
}

/// The signals of `c`'s operating points that `keep`, in campaign order,
/// dealt over `folds` (default: `opts.folds`, at most one per run) by
/// [`stratified_folds`].
fn prepare_of(
    c: &Campaign,
    cal: SensorLaw,
    opts: &DiagnoseOptions,
    keep: impl Fn(&Run) -> bool,
    folds: Option<usize>,
) -> Result<Vec<RunSignals>, DiagnoseError> {
    let ops: Vec<&Run> = c.runs_of("operating_point").filter(|r| keep(r)).collect();
    let conditions: Vec<(f64, f64)> = ops
        .iter()
        .map(|r| match r.kind {
            RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, .. } => (motor_rpm_setpoint, normal_force_n),
            _ => (0.0, 0.0),
        })
        .collect();
    let folds = stratified_folds(&conditions, folds.unwrap_or(opts.folds).min(ops.len()));
    let mut out = Vec::with_capacity(ops.len());
    for (i, run) in ops.iter().enumerate() {
        out.push(prepare_run(c, run, cal, folds[i], opts)?);
    }
    Ok(out)
}

fn column<'a, T>(run: &'a Run, col: &'static str, v: &'a Option<Vec<T>>) -> Result<&'a Vec<T>, DiagnoseError> {
    v.as_ref().ok_or_else(|| DiagnoseError::MissingColumn { run: run.id.clone(), column: col })
}

fn prepare_run(
    c: &Campaign,
    run: &Run,
    cal: SensorLaw,
    fold: usize,
    opts: &DiagnoseOptions,
) -> Result<RunSignals, DiagnoseError> {
    let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else {
        unreachable!("prepare_run is only called on operating points")
    };
    let d = &run.data;
    let t = d.time_s.clone();
    let tpr = c.rig.encoder_ticks_per_rev;
    let phi1 = ticks_to_rad(column(run, "rotor_ticks", &d.rotor_ticks)?, tpr);
    let phi2 = ticks_to_rad(column(run, "motor_ticks", &d.motor_ticks)?, tpr);
    let volt = column(run, "motor_voltage_v", &d.motor_voltage_v)?.clone();
    let mv = column(run, "brake_force_mv", &d.brake_force_mv)?;
    let force = cal.force_n(mv);
    let h = half_window_samples(&t, opts.rotor_speed_half_window_s);
    let w1 = centred_speed(&t, &phi1, h);
    let w2 = centred_speed(&t, &phi2, half_window_samples(&t, opts.motor_speed_half_window_s));

    // Stuck detection on the raw encoder: no tick change across ±half samples.
    let n = t.len();
    let ticks = d.rotor_ticks.as_ref().expect("checked above");
    let moved: Vec<bool> = (0..n).map(|k| ticks[(k + h).min(n - 1)] != ticks[k.saturating_sub(h)]).collect();
    let mut slip_idx = Vec::new();
    let mut mu_obs = Vec::new();
    let guard = 2 * h;
    let start = opts.skip_start_s;
    let mut last_stuck: Option<usize> = None;
    let mut next_stuck = vec![usize::MAX; n];
    for k in (0..n).rev() {
        next_stuck[k] = if !moved[k] {
            k
        } else if k + 1 < n {
            next_stuck[k + 1]
        } else {
            usize::MAX
        };
    }
    for k in 0..n {
        if !moved[k] {
            last_stuck = Some(k);
            continue;
        }
        let far_prev = last_stuck.is_none_or(|s| k - s > guard);
        let far_next = next_stuck[k] == usize::MAX || next_stuck[k] - k > guard;
        if t[k] >= start && far_prev && far_next && w1[k].abs() >= opts.slip_speed_rad_s && normal_force_n > 0.0 {
            slip_idx.push(k);
            mu_obs.push(w1[k].signum() * force[k] / normal_force_n);
        }
    }
    let steady_from = t.partition_point(|&x| x < ramp_s + opts.settle_s);
    Ok(RunSignals {
        id: run.id.clone(),
        fold,
        setpoint_rad_s: rig_types::units::rpm_to_rad_s(motor_rpm_setpoint),
        normal_force_n,
        ramp_s,
        force_noise_n: diff_noise(&force),
        voltage_noise_v: diff_noise(&volt),
        time_s: t,
        rotor_angle_rad: phi1,
        rotor_speed_rad_s: w1,
        motor_angle_rad: phi2,
        motor_speed_rad_s: w2,
        voltage_v: volt,
        friction_force_n: force,
        slip_idx,
        mu_obs,
        steady_from,
        drive: Default::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folds_split_each_condition() {
        // Three runs at the top speed land in three different folds.
        let c = [(130.0, 4.0), (20.0, 1.0), (130.0, 10.0), (45.0, 1.0), (130.0, 25.0), (20.0, 4.0)];
        let f = stratified_folds(&c, 3);
        assert_ne!(f[0], f[2]);
        assert_ne!(f[2], f[4]);
        assert_ne!(f[0], f[4]);
        for k in 0..3 {
            assert_eq!(f.iter().filter(|&&x| x == k).count(), 2);
        }
    }

    #[test]
    fn diff_noise_recovers_sigma_on_a_smooth_signal() {
        // Deterministic pseudo-noise (LCG) with known σ on a slow sine.
        let mut s: u64 = 12345;
        let mut g = || {
            // Sum of 12 uniforms − 6 ≈ N(0,1).
            let mut acc = 0.0;
            for _ in 0..12 {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                acc += (s >> 11) as f64 / (1u64 << 53) as f64;
            }
            acc - 6.0
        };
        let x: Vec<f64> = (0..20000).map(|k| (k as f64 * 0.001).sin() + 0.05 * g()).collect();
        let sd = diff_noise(&x);
        assert!((sd - 0.05).abs() < 0.003, "σ = {sd}");
    }
}

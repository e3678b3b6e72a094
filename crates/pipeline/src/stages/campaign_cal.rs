//! Stage `campaign-calibration`: force-sensor factor and offset, static
//! stiffness, and the free decay of every voltage step (δ, ξ, ω_d, ω_n, J1)
//! from the campaign's calibration runs (rig_calibrate::calibrate_campaign).

use crate::StageCtx;
use anyhow::Result;
use rig_calibrate::{CalibrationSettings, calibrate_campaign_with, render};
use rig_types::sensor as signal;
use rig_types::{RunKind, SeriesStyle};

/// `[stage.params]` of `campaign-calibration`: the calibration's own settings.
pub type Params = CalibrationSettings;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let settings: Params = ctx.typed_params()?;
    let campaign = ctx.campaign()?.clone();
    let cal = calibrate_campaign_with(&campaign, &settings)?;

    ctx.write_table("tables/campaign-force-calibration.csv", &render::force_table(&cal))?;
    ctx.write_table("tables/campaign-stiffness.csv", &render::stiffness_table(&cal))?;
    ctx.write_table("tables/campaign-log-decrement.csv", &render::log_decrement_table(&cal))?;
    ctx.write_json("data/campaign-calibration.json", &cal)?;

    // Fig. 4.8: the step closest to the thesis' 8 V (first one on a tie, campaign order).
    let step = campaign
        .runs_of("voltage_step")
        .filter_map(|r| match r.kind {
            RunKind::VoltageStep { voltage_v } => Some((r, (voltage_v - 8.0).abs())),
            _ => None,
        })
        .fold(None, |best: Option<(&rig_types::Run, f64)>, (r, d)| match best {
            Some((_, bd)) if bd <= d => best,
            _ => Some((r, d)),
        })
        .map(|(r, _)| r);
    if let (Some(run), Some(dec)) = (step, step.and_then(|r| cal.steps.iter().find(|s| s.id == r.id))) {
        let tpr = campaign.rig.encoder_ticks_per_rev;
        let t = &run.data.time_s;
        let (rt, mt) = (run.data.rotor_ticks.as_deref().unwrap_or(&[]), run.data.motor_ticks.as_deref().unwrap_or(&[]));
        let w1 = signal::encoder_speed_rad_s(t, rt, tpr);
        let w2 = signal::encoder_speed_rad_s(t, mt, tpr);
        let twist_ticks: Vec<i64> = mt.iter().zip(rt).map(|(m, r)| m - r).collect();
        let twist = signal::ticks_to_rad(&twist_ticks, tpr);
        let speed_note = match &dec.rotor_speed {
            Some(a) => format!(
                "On the rotor speed itself the same method finds δ = {:.4} ± {:.4} over {} pairs (marked).",
                a.log_decrement_mean,
                a.log_decrement_std,
                a.pairs.len()
            ),
            None => "The rotor speed shows no swing above the 3 rad/s floor.".into(),
        };
        ctx.write_figure(&render::decay_figure(
            "fig-4-08-campaign",
            &format!("Fig. 4.8 (campaign): rotor speed after a {} V step, run {}", dec.voltage_v, dec.id),
            &format!(
                "Rotor-1 speed Ω1 and motor-side speed Ω2 from the encoders (central difference over ±20 ms, then a ±20 ms \
                 moving average: zero phase, ≈0.16 rad/s quantisation noise), decimated for plotting. The calibration uses the \
                 shaft twist φ2 − φ1 (fig-4-08-campaign-twist): δ = {:.4} ± {:.4} over {} peak pairs, ω_d = {:.4} rad/s. {}",
                dec.twist.log_decrement_mean,
                dec.twist.log_decrement_std,
                dec.twist.pairs.len(),
                dec.twist.damped_rad_s_mean,
                speed_note
            ),
            "speed [rad/s]",
            t,
            &[("rotor speed Ω1", &w1, SeriesStyle::Line), ("motor-side speed Ω2", &w2, SeriesStyle::Dashed)],
            dec.rotor_speed.as_ref(),
            3,
        ))?;
        ctx.write_figure(&render::decay_figure(
            "fig-4-08-campaign-twist",
            &format!("Shaft twist φ2 − φ1 after a {} V step, run {} (the log-decrement signal)", dec.voltage_v, dec.id),
            &format!(
                "Twist from the two encoders (ticks difference × 2π/1000), decimated for plotting; marked: the extrema of the \
                 pairs used (swings ≥ {} ticks, first {} extrema skipped as start-up). δ = {:.4} ± {:.4}, ξ = {:.5}, \
                 ω_d = {:.4} rad/s, ω_n = {:.4} rad/s, J1 = K/ω_n² = {:.5} kg·m² with K = {:.4} N·m/rad.",
                settings.twist_min_swing_ticks,
                settings.skip_extrema,
                dec.twist.log_decrement_mean,
                dec.twist.log_decrement_std,
                dec.twist.damping_ratio_mean,
                dec.twist.damped_rad_s_mean,
                dec.twist.natural_rad_s_mean,
                dec.rotor_inertia_kgm2,
                cal.stiffness_nm_rad
            ),
            "twist [rad]",
            t,
            &[("twist φ2 − φ1", &twist, SeriesStyle::Line)],
            Some(&dec.twist),
            4,
        ))?;
    }

    let k_points: Vec<(f64, f64)> = cal.twist_runs.iter().map(|r| (r.angle_rad, r.torque_nm)).collect();
    // The calibration's fits (two twist runs are enough for K; the offset fit
    // needs three, and with fewer the calibration repeats the origin fit).
    let k_origin = rig_calibrate::stats::fit_through_origin(
        &cal.twist_runs.iter().map(|r| r.angle_rad).collect::<Vec<_>>(),
        &cal.twist_runs.iter().map(|r| r.torque_nm).collect::<Vec<_>>(),
        settings.confidence,
    )?;
    let k_offset = cal.stiffness_with_offset.clone();
    let offset_note = if k_offset.through_origin {
        format!("; {} runs are too few for a line with an offset", k_points.len())
    } else {
        format!(" and with an offset (K = {:.4}, offset {:.5} N·m)", k_offset.slope, k_offset.intercept)
    };
    ctx.write_figure(&render::fit_figure(
        "fig-4-10-campaign",
        "Fig. 4.10 (campaign): torque vs rotor angle in the static twist runs",
        &format!(
            "Each point: a static_twist run's known torque against its mean rotor angle (ticks × 2π/1000). Lines: least \
             squares through the origin (K = {:.4} N·m/rad, {:.0} % CI {:.4} to {:.4}){offset_note}.",
            k_origin.slope, 100.0 * settings.confidence, k_origin.slope_ci[0], k_origin.slope_ci[1]
        ),
        ("angle [rad]", "torque [N·m]"),
        &k_points,
        (&k_origin, &k_offset),
        "K",
        (4, 4),
    ))?;
    let f_points: Vec<(f64, f64)> = cal.force_runs.iter().map(|r| (r.load_n, r.mean_mv)).collect();
    let (f_origin, f_offset) = rig_calibrate::thesis::fits(&f_points, settings.confidence)?;
    ctx.write_figure(&render::fit_figure(
        "fig-4-14-campaign",
        "Fig. 4.14 (campaign): force-sensor voltage vs load",
        &format!(
            "Each point: a force_calibration run's known load against its mean sensor voltage. Lines: least squares through \
             the origin ({:.3} mV/N) and with an offset ({:.3} mV/N, {:.0} % CI {:.3} to {:.3}; offset {:.3} ± {:.3} mV), the \
             calibration used to turn brake_force_mv into newtons.",
            f_origin.slope,
            f_offset.slope,
            100.0 * settings.confidence,
            f_offset.slope_ci[0],
            f_offset.slope_ci[1],
            f_offset.intercept,
            f_offset.intercept_stderr
        ),
        ("load [N]", "voltage [mV]"),
        &f_points,
        (&f_origin, &f_offset),
        "factor",
        (3, 3),
    ))?;
    Ok(())
}

//! The diagnosis' structural candidates (rig_diagnose::structure) on
//! campaigns whose damping placement is known: the rig's shaft damping moved
//! from the twist rate onto the absolute rotor speed (a drag on Ω1, the
//! rotor row of Eq. 4-7's diag(C, Cm), simulated by rig-model's
//! `rotor_damping_nm_s_rad`) is named `rotor_absolute` (or the placement that
//! contains it) with a free-run gain; the rig model's own placement keeps
//! `twist_rate`.

use rig_virtual_rig::{Protocol, draw_truth, generate};
use std::path::Path;

fn opts() -> rig_diagnose::DiagnoseOptions {
    rig_diagnose::DiagnoseOptions::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml")
}

fn thesis() -> rig_calibrate::ThesisData {
    let t = rig_ingest::thesis::read_thesis_tables(Path::new("../../data/thesis")).expect("data/thesis");
    rig_calibrate::thesis_data(&t).expect("thesis data")
}

/// The small protocol with two slow, heavily braked points (stick-slip).
fn protocol() -> Protocol {
    let mut p = Protocol::small();
    p.op_points[0] = (10.0, 10.0);
    p.op_points[4] = (20.0, 25.0);
    p
}

#[test]
fn damping_on_the_rotor_speed_is_named_with_its_free_run_gain() {
    let mut truth = draw_truth("none", 130.0, 4242);
    let c_nm_s_rad = truth.params.shaft_damping_nm_s_rad;
    truth.params.shaft_damping_nm_s_rad = 0.0;
    truth.params.rotor_damping_nm_s_rad = c_nm_s_rad;
    let c = generate("rotor-drag", &truth, &protocol(), 4242).expect("generate");
    let d = rig_diagnose::diagnose_campaign(&c, Some(&thesis()), &opts()).expect("diagnosis");
    println!("{}\n{:#?}", d.structure.notes, d.detail.structure_scores);
    assert!(
        d.structure.damping == "rotor_absolute" || d.structure.damping == "twist_rate_and_rotor",
        "structure {} ({})",
        d.structure.damping,
        d.structure.notes
    );
    let won = d.detail.structure_scores.iter().find(|s| s.accepted).expect("a winner");
    assert!(won.relative_gain >= 0.05 && won.t >= 2.0, "{won:?}");
    // The final model's free run is within its thresholds; what is left (if
    // anything) is the estimate's voltage-step fit, made in the twist-rate
    // placement, not the motion.
    let left: Vec<&str> = d.detail.free_run_extended.iter().filter(|k| k.flagged).map(|k| k.channel.as_str()).collect();
    assert!(left.is_empty(), "final model's free run flagged: {left:?}");
    assert!(d.findings.iter().all(|f| !f.where_.iter().any(|w| w == "free_run")), "{:?}", d.findings);
    let base_flags = d.detail.free_run_baseline.iter().filter(|k| k.flagged).count();
    assert!(base_flags > 0, "the baseline's free run should miss the rotor drag");
}

#[test]
fn the_rig_models_own_placement_keeps_twist_rate() {
    let truth = draw_truth("none", 130.0, 4243);
    let c = generate("twist-rate", &truth, &protocol(), 4243).expect("generate");
    let d = rig_diagnose::diagnose_campaign(&c, Some(&thesis()), &opts()).expect("diagnosis");
    println!("{}\n{:#?}", d.structure.notes, d.detail.structure_scores);
    assert_eq!(d.structure.damping, "twist_rate", "{}", d.structure.notes);
    assert_eq!(d.verdict, "none", "{:?}", d.findings.last().map(|f| &f.evidence));
}

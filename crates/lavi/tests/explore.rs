//! Developer aid (ignored): runs the study on ../shared and prints the numbers.

/// Run 175's path and the `lavi` stage's params of pipeline.toml.
fn setup() -> (std::path::PathBuf, rig_lavi::StudyParams) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/ufrj-lavi-2018/run-175.csv");
    let text =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../pipeline.toml")).unwrap();
    let v: toml::Value = toml::from_str(&text).unwrap();
    let st = v["stage"].as_array().unwrap().iter().find(|s| s["name"].as_str() == Some("lavi")).unwrap();
    let mut params = st["params"].clone();
    // `[shared.selection]` is merged into the stage's params by the pipeline's runner.
    params.as_table_mut().unwrap().insert("selection".into(), v["shared"]["selection"].clone());
    (path, params.try_into().unwrap())
}

#[test]
#[ignore]
fn explore() {
    let (path, p) = setup();
    let (s, _, _) = rig_lavi::study::analyse(&path, &p).unwrap();
    println!("baseline {:?}\n{:?}", s.baseline, s.derivation);
    for (i, w) in s.windows.iter().enumerate() {
        println!(
            "{} meas {:?}\n   base {:?}\n   fin  {:?}",
            w.label, s.measured[i], s.baseline_features[i], s.final_features[i]
        );
    }
    println!("baseline held {:?} cal {}", s.selection.baseline_heldout, s.selection.baseline_calibration);
    for t in &s.selection.trials {
        println!(
            "step {} {:?} cal {:.3} held {:.3} gain {:.3} t {:.2} wins {} earns {} {:?} evals {}",
            t.step,
            t.candidate,
            t.fitted.calibration_misfit,
            t.heldout_misfit,
            t.relative_gain,
            t.paired_t,
            t.wins,
            t.earns_place,
            t.fitted.params,
            t.fitted.evaluations
        );
    }
    println!("wob {:?} adequate {}", s.wob, s.adequate);
    if let Some(d) = &s.drive {
        println!("drive step {} fit {:?}\n model {:?}\n law_from_torque {}", d.step, d.fit, d.model, d.law_from_torque);
        for (i, w) in s.windows.iter().enumerate() {
            println!("{} top {:?}\n   feat {:?}", w.label, d.top[i], d.features[i]);
        }
    }
    // Step-1 candidates: held-out windows within each feature's target.
    for (c, f) in &s.candidate_features {
        let met: Vec<usize> = (0..rig_lavi::FEATURES.len())
            .map(|k| {
                (1..s.windows.len())
                    .filter(|&w| rig_lavi::score::feature_errors(&s.measured[w], &f[w])[k].abs() <= 1.0)
                    .count()
            })
            .collect();
        println!("{:?} met {:?}", c, met);
    }
}

/// Developer aid (ignored): prints the repair audit of run 175.
#[test]
#[ignore]
fn repairs() {
    let (path, p) = setup();
    let (_, d) = rig_lavi::data::prepare(&path, &p).unwrap();
    println!("noise {} rad/s, twist {:?}, dips {:?}", d.top_noise_rad_s, d.twist_excursion_rad, d.glitches);
    for r in &d.repairs {
        println!("{r:?}");
    }
}

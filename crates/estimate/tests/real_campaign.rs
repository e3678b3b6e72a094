//! estimate_rig on the repository's campaign (data/emulated-rig-2026), read
//! with a minimal std/toml reader (rig-ingest pulls polars; not needed here).
//! Ignored by default: it is a timing and sanity run, `cargo test -- --ignored`.

use rig_estimate::{EstimateOptions, InitialValues, estimate_rig};
use rig_types::{Campaign, RigInfo, Run, RunData, RunKind};
use std::path::Path;
use std::time::Instant;

fn read_campaign(dir: &Path) -> Campaign {
    let doc: toml::Table = std::fs::read_to_string(dir.join("campaign.toml")).unwrap().parse().unwrap();
    let rig = doc["rig"].as_table().unwrap();
    let f = |t: &toml::Table, k: &str| t[k].as_float().or_else(|| t[k].as_integer().map(|i| i as f64)).unwrap();
    let mut runs = Vec::new();
    for r in doc["runs"].as_array().unwrap() {
        let r = r.as_table().unwrap();
        let kind = match r["kind"].as_str().unwrap() {
            "force_calibration" => RunKind::ForceCalibration { load_n: f(r, "load_n") },
            "static_twist" => RunKind::StaticTwist { torque_nm: f(r, "torque_nm") },
            "voltage_step" => RunKind::VoltageStep { voltage_v: f(r, "voltage_v") },
            _ => RunKind::OperatingPoint {
                motor_rpm_setpoint: f(r, "motor_rpm_setpoint"),
                normal_force_n: f(r, "normal_force_n"),
                ramp_s: f(r, "ramp_s"),
            },
        };
        let file = r["file"].as_str().unwrap();
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); header.len()];
        for l in lines {
            for (c, v) in cols.iter_mut().zip(l.split(',')) {
                c.push(v.parse().unwrap());
            }
        }
        let col = |name: &str| header.iter().position(|h| *h == name).map(|i| cols[i].clone());
        let ticks = |name: &str| col(name).map(|v| v.iter().map(|x| *x as i64).collect());
        let data = RunData {
            time_s: col("time_s").unwrap(),
            motor_voltage_v: col("motor_voltage_v"),
            motor_ticks: ticks("motor_ticks"),
            rotor_ticks: ticks("rotor_ticks"),
            brake_force_mv: col("brake_force_mv"),
        };
        runs.push(Run { id: r["id"].as_str().unwrap().into(), kind, file: file.into(), data });
    }
    Campaign {
        name: doc["name"].as_str().unwrap().into(),
        description: String::new(),
        rig: RigInfo {
            encoder_ticks_per_rev: rig["encoder_ticks_per_rev"].as_integer().unwrap() as u32,
            brake_disc_radius_m: f(rig, "brake_disc_radius_m"),
            supply_voltage_v: f(rig, "supply_voltage_v"),
            sample_rate_hz: f(rig, "sample_rate_hz"),
        },
        runs,
    }
}

#[test]
#[ignore]
fn emulated_rig_2026_timing() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/emulated-rig-2026");
    let c = read_campaign(&dir);
    let cal = rig_calibrate::calibrate_campaign(&c).unwrap();
    let init = InitialValues {
        motor_inertia_kgm2: 0.37e-3,
        inductance_h: 1.10e-3,
        resistance_ohm: 0.33,
        torque_constant_nm_a: 0.12,
        voltage_constant_v_s_rad: 6.02e-2,
        friction_torque_nm: 0.1,
        speed_regulation_nm_s_rad: 1.91e-4,
        rotor_inertia_kgm2: 0.0283,
        shaft_stiffness_nm_rad: 0.268,
    };
    for free_l in [false] {
        let mut o = EstimateOptions::new(
            init.clone(),
            rig_model::SimOptions::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml"),
        );
        o.free_inductance = free_l;
        let t0 = Instant::now();
        let e = estimate_rig(&c, &cal, &o).unwrap();
        eprintln!(
            "free L {free_l}: estimate_rig {:?}, {} iterations, SSR {:.4}",
            t0.elapsed(),
            e.report.iterations,
            e.report.ssr
        );
        for p in &e.report.params {
            eprintln!("  {:5} {:.5e} {:?}", p.name, p.estimate, p.stderr);
        }
        for r in &e.report.runs {
            eprintln!(
                "  {} used {} {:?}",
                r.run,
                r.used,
                r.channels
                    .iter()
                    .map(|c| (c.channel.clone(), (c.fit_percent * 100.0).round() / 100.0))
                    .collect::<Vec<_>>()
            );
        }
        eprintln!("  pi {:?}\n  fr {:?}", e.pi, e.friction);
    }
}

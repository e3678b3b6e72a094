//! Criterion bench: the whole blind diagnosis (calibrate → estimate the
//! baseline → diagnose, with every check and both free runs) of a 30-run campaign. The campaign is the shipped data/emulated-rig-2026 (an
//! emulated, i.e. generated, 30-operating-point campaign) or the folder in
//! $RIG_BENCH_CAMPAIGN (e.g. one written by rig-virtual-rig's write_campaign).
//! rig-diagnose may not depend on rig-virtual-rig (tidy test) and rig-ingest
//! would build polars in the bench profile, so a minimal reader lives here:
//! it trusts the folder (it is not a validator).

use criterion::{Criterion, criterion_group, criterion_main};
use rig_diagnose::{BlindChain, diagnose_campaign};
use rig_types::{Campaign, RigInfo, Run, RunData, RunKind};
use std::path::{Path, PathBuf};

fn read(dir: &Path) -> Campaign {
    let text = std::fs::read_to_string(dir.join("campaign.toml")).expect("campaign.toml");
    let v: toml::Table = text.parse().expect("toml");
    let rig = v["rig"].as_table().expect("[rig]");
    let f = |t: &toml::Table, k: &str| t[k].as_float().or_else(|| t[k].as_integer().map(|i| i as f64)).expect(k);
    let mut runs = Vec::new();
    for r in v["runs"].as_array().expect("runs") {
        let r = r.as_table().expect("run");
        let kind = match r["kind"].as_str().expect("kind") {
            "force_calibration" => RunKind::ForceCalibration { load_n: f(r, "load_n") },
            "static_twist" => RunKind::StaticTwist { torque_nm: f(r, "torque_nm") },
            "voltage_step" => RunKind::VoltageStep { voltage_v: f(r, "voltage_v") },
            _ => RunKind::OperatingPoint {
                motor_rpm_setpoint: f(r, "motor_rpm_setpoint"),
                normal_force_n: f(r, "normal_force_n"),
                ramp_s: f(r, "ramp_s"),
            },
        };
        let file = PathBuf::from(r["file"].as_str().expect("file"));
        let csv = std::fs::read_to_string(dir.join(&file)).expect("csv");
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().expect("header").split(',').collect();
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); header.len()];
        for l in lines {
            for (c, x) in l.split(',').enumerate() {
                cols[c].push(x.parse().expect("number"));
            }
        }
        let get = |name: &str| header.iter().position(|h| *h == name).map(|i| cols[i].clone());
        let ints = |name: &str| get(name).map(|v| v.into_iter().map(|x| x as i64).collect());
        let data = RunData {
            time_s: get("time_s").expect("time_s"),
            motor_voltage_v: get("motor_voltage_v"),
            motor_ticks: ints("motor_ticks"),
            rotor_ticks: ints("rotor_ticks"),
            brake_force_mv: get("brake_force_mv"),
        };
        runs.push(Run { id: r["id"].as_str().expect("id").into(), kind, file, data });
    }
    Campaign {
        name: v["name"].as_str().unwrap_or("bench").into(),
        description: String::new(),
        rig: RigInfo {
            encoder_ticks_per_rev: rig["encoder_ticks_per_rev"].as_integer().expect("ticks") as u32,
            brake_disc_radius_m: f(rig, "brake_disc_radius_m"),
            supply_voltage_v: f(rig, "supply_voltage_v"),
            sample_rate_hz: f(rig, "sample_rate_hz"),
        },
        runs,
    }
}

fn bench(c: &mut Criterion) {
    let dir = std::env::var("RIG_BENCH_CAMPAIGN")
        .map(PathBuf::from)
        .unwrap_or_else(|_| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/emulated-rig-2026"));
    let campaign = read(&dir);
    let chain = BlindChain::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml");
    // The thesis' published values as the thesis-tables stage wrote them
    // (reports/data/thesis.json): with them the chain estimates the baseline
    // and runs every check and both free runs, as the diagnosis stage does.
    let thesis: rig_calibrate::ThesisData = serde_json::from_str(
        &std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../reports/data/thesis.json"))
            .expect("reports/data/thesis.json (run cargo xtask reproduce once)"),
    )
    .expect("thesis.json");
    let mut g = c.benchmark_group("diagnose");
    g.sample_size(10);
    g.bench_function("30-run campaign, blind, with baseline estimate and every check", |b| {
        b.iter(|| diagnose_campaign(&campaign, Some(&thesis), &chain).expect("diagnosis"))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // No plots: criterion's plotters backend panics on this machine (no font); the numbers are what is recorded.
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);

//! Another lab's protocol runs end to end: a campaign the virtual rig records
//! at another sample rate (1 kHz, 250 Hz), with 14 other operating points,
//! 30 s runs, a 3 s ramp and other run ids, goes through the runner (what
//! `cargo xtask reproduce --campaign DIR` runs) with every campaign stage
//! succeeding. Windows are in seconds and the protocol is read from the
//! campaign, so nothing here is tuned to the shipped 500 Hz, 40 s, 2 s ramp.
//!
//! The other campaigns `rig-campaign/1` allows (twentieth session): a time
//! column that is authoritative and not the nominal rate (a clock 2 % off,
//! jittered sampling, runs of different lengths), columns in another order
//! in every file, other rates and lengths, ramps of zero and longer than half
//! the run, set-points outside the thesis' range, a gap in the time column,
//! different ramps in one campaign, a negative voltage step, and campaigns
//! with few runs of a kind. What a stage cannot work with is refused with
//! the file and the rule (one operating point; no run with a steady window;
//! encoders running against the drive). Two that failed run now: an open
//! brake (`normal_force_n = 0`) and every operating point at one set-point.
//!
//! The sweeps stage's maps and diagrams are simulations on a grid that does
//! not depend on the campaign's protocol; their grids are coarsened here
//! (4 × 3 map points, 4 diagram points) only to keep the test's time down.

use rig_pipeline::Runner;
use rig_pipeline::testing::workspace_root;
use rig_types::{Campaign, RunData};
use rig_virtual_rig::{Hidden, Protocol, Truth, draw_rig, draw_truth, generate, ids, write_campaign};
use std::path::{Path, PathBuf};

/// The campaign stages (their upstream, thesis-tables, runs first).
const STAGES: [&str; 7] =
    ["campaign-calibration", "estimation", "simulation", "sweeps", "spectra", "harmonic", "diagnosis"];

fn other_lab(sample_rate_hz: f64) -> Protocol {
    let mut op_points = Vec::new();
    for rpm in [12.0, 28.0, 42.0, 60.0, 78.0, 100.0, 120.0] {
        for n in [3.0, 8.0] {
            op_points.push((rpm, n));
        }
    }
    Protocol {
        sample_rate_hz,
        force_loads_n: vec![1.0, 2.5, 4.0, 5.5],
        twist_torques_nm: vec![0.1, 0.2, 0.3, 0.4],
        step_voltages_v: vec![7.0, 9.0, 11.0],
        step_duration_s: 15.0,
        op_points,
        op_duration_s: 30.0,
        ramp_s: 3.0,
    }
}

/// New ids for every run (the file follows the id).
fn rename(id: &str) -> String {
    let (kind, n) = id.rsplit_once('-').unwrap_or((id, ""));
    let kind = match kind {
        "op" => "point",
        "cal" => "load",
        "twist" => "torque",
        "step" => "volt",
        k => k,
    };
    format!("lab2-{kind}-{n}")
}

/// The virtual rig's campaign under `protocol`, every run renamed.
fn campaign_of(protocol: &Protocol, seed: u64) -> Campaign {
    campaign_of_truth(&draw_rig(seed), protocol, seed)
}

/// [`campaign_of`] of the rig `truth`.
fn campaign_of_truth(truth: &Truth, protocol: &Protocol, seed: u64) -> Campaign {
    let mut c = generate("other-lab", truth, protocol, seed).expect("generate");
    for r in &mut c.runs {
        r.id = rename(&r.id);
        r.file = PathBuf::from(format!("runs/{}.csv", r.id));
    }
    c
}

/// A run's out dir, removed with its campaign when dropped.
#[derive(Debug)]
struct Out {
    _dir: tempfile::TempDir,
    path: PathBuf,
}

impl Out {
    fn join(&self, rel: &str) -> PathBuf {
        self.path.join(rel)
    }
}

/// Writes `c` (then `edit` rewrites files on disk) and runs the campaign
/// stages through the runner; the runner's error and summary on failure.
fn run_campaign(label: &str, c: &Campaign, edit: impl Fn(&Path)) -> Result<Out, String> {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    let campaign = dir.join("campaign");
    write_campaign(&campaign, c).expect("write campaign");
    edit(&campaign);
    let out = dir.join("out");
    let mut runner = Runner::new(&workspace_root().join("pipeline.toml"))
        .expect("pipeline.toml")
        .campaign(&campaign)
        .out(&out)
        .only(&STAGES)
        .jobs(2);
    for (key, value) in [("map_rpm_points", "4"), ("map_force_points", "3"), ("diagram_points", "4")] {
        runner = runner.set_param("sweeps", key, value).expect("sweeps param");
    }
    let report = match runner.run() {
        Ok(r) => r,
        Err(e) => return Err(format!("{label}: refused: {}", rig_pipeline::describe(&e.into()))),
    };
    let summary = report.summary(false);
    if let Err(e) = report.into_result() {
        return Err(format!("{label}: {e:#}\n{summary}"));
    }
    for f in ["data/rig-params.json", "diagnosis.json", "estimation.md", "tables/campaign-simulation-misfit.csv"] {
        if !out.join(f).is_file() {
            return Err(format!("{label}: {f} missing\n{summary}"));
        }
    }
    Ok(Out { _dir: tmp, path: out })
}

fn runs_end_to_end(label: &str, c: &Campaign, edit: impl Fn(&Path)) -> Out {
    run_campaign(label, c, edit).unwrap_or_else(|e| panic!("{e}"))
}

fn run_protocol(sample_rate_hz: f64, seed: u64) {
    runs_end_to_end(&format!("{sample_rate_hz} Hz"), &campaign_of(&other_lab(sample_rate_hz), seed), |_| {});
}

#[test]
fn a_1khz_campaign_of_another_protocol_runs_end_to_end() {
    run_protocol(1000.0, 2601);
}

#[test]
fn a_250hz_campaign_of_another_protocol_runs_end_to_end() {
    run_protocol(250.0, 2602);
}

/// A small protocol for the variants: 8 operating points.
fn small_lab(sample_rate_hz: f64) -> Protocol {
    let mut op_points = Vec::new();
    for rpm in [15.0, 40.0, 75.0, 110.0] {
        for n in [3.0, 8.0] {
            op_points.push((rpm, n));
        }
    }
    Protocol { op_points, op_duration_s: 20.0, ..other_lab(sample_rate_hz) }
}

/// The recorder's clock runs 2 % fast of the declared rate: the time column
/// (authoritative) says 510 samples a second, campaign.toml 500. It runs end
/// to end, and the analysis reads the time column: the blind chain on it
/// (read back from disk, its time column written at 0.1 ms) gives the numbers
/// of the same samples declared at their true rate, 510 Hz.
///
/// The criterion, stated before it was run (twenty-first session): the
/// rotor balance (the torque-balance check's statistic and floor, every
/// structure's cross-validated balance and event misfits), the voltage-step
/// checks (statistic and floor) and the estimate (PI gains, μs, μk, K, C,
/// J1, the motor constants) agree to 10⁻⁴ relative, and the verdict and the
/// effects found are the same. The off campaign's clock is its mean step
/// (`rig_types::sensor::clock_rate_hz`), which the column's 0.1 ms rounding
/// leaves within 10⁻⁴ s / 20 s = 5·10⁻⁶ of 1/510 s: 10⁻⁴ is twenty times
/// that. Before, the balance's derivatives divided by the declared step and
/// its misfit rose 7 % (docs/findings.md, twentieth session), 700 times the
/// criterion.
#[test]
fn a_clock_two_percent_off_the_nominal_rate_runs_end_to_end() {
    let true_rate = campaign_of(&small_lab(510.0), 2603);
    let mut c = true_rate.clone();
    c.rig.sample_rate_hz = 500.0;
    let out = runs_end_to_end("clock 2 % off", &c, |_| {});
    let thesis: rig_calibrate::ThesisData =
        serde_json::from_str(&std::fs::read_to_string(out.join("data/thesis.json")).expect("thesis.json"))
            .expect("thesis");
    let text = std::fs::read_to_string(workspace_root().join("pipeline.toml")).expect("pipeline.toml");
    let chain = rig_diagnose::BlindChain::from_pipeline_toml(&text).expect("the chain");
    let blind = |c: &Campaign| {
        let tmp = tempfile::tempdir().expect("tempdir");
        write_campaign(tmp.path(), c).expect("write campaign");
        let c = rig_ingest::read_campaign(tmp.path()).expect("read back");
        let (cal, baseline) = chain.calibrate_and_estimate(&c, Some(&thesis)).expect("calibrate");
        let p = baseline.expect("a baseline").expect("estimate");
        let d = rig_diagnose::diagnose(&c, &cal, Some(&p), Some(thesis.friction.mu_dynamic), &chain.diagnosis)
            .expect("diagnosis");
        (p, d)
    };
    let ((p_off, d_off), (p_true, d_true)) = (blind(&c), blind(&true_rate));
    let mut numbers: Vec<(String, f64, f64)> = Vec::new();
    let mut add = |name: &str, a: f64, b: f64| numbers.push((name.to_string(), a, b));
    let (m_off, m_true) = (&p_off.motor, &p_true.motor);
    for (name, a, b) in [
        ("kp", p_off.drive.kp_v_s_rad, p_true.drive.kp_v_s_rad),
        ("ki", p_off.drive.ki_v_rad, p_true.drive.ki_v_rad),
        ("J1", p_off.rotor_inertia_kgm2, p_true.rotor_inertia_kgm2),
        ("K", p_off.shaft_stiffness_nm_rad, p_true.shaft_stiffness_nm_rad),
        ("C", p_off.shaft_damping_nm_s_rad, p_true.shaft_damping_nm_s_rad),
    ] {
        add(name, a, b);
    }
    let (f_off, f_true) =
        (serde_json::to_value(&p_off.friction).unwrap(), serde_json::to_value(&p_true.friction).unwrap());
    for key in ["mu_static", "mu_kinetic"] {
        add(key, f_off[key].as_f64().expect(key), f_true[key].as_f64().expect(key));
    }
    let (mo, mt) = (serde_json::to_value(m_off).unwrap(), serde_json::to_value(m_true).unwrap());
    for (key, v) in mo.as_object().expect("motor params") {
        if let (Some(a), Some(b)) = (v.as_f64(), mt[key].as_f64()) {
            add(&format!("motor.{key}"), a, b);
        }
    }
    for (a, b) in d_off.detail.channel_checks.iter().zip(&d_true.detail.channel_checks) {
        assert_eq!(a.channel, b.channel);
        if a.channel == "operating_point.torque_balance" || a.channel.starts_with("voltage_step.") {
            add(&format!("{} statistic", a.channel), a.statistic, b.statistic);
            add(&format!("{} floor", a.channel), a.noise_floor, b.noise_floor);
        }
    }
    for (a, b) in d_off.detail.structure_scores.iter().zip(&d_true.detail.structure_scores) {
        assert_eq!(a.id, b.id);
        add(&format!("{} balance misfit", a.id), a.balance_misfit, b.balance_misfit);
        add(&format!("{} event misfit", a.id), a.event_misfit, b.event_misfit);
    }
    assert!(numbers.iter().any(|n| n.0 == "operating_point.torque_balance statistic"), "the balance check is made");
    assert!(numbers.iter().any(|n| n.0.ends_with("balance misfit")), "the structures are scored");
    assert!(numbers.iter().any(|n| n.0 == "voltage_step.residual floor"), "the step checks are made");
    let off: Vec<String> = numbers
        .iter()
        // Both NaN: a misfit neither has (no event-locked rows on this draw).
        .filter(|(_, a, b)| !((a - b).abs() <= 1e-4 * b.abs().max(a.abs()) || (a.is_nan() && b.is_nan())))
        .map(|(n, a, b)| format!("{n}: {a:e} declared 500 Hz vs {b:e} declared 510 Hz ({:+.2e})", a / b - 1.0))
        .collect();
    assert!(off.is_empty(), "the clock 2 % off moves:\n{}", off.join("\n"));
    assert_eq!(d_off.verdict, d_true.verdict);
    let effects = |d: &rig_diagnose::Diagnosis| d.findings.iter().map(|f| f.effect.clone()).collect::<Vec<_>>();
    assert_eq!(effects(&d_off), effects(&d_true));
}

/// Non-uniform sampling: recorded at 2 kHz, kept at one sample in about four
/// (steps of 1.5–2.5 ms), declared 500 Hz.
#[test]
fn jittered_sampling_runs_end_to_end() {
    let mut c = campaign_of(&small_lab(2000.0), 2604);
    c.rig.sample_rate_hz = 500.0;
    for (j, r) in c.runs.iter_mut().enumerate() {
        let n = r.data.time_s.len();
        let keep: Vec<usize> = (0..n / 4)
            .map(|k| if k == 0 { 0 } else { 4 * k + [0, 1, 3][(k * 7 + j) % 3] - 1 })
            .filter(|&i| i < n)
            .collect();
        let d = &mut r.data;
        keep_samples(d, &keep);
    }
    runs_end_to_end("jittered", &c, |_| {});
}

/// Every CSV's columns rotated (time last in some), runs of unequal length.
#[test]
fn columns_in_another_order_and_runs_of_unequal_length_run_end_to_end() {
    let mut c = campaign_of(&small_lab(500.0), 2605);
    for (j, r) in c.runs.iter_mut().filter(|r| r.kind.name() == "operating_point").enumerate() {
        let keep = r.data.time_s.len() - 1000 * (j % 3);
        let d = &mut r.data;
        d.time_s.truncate(keep);
        for v in [&mut d.motor_voltage_v, &mut d.brake_force_mv].into_iter().flatten() {
            v.truncate(keep);
        }
        for v in [&mut d.motor_ticks, &mut d.rotor_ticks].into_iter().flatten() {
            v.truncate(keep);
        }
    }
    runs_end_to_end("columns rotated", &c, |camp| {
        let mut files: Vec<PathBuf> =
            std::fs::read_dir(camp.join("runs")).unwrap().map(|e| e.unwrap().path()).collect();
        files.sort();
        for (j, f) in files.iter().enumerate() {
            let text = std::fs::read_to_string(f).unwrap();
            let mut out = String::new();
            for line in text.lines() {
                let mut cells: Vec<&str> = line.split(',').collect();
                let k = (1 + j) % cells.len();
                cells.rotate_left(k);
                out.push_str(&cells.join(","));
                out.push('\n');
            }
            std::fs::write(f, out).unwrap();
        }
    });
}

#[test]
fn a_2khz_campaign_runs_end_to_end() {
    let p = Protocol { op_duration_s: 10.0, step_duration_s: 8.0, ramp_s: 1.0, ..small_lab(2000.0) };
    runs_end_to_end("2 kHz", &campaign_of(&p, 2606), |_| {});
}

#[test]
fn a_100hz_campaign_runs_end_to_end() {
    runs_end_to_end("100 Hz", &campaign_of(&small_lab(100.0), 2607), |_| {});
}

/// 10 s operating points (a 1 s ramp), 5 s voltage steps.
#[test]
fn short_runs_run_end_to_end() {
    let p = Protocol { op_duration_s: 10.0, step_duration_s: 5.0, ramp_s: 1.0, ..small_lab(500.0) };
    runs_end_to_end("short runs", &campaign_of(&p, 2608), |_| {});
}

#[test]
fn no_ramp_runs_end_to_end() {
    let p = Protocol { ramp_s: 0.0, ..small_lab(500.0) };
    runs_end_to_end("ramp 0", &campaign_of(&p, 2609), |_| {});
}

/// A 12 s ramp on 20 s runs: the spectra's steady window (after the ramp
/// and 8 s of settling) is empty on every run but the two that last longer.
#[test]
fn a_ramp_longer_than_half_the_run_runs_end_to_end() {
    let p = Protocol { ramp_s: 12.0, ..small_lab(500.0) };
    let mut c = campaign_of(&p, 2610);
    for r in c.runs.iter_mut().filter(|r| r.kind.name() == "operating_point").take(2) {
        // Two runs recorded 30 s instead of 20 s: the clock read on.
        let d = &mut r.data;
        let n = d.time_s.len();
        let dt = d.time_s[1] - d.time_s[0];
        for k in n..(n * 3 / 2) {
            d.time_s.push(k as f64 * dt);
        }
        let last = |v: &mut Vec<f64>| v.resize(n * 3 / 2, *v.last().unwrap());
        d.motor_voltage_v.as_mut().map(last);
        d.brake_force_mv.as_mut().map(last);
        let cont = |v: &mut Vec<i64>| {
            let step = v[n - 1] - v[n - 2];
            for k in n..(n * 3 / 2) {
                let next = v[k - 1] + step;
                v.push(next);
            }
        };
        d.motor_ticks.as_mut().map(cont);
        d.rotor_ticks.as_mut().map(cont);
    }
    let out = runs_end_to_end("ramp 12 s of 20", &c, |_| {});
    let short = std::fs::read_to_string(out.join("tables/lines-short-runs.csv")).expect("the runs left out are listed");
    assert_eq!(short.lines().count(), 1 + 6, "{short}");
    assert!(short.contains("lab2-point-03,"), "{short}");
    assert!(!short.contains("lab2-point-01,"), "{short}");
}

/// Every operating point ends before its steady window: spectra (and what
/// reads it) stops with the rule; the shipped campaign has no such table.
#[test]
fn runs_without_a_steady_window_are_refused_by_spectra_with_the_rule() {
    let p = Protocol { op_duration_s: 10.0, ramp_s: 3.0, ..small_lab(500.0) };
    let err = run_campaign("no steady window", &campaign_of(&p, 2615), |_| {}).unwrap_err();
    assert!(
        err.contains("stage spectra: campaign other-lab: needs at least 1 operating_point run with a steady window"),
        "{err}"
    );
}

#[test]
fn set_points_outside_the_thesis_range_run_end_to_end() {
    let p = Protocol {
        op_points: vec![
            (2.0, 3.0),
            (5.0, 40.0),
            (300.0, 3.0),
            (400.0, 8.0),
            (60.0, 0.5),
            (150.0, 60.0),
            (40.0, 8.0),
            (90.0, 3.0),
        ],
        ..small_lab(500.0)
    };
    runs_end_to_end("set-points outside", &campaign_of(&p, 2611), |_| {});
}

/// The ids of `c`'s operating points with the brake open.
fn brake_open_ids(c: &Campaign) -> Vec<String> {
    c.runs
        .iter()
        .filter(
            |r| matches!(r.kind, rig_types::RunKind::OperatingPoint { normal_force_n, .. } if normal_force_n == 0.0),
        )
        .map(|r| r.id.clone())
        .collect()
}

/// `diagnosis.json` of a run's out dir.
fn diagnosis_json(o: &Out) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(o.join("diagnosis.json")).unwrap()).unwrap()
}

/// The drive channel's record of the open-brake runs (`drive_channel` of
/// `diagnosis.json`): every operating point counted, the open ones named
/// in campaign order, each with its held-out voltage errors (run, baseline,
/// final, floor).
fn drive_channel_of(d: &serde_json::Value, c: &Campaign, open: &[String]) -> Vec<(String, f64, f64, f64)> {
    let dc = &d["drive_channel"];
    assert_eq!(dc["runs"], serde_json::json!(c.runs_of("operating_point").count()), "{dc:#}");
    assert_eq!(dc["brake_open"], serde_json::json!(open.len()), "{dc:#}");
    let rows: Vec<(String, f64, f64, f64)> = dc["brake_open_heldout"]
        .as_array()
        .expect("brake_open_heldout")
        .iter()
        .map(|r| {
            let f = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
            (
                r["run"].as_str().expect("run").to_string(),
                f("relative_voltage_error_baseline"),
                f("relative_voltage_error_final"),
                f("noise_floor"),
            )
        })
        .collect();
    assert_eq!(rows.iter().map(|r| r.0.clone()).collect::<Vec<_>>(), open, "{dc:#}");
    rows
}

/// Two operating points with the brake open (`normal_force_n = 0`, which
/// the spec allows). They give no slip samples (μ = F/N has no N), so a
/// per-run friction parameter (a modulation's phase) had nothing to fit and
/// the diagnosis stopped on a singular joint fit (twentieth session). The
/// diagnosis leaves them out of the friction selection and names them; its
/// verdict and findings are those of the same campaign without them.
/// Twenty-first session: the drive channel reads them (the PI loop needs no
/// brake): its fits count every operating point, and each open run, held
/// out of its fold's drive fit, is predicted by the PI law fitted on the
/// other runs.
#[test]
fn an_open_brake_runs_end_to_end() {
    let mut p = small_lab(500.0);
    p.op_points.push((30.0, 0.0));
    p.op_points.push((90.0, 0.0));
    let c = campaign_of(&p, 2612);
    let open = brake_open_ids(&c);
    assert_eq!(open.len(), 2);
    let out = runs_end_to_end("open brake", &c, |_| {});
    let json = diagnosis_json;
    let d = json(&out);
    assert_eq!(d["brake_open_runs"], serde_json::json!(open), "{d:#}");
    // Held out, the PI law fitted on the other runs predicts each open run's
    // voltage within the diagnosis' adequacy ratio of its noise floor (the
    // drive law needs no brake).
    let text = std::fs::read_to_string(workspace_root().join("pipeline.toml")).expect("pipeline.toml");
    let ratio = rig_diagnose::DiagnoseOptions::from_pipeline_toml(&text).expect("diagnosis params").adequacy_ratio;
    for (id, baseline, final_, floor) in drive_channel_of(&d, &c, &open) {
        assert!(baseline == final_ && baseline <= ratio * floor, "{id}: held-out e_V {baseline}, floor {floor}");
    }
    // The same rig and seed without the open-brake runs: the same verdict and
    // the same effects found (the open runs inform no friction fit).
    let mut without = c.clone();
    without.runs.retain(|r| !open.contains(&r.id));
    let base = json(&runs_end_to_end("brake applied", &without, |_| {}));
    assert!(base.get("drive_channel").is_none() && base.get("brake_open_runs").is_none(), "{base:#}");
    let effects = |v: &serde_json::Value| -> Vec<serde_json::Value> {
        v["findings"].as_array().unwrap().iter().map(|f| f["effect"].clone()).collect()
    };
    assert_eq!(d["verdict"], base["verdict"]);
    assert_eq!(effects(&d), effects(&base));
}

/// A drive limit that clips the fast runs, two of them with the brake open
/// (75 and 110 rpm, beside the braked 15–110 rpm): the limit is found
/// (within the confusion stage's 5 % of the truth), and the open runs the
/// limit clips carry it, held out of their fold's fits: the final model's
/// drive (with its limit) predicts their voltage better than the baseline's
/// (saturating at the supply). A run clips when its recorded voltage stays
/// within 2 % of the limit for a second.
#[test]
fn a_drive_limit_the_open_brake_runs_carry_is_found() {
    let mut p = small_lab(500.0);
    p.op_points.push((75.0, 0.0));
    p.op_points.push((110.0, 0.0));
    let seed = 2613;
    let truth = draw_truth(ids::DRIVE_VOLTAGE_LIMIT, 110.0, seed);
    let Hidden::DriveVoltageLimit { limit_v } = truth.hidden else { panic!("{:?}", truth.hidden) };
    let c = campaign_of_truth(&truth, &p, seed);
    let open = brake_open_ids(&c);
    assert_eq!(open.len(), 2);
    let clipping: Vec<String> = c
        .runs
        .iter()
        .filter(|r| open.contains(&r.id))
        .filter(|r| {
            let v = r.data.motor_voltage_v.as_ref().expect("voltage");
            let near = v.iter().filter(|x| x.abs() >= 0.98 * limit_v).count() as f64;
            near >= c.rig.sample_rate_hz
        })
        .map(|r| r.id.clone())
        .collect();
    assert!(!clipping.is_empty(), "no open run clips at {limit_v} V");
    let d = diagnosis_json(&runs_end_to_end("open brake, drive limit", &c, |_| {}));
    let found = d["findings"].as_array().unwrap().iter().find(|f| f["effect"] == ids::DRIVE_VOLTAGE_LIMIT);
    let found = found.unwrap_or_else(|| panic!("the drive limit is not found: {d:#}"));
    let fitted = found["params"]["limit_v"].as_f64().expect("limit_v");
    assert!((fitted / limit_v - 1.0).abs() <= 0.05, "limit {fitted} V against the truth's {limit_v} V");
    let rows = drive_channel_of(&d, &c, &open);
    eprintln!("truth {limit_v} V, fitted {fitted} V; clipping {clipping:?}; drive channel: {rows:?}");
    for (id, baseline, final_, _) in rows.iter().filter(|r| clipping.contains(&r.0)) {
        assert!(final_ < baseline, "{id}: held-out e_V {final_} with the limit, {baseline} without");
    }
}

#[test]
fn few_runs_of_each_kind_run_end_to_end() {
    let p = Protocol {
        force_loads_n: vec![1.0, 3.0, 5.0],
        twist_torques_nm: vec![0.15, 0.3],
        step_voltages_v: vec![9.0],
        ..small_lab(500.0)
    };
    runs_end_to_end("few runs", &campaign_of(&p, 2613), |_| {});
}

/// One operating point: the diagnosis (cross-validation over runs) refuses
/// the campaign before anything is written, naming the file and the rule.
#[test]
fn a_single_operating_point_is_refused_with_the_rule() {
    let p = Protocol { op_points: vec![(40.0, 5.0)], ..small_lab(500.0) };
    let err = run_campaign("one op", &campaign_of(&p, 2614), |_| {}).unwrap_err();
    assert!(err.contains("campaign.toml: 1 operating_point run: stage diagnosis needs at least 3"), "{err}");
}

/// A voltage step of negative voltage turns the motor the other way (the
/// spec allows it; its counts run negative): the campaign runs end to end
/// and the step's decay reads as its positive twin's (same rig, same seed):
/// the log decrement to the 4th decimal.
#[test]
fn a_negative_voltage_step_runs_end_to_end() {
    let decrement = |v: f64| {
        let p = Protocol { step_voltages_v: vec![v, 7.0, 11.0], ..small_lab(500.0) };
        let out = runs_end_to_end(&format!("step {v} V"), &campaign_of(&p, 2617), |_| {});
        let t = std::fs::read_to_string(out.join("tables/campaign-log-decrement.csv")).unwrap();
        let row = t.lines().nth(1).expect("the first step's row").to_string();
        row.split(',').nth(3).expect("log_decrement").to_string()
    };
    assert_eq!(decrement(-9.0), decrement(9.0));
}

/// Operating points recorded with both encoders (and voltage and force)
/// turned the other way: counts are positive in the drive direction and the
/// set-point is positive, so the reader refuses the first row more than a
/// revolution backwards, naming file, line and rule. Read as it was, the
/// run went through every stage with the PI gains' sign wrong (kp −0.23
/// against 1.51 V·s/rad) and a false `unexplained` diagnosis.
#[test]
fn an_operating_point_turning_the_other_way_is_refused_with_the_rule() {
    let truth = draw_rig(2616);
    let mut c = campaign_of(&small_lab(500.0), 2616);
    for r in c.runs.iter_mut().filter(|r| r.kind.name() == "operating_point") {
        let d = &mut r.data;
        for v in [&mut d.motor_ticks, &mut d.rotor_ticks].into_iter().flatten() {
            v.iter_mut().for_each(|x| *x = -*x);
        }
        d.motor_voltage_v.iter_mut().flatten().for_each(|x| *x = -*x);
        d.brake_force_mv.iter_mut().flatten().for_each(|x| *x = 2.0 * truth.force_offset_mv - *x);
    }
    let err = run_campaign("turned the other way", &c, |_| {}).unwrap_err();
    assert!(err.contains("runs/lab2-point-01.csv:"), "{err}");
    assert!(
        err.contains("is more than one revolution (1000 counts) against the drive direction: encoder counts are positive in the drive direction and motor_rpm_setpoint = 15 rpm drives it forward"),
        "{err}"
    );
}

/// The fewest operating points the diagnosis takes (3), at one normal force.
#[test]
fn three_operating_points_at_one_force_run_end_to_end() {
    let p = Protocol { op_points: vec![(20.0, 5.0), (60.0, 5.0), (110.0, 5.0)], ..small_lab(500.0) };
    runs_end_to_end("three points", &campaign_of(&p, 2618), |_| {});
}

/// Every operating point at one set-point (the folds cannot stratify by it).
/// The runs share a steady voltage (one set-point, similar loads), which
/// `rig_estimate::pi::voltage_plateau_v`'s two-run rule read as a drive
/// limit's plateau, so every sample counted as saturated and the estimation
/// stopped: "PI gains from operating_point runs: only 0 usable samples"
/// (twentieth session). A run now counts towards the rule only when its
/// motor falls behind the reference on the plateau, which a clipped drive
/// does and these runs do not.
#[test]
fn operating_points_at_one_set_point_run_end_to_end() {
    let p = Protocol {
        op_points: vec![(40.0, 2.0), (40.0, 4.0), (40.0, 6.0), (40.0, 9.0), (40.0, 12.0)],
        ..small_lab(500.0)
    };
    runs_end_to_end("one set-point", &campaign_of(&p, 2619), |_| {});
}

/// A recorder that dropped half a second of samples in every operating point
/// (5.0–5.5 s: the time column jumps; strictly increasing, so allowed).
#[test]
fn a_gap_in_the_time_column_runs_end_to_end() {
    let mut c = campaign_of(&small_lab(500.0), 2620);
    for r in c.runs.iter_mut().filter(|r| r.kind.name() == "operating_point") {
        let d = &mut r.data;
        let keep: Vec<usize> = (0..d.time_s.len()).filter(|&i| !(5.0..5.5).contains(&d.time_s[i])).collect();
        keep_samples(d, &keep);
    }
    runs_end_to_end("a gap", &c, |_| {});
}

/// Operating points of one rig with different ramps (0 s and 5 s) in one
/// campaign: each run's ramp is read from its own metadata.
#[test]
fn operating_points_with_different_ramps_run_end_to_end() {
    let mut c = campaign_of(&Protocol { ramp_s: 0.0, ..small_lab(500.0) }, 2621);
    let other = campaign_of(&Protocol { ramp_s: 5.0, ..small_lab(500.0) }, 2621);
    c.runs.retain(|r| r.kind.name() != "operating_point" || r.id.ends_with(['1', '3', '5', '7']));
    for mut r in
        other.runs.into_iter().filter(|r| r.kind.name() == "operating_point" && r.id.ends_with(['2', '4', '6', '8']))
    {
        r.id.push_str("-ramp5");
        r.file = PathBuf::from(format!("runs/{}.csv", r.id));
        c.runs.push(r);
    }
    runs_end_to_end("mixed ramps", &c, |_| {});
}

/// Keeps the samples `keep` (indices, increasing) of every column of a run.
fn keep_samples(d: &mut RunData, keep: &[usize]) {
    let pick_f = |v: &mut Vec<f64>| *v = keep.iter().map(|&i| v[i]).collect();
    let pick_i = |v: &mut Vec<i64>| *v = keep.iter().map(|&i| v[i]).collect();
    pick_f(&mut d.time_s);
    d.motor_voltage_v.as_mut().map(pick_f);
    d.brake_force_mv.as_mut().map(pick_f);
    d.motor_ticks.as_mut().map(pick_i);
    d.rotor_ticks.as_mut().map(pick_i);
}

/// A drive limit only the open-brake runs reach: braked operating points at
/// 15–75 rpm, open ones at 110, 120 and 130 rpm, and the limit halfway
/// between the highest voltage a braked run records without it (99th
/// percentile of |V|) and the highest an open run records. The braked runs'
/// voltage never comes within 2 % of the limit, so the runs the selection
/// scores do not show the clip: the limit is found because the open runs
/// enter the drive's fits (the PI gains fitted without a limit on records
/// that clip predict the held-out runs worse than with it). The same
/// campaign without its open runs (the drive channel before the
/// twenty-first session saw only those) does not find it.
#[test]
fn a_drive_limit_only_the_open_brake_runs_reach_is_found() {
    let mut p = small_lab(500.0);
    p.op_points.retain(|&(rpm, _)| rpm <= 75.0);
    p.op_points.extend([(110.0, 0.0), (120.0, 0.0), (130.0, 0.0)]);
    let seed = 2614;
    let plain = campaign_of(&p, seed);
    let open = brake_open_ids(&plain);
    assert_eq!(open.len(), 3);
    let v_max = |c: &Campaign, of_open: bool| -> f64 {
        c.runs_of("operating_point")
            .filter(|r| open.contains(&r.id) == of_open)
            .map(|r| {
                let mut v: Vec<f64> =
                    r.data.motor_voltage_v.as_ref().expect("voltage").iter().map(|x| x.abs()).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() * 99 / 100]
            })
            .fold(0.0, f64::max)
    };
    let limit_v = 0.5 * (v_max(&plain, false) + v_max(&plain, true));
    let truth = draw_rig(seed).with_hidden(vec![Hidden::DriveVoltageLimit { limit_v }]);
    let c = campaign_of_truth(&truth, &p, seed);
    for r in c.runs_of("operating_point").filter(|r| !open.contains(&r.id)) {
        let v = r.data.motor_voltage_v.as_ref().expect("voltage");
        assert!(v.iter().all(|x| x.abs() < 0.98 * limit_v), "{} reaches the limit {limit_v} V", r.id);
    }
    let limit_found = |d: &serde_json::Value| {
        d["findings"].as_array().unwrap().iter().find(|f| f["effect"] == ids::DRIVE_VOLTAGE_LIMIT).cloned()
    };
    let d = diagnosis_json(&runs_end_to_end("open brake, a limit only they reach", &c, |_| {}));
    let found = limit_found(&d).unwrap_or_else(|| panic!("the drive limit is not found: {d:#}"));
    let fitted = found["params"]["limit_v"].as_f64().expect("limit_v");
    assert!((fitted / limit_v - 1.0).abs() <= 0.05, "limit {fitted} V against the truth's {limit_v} V");
    let rows = drive_channel_of(&d, &c, &open);
    let step1 = d["candidates"].as_array().unwrap().iter().find(|x| x["effect"] == ids::DRIVE_VOLTAGE_LIMIT).cloned();
    eprintln!("truth {limit_v} V, fitted {fitted} V; first step {step1:?}; drive channel: {rows:?}");
    let mut without = c.clone();
    without.runs.retain(|r| !open.contains(&r.id));
    let base = diagnosis_json(&runs_end_to_end("the same, brake applied only", &without, |_| {}));
    eprintln!("without the open runs: {}", base["verdict"]);
    assert!(limit_found(&base).is_none(), "found without the open runs: {base:#}");
}

//! Developer aids on run 175 with pipeline.toml's `lavi` params.
//!
//! `cargo run --profile dev --example profile_study`: runs the study once and
//! prints the CPU time (all threads), the wall time and the Nelder–Mead
//! evaluations of every fit, trial by trial, and the free runs made and
//! reused (`Evaluator::outcome`): where the study's time goes.
//!
//! `cargo run --profile dev --example profile_study -- torque`: the trade-off
//! behind the missed torque targets. The final model of the study (structure
//! and J, k, c as selected) run free with a Coulomb law at the friction
//! levels the torque channel measures on the calibration window (break-away
//! T_s, slip T_k), and with T_s and T_k swept: which targets hold on the
//! held-out windows, per feature, and the torque through the stick phases.
//!
//! `cargo run --profile dev --example profile_study -- top`: `top_delay`'s scan
//! on the baseline (rig_lavi::top_delay::scan), point by point, and its CPU time.
//!
//! `cargo run --profile dev --example profile_study -- dump DIR`: per window,
//! `DIR/<window>.csv` with the span's time, the recorded bit speed and the
//! final model's free-run bit speed (rpm): the series behind the features,
//! for an independent look at what a window's misses are made of.
//!
//! `cargo run --profile dev --example profile_study -- static`:
//! `static_friction`'s grid on the final model, every point's calibration
//! misfit and, looked at after the choice, its held-out misfit and targets.

use rig_lavi::score::{Evaluator, feature_errors};
use rig_lavi::sim::{FrictionLaw, Model};
use rig_lavi::{FEATURES, StudyParams};
use std::path::{Path, PathBuf};

/// CPU time (user + system) of this process so far, s (`rig_types::cpu`).
fn cpu_s() -> f64 {
    rig_types::cpu::process_cpu_s().expect("/proc/self/stat")
}

/// Run 175's path and the `lavi` stage's params of pipeline.toml (with `[shared.selection]`).
fn setup() -> (PathBuf, StudyParams) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("../../../shared/data/ufrj-lavi-2018/run-175.csv");
    let text = std::fs::read_to_string(root.join("../../pipeline.toml")).expect("pipeline.toml");
    let v: toml::Value = toml::from_str(&text).expect("pipeline.toml parses");
    let st = v["stage"].as_array().expect("[[stage]]").iter().find(|s| s["name"].as_str() == Some("lavi"));
    let mut params = st.expect("a lavi stage")["params"].clone();
    params.as_table_mut().expect("params").insert("selection".into(), v["shared"]["selection"].clone());
    (path, params.try_into().expect("the lavi stage's params"))
}

fn main() {
    let (path, p) = setup();
    if std::env::args().nth(1).as_deref() == Some("torque") {
        torque_level(&path, &p);
    } else if std::env::args().nth(1).as_deref() == Some("top") {
        top_scan(&path, &p);
    } else if std::env::args().nth(1).as_deref() == Some("dump") {
        dump(&path, &p, Path::new(&std::env::args().nth(2).expect("dump DIR")));
    } else if std::env::args().nth(1).as_deref() == Some("static") {
        static_grid(&path, &p);
    } else {
        profile(&path, &p);
    }
}

fn profile(path: &Path, p: &StudyParams) {
    let c = cpu_s();
    let _ = rig_lavi::data::prepare(path, p).expect("run 175 reads");
    println!("prepare (read and repairs): CPU {:.2} s", cpu_s() - c);
    let (c0, w0) = (cpu_s(), std::time::Instant::now());
    let (s, _, _) = rig_lavi::study::analyse(path, p).expect("the study runs");
    let (cpu, wall) = (cpu_s() - c0, w0.elapsed().as_secs_f64());
    let mut total = 0;
    for t in &s.selection.trials {
        total += t.fitted.evaluations;
        println!(
            "step {} {:<16} evals {:>5} cal {:.3} held {:.3} gain {:.3} t {:.2}",
            t.step,
            t.candidate.id(),
            t.fitted.evaluations,
            t.fitted.calibration_misfit,
            t.heldout_misfit,
            t.relative_gain,
            t.paired_t
        );
    }
    println!("verdict {} chosen {:?}", s.verdict(), s.selection.chosen);
    println!("evaluations {total}, analyse: CPU {cpu:.2} s, wall {wall:.2} s");
    println!("free runs made {}, outcomes reused {}", s.free_runs[0], s.free_runs[1]);
    let (c, w) = (cpu_s(), std::time::Instant::now());
    let _ = rig_lavi::run_study(path, p).expect("the study runs");
    println!("run_study (analyse and render): CPU {:.2} s, wall {:.2} s", cpu_s() - c, w.elapsed().as_secs_f64());
}

fn dump(path: &Path, p: &StudyParams, dir: &Path) {
    let (s, d, _) = rig_lavi::study::analyse(path, p).expect("the study runs");
    let ev = Evaluator::of_study(&d, s.windows.clone(), p).expect("evaluator");
    std::fs::create_dir_all(dir).expect("dump dir");
    for (wi, w) in s.windows.iter().enumerate() {
        let run = ev.simulate(&s.selection.final_model, wi).expect("the final model runs");
        let mut csv = String::from("time_s,bit_rpm,sim_bit_rpm\n");
        for (k, i) in w.span.clone().enumerate() {
            csv.push_str(&format!(
                "{},{},{}\n",
                d.time_s[i],
                d.bit_raw_rpm[i],
                run.bit_rad_s[k] / rig_lavi::data::RPM_TO_RAD_S
            ));
        }
        std::fs::write(dir.join(format!("{}.csv", w.label)), csv).expect("write");
    }
}

fn torque_level(path: &Path, p: &StudyParams) {
    let (s, d, _) = rig_lavi::study::analyse(path, p).expect("the study runs");
    let ev = Evaluator::of_study(&d, s.windows.clone(), p).expect("evaluator");
    let cal = &ev.measured[0];
    println!(
        "calibration window measured: break-away {:.3} N m, slip {:.3} N m",
        cal.breakaway_torque_nm, cal.slip_torque_nm
    );
    for (w, st) in s.windows.iter().zip(&s.stick_torque) {
        println!("{} stick torque: record {:?}\n       final model {:?}", w.label, st[0], st[1]);
    }
    let report = |name: &str, m: &Model| {
        let f = ev.all_features(m);
        let st: Vec<rig_lavi::StickTorque> = (1..f.len()).map(|w| ev.stick_torque(Some(m), w).expect("runs")).collect();
        let (n, falling): (usize, usize) = (st.iter().map(|x| x.phases).sum(), st.iter().map(|x| x.falling).sum());
        println!("{name:<44} held-out stick phases {n}, ending lower {falling}");
        let met: Vec<usize> = (0..FEATURES.len())
            .map(|k| (1..f.len()).filter(|&w| feature_errors(&ev.measured[w], &f[w])[k].abs() <= 1.0).count())
            .collect();
        let mean = |g: &dyn Fn(&rig_lavi::Features) -> f64| (1..f.len()).map(|w| g(&f[w])).sum::<f64>() / 7.0;
        println!(
            "{name:<44} met {met:?}  held-out means: max {:.0} rpm, min {:.1} rpm, stick {:.3}, slip {:.3} N m, break-away {:.3} N m, misfit {:.3}",
            mean(&|x| x.bit_speed_max_rpm),
            mean(&|x| x.bit_speed_min_rpm),
            mean(&|x| x.stick_fraction),
            mean(&|x| x.slip_torque_nm),
            mean(&|x| x.breakaway_torque_nm),
            rig_lavi::select::overall(&ev.heldout_misfits(m)),
        );
    };
    let fin = s.selection.final_model;
    report("final model (as selected)", &fin);
    let coulomb = |ts: f64, tk: f64, m: &Model| Model {
        friction: FrictionLaw {
            static_nm: ts,
            kinetic_nm: tk,
            stribeck_speed_rad_s: 0.01,
            shape_exponent: 1.0,
            viscous_nm_s_rad: 0.0,
        },
        ..*m
    };
    let (ts, tk) = (cal.breakaway_torque_nm, cal.slip_torque_nm);
    report("final structure, Coulomb at the measured levels", &coulomb(ts, tk, &fin));
    report("baseline structure, Coulomb at the measured levels", &coulomb(ts, tk, &s.baseline));
    for ts in [2.2, 2.4, 2.6, 2.8, 3.0] {
        report(&format!("final structure, Coulomb T_s {ts:.1}, T_k {tk:.2}"), &coulomb(ts, tk, &fin));
    }
    for tk in [1.6, 1.8, 2.0, 2.2] {
        report(&format!("final structure, Coulomb T_s {ts:.2}, T_k {tk:.1}"), &coulomb(ts, tk, &fin));
    }
}

/// `-- top`: the `top_delay` scan on the baseline (τ_top, the torque delay, the equation of motion, the
/// least-squares law and its free run's calibration misfit), with the CPU time it takes.
fn top_scan(path: &Path, p: &StudyParams) {
    let (d, wins) = prepared(path, p);
    let ev = Evaluator::of_study(&d, wins.clone(), p).expect("evaluator");
    let (base, _) =
        rig_lavi::fit::derive(&d, &wins[0], p.slip_speed_rpm, rig_lavi::fit::Structure::BASELINE).expect("baseline");
    let c = cpu_s();
    let (pts, best) = rig_lavi::top_delay::scan(&ev, &base).expect("scan");
    println!("scan: {} points, CPU {:.2} s, best {}", pts.len(), cpu_s() - c, best);
    for q in &pts {
        println!(
            "tau_top {:+5.1} ms torque {:+5.1} ms R2 {:.4} k {:.3} c {:+.4} law {:.3} -> {:.3} N m cal {:.3}",
            1e3 * q.top_delay_s,
            1e3 * q.torque_delay_s,
            q.r_squared,
            q.stiffness_nm_rad,
            q.damping_nm_s_rad,
            q.law_static_nm,
            q.law_at_max_nm,
            q.calibration_misfit
        );
    }
}

/// `-- static`: `static_friction`'s grid on the final model, every point's calibration misfit and
/// held-out misfit and targets (what the grid would do held out; the fit looks at the calibration only).
fn static_grid(path: &Path, p: &StudyParams) {
    let (s, d, _) = rig_lavi::study::analyse(path, p).expect("the study runs");
    let ev = Evaluator::of_study(&d, s.windows.clone(), p).expect("evaluator");
    let fin = s.selection.final_model;
    for f in rig_lavi::static_friction::fractions() {
        let m = rig_lavi::static_friction::with_fraction(&fin, f);
        let fe = ev.all_features(&m);
        let met: Vec<usize> = (0..FEATURES.len())
            .map(|k| (1..fe.len()).filter(|&w| feature_errors(&ev.measured[w], &fe[w])[k].abs() <= 1.0).count())
            .collect();
        let held = ev.heldout_misfits(&m);
        println!(
            "excess {:4.0} % ({:.3} N m) cal {:.3} (max {:.1} stick {:.4} break-away {:.3}) held {:.3} met {met:?} = {} per window {:?}",
            100.0 * f,
            m.static_excess_nm,
            ev.misfit(&m, 0),
            fe[0].bit_speed_max_rpm,
            fe[0].stick_fraction,
            fe[0].breakaway_torque_nm,
            rig_lavi::select::overall(&held),
            met.iter().sum::<usize>(),
            held.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>(),
        );
    }
}

/// The record prepared and its windows, as the study cuts them.
fn prepared(path: &Path, p: &StudyParams) -> (rig_lavi::data::Prepared, Vec<rig_lavi::data::WindowSpec>) {
    let (_, d) = rig_lavi::data::prepare(path, p).expect("run 175 reads");
    let wins = rig_lavi::data::windows(&d, p).expect("windows");
    (d, wins)
}

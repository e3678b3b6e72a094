//! Developer aid: runs the LAVI study once on run 175 with pipeline.toml's
//! params and prints the CPU time (all threads), the wall time and
//! the Nelder–Mead evaluations of every fit, trial by trial: where the study's
//! time goes (`cargo run --profile dev --example profile_study`).

/// CPU time of this process (all threads), s: utime + stime of /proc/self/stat at 100 ticks/s.
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    let after = &stat[stat.rfind(')').expect("comm field") + 2..];
    let f: Vec<f64> = after.split_whitespace().map(|x| x.parse().unwrap_or(0.0)).collect();
    (f[11] + f[12]) / 100.0
}

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("../../../shared/data/ufrj-lavi-2018/run-175.csv");
    let text = std::fs::read_to_string(root.join("../../pipeline.toml")).expect("pipeline.toml");
    let v: toml::Value = toml::from_str(&text).expect("pipeline.toml parses");
    let st = v["stage"].as_array().expect("[[stage]]").iter().find(|s| s["name"].as_str() == Some("lavi"));
    let mut params = st.expect("a lavi stage")["params"].clone();
    params.as_table_mut().expect("params").insert("selection".into(), v["shared"]["selection"].clone());
    let p: rig_lavi::StudyParams = params.try_into().expect("the lavi stage's params");
    let c = cpu_s();
    let _ = rig_lavi::data::prepare(&path, &p).expect("run 175 reads");
    println!("prepare (read and repairs): CPU {:.2} s", cpu_s() - c);
    let (c0, w0) = (cpu_s(), std::time::Instant::now());
    let (s, _, _) = rig_lavi::study::analyse(&path, &p).expect("the study runs");
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
    let (c, w) = (cpu_s(), std::time::Instant::now());
    let _ = rig_lavi::run_study(&path, &p).expect("the study runs");
    println!("run_study (analyse and render): CPU {:.2} s, wall {:.2} s", cpu_s() - c, w.elapsed().as_secs_f64());
}

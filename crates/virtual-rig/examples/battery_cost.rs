//! What a battery's campaigns cost, case by case: generation and blind
//! diagnosis of every `STRIDE`-th case of a battery (from case `OFFSET`), one
//! case after the other (rayon inside each diagnosis), each with the CPU time
//! of its generation and of its diagnosis (/proc/self/stat, 10 ms ticks; wall
//! time is what other jobs on the shared cores inflate) and its answer to the
//! last bit (the shard slices' `ExactResult`), one JSON line per case. A
//! stride samples every group of the battery in proportion (the cases are in
//! group order), so its CPU total × stride estimates the whole battery's
//! (docs/performance.md, issue 23); two builds that print the same answers
//! diagnose alike.
//! `cargo run --workspace --example battery_cost -- [full|ci|smoke] [STRIDE] [OFFSET] [SEED] [--json DIR] [--count N]`
//! (SEED: the first case seed, 7000 as the confusion stage's; `--json DIR`
//! also writes each case's whole diagnosis JSON to `DIR/<case id>.json`, which
//! carries what `ExactResult` leaves out, e.g. the extension's fitted
//! parameters, so two builds can be compared number by number; `--count N`
//! stops after N cases, e.g. `full 1 73 --count 44` = the 11
//! `vocabulary_plus_outside` and 33 `outside` cases)
//! (the dev profile optimises the numeric crates; never --release, which rebuilds polars).

use rig_virtual_rig::battery::{Battery, DiagnosisResult, ExactResult};

/// CPU time (user + system) of this process so far, s (`rig_types::cpu`).
fn cpu_s() -> f64 {
    rig_types::cpu::process_cpu_s().expect("/proc/self/stat")
}

fn main() {
    let mut args: Vec<String> = std::env::args().collect();
    let json_dir = args.iter().position(|a| a == "--json").map(|i| {
        let dir = std::path::PathBuf::from(args.get(i + 1).expect("--json DIR"));
        args.drain(i..i + 2);
        std::fs::create_dir_all(&dir).expect("--json DIR: create");
        dir
    });
    let count = args.iter().position(|a| a == "--count").map(|i| {
        let n: usize = args.get(i + 1).and_then(|s| s.parse().ok()).expect("--count N");
        args.drain(i..i + 2);
        n
    });
    let name = args.get(1).map_or("ci", String::as_str);
    let stride: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1).max(1);
    let offset: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    // pipeline.toml's `[stage.params] seed` of the confusion stage.
    let seed: u64 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(7000);
    let battery = Battery::named(name, seed).expect("battery: full, ci or smoke");
    let opts =
        rig_diagnose::BlindChain::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis");
    let thesis = rig_calibrate::thesis_data(&rig_ingest::thesis::read_thesis_tables(&dir).expect("data/thesis"))
        .expect("thesis data");
    let (mut gen_total, mut diag_total, mut n) = (0.0, 0.0, 0);
    let w0 = std::time::Instant::now();
    for case in battery.cases.iter().skip(offset).step_by(stride).take(count.unwrap_or(usize::MAX)) {
        let c0 = cpu_s();
        let campaign = case.generate(&battery.protocol).expect("generate");
        let c1 = cpu_s();
        let value = rig_diagnose::diagnose_campaign(&campaign, Some(&thesis), &opts)
            .map_err(|e| e.to_string())
            .and_then(|d| serde_json::to_value(&d).map_err(|e| e.to_string()));
        let result = value
            .clone()
            .and_then(|v| serde_json::from_value::<DiagnosisResult>(v).map_err(|e| e.to_string()))
            .map(ExactResult::from);
        let c2 = cpu_s();
        if let (Some(dir), Ok(v)) = (&json_dir, &value) {
            let text = serde_json::to_string_pretty(v).expect("diagnosis JSON");
            std::fs::write(dir.join(format!("{}.json", case.id)), text + "\n").expect("--json DIR: write");
        }
        gen_total += c1 - c0;
        diag_total += c2 - c1;
        n += 1;
        let line = serde_json::json!({
            "case": case.id, "group": case.group.name(), "generate_cpu_s": c1 - c0, "diagnose_cpu_s": c2 - c1,
            "result": result,
        });
        println!("{line}");
    }
    eprintln!(
        "{name} battery, {n} of {} cases (every {stride}th from {offset}): generation {gen_total:.2} s CPU, \
         diagnosis {diag_total:.2} s CPU, {:.2} s wall; × {stride} ≈ {:.0} s CPU for the whole battery",
        battery.cases.len(),
        w0.elapsed().as_secs_f64(),
        (gen_total + diag_total) * stride as f64
    );
}

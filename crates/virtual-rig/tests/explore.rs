//! Exploration: prints the diagnosis of one generated campaign per class (not a CI test).

use rig_virtual_rig::{Hidden, Protocol, draw_truth, generate};

#[test]
#[ignore]
fn explore() {
    let classes: Vec<String> = std::env::var("CLASSES")
        .map(|s| s.split(',').map(String::from).collect())
        .unwrap_or_else(|_| Hidden::CLASSES.iter().map(|s| s.to_string()).collect());
    let seed: u64 = std::env::var("SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let proto = if std::env::var("FULL").is_ok() { Protocol::full() } else { Protocol::small() };
    for class in classes {
        let truth = draw_truth(&class, 130.0, seed);
        let t0 = std::time::Instant::now();
        let c = generate("explore", &truth, &proto, seed).unwrap();
        let tg = t0.elapsed();
        let cal = rig_calibrate::calibrate_campaign(&c).unwrap();
        let t1 = std::time::Instant::now();
        let d = rig_diagnose::diagnose(&c, &cal, None, None, &Default::default()).unwrap();
        println!("== {class} truth {:?} gen {:?} diag {:?}", truth.hidden, tg, t1.elapsed());
        println!("verdict {}  {}", d.verdict, d.detail.baseline_text);
        for s in &d.detail.scores {
            println!("  {:30} dBIC {:12.1} M {:.4} gain {:.3} sig {} | {}", s.0, s.1, s.2, s.3, s.4, s.5);
        }
        println!("  base M {:.4} floor {:.4} lines {:?}", d.detail.heldout_misfit_baseline, d.detail.heldout_misfit_noise_floor, d.detail.lines);
    }
}

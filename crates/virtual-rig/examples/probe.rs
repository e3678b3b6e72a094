//! Probe: diagnoses seeded virtual-rig campaigns (or a campaign folder) and
//! prints verdict, findings, adequacy ratio and timing — the tool used to
//! calibrate the diagnosis thresholds (rig-diagnose crate docs).
//! `cargo run -p rig-virtual-rig --example probe -- CLASS SEED [small|full]` (the dev
//! profile optimises the numeric crates; never --release, which rebuilds polars)
//! or `-- dir PATH`.

use rig_virtual_rig::{Protocol, draw_truth, generate};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opts =
        rig_diagnose::BlindChain::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml");
    let c = if args[1] == "dir" {
        rig_ingest::read_campaign(std::path::Path::new(&args[2])).expect("campaign")
    } else {
        let proto = if args.get(3).map(String::as_str) == Some("full") { Protocol::full() } else { Protocol::small() };
        let seed: u64 = args[2].parse().expect("seed");
        let truth = draw_truth(&args[1], 130.0, seed);
        println!("truth: {:?}", truth.hidden);
        generate("probe", &truth, &proto, seed).expect("generate")
    };
    let t0 = Instant::now();
    let d = rig_diagnose::diagnose_campaign(&c, None, &opts).expect("diagnosis");
    println!("verdict {} in {:.2} s", d.verdict, t0.elapsed().as_secs_f64());
    println!("adequacy {:?}", d.adequacy);
    for f in &d.findings {
        println!(
            "  {} {:?} gain {} ± {} ({} -> {}) crit {:?}",
            f.effect,
            f.params,
            f.relative_gain,
            f.relative_gain_fold_sd,
            f.heldout_misfit_baseline,
            f.heldout_misfit_extended,
            f.criterion
        );
        for s in &f.signature {
            println!("    sig {} {}", s.signal, s.heldout_gain);
        }
    }
    for r in &d.detail.steps {
        println!(
            "  step {} {:28} {:.4} -> {:.4} gain {:.3} ± {:.3} t {:.1} {}",
            r.step, r.effect, r.misfit_before, r.misfit_after, r.gain, r.gain_fold_sd, r.t, r.accepted
        );
    }
    println!("channels over noise {:?}, lines {:?}", d.detail.channel_over_noise, d.detail.lines);
}

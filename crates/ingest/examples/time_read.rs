//! Times read_campaign on a folder (default: the shipped campaign).
fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "data/emulated-rig-2026".into());
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let c = rig_ingest::read_campaign(std::path::Path::new(&dir)).unwrap();
        println!("{} runs in {:.3} s", c.runs.len(), t.elapsed().as_secs_f64());
    }
}

//! Wall and CPU time of each stage, written to `<out>/timings.json` by
//! `cargo xtask reproduce`. Timings are not reproducible, so they are kept out
//! of everything that is: not an artifact, not in `manifest.json`, not in the
//! cache records or any stage key, not compared by `cargo xtask diff`, and
//! git-ignored under reports/.

use crate::error::PipelineError;
use crate::runner::{Outcome, RunReport};
use crate::store;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Time one stage took.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timing {
    pub wall_s: f64,
    /// CPU time (user + system) of the whole process while the stage ran:
    /// with more than one job it includes the stages that ran alongside;
    /// `--jobs 1` attributes it exactly. `None` where /proc is unavailable.
    pub cpu_s: Option<f64>,
}

pub use rig_types::cpu::process_cpu_s;

/// Starts a stopwatch; [`Stopwatch::stop`] gives the [`Timing`] since.
pub struct Stopwatch {
    wall: std::time::Instant,
    cpu: Option<f64>,
}

impl Stopwatch {
    pub fn start() -> Self {
        Stopwatch { wall: std::time::Instant::now(), cpu: process_cpu_s() }
    }

    pub fn stop(&self) -> Timing {
        let cpu_s = self.cpu.zip(process_cpu_s()).map(|(a, b)| b - a);
        Timing { wall_s: self.wall.elapsed().as_secs_f64(), cpu_s }
    }
}

#[derive(Serialize)]
struct Timings<'a> {
    format: &'static str,
    note: &'static str,
    jobs: usize,
    total: Timing,
    stages: BTreeMap<&'a str, StageTiming<'a>>,
}

#[derive(Serialize)]
struct StageTiming<'a> {
    outcome: &'a str,
    #[serde(flatten)]
    timing: Timing,
}

fn outcome(o: &Outcome) -> &'static str {
    match o {
        Outcome::Ran => "ran",
        Outcome::UpToDate => "up to date",
        Outcome::WouldRun => "would run",
        Outcome::SkippedOptional | Outcome::SkippedEmpty | Outcome::SkippedOnDemand => "skipped",
        Outcome::Failed(_) => "failed",
        Outcome::Blocked { .. } => "blocked",
    }
}

/// Writes `<out>/timings.json` (temporary file + rename).
pub fn write(out_dir: &Path, report: &RunReport, jobs: usize) -> Result<PathBuf, PipelineError> {
    let t = Timings {
        format: "rig-lab-timings/1",
        note: "wall and CPU seconds of this run; not reproducible, not an artifact, not in manifest.json",
        jobs,
        total: report.total,
        stages: report
            .stages
            .iter()
            .map(|s| (s.name.as_str(), StageTiming { outcome: outcome(&s.outcome), timing: s.timing }))
            .collect(),
    };
    let path = out_dir.join("timings.json");
    let mut text = serde_json::to_string_pretty(&t)
        .map_err(|e| PipelineError::Json { path: path.clone(), reason: e.to_string() })?;
    text.push('\n');
    store::write_atomic(&path, text.as_bytes())?;
    Ok(path)
}

/// One line per stage that ran: wall and CPU seconds, then the total.
pub fn table(report: &RunReport) -> String {
    let cpu = |t: &Timing| t.cpu_s.map_or("-".to_string(), |c| format!("{c:8.2}"));
    let mut s = format!("{:<22} {:>8} {:>8}\n", "stage", "wall s", "CPU s");
    for st in report.stages.iter().filter(|s| matches!(s.outcome, Outcome::Ran | Outcome::UpToDate)) {
        s.push_str(&format!("{:<22} {:8.2} {}\n", st.name, st.timing.wall_s, cpu(&st.timing)));
    }
    s.push_str(&format!("{:<22} {:8.2} {}\n", "total", report.total.wall_s, cpu(&report.total)));
    s
}

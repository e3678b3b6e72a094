//! A battery's shards: one slice of its diagnoses per array task, their
//! answers stored to the bit ([`ExactResult`]), and the merge that rebuilds
//! the battery and judges every case again ([`merge_slices`]).

use super::{Battery, DiagnosisResult, Finding, Outcome, StructureAnswer};
use std::collections::BTreeMap;

/// One shard's diagnoses of a battery: enough to rebuild the battery
/// ([`Battery::named`]) and judge every case again after a merge.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BatterySlice {
    pub battery: String,
    pub seed: u64,
    pub total_cases: usize,
    pub shard_index: usize,
    pub shard_count: usize,
    pub results: Vec<CaseResult>,
}

/// The diagnosis of the case at `index` (its id, to check the rebuilt battery).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseResult {
    pub index: usize,
    pub id: String,
    pub result: Result<ExactResult, String>,
}

/// A [`DiagnosisResult`] whose parameters are stored as their f64 bit
/// patterns, so a slice read back gives the very same numbers (JSON's
/// decimal text need not round-trip every f64 in serde_json's default parser).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExactResult {
    pub verdict: String,
    pub findings: Vec<(String, BTreeMap<String, u64>)>,
    #[serde(default)]
    pub structure: Option<String>,
}

impl From<DiagnosisResult> for ExactResult {
    fn from(d: DiagnosisResult) -> Self {
        let findings = d
            .findings
            .into_iter()
            .map(|f| (f.effect, f.params.into_iter().map(|(k, v)| (k, v.to_bits())).collect()))
            .collect();
        ExactResult { verdict: d.verdict, findings, structure: d.structure.map(|s| s.damping) }
    }
}

impl From<ExactResult> for DiagnosisResult {
    fn from(e: ExactResult) -> Self {
        let findings = e
            .findings
            .into_iter()
            .map(|(effect, p)| Finding { effect, params: p.into_iter().map(|(k, v)| (k, f64::from_bits(v))).collect() })
            .collect();
        DiagnosisResult {
            verdict: e.verdict,
            findings,
            structure: e.structure.map(|damping| StructureAnswer { damping }),
        }
    }
}

/// Joins the slices of one battery's job array: the battery rebuilt from
/// its name and seed, and every case's outcome judged again, in the
/// battery's order. Refuses slices of different batteries, a case id that is
/// not the rebuilt battery's, and a set that misses or repeats a case.
pub fn merge_slices(slices: Vec<BatterySlice>) -> Result<(Battery, Vec<Outcome>), String> {
    let first = slices.first().ok_or("no battery slice to merge")?;
    let (name, seed, total) = (first.battery.clone(), first.seed, first.total_cases);
    if slices.iter().any(|s| s.battery != name || s.seed != seed || s.total_cases != total) {
        return Err("slices come from different batteries (name, seed or size differ)".into());
    }
    let battery = Battery::named(&name, seed).ok_or_else(|| format!("unknown battery {name:?}"))?;
    if battery.cases.len() != total {
        return Err(format!("battery {name} has {} cases, the slices {total}", battery.cases.len()));
    }
    let mut results: Vec<CaseResult> = slices.into_iter().flat_map(|s| s.results).collect();
    results.sort_by_key(|r| r.index);
    if results.len() != total || results.iter().enumerate().any(|(k, r)| r.index != k) {
        return Err("slices must cover every case exactly once (missing or duplicate shard)".into());
    }
    let mut outcomes = Vec::with_capacity(total);
    for (r, case) in results.into_iter().zip(&battery.cases) {
        if r.id != case.id {
            return Err(format!("case {} of the slices is {}, the battery's is {}", r.index, r.id, case.id));
        }
        outcomes.push(Outcome::new(case.clone(), r.result.map(DiagnosisResult::from)));
    }
    Ok((battery, outcomes))
}

//! A case's answer judged against its truth (issue 9's rule): the verdict,
//! every hidden vocabulary effect found within [`battery_tolerance`], and
//! nothing spurious.

use super::{Case, DiagnosisResult, Expected};
use crate::ids;
use rig_types::fmt_fixed;

/// Relative tolerance on a recovered parameter (issue 9: 25 %, frequencies
/// 5 %, the order exact).
pub fn battery_tolerance(param: &str) -> f64 {
    match param {
        "order" => 0.0,
        "frequency_hz" => 0.05,
        _ => 0.25,
    }
}

/// Whether the answer is right, and why not.
#[derive(Debug, Clone, PartialEq)]
pub struct Judgement {
    pub right: bool,
    /// Empty when right; otherwise every reason, `; `-separated.
    pub reason: String,
}

/// Scores a diagnosis of `case`: the verdict must be the expected one (any
/// effect of a compound; for a structural fault `unexplained`, or the
/// structure named among the findings with the verdict the structure or a
/// vocabulary effect of the truth), every vocabulary effect of the truth must
/// be among the findings with every parameter within [`battery_tolerance`],
/// and nothing that is not in the truth may be found (a structural finding
/// other than the truth's structure included).
pub fn judge(case: &Case, result: &Result<DiagnosisResult, String>) -> Judgement {
    let d = match result {
        Ok(d) => d,
        Err(e) => return Judgement { right: false, reason: format!("error: {e}") },
    };
    let mut why = Vec::new();
    // The truth's structural id, which a finding may name.
    let mut structure = None;
    let (required, verdict_ok) = match case.expected() {
        Expected::None => (vec![], d.verdict == "none"),
        Expected::Effects(e) => {
            let ok = e.iter().any(|x| *x == d.verdict);
            (e, ok)
        }
        Expected::Unexplained { partial } => (partial, d.verdict == ids::UNEXPLAINED),
        Expected::Structural { id, partial } => {
            let named = d.findings.iter().any(|f| f.effect == id)
                || d.structure.as_ref().is_some_and(|s| ids::damping_placements(id).contains(&s.damping.as_str()));
            let ok =
                d.verdict == ids::UNEXPLAINED || (named && (d.verdict == id || partial.contains(&d.verdict.as_str())));
            structure = Some(id);
            (partial, ok)
        }
    };
    if !verdict_ok {
        why.push(format!("verdict `{}`, expected `{}`", d.verdict, case.expected_verdict()));
    }
    for h in case.truth.hidden_all().into_iter().filter(|h| !h.is_outside()) {
        let Some(f) = d.findings.iter().find(|f| f.effect == h.id()) else {
            why.push(format!("{} not found", h.id()));
            continue;
        };
        for (k, truth) in h.params() {
            match f.params.get(k) {
                None => why.push(format!("{}.{k} missing", h.id())),
                Some(&est) => {
                    let rel = (est - truth).abs() / truth.abs();
                    let tol = battery_tolerance(k);
                    if rel.is_nan() || rel > tol + 1e-12 {
                        why.push(format!(
                            "{}.{k} = {} vs truth {} ({:.1} % off, tolerance {:.0} %)",
                            h.id(),
                            fmt_fixed(est, 4),
                            fmt_fixed(truth, 4),
                            100.0 * rel,
                            100.0 * tol
                        ));
                    }
                }
            }
        }
    }
    // A damping placement other than the rig model's, where the truth has none, is spurious.
    if let Some(s) = &d.structure {
        let truth_placements = structure.map_or(&[][..], ids::damping_placements);
        if s.damping != ids::DAMPING_TWIST_RATE && !truth_placements.contains(&s.damping.as_str()) {
            why.push(format!("spurious structure: damping on {}", s.damping));
        }
    }
    for f in &d.findings {
        if f.effect != ids::UNEXPLAINED
            && !required.contains(&f.effect.as_str())
            && Some(f.effect.as_str()) != structure
        {
            why.push(format!("spurious finding {}", f.effect));
        }
    }
    Judgement { right: why.is_empty(), reason: why.join("; ") }
}

/// One judged case.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    pub case: Case,
    pub result: Result<DiagnosisResult, String>,
    pub judgement: Judgement,
}

impl Outcome {
    pub fn new(case: Case, result: Result<DiagnosisResult, String>) -> Outcome {
        let judgement = judge(&case, &result);
        Outcome { case, result, judgement }
    }

    /// The verdict, or `error`.
    pub fn verdict(&self) -> &str {
        match &self.result {
            Ok(d) => &d.verdict,
            Err(_) => "error",
        }
    }
}

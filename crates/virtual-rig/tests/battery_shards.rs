//! The battery as a job array: shards run apart, written as JSON slices and
//! merged give the unsharded run's outputs byte for byte, on 1 or 2 threads;
//! a missing or repeated shard is refused.

use rig_virtual_rig::battery::{
    Battery, BatterySlice, Case, DiagnosisResult, Expected, Finding, battery_outputs, merge_slices,
};

/// Answers from the truth, with parameters that are no round decimals (so
/// the slices' JSON must carry every bit).
fn oracle(case: &Case) -> Result<DiagnosisResult, String> {
    let findings: Vec<Finding> = case
        .truth
        .hidden_all()
        .iter()
        .filter(|h| !h.is_outside())
        .map(|h| Finding {
            effect: h.id().into(),
            params: h.params().into_iter().map(|(k, v)| (k.into(), v * (1.0 + 1e-3 / 3.0))).collect(),
        })
        .collect();
    let verdict = match case.expected() {
        Expected::None => "none".to_string(),
        Expected::Effects(e) => e[0].to_string(),
        Expected::Unexplained { .. } | Expected::Structural { .. } => "unexplained".to_string(),
    };
    if case.id.starts_with("outside") {
        return Err("a diagnosis error travels too".into());
    }
    Ok(DiagnosisResult { verdict, findings, structure: None })
}

fn files(b: &Battery, out: &[rig_virtual_rig::battery::Outcome]) -> Vec<(&'static str, String)> {
    let (mut f, sheet) = battery_outputs(b, out);
    f.push(("sheet", format!("{sheet:?}")));
    f
}

#[test]
fn sharded_and_merged_battery_equals_the_unsharded_run() {
    let b = Battery::named("smoke", 7000).unwrap();
    assert_eq!(b.cases.len(), 4);
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let whole = pool(2).install(|| b.run(|c, _| oracle(c)));
    let whole_1 = pool(1).install(|| b.run(|c, _| oracle(c)));
    assert_eq!(whole, whole_1, "1 or 2 threads, the same outcomes");
    let expect = files(&b, &whole);
    let n = 3;
    let slices: Vec<BatterySlice> = (1..=n)
        .map(|i| {
            let s = b.run_slice(i, n, |c, _| oracle(c));
            serde_json::from_str(&serde_json::to_string_pretty(&s).unwrap()).unwrap()
        })
        .collect();
    let (merged_b, merged) = merge_slices(slices.iter().rev().cloned().collect()).unwrap();
    assert_eq!(merged_b, b);
    assert_eq!(merged, whole);
    assert_eq!(files(&merged_b, &merged), expect);
    let err = merge_slices(slices[..2].to_vec()).unwrap_err();
    assert!(err.contains("missing or duplicate shard"), "{err}");
    let mut twice = slices.clone();
    twice.push(slices[0].clone());
    assert!(merge_slices(twice).unwrap_err().contains("missing or duplicate shard"));
    let mut other = slices.clone();
    other[1].seed += 1;
    assert!(merge_slices(other).unwrap_err().contains("different batteries"));
}

#[test]
fn shards_are_interleaved_and_cover_every_case_once() {
    let b = Battery::named("ci", 7000).unwrap();
    let n = 4;
    let shards: Vec<Vec<usize>> = (1..=n).map(|i| b.shard_indices(i, n)).collect();
    // Case k in shard k mod n + 1: every shard samples the whole battery.
    for (i, s) in shards.iter().enumerate() {
        assert!(s.iter().all(|&k| k % n == i), "shard {}: {s:?}", i + 1);
    }
    let sizes: Vec<usize> = shards.iter().map(Vec::len).collect();
    assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1, "{sizes:?}");
    let mut all: Vec<usize> = shards.concat();
    all.sort_unstable();
    assert_eq!(all, (0..b.cases.len()).collect::<Vec<_>>());
}

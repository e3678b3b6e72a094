//! The battery's tables: confusion matrix, false-alarm rate with its exact
//! binomial interval, detection curves, wrong answers, and a Markdown report.

use super::{Battery, Group, Outcome};
use crate::confusion::VERDICTS;
use rig_types::{AxisScale, MarkerShape, Panel, SeriesStyle, Sheet, Table, band, figure, fmt_fixed, series};

/// Every table and text the `confusion` stage writes for `outcomes` of
/// `battery`, as (path under the out dir, table or text), in a fixed order,
/// and the detection sheet (`None` without ladder cases): one home for the
/// stage and for `cargo xtask merge-shards`, so a merged job array writes
/// the same bytes as an unsharded run.
pub fn battery_outputs(battery: &Battery, outcomes: &[Outcome]) -> (Vec<(&'static str, String)>, Option<Sheet>) {
    let detection = detection_table(outcomes);
    let sheet = detection_sheet(&detection, battery.name);
    let files = vec![
        ("tables/confusion-matrix.csv", confusion_table(outcomes).to_csv()),
        ("tables/confusion-false-alarms.csv", false_alarm_table(outcomes).to_csv()),
        ("tables/confusion-detection.csv", detection.to_csv()),
        ("tables/confusion-wrong.csv", wrong_table(outcomes).to_csv()),
        ("confusion.md", report_markdown(battery, outcomes)),
    ];
    (files, sheet)
}

/// Two-sided 95 % Clopper–Pearson interval of a binomial proportion k/n
/// (exact: the p at which P(X ≥ k) resp. P(X ≤ k) is 2.5 %).
pub fn clopper_pearson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    // P(X <= k | n, p), summed in logs.
    let cdf = |k: usize, p: f64| -> f64 {
        if p <= 0.0 {
            return 1.0;
        }
        if p >= 1.0 {
            return if k >= n { 1.0 } else { 0.0 };
        }
        let mut log_c = 0.0f64;
        let mut s = 0.0;
        for i in 0..=k.min(n) {
            if i > 0 {
                log_c += ((n - i + 1) as f64).ln() - (i as f64).ln();
            }
            s += (log_c + i as f64 * p.ln() + (n - i) as f64 * (1.0 - p).ln()).exp();
        }
        s.min(1.0)
    };
    let solve = |f: &dyn Fn(f64) -> f64| {
        // f increasing in p from < 0 to > 0.
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if f(mid) < 0.0 { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    };
    // Lower: P(X >= k | p) = 0.025, i.e. 1 − cdf(k − 1, p) = 0.025.
    let lower = if k == 0 { 0.0 } else { solve(&|p| (1.0 - cdf(k - 1, p)) - 0.025) };
    // Upper: P(X <= k | p) = 0.025 (cdf falls with p).
    let upper = if k >= n { 1.0 } else { solve(&|p| 0.025 - cdf(k, p)) };
    (lower, upper)
}

/// Rows: truth class (in battery order; ladder cases are left to
/// [`detection_table`]); columns: group, expected verdict, the count of each
/// verdict of [`VERDICTS`] and `other`, then n, right (judged) and its rate.
pub fn confusion_table(outcomes: &[Outcome]) -> Table {
    let mut cols = vec!["truth_class".to_string(), "group".to_string(), "expected".to_string()];
    cols.extend(VERDICTS.iter().map(|v| v.to_string()));
    cols.extend(["other", "n", "right", "right_rate"].map(String::from));
    let mut t = Table::new(cols);
    let mut classes: Vec<String> = Vec::new();
    for o in outcomes.iter().filter(|o| o.case.group != Group::Ladder) {
        let c = o.case.truth_class();
        if !classes.contains(&c) {
            classes.push(c);
        }
    }
    for class in classes {
        let rows: Vec<&Outcome> =
            outcomes.iter().filter(|o| o.case.group != Group::Ladder && o.case.truth_class() == class).collect();
        let mut r = vec![class, rows[0].case.group.name().to_string(), rows[0].case.expected_verdict()];
        for v in VERDICTS {
            r.push(rows.iter().filter(|o| o.verdict() == v).count().to_string());
        }
        r.push(rows.iter().filter(|o| !VERDICTS.contains(&o.verdict())).count().to_string());
        let right = rows.iter().filter(|o| o.judgement.right).count();
        r.push(rows.len().to_string());
        r.push(right.to_string());
        r.push(fmt_fixed(right as f64 / rows.len() as f64, 2));
        t.push(r);
    }
    t
}

/// The false-alarm rate on the effect-free campaigns, any verdict other than
/// `none` counting as an alarm, with its 95 % Clopper–Pearson interval: one
/// row per null group (`null`, `null_stick_slip`) present, then `all` when both are.
pub fn false_alarm_table(outcomes: &[Outcome]) -> Table {
    let mut t = Table::new(["group", "n_null", "alarms", "false_alarm_rate", "ci95_low", "ci95_high"]);
    let is_null = |g: Group| matches!(g, Group::Null | Group::NullStickSlip);
    let mut row = |name: &str, keep: &dyn Fn(Group) -> bool| {
        let nulls: Vec<&Outcome> = outcomes.iter().filter(|o| keep(o.case.group)).collect();
        let alarms = nulls.iter().filter(|o| o.verdict() != "none").count();
        let n = nulls.len();
        let (lo, hi) = clopper_pearson(alarms, n);
        let rate = if n == 0 { f64::NAN } else { alarms as f64 / n as f64 };
        t.push([
            name.to_string(),
            n.to_string(),
            alarms.to_string(),
            fmt_fixed(rate, 3),
            fmt_fixed(lo, 3),
            fmt_fixed(hi, 3),
        ]);
    };
    let groups: Vec<Group> = [Group::Null, Group::NullStickSlip]
        .into_iter()
        .filter(|g| outcomes.iter().any(|o| o.case.group == *g))
        .collect();
    for g in &groups {
        row(g.name(), &|x| x == *g);
    }
    if groups.len() != 1 {
        row("all", &is_null);
    }
    t
}

/// Per vocabulary effect and ladder rung: the probability that the answer is
/// right (judged as [`super::judge`]) against the effect's size, with its 95 %
/// Clopper–Pearson interval, and how often the effect was named at all.
pub fn detection_table(outcomes: &[Outcome]) -> Table {
    let mut t =
        Table::new(["effect", "step", "size_name", "size", "n", "named", "right", "p_right", "ci95_low", "ci95_high"]);
    let mut keys: Vec<(&'static str, usize, &'static str, f64)> = Vec::new();
    for o in outcomes {
        if let Some(r) = &o.case.rung
            && !keys.iter().any(|k| k.0 == r.effect && k.1 == r.step)
        {
            keys.push((r.effect, r.step, r.size_name, r.size));
        }
    }
    for (effect, step, size_name, size) in keys {
        let rows: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.case.rung.as_ref().is_some_and(|r| r.effect == effect && r.step == step))
            .collect();
        let named = rows
            .iter()
            .filter(|o| o.result.as_ref().is_ok_and(|d| d.findings.iter().any(|f| f.effect == effect)))
            .count();
        let right = rows.iter().filter(|o| o.judgement.right).count();
        let (lo, hi) = clopper_pearson(right, rows.len());
        t.push([
            effect.to_string(),
            step.to_string(),
            size_name.to_string(),
            fmt_fixed(size, 4),
            rows.len().to_string(),
            named.to_string(),
            right.to_string(),
            fmt_fixed(right as f64 / rows.len() as f64, 2),
            fmt_fixed(lo, 3),
            fmt_fixed(hi, 3),
        ]);
    }
    t
}

/// The detection limits as a sheet, one panel per vocabulary effect: the
/// probability of the right answer against the effect's size (filled
/// circles) with its 95 % Clopper–Pearson band, and how often the effect was
/// named at all (open squares). Sizes on a log axis, except the drive limit,
/// whose ladder is linear in limit / back-EMF. Drawn from the
/// [`detection_table`] `t`; `None` without ladder cases.
pub fn detection_sheet(t: &Table, battery: &str) -> Option<Sheet> {
    if t.rows.is_empty() {
        return None;
    }
    let num = |r: &Vec<String>, c: &str| -> f64 {
        let j = t.columns.iter().position(|x| x == c).expect("detection column");
        r[j].parse().unwrap_or(f64::NAN)
    };
    let mut effects: Vec<(String, String)> = Vec::new();
    for r in &t.rows {
        if !effects.iter().any(|e| e.0 == r[0]) {
            effects.push((r[0].clone(), r[2].clone()));
        }
    }
    let panels = effects
        .into_iter()
        .map(|(effect, size_name)| {
            let mut rows: Vec<&Vec<String>> = t.rows.iter().filter(|r| r[0] == effect).collect();
            rows.sort_by(|a, b| num(a, "size").total_cmp(&num(b, "size")));
            let x: Vec<f64> = rows.iter().map(|r| num(r, "size")).collect();
            let col = |c: &str| rows.iter().map(|r| num(r, c)).collect::<Vec<f64>>();
            let named: Vec<f64> = rows.iter().map(|r| num(r, "named") / num(r, "n")).collect();
            let spec = figure(
                &format!("battery-detection-{effect}"),
                &effect,
                "",
                (&size_name, 4),
                ("P(right answer) [-]", 2),
                vec![
                    band("95 % interval", &x, &col("ci95_low"), &col("ci95_high")),
                    series(
                        "right",
                        x.clone(),
                        col("p_right"),
                        SeriesStyle::Marker { shape: MarkerShape::Circle, filled: true },
                    ),
                    series(
                        "named",
                        x.clone(),
                        named,
                        SeriesStyle::Marker { shape: MarkerShape::Square, filled: false },
                    ),
                ],
            );
            let x_scale = if effect == crate::ids::DRIVE_VOLTAGE_LIMIT { AxisScale::Linear } else { AxisScale::Log10 };
            Panel { spec, x_scale }
        })
        .collect();
    Some(Sheet {
        id: "battery-detection".into(),
        title: format!("Detection limit per vocabulary effect (battery `{battery}`)"),
        caption: "Each vocabulary effect hidden alone at six sizes on the full protocol, three rigs drawn per size \
                  (seeded), each campaign diagnosed blind. Filled circles: the fraction of right answers (the \
                  effect named with its parameters within 25 %, frequencies 5 %, order exact, and nothing else); \
                  shaded: its 95 % Clopper–Pearson interval (three campaigns per size, so the interval is wide); \
                  open squares: the fraction of campaigns in which the effect was named at all. Sizes: the \
                  modulation amplitude ratio, the Stribeck excess (μs − μk)/μk, the viscous excess at 10 rad/s \
                  relative to μk (log axes), and the drive limit over the back-EMF n·k_e·Ω of the highest set-point \
                  (linear axis; above 1 the limit bites only under load, at 1.15 hardly)."
            .into(),
        columns: 2,
        panels,
    })
}

/// One row per wrong answer: case, truth class, expected, verdict, reason.
pub fn wrong_table(outcomes: &[Outcome]) -> Table {
    let mut t = Table::new(["case", "truth_class", "expected", "verdict", "reason"]);
    for o in outcomes.iter().filter(|o| !o.judgement.right) {
        t.push([
            o.case.id.clone(),
            o.case.truth_class(),
            o.case.expected_verdict(),
            o.verdict().to_string(),
            o.judgement.reason.clone(),
        ]);
    }
    t
}

/// A table as a Markdown table.
pub fn markdown_table(t: &Table) -> String {
    let mut s = format!("| {} |\n|{}\n", t.columns.join(" | "), "---|".repeat(t.columns.len()));
    for r in &t.rows {
        s.push_str(&format!("| {} |\n", r.join(" | ")));
    }
    s
}

/// The battery's report (Markdown): what was run, the false-alarm rate, the
/// confusion matrix, the detection curves and every wrong answer with its reason.
pub fn report_markdown(battery: &Battery, outcomes: &[Outcome]) -> String {
    let right = outcomes.iter().filter(|o| o.judgement.right).count();
    let p = &battery.protocol;
    let mut s = format!(
        "# Virtual-rig battery `{}`\n\n{} campaigns (protocol: {} operating points of {} s at {} Hz), each diagnosed \
         blind. Right = the expected verdict (any effect of a compound; `unexplained` when an effect outside the \
         vocabulary is hidden; for a structural fault `unexplained` or the structure named), every hidden vocabulary effect among the findings with its parameters within 25 % \
         (frequencies 5 %, order exact), and no other vocabulary effect. {} of {} answers are right.\n\n",
        battery.name,
        outcomes.len(),
        p.op_points.len(),
        p.op_duration_s,
        p.sample_rate_hz,
        right,
        outcomes.len()
    );
    s.push_str("## False alarms on effect-free rigs (95 % Clopper–Pearson interval)\n\n");
    s.push_str(&markdown_table(&false_alarm_table(outcomes)));
    s.push_str("\n## Confusion matrix (truth class × verdict)\n\n");
    s.push_str(&markdown_table(&confusion_table(outcomes)));
    let det = detection_table(outcomes);
    if !det.rows.is_empty() {
        s.push_str("\n## Detection limit per vocabulary effect (probability of the right answer vs size)\n\n");
        s.push_str(&markdown_table(&det));
    }
    let wrong = wrong_table(outcomes);
    if !wrong.rows.is_empty() {
        s.push_str("\n## Wrong answers\n\n");
        s.push_str(&markdown_table(&wrong));
    }
    s
}

//! The findings summary at the top of the page: the answer on the first
//! screen — the diagnosis' verdict, its findings with their held-out gains and
//! spread, structure, parameters pinned at a bound, adequacy (free run
//! included), the audit's counts and every other `*-diagnosis.json` of the out
//! dir (the real recordings) — one line each, linking to its section.
//!
//! It renders the fields of the diagnosis schema (`../shared/spec/diagnosis.md`)
//! that are present and says nothing of those absent; fields it does not know
//! inside `adequacy` are listed by name, so a new check is shown, not dropped.

use crate::markdown::escape;
use serde_json::Value;

/// A JSON number, a few significant digits (3, at least the integer part), no exponent.
pub(crate) fn num(x: f64) -> String {
    if !x.is_finite() {
        return x.to_string();
    }
    if x == 0.0 {
        return "0".into();
    }
    let digits_before = x.abs().log10().floor() as i32 + 1;
    let decimals = (3 - digits_before).clamp(0, 8) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// A fraction as a percentage with one decimal.
fn pct(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

/// A scalar JSON value as short text (numbers through [`num`]).
fn scalar(v: &Value) -> String {
    match v {
        Value::Number(n) => n.as_f64().map(num).unwrap_or_else(|| n.to_string()),
        Value::String(s) => s.clone(),
        Value::Bool(b) => if *b { "yes" } else { "no" }.into(),
        Value::Null => "—".into(),
        other => other.to_string(),
    }
}

fn f64_of(v: &Value, key: &str) -> Option<f64> {
    v.get(key).and_then(Value::as_f64)
}

/// "gain 95.6 % ± 0.7 % (fold s.d.)": the relative gain and, when given, its
/// spread (any `relative_gain_*sd` key: fold s.d., s.d.).
fn gain(v: &Value) -> Option<String> {
    let g = f64_of(v, "relative_gain")?;
    let mut s = format!("gain {}", pct(g));
    let spread = v
        .as_object()
        .and_then(|o| o.iter().find(|(k, x)| k.starts_with("relative_gain_") && k.ends_with("sd") && x.is_number()));
    if let Some((k, x)) = spread {
        let what = k.trim_start_matches("relative_gain_").trim_end_matches("sd").trim_end_matches('_');
        let what = if what.is_empty() { "s.d.".to_string() } else { format!("{} s.d.", what.replace('_', " ")) };
        s.push_str(&format!(" ± {} ({what})", pct(x.as_f64().unwrap_or(f64::NAN))));
    }
    Some(s)
}

/// One finding in a line: effect, parameters, gain with spread, held-out misfits.
fn finding(f: &Value) -> String {
    let effect = f.get("effect").map(scalar).unwrap_or_default();
    let mut parts = vec![format!("<code>{}</code>", escape(&effect))];
    if let Some(p) = f.get("params").and_then(Value::as_object).filter(|p| !p.is_empty() && p.len() <= 3) {
        let list: Vec<String> = p.iter().map(|(k, v)| format!("{} {}", escape(k), escape(&scalar(v)))).collect();
        parts.push(format!("({})", list.join(", ")));
    }
    if let Some(g) = gain(f) {
        parts.push(g);
    }
    // An unexplained finding's misfits are the whole chain's: its residual and signature say more.
    let misfits = (f64_of(f, "heldout_misfit_baseline"), f64_of(f, "heldout_misfit_extended"));
    if let (Some(a), Some(b), false) = (misfits.0, misfits.1, effect == "unexplained") {
        let runs = f.get("heldout_runs").and_then(Value::as_array).map(Vec::len);
        let over = runs.map(|n| format!(" on {n} held out")).unwrap_or_default();
        parts.push(format!("misfit {} → {}{over}", num(a), num(b)));
    }
    if effect == "unexplained" {
        if let Some(r) = f64_of(f, "residual_over_noise") {
            parts.push(format!("residual {} × noise", num(r)));
        }
        if let Some(top) = f.get("signature").and_then(Value::as_array).and_then(|s| s.first()) {
            let signal = top.get("signal").map(scalar).unwrap_or_default();
            let g = f64_of(top, "heldout_gain").map(|g| format!(" (held-out gain {})", pct(g))).unwrap_or_default();
            parts.push(format!("follows <code>{}</code>{g}", escape(&signal)));
        }
        if let Some(ext) = f.get("extension") {
            let g = gain(ext).map(|g| format!(": free-run {g}")).unwrap_or_default();
            let formula = ext.get("formula").map(scalar).unwrap_or_default();
            parts.push(format!("best extension <em>{}</em>{g}", escape(&formula)));
        }
    }
    parts.join(" ")
}

/// The adequacy object as one line: adequate or not, the residual against its
/// threshold, then every other field (a nested object, e.g. the free run, in brackets).
fn adequacy(a: &Value) -> String {
    let Some(o) = a.as_object() else { return escape(&scalar(a)) };
    let mut parts = Vec::new();
    match o.get("adequate").and_then(Value::as_bool) {
        Some(true) => parts.push("<strong>adequate</strong>".to_string()),
        Some(false) => parts.push("<strong>not adequate</strong>".to_string()),
        None => {}
    }
    if let Some(r) = f64_of(a, "residual_over_noise") {
        let t = f64_of(a, "threshold").map(|t| format!(" (threshold {})", num(t))).unwrap_or_default();
        parts.push(format!("residual {} × noise{t}", num(r)));
    }
    for (k, v) in o {
        if matches!(k.as_str(), "adequate" | "residual_over_noise" | "threshold") {
            continue;
        }
        match v {
            Value::Object(_) => parts.push(format!("{}: [{}]", escape(k), adequacy(v))),
            Value::Array(items) => parts.push(format!("{} {}", escape(k), items.len())),
            _ => parts.push(format!("{} {}", escape(k), escape(&scalar(v)))),
        }
    }
    parts.join(", ")
}

/// `structure` as one line: its fields, `notes` last.
fn structure(s: &Value) -> String {
    let Some(o) = s.as_object() else { return escape(&scalar(s)) };
    let parts: Vec<String> = o
        .iter()
        .filter(|(k, _)| k.as_str() != "notes")
        .map(|(k, v)| format!("{} <code>{}</code>", escape(k), escape(&scalar(v))))
        .collect();
    let mut s = parts.join(", ");
    if let Some(n) = o.get("notes") {
        s.push_str(&format!(" — {}", escape(&scalar(n))));
    }
    s
}

/// Every parameter pinned at a bound: name, bound and where it wanted to go.
fn at_bounds(list: &[Value]) -> String {
    let items: Vec<String> = list
        .iter()
        .map(|p| {
            let name = p.get("parameter").map(scalar).unwrap_or_default();
            let bound = p.get("bound").map(scalar).unwrap_or_default();
            let free =
                p.get("unconstrained").map(|u| format!(" (unconstrained {})", escape(&scalar(u)))).unwrap_or_default();
            format!("<code>{}</code> at {}{free}", escape(&name), escape(&bound))
        })
        .collect();
    items.join("; ")
}

/// One row of the summary: a linked heading and its line.
fn row(anchor: &str, head: &str, line: &str) -> String {
    format!("<tr><th><a href=\"#{}\">{}</a></th><td>{line}</td></tr>\n", escape(anchor), escape(head))
}

/// The rows a diagnosis JSON contributes. `full`: one row per field (the
/// campaign's own diagnosis); otherwise one row for the whole file.
pub(crate) fn diagnosis_rows(d: &Value, anchor: &str, head: &str, full: bool) -> String {
    let verdict = d.get("verdict").map(scalar).unwrap_or_else(|| "(no verdict field)".into());
    let findings: Vec<String> =
        d.get("findings").and_then(Value::as_array).map(|f| f.iter().map(finding).collect()).unwrap_or_default();
    let mut verdict_line = format!("<strong><code>{}</code></strong>", escape(&verdict));
    if !findings.is_empty() {
        let items: Vec<String> = findings.iter().map(|f| format!("<li>{f}</li>")).collect();
        verdict_line.push_str(&format!("<ul class=\"findings\">{}</ul>", items.concat()));
    }
    let mut extra: Vec<(&str, String)> = Vec::new();
    if let Some(s) = d.get("structure") {
        extra.push(("Structure", structure(s)));
    }
    if let Some(list) = d.get("parameters_at_bounds").and_then(Value::as_array) {
        let line = if list.is_empty() { "none".to_string() } else { at_bounds(list) };
        extra.push(("At a bound", line));
    }
    if let Some(a) = d.get("adequacy") {
        extra.push(("Adequacy", adequacy(a)));
    }
    // A free-run check the schema may carry beside `adequacy` rather than inside it.
    if let Some(o) = d.as_object() {
        for (k, v) in o.iter().filter(|(k, _)| k.starts_with("free_run")) {
            extra.push(("Free run", format!("{}: {}", escape(k), adequacy(v))));
        }
    }
    if full {
        let mut s = row(anchor, head, &verdict_line);
        for (h, line) in extra {
            s.push_str(&row(anchor, h, &line));
        }
        s
    } else {
        let mut line = verdict_line;
        for (h, l) in extra {
            line.push_str(&format!("<div>{h}: {l}</div>"));
        }
        row(anchor, head, &line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_three_significant_digits() {
        assert_eq!(num(7.4250361255190445), "7.43");
        assert_eq!(num(0.003329), "0.00333");
        assert_eq!(num(1234.6), "1235");
        assert_eq!(num(-47.75), "-47.8");
        assert_eq!(num(4.0), "4");
        assert_eq!(num(0.0), "0");
    }

    #[test]
    fn a_finding_shows_gain_spread_and_misfits() {
        let f: Value = serde_json::from_str(
            r#"{"effect":"normal_force_modulation","params":{"amplitude_ratio":0.15,"frequency_hz":1.9},
                "heldout_runs":["a","b"],"heldout_misfit_baseline":0.07533,"heldout_misfit_extended":0.003329,
                "relative_gain":0.9558,"relative_gain_fold_sd":0.0071}"#,
        )
        .unwrap();
        assert_eq!(
            finding(&f),
            "<code>normal_force_modulation</code> (amplitude_ratio 0.15, frequency_hz 1.9) \
             gain 95.6 % ± 0.7 % (fold s.d.) misfit 0.0753 → 0.00333 on 2 held out"
        );
    }

    #[test]
    fn unknown_adequacy_fields_are_listed_not_dropped() {
        let a: Value = serde_json::from_str(
            r#"{"residual_over_noise":1.38,"threshold":4.0,"adequate":true,
                "free_run":{"adequate":false,"worst_feature":"stick_fraction"}}"#,
        )
        .unwrap();
        assert_eq!(
            adequacy(&a),
            "<strong>adequate</strong>, residual 1.38 × noise (threshold 4), \
             free_run: [<strong>not adequate</strong>, worst_feature stick_fraction]"
        );
    }
}

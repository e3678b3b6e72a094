//! The `report` stage: its pipeline snapshot, and the page built from
//! hand-made out dirs (empty, and with one file of each kind) so it is
//! tested without the other stages.

use rig_pipeline::StageCtx;
use rig_types::{FigureSpec, Series, SeriesStyle};
use std::collections::BTreeMap;
use std::path::Path;

#[test]
#[ignore = "runs the whole pipeline upstream of the report; run with --ignored once every stage works"]
fn snap() {
    rig_pipeline::testing::snapshot_stage("report");
}

/// Runs the report body on `out` and returns what it staged.
fn run_report(out: &Path) -> BTreeMap<String, Vec<u8>> {
    let root = rig_pipeline::testing::workspace_root();
    let mut ctx = StageCtx::new(
        "report",
        &root.join("data/emulated-rig-2026"),
        &root.join("data/thesis"),
        None,
        out,
        toml::Table::new(),
    );
    let body = rig_pipeline::stages::lookup("report").expect("report is registered");
    body(&mut ctx).expect("the report stage succeeds");
    ctx.into_staged()
}

fn text(staged: &BTreeMap<String, Vec<u8>>, rel: &str) -> String {
    String::from_utf8(staged.get(rel).unwrap_or_else(|| panic!("{rel} not written")).clone()).unwrap()
}

fn write(out: &Path, rel: &str, bytes: &[u8]) {
    let p = out.join(rel);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(p, bytes).unwrap();
}

fn figure(id: &str, title: &str) -> FigureSpec {
    FigureSpec {
        id: id.into(),
        title: title.into(),
        caption: format!("Caption of {id} & more."),
        x_label: "time (s)".into(),
        y_label: "rotor speed (rad/s)".into(),
        series: vec![Series {
            name: "measured".into(),
            x: vec![0.0, 1.0, 2.0],
            y: vec![1.0, 0.5, 0.8],
            style: SeriesStyle::Line,
        }],
        x_decimals: 2,
        y_decimals: 2,
        heatmap: None,
    }
}

/// Writes the four files `StageCtx::write_figure` writes.
fn write_figure(out: &Path, spec: &FigureSpec) {
    write(out, &format!("figures/{}.svg", spec.id), rig_figures::render_svg(spec).unwrap().as_bytes());
    write(out, &format!("figures/{}.png", spec.id), &rig_figures::render_png(spec).unwrap());
    write(out, &format!("figures/{}.txt", spec.id), format!("{}\n\n{}\n", spec.title, spec.caption).as_bytes());
    write(out, &format!("figures/{}.csv", spec.id), rig_figures::series_csv(spec).as_bytes());
}

#[test]
fn empty_out_dir_gives_a_page_of_not_produced_notes() {
    let dir = tempfile::tempdir().unwrap();
    let staged = run_report(dir.path());
    assert_eq!(staged.keys().collect::<Vec<_>>(), ["figures.md", "index.html"]);
    let html = text(&staged, "index.html");
    for rel in ["audit.csv", "estimation.md", "diagnosis.json", "sweeps.md", "harmonic.md", "lavi.md", "confusion.md"] {
        assert!(html.contains(&format!("Not produced: <code>{rel}</code>")), "no note for {rel}");
    }
    assert!(html.contains("Not produced: <code>figures/fig-4-08*.svg</code> (stage <code>campaign-calibration</code>"));
    for n in 1..=29 {
        assert!(html.contains(&format!("id=\"fig-4.{n}\"")), "figure 4.{n} missing");
    }
    assert!(html.contains("cargo xtask reproduce --campaign DIR --out OUT"));
    // The summary comes first and says what is missing.
    assert!(html.find("<section id=\"summary\">").unwrap() < html.find("<nav>").unwrap());
    assert!(html.contains("<th><a href=\"#diagnosis\">Verdict</a></th><td class=\"missing\">not produced</td>"));
    assert!(html.contains("<th><a href=\"#audit\">Published numbers</a></th><td>not produced</td>"));
    let md = text(&staged, "figures.md");
    assert!(md.contains("| 4.1 | Test rig set-up. | not reproducible (photo) |  |  |"), "{md}");
    assert!(
        md.contains(
            "| 4.8 | Time-domain response rotor 1 with input voltage of 8 V. | not produced | campaign-calibration |  |"
        ),
        "{md}"
    );
}

#[test]
fn populated_out_dir_shows_audit_figures_and_diagnosis() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    write(out, "audit.csv", b"id,published,recomputed,status\nK_sA,0.268,0.2679,ok\nxi_1,0.094,0.0955,rounding\nJ_1E,0.0287,0.0293,inconsistent\n");
    write(out, "audit.md", b"# Audit\n\nThe chapter's **J_1E** does not follow from Eq. 4-4.\n");
    write(out, "estimation.md", b"## Fit\n\n| parameter | value |\n|---|---|\n| k_T | 0.126 |\n");
    write(
        out,
        "diagnosis.json",
        br#"{"campaign":"emulated-rig-2026","verdict":"normal_force_modulation",
            "findings":[{"effect":"normal_force_modulation","params":{"amplitude_ratio":0.2,"frequency_hz":1.3},
              "params_stderr":{"amplitude_ratio":0.01,"frequency_hz":0.002},"evidence":"a line at 1.3 Hz <not a tag>",
              "heldout_runs":["op-07","op-12"],"heldout_misfit_baseline":0.41,"heldout_misfit_extended":0.12,"relative_gain":0.71,
              "relative_gain_fold_sd":0.031}],
            "candidates":[{"effect":"velocity_weakening_friction","heldout_misfit_extended":0.39,"criterion":1234.5}],
            "structure":{"damping":"rotor_absolute","notes":"the damping acts on the rotor speed"},
            "parameters_at_bounds":[{"parameter":"shaft_damping_nm_s_rad","bound":0.0,"unconstrained":-0.245,"meaning":"m"}],
            "adequacy":{"residual_over_noise":1.38,"threshold":4.0,"adequate":true}}"#,
    );
    write(out, "tables/campaign-stiffness.csv", b"trial,k_nm_rad\n1,0.262\n");
    write(
        out,
        "lavi-diagnosis.json",
        br#"{"campaign":"ufrj-lavi-2018/run-175","verdict":"unexplained",
            "findings":[{"effect":"friction_law","relative_gain":0.7143,"heldout_misfit_baseline":7.42504,
              "heldout_misfit_extended":2.1208,"heldout_runs":["4-8","10-14"]},
             {"effect":"unexplained","residual_over_noise":1.64,
              "signature":[{"signal":"bit_speed_rad_s","heldout_gain":0.938}]}]}"#,
    );
    write(
        out,
        "slider-diagnosis.json",
        br#"{"campaign":"slider-2026","verdict":"none","findings":[],"adequacy":{"adequate":false}}"#,
    );
    write(out, "slider.md", b"# Slider\n\nThe slider rig's own report.\n");
    write(out, "broken-diagnosis.json", b"{not json");
    write_figure(out, &figure("fig-4-08-campaign", "Free decay"));
    write_figure(out, &figure("fig-4-17a", "Limit cycle (a)"));
    write_figure(out, &figure("overlay-op-01", "Overlay op-01"));

    let staged = run_report(out);
    let html = text(&staged, "index.html");
    // The findings summary: first, one linked row per item, every *-diagnosis.json picked up.
    let pos = |s: &str| html.find(s).unwrap_or_else(|| panic!("{s} missing"));
    assert!(pos("<section id=\"summary\">") < pos("<nav>"));
    assert!(pos("</section>") < pos("<nav>"));
    for row in [
        "<th><a href=\"#diagnosis\">Verdict</a></th><td><strong><code>normal_force_modulation</code></strong>\
         <ul class=\"findings\"><li><code>normal_force_modulation</code> (amplitude_ratio 0.2, frequency_hz 1.3) \
         gain 71.0 % ± 3.1 % (fold s.d.) misfit 0.41 → 0.12 on 2 held out</li></ul></td>",
        "<th><a href=\"#diagnosis\">Structure</a></th><td>damping <code>rotor_absolute</code> — the damping acts on the rotor speed</td>",
        "<th><a href=\"#diagnosis\">At a bound</a></th><td><code>shaft_damping_nm_s_rad</code> at 0 (unconstrained -0.245)</td>",
        "<th><a href=\"#diagnosis\">Adequacy</a></th><td><strong>adequate</strong>, residual 1.38 × noise (threshold 4)</td>",
        "<th><a href=\"#audit\">Published numbers</a></th><td><span class=\"ok\">1 ok</span> <span class=\"rounding\">1 rounding</span> \
         <span class=\"inconsistent\">1 inconsistent</span> <span class=\"note\">0 note</span> of 3",
        "<th><a href=\"#lavi\">Real data: ufrj-lavi-2018/run-175</a></th><td><strong><code>unexplained</code></strong>\
         <ul class=\"findings\"><li><code>friction_law</code> gain 71.4 % misfit 7.43 → 2.12 on 2 held out</li>\
         <li><code>unexplained</code> residual 1.64 × noise follows <code>bit_speed_rad_s</code> (held-out gain 93.8 %)</li></ul></td>",
        "<th><a href=\"#slider\">Real data: slider-2026</a></th><td><strong><code>none</code></strong>\
         <div>Adequacy: <strong>not adequate</strong></div></td>",
        "<th>broken</th><td class=\"missing\">broken-diagnosis.json is not valid JSON</td>",
    ] {
        assert!(
            html.contains(row),
            "summary row missing: {row}\n{}",
            &html[pos("<section id=\"summary\">")..pos("<nav>")]
        );
    }
    // Absent fields say nothing: the LAVI row has no structure, bound or adequacy part.
    let lavi_row = &html[pos("<th><a href=\"#lavi\">")..];
    let lavi_row = &lavi_row[..lavi_row.find("</tr>").unwrap()];
    assert!(!lavi_row.contains("structure") && !lavi_row.contains("adequacy") && !lavi_row.contains("bound"));
    // A diagnosis without a section of its own gets one, with its Markdown, listed in the contents.
    assert!(pos("<li><a href=\"#slider\">slider-2026</a></li>") < pos("<li><a href=\"#tables\">"));
    assert!(pos("<h2 id=\"slider\">slider-2026</h2>") < pos("<h2 id=\"tables\">"));
    assert!(html.contains("The slider rig&#39;s own report."));
    // Every summary link has its target on the page.
    let summary = &html[pos("<section id=\"summary\">")..pos("<nav>")];
    for (i, _) in summary.match_indices("href=\"#") {
        let id = &summary[i + 7..][..summary[i + 7..].find('"').unwrap()];
        assert!(html.contains(&format!("id=\"{id}\"")), "summary links to #{id}, which is not on the page");
    }
    assert!(html.contains("<tr class=\"ok\"><td>K_sA</td>"));
    assert!(html.contains("<tr class=\"rounding\"><td>xi_1</td>"));
    assert!(html.contains("<tr class=\"inconsistent\"><td>J_1E</td>"));
    assert!(html.contains(
        "1 ok</span> <span class=\"rounding\">1 rounding</span> <span class=\"inconsistent\">1 inconsistent</span> \
         <span class=\"note\">0 note</span> of 3 audited"
    ));
    assert!(html.contains("<strong>J_1E</strong> does not follow"));
    assert!(html.contains("<td>k_T</td><td>0.126</td>"));
    assert!(html.contains("Verdict: <strong><code>normal_force_modulation</code></strong>"));
    assert!(html.contains("a line at 1.3 Hz &lt;not a tag&gt;"), "JSON text is escaped");
    assert!(
        html.contains("<td><code>amplitude_ratio</code></td><td class=\"num\">0.2</td><td class=\"num\">0.01</td>")
    );
    assert!(html.contains("<th>effect</th><th>criterion</th><th>heldout_misfit_extended</th>"));
    assert!(html.contains("<code>tables/campaign-stiffness.csv</code> (1 rows)"));
    // Figures sit under their catalogue entry, the rest under "Further figures".
    assert!(pos("id=\"fig-4.8\"") < pos("<figure id=\"fig-4-08-campaign\">"));
    assert!(pos("<figure id=\"fig-4-08-campaign\">") < pos("id=\"fig-4.9\""));
    assert!(pos("id=\"fig-4.17\"") < pos("<figure id=\"fig-4-17a\">"));
    assert!(pos("id=\"more-figures\"") < pos("<figure id=\"overlay-op-01\">"));
    assert!(html.contains("<strong>Free decay</strong> Caption of fig-4-08-campaign &amp; more."));
    assert_eq!(html.matches("<svg").count(), 3);
    assert!(html.contains("data-figures=\"3\""));
    // Self-contained: the only URL is the SVG namespace; nothing is loaded.
    let urls: Vec<&str> =
        html.match_indices("http").map(|(i, _)| &html[i.saturating_sub(7)..(i + 40).min(html.len())]).collect();
    assert!(urls.iter().all(|u| u.starts_with("xmlns=\"http://www.w3.org/2000/svg\"")), "{urls:#?}");
    assert!(!html.contains("<link") && !html.contains(" src="));

    let md = text(&staged, "figures.md");
    assert!(md.contains("| 4.17 | Limit cycles of the numerical model of the test rig: (a) 54.5 RPM and 4.5 N, and (b) 122 RPM and 25 N. | reproduced | simulation | `fig-4-17a` |"), "{md}");

    // Deterministic bytes.
    assert_eq!(staged, run_report(out));
}

/// A tool, not a check: renders the report for an existing out dir (e.g. a
/// partial `cargo xtask reproduce --out DIR`) without running the upstream
/// stages, to look at the page while the pipeline is incomplete:
/// `RIG_REPORT_OUT=/tmp/out cargo test -p rig-pipeline --test snap_report -- --ignored render_existing`.
#[test]
#[ignore = "tool: needs RIG_REPORT_OUT"]
fn render_existing_out_dir() {
    let out = std::path::PathBuf::from(std::env::var("RIG_REPORT_OUT").expect("set RIG_REPORT_OUT to an out dir"));
    for (rel, bytes) in run_report(&out) {
        std::fs::write(out.join(rel), bytes).unwrap();
    }
}

//! What the sweeps study shows: the agreement table, the severity maps
//! ([`map_figure`], Fig. 4.16), the bifurcation diagrams ([`diagram_figure`],
//! Figs. 4.18, 4.20), the measured time responses (Figs. 4.19, 4.21) and
//! sweeps.md. The map and chain tables are in `tables.rs`.

use crate::operating::{Labelled, LabelledPoint, OpPoint};
use crate::study::{ModelSweeps, SweepsStudy};
use crate::{
    ChainResult, Classification, Direction, Point, SweepError, WindowSpec, chain_table, hysteresis, map_table,
};
use rig_types::sensor::encoder_speed_rad_s;
use rig_types::units::RAD_S_TO_RPM;
use rig_types::{
    AxisScale, Campaign, FigureSpec, Heatmap, MarkerShape, Panel, Run, Series, SeriesStyle, Sheet, Table, band,
    fmt_fixed,
};

/// Most points a time-response series gets.
const MAX_POINTS: usize = 2000;
/// Max and min of a window, for the diagrams' two series.
type Extreme = (&'static str, fn(&Classification) -> f64);
const EXTREMES: [Extreme; 2] = [("max", |k| k.max_rad_s), ("min", |k| k.min_rad_s)];

/// Every table and figure of the study, in the order the stage writes them.
pub struct SweepsOutput {
    /// (path relative to the out dir, table).
    pub tables: Vec<(String, Table)>,
    /// The severity-map tables: written with a Parquet twin beside the CSV.
    pub large_tables: Vec<(String, Table)>,
    pub figures: Vec<FigureSpec>,
    /// The bifurcation diagrams: one panel per model.
    pub sheets: Vec<Sheet>,
    /// sweeps.md.
    pub markdown: String,
}

/// Renders the whole study; `campaign` gives the recordings of the time responses.
pub fn outputs(study: &SweepsStudy, campaign: &Campaign) -> Result<SweepsOutput, SweepError> {
    let (models, ops, labels) = (&study.models, &study.ops, &study.labelled);
    let (mut tables, mut large_tables) = (Vec::new(), Vec::new());
    for m in models {
        large_tables.push((format!("tables/sweep-map-{}.csv", m.name), map_table(&m.map)));
        for (kind, chains) in [
            ("speed", &m.speed),
            ("friction", &m.friction),
            ("speed-campaign", &m.speed_campaign),
            ("friction-campaign", &m.friction_campaign),
        ] {
            tables.push((format!("tables/sweep-bifurcation-{kind}-{}.csv", m.name), chain_table(chains)));
        }
    }
    tables.push(("tables/sweep-agreement.csv".into(), agreement_table(ops, labels, models)));
    let mut figures = Vec::new();
    for m in models {
        for dir in [0, 1] {
            figures.push(map_figure(m, dir, ops, labels, &study.settings.window));
        }
    }
    let speed_fig = |id: &str, force: f64, pick: fn(&ModelSweeps) -> &Vec<ChainResult>| {
        diagram_figure(
            id,
            "motor speed MRPM [rpm]",
            models,
            pick,
            |p| p.motor_rpm,
            ops,
            |p| (p.normal_force_n - force).abs() < 0.5,
            &format!("{} N", fmt_fixed(force, 2)),
        )
    };
    let mut sheets = vec![
        speed_fig("fig-4-18", study.speed_sweep_force_n, |m| &m.speed),
        speed_fig("fig-4-18-campaign", study.campaign_force_n, |m| &m.speed_campaign),
    ];
    let friction_fig = |id: &str, rpm: f64, pick: fn(&ModelSweeps) -> &Vec<ChainResult>| {
        diagram_figure(
            id,
            "normal force Frict [N]",
            models,
            pick,
            |p| p.normal_force_n,
            ops,
            |p| (p.motor_rpm - rpm).abs() < 2.5,
            &format!("{} rpm", fmt_fixed(rpm, 1)),
        )
    };
    sheets.push(friction_fig("fig-4-20", study.friction_sweep_rpm, |m| &m.friction));
    sheets.push(friction_fig("fig-4-20-campaign", study.campaign_rpm, |m| &m.friction_campaign));
    let tpr = campaign.rig.encoder_ticks_per_rev;
    for (fig, target, id) in &study.chosen {
        let run = campaign.runs.iter().find(|r| &r.id == id).expect("chosen from the campaign's runs");
        let op = ops.iter().find(|o| &o.id == id).expect("every run has an op point");
        figures.push(time_response_figure(fig, *target, run, op, tpr)?);
    }
    Ok(SweepsOutput { tables, large_tables, figures, sheets, markdown: markdown(study) })
}

fn missing(run: &Run, column: &str) -> SweepError {
    SweepError::Analysis(format!("run {}: no {column}", run.id))
}

/// The map class of the grid point nearest to `p` (range-normalised distance), per direction.
fn nearest_map_label(m: &ModelSweeps, p: Point, dir: usize) -> String {
    let spec = &m.map.spec;
    let (sr, fr) = (range(&spec.speeds_rpm), range(&spec.forces_n));
    let near = |v: &[f64], x: f64, r: f64| {
        (0..v.len()).min_by(|&a, &b| ((v[a] - x) / r).abs().total_cmp(&((v[b] - x) / r).abs())).unwrap_or(0)
    };
    let (i, j) = (near(&spec.speeds_rpm, p.motor_rpm, sr), near(&spec.forces_n, p.normal_force_n, fr));
    let chain = &m.map.chains[2 * j + dir];
    let k = if dir == 0 { i } else { spec.speeds_rpm.len() - 1 - i };
    label(&chain.points[k].result)
}

fn range(v: &[f64]) -> f64 {
    (v.last().copied().unwrap_or(1.0) - v.first().copied().unwrap_or(0.0)).abs().max(f64::MIN_POSITIVE)
}

fn label(r: &Result<Classification, String>) -> String {
    r.as_ref().map(|c| c.regime.label()).unwrap_or_else(|_| "not converged".into())
}

fn yes(b: bool) -> String {
    if b { "yes" } else { "no" }.into()
}

/// `tables/sweep-agreement.csv`: every campaign run and labelled point, measured (or labelled) class
/// against both models simulated from rest and the nearest map cell of each sweep direction.
pub fn agreement_table(ops: &[OpPoint], labels: &[Labelled], models: &[ModelSweeps]) -> Table {
    let mut t = Table::new([
        "point",
        "source",
        "motor_rpm",
        "normal_force_n",
        "measured_class",
        "measured_severity_full",
        "thesis_class",
        "thesis_agree_vibration",
        "thesis_agree_class",
        "rig_class",
        "rig_agree_vibration",
        "rig_agree_class",
        "thesis_map_up",
        "thesis_map_down",
        "rig_map_up",
        "rig_map_down",
    ]);
    let maps = |p: Point| models.iter().flat_map(move |m| [nearest_map_label(m, p, 0), nearest_map_label(m, p, 1)]);
    for o in ops {
        let (m, th, rg) = (&o.measured.regime, &o.thesis.regime, &o.rig.regime);
        let mut row = vec![
            o.id.clone(),
            "campaign".into(),
            fmt_fixed(o.point.motor_rpm, 1),
            fmt_fixed(o.point.normal_force_n, 2),
            m.label(),
            fmt_fixed(o.measured.severity_full, 3),
            th.label(),
            yes(th.vibrating() == m.vibrating()),
            yes(th.label() == m.label()),
            rg.label(),
            yes(rg.vibrating() == m.vibrating()),
            yes(rg.label() == m.label()),
        ];
        row.extend(maps(o.point));
        t.push(row);
    }
    for Labelled { point: LabelledPoint { id, point: p, label: lab, source }, thesis: th, rig: rg } in labels {
        let vib = lab == "vibrating";
        let mut row = vec![
            id.clone(),
            format!("thesis {source}"),
            fmt_fixed(p.motor_rpm, 1),
            fmt_fixed(p.normal_force_n, 2),
            lab.clone(),
            String::new(),
            th.regime.label(),
            yes(th.regime.vibrating() == vib),
            String::new(),
            rg.regime.label(),
            yes(rg.regime.vibrating() == vib),
            String::new(),
        ];
        row.extend(maps(*p));
        t.push(row);
    }
    t
}

fn ok_points(c: &ChainResult) -> impl Iterator<Item = (Point, &Classification)> {
    c.points.iter().filter_map(|o| o.result.as_ref().ok().map(|k| (o.point, k)))
}

/// Heat map of severity (max − min)/mean over the map for one direction, with
/// the points where the other direction disagrees, and the measured points.
pub fn map_figure(m: &ModelSweeps, dir: usize, ops: &[OpPoint], labels: &[Labelled], w: &WindowSpec) -> FigureSpec {
    let spec = &m.map.spec;
    let (nx, ny) = (spec.speeds_rpm.len(), spec.forces_n.len());
    let mut z = vec![vec![0.0; nx]; ny];
    let mut failed = 0;
    let mut bistable = (Vec::new(), Vec::new());
    for (j, z_row) in z.iter_mut().enumerate() {
        let (up, down) = (&m.map.chains[2 * j], &m.map.chains[2 * j + 1]);
        let chain = if dir == 0 { up } else { down };
        for (k, o) in chain.points.iter().enumerate() {
            let i = if dir == 0 { k } else { nx - 1 - k };
            match &o.result {
                Ok(c) => z_row[i] = c.severity_full,
                Err(_) => failed += 1,
            }
        }
        for (p, _, _) in hysteresis(up, down) {
            bistable.0.push(p.motor_rpm);
            bistable.1.push(p.normal_force_n);
        }
    }
    // The map first: the bistable region hatched and outlined, measured and
    // labelled points as open markers (shape = source and class) over it.
    let mut series = vec![Series {
        name: "bistable: up ≠ down".into(),
        x: bistable.0,
        y: bistable.1,
        style: SeriesStyle::HatchCells,
    }];
    let open = |shape| SeriesStyle::Marker { shape, filled: false };
    for vib in [true, false] {
        let class = if vib { "vibrating" } else { "quiet" };
        let pts: Vec<&OpPoint> = ops.iter().filter(|o| o.measured.regime.vibrating() == vib).collect();
        series.push(Series {
            name: format!("measured {class}"),
            x: pts.iter().map(|o| o.point.motor_rpm).collect(),
            y: pts.iter().map(|o| o.point.normal_force_n).collect(),
            style: open(if vib { MarkerShape::Circle } else { MarkerShape::Diamond }),
        });
        let ls: Vec<&LabelledPoint> =
            labels.iter().map(|l| &l.point).filter(|l| (l.label == "vibrating") == vib).collect();
        series.push(Series {
            name: format!("thesis label {class}"),
            x: ls.iter().map(|l| l.point.motor_rpm).collect(),
            y: ls.iter().map(|l| l.point.normal_force_n).collect(),
            style: open(if vib { MarkerShape::Square } else { MarkerShape::TriangleUp }),
        });
    }
    let dname = if dir == 0 { "up" } else { "down" };
    FigureSpec {
        id: format!("fig-4-16-{}-{dname}", m.name),
        title: format!("Severity map of the {} model, motor speed swept {dname}", m.name),
        caption: format!(
            "Stick-slip severity (max − min)/mean of rotor speed over a {nx} × {ny} grid of motor set-point × \
             normal force (the chapter's Frict), {} model, each friction row swept {dname} in speed by \
             continuation (each point starts from the previous point's end state; {} s discarded after each \
             step, the next {} s classified). Hatched and outlined: grid cells where the up and down sweeps end \
             in different regimes (the bistable band). Open markers: campaign operating points classified from \
             their recordings by the same classifier (circle vibrating, diamond quiet; vibrating = any regime \
             but equilibrium); the chapter's labelled points (Figs. 4.17, 4.19, 4.21–4.24; square vibrating, \
             triangle quiet). {failed} grid points did not converge (shown as 0).",
            m.name,
            fmt_fixed(w.transient_s, 1),
            fmt_fixed(w.window_s, 1)
        ),
        x_label: "motor speed MRPM [rpm]".into(),
        y_label: "normal force Frict [N]".into(),
        series,
        x_decimals: 2,
        y_decimals: 3,
        heatmap: Some(Heatmap {
            x: spec.speeds_rpm.clone(),
            y: spec.forces_n.clone(),
            z,
            z_label: "severity (max − min)/mean [-]".into(),
        }),
    }
}

/// A bifurcation diagram as the field draws it: one panel per model, the
/// window's min and max rotor speed as points, swept up (filled triangles up)
/// and down (open triangles down), the parameter range where the two
/// directions end in different regimes shaded (the bistable band), and the
/// campaign runs on that line as open circles in every panel.
#[allow(clippy::too_many_arguments)]
pub fn diagram_figure(
    id: &str,
    x_label: &str,
    models: &[ModelSweeps],
    pick: fn(&ModelSweeps) -> &Vec<ChainResult>,
    x_of: fn(&Point) -> f64,
    ops: &[OpPoint],
    on_line: impl Fn(&Point) -> bool,
    fixed: &str,
) -> Sheet {
    let meas: Vec<&OpPoint> = ops.iter().filter(|o| on_line(&o.point)).collect();
    let ids: Vec<&str> = meas.iter().map(|o| o.id.as_str()).collect();
    let extremes = |k: &Classification| EXTREMES.map(|(_, f)| f(k) * RAD_S_TO_RPM);
    let measured = Series {
        name: "measured (campaign)".into(),
        x: meas.iter().flat_map(|o| [x_of(&o.point); 2]).collect(),
        y: meas.iter().flat_map(|o| extremes(&o.measured)).collect(),
        style: SeriesStyle::Marker { shape: MarkerShape::Circle, filled: false },
    };
    let panels = models
        .iter()
        .map(|m| {
            let chains = pick(m);
            let mut series = Vec::new();
            for dir in [Direction::Up, Direction::Down] {
                let pts: Vec<(Point, &Classification)> =
                    chains.iter().filter(|c| c.direction == dir).flat_map(ok_points).collect();
                let (shape, filled) = if dir == Direction::Up {
                    (MarkerShape::TriangleUp, true)
                } else {
                    (MarkerShape::TriangleDown, false)
                };
                series.push(Series {
                    name: format!("swept {}", dir.as_str()),
                    x: pts.iter().flat_map(|(p, _)| [x_of(p); 2]).collect(),
                    y: pts.iter().flat_map(|(_, k)| extremes(k)).collect(),
                    style: SeriesStyle::Marker { shape, filled },
                });
            }
            series.push(measured.clone());
            let top = series.iter().flat_map(|s| s.y.iter().copied()).filter(|y| y.is_finite()).fold(0.0, f64::max);
            series.extend(bistable_bands(chains, x_of, top));
            let spec = FigureSpec {
                id: format!("{id}-{}", m.name),
                title: format!("{} model", m.name),
                caption: String::new(),
                x_label: x_label.into(),
                y_label: "rotor speed RRPM min, max [rpm]".into(),
                series,
                x_decimals: 3,
                y_decimals: 2,
                heatmap: None,
            };
            Panel { spec, x_scale: AxisScale::Linear }
        })
        .collect();
    Sheet {
        id: id.into(),
        title: format!("Bifurcation diagram at {fixed}: min and max rotor speed, swept up and down"),
        caption: format!(
            "Minimum and maximum rotor-1 speed RRPM in the classification window at {fixed}, one panel per model \
             (thesis model as published, rig model), each swept up (filled triangles) and down (open triangles) by \
             continuation (each point starts from the previous point's end state). Grey: where the two \
             directions end in different regimes, the model is bistable. Open circles: campaign runs at {fixed} \
             ({}), min and max of the encoder-derived rotor speed over the last 20 s of the record. Where min and \
             max meet the rotor slides steadily; min at 0 is stick-slip.",
            if ids.is_empty() { "none in this campaign".to_string() } else { ids.join(", ") }
        ),
        columns: models.len().max(1),
        panels,
    }
}

/// The bistable band of an up/down pair of chains as shaded x-intervals from
/// 0 to `top`: each point where the directions disagree ([`hysteresis`])
/// covers half the step to its neighbours, and touching intervals merge. The
/// first band is named (so the legend has it even when the model has no
/// bistable point: an empty band); the others are not.
fn bistable_bands(chains: &[ChainResult], x_of: fn(&Point) -> f64, top: f64) -> Vec<Series> {
    let up = chains.iter().find(|c| c.direction == Direction::Up);
    let down = chains.iter().find(|c| c.direction == Direction::Down);
    let (Some(up), Some(down)) = (up, down) else { return vec![band("bistable (up ≠ down)", &[], &[], &[])] };
    let grid: Vec<f64> = up.points.iter().map(|o| x_of(&o.point)).collect();
    let half = |x: f64| {
        let k = grid.iter().position(|&g| g == x).unwrap_or(0);
        let lo = if k > 0 { 0.5 * (grid[k] - grid[k - 1]) } else { 0.0 };
        let hi = if k + 1 < grid.len() { 0.5 * (grid[k + 1] - grid[k]) } else { 0.0 };
        (x - lo, x + hi)
    };
    let mut spans: Vec<(f64, f64)> = Vec::new();
    for (p, _, _) in hysteresis(up, down) {
        let (a, b) = half(x_of(&p));
        match spans.last_mut() {
            Some(last) if a <= last.1 + 1e-9 => last.1 = last.1.max(b),
            _ => spans.push((a, b)),
        }
    }
    if spans.is_empty() {
        return vec![band("bistable (up ≠ down)", &[], &[], &[])];
    }
    spans
        .iter()
        .enumerate()
        .map(|(i, &(a, b))| band(if i == 0 { "bistable (up ≠ down)" } else { "" }, &[a, b], &[0.0, 0.0], &[top, top]))
        .collect()
}

fn thin(x: &[f64]) -> Vec<f64> {
    rig_spectra::thin_indices(x.len(), MAX_POINTS).into_iter().map(|i| x[i]).collect()
}

pub fn time_response_figure(
    id: &str,
    target: Point,
    run: &Run,
    op: &OpPoint,
    tpr: u32,
) -> Result<FigureSpec, SweepError> {
    let t = &run.data.time_s;
    let rotor = run.data.rotor_ticks.as_ref().ok_or_else(|| missing(run, "rotor_ticks"))?;
    let motor = run.data.motor_ticks.as_ref().ok_or_else(|| missing(run, "motor_ticks"))?;
    let rpm =
        |ticks: &[i64]| thin(&encoder_speed_rad_s(t, ticks, tpr).iter().map(|v| v * RAD_S_TO_RPM).collect::<Vec<_>>());
    Ok(FigureSpec {
        id: id.into(),
        title: format!(
            "Measured time response, run {} ({} rpm, {} N), nearest to the chapter's {} rpm, {} N",
            run.id,
            fmt_fixed(op.point.motor_rpm, 1),
            fmt_fixed(op.point.normal_force_n, 2),
            fmt_fixed(target.motor_rpm, 1),
            fmt_fixed(target.normal_force_n, 2)
        ),
        caption: format!(
            "Rotor speed RRPM and motor-side speed MRPM of campaign run {} (set-point {} rpm, normal force {} N), \
             the run nearest (range-normalised distance) to the chapter's point at {} rpm and {} N; the (b) panel \
             never reuses the (a) panel's run. Speeds from the encoders through the calibration differentiator \
             (±20 ms central difference and moving average), thinned to at most {MAX_POINTS} points. The same \
             classifier as the sweeps calls the last 20 s `{}` (severity (max − min)/mean {}).",
            run.id,
            fmt_fixed(op.point.motor_rpm, 1),
            fmt_fixed(op.point.normal_force_n, 2),
            fmt_fixed(target.motor_rpm, 1),
            fmt_fixed(target.normal_force_n, 2),
            op.measured.regime.label(),
            fmt_fixed(op.measured.severity_full, 3)
        ),
        x_label: "time [s]".into(),
        y_label: "speed [rpm]".into(),
        series: vec![
            Series { name: "rotor RRPM".into(), x: thin(t), y: rpm(rotor), style: SeriesStyle::Line },
            Series { name: "motor MRPM".into(), x: thin(t), y: rpm(motor), style: SeriesStyle::Dashed },
        ],
        x_decimals: 3,
        y_decimals: 2,
        heatmap: None,
    })
}

/// sweeps.md: the procedure, the bistable bands, the agreement with the measurements.
pub fn markdown(study: &SweepsStudy) -> String {
    let (models, ops, labels, chosen, s) = (&study.models, &study.ops, &study.labelled, &study.chosen, &study.settings);
    let w = &s.window;
    let mut md = String::from("# Sweeps: severity maps and bifurcation diagrams, up and down\n\n");
    md.push_str(&format!(
        "Every point of a sweep starts from the previous point's end state (continuation). After each parameter \
         step {} s are discarded (5 torsional periods of ≈ 2 s; the first point of a chain starts from rest and \
         gets {} s), then {} s are classified at {} Hz (3 to 10 stick-slip cycles). Classes: equilibrium \
         (peak-to-peak below max(0.5 rad/s, 10 % of the mean)), period-k (Poincaré section: peaks of Ω1 between \
         upward crossings of its mean, k clusters repeating), quasi-periodic (spectral line analysis finds an \
         incommensurate second base and explains every line) and chaotic (anything else); `stick-slip` when the \
         minimum speed falls to max(0.3 rad/s, 10 % of the mean). Severity in both conventions is in the tables \
         (`severity_half` = (max − min)/(2·mean), `severity_full` = (max − min)/mean).\n\n",
        fmt_fixed(w.transient_s, 1),
        fmt_fixed(w.first_transient_s, 1),
        fmt_fixed(w.window_s, 1),
        fmt_fixed(w.sample_rate_hz, 0)
    ));
    md.push_str("## Where up and down sweeps differ (the bistable band)\n\n");
    for m in models {
        for (what, chains) in [
            ("speed sweep (Fig. 4.18)", &m.speed),
            ("friction sweep (Fig. 4.20)", &m.friction),
            ("speed sweep, campaign force", &m.speed_campaign),
            ("friction sweep, campaign speed", &m.friction_campaign),
        ] {
            let h = hysteresis(&chains[0], &chains[1]);
            md.push_str(&format!("- {} model, {what}: ", m.name));
            if h.is_empty() {
                md.push_str("up and down agree everywhere.\n");
            } else {
                let (lo, hi) = (h.first().expect("not empty").0, h.last().expect("not empty").0);
                md.push_str(&format!(
                    "{} of {} points differ, from ({} rpm, {} N) to ({} rpm, {} N); e.g. up `{}` vs down `{}`.\n",
                    h.len(),
                    chains[0].points.len(),
                    fmt_fixed(lo.motor_rpm, 1),
                    fmt_fixed(lo.normal_force_n, 2),
                    fmt_fixed(hi.motor_rpm, 1),
                    fmt_fixed(hi.normal_force_n, 2),
                    h[0].1,
                    h[0].2
                ));
            }
        }
        let bistable: usize =
            (0..m.map.chains.len() / 2).map(|j| hysteresis(&m.map.chains[2 * j], &m.map.chains[2 * j + 1]).len()).sum();
        md.push_str(&format!(
            "- {} model, severity map: {} of {} grid points end in different regimes up and down.\n",
            m.name,
            bistable,
            m.map.spec.speeds_rpm.len() * m.map.spec.forces_n.len()
        ));
    }
    md.push_str("\n## Where the models agree with the measurements\n\n");
    md.push_str(
        "Campaign runs classified from their recordings and both models simulated from rest with the same \
         protocol (`tables/sweep-agreement.csv`):\n\n",
    );
    for (name, pick) in [("thesis", 0usize), ("rig", 1)] {
        let cls = |o: &OpPoint| if pick == 0 { o.thesis.regime } else { o.rig.regime };
        let vib = ops.iter().filter(|o| cls(o).vibrating() == o.measured.regime.vibrating()).count();
        let same = ops.iter().filter(|o| cls(o).label() == o.measured.regime.label()).count();
        let lab = labels
            .iter()
            .filter(|l| {
                (if pick == 0 { &l.thesis } else { &l.rig }).regime.vibrating() == (l.point.label == "vibrating")
            })
            .count();
        md.push_str(&format!(
            "- {name} model: vibrating/quiet agrees on {vib} of {} runs, exact class on {same}; the chapter's \
             labelled points: {lab} of {}.\n",
            ops.len(),
            labels.len()
        ));
        let miss: Vec<String> = ops
            .iter()
            .filter(|o| cls(o).vibrating() != o.measured.regime.vibrating())
            .map(|o| {
                format!(
                    "{} ({} rpm, {} N: measured `{}`, model `{}`)",
                    o.id,
                    fmt_fixed(o.point.motor_rpm, 1),
                    fmt_fixed(o.point.normal_force_n, 2),
                    o.measured.regime.label(),
                    cls(o).label()
                )
            })
            .collect();
        if !miss.is_empty() {
            md.push_str(&format!("  Disagree: {}.\n", miss.join("; ")));
        }
    }
    md.push_str("\n## Runs shown as Figs. 4.19 and 4.21\n\n");
    for (fig, target, run) in chosen {
        md.push_str(&format!(
            "- {fig}: run {} for the chapter's {} rpm, {} N.\n",
            run,
            fmt_fixed(target.motor_rpm, 1),
            fmt_fixed(target.normal_force_n, 2)
        ));
    }
    md
}

//! Loads data/thesis/*.csv for tests without rig-ingest (which pulls polars):
//! a minimal reader for these hand-written files; rig-ingest's reader is the
//! real one and is tested there and through the pipeline stage.

use rig_calibrate::published::*;
use std::path::Path;

fn split(line: &str) -> Vec<String> {
    let (mut cells, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    let mut it = line.chars().peekable();
    while let Some(c) = it.next() {
        match (quoted, c) {
            (true, '"') if it.peek() == Some(&'"') => {
                cur.push('"');
                it.next();
            }
            (true, '"') => quoted = false,
            (false, '"') => quoted = true,
            (false, ',') => cells.push(std::mem::take(&mut cur)),
            (_, c) => cur.push(c),
        }
    }
    cells.push(cur);
    cells
}

fn rows(name: &str) -> Vec<std::collections::BTreeMap<String, String>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis").join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let head = split(lines.next().unwrap());
    lines.map(|l| head.iter().cloned().zip(split(l)).collect()).collect()
}

fn p(s: &str) -> Printed {
    let (m, e) = s.split_once('e').map(|(m, e)| (m, e.parse::<i32>().unwrap())).unwrap_or((s, 0));
    let dec = m.split_once('.').map(|(_, f)| f.len() as i32).unwrap_or(0) - e;
    Printed { value: s.parse().unwrap(), decimals: dec }
}

fn po(s: &str) -> Option<Printed> {
    if s.is_empty() { None } else { Some(p(s)) }
}

fn params(name: &str) -> Vec<ParamRow> {
    rows(name)
        .into_iter()
        .map(|r| ParamRow {
            symbol: r["symbol"].clone(),
            description: r["description"].clone(),
            value: p(&r["value"]),
            unit: r["unit"].clone(),
        })
        .collect()
}

pub fn thesis_tables() -> ThesisTables {
    ThesisTables {
        table_4_1: params("table-4-1.csv"),
        table_4_2: rows("table-4-2.csv")
            .into_iter()
            .map(|r| DecayRow {
                trial: r["trial"].clone(),
                x1_rad: p(&r["x1_rad"]),
                x2_rad: p(&r["x2_rad"]),
                log_decrement: p(&r["log_decrement"]),
                damping_ratio: p(&r["damping_ratio"]),
                damped_hz: p(&r["damped_hz"]),
                natural_hz: p(&r["natural_hz"]),
            })
            .collect(),
        table_4_3: rows("table-4-3.csv")
            .into_iter()
            .map(|r| StiffnessRow {
                trial: r["trial"].clone(),
                torque_nm: po(&r["torque_nm"]),
                angle_rad: po(&r["angle_rad"]),
                k_se_nm_rad: p(&r["k_se_nm_rad"]),
                rel_error_pct: p(&r["rel_error_pct"]),
            })
            .collect(),
        table_4_4: params("table-4-4.csv"),
        table_4_5: params("table-4-5.csv"),
        table_4_6: rows("table-4-6.csv")
            .into_iter()
            .map(|r| ForceRow {
                trial: r["trial"].clone(),
                weight_n: po(&r["weight_n"]),
                voltage_mv: po(&r["voltage_mv"]),
                factor_mv_per_n: p(&r["factor_mv_per_n"]),
            })
            .collect(),
        table_4_7: rows("table-4-7.csv")
            .into_iter()
            .map(|r| FrictionRow {
                symbol: r["symbol"].clone(),
                description: r["description"].clone(),
                value: p(&r["value"]),
                setpoint_relation: r["setpoint_relation"].clone(),
                setpoint_rpm: p(&r["setpoint_rpm"]),
            })
            .collect(),
        table_4_8: rows("table-4-8.csv")
            .into_iter()
            .map(|r| PeakRow { peak: r["peak"].clone(), freq_hz: p(&r["freq_hz"]), freq_rad_s: p(&r["freq_rad_s"]) })
            .collect(),
        statements: rows("equations.csv")
            .into_iter()
            .map(|r| Statement {
                id: r["id"].clone(),
                symbol: r["symbol"].clone(),
                value: p(&r["value"]),
                unit: r["unit"].clone(),
                location: r["where"].clone(),
                statement: r["statement"].clone(),
            })
            .collect(),
        labelled_points: rows("labelled-operating-points.csv")
            .into_iter()
            .map(|r| LabelledPoint {
                figure: r["figure"].clone(),
                panel: r["panel"].clone(),
                motor_rpm: r["motor_rpm"].parse().unwrap(),
                frict_n: r["frict_n"].parse().unwrap(),
                label: r["label"].clone(),
                source: r["source"].clone(),
            })
            .collect(),
    }
}

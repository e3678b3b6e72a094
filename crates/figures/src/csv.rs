//! The figure's data as long-format CSV (`series,x,y`), rounded to the
//! decimals the spec says the data supports: the text snapshots and
//! `xtask diff` compare.

use rig_types::{FigureSpec, Sheet, Table, fmt_fixed};

/// Long-format CSV: one row per point, `series,x,y`, x and y formatted by
/// [`fmt_fixed`] at `x_decimals` / `y_decimals`; a non-finite value is
/// written as `NaN` (it is a gap in the plotted line).
///
/// A heat map adds a `z` column (empty on series rows) and one row per cell,
/// series `heatmap`, in row-major order (y outer, x inner). FigureSpec has no
/// z precision, so z is written with four significant digits relative to the
/// largest |z|: enough to see a moved cell, not so many that solver noise
/// shows.
pub fn series_csv(spec: &FigureSpec) -> String {
    spec_table(spec).to_csv()
}

/// A sheet's data: every panel's [`series_csv`] rows with a leading `panel`
/// column (the panel's title), panels in order; `z` present when any panel
/// has a heat map.
pub fn sheet_csv(sheet: &Sheet) -> String {
    let with_z = sheet.panels.iter().any(|p| p.spec.heatmap.is_some());
    let mut cols = vec!["panel", "series", "x", "y"];
    if with_z {
        cols.push("z");
    }
    let mut out = Table::new(cols);
    for p in &sheet.panels {
        for mut row in spec_table(&p.spec).rows {
            if with_z && row.len() == 3 {
                row.push(String::new());
            }
            out.push(std::iter::once(p.spec.title.clone()).chain(row));
        }
    }
    out.to_csv()
}

fn spec_table(spec: &FigureSpec) -> Table {
    let fmt = |v: f64, d: usize| if v.is_finite() { fmt_fixed(v, d) } else { "NaN".to_string() };
    let with_z = spec.heatmap.is_some();
    let mut table = if with_z { Table::new(["series", "x", "y", "z"]) } else { Table::new(["series", "x", "y"]) };
    for s in &spec.series {
        for (&x, &y) in s.x.iter().zip(&s.y) {
            let mut row = vec![s.name.clone(), fmt(x, spec.x_decimals), fmt(y, spec.y_decimals)];
            if with_z {
                row.push(String::new());
            }
            table.push(row);
        }
    }
    if let Some(h) = &spec.heatmap {
        let z_decimals = z_decimals(&h.z);
        for (row, &y) in h.z.iter().zip(&h.y) {
            for (&z, &x) in row.iter().zip(&h.x) {
                table.push([
                    "heatmap".to_string(),
                    fmt(x, spec.x_decimals),
                    fmt(y, spec.y_decimals),
                    fmt(z, z_decimals),
                ]);
            }
        }
    }
    table
}

/// Decimals giving four significant digits for the largest finite |z|.
fn z_decimals(z: &[Vec<f64>]) -> usize {
    let max_abs = z.iter().flatten().filter(|v| v.is_finite()).fold(0.0_f64, |m, v| m.max(v.abs()));
    if max_abs == 0.0 {
        return 0;
    }
    (3.0 - max_abs.log10().floor()).clamp(0.0, 12.0) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig_types::{Heatmap, Series, SeriesStyle};

    fn spec(heatmap: Option<Heatmap>) -> FigureSpec {
        FigureSpec {
            id: "t".into(),
            title: "t".into(),
            caption: String::new(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: vec![Series {
                name: "a, b".into(),
                x: vec![0.0, 0.126, 1.0],
                y: vec![-0.0001, f64::NAN, 2.5],
                style: SeriesStyle::Line,
            }],
            x_decimals: 2,
            y_decimals: 1,
            heatmap,
        }
    }

    #[test]
    fn rounds_quotes_and_marks_gaps() {
        assert_eq!(series_csv(&spec(None)), "series,x,y\n\"a, b\",0.00,0.0\n\"a, b\",0.13,NaN\n\"a, b\",1.00,2.5\n");
    }

    #[test]
    fn heatmap_cells_follow_series_rows() {
        let h = Heatmap { x: vec![1.0, 2.0], y: vec![10.0], z: vec![vec![12.3456, 0.5]], z_label: "z".into() };
        assert_eq!(
            series_csv(&spec(Some(h))),
            "series,x,y,z\n\"a, b\",0.00,0.0,\n\"a, b\",0.13,NaN,\n\"a, b\",1.00,2.5,\nheatmap,1.00,10.0,12.35\nheatmap,2.00,10.0,0.50\n"
        );
    }
}

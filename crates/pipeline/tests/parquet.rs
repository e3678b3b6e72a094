//! Every Parquet table the pipeline writes, read back with polars, holds the
//! values of its CSV twin: same columns, same rows, and each cell equal to
//! the CSV text read by polars' own CSV reader (all columns as text).

use polars::prelude::*;
use std::io::Cursor;

fn csv_as_text(path: &std::path::Path) -> DataFrame {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    CsvReadOptions::default()
        .with_has_header(true)
        .with_infer_schema_length(Some(0))
        .map_parse_options(|p| p.with_missing_is_null(false))
        .into_reader_with_file_handle(Cursor::new(bytes))
        .finish()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn same_value(parquet: &Column, i: usize, text: &str) -> bool {
    let v = parquet.get(i).unwrap();
    match v {
        AnyValue::Null => text.is_empty(),
        AnyValue::Int64(x) => text.parse::<i64>() == Ok(x),
        AnyValue::Float64(x) => text.parse::<f64>().is_ok_and(|t| t == x || (t.is_nan() && x.is_nan())),
        AnyValue::Boolean(b) => text == if b { "true" } else { "false" },
        AnyValue::String(s) => s == text,
        other => panic!("unexpected Parquet value {other:?}"),
    }
}

#[test]
fn parquet_tables_match_their_csv() {
    let out = rig_pipeline::testing::shared_outputs(&["diagnosis"]);
    let tables = out.dir.join("tables");
    let mut checked = Vec::new();
    let mut names: Vec<_> = std::fs::read_dir(&tables).unwrap().map(|e| e.unwrap().path()).collect();
    names.sort();
    for path in names.into_iter().filter(|p| p.extension().is_some_and(|e| e == "parquet")) {
        let bytes = std::fs::read(&path).unwrap();
        let pq = ParquetReader::new(Cursor::new(bytes)).finish().unwrap();
        let csv = csv_as_text(&path.with_extension("csv"));
        assert_eq!(pq.get_column_names(), csv.get_column_names(), "{}", path.display());
        assert_eq!(pq.height(), csv.height(), "{}", path.display());
        for (p, c) in pq.columns().iter().zip(csv.columns()) {
            let c = c.str().unwrap();
            for i in 0..pq.height() {
                let text = c.get(i).unwrap_or("");
                assert!(
                    same_value(p, i, text),
                    "{} column {} row {i}: Parquet {:?}, CSV {text:?}",
                    path.display(),
                    p.name(),
                    p.get(i)
                );
            }
        }
        checked.push(path.file_name().unwrap().to_string_lossy().to_string());
    }
    for must in ["diagnosis-runs.parquet", "diagnosis-speed-traces.parquet"] {
        assert!(checked.iter().any(|c| c == must), "{must} not written (checked {checked:?})");
    }
}

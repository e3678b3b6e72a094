//! A [`Table`] as Parquet, written with polars: the same cells as its CSV,
//! typed per column, for readers who load the large tables into polars or
//! pandas. The CSV stays the text artifact snapshots pin.
//!
//! Column types are read off the cells: every non-empty cell an integer →
//! Int64; every non-empty cell a number (`NaN` included) → Float64; every
//! non-empty cell `true`/`false` → Boolean; otherwise String. An empty cell
//! is null in a typed column and "" in a String column. Column names are the
//! CSV's (they carry the units: `motor_rpm`, `normal_force_n`).
//!
//! The bytes depend only on the table: uncompressed pages, no statistics, no
//! key-value metadata; polars writes no clock time, so two runs give the same file.

use anyhow::Result;
use polars::prelude::*;
use rig_types::Table;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Int,
    Float,
    Bool,
    Text,
}

fn kind_of(cells: &[&str]) -> Kind {
    let filled: Vec<&str> = cells.iter().copied().filter(|c| !c.is_empty()).collect();
    if filled.is_empty() {
        Kind::Text
    } else if filled.iter().all(|c| c.parse::<i64>().is_ok()) {
        Kind::Int
    } else if filled.iter().all(|c| c.parse::<f64>().is_ok()) {
        Kind::Float
    } else if filled.iter().all(|c| *c == "true" || *c == "false") {
        Kind::Bool
    } else {
        Kind::Text
    }
}

/// The table as a typed polars frame (see the module docs for the types).
pub fn table_frame(table: &Table) -> Result<DataFrame> {
    let columns: Vec<Column> = table
        .columns
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let cells: Vec<&str> = table.rows.iter().map(|r| r[j].as_str()).collect();
            let name = PlSmallStr::from(name.as_str());
            let series = match kind_of(&cells) {
                Kind::Int => {
                    Series::new(name, cells.iter().map(|c| c.parse::<i64>().ok()).collect::<Vec<Option<i64>>>())
                }
                Kind::Float => {
                    Series::new(name, cells.iter().map(|c| c.parse::<f64>().ok()).collect::<Vec<Option<f64>>>())
                }
                Kind::Bool => {
                    Series::new(name, cells.iter().map(|c| c.parse::<bool>().ok()).collect::<Vec<Option<bool>>>())
                }
                Kind::Text => Series::new(name, cells.to_vec()),
            };
            series.into_column()
        })
        .collect();
    DataFrame::new(table.rows.len(), columns).map_err(|e| anyhow::anyhow!("building the polars frame of a table: {e}"))
}

/// Parquet bytes of the table.
pub fn table_parquet(table: &Table) -> Result<Vec<u8>> {
    let mut df = table_frame(table)?;
    let mut out = Vec::new();
    ParquetWriter::new(&mut out)
        .with_compression(ParquetCompression::Uncompressed)
        .with_statistics(StatisticsOptions::empty())
        .finish(&mut df)
        .map_err(|e| anyhow::anyhow!("writing Parquet: {e}"))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Table {
        let mut t = Table::new(["run", "fold", "motor_rpm", "stick_slip", "note"]);
        t.push(["op-01", "2", "20.0", "true", ""]);
        t.push(["op-02", "", "NaN", "false", "a, b"]);
        t
    }

    #[test]
    fn columns_are_typed_and_bytes_repeat() {
        let a = table_parquet(&table()).unwrap();
        assert_eq!(a, table_parquet(&table()).unwrap());
        let df = ParquetReader::new(std::io::Cursor::new(a)).finish().unwrap();
        let types: Vec<DataType> = df.dtypes();
        assert_eq!(
            types,
            vec![DataType::String, DataType::Int64, DataType::Float64, DataType::Boolean, DataType::String]
        );
        assert_eq!(df.column("fold").unwrap().i64().unwrap().get(1), None);
        assert!(df.column("motor_rpm").unwrap().f64().unwrap().get(1).unwrap().is_nan());
        assert_eq!(df.column("note").unwrap().str().unwrap().get(1), Some("a, b"));
    }
}

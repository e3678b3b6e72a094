//! The chapter's published tables (plain data in `rig_types::thesis`, read by
//! `rig_ingest::thesis` from data/thesis/*.csv) and look-ups into them.

use crate::CalibrateError;
pub use rig_types::thesis::*;

fn missing(table: &str, what: &str) -> CalibrateError {
    CalibrateError::Published { table: table.to_string(), reason: format!("row `{what}` is missing") }
}

/// A parameter by symbol.
pub fn param<'a>(rows: &'a [ParamRow], table: &str, symbol: &str) -> Result<&'a ParamRow, CalibrateError> {
    rows.iter().find(|r| r.symbol == symbol).ok_or_else(|| missing(table, symbol))
}

/// Look-ups by symbol or id, with an error naming the file and the missing row.
pub trait PublishedTables {
    fn statement(&self, id: &str) -> Result<&Statement, CalibrateError>;
    fn t41(&self, symbol: &str) -> Result<Printed, CalibrateError>;
    fn t44(&self, symbol: &str) -> Result<Printed, CalibrateError>;
    fn t45(&self, symbol: &str) -> Result<Printed, CalibrateError>;
    fn friction(&self, symbol: &str) -> Result<&FrictionRow, CalibrateError>;
}

impl PublishedTables for ThesisTables {
    fn statement(&self, id: &str) -> Result<&Statement, CalibrateError> {
        self.statements.iter().find(|s| s.id == id).ok_or_else(|| missing("equations.csv", id))
    }
    fn t41(&self, symbol: &str) -> Result<Printed, CalibrateError> {
        Ok(param(&self.table_4_1, "table-4-1.csv", symbol)?.value)
    }
    fn t44(&self, symbol: &str) -> Result<Printed, CalibrateError> {
        Ok(param(&self.table_4_4, "table-4-4.csv", symbol)?.value)
    }
    fn t45(&self, symbol: &str) -> Result<Printed, CalibrateError> {
        Ok(param(&self.table_4_5, "table-4-5.csv", symbol)?.value)
    }
    fn friction(&self, symbol: &str) -> Result<&FrictionRow, CalibrateError> {
        self.table_4_7.iter().find(|r| r.symbol == symbol).ok_or_else(|| missing("table-4-7.csv", symbol))
    }
}

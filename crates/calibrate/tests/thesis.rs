//! The thesis side on the shipped data/thesis tables: recomputed tables and
//! the audit, pinned as CSV text after checking the values (see each test).

mod common;

use rig_calibrate::{Status, audit, thesis_outputs};

fn check(name: &str, csv: String) {
    insta::assert_snapshot!(name, csv);
}

#[test]
fn recomputed_tables() {
    let o = thesis_outputs(&common::thesis_tables(), 0.5).unwrap();
    check("eq_4_1", o.eq_4_1.to_csv());
    check("table_4_2", o.table_4_2.to_csv());
    check("eq_4_4_4_5", o.eq_4_4_4_5.to_csv());
    check("table_4_3", o.table_4_3.to_csv());
    check("table_4_6", o.table_4_6.to_csv());
}

#[test]
fn audit_csv() {
    let rows = audit::audit(&common::thesis_tables(), 0.5).unwrap();
    check("audit", audit::audit_table(&rows).to_csv());
}

/// A tighter tolerance can only move rows from `rounding` to `inconsistent`.
#[test]
fn tolerance_is_monotone() {
    let t = common::thesis_tables();
    let loose = audit::audit(&t, 0.5).unwrap();
    let tight = audit::audit(&t, 0.0).unwrap();
    let bad = |r: &[rig_calibrate::AuditRow]| r.iter().filter(|x| x.status == Status::Inconsistent).count();
    assert!(bad(&tight) >= bad(&loose));
}

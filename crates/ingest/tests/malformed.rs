//! The refusal corpus: each test builds a tiny valid campaign in a tempdir,
//! breaks ONE rule of recording-format.md, and asserts the exact message
//! (file, line, rule) that `read_campaign` returns, and that nothing was written.

use rig_ingest::read_campaign;
use std::collections::BTreeMap;
use std::path::Path;

const TOML: &str = r#"format = "rig-campaign/1"
name = "tiny"
description = "five runs of three to four rows"

[rig]
encoder_ticks_per_rev = 1000
brake_disc_radius_m = 0.062
supply_voltage_v = 24.0
sample_rate_hz = 500.0

[[runs]]
id = "cal-0"
kind = "force_calibration"
file = "runs/cal-0.csv"
load_n = 0.0

[[runs]]
id = "cal-1"
kind = "force_calibration"
file = "runs/cal-1.csv"
load_n = 0.692

[[runs]]
id = "twist-1"
kind = "static_twist"
file = "runs/twist-1.csv"
torque_nm = 0.1155

[[runs]]
id = "step-6v"
kind = "voltage_step"
file = "runs/step-6v.csv"
voltage_v = 6.0

[[runs]]
id = "op-01"
kind = "operating_point"
file = "runs/op-01.csv"
motor_rpm_setpoint = 20.0
normal_force_n = 1.0
ramp_s = 2.0
"#;

/// The valid base campaign: file name -> text.
fn base() -> BTreeMap<String, String> {
    let files = [
        ("campaign.toml", TOML),
        ("runs/cal-0.csv", "time_s,brake_force_mv\n0.0000,3.10\n0.0020,2.95\n0.0040,3.02\n"),
        ("runs/cal-1.csv", "time_s,brake_force_mv\n0.0000,151.75\n0.0020,150.10\n0.0040,151.02\n"),
        ("runs/twist-1.csv", "time_s,rotor_ticks\n0.0000,70\n0.0020,70\n0.0040,71\n"),
        (
            "runs/step-6v.csv",
            "time_s,motor_voltage_v,motor_ticks,rotor_ticks\n0.0000,6.012,0,0\n0.0020,5.999,0,0\n0.0040,6.003,1,0\n",
        ),
        (
            "runs/op-01.csv",
            "time_s,motor_voltage_v,motor_ticks,rotor_ticks,brake_force_mv\n\
             0.0000,-0.006,0,0,4.71\n0.0020,0.021,0,0,3.16\n0.0040,0.050,1,0,3.90\n0.0060,0.080,2,1,4.20\n",
        ),
    ];
    files.into_iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

/// Replaces the unique occurrence of `from` in `file` by `to`.
fn edit(files: &mut BTreeMap<String, String>, file: &str, from: &str, to: &str) {
    let text = files.get_mut(file).unwrap_or_else(|| panic!("no file {file} in the fixture"));
    assert_eq!(text.matches(from).count(), 1, "{from:?} must occur exactly once in {file}");
    *text = text.replacen(from, to, 1);
}

/// Every file under `dir` with its bytes, to show a failed read wrote nothing.
fn snapshot_dir(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let meta = std::fs::symlink_metadata(&p).unwrap();
            if meta.is_dir() {
                stack.push(p);
            } else {
                let bytes = if meta.is_file() { std::fs::read(&p).unwrap() } else { Vec::new() };
                out.insert(p.strip_prefix(dir).unwrap().display().to_string(), bytes);
            }
        }
    }
    out
}

/// Writes the base campaign, applies `mutate` to its texts and `fs_hook` to
/// the folder, reads it, and asserts the refusal message (the folder path
/// replaced by `<c>`) and that the folder is unchanged.
fn check_with(mutate: impl FnOnce(&mut BTreeMap<String, String>), fs_hook: impl FnOnce(&Path), expected: &str) {
    let mut files = base();
    mutate(&mut files);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("c");
    for (name, text) in &files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    fs_hook(&dir);
    let before = snapshot_dir(tmp.path());
    let err = read_campaign(&dir).expect_err("the broken campaign must be refused");
    let message = err.to_string().replace(&dir.display().to_string(), "<c>");
    assert_eq!(message, expected);
    assert_eq!(snapshot_dir(tmp.path()), before, "a failed read must not write anything");
}

fn check(mutate: impl FnOnce(&mut BTreeMap<String, String>), expected: &str) {
    check_with(mutate, |_| {}, expected);
}

#[test]
fn the_base_fixture_is_valid() {
    let tmp = tempfile::tempdir().unwrap();
    for (name, text) in base() {
        let path = tmp.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    let c = read_campaign(tmp.path()).unwrap();
    assert_eq!(c.runs.len(), 5);
    let op = &c.runs[4].data;
    assert_eq!(op.time_s, vec![0.0, 0.002, 0.004, 0.006]);
    assert_eq!(op.motor_ticks.as_deref(), Some(&[0, 0, 1, 2][..]));
    assert_eq!(op.brake_force_mv.as_deref(), Some(&[4.71, 3.16, 3.90, 4.20][..]));
}

// ---- campaign.toml ----

#[test]
fn bad_toml() {
    check(
        |f| edit(f, "campaign.toml", "name = \"tiny\"", "name = \"tiny"),
        "<c>/campaign.toml:2: invalid campaign.toml: invalid basic string, expected `\"`",
    );
}

#[test]
fn wrong_format_string() {
    check(
        |f| edit(f, "campaign.toml", "rig-campaign/1", "rig-campaign/2"),
        "<c>/campaign.toml:1: format must be exactly \"rig-campaign/1\", found \"rig-campaign/2\"",
    );
}

#[test]
fn missing_format() {
    check(
        |f| edit(f, "campaign.toml", "format = \"rig-campaign/1\"\n", ""),
        "<c>/campaign.toml: format = \"rig-campaign/1\" is missing",
    );
}

#[test]
fn unknown_top_level_key() {
    check(
        |f| edit(f, "campaign.toml", "name = \"tiny\"", "name = \"tiny\"\noperator = \"me\""),
        "<c>/campaign.toml:3: invalid campaign.toml: unknown field `operator`, expected one of `format`, `name`, `description`, `rig`, `runs`",
    );
}

#[test]
fn missing_rig() {
    check(
        |f| {
            edit(f, "campaign.toml", "[rig]\nencoder_ticks_per_rev = 1000\nbrake_disc_radius_m = 0.062\n", "");
            edit(f, "campaign.toml", "supply_voltage_v = 24.0\nsample_rate_hz = 500.0\n", "");
        },
        "<c>/campaign.toml: [rig] is missing (encoder_ticks_per_rev, brake_disc_radius_m, supply_voltage_v, sample_rate_hz)",
    );
}

#[test]
fn missing_rig_field() {
    check(
        |f| edit(f, "campaign.toml", "brake_disc_radius_m = 0.062\n", ""),
        "<c>/campaign.toml:5: [rig]: brake_disc_radius_m is missing",
    );
}

#[test]
fn non_positive_sample_rate() {
    check(
        |f| edit(f, "campaign.toml", "sample_rate_hz = 500.0", "sample_rate_hz = 0.0"),
        "<c>/campaign.toml:9: [rig] sample_rate_hz must be > 0, found 0",
    );
}

#[test]
fn non_finite_rig_value() {
    check(
        |f| edit(f, "campaign.toml", "supply_voltage_v = 24.0", "supply_voltage_v = inf"),
        "<c>/campaign.toml:8: [rig]: supply_voltage_v must be finite, found inf",
    );
}

#[test]
fn fractional_encoder_resolution() {
    check(
        |f| edit(f, "campaign.toml", "encoder_ticks_per_rev = 1000", "encoder_ticks_per_rev = 1000.5"),
        "<c>/campaign.toml:6: [rig] encoder_ticks_per_rev must be a positive integer, found 1000.5",
    );
}

#[test]
fn unknown_rig_key() {
    check(
        |f| edit(f, "campaign.toml", "sample_rate_hz = 500.0", "sample_rate_hz = 500.0\nsample_rate = 500.0"),
        "<c>/campaign.toml:10: [rig]: unknown key \"sample_rate\" (allowed: encoder_ticks_per_rev, brake_disc_radius_m, supply_voltage_v, sample_rate_hz)",
    );
}

#[test]
fn no_runs() {
    check(
        |f| {
            let t = f.get_mut("campaign.toml").unwrap();
            *t = t[..t.find("[[runs]]").unwrap()].to_string();
        },
        "<c>/campaign.toml: the campaign has no [[runs]]",
    );
}

#[test]
fn unknown_kind() {
    check(
        |f| edit(f, "campaign.toml", "kind = \"static_twist\"", "kind = \"static_twsit\""),
        "<c>/campaign.toml:25: run \"twist-1\": unknown run kind \"static_twsit\" (known: force_calibration, static_twist, voltage_step, operating_point)",
    );
}

#[test]
fn duplicate_run_id() {
    check(
        |f| edit(f, "campaign.toml", "id = \"cal-1\"", "id = \"cal-0\""),
        "<c>/campaign.toml:17: run id \"cal-0\" is used twice (first at line 11); run ids must be unique",
    );
}

#[test]
fn bad_run_id_chars() {
    check(
        |f| edit(f, "campaign.toml", "id = \"twist-1\"", "id = \"Twist_1\""),
        "<c>/campaign.toml:24: run id \"Twist_1\" must match [a-z0-9-]+",
    );
}

#[test]
fn missing_run_id() {
    check(|f| edit(f, "campaign.toml", "id = \"twist-1\"\n", ""), "<c>/campaign.toml:23: [[runs]] #3: id is missing");
}

#[test]
fn missing_metadata_key() {
    check(|f| edit(f, "campaign.toml", "ramp_s = 2.0\n", ""), "<c>/campaign.toml:35: run \"op-01\": ramp_s is missing");
}

#[test]
fn unknown_metadata_key() {
    check(
        |f| edit(f, "campaign.toml", "load_n = 0.692", "lod_n = 0.692"),
        "<c>/campaign.toml:21: run \"cal-1\" (kind force_calibration): unknown key \"lod_n\" (allowed: id, kind, file, load_n)",
    );
}

#[test]
fn metadata_of_another_kind() {
    check(
        |f| edit(f, "campaign.toml", "torque_nm = 0.1155", "torque_nm = 0.1155\nload_n = 1.0"),
        "<c>/campaign.toml:28: run \"twist-1\" (kind static_twist): unknown key \"load_n\" (allowed: id, kind, file, torque_nm)",
    );
}

#[test]
fn metadata_not_a_number() {
    check(
        |f| edit(f, "campaign.toml", "voltage_v = 6.0", "voltage_v = \"6 V\""),
        "<c>/campaign.toml:33: run \"step-6v\": voltage_v must be a number, found \"6 V\"",
    );
}

#[test]
fn negative_load() {
    check(
        |f| edit(f, "campaign.toml", "load_n = 0.692", "load_n = -0.692"),
        "<c>/campaign.toml:21: run \"cal-1\": load_n must be >= 0 N, found -0.692",
    );
}

#[test]
fn zero_torque() {
    check(
        |f| edit(f, "campaign.toml", "torque_nm = 0.1155", "torque_nm = 0"),
        "<c>/campaign.toml:27: run \"twist-1\": torque_nm must be > 0 N m, found 0",
    );
}

#[test]
fn zero_step_voltage() {
    check(
        |f| edit(f, "campaign.toml", "voltage_v = 6.0", "voltage_v = 0.0"),
        "<c>/campaign.toml:33: run \"step-6v\": voltage_v must be non-zero and within +/- supply_voltage_v = 24 V, found 0",
    );
}

#[test]
fn step_voltage_above_supply() {
    check(
        |f| edit(f, "campaign.toml", "voltage_v = 6.0", "voltage_v = -30.0"),
        "<c>/campaign.toml:33: run \"step-6v\": voltage_v must be non-zero and within +/- supply_voltage_v = 24 V, found -30",
    );
}

#[test]
fn zero_setpoint() {
    check(
        |f| edit(f, "campaign.toml", "motor_rpm_setpoint = 20.0", "motor_rpm_setpoint = 0.0"),
        "<c>/campaign.toml:39: run \"op-01\": motor_rpm_setpoint must be > 0 rpm, found 0",
    );
}

#[test]
fn negative_normal_force() {
    check(
        |f| edit(f, "campaign.toml", "normal_force_n = 1.0", "normal_force_n = -1.0"),
        "<c>/campaign.toml:40: run \"op-01\": normal_force_n must be >= 0 N, found -1",
    );
}

#[test]
fn negative_ramp() {
    check(
        |f| edit(f, "campaign.toml", "ramp_s = 2.0", "ramp_s = -0.5"),
        "<c>/campaign.toml:41: run \"op-01\": ramp_s must be >= 0 s, found -0.5",
    );
}

#[test]
fn nan_metadata() {
    check(
        |f| edit(f, "campaign.toml", "normal_force_n = 1.0", "normal_force_n = nan"),
        "<c>/campaign.toml:40: run \"op-01\": normal_force_n must be finite, found NaN",
    );
}

// ---- run files ----

#[test]
fn path_escaping_folder() {
    check(
        |f| edit(f, "campaign.toml", "file = \"runs/cal-1.csv\"", "file = \"runs/../../cal-1.csv\""),
        "<c>/campaign.toml:20: run \"cal-1\": file \"runs/../../cal-1.csv\" must stay inside the campaign folder (no `..`)",
    );
}

#[test]
fn absolute_path() {
    check(
        |f| edit(f, "campaign.toml", "file = \"runs/cal-1.csv\"", "file = \"/etc/passwd\""),
        "<c>/campaign.toml:20: run \"cal-1\": file \"/etc/passwd\" must be relative to the campaign folder, not absolute",
    );
}

#[test]
fn missing_file() {
    check(
        |f| {
            f.remove("runs/op-01.csv");
        },
        "<c>/campaign.toml:38: run \"op-01\": file \"runs/op-01.csv\" does not exist or cannot be opened (No such file or directory (os error 2))",
    );
}

#[test]
fn file_is_a_folder() {
    check(
        |f| edit(f, "campaign.toml", "file = \"runs/cal-1.csv\"", "file = \"runs\""),
        "<c>/campaign.toml:20: run \"cal-1\": file \"runs\" is not a regular file",
    );
}

#[test]
fn symlink_out_of_the_folder() {
    check_with(
        |_| {},
        |dir| {
            let outside = dir.parent().unwrap().join("outside.csv");
            std::fs::write(&outside, "time_s,brake_force_mv\n0.0,1.0\n").unwrap();
            std::fs::remove_file(dir.join("runs/cal-1.csv")).unwrap();
            std::os::unix::fs::symlink(&outside, dir.join("runs/cal-1.csv")).unwrap();
        },
        "<c>/campaign.toml:20: run \"cal-1\": file \"runs/cal-1.csv\" resolves (through a symlink) outside the campaign folder",
    );
}

// ---- CSV structure ----

#[test]
fn missing_column() {
    check(
        |f| {
            f.insert("runs/twist-1.csv".into(), "time_s\n0.0\n0.002\n".into());
        },
        "<c>/runs/twist-1.csv:1: missing column rotor_ticks (the columns must be exactly: time_s, rotor_ticks)",
    );
}

#[test]
fn extra_column() {
    check(
        |f| {
            edit(f, "runs/cal-1.csv", "time_s,brake_force_mv\n", "time_s,brake_force_mv,rotor_ticks\n");
        },
        "<c>/runs/cal-1.csv:1: unexpected column \"rotor_ticks\" (the columns must be exactly: time_s, brake_force_mv)",
    );
}

#[test]
fn duplicate_column() {
    check(
        |f| edit(f, "runs/twist-1.csv", "time_s,rotor_ticks\n", "time_s,rotor_ticks,time_s\n"),
        "<c>/runs/twist-1.csv:1: column time_s appears twice in the header",
    );
}

#[test]
fn empty_file() {
    check(
        |f| {
            f.insert("runs/cal-0.csv".into(), String::new());
        },
        "<c>/runs/cal-0.csv:1: empty file: a header row is required (time_s, brake_force_mv)",
    );
}

#[test]
fn header_only() {
    check(
        |f| {
            f.insert("runs/cal-0.csv".into(), "time_s,brake_force_mv\n".into());
        },
        "<c>/runs/cal-0.csv:1: header row but no data rows",
    );
}

#[test]
fn ragged_row_too_few_cells() {
    check(
        |f| edit(f, "runs/op-01.csv", "0.0040,0.050,1,0,3.90", "0.0040,0.050,1,3.90"),
        "<c>/runs/op-01.csv:4: row has 4 cells but the header has 5",
    );
}

#[test]
fn ragged_row_too_many_cells() {
    check(
        |f| edit(f, "runs/twist-1.csv", "0.0020,70\n", "0.0020,70,71\n"),
        "<c>/runs/twist-1.csv:3: row has 3 cells but the header has 2",
    );
}

#[test]
fn blank_line() {
    check(
        |f| edit(f, "runs/cal-1.csv", "0.0020,150.10\n", "\n0.0020,150.10\n"),
        "<c>/runs/cal-1.csv:3: empty line (every row needs 2 cells)",
    );
}

// ---- CSV cells ----

#[test]
fn missing_cell() {
    check(
        |f| edit(f, "runs/step-6v.csv", "0.0020,5.999,0,0", "0.0020,,0,0"),
        "<c>/runs/step-6v.csv:3: missing value in column motor_voltage_v",
    );
}

#[test]
fn nan_cell() {
    check(
        |f| edit(f, "runs/op-01.csv", "0.0040,0.050,1,0,3.90", "0.0040,0.050,1,0,NaN"),
        "<c>/runs/op-01.csv:4: non-finite value 'NaN' in column brake_force_mv (values must be finite)",
    );
}

#[test]
fn inf_cell() {
    check(
        |f| edit(f, "runs/cal-1.csv", "0.0020,150.10", "0.0020,-inf"),
        "<c>/runs/cal-1.csv:3: non-finite value '-inf' in column brake_force_mv (values must be finite)",
    );
}

#[test]
fn text_in_numeric_column() {
    check(
        |f| edit(f, "runs/step-6v.csv", "0.0040,6.003,1,0", "0.0040,six,1,0"),
        "<c>/runs/step-6v.csv:4: 'six' in column motor_voltage_v is not a number",
    );
}

#[test]
fn text_in_encoder_column() {
    check(
        |f| edit(f, "runs/twist-1.csv", "0.0040,71", "0.0040,n/a"),
        "<c>/runs/twist-1.csv:4: 'n/a' in column rotor_ticks is not a number",
    );
}

#[test]
fn non_integer_ticks() {
    check(
        |f| edit(f, "runs/op-01.csv", "0.0060,0.080,2,1,4.20", "0.0060,0.080,1.5,1,4.20"),
        "<c>/runs/op-01.csv:5: motor_ticks must be an integer count (encoder columns are integers), found '1.5'",
    );
}

#[test]
fn float_spelled_ticks() {
    check(
        |f| edit(f, "runs/twist-1.csv", "0.0020,70", "0.0020,7e1"),
        "<c>/runs/twist-1.csv:3: rotor_ticks must be an integer count (encoder columns are integers), found '7e1'",
    );
}

#[test]
fn earliest_bad_cell_wins() {
    // Line 5 has text in an early column, line 4 a NaN in a later one: line 4 is reported.
    check(
        |f| {
            edit(f, "runs/op-01.csv", "0.0060,0.080,2,1,4.20", "0.0060,x,2,1,4.20");
            edit(f, "runs/op-01.csv", "0.0040,0.050,1,0,3.90", "0.0040,0.050,1,0,inf");
        },
        "<c>/runs/op-01.csv:4: non-finite value 'inf' in column brake_force_mv (values must be finite)",
    );
}

// ---- time ----

#[test]
fn time_not_starting_at_zero() {
    check(
        |f| {
            f.insert("runs/cal-1.csv".into(), "time_s,brake_force_mv\n0.0020,150.10\n0.0040,151.02\n".into());
        },
        "<c>/runs/cal-1.csv:2: time_s must start at 0 (found 0.0020)",
    );
}

#[test]
fn non_monotone_time() {
    check(
        |f| edit(f, "runs/op-01.csv", "0.0060,0.080", "0.0030,0.080"),
        "<c>/runs/op-01.csv:5: time_s must be strictly increasing (0.0030 after 0.0040)",
    );
}

#[test]
fn duplicate_time() {
    check(
        |f| edit(f, "runs/twist-1.csv", "0.0040,71", "0.0020,71"),
        "<c>/runs/twist-1.csv:4: time_s must be strictly increasing (0.0020 after 0.0020)",
    );
}

#[test]
fn time_column_not_first_still_checked() {
    check(
        |f| {
            f.insert("runs/twist-1.csv".into(), "rotor_ticks,time_s\n70,0.0\n70,0.002\n71,0.001\n".into());
        },
        "<c>/runs/twist-1.csv:4: time_s must be strictly increasing (0.001 after 0.002)",
    );
}

// ---- encodings and spellings ----

#[test]
fn crlf_line_endings_are_accepted() {
    let tmp = tempfile::tempdir().unwrap();
    for (name, text) in base() {
        let path = tmp.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text.replace('\n', "\r\n")).unwrap();
    }
    let c = read_campaign(tmp.path()).unwrap();
    assert_eq!(c.runs[3].data.motor_voltage_v.as_deref(), Some(&[6.012, 5.999, 6.003][..]));
    assert_eq!(c.runs[3].data.rotor_ticks.as_deref(), Some(&[0, 0, 0][..]));
}

#[test]
fn not_utf8() {
    check_with(
        |_| {},
        |dir| {
            let mut bytes = std::fs::read(dir.join("runs/cal-1.csv")).unwrap();
            // The first byte of line 3 (after the second newline) becomes invalid UTF-8.
            let third_line = bytes.iter().enumerate().filter(|(_, b)| **b == b'\n').nth(1).unwrap().0 + 1;
            bytes[third_line] = 0xff;
            std::fs::write(dir.join("runs/cal-1.csv"), bytes).unwrap();
        },
        "<c>/runs/cal-1.csv:3: the file is not UTF-8 text",
    );
}

#[test]
fn quoted_number() {
    check(
        |f| edit(f, "runs/cal-1.csv", "0.0020,150.10", "0.0020,\"150.10\""),
        "<c>/runs/cal-1.csv:3: '\"150.10\"' in column brake_force_mv is not a number",
    );
}

#[test]
fn crlf_blank_line() {
    check(
        |f| {
            let t = f.get_mut("runs/twist-1.csv").unwrap();
            *t = t.replace('\n', "\r\n").replace("0.0020,70\r\n", "0.0020,70\r\n\r\n");
        },
        "<c>/runs/twist-1.csv:4: empty line (every row needs 2 cells)",
    );
}

#[test]
fn error_accessors_name_file_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let mut files = base();
    edit(&mut files, "runs/op-01.csv", "0.0060,0.080", "0.0030,0.080");
    for (name, text) in files {
        let path = tmp.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    let err = read_campaign(tmp.path()).unwrap_err();
    assert_eq!(err.file(), tmp.path().join("runs/op-01.csv"));
    assert_eq!(err.line(), Some(5));
    assert!(matches!(err, rig_ingest::IngestError::Rule { .. }));
}

#[test]
fn force_sample_beyond_what_the_sensor_can_output() {
    check(
        |f| edit(f, "runs/cal-1.csv", "0.0020,150.10", "0.0020,1e308"),
        "<c>/runs/cal-1.csv:3: brake_force_mv = 1e308 mV is physically impossible: |brake_force_mv| must be <= 24000 mV (what a sensor on the rig's supply can output, supply_voltage_v = 24)",
    );
}

#[test]
fn motor_voltage_beyond_the_supply() {
    check(
        |f| edit(f, "runs/op-01.csv", "0.0040,0.050,1,0,3.90", "0.0040,-25.5,1,0,3.90"),
        "<c>/runs/op-01.csv:4: motor_voltage_v = -25.5 V is physically impossible: |motor_voltage_v| must be <= 25.2 V (the drive's supply, supply_voltage_v = 24)",
    );
}

// ---- files and cells the format does not describe ----

#[test]
fn trailing_empty_cell() {
    check(
        |f| edit(f, "runs/twist-1.csv", "0.0020,70\n", "0.0020,70,\n"),
        "<c>/runs/twist-1.csv:3: row has 3 cells but the header has 2",
    );
}

#[test]
fn trailing_empty_cells_on_every_row() {
    check(
        |f| {
            let t = f.get_mut("runs/step-6v.csv").unwrap();
            *t = t.replace('\n', ",,\n");
        },
        "<c>/runs/step-6v.csv:1: unexpected column \"\" (the columns must be exactly: time_s, motor_voltage_v, motor_ticks, rotor_ticks)",
    );
}

/// The first ragged row is reported: before a later bad cell, and also when
/// its cell too many is balanced by a short row (the file's comma count right).
#[test]
fn the_first_ragged_row_is_reported() {
    for later in ["0.0060,x,2,1,4.20", "0.0060,0.080,2,1"] {
        check(
            |f| {
                edit(f, "runs/op-01.csv", "0.0020,0.021,0,0,3.16", "0.0020,0.021,0,0,3.16,");
                edit(f, "runs/op-01.csv", "0.0060,0.080,2,1,4.20", later);
            },
            "<c>/runs/op-01.csv:3: row has 6 cells but the header has 5",
        );
    }
}

const UNDESCRIBED: &str = "the format does not describe: a campaign's recordings are the CSV files its campaign.toml \
                           lists ([[runs]] file), runs/ holds nothing else, and no run lists this one";

#[test]
fn a_file_in_runs_no_run_lists() {
    check(
        |f| drop(f.insert("runs/notes.txt".into(), "taken on a Tuesday".into())),
        &format!("<c>/runs/notes.txt: a file {UNDESCRIBED}"),
    );
}

#[test]
fn a_csv_in_runs_no_run_lists() {
    check(
        |f| drop(f.insert("runs/cal-9.csv".into(), "time_s,brake_force_mv\n0.0000,3.10\n".into())),
        &format!("<c>/runs/cal-9.csv: a file {UNDESCRIBED}"),
    );
}

#[test]
fn a_folder_in_runs_no_run_lists() {
    check_with(
        |_| {},
        |dir| std::fs::create_dir(dir.join("runs/old")).unwrap(),
        &format!("<c>/runs/old: a folder {UNDESCRIBED}"),
    );
}

#[test]
fn a_csv_beside_campaign_toml_no_run_lists() {
    check(
        |f| drop(f.insert("op-02.csv".into(), "time_s,brake_force_mv\n0.0000,3.10\n".into())),
        &format!("<c>/op-02.csv: a CSV file {UNDESCRIBED}"),
    );
}

/// What the spec allows stays allowed: a run's file anywhere inside the
/// folder (`file` is relative to the campaign folder), in a subfolder of
/// runs/, and a README beside campaign.toml (documentation, not a recording).
#[test]
fn files_the_spec_allows_are_read() {
    let tmp = tempfile::tempdir().unwrap();
    let mut files = base();
    let cal = files.remove("runs/cal-1.csv").unwrap();
    files.insert("calibration/cal-1.csv".into(), cal);
    let twist = files.remove("runs/twist-1.csv").unwrap();
    files.insert("runs/static/twist-1.csv".into(), twist);
    files.insert("README.md".into(), "# tiny\n".into());
    edit(&mut files, "campaign.toml", "runs/cal-1.csv", "calibration/cal-1.csv");
    edit(&mut files, "campaign.toml", "runs/twist-1.csv", "./runs/static/twist-1.csv");
    for (name, text) in &files {
        let path = tmp.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    let c = read_campaign(tmp.path()).unwrap();
    assert_eq!(c.runs.len(), 5);
    assert_eq!(c.runs[2].data.rotor_ticks.as_deref(), Some(&[70, 70, 71][..]));
}

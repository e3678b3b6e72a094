//! The shipped campaign (data/emulated-rig-2026) and the real LAVI recording
//! load, with counts, lengths and first/last values that were read off the
//! CSV text independently (sed/awk/wc), not from this reader.

use rig_ingest::lavi::read_lavi;
use rig_ingest::read_campaign;
use rig_types::RunKind;
use std::path::PathBuf;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn shipped_campaign_loads() {
    let c = read_campaign(&repo().join("data/emulated-rig-2026")).expect("the shipped campaign is valid");
    assert_eq!(c.name, "emulated-rig-2026");
    assert_eq!(c.rig.encoder_ticks_per_rev, 1000);
    assert_eq!(c.rig.brake_disc_radius_m, 0.062);
    assert_eq!(c.rig.supply_voltage_v, 24.0);
    assert_eq!(c.rig.sample_rate_hz, 500.0);

    // Runs per kind and rows per run (wc -l minus the header).
    for (kind, runs, rows) in [
        ("force_calibration", 5, 1000),
        ("static_twist", 5, 1000),
        ("voltage_step", 4, 10_000),
        ("operating_point", 30, 20_000),
    ] {
        let of_kind: Vec<_> = c.runs_of(kind).collect();
        assert_eq!(of_kind.len(), runs, "{kind}");
        for r in of_kind {
            let d = &r.data;
            assert_eq!(d.time_s.len(), rows, "{}", r.id);
            for col in [d.motor_voltage_v.as_ref(), d.brake_force_mv.as_ref()].into_iter().flatten() {
                assert_eq!(col.len(), rows, "{}", r.id);
            }
            for col in [d.motor_ticks.as_ref(), d.rotor_ticks.as_ref()].into_iter().flatten() {
                assert_eq!(col.len(), rows, "{}", r.id);
            }
            assert_eq!(d.time_s[0], 0.0);
            assert_eq!(r.file, PathBuf::from(format!("runs/{}.csv", r.id)));
        }
    }
    assert_eq!(c.runs.len(), 44);

    let run = |id: &str| c.runs.iter().find(|r| r.id == id).unwrap_or_else(|| panic!("no run {id}"));
    let cal = run("cal-1");
    assert_eq!(cal.kind, RunKind::ForceCalibration { load_n: 0.692 });
    assert_eq!(cal.data.brake_force_mv.as_ref().unwrap()[..2], [151.75, 150.10]);
    assert_eq!(*cal.data.time_s.last().unwrap(), 1.998);
    assert!(cal.data.motor_ticks.is_none() && cal.data.rotor_ticks.is_none() && cal.data.motor_voltage_v.is_none());

    let twist = run("twist-1");
    assert_eq!(twist.kind, RunKind::StaticTwist { torque_nm: 0.1155 });
    assert_eq!(twist.data.rotor_ticks.as_ref().unwrap()[0], 70);

    let step = run("step-12v");
    assert_eq!(step.kind, RunKind::VoltageStep { voltage_v: 12.0 });
    assert_eq!(step.data.motor_voltage_v.as_ref().unwrap()[0], 11.969);
    assert_eq!(*step.data.motor_ticks.as_ref().unwrap().last().unwrap(), 78329);
    assert_eq!(*step.data.rotor_ticks.as_ref().unwrap().last().unwrap(), 78231);

    let op = run("op-30");
    assert_eq!(op.kind, RunKind::OperatingPoint { motor_rpm_setpoint: 20.0, normal_force_n: 18.0, ramp_s: 2.0 });
    let d = &op.data;
    assert_eq!(
        (d.time_s[1], d.motor_voltage_v.as_ref().unwrap()[0], d.brake_force_mv.as_ref().unwrap()[0]),
        (0.002, -0.008, 3.61)
    );
    assert_eq!(*d.time_s.last().unwrap(), 39.998);
    assert_eq!(*d.motor_ticks.as_ref().unwrap().last().unwrap(), 12993);
    assert_eq!(*d.rotor_ticks.as_ref().unwrap().last().unwrap(), 12228);
    assert_eq!(*d.brake_force_mv.as_ref().unwrap().last().unwrap(), 4329.58);

    // Same folder, same campaign: nothing depends on thread timing or map order.
    assert_eq!(read_campaign(&repo().join("data/emulated-rig-2026")).unwrap(), c);
}

/// The real recording lives outside the repository (../shared, never copied
/// in); the test is skipped, saying so, where that folder is absent.
#[test]
fn lavi_run_175_loads() {
    let path = repo().join("../shared/data/ufrj-lavi-2018/run-175.csv");
    if !path.exists() {
        eprintln!("skipped: {} is not present", path.display());
        return;
    }
    let r = read_lavi(&path).expect("run 175 is valid");
    assert_eq!(r.len(), 59_000);
    assert_eq!((r.time_s[0], *r.time_s.last().unwrap()), (0.0, 58.999));
    assert_eq!(
        (r.top_speed_rpm[0], r.bit_speed_rpm[0], r.bit_torque_nm[0], r.wob_n[0]),
        (104.7762, 148.1578, 0.54625, 539.867)
    );
    assert_eq!(
        (*r.top_speed_rpm.last().unwrap(), *r.bit_speed_rpm.last().unwrap(), *r.bit_torque_nm.last().unwrap()),
        (57.7987, 29.8606, 2.17544)
    );
    // The glitch the README warns about is kept as recorded (awk: min -262.8337).
    let min = r.top_speed_rpm.iter().copied().fold(f64::INFINITY, f64::min);
    assert_eq!(min, -262.8337);
}

#[test]
fn lavi_reader_refuses_like_the_campaign_reader() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("run.csv");
    let header = "time_s,top_speed_rpm,bit_speed_rpm,bit_torque_nm,wob_n\n";
    let cases = [
        (format!("{header}1.000,1,2,3,4\n1.001,1,2,3,4\n"), None),
        (
            format!("{header}1.000,1,2,3,4\n1.000,1,2,3,4\n"),
            Some(":3: time_s must be strictly increasing (1.000 after 1.000)"),
        ),
        (
            format!("{header}1.000,1,2,3,4\n1.001,1,2,nan,4\n"),
            Some(":3: non-finite value 'nan' in column bit_torque_nm (values must be finite)"),
        ),
        (
            "time_s,top_speed_rpm,bit_speed_rpm,bit_torque_nm\n0,1,2,3\n".to_string(),
            Some(
                ":1: missing column wob_n (the columns must be exactly: time_s, top_speed_rpm, bit_speed_rpm, bit_torque_nm, wob_n)",
            ),
        ),
    ];
    for (text, expected) in cases {
        std::fs::write(&path, &text).unwrap();
        match (read_lavi(&path), expected) {
            (Ok(r), None) => assert_eq!(r.time_s, vec![1.0, 1.001]),
            (Err(e), Some(suffix)) => assert_eq!(e.to_string(), format!("{}{suffix}", path.display())),
            (got, want) => panic!("{text:?}: got {got:?}, want {want:?}"),
        }
    }
}

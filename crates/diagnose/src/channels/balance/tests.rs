//! The torque balance's tests: rows against the explicit triangle, lanes
//! against each balance alone, a force combination against its force.

use super::Row;
use super::recorded::{Recorded, RecordedRun};
use super::rows::{row_at, rows_lanes};
use std::borrow::Cow;

fn rows(phi1: &[f64], phi2: &[f64], f: &[f64], dt: f64, w: usize, r_m: f64, from: usize) -> Vec<Row> {
    let [out] = rows_lanes([(phi1, phi2, f)], dt, w, r_m, from);
    out
}

/// Lanes built together are each lane built alone, bit for bit (the
/// sensor grid's balances are read as the single balance's).
#[test]
fn lanes_are_each_balance_alone() {
    let (n, dt, w, r_m) = (2500, 0.002, 40, 0.09);
    let t = |k: usize| k as f64 * dt;
    let phi1: Vec<f64> = (0..n).map(|k| 3.0 * t(k) + 0.02 * (40.0 * t(k)).sin()).collect();
    let phi2: Vec<Vec<f64>> =
        (0..3).map(|j| (0..n).map(|k| 3.0 * t(k) + 0.5 + 0.01 * j as f64 * (7.0 * t(k)).cos()).collect()).collect();
    let f: Vec<Vec<f64>> =
        (0..3).map(|j| (0..n).map(|k| 10.0 + ((k * 7919 + j * 31) % 101) as f64 * 0.01).collect()).collect();
    for from in [0, 37] {
        let lanes =
            rows_lanes(std::array::from_fn::<_, 3, _>(|j| (&phi1[..], &phi2[j][..], &f[j][..])), dt, w, r_m, from);
        for (j, lane) in lanes.iter().enumerate() {
            let alone = rows(&phi1, &phi2[j], &f[j], dt, w, r_m, from);
            assert!(!alone.is_empty());
            let bits = |r: &[Row]| {
                r.iter()
                    .flat_map(|(x, y)| x.iter().chain([y]).map(|v| v.to_bits()).collect::<Vec<_>>())
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(lane), bits(&alone), "lane {j}, from {from}");
        }
    }
    // Lanes on the same angles (a force sensor's points) share the
    // twist's sums: still each lane alone, to the bit.
    let shared = rows_lanes(std::array::from_fn::<_, 3, _>(|j| (&phi1[..], &phi2[0][..], &f[j][..])), dt, w, r_m, 37);
    for (j, lane) in shared.iter().enumerate() {
        let alone = rows(&phi1, &phi2[0], &f[j], dt, w, r_m, 37);
        let bits = |r: &[Row]| r.iter().flat_map(|(x, y)| x.iter().chain([y]).map(|v| v.to_bits())).collect::<Vec<_>>();
        assert!(!alone.is_empty());
        assert_eq!(bits(lane), bits(&alone), "shared angles, lane {j}");
    }
    assert!(shared[0] != shared[1], "the lanes' forces differ");
    // Unequal lengths: each lane alone.
    let short = &f[1][..n - 300];
    let [a, b] = rows_lanes([(&phi1[..], &phi2[0][..], &f[0][..]), (&phi1[..], &phi2[1][..], short)], dt, w, r_m, 0);
    assert_eq!(a.len(), rows(&phi1, &phi2[0], &f[0], dt, w, r_m, 0).len());
    assert_eq!(b, rows(&phi1, &phi2[1], short, dt, w, r_m, 0));
    assert!(b.len() < a.len());
}

/// The running box sums give [`row_at`]'s rows (its explicit triangle
/// weights, the independent reference) on a record with every term
/// moving: ramps, a ring and a noisy force.
#[test]
fn rows_are_the_triangle_rows() {
    let (n, dt, w, r_m) = (3000, 0.002, 50, 0.09);
    let t = |k: usize| k as f64 * dt;
    let phi1: Vec<f64> = (0..n).map(|k| 3.0 * t(k) + 0.02 * (40.0 * t(k)).sin()).collect();
    let phi2: Vec<f64> = (0..n).map(|k| 3.0 * t(k) + 0.5 + 0.01 * (7.0 * t(k)).cos()).collect();
    let f: Vec<f64> = (0..n).map(|k| 10.0 + ((k * 7919) % 101) as f64 * 0.01).collect();
    for from in [0, 37, 120] {
        let fast = rows(&phi1, &phi2, &f, dt, w, r_m, from);
        let slow: Vec<_> = (from.max(w)..n).step_by(w).map_while(|b| row_at(&phi1, &phi2, &f, dt, w, r_m, b)).collect();
        assert_eq!(fast.len(), slow.len());
        for ((x, y), (xs, ys)) in fast.iter().zip(&slow) {
            assert!((y - ys).abs() < 1e-12 * ys.abs().max(1.0), "{y} vs {ys}");
            for (a, b) in x.iter().zip(xs) {
                assert!((a - b).abs() < 1e-9 * b.abs().max(1.0), "{a} vs {b}");
            }
        }
    }
}

/// A balance of F + a1·G1 + a2·G2 combined from the three balances
/// ([`super::BalanceData::force_combination`]) is the balance of that
/// force built sample by sample (the independent reference), rows,
/// event-locked rows, normal equations and fits, to rounding: on two
/// runs with transitions, a noisy force and coefficients of the force
/// sensor's grid (a2 up to rate²/ω² ≈ 1.6·10³ at 2 Hz).
#[test]
fn a_force_combination_is_the_combined_force_balance() {
    let (n, dt, w, r_m) = (4000, 0.002, 50, 0.09);
    let t = |k: usize| k as f64 * dt;
    let run = |j: usize| {
        let rotor_rad: Vec<f64> = (0..n).map(|k| 2.0 * t(k) + 0.05 * (9.0 * t(k) + j as f64).sin()).collect();
        let motor_rad: Vec<f64> = (0..n).map(|k| 2.0 * t(k) + 0.4 + 0.01 * (3.0 * t(k)).cos()).collect();
        let force_n: Vec<f64> =
            (0..n).map(|k| 30.0 + (6.0 * t(k)).sin() + ((k * 7919 + j) % 101) as f64 * 0.003).collect();
        RecordedRun {
            id: format!("op-{j}"),
            rotor_rad,
            motor_rad,
            force_n,
            from: 120,
            transitions: vec![(1, 400), (0, 900), (1, 1500), (0, 2100), (1, 3920)],
            force_noise_n: 0.01,
        }
    };
    let rec = Recorded { runs: vec![run(0), run(1)], rate_hz: 1.0 / dt, w, dt, r_m, kernel_gain: 0.5, j1_kgm2: 0.02 };
    let diff = |f: &[f64], second: bool| -> Vec<f64> {
        (0..f.len())
            .map(|k| match (k.checked_sub(1), f.get(k + 1)) {
                (Some(j), Some(&next)) if second => next - 2.0 * f[k] + f[j],
                (Some(j), Some(&next)) => next - f[j],
                _ => 0.0,
            })
            .collect()
    };
    let [f0, g1, g2] = rec.balance_lanes(|_, r| {
        [Cow::Borrowed(r.force_n.as_slice()), Cow::Owned(diff(&r.force_n, false)), Cow::Owned(diff(&r.force_n, true))]
            .map(|f| (Cow::Borrowed(r.rotor_rad.as_slice()), Cow::Borrowed(r.motor_rad.as_slice()), f))
    });
    for (a1, a2) in [(0.0, 0.0), (0.8, 1583.0), (0.05, 6.3)] {
        let combined = f0.force_combination(&[(a1, &g1), (a2, &g2)]);
        let direct = rec.balance_with(|_, r| {
            let (d1, d2) = (diff(&r.force_n, false), diff(&r.force_n, true));
            let f: Vec<f64> = (0..n).map(|k| r.force_n[k] + a1 * d1[k] + a2 * d2[k]).collect();
            (r.rotor_rad.as_slice().into(), r.motor_rad.as_slice().into(), f.into())
        });
        let close = |a: f64, b: f64, scale: f64| (a - b).abs() <= 1e-12 * scale.max(1.0);
        for (c, d) in combined.runs.iter().zip(&direct.runs) {
            assert_eq!((c.rows.len(), c.events.len()), (d.rows.len(), d.events.len()));
            assert!(c.rows.len() > 50 && c.events.len() == 4, "{} rows, {} events", c.rows.len(), c.events.len());
            let scale = d.rows.iter().fold(0.0f64, |m, (_, y)| m.max(y.abs()));
            for ((xc, yc), (xd, yd)) in c
                .rows
                .iter()
                .chain(c.events.iter().flat_map(|e| &e.1))
                .zip(d.rows.iter().chain(d.events.iter().flat_map(|e| &e.1)))
            {
                assert_eq!(xc, xd, "the regressors are the angles'");
                assert!(close(*yc, *yd, scale), "a1 {a1}, a2 {a2}: {yc} vs {yd}");
            }
            assert_eq!(c.ata, d.ata);
            assert!(c.atb.iter().zip(&d.atb).all(|(u, v)| close(*u, *v, v.abs() * 1e3)), "{:?} vs {:?}", c.atb, d.atb);
            assert!(close(c.yty, d.yty, d.yty), "{} vs {}", c.yty, d.yty);
        }
        let (fc, fd) = (combined.fit(|_| true, true, false).unwrap(), direct.fit(|_| true, true, false).unwrap());
        assert!(close(fc.stiffness_nm_rad, fd.stiffness_nm_rad, 1e3 * fd.stiffness_nm_rad.abs()), "{fc:?} vs {fd:?}");
        let (rc, rd) = (combined.run_rms(&fc, |_| true), direct.run_rms(&fd, |_| true));
        assert!(rc.iter().zip(&rd).all(|(u, v)| (u.1 - v.1).abs() <= 1e-9 * v.1), "{rc:?} vs {rd:?}");
    }
    // The differences move the balance: a sensor point is not the record.
    let moved = f0.force_combination(&[(0.8, &g1), (1583.0, &g2)]);
    assert!(moved.runs[0].rows.iter().zip(&f0.runs[0].rows).any(|(a, b)| (a.1 - b.1).abs() > 1e-6));
}

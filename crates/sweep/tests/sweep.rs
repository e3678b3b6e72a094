//! Continuation sweeps on the rig and thesis models: the bistable band shows
//! as up ≠ down, maps are byte-identical on 1 and 2 threads and when sharded
//! and merged, shard specs are checked.

mod common;

use rig_sweep::{
    MapSpec, Point, Shard, SweepError, bifurcation_chains, chain_table, hysteresis, linspace, map_table, merge_slices,
    run_chains, run_map_shard,
};

fn small_map() -> MapSpec {
    MapSpec { speeds_rpm: linspace(10.0, 60.0, 4), forces_n: linspace(5.0, 25.0, 3) }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

#[test]
fn map_is_byte_identical_on_one_and_two_threads() {
    let (p, s) = (common::rig_params(), common::settings(10.0, 5.0, 10.0));
    let one = pool(1).install(|| map_table(&run_map_shard(&p, &small_map(), Shard::WHOLE, &s, &|| {})).to_csv());
    let two = pool(2).install(|| map_table(&run_map_shard(&p, &small_map(), Shard::WHOLE, &s, &|| {})).to_csv());
    assert_eq!(one, two);
    // 2 directions × 4 speeds × 3 forces, plus the header.
    assert_eq!(one.lines().count(), 1 + 24);
}

#[test]
fn sharded_and_merged_equals_unsharded() {
    let (p, s) = (common::rig_params(), common::settings(10.0, 5.0, 10.0));
    let whole = map_table(&run_map_shard(&p, &small_map(), Shard::WHOLE, &s, &|| {})).to_csv();
    // 6 chains in 4 shards: sizes 1, 2, 1, 2; merged in a scrambled order.
    let mut slices: Vec<_> =
        (1..=4).map(|i| run_map_shard(&p, &small_map(), Shard { index: i, count: 4 }, &s, &|| {})).collect();
    slices.reverse();
    let merged = merge_slices(slices.clone()).expect("complete shards merge");
    assert_eq!(map_table(&merged).to_csv(), whole);
    // A missing shard is refused, not silently merged.
    slices.remove(1);
    assert!(matches!(merge_slices(slices), Err(SweepError::Merge { .. })));
}

#[test]
fn shard_specs() {
    assert_eq!(Shard::parse("2/4"), Ok(Shard { index: 2, count: 4 }));
    for bad in ["0/4", "5/4", "1/0", "1", "a/2"] {
        assert!(matches!(Shard::parse(bad), Err(SweepError::BadShard { .. })), "{bad}");
    }
    // Ranges cover 0..total once, in order.
    let ranges: Vec<_> = (1..=3).map(|i| Shard { index: i, count: 3 }.range(7)).collect();
    assert_eq!(ranges, vec![0..2, 2..4, 4..7]);
}

/// The thesis model at 25 N: started from rest at low speed it is in
/// stick-slip and the up sweep keeps it there; swept down from steady sliding
/// at high speed, sliding stays stable down to the lowest speed — the
/// coexistence of the two attractors the chapter calls bistable. (Steady
/// sliding is linearly stable here: the lookup is flat above 0.5 rpm and C > 0.)
#[test]
fn thesis_model_is_bistable_at_low_speed() {
    let (p, s) = (common::thesis_params(), common::settings(20.0, 10.0, 20.0));
    let chains = bifurcation_chains(&[10.0, 25.0, 55.0, 85.0], |v| Point { motor_rpm: v, normal_force_n: 25.0 });
    let r = run_chains(&p, &chains, &s, &|| {});
    let up0 = r[0].points[0].result.as_ref().expect("converges");
    let down_last = r[1].points[3].result.as_ref().expect("converges");
    assert!(up0.regime.vibrating() && up0.min_rad_s < 0.05, "up at 10 rpm: {up0:?}");
    assert!(!down_last.regime.vibrating(), "down at 10 rpm: {down_last:?}");
    let h = hysteresis(&r[0], &r[1]);
    assert!(h.iter().any(|(p, _, _)| p.motor_rpm == 10.0), "{}", chain_table(&r).to_csv());
    // At 85 rpm both directions slide steadily.
    assert!(!h.iter().any(|(p, _, _)| p.motor_rpm == 85.0));
}

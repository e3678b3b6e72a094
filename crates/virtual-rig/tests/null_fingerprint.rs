//! A campaign without hidden effects (and one with any single effect of the
//! old confusion experiment) is byte-identical to what the virtual rig
//! generated before the effects outside the vocabulary, the extra thermal
//! state of rig-model and the battery existed: the FNV-1a hash of every
//! written file is pinned (value taken from commit 04c13ae, before the change).

use rig_virtual_rig::{Protocol, draw_truth, generate, write_campaign};

fn fnv1a(bytes: &[u8], mut h: u64) -> u64 {
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    h
}

fn fingerprint(class: &str, seed: u64) -> u64 {
    let proto = Protocol {
        op_points: vec![(20.0, 4.0), (85.0, 10.0), (130.0, 25.0)],
        op_duration_s: 12.0,
        step_voltages_v: vec![8.0],
        step_duration_s: 6.0,
        ..Protocol::small()
    };
    let truth = draw_truth(class, 130.0, seed);
    let c = generate("fingerprint", &truth, &proto, seed).expect("generate");
    let dir = tempfile::tempdir().expect("tempdir");
    write_campaign(dir.path(), &c).expect("write");
    let mut names: Vec<_> =
        std::fs::read_dir(dir.path().join("runs")).expect("runs").map(|e| e.expect("entry").path()).collect();
    names.sort();
    names.insert(0, dir.path().join("campaign.toml"));
    names.iter().fold(0xcbf2_9ce4_8422_2325, |h, p| fnv1a(&std::fs::read(p).expect("read"), h))
}

#[test]
fn every_old_class_is_byte_identical_to_before() {
    let pinned = [
        ("none", 0x07c0_f8e8_04ec_4f97u64),
        ("normal_force_modulation", 0x943d_ea0e_ad79_d37e),
        ("angle_periodic_friction", 0xa800_e663_cad5_1bcb),
        ("velocity_weakening_friction", 0x5b51_b453_dedf_8bce),
        ("viscous_brake_friction", 0x3b2a_3956_c9c7_f38e),
        ("drive_voltage_limit", 0xf946_ab7c_23fb_d0be),
        ("motor_cogging", 0xe367_2e63_ecc4_1f06),
    ];
    assert_eq!(rig_virtual_rig::Hidden::CLASSES.len(), pinned.len());
    for (class, hash) in pinned {
        assert_eq!(fingerprint(class, 11), hash, "{class}");
    }
}

//! A campaign without hidden effects is byte-identical to what the virtual rig
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
fn null_and_vocabulary_campaigns_are_byte_identical_to_before() {
    let got: Vec<(&str, u64)> =
        ["none", "normal_force_modulation", "motor_cogging"].iter().map(|c| (*c, fingerprint(c, 11))).collect();
    println!("{got:x?}");
    let pinned: [(&str, u64); 3] = [
        ("none", 0x07c0_f8e8_04ec_4f97),
        ("normal_force_modulation", 0x943d_ea0e_ad79_d37e),
        ("motor_cogging", 0xe367_2e63_ecc4_1f06),
    ];
    assert_eq!(got, pinned);
}

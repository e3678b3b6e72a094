//! `f64::total_cmp`'s order as integer keys: sorting or comparing the keys
//! orders the numbers as `total_cmp` does (signed zeros, NaNs and
//! infinities included), equal keys are equal bits, and the key gives the
//! number back. Integer keys sort and compare faster than the comparator
//! (the running median of `rig-spectra`, the drive's sorted |V| and hull in
//! `rig-diagnose`); one home for the transform.

/// `total_cmp`'s key of `x`: its bits as i64 with the magnitude bits flipped
/// for negatives (the transform `f64::total_cmp` applies; an involution).
pub fn total_key(x: f64) -> i64 {
    flip(x.to_bits() as i64)
}

/// The number whose [`total_key`] is `key`.
pub fn from_total_key(key: i64) -> f64 {
    f64::from_bits(flip(key) as u64)
}

/// [`total_key`] as an unsigned key (the sign bit flipped), for packing
/// into a wider unsigned key whose high part sorts first.
pub fn total_key_u64(x: f64) -> u64 {
    (total_key(x) as u64) ^ (1 << 63)
}

/// The number whose [`total_key_u64`] is `key`.
pub fn from_total_key_u64(key: u64) -> f64 {
    from_total_key((key ^ (1 << 63)) as i64)
}

fn flip(k: i64) -> i64 {
    k ^ ((((k >> 63) as u64) >> 1) as i64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both keys order numbers as `f64::total_cmp` and give each back bit for bit.
    #[test]
    fn keys_order_as_total_cmp_and_invert() {
        let mut xs = vec![0.0, -0.0, 1.0, -1.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN];
        xs.extend([f64::MIN_POSITIVE, -f64::MIN_POSITIVE, 5e-324, -5e-324, f64::MAX, f64::MIN, 0.1, 0.1 + 1e-17]);
        let mut seed = 7u64;
        for _ in 0..2000 {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            xs.push(f64::from_bits(seed));
            xs.push((seed >> 40) as f64 * if seed & 1 == 0 { 1e-3 } else { -1e-3 });
        }
        for a in &xs {
            assert_eq!(from_total_key(total_key(*a)).to_bits(), a.to_bits());
            assert_eq!(from_total_key_u64(total_key_u64(*a)).to_bits(), a.to_bits());
            for b in xs.iter().step_by(7) {
                assert_eq!(total_key(*a).cmp(&total_key(*b)), a.total_cmp(b), "{a} vs {b}");
                assert_eq!(total_key_u64(*a).cmp(&total_key_u64(*b)), a.total_cmp(b), "{a} vs {b}");
            }
        }
    }
}

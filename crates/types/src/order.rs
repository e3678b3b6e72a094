//! `f64::total_cmp`'s order as integer keys: sorting or comparing the keys
//! orders the numbers as `total_cmp` does (signed zeros, NaNs and
//! infinities included), equal keys are equal bits, and the key gives the
//! number back. Integer keys sort and compare faster than the comparator
//! (the running median of `rig-spectra`, the drive's sorted |V| and hull in
//! `rig-diagnose`); one home for the transform. The transforms are
//! `#[inline]`: a few integer operations, called per sample from other
//! crates (the running median's keys were 4.4 % of the slider study's CPU
//! as calls).

/// `total_cmp`'s key of `x`: its bits as i64 with the magnitude bits flipped
/// for negatives (the transform `f64::total_cmp` applies; an involution).
#[inline]
pub fn total_key(x: f64) -> i64 {
    flip(x.to_bits() as i64)
}

/// The number whose [`total_key`] is `key`.
#[inline]
pub fn from_total_key(key: i64) -> f64 {
    f64::from_bits(flip(key) as u64)
}

/// [`total_key`] as an unsigned key (the sign bit flipped), for packing
/// into a wider unsigned key whose high part sorts first.
#[inline]
pub fn total_key_u64(x: f64) -> u64 {
    (total_key(x) as u64) ^ (1 << 63)
}

/// The number whose [`total_key_u64`] is `key`.
#[inline]
pub fn from_total_key_u64(key: u64) -> f64 {
    from_total_key((key ^ (1 << 63)) as i64)
}

/// The indices of `keys` in ascending key order, equal keys in index order
/// (the order of sorting the pairs (key, index)): a stable least-significant
/// digit radix sort, 8 bits a pass, a pass skipped where every key has the
/// same digit. The order is a function of the keys alone, so any stable sort
/// gives it; this one is linear in n (the drive's |V| order of 20 000
/// samples per run: two-thirds of its time went to sorting 128-bit keys).
pub fn argsort_u64(keys: &[u64]) -> Vec<usize> {
    let n = keys.len();
    let mut counts = vec![[0usize; 256]; 8];
    for &k in keys {
        for (d, c) in counts.iter_mut().enumerate() {
            c[((k >> (8 * d)) & 0xff) as usize] += 1;
        }
    }
    let mut cur: Vec<(u64, usize)> = keys.iter().copied().zip(0..n).collect();
    let mut next = vec![(0u64, 0usize); n];
    for (d, c) in counts.iter().enumerate() {
        if c.contains(&n) {
            continue;
        }
        let mut start = [0usize; 256];
        let mut sum = 0;
        for (s, &m) in start.iter_mut().zip(c.iter()) {
            *s = sum;
            sum += m;
        }
        for &(k, i) in &cur {
            let b = ((k >> (8 * d)) & 0xff) as usize;
            next[start[b]] = (k, i);
            start[b] += 1;
        }
        std::mem::swap(&mut cur, &mut next);
    }
    cur.into_iter().map(|(_, i)| i).collect()
}

#[inline]
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

    /// The radix order is the order of sorting (key, index): keys with many
    /// ties, digits that never vary, the extremes, and sizes 0 and 1.
    #[test]
    fn argsort_is_the_stable_sort_order() {
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            seed
        };
        for (n, mask) in
            [(0, !0), (1, !0), (2, 0), (300, 0xff), (5000, 0x0f0f_0000_00ff), (20000, !0), (20000, 0x3ff << 40)]
        {
            let keys: Vec<u64> =
                (0..n).map(|_| rnd() & mask | (7 << 56)).chain([0, u64::MAX].into_iter().take(n.min(2))).collect();
            let mut want: Vec<(u64, usize)> = keys.iter().copied().zip(0..).collect();
            want.sort_unstable();
            let want: Vec<usize> = want.into_iter().map(|(_, i)| i).collect();
            assert_eq!(argsort_u64(&keys), want, "n {n}, mask {mask:#x}");
        }
        // Voltages as the drive keys them: |V| on a quantised grid, many ties.
        let v: Vec<u64> = (0..20000).map(|k| total_key_u64(((k * 7919 % 4096) as f64 * 0.00244).abs())).collect();
        let mut want: Vec<(u64, usize)> = v.iter().copied().zip(0..).collect();
        want.sort_unstable();
        assert_eq!(argsort_u64(&v), want.into_iter().map(|(_, i)| i).collect::<Vec<_>>());
    }
}

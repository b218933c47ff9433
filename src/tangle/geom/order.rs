//! Tangle's sorts by numbers, through one sort. Each `sort_by` with its own
//! element type or comparator is a separate copy of the standard library's
//! sort in the wasm module (5–8 KB each), so Tangle's own sorts by float
//! keys all sort [`Key`]s with [`sort`]: an integer, a float mapped to an
//! integer in [`f64::total_cmp`]'s order ([`key`]), and an integer tie-break.
//! The sort is unstable, so a caller whose equal keys could carry different
//! items puts the item's index in the tie-break, which gives the order a
//! stable sort gives.

/// What [`sort`] sorts: compared as a tuple, first field first.
pub type Key = (u64, u64, u64);

/// `x` as an integer that orders as [`f64::total_cmp`] orders floats
/// (negative NaN < −∞ < … < −0 < +0 < … < +∞ < NaN); [`from_key`] inverts it.
pub fn key(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | 1 << 63
    }
}

/// The float whose [`key`] is `k`.
pub fn from_key(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

/// Sort `keys` ascending (the one sort instance).
pub fn sort(keys: &mut [Key]) {
    keys.sort_unstable();
}

/// Sort floats in [`f64::total_cmp`]'s order, as `v.sort_by(f64::total_cmp)`.
pub fn sort_f64(v: &mut [f64]) {
    let mut keys: Vec<Key> = v.iter().map(|&x| (0, key(x), 0)).collect();
    sort(&mut keys);
    for (x, k) in v.iter_mut().zip(&keys) {
        *x = from_key(k.1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const SPECIAL: [f64; 12] = [
        f64::NAN,
        -f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        f64::MAX,
        f64::MIN,
    ];

    /// Bit patterns, so that NaNs and the two zeros are told apart.
    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn keys_order_as_total_cmp_and_invert_on_special_values() {
        for a in SPECIAL {
            assert_eq!(from_key(key(a)).to_bits(), a.to_bits(), "{a}");
            for b in SPECIAL {
                assert_eq!(key(a).cmp(&key(b)), a.total_cmp(&b), "{a} vs {b}");
            }
        }
    }

    proptest! {
        #[test]
        fn sort_f64_gives_the_bits_sort_by_total_cmp_gives(
            raw in proptest::collection::vec(any::<u64>(), 0..200),
            picks in proptest::collection::vec(0usize..12, 0..20),
        ) {
            // Any bit pattern (NaNs with payloads, subnormals) plus the
            // special values, with repeats.
            let mut v: Vec<f64> = raw.iter().map(|&b| f64::from_bits(b)).collect();
            v.extend(picks.iter().map(|&i| SPECIAL[i]));
            v.extend_from_within(..v.len() / 3);
            let mut want = v.clone();
            want.sort_by(f64::total_cmp);
            sort_f64(&mut v);
            prop_assert_eq!(bits(&v), bits(&want));
        }
    }
}

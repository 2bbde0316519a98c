//! SplitMix64 (Steele, Lea and Flood 2014): the one mixing function behind every derived seed of
//! the kit (`ilopt run`'s evaluation episodes, paper-checks' run, episode and bootstrap seeds),
//! and FNV-1a, the hash that turns a key into a seed (or a figure label into its style).

/// The SplitMix64 output for state `z`: `z + 0x9E3779B97F4A7C15`, then the finaliser
/// (xor-shift 30, multiply, xor-shift 27, multiply, xor-shift 31). A bijection of `u64` that
/// decorrelates nearby inputs; applied to the states `s + k·γ` it is the SplitMix64 stream.
pub fn splitmix64(z: u64) -> u64 {
    let mut z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// FNV-1a (64 bit) of a string: the stable hash that turns a key (a configuration's identity, a
/// figure label) into a seed or an index.
pub fn fnv1a(s: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in s.as_bytes() {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::{fnv1a, splitmix64};

    #[test]
    fn fnv1a_matches_the_reference_values() {
        // The FNV-1a 64-bit test vectors of the reference implementation (Fowler, Noll, Vo).
        assert_eq!(fnv1a(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a("a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a("foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn the_stream_from_zero_matches_the_reference_values() {
        // The first outputs of SplitMix64 seeded with 0 (Vigna's reference implementation).
        let mut state = 0u64;
        let mut next = || {
            let out = splitmix64(state);
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            out
        };
        assert_eq!(next(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(next(), 0x6E78_9E6A_A1B9_65F4);
        assert_eq!(next(), 0x06C4_5D18_8009_454F);
    }
}

//! Low-discrepancy points shared by both passes: the first two dimensions of Sobol's sequence and
//! Owen's scrambling of them by hashing (pure functions; the film's `Sampler` and the hierarchy's
//! link visibility draw from them).

/// Point i of the first two dimensions of Sobol's sequence (Sobol 1967), as 32-bit fractions: dimension
/// 0 is the van der Corput radical inverse (the bits of i reversed), dimension 1 has generator matrix
/// Pascal's triangle mod 2 (direction numbers v₁ = 2³¹, v_{k+1} = v_k ⊕ (v_k ≫ 1)). Together a
/// (0, 2)-sequence in base 2.
pub fn sobol_2d_bits(i: u32) -> [u32; 2] {
    let mut y = 0u32;
    let mut bits = i;
    while bits != 0 {
        y ^= PASCAL_DIRECTIONS[bits.trailing_zeros() as usize];
        bits &= bits - 1;
    }
    [i.reverse_bits(), y]
}

/// Direction numbers of Sobol's dimension 1: v₀ = 2³¹, v_{k+1} = v_k ⊕ (v_k ≫ 1).
const PASCAL_DIRECTIONS: [u32; 32] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        k += 1;
    }
    v
};

/// Owen's nested uniform scrambling of a 32-bit fraction by hashing (Laine and Karras 2011's
/// permutation on the reversed bits, constants from Burley 2020): each bit is flipped by a hash of
/// the bits above it and the seed, so every elementary interval maps onto one of its size and a
/// scrambled point is uniform.
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    let mut v = x.reverse_bits();
    v = v.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50_b47c);
    v ^= v.wrapping_mul(0xb82f_1e52);
    v ^= v.wrapping_mul(0xc7af_e638);
    v ^= v.wrapping_mul(0x8d22_f6e6);
    v.reverse_bits()
}

/// Point i of the Owen-scrambled 2-D Sobol sequence with one seed per dimension, in [0, 1)² (24 bits).
pub fn owen_sobol_2d(i: u32, seeds: [u32; 2]) -> [f32; 2] {
    let [x, y] = sobol_2d_bits(i);
    let to_unit = |b: u32| (b >> 8) as f32 * (1.0 / (1u32 << 24) as f32);
    [to_unit(owen_scramble(x, seeds[0])), to_unit(owen_scramble(y, seeds[1]))]
}

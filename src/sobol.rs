//! Low-discrepancy points shared by both passes: the first two dimensions of Sobol's sequence and
//! Owen's scrambling of them by hashing (pure functions; the film's `Sampler` and the hierarchy's
//! link visibility draw from them).

/// Point i of the first two dimensions of Sobol's sequence (Sobol 1967), as 32-bit fractions: dimension
/// 0 is the van der Corput radical inverse (the bits of i reversed), dimension 1 has generator matrix
/// Pascal's triangle mod 2 (direction numbers v₁ = 2³¹, v_{k+1} = v_k ⊕ (v_k ≫ 1)). Together a
/// (0, 2)-sequence in base 2.
pub fn sobol_2d_bits(i: u32) -> [u32; 2] {
    let byte = |k: usize| PASCAL_BY_BYTE[k][((i >> (8 * k)) & 0xff) as usize];
    [i.reverse_bits(), byte(0) ^ byte(1) ^ byte(2) ^ byte(3)]
}

/// Sobol's dimension 1 by byte of the index: entry [k][b] is the XOR of the direction numbers
/// v_{8k+j} over the set bits j of b, with v₀ = 2³¹, v_{j+1} = v_j ⊕ (v_j ≫ 1).
const PASCAL_BY_BYTE: [[u32; 256]; 4] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut j = 1;
    while j < 32 {
        v[j] = v[j - 1] ^ (v[j - 1] >> 1);
        j += 1;
    }
    let mut table = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut b = 1;
        while b < 256 {
            // b with its lowest set bit cleared, plus that bit's direction number.
            let low = (b as u32).trailing_zeros() as usize;
            table[k][b] = table[k][b & (b - 1)] ^ v[8 * k + low];
            b += 1;
        }
        k += 1;
    }
    table
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The byte tables give the sum of direction numbers over the index's set bits, for low and high
    /// bits alike.
    #[test]
    fn dimension_one_by_byte_equals_the_direction_number_sum() {
        let direct = |i: u32| {
            let (mut y, mut v) = (0u32, 1u32 << 31);
            for bit in 0..32 {
                if i >> bit & 1 != 0 {
                    y ^= v;
                }
                v ^= v >> 1;
            }
            y
        };
        for i in (0..4096u32).chain([0xffff_ffff, 0x8000_0001, 0x1234_5678, 0xdead_beef]) {
            assert_eq!(sobol_2d_bits(i)[1], direct(i), "index {i:#x}");
        }
    }
}

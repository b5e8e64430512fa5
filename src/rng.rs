//! A small deterministic random number generator (PCG32, O'Neill 2014), seeded per pixel or per
//! element so that results never depend on the thread schedule.

/// PCG-XSH-RR 64/32.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

const MULTIPLIER: u64 = 6364136223846793005;

impl Pcg32 {
    /// A generator for stream `stream` (e.g. a pixel or element index) of seed `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Pcg32 { state: 0, inc: (splitmix64(stream ^ 0x9E37_79B9_7F4A_7C15) << 1) | 1 };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(splitmix64(seed));
        rng.next_u32();
        rng
    }

    /// A generator for stream `stream` seeded by this one's current state, which it leaves as it is:
    /// a deterministic side stream (a different increment, so a different sequence) whose draws do not
    /// shift this generator's.
    pub fn fork(&self, stream: u64) -> Self {
        Pcg32::new(self.state, stream)
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULTIPLIER).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [0, 1) with 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// SplitMix64 finaliser: a good 64-bit hash of an integer.
pub fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_deterministic_and_distinct() {
        let a: Vec<u32> = (0..4).map(|_| 0).scan(Pcg32::new(7, 1), |r, _: u32| Some(r.next_u32())).collect();
        let b: Vec<u32> = (0..4).map(|_| 0).scan(Pcg32::new(7, 1), |r, _: u32| Some(r.next_u32())).collect();
        let c: Vec<u32> = (0..4).map(|_| 0).scan(Pcg32::new(7, 2), |r, _: u32| Some(r.next_u32())).collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn a_fork_leaves_its_parent_as_it_was_and_draws_other_numbers() {
        let mut parent = Pcg32::new(7, 1);
        let mut untouched = parent.clone();
        let mut fork = parent.fork(3);
        let forked: Vec<u32> = (0..4).map(|_| fork.next_u32()).collect();
        let after: Vec<u32> = (0..4).map(|_| parent.next_u32()).collect();
        assert_eq!(after, (0..4).map(|_| untouched.next_u32()).collect::<Vec<_>>());
        assert_ne!(forked, after);
        assert_eq!(
            forked,
            (0..4).map(|_| 0).scan(Pcg32::new(7, 1).fork(3), |r, _: u32| Some(r.next_u32())).collect::<Vec<_>>()
        );
        let mut other = Pcg32::new(7, 1).fork(4);
        assert_ne!(forked, (0..4).map(|_| other.next_u32()).collect::<Vec<_>>());
    }

    #[test]
    fn uniform_mean_is_one_half() {
        let mut r = Pcg32::new(1, 0);
        let n = 100_000;
        let mean: f64 = (0..n).map(|_| r.next_f32() as f64).sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1) is sqrt(1/12/n) ≈ 9e-4; allow 5 of them.
        assert!((mean - 0.5).abs() < 5e-3, "{mean}");
    }
}

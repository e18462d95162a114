//! PCG generators keyed by (seed, item, pass), so any split of the work draws the same numbers.
//! `sampling::Sampler` hands them to estimators; `primary_space` keys a Markov chain's own stream
//! with them. Both read this module, so neither imports the other for it.

use rand_pcg::rand_core::Rng;
use rand_pcg::Pcg32;

/// SplitMix64 finaliser: decorrelates the key words before they become PCG state and stream.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
    z ^ (z >> 31)
}

/// The generator of one work item (a pixel, or a light path) in one pass of one seeded run.
pub fn keyed_pcg(seed: u64, item: u64, pass: u64) -> Pcg32 {
    let state = mix64(seed ^ mix64(item.wrapping_add(0x9e3779b97f4a7c15)));
    let stream = mix64(pass ^ mix64(seed.wrapping_add(item.rotate_left(32))));
    Pcg32::new(state, stream)
}

/// Uniform in [0, 1), never 1: the top 24 bits of one draw (an f32's mantissa holds them exactly).
#[inline]
pub fn uniform_f32(rng: &mut Pcg32) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

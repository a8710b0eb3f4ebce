//! Camera sample positions, identical for every integrator and primary
//! mode so that their images can be compared pixel by pixel.

use raykit_core::rng::Pcg32;

/// Image position (in pixels, (0, 0) the top-left corner) of sample
/// `sample` of pixel (`x`, `y`): the pixel centre when `spp` is 1, else a
/// uniform jitter over the pixel from a [`Pcg32`] whose stream is the pixel
/// index and whose seed is `seed` mixed with the sample number, so the
/// position does not depend on scheduling or on the other samples.
pub fn sample_position(seed: u64, width: u32, spp: u32, x: u32, y: u32, sample: u32) -> (f32, f32) {
    if spp <= 1 {
        return (x as f32 + 0.5, y as f32 + 0.5);
    }
    let pixel = y as u64 * width as u64 + x as u64;
    let mixed = seed ^ (sample as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut rng = Pcg32::with_stream(mixed, pixel);
    (x as f32 + rng.next_f32(), y as f32 + rng.next_f32())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_stay_inside_their_pixel_and_differ() {
        let mut seen = std::collections::HashSet::new();
        for s in 0..16 {
            let (fx, fy) = sample_position(3, 10, 16, 4, 7, s);
            assert!((4.0..5.0).contains(&fx) && (7.0..8.0).contains(&fy));
            seen.insert((fx.to_bits(), fy.to_bits()));
        }
        assert_eq!(seen.len(), 16);
        assert_eq!(sample_position(3, 10, 1, 4, 7, 0), (4.5, 7.5));
    }
}

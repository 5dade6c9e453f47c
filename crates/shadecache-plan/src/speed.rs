//! Frame-time statistics: the median, quantiles, and the speed-up's
//! bootstrap interval. The profiler ranks variants with them, and the host
//! crate's governor decides with them on the player's GPU, so that both
//! read a speed-up the same way.

/// The median of a list (the mean of the middle two when even).
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    if sorted.len().is_multiple_of(2) {
        (sorted[mid - 1] + sorted[mid]) / 2.0
    } else {
        sorted[mid]
    }
}

/// The `q`-quantile (0 to 1) of `values`, linearly interpolated between
/// order statistics; 0 for none.
pub fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let at = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (below, above) = (at.floor() as usize, at.ceil() as usize);
    sorted[below] + (sorted[above] - sorted[below]) * (at - below as f64)
}

/// A 95% interval for the speed-up median(reference) / median(variant),
/// by the percentile bootstrap: both sets of frame times resampled with
/// replacement, independently, 2000 times. Frame times are neither normal
/// nor independent of the order they ran in (the runs interleave frame by
/// frame, so drift touches both alike), hence a resampling interval, not a
/// t-interval. The resampling is seeded, so a report is reproducible from
/// its frame times.
pub fn speedup_interval(reference: &[f64], variant: &[f64]) -> [f64; 2] {
    speedup_interval_resampled(reference, variant, 2000)
}

/// [`speedup_interval`] with `resamples` resamples instead of 2000: fewer
/// make a coarser interval in less time, for a decision made while a game
/// runs.
pub fn speedup_interval_resampled(
    reference: &[f64],
    variant: &[f64],
    resamples: usize,
) -> [f64; 2] {
    if reference.is_empty() || variant.is_empty() || resamples == 0 {
        return [0.0, 0.0];
    }
    // xorshift64*: a fixed, dependency-free generator is enough to pick
    // indices; the interval must not change between runs of one report.
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = |n: usize| {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 33) as usize % n
    };
    let mut ratios = Vec::with_capacity(resamples);
    let mut a = vec![0.0; reference.len()];
    let mut b = vec![0.0; variant.len()];
    for _ in 0..resamples {
        for x in a.iter_mut() {
            *x = reference[next(reference.len())];
        }
        for x in b.iter_mut() {
            *x = variant[next(variant.len())];
        }
        let denominator = median(&b);
        if denominator > 0.0 {
            ratios.push(median(&a) / denominator);
        }
    }
    [quantile(&ratios, 0.025), quantile(&ratios, 0.975)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_speedup_interval_holds_the_ratio_and_widens_with_noise() {
        let reference = [10.0, 10.2, 9.8, 10.1, 9.9, 10.0, 10.3, 9.7];
        let steady = [5.0, 5.1, 4.9, 5.0, 5.05, 4.95, 5.0, 5.0];
        let [lo, hi] = speedup_interval(&reference, &steady);
        assert!(lo < 2.0 && 2.0 < hi && lo > 1.8 && hi < 2.2, "[{lo}, {hi}]");
        // A variant whose frames spread over the reference's straddles 1.
        let noisy = [7.0, 13.0, 8.0, 12.5, 9.0, 11.0, 14.0, 6.5];
        let [lo, hi] = speedup_interval(&reference, &noisy);
        assert!(lo < 1.0 && hi > 1.0, "[{lo}, {hi}]");
        // Seeded: the same frames give the same interval.
        assert_eq!(
            speedup_interval(&reference, &noisy),
            speedup_interval(&reference, &noisy)
        );
        assert_eq!(quantile(&[1.0, 2.0, 3.0, 4.0], 0.5), 2.5);
    }
}

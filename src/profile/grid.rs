//! Which configurations a profile measures: the grid of knobs, and how a
//! sweep prunes it.
//!
//! A plain profile measures the full product of the lists it is given
//! (Δn × k × reconstruction × cache format × ε for every node and variant).
//! A **sweep** (`profile --sweep`) covers the whole accuracy-against-time
//! grid of [`Axes::sweep`] — 5 periods × 4 block sizes × 2 formats × 4
//! reconstructions × 3 depth tolerances = 480 settings per node and
//! variant — which is too many to render interleaved, so it prunes, and
//! the report lists what it pruned and why:
//!
//! 1. **By the cost model.** A refresh period Δn recomputes at least 1/Δn
//!    of the pixels, so with the node's estimated P/T = f no configuration
//!    can beat the ideal bound 1 / (1 − (1 − 1/Δn)·f) (ours: Amdahl's law
//!    for a reused share ρ = 1 − 1/Δn of a payload costing f; seed 002
//!    gives no such formula). A
//!    (node, Δn) whose bound is below [`MIN_IDEAL_SPEEDUP`] cannot pay for
//!    the passes a cache adds and is not measured; a node left with no Δn
//!    is dropped.
//! 2. **By the knobs' roles.** Δn and k decide *which* pixels are
//!    recomputed each frame; the format, the reconstruction and ε decide
//!    *how* a reused value is read back. So the sweep measures two planes
//!    through a base setting rather than their product: the refresh plane
//!    (every Δn × k at the base format, reconstruction and ε) and the
//!    read-back plane (every format × reconstruction × ε at the base Δn
//!    and k). The cross terms are the pruned rest.

pub use crate::report::{Axes, Design, Pruned, Setting};
use crate::rewrite::{
    CacheFormat, CacheRead, Options as RewriteOptions, Reconstruction, Refusal, Upsampler, Variant,
};

/// A (node, Δn) is pruned when even its ideal speed-up is below this.
pub const MIN_IDEAL_SPEEDUP: f64 = 1.1;

impl Axes {
    /// The sweep's grid: Δn ∈ {4, 8, 16, 32, 64}, k ∈ {1, 2, 4, 8}, both
    /// formats, every reconstruction (the packed ones are refused for
    /// four-component payloads), and ε at a quarter of, at, and four times
    /// the default.
    pub fn sweep() -> Self {
        let epsilon = RewriteOptions::default().depth_epsilon;
        Axes {
            refresh_periods: vec![4, 8, 16, 32, 64],
            refresh_quads: vec![1, 2, 4, 8],
            reconstructions: CacheRead::ALL.map(Reconstruction::from).to_vec(),
            cache_formats: vec![CacheFormat::Rgba16float, CacheFormat::Rgba32float],
            depth_epsilons: vec![epsilon / 4.0, epsilon, epsilon * 4.0],
        }
    }

    /// Settings in the full product.
    pub fn product_len(&self) -> usize {
        self.refresh_periods.len()
            * self.refresh_quads.len()
            * self.reconstructions.len()
            * self.cache_formats.len()
            * self.depth_epsilons.len()
    }

    /// The base setting the sweep's planes go through: on each axis the
    /// profile's default where the axis has it, else its first value.
    pub fn base(&self) -> Option<Setting> {
        let defaults = RewriteOptions::default();
        fn pick<T: Copy + PartialEq>(values: &[T], default: T) -> Option<T> {
            values
                .iter()
                .copied()
                .find(|&v| v == default)
                .or_else(|| values.first().copied())
        }
        Some(Setting {
            refresh_period: pick(&self.refresh_periods, defaults.refresh_period)?,
            refresh_quad: pick(&self.refresh_quads, defaults.refresh_quad)?,
            reconstruction: pick(&self.reconstructions, defaults.reconstruction.into())?,
            cache_format: pick(&self.cache_formats, defaults.cache_format)?,
            depth_epsilon: pick(&self.depth_epsilons, defaults.depth_epsilon)?,
            adaptive: false,
        })
    }

    /// Every setting of the full product, in axis order.
    fn product(&self) -> Vec<Setting> {
        let mut out = Vec::with_capacity(self.product_len());
        for &refresh_period in &self.refresh_periods {
            for &refresh_quad in &self.refresh_quads {
                for &reconstruction in &self.reconstructions {
                    for &cache_format in &self.cache_formats {
                        for &depth_epsilon in &self.depth_epsilons {
                            out.push(Setting {
                                refresh_period,
                                refresh_quad,
                                reconstruction,
                                cache_format,
                                depth_epsilon,
                                adaptive: false,
                            });
                        }
                    }
                }
            }
        }
        out
    }
}

impl Setting {
    /// Rewrite options with this setting over `base` for `variant`: its
    /// reconstruction and adaptive refresh as the variant takes them (a
    /// cache variant's read-back and refresh, lowres's upsampler and
    /// reshading); refused where the variant cannot take them.
    pub fn rewrite_options_of(
        &self,
        variant: Variant,
        base: &RewriteOptions,
    ) -> Result<RewriteOptions, Refusal> {
        let mut options = self.rewrite_options(base);
        options.set_reconstruction(variant, self.reconstruction)?;
        options.set_adaptive(variant, self.adaptive)?;
        Ok(options)
    }

    /// Rewrite options with this setting over `base` as the cache
    /// variants take it (an upsampler leaves `base`'s read-back).
    pub fn rewrite_options(&self, base: &RewriteOptions) -> RewriteOptions {
        RewriteOptions {
            refresh_period: self.refresh_period,
            refresh_quad: self.refresh_quad,
            reconstruction: self
                .reconstruction
                .cache_read()
                .unwrap_or(base.reconstruction),
            cache_format: self.cache_format,
            depth_epsilon: self.depth_epsilon,
            ..base.clone()
        }
    }
}

/// The settings to measure per node, for `variants` variants each.
#[derive(Clone, Debug)]
pub struct Grid {
    /// How the grid was walked.
    pub design: Design,
    /// The values of each knob.
    pub axes: Axes,
    /// Settings per node, in the order of the nodes given to [`Grid::new`].
    pub settings: Vec<Vec<Setting>>,
    /// What was left out, and why.
    pub pruned: Vec<Pruned>,
    /// Configurations of the full grid (nodes × variants × product).
    pub full: usize,
}

impl Grid {
    /// The grid for nodes `(id, estimated P/T)` and `variants` variants.
    pub fn new(axes: Axes, design: Design, nodes: &[(String, f64)], variants: usize) -> Self {
        let product = axes.product();
        let full = nodes.len() * variants * product.len();
        let mut pruned = Vec::new();
        let base = axes.base();
        let settings = nodes
            .iter()
            .map(|(id, estimate)| {
                if design == Design::Full {
                    return product.clone();
                }
                let f = estimate.clamp(0.0, 1.0);
                let mut kept = Vec::new();
                let mut by_cost = 0;
                let mut by_plane = 0;
                for setting in &product {
                    let bound = ideal_bound(setting.refresh_period, f);
                    if bound < MIN_IDEAL_SPEEDUP {
                        by_cost += 1;
                    } else if base.is_some_and(|b| on_a_plane(setting, &b)) {
                        kept.push(*setting);
                    } else {
                        by_plane += 1;
                    }
                }
                if by_cost > 0 {
                    let periods: Vec<String> = axes
                        .refresh_periods
                        .iter()
                        .filter(|&&p| ideal_bound(p, f) < MIN_IDEAL_SPEEDUP)
                        .map(|p| p.to_string())
                        .collect();
                    pruned.push(Pruned {
                        rule: "cost-model".into(),
                        node: Some(id.clone()),
                        configurations: by_cost * variants,
                        reason: format!(
                            "estimated P/T {f:.2}: with Δn = {} the ideal bound 1/(1 − (1 − 1/Δn)·P/T) is below {MIN_IDEAL_SPEEDUP}×",
                            periods.join(", ")
                        ),
                    });
                }
                if by_plane > 0 {
                    pruned.push(Pruned {
                        rule: "planes".into(),
                        node: Some(id.clone()),
                        configurations: by_plane * variants,
                        reason: "cross terms of the refresh plane (Δn × k) and the read-back plane (format × reconstruction × ε) away from the base setting".into(),
                    });
                }
                kept
            })
            .collect();
        Grid {
            design,
            axes,
            settings,
            pruned,
            full,
        }
    }

    /// Configurations to measure.
    pub fn len(&self, variants: usize) -> usize {
        self.settings.iter().map(Vec::len).sum::<usize>() * variants
    }
}

/// 1 / (1 − ρ·f) with the most reuse a refresh period allows, ρ = 1 − 1/Δn
/// (Δn = 0 turns refresh off: ρ = 1).
pub fn ideal_bound(refresh_period: u32, p_over_t: f64) -> f64 {
    let reuse = if refresh_period == 0 {
        1.0
    } else {
        1.0 - 1.0 / f64::from(refresh_period)
    };
    1.0 / (1.0 - reuse * p_over_t).max(1e-6)
}

/// On the refresh plane or the read-back plane through `base`.
fn on_a_plane(setting: &Setting, base: &Setting) -> bool {
    let refresh_as_base =
        setting.refresh_period == base.refresh_period && setting.refresh_quad == base.refresh_quad;
    let read_back_as_base = setting.reconstruction == base.reconstruction
        && setting.cache_format == base.cache_format
        && setting.depth_epsilon == base.depth_epsilon;
    refresh_as_base || read_back_as_base
}

/// The settings the grid walks for one variant of a node, in order.
pub(super) fn variant_settings(
    settings: &[Setting],
    variant: Variant,
    base: &RewriteOptions,
    lowres: (&[Upsampler], &[bool]),
) -> Vec<Setting> {
    if variant.upsamples() {
        lowres_settings(settings, base, lowres)
    } else {
        adaptive_settings(settings, lowres.1, base)
    }
}

/// The nodes a run measures, each with the part of its configurations
/// (numbered from 0 within the node, in the order the grid walks them:
/// variants, then settings; `configurations_of` counts them) that is the
/// run's, and how many the grid has. Unsharded, every node and all of
/// each. A shard (`--shard K/N`)
/// takes a contiguous slice of the grid's configurations
/// ([`crate::report::Shard::slice`]), so it touches about 1/N of the
/// nodes, and sets up and times the fixed-cost runs of those alone: the
/// payload and probe runs of every node in every shard are what kept a
/// sharded sweep over hundreds of nodes from fitting in memory.
pub(super) fn shard_nodes<T>(
    nodes: Vec<T>,
    configurations_of: impl Fn(&T) -> usize,
    shard: Option<crate::report::Shard>,
) -> (Vec<T>, Vec<std::ops::Range<usize>>, usize) {
    let counts: Vec<usize> = nodes.iter().map(configurations_of).collect();
    let total = counts.iter().sum();
    let slice = shard.map_or(0..total, |s| s.slice(total));
    let mut first = 0;
    let (mut kept, mut takes) = (Vec::new(), Vec::new());
    for (node, count) in nodes.into_iter().zip(counts) {
        let (start, end) = (slice.start.max(first), slice.end.min(first + count));
        // Unsharded, every node stays, as its payload is measured whatever
        // its configurations.
        if start < end || shard.is_none() {
            kept.push(node);
            takes.push(start - first..end - first);
        }
        first += count;
    }
    (kept, takes, total)
}

/// The cache variants' settings with adaptive refresh as `adaptive` asks:
/// off, or on for every setting; asked both ways (a sweep), every setting
/// without it and the base setting (`base`'s knobs) with it too: one
/// more point per node and variant, as the sweep's planes go through the
/// base.
pub(super) fn adaptive_settings(
    settings: &[Setting],
    adaptive: &[bool],
    base: &RewriteOptions,
) -> Vec<Setting> {
    let with = |setting: &Setting, adaptive| Setting {
        adaptive,
        ..*setting
    };
    match (adaptive.contains(&false), adaptive.contains(&true)) {
        (_, false) => settings.to_vec(),
        (false, true) => settings.iter().map(|s| with(s, true)).collect(),
        (true, true) => {
            let base = Setting {
                refresh_period: base.refresh_period,
                refresh_quad: base.refresh_quad,
                reconstruction: base.reconstruction.into(),
                cache_format: base.cache_format,
                depth_epsilon: base.depth_epsilon,
                adaptive: true,
            };
            let mut out = settings.to_vec();
            out.push(base);
            out
        }
    }
}

/// Lowres's settings: each of its reconstructions at each cache format
/// the grid measures, its Δn and k those its factor sets (s², s); the
/// refresh knobs of the cache variants do not apply to it.
pub(super) fn lowres_settings(
    settings: &[Setting],
    base: &RewriteOptions,
    (upsamplers, reshades): (&[Upsampler], &[bool]),
) -> Vec<Setting> {
    let s = base.upsampling.factor;
    let mut formats: Vec<CacheFormat> = settings.iter().map(|s| s.cache_format).collect();
    formats.dedup();
    let mut out = Vec::new();
    for &upsampler in upsamplers {
        let reconstruction = upsampler.into();
        for &cache_format in &formats {
            for &adaptive in reshades {
                let setting = Setting {
                    refresh_period: s * s,
                    refresh_quad: s,
                    reconstruction,
                    cache_format,
                    depth_epsilon: base.depth_epsilon,
                    adaptive,
                };
                if !out.contains(&setting) {
                    out.push(setting);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_full_design_measures_the_product() {
        let axes = Axes::sweep();
        let grid = Grid::new(axes.clone(), Design::Full, &[("a".into(), 0.01)], 3);
        assert_eq!(grid.settings[0].len(), 480);
        assert_eq!(grid.len(3), 1440);
        assert!(grid.pruned.is_empty());
    }

    #[test]
    fn planes_keep_the_two_planes_through_the_base() {
        let grid = Grid::new(Axes::sweep(), Design::Planes, &[("a".into(), 0.9)], 1);
        // 20 refresh settings + 24 read-back settings, sharing the base.
        assert_eq!(grid.settings[0].len(), 20 + 24 - 1);
        let base = grid.axes.base().unwrap();
        assert_eq!(base.refresh_period, 32);
        assert_eq!(base.refresh_quad, 4);
        assert!(grid.settings[0].contains(&base));
        let pruned: usize = grid.pruned.iter().map(|p| p.configurations).sum();
        assert_eq!(pruned + grid.len(1), grid.full);
    }

    #[test]
    fn the_cost_model_prunes_periods_that_cannot_pay() {
        // f = 0.15: Δn = 4 gives at most 1/(1 − 0.75·0.15) = 1.127×,
        // so nothing is pruned at 1.1; f = 0.1 prunes Δn = 4 (1.08×) and
        // Δn = 8 (1.096×) but keeps Δn = 16 (1.10×).
        let grid = Grid::new(
            Axes::sweep(),
            Design::Planes,
            &[("a".into(), 0.15), ("b".into(), 0.1), ("c".into(), 0.01)],
            2,
        );
        assert!(grid.settings[0].iter().any(|s| s.refresh_period == 4));
        assert!(grid.settings[1]
            .iter()
            .all(|s| s.refresh_period != 4 && s.refresh_period != 8));
        assert!(grid.settings[1].iter().any(|s| s.refresh_period == 16));
        assert!(
            grid.settings[2].is_empty(),
            "a node that cannot pay is dropped"
        );
        let cost: Vec<&Pruned> = grid
            .pruned
            .iter()
            .filter(|p| p.rule == "cost-model")
            .collect();
        assert_eq!(cost.len(), 2);
        assert!(cost[0].reason.contains("Δn = 4, 8"), "{}", cost[0].reason);
        let pruned: usize = grid.pruned.iter().map(|p| p.configurations).sum();
        assert_eq!(pruned + grid.len(2), grid.full);
    }

    #[test]
    fn refresh_off_allows_full_reuse() {
        assert!((ideal_bound(0, 0.5) - 2.0).abs() < 1e-9);
        assert!((ideal_bound(2, 0.5) - 1.0 / 0.75).abs() < 1e-9);
    }
}

//! What each variant is made of: its passes, how they read what last
//! frame left, what it refuses and what its plan says of its cache.
//!
//! [`Recipe::of`] is the one place a variant's name (the plan's
//! [`Variant`], what files and the command line say) becomes what builds
//! it. The cache variants' read-back and lowres's upsampler are separate
//! types, so a recipe cannot mix them. Adding a variant is an arm here
//! and the module that builds its passes.

use super::gbuffer::Keeps;
use super::helpers::Readback;
use super::lowres;
use super::stage::{CacheStage, Stage};
use super::{Options, Refusal};
use crate::plan::{CacheRead, Reconstruction, Upsampling, Variant};

/// A variant as the rewrite builds it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Recipe {
    /// One-, two- or three-pass (seed 002 §3): passes that draw the
    /// geometry and read the cache with `read`.
    Cache {
        passes: CachePasses,
        read: CacheRead,
    },
    /// Three-pass's passes in screen space, after one geometry pass into a
    /// G-buffer ([`super::gbuffer`]).
    Deferred { read: CacheRead },
    /// The payload shaded at 1/s × 1/s of the pixels and upsampled
    /// (seed 001, [`super::lowres`]); `deferred`, its passes in screen
    /// space after one geometry pass into a G-buffer (the paper's
    /// pipeline).
    Lowres {
        upsampling: Upsampling,
        deferred: bool,
    },
}

/// How many passes a cache variant draws the geometry in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CachePasses {
    One,
    Two,
    Three,
}

impl Recipe {
    /// What builds `variant` with `options`; the reference (the shader
    /// as written) and settings the variant cannot take are refused.
    pub fn of(variant: Variant, options: &Options) -> Result<Recipe, Refusal> {
        let read = options.reconstruction;
        Ok(match variant {
            Variant::OnePass => Recipe::Cache {
                passes: CachePasses::One,
                read,
            },
            Variant::TwoPass => Recipe::Cache {
                passes: CachePasses::Two,
                read,
            },
            Variant::ThreePass => Recipe::Cache {
                passes: CachePasses::Three,
                read,
            },
            Variant::Deferred => Recipe::Deferred { read },
            Variant::Lowres | Variant::DeferredLowres => {
                options.upsampling.check().map_err(Refusal::new)?;
                Recipe::Lowres {
                    upsampling: options.upsampling.clone(),
                    deferred: variant == Variant::DeferredLowres,
                }
            }
            Variant::Reference => {
                return Err(Refusal::new(
                    "the reference is the original shader; there is nothing to rewrite",
                ))
            }
        })
    }

    /// The variant's name.
    pub fn variant(&self) -> Variant {
        match self {
            Recipe::Cache { passes, .. } => match passes {
                CachePasses::One => Variant::OnePass,
                CachePasses::Two => Variant::TwoPass,
                CachePasses::Three => Variant::ThreePass,
            },
            Recipe::Deferred { .. } => Variant::Deferred,
            Recipe::Lowres {
                deferred: false, ..
            } => Variant::Lowres,
            Recipe::Lowres { deferred: true, .. } => Variant::DeferredLowres,
        }
    }

    /// Its passes, as the fragment stages they run, in order.
    pub fn stages(&self) -> Vec<Stage> {
        use CacheStage as C;
        let cache = |stages: &[CacheStage]| stages.iter().copied().map(Stage::Cache).collect();
        match self {
            Recipe::Cache { passes, .. } => match passes {
                CachePasses::One => cache(&[C::OnePass]),
                CachePasses::Two => cache(&[C::ReuseOrDiscard, C::Full]),
                CachePasses::Three => {
                    cache(&[C::ReprojectOrDiscard, C::Payload, C::ShadeFromCache])
                }
            },
            // Three-pass's passes in screen space, after the one geometry
            // pass.
            Recipe::Deferred { .. } => std::iter::once(Stage::GBuffer)
                .chain(cache(&[
                    C::ReprojectOrDiscard,
                    C::Payload,
                    C::ShadeFromCache,
                ]))
                .collect(),
            Recipe::Lowres {
                upsampling,
                deferred,
            } => lowres::stages(upsampling, *deferred),
        }
    }

    /// How its passes read what last frame left.
    pub fn readback(&self) -> Readback {
        match self {
            Recipe::Cache { read, .. } | Recipe::Deferred { read } => Readback::Cache(*read),
            Recipe::Lowres { upsampling, .. } => Readback::History(upsampling.reconstruction),
        }
    }

    /// The plan's name for its read-back.
    pub fn reconstruction(&self) -> Reconstruction {
        match self.readback() {
            Readback::Cache(read) => read.into(),
            Readback::History(upsampler) => upsampler.into(),
        }
    }

    /// Its upsampling, when it shades samples and upsamples them.
    pub fn upsampling(&self) -> Option<&Upsampling> {
        match self {
            Recipe::Lowres { upsampling, .. } => Some(upsampling),
            _ => None,
        }
    }

    /// With a G-buffer (the deferred variants), what it keeps beyond the
    /// inputs the shader reads: the fragment's depth where the cache packs
    /// it, and lowres's geometry.
    pub fn screen_space(&self) -> Option<Keeps> {
        match self {
            Recipe::Deferred { read } => Some(Keeps {
                depth: read.packs_depth(),
                lowres: false,
            }),
            Recipe::Lowres { deferred: true, .. } => Some(Keeps {
                depth: false,
                lowres: true,
            }),
            _ => None,
        }
    }

    /// Why it cannot be built on a module without its vertex stage (one
    /// composed with the host's), when it cannot.
    pub fn needs_vertex_stage(&self) -> Option<&'static str> {
        matches!(
            self,
            Recipe::Lowres {
                deferred: false,
                ..
            }
        )
        .then_some(lowres::NEEDS_VERTEX_STAGE)
    }
}

impl Options {
    /// Takes `reconstruction` as `variant` reads back: a cache variant's
    /// read of its cache, lowres's upsampler. A reconstruction the variant
    /// does not read with is refused with its reason.
    pub fn set_reconstruction(
        &mut self,
        variant: Variant,
        reconstruction: Reconstruction,
    ) -> Result<(), Refusal> {
        match Recipe::of(variant, self)? {
            Recipe::Lowres { .. } => {
                self.upsampling.reconstruction = reconstruction.upsampler().ok_or_else(|| {
                    Refusal::new(format!(
                        "{variant} rebuilds the payload from its samples: its reconstruction is nearest, bilinear, spatial, temporal or spatio-temporal, not {reconstruction}"
                    ))
                })?;
            }
            Recipe::Cache { .. } | Recipe::Deferred { .. } => {
                self.reconstruction = reconstruction.cache_read().ok_or_else(|| {
                    Refusal::new(format!(
                        "{reconstruction} reconstruction upsamples lowres's samples; {variant} reads its cache with bilinear, nearest, bilinear-packed or nearest-packed"
                    ))
                })?;
            }
        }
        Ok(())
    }

    /// Turns `variant`'s adaptive refresh on or off: a cache variant's
    /// refresh of the values that changed, lowres's reshading of the
    /// pixels it cannot vouch for.
    pub fn set_adaptive(&mut self, variant: Variant, adaptive: bool) -> Result<(), Refusal> {
        match Recipe::of(variant, self)? {
            Recipe::Lowres { .. } => self.upsampling.reshade = adaptive,
            Recipe::Cache { .. } | Recipe::Deferred { .. } => self.adaptive_refresh = adaptive,
        }
        Ok(())
    }
}

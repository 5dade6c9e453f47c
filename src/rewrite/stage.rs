//! The passes a variant is made of: each pass's fragment stage
//! ([`Stage`]) and what it writes ([`Writes`]).

/// What a pass's fragment stage writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Writes {
    /// The original outputs plus the cache and its age at the next two
    /// free locations.
    ColorAndCache,
    /// The cache alone, at location 0, and its age at location 1.
    Cache,
    /// The original outputs alone.
    Color,
    /// The cache's decision as a colour, at location 0.
    Classes,
    /// The G-buffer's textures, at locations from 0.
    GBuffer,
    /// Lowres's samples at location 0 and their geometry at 1.
    Samples,
    /// The original outputs plus the upsampled payload and its history at
    /// the next two free locations.
    ColorAndHistory,
    /// No colour: the pass marks the stencil alone.
    Stencil,
}

/// The fragment entry point of one pass: one of the stages that read the
/// cache, the deferred variant's G-buffer pass, or one of lowres's. Each
/// kind is built by its own module ([`super::fragment`],
/// [`super::gbuffer`], [`super::lowres`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// A pass that looks the fragment up in the cache, or fills it.
    Cache(CacheStage),
    /// The deferred variant's geometry pass: depth, and the fragment's
    /// inputs and previous clip position into the G-buffer.
    GBuffer,
    /// A pass of lowres's.
    Lowres(LowresStage),
}

/// The stages built from the cache's lookup and the payload/shade split
/// ([`super::fragment::entry_point`]), drawing the geometry or, deferred,
/// in screen space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CacheStage {
    /// One-pass: hit → shade from the cache; miss or refresh → payload.
    OnePass,
    /// Two-pass, pass 1: hit → colour + cache; miss or refresh → discard.
    ReuseOrDiscard,
    /// The original computation, writing colour and cache (two-pass pass 2).
    Full,
    /// Three-pass, pass 1: hit → cache; miss or refresh → discard.
    ReprojectOrDiscard,
    /// Three-pass, pass 2: the payload into the cache.
    Payload,
    /// Three-pass, pass 3: shade from the cache at the pixel itself.
    ShadeFromCache,
    /// A diagnostic pass, drawn after a frame: the cache's decision at each
    /// visible pixel as a colour (reuse, refresh, off-screen, disoccluded).
    Classify,
}

/// Lowres's passes ([`super::lowres`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LowresStage {
    /// In screen space (deferred lowres), before the samples: each draw's
    /// pixels of this frame's lattice marked in the stencil of the
    /// samples' size, from the draw ordinals the G-buffer keeps.
    Lattice,
    /// Pass 1: the payload at 1/s × 1/s of the pixels, jittered, and the
    /// samples' geometry.
    Samples,
    /// Pass 2: the payload rebuilt at every pixel from the samples and the
    /// history, and the shading from it.
    Upsample,
    /// With adaptive refresh, pass 3: the original computation at the
    /// pixels the upsampling left (its unreliable ones), writing colour,
    /// the payload and an exact history.
    Reshade,
}

impl Stage {
    /// What its fragment stage writes.
    pub fn writes(self) -> Writes {
        use CacheStage as C;
        match self {
            Stage::Cache(C::OnePass | C::ReuseOrDiscard | C::Full) => Writes::ColorAndCache,
            Stage::Cache(C::ReprojectOrDiscard | C::Payload) => Writes::Cache,
            Stage::Cache(C::ShadeFromCache) => Writes::Color,
            Stage::Cache(C::Classify) => Writes::Classes,
            Stage::GBuffer => Writes::GBuffer,
            Stage::Lowres(LowresStage::Lattice) => Writes::Stencil,
            Stage::Lowres(LowresStage::Samples) => Writes::Samples,
            Stage::Lowres(LowresStage::Upsample | LowresStage::Reshade) => Writes::ColorAndHistory,
        }
    }

    /// Whether its fragment stage may discard.
    pub fn discards(self) -> bool {
        matches!(
            self,
            Stage::Cache(CacheStage::ReuseOrDiscard | CacheStage::ReprojectOrDiscard)
                | Stage::Lowres(LowresStage::Lattice)
        )
    }

    /// Whether the pass looks the fragment up in last frame's cache, and
    /// so reads the previous clip position. The others are drawn with the
    /// vertex stage as the original has it (no previous-frame twin, no
    /// extra varying).
    pub fn reprojects(self) -> bool {
        use CacheStage as C;
        matches!(
            self,
            Stage::Cache(C::OnePass | C::ReuseOrDiscard | C::ReprojectOrDiscard | C::Classify)
                | Stage::GBuffer
                | Stage::Lowres(LowresStage::Samples | LowresStage::Upsample)
        )
    }

    /// Whether the screen shows the cached value itself (not recomputed
    /// where it cannot be held): what a cache format must hold exactly.
    pub fn shows_cached_value(self) -> bool {
        self == Stage::Cache(CacheStage::ShadeFromCache)
    }

    /// Whether the payload is computed in the miss branch, in non-uniform
    /// control flow: its derivatives must be taken before it.
    pub fn computes_payload_on_miss(self) -> bool {
        self == Stage::Cache(CacheStage::OnePass)
    }
}

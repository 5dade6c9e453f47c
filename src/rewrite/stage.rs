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
}

/// The fragment entry point of one pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The deferred variant's geometry pass: depth, and the fragment's
    /// inputs and previous clip position into the G-buffer.
    GBuffer,
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
    /// Lowres, pass 1: the payload at 1/s × 1/s of the pixels, jittered,
    /// and the samples' geometry ([`super::lowres`]).
    Samples,
    /// Lowres, pass 2: the payload rebuilt at every pixel from the samples
    /// and the history, and the shading from it.
    Upsample,
    /// Lowres with adaptive refresh, pass 3: the original computation at
    /// the pixels the upsampling left (its unreliable ones), writing
    /// colour, the payload and an exact history.
    Reshade,
}

impl Stage {
    pub fn writes(self) -> Writes {
        match self {
            Stage::OnePass | Stage::ReuseOrDiscard | Stage::Full => Writes::ColorAndCache,
            Stage::ReprojectOrDiscard | Stage::Payload => Writes::Cache,
            Stage::ShadeFromCache => Writes::Color,
            Stage::Classify => Writes::Classes,
            Stage::GBuffer => Writes::GBuffer,
            Stage::Samples => Writes::Samples,
            Stage::Upsample | Stage::Reshade => Writes::ColorAndHistory,
        }
    }

    pub fn discards(self) -> bool {
        matches!(self, Stage::ReuseOrDiscard | Stage::ReprojectOrDiscard)
    }

    /// Whether the pass looks the fragment up in last frame's cache, and
    /// so reads the previous clip position. The others are drawn with the
    /// vertex stage as the original has it (no previous-frame twin, no
    /// extra varying).
    pub fn reprojects(self) -> bool {
        matches!(
            self,
            Stage::OnePass
                | Stage::ReuseOrDiscard
                | Stage::ReprojectOrDiscard
                | Stage::Classify
                | Stage::GBuffer
                | Stage::Samples
                | Stage::Upsample
        )
    }

    /// Whether the screen shows the cached value itself (not recomputed
    /// where it cannot be held): what a cache format must hold exactly.
    pub fn shows_cached_value(self) -> bool {
        matches!(self, Stage::ShadeFromCache)
    }

    /// Whether the payload is computed in the miss branch, in non-uniform
    /// control flow: its derivatives must be taken before it.
    pub fn computes_payload_on_miss(self) -> bool {
        matches!(self, Stage::OnePass)
    }
}

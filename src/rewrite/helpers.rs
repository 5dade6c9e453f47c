//! The cache's helper functions (`shaders/cache.wgsl`), imported into the
//! module being rewritten: the lookup the settings choose, the refresh
//! decision, the classification, the encoding of a written payload.

use naga::{Function, Handle, Module};

use super::split::Split;
use super::{cache_helpers, CacheSlot, Options, Refusal};
use crate::analysis::Candidate;
use crate::plan::{CacheFormat, CacheRead, Upsampler};

/// The pieces every fragment entry point is built from.
#[derive(Debug)]
pub struct Pieces {
    /// The original fragment entry point's arguments.
    pub arguments: Vec<naga::FunctionArgument>,
    /// Its result.
    pub result: naga::FunctionResult,
    pub name: String,
    pub payload: Handle<Function>,
    /// One-pass with derivatives in the payload: computes them before the
    /// branch; the payload function then takes its result as a last
    /// argument (see [`super::gradients`]).
    pub gradients: Option<Handle<Function>>,
    pub shade: Handle<Function>,
    /// The payload's type and component count.
    pub payload_ty: Handle<naga::Type>,
    pub components: u32,
    pub previous_location: u32,
    pub lookup: Handle<Function>,
    pub refresh: Handle<Function>,
    pub current: Handle<Function>,
    pub classify: Handle<Function>,
    /// The age written beside a payload (`cache_age_written`).
    pub age_written: Handle<Function>,
    /// For a node under branches ([`super::path`]): whether the original
    /// computes it at this pixel, and the helper that marks the pixels
    /// where it does not (`cache_classify_absent`).
    pub presence: Option<(Handle<Function>, Handle<Function>)>,
    /// Applied to every payload written to the cache (`cache_encode`).
    pub encode: Handle<Function>,
    /// With a packed reconstruction, puts the fragment's depth into the
    /// cache's fourth channel (`cache_pack`), before `encode`.
    pub pack: Option<Handle<Function>>,
    pub vec4: Handle<naga::Type>,
    /// The lowres variant's helpers.
    pub lowres: LowresHelpers,
    /// With adaptive refresh, the age a computed value starts from
    /// (`cache_adaptive_age`).
    pub adaptive: Option<Handle<Function>>,
}

/// The imported helpers the lowres passes call.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LowresHelpers {
    pub jitter: Handle<Function>,
    pub sample_texel: Handle<Function>,
    pub upsample: Handle<Function>,
    pub unit_normal: Handle<Function>,
    pub geometric_normal: Handle<Function>,
    /// The history's lookup (`cache_history`, or `cache_history_loads`
    /// for an rgba32float cache).
    pub history: Handle<Function>,
    /// The history of a pixel shaded at full resolution.
    pub exact_history: Handle<Function>,
    /// In screen space: the full-resolution pixel a sample shades
    /// (`cache_lattice_pixel`), and the draw's ordinal the G-buffer keeps
    /// (`cache_draw_id`).
    pub lattice_pixel: Handle<Function>,
    pub draw_id: Handle<Function>,
}

/// How a variant's passes read what last frame left: a cache variant's
/// cache, or lowres's history behind its upsampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Readback {
    Cache(CacheRead),
    History(Upsampler),
}

/// The imported helpers a variant's passes call.
pub(super) struct CacheHelpers {
    lookup: Handle<Function>,
    refresh: Handle<Function>,
    current: Handle<Function>,
    classify: Handle<Function>,
    classify_absent: Handle<Function>,
    age_written: Handle<Function>,
    encode: Handle<Function>,
    /// With a packed reconstruction, `cache_pack`.
    pack: Option<Handle<Function>>,
    /// "No value": a payload's value where the node is not computed.
    pub absent: Handle<Function>,
    vec4: Handle<naga::Type>,
    lowres: LowresHelpers,
    adaptive: Option<Handle<Function>>,
}

impl CacheHelpers {
    /// Imports the helpers into `module`, their resources bound at `slot`.
    pub fn import(
        module: &mut Module,
        slot: CacheSlot,
        options: &Options,
        readback: Readback,
        candidate: &Candidate,
    ) -> Result<CacheHelpers, Refusal> {
        let imported =
            crate::proc::import::import(module, cache_helpers()?, slot.group, slot.first_binding)
                .map_err(|err| Refusal::internal(format!("importing the cache helpers: {err}")))?;
        let helper = |name: &str| {
            imported.functions.get(name).copied().ok_or_else(|| {
                Refusal::internal(format!("`{name}` missing from the cache helpers"))
            })
        };
        // rgba16float is filterable: one bilinear sample; rgba32float is
        // not: four loads. Nearest reads one texel of each. Packed
        // reconstructions read the depth from the payload texture instead.
        let lookup = match (readback, options.cache_format) {
            // Lowres reads its history bilinearly (with nearest and
            // bilinear upsampling it reads none).
            (Readback::Cache(CacheRead::Nearest) | Readback::History(Upsampler::Nearest), _) => {
                "cache_lookup_nearest"
            }
            (
                Readback::Cache(CacheRead::Bilinear) | Readback::History(_),
                CacheFormat::Rgba16float,
            ) => "cache_lookup",
            (
                Readback::Cache(CacheRead::Bilinear) | Readback::History(_),
                CacheFormat::Rgba32float,
            ) => "cache_lookup_loads",
            (Readback::Cache(CacheRead::NearestPacked), _) => "cache_lookup_nearest_packed",
            (Readback::Cache(CacheRead::BilinearPacked), CacheFormat::Rgba16float) => {
                "cache_lookup_packed"
            }
            (Readback::Cache(CacheRead::BilinearPacked), CacheFormat::Rgba32float) => {
                "cache_lookup_loads_packed"
            }
        };
        let pack = match readback {
            Readback::Cache(read) if read.packs_depth() => {
                if candidate.components > 3 {
                    return Err(Refusal::new(format!(
                        "{} keeps the depth in the cache's fourth channel, and this payload has four components; use {} or {}",
                        read.as_str(),
                        CacheRead::Bilinear.as_str(),
                        CacheRead::Nearest.as_str()
                    )));
                }
                Some(helper("cache_pack")?)
            }
            _ => None,
        };
        let vec4 = super::builder::vec4_type(module);
        let lowres = matches!(readback, Readback::History(_));
        let adaptive = if options.adaptive_refresh && !lowres {
            Some(helper("cache_adaptive_age")?)
        } else {
            None
        };
        Ok(CacheHelpers {
            adaptive,
            lookup: helper(lookup)?,
            refresh: helper("cache_refresh")?,
            current: helper("cache_current")?,
            // Lowres's refreshed pixels are its lattice's.
            classify: helper(if lowres {
                "cache_classify_lowres"
            } else {
                "cache_classify"
            })?,
            classify_absent: helper("cache_classify_absent")?,
            age_written: helper("cache_age_written")?,
            encode: helper("cache_encode")?,
            absent: helper("cache_absent")?,
            pack,
            vec4,
            lowres: LowresHelpers {
                jitter: helper("cache_jitter")?,
                sample_texel: helper("cache_sample_texel")?,
                upsample: helper("cache_upsample")?,
                unit_normal: helper("cache_unit_normal")?,
                geometric_normal: helper("cache_geometric_normal")?,
                exact_history: helper("cache_exact_history")?,
                lattice_pixel: helper("cache_lattice_pixel")?,
                draw_id: helper("cache_draw_id")?,
                history: helper(match options.cache_format {
                    CacheFormat::Rgba16float => "cache_history",
                    CacheFormat::Rgba32float => "cache_history_loads",
                })?,
            },
        })
    }

    /// What the passes' fragment entry points are built from.
    pub fn pieces(
        &self,
        entry: &naga::EntryPoint,
        result: naga::FunctionResult,
        split: Split,
        candidate: &Candidate,
        previous_location: u32,
    ) -> Pieces {
        Pieces {
            arguments: entry.function.arguments.clone(),
            result,
            name: entry.name.clone(),
            payload: split.payload,
            gradients: split.gradients,
            shade: split.shade,
            payload_ty: split.payload_ty,
            components: candidate.components,
            previous_location,
            lookup: self.lookup,
            refresh: self.refresh,
            current: self.current,
            classify: self.classify,
            age_written: self.age_written,
            presence: split
                .presence
                .map(|presence| (presence, self.classify_absent)),
            encode: self.encode,
            pack: self.pack,
            vec4: self.vec4,
            lowres: self.lowres,
            adaptive: self.adaptive,
        }
    }
}

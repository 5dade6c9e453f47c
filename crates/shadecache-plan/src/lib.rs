//! The plan of a shadecache variant: the data that says how to run it.
//!
//! A [`Plan`] is written as `plan.json` next to a variant's pass shaders,
//! and whatever runs the variant — shadecache's own runtime and profiler,
//! or an application — executes exactly what it says: the passes in
//! order, per pass its shader and entry points, colour targets and
//! formats, depth compare and write, whether it discards and which
//! bindings it uses; the vertex layout; every binding the host supplies
//! (the original resources, their previous-frame twins, the cache
//! textures, the refresh uniforms); clear values; and the rule for
//! swapping the double-buffered cache. The repository's
//! `docs/plan-json.md` documents the format.
//!
//! This crate depends on serde alone, so an application reads plans
//! without linking the toolchain (naga, wgpu, the profiler); the
//! toolchain writes them with the same definitions. It also holds what
//! the toolchain and the applications both compute from frame times
//! ([`speed`]: the speed-up and its interval).

#![deny(missing_docs)]

pub mod speed;

use std::fmt;

use serde::{Deserialize, Serialize};

/// The depth buffer's format: it is also last frame's depth in the cache.
pub const DEPTH_FORMAT: TextureFormat = TextureFormat::Depth32Float;

/// The cache's age target: whole frames since each value was computed,
/// exact up to 2048 (`shaders/cache.wgsl`, `CACHE_AGE_LIMIT`).
pub const AGE_FORMAT: TextureFormat = TextureFormat::R16Float;

/// The version of the format this crate reads and writes: a plan's
/// `format`.
pub const FORMAT_VERSION: u32 = 1;

/// A texture format a plan names: a colour target, the cache, the depth
/// buffer. Written as WebGPU spells it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "&'static str", try_from = "String")]
pub enum TextureFormat {
    /// `rgba8unorm`.
    Rgba8Unorm,
    /// `rgba8unorm-srgb`.
    Rgba8UnormSrgb,
    /// `bgra8unorm`.
    Bgra8Unorm,
    /// `bgra8unorm-srgb`.
    Bgra8UnormSrgb,
    /// `r16float`.
    R16Float,
    /// `rg16float`.
    Rg16Float,
    /// `rgba16float`.
    Rgba16Float,
    /// `r32float`.
    R32Float,
    /// `rg32float`.
    Rg32Float,
    /// `rgba32float`.
    Rgba32Float,
    /// `r32uint`.
    R32Uint,
    /// `rg32uint`.
    Rg32Uint,
    /// `rgba32uint`.
    Rgba32Uint,
    /// `r32sint`.
    R32Sint,
    /// `rg32sint`.
    Rg32Sint,
    /// `rgba32sint`.
    Rgba32Sint,
    /// `depth16unorm`.
    Depth16Unorm,
    /// `depth24plus`.
    Depth24Plus,
    /// `depth24plus-stencil8`.
    Depth24PlusStencil8,
    /// `depth32float`.
    Depth32Float,
}

impl TextureFormat {
    /// Every format a plan may name.
    pub const ALL: [TextureFormat; 20] = [
        TextureFormat::Rgba8Unorm,
        TextureFormat::Rgba8UnormSrgb,
        TextureFormat::Bgra8Unorm,
        TextureFormat::Bgra8UnormSrgb,
        TextureFormat::R16Float,
        TextureFormat::Rg16Float,
        TextureFormat::Rgba16Float,
        TextureFormat::R32Float,
        TextureFormat::Rg32Float,
        TextureFormat::Rgba32Float,
        TextureFormat::R32Uint,
        TextureFormat::Rg32Uint,
        TextureFormat::Rgba32Uint,
        TextureFormat::R32Sint,
        TextureFormat::Rg32Sint,
        TextureFormat::Rgba32Sint,
        TextureFormat::Depth16Unorm,
        TextureFormat::Depth24Plus,
        TextureFormat::Depth24PlusStencil8,
        TextureFormat::Depth32Float,
    ];

    /// WebGPU's spelling, as the plan writes it.
    pub fn as_str(self) -> &'static str {
        match self {
            TextureFormat::Rgba8Unorm => "rgba8unorm",
            TextureFormat::Rgba8UnormSrgb => "rgba8unorm-srgb",
            TextureFormat::Bgra8Unorm => "bgra8unorm",
            TextureFormat::Bgra8UnormSrgb => "bgra8unorm-srgb",
            TextureFormat::R16Float => "r16float",
            TextureFormat::Rg16Float => "rg16float",
            TextureFormat::Rgba16Float => "rgba16float",
            TextureFormat::R32Float => "r32float",
            TextureFormat::Rg32Float => "rg32float",
            TextureFormat::Rgba32Float => "rgba32float",
            TextureFormat::R32Uint => "r32uint",
            TextureFormat::Rg32Uint => "rg32uint",
            TextureFormat::Rgba32Uint => "rgba32uint",
            TextureFormat::R32Sint => "r32sint",
            TextureFormat::Rg32Sint => "rg32sint",
            TextureFormat::Rgba32Sint => "rgba32sint",
            TextureFormat::Depth16Unorm => "depth16unorm",
            TextureFormat::Depth24Plus => "depth24plus",
            TextureFormat::Depth24PlusStencil8 => "depth24plus-stencil8",
            TextureFormat::Depth32Float => "depth32float",
        }
    }
}

impl fmt::Display for TextureFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for TextureFormat {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        TextureFormat::ALL
            .into_iter()
            .find(|format| format.as_str() == text)
            .ok_or_else(|| format!("unknown texture format `{text}`"))
    }
}

impl From<TextureFormat> for &'static str {
    fn from(format: TextureFormat) -> &'static str {
        format.as_str()
    }
}

impl TryFrom<String> for TextureFormat {
    type Error = String;

    fn try_from(text: String) -> Result<Self, String> {
        text.parse()
    }
}

/// A vertex input's format, as WebGPU spells it (`float32x3`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "&'static str", try_from = "String")]
pub enum VertexFormat {
    /// `float16`.
    Float16,
    /// `float16x2`.
    Float16x2,
    /// `float16x4`.
    Float16x4,
    /// `float32`.
    Float32,
    /// `float32x2`.
    Float32x2,
    /// `float32x3`.
    Float32x3,
    /// `float32x4`.
    Float32x4,
    /// `sint32`.
    Sint32,
    /// `sint32x2`.
    Sint32x2,
    /// `sint32x3`.
    Sint32x3,
    /// `sint32x4`.
    Sint32x4,
    /// `uint32`.
    Uint32,
    /// `uint32x2`.
    Uint32x2,
    /// `uint32x3`.
    Uint32x3,
    /// `uint32x4`.
    Uint32x4,
}

impl VertexFormat {
    /// Every format a plan may name.
    pub const ALL: [VertexFormat; 15] = [
        VertexFormat::Float16,
        VertexFormat::Float16x2,
        VertexFormat::Float16x4,
        VertexFormat::Float32,
        VertexFormat::Float32x2,
        VertexFormat::Float32x3,
        VertexFormat::Float32x4,
        VertexFormat::Sint32,
        VertexFormat::Sint32x2,
        VertexFormat::Sint32x3,
        VertexFormat::Sint32x4,
        VertexFormat::Uint32,
        VertexFormat::Uint32x2,
        VertexFormat::Uint32x3,
        VertexFormat::Uint32x4,
    ];

    /// WebGPU's spelling, as the plan writes it.
    pub fn as_str(self) -> &'static str {
        match self {
            VertexFormat::Float16 => "float16",
            VertexFormat::Float16x2 => "float16x2",
            VertexFormat::Float16x4 => "float16x4",
            VertexFormat::Float32 => "float32",
            VertexFormat::Float32x2 => "float32x2",
            VertexFormat::Float32x3 => "float32x3",
            VertexFormat::Float32x4 => "float32x4",
            VertexFormat::Sint32 => "sint32",
            VertexFormat::Sint32x2 => "sint32x2",
            VertexFormat::Sint32x3 => "sint32x3",
            VertexFormat::Sint32x4 => "sint32x4",
            VertexFormat::Uint32 => "uint32",
            VertexFormat::Uint32x2 => "uint32x2",
            VertexFormat::Uint32x3 => "uint32x3",
            VertexFormat::Uint32x4 => "uint32x4",
        }
    }
}

impl fmt::Display for VertexFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for VertexFormat {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        VertexFormat::ALL
            .into_iter()
            .find(|format| format.as_str() == text)
            .ok_or_else(|| format!("unknown vertex format `{text}`"))
    }
}

impl From<VertexFormat> for &'static str {
    fn from(format: VertexFormat) -> &'static str {
        format.as_str()
    }
}

impl TryFrom<String> for VertexFormat {
    type Error = String;

    fn try_from(text: String) -> Result<Self, String> {
        text.parse()
    }
}

impl VertexFormat {
    /// Components per input: 1 to 4.
    pub fn components(self) -> u32 {
        match self.as_str().rsplit_once('x') {
            Some((_, count)) => count.parse().unwrap_or(1),
            None => 1,
        }
    }

    /// Whether the input is floating point (else a 32-bit integer).
    pub fn is_float(self) -> bool {
        self.as_str().starts_with("float")
    }

    /// Whether the input is 32-bit floating point.
    pub fn is_float32(self) -> bool {
        use VertexFormat as V;
        matches!(
            self,
            V::Float32 | V::Float32x2 | V::Float32x3 | V::Float32x4
        )
    }
}

/// How to run one variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Version of this format.
    pub format: u32,
    /// The original shader's file, as the toolchain read it: what the passes
    /// were made from.
    pub shader: String,
    /// The original fragment entry point the variant rewrites.
    pub entry: String,
    /// The cached node: the intermediate value the cache holds.
    pub node: PlanNode,
    /// Which variant the passes make up; a host checks it is one it runs.
    pub variant: Variant,
    /// The frame's passes, in the order a host records them.
    pub passes: Vec<Pass>,
    /// A diagnostic pass, drawn after the frame's passes and before the
    /// swap: the cache's decision at each visible pixel as a colour (green
    /// reuse, blue refresh, orange off-screen, red disoccluded). Not part
    /// of rendering a frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub classify: Option<Pass>,
    /// The vertex buffers' attributes every geometry pass reads (buffer slot 0
    /// per vertex, slot 1 per instance), in packing order.
    pub vertex_layout: Vec<VertexAttribute>,
    /// The lowres variant's upsampling (seed 001): its factor s and the
    /// reconstruction's knobs. Absent for the other variants.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upsampling: Option<Upsampling>,
    /// For a fragment-only module: what the host's own vertex stage must
    /// output for these passes (absent when the module has its vertex
    /// stage and the passes carry it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub host_vertex: Option<HostVertex>,
    /// Every resource the passes bind: the original ones, their previous-frame
    /// twins and the cache's own.
    pub bindings: Bindings,
    /// The cache's textures: their format, how they are read back, and the
    /// refresh uniform's layout.
    pub cache: Cache,
    /// The refresh pattern's settings, as the `CacheParams` uniform carries
    /// them.
    pub refresh: Refresh,
    /// The clear values of the frame's targets.
    pub clear: Clear,
    /// What the variant assumes of the frame it runs in; a host refuses a
    /// frame that breaks it.
    #[serde(default)]
    pub assumes: FrameAssumptions,
    /// The shader defs that change the code the passes were made from
    /// (of those the composed sources test with `@if`, `#ifdef` or
    /// `constants::`, each whose flip alone changes what the entry points
    /// run, and every number), each with the value the passes were
    /// composed with.
    /// An engine that composes the original once per draw state (Bevy, per
    /// mesh and view) draws through these passes only where it composes
    /// the original with the same values; any other def leaves the passes
    /// as they are. Empty for a shader composed without defs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shader_defs: Vec<ShaderDef>,
}

/// A shader def the composed source tests, and its value in the
/// composition the passes were made from.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShaderDef {
    /// The def's name (`VERTEX_UVS`).
    pub name: String,
    /// Its value: unset, a boolean, or a number (which also turns the
    /// feature of its name on, as Bevy and naga_oil do).
    pub value: ShaderDefValue,
}

/// A shader def's value; a def set to `false` is unset (a WESL feature
/// that is off).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShaderDefValue {
    /// Not set, or set to `false`.
    Unset,
    /// Set, with no value (`true`).
    Set,
    /// A signed number.
    Int(i32),
    /// An unsigned number.
    #[serde(rename = "uint")]
    UInt(u32),
}

/// How the lowres variant rebuilds the payload at full resolution from
/// the samples it shades at 1/s × 1/s of the pixels (seed 001).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Upsampling {
    /// How the payload is rebuilt from the samples: nearest, bilinear,
    /// spatial, temporal or spatio-temporal (the paper's method).
    #[serde(default = "spatio_temporal")]
    pub reconstruction: Upsampler,
    /// s: one pixel of each s×s window is shaded per frame (2 or 4), the
    /// window's offset stepping through a Bayer order of the s² positions
    /// (`refresh_phase` = frame mod s²).
    pub factor: u32,
    /// σn of the normal weight (eq. 2).
    pub sigma_normal: f32,
    /// σz of the depth weight: a share of the view depth, |z_i − z_j| /
    /// z_i, or with `depth_tolerance` of the depth range (eq. 2).
    pub sigma_depth: f32,
    /// a: the sensitivity of the history's weight to the temporal gradient
    /// (eq. 8); 1 in most of the paper's scenes.
    pub sensitivity: f32,
    /// Adaptive refresh: shade at full resolution, in a third pass, the
    /// pixels the upsampling cannot vouch for (the paper's Fig. 5 "red":
    /// no temporal weight, being disoccluded or changed, and undersampled,
    /// with no own sample this frame) instead of showing their spatial
    /// guess.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub reshade: bool,
    /// The samples pass reads textures at the full resolution's level of
    /// detail: its derivatives are s times the full resolution's, so
    /// implicit-LOD samples get a bias of −log2 s and explicit gradients
    /// and derivatives are scaled by 1/s. Off, the samples read log2 s
    /// mip levels coarser (what the bias gives is measured by turning it
    /// off; the paper is silent on it). Ours.
    #[serde(default = "yes", skip_serializing_if = "is_yes")]
    pub lod_bias: bool,
    /// How the temporal gradient is filtered in space before eq. 8.
    #[serde(default, skip_serializing_if = "is_default")]
    pub gradient_filter: GradientFilter,
    /// The temporal reconstruction's holes (every pixel the history
    /// misses and this frame did not shade) shaded at full resolution in
    /// a third pass: the paper's temporal baseline, "with second-pass hole
    /// filling" (§5, after Sitthi-amorn et al. 2008). Off, they take the
    /// spatial upsampling (shaded only where `reshade` says so). The
    /// other reconstructions are not changed by it.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fill_holes: bool,
    /// What σz is a share of.
    #[serde(default, skip_serializing_if = "is_default")]
    pub depth_tolerance: DepthTolerance,
    /// The history's disocclusion test compares the draw's ordinal with
    /// the one the history keeps where the point was last frame, beside
    /// the depth: the paper's material ids, for contact points, where two
    /// surfaces meet at one depth. Off, depth alone decides. It holds
    /// where the application draws its meshes in the same order from
    /// frame to frame (a mesh culled or added shifts the ordinals after
    /// it, and their histories miss for that frame).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub material_ids: bool,
}

/// What lowres's σz (eq. 2's depth weight) is a share of.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DepthTolerance {
    /// Ours: of the pixel's view depth, |z_i − z_j| / z_i, which needs no
    /// camera planes and holds with reversed Z and an infinite far plane.
    #[default]
    OfDepth,
    /// The paper's (§3.1): of the camera's depth range, far − near, which
    /// the host must be given (`CachedShader::set_depth_range`); where it
    /// is not, or the far plane is infinite, of the depth.
    OfRange,
}

/// How lowres filters the temporal gradient in space (eq. 8's ∇).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GradientFilter {
    /// Ours: the samples' signed gradients, weighted as the spatial
    /// upsampling weighs them (normal, depth, draw and the image hat).
    #[default]
    Ours,
    /// The paper's (§3.5.1, Figs. 6–7): the absolute gradients, blind to
    /// the geometry, over the same four samples (the paper reads a mip of
    /// |∇| at level 2.5, a footprint of about the same width). Opposite
    /// changes side by side do not cancel, and a disocclusion spreads.
    Paper,
}

/// Whether a knob is at its default (and left out of the plan).
fn is_default<T: Default + PartialEq>(value: &T) -> bool {
    *value == T::default()
}

fn yes() -> bool {
    true
}

fn is_yes(value: &bool) -> bool {
    *value
}

/// The knobs of seed 001 as the paper sets them: spatio-temporal
/// reconstruction, σn = 0.2 (§3.1), σz as
/// 3% (§3.1, there of the depth range; here of the depth itself), a = 1
/// (§3.5.1), s = 4 (§3.2).
pub const DEFAULT_UPSAMPLING: Upsampling = Upsampling {
    reconstruction: Upsampler::SpatioTemporal,
    factor: 4,
    sigma_normal: 0.2,
    sigma_depth: 0.03,
    sensitivity: 1.0,
    reshade: false,
    lod_bias: true,
    gradient_filter: GradientFilter::Ours,
    fill_holes: false,
    depth_tolerance: DepthTolerance::OfDepth,
    material_ids: false,
};

fn spatio_temporal() -> Upsampler {
    Upsampler::SpatioTemporal
}

/// The narrowest width of lowres's weights (σn, σz) and the least
/// sensitivity a: the shader divides by σ², and below this σ² is a
/// subnormal or 0 in f32.
pub const MIN_SIGMA: f32 = 1e-6;
/// The widest weights: σ² stays within f32.
pub const MAX_SIGMA: f32 = 1e6;

impl Upsampling {
    /// These knobs with the paper's path wherever ours differs and is a
    /// knob: the absolute, geometry-blind gradient filter, the temporal
    /// baseline's hole filling, σz of the depth range and material ids in
    /// the disocclusion test. (The project's two rules, the exact sample
    /// and the dropped history, stay.)
    pub fn as_the_paper(&self) -> Upsampling {
        Upsampling {
            gradient_filter: GradientFilter::Paper,
            fill_holes: true,
            depth_tolerance: DepthTolerance::OfRange,
            material_ids: true,
            ..self.clone()
        }
    }

    /// The knobs in words, as the reports say them: `s = 4, σn = 0.2,
    /// σz = 0.03, a = 1`, and what differs from the defaults of the rest.
    pub fn in_words(&self) -> String {
        let mut words = format!(
            "s = {}, σn = {}, σz = {}, a = {}",
            self.factor, self.sigma_normal, self.sigma_depth, self.sensitivity
        );
        if !self.lod_bias {
            words.push_str(", no LOD bias");
        }
        if self.gradient_filter == GradientFilter::Paper {
            words.push_str(", the paper's gradient filter");
        }
        if self.fill_holes {
            words.push_str(", holes filled");
        }
        if self.depth_tolerance == DepthTolerance::OfRange {
            words.push_str(", σz of the depth range");
        }
        if self.material_ids {
            words.push_str(", material ids");
        }
        words
    }

    /// Whether a third pass shades what the upsampling leaves: with
    /// `reshade`, or for the temporal reconstruction with `fill_holes`.
    pub fn shades_leftovers(&self) -> bool {
        self.reshade || (self.fill_holes && self.reconstruction == Upsampler::Temporal)
    }

    /// Checks the knobs: s is 2 or 4, σn and σz lie in
    /// [[`MIN_SIGMA`], [`MAX_SIGMA`]], a in [[`MIN_SIGMA`], 1].
    pub fn check(&self) -> Result<(), String> {
        if self.factor != 2 && self.factor != 4 {
            return Err(format!(
                "an upsampling factor of {} is not one lowres takes: s is 2 or 4 (one pixel of each s×s window per frame)",
                self.factor
            ));
        }
        for (name, value) in [("σn", self.sigma_normal), ("σz", self.sigma_depth)] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(format!(
                    "{name} = {value}: the weights' widths must be positive and finite"
                ));
            }
            if !(MIN_SIGMA..=MAX_SIGMA).contains(&value) {
                return Err(format!(
                    "{name} = {value:e}: the weights' widths lie from {MIN_SIGMA:e} to {MAX_SIGMA:e} (the shader divides by σ², which leaves f32's range outside them)"
                ));
            }
        }
        if !(self.sensitivity >= MIN_SIGMA && self.sensitivity <= 1.0) {
            return Err(format!(
                "a = {}: the sensitivity must lie in [{MIN_SIGMA:e}, 1]",
                self.sensitivity
            ));
        }
        Ok(())
    }
}

/// What a variant assumes of the application's frame. The cache holds
/// one value and one depth per pixel of the whole target, for the one
/// surface the depth test keeps.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameAssumptions {
    /// Samples per pixel of every target.
    pub sample_count: u32,
    /// Whether the colour outputs may blend with what the targets hold.
    pub blending: bool,
    /// Whether the viewport may be smaller than the targets.
    pub partial_viewport: bool,
    /// Whether one draw may render several views (multiview).
    pub multiview: bool,
}

impl Default for FrameAssumptions {
    fn default() -> Self {
        FrameAssumptions {
            sample_count: 1,
            blending: false,
            partial_viewport: false,
            multiview: false,
        }
    }
}

/// What the vertex stage of a host drawing a fragment-only module's
/// passes must output, beside what the fragment entry point already reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HostVertex {
    /// The location of `previous_clip_position: vec4<f32>`: last frame's
    /// clip position of the same vertex (the view-projection and model of
    /// frame t − 1 applied to it), perspective-interpolated.
    pub previous_clip_position_location: u32,
    /// The same, in words, with the position's `@invariant`.
    pub requirement: String,
}

/// The cached node, as `shadecache analyze` reports it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanNode {
    /// Its id (`n12`), stable for one shader text: what `--node` takes.
    pub id: String,
    /// Its source text.
    pub text: String,
    /// Its WGSL type (`vec3<f32>`), serialised as `type`.
    #[serde(rename = "type")]
    pub ty: String,
    /// Its scalar components (1 to 4): how many of the payload texture's
    /// channels hold it.
    pub components: u32,
    /// Absent for a node every pixel computes. `uniform-branch`: under
    /// branches whose conditions depend only on uniforms, overrides and
    /// constants (material flags), so a draw computes it everywhere or
    /// nowhere; `per-pixel-branch`: under a branch some pixels take. Where
    /// the node is not computed, the cache holds NaN ("no value") and the
    /// classify pass marks the pixel absent (docs/rewrite.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<String>,
    /// For a node inside a helper: the helper, and the calls from the
    /// entry point down to it, which the passes inline (docs/rewrite.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub function: Option<String>,
    /// The calls from the entry point down to the helper that holds it,
    /// outermost first; empty for a node of the entry point.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub call_path: Vec<PlanCall>,
}

/// One call on a node's call path.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlanCall {
    /// The helper called.
    pub function: String,
    /// The call's source text.
    pub text: String,
    /// 1-based line and column of the call in the shader.
    pub at: [usize; 2],
}

/// One render pass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pass {
    /// `pass1`, `pass2`...: also the shader file's stem.
    pub name: String,
    /// What the pass does, in words.
    pub role: String,
    /// The shader file (relative to the plan): WGSL unless `rewrite --emit`
    /// chose another language; for GLSL, the vertex stage's file.
    pub shader: String,
    /// For a language with one file per stage (GLSL): every file of the
    /// pass, vertex stage first. Empty otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stage_shaders: Vec<String>,
    /// The vertex entry point in [`Pass::shader`]; for a fragment-only module,
    /// the host's own.
    pub vertex_entry: String,
    /// The fragment entry point in [`Pass::shader`].
    pub fragment_entry: String,
    /// The colour targets the fragment stage writes, by location.
    pub color_targets: Vec<ColorTarget>,
    /// The depth test and write, and whether the depth buffer is cleared.
    pub depth: Depth,
    /// Whether the fragment stage can `discard` (which disables early depth
    /// tests on some GPUs).
    pub discards: bool,
    /// (group, binding) of every resource this pass's shaders use.
    pub bindings: Vec<[u32; 2]>,
    /// What the pass draws: the application's geometry, or one triangle
    /// over the screen per application draw (the deferred variant's
    /// screen-space passes).
    #[serde(default, skip_serializing_if = "DrawKind::is_geometry")]
    pub draw: DrawKind,
    /// The stencil test and write of the pass; absent when it has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stencil: Option<Stencil>,
    /// The pass renders at 1/d × 1/d of the frame's size (rounded up),
    /// into targets and a depth buffer of that size: the lowres variant's
    /// samples. 1 for the frame's own size.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub resolution_divisor: u32,
}

fn one() -> u32 {
    1
}

fn is_one(value: &u32) -> bool {
    *value == 1
}

/// What a pass draws.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DrawKind {
    /// The application's draws, as in its original pass.
    #[default]
    Geometry,
    /// For each of the application's draws, with its bind groups, one
    /// triangle covering the screen (three vertices, no vertex buffer),
    /// with the stencil reference of that draw: the pass reads the
    /// G-buffer and runs only where the draw's surface is visible.
    Fullscreen,
}

impl DrawKind {
    /// Whether the pass draws the application's geometry (serde skips the
    /// default).
    pub fn is_geometry(&self) -> bool {
        *self == DrawKind::Geometry
    }
}

/// A stencil test, the same for front and back faces. The reference is
/// the draw's ordinal in its pass (1 for the first draw) OR-ed with
/// `reference_bits`; ordinals run to [`MAX_STENCIL_DRAWS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stencil {
    /// The test against the reference.
    pub compare: CompareFunction,
    /// The stencil bits the test reads.
    pub read_mask: u32,
    /// The stencil bits a replace writes.
    pub write_mask: u32,
    /// `true`: replace the masked bits with the reference where the test
    /// passes (and the fragment is not discarded); `false`: keep them.
    pub replace: bool,
    /// Bits OR-ed into every draw's reference (the top bit marks reused
    /// pixels).
    pub reference_bits: u32,
}

/// The most draws a pass with a stencil test may have: their ordinals
/// take the stencil's low seven bits, the top bit marks reused pixels.
pub const MAX_STENCIL_DRAWS: u32 = 127;

/// One colour target of a pass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ColorTarget {
    /// The fragment output's `@location`.
    pub location: u32,
    /// What the pass renders into at this location.
    pub target: TargetKind,
    /// The target's texture format.
    pub format: TextureFormat,
    /// `clear` (first pass to write the target this frame) or `load`.
    pub load: LoadOp,
}

/// What a colour target is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TargetKind {
    /// The frame.
    Color,
    /// This frame's payload texture.
    Cache,
    /// This frame's age texture: frames since each cached value was
    /// computed.
    Age,
    /// The classification pass's picture of the cache's decisions.
    Classes,
    /// One of this frame's G-buffer textures (the deferred variant): the
    /// location is its index.
    #[serde(rename = "g-buffer")]
    GBuffer,
    /// The lowres variant's samples: the payload at 1/s × 1/s of the
    /// pixels, in the cache's format.
    Samples,
    /// The samples' geometry (rgba32float): their normal, view depth, draw
    /// id and relative temporal gradient.
    #[serde(rename = "sample-geometry")]
    SampleGeometry,
    /// This frame's upsampling history (rgba32float): the accumulated
    /// weight and the latest temporal gradients.
    History,
}

/// What a pass does with a target's contents when it begins.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LoadOp {
    /// Clear to the plan's clear value: the first pass to write it this
    /// frame.
    Clear,
    /// Keep what earlier passes wrote.
    Load,
}

impl TargetKind {
    /// Its name in `plan.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            TargetKind::Color => "color",
            TargetKind::Cache => "cache",
            TargetKind::Age => "age",
            TargetKind::Classes => "classes",
            TargetKind::GBuffer => "g-buffer",
            TargetKind::Samples => "samples",
            TargetKind::SampleGeometry => "sample-geometry",
            TargetKind::History => "history",
        }
    }
}

impl LoadOp {
    /// Its name in `plan.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            LoadOp::Clear => "clear",
            LoadOp::Load => "load",
        }
    }
}

impl CompareFunction {
    /// Its name as WebGPU spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            CompareFunction::Less => "less",
            CompareFunction::LessEqual => "less-equal",
            CompareFunction::Greater => "greater",
            CompareFunction::GreaterEqual => "greater-equal",
            CompareFunction::Equal => "equal",
            CompareFunction::Always => "always",
        }
    }
}

/// The plan's spelling of each.
macro_rules! display_as_str {
    ($($ty:ty),*) => {$(
        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }
    )*};
}
display_as_str!(
    TargetKind,
    LoadOp,
    CompareFunction,
    CacheFormat,
    Reconstruction,
    CacheRead,
    Upsampler,
    DepthConvention,
    ResourceKind
);

/// A depth test, as WebGPU spells it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CompareFunction {
    /// Passes where the fragment is nearer with standard depth.
    Less,
    /// Passes where the fragment is nearer or at the same depth.
    LessEqual,
    /// Passes where the fragment is nearer with reversed Z.
    Greater,
    /// Passes where the fragment is nearer or at the same depth, with reversed
    /// Z.
    GreaterEqual,
    /// Passes where the fragment is at the depth already written (a pass after
    /// a depth pre-pass).
    Equal,
    /// Always passes.
    Always,
}

/// A pass's depth test and write.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Depth {
    /// The depth buffer's format ([`DEPTH_FORMAT`]).
    pub format: TextureFormat,
    /// `less` (`greater` with reversed Z) or `equal`; a host's plan may
    /// also say `less-equal`, `greater-equal` or `always`.
    pub compare: CompareFunction,
    /// Whether the pass writes the depth of the fragments that pass.
    pub write: bool,
    /// `clear` (the first pass to test against it this frame) or `load`.
    pub load: LoadOp,
}

/// One vertex attribute of the layout.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VertexAttribute {
    /// The vertex stage's `@location`.
    pub location: u32,
    /// The input's name in the vertex stage (or its struct member's).
    pub name: String,
    /// A WebGPU vertex format, e.g. `float32x3`.
    pub format: VertexFormat,
    /// Which buffer steps it: the per-vertex one (buffer slot 0) or the
    /// per-instance one (slot 1). Each is packed in the layout's order.
    #[serde(default, skip_serializing_if = "StepMode::is_vertex")]
    pub step: StepMode,
    /// For the previous-frame twin of a per-instance input: the location
    /// of the input whose last-frame value the host puts here (this
    /// frame's on the first frame), as it does for a buffer's twin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub previous_of: Option<u32>,
}

/// How a vertex input advances: once per vertex or once per instance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StepMode {
    /// Once per vertex: buffer slot 0.
    #[default]
    Vertex,
    /// Once per instance: buffer slot 1.
    Instance,
}

impl StepMode {
    /// Whether it steps per vertex (serde skips the default).
    pub fn is_vertex(&self) -> bool {
        *self == StepMode::Vertex
    }
}

/// Every resource the passes bind, by who supplies it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bindings {
    /// The user's resources, as in the original shader.
    pub original: Vec<Resource>,
    /// Previous-frame twins: same type as the binding they shadow, filled
    /// with last frame's contents (this frame's on the first frame).
    pub previous: Vec<Twin>,
    /// Resources that keep last frame's values themselves, in `previous_`
    /// members beside the members the position reads (Bevy's mesh
    /// `previous_world_from_local`): the previous position reads those,
    /// the resource has no twin, and the host keeps the `previous_`
    /// members up to date as it writes the rest (this frame's values on
    /// the first frame).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub previous_members: Vec<PreviousMembers>,
    /// The cache's own resources.
    pub cache: Vec<Resource>,
}

/// A resource the previous position reads through its own `previous_`
/// members.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PreviousMembers {
    /// The resource, as in [`Bindings::original`].
    pub resource: Resource,
    /// Each member the position reads, and the member that holds its
    /// value last frame (`["world_from_local",
    /// "previous_world_from_local"]`).
    pub members: Vec<[String; 2]>,
}

/// One bound resource.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resource {
    /// Its `@group`.
    pub group: u32,
    /// Its `@binding`.
    pub binding: u32,
    /// Its name in the shader.
    pub name: String,
    /// What it holds: what the host must create and bind.
    pub kind: ResourceKind,
    /// For the cache's resources, what to bind, e.g. `previous payload`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// What a binding holds, as WGSL declares it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ResourceKind {
    /// A uniform buffer (`var<uniform>`).
    Uniform,
    /// Read-only storage (`var<storage, read>`).
    Storage,
    /// Read-write storage (`var<storage, read_write>`).
    StorageReadWrite,
    /// A storage texture (`texture_storage_2d<…>`).
    StorageTexture,
    /// A sampled 2D texture (`texture_2d<f32>`).
    Texture,
    /// `texture_2d<u32>`, read with `textureLoad` (a G-buffer).
    UintTexture,
    /// A sampled 2D texture array (`texture_2d_array<f32>`).
    TextureArray,
    /// A sampled cube texture (`texture_cube<f32>`).
    CubeTexture,
    /// A sampled cube texture array (`texture_cube_array<f32>`).
    CubeTextureArray,
    /// A depth texture (`texture_depth_2d`: a shadow map).
    DepthTexture,
    /// A depth texture array (`texture_depth_2d_array`).
    DepthTextureArray,
    /// A depth cube texture (`texture_depth_cube`).
    DepthCubeTexture,
    /// A depth cube texture array (`texture_depth_cube_array`).
    DepthCubeTextureArray,
    /// A sampled 1D texture (`texture_1d<f32>`).
    #[serde(rename = "texture-1d")]
    Texture1d,
    /// A sampled 3D texture (`texture_3d<f32>`).
    #[serde(rename = "texture-3d")]
    Texture3d,
    /// A filtering sampler (`sampler`).
    Sampler,
    /// A comparison sampler (`sampler_comparison`).
    ComparisonSampler,
    /// Anything else a module may bind.
    Other,
}

/// The shape of a sampled 2D or cube texture: what a host must create.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampledTexture {
    /// A depth texture (a shadow map).
    pub depth: bool,
    /// A cube texture (six faces).
    pub cube: bool,
    /// An array of layers (of 2D textures or of cubes).
    pub arrayed: bool,
}

impl ResourceKind {
    /// The shape of a sampled 2D or cube texture, plain or depth, single
    /// or arrayed; `None` for everything else (buffers, samplers, 1D and
    /// 3D and storage textures).
    pub fn sampled(self) -> Option<SampledTexture> {
        use ResourceKind as K;
        let (depth, cube, arrayed) = match self {
            K::Texture => (false, false, false),
            K::TextureArray => (false, false, true),
            K::CubeTexture => (false, true, false),
            K::CubeTextureArray => (false, true, true),
            K::DepthTexture => (true, false, false),
            K::DepthTextureArray => (true, false, true),
            K::DepthCubeTexture => (true, true, false),
            K::DepthCubeTextureArray => (true, true, true),
            _ => return None,
        };
        Some(SampledTexture {
            depth,
            cube,
            arrayed,
        })
    }

    /// Its name in `plan.json`.
    pub fn as_str(self) -> &'static str {
        use ResourceKind as K;
        match self {
            K::Uniform => "uniform",
            K::Storage => "storage",
            K::StorageReadWrite => "storage-read-write",
            K::StorageTexture => "storage-texture",
            K::Texture => "texture",
            K::UintTexture => "uint-texture",
            K::TextureArray => "texture-array",
            K::CubeTexture => "cube-texture",
            K::CubeTextureArray => "cube-texture-array",
            K::DepthTexture => "depth-texture",
            K::DepthTextureArray => "depth-texture-array",
            K::DepthCubeTexture => "depth-cube-texture",
            K::DepthCubeTextureArray => "depth-cube-texture-array",
            K::Texture1d => "texture-1d",
            K::Texture3d => "texture-3d",
            K::Sampler => "sampler",
            K::ComparisonSampler => "comparison-sampler",
            K::Other => "other",
        }
    }
}

/// A previous-frame twin: a resource the rewritten passes read last frame's
/// values from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Twin {
    /// Its `@group`.
    pub group: u32,
    /// Its `@binding`.
    pub binding: u32,
    /// Its name in the rewritten passes (`previous_` and the original's).
    pub name: String,
    /// The original resource it holds last frame's contents of.
    pub shadows: Resource,
}

/// The cache's textures and how the passes read them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cache {
    /// The payload texture's format.
    pub format: CacheFormat,
    /// Why the format is not the one asked for, when it is not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format_note: Option<String>,
    /// How a cache variant reads the payload back where a point was last frame;
    /// for lowres, the upsampling filter.
    #[serde(default = "bilinear")]
    pub reconstruction: Reconstruction,
    /// How many components of the payload texture hold the payload.
    pub components: u32,
    /// The double-buffering rule.
    pub swap: String,
    /// Byte layout of the refresh uniform (`CacheParams`), in order.
    pub params: Vec<Field>,
}

/// One field of the refresh uniform (`CacheParams`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Field {
    /// Its name in `CacheParams`.
    pub name: String,
    /// Its WGSL type, serialised as `type`.
    #[serde(rename = "type")]
    pub ty: String,
    /// Its byte offset in the uniform.
    pub offset: u32,
}

/// The refresh pattern: which pixels recompute the payload each frame (seed 002
/// §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Refresh {
    /// Δn: the frames between two refreshes of a pixel (1 refreshes every
    /// frame, 0 turns refresh off); `CacheParams.refresh_period`.
    pub period: u32,
    /// k: the side, in pixels, of the square blocks that share one refresh
    /// offset; for lowres, its factor s. `CacheParams.refresh_quad`.
    pub quad: u32,
    /// ε, relative: a cached depth d agrees with the expected e when
    /// |d − e| < ε·|e − far depth|. `CacheParams.depth_epsilon`.
    pub depth_epsilon: f32,
    /// Where the per-block offsets come from.
    pub offsets: String,
}

/// Clear values of the frame's targets, as WebGPU's `Color` and depth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Clear {
    /// The colour targets' clear value, RGBA.
    pub color: [f64; 4],
    /// The payload texture's clear value, RGBA (zeros: with the previous
    /// depth cleared to the far plane, a first frame misses everywhere).
    pub cache: [f64; 4],
    /// The far plane's depth: 1.0, or 0.0 with reversed Z. Also the
    /// `far_depth` of `CacheParams`.
    pub depth: f64,
}

fn bilinear() -> Reconstruction {
    Reconstruction::Bilinear
}

/// The three ways of running a cache (seed 002, §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Variant {
    /// One pass: the lookup, the payload on a miss or a refresh, and the
    /// shading in one fragment stage (seed 002 §3.1).
    OnePass,
    /// Two passes: reuse where the lookup hits, else discard; then the original
    /// computation at the pixels left (seed 002 §3.2).
    TwoPass,
    /// Three passes: the lookup into the cache, the payload where it missed,
    /// then the shading from the cache (seed 002 §3.3).
    ThreePass,
    /// One geometry pass writes depth and the fragment inputs into a
    /// G-buffer; the lookup, the misses and the shading run in screen
    /// space.
    Deferred,
    /// The payload shaded at 1/s × 1/s of the pixels on a jittered
    /// lattice and rebuilt at full resolution from the samples and the
    /// reprojected history (seed 001).
    Lowres,
    /// Lowres in screen space, as seed 001 ran it: one geometry pass into
    /// the deferred variant's G-buffer, the payload shaded from it at
    /// 1/s × 1/s of the pixels on the jittered lattice, and the
    /// upsampling and shading in screen space.
    DeferredLowres,
    /// The unmodified shader, run by the profiler as the reference; never
    /// a rewrite.
    Reference,
}

impl Variant {
    /// The reprojection-cache variants (seed 002), lowres aside.
    pub const CACHE: [Variant; 4] = [
        Variant::OnePass,
        Variant::TwoPass,
        Variant::ThreePass,
        Variant::Deferred,
    ];

    /// Every variant the toolchain writes, in the profiler's order
    /// ([`Variant::Reference`] is not one).
    pub const ALL: [Variant; 6] = [
        Variant::OnePass,
        Variant::TwoPass,
        Variant::ThreePass,
        Variant::Deferred,
        Variant::Lowres,
        Variant::DeferredLowres,
    ];

    /// Whether it reuses work by shading a share of the pixels each frame
    /// and upsampling them (lowres), rather than by reprojecting a cached
    /// payload: what its classes and its refresh knobs mean.
    pub fn upsamples(self) -> bool {
        matches!(self, Variant::Lowres | Variant::DeferredLowres)
    }

    /// Its name on the command line and in `plan.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            Variant::OnePass => "one-pass",
            Variant::TwoPass => "two-pass",
            Variant::ThreePass => "three-pass",
            Variant::Deferred => "deferred",
            Variant::Lowres => "lowres",
            Variant::DeferredLowres => "deferred-lowres",
            Variant::Reference => "reference",
        }
    }
}

impl fmt::Display for Variant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The texture format of the payload cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CacheFormat {
    /// Half floats: the default, and enough for colours and normals.
    Rgba16float,
    /// Full floats: for payloads that half floats round too far (positions,
    /// large values).
    Rgba32float,
}

impl CacheFormat {
    /// The payload texture's format.
    pub fn texture_format(self) -> TextureFormat {
        match self {
            CacheFormat::Rgba16float => TextureFormat::Rgba16Float,
            CacheFormat::Rgba32float => TextureFormat::Rgba32Float,
        }
    }
    /// Its name in `plan.json` and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            CacheFormat::Rgba16float => "rgba16float",
            CacheFormat::Rgba32float => "rgba32float",
        }
    }
}

/// How a cache variant reads its cache back where a point was last frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CacheRead {
    /// Bilinear over the 2×2 texels around the point; all four (those with
    /// weight) must pass the depth test against last frame's depth buffer.
    Bilinear,
    /// The texel the point falls in, tested on its own depth.
    Nearest,
    /// Payload and depth filtered together from one texture, the depth in
    /// its fourth channel (seed 002 §3: "a single four-channel buffer"):
    /// one read instead of a sample and a gather. For payloads of up to
    /// three components.
    BilinearPacked,
    /// The texel the point falls in, its depth in its fourth channel: one
    /// load instead of two. For payloads of up to three components.
    NearestPacked,
}

impl CacheRead {
    /// Every read, the default first.
    pub const ALL: [CacheRead; 4] = [
        CacheRead::Bilinear,
        CacheRead::Nearest,
        CacheRead::BilinearPacked,
        CacheRead::NearestPacked,
    ];

    /// Its name in `plan.json` and on the command line.
    pub fn as_str(self) -> &'static str {
        Reconstruction::from(self).as_str()
    }

    /// Whether the cache keeps the depth in the payload texture's fourth
    /// channel rather than reading last frame's depth buffer.
    pub fn packs_depth(self) -> bool {
        matches!(self, CacheRead::BilinearPacked | CacheRead::NearestPacked)
    }
}

/// How the lowres variant rebuilds the payload at every pixel from the
/// samples it shaded (seed 001).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Upsampler {
    /// The nearest sample.
    Nearest,
    /// The four nearest samples, bilinearly.
    Bilinear,
    /// The joint-bilateral upsampling of this frame's samples, with
    /// normal, depth and draw weights and a linear hat in image space
    /// (seed 001, eqs. 1–3); no history.
    Spatial,
    /// Each pixel shaded this frame takes its sample, the others the
    /// reprojected history (eq. 4); where the history misses, the spatial
    /// upsampling.
    Temporal,
    /// The spatial upsampling blended with the exponential history,
    /// weighted by the temporal gradient's confidence (eqs. 6–8): the
    /// paper's method.
    SpatioTemporal,
}

impl Upsampler {
    /// Every upsampler, the simplest first.
    pub const ALL: [Upsampler; 5] = [
        Upsampler::Nearest,
        Upsampler::Bilinear,
        Upsampler::Spatial,
        Upsampler::Temporal,
        Upsampler::SpatioTemporal,
    ];

    /// Its name in `plan.json` and on the command line.
    pub fn as_str(self) -> &'static str {
        Reconstruction::from(self).as_str()
    }

    /// Whether it reads the history (and so the samples pass takes their
    /// temporal gradient): temporal and spatio-temporal.
    pub fn reads_history(self) -> bool {
        matches!(self, Upsampler::Temporal | Upsampler::SpatioTemporal)
    }
}

impl From<CacheRead> for Reconstruction {
    fn from(read: CacheRead) -> Reconstruction {
        match read {
            CacheRead::Bilinear => Reconstruction::Bilinear,
            CacheRead::Nearest => Reconstruction::Nearest,
            CacheRead::BilinearPacked => Reconstruction::BilinearPacked,
            CacheRead::NearestPacked => Reconstruction::NearestPacked,
        }
    }
}

impl From<Upsampler> for Reconstruction {
    fn from(upsampler: Upsampler) -> Reconstruction {
        match upsampler {
            Upsampler::Nearest => Reconstruction::Nearest,
            Upsampler::Bilinear => Reconstruction::Bilinear,
            Upsampler::Spatial => Reconstruction::Spatial,
            Upsampler::Temporal => Reconstruction::Temporal,
            Upsampler::SpatioTemporal => Reconstruction::SpatioTemporal,
        }
    }
}

/// How a plan's cache is read back, as `plan.json` and reports name it:
/// a cache variant's [`CacheRead`], or lowres's [`Upsampler`]. The
/// toolchain's options take the two types apart, so a mix cannot be
/// asked for; this is their one name in files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reconstruction {
    /// Bilinear over the 2×2 texels around the point; all four (those with
    /// weight) must pass the depth test against last frame's depth buffer.
    Bilinear,
    /// The texel the point falls in, tested on its own depth.
    Nearest,
    /// Payload and depth filtered together from one texture, the depth in
    /// its fourth channel (seed 002 §3): one read instead of a sample and
    /// a gather. For payloads of up to three components.
    BilinearPacked,
    /// The texel the point falls in, its depth in its fourth channel: one
    /// load instead of two. For payloads of up to three components.
    NearestPacked,
    /// Lowres only: the joint-bilateral upsampling of this frame's
    /// samples, with normal, depth and draw weights and a linear hat in
    /// image space (seed 001, eqs. 1–3); no history.
    Spatial,
    /// Lowres only: each pixel shaded this frame takes its sample, the
    /// others the reprojected history (eq. 4); where the history misses,
    /// the spatial upsampling.
    Temporal,
    /// Lowres only: the spatial upsampling blended with the exponential
    /// history, weighted by the temporal gradient's confidence (eqs. 6–8).
    SpatioTemporal,
}

impl Reconstruction {
    /// As a cache variant's read; `None` for an upsampler of lowres's
    /// alone.
    pub fn cache_read(self) -> Option<CacheRead> {
        CacheRead::ALL
            .into_iter()
            .find(|read| Reconstruction::from(*read) == self)
    }

    /// As lowres's upsampler; `None` for a packed cache read.
    pub fn upsampler(self) -> Option<Upsampler> {
        Upsampler::ALL
            .into_iter()
            .find(|upsampler| Reconstruction::from(*upsampler) == self)
    }

    /// The cache variants' reconstructions (reads of the cache).
    pub const CACHE: [Reconstruction; 4] = [
        Reconstruction::Bilinear,
        Reconstruction::Nearest,
        Reconstruction::BilinearPacked,
        Reconstruction::NearestPacked,
    ];

    /// Every reconstruction, the cache reads first, then lowres's upsamplers.
    pub const ALL: [Reconstruction; 7] = [
        Reconstruction::Bilinear,
        Reconstruction::Nearest,
        Reconstruction::BilinearPacked,
        Reconstruction::NearestPacked,
        Reconstruction::Spatial,
        Reconstruction::Temporal,
        Reconstruction::SpatioTemporal,
    ];

    /// Its name in `plan.json` and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Reconstruction::Bilinear => "bilinear",
            Reconstruction::Nearest => "nearest",
            Reconstruction::BilinearPacked => "bilinear-packed",
            Reconstruction::NearestPacked => "nearest-packed",
            Reconstruction::Spatial => "spatial",
            Reconstruction::Temporal => "temporal",
            Reconstruction::SpatioTemporal => "spatio-temporal",
        }
    }

    /// Whether the reconstruction upsamples lowres's samples (the others
    /// read the reprojection cache; lowres takes `nearest` and `bilinear`
    /// too, as upsampling filters).
    pub fn upsamples(self) -> bool {
        matches!(
            self,
            Reconstruction::Spatial | Reconstruction::Temporal | Reconstruction::SpatioTemporal
        )
    }

    /// Whether the cache keeps the depth in the payload texture's fourth
    /// channel rather than reading last frame's depth buffer.
    pub fn packs_depth(self) -> bool {
        matches!(
            self,
            Reconstruction::BilinearPacked | Reconstruction::NearestPacked
        )
    }
}

/// Which way the depth buffer runs: the host's projection decides, and the
/// plan follows it (depth compares, the clear value, and the far-plane
/// depth the cache's depth test measures from).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DepthConvention {
    /// Near plane at depth 0, far plane (or infinity) at 1; nearer is
    /// `less`.
    #[default]
    Standard,
    /// Reversed Z: near plane at 1, far plane (or infinity) at 0; nearer
    /// is `greater`.
    Reversed,
}

impl DepthConvention {
    /// Its name in `plan.json` and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            DepthConvention::Standard => "standard",
            DepthConvention::Reversed => "reversed",
        }
    }

    /// The depth-buffer value of the far plane, or of infinity with an
    /// infinite far plane: the depth buffer's clear value.
    pub fn far_depth(self) -> f32 {
        match self {
            DepthConvention::Standard => 1.0,
            DepthConvention::Reversed => 0.0,
        }
    }

    /// The depth compare that keeps the nearer fragment.
    pub fn nearer(self) -> CompareFunction {
        match self {
            DepthConvention::Standard => CompareFunction::Less,
            DepthConvention::Reversed => CompareFunction::Greater,
        }
    }
}

/// The largest refresh period Δn: the refresh indicator maps 16 hash bits
/// onto [0, Δn) with a product that must fit a u32 (shaders/cache.wgsl,
/// `cache_refresh`). 65535 frames is 18 minutes at 60 Hz.
pub const MAX_REFRESH_PERIOD: u32 = 65535;

/// The most colour targets a pass writes: WebGPU's limit on colour
/// attachments (`maxColorAttachments`, 8).
pub const MAX_COLOR_TARGETS: u32 = 8;

/// The largest the refresh uniform (`CacheParams`) may be, in bytes: its
/// fields lie below it.
pub const MAX_PARAMS_BYTES: u32 = 256;

/// The default ε of the cache's depth test, relative: a cached depth d
/// agrees with the expected depth e when |d − e| < ε·|e − far depth|.
pub const DEFAULT_DEPTH_EPSILON: f32 = 0.02;

impl Plan {
    /// Checks what deserializing cannot, everything a host trusts: the
    /// format version; that every pass's bindings are among the plan's
    /// resources; at least one pass; colour targets at locations below
    /// [`MAX_COLOR_TARGETS`]; a resolution divisor of 1, or lowres's s
    /// for its samples; the refresh pattern's and the depth test's knobs
    /// within their ranges; lowres's upsampling knobs
    /// ([`Upsampling::check`]); the far plane's depth 0 or 1; the refresh
    /// uniform's fields 4-aligned within [`MAX_PARAMS_BYTES`]. Read a plan
    /// with any serde format (`plan.json` is JSON), then check it once: a
    /// hand-edited plan is an error here, never a gigabyte's allocation in
    /// a host.
    pub fn check(&self) -> Result<(), String> {
        if self.format != FORMAT_VERSION {
            return Err(format!(
                "plan format {} is not the {FORMAT_VERSION} this reader knows",
                self.format
            ));
        }
        self.check_passes()?;
        self.check_knobs()?;
        let declared = |[group, binding]: [u32; 2]| {
            let at = |g: u32, b: u32| g == group && b == binding;
            self.bindings
                .original
                .iter()
                .any(|r| at(r.group, r.binding))
                || self
                    .bindings
                    .previous
                    .iter()
                    .any(|t| at(t.group, t.binding))
                || self.bindings.cache.iter().any(|r| at(r.group, r.binding))
        };
        for pass in self.passes.iter().chain(&self.classify) {
            if let Some(&[group, binding]) = pass.bindings.iter().find(|&&b| !declared(b)) {
                return Err(format!(
                    "pass `{}` binds group {group}, binding {binding}, which the plan does not declare",
                    pass.name
                ));
            }
        }
        Ok(())
    }

    /// The passes: at least one, their colour targets at locations a
    /// device has, their resolution 1, or for lowres's samples its s.
    fn check_passes(&self) -> Result<(), String> {
        if self.passes.is_empty() {
            return Err("the plan has no pass".into());
        }
        let factor = self.upsampling.as_ref().map(|u| u.factor);
        for pass in self.passes.iter().chain(&self.classify) {
            if let Some(target) = pass
                .color_targets
                .iter()
                .find(|t| t.location >= MAX_COLOR_TARGETS)
            {
                return Err(format!(
                    "pass `{}` writes a colour target at location {}, beyond the {MAX_COLOR_TARGETS} a device has",
                    pass.name, target.location
                ));
            }
            let divisor = pass.resolution_divisor;
            if divisor != 1 && Some(divisor) != factor {
                return Err(format!(
                    "pass `{}` renders at 1/{divisor} of the frame: a pass renders at the frame's size, or lowres's samples at 1/s with s its upsampling factor ({})",
                    pass.name,
                    factor.map_or("none".to_string(), |s| s.to_string())
                ));
            }
        }
        Ok(())
    }

    /// The knobs the passes' uniform carries: the refresh pattern's, the
    /// depth test's, lowres's, the far plane's depth and the uniform's
    /// layout.
    fn check_knobs(&self) -> Result<(), String> {
        let refresh = &self.refresh;
        if refresh.period > MAX_REFRESH_PERIOD {
            return Err(format!(
                "a refresh period of {} frames is beyond the largest the refresh indicator takes, {MAX_REFRESH_PERIOD}",
                refresh.period
            ));
        }
        if refresh.quad == 0 {
            return Err("refresh.quad is 0: refresh blocks are at least 1 pixel".into());
        }
        if !(0.0..1.0).contains(&refresh.depth_epsilon) {
            return Err(format!(
                "refresh.depth_epsilon = {}: the depth test's tolerance lies in [0, 1)",
                refresh.depth_epsilon
            ));
        }
        if self.clear.depth != 0.0 && self.clear.depth != 1.0 {
            return Err(format!(
                "clear.depth = {}: the far plane's depth is 1, or 0 with reversed Z",
                self.clear.depth
            ));
        }
        match (&self.upsampling, self.variant.upsamples()) {
            (Some(upsampling), _) => upsampling.check()?,
            (None, true) => {
                return Err(format!(
                    "a {} plan without its upsampling knobs (`upsampling`)",
                    self.variant
                ))
            }
            (None, false) => {}
        }
        if let Some(field) = self
            .cache
            .params
            .iter()
            .find(|f| f.offset % 4 != 0 || f.offset >= MAX_PARAMS_BYTES)
        {
            return Err(format!(
                "cache.params: `{}` at byte {} is not 4-aligned within the uniform's {MAX_PARAMS_BYTES} bytes",
                field.name, field.offset
            ));
        }
        Ok(())
    }
}

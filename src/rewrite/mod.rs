//! candidates → variants: rewriting a shader into reprojection-cache
//! variants at the level of naga's IR (seed 002, §3).
//!
//! For one candidate node and one [`Variant`], [`rewrite`] clones the
//! module and builds every pass as its own module:
//!
//! 1. the toolchain's cache helpers (`shaders/cache.wgsl`: reprojection,
//!    bilinear lookup with depth test, refresh indicator) are
//!    imported (`proc::import`) into the first free bind group;
//! 2. the [vertex stage](vertex) gains the previous clip position, computed
//!    by the same code as the position but with previous-frame twins of the
//!    uniforms and read-only storage it reads; the position is `@invariant`;
//! 3. the fragment entry point is split at the node into a payload function
//!    and a shade function (`copy`: handle-mapped, dead code dropped), and
//!    each pass's fragment entry point (`fragment`) is built from calls to them;
//! 4. each pass module is compacted, checked for derivatives in non-uniform
//!    control flow ([uniformity]) and validated by naga with every flag.
//!
//! A variant that cannot be built is a [`Refusal`] with the reason; nothing
//! broken is ever returned.

#![warn(missing_docs)]

pub(crate) mod builder;
pub(crate) mod copy;
pub(crate) mod fragment;
pub(crate) mod gbuffer;
pub(crate) mod gradients;
mod helpers;
pub mod lowres;
pub(crate) mod member_twins;
pub(crate) mod path;
pub mod plan;
pub mod reprojection;
mod split;
pub(crate) mod stage;
pub mod uniformity;
mod variants;
pub mod vertex;

use std::fmt;

use naga::valid::ModuleInfo;

use crate::analysis::graph::ExprGraph;
use crate::analysis::{Analysis, Candidate};
use crate::front::Shader;
use crate::plan::Plan;
use helpers::Pieces;
use stage::{CacheStage, Stage};
use variants::Recipe;

/// The toolchain's cache helpers, imported into every rewritten module.
pub const CACHE_WGSL: &str = include_str!("../../shaders/cache.wgsl");

pub use crate::plan::{
    CacheFormat, CacheRead, DepthConvention, DepthTolerance, GradientFilter, Reconstruction,
    Upsampler, Upsampling, Variant, DEFAULT_DEPTH_EPSILON, DEFAULT_UPSAMPLING, MAX_REFRESH_PERIOD,
};

/// The index of the pass of `variant` that computes the payload alone
/// (three-pass's pass 2), which the profiler draws over every pixel for
/// P/T; `None` for a variant without one.
pub fn payload_pass(variant: Variant) -> Option<usize> {
    let recipe = Recipe::of(variant, &Options::default()).ok()?;
    recipe
        .stages()
        .iter()
        .position(|&s| s == Stage::Cache(CacheStage::Payload))
}

/// How to build the variants.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Δn: every pixel is recomputed once every Δn frames; 0 never, at
    /// most [`MAX_REFRESH_PERIOD`].
    pub refresh_period: u32,
    /// k: refresh decisions are made per k×k block.
    pub refresh_quad: u32,
    /// The payload cache's texture format.
    pub cache_format: CacheFormat,
    /// ε of the depth test, relative: a cached depth d agrees with the
    /// expected depth e when |d − e| < ε·|e − far depth|. In a perspective
    /// projection |e − far depth| is proportional to 1/distance, so ε bounds
    /// the relative difference in distance, |Δz|/z, the same near and far
    /// and for either [`DepthConvention`]. Must be below 1.
    pub depth_epsilon: f32,
    /// Which way the host's depth buffer runs.
    pub depth: DepthConvention,
    /// How a cache variant reads the payload and depth back where a
    /// point was; lowres's is its [`Options::upsampling`]'s.
    pub reconstruction: CacheRead,
    /// Format of the colour targets, written into the plan.
    pub color_format: crate::plan::TextureFormat,
    /// The vertex entry point that draws with the fragment one; `None`
    /// infers it (`vertex::vertex_entry`).
    pub vertex_entry: Option<String>,
    /// Make the payload and the shade free (each returns zero at once):
    /// the passes then cost what the variant costs with nothing to
    /// compute — rasterisation, the twin vertex stage, the lookup, the
    /// cache writes — which the profiler measures as its fixed cost. Not a
    /// shader to use.
    pub free_payload: bool,
    /// The per-vertex inputs (by name) that the application changes from
    /// frame to frame: vertices it deforms itself (a cloth, a morph target
    /// blended on the CPU). Those the position reads get a previous-frame
    /// twin input, which the host fills from last frame's copy of their
    /// vertex buffer, as per-instance inputs' twins are filled. Inputs
    /// skinned on the GPU need none: their joint matrices are a buffer,
    /// which has its twin.
    pub deforming_inputs: Vec<String>,
    /// The lowres variant's reconstruction, factor and knobs (seed 001);
    /// [`Options::reconstruction`] is the cache variants'.
    pub upsampling: Upsampling,
    /// Adaptive refresh for the cache variants: a value that changed by
    /// 10% or more since it was cached is refreshed again after Δn/4
    /// frames instead of Δn (`cache_adaptive_age`); the passes that
    /// compute the payload then reproject, to compare. Lowres's own is
    /// [`Upsampling::reshade`].
    pub adaptive_refresh: bool,
    /// The bind groups the host's device has ([`DEFAULT_MAX_BIND_GROUPS`]
    /// is WebGPU's default). The cache takes the first group the shader
    /// leaves free; a shader that uses all of them shares its last with
    /// the cache, and the host then binds that group itself. An engine
    /// that binds every group of its own (Bevy: view, binding arrays,
    /// mesh, material) on a device with more gives the device's count, so
    /// the cache gets a group of its own.
    pub max_bind_groups: u32,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            refresh_period: 32,
            refresh_quad: 4,
            cache_format: CacheFormat::Rgba16float,
            depth_epsilon: DEFAULT_DEPTH_EPSILON,
            depth: DepthConvention::Standard,
            reconstruction: CacheRead::Bilinear,
            color_format: crate::plan::TextureFormat::Rgba8Unorm,
            vertex_entry: None,
            free_payload: false,
            deforming_inputs: Vec::new(),
            upsampling: DEFAULT_UPSAMPLING,
            adaptive_refresh: false,
            max_bind_groups: DEFAULT_MAX_BIND_GROUPS,
        }
    }
}

/// Why a variant was not produced.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refusal {
    /// Whether the shader or the toolchain is why.
    pub kind: RefusalKind,
    /// The reason, in words; an internal one starts "internal error:".
    pub reason: String,
}

/// What kind of refusal: a limit of what the rewrite supports, or a bug.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum RefusalKind {
    /// The shader asks for what a variant cannot do (the reason says what).
    Unsupported,
    /// The rewrite failed itself: what it built did not validate, or broke
    /// a rule it checks. A bug in shadecache.
    Internal,
}

impl Refusal {
    /// A variant the shader cannot have, for `reason`.
    pub fn new(reason: impl Into<String>) -> Self {
        Refusal {
            kind: RefusalKind::Unsupported,
            reason: reason.into(),
        }
    }

    /// A failure of the rewrite itself: `what` went wrong.
    pub fn internal(what: impl fmt::Display) -> Self {
        Refusal {
            kind: RefusalKind::Internal,
            reason: format!("internal error: {what}"),
        }
    }

    /// Whether the refusal is a bug of the rewrite rather than a limit of
    /// what it supports.
    pub fn is_internal(&self) -> bool {
        self.kind == RefusalKind::Internal
    }
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.reason)
    }
}

/// One pass's module, validated.
#[derive(Debug)]
pub struct PassModule {
    /// File stem, e.g. `pass1`.
    pub name: String,
    /// The pass's module.
    pub module: naga::Module,
    /// Its validation (all checks on).
    pub info: ModuleInfo,
}

/// A variant ready to write: its pass modules and its plan.
#[derive(Debug)]
#[non_exhaustive]
pub struct Rewritten {
    /// The variant.
    pub variant: Variant,
    /// The id of the node it caches.
    pub node: String,
    /// Its passes, in the order they run.
    pub passes: Vec<PassModule>,
    /// The diagnostic pass that colours the cache's decisions (plan's
    /// `classify`).
    pub classify: PassModule,
    /// How to run them (`plan.json`).
    pub plan: Plan,
}

/// WebGPU's default limit on bind groups.
pub const DEFAULT_MAX_BIND_GROUPS: u32 = 4;

/// Where the cache's own resources and the previous-frame twins are bound:
/// the cache's at `first_binding +` their bindings in `shaders/cache.wgsl`,
/// the twins after them (`first_twin_binding`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CacheSlot {
    /// The bind group.
    pub group: u32,
    /// The first binding in it.
    pub first_binding: u32,
}

impl CacheSlot {
    /// The first bind group `module` leaves free, from binding 0; when it
    /// uses all `max_bind_groups` (WebGPU's default is four; engines bind
    /// view, material, mesh and more), its last group after the last
    /// binding there.
    pub fn for_module(module: &naga::Module, max_bind_groups: u32) -> CacheSlot {
        let bindings: Vec<naga::ResourceBinding> = module
            .global_variables
            .iter()
            .filter_map(|(_, g)| g.binding)
            .collect();
        let free = bindings.iter().map(|b| b.group + 1).max().unwrap_or(0);
        if free < max_bind_groups {
            return CacheSlot {
                group: free,
                first_binding: 0,
            };
        }
        let group = max_bind_groups.max(1) - 1;
        let last = bindings
            .iter()
            .filter(|b| b.group == group)
            .map(|b| b.binding + 1)
            .max()
            .unwrap_or(0);
        CacheSlot {
            group,
            first_binding: last,
        }
    }
}

/// One of the toolchain's own modules (`shaders/NAME`, its `text`)
/// parsed and validated, once per process (`cell` keeps it).
pub(crate) fn toolchain_module(
    cell: &'static std::sync::OnceLock<Result<naga::Module, String>>,
    name: &str,
    text: &str,
) -> Result<&'static naga::Module, Refusal> {
    cell.get_or_init(|| {
        crate::front::parse(crate::diagnostic::SourceFile::new(name, text))
            .map(|shader| shader.module)
            .map_err(|err| err.render())
    })
    .as_ref()
    .map_err(|err| Refusal::internal(format!("`{name}` does not parse: {err}")))
}

/// `shaders/cache.wgsl` parsed and validated, once per process.
pub(crate) fn cache_helpers() -> Result<&'static naga::Module, Refusal> {
    static HELPERS: std::sync::OnceLock<Result<naga::Module, String>> = std::sync::OnceLock::new();
    toolchain_module(&HELPERS, "shaders/cache.wgsl", CACHE_WGSL)
}

/// The first binding after the cache's own (`shaders/cache.wgsl`'s, from
/// 0 in their group): where the previous-frame twins start.
pub(crate) fn first_twin_binding() -> Result<u32, String> {
    let helpers = cache_helpers().map_err(|r| r.reason)?;
    Ok(helpers
        .global_variables
        .iter()
        .filter_map(|(_, g)| g.binding.as_ref().map(|b| b.binding + 1))
        .max()
        .unwrap_or(0))
}

/// The byte layout of the refresh uniform, `CacheParams`, as
/// `shaders/cache.wgsl` declares it (naga lays the struct out): what the
/// plan's `cache.params` says and the host writes, stated once.
pub fn cache_params_layout() -> Result<Vec<crate::plan::Field>, Refusal> {
    let helpers = cache_helpers()?;
    let params = helpers
        .types
        .iter()
        .find(|(_, ty)| ty.name.as_deref() == Some("CacheParams"))
        .ok_or_else(|| Refusal::internal("the cache helpers declare no `CacheParams`"))?
        .1;
    let naga::TypeInner::Struct { ref members, .. } = params.inner else {
        return Err(Refusal::internal("`CacheParams` is not a struct"));
    };
    Ok(members
        .iter()
        .map(|member| crate::plan::Field {
            name: member.name.clone().unwrap_or_default(),
            ty: crate::analysis::type_name(&helpers.types, &helpers.types[member.ty].inner),
            offset: member.offset,
        })
        .collect())
}

/// Rewrites `shader` to cache `candidate` with `variant`.
///
/// A node inside a helper is cached where its call path puts it: the calls
/// on that path are inlined into the entry point first (on naga IR,
/// `crate::proc::inline`), the other calls stay calls.
pub fn rewrite(
    shader: &Shader,
    analysis: &Analysis,
    candidate: &Candidate,
    variant: Variant,
    options: &Options,
) -> Result<Rewritten, Refusal> {
    if candidate.node.call_path.is_empty() {
        return rewrite_at(
            shader,
            analysis,
            candidate,
            candidate.node.expression,
            variant,
            options,
        );
    }
    let path: Vec<usize> = candidate.node.call_path.iter().map(|s| s.ordinal).collect();
    let (specialised, node) = crate::analysis::calls::specialise(
        shader,
        analysis.entry_index,
        &path,
        candidate.node.expression,
    )
    .map_err(|err| {
        Refusal::internal(format!(
            "inlining the calls down to `{}`: {err}",
            candidate.node.function
        ))
    })?;
    rewrite_at(&specialised, analysis, candidate, node, variant, options)
}

/// Rewrites `shader` to cache the value of `node`, an expression of its
/// fragment entry point, as `candidate` describes it: the settings and
/// the node checked, the cache's helpers imported, the vertex stage
/// instrumented, the fragment stage split at the node into payload and
/// shade, a module per pass, and the plan.
fn rewrite_at(
    shader: &Shader,
    analysis: &Analysis,
    candidate: &Candidate,
    node: naga::Handle<naga::Expression>,
    variant: Variant,
    options: &Options,
) -> Result<Rewritten, Refusal> {
    let recipe = Recipe::of(variant, options)?;
    refuse_settings(options)?;
    let stages = recipe.stages();
    let (options, format_note) = cache_format(&stages, options, candidate);
    let options = &options;
    let original = &shader.module;
    let entry = &original.entry_points[analysis.entry_index];
    let function = &entry.function;
    let Some(result) = function.result.clone() else {
        return Err(Refusal::new("the fragment entry point returns nothing"));
    };
    if let Some(refusal) = refuse_entry_point(shader, analysis) {
        return Err(refusal);
    }
    // Trip counts do not matter here, only where expressions run.
    let layout = crate::proc::layout(
        original,
        function,
        crate::cost::Weights::default().default_loop_trips,
    );
    let graph = ExprGraph::new(function, &layout);
    let slice = split::PayloadSlice::of(original, function, &layout, &graph, node, &stages)?;
    // Where the cache's resources go: the first bind group the user's
    // shader leaves free; when it uses all four WebGPU allows, after its
    // last binding in the last one.
    let slot = CacheSlot::for_module(original, options.max_bind_groups);
    let mut module = original.clone();
    let helpers =
        helpers::CacheHelpers::import(&mut module, slot, options, recipe.readback(), candidate)?;
    let vertex = instrumented_vertex(&mut module, analysis, options, slot)?;
    if let (None, Some(reason)) = (vertex.entry_index, recipe.needs_vertex_stage()) {
        return Err(Refusal::new(reason));
    }
    mark_positions_invariant(&mut module);
    let functions = split::split(
        &mut module,
        (shader, analysis, candidate),
        &graph,
        &slice,
        node,
        (options, helpers.absent),
    )?;
    let pieces = helpers.pieces(
        entry,
        result,
        functions,
        candidate,
        vertex.previous_location,
    );
    let gbuffer = g_buffer(&recipe, &mut module, &pieces, slot, &vertex)?;
    let passes_of = PassContext {
        module: &module,
        pieces: &pieces,
        vertex: &vertex,
        entry,
        gbuffer: gbuffer.as_ref(),
        recipe: &recipe,
    };
    let mut passes = Vec::new();
    for (index, &stage) in stages.iter().enumerate() {
        passes.push((stage, passes_of.pass(stage, format!("pass{}", index + 1))?));
    }
    let classify = passes_of.pass(Stage::Cache(CacheStage::Classify), "classify".into())?;

    let mut plan = plan::build(plan::Inputs {
        shader,
        analysis,
        candidate,
        recipe: &recipe,
        options,
        slot,
        vertex: &vertex,
        passes: &passes,
        classify: &classify,
        gbuffer: gbuffer.as_ref(),
        result: &pieces.result,
        params: cache_params_layout()?,
    })
    .map_err(Refusal::new)?;
    plan.cache.format_note = format_note;
    plan.node.path = slice.path.as_ref().map(|p| p.describe().to_string());
    // What a host will check of the plan holds of every plan written.
    plan.check().map_err(Refusal::internal)?;
    Ok(Rewritten {
        variant,
        node: candidate.node.id.clone(),
        passes: passes.into_iter().map(|(_, p)| p).collect(),
        classify,
        plan,
    })
}

/// The deferred variant's G-buffer, its textures bound after the twins;
/// `None` for a variant whose passes draw the geometry.
fn g_buffer(
    recipe: &Recipe,
    module: &mut naga::Module,
    pieces: &Pieces,
    slot: CacheSlot,
    vertex: &vertex::VertexStage,
) -> Result<Option<gbuffer::GBuffer>, Refusal> {
    let Some(keeps) = recipe.screen_space() else {
        return Ok(None);
    };
    let first = slot.first_binding
        + first_twin_binding().map_err(Refusal::internal)?
        + vertex.twins.len() as u32;
    gbuffer::GBuffer::new(module, pieces, keeps, (slot.group, first)).map(Some)
}

/// The vertex stage the passes draw with, instrumented: the previous clip
/// position computed beside the position, its twins bound after the
/// cache's resources. A fragment-only module (its vertex stage composed
/// elsewhere) gets fragment passes that take the previous clip position
/// as an input; the plan says what the host's vertex stage must output.
fn instrumented_vertex(
    module: &mut naga::Module,
    analysis: &Analysis,
    options: &Options,
    slot: CacheSlot,
) -> Result<vertex::VertexStage, Refusal> {
    if vertex::is_fragment_only(module) && options.vertex_entry.is_none() {
        return Ok(vertex::fragment_only(module, analysis.entry_index));
    }
    let vertex_index = vertex::vertex_entry(
        module,
        analysis.entry_index,
        options.vertex_entry.as_deref(),
    )?;
    let twins = slot.first_binding + first_twin_binding().map_err(Refusal::internal)?;
    vertex::instrument(
        module,
        vertex_index,
        (slot.group, twins),
        &options.deforming_inputs,
    )
}

/// Settings no variant can be built with.
fn refuse_settings(options: &Options) -> Result<(), Refusal> {
    if options.refresh_quad == 0 {
        return Err(Refusal::new(
            "a refresh block of 0 pixels: k (--refresh-quad) is at least 1",
        ));
    }
    if !(0.0..1.0).contains(&options.depth_epsilon) {
        return Err(Refusal::new(format!(
            "a depth tolerance ε of {}: it lies in [0, 1)",
            options.depth_epsilon
        )));
    }
    if options.refresh_period > MAX_REFRESH_PERIOD {
        return Err(Refusal::new(format!(
            "a refresh period of {} frames is beyond the largest the refresh indicator takes, {MAX_REFRESH_PERIOD}",
            options.refresh_period
        )));
    }
    Ok(())
}

/// The options with the cache format the passes (`stages`) can use, and
/// why it differs from the one asked for. Three-pass shades from the
/// cached value itself, so a payload an rgba16float cache cannot hold
/// would be wrong on screen (one- and two-pass recompute it instead: the
/// lookup misses, see `cache_encode`). Where the analysis cannot bound
/// the node's value below 65504, three-pass keeps its cache in
/// rgba32float.
fn cache_format(
    stages: &[Stage],
    options: &Options,
    candidate: &Candidate,
) -> (Options, Option<String>) {
    let shows_cached_value = stages.iter().any(|s| s.shows_cached_value());
    if shows_cached_value && options.cache_format == CacheFormat::Rgba16float && !candidate.fits_f16
    {
        let widened = Options {
            cache_format: CacheFormat::Rgba32float,
            ..options.clone()
        };
        let note = format!(
            "rgba32float instead of rgba16float: the node's value may reach 65504 (it is {}), and three-pass shades from the cached value",
            crate::analysis::range::describe(candidate.range)
        );
        (widened, Some(note))
    } else {
        (options.clone(), None)
    }
}

/// What every pass of a variant is built from: the rewritten module, the
/// fragment stage's pieces, the instrumented vertex stage, the original
/// entry point, the deferred variant's G-buffer and the recipe.
struct PassContext<'a> {
    module: &'a naga::Module,
    pieces: &'a Pieces,
    vertex: &'a vertex::VertexStage,
    entry: &'a naga::EntryPoint,
    gbuffer: Option<&'a gbuffer::GBuffer>,
    recipe: &'a Recipe,
}

impl PassContext<'_> {
    /// One pass's module: the rewritten module with the vertex entry
    /// point and the pass's fragment entry point for `stage`, compacted,
    /// validated, and checked for derivatives in non-uniform control flow
    /// and after a kill. With a G-buffer (the deferred variant), every
    /// pass but the G-buffer pass itself runs in screen space and reads
    /// it.
    fn pass(&self, stage: Stage, name: String) -> Result<PassModule, Refusal> {
        let (pieces, vertex) = (self.pieces, self.vertex);
        let mut pass = self.module.clone();
        let (fragment, screen_vertex) = self.fragment(&mut pass, stage)?;
        let mut vertex_entry = match screen_vertex {
            Some(fullscreen) => Some(fullscreen),
            None => vertex.entry_index.map(|i| pass.entry_points[i].clone()),
        };
        // A pass that does not reproject draws with the vertex stage as
        // the original has it: no twins read, no previous position
        // interpolated.
        if let (Some(entry), Some(plain), false, None) = (
            &mut vertex_entry,
            &vertex.plain,
            fragment::reprojects_in(stage, pieces),
            self.gbuffer,
        ) {
            entry.function = plain.clone();
        }
        // The samples are shaded on the jittered lattice (in screen space
        // they read the lattice's pixels from the G-buffer).
        if let (Some(entry), Stage::Lowres(stage::LowresStage::Samples), None) =
            (&mut vertex_entry, stage, self.gbuffer)
        {
            lowres::jitter_vertex(&mut pass, entry, pieces.lowres.jitter)?;
        }
        pass.entry_points = vertex_entry
            .into_iter()
            .chain([naga::EntryPoint {
                function: fragment,
                ..self.entry.clone()
            }])
            .collect();
        naga::compact::compact(&mut pass, naga::compact::KeepUnused::No);
        let info = crate::front::validate(&pass).map_err(|err| {
            let diagnostic = crate::diagnostic::Diagnostic::from_spanned_error(&err);
            Refusal::internal(format!(
                "{name} does not validate: {} ({})",
                diagnostic.message,
                diagnostic.notes.join("; ")
            ))
        })?;
        uniformity::check(&pass, &info)
            .map_err(|err| Refusal::internal(format!("the rewrite left {err}")))?;
        uniformity::check_kills(&pass)
            .map_err(|err| Refusal::internal(format!("the rewrite left {err}")))?;
        Ok(PassModule {
            name,
            module: pass,
            info,
        })
    }

    /// The fragment entry point of `stage`, built by the module that
    /// builds that kind of pass, and the vertex entry point a screen-space
    /// pass draws with.
    fn fragment(
        &self,
        pass: &mut naga::Module,
        stage: Stage,
    ) -> Result<(naga::Function, Option<naga::EntryPoint>), Refusal> {
        let pieces = self.pieces;
        Ok(match (stage, self.gbuffer, self.recipe.upsampling()) {
            (Stage::Lowres(stage), Some(gbuffer), Some(upsampling)) => (
                lowres::entry(
                    pass,
                    pieces,
                    stage,
                    upsampling,
                    fragment::Inputs::Screen(gbuffer),
                )?,
                Some(gbuffer.fullscreen.clone()),
            ),
            (Stage::Lowres(stage), None, Some(upsampling)) => (
                lowres::entry(pass, pieces, stage, upsampling, fragment::Inputs::Varyings)?,
                None,
            ),
            (Stage::Lowres(stage), _, None) => {
                return Err(Refusal::internal(format!(
                    "the {stage:?} pass of a variant without upsampling"
                )))
            }
            (Stage::GBuffer, Some(gbuffer), _) => (gbuffer.write_entry(pass, pieces)?, None),
            (Stage::GBuffer, None, _) => {
                return Err(Refusal::internal("a G-buffer pass without a G-buffer"))
            }
            (Stage::Cache(stage), Some(gbuffer), _) => (
                fragment::entry_point(pass, pieces, stage, fragment::Inputs::Screen(gbuffer))?,
                Some(gbuffer.fullscreen.clone()),
            ),
            (Stage::Cache(stage), None, _) => (
                fragment::entry_point(pass, pieces, stage, fragment::Inputs::Varyings)?,
                None,
            ),
        })
    }
}

/// Makes `function` return zero (of its result type) at once: a payload,
/// a shade or a fragment stage made free, to measure what the rest costs.
pub fn free_function(function: &mut naga::Function) {
    function.expressions = naga::Arena::new();
    function.local_variables = naga::Arena::new();
    function.named_expressions = Default::default();
    let value = function.result.as_ref().map(|result| {
        function.expressions.append(
            naga::Expression::ZeroValue(result.ty),
            naga::Span::UNDEFINED,
        )
    });
    function.body = naga::Block::from_vec(vec![naga::Statement::Return { value }]);
}

/// Why no node of the analysed fragment entry point can be cached,
/// whichever node and variant: said once for the shader rather than once
/// per node and variant (a grid shader that writes its depth was 380
/// identical refusals).
pub fn refuse_entry_point(shader: &Shader, analysis: &Analysis) -> Option<Refusal> {
    let function = &shader.module.entry_points[analysis.entry_index].function;
    let result = function.result.as_ref()?;
    writes_frag_depth(&shader.module, result).then(|| {
        Refusal::new(
            "the fragment stage writes @builtin(frag_depth), so the depth of each pixel is the shader's and not the rasterised one: the cache reprojects a pixel from its rasterised position and tests the rasterised depth against the cached one, and a surface the shader moves in depth (an infinite grid, an impostor, a ray-marched object) would reuse values where it no longer is, and miss where it is. Nothing of this entry point can be cached as it is: to measure what caching its colour would save, profile a copy whose fragment stage returns the colour alone",
        )
    })
}

/// [`refuse_entry_point`] as an error at the entry point's name: what a
/// command says before trying any node.
pub fn check_entry_point(
    shader: &Shader,
    analysis: &Analysis,
) -> Result<(), crate::diagnostic::Error> {
    let Some(refusal) = refuse_entry_point(shader, analysis) else {
        return Ok(());
    };
    let at = crate::front::find_function_name(&shader.file.text, &analysis.entry).unwrap_or(0..0);
    Err(crate::diagnostic::Error::in_file(
        shader.file.clone(),
        crate::diagnostic::Diagnostic::error(format!(
            "entry point `{}` cannot be cached: {}",
            analysis.entry, refusal.reason
        ))
        .with_label(at, "this entry point"),
    ))
}

/// Whether the fragment result writes `@builtin(frag_depth)`.
pub(crate) fn writes_frag_depth(module: &naga::Module, result: &naga::FunctionResult) -> bool {
    crate::proc::has_binding(module, &result.binding, result.ty, |b| {
        matches!(b, naga::Binding::BuiltIn(naga::BuiltIn::FragDepth))
    })
}

/// Marks every `@builtin(position)` of every struct invariant, so the
/// vertex output and the fragment input agree.
pub(crate) fn mark_positions_invariant(module: &mut naga::Module) {
    let handles: Vec<_> = module.types.iter().map(|(h, _)| h).collect();
    for handle in handles {
        let ty = &module.types[handle];
        if let naga::TypeInner::Struct { ref members, span } = ty.inner {
            if members.iter().any(|m| {
                matches!(
                    m.binding,
                    Some(naga::Binding::BuiltIn(naga::BuiltIn::Position {
                        invariant: false
                    }))
                )
            }) {
                let mut members = members.clone();
                for member in &mut members {
                    if let Some(naga::Binding::BuiltIn(naga::BuiltIn::Position { invariant })) =
                        member.binding.as_mut()
                    {
                        *invariant = true;
                    }
                }
                let replacement = naga::Type {
                    name: ty.name.clone(),
                    inner: naga::TypeInner::Struct { members, span },
                };
                module.types.replace(handle, replacement);
            }
        }
    }
}

/// The type handle of `expr`, inserting the type when validation only
/// knows it by value.
pub(crate) fn type_handle(
    module: &mut naga::Module,
    info: &naga::valid::FunctionInfo,
    expr: naga::Handle<naga::Expression>,
) -> naga::Handle<naga::Type> {
    match info[expr].ty {
        naga::proc::TypeResolution::Handle(h) => h,
        naga::proc::TypeResolution::Value(ref inner) => module.types.insert(
            naga::Type {
                name: None,
                inner: inner.clone(),
            },
            naga::Span::UNDEFINED,
        ),
    }
}

/// A function's arguments as a helper function takes them: no bindings.
pub(crate) fn without_bindings(
    arguments: &[naga::FunctionArgument],
) -> Vec<naga::FunctionArgument> {
    arguments
        .iter()
        .map(|a| naga::FunctionArgument {
            binding: None,
            ..a.clone()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A shader binding all four of WebGPU's groups (as Bevy's materials
    /// do) shares its last with the cache on a four-group device, and
    /// leaves the material's group alone on a device with more.
    #[test]
    fn a_shader_using_every_group_gets_a_group_of_its_own_when_the_device_has_more() {
        let module = naga::front::wgsl::parse_str(
            "@group(0) @binding(0) var<uniform> view: vec4<f32>;
             @group(3) @binding(2) var<uniform> material: vec4<f32>;
             @fragment fn f() -> @location(0) vec4<f32> { return view + material; }",
        )
        .unwrap();
        let shared = CacheSlot {
            group: 3,
            first_binding: 3,
        };
        let own = CacheSlot {
            group: 4,
            first_binding: 0,
        };
        assert_eq!(
            CacheSlot::for_module(&module, DEFAULT_MAX_BIND_GROUPS),
            shared
        );
        assert_eq!(CacheSlot::for_module(&module, 8), own);
    }
}

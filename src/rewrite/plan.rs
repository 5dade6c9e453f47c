//! variants → plans: building a variant's [`Plan`] from the rewrite that
//! made its passes, and the plan of the unmodified shader the profiler
//! runs as the reference. The plan's definition is the `shadecache-plan`
//! crate's ([`crate::plan`]), which depends on nothing of ours.

use naga::{Binding, Module, TypeInner};

use super::fragment;
use super::stage::{CacheStage, LowresStage, Stage, Writes};
use super::variants::Recipe;
use super::vertex::VertexStage;
use super::{Options, PassModule};
use crate::analysis::{Analysis, Candidate};
use crate::front::Shader;
use crate::plan::*;
use crate::rewrite;

/// What [`build`] needs.
#[derive(Debug)]
pub(crate) struct Inputs<'a> {
    pub shader: &'a Shader,
    pub analysis: &'a Analysis,
    pub candidate: &'a Candidate,
    pub recipe: &'a Recipe,
    pub options: &'a Options,
    pub slot: rewrite::CacheSlot,
    pub vertex: &'a VertexStage,
    pub passes: &'a [(Stage, PassModule)],
    pub classify: &'a PassModule,
    /// The deferred variant's G-buffer.
    pub gbuffer: Option<&'a rewrite::gbuffer::GBuffer>,
    pub result: &'a naga::FunctionResult,
    /// `CacheParams`' layout ([`super::cache_params_layout`]).
    pub params: Vec<Field>,
}

pub(crate) fn build(inputs: Inputs) -> Result<Plan, String> {
    let Inputs {
        shader,
        analysis,
        candidate,
        recipe,
        options,
        slot,
        vertex,
        passes,
        classify,
        gbuffer,
        result,
        params,
    } = inputs;
    let module = &shader.module;
    let entry = &module.entry_points[analysis.entry_index];
    let group = slot.group;
    // A fragment-only module's passes have no vertex entry point: the
    // host draws them with its own (`host_vertex`).
    let vertex_entry = vertex.entry_index.map(|i| &module.entry_points[i]);
    let vertex_name = vertex_entry.map_or(String::new(), |v| v.name.clone());
    let names = PassNames {
        vertex: vertex_name.clone(),
        fragment: entry.name.clone(),
    };
    let mut plan_passes: Vec<Pass> = passes
        .iter()
        .map(|(stage, pass)| plan_pass(module, result, options, (*stage, pass), &names, gbuffer))
        .collect();
    first_writers_clear(&mut plan_passes);
    let upsampling = recipe.upsampling();

    let entries: Vec<usize> = std::iter::once(analysis.entry_index)
        .chain(vertex.entry_index)
        .collect();
    let original = entry_resources(module, &entries);
    let first_twin = slot.first_binding + rewrite::first_twin_binding()?;
    let previous = vertex
        .twins
        .iter()
        .filter_map(|&(from, to)| {
            let shadows = resource(module, &module.global_variables[from], None)?;
            Some(Twin {
                group,
                binding: twin_binding(vertex, first_twin, to),
                name: format!("previous_{}", shadows.name),
                shadows,
            })
        })
        .collect();
    let mut cache = cache_resources(group, slot.first_binding)?;
    if let Some(gbuffer) = gbuffer {
        cache.extend(gbuffer_resources(gbuffer));
    }

    Ok(Plan {
        format: 1,
        shader: shader.file.path.clone(),
        entry: entry.name.clone(),
        node: plan_node(candidate),
        variant: recipe.variant(),
        passes: plan_passes,
        classify: Some(classify_pass(
            module, result, options, classify, &names, gbuffer,
        )),
        vertex_layout: match vertex_entry {
            Some(v) => vertex_layout(module, &v.function, &vertex.instance_twins)?,
            None => Vec::new(),
        },
        host_vertex: vertex_entry.is_none().then(|| HostVertex {
            previous_clip_position_location: vertex.previous_location,
            requirement: format!(
                "the module has no vertex stage: the host's must output, beside what `{}` reads, \
                 `@location({}) previous_clip_position: vec4<f32>` (last frame's clip position \
                 of the same vertex: last frame's view-projection and model applied to it, \
                 perspective-interpolated) and mark its `@builtin(position)` `@invariant`",
                entry.name, vertex.previous_location
            ),
        }),
        bindings: Bindings {
            original,
            previous,
            previous_members: previous_members(module, &vertex.member_twins),
            cache,
        },
        cache: Cache {
            format: options.cache_format,
            format_note: None,
            reconstruction: recipe.reconstruction(),
            components: candidate.components,
            swap: if upsampling.is_some() {
                "two payload textures, two history textures and two depth buffers alternate: at the end of a frame, this frame's payload, history and depth become last frame's (cache_previous_payload, cache_previous_history, cache_previous_depth); the samples, their geometry and their depth buffer (1/s × 1/s) are made again every frame; on the first frame, after a resize or a camera cut, the previous depth is cleared to the far-plane depth so every pixel's history misses".into()
            } else {
                "two payload textures, two age textures and two depth buffers alternate: at the end of a frame, this frame's payload texture, age texture and depth buffer become last frame's (bound as cache_previous_payload, cache_previous_age and cache_previous_depth) and last frame's are rendered into next; on the first frame, after a resize or a camera cut, the previous depth is cleared to the far-plane depth (clear.depth) so every pixel misses".into()
            },
            params,
        },
        refresh: refresh(options, upsampling),
        upsampling: upsampling.cloned(),
        clear: Clear {
            color: [0.0, 0.0, 0.0, 1.0],
            cache: [0.0, 0.0, 0.0, 0.0],
            depth: options.depth.far_depth().into(),
        },
        // The helpers map last frame's positions into the viewport's
        // rectangle of the target (`viewport_origin`); lowres's samples
        // are a lattice over the whole target.
        assumes: FrameAssumptions {
            partial_viewport: upsampling.is_none(),
            ..FrameAssumptions::default()
        },
        shader_defs: shader.defs.clone(),
    })
}

/// The refresh the passes follow: with `upsampling`, lowres's lattice;
/// else the cache's refresh pattern (with adaptive refresh, said).
fn refresh(options: &Options, upsampling: Option<&Upsampling>) -> Refresh {
    if let Some(upsampling) = upsampling {
        let s = upsampling.factor;
        return Refresh {
            period: s * s,
            quad: s,
            depth_epsilon: options.depth_epsilon,
            offsets: "the samples' offset in each s×s window (s = quad) is refresh_phase = frame mod s² (period) read through a Bayer order (shaders/cache.wgsl, cache_sample_offset): every pixel is shaded once every s² frames".into(),
        };
    }
    let mut offsets = String::from("16 bits of a PCG hash of the k×k block coordinates, times the period, over 2^16; refresh when (offset + refresh_phase) mod period == 0, with refresh_phase = frame mod period kept by the host, or when the value's age (the age target) reaches min(period, 2048)");
    if options.adaptive_refresh {
        offsets.push_str("; adaptive: a value computed where the cache held one for the same point that differs from it by 10% or more starts at age ⌊¾·min(period, 2048)⌋, so it is refreshed again after a quarter of the period (cache_adaptive_age)");
    }
    Refresh {
        period: options.refresh_period,
        quad: options.refresh_quad,
        depth_epsilon: options.depth_epsilon,
        offsets,
    }
}

/// The entry points every pass draws with.
struct PassNames {
    /// Empty for a fragment-only module, whose host draws with its own.
    vertex: String,
    fragment: String,
}

/// One pass of the plan: its targets (the frame's outputs, the cache and
/// its age, the G-buffer) with their loads (made right by
/// [`first_writers_clear`]), its depth and stencil state, what it draws,
/// whether it discards and what it binds.
fn plan_pass(
    module: &Module,
    result: &naga::FunctionResult,
    options: &Options,
    (stage, pass): (Stage, &PassModule),
    names: &PassNames,
    gbuffer: Option<&rewrite::gbuffer::GBuffer>,
) -> Pass {
    let target = |location: u32, target: TargetKind, format: TextureFormat| ColorTarget {
        location,
        target,
        format,
        load: LoadOp::Load,
    };
    let color = |l: u32| {
        target(
            l,
            TargetKind::Color,
            output_format(module, result, l, options.color_format),
        )
    };
    let cache = |l: u32| target(l, TargetKind::Cache, options.cache_format.texture_format());
    let history = |l: u32| target(l, TargetKind::History, HISTORY_FORMAT);
    let age = |l: u32| target(l, TargetKind::Age, AGE_FORMAT);
    let color_locations = fragment::output_locations(module, result);
    let cache_location = fragment::cache_location(module, result);
    let color_targets = match stage.writes() {
        Writes::Color => color_locations.iter().map(|&l| color(l)).collect(),
        Writes::Cache => vec![cache(0), age(1)],
        Writes::Classes => vec![target(0, TargetKind::Classes, TextureFormat::Rgba8Unorm)],
        Writes::ColorAndCache => {
            let mut targets: Vec<_> = color_locations.iter().map(|&l| color(l)).collect();
            targets.push(cache(cache_location));
            targets.push(age(cache_location + 1));
            targets
        }
        Writes::Samples => vec![
            target(
                0,
                TargetKind::Samples,
                options.cache_format.texture_format(),
            ),
            target(1, TargetKind::SampleGeometry, HISTORY_FORMAT),
        ],
        Writes::ColorAndHistory => {
            let mut targets: Vec<_> = color_locations.iter().map(|&l| color(l)).collect();
            targets.push(cache(cache_location));
            targets.push(history(cache_location + 1));
            targets
        }
        Writes::Stencil => Vec::new(),
        Writes::GBuffer => gbuffer
            .map(|g| g.formats.as_slice())
            .unwrap_or_default()
            .iter()
            .enumerate()
            .map(|(i, &format)| target(i as u32, TargetKind::GBuffer, format))
            .collect(),
    };
    let screen = gbuffer.is_some() && stage != Stage::GBuffer;
    let (compare, write) = match stage {
        _ if screen => (CompareFunction::Always, false),
        Stage::Cache(CacheStage::ShadeFromCache) | Stage::Cache(CacheStage::Classify) => {
            (CompareFunction::Equal, false)
        }
        _ => (options.depth.nearer(), true),
    };
    Pass {
        name: pass.name.clone(),
        role: role(stage, screen).into(),
        shader: format!("{}.wgsl", pass.name),
        stage_shaders: Vec::new(),
        vertex_entry: match gbuffer {
            Some(gbuffer) if screen => gbuffer.fullscreen.name.clone(),
            _ => names.vertex.clone(),
        },
        fragment_entry: names.fragment.clone(),
        color_targets,
        depth: Depth {
            format: DEPTH_FORMAT,
            compare,
            write,
            load: LoadOp::Load,
        },
        discards: stage.discards() || pass_discards(&pass.module),
        bindings: used_bindings(&pass.module),
        draw: if screen {
            DrawKind::Fullscreen
        } else {
            DrawKind::Geometry
        },
        stencil: gbuffer.map(|_| deferred_stencil(stage)),
        resolution_divisor: match stage {
            Stage::Lowres(LowresStage::Lattice | LowresStage::Samples) => options.upsampling.factor,
            _ => 1,
        },
    }
}

/// The format of lowres's history and of its samples' geometry.
const HISTORY_FORMAT: TextureFormat = TextureFormat::Rgba32Float;

/// The stencil bit a deferred lookup sets where it reused the cache.
const REUSED_BIT: u32 = 0x80;
/// The stencil bits that hold the draw's ordinal.
const ORDINAL_BITS: u32 = 0x7f;

/// The deferred variants' stencil, by pass: the geometry pass writes
/// each draw's ordinal where the draw is visible; the lookup, drawn per
/// draw over the screen, runs on that draw's pixels and marks those it
/// reuses; the misses run where the draw's pixels are not marked; the
/// shading (and the classification) on all the draw's pixels. Deferred
/// lowres's lattice writes the ordinals into the samples' stencil, its
/// samples test them there, its upsampling marks what it keeps and its
/// reshading runs where the upsampling discarded.
fn deferred_stencil(stage: Stage) -> Stencil {
    let test = |read_mask| Stencil {
        compare: CompareFunction::Equal,
        read_mask,
        write_mask: 0,
        replace: false,
        reference_bits: 0,
    };
    match stage {
        Stage::GBuffer | Stage::Lowres(LowresStage::Lattice) => Stencil {
            compare: CompareFunction::Always,
            read_mask: 0xff,
            write_mask: ORDINAL_BITS,
            replace: true,
            reference_bits: 0,
        },
        Stage::Cache(CacheStage::ReprojectOrDiscard) | Stage::Lowres(LowresStage::Upsample) => {
            Stencil {
                write_mask: REUSED_BIT,
                replace: true,
                reference_bits: REUSED_BIT,
                ..test(ORDINAL_BITS)
            }
        }
        Stage::Cache(CacheStage::Payload) | Stage::Lowres(LowresStage::Reshade) => test(0xff),
        _ => test(ORDINAL_BITS),
    }
}

/// Makes the first pass that writes each kind of target clear it, and
/// the later ones load it; and the first pass at each resolution clear
/// its depth buffer (lowres's samples have one of their size).
fn first_writers_clear(passes: &mut [Pass]) {
    let mut written = Vec::new();
    let mut sizes = Vec::new();
    for pass in passes.iter_mut() {
        pass.depth.load = if sizes.contains(&pass.resolution_divisor) {
            LoadOp::Load
        } else {
            sizes.push(pass.resolution_divisor);
            LoadOp::Clear
        };
        for target in &mut pass.color_targets {
            let key = (target.target, target.location);
            target.load = if written.contains(&key) {
                LoadOp::Load
            } else {
                LoadOp::Clear
            };
        }
        written.extend(pass.color_targets.iter().map(|t| (t.target, t.location)));
    }
}

/// The diagnostic pass, drawn after a frame over what it drew (depth
/// equal, or the draw's stencil in screen space): the cache's decision at
/// each pixel as a colour, into a target it clears.
fn classify_pass(
    module: &Module,
    result: &naga::FunctionResult,
    options: &Options,
    classify: &PassModule,
    names: &PassNames,
    gbuffer: Option<&rewrite::gbuffer::GBuffer>,
) -> Pass {
    let mut pass = plan_pass(
        module,
        result,
        options,
        (Stage::Cache(CacheStage::Classify), classify),
        names,
        gbuffer,
    );
    for target in &mut pass.color_targets {
        target.load = LoadOp::Clear;
    }
    pass
}

/// The cached node as the plan names it, with the calls down to it.
fn plan_node(candidate: &Candidate) -> PlanNode {
    PlanNode {
        id: candidate.node.id.clone(),
        text: candidate.node.text.clone(),
        ty: candidate.node.ty.clone(),
        components: candidate.components,
        path: None,
        function: (!candidate.node.call_path.is_empty()).then(|| candidate.node.function.clone()),
        call_path: candidate
            .node
            .call_path
            .iter()
            .map(|step| PlanCall {
                function: step.function.clone(),
                text: step.text.clone(),
                at: step.span.start,
            })
            .collect(),
    }
}

/// The target format for the fragment output at `location`: `float` (the
/// colour format asked for) for a float output, a 32-bit integer format
/// with as many channels for an integer one (a G-buffer's ids).
pub(crate) fn output_format(
    module: &Module,
    result: &naga::FunctionResult,
    location: u32,
    float: TextureFormat,
) -> TextureFormat {
    let output = crate::proc::located(module, &result.binding, result.ty)
        .into_iter()
        .find(|(l, _)| *l == location);
    let (size, kind) = match output.map(|(_, inner)| inner) {
        Some(TypeInner::Scalar(scalar)) => (1, scalar.kind),
        Some(TypeInner::Vector { size, scalar }) => (size as u32, scalar.kind),
        _ => return float,
    };
    use TextureFormat as T;
    match (kind, size) {
        (naga::ScalarKind::Uint, 1) => T::R32Uint,
        (naga::ScalarKind::Uint, 2) => T::Rg32Uint,
        (naga::ScalarKind::Uint, _) => T::Rgba32Uint,
        (naga::ScalarKind::Sint, 1) => T::R32Sint,
        (naga::ScalarKind::Sint, 2) => T::Rg32Sint,
        (naga::ScalarKind::Sint, _) => T::Rgba32Sint,
        _ => float,
    }
}

fn role(stage: Stage, screen: bool) -> &'static str {
    if screen {
        return match stage {
            Stage::Cache(CacheStage::ReprojectOrDiscard) => "screen space, per draw over its pixels (stencil): reproject; hit: write the cached payload to this frame's cache and mark the pixel; miss or refresh: discard",
            Stage::Cache(CacheStage::Payload) => "screen space, per draw over its unmarked pixels (stencil): compute the payload from the G-buffer into the cache",
            Stage::Cache(CacheStage::ShadeFromCache) => "screen space, per draw over its pixels (stencil): shade from the G-buffer and this frame's cache at the pixel",
            Stage::Cache(CacheStage::Classify) => "diagnostic, after the frame, in screen space: the cache's decision at each visible pixel",
            Stage::Lowres(LowresStage::Lattice) => "at 1/s × 1/s, screen space, per draw: mark in the samples' stencil the lattice pixels whose G-buffer ordinal is the draw's; discard the rest",
            Stage::Lowres(LowresStage::Samples) => "at 1/s × 1/s, screen space, per draw over its lattice pixels (stencil): the payload from the G-buffer at this frame's lattice pixel (level of detail biased by −log2 s) into the samples, and their normal, depth, draw id and temporal gradient",
            Stage::Lowres(LowresStage::Upsample) => "screen space, per draw over its pixels (stencil): rebuild the payload from the four nearest samples and the reprojected history, shade from the G-buffer and it, write colour, the payload and its history (with adaptive refresh: discard the pixels it cannot vouch for, mark the rest)",
            Stage::Lowres(LowresStage::Reshade) => "screen space, per draw over its unmarked pixels (stencil): compute the payload from the G-buffer at full resolution and shade, write colour, the payload and an exact history",
            _ => "screen space",
        };
    }
    match stage {
        Stage::GBuffer => "the only geometry pass: depth, each draw's ordinal in the stencil, and the fragment's inputs and previous clip position into the G-buffer",
        Stage::Cache(CacheStage::OnePass) => "reproject; hit: shade from the cached payload; miss or refresh: compute the payload; write colour and cache",
        Stage::Cache(CacheStage::ReuseOrDiscard) => "reproject; hit: shade from the cached payload, write colour and cache; miss or refresh: discard",
        Stage::Cache(CacheStage::Full) => "the pixels pass 1 left empty (depth test): compute payload and colour, write colour and cache",
        Stage::Cache(CacheStage::ReprojectOrDiscard) => "reproject; hit: write the cached payload to this frame's cache; miss or refresh: discard",
        Stage::Cache(CacheStage::Payload) => "the pixels pass 1 left empty (depth test): compute the payload into the cache",
        Stage::Cache(CacheStage::ShadeFromCache) => "every pixel (depth equal): shade from this frame's cache at the pixel",
        Stage::Cache(CacheStage::Classify) => "diagnostic, after the frame (depth equal): the cache's decision at each visible pixel",
        Stage::Lowres(LowresStage::Samples) => "at 1/s × 1/s of the pixels, its own depth buffer, the projection jittered onto this frame's lattice: the payload (level of detail biased by −log2 s) into the samples, and their normal, depth, draw id and temporal gradient",
        Stage::Lowres(LowresStage::Upsample) => "every pixel (depth test): rebuild the payload from the four nearest samples and the reprojected history, shade from it, write colour, the payload and its history (with adaptive refresh: discard the pixels it cannot vouch for)",
        Stage::Lowres(LowresStage::Reshade) => "the pixels pass 2 left empty (depth test): compute the payload at full resolution and shade, write colour, the payload and an exact history",
        Stage::Lowres(LowresStage::Lattice) => "the lattice's stencil (screen space only)",
    }
}

/// The binding of `twin`: the twins follow the cache's own bindings, in
/// the order the vertex stage made them.
fn twin_binding(
    vertex: &VertexStage,
    first_twin: u32,
    twin: naga::Handle<naga::GlobalVariable>,
) -> u32 {
    let index = vertex.twins.iter().position(|&(_, t)| t == twin);
    first_twin + index.unwrap_or(0) as u32
}

fn pass_discards(module: &Module) -> bool {
    let mut discards = false;
    let mut scan = |body: &naga::Block| {
        crate::proc::each_statement(body, &mut |s| {
            discards |= matches!(s, naga::Statement::Kill)
        })
    };
    for (_, f) in module.functions.iter() {
        scan(&f.body);
    }
    for ep in &module.entry_points {
        scan(&ep.function.body);
    }
    discards
}

fn used_bindings(module: &Module) -> Vec<[u32; 2]> {
    let mut out: Vec<[u32; 2]> = module
        .global_variables
        .iter()
        .filter_map(|(_, g)| g.binding.as_ref().map(|b| [b.group, b.binding]))
        .collect();
    out.sort();
    out
}

/// The resources the entry points at `entries` use, in the module's
/// order: what a draw with them binds (a module may declare more, two at
/// one slot when no entry point uses both).
pub(crate) fn entry_resources(module: &Module, entries: &[usize]) -> Vec<Resource> {
    let used = crate::proc::globals_used_by(module, entries);
    module
        .global_variables
        .iter()
        .filter(|(h, _)| used.contains(h))
        .filter_map(|(_, g)| resource(module, g, None))
        .collect()
}

/// The cache's own resources, as `shaders/cache.wgsl` declares them (its
/// bindings from `first_binding` on in `group`), each with what to bind.
fn cache_resources(group: u32, first_binding: u32) -> Result<Vec<Resource>, String> {
    let helpers = rewrite::cache_helpers().map_err(|r| r.reason)?;
    let mut resources: Vec<Resource> = helpers
        .global_variables
        .iter()
        .filter_map(|(_, global)| {
            let name = global.name.clone()?;
            let mut resource = resource(helpers, global, Some(what_to_bind(&name).into()))?;
            resource.group = group;
            resource.binding += first_binding;
            Some(resource)
        })
        .collect();
    resources.sort_by_key(|r| r.binding);
    Ok(resources)
}

/// What a host binds for each of the cache's resources.
fn what_to_bind(name: &str) -> &'static str {
    match name {
        "cache_params" => "the refresh uniform (CacheParams), updated every frame",
        "cache_previous_payload" => "last frame's payload texture",
        "cache_previous_depth" => "last frame's depth buffer",
        "cache_current_payload" => "this frame's payload texture, after the passes that write it",
        "cache_sampler" => "linear filtering, clamp to edge",
        "cache_previous_age" => "last frame's age texture (r16float)",
        "cache_samples" => "this frame's samples (lowres: 1/s × 1/s, the cache's format)",
        "cache_sample_geometry" => {
            "this frame's samples' geometry (lowres: 1/s × 1/s, rgba32float)"
        }
        "cache_previous_history" => "last frame's upsampling history (lowres: rgba32float)",
        "cache_draw" => {
            "the draw's ordinal in its pass (vec4<u32>, x), at a dynamic offset per draw"
        }
        _ => "see shaders/cache.wgsl",
    }
}

/// The resources read through their own `previous_` members, by name.
fn previous_members(
    module: &Module,
    twins: &[crate::rewrite::member_twins::MemberTwin],
) -> Vec<shadecache_plan::PreviousMembers> {
    let name = |ty: naga::Handle<naga::Type>, index: u32| match &module.types[ty].inner {
        naga::TypeInner::Struct { members, .. } => members
            .get(index as usize)
            .and_then(|m| m.name.clone())
            .unwrap_or_default(),
        _ => String::new(),
    };
    twins
        .iter()
        .filter_map(|twin| {
            Some(shadecache_plan::PreviousMembers {
                resource: resource(module, &module.global_variables[twin.global], None)?,
                members: twin
                    .swaps
                    .iter()
                    .map(|&(ty, from, to)| [name(ty, from), name(ty, to)])
                    .collect(),
            })
        })
        .collect()
}

fn resource(
    module: &Module,
    global: &naga::GlobalVariable,
    source: Option<String>,
) -> Option<Resource> {
    let binding = global.binding.as_ref()?;
    use ResourceKind as K;
    let kind = match global.space {
        naga::AddressSpace::Uniform => K::Uniform,
        naga::AddressSpace::Storage { access } if access.contains(naga::StorageAccess::STORE) => {
            K::StorageReadWrite
        }
        naga::AddressSpace::Storage { .. } => K::Storage,
        _ => match module.types[global.ty].inner {
            TypeInner::Image {
                class: naga::ImageClass::Storage { .. },
                ..
            } => K::StorageTexture,
            TypeInner::Image {
                dim,
                arrayed,
                class,
            } => {
                let depth = matches!(class, naga::ImageClass::Depth { .. });
                let uint = matches!(
                    class,
                    naga::ImageClass::Sampled {
                        kind: naga::ScalarKind::Uint,
                        multi: false
                    }
                );
                match (dim, arrayed, depth) {
                    (naga::ImageDimension::D2, false, false) if uint => K::UintTexture,
                    (naga::ImageDimension::D2, false, false) => K::Texture,
                    (naga::ImageDimension::D2, true, false) => K::TextureArray,
                    (naga::ImageDimension::Cube, false, false) => K::CubeTexture,
                    (naga::ImageDimension::Cube, true, false) => K::CubeTextureArray,
                    (naga::ImageDimension::D2, false, true) => K::DepthTexture,
                    (naga::ImageDimension::D2, true, true) => K::DepthTextureArray,
                    (naga::ImageDimension::Cube, false, true) => K::DepthCubeTexture,
                    (naga::ImageDimension::Cube, true, true) => K::DepthCubeTextureArray,
                    (naga::ImageDimension::D1, ..) => K::Texture1d,
                    (naga::ImageDimension::D3, ..) => K::Texture3d,
                }
            }
            TypeInner::Sampler { comparison: true } => K::ComparisonSampler,
            TypeInner::Sampler { .. } => K::Sampler,
            _ => K::Other,
        },
    };
    Some(Resource {
        group: binding.group,
        binding: binding.binding,
        name: global.name.clone().unwrap_or_default(),
        kind,
        source,
    })
}

/// The vertex buffer layout the original vertex entry point expects,
/// per-instance inputs ([`crate::proc::instance_locations`]) stepped
/// per instance, followed by the previous-frame twins `twins` gives as
/// (input's location, twin's location).
fn vertex_layout(
    module: &Module,
    function: &naga::Function,
    twins: &[(u32, u32)],
) -> Result<Vec<VertexAttribute>, String> {
    let per_instance = crate::proc::instance_locations(module, function);
    let mut out = Vec::new();
    let mut add = |name: Option<&String>,
                   ty: naga::Handle<naga::Type>,
                   binding: &Option<Binding>| {
        if let Some(Binding::Location { location, .. }) = *binding {
            let name = name.cloned().unwrap_or_default();
            let format = vertex_format(&module.types[ty].inner).ok_or_else(|| {
                    format!(
                        "vertex input @location({location}) `{name}` is a {}, which no WebGPU vertex format holds",
                        crate::analysis::type_name(&module.types, &module.types[ty].inner)
                    )
                })?;
            out.push(VertexAttribute {
                location,
                name,
                format,
                step: if per_instance.contains(&location) {
                    StepMode::Instance
                } else {
                    StepMode::Vertex
                },
                previous_of: None,
            });
        }
        Ok::<(), String>(())
    };
    for input in crate::proc::inputs(module, function) {
        add(input.name, input.ty, input.binding)?;
    }
    out.sort_by_key(|a| a.location);
    let twinned: Vec<VertexAttribute> = twins
        .iter()
        .filter_map(|&(of, location)| {
            let input = out.iter().find(|a| a.location == of)?;
            Some(VertexAttribute {
                location,
                name: format!("previous_{}", input.name),
                previous_of: Some(of),
                ..input.clone()
            })
        })
        .collect();
    out.extend(twinned);
    Ok(out)
}

/// The vertex format of an input of WGSL type `inner`; `None` for what
/// WebGPU cannot feed (a three-component `f16` vector).
fn vertex_format(inner: &TypeInner) -> Option<VertexFormat> {
    let (scalar, count) = match *inner {
        TypeInner::Scalar(s) => (s, 1),
        TypeInner::Vector { size, scalar } => (scalar, size as u32),
        _ => return None,
    };
    use VertexFormat as V;
    Some(match (scalar.kind, scalar.width, count) {
        (naga::ScalarKind::Float, 2, 1) => V::Float16,
        (naga::ScalarKind::Float, 2, 2) => V::Float16x2,
        (naga::ScalarKind::Float, 2, 4) => V::Float16x4,
        (naga::ScalarKind::Float, 4, 1) => V::Float32,
        (naga::ScalarKind::Float, 4, 2) => V::Float32x2,
        (naga::ScalarKind::Float, 4, 3) => V::Float32x3,
        (naga::ScalarKind::Float, 4, 4) => V::Float32x4,
        (naga::ScalarKind::Sint, 4, 1) => V::Sint32,
        (naga::ScalarKind::Sint, 4, 2) => V::Sint32x2,
        (naga::ScalarKind::Sint, 4, 3) => V::Sint32x3,
        (naga::ScalarKind::Sint, 4, 4) => V::Sint32x4,
        (naga::ScalarKind::Uint, 4, 1) => V::Uint32,
        (naga::ScalarKind::Uint, 4, 2) => V::Uint32x2,
        (naga::ScalarKind::Uint, 4, 3) => V::Uint32x3,
        (naga::ScalarKind::Uint, 4, 4) => V::Uint32x4,
        _ => return None,
    })
}

/// The plan of the unmodified shader, which the profiler runs as the
/// reference: one pass, the original entry points, depth `less`
/// (`greater` with reversed Z). Its
/// shader file is the original source (`reference.wgsl`).
pub fn reference(shader: &Shader, analysis: &Analysis, options: &Options) -> Result<Plan, String> {
    let module = &shader.module;
    let entry = &module.entry_points[analysis.entry_index];
    let vertex_index = rewrite::vertex::vertex_entry(
        module,
        analysis.entry_index,
        options.vertex_entry.as_deref(),
    )
    .map_err(|r| r.reason)?;
    let vertex_entry = &module.entry_points[vertex_index];
    let Some(result) = entry.function.result.as_ref() else {
        return Err("the fragment entry point returns nothing".into());
    };
    // What the draw binds: the original module may declare more.
    let original = entry_resources(module, &[analysis.entry_index, vertex_index]);
    let mut bindings: Vec<[u32; 2]> = original.iter().map(|r| [r.group, r.binding]).collect();
    bindings.sort();
    bindings.dedup();
    let layout = crate::proc::layout(module, &entry.function, 8.0);
    Ok(Plan {
        format: 1,
        shader: shader.file.path.clone(),
        entry: entry.name.clone(),
        node: PlanNode {
            id: String::new(),
            text: String::new(),
            ty: String::new(),
            components: 0,
            path: None,
            function: None,
            call_path: Vec::new(),
        },
        variant: Variant::Reference,
        passes: vec![Pass {
            name: "reference".into(),
            role: "the unmodified shader".into(),
            shader: "reference.wgsl".into(),
            stage_shaders: Vec::new(),
            vertex_entry: vertex_entry.name.clone(),
            fragment_entry: entry.name.clone(),
            color_targets: fragment::output_locations(module, result)
                .into_iter()
                .map(|location| ColorTarget {
                    location,
                    target: TargetKind::Color,
                    format: output_format(module, result, location, options.color_format),
                    load: LoadOp::Clear,
                })
                .collect(),
            depth: Depth {
                format: DEPTH_FORMAT,
                compare: options.depth.nearer(),
                write: true,
                load: LoadOp::Clear,
            },
            discards: layout.discards,
            bindings,
            draw: DrawKind::Geometry,
            stencil: None,
            resolution_divisor: 1,
        }],
        classify: None,
        vertex_layout: vertex_layout(module, &vertex_entry.function, &[])?,
        upsampling: None,
        host_vertex: None,
        bindings: Bindings {
            original,
            previous: Vec::new(),
            previous_members: Vec::new(),
            cache: Vec::new(),
        },
        cache: Cache {
            format: options.cache_format,
            format_note: None,
            reconstruction: options.reconstruction.into(),
            components: 0,
            swap: String::new(),
            params: Vec::new(),
        },
        refresh: Refresh {
            period: options.refresh_period,
            quad: options.refresh_quad,
            depth_epsilon: options.depth_epsilon,
            offsets: String::new(),
        },
        clear: Clear {
            color: [0.0, 0.0, 0.0, 1.0],
            cache: [0.0; 4],
            depth: options.depth.far_depth().into(),
        },
        assumes: FrameAssumptions::default(),
        shader_defs: shader.defs.clone(),
    })
}

/// The G-buffer's textures as the plan lists them, each with what it
/// holds.
fn gbuffer_resources(gbuffer: &rewrite::gbuffer::GBuffer) -> Vec<Resource> {
    gbuffer
        .formats
        .iter()
        .enumerate()
        .map(|(t, format)| {
            let holds: Vec<&str> = gbuffer
                .holds
                .iter()
                .skip(t * 4)
                .take(4)
                .map(String::as_str)
                .collect();
            Resource {
                group: gbuffer.group,
                binding: gbuffer.first_binding + t as u32,
                name: rewrite::gbuffer::texture_name(t),
                kind: ResourceKind::UintTexture,
                source: Some(format!(
                    "this frame's G-buffer texture {t} ({format}, rendered by the geometry pass): the bits of {}",
                    holds.join(", ")
                )),
            }
        })
        .collect()
}

//! The I-frame pass, on naga IR: the user's shader drawing its frame as
//! before, plus the two 3-D flow fields of seed 000 §5 (eqs. 1–2) as
//! extra colour outputs.
//!
//! - The vertex stage computes the position three times with identical
//!   code (`rewrite::vertex::instrument_times`): now, with the
//!   *previous* I-frame's resources, and with the *next* I-frame's. Every
//!   uniform and read-only storage buffer the position reads gets a twin
//!   per time; the host fills them with that time's contents. So does
//!   every per-instance vertex input it reads: a twin input per time (the
//!   plan lists them as inputs like the others, `previous_<input>` and
//!   `next_<input>`), which the run packs with that time's instance
//!   transforms.
//! - The fragment stage runs the original fragment function as a helper
//!   (its outputs, discards and derivatives unchanged) and then writes
//!   `flow_previous` (Vb: to the previous I-frame) and `flow_next` (Vf: to
//!   the next) in `rgba16float` at the locations after the user's outputs
//!   (`shaders/iframe.wgsl`'s `flow_to`). Colour plus two such flows is
//!   within WebGPU's default 32 bytes of colour attachments per sample.
//!
//! The paper renders Vf in a geometry pass of its own, because an
//! interactive application knows t + 1's parameters only after drawing t.
//! A scripted scene knows them in advance, so both flows come from one
//! pass here; the report says so, since it is cheaper than the paper's
//! cost structure by one depth-and-flow geometry pass.

use std::sync::OnceLock;

use naga::{Binding, BuiltIn, Expression, Function, Handle, Module, Statement, TypeInner};

use crate::analysis::graph::ExprSet;
use crate::analysis::Analysis;
use crate::front::Shader;
use crate::plan::{ColorTarget, LoadOp, Plan, TargetKind, TextureFormat};
use crate::rewrite::builder::{self, Builder};
use crate::rewrite::copy::FunctionCopy;
use crate::rewrite::vertex::{self, TwinTime};
use crate::rewrite::{self, CacheSlot, Options, Refusal};

/// The flows' format: filterable, and small enough that colour and two
/// flows fit the default attachment budget.
pub const FLOW_FORMAT: TextureFormat = TextureFormat::Rgba16Float;

/// The I-frame helpers (`shaders/iframe.wgsl`).
const IFRAME_WGSL: &str = include_str!("../../shaders/iframe.wgsl");

/// The scene-assisted B-frame helpers (`shaders/bframe_scene.wgsl`).
const BFRAME_SCENE_WGSL: &str = include_str!("../../shaders/bframe_scene.wgsl");

/// The fragment entry point of the scene-assisted B-frame pass.
pub const SCENE_ASSISTED_ENTRY: &str = "fs_scene_assisted";

/// The decisions' format in the scene-assisted pass (as the fullscreen
/// B-frame passes').
pub const DECISION_FORMAT: TextureFormat = TextureFormat::R32Uint;

/// How a scene-assisted B-frame treats what neither I-frame shows
/// (`SceneParams::mode` in `shaders/bframe_scene.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneMode {
    /// The nearer of the two I-frames' colours (the paper's choice).
    ClosestOnMiss = 0,
    /// Shaded by the original fragment stage in a second pass.
    ShadeOnMiss = 1,
    /// A baseline: I-frame 0 alone, its colour kept even where the point
    /// is not visible there (no reshading).
    ReverseReprojection = 2,
    /// A measurement, not a method: each pixel's exact correspondence in
    /// I-frame 0, as (p − p₀, seen there, 1) in the colour output, for
    /// the image-based search's correspondence error.
    Correspondence = 3,
    /// Not a B-frame: the moving objects alone (the host draws no other)
    /// at the B-frame's time, each pixel's offset from I-frame 0 as
    /// (p − p₀, 0, 1) where no still surface hides it, 0 elsewhere: seed
    /// 003's dynamic-object velocity, its w the dynamic-object mask.
    MovingObjects = 4,
    /// I-frame 0 alone where it shows the point; elsewhere shaded by the
    /// original fragment stage in a second pass (seed 000's baseline,
    /// reverse reprojection with reshading, Figs. 7–10).
    ReverseReprojectionReshade = 5,
}

impl SceneMode {
    /// Whether the pass writes offsets, not colours (its colour target is
    /// then `rgba16float`, whatever the user's colour format).
    fn writes_offsets(self) -> bool {
        matches!(self, SceneMode::Correspondence | SceneMode::MovingObjects)
    }

    /// Whether the pass discards what a second pass of the original
    /// fragment stage shades.
    pub fn reshades(self) -> bool {
        matches!(
            self,
            SceneMode::ShadeOnMiss | SceneMode::ReverseReprojectionReshade
        )
    }
}

/// The I-frame pass's module, its WGSL and its plan, and which bindings
/// the host fills with which time's contents.
#[derive(Debug)]
pub struct IFrameShader {
    /// The module, for the tests that check it on IR.
    #[cfg(test)]
    pub module: Module,
    pub text: String,
    /// One geometry pass: the user's colour targets, then `flow_previous`
    /// and `flow_next`.
    pub plan: Plan,
    /// Locations of `flow_previous` and `flow_next`.
    pub flow_locations: [u32; 2],
    /// `[group, binding]` of the flow parameters (`FlowParams`).
    pub params: [u32; 2],
    /// (original, previous I-frame's twin) `[group, binding]`s.
    pub previous: Vec<([u32; 2], [u32; 2])>,
    /// (original, next I-frame's twin) `[group, binding]`s.
    pub next: Vec<([u32; 2], [u32; 2])>,
    /// The per-instance vertex inputs the position reads, twinned for the
    /// previous and the next I-frame: inputs of the plan's vertex layout
    /// like the others, which the host fills with those times' values.
    pub instance_twins: Vec<InstanceTwin>,
    /// The bind group of the scene-assisted pass's I-frame textures
    /// (`shaders/bframe_scene.wgsl`'s resources, from binding 0): the one
    /// after the twins', the fifth when the shader uses four.
    pub scene_group: u32,
    /// The scene-assisted pass's outputs: colour at the user's first
    /// colour location, decisions after the user's outputs.
    pub scene_locations: [u32; 2],
    /// Resources of the scene-assisted pass and of the original fragment
    /// entry point (`<entry>_original`), with the vertex stage's.
    scene_bindings: Vec<crate::plan::Resource>,
    original_entry: String,
}

/// A per-instance vertex input's twin at another I-frame's time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InstanceTwin {
    /// 0 for the previous I-frame, 1 for the next.
    pub time: usize,
    /// The location of the input it twins.
    pub of: u32,
    /// Its own location.
    pub location: u32,
}

/// `shaders/iframe.wgsl` parsed, once per process.
fn iframe_helpers() -> Result<&'static Module, Refusal> {
    static HELPERS: OnceLock<Result<Module, String>> = OnceLock::new();
    rewrite::toolchain_module(&HELPERS, "shaders/iframe.wgsl", IFRAME_WGSL)
}

/// `shaders/bframe_scene.wgsl` parsed, once per process.
fn scene_helpers() -> Result<&'static Module, Refusal> {
    static HELPERS: OnceLock<Result<Module, String>> = OnceLock::new();
    rewrite::toolchain_module(&HELPERS, "shaders/bframe_scene.wgsl", BFRAME_SCENE_WGSL)
}

/// Instruments `shader`'s fragment entry point (the analysis's) and the
/// vertex entry point that draws with it into the I-frame pass. The
/// per-instance vertex inputs the position reads get a twin input per
/// other I-frame, which must fit in `max_vertex_attributes` (the device's)
/// with the shader's own.
pub fn instrument(
    shader: &Shader,
    analysis: &Analysis,
    options: &Options,
    max_vertex_attributes: u32,
) -> Result<IFrameShader, Refusal> {
    let original = &shader.module;
    let entry_index = analysis.entry_index;
    let entry = original.entry_points[entry_index].clone();
    let (result, vertex_index) = instrumentable(original, &entry, entry_index, options)?;
    let slot = CacheSlot::for_module(original, options.max_bind_groups);
    let mut module = original.clone();
    let (flow_to, params_global) = import_helpers(&mut module, slot)?;

    // The twins follow the flow parameters: the previous I-frame's, then
    // the next one's.
    let twinned = vertex::twinned(&module, vertex_index).len() as u32;
    let first = slot.first_binding + 1;
    let times = [
        TwinTime {
            name: "previous",
            group: slot.group,
            first_binding: first,
            own_previous: false,
        },
        TwinTime {
            name: "next",
            group: slot.group,
            first_binding: first + twinned,
            own_previous: false,
        },
    ];
    let stage = vertex::instrument_times(
        &mut module,
        vertex_index,
        &times,
        max_vertex_attributes,
        &[],
    )?;
    let instance_twins: Vec<InstanceTwin> = stage
        .instance_twins
        .iter()
        .enumerate()
        .flat_map(|(time, twins)| {
            twins
                .iter()
                .map(move |&(of, location)| InstanceTwin { time, of, location })
        })
        .collect();
    rewrite::mark_positions_invariant(&mut module);
    let locations = [stage.times[0].location, stage.times[1].location];
    let flow_locations = flow_entry(
        &mut module,
        entry_index,
        &entry,
        &result,
        locations,
        flow_to,
    )?;

    // The scene-assisted pass, and the original fragment stage for its
    // shade-on-miss pass. The I-frames' textures take the group after the
    // twins': past WebGPU's default four when the shader uses them all
    // (engines do), which needs an adapter that grants more (the
    // interpolation runtime asks for what the adapter grants).
    let color_location = rewrite::fragment::output_locations(original, &result)
        .first()
        .copied()
        .unwrap_or(0);
    let scene_locations = [color_location, flow_locations[0]];
    let original_entry = format!("{}_original", entry.name);
    let scene_group = slot.group + 1;
    scene_entry(&mut module, locations, scene_locations, scene_group)?;
    module.entry_points.push(naga::EntryPoint {
        name: original_entry.clone(),
        ..entry.clone()
    });

    let info = crate::front::validate(&module)
        .map_err(|err| Refusal::internal(format!("the I-frame pass does not validate: {err}")))?;
    let text = crate::back::wgsl_text(&module, &info).map_err(Refusal::internal)?;
    let plan = plan(
        shader,
        analysis,
        options,
        &module,
        (entry_index, vertex_index),
        flow_locations,
        (&instance_twins, &times),
    )
    .map_err(Refusal::internal)?;
    let scene_bindings = {
        let entries: Vec<usize> = module
            .entry_points
            .iter()
            .enumerate()
            .filter(|(_, e)| e.name == SCENE_ASSISTED_ENTRY || e.name == original_entry)
            .map(|(i, _)| i)
            .chain([vertex_index])
            .collect();
        rewrite::plan::entry_resources(&module, &entries)
    };
    let pairs = |i: usize| -> Result<Vec<TwinPair>, Refusal> {
        stage.times[i]
            .twins
            .iter()
            .map(|&(from, to)| Ok((binding_key(&module, from)?, binding_key(&module, to)?)))
            .collect()
    };
    Ok(IFrameShader {
        scene_group,
        scene_locations,
        scene_bindings,
        original_entry,
        params: binding_key(&module, params_global)?,
        previous: pairs(0)?,
        next: pairs(1)?,
        instance_twins,
        plan,
        flow_locations,
        text,
        #[cfg(test)]
        module,
    })
}

/// A twin's (group, binding) and the (group, binding) of what it shadows.
type TwinPair = ([u32; 2], [u32; 2]);

/// The fragment entry point's result and the vertex entry point drawing
/// with it, or why the I-frame pass cannot be made of them.
fn instrumentable(
    original: &naga::Module,
    entry: &naga::EntryPoint,
    entry_index: usize,
    options: &Options,
) -> Result<(naga::FunctionResult, usize), Refusal> {
    let Some(result) = entry.function.result.clone() else {
        return Err(Refusal::new("the fragment entry point returns nothing"));
    };
    if rewrite::writes_frag_depth(original, &result) {
        return Err(Refusal::new(
            "the fragment stage writes @builtin(frag_depth); the flows are taken at the rasterised depth",
        ));
    }
    if vertex::is_fragment_only(original) && options.vertex_entry.is_none() {
        return Err(Refusal::new(
            "the module has no vertex stage whose position could be computed at the previous and next I-frames; give it with --vertex",
        ));
    }
    let vertex_index =
        vertex::vertex_entry(original, entry_index, options.vertex_entry.as_deref())?;
    Ok((result, vertex_index))
}

/// Imports the I-frame helpers (`shaders/iframe.wgsl`) into `module` at
/// `slot`: the flow function and the flow parameters' global.
fn import_helpers(
    module: &mut naga::Module,
    slot: CacheSlot,
) -> Result<(Handle<naga::Function>, Handle<naga::GlobalVariable>), Refusal> {
    let imported =
        crate::proc::import::import(module, iframe_helpers()?, slot.group, slot.first_binding)
            .map_err(|err| Refusal::internal(format!("importing the I-frame helpers: {err}")))?;
    let flow_to = *imported
        .functions
        .get("flow_to")
        .ok_or_else(|| Refusal::internal("`flow_to` missing from the I-frame helpers"))?;
    let params_global = *imported
        .globals
        .get("flow_params")
        .ok_or_else(|| Refusal::internal("`flow_params` missing from the I-frame helpers"))?;
    Ok((flow_to, params_global))
}

/// The (group, binding) of a global the pass binds: a twin, what it
/// shadows, or the flow parameters.
fn binding_key(
    module: &naga::Module,
    global: Handle<naga::GlobalVariable>,
) -> Result<[u32; 2], Refusal> {
    let binding = module.global_variables[global]
        .binding
        .as_ref()
        .ok_or_else(|| Refusal::internal("a twin or the resource it shadows is not bound"))?;
    Ok([binding.group, binding.binding])
}

/// Where the fragment entry point reads `@builtin(position)`.
enum FragCoord {
    /// Argument `i` is the position.
    Argument(u32),
    /// Member `m` of struct argument `i` is.
    Member(u32, u32),
    /// Neither: the new entry point adds it as its last argument.
    Added,
}

fn frag_coord(module: &Module, function: &Function) -> FragCoord {
    for (i, argument) in function.arguments.iter().enumerate() {
        if rewrite::fragment::is_position(&argument.binding) {
            return FragCoord::Argument(i as u32);
        }
        if let TypeInner::Struct { ref members, .. } = module.types[argument.ty].inner {
            if let Some(m) = members
                .iter()
                .position(|m| rewrite::fragment::is_position(&m.binding))
            {
                return FragCoord::Member(i as u32, m as u32);
            }
        }
    }
    FragCoord::Added
}

/// Replaces the fragment entry point with one that calls the original as
/// `<entry>_shade` and adds the two flows to its outputs; returns their
/// locations. `clip_locations` are where the vertex stage outputs the
/// previous and the next clip position.
fn flow_entry(
    module: &mut Module,
    entry_index: usize,
    entry: &naga::EntryPoint,
    result: &naga::FunctionResult,
    clip_locations: [u32; 2],
    flow_to: Handle<Function>,
) -> Result<[u32; 2], Refusal> {
    let function = &entry.function;
    let mut all = ExprSet::with_capacity(function.expressions.len());
    all.insert_range(..);
    let shade = FunctionCopy::new(
        module,
        function,
        &all,
        Function {
            name: Some(format!("{}_shade", entry.name)),
            arguments: rewrite::without_bindings(&function.arguments),
            result: Some(naga::FunctionResult {
                ty: result.ty,
                binding: None,
            }),
            ..Function::default()
        },
    )
    .run();
    let shade = module.functions.append(shade, naga::Span::UNDEFINED);
    let vec4 = builder::vec4_type(module);

    // The output: the user's members (or its one output), then the flows.
    let (mut members, span, is_struct) = match module.types[result.ty].inner {
        TypeInner::Struct { ref members, span } => (members.clone(), span, true),
        _ => (
            vec![naga::StructMember {
                name: Some("color".into()),
                ty: result.ty,
                binding: result.binding.clone(),
                offset: 0,
            }],
            16,
            false,
        ),
    };
    let user_members = members.len() as u32;
    let first_flow = rewrite::fragment::output_locations(module, result)
        .into_iter()
        .map(|l| l + 1)
        .max()
        .unwrap_or(0);
    let flow_locations = [first_flow, first_flow + 1];
    let mut offset = span.div_ceil(16) * 16;
    for (name, location) in ["flow_previous", "flow_next"]
        .into_iter()
        .zip(flow_locations)
    {
        members.push(naga::StructMember {
            name: Some(name.into()),
            ty: vec4,
            binding: Some(builder::location(location)),
            offset,
        });
        offset += 16;
    }
    let output = module.types.insert(
        naga::Type {
            name: Some(format!("{}IFrameOutput", crate::proc::pascal(&entry.name))),
            inner: TypeInner::Struct {
                members,
                span: offset,
            },
        },
        naga::Span::UNDEFINED,
    );

    let coord = frag_coord(module, function);
    let mut arguments = function.arguments.clone();
    if let FragCoord::Added = coord {
        arguments.push(naga::FunctionArgument {
            name: Some("frag_coord".into()),
            ty: vec4,
            binding: Some(Binding::BuiltIn(BuiltIn::Position { invariant: true })),
        });
    }
    for (name, location) in ["previous_clip_position", "next_clip_position"]
        .into_iter()
        .zip(clip_locations)
    {
        arguments.push(naga::FunctionArgument {
            name: Some(name.into()),
            ty: vec4,
            binding: Some(builder::perspective_location(location)),
        });
    }
    let count = function.arguments.len() as u32;
    let mut b = Builder::new(Function {
        name: function.name.clone(),
        arguments: arguments.clone(),
        result: Some(naga::FunctionResult {
            ty: output,
            binding: None,
        }),
        ..Function::default()
    });
    let originals: Vec<_> = (0..count).map(|i| b.argument(i)).collect();
    let shaded = b.call(shade, originals.clone());
    let position = match coord {
        FragCoord::Argument(i) => originals[i as usize],
        FragCoord::Member(i, m) => b.member(originals[i as usize], m),
        FragCoord::Added => b.argument(count),
    };
    let clips = arguments.len() as u32 - 2;
    let previous = b.argument(clips);
    let next = b.argument(clips + 1);
    let flow_previous = b.call(flow_to, vec![position, previous]);
    let flow_next = b.call(flow_to, vec![position, next]);
    let mut components: Vec<_> = if is_struct {
        (0..user_members).map(|m| b.member(shaded, m)).collect()
    } else {
        vec![shaded]
    };
    components.extend([flow_previous, flow_next]);
    let value = b.expr(Expression::Compose {
        ty: output,
        components,
    });
    b.push(Statement::Return { value: Some(value) });
    module.entry_points[entry_index].function = b.finish();
    Ok(flow_locations)
}

/// Adds the scene-assisted B-frame's fragment entry point: the previous
/// and next clip positions in (at `clip_locations`), the colour the
/// I-frames give (`scene_assisted` of `shaders/bframe_scene.wgsl`,
/// imported with its resources in `group`) and the decision out, at
/// `locations`.
fn scene_entry(
    module: &mut Module,
    clip_locations: [u32; 2],
    locations: [u32; 2],
    group: u32,
) -> Result<(), Refusal> {
    let imported = crate::proc::import::import(module, scene_helpers()?, group, 0)
        .map_err(|err| Refusal::internal(format!("importing the scene-assisted helpers: {err}")))?;
    let helper = *imported.functions.get("scene_assisted").ok_or_else(|| {
        Refusal::internal("`scene_assisted` missing from the scene-assisted helpers")
    })?;
    let vec4 = builder::vec4_type(module);
    let u32_ty = builder::scalar_type(module, naga::Scalar::U32);
    let output = module.types.insert(
        naga::Type {
            name: Some("SceneAssistedOutput".into()),
            inner: TypeInner::Struct {
                members: vec![
                    naga::StructMember {
                        name: Some("color".into()),
                        ty: vec4,
                        binding: Some(builder::location(locations[0])),
                        offset: 0,
                    },
                    naga::StructMember {
                        name: Some("decision".into()),
                        ty: u32_ty,
                        binding: Some(builder::location(locations[1])),
                        offset: 16,
                    },
                ],
                span: 32,
            },
        },
        naga::Span::UNDEFINED,
    );
    let mut arguments = vec![naga::FunctionArgument {
        name: Some("frag_coord".into()),
        ty: vec4,
        binding: Some(Binding::BuiltIn(BuiltIn::Position { invariant: true })),
    }];
    arguments.extend(
        ["previous_clip_position", "next_clip_position"]
            .into_iter()
            .zip(clip_locations)
            .map(|(name, location)| naga::FunctionArgument {
                name: Some(name.into()),
                ty: vec4,
                binding: Some(builder::perspective_location(location)),
            }),
    );
    let mut b = Builder::new(Function {
        name: Some(SCENE_ASSISTED_ENTRY.into()),
        arguments,
        result: Some(naga::FunctionResult {
            ty: output,
            binding: None,
        }),
        ..Function::default()
    });
    let (frag_coord, previous, next) = (b.argument(0), b.argument(1), b.argument(2));
    let found = b.call(helper, vec![frag_coord, previous, next]);
    let components = vec![b.member(found, 0), b.member(found, 1)];
    let value = b.expr(Expression::Compose {
        ty: output,
        components,
    });
    b.push(Statement::Return { value: Some(value) });
    module.entry_points.push(builder::entry_point(
        SCENE_ASSISTED_ENTRY,
        naga::ShaderStage::Fragment,
        b.finish(),
    ));
    Ok(())
}

impl IFrameShader {
    /// One object's per-instance records for the I-frame's vertex layout,
    /// from its records as the layout without twins packs them at three
    /// times (`records`: now, the previous I-frame, the next): each input
    /// now, each twin its input's value at its time. No instance is
    /// simulated again; the twins' bytes are the other times' own.
    pub fn instance_records(&self, records: [&[u8]; 3]) -> Result<Vec<u8>, String> {
        let size = |a: &crate::plan::VertexAttribute| {
            shadecache_host::toolchain::vertex_format(a.format).size() as usize
        };
        let packed: Vec<&crate::plan::VertexAttribute> = self
            .plan
            .vertex_layout
            .iter()
            .filter(|a| a.step == crate::plan::StepMode::Instance && a.previous_of.is_none())
            .collect();
        let twin = |location: u32| self.instance_twins.iter().find(|t| t.location == location);
        // Where each input is in a record without the twins.
        let mut offsets = std::collections::HashMap::new();
        let mut stride = 0;
        for a in packed.iter().filter(|a| twin(a.location).is_none()) {
            offsets.insert(a.location, stride);
            stride += size(a);
        }
        if stride == 0 {
            return Ok(records[0].to_vec());
        }
        let count = records[0].len() / stride;
        if records.iter().any(|r| r.len() != count * stride) {
            return Err(format!(
                "internal error: per-instance records of {} bytes at the three times, not {count} of {stride}",
                records.map(<[u8]>::len).map(|n| n.to_string()).join(", ")
            ));
        }
        let mut out = Vec::new();
        for instance in 0..count {
            for a in &packed {
                let (time, of) = twin(a.location).map_or((0, a.location), |t| (t.time + 1, t.of));
                let start = instance * stride + offsets[&of];
                out.extend_from_slice(&records[time][start..start + size(a)]);
            }
        }
        Ok(out)
    }

    /// The scene-assisted B-frame's plan in `mode`: the geometry at the
    /// B-frame's time reprojected into both I-frames (its colour and
    /// decisions), and for shade-on-miss a second pass of the original
    /// fragment stage over what the first discarded (its depth test keeps
    /// to the pixels no earlier fragment covered).
    pub fn scene_plan(&self, mode: SceneMode) -> Result<Plan, String> {
        let group = self.scene_group;
        let mut plan = self.plan.clone();
        plan.bindings.original = self.scene_bindings.clone();
        let iframe = &self.plan.passes[0];
        let color_format = iframe
            .color_targets
            .iter()
            .find(|t| t.location == self.scene_locations[0] && !mode.writes_offsets())
            .map_or(TextureFormat::Rgba16Float, |t| t.format);
        let pass_bindings = |group_too: bool| -> Vec<[u32; 2]> {
            let mut keys: Vec<[u32; 2]> = self
                .scene_bindings
                .iter()
                .filter(|r| group_too || r.group != group)
                .map(|r| [r.group, r.binding])
                .collect();
            keys.sort();
            keys.dedup();
            keys
        };
        let mut passes = vec![crate::plan::Pass {
            name: "scene".into(),
            role: "the geometry at the B-frame's time, coloured from the I-frames where its points are visible there".into(),
            fragment_entry: SCENE_ASSISTED_ENTRY.into(),
            color_targets: vec![
                ColorTarget {
                    location: self.scene_locations[0],
                    target: TargetKind::Color,
                    format: color_format,
                    load: LoadOp::Clear,
                },
                ColorTarget {
                    location: self.scene_locations[1],
                    target: TargetKind::Color,
                    format: DECISION_FORMAT,
                    load: LoadOp::Clear,
                },
            ],
            discards: mode.reshades() || mode == SceneMode::MovingObjects,
            bindings: pass_bindings(true),
            ..iframe.clone()
        }];
        if mode.reshades() {
            let mut shade = iframe.clone();
            shade.name = "shade".into();
            shade.role = if mode == SceneMode::ShadeOnMiss {
                "the original fragment stage where neither I-frame shows the surface"
            } else {
                "the original fragment stage where I-frame 0 does not show the surface"
            }
            .into();
            shade.fragment_entry = self.original_entry.clone();
            shade
                .color_targets
                .retain(|t| !self.flow_locations.contains(&t.location));
            for target in &mut shade.color_targets {
                target.load = LoadOp::Load;
            }
            shade.depth.load = LoadOp::Load;
            shade.bindings = pass_bindings(false);
            passes.push(shade);
        }
        plan.passes = passes;
        Ok(plan)
    }
}

/// The I-frame pass's plan: the reference's, with the flows among its
/// targets and every resource the instrumented entry points read (the
/// flow parameters and the twins with the user's).
fn plan(
    shader: &Shader,
    analysis: &Analysis,
    options: &Options,
    module: &Module,
    (fragment, vertex): (usize, usize),
    flow_locations: [u32; 2],
    (instance_twins, times): (&[InstanceTwin], &[TwinTime]),
) -> Result<Plan, String> {
    let mut plan = rewrite::plan::reference(shader, analysis, options)?;
    // The per-instance inputs' twins: inputs like the others (not the
    // host's copies of last frame's), which the run fills with the other
    // I-frames' values.
    for twin in instance_twins {
        let input = plan
            .vertex_layout
            .iter()
            .find(|a| a.location == twin.of)
            .cloned()
            .ok_or_else(|| format!("no vertex input at @location({}) to twin", twin.of))?;
        plan.vertex_layout.push(crate::plan::VertexAttribute {
            location: twin.location,
            name: format!("{}_{}", times[twin.time].name, input.name),
            ..input
        });
    }
    plan.vertex_layout.sort_by_key(|a| a.location);
    let original = rewrite::plan::entry_resources(module, &[fragment, vertex]);
    let mut bindings: Vec<[u32; 2]> = original.iter().map(|r| [r.group, r.binding]).collect();
    bindings.sort();
    bindings.dedup();
    plan.bindings.original = original;
    // Where nothing is drawn the flows must read invalid (w = 0): every
    // target clears to zero, the colour's alpha too.
    plan.clear.color = [0.0; 4];
    let pass = &mut plan.passes[0];
    pass.name = "iframe".into();
    pass.role = "the shader as written, plus the flows to the previous and the next I-frame".into();
    pass.shader = "iframe.wgsl".into();
    pass.bindings = bindings;
    pass.color_targets
        .extend(flow_locations.into_iter().map(|location| ColorTarget {
            location,
            target: TargetKind::Color,
            format: FLOW_FORMAT,
            load: LoadOp::Clear,
        }));
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn instrumented(source: &str) -> IFrameShader {
        let shader = crate::front::parse(crate::diagnostic::SourceFile::new("test.wgsl", source))
            .expect("parses");
        let analysis = crate::analysis::analyze(&shader, &Default::default()).expect("analyses");
        instrument(&shader, &analysis, &Options::default(), 16).expect("instruments")
    }

    #[test]
    fn iframe_pass_outputs_both_flows_after_the_users_outputs() {
        let iframe = instrumented(include_str!("../../corpus/noise_marble.wgsl"));
        assert_eq!(iframe.flow_locations, [1, 2]);
        // Frame's uniform at group 0: the flow parameters and its two
        // twins in the first free group.
        assert_eq!(iframe.params, [1, 0]);
        assert_eq!(iframe.previous, vec![([0, 0], [1, 1])]);
        assert_eq!(iframe.next, vec![([0, 0], [1, 2])]);
        assert!(iframe.text.contains("fn vs_main_previous("));
        assert!(iframe.text.contains("fn vs_main_next("));
        assert!(iframe.text.contains("flow_to("));
        let targets = &iframe.plan.passes[0].color_targets;
        assert_eq!(targets.len(), 3);
        assert_eq!(targets[2].format, FLOW_FORMAT);
    }
}

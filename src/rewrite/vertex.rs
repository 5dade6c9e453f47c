//! The vertex stage of every variant: the original position computation,
//! marked `@invariant`, plus the same computation evaluated with last
//! frame's resources — the previous clip position the fragment stage
//! reprojects with.
//!
//! Nothing about the user's matrices is assumed. Every uniform and
//! read-only storage buffer the vertex entry point reads, directly or
//! through helper functions, gets a *previous-frame twin*: a new binding of
//! the same type that the host fills with last frame's contents. For the
//! cache (last frame), two kinds need none ([`super::member_twins`]): one
//! the position does not read (only other outputs do), and one that keeps
//! last frame's values in `previous_` siblings of what the position reads. The whole
//! vertex function is copied twice into helper functions — once as it is,
//! once reading the twins — and the new entry point calls both, so the
//! position is computed by identical code in every pass.

use std::collections::{BTreeSet, HashMap};

use naga::{Binding, BuiltIn, Expression, Function, Handle, Module, Statement, TypeInner};

use super::builder::Builder;
use super::copy::FunctionCopy;
use super::fragment::is_position;
use super::member_twins::{self, MemberTwin};
use super::Refusal;
use crate::analysis::graph::ExprSet;

/// What instrumenting the vertex stage produced.
#[derive(Debug)]
pub(crate) struct VertexStage {
    /// Index of the vertex entry point in the module; `None` for a
    /// fragment-only module, whose host's vertex stage must output the
    /// previous clip position ([`fragment_only`]).
    pub entry_index: Option<usize>,
    /// Location of the interpolated previous clip position.
    pub previous_location: u32,
    /// (original, twin) global variables.
    pub twins: Vec<(Handle<naga::GlobalVariable>, Handle<naga::GlobalVariable>)>,
    /// Resources whose last-frame values are their own `previous_`
    /// members, which the previous position reads instead of a twin
    /// ([`super::member_twins`]).
    pub member_twins: Vec<MemberTwin>,
    /// (input's location, twin's location) of each vertex input the
    /// position reads that changes between frames (per-instance inputs,
    /// and per-vertex ones the application deforms): the new entry point
    /// takes last frame's value of it at the twin's location.
    pub instance_twins: Vec<(u32, u32)>,
    /// The entry point's function for the passes that do not reproject:
    /// the original inputs and outputs, the same position helper (so
    /// depth tests between passes stay exact), no previous clip position.
    pub plain: Option<Function>,
}

/// WebGPU's default `maxVertexAttributes`: inputs and their twins must fit
/// in locations 0 to 15.
const MAX_VERTEX_ATTRIBUTES: u32 = 16;

/// A vertex input the position reads that changes between frames (per
/// instance, or deformed by the application): its argument, the member
/// within it for a struct argument, its location and type.
#[derive(Clone, Copy, Debug)]
struct InstanceInput {
    argument: u32,
    member: Option<u32>,
    location: u32,
    ty: Handle<naga::Type>,
}

/// The per-instance inputs of the vertex entry point `function` that its
/// position output (`position_member` of its result struct, or the result
/// itself) depends on: only those need last frame's value. A struct
/// argument the position uses whole counts with every member.
fn instance_inputs_of_position(
    module: &Module,
    function: &Function,
    position_member: Option<u32>,
    deforming: &[u32],
) -> Vec<InstanceInput> {
    let mut per_instance = crate::proc::instance_locations(module, function);
    per_instance.extend(deforming.iter().copied());
    if per_instance.is_empty() {
        return Vec::new();
    }
    let layout = crate::proc::layout(module, function, 8.0);
    let graph = crate::analysis::graph::ExprGraph::new(function, &layout);
    let mut slice = ExprSet::with_capacity(function.expressions.len());
    for value in crate::proc::output_values(function, &layout, position_member) {
        slice.union_with(&graph.slice(value));
    }
    let (whole, struct_members) = arguments_read(module, function, &slice);
    let mut out = Vec::new();
    for (i, argument) in function.arguments.iter().enumerate() {
        let i = i as u32;
        let mut add = |member: Option<u32>, binding: &Option<Binding>, ty| {
            if let Some(location) =
                crate::proc::location_of(binding).filter(|l| per_instance.contains(l))
            {
                out.push(InstanceInput {
                    argument: i,
                    member,
                    location,
                    ty,
                });
            }
        };
        match module.types[argument.ty].inner {
            TypeInner::Struct { ref members, .. } => {
                for (m, member) in members.iter().enumerate() {
                    let m = m as u32;
                    if whole.contains(&i) || struct_members.contains(&(i, m)) {
                        add(Some(m), &member.binding, member.ty);
                    }
                }
            }
            _ if whole.contains(&i) => add(None, &argument.binding, argument.ty),
            _ => {}
        }
    }
    out
}

/// Which arguments a set of expressions reads: whole (`.0`), or only some
/// members of a struct argument (`.1`, as (argument, member)).
fn arguments_read(
    module: &Module,
    function: &Function,
    set: &ExprSet,
) -> (BTreeSet<u32>, BTreeSet<(u32, u32)>) {
    let exprs = &function.expressions;
    let mut whole = BTreeSet::new();
    let mut members = BTreeSet::new();
    for (handle, expr) in exprs.iter() {
        if !set.contains(handle.index()) {
            continue;
        }
        for operand in crate::proc::operands(expr) {
            if let Expression::FunctionArgument(argument) = exprs[operand] {
                match *expr {
                    Expression::AccessIndex { index, .. } => {
                        members.insert((argument, index));
                    }
                    _ => {
                        whole.insert(argument);
                    }
                }
            }
        }
        if let Expression::FunctionArgument(argument) = *expr {
            let ty = function.arguments[argument as usize].ty;
            if !matches!(module.types[ty].inner, TypeInner::Struct { .. }) {
                whole.insert(argument);
            }
        }
    }
    (whole, members)
}

/// The vertex entry point that draws with the fragment entry point at
/// `fragment` ([`crate::proc::vertex_entry`]), or the refusal saying why
/// none does.
pub(crate) fn vertex_entry(
    module: &Module,
    fragment: usize,
    wanted: Option<&str>,
) -> Result<usize, Refusal> {
    crate::proc::vertex_entry(module, fragment, wanted).map_err(Refusal::new)
}

/// Adds the previous clip position to the vertex entry point at
/// `entry_index`, with twins of its resources in bind group `group` from
/// binding `first_binding` on.
///
/// `deforming` names per-vertex inputs the application changes between
/// frames: those the position reads get a twin input as per-instance ones
/// do. A name no input of the entry point has is a refusal.
pub(crate) fn instrument(
    module: &mut Module,
    entry_index: usize,
    (group, first_binding): (u32, u32),
    deforming: &[String],
) -> Result<VertexStage, Refusal> {
    let previous = TwinTime {
        name: "previous",
        group,
        first_binding,
        own_previous: true,
    };
    let deforming = input_locations(module, entry_index, deforming)?;
    let mut stage = instrument_times(
        module,
        entry_index,
        &[previous],
        MAX_VERTEX_ATTRIBUTES,
        &deforming,
    )?;
    let TimedPosition {
        location,
        twins,
        member_twins,
    } = stage.times.remove(0);
    Ok(VertexStage {
        entry_index: Some(entry_index),
        previous_location: location,
        twins,
        member_twins,
        instance_twins: stage.instance_twins.remove(0),
        plain: Some(stage.plain),
    })
}

/// The locations of the vertex entry point's inputs named `names`.
fn input_locations(
    module: &Module,
    entry_index: usize,
    names: &[String],
) -> Result<Vec<u32>, Refusal> {
    let function = &module.entry_points[entry_index].function;
    let inputs = crate::proc::inputs(module, function);
    names
        .iter()
        .map(|name| {
            inputs
                .iter()
                .find(|input| input.name == Some(name))
                .and_then(|input| crate::proc::location_of(input.binding))
                .ok_or_else(|| {
                    let known: Vec<&str> = inputs
                        .iter()
                        .filter(|i| crate::proc::location_of(i.binding).is_some())
                        .filter_map(|i| i.name.map(String::as_str))
                        .collect();
                    Refusal::new(format!(
                        "no vertex input is named `{name}` (the vertex entry point `{}` has {})",
                        module.entry_points[entry_index].name,
                        known.join(", ")
                    ))
                })
        })
        .collect()
}

/// One other time the position is computed at: `<name>_clip_position`
/// from twins `<name>_<resource>` bound in `group` from `first_binding`
/// on, which the host fills with that time's contents (last frame's for
/// the cache; the previous and the next I-frame's for whole-frame reuse).
#[derive(Clone, Copy, Debug)]
pub(crate) struct TwinTime {
    pub name: &'static str,
    pub group: u32,
    pub first_binding: u32,
    /// Whether a resource's own `previous_` members hold this time's
    /// values ([`super::member_twins`]): last frame's, for the cache; not
    /// an I-frame's several frames back.
    pub own_previous: bool,
}

/// The position at one [`TwinTime`]: the output's location and the
/// (original, twin) resources it reads.
#[derive(Debug)]
pub(crate) struct TimedPosition {
    pub location: u32,
    pub twins: Vec<(Handle<naga::GlobalVariable>, Handle<naga::GlobalVariable>)>,
    /// The resources read through their own `previous_` members instead.
    pub member_twins: Vec<MemberTwin>,
}

/// What [`instrument_times`] made of the vertex entry point.
#[derive(Debug)]
pub(crate) struct TimedVertexStage {
    /// One per time asked for, in order, at consecutive locations.
    pub times: Vec<TimedPosition>,
    /// As [`VertexStage::instance_twins`], one list per time asked for.
    pub instance_twins: Vec<Vec<(u32, u32)>>,
    /// As [`VertexStage::plain`].
    pub plain: Function,
}

/// Adds the clip position at each of `times` to the vertex entry point at
/// `entry_index`. Per-instance vertex inputs the position reads get a twin
/// input per time (`<time>_<input>`, at free locations below
/// `max_vertex_attributes`), which the host fills with that time's values;
/// a refusal when they do not fit.
pub(crate) fn instrument_times(
    module: &mut Module,
    entry_index: usize,
    times: &[TwinTime],
    max_vertex_attributes: u32,
    deforming: &[u32],
) -> Result<TimedVertexStage, Refusal> {
    let entry = module.entry_points[entry_index].clone();
    let function = &entry.function;
    let Some(result) = function.result.clone() else {
        return Err(Refusal::new("the vertex entry point returns nothing"));
    };

    // Where the position is in the result.
    let members = match module.types[result.ty].inner {
        TypeInner::Struct { ref members, span } => Some((members.clone(), span)),
        _ => None,
    };
    let position_member = position_member(&members, &result)?;

    // Per-instance inputs the position reads, each with a twin input at a
    // free location that carries last frame's value.
    let instance_inputs = instance_inputs_of_position(module, function, position_member, deforming);
    let instance_twins = twin_locations(
        module,
        function,
        &instance_inputs,
        times.len(),
        max_vertex_attributes,
    )?;

    // The resources the entry point reads: the twins added below are not
    // among them, so this holds for every time.
    let candidates = twinned(module, entry_index);
    let mut twins_per_time = Vec::new();
    let mut twin_maps = Vec::new();
    for time in times {
        let reads = match time.own_previous {
            true => member_twins::position_reads(module, entry_index, position_member, &candidates),
            false => member_twins::PositionReads::default(),
        };
        let twins = twin_resources(module, time, &candidates, &reads);
        let members = reads.members;
        let twin_map: GlobalTwins = twins.iter().copied().collect();
        let function_twins = twin_helpers(module, function, (&twin_map, &members), time.name);
        twins_per_time.push(twins);
        twin_maps.push(TimeTwins {
            time: time.name,
            globals: twin_map,
            members,
            functions: function_twins,
        });
    }
    let helpers = PositionHelpers::add(
        module,
        (&entry.name, function),
        result.ty,
        &twin_maps,
        position_member,
    );
    let names: Vec<&str> = times.iter().map(|t| t.name).collect();
    let (output, locations) =
        timed_output(module, members, &result, helpers.vec4, &entry.name, &names);

    // The new entry point: call the current and each other time's,
    // forward every member, add the other positions.
    let mut entry_arguments = function.arguments.clone();
    for (time, twins) in times.iter().zip(&instance_twins) {
        entry_arguments.extend(twin_arguments(
            module,
            function,
            &instance_inputs,
            (time.name, twins),
        ));
    }
    let mut b = Builder::new(Function {
        name: function.name.clone(),
        arguments: entry_arguments,
        result: Some(naga::FunctionResult {
            ty: output.ty,
            binding: None,
        }),
        ..Function::default()
    });
    let arguments: Vec<_> = (0..function.arguments.len() as u32)
        .map(|i| b.argument(i))
        .collect();
    let now = b.call(helpers.current, arguments.clone());
    let mut others = Vec::new();
    for (i, &helper) in helpers.others.iter().enumerate() {
        // The entry point's arguments after the original ones: each
        // time's twins in turn.
        let first_twin = (function.arguments.len() + i * instance_inputs.len()) as u32;
        let other_arguments = other_time_arguments(
            module,
            function,
            &mut b,
            arguments.clone(),
            (&instance_inputs, first_twin),
        );
        others.push(b.call(helper, other_arguments));
    }
    let mut components: Vec<_> = match position_member {
        Some(_) => (0..output.members - times.len() as u32)
            .map(|i| b.member(now, i))
            .collect(),
        None => vec![now],
    };
    components.extend(others);
    let value = b.expr(Expression::Compose {
        ty: output.ty,
        components,
    });
    b.push(Statement::Return { value: Some(value) });
    module.entry_points[entry_index].function = b.finish();

    Ok(TimedVertexStage {
        times: locations
            .into_iter()
            .zip(twins_per_time)
            .zip(twin_maps)
            .map(|((location, twins), time)| TimedPosition {
                location,
                twins,
                member_twins: time.members,
            })
            .collect(),
        instance_twins,
        plain: plain_entry(function, helpers.current),
    })
}

/// Each twinned resource's twin.
type GlobalTwins = HashMap<Handle<naga::GlobalVariable>, Handle<naga::GlobalVariable>>;
/// Each helper that reads a twinned resource, and its twin.
type FunctionTwins = HashMap<Handle<Function>, Handle<Function>>;

/// How the position at one other time reads that time's values.
struct TimeTwins {
    time: &'static str,
    globals: GlobalTwins,
    members: Vec<MemberTwin>,
    functions: FunctionTwins,
}

/// The result member that is `@builtin(position)`; `None` when the
/// result is the position itself.
fn position_member(
    members: &Option<(Vec<naga::StructMember>, u32)>,
    result: &naga::FunctionResult,
) -> Result<Option<u32>, Refusal> {
    let missing = || Refusal::new("the vertex entry point does not output @builtin(position)");
    match (members, is_position(&result.binding)) {
        (None, true) => Ok(None),
        (Some((members, _)), false) => members
            .iter()
            .position(|m| is_position(&m.binding))
            .map(|index| Some(index as u32))
            .ok_or_else(missing),
        _ => Err(missing()),
    }
}

/// A twin for `time` of each of `candidates` ([`twinned`]), the resources
/// the position computation may read (but those in `reads`: read through
/// their own previous values, or not by the position at all):
/// uniforms and read-only storage, in the entry point or any helper it
/// calls, bound in the time's group from its first binding on. (In handle
/// order, so twins get the same bindings on every run.)
fn twin_resources(
    module: &mut Module,
    time: &TwinTime,
    candidates: &[Handle<naga::GlobalVariable>],
    reads: &member_twins::PositionReads,
) -> Vec<(Handle<naga::GlobalVariable>, Handle<naga::GlobalVariable>)> {
    let mut twins = Vec::new();
    let own: Vec<_> = reads.members.iter().map(|m| m.global).collect();
    let needed = candidates
        .iter()
        .copied()
        .filter(|g| !own.contains(g) && !reads.unread.contains(g));
    for (binding, g) in (time.first_binding..).zip(needed) {
        let global = module.global_variables[g].clone();
        let twin = module.global_variables.append(
            naga::GlobalVariable {
                name: global.name.as_ref().map(|n| format!("{}_{n}", time.name)),
                binding: Some(naga::ResourceBinding {
                    group: time.group,
                    binding,
                }),
                ..global
            },
            naga::Span::UNDEFINED,
        );
        twins.push((g, twin));
    }
    twins
}

/// The resources the vertex entry point at `entry_index` reads that get
/// twins, in handle order: uniforms and read-only storage, read directly
/// or through helpers.
pub(crate) fn twinned(module: &Module, entry_index: usize) -> Vec<Handle<naga::GlobalVariable>> {
    let mut read: Vec<_> = crate::proc::globals_used_by(module, &[entry_index])
        .into_iter()
        .filter(|&g| match module.global_variables[g].space {
            naga::AddressSpace::Uniform => true,
            naga::AddressSpace::Storage { access } => !access.contains(naga::StorageAccess::STORE),
            _ => false,
        })
        .collect();
    read.sort();
    read
}

/// Twins (`<helper>_<time>`) of the helpers `function` calls that read a
/// twinned resource (directly or through their callees), callees first.
fn twin_helpers(
    module: &mut Module,
    function: &Function,
    (twin_map, members): (&GlobalTwins, &[MemberTwin]),
    time: &str,
) -> FunctionTwins {
    let mut reachable = Vec::new();
    crate::proc::collect_callees(module, &function.body, &mut reachable, &mut BTreeSet::new());
    let mut function_twins = FunctionTwins::new();
    for &f in &reachable {
        let source = module.functions[f].clone();
        let reads_twinned = source.expressions.iter().any(|(_, e)| {
            matches!(*e, Expression::GlobalVariable(g)
                if twin_map.contains_key(&g) || members.iter().any(|m| m.global == g))
        }) || calls_any(&source.body, &function_twins);
        if !reads_twinned {
            continue;
        }
        let all = everything(&source);
        let mut copy = FunctionCopy::new(
            module,
            &source,
            &all,
            Function {
                name: source.name.as_ref().map(|n| format!("{n}_{time}")),
                arguments: source.arguments.clone(),
                result: source.result.clone(),
                ..Function::default()
            },
        );
        for (&from, &to) in twin_map {
            copy.replace_global(from, to);
        }
        for (&from, &to) in &function_twins {
            copy.replace_function(from, to);
        }
        member_twins::swap_members(module, &mut copy, &source, members);
        let twin = copy.run();
        let handle = module.functions.append(twin, naga::Span::UNDEFINED);
        function_twins.insert(f, handle);
    }
    function_twins
}

/// The vertex function as helpers: `<entry>_current`, unchanged, and one
/// `<entry>_<time>` per other time, reading that time's twins and
/// returning only the position.
struct PositionHelpers {
    current: Handle<Function>,
    others: Vec<Handle<Function>>,
    vec4: Handle<naga::Type>,
}

impl PositionHelpers {
    fn add(
        module: &mut Module,
        (name, function): (&str, &Function),
        result_ty: Handle<naga::Type>,
        times: &[TimeTwins],
        position_member: Option<u32>,
    ) -> PositionHelpers {
        let stripped_arguments = super::without_bindings(&function.arguments);
        let all = everything(function);
        let current = FunctionCopy::new(
            module,
            function,
            &all,
            Function {
                name: Some(format!("{name}_current")),
                arguments: stripped_arguments.clone(),
                result: Some(naga::FunctionResult {
                    ty: result_ty,
                    binding: None,
                }),
                ..Function::default()
            },
        )
        .run();
        let vec4 = super::builder::vec4_type(module);
        let current = module.functions.append(current, naga::Span::UNDEFINED);
        let mut others = Vec::new();
        for twins in times {
            let mut other = FunctionCopy::new(
                module,
                function,
                &all,
                Function {
                    name: Some(format!("{name}_{}", twins.time)),
                    arguments: stripped_arguments.clone(),
                    result: Some(naga::FunctionResult {
                        ty: vec4,
                        binding: None,
                    }),
                    ..Function::default()
                },
            );
            for (&from, &to) in &twins.globals {
                other.replace_global(from, to);
            }
            for (&from, &to) in &twins.functions {
                other.replace_function(from, to);
            }
            member_twins::swap_members(module, &mut other, function, &twins.members);
            if let Some(index) = position_member {
                other.return_member(index);
            }
            let other = other.run();
            others.push(module.functions.append(other, naga::Span::UNDEFINED));
        }
        PositionHelpers {
            current,
            others,
            vec4,
        }
    }
}

/// The new entry point's output type and how many members it has.
struct CacheOutput {
    ty: Handle<naga::Type>,
    members: u32,
}

/// The new output: the old members (the position now invariant) and each
/// other time's clip position, `<time>_clip_position`, at the next free
/// locations, which it returns. A single `previous` time names the type
/// `<Entry>CacheOutput` (the cache variants'), else `<Entry>TimedOutput`.
fn timed_output(
    module: &mut Module,
    members: Option<(Vec<naga::StructMember>, u32)>,
    result: &naga::FunctionResult,
    vec4: Handle<naga::Type>,
    entry_name: &str,
    times: &[&str],
) -> (CacheOutput, Vec<u32>) {
    let (mut new_members, old_span) = members.unwrap_or_else(|| {
        (
            vec![naga::StructMember {
                name: Some("position".into()),
                ty: vec4,
                binding: result.binding.clone(),
                offset: 0,
            }],
            16,
        )
    });
    let first_location = new_members
        .iter()
        .filter_map(|m| crate::proc::location_of(&m.binding).map(|l| l + 1))
        .max()
        .unwrap_or(0);
    for member in &mut new_members {
        if let Some(Binding::BuiltIn(BuiltIn::Position { invariant })) = member.binding.as_mut() {
            *invariant = true;
        }
    }
    let mut offset = old_span.div_ceil(16) * 16;
    let mut locations = Vec::new();
    for (i, time) in times.iter().enumerate() {
        let location = first_location + i as u32;
        new_members.push(naga::StructMember {
            name: Some(format!("{time}_clip_position")),
            ty: vec4,
            binding: Some(super::builder::perspective_location(location)),
            offset,
        });
        offset += 16;
        locations.push(location);
    }
    let count = new_members.len() as u32;
    let kind = if times == ["previous"] {
        "CacheOutput"
    } else {
        "TimedOutput"
    };
    let ty = module.types.insert(
        naga::Type {
            name: Some(format!("{}{kind}", crate::proc::pascal(entry_name))),
            inner: TypeInner::Struct {
                members: new_members,
                span: offset,
            },
        },
        naga::Span::UNDEFINED,
    );
    (CacheOutput { ty, members: count }, locations)
}

/// `function`'s entry point as a call of `current`, the vertex function
/// as a helper: what the passes that do not reproject draw with.
fn plain_entry(function: &Function, current: Handle<Function>) -> Function {
    let mut result = function.result.clone();
    // A bare position output is invariant like the struct members
    // `mark_positions_invariant` handles.
    if let Some(Binding::BuiltIn(BuiltIn::Position { invariant })) =
        result.as_mut().and_then(|r| r.binding.as_mut())
    {
        *invariant = true;
    }
    let mut b = Builder::new(Function {
        name: function.name.clone(),
        arguments: function.arguments.clone(),
        result,
        ..Function::default()
    });
    let arguments: Vec<_> = (0..function.arguments.len() as u32)
        .map(|i| b.argument(i))
        .collect();
    let value = b.call(current, arguments);
    b.push(Statement::Return { value: Some(value) });
    b.finish()
}

/// Free input locations for the twins of `inputs` at each of `times`
/// other times, lowest first, as (input's location, twin's location) per
/// time; a refusal when the inputs and their twins do not fit in `limit`
/// vertex attributes.
fn twin_locations(
    module: &Module,
    function: &Function,
    inputs: &[InstanceInput],
    times: usize,
    limit: u32,
) -> Result<Vec<Vec<(u32, u32)>>, Refusal> {
    let used: BTreeSet<u32> = function
        .arguments
        .iter()
        .flat_map(|a| crate::proc::located(module, &a.binding, a.ty))
        .map(|(location, _)| location)
        .collect();
    let wanted = inputs.len() * times;
    let free: Vec<u32> = (0..limit)
        .filter(|l| !used.contains(l))
        .take(wanted)
        .collect();
    if free.len() < wanted {
        let whose = if times == 1 {
            "whose last-frame twins".to_string()
        } else {
            format!("whose twins at {times} other times")
        };
        let limit_name = if limit == MAX_VERTEX_ATTRIBUTES {
            format!("WebGPU's {limit}")
        } else {
            format!("the device's {limit}")
        };
        return Err(Refusal::new(format!(
            "the position reads {} vertex input(s) that change between frames (per instance, or deformed), {whose} do not fit beside the shader's {} inputs in {limit_name} vertex attributes",
            inputs.len(),
            used.len()
        )));
    }
    if inputs.is_empty() {
        return Ok(vec![Vec::new(); times]);
    }
    Ok(free
        .chunks(inputs.len())
        .map(|chunk| {
            inputs
                .iter()
                .map(|i| i.location)
                .zip(chunk.iter().copied())
                .collect()
        })
        .collect())
}

/// The new entry point's extra arguments for one other time: each twinned
/// input's twin, `<time>_<name>` at its twin location, in `inputs`' order.
fn twin_arguments(
    module: &Module,
    function: &Function,
    inputs: &[InstanceInput],
    (time, twins): (&str, &[(u32, u32)]),
) -> Vec<naga::FunctionArgument> {
    inputs
        .iter()
        .zip(twins)
        .map(|(input, &(_, location))| {
            let argument = &function.arguments[input.argument as usize];
            let name = match (input.member, &module.types[argument.ty].inner) {
                (Some(m), TypeInner::Struct { members, .. }) => members[m as usize].name.clone(),
                _ => argument.name.clone(),
            };
            naga::FunctionArgument {
                name: Some(format!("{time}_{}", name.unwrap_or_default())),
                ty: input.ty,
                binding: Some(super::builder::location(location)),
            }
        })
        .collect()
}

/// The arguments of another time's copy of the vertex function: the
/// entry point's own `arguments`, with each per-instance input of `inputs`
/// taken from its twin (that time's twins are the entry point's arguments
/// from `first_twin` on, in `inputs`' order). A struct argument with
/// twinned members is composed again from its members and the twins.
fn other_time_arguments(
    module: &Module,
    function: &Function,
    b: &mut Builder,
    mut arguments: Vec<Handle<Expression>>,
    (inputs, first_twin): (&[InstanceInput], u32),
) -> Vec<Handle<Expression>> {
    for (i, argument) in function.arguments.iter().enumerate() {
        let twins: Vec<(Option<u32>, u32)> = inputs
            .iter()
            .zip(first_twin..)
            .filter(|(input, _)| input.argument as usize == i)
            .map(|(input, twin)| (input.member, twin))
            .collect();
        let Some(&(_, first)) = twins.first() else {
            continue;
        };
        let TypeInner::Struct { ref members, .. } = module.types[argument.ty].inner else {
            arguments[i] = b.argument(first);
            continue;
        };
        let components = (0..members.len() as u32)
            .map(
                |m| match twins.iter().find(|&&(member, _)| member == Some(m)) {
                    Some(&(_, twin)) => b.argument(twin),
                    None => b.member(arguments[i], m),
                },
            )
            .collect();
        arguments[i] = b.expr(Expression::Compose {
            ty: argument.ty,
            components,
        });
    }
    arguments
}

/// The vertex side of a fragment-only module (engines compose the vertex
/// stage elsewhere): no vertex entry point to instrument, so the host's
/// must output the previous clip position, at the first location after
/// every one the fragment entry point `fragment` reads.
pub(crate) fn fragment_only(module: &Module, fragment: usize) -> VertexStage {
    let function = &module.entry_points[fragment].function;
    let locations: Vec<u32> = crate::proc::inputs(module, function)
        .iter()
        .filter_map(|input| crate::proc::location_of(input.binding))
        .collect();
    VertexStage {
        entry_index: None,
        previous_location: locations.iter().map(|l| l + 1).max().unwrap_or(0),
        twins: Vec::new(),
        member_twins: Vec::new(),
        instance_twins: Vec::new(),
        plain: None,
    }
}

/// Whether `module` has no vertex entry point at all.
pub fn is_fragment_only(module: &Module) -> bool {
    crate::proc::entry_points_of(module, naga::ShaderStage::Vertex).is_empty()
}

/// Every expression of `function`: copying with this set keeps it whole.
fn everything(function: &Function) -> ExprSet {
    let mut set = ExprSet::with_capacity(function.expressions.len());
    set.insert_range(..);
    set
}

fn calls_any(block: &naga::Block, functions: &HashMap<Handle<Function>, Handle<Function>>) -> bool {
    let mut found = false;
    crate::proc::each_statement(block, &mut |statement| {
        if let Statement::Call { function, .. } = *statement {
            found |= functions.contains_key(&function);
        }
    });
    found
}

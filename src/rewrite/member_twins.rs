//! Which resources the previous position needs no twin of.
//!
//! The vertex stage's twins ([`super::vertex`]) are copies of whole
//! resources that the host fills with last frame's contents. Two kinds of
//! resource need none:
//!
//! - One that keeps last frame's values itself, beside this frame's, in
//!   the same struct: Bevy's `Mesh` has `previous_world_from_local` next to
//!   `world_from_local` (what its motion-vector prepass reads), Unity's
//!   per-draw constants have `unity_MatrixPreviousM`. A twin would be a
//!   second copy of what the engine has, and one the engine may not let
//!   the host make (Bevy's mesh buffer cannot be copied from). Where every
//!   member the position reads of it has a sibling `previous_<member>` of
//!   the same type, the previous position reads the siblings instead.
//! - One the position does not read at all: the vertex stage reads it for
//!   its other outputs only (Bevy's mesh metadata, for compressed UVs).
//!
//! Both are told from the position computation: the vertex entry point's
//! slice of its `@builtin(position)` output, member by member through
//! local structs ([`ExprGraph::member_precise`]), and, for each helper
//! whose result that slice uses, the slice of the helper's result; a
//! helper called for its effect counts whole. A read the rule cannot see
//! through — the resource or an element of it loaded whole and passed on,
//! a member with no sibling, `arrayLength` — keeps the resource's twin,
//! as before. Only the cache's previous time (last frame) uses this: an
//! I-frame several frames back is not what `previous_` members hold.

use std::collections::{BTreeSet, HashSet};

use naga::{Expression, Function, Handle, Module, Statement, TypeInner};

use super::copy::FunctionCopy;
use crate::analysis::graph::{ExprGraph, ExprSet};

/// A resource whose previous values are its own `previous_` members: in
/// the previous position, each member access `from` reads `to` instead.
#[derive(Clone, Debug)]
pub(crate) struct MemberTwin {
    pub global: Handle<naga::GlobalVariable>,
    /// (struct type, member read, the member holding its previous value).
    pub swaps: Vec<(Handle<naga::Type>, u32, u32)>,
}

/// Of `candidates` (the resources that would get twins), those whose
/// previous values the vertex entry point at `entry_index` can read from
/// their own `previous_` members, and those its position does not read.
pub(crate) fn position_reads(
    module: &Module,
    entry_index: usize,
    position_member: Option<u32>,
    candidates: &[Handle<naga::GlobalVariable>],
) -> PositionReads {
    let entry = &module.entry_points[entry_index].function;
    let mut reads = Vec::new();
    sliced_reads(
        module,
        entry,
        position_member,
        &mut reads,
        &mut BTreeSet::new(),
    );

    let mut found = PositionReads::default();
    'candidates: for &global in candidates {
        let mut swaps = Vec::new();
        let mut read = false;
        for (function, exprs) in &reads {
            let chains = chains(module, function, &[global]);
            read |= exprs.iter().any(|h| chains[h.index()].is_some());
            if !swappable(function, &chains, exprs) {
                continue 'candidates;
            }
            swaps.extend(chains.iter().filter_map(|c| match *c {
                Some(Chain::Swap { ty, from, to, .. }) => Some((ty, from, to)),
                _ => None,
            }));
        }
        swaps.sort();
        swaps.dedup();
        match (read, swaps.is_empty()) {
            (false, _) => found.unread.push(global),
            (true, false) => found.members.push(MemberTwin { global, swaps }),
            // Read, but only at the top (a whole value, swappable by no
            // member): impossible for a resource read at all, as a read
            // ends at a load or a member; the twin, to be safe.
            (true, true) => {}
        }
    }
    found
}

/// What the position computation reads of the resources that would get
/// twins.
#[derive(Debug, Default)]
pub(crate) struct PositionReads {
    /// Read only through members with `previous_` siblings.
    pub members: Vec<MemberTwin>,
    /// Not read at all: only outputs other than the position read them
    /// (Bevy's mesh metadata, for compressed UVs), so last frame's value
    /// of them is never needed.
    pub unread: Vec<Handle<naga::GlobalVariable>>,
}

/// The expressions of `function` that its output `member` (its result, for
/// `None`) depends on, and the same, recursively, of every helper whose
/// result they use: the position computation, read by read. A helper
/// called for its effect (no result, or a pointer argument it may write
/// through) counts whole, with everything it calls.
fn sliced_reads<'m>(
    module: &'m Module,
    function: &'m Function,
    member: Option<u32>,
    reads: &mut Vec<(&'m Function, Vec<Handle<Expression>>)>,
    seen: &mut BTreeSet<Handle<Function>>,
) {
    let layout = crate::proc::layout(module, function, 8.0);
    let graph = ExprGraph::member_precise(function, &layout);
    let mut slice = ExprSet::with_capacity(function.expressions.len());
    for value in crate::proc::output_values(function, &layout, member) {
        slice.union_with(&graph.slice(value));
    }
    let in_slice = |h: Handle<Expression>| slice.contains(h.index());
    let mut called = Vec::new();
    crate::proc::each_statement(&function.body, &mut |s| {
        if let Statement::Call {
            function, result, ..
        } = *s
        {
            let writes_through_pointer = module.functions[function]
                .arguments
                .iter()
                .any(|a| matches!(module.types[a.ty].inner, TypeInner::Pointer { .. }));
            match result {
                _ if writes_through_pointer => called.push((function, false)),
                Some(result) if in_slice(result) => called.push((function, true)),
                Some(_) => {}
                None => called.push((function, false)),
            }
        }
    });
    let exprs = function.expressions.iter().map(|(h, _)| h);
    reads.push((function, exprs.filter(|&h| in_slice(h)).collect()));
    for (f, by_result) in called {
        if !seen.insert(f) {
            continue;
        }
        match by_result {
            true => sliced_reads(module, &module.functions[f], None, reads, seen),
            false => whole_reads(module, f, reads, seen),
        }
    }
}

/// Every expression of helper `f` and of everything it calls.
fn whole_reads<'m>(
    module: &'m Module,
    f: Handle<Function>,
    reads: &mut Vec<(&'m Function, Vec<Handle<Expression>>)>,
    seen: &mut BTreeSet<Handle<Function>>,
) {
    let mut functions = vec![f];
    crate::proc::collect_callees(module, &module.functions[f].body, &mut functions, seen);
    for f in functions {
        let function = &module.functions[f];
        let all = function.expressions.iter().map(|(h, _)| h).collect();
        reads.push((function, all));
    }
}

/// Where an expression rooted at a resource has got, reading down from it.
#[derive(Clone, Copy, Debug)]
enum Chain {
    /// At (a pointer to, or a value of) this type, no member with a
    /// sibling selected yet.
    At(Handle<naga::Type>),
    /// Selecting member `from` of struct `ty` from `base`, which has the
    /// sibling `to`.
    Swap {
        base: Handle<Expression>,
        ty: Handle<naga::Type>,
        from: u32,
        to: u32,
    },
    /// Deeper within a member with a sibling.
    Within,
    /// A component of something with no sibling: a read no swap covers.
    Uncovered,
}

/// Each expression of `function` rooted at one of `globals`, followed down
/// (in arena order, so a base comes before what reads it).
fn chains(
    module: &Module,
    function: &Function,
    globals: &[Handle<naga::GlobalVariable>],
) -> Vec<Option<Chain>> {
    let mut chains: Vec<Option<Chain>> = vec![None; function.expressions.len()];
    let deeper = |module: &Module, ty: Handle<naga::Type>| match module.types[ty].inner {
        TypeInner::Array { base, .. } | TypeInner::BindingArray { base, .. } => Chain::At(base),
        _ => Chain::Uncovered,
    };
    for (h, expr) in function.expressions.iter() {
        let chain = match *expr {
            Expression::GlobalVariable(g) if globals.contains(&g) => {
                Some(Chain::At(module.global_variables[g].ty))
            }
            Expression::Load { pointer } => match chains[pointer.index()] {
                Some(Chain::Swap { .. }) => Some(Chain::Within),
                other => other,
            },
            Expression::Access { base, .. } => match chains[base.index()] {
                Some(Chain::At(ty)) => Some(deeper(module, ty)),
                Some(Chain::Swap { .. } | Chain::Within) => Some(Chain::Within),
                other => other,
            },
            Expression::AccessIndex { base, index } => match chains[base.index()] {
                Some(Chain::At(ty)) => Some(match &module.types[ty].inner {
                    TypeInner::Struct { members, .. } => match previous_sibling(members, index) {
                        Some(to) => Chain::Swap {
                            base,
                            ty,
                            from: index,
                            to,
                        },
                        None => members
                            .get(index as usize)
                            .map_or(Chain::Uncovered, |m| Chain::At(m.ty)),
                    },
                    _ => deeper(module, ty),
                }),
                Some(Chain::Swap { .. } | Chain::Within) => Some(Chain::Within),
                other => other,
            },
            _ => None,
        };
        chains[h.index()] = chain;
    }
    chains
}

/// Whether every read of the resource among `exprs` ends within a member
/// with a sibling: no component of an uncovered member is read, and a
/// chain still at a type is only read deeper (a load or an access), not
/// used whole.
fn swappable(function: &Function, chains: &[Option<Chain>], exprs: &[Handle<Expression>]) -> bool {
    let wanted: HashSet<Handle<Expression>> = exprs.iter().copied().collect();
    let mut read_deeper = vec![false; chains.len()];
    for (h, expr) in function.expressions.iter() {
        if !wanted.contains(&h) || chains[h.index()].is_none() {
            continue;
        }
        if let Expression::Load { pointer: base }
        | Expression::Access { base, .. }
        | Expression::AccessIndex { base, .. } = *expr
        {
            read_deeper[base.index()] = true;
        }
    }
    exprs.iter().all(|&h| match chains[h.index()] {
        Some(Chain::Uncovered) => false,
        Some(Chain::At(_)) => read_deeper[h.index()],
        _ => true,
    })
}

/// The member `previous_<name>` of the same type as member `index`.
fn previous_sibling(members: &[naga::StructMember], index: u32) -> Option<u32> {
    let member = members.get(index as usize)?;
    let name = format!("previous_{}", member.name.as_deref()?);
    members
        .iter()
        .position(|m| m.name.as_deref() == Some(&name) && m.ty == member.ty)
        .map(|i| i as u32)
}

/// Makes `copy` (of `source`, a function of `module`) read each of
/// `twins`' previous members where `source` reads the current ones.
pub(crate) fn swap_members(
    module: &Module,
    copy: &mut FunctionCopy,
    source: &Function,
    twins: &[MemberTwin],
) {
    if twins.is_empty() {
        return;
    }
    let globals: Vec<_> = twins.iter().map(|t| t.global).collect();
    let chains = chains(module, source, &globals);
    for ((h, _), chain) in source.expressions.iter().zip(chains) {
        if let Some(Chain::Swap { base, to, .. }) = chain {
            copy.rebuild(
                h,
                Box::new(move |copy: &mut FunctionCopy| {
                    let read = Expression::AccessIndex { base, index: to };
                    crate::proc::remap::expression(&read, copy)
                }),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::diagnostic::SourceFile;

    /// A Bevy-like mesh array: `world_from_local` with its
    /// `previous_world_from_local`, and members without siblings that only
    /// the normal reads.
    const MESHES: &str = "
struct Mesh {
    world_from_local: mat4x4<f32>,
    previous_world_from_local: mat4x4<f32>,
    local_from_world: mat4x4<f32>,
    flags: u32,
}
struct View { clip_from_world: mat4x4<f32> }
@group(0) @binding(0) var<uniform> view: View;
@group(1) @binding(0) var<storage, read> mesh: array<Mesh>;
@group(0) @binding(1) var<uniform> tint: vec4<f32>;
struct Out {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
}
fn world_from_local(i: u32) -> mat4x4<f32> { return mesh[i].world_from_local; }
fn model_of(m: Mesh) -> mat4x4<f32> { return m.world_from_local; }
@vertex
fn vertex(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>, @builtin(instance_index) i: u32) -> Out {
    var out: Out;
    POSITION
    out.normal = (transpose(mesh[i].local_from_world) * vec4(n, 0.0)).xyz * f32(mesh[i].flags & 1u) * tint.xyz;
    return out;
}
@fragment
fn fragment(in: Out) -> @location(0) vec4<f32> { return vec4(in.normal, 1.0); }
";

    /// The twinned resources' names and the member twins' resource names,
    /// after instrumenting the vertex stage whose position is `position`.
    fn instrumented(position: &str) -> (Vec<String>, Vec<String>) {
        let text = MESHES.replace("POSITION", position);
        let shader = crate::front::parse(SourceFile::new("t.wgsl", text))
            .map_err(|e| e.render())
            .unwrap();
        let mut module = shader.module.clone();
        let stage = super::super::vertex::instrument(&mut module, 0, (3, 0), &[]).unwrap();
        crate::front::validate(&module).unwrap();
        let name = |g: naga::Handle<naga::GlobalVariable>| {
            module.global_variables[g].name.clone().unwrap_or_default()
        };
        (
            stage.twins.iter().map(|&(from, _)| name(from)).collect(),
            stage.member_twins.iter().map(|t| name(t.global)).collect(),
        )
    }

    /// The position reads the mesh's model through a helper and the view
    /// directly: the mesh needs no twin (its normal's members without
    /// siblings are outside the position), the view, with no
    /// `previous_clip_from_world`, still does.
    #[test]
    fn an_array_element_with_previous_siblings_needs_no_twin() {
        let (twins, members) = instrumented(
            "out.position = view.clip_from_world * world_from_local(i) * vec4(p, 1.0);",
        );
        assert_eq!(twins, ["view"]);
        assert_eq!(members, ["mesh"]);
    }

    /// A resource the vertex stage reads only for another output (`tint`,
    /// for the normal) needs no twin: last frame's value of it never
    /// reaches the position. Read by the position, it gets one.
    #[test]
    fn a_resource_only_other_outputs_read_needs_no_twin() {
        let plain = "out.position = view.clip_from_world * world_from_local(i) * vec4(p, 1.0);";
        assert_eq!(instrumented(plain).0, ["view"]);
        let tinted =
            "out.position = view.clip_from_world * world_from_local(i) * vec4(p * tint.w, 1.0);";
        assert_eq!(instrumented(tinted).0, ["view", "tint"]);
    }

    /// As Bevy's vertex stage: the position computed from a member of a
    /// local struct whose other member (the normal) reads the mesh's
    /// members without siblings. The slice goes by member, so the normal's
    /// reads do not count.
    #[test]
    fn a_local_structs_other_members_are_outside_the_position() {
        let (twins, members) = instrumented(
            "var w: Out;
    w.normal = (transpose(mesh[i].local_from_world) * vec4(n, 0.0)).xyz;
    w.position = world_from_local(i) * vec4(p, 1.0);
    out.position = view.clip_from_world * w.position;",
        );
        assert_eq!(twins, ["view"]);
        assert_eq!(members, ["mesh"]);
    }

    /// Reads the rule cannot swap keep the twin: a member without a
    /// sibling in the position, and an element loaded whole and passed
    /// on (a member read of a loaded element is swapped like any other).
    #[test]
    fn a_read_without_a_sibling_keeps_the_twin() {
        let (twins, members) = instrumented(
            "out.position = view.clip_from_world * mesh[i].world_from_local * vec4(p * f32(mesh[i].flags), 1.0);",
        );
        assert_eq!(twins, ["view", "mesh"]);
        assert!(members.is_empty());
        let (twins, members) = instrumented(
            "let m = mesh[i]; out.position = view.clip_from_world * model_of(m) * vec4(p, 1.0);",
        );
        assert_eq!(twins, ["view", "mesh"]);
        assert!(members.is_empty());
        let (twins, members) = instrumented(
            "let m = mesh[i]; out.position = view.clip_from_world * m.world_from_local * vec4(p, 1.0);",
        );
        assert_eq!(
            (twins, members),
            (vec!["view".to_string()], vec!["mesh".to_string()])
        );
    }
}

//! Splitting the fragment entry point at the node: the payload slice
//! (what computing the node needs, with the branches and early returns on
//! its path and the conditions of the kills before it), the payload
//! function that computes it, and the shade function that takes it as an
//! argument in its place.

use naga::{Expression, Function, Handle, Module};

use super::path::{self, Path};
use super::stage::Stage;
use super::{copy, free_function, gradients, type_handle, uniformity, without_bindings};
use super::{Options, Refusal};
use crate::analysis::graph::{ExprGraph, ExprSet};
use crate::analysis::{Analysis, Candidate};
use crate::front::Shader;
use crate::proc::FunctionLayout;

/// What computing the node needs.
pub(super) struct PayloadSlice {
    pub live: ExprSet,
    /// The branches the node is computed under; `None` when every pixel
    /// computes it.
    pub path: Option<Path>,
    /// One-pass with implicit derivatives in the slice: they are computed
    /// before its miss branch ([`gradients`]).
    pub hoist_derivatives: bool,
}

impl PayloadSlice {
    /// The node's slice in `function`, refusing what a variant's passes
    /// (`passes`, the stages they run) cannot
    /// compute: a payload before a discard its passes would confuse with
    /// their own, derivatives one-pass cannot take before its miss branch.
    pub fn of(
        original: &Module,
        function: &Function,
        layout: &FunctionLayout,
        graph: &ExprGraph,
        node: Handle<Expression>,
        passes: &[Stage],
    ) -> Result<PayloadSlice, Refusal> {
        let at = layout
            .placement(node)
            .ok_or_else(|| Refusal::new("the node is not evaluated by the entry point"))?;
        let node_order = layout.order_of(node).unwrap_or(usize::MAX);
        let discards_after = layout.kills.iter().any(|kill| kill.after > node_order);
        // A pass that discards misses cannot tell them from the pixels the
        // shader itself would cut out after the node, unless a G-buffer
        // pass has decided coverage before it (the stencil holds it).
        let coverage_decided = passes.contains(&Stage::GBuffer);
        if discards_after && !coverage_decided && passes.iter().any(|s| s.discards()) {
            return Err(Refusal::new(
                "the shader may discard after the node is computed, so the payload pass cannot know which pixels are cut out",
            ));
        }
        let mut live = graph.slice(node);
        // Under branches, the payload evaluates the path to the node too.
        // A pixel that returns before the node does not compute it either.
        let early_returns = layout
            .returns
            .iter()
            .filter(|r| r.after <= node_order)
            .map(|r| &r.placement);
        let path = Path::of(function, graph, at, early_returns);
        if let Some(path) = &path {
            live.union_with(&path.live);
        }
        for kill in layout.kills.iter().filter(|k| k.after <= node_order) {
            for &condition in &kill.placement.controls {
                live.union_with(&graph.slice(condition));
            }
        }
        let hoist_derivatives = passes.iter().any(|s| s.computes_payload_on_miss())
            && derivatives_before_the_miss(original, function, layout, &live)?;
        Ok(PayloadSlice {
            live,
            path,
            hoist_derivatives,
        })
    }
}

/// Whether the slice takes implicit derivatives, which one-pass must
/// compute before its miss branch; a refusal where they cannot be: inside
/// a helper (gradients are hoisted from the entry point's own
/// expressions; egui's `sample_texture` would be called in the miss branch
/// as it is), or in a loop or branch (no single value to compute first).
fn derivatives_before_the_miss(
    original: &Module,
    function: &Function,
    layout: &FunctionLayout,
    live: &ExprSet,
) -> Result<bool, Refusal> {
    if let Some(call) = layout.calls.iter().find(|call| {
        call.result.is_some_and(|r| live.contains(r.index()))
            && uniformity::needs_derivatives(original, call.function)
    }) {
        return Err(Refusal::new(format!(
            "one-pass computes the payload only on a miss, in non-uniform control flow, and the payload calls `{}`, which takes implicit derivatives inside the helper, where they cannot be computed before the miss branch; two-pass and three-pass compute the payload in uniform control flow",
            original.functions[call.function].name.as_deref().unwrap_or("a helper")
        )));
    }
    let mut found = false;
    for (handle, expression) in function.expressions.iter() {
        if !live.contains(handle.index()) {
            continue;
        }
        let Some(what) = uniformity::implicit_derivative(expression) else {
            continue;
        };
        found = true;
        if layout
            .placement(handle)
            .is_some_and(|at| at.loop_depth > 0 || !at.controls.is_empty())
        {
            return Err(Refusal::new(format!(
                "one-pass computes the payload only on a miss, in non-uniform control flow, and the payload takes implicit derivatives ({what}) inside a loop or branch, which cannot be computed before the miss branch; two-pass and three-pass compute the payload in uniform control flow"
            )));
        }
    }
    Ok(found)
}

/// The functions the split adds to the module.
pub(super) struct Split {
    pub payload: Handle<Function>,
    /// One-pass's gradients, computed before its miss branch.
    pub gradients: Option<Handle<Function>>,
    pub shade: Handle<Function>,
    pub payload_ty: Handle<naga::Type>,
    /// For a node under branches: whether the original computes it at a
    /// pixel.
    pub presence: Option<Handle<Function>>,
}

/// Adds the payload, shade (and gradients, and presence) functions of
/// the entry point split at `node` to `module`. `absent` is the cache
/// helper giving "no value".
pub(super) fn split(
    module: &mut Module,
    (shader, analysis, candidate): (&Shader, &Analysis, &Candidate),
    graph: &ExprGraph,
    slice: &PayloadSlice,
    node: Handle<Expression>,
    (options, absent): (&Options, Handle<Function>),
) -> Result<Split, Refusal> {
    let original = &shader.module;
    let entry = &original.entry_points[analysis.entry_index];
    let function = &entry.function;
    let info = shader.info.get_entry_point(analysis.entry_index);
    let payload_ty = type_handle(module, info, node);
    let stripped = without_bindings(&function.arguments);
    let (payload, gradients) = if slice.hoist_derivatives {
        let hoisted = gradients::hoist(
            module,
            &gradients::Source {
                original,
                function,
                info,
                graph,
                live: &slice.live,
            },
            &gradients::PayloadShape {
                node,
                arguments: &stripped,
                result: payload_ty,
                name: &entry.name,
                absent,
                components: candidate.components,
            },
        )?;
        (hoisted.payload, Some(hoisted.gradients))
    } else {
        let mut payload_copy = copy::FunctionCopy::new(
            original,
            function,
            &slice.live,
            Function {
                name: Some(format!("{}_payload", entry.name)),
                arguments: stripped.clone(),
                result: Some(naga::FunctionResult {
                    ty: payload_ty,
                    binding: None,
                }),
                ..Function::default()
            },
        );
        payload_copy.return_at(node);
        let payload_fn = path::finish_payload(payload_copy, absent, candidate.components);
        (
            module.functions.append(payload_fn, naga::Span::UNDEFINED),
            None,
        )
    };
    let shade = shade_function(
        module,
        (original, function),
        graph,
        node,
        stripped,
        payload_ty,
        &entry.name,
    );
    if options.free_payload {
        free_function(module.functions.get_mut(payload));
        free_function(module.functions.get_mut(shade));
    }
    let presence = slice.path.as_ref().map(|node_path| {
        path::presence(
            module,
            original,
            function,
            node_path,
            node,
            without_bindings(&function.arguments),
            format!("{}_computes_node", entry.name),
        )
    });
    Ok(Split {
        payload,
        gradients,
        shade,
        payload_ty,
        presence,
    })
}

/// The entry point's remainder after the node, taking the binding-free
/// `arguments` and the node's value as a last one, `cached`.
fn shade_function(
    module: &mut Module,
    (original, function): (&Module, &Function),
    graph: &ExprGraph,
    node: Handle<Expression>,
    mut arguments: Vec<naga::FunctionArgument>,
    payload_ty: Handle<naga::Type>,
    entry_name: &str,
) -> Handle<Function> {
    arguments.push(naga::FunctionArgument {
        name: Some("cached".into()),
        ty: payload_ty,
        binding: None,
    });
    let cached_index = arguments.len() as u32 - 1;
    let live = graph.remainder(node);
    let mut shade_copy = copy::FunctionCopy::new(
        original,
        function,
        &live,
        Function {
            name: Some(format!("{entry_name}_shade")),
            arguments,
            result: function.result.as_ref().map(|result| naga::FunctionResult {
                ty: result.ty,
                binding: None,
            }),
            ..Function::default()
        },
    );
    shade_copy.substitute(node, Expression::FunctionArgument(cached_index));
    module
        .functions
        .append(shade_copy.run(), naga::Span::UNDEFINED)
}

//! Nodes computed under branches.
//!
//! Engines put their costly work under branches: Bevy's whole lit path
//! sits under `if ((material.flags & UNLIT_BIT) == 0u)`, a terrain shader
//! picks grass or rock by the slope of the pixel's normal. A node computed
//! there has a value only on the pixels (or the draws) that take the
//! branches leading to it: its *path*, the conditions of the `if`s and the
//! selectors of the `switch`es around it.
//!
//! The payload function evaluates the path and the node where the path is
//! taken, and returns *no value* — `cache_absent()`, a NaN — where it is
//! not. The cache then holds NaN at those pixels, so next frame's lookup
//! there misses rather than reusing a value that never existed. The shade
//! function keeps the branches and reads the cached node only inside them,
//! where the original computes it. So a pixel that enters the branch this
//! frame after missing it last frame recomputes the node, and one that
//! leaves it simply stops reading it.
//!
//! When every condition is *uniform for the draw* — it depends only on
//! uniforms, overrides and constants, as material flags do — the path is
//! taken by every pixel of a draw or by none, and the node is cached like
//! an unconditional one. Otherwise the path is per pixel. The classify pass
//! (the profiler's maps and hit rates) evaluates the path too, and marks
//! the pixels without the node as absent, so hits, misses and refreshes
//! are counted only where the node exists.

use naga::{Block, Expression, Function, Handle, Module, Span, Statement};

use super::copy::FunctionCopy;
use crate::analysis::graph::{self, ExprGraph, ExprSet};
use crate::proc::Placement;

/// The branches a node is computed under.
#[derive(Clone, Debug)]
pub struct Path {
    /// Everything evaluating the conditions and selectors around the node,
    /// and those around the `return`s before it, needs.
    pub live: ExprSet,
    /// Whether each condition depends only on uniforms, overrides and
    /// constants (not on any fragment input).
    pub uniform: bool,
}

impl Path {
    /// The path to a node placed at `at`, where `returns` are the places of
    /// the `return`s evaluated before it (a pixel that returns early does
    /// not compute the node either); `None` when every pixel computes it.
    pub fn of<'p>(
        function: &Function,
        graph: &ExprGraph,
        at: &Placement,
        returns: impl IntoIterator<Item = &'p Placement>,
    ) -> Option<Path> {
        let mut conditions = at.controls.clone();
        let mut early_return = false;
        for placement in returns {
            early_return = true;
            conditions.extend(placement.controls.iter().copied());
        }
        if conditions.is_empty() && !early_return {
            return None;
        }
        let mut live = ExprSet::with_capacity(function.expressions.len());
        for &condition in &conditions {
            live.union_with(&graph.slice(condition));
        }
        let exprs: Vec<&Expression> = function.expressions.iter().map(|(_, e)| e).collect();
        let uniform = !graph::reads_arguments(&exprs, &live);
        Some(Path { live, uniform })
    }

    /// How the plan describes it.
    pub fn describe(&self) -> &'static str {
        if self.uniform {
            "uniform-branch"
        } else {
            "per-pixel-branch"
        }
    }
}

/// Runs a copy made with [`FunctionCopy::return_at`] the node: on the paths
/// that do not reach the node, it returns `cache_absent()` (`absent`),
/// narrowed to the payload's `components`.
pub fn finish_payload(
    copy: FunctionCopy<'_>,
    absent: Handle<Function>,
    components: u32,
) -> Function {
    // Also where the source returns before the node: that pixel does not
    // compute it either.
    copy.run_or_return(Box::new(move |copy, block| {
        absent_value(copy, block, absent, components)
    }))
}

/// `cache_absent()` narrowed to the payload's components, its call pushed
/// into `block`.
fn absent_value(
    copy: &mut FunctionCopy<'_>,
    block: &mut Block,
    absent: Handle<Function>,
    components: u32,
) -> Handle<Expression> {
    copy.flush_into(block);
    let none = copy
        .target
        .expressions
        .append(Expression::CallResult(absent), Span::UNDEFINED);
    block.push(
        Statement::Call {
            function: absent,
            arguments: Vec::new(),
            result: Some(none),
        },
        Span::UNDEFINED,
    );
    match components {
        4 => none,
        1 => copy.add(Expression::AccessIndex {
            base: none,
            index: 0,
        }),
        n => copy.add(Expression::Swizzle {
            size: match n {
                2 => naga::VectorSize::Bi,
                _ => naga::VectorSize::Tri,
            },
            vector: none,
            pattern: [
                naga::SwizzleComponent::X,
                naga::SwizzleComponent::Y,
                naga::SwizzleComponent::Z,
                naga::SwizzleComponent::W,
            ],
        }),
    }
}

/// A function of the fragment's inputs (`arguments`, without bindings)
/// that says whether the original computes `node` at this pixel: the
/// path's branches, returning `true` where the node would be evaluated and
/// `false` after them.
pub fn presence(
    module: &mut Module,
    original: &Module,
    function: &Function,
    path: &Path,
    node: Handle<Expression>,
    arguments: Vec<naga::FunctionArgument>,
    name: String,
) -> Handle<Function> {
    let bool_ty = module.types.insert(
        naga::Type {
            name: None,
            inner: naga::TypeInner::Scalar(naga::Scalar::BOOL),
        },
        Span::UNDEFINED,
    );
    let mut copy = FunctionCopy::new(
        original,
        function,
        &path.live,
        Function {
            name: Some(name),
            arguments,
            result: Some(naga::FunctionResult {
                ty: bool_ty,
                binding: None,
            }),
            ..Function::default()
        },
    );
    copy.return_value_at(node, Expression::Literal(naga::Literal::Bool(true)));
    let presence = copy.run_or_return(Box::new(|copy, _| {
        copy.add(Expression::Literal(naga::Literal::Bool(false)))
    }));
    module.functions.append(presence, Span::UNDEFINED)
}

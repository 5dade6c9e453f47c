//! IR helpers shared by the stages: what an expression reads, where in the
//! statement tree each expression is evaluated, and how often.
//!
//! naga keeps expressions in a per-function arena and says *when* they are
//! evaluated through `Emit` statements placed in the function's blocks
//! (see naga's `ir` module documentation). Several stages need the same
//! facts about that structure — the cost model needs how many times an
//! expression runs, the analysis needs whether it runs inside a loop and
//! which branch conditions govern it, the expression graph needs every value
//! a statement consumes — so they are computed here once per function.
//!
//! `kind` says what each naga expression does, in the one exhaustive
//! match the analysis and the cost model share.
//!
//! It also copies IR between modules: `remap` maps the handles of one
//! expression or statement, `import` copies a whole module into another
//! (the cache helpers into a rewrite, a separate vertex module into the
//! fragment one's).

pub(crate) mod import;
pub(crate) mod inline;
mod kind;
mod names;
mod operands;
mod placement;
mod reaching;
pub(crate) mod remap;
mod stages;

pub use kind::{kind, takes_derivatives, ExpressionKind};
pub use names::{name_words, pascal};
pub use operands::{operands, pointer_root, PointerRoot};
pub use placement::{
    collect_callees, each_spanned_statement, each_statement, has_effects, layout, CallSite,
    FunctionLayout, Placement, Store,
};
pub use reaching::{reaching_definitions, Definition};
pub use stages::{inputs, instance_locations, located, location_of, output_values, vertex_entry};

/// Whether a value with `binding` and type `ty` — an entry point's argument
/// or result — carries a binding that `wanted` accepts, on itself or on one
/// of its struct members.
pub fn has_binding(
    module: &naga::Module,
    binding: &Option<naga::Binding>,
    ty: naga::Handle<naga::Type>,
    wanted: impl Fn(&naga::Binding) -> bool,
) -> bool {
    binding.as_ref().is_some_and(&wanted)
        || match module.types[ty].inner {
            naga::TypeInner::Struct { ref members, .. } => members
                .iter()
                .any(|m| m.binding.as_ref().is_some_and(&wanted)),
            _ => false,
        }
}

/// The number of scalar components of a type: 1 for scalars, n for vectors,
/// columns × rows for matrices, 1 for everything else.
pub fn components(inner: &naga::TypeInner) -> u32 {
    match *inner {
        naga::TypeInner::Scalar(_) | naga::TypeInner::Atomic(_) => 1,
        naga::TypeInner::Vector { size, .. } => size as u32,
        naga::TypeInner::Matrix { columns, rows, .. } => columns as u32 * rows as u32,
        _ => 1,
    }
}

/// Evaluates an expression to an integer when it is an integer literal or a
/// named constant whose initializer is one.
pub fn const_int(
    module: &naga::Module,
    function: &naga::Function,
    expr: naga::Handle<naga::Expression>,
) -> Option<i64> {
    match function.expressions[expr] {
        naga::Expression::Literal(literal) => literal_int(literal),
        naga::Expression::Constant(constant) => {
            match module.global_expressions[module.constants[constant].init] {
                naga::Expression::Literal(literal) => literal_int(literal),
                _ => None,
            }
        }
        _ => None,
    }
}

fn literal_int(literal: naga::Literal) -> Option<i64> {
    match literal {
        naga::Literal::I32(v) => Some(v as i64),
        naga::Literal::U32(v) => Some(v as i64),
        naga::Literal::I64(v) => Some(v),
        naga::Literal::U64(v) => i64::try_from(v).ok(),
        naga::Literal::AbstractInt(v) => Some(v),
        _ => None,
    }
}

/// The global variables the entry points at `entries` use, directly or
/// through the functions they call: what a draw with them binds. A module
/// may declare more (wgpu's `shadow` example binds its lights as storage
/// for one fragment entry point and as a uniform array for the other, at
/// the same slot).
pub fn globals_used_by(
    module: &naga::Module,
    entries: &[usize],
) -> std::collections::HashSet<naga::Handle<naga::GlobalVariable>> {
    fn visit(
        module: &naga::Module,
        function: &naga::Function,
        used: &mut std::collections::HashSet<naga::Handle<naga::GlobalVariable>>,
        seen: &mut std::collections::HashSet<naga::Handle<naga::Function>>,
    ) {
        for (_, expr) in function.expressions.iter() {
            if let naga::Expression::GlobalVariable(g) = *expr {
                used.insert(g);
            }
        }
        each_statement(&function.body, &mut |statement| {
            if let naga::Statement::Call { function, .. } = *statement {
                if seen.insert(function) {
                    visit(module, &module.functions[function], used, seen);
                }
            }
        });
    }
    let mut used = std::collections::HashSet::new();
    let mut seen = std::collections::HashSet::new();
    for &entry in entries {
        if let Some(ep) = module.entry_points.get(entry) {
            visit(module, &ep.function, &mut used, &mut seen);
        }
    }
    used
}

/// The name and (group, binding) of every resource the entry points at
/// `entries` use (two resources may share a slot when no entry point uses
/// both, so the slot alone does not say which).
#[cfg(feature = "profile")]
pub fn resources_used_by(
    module: &naga::Module,
    entries: &[usize],
) -> std::collections::HashSet<(String, [u32; 2])> {
    globals_used_by(module, entries)
        .into_iter()
        .filter_map(|g| {
            let global = &module.global_variables[g];
            let b = global.binding?;
            Some((
                global.name.clone().unwrap_or_default(),
                [b.group, b.binding],
            ))
        })
        .collect()
}

/// The indices of `module`'s entry points of `stage`.
pub fn entry_points_of(module: &naga::Module, stage: naga::ShaderStage) -> Vec<usize> {
    module
        .entry_points
        .iter()
        .enumerate()
        .filter(|(_, ep)| ep.stage == stage)
        .map(|(i, _)| i)
        .collect()
}

/// The names of the entry points at `indices`, for messages: `` `vs`, `vs_shadow` ``,
/// or `none`.
pub fn entry_point_names(module: &naga::Module, indices: &[usize]) -> String {
    if indices.is_empty() {
        return "none".into();
    }
    indices
        .iter()
        .map(|&i| format!("`{}`", module.entry_points[i].name))
        .collect::<Vec<_>>()
        .join(", ")
}

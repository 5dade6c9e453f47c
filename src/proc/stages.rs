//! Which entry points work together: the vertex stage that draws with a
//! fragment stage, and the values a vertex stage outputs.

use std::collections::BTreeSet;

use naga::{Binding, Expression, Function, Handle, Module, Statement, TypeInner};

use super::FunctionLayout;

/// The vertex entry point that draws with the fragment entry point at
/// `fragment`: the one named `wanted`; else the module's only one; else,
/// among several (a shadow pass and a main pass, as wgpu's `shadow`
/// example has), the only one whose outputs are what the fragment stage
/// takes — its input struct, or a value at every location it reads.
pub fn vertex_entry(
    module: &Module,
    fragment: usize,
    wanted: Option<&str>,
) -> Result<usize, String> {
    let vertices = super::entry_points_of(module, naga::ShaderStage::Vertex);
    let names = |indices: &[usize]| super::entry_point_names(module, indices);
    let fragment = &module.entry_points[fragment];
    let feeds_fragment =
        |v: usize| feeds(module, &module.entry_points[v].function, &fragment.function);
    if let Some(name) = wanted {
        return match module.entry_points.iter().position(|ep| ep.name == name) {
            Some(index) if !vertices.contains(&index) => Err(format!(
                "`{name}` is not a vertex entry point; the vertex entry points are {}",
                names(&vertices)
            )),
            Some(index) if feeds_fragment(index) => Ok(index),
            Some(_) => Err(format!(
                "`{name}` does not output what `{}` takes (its input struct, or a value at each location it reads)",
                fragment.name
            )),
            None => Err(format!(
                "the shader has no entry point named `{name}`; its vertex entry points are {}",
                names(&vertices)
            )),
        };
    }
    if let [only] = vertices[..] {
        return Ok(only);
    }
    if vertices.is_empty() {
        return Err(
            "the shader has no vertex entry point to compute the previous position with".into(),
        );
    }
    let feeding: Vec<usize> = vertices
        .iter()
        .copied()
        .filter(|&v| feeds_fragment(v))
        .collect();
    match feeding[..] {
        [only] => Ok(only),
        [] => Err(format!(
            "none of the vertex entry points ({}) outputs what `{}` takes; name the one that draws with it with --vertex-entry",
            names(&vertices),
            fragment.name
        )),
        _ => Err(format!(
            "several vertex entry points ({}) output what `{}` takes; name the one that draws with it with --vertex-entry",
            names(&feeding),
            fragment.name
        )),
    }
}

/// Whether `vertex`'s outputs are what `fragment` takes: the same struct
/// type, or a value of the same type at every location the fragment stage
/// reads.
fn feeds(module: &Module, vertex: &Function, fragment: &Function) -> bool {
    let Some(result) = &vertex.result else {
        return false;
    };
    if fragment.arguments.iter().any(|a| a.ty == result.ty) {
        return true;
    }
    let outputs = located(module, &result.binding, result.ty);
    fragment
        .arguments
        .iter()
        .flat_map(|a| located(module, &a.binding, a.ty))
        .all(|input| outputs.contains(&input))
}

/// One value an entry point takes: an argument, or a member of an
/// argument's struct.
#[derive(Clone, Copy, Debug)]
pub struct Input<'a> {
    pub name: Option<&'a String>,
    pub ty: Handle<naga::Type>,
    pub binding: &'a Option<Binding>,
}

/// Every value `function` takes, arguments' struct members in place of
/// the struct, in order.
pub fn inputs<'a>(module: &'a Module, function: &'a Function) -> Vec<Input<'a>> {
    let mut out = Vec::new();
    for argument in &function.arguments {
        match module.types[argument.ty].inner {
            TypeInner::Struct { ref members, .. } => out.extend(members.iter().map(|m| Input {
                name: m.name.as_ref(),
                ty: m.ty,
                binding: &m.binding,
            })),
            _ => out.push(Input {
                name: argument.name.as_ref(),
                ty: argument.ty,
                binding: &argument.binding,
            }),
        }
    }
    out
}

/// The `(location, type)` pairs a value with `binding` and type `ty`
/// carries, on itself or on its struct's members.
pub fn located(
    module: &Module,
    binding: &Option<Binding>,
    ty: Handle<naga::Type>,
) -> Vec<(u32, naga::TypeInner)> {
    match module.types[ty].inner {
        TypeInner::Struct { ref members, .. } => members
            .iter()
            .filter_map(|m| location_of(&m.binding).map(|l| (l, module.types[m.ty].inner.clone())))
            .collect(),
        ref inner => location_of(binding)
            .map(|l| (l, inner.clone()))
            .into_iter()
            .collect(),
    }
}

/// The vertex inputs of `function` that step per instance.
///
/// A shader does not say how its inputs step: the host's pipeline does.
/// The tutorials' and engines' naming says it instead: an input is per
/// instance when its struct type or argument is named for instances
/// (`InstanceInput`, `instance: ...`), or its own name is (`instance_*`,
/// Bevy's `i_*` prefix).
pub fn instance_locations(module: &Module, function: &Function) -> BTreeSet<u32> {
    let named_instance = |name: Option<&String>| {
        name.is_some_and(|n| {
            let n = n.to_ascii_lowercase();
            n.contains("instance") || n.starts_with("i_")
        })
    };
    let mut out = BTreeSet::new();
    for argument in &function.arguments {
        let ty = &module.types[argument.ty];
        match ty.inner {
            TypeInner::Struct { ref members, .. } => {
                let whole =
                    named_instance(ty.name.as_ref()) || named_instance(argument.name.as_ref());
                for member in members {
                    if whole || named_instance(member.name.as_ref()) {
                        out.extend(location_of(&member.binding));
                    }
                }
            }
            _ if named_instance(argument.name.as_ref()) => {
                out.extend(location_of(&argument.binding))
            }
            _ => {}
        }
    }
    out
}

/// The location a binding gives, if it is one.
pub fn location_of(binding: &Option<Binding>) -> Option<u32> {
    match *binding {
        Some(Binding::Location { location, .. }) => Some(location),
        _ => None,
    }
}

/// The values that become output `member` of `function`'s result (the
/// result itself for `None`): the returned value, its component for a
/// composed struct, or for a returned local struct what is stored into
/// that member (and any store that may write it: the whole variable, a
/// deeper pointer into it).
pub fn output_values(
    function: &Function,
    layout: &FunctionLayout,
    member: Option<u32>,
) -> Vec<Handle<Expression>> {
    let exprs = &function.expressions;
    let mut returned = Vec::new();
    super::each_statement(&function.body, &mut |statement| {
        if let Statement::Return { value: Some(value) } = *statement {
            returned.push(value);
        }
    });
    let mut values = Vec::new();
    for value in returned {
        let local = match (member, &exprs[value]) {
            (Some(m), Expression::Compose { components, .. }) => {
                values.extend(components.get(m as usize).copied());
                continue;
            }
            (Some(_), &Expression::Load { pointer }) => match exprs[pointer] {
                Expression::LocalVariable(local) => local,
                _ => {
                    values.push(value);
                    continue;
                }
            },
            _ => {
                values.push(value);
                continue;
            }
        };
        let m = member.unwrap_or(0);
        values.extend(function.local_variables[local].init);
        let is_local =
            |e: Handle<Expression>| matches!(exprs[e], Expression::LocalVariable(l) if l == local);
        for store in &layout.stores {
            if store.target != Some(super::PointerRoot::Local(local)) {
                continue;
            }
            let other_member = matches!(
                exprs[store.pointer],
                Expression::AccessIndex { base, index } if is_local(base) && index != m
            );
            if !other_member {
                values.push(store.value);
            }
        }
    }
    values
}

//! Roles: which of the shader's own members the simulation animates.
//!
//! A shader names its matrices as it likes (`camera.view_proj`,
//! `model.world`, `u_mvp`); the simulation knows a fixed set of quantities
//! ([`ROLES`]: the camera's view-projection, the model matrix, the camera
//! and light positions, time). A scene's `[roles]` table maps one onto the
//! other, `"camera.view_proj" = "clip_from_world"`. [`check`] holds that
//! table against the shader, and [`infer`] guesses it from the IR for
//! `scene init` and the default scene:
//!
//! - the matrices applied on the way from the vertex position to
//!   `@builtin(position)` are, last to first, the view-projection and the
//!   model matrix (three: projection, view and model; one: their product);
//! - positions and time cannot be told apart by their use (a light and a
//!   camera are both subtracted from the world position), so they are
//!   inferred from their names (`camera`/`eye`/`view` with `pos`, `light`
//!   with `pos` or `dir`, `time`), and the comment `scene init` writes says
//!   so.

use std::collections::HashMap;

use naga::{Expression, Handle, Module, Statement, TypeInner};

use super::layout::{fits_role, implicit_role, Shape, ROLES};
use super::storage::StorageBuffer;
use super::uniforms::UniformBuffer;
use super::Scene;
use crate::diagnostic::Error;

/// A role `scene init` inferred, with how.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Inferred {
    /// `buffer.member` (or a plain uniform's name).
    pub key: String,
    pub role: &'static str,
    pub how: String,
}

/// The `[roles]` key of member `member` of binding `binding`.
pub fn key(binding: &str, member: &str) -> String {
    // A plain uniform's members are named from it (`lights[2].color` of
    // `var<uniform> lights: array<Light, 4>`).
    let own = member == binding
        || member
            .strip_prefix(binding)
            .is_some_and(|rest| rest.starts_with('[') || rest.starts_with('.'));
    if own {
        member.to_string()
    } else {
        format!("{binding}.{member}")
    }
}

/// Checks the scene's `[roles]` against the shader's buffers: every key
/// names a member, every role is known and fits the member's type, and no
/// member has both a role and a value. Errors point at the role in the
/// scene file.
pub fn check(
    uniforms: &[UniformBuffer],
    storage: &[StorageBuffer],
    scene: &Scene,
) -> Result<(), Error> {
    // Every member as (its key, its shape, its `[uniforms]` name for a
    // uniform's).
    let members = || {
        let uniform = uniforms.iter().flat_map(|b| {
            b.members
                .iter()
                .map(move |m| (key(&b.name, &m.name), m.shape, Some(m.name.as_str())))
        });
        let storage = storage.iter().flat_map(|b| {
            b.members
                .iter()
                .map(move |m| (key(&b.name, &m.name), m.shape, None))
        });
        uniform.chain(storage)
    };
    for (key, role) in &scene.roles {
        let at = |message: String| Err(scene.error(message, Some(role.span())));
        let role_name = role.get_ref().as_str();
        if !ROLES.iter().any(|(name, _)| *name == role_name) {
            let known: Vec<&str> = ROLES.iter().map(|(name, _)| *name).collect();
            return at(format!(
                "unknown role `{role_name}` for `{key}`: the roles are {}",
                known.join(", ")
            ));
        }
        let Some((_, shape, uniform)) = members().find(|(k, ..)| k == key) else {
            let mut names: Vec<String> = members().map(|(k, ..)| format!("`{k}`")).collect();
            names.sort();
            let listing = if names.is_empty() {
                "it binds no uniform or storage buffer".to_string()
            } else {
                format!("its members are {}", names.join(", "))
            };
            return at(format!(
                "[roles] names `{key}`, which the shader does not have: {listing}"
            ));
        };
        if !fits_role(role_name, shape) {
            let described = ROLES
                .iter()
                .find(|(name, _)| *name == role_name)
                .map_or("", |(_, d)| d);
            return at(format!(
                "`{key}` is {} and cannot take role `{role_name}`: {described}",
                shape_name(shape)
            ));
        }
        if let Some(member) = uniform.filter(|m| scene.uniforms.contains_key(*m)) {
            return at(format!(
                "`{key}` is given twice: a role here and a value under [uniforms] `{member}`; keep one"
            ));
        }
    }
    Ok(())
}

/// The WGSL type of a member of `shape`, for messages.
pub fn shape_name(shape: Shape) -> String {
    let vector = |scalar: &str, n: u32| {
        if n == 1 {
            scalar.to_string()
        } else {
            format!("vec{n}<{scalar}>")
        }
    };
    match shape {
        Shape::F32(n) => vector("f32", n),
        Shape::U32(n) => vector("u32", n),
        Shape::I32(n) => vector("i32", n),
        Shape::Matrix(c, r) => format!("mat{c}x{r}<f32>"),
        Shape::Other => "a type a scene cannot write".into(),
    }
}

/// Infers the roles of the shader's members: the matrices on the way to
/// `@builtin(position)` of the vertex entry point `vertex`, the positions
/// and time by name. Members already named like a role are left out (they
/// take it without `[roles]`).
pub fn infer(
    module: &Module,
    vertex: Option<usize>,
    uniforms: &[UniformBuffer],
    storage: &[StorageBuffer],
) -> Vec<Inferred> {
    let mut out: Vec<Inferred> = Vec::new();
    let named_role = |key: &str| implicit_role(key).is_some();
    if let Some(vertex) = vertex {
        let function = &module.entry_points[vertex].function;
        let chain = position_matrices(module, function);
        let roles: &[&'static str] = match chain.len() {
            1 => &["clip_from_local"],
            2 => &["clip_from_world", "world_from_local"],
            3 => &["clip_from_view", "view_from_world", "world_from_local"],
            _ => &[],
        };
        let order = ["applied last", "applied next", "applied first"];
        for (i, (key, role)) in chain.iter().zip(roles).enumerate() {
            // A matrix made from vertex inputs (a model matrix passed per
            // instance) takes its place in the chain but is no member.
            let Some(key) = key else {
                continue;
            };
            if named_role(key) {
                continue;
            }
            let place = if chain.len() == 1 {
                "the only matrix".to_string()
            } else if i + 1 == chain.len() {
                order[2].to_string()
            } else {
                order[i].to_string()
            };
            out.push(Inferred {
                key: key.clone(),
                role,
                how: format!(
                    "{place} on the way from the vertex position to @builtin(position) in `{}`",
                    module.entry_points[vertex].name
                ),
            });
        }
    }
    let members = uniforms
        .iter()
        .flat_map(|b| b.members.iter().map(move |m| (&b.name, m)))
        .chain(
            storage
                .iter()
                .flat_map(|b| b.members.iter().map(move |m| (&b.name, m))),
        );
    let members: Vec<_> = members.collect();
    // Roles members take by their own names (`light_position`): taken.
    let taken: Vec<&str> = members
        .iter()
        .filter_map(|(binding, member)| implicit_role(&key(binding, &member.name)))
        .collect();
    for (binding, member) in members {
        let key = key(binding, &member.name);
        if named_role(&key) || out.iter().any(|i| i.key == key) {
            continue;
        }
        if let Some(role) = role_by_name(&key, member.shape) {
            // One member per role by name: a second (a fill light's
            // position beside `light_position`) would be a guess.
            if taken.contains(&role) || out.iter().any(|i| i.role == role) {
                continue;
            }
            out.push(Inferred {
                key,
                role,
                how: format!("by its name (a {})", shape_name(member.shape)),
            });
        }
    }
    out
}

/// The role a member's name suggests, if its type fits it: for matrices
/// the position chain did not reach (a sky drawn from the inverse
/// projection), for positions and for time.
fn role_by_name(key: &str, shape: Shape) -> Option<&'static str> {
    // A matrix by its own name (`camera.view_proj`: not the camera's
    // position); a position by the binding's as well (`light.position`).
    let member = key.rsplit('.').next().unwrap_or(key).to_ascii_lowercase();
    let whole = key.to_ascii_lowercase();
    let name = if shape == Shape::Matrix(4, 4) {
        member.clone()
    } else {
        whole.clone()
    };
    let has = |words: &[&str]| words.iter().any(|w| name.contains(w));
    // Whole words, where a part would mislead: the `dir` of
    // `directional_lights[0].color` is no direction.
    let key_words = crate::proc::name_words(key);
    let has_word = |words: &[&str]| key_words.iter().any(|w| words.contains(&w.as_str()));
    let role = if shape == Shape::Matrix(4, 4) {
        if let Some(named) = matrix_named_from_to(&member) {
            // Named by its spaces: exactly that matrix, or none.
            return named;
        }
        // A matrix of a light (`s_lights[i].proj`) is the light's.
        if whole.contains("light") {
            "light_clip_from_world"
        } else if has(&["mvp"]) {
            "clip_from_local"
        } else if has(&["proj"]) && has(&["inv"]) {
            // The inverse projection; the inverse view-projection (Bevy's
            // older `inverse_view_proj`, world from clip) is no role's.
            if has(&["viewproj", "view_proj"]) {
                return None;
            }
            "view_from_clip"
        } else if has(&["viewproj", "view_proj", "vp", "clip"]) {
            "clip_from_world"
        } else if has(&["proj"]) {
            "clip_from_view"
        } else if has(&["view"]) && !has(&["inv"]) {
            "view_from_world"
        } else if has(&["model", "world", "transform"]) {
            "world_from_local"
        } else {
            return None;
        }
    } else if has(&["light"]) && has_word(&["pos", "position", "dir", "direction"]) {
        "light_position"
    } else if (has(&["camera", "cam", "eye", "view"]) && has(&["pos", "origin", "world"]))
        || viewer_alone(key.rsplit('.').next().unwrap_or(key))
    {
        "camera_position"
    } else if has(&["time", "elapsed"]) {
        "time"
    } else if has(&["resolution", "viewport", "screen_size", "screensize"]) {
        "resolution"
    } else {
        return None;
    };
    fits_role(role, shape).then_some(role)
}

/// A matrix named in the `a_from_b` convention (Bevy's `clip_from_world`,
/// `world_from_view`): the role that is exactly that transform, or
/// `Some(None)` when no role is (`world_from_view` is the inverse of the
/// view matrix, and taking it for `view_from_world`, by its word `view`,
/// filled the inverse); `None` when the name is not of that form.
fn matrix_named_from_to(member: &str) -> Option<Option<&'static str>> {
    let words = crate::proc::name_words(member);
    let at = words.iter().position(|w| w == "from")?;
    let space = |word: Option<&String>| match word.map(String::as_str) {
        Some("clip") => Some("clip"),
        Some("view" | "camera" | "eye") => Some("view"),
        Some("world") => Some("world"),
        Some("local" | "model" | "object") => Some("local"),
        _ => None,
    };
    let to = space(at.checked_sub(1).and_then(|i| words.get(i)))?;
    let from = space(words.get(at + 1))?;
    let role = format!("{to}_from_{from}");
    let previous = words.iter().any(|w| w == "previous" || w == "prev");
    let role = if previous {
        format!("previous_{role}")
    } else {
        role
    };
    Some(
        ROLES
            .iter()
            .map(|(name, _)| *name)
            .find(|name| *name == role),
    )
}

/// Whether a member is named for the viewer alone (`eye`, `u_eye`,
/// `camera`, `viewer`): a point, when its type fits, is where it stands.
fn viewer_alone(member: &str) -> bool {
    let words = crate::proc::name_words(member);
    let words: Vec<&str> = words
        .iter()
        .map(String::as_str)
        .filter(|w| !matches!(*w, "u" | "i" | "m" | "g"))
        .collect();
    matches!(words[..], ["eye" | "camera" | "cam" | "viewer"])
}

/// The matrices applied to the vertex position on its way to
/// `@builtin(position)`, last applied first: a uniform or storage member
/// as its `[roles]` key, `None` for a matrix from elsewhere (built from
/// per-instance vertex inputs, computed). Empty when the position is not
/// a chain of products (computed in a helper).
fn position_matrices(module: &Module, function: &naga::Function) -> Vec<Option<String>> {
    let Some(position) = position_output(module, function) else {
        return Vec::new();
    };
    let stores = single_stores(function);
    let mut chain = Vec::new();
    walk_product(module, function, &stores, position, &mut chain, 0);
    chain
}

/// The expression the vertex entry point returns as `@builtin(position)`:
/// the returned value itself, a component of the struct it composes, or
/// what is stored into that member of the local it returns.
fn position_output(module: &Module, function: &naga::Function) -> Option<Handle<Expression>> {
    let result = function.result.as_ref()?;
    let is_position = |binding: &Option<naga::Binding>| {
        matches!(
            binding,
            Some(naga::Binding::BuiltIn(naga::BuiltIn::Position { .. }))
        )
    };
    let member = if is_position(&result.binding) {
        None
    } else {
        let TypeInner::Struct { ref members, .. } = module.types[result.ty].inner else {
            return None;
        };
        Some(members.iter().position(|m| is_position(&m.binding))? as u32)
    };
    let mut found = None;
    crate::proc::each_statement(&function.body, &mut |statement| match *statement {
        Statement::Return { value: Some(value) } if found.is_none() => {
            found = match (member, &function.expressions[value]) {
                (None, _) => Some(value),
                (Some(index), Expression::Compose { components, .. }) => {
                    components.get(index as usize).copied()
                }
                _ => None,
            };
        }
        Statement::Store { pointer, value } if found.is_none() => {
            if let (Some(index), Expression::AccessIndex { base, index: i }) =
                (member, &function.expressions[pointer])
            {
                if *i == index
                    && matches!(function.expressions[*base], Expression::LocalVariable(_))
                {
                    found = Some(value);
                }
            }
        }
        _ => {}
    });
    found
}

/// What a local variable (or one member of it, `out.world_position`) is
/// stored exactly once: the value a load of it gives. Stored more than
/// once, it is left out.
type Place = (Handle<naga::LocalVariable>, Option<u32>);
type Stores = HashMap<Place, Handle<Expression>>;

fn single_stores(function: &naga::Function) -> Stores {
    let mut count: HashMap<Place, (usize, Handle<Expression>)> = HashMap::new();
    for (handle, local) in function.local_variables.iter() {
        if let Some(init) = local.init {
            count.insert((handle, None), (1, init));
        }
    }
    crate::proc::each_statement(&function.body, &mut |statement| {
        if let Statement::Store { pointer, value } = *statement {
            if let Some(key) = local_place(function, pointer) {
                let entry = count.entry(key).or_insert((0, value));
                entry.0 += 1;
                entry.1 = value;
            }
        }
    });
    count
        .into_iter()
        .filter(|(_, (n, _))| *n == 1)
        .map(|(key, (_, value))| (key, value))
        .collect()
}

/// A pointer to a local variable or to one member of it.
fn local_place(function: &naga::Function, pointer: Handle<Expression>) -> Option<Place> {
    match function.expressions[pointer] {
        Expression::LocalVariable(local) => Some((local, None)),
        Expression::AccessIndex { base, index } => match function.expressions[base] {
            Expression::LocalVariable(local) => Some((local, Some(index))),
            _ => None,
        },
        _ => None,
    }
}

/// Follows `expr` down the chain of matrix products to the vertex
/// position, pushing each uniform or storage matrix it applies.
fn walk_product(
    module: &Module,
    function: &naga::Function,
    stores: &Stores,
    expr: Handle<Expression>,
    chain: &mut Vec<Option<String>>,
    depth: usize,
) {
    // Deep enough for any real chain; guards against odd IR.
    if depth > 64 {
        return;
    }
    let recurse = |e, chain: &mut Vec<Option<String>>| {
        walk_product(module, function, stores, e, chain, depth + 1)
    };
    let is_matrix = |e: Handle<Expression>| is_matrix(module, function, e, 0);
    match function.expressions[expr] {
        Expression::Binary {
            op: naga::BinaryOperator::Multiply,
            left,
            right,
        } => {
            // Column vectors (M * v) or row vectors (v * M).
            let (matrix, vector) = if is_matrix(left) && !is_matrix(right) {
                (left, right)
            } else if is_matrix(right) && !is_matrix(left) {
                (right, left)
            } else {
                return;
            };
            matrix_factors(module, function, stores, matrix, chain, depth + 1);
            recurse(vector, chain);
        }
        Expression::Compose { ref components, .. } => {
            if let Some(&first) = components.first() {
                recurse(first, chain);
            }
        }
        Expression::Swizzle { vector, .. } => recurse(vector, chain),
        Expression::AccessIndex { base, .. } if !is_matrix(base) => recurse(base, chain),
        Expression::As { expr: inner, .. } => recurse(inner, chain),
        Expression::Load { pointer } => {
            if let Some(&value) = local_place(function, pointer).and_then(|key| stores.get(&key)) {
                recurse(value, chain);
            }
        }
        _ => {}
    }
}

/// Whether `expr` is a matrix, for the expressions a position chain is
/// made of (naga gives types only through validation, and these few
/// cases are all the chain needs).
fn is_matrix(
    module: &Module,
    function: &naga::Function,
    expr: Handle<Expression>,
    depth: usize,
) -> bool {
    let ty = match function.expressions[expr] {
        Expression::Load { pointer } => pointee(module, function, pointer, depth + 1),
        Expression::Binary {
            op: naga::BinaryOperator::Multiply,
            left,
            right,
        } if depth < 64 => {
            return is_matrix(module, function, left, depth + 1)
                && is_matrix(module, function, right, depth + 1)
        }
        Expression::FunctionArgument(i) => function.arguments.get(i as usize).map(|a| a.ty),
        Expression::Compose { ty, .. } => Some(ty),
        Expression::CallResult(f) => module.functions[f].result.as_ref().map(|r| r.ty),
        _ => None,
    };
    ty.is_some_and(|ty| matches!(module.types[ty].inner, TypeInner::Matrix { .. }))
}

/// The type a pointer expression points to.
fn pointee(
    module: &Module,
    function: &naga::Function,
    pointer: Handle<Expression>,
    depth: usize,
) -> Option<Handle<naga::Type>> {
    if depth > 64 {
        return None;
    }
    match function.expressions[pointer] {
        Expression::LocalVariable(l) => Some(function.local_variables[l].ty),
        Expression::GlobalVariable(g) => Some(module.global_variables[g].ty),
        Expression::AccessIndex { base, index } => {
            let base = pointee(module, function, base, depth + 1)?;
            match module.types[base].inner {
                TypeInner::Struct { ref members, .. } => members.get(index as usize).map(|m| m.ty),
                TypeInner::Array { base, .. } => Some(base),
                _ => None,
            }
        }
        Expression::Access { base, .. } => {
            let base = pointee(module, function, base, depth + 1)?;
            match module.types[base].inner {
                TypeInner::Array { base, .. } => Some(base),
                _ => None,
            }
        }
        _ => None,
    }
}

/// The matrices a matrix expression multiplies together, in order
/// (`proj * view` gives both): uniform or storage members by key, others
/// `None`.
fn matrix_factors(
    module: &Module,
    function: &naga::Function,
    stores: &Stores,
    matrix: Handle<Expression>,
    chain: &mut Vec<Option<String>>,
    depth: usize,
) {
    if depth > 64 {
        return;
    }
    match function.expressions[matrix] {
        Expression::Binary {
            op: naga::BinaryOperator::Multiply,
            left,
            right,
        } => {
            matrix_factors(module, function, stores, left, chain, depth + 1);
            matrix_factors(module, function, stores, right, chain, depth + 1);
        }
        Expression::Load { pointer } => {
            if let Some(key) = local_place(function, pointer) {
                match stores.get(&key) {
                    Some(&value) => {
                        matrix_factors(module, function, stores, value, chain, depth + 1)
                    }
                    None => chain.push(None),
                }
                return;
            }
            chain.push(member_key(module, function, pointer));
        }
        _ => chain.push(None),
    }
}

/// The `[roles]` key of a pointer into a uniform or storage buffer:
/// `buffer.member`, `buffer` for a plain one, through an array index
/// (`instances[i].world`).
fn member_key(
    module: &Module,
    function: &naga::Function,
    pointer: Handle<Expression>,
) -> Option<String> {
    // The buffer: the global at the root of the pointer, through array
    // indexing only.
    let buffer = |mut e: Handle<Expression>| -> Option<String> {
        loop {
            match function.expressions[e] {
                Expression::GlobalVariable(g) => {
                    let global = &module.global_variables[g];
                    let buffer = matches!(
                        global.space,
                        naga::AddressSpace::Uniform | naga::AddressSpace::Storage { .. }
                    );
                    return buffer.then(|| global.name.clone().unwrap_or_default());
                }
                Expression::Access { base, .. } => e = base,
                Expression::AccessIndex { base, .. }
                    if matches!(
                        pointee(module, function, base, 0).map(|t| &module.types[t].inner),
                        Some(TypeInner::Array { .. })
                    ) =>
                {
                    e = base
                }
                _ => return None,
            }
        }
    };
    match function.expressions[pointer] {
        Expression::GlobalVariable(_) => buffer(pointer),
        Expression::AccessIndex { base, index } => {
            let binding = buffer(base)?;
            let ty = pointee(module, function, base, 0)?;
            let TypeInner::Struct { ref members, .. } = module.types[ty].inner else {
                return None;
            };
            let member = members.get(index as usize)?.name.clone()?;
            Some(key(&binding, &member))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light's position or direction is named so by whole words: Bevy's
    /// `lights.directional_lights[0].color` holds no direction (its `dir`
    /// is part of `directional`), and took the light's position.
    #[test]
    fn a_light_role_by_name_takes_whole_words() {
        for (key, role) in [
            ("light.position", Some("light_position")),
            ("u.light_dir", Some("light_position")),
            ("u.lightPos", Some("light_position")),
            (
                "lights.directional_lights[0].direction_to_light",
                Some("light_position"),
            ),
            ("lights.directional_lights[0].color", None),
        ] {
            assert_eq!(role_by_name(key, Shape::F32(3)), role, "{key}");
        }
    }

    /// A matrix named `a_from_b` (Bevy's `View`) is exactly that transform
    /// or no role: `world_from_view`, the inverse view matrix, took the
    /// view matrix's role by its word `view`, and the scene filled the
    /// inverse of what the shader reads. Older names likewise:
    /// `inverse_view_proj` took the inverse projection's.
    #[test]
    fn a_matrix_named_from_space_to_space_is_that_transform_or_none() {
        for (member, role) in [
            ("view.clip_from_world", Some("clip_from_world")),
            ("view.view_from_world", Some("view_from_world")),
            ("view.world_from_view", None),
            ("view.world_from_clip", None),
            ("view.view_from_clip", Some("view_from_clip")),
            ("view.unjittered_clip_from_world", Some("clip_from_world")),
            ("mesh.world_from_local", Some("world_from_local")),
            (
                "u.previous_clip_from_world",
                Some("previous_clip_from_world"),
            ),
            // Not of the form: the words decide, as before.
            ("camera.view_proj", Some("clip_from_world")),
            ("u.view", Some("view_from_world")),
            ("view.inverse_projection", Some("view_from_clip")),
            // The inverse of the view-projection, which no role is (it
            // was taken for the inverse projection).
            ("view.inverse_view_proj", None),
        ] {
            assert_eq!(role_by_name(member, Shape::Matrix(4, 4)), role, "{member}");
        }
    }
}

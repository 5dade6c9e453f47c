//! A vertex stage for a fragment-only module.
//!
//! Engines keep a material's fragment shader apart from the vertex stage
//! that draws it (Bevy's materials import the mesh's vertex stage). To
//! profile such a module with no `--vertex` file, a vertex stage is made
//! from what the fragment entry point takes: every `@location` input is
//! written from the mesh by its name and type —
//!
//! - a world position (`world` with `pos`/`position`): the vertex
//!   position moved by the model matrix;
//! - a normal: the vertex normal turned by the model matrix;
//! - a tangent: a unit vector across the normal (w = 1);
//! - a texture coordinate (`uv`, `tex`, `coord`): the mesh's uv;
//! - a colour: white;
//! - an instance index: `@builtin(instance_index)`;
//! - any other position: the world position; anything else zero;
//!
//! and `@builtin(position)` is the world position through
//! `clip_from_world`. Its two matrices live in a uniform buffer of its
//! own, at the first bind group the module does not use, named so that
//! the simulation fills them (`clip_from_world`, `world_from_local`).
//! [`generate`] says what it wrote for each input, for the report.
//!
//! The stage is written as WGSL and parsed by naga, then joined to the
//! module as a `--vertex` module is ([`super::with_vertex_module`]): it is
//! a new module made from names and types, not an edit of the user's
//! source, and WGSL is the shortest correct way to say it.

use std::fmt::Write as _;

use naga::{Binding, Module, ScalarKind, TypeInner};

use super::{parse, with_vertex_module, Shader};
use crate::diagnostic::{Diagnostic, Error, SourceFile};

/// The module's fragment entry point `fragment` drawn by a generated
/// vertex stage: the joined shader, and one line per input saying what
/// feeds it.
pub fn generate(shader: &Shader, fragment: usize) -> Result<(Shader, Vec<String>), Error> {
    let (text, fed) = vertex_source(&shader.module, fragment).map_err(|reason| {
        Error::in_file(
            shader.file.clone(),
            Diagnostic::error(format!(
                "cannot make a vertex stage for this fragment-only module: {reason}"
            ))
            .with_label(0..0, "a fragment-only module")
            .with_note("give the module with its vertex stage with --vertex FILE"),
        )
    })?;
    let generated = parse(SourceFile::new(
        format!("vertex stage generated for {}", shader.file.path),
        text,
    ))
    .map_err(|err| {
        Error::internal(Diagnostic::error(format!(
            "the generated vertex stage for `{}` does not parse: {}; this is a bug in shadecache",
            shader.file.path,
            err.render()
        )))
    })?;
    let joined = with_vertex_module(shader.clone_parts(), &generated, None)?;
    Ok((joined, fed))
}

/// The WGSL of the vertex stage for `fragment`, and what feeds each input.
fn vertex_source(module: &Module, fragment: usize) -> Result<(String, Vec<String>), String> {
    let function = &module.entry_points[fragment].function;
    // Every input the fragment stage takes at a location: (its name, its
    // WGSL type, its interpolation attribute, its location).
    let mut inputs = Vec::new();
    let mut add = |name: Option<&String>, ty, binding: &Option<Binding>| -> Result<(), String> {
        let Some(Binding::Location {
            location,
            interpolation,
            sampling,
            ..
        }) = *binding
        else {
            return Ok(());
        };
        let name = name.cloned().unwrap_or_else(|| format!("input{location}"));
        let wgsl = wgsl_type(module, ty).ok_or_else(|| {
            format!("input `{name}` at @location({location}) has a type it cannot write")
        })?;
        let attribute = interpolate_attribute(interpolation, sampling);
        inputs.push((name, wgsl, attribute, location));
        Ok(())
    };
    for input in crate::proc::inputs(module, function) {
        add(input.name, input.ty, input.binding)?;
    }
    let group = module
        .global_variables
        .iter()
        .filter_map(|(_, g)| g.binding.as_ref().map(|b| b.group + 1))
        .max()
        .unwrap_or(0);

    let mut text = format!(
        "struct ShadecacheVertexView {{ clip_from_world: mat4x4<f32>, world_from_local: mat4x4<f32> }}\n\
         @group({group}) @binding(0) var<uniform> shadecache_vertex_view: ShadecacheVertexView;\n\
         struct ShadecacheVertexOut {{\n    @builtin(position) shadecache_clip: vec4<f32>,\n"
    );
    for (name, wgsl, attribute, location) in &inputs {
        let _ = writeln!(text, "    @location({location}){attribute} {name}: {wgsl},");
    }
    text.push_str(
        "}\n@vertex\nfn shadecache_vertex(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) uv: vec2<f32>, @builtin(instance_index) instance: u32) -> ShadecacheVertexOut {\n    let world = shadecache_vertex_view.world_from_local * vec4<f32>(position, 1.0);\n    let world_normal = normalize((shadecache_vertex_view.world_from_local * vec4<f32>(normal, 0.0)).xyz);\n    let across = normalize(cross(world_normal, vec3<f32>(0.0, 0.6, 0.8)));\n    var out: ShadecacheVertexOut;\n    out.shadecache_clip = shadecache_vertex_view.clip_from_world * world;\n",
    );
    let mut fed = Vec::new();
    for (name, wgsl, _, location) in &inputs {
        let (value, what) = feed(name, wgsl);
        let _ = writeln!(text, "    out.{name} = {value};");
        fed.push(format!(
            "vertex stage generated: @location({location}) `{name}` = {what}"
        ));
    }
    text.push_str("    return out;\n}\n");
    Ok((text, fed))
}

/// The value a generated vertex stage writes into input `name` of WGSL
/// type `wgsl`, and what it is in words.
fn feed(name: &str, wgsl: &str) -> (String, &'static str) {
    let words = crate::proc::name_words(name);
    let has = |list: &[&str]| words.iter().any(|w| list.contains(&w.as_str()));
    let float = |n: usize| {
        wgsl == if n == 1 {
            "f32".into()
        } else {
            format!("vec{n}<f32>")
        }
    };
    let world = if float(3) {
        Some("world.xyz")
    } else if float(4) {
        Some("world")
    } else {
        None
    };
    if has(&["instance"]) && (wgsl == "u32" || wgsl == "i32") {
        return (format!("{wgsl}(instance)"), "the instance index");
    }
    if has(&["normal"]) && (float(3) || float(4)) {
        let value = if float(3) {
            "world_normal"
        } else {
            "vec4<f32>(world_normal, 0.0)"
        };
        return (value.into(), "the mesh's normal in world space");
    }
    if has(&["tangent"]) && (float(3) || float(4)) {
        let value = if float(3) {
            "across"
        } else {
            "vec4<f32>(across, 1.0)"
        };
        return (value.into(), "a unit vector across the normal (w = 1)");
    }
    if has(&["uv", "tex", "texcoord", "coord"]) && float(2) {
        return ("uv".into(), "the mesh's texture coordinate");
    }
    if has(&["color", "colour", "tint"]) && (float(3) || float(4)) {
        let value = if float(3) {
            "vec3<f32>(1.0)"
        } else {
            "vec4<f32>(1.0)"
        };
        return (value.into(), "white");
    }
    if has(&["pos", "position", "world"]) {
        if let Some(value) = world {
            return (value.into(), "the world position");
        }
    }
    (
        format!("{wgsl}()"),
        "zero (its name says nothing the mesh has)",
    )
}

/// The WGSL spelling of a scalar or vector type of 32-bit numbers.
fn wgsl_type(module: &Module, ty: naga::Handle<naga::Type>) -> Option<String> {
    let scalar = |s: naga::Scalar| -> Option<&'static str> {
        match (s.kind, s.width) {
            (ScalarKind::Float, 4) => Some("f32"),
            (ScalarKind::Uint, 4) => Some("u32"),
            (ScalarKind::Sint, 4) => Some("i32"),
            _ => None,
        }
    };
    match module.types[ty].inner {
        TypeInner::Scalar(s) => scalar(s).map(str::to_string),
        TypeInner::Vector { size, scalar: s } => Some(format!("vec{}<{}>", size as u8, scalar(s)?)),
        _ => None,
    }
}

/// The `@interpolate(...)` attribute that gives an output the
/// interpolation of the input it feeds.
fn interpolate_attribute(
    interpolation: Option<naga::Interpolation>,
    sampling: Option<naga::Sampling>,
) -> String {
    use naga::{Interpolation as I, Sampling as S};
    let kind = match interpolation {
        None | Some(I::Perspective) => "perspective",
        Some(I::Linear) => "linear",
        Some(I::Flat) => "flat",
        Some(I::PerVertex) => return String::new(),
    };
    let sample = match sampling {
        None => None,
        Some(S::Center) => Some("center"),
        Some(S::Centroid) => Some("centroid"),
        Some(S::Sample) => Some("sample"),
        Some(S::First) => Some("first"),
        Some(S::Either) => Some("either"),
    };
    match (kind, sample) {
        ("perspective", None | Some("center")) => String::new(),
        ("flat", Some(sample @ ("first" | "either"))) => format!(" @interpolate(flat, {sample})"),
        ("flat", _) => " @interpolate(flat)".into(),
        (kind, None) => format!(" @interpolate({kind})"),
        (kind, Some(sample)) => format!(" @interpolate({kind}, {sample})"),
    }
}

//! The fragment stages of the three variants (seed 002, §3).
//!
//! The original fragment entry point is split at the node into two helper
//! functions, each holding only the code it needs (dead code dropped):
//!
//! * the **payload** function: the node's backward slice, returning it;
//! * the **shade** function: everything else, with the node read from an
//!   extra argument.
//!
//! Each pass's entry point is then a few calls: look the payload up in
//! last frame's cache, decide hit / miss / refresh, call the payload
//! function where needed, call the shade function, write colour and cache.
//! The shade function always runs in uniform control flow (after the
//! branch, or after a `discard`), so derivatives and implicit-LOD sampling
//! in it stay valid; only the payload function can land in a branch.

use naga::{Binding, Expression, Function, Handle, Module, Statement, TypeInner};

use super::builder::{location, Builder};
use super::helpers::Pieces;
use super::stage::{CacheStage, Stage, Writes};
use super::Refusal;

/// Whether the pass of `stage` reprojects: the stages that look the
/// fragment up, and with adaptive refresh those that compute the payload
/// too (they compare it with the cached value).
pub(super) fn reprojects_in(stage: Stage, pieces: &Pieces) -> bool {
    stage.reprojects()
        || (pieces.adaptive.is_some()
            && matches!(stage, Stage::Cache(CacheStage::Full | CacheStage::Payload)))
}

/// The `@location`s of a fragment result (a struct's members or the value).
pub fn output_locations(module: &Module, result: &naga::FunctionResult) -> Vec<u32> {
    crate::proc::located(module, &result.binding, result.ty)
        .into_iter()
        .map(|(location, _)| location)
        .collect()
}

/// Where the cache goes: the location after the original outputs. The
/// cache's age goes at the one after it.
pub fn cache_location(module: &Module, result: &naga::FunctionResult) -> u32 {
    output_locations(module, result)
        .into_iter()
        .map(|l| l + 1)
        .max()
        .unwrap_or(0)
}

/// Where a pass's fragment stage reads the original inputs from.
#[derive(Clone, Copy, Debug)]
pub(super) enum Inputs<'g> {
    /// Its own arguments: the rasterised varyings of the geometry.
    Varyings,
    /// A screen-space pass's source at the pixel (the deferred variant's
    /// G-buffer).
    Screen(&'g dyn ScreenInputs),
}

/// What a screen-space pass reads the original inputs from, at the pixel
/// its only argument (the fragment position) is at. The G-buffer
/// ([`super::gbuffer`]) is one; this module builds the passes on it
/// without depending on how it is laid out.
pub(super) trait ScreenInputs: std::fmt::Debug {
    /// At the pixel the fragment is at.
    fn read(&self, b: &mut Builder, module: &mut Module, pieces: &Pieces) -> Fragment;
    /// At the pixel whose centre is `xy` (a `vec2<f32>`): lowres's samples
    /// pass, at 1/s × 1/s, reads the pixel of its lattice.
    fn read_at(
        &self,
        b: &mut Builder,
        module: &mut Module,
        pieces: &Pieces,
        xy: Handle<Expression>,
    ) -> Fragment;
    /// The ordinal of the draw visible at the pixel whose centre is `xy`
    /// (0 where none is), where the source keeps it.
    fn ordinal_at(&self, b: &mut Builder, xy: Handle<Expression>) -> Option<Handle<Expression>>;
}

/// What a fragment entry point works from: the original entry point's
/// arguments, last frame's clip position (where the pass reprojects) and
/// the fragment's position.
pub(super) struct Fragment {
    pub originals: Vec<Handle<Expression>>,
    pub previous: Option<Handle<Expression>>,
    pub frag_coord: Handle<Expression>,
}

/// Where [`read_varyings`] finds what it reads among the arguments
/// [`varying_arguments`] made.
pub(super) struct VaryingsAt {
    originals: u32,
    previous: Option<u32>,
    frag_coord: FragCoord,
}

/// The arguments of a fragment entry point drawn over the geometry: the
/// original ones (a bare `@builtin(position)` made invariant like the
/// struct members `mark_positions_invariant` handles), the previous clip
/// position where `reprojects`, and the fragment position when the
/// original does not take it.
pub(super) fn varying_arguments(
    module: &Module,
    pieces: &Pieces,
    reprojects: bool,
) -> (Vec<naga::FunctionArgument>, VaryingsAt) {
    let mut arguments = pieces.arguments.clone();
    for argument in &mut arguments {
        if let Some(Binding::BuiltIn(naga::BuiltIn::Position { invariant })) =
            argument.binding.as_mut()
        {
            *invariant = true;
        }
    }
    let previous = reprojects.then_some(arguments.len() as u32);
    if reprojects {
        arguments.push(naga::FunctionArgument {
            name: Some("previous_clip_position".into()),
            ty: pieces.vec4,
            binding: Some(Binding::Location {
                location: pieces.previous_location,
                interpolation: Some(naga::Interpolation::Perspective),
                sampling: Some(naga::Sampling::Center),
                blend_src: None,
                per_primitive: false,
            }),
        });
    }
    let frag_coord = match find_frag_coord(module, &pieces.arguments) {
        Some(at) => at,
        None => {
            arguments.push(frag_coord_argument(pieces.vec4));
            FragCoord::Argument(arguments.len() as u32 - 1)
        }
    };
    let at = VaryingsAt {
        originals: pieces.arguments.len() as u32,
        previous,
        frag_coord,
    };
    (arguments, at)
}

/// `@builtin(position) frag_coord: vec4<f32>`, invariant.
pub(super) fn frag_coord_argument(vec4: Handle<naga::Type>) -> naga::FunctionArgument {
    naga::FunctionArgument {
        name: Some("frag_coord".into()),
        ty: vec4,
        binding: Some(Binding::BuiltIn(naga::BuiltIn::Position {
            invariant: true,
        })),
    }
}

/// Reads the arguments [`varying_arguments`] made.
pub(super) fn read_varyings(b: &mut Builder, at: &VaryingsAt) -> Fragment {
    let originals = (0..at.originals).map(|i| b.argument(i)).collect();
    let previous = at.previous.map(|i| b.argument(i));
    let frag_coord = match at.frag_coord {
        FragCoord::Argument(i) => b.argument(i),
        FragCoord::Member(i, m) => {
            let arg = b.argument(i);
            b.member(arg, m)
        }
    };
    Fragment {
        originals,
        previous,
        frag_coord,
    }
}

/// Builds the fragment entry point for `stage`, reading the original
/// inputs from `inputs`.
pub(super) fn entry_point(
    module: &mut Module,
    pieces: &Pieces,
    stage: CacheStage,
    inputs: Inputs,
) -> Result<Function, Refusal> {
    let writes = Stage::Cache(stage).writes();
    // Where the inputs come from: the arguments made here, or the G-buffer.
    enum Reader<'g> {
        Arguments(VaryingsAt),
        Screen(&'g dyn ScreenInputs),
    }
    let (arguments, reader) = match inputs {
        Inputs::Varyings => {
            let reprojects = reprojects_in(Stage::Cache(stage), pieces);
            let (arguments, at) = varying_arguments(module, pieces, reprojects);
            (arguments, Reader::Arguments(at))
        }
        Inputs::Screen(screen) => (
            vec![frag_coord_argument(pieces.vec4)],
            Reader::Screen(screen),
        ),
    };
    let (result_ty, cache_member) = output_type(module, pieces, writes);
    let mut b = Builder::new(Function {
        name: Some(pieces.name.clone()),
        arguments,
        result: Some(naga::FunctionResult {
            ty: result_ty,
            binding: match writes {
                Writes::Classes => Some(location(0)),
                Writes::Color => pieces.result.binding.clone(),
                // A struct: its members carry the bindings.
                Writes::Cache
                | Writes::ColorAndCache
                | Writes::GBuffer
                | Writes::Samples
                | Writes::ColorAndHistory
                | Writes::Stencil => None,
            },
        }),
        ..Function::default()
    });
    let fragment = match reader {
        Reader::Arguments(at) => read_varyings(&mut b, &at),
        Reader::Screen(screen) => screen.read(&mut b, module, pieces),
    };
    let Fragment {
        originals,
        previous,
        frag_coord,
    } = fragment;
    // Last frame's clip position, in the passes that reproject.
    let previous = previous
        .ok_or_else(|| Refusal::internal(format!("{stage:?} reads no previous clip position")));

    if stage == CacheStage::Classify {
        classify_return(&mut b, pieces, (previous?, frag_coord), &originals);
        return Ok(b.finish());
    }
    let at = Fragment {
        originals,
        previous: previous.ok(),
        frag_coord,
    };
    let payload = payload_of(&mut b, module, pieces, stage, &at)?;
    let age = match payload.age {
        Some(age) => age,
        None => b.literal_f32(0.0),
    };
    let output = Output {
        ty: result_ty,
        cache_member,
    };
    let value = output_value(
        &mut b,
        module,
        pieces,
        Stage::Cache(stage),
        &at,
        (payload.value, age),
        output,
    )?;
    if let Some(reuse) = payload.deferred_kill {
        kill_unless(&mut b, reuse);
    }
    b.push(Statement::Return { value: Some(value) });
    Ok(b.finish())
}

/// The classification pass's body: the lookup's status, made `absent`
/// where the original value is not there.
fn classify_return(
    b: &mut Builder,
    pieces: &Pieces,
    (previous, frag_coord): (Handle<Expression>, Handle<Expression>),
    originals: &[Handle<Expression>],
) {
    let lookup = b.call(pieces.lookup, vec![previous]);
    let status = b.member(lookup, 2);
    let age = b.member(lookup, 3);
    let mut classes = b.call(pieces.classify, vec![status, frag_coord, age]);
    if let Some((presence, absent)) = pieces.presence {
        let present = b.call(presence, originals.to_vec());
        classes = b.call(absent, vec![present, classes]);
    }
    b.push(Statement::Return {
        value: Some(classes),
    });
}

/// Ends the invocation where `reuse` is false.
pub(super) fn kill_unless(b: &mut Builder, reuse: Handle<Expression>) {
    let kill = b.nested(|b| b.push(Statement::Kill));
    b.push(Statement::If {
        condition: reuse,
        accept: naga::Block::new(),
        reject: kill,
    });
}

/// The payload a pass shades with, the age to write beside it (the
/// lookup's where the cached value is reused, 0 where it is computed:
/// `None`), and the reuse condition whose misses are discarded at the end
/// (when the shade takes derivatives).
struct PassPayload {
    value: Handle<Expression>,
    age: Option<Handle<Expression>>,
    deferred_kill: Option<Handle<Expression>>,
}

fn payload_of(
    b: &mut Builder,
    module: &Module,
    pieces: &Pieces,
    stage: CacheStage,
    at: &Fragment,
) -> Result<PassPayload, Refusal> {
    let previous = || {
        at.previous
            .ok_or_else(|| Refusal::internal(format!("{stage:?} reads no previous clip position")))
    };
    let plain = |value| PassPayload {
        value,
        age: None,
        deferred_kill: None,
    };
    Ok(match stage {
        CacheStage::OnePass => {
            let (lookup, reuse) = reuse_condition(b, pieces, previous()?, at.frag_coord);
            let reused_age = b.call(pieces.age_written, vec![lookup, reuse]);
            let value = one_pass_payload(b, pieces, (lookup, reuse), &at.originals);
            let age = match pieces.adaptive {
                // A computed value starts from its adaptive age.
                Some(adaptive) => {
                    let texel = to_vec4(b, value, pieces.components, pieces.vec4);
                    let computed = b.call(adaptive, vec![lookup, texel]);
                    b.expr(Expression::Select {
                        condition: reuse,
                        accept: reused_age,
                        reject: computed,
                    })
                }
                None => reused_age,
            };
            PassPayload {
                value,
                age: Some(age),
                deferred_kill: None,
            }
        }
        CacheStage::ReuseOrDiscard | CacheStage::ReprojectOrDiscard => {
            let (lookup, reuse) = reuse_condition(b, pieces, previous()?, at.frag_coord);
            let age = b.call(pieces.age_written, vec![lookup, reuse]);
            // naga writes `discard` as OpKill, which ends the invocation:
            // a derivative after it is undefined in every quad a missed
            // lane leaves. When the shade takes derivatives, every lane
            // shades first and the misses are discarded at the end.
            let shade_derives = Stage::Cache(stage).writes() != Writes::Cache
                && super::uniformity::needs_derivatives(module, pieces.shade);
            if !shade_derives {
                kill_unless(b, reuse);
            }
            let cached = b.member(lookup, 0);
            PassPayload {
                value: from_vec4(b, cached, pieces.components),
                age: Some(age),
                deferred_kill: shade_derives.then_some(reuse),
            }
        }
        CacheStage::Full | CacheStage::Payload => {
            let value = b.call(pieces.payload, at.originals.clone());
            match pieces.adaptive {
                Some(adaptive) => {
                    let lookup = b.call(pieces.lookup, vec![previous()?]);
                    let texel = to_vec4(b, value, pieces.components, pieces.vec4);
                    let age = b.call(adaptive, vec![lookup, texel]);
                    PassPayload {
                        value,
                        age: Some(age),
                        deferred_kill: None,
                    }
                }
                None => plain(value),
            }
        }
        CacheStage::ShadeFromCache => {
            let cached = b.call(pieces.current, vec![at.frag_coord]);
            plain(from_vec4(b, cached, pieces.components))
        }
        // Its entry point returns the classes before any payload.
        CacheStage::Classify => return Err(Refusal::internal("the classify pass has no payload")),
    })
}

/// One-pass's payload: the cached value where `reuse` holds, else the
/// payload computed (with the gradients hoisted before the branch).
fn one_pass_payload(
    b: &mut Builder,
    pieces: &Pieces,
    (lookup, reuse): (Handle<Expression>, Handle<Expression>),
    originals: &[Handle<Expression>],
) -> Handle<Expression> {
    let mut payload_arguments = originals.to_vec();
    if let Some(gradients) = pieces.gradients {
        let value = b.call(gradients, originals.to_vec());
        b.name(value, "gradients");
        payload_arguments.push(value);
    }
    let local = b.function.local_variables.append(
        naga::LocalVariable {
            name: Some("payload".into()),
            ty: pieces.payload_ty,
            init: None,
        },
        naga::Span::UNDEFINED,
    );
    let pointer = b.expr(Expression::LocalVariable(local));
    let accept = b.nested(|b| {
        let cached = b.member(lookup, 0);
        let value = from_vec4(b, cached, pieces.components);
        b.push(Statement::Store { pointer, value });
    });
    let reject = b.nested(|b| {
        let value = b.call(pieces.payload, payload_arguments);
        b.push(Statement::Store { pointer, value });
    });
    b.push(Statement::If {
        condition: reuse,
        accept,
        reject,
    });
    b.expr(Expression::Load { pointer })
}

/// A pass's result type and, for colour + cache, the number of original
/// members before the cache member ([`output_type`]).
#[derive(Clone, Copy)]
struct Output {
    ty: Handle<naga::Type>,
    cache_member: Option<u32>,
}

/// What a pass returns from its payload and age: the cache texel, the
/// shaded colour, or both.
fn output_value(
    b: &mut Builder,
    module: &Module,
    pieces: &Pieces,
    stage: Stage,
    at: &Fragment,
    (payload, age): (Handle<Expression>, Handle<Expression>),
    output: Output,
) -> Result<Handle<Expression>, Refusal> {
    let frag_coord = at.frag_coord;
    Ok(match stage.writes() {
        Writes::Cache => {
            let cache = cache_texel(b, pieces, payload, frag_coord);
            let cache = b.call(pieces.encode, vec![cache]);
            b.expr(Expression::Compose {
                ty: output.ty,
                components: vec![cache, age],
            })
        }
        Writes::Classes
        | Writes::GBuffer
        | Writes::Samples
        | Writes::ColorAndHistory
        | Writes::Stencil => return Err(Refusal::internal(format!("{stage:?} writes no payload"))),
        Writes::Color => {
            let mut arguments = at.originals.clone();
            arguments.push(payload);
            b.call(pieces.shade, arguments)
        }
        Writes::ColorAndCache => shade_with_cache(
            b,
            module,
            pieces,
            (&at.originals, payload),
            (
                |b: &mut Builder| cache_texel(b, pieces, payload, frag_coord),
                age,
            ),
            (output.ty, output.cache_member),
        ),
    })
}

/// The shading from `payload`, then the original outputs, the encoded
/// cache texel (`cache` makes it, after the shading) and `second` (the
/// age, or lowres's history) as `output` (from [`color_and_cache_output`],
/// with its count of original members).
pub(super) fn shade_with_cache(
    b: &mut Builder,
    module: &Module,
    pieces: &Pieces,
    (originals, payload): (&[Handle<Expression>], Handle<Expression>),
    (cache, second): (
        impl FnOnce(&mut Builder) -> Handle<Expression>,
        Handle<Expression>,
    ),
    (ty, members): (Handle<naga::Type>, Option<u32>),
) -> Handle<Expression> {
    let mut arguments = originals.to_vec();
    arguments.push(payload);
    let color = b.call(pieces.shade, arguments);
    b.name(color, "color");
    let cache = cache(b);
    let cache = b.call(pieces.encode, vec![cache]);
    let mut components: Vec<_> = match members {
        Some(count) if count > 0 && is_struct(module, pieces.result.ty) => {
            (0..count).map(|i| b.member(color, i)).collect()
        }
        _ => vec![color],
    };
    components.push(cache);
    components.push(second);
    b.expr(Expression::Compose { ty, components })
}

fn f32_type(module: &mut Module) -> Handle<naga::Type> {
    module.types.insert(
        naga::Type {
            name: None,
            inner: TypeInner::Scalar(naga::Scalar::F32),
        },
        naga::Span::UNDEFINED,
    )
}

pub(super) fn is_struct(module: &Module, ty: Handle<naga::Type>) -> bool {
    matches!(module.types[ty].inner, TypeInner::Struct { .. })
}

/// The result type of a pass, and for colour + cache the number of
/// original members before the cache member.
fn output_type(
    module: &mut Module,
    pieces: &Pieces,
    writes: Writes,
) -> (Handle<naga::Type>, Option<u32>) {
    match writes {
        Writes::Classes
        | Writes::GBuffer
        | Writes::Samples
        | Writes::ColorAndHistory
        | Writes::Stencil => (pieces.vec4, None),
        Writes::Cache => {
            let f32_ty = f32_type(module);
            let ty = module.types.insert(
                naga::Type {
                    name: Some("CacheOutput".into()),
                    inner: TypeInner::Struct {
                        members: vec![
                            naga::StructMember {
                                name: Some("cache".into()),
                                ty: pieces.vec4,
                                binding: Some(location(0)),
                                offset: 0,
                            },
                            naga::StructMember {
                                name: Some("age".into()),
                                ty: f32_ty,
                                binding: Some(location(1)),
                                offset: 16,
                            },
                        ],
                        span: 32,
                    },
                },
                naga::Span::UNDEFINED,
            );
            (ty, None)
        }
        Writes::Color => (pieces.result.ty, None),
        Writes::ColorAndCache => {
            let f32_ty = f32_type(module);
            color_and_cache_output(module, pieces, f32_ty)
        }
    }
}

/// The original outputs, then the cache (`vec4<f32>`) at the first free
/// location and `second` at the next (the age, or lowres's history); with
/// the number of original members before the cache.
pub(super) fn color_and_cache_output(
    module: &mut Module,
    pieces: &Pieces,
    second: Handle<naga::Type>,
) -> (Handle<naga::Type>, Option<u32>) {
    let cache_at = cache_location(module, &pieces.result);
    let (mut members, span) = match module.types[pieces.result.ty].inner {
        TypeInner::Struct { ref members, span } => (members.clone(), span),
        _ => (
            vec![naga::StructMember {
                name: Some("color".into()),
                ty: pieces.result.ty,
                binding: pieces.result.binding.clone(),
                offset: 0,
            }],
            16,
        ),
    };
    let count = members.len() as u32;
    let offset = span.div_ceil(16) * 16;
    members.push(naga::StructMember {
        name: Some("cache".into()),
        ty: pieces.vec4,
        binding: Some(location(cache_at)),
        offset,
    });
    let second_is_vec4 = second == pieces.vec4;
    members.push(naga::StructMember {
        name: Some(if second_is_vec4 { "history" } else { "age" }.into()),
        ty: second,
        binding: Some(location(cache_at + 1)),
        offset: offset + 16,
    });
    let ty = module.types.insert(
        naga::Type {
            name: Some("CacheFragmentOutput".into()),
            inner: TypeInner::Struct {
                members,
                span: offset + 32,
            },
        },
        naga::Span::UNDEFINED,
    );
    (ty, Some(count))
}

/// Looks the fragment up in last frame's cache and decides whether to
/// reuse it: `lookup.hit && !refresh`. Returns the lookup and the decision.
fn reuse_condition(
    b: &mut Builder,
    pieces: &Pieces,
    previous: Handle<Expression>,
    frag_coord: Handle<Expression>,
) -> (Handle<Expression>, Handle<Expression>) {
    let lookup = b.call(pieces.lookup, vec![previous]);
    let age = b.member(lookup, 3);
    let refresh = b.call(pieces.refresh, vec![frag_coord, age]);
    let hit = b.member(lookup, 1);
    let fresh = b.expr(Expression::Unary {
        op: naga::UnaryOperator::LogicalNot,
        expr: refresh,
    });
    let reuse = b.expr(Expression::Binary {
        op: naga::BinaryOperator::LogicalAnd,
        left: hit,
        right: fresh,
    });
    b.name(lookup, "lookup");
    b.name(refresh, "refresh");
    b.name(reuse, "reuse");
    (lookup, reuse)
}

/// The payload's own type from the cache's `vec4<f32>`.
pub(super) fn from_vec4(
    b: &mut Builder,
    value: Handle<Expression>,
    components: u32,
) -> Handle<Expression> {
    use naga::SwizzleComponent as S;
    let pattern = [S::X, S::Y, S::Z, S::W];
    match components {
        1 => b.member(value, 0),
        2 => b.expr(Expression::Swizzle {
            size: naga::VectorSize::Bi,
            vector: value,
            pattern,
        }),
        3 => b.expr(Expression::Swizzle {
            size: naga::VectorSize::Tri,
            vector: value,
            pattern,
        }),
        _ => value,
    }
}

/// What the cache keeps of `payload`: padded to a `vec4<f32>`, with the
/// fragment's depth in the fourth channel when the reconstruction packs it.
fn cache_texel(
    b: &mut Builder,
    pieces: &Pieces,
    payload: Handle<Expression>,
    frag_coord: Handle<Expression>,
) -> Handle<Expression> {
    let cache = to_vec4(b, payload, pieces.components, pieces.vec4);
    match pieces.pack {
        Some(pack) => b.call(pack, vec![cache, frag_coord]),
        None => cache,
    }
}

/// The payload padded with zeros to the cache's `vec4<f32>`.
pub(super) fn to_vec4(
    b: &mut Builder,
    value: Handle<Expression>,
    components: u32,
    vec4: Handle<naga::Type>,
) -> Handle<Expression> {
    if components >= 4 {
        return value;
    }
    let mut parts = vec![value];
    for _ in components..4 {
        parts.push(b.literal_f32(0.0));
    }
    b.expr(Expression::Compose {
        ty: vec4,
        components: parts,
    })
}

#[derive(Clone, Copy, Debug)]
enum FragCoord {
    Argument(u32),
    Member(u32, u32),
}

/// Whether a binding is `@builtin(position)`, invariant or not.
pub(crate) fn is_position(binding: &Option<Binding>) -> bool {
    matches!(
        binding,
        Some(Binding::BuiltIn(naga::BuiltIn::Position { .. }))
    )
}

/// Where the original arguments carry `@builtin(position)`, if they do.
fn find_frag_coord(module: &Module, arguments: &[naga::FunctionArgument]) -> Option<FragCoord> {
    for (i, argument) in arguments.iter().enumerate() {
        if is_position(&argument.binding) {
            return Some(FragCoord::Argument(i as u32));
        }
        if let TypeInner::Struct { ref members, .. } = module.types[argument.ty].inner {
            if let Some(m) = members.iter().position(|m| is_position(&m.binding)) {
                return Some(FragCoord::Member(i as u32, m as u32));
            }
        }
    }
    None
}

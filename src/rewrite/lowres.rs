//! The lowres variant's passes: spatio-temporal upsampling of the payload
//! (seed 001, Herzog et al. 2010).
//!
//! Pass 1 draws the geometry at 1/s × 1/s of the pixels with the
//! projection jittered (`cache_jitter`), so that each low-resolution pixel
//! shades the full-resolution pixel centre s·a + offset, the offset
//! stepping through the s×s window in a Bayer order (`cache_sample_offset`).
//! It writes the payload (the samples) and the samples' geometry: normal,
//! view depth, the draw's id, and the relative temporal gradient against
//! last frame's result where the sample's point was. Its texture reads
//! see derivatives s times too large, so their level of detail is biased
//! by −log2 s and explicit derivatives are divided by s.
//! Its `@builtin(position)` is the low-resolution pixel's in x and y; no
//! payload reads those (the analysis rejects screen-space nodes: a cached
//! value would be reprojected onto other pixels), and its z and w are the
//! full-resolution fragment's, since the jitter moves x and y alone.
//!
//! Pass 2 draws the geometry at full resolution: it rebuilds the payload
//! at each pixel from the four nearest samples and the reprojected
//! history (`cache_upsample`: nearest, bilinear, spatial, temporal or
//! spatio-temporal), shades with it, and writes the result and its
//! history for the next frame.
//!
//! Deferred lowres (`deferred-lowres`) is the paper's pipeline: the
//! geometry is drawn once, into the deferred variant's G-buffer
//! ([`super::gbuffer`], which then also keeps the fragment's w, the
//! interpolated normal and the draw's ordinal), and the passes above
//! run in screen space, one triangle over the screen per draw. The
//! samples pass, at 1/s × 1/s, reads the G-buffer at the lattice pixel
//! s·a + offset (`cache_lattice_pixel`): no jitter, and its fragment
//! position is that pixel's at full resolution. The draws' stencil is the
//! full frame's and cannot be tested at 1/s, so a pass before it (the
//! lattice) marks a stencil of the samples' size: each draw keeps the
//! lattice pixels whose G-buffer ordinal is its own and discards the rest,
//! with nothing after the kill. The upsampling and the reshading are
//! drawn on each draw's pixels of the frame's stencil, as the deferred
//! variant's passes are.

use naga::{Binding, Expression, Function, Handle, Module, Statement, TypeInner};

use super::builder::{location, Builder};
use super::copy::FunctionCopy;
use super::fragment::{self, Inputs};
use super::helpers::{LowresHelpers, Pieces};
use super::stage::{LowresStage, Stage};
use super::Refusal;
use crate::analysis::graph::ExprSet;
use crate::plan::{DepthTolerance, GradientFilter, Upsampler, Upsampling};

/// Lowres's passes: the samples, the upsampling, and with adaptive
/// refresh the reshading of the pixels it cannot vouch for. `deferred`,
/// the G-buffer pass and the lattice's stencil come first, and the rest
/// run in screen space.
pub(crate) fn stages(upsampling: &Upsampling, deferred: bool) -> Vec<Stage> {
    let mut stages = Vec::new();
    if deferred {
        stages.extend([Stage::GBuffer, Stage::Lowres(LowresStage::Lattice)]);
    }
    stages.extend([LowresStage::Samples, LowresStage::Upsample].map(Stage::Lowres));
    if upsampling.shades_leftovers() {
        stages.push(Stage::Lowres(LowresStage::Reshade));
    }
    stages
}

/// Why lowres cannot be built on a module without its vertex stage.
pub(crate) const NEEDS_VERTEX_STAGE: &str = "lowres shades its samples with the projection jittered in the vertex stage, and this module has no vertex stage (it is composed with the host's): give the module with the vertex stage (`--vertex FILE`, `Build::vertex_shader`) so the rewrite can jitter it";

/// The fragment entry point of lowres's pass `stage`, drawn over the
/// geometry (`Inputs::Varyings`) or in screen space from the G-buffer.
pub(super) fn entry(
    module: &mut Module,
    pieces: &Pieces,
    stage: LowresStage,
    upsampling: &Upsampling,
    inputs: Inputs,
) -> Result<Function, Refusal> {
    let helpers = &pieces.lowres;
    match stage {
        LowresStage::Lattice => lattice_entry(pieces, helpers, inputs),
        LowresStage::Samples => samples_entry(module, pieces, helpers, upsampling, inputs),
        LowresStage::Upsample => upsample_entry(module, pieces, helpers, upsampling, inputs),
        LowresStage::Reshade => reshade_entry(module, pieces, helpers, inputs),
    }
}

/// The history where the fragment was (`before`, `hit`): looked up where
/// the reconstruction reads it, else a miss that costs nothing.
fn history(
    b: &mut Builder,
    pieces: &Pieces,
    previous: Handle<Expression>,
    upsampler: Upsampler,
) -> (Handle<Expression>, Handle<Expression>) {
    if upsampler.reads_history() {
        let lookup = b.call(pieces.lowres.history, vec![previous]);
        (b.member(lookup, 0), b.member(lookup, 1))
    } else {
        let before = b.expr(Expression::ZeroValue(pieces.vec4));
        let hit = b.expr(Expression::Literal(naga::Literal::Bool(false)));
        (before, hit)
    }
}

/// `cache_upsample`'s mode for `upsampling`: its reconstruction, and the
/// flags of the paper's gradient filter, of hole filling, of σz of the
/// depth range and of material ids (`CACHE_MODE_*` in
/// `shaders/cache.wgsl`).
fn mode(upsampling: &Upsampling) -> u32 {
    let reconstruction = match upsampling.reconstruction {
        Upsampler::Nearest => 0,
        Upsampler::Bilinear => 1,
        Upsampler::Spatial => 2,
        Upsampler::Temporal => 3,
        Upsampler::SpatioTemporal => 4,
    };
    let paper_gradient = upsampling.gradient_filter == GradientFilter::Paper;
    let of_range = upsampling.depth_tolerance == DepthTolerance::OfRange;
    reconstruction
        | (u32::from(paper_gradient) << 8)
        | (u32::from(upsampling.fill_holes) << 9)
        | (u32::from(of_range) << 10)
        | (u32::from(upsampling.material_ids) << 11)
}

/// Where the fragment's normal comes from: an input the shader
/// interpolates (an argument or a struct member whose name says normal),
/// else the geometry's derivatives.
#[derive(Clone, Copy, Debug)]
enum NormalSource {
    Argument(u32),
    Member(u32, u32),
    Geometric,
}

/// The input the normal is read from (argument, struct member), if the
/// shader interpolates one: the deferred lowres's G-buffer keeps it.
pub(crate) fn normal_input(
    module: &Module,
    arguments: &[naga::FunctionArgument],
) -> Option<(u32, Option<u32>)> {
    match normal_source(module, arguments) {
        NormalSource::Argument(i) => Some((i, None)),
        NormalSource::Member(i, m) => Some((i, Some(m))),
        NormalSource::Geometric => None,
    }
}

/// The shader's interpolated normal: a `vec3<f32>` input at a location
/// whose name contains "normal" (`world_normal`, `v_normal`, `N`-less
/// engines fall back to the geometry).
fn normal_source(module: &Module, arguments: &[naga::FunctionArgument]) -> NormalSource {
    let is_normal = |name: &Option<String>, ty: Handle<naga::Type>, binding: &Option<Binding>| {
        let vec3 = matches!(
            module.types[ty].inner,
            TypeInner::Vector {
                size: naga::VectorSize::Tri,
                scalar: naga::Scalar::F32
            }
        );
        vec3 && matches!(binding, Some(Binding::Location { .. }))
            && name
                .as_deref()
                .is_some_and(|n| n.to_ascii_lowercase().contains("normal"))
    };
    for (i, argument) in arguments.iter().enumerate() {
        if is_normal(&argument.name, argument.ty, &argument.binding) {
            return NormalSource::Argument(i as u32);
        }
        if let TypeInner::Struct { ref members, .. } = module.types[argument.ty].inner {
            if let Some(m) = members
                .iter()
                .position(|m| is_normal(&m.name, m.ty, &m.binding))
            {
                return NormalSource::Member(i as u32, m as u32);
            }
        }
    }
    NormalSource::Geometric
}

/// The fragment's unit normal, computed first in the entry point (the
/// geometric one takes derivatives, so it must be in uniform control
/// flow; nothing before it branches).
fn normal(
    b: &mut Builder,
    module: &Module,
    pieces: &Pieces,
    helpers: &LowresHelpers,
    (originals, frag_coord): (&[Handle<Expression>], Handle<Expression>),
    low: bool,
) -> Handle<Expression> {
    let n = match normal_source(module, &pieces.arguments) {
        NormalSource::Argument(i) => {
            let raw = originals[i as usize];
            b.call(helpers.unit_normal, vec![raw])
        }
        NormalSource::Member(i, m) => {
            let raw = b.member(originals[i as usize], m);
            b.call(helpers.unit_normal, vec![raw])
        }
        NormalSource::Geometric => {
            let low = b.expr(Expression::Literal(naga::Literal::Bool(low)));
            b.call(helpers.geometric_normal, vec![frag_coord, low])
        }
    };
    b.name(n, "normal");
    n
}

/// Which pixel a screen-space pass reads: its own, or (the samples, at
/// 1/s × 1/s) the pixel of this frame's lattice it shades.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pixel {
    Own,
    Lattice,
}

/// A fragment entry point returning `output`: its builder and what it
/// reads. Drawn over the geometry, its arguments are the original's and
/// (where `reprojects`) the previous clip position; in screen space, the
/// fragment position alone, the rest read from the G-buffer at `pixel`.
fn entry_builder(
    module: &mut Module,
    pieces: &Pieces,
    (inputs, pixel): (Inputs, Pixel),
    reprojects: bool,
    output: Handle<naga::Type>,
) -> (Builder, fragment::Fragment) {
    let function = |arguments| Function {
        name: Some(pieces.name.clone()),
        arguments,
        result: Some(naga::FunctionResult {
            ty: output,
            binding: None,
        }),
        ..Function::default()
    };
    match inputs {
        Inputs::Varyings => {
            let (arguments, at) = fragment::varying_arguments(module, pieces, reprojects);
            let mut b = Builder::new(function(arguments));
            let frag = fragment::read_varyings(&mut b, &at);
            (b, frag)
        }
        Inputs::Screen(screen) => {
            let mut b = Builder::new(function(vec![fragment::frag_coord_argument(pieces.vec4)]));
            let frag = match pixel {
                Pixel::Own => screen.read(&mut b, module, pieces),
                Pixel::Lattice => {
                    let low = b.argument(0);
                    let xy = b.call(pieces.lowres.lattice_pixel, vec![low]);
                    screen.read_at(&mut b, module, pieces, xy)
                }
            };
            (b, frag)
        }
    }
}

/// In screen space, before the samples: each draw, drawn over the
/// samples' stencil, keeps the pixels of the lattice where the G-buffer
/// holds its ordinal (the stencil replaces there) and discards the rest.
/// Nothing follows the kill.
fn lattice_entry(
    pieces: &Pieces,
    helpers: &LowresHelpers,
    inputs: Inputs,
) -> Result<Function, Refusal> {
    let Inputs::Screen(screen) = inputs else {
        return Err(Refusal::internal(
            "the lattice's stencil is a screen-space pass",
        ));
    };
    let mut b = Builder::new(Function {
        name: Some(pieces.name.clone()),
        arguments: vec![fragment::frag_coord_argument(pieces.vec4)],
        ..Function::default()
    });
    let low = b.argument(0);
    let xy = b.call(helpers.lattice_pixel, vec![low]);
    let ordinal = screen
        .ordinal_at(&mut b, xy)
        .ok_or_else(|| Refusal::internal("the G-buffer keeps no draw ordinals"))?;
    let own = b.call(helpers.draw_id, Vec::new());
    let mine = b.expr(Expression::Binary {
        op: naga::BinaryOperator::Equal,
        left: ordinal,
        right: own,
    });
    fragment::kill_unless(&mut b, mine);
    b.push(Statement::Return { value: None });
    Ok(b.finish())
}

fn literal_u32(b: &mut Builder, value: u32) -> Handle<Expression> {
    b.expr(Expression::Literal(naga::Literal::U32(value)))
}

/// Pass 1's fragment entry point: the payload with its level of detail
/// biased by −log2 s, written to the samples (location 0), and the
/// sample's geometry texel (location 1).
fn samples_entry(
    module: &mut Module,
    pieces: &Pieces,
    helpers: &LowresHelpers,
    upsampling: &Upsampling,
    inputs: Inputs,
) -> Result<Function, Refusal> {
    let payload = if upsampling.lod_bias {
        biased_payload(module, pieces.payload, upsampling.factor)?
    } else {
        pieces.payload
    };
    let output = two_member_output(module, "LowresSamples", pieces.vec4, pieces.vec4);
    let (mut b, frag) = entry_builder(module, pieces, (inputs, Pixel::Lattice), true, output);
    let previous = frag
        .previous
        .ok_or_else(|| Refusal::internal("the samples pass reads no previous clip position"))?;
    // In screen space the fragment position is the lattice pixel's, at
    // full resolution.
    let low = matches!(inputs, Inputs::Varyings);
    let n = normal(
        &mut b,
        module,
        pieces,
        helpers,
        (&frag.originals, frag.frag_coord),
        low,
    );
    let value = b.call(payload, frag.originals.clone());
    let value = fragment::to_vec4(&mut b, value, pieces.components, pieces.vec4);
    b.name(value, "sample");
    let (before, hit) = history(&mut b, pieces, previous, upsampling.reconstruction);
    let components = literal_u32(&mut b, pieces.components);
    let geometry = b.call(
        helpers.sample_texel,
        vec![value, n, frag.frag_coord, before, hit, components],
    );
    let encoded = b.call(pieces.encode, vec![value]);
    let result = b.expr(Expression::Compose {
        ty: output,
        components: vec![encoded, geometry],
    });
    b.push(Statement::Return {
        value: Some(result),
    });
    Ok(b.finish())
}

/// Pass 2's fragment entry point: the payload rebuilt by
/// `cache_upsample`, the shading from it, and the result and history
/// written after the original outputs (the cache at the first free
/// location, the history at the next).
fn upsample_entry(
    module: &mut Module,
    pieces: &Pieces,
    helpers: &LowresHelpers,
    upsampling: &Upsampling,
    inputs: Inputs,
) -> Result<Function, Refusal> {
    let (reconstruction, reshade) = (upsampling.reconstruction, upsampling.shades_leftovers());
    let mode = mode(upsampling);
    let output = fragment::color_and_cache_output(module, pieces, pieces.vec4);
    let (mut b, frag) = entry_builder(module, pieces, (inputs, Pixel::Own), true, output.0);
    let previous = frag
        .previous
        .ok_or_else(|| Refusal::internal("the upsampling pass reads no previous clip position"))?;
    let n = normal(
        &mut b,
        module,
        pieces,
        helpers,
        (&frag.originals, frag.frag_coord),
        false,
    );
    let (before, hit) = history(&mut b, pieces, previous, reconstruction);
    let mode = literal_u32(&mut b, mode);
    let components = literal_u32(&mut b, pieces.components);
    let upsampled = b.call(
        helpers.upsample,
        vec![mode, components, frag.frag_coord, n, before, hit, previous],
    );
    b.name(upsampled, "upsampled");
    let value = b.member(upsampled, 0);
    let history = b.member(upsampled, 1);
    let payload = fragment::from_vec4(&mut b, value, pieces.components);
    let result = fragment::shade_with_cache(
        &mut b,
        module,
        pieces,
        (&frag.originals, payload),
        (|_: &mut Builder| value, history),
        output,
    );
    // Adaptive refresh: the unreliable pixels are left to the third pass.
    // The kill comes last, after the shading's derivatives (naga writes
    // `discard` as OpKill, which ends the invocation).
    if reshade {
        let unreliable = b.member(upsampled, 2);
        let kept = b.expr(Expression::Unary {
            op: naga::UnaryOperator::LogicalNot,
            expr: unreliable,
        });
        fragment::kill_unless(&mut b, kept);
    }
    b.push(Statement::Return {
        value: Some(result),
    });
    Ok(b.finish())
}

/// Pass 3 with adaptive refresh: the original payload at full resolution
/// where pass 2 discarded (the depth test passes only there), the shading
/// from it, the payload and an exact history (weight 1, gradient 0).
fn reshade_entry(
    module: &mut Module,
    pieces: &Pieces,
    helpers: &LowresHelpers,
    inputs: Inputs,
) -> Result<Function, Refusal> {
    let output = fragment::color_and_cache_output(module, pieces, pieces.vec4);
    let (mut b, frag) = entry_builder(module, pieces, (inputs, Pixel::Own), false, output.0);
    let payload = b.call(pieces.payload, frag.originals.clone());
    let value = fragment::to_vec4(&mut b, payload, pieces.components, pieces.vec4);
    let history = b.call(helpers.exact_history, Vec::new());
    let result = fragment::shade_with_cache(
        &mut b,
        module,
        pieces,
        (&frag.originals, payload),
        (|_: &mut Builder| value, history),
        output,
    );
    b.push(Statement::Return {
        value: Some(result),
    });
    Ok(b.finish())
}

/// A struct of two `vec4<f32>` outputs at locations 0 and 1.
fn two_member_output(
    module: &mut Module,
    name: &str,
    first: Handle<naga::Type>,
    second: Handle<naga::Type>,
) -> Handle<naga::Type> {
    let member = |name: &str, ty, at: u32| naga::StructMember {
        name: Some(name.into()),
        ty,
        binding: Some(location(at)),
        offset: at * 16,
    };
    module.types.insert(
        naga::Type {
            name: Some(name.into()),
            inner: TypeInner::Struct {
                members: vec![member("samples", first, 0), member("geometry", second, 1)],
                span: 32,
            },
        },
        naga::Span::UNDEFINED,
    )
}

/// A copy of the payload function for the samples pass, where every
/// derivative is s times what it is at full resolution: implicit-LOD
/// samples get a bias of −log2 s (added to an explicit bias), explicit
/// gradients and `dpdx`/`dpdy`/`fwidth` are divided by s. Reads in
/// functions the payload calls are not reached (a texture sampled in a
/// helper keeps its level, one mip coarser per factor of two).
fn biased_payload(
    module: &mut Module,
    payload: Handle<Function>,
    factor: u32,
) -> Result<Handle<Function>, Refusal> {
    let source = module.functions[payload].clone();
    let mut live = ExprSet::with_capacity(source.expressions.len());
    live.insert_range(..);
    let bias = -(factor as f32).log2();
    let scale = 1.0 / factor as f32;
    let src = &source;
    let biased = {
        let mut copy = FunctionCopy::new(
            module,
            &source,
            &live,
            Function {
                name: source.name.as_ref().map(|n| format!("{n}_lowres")),
                arguments: source.arguments.clone(),
                result: source.result.clone(),
                ..Function::default()
            },
        );
        for (handle, expr) in source.expressions.iter() {
            match *expr {
                Expression::ImageSample {
                    level: naga::SampleLevel::Auto | naga::SampleLevel::Bias(_),
                    depth_ref: None,
                    gather: None,
                    ..
                } => copy.rebuild(
                    handle,
                    Box::new(move |copy: &mut FunctionCopy| {
                        let mut sample =
                            crate::proc::remap::expression(&src.expressions[handle], copy);
                        if let Expression::ImageSample { ref mut level, .. } = sample {
                            let lod = copy.add(Expression::Literal(naga::Literal::F32(bias)));
                            *level = match *level {
                                naga::SampleLevel::Bias(b) => {
                                    naga::SampleLevel::Bias(copy.add(Expression::Binary {
                                        op: naga::BinaryOperator::Add,
                                        left: b,
                                        right: lod,
                                    }))
                                }
                                _ => naga::SampleLevel::Bias(lod),
                            };
                        }
                        sample
                    }),
                ),
                Expression::ImageSample {
                    level: naga::SampleLevel::Gradient { .. },
                    ..
                } => copy.rebuild(
                    handle,
                    Box::new(move |copy: &mut FunctionCopy| {
                        let mut sample =
                            crate::proc::remap::expression(&src.expressions[handle], copy);
                        if let Expression::ImageSample {
                            level:
                                naga::SampleLevel::Gradient {
                                    ref mut x,
                                    ref mut y,
                                },
                            ..
                        } = sample
                        {
                            let k = copy.add(Expression::Literal(naga::Literal::F32(scale)));
                            *x = scaled(copy, *x, k);
                            *y = scaled(copy, *y, k);
                        }
                        sample
                    }),
                ),
                Expression::Derivative { .. } => copy.rebuild(
                    handle,
                    Box::new(move |copy: &mut FunctionCopy| {
                        let derivative =
                            crate::proc::remap::expression(&src.expressions[handle], copy);
                        let d = copy.add(derivative);
                        let k = copy.add(Expression::Literal(naga::Literal::F32(scale)));
                        Expression::Binary {
                            op: naga::BinaryOperator::Multiply,
                            left: d,
                            right: k,
                        }
                    }),
                ),
                _ => {}
            }
        }
        copy.run()
    };
    Ok(module.functions.append(biased, naga::Span::UNDEFINED))
}

fn scaled(
    copy: &mut FunctionCopy,
    value: Handle<Expression>,
    k: Handle<Expression>,
) -> Handle<Expression> {
    copy.add(Expression::Binary {
        op: naga::BinaryOperator::Multiply,
        left: value,
        right: k,
    })
}

/// Wraps a pass's vertex entry point so that its clip position is
/// jittered for the samples pass: the original entry becomes a function
/// the new entry calls, and the position it returns goes through
/// `cache_jitter`.
pub(crate) fn jitter_vertex(
    module: &mut Module,
    entry: &mut naga::EntryPoint,
    jitter: Handle<Function>,
) -> Result<(), Refusal> {
    let original = entry.function.clone();
    let result = original
        .result
        .clone()
        .ok_or_else(|| Refusal::internal("the vertex entry point returns nothing"))?;
    let position_member = match module.types[result.ty].inner {
        TypeInner::Struct { ref members, .. } => Some(
            members
                .iter()
                .position(|m| fragment::is_position(&m.binding))
                .ok_or_else(|| {
                    Refusal::internal("the vertex stage's output has no @builtin(position)")
                })? as u32,
        ),
        _ => None,
    };
    let mut helper = original.clone();
    helper.name = Some(format!("{}_unjittered", entry.name));
    helper.arguments = super::without_bindings(&original.arguments);
    helper.result = Some(naga::FunctionResult {
        ty: result.ty,
        binding: None,
    });
    let helper = module.functions.append(helper, naga::Span::UNDEFINED);
    let mut b = Builder::new(Function {
        name: original.name.clone(),
        arguments: original.arguments.clone(),
        result: Some(result.clone()),
        ..Function::default()
    });
    let arguments = (0..original.arguments.len() as u32)
        .map(|i| b.argument(i))
        .collect();
    let out = b.call(helper, arguments);
    let value = match position_member {
        None => b.call(jitter, vec![out]),
        Some(at) => {
            let TypeInner::Struct { ref members, .. } = module.types[result.ty].inner else {
                return Err(Refusal::internal(
                    "the vertex output stopped being a struct",
                ));
            };
            let count = members.len() as u32;
            let mut components = Vec::new();
            for i in 0..count {
                let member = b.member(out, i);
                components.push(if i == at {
                    b.call(jitter, vec![member])
                } else {
                    member
                });
            }
            b.expr(Expression::Compose {
                ty: result.ty,
                components,
            })
        }
    };
    b.push(Statement::Return { value: Some(value) });
    entry.function = b.finish();
    Ok(())
}

/// The offset (x, y) within every s×s window that phase p samples: the
/// CPU's statement of `cache_sample_offset` (`shaders/cache.wgsl`), the
/// Bayer order M(x, y) = reverse(interleave(x ^ y, y)) inverted. s is a
/// power of two.
pub fn sample_offset(phase: u32, s: u32) -> (u32, u32) {
    let bits = s.max(1).trailing_zeros();
    let reversed = if bits == 0 {
        0
    } else {
        phase.reverse_bits() >> (32 - 2 * bits)
    };
    let (mut a, mut b) = (0, 0);
    for i in 0..bits {
        a |= ((reversed >> (2 * i)) & 1) << i;
        b |= ((reversed >> (2 * i + 1)) & 1) << i;
    }
    (a ^ b, b)
}

#[cfg(test)]
mod tests {
    use super::sample_offset;

    /// The host keeps the phase as frame mod s² (`set_frame_counter`, then
    /// +1 mod s² a frame): any s² consecutive frames sample each offset of
    /// the window once, across the u32 frame counter's wrap as anywhere.
    #[test]
    fn jitter_covers_every_pixel_every_s2_frames() {
        for s in [2u32, 4] {
            let period = u64::from(s * s);
            for start in [0u64, 5, (1 << 32) - 16, (1 << 32) - 7, u64::MAX - 20] {
                let mut seen = std::collections::HashSet::new();
                for frame in start..start + period {
                    let (x, y) = sample_offset((frame % period) as u32, s);
                    assert!(x < s && y < s, "s = {s}: ({x}, {y})");
                    seen.insert((x, y));
                }
                assert_eq!(seen.len() as u64, period, "s = {s}, from frame {start}");
            }
        }
        // The paper's 4×4 order is lost; ours is Bayer's.
        let bayer = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];
        for (y, row) in bayer.iter().enumerate() {
            for (x, &phase) in row.iter().enumerate() {
                assert_eq!(sample_offset(phase, 4), (x as u32, y as u32));
            }
        }
    }
}

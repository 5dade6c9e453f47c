//! The deferred variant's G-buffer: what its one geometry pass keeps of
//! each visible fragment, so that the lookup, the misses and the shading
//! run in screen space without drawing the geometry again.
//!
//! The geometry pass runs the instrumented vertex stage (with its
//! previous-frame twin) and a fragment stage that only stores: last
//! frame's NDC, the fragment position's depth and w where they are read,
//! and every input of the original fragment entry point that the payload
//! and shade functions read — varyings, `front_facing`, `primitive_index` — as
//! 32-bit words, bit for bit (`bitcast`), packed into as few `r32uint`,
//! `rg32uint` or `rgba32uint` targets as hold them. Integer targets keep
//! every bit: a NaN varying stays the NaN it was, an `i32` id its value.
//!
//! Where the fragment stage can `discard` (an alpha test), the geometry
//! pass also calls the payload and the shade for their discards, so that
//! its depth and stencil hold the pixels the original covers.
//!
//! A screen-space pass draws one triangle over the screen per draw of the
//! application (the stencil holds each draw's ordinal, so the draw's own
//! bind groups shade its own pixels) and rebuilds the original inputs
//! from the G-buffer at its pixel: the same values the original fragment
//! stage received, so at Δn = 1 the variant draws the reference. The
//! fragment position's x and y are the pixel centre, as in the original.
//!
//! Derivatives in the screen-space passes (`dpdx`, `fwidth`, the implicit
//! level of detail of `textureSample`) are taken of the values rebuilt
//! from the G-buffer, in uniform control flow, across the 2×2 quads of
//! the screen: inside a surface they are the original's (a varying is
//! linear across a triangle, and its neighbour pixels hold the same
//! plane's values); at a silhouette the neighbour holds another surface,
//! or nothing, where the original extrapolated its own triangle with a
//! helper invocation. The derivative there is the difference across the
//! edge.

use std::collections::{BTreeMap, BTreeSet};

use naga::{
    Binding, Expression, Function, Handle, Module, Scalar, ScalarKind, Statement, TypeInner,
    VectorSize,
};

use super::builder::{scalar_type, vector_type, Builder};
use super::fragment::{self, Fragment};
use super::helpers::Pieces;
use super::lowres;
use super::Refusal;
use crate::plan::TextureFormat;

/// WebGPU's `maxColorAttachments`: eight targets of four words at most.
const MAX_TARGETS: u32 = 8;

/// How the G-buffer of one rewrite is laid out, and the module's pieces
/// that read and write it.
#[derive(Debug)]
pub struct GBuffer {
    leaves: Vec<Leaf>,
    /// What each word holds, in words.
    pub holds: Vec<String>,
    /// Each texture's format, by index (= location in the geometry pass).
    pub formats: Vec<TextureFormat>,
    /// Each texture's global variable ([`texture_name`]), read by the
    /// screen-space passes.
    textures: Vec<Handle<naga::GlobalVariable>>,
    /// The vertex stage of the screen-space passes: one triangle over the
    /// screen, from the vertex index.
    pub fullscreen: naga::EntryPoint,
    /// The words of the fragment position's z and w, where kept.
    depth_word: Option<u32>,
    w_word: Option<u32>,
    /// The word of the draw's ordinal, where kept (deferred lowres).
    ordinal_word: Option<u32>,
    /// The fragment stage can `discard`: the geometry pass runs the
    /// payload and the shade for their discards alone (their values
    /// unused, so a compiler keeps only what decides the discard), and the
    /// stencil then holds only the pixels the original covers.
    coverage_by_shading: bool,
    /// Where the textures are bound: `group`, from `first_binding` on.
    pub group: u32,
    pub first_binding: u32,
}

/// What a G-buffer keeps beyond the inputs the payload and the shade
/// read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Keeps {
    /// The fragment position's depth (a packed cache read compares it).
    pub depth: bool,
    /// Lowres's geometry in screen space: the fragment position's w (its
    /// weights compare view depths, 1/w), the interpolated normal they
    /// compare, and the draw's ordinal, which tells the draws apart at the
    /// samples' size.
    pub lowres: bool,
}

/// One input of the original fragment entry point: an argument, or a
/// member of a struct argument.
#[derive(Debug)]
struct Leaf {
    argument: u32,
    member: Option<u32>,
    ty: Handle<naga::Type>,
    stored: Stored,
}

#[derive(Debug)]
enum Stored {
    /// Not read by the payload or the shade: a zero stands in.
    Unread,
    /// `@builtin(position)`: the pixel centre and the stored z and w.
    Position,
    /// `@builtin(front_facing)`: one word, 0 or 1.
    FrontFacing { word: u32 },
    /// A number or a vector of them, a word per component.
    Words {
        first: u32,
        scalar: Scalar,
        size: Option<VectorSize>,
    },
}

/// How many of a struct argument's members the functions read: all of
/// it (passed on whole), or some members.
#[derive(Debug)]
enum Read {
    Whole,
    Members(BTreeSet<u32>),
}

impl Read {
    /// Whether `member` (`None`: the argument itself) is read.
    fn includes(read: Option<&Read>, member: Option<u32>) -> bool {
        match (read, member) {
            (None, _) => false,
            (Some(Read::Whole), _) | (Some(_), None) => true,
            (Some(Read::Members(set)), Some(m)) => set.contains(&m),
        }
    }
}

/// An input of the original fragment entry point as the G-buffer sees it,
/// before its words are laid out.
struct Input {
    argument: u32,
    member: Option<u32>,
    binding: Option<Binding>,
    ty: Handle<naga::Type>,
    label: String,
    is_read: bool,
}

/// Every input of the original entry point, a struct argument's members
/// each on its own, with whether the functions read it.
fn inputs(module: &Module, pieces: &Pieces, read: &BTreeMap<u32, Read>) -> Vec<Input> {
    let mut inputs = Vec::new();
    for (index, argument) in pieces.arguments.iter().enumerate() {
        let index = index as u32;
        let name = argument
            .name
            .clone()
            .unwrap_or_else(|| format!("argument{index}"));
        let read = read.get(&index);
        match module.types[argument.ty].inner {
            TypeInner::Struct { ref members, .. } => {
                inputs.extend(members.iter().enumerate().map(|(m, member)| Input {
                    argument: index,
                    member: Some(m as u32),
                    binding: member.binding.clone(),
                    ty: member.ty,
                    label: format!(
                        "{name}.{}",
                        member.name.clone().unwrap_or_else(|| m.to_string())
                    ),
                    is_read: Read::includes(read, Some(m as u32)),
                }))
            }
            _ => inputs.push(Input {
                argument: index,
                member: None,
                binding: argument.binding.clone(),
                ty: argument.ty,
                label: name,
                is_read: Read::includes(read, None),
            }),
        }
    }
    inputs
}

impl GBuffer {
    /// Lays out the G-buffer for `pieces` and declares its textures in
    /// `group` from `first_binding` on. Refuses inputs a G-buffer cannot
    /// hold, and inputs beyond eight targets.
    ///
    /// The words: last frame's position in NDC (x, y, z: the clip
    /// position divided by w in the geometry pass, as the lookup would
    /// divide it, so the lookup sees the same numbers), the fragment's
    /// depth where the shader reads `@builtin(position)` or the cache
    /// packs the depth, its w where the shader reads the position, then
    /// the inputs read.
    pub fn new(
        module: &mut Module,
        pieces: &Pieces,
        keeps: Keeps,
        (group, first_binding): (u32, u32),
    ) -> Result<GBuffer, Refusal> {
        let mut read = arguments_read(module, pieces);
        if keeps.lowres {
            if let Some((argument, member)) = lowres::normal_input(module, &pieces.arguments) {
                note_read(&mut read, argument, member);
            }
        }
        let inputs = inputs(module, pieces, &read);
        let reads_position = inputs
            .iter()
            .any(|input| input.is_read && fragment::is_position(&input.binding));
        let mut holds: Vec<String> = ["previous_ndc.x", "previous_ndc.y", "previous_ndc.z"]
            .map(String::from)
            .to_vec();
        let mut keep = |kept: bool, what: &str| {
            kept.then(|| {
                holds.push(what.into());
                holds.len() as u32 - 1
            })
        };
        let depth_word = keep(reads_position || keeps.depth, "position.z");
        let w_word = keep(reads_position || keeps.lowres, "position.w");
        let ordinal_word = keep(keeps.lowres, "draw ordinal");
        let leaves = inputs
            .into_iter()
            .map(|input| {
                let stored = store(
                    module,
                    &input.binding,
                    input.ty,
                    input.is_read,
                    &input.label,
                    &mut holds,
                )?;
                Ok(Leaf {
                    argument: input.argument,
                    member: input.member,
                    ty: input.ty,
                    stored,
                })
            })
            .collect::<Result<Vec<_>, Refusal>>()?;
        let words = holds.len() as u32;
        if words > MAX_TARGETS * 4 {
            return Err(Refusal::new(format!(
                "the G-buffer would need {words} words per pixel ({} bytes: {}), beyond the {} words of WebGPU's {MAX_TARGETS} colour targets",
                words * 4,
                holds.join(", "),
                MAX_TARGETS * 4
            )));
        }
        let formats: Vec<TextureFormat> = (0..words.div_ceil(4))
            .map(|t| match (words - t * 4).min(4) {
                1 => TextureFormat::R32Uint,
                2 => TextureFormat::Rg32Uint,
                _ => TextureFormat::Rgba32Uint,
            })
            .collect();
        let textures = texture_globals(module, formats.len() as u32, (group, first_binding));
        Ok(GBuffer {
            leaves,
            holds,
            formats,
            textures,
            fullscreen: fullscreen_entry(module, pieces.vec4),
            depth_word,
            w_word,
            ordinal_word,
            coverage_by_shading: discards(module, pieces),
            group,
            first_binding,
        })
    }

    /// The geometry pass's fragment entry point: the original inputs and
    /// the previous clip position as words into the G-buffer's targets.
    pub fn write_entry(&self, module: &mut Module, pieces: &Pieces) -> Result<Function, Refusal> {
        let (arguments, at) = fragment::varying_arguments(module, pieces, true);
        let output = self.output_type(module);
        let mut b = Builder::new(Function {
            name: Some(pieces.name.clone()),
            arguments,
            result: Some(naga::FunctionResult {
                ty: output,
                binding: None,
            }),
            ..Function::default()
        });
        let Fragment {
            originals,
            previous,
            frag_coord,
        } = fragment::read_varyings(&mut b, &at);
        let previous = previous
            .ok_or_else(|| Refusal::internal("the G-buffer pass reads no previous position"))?;
        if self.coverage_by_shading {
            let payload = b.call(pieces.payload, originals.clone());
            let mut arguments = originals.clone();
            arguments.push(payload);
            b.call(pieces.shade, arguments);
        }
        let ndc = previous_ndc(&mut b, module, previous);
        let bits = bitcast(&mut b, ndc, ScalarKind::Uint);
        let mut words: Vec<_> = (0..3).map(|c| b.member(bits, c)).collect();
        let bits = bitcast(&mut b, frag_coord, ScalarKind::Uint);
        if self.depth_word.is_some() {
            words.push(b.member(bits, 2));
        }
        if self.w_word.is_some() {
            words.push(b.member(bits, 3));
        }
        if self.ordinal_word.is_some() {
            words.push(b.call(pieces.lowres.draw_id, Vec::new()));
        }
        for leaf in &self.leaves {
            let value = match leaf.member {
                Some(m) => b.member(originals[leaf.argument as usize], m),
                None => originals[leaf.argument as usize],
            };
            match leaf.stored {
                Stored::Unread | Stored::Position => {}
                Stored::FrontFacing { .. } => {
                    let one = b.expr(Expression::Literal(naga::Literal::U32(1)));
                    let zero = b.expr(Expression::Literal(naga::Literal::U32(0)));
                    words.push(b.expr(Expression::Select {
                        condition: value,
                        accept: one,
                        reject: zero,
                    }));
                }
                Stored::Words { scalar, size, .. } => {
                    let bits = if scalar.kind == ScalarKind::Uint {
                        value
                    } else {
                        bitcast(&mut b, value, ScalarKind::Uint)
                    };
                    match size {
                        None => words.push(bits),
                        Some(size) => words.extend((0..size as u32).map(|c| b.member(bits, c))),
                    }
                }
            }
        }
        let zero = b.expr(Expression::Literal(naga::Literal::U32(0)));
        let mut components = Vec::new();
        for (t, format) in self.formats.iter().enumerate() {
            let count = format_words(*format);
            let mut parts: Vec<_> = (0..count)
                .map(|c| words.get(t * 4 + c).copied().unwrap_or(zero))
                .collect();
            let texel = if count == 1 {
                parts.remove(0)
            } else {
                let ty = vector_type(module, vector_size(count as u32), Scalar::U32);
                b.expr(Expression::Compose {
                    ty,
                    components: parts,
                })
            };
            components.push(texel);
        }
        let value = b.expr(Expression::Compose {
            ty: output,
            components,
        });
        b.push(Statement::Return { value: Some(value) });
        Ok(b.finish())
    }

    /// Rebuilds what the original fragment stage received at the pixel
    /// whose centre is `xy` (a `vec2<f32>`; `x` and `y` its components),
    /// with last frame's clip position.
    fn read_inputs(
        &self,
        b: &mut Builder,
        module: &mut Module,
        pieces: &Pieces,
        (xy, x, y): (Handle<Expression>, Handle<Expression>, Handle<Expression>),
    ) -> Fragment {
        let texel = texel_of(b, xy);
        let texels: Vec<Handle<Expression>> = (0..self.textures.len())
            .map(|t| self.load(b, texel, t))
            .collect();
        let word = |b: &mut Builder, w: u32| load_word(b, &texels, w);
        // Last frame's clip position as the NDC over w = 1: the lookup's
        // division by w then gives the stored NDC back exactly.
        let ndc_bits = leading(b, texels[0], VectorSize::Tri);
        let ndc = bitcast(b, ndc_bits, ScalarKind::Float);
        let one = b.literal_f32(1.0);
        let previous = b.expr(Expression::Compose {
            ty: pieces.vec4,
            components: vec![ndc, one],
        });
        b.name(previous, "previous_clip_position");
        let kept = |b: &mut Builder, at: Option<u32>, otherwise: f32| match at {
            Some(at) => {
                let bits = word(b, at);
                bitcast(b, bits, ScalarKind::Float)
            }
            None => b.literal_f32(otherwise),
        };
        let z = kept(b, self.depth_word, 0.0);
        let w = kept(b, self.w_word, 1.0);
        let frag_coord = b.expr(Expression::Compose {
            ty: pieces.vec4,
            components: vec![x, y, z, w],
        });
        b.name(frag_coord, "frag_coord");
        let values = self.leaf_values(b, module, &texels, frag_coord);
        let originals = pieces
            .arguments
            .iter()
            .enumerate()
            .map(|(index, argument)| {
                let index = index as u32;
                match module.types[argument.ty].inner {
                    TypeInner::Struct { ref members, .. } => {
                        let components = (0..members.len() as u32)
                            .map(|m| values[&(index, Some(m))])
                            .collect();
                        b.expr(Expression::Compose {
                            ty: argument.ty,
                            components,
                        })
                    }
                    _ => values[&(index, None)],
                }
            })
            .collect();
        Fragment {
            originals,
            previous: Some(previous),
            frag_coord,
        }
    }

    /// Texture `t` of the G-buffer at `texel`.
    fn load(&self, b: &mut Builder, texel: Handle<Expression>, t: usize) -> Handle<Expression> {
        let image = b.expr(Expression::GlobalVariable(self.textures[t]));
        let level = b.expr(Expression::Literal(naga::Literal::I32(0)));
        let loaded = b.expr(Expression::ImageLoad {
            image,
            coordinate: texel,
            array_index: None,
            sample: None,
            level: Some(level),
        });
        b.name(loaded, &format!("g{t}"));
        loaded
    }

    /// Each original input (argument, struct member) as this pixel's
    /// G-buffer words rebuild it; the position is `frag_coord`.
    fn leaf_values(
        &self,
        b: &mut Builder,
        module: &mut Module,
        texels: &[Handle<Expression>],
        frag_coord: Handle<Expression>,
    ) -> BTreeMap<(u32, Option<u32>), Handle<Expression>> {
        let word = |b: &mut Builder, w: u32| load_word(b, texels, w);
        let mut values: BTreeMap<(u32, Option<u32>), Handle<Expression>> = BTreeMap::new();
        for leaf in &self.leaves {
            let value = match leaf.stored {
                Stored::Unread => b.expr(Expression::ZeroValue(leaf.ty)),
                Stored::Position => frag_coord,
                Stored::FrontFacing { word: at } => {
                    let bits = word(b, at);
                    let zero = b.expr(Expression::Literal(naga::Literal::U32(0)));
                    b.expr(Expression::Binary {
                        op: naga::BinaryOperator::NotEqual,
                        left: bits,
                        right: zero,
                    })
                }
                Stored::Words {
                    first,
                    scalar,
                    size,
                } => {
                    let bits = match size {
                        None => word(b, first),
                        Some(size) => {
                            let components = (0..size as u32).map(|c| word(b, first + c)).collect();
                            let ty = vector_type(module, size, Scalar::U32);
                            b.expr(Expression::Compose { ty, components })
                        }
                    };
                    if scalar.kind == ScalarKind::Uint {
                        bits
                    } else {
                        bitcast(b, bits, scalar.kind)
                    }
                }
            };
            values.insert((leaf.argument, leaf.member), value);
        }
        values
    }

    /// The geometry pass's result: a member per target, at its location.
    fn output_type(&self, module: &mut Module) -> Handle<naga::Type> {
        let members = self
            .formats
            .iter()
            .enumerate()
            .map(|(t, format)| {
                let count = format_words(*format) as u32;
                let ty = if count == 1 {
                    scalar_type(module, Scalar::U32)
                } else {
                    vector_type(module, vector_size(count), Scalar::U32)
                };
                naga::StructMember {
                    name: Some(format!("g{t}")),
                    ty,
                    binding: Some(super::builder::location(t as u32)),
                    offset: t as u32 * 16,
                }
            })
            .collect();
        module.types.insert(
            naga::Type {
                name: Some("GBufferOutput".into()),
                inner: TypeInner::Struct {
                    members,
                    span: self.formats.len() as u32 * 16,
                },
            },
            naga::Span::UNDEFINED,
        )
    }
}

/// Last frame's NDC, `clip.xyz / clip.w`, where the point was in front
/// of the camera (w > 0); (−4, −4, 0) otherwise (and for a NaN w), off
/// the viewport, so the lookup still finds it off-screen.
fn previous_ndc(
    b: &mut Builder,
    module: &mut Module,
    previous: Handle<Expression>,
) -> Handle<Expression> {
    let xyz = leading(b, previous, VectorSize::Tri);
    let w = b.member(previous, 3);
    let ws = b.expr(Expression::Splat {
        size: VectorSize::Tri,
        value: w,
    });
    let ndc = b.expr(Expression::Binary {
        op: naga::BinaryOperator::Divide,
        left: xyz,
        right: ws,
    });
    let zero = b.literal_f32(0.0);
    let in_front = b.expr(Expression::Binary {
        op: naga::BinaryOperator::Greater,
        left: w,
        right: zero,
    });
    let off = b.literal_f32(-4.0);
    let vec3 = vector_type(module, VectorSize::Tri, Scalar::F32);
    let outside = b.expr(Expression::Compose {
        ty: vec3,
        components: vec![off, off, zero],
    });
    let ndc = b.expr(Expression::Select {
        condition: in_front,
        accept: ndc,
        reject: outside,
    });
    b.name(ndc, "previous_ndc");
    ndc
}

/// How one input is kept: its words appended to `holds`, labelled.
fn store(
    module: &Module,
    binding: &Option<Binding>,
    ty: Handle<naga::Type>,
    is_read: bool,
    label: &str,
    holds: &mut Vec<String>,
) -> Result<Stored, Refusal> {
    use naga::BuiltIn as B;
    match binding {
        Some(Binding::BuiltIn(B::Position { .. })) => return Ok(Stored::Position),
        _ if !is_read => return Ok(Stored::Unread),
        Some(Binding::BuiltIn(B::FrontFacing)) => {
            holds.push(label.to_string());
            return Ok(Stored::FrontFacing {
                word: holds.len() as u32 - 1,
            });
        }
        Some(Binding::BuiltIn(B::PrimitiveIndex)) | Some(Binding::Location { .. }) => {}
        Some(Binding::BuiltIn(other)) => {
            return Err(Refusal::new(format!(
                "the fragment stage reads @builtin({other:?}) (`{label}`), which a G-buffer pass cannot pass on to screen space"
            )))
        }
        None => {
            return Err(Refusal::internal(format!(
                "fragment input `{label}` has no binding"
            )))
        }
    }
    let (scalar, size) = match module.types[ty].inner {
        TypeInner::Scalar(scalar) => (scalar, None),
        TypeInner::Vector { size, scalar } => (scalar, Some(size)),
        ref other => {
            return Err(Refusal::internal(format!(
                "fragment input `{label}` is a {other:?}"
            )))
        }
    };
    if scalar.width != 4 {
        return Err(Refusal::new(format!(
            "the fragment input `{label}` is {}-bit; the G-buffer holds 32-bit words",
            scalar.width * 8
        )));
    }
    let first = holds.len() as u32;
    match size {
        None => holds.push(label.to_string()),
        Some(size) => holds.extend(
            ["x", "y", "z", "w"][..size as usize]
                .iter()
                .map(|c| format!("{label}.{c}")),
        ),
    }
    Ok(Stored::Words {
        first,
        scalar,
        size,
    })
}

/// Which of the original entry point's arguments (and of a struct's
/// members) the payload, shade, gradient and presence functions read.
fn arguments_read(module: &Module, pieces: &Pieces) -> BTreeMap<u32, Read> {
    let functions = [Some(pieces.payload), Some(pieces.shade), pieces.gradients]
        .into_iter()
        .chain([pieces.presence.map(|(presence, _)| presence)])
        .flatten();
    let mut read: BTreeMap<u32, Read> = BTreeMap::new();
    let mut note = |argument: u32, member: Option<u32>| note_read(&mut read, argument, member);
    for handle in functions {
        let function = &module.functions[handle];
        let argument_of = |h: Handle<Expression>| match function.expressions[h] {
            Expression::FunctionArgument(i) if (i as usize) < pieces.arguments.len() => Some(i),
            _ => None,
        };
        for (_, expr) in function.expressions.iter() {
            if let Expression::AccessIndex { base, index } = *expr {
                if let Some(argument) = argument_of(base) {
                    note(argument, Some(index));
                }
                continue;
            }
            for operand in crate::proc::operands(expr) {
                if let Some(argument) = argument_of(operand) {
                    note(argument, None);
                }
            }
        }
        crate::proc::each_statement(&function.body, &mut |statement| {
            for value in statement_values(statement) {
                if let Some(argument) = argument_of(value) {
                    note(argument, None);
                }
            }
        });
    }
    read
}

/// Notes that `argument` (its `member`, or the whole of it) is read.
fn note_read(read: &mut BTreeMap<u32, Read>, argument: u32, member: Option<u32>) {
    match (read.get_mut(&argument), member) {
        (Some(Read::Whole), _) => {}
        (Some(Read::Members(set)), Some(m)) => {
            set.insert(m);
        }
        (_, None) => {
            read.insert(argument, Read::Whole);
        }
        (None, Some(m)) => {
            read.insert(argument, Read::Members(BTreeSet::from([m])));
        }
    }
}

/// The values a statement reads directly (not through an expression).
fn statement_values(statement: &Statement) -> Vec<Handle<Expression>> {
    match *statement {
        Statement::Call { ref arguments, .. } => arguments.clone(),
        Statement::Return { value } => value.into_iter().collect(),
        Statement::Store { pointer, value } => vec![pointer, value],
        Statement::If { condition, .. } => vec![condition],
        Statement::Switch { selector, .. } => vec![selector],
        Statement::ImageStore {
            image,
            coordinate,
            array_index,
            value,
        } => [Some(image), Some(coordinate), array_index, Some(value)]
            .into_iter()
            .flatten()
            .collect(),
        Statement::Atomic { pointer, value, .. } => vec![pointer, value],
        _ => Vec::new(),
    }
}

/// Whether the payload or the shade function (or what they call) can
/// `discard`: then which pixels the fragment stage covers is decided by
/// its shading (an alpha test, a cut-out material).
fn discards(module: &Module, pieces: &Pieces) -> bool {
    let mut seen = BTreeSet::new();
    let mut stack = vec![pieces.payload, pieces.shade];
    let mut kills = false;
    while let Some(handle) = stack.pop() {
        if !seen.insert(handle) {
            continue;
        }
        crate::proc::each_statement(&module.functions[handle].body, &mut |s| match *s {
            Statement::Kill => kills = true,
            Statement::Call { function, .. } => stack.push(function),
            _ => {}
        });
    }
    kills
}

/// `@vertex fn shadecache_fullscreen(@builtin(vertex_index) i: u32) ->
/// FullscreenOutput` (its `@builtin(position)`): vertices 0, 1, 2 at (−1, −1), (3, −1)
/// and (−1, 3) in clip space, a triangle that covers the screen, at depth
/// 0 (the screen-space passes test no depth).
fn fullscreen_entry(module: &mut Module, vec4: Handle<naga::Type>) -> naga::EntryPoint {
    let u32_ty = scalar_type(module, Scalar::U32);
    // A struct, so that the position is written `@invariant` like every
    // position the rewrite emits.
    let output = module.types.insert(
        naga::Type {
            name: Some("FullscreenOutput".into()),
            inner: TypeInner::Struct {
                members: vec![naga::StructMember {
                    name: Some("position".into()),
                    ty: vec4,
                    binding: Some(Binding::BuiltIn(naga::BuiltIn::Position {
                        invariant: true,
                    })),
                    offset: 0,
                }],
                span: 16,
            },
        },
        naga::Span::UNDEFINED,
    );
    let mut b = Builder::new(Function {
        name: Some("shadecache_fullscreen".into()),
        arguments: vec![naga::FunctionArgument {
            name: Some("vertex".into()),
            ty: u32_ty,
            binding: Some(Binding::BuiltIn(naga::BuiltIn::VertexIndex)),
        }],
        result: Some(naga::FunctionResult {
            ty: output,
            binding: None,
        }),
        ..Function::default()
    });
    let vertex = b.argument(0);
    let u = |b: &mut Builder, v: u32| b.expr(Expression::Literal(naga::Literal::U32(v)));
    let f = |b: &mut Builder, v: f32| b.literal_f32(v);
    let binary = |b: &mut Builder, op, left, right| b.expr(Expression::Binary { op, left, right });
    use naga::BinaryOperator as Op;
    let one = u(&mut b, 1);
    let two = u(&mut b, 2);
    let shifted = binary(&mut b, Op::ShiftLeft, vertex, one);
    let x_bits = binary(&mut b, Op::And, shifted, two);
    let y_bits = binary(&mut b, Op::And, vertex, two);
    let coordinate = |b: &mut Builder, bits| {
        let value = b.expr(Expression::As {
            expr: bits,
            kind: ScalarKind::Float,
            convert: Some(4),
        });
        let two = f(b, 2.0);
        let one = f(b, 1.0);
        let scaled = binary(b, Op::Multiply, value, two);
        binary(b, Op::Subtract, scaled, one)
    };
    let x = coordinate(&mut b, x_bits);
    let y = coordinate(&mut b, y_bits);
    let z = f(&mut b, 0.0);
    let w = f(&mut b, 1.0);
    let position = b.expr(Expression::Compose {
        ty: vec4,
        components: vec![x, y, z, w],
    });
    let value = b.expr(Expression::Compose {
        ty: output,
        components: vec![position],
    });
    b.push(Statement::Return { value: Some(value) });
    super::builder::entry_point(
        "shadecache_fullscreen",
        naga::ShaderStage::Vertex,
        b.finish(),
    )
}

/// The name of G-buffer texture `index`: `gbuffer_a`, `gbuffer_b`... (a
/// letter, since naga's writer suffixes names that end in a digit).
pub fn texture_name(index: usize) -> String {
    format!("gbuffer_{}", (b'a' + index as u8) as char)
}

/// The first `size` components of `vector` (`.xy`, `.xyz`).
fn leading(b: &mut Builder, vector: Handle<Expression>, size: VectorSize) -> Handle<Expression> {
    use naga::SwizzleComponent as C;
    b.expr(Expression::Swizzle {
        size,
        vector,
        pattern: [C::X, C::Y, C::Z, C::W],
    })
}

/// `bitcast` of a scalar or vector to `kind`, keeping its width and size.
fn bitcast(b: &mut Builder, value: Handle<Expression>, kind: ScalarKind) -> Handle<Expression> {
    b.expr(Expression::As {
        expr: value,
        kind,
        convert: None,
    })
}

fn format_words(format: TextureFormat) -> usize {
    match format {
        TextureFormat::R32Uint => 1,
        TextureFormat::Rg32Uint => 2,
        _ => 4,
    }
}

fn vector_size(count: u32) -> VectorSize {
    match count {
        2 => VectorSize::Bi,
        3 => VectorSize::Tri,
        _ => VectorSize::Quad,
    }
}

impl fragment::ScreenInputs for GBuffer {
    fn read(&self, b: &mut Builder, module: &mut Module, pieces: &Pieces) -> Fragment {
        let screen = b.argument(0);
        let xy = leading(b, screen, VectorSize::Bi);
        let (x, y) = (b.member(screen, 0), b.member(screen, 1));
        self.read_inputs(b, module, pieces, (xy, x, y))
    }

    fn read_at(
        &self,
        b: &mut Builder,
        module: &mut Module,
        pieces: &Pieces,
        xy: Handle<Expression>,
    ) -> Fragment {
        let (x, y) = (b.member(xy, 0), b.member(xy, 1));
        self.read_inputs(b, module, pieces, (xy, x, y))
    }

    fn ordinal_at(&self, b: &mut Builder, xy: Handle<Expression>) -> Option<Handle<Expression>> {
        let at = self.ordinal_word?;
        let texel = texel_of(b, xy);
        // Only the texture that holds the word is read; a load of a
        // `texture_2d<u32>` is four words whatever its format.
        let loaded = self.load(b, texel, (at / 4) as usize);
        let ordinal = b.member(loaded, at % 4);
        b.name(ordinal, "ordinal");
        Some(ordinal)
    }
}

/// The integer texel of a pixel centre `xy`.
fn texel_of(b: &mut Builder, xy: Handle<Expression>) -> Handle<Expression> {
    let texel = b.expr(Expression::As {
        expr: xy,
        kind: ScalarKind::Sint,
        convert: Some(4),
    });
    b.name(texel, "texel");
    texel
}

/// The G-buffer's `count` textures (`texture_2d<u32>`), bound in `group`
/// from `first_binding` on.
fn texture_globals(
    module: &mut Module,
    count: u32,
    (group, first_binding): (u32, u32),
) -> Vec<Handle<naga::GlobalVariable>> {
    let texture_ty = module.types.insert(
        naga::Type {
            name: None,
            inner: TypeInner::Image {
                dim: naga::ImageDimension::D2,
                arrayed: false,
                class: naga::ImageClass::Sampled {
                    kind: ScalarKind::Uint,
                    multi: false,
                },
            },
        },
        naga::Span::UNDEFINED,
    );
    (0..count)
        .map(|t| {
            module.global_variables.append(
                naga::GlobalVariable {
                    name: Some(texture_name(t as usize)),
                    space: naga::AddressSpace::Handle,
                    binding: Some(naga::ResourceBinding {
                        group,
                        binding: first_binding + t,
                    }),
                    ty: texture_ty,
                    init: None,
                    memory_decorations: Default::default(),
                },
                naga::Span::UNDEFINED,
            )
        })
        .collect()
}

/// Word `w` of a pixel's G-buffer, from its loaded `texels`.
fn load_word(b: &mut Builder, texels: &[Handle<Expression>], w: u32) -> Handle<Expression> {
    b.member(texels[(w / 4) as usize], w % 4)
}

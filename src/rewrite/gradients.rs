//! Hoisting implicit derivatives out of one-pass's miss branch.
//!
//! One-pass computes the payload only on a miss, inside a non-uniform
//! branch, where WGSL forbids implicit derivatives. So the derivatives the
//! payload takes are computed *before* the branch, in uniform control flow,
//! by a gradients function — a copy of just the slices of the sampled
//! coordinates and differentiated values, ending in the derivatives — and
//! passed into the payload function, which samples with
//! `textureSampleGrad` and reads `dpdx`/`dpdy`/`fwidth` values from them:
//!
//! * `textureSample(t, s, uv)` → `textureSampleGrad(t, s, uv, dpdx(uv), dpdy(uv))`;
//! * `textureSampleBias(t, s, uv, b)` → gradients scaled by 2^b, which is
//!   what a LOD bias of b does to the selected level;
//! * `textureSampleCompare(t, s, uv, r)` → `textureSampleCompareLevel`
//!   (level 0: WGSL has no comparison sample with gradients, and depth
//!   textures used for comparisons rarely have mip levels);
//! * `dpdx(e)`, `dpdy(e)`, `fwidth(e)` → their values, computed before the
//!   branch.

use naga::{Expression, Function, Handle, Module, Statement, TypeInner};

use super::copy::FunctionCopy;
use super::Refusal;
use crate::analysis::graph::{ExprGraph, ExprSet};
use crate::proc::remap::{self, Mapper};

/// An implicit-derivative operation of the payload and where its hoisted
/// values are in the gradients struct.
#[derive(Clone, Debug)]
enum Site {
    /// A sample: gradients at members `x` and `x + 1`.
    Sample {
        expr: Handle<Expression>,
        member: u32,
    },
    /// A comparison sample: sampled at level 0, nothing hoisted.
    Compare { expr: Handle<Expression> },
    /// A derivative: its value at `member`.
    Derivative {
        expr: Handle<Expression>,
        member: u32,
    },
}

/// The gradients function and the payload function that uses it.
#[derive(Debug)]
pub struct Hoisted {
    pub gradients: Handle<Function>,
    pub payload: Handle<Function>,
}

/// What the payload is computed from: the original entry point's
/// function, its info and expression graph, and the expressions the
/// payload keeps (`live`).
#[derive(Debug)]
pub(crate) struct Source<'a> {
    pub original: &'a Module,
    pub function: &'a Function,
    pub info: &'a naga::valid::FunctionInfo,
    pub graph: &'a ExprGraph,
    pub live: &'a ExprSet,
}

/// The payload function to build: the value it returns (`node`), the
/// entry point's arguments without bindings, the payload type, the entry
/// point's name, the presence function of a value that may be absent, and
/// the payload's components.
#[derive(Debug)]
pub(crate) struct PayloadShape<'a> {
    pub node: Handle<Expression>,
    pub arguments: &'a [naga::FunctionArgument],
    pub result: Handle<naga::Type>,
    pub name: &'a str,
    pub absent: Handle<Function>,
    pub components: u32,
}

/// The payload's implicit derivatives: each site, the types of the values
/// hoisted for them in order, and the expressions those values need.
struct Sites {
    sites: Vec<Site>,
    members: Vec<Handle<naga::Type>>,
    needed: ExprSet,
}

/// Builds the gradients function and a payload function taking its result.
pub(crate) fn hoist(
    module: &mut Module,
    source: &Source,
    shape: &PayloadShape,
) -> Result<Hoisted, Refusal> {
    let sites = find_sites(module, source);
    let struct_ty = gradients_struct(module, &sites.members, shape.name)?;
    let gradients_fn = gradients_function(source, &sites, shape, struct_ty);
    let payload_fn = payload_function(source, sites.sites, shape, struct_ty);
    Ok(Hoisted {
        gradients: module.functions.append(gradients_fn, naga::Span::UNDEFINED),
        payload: module.functions.append(payload_fn, naga::Span::UNDEFINED),
    })
}

/// Every sample with an implicit level and every derivative among the
/// payload's expressions, with the values to hoist for each.
fn find_sites(module: &mut Module, source: &Source) -> Sites {
    let (function, info, graph) = (source.function, source.info, source.graph);
    let exprs: Vec<(Handle<Expression>, &Expression)> = function.expressions.iter().collect();
    let mut sites = Vec::new();
    let mut members: Vec<Handle<naga::Type>> = Vec::new();
    let mut needed = ExprSet::with_capacity(function.expressions.len());
    for index in source.live.ones() {
        let (handle, expr) = exprs[index];
        match *expr {
            Expression::ImageSample {
                coordinate,
                level: level @ (naga::SampleLevel::Auto | naga::SampleLevel::Bias(_)),
                depth_ref: None,
                ..
            } => {
                let ty = super::type_handle(module, info, coordinate);
                sites.push(Site::Sample {
                    expr: handle,
                    member: members.len() as u32,
                });
                members.extend([ty, ty]);
                needed.union_with(&graph.slice(coordinate));
                if let naga::SampleLevel::Bias(bias) = level {
                    needed.union_with(&graph.slice(bias));
                }
            }
            Expression::ImageSample {
                level: naga::SampleLevel::Auto,
                depth_ref: Some(_),
                ..
            } => sites.push(Site::Compare { expr: handle }),
            Expression::Derivative { expr: operand, .. } => {
                let ty = super::type_handle(module, info, handle);
                sites.push(Site::Derivative {
                    expr: handle,
                    member: members.len() as u32,
                });
                members.push(ty);
                needed.union_with(&graph.slice(operand));
            }
            _ => {}
        }
    }
    Sites {
        sites,
        members,
        needed,
    }
}

/// The struct carrying the hoisted values, laid out as WGSL lays it out.
fn gradients_struct(
    module: &mut Module,
    members: &[Handle<naga::Type>],
    name: &str,
) -> Result<Handle<naga::Type>, Refusal> {
    let mut offset: u32 = 0;
    let mut struct_members = Vec::new();
    for (i, &ty) in members.iter().enumerate() {
        let (size, align) = size_align(&module.types[ty].inner)
            .ok_or_else(|| Refusal::new("a hoisted derivative is not f32 or a vector of f32"))?;
        offset = offset.div_ceil(align) * align;
        struct_members.push(naga::StructMember {
            // Letters only: naga's namer suffixes names ending in a digit.
            name: Some(format!("d{}", letters(i))),
            ty,
            binding: None,
            offset,
        });
        offset += size;
    }
    Ok(module.types.insert(
        naga::Type {
            name: Some(format!("{}Gradients", crate::proc::pascal(name))),
            inner: TypeInner::Struct {
                members: struct_members,
                span: offset.div_ceil(16).max(1) * 16,
            },
        },
        naga::Span::UNDEFINED,
    ))
}

/// The gradients function: the needed slices, then the derivatives.
fn gradients_function(
    source: &Source,
    sites: &Sites,
    shape: &PayloadShape,
    struct_ty: Handle<naga::Type>,
) -> Function {
    let function = source.function;
    let mut copy = FunctionCopy::new(
        source.original,
        function,
        &sites.needed,
        Function {
            name: Some(format!("{}_gradients", shape.name)),
            arguments: shape.arguments.to_vec(),
            result: Some(naga::FunctionResult {
                ty: struct_ty,
                binding: None,
            }),
            ..Function::default()
        },
    );
    copy.drop_returns();
    let body = copy.copy_body();
    let mut components = Vec::new();
    for site in &sites.sites {
        match *site {
            Site::Sample { expr, .. } => {
                let Expression::ImageSample {
                    coordinate, level, ..
                } = function.expressions[expr]
                else {
                    continue;
                };
                components.extend(sample_gradients(&mut copy, coordinate, level));
            }
            Site::Derivative { expr, .. } => {
                let Expression::Derivative {
                    axis,
                    ctrl,
                    expr: operand,
                } = function.expressions[expr]
                else {
                    continue;
                };
                let operand = copy.expression(operand);
                components.push(copy.add(Expression::Derivative {
                    axis,
                    ctrl,
                    expr: operand,
                }));
            }
            Site::Compare { .. } => {}
        }
    }
    let value = copy.add(Expression::Compose {
        ty: struct_ty,
        components,
    });
    copy.finish(body, Statement::Return { value: Some(value) })
}

/// A sample's two gradients in the copy: of its coordinate along x and y,
/// scaled by 2^bias for a biased sample.
fn sample_gradients(
    copy: &mut FunctionCopy,
    coordinate: Handle<Expression>,
    level: naga::SampleLevel,
) -> [Handle<Expression>; 2] {
    let coordinate = copy.expression(coordinate);
    let scale = match level {
        naga::SampleLevel::Bias(bias) => {
            let bias = copy.expression(bias);
            Some(copy.add(Expression::Math {
                fun: naga::MathFunction::Exp2,
                arg: bias,
                arg1: None,
                arg2: None,
                arg3: None,
            }))
        }
        _ => None,
    };
    [naga::DerivativeAxis::X, naga::DerivativeAxis::Y].map(|axis| {
        let d = copy.add(Expression::Derivative {
            axis,
            ctrl: naga::DerivativeControl::None,
            expr: coordinate,
        });
        match scale {
            Some(scale) => copy.add(Expression::Binary {
                op: naga::BinaryOperator::Multiply,
                left: d,
                right: scale,
            }),
            None => d,
        }
    })
}

/// The payload function, reading the hoisted values from its last
/// argument.
fn payload_function(
    source: &Source,
    sites: Vec<Site>,
    shape: &PayloadShape,
    struct_ty: Handle<naga::Type>,
) -> Function {
    let function = source.function;
    let mut payload_arguments = shape.arguments.to_vec();
    payload_arguments.push(naga::FunctionArgument {
        name: Some("gradients".into()),
        ty: struct_ty,
        binding: None,
    });
    let gradients_arg = payload_arguments.len() as u32 - 1;
    let mut payload = FunctionCopy::new(
        source.original,
        function,
        source.live,
        Function {
            name: Some(format!("{}_payload", shape.name)),
            arguments: payload_arguments,
            result: Some(naga::FunctionResult {
                ty: shape.result,
                binding: None,
            }),
            ..Function::default()
        },
    );
    payload.return_at(shape.node);
    for site in sites {
        match site {
            Site::Sample { expr, member } => payload.rebuild(
                expr,
                Box::new(move |copy: &mut FunctionCopy| {
                    let argument = copy.add(Expression::FunctionArgument(gradients_arg));
                    let x = copy.add(Expression::AccessIndex {
                        base: argument,
                        index: member,
                    });
                    let y = copy.add(Expression::AccessIndex {
                        base: argument,
                        index: member + 1,
                    });
                    let mut sample = remap::expression(&function.expressions[expr], copy);
                    if let Expression::ImageSample { ref mut level, .. } = sample {
                        *level = naga::SampleLevel::Gradient { x, y };
                    }
                    sample
                }),
            ),
            Site::Compare { expr } => payload.rebuild(
                expr,
                Box::new(move |copy: &mut FunctionCopy| {
                    let mut sample = remap::expression(&function.expressions[expr], copy);
                    if let Expression::ImageSample { ref mut level, .. } = sample {
                        *level = naga::SampleLevel::Zero;
                    }
                    sample
                }),
            ),
            Site::Derivative { expr, member } => payload.rebuild(
                expr,
                Box::new(move |copy: &mut FunctionCopy| {
                    let argument = copy.add(Expression::FunctionArgument(gradients_arg));
                    Expression::AccessIndex {
                        base: argument,
                        index: member,
                    }
                }),
            ),
        }
    }
    super::path::finish_payload(payload, shape.absent, shape.components)
}

/// 0 → `a`, 25 → `z`, 26 → `ba`...
fn letters(mut i: usize) -> String {
    let mut out = Vec::new();
    loop {
        out.push(b'a' + (i % 26) as u8);
        i /= 26;
        if i == 0 {
            break;
        }
    }
    out.reverse();
    String::from_utf8(out).unwrap_or_default()
}

/// Size and alignment of f32 scalars and vectors (WGSL's layout rules).
fn size_align(inner: &TypeInner) -> Option<(u32, u32)> {
    match *inner {
        TypeInner::Scalar(naga::Scalar::F32) => Some((4, 4)),
        TypeInner::Vector {
            size,
            scalar: naga::Scalar::F32,
        } => Some(match size {
            naga::VectorSize::Bi => (8, 8),
            naga::VectorSize::Tri => (12, 16),
            naga::VectorSize::Quad => (16, 16),
        }),
        _ => None,
    }
}

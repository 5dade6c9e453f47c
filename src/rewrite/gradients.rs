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

/// Builds the gradients function and a payload function taking its result,
/// for the payload computing `node` with `live` of `function`. `arguments`
/// are the entry point's arguments without bindings; `result` the payload
/// type.
#[allow(clippy::too_many_arguments)]
pub fn hoist(
    module: &mut Module,
    original: &Module,
    function: &Function,
    info: &naga::valid::FunctionInfo,
    graph: &ExprGraph,
    live: &ExprSet,
    node: Handle<Expression>,
    arguments: &[naga::FunctionArgument],
    result: Handle<naga::Type>,
    name: &str,
    absent: Handle<Function>,
    payload_components: u32,
) -> Result<Hoisted, Refusal> {
    let exprs: Vec<(Handle<Expression>, &Expression)> = function.expressions.iter().collect();
    let mut sites = Vec::new();
    let mut members: Vec<Handle<naga::Type>> = Vec::new();
    let mut needed = ExprSet::with_capacity(function.expressions.len());
    for index in live.ones() {
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

    // The struct carrying the hoisted values.
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
    let struct_ty = module.types.insert(
        naga::Type {
            name: Some(format!("{}Gradients", super::vertex::pascal(name))),
            inner: TypeInner::Struct {
                members: struct_members,
                span: offset.div_ceil(16).max(1) * 16,
            },
        },
        naga::Span::UNDEFINED,
    );

    // The gradients function: the needed slices, then the derivatives.
    let mut copy = FunctionCopy::new(
        original,
        function,
        &needed,
        Function {
            name: Some(format!("{name}_gradients")),
            arguments: arguments.to_vec(),
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
    for site in &sites {
        match *site {
            Site::Sample { expr, .. } => {
                let Expression::ImageSample {
                    coordinate, level, ..
                } = function.expressions[expr]
                else {
                    continue;
                };
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
                for axis in [naga::DerivativeAxis::X, naga::DerivativeAxis::Y] {
                    let mut d = copy.add(Expression::Derivative {
                        axis,
                        ctrl: naga::DerivativeControl::None,
                        expr: coordinate,
                    });
                    if let Some(scale) = scale {
                        d = copy.add(Expression::Binary {
                            op: naga::BinaryOperator::Multiply,
                            left: d,
                            right: scale,
                        });
                    }
                    components.push(d);
                }
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
    let gradients_fn = copy.finish(body, Statement::Return { value: Some(value) });

    // The payload function, reading the hoisted values.
    let mut payload_arguments = arguments.to_vec();
    payload_arguments.push(naga::FunctionArgument {
        name: Some("gradients".into()),
        ty: struct_ty,
        binding: None,
    });
    let gradients_arg = payload_arguments.len() as u32 - 1;
    let mut payload = FunctionCopy::new(
        original,
        function,
        live,
        Function {
            name: Some(format!("{name}_payload")),
            arguments: payload_arguments,
            result: Some(naga::FunctionResult {
                ty: result,
                binding: None,
            }),
            ..Function::default()
        },
    );
    payload.return_at(node);
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
    let payload_fn = super::path::finish_payload(payload, absent, payload_components);
    Ok(Hoisted {
        gradients: module.functions.append(gradients_fn, naga::Span::UNDEFINED),
        payload: module.functions.append(payload_fn, naga::Span::UNDEFINED),
    })
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

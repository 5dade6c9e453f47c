use std::cell::RefCell;
use std::collections::HashMap;

use naga::valid::{FunctionInfo, ModuleInfo};
use naga::{BinaryOperator as B, Expression, Function, Handle, MathFunction as M, TypeInner};

use super::Weights;
use crate::proc::{self, ExpressionKind, FunctionLayout, PointerRoot};

/// Estimates the run-time cost of expressions and functions of one module.
#[derive(Debug)]
pub struct CostModel<'m> {
    module: &'m naga::Module,
    info: &'m ModuleInfo,
    weights: Weights,
    /// Cost of one call of each helper function, filled on demand.
    functions: RefCell<HashMap<Handle<Function>, f64>>,
}

impl<'m> CostModel<'m> {
    /// A cost model of `module` (validated, with its `info`) under `weights`.
    pub fn new(module: &'m naga::Module, info: &'m ModuleInfo, weights: Weights) -> Self {
        CostModel {
            module,
            info,
            weights,
            functions: RefCell::new(HashMap::new()),
        }
    }

    /// The weights it counts with.
    pub fn weights(&self) -> &Weights {
        &self.weights
    }

    /// The statement layout of `function`, with this model's default trip
    /// count for loops of unknown bounds.
    pub fn layout(&self, function: &Function) -> FunctionLayout {
        proc::layout(self.module, function, self.weights.default_loop_trips)
    }

    /// The cost of evaluating `expr` once, not counting its operands. A call
    /// result costs the whole body of the function called.
    pub fn expression(
        &self,
        function: &Function,
        info: &FunctionInfo,
        expr: Handle<Expression>,
    ) -> f64 {
        let w = &self.weights;
        let types = &self.module.types;
        let ty = |h: Handle<Expression>| info[h].ty.inner_with(types);
        let width = |h: Handle<Expression>| proc::components(ty(h)) as f64;
        let n = width(expr);
        let expression = &function.expressions[expr];
        match proc::kind(expression) {
            ExpressionKind::Name | ExpressionKind::Move => 0.0,
            // A dynamic index is an address computation.
            ExpressionKind::DynamicIndex => w.arithmetic,
            ExpressionKind::Load => self.load(function, expression),
            ExpressionKind::Sample => w.texture_sample,
            ExpressionKind::TexelLoad => w.texture_load,
            ExpressionKind::Query => w.texture_query,
            ExpressionKind::Arithmetic => match *expression {
                Expression::Relational { argument, .. } => w.arithmetic * width(argument),
                Expression::Binary { op, left, right } => {
                    let weight = match op {
                        B::Divide | B::Modulo => w.division,
                        _ => w.arithmetic,
                    };
                    weight * binary_operations(op, ty(left), ty(right), n)
                }
                Expression::Math { fun, arg, .. } => self.math(fun, width(arg), n),
                // Unary operators, `select`, conversions: one operation a
                // component.
                _ => w.arithmetic * n,
            },
            ExpressionKind::Derivative => w.derivative * n,
            ExpressionKind::Call => match *expression {
                Expression::CallResult(callee) => self.function(callee) + w.call,
                _ => w.call,
            },
            // They read memory or other invocations.
            ExpressionKind::StatementResult => w.load,
        }
    }

    /// A load's cost: a memory read from a uniform, storage or immediate
    /// variable, nothing from a local (a register).
    fn load(&self, function: &Function, expression: &Expression) -> f64 {
        let Expression::Load { pointer } = *expression else {
            return 0.0;
        };
        match proc::pointer_root(function, pointer) {
            Some(PointerRoot::Global(global)) => match self.module.global_variables[global].space {
                naga::AddressSpace::Uniform
                | naga::AddressSpace::Storage { .. }
                | naga::AddressSpace::Immediate => self.weights.load,
                _ => 0.0,
            },
            _ => 0.0,
        }
    }

    /// A built-in math function applied to an argument of `arg` components
    /// giving a result of `result` components.
    fn math(&self, fun: M, arg: f64, result: f64) -> f64 {
        let w = &self.weights;
        match fun {
            M::Abs | M::Min | M::Max | M::Clamp | M::Saturate | M::Sign => w.simple_math * result,
            M::Ceil | M::Floor | M::Round | M::Fract | M::Trunc | M::Modf | M::Frexp | M::Ldexp => {
                w.simple_math * result
            }
            M::Fma | M::Mix | M::Step | M::SmoothStep | M::QuantizeToF16 => w.simple_math * result,
            M::Radians | M::Degrees => w.arithmetic * result,
            M::Cos
            | M::Cosh
            | M::Sin
            | M::Sinh
            | M::Tan
            | M::Tanh
            | M::Acos
            | M::Asin
            | M::Atan
            | M::Atan2
            | M::Asinh
            | M::Acosh
            | M::Atanh
            | M::Exp
            | M::Exp2
            | M::Log
            | M::Log2
            | M::Pow
            | M::Sqrt
            | M::InverseSqrt => w.transcendental * result,
            // n multiply-adds.
            M::Dot | M::Outer => w.arithmetic * arg * if fun == M::Outer { arg } else { 1.0 },
            M::Dot4I8Packed | M::Dot4U8Packed => w.arithmetic * 4.0,
            M::Cross => w.arithmetic * 6.0,
            // a dot product and a square root.
            M::Length | M::Distance => w.arithmetic * 2.0 * arg + w.transcendental,
            // a dot product, an inverse square root, a scale.
            M::Normalize => w.arithmetic * 2.0 * arg + w.transcendental,
            M::FaceForward | M::Reflect => w.arithmetic * 3.0 * arg,
            M::Refract => w.arithmetic * 5.0 * arg + w.transcendental,
            M::Transpose => 0.0,
            M::Determinant | M::Inverse => w.arithmetic * arg * arg.sqrt().max(1.0) * 2.0,
            M::CountTrailingZeros
            | M::CountLeadingZeros
            | M::CountOneBits
            | M::ReverseBits
            | M::ExtractBits
            | M::InsertBits
            | M::FirstTrailingBit
            | M::FirstLeadingBit => w.arithmetic * result,
            M::Pack4x8snorm
            | M::Pack4x8unorm
            | M::Pack2x16snorm
            | M::Pack2x16unorm
            | M::Pack2x16float
            | M::Pack4xI8
            | M::Pack4xU8
            | M::Pack4xI8Clamp
            | M::Pack4xU8Clamp
            | M::Unpack4x8snorm
            | M::Unpack4x8unorm
            | M::Unpack2x16snorm
            | M::Unpack2x16unorm
            | M::Unpack2x16float
            | M::Unpack4xI8
            | M::Unpack4xU8 => w.arithmetic * 4.0,
        }
    }

    /// The cost of one call of a helper function: its body, loops by their
    /// trip counts, nested calls by their own bodies. Memoised; a function
    /// being costed that is reached again (recursion, which WGSL forbids)
    /// counts as zero.
    pub fn function(&self, handle: Handle<Function>) -> f64 {
        if let Some(&cost) = self.functions.borrow().get(&handle) {
            return cost;
        }
        // Mark as in progress so a cycle terminates.
        self.functions.borrow_mut().insert(handle, 0.0);
        let function = &self.module.functions[handle];
        let layout = self.layout(function);
        let cost = self.body(function, &self.info[handle], &layout);
        self.functions.borrow_mut().insert(handle, cost);
        cost
    }

    /// The cost of one invocation of a function body: every evaluated
    /// expression times the trip counts around it, plus calls made for their
    /// effects alone (calls with a result are costed by their result).
    pub fn body(&self, function: &Function, info: &FunctionInfo, layout: &FunctionLayout) -> f64 {
        let expressions: f64 = layout
            .placed()
            .map(|(expr, at)| self.expression(function, info, expr) * at.multiplier)
            .sum();
        let void_calls: f64 = layout
            .calls
            .iter()
            .filter(|call| call.result.is_none())
            .map(|call| {
                (self.function(call.function) + self.weights.call) * call.placement.multiplier
            })
            .sum();
        expressions + void_calls
    }
}

/// The multiply-adds of a binary operation on operands of types `left` and
/// `right` with a result of `n` components.
fn binary_operations(op: B, left: &TypeInner, right: &TypeInner, n: f64) -> f64 {
    match (left, right) {
        // matrix × vector, vector × matrix: one multiply-add per matrix
        // element.
        (&TypeInner::Matrix { columns, rows, .. }, &TypeInner::Vector { .. })
        | (&TypeInner::Vector { .. }, &TypeInner::Matrix { columns, rows, .. })
            if op == B::Multiply =>
        {
            columns as u32 as f64 * rows as u32 as f64
        }
        // (r × k) · (k × c): r·k·c multiply-adds.
        (
            &TypeInner::Matrix {
                columns: k,
                rows: r,
                ..
            },
            &TypeInner::Matrix { columns: c, .. },
        ) if op == B::Multiply => r as u32 as f64 * k as u32 as f64 * c as u32 as f64,
        _ => n,
    }
}

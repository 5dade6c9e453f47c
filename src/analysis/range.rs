//! The range a value can take: interval arithmetic over the IR, to flag
//! candidates whose payload may not fit an rgba16float cache (|x| < 65504).
//!
//! Each expression gets one interval bounding all its components. It is
//! conservative: what the analysis cannot bound is unbounded, and an
//! unbounded value **may exceed** f16. Unbounded are the fragment inputs,
//! uniform and storage values, texture reads (a texture's format is not in
//! the shader) and whatever is computed from them without a bounding
//! operation; bounded are literals, integer values (by their type), and the
//! results of `sin`, `cos`, `fract`, `x - floor(x)`, `normalize`,
//! `saturate`, `clamp`, comparisons, and arithmetic on bounded values.
//! Helper functions are followed: a call's result is its body's return
//! value for the intervals of the call's arguments.
//!
//! Uniform values are unbounded to the analysis of a shader alone. Where the
//! values are known — the profiler knows every value a scene writes, over
//! all its frames — [`UniformBounds`] gives them, and the loads of those
//! members are bounded by them.

use std::collections::HashMap;

use naga::{BinaryOperator, Expression, Function, Handle, MathFunction, ScalarKind, UnaryOperator};

use crate::proc::{each_statement, pointer_root, PointerRoot};

/// The largest magnitude below which an rgba16float cache stores a value
/// (65504 is its largest finite value; the cache treats reaching it as an
/// overflow).
pub const F16_LIMIT: f64 = 65504.0;

/// A closed interval of reals; infinite ends mean "unbounded".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    pub const ALL: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    pub fn new(lo: f64, hi: f64) -> Self {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return Interval::ALL;
        }
        Interval { lo, hi }
    }

    fn point(v: f64) -> Self {
        Interval::new(v, v)
    }

    fn magnitude(self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    fn symmetric(m: f64) -> Self {
        Interval::new(-m, m)
    }

    fn union(self, other: Interval) -> Self {
        Interval::new(self.lo.min(other.lo), self.hi.max(other.hi))
    }

    /// The ends, `None` where unbounded.
    pub fn ends(self) -> [Option<f64>; 2] {
        [self.lo, self.hi].map(|v| v.is_finite().then_some(v))
    }

    pub fn is_bounded(self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    /// Whether every value lies strictly inside (−65504, 65504).
    pub fn fits_f16(self) -> bool {
        self.lo > -F16_LIMIT && self.hi < F16_LIMIT
    }

    fn add(self, o: Interval) -> Self {
        Interval::new(self.lo + o.lo, self.hi + o.hi)
    }

    fn sub(self, o: Interval) -> Self {
        Interval::new(self.lo - o.hi, self.hi - o.lo)
    }

    fn mul(self, o: Interval) -> Self {
        // The ends are limits of reals: a zero end times an infinite one
        // contributes 0 (IEEE's 0 × ∞ = NaN would lose the bound), so
        // [0, 1] × [0, ∞) is [0, ∞) and [1, 2] × [0, ∞) too.
        let times = |a: f64, b: f64| if a == 0.0 || b == 0.0 { 0.0 } else { a * b };
        let p = [
            times(self.lo, o.lo),
            times(self.lo, o.hi),
            times(self.hi, o.lo),
            times(self.hi, o.hi),
        ];
        Interval::new(
            p.iter().copied().fold(f64::INFINITY, f64::min),
            p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    }

    fn div(self, o: Interval) -> Self {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return Interval::ALL;
        }
        // 1/∞ is 0: the reciprocal of [1, ∞) is [0, 1].
        self.mul(Interval::new(1.0 / o.hi, 1.0 / o.lo))
    }

    fn min(self, o: Interval) -> Self {
        Interval::new(self.lo.min(o.lo), self.hi.min(o.hi))
    }

    fn max(self, o: Interval) -> Self {
        Interval::new(self.lo.max(o.lo), self.hi.max(o.hi))
    }
}

/// Known bounds of uniform values: for each uniform buffer (group,
/// binding), an interval for each struct member by its index, or for the
/// whole value (index 0) where the uniform is not a struct. One interval
/// bounds every component of a member.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UniformBounds(HashMap<(u32, u32, u32), Interval>);

impl UniformBounds {
    /// Widens the bound of member `member` of the uniform at (`group`,
    /// `binding`) to hold `values`. A NaN value leaves it unbounded.
    pub fn observe(&mut self, group: u32, binding: u32, member: u32, values: &[f64]) {
        for &v in values {
            let seen = if v.is_nan() {
                Interval::ALL
            } else {
                Interval::point(v)
            };
            self.0
                .entry((group, binding, member))
                .and_modify(|known| *known = known.union(seen))
                .or_insert(seen);
        }
    }

    fn get(&self, group: u32, binding: u32, member: u32) -> Interval {
        self.0
            .get(&(group, binding, member))
            .copied()
            .unwrap_or(Interval::ALL)
    }
}

/// Intervals of the values of a fragment entry point, computed on demand
/// and remembered.
pub struct EntryRanges<'a>(Ranges<'a>);

impl std::fmt::Debug for EntryRanges<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EntryRanges")
            .field("known", &self.0.memo.len())
            .finish_non_exhaustive()
    }
}

impl<'a> EntryRanges<'a> {
    /// Uniform values within `uniforms`.
    pub fn with_uniforms(
        module: &'a naga::Module,
        info: &'a naga::valid::ModuleInfo,
        entry_index: usize,
        uniforms: &'a UniformBounds,
    ) -> Self {
        let function = &module.entry_points[entry_index].function;
        EntryRanges(Ranges {
            module,
            function,
            info: info.get_entry_point(entry_index),
            module_info: info,
            uniforms,
            arguments: vec![Interval::ALL; function.arguments.len()],
            memo: HashMap::new(),
            depth: 0,
        })
    }

    /// The interval of `expr`, an expression of the entry point.
    pub fn of(&mut self, expr: Handle<Expression>) -> Interval {
        self.0.of(expr)
    }
}

/// Bounds in words: "in [lo, hi]", "unbounded", "at least lo" or "at most hi".
pub fn describe(range: [Option<f64>; 2]) -> String {
    fn number(v: f64) -> String {
        if v != 0.0 && !(1e-3..1e5).contains(&v.abs()) {
            format!("{v:.3e}")
        } else {
            // Four significant decimals, without trailing zeros.
            let text = format!("{v:.4}");
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        }
    }
    match range {
        [Some(lo), Some(hi)] => format!("in [{}, {}]", number(lo), number(hi)),
        [None, None] => "unbounded".into(),
        [Some(lo), None] => format!("at least {}", number(lo)),
        [None, Some(hi)] => format!("at most {}", number(hi)),
    }
}

/// Calls nest no deeper than this before their results count as unbounded
/// (WGSL has no recursion; this only bounds the work).
const MAX_CALL_DEPTH: usize = 16;

/// Pieces a call's widest bounded argument is split into.
const SPLITS: usize = 16;

struct Ranges<'a> {
    module: &'a naga::Module,
    function: &'a Function,
    info: &'a naga::valid::FunctionInfo,
    module_info: &'a naga::valid::ModuleInfo,
    uniforms: &'a UniformBounds,
    arguments: Vec<Interval>,
    /// `None` while an expression is being evaluated (a cycle through a
    /// variable counts as unbounded).
    memo: HashMap<Handle<Expression>, Option<Interval>>,
    depth: usize,
}

impl Ranges<'_> {
    fn of(&mut self, expr: Handle<Expression>) -> Interval {
        match self.memo.get(&expr) {
            Some(Some(known)) => return *known,
            Some(None) => return Interval::ALL,
            None => {}
        }
        self.memo.insert(expr, None);
        let range = self.compute(expr);
        // A value never exceeds what its type can hold.
        let range = match self.scalar_kind(expr) {
            Some((ScalarKind::Uint, 4)) => range
                .max(Interval::point(0.0))
                .min(Interval::point(u32::MAX as f64)),
            Some((ScalarKind::Sint, 4)) => range
                .max(Interval::point(i32::MIN as f64))
                .min(Interval::point(i32::MAX as f64)),
            Some((ScalarKind::Bool, _)) => Interval::new(0.0, 1.0),
            _ => range,
        };
        self.memo.insert(expr, Some(range));
        range
    }

    fn scalar_kind(&self, expr: Handle<Expression>) -> Option<(ScalarKind, u8)> {
        self.info[expr]
            .ty
            .inner_with(&self.module.types)
            .scalar()
            .map(|s| (s.kind, s.width))
    }

    fn compute(&mut self, expr: Handle<Expression>) -> Interval {
        use Expression as E;
        match self.function.expressions[expr] {
            E::Literal(literal) => literal_value(literal).map_or(Interval::ALL, Interval::point),
            E::Constant(constant) => {
                let init = self.module.constants[constant].init;
                match self.module.global_expressions[init] {
                    E::Literal(literal) => {
                        literal_value(literal).map_or(Interval::ALL, Interval::point)
                    }
                    _ => Interval::ALL,
                }
            }
            E::ZeroValue(_) => Interval::point(0.0),
            E::FunctionArgument(i) => self
                .arguments
                .get(i as usize)
                .copied()
                .unwrap_or(Interval::ALL),
            E::Compose { ref components, .. } => {
                let components = components.clone();
                components
                    .iter()
                    .map(|&c| self.of(c))
                    .reduce(Interval::union)
                    .unwrap_or(Interval::ALL)
            }
            E::Splat { value, .. } => self.of(value),
            E::Swizzle { vector, .. } => self.of(vector),
            // Of a vector: its bound; of a struct or array: unknown.
            E::AccessIndex { base, .. } | E::Access { base, .. } => {
                match self.info[base].ty.inner_with(&self.module.types) {
                    naga::TypeInner::Vector { .. } | naga::TypeInner::Matrix { .. } => {
                        self.of(base)
                    }
                    _ => Interval::ALL,
                }
            }
            E::Load { pointer } => self.load(pointer),
            E::Unary { op, expr } => {
                let x = self.of(expr);
                match op {
                    UnaryOperator::Negate => Interval::new(-x.hi, -x.lo),
                    UnaryOperator::LogicalNot => Interval::new(0.0, 1.0),
                    // Integers: bounded by their type (see `of`).
                    UnaryOperator::BitwiseNot => Interval::ALL,
                }
            }
            E::Binary { op, left, right } => self.binary(op, left, right),
            E::Select { accept, reject, .. } => self.of(accept).union(self.of(reject)),
            E::Relational { .. } => Interval::new(0.0, 1.0),
            E::Derivative { expr, .. } => {
                // A difference of two values of the expression.
                let x = self.of(expr);
                Interval::symmetric(x.hi - x.lo)
            }
            E::Math {
                fun,
                arg,
                arg1,
                arg2,
                ..
            } => self.math(fun, arg, arg1, arg2),
            // A numeric conversion keeps the value (an integer target
            // clamps it to its range, see `of`); a bitcast (`convert:
            // None`) is bounded by its type alone.
            E::As {
                expr: inner,
                convert: Some(_),
                ..
            } => self.of(inner),
            E::CallResult(function) => self.call(function, expr),
            E::ImageSample {
                depth_ref: Some(_), ..
            } => Interval::new(0.0, 1.0),
            // Textures, uniforms, storage, atomics, queries...
            _ => Interval::ALL,
        }
    }

    fn binary(
        &mut self,
        op: BinaryOperator,
        left: Handle<Expression>,
        right: Handle<Expression>,
    ) -> Interval {
        use BinaryOperator as B;
        // fract written out: x - floor(x) lies in [0, 1).
        if op == B::Subtract {
            if let Expression::Math {
                fun: MathFunction::Floor,
                arg,
                ..
            } = self.function.expressions[right]
            {
                if arg == left {
                    return Interval::new(0.0, 1.0);
                }
            }
        }
        let (a, b) = (self.of(left), self.of(right));
        let matrix = |h: Handle<Expression>, s: &Self| {
            matches!(
                s.info[h].ty.inner_with(&s.module.types),
                naga::TypeInner::Matrix { .. }
            )
        };
        match op {
            B::Add => a.add(b),
            B::Subtract => a.sub(b),
            B::Multiply if matrix(left, self) || matrix(right, self) => {
                // A sum of up to four products.
                let p = a.mul(b);
                Interval::symmetric(4.0 * p.magnitude())
            }
            B::Multiply => a.mul(b),
            B::Divide => a.div(b),
            // |x mod y| < |y|.
            B::Modulo => {
                if b.is_bounded() {
                    Interval::symmetric(b.magnitude())
                } else {
                    a
                }
            }
            B::Equal
            | B::NotEqual
            | B::Less
            | B::LessEqual
            | B::Greater
            | B::GreaterEqual
            | B::LogicalAnd
            | B::LogicalOr => Interval::new(0.0, 1.0),
            // x & m of unsigned values is at most m.
            B::And if a.lo >= 0.0 && b.lo >= 0.0 => Interval::new(0.0, a.hi.min(b.hi)),
            B::ShiftRight if a.lo >= 0.0 => Interval::new(0.0, a.hi),
            // Other integer operations: bounded by their type (see `of`).
            B::And | B::ExclusiveOr | B::InclusiveOr | B::ShiftLeft | B::ShiftRight => {
                Interval::ALL
            }
        }
    }

    fn math(
        &mut self,
        fun: MathFunction,
        arg: Handle<Expression>,
        arg1: Option<Handle<Expression>>,
        arg2: Option<Handle<Expression>>,
    ) -> Interval {
        use MathFunction as M;
        let x = self.of(arg);
        let mut second = || arg1.map_or(Interval::ALL, |h| self.of(h));
        let unit = Interval::new(0.0, 1.0);
        match fun {
            M::Abs => {
                if x.lo >= 0.0 {
                    x
                } else {
                    Interval::new(0.0, x.magnitude())
                }
            }
            M::Min => x.min(second()),
            M::Max => x.max(second()),
            M::Clamp => {
                let low = second();
                let high = arg2.map_or(Interval::ALL, |h| self.of(h));
                x.max(low).min(high)
            }
            M::Saturate | M::Step | M::SmoothStep | M::Fract => unit,
            M::Sin | M::Cos | M::Tanh | M::Sign | M::Normalize => Interval::new(-1.0, 1.0),
            M::Floor | M::Ceil | M::Round | M::Trunc => Interval::new(x.lo.floor(), x.hi.ceil()),
            M::Sqrt => Interval::new(x.lo.max(0.0).sqrt(), x.hi.max(0.0).sqrt()),
            M::Exp => Interval::new(x.lo.exp(), x.hi.exp()),
            M::Exp2 => Interval::new(x.lo.exp2(), x.hi.exp2()),
            M::Log if x.lo > 0.0 => Interval::new(x.lo.ln(), x.hi.ln()),
            M::Log2 if x.lo > 0.0 => Interval::new(x.lo.log2(), x.hi.log2()),
            M::Pow => {
                let y = second();
                if x.lo >= 0.0 && x.hi <= 1.0 && y.lo >= 0.0 {
                    unit
                } else if x.lo >= 0.0 && x.is_bounded() && y.is_bounded() {
                    // For x ≥ 0, x^y is monotone in x and in y: its
                    // extremes over the box are at the corners.
                    let corners = [
                        x.lo.powf(y.lo),
                        x.lo.powf(y.hi),
                        x.hi.powf(y.lo),
                        x.hi.powf(y.hi),
                    ];
                    Interval::new(
                        corners.iter().copied().fold(f64::INFINITY, f64::min),
                        corners.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                    )
                } else {
                    Interval::ALL
                }
            }
            M::Dot => match arg1 {
                Some(b) => self.dot(arg, b),
                None => Interval::ALL,
            },
            // Vectors of at most four components.
            M::Cross => Interval::symmetric(2.0 * x.magnitude() * second().magnitude()),
            M::Length => Interval::new(0.0, 2.0 * x.magnitude()),
            M::Distance => Interval::new(0.0, 2.0 * x.sub(second()).magnitude()),
            M::Mix => {
                // a + (b − a)·t
                let b = second();
                let t = arg2.map_or(Interval::ALL, |h| self.of(h));
                x.add(b.sub(x).mul(t))
            }
            M::Fma => {
                let b = second();
                let c = arg2.map_or(Interval::ALL, |h| self.of(h));
                x.mul(b).add(c)
            }
            _ => Interval::ALL,
        }
    }

    /// A load from a local variable: its initialiser and every value
    /// stored to it, where it is stored whole.
    fn load(&mut self, pointer: Handle<Expression>) -> Interval {
        let Expression::LocalVariable(variable) = self.function.expressions[pointer] else {
            return self.uniform(pointer);
        };
        let mut values = Vec::new();
        let mut partial = false;
        let function = self.function;
        let into_variable = |p: Handle<Expression>| matches!(pointer_root(function, p), Some(PointerRoot::Local(v)) if v == variable);
        each_statement(&function.body, &mut |statement| match *statement {
            naga::Statement::Store { pointer: p, value } if p == pointer => values.push(value),
            naga::Statement::Store { pointer: p, .. } if into_variable(p) => partial = true,
            // Passed to a helper, which may write through the pointer.
            naga::Statement::Call { ref arguments, .. }
                if arguments.iter().any(|&a| into_variable(a)) =>
            {
                partial = true
            }
            _ => {}
        });
        if partial {
            return Interval::ALL;
        }
        let mut range = match self.function.local_variables[variable].init {
            Some(init) => self.of(init),
            // Zero-initialised.
            None => Interval::point(0.0),
        };
        for value in values {
            range = range.union(self.of(value));
        }
        range
    }

    /// A load from a uniform: the bound the caller knows for its member
    /// (any component of it), or unbounded.
    fn uniform(&self, pointer: Handle<Expression>) -> Interval {
        // Walk down to the global, remembering the index taken just above it.
        let (mut at, mut member) = (pointer, None);
        let global = loop {
            match self.function.expressions[at] {
                Expression::AccessIndex { base, index } => {
                    member = Some(index);
                    at = base;
                }
                Expression::Access { base, .. } => {
                    member = None;
                    at = base;
                }
                Expression::GlobalVariable(global) => break global,
                _ => return Interval::ALL,
            }
        };
        let variable = &self.module.global_variables[global];
        let (naga::AddressSpace::Uniform, Some(binding)) = (variable.space, &variable.binding)
        else {
            return Interval::ALL;
        };
        let member = match self.module.types[variable.ty].inner {
            // A whole struct is not one value; a dynamic index into it
            // cannot occur.
            naga::TypeInner::Struct { .. } => match member {
                Some(index) => index,
                None => return Interval::ALL,
            },
            _ => 0,
        };
        self.uniforms.get(binding.group, binding.binding, member)
    }

    /// Whether `expr` is a unit vector: `normalize(...)`.
    fn is_unit(&self, expr: Handle<Expression>) -> bool {
        matches!(
            self.function.expressions[expr],
            Expression::Math {
                fun: MathFunction::Normalize,
                ..
            }
        )
    }

    /// The number of components of a vector value (1 for a scalar).
    fn components(&self, expr: Handle<Expression>) -> f64 {
        match *self.info[expr].ty.inner_with(&self.module.types) {
            naga::TypeInner::Vector { size, .. } => size as u8 as f64,
            _ => 1.0,
        }
    }

    /// A dot product: of two unit vectors, in [−1, 1]; of a vector with
    /// itself, non-negative; else a sum of `n` products.
    fn dot(&mut self, a: Handle<Expression>, b: Handle<Expression>) -> Interval {
        if self.is_unit(a) && self.is_unit(b) {
            return Interval::new(-1.0, 1.0);
        }
        let (x, y) = (self.of(a), self.of(b));
        let n = self.components(a);
        if a == b {
            let m = x.magnitude();
            return Interval::new(0.0, if m.is_finite() { n * m * m } else { m });
        }
        let product = x.mul(y);
        Interval::new(n * product.lo, n * product.hi)
    }

    /// A call's result: the callee's return values for these arguments.
    fn call(&mut self, callee: Handle<Function>, result: Handle<Expression>) -> Interval {
        if self.depth >= MAX_CALL_DEPTH {
            return Interval::ALL;
        }
        let mut arguments = None;
        each_statement(&self.function.body, &mut |statement| {
            if let naga::Statement::Call {
                result: Some(r),
                arguments: ref args,
                ..
            } = *statement
            {
                if r == result {
                    arguments = Some(args.clone());
                }
            }
        });
        let Some(arguments) = arguments else {
            return Interval::ALL;
        };
        let arguments: Vec<Interval> = arguments.iter().map(|&a| self.of(a)).collect();
        let whole = self.returned(callee, arguments.clone());
        // Interval arithmetic loses precision when a value is used several
        // times (t·t·(3 − 2t) on [0, 1] gives [−1, 3]). Splitting the
        // widest bounded argument into pieces and taking the union of the
        // pieces' results narrows that, at a few evaluations of the helper.
        let widest = (0..arguments.len())
            .filter(|&i| arguments[i].is_bounded() && arguments[i].hi > arguments[i].lo)
            .max_by(|&a, &b| {
                (arguments[a].hi - arguments[a].lo).total_cmp(&(arguments[b].hi - arguments[b].lo))
            });
        let Some(i) = widest.filter(|_| self.depth < 2) else {
            return whole;
        };
        let Interval { lo, hi } = arguments[i];
        let pieces = (0..SPLITS)
            .map(|k| {
                let mut split = arguments.clone();
                let at = |k: usize| lo + (hi - lo) * k as f64 / SPLITS as f64;
                split[i] = Interval::new(at(k), at(k + 1));
                self.returned(callee, split)
            })
            .reduce(Interval::union)
            .unwrap_or(whole);
        Interval::new(whole.lo.max(pieces.lo), whole.hi.min(pieces.hi))
    }

    /// The union of `callee`'s return values for `arguments`.
    fn returned(&self, callee: Handle<Function>, arguments: Vec<Interval>) -> Interval {
        let function = &self.module.functions[callee];
        let mut inner = Ranges {
            module: self.module,
            function,
            info: &self.module_info[callee],
            module_info: self.module_info,
            uniforms: self.uniforms,
            arguments,
            memo: HashMap::new(),
            depth: self.depth + 1,
        };
        let mut returns = Vec::new();
        each_statement(&function.body, &mut |statement| {
            if let naga::Statement::Return { value: Some(v) } = *statement {
                returns.push(v);
            }
        });
        returns
            .into_iter()
            .map(|v| inner.of(v))
            .reduce(Interval::union)
            .unwrap_or(Interval::ALL)
    }
}

fn literal_value(literal: naga::Literal) -> Option<f64> {
    use naga::Literal as L;
    Some(match literal {
        L::F64(v) => v,
        L::F32(v) => f64::from(v),
        L::F16(v) => f64::from(v.to_f32()),
        L::U32(v) => f64::from(v),
        L::U16(v) => f64::from(v),
        L::I16(v) => f64::from(v),
        L::I32(v) => f64::from(v),
        L::U64(v) => v as f64,
        L::I64(v) => v as f64,
        L::Bool(v) => f64::from(u8::from(v)),
        L::AbstractInt(v) => v as f64,
        L::AbstractFloat(v) => v,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range_of(source: &str, node_text: &str) -> Interval {
        range_with(source, node_text, &UniformBounds::default())
    }

    fn range_with(source: &str, node_text: &str, uniforms: &UniformBounds) -> Interval {
        let shader =
            crate::front::parse(crate::diagnostic::SourceFile::new("t.wgsl", source)).unwrap();
        let analysis = crate::analysis::analyze(&shader, &Default::default()).unwrap();
        let candidate = analysis
            .candidates
            .iter()
            .find(|c| c.node.text == node_text)
            .expect("the test names a candidate");
        EntryRanges::with_uniforms(&shader.module, &shader.info, analysis.entry_index, uniforms)
            .of(candidate.node.expression)
    }

    const SHADER: &str = "
struct P { scale: f32 }
@group(0) @binding(0) var<uniform> params: P;

fn wave(x: f32) -> f32 {
    let f = x - floor(x);
    return f * f * (3.0 - 2.0 * f);
}

@fragment
fn fs(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {
    let a = sin(uv.x * 40.0) * 3.0;
    let b = wave(uv.y * 9.0) * 100.0;
    let c = exp(uv.x * 20.0);
    let d = uv.y * params.scale;
    let e = clamp(d, -2.0, 2.0) + 1.0;
    let g = 1.0 / (a + 4.0);
    return vec4<f32>(a, b + c, d + e, g);
}
";

    #[test]
    fn bounded_operations_bound_their_values() {
        assert_eq!(
            range_of(SHADER, "sin(uv.x * 40.0) * 3.0"),
            Interval::new(-3.0, 3.0)
        );
        // The helper is followed: its `x - floor(x)` is in [0, 1].
        let b = range_of(SHADER, "wave(uv.y * 9.0) * 100.0");
        assert!(b.is_bounded() && b.fits_f16(), "{b:?}");
        assert_eq!(
            range_of(SHADER, "clamp(d, -2.0, 2.0) + 1.0"),
            Interval::new(-1.0, 3.0)
        );
    }

    #[test]
    fn inputs_uniforms_and_growth_may_exceed_f16() {
        assert!(!range_of(SHADER, "exp(uv.x * 20.0)").fits_f16());
        assert!(!range_of(SHADER, "uv.y * params.scale").fits_f16());
        // a + 4 lies in [1, 7]: the reciprocal is bounded.
        assert_eq!(
            range_of(SHADER, "1.0 / (a + 4.0)"),
            Interval::new(1.0 / 7.0, 1.0)
        );
    }

    #[test]
    fn the_marble_turbulence_fits_f16() {
        let source = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/noise_marble.wgsl"),
        )
        .unwrap();
        let turbulence = range_of(&source, "s4 + (0.0625 * abs(gradient_noise(p * 16.0)))");
        assert!(turbulence.fits_f16(), "{turbulence:?}");
        // The colour reads the light's colour, a uniform: unbounded.
        assert!(!range_of(&source, "(ambient_light * albedo) + direct").fits_f16());
    }

    #[test]
    fn known_uniform_values_bound_the_marble_colour() {
        let source = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/noise_marble.wgsl"),
        )
        .unwrap();
        // `Frame.light_color` is member 6 of the uniform at group 0, binding 0.
        let mut uniforms = UniformBounds::default();
        uniforms.observe(0, 0, 6, &[1.0, 0.97, 0.92]);
        let colour = range_with(&source, "(ambient_light * albedo) + direct", &uniforms);
        // light × (0.08·albedo + attenuation·(albedo·n·l + 0.35·specular)),
        // with attenuation in [0, 1] (a reciprocal of 1 + 0.05·|d|²), n·l
        // and the specular power of unit vectors in [0, 1].
        assert!(colour.is_bounded() && colour.fits_f16(), "{colour:?}");
        assert!(colour.hi < 2.0, "{colour:?}");
        // A light bright enough to overflow f16 is flagged.
        let mut bright = UniformBounds::default();
        bright.observe(0, 0, 6, &[1.0e5, 0.0, 0.0]);
        assert!(!range_with(&source, "(ambient_light * albedo) + direct", &bright).fits_f16());
        // Another member's bound does not bound the light's colour.
        let mut other = UniformBounds::default();
        other.observe(0, 0, 5, &[4.0]);
        assert!(!range_with(&source, "(ambient_light * albedo) + direct", &other).is_bounded());
    }

    #[test]
    fn bounds_in_words() {
        assert_eq!(describe([Some(0.0), Some(1.5)]), "in [0, 1.5]");
        assert_eq!(
            describe([Some(-1e6), Some(2e-5)]),
            "in [-1.000e6, 2.000e-5]"
        );
        assert_eq!(describe([None, None]), "unbounded");
        assert_eq!(describe([Some(0.25), None]), "at least 0.25");
        assert_eq!(describe([None, Some(3.0)]), "at most 3");
    }

    #[test]
    fn products_with_unbounded_ends_keep_their_sign() {
        let half = Interval::new(0.0, f64::INFINITY);
        assert_eq!(Interval::new(0.0, 1.0).mul(half), half);
        assert_eq!(
            Interval::point(0.0).mul(Interval::ALL),
            Interval::point(0.0)
        );
        assert_eq!(Interval::new(-1.0, 1.0).mul(half), Interval::ALL);
        // 1 / (1 + [0, ∞)) is in [0, 1].
        assert_eq!(
            Interval::point(1.0).div(Interval::point(1.0).add(half)),
            Interval::new(0.0, 1.0)
        );
    }

    #[test]
    fn dot_products_of_unit_vectors_and_of_a_vector_with_itself() {
        const DOTS: &str = "
@fragment
fn fs(@location(0) a: vec3<f32>, @location(1) b: vec3<f32>) -> @location(0) vec4<f32> {
    let cosine = dot(normalize(a), normalize(b));
    let falloff = 1.0 / (1.0 + dot(a, a));
    let raw = dot(a, b);
    return vec4<f32>(cosine, falloff, raw, 1.0);
}
";
        assert_eq!(
            range_of(DOTS, "dot(normalize(a), normalize(b))"),
            Interval::new(-1.0, 1.0)
        );
        assert_eq!(
            range_of(DOTS, "1.0 / (1.0 + dot(a, a))"),
            Interval::new(0.0, 1.0)
        );
        assert!(!range_of(DOTS, "dot(a, b)").is_bounded());
    }
}

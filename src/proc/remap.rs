//! Handle remapping: rewriting an expression or statement so that every
//! handle it holds points into another arena.
//!
//! naga has no public helper for this (its own is crate-private), and every
//! IR transform needs it: copying part of a function into a new one,
//! importing the toolchain's own WGSL into a user's module. One exhaustive
//! match over expressions and one over statements live here, so a new naga
//! variant is a compile error in one place.

use naga::{Expression, Handle, Statement};

/// Where each kind of handle goes. Implementors decide what a handle maps
/// to; copying code calls these for every handle it meets. Expressions
/// always move (they live in a function's arena); the rest keep their
/// handle unless the implementor says otherwise, as a copy within one
/// module does.
pub trait Mapper {
    fn expression(&mut self, handle: Handle<Expression>) -> Handle<Expression>;
    fn ty(&mut self, handle: Handle<naga::Type>) -> Handle<naga::Type> {
        handle
    }
    fn constant(&mut self, handle: Handle<naga::Constant>) -> Handle<naga::Constant> {
        handle
    }
    fn override_(&mut self, handle: Handle<naga::Override>) -> Handle<naga::Override> {
        handle
    }
    fn global(&mut self, handle: Handle<naga::GlobalVariable>) -> Handle<naga::GlobalVariable> {
        handle
    }
    fn local(&mut self, handle: Handle<naga::LocalVariable>) -> Handle<naga::LocalVariable> {
        handle
    }
    fn function(&mut self, handle: Handle<naga::Function>) -> Handle<naga::Function> {
        handle
    }
}

/// `expr` with every handle mapped.
pub fn expression(expr: &Expression, m: &mut impl Mapper) -> Expression {
    use Expression as E;
    match *expr {
        E::Literal(literal) => E::Literal(literal),
        E::Constant(c) => E::Constant(m.constant(c)),
        E::Override(o) => E::Override(m.override_(o)),
        E::ZeroValue(ty) => E::ZeroValue(m.ty(ty)),
        E::Compose { ty, ref components } => E::Compose {
            ty: m.ty(ty),
            components: components.iter().map(|&c| m.expression(c)).collect(),
        },
        E::Access { base, index } => E::Access {
            base: m.expression(base),
            index: m.expression(index),
        },
        E::AccessIndex { base, index } => E::AccessIndex {
            base: m.expression(base),
            index,
        },
        E::Splat { size, value } => E::Splat {
            size,
            value: m.expression(value),
        },
        E::Swizzle {
            size,
            vector,
            pattern,
        } => E::Swizzle {
            size,
            vector: m.expression(vector),
            pattern,
        },
        E::FunctionArgument(index) => E::FunctionArgument(index),
        E::GlobalVariable(g) => E::GlobalVariable(m.global(g)),
        E::LocalVariable(l) => E::LocalVariable(m.local(l)),
        E::Load { pointer } => E::Load {
            pointer: m.expression(pointer),
        },
        E::ImageSample { .. } | E::ImageLoad { .. } | E::ImageQuery { .. } => image(expr, m),
        E::Unary { .. }
        | E::Binary { .. }
        | E::Select { .. }
        | E::Derivative { .. }
        | E::Relational { .. }
        | E::Math { .. }
        | E::As { .. } => arithmetic(expr, m),
        E::CallResult(f) => E::CallResult(m.function(f)),
        E::AtomicResult { ty, comparison } => E::AtomicResult {
            ty: m.ty(ty),
            comparison,
        },
        E::WorkGroupUniformLoadResult { ty } => E::WorkGroupUniformLoadResult { ty: m.ty(ty) },
        E::ArrayLength(h) => E::ArrayLength(m.expression(h)),
        E::RayQueryVertexPositions { query, committed } => E::RayQueryVertexPositions {
            query: m.expression(query),
            committed,
        },
        E::RayQueryProceedResult => E::RayQueryProceedResult,
        E::RayQueryGetIntersection { query, committed } => E::RayQueryGetIntersection {
            query: m.expression(query),
            committed,
        },
        E::SubgroupBallotResult => E::SubgroupBallotResult,
        E::SubgroupOperationResult { ty } => E::SubgroupOperationResult { ty: m.ty(ty) },
        E::CooperativeLoad {
            columns,
            rows,
            role,
            ref data,
        } => E::CooperativeLoad {
            columns,
            rows,
            role,
            data: cooperative_data(data, m),
        },
        E::CooperativeMultiplyAdd { a, b, c } => E::CooperativeMultiplyAdd {
            a: m.expression(a),
            b: m.expression(b),
            c: m.expression(c),
        },
    }
}

/// An image expression with its handles mapped; [`expression`] calls it
/// for those alone (anything else comes back as it is).
fn image(expr: &Expression, m: &mut impl Mapper) -> Expression {
    use Expression as E;
    match *expr {
        E::ImageSample {
            image,
            sampler,
            gather,
            coordinate,
            array_index,
            offset,
            level,
            depth_ref,
            clamp_to_edge,
        } => E::ImageSample {
            image: m.expression(image),
            sampler: m.expression(sampler),
            gather,
            coordinate: m.expression(coordinate),
            array_index: array_index.map(|h| m.expression(h)),
            offset: offset.map(|h| m.expression(h)),
            level: sample_level(level, m),
            depth_ref: depth_ref.map(|h| m.expression(h)),
            clamp_to_edge,
        },
        E::ImageLoad {
            image,
            coordinate,
            array_index,
            sample,
            level,
        } => E::ImageLoad {
            image: m.expression(image),
            coordinate: m.expression(coordinate),
            array_index: array_index.map(|h| m.expression(h)),
            sample: sample.map(|h| m.expression(h)),
            level: level.map(|h| m.expression(h)),
        },
        E::ImageQuery { image, query } => E::ImageQuery {
            image: m.expression(image),
            query: match query {
                naga::ImageQuery::Size { level } => naga::ImageQuery::Size {
                    level: level.map(|h| m.expression(h)),
                },
                other => other,
            },
        },
        ref other => other.clone(),
    }
}

/// An arithmetic expression with its handles mapped; [`expression`]
/// calls it for those alone (anything else comes back as it is).
fn arithmetic(expr: &Expression, m: &mut impl Mapper) -> Expression {
    use Expression as E;
    match *expr {
        E::Unary { op, expr } => E::Unary {
            op,
            expr: m.expression(expr),
        },
        E::Binary { op, left, right } => E::Binary {
            op,
            left: m.expression(left),
            right: m.expression(right),
        },
        E::Select {
            condition,
            accept,
            reject,
        } => E::Select {
            condition: m.expression(condition),
            accept: m.expression(accept),
            reject: m.expression(reject),
        },
        E::Derivative { axis, ctrl, expr } => E::Derivative {
            axis,
            ctrl,
            expr: m.expression(expr),
        },
        E::Relational { fun, argument } => E::Relational {
            fun,
            argument: m.expression(argument),
        },
        E::Math {
            fun,
            arg,
            arg1,
            arg2,
            arg3,
        } => E::Math {
            fun,
            arg: m.expression(arg),
            arg1: arg1.map(|h| m.expression(h)),
            arg2: arg2.map(|h| m.expression(h)),
            arg3: arg3.map(|h| m.expression(h)),
        },
        E::As {
            expr,
            kind,
            convert,
        } => E::As {
            expr: m.expression(expr),
            kind,
            convert,
        },
        ref other => other.clone(),
    }
}

fn sample_level(level: naga::SampleLevel, m: &mut impl Mapper) -> naga::SampleLevel {
    use naga::SampleLevel as L;
    match level {
        L::Auto => L::Auto,
        L::Zero => L::Zero,
        L::Exact(h) => L::Exact(m.expression(h)),
        L::Bias(h) => L::Bias(m.expression(h)),
        L::Gradient { x, y } => L::Gradient {
            x: m.expression(x),
            y: m.expression(y),
        },
    }
}

fn cooperative_data(data: &naga::CooperativeData, m: &mut impl Mapper) -> naga::CooperativeData {
    naga::CooperativeData {
        pointer: m.expression(data.pointer),
        stride: m.expression(data.stride),
        row_major: data.row_major,
    }
}

/// A statement that holds no block and no expression range, with every
/// handle mapped. `None` for `Emit`, `Block`, `If`, `Switch` and `Loop`:
/// the caller walks those itself, since it decides what of them to keep.
pub fn simple_statement(statement: &Statement, m: &mut impl Mapper) -> Option<Statement> {
    use Statement as S;
    Some(match *statement {
        S::Emit(_) | S::Block(_) | S::If { .. } | S::Switch { .. } | S::Loop { .. } => return None,
        S::Break => S::Break,
        S::Continue => S::Continue,
        S::Kill => S::Kill,
        S::Return { value } => S::Return {
            value: value.map(|h| m.expression(h)),
        },
        S::ControlBarrier(barrier) => S::ControlBarrier(barrier),
        S::MemoryBarrier(barrier) => S::MemoryBarrier(barrier),
        S::Store { pointer, value } => S::Store {
            pointer: m.expression(pointer),
            value: m.expression(value),
        },
        S::ImageStore {
            image,
            coordinate,
            array_index,
            value,
        } => S::ImageStore {
            image: m.expression(image),
            coordinate: m.expression(coordinate),
            array_index: array_index.map(|h| m.expression(h)),
            value: m.expression(value),
        },
        S::Atomic {
            pointer,
            ref fun,
            value,
            result,
        } => S::Atomic {
            pointer: m.expression(pointer),
            fun: atomic_function(fun, m),
            value: m.expression(value),
            result: result.map(|h| m.expression(h)),
        },
        S::ImageAtomic {
            image,
            coordinate,
            array_index,
            ref fun,
            value,
        } => S::ImageAtomic {
            image: m.expression(image),
            coordinate: m.expression(coordinate),
            array_index: array_index.map(|h| m.expression(h)),
            fun: atomic_function(fun, m),
            value: m.expression(value),
        },
        S::WorkGroupUniformLoad { pointer, result } => S::WorkGroupUniformLoad {
            pointer: m.expression(pointer),
            result: m.expression(result),
        },
        S::Call {
            function,
            ref arguments,
            result,
        } => S::Call {
            function: m.function(function),
            arguments: arguments.iter().map(|&h| m.expression(h)).collect(),
            result: result.map(|h| m.expression(h)),
        },
        S::RayQuery { query, ref fun } => S::RayQuery {
            query: m.expression(query),
            fun: match *fun {
                naga::RayQueryFunction::Initialize {
                    acceleration_structure,
                    descriptor,
                } => naga::RayQueryFunction::Initialize {
                    acceleration_structure: m.expression(acceleration_structure),
                    descriptor: m.expression(descriptor),
                },
                naga::RayQueryFunction::Proceed { result } => naga::RayQueryFunction::Proceed {
                    result: m.expression(result),
                },
                naga::RayQueryFunction::GenerateIntersection { hit_t } => {
                    naga::RayQueryFunction::GenerateIntersection {
                        hit_t: m.expression(hit_t),
                    }
                }
                naga::RayQueryFunction::ConfirmIntersection => {
                    naga::RayQueryFunction::ConfirmIntersection
                }
                naga::RayQueryFunction::Terminate => naga::RayQueryFunction::Terminate,
            },
        },
        S::RayPipelineFunction(naga::RayPipelineFunction::TraceRay {
            acceleration_structure,
            descriptor,
            payload,
        }) => S::RayPipelineFunction(naga::RayPipelineFunction::TraceRay {
            acceleration_structure: m.expression(acceleration_structure),
            descriptor: m.expression(descriptor),
            payload: m.expression(payload),
        }),
        S::SubgroupBallot { result, predicate } => S::SubgroupBallot {
            result: m.expression(result),
            predicate: predicate.map(|h| m.expression(h)),
        },
        S::SubgroupGather {
            mode,
            argument,
            result,
        } => S::SubgroupGather {
            mode: gather_mode(mode, m),
            argument: m.expression(argument),
            result: m.expression(result),
        },
        S::SubgroupCollectiveOperation {
            op,
            collective_op,
            argument,
            result,
        } => S::SubgroupCollectiveOperation {
            op,
            collective_op,
            argument: m.expression(argument),
            result: m.expression(result),
        },
        S::CooperativeStore { target, ref data } => S::CooperativeStore {
            target: m.expression(target),
            data: cooperative_data(data, m),
        },
    })
}

fn atomic_function(fun: &naga::AtomicFunction, m: &mut impl Mapper) -> naga::AtomicFunction {
    match *fun {
        naga::AtomicFunction::Exchange { compare } => naga::AtomicFunction::Exchange {
            compare: compare.map(|h| m.expression(h)),
        },
        other => other,
    }
}

fn gather_mode(mode: naga::GatherMode, m: &mut impl Mapper) -> naga::GatherMode {
    use naga::GatherMode as G;
    match mode {
        G::BroadcastFirst => G::BroadcastFirst,
        G::Broadcast(h) => G::Broadcast(m.expression(h)),
        G::Shuffle(h) => G::Shuffle(m.expression(h)),
        G::ShuffleDown(h) => G::ShuffleDown(m.expression(h)),
        G::ShuffleUp(h) => G::ShuffleUp(m.expression(h)),
        G::ShuffleXor(h) => G::ShuffleXor(m.expression(h)),
        G::QuadBroadcast(h) => G::QuadBroadcast(m.expression(h)),
        G::QuadSwap(direction) => G::QuadSwap(direction),
    }
}

/// `inner` with its type handles mapped.
pub fn type_inner(inner: &naga::TypeInner, m: &mut impl Mapper) -> naga::TypeInner {
    use naga::TypeInner as T;
    match *inner {
        T::Pointer { base, space } => T::Pointer {
            base: m.ty(base),
            space,
        },
        T::Array { base, size, stride } => T::Array {
            base: m.ty(base),
            size: array_size(size, m),
            stride,
        },
        T::BindingArray { base, size } => T::BindingArray {
            base: m.ty(base),
            size: array_size(size, m),
        },
        T::Struct { ref members, span } => T::Struct {
            members: members
                .iter()
                .map(|member| naga::StructMember {
                    name: member.name.clone(),
                    ty: m.ty(member.ty),
                    binding: member.binding.clone(),
                    offset: member.offset,
                })
                .collect(),
            span,
        },
        ref other => other.clone(),
    }
}

fn array_size(size: naga::ArraySize, m: &mut impl Mapper) -> naga::ArraySize {
    match size {
        naga::ArraySize::Pending(o) => naga::ArraySize::Pending(m.override_(o)),
        other => other,
    }
}

/// `block` with every handle mapped, statements in order (nested blocks in
/// turn, a loop's body before its continuing block, as
/// [`super::each_statement`] visits them). `replace` may put something
/// else in place of a statement: it returns whether it did. An `Emit` of
/// handles that no longer follow each other becomes one per run. Spans are
/// kept when `keep_spans`.
pub fn block(
    block: &naga::Block,
    m: &mut impl Mapper,
    keep_spans: bool,
    replace: &mut dyn FnMut(&Statement, naga::Span, &mut naga::Block) -> bool,
) -> naga::Block {
    let mut out = naga::Block::new();
    for (statement, &span) in block.span_iter() {
        if replace(statement, span, &mut out) {
            continue;
        }
        let span = if keep_spans {
            span
        } else {
            naga::Span::UNDEFINED
        };
        let copied = match *statement {
            Statement::Emit(ref range) => {
                emits(range, m, span, &mut out);
                continue;
            }
            Statement::Block(ref inner) => {
                Statement::Block(self::block(inner, m, keep_spans, replace))
            }
            Statement::If {
                condition,
                ref accept,
                ref reject,
            } => Statement::If {
                condition: m.expression(condition),
                accept: self::block(accept, m, keep_spans, replace),
                reject: self::block(reject, m, keep_spans, replace),
            },
            Statement::Switch {
                selector,
                ref cases,
            } => {
                let selector = m.expression(selector);
                let mut copied = Vec::with_capacity(cases.len());
                for case in cases {
                    copied.push(naga::SwitchCase {
                        value: case.value,
                        body: self::block(&case.body, m, keep_spans, replace),
                        fall_through: case.fall_through,
                    });
                }
                Statement::Switch {
                    selector,
                    cases: copied,
                }
            }
            Statement::Loop {
                ref body,
                ref continuing,
                break_if,
            } => Statement::Loop {
                body: self::block(body, m, keep_spans, replace),
                continuing: self::block(continuing, m, keep_spans, replace),
                break_if: break_if.map(|b| m.expression(b)),
            },
            ref simple => match simple_statement(simple, m) {
                Some(copied) => copied,
                None => continue,
            },
        };
        out.push(copied, span);
    }
    out
}

/// `range` mapped, as the fewest ranges of consecutive handles.
fn emits(
    range: &naga::Range<Expression>,
    m: &mut impl Mapper,
    span: naga::Span,
    out: &mut naga::Block,
) {
    let mut run: Option<(Handle<Expression>, Handle<Expression>)> = None;
    for handle in range.clone() {
        let new = m.expression(handle);
        run = match run {
            Some((first, last)) if new.index() == last.index() + 1 => Some((first, new)),
            Some((first, last)) => {
                out.push(
                    Statement::Emit(naga::Range::new_from_bounds(first, last)),
                    span,
                );
                Some((new, new))
            }
            None => Some((new, new)),
        };
    }
    if let Some((first, last)) = run {
        out.push(
            Statement::Emit(naga::Range::new_from_bounds(first, last)),
            span,
        );
    }
}

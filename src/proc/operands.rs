use naga::{Expression, Handle};

/// The expressions `expr` reads directly, in a fixed order.
pub fn operands(expr: &Expression) -> Vec<Handle<Expression>> {
    let mut out = Vec::new();
    match *expr {
        Expression::Literal(_)
        | Expression::Constant(_)
        | Expression::Override(_)
        | Expression::ZeroValue(_)
        | Expression::FunctionArgument(_)
        | Expression::GlobalVariable(_)
        | Expression::LocalVariable(_)
        | Expression::CallResult(_)
        | Expression::AtomicResult { .. }
        | Expression::WorkGroupUniformLoadResult { .. }
        | Expression::RayQueryProceedResult
        | Expression::SubgroupBallotResult
        | Expression::SubgroupOperationResult { .. } => {}
        Expression::Compose { ref components, .. } => out.extend(components.iter().copied()),
        Expression::Access { base, index } => out.extend([base, index]),
        Expression::AccessIndex { base, .. } => out.push(base),
        Expression::Splat { value, .. } => out.push(value),
        Expression::Swizzle { vector, .. } => out.push(vector),
        Expression::Load { pointer } => out.push(pointer),
        Expression::ImageSample {
            image,
            sampler,
            coordinate,
            array_index,
            offset,
            level,
            depth_ref,
            ..
        } => {
            out.extend([image, sampler, coordinate]);
            out.extend(array_index);
            out.extend(offset);
            match level {
                naga::SampleLevel::Auto | naga::SampleLevel::Zero => {}
                naga::SampleLevel::Exact(h) | naga::SampleLevel::Bias(h) => out.push(h),
                naga::SampleLevel::Gradient { x, y } => out.extend([x, y]),
            }
            out.extend(depth_ref);
        }
        Expression::ImageLoad {
            image,
            coordinate,
            array_index,
            sample,
            level,
        } => {
            out.extend([image, coordinate]);
            out.extend(array_index);
            out.extend(sample);
            out.extend(level);
        }
        Expression::ImageQuery { image, query } => {
            out.push(image);
            if let naga::ImageQuery::Size { level: Some(level) } = query {
                out.push(level);
            }
        }
        Expression::Unary { expr, .. } => out.push(expr),
        Expression::Binary { left, right, .. } => out.extend([left, right]),
        Expression::Select {
            condition,
            accept,
            reject,
        } => out.extend([condition, accept, reject]),
        Expression::Derivative { expr, .. } => out.push(expr),
        Expression::Relational { argument, .. } => out.push(argument),
        Expression::Math {
            arg,
            arg1,
            arg2,
            arg3,
            ..
        } => {
            out.push(arg);
            out.extend(arg1);
            out.extend(arg2);
            out.extend(arg3);
        }
        Expression::As { expr, .. } => out.push(expr),
        Expression::ArrayLength(expr) => out.push(expr),
        Expression::RayQueryVertexPositions { query, .. }
        | Expression::RayQueryGetIntersection { query, .. } => out.push(query),
        Expression::CooperativeLoad { ref data, .. } => out.extend([data.pointer, data.stride]),
        Expression::CooperativeMultiplyAdd { a, b, c } => out.extend([a, b, c]),
    }
    out
}

/// What a pointer expression ultimately points into.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PointerRoot {
    Local(Handle<naga::LocalVariable>),
    Global(Handle<naga::GlobalVariable>),
    /// A pointer passed in as an argument (helper functions only).
    Argument(u32),
}

/// Follows `Access`/`AccessIndex` chains from a pointer to the variable it
/// points into. `None` when `pointer` is not a pointer into a variable.
pub fn pointer_root(function: &naga::Function, pointer: Handle<Expression>) -> Option<PointerRoot> {
    let mut current = pointer;
    loop {
        match function.expressions[current] {
            Expression::Access { base, .. } | Expression::AccessIndex { base, .. } => {
                current = base
            }
            Expression::LocalVariable(local) => return Some(PointerRoot::Local(local)),
            Expression::GlobalVariable(global) => return Some(PointerRoot::Global(global)),
            Expression::FunctionArgument(index) => return Some(PointerRoot::Argument(index)),
            _ => return None,
        }
    }
}

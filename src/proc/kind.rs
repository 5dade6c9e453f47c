//! What each naga expression does, in one exhaustive match.
//!
//! The analysis (does a slice compute anything?), the cost model (what
//! does it cost?) and the uniformity reasoning ask the same question of
//! every expression. Each used to keep its own list of naga's variants,
//! ending in a wildcard or a `matches!`: a variant a naga upgrade adds
//! would have fallen silently into whichever arm came last. Here the match
//! has no wildcard, so such a variant fails to compile until it is given
//! its kind, and every stage that asks follows.

use naga::Expression;

/// What an expression does, at the level the stages reason at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExpressionKind {
    /// Names a value or a place and computes nothing: a literal, a
    /// constant, an override, a zero value, an argument, a variable.
    Name,
    /// Moves data without arithmetic: a composition, a splat, a swizzle, a
    /// constant index.
    Move,
    /// A dynamic index: an address computation.
    DynamicIndex,
    /// A load through a pointer: from memory when it points into a
    /// uniform, storage or immediate variable, from a register otherwise.
    Load,
    /// A filtered texture sample.
    Sample,
    /// An unfiltered texel load.
    TexelLoad,
    /// A query of a resource's size or levels, or a runtime array's length.
    Query,
    /// Arithmetic on values: unary and binary operators, `select`,
    /// conversions, relational and math built-ins.
    Arithmetic,
    /// A screen-space derivative.
    Derivative,
    /// A function's result.
    Call,
    /// The result a statement left: atomics, workgroup-uniform loads,
    /// subgroup operations, ray queries, cooperative matrices. They read
    /// memory or other invocations.
    StatementResult,
}

impl ExpressionKind {
    /// Whether the expression only names or moves data: no arithmetic, no
    /// texture or memory access beyond a plain load.
    pub fn moves_data_only(self) -> bool {
        matches!(
            self,
            ExpressionKind::Name
                | ExpressionKind::Move
                | ExpressionKind::DynamicIndex
                | ExpressionKind::Load
        )
    }
}

/// What `expr` does. Exhaustive over naga's expressions, on purpose.
pub fn kind(expr: &Expression) -> ExpressionKind {
    use ExpressionKind as K;
    match *expr {
        Expression::Literal(_)
        | Expression::Constant(_)
        | Expression::Override(_)
        | Expression::ZeroValue(_)
        | Expression::FunctionArgument(_)
        | Expression::GlobalVariable(_)
        | Expression::LocalVariable(_) => K::Name,
        Expression::Compose { .. }
        | Expression::Splat { .. }
        | Expression::Swizzle { .. }
        | Expression::AccessIndex { .. } => K::Move,
        Expression::Access { .. } => K::DynamicIndex,
        Expression::Load { .. } => K::Load,
        Expression::ImageSample { .. } => K::Sample,
        Expression::ImageLoad { .. } => K::TexelLoad,
        Expression::ImageQuery { .. } | Expression::ArrayLength(_) => K::Query,
        Expression::Unary { .. }
        | Expression::Binary { .. }
        | Expression::Select { .. }
        | Expression::As { .. }
        | Expression::Relational { .. }
        | Expression::Math { .. } => K::Arithmetic,
        Expression::Derivative { .. } => K::Derivative,
        Expression::CallResult(_) => K::Call,
        Expression::AtomicResult { .. }
        | Expression::WorkGroupUniformLoadResult { .. }
        | Expression::SubgroupBallotResult
        | Expression::SubgroupOperationResult { .. }
        | Expression::RayQueryProceedResult
        | Expression::RayQueryGetIntersection { .. }
        | Expression::RayQueryVertexPositions { .. }
        | Expression::CooperativeLoad { .. }
        | Expression::CooperativeMultiplyAdd { .. } => K::StatementResult,
    }
}

/// Whether `expr` takes implicit derivatives: an explicit derivative, or
/// a sample whose level the hardware picks from them.
pub fn takes_derivatives(expr: &Expression) -> bool {
    match kind(expr) {
        ExpressionKind::Derivative => true,
        ExpressionKind::Sample => matches!(
            *expr,
            Expression::ImageSample {
                level: naga::SampleLevel::Auto | naga::SampleLevel::Bias(_),
                ..
            }
        ),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kinds the stages tell apart, on a shader that has each.
    #[test]
    fn kinds_of_a_fragment_shaders_expressions() {
        let module = naga::front::wgsl::parse_str(
            "@group(0) @binding(0) var t: texture_2d<f32>;
             @group(0) @binding(1) var s: sampler;
             @group(0) @binding(2) var<uniform> u: vec4<f32>;
             fn f(x: f32) -> f32 { return x; }
             @fragment fn main(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {
                 let c = textureSample(t, s, uv);
                 let l = textureSampleLevel(t, s, uv, 0.0);
                 let d = dpdx(uv.x);
                 return vec4<f32>(c.x * d + l.y + f(u.z), 0.0, 0.0, 1.0);
             }",
        )
        .expect("parses");
        let main = &module.entry_points[0].function;
        let kinds: Vec<ExpressionKind> = main.expressions.iter().map(|(_, e)| kind(e)).collect();
        for wanted in [
            ExpressionKind::Name,
            ExpressionKind::Move,
            ExpressionKind::Load,
            ExpressionKind::Sample,
            ExpressionKind::Arithmetic,
            ExpressionKind::Derivative,
            ExpressionKind::Call,
        ] {
            assert!(kinds.contains(&wanted), "{wanted:?} in {kinds:?}");
        }
        let derivatives = main
            .expressions
            .iter()
            .filter(|(_, e)| takes_derivatives(e))
            .count();
        // dpdx and the implicit-level sample, not the explicit-level one.
        assert_eq!(derivatives, 2);
    }
}

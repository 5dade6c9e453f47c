//! The rewriter's own check that no implicit-derivative operation ended up
//! in non-uniform control flow.
//!
//! WGSL requires `textureSample`, `textureSampleBias`,
//! `textureSampleCompare` and `dpdx`/`dpdy`/`fwidth` (and variants) to run
//! in uniform control flow. naga 30 does not enforce this in fragment
//! shaders, so a variant that moved such an operation into its hit/miss
//! branch would pass naga and fail in browsers. This check runs on every
//! pass before it is written: a violation is a bug in the rewrite, caught
//! here rather than by an external validator.

use std::fmt;

use naga::valid::ModuleInfo;
use naga::{Block, Expression, Function, Handle, Module, Statement};

/// An implicit-derivative operation in non-uniform control flow.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    pub entry_point: String,
    pub what: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} in non-uniform control flow in entry point `{}`",
            self.what, self.entry_point
        )
    }
}

/// Checks every fragment entry point of `module`.
pub fn check(module: &Module, info: &ModuleInfo) -> Result<(), Violation> {
    for (index, entry) in module.entry_points.iter().enumerate() {
        if entry.stage != naga::ShaderStage::Fragment {
            continue;
        }
        let checker = Checker {
            module,
            function: &entry.function,
            info: info.get_entry_point(index),
        };
        if let Some(what) = checker.block(&entry.function.body, false) {
            return Err(Violation {
                entry_point: entry.name.clone(),
                what,
            });
        }
    }
    Ok(())
}

struct Checker<'a> {
    module: &'a Module,
    function: &'a Function,
    info: &'a naga::valid::FunctionInfo,
}

impl Checker<'_> {
    fn non_uniform(&self, expr: Handle<Expression>) -> bool {
        self.info[expr].uniformity.non_uniform_result.is_some()
    }

    /// The first violation in `block`, entered in non-uniform control flow
    /// when `divergent`.
    fn block(&self, block: &Block, divergent: bool) -> Option<String> {
        for statement in block.iter() {
            let found = match *statement {
                Statement::Emit(ref range) if divergent => range
                    .clone()
                    .find_map(|h| implicit_derivative(&self.function.expressions[h])),
                Statement::Call { function, .. }
                    if divergent && needs_derivatives(self.module, function) =>
                {
                    Some(format!(
                        "a call of `{}`, which takes implicit derivatives,",
                        self.module.functions[function]
                            .name
                            .as_deref()
                            .unwrap_or("?")
                    ))
                }
                Statement::Block(ref inner) => self.block(inner, divergent),
                Statement::If {
                    condition,
                    ref accept,
                    ref reject,
                } => {
                    let inner = divergent || self.non_uniform(condition);
                    self.block(accept, inner)
                        .or_else(|| self.block(reject, inner))
                }
                Statement::Switch {
                    selector,
                    ref cases,
                } => {
                    let inner = divergent || self.non_uniform(selector);
                    cases.iter().find_map(|case| self.block(&case.body, inner))
                }
                Statement::Loop {
                    ref body,
                    ref continuing,
                    break_if,
                } => {
                    // A loop is divergent when any exit condition inside it is.
                    let mut conditions = Vec::new();
                    crate::proc::each_statement(body, &mut |s| match *s {
                        Statement::If { condition, .. } => conditions.push(condition),
                        Statement::Switch { selector, .. } => conditions.push(selector),
                        _ => {}
                    });
                    conditions.extend(break_if);
                    let inner = divergent || conditions.iter().any(|&c| self.non_uniform(c));
                    self.block(body, inner)
                        .or_else(|| self.block(continuing, inner))
                }
                _ => None,
            };
            if found.is_some() {
                return found;
            }
        }
        None
    }
}

/// Describes `expr` if it takes implicit derivatives.
pub fn implicit_derivative(expr: &Expression) -> Option<String> {
    match *expr {
        Expression::Derivative { axis, .. } => Some(
            match axis {
                naga::DerivativeAxis::X => "dpdx",
                naga::DerivativeAxis::Y => "dpdy",
                naga::DerivativeAxis::Width => "fwidth",
            }
            .into(),
        ),
        Expression::ImageSample {
            level, depth_ref, ..
        } => match level {
            naga::SampleLevel::Auto if depth_ref.is_some() => Some("textureSampleCompare".into()),
            naga::SampleLevel::Auto => Some("textureSample".into()),
            naga::SampleLevel::Bias(_) => Some("textureSampleBias".into()),
            _ => None,
        },
        _ => None,
    }
}

/// Whether calling `function` takes implicit derivatives, directly or
/// through its callees.
pub fn needs_derivatives(module: &Module, function: Handle<Function>) -> bool {
    let f = &module.functions[function];
    if f.expressions
        .iter()
        .any(|(_, e)| implicit_derivative(e).is_some())
    {
        return true;
    }
    let mut found = false;
    crate::proc::each_statement(&f.body, &mut |s| {
        if let Statement::Call { function, .. } = *s {
            found |= needs_derivatives(module, function);
        }
    });
    found
}

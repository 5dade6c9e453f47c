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
//!
//! [`check_kills`] is the other half: naga writes WGSL's `discard` as
//! SPIR-V `OpKill`, which ends the invocation instead of demoting it to a
//! helper, so a derivative taken after a kill is undefined in every quad
//! a killed lane leaves. Every validator and lavapipe pass it; this check
//! walks the IR.

use std::fmt;

use naga::valid::ModuleInfo;
use naga::{Block, Expression, Function, Handle, Module, Statement};

/// An implicit-derivative operation in non-uniform control flow.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The entry point it is in.
    pub entry_point: String,
    /// What takes the derivative, in words.
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

/// A derivative (or implicit-LOD sample) that can run after a `discard`
/// the rewrite put in a pass's entry point.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AfterKill {
    /// The entry point it is in.
    pub entry_point: String,
    /// What takes the derivative, in words.
    pub what: String,
}

impl fmt::Display for AfterKill {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} after a `discard` in entry point `{}` (naga writes it as OpKill: the derivative is undefined in quads it leaves)",
            self.what, self.entry_point
        )
    }
}

/// Checks that no derivative can run after a `discard` of a fragment entry
/// point's own body, there or in what it calls later. The shader's own
/// `discard`s, inside the helpers copied from it, are the shader's: its
/// derivatives after them are as defined as in the original.
pub fn check_kills(module: &Module) -> Result<(), AfterKill> {
    for entry in &module.entry_points {
        if entry.stage != naga::ShaderStage::Fragment {
            continue;
        }
        let walk = KillWalk {
            module,
            function: &entry.function,
        };
        if let (Some(what), _) = walk.block(&entry.function.body, false) {
            return Err(AfterKill {
                entry_point: entry.name.clone(),
                what,
            });
        }
    }
    Ok(())
}

/// Walks an entry point's body in execution order, knowing whether a lane
/// of the quad may have been killed before each statement.
struct KillWalk<'a> {
    module: &'a Module,
    function: &'a Function,
}

impl KillWalk<'_> {
    /// The first derivative after a kill in `block` (entered after one
    /// when `killed`), and whether one may have run by its end.
    fn block(&self, block: &Block, mut killed: bool) -> (Option<String>, bool) {
        for statement in block.iter() {
            let found = match *statement {
                Statement::Kill => {
                    killed = true;
                    None
                }
                Statement::Emit(_) | Statement::Call { .. } if killed => {
                    derivative_in(self.module, self.function, statement)
                }
                Statement::Block(ref inner) => {
                    let (found, k) = self.block(inner, killed);
                    killed = k;
                    found
                }
                Statement::If {
                    ref accept,
                    ref reject,
                    ..
                } => {
                    // The other lanes of the quad may have taken the arm
                    // that killed: after the `if`, every lane is suspect.
                    let (a, ka) = self.block(accept, killed);
                    let (r, kr) = self.block(reject, killed);
                    killed = ka || kr;
                    a.or(r)
                }
                Statement::Switch { ref cases, .. } => {
                    let mut found = None;
                    let mut any = killed;
                    for case in cases {
                        let (f, k) = self.block(&case.body, killed);
                        found = found.or(f);
                        any |= k;
                    }
                    killed = any;
                    found
                }
                Statement::Loop {
                    ref body,
                    ref continuing,
                    ..
                } => {
                    let (f, k) = self.block(body, killed);
                    let (g, k) = self.block(continuing, k);
                    // A kill in one iteration comes before the next one's
                    // start.
                    let again = if k && !killed {
                        self.block(body, true).0
                    } else {
                        None
                    };
                    killed = k;
                    f.or(g).or(again)
                }
                _ => None,
            };
            if found.is_some() {
                return (found, killed);
            }
        }
        (None, killed)
    }
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
                Statement::Emit(_) | Statement::Call { .. } if divergent => {
                    derivative_in(self.module, self.function, statement)
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

/// Describes what `statement` itself runs that takes implicit derivatives:
/// an expression it emits, or a call of a function that takes them.
fn derivative_in(module: &Module, function: &Function, statement: &Statement) -> Option<String> {
    match *statement {
        Statement::Emit(ref range) => range
            .clone()
            .find_map(|h| implicit_derivative(&function.expressions[h])),
        Statement::Call { function: f, .. } if needs_derivatives(module, f) => Some(format!(
            "a call of `{}`, which takes implicit derivatives,",
            module.functions[f].name.as_deref().unwrap_or("?")
        )),
        _ => None,
    }
}

/// Describes `expr` if it takes implicit derivatives (which expressions
/// do is `proc::takes_derivatives`'s answer; this names them).
pub fn implicit_derivative(expr: &Expression) -> Option<String> {
    if !crate::proc::takes_derivatives(expr) {
        return None;
    }
    let name = match *expr {
        Expression::Derivative { axis, .. } => match axis {
            naga::DerivativeAxis::X => "dpdx",
            naga::DerivativeAxis::Y => "dpdy",
            naga::DerivativeAxis::Width => "fwidth",
        },
        Expression::ImageSample {
            level: naga::SampleLevel::Bias(_),
            ..
        } => "textureSampleBias",
        Expression::ImageSample {
            depth_ref: Some(_), ..
        } => "textureSampleCompare",
        Expression::ImageSample { .. } => "textureSample",
        _ => "an implicit derivative",
    };
    Some(name.into())
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

#[cfg(test)]
mod kill_tests {
    use super::check_kills;

    fn module(body: &str) -> naga::Module {
        naga::front::wgsl::parse_str(&format!(
            "@fragment fn fs(@location(0) x: f32) -> @location(0) vec4<f32> {{ {body} }}"
        ))
        .unwrap()
    }

    #[test]
    fn a_derivative_after_a_discard_is_found() {
        let found = check_kills(&module(
            "if x > 0.5 { discard; } let d = dpdx(x); return vec4<f32>(d);",
        ));
        assert!(found.unwrap_err().what.contains("dpdx"));
    }

    #[test]
    fn a_derivative_before_or_beside_a_discard_is_not() {
        assert!(check_kills(&module(
            "let d = dpdx(x); if x > 0.5 { discard; } return vec4<f32>(d);"
        ))
        .is_ok());
        assert!(check_kills(&module(
            "var d = 0.0; if x > 0.5 { discard; } else { d = fwidth(x); } return vec4<f32>(d);"
        ))
        .is_ok());
    }

    #[test]
    fn a_discard_in_a_loop_comes_before_the_next_iteration() {
        let found = check_kills(&module(
            "var s = 0.0; for (var i = 0; i < 4; i++) { s += dpdy(x * f32(i)); if s > 1.0 { discard; } } return vec4<f32>(s);",
        ));
        assert!(found.unwrap_err().what.contains("dpdy"));
    }
}

//! Copying the live part of a function into a new function of the same
//! module: the IR builder behind the payload and shading functions.
//!
//! Expressions are copied on demand through a handle map and re-emitted in
//! the new function in the order the statements need them. What is copied
//! is decided by a *live* set from the expression graph: an `Emit` keeps
//! only live expressions, a store survives when a live load reads its
//! variable, a branch when its condition is live, a call when its result is
//! live or it has effects. Everything else is dead code and is dropped.

use std::collections::HashMap;

use naga::{Block, Expression, Function, Handle, LocalVariable, Span, Statement};

use crate::analysis::graph::ExprSet;
use crate::proc;
use crate::proc::remap::{self, Mapper};

/// Builds the replacement of an expression in the new function; it may
/// copy operands and append new expressions through the copy.
pub type Hook<'a> = Box<dyn FnMut(&mut FunctionCopy<'a>) -> Expression + 'a>;

/// Builds the value a `return` of the source returns instead, pushing any
/// statement it needs (a call) into the block.
pub type ReturnHook<'a> =
    Box<dyn FnMut(&mut FunctionCopy<'a>, &mut Block) -> Handle<Expression> + 'a>;

/// Builds a new function from parts of `source`.
pub struct FunctionCopy<'a> {
    module: &'a naga::Module,
    source: &'a Function,
    live: &'a ExprSet,
    /// The function being built.
    pub target: Function,
    exprs: HashMap<Handle<Expression>, Handle<Expression>>,
    locals: HashMap<Handle<LocalVariable>, Handle<LocalVariable>>,
    /// Expressions to read from somewhere else than their computation.
    substitutes: HashMap<Handle<Expression>, Expression>,
    /// Copied expressions that still need an `Emit`.
    pending: Vec<Handle<Expression>>,
    /// Stop after this expression is emitted, returning it (or
    /// `stop_value`).
    stop_at: Option<Handle<Expression>>,
    stop_value: Option<Expression>,
    /// How deep in nested blocks the copy is, and was when it stopped at
    /// `stop_at`. Once stopped nothing more is copied: the node's value is
    /// the last thing a copy that returns it needs.
    depth: usize,
    stop_depth: Option<usize>,
    /// Globals and functions to use in place of others.
    globals: HashMap<Handle<naga::GlobalVariable>, Handle<naga::GlobalVariable>>,
    functions: HashMap<Handle<Function>, Handle<Function>>,
    /// Return this member of the returned value instead of the value.
    return_member: Option<u32>,
    /// Leave `return` statements out (the caller ends the body itself).
    drop_returns: bool,
    /// Expressions rebuilt by a hook instead of copied.
    hooks: HashMap<Handle<Expression>, Hook<'a>>,
    /// What the source's own `return`s return instead
    /// ([`FunctionCopy::run_or_return`]).
    return_hook: Option<ReturnHook<'a>>,
}

impl std::fmt::Debug for FunctionCopy<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FunctionCopy")
            .field("target", &self.target.name)
            .finish_non_exhaustive()
    }
}

impl<'a> FunctionCopy<'a> {
    pub fn new(
        module: &'a naga::Module,
        source: &'a Function,
        live: &'a ExprSet,
        target: Function,
    ) -> Self {
        FunctionCopy {
            module,
            source,
            live,
            target,
            exprs: HashMap::new(),
            locals: HashMap::new(),
            substitutes: HashMap::new(),
            pending: Vec::new(),
            stop_at: None,
            stop_value: None,
            depth: 0,
            stop_depth: None,
            globals: HashMap::new(),
            functions: HashMap::new(),
            return_member: None,
            drop_returns: false,
            hooks: HashMap::new(),
            return_hook: None,
        }
    }

    /// Rebuilds `expr` with `hook` instead of copying it.
    pub fn rebuild(&mut self, expr: Handle<Expression>, hook: Hook<'a>) {
        self.hooks.insert(expr, hook);
    }

    /// Leaves every `return` out; see [`FunctionCopy::copy_body`].
    pub fn drop_returns(&mut self) {
        self.drop_returns = true;
    }

    /// Appends a new expression to the function being built (emitted before
    /// the next statement).
    pub fn add(&mut self, expr: Expression) -> Handle<Expression> {
        self.append(expr, Span::UNDEFINED)
    }

    /// Copies the live part of the source body and returns it, leaving the
    /// copy usable: [`Mapper::expression`] gives the new handle of any
    /// source expression, [`FunctionCopy::add`] appends more, and
    /// [`FunctionCopy::finish`] ends the body with a statement.
    pub fn copy_body(&mut self) -> Block {
        self.block(&self.source.body)
    }

    /// Emits what is pending into `body`, appends `last`, and returns the
    /// function.
    pub fn finish(mut self, mut body: Block, last: Statement) -> Function {
        self.flush(&mut body);
        body.push(last, Span::UNDEFINED);
        self.target.body = body;
        self.target
    }

    /// Reads `to` wherever the source reads global `from`.
    pub fn replace_global(
        &mut self,
        from: Handle<naga::GlobalVariable>,
        to: Handle<naga::GlobalVariable>,
    ) {
        self.globals.insert(from, to);
    }

    /// Calls `to` wherever the source calls `from`.
    pub fn replace_function(&mut self, from: Handle<Function>, to: Handle<Function>) {
        self.functions.insert(from, to);
    }

    /// Returns member `index` of each returned value (a struct) instead.
    pub fn return_member(&mut self, index: u32) {
        self.return_member = Some(index);
    }

    /// Reads `expr` as `replacement` (an expression of the new function that
    /// needs no emit, such as an argument) instead of computing it.
    pub fn substitute(&mut self, expr: Handle<Expression>, replacement: Expression) {
        self.substitutes.insert(expr, replacement);
    }

    /// Copies statements up to the emission of `expr`, then returns it.
    pub fn return_at(&mut self, expr: Handle<Expression>) {
        self.stop_at = Some(expr);
    }

    /// Copies statements up to where `expr` is evaluated, then returns
    /// `value` (an expression of the new function, such as a literal)
    /// instead of computing `expr`.
    pub fn return_value_at(&mut self, expr: Handle<Expression>, value: Expression) {
        self.stop_at = Some(expr);
        self.stop_value = Some(value);
    }

    /// Copies the live part of the source body up to the node (see
    /// [`FunctionCopy::return_at`]) and returns the function, which returns
    /// what `elsewhere` builds on every path that does not reach the node:
    /// where the source returns before it, and after the body when the node
    /// is computed under a branch (or never). `elsewhere` may push a
    /// statement, such as a call, into the block it is given.
    pub fn run_or_return(mut self, elsewhere: ReturnHook<'a>) -> Function {
        self.return_hook = Some(elsewhere);
        let mut body = self.copy_body();
        match self.return_hook.take() {
            Some(mut elsewhere) if self.stop_depth != Some(0) => {
                let value = elsewhere(&mut self, &mut body);
                self.finish(body, Statement::Return { value: Some(value) })
            }
            _ => {
                self.target.body = body;
                self.target
            }
        }
    }

    /// The value returned at the node.
    fn stop_value(&mut self, expr: Handle<Expression>) -> Handle<Expression> {
        match self.stop_value.clone() {
            Some(value) => self.add(value),
            None => self.expression(expr),
        }
    }

    /// Copies the live part of the source body into the target's body.
    pub fn run(mut self) -> Function {
        let body = self.copy_body();
        self.target.body = body;
        self.target
    }

    fn append(&mut self, expr: Expression, span: Span) -> Handle<Expression> {
        let needs_emit = !expr.needs_pre_emit()
            && !matches!(
                expr,
                Expression::CallResult(_)
                    | Expression::AtomicResult { .. }
                    | Expression::WorkGroupUniformLoadResult { .. }
                    | Expression::RayQueryProceedResult
                    | Expression::SubgroupBallotResult
                    | Expression::SubgroupOperationResult { .. }
            );
        let handle = self.target.expressions.append(expr, span);
        if needs_emit {
            self.pending.push(handle);
        }
        handle
    }

    /// Emits what was copied since the last statement into `block`.
    pub fn flush_into(&mut self, block: &mut Block) {
        self.flush(block);
    }

    /// Emits what was copied since the last statement, as few ranges as
    /// possible.
    fn flush(&mut self, block: &mut Block) {
        let mut pending = std::mem::take(&mut self.pending);
        pending.sort_by_key(|h| h.index());
        let mut start = 0;
        while start < pending.len() {
            let mut end = start;
            while end + 1 < pending.len() && pending[end + 1].index() == pending[end].index() + 1 {
                end += 1;
            }
            block.push(
                Statement::Emit(naga::Range::new_from_bounds(pending[start], pending[end])),
                Span::UNDEFINED,
            );
            start = end + 1;
        }
    }

    fn is_live(&self, expr: Handle<Expression>) -> bool {
        self.live.contains(expr.index())
    }

    fn block(&mut self, block: &Block) -> Block {
        let mut out = Block::new();
        for (statement, &span) in block.span_iter() {
            if self.stop_depth.is_some() {
                break;
            }
            self.statement(statement, span, &mut out);
        }
        out
    }

    /// A block nested in a statement, one level deeper.
    fn nested(&mut self, block: &Block) -> Block {
        self.depth += 1;
        let out = self.block(block);
        self.depth -= 1;
        out
    }

    fn statement(&mut self, statement: &Statement, span: Span, out: &mut Block) {
        match *statement {
            Statement::Emit(ref range) => {
                for expr in range.clone() {
                    if Some(expr) == self.stop_at {
                        let value = self.stop_value(expr);
                        self.flush(out);
                        out.push(Statement::Return { value: Some(value) }, span);
                        self.stop_depth = Some(self.depth);
                        return;
                    }
                    if self.is_live(expr) {
                        self.expression(expr);
                    }
                }
                self.flush(out);
            }
            Statement::Block(ref inner) => {
                let inner = self.nested(inner);
                if !inner.is_empty() {
                    out.push(Statement::Block(inner), span);
                }
            }
            Statement::If {
                condition,
                ref accept,
                ref reject,
            } => {
                if !self.is_live(condition) {
                    return;
                }
                let condition = self.expression(condition);
                self.flush(out);
                let accept = self.nested(accept);
                let reject = self.nested(reject);
                out.push(
                    Statement::If {
                        condition,
                        accept,
                        reject,
                    },
                    span,
                );
            }
            Statement::Switch {
                selector,
                ref cases,
            } => {
                if !self.is_live(selector) {
                    return;
                }
                let selector = self.expression(selector);
                self.flush(out);
                let cases = cases
                    .iter()
                    .map(|case| naga::SwitchCase {
                        value: case.value,
                        body: self.nested(&case.body),
                        fall_through: case.fall_through,
                    })
                    .collect();
                out.push(Statement::Switch { selector, cases }, span);
            }
            Statement::Loop {
                ref body,
                ref continuing,
                break_if,
            } => {
                if !self.loop_is_live(body, continuing, break_if) {
                    return;
                }
                let body = self.nested(body);
                let mut continuing = self.nested(continuing);
                let break_if = break_if.map(|h| self.expression(h));
                self.flush(&mut continuing);
                out.push(
                    Statement::Loop {
                        body,
                        continuing,
                        break_if,
                    },
                    span,
                );
            }
            Statement::Return { .. } if self.drop_returns => {}
            Statement::Return { .. } if self.return_hook.is_some() => {
                if let Some(mut hook) = self.return_hook.take() {
                    let value = hook(self, out);
                    self.return_hook = Some(hook);
                    self.flush(out);
                    out.push(Statement::Return { value: Some(value) }, span);
                }
            }
            Statement::Return { value: Some(value) } if self.return_member.is_some() => {
                let base = self.expression(value);
                let member = self.append(
                    Expression::AccessIndex {
                        base,
                        index: self.return_member.unwrap_or_default(),
                    },
                    span,
                );
                self.flush(out);
                out.push(
                    Statement::Return {
                        value: Some(member),
                    },
                    span,
                );
            }
            // The call's value is read from elsewhere (the cache).
            Statement::Call {
                result: Some(result),
                ..
            } if self.substitutes.contains_key(&result) => {}
            Statement::Call {
                result: Some(result),
                ..
            } if Some(result) == self.stop_at => {
                if self.stop_value.is_none() {
                    if let Some(copied) = remap::simple_statement(statement, self) {
                        self.flush(out);
                        out.push(copied, span);
                    }
                }
                let value = self.stop_value(result);
                self.flush(out);
                out.push(Statement::Return { value: Some(value) }, span);
                self.stop_depth = Some(self.depth);
            }
            // A store no live load reads (its value is not live: the live
            // sets follow reaching definitions) is dead here, even into a
            // variable that is live: the shade pass's `lit += f(..)` before
            // the cached `lit += ..` is overwritten by the cached value,
            // and its call is not copied.
            Statement::Store { pointer, value }
                if !self.is_live(pointer) || !self.is_live(value) => {}
            Statement::Call {
                function, result, ..
            } if !result.is_some_and(|r| self.is_live(r))
                && !proc::has_effects(self.module, function) => {}
            _ => {
                if let Some(copied) = remap::simple_statement(statement, self) {
                    self.flush(out);
                    out.push(copied, span);
                }
            }
        }
    }

    /// Whether anything a loop computes is needed.
    fn loop_is_live(
        &self,
        body: &Block,
        continuing: &Block,
        break_if: Option<Handle<Expression>>,
    ) -> bool {
        if break_if.is_some_and(|h| self.is_live(h)) {
            return true;
        }
        let layout_of = |block: &Block| {
            let mut live = false;
            proc::each_statement(block, &mut |statement| {
                live |= match *statement {
                    Statement::Emit(ref range) => range.clone().any(|h| self.is_live(h)),
                    Statement::Store { pointer, .. } => self.is_live(pointer),
                    Statement::Call {
                        function, result, ..
                    } => {
                        result.is_some_and(|r| self.is_live(r))
                            || proc::has_effects(self.module, function)
                    }
                    Statement::Kill | Statement::Return { .. } => true,
                    _ => false,
                };
            });
            live
        };
        layout_of(body) || layout_of(continuing)
    }
}

impl Mapper for FunctionCopy<'_> {
    fn expression(&mut self, handle: Handle<Expression>) -> Handle<Expression> {
        if let Some(&mapped) = self.exprs.get(&handle) {
            return mapped;
        }
        let span = self.source.expressions.get_span(handle);
        let copied = if let Some(mut hook) = self.hooks.remove(&handle) {
            hook(self)
        } else {
            match self.substitutes.get(&handle) {
                Some(replacement) => replacement.clone(),
                None => remap::expression(&self.source.expressions[handle], self),
            }
        };
        let mapped = self.append(copied, span);
        self.exprs.insert(handle, mapped);
        if let Some(name) = self.source.named_expressions.get(&handle) {
            self.target.named_expressions.insert(mapped, name.clone());
        }
        mapped
    }

    fn global(&mut self, handle: Handle<naga::GlobalVariable>) -> Handle<naga::GlobalVariable> {
        self.globals.get(&handle).copied().unwrap_or(handle)
    }

    fn local(&mut self, handle: Handle<LocalVariable>) -> Handle<LocalVariable> {
        if let Some(&mapped) = self.locals.get(&handle) {
            return mapped;
        }
        let local = &self.source.local_variables[handle];
        let span = self.source.local_variables.get_span(handle);
        // Reserve the variable first: its initializer may not refer to it,
        // but the map must hold it before the initializer is copied.
        let mapped = self.target.local_variables.append(
            LocalVariable {
                name: local.name.clone(),
                ty: local.ty,
                init: None,
            },
            span,
        );
        self.locals.insert(handle, mapped);
        if let Some(init) = local.init {
            let init = self.expression(init);
            self.target.local_variables.get_mut(mapped).init = Some(init);
        }
        mapped
    }

    fn function(&mut self, handle: Handle<naga::Function>) -> Handle<naga::Function> {
        self.functions.get(&handle).copied().unwrap_or(handle)
    }
}

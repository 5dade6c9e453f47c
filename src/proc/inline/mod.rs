//! Inlining helper calls on naga IR: a function specialised for the calls
//! it makes, so that what a helper computes at one call site becomes part
//! of the caller's own expressions.
//!
//! The analysis inlines every call the fragment entry point makes, helpers
//! of helpers included, so that each call site's expressions are nodes of
//! their own (`fbm` called four times gives four sets of nodes, each with
//! the value it has there). A rewrite inlines only the calls on the path to
//! the node it caches; the rest of the shader keeps its helpers.
//!
//! naga has no inliner (its back ends write calls as calls), hence this
//! one. Inlining one call:
//!
//! * the callee's locals become new locals of the caller, set where the
//!   call was to their initialisers (or zero), since a call inside a loop
//!   starts afresh each time while a local's initialiser runs once;
//! * its arguments are the call's argument expressions (pointers included);
//! * its `return` stores into a result local, which the call's result
//!   expression now loads, spanned like the call. A `return` before the
//!   end sets a flag as well: the callee's statements after the statement
//!   that returned run under `if !returned`, or, inside one of the callee's
//!   loops or switches, `if returned { break; }` leaves it first;
//! * its expressions go into the caller's arena where the call's result
//!   was, so every expression still refers only to earlier ones, as naga
//!   requires, and its statements replace the `Call` in the caller's block.
//!
//! Every expression of the result remembers where it came from
//! ([`Origin`]): the call whose inlining brought it in and its handle in
//! the function it was copied from. That is how the analysis names a node
//! by its helper's source and its call path, and how a rewrite finds the
//! node again in a function that inlines only part of what the analysis
//! inlined.

use naga::{Block, Expression, Function, Handle, LocalVariable, Span, Statement};

use super::remap::{self, Mapper};

/// A function with some of its calls inlined.
#[derive(Clone, Debug)]
pub struct Inlined {
    pub function: Function,
    /// Where each expression of `function` came from, by arena index.
    pub origins: Vec<Origin>,
    /// The calls inlined, each before the calls inlined from its callee.
    pub calls: Vec<InlinedCall>,
}

/// Where an expression of an [`Inlined`] function came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Origin {
    /// The inlined call (an index into [`Inlined::calls`]) whose callee
    /// it was copied from; `None` for the root function's own.
    pub call: Option<usize>,
    /// Its handle in that function; `None` for the ones the inliner made.
    /// The load that stands for an inlined call's result has the call's
    /// `CallResult` handle in the calling function.
    pub expression: Option<Handle<Expression>>,
}

/// One inlined call.
#[derive(Clone, Debug)]
pub struct InlinedCall {
    /// The inlined call whose callee makes this call; `None` for the root.
    pub parent: Option<usize>,
    /// Which `Call` statement of the calling function it is: its index
    /// among them in statement order (nested blocks in order, a loop's body
    /// before its continuing block), as [`super::each_statement`] visits
    /// them.
    pub ordinal: usize,
    pub function: Handle<Function>,
    /// The call's span in the calling function: its statement's, else its
    /// result's.
    pub span: Span,
}

impl Inlined {
    /// The ordinals from the root down to `call`, `call`'s own last.
    pub fn path(&self, call: usize) -> Vec<usize> {
        let mut path = Vec::new();
        let mut at = Some(call);
        while let Some(index) = at {
            path.push(self.calls[index].ordinal);
            at = self.calls[index].parent;
        }
        path.reverse();
        path
    }

    /// The expression copied from `expression` of the function that `call`
    /// (`None`: the root) inlined.
    pub fn find(
        &self,
        call: Option<usize>,
        expression: Handle<Expression>,
    ) -> Option<Handle<Expression>> {
        let index = self
            .origins
            .iter()
            .position(|o| o.call == call && o.expression == Some(expression))?;
        self.function.expressions.iter().nth(index).map(|(h, _)| h)
    }
}

/// Inlines into `root` every call for which `select` is true of its call
/// path: the ordinals ([`InlinedCall::ordinal`]) of the calls from `root`
/// down to it, its own last. A call not selected is kept as a call, and
/// what its callee calls is not looked at. `module` gains the `bool` type
/// an early return's flag needs.
pub fn inline(
    module: &mut naga::Module,
    root: &Function,
    select: &mut dyn FnMut(&[usize]) -> bool,
) -> Result<Inlined, String> {
    let bool_ty = module.types.insert(
        naga::Type {
            name: None,
            inner: naga::TypeInner::Scalar(naga::Scalar::BOOL),
        },
        Span::UNDEFINED,
    );
    let mut context = Context {
        module,
        bool_ty,
        select,
        calls: Vec::new(),
        path: Vec::new(),
    };
    let (function, origins) = context.specialise(root, None)?;
    Ok(Inlined {
        function,
        origins,
        calls: context.calls,
    })
}

/// A `Call` statement of the function being specialised.
struct Site {
    function: Handle<Function>,
    arguments: Vec<Handle<Expression>>,
    result: Option<Handle<Expression>>,
    span: Span,
}

/// A callee made ready to splice: specialised itself, its returns lowered
/// to stores, its locals without initialisers.
struct Prepared {
    function: Function,
    origins: Vec<Origin>,
    /// The pointer to its result local.
    result: Option<Handle<Expression>>,
}

struct Context<'m, 's> {
    module: &'m naga::Module,
    bool_ty: Handle<naga::Type>,
    select: &'s mut dyn FnMut(&[usize]) -> bool,
    calls: Vec<InlinedCall>,
    path: Vec<usize>,
}

impl Context<'_, '_> {
    /// `function` with its selected calls inlined; `own` is the inlined
    /// call it is the callee of.
    fn specialise(
        &mut self,
        function: &Function,
        own: Option<usize>,
    ) -> Result<(Function, Vec<Origin>), String> {
        let mut sites = Vec::new();
        super::each_spanned_statement(&function.body, &mut |statement, span| {
            if let Statement::Call {
                function: callee,
                ref arguments,
                result,
            } = *statement
            {
                let span = if span.is_defined() {
                    span
                } else {
                    result.map_or(span, |r| function.expressions.get_span(r))
                };
                sites.push(Site {
                    function: callee,
                    arguments: arguments.clone(),
                    result,
                    span,
                });
            }
        });
        let mut prepared = Vec::with_capacity(sites.len());
        for (ordinal, site) in sites.iter().enumerate() {
            self.path.push(ordinal);
            let chosen = (self.select)(&self.path);
            let callee = if chosen {
                let call = self.calls.len();
                self.calls.push(InlinedCall {
                    parent: own,
                    ordinal,
                    function: site.function,
                    span: site.span,
                });
                let module = self.module;
                let (inner, origins) =
                    self.specialise(&module.functions[site.function], Some(call))?;
                Some(lower_returns(self.bool_ty, inner, origins, call))
            } else {
                None
            };
            self.path.pop();
            prepared.push(callee);
        }
        if prepared.iter().all(Option::is_none) {
            let origins = function
                .expressions
                .iter()
                .map(|(handle, _)| Origin {
                    call: own,
                    expression: Some(handle),
                })
                .collect();
            return Ok((function.clone(), origins));
        }
        Splice::new(function, own, &sites, prepared).run()
    }
}

/// Lowers the returns of a specialised callee to stores into a result
/// local (and a flag, for returns before the end), and its locals'
/// initialisers to stores at its start.
fn lower_returns(
    bool_ty: Handle<naga::Type>,
    mut function: Function,
    mut origins: Vec<Origin>,
    call: usize,
) -> Prepared {
    let own = Some(call);
    let mut made = |function: &mut Function, expr: Expression, span: Span| {
        origins.push(Origin {
            call: own,
            expression: None,
        });
        function.expressions.append(expr, span)
    };
    let name = function.name.clone().unwrap_or_else(|| "helper".into());

    // Locals start where the call is (a call in a loop starts afresh).
    let mut start = locals_started(&mut function, &mut made);

    let result = function.result.as_ref().map(|r| r.ty).map(|ty| {
        let local = function.local_variables.append(
            LocalVariable {
                name: Some(format!("{name}_result")),
                ty,
                init: None,
            },
            Span::UNDEFINED,
        );
        made(
            &mut function,
            Expression::LocalVariable(local),
            Span::UNDEFINED,
        )
    });
    let flag = has_early_return(&function.body).then(|| {
        let local = function.local_variables.append(
            LocalVariable {
                name: Some("returned".into()),
                ty: bool_ty,
                init: None,
            },
            Span::UNDEFINED,
        );
        let pointer = made(
            &mut function,
            Expression::LocalVariable(local),
            Span::UNDEFINED,
        );
        let no = made(
            &mut function,
            Expression::Literal(naga::Literal::Bool(false)),
            Span::UNDEFINED,
        );
        let yes = made(
            &mut function,
            Expression::Literal(naga::Literal::Bool(true)),
            Span::UNDEFINED,
        );
        start.push(Statement::Store { pointer, value: no }, Span::UNDEFINED);
        (pointer, yes)
    });
    let body = std::mem::take(&mut function.body);
    let mut lowering = Lowering {
        function: &mut function,
        made: &mut made,
        result,
        flag,
    };
    let mut lowered = lowering.block(body, false);
    start.append(&mut lowered);
    function.body = start;
    Prepared {
        function,
        origins,
        result,
    }
}

/// The stores that start `function`'s locals where its call is: each
/// initialiser becomes a store, and a local without one is zeroed.
/// `made` appends an expression the lowering makes.
fn locals_started(
    function: &mut Function,
    made: &mut impl FnMut(&mut Function, Expression, Span) -> Handle<Expression>,
) -> Block {
    let mut start = Block::new();
    let locals: Vec<(Handle<LocalVariable>, LocalVariable, Span)> = function
        .local_variables
        .iter()
        .map(|(h, l)| (h, l.clone(), function.local_variables.get_span(h)))
        .collect();
    for (local, variable, span) in locals {
        let pointer = made(function, Expression::LocalVariable(local), Span::UNDEFINED);
        let value = match variable.init {
            Some(init) => {
                let (value, emitted) = fresh_copy(function, init, made);
                if let Some(range) = emitted {
                    start.push(Statement::Emit(range), span);
                }
                value
            }
            None => made(
                function,
                Expression::ZeroValue(variable.ty),
                Span::UNDEFINED,
            ),
        };
        start.push(Statement::Store { pointer, value }, span);
        function.local_variables.get_mut(local).init = None;
    }

    start
}

/// Whether a `return` comes anywhere but as the body's last statement.
fn has_early_return(body: &Block) -> bool {
    let mut returns = 0;
    super::each_statement(body, &mut |s| {
        if matches!(s, Statement::Return { .. }) {
            returns += 1;
        }
    });
    let last_returns = matches!(body.last(), Some(Statement::Return { .. }));
    returns > usize::from(last_returns)
}

/// Whether `statement` is or holds a `return`.
fn contains_return(statement: &Statement) -> bool {
    let blocks: Vec<&Block> = match *statement {
        Statement::Return { .. } => return true,
        Statement::Block(ref block) => vec![block],
        Statement::If {
            ref accept,
            ref reject,
            ..
        } => vec![accept, reject],
        Statement::Switch { ref cases, .. } => cases.iter().map(|c| &c.body).collect(),
        Statement::Loop {
            ref body,
            ref continuing,
            ..
        } => vec![body, continuing],
        _ => return false,
    };
    let mut found = false;
    for block in blocks {
        super::each_statement(block, &mut |s| {
            found |= matches!(s, Statement::Return { .. });
        });
    }
    found
}

/// A copy of the constant expression `init` that can be emitted where the
/// copy is used: the original may be emitted elsewhere in the body (naga
/// emits an expression once). Returns the copy and the range to emit.
fn fresh_copy(
    function: &mut Function,
    init: Handle<Expression>,
    made: &mut impl FnMut(&mut Function, Expression, Span) -> Handle<Expression>,
) -> (Handle<Expression>, Option<naga::Range<Expression>>) {
    // The subtree below `init`, in arena order (operands come first).
    let mut subtree = vec![init];
    let mut at = 0;
    while at < subtree.len() {
        let expr = &function.expressions[subtree[at]];
        if !expr.needs_pre_emit() {
            subtree.extend(super::operands(expr));
        }
        at += 1;
    }
    subtree.sort_by_key(|h| h.index());
    subtree.dedup();
    let mut map = std::collections::HashMap::new();
    let (mut first, mut last) = (None, None);
    for handle in subtree {
        let expr = &function.expressions[handle];
        if expr.needs_pre_emit() {
            map.insert(handle, handle);
            continue;
        }
        let copy = remap::expression(expr, &mut MapTable::exprs(&map));
        let span = function.expressions.get_span(handle);
        let new = made(function, copy, span);
        first.get_or_insert(new);
        last = Some(new);
        map.insert(handle, new);
    }
    let range = first
        .zip(last)
        .map(|(a, b)| naga::Range::new_from_bounds(a, b));
    (map[&init], range)
}

/// The callee's body with returns made stores.
struct Lowering<'f, 'm, M: FnMut(&mut Function, Expression, Span) -> Handle<Expression>> {
    function: &'f mut Function,
    made: &'m mut M,
    /// The result local's pointer.
    result: Option<Handle<Expression>>,
    /// The flag's pointer and `true`, when a return comes early.
    flag: Option<(Handle<Expression>, Handle<Expression>)>,
}

impl<M: FnMut(&mut Function, Expression, Span) -> Handle<Expression>> Lowering<'_, '_, M> {
    /// `breakable`: inside one of the callee's loops or switches, where a
    /// `break` leaves the innermost of them.
    fn block(&mut self, block: Block, breakable: bool) -> Block {
        let mut out = Block::new();
        let mut rest = block.span_into_iter();
        while let Some((statement, span)) = rest.next() {
            if let Statement::Return { value } = statement {
                if let (Some(value), Some(pointer)) = (value, self.result) {
                    out.push(Statement::Store { pointer, value }, span);
                }
                if let Some((pointer, yes)) = self.flag {
                    out.push(
                        Statement::Store {
                            pointer,
                            value: yes,
                        },
                        span,
                    );
                    if breakable {
                        out.push(Statement::Break, span);
                    }
                }
                // What follows a return in its block never runs.
                return out;
            }
            // Inside a loop, a block that returns has broken out already
            // (or checked the flag after the statement that returned).
            let returns = contains_return(&statement)
                && !(breakable && matches!(statement, Statement::Block(_)));
            let statement = self.nested(statement, breakable);
            out.push(statement, span);
            let Some((pointer, _)) = self.flag.filter(|_| returns) else {
                continue;
            };
            let returned =
                (self.made)(self.function, Expression::Load { pointer }, Span::UNDEFINED);
            if breakable {
                out.push(
                    Statement::Emit(naga::Range::new_from_bounds(returned, returned)),
                    Span::UNDEFINED,
                );
                out.push(
                    Statement::If {
                        condition: returned,
                        accept: Block::from_vec(vec![Statement::Break]),
                        reject: Block::new(),
                    },
                    Span::UNDEFINED,
                );
                continue;
            }
            let running = (self.made)(
                self.function,
                Expression::Unary {
                    op: naga::UnaryOperator::LogicalNot,
                    expr: returned,
                },
                Span::UNDEFINED,
            );
            out.push(
                Statement::Emit(naga::Range::new_from_bounds(returned, running)),
                Span::UNDEFINED,
            );
            let remaining: Block = {
                let mut block = Block::new();
                for (statement, span) in rest.by_ref() {
                    block.push(statement, span);
                }
                block
            };
            let accept = self.block(remaining, false);
            out.push(
                Statement::If {
                    condition: running,
                    accept,
                    reject: Block::new(),
                },
                Span::UNDEFINED,
            );
        }
        out
    }

    fn nested(&mut self, statement: Statement, breakable: bool) -> Statement {
        match statement {
            Statement::Block(block) => Statement::Block(self.block(block, breakable)),
            Statement::If {
                condition,
                accept,
                reject,
            } => Statement::If {
                condition,
                accept: self.block(accept, breakable),
                reject: self.block(reject, breakable),
            },
            Statement::Switch { selector, cases } => Statement::Switch {
                selector,
                cases: cases
                    .into_iter()
                    .map(|case| naga::SwitchCase {
                        body: self.block(case.body, true),
                        ..case
                    })
                    .collect(),
            },
            // WGSL has no return in a continuing block.
            Statement::Loop {
                body,
                continuing,
                break_if,
            } => Statement::Loop {
                body: self.block(body, true),
                continuing,
                break_if,
            },
            other => other,
        }
    }
}

/// Handle maps by table; what a table leaves out maps to itself.
struct MapTable<'t> {
    exprs: Exprs<'t>,
    locals: Option<&'t [Handle<LocalVariable>]>,
}

enum Exprs<'t> {
    Sparse(&'t std::collections::HashMap<Handle<Expression>, Handle<Expression>>),
    Dense(&'t [Option<Handle<Expression>>]),
}

impl<'t> MapTable<'t> {
    fn exprs(map: &'t std::collections::HashMap<Handle<Expression>, Handle<Expression>>) -> Self {
        MapTable {
            exprs: Exprs::Sparse(map),
            locals: None,
        }
    }
}

impl Mapper for MapTable<'_> {
    fn expression(&mut self, handle: Handle<Expression>) -> Handle<Expression> {
        match self.exprs {
            Exprs::Sparse(map) => map.get(&handle).copied().unwrap_or(handle),
            // Splice maps every operand before it copies what reads it.
            Exprs::Dense(map) => map[handle.index()].unwrap_or(handle),
        }
    }
    fn local(&mut self, handle: Handle<LocalVariable>) -> Handle<LocalVariable> {
        self.locals.map_or(handle, |locals| locals[handle.index()])
    }
}

/// One prepared callee, once its expressions and locals are in the
/// target: its body, to put in place of the call, and how to map it.
struct Spliced {
    body: Block,
    exprs: Vec<Option<Handle<Expression>>>,
    locals: Vec<Handle<LocalVariable>>,
    result: Option<Handle<Expression>>,
}

/// Rebuilds a function with prepared callees in place of their calls.
struct Splice<'a> {
    source: &'a Function,
    own: Option<usize>,
    sites: &'a [Site],
    prepared: Vec<Option<Prepared>>,
    target: Function,
    origins: Vec<Origin>,
    /// The source's expressions in the target.
    map: Vec<Option<Handle<Expression>>>,
    spliced: Vec<Option<Spliced>>,
}

impl<'a> Splice<'a> {
    fn new(
        source: &'a Function,
        own: Option<usize>,
        sites: &'a [Site],
        prepared: Vec<Option<Prepared>>,
    ) -> Self {
        let spliced = prepared.iter().map(|_| None).collect();
        Splice {
            source,
            own,
            sites,
            prepared,
            target: Function {
                name: source.name.clone(),
                arguments: source.arguments.clone(),
                result: source.result.clone(),
                local_variables: source.local_variables.clone(),
                diagnostic_filter_leaf: source.diagnostic_filter_leaf,
                ..Function::default()
            },
            origins: Vec::new(),
            map: vec![None; source.expressions.len()],
            spliced,
        }
    }

    fn run(mut self) -> Result<(Function, Vec<Origin>), String> {
        // Where each callee's expressions go: at its result, which they
        // compute, or after the last argument of a call without one.
        let mut at: Vec<(usize, usize)> = Vec::new();
        for (ordinal, site) in self.sites.iter().enumerate() {
            if self.prepared[ordinal].is_none() {
                continue;
            }
            let position = match site.result {
                Some(result) => result.index(),
                None => site
                    .arguments
                    .iter()
                    .map(|a| a.index() + 1)
                    .max()
                    .unwrap_or(0),
            };
            at.push((position, ordinal));
        }
        at.sort();
        let mut next = at.into_iter().peekable();
        let handles: Vec<Handle<Expression>> =
            self.source.expressions.iter().map(|(h, _)| h).collect();
        for index in 0..=handles.len() {
            while let Some(&(_, ordinal)) = next.peek().filter(|&&(p, _)| p == index) {
                next.next();
                self.splice_expressions(ordinal)?;
            }
            let Some(&handle) = handles.get(index) else {
                break;
            };
            if self.map[index].is_some() {
                // An inlined call's result: its load is already there.
                continue;
            }
            let copy = remap::expression(
                &self.source.expressions[handle],
                &mut MapTable {
                    exprs: Exprs::Dense(&self.map),
                    locals: None,
                },
            );
            let span = self.source.expressions.get_span(handle);
            self.map[index] = Some(self.target.expressions.append(copy, span));
            self.origins.push(Origin {
                call: self.own,
                expression: Some(handle),
            });
        }
        // The function's own locals keep their handles; their initialisers
        // moved with the arena.
        let own_locals: Vec<Handle<LocalVariable>> =
            self.source.local_variables.iter().map(|(h, _)| h).collect();
        for local in own_locals {
            let variable = self.target.local_variables.get_mut(local);
            if let Some(init) = variable.init {
                variable.init = self.map[init.index()];
            }
        }
        for (&handle, name) in &self.source.named_expressions {
            if let Some(new) = self.map[handle.index()] {
                self.target.named_expressions.insert(new, name.clone());
            }
        }
        self.target.body = self.body();
        Ok((self.target, self.origins))
    }

    /// Copies one prepared callee's locals and expressions into the target.
    fn splice_expressions(&mut self, ordinal: usize) -> Result<(), String> {
        let site = &self.sites[ordinal];
        let Some(mut prepared) = self.prepared[ordinal].take() else {
            return Ok(());
        };
        let callee = &prepared.function;
        let locals: Vec<Handle<LocalVariable>> = callee
            .local_variables
            .iter()
            .map(|(h, l)| {
                let span = callee.local_variables.get_span(h);
                self.target.local_variables.append(l.clone(), span)
            })
            .collect();
        let mut exprs: Vec<Option<Handle<Expression>>> = vec![None; callee.expressions.len()];
        for (handle, expr) in callee.expressions.iter() {
            let new = if let Expression::FunctionArgument(index) = *expr {
                let argument = site.arguments.get(index as usize).copied();
                argument.and_then(|a| self.map[a.index()]).ok_or_else(|| {
                    format!(
                        "argument {index} of the call of `{}` comes after the call",
                        callee.name.as_deref().unwrap_or("a helper")
                    )
                })?
            } else {
                let copy = remap::expression(
                    expr,
                    &mut MapTable {
                        exprs: Exprs::Dense(&exprs),
                        locals: Some(&locals),
                    },
                );
                let span = callee.expressions.get_span(handle);
                self.origins.push(prepared.origins[handle.index()]);
                self.target.expressions.append(copy, span)
            };
            exprs[handle.index()] = Some(new);
        }
        for (&handle, name) in &callee.named_expressions {
            if !matches!(callee.expressions[handle], Expression::FunctionArgument(_)) {
                if let Some(new) = exprs[handle.index()] {
                    self.target.named_expressions.insert(new, name.clone());
                }
            }
        }
        let result = match (site.result, prepared.result) {
            (Some(call_result), Some(pointer)) => {
                let pointer = exprs[pointer.index()]
                    .ok_or("internal error: the result local of an inlined call was not copied")?;
                let span = self.source.expressions.get_span(call_result);
                let load = self
                    .target
                    .expressions
                    .append(Expression::Load { pointer }, span);
                self.origins.push(Origin {
                    call: self.own,
                    expression: Some(call_result),
                });
                self.map[call_result.index()] = Some(load);
                Some(load)
            }
            _ => None,
        };
        self.spliced[ordinal] = Some(Spliced {
            body: std::mem::take(&mut prepared.function.body),
            exprs,
            locals,
            result,
        });
        Ok(())
    }

    /// The source's body, with each spliced callee's statements in place
    /// of its call.
    fn body(&mut self) -> Block {
        let Splice {
            source,
            map,
            spliced,
            ..
        } = self;
        // The next `Call` statement's ordinal, as the body is walked.
        let mut ordinal = 0;
        let mut table = MapTable {
            exprs: Exprs::Dense(map),
            locals: None,
        };
        remap::block(
            &source.body,
            &mut table,
            true,
            &mut |statement, span, out| {
                if !matches!(statement, Statement::Call { .. }) {
                    return false;
                }
                ordinal += 1;
                let Some(spliced) = spliced[ordinal - 1].take() else {
                    return false;
                };
                let mut table = MapTable {
                    exprs: Exprs::Dense(&spliced.exprs),
                    locals: Some(&spliced.locals),
                };
                out.append(&mut remap::block(
                    &spliced.body,
                    &mut table,
                    true,
                    &mut |_, _, _| false,
                ));
                if let Some(load) = spliced.result {
                    out.push(
                        Statement::Emit(naga::Range::new_from_bounds(load, load)),
                        span,
                    );
                }
                true
            },
        )
    }
}

#[cfg(test)]
mod tests;

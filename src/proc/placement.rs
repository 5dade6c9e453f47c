use std::collections::BTreeSet;

use naga::{Block, Expression, Function, Handle, Module, Statement};

use super::{const_int, pointer_root, PointerRoot};

/// Where an expression is evaluated.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// Estimated evaluations per invocation of the function: the product of
    /// the trip counts of the enclosing loops. Both sides of a branch count
    /// fully (under divergence a SIMD group runs both).
    pub multiplier: f64,
    /// How many loops enclose it.
    pub loop_depth: u32,
    /// The values that decide whether, and how often, it runs: conditions of
    /// enclosing `if`s, selectors of enclosing `switch`es, and every branch
    /// condition inside enclosing loops (they decide the trip count).
    pub controls: Vec<Handle<Expression>>,
}

impl Placement {
    fn top() -> Self {
        Placement {
            multiplier: 1.0,
            loop_depth: 0,
            controls: Vec::new(),
        }
    }
}

/// A `Store` statement and where it runs.
#[derive(Clone, Debug)]
pub struct Store {
    pub pointer: Handle<Expression>,
    pub value: Handle<Expression>,
    pub target: Option<PointerRoot>,
    pub placement: Placement,
}

/// A `Call` statement and where it runs.
#[derive(Clone, Debug)]
pub struct CallSite {
    pub function: Handle<naga::Function>,
    pub arguments: Vec<Handle<Expression>>,
    pub result: Option<Handle<Expression>>,
    pub placement: Placement,
}

/// A loop and the trip count inferred for it.
#[derive(Clone, Debug)]
pub struct LoopBound {
    /// `Some(n)` when the loop has the shape `for (var i = a; i < b; i += s)`
    /// (or `<=`, `>`, `>=`, `!=`, decrementing) with constant `a`, `b`, `s`.
    pub trips: Option<u64>,
    /// The multiplier used for its body: `trips` or the default.
    pub assumed: f64,
}

/// The statement structure of one function, flattened for the analyses.
#[derive(Clone, Debug, Default)]
pub struct FunctionLayout {
    placements: Vec<Option<Placement>>,
    /// Evaluated expressions in the order the statements evaluate them.
    order: Vec<Handle<Expression>>,
    pub stores: Vec<Store>,
    pub calls: Vec<CallSite>,
    /// Values the function's effects consume directly: returned values,
    /// branch conditions and selectors, stores into non-local memory,
    /// arguments of calls, image stores and atomics.
    pub roots: Vec<Handle<Expression>>,
    pub loops: Vec<LoopBound>,
    /// Whether the function contains a `discard`.
    pub discards: bool,
    /// Every `discard`, in statement order.
    pub kills: Vec<ExitSite>,
    /// Every `return`, in statement order.
    pub returns: Vec<ExitSite>,
}

/// A `discard` or `return` statement and where it runs.
#[derive(Clone, Debug)]
pub struct ExitSite {
    /// How many expressions are evaluated before it (an index into the
    /// evaluation order, comparable with [`FunctionLayout::order_of`]).
    pub after: usize,
    pub placement: Placement,
}

impl FunctionLayout {
    /// Where `expr` is evaluated; `None` for expressions no statement
    /// evaluates (literals, constants, arguments, variable pointers), which
    /// cost nothing at run time.
    pub fn placement(&self, expr: Handle<Expression>) -> Option<&Placement> {
        self.placements.get(expr.index()).and_then(Option::as_ref)
    }

    /// Where `expr` comes in the evaluation order.
    pub fn order_of(&self, expr: Handle<Expression>) -> Option<usize> {
        self.order.iter().position(|&e| e == expr)
    }

    /// All evaluated expressions with their placements, in evaluation order.
    pub fn placed(&self) -> impl Iterator<Item = (Handle<Expression>, &Placement)> + '_ {
        self.order
            .iter()
            .filter_map(|&expr| self.placement(expr).map(|p| (expr, p)))
    }
}

/// Walks `function`'s statements and records where each expression runs.
/// Loops whose trip count cannot be inferred run `default_trips` times.
pub fn layout(
    module: &naga::Module,
    function: &naga::Function,
    default_trips: f64,
) -> FunctionLayout {
    let mut walker = Walker {
        module,
        function,
        default_trips,
        out: FunctionLayout {
            placements: vec![None; function.expressions.len()],
            ..FunctionLayout::default()
        },
    };
    walker.block(&function.body, &Placement::top());
    walker.out
}

struct Walker<'a> {
    module: &'a naga::Module,
    function: &'a naga::Function,
    default_trips: f64,
    out: FunctionLayout,
}

impl Walker<'_> {
    fn place(&mut self, expr: Handle<Expression>, at: &Placement) {
        if let Some(slot) = self.out.placements.get_mut(expr.index()) {
            if slot.is_none() {
                self.out.order.push(expr);
            }
            *slot = Some(at.clone());
        }
    }

    fn block(&mut self, block: &Block, at: &Placement) {
        for (index, statement) in block.iter().enumerate() {
            self.statement(statement, &block[..index], at);
        }
    }

    fn statement(&mut self, statement: &Statement, before: &[Statement], at: &Placement) {
        match *statement {
            Statement::Emit(ref range) => {
                for expr in range.clone() {
                    self.place(expr, at);
                }
            }
            Statement::Block(ref inner) => self.block(inner, at),
            Statement::If {
                condition,
                ref accept,
                ref reject,
            } => {
                self.out.roots.push(condition);
                let mut inner = at.clone();
                inner.controls.push(condition);
                self.block(accept, &inner);
                self.block(reject, &inner);
            }
            Statement::Switch {
                selector,
                ref cases,
            } => {
                self.out.roots.push(selector);
                let mut inner = at.clone();
                inner.controls.push(selector);
                for case in cases {
                    self.block(&case.body, &inner);
                }
            }
            Statement::Loop {
                ref body,
                ref continuing,
                break_if,
            } => self.loop_statement((body, continuing, break_if), before, at),
            Statement::Return { value } => {
                self.out.roots.extend(value);
                self.out.returns.push(ExitSite {
                    after: self.out.order.len(),
                    placement: at.clone(),
                });
            }
            Statement::Kill => {
                self.out.discards = true;
                self.out.kills.push(ExitSite {
                    after: self.out.order.len(),
                    placement: at.clone(),
                });
            }
            Statement::Store { pointer, value } => {
                let target = pointer_root(self.function, pointer);
                if !matches!(target, Some(PointerRoot::Local(_))) {
                    self.out.roots.extend([pointer, value]);
                }
                self.out.stores.push(Store {
                    pointer,
                    value,
                    target,
                    placement: at.clone(),
                });
            }
            Statement::Call {
                function,
                ref arguments,
                result,
            } => self.call_statement(function, arguments, result, at),
            Statement::ImageStore { .. }
            | Statement::Atomic { .. }
            | Statement::ImageAtomic { .. }
            | Statement::WorkGroupUniformLoad { .. }
            | Statement::SubgroupBallot { .. }
            | Statement::SubgroupGather { .. }
            | Statement::SubgroupCollectiveOperation { .. }
            | Statement::RayQuery { .. }
            | Statement::RayPipelineFunction(_)
            | Statement::CooperativeStore { .. } => self.memory_statement(statement, at),
            Statement::Break
            | Statement::Continue
            | Statement::ControlBarrier(_)
            | Statement::MemoryBarrier(_) => {}
        }
    }

    /// A loop: its trip count (from the statements `before` it), its body
    /// and continuing block placed that many times over, under the
    /// conditions that leave it.
    fn loop_statement(
        &mut self,
        (body, continuing, break_if): (&Block, &Block, Option<Handle<Expression>>),
        before: &[Statement],
        at: &Placement,
    ) {
        let trips = loop_trips(self.module, self.function, before, body, continuing);
        let assumed = trips.map_or(self.default_trips, |n| n as f64);
        self.out.loops.push(LoopBound { trips, assumed });
        let mut inner = at.clone();
        inner.multiplier *= assumed;
        inner.loop_depth += 1;
        collect_conditions(body, &mut inner.controls);
        collect_conditions(continuing, &mut inner.controls);
        inner.controls.extend(break_if);
        self.out.roots.extend(break_if);
        self.block(body, &inner);
        self.block(continuing, &inner);
    }

    fn call_statement(
        &mut self,
        function: Handle<naga::Function>,
        arguments: &[Handle<Expression>],
        result: Option<Handle<Expression>>,
        at: &Placement,
    ) {
        // A call whose value is unused, or whose callee writes
        // memory or discards, needs its arguments for its effects;
        // otherwise they are needed only through its result.
        if result.is_none() || has_effects(self.module, function) {
            self.out.roots.extend(arguments.iter().copied());
        }
        if let Some(result) = result {
            self.place(result, at);
        }
        self.out.calls.push(CallSite {
            function,
            arguments: arguments.to_vec(),
            result,
            placement: at.clone(),
        });
    }

    /// A statement that writes memory, reads other invocations or traces
    /// rays: what it reads is needed for its effect; what it returns is
    /// placed here.
    fn memory_statement(&mut self, statement: &Statement, at: &Placement) {
        match *statement {
            Statement::ImageStore {
                image,
                coordinate,
                array_index,
                value,
            } => {
                self.out.roots.extend([image, coordinate, value]);
                self.out.roots.extend(array_index);
            }
            Statement::Atomic {
                pointer,
                ref fun,
                value,
                result,
            } => {
                self.out.roots.extend([pointer, value]);
                if let naga::AtomicFunction::Exchange {
                    compare: Some(compare),
                } = *fun
                {
                    self.out.roots.push(compare);
                }
                if let Some(result) = result {
                    self.place(result, at);
                }
            }
            Statement::ImageAtomic {
                image,
                coordinate,
                array_index,
                value,
                ..
            } => {
                self.out.roots.extend([image, coordinate, value]);
                self.out.roots.extend(array_index);
            }
            Statement::WorkGroupUniformLoad { pointer, result } => {
                self.out.roots.push(pointer);
                self.place(result, at);
            }
            Statement::SubgroupBallot { result, predicate } => {
                self.out.roots.extend(predicate);
                self.place(result, at);
            }
            Statement::SubgroupGather {
                argument, result, ..
            }
            | Statement::SubgroupCollectiveOperation {
                argument, result, ..
            } => {
                self.out.roots.push(argument);
                self.place(result, at);
            }
            Statement::RayQuery { query, ref fun } => {
                self.out.roots.push(query);
                match *fun {
                    naga::RayQueryFunction::Initialize {
                        acceleration_structure,
                        descriptor,
                    } => self.out.roots.extend([acceleration_structure, descriptor]),
                    naga::RayQueryFunction::Proceed { result } => self.place(result, at),
                    naga::RayQueryFunction::GenerateIntersection { hit_t } => {
                        self.out.roots.push(hit_t)
                    }
                    naga::RayQueryFunction::ConfirmIntersection
                    | naga::RayQueryFunction::Terminate => {}
                }
            }
            Statement::RayPipelineFunction(naga::RayPipelineFunction::TraceRay {
                acceleration_structure,
                descriptor,
                payload,
            }) => self
                .out
                .roots
                .extend([acceleration_structure, descriptor, payload]),
            Statement::CooperativeStore { target, ref data } => {
                self.out.roots.extend([target, data.pointer, data.stride])
            }
            // The control flow and plain stores are `statement`'s.
            _ => {}
        }
    }
}

/// Whether calling `function` does anything besides returning a value:
/// writes memory other than its own locals, discards, or calls a function
/// that does.
pub fn has_effects(module: &naga::Module, function: Handle<naga::Function>) -> bool {
    let callee = &module.functions[function];
    let mut effects = false;
    each_statement(&callee.body, &mut |statement| {
        effects |= match *statement {
            Statement::Store { pointer, .. } => {
                !matches!(pointer_root(callee, pointer), Some(PointerRoot::Local(_)))
            }
            Statement::Kill
            | Statement::ImageStore { .. }
            | Statement::Atomic { .. }
            | Statement::ImageAtomic { .. }
            | Statement::RayQuery { .. }
            | Statement::RayPipelineFunction(_)
            | Statement::CooperativeStore { .. } => true,
            Statement::Call { function, .. } => has_effects(module, function),
            _ => false,
        };
    });
    effects
}

/// Calls `visit` on every statement of `block`, nested ones included, in
/// order.
pub fn each_statement(block: &Block, visit: &mut impl FnMut(&Statement)) {
    each_spanned_statement(block, &mut |statement, _| visit(statement));
}

/// The helpers `block` calls, directly or not, callees first; `seen`
/// holds those already collected.
pub fn collect_callees(
    module: &Module,
    block: &naga::Block,
    out: &mut Vec<Handle<Function>>,
    seen: &mut BTreeSet<Handle<Function>>,
) {
    each_statement(block, &mut |statement| {
        if let Statement::Call { function, .. } = *statement {
            if seen.insert(function) {
                collect_callees(module, &module.functions[function].body, out, seen);
                out.push(function);
            }
        }
    });
}

/// Calls `visit` on every statement of `block` and its span, nested ones
/// included, in order.
pub fn each_spanned_statement(block: &Block, visit: &mut impl FnMut(&Statement, naga::Span)) {
    for (statement, &span) in block.span_iter() {
        visit(statement, span);
        match *statement {
            Statement::Block(ref inner) => each_spanned_statement(inner, visit),
            Statement::If {
                ref accept,
                ref reject,
                ..
            } => {
                each_spanned_statement(accept, visit);
                each_spanned_statement(reject, visit);
            }
            Statement::Switch { ref cases, .. } => {
                for case in cases {
                    each_spanned_statement(&case.body, visit);
                }
            }
            Statement::Loop {
                ref body,
                ref continuing,
                ..
            } => {
                each_spanned_statement(body, visit);
                each_spanned_statement(continuing, visit);
            }
            _ => {}
        }
    }
}

/// Every branch condition, selector and `break if` inside `block`.
fn collect_conditions(block: &Block, out: &mut Vec<Handle<Expression>>) {
    each_statement(block, &mut |statement| match *statement {
        Statement::If { condition, .. } => out.push(condition),
        Statement::Switch { selector, .. } => out.push(selector),
        Statement::Loop { break_if, .. } => out.extend(break_if),
        _ => {}
    });
}

/// Infers the trip count of a loop in the shape naga's WGSL front end gives
/// `for` and `while` loops: the body opens with
/// `if (i OP bound) {} else { break; }`, the continuing block stores
/// `i ± step` into `i`, and `i` starts from a constant (its initializer or
/// the last store before the loop).
fn loop_trips(
    module: &naga::Module,
    function: &naga::Function,
    before: &[Statement],
    body: &Block,
    continuing: &Block,
) -> Option<u64> {
    let int = |expr| const_int(module, function, expr);
    let load_of = |expr| local_load(function, expr);

    // The exit test: the first statement after the leading emits.
    let condition = body.iter().find_map(|statement| match *statement {
        Statement::Emit(_) => None,
        Statement::If {
            condition,
            ref accept,
            ref reject,
        } if accept.is_empty()
            && reject.len() == 1
            && matches!(reject.iter().next(), Some(Statement::Break)) =>
        {
            Some(Some(condition))
        }
        _ => Some(None),
    })??;
    let Expression::Binary { op, left, right } = function.expressions[condition] else {
        return None;
    };
    use naga::BinaryOperator as B;
    // Normalise to `i OP bound`.
    let (counter, bound, op) = match (load_of(left), load_of(right)) {
        (Some(local), _) if int(right).is_some() => (local, int(right)?, op),
        (_, Some(local)) if int(left).is_some() => {
            let flipped = match op {
                B::Less => B::Greater,
                B::LessEqual => B::GreaterEqual,
                B::Greater => B::Less,
                B::GreaterEqual => B::LessEqual,
                other => other,
            };
            (local, int(left)?, flipped)
        }
        _ => return None,
    };

    let step = counter_step(module, function, continuing, counter)?;
    // The counter must not be written in the body itself.
    if writes_local(body, function, counter) {
        return None;
    }

    // The start value: the initializer, or the last store before the loop.
    let mut start = function.local_variables[counter].init.and_then(int);
    for statement in before.iter() {
        if let Statement::Store { pointer, value } = *statement {
            if function.expressions[pointer] == Expression::LocalVariable(counter) {
                start = int(value);
            }
        }
    }
    let start = start?;

    let trips = match op {
        B::Less if step > 0 => (bound - start + step - 1).div_euclid(step),
        B::LessEqual if step > 0 => (bound - start).div_euclid(step) + 1,
        B::Greater if step < 0 => (start - bound + (-step) - 1).div_euclid(-step),
        B::GreaterEqual if step < 0 => (start - bound).div_euclid(-step) + 1,
        B::NotEqual if step != 0 && (bound - start) % step == 0 => (bound - start) / step,
        _ => return None,
    };
    u64::try_from(trips.max(0)).ok()
}

/// The load of a local variable that `expr` is, if it is one.
fn local_load(
    function: &naga::Function,
    expr: Handle<Expression>,
) -> Option<Handle<naga::LocalVariable>> {
    match function.expressions[expr] {
        Expression::Load { pointer } => match function.expressions[pointer] {
            Expression::LocalVariable(local) => Some(local),
            _ => None,
        },
        _ => None,
    }
}

/// The step of a loop's `counter`: the only store to it in `continuing`,
/// the counter plus or minus a constant.
fn counter_step(
    module: &naga::Module,
    function: &naga::Function,
    continuing: &Block,
    counter: Handle<naga::LocalVariable>,
) -> Option<i64> {
    use naga::BinaryOperator as B;
    let int = |expr| const_int(module, function, expr);
    let load_of = |expr| local_load(function, expr);
    let mut step = None;
    for statement in continuing.iter() {
        if let Statement::Store { pointer, value } = *statement {
            if function.expressions[pointer] != Expression::LocalVariable(counter) {
                continue;
            }
            if step.is_some() {
                return None;
            }
            let Expression::Binary { op, left, right } = function.expressions[value] else {
                return None;
            };
            step = match (
                op,
                load_of(left) == Some(counter),
                load_of(right) == Some(counter),
            ) {
                (B::Add, true, _) => int(right),
                (B::Add, _, true) => int(left),
                (B::Subtract, true, _) => int(right).map(|s| -s),
                _ => None,
            };
            step?;
        }
    }
    step
}

fn writes_local(
    block: &Block,
    function: &naga::Function,
    local: Handle<naga::LocalVariable>,
) -> bool {
    let target = Some(PointerRoot::Local(local));
    let mut writes = false;
    each_statement(block, &mut |statement| {
        writes |= match *statement {
            Statement::Store { pointer, .. } => pointer_root(function, pointer) == target,
            // A call may write the counter through a pointer argument.
            Statement::Call { ref arguments, .. } => arguments
                .iter()
                .any(|&argument| pointer_root(function, argument) == target),
            _ => false,
        };
    });
    writes
}

//! Reaching definitions of function-local variables.
//!
//! A load of a local `var` reads whatever the last writes before it left
//! there. Shaders as engines write them carry their results through such
//! variables — `var color = base; if (flags & TEXTURED) { color *= tex; }
//! ... return color;` — so the value of a load is decided by the stores
//! that can *reach* it: the ones with a path to the load on which no other
//! store overwrites the whole variable. This is the textbook forward
//! data-flow problem, solved here over naga's structured statement tree
//! rather than a control-flow graph: an `if` joins its two arms, a
//! `switch` its cases, a `loop` is iterated to a fixed point, and `break`,
//! `continue`, `return` and `discard` leave the path they end.
//!
//! A store through the whole variable (`v = x`) kills the definitions
//! before it; a store through part of it (`v.member = x`, `v[i] = x`) or a
//! call given a pointer into it adds a definition and kills none.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use naga::{Block, Expression, Handle, LocalVariable, Statement};

use super::{pointer_root, PointerRoot};

/// One definition of a local variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Definition {
    /// The variable's initializer, or its zero value when it has none.
    Init,
    /// The store with this index in [`super::FunctionLayout::stores`]
    /// (statement order).
    Store(usize),
    /// The call with this index in [`super::FunctionLayout::calls`], given
    /// a pointer into the variable.
    Call(usize),
}

/// What may reach a point: per variable, its definitions. Every variable
/// starts with [`Definition::Init`].
type State = BTreeMap<Handle<LocalVariable>, BTreeSet<Definition>>;

/// For every load of a local variable (through the whole variable or a
/// part of it), the definitions that may reach it.
pub fn reaching_definitions(
    function: &naga::Function,
) -> HashMap<Handle<Expression>, Vec<Definition>> {
    let mut walker = Walker {
        function,
        stores: 0,
        calls: 0,
        loads: HashMap::new(),
        exits: Vec::new(),
    };
    let start: State = function
        .local_variables
        .iter()
        .map(|(local, _)| (local, BTreeSet::from([Definition::Init])))
        .collect();
    walker.block(&function.body, Some(start));
    walker
        .loads
        .into_iter()
        .map(|(load, defs)| (load, defs.into_iter().collect()))
        .collect()
}

/// Where `break` and `continue` send the state they end with.
#[derive(Default)]
struct Exits {
    breaks: Option<State>,
    continues: Option<State>,
    /// A `switch` takes `break`s only; `continue` goes to the loop around.
    is_switch: bool,
}

struct Walker<'a> {
    function: &'a naga::Function,
    /// Statements numbered so far, in the order the layout numbers them.
    stores: usize,
    calls: usize,
    loads: HashMap<Handle<Expression>, BTreeSet<Definition>>,
    exits: Vec<Exits>,
}

/// Joins `from` into `into`; `None` is a point no path reaches.
fn join(into: &mut Option<State>, from: Option<State>) {
    let Some(from) = from else { return };
    match into {
        None => *into = Some(from),
        Some(into) => {
            for (local, definitions) in from {
                into.entry(local).or_default().extend(definitions);
            }
        }
    }
}

impl Walker<'_> {
    fn local_of(&self, pointer: Handle<Expression>) -> Option<Handle<LocalVariable>> {
        match pointer_root(self.function, pointer) {
            Some(PointerRoot::Local(local)) => Some(local),
            _ => None,
        }
    }

    fn block(&mut self, block: &Block, mut state: Option<State>) -> Option<State> {
        for statement in block.iter() {
            state = self.statement(statement, state);
        }
        state
    }

    /// The state after `statement`, given the state before it. Numbering
    /// of stores and calls goes on on unreachable paths too, so indices stay
    /// those of the layout.
    fn statement(&mut self, statement: &Statement, state: Option<State>) -> Option<State> {
        match *statement {
            Statement::Emit(ref range) => {
                if let Some(state) = &state {
                    for expr in range.clone() {
                        if let Expression::Load { pointer } = self.function.expressions[expr] {
                            if let Some(defs) = self.local_of(pointer).and_then(|l| state.get(&l)) {
                                self.loads.entry(expr).or_default().extend(defs);
                            }
                        }
                    }
                }
                state
            }
            Statement::Block(ref inner) => self.block(inner, state),
            Statement::If {
                ref accept,
                ref reject,
                ..
            } => {
                let mut after = self.block(accept, state.clone());
                join(&mut after, self.block(reject, state));
                after
            }
            Statement::Switch { ref cases, .. } => {
                self.exits.push(Exits {
                    is_switch: true,
                    ..Exits::default()
                });
                let mut after = None;
                let mut falling: Option<State> = None;
                for case in cases {
                    let mut entry = state.clone();
                    join(&mut entry, falling.take());
                    let end = self.block(&case.body, entry);
                    if case.fall_through {
                        falling = end;
                    } else {
                        join(&mut after, end);
                    }
                }
                join(&mut after, falling);
                let exits = self.exits.pop().unwrap_or_default();
                join(&mut after, exits.breaks);
                after
            }
            Statement::Loop {
                ref body,
                ref continuing,
                break_if,
            } => self.loop_(body, continuing, break_if.is_some(), state),
            Statement::Break => {
                if let Some(exits) = self.exits.last_mut() {
                    join(&mut exits.breaks, state);
                }
                None
            }
            Statement::Continue => {
                if let Some(exits) = self.exits.iter_mut().rev().find(|e| !e.is_switch) {
                    join(&mut exits.continues, state);
                }
                None
            }
            Statement::Return { .. } | Statement::Kill => None,
            Statement::Store { pointer, .. } => {
                let index = self.stores;
                self.stores += 1;
                let mut state = state?;
                if let Some(defs) = self.local_of(pointer).and_then(|l| state.get_mut(&l)) {
                    let whole = matches!(
                        self.function.expressions[pointer],
                        Expression::LocalVariable(_)
                    );
                    if whole {
                        defs.clear();
                    }
                    defs.insert(Definition::Store(index));
                }
                Some(state)
            }
            Statement::Call { ref arguments, .. } => {
                let index = self.calls;
                self.calls += 1;
                let mut state = state?;
                for &argument in arguments {
                    if let Some(defs) = self.local_of(argument).and_then(|l| state.get_mut(&l)) {
                        defs.insert(Definition::Call(index));
                    }
                }
                Some(state)
            }
            _ => state,
        }
    }

    /// A loop: the body runs from the state before the loop joined with the
    /// states its iterations end with, until that no longer grows. After
    /// the loop come the `break`s' states (and the continuing block's end,
    /// when a `break if` can leave there).
    fn loop_(
        &mut self,
        body: &Block,
        continuing: &Block,
        has_break_if: bool,
        before: Option<State>,
    ) -> Option<State> {
        let (stores, calls) = (self.stores, self.calls);
        let mut entry = before.clone();
        loop {
            // Each pass numbers the same statements again.
            self.stores = stores;
            self.calls = calls;
            self.exits.push(Exits::default());
            let body_end = self.block(body, entry.clone());
            let mut exits = self.exits.pop().unwrap_or_default();
            let mut continuing_entry = body_end;
            join(&mut continuing_entry, exits.continues.take());
            // `continuing` cannot break or continue (WGSL), only `break if`.
            let continuing_end = self.block(continuing, continuing_entry);

            let mut next = before.clone();
            join(&mut next, continuing_end.clone());
            if next == entry {
                let mut after = exits.breaks;
                if has_break_if {
                    join(&mut after, continuing_end);
                }
                return after;
            }
            entry = next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reaching definitions of the load bound to `let name`.
    fn reaching(source: &str, name: &str) -> Vec<Definition> {
        let module = naga::front::wgsl::parse_str(source).expect("valid WGSL");
        let function = &module.entry_points[0].function;
        let (load, _) = function
            .named_expressions
            .iter()
            .find(|(_, n)| n.as_str() == name)
            .expect("the named load");
        reaching_definitions(function)
            .remove(load)
            .expect("the load is recorded")
    }

    /// The indices are those of the layout: every definition reaching a
    /// load writes the variable the load reads, in every function of the
    /// engine-style corpus shaders (loops, nested flag branches, partial
    /// stores into a struct).
    #[test]
    fn definitions_index_the_layouts_stores_and_calls() {
        for source in [
            include_str!("../../corpus/pbr_material_flags.wgsl"),
            include_str!("../../corpus/terrain_slope_branch.wgsl"),
        ] {
            let module = naga::front::wgsl::parse_str(source).expect("valid WGSL");
            let functions = module
                .functions
                .iter()
                .map(|(_, f)| f)
                .chain(module.entry_points.iter().map(|ep| &ep.function));
            let mut checked = 0;
            for function in functions {
                let layout = super::super::layout(&module, function, 8.0);
                for (load, definitions) in reaching_definitions(function) {
                    let pointer = match function.expressions[load] {
                        Expression::Load { pointer } => Some(pointer),
                        _ => None,
                    };
                    let root = pointer.and_then(|p| pointer_root(function, p));
                    assert!(root.is_some(), "a load of a local");
                    for definition in definitions {
                        match definition {
                            Definition::Init => {}
                            Definition::Store(i) => assert_eq!(layout.stores[i].target, root),
                            Definition::Call(i) => assert!(layout.calls[i]
                                .arguments
                                .iter()
                                .any(|&a| pointer_root(function, a) == root)),
                        }
                        checked += 1;
                    }
                }
            }
            assert!(checked > 20, "{checked} definitions checked");
        }
    }

    const HEAD: &str = "@fragment\nfn fs(@location(0) x: f32) -> @location(0) vec4<f32> {\n";

    #[test]
    fn a_store_in_each_arm_both_reach_and_kill_the_first() {
        let source = format!(
            "{HEAD}    var c = 1.0;\n    if (x > 0.5) {{ c = sin(x); }} else {{ c = cos(x); }}\n    let r: f32 = c;\n    return vec4<f32>(r);\n}}\n"
        );
        assert_eq!(
            reaching(&source, "r"),
            vec![Definition::Store(0), Definition::Store(1)]
        );
    }

    #[test]
    fn a_store_in_one_arm_keeps_the_initializer() {
        let source = format!(
            "{HEAD}    var c = 1.0;\n    if (x > 0.5) {{ c = sin(x); }}\n    let r: f32 = c;\n    c = 2.0;\n    return vec4<f32>(r, c, 0.0, 1.0);\n}}\n"
        );
        // The store after the load does not reach it.
        assert_eq!(
            reaching(&source, "r"),
            vec![Definition::Init, Definition::Store(0)]
        );
    }

    #[test]
    fn a_loop_reaches_its_own_next_iteration_and_what_follows() {
        let source = format!(
            "{HEAD}    var sum = 0.0;\n    for (var i = 0; i < 4; i++) {{\n        let inside: f32 = sum;\n        sum = inside + sin(x * f32(i));\n    }}\n    let after: f32 = sum;\n    return vec4<f32>(after);\n}}\n"
        );
        // Store 0 is `sum = ...`, store 1 the counter's `i++`.
        assert_eq!(
            reaching(&source, "inside"),
            vec![Definition::Init, Definition::Store(0)]
        );
        assert_eq!(
            reaching(&source, "after"),
            vec![Definition::Init, Definition::Store(0)]
        );
    }

    #[test]
    fn a_partial_store_adds_without_killing() {
        let source = format!(
            "{HEAD}    var v = vec2<f32>(x);\n    v.y = sin(x);\n    let r: vec2<f32> = v;\n    return vec4<f32>(r, 0.0, 1.0);\n}}\n"
        );
        // naga stores a non-constant initializer (store 0); `v.y = ...` is
        // store 1, which keeps it.
        assert_eq!(
            reaching(&source, "r"),
            vec![Definition::Store(0), Definition::Store(1)]
        );
    }

    #[test]
    fn a_returning_arm_does_not_reach_past_the_branch() {
        let source = format!(
            "{HEAD}    var c = 1.0;\n    if (x > 0.5) {{ c = sin(x); return vec4<f32>(c); }} else {{ c = cos(x); }}\n    let r: f32 = c;\n    return vec4<f32>(r);\n}}\n"
        );
        assert_eq!(reaching(&source, "r"), vec![Definition::Store(1)]);
    }

    #[test]
    fn switch_cases_and_their_breaks_join() {
        let source = format!(
            "{HEAD}    var c = 1.0;\n    switch (i32(x)) {{\n        case 0: {{ c = sin(x); }}\n        case 1: {{ if (x > 0.5) {{ c = 3.0; break; }} c = 4.0; }}\n        default: {{}}\n    }}\n    let r: f32 = c;\n    return vec4<f32>(r);\n}}\n"
        );
        assert_eq!(
            reaching(&source, "r"),
            vec![
                Definition::Init,
                Definition::Store(0),
                Definition::Store(1),
                Definition::Store(2)
            ]
        );
    }
}

//! The expression graph of one function: an edge from each expression to
//! every value it needs, through operands and through local variables.

use fixedbitset::FixedBitSet;
use naga::{Expression, Handle};
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::visit::{Dfs, EdgeFiltered, EdgeRef};

use crate::proc::{self, FunctionLayout, PointerRoot};

/// A set of expressions of one function.
pub type ExprSet = FixedBitSet;

/// Whether any expression of `set` reads an argument of the function (for
/// a fragment entry point: a per-fragment input). A set that reads none
/// depends only on uniforms, constants and overrides, and has the same
/// value at every pixel of a draw. `exprs` is the function's arena in
/// order.
pub fn reads_arguments(exprs: &[&Expression], set: &ExprSet) -> bool {
    set.ones()
        .any(|i| matches!(exprs[i], Expression::FunctionArgument(_)))
}

/// The dependence graph of a function's expressions.
///
/// Node `i` is the expression with arena index `i`. An edge `a → b` means
/// computing `a` needs `b`: `b` is an operand of `a`; or `a` loads a local
/// (or private) variable and `b` is a value stored into it, an index of the
/// pointer stored through, or a condition under which the store runs (for
/// a local, only the stores that reach the load: [`proc::reaching_definitions`]); or
/// `a` is a call result and `b` one of the call's arguments.
#[derive(Debug)]
pub struct ExprGraph {
    graph: DiGraph<Handle<Expression>, ()>,
    roots: Vec<NodeIndex>,
}

impl ExprGraph {
    pub fn new(function: &naga::Function, layout: &FunctionLayout) -> Self {
        let mut graph = DiGraph::with_capacity(function.expressions.len(), 0);
        for (handle, _) in function.expressions.iter() {
            graph.add_node(handle);
        }
        let node = |h: Handle<Expression>| NodeIndex::new(h.index());

        // What one definition of a variable needs: the value stored, the
        // pointer stored through (its indices) and the conditions under
        // which the store runs.
        let store_needs = |store: &proc::Store, needed: &mut Vec<Handle<Expression>>| {
            needed.push(store.value);
            needed.push(store.pointer);
            needed.extend(store.placement.controls.iter().copied());
        };
        let call_needs = |call: &proc::CallSite, needed: &mut Vec<Handle<Expression>>| {
            needed.extend(call.arguments.iter().copied());
            needed.extend(call.placement.controls.iter().copied());
        };
        // Every value written into a variable, wherever it is written: for
        // private globals, and for a local load the reaching-definitions
        // walk did not see (it sees every emitted one).
        let writes_to = |root: PointerRoot| -> Vec<Handle<Expression>> {
            let mut needed = Vec::new();
            if let PointerRoot::Local(local) = root {
                needed.extend(function.local_variables[local].init);
            }
            for store in layout.stores.iter().filter(|s| s.target == Some(root)) {
                store_needs(store, &mut needed);
            }
            // A call given a pointer into the variable may write through it.
            for call in &layout.calls {
                if call
                    .arguments
                    .iter()
                    .any(|&arg| proc::pointer_root(function, arg) == Some(root))
                {
                    call_needs(call, &mut needed);
                }
            }
            needed
        };
        // What a load of a local needs: only the definitions that reach it.
        let reaching_definitions = proc::reaching_definitions(function);
        let reaching = |load: Handle<Expression>,
                        local: Handle<naga::LocalVariable>|
         -> Option<Vec<Handle<Expression>>> {
            let definitions = reaching_definitions.get(&load)?;
            let mut needed = Vec::new();
            for definition in definitions {
                match *definition {
                    proc::Definition::Init => {
                        needed.extend(function.local_variables[local].init);
                    }
                    proc::Definition::Store(index) => {
                        store_needs(&layout.stores[index], &mut needed)
                    }
                    proc::Definition::Call(index) => call_needs(&layout.calls[index], &mut needed),
                }
            }
            Some(needed)
        };

        for (handle, expr) in function.expressions.iter() {
            for operand in proc::operands(expr) {
                graph.add_edge(node(handle), node(operand), ());
            }
            if let Expression::Load { pointer } = *expr {
                let needed = match proc::pointer_root(function, pointer) {
                    Some(root @ PointerRoot::Local(local)) => {
                        reaching(handle, local).unwrap_or_else(|| writes_to(root))
                    }
                    Some(root @ PointerRoot::Global(_)) => writes_to(root),
                    _ => Vec::new(),
                };
                for needed in needed {
                    graph.add_edge(node(handle), node(needed), ());
                }
            }
        }
        for call in &layout.calls {
            if let Some(result) = call.result {
                for &argument in &call.arguments {
                    graph.add_edge(node(result), node(argument), ());
                }
            }
        }
        let roots = layout.roots.iter().map(|&h| node(h)).collect();
        ExprGraph { graph, roots }
    }

    fn empty_set(&self) -> ExprSet {
        FixedBitSet::with_capacity(self.graph.node_count())
    }

    /// The backward slice of `expr`: everything computing it needs,
    /// `expr` included.
    pub fn slice(&self, expr: Handle<Expression>) -> ExprSet {
        let mut set = self.empty_set();
        let mut dfs = Dfs::new(&self.graph, NodeIndex::new(expr.index()));
        while let Some(node) = dfs.next(&self.graph) {
            set.insert(node.index());
        }
        set
    }

    /// What the rest of the function needs once `expr` is read from a cache
    /// instead of computed: the slice of the function's effects with the
    /// edges out of `expr` cut. `expr` itself is in the set when it is used.
    pub fn remainder(&self, expr: Handle<Expression>) -> ExprSet {
        let cut = NodeIndex::new(expr.index());
        let filtered = EdgeFiltered::from_fn(&self.graph, |edge| edge.source() != cut);
        let mut set = self.empty_set();
        let mut dfs = Dfs::empty(&filtered);
        for &root in &self.roots {
            // `move_to` keeps the visited map, so shared parts are walked once.
            dfs.move_to(root);
            while let Some(node) = dfs.next(&filtered) {
                set.insert(node.index());
            }
        }
        set
    }
}

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

    /// For every expression, what only it needs: the expressions every path
    /// from the function's effects to them passes through it ([`Private`]).
    /// One dominator tree for the whole function, where asking
    /// [`Self::remainder`] of every candidate walks the graph once per
    /// candidate (quadratic in a long expression).
    pub fn private(&self) -> Private {
        // A virtual root above the effects: dominators need one entry.
        let n = self.graph.node_count();
        let Some(&any) = self.graph.node_weights().next() else {
            return Private {
                idom: Vec::new(),
                reachable: FixedBitSet::new(),
            };
        };
        let mut graph = self.graph.clone();
        // Its weight is never read.
        let root = graph.add_node(any);
        for &r in &self.roots {
            graph.add_edge(root, r, ());
        }
        let dominators = petgraph::algo::dominators::simple_fast(&graph, root);
        let idom: Vec<Option<usize>> = (0..n)
            .map(|i| {
                dominators
                    .immediate_dominator(NodeIndex::new(i))
                    .map(|d| d.index())
                    .filter(|&d| d < n)
            })
            .collect();
        let mut reachable = FixedBitSet::with_capacity(n);
        for i in 0..n {
            if dominators.immediate_dominator(NodeIndex::new(i)).is_some() {
                reachable.insert(i);
            }
        }
        Private { idom, reachable }
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

/// The dominator tree of a function's expression graph, rooted at its
/// effects: `a` dominates `b` when every chain of needs from an effect to
/// `b` goes through `a`. What `a` strictly dominates is exactly the part
/// of its slice that nothing else needs: the slice minus
/// [`ExprGraph::remainder`].
#[derive(Debug)]
pub struct Private {
    /// Immediate dominator of each expression; `None` for the effects
    /// themselves and for what no effect needs.
    idom: Vec<Option<usize>>,
    /// The expressions some effect needs.
    reachable: FixedBitSet,
}

impl Private {
    /// Whether some effect of the function needs `expr`.
    pub fn is_needed(&self, expr: Handle<Expression>) -> bool {
        self.reachable.contains(expr.index())
    }

    /// For each expression, the sum of `weight` over what it strictly
    /// dominates: in one pass up the tree, deepest first.
    pub fn dominated_sums(&self, weight: &[f64]) -> Vec<f64> {
        let n = self.idom.len();
        // Depths, iteratively: a long chain is a deep tree.
        let mut depth: Vec<Option<usize>> = vec![None; n];
        for start in 0..n {
            let mut path = Vec::new();
            let mut at = start;
            let base = loop {
                if let Some(d) = depth[at] {
                    break d;
                }
                path.push(at);
                match self.idom[at] {
                    Some(up) => at = up,
                    None => break 0,
                }
            };
            let first = base + usize::from(depth[at].is_some());
            for (d, &node) in (first..).zip(path.iter().rev()) {
                depth[node] = Some(d);
            }
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(depth[i]));
        let mut subtree: Vec<f64> = weight.to_vec();
        subtree.resize(n, 0.0);
        for &node in &order {
            if let Some(up) = self.idom[node] {
                subtree[up] += subtree[node];
            }
        }
        (0..n)
            .map(|i| subtree[i] - weight.get(i).copied().unwrap_or(0.0))
            .collect()
    }
}

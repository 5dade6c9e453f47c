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
        Self::build(function, layout, false)
    }

    /// As [`ExprGraph::new`], but a load of a local's member needs no
    /// store to another member: `out.position` computed from
    /// `out.world_position` does not need what was stored in
    /// `out.world_normal`. (Only constant member paths are told apart; a
    /// dynamic index may write any element.) The cache's analysis keeps
    /// [`ExprGraph::new`], whose per-variable slices its figures were
    /// measured with; what needs the position alone uses this.
    pub fn member_precise(function: &naga::Function, layout: &FunctionLayout) -> Self {
        Self::build(function, layout, true)
    }

    fn build(function: &naga::Function, layout: &FunctionLayout, precise: bool) -> Self {
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
        // What a call reads through the pointers it is given: every value
        // written into the variables they point into (Bevy's
        // `point_light(id, &lighting_input)` reads the members
        // `apply_pbr_lighting` stored into its local). Without it, a slice
        // that needs the call's result or what it writes kept the call and
        // dropped those stores, and the callee read an unwritten variable.
        let call_reads = |call: &proc::CallSite| -> Vec<Handle<Expression>> {
            let mut roots: Vec<PointerRoot> = call
                .arguments
                .iter()
                .filter_map(|&arg| proc::pointer_root(function, arg))
                .filter(|root| matches!(root, PointerRoot::Local(_) | PointerRoot::Global(_)))
                .collect();
            roots.dedup();
            roots.into_iter().flat_map(writes_to).collect()
        };
        let call_needs = |call: &proc::CallSite, needed: &mut Vec<Handle<Expression>>| {
            call_needs(call, needed);
            needed.extend(call_reads(call));
        };
        // What a load of a local needs: only the definitions that reach it.
        let reaching_definitions = proc::reaching_definitions(function);
        let reaching = |load: Handle<Expression>,
                        local: Handle<naga::LocalVariable>|
         -> Option<Vec<Handle<Expression>>> {
            let definitions = reaching_definitions.get(&load)?;
            let loaded = match function.expressions[load] {
                Expression::Load { pointer } => pointer,
                _ => load,
            };
            let mut needed = Vec::new();
            for definition in definitions {
                match *definition {
                    proc::Definition::Init => {
                        needed.extend(function.local_variables[local].init);
                    }
                    proc::Definition::Store(index)
                        if precise && disjoint(function, loaded, layout.stores[index].pointer) => {}
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
                for read in call_reads(call) {
                    graph.add_edge(node(result), node(read), ());
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
        if n == 0 {
            return Private {
                idom: Vec::new(),
                reachable: FixedBitSet::new(),
            };
        }
        // Node n is the virtual root.
        let mut successors: Vec<Vec<usize>> = (0..n)
            .map(|i| {
                self.graph
                    .neighbors(NodeIndex::new(i))
                    .map(|d| d.index())
                    .collect()
            })
            .collect();
        successors.push(self.roots.iter().map(|r| r.index()).collect());
        let dominators = immediate_dominators(&successors, n);
        let idom: Vec<Option<usize>> = dominators[..n]
            .iter()
            .map(|d| d.filter(|&d| d < n))
            .collect();
        let mut reachable = FixedBitSet::with_capacity(n);
        for (i, d) in dominators[..n].iter().enumerate() {
            if d.is_some() {
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

/// The constant member path of a pointer from its variable (`None` for a
/// dynamic index), outermost first.
fn member_path(function: &naga::Function, mut pointer: Handle<Expression>) -> Vec<Option<u32>> {
    let mut path = Vec::new();
    loop {
        match function.expressions[pointer] {
            Expression::AccessIndex { base, index } => {
                path.push(Some(index));
                pointer = base;
            }
            Expression::Access { base, .. } => {
                path.push(None);
                pointer = base;
            }
            _ => break,
        }
    }
    path.reverse();
    path
}

/// Whether two pointers into one variable reach parts that cannot
/// overlap: their paths part at a constant index.
fn disjoint(function: &naga::Function, a: Handle<Expression>, b: Handle<Expression>) -> bool {
    member_path(function, a)
        .iter()
        .zip(&member_path(function, b))
        .any(|pair| matches!(pair, (Some(x), Some(y)) if x != y))
}

/// A fact about an expression that a slice has when any of its
/// expressions has it: merging is idempotent, so an expression two paths
/// reach counts once. The default is the fact of no expression.
pub trait SliceFact: Clone + Default {
    fn merge(&mut self, other: &Self);
}

/// Facts about every expression's backward slice, computed for all of
/// them at once ([`ExprGraph::summaries`]).
#[derive(Debug)]
pub struct Summaries<F> {
    /// The sum of the weight over each expression's slice.
    pub cost: Vec<f64>,
    /// The merge of the facts over each expression's slice.
    pub facts: Vec<F>,
}

/// The most bits [`ExprGraph::summaries`] spends on which shared parts each
/// slice holds (16 MiB); beyond it, slices are walked one by one.
const SHARED_BITS_BUDGET: u128 = 1 << 27;

impl ExprGraph {
    /// The cost and facts of every expression's slice, in time close to
    /// linear in the graph where walking each candidate's slice is
    /// quadratic (a long sum's nested partial sums).
    ///
    /// Cycles (loop-carried values) are collapsed first: every expression
    /// of a strongly connected component has the same slice. In the
    /// acyclic graph of components, facts merge up from what a component
    /// needs. Costs cannot merge that way — a part two operands share
    /// would count twice — so the components needed by more than one
    /// other (the *shared* ones) are set apart: each component's *tree
    /// cost* sums its own weight and the tree costs of the unshared
    /// components it needs, whose only path up leads to it; the slice's
    /// cost is its tree cost plus that of every shared component in it,
    /// a bit set over the shared components carried up like a fact.
    /// `None` when those bit sets would outgrow 16 MiB (`SHARED_BITS_BUDGET`).
    pub fn summaries<F: SliceFact>(&self, weight: &[f64], fact: &[F]) -> Option<Summaries<F>> {
        // Tarjan's order is a reverse topological one: what a component
        // needs comes before it.
        let components = petgraph::algo::tarjan_scc(&self.graph);
        let n = self.graph.node_count();
        let mut component_of = vec![0usize; n];
        for (c, members) in components.iter().enumerate() {
            for member in members {
                component_of[member.index()] = c;
            }
        }
        let mut needs: Vec<Vec<usize>> = Vec::with_capacity(components.len());
        let mut needed_by = vec![0u32; components.len()];
        for (c, members) in components.iter().enumerate() {
            let mut needed: Vec<usize> = members
                .iter()
                .flat_map(|&m| self.graph.neighbors(m))
                .map(|d| component_of[d.index()])
                .filter(|&d| d != c)
                .collect();
            needed.sort_unstable();
            needed.dedup();
            for &d in &needed {
                needed_by[d] += 1;
            }
            needs.push(needed);
        }
        let mut shared_index = vec![None; components.len()];
        let mut shared = Vec::new();
        for (c, &count) in needed_by.iter().enumerate() {
            if count > 1 {
                shared_index[c] = Some(shared.len());
                shared.push(c);
            }
        }
        if components.len() as u128 * shared.len() as u128 > SHARED_BITS_BUDGET {
            return None;
        }

        let mut tree = vec![0.0; components.len()];
        let mut facts: Vec<F> = Vec::with_capacity(components.len());
        let mut shared_sets: Vec<FixedBitSet> = Vec::with_capacity(components.len());
        for (c, members) in components.iter().enumerate() {
            let mut cost = 0.0;
            let mut merged = F::default();
            for m in members.iter().map(|m| m.index()) {
                cost += weight[m];
                merged.merge(&fact[m]);
            }
            let mut set = FixedBitSet::with_capacity(shared.len());
            for &d in &needs[c] {
                merged.merge(&facts[d]);
                set.union_with(&shared_sets[d]);
                match shared_index[d] {
                    Some(i) => set.insert(i),
                    None => cost += tree[d],
                }
            }
            tree[c] = cost;
            facts.push(merged);
            shared_sets.push(set);
        }
        let cost_of_component: Vec<f64> = (0..components.len())
            .map(|c| {
                shared_sets[c]
                    .ones()
                    .fold(tree[c], |sum, i| sum + tree[shared[i]])
            })
            .collect();
        Some(Summaries {
            cost: (0..n).map(|i| cost_of_component[component_of[i]]).collect(),
            facts: (0..n).map(|i| facts[component_of[i]].clone()).collect(),
        })
    }
}

/// The immediate dominator of every node of the graph `successors`
/// (adjacency lists) that `root` reaches; `None` for the root and for the
/// nodes it does not reach.
///
/// Lengauer and Tarjan's algorithm with path compression (O(E log V)).
/// Written here because petgraph's `simple_fast` (Cooper, Harvey and
/// Kennedy) walks the dominator tree up from both sides of every edge on
/// each pass, quadratic on the deep trees a long sum's nested partial sums
/// make; the near-linear implementations on crates.io come inside a
/// compiler's data-structure crate.
fn immediate_dominators(successors: &[Vec<usize>], root: usize) -> Vec<Option<usize>> {
    const NONE: usize = usize::MAX;
    let n = successors.len();
    // Depth-first preorder, iteratively (a long chain is a deep tree):
    // a node is numbered when popped, its parent the node that pushed it.
    let mut number = vec![NONE; n];
    let mut vertex = Vec::with_capacity(n);
    let mut parent = vec![NONE; n];
    let mut stack = vec![(root, NONE)];
    while let Some((v, from)) = stack.pop() {
        if number[v] != NONE {
            continue;
        }
        number[v] = vertex.len();
        vertex.push(v);
        parent[v] = from;
        for &w in successors[v].iter().rev() {
            if number[w] == NONE {
                stack.push((w, v));
            }
        }
    }
    let mut predecessors: Vec<Vec<usize>> = vec![Vec::new(); n];
    for &v in &vertex {
        for &w in &successors[v] {
            predecessors[w].push(v);
        }
    }

    // semi: the semidominator's preorder number; ancestor and label: the
    // forest of processed nodes, compressed, with the node of least
    // semidominator on each compressed path.
    let mut semi = number.clone();
    let mut idom = vec![NONE; n];
    let mut ancestor = vec![NONE; n];
    let mut label: Vec<usize> = (0..n).collect();
    let mut bucket: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut path = Vec::new();
    let mut eval = |v: usize, ancestor: &mut [usize], label: &mut [usize], semi: &[usize]| {
        if ancestor[v] == NONE {
            return v;
        }
        let mut x = v;
        while ancestor[ancestor[x]] != NONE {
            path.push(x);
            x = ancestor[x];
        }
        while let Some(y) = path.pop() {
            let up = ancestor[y];
            if semi[label[up]] < semi[label[y]] {
                label[y] = label[up];
            }
            ancestor[y] = ancestor[up];
        }
        label[v]
    };
    for i in (1..vertex.len()).rev() {
        let w = vertex[i];
        for &v in &predecessors[w] {
            let u = eval(v, &mut ancestor, &mut label, &semi);
            if semi[u] < semi[w] {
                semi[w] = semi[u];
            }
        }
        bucket[vertex[semi[w]]].push(w);
        let p = parent[w];
        ancestor[w] = p;
        for v in std::mem::take(&mut bucket[p]) {
            let u = eval(v, &mut ancestor, &mut label, &semi);
            idom[v] = if semi[u] < semi[v] { u } else { p };
        }
    }
    for &w in vertex.iter().skip(1) {
        if idom[w] != vertex[semi[w]] {
            idom[w] = idom[idom[w]];
        }
    }
    idom.iter()
        .enumerate()
        .map(|(v, &d)| (v != root && d != NONE).then_some(d))
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Debug, Default, PartialEq)]
    struct Seen(u64);

    impl SliceFact for Seen {
        fn merge(&mut self, other: &Self) {
            self.0 |= other.0;
        }
    }

    /// The dominators agree with petgraph's on random graphs, cycles,
    /// unreachable nodes and parallel edges included.
    #[test]
    fn immediate_dominators_agree_with_petgraphs() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |bound: usize| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % bound as u64) as usize
        };
        for case in 0..200 {
            let n = 2 + case % 40;
            let edges = n * (1 + case % 3);
            let mut successors: Vec<Vec<usize>> = vec![Vec::new(); n];
            let mut graph = DiGraph::<(), ()>::new();
            let nodes: Vec<_> = (0..n).map(|_| graph.add_node(())).collect();
            for _ in 0..edges {
                let (a, b) = (next(n), next(n));
                successors[a].push(b);
                graph.add_edge(nodes[a], nodes[b], ());
            }
            let ours = immediate_dominators(&successors, 0);
            let theirs = petgraph::algo::dominators::simple_fast(&graph, nodes[0]);
            for v in 0..n {
                let expected = theirs.immediate_dominator(nodes[v]).map(|d| d.index());
                assert_eq!(ours[v], expected, "case {case}, node {v}: {successors:?}");
            }
        }
    }

    /// The summaries agree with walking each slice, on functions with
    /// shared operands, locals stored in both arms and a loop.
    #[test]
    fn summaries_agree_with_walking_each_slice() {
        let source = "
@fragment
fn fs(@location(0) p: vec3<f32>) -> @location(0) vec4<f32> {
    let a = sin(p.x) * cos(p.y);
    let b = a * a + sin(p.z);
    var c = 0.0;
    if (p.x > 0.5) { c = b * 2.0; } else { c = a + 1.0; }
    var sum = 0.0;
    for (var i = 0; i < 4; i++) {
        sum += c * f32(i) + b;
    }
    let d = sum + a * b + p.x;
    return vec4<f32>(d, c, b, a);
}
";
        let module = naga::front::wgsl::parse_str(source).unwrap();
        let function = &module.entry_points[0].function;
        let layout = crate::proc::layout(&module, function, 8.0);
        let graph = ExprGraph::new(function, &layout);
        let n = function.expressions.len();
        // Distinct powers of two: any double count shows.
        let weight: Vec<f64> = (0..n).map(|i| f64::from(1u32 << (i % 31))).collect();
        let fact: Vec<Seen> = (0..n).map(|i| Seen(1 << (i % 64))).collect();
        let summaries = graph.summaries(&weight, &fact).unwrap();
        for (handle, _) in function.expressions.iter() {
            let slice = graph.slice(handle);
            let cost = slice.ones().map(|i| weight[i]).sum::<f64>();
            let seen = slice.ones().fold(0, |s, i| s | fact[i].0);
            assert_eq!(summaries.cost[handle.index()], cost, "{handle:?}");
            assert_eq!(summaries.facts[handle.index()], Seen(seen), "{handle:?}");
        }
    }
}

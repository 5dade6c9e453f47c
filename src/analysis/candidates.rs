//! Finding the nodes of an entry point and sorting them into candidates and
//! rejected nodes.

use std::collections::{BTreeMap, HashMap};

use naga::{Expression, Handle, TypeInner};
use serde::Serialize;

use super::graph::{ExprGraph, ExprSet, SliceFact};
use super::per_frame::{loaded_buffer_member, per_frame_slots, PER_FRAME_INPUTS};
use super::spans::call_extent;
use super::{id, Analysis, Candidate, Node, Rejected, SourceSpan};
use crate::cost::CostModel;
use crate::front::Shader;
use crate::proc;

/// Why a node cannot be cached.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum RejectReason {
    /// Computed inside a loop: each iteration has its own value.
    InLoop,
    /// Of a type no cache texture holds (not a number or a vector of up to
    /// four).
    NotStorable,
    /// Too cheap to be worth a lookup.
    Trivial,
    /// Reads uniforms alone: the same at every pixel, nothing to cache per
    /// pixel.
    UniformOnly,
    /// Depends on where the pixel is on screen, which reprojection moves.
    ScreenSpace,
}

impl RejectReason {
    /// The reason as `analysis.json` and the text output spell it.
    pub fn as_str(self) -> &'static str {
        match self {
            RejectReason::InLoop => "in-loop",
            RejectReason::NotStorable => "not-storable",
            RejectReason::Trivial => "trivial",
            RejectReason::UniformOnly => "uniform-only",
            RejectReason::ScreenSpace => "screen-space",
        }
    }
}

/// Finds the candidates of fragment entry point `entry_index` (of the
/// inlined module when `analysed` has one): every node of the source with
/// its slice's cost and facts, classified, ranked.
pub(super) fn find(
    shader: &Shader,
    analysed: Option<std::sync::Arc<super::calls::Analysed>>,
    entry_index: usize,
    model: &CostModel,
) -> Analysis {
    let (module, module_info) = match &analysed {
        Some(a) => (&a.module, &a.info),
        None => (&shader.module, &shader.info),
    };
    let entry = &module.entry_points[entry_index];
    let function = &entry.function;
    let info = module_info.get_entry_point(entry_index);
    let layout = model.layout(function);
    let graph = ExprGraph::new(function, &layout);
    let costs = SliceCosts::new(module, (entry_index, info), model, &layout, &graph);
    let source = &shader.file.text;
    let lines = LineIndex::new(source);
    let origins = Origins::new(shader, analysed.as_deref(), &entry.name, &lines);
    let by_span = nodes_by_span(module, (function, info), source, &origins);

    let no_bounds = super::range::UniformBounds::default();
    let mut ranges = super::NodeRanges::new(shader, analysed.as_deref(), entry_index, &no_bounds);
    let keys = node_keys(&entry.name, origins.paths.as_ref());
    let mut naming = NodeNames::new(source, &keys);
    let mut candidates = Vec::new();
    let mut rejected = Vec::new();
    for (&(group, start, end), &expr) in &by_span {
        let origin = origins.of(expr);
        let node = Node {
            id: naming.id(group, start, end),
            span: SourceSpan {
                start: lines.line_col(start).into(),
                end: lines.line_col(end).into(),
            },
            ty: type_name(&module.types, info[expr].ty.inner_with(&module.types)),
            text: id::shown_text(&source[start..end]),
            function: origins
                .function_of(origin.call)
                .unwrap_or_default()
                .to_string(),
            call_path: origins.call_path(origin.call),
            expression: origin.expression.unwrap_or(expr),
            analysed: expr,
            range: start..end,
        };
        let (cost, facts) = costs.summary(expr);
        match classify(module, info, &layout, &facts, expr) {
            Err((reason, detail)) => rejected.push(Rejected {
                node,
                reason,
                detail,
            }),
            Ok(components) => {
                let range = ranges.of(&node);
                candidates.push(Candidate {
                    node,
                    components,
                    cost,
                    ratio: if costs.total > 0.0 {
                        cost / costs.total
                    } else {
                        0.0
                    },
                    overlap: costs.overlap(expr, cost),
                    derivatives: facts.has(SliceFacts::DERIVATIVES),
                    depends_on: facts.per_frame_inputs(),
                    range: range.ends(),
                    fits_f16: range.fits_f16(),
                });
            }
        }
    }
    rank(&mut candidates);
    Analysis {
        shader: shader.file.path.clone(),
        entry: entry.name.clone(),
        total_cost: costs.total,
        candidates,
        rejected,
        entry_index,
        analysed,
    }
}

/// What each expression's slice costs and what is true of it, and what
/// only each expression needs, computed for every expression at once
/// where the slices allow (else walked per expression).
struct SliceCosts<'g> {
    graph: &'g ExprGraph,
    /// What each expression costs per invocation, loops included.
    weighted: Vec<f64>,
    /// The whole entry point's cost.
    total: f64,
    private: super::graph::Private,
    /// What only each expression needs, summed.
    dominated: Vec<f64>,
    own_facts: Vec<SliceFacts>,
    summaries: Option<super::graph::Summaries<SliceFacts>>,
}

impl<'g> SliceCosts<'g> {
    fn new(
        module: &naga::Module,
        (entry_index, info): (usize, &naga::valid::FunctionInfo),
        model: &CostModel,
        layout: &proc::FunctionLayout,
        graph: &'g ExprGraph,
    ) -> Self {
        let function = &module.entry_points[entry_index].function;
        // Arena handles cannot be made from an index outside naga, so
        // slices (bit sets by arena index) are read through this table.
        let exprs: Vec<&Expression> = function.expressions.iter().map(|(_, e)| e).collect();
        let mut weighted = vec![0.0; function.expressions.len()];
        for (expr, at) in layout.placed() {
            weighted[expr.index()] = model.expression(function, info, expr) * at.multiplier;
        }
        let total = model.body(function, info, layout);
        let private = graph.private();
        let dominated = private.dominated_sums(&weighted);
        let varyings = super::varyings::per_frame_varyings(module, entry_index);
        let own_facts: Vec<SliceFacts> = (0..exprs.len())
            .map(|i| SliceFacts::of_expression(module, function, &exprs, &varyings, i))
            .collect();
        let summaries = graph.summaries(&weighted, &own_facts);
        SliceCosts {
            graph,
            weighted,
            total,
            private,
            dominated,
            own_facts,
            summaries,
        }
    }

    fn cost_of(&self, set: &ExprSet) -> f64 {
        // (fold from +0.0: an empty float `sum()` is -0.0)
        set.ones().fold(0.0, |sum, i| sum + self.weighted[i])
    }

    /// The cost and facts of `expr`'s slice.
    fn summary(&self, expr: Handle<Expression>) -> (f64, SliceFacts) {
        match &self.summaries {
            Some(s) => (s.cost[expr.index()], s.facts[expr.index()].clone()),
            None => {
                let slice = self.graph.slice(expr);
                let facts = slice.ones().fold(SliceFacts::NONE, |mut facts, i| {
                    facts.merge(&self.own_facts[i]);
                    facts
                });
                (self.cost_of(&slice), facts)
            }
        }
    }

    /// The overlap of `expr`'s slice (costing `cost`): the slice less the
    /// node and what only it needs (what it dominates). A node nothing
    /// needs has no dominator; its remainder is walked.
    fn overlap(&self, expr: Handle<Expression>, cost: f64) -> f64 {
        if self.private.is_needed(expr) {
            (cost - self.weighted[expr.index()] - self.dominated[expr.index()]).max(0.0)
        } else {
            let mut shared = self.graph.remainder(expr);
            shared.intersect_with(&self.graph.slice(expr));
            shared.set(expr.index(), false);
            self.cost_of(&shared)
        }
    }
}

/// Where each expression of the analysed function came from: the entry
/// point's own, or a helper's at one call site.
struct Origins<'a> {
    shader: &'a Shader,
    inlined: Option<&'a proc::inline::Inlined>,
    entry_name: &'a str,
    paths: Option<super::calls::Paths>,
}

impl<'a> Origins<'a> {
    fn new(
        shader: &'a Shader,
        analysed: Option<&'a super::calls::Analysed>,
        entry_name: &'a str,
        lines: &LineIndex,
    ) -> Self {
        let inlined = analysed.map(|a| &a.inlined);
        let paths = inlined.map(|inlined| {
            super::calls::Paths::new(&shader.module, inlined, &shader.file.text, &|offset| {
                lines.line_col(offset)
            })
        });
        Origins {
            shader,
            inlined,
            entry_name,
            paths,
        }
    }

    fn of(&self, handle: Handle<Expression>) -> proc::inline::Origin {
        match self.inlined {
            Some(inlined) => inlined.origins[handle.index()],
            None => proc::inline::Origin {
                call: None,
                expression: Some(handle),
            },
        }
    }

    /// The name of the function a call site's expressions come from (the
    /// entry point's for its own).
    fn function_of(&self, call: Option<usize>) -> Option<&'a str> {
        match (call, self.inlined) {
            (Some(call), Some(inlined)) => self.shader.module.functions
                [inlined.calls[call].function]
                .name
                .as_deref(),
            _ => Some(self.entry_name),
        }
    }

    fn call_path(&self, call: Option<usize>) -> Vec<super::calls::CallStep> {
        match (call, &self.paths) {
            (Some(call), Some(paths)) => paths.steps[call].clone(),
            _ => Vec::new(),
        }
    }
}

/// One node per source span and call path: where the front end made
/// several expressions for one piece of source (a load and its pointer, a
/// splat and its scalar), the last one, which consumes the others, stands
/// for it. Loads of local variables have no span of their own; they are
/// spanned by the variable's name where it is read. Keyed by (call path
/// group, start, end): 0 for the entry point's own, call + 1 for a
/// helper's.
fn nodes_by_span(
    module: &naga::Module,
    (function, info): (&naga::Function, &naga::valid::FunctionInfo),
    source: &str,
    origins: &Origins,
) -> BTreeMap<(usize, usize, usize), Handle<Expression>> {
    let load_spans = super::spans::local_loads(function, source, &|load| {
        let call = origins.of(load).call;
        (call.map_or(0, |c| c + 1), origins.function_of(call))
    });
    let mut by_span = BTreeMap::new();
    for (handle, _) in function.expressions.iter() {
        let origin = origins.of(handle);
        if origin.expression.is_none() {
            // Made by the inliner: no source of its own.
            continue;
        }
        let span = function.expressions.get_span(handle).to_range();
        let Some(range) = span.or_else(|| load_spans.get(&handle).cloned()) else {
            continue;
        };
        if range.is_empty()
            || range.end > source.len()
            || !source.is_char_boundary(range.start)
            || !source.is_char_boundary(range.end)
        {
            continue;
        }
        let range = call_extent(source, range);
        if !is_value(info[handle].ty.inner_with(&module.types)) {
            continue;
        }
        let group = origin.call.map_or(0, |c| c + 1);
        by_span.insert((group, range.start, range.end), handle);
    }
    by_span
}

/// Node ids: the occurrence number counts equal texts in source order,
/// per call path; a helper's nodes hash their call path with the entry
/// point's name, so the entry point's own ids are as they were. Ask in
/// the order of [`nodes_by_span`]'s keys.
struct NodeNames<'a> {
    source: &'a str,
    /// The hash key of each call path group ([`node_keys`]).
    keys: &'a [String],
    seen: HashMap<u64, usize>,
    group: usize,
    hasher: id::PrefixHasher<'a>,
}

/// The hash key of each call path group: the entry point's name for its
/// own nodes, with each call path's key for a helper's.
fn node_keys(entry_name: &str, paths: Option<&super::calls::Paths>) -> Vec<String> {
    std::iter::once(entry_name.to_string())
        .chain(
            paths
                .iter()
                .flat_map(|p| p.keys.iter())
                .map(|key| format!("{entry_name}\0{key}")),
        )
        .collect()
}

impl<'a> NodeNames<'a> {
    fn new(source: &'a str, keys: &'a [String]) -> Self {
        NodeNames {
            source,
            keys,
            seen: HashMap::new(),
            group: usize::MAX,
            hasher: id::PrefixHasher::new(source, &keys[0]),
        }
    }

    fn id(&mut self, group: usize, start: usize, end: usize) -> String {
        if group != self.group {
            self.hasher = id::PrefixHasher::new(self.source, &self.keys[group]);
            self.group = group;
        }
        // Spans come in order of start, then end: nested prefixes hash on.
        let state = self.hasher.node(start, end);
        let occurrence = self.seen.entry(state).or_insert(0);
        let id = id::PrefixHasher::id(state, *occurrence);
        *occurrence += 1;
        id
    }
}

/// Highest P/T first; a node that goes stale as the camera, the light or
/// time moves comes after object-space nodes within `PER_FRAME_PENALTY`
/// of its P/T.
fn rank(candidates: &mut [Candidate]) {
    let rank = |c: &Candidate| {
        c.ratio
            - if c.depends_on.is_empty() {
                0.0
            } else {
                PER_FRAME_PENALTY
            }
    };
    candidates.sort_by(|a, b| {
        rank(b)
            .total_cmp(&rank(a))
            .then(a.node.range.start.cmp(&b.node.range.start))
    });
}

/// Line and column of byte offsets, as [`crate::diagnostic::SourceFile::line_col`]
/// gives them, from one index of the lines: asking the file for every node
/// scans it from the start each time.
struct LineIndex<'a> {
    text: &'a str,
    /// Byte offset of each line's start, and whether the line is ASCII
    /// (its columns are then byte counts).
    lines: Vec<(usize, bool)>,
}

impl<'a> LineIndex<'a> {
    fn new(text: &'a str) -> Self {
        let mut lines = Vec::new();
        let mut start = 0;
        for line in text.split_inclusive('\n') {
            lines.push((start, line.is_ascii()));
            start += line.len();
        }
        if lines.is_empty() || text.ends_with('\n') {
            lines.push((start, true));
        }
        LineIndex { text, lines }
    }

    fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.lines.partition_point(|&(start, _)| start <= offset);
        let (start, ascii) = self.lines[line.saturating_sub(1)];
        let col = if ascii {
            offset - start
        } else {
            self.text[start..offset].chars().count()
        };
        (line.max(1), col + 1)
    }
}

/// Why `expr` cannot be cached, or its number of components if it can.
fn classify(
    module: &naga::Module,
    info: &naga::valid::FunctionInfo,
    layout: &proc::FunctionLayout,
    facts: &SliceFacts,
    expr: Handle<Expression>,
) -> Result<u32, (RejectReason, String)> {
    if let Some(at) = layout.placement(expr) {
        if at.loop_depth > 0 {
            return Err((
                RejectReason::InLoop,
                format!(
                    "evaluated inside {} loop{}: it has no single value per pixel to keep",
                    at.loop_depth,
                    if at.loop_depth > 1 { "s" } else { "" }
                ),
            ));
        }
    }

    let ty = info[expr].ty.inner_with(&module.types);
    let components = match *ty {
        TypeInner::Scalar(naga::Scalar::F32) => 1,
        TypeInner::Vector {
            size,
            scalar: naga::Scalar::F32,
        } => size as u32,
        _ => {
            return Err((
                RejectReason::NotStorable,
                format!(
                    "a `{}` does not fit a colour texel without loss; only f32 and vectors of f32 can be cached",
                    type_name(&module.types, ty)
                ),
            ))
        }
    };

    if !facts.has(SliceFacts::COMPUTES) {
        return Err((
            RejectReason::Trivial,
            "only reads or rearranges existing values: there is no computation to save".into(),
        ));
    }
    if !facts.has(SliceFacts::READS_ARGUMENT) {
        return Err((
            RejectReason::UniformOnly,
            "depends only on uniforms, constants and overrides: it is the same for every pixel"
                .into(),
        ));
    }
    if let Some(what) = facts.screen_space_read() {
        return Err((
            RejectReason::ScreenSpace,
            format!(
                "reads the pixel's own place on the screen ({what}): reprojected, a cached value would land on other pixels and carry this one's; what belongs to the surface point (its depth, `front_facing`) stays cacheable"
            ),
        ));
    }
    Ok(components)
}

/// How much P/T a node that depends on per-frame inputs gives up in the
/// ranking: it goes stale under exactly the motion scenes declare.
const PER_FRAME_PENALTY: f64 = 0.02;

/// What a candidate's classification and notes need to know of its
/// slice. Each is true of the slice when it is of one of its expressions,
/// so the facts of every slice are merged up the expression graph at once
/// ([`super::graph::ExprGraph::summaries`]).
#[derive(Clone, Debug)]
struct SliceFacts {
    flags: u8,
    /// For each of [`PER_FRAME_INPUTS`], the lowest arena index of an
    /// expression of the slice that reads it (`u32::MAX`: none), so the
    /// inputs are listed in the order the function reads them.
    first_read: [u32; 3],
}

impl SliceFacts {
    /// Some expression computes: arithmetic, a texture access, a call.
    const COMPUTES: u8 = 1;
    /// Some expression reads an argument: a per-fragment input.
    const READS_ARGUMENT: u8 = 2;
    /// Some expression takes a derivative, explicit or implicit.
    const DERIVATIVES: u8 = 4;
    const SAMPLE_INDEX: u8 = 8;
    const SAMPLE_MASK: u8 = 16;
    /// Some expression reads `@builtin(position)`'s x or y.
    const POSITION_XY: u8 = 32;

    const NONE: SliceFacts = SliceFacts {
        flags: 0,
        first_read: [u32::MAX; 3],
    };

    fn has(&self, flag: u8) -> bool {
        self.flags & flag != 0
    }

    /// The facts of expression `i` alone.
    fn of_expression(
        module: &naga::Module,
        function: &naga::Function,
        exprs: &[&Expression],
        varyings: &HashMap<u32, Vec<usize>>,
        i: usize,
    ) -> SliceFacts {
        let expr = exprs[i];
        let mut facts = SliceFacts::NONE;
        let mut set = |flag: u8, when: bool| {
            if when {
                facts.flags |= flag;
            }
        };
        set(SliceFacts::COMPUTES, !proc::kind(expr).moves_data_only());
        set(
            SliceFacts::READS_ARGUMENT,
            matches!(expr, Expression::FunctionArgument(_)),
        );
        set(SliceFacts::DERIVATIVES, proc::takes_derivatives(expr));
        let carried = carried_builtin(module, function, exprs, expr);
        set(
            SliceFacts::SAMPLE_INDEX,
            carried == Some(naga::BuiltIn::SampleIndex),
        );
        set(
            SliceFacts::SAMPLE_MASK,
            carried == Some(naga::BuiltIn::SampleMask),
        );
        // A read of the position that takes more than its z or w alone.
        let reads_position = proc::operands(expr).iter().any(|&o| {
            matches!(
                carried_builtin(module, function, exprs, exprs[o.index()]),
                Some(naga::BuiltIn::Position { .. })
            )
        });
        set(SliceFacts::POSITION_XY, reads_position && !depth_only(expr));
        let mut slots = loaded_buffer_member(module, exprs, expr)
            .map(|name| per_frame_slots(&name))
            .unwrap_or_default();
        // An input the vertex stage computed from per-frame values.
        if let Some(location) = input_location(module, function, exprs, expr) {
            slots.extend(varyings.get(&location).into_iter().flatten());
        }
        for slot in slots {
            facts.first_read[slot] = i as u32;
        }
        facts
    }

    /// The per-frame inputs the slice reads, in the order it first reads
    /// them.
    fn per_frame_inputs(&self) -> Vec<String> {
        let mut read: Vec<(u32, &str)> = PER_FRAME_INPUTS
            .iter()
            .zip(self.first_read)
            .filter(|&(_, first)| first != u32::MAX)
            .map(|(&(input, _), first)| (first, input))
            .collect();
        read.sort();
        read.into_iter()
            .map(|(_, input)| input.to_string())
            .collect()
    }

    /// What in the slice reads where the pixel is on the screen rather
    /// than what surface point it shows: `@builtin(position)`'s x or y
    /// (its z and w, the depth, belong to the point), `sample_index`,
    /// `sample_mask`.
    fn screen_space_read(&self) -> Option<&'static str> {
        if self.has(SliceFacts::SAMPLE_INDEX) {
            Some("`@builtin(sample_index)`")
        } else if self.has(SliceFacts::SAMPLE_MASK) {
            Some("`@builtin(sample_mask)`")
        } else if self.has(SliceFacts::POSITION_XY) {
            Some("`@builtin(position).xy`")
        } else {
            None
        }
    }
}

impl Default for SliceFacts {
    fn default() -> Self {
        SliceFacts::NONE
    }
}

impl super::graph::SliceFact for SliceFacts {
    fn merge(&mut self, other: &Self) {
        self.flags |= other.flags;
        for (mine, &theirs) in self.first_read.iter_mut().zip(&other.first_read) {
            *mine = (*mine).min(theirs);
        }
    }
}

/// The binding of the fragment input `expr` reads: an argument's, or a
/// member's of a struct argument.
fn input_binding<'a>(
    module: &'a naga::Module,
    function: &'a naga::Function,
    exprs: &[&Expression],
    expr: &Expression,
) -> Option<&'a naga::Binding> {
    match *expr {
        Expression::FunctionArgument(i) => function.arguments.get(i as usize)?.binding.as_ref(),
        Expression::AccessIndex { base, index } => {
            let Expression::FunctionArgument(i) = *exprs[base.index()] else {
                return None;
            };
            match module.types[function.arguments.get(i as usize)?.ty].inner {
                TypeInner::Struct { ref members, .. } => {
                    members.get(index as usize)?.binding.as_ref()
                }
                _ => None,
            }
        }
        _ => None,
    }
}

/// The location of the fragment input `expr` reads.
fn input_location(
    module: &naga::Module,
    function: &naga::Function,
    exprs: &[&Expression],
    expr: &Expression,
) -> Option<u32> {
    match *input_binding(module, function, exprs, expr)? {
        naga::Binding::Location { location, .. } => Some(location),
        _ => None,
    }
}

/// The builtin an argument (or a struct member of one) carries, for the
/// expression that reads it.
fn carried_builtin(
    module: &naga::Module,
    function: &naga::Function,
    exprs: &[&Expression],
    expr: &Expression,
) -> Option<naga::BuiltIn> {
    match *input_binding(module, function, exprs, expr)? {
        naga::Binding::BuiltIn(builtin) => Some(builtin),
        _ => None,
    }
}

/// Whether `expr` takes only the z or w of the vector it reads (of the
/// position: the depth, which belongs to the surface point).
fn depth_only(expr: &Expression) -> bool {
    match *expr {
        Expression::AccessIndex { index, .. } => index >= 2,
        Expression::Swizzle {
            size, ref pattern, ..
        } => pattern[..size as usize]
            .iter()
            .all(|c| matches!(c, naga::SwizzleComponent::Z | naga::SwizzleComponent::W)),
        _ => false,
    }
}

/// Whether a type is a value (not a pointer or a resource handle).
fn is_value(ty: &TypeInner) -> bool {
    !matches!(
        ty,
        TypeInner::Pointer { .. }
            | TypeInner::ValuePointer { .. }
            | TypeInner::Image { .. }
            | TypeInner::Sampler { .. }
            | TypeInner::AccelerationStructure { .. }
            | TypeInner::RayQuery { .. }
            | TypeInner::BindingArray { .. }
    )
}

/// The WGSL spelling of a type, for reports.
pub(crate) fn type_name(types: &naga::UniqueArena<naga::Type>, ty: &TypeInner) -> String {
    let scalar = |s: naga::Scalar| -> String {
        match (s.kind, s.width) {
            (naga::ScalarKind::Float, 4) => "f32".into(),
            (naga::ScalarKind::Float, 2) => "f16".into(),
            (naga::ScalarKind::Float, 8) => "f64".into(),
            (naga::ScalarKind::Sint, 4) => "i32".into(),
            (naga::ScalarKind::Uint, 4) => "u32".into(),
            (naga::ScalarKind::Sint, 8) => "i64".into(),
            (naga::ScalarKind::Uint, 8) => "u64".into(),
            (naga::ScalarKind::Bool, _) => "bool".into(),
            (kind, width) => format!("{kind:?}{}", width * 8).to_lowercase(),
        }
    };
    match *ty {
        TypeInner::Scalar(s) => scalar(s),
        TypeInner::Vector { size, scalar: s } => format!("vec{}<{}>", size as u8, scalar(s)),
        TypeInner::Matrix {
            columns,
            rows,
            scalar: s,
        } => format!("mat{}x{}<{}>", columns as u8, rows as u8, scalar(s)),
        TypeInner::Atomic(s) => format!("atomic<{}>", scalar(s)),
        TypeInner::Array { base, .. } => {
            format!("array<{}>", type_name(types, &types[base].inner))
        }
        TypeInner::Struct { .. } => {
            let name = types
                .iter()
                .find(|(_, t)| &t.inner == ty)
                .and_then(|(_, t)| t.name.clone());
            format!("struct {}", name.unwrap_or_default())
                .trim_end()
                .to_string()
        }
        _ => "other".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::LineIndex;
    use crate::diagnostic::SourceFile;

    #[test]
    fn the_line_index_agrees_with_the_file() {
        let text = "fn a() {}\n\n  let é = 1.0;\r\nlast";
        let file = SourceFile::new("t.wgsl", text);
        let index = LineIndex::new(text);
        for offset in 0..=text.len() + 2 {
            assert_eq!(
                index.line_col(offset),
                file.line_col(offset),
                "offset {offset}"
            );
        }
        let ends_with_newline = "a\nb\n";
        let file = SourceFile::new("t.wgsl", ends_with_newline);
        let index = LineIndex::new(ends_with_newline);
        for offset in 0..=ends_with_newline.len() {
            assert_eq!(
                index.line_col(offset),
                file.line_col(offset),
                "offset {offset}"
            );
        }
    }
}

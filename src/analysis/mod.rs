//! IR → candidates: which values of the fragment entry point could be
//! cached, and what each would save.
//!
//! A *node* is one expression of the fragment entry point's naga IR that has
//! a span in the source. Each node is either a **candidate** — a value that
//! could be stored in a colour texture and reused next frame — or
//! **rejected** with a reason:
//!
//! * `in-loop`: evaluated inside a loop, so it has no single value per pixel;
//! * `not-storable`: not `f32` or a vector of up to four `f32` (integers,
//!   booleans, matrices and structs do not fit one colour texel without loss);
//! * `trivial`: only moves data (a literal, an argument, a bare load, a
//!   swizzle or a constructor of such), so there is nothing to save;
//! * `uniform-only`: depends on no per-fragment input — only uniforms,
//!   constants and overrides — so it is the same for every pixel;
//! * `screen-space`: reads where the pixel is on the screen
//!   (`@builtin(position).xy`, `sample_index`, `sample_mask`: dithers,
//!   screen-space patterns), so reprojected onto another pixel it would be
//!   wrong; the position's depth and `front_facing` belong to the surface
//!   point and stay cacheable.
//!
//! Pointers and resource handles (textures, samplers) are not values and are
//! not listed at all. Expressions inside helper functions are nodes per call
//! site (`calls`): the entry point is analysed with its helpers inlined,
//! and each node says which function's source it is in and the calls that
//! lead there. A call of a helper is a node too: the value it returns there.
//!
//! For each candidate the `graph` gives its backward slice (what the payload
//! needs) and the remainder (what the rest of the entry point still needs
//! when the node is read from the cache). The [cost model](crate::cost)
//! turns them into P (the slice's cost), T (the entry point's cost), P/T, and
//! the *overlap*: the cost of the part of the slice the remainder also needs,
//! which a multi-pass variant pays twice (seed 002, fig. 7).

#![warn(missing_docs)]

pub(crate) mod calls;
mod candidates;
mod entry;
pub(crate) mod graph;
mod id;
mod per_frame;
pub(crate) mod range;
mod spans;
pub mod text;
mod varyings;

use std::ops::Range;

use naga::{Expression, Handle};
use serde::Serialize;

pub use crate::proc::name_words;
pub use calls::CallStep;
pub(crate) use candidates::type_name;
pub use candidates::RejectReason;
pub use entry::{fragment_entry, stage_name};
pub use id::node_id;

use crate::cost::{CostModel, Weights};
use crate::diagnostic::{Diagnostic, Error};
use crate::front::Shader;

/// What to analyse and how to cost it.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The fragment entry point; `None` picks the only one.
    pub entry: Option<String>,
    /// The cost model's weights.
    pub weights: Weights,
}

/// The result of analysing one fragment entry point. Serialises to the JSON
/// format documented in `docs/analysis-json.md`.
#[derive(Clone, Debug, Serialize)]
#[non_exhaustive]
pub struct Analysis {
    /// The shader's path as given.
    pub shader: String,
    /// The fragment entry point analysed.
    pub entry: String,
    /// T: the estimated cost of the whole entry point.
    pub total_cost: f64,
    /// Candidates, highest estimated P/T first.
    pub candidates: Vec<Candidate>,
    /// Rejected nodes in source order.
    pub rejected: Vec<Rejected>,
    /// Index of the entry point in the module.
    #[serde(skip)]
    pub entry_index: usize,
    /// The entry point as analysed, with its helpers inlined; `None` when
    /// it calls none (it is then the shader's own).
    #[serde(skip)]
    pub analysed: Option<std::sync::Arc<calls::Analysed>>,
}

/// Where a node is in the source: 1-based `[line, column]` of its first
/// character and of the position just past its last (columns count
/// characters).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct SourceSpan {
    /// Line and column (1-based) of the first character.
    pub start: [usize; 2],
    /// Line and column (1-based) just past the last character.
    pub end: [usize; 2],
}

/// What every node carries.
#[derive(Clone, Debug, Serialize)]
#[non_exhaustive]
pub struct Node {
    /// The stable id (`n` and eight hex digits) that `--nodes` and the build
    /// API take.
    pub id: String,
    /// Where the node is in the source.
    pub span: SourceSpan,
    /// The source text the node covers.
    pub text: String,
    /// Its WGSL type, e.g. `vec3<f32>`.
    #[serde(rename = "type")]
    pub ty: String,
    /// The function whose source the span is in: the entry point's own
    /// name for its expressions, a helper's for the helper's.
    pub function: String,
    /// The calls from the entry point down to `function`, outermost
    /// first; empty for the entry point's own expressions.
    pub call_path: Vec<CallStep>,
    /// The expression in `function`'s arena.
    #[serde(skip)]
    pub expression: Handle<Expression>,
    /// The expression in the analysed entry point's arena
    /// ([`Analysis::analysed`], or the shader's own entry point).
    #[serde(skip)]
    pub analysed: Handle<Expression>,
    /// Byte range of `text` in the source.
    #[serde(skip)]
    pub range: Range<usize>,
}

/// A value that could be cached.
#[derive(Clone, Debug, Serialize)]
#[non_exhaustive]
pub struct Candidate {
    #[serde(flatten)]
    /// The node.
    pub node: Node,
    /// 1 to 4 `f32` components.
    pub components: u32,
    /// P: the estimated cost of computing the node (its backward slice).
    pub cost: f64,
    /// P/T.
    pub ratio: f64,
    /// Estimated cost of the slice's sub-expressions the rest of the entry
    /// point also uses.
    pub overlap: f64,
    /// Whether the slice takes implicit derivatives (`textureSample`,
    /// `dpdx`...), which a rewrite must keep in uniform control flow.
    pub derivatives: bool,
    /// The per-frame inputs the slice reads, by the names of the uniform
    /// and storage members it loads (`time`, `camera`, `light`): a cached
    /// value goes stale as they change, so such nodes rank after
    /// object-space ones of similar P/T.
    pub depends_on: Vec<String>,
    /// Bounds of the node's value from interval arithmetic (`range`);
    /// `null` ends are unbounded.
    pub range: [Option<f64>; 2],
    /// Whether the value provably fits an rgba16float cache (|x| < 65504).
    /// When it may not, the three-pass rewrite keeps its cache in
    /// rgba32float (docs/rewrite.md).
    pub fits_f16: bool,
}

/// A node that cannot be cached, and why.
#[derive(Clone, Debug, Serialize)]
#[non_exhaustive]
pub struct Rejected {
    #[serde(flatten)]
    /// The node.
    pub node: Node,
    /// Why it is not a candidate.
    pub reason: RejectReason,
    /// A sentence saying why, for people.
    pub detail: String,
}

/// Analyses the fragment entry point of a parsed and validated shader.
/// Analyses every fragment entry point of `shader` in turn, in the
/// module's order, or only the one `options.entry` names (or the only one
/// there is): what `analyze`, `rewrite` and `profile` take when no
/// `--entry` narrows them.
pub fn analyze_entries(shader: &Shader, options: &Options) -> Result<Vec<Analysis>, Error> {
    entry::fragment_entries_to_take(shader, options.entry.as_deref())
        .into_iter()
        .map(|entry| {
            analyze(
                shader,
                &Options {
                    entry,
                    ..options.clone()
                },
            )
        })
        .collect()
}

/// Analyses the fragment entry point `options` names (or the module's only
/// one): every candidate with its estimated P/T, and the values rejected with
/// why. Errors name an entry point that does not exist or is ambiguous.
pub fn analyze(shader: &Shader, options: &Options) -> Result<Analysis, Error> {
    let entry_index = fragment_entry(shader, options.entry.as_deref())?;
    let analysed = calls::inline_all(shader, entry_index)?;
    let (module, info) = match &analysed {
        Some(a) => (&a.module, &a.info),
        None => (&shader.module, &shader.info),
    };
    let model = CostModel::new(module, info, options.weights.clone());
    Ok(candidates::find(
        shader,
        analysed.clone(),
        entry_index,
        &model,
    ))
}

/// Bounds of nodes' values. The entry point's own nodes are bounded on
/// the shader as written, where the range analysis follows each call into
/// its helper and narrows the result by splitting an argument's range; a
/// helper's nodes on the entry point with its helpers inlined.
pub(crate) struct NodeRanges<'a> {
    own: range::EntryRanges<'a>,
    inlined: Option<range::EntryRanges<'a>>,
}

impl<'a> NodeRanges<'a> {
    pub(crate) fn new(
        shader: &'a Shader,
        analysed: Option<&'a calls::Analysed>,
        entry_index: usize,
        uniforms: &'a range::UniformBounds,
    ) -> Self {
        NodeRanges {
            own: range::EntryRanges::with_uniforms(
                &shader.module,
                &shader.info,
                entry_index,
                uniforms,
            ),
            inlined: analysed.map(|a| {
                range::EntryRanges::with_uniforms(&a.module, &a.info, entry_index, uniforms)
            }),
        }
    }

    pub(crate) fn of(&mut self, node: &Node) -> range::Interval {
        match (&mut self.inlined, node.call_path.is_empty()) {
            (Some(inlined), false) => inlined.of(node.analysed),
            _ => self.own.of(node.expression),
        }
    }
}

/// Which nodes a command works on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Nodes {
    /// Every candidate.
    All,
    /// The N candidates with the highest estimated P/T.
    Top(usize),
    /// These ids (from `shadecache analyze`).
    Ids(Vec<String>),
}

impl Analysis {
    /// Checks that the vertex entry point `wanted` (or, without a name, the
    /// one inferred) draws with the analysed fragment entry point: a
    /// wrong `--vertex-entry` is one error before any node is rewritten,
    /// not the same refusal for every node and variant.
    pub fn check_vertex_entry(&self, shader: &Shader, wanted: &str) -> Result<(), Error> {
        crate::proc::vertex_entry(&shader.module, self.entry_index, Some(wanted))
            .map(|_| ())
            .map_err(|reason| Error::plain(Diagnostic::error(format!("--vertex-entry: {reason}"))))
    }

    /// Bounds every candidate's value again, knowing the uniform values
    /// `uniforms` take (the profiler knows them from its scene): a node
    /// that reads a uniform is unbounded to the shader alone, and may fit
    /// f16 for the values a scene gives it.
    pub fn bound_uniforms(&mut self, shader: &Shader, uniforms: &range::UniformBounds) {
        let mut ranges =
            NodeRanges::new(shader, self.analysed.as_deref(), self.entry_index, uniforms);
        for candidate in &mut self.candidates {
            let range = ranges.of(&candidate.node);
            candidate.range = range.ends();
            candidate.fits_f16 = range.fits_f16();
        }
    }

    /// The candidates `nodes` names. An id that names a rejected node is an
    /// error pointing at it with the reason; an unknown id is an error
    /// listing the candidates.
    pub fn select(
        &self,
        file: &std::sync::Arc<crate::diagnostic::SourceFile>,
        nodes: &Nodes,
    ) -> Result<Vec<&Candidate>, Error> {
        use crate::diagnostic::Diagnostic;
        let chosen: Vec<&Candidate> = match nodes {
            Nodes::All => self.candidates.iter().collect(),
            Nodes::Top(n) => self.candidates.iter().take(*n).collect(),
            Nodes::Ids(ids) => ids
                .iter()
                .map(|id| {
                    if let Some(candidate) = self.candidate(id) {
                        return Ok(candidate);
                    }
                    if let Some(rejected) = self.rejected(id) {
                        return Err(Error::in_file(
                            file.clone(),
                            Diagnostic::error(format!(
                                "node {id} cannot be cached: {}",
                                rejected.detail
                            ))
                            .with_label(rejected.node.range.clone(), rejected.reason.as_str()),
                        ));
                    }
                    let known: Vec<&str> = self
                        .candidates
                        .iter()
                        .take(8)
                        .map(|c| c.node.id.as_str())
                        .collect();
                    Err(Error::plain(
                        Diagnostic::error(format!("unknown node id `{id}` in `{}`", file.path))
                            .with_note(format!(
                                "candidates, highest P/T first: {}{}",
                                known.join(", "),
                                if self.candidates.len() > known.len() {
                                    ", ..."
                                } else {
                                    ""
                                }
                            ))
                            .with_note("`shadecache analyze` lists every node and its id"),
                    ))
                })
                .collect::<Result<_, _>>()?,
        };
        if chosen.is_empty() {
            return Err(Error::in_file(
                file.clone(),
                Diagnostic::error(format!("`{}` has no cache candidates", file.path)),
            ));
        }
        Ok(chosen)
    }

    /// Looks a node up by id among the candidates.
    pub fn candidate(&self, id: &str) -> Option<&Candidate> {
        self.candidates.iter().find(|c| c.node.id == id)
    }

    /// Looks a node up by id among the rejected nodes.
    pub fn rejected(&self, id: &str) -> Option<&Rejected> {
        self.rejected.iter().find(|r| r.node.id == id)
    }
}

//! The static cost model: an estimate of what each expression, helper
//! function and whole entry point costs to evaluate, in abstract units.
//!
//! The analysis ranks cache candidates by P/T, the estimated cost of the
//! payload's backward slice (P) over the cost of the whole fragment entry
//! point (T). Seed 002 (§4.1, Fig. 8) sorts AST nodes by P/T measured on
//! its GPU; this static estimate is ours. Measured costs replace these
//! estimates once the profiler has run the shader; until then the model only
//! has to order candidates sensibly.
//!
//! * [`Weights`] is data: one number per class of operation (arithmetic,
//!   division, simple math, transcendental, texture sample, texture load,
//!   derivative, memory load...), plus the trip count assumed for loops whose
//!   bounds are not constant. It serialises to JSON so a calibration can be
//!   stored and loaded; `docs/cost-model.md` lists every weight.
//! * [`CostModel`] maps each naga expression to a class and a count of scalar
//!   operations, multiplies by the weight, costs helper calls by their
//!   bodies (recursively, memoised) and loops by their trip counts.

#![warn(missing_docs)]

mod model;
mod weights;

pub use model::CostModel;
pub use weights::Weights;

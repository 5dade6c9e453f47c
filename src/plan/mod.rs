//! plans: the data that says how to run a variant, as the `shadecache-plan`
//! crate defines it (serde only, so applications read plans without the
//! toolchain). [`crate::rewrite::plan`] builds them; the runtime, the
//! back ends and the profiler read them. `docs/plan-json.md` documents the
//! format.

pub use shadecache_plan::*;

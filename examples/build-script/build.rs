//! Rewrites the marble shader into its three-pass cache variant at build
//! time. The node id comes from `shadecache analyze`: the turbulence sum.

fn main() -> Result<(), shadecache::build::BuildError> {
    shadecache::build::Build::new()
        .shader("../../corpus/noise_marble.wgsl")
        .node("nb0c12cc4")
        .variant(shadecache::rewrite::Variant::ThreePass)
        .variant(shadecache::rewrite::Variant::OnePass)
        .run()?;
    Ok(())
}

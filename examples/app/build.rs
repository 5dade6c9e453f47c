//! Rewrites the planet's shader into its three-pass cache variant and its
//! lowres variant (the albedo shaded at a sixteenth of the pixels and
//! upsampled, seed 001) at build time. The node is the marble albedo,
//! `marble(in.surface)`: its id comes from `shadecache analyze
//! shaders/planet.wgsl` (candidate #5; the lit colour above it changes with
//! the sun, the albedo only with the surface).

fn main() -> Result<(), shadecache::build::BuildError> {
    shadecache::build::Build::new()
        .shader("shaders/planet.wgsl")
        .node("nf50106c5")
        .variant(shadecache::rewrite::Variant::ThreePass)
        .variant(shadecache::rewrite::Variant::Lowres)
        .options(shadecache::rewrite::Options {
            refresh_period: 16,
            color_format: shadecache::plan::TextureFormat::Rgba16Float,
            ..shadecache::rewrite::Options::default()
        })
        .run()?;
    Ok(())
}

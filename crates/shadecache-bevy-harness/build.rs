//! Rewrites the scene's materials into their cache variants at build
//! time ([`lava_build`] says how): a game's build script.

#[path = "lava_build.rs"]
mod lava_build;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    lava_build::game_build(std::path::Path::new("assets")).run()?;
    Ok(())
}

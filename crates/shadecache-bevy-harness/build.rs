//! Rewrites the game's materials into their one-pass cache variants at
//! build time ([`lava_build`] says how).

#[path = "lava_build.rs"]
mod lava_build;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    lava_build::game_build().run()?;
    Ok(())
}

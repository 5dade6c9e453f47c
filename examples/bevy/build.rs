//! Rewrites the lava material into its one-pass cache variant at build
//! time ([`lava_build`] says how).

#[path = "lava_build.rs"]
mod lava_build;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    lava_build::lava_build().run()?;
    Ok(())
}

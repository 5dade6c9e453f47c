//! `shadecache scene init`: write the default scene for a shader, every
//! value spelled out, for the user to edit.

use std::path::PathBuf;

use shadecache::diagnostic::{Color, Error};
use shadecache::scene::init;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub command: SceneCommand,
}

#[derive(Debug, clap::Subcommand)]
pub enum SceneCommand {
    /// Write the default scene for a shader to stdout: its roles inferred from the IR, every other binding a neutral value.
    Init(InitArgs),
}

#[derive(Debug, clap::Args)]
pub struct InitArgs {
    /// The WGSL shader the scene is for.
    pub shader: PathBuf,

    #[command(flatten)]
    pub stages: super::StageArgs,
}

pub fn exec(args: Args, _color: Color) -> Result<(), Error> {
    match args.command {
        SceneCommand::Init(args) => {
            let shader = args.stages.load(&args.shader)?;
            let init = init::for_shader(
                &shader,
                args.stages.entry.as_deref(),
                args.stages.vertex_entry.as_deref(),
            )?;
            super::write_stdout(&init.text)
        }
    }
}

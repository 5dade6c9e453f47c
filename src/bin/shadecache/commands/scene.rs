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

    /// The fragment entry point, when the shader has several.
    #[arg(long, value_name = "NAME")]
    pub entry: Option<String>,

    /// The vertex entry point that draws with it, when the shader has
    /// several and the pairing cannot be inferred.
    #[arg(long, value_name = "NAME")]
    pub vertex_entry: Option<String>,

    /// The module with the vertex stage, for a fragment-only shader
    /// (engines keep the stages in separate files); resources both bind at
    /// one (group, binding) are one.
    #[arg(long, value_name = "FILE.wgsl")]
    pub vertex: Option<PathBuf>,

    #[command(flatten)]
    pub compose: super::ComposeArgs,
}

pub fn exec(args: Args, _color: Color) -> Result<(), Error> {
    match args.command {
        SceneCommand::Init(args) => {
            let shader = super::load_shader(
                &args.shader,
                &args.compose,
                args.vertex.as_deref(),
                args.vertex_entry.as_deref(),
            )?;
            let init =
                init::for_shader(&shader, args.entry.as_deref(), args.vertex_entry.as_deref())?;
            super::write_stdout(&init.text)
        }
    }
}

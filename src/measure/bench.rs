//! What every run of a measured comparison draws with: the device, the
//! scene's inputs, the size and the culling. The reference (the user's
//! shader as written) and each configuration are runners made here, so
//! they draw the same scene alike.

use std::collections::HashMap;

use super::fail;
use super::inputs::SceneInputs;
use crate::back;
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::plan::Plan;
use crate::runtime::{Gpu, PipelineOptions, RunOptions, Runner};

/// Makes runners that draw the run's scene.
pub(crate) struct Bench<'a> {
    pub gpu: &'a Gpu,
    pub inputs: &'a SceneInputs<'a>,
    pub size: [u32; 2],
    pub cull_back_faces: bool,
}

impl Bench<'_> {
    /// A runner for a plan and its shaders by file name; with `classify`,
    /// it draws the cache's decisions after each frame.
    pub fn runner(
        &self,
        plan: &Plan,
        sources: &HashMap<String, String>,
        classify: bool,
    ) -> Result<Runner, String> {
        self.runner_with(
            plan,
            sources,
            RunOptions {
                classify,
                ..RunOptions::default()
            },
        )
    }

    /// A runner as [`Bench::runner`], with `options` (the scene's culling
    /// whatever they say).
    pub fn runner_with(
        &self,
        plan: &Plan,
        sources: &HashMap<String, String>,
        options: RunOptions,
    ) -> Result<Runner, String> {
        if super::watch::watching() {
            let what = match plan.variant {
                crate::plan::Variant::Reference => "the reference".to_string(),
                variant => format!("{variant} of node {} `{}`", plan.node.id, plan.node.text),
            };
            super::watch::tell(super::watch::Step::Building(&what));
        }
        let runner = Runner::new(
            self.gpu,
            plan,
            |name| sources.get(name).cloned(),
            &self.inputs.meshes,
            &self.inputs.textures,
            (self.size[0], self.size[1]),
            RunOptions {
                pipelines: PipelineOptions {
                    cull_back_faces: self.cull_back_faces,
                    ..options.pipelines
                },
                ..options
            },
        );
        super::watch::tell(super::watch::Step::Idle);
        runner
    }
}

/// The reference: the user's source as written (a module given its
pub(crate) fn reference(bench: &Bench, shader: &Shader, plan: &Plan) -> Result<Runner, Error> {
    let text = match shader.vertex_file {
        None => shader.file.text.clone(),
        Some(_) => back::wgsl_text(&shader.module, &shader.info).map_err(fail)?,
    };
    let sources = HashMap::from([("reference.wgsl".to_string(), text)]);
    bench
        .runner(plan, &sources, false)
        .map_err(|err| fail(format!("the reference does not run: {err}")))
}

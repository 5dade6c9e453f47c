//! The methods that rasterise the geometry again at each B-frame's time
//! and fetch its shading from the I-frames: scene-assisted (Yang et al.
//! 2011 §4, closest-on-miss or shade-on-miss) and single-direction
//! reverse reprojection (with or without its misses reshaded), all one
//! pass of the instrumented shader in a [`SceneMode`], drawn through the
//! host with the I-frames bound in the group after the twins'.
//!
//! [`SceneRun`] is that pass; image-based's exact correspondences and
//! half-velocity's moving objects draw with it too.

use crate::diagnostic::Error;
use crate::interpolate::bframe::{BFrameParams, IFrameTextures};
use crate::interpolate::frame_method::{FrameMethod, Setup};
use crate::interpolate::frames::{Drawn, Frames, IntervalAt};
use crate::interpolate::iframe::SceneMode;
use crate::interpolate::thin::FrameDepth;
use crate::interpolate::Method;
use crate::measure::clock::{timed, Clock};
use crate::measure::fail;
use crate::runtime::{Gpu, RunOptions, Runner};

/// One method's pass of the geometry at B-frame times: its runner and
/// what it binds of the I-frames.
pub(super) struct SceneRun {
    pub method: Method,
    pub mode: SceneMode,
    pub runner: Runner,
    params: wgpu::Buffer,
    sampler: wgpu::Sampler,
}

impl SceneRun {
    /// `method`'s pass in `mode`; the reason when the instrumented shader
    /// cannot have it, or its I-frames' bind group is past the adapter's.
    pub fn new(setup: &Setup, method: Method, mode: SceneMode) -> Result<SceneRun, String> {
        let gpu = setup.bench.gpu;
        let group = setup.instrumented.scene_group;
        let granted = gpu.device.limits().max_bind_groups;
        if group >= granted {
            return Err(format!(
                "its I-frame textures take bind group {group} (the shader and the twins use the groups before), and the adapter grants {granted}"
            ));
        }
        let plan = setup.instrumented.scene_plan(mode)?;
        let runner = setup.bench.runner_with(
            &plan,
            setup.sources,
            RunOptions {
                external_group: Some(group),
                ..RunOptions::default()
            },
        )?;
        Ok(SceneRun {
            method,
            mode,
            runner,
            params: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scene-assisted parameters"),
                size: 32,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            sampler: crate::interpolate::gpu::linear_clamp(&gpu.device),
        })
    }

    /// Its pass's target at output `location`.
    pub fn output(&self, location: u32) -> Result<&wgpu::Texture, String> {
        self.runner.color_at(location).ok_or_else(|| {
            format!("internal error: the scene-assisted pass has no target at {location}")
        })
    }

    /// Binds the two I-frames and this B-frame's parameters
    /// (`SceneParams` of `shaders/bframe_scene.wgsl`).
    pub fn bind(
        &mut self,
        gpu: &Gpu,
        (earlier, later): &(IFrameTextures, IFrameTextures),
        params: &BFrameParams,
    ) -> Result<(), Error> {
        let mode = self.mode as u32;
        let words = [
            params.viewport[0].to_bits(),
            params.viewport[1].to_bits(),
            params.alpha.to_bits(),
            params.depth_epsilon.to_bits(),
            params.far_depth.to_bits(),
            mode,
            0,
            0,
        ];
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        gpu.queue.write_buffer(&self.params, 0, &bytes);
        let (color, depth) = (
            crate::interpolate::gpu::view,
            crate::interpolate::gpu::depth_view,
        );
        let views = [
            color(earlier.color),
            depth(earlier.depth),
            color(later.color),
            depth(later.depth),
        ];
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: self.params.as_entire_binding(),
        }];
        entries.extend(
            views
                .iter()
                .zip(1..)
                .map(|(view, binding)| wgpu::BindGroupEntry {
                    binding,
                    resource: wgpu::BindingResource::TextureView(view),
                }),
        );
        entries.push(wgpu::BindGroupEntry {
            binding: 5,
            resource: wgpu::BindingResource::Sampler(&self.sampler),
        });
        self.runner
            .bind_external(gpu, "I-frames", &entries)
            .map_err(fail)?;
        Ok(())
    }
}

/// A scene-assisted or reverse-reprojection method ([`Method::scene_mode`]).
pub(super) struct SceneAssisted {
    pub run: SceneRun,
}

impl FrameMethod for SceneAssisted {
    fn method(&self) -> Method {
        self.run.method
    }

    /// Scene-assisted blends both I-frames; reverse reprojection reads
    /// the earlier one alone.
    fn reads_later_frame(&self) -> bool {
        matches!(
            self.run.mode,
            SceneMode::ClosestOnMiss | SceneMode::ShadeOnMiss
        )
    }

    fn draw<'s>(
        &'s mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &'s IntervalAt,
        k: u32,
        params: &BFrameParams,
    ) -> Result<Drawn<'s>, Error> {
        let run = &mut self.run;
        run.bind(frames.gpu, at.textures, params)?;
        let inputs = frames.twinned_inputs(at.inputs_of, [at.start + k, at.start, at.end])?;
        let (time, _, _) = timed(clock, &mut run.runner, &inputs, "bframe").map_err(fail)?;
        let [color, decision] = frames.instrumented.scene_locations;
        let run = &self.run;
        Ok(Drawn {
            time,
            color: run.output(color).map_err(fail)?,
            depth: FrameDepth::Buffer(run.runner.depth()),
            decisions: Some(run.output(decision).map_err(fail)?),
        })
    }
}

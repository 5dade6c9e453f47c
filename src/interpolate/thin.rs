//! Objects drawn at every displayed frame (seed 000 §6, Fig. 4(d)).
//!
//! Thin, fast geometry (the windmill's blades) defeats every warping
//! method: the blades cover different pixels in each I-frame, so the
//! search finds no correspondence (double misses behind them) and a
//! blend leaves ghosts. The paper's answer is to interpolate only what
//! lies behind them and render the blades conventionally in every
//! displayed frame, "using the same Z-buffer bridging approach": the
//! interpolated frame's depth goes into the Z-buffer the blades are
//! depth-tested against. A scene marks such objects `every_frame`; then
//! - the I-frames (and every pass that draws the geometry at a B-frame's
//!   time) leave them out;
//! - each displayed frame, interpolated or not, is bridged into the
//!   targets of the original shader's pass (`shaders/bridge.wgsl`: its
//!   colour, and its depth: the depth buffer of the pass that drew it, or
//!   for image-based the depth its search chose, as the paper's), which
//!   then draws the objects at that frame's time, depth-tested.
//!
//! Methods that keep no depth of their own frame (sample-and-hold,
//! linear blending, half-velocity, the morphs) are bridged with I-frame
//! 0's: what the frame shows is I-frame 0's surfaces moved, so an object
//! drawn every frame can be hidden where a surface moved in front of it
//! (the report's note says so). The bridge and the draw count in each
//! displayed frame's time.

use super::setup::RunPlan;
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::bench::{self, Bench};
use crate::measure::fail;
use crate::runtime::{DrawShare, FrameInputs, FramePart, Gpu, Runner};

/// The bridging shader.
const BRIDGE_WGSL: &str = include_str!("../../shaders/bridge.wgsl");

/// What an interpolated frame's depth is.
#[derive(Clone, Copy, Debug)]
pub enum FrameDepth<'a> {
    /// A depth buffer (an I-frame's, a geometry pass's).
    Buffer(&'a wgpu::Texture),
    /// The depth image-based's search chose per pixel (r32float).
    Chosen(&'a wgpu::Texture),
}

/// The objects drawn at every displayed frame, and how they are drawn.
#[derive(Debug)]
pub struct ThinObjects {
    /// The original shader, drawing them into a bridged frame.
    runner: Runner,
    /// The bridging pipelines and layouts: from a depth buffer, from a
    /// chosen depth.
    bridge: [(wgpu::RenderPipeline, wgpu::BindGroupLayout); 2],
}

impl ThinObjects {
    /// The objects drawn at every displayed frame (`every_frame`) and their
    /// drawing, with a note saying how they are shown; `None` where the
    /// scene has none.
    pub(super) fn of_scene(
        bench: &Bench,
        shader: &Shader,
        plan: &RunPlan,
        every_frame: &[bool],
        notes: &mut Vec<String>,
    ) -> Result<Option<ThinObjects>, Error> {
        let count = every_frame.iter().filter(|t| **t).count();
        if count == 0 {
            return Ok(None);
        }
        let runner = bench::reference(bench, shader, &plan.reference)?;
        notes.push(format!(
            "{count} object(s) drawn at every displayed frame (`every_frame`) and left out of the I-frames, depth-tested into each method's frames through the Z-buffer bridge (Yang et al. 2011 Fig. 4(d)): against the depth the frame was drawn with (image-based: the depth its search chose), or I-frame 0's for the methods that keep none (sample-and-hold, linear blending, half-velocity, the morphs); the bridge and the draw count in every displayed frame's time"
        ));
        if count == every_frame.len() {
            notes.push(
                "every object is drawn at every displayed frame: the I-frames hold only the background, so there is nothing to interpolate and every method shows the reference's frames; mark the objects the methods should interpolate without `every_frame`".into(),
            );
        }
        Ok(Some(ThinObjects::new(bench.gpu, runner).map_err(fail)?))
    }

    /// `runner` draws with the original shader.
    pub fn new(gpu: &Gpu, runner: Runner) -> Result<ThinObjects, String> {
        let device = &gpu.device;
        let depth_format = runner.depth().format();
        let color_format = runner
            .color()
            .ok_or("the original pass draws no colour")?
            .format();
        let bridge = crate::runtime::validated(device, || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("shaders/bridge.wgsl"),
                source: wgpu::ShaderSource::Wgsl(BRIDGE_WGSL.into()),
            });
            let texture = super::gpu::texture_entry;
            let color = texture(0, wgpu::TextureSampleType::Float { filterable: false });
            [
                (
                    "fs_bridge_depth",
                    texture(1, wgpu::TextureSampleType::Depth),
                ),
                (
                    "fs_bridge_chosen",
                    texture(2, wgpu::TextureSampleType::Float { filterable: false }),
                ),
            ]
            .map(|(entry, depth)| {
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("bridge"),
                    entries: &[color, depth],
                });
                let pipeline_layout =
                    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("bridge"),
                        bind_group_layouts: &[Some(&layout)],
                        immediate_size: 0,
                    });
                let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("bridge"),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_fullscreen"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        targets: &[Some(color_format.into())],
                    }),
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: depth_format,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Always),
                        stencil: wgpu::StencilState::default(),
                        bias: wgpu::DepthBiasState::default(),
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    multiview_mask: None,
                    cache: None,
                });
                (pipeline, layout)
            })
        })
        .map_err(|err| format!("the Z-buffer bridge does not build: {err}"))?;
        Ok(ThinObjects { runner, bridge })
    }

    /// Draws the objects `every_frame` marks, at the time of `inputs` (a
    /// displayed frame's, every object in it), over the frame `color`
    /// whose depth is `depth`; the result is [`ThinObjects::color`].
    pub fn composite(
        &mut self,
        gpu: &Gpu,
        (inputs, every_frame): (&FrameInputs, &[bool]),
        (color, depth): (&wgpu::Texture, FrameDepth),
        mut profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) -> Result<(), String> {
        use super::gpu::reborrow;
        // A frame that draws nothing yet, to bridge into and draw more in.
        let empty = FramePart::default();
        self.runner
            .frame_part(gpu, inputs, Some(&empty), reborrow(&mut profiler))?;
        self.bridge(gpu, (color, depth), reborrow(&mut profiler))?;
        let draws: Vec<DrawShare> = self
            .runner
            .whole_draws(inputs)
            .into_iter()
            .filter(|d| every_frame.get(d.object).copied().unwrap_or(false))
            .collect();
        let part = FramePart { draws, more: true };
        self.runner.frame_part(gpu, inputs, Some(&part), profiler)
    }

    /// The last composited frame.
    pub fn color(&self) -> Result<&wgpu::Texture, String> {
        self.runner
            .color()
            .ok_or_else(|| "the original pass draws no colour".to_string())
    }

    /// Copies `color` and `depth` into the runner's last frame's colour
    /// and depth targets.
    fn bridge(
        &self,
        gpu: &Gpu,
        (color, depth): (&wgpu::Texture, FrameDepth),
        mut profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) -> Result<(), String> {
        let view = super::gpu::view;
        let (index, depth_view, binding) = match depth {
            FrameDepth::Buffer(texture) => (0, super::gpu::depth_view(texture), 1),
            FrameDepth::Chosen(texture) => (1, view(texture), 2),
        };
        let (pipeline, layout) = &self.bridge[index];
        let color_view = view(color);
        let bind_group = crate::runtime::validated(&gpu.device, || {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("bridge"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&color_view),
                    },
                    wgpu::BindGroupEntry {
                        binding,
                        resource: wgpu::BindingResource::TextureView(&depth_view),
                    },
                ],
            })
        })?;
        // The bridge writes every pixel's colour and depth (the depth test
        // off): what the targets held before does not matter.
        let target = view(self.color()?);
        let depth_target = self
            .runner
            .depth()
            .create_view(&wgpu::TextureViewDescriptor::default());
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        super::gpu::timed_pass(
            &mut encoder,
            &mut profiler,
            "bridge",
            (
                std::slice::from_ref(&target),
                Some((&depth_target, wgpu::StoreOp::Store)),
            ),
            |pass| {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.draw(0..3, 0..1);
            },
        );
        gpu.queue.submit([encoder.finish()]);
        Ok(())
    }
}

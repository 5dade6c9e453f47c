//! The B-frame passes: one fullscreen pass per B-frame, reading two
//! I-frames' colour, depth and flows (`shaders/bframe.wgsl`), writing the
//! B-frame's colour and what each pixel decided.

use std::collections::HashMap;

pub use super::gpu::COLOR_FORMAT;
use super::gpu::{
    depth_view, fullscreen_pass, fullscreen_pipeline, linear_clamp, parameters_sampler_and,
    texture_entry, view,
};
use super::Method;
use crate::runtime::Gpu;

/// The B-frame shaders.
pub const BFRAME_WGSL: &str = include_str!("../../shaders/bframe.wgsl");

/// The decisions' format: one `u32` code per pixel (`shaders/bframe.wgsl`'s
/// `SAME_SURFACE`...).
pub const DECISION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The image-based pass's offsets (p − q into each I-frame), read by the
/// next B-frame's latest-frame initialisation.
pub const OFFSETS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The depth the image-based pass chose, beside its offsets, and the
/// direction it took (1 forward, 0 backward).
pub const CHOSEN_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// I-frame 0 with its moving objects wiped out, at half its width and
/// height, and what became of each pixel in alpha (`fs_inpaint`).
pub const REMOVED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// What each B-frame pixel decided, as the shader codes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Decision {
    /// Both searches found the same surface (or, for half-velocity, the
    /// later frame's velocity was used).
    SameSurface = 0,
    /// Two surfaces were found and the nearer taken (half-velocity: the
    /// earlier frame's velocity extrapolated a tail).
    NearerSurface = 1,
    /// Only one search converged (half-velocity: the direction test held
    /// the pixel).
    OneDirection = 2,
    /// Neither converged where an I-frame has geometry.
    DoubleMiss = 3,
    /// No geometry in either I-frame at the pixel, and nothing found.
    Background = 4,
}

/// The knobs of a B-frame pass, as `BFrameParams` lays them out.
#[derive(Clone, Copy, Debug)]
pub struct BFrameParams {
    pub viewport: [f32; 2],
    pub alpha: f32,
    pub screen_epsilon: f32,
    pub depth_epsilon: f32,
    pub far_depth: f32,
    pub dual_init: bool,
    /// Of two converged starts the smaller residual wins, as seed 000
    /// states it (else the nearer surface).
    pub smaller_residual: bool,
    pub velocity_merge: bool,
    /// Half-velocity's moving objects are bound ([`BFrames::render`] sets
    /// it).
    pub moving_objects: bool,
    pub min_cosine: f32,
    /// α' of the image-based B-frame before this one in the interval:
    /// latest-frame initialisation from its offsets (000 eqs. 18–19).
    /// `None` for the first B-frame of an interval, or to turn it off.
    pub previous_alpha: Option<f32>,
    /// Character removal's neighbour distance, in pixels.
    pub inpaint_delta: u32,
}

impl BFrameParams {
    /// The uniform's bytes (`BFrameParams` in `shaders/bframe.wgsl`: ten
    /// 4-byte fields in order, padded to 48).
    fn bytes(&self) -> Vec<u8> {
        let words: [u32; 12] = [
            self.viewport[0].to_bits(),
            self.viewport[1].to_bits(),
            self.alpha.to_bits(),
            self.screen_epsilon.to_bits(),
            self.depth_epsilon.to_bits(),
            self.far_depth.to_bits(),
            u32::from(self.dual_init)
                | (u32::from(self.velocity_merge) << 1)
                | (u32::from(self.moving_objects) << 2)
                | (u32::from(self.smaller_residual) << 3),
            self.min_cosine.to_bits(),
            self.previous_alpha.unwrap_or(0.0).to_bits(),
            self.inpaint_delta,
            0,
            0,
        ];
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }
}

/// One I-frame as the B-frame passes read it.
#[derive(Clone, Copy, Debug)]
pub struct IFrameTextures<'a> {
    pub color: &'a wgpu::Texture,
    pub depth: &'a wgpu::Texture,
    /// Its flow to the I-frame before it.
    pub flow_previous: &'a wgpu::Texture,
    /// Its flow to the I-frame after it.
    pub flow_next: &'a wgpu::Texture,
}

/// The B-frame pipelines of the methods asked for, and their targets.
#[derive(Debug)]
pub struct BFrames {
    pipelines: HashMap<Method, wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    sampler: wgpu::Sampler,
    color: wgpu::Texture,
    decisions: wgpu::Texture,
    /// The image-based pass's offsets and chosen depths, in turn written
    /// and read by consecutive B-frames ([`BFrames::render`] alternates).
    offsets: [(wgpu::Texture, wgpu::Texture); 2],
    /// Which of `offsets` the next image-based B-frame writes.
    turn: std::cell::Cell<usize>,
    /// Whether the image-based pass writes `offsets` (with latest-frame
    /// initialisation, or for the depths it chose).
    latest: bool,
    /// Character removal (`fs_inpaint`): its pipeline and layout, and the
    /// two targets its passes write in turn.
    inpaint: [wgpu::RenderPipeline; 2],
    inpaint_layout: wgpu::BindGroupLayout,
    removed: [wgpu::Texture; 2],
    /// Which of `removed` holds the last removal's result.
    removed_last: std::cell::Cell<usize>,
    /// Zeros, bound where half-velocity has no moving objects and for the
    /// other methods.
    no_moving: wgpu::Texture,
}

/// Half-velocity's moving objects for one B-frame: the moving-objects
/// pass at its time, and I-frame 0 with them wiped out
/// ([`BFrames::remove_moving_objects`]).
#[derive(Clone, Copy, Debug)]
pub struct MovingObjects<'a> {
    pub now: &'a wgpu::Texture,
    pub removed: &'a wgpu::Texture,
}

/// A method's colour targets: the B-frame and its decisions; for
/// image-based with latest-frame initialisation also its offsets and
/// chosen depths.
fn targets(method: Method, latest: bool) -> Vec<Option<wgpu::ColorTargetState>> {
    let mut formats = vec![COLOR_FORMAT, DECISION_FORMAT];
    if method == Method::ImageBased && latest {
        formats.extend([OFFSETS_FORMAT, CHOSEN_DEPTH_FORMAT]);
    }
    formats.into_iter().map(|f| Some(f.into())).collect()
}

/// The B-frame passes' bindings: the parameters, the sampler, and both
/// I-frames' colour, depth, flows and the image-based search's textures.
fn layout_entries() -> [wgpu::BindGroupLayoutEntry; 13] {
    let float = wgpu::TextureSampleType::Float { filterable: true };
    [
        wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        },
        wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        },
        texture_entry(2, float),
        texture_entry(3, wgpu::TextureSampleType::Depth),
        texture_entry(4, float),
        texture_entry(5, float),
        texture_entry(6, float),
        texture_entry(7, wgpu::TextureSampleType::Depth),
        texture_entry(8, float),
        texture_entry(9, float),
        texture_entry(10, wgpu::TextureSampleType::Float { filterable: false }),
        texture_entry(11, float),
        texture_entry(12, float),
    ]
}

impl BFrames {
    /// Builds the passes of `methods` (those that are B-frame passes) for
    /// frames of `size`, the image-based search taking `iterations` steps,
    /// with latest-frame initialisation over taps `latest_radius` pixels
    /// away when it is given.
    pub fn new(
        gpu: &Gpu,
        size: (u32, u32),
        methods: &[Method],
        (iterations, latest_radius): (u32, Option<u32>),
    ) -> Result<BFrames, String> {
        BFrames::writing_depth(gpu, size, methods, (iterations, latest_radius), false)
    }

    /// [`BFrames::new`], with image-based writing its offsets and chosen
    /// depths whatever the initialisation when `chosen_depth` holds
    /// ([`BFrames::chosen_depth`]: what objects drawn every frame are
    /// depth-tested against).
    pub fn writing_depth(
        gpu: &Gpu,
        size: (u32, u32),
        methods: &[Method],
        (iterations, latest_radius): (u32, Option<u32>),
        chosen_depth: bool,
    ) -> Result<BFrames, String> {
        let latest = latest_radius.is_some() || chosen_depth;
        let latest_init = latest_radius.is_some();
        let device = &gpu.device;
        let float = wgpu::TextureSampleType::Float { filterable: true };
        let entries = layout_entries();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("B-frame"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("B-frame"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let (pipelines, inpaint_layout, inpaint) = crate::runtime::validated(device, || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("shaders/bframe.wgsl"),
                source: wgpu::ShaderSource::Wgsl(BFRAME_WGSL.into()),
            });
            let mut pipelines = HashMap::new();
            for &method in methods {
                let Some(entry) = method.fragment_entry() else {
                    continue;
                };
                let latest_pass = method == Method::ImageBased && latest;
                let entry = if latest_pass {
                    "fs_image_based_latest"
                } else {
                    entry
                };
                let iterations = ("search_iterations", f64::from(iterations));
                let constants: Vec<(&str, f64)> = if latest_pass {
                    vec![
                        iterations,
                        ("latest_init", f64::from(u8::from(latest_init))),
                        ("latest_radius", f64::from(latest_radius.unwrap_or(1))),
                    ]
                } else {
                    vec![iterations]
                };
                let made = fullscreen_pipeline(
                    device,
                    &module,
                    method.name(),
                    &pipeline_layout,
                    entry,
                    &constants,
                    &targets(method, latest),
                );
                pipelines.insert(method, made);
            }
            let inpaint_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("character removal"),
                    entries: &[
                        entries[0],
                        texture_entry(14, float),
                        texture_entry(15, float),
                    ],
                });
            let inpaint_pipeline_layout =
                device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("character removal"),
                    bind_group_layouts: &[Some(&inpaint_layout)],
                    immediate_size: 0,
                });
            let inpaint = ["fs_inpaint_first", "fs_inpaint"].map(|entry| {
                fullscreen_pipeline(
                    device,
                    &module,
                    "character removal",
                    &inpaint_pipeline_layout,
                    entry,
                    &[],
                    &[Some(REMOVED_FORMAT.into())],
                )
            });
            (pipelines, inpaint_layout, inpaint)
        })
        .map_err(|err| format!("the B-frame passes do not build: {err}"))?;
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("B-frame parameters"),
            size: 48,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = linear_clamp(device);
        let target =
            |label, format| shadecache_host::toolchain::render_target(device, label, size, format);
        Ok(BFrames {
            pipelines,
            layout,
            params,
            sampler,
            color: target("B-frame", COLOR_FORMAT),
            decisions: target("B-frame decisions", DECISION_FORMAT),
            offsets: [0, 1].map(|_| {
                (
                    target("image-based offsets", OFFSETS_FORMAT),
                    target("image-based chosen depths", CHOSEN_DEPTH_FORMAT),
                )
            }),
            turn: std::cell::Cell::new(0),
            latest,
            inpaint,
            inpaint_layout,
            removed: [0, 1].map(|_| {
                shadecache_host::toolchain::render_target(
                    device,
                    "I-frame 0, moving objects removed",
                    (size.0.div_ceil(2), size.1.div_ceil(2)),
                    REMOVED_FORMAT,
                )
            }),
            removed_last: std::cell::Cell::new(0),
            no_moving: target("no moving objects", REMOVED_FORMAT),
        })
    }

    /// The last B-frame's colour.
    pub fn color(&self) -> &wgpu::Texture {
        &self.color
    }

    /// The offsets (p − q into I-frame 0, p − q into I-frame 1) the last
    /// image-based B-frame wrote, when made with latest-frame
    /// initialisation.
    pub fn written_offsets(&self) -> &wgpu::Texture {
        &self.offsets[1 - self.turn.get()].0
    }

    /// The depth the last image-based B-frame chose at each pixel (I-frame
    /// 0's or 1's depth of the surface it shows), when made writing it.
    pub fn chosen_depth(&self) -> &wgpu::Texture {
        &self.offsets[1 - self.turn.get()].1
    }

    /// The last B-frame's decisions ([`Decision`] per pixel).
    pub fn decisions(&self) -> &wgpu::Texture {
        &self.decisions
    }

    /// I-frame 0 with its moving objects wiped out (003 slides 39–46):
    /// `passes` passes of `fs_inpaint` from its colour and a flow of it
    /// (w = 2 on a moving object), each timed as `<label>/character
    /// removal` when a profiler is given. The result is what
    /// [`BFrames::removed`] returns.
    pub fn remove_moving_objects(
        &self,
        gpu: &Gpu,
        (color, mask): (&wgpu::Texture, &wgpu::Texture),
        params: &BFrameParams,
        passes: u32,
        mut profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) {
        gpu.queue.write_buffer(&self.params, 0, &params.bytes());
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        for pass in 0..passes {
            let out = (pass % 2) as usize;
            let (color, mask) = if pass == 0 {
                (view(color), view(mask))
            } else {
                let previous = view(&self.removed[1 - out]);
                (previous.clone(), previous)
            };
            let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("character removal"),
                layout: &self.inpaint_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: self.params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 14,
                        resource: wgpu::BindingResource::TextureView(&color),
                    },
                    wgpu::BindGroupEntry {
                        binding: 15,
                        resource: wgpu::BindingResource::TextureView(&mask),
                    },
                ],
            });
            fullscreen_pass(
                &mut encoder,
                &mut profiler,
                "character removal",
                (&self.inpaint[usize::from(pass > 0)], &bind_group),
                &[view(&self.removed[out])],
            );
            self.removed_last.set(out);
        }
        gpu.queue.submit([encoder.finish()]);
    }

    /// I-frame 0 with its moving objects wiped out, as the last
    /// [`BFrames::remove_moving_objects`] left it.
    pub fn removed(&self) -> &wgpu::Texture {
        &self.removed[self.removed_last.get()]
    }

    /// Renders the B-frame of `method` between `earlier` and `later`, its
    /// pass timed as `<label>/<method>` when a profiler is given;
    /// half-velocity with `moving` objects, when the scene has some.
    pub fn render(
        &self,
        gpu: &Gpu,
        method: Method,
        (earlier, later): (&IFrameTextures, &IFrameTextures),
        params: &BFrameParams,
        moving: Option<MovingObjects>,
        profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) -> Result<(), String> {
        let pipeline = self
            .pipelines
            .get(&method)
            .ok_or_else(|| format!("{} has no B-frame pass", method.name()))?;
        let params = BFrameParams {
            moving_objects: moving.is_some(),
            ..*params
        };
        gpu.queue.write_buffer(&self.params, 0, &params.bytes());
        let depth = depth_view;
        let (write, read) = (self.turn.get(), 1 - self.turn.get());
        let views = [
            view(earlier.color),
            depth(earlier.depth),
            view(earlier.flow_previous),
            view(earlier.flow_next),
            view(later.color),
            depth(later.depth),
            view(later.flow_previous),
            view(&self.offsets[read].0),
            view(&self.offsets[read].1),
            view(moving.map_or(&self.no_moving, |m| m.now)),
            view(moving.map_or(&self.no_moving, |m| m.removed)),
        ];
        let entries = parameters_sampler_and(&self.params, &self.sampler, &views);
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("B-frame"),
            layout: &self.layout,
            entries: &entries,
        });
        let mut outputs = vec![view(&self.color), view(&self.decisions)];
        if method == Method::ImageBased && self.latest {
            outputs.extend([view(&self.offsets[write].0), view(&self.offsets[write].1)]);
            self.turn.set(read);
        }
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let mut profiler = profiler;
        fullscreen_pass(
            &mut encoder,
            &mut profiler,
            method.name(),
            (pipeline, &bind_group),
            &outputs,
        );
        gpu.queue.submit([encoder.finish()]);
        Ok(())
    }
}

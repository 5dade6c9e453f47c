//! Morph-and-blur extrapolation (seed 004): the frames after a rendered
//! frame, warped forward from it (`shaders/morph.wgsl`).
//!
//! Once per rendered frame ([`Morph::prepare`]): the argmax pyramid that
//! snaps the grid to the motion's discontinuities, the low-pass pyramid,
//! and the rendered frame as displayed (its high frequencies amplified so
//! that the group of N displayed frames integrates to it). Per in-between
//! frame ([`Morph::render`]): one draw of the grid, its vertices moved by
//! s_k = k/N of the motion, depth-tested with the rendered frame's depth;
//! the fragment warps the colour and the low-pass together and assembles
//! the in-between frame from them, so an extrapolated frame costs one
//! pass.
//!
//! Two orders of blur ([`BlurOrder`]). The paper blurs each morphed
//! frame (a pyramid per in-between frame: [`BlurOrder::Paper`]). By
//! default the rendered frame's low-pass is warped with it instead, by
//! the same grid ([`BlurOrder::WarpBlurred`]), which costs no pyramid per
//! in-between frame. The two agree only where the motion is uniform over
//! the blur's footprint: near a motion edge the paper's blur of the
//! morphed frame mixes both sides as they are in that frame, ours as they
//! were in the rendered one. Tiles that stretch or fold are blended to the
//! low-pass by their distortion in both.

use super::gpu::{
    depth_view, fullscreen_pass, linear_clamp, parameters_sampler_and, timed_pass, view,
};
use crate::runtime::Gpu;

/// The morph's shaders.
pub const MORPH_WGSL: &str = include_str!("../../shaders/morph.wgsl");

/// The in-between frames' and the displayed rendered frame's format: the
/// measured colour format.
const COLOR_FORMAT: wgpu::TextureFormat = super::gpu::COLOR_FORMAT;

/// The argmax pyramid's texels (`fs_flow_edges`).
const ARGMAX_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The morph's depth buffer.
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// What a run fixes of the passes: the frame's size, the grid's spacing
/// (a power of two that divides the frame) and the low-pass's pyramid
/// level.
#[derive(Clone, Copy, Debug)]
pub struct MorphSetup {
    pub size: [u32; 2],
    pub grid: u32,
    pub blur_level: u32,
    /// Blur only where the motion is fast enough (the speed is
    /// [`MorphParams::blur_min_speed`]): a gate by speed, not the paper's
    /// selective blur (by luminance and range).
    pub blur_gated_by_speed: bool,
    /// Whether each morphed frame is blurred (the paper's order) or the
    /// rendered frame's low-pass warped with it.
    pub blur_order: BlurOrder,
}

/// Where the blur of an in-between frame comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BlurOrder {
    /// The rendered frame blurred once and warped by each in-between
    /// frame's grid with the sharp frame: one pass an in-between frame.
    #[default]
    WarpBlurred,
    /// Seed 004's: each in-between frame morphed sharp, then blurred
    /// (the pyramid again), then assembled: R6, R7, R8 of the design
    /// note.
    Paper,
}

/// The knobs of one pass, as `MorphParams` of `shaders/morph.wgsl` lays
/// them out.
#[derive(Clone, Copy, Debug)]
pub struct MorphParams {
    /// s_k = k/N.
    pub step: f32,
    /// N.
    pub frames: f32,
    pub gamma: f32,
    /// The flow bound is the motion to the next rendered frame (the
    /// twin's); else the flow to the previous one, extrapolated.
    pub exact_motion: bool,
    /// Degrees per second of eye motion per pixel of flow.
    pub speed_scale: f32,
    /// f(v)'s ramp, deg/s.
    pub tracking: [f32; 2],
    /// The speed gate's least speed, deg/s ([`MorphSetup::blur_gated_by_speed`]).
    pub blur_min_speed: Option<f32>,
    /// The distortion's ramp to full blur.
    pub distortion: [f32; 2],
    pub snap_threshold: f32,
    pub far_depth: f32,
    /// Blur and compensate (else the warp alone).
    pub blur: bool,
    pub snap: bool,
}

impl MorphParams {
    fn bytes(&self, setup: &MorphSetup) -> Vec<u8> {
        let floats = [
            setup.size[0] as f32,
            setup.size[1] as f32,
            self.step,
            self.frames,
            self.gamma,
            if self.exact_motion { 1.0 } else { -1.0 },
            self.speed_scale,
            self.tracking[0],
            self.tracking[1],
            self.blur_min_speed.unwrap_or(0.0),
            self.distortion[0],
            self.distortion[1],
            self.snap_threshold,
            self.far_depth,
        ];
        let mut words: Vec<u32> = floats.iter().map(|f| f.to_bits()).collect();
        words.push(setup.grid);
        words.push(u32::from(self.snap));
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }
}

/// The rendered frame a morph reads: its colour, depth and the flow that
/// gives the motion.
#[derive(Clone, Copy, Debug)]
pub struct Source<'a> {
    pub color: &'a wgpu::Texture,
    pub depth: &'a wgpu::Texture,
    pub flow: &'a wgpu::Texture,
}

/// What a pass reads of the pyramids.
#[derive(Clone, Copy, Default)]
struct Reads<'a> {
    /// The argmax per grid vertex.
    snap: bool,
    /// The low-pass level.
    low: bool,
    /// The low-pass at full resolution.
    low_full: bool,
    /// What a halving pass halves.
    argmax_source: Option<&'a wgpu::Texture>,
    blur_source: Option<&'a wgpu::Texture>,
    /// The morphed frame's distortion (the paper's order).
    distortion: bool,
}

/// The morph's pipelines and targets.
#[derive(Debug)]
pub struct Morph {
    setup: MorphSetup,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    sampler: wgpu::Sampler,
    flow_edges: wgpu::RenderPipeline,
    argmax_reduce: wgpu::RenderPipeline,
    blur_down: wgpu::RenderPipeline,
    compensate: wgpu::RenderPipeline,
    /// The grid with blur and compensation, and the warp alone.
    morph: wgpu::RenderPipeline,
    warp: wgpu::RenderPipeline,
    /// Two triangles per tile of the grid's vertices.
    indices: wgpu::Buffer,
    index_count: u32,
    /// The argmax pyramid, from the shifted full frame down to one texel
    /// per grid vertex.
    argmax: Vec<wgpu::Texture>,
    /// The low-pass pyramid, levels 1 to `blur_level`.
    pyramid: Vec<wgpu::Texture>,
    displayed: wgpu::Texture,
    /// The low-pass at full resolution, as the displayed frame was
    /// compensated against it.
    low_full: wgpu::Texture,
    color: wgpu::Texture,
    depth: wgpu::Texture,
    /// With the paper's order, its passes and the morphed frame.
    paper: Option<PaperOrder>,
    /// Bound to what a pass does not read (1×1).
    no_argmax: wgpu::Texture,
    no_color: wgpu::Texture,
}

/// The passes and targets of [`BlurOrder::Paper`]: the grid writing the
/// morphed frame sharp with its distortion, and the assembly from it and
/// its low-pass.
#[derive(Debug)]
struct PaperOrder {
    warp: wgpu::RenderPipeline,
    assemble: wgpu::RenderPipeline,
    /// M_k.
    warped: wgpu::Texture,
    /// D_k.
    distortion: wgpu::Texture,
}

fn entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty,
        count: None,
    }
}

fn texture(sample_type: wgpu::TextureSampleType) -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    }
}

/// The morph's bindings, one layout for every pass.
fn layout_entries() -> [wgpu::BindGroupLayoutEntry; 11] {
    let both = wgpu::ShaderStages::VERTEX_FRAGMENT;
    let float = wgpu::TextureSampleType::Float { filterable: true };
    let uint = wgpu::TextureSampleType::Uint;
    [
        entry(
            0,
            both,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        ),
        entry(
            1,
            both,
            wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        ),
        entry(2, both, texture(float)),
        entry(3, both, texture(wgpu::TextureSampleType::Depth)),
        entry(4, both, texture(float)),
        entry(5, both, texture(uint)),
        entry(6, both, texture(float)),
        entry(7, both, texture(uint)),
        entry(8, both, texture(float)),
        entry(9, both, texture(float)),
        entry(10, both, texture(float)),
    ]
}

/// The argmax pyramid's level sizes: level 0 is the frame shifted by
/// grid/2 and padded to whole neighbourhoods, ((W/g + 1)·g) × ((H/g + 1)·g);
/// each level halves it, down to (W/g + 1) × (H/g + 1).
pub fn argmax_sizes(size: [u32; 2], grid: u32) -> Vec<(u32, u32)> {
    let vertices = (size[0] / grid + 1, size[1] / grid + 1);
    let levels = grid.trailing_zeros();
    (0..=levels)
        .map(|l| {
            let scale = grid >> l;
            (vertices.0 * scale, vertices.1 * scale)
        })
        .collect()
}

impl Morph {
    /// Builds the passes for `setup`.
    pub fn new(gpu: &Gpu, setup: MorphSetup) -> Result<Morph, String> {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("morph"),
            entries: &layout_entries(),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("morph"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let gated = (
            "blur_gated_by_speed",
            f64::from(u8::from(setup.blur_gated_by_speed)),
        );
        let ((flow_edges, argmax_reduce, blur_down, compensate), morph, warp, paper) =
            crate::runtime::validated(device, || {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("shaders/morph.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(MORPH_WGSL.into()),
                });
                let fullscreen = |entry: &str, formats: &[wgpu::TextureFormat]| {
                    let targets: Vec<_> = formats.iter().map(|f| Some((*f).into())).collect();
                    super::gpu::fullscreen_pipeline(
                        device,
                        &module,
                        entry,
                        &pipeline_layout,
                        entry,
                        &[gated],
                        &targets,
                    )
                };
                let grid = |blur: bool, fragment: &str, targets: &[wgpu::TextureFormat]| {
                    let constants = [("blur", f64::from(u8::from(blur))), gated];
                    let pipeline = (&module, &pipeline_layout, fragment);
                    grid_pipeline(device, pipeline, &constants, targets)
                };
                let paper = (setup.blur_order == BlurOrder::Paper).then(|| {
                    (
                        grid(true, "fs_warp_and_distortion", &[COLOR_FORMAT; 2]),
                        fullscreen("fs_assemble", &[COLOR_FORMAT]),
                    )
                });
                (
                    (
                        fullscreen("fs_flow_edges", &[ARGMAX_FORMAT]),
                        fullscreen("fs_argmax_reduce", &[ARGMAX_FORMAT]),
                        fullscreen("fs_blur_down", &[COLOR_FORMAT]),
                        fullscreen("fs_compensate", &[COLOR_FORMAT, COLOR_FORMAT]),
                    ),
                    grid(true, "fs_morph", &[COLOR_FORMAT]),
                    grid(false, "fs_morph", &[COLOR_FORMAT]),
                    paper,
                )
            })
            .map_err(|err| format!("the morph passes do not build: {err}"))?;
        let target = |label, size, format| {
            shadecache_host::toolchain::render_target(device, label, size, format)
        };
        let [width, height] = setup.size;
        let argmax = argmax_sizes(setup.size, setup.grid)
            .into_iter()
            .map(|size| target("morph argmax pyramid", size, ARGMAX_FORMAT))
            .collect();
        let pyramid = (1..=setup.blur_level)
            .map(|l| {
                let size = (width.div_ceil(1 << l), height.div_ceil(1 << l));
                target("morph low-pass pyramid", size, COLOR_FORMAT)
            })
            .collect();
        let indices = grid_indices(setup.size, setup.grid);
        let index_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("morph grid"),
            size: (indices.len() * 4) as u64,
            usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        gpu.queue.write_buffer(&index_buffer, 0, &bytes);
        Ok(Morph {
            setup,
            layout,
            indices: index_buffer,
            index_count: indices.len() as u32,
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("morph parameters"),
                size: 64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            sampler: linear_clamp(device),
            flow_edges,
            argmax_reduce,
            blur_down,
            compensate,
            morph,
            warp,
            argmax,
            pyramid,
            displayed: target("morph displayed frame", (width, height), COLOR_FORMAT),
            low_full: target("morph low-pass", (width, height), COLOR_FORMAT),
            color: target("morph in-between frame", (width, height), COLOR_FORMAT),
            depth: target("morph depth", (width, height), DEPTH_FORMAT),
            paper: paper.map(|(warp, assemble)| PaperOrder {
                warp,
                assemble,
                warped: target("morphed frame", (width, height), COLOR_FORMAT),
                distortion: target("morph distortion", (width, height), COLOR_FORMAT),
            }),
            no_argmax: target("no argmax", (1, 1), ARGMAX_FORMAT),
            no_color: target("no colour", (1, 1), COLOR_FORMAT),
        })
    }

    /// A bind group of `source` and what the pass reads of the pyramids
    /// (`Reads`). The bindings it does not read get an unused 1×1
    /// texture: one that the pass writes must not be bound to it.
    fn bind(&self, gpu: &Gpu, source: &Source, reads: Reads) -> wgpu::BindGroup {
        let argmax = |t: Option<&wgpu::Texture>| view(t.unwrap_or(&self.no_argmax));
        let color = |t: Option<&wgpu::Texture>| view(t.unwrap_or(&self.no_color));
        let views = [
            view(source.color),
            depth_view(source.depth),
            view(source.flow),
            argmax(reads.snap.then(|| self.snapped())),
            color(reads.low.then(|| self.pyramid.last()).flatten()),
            argmax(reads.argmax_source),
            color(reads.blur_source),
            color(reads.low_full.then_some(&self.low_full)),
            color(
                reads
                    .distortion
                    .then(|| self.paper.as_ref().map(|p| &p.distortion))
                    .flatten(),
            ),
        ];
        let entries = parameters_sampler_and(&self.params, &self.sampler, &views);
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("morph"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// What every in-between frame of a rendered frame shares, timed as
    /// `<label>/…` when a profiler is given: the snapping pyramid (with
    /// `params.snap`), and with `params.blur` the low-pass pyramid and the
    /// displayed rendered frame ([`Morph::displayed`]).
    pub fn prepare(
        &self,
        gpu: &Gpu,
        source: &Source,
        params: &MorphParams,
        mut profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) {
        gpu.queue
            .write_buffer(&self.params, 0, &params.bytes(&self.setup));
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        if params.snap {
            let group = self.bind(gpu, source, Reads::default());
            fullscreen_pass(
                &mut encoder,
                &mut profiler,
                "flow edges",
                (&self.flow_edges, &group),
                &[view(&self.argmax[0])],
            );
            for level in 1..self.argmax.len() {
                let reads = Reads {
                    argmax_source: Some(&self.argmax[level - 1]),
                    ..Reads::default()
                };
                let group = self.bind(gpu, source, reads);
                fullscreen_pass(
                    &mut encoder,
                    &mut profiler,
                    "argmax",
                    (&self.argmax_reduce, &group),
                    &[view(&self.argmax[level])],
                );
            }
        }
        if params.blur {
            self.low_pass(gpu, source, source.color, &mut encoder, &mut profiler);
            let reads = Reads {
                low: true,
                ..Reads::default()
            };
            let group = self.bind(gpu, source, reads);
            fullscreen_pass(
                &mut encoder,
                &mut profiler,
                "compensate",
                (&self.compensate, &group),
                &[view(&self.displayed), view(&self.low_full)],
            );
        }
        gpu.queue.submit([encoder.finish()]);
    }

    /// The low-pass pyramid of `frame` (the rendered frame, or with the
    /// paper's order a morphed one), levels 1 to `blur_level`.
    fn low_pass(
        &self,
        gpu: &Gpu,
        source: &Source,
        frame: &wgpu::Texture,
        encoder: &mut wgpu::CommandEncoder,
        profiler: &mut Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) {
        for level in 0..self.pyramid.len() {
            let from = level.checked_sub(1).map_or(frame, |l| &self.pyramid[l]);
            let reads = Reads {
                blur_source: Some(from),
                ..Reads::default()
            };
            let group = self.bind(gpu, source, reads);
            fullscreen_pass(
                encoder,
                profiler,
                "low-pass",
                (&self.blur_down, &group),
                &[view(&self.pyramid[level])],
            );
        }
    }

    /// One in-between frame at `params.step` ([`Morph::color`]), after
    /// [`Morph::prepare`] of the same source, timed as `<label>/morph`
    /// (and with the paper's order of blur `<label>/low-pass` and
    /// `<label>/assemble`).
    pub fn render(
        &self,
        gpu: &Gpu,
        source: &Source,
        params: &MorphParams,
        profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) {
        gpu.queue
            .write_buffer(&self.params, 0, &params.bytes(&self.setup));
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let mut profiler = profiler;
        match (&self.paper, params.blur) {
            (Some(paper), true) => self.morph_then_blur(
                gpu,
                (source, params.snap),
                paper,
                &mut encoder,
                &mut profiler,
            ),
            (_, blur) => {
                let reads = Reads {
                    snap: params.snap,
                    low_full: blur,
                    ..Reads::default()
                };
                let pipeline = if blur { &self.morph } else { &self.warp };
                self.grid(
                    gpu,
                    source,
                    reads,
                    pipeline,
                    &[view(&self.color)],
                    &mut encoder,
                    &mut profiler,
                );
            }
        }
        gpu.queue.submit([encoder.finish()]);
    }

    /// The paper's order: the grid morphs the sharp frame (with its
    /// distortion), the pyramid blurs the morphed frame, and the assembly
    /// makes the in-between frame from the two.
    fn morph_then_blur(
        &self,
        gpu: &Gpu,
        (source, snap): (&Source, bool),
        paper: &PaperOrder,
        encoder: &mut wgpu::CommandEncoder,
        profiler: &mut Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) {
        let reads = Reads {
            snap,
            ..Reads::default()
        };
        let targets = [view(&paper.warped), view(&paper.distortion)];
        self.grid(gpu, source, reads, &paper.warp, &targets, encoder, profiler);
        self.low_pass(gpu, source, &paper.warped, encoder, profiler);
        let morphed = Source {
            color: &paper.warped,
            ..*source
        };
        let reads = Reads {
            low: true,
            distortion: true,
            ..Reads::default()
        };
        let group = self.bind(gpu, &morphed, reads);
        fullscreen_pass(
            encoder,
            profiler,
            "assemble",
            (&paper.assemble, &group),
            &[view(&self.color)],
        );
    }

    /// One draw of the grid with `pipeline` into `targets`, depth-tested
    /// with the rendered frame's depth.
    #[allow(clippy::too_many_arguments)]
    fn grid(
        &self,
        gpu: &Gpu,
        source: &Source,
        reads: Reads,
        pipeline: &wgpu::RenderPipeline,
        targets: &[wgpu::TextureView],
        encoder: &mut wgpu::CommandEncoder,
        profiler: &mut Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) {
        let group = self.bind(gpu, source, reads);
        let depth = view(&self.depth);
        timed_pass(
            encoder,
            profiler,
            "morph",
            (targets, Some((&depth, wgpu::StoreOp::Discard))),
            |pass| {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..self.index_count, 0, 0..1);
            },
        );
    }

    /// The last in-between frame.
    pub fn color(&self) -> &wgpu::Texture {
        &self.color
    }

    /// The rendered frame as displayed, compensated (after a
    /// [`Morph::prepare`] with blur).
    pub fn displayed(&self) -> &wgpu::Texture {
        &self.displayed
    }

    /// One texel per grid vertex: its neighbourhood's packed argmax
    /// (after a [`Morph::prepare`] with snapping).
    pub fn snapped(&self) -> &wgpu::Texture {
        self.argmax.last().unwrap_or(&self.no_argmax)
    }
}

/// The grid's triangles: two per tile, over vertices numbered row by row,
/// W/grid + 1 to a row.
fn grid_indices([width, height]: [u32; 2], grid: u32) -> Vec<u32> {
    let (tiles_x, tiles_y) = (width / grid, height / grid);
    let columns = tiles_x + 1;
    let mut indices = Vec::with_capacity((tiles_x * tiles_y * 6) as usize);
    for y in 0..tiles_y {
        for x in 0..tiles_x {
            let v = y * columns + x;
            indices.extend([v, v + 1, v + columns, v + 1, v + columns + 1, v + columns]);
        }
    }
    indices
}

/// The grid's pipeline: depth-tested (nearer wins, `vs_morph` orders the
/// depth so whichever way it runs), no culling (fold-overs flip the
/// winding).
fn grid_pipeline(
    device: &wgpu::Device,
    (module, layout, fragment): (&wgpu::ShaderModule, &wgpu::PipelineLayout, &str),
    constants: &[(&str, f64)],
    formats: &[wgpu::TextureFormat],
) -> wgpu::RenderPipeline {
    let targets: Vec<Option<wgpu::ColorTargetState>> =
        formats.iter().map(|f| Some((*f).into())).collect();
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("morph"),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_morph"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            targets: &targets,
        }),
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..wgpu::PrimitiveState::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// The argmax per grid vertex the GPU finds for the motion `motion`
/// (row-major, pixels, over `setup.size`): the snapping pyramid alone, on
/// a flow made from it. What [`argmax_on_cpu`] is checked against.
#[cfg(test)]
pub fn argmax_on_gpu(
    gpu: &Gpu,
    setup: MorphSetup,
    motion: &[[f32; 2]],
    snap_threshold: f32,
) -> Result<Vec<u32>, String> {
    let morph = Morph::new(gpu, setup)?;
    let size = (setup.size[0], setup.size[1]);
    let texels: Vec<u8> = motion
        .iter()
        .flat_map(|m| [m[0], m[1], 0.0, 1.0])
        .flat_map(|v| half::f16::from_f32(v).to_le_bytes())
        .collect();
    let flow = wgpu::util::DeviceExt::create_texture_with_data(
        &gpu.device,
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("motion"),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: COLOR_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &texels,
    );
    let target =
        |label, format| shadecache_host::toolchain::render_target(&gpu.device, label, size, format);
    let (color, depth) = (
        target("colour", COLOR_FORMAT),
        target("depth", DEPTH_FORMAT),
    );
    let source = Source {
        color: &color,
        depth: &depth,
        flow: &flow,
    };
    let params = MorphParams {
        step: 0.0,
        frames: 2.0,
        gamma: 2.2,
        exact_motion: true,
        speed_scale: 0.0,
        tracking: [70.0, 90.0],
        blur_min_speed: None,
        distortion: [0.25, 1.0],
        snap_threshold,
        far_depth: 1.0,
        blur: false,
        snap: true,
    };
    morph.prepare(gpu, &source, &params, None);
    Ok(crate::runtime::read_texture(gpu, morph.snapped(), 4)?
        .chunks_exact(4)
        .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
        .collect())
}

/// The argmax a neighbourhood's texel holds, as `fs_flow_edges` and
/// `fs_argmax_reduce` compute it, on the CPU: for each grid vertex, the
/// largest packed (gradient, y, x) over its neighbourhood of the motion
/// `motion` (row-major, pixels). A mirror for the tests.
#[cfg(test)]
pub fn argmax_on_cpu(
    motion: &[[f32; 2]],
    size: [u32; 2],
    grid: u32,
    snap_threshold: f32,
) -> Vec<u32> {
    let [w, h] = [size[0] as i32, size[1] as i32];
    let at = |x: i32, y: i32| motion[(y * w + x) as usize];
    let gradient = |x: i32, y: i32| -> f32 {
        let here = at(x, y);
        let mut g = 0.0f32;
        for (nx, ny) in [(x + 1, y), (x, y + 1)] {
            if nx < w && ny < h {
                let there = at(nx, ny);
                g = g.max((there[0] - here[0]).hypot(there[1] - here[1]));
            }
        }
        g
    };
    let (columns, rows) = (w / grid as i32 + 1, h / grid as i32 + 1);
    let half = grid as i32 / 2;
    let mut out = Vec::new();
    for j in 0..rows {
        for i in 0..columns {
            let mut best = 0u32;
            for ry in 0..grid as i32 {
                for rx in 0..grid as i32 {
                    let (x, y) = (i * grid as i32 - half + rx, j * grid as i32 - half + ry);
                    let mut packed = ((ry as u32) << 8) | rx as u32;
                    if x >= 0 && y >= 0 && x < w && y < h {
                        let g = gradient(x, y);
                        if g >= snap_threshold {
                            packed |= ((g * 256.0).clamp(0.0, 65535.0) as u32) << 16;
                        }
                    }
                    best = best.max(packed);
                }
            }
            out.push(best);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    /// The passes' module passes naga's validation with every flag (Tint
    /// and a pipeline per pass: the interpolation tests).
    #[test]
    fn morph_shaders_validate() {
        let source = super::MORPH_WGSL;
        let module = naga::front::wgsl::parse_str(source);
        let Ok(module) = module else {
            let error = module.err().map(|e| e.emit_to_string(source));
            unreachable!("{}", error.unwrap_or_default())
        };
        let valid = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module);
        assert!(
            valid.is_ok(),
            "{}",
            valid
                .err()
                .map(|e| e.emit_to_string(source))
                .unwrap_or_default()
        );
    }

    #[test]
    fn grid_has_two_triangles_per_tile() {
        let indices = super::grid_indices([32, 16], 8);
        assert_eq!(indices.len(), 4 * 2 * 6);
        // Five vertices to a row: the last tile's far corner is the last
        // vertex.
        assert_eq!(indices.iter().max(), Some(&(5 * 3 - 1)));
    }
}

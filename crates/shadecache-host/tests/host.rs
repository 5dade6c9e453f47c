//! The host crate on a small application: a square drawn with a camera
//! and a model matrix (`fixtures/square.wgsl`), rewritten by shadecache
//! into the fixtures' three-pass and one-pass variants (node `rings(...)`,
//! Δn = 64). Each test is the application: its own buffers, layouts and
//! render loop.
//!
//! GPU tests need an adapter (lavapipe in CI); without one they fail,
//! unless `SHADECACHE_SKIP_GPU_TESTS=1` says to skip them.

use shadecache_host::{
    CachedShader, Error, FrameLayout, Options, Plan, Targets, TwinSources, Twins,
    VertexBufferDescriptor, Viewport,
};

const SIZE: u32 = 64;

fn variant(name: &str) -> (Plan, Vec<(&'static str, &'static str)>) {
    let (plan, files): (&str, Vec<(&str, &str)>) = match name {
        "three-pass" => (
            include_str!("fixtures/square/three-pass/plan.json"),
            vec![
                (
                    "pass1.wgsl",
                    include_str!("fixtures/square/three-pass/pass1.wgsl"),
                ),
                (
                    "pass2.wgsl",
                    include_str!("fixtures/square/three-pass/pass2.wgsl"),
                ),
                (
                    "pass3.wgsl",
                    include_str!("fixtures/square/three-pass/pass3.wgsl"),
                ),
                (
                    "classify.wgsl",
                    include_str!("fixtures/square/three-pass/classify.wgsl"),
                ),
            ],
        ),
        "deferred" => (
            include_str!("fixtures/square/deferred/plan.json"),
            vec![
                (
                    "pass1.wgsl",
                    include_str!("fixtures/square/deferred/pass1.wgsl"),
                ),
                (
                    "pass2.wgsl",
                    include_str!("fixtures/square/deferred/pass2.wgsl"),
                ),
                (
                    "pass3.wgsl",
                    include_str!("fixtures/square/deferred/pass3.wgsl"),
                ),
                (
                    "pass4.wgsl",
                    include_str!("fixtures/square/deferred/pass4.wgsl"),
                ),
                (
                    "classify.wgsl",
                    include_str!("fixtures/square/deferred/classify.wgsl"),
                ),
            ],
        ),
        "gbuffer" => (
            include_str!("fixtures/gbuffer/three-pass/plan.json"),
            vec![
                (
                    "pass1.wgsl",
                    include_str!("fixtures/gbuffer/three-pass/pass1.wgsl"),
                ),
                (
                    "pass2.wgsl",
                    include_str!("fixtures/gbuffer/three-pass/pass2.wgsl"),
                ),
                (
                    "pass3.wgsl",
                    include_str!("fixtures/gbuffer/three-pass/pass3.wgsl"),
                ),
                (
                    "classify.wgsl",
                    include_str!("fixtures/gbuffer/three-pass/classify.wgsl"),
                ),
            ],
        ),
        _ => (
            include_str!("fixtures/square/one-pass/plan.json"),
            vec![
                (
                    "pass1.wgsl",
                    include_str!("fixtures/square/one-pass/pass1.wgsl"),
                ),
                (
                    "classify.wgsl",
                    include_str!("fixtures/square/one-pass/classify.wgsl"),
                ),
            ],
        ),
    };
    (
        serde_json::from_str(plan).expect("the fixture plan reads"),
        files,
    )
}

struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
}

fn gpu() -> Option<Gpu> {
    gpu_with(wgpu::Features::empty())
}

/// A device with `features`, where the adapter has them.
fn gpu_with(features: wgpu::Features) -> Option<Gpu> {
    gpu_with_limits(features, wgpu::Limits::default())
}

/// A device with `features` and no more than `limits`.
fn gpu_with_limits(features: wgpu::Features, limits: wgpu::Limits) -> Option<Gpu> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let Ok(adapter) =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
    else {
        if std::env::var_os("SHADECACHE_SKIP_GPU_TESTS").is_some_and(|v| v == "1") {
            use std::io::Write;
            // To the stream itself: libtest captures the print macros, and
            // a skip must not pass unseen.
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED (no GPU adapter, SHADECACHE_SKIP_GPU_TESTS=1)"
            );
            return None;
        }
        panic!("no GPU adapter: install a Vulkan driver (mesa-vulkan-drivers), or set SHADECACHE_SKIP_GPU_TESTS=1");
    };
    let features = features & adapter.features();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: features,
        required_limits: limits,
        ..Default::default()
    }))
    .expect("a device");
    Some(Gpu { device, queue })
}

const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 2] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2];

fn uniform_entry() -> [wgpu::BindGroupLayoutEntry; 1] {
    [wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }]
}

fn color_target() -> wgpu::ColorTargetState {
    wgpu::ColorTargetState {
        format: wgpu::TextureFormat::Rgba8Unorm,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    }
}

/// Calls `f` with the application's frame as its original pipeline has
/// it; `edit` changes it first.
fn with_frame<R>(
    edit: impl FnOnce(&mut FrameLayout<'_>),
    f: impl FnOnce(&FrameLayout<'_>) -> R,
) -> R {
    let buffers = [Some(wgpu::VertexBufferLayout {
        array_stride: 20,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    })];
    let entries = uniform_entry();
    let groups = [(0, &entries[..]), (1, &entries[..])];
    let colors = [Some(color_target())];
    let mut frame = FrameLayout::new(&buffers, &groups, &colors);
    edit(&mut frame);
    f(&frame)
}

fn make(
    gpu: &Gpu,
    name: &str,
    edit: impl FnOnce(&mut FrameLayout<'_>),
) -> Result<CachedShader, Error> {
    let (plan, files) = variant(name);
    make_from(gpu, &plan, &files, edit)
}

/// [`make`] with the plan given (a test's edit of a fixture's).
fn make_from(
    gpu: &Gpu,
    plan: &Plan,
    files: &[(&str, &str)],
    edit: impl FnOnce(&mut FrameLayout<'_>),
) -> Result<CachedShader, Error> {
    with_frame(edit, |frame| {
        CachedShader::new(
            &gpu.device,
            plan,
            |file| files.iter().find(|(n, _)| *n == file).map(|(_, t)| *t),
            frame,
            (SIZE, SIZE),
            Options::default(),
        )
    })
}

fn matrix(x: f32) -> [f32; 16] {
    // Column-major: scale by a half, move by x.
    [
        0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, x, 0.0, 0.5, 1.0,
    ]
}

fn bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The application: its buffers, bind groups, target, and the variant.
struct App {
    cached: CachedShader,
    camera: wgpu::Buffer,
    object: wgpu::Buffer,
    groups: [wgpu::BindGroup; 2],
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    twins: Twins,
    /// The frame's colour targets, by output location.
    targets: Vec<wgpu::Texture>,
}

fn buffer(gpu: &Gpu, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: contents.len() as u64,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    gpu.queue.write_buffer(&buffer, 0, contents);
    buffer
}

fn target(gpu: &Gpu, size: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("frame"),
        size: wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// How the application's draw call is made.
#[derive(Clone, Copy)]
enum Drawn {
    /// Through [`shadecache_host::Draw::draw_indexed`] with its own twins.
    ThroughHost,
    /// With the twins of another shader's draw.
    WithOthersTwins,
    /// Its object group set at the cache's group too.
    OnTheCacheGroup,
    /// Nothing drawn in the frame.
    Nothing,
}

impl App {
    /// The square with one rgba8unorm target.
    fn new(gpu: &Gpu, name: &str) -> App {
        let depth = wgpu::TextureFormat::Depth32Float;
        App::with_targets(gpu, name, &[wgpu::TextureFormat::Rgba8Unorm], depth)
    }

    /// The square drawn into targets of `formats`, by output location,
    /// with depth in `depth`.
    fn with_targets(
        gpu: &Gpu,
        name: &str,
        formats: &[wgpu::TextureFormat],
        depth: wgpu::TextureFormat,
    ) -> App {
        let states: Vec<Option<wgpu::ColorTargetState>> = formats
            .iter()
            .map(|&format| {
                Some(wgpu::ColorTargetState {
                    format,
                    ..color_target()
                })
            })
            .collect();
        let cached = make(gpu, name, |frame| {
            frame.color_targets = Box::leak(states.into());
            frame.depth_format = depth;
        })
        .expect("the variant is made");
        App::around(gpu, cached, formats)
    }

    /// The square drawn through `cached`, into targets of `formats`.
    fn around(gpu: &Gpu, mut cached: CachedShader, formats: &[wgpu::TextureFormat]) -> App {
        let identity = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_SRC;
        let camera = buffer(gpu, &bytes(&identity), uniform);
        let object = buffer(gpu, &bytes(&matrix(0.0)), uniform);
        // The application's layout, made from its own entries.
        let entries = uniform_entry();
        let layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: None,
                entries: &entries,
            });
        let group = |buffer: &wgpu::Buffer| {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            })
        };
        let groups = [group(&camera), group(&object)];
        #[rustfmt::skip]
        let square = bytes(&[
            -1.0, -1.0, 0.0, 0.0, 1.0,
            1.0, -1.0, 0.0, 1.0, 1.0,
            1.0, 1.0, 0.0, 1.0, 0.0,
            -1.0, 1.0, 0.0, 0.0, 0.0,
        ]);
        let vertices = buffer(gpu, &square, wgpu::BufferUsages::VERTEX);
        let index_bytes: Vec<u8> = [0u32, 1, 2, 0, 2, 3]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let indices = buffer(gpu, &index_bytes, wgpu::BufferUsages::INDEX);
        let twins = cached
            .twins(&TwinSources {
                buffers: &[([0, 0], &camera), ([1, 0], &object)],
                ..TwinSources::default()
            })
            .expect("twins");
        App {
            cached,
            camera,
            object,
            groups,
            vertices,
            indices,
            twins,
            targets: formats.iter().map(|&f| target(gpu, SIZE, f)).collect(),
        }
    }

    /// Writes the object's matrix, as an application does, then records
    /// and submits a frame.
    fn frame(&mut self, gpu: &Gpu, x: f32) {
        self.record(gpu, x, Drawn::ThroughHost)
            .expect("the frame records");
    }

    /// [`App::frame`] with the draws recorded by the application itself
    /// into the passes the host begins, as an engine's render commands do
    /// (`record_engine_timed`).
    fn engine_frame(&mut self, gpu: &Gpu, x: f32) -> Result<(), Error> {
        gpu.queue.write_buffer(&self.object, 0, &bytes(&matrix(x)));
        let view = self.targets[0].create_view(&wgpu::TextureViewDescriptor::default());
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let color = [Some(&view)];
        let targets = Targets {
            color: &color,
            clear: Some(wgpu::Color::BLACK),
            depth: None,
        };
        let (groups, vertices, indices) = (&self.groups, &self.vertices, &self.indices);
        self.cached.record_engine_timed(
            &gpu.queue,
            &mut encoder,
            &targets,
            &mut shadecache_host::NoTimer,
            &self.twins,
            |_, mut pass| {
                pass.set_bind_group(0, &groups[0], &[]);
                pass.set_bind_group(1, &groups[1], &[]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..6, 0, 0..1);
                Ok(())
            },
        )?;
        gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// [`App::frame`], drawing as `drawn` says; the error `record` gives.
    fn record(&mut self, gpu: &Gpu, x: f32, drawn: Drawn) -> Result<(), Error> {
        self.record_with(gpu, x, drawn, None)
    }

    /// [`App::record`] into a frame that shares the application's depth
    /// `depth` (and keeps what the colour target holds) when given.
    fn record_with(
        &mut self,
        gpu: &Gpu,
        x: f32,
        drawn: Drawn,
        depth: Option<&wgpu::TextureView>,
    ) -> Result<(), Error> {
        self.record_timed(
            gpu,
            x,
            drawn,
            depth,
            &mut shadecache_host::NoTimer,
            |_, _| {},
        )
    }

    /// [`App::record_with`], its passes timed by `timer`, and `before_submit`
    /// given the timer and the encoder after them (to resolve the queries).
    fn record_timed<T: shadecache_host::PassTimer>(
        &mut self,
        gpu: &Gpu,
        x: f32,
        drawn: Drawn,
        depth: Option<&wgpu::TextureView>,
        timer: &mut T,
        before_submit: impl FnOnce(&mut T, &mut wgpu::CommandEncoder),
    ) -> Result<(), Error> {
        gpu.queue.write_buffer(&self.object, 0, &bytes(&matrix(x)));
        let views: Vec<wgpu::TextureView> = self
            .targets
            .iter()
            .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()))
            .collect();
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let color: Vec<Option<&wgpu::TextureView>> = views.iter().map(Some).collect();
        let targets = Targets {
            color: &color,
            clear: depth.is_none().then_some(wgpu::Color::BLACK),
            depth,
        };
        let (groups, twins) = (&self.groups, &self.twins);
        let (vertices, indices) = (&self.vertices, &self.indices);
        let others = match drawn {
            Drawn::WithOthersTwins => Some(App::new(gpu, "three-pass")),
            _ => None,
        };
        let cache_group = self.cached.cache_group();
        self.cached
            .record_timed(&gpu.queue, &mut encoder, &targets, timer, |draw| {
                draw.set_bind_group(0, &groups[0], &[]);
                draw.set_bind_group(1, &groups[1], &[]);
                if let (Drawn::OnTheCacheGroup, Some(group)) = (drawn, cache_group) {
                    draw.set_bind_group(group, &groups[1], &[]);
                }
                draw.set_vertex_buffer(0, vertices.slice(..));
                draw.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                match (drawn, &others) {
                    (Drawn::Nothing, _) => {}
                    (_, Some(others)) => draw.draw_indexed(&others.twins, 0..6, 0, 0..1),
                    _ => draw.draw_indexed(twins, 0..6, 0, 0..1),
                }
            })?;
        before_submit(timer, &mut encoder);
        gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The last frame's age at each pixel, row by row.
    fn ages(&self, gpu: &Gpu) -> Vec<f32> {
        read(gpu, self.cached.age(), 2)
            .chunks_exact(2)
            .map(|h| f16_to_f32(u16::from_le_bytes([h[0], h[1]])))
            .collect()
    }
}

/// An IEEE half float's value (normal numbers and zero: ages are small
/// whole numbers).
fn f16_to_f32(bits: u16) -> f32 {
    let exponent = i32::from((bits >> 10) & 0x1f);
    let mantissa = f32::from(bits & 0x3ff);
    if exponent == 0 {
        return mantissa * 2f32.powi(-24);
    }
    (1.0 + mantissa / 1024.0) * 2f32.powi(exponent - 15)
}

fn read(gpu: &Gpu, texture: &wgpu::Texture, bytes_per_texel: u32) -> Vec<u8> {
    let (width, height) = (texture.width(), texture.height());
    let row = width * bytes_per_texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: u64::from(padded * height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        texture.size(),
    );
    gpu.queue.submit([encoder.finish()]);
    buffer.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("the read finishes");
    let data = buffer.slice(..).get_mapped_range().expect("mapped");
    (0..height as usize)
        .flat_map(|y| data[y * padded as usize..][..row as usize].to_vec())
        .collect()
}

/// The pixels well inside the square at x (in clip space), 2 pixels in
/// from its edges: a bilinear lookup there reads the square only.
fn inside(x: f32, size: u32) -> impl Iterator<Item = usize> {
    let to_pixel = |clip: f32| (clip + 1.0) * 0.5 * size as f32;
    let (left, right) = (
        to_pixel(x - 0.5) as usize + 2,
        to_pixel(x + 0.5) as usize - 2,
    );
    let (top, bottom) = (to_pixel(-0.5) as usize + 2, to_pixel(0.5) as usize - 2);
    (top..bottom).flat_map(move |y| (left..right).map(move |x| y * size as usize + x))
}

fn ages_at(ages: &[f32], pixels: impl Iterator<Item = usize>) -> Vec<f32> {
    let mut found: Vec<f32> = pixels.map(|p| ages[p]).collect();
    found.sort_by(f32::total_cmp);
    found.dedup();
    found
}

/// The share of `pixels` whose value is `age` frames old. With Δn = 64 a
/// few 4×4 blocks refresh in any frame (age 0): a reused frame has most
/// pixels, not all, at its age.
fn share_at(ages: &[f32], pixels: impl Iterator<Item = usize>, age: f32) -> f64 {
    let found: Vec<f32> = pixels.map(|p| ages[p]).collect();
    found.iter().filter(|&&a| a == age).count() as f64 / found.len() as f64
}

/// Most of the pixels reused: all but the refreshed blocks.
const REUSED: f64 = 0.9;

#[test]
fn a_frame_that_does_not_match_the_plan_is_an_error_naming_it() {
    let Some(gpu) = gpu() else { return };
    let mismatch = |edit: &dyn Fn(&mut FrameLayout<'_>), named: &str| {
        let one = [VERTEX_ATTRIBUTES[0]];
        let result = make(&gpu, "three-pass", |frame| {
            edit(frame);
            if named == "tex_coords" {
                // No buffer holds @location(1).
                frame.vertex_buffers = Box::leak(Box::new([Some(wgpu::VertexBufferLayout {
                    array_stride: 12,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: Box::leak(Box::new(one)),
                })]));
            }
        });
        match result {
            Err(Error::Mismatch(text)) => assert!(text.contains(named), "{text}"),
            other => panic!("{named}: {other:?}"),
        }
    };
    mismatch(&|_| {}, "tex_coords");
    // The object's matrix declared as storage.
    let storage = [wgpu::BindGroupLayoutEntry {
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        ..uniform_entry()[0]
    }];
    let storage: &'static [wgpu::BindGroupLayoutEntry] = Box::leak(Box::new(storage));
    let uniform: &'static [wgpu::BindGroupLayoutEntry] = Box::leak(Box::new(uniform_entry()));
    let groups: &'static [(u32, &[wgpu::BindGroupLayoutEntry])] =
        Box::leak(Box::new([(0, uniform), (1, storage)]));
    mismatch(&|frame| frame.bind_group_layouts = groups, "`object`");
    mismatch(&|frame| frame.color_targets = &[], "@location(0)");

    // Twins without the object's buffer, and with one that cannot be copied.
    let mut cached = make(&gpu, "three-pass", |_| {}).unwrap();
    let copyable = buffer(
        &gpu,
        &[0; 64],
        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_SRC,
    );
    let fixed = buffer(&gpu, &[0; 64], wgpu::BufferUsages::UNIFORM);
    let missing = cached.twins(&TwinSources {
        buffers: &[([0, 0], &copyable)],
        ..TwinSources::default()
    });
    assert!(
        matches!(&missing, Err(Error::Mismatch(t)) if t.contains("`object`")),
        "{missing:?}"
    );
    let uncopyable = cached.twins(&TwinSources {
        buffers: &[([0, 0], &copyable), ([1, 0], &fixed)],
        ..TwinSources::default()
    });
    assert!(
        matches!(&uncopyable, Err(Error::Mismatch(t)) if t.contains("COPY_SRC")),
        "{uncopyable:?}"
    );
}

#[test]
fn what_a_cache_cannot_do_is_refused() {
    let Some(gpu) = gpu() else { return };
    let refused =
        |edit: &dyn Fn(&mut FrameLayout<'_>), why: &str| match make(&gpu, "one-pass", edit) {
            Err(Error::Refused(text)) => assert!(text.contains(why), "{text}"),
            other => panic!("{why}: {other:?}"),
        };
    refused(&|frame| frame.sample_count = 4, "samples per pixel");
    // A viewport in part of the target is the variants' to take (split
    // screen); a plan that assumes the whole target (lowres's lattice, a
    // plan from before viewports) refuses it.
    let part =
        |frame: &mut FrameLayout<'_>| frame.viewport = Viewport::Rect([8.0, 0.0, 32.0, 32.0]);
    assert!(make(&gpu, "one-pass", part).is_ok());
    let (mut plan, files) = variant("one-pass");
    plan.assumes.partial_viewport = false;
    let whole_target_only = make_from(&gpu, &plan, &files, part);
    assert!(
        matches!(&whole_target_only, Err(Error::Refused(text)) if text.contains("viewport")),
        "{whole_target_only:?}"
    );
    refused(
        &|frame| frame.multiview = std::num::NonZeroU32::new(2),
        "multiview",
    );
    let blended: &'static [Option<wgpu::ColorTargetState>] =
        Box::leak(Box::new([Some(wgpu::ColorTargetState {
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            ..color_target()
        })]));
    refused(&|frame| frame.color_targets = blended, "blending");
}

/// A frame drawn in parts (`record_more_timed`) needs a plan without a
/// cache, and a frame recorded first to add to.
#[test]
fn more_draws_into_a_cache_frame_are_refused() {
    let Some(gpu) = gpu() else { return };
    let mut cached = make(&gpu, "one-pass", |_| {}).unwrap();
    let texture = target(&gpu, SIZE, wgpu::TextureFormat::Rgba8Unorm);
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    let color = [Some(&view)];
    let targets = shadecache_host::Targets {
        color: &color,
        clear: None,
        depth: None,
    };
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    match cached.record_more_timed(
        &mut encoder,
        &targets,
        &mut shadecache_host::NoTimer,
        |_| {},
    ) {
        Err(Error::Refused(text)) => assert!(text.contains("without a cache"), "{text}"),
        other => panic!("{other:?}"),
    }
}

/// The application's depth target, `depth32float` as the frame's, that
/// the test clears to `depth` and the colour target to red, as the
/// application's own draws before the cached ones would leave them.
fn shared_depth(gpu: &Gpu, app: &App, depth: f32) -> wgpu::Texture {
    let texture = target(gpu, SIZE, wgpu::TextureFormat::Depth32Float);
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    let color = app.targets[0].create_view(&wgpu::TextureViewDescriptor::default());
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("the application's earlier draws"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &color,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::RED),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(depth),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        ..wgpu::RenderPassDescriptor::default()
    });
    gpu.queue.submit([encoder.finish()]);
    texture
}

/// Cached draws in a frame with the application's other draws share its
/// depth (`Targets::depth`): where the application drew nearer, the
/// cached square is hidden and the colour is the application's; where it
/// drew nothing, the square is drawn, its depth written for what the
/// application draws after, and the next frames reuse it as with the
/// cache's own depth (the depth left in the shared target is copied into
/// the cache for the next frame's reprojection: without the copy, every
/// pixel would miss). A depth of another format or size is an error.
#[test]
fn cached_draws_share_the_applications_depth() {
    let Some(gpu) = gpu() else { return };
    let mut shared = App::new(&gpu, "three-pass");
    let mut own = App::new(&gpu, "three-pass");
    // Something nearer than the square covers the frame: the square is
    // hidden, the frame stays the application's red.
    let near = shared_depth(&gpu, &shared, 0.0);
    let near_view = near.create_view(&wgpu::TextureViewDescriptor::default());
    shared
        .record_with(&gpu, 0.0, Drawn::ThroughHost, Some(&near_view))
        .expect("the frame records");
    let red = read(&gpu, &shared.targets[0], 4);
    assert!(
        red.chunks(4).all(|p| p == [255, 0, 0, 255]),
        "the square drawn over a nearer surface"
    );

    // Nothing nearer: the frames are those of the cache's own depth, and
    // so is the reuse.
    shared.cached.reset();
    for frame in 0..3 {
        let far = shared_depth(&gpu, &shared, 1.0);
        let far_view = far.create_view(&wgpu::TextureViewDescriptor::default());
        shared
            .record_with(&gpu, 0.0, Drawn::ThroughHost, Some(&far_view))
            .expect("the frame records");
        own.frame(&gpu, 0.0);
        // Inside the square, the frame of the cache's own depth; outside,
        // what the application drew (the own-depth frame cleared it).
        let (ours, theirs) = (
            read(&gpu, &shared.targets[0], 4),
            read(&gpu, &own.targets[0], 4),
        );
        let square: Vec<usize> = inside(0.0, SIZE).collect();
        let differ = square
            .iter()
            .filter(|&&i| ours[i * 4..i * 4 + 4] != theirs[i * 4..i * 4 + 4])
            .count();
        assert_eq!(
            differ, 0,
            "frame {frame}: {differ} pixels of the square differ"
        );
        assert_eq!(
            &ours[..4],
            [255, 0, 0, 255],
            "frame {frame}: the corner is not the application's"
        );
        assert!(
            shared.ages(&gpu) == own.ages(&gpu),
            "frame {frame}: the ages differ from the cache's own depth's"
        );
        // The square's depth is left for the application's later draws.
        let depth_of = |texture: &wgpu::Texture| -> Vec<f32> {
            read(&gpu, texture, 4)
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        };
        let (left, drawn) = (depth_of(&far), depth_of(own.cached.depth()));
        assert!(
            square.iter().all(|&i| left[i] == drawn[i] && left[i] < 1.0),
            "frame {frame}: the square's depth is not in the application's"
        );
        assert_eq!(left[0], 1.0, "frame {frame}");
    }
    assert!(share_at(&shared.ages(&gpu), inside(0.0, SIZE), 2.0) > REUSED);

    // A depth the cache cannot take.
    let small = target(&gpu, SIZE / 2, wgpu::TextureFormat::Depth32Float);
    let small_view = small.create_view(&wgpu::TextureViewDescriptor::default());
    match shared.record_with(&gpu, 0.0, Drawn::ThroughHost, Some(&small_view)) {
        Err(Error::Mismatch(message)) => assert!(message.contains("32×32"), "{message}"),
        other => panic!("{other:?}"),
    }
}

/// The first frame computes everything; a still frame reuses everything
/// inside the square; `reset()` and `resize()` compute everything again.
#[test]
fn resize_and_reset_give_misses_not_stale_reuse() {
    let Some(gpu) = gpu() else { return };
    let mut app = App::new(&gpu, "three-pass");
    app.frame(&gpu, 0.0);
    assert_eq!(
        ages_at(&app.ages(&gpu), inside(0.0, SIZE)),
        [0.0],
        "first frame"
    );
    app.frame(&gpu, 0.0);
    assert!(
        share_at(&app.ages(&gpu), inside(0.0, SIZE), 1.0) > REUSED,
        "still frame"
    );
    app.cached.reset();
    app.frame(&gpu, 0.0);
    assert_eq!(
        ages_at(&app.ages(&gpu), inside(0.0, SIZE)),
        [0.0],
        "after reset"
    );
    app.frame(&gpu, 0.0);
    assert!(share_at(&app.ages(&gpu), inside(0.0, SIZE), 1.0) > REUSED);
    let small = 48;
    app.cached.resize((small, small)).expect("48×48 fits");
    app.targets = vec![target(&gpu, small, wgpu::TextureFormat::Rgba8Unorm)];
    app.frame(&gpu, 0.0);
    assert_eq!(
        ages_at(&app.ages(&gpu), inside(0.0, small)),
        [0.0],
        "after resize"
    );
    app.frame(&gpu, 0.0);
    assert!(share_at(&app.ages(&gpu), inside(0.0, small), 1.0) > REUSED);
}

/// The bytes a cache says its targets take are those its plan asks for,
/// counted by hand: the payload, age (`r16float`) and depth (32-bit) twice
/// and the classification (`rgba8unorm`) once, the deferred variant's
/// G-buffer besides; a resize counts the new size.
#[test]
fn target_bytes_count_every_target_the_cache_owns() {
    let Some(gpu) = gpu() else { return };
    let pixels = u64::from(SIZE * SIZE);
    let one = make(&gpu, "one-pass", |_| {}).expect("one-pass");
    // An rgba16float payload: 32 bytes a pixel.
    assert_eq!(one.target_bytes(), pixels * (2 * 8 + 2 * 2 + 2 * 4 + 4));
    let mut three = make(&gpu, "three-pass", |_| {}).expect("three-pass");
    // An rgba32float payload (the node is unbounded): 48.
    assert_eq!(three.target_bytes(), pixels * 48);
    three.resize((48, 32)).expect("48×32 fits");
    assert_eq!(three.target_bytes(), 48 * 32 * 48);
    let deferred = make(&gpu, "deferred", |_| {}).expect("deferred");
    // Its depth has the stencil its plan tests.
    let depth = match deferred.depth().format() {
        wgpu::TextureFormat::Depth24PlusStencil8 => 4,
        wgpu::TextureFormat::Depth32FloatStencil8 => 8,
        other => panic!("{other:?} has no stencil"),
    };
    // rgba32uint and r32uint: 20 bytes of G-buffer.
    assert_eq!(
        deferred.target_bytes(),
        pixels * (2 * 16 + 2 * 2 + 2 * depth + 4 + 20)
    );
}

/// After `reset()` the cache starts over as one just made: the frames
/// after it, ages and refreshed blocks included, are a new cache's (the
/// refresh pattern starts from its first frame again), so a profile of a
/// cold start is what an application sees after a camera cut.
#[test]
fn a_reset_cache_starts_over_as_one_just_made() {
    let Some(gpu) = gpu() else { return };
    let mut used = App::new(&gpu, "three-pass");
    for _ in 0..5 {
        used.frame(&gpu, 0.0);
    }
    used.cached.reset();
    let mut new = App::new(&gpu, "three-pass");
    for n in 0..4 {
        used.frame(&gpu, 0.0);
        new.frame(&gpu, 0.0);
        assert_eq!(used.ages(&gpu), new.ages(&gpu), "frame {n} after the reset");
    }
}

/// A square moving right reprojects into where it was: every pixel inside
/// it hits, the band it moved onto included. That holds only when the
/// object's twin holds last frame's matrix when the next frame runs: the
/// host copies after the frame's passes, before the application's writes
/// for the next frame take effect.
#[test]
fn the_twin_copy_precedes_the_next_frames_writes() {
    let Some(gpu) = gpu() else { return };
    let mut app = App::new(&gpu, "three-pass");
    app.frame(&gpu, -0.25);
    app.frame(&gpu, 0.0);
    let hits = share_at(&app.ages(&gpu), inside(0.0, SIZE), 1.0);
    assert!(hits > REUSED, "moving square: {hits}");
    // The camera's twin too: the camera moves the square back.
    let shifted = [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -0.25, 0.0, 0.0, 1.0,
    ];
    gpu.queue.write_buffer(&app.camera, 0, &bytes(&shifted));
    app.frame(&gpu, 0.0);
    let hits = share_at(&app.ages(&gpu), inside(-0.25, SIZE), 2.0);
    assert!(hits > REUSED, "moving camera: {hits}");
}

/// A deferred renderer's frame: an HDR colour target and an integer
/// material-id target, the formats the application's frame has (the plan
/// assumes rgba8unorm and rgba32uint). Values above 1 survive in the
/// cached frames, and the ids are written by the pass that shades.
#[test]
fn a_g_buffer_with_an_hdr_and_an_integer_target_runs() {
    let Some(gpu) = gpu() else { return };
    let formats = [
        wgpu::TextureFormat::Rgba16Float,
        wgpu::TextureFormat::Rgba32Uint,
    ];
    let depth = wgpu::TextureFormat::Depth32Float;
    let mut app = App::with_targets(&gpu, "gbuffer", &formats, depth);
    for frame in 0..3 {
        app.frame(&gpu, 0.0);
        let colors = read(&gpu, &app.targets[0], 8);
        let ids = read(&gpu, &app.targets[1], 16);
        let mut brightest = 0f32;
        for pixel in inside(0.0, SIZE) {
            let id = u32::from_le_bytes(ids[pixel * 16..][..4].try_into().unwrap());
            assert_eq!(id, 7, "frame {frame}, pixel {pixel}");
            let red = u16::from_le_bytes([colors[pixel * 8], colors[pixel * 8 + 1]]);
            brightest = brightest.max(f16_to_f32(red));
        }
        assert!(brightest > 1.5, "frame {frame}: HDR clamped to {brightest}");
    }
}

/// The application's depth format is the one the host renders and keeps
/// as last frame's depth: with depth and stencil in one texture, the cache
/// binds its depth aspect and reuses as with depth32float.
#[test]
fn a_depth_stencil_format_renders_and_reuses() {
    let Some(gpu) = gpu() else { return };
    let formats = [wgpu::TextureFormat::Rgba8Unorm];
    let depth = wgpu::TextureFormat::Depth24PlusStencil8;
    let mut app = App::with_targets(&gpu, "three-pass", &formats, depth);
    assert_eq!(app.cached.depth().format(), depth);
    app.frame(&gpu, 0.0);
    assert_eq!(ages_at(&app.ages(&gpu), inside(0.0, SIZE)), [0.0]);
    app.frame(&gpu, 0.0);
    assert!(share_at(&app.ages(&gpu), inside(0.0, SIZE), 1.0) > REUSED);
}

/// The deferred variant through the host: one geometry pass, screen-space
/// passes drawn per draw. Its first frame (every pixel computed) is
/// three-pass's to the bit (both shade from an rgba16float cache), it
/// reuses a moving square and under a moving camera as three-pass does
/// (the twins feed its geometry pass), and the host gives its depth buffer
/// the stencil the plan tests though the frame's format has none.
#[test]
fn a_deferred_plan_runs_through_the_host() {
    let Some(gpu) = gpu() else { return };
    let mut three = App::new(&gpu, "three-pass");
    let mut deferred = App::new(&gpu, "deferred");
    assert!(deferred.cached.depth().format().has_stencil_aspect());
    three.frame(&gpu, -0.25);
    deferred.frame(&gpu, -0.25);
    let (a, b) = (
        read(&gpu, &three.targets[0], 4),
        read(&gpu, &deferred.targets[0], 4),
    );
    let covered = inside(-0.25, SIZE).count();
    assert!(covered > 100);
    for pixel in inside(-0.25, SIZE) {
        assert_eq!(a[pixel * 4..][..4], b[pixel * 4..][..4], "pixel {pixel}");
    }
    // Outside the square the frame keeps the application's clear colour.
    assert_eq!(b[..4], [0, 0, 0, 255]);
    deferred.frame(&gpu, 0.0);
    let hits = share_at(&deferred.ages(&gpu), inside(0.0, SIZE), 1.0);
    assert!(hits > REUSED, "moving square: {hits}");
    let shifted = [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -0.25, 0.0, 0.0, 1.0,
    ];
    gpu.queue
        .write_buffer(&deferred.camera, 0, &bytes(&shifted));
    deferred.frame(&gpu, 0.0);
    let hits = share_at(&deferred.ages(&gpu), inside(-0.25, SIZE), 2.0);
    assert!(hits > REUSED, "moving camera: {hits}");
}

/// A deferred plan's passes mark each draw's pixels in the stencil: a
/// frame whose callback draws nothing is an error that says so, not a
/// blank frame.
#[test]
fn a_deferred_frame_without_draws_is_an_error() {
    let Some(gpu) = gpu() else { return };
    let mut app = App::new(&gpu, "deferred");
    let err = app
        .record(&gpu, 0.0, Drawn::Nothing)
        .expect_err("the stencil passes saw no draw");
    assert!(err.to_string().contains("drew nothing"), "{err}");
    let mut three = App::new(&gpu, "three-pass");
    three
        .record(&gpu, 0.0, Drawn::Nothing)
        .expect("a plan without stencil records an empty frame");
}

/// A draw cannot be recorded without its twins: `Draw` has no draw call
/// that does not take them, and no raw render pass (the doctest on
/// `Draw` that tries fails to compile). Twins of another shader, or the
/// cache's group set by the application, are errors from `record`, not
/// wgpu validation errors that its default handler turns into a panic.
#[test]
fn host_record_without_twins_is_an_error_or_does_not_compile() {
    let Some(gpu) = gpu() else { return };
    let mut app = App::new(&gpu, "three-pass");
    let err = app
        .record(&gpu, 0.0, Drawn::WithOthersTwins)
        .expect_err("another shader's twins");
    assert!(
        matches!(&err, Error::Draw(text) if text.contains("another CachedShader")),
        "{err}"
    );
    assert!(
        app.cached.cache_group().is_some(),
        "the fixture binds a cache group"
    );
    let err = app
        .record(&gpu, 0.0, Drawn::OnTheCacheGroup)
        .expect_err("the cache's group");
    assert!(
        matches!(&err, Error::Draw(text) if text.contains("the cache's")),
        "{err}"
    );
    app.frame(&gpu, 0.0);
}

/// `new` and `resize` check the size against the device: zero, or past
/// its largest 2D texture, is [`Error::Limits`] (wgpu would panic in its
/// default handler), and a refused resize keeps the cache running at its
/// old size.
#[test]
fn host_resize_beyond_limits_is_an_error() {
    let Some(gpu) = gpu() else { return };
    let most = gpu.device.limits().max_texture_dimension_2d;
    let (plan, files) = variant("three-pass");
    let made = with_frame(
        |_| {},
        |frame| {
            CachedShader::new(
                &gpu.device,
                &plan,
                |file| files.iter().find(|(n, _)| *n == file).map(|(_, t)| *t),
                frame,
                (0, SIZE),
                Options::default(),
            )
        },
    );
    assert!(matches!(made, Err(Error::Limits(_))), "{made:?}");
    let mut app = App::new(&gpu, "three-pass");
    for size in [(most + 1, SIZE), (SIZE, most + 1), (0, 0)] {
        let err = app.cached.resize(size).expect_err("beyond the limits");
        assert!(
            matches!(&err, Error::Limits(text) if text.contains(&most.to_string())),
            "{err}"
        );
        assert_eq!(app.cached.size(), (SIZE, SIZE));
    }
    app.frame(&gpu, 0.0);
}

/// Without its default features the host is async only: nothing in its
/// dependencies blocks (pollster), so it can serve the web.
#[test]
fn host_without_default_features_has_no_blocking_dependency() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let tree = |features: &[&str]| {
        let out = std::process::Command::new(&cargo)
            .args(["tree", "--offline", "-p", "shadecache-host", "-e", "normal"])
            .args(["--prefix", "none", "--format", "{p}"])
            .args(features)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .expect("cargo runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let lean = tree(&["--no-default-features"]);
    assert!(lean.contains("wgpu"), "{lean}");
    assert!(!lean.contains("pollster"), "{lean}");
    // The check can fail: with the default features it is there.
    assert!(tree(&[]).contains("pollster"));
}

/// An engine that records its own draws into the passes the host begins
/// (Bevy's render phases) gets the frames the host's own draw callback
/// gives, frame after frame under motion (so the twins are bound and
/// copied as for `record`).
#[test]
fn an_engines_own_draws_give_the_frames_of_the_hosts() {
    let Some(gpu) = gpu() else { return };
    for name in ["three-pass", "one-pass"] {
        let mut through_host = App::new(&gpu, name);
        let mut engine = App::new(&gpu, name);
        for x in [-0.25, 0.0, 0.1, 0.1] {
            through_host.frame(&gpu, x);
            engine.engine_frame(&gpu, x).expect("the frame records");
            assert_eq!(
                read(&gpu, &through_host.targets[0], 4),
                read(&gpu, &engine.targets[0], 4),
                "{name}, x = {x}"
            );
            assert_eq!(
                through_host.ages(&gpu),
                engine.ages(&gpu),
                "{name}, x = {x}"
            );
        }
    }
}

/// The variant with pipelines the application made itself from the
/// host's descriptors, as an engine's pipeline cache makes them: each
/// group's layout from its entries, the pass's WGSL by the plan's name.
fn made_by_the_application(gpu: &Gpu, name: &str) -> CachedShader {
    let (plan, files) = variant(name);
    let device = &gpu.device;
    let depth =
        |frame: &mut FrameLayout<'_>| frame.depth_format = wgpu::TextureFormat::Depth32Float;
    with_frame(depth, |frame| {
        let described = CachedShader::describe_pipelines(device, &plan, frame, Options::default())
            .expect("the passes are described");
        let pipelines = described
            .descriptors()
            .map(|pass| {
                let groups: Vec<wgpu::BindGroupLayout> = pass
                    .bind_group_layouts
                    .iter()
                    .map(|entries| {
                        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                            label: None,
                            entries,
                        })
                    })
                    .collect();
                let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(Some).collect();
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: None,
                    bind_group_layouts: &groups,
                    immediate_size: 0,
                });
                let (_, source) = files
                    .iter()
                    .find(|(file, _)| *file == pass.shader)
                    .expect("the plan's shader is a fixture");
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: None,
                    source: wgpu::ShaderSource::Wgsl((*source).into()),
                });
                let buffers: Vec<Option<wgpu::VertexBufferLayout<'_>>> = pass
                    .vertex_buffers
                    .iter()
                    .map(|b| b.as_ref().map(VertexBufferDescriptor::borrowed))
                    .collect();
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(&pass.label),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(&pass.vertex_entry),
                        compilation_options: Default::default(),
                        buffers: &buffers,
                    },
                    primitive: pass.primitive,
                    depth_stencil: Some(pass.depth_stencil.clone()),
                    multisample: pass.multisample,
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(&pass.fragment_entry),
                        compilation_options: Default::default(),
                        targets: &pass.targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
            .collect();
        pollster::block_on(CachedShader::from_pipelines_async(
            device,
            described,
            (SIZE, SIZE),
            pipelines,
        ))
        .expect("the variant takes the application's pipelines")
    })
}

/// An application that makes the variant's pipelines itself from the
/// host's descriptors (an engine's pipeline cache, compiling off the
/// frame) gets the frames of the pipelines the host makes, under motion,
/// for every kind of variant: the descriptors are the host's pipelines,
/// and the host's bind groups bind to pipelines of layouts made from
/// their entries.
#[test]
fn pipelines_the_application_makes_from_the_descriptors_give_the_hosts_frames() {
    let Some(gpu) = gpu() else { return };
    for name in ["three-pass", "one-pass", "deferred"] {
        let mut host = App::new(&gpu, name);
        let mut application = App::around(
            &gpu,
            made_by_the_application(&gpu, name),
            &[wgpu::TextureFormat::Rgba8Unorm],
        );
        for x in [-0.25, 0.0, 0.1, 0.1] {
            host.frame(&gpu, x);
            application.frame(&gpu, x);
            assert_eq!(
                read(&gpu, &host.targets[0], 4),
                read(&gpu, &application.targets[0], 4),
                "{name}, x = {x}"
            );
            assert_eq!(host.ages(&gpu), application.ages(&gpu), "{name}, x = {x}");
        }
    }
}

/// Pipelines of another count than the passes described are refused.
#[test]
fn pipelines_of_another_count_than_the_descriptors_are_refused() {
    let Some(gpu) = gpu() else { return };
    let (plan, _) = variant("three-pass");
    let described = with_frame(
        |_| {},
        |frame| CachedShader::describe_pipelines(&gpu.device, &plan, frame, Options::default()),
    )
    .expect("the passes are described");
    let err = pollster::block_on(CachedShader::from_pipelines_async(
        &gpu.device,
        described,
        (SIZE, SIZE),
        Vec::new(),
    ))
    .expect_err("no pipelines for three passes");
    assert!(
        err.to_string()
            .contains("0 pipelines were given for the 3 passes"),
        "{err}"
    );
}

/// A variant whose passes bind more groups than the device has is refused
/// with the reason when its pipelines are described, before anything is
/// made: an engine that makes them itself (Bevy's pipeline cache makes
/// them outside an error scope) would otherwise meet wgpu's error
/// handler.
#[test]
fn more_bind_groups_than_the_device_has_are_refused_when_described() {
    let limits = wgpu::Limits {
        max_bind_groups: 2,
        ..wgpu::Limits::default()
    };
    let Some(gpu) = gpu_with_limits(wgpu::Features::empty(), limits) else {
        return;
    };
    let (plan, _) = variant("three-pass");
    let described = with_frame(
        |_| {},
        |frame| CachedShader::describe_pipelines(&gpu.device, &plan, frame, Options::default()),
    );
    let err = described.expect_err("three groups on a device of two");
    assert!(err.to_string().contains("and the device has 2"), "{err}");
    let made = make(&gpu, "three-pass", |_| {});
    let err = made.expect_err("three groups on a device of two");
    assert!(err.to_string().contains("and the device has 2"), "{err}");
}

/// What WGSL does not say of a buffer binding — a dynamic offset, a least
/// size — is the application's: a frame whose uniforms have them (as
/// engines' view and material uniforms do) matches the plan, where
/// another kind of buffer does not.
#[test]
fn a_uniform_with_a_dynamic_offset_and_a_least_size_matches_its_binding() {
    let Some(gpu) = gpu() else { return };
    let engines = [wgpu::BindGroupLayoutEntry {
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: wgpu::BufferSize::new(64),
        },
        ..uniform_entry()[0]
    }];
    let engines: &'static [wgpu::BindGroupLayoutEntry] = Box::leak(Box::new(engines));
    let groups: &'static [(u32, &[wgpu::BindGroupLayoutEntry])] =
        Box::leak(Box::new([(0, engines), (1, engines)]));
    for name in ["three-pass", "one-pass"] {
        let made = make(&gpu, name, |frame| frame.bind_group_layouts = groups);
        assert!(made.is_ok(), "{name}: {:?}", made.err());
    }
}

/// A hand-edited plan is an error where it is read, naming what is wrong,
/// never a panic or an allocation of gigabytes: the table of corrupted
/// plans of the adversarial review (a G-buffer target at location
/// 2³² − 1, a uniform field at byte 2³² − 16, resolution divisors of 0
/// and 2³² − 1, lowres without or with out-of-range upsampling knobs, a
/// refresh period past the indicator's, a block of 0 pixels, a depth
/// tolerance and a far-plane depth out of range, no pass). `Plan::check`
/// refuses each, and `CachedShader::new` checks the plan before it makes
/// anything.
#[test]
fn a_corrupted_plan_is_an_error_not_an_allocation() {
    let original: serde_json::Value =
        serde_json::from_str(include_str!("fixtures/square/three-pass/plan.json")).unwrap();
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, &str); 11] = [
        (
            "a target at location 2^32 - 1",
            |p| p["passes"][0]["color_targets"][0]["location"] = 4294967295u32.into(),
            "location 4294967295",
        ),
        (
            "a uniform field at byte 2^32 - 16",
            |p| p["cache"]["params"][0]["offset"] = 4294967280u32.into(),
            "4-aligned",
        ),
        (
            "a resolution divisor of 2^32 - 1",
            |p| p["passes"][0]["resolution_divisor"] = 4294967295u32.into(),
            "1/4294967295",
        ),
        (
            "a resolution divisor of 0",
            |p| p["passes"][0]["resolution_divisor"] = 0.into(),
            "1/0",
        ),
        (
            "lowres without its upsampling",
            |p| p["variant"] = "lowres".into(),
            "upsampling",
        ),
        (
            "upsampling knobs out of range",
            |p| {
                p["upsampling"] = serde_json::json!({
                    "reconstruction": "spatial", "factor": 3,
                    "sigma_normal": -1.0, "sigma_depth": 0.03, "sensitivity": 1.0
                })
            },
            "factor of 3",
        ),
        (
            "a refresh period past 65535",
            |p| p["refresh"]["period"] = 70000.into(),
            "70000",
        ),
        (
            "a refresh block of 0 pixels",
            |p| p["refresh"]["quad"] = 0.into(),
            "quad is 0",
        ),
        (
            "a negative depth tolerance",
            |p| p["refresh"]["depth_epsilon"] = (-3.0).into(),
            "depth_epsilon = -3",
        ),
        (
            "a far plane at depth 2",
            |p| p["clear"]["depth"] = 2.0.into(),
            "clear.depth = 2",
        ),
        (
            "no pass",
            |p| p["passes"] = serde_json::json!([]),
            "no pass",
        ),
    ];
    for (what, edit, says) in cases {
        let mut json = original.clone();
        edit(&mut json);
        let plan: Plan = serde_json::from_value(json).expect(what);
        let err = plan.check().expect_err(what);
        assert!(err.contains(says), "{what}: {err}");
    }
    // The fixture itself is a plan a host takes.
    let plan: Plan = serde_json::from_value(original.clone()).unwrap();
    plan.check().unwrap();
    // And the host reads no further than the check.
    let Some(gpu) = gpu() else { return };
    let mut json = original;
    json["passes"][0]["color_targets"][0]["location"] = 4294967295u32.into();
    let corrupted: Plan = serde_json::from_value(json).unwrap();
    let made = with_frame(
        |_| {},
        |frame| {
            CachedShader::new(
                &gpu.device,
                &corrupted,
                |_| Some(""),
                frame,
                (SIZE, SIZE),
                Options::default(),
            )
        },
    );
    assert!(matches!(made, Err(Error::Plan(_))), "{:?}", made.err());
}

/// A running application's frame times arrive when the GPU is done with
/// them, without a wait: each frame is asked for after its submit, and
/// every frame's time comes back once, under its own number, however
/// many frames later; a governor fed with them holds an estimate.
#[test]
fn frame_times_are_read_when_ready_without_waiting() {
    let Some(gpu) = gpu_with(wgpu::Features::TIMESTAMP_QUERY) else {
        return;
    };
    let Some(mut timer) = shadecache_host::FrameTimer::new(&gpu.device, &gpu.queue, 4, 3) else {
        eprintln!("SKIPPED (the adapter has no timestamp queries)");
        return;
    };
    let mut app = App::new(&gpu, "three-pass");
    let mut governor = shadecache_host::Governor::new(shadecache_host::GovernorSettings {
        min_samples: 4,
        window: 8,
        probe_every: 2,
        decide_every: 1,
        warmup: 2,
        ..Default::default()
    })
    .expect("the settings govern");
    let mut arrived = Vec::new();
    let mut untimed = Vec::new();
    for _ in 0..24 {
        let next = governor.next_frame();
        if !timer.begin_frame(next.frame) {
            untimed.push(next.frame);
        }
        app.record_timed(
            &gpu,
            0.0,
            Drawn::ThroughHost,
            None,
            &mut timer,
            |timer, encoder| timer.resolve(encoder),
        )
        .expect("the frame records");
        for (frame, ms) in timer.ready(&gpu.device).expect("the times read") {
            governor.measured(frame, ms);
            arrived.push((frame, ms));
        }
    }
    // What is still on the way comes in once the GPU is idle.
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("the GPU finishes");
    for (frame, ms) in timer.ready(&gpu.device).expect("the times read") {
        governor.measured(frame, ms);
        arrived.push((frame, ms));
    }
    let mut frames: Vec<u64> = arrived.iter().map(|(f, _)| *f).collect();
    frames.extend(&untimed);
    frames.sort();
    assert_eq!(
        frames,
        (0..24).collect::<Vec<u64>>(),
        "{arrived:?} untimed {untimed:?}"
    );
    assert!(arrived.len() >= 8, "{arrived:?}");
    assert!(arrived.iter().all(|(_, ms)| *ms > 0.0), "{arrived:?}");
    assert!(governor.estimate().is_some());
}

/// Clears `view` to `color` (a render pass with nothing drawn).
fn clear_to(gpu: &Gpu, view: &wgpu::TextureView, color: wgpu::Color) {
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            resolve_target: None,
            depth_slice: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(color),
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    });
    gpu.queue.submit([encoder.finish()]);
}

/// Records the watch's comparison of `frames` over what `app`'s last
/// frame covered, submits it, and waits for its answer (`ready` itself
/// never waits).
fn watched(
    gpu: &Gpu,
    watch: &mut shadecache_host::ErrorWatch,
    frame: u64,
    original: Option<&wgpu::Texture>,
    app: &App,
) -> shadecache_host::WatchedError {
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    let io = (&gpu.queue, &mut encoder);
    let timer = &mut shadecache_host::NoTimer;
    let cached = &app.targets[0];
    let recorded = match original {
        None => watch.compare(
            &gpu.device,
            io,
            timer,
            frame,
            cached,
            shadecache_host::Coverage::Cache(&app.cached),
        ),
        Some(original) => watch.compare_frames(
            &gpu.device,
            io,
            timer,
            frame,
            [original, cached],
            shadecache_host::Coverage::Cache(&app.cached),
        ),
    }
    .expect("the frames compare");
    assert!(recorded);
    assert!(!watch.is_free(), "a second comparison waits for the first");
    gpu.queue.submit([encoder.finish()]);
    loop {
        if let Some(error) = watch.ready(&gpu.device).expect("the numbers read") {
            assert!(watch.is_free());
            return error;
        }
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("the GPU finishes");
    }
}

/// The error watch's PSNR, over the pixels the cached draws covered,
/// is what a read-back of the same frames gives on the CPU by the
/// profiler's rule (linear RGB, peak 1, mean over the covered pixels'
/// channels); a frame against itself is at the cap. Frames the watch
/// cannot read are an error naming them.
#[test]
fn the_error_watch_gives_the_psnr_of_a_read_back() {
    let Some(gpu) = gpu() else { return };
    let mut app = App::new(&gpu, "three-pass");
    app.frame(&gpu, 0.0);
    app.frame(&gpu, 0.1);
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let mut watch = shadecache_host::ErrorWatch::new(&gpu.device, (SIZE, SIZE), format)
        .expect("the watch is made");
    clear_to(
        &gpu,
        watch.spare_view(),
        wgpu::Color {
            r: 0.5,
            g: 0.25,
            b: 0.75,
            a: 1.0,
        },
    );
    let error = watched(&gpu, &mut watch, 7, None, &app);

    let pixels = read(&gpu, &app.targets[0], 4);
    let depth: Vec<f32> = read(&gpu, app.cached.depth(), 4)
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let (mut squared, mut covered) = (0.0f64, 0u64);
    for (pixel, &d) in depth.iter().enumerate() {
        if d == 1.0 {
            continue;
        }
        covered += 1;
        // The spare target holds the clear colour in 8 bits.
        for (channel, spare) in [0.5f64, 0.25, 0.75].into_iter().enumerate() {
            let spare = (spare * 255.0).round() / 255.0;
            let value = f64::from(pixels[pixel * 4 + channel]) / 255.0;
            squared += (value - spare) * (value - spare);
        }
    }
    let expected = 10.0 * (3.0 * covered as f64 / squared).log10();
    assert_eq!(error.frame, 7);
    assert_eq!(error.covered, covered);
    assert!(
        covered > 500 && covered < u64::from(SIZE * SIZE) / 2,
        "{covered}"
    );
    assert!(
        (error.psnr - expected).abs() < 0.01,
        "watch {:.4} dB, read-back {expected:.4} dB",
        error.psnr
    );

    let same = watched(&gpu, &mut watch, 8, Some(&app.targets[0]), &app);
    assert_eq!(same.psnr, 100.0);

    let unreadable = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("no binding"),
        size: wgpu::Extent3d {
            width: SIZE,
            height: SIZE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    let refused = watch.compare_frames(
        &gpu.device,
        (&gpu.queue, &mut encoder),
        &mut shadecache_host::NoTimer,
        9,
        [&unreadable, &app.targets[0]],
        shadecache_host::Coverage::Cache(&app.cached),
    );
    assert!(
        matches!(&refused, Err(Error::Mismatch(text)) if text.contains("original") && text.contains("TEXTURE_BINDING")),
        "{refused:?}"
    );
    assert!(shadecache_host::ErrorWatch::new(
        &gpu.device,
        (SIZE, SIZE),
        wgpu::TextureFormat::Rgba8Uint
    )
    .is_err());
}

/// With the coverage of the pixels either frame changed from a base frame
/// (an engine's cached draws sharing the view's depth with its other
/// meshes): two squares at different places over a black base, compared
/// over the union of what they drew, as a read-back gives on the CPU.
#[test]
fn the_error_watch_compares_what_either_frame_changed_from_a_base() {
    let Some(gpu) = gpu() else { return };
    let (mut left, mut right) = (App::new(&gpu, "three-pass"), App::new(&gpu, "three-pass"));
    left.frame(&gpu, -0.2);
    right.frame(&gpu, 0.2);
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let base = target(&gpu, SIZE, format);
    clear_to(
        &gpu,
        &base.create_view(&Default::default()),
        wgpu::Color::BLACK,
    );
    let mut watch = shadecache_host::ErrorWatch::new(&gpu.device, (SIZE, SIZE), format)
        .expect("the watch is made");
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    watch
        .compare_frames(
            &gpu.device,
            (&gpu.queue, &mut encoder),
            &mut shadecache_host::NoTimer,
            3,
            [&left.targets[0], &right.targets[0]],
            shadecache_host::Coverage::ChangedFrom(&base),
        )
        .expect("the frames compare");
    gpu.queue.submit([encoder.finish()]);
    let error = loop {
        if let Some(error) = watch.ready(&gpu.device).expect("the numbers read") {
            break error;
        }
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("the GPU finishes");
    };
    let (a, b) = (
        read(&gpu, &left.targets[0], 4),
        read(&gpu, &right.targets[0], 4),
    );
    let (mut squared, mut covered) = (0.0f64, 0u64);
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        if pa == [0, 0, 0, 255] && pb == [0, 0, 0, 255] {
            continue;
        }
        covered += 1;
        for c in 0..3 {
            let d = (f64::from(pa[c]) - f64::from(pb[c])) / 255.0;
            squared += d * d;
        }
    }
    let expected = 10.0 * (3.0 * covered as f64 / squared).log10();
    assert_eq!(error.covered, covered);
    assert!(covered > 1000, "{covered}");
    assert!(
        (error.psnr - expected).abs() < 0.01,
        "watch {:.4} dB, read-back {expected:.4} dB",
        error.psnr
    );
}

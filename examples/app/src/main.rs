//! A small wgpu application that runs a cached variant of its own shader.
//!
//! `build.rs` rewrites `shaders/planet.wgsl` with shadecache's build API
//! into its three-pass reprojection-cache variant (the marble albedo
//! cached, the sun's lighting recomputed every frame). The planet is
//! skinned, as engines skin characters: its northern hemisphere twists
//! against the southern one, the joints' matrices in the locals uniform,
//! whose previous-frame twin gives each vertex where it was. At run time the
//! application links only the host crate: it reads the plan, makes the
//! variant on its own device from its own layouts, and each frame records
//! it into its own encoder with its own draw call. The render loop runs
//! the original pipeline and the cached variant on the same frame, so it
//! can show both, measure the cached frame's error against the original,
//! and time every pass with timestamp queries.
//!
//! Headless, by default it runs as it would ship: the host crate's
//! governor chooses each frame between the original pipeline and the
//! variant from the GPU times it measures on this adapter, and its error
//! watch keeps the cached frames within 35 dB of the original
//! (`--min-psnr`), lowering Δn where they drift; the app prints what it
//! decided and what the frames cost (`governed.rs`). `--mode always` and
//! `--mode off` run the same loop one way. With
//! `--compare` it draws every frame both ways, writes a few frames as PNG
//! and prints per-frame errors and per-pass GPU times. With the `window`
//! feature and a display, `--window` draws into a window instead, the
//! space bar switching between the original pipeline and the cached
//! variant.
//!
//! ```text
//! cargo run --release -- [--frames N] [--size PIXELS] [--refresh-period N] [--variant three-pass|lowres] [--mode always|off|auto] [--min-psnr DB|none]
//! cargo run --release -- --compare [--frames N] [--warmup N] [--size PIXELS] [--refresh-period N] [--variant three-pass|lowres] [--out DIR]
//! cargo run --release --features window -- --window [--refresh-period N]
//! ```

mod governed;
mod planet;
#[cfg(feature = "window")]
mod window;

use std::error::Error;
use std::path::PathBuf;

use planet::Planet;
use shadecache_host::{
    CacheMode, CachedShader, FrameLayout, PassTimer, Plan, Targets, Timestamps, TwinSources,
};

/// The variant the build script wrote, by the plan's file names.
const PLAN: &str = include_str!(concat!(
    env!("OUT_DIR"),
    "/shadecache/planet/nf50106c5/three-pass/plan.json"
));
const PASSES: [(&str, &str); 3] = [
    (
        "pass1.wgsl",
        include_str!(concat!(
            env!("OUT_DIR"),
            "/shadecache/planet/nf50106c5/three-pass/pass1.wgsl"
        )),
    ),
    (
        "pass2.wgsl",
        include_str!(concat!(
            env!("OUT_DIR"),
            "/shadecache/planet/nf50106c5/three-pass/pass2.wgsl"
        )),
    ),
    (
        "pass3.wgsl",
        include_str!(concat!(
            env!("OUT_DIR"),
            "/shadecache/planet/nf50106c5/three-pass/pass3.wgsl"
        )),
    ),
];
/// The lowres variant the build script wrote.
const LOWRES_PLAN: &str = include_str!(concat!(
    env!("OUT_DIR"),
    "/shadecache/planet/nf50106c5/lowres/plan.json"
));
const LOWRES_PASSES: [(&str, &str); 2] = [
    (
        "pass1.wgsl",
        include_str!(concat!(
            env!("OUT_DIR"),
            "/shadecache/planet/nf50106c5/lowres/pass1.wgsl"
        )),
    ),
    (
        "pass2.wgsl",
        include_str!(concat!(
            env!("OUT_DIR"),
            "/shadecache/planet/nf50106c5/lowres/pass2.wgsl"
        )),
    ),
];
const ORIGINAL: &str = include_str!("../shaders/planet.wgsl");

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The fewest frames before the steady state: the first frames fill the
/// cache. At least Δn, as the profiler does, so every refresh has come.
const WARMUP: u32 = 4;
/// A frame equal to the original is reported at this PSNR.
const PSNR_CAP: f64 = 100.0;

struct Args {
    /// Frames measured, after the warm-up (with --compare; default 24), or
    /// played (governed; default 600).
    frames: Option<u32>,
    warmup: Option<u32>,
    size: u32,
    refresh_period: Option<u32>,
    /// Run the lowres variant instead of three-pass.
    lowres: bool,
    out: PathBuf,
    /// Draw into a window instead, switching between the original and the
    /// cached variant with the space bar.
    window: bool,
    /// Draw each frame both ways and compare them, instead of letting the
    /// governor choose.
    compare: bool,
    /// How the governed run caches (`--mode`, `--min-psnr`).
    mode: CacheMode,
}

/// The error budget the app ships with: the least PSNR, in dB, of a
/// watched cached frame against the original.
const MIN_PSNR: f64 = 35.0;

fn args() -> Result<Args, String> {
    let mut args = Args {
        frames: None,
        warmup: None,
        size: 256,
        refresh_period: None,
        lowres: false,
        out: PathBuf::from("frames"),
        window: false,
        compare: false,
        mode: CacheMode::Auto {
            min_psnr: Some(MIN_PSNR),
        },
    };
    let mut given = std::env::args().skip(1);
    while let Some(flag) = given.next() {
        let mut value = || given.next().ok_or_else(|| format!("{flag} needs a value"));
        let number = |text: String| text.parse::<u32>().map_err(|err| format!("{flag}: {err}"));
        match flag.as_str() {
            "--frames" => args.frames = Some(number(value()?)?),
            "--warmup" => args.warmup = Some(number(value()?)?),
            "--size" => args.size = number(value()?)?.max(16),
            "--refresh-period" => args.refresh_period = Some(number(value()?)?),
            "--variant" => {
                args.lowres = match value()?.as_str() {
                    "three-pass" => false,
                    "lowres" => true,
                    other => return Err(format!("--variant: three-pass or lowres, not `{other}`")),
                }
            }
            "--out" => args.out = PathBuf::from(value()?),
            "--window" => args.window = true,
            "--compare" => args.compare = true,
            "--mode" => {
                args.mode = match value()?.as_str() {
                    "always" => CacheMode::Always,
                    "off" => CacheMode::Off,
                    "auto" => CacheMode::Auto {
                        min_psnr: Some(MIN_PSNR),
                    },
                    other => return Err(format!("--mode: always, off or auto, not `{other}`")),
                }
            }
            "--min-psnr" => {
                let text = value()?;
                let budget = match text.as_str() {
                    "none" => None,
                    _ => Some(
                        text.parse::<f64>()
                            .ok()
                            .filter(|db| db.is_finite() && *db > 0.0)
                            .ok_or(format!(
                                "--min-psnr: a PSNR in dB above 0, or none, not `{text}`"
                            ))?,
                    ),
                };
                args.mode = CacheMode::Auto { min_psnr: budget };
            }
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(args)
}

struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    name: String,
}

fn gpu() -> Result<Gpu, Box<dyn Error>> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
        ..wgpu::DeviceDescriptor::default()
    }))?;
    let info = adapter.get_info();
    Ok(Gpu {
        device,
        queue,
        name: format!("{} ({:?})", info.name, info.backend),
    })
}

/// The original pipeline, as the application made it before caching.
fn original_pipeline(
    gpu: &Gpu,
    planet: &Planet,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let module = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("planet.wgsl"),
            source: wgpu::ShaderSource::Wgsl(ORIGINAL.into()),
        });
    let layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[Some(&planet.layout), Some(&planet.layout)],
            immediate_size: 0,
        });
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("planet"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(planet::vertex_layout())],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: planet::DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        })
}

/// The cached variant on the application's device, from its own layouts.
/// The original pass into `view`, cleared to `clear`, with its own
/// depth; timed as `original` when a timer is given.
fn draw_original(
    encoder: &mut wgpu::CommandEncoder,
    (pipeline, planet): (&wgpu::RenderPipeline, &Planet),
    (view, depth): (&wgpu::TextureView, &wgpu::TextureView),
    clear: wgpu::Color,
    mut timer: Option<&mut impl PassTimer>,
) {
    let query = timer.as_mut().map(|t| t.begin(encoder, "original"));
    let writes = timer
        .as_ref()
        .zip(query.as_ref())
        .and_then(|(t, q)| t.timestamp_writes(q));
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("original"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(clear),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: writes,
        ..Default::default()
    });
    pass.set_pipeline(pipeline);
    planet.draw(&mut pass);
}

/// The cached variant drawing into `format` targets of `size`.
/// Three-pass unless `lowres`, whose Δn is its factor's s² and not set
/// here.
fn cached_shader(
    gpu: &Gpu,
    (refresh_period, lowres): (Option<u32>, bool),
    format: wgpu::TextureFormat,
    size: (u32, u32),
) -> Result<CachedShader, Box<dyn Error>> {
    if lowres {
        let plan: Plan = serde_json::from_str(LOWRES_PLAN)?;
        let source = |name: &str| {
            LOWRES_PASSES
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, s)| *s)
        };
        return made(gpu, &plan, source, format, size);
    }
    let mut plan: Plan = serde_json::from_str(PLAN)?;
    if let Some(period) = refresh_period {
        // Δn is data: the refresh uniform carries it to the passes.
        plan.refresh.period = period;
    }
    let source = |name: &str| PASSES.iter().find(|(n, _)| *n == name).map(|(_, s)| *s);
    made(gpu, &plan, source, format, size)
}

/// `plan` on the application's device, in its frame.
fn made<'s>(
    gpu: &Gpu,
    plan: &Plan,
    source: impl Fn(&str) -> Option<&'s str>,
    format: wgpu::TextureFormat,
    size: (u32, u32),
) -> Result<CachedShader, Box<dyn Error>> {
    let buffers = [Some(planet::vertex_layout())];
    let groups = [
        (0, &planet::UNIFORM_ENTRY[..]),
        (1, &planet::UNIFORM_ENTRY[..]),
    ];
    let colors = [Some(format.into())];
    let frame = FrameLayout::new(&buffers, &groups, &colors);
    Ok(CachedShader::new(
        &gpu.device,
        plan,
        source,
        &frame,
        size,
        shadecache_host::Options::default(),
    )?)
}

fn main() -> Result<(), Box<dyn Error>> {
    let args = args()?;
    if args.window {
        #[cfg(feature = "window")]
        return window::run(args.refresh_period);
        #[cfg(not(feature = "window"))]
        return Err(
            "--window needs the `window` feature: cargo run --features window -- --window".into(),
        );
    }
    let gpu = gpu()?;
    let planet = Planet::new(&gpu.device, &gpu.queue, 1.0);
    let original = original_pipeline(&gpu, &planet, COLOR_FORMAT);
    let size = (args.size, args.size);
    let mut cached = cached_shader(&gpu, (args.refresh_period, args.lowres), COLOR_FORMAT, size)?;
    let twins = cached.twins(&TwinSources {
        buffers: &[([0, 0], &planet.globals), ([1, 0], &planet.locals)],
        ..TwinSources::default()
    })?;
    if !args.compare {
        println!("adapter: {}", gpu.name);
        let plan = cached.plan();
        let frames = args.frames.unwrap_or(600);
        println!(
            "variant: {} caching `{}`, Δn = {}, {}×{}, {frames} frames, {}",
            plan.variant,
            plan.node.text,
            plan.refresh.period,
            args.size,
            args.size,
            match args.mode {
                CacheMode::Always => "cached every frame (--mode always)".to_string(),
                CacheMode::Off => "the original every frame (--mode off)".to_string(),
                CacheMode::Auto { min_psnr: None } => "governed".to_string(),
                CacheMode::Auto { min_psnr: Some(db) } => format!("governed, error budget {db} dB"),
            }
        );
        return governed::run(
            &gpu,
            (&planet, &original),
            (&mut cached, &twins),
            (size, frames, args.mode),
        );
    }
    let mut timer = Timestamps::new(&gpu.device, &gpu.queue, 4);
    let targets =
        ["original", "cached"].map(|label| texture(&gpu.device, label, size, COLOR_FORMAT));
    let depth = texture(&gpu.device, "depth", size, planet::DEPTH_FORMAT);
    let views = targets
        .each_ref()
        .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()));
    let depth_view = depth.create_view(&wgpu::TextureViewDescriptor::default());
    std::fs::create_dir_all(&args.out)?;

    println!("adapter: {}", gpu.name);
    let plan = cached.plan();
    let warmup = args.warmup.unwrap_or(WARMUP.max(plan.refresh.period));
    let measured = args.frames.unwrap_or(24);
    let frames = warmup + measured;
    println!(
        "variant: {} caching `{}`, Δn = {}, {}×{}, {measured} frames after {warmup} warm-up",
        plan.variant, plan.node.text, plan.refresh.period, args.size, args.size
    );
    let mut steady = Steady::default();
    for frame in 0..frames {
        // The application writes its uniforms as it always did.
        planet.update(&gpu.queue, frame);
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        // The original pass.
        draw_original(
            &mut encoder,
            (&original, &planet),
            (&views[0], &depth_view),
            wgpu::Color::TRANSPARENT,
            timer.as_mut(),
        );
        // The cached variant: the same draw in each of its passes.
        let color = [Some(&views[1])];
        let frame_targets = Targets {
            color: &color,
            clear: Some(wgpu::Color::TRANSPARENT),
            depth: None,
        };
        let draw = |draw: &mut shadecache_host::Draw<'_, '_>| {
            planet.draw_cached(draw, &twins);
        };
        match timer.as_mut() {
            Some(timer) => {
                cached.record_timed(&gpu.queue, &mut encoder, &frame_targets, timer, draw)?
            }
            None => cached.record(&gpu.queue, &mut encoder, &frame_targets, draw)?,
        }
        if let Some(timer) = &timer {
            timer.resolve(&mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);
        let times = match timer.as_mut() {
            Some(timer) => timer.read(&gpu.device)?,
            None => Vec::new(),
        };

        let [reference, frame_pixels] = [&targets[0], &targets[1]].map(|t| read_rgba16f(&gpu, t));
        let (psnr, max_error) = compare(&reference?, &frame_pixels?);
        println!("frame {frame:3}: PSNR {psnr:6.2} dB, max error {max_error:.4}");
        if frame >= warmup {
            steady.add(psnr, max_error, &times);
        }
        if frame == 0 || frame == frames / 2 || frame + 1 == frames {
            for (name, texture) in [("original", &targets[0]), ("cached", &targets[1])] {
                let path = args.out.join(format!("{name}_{frame:03}.png"));
                write_png(&gpu, texture, &path)?;
            }
        }
    }
    steady.print(warmup, frames);
    println!("wrote frames to {}", args.out.display());
    Ok(())
}

/// The steady state's error and times.
#[derive(Default)]
struct Steady {
    psnr: Vec<f64>,
    max_error: f64,
    /// Per pass: its name and summed milliseconds.
    times: Vec<(String, f64)>,
}

impl Steady {
    fn add(&mut self, psnr: f64, max_error: f64, times: &[shadecache_host::PassTime]) {
        self.psnr.push(psnr);
        self.max_error = self.max_error.max(max_error);
        for time in times {
            match self.times.iter_mut().find(|(n, _)| *n == time.pass) {
                Some((_, sum)) => *sum += time.milliseconds,
                None => self.times.push((time.pass.clone(), time.milliseconds)),
            }
        }
    }

    fn print(&self, warmup: u32, frames: u32) {
        let n = self.psnr.len().max(1) as f64;
        let mean = self.psnr.iter().sum::<f64>() / n;
        let min = self.psnr.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "steady state (frames {warmup}..{frames}): mean PSNR {mean:.2} dB, min {min:.2} dB, max error {:.4}",
            self.max_error
        );
        if self.times.is_empty() {
            println!("GPU times: the adapter has no timestamp queries");
            return;
        }
        let passes: Vec<String> = self
            .times
            .iter()
            .map(|(name, sum)| format!("{name} {:.3}", sum / n))
            .collect();
        let original: f64 = self
            .times
            .iter()
            .filter(|(p, _)| p == "original")
            .map(|t| t.1)
            .sum();
        let cached: f64 = self
            .times
            .iter()
            .filter(|(p, _)| p != "original")
            .map(|t| t.1)
            .sum();
        println!("GPU ms per frame: {}", passes.join(", "));
        println!(
            "cached / original: {:.3} ms / {:.3} ms = {:.2}× speed-up",
            cached / n,
            original / n,
            original / cached.max(f64::MIN_POSITIVE)
        );
    }
}

/// PSNR (peak 1, linear) and the largest error over the pixels the
/// original covers (alpha 1; the background is cleared to 0).
fn compare(reference: &[f32], frame: &[f32]) -> (f64, f64) {
    let mut squared = 0.0;
    let mut samples = 0usize;
    let mut max_error = 0f64;
    for (r, f) in reference.chunks_exact(4).zip(frame.chunks_exact(4)) {
        if r[3] < 0.5 {
            continue;
        }
        for c in 0..3 {
            let e = f64::from(r[c] - f[c]);
            squared += e * e;
            max_error = max_error.max(e.abs());
        }
        samples += 3;
    }
    let mse = squared / samples.max(1) as f64;
    let psnr = if mse == 0.0 {
        PSNR_CAP
    } else {
        (10.0 * (1.0 / mse).log10()).min(PSNR_CAP)
    };
    (psnr, max_error)
}

fn read_rgba16f(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<f32>, Box<dyn Error>> {
    let (width, height) = (texture.width(), texture.height());
    let row = width * 8;
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
    gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
    let data = buffer.slice(..).get_mapped_range()?;
    let mut out = Vec::with_capacity((width * height * 4) as usize);
    for y in 0..height as usize {
        let start = y * padded as usize;
        for half in data[start..start + row as usize].chunks_exact(2) {
            out.push(half::f16::from_le_bytes([half[0], half[1]]).to_f32());
        }
    }
    Ok(out)
}

/// Writes a frame as an 8-bit PNG (linear values clamped to [0, 1]).
fn write_png(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    path: &std::path::Path,
) -> Result<(), Box<dyn Error>> {
    let pixels = read_rgba16f(gpu, texture)?;
    let bytes: Vec<u8> = pixels
        .iter()
        .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    image::save_buffer(
        path,
        &bytes,
        texture.width(),
        texture.height(),
        image::ExtendedColorType::Rgba8,
    )?;
    Ok(())
}

/// A 2D texture the passes render into and that can be read back.
fn texture(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        // Bound as a texture by the error watch, which reads the frame.
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

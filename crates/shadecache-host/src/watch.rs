//! The error watch: how far a cached frame is from the original, measured
//! on the GPU the application runs on, without a stall.
//!
//! A governor that only times frames keeps a cache that is fast and wrong:
//! a light that starts to move leaves the cached shading behind it. Once
//! in a while (a [`crate::Governor`] says when) the application draws the
//! original frame as well, into a spare target, and [`ErrorWatch::compare`]
//! records a small compute pass that compares the two over the pixels the
//! cached draws cover: each invocation sums the squared RGB differences of
//! the covered pixels of one 16×16 tile and counts them, and writes the
//! two numbers to a buffer; the buffer is copied for reading and mapped when
//! the GPU is done. [`ErrorWatch::ready`] polls without waiting and
//! gives the frame's PSNR once the numbers are there, frames later.
//!
//! The measure is the profiler's (`shadecache profile`'s `psnr`): linear
//! RGB, peak 1, values above 1 counted as they are, over the covered
//! pixels, capped at 100 dB; a NaN or infinite difference counts as a huge
//! error, as a value the original does not show. Covered is where the
//! cache's own depth buffer holds something nearer than the far plane:
//! the pixels the cached draws wrote, which are what the profiler's
//! classification marks. The watch's two targets are read as float
//! textures, so both must be of a float or normalised format made with
//! `TEXTURE_BINDING` (an `*-srgb` target reads back as linear light, as
//! the profiler's `rgba16float` frames are).
//!
//! The compute pass is timed through the frame's [`PassTimer`], so a
//! frame that watches costs what it costs, the extra original draw and the
//! comparison included, and a governor counts it.

use crate::readback::MapWhenReady;
use crate::{CachedShader, Error, PassTimer};

/// PSNR is capped here, as the profiler caps it: identical frames would
/// be infinite.
pub const PSNR_CAP: f64 = 100.0;

/// Side of the square tile one invocation of the comparison sums.
const TILE: u32 = 16;

/// A squared difference larger than this counts as this: a NaN or an
/// infinity on one side, which the profiler counts as the largest error.
const HUGE: f32 = 1.0e30;

const COMPARE_WGSL: &str = r#"
@group(0) @binding(0) var original: texture_2d<f32>;
@group(0) @binding(1) var cached: texture_2d<f32>;
COVERAGE_BINDING
@group(0) @binding(3) var<storage, read_write> partials: array<vec2<f32>>;

struct Params {
    size: vec2<u32>,
    tiles_x: u32,
    far_depth: f32,
}
@group(0) @binding(4) var<uniform> params: Params;

// One invocation sums one 16×16 tile: no workgroup memory and no barrier
// (a CPU rasteriser runs a barrier loop far slower than the loads).
@compute @workgroup_size(64)
fn compare(@builtin(global_invocation_id) id: vec3<u32>) {
    let tiles_y = (params.size.y + 15u) / 16u;
    if id.x >= params.tiles_x * tiles_y {
        return;
    }
    let origin = vec2<u32>(id.x % params.tiles_x, id.x / params.tiles_x) * 16u;
    var squared = 0.0;
    var covered = 0.0;
    for (var y = 0u; y < 16u; y = y + 1u) {
        for (var x = 0u; x < 16u; x = x + 1u) {
            let pixel = origin + vec2<u32>(x, y);
            if any(pixel >= params.size) {
                continue;
            }
            let original_texel = textureLoad(original, pixel, 0);
            let cached_texel = textureLoad(cached, pixel, 0);
            if !(COVERED) {
                continue;
            }
            let difference = original_texel.rgb - cached_texel.rgb;
            let value = dot(difference, difference);
            // A NaN compares false: it counts as the huge error.
            squared = squared + select(HUGE, value, value < HUGE);
            covered = covered + 1.0;
        }
    }
    partials[id.x] = vec2<f32>(squared, covered);
}
"#;

/// The comparison's coverage, by [`Coverage`]: its binding 2 and the test
/// of a pixel.
fn compare_wgsl(coverage: CoverageKind) -> String {
    let (binding, covered) = match coverage {
        CoverageKind::Cache => (
            "@group(0) @binding(2) var coverage: texture_depth_2d;",
            "textureLoad(coverage, pixel, 0) != params.far_depth",
        ),
        CoverageKind::ChangedFrom => (
            "@group(0) @binding(2) var base: texture_2d<f32>;",
            "any(original_texel != textureLoad(base, pixel, 0)) || any(cached_texel != textureLoad(base, pixel, 0))",
        ),
    };
    COMPARE_WGSL
        .replace("COVERAGE_BINDING", binding)
        .replace("COVERED", covered)
        .replace("HUGE", &format!("{HUGE:e}"))
}

/// Which pixels the watch compares.
#[derive(Clone, Copy, Debug)]
pub enum Coverage<'a> {
    /// Those the cache's last recorded frame drew (its own depth nearer
    /// than the far plane): for an application whose cached draws have the
    /// cache's depth to themselves.
    Cache(&'a CachedShader),
    /// Those where the original or the cached frame differs from this
    /// one, the frame as it was before the cached meshes were drawn: for
    /// an engine whose cached draws share the view's depth with its other
    /// meshes (the cache's depth then holds those too, and would count
    /// their pixels, equal in both frames, as compared).
    ChangedFrom(&'a wgpu::Texture),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CoverageKind {
    Cache,
    ChangedFrom,
}

/// One watched frame's error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WatchedError {
    /// The frame it was measured on, as given to [`ErrorWatch::compare`].
    pub frame: u64,
    /// PSNR of the cached frame against the original over the covered
    /// pixels, in dB (capped at 100; 100 when none is covered).
    pub psnr: f64,
    /// The pixels compared.
    pub covered: u64,
}

/// Compares a cached frame with the original on the GPU and reads the
/// answer when it is ready (module docs).
#[derive(Debug)]
pub struct ErrorWatch {
    size: (u32, u32),
    spare: wgpu::Texture,
    spare_view: wgpu::TextureView,
    /// The comparison's pipeline and layout by [`CoverageKind`].
    pipelines: [(wgpu::ComputePipeline, wgpu::BindGroupLayout); 2],
    params: wgpu::Buffer,
    partials: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// The frame whose numbers are on their way, and their read.
    pending: Option<u64>,
    map: MapWhenReady,
}

impl ErrorWatch {
    /// A watch of `size` frames, with a spare target of `format` for the
    /// original (a float or normalised colour format).
    pub fn new(
        device: &wgpu::Device,
        size: (u32, u32),
        format: wgpu::TextureFormat,
    ) -> Result<ErrorWatch, Error> {
        if !matches!(
            format.sample_type(None, None),
            Some(wgpu::TextureSampleType::Float { .. })
        ) {
            return Err(Error::Refused(format!(
                "the error watch reads frames as float textures; {format:?} is not one"
            )));
        }
        let pipelines = [CoverageKind::Cache, CoverageKind::ChangedFrom]
            .map(|coverage| comparison(device, coverage));
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadecache error watch parameters"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (spare, partials, readback) = sized(device, size, format);
        Ok(ErrorWatch {
            size,
            spare_view: spare.create_view(&wgpu::TextureViewDescriptor::default()),
            spare,
            pipelines,
            params,
            partials,
            readback,
            pending: None,
            map: MapWhenReady::default(),
        })
    }

    /// Makes the spare target and the buffers for `size` frames; a
    /// comparison on its way is dropped.
    pub fn resize(&mut self, device: &wgpu::Device, size: (u32, u32)) {
        if size == self.size {
            return;
        }
        let (spare, partials, readback) = sized(device, size, self.spare.format());
        self.spare_view = spare.create_view(&wgpu::TextureViewDescriptor::default());
        self.spare = spare;
        self.partials = partials;
        self.readback = readback;
        self.size = size;
        self.pending = None;
        self.map = MapWhenReady::default();
    }

    /// The spare target to draw the original into, on a frame that
    /// watches: the size and format the watch was made with.
    pub fn spare(&self) -> &wgpu::Texture {
        &self.spare
    }

    /// A view of [`ErrorWatch::spare`], to draw into.
    pub fn spare_view(&self) -> &wgpu::TextureView {
        &self.spare_view
    }

    /// Why `texture` cannot be compared: another size than the watch's, a
    /// format not read as float, no `TEXTURE_BINDING`, multisampled.
    fn check_frame(&self, what: &str, texture: &wgpu::Texture) -> Result<(), Error> {
        let size = (texture.width(), texture.height());
        let problem = if size != self.size {
            Some(format!(
                "is {}×{}, the watch's frames {}×{}",
                size.0, size.1, self.size.0, self.size.1
            ))
        } else if !matches!(
            texture.format().sample_type(None, None),
            Some(wgpu::TextureSampleType::Float { .. })
        ) {
            Some(format!("is {:?}, not a float format", texture.format()))
        } else if !texture
            .usage()
            .contains(wgpu::TextureUsages::TEXTURE_BINDING)
        {
            Some("was made without TEXTURE_BINDING".into())
        } else if texture.sample_count() != 1 {
            Some("is multisampled".into())
        } else {
            None
        };
        match problem {
            Some(problem) => Err(Error::Mismatch(format!(
                "the {what} frame the error watch compares {problem}"
            ))),
            None => Ok(()),
        }
    }

    /// Whether a comparison can be recorded now: false while the last
    /// one's numbers are still on their way (one is read at a time; at a
    /// watch every 64 frames, they arrive long before the next).
    pub fn is_free(&self) -> bool {
        self.pending.is_none()
    }

    /// Records the comparison of `cached` (the frame as the cached
    /// variant drew it) with the spare target (where the application drew
    /// the same frame with the original) over the pixels of `coverage`,
    /// into `encoder`, after both were drawn;
    /// timed through `timer` as pass `watch`. Call [`ErrorWatch::ready`]
    /// after submitting. `false` when [`ErrorWatch::is_free`] is not
    /// (nothing is recorded).
    pub fn compare<T: PassTimer>(
        &mut self,
        device: &wgpu::Device,
        (queue, encoder): (&wgpu::Queue, &mut wgpu::CommandEncoder),
        timer: &mut T,
        frame: u64,
        cached: &wgpu::Texture,
        coverage: Coverage<'_>,
    ) -> Result<bool, Error> {
        let spare = self.spare.clone();
        self.compare_frames(
            device,
            (queue, encoder),
            timer,
            frame,
            [&spare, cached],
            coverage,
        )
    }

    /// [`ErrorWatch::compare`] with the original drawn elsewhere than the
    /// spare target (a texture of the watch's size).
    pub fn compare_frames<T: PassTimer>(
        &mut self,
        device: &wgpu::Device,
        (queue, encoder): (&wgpu::Queue, &mut wgpu::CommandEncoder),
        timer: &mut T,
        frame: u64,
        [original, cached]: [&wgpu::Texture; 2],
        coverage: Coverage<'_>,
    ) -> Result<bool, Error> {
        if !self.is_free() {
            return Ok(false);
        }
        for (what, texture) in [("original", original), ("cached", cached)] {
            self.check_frame(what, texture)?;
        }
        let (kind, far_depth, coverage_view) = match coverage {
            Coverage::Cache(cache) => {
                if cache.size() != self.size {
                    return Err(Error::Mismatch(format!(
                        "the error watch is for {}×{} frames and the cache's are {}×{}",
                        self.size.0,
                        self.size.1,
                        cache.size().0,
                        cache.size().1
                    )));
                }
                let depth = cache.depth().create_view(&wgpu::TextureViewDescriptor {
                    aspect: wgpu::TextureAspect::DepthOnly,
                    ..Default::default()
                });
                (CoverageKind::Cache, cache.plan().clear.depth as f32, depth)
            }
            Coverage::ChangedFrom(base) => {
                self.check_frame("base", base)?;
                (
                    CoverageKind::ChangedFrom,
                    0.0,
                    base.create_view(&Default::default()),
                )
            }
        };
        // An `*-srgb` texture's view decodes to linear light, as the
        // profiler's frames are.
        let view = |texture: &wgpu::Texture| texture.create_view(&Default::default());
        let (original, cached) = (view(original), view(cached));
        let tiles = (self.size.0.div_ceil(TILE), self.size.1.div_ceil(TILE));
        let mut params = Vec::with_capacity(16);
        for value in [self.size.0, self.size.1, tiles.0] {
            params.extend(value.to_le_bytes());
        }
        params.extend(far_depth.to_le_bytes());
        queue.write_buffer(&self.params, 0, &params);
        let (pipeline, layout) = &self.pipelines[kind as usize];
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadecache error watch"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&original),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&cached),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&coverage_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: self.partials.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: self.params.as_entire_binding(),
                },
            ],
        });
        let query = timer.begin(encoder, "watch");
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("shadecache error watch"),
                timestamp_writes: timer.compute_timestamp_writes(&query),
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups((tiles.0 * tiles.1).div_ceil(64), 1, 1);
        }
        timer.end(encoder, query);
        encoder.copy_buffer_to_buffer(&self.partials, 0, &self.readback, 0, self.partials.size());
        self.pending = Some(frame);
        Ok(true)
    }

    /// The error of the frame compared last, once its numbers have
    /// arrived: starts their read (call after submitting the comparison)
    /// and polls the device without waiting.
    pub fn ready(&mut self, device: &wgpu::Device) -> Result<Option<WatchedError>, Error> {
        let Some(frame) = self.pending else {
            return Ok(None);
        };
        self.map.start(self.readback.slice(..));
        device
            .poll(wgpu::PollType::Poll)
            .map_err(|err| Error::Wgpu(err.to_string()))?;
        if !self.map.done() {
            return Ok(None);
        }
        let (squared, covered) = {
            let data = self
                .readback
                .slice(..)
                .get_mapped_range()
                .map_err(|err| Error::Wgpu(format!("{err:?}")))?;
            data.chunks_exact(8).fold((0.0f64, 0.0f64), |(s, n), pair| {
                let value = |at: usize| {
                    f64::from(f32::from_le_bytes(
                        pair[at..at + 4].try_into().unwrap_or([0; 4]),
                    ))
                };
                (s + value(0), n + value(4))
            })
        };
        self.readback.unmap();
        self.pending = None;
        Ok(Some(WatchedError {
            frame,
            psnr: psnr(squared, covered as u64 * 3),
            covered: covered as u64,
        }))
    }
}

/// The comparison's pipeline and bind group layout for `coverage`.
fn comparison(
    device: &wgpu::Device,
    coverage: CoverageKind,
) -> (wgpu::ComputePipeline, wgpu::BindGroupLayout) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadecache error watch"),
        source: wgpu::ShaderSource::Wgsl(compare_wgsl(coverage).into()),
    });
    let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    let unfiltered = wgpu::TextureSampleType::Float { filterable: false };
    let coverage_type = match coverage {
        CoverageKind::Cache => wgpu::TextureSampleType::Depth,
        CoverageKind::ChangedFrom => unfiltered,
    };
    let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadecache error watch"),
        entries: &[
            texture(0, unfiltered),
            texture(1, unfiltered),
            texture(2, coverage_type),
            buffer(3, wgpu::BufferBindingType::Storage { read_only: false }),
            buffer(4, wgpu::BufferBindingType::Uniform),
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadecache error watch"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("shadecache error watch"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("compare"),
        compilation_options: Default::default(),
        cache: None,
    });
    (pipeline, layout)
}

/// The spare target and the partial sums' buffers of `size` frames.
fn sized(
    device: &wgpu::Device,
    size: (u32, u32),
    format: wgpu::TextureFormat,
) -> (wgpu::Texture, wgpu::Buffer, wgpu::Buffer) {
    // The host's render target: drawn into, bound by the comparison, and a
    // copy destination for an application that starts the original from
    // a copy of its frame.
    let spare =
        crate::cached::render_target(device, "shadecache error watch's original", size, format);
    let bytes = u64::from(size.0.max(1).div_ceil(TILE) * size.1.max(1).div_ceil(TILE)) * 8;
    let buffer = |label, usage| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage,
            mapped_at_creation: false,
        })
    };
    (
        spare,
        buffer(
            "shadecache error watch's sums",
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        ),
        buffer(
            "shadecache error watch's read-back",
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        ),
    )
}

/// PSNR of a sum of squared differences over `samples` channel values,
/// peak 1, capped (the profiler's rule).
fn psnr(squared: f64, samples: u64) -> f64 {
    if samples == 0 || squared <= 0.0 {
        return PSNR_CAP;
    }
    (10.0 * (samples as f64 / squared).log10()).min(PSNR_CAP)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psnr_is_the_profilers() {
        // Mean squared error 0.01 over the channels: 20 dB.
        assert!((psnr(0.01 * 300.0, 300) - 20.0).abs() < 1e-9);
        assert_eq!(psnr(0.0, 300), PSNR_CAP);
        assert_eq!(psnr(1.0, 0), PSNR_CAP);
    }
}

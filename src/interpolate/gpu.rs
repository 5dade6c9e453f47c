//! The GPU pieces every fullscreen pass of the stage is built from: the
//! frame's colour format, the sampler, the views, the bind-group layout
//! entries, one pipeline over the frame and one timed render pass. The
//! B-frame passes ([`super::bframe`]), the morph ([`super::morph`]) and
//! the Z-buffer bridge ([`super::thin`]) draw with them.

/// The B-frame's colour format: the measured colour format, so a B-frame
/// compares with the reference as an I-frame does.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The sampler every B-frame pass reads colour and flows with: linear
/// filtering, clamped to the edge.
pub(super) fn linear_clamp(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("linear clamp"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..wgpu::SamplerDescriptor::default()
    })
}

/// A fullscreen pass's bindings as the B-frame and morph shaders lay them
/// out: the parameters at 0, the sampler at 1, `views` from 2 on.
pub(super) fn parameters_sampler_and<'a>(
    params: &'a wgpu::Buffer,
    sampler: &'a wgpu::Sampler,
    views: &'a [wgpu::TextureView],
) -> Vec<wgpu::BindGroupEntry<'a>> {
    let mut entries = vec![
        wgpu::BindGroupEntry {
            binding: 0,
            resource: params.as_entire_binding(),
        },
        wgpu::BindGroupEntry {
            binding: 1,
            resource: wgpu::BindingResource::Sampler(sampler),
        },
    ];
    entries.extend(
        views
            .iter()
            .zip(2..)
            .map(|(view, binding)| wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(view),
            }),
    );
    entries
}

/// A whole texture's view.
pub(super) fn view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

/// A depth buffer's depth, as a `texture_depth_2d` reads it.
pub(super) fn depth_view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        aspect: wgpu::TextureAspect::DepthOnly,
        ..wgpu::TextureViewDescriptor::default()
    })
}

/// A fragment stage's 2D texture binding.
pub(super) fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A pipeline drawing `entry` of `shaders/bframe.wgsl` over the frame.
pub(super) fn fullscreen_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    label: &str,
    layout: &wgpu::PipelineLayout,
    entry: &str,
    constants: &[(&str, f64)],
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            targets,
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// The profiler of a timed recording, lent to one of its passes.
pub(super) fn reborrow<'a>(
    profiler: &'a mut Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
) -> Option<(&'a mut wgpu_profiler::GpuProfiler, &'a str)> {
    profiler.as_mut().map(|(p, label)| (&mut **p, *label))
}

/// Records one fullscreen pass of `pipeline` into `outputs` (cleared),
/// timed as `<label>/<name>` when a profiler is given.
pub(super) fn fullscreen_pass(
    encoder: &mut wgpu::CommandEncoder,
    profiler: &mut Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    name: &str,
    (pipeline, bind_group): (&wgpu::RenderPipeline, &wgpu::BindGroup),
    outputs: &[wgpu::TextureView],
) {
    timed_pass(encoder, profiler, name, (outputs, None), |pass| {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..3, 0..1);
    });
}

/// Records one render pass into `outputs` (cleared) and an optional depth
/// buffer (cleared to 1; kept or not as its store op says), drawn by
/// `draw`, timed as `<label>/<name>` when a profiler is given.
pub(super) fn timed_pass(
    encoder: &mut wgpu::CommandEncoder,
    profiler: &mut Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    name: &str,
    (outputs, depth): (
        &[wgpu::TextureView],
        Option<(&wgpu::TextureView, wgpu::StoreOp)>,
    ),
    draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
) {
    let query = profiler
        .as_mut()
        .map(|(profiler, label)| profiler.begin_pass_query(format!("{label}/{name}"), encoder));
    {
        let attachments: Vec<_> = outputs
            .iter()
            .map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(name),
            color_attachments: &attachments,
            depth_stencil_attachment: depth.map(|(view, store)| {
                wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store,
                    }),
                    stencil_ops: None,
                }
            }),
            timestamp_writes: query
                .as_ref()
                .and_then(|q| q.render_pass_timestamp_writes()),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        draw(&mut pass);
    }
    if let (Some((profiler, _)), Some(query)) = (profiler.as_mut(), query) {
        profiler.end_query(encoder, query);
        profiler.resolve_queries(encoder);
    }
}

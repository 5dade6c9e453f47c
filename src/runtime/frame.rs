//! The frame the profiler draws, described as an application describes
//! its own to the host crate: from the plan.

use std::collections::HashMap;

use shadecache_host::{CachedShader, FrameLayout};

use super::gpu::Gpu;
use crate::plan::{Plan, StepMode, TargetKind, VertexAttribute};

/// How to build the pipelines beyond what the plan says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PipelineOptions {
    /// A debugging view: the frame's colour targets blend additively, so a
    /// pixel's value is the sum of every shading of it. With a shader that
    /// writes a constant, it counts how many times each pixel was shaded.
    pub count_shading: bool,
    /// Cull back faces (counter-clockwise triangles face front), as the
    /// scene says; the same for the reference and every variant.
    pub cull_back_faces: bool,
}

/// How to run beyond what the plan says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunOptions {
    pub pipelines: PipelineOptions,
    /// Draw the plan's `classify` pass after each frame (see
    /// `Runner::classes`).
    pub classify: bool,
    /// A bind group of the plan's the caller binds itself (textures other
    /// runs rendered): the runner makes its layout, not its contents
    /// (`Runner::bind_external`).
    pub external_group: Option<u32>,
}

/// The frame the runner draws, as an application would describe its own:
/// the plan's inputs packed per step (slot 0 per vertex, slot 1 per
/// instance, twins left to the host), the layouts the plan implies, its
/// colour outputs in the plan's formats.
#[derive(Debug)]
pub struct PlanFrame {
    vertex: [Vec<wgpu::VertexAttribute>; 2],
    pub(super) groups: Vec<(u32, Vec<wgpu::BindGroupLayoutEntry>)>,
    colors: Vec<Option<wgpu::ColorTargetState>>,
    cull_back_faces: bool,
}

impl PlanFrame {
    pub fn new(plan: &Plan, options: PipelineOptions) -> Result<PlanFrame, String> {
        let mut vertex = [Vec::new(), Vec::new()];
        for (slot, step) in [StepMode::Vertex, StepMode::Instance]
            .into_iter()
            .enumerate()
        {
            vertex[slot] = packed(&plan.vertex_layout, step);
        }
        let groups = shadecache_host::toolchain::plan_groups(plan)
            .into_iter()
            .map(|group| {
                shadecache_host::toolchain::plan_layout_entries(plan, group)
                    .map(|entries| (group, entries))
                    .map_err(|err| err.to_string())
            })
            .collect::<Result<_, _>>()?;
        let mut colors: Vec<Option<wgpu::ColorTargetState>> = Vec::new();
        for target in plan.passes.iter().flat_map(|p| &p.color_targets) {
            if target.target != TargetKind::Color {
                continue;
            }
            let index = target.location as usize;
            if colors.len() <= index {
                colors.resize(index + 1, None);
            }
            colors[index] = Some(wgpu::ColorTargetState {
                format: shadecache_host::toolchain::texture_format(target.format),
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            });
        }
        Ok(PlanFrame {
            vertex,
            groups,
            colors,
            cull_back_faces: options.cull_back_faces,
        })
    }

    /// The frame's colour formats, by output location.
    pub(super) fn color_formats(&self) -> impl Iterator<Item = Option<wgpu::TextureFormat>> + '_ {
        self.colors
            .iter()
            .map(|state| state.as_ref().map(|s| s.format))
    }

    /// Calls `f` with the frame's layout (its parts borrow from here).
    pub fn with_layout<R>(&self, f: impl FnOnce(&FrameLayout<'_>) -> R) -> R {
        let stride = |attributes: &[wgpu::VertexAttribute]| {
            attributes
                .iter()
                .map(|a| a.offset + a.format.size())
                .max()
                .unwrap_or(0)
        };
        let mut buffers = vec![Some(wgpu::VertexBufferLayout {
            array_stride: stride(&self.vertex[0]),
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &self.vertex[0],
        })];
        if !self.vertex[1].is_empty() {
            buffers.push(Some(wgpu::VertexBufferLayout {
                array_stride: stride(&self.vertex[1]),
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &self.vertex[1],
            }));
        }
        let groups: Vec<(u32, &[wgpu::BindGroupLayoutEntry])> = self
            .groups
            .iter()
            .map(|(group, entries)| (*group, entries.as_slice()))
            .collect();
        let mut layout = FrameLayout::new(&buffers, &groups, &self.colors);
        layout.primitive.cull_mode = self.cull_back_faces.then_some(wgpu::Face::Back);
        f(&layout)
    }
}

/// The plan's inputs that step as `step` and are not twins, packed in
/// order.
fn packed(layout: &[VertexAttribute], step: StepMode) -> Vec<wgpu::VertexAttribute> {
    let mut offset = 0;
    layout
        .iter()
        .filter(|attribute| attribute.step == step && attribute.previous_of.is_none())
        .map(|attribute| {
            let format = shadecache_host::toolchain::vertex_format(attribute.format);
            let out = wgpu::VertexAttribute {
                format,
                offset,
                shader_location: attribute.location,
            };
            offset += format.size();
            out
        })
        .collect()
}

/// The shaders a plan names, read once.
fn sources(plan: &Plan, shader: impl Fn(&str) -> Option<String>) -> HashMap<String, String> {
    plan.passes
        .iter()
        .chain(&plan.classify)
        .filter_map(|pass| Some((pass.shader.clone(), shader(&pass.shader)?)))
        .collect()
}

/// The variant on the GPU from `plan` and its shaders (`shader` gives a
/// file's text by the plan's name), drawn in the frame the plan implies at
/// `size`: what the runner draws with, and the frame it was made for.
pub(super) fn cached_shader(
    gpu: &Gpu,
    plan: &Plan,
    shader: impl Fn(&str) -> Option<String>,
    size: (u32, u32),
    options: RunOptions,
) -> Result<(CachedShader, PlanFrame), String> {
    let sources = sources(plan, shader);
    let frame = PlanFrame::new(plan, options.pipelines)?;
    let cached = frame
        .with_layout(|layout| {
            CachedShader::new(
                &gpu.device,
                plan,
                |name| sources.get(name).map(String::as_str),
                layout,
                size,
                shadecache_host::Options {
                    classify: options.classify,
                    count_shading: options.pipelines.count_shading,
                    ..shadecache_host::Options::default()
                },
            )
        })
        .map_err(|err| err.to_string())?;
    Ok((cached, frame))
}

/// Makes every pass of `plan` on the GPU as the runner would, the
/// classification included, with the frame the plan implies: returns how
/// many pipelines were made.
#[cfg(all(test, feature = "interpolate"))]
pub fn build_passes(
    gpu: &Gpu,
    plan: &Plan,
    shader: impl Fn(&str) -> Option<String>,
    options: PipelineOptions,
) -> Result<usize, String> {
    let options = RunOptions {
        pipelines: options,
        classify: true,
        external_group: None,
    };
    let (cached, _) = cached_shader(gpu, plan, shader, (1, 1), options)?;
    Ok(cached.plan().passes.len() + usize::from(cached.plan().classify.is_some()))
}

//! What a profile measures, before anything is drawn: the frame counts,
//! the buffers the draw binds, the analysis bounded by the scene's values,
//! the nodes the grid keeps with their settings, and the rewrite options
//! every run shares.

use std::collections::HashSet;

use super::grid::{Grid, Setting};
use super::{Options, MEASURED_COLOR_FORMAT};
use crate::analysis::{Analysis, Candidate};
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::fail;
use crate::measure::setup::{check_counts, scene_bindings, SceneBindings};
use crate::rewrite::Options as RewriteOptions;
use crate::scene::storage::StorageBuffer;
use crate::scene::uniforms::UniformBuffer;
use crate::scene::Scene;

/// A profile's plan of work.
pub(super) struct Prepared {
    pub size: [u32; 2],
    pub aspect: f32,
    /// Frames measured, and warm-up frames before them.
    pub frames: u32,
    pub warmup: u32,
    /// Whether every measured frame sees the cache in its steady state
    /// (the warm-up covers the longest refresh period).
    pub steady_state: bool,
    /// The name and (group, binding) of every resource the draw binds.
    pub used: HashSet<(String, [u32; 2])>,
    pub uniforms: Vec<UniformBuffer>,
    pub storage: Vec<StorageBuffer>,
    pub analysis: Analysis,
    /// The candidates asked for, in the grid's node order.
    pub selected: Vec<Candidate>,
    pub grid: Grid,
    /// The grid's base setting, and the rewrite options it gives.
    pub base_setting: Setting,
    pub base: RewriteOptions,
    /// The options every rewrite starts from: the scene's depth convention,
    /// the vertex entry point, the measured colour format.
    pub defaults: RewriteOptions,
}

impl Prepared {
    /// The nodes the grid kept, with their settings.
    pub fn nodes(&self) -> Vec<(&Candidate, &[Setting])> {
        self.selected
            .iter()
            .zip(&self.grid.settings)
            .filter(|(_, settings)| !settings.is_empty())
            .map(|(candidate, settings)| (candidate, settings.as_slice()))
            .collect()
    }
}

/// Checks the scene against what the shader reads and plans the profile.
pub(super) fn prepare(
    shader: &Shader,
    scene: &Scene,
    options: &Options,
) -> Result<Prepared, Error> {
    let size = options.size.unwrap_or(scene.size);
    let longest_period = options.axes().refresh_periods.iter().copied().max();
    let frames = options.frames.unwrap_or(scene.frames);
    let warmup = options
        .warmup
        .unwrap_or_else(|| scene.warmup.max(longest_period.unwrap_or(0)));
    check_counts(size, frames, options.warmup.unwrap_or(0))?;
    let SceneBindings {
        aspect,
        used,
        uniforms,
        storage,
        analysis,
    } = scene_bindings(
        shader,
        scene,
        (options.entry.as_deref(), options.vertex_entry.as_deref()),
        size,
        warmup + frames,
    )?;
    let selected: Vec<Candidate> = analysis
        .select(&shader.file, &options.nodes)?
        .into_iter()
        .cloned()
        .collect();
    let estimates: Vec<(String, f64)> = selected
        .iter()
        .map(|c| (c.node.id.clone(), c.ratio))
        .collect();
    let grid = Grid::new(
        options.axes(),
        options.design,
        &estimates,
        options.variants.len(),
    );
    let base_setting = grid
        .axes
        .base()
        .ok_or_else(|| fail("every knob needs at least one value to measure".into()))?;
    // Frames are rendered to rgba16float and compared in linear float: an
    // 8-bit target would clamp what is above 1 and quantise the rest.
    let defaults = RewriteOptions {
        depth: scene.camera.depth,
        vertex_entry: options.vertex_entry.clone(),
        color_format: MEASURED_COLOR_FORMAT,
        deforming_inputs: deforming_inputs(
            shader,
            scene,
            (analysis.entry_index, options.vertex_entry.as_deref()),
        ),
        upsampling: options.upsampling.clone(),
        ..RewriteOptions::default()
    };
    Ok(Prepared {
        size,
        aspect,
        frames,
        warmup,
        steady_state: longest_period.is_none_or(|period| warmup >= period),
        used,
        uniforms,
        storage,
        selected,
        grid,
        base: base_setting.rewrite_options(&defaults),
        base_setting,
        defaults,
        analysis,
    })
}

/// The per-vertex inputs the scene's CPU deformation changes: when an
/// object ripples (`deformation`), those the mesh feeds with its positions,
/// normals or tangents. Their twins read last frame's vertex buffer. A
/// fragment-only module has none.
fn deforming_inputs(
    shader: &Shader,
    scene: &Scene,
    (fragment, vertex_entry): (usize, Option<&str>),
) -> Vec<String> {
    let ripples = scene.has(crate::scene::Effect::Deformation)
        && scene.objects.iter().any(|o| o.deformation.is_some());
    let module = &shader.module;
    let Some(vertex) = ripples
        .then(|| crate::proc::vertex_entry(module, fragment, vertex_entry).ok())
        .flatten()
    else {
        return Vec::new();
    };
    let function = &module.entry_points[vertex].function;
    let per_instance = crate::proc::instance_locations(module, function);
    crate::proc::inputs(module, function)
        .into_iter()
        .filter_map(|input| {
            let location = crate::proc::location_of(input.binding)?;
            let name = input.name?;
            use crate::scene::mesh::VertexSource as S;
            // A constant the scene gives it does not move.
            let moved = !scene.vertex_inputs.contains_key(name)
                && matches!(
                    S::of_mesh(name, location),
                    Some(S::Position | S::Normal | S::Tangent)
                );
            (moved && !per_instance.contains(&location)).then(|| name.clone())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A library caller's counts are bounded as the command line's are:
    /// no frame count of 0 silently made 1, no four billion frames.
    #[test]
    fn counts_beyond_the_bounds_are_errors() {
        assert!(check_counts([64, 64], 1, 0).is_ok());
        for (size, frames, warmup, says) in [
            ([64, 64], 0, 0, "1 to 10000"),
            ([64, 64], 4_000_000_000, 0, "1 to 10000"),
            ([64, 64], 1, 4_000_000_000, "at most 10000"),
            ([0, 64], 1, 0, "between 1 and 8192"),
        ] {
            let err = check_counts(size, frames, warmup).unwrap_err().render();
            assert!(err.contains(says), "{err}");
        }
    }
}

//! Payload interpolation: the reprojection cache's split of the shader
//! at a node, used between I-frames: what Yang et al. 2011 §9 proposes
//! for its terrain and does not evaluate (reprojecting the pixel shader's
//! inputs and shading each B-frame anew). Unlike that proposal, each
//! B-frame here rasterises the geometry again.
//!
//! Every warping method moves the I-frames' *colours*; what a light or
//! the view changed in between is dragged along the flow with the
//! surface (seed 000 §6's limitation: a moving highlight, a light
//! orbiting a still object). Here the cache's three-pass rewrite
//! ([`crate::rewrite`], seed 002 §3) splits the fragment stage at a node
//! into a payload (the node's backward slice: the marble's albedo, a
//! material's inputs) and a shade (the rest: lights, view-dependent
//! terms):
//! - at each I-frame, three-pass's payload pass (its pass 2, drawn over
//!   every pixel with its own depth test) writes the node's value into a
//!   payload texture: one more geometry pass an I-frame, counted in its
//!   I-frame time;
//! - at each B-frame, image-based's search (000 §5, the same pass and
//!   decisions as the colours', in [`super::bframe`]) interpolates the
//!   two I-frames' payloads bidirectionally, read through their flows,
//!   and three-pass's shade pass (its pass 3, drawn at the B-frame's
//!   time with the B-frame's uniforms and its own depth test) shades
//!   every pixel from that payload at the pixel.
//!
//! The payload must not read what changes between frames (the light,
//! the camera, time), or it freezes at the I-frames' values: by default
//! the node is the analysis's highest-ranked candidate that reads no
//! per-frame input (`Candidate::depends_on` empty); `--node` names
//! another. The B-frame search filters the payload bilinearly, so it is
//! kept in `rgba16float`: of those candidates the first the analysis
//! bounds within it is taken, and a node that may not fit is refused
//! with the reason.
//!
//! The shade pass reads the payload texture the rewrite binds as "this
//! frame's cache" in the cache's group; here it is moved, on IR, to a
//! group of its own after the shader's, which the run binds to the
//! interpolated payload (`RunOptions::external_group`).

use naga::ResourceBinding;

use crate::analysis::{Analysis, Candidate};
use crate::front::Shader;
use crate::plan::{CacheFormat, LoadOp, Pass, Plan, Resource, ResourceKind, Variant};
use crate::rewrite::{self, Refusal};

/// The name the shade pass's payload texture has in the module.
const PAYLOAD_TEXTURE: &str = "cache_current_payload";

/// Three-pass's payload pass and its shade pass, by index in its plan.
const PAYLOAD_PASS: usize = 1;
const SHADE_PASS: usize = 2;

/// The two passes payload interpolation draws, as plans the runtime runs.
#[derive(Debug)]
pub struct PayloadPasses {
    /// The node cached, its id and source text.
    pub node: (String, String),
    /// At each I-frame: the payload into the plan's cache target.
    pub iframe: Plan,
    /// At each B-frame: the shading from the payload at the pixel, which
    /// it reads at `[payload_group, 0]`.
    pub shade: Plan,
    /// The bind group the shade pass reads the interpolated payload from.
    pub payload_group: u32,
    /// The passes' WGSL, by the plans' shader names.
    pub sources: std::collections::HashMap<String, String>,
}

/// The node to interpolate when none is named: the highest-ranked
/// candidate whose slice reads no per-frame input, of those first whose
/// value provably fits `rgba16float`. (A named one is
/// `Analysis::select`'s, with its diagnostics.)
pub fn choose(analysis: &Analysis) -> Result<&Candidate, String> {
    let steady = || {
        analysis
            .candidates
            .iter()
            .filter(|c| c.depends_on.is_empty())
    };
    // One the search can filter first (`passes` refuses the others).
    let fits = steady().find(|c| c.fits_f16);
    fits.or_else(|| steady().next()).ok_or_else(|| {
            let read: Vec<String> = analysis
                .candidates
                .iter()
                .flat_map(|c| c.depends_on.iter().cloned())
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .collect();
            format!(
                "every candidate node reads per-frame inputs ({}), which an interpolated payload would freeze at the I-frames' values; name one with --node to interpolate it anyway",
                if read.is_empty() { "none found".to_string() } else { read.join(", ") }
            )
        })
}

/// Builds the two passes for `candidate` with `options` (the run's
/// rewrite options): three-pass's payload and shade passes, each drawn
/// alone with the reference's depth test.
pub fn passes(
    shader: &Shader,
    analysis: &Analysis,
    candidate: &Candidate,
    options: &rewrite::Options,
    reference: &Plan,
) -> Result<PayloadPasses, Refusal> {
    let options = rewrite::Options {
        cache_format: CacheFormat::Rgba16float,
        ..options.clone()
    };
    let rewritten = rewrite::rewrite(shader, analysis, candidate, Variant::ThreePass, &options)?;
    if rewritten.plan.cache.format != CacheFormat::Rgba16float {
        return Err(Refusal::new(format!(
            "the payload (node {}) may not fit rgba16float, the format the B-frame search filters (the rewrite says: {})",
            candidate.node.id,
            rewritten
                .plan
                .cache
                .format_note
                .as_deref()
                .unwrap_or("the analysis cannot bound it")
        )));
    }
    let depth = reference
        .passes
        .first()
        .ok_or_else(|| Refusal::internal("the reference plan has no pass"))?
        .depth
        .clone();
    let pass = |index: usize, name: &str| -> Result<Pass, Refusal> {
        let mut pass = rewritten
            .plan
            .passes
            .get(index)
            .cloned()
            .ok_or_else(|| Refusal::internal("three-pass has fewer than three passes"))?;
        pass.name = name.to_string();
        pass.shader = format!("{name}.wgsl");
        pass.stage_shaders.clear();
        pass.depth = depth.clone();
        pass.stencil = None;
        for target in &mut pass.color_targets {
            target.load = LoadOp::Clear;
        }
        Ok(pass)
    };

    let mut iframe = rewritten.plan.clone();
    iframe.classify = None;
    iframe.passes = vec![pass(PAYLOAD_PASS, "payload_iframe")?];
    iframe.passes[0].role = "every pixel (depth test): the payload into the cache".into();
    let payload_text = pass_text(&rewritten.passes[PAYLOAD_PASS])?;

    let mut module = rewritten.passes[SHADE_PASS].module.clone();
    let payload_group = move_payload_texture(&mut module)?;
    let info = crate::front::validate(&module).map_err(|err| {
        Refusal::internal(format!("the payload's shade pass does not validate: {err}"))
    })?;
    let shade_text = crate::back::wgsl_text(&module, &info).map_err(Refusal::internal)?;
    let mut shade = rewritten.plan.clone();
    shade.classify = None;
    let cache_group = rewritten.plan.bindings.cache.first().map(|r| r.group);
    let mut shade_pass = pass(SHADE_PASS, "payload_shade")?;
    shade_pass.role =
        "every pixel (depth test), at the B-frame's time: shade from the interpolated payload at the pixel"
            .into();
    shade_pass.bindings.retain(|b| Some(b[0]) != cache_group);
    shade_pass.bindings.push([payload_group, 0]);
    shade.passes = vec![shade_pass];
    shade.bindings.cache.clear();
    shade.bindings.previous.clear();
    shade.bindings.original.push(Resource {
        group: payload_group,
        binding: 0,
        name: PAYLOAD_TEXTURE.into(),
        kind: ResourceKind::Texture,
        source: Some("the B-frame's payload, interpolated from the I-frames'".into()),
    });
    Ok(PayloadPasses {
        node: (candidate.node.id.clone(), candidate.node.text.clone()),
        sources: [
            ("payload_iframe.wgsl".to_string(), payload_text),
            ("payload_shade.wgsl".to_string(), shade_text),
        ]
        .into(),
        iframe,
        shade,
        payload_group,
    })
}

/// A pass module's WGSL.
fn pass_text(pass: &rewrite::PassModule) -> Result<String, Refusal> {
    crate::back::wgsl_text(&pass.module, &pass.info).map_err(Refusal::internal)
}

/// Moves the shade pass's payload texture out of the cache's group into
/// `[g, 0]`, g the group after every other resource's; returns g.
fn move_payload_texture(module: &mut naga::Module) -> Result<u32, Refusal> {
    let handle = module
        .global_variables
        .iter()
        .find(|(_, g)| g.name.as_deref() == Some(PAYLOAD_TEXTURE))
        .map(|(h, _)| h)
        .ok_or_else(|| Refusal::internal("the shade pass reads no payload texture"))?;
    let group = module
        .global_variables
        .iter()
        .filter(|(h, _)| *h != handle)
        .filter_map(|(_, g)| g.binding.as_ref().map(|b| b.group + 1))
        .max()
        .unwrap_or(0);
    module.global_variables[handle].binding = Some(ResourceBinding { group, binding: 0 });
    Ok(group)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn analysed(source: &str) -> (Shader, Analysis) {
        let shader = crate::front::parse(crate::diagnostic::SourceFile::new("test.wgsl", source))
            .expect("parses");
        let analysis = crate::analysis::analyze(&shader, &Default::default()).expect("analyses");
        (shader, analysis)
    }

    #[test]
    fn payload_passes_are_three_pass_payload_and_shade() {
        assert_eq!(
            rewrite::payload_pass(Variant::ThreePass),
            Some(PAYLOAD_PASS)
        );
        let (shader, analysis) = analysed(include_str!("../../corpus/noise_marble.wgsl"));
        let candidate = choose(&analysis).expect("the marble's albedo reads no per-frame input");
        assert!(candidate.depends_on.is_empty());
        assert!(
            candidate.node.text.contains("mix(vein_color"),
            "{}",
            candidate.node.text
        );
        let options = rewrite::Options::default();
        let reference = crate::rewrite::plan::reference(&shader, &analysis, &options).unwrap();
        let passes = passes(&shader, &analysis, candidate, &options, &reference).unwrap();
        // The shader binds group 0 only: the payload texture takes group 1,
        // and no cache group is left in the shade pass.
        assert_eq!(passes.payload_group, 1);
        assert!(passes.shade.bindings.cache.is_empty());
        assert_eq!(passes.shade.passes[0].bindings, vec![[0, 0], [1, 0]]);
        assert!(passes.sources["payload_shade.wgsl"]
            .contains("@group(1) @binding(0) \nvar cache_current_payload"));
        // Each drawn alone, with the reference's depth test.
        for plan in [&passes.iframe, &passes.shade] {
            assert_eq!(plan.passes.len(), 1);
            assert_eq!(plan.passes[0].depth, reference.passes[0].depth);
            plan.check().unwrap();
        }
        assert_eq!(
            passes.iframe.passes[0].color_targets[0].target,
            crate::plan::TargetKind::Cache
        );
    }

    #[test]
    fn payload_refused_where_every_candidate_reads_per_frame_inputs() {
        let (_, analysis) = analysed(
            "struct Frame { light: vec4<f32>, time: f32 }
             @group(0) @binding(0) var<uniform> frame: Frame;
             @fragment fn fs_main(@location(0) world: vec3<f32>) -> @location(0) vec4<f32> {
                 let a = sin(frame.light.xyz * world + frame.time);
                 let b = cos(a * a + exp(a)) * sin(a * 3.0 + frame.time);
                 return vec4<f32>(pow(abs(b), vec3<f32>(2.2)) + sqrt(abs(a)), 1.0);
             }",
        );
        assert!(!analysis.candidates.is_empty());
        let reason = choose(&analysis).unwrap_err();
        assert!(reason.contains("per-frame inputs (light"), "{reason}");
        assert!(reason.contains("--node"), "{reason}");
    }
}

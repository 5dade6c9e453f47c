//! The `CacheParams` uniform: each field the plan lays out, at its
//! offset, filled by its name.

use shadecache_plan::{CacheFormat, Field, Plan};

use crate::Error;

/// Bytes of the uniform: its fields' end rounded up to 16 (WGSL's uniform
/// layout), at least 16.
pub(crate) fn size(fields: &[Field]) -> Result<usize, Error> {
    let mut end = 0;
    for field in fields {
        let width = match field.ty.as_str() {
            "f32" | "u32" | "i32" => 4,
            "vec2<f32>" | "vec2<u32>" => 8,
            "vec4<f32>" | "vec4<u32>" => 16,
            other => {
                return Err(Error::Plan(format!(
                    "CacheParams field `{}` has a type this host cannot write: {other}",
                    field.name
                )))
            }
        };
        end = end.max(field.offset as usize + width);
    }
    Ok(end.div_ceil(16).max(1) * 16)
}

/// The frame's state the uniform carries.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameState {
    /// The target's size.
    pub size: (u32, u32),
    /// The viewport in it: x, y, width, height.
    pub viewport: [f32; 4],
    /// c, the frame counter.
    pub frame: u64,
    /// c mod Δn, advanced with it.
    pub phase: u32,
    /// The camera's far − near; 0 where not given.
    pub depth_range: f32,
}

fn vec2(x: f32, y: f32) -> Vec<u8> {
    [x, y].iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The uniform's bytes for a frame.
pub(crate) fn bytes(plan: &Plan, state: FrameState) -> Result<Vec<u8>, Error> {
    let refresh = &plan.refresh;
    let mut bytes = vec![0u8; size(&plan.cache.params)?];
    for field in &plan.cache.params {
        let value: Vec<u8> = match field.name.as_str() {
            "viewport" => vec2(state.viewport[2], state.viewport[3]),
            "viewport_origin" => vec2(state.viewport[0], state.viewport[1]),
            "target_size" => vec2(state.size.0 as f32, state.size.1 as f32),
            "depth_epsilon" => refresh.depth_epsilon.to_le_bytes().to_vec(),
            "refresh_phase" => state.phase.to_le_bytes().to_vec(),
            "refresh_period" => refresh.period.to_le_bytes().to_vec(),
            "refresh_quad" => refresh.quad.to_le_bytes().to_vec(),
            "frame" => (state.frame as u32).to_le_bytes().to_vec(),
            // The largest value the payload texture holds: what is above
            // it is "no value".
            "payload_limit" => match plan.cache.format {
                CacheFormat::Rgba16float => 65504.0f32,
                CacheFormat::Rgba32float => f32::MAX,
            }
            .to_le_bytes()
            .to_vec(),
            // The depth test's tolerance is relative to it.
            "far_depth" => (plan.clear.depth as f32).to_le_bytes().to_vec(),
            // Lowres's knobs; zero for the variants without them.
            "upsample_sigma_normal" => upsampling(plan, |u| u.sigma_normal),
            "upsample_sigma_depth" => upsampling(plan, |u| u.sigma_depth),
            "upsample_sensitivity" => upsampling(plan, |u| u.sensitivity),
            "upsample_depth_range" => state.depth_range.to_le_bytes().to_vec(),
            other => {
                return Err(Error::Plan(format!(
                    "the plan's CacheParams has a field `{other}` this host does not fill"
                )))
            }
        };
        let at = field.offset as usize;
        bytes
            .get_mut(at..at + value.len())
            .ok_or_else(|| {
                Error::Plan(format!(
                    "CacheParams field `{}` lies outside it",
                    field.name
                ))
            })?
            .copy_from_slice(&value);
    }
    Ok(bytes)
}

/// One of the plan's upsampling knobs as uniform bytes (0 without them).
fn upsampling(plan: &Plan, knob: impl Fn(&shadecache_plan::Upsampling) -> f32) -> Vec<u8> {
    plan.upsampling
        .as_ref()
        .map_or(0.0, knob)
        .to_le_bytes()
        .to_vec()
}

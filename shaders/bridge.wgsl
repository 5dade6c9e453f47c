// Z-buffer bridging (seed 000 §6, Fig. 4): an interpolated frame's colour
// and depth copied into the targets of a pass that then rasterises the
// objects drawn at every displayed frame (thin, fast geometry the
// interpolation cannot follow), depth-tested against what the
// interpolation shows. One fullscreen pass; its depth attachment takes
// `frag_depth` with the test off.

@group(0) @binding(0) var frame_color: texture_2d<f32>;
// The frame's depth as a depth buffer (an I-frame's, a geometry pass's)...
@group(0) @binding(1) var frame_depth: texture_depth_2d;
// ...or as the depth image-based's search chose (r32float).
@group(0) @binding(2) var chosen_depth: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0), 0.0, 1.0);
}

struct Bridged {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_bridge_depth(@builtin(position) frag_coord: vec4<f32>) -> Bridged {
    let at = vec2<i32>(frag_coord.xy);
    return Bridged(textureLoad(frame_color, at, 0), textureLoad(frame_depth, at, 0));
}

@fragment
fn fs_bridge_chosen(@builtin(position) frag_coord: vec4<f32>) -> Bridged {
    let at = vec2<i32>(frag_coord.xy);
    return Bridged(textureLoad(frame_color, at, 0), textureLoad(chosen_depth, at, 0).x);
}

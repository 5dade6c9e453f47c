// The I-frame's flow fields (seed 000 §5, eqs. 1–2), imported at IR level
// into the user's module by the interpolation stage. The rewriter assigns
// the bind group (the first one the user's shader leaves free); the host
// fills `flow_params` and the twins of the position's resources with the
// previous and the next I-frame's contents.
//
// A flow is stored per pixel of the I-frame: where the surface point seen
// at this pixel is at another time, relative to here. x and y are in
// pixels (x right, y down), z in NDC depth; w is 0 where the flow is not
// valid (the other clip position behind the camera or a component not
// finite), with x, y, z zero, and else 1 on a still object and 2 on one
// that moves (seed 003's dynamic-object mask).

struct FlowParams {
    // The frame's size in pixels.
    viewport: vec2<f32>,
    // 1 when the object drawn moves in the world, 0 when it is still.
    moving: f32,
    // Keeps the struct 16 bytes.
    padding: f32,
}

@group(1) @binding(0) var<uniform> flow_params: FlowParams;

// The largest flow component stored: the targets are rgba16float, whose
// largest finite value is 65504.
const FLOW_LIMIT: f32 = 65000.0;

// Whether every component is finite, by its exponent bits: WGSL lets
// compilers assume floats are never NaN or infinite, so `x != x` may be
// folded away.
fn flow_finite(v: vec4<f32>) -> bool {
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

// The flow from the fragment at `frag_coord` (its `@builtin(position)`) to
// the same surface point's clip position `other` at another time,
// perspective-interpolated from the vertices as the cache's previous clip
// position is.
fn flow_to(frag_coord: vec4<f32>, other: vec4<f32>) -> vec4<f32> {
    let ndc = other.xyz / other.w;
    let pixel = vec2<f32>(
        (ndc.x * 0.5 + 0.5) * flow_params.viewport.x,
        (0.5 - 0.5 * ndc.y) * flow_params.viewport.y,
    );
    let flow = vec4<f32>(pixel - frag_coord.xy, ndc.z - frag_coord.z, 1.0 + flow_params.moving);
    let valid = (other.w > 1e-6) & flow_finite(other) & flow_finite(flow)
        & all(abs(flow.xyz) < vec3<f32>(FLOW_LIMIT));
    return select(vec4<f32>(0.0), flow, valid);
}

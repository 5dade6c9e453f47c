// A fragment stage whose cost is nearly all in one smooth value (400
// waves summed in a loop): cached, it is reliably faster, even on a CPU
// rasteriser, so a profile's answer has a winner to measure again.

struct Camera {
    clip_from_world: mat4x4<f32>,
}
@group(0) @binding(0) var<uniform> camera: Camera;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) local_position: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = camera.clip_from_world * vec4<f32>(position, 1.0);
    out.local_position = position;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    var pattern = 0.0;
    for (var i = 0; i < 400; i++) {
        let f = 1.0 + f32(i) * 0.005;
        pattern += sin(in.local_position.x * f + cos(in.local_position.y * f)) / f;
    }
    let shade = 0.5 + 0.5 * sin(pattern * 0.005);
    return vec4<f32>(vec3<f32>(shade), 1.0);
}

// Per-pixel values of a surface, a dither over the pixel's own screen
// position, and values that read time and the camera: what the analysis
// must flag (screen-space, per-frame) and what it may cache.
struct Frame {
    time: f32,
    camera_position: vec3<f32>,
}
@group(0) @binding(0) var<uniform> frame: Frame;

@fragment
fn fs(@builtin(position) pixel: vec4<f32>, @location(0) world: vec3<f32>) -> @location(0) vec4<f32> {
    let dither = fract(sin(dot(pixel.xy, vec2<f32>(12.9898, 78.233))) * 43758.5453);
    let depth_fog = exp(-pixel.z * 4.0);
    let pattern = sin(world.x * 10.0) * cos(world.y * 7.0);
    let pulse = sin(world.x * 10.0 + frame.time) * cos(world.y * 7.0);
    let view_distance = length(frame.camera_position - world);
    var detail = 0.0;
    for (var i = 0; i < 16; i++) {
        detail += sin(world.z * f32(i));
    }
    return vec4<f32>(vec3<f32>(pattern * depth_fog + dither * 0.01 + pulse + view_distance + detail), 1.0);
}

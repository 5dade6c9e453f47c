// Directional blur with a run-time tap count, then lighting.
//
// The fragment entry point averages texture samples along a direction in
// texture space (like a motion or anisotropic blur). The number of taps is
// a uniform value, so the loop's trip count is not known when the shader is
// compiled. The values inside the loop change every iteration; the work
// after the loop (tone adjustment and lighting) uses the averaged result.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    // Blur direction in texture space; its length is the spacing of taps.
    blur_direction: vec2<f32>,
    // Saturation applied after the blur (1 = unchanged).
    saturation: f32,
    // Number of taps of the blur (clamped to 64 in the shader).
    sample_count: u32,
    light_position: vec3<f32>,
    time: f32,
    light_color: vec3<f32>,
    ambient: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var color_texture: texture_2d<f32>;
@group(0) @binding(2) var color_sampler: sampler;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(in.position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = (frame.world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    out.uv = in.uv;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    // Tap count from the uniform; the blur is centred on the pixel's uv.
    let taps = clamp(frame.sample_count, 1u, 64u);
    let half_span = 0.5 * f32(taps - 1u);
    let start_uv = in.uv - (half_span * frame.blur_direction);

    // Tent-weighted average along the blur direction. Explicit level 0:
    // the loop bound comes from a uniform, but explicit sampling keeps the
    // shader valid wherever the loop ends up.
    var sum = vec3<f32>(0.0);
    var weight_sum = 0.0;
    for (var i = 0u; i < taps; i++) {
        let t = f32(i);
        let weight = 1.0 + half_span - abs(t - half_span);
        let uv = start_uv + (t * frame.blur_direction);
        sum += weight * textureSampleLevel(color_texture, color_sampler, uv, 0.0).rgb;
        weight_sum += weight;
    }

    // Work after the loop, on the averaged colour.
    let blurred = sum / weight_sum;
    let luminance = dot(blurred, vec3<f32>(0.2126, 0.7152, 0.0722));
    let albedo = max(mix(vec3<f32>(luminance), blurred, frame.saturation), vec3<f32>(0.0));

    // Lambert plus a soft wrap term from a point light.
    let n = normalize(in.world_normal);
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let wrap = max((dot(n, l) + 0.3) / 1.3, 0.0);
    let falloff = 1.0 / (1.0 + (0.03 * dot(to_light, to_light)));
    let color = albedo * ((frame.light_color * (wrap * falloff)) + vec3<f32>(frame.ambient));
    return vec4<f32>(color, 1.0);
}

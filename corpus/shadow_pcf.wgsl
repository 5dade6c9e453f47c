// Diffuse lighting with a percentage-closer-filtered shadow map.
//
// The fragment stage projects its world position into the light's clip
// space, then takes a 4x4 grid of depth comparisons around that point
// (textureSampleCompareLevel in a constant-bound loop inside a helper) and
// averages them into a soft visibility term.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    // View-projection of the light that rendered the shadow map.
    light_clip_from_world: mat4x4<f32>,
    light_position: vec3<f32>,
    // Depth bias against shadow acne, in light NDC depth units.
    shadow_bias: f32,
    light_color: vec3<f32>,
    // Spacing of the PCF taps in shadow-map texels.
    pcf_spread: f32,
    albedo: vec3<f32>,
    ambient: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var shadow_map: texture_depth_2d;
@group(0) @binding(2) var shadow_sampler: sampler_comparison;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
}

@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(in.position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = (frame.world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    return out;
}

// Fraction of a 4x4 neighbourhood of shadow-map texels around uv that is lit
// at the given receiver depth (1 = fully lit, 0 = fully in shadow).
fn pcf_visibility(uv: vec2<f32>, receiver_depth: f32) -> f32 {
    let texel = frame.pcf_spread / vec2<f32>(textureDimensions(shadow_map));
    var lit = 0.0;
    for (var i = 0; i < 4; i++) {
        for (var j = 0; j < 4; j++) {
            // Offsets -1.5, -0.5, 0.5, 1.5 texels: centred on uv.
            let offset = vec2<f32>(f32(i) - 1.5, f32(j) - 1.5) * texel;
            lit += textureSampleCompareLevel(shadow_map, shadow_sampler, uv + offset, receiver_depth);
        }
    }
    return lit / 16.0;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    // Position in the light's clip space, then its shadow-map coordinates
    // (NDC y points up, texture v points down).
    let light_clip = frame.light_clip_from_world * vec4<f32>(in.world_position, 1.0);
    let light_ndc = light_clip.xyz / light_clip.w;
    let shadow_uv = (light_ndc.xy * vec2<f32>(0.5, -0.5)) + vec2<f32>(0.5);
    let receiver_depth = light_ndc.z - frame.shadow_bias;

    // Soft shadow from 16 comparisons.
    let visibility = pcf_visibility(shadow_uv, receiver_depth);

    // Lambert diffuse from a point light.
    let n = normalize(in.world_normal);
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let n_dot_l = max(dot(n, l), 0.0);
    let falloff = 1.0 / (1.0 + (0.02 * dot(to_light, to_light)));
    let diffuse = frame.light_color * (n_dot_l * falloff * visibility);

    // Depends only on the uniform: the same for every pixel.
    let ambient_term = frame.albedo * frame.ambient;

    let color = ambient_term + (frame.albedo * diffuse);
    return vec4<f32>(color, 1.0);
}

// A forward pass and its shadow pass in one module, as wgpu's `shadow`
// example keeps them: a depth-only vertex stage for the shadow maps and a
// main vertex stage, each fragment stage taking the struct one of them
// returns, integer vertex positions and normals, and the lights bound at
// one slot either as storage (`fs_main`) or as a uniform array
// (`fs_main_uniform_lights`, for adapters without storage in fragment
// shaders). Lighting: a loop over the lights, each with a 3×3 PCF
// shadow lookup into a depth texture array.

struct Globals {
    view_proj: mat4x4<f32>,
    num_lights: vec4<u32>,
}
@group(0) @binding(0) var<uniform> u_globals: Globals;

struct Entity {
    world: mat4x4<f32>,
    color: vec4<f32>,
}
@group(1) @binding(0) var<uniform> u_entity: Entity;

@vertex
fn vs_shadow(@location(0) position: vec4<i32>) -> @builtin(position) vec4<f32> {
    return u_globals.view_proj * u_entity.world * vec4<f32>(position);
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_normal: vec3<f32>,
    @location(1) world_position: vec4<f32>,
}

@vertex
fn vs_main(@location(0) position: vec4<i32>, @location(1) normal: vec4<i32>) -> VertexOutput {
    let world = u_entity.world;
    let world_position = world * vec4<f32>(position);
    var out: VertexOutput;
    out.world_normal = mat3x3<f32>(world[0].xyz, world[1].xyz, world[2].xyz) * vec3<f32>(normal.xyz);
    out.world_position = world_position;
    out.clip_position = u_globals.view_proj * world_position;
    return out;
}

struct Light {
    view_proj: mat4x4<f32>,
    position: vec4<f32>,
    color: vec4<f32>,
}

const MAX_LIGHTS: u32 = 8u;

@group(0) @binding(1) var<storage, read> s_lights: array<Light>;
@group(0) @binding(1) var<uniform> u_lights: array<Light, 8>;
@group(0) @binding(2) var t_shadow: texture_depth_2d_array;
@group(0) @binding(3) var sampler_shadow: sampler_comparison;

// 3×3 percentage-closer filtering in layer `layer` of the shadow maps.
fn shadow_factor(layer: u32, light_clip: vec4<f32>) -> f32 {
    if (light_clip.w <= 0.0) {
        return 1.0;
    }
    let ndc = light_clip.xyz / light_clip.w;
    let uv = ndc.xy * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5, 0.5);
    let texel = 1.0 / 1024.0;
    var lit = 0.0;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            let offset = vec2<f32>(f32(x), f32(y)) * texel;
            lit += textureSampleCompareLevel(t_shadow, sampler_shadow, uv + offset, i32(layer), ndc.z - 0.002);
        }
    }
    return lit / 9.0;
}

fn lambert(light: Light, normal: vec3<f32>, world_position: vec3<f32>) -> vec3<f32> {
    let to_light = light.position.xyz - world_position;
    let falloff = 1.0 / (1.0 + 0.05 * dot(to_light, to_light));
    return max(dot(normal, normalize(to_light)), 0.0) * falloff * light.color.rgb;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let normal = normalize(in.world_normal);
    var color = vec3<f32>(0.05);
    for (var i = 0u; i < min(u_globals.num_lights.x, MAX_LIGHTS); i++) {
        let light = s_lights[i];
        let shadow = shadow_factor(i, light.view_proj * in.world_position);
        color += shadow * lambert(light, normal, in.world_position.xyz);
    }
    return vec4<f32>(color, 1.0) * u_entity.color;
}

@fragment
fn fs_main_uniform_lights(in: VertexOutput) -> @location(0) vec4<f32> {
    let normal = normalize(in.world_normal);
    var color = vec3<f32>(0.05);
    for (var i = 0u; i < min(u_globals.num_lights.x, MAX_LIGHTS); i++) {
        let light = u_lights[i];
        let shadow = shadow_factor(i, light.view_proj * in.world_position);
        color += shadow * lambert(light, normal, in.world_position.xyz);
    }
    return vec4<f32>(color, 1.0) * u_entity.color;
}

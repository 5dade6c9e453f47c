// A physically based material the way engines write one (after the shape of
// Bevy's `pbr.wgsl`): bind groups per frequency (view, material, mesh),
// material features switched by bits of `material.flags`, the result carried
// in the local `output_color`, the lit path under `if ((flags & UNLIT) ==
// 0u)`, a BRDF in helper functions and a loop over the view's lights.
//
// The lights are a ring of `view.light_count` point lights around
// `view.light_position`, each a little dimmer than the last, so that the
// loop's trip count is a uniform, as it is for engines' light lists.

const BASE_COLOR_TEXTURE_BIT: u32 = 1u;
const ROUGHNESS_TEXTURE_BIT: u32 = 2u;
const UNLIT_BIT: u32 = 4u;
const PI: f32 = 3.141592653589793;

struct View {
    clip_from_world: mat4x4<f32>,
    camera_position: vec3<f32>,
    light_count: u32,
    light_position: vec3<f32>,
    light_radius: f32,
    light_color: vec3<f32>,
    exposure: f32,
}

struct StandardMaterial {
    base_color: vec4<f32>,
    emissive: vec4<f32>,
    perceptual_roughness: f32,
    metallic: f32,
    reflectance: f32,
    flags: u32,
}

struct Mesh {
    world_from_local: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(1) @binding(0) var<uniform> material: StandardMaterial;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var base_color_sampler: sampler;
@group(1) @binding(3) var roughness_texture: texture_2d<f32>;
@group(2) @binding(0) var<uniform> mesh: Mesh;

struct Vertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct MeshVertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec4<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vertex(vertex: Vertex) -> MeshVertexOutput {
    var out: MeshVertexOutput;
    out.world_position = mesh.world_from_local * vec4<f32>(vertex.position, 1.0);
    out.clip_position = view.clip_from_world * out.world_position;
    out.world_normal = normalize((mesh.world_from_local * vec4<f32>(vertex.normal, 0.0)).xyz);
    out.uv = vertex.uv;
    return out;
}

struct PbrInput {
    base_color: vec4<f32>,
    perceptual_roughness: f32,
    metallic: f32,
    reflectance: f32,
    world_position: vec3<f32>,
    N: vec3<f32>,
    V: vec3<f32>,
}

fn perceptual_roughness_to_roughness(perceptual_roughness: f32) -> f32 {
    let clamped = clamp(perceptual_roughness, 0.089, 1.0);
    return clamped * clamped;
}

// GGX normal distribution.
fn D_GGX(roughness: f32, NoH: f32) -> f32 {
    let one_minus = 1.0 - NoH * NoH;
    let a = NoH * roughness;
    let k = roughness / (one_minus + a * a);
    return k * k * (1.0 / PI);
}

// Height-correlated Smith visibility.
fn V_SmithGGXCorrelated(roughness: f32, NoV: f32, NoL: f32) -> f32 {
    let a2 = roughness * roughness;
    let lambda_v = NoL * sqrt((NoV - a2 * NoV) * NoV + a2);
    let lambda_l = NoV * sqrt((NoL - a2 * NoL) * NoL + a2);
    return 0.5 / (lambda_v + lambda_l);
}

fn F_Schlick(f0: vec3<f32>, f90: f32, VoH: f32) -> vec3<f32> {
    return f0 + (vec3<f32>(f90) - f0) * pow(1.0 - VoH, 5.0);
}

fn distance_attenuation(distance_square: f32, inverse_range_squared: f32) -> f32 {
    let factor = distance_square * inverse_range_squared;
    let smooth_factor = clamp(1.0 - factor * factor, 0.0, 1.0);
    return smooth_factor * smooth_factor / max(distance_square, 0.0001);
}

fn point_light(input: PbrInput, light_position: vec3<f32>, light_color: vec3<f32>, F0: vec3<f32>, diffuse_color: vec3<f32>, roughness: f32) -> vec3<f32> {
    let to_light = light_position - input.world_position;
    let L = normalize(to_light);
    let H = normalize(L + input.V);
    let NoL = clamp(dot(input.N, L), 0.0, 1.0);
    let NoV = max(dot(input.N, input.V), 0.0001);
    let NoH = clamp(dot(input.N, H), 0.0, 1.0);
    let LoH = clamp(dot(L, H), 0.0, 1.0);
    let D = D_GGX(roughness, NoH);
    let V = V_SmithGGXCorrelated(roughness, NoV, NoL);
    let F = F_Schlick(F0, 1.0, LoH);
    let specular = D * V * F;
    let diffuse = diffuse_color * (1.0 / PI);
    let attenuation = distance_attenuation(dot(to_light, to_light), 1.0 / (view.light_radius * view.light_radius));
    return (diffuse + specular) * light_color * (attenuation * NoL);
}

fn apply_pbr_lighting(input: PbrInput) -> vec4<f32> {
    let roughness = perceptual_roughness_to_roughness(input.perceptual_roughness);
    let F0 = 0.16 * input.reflectance * input.reflectance * (1.0 - input.metallic) + input.base_color.rgb * input.metallic;
    let diffuse_color = input.base_color.rgb * (1.0 - input.metallic);
    var light_accum = vec3<f32>(0.0);
    for (var i = 0u; i < view.light_count; i = i + 1u) {
        let angle = f32(i) * (2.0 * PI / f32(view.light_count));
        let offset = vec3<f32>(cos(angle), 0.0, sin(angle)) * 1.5;
        let color = view.light_color / (1.0 + f32(i));
        light_accum += point_light(input, view.light_position + offset, color, F0, diffuse_color, roughness);
    }
    let ambient = diffuse_color * 0.03;
    return vec4<f32>(light_accum + ambient + material.emissive.rgb, input.base_color.a);
}

fn tone_mapping(color: vec4<f32>) -> vec4<f32> {
    let exposed = color.rgb * view.exposure;
    return vec4<f32>(exposed / (vec3<f32>(1.0) + exposed), color.a);
}

@fragment
fn fragment(in: MeshVertexOutput, @builtin(front_facing) is_front: bool) -> @location(0) vec4<f32> {
    var output_color: vec4<f32> = material.base_color;
    if ((material.flags & BASE_COLOR_TEXTURE_BIT) != 0u) {
        output_color = output_color * textureSample(base_color_texture, base_color_sampler, in.uv);
    }
    if ((material.flags & UNLIT_BIT) == 0u) {
        var pbr_input: PbrInput;
        pbr_input.base_color = output_color;
        var perceptual_roughness = material.perceptual_roughness;
        if ((material.flags & ROUGHNESS_TEXTURE_BIT) != 0u) {
            perceptual_roughness = perceptual_roughness * textureSample(roughness_texture, base_color_sampler, in.uv).g;
        }
        pbr_input.perceptual_roughness = perceptual_roughness;
        pbr_input.metallic = material.metallic;
        pbr_input.reflectance = material.reflectance;
        pbr_input.world_position = in.world_position.xyz;
        var N = normalize(in.world_normal);
        if (!is_front) {
            N = -N;
        }
        pbr_input.N = N;
        pbr_input.V = normalize(view.camera_position - in.world_position.xyz);
        output_color = tone_mapping(apply_pbr_lighting(pbr_input));
    }
    return output_color;
}

// A marble planet lit by a sun, written the way a wgpu tutorial writes
// its shaders: a globals uniform for the camera and the sun, a locals
// uniform for the object, the material in helper functions. The planet is
// skinned as engines skin characters: its northern hemisphere is a second
// joint that twists against the southern one, each vertex blending the
// joints' matrices (the model matrix times the joint's pose) by its
// weights.

struct Globals {
    view_projection: mat4x4<f32>,
    sun_direction: vec4<f32>,
    sun_color: vec4<f32>,
}

struct Locals {
    joints: array<mat4x4<f32>, 2>,
}

@group(0) @binding(0) var<uniform> globals: Globals;
@group(1) @binding(0) var<uniform> locals: Locals;

struct VertexIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) joint_indices: vec4<u32>,
    @location(3) joint_weights: vec4<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) surface: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
}

fn skin_model(indices: vec4<u32>, weights: vec4<f32>) -> mat4x4<f32> {
    return weights.x * locals.joints[indices.x]
        + weights.y * locals.joints[indices.y]
        + weights.z * locals.joints[indices.z]
        + weights.w * locals.joints[indices.w];
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    let model = skin_model(v.joint_indices, v.joint_weights);
    var out: VertexOut;
    out.clip = globals.view_projection * model * vec4<f32>(v.pos, 1.0);
    out.surface = v.pos;
    out.world_normal = (model * vec4<f32>(v.normal, 0.0)).xyz;
    return out;
}

fn hash(p: vec3<f32>) -> f32 {
    let q = fract(p * 0.3183099 + vec3<f32>(0.1, 0.7, 0.3)) * 17.0;
    return fract(q.x * q.y * q.z * (q.x + q.y + q.z));
}

fn value_noise(p: vec3<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let a = mix(hash(i), hash(i + vec3<f32>(1.0, 0.0, 0.0)), u.x);
    let b = mix(hash(i + vec3<f32>(0.0, 1.0, 0.0)), hash(i + vec3<f32>(1.0, 1.0, 0.0)), u.x);
    let c = mix(hash(i + vec3<f32>(0.0, 0.0, 1.0)), hash(i + vec3<f32>(1.0, 0.0, 1.0)), u.x);
    let d = mix(hash(i + vec3<f32>(0.0, 1.0, 1.0)), hash(i + vec3<f32>(1.0, 1.0, 1.0)), u.x);
    return mix(mix(a, b, u.y), mix(c, d, u.y), u.z);
}

fn turbulence(p: vec3<f32>) -> f32 {
    var sum = 0.0;
    var amplitude = 0.5;
    var at = p;
    for (var octave = 0; octave < 7; octave++) {
        sum += abs(value_noise(at) * 2.0 - 1.0) * amplitude;
        at *= 2.03;
        amplitude *= 0.5;
    }
    return sum;
}

fn marble(p: vec3<f32>) -> vec3<f32> {
    let veins = 0.5 + 0.5 * sin(p.x * 5.0 + turbulence(p * 2.5) * 7.0);
    let stone = vec3<f32>(0.92, 0.9, 0.86);
    let vein = vec3<f32>(0.25, 0.32, 0.45);
    return mix(vein, stone, pow(veins, 0.6));
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let albedo = marble(in.surface);
    let n = normalize(in.world_normal);
    let lit = max(dot(n, normalize(globals.sun_direction.xyz)), 0.0);
    let color = albedo * (0.12 + 0.88 * lit) * globals.sun_color.rgb;
    return vec4<f32>(color, 1.0);
}

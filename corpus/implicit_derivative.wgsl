// Textured surface with a procedural modulation, sampled with implicit
// level of detail.
//
// textureSample picks its mip level from screen-space derivatives of the
// texture coordinates, so it must run in uniform control flow: it sits at
// the top level of the fragment entry point. Its result feeds the albedo,
// which is multiplied by a procedural stripe term and then lit.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
    light_position: vec3<f32>,
    // Texture repeats per uv unit.
    uv_scale: f32,
    light_color: vec3<f32>,
    // Stripes per uv unit of the procedural modulation.
    stripe_frequency: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var albedo_texture: texture_2d<f32>;
@group(0) @binding(2) var albedo_sampler: sampler;

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
    // Implicit-LOD texture sample (needs derivatives of the uv).
    let texel = textureSample(albedo_texture, albedo_sampler, in.uv * frame.uv_scale);

    // Procedural modulation: soft diagonal stripes with a slow sine wobble.
    let diagonal = (in.uv.x + in.uv.y) * frame.stripe_frequency;
    let wobble = 0.15 * sin(in.uv.y * 23.0);
    let stripe = 0.5 + (0.5 * cos(6.2831853 * (diagonal + wobble)));
    let modulation = mix(0.65, 1.0, stripe);
    let albedo = texel.rgb * modulation;

    // Lambert plus Phong specular from a point light.
    let n = normalize(in.world_normal);
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let v = normalize(frame.camera_position - in.world_position);
    let r = reflect(-l, n);
    let n_dot_l = max(dot(n, l), 0.0);
    let specular = pow(max(dot(r, v), 0.0), 24.0) * texel.a;
    let falloff = 1.0 / (1.0 + (0.04 * dot(to_light, to_light)));
    let color = frame.light_color * falloff * ((albedo * n_dot_l) + vec3<f32>(0.25 * specular));
    return vec4<f32>(color + (0.05 * albedo), 1.0);
}

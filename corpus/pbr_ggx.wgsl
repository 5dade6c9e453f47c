// Physically based shading: Cook-Torrance microfacet BRDF (GGX
// distribution, Smith height-correlated visibility, Schlick Fresnel) for
// two point lights, with a procedural brushed pattern varying roughness.
//
// Several values here depend only on the uniform (perceptual roughness to
// alpha, base reflectance); they are the same for every pixel. The shared
// terms n, v and n_dot_v are used by both lights' BRDF evaluations and by
// the ambient term.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    // Perceptual roughness in [0, 1].
    roughness: f32,
    base_color: vec3<f32>,
    // 0 = dielectric, 1 = metal.
    metallic: f32,
    light_position: vec3<f32>,
    time: f32,
    light_color: vec3<f32>,
    ambient: f32,
    fill_light_position: vec3<f32>,
    // Strength of the brushed roughness variation.
    brush_amount: f32,
    fill_light_color: vec3<f32>,
    // Brush strokes per uv unit.
    brush_frequency: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

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

// GGX / Trowbridge-Reitz normal distribution.
fn distribution_ggx(n_dot_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = ((n_dot_h * n_dot_h) * (a2 - 1.0)) + 1.0;
    return a2 / (3.14159265 * d * d);
}

// Smith height-correlated visibility term V = G / (4 n.l n.v).
fn visibility_smith(n_dot_v: f32, n_dot_l: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = n_dot_l * sqrt((n_dot_v * n_dot_v * (1.0 - a2)) + a2);
    let gl = n_dot_v * sqrt((n_dot_l * n_dot_l * (1.0 - a2)) + a2);
    return 0.5 / max(gv + gl, 1e-5);
}

// Schlick's Fresnel approximation.
fn fresnel_schlick(v_dot_h: f32, f0: vec3<f32>) -> vec3<f32> {
    return f0 + ((vec3<f32>(1.0) - f0) * pow(1.0 - v_dot_h, 5.0));
}

// Outgoing radiance from one point light.
fn point_light(
    light_position: vec3<f32>,
    light_color: vec3<f32>,
    world_position: vec3<f32>,
    n: vec3<f32>,
    v: vec3<f32>,
    n_dot_v: f32,
    diffuse_color: vec3<f32>,
    f0: vec3<f32>,
    alpha: f32,
) -> vec3<f32> {
    let to_light = light_position - world_position;
    let l = normalize(to_light);
    let h = normalize(l + v);
    let n_dot_l = max(dot(n, l), 0.0);
    let n_dot_h = max(dot(n, h), 0.0);
    let v_dot_h = max(dot(v, h), 0.0);
    let specular = distribution_ggx(n_dot_h, alpha) * visibility_smith(n_dot_v, n_dot_l, alpha) * fresnel_schlick(v_dot_h, f0);
    let diffuse = diffuse_color / 3.14159265;
    let radiance = light_color / max(dot(to_light, to_light), 1e-4);
    return (diffuse + specular) * radiance * n_dot_l;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    // Depend only on the uniform: the same for every pixel.
    let f0 = mix(vec3<f32>(0.04), frame.base_color, frame.metallic);
    let diffuse_color = frame.base_color * (1.0 - frame.metallic);

    // Brushed-metal roughness variation along u.
    let strokes = sin(in.uv.y * frame.brush_frequency) * sin((in.uv.y * frame.brush_frequency * 2.7) + (in.uv.x * 3.0));
    let roughness = clamp(frame.roughness + (frame.brush_amount * strokes), 0.05, 1.0);
    let alpha = roughness * roughness;

    // Terms shared by both lights and the ambient term.
    let n = normalize(in.world_normal);
    let v = normalize(frame.camera_position - in.world_position);
    let n_dot_v = max(dot(n, v), 1e-4);

    let key = point_light(frame.light_position, frame.light_color, in.world_position, n, v, n_dot_v, diffuse_color, f0, alpha);
    let fill = point_light(frame.fill_light_position, frame.fill_light_color, in.world_position, n, v, n_dot_v, diffuse_color, f0, alpha);

    // Ambient with a Fresnel-weighted specular share.
    let ambient_specular = fresnel_schlick(n_dot_v, f0) * (1.0 - roughness);
    let ambient = frame.ambient * (diffuse_color + ambient_specular);

    let color = key + fill + ambient;
    return vec4<f32>(color, 1.0);
}

// Instanced objects with per-instance transforms and colours read from a
// storage buffer in the vertex stage.
//
// Each instance has its own world_from_local matrix and colour; the vertex
// stage picks them with @builtin(instance_index) and passes the colour on.
// The fragment stage lights the instance with a hemisphere ambient term,
// Blinn-Phong and a Fresnel rim.

struct Frame {
    clip_from_world: mat4x4<f32>,
    // Applied after the instance transform (moves the whole group).
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
    light_position: vec3<f32>,
    shininess: f32,
    light_color: vec3<f32>,
    rim_strength: f32,
    sky_color: vec3<f32>,
    ambient: f32,
    ground_color: vec3<f32>,
    specular: f32,
}

struct Instance {
    world_from_local: mat4x4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> instances: array<Instance>;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) instance_index: u32,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) @interpolate(flat) instance_color: vec4<f32>,
}

@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    let instance = instances[in.instance_index];
    let world_from_local = frame.world_from_local * instance.world_from_local;
    let world = world_from_local * vec4<f32>(in.position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = (world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    out.instance_color = instance.color;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let albedo = in.instance_color.rgb;
    let n = normalize(in.world_normal);
    let v = normalize(frame.camera_position - in.world_position);

    // Hemisphere ambient: sky colour from above, ground colour from below.
    let sky_amount = 0.5 + (0.5 * n.y);
    let hemisphere = mix(frame.ground_color, frame.sky_color, sky_amount) * frame.ambient;

    // Blinn-Phong from a point light.
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let h = normalize(l + v);
    let n_dot_l = max(dot(n, l), 0.0);
    let highlight = pow(max(dot(n, h), 0.0), frame.shininess) * frame.specular * select(0.0, 1.0, n_dot_l > 0.0);
    let falloff = 1.0 / (1.0 + (0.02 * dot(to_light, to_light)));

    // Fresnel rim (Schlick's approximation of the grazing-angle term).
    let rim = pow(1.0 - max(dot(n, v), 0.0), 5.0) * frame.rim_strength;

    let color = (albedo * hemisphere) + (frame.light_color * falloff * ((albedo * n_dot_l) + vec3<f32>(highlight))) + (frame.sky_color * rim);
    return vec4<f32>(color, in.instance_color.a);
}

// A skinned mesh, written the way engines skin: per vertex, four joint
// indices and their weights; per frame, every joint's skinning matrix
// (the model matrix times the joint's pose) in a storage array, blended in
// the vertex stage as Bevy's `skin_model` blends them.
//
// The fragment stage paints scales from five octaves of value noise in the
// mesh's rest pose (so the pattern stays on the skin as it bends) and
// lights them with a Lambert term and a rim.

struct View {
    clip_from_world: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
    light_position: vec3<f32>,
    rim_strength: f32,
}

@group(0) @binding(0) var<uniform> view: View;
@group(1) @binding(0) var<storage, read> joint_matrices: array<mat4x4<f32>>;

struct Vertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) joint_indices: vec4<u32>,
    @location(3) joint_weights: vec4<f32>,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) rest_position: vec3<f32>,
}

fn skin_model(indices: vec4<u32>, weights: vec4<f32>) -> mat4x4<f32> {
    return weights.x * joint_matrices[indices.x]
        + weights.y * joint_matrices[indices.y]
        + weights.z * joint_matrices[indices.z]
        + weights.w * joint_matrices[indices.w];
}

@vertex
fn vs_main(vertex: Vertex) -> VertexOutput {
    let model = skin_model(vertex.joint_indices, vertex.joint_weights);
    let world = model * vec4<f32>(vertex.position, 1.0);
    var out: VertexOutput;
    out.clip_position = view.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = (model * vec4<f32>(vertex.normal, 0.0)).xyz;
    out.rest_position = vertex.position;
    return out;
}

fn hash(p: vec3<f32>) -> f32 {
    return fract(sin(dot(p, vec3<f32>(12.9898, 78.233, 37.719))) * 43758.5453);
}

fn value_noise(p: vec3<f32>) -> f32 {
    let cell = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    var sum = 0.0;
    for (var corner = 0u; corner < 8u; corner++) {
        let offset = vec3<f32>(f32(corner & 1u), f32((corner >> 1u) & 1u), f32((corner >> 2u) & 1u));
        let w = mix(1.0 - u, u, offset);
        sum += w.x * w.y * w.z * hash(cell + offset);
    }
    return sum;
}

fn scales(p: vec3<f32>) -> f32 {
    var q = p;
    var amplitude = 0.5;
    var sum = 0.0;
    for (var octave = 0; octave < 5; octave++) {
        sum += amplitude * value_noise(q);
        q *= 2.03;
        amplitude *= 0.5;
    }
    return sum;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let pattern = scales(in.rest_position * 7.0);
    let albedo = mix(vec3<f32>(0.25, 0.42, 0.18), vec3<f32>(0.85, 0.8, 0.45), pattern);
    let n = normalize(in.world_normal);
    let to_light = normalize(view.light_position - in.world_position);
    let to_eye = normalize(view.camera_position - in.world_position);
    let diffuse = max(dot(n, to_light), 0.0);
    let rim = view.rim_strength * pow(1.0 - max(dot(n, to_eye), 0.0), 3.0);
    return vec4<f32>(albedo * (0.2 + 0.8 * diffuse) + vec3<f32>(rim), 1.0);
}

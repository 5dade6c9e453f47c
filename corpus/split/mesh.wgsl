// The vertex stage of corpus/split/toon_material.wgsl, kept in its own
// module as engines keep theirs (Bevy's `mesh.wgsl` beside each
// material's fragment shader). Both modules declare the view uniform at
// group 0, binding 0: one resource.

struct View {
    clip_from_world: mat4x4<f32>,
    world_position: vec3<f32>,
    exposure: f32,
}
@group(0) @binding(0) var<uniform> view: View;

struct Mesh {
    world_from_local: mat4x4<f32>,
}
@group(2) @binding(0) var<uniform> mesh: Mesh;

struct Vertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) world_position: vec4<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vertex(vertex: Vertex) -> VertexOutput {
    var out: VertexOutput;
    out.world_position = mesh.world_from_local * vec4<f32>(vertex.position, 1.0);
    out.world_normal = normalize((mesh.world_from_local * vec4<f32>(vertex.normal, 0.0)).xyz);
    out.position = view.clip_from_world * out.world_position;
    out.uv = vertex.uv;
    return out;
}

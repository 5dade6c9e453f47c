#define_import_path engine::view

// The per-frame view, bound once for every material (group 0).
struct View {
    clip_from_world: mat4x4<f32>,
    world_position: vec3<f32>,
    time: f32,
}

@group(0) @binding(0) var<uniform> view: View;

// A material composed from modules the way Bevy composes its shaders:
// the view and the lighting come from `#import`s (under
// corpus/composed/modules, `--import-path corpus/composed/modules`), and
// an `#ifdef` shader def switches the fog on (`--def FOG`).

#import engine::view::{view, View}
#import engine::lighting::point_light

struct Mesh {
    world_from_local: mat4x4<f32>,
}
@group(2) @binding(0) var<uniform> mesh: Mesh;

struct RippleMaterial {
    base_color: vec3<f32>,
    gloss: f32,
    ripple_scale: f32,
    ripple_speed: f32,
}
@group(2) @binding(1) var<uniform> material: RippleMaterial;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
}

@vertex
fn vertex(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VertexOutput {
    let world = mesh.world_from_local * vec4<f32>(position, 1.0);
    var out: VertexOutput;
    out.position = view.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = normalize((mesh.world_from_local * vec4<f32>(normal, 0.0)).xyz);
    return out;
}

fn ripples(p: vec3<f32>, t: f32) -> f32 {
    var height = 0.0;
    for (var i = 1; i <= 5; i++) {
        let k = f32(i) * material.ripple_scale;
        height += sin(length(p.xz) * k - t * material.ripple_speed * f32(i)) / f32(i);
    }
    return height;
}

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let height = ripples(in.world_position, view.time);
    let tint = 0.75 + 0.25 * height;
    let normal = normalize(in.world_normal + vec3<f32>(0.0, 0.1 * height, 0.0));
    var color = point_light(in.world_position, normal, material.base_color * tint, material.gloss);
#ifdef FOG
    let distance = length(view.world_position - in.world_position);
    color = mix(color, vec3<f32>(0.6, 0.65, 0.7), saturate(distance / 12.0));
#endif
    return vec4<f32>(color, 1.0);
}

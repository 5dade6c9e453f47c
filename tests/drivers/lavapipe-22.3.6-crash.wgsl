// The smallest shader found to crash Mesa 22.3.6's lavapipe (LLVM 15):
// a SIGSEGV in a lavapipe thread at the first reference frame, whatever
// the frame size, with valid WGSL that naga accepts. Reduced from Bevy's
// PBR shader as naga_oil's example composes it; the crash goes away when
// dead code is deleted (the unused `view_z`, either half of the `&&`),
// so it is the driver's shader compiler, not the data. Mesa 24 and newer
// draw it. `lavapipe_22_reproducer_profiles` profiles it.
struct MeshVertexOutput { @location(1) world_normal: vec3<f32>, }
struct View { inverse_view: mat4x4<f32>, };
struct DirectionalLight { view_projection: mat4x4<f32>, color: vec4<f32>, flags: u32, };
const DIRECTIONAL_LIGHT_FLAGS_SHADOWS_ENABLED_BIT: u32 = 1u;
struct Lights { directional_lights: array<DirectionalLight, 1u>, n_directional_lights: u32, };
@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> lights: Lights;
struct Mesh { inverse_transpose_model: mat4x4<f32>, flags: u32, };
const MESH_FLAGS_SHADOW_RECEIVER_BIT: u32 = 1u;
@group(2) @binding(0) var<uniform> mesh: Mesh;
struct StandardMaterial { base_color: vec4<f32>, };
@group(1) @binding(0) var<uniform> material: StandardMaterial;
fn fetch_directional_shadow(light_id: u32, frag_position: vec4<f32>, surface_normal: vec3<f32>) -> f32 {
    let light = lights.directional_lights[light_id];
    let offset_position = frag_position;
    let offset_position_clip = light.view_projection * offset_position;
    let offset_position_ndc = offset_position_clip.xyz;
    let flip_correction = vec2<f32>(0.5, -0.5);
    let light_local = offset_position_ndc.xy * flip_correction + vec2<f32>(0.5, 0.5);
    let depth = offset_position_ndc.z;
    return light_local.x + depth;
}
struct PbrInput { world_position: vec4<f32>, };
fn pbr(in: PbrInput) -> vec4<f32> {
    var output_color: vec4<f32>;
    var light_accum: vec3<f32> = vec3<f32>(0.0);
    let view_z = dot(vec4<f32>(view.inverse_view[3].z), in.world_position);
    let n_directional_lights = lights.n_directional_lights;
    for (var i: u32 = 0u; i < n_directional_lights; i = i + 1u) {
        let light = lights.directional_lights[i];
        var shadow: f32 = 1.0;
        if ((mesh.flags & MESH_FLAGS_SHADOW_RECEIVER_BIT) != 0u
                && (light.flags & DIRECTIONAL_LIGHT_FLAGS_SHADOWS_ENABLED_BIT) != 0u) {
            shadow = fetch_directional_shadow(i, in.world_position, vec3<f32>(0.0));
        }
        let light_contrib = light.color.rgb;
        light_accum = light_accum + light_contrib * shadow;
    }
    output_color = vec4<f32>(light_accum, 1.0);
    return output_color;
}
@fragment
fn fragment(mesh: MeshVertexOutput) -> @location(0) vec4<f32> {
    var output_color: vec4<f32> = material.base_color;
    var pbr_input: PbrInput;
    pbr_input.world_position = vec4<f32>(mesh.world_normal, 1.0);
    output_color = pbr(pbr_input);
    return output_color;
}

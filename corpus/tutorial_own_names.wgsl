// A lit, textured model as the wgpu tutorials write it: a camera uniform
// with `view_proj` and `view_pos`, a model uniform with its own `model`
// matrix, a light uniform with `position` and `color`, the vertex inputs
// at the locations the tutorial's vertex buffer layout gives them
// (position, tex_coords, normal, tangent) and a Blinn-Phong fragment stage
// with normal mapping. No member carries a name the simulation knows: a
// scene maps them with [roles], or the default scene infers them.

struct CameraUniform {
    view_pos: vec4<f32>,
    view_proj: mat4x4<f32>,
}
@group(1) @binding(0)
var<uniform> camera: CameraUniform;

struct Light {
    position: vec3<f32>,
    intensity: f32,
    color: vec3<f32>,
    shininess: f32,
}
@group(2) @binding(0)
var<uniform> light: Light;

struct ModelUniform {
    model: mat4x4<f32>,
    tint: vec4<f32>,
}
@group(2) @binding(1)
var<uniform> object: ModelUniform;

@group(0) @binding(0)
var t_diffuse: texture_2d<f32>;
@group(0) @binding(1)
var s_diffuse: sampler;
@group(0) @binding(2)
var t_normal: texture_2d<f32>;
@group(0) @binding(3)
var s_normal: sampler;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) tex_coords: vec2<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) tangent: vec3<f32>,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) tex_coords: vec2<f32>,
    @location(1) world_position: vec3<f32>,
    @location(2) world_normal: vec3<f32>,
    @location(3) world_tangent: vec3<f32>,
}

@vertex
fn vs_main(model: VertexInput) -> VertexOutput {
    let world_position = object.model * vec4<f32>(model.position, 1.0);
    var out: VertexOutput;
    out.tex_coords = model.tex_coords;
    out.world_position = world_position.xyz;
    out.world_normal = normalize((object.model * vec4<f32>(model.normal, 0.0)).xyz);
    out.world_tangent = normalize((object.model * vec4<f32>(model.tangent, 0.0)).xyz);
    out.clip_position = camera.view_proj * world_position;
    return out;
}

fn blinn_phong(normal: vec3<f32>, to_light: vec3<f32>, to_view: vec3<f32>) -> vec3<f32> {
    let diffuse = dot(normal, to_light);
    // Facing away from the light: neither diffuse light nor a highlight.
    if (diffuse <= 0.0) {
        return vec3<f32>(0.0);
    }
    let half_dir = normalize(to_view + to_light);
    let specular = pow(max(dot(normal, half_dir), 0.0), 8.0 + 56.0 * light.shininess);
    return light.color * light.intensity * (diffuse + specular);
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let object_color = textureSample(t_diffuse, s_diffuse, in.tex_coords) * object.tint;
    let object_normal = textureSample(t_normal, s_normal, in.tex_coords).xyz * 2.0 - 1.0;

    let n = normalize(in.world_normal);
    let t = normalize(in.world_tangent - n * dot(in.world_tangent, n));
    let b = cross(n, t);
    let normal = normalize(mat3x3<f32>(t, b, n) * object_normal);

    let to_light = normalize(light.position - in.world_position);
    let to_view = normalize(camera.view_pos.xyz - in.world_position);
    var lit = vec3<f32>(0.1);
    lit += blinn_phong(normal, to_light, to_view);
    // A little sheen in the grazing direction.
    let rim = pow(1.0 - max(dot(normal, to_view), 0.0), 4.0);
    lit += vec3<f32>(rim * 0.25);

    let result = lit * object_color.rgb;
    return vec4<f32>(result, object_color.a);
}

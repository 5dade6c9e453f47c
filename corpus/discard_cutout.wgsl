// Alpha-tested foliage cutout with two-sided lighting.
//
// Coverage is the texture's alpha times a procedural leaf-vein mask; pixels
// below the threshold are discarded. The implicit-LOD texture sample is
// taken before the discard (it needs uniform control flow); the work after
// the discard is arithmetic only.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    // Coverage below this value is cut out.
    alpha_threshold: f32,
    light_position: vec3<f32>,
    time: f32,
    light_color: vec3<f32>,
    // Share of light passing through the leaf to its back face.
    translucency: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var leaf_texture: texture_2d<f32>;
@group(0) @binding(2) var leaf_sampler: sampler;

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

struct FragmentOutput {
    @location(0) color: vec4<f32>,
}

@fragment
fn fs_main(in: VertexOutput, @builtin(front_facing) front_facing: bool) -> FragmentOutput {
    // Texture first: implicit LOD must come before the non-uniform discard.
    let texel = textureSample(leaf_texture, leaf_sampler, in.uv);

    // Procedural leaf outline: an ellipse around the uv centre line, with
    // serrated edges and holes between the veins.
    let centred = (in.uv * 2.0) - vec2<f32>(1.0);
    let outline = 1.0 - length(centred * vec2<f32>(1.6, 1.0));
    let serration = 0.06 * sin(centred.y * 40.0);
    let veins = abs(sin((centred.y * 9.0) + (abs(centred.x) * 6.0)));
    let holes = smoothstep(0.85, 0.98, veins) * smoothstep(0.1, 0.3, abs(centred.x));
    let alpha = texel.a * clamp((outline + serration) * 8.0, 0.0, 1.0) * (1.0 - (0.8 * holes));

    if (alpha < frame.alpha_threshold) {
        discard;
    }

    // Two-sided lighting: flip the normal for back faces, and let some light
    // through the leaf (translucency) when it is lit from behind.
    let side = select(-1.0, 1.0, front_facing);
    let n = normalize(in.world_normal) * side;
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let v = normalize(frame.camera_position - in.world_position);
    let n_dot_l = dot(n, l);
    let front_light = max(n_dot_l, 0.0);
    let back_light = max(-n_dot_l, 0.0) * frame.translucency * max(dot(-l, v), 0.0);
    let vein_tint = mix(vec3<f32>(1.0), vec3<f32>(0.8, 0.9, 0.6), smoothstep(0.6, 0.9, veins));
    let albedo = texel.rgb * vein_tint;
    let color = albedo * ((frame.light_color * (front_light + back_light)) + vec3<f32>(0.06));

    var out: FragmentOutput;
    out.color = vec4<f32>(color, 1.0);
    return out;
}

// Screen-space plasma on a mesh whose vertex stage returns the clip
// position directly (no vertex output struct, no varyings).
//
// The fragment stage works only from @builtin(position) and the uniform:
// a sum of animated sine waves over the pixel's framebuffer coordinate,
// mapped through a cosine palette (screen-space: not cacheable), under
// distance fog from the fragment's depth (a property of the surface point:
// cacheable).

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    // Framebuffer size in pixels.
    resolution: vec2<f32>,
    time: f32,
    // Wave frequency relative to the screen height.
    pattern_scale: f32,
    light_color: vec3<f32>,
    // Contrast of the bands.
    contrast: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return frame.clip_from_world * (frame.world_from_local * vec4<f32>(position, 1.0));
}

@fragment
fn fs_main(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    // Pixel position normalised by the screen height, centred on the screen.
    let uv = (frag_coord.xy - (0.5 * frame.resolution)) / frame.resolution.y;
    let q = uv * frame.pattern_scale;

    // Depend only on the uniform: the same for every pixel.
    let phase = frame.time * 0.7;
    let orbit = vec2<f32>(cos(frame.time * 0.3), sin(frame.time * 0.4)) * 0.5;

    // Plasma: four sine waves (horizontal, diagonal, radial, moving radial).
    let wave_a = sin(q.x + phase);
    let wave_b = sin((0.5 * (q.x + q.y)) + (1.3 * phase));
    let wave_c = sin(length(q) - phase);
    let wave_d = sin(2.0 * length(q - (orbit * frame.pattern_scale)));
    let plasma = 0.25 * (wave_a + wave_b + wave_c + wave_d);

    // Cosine palette (Inigo Quilez): a + b * cos(2 pi (c t + d)).
    let t = 0.5 + (0.5 * plasma * frame.contrast);
    let palette = vec3<f32>(0.5) + (vec3<f32>(0.5) * cos(6.2831853 * ((vec3<f32>(1.0) * t) + vec3<f32>(0.0, 0.33, 0.67))));

    // Vignette towards the screen corners.
    let vignette = 1.0 - (0.6 * dot(uv, uv));

    // Exponential-squared distance fog: 1 / w of the fragment position is
    // its depth in view space.
    let view_depth = 1.0 / frag_coord.w;
    let fog = 1.0 - exp(-0.08 * view_depth * view_depth);
    let fog_color = vec3<f32>(0.05, 0.06, 0.09);
    let color = mix(palette * frame.light_color * vignette, fog_color, fog);
    return vec4<f32>(color, 1.0);
}

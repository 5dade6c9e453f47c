// Antialiased procedural grid over a checkerboard, with a faceted normal
// from screen-space derivatives.
//
// fwidth gives the filter width of the grid coordinates per pixel, so the
// grid lines and checker edges are smoothed over about one pixel at any
// distance. The shading normal is the cross product of dpdx and dpdy of the
// world position (flat shading without mesh normals). All derivatives are
// taken at the top level of the fragment entry point (uniform control flow).

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    // Grid cells per world unit.
    grid_scale: f32,
    light_position: vec3<f32>,
    // Grid line width as a fraction of a cell.
    line_width: f32,
    light_color: vec3<f32>,
    time: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let grid_uv = in.world_position.xz * frame.grid_scale;

    // Filter width of the grid coordinates (cells per pixel).
    let width = max(fwidth(grid_uv), vec2<f32>(1e-5));

    // Grid lines: distance to the nearest line in pixels, then coverage.
    let to_line = abs(fract(grid_uv - vec2<f32>(0.5)) - vec2<f32>(0.5));
    let line_pixels = (to_line - vec2<f32>(0.5 * frame.line_width)) / width;
    let line_coverage = 1.0 - clamp(min(line_pixels.x, line_pixels.y), 0.0, 1.0);

    // Box-filtered checkerboard (integral of the square wave over the
    // pixel footprint), fading to grey where cells are below a pixel.
    let lo = grid_uv - (0.5 * width);
    let hi = grid_uv + (0.5 * width);
    let square_lo = abs(fract(lo * 0.5) - vec2<f32>(0.5));
    let square_hi = abs(fract(hi * 0.5) - vec2<f32>(0.5));
    let box = (2.0 * (square_lo - square_hi)) / width;
    let checker = 0.5 - (0.5 * box.x * box.y);

    let cell_color = mix(vec3<f32>(0.30, 0.32, 0.36), vec3<f32>(0.78, 0.79, 0.82), checker);
    let albedo = mix(cell_color, vec3<f32>(0.95, 0.55, 0.15), line_coverage);

    // Faceted normal from derivatives, turned towards the camera.
    let dx = dpdx(in.world_position);
    let dy = dpdy(in.world_position);
    let v = normalize(frame.camera_position - in.world_position);
    let facet = normalize(cross(dx, dy));
    let n = faceForward(facet, -v, facet);

    // Lambert from a point light plus a little ambient.
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let n_dot_l = max(dot(n, l), 0.0);
    let falloff = 1.0 / (1.0 + (0.01 * dot(to_light, to_light)));
    let color = albedo * ((frame.light_color * (n_dot_l * falloff)) + vec3<f32>(0.08));
    return vec4<f32>(color, 1.0);
}

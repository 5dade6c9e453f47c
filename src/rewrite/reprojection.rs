//! The reprojection arithmetic of `shaders/cache.wgsl`, on the CPU.
//!
//! The functions here mirror the shader's `cache_footprint`,
//! `cache_lookup_nearest` and `cache_refresh` formula for formula, in f32
//! as the shader computes them: clip position → NDC → texel coordinates in
//! last frame's cache, the 2×2 bilinear footprint and its weights, the
//! inside test, the slope-following expected depth and the depth test, the
//! refresh indicator of seed 002's eq. 1. Nothing renders with them: they
//! let tests predict what the shader decides, check the geometry of
//! reprojection under arbitrary camera and object motion, and reason about
//! hard cases without a GPU. The hard-case tests run the same cases through
//! both and require the same decisions, so **a change to the shader's
//! helpers must be made here too**, in step. The packed lookups
//! (`cache_lookup_packed`...) share `cache_point` and `cache_nearest` with
//! these, and are tested on the GPU against the separate ones rather than
//! mirrored here.
//!
//! Conventions (wgpu's): NDC x and y in [-1, 1] with y up, depth in [0, 1];
//! framebuffer positions in pixels from the top-left corner with pixel
//! centres at half-integers (what a fragment sees as
//! `@builtin(position).xy`); cache texel coordinates put texel `i`'s centre
//! at `i`, so a texel coordinate is a framebuffer position less one half.

use glam::{IVec2, UVec2, Vec2, Vec4};

/// Why a lookup missed, as the shader's `status`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Status {
    /// The point was visible last frame at the reprojected position.
    Hit = 0,
    /// Behind the previous camera (w ≤ 0 or NaN) or outside the viewport.
    Offscreen = 1,
    /// A tap of the footprint disagrees with the expected depth.
    Disoccluded = 2,
}

impl Status {
    /// The shader's code for it.
    pub fn code(self) -> u32 {
        self as u32
    }
}

/// Bilinear taps weighing less than this take no part in the depth test.
pub const NEGLIGIBLE_WEIGHT: f32 = 0.001;

/// How far, in texels, a point may lie outside the outermost texel centres
/// and still count as inside (its outside taps then weigh less than
/// [`NEGLIGIBLE_WEIGHT`]).
pub const EDGE_SLACK: f32 = 0.001;

/// Last frame's depth buffer as the lookups read it, the depth test's
/// relative ε (`CacheParams::depth_epsilon`) and the far plane's depth
/// (`CacheParams::far_depth`: 1, or 0 with reversed Z).
#[derive(Clone, Copy, Debug)]
pub struct PreviousDepth<'a> {
    /// The cache's size in texels.
    pub size: UVec2,
    /// Row-major, top row first.
    pub depth: &'a [f32],
    /// The depth test's ε.
    pub epsilon: f32,
    /// The far plane's depth.
    pub far_depth: f32,
}

impl PreviousDepth<'_> {
    /// `cache_depth_agrees`: a tap agrees with the expected depth when
    /// |tap − expected| < ε·|expected − far depth|.
    pub fn agrees(&self, tap: f32, expected: f32) -> bool {
        (tap - expected).abs() < self.epsilon * (expected - self.far_depth).abs()
    }

    /// The viewport in pixels, as `CacheParams::viewport`.
    pub fn viewport(&self) -> Vec2 {
        self.size.as_vec2()
    }

    /// The depth at a texel, clamped to the edge as the shader's sampler
    /// (clamp-to-edge) and its loads (clamped indices) read it.
    pub fn at(&self, texel: IVec2) -> f32 {
        let last = self.size.as_ivec2() - IVec2::ONE;
        let t = texel.clamp(IVec2::ZERO, last);
        self.depth[(t.y as u32 * self.size.x + t.x as u32) as usize]
    }
}

/// `previous_clip.xyz / previous_clip.w`.
pub fn ndc(clip: Vec4) -> glam::Vec3 {
    clip.truncate() / clip.w
}

/// The framebuffer position of a clip-space point: what a rasteriser with
/// this viewport gives as `@builtin(position).xy` (y down, pixel centres at
/// half-integers).
pub fn pixel_position(clip: Vec4, viewport: Vec2) -> Vec2 {
    let ndc = ndc(clip);
    Vec2::new((ndc.x * 0.5) + 0.5, 0.5 - (ndc.y * 0.5)) * viewport
}

/// The cache texel coordinate of a clip-space point (texel `i`'s centre at
/// `i`): [`pixel_position`] less one half, as `cache_footprint` computes it.
pub fn texel_position(clip: Vec4, viewport: Vec2) -> Vec2 {
    pixel_position(clip, viewport) - Vec2::splat(0.5)
}

/// `cache_footprint`'s inside test: in front of the previous camera and
/// within [`EDGE_SLACK`] of the outermost texel centres. False for any NaN.
pub fn footprint_inside(clip: Vec4, viewport: Vec2) -> bool {
    let texel = texel_position(clip, viewport);
    let slack = Vec2::splat(EDGE_SLACK);
    (clip.w > 0.0) && texel.cmpge(-slack).all() && texel.cmple((viewport - Vec2::ONE) + slack).all()
}

/// `cache_lookup_nearest`'s inside test: in front of the previous camera
/// and within the viewport's pixels. False for any NaN.
pub fn nearest_inside(clip: Vec4, viewport: Vec2) -> bool {
    let position = pixel_position(clip, viewport);
    (clip.w > 0.0) && position.cmpge(Vec2::ZERO).all() && position.cmplt(viewport).all()
}

/// `cache_previous_slope`: the previous depth's slope per texel of last
/// frame's cache, from its slope per pixel of this frame (`dpdx`, `dpdy` of
/// the depth) and how the previous texel position moves per pixel of this
/// frame (`along_x` = `dpdx`, `along_y` = `dpdy` of it: the columns of the
/// mapping's Jacobian J). The per-pixel slope is the per-texel one times J,
/// so this is the per-pixel slope times J⁻¹; where J is singular (|det J| ≤
/// 10⁻⁶) or the result not finite, the per-pixel slope stands in.
pub fn previous_slope(per_pixel: Vec2, along_x: Vec2, along_y: Vec2) -> Vec2 {
    let det = (along_x.x * along_y.y) - (along_y.x * along_x.y);
    let per_texel = Vec2::new(
        (per_pixel.x * along_y.y) - (per_pixel.y * along_x.y),
        (per_pixel.y * along_x.x) - (per_pixel.x * along_y.x),
    ) / det;
    let usable = det.abs() > 1e-6 && per_texel.abs().cmplt(Vec2::splat(1e30)).all();
    if usable {
        per_texel
    } else {
        per_pixel
    }
}

/// `cache_expected_depth` for one tap: the point's previous depth carried
/// along the surface's depth slope per previous texel ([`previous_slope`])
/// by the tap's offset from the point, in texels.
pub fn expected_depth(depth: f32, offset: Vec2, slope: Vec2) -> f32 {
    depth + (offset.x * slope.x) + (offset.y * slope.y)
}

/// Where a fragment was last frame, in the cache: `CacheFootprint`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    /// Hit or why not.
    pub status: Status,
    /// The top-left texel of the 2×2 bilinear footprint.
    pub base: Vec2,
    /// The point's position within it, (0, 0) at `base`: the bilinear
    /// weights along x and y.
    pub fraction: Vec2,
}

impl Footprint {
    /// The four taps and their bilinear weights, in `textureGather`'s order:
    /// (0, 1), (1, 1), (1, 0), (0, 0) from `base`. Texels may lie outside
    /// the viewport (the shader reads the edge there).
    /// Texel indices saturate for a non-finite position (w = 0).
    pub fn taps(&self) -> [(IVec2, f32); 4] {
        let tap = |x: f32, y: f32| (self.base + Vec2::new(x, y)).as_ivec2();
        let f = self.fraction;
        [
            (tap(0.0, 1.0), (1.0 - f.x) * f.y),
            (tap(1.0, 1.0), f.x * f.y),
            (tap(1.0, 0.0), f.x * (1.0 - f.y)),
            (tap(0.0, 0.0), (1.0 - f.x) * (1.0 - f.y)),
        ]
    }
}

/// `cache_footprint`: off-screen when the point was behind the previous
/// camera or outside the texel centres; disoccluded when a tap weighing at
/// least [`NEGLIGIBLE_WEIGHT`] disagrees with the expected depth by ε or
/// more. `slope` is the previous NDC depth's slope per previous texel, as
/// the shader's `cache_previous_slope` gives it.
pub fn footprint(clip: Vec4, slope: Vec2, previous: &PreviousDepth) -> Footprint {
    let viewport = previous.viewport();
    let depth = ndc(clip).z;
    let texel = texel_position(clip, viewport);
    let base = texel.floor();
    let fraction = texel - base;
    let mut footprint = Footprint {
        status: Status::Hit,
        base,
        fraction,
    };
    let agree = footprint.taps().iter().all(|&(tap, weight)| {
        let offset = tap.as_vec2() - texel;
        let expected = expected_depth(depth, offset, slope);
        previous.agrees(previous.at(tap), expected) || weight < NEGLIGIBLE_WEIGHT
    });
    footprint.status = if !footprint_inside(clip, viewport) {
        Status::Offscreen
    } else if agree {
        Status::Hit
    } else {
        Status::Disoccluded
    };
    footprint
}

/// `cache_lookup_nearest`'s decision and the texel it reads: the texel the
/// point falls in, tested on its own depth.
pub fn nearest(clip: Vec4, slope: Vec2, previous: &PreviousDepth) -> (Status, IVec2) {
    let viewport = previous.viewport();
    let position = pixel_position(clip, viewport);
    // `vec2<i32>(floor(p))` of a NaN or huge value: the shader's result is
    // some texel, clamped; Rust's saturating cast gives one too.
    let texel = position
        .floor()
        .as_ivec2()
        .clamp(IVec2::ZERO, previous.size.as_ivec2() - IVec2::ONE);
    let offset = (texel.as_vec2() + Vec2::splat(0.5)) - position;
    let expected = expected_depth(ndc(clip).z, offset, slope);
    let agree = previous.agrees(previous.at(texel), expected);
    let status = if !nearest_inside(clip, viewport) {
        Status::Offscreen
    } else if agree {
        Status::Hit
    } else {
        Status::Disoccluded
    };
    (status, texel)
}

/// `cache_hash`: PCG's output permutation of one u32.
pub fn hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// `cache_refresh`'s phase rule, seed 002's eq. 1 (see [`stale`] for the
/// rest): whether the pixel at framebuffer
/// position `pixel` is recomputed this frame, given the host's refresh
/// phase (c mod Δn, below Δn), the period Δn (0: never, at most 65535) and
/// the block size k.
pub fn refresh(pixel: Vec2, phase: u32, period: u32, quad: u32) -> bool {
    let k = quad.max(1) as f32;
    let block = (pixel / k).as_uvec2();
    let offset = refresh_offset(block.x, block.y, period);
    let mut b = offset + phase;
    if b >= period {
        b -= period;
    }
    period != 0 && b == 0
}

/// The largest age the cache's r16float age target holds exactly
/// (`CACHE_AGE_LIMIT`).
pub const AGE_LIMIT: f32 = 2048.0;

/// The rest of `cache_refresh`: a value whose age this frame (one more
/// than the oldest texel it is read from, at most [`AGE_LIMIT`]) has
/// reached Δn is refreshed whatever the phase says; so `cache_refresh` is
/// `refresh(..) || stale(age, period)`, and both are off when Δn = 0.
pub fn stale(age: f32, period: u32) -> bool {
    period != 0 && age >= (period as f32).min(AGE_LIMIT)
}

/// The offset in [0, Δn) of the block at (`x`, `y`): 16 bits of one hash
/// of both coordinates, times Δn, over 2^16.
pub fn refresh_offset(x: u32, y: u32, period: u32) -> u32 {
    let h = hash(x ^ y.wrapping_mul(0x9e37_79b9)) >> 16;
    (h * period) >> 16
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat4, DQuat, DVec2, DVec3, DVec4};
    use proptest::prelude::*;

    /// A perspective camera as a scene has one.
    #[derive(Clone, Copy, Debug)]
    struct Camera {
        eye: DVec3,
        target: DVec3,
        fov_degrees: f64,
        near: f64,
        far: f64,
    }

    impl Camera {
        fn view(&self) -> DMat4 {
            DMat4::look_at_rh(self.eye, self.target, DVec3::Y)
        }

        fn clip_from_world(&self, aspect: f64) -> DMat4 {
            DMat4::perspective_rh(self.fov_degrees.to_radians(), aspect, self.near, self.far)
                * self.view()
        }

        /// The world point at `ndc` (x, y) and `distance` in front of the
        /// camera.
        fn point(&self, aspect: f64, ndc: DVec2, distance: f64) -> DVec3 {
            let half = (self.fov_degrees.to_radians() * 0.5).tan();
            let in_view = DVec3::new(
                ndc.x * half * aspect * distance,
                ndc.y * half * distance,
                -distance,
            );
            self.view().inverse().transform_point3(in_view)
        }
    }

    fn vec3(range: f64) -> impl Strategy<Value = DVec3> {
        (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    /// A camera anywhere near the scene, looking at `target` plus up to 2
    /// units, with random field of view and clip planes; moved back when
    /// that is closer than a unit, tilted when it looks straight down.
    fn camera_towards(target: DVec3) -> impl Strategy<Value = Camera> {
        (
            vec3(10.0),
            vec3(2.0),
            20.0..100.0f64,
            0.1..1.0f64,
            40.0..200.0f64,
        )
            .prop_map(move |(eye, offset, fov_degrees, near, far)| {
                let target = target + offset;
                let mut eye = eye;
                if (target - eye).length() < 1.0 {
                    eye = target + DVec3::new(0.0, 0.5, 3.0);
                }
                if (target - eye).normalize().y.abs() > 0.99 {
                    eye.x += 1.0;
                }
                Camera {
                    eye,
                    target,
                    fov_degrees,
                    near,
                    far,
                }
            })
    }

    /// Scale, then a rotation about `axis` (the y axis when `axis` is
    /// nearly zero), then a translation.
    fn transform(axis: DVec3, angle: f64, translation: DVec3, scale: f64) -> DMat4 {
        let axis = if axis.length() < 1e-3 {
            DVec3::Y
        } else {
            axis.normalize()
        };
        DMat4::from_scale_rotation_translation(
            DVec3::splat(scale),
            DQuat::from_axis_angle(axis, angle),
            translation,
        )
    }

    /// Scale, rotation and translation: a rigid motion with uniform scale.
    fn object() -> impl Strategy<Value = DMat4> {
        (
            vec3(1.0),
            -std::f64::consts::PI..std::f64::consts::PI,
            vec3(3.0),
            0.25..4.0f64,
        )
            .prop_map(|(axis, angle, translation, scale)| {
                transform(axis, angle, translation, scale)
            })
    }

    fn viewport() -> impl Strategy<Value = Vec2> {
        (16u32..1024, 16u32..1024).prop_map(|(w, h)| Vec2::new(w as f32, h as f32))
    }

    /// A point in last frame's view: NDC x and y, distance from the eye.
    fn placement() -> impl Strategy<Value = (DVec2, f64)> {
        ((-0.95..0.95f64, -0.95..0.95f64), 1.0..30.0f64)
            .prop_map(|((x, y), distance)| (DVec2::new(x, y), distance))
    }

    /// The framebuffer position and depth of a point, in f64: the
    /// reference. `None` outside the view volume.
    fn exact_position(clip_from_local: DMat4, point: DVec3, viewport: Vec2) -> Option<DVec3> {
        let clip = clip_from_local * point.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        (clip.w > 0.0 && ndc.z > 0.0 && ndc.z < 1.0 && ndc.x.abs() < 1.0 && ndc.y.abs() < 1.0).then(
            || {
                let v = viewport.as_dvec2();
                DVec3::new((ndc.x * 0.5 + 0.5) * v.x, (0.5 - ndc.y * 0.5) * v.y, ndc.z)
            },
        )
    }

    /// The f32 clip position the vertex stage computes:
    /// `clip_from_world * (world_from_local * position)`.
    fn vertex_clip(clip_from_world: DMat4, world_from_local: DMat4, local: DVec3) -> Vec4 {
        clip_from_world.as_mat4() * (world_from_local.as_mat4() * local.as_vec3().extend(1.0))
    }

    /// Takes a cache texel coordinate and its previous depth back to the
    /// object's local space, in f64, through last frame's matrices.
    fn unproject(clip_from_local: DMat4, texel: Vec2, depth: f32, viewport: Vec2) -> DVec3 {
        let v = viewport.as_dvec2();
        let position = texel.as_dvec2() + 0.5;
        let ndc = DVec4::new(
            position.x / v.x * 2.0 - 1.0,
            1.0 - position.y / v.y * 2.0,
            depth as f64,
            1.0,
        );
        let local = clip_from_local.inverse() * ndc;
        local.truncate() / local.w
    }

    /// Two frames of one object point: the cameras, the object's
    /// transforms, the point (local), and the viewport. `step` when the
    /// motion is that of consecutive frames (small), rather than any.
    #[derive(Debug)]
    struct Frames {
        previous: Camera,
        current: Camera,
        previous_object: DMat4,
        current_object: DMat4,
        local: DVec3,
        viewport: Vec2,
        step: bool,
    }

    impl Frames {
        fn aspect(&self) -> f64 {
            (self.viewport.x / self.viewport.y) as f64
        }

        fn previous_clip_from_local(&self) -> DMat4 {
            self.previous.clip_from_world(self.aspect()) * self.previous_object
        }

        fn current_clip_from_local(&self) -> DMat4 {
            self.current.clip_from_world(self.aspect()) * self.current_object
        }

        fn visible_in_both(&self) -> bool {
            let (a, b) = (
                self.previous_clip_from_local(),
                self.current_clip_from_local(),
            );
            exact_position(a, self.local, self.viewport).is_some()
                && exact_position(b, self.local, self.viewport).is_some()
        }

        /// The previous clip position as the instrumented vertex stage
        /// computes it, from last frame's uniforms.
        fn previous_clip(&self) -> Vec4 {
            vertex_clip(
                self.previous.clip_from_world(self.aspect()),
                self.previous_object,
                self.local,
            )
        }
    }

    /// One frame's motion of a camera: eye and target moved by up to half
    /// a unit, the field of view by up to 2°.
    fn camera_step(camera: Camera) -> impl Strategy<Value = Camera> {
        (vec3(0.5), vec3(0.5), -2.0..2.0f64).prop_map(move |(eye, target, fov)| Camera {
            eye: camera.eye + eye,
            target: camera.target + target,
            fov_degrees: camera.fov_degrees + fov,
            ..camera
        })
    }

    /// One frame's motion of an object: up to 0.2 rad of rotation, half a
    /// unit of translation and 10% of scale, applied in world space.
    fn object_step() -> impl Strategy<Value = DMat4> {
        (vec3(1.0), -0.2..0.2f64, vec3(0.5), 0.9..1.1f64).prop_map(
            |(axis, angle, translation, scale)| transform(axis, angle, translation, scale),
        )
    }

    /// A point placed in last frame's view, on an object that may move
    /// (`moving`), seen by a camera that moves by a frame's step or (not
    /// `step`) to anywhere looking towards where the point is now, or (not
    /// `camera_moves`) stays.
    fn frames(moving: bool, camera_moves: bool) -> impl Strategy<Value = Frames> {
        (
            camera_towards(DVec3::ZERO),
            object(),
            object_step(),
            object(),
            placement(),
            viewport(),
            any::<bool>(),
        )
            .prop_flat_map(
                move |(
                    previous,
                    previous_object,
                    delta,
                    other,
                    (ndc, distance),
                    viewport,
                    step,
                )| {
                    let aspect = (viewport.x / viewport.y) as f64;
                    let world = previous.point(aspect, ndc, distance);
                    let local = previous_object.inverse().transform_point3(world);
                    let current_object = match (moving, step) {
                        (false, _) => previous_object,
                        (true, true) => delta * previous_object,
                        (true, false) => other,
                    };
                    let now = current_object.transform_point3(local);
                    let current = match (camera_moves, step) {
                        (false, _) => Just(previous).boxed(),
                        (true, true) => camera_step(previous).boxed(),
                        (true, false) => camera_towards(now).boxed(),
                    };
                    current.prop_map(move |current| Frames {
                        previous,
                        current,
                        previous_object,
                        current_object,
                        local,
                        viewport,
                        step: step || !camera_moves,
                    })
                },
            )
    }

    /// The checks both motion properties share: the reprojection lands
    /// within 0.01 px of where last frame drew the point, whatever the
    /// motion. For a frame's step of motion, the cache texel found there,
    /// taken back through last frame's matrices at its depth (f32, as the
    /// depth buffer holds it) and forward through this frame's, is this
    /// frame's pixel again within 0.01 px. (Across arbitrary motion, a
    /// camera much closer than last frame's magnifies last frame's pixels,
    /// and the depth buffer's precision along the view ray, beyond that.)
    fn check(frames: &Frames) -> Result<(), TestCaseError> {
        let viewport = frames.viewport;
        let previous_clip = frames.previous_clip();
        let texel = texel_position(previous_clip, viewport);
        let drawn =
            exact_position(frames.previous_clip_from_local(), frames.local, viewport).unwrap();
        prop_assert!(
            (texel.as_dvec2() + 0.5 - drawn.truncate())
                .abs()
                .max_element()
                < 0.01,
            "texel {texel} drawn at {drawn}"
        );
        prop_assert!(footprint_inside(previous_clip, viewport) || on_the_rim(texel, viewport));
        if !frames.step {
            return Ok(());
        }

        let now = exact_position(frames.current_clip_from_local(), frames.local, viewport).unwrap();
        let back = unproject(
            frames.previous_clip_from_local(),
            texel,
            ndc(previous_clip).z,
            viewport,
        );
        let again = exact_position(frames.current_clip_from_local(), back, viewport);
        prop_assert!(
            again.is_some_and(|p| (p.truncate() - now.truncate()).abs().max_element() < 0.01),
            "{again:?} against {now}"
        );
        Ok(())
    }

    /// Within the outer half texel of the viewport, where the footprint
    /// leaves the texel centres and the lookup rightly misses.
    fn on_the_rim(texel: Vec2, viewport: Vec2) -> bool {
        texel.cmplt(Vec2::ZERO).any() || texel.cmpgt(viewport - Vec2::ONE).any()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// A point fixed in the world, seen by two random cameras, lands
        /// within 0.01 px of where last frame drew it; with the camera
        /// still too, that is its own pixel's texel centre.
        #[test]
        fn static_point_reprojects_to_where_it_was_drawn(
            frames in frames(false, true),
            still in frames(false, false),
        ) {
            prop_assume!(frames.visible_in_both() && still.visible_in_both());
            check(&frames)?;
            check(&still)?;
            let texel = texel_position(still.previous_clip(), still.viewport);
            let current_clip = vertex_clip(
                still.current.clip_from_world(still.aspect()),
                still.current_object,
                still.local,
            );
            let pixel = pixel_position(current_clip, still.viewport);
            prop_assert!((texel + Vec2::splat(0.5) - pixel).abs().max_element() < 0.01);
        }

        /// A point on a moving object, reprojected with last frame's object
        /// transform (the previous-frame uniforms), lands within 0.01 px of
        /// where last frame drew it, and maps back to this frame's pixel.
        #[test]
        fn moving_point_reprojects_with_last_frames_transform(
            frames in frames(true, true),
        ) {
            prop_assume!(frames.visible_in_both());
            check(&frames)?;
        }

        /// A point behind the previous camera (or on its plane: w = 0) is
        /// never inside, for either lookup, though its NDC, whose signs the
        /// divide by a negative w flips, often lands in the viewport.
        #[test]
        fn behind_the_previous_camera_is_never_inside(
            previous in camera_towards(DVec3::ZERO),
            world_from_local in object(),
            behind in prop_oneof![Just(0.0), 0.0..50.0f64],
            spread in (-2.0..2.0f64, -2.0..2.0f64),
            viewport in viewport(),
        ) {
            let aspect = (viewport.x / viewport.y) as f64;
            // In view space the camera looks down -z: z ≥ 0 is behind it.
            // Laterally within twice the mirrored view's width.
            let half = (previous.fov_degrees.to_radians() * 0.5).tan() * behind.max(1.0);
            let in_view = DVec3::new(spread.0 * half * aspect, spread.1 * half, behind);
            let world = previous.view().inverse().transform_point3(in_view);
            let local = world_from_local.inverse().transform_point3(world);
            let clip = vertex_clip(previous.clip_from_world(aspect), world_from_local, local);
            prop_assume!(clip.w <= 0.0, "rounding put it in front");
            prop_assert!(!footprint_inside(clip, viewport));
            prop_assert!(!nearest_inside(clip, viewport));
            let depth = vec![0.5; (viewport.x * viewport.y) as usize];
            let cache = PreviousDepth { size: viewport.as_uvec2(), depth: &depth, epsilon: 1e-3, far_depth: 1.0 };
            prop_assert_eq!(footprint(clip, Vec2::ZERO, &cache).status, Status::Offscreen);
            prop_assert_eq!(nearest(clip, Vec2::ZERO, &cache).0, Status::Offscreen);
        }
    }

    /// The slope per previous texel comes back through any zoom and roll
    /// of the mapping; a singular mapping keeps the slope per pixel.
    #[test]
    fn previous_slope_undoes_the_mapping() {
        let per_texel = Vec2::new(0.03, -0.01);
        for (scale, angle) in [(1.0f32, 0.0f32), (0.5, 0.3), (2.0, -1.2), (1.3, 3.0)] {
            let along_x = Vec2::new(angle.cos(), angle.sin()) * scale;
            let along_y = along_x.perp();
            let per_pixel = Vec2::new(per_texel.dot(along_x), per_texel.dot(along_y));
            let back = previous_slope(per_pixel, along_x, along_y);
            assert!((back - per_texel).abs().max_element() < 1e-6, "{back}");
        }
        let flat = previous_slope(Vec2::new(0.1, 0.2), Vec2::ZERO, Vec2::Y);
        assert_eq!(flat, Vec2::new(0.1, 0.2));
    }

    /// A value is stale at Δn frames, at most at the age limit, never
    /// with refresh off.
    #[test]
    fn staleness_reaches_at_the_period() {
        assert!(!stale(7.0, 8) && stale(8.0, 8));
        assert!(!stale(1e9, 0));
        assert!(stale(AGE_LIMIT, 65535) && !stale(AGE_LIMIT - 1.0, 65535));
    }

    /// The footprint of a point on a texel centre is that texel alone.
    #[test]
    fn a_texel_centre_is_its_own_footprint() {
        let clip = Vec4::new(-1.0 + 5.5 / 8.0, 1.0 - 3.5 / 8.0, 0.5, 1.0);
        let depth = vec![0.5; 256];
        let cache = PreviousDepth {
            size: UVec2::new(16, 16),
            depth: &depth,
            epsilon: 1e-3,
            far_depth: 1.0,
        };
        let found = footprint(clip, Vec2::ZERO, &cache);
        assert_eq!(found.status, Status::Hit);
        assert_eq!(found.base, Vec2::new(5.0, 3.0));
        assert_eq!(found.fraction, Vec2::ZERO);
        assert_eq!(found.taps()[3], (IVec2::new(5, 3), 1.0));
        assert_eq!(
            nearest(clip, Vec2::ZERO, &cache),
            (Status::Hit, IVec2::new(5, 3))
        );
    }

    /// Block offsets fall in [0, Δn) and spread evenly: over 256×256
    /// blocks, every offset's count is within 5 standard deviations of
    /// blocks/Δn, and no two neighbouring blocks agree much more often than
    /// 1/Δn (a pattern, not noise, would).
    #[test]
    fn refresh_offsets_are_uniform_over_the_period() {
        for period in [1u32, 2, 7, 8, 32, 64, 100, 1000] {
            let mut counts = vec![0u32; period as usize];
            let mut same_as_left = 0u32;
            for y in 0..256 {
                for x in 0..256 {
                    let offset = refresh_offset(x, y, period);
                    assert!(offset < period, "Δn {period}: offset {offset}");
                    counts[offset as usize] += 1;
                    if x > 0 && refresh_offset(x - 1, y, period) == offset {
                        same_as_left += 1;
                    }
                }
            }
            let blocks = 65536.0;
            let expected = blocks / f64::from(period);
            let sigma = (expected * (1.0 - 1.0 / f64::from(period))).sqrt();
            for (offset, &count) in counts.iter().enumerate() {
                assert!(
                    (f64::from(count) - expected).abs() <= 5.0 * sigma + 1e-9,
                    "Δn {period}: offset {offset} taken {count} times, expected {expected:.0}"
                );
            }
            let pairs = 256.0 * 255.0;
            let agree = f64::from(same_as_left) / pairs;
            assert!(
                agree <= 1.0 / f64::from(period) + 5.0 * (1.0 / f64::from(period) / pairs).sqrt(),
                "Δn {period}: neighbours agree {agree:.4}"
            );
        }
        // The largest period keeps h·Δn within a u32 and offsets in range.
        for x in 0..64 {
            assert!(refresh_offset(x, 3 * x, 65535) < 65535);
        }
    }
}

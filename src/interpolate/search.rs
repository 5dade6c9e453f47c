//! The image-based search of `shaders/bframe.wgsl` (`search`), on the CPU.
//!
//! Seed 000's eqs. 4–7 (and 8–12 the other way) are a fixed-point
//! iteration q ← p − s·V(q), stopped after m steps; its residual
//! |q + s·V(q) − p| is the screen-space error the decisions threshold. The
//! shader reads V per texel (unfiltered: a filtered flow mixes an object's
//! motion with the background's along its silhouette), and stops early
//! where a step stays in its texel, because from there every step reads
//! the same V and lands on the same point. The mirror here lets tests
//! state what the iteration does for a given flow field without a GPU:
//! for a translation (V constant) it is exact after one step at any
//! speed; for a zoom V(q) = k·(q − c) the distance to the fixed point
//! contracts by |s·k| per step, up to half a texel's diagonal of
//! quantisation; stopping early changes nothing. **A change to the
//! shader's search must be made here too.**

use glam::{IVec2, Vec2};

/// A correspondence the search found: the point, and its residual in
/// pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    pub point: Vec2,
    pub residual: f32,
}

/// The texel a point lies in (`texel` of the shader, without its clamp to
/// the frame).
pub fn texel(q: Vec2) -> IVec2 {
    q.floor().as_ivec2()
}

/// `search` of `shaders/bframe.wgsl`: from `start`, up to `iterations`
/// steps of q ← p − s·V(texel(q)), stopping where a step stays in its
/// texel; then the residual. `flow` is the I-frame's flow texture.
pub fn search(
    flow: impl Fn(IVec2) -> Vec2,
    p: Vec2,
    start: Vec2,
    s: f32,
    iterations: u32,
) -> Found {
    search_with(flow, p, start, s, iterations, true)
}

fn search_with(
    flow: impl Fn(IVec2) -> Vec2,
    p: Vec2,
    start: Vec2,
    s: f32,
    iterations: u32,
    stop_in_texel: bool,
) -> Found {
    let mut q = start;
    let mut v = flow(texel(q));
    for _ in 0..iterations {
        let next = p - s * v;
        let stays = texel(next) == texel(q);
        q = next;
        if stays && stop_in_texel {
            break;
        }
        v = flow(texel(q));
    }
    Found {
        point: q,
        residual: (q + s * v - p).length(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Half a texel's diagonal: how far a point is from its texel's centre
    /// at most.
    const HALF_DIAGONAL: f32 = std::f32::consts::FRAC_1_SQRT_2;

    fn centre(t: IVec2) -> Vec2 {
        t.as_vec2() + 0.5
    }

    proptest! {
        /// Pure translation: V is the same everywhere, so one step lands
        /// on the fixed point whatever the speed (000 §5.1: eq. 3's
        /// solution exists and is unique).
        #[test]
        fn pure_translation_search_converges_in_one_iteration(
            speed in 0.0f32..512.0,
            angle in 0.0f32..std::f32::consts::TAU,
            alpha in 0.05f32..0.95,
            px in 0.0f32..512.0,
            py in 0.0f32..512.0,
        ) {
            let v = Vec2::from_angle(angle) * speed;
            let p = Vec2::new(px, py);
            let found = search(|_| v, p, p, alpha, 1);
            prop_assert!(found.residual <= 1e-3 * (1.0 + speed), "residual {}", found.residual);
            prop_assert!((found.point - (p - alpha * v)).length() <= 1e-3 * (1.0 + speed));
        }

        /// A zoom about c, V(q) = k·(q − c), stored per texel (k times the
        /// texel centre's offset): each step multiplies the distance to
        /// the fixed point q* = (p + s·k·c) / (1 + s·k) by a = |s·k| and
        /// adds at most a times the half diagonal of quantisation, so
        /// after m steps it is within a^m·|q₀ − q*| + d·a·(1 − a^m)/(1 − a).
        #[test]
        fn zoom_search_contracts_by_alpha_k(
            k in -1.5f32..1.5,
            alpha in 0.1f32..0.9,
            px in -64.0f32..64.0,
            py in -64.0f32..64.0,
        ) {
            let c = Vec2::new(128.0, 96.0);
            let p = c + Vec2::new(px, py);
            let flow = |t: IVec2| k * (centre(t) - c);
            let a = (alpha * k).abs();
            prop_assume!(a < 0.95);
            let fixed = (p + alpha * k * c) / (1.0 + alpha * k);
            let first = (p - fixed).length();
            for m in 1..5 {
                let distance = (search(flow, p, p, alpha, m).point - fixed).length();
                let bound = first * a.powi(m as i32)
                    + HALF_DIAGONAL * a * (1.0 - a.powi(m as i32)) / (1.0 - a);
                prop_assert!(
                    distance <= bound + 1e-3 * (1.0 + first),
                    "m = {m}: {distance} px from the fixed point, bound {bound}"
                );
            }
        }

        /// The early stop is only a saving: on any per-texel flow field,
        /// from any start, the point and residual equal those of all m
        /// steps.
        #[test]
        fn stopping_where_a_step_stays_in_its_texel_changes_nothing(
            seed in any::<u32>(),
            scale in 0.0f32..24.0,
            alpha in 0.05f32..0.95,
            px in 0.0f32..64.0,
            py in 0.0f32..64.0,
            m in 1u32..7,
        ) {
            // A rough flow field: a hash of the texel, a few texels long.
            let flow = |t: IVec2| {
                let h = (t.x as u32).wrapping_mul(0x9e37_79b9)
                    ^ (t.y as u32).wrapping_mul(0x85eb_ca6b)
                    ^ seed;
                let h = h.wrapping_mul(0xc2b2_ae35);
                Vec2::new((h & 0xffff) as f32, (h >> 16) as f32) / 65535.0 * 2.0 * scale
                    - Vec2::splat(scale)
            };
            let p = Vec2::new(px, py);
            let stopped = search_with(flow, p, p, alpha, m, true);
            let full = search_with(flow, p, p, alpha, m, false);
            prop_assert_eq!(stopped, full);
        }
    }
}

//! The image-based search of `shaders/bframe.wgsl` (`search`), on the CPU.
//!
//! Seed 000's eqs. 4–7 (and 8–12 the other way) are a fixed-point
//! iteration q ← p − s·V(q), stopped after m steps; its residual
//! |q + s·V(q) − p| is the screen-space error the decisions threshold. The
//! mirror here lets tests state what the iteration does for a given flow
//! field without a GPU: for a translation (V constant) it is exact after
//! one step at any speed; for a zoom V(q) = k·(q − c) the error contracts
//! by |s·k| per step. **A change to the shader's search must be made here
//! too.**

use glam::Vec2;

/// A correspondence the search found: the point, and its residual in
/// pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    pub point: Vec2,
    pub residual: f32,
}

/// `search` of `shaders/bframe.wgsl`: from `start`, `iterations` steps of
/// q ← p − s·V(q); then the residual.
pub fn search(flow: impl Fn(Vec2) -> Vec2, p: Vec2, start: Vec2, s: f32, iterations: u32) -> Found {
    let mut q = start;
    for _ in 0..iterations {
        q = p - s * flow(q);
    }
    Found {
        point: q,
        residual: (q + s * flow(q) - p).length(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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

        /// A zoom about c, V(q) = k·(q − c): each step multiplies the
        /// error by s·k (a contraction while |s·k| < 1), so after m steps
        /// the residual is |s·k|^m times the first guess's.
        #[test]
        fn zoom_search_contracts_by_alpha_k(
            k in -1.5f32..1.5,
            alpha in 0.1f32..0.9,
            px in -64.0f32..64.0,
            py in -64.0f32..64.0,
        ) {
            let c = Vec2::new(128.0, 96.0);
            let p = c + Vec2::new(px, py);
            let flow = |q: Vec2| k * (q - c);
            let factor = (alpha * k).abs();
            let first = search(flow, p, p, alpha, 0).residual;
            for m in 1..4 {
                let residual = search(flow, p, p, alpha, m).residual;
                let expected = first * factor.powi(m as i32);
                prop_assert!(
                    (residual - expected).abs() <= 1e-3 * (1.0 + first),
                    "m = {m}: residual {residual}, expected {expected}"
                );
            }
        }
    }
}

//! Where the motion is discontinuous: the pixels near a motion edge, over
//! which each method's error is also measured (`edge_psnr` in the
//! report). Every method that warps, searches or blurs does worst there
//! (disocclusions open, a warp's grid stretches, a blur mixes both
//! sides), and a whole-frame mean dilutes it with the pixels every method
//! gets right.

/// A motion edge is where the flows of 4-neighbours differ by at least
/// this, in pixels over the interval, or where one has a valid flow and
/// the other none (geometry against the background).
pub const EDGE_STEP_PX: f32 = 1.0;

/// How far from an edge a pixel counts as near it (Chebyshev distance):
/// the reach of the morph's blur at its default level and of a grid tile,
/// and what the fidelity review measured.
pub const EDGE_RADIUS_PX: usize = 12;

/// The pixels within `radius` of a motion edge of `flow` (RGBA per pixel:
/// Δx, Δy in pixels, Δz, valid), `[width, height]`, row by row.
pub fn near_motion_edges(flow: &[f32], [width, height]: [usize; 2], radius: usize) -> Vec<bool> {
    let at = |x: usize, y: usize| {
        let f = &flow[(y * width + x) * 4..(y * width + x) * 4 + 4];
        (f[3] > 0.0).then_some([f[0], f[1]])
    };
    let differ = |a: Option<[f32; 2]>, b: Option<[f32; 2]>| match (a, b) {
        (Some(a), Some(b)) => (a[0] - b[0]).hypot(a[1] - b[1]) >= EDGE_STEP_PX,
        (None, None) => false,
        _ => true,
    };
    let mut edges = vec![false; width * height];
    for y in 0..height {
        for x in 0..width {
            let here = at(x, y);
            if x + 1 < width && differ(here, at(x + 1, y)) {
                edges[y * width + x] = true;
                edges[y * width + x + 1] = true;
            }
            if y + 1 < height && differ(here, at(x, y + 1)) {
                edges[y * width + x] = true;
                edges[(y + 1) * width + x] = true;
            }
        }
    }
    dilate(&edges, [width, height], radius)
}

/// `mask` grown by `radius` pixels in every direction (a square: a
/// separable maximum, rows then columns).
fn dilate(mask: &[bool], [width, height]: [usize; 2], radius: usize) -> Vec<bool> {
    let mut rows = vec![false; mask.len()];
    for y in 0..height {
        for x in 0..width {
            let (from, to) = (x.saturating_sub(radius), (x + radius).min(width - 1));
            rows[y * width + x] = (from..=to).any(|i| mask[y * width + i]);
        }
    }
    let mut out = vec![false; mask.len()];
    for y in 0..height {
        for x in 0..width {
            let (from, to) = (y.saturating_sub(radius), (y + radius).min(height - 1));
            out[y * width + x] = (from..=to).any(|j| rows[j * width + x]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::near_motion_edges;

    /// A square moving 3 px over a still, valid background: its outline is
    /// an edge, and the pixels within the radius of it are near; uniform
    /// motion elsewhere (the square's inside, the background) is not.
    #[test]
    fn motion_edges_are_where_neighbouring_flows_differ() {
        let (w, h) = (32usize, 32usize);
        let mut flow = vec![0.0f32; w * h * 4];
        for y in 0..h {
            for x in 0..w {
                let p = (y * w + x) * 4;
                flow[p + 3] = 1.0;
                if (10..20).contains(&x) && (10..20).contains(&y) {
                    flow[p] = 3.0;
                }
            }
        }
        let near = near_motion_edges(&flow, [w, h], 2);
        let at = |x: usize, y: usize| near[y * w + x];
        assert!(at(9, 15) && at(10, 15) && at(19, 15) && at(20, 15));
        assert!(at(7, 15) && at(12, 15), "within 2 of the edge");
        assert!(!at(6, 15) && !at(13, 15), "3 from the edge");
        assert!(!at(15, 15) && !at(0, 0));
        // Uniform motion everywhere: no edge at all.
        let still: Vec<f32> = flow.chunks(4).flat_map(|_| [3.0, 0.0, 0.0, 1.0]).collect();
        assert!(near_motion_edges(&still, [w, h], 12).iter().all(|&n| !n));
    }
}

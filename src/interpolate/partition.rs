//! Partitioned rendering (seed 000 §7, Fig. 5): an I-frame's draws
//! spread over the n displayed frames before it is needed, so that every
//! displayed frame costs about the same.
//!
//! The paper divides "the draw calls into groups with roughly uniform
//! render cost", which "may require profiling the cost of all render
//! tasks". Here the run profiles: each object's draw is timed alone at
//! the first I-frame (over an empty frame's cost), and the frame's draws,
//! in their order, are cut into n contiguous parts of about equal
//! measured cost ([`split`]). A cut may fall inside an object's draw: it
//! is split along its instances when it has several (the paper's
//! "characters were uniformly partitioned"), else along its triangles
//! (the cells of the paper's terrain grid only where the mesh's index
//! order follows them), its cost spread evenly over
//! them. The parts keep the draws' order, so drawn one after another
//! into the same targets, each loading what the one before left
//! ([`crate::runtime::Runner::frame_part`]), they make the frame drawn
//! at once, exactly (the depth test sees the same fragments in the same
//! order).

use crate::runtime::{DrawShare, FramePart};

/// Cuts the draws `whole` (in order) into `n` contiguous parts of about
/// equal cost, `costs[i]` being the cost of `whole[i]` (its measured
/// time; a cost ≤ 0 counts as nothing). The first part begins the frame,
/// the others add to it. A part can be empty where one draw outweighs a
/// part and cannot be split finer (one triangle, one instance).
pub fn split(whole: &[DrawShare], costs: &[f64], n: u32) -> Vec<FramePart> {
    let n = n.max(1) as usize;
    let cost = |i: usize| costs.get(i).copied().unwrap_or(0.0).max(0.0);
    let total: f64 = (0..whole.len()).map(cost).sum();
    let mut parts: Vec<FramePart> = (0..n)
        .map(|j| FramePart {
            draws: Vec::new(),
            more: j > 0,
        })
        .collect();
    // The cost before each draw, and each part's share of the total.
    let mut before = 0.0;
    for (i, draw) in whole.iter().enumerate() {
        let units = Units::of(draw);
        let unit_cost = cost(i) / f64::from(units.count.max(1));
        // The units of this draw that fall in each part: unit u starts at
        // before + u·unit_cost and belongs to the part its middle is in.
        let part_of = |u: u32| -> usize {
            if total <= 0.0 {
                // No costs measured: split the draws' order evenly.
                return (i * n / whole.len().max(1)).min(n - 1);
            }
            let middle = before + (f64::from(u) + 0.5) * unit_cost;
            ((middle / total * n as f64) as usize).min(n - 1)
        };
        let mut start = 0;
        while start < units.count {
            let part = part_of(start);
            let mut end = start + 1;
            while end < units.count && part_of(end) == part {
                end += 1;
            }
            parts[part].draws.push(units.share(draw, start..end));
            start = end;
        }
        before += cost(i);
    }
    parts
}

/// What a draw is split along: its instances when it has several, else
/// its triangles.
struct Units {
    count: u32,
    along_instances: bool,
}

impl Units {
    fn of(draw: &DrawShare) -> Units {
        let instances = draw.instances.len() as u32;
        if instances > 1 {
            Units {
                count: instances,
                along_instances: true,
            }
        } else {
            Units {
                count: (draw.indices.len() as u32) / 3,
                along_instances: false,
            }
        }
    }

    /// The share of `draw` of units `range`.
    fn share(&self, draw: &DrawShare, range: std::ops::Range<u32>) -> DrawShare {
        if self.along_instances {
            let first = draw.instances.start;
            DrawShare {
                instances: first + range.start..first + range.end,
                ..draw.clone()
            }
        } else {
            let first = draw.indices.start;
            DrawShare {
                indices: first + range.start * 3..first + range.end * 3,
                ..draw.clone()
            }
        }
    }
}

/// One measured interval's work, ms, as its displayed frames share it:
/// the frames after its opening I-frame, the last its closing I-frame.
#[derive(Clone, Copy, Debug)]
pub struct IntervalWork<'a> {
    /// Its B-frames' times, in order (k = 1 … n − 1).
    pub bframes: &'a [f64],
    /// The closing I-frame's time drawn at once.
    pub iframe: f64,
    /// With partitioning, the closing I-frame's parts' times (n of them):
    /// drawn one per displayed frame, the last with the I-frame shown.
    pub parts: Option<&'a [f64]>,
    /// What the method adds to each I-frame (the morph's preparation, the
    /// payload's pass), drawn with the I-frame.
    pub added: f64,
}

impl IntervalWork<'_> {
    /// Each displayed frame's time: a B-frame's pass (and a part of the
    /// next I-frame), then the I-frame's (at once, or its last part) with
    /// what the method adds.
    pub fn frame_times(&self) -> Vec<f64> {
        let part = |k: usize| self.parts.and_then(|p| p.get(k)).copied().unwrap_or(0.0);
        let mut times: Vec<f64> = self
            .bframes
            .iter()
            .enumerate()
            .map(|(k, b)| b + part(k))
            .collect();
        let last = self.bframes.len();
        let iframe = match self.parts {
            Some(_) => part(last),
            None => self.iframe,
        };
        times.push(iframe + self.added);
        times
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn draw(object: usize, triangles: u32, instances: u32) -> DrawShare {
        DrawShare {
            object,
            indices: 0..triangles * 3,
            instances: 0..instances,
        }
    }

    /// Every unit of every draw is in exactly one part, in the draws'
    /// order.
    fn assert_covers(whole: &[DrawShare], parts: &[FramePart]) {
        let flat: Vec<&DrawShare> = parts.iter().flat_map(|p| &p.draws).collect();
        let mut at = 0;
        for draw in whole {
            let mut indices = draw.indices.start;
            let mut instances = draw.instances.start;
            while at < flat.len() && flat[at].object == draw.object {
                let share = flat[at];
                if share.instances == draw.instances {
                    assert_eq!(share.indices.start, indices);
                    indices = share.indices.end;
                } else {
                    assert_eq!(share.indices, draw.indices);
                    assert_eq!(share.instances.start, instances);
                    instances = share.instances.end;
                }
                at += 1;
            }
            assert!(
                indices == draw.indices.end || instances == draw.instances.end,
                "object {} not covered",
                draw.object
            );
        }
        assert_eq!(at, flat.len());
    }

    #[test]
    fn equal_objects_go_one_part_each() {
        let whole: Vec<_> = (0..4).map(|i| draw(i, 10, 1)).collect();
        let parts = split(&whole, &[1.0; 4], 4);
        for (j, part) in parts.iter().enumerate() {
            assert_eq!(part.draws, vec![whole[j].clone()]);
            assert_eq!(part.more, j > 0);
        }
    }

    #[test]
    fn an_expensive_object_is_split_along_its_triangles() {
        // One floor costing as much as three spheres: it takes two parts.
        let whole = vec![draw(0, 100, 1), draw(1, 50, 1), draw(2, 50, 1)];
        let parts = split(&whole, &[2.0, 1.0, 1.0], 4);
        assert_covers(&whole, &parts);
        assert_eq!(
            parts[0].draws,
            vec![DrawShare {
                indices: 0..150,
                ..whole[0].clone()
            }]
        );
        assert_eq!(
            parts[1].draws,
            vec![DrawShare {
                indices: 150..300,
                ..whole[0].clone()
            }]
        );
        assert_eq!(parts[2].draws, vec![whole[1].clone()]);
        assert_eq!(parts[3].draws, vec![whole[2].clone()]);
    }

    #[test]
    fn instanced_draws_split_along_instances() {
        let whole = vec![draw(0, 12, 8)];
        let parts = split(&whole, &[1.0], 4);
        assert_covers(&whole, &parts);
        for (j, part) in parts.iter().enumerate() {
            let j = j as u32;
            assert_eq!(part.draws[0].instances, 2 * j..2 * j + 2);
            assert_eq!(part.draws[0].indices, 0..36);
        }
    }

    #[test]
    fn an_unsplittable_draw_leaves_parts_empty() {
        let whole = vec![draw(0, 1, 1), draw(1, 1, 1)];
        let parts = split(&whole, &[3.0, 1.0], 4);
        assert_covers(&whole, &parts);
        let counts: Vec<usize> = parts.iter().map(|p| p.draws.len()).collect();
        assert_eq!(counts.iter().sum::<usize>(), 2);
        assert!(counts.contains(&0));
    }

    #[test]
    fn without_costs_the_draws_split_evenly() {
        let whole: Vec<_> = (0..8).map(|i| draw(i, 4, 1)).collect();
        let parts = split(&whole, &[0.0; 8], 4);
        assert_covers(&whole, &parts);
        assert!(parts.iter().all(|p| p.draws.len() == 2));
    }

    #[test]
    fn partitioned_work_spreads_the_iframe_over_the_frames() {
        let at_once = IntervalWork {
            bframes: &[1.0, 1.0, 1.0],
            iframe: 4.0,
            parts: None,
            added: 0.5,
        };
        assert_eq!(at_once.frame_times(), vec![1.0, 1.0, 1.0, 4.5]);
        let parts = [1.0, 1.0, 1.0, 1.25];
        let partitioned = IntervalWork {
            parts: Some(&parts),
            ..at_once
        };
        assert_eq!(partitioned.frame_times(), vec![2.0, 2.0, 2.0, 1.75]);
        // The same work either way, but the parts' overhead.
        let total = |w: &IntervalWork| w.frame_times().iter().sum::<f64>();
        assert_eq!(total(&at_once) + 0.25, total(&partitioned));
    }
}

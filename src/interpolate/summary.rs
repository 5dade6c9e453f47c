//! The measured run summed up as the report says it: each method's time
//! ratios (its I-frames' and B-frames' against the reference), its
//! errors, its displayed frames' times and the run's notes.

use std::collections::BTreeMap;
use std::path::Path;

use super::bframe::Decision;
use super::frames::Frames;
use super::measured::{Measured, MethodRun};
use super::report::{self, DisplayedFrame, FrameTimes, MethodReport, Parameters, Pictures, Report};
use super::Method;
use crate::front::Shader;
use crate::measure::clock::Clock;
use crate::measure::metrics::{self, FrameError};

/// How a measured run is summed up: its frames, and whether its I-frames
/// were drawn in parts.
pub(super) struct Summary<'a> {
    pub frames: &'a Frames<'a>,
    pub partitioned: bool,
}

impl Summary<'_> {
    /// The time of each displayed frame `method` showed over the measured
    /// intervals: its B-frames' passes and its I-frames' (the original's
    /// for the methods that read no flows), with `--partition` the
    /// I-frames' parts spread over the frames.
    fn displayed_frame_times(&self, method: Method, measured: &Measured) -> Vec<f64> {
        let n = self.frames.options.frames_per_interval as usize;
        if method == Method::Reference {
            return measured.reference_times.clone();
        }
        let run = measured.methods.get(&method);
        let bframes = run.map_or(&[][..], |r| &r.times[..]);
        let mut times = Vec::new();
        for (i, chunk) in bframes.chunks(n - 1).enumerate() {
            let (iframe, parts) = if run.is_some_and(|r| r.reads_flows) {
                (measured.iframe_times.get(i), measured.iframe_parts.get(i))
            } else {
                (
                    measured.reference_times.get(i * n + n - 1),
                    measured.reference_parts.get(i),
                )
            };
            let work = super::partition::IntervalWork {
                bframes: chunk,
                iframe: iframe.copied().unwrap_or(0.0),
                parts: parts.map(|p| &p[..]),
                added: run
                    .and_then(|r| r.prepare_times.get(i))
                    .copied()
                    .unwrap_or(0.0),
            };
            times.extend(work.frame_times());
        }
        times
    }

    /// What `method` measured, as the report says it.
    fn method_report(
        &self,
        method: Method,
        measured: &Measured,
        (reference_ms, iframe_ms): (f64, f64),
    ) -> MethodReport {
        let n = self.frames.options.frames_per_interval;
        let run = measured.methods.get(&method);
        let blur = measured.blur.as_ref().and_then(|b| match method {
            Method::Reference => Some((1.0, metrics::PSNR_CAP)),
            _ => b.of(method),
        });
        let b_ms = run.map_or(0.0, |r| metrics::median(&r.times));
        // The methods whose I-frames add passes of their own (the morph's
        // preparation, the payload's pass) timed them beside the I-frame.
        let adds_passes = run.is_some_and(|r| !r.prepare_times.is_empty());
        let reads_flows = run.is_some_and(|r| r.reads_flows);
        let i_ms = if adds_passes {
            iframe_ms + run.map_or(0.0, |r| metrics::median(&r.prepare_times))
        } else if reads_flows {
            iframe_ms
        } else {
            reference_ms
        };
        let (i_ratio, b_ratio, amortized) = if method == Method::Reference {
            (1.0, 1.0, 1.0)
        } else {
            (
                i_ms / reference_ms,
                b_ms / reference_ms,
                (i_ms + f64::from(n - 1) * b_ms) / (f64::from(n) * reference_ms),
            )
        };
        let errors: Vec<&FrameError> = run
            .map(|r| r.frames.iter().map(|(_, _, e)| e).collect())
            .unwrap_or_default();
        let ssims: Vec<f64> = errors.iter().map(|e| e.ssim).collect();
        let psnrs: Vec<f64> = errors.iter().map(|e| e.psnr_frame).collect();
        let double_miss_rate = (method == Method::ImageBased).then(|| double_miss_rate(run));
        MethodReport {
            method,
            frames_per_interval: n,
            i_frame_time_ratio: i_ratio,
            b_frame_time_ratio: b_ratio,
            amortized_time_ratio: amortized,
            b_frame_ms: b_ms,
            ssim_mean: if method == Method::Reference {
                1.0
            } else {
                metrics::mean(&ssims)
            },
            ssim_min: ssims.iter().copied().fold(1.0, f64::min),
            psnr_mean: if method == Method::Reference {
                metrics::PSNR_CAP
            } else {
                metrics::mean(&psnrs)
            },
            double_miss_rate,
            correspondence_error_px: (method == Method::ImageBased)
                .then(|| correspondence_error(measured))
                .flatten(),
            added_latency_frames: if run.is_some_and(|r| r.reads_later_frame) || self.partitioned {
                f64::from(n - 1)
            } else {
                0.0
            },
            displayed_frame_ms: FrameTimes::of(
                &self.displayed_frame_times(method, measured),
                self.partitioned,
            ),
            worst_frame: run.and_then(|r| r.worst.as_ref().map(|w| w.1)),
            motion_blur_ssim: blur.map(|b| b.0),
            motion_blur_psnr: blur.map(|b| b.1),
            pursuit_error: if method == Method::Reference {
                Some(0.0)
            } else {
                run.filter(|r| !r.pursuit.is_empty())
                    .map(|r| metrics::mean(&r.pursuit))
            },
            flicker: if method == Method::Reference {
                Some(0.0)
            } else {
                run.filter(|r| !r.flicker.is_empty())
                    .map(|r| metrics::mean(&r.flicker))
            },
            displayed_i_frame_psnr: run.filter(|r| !r.displayed_iframes.is_empty()).map(|r| {
                let psnr: Vec<f64> = r
                    .displayed_iframes
                    .iter()
                    .map(|(_, e)| e.psnr_frame)
                    .collect();
                metrics::mean(&psnr)
            }),
            edge_psnr: if method == Method::Reference {
                None
            } else {
                run.filter(|r| !r.edge_psnr.is_empty())
                    .map(|r| metrics::mean(&r.edge_psnr))
            },
            extrapolated_frame_ratio: (method.extrapolates() && adds_passes).then(|| {
                let prepare = run.map_or(0.0, |r| metrics::median(&r.prepare_times));
                (b_ms + prepare / f64::from(n - 1)) / reference_ms
            }),
        }
    }

    pub fn report(
        &self,
        shader: &Shader,
        (scene_path, scene_description): (&Path, &str),
        clock: &Clock,
        measured: Measured,
        intervals: u32,
        mut notes: Vec<String>,
    ) -> (Report, Pictures) {
        let n = self.frames.options.frames_per_interval;
        let reference_ms = metrics::median(&measured.reference_times);
        let iframe_ms = metrics::median(&measured.iframe_times);
        let mut methods = Vec::new();
        let mut pictures = Pictures::default();
        // The methods that ran: the refused ones are in the notes.
        let shown: Vec<Method> = self
            .frames
            .options
            .methods
            .iter()
            .copied()
            .filter(|m| *m == Method::Reference || measured.methods.contains_key(m))
            .collect();
        for &method in &shown {
            let run = measured.methods.get(&method);
            if let Some((_, _, reference, result)) = run.and_then(|r| r.worst.clone()) {
                pictures.worst.push((method, reference, result));
            }
            methods.push(self.method_report(method, &measured, (reference_ms, iframe_ms)));
        }
        let frames = displayed_frames(&shown, &measured);
        notes.push("one I-frame pass writes both flows: the paper renders the forward flow in a geometry pass of its own, so its I-frames cost more than these".to_string());
        if !self.frames.options.methods.contains(&Method::Reference) {
            notes.push("the reference is rendered every frame all the same: the errors and ratios are against it".into());
        }
        notes.extend(report::motion_difference(&methods));
        let answer = report::answer(&methods, n);
        let report = Report {
            format: report::FORMAT,
            shader: shader.file.path.clone(),
            scene: scene_path.display().to_string(),
            scene_description: scene_description.to_string(),
            adapter: format!(
                "{} ({:?})",
                self.frames.gpu.adapter.name, self.frames.gpu.adapter.backend
            ),
            driver: crate::runtime::driver_line(&self.frames.gpu.adapter),
            timing: if clock.timestamps {
                "gpu-timestamps"
            } else {
                "cpu"
            }
            .into(),
            size: self.frames.size,
            frames_per_interval: n,
            intervals,
            parameters: Parameters {
                options: self.frames.options.clone(),
                flow_format: "rgba16float".into(),
                flows: "both flows from the I-frame pass (next- and previous-I-frame twins)".into(),
            },
            reference_ms,
            i_frame_ms: iframe_ms,
            i_frame_psnr_min: measured
                .iframe_errors
                .iter()
                .map(|(_, e)| e.psnr_frame)
                .fold(metrics::PSNR_CAP, f64::min),
            methods,
            frames,
            notes,
            answer,
        };
        pictures.kept = measured.kept;
        pictures.iframes = measured.iframes;
        (report, pictures)
    }
}

/// SSIM of every displayed frame measured, per method: an I-frame's is
/// the I-frame's against the reference (every method shows it, but the
/// extrapolators that compensate, which show their own), a B-frame's the
/// method's; the reference's is 1.
fn displayed_frames(methods: &[Method], measured: &Measured) -> Vec<DisplayedFrame> {
    let mut frames: BTreeMap<u32, DisplayedFrame> = BTreeMap::new();
    for &(frame, ref error) in &measured.iframe_errors {
        frames.insert(
            frame,
            DisplayedFrame {
                frame,
                alpha: 0.0,
                ssim: methods
                    .iter()
                    .map(|&m| {
                        if m == Method::Reference {
                            1.0
                        } else {
                            error.ssim
                        }
                    })
                    .collect(),
            },
        );
    }
    for (i, &method) in methods.iter().enumerate() {
        let Some(run) = measured.methods.get(&method) else {
            continue;
        };
        // The extrapolators that compensate show their own I-frames.
        for &(frame, ref error) in &run.displayed_iframes {
            if let Some(entry) = frames.get_mut(&frame) {
                entry.ssim[i] = error.ssim;
            }
        }
        for &(frame, alpha, ref error) in &run.frames {
            let entry = frames.entry(frame).or_insert_with(|| DisplayedFrame {
                frame,
                alpha,
                ssim: vec![1.0; methods.len()],
            });
            entry.ssim[i] = error.ssim;
        }
    }
    frames.into_values().collect()
}

/// Image-based's share of the pixels with geometry that were double
/// misses.
fn double_miss_rate(run: Option<&MethodRun>) -> f64 {
    let d = run.map_or([0; 5], |r| r.decisions);
    let with_geometry: u64 = d.iter().sum::<u64>() - d[Decision::Background as usize];
    if with_geometry == 0 {
        0.0
    } else {
        d[Decision::DoubleMiss as usize] as f64 / with_geometry as f64
    }
}

/// Image-based's correspondence errors over the measured B-frames, when
/// they were measured.
fn correspondence_error(measured: &Measured) -> Option<report::CorrespondenceError> {
    let c = &measured.correspondence;
    if c.means.is_empty() {
        return None;
    }
    let all: Vec<f64> = c.means.iter().map(|m| m.0).collect();
    let hit: Vec<f64> = c.means.iter().map(|m| m.1).collect();
    Some(report::CorrespondenceError {
        all: metrics::mean(&all),
        hit: metrics::mean(&hit),
        total: c.total.spread(),
        used: c.used.spread(),
        linear: c.linear.spread(),
    })
}

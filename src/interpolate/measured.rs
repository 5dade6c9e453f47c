//! What a run keeps of its measured intervals, per method and for the
//! run as a whole, until the report sums it up ([`super::summary`]).

use std::collections::BTreeMap;

use super::correspondence::Samples;
use super::report::{KeptFrame, KeptIFrame};
use super::Method;
use crate::measure::metrics::{FrameError, LinearFrame};

/// One method's measured B-frames.
#[derive(Default)]
pub(super) struct MethodRun {
    /// Whether its I-frames are the instrumented pass (else the
    /// original's frame): [`super::frame_method::FrameMethod::reads_flows`].
    pub reads_flows: bool,
    /// Whether it waits for the later I-frame:
    /// [`super::frame_method::FrameMethod::reads_later_frame`].
    pub reads_later_frame: bool,
    pub times: Vec<f64>,
    /// (displayed frame, α, error).
    pub frames: Vec<(u32, f64, FrameError)>,
    pub decisions: [u64; 5],
    /// The lowest-SSIM B-frame: (SSIM, frame, reference, result).
    pub worst: Option<(f64, u32, Vec<u8>, Vec<u8>)>,
    /// The extrapolators: what each interval's I-frame passes add (the
    /// morph's preparation), ms.
    pub prepare_times: Vec<f64>,
    /// The extrapolators that compensate: their displayed I-frames
    /// against the reference, by displayed frame.
    pub displayed_iframes: Vec<(u32, FrameError)>,
    /// Its pursuit error per interval.
    pub pursuit: Vec<f64>,
    /// Its flicker term per interval (`pursuit.rs`).
    pub flicker: Vec<f64>,
    /// Per B-frame with a motion edge near, the PSNR over the pixels near
    /// one (`edges.rs`).
    pub edge_psnr: Vec<f64>,
}

/// Image-based's correspondence errors over the measured B-frames.
#[derive(Default)]
pub(super) struct CorrespondenceErrors {
    /// Per B-frame, the mean E_total over every covered pixel and over
    /// those I-frame 0 shows.
    pub means: Vec<(f64, f64)>,
    pub total: Samples,
    pub used: Samples,
    pub linear: Samples,
}

/// What the run keeps of the measured intervals.
#[derive(Default)]
pub(super) struct Measured {
    /// Image-based's correspondence errors.
    pub correspondence: CorrespondenceErrors,
    /// With `motion_blur`, the composites around each I-frame.
    pub blur: Option<super::blur::MotionBlur>,
    /// The reference at the last interval's end: the next one's start.
    pub previous_end: Option<LinearFrame>,
    /// B-frames kept whole ([`super::Options::keep_frames`], and the end points
    /// of [`super::Options::endpoints`]).
    pub kept: Vec<KeptFrame>,
    pub iframes: Vec<KeptIFrame>,
    pub reference_times: Vec<f64>,
    /// Per recorded interval, its closing I-frame's time (with
    /// `--partition`, its parts' total).
    pub iframe_times: Vec<f64>,
    /// With `--partition`, per recorded interval, the time of each part of
    /// its closing I-frame, instrumented and original.
    pub iframe_parts: Vec<Vec<f64>>,
    pub reference_parts: Vec<Vec<f64>>,
    /// The I-frames against the reference at the same time.
    pub iframe_errors: Vec<(u32, FrameError)>,
    pub methods: BTreeMap<Method, MethodRun>,
    /// The interval's displayed frames per method, for the pursuit error:
    /// the I-frame as the method shows it (`None`: as rendered) and its
    /// B-frames.
    pub groups: BTreeMap<Method, Vec<Option<LinearFrame>>>,
}

use std::fmt;

/// Why a plan cannot be run in this frame, or a frame cannot be recorded.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The plan is inconsistent, of another format version, or asks for
    /// what this host does not know (a newer toolchain's plan).
    Plan(String),
    /// The application's frame does not match what the plan's shaders
    /// read: a vertex input, a binding, a colour target, a buffer given
    /// for a twin. The text names the mismatch.
    Mismatch(String),
    /// What the variant cannot do correctly in this frame (blending into a
    /// cached output, MSAA, a partial viewport, multiview): refused rather
    /// than run wrong. The text says why.
    Refused(String),
    /// wgpu rejected a pipeline or bind group made from the plan.
    Wgpu(String),
    /// The device cannot hold what was asked: a size of zero or past its
    /// largest 2D texture, a bind group or vertex buffer slot past its
    /// limits.
    Limits(String),
    /// The GPU did not finish the work waited on within the time allowed.
    Timeout(String),
    /// A draw was recorded wrongly: through twins made by another
    /// [`CachedShader`](crate::CachedShader), or on a slot the host owns.
    Draw(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Plan(text) => write!(f, "the plan: {text}"),
            Error::Mismatch(text) => write!(f, "the frame does not match the plan: {text}"),
            Error::Refused(text) => write!(f, "refused: {text}"),
            Error::Wgpu(text) => write!(f, "wgpu: {text}"),
            Error::Limits(text) => write!(f, "beyond the device's limits: {text}"),
            Error::Timeout(text) => write!(f, "timed out: {text}"),
            Error::Draw(text) => write!(f, "the draw: {text}"),
        }
    }
}

impl std::error::Error for Error {}

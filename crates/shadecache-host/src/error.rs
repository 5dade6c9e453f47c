use std::fmt;

/// Why a plan cannot be run in this frame, or a frame cannot be recorded.
#[derive(Clone, Debug, PartialEq, Eq)]
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
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Plan(text) => write!(f, "the plan: {text}"),
            Error::Mismatch(text) => write!(f, "the frame does not match the plan: {text}"),
            Error::Refused(text) => write!(f, "refused: {text}"),
            Error::Wgpu(text) => write!(f, "wgpu: {text}"),
        }
    }
}

impl std::error::Error for Error {}

//! A buffer read back without waiting for the GPU: mapped once what fills
//! it was submitted, read when the map has completed, frames later. The
//! frame timer's timestamps and the error watch's sums are read this way.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Whether a read-back buffer is being mapped, and whether its map has
/// completed.
#[derive(Debug, Default)]
pub(crate) struct MapWhenReady {
    /// Set by the map's callback once the buffer can be read.
    mapped: Arc<AtomicBool>,
    mapping: bool,
}

impl MapWhenReady {
    /// Starts mapping `slice` for reading, unless a map of it is under
    /// way; call after submitting what fills it.
    pub fn start(&mut self, slice: wgpu::BufferSlice<'_>) {
        if self.mapping {
            return;
        }
        self.mapping = true;
        let mapped = self.mapped.clone();
        slice.map_async(wgpu::MapMode::Read, move |result| {
            if result.is_ok() {
                mapped.store(true, Ordering::Release);
            }
        });
    }

    /// Whether the map has completed (once: the caller reads the mapped
    /// range and unmaps it, and the next [`MapWhenReady::start`] maps
    /// again). The device must have been polled since.
    pub fn done(&mut self) -> bool {
        let done = self.mapped.swap(false, Ordering::Acquire);
        if done {
            self.mapping = false;
        }
        done
    }
}

//! Per-pass GPU timing: a small trait the host records through, and an
//! implementation with plain timestamp queries. (shadecache's profiler
//! implements the trait over wgpu-profiler.)

use serde::Serialize;

use crate::readback::MapWhenReady;

/// Times render passes. The host begins a query before each pass it
/// records, gives the pass the query's timestamp writes, and ends it after.
pub trait PassTimer {
    /// What a begun query keeps until it ends.
    type Query;
    /// Begins timing pass `pass`, before it is recorded.
    fn begin(&mut self, encoder: &mut wgpu::CommandEncoder, pass: &str) -> Self::Query;
    /// The timestamp writes the pass takes, if any.
    fn timestamp_writes<'a>(
        &'a self,
        query: &'a Self::Query,
    ) -> Option<wgpu::RenderPassTimestampWrites<'a>>;
    /// The timestamp writes a compute pass takes, if any (the error
    /// watch's comparison is one); none unless the timer says.
    fn compute_timestamp_writes<'a>(
        &'a self,
        _query: &'a Self::Query,
    ) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        None
    }
    /// Ends timing the pass, after it is recorded.
    fn end(&mut self, encoder: &mut wgpu::CommandEncoder, query: Self::Query);
}

/// No timing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoTimer;

impl PassTimer for NoTimer {
    type Query = ();
    fn begin(&mut self, _: &mut wgpu::CommandEncoder, _: &str) {}
    fn timestamp_writes<'a>(&'a self, _: &'a ()) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        None
    }
    fn end(&mut self, _: &mut wgpu::CommandEncoder, _: ()) {}
}

/// One pass's GPU time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassTime {
    /// The pass's name in the plan.
    pub pass: String,
    /// Its GPU time.
    pub milliseconds: f64,
}

/// How long a frame's timestamps are waited for unless set: far past a
/// frame's time, even on a software rasteriser, short of a hang.
const DEFAULT_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(10);

/// Timestamp queries around each pass of one frame: begin a frame, record
/// it through this timer, [`Timestamps::resolve`] into the same encoder,
/// submit, then [`Timestamps::read`].
#[derive(Debug)]
pub struct Timestamps {
    slot: QuerySlot,
    capacity: u32,
    period_ns: f32,
    passes: Vec<String>,
    /// The longest [`Timestamps::read`] waits for the frame.
    timeout: std::time::Duration,
}

impl Timestamps {
    /// Room for `passes` passes a frame; `None` when the device was not
    /// opened with `Features::TIMESTAMP_QUERY`.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, passes: u32) -> Option<Timestamps> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        Some(Timestamps {
            slot: QuerySlot::new(device, passes.max(1)),
            capacity: passes.max(1),
            period_ns: queue.get_timestamp_period(),
            passes: Vec::new(),
            timeout: DEFAULT_TIMEOUT,
        })
    }

    /// Sets how long [`Timestamps::read`] waits for the frame before it
    /// returns [`crate::Error::Timeout`] (10 s unless set).
    pub fn with_timeout(mut self, timeout: std::time::Duration) -> Timestamps {
        self.timeout = timeout;
        self
    }

    /// Resolves this frame's queries; record after the passes.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        self.slot.resolve(encoder, self.passes.len() as u32);
    }

    /// The frame's pass times, once its commands were submitted; starts
    /// the next frame. Waits for the GPU at most the timeout (native
    /// backends; on the web the map resolves from the event loop).
    pub fn read(&mut self, device: &wgpu::Device) -> Result<Vec<PassTime>, crate::Error> {
        let passes = std::mem::take(&mut self.passes);
        if passes.is_empty() {
            return Ok(Vec::new());
        }
        let used = passes.len() as u32;
        self.slot
            .read_slice(used)
            .map_async(wgpu::MapMode::Read, |_| {});
        device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(self.timeout),
            })
            .map_err(|err| match err {
                wgpu::PollError::Timeout => crate::Error::Timeout(format!(
                    "the frame's timestamps were not ready within {:?}",
                    self.timeout
                )),
                err => crate::Error::Wgpu(err.to_string()),
            })?;
        let ticks = self.slot.ticks(used)?;
        Ok(passes
            .into_iter()
            .zip(ticks.chunks_exact(2))
            .map(|(pass, pair)| PassTime {
                pass,
                milliseconds: milliseconds(pair[0], pair[1], self.period_ns),
            })
            .collect())
    }
}

impl PassTimer for Timestamps {
    /// The pass's index this frame; `None` past the capacity.
    type Query = Option<u32>;

    fn begin(&mut self, _: &mut wgpu::CommandEncoder, pass: &str) -> Option<u32> {
        let index = self.passes.len() as u32;
        (index < self.capacity).then(|| {
            self.passes.push(pass.to_string());
            index
        })
    }

    fn timestamp_writes<'a>(
        &'a self,
        query: &'a Option<u32>,
    ) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        Some(self.slot.writes((*query)?))
    }

    fn compute_timestamp_writes<'a>(
        &'a self,
        query: &'a Option<u32>,
    ) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        Some(self.slot.compute_writes((*query)?))
    }

    fn end(&mut self, _: &mut wgpu::CommandEncoder, _: Option<u32>) {}
}

/// One frame's timestamp queries (a begin and an end per pass), and the
/// buffers they are resolved into and read back from: what [`Timestamps`]
/// and each of a [`FrameTimer`]'s frames in flight hold.
#[derive(Debug)]
struct QuerySlot {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl QuerySlot {
    /// Room for `passes` passes.
    fn new(device: &wgpu::Device, passes: u32) -> QuerySlot {
        let bytes = u64::from(passes) * 16;
        QuerySlot {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("shadecache pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: passes * 2,
            }),
            resolved: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadecache resolved timestamps"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadecache timestamp readback"),
                size: bytes,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
        }
    }

    /// The writes of pass `index`'s begin and end.
    fn writes(&self, index: u32) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(index * 2),
            end_of_pass_write_index: Some(index * 2 + 1),
        }
    }

    /// The same writes for a compute pass.
    fn compute_writes(&self, index: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        let writes = self.writes(index);
        wgpu::ComputePassTimestampWrites {
            query_set: writes.query_set,
            beginning_of_pass_write_index: writes.beginning_of_pass_write_index,
            end_of_pass_write_index: writes.end_of_pass_write_index,
        }
    }

    /// Resolves the first `used` passes' queries and copies them where
    /// they are read back; nothing when none was used.
    fn resolve(&self, encoder: &mut wgpu::CommandEncoder, used: u32) {
        if used == 0 {
            return;
        }
        encoder.resolve_query_set(&self.queries, 0..used * 2, &self.resolved, 0);
        encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.readback, 0, u64::from(used) * 16);
    }

    /// The read-back bytes of the first `used` passes, to map.
    fn read_slice(&self, used: u32) -> wgpu::BufferSlice<'_> {
        self.readback.slice(..u64::from(used) * 16)
    }

    /// The mapped ticks of the first `used` passes (begin, end, begin...),
    /// and the read-back buffer unmapped.
    fn ticks(&self, used: u32) -> Result<Vec<u64>, crate::Error> {
        let ticks = {
            let data = self
                .read_slice(used)
                .get_mapped_range()
                .map_err(|err| crate::Error::Wgpu(format!("{err:?}")))?;
            data.chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect()
        };
        self.readback.unmap();
        Ok(ticks)
    }
}

/// Milliseconds from tick `begin` to tick `end`.
fn milliseconds(begin: u64, end: u64, period_ns: f32) -> f64 {
    end.saturating_sub(begin) as f64 * f64::from(period_ns) / 1e6
}

/// One frame's queries in a [`FrameTimer`], and where its times are read.
#[derive(Debug)]
struct FrameSlot {
    slot: QuerySlot,
    /// The frame recorded into it, and its queries used.
    frame: Option<u64>,
    used: u32,
    /// The read of its times.
    map: MapWhenReady,
}

/// Whole frames' GPU times, read when they are ready, never waited for:
/// what a running application measures itself with (a
/// [`crate::Governor`] decides from it), where [`Timestamps`] waits for
/// each frame as a profiler may.
///
/// A frame is timed from the start of its first timed pass to the end of
/// its last, through this timer as a [`PassTimer`] (the host's passes,
/// and the application's own original pass timed the same way). Per
/// frame: [`FrameTimer::begin_frame`], record, [`FrameTimer::resolve`]
/// into the frame's encoder, submit, then [`FrameTimer::ready`], which
/// starts the reads of what was submitted and returns the frames whose
/// times have arrived. Up to `in_flight` frames wait for their times; a
/// frame begun while all are waiting goes untimed (`begin_frame` says so).
#[derive(Debug)]
pub struct FrameTimer {
    slots: Vec<FrameSlot>,
    /// The slot being recorded.
    current: Option<usize>,
    capacity: u32,
    period_ns: f32,
}

impl FrameTimer {
    /// Room for `passes` timed passes a frame and `in_flight` frames
    /// waiting for their times; `None` when the device was not opened with
    /// `Features::TIMESTAMP_QUERY`.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        passes: u32,
        in_flight: usize,
    ) -> Option<FrameTimer> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let capacity = passes.max(1);
        let slots = (0..in_flight.max(1))
            .map(|_| FrameSlot {
                slot: QuerySlot::new(device, capacity),
                frame: None,
                used: 0,
                map: MapWhenReady::default(),
            })
            .collect();
        Some(FrameTimer {
            slots,
            current: None,
            capacity,
            period_ns: queue.get_timestamp_period(),
        })
    }

    /// Starts timing frame `frame`; false when every slot still waits for
    /// its times (the frame is not timed).
    pub fn begin_frame(&mut self, frame: u64) -> bool {
        // A frame begun and never resolved was not submitted with its
        // queries: its slot is free.
        if let Some(index) = self.current.take() {
            self.slots[index].frame = None;
        }
        self.current = self.slots.iter().position(|slot| slot.frame.is_none());
        if let Some(index) = self.current {
            let slot = &mut self.slots[index];
            slot.frame = Some(frame);
            slot.used = 0;
        }
        self.current.is_some()
    }

    /// Resolves the frame's queries into `encoder`; record after its
    /// passes, before the encoder is submitted.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let Some(index) = self.current.take() else {
            return;
        };
        let slot = &mut self.slots[index];
        if slot.used == 0 {
            // Nothing timed: the slot is free again.
            slot.frame = None;
            return;
        }
        slot.slot.resolve(encoder, slot.used);
    }

    /// The frames whose times have arrived, as (frame, milliseconds from
    /// its first pass's start to its last pass's end). Call after
    /// submitting the frames resolved: it starts their reads and polls the
    /// device without waiting.
    pub fn ready(&mut self, device: &wgpu::Device) -> Result<Vec<(u64, f64)>, crate::Error> {
        for (index, slot) in self.slots.iter_mut().enumerate() {
            if slot.frame.is_some() && Some(index) != self.current {
                slot.map.start(slot.slot.read_slice(slot.used));
            }
        }
        device
            .poll(wgpu::PollType::Poll)
            .map_err(|err| crate::Error::Wgpu(err.to_string()))?;
        let mut times = Vec::new();
        for slot in &mut self.slots {
            if !slot.map.done() {
                continue;
            }
            let ticks = slot.slot.ticks(slot.used)?;
            let (first, last) = (
                ticks.iter().step_by(2).min(),
                ticks.iter().skip(1).step_by(2).max(),
            );
            if let (Some(frame), Some(&first), Some(&last)) = (slot.frame.take(), first, last) {
                times.push((frame, milliseconds(first, last, self.period_ns)));
            }
        }
        times.sort_by_key(|(frame, _)| *frame);
        Ok(times)
    }
}

impl PassTimer for FrameTimer {
    /// The pass's index in the frame's slot; `None` when the frame is not
    /// timed or past the capacity.
    type Query = Option<u32>;

    fn begin(&mut self, _: &mut wgpu::CommandEncoder, _: &str) -> Option<u32> {
        let slot = &mut self.slots[self.current?];
        (slot.used < self.capacity).then(|| {
            slot.used += 1;
            slot.used - 1
        })
    }

    fn timestamp_writes<'a>(
        &'a self,
        query: &'a Option<u32>,
    ) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        Some(self.slots[self.current?].slot.writes((*query)?))
    }

    fn compute_timestamp_writes<'a>(
        &'a self,
        query: &'a Option<u32>,
    ) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        Some(self.slots[self.current?].slot.compute_writes((*query)?))
    }

    fn end(&mut self, _: &mut wgpu::CommandEncoder, _: Option<u32>) {}
}

//! Recording a frame: the command encoder and, where the adapter has timestamp queries, the GPU
//! time of each named pass. Timings come back through a small ring of persistent staging buffers:
//! [`PassTimer::wait`] blocks for them (the command line, the benchmarks), [`PassTimer::poll`]
//! picks up whatever has arrived without waiting (the lab, a frame later).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use super::readback::map_now;
use super::{GpuContext, RenderError};

/// Begin and end queries for at most this many passes per frame.
pub const MAX_SPANS: u32 = 16;
/// Staging buffers in flight.
const RING: usize = 3;

/// A frame's encoder and its pass timer.
pub struct Recorder<'a> {
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub timer: Option<&'a PassTimer>,
}

impl<'a> Recorder<'a> {
    pub fn new(encoder: &'a mut wgpu::CommandEncoder, timer: Option<&'a PassTimer>) -> Self {
        Recorder { encoder, timer }
    }

    /// A timed span named `name` (one or more render passes in a row).
    pub fn span(&self, name: &'static str) -> Span {
        Span(self.timer.and_then(|t| t.open(name)))
    }
}

/// The queries of one timed span; `None` where timing is off or the frame has too many spans.
#[derive(Clone, Copy, Debug)]
pub struct Span(Option<u32>);

impl Span {
    /// Timestamp writes for a render pass of the span: the first writes the start, the last the
    /// end (one pass may be both).
    pub fn writes<'q>(
        &self,
        rec_timer: Option<&'q PassTimer>,
        first: bool,
        last: bool,
    ) -> Option<wgpu::RenderPassTimestampWrites<'q>> {
        let (timer, i) = (rec_timer?, self.0?);
        (first || last).then_some(wgpu::RenderPassTimestampWrites {
            query_set: &timer.queries,
            beginning_of_pass_write_index: first.then_some(2 * i),
            end_of_pass_write_index: last.then_some(2 * i + 1),
        })
    }

    /// The same for a compute pass.
    pub fn compute_writes<'q>(
        &self,
        rec_timer: Option<&'q PassTimer>,
    ) -> Option<wgpu::ComputePassTimestampWrites<'q>> {
        let (timer, i) = (rec_timer?, self.0?);
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &timer.queries,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }
}

struct Slot {
    buffer: wgpu::Buffer,
    names: Vec<&'static str>,
    /// Mapped and ready to read.
    ready: Arc<AtomicBool>,
    /// Waiting for the GPU (copied into, map requested).
    pending: bool,
}

/// Timestamp queries around passes, resolved into a ring of staging buffers.
pub struct PassTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    names: RefCell<Vec<&'static str>>,
    ring: Vec<Slot>,
    next: usize,
    period_ms: f64,
}

const BYTES: u64 = 2 * MAX_SPANS as u64 * 8;

impl PassTimer {
    /// `None` where the adapter has no timestamp queries.
    pub fn new(ctx: &GpuContext) -> Option<PassTimer> {
        if !ctx.timestamps {
            return None;
        }
        let device = &ctx.device;
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("PassTimer::queries"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * MAX_SPANS,
        });
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("PassTimer::resolve"),
            size: BYTES,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let ring = (0..RING)
            .map(|_| Slot {
                buffer: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("PassTimer::staging"),
                    size: BYTES,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                }),
                names: Vec::new(),
                ready: Arc::new(AtomicBool::new(false)),
                pending: false,
            })
            .collect();
        Some(PassTimer {
            queries,
            resolve,
            names: RefCell::new(Vec::new()),
            ring,
            next: 0,
            period_ms: f64::from(ctx.queue.get_timestamp_period()) * 1e-6,
        })
    }

    fn open(&self, name: &'static str) -> Option<u32> {
        let mut names = self.names.borrow_mut();
        let i = names.len() as u32;
        (i < MAX_SPANS).then(|| {
            names.push(name);
            i
        })
    }

    /// Resolve this frame's queries into a free staging buffer. Returns the bytes that frame will
    /// read back, 0 when no buffer is free (that frame goes untimed) or nothing was timed.
    pub fn finish(&mut self, encoder: &mut wgpu::CommandEncoder) -> u64 {
        let names = std::mem::take(&mut *self.names.borrow_mut());
        if names.is_empty() {
            return 0;
        }
        let Some(k) = (0..RING)
            .map(|j| (self.next + j) % RING)
            .find(|&k| !self.ring[k].pending)
        else {
            return 0;
        };
        let count = 2 * names.len() as u32;
        let bytes = u64::from(count) * 8;
        encoder.resolve_query_set(&self.queries, 0..count, &self.resolve, 0);
        let slot = &mut self.ring[k];
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &slot.buffer, 0, bytes);
        slot.names = names;
        slot.pending = true;
        slot.ready.store(false, Ordering::Release);
        self.next = (k + 1) % RING;
        bytes
    }

    /// Ask for the staging buffers copied into by submitted frames to be mapped (call after the
    /// submit).
    pub fn request_maps(&mut self) {
        for slot in self.ring.iter_mut().filter(|s| s.pending) {
            if slot.ready.load(Ordering::Acquire) {
                continue;
            }
            let ready = slot.ready.clone();
            let n = slot.names.len() as u64 * 16;
            slot.buffer
                .slice(..n)
                .map_async(wgpu::MapMode::Read, move |r| {
                    ready.store(r.is_ok(), Ordering::Release)
                });
        }
    }

    /// The newest timings that have arrived, without waiting; `None` if none has.
    pub fn poll(&mut self, ctx: &GpuContext) -> Option<Vec<(String, f64)>> {
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        let mut newest = None;
        for k in 0..RING {
            let slot = &mut self.ring[k];
            if slot.pending && slot.ready.load(Ordering::Acquire) {
                newest = Some(read_slot(slot, self.period_ms));
            }
        }
        newest
    }

    /// Wait for every submitted frame's timings and return the newest.
    pub fn wait(&mut self, ctx: &GpuContext) -> Result<Vec<(String, f64)>, RenderError> {
        map_now(&ctx.device)?;
        Ok(self.poll(ctx).unwrap_or_default())
    }
}

fn read_slot(slot: &mut Slot, period_ms: f64) -> Vec<(String, f64)> {
    let n = slot.names.len() as u64 * 16;
    let out = match slot.buffer.slice(..n).get_mapped_range() {
        Ok(view) => {
            let ticks: Vec<u64> = view
                .chunks_exact(8)
                .map(|b| u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
                .collect();
            slot.names
                .iter()
                .enumerate()
                .filter_map(|(i, name)| {
                    let (a, b) = (ticks.get(2 * i)?, ticks.get(2 * i + 1)?);
                    Some((name.to_string(), b.saturating_sub(*a) as f64 * period_ms))
                })
                .collect()
        }
        Err(_) => Vec::new(),
    };
    slot.buffer.unmap();
    slot.pending = false;
    slot.ready.store(false, Ordering::Release);
    out
}

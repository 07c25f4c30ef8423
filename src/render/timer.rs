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

/// A frame's encoder, its pass timer, and the debug groups it is recorded in.
///
/// The groups give a capture (RenderDoc, Xcode, PIX) the frame's structure by name: a
/// [`Recorder::group`] around a stretch of work (the frame, a method's passes, the readbacks),
/// and around each timed [`Recorder::span`] one group named as the span, which lasts until the
/// next span or group begins or its own group ends. Spans are leaves of that tree, groups are
/// its inner nodes, and every group a recorder opens it closes: a frame is balanced by
/// construction, not by calls kept in pairs by hand. A group reaches the encoder when the first
/// span inside it opens, so one with no pass in it (a method whose maps are up to date) leaves
/// nothing behind. Outside every group a span is timed but opens no group (nothing would close
/// it). Where the driver cannot take a group around passes ([`groups_span_passes`]) the
/// bookkeeping runs and the encoder is told nothing.
pub struct Recorder<'a> {
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub timer: Option<&'a PassTimer>,
    groups: Groups,
    /// The encoder gets the groups.
    labels: bool,
}

impl<'a> Recorder<'a> {
    pub fn new(encoder: &'a mut wgpu::CommandEncoder, timer: Option<&'a PassTimer>) -> Self {
        Recorder {
            encoder,
            timer,
            groups: Groups::default(),
            labels: true,
        }
    }

    /// The same, telling the encoder its debug groups only where `on`.
    pub fn with_groups(mut self, on: bool) -> Self {
        self.labels = on;
        self
    }

    /// A timed span named `name` (one or more passes in a row), in a debug group of that name.
    pub fn span(&mut self, name: &'static str) -> Span {
        let ops = self.groups.span(name);
        self.apply(ops);
        Span(self.timer.and_then(|t| t.open(name)))
    }

    /// Record `f` in a debug group named `name`.
    pub fn group<R>(&mut self, name: &str, f: impl FnOnce(&mut Self) -> R) -> R {
        let ops = self.groups.group(name);
        self.apply(ops);
        let out = f(self);
        let ops = self.groups.close();
        self.apply(ops);
        out
    }

    fn apply(&mut self, ops: Vec<GroupOp>) {
        if !self.labels {
            return;
        }
        for op in ops {
            match op {
                GroupOp::Push(name) => self.encoder.push_debug_group(&name),
                GroupOp::Pop => self.encoder.pop_debug_group(),
            }
        }
    }
}

/// Whether the driver under `adapter` takes debug groups around passes. wgpu records each pass
/// into a command buffer of its own, so a group around passes begins in one command buffer and
/// ends in another, as Vulkan allows; Mesa's Vulkan drivers before 24 (lavapipe 22.3 here) keep
/// the labels per command buffer, pop past the empty stack of the one a group ends in, and crash
/// at a later label. (wgpu hands labels to Vulkan only with `InstanceFlags::DEBUG`: a debug
/// build, or `WGPU_DEBUG=1`, which a RenderDoc capture wants anyway.)
pub fn groups_span_passes(adapter: &wgpu::AdapterInfo) -> bool {
    adapter.backend != wgpu::Backend::Vulkan
        || super::adapter::mesa_major(&adapter.driver_info).is_none_or(|v| v >= 24)
}

/// What the encoder is told.
#[derive(Clone, Debug, PartialEq, Eq)]
enum GroupOp {
    Push(String),
    Pop,
}

/// One open group: opened by a span or not, its name, and whether the encoder has it yet.
#[derive(Debug)]
struct Open {
    span: bool,
    name: String,
    pushed: bool,
}

/// The debug groups open in a recorder, innermost last: the bookkeeping apart from the encoder
/// (it answers with what to tell the encoder), so a test can follow it.
#[derive(Debug, Default)]
struct Groups {
    open: Vec<Open>,
}

impl Groups {
    /// Open a group named `name` (ending the span open here, if any); the encoder gets it with
    /// the first span inside it.
    fn group(&mut self, name: &str) -> Vec<GroupOp> {
        let ops = self.end_span();
        self.open.push(Open {
            span: false,
            name: name.to_string(),
            pushed: false,
        });
        ops
    }

    /// Open the span `name` (ending the span open here, if any) with every group around it
    /// that the encoder does not have yet; none outside every group.
    fn span(&mut self, name: &str) -> Vec<GroupOp> {
        let mut ops = self.end_span();
        if self.open.is_empty() {
            return ops;
        }
        for g in self.open.iter_mut().filter(|g| !g.pushed) {
            ops.push(GroupOp::Push(g.name.clone()));
            g.pushed = true;
        }
        ops.push(GroupOp::Push(name.to_string()));
        self.open.push(Open {
            span: true,
            name: name.to_string(),
            pushed: true,
        });
        ops
    }

    /// Close the innermost [`Groups::group`] and the span open in it.
    fn close(&mut self) -> Vec<GroupOp> {
        let mut ops = self.end_span();
        if self.open.pop().is_some_and(|g| g.pushed) {
            ops.push(GroupOp::Pop);
        }
        ops
    }

    fn end_span(&mut self) -> Vec<GroupOp> {
        if self.open.last().is_some_and(|g| g.span) {
            self.open.pop();
            return vec![GroupOp::Pop];
        }
        Vec::new()
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

    /// [`Span::compute_writes`] for a span over several compute passes: its start in the
    /// `first`, its end in the `last`.
    pub fn compute_writes_over<'q>(
        &self,
        rec_timer: Option<&'q PassTimer>,
        first: bool,
        last: bool,
    ) -> Option<wgpu::ComputePassTimestampWrites<'q>> {
        let (timer, i) = (rec_timer?, self.0?);
        (first || last).then_some(wgpu::ComputePassTimestampWrites {
            query_set: &timer.queries,
            beginning_of_pass_write_index: first.then_some(2 * i),
            end_of_pass_write_index: last.then_some(2 * i + 1),
        })
    }
}

struct Slot {
    buffer: wgpu::Buffer,
    names: Vec<&'static str>,
    /// The tag of the submit whose passes it timed ([`PassTimer::finish`]).
    tag: u64,
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
                tag: 0,
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

    /// Resolve this frame's queries into a free staging buffer, tagged `tag` (the submit's, which
    /// [`PassTimer::poll_tagged`] hands back with its timings). Returns the bytes that frame will
    /// read back, 0 when no buffer is free (that frame goes untimed) or nothing was timed.
    pub fn finish(&mut self, encoder: &mut wgpu::CommandEncoder, tag: u64) -> u64 {
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
        encoder.push_debug_group("readbacks: pass timings");
        encoder.resolve_query_set(&self.queries, 0..count, &self.resolve, 0);
        let slot = &mut self.ring[k];
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &slot.buffer, 0, bytes);
        encoder.pop_debug_group();
        slot.names = names;
        slot.tag = tag;
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
        self.poll_tagged(ctx).map(|(_, timings)| timings)
    }

    /// [`PassTimer::poll`], with the tag the timed submit was given.
    pub fn poll_tagged(&mut self, ctx: &GpuContext) -> Option<(u64, Vec<(String, f64)>)> {
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        let mut newest: Option<(u64, Vec<(String, f64)>)> = None;
        for k in 0..RING {
            let slot = &mut self.ring[k];
            if slot.pending && slot.ready.load(Ordering::Acquire) {
                let tag = slot.tag;
                let timings = read_slot(slot, self.period_ms);
                if newest.as_ref().is_none_or(|(t, _)| tag >= *t) {
                    newest = Some((tag, timings));
                }
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

#[cfg(test)]
mod tests {
    use super::{GroupOp, Groups};
    use crate::render::adapter::mesa_major;

    #[test]
    fn mesa_versions_are_read_from_the_driver_description() {
        assert_eq!(mesa_major("Mesa 22.3.6 (LLVM 15.0.6)"), Some(22));
        assert_eq!(mesa_major("Mesa 24.0.5-1ubuntu1"), Some(24));
        assert_eq!(mesa_major("535.104.05"), None);
        assert_eq!(mesa_major(""), None);
    }

    /// What the encoder is told for `script` (a frame as `record_frame` records it), as an
    /// outline of (depth, name), and the depth at the end; fails on a pop with nothing open.
    fn outline(script: &[(&str, &str)]) -> (Vec<(usize, String)>, usize) {
        let mut groups = Groups::default();
        let mut depth = 0usize;
        let mut out = Vec::new();
        for &(op, name) in script {
            let ops = match op {
                "group" => groups.group(name),
                "span" => groups.span(name),
                _ => groups.close(),
            };
            for o in ops {
                match o {
                    GroupOp::Push(n) => {
                        out.push((depth, n));
                        depth += 1;
                    }
                    GroupOp::Pop => {
                        assert!(depth > 0, "pops a group it never pushed at {op} {name}");
                        depth -= 1;
                    }
                }
            }
            let pushed = groups.open.iter().filter(|g| g.pushed).count();
            assert_eq!(depth, pushed, "the encoder's depth is what is open");
        }
        (out, depth)
    }

    fn named(outline: &[(usize, &str)]) -> Vec<(usize, String)> {
        outline.iter().map(|&(d, n)| (d, n.to_string())).collect()
    }

    #[test]
    fn spans_nest_in_groups_and_every_group_closes() {
        let (out, depth) = outline(&[
            ("group", "frame"),
            ("group", "method"),
            ("span", "shadow_map"),
            ("span", "dbuffer_volumes"),
            ("close", ""),
            ("span", "camera_pass"),
            ("span", "view_pass"),
            ("close", ""),
            ("group", "readbacks"),
            ("span", "probe"),
            ("close", ""),
        ]);
        let expected = [
            (0, "frame"),
            (1, "method"),
            (2, "shadow_map"),
            (2, "dbuffer_volumes"),
            (1, "camera_pass"),
            (1, "view_pass"),
            (0, "readbacks"),
            (1, "probe"),
        ];
        assert_eq!(out, named(&expected));
        assert_eq!(depth, 0, "balanced");
    }

    #[test]
    fn a_group_with_no_span_in_it_reaches_no_encoder() {
        // A method whose maps are up to date records nothing in its group.
        let (out, depth) = outline(&[
            ("group", "frame"),
            ("group", "method"),
            ("close", ""),
            ("span", "camera_pass"),
            ("close", ""),
            ("group", "maps alone"),
            ("close", ""),
        ]);
        assert_eq!(out, named(&[(0, "frame"), (1, "camera_pass")]));
        assert_eq!(depth, 0);
    }

    #[test]
    fn a_span_outside_every_group_opens_none() {
        let (out, depth) = outline(&[("span", "sample_maps"), ("span", "ssm_skins")]);
        assert!(out.is_empty());
        assert_eq!(depth, 0);
        let (out, depth) = outline(&[
            ("span", "floor"),
            ("group", "frame"),
            ("span", "camera_pass"),
            ("close", ""),
        ]);
        assert_eq!(out, named(&[(0, "frame"), (1, "camera_pass")]));
        assert_eq!(depth, 0);
    }

    #[test]
    fn a_group_opened_inside_a_span_ends_the_span() {
        let (out, depth) = outline(&[
            ("group", "frame"),
            ("span", "shadow_map"),
            ("group", "method"),
            ("span", "camera_pass"),
            ("close", ""),
            ("close", ""),
        ]);
        let expected = [
            (0, "frame"),
            (1, "shadow_map"),
            (1, "method"),
            (2, "camera_pass"),
        ];
        assert_eq!(out, named(&expected));
        assert_eq!(depth, 0);
    }
}

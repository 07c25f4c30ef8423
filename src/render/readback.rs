//! Copying textures back to the CPU, only when a person or a file needs them: through persistent
//! staging buffers (made once, reused while large enough), all the textures of one call in one
//! submit and one wait per band. A texture larger than a staging buffer's cap is read in bands
//! of rows, so an 8192² image needs no 512 MB buffer (rows padded to wgpu's 256-byte alignment
//! on the way), and [`Readback::read_rows`] hands each row to the caller as it arrives, so
//! nothing needs the whole texture in memory as raw bytes.
//!
//! A depth texture is copied whole or not at all (WebGPU copies no part of a depth
//! subresource): a depth read that does not fit one staging buffer ([`fits_whole`]) is refused
//! here, and [`read_frame`](super::frame::read_frame) reads such a depth through its exact
//! `R32Float` copy instead, which bands like any colour texture. Every round runs in a
//! validation error scope: what the device refuses comes back as the read's error, never as
//! rows of stale bytes.

use std::ops::Range;

use super::{GpuContext, RenderError};

/// The largest staging buffer one texture uses per round.
pub const STAGING_CAP: u64 = 32 << 20;

/// A texture to read: which aspect (depth for a depth texture), the bytes of one texel, and
/// which rows.
#[derive(Clone)]
pub struct TextureRead<'a> {
    pub texture: &'a wgpu::Texture,
    pub aspect: wgpu::TextureAspect,
    pub texel: u32,
    pub rows: Range<u32>,
}

impl<'a> TextureRead<'a> {
    pub fn color(texture: &'a wgpu::Texture, texel: u32) -> Self {
        TextureRead {
            texture,
            aspect: wgpu::TextureAspect::All,
            texel,
            rows: 0..texture.height(),
        }
    }

    pub fn depth(texture: &'a wgpu::Texture) -> Self {
        TextureRead {
            texture,
            aspect: wgpu::TextureAspect::DepthOnly,
            texel: 4,
            rows: 0..texture.height(),
        }
    }

    /// Only rows `rows` (clamped to the texture).
    pub fn rows(mut self, rows: Range<u32>) -> Self {
        let h = self.texture.height();
        self.rows = rows.start.min(h)..rows.end.min(h);
        self
    }

    fn bytes(&self) -> usize {
        self.texture.width() as usize * self.rows.len() * self.texel as usize
    }

    /// A depth (or stencil) aspect: copied whole only.
    fn whole_only(&self) -> bool {
        self.aspect != wgpu::TextureAspect::All
    }
}

/// Whether `texture` (`texel` bytes a texel) is copied in one round: its padded rows fit one
/// staging buffer. A depth texture that does not is read through a colour copy.
pub fn fits_whole(ctx: &GpuContext, texture: &wgpu::Texture, texel: u32) -> bool {
    padded_row(texture.width(), texel) * u64::from(texture.height()) <= staging_cap(ctx)
}

fn staging_cap(ctx: &GpuContext) -> u64 {
    STAGING_CAP.min(ctx.max_buffer_size())
}

/// Persistent staging buffers.
#[derive(Default)]
pub struct Readback {
    staging: Vec<wgpu::Buffer>,
    /// Bytes copied back by the last call.
    pub last_bytes: u64,
}

/// Wait until everything submitted has run and mapping callbacks have fired, at most
/// [`gpu_timeout`](super::watchdog::gpu_timeout): past it the device is taken to be stuck (a shader that never ends) and
/// [`RenderError::Stalled`] returned. The device is then kept alive for the rest of the process
/// (one handle leaked): dropping it would wait for the stuck work, and the program could not
/// say why it stopped.
pub fn map_now(device: &wgpu::Device) -> Result<(), RenderError> {
    let timeout = super::watchdog::gpu_timeout();
    match device.poll(wgpu::PollType::Wait {
        submission_index: None,
        timeout: Some(timeout),
    }) {
        Ok(_) => Ok(()),
        Err(wgpu::PollError::Timeout) => {
            std::mem::forget(device.clone());
            Err(RenderError::Stalled(timeout.as_secs_f64()))
        }
        Err(e) => Err(RenderError::Readback(e.to_string())),
    }
}

fn padded_row(width: u32, texel: u32) -> u64 {
    let row = u64::from(width) * u64::from(texel);
    let align = u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    row.div_ceil(align) * align
}

impl Readback {
    /// The texels of every texture's rows, unpadded, in `reads` order.
    pub fn read(
        &mut self,
        ctx: &GpuContext,
        reads: &[TextureRead<'_>],
    ) -> Result<Vec<Vec<u8>>, RenderError> {
        let mut out: Vec<Vec<u8>> = reads
            .iter()
            .map(|r| Vec::with_capacity(r.bytes()))
            .collect();
        self.read_rows(ctx, reads, &mut |k, _, row| out[k].extend_from_slice(row))?;
        Ok(out)
    }

    /// Read `reads`, handing every row to `sink` as `(index in reads, y, texels)`, each
    /// texture's rows in increasing `y`.
    pub fn read_rows(
        &mut self,
        ctx: &GpuContext,
        reads: &[TextureRead<'_>],
        sink: &mut dyn FnMut(usize, u32, &[u8]),
    ) -> Result<(), RenderError> {
        let device = &ctx.device;
        let cap = staging_cap(ctx);
        // Rows per round for each texture, and the staging size that takes.
        let plans: Vec<(u64, u32)> = reads
            .iter()
            .map(|r| {
                let row = padded_row(r.texture.width(), r.texel);
                let rows = (cap / row).clamp(1, u64::from(r.rows.len().max(1) as u32)) as u32;
                (row, rows)
            })
            .collect();
        for (r, &(_, rows)) in reads.iter().zip(&plans) {
            let h = r.texture.height();
            if r.whole_only() && (r.rows != (0..h) || rows < h) {
                return Err(RenderError::Readback(format!(
                    "a depth texture is copied whole, and {}x{h} ({} MiB) does not fit a \
                     {} MiB staging buffer: read its colour copy",
                    r.texture.width(),
                    (padded_row(r.texture.width(), r.texel) * u64::from(h)) >> 20,
                    cap >> 20
                )));
            }
        }
        while self.staging.len() < reads.len() {
            self.staging.push(staging(device, 256));
        }
        for (k, &(row, rows)) in plans.iter().enumerate() {
            let need = row * u64::from(rows);
            if self.staging[k].size() < need {
                self.staging[k] = staging(device, need);
            }
        }
        let mut next: Vec<u32> = reads.iter().map(|r| r.rows.start).collect();
        self.last_bytes = 0;
        // One round reads the next band of every texture that has rows left.
        while reads.iter().zip(&next).any(|(r, &y)| y < r.rows.end) {
            let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("Readback::encoder"),
            });
            encoder.push_debug_group("readback");
            let mut bands = Vec::new();
            for (k, r) in reads.iter().enumerate() {
                let (row, rows) = plans[k];
                let y = next[k];
                if y >= r.rows.end {
                    continue;
                }
                let n = rows.min(r.rows.end - y);
                encoder.copy_texture_to_buffer(
                    wgpu::TexelCopyTextureInfo {
                        texture: r.texture,
                        mip_level: 0,
                        origin: wgpu::Origin3d { x: 0, y, z: 0 },
                        aspect: r.aspect,
                    },
                    wgpu::TexelCopyBufferInfo {
                        buffer: &self.staging[k],
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(row as u32),
                            rows_per_image: Some(n),
                        },
                    },
                    wgpu::Extent3d {
                        width: r.texture.width(),
                        height: n,
                        depth_or_array_layers: 1,
                    },
                );
                bands.push((k, y, n, row));
            }
            encoder.pop_debug_group();
            ctx.queue.submit([encoder.finish()]);
            // A copy the device refused copied nothing: its error, not the staging's old bytes.
            if let Some(e) = pollster::block_on(scope.pop()) {
                return Err(RenderError::Gpu(e.to_string()));
            }
            for &(k, _, n, row) in &bands {
                self.staging[k]
                    .slice(..row * u64::from(n))
                    .map_async(wgpu::MapMode::Read, |_| {});
            }
            map_now(device)?;
            for (k, y, n, row) in bands {
                let width_bytes = reads[k].texture.width() as usize * reads[k].texel as usize;
                let slice = self.staging[k].slice(..row * u64::from(n));
                let result = (|| {
                    let view = slice
                        .get_mapped_range()
                        .map_err(|e| RenderError::Readback(e.to_string()))?;
                    for (i, line) in view.chunks(row as usize).take(n as usize).enumerate() {
                        let Some(texels) = line.get(..width_bytes) else {
                            return Err(RenderError::Readback("short staging row".into()));
                        };
                        sink(k, y + i as u32, texels);
                    }
                    Ok(())
                })();
                self.staging[k].unmap();
                result?;
                next[k] += n;
                self.last_bytes += width_bytes as u64 * u64::from(n);
            }
        }
        Ok(())
    }
}

fn staging(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("Readback::staging"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    })
}

/// Little-endian `f32`s from bytes.
pub fn f32s(bytes: &[u8]) -> Vec<f32> {
    f32s_of(bytes).collect()
}

/// Little-endian `f32`s from bytes, as an iterator.
pub fn f32s_of(bytes: &[u8]) -> impl Iterator<Item = f32> + '_ {
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Little-endian `u32`s from bytes.
pub fn u32s(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// A mappable copy of `buffer`, its copy submitted (not waited for).
pub fn copy_to_staging(ctx: &GpuContext, buffer: &wgpu::Buffer, label: &str) -> wgpu::Buffer {
    let size = buffer.size();
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    staging
}

/// The `u32`s of `buffer`, copied to a staging buffer and read back (waits for the GPU).
pub fn read_u32s(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u32>, RenderError> {
    let staging = copy_to_staging(ctx, buffer, "readback::words");
    let slice = staging.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    map_now(&ctx.device)?;
    let words = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        u32s(&view)
    };
    staging.unmap();
    ctx.check_lost()?;
    Ok(words)
}

/// A small buffer a frame's passes copy into (counts, a few walls), mapped a frame or more later
/// without a wait: the lab's overlays and stats. A copy is recorded only while the last one is
/// not being mapped ([`LateCopy::free`]); [`LateCopy::poll`], once per frame, asks for the map
/// after a copy was submitted, and a later call hands the bytes over.
pub struct LateCopy {
    pub buffer: wgpu::Buffer,
    mapped: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// Copied in a recorded frame, not yet asked to map.
    waiting: bool,
    mapping: bool,
}

impl LateCopy {
    pub fn new(device: &wgpu::Device, label: &str, size: u64) -> LateCopy {
        LateCopy {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
            mapped: Default::default(),
            waiting: false,
            mapping: false,
        }
    }

    /// Whether a copy into it may be recorded now (the last one is not being mapped).
    pub fn free(&self) -> bool {
        !self.mapping
    }

    /// A copy into it was recorded (the frame that holds it is about to be submitted).
    pub fn copied(&mut self) {
        self.waiting = true;
    }

    /// Whether a copy is on its way back.
    pub fn pending(&self) -> bool {
        self.waiting || self.mapping
    }

    /// Never waits: the first call after a copy asks for the map, a later one returns its bytes
    /// (empty where the map failed) and frees the buffer.
    pub fn poll(&mut self) -> Option<Vec<u8>> {
        use std::sync::atomic::Ordering;
        if self.waiting && !self.mapping {
            let flag = self.mapped.clone();
            flag.store(false, Ordering::Release);
            self.buffer
                .slice(..)
                .map_async(wgpu::MapMode::Read, move |r| {
                    flag.store(r.is_ok(), Ordering::Release);
                });
            self.waiting = false;
            self.mapping = true;
            return None;
        }
        if !self.mapping || !self.mapped.load(Ordering::Acquire) {
            return None;
        }
        let bytes = match self.buffer.slice(..).get_mapped_range() {
            Ok(view) => view.to_vec(),
            Err(_) => Vec::new(),
        };
        self.buffer.unmap();
        self.mapping = false;
        Some(bytes)
    }
}

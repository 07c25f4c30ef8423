//! Copying textures back to the CPU, only when a person or a file needs them: through persistent
//! staging buffers (made once, reused while large enough), all the textures of one call in one
//! submit and one wait. A texture larger than a staging buffer's cap is read in bands of rows, so
//! an 8192² image needs no 512 MB buffer (rows padded to wgpu's 256-byte alignment on the way).

use super::{GpuContext, RenderError};

/// The largest staging buffer one texture uses per round.
pub const STAGING_CAP: u64 = 64 << 20;

/// A texture to read: which aspect (depth for a depth texture) and the bytes of one texel.
#[derive(Clone, Copy)]
pub struct TextureRead<'a> {
    pub texture: &'a wgpu::Texture,
    pub aspect: wgpu::TextureAspect,
    pub texel: u32,
}

impl<'a> TextureRead<'a> {
    pub fn color(texture: &'a wgpu::Texture, texel: u32) -> Self {
        TextureRead {
            texture,
            aspect: wgpu::TextureAspect::All,
            texel,
        }
    }

    pub fn depth(texture: &'a wgpu::Texture) -> Self {
        TextureRead {
            texture,
            aspect: wgpu::TextureAspect::DepthOnly,
            texel: 4,
        }
    }
}

/// Persistent staging buffers.
#[derive(Default)]
pub struct Readback {
    staging: Vec<wgpu::Buffer>,
    /// Bytes copied back by the last call.
    pub last_bytes: u64,
}

/// Wait until everything submitted has run and mapping callbacks have fired.
pub fn map_now(device: &wgpu::Device) -> Result<(), RenderError> {
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|e| RenderError::Readback(e.to_string()))
}

fn padded_row(width: u32, texel: u32) -> u64 {
    let row = u64::from(width) * u64::from(texel);
    let align = u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    row.div_ceil(align) * align
}

impl Readback {
    /// The texels of every texture (mip 0, layer 0), rows unpadded, in `reads` order.
    pub fn read(
        &mut self,
        ctx: &GpuContext,
        reads: &[TextureRead<'_>],
    ) -> Result<Vec<Vec<u8>>, RenderError> {
        let device = &ctx.device;
        let cap = STAGING_CAP.min(ctx.max_buffer_size());
        // Rows per round for each texture, and the staging size that takes.
        let plans: Vec<(u64, u32)> = reads
            .iter()
            .map(|r| {
                let row = padded_row(r.texture.width(), r.texel);
                let rows = (cap / row).clamp(1, u64::from(r.texture.height())) as u32;
                (row, rows)
            })
            .collect();
        while self.staging.len() < reads.len() {
            self.staging.push(staging(device, 256));
        }
        for (k, &(row, rows)) in plans.iter().enumerate() {
            let need = row * u64::from(rows);
            if self.staging[k].size() < need {
                self.staging[k] = staging(device, need);
            }
        }
        let mut out: Vec<Vec<u8>> = reads
            .iter()
            .map(|r| {
                Vec::with_capacity(
                    r.texture.width() as usize * r.texture.height() as usize * r.texel as usize,
                )
            })
            .collect();
        let mut done = vec![0u32; reads.len()];
        self.last_bytes = 0;
        // One round reads the next band of every texture that has rows left.
        while reads
            .iter()
            .zip(&done)
            .any(|(r, &d)| d < r.texture.height())
        {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("Readback::encoder"),
            });
            let mut bands = Vec::new();
            for (k, r) in reads.iter().enumerate() {
                let (row, rows) = plans[k];
                let y = done[k];
                if y >= r.texture.height() {
                    continue;
                }
                let n = rows.min(r.texture.height() - y);
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
                bands.push((k, n, row));
            }
            ctx.queue.submit([encoder.finish()]);
            for &(k, n, row) in &bands {
                self.staging[k]
                    .slice(..row * u64::from(n))
                    .map_async(wgpu::MapMode::Read, |_| {});
            }
            map_now(device)?;
            for (k, n, row) in bands {
                let width_bytes = reads[k].texture.width() as usize * reads[k].texel as usize;
                let slice = self.staging[k].slice(..row * u64::from(n));
                {
                    let view = slice
                        .get_mapped_range()
                        .map_err(|e| RenderError::Readback(e.to_string()))?;
                    for line in view.chunks(row as usize).take(n as usize) {
                        let Some(texels) = line.get(..width_bytes) else {
                            return Err(RenderError::Readback("short staging row".into()));
                        };
                        out[k].extend_from_slice(texels);
                    }
                }
                self.staging[k].unmap();
                done[k] += n;
                self.last_bytes += width_bytes as u64 * u64::from(n);
            }
        }
        Ok(out)
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
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

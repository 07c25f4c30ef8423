//! Copying textures back to the CPU (rows padded to wgpu's 256-byte alignment on the way).

use super::RenderError;

/// A texture queued for readback into a mappable buffer.
pub struct Pending {
    buffer: wgpu::Buffer,
    width: u32,
    height: u32,
    /// Bytes of one texel.
    texel: u32,
    padded_row: u32,
}

/// Record a copy of `texture` (whole mip 0) into a new mappable buffer.
pub fn copy(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    texel: u32,
) -> Pending {
    let (width, height) = (texture.width(), texture.height());
    let row = width * texel;
    let padded_row =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(padded_row) * u64::from(height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(height),
            },
        },
        texture.size(),
    );
    Pending {
        buffer,
        width,
        height,
        texel,
        padded_row,
    }
}

/// Map a buffer after the submission that fills it and return its bytes.
pub fn map_bytes(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>, RenderError> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let bytes = slice
        .get_mapped_range()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

impl Pending {
    /// The texels' bytes, rows unpadded (call after submitting the copy).
    pub fn read_bytes(&self, device: &wgpu::Device) -> Result<Vec<u8>, RenderError> {
        let bytes = map_bytes(device, &self.buffer)?;
        let row = (self.width * self.texel) as usize;
        let mut out = Vec::with_capacity(row * self.height as usize);
        for y in 0..self.height as usize {
            let start = y * self.padded_row as usize;
            let Some(line) = bytes.get(start..start + row) else {
                return Err(RenderError::Readback("short buffer".into()));
            };
            out.extend_from_slice(line);
        }
        Ok(out)
    }

    /// The texels as `f32` components, rows unpadded.
    pub fn read_f32(&self, device: &wgpu::Device) -> Result<Vec<f32>, RenderError> {
        Ok(self
            .read_bytes(device)?
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }
}

//! Reading textures back: a depth texture is copied whole or not at all (WebGPU copies no part
//! of one), so a depth read of some rows is refused by `Readback` itself, in words, not left to
//! the device's validation; and the depth a frame reads is exact whichever path it takes (the
//! copy as it is, or through its `R32Float` copy above one staging buffer).

use dbuffer::render::readback::{fits_whole, Readback, TextureRead};
use dbuffer::render::{GpuContext, RenderError, Texture};

fn depth(ctx: &GpuContext, w: u32, h: u32) -> Texture {
    Texture::new(
        &ctx.device,
        "test depth",
        (w, h),
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
    )
}

#[test]
fn a_depth_texture_is_read_whole_or_refused_in_words() {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let d = depth(&ctx, 64, 48);
    let mut readback = Readback::default();
    // Whole: it fits one staging buffer.
    assert!(fits_whole(&ctx, &d.texture, 4));
    let whole = readback
        .read(&ctx, &[TextureRead::depth(&d.texture)])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(whole[0].len(), 64 * 48 * 4);
    // A band of its rows: refused before any copy, saying why.
    match readback.read(&ctx, &[TextureRead::depth(&d.texture).rows(8..16)]) {
        Err(RenderError::Readback(e)) => assert!(e.contains("depth"), "{e}"),
        other => panic!("a depth band was read: {:?}", other.map(|v| v.len())),
    }
    assert!(ctx.take_uncaptured_errors().is_empty());
    // An 8.4 Mpx depth does not fit: a frame reads its colour copy instead.
    let big = depth(&ctx, 4000, 2100);
    assert!(!fits_whole(&ctx, &big.texture, 4));
    assert!(!dbuffer::render::frame::reads_depth_whole(
        &ctx,
        &big.texture
    ));
}

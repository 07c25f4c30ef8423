//! Peak and current resident memory, and dbuffer's own heap, after each stage of one offline
//! render the way `dbuffer render` makes it (Linux):
//!
//!     cargo run --release --example mem_stages -- SCENE [WxH] [DBUFFER_SIZE]
//!
//! How the memory table (docs/guide/limits.md) of `dbuffer render` was measured and broken down by stage.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use dbuffer::render::offline::Offline;
use dbuffer::render::FrameRequest;

/// The Rust heap: what dbuffer itself allocates (the Vulkan driver allocates through libc and
/// is not counted here; on a CPU device its "GPU" memory is the rest of the resident set).
struct Counting;

static NOW: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = NOW.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        unsafe { System.dealloc(p, layout) };
        NOW.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, p: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, layout, new_size) };
        if !q.is_null() {
            let now = NOW.fetch_add(new_size, Ordering::Relaxed) + new_size;
            PEAK.fetch_max(now, Ordering::Relaxed);
            NOW.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        q
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

fn status(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse().ok())
        })
        .unwrap_or(0)
}

fn mark(stage: &str) {
    eprintln!(
        "{stage:<28} rss {:>6} MiB  peak {:>6} MiB   rust heap {:>6} MiB  peak {:>6} MiB",
        status("VmRSS:") / 1024,
        status("VmHWM:") / 1024,
        NOW.load(Ordering::Relaxed) >> 20,
        PEAK.load(Ordering::Relaxed) >> 20
    );
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_name = args.first().map_or("fig7-concave", String::as_str);
    let (w, h) = args
        .get(1)
        .and_then(|s| s.split_once('x'))
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .unwrap_or((1024, 1024));
    let ds = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1024);
    mark("start");
    let scene = dbuffer::scene::load(scene_name)?;
    mark("scene loaded");
    let offline = Offline::new()?;
    mark("device");
    let mut session = offline.session(scene);
    mark("session (surfaces uploaded)");
    let _ = session.prepared();
    mark("casters prepared");
    let request = FrameRequest {
        width: w,
        height: h,
        dbuffer_size: ds,
        read_dbuffer: false,
        ..FrameRequest::default()
    };
    // As `dbuffer render` does it: the frame, then the D-buffer streamed to its files in bands.
    let (frame, report) =
        dbuffer::render::offline::render_in(&offline.ctx, &mut session, &request, &mut |_, _| {})?;
    mark("frame read back");
    let maps_of = session.prepare_maps(&offline.ctx, &request)?;
    let size = session.light_maps(maps_of).map_or(0, |m| m.size);
    let mut meta = dbuffer::output::render_meta(
        "mem",
        session.scene(),
        &request,
        &offline.ctx,
        &frame,
        &report,
    );
    meta.dbuffer_size = size;
    let ctx = &offline.ctx;
    let band = ((16 << 20) / (20 * size.max(1))).max(1);
    let mut rows = dbuffer::output::BandedRows::new(size, band, |first, n| {
        session
            .read_map_rows(ctx, maps_of, first..first + n)
            .map(|b| dbuffer::output::dbuffer_texels(&b))
            .map_err(|e| e.to_string())
    });
    let dir = std::env::temp_dir().join("dbuffer-mem-stages");
    dbuffer::output::write_render_parts(
        &dir,
        &meta,
        &dbuffer::output::FramePixels(&frame),
        &mut rows,
    )?;
    mark("files written");
    Ok(())
}

//! A scene scored against the ray-cast reference at a small size: the reference rendered once
//! (K = 256), the pixels every metric counts, and each method's frame measured against it with
//! its row printed (`| scene | label | class mismatch % | MAE | penumbra MAE | p99 |`).

use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::metrics::{self, Metrics};
use dbuffer::geometry::{view, VtVariant};
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, FrameRequest, Knobs, Method};
use dbuffer::scene::{self, Scene};

/// The frame of `method` on `scene` at `size`², D-buffer and maps 1024², V(t) exact.
pub fn render(
    offline: &mut Offline,
    scene: &Scene,
    method: Method,
    knobs: Knobs,
    size: u32,
) -> Frame {
    let request = FrameRequest {
        width: size,
        height: size,
        dbuffer_size: 1024,
        method,
        vt: VtVariant::Exact,
        knobs: knobs.with(&SAMPLES, 256),
        read_dbuffer: false,
        read_cost: false,
        colour_only: false,
    };
    offline
        .render(scene, &request)
        .unwrap_or_else(|e| panic!("{method}: {e}"))
        .0
}

pub struct Scored {
    pub offline: Offline,
    pub scene: Scene,
    pub size: u32,
    pub reference: Vec<f32>,
    pub mask: Vec<bool>,
}

impl Scored {
    pub fn new(name: &str, size: u32) -> Scored {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
        let reference = render(
            &mut offline,
            &scene,
            Method::REFERENCE,
            Knobs::default(),
            size,
        );
        let receivers = view::receivers(&scene, &Bvh::build(scene.all_triangles()), size, size);
        let mask = dbuffer::compare::counted_pixels(&receivers, &reference);
        Scored {
            offline,
            scene,
            size,
            reference: reference.visibility,
            mask,
        }
    }

    /// `method`'s frame and its metrics, the row printed under its name.
    pub fn measure(&mut self, method: Method, knobs: Knobs) -> (Frame, Metrics) {
        self.measure_as(method, knobs, &method.to_string())
    }

    /// The same, the row printed under `label`.
    pub fn measure_as(&mut self, method: Method, knobs: Knobs, label: &str) -> (Frame, Metrics) {
        let frame = render(&mut self.offline, &self.scene, method, knobs, self.size);
        let m = metrics::compare(&self.reference, &frame.visibility, &self.mask);
        println!(
            "| {} | {label} | {:.2} | {:.4} | {:.4} | {:.3} |",
            self.scene.name, m.class_mismatch_pct, m.mae, m.penumbra_mae, m.p99
        );
        (frame, m)
    }
}

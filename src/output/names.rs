//! What a render's files are called, the colours of `classes.png`, and what `meta.json` holds.

use serde::ser::{SerializeMap, Serializer};

use crate::geometry::metrics::ShadowClass;
use crate::render::Frame;

/// The shaded image.
pub const IMAGE_PNG: &str = "image.png";
/// Visibility per pixel.
pub const VISIBILITY_EXR: &str = "visibility.exr";
/// World position per pixel.
pub const POSITION_EXR: &str = "position.exr";
/// The light-view D-buffer.
pub const DBUFFER_EXR: &str = "dbuffer.exr";
/// |cx_s| of both volumes.
pub const DBUFFER_S_EXR: &str = "dbuffer_s.exr";
/// Shadow classes per pixel.
pub const CLASSES_PNG: &str = "classes.png";
/// Everything else about the render.
pub const META_JSON: &str = "meta.json";

/// Every file [`write_render`](super::write_render) writes, in the order it writes them (and returns their paths).
pub const FILE_NAMES: [&str; 7] = [
    IMAGE_PNG,
    VISIBILITY_EXR,
    POSITION_EXR,
    DBUFFER_EXR,
    DBUFFER_S_EXR,
    CLASSES_PNG,
    META_JSON,
];

/// The name of the hidden temporary folder [`write_render`](super::write_render) makes inside the output folder
/// starts so (followed by the process id and a counter); none is left behind on return.
pub const TEMP_PREFIX: &str = ".dbuffer-render-";

/// `classes.png` colour of a pixel that saw no surface: black.
pub const NOT_HIT_RGB: [u8; 3] = [0, 0, 0];
/// `classes.png` colour of a lit pixel (V ≥ 1 − ε): light warm gray.
pub const LIT_RGB: [u8; 3] = [224, 218, 204];
/// `classes.png` colour of a penumbra pixel: mid orange.
pub const PENUMBRA_RGB: [u8; 3] = [230, 140, 40];
/// `classes.png` colour of an umbra pixel (V ≤ ε): dark blue.
pub const UMBRA_RGB: [u8; 3] = [30, 50, 130];

/// The `classes.png` colour of a shadow class (class 0 lit, 1 penumbra, 2 umbra):
///
/// | class | colour | RGB |
/// |---|---|---|
/// | lit (0) | light warm gray | (224, 218, 204) |
/// | penumbra (1) | mid orange | (230, 140, 40) |
/// | umbra (2) | dark blue | (30, 50, 130) |
/// | no surface hit | black | (0, 0, 0) |
pub fn class_rgb(class: ShadowClass) -> [u8; 3] {
    match class {
        ShadowClass::Lit => LIT_RGB,
        ShadowClass::Penumbra => PENUMBRA_RGB,
        ShadowClass::Umbra => UMBRA_RGB,
    }
}

/// `meta.json` of a frame rendered offline: the request, the adapter, the timings, the geometry
/// stage's counts and warnings (and whether the D-buffer's frustum had to cut a penumbra).
pub fn render_meta(
    name: &str,
    scene: &crate::scene::Scene,
    request: &crate::render::FrameRequest,
    ctx: &crate::render::GpuContext,
    frame: &Frame,
    report: &crate::render::offline::FrameReport,
) -> RenderMeta {
    let mut warnings = report.warnings.clone();
    if report.clipped {
        warnings.push(format!(
            "the casters' penumbrae reach beyond {}° from the D-buffer's axis; shadows there are cut",
            crate::geometry::light_view::MAX_HALF_ANGLE_DEG
        ));
    }
    let g = report.geometry;
    RenderMeta {
        scene: name.to_string(),
        method: request.method.name().to_string(),
        variant: request.vt.name().to_string(),
        width: frame.width,
        height: frame.height,
        dbuffer_size: frame.maps.as_ref().map_or(0, |m| m.size),
        adapter: ctx.adapter.name.clone(),
        backend: format!("{:?}", ctx.adapter.backend),
        cpu_ms: report.cpu_ms.clone(),
        gpu_ms: frame.gpu_ms.clone(),
        triangles: scene.objects.iter().map(|o| o.mesh.triangles.len()).sum(),
        caster_triangles: scene.caster_triangle_count(),
        umbra_silhouette_edges: g.umbra_edges,
        penumbra_silhouette_edges: g.penumbra_edges,
        umbra_volume_triangles: g.umbra_triangles,
        penumbra_volume_triangles: g.penumbra_triangles,
        warnings,
    }
}

/// What `meta.json` holds. The two timing lists are written as JSON objects in their order,
/// `{"geometry": 0.4, ...}`; a name that repeats gets ` #2`, ` #3`, ... so that no timing is lost,
/// and a non-finite time is written as `null`.
#[derive(serde::Serialize, Clone, Debug)]
pub struct RenderMeta {
    pub scene: String,
    pub method: String,
    pub variant: String,
    pub width: u32,
    pub height: u32,
    pub dbuffer_size: u32,
    pub adapter: String,
    pub backend: String,
    /// Per stage, e.g. [("geometry", 0.4)], CPU milliseconds.
    #[serde(serialize_with = "ms_map")]
    pub cpu_ms: Vec<(String, f64)>,
    /// Per GPU pass, GPU milliseconds from timestamp queries (empty if the adapter has none).
    #[serde(serialize_with = "ms_map")]
    pub gpu_ms: Vec<(String, f64)>,
    pub triangles: usize,
    pub caster_triangles: usize,
    pub umbra_silhouette_edges: usize,
    pub penumbra_silhouette_edges: usize,
    pub umbra_volume_triangles: usize,
    pub penumbra_volume_triangles: usize,
    pub warnings: Vec<String>,
}

/// A list of (name, milliseconds) as a JSON object in list order; repeated names get ` #k`.
fn ms_map<S: Serializer>(list: &[(String, f64)], s: S) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(list.len()))?;
    for (i, (name, ms)) in list.iter().enumerate() {
        let earlier = list[..i].iter().filter(|(n, _)| n == name).count();
        if earlier == 0 {
            map.serialize_entry(name, ms)?;
        } else {
            map.serialize_entry(&format!("{name} #{}", earlier + 1), ms)?;
        }
    }
    map.end()
}

impl RenderMeta {
    /// The text of `meta.json`: pretty-printed, with a final newline.
    pub fn to_json_pretty(&self) -> Result<String, serde_json::Error> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        Ok(text)
    }
}

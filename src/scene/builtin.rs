//! Built-in scenes (docs/guide/scenes.md): after the D-buffer paper's figures, with a linear light
//! after the figures of Heidrich et al. 2000, and under rectangle and polygon lights. Each is a TOML file in `assets/scenes/`, embedded in the
//! binary and parsed by the same code as user scene files, so they double as examples.

use super::{Scene, SceneError, SceneFile};
use std::path::Path;

/// `(name, TOML source)`, in the order `dbuffer scenes` lists them.
const SCENES: &[(&str, &str)] = &[
    (
        "fig1-large-light",
        include_str!("../../assets/scenes/fig1-large-light.toml"),
    ),
    (
        "fig7-concave",
        include_str!("../../assets/scenes/fig7-concave.toml"),
    ),
    (
        "fig8a-distance",
        include_str!("../../assets/scenes/fig8a-distance.toml"),
    ),
    (
        "fig8b-light-size",
        include_str!("../../assets/scenes/fig8b-light-size.toml"),
    ),
    (
        "fig8c-complex",
        include_str!("../../assets/scenes/fig8c-complex.toml"),
    ),
    (
        "table1-224",
        include_str!("../../assets/scenes/table1-224.toml"),
    ),
    (
        "table1-960",
        include_str!("../../assets/scenes/table1-960.toml"),
    ),
    (
        "table1-1440",
        include_str!("../../assets/scenes/table1-1440.toml"),
    ),
    (
        "table1-5760",
        include_str!("../../assets/scenes/table1-5760.toml"),
    ),
    ("bunny", include_str!("../../assets/scenes/bunny.toml")),
    ("overlap", include_str!("../../assets/scenes/overlap.toml")),
    (
        "leak-test",
        include_str!("../../assets/scenes/leak-test.toml"),
    ),
    (
        "no-umbra",
        include_str!("../../assets/scenes/no-umbra.toml"),
    ),
    (
        "acute-corner",
        include_str!("../../assets/scenes/acute-corner.toml"),
    ),
    (
        "fusion-cross",
        include_str!("../../assets/scenes/fusion-cross.toml"),
    ),
    (
        "fusion-links",
        include_str!("../../assets/scenes/fusion-links.toml"),
    ),
    (
        "fusion-many",
        include_str!("../../assets/scenes/fusion-many.toml"),
    ),
    // Many casters: the content engines face, where one chord per pixel breaks.
    ("cluster", include_str!("../../assets/scenes/cluster.toml")),
    ("blinds", include_str!("../../assets/scenes/blinds.toml")),
    // Linear lights (the figures of Heidrich et al. 2000).
    (
        "line-fig2",
        include_str!("../../assets/scenes/line-fig2.toml"),
    ),
    (
        "line-fig3-tilted",
        include_str!("../../assets/scenes/line-fig3-tilted.toml"),
    ),
    (
        "line-fig6-gap",
        include_str!("../../assets/scenes/line-fig6-gap.toml"),
    ),
    (
        "line-fig8-overlap",
        include_str!("../../assets/scenes/line-fig8-overlap.toml"),
    ),
    (
        "line-fig9",
        include_str!("../../assets/scenes/line-fig9.toml"),
    ),
    (
        "line-bar",
        include_str!("../../assets/scenes/line-bar.toml"),
    ),
    // Rectangle and polygon lights.
    (
        "rect-strip",
        include_str!("../../assets/scenes/rect-strip.toml"),
    ),
    (
        "rect-fig7",
        include_str!("../../assets/scenes/rect-fig7.toml"),
    ),
    (
        "polygon-triangle",
        include_str!("../../assets/scenes/polygon-triangle.toml"),
    ),
    (
        "rect-fusion",
        include_str!("../../assets/scenes/rect-fusion.toml"),
    ),
    ("pergola", include_str!("../../assets/scenes/pergola.toml")),
];

/// The names of the built-in scenes, in a fixed order.
pub fn names() -> &'static [&'static str] {
    const NAMES: [&str; SCENES.len()] = {
        let mut names = [""; SCENES.len()];
        let mut i = 0;
        while i < SCENES.len() {
            names[i] = SCENES[i].0;
            i += 1;
        }
        names
    };
    &NAMES
}

/// The TOML source of built-in scene `name`.
pub fn source(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// The parsed scene file of built-in scene `name`; `None` if there is no such scene.
pub fn file(name: &str) -> Option<Result<SceneFile, SceneError>> {
    source(name).map(|text| SceneFile::parse(text, &format!("built-in scene {name}")))
}

/// Built-in scene `name`, built (meshes in world space); `None` if there is no such scene.
/// Built-in scenes use only built-in meshes, so this works from any directory.
pub fn get(name: &str) -> Option<Result<Scene, SceneError>> {
    let label = format!("built-in scene {name}");
    file(name).map(|f| f.and_then(|f| f.build_named(Path::new("."), &label, name)))
}

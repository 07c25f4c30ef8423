//! The tests that need no GPU: the scenes and their parsers (with the fuzzer's short run), the
//! geometry and its CPU twins against the ray-cast oracle, the files `render` writes, and the
//! documentation against the code. One module per topic; run one with
//! `cargo test --test cpu scene_files`.

mod area_lights;
mod docs;
mod docs_knobs;
mod fmt_check;
mod fused_vs_oracle;
mod fuzz_parsers;
mod gltf_models;
mod gltf_shipped;
mod layers;
mod oracle_analytic;
mod output_files;
mod scene_builtins;
mod scene_files;
mod shader_reload;
mod twin_builtins;
mod twin_vs_oracle;

/// The fuzzer measures each input's peak allocation (`fuzz_parsers`), which needs its counting
/// allocator as the binary's. It counts per thread, so the other tests here, on threads of
/// their own, neither disturb its figures nor notice it beyond a thread-local add per allocation.
#[global_allocator]
static ALLOC: dbuffer_fuzzer::CountingAlloc = dbuffer_fuzzer::CountingAlloc;

//! libFuzzer target: OBJ meshes, through the checks of the `dbuffer-fuzzer` crate
//! (`tests/fuzzer/`).
#![no_main]

use dbuffer_fuzzer as fuzz;

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

static SANDBOX: OnceLock<fuzz::Sandbox> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let sandbox = SANDBOX.get_or_init(|| fuzz::Sandbox::new("libfuzzer-obj"));
    if let Some(target) = fuzz::targets().into_iter().find(|t| t.name == "obj") {
        if let Err(broken) = (target.run)(sandbox, data) {
            panic!("{broken}");
        }
    }
});

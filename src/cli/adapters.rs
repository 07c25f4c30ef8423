//! `dbuffer adapters`, `-v`'s adapter line, and how an error is printed.

use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Result;
use dbuffer::render::adapter::{self, Verdict};
use dbuffer::render::gpu_reference;
use dbuffer::render::passes::trace::Path;
use dbuffer::render::{GpuContext, Method, RenderError};

static VERBOSE: AtomicBool = AtomicBool::new(false);

/// `-v` was given (on any command).
pub fn set_verbose(on: bool) {
    VERBOSE.store(on, Ordering::Relaxed);
}

/// With `-v`: which adapter `ctx` is on and why it was chosen (on stderr).
pub fn chosen(ctx: &GpuContext) {
    if VERBOSE.load(Ordering::Relaxed) {
        errln!("adapter   {}", adapter::info_line(&ctx.adapter));
        errln!("chosen by {}", ctx.chosen);
    }
}

/// Every adapter on every backend wgpu looks at, and what each method gets on it.
pub fn list() -> Result<()> {
    let (adapters, why) = adapter::every_adapter();
    outln!("backends  {why}");
    if adapters.is_empty() {
        outln!(
            "no adapter found: on a machine without a GPU install Mesa's Vulkan driver \
             (Debian: mesa-vulkan-drivers) or its GL one (libegl1 libegl-mesa0 libgl1-mesa-dri)"
        );
        return Ok(());
    }
    let width = Method::all()
        .iter()
        .map(|m| m.name().len())
        .max()
        .unwrap_or(0);
    for (i, a) in adapters.iter().enumerate() {
        outln!();
        outln!("adapter {i}: {}", adapter::info_line(&a.info));
        for &m in Method::all() {
            let (word, detail) = match m.on(&a.caps) {
                Verdict::Runs => ("runs", String::new()),
                Verdict::Fallback(f) => ("runs with fallback", f.join("; ")),
                Verdict::Cannot(missing) => ("cannot", format!("needs {}", missing.join(", "))),
            };
            if detail.is_empty() {
                outln!("  {:<width$}  {word}", m.name());
            } else {
                outln!("  {:<width$}  {word}: {detail}", m.name());
            }
        }
        // The shadow-ray tracer: which path `compare --reference gpu` takes here.
        match gpu_reference::refuses_on(&a.caps) {
            None => match Path::best(&a.caps) {
                Path::RayQuery => outln!("  GPU reference: hardware ray queries (compute)"),
                Path::WgslBvh => outln!("  GPU reference: the BVH traversed in WGSL (compute)"),
            },
            Some(why) => outln!("  GPU reference: cannot ({why})"),
        }
    }
    Ok(())
}

/// What `main` prints for an error: `dbuffer: ` and the causes on one line (newlines in a name
/// escaped, so a path cannot fake a line); a GPU's own message (wgpu's, several lines) with its
/// cause chain on indented lines under it, and what the user can do. Every subcommand's errors
/// come here: the GPU's is found wherever it sits in the chain, inside an animation's error too.
pub fn error_lines(e: &anyhow::Error) -> String {
    // A shader's error: the file and line of its source and, under it, the line itself; no
    // advice about adapters (the file is the user's to fix).
    if let Some(shader) = e
        .chain()
        .find_map(|c| c.downcast_ref::<dbuffer::render::shaders::ShaderError>())
    {
        let mut out = String::from("dbuffer: ");
        for context in e
            .chain()
            .take_while(|c| !c.is::<dbuffer::render::shaders::ShaderError>())
        {
            out.push_str(&context.to_string().replace('\n', "\\n"));
            out.push_str(": ");
        }
        out.push_str(&shader.headline().replace('\n', "\\n"));
        out.push('\n');
        if let Some(text) = &shader.text {
            out.push_str("    ");
            out.push_str(text.trim_end());
            out.push('\n');
        }
        return out;
    }
    let gpu = e.chain().find_map(gpu_error);
    let Some(gpu) = gpu else {
        return format!("dbuffer: {}\n", format!("{e:#}").replace('\n', "\\n"));
    };
    let mut out = String::from("dbuffer: ");
    for context in e.chain().take_while(|c| gpu_error(*c).is_none()) {
        out.push_str(&context.to_string().replace('\n', "\\n"));
        out.push_str(": ");
    }
    out.push_str(&gpu_lines(&gpu.to_string()));
    // Another adapter is advice for what the adapter refused, not for a user's shader (its
    // pipeline labelled `file:PATH`): that is the file's to fix.
    let user_shader = gpu.to_string().contains("label = 'file:");
    if matches!(gpu, RenderError::Gpu(_) | RenderError::Device(_)) && !user_shader {
        out.push_str(
            "  what you can do: try another backend or adapter (--backend vulkan|gl|metal|dx12; \
             `dbuffer adapters` lists them and what each method needs), and report this \
             message with that list\n",
        );
    }
    out
}

/// The error the GPU (or wgpu on its behalf) reported, if `e` is one: a [`RenderError`] of a
/// GPU kind, bare or as an animation's.
fn gpu_error<'a>(e: &'a (dyn std::error::Error + 'static)) -> Option<&'a RenderError> {
    let render = e.downcast_ref::<RenderError>().or_else(|| {
        match e.downcast_ref::<dbuffer::animation::AnimationError>() {
            Some(dbuffer::animation::AnimationError::Render(r)) => Some(r),
            _ => None,
        }
    })?;
    matches!(
        render,
        RenderError::Gpu(_)
            | RenderError::Device(_)
            | RenderError::Lost(_)
            | RenderError::Stalled(_)
            | RenderError::NoAdapter(_)
            | RenderError::Readback(_)
    )
    .then_some(render)
}

/// A GPU's message as lines: its first line as it is, each cause under it indented (wgpu's
/// empty lines and its "Caused by:" left out), every line ended.
pub fn gpu_lines(message: &str) -> String {
    let mut lines = message
        .lines()
        .map(str::trim_end)
        .filter(|l| !l.trim().is_empty() && l.trim() != "Caused by:");
    let mut out = String::from(lines.next().unwrap_or_default());
    out.push('\n');
    for line in lines {
        out.push_str("  ");
        out.push_str(line);
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// wgpu's validation error as the GL backend prints it: its message, then its causes on
    /// indented lines (never one line with literal `\n`s), then what to do.
    #[test]
    fn a_gpu_error_is_its_message_and_indented_causes() {
        let wgpu = "Validation Error\n\nCaused by:\n  In Device::create_render_pipeline, label = \
                    'ShadowMapPass::pipeline'\n    Color state [0] is invalid\n      Format \
                    R32Float is not renderable\n";
        let e = anyhow::Error::new(RenderError::Gpu(wgpu.into())).context("rendering");
        let text = error_lines(&e);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "dbuffer: rendering: the GPU reported an error: Validation Error"
        );
        assert_eq!(
            lines[1],
            "    In Device::create_render_pipeline, label = 'ShadowMapPass::pipeline'"
        );
        assert_eq!(lines[3], "        Format R32Float is not renderable");
        assert!(lines[4].starts_with("  what you can do: try another backend"));
        assert!(
            !text.contains("\\n") && !text.contains("Caused by"),
            "{text}"
        );
    }

    /// A user's method's pipeline error is the file's to fix: no advice to change adapters.
    #[test]
    fn a_user_shader_error_gets_no_adapter_advice() {
        let wgpu = "Validation Error\n\nCaused by:\n  In Device::create_render_pipeline, label = \
                    'file:my.wgsl'\n    Error matching shader requirements\n";
        let e = anyhow::Error::new(RenderError::Gpu(wgpu.into()));
        let text = error_lines(&e);
        assert!(text.contains("label = 'file:my.wgsl'"), "{text}");
        assert!(!text.contains("what you can do"), "{text}");
    }

    /// Any other error stays one line, a newline in a name escaped (it cannot fake a line).
    #[test]
    fn other_errors_stay_one_line() {
        let e = anyhow::anyhow!("cannot read a\nb.obj").context("cannot load scene 'x'");
        assert_eq!(
            error_lines(&e),
            "dbuffer: cannot load scene 'x': cannot read a\\nb.obj\n"
        );
    }
}

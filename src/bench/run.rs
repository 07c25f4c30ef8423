//! Running the bench: every case's frames through the lab's own calls (a [`Session`] per scene
//! and method), the display path, frame coherence and the geometry-scaling curve.

use crate::render::truth;
use std::time::Instant;

use glam::{Affine3A, Vec3};

use super::{
    targets, BenchError, Case, Coherence, Config, Display, DisplayRun, FrameSource, PassTime,
    Report, Run, ScalingPoint, SceneInfo, Stat, Timing, TABLE1_SIZES,
};
use crate::geometry::{PreparedCasters, VolumeParams, VtVariant};
use crate::render::passes::floor::Floor;
use crate::render::passes::view::{Mapping, View, ViewParams};
use crate::render::readback::map_now;
use crate::render::session::{FrameJob, Session};
use crate::render::timer::{PassTimer, Recorder};
use crate::render::{Frame, FrameRequest, FrameTargets, GpuContext, Method};
use crate::scene::{
    self, shapes, AreaLight, Camera, Light, LightKind, Object, Outline, Scene, MAX_POLYGON_VERTICES,
};

/// What the run reports as it goes (for a progress line on stderr).
pub type Progress<'a> = &'a mut dyn FnMut(&str);

/// Load the scenes `config` names, in order (before any GPU work: a bad name fails first).
pub fn load_scenes(config: &Config) -> Result<Vec<Scene>, BenchError> {
    config
        .scenes
        .iter()
        .map(|name| {
            scene::load(name).map_err(|source| BenchError::Scene {
                name: name.clone(),
                source: Box::new(source),
            })
        })
        .collect()
}

/// Run the bench on `ctx` over `loaded`, the scenes of [`load_scenes`].
pub fn run(
    ctx: &GpuContext,
    config: &Config,
    loaded: Vec<Scene>,
    progress: Progress,
) -> Result<Report, BenchError> {
    config.validate()?;
    let started = Instant::now();
    let mut scenes = Vec::new();
    for scene in &loaded {
        let name = &scene.name;
        progress(&format!("geometry  {name}"));
        scenes.push(scene_info(scene, config.geometry_runs));
    }

    let total = loaded.len() * config.sizes.len();
    let mut runs = Vec::with_capacity(total * config.cases.len());
    let mut display = Vec::new();
    let mut done = 0;
    for scene in &loaded {
        // One session per method, so no method pays for another's targets or volumes.
        let mut sessions: Vec<Session> = config
            .cases
            .iter()
            .map(|case| Session::new(ctx, scene_for(case, scene)))
            .collect();
        // Cases timed under the other kind of light (see `scene_for`) say so in their label.
        let converted: Vec<bool> = sessions
            .iter()
            .map(|s| s.scene().light.kind() != scene.light.kind())
            .collect();
        for &size in &config.sizes {
            progress(&format!(
                "display   {} {size}²: lab frame, readback path, floor",
                scene.name
            ));
            display.push(time_display(ctx, scene, config, size));
            let elapsed = started.elapsed().as_secs_f64();
            let eta = if done == 0 {
                String::new()
            } else {
                let left = elapsed / done as f64 * (total - done) as f64;
                format!(", ~{left:.0} s of frames left")
            };
            progress(&format!(
                "[{}/{total}] {} {size}²: {} cases, {} frames each, interleaved{eta}",
                done + 1,
                scene.name,
                config.cases.len(),
                config.warmup + config.frames,
            ));
            runs.extend(time_size(ctx, &mut sessions, &converted, config, size));
            done += 1;
        }
    }

    let coherence = if config.coherence {
        let name = config
            .scenes
            .iter()
            .position(|s| s == "table1-5760")
            .unwrap_or(config.scenes.len() - 1);
        let size = config
            .sizes
            .iter()
            .copied()
            .max()
            .unwrap_or(TABLE1_SIZES[1]);
        let scene = &loaded[name.min(loaded.len() - 1)];
        progress(&format!(
            "coherence {} {size}²: geometry cached, then rebuilt every frame",
            scene.name
        ));
        Some(coherence(ctx, scene, config, size))
    } else {
        None
    };

    let mut scaling = Vec::new();
    for &t in &config.scaling {
        progress(&format!("scaling   geometry of a {t}-triangle sphere"));
        scaling.push(scaling_point(ctx, t, config.scaling_runs));
    }

    let reference_rays_per_s = reference_throughput(&runs);
    let mut report = Report {
        adapter: ctx.adapter.name.clone(),
        backend: format!("{:?}", ctx.adapter.backend),
        device_type: format!("{:?}", ctx.adapter.device_type),
        timestamps: ctx.timestamps,
        host: crate::render::adapter::host_description(),
        quick: config.quick,
        warmup: config.warmup,
        frames: config.frames,
        dbuffer_size: config.dbuffer_size,
        unix_time: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0),
        seconds: 0.0,
        scenes,
        runs,
        display,
        coherence,
        scaling,
        reference_rays_per_s,
        targets: Vec::new(),
    };
    report.targets = targets(&report);
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The scene's caster count and its geometry stage: prepared once, built `runs` times.
fn scene_info(scene: &Scene, runs: usize) -> SceneInfo {
    let t = Instant::now();
    let prepared = PreparedCasters::new(scene);
    let prepare_ms = ms_since(t);
    let params = VolumeParams::for_scene(scene);
    let mut samples = Vec::with_capacity(runs);
    let mut last = None;
    // The geometry stage is the D-buffer's: a disk light's (none for a line light).
    for light in std::iter::repeat_n(scene.light.as_area(), runs.max(1)).flatten() {
        let t = Instant::now();
        let g = prepared.build(light, &params);
        samples.push(ms_since(t));
        last = Some(std::hint::black_box(g));
    }
    let stats = last.map(|g| g.stats).unwrap_or_default();
    SceneInfo {
        name: scene.name.clone(),
        caster_triangles: scene.caster_triangle_count(),
        prepare_ms,
        geometry_ms: Stat::of(&samples).unwrap_or_default(),
        umbra_triangles: stats.umbra_triangles,
        penumbra_triangles: stats.penumbra_triangles,
    }
}

fn request(config: &Config, size: u32, case: &Case) -> FrameRequest {
    FrameRequest {
        width: size,
        height: size,
        dbuffer_size: config.dbuffer_size,
        method: case.method,
        vt: VtVariant::Smoothstep,
        knobs: case.knobs,
        read_dbuffer: false,
        read_cost: false,
        colour_only: false,
    }
}

/// Sum of a frame's GPU passes, or `None` without timestamps.
fn gpu_total(gpu_ms: &[(String, f64)]) -> Option<f64> {
    (!gpu_ms.is_empty()).then(|| gpu_ms.iter().map(|(_, ms)| ms).sum())
}

/// The light-space passes of a frame: every pass but the camera pass.
fn light_total(gpu_ms: &[(String, f64)]) -> Option<f64> {
    let light: Vec<f64> = gpu_ms
        .iter()
        .filter(|(p, _)| p != "camera_pass")
        .map(|(_, ms)| *ms)
        .collect();
    (!light.is_empty()).then(|| light.iter().sum())
}

/// The frames of one method at one size, as they come in.
#[derive(Default)]
struct Samples {
    wall: Vec<f64>,
    totals: Vec<f64>,
    light: Vec<f64>,
    passes: Vec<(String, Vec<f64>)>,
    hit_pixels: usize,
    rays: Vec<f64>,
}

impl Samples {
    fn add(&mut self, frame: &Frame, wall_ms: f64) {
        self.wall.push(wall_ms);
        self.totals.extend(gpu_total(&frame.gpu_ms));
        self.light.extend(light_total(&frame.gpu_ms));
        for (pass, ms) in &frame.gpu_ms {
            match self.passes.iter_mut().find(|(p, _)| p == pass) {
                Some((_, v)) => v.push(*ms),
                None => self.passes.push((pass.clone(), vec![*ms])),
            }
        }
        self.hit_pixels = (0..frame.len()).filter(|&i| frame.hit(i)).count();
    }

    fn timing(self, cpu_side: bool) -> Timing {
        let frames = self.wall.len();
        let wall_ms = Stat::of(&self.wall).unwrap_or_default();
        let gpu_total_ms = Stat::of(&self.totals);
        let (frame_ms, frame_source) = match gpu_total_ms {
            Some(g) if !cpu_side => (g, FrameSource::GpuTimestamps),
            _ => (wall_ms, FrameSource::FencedWall),
        };
        Timing {
            fps: if frame_ms.median > 0.0 {
                1e3 / frame_ms.median
            } else {
                0.0
            },
            frame_ms,
            frame_source,
            passes: self
                .passes
                .into_iter()
                .filter_map(|(pass, v)| {
                    Some(PassTime {
                        pass,
                        ms: Stat::of(&v)?,
                    })
                })
                .collect(),
            gpu_total_ms,
            light_ms: Stat::of(&self.light),
            wall_ms,
            hit_pixels: self.hit_pixels,
            rays_ms: Stat::of(&self.rays),
            frames,
        }
    }
}

/// The scene `method` is timed on: `scene` itself, or, for a method that refuses its light, the
/// same scene under the light converted to the kind the method takes (`Light::converted`: a
/// disk's diameter as a segment, a segment's length as a disk), so every method of the registry
/// has a frame on the same casters at the same size to compare with the D-buffer's.
///
/// A case timed under a polygon ([`Case::polygon_dbuffer`]) gets the regular 16-gon inscribed
/// in the scene's disk (the most vertices a polygon light may have).
pub fn scene_for(case: &Case, scene: &Scene) -> Scene {
    if let (Some(LightKind::Polygon), Some(disk)) = (case.light, scene.light.as_area()) {
        return Scene {
            light: Light::Area(disk.inscribed_polygon(MAX_POLYGON_VERTICES)),
            ..scene.clone()
        };
    }
    match case.method.needs() {
        Some(kinds) if !kinds.contains(&scene.light.kind()) => Scene {
            light: scene.light.converted(kinds[0]),
            ..scene.clone()
        },
        _ => scene.clone(),
    }
}

/// Every method at one size: [`time_frames`] over one session per case, each row labelled.
/// `sessions[i]` renders `config.cases[i]`; a method that fails is dropped from the rounds and
/// its row says why.
fn time_size(
    ctx: &GpuContext,
    sessions: &mut [Session],
    converted: &[bool],
    config: &Config,
    size: u32,
) -> Vec<Run> {
    let requests: Vec<FrameRequest> = config
        .cases
        .iter()
        .map(|case| request(config, size, case))
        .collect();
    let timings = time_frames(
        ctx,
        sessions,
        &requests,
        config.warmup,
        config.frames,
        config.slow_frame_ms,
    );
    config
        .cases
        .iter()
        .zip(sessions.iter_mut().zip(converted))
        .zip(timings)
        .zip(&requests)
        .map(|(((case, (session, &converted)), timing), req)| Run {
            scene: session.scene().name.clone(),
            size,
            label: if converted {
                format!("{} ({} light)", case.label, session.scene().light.kind())
            } else {
                case.label.clone()
            },
            method: case.method.name().to_string(),
            fill: timing
                .is_ok()
                .then(|| session.stencil_fill(ctx, case.method)?.ok())
                .flatten(),
            work: timing
                .is_ok()
                .then(|| work_per_pixel(ctx, session, req))
                .flatten(),
            error: timing.as_ref().err().cloned(),
            timing: timing.ok(),
        })
        .collect()
}

/// The mean of what `request`'s method counted per pixel in its cost view (its `Cost` unit:
/// taps, listed edges, BVH nodes…), over the pixels that show a surface, from one more frame
/// with the cost target read back (untimed); `None` if it fails.
fn work_per_pixel(ctx: &GpuContext, session: &mut Session, request: &FrameRequest) -> Option<f64> {
    let frame = session
        .frame(
            ctx,
            &FrameRequest {
                read_cost: true,
                ..*request
            },
        )
        .ok()?;
    let (sum, n) = (0..frame.len())
        .filter(|&i| frame.hit(i))
        .filter_map(|i| frame.cost.get(i))
        .fold((0.0f64, 0usize), |(s, n), c| (s + f64::from(c[0]), n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The bench's protocol, the one `dbuffer study` times its cells by too: `warmup` frames, then
/// `frames` rounds of one frame per request, so a machine whose speed drifts (a shared CPU
/// adapter) slows every request alike (the GPU methods' rounds, then the CPU-side references').
/// Every timed frame makes its light-space maps again (`Session::invalidate_light_maps`): the
/// whole frame is timed, light pass and camera pass. `sessions[i]` renders `requests[i]`; a
/// request that fails is dropped from the rounds and its result says why.
///
/// `slow_ms`: a request whose first timed frame took longer (wall) is timed on that frame alone
/// (`dbuffer study`'s guard: a minute-long frame is measured once, its spread small beside it).
pub fn time_frames(
    ctx: &GpuContext,
    sessions: &mut [Session],
    requests: &[FrameRequest],
    warmup: usize,
    frames: usize,
    slow_ms: Option<f64>,
) -> Vec<Result<Timing, String>> {
    // A method the device cannot run is skipped with its reason, before any frame.
    let mut errors: Vec<Option<String>> = requests
        .iter()
        .map(|r| r.method.refuses_on(&ctx.caps))
        .collect();
    let mut samples: Vec<Samples> = requests.iter().map(|_| Samples::default()).collect();
    // The GPU cases' rounds first, then the CPU-side references' own: a frame timed right after a
    // reference's ray casting (seconds of both cores) ran every GPU pass about 1 ms slower on
    // lavapipe, a bias on whichever case came first in a round.
    for cpu_side in [false, true] {
        for round in 0..warmup + frames {
            for (i, session) in sessions.iter_mut().enumerate() {
                if errors[i].is_some() || requests[i].method.cpu_side() != cpu_side {
                    continue;
                }
                let slow = slow_ms.is_some_and(|s| samples[i].wall.first().is_some_and(|&w| w > s));
                if slow {
                    continue;
                }
                session.invalidate_light_maps();
                let t = Instant::now();
                let frame = if truth::is_soft(requests[i].method) {
                    // The reference: one more sample per pixel, then its frame (reference-hard, also
                    // CPU-side, casts its rays again in the frame: its image was invalidated).
                    session
                        .advance_reference(ctx, &requests[i], 1)
                        .and_then(|_| session.frame(ctx, &requests[i]))
                } else {
                    session.frame(ctx, &requests[i])
                };
                match frame {
                    Ok(frame) if round >= warmup => samples[i].add(&frame, ms_since(t)),
                    Ok(_) => {}
                    Err(e) => errors[i] = Some(e.to_string()),
                }
            }
        }
    }
    // The reference's ray casting alone: one more sample per pixel without a frame.
    for (i, request) in requests.iter().enumerate() {
        if !truth::is_soft(request.method) || errors[i].is_some() {
            continue;
        }
        for _ in 0..frames {
            let t = Instant::now();
            if sessions[i].advance_reference(ctx, request, 1).is_err() {
                break;
            }
            samples[i].rays.push(ms_since(t));
        }
    }
    samples
        .into_iter()
        .zip(errors)
        .zip(requests)
        .map(|((samples, error), request)| match error {
            Some(e) => Err(e),
            None => Ok(samples.timing(request.method.cpu_side())),
        })
        .collect()
}

/// The lab's display path headless (light still and light moving), the readback path
/// `dbuffer render` takes, and the floor, on one scene and size, interleaved frame by frame.
fn time_display(ctx: &GpuContext, scene: &Scene, config: &Config, size: u32) -> DisplayRun {
    let mut session = Session::new(ctx, scene.clone());
    let req = request(config, size, &Case::for_method(Method::DBUFFER));
    let view = ViewParams {
        view: View::Final,
        channels: [true, false, false, false],
        mapping: Mapping::unit(),
    };
    let mut targets = FrameTargets::new();
    let base = scene.light;
    let mut nudge = 0u32;
    let mut lab = |session: &mut Session, targets: &mut FrameTargets, moving: bool| {
        if moving {
            // The light a centimetre to one side or the other: everything light-space is redone.
            nudge += 1;
            let dx = if nudge.is_multiple_of(2) { 0.01 } else { -0.01 };
            session.set_light(base.with_center(base.center() + Vec3::new(dx, 0.0, 0.0)));
        }
        let t = Instant::now();
        let job = FrameJob {
            targets,
            request: req,
            view: Some(view),
            render: true,
            probes: Vec::new(),
        };
        session.submit(ctx, &mut [job]).ok()?;
        map_now(&ctx.device).ok()?;
        let wall = ms_since(t);
        let gpu = session.poll_timings(ctx).as_deref().and_then(gpu_total);
        Some((wall, gpu))
    };
    let mut floor = Floor::new(ctx);
    let timer = PassTimer::new(ctx);
    let mut timer = timer;
    let mut floor_frame = |session: &Session| -> Option<f64> {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("floor"),
            });
        {
            let mut rec = Recorder::new(&mut encoder, timer.as_ref());
            floor.record(
                ctx,
                &mut rec,
                session.scene(),
                session.surfaces(),
                (size, size),
            );
        }
        let t = timer.as_mut()?;
        t.finish(&mut encoder, 0);
        ctx.queue.submit([encoder.finish()]);
        t.request_maps();
        gpu_total(&t.wait(ctx).ok()?)
    };
    let (mut still, mut moving, mut readback, mut floors) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let readback_req = FrameRequest {
        read_dbuffer: true,
        ..req
    };
    session.set_light(base);
    for round in 0..config.warmup + config.frames {
        let timed = round >= config.warmup;
        let s = lab(&mut session, &mut targets, false);
        let m = lab(&mut session, &mut targets, true);
        session.set_light(base);
        // The readback path with the D-buffer cached, as the lab had it with a still light.
        let _ = session.frame(ctx, &readback_req);
        let t = Instant::now();
        let r = session
            .frame(ctx, &readback_req)
            .ok()
            .map(|f| (ms_since(t), gpu_total(&f.gpu_ms)));
        let f = floor_frame(&session);
        if timed {
            still.extend(s);
            moving.extend(m);
            readback.extend(r);
            floors.extend(f);
        }
    }
    let display = |v: &[(f64, Option<f64>)]| Display {
        wall_ms: Stat::of(&v.iter().map(|x| x.0).collect::<Vec<_>>()).unwrap_or_default(),
        gpu_ms: Stat::of(&v.iter().filter_map(|x| x.1).collect::<Vec<_>>()),
    };
    DisplayRun {
        scene: scene.name.clone(),
        size,
        floor_gpu_ms: Stat::of(&floors),
        lab_still: display(&still),
        lab_moving: display(&moving),
        readback: display(&readback),
    }
}

/// The D-buffer's steady frame with the geometry cached, then with the geometry invalidated before
/// every frame (`Session::invalidate_geometry`: what a light dragged every frame costs).
fn coherence(ctx: &GpuContext, scene: &Scene, config: &Config, size: u32) -> Coherence {
    let mut session = Session::new(ctx, scene.clone());
    let req = request(config, size, &Case::for_method(Method::DBUFFER));
    let frames = config.frames.max(3);
    // Cached and rebuilt frames alternate, so both see the same machine (a shared CPU adapter
    // drifts more over a run than the geometry stage costs).
    let (mut cached_wall, mut cached_gpu) = (Vec::new(), Vec::new());
    let (mut rebuilt_wall, mut rebuilt_gpu, mut geometry) = (Vec::new(), Vec::new(), Vec::new());
    let mut rebuilds = 0;
    for i in 0..2 * (config.warmup + frames) {
        let rebuild = i % 2 == 1;
        let (before, _) = session.geometry_builds(Method::DBUFFER);
        if rebuild {
            session.invalidate_geometry();
        } else {
            session.invalidate_light_maps();
        }
        let t = Instant::now();
        let Ok(frame) = session.frame(ctx, &req) else {
            continue;
        };
        let ms = ms_since(t);
        let (after, geometry_ms) = session.geometry_builds(Method::DBUFFER);
        if i < 2 * config.warmup {
            continue;
        }
        let gpu = gpu_total(&frame.gpu_ms);
        if rebuild {
            rebuilds += after - before;
            rebuilt_wall.push(ms);
            rebuilt_gpu.extend(gpu);
            geometry.push(geometry_ms);
        } else {
            cached_wall.push(ms);
            cached_gpu.extend(gpu);
        }
    }
    Coherence {
        scene: scene.name.clone(),
        size,
        rebuild_by: "Session::invalidate_geometry() before every frame".into(),
        cached_wall_ms: Stat::of(&cached_wall).unwrap_or_default(),
        rebuilt_wall_ms: Stat::of(&rebuilt_wall).unwrap_or_default(),
        cached_gpu_ms: Stat::of(&cached_gpu),
        rebuilt_gpu_ms: Stat::of(&rebuilt_gpu),
        rebuilt_geometry_ms: Stat::of(&geometry),
        rebuilds,
        frames,
    }
}

/// A UV sphere of about `triangles` triangles (4·n², n = √(t/4) rounded) under a tilted light,
/// alone in a scene.
pub fn scaling_scene(triangles: u32) -> Scene {
    let n = ((f64::from(triangles) / 4.0).sqrt().round() as u32).max(2);
    let mesh = shapes::sphere(2 * n, n + 1)
        .transformed(&Affine3A::from_translation(Vec3::new(0.0, 1.5, 0.0)));
    Scene {
        name: format!("sphere-{}", mesh.triangles.len()),
        camera: Camera {
            eye: Vec3::new(0.0, 3.0, 6.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            fov_y_deg: 45.0,
        },
        light: AreaLight {
            center: Vec3::new(0.3, 4.0, -0.2),
            normal: Vec3::new(0.1, -1.0, 0.05).normalize(),
            radius: 0.6,
            intensity: 1.0,
            outline: Outline::Disk,
        }
        .into(),
        objects: vec![Object {
            name: "sphere".into(),
            mesh,
            casts_shadow: true,
        }],
    }
}

fn scaling_point(ctx: &GpuContext, triangles: u32, runs: usize) -> ScalingPoint {
    let scene = scaling_scene(triangles);
    let t = Instant::now();
    let prepared = PreparedCasters::new(&scene);
    let prepare_ms = ms_since(t);
    let params = VolumeParams::for_scene(&scene);
    let mut samples = Vec::new();
    let mut volume_triangles = 0;
    for light in std::iter::repeat_n(scene.light.as_area(), runs.max(1)).flatten() {
        let t = Instant::now();
        let g = prepared.build(light, &params);
        samples.push(ms_since(t));
        volume_triangles = g.stats.umbra_triangles + g.stats.penumbra_triangles;
        drop(std::hint::black_box(g));
    }
    // Both paths on this adapter, a light move until the light pass could draw; the GPU path
    // only where the adapter runs it.
    use crate::render::methods::dbuffer::{gpu_geometry_runs, light_move_ms, GeometryPath};
    let moved = |path| {
        light_move_ms(ctx, &scene, path, runs)
            .ok()
            .and_then(|ms| Stat::of(&ms))
    };
    ScalingPoint {
        triangles: scene.caster_triangle_count(),
        prepare_ms,
        build_ms: Stat::of(&samples).unwrap_or_default(),
        volume_triangles,
        cpu_move_ms: moved(GeometryPath::Cpu),
        gpu_move_ms: gpu_geometry_runs(&ctx.caps)
            .then(|| moved(GeometryPath::Gpu))
            .flatten(),
    }
}

/// Shadow rays per second of the reference: one ray per hit pixel per 1-spp step of
/// `Session::advance_reference` (surfaces facing away from the light may cast none, so this is a
/// lower bound), the median over the runs.
fn reference_throughput(runs: &[Run]) -> Option<f64> {
    let rates: Vec<f64> = runs
        .iter()
        .filter(|r| r.method == truth::SOFT.name())
        .filter_map(|r| r.timing.as_ref())
        .filter_map(|t| Some((t.hit_pixels, t.rays_ms?.median)))
        .filter(|&(px, ms)| ms > 0.0 && px > 0)
        .map(|(px, ms)| px as f64 / (ms * 1e-3))
        .collect();
    Stat::of(&rates).map(|s| s.median)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::SCALING_TRIANGLES;

    #[test]
    fn scaling_scene_sizes() {
        for t in SCALING_TRIANGLES {
            let s = scaling_scene(t);
            assert_eq!(s.caster_triangle_count(), t as usize);
        }
    }
}

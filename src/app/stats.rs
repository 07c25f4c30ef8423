//! Timings the lab shows: per render, the CPU time to record and submit it (with or without a
//! geometry rebuild) and GPU time per pass from timestamp queries (a frame later); per window
//! frame, the CPU time it took, the frame rate, and the bytes read back from the GPU.

use std::collections::VecDeque;

use eframe::egui;

/// Samples kept for the plots and medians.
const KEEP: usize = 240;

#[derive(Clone, Debug, Default)]
pub struct RenderTiming {
    /// CPU wall milliseconds of recording and submitting the frame (the GPU runs on).
    pub wall_ms: f64,
    /// CPU milliseconds of the geometry stage, when this render rebuilt it.
    pub geometry_ms: Option<f64>,
}

#[derive(Default)]
pub struct Stats {
    /// Window frame intervals, seconds (idle gaps included: the lab draws only on change).
    pub frame_dt: VecDeque<f32>,
    /// CPU milliseconds of each window frame (eframe's measure: the app's update and its
    /// render), which unlike the interval leaves out the idle time between frames.
    pub frame_cpu_ms: VecDeque<f32>,
    pub renders: VecDeque<RenderTiming>,
    /// GPU milliseconds per pass of the frames whose timings came back.
    pub gpu: VecDeque<Vec<(String, f64)>>,
    /// Bytes read back from the GPU, per window frame that submitted work.
    pub read_bytes: VecDeque<u64>,
    pub renders_total: u64,
    /// Window frames run.
    pub window_frames: u64,
    last_frame: Option<f64>,
}

impl Stats {
    /// Called at the start of every window frame with eframe's CPU time of the previous one.
    pub fn ui_frame(&mut self, ctx: &egui::Context, previous_cpu_s: Option<f32>) {
        self.window_frames += 1;
        if let Some(s) = previous_cpu_s.filter(|s| s.is_finite() && *s >= 0.0) {
            push(&mut self.frame_cpu_ms, s * 1000.0);
        }
        let now = ctx.input(|i| i.time);
        if let Some(last) = self.last_frame {
            let dt = (now - last) as f32;
            if dt > 0.0 && dt.is_finite() {
                push(&mut self.frame_dt, dt);
            }
        }
        self.last_frame = Some(now);
    }

    /// A window frame submitted `renders` new frames (and maybe only views or probes), in
    /// `wall_ms` of CPU, rebuilding the geometry in `geometry_ms`, reading back `bytes`.
    pub fn submitted(
        &mut self,
        renders: usize,
        wall_ms: f64,
        geometry_ms: Option<f64>,
        bytes: u64,
    ) {
        if renders > 0 {
            self.renders_total += renders as u64;
            push(
                &mut self.renders,
                RenderTiming {
                    wall_ms,
                    geometry_ms,
                },
            );
        }
        if renders > 0 || bytes > 0 {
            push(&mut self.read_bytes, bytes);
        }
    }

    /// Pass timings that came back from the GPU.
    pub fn gpu(&mut self, passes: Vec<(String, f64)>) {
        push(&mut self.gpu, passes);
    }

    /// Median render wall time of the renders with (`true`) or without a geometry rebuild.
    pub fn median_wall_ms(&self, rebuilt: bool) -> Option<f64> {
        median(
            self.renders
                .iter()
                .filter(|r| r.geometry_ms.is_some() == rebuilt)
                .map(|r| r.wall_ms)
                .collect(),
        )
    }

    /// Median CPU milliseconds of the geometry stage over the renders that rebuilt it.
    pub fn median_geometry_ms(&self) -> Option<f64> {
        median(self.renders.iter().filter_map(|r| r.geometry_ms).collect())
    }

    /// Median GPU milliseconds per pass over the kept frames, every pass any of them ran (a
    /// frame that only redraws the view still lists the camera pass of the last render), in
    /// the order they first came.
    pub fn median_gpu_ms(&self) -> Vec<(String, f64)> {
        let mut passes: Vec<&str> = Vec::new();
        for (pass, _) in self.gpu.iter().flatten() {
            if !passes.contains(&pass.as_str()) {
                passes.push(pass);
            }
        }
        passes
            .into_iter()
            .filter_map(|pass| {
                let values = self
                    .gpu
                    .iter()
                    .flat_map(|r| r.iter().filter(|(p, _)| p == pass).map(|(_, ms)| *ms))
                    .collect();
                median(values).map(|m| (pass.to_string(), m))
            })
            .collect()
    }

    /// Bytes read back by the last window frame that submitted work, and the most over the
    /// kept ones.
    pub fn read_bytes(&self) -> Option<(u64, u64)> {
        let last = *self.read_bytes.back()?;
        Some((last, self.read_bytes.iter().copied().max().unwrap_or(last)))
    }

    /// Window frames per second over the last second of frames.
    pub fn fps(&self) -> Option<f32> {
        if *self.frame_dt.back()? > 1.0 {
            return None; // idle: nothing changed, nothing drawn
        }
        let mut total = 0.0;
        let mut n = 0;
        for dt in self.frame_dt.iter().rev() {
            if total >= 1.0 {
                break;
            }
            total += dt;
            n += 1;
        }
        (n > 0 && total > 0.0).then(|| n as f32 / total)
    }
}

fn push<T>(q: &mut VecDeque<T>, v: T) {
    if q.len() == KEEP {
        q.pop_front();
    }
    q.push_back(v);
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_split_by_geometry_rebuilds() {
        let mut s = Stats::default();
        s.submitted(1, 10.0, Some(7.0), 64);
        for ms in [2.0, 3.0, 4.0] {
            s.submitted(1, ms, None, 32);
            s.gpu(vec![("shadow_map".into(), ms / 2.0)]);
        }
        s.submitted(0, 0.0, None, 0);
        assert_eq!(s.median_wall_ms(true), Some(10.0));
        assert_eq!(s.median_geometry_ms(), Some(7.0));
        assert_eq!(s.median_wall_ms(false), Some(3.0));
        assert_eq!(s.median_gpu_ms(), vec![("shadow_map".to_string(), 1.5)]);
        // A frame that only redraws the view keeps the last render's passes listed.
        s.gpu(vec![("view".into(), 0.5)]);
        assert_eq!(
            s.median_gpu_ms(),
            vec![("shadow_map".to_string(), 1.5), ("view".to_string(), 0.5)]
        );
        assert_eq!(s.renders_total, 4);
        assert_eq!(
            s.read_bytes(),
            Some((32, 64)),
            "idle frames are not counted"
        );
        for _ in 0..KEEP {
            s.submitted(1, 1.0, None, 0);
        }
        assert_eq!(s.renders.len(), KEEP);
    }

    #[test]
    fn frame_cpu_time_leaves_out_idle_gaps_and_bad_readings() {
        let ctx = egui::Context::default();
        let mut s = Stats::default();
        for cpu in [None, Some(0.004), Some(f32::NAN), Some(-1.0), Some(0.25)] {
            s.ui_frame(&ctx, cpu);
        }
        assert_eq!(s.frame_cpu_ms, [4.0, 250.0]);
    }

    #[test]
    fn fps_over_the_last_second() {
        let mut s = Stats::default();
        for _ in 0..30 {
            s.frame_dt.push_back(0.02);
        }
        let fps = s.fps().unwrap();
        assert!((fps - 50.0).abs() < 2.0, "{fps}");
    }
}

//! The FLIP view's map: the main side's frame against the soft truth's image of the same view,
//! both read back, FLIP computed on a thread of its own and uploaded when it arrives.

use super::*;
use crate::geometry::flip;

/// A FLIP map, as the thread that computed it hands it over.
pub(super) struct FlipMap {
    map: Vec<f32>,
    thread: ThreadId,
}

/// A FLIP map being computed off the caller's thread.
pub(super) struct FlipJob {
    /// The frame and reference snapshot it is of.
    wanted: (RenderKey, u64),
    /// The reference it is against (the view shows it while that reference is current).
    key: ReferenceKey,
    rx: Receiver<Result<FlipMap, String>>,
}

#[derive(Default)]
pub(super) struct FlipState {
    /// The reference's shaded image (never shown itself).
    pub(super) targets: FrameTargets,
    /// The frame and reference snapshot the map on the GPU was made for.
    pub(super) made: Option<(RenderKey, u64)>,
    /// Bumped for every map handed to the GPU (the FLIP view draws again).
    pub(super) serial: u64,
    pub(super) job: Option<FlipJob>,
    /// The thread the last map was computed on.
    pub(super) thread: Option<ThreadId>,
}

impl ViewSession {
    /// Start a FLIP map of the main side's frame against the soft truth's image of the same
    /// view, once per new frame or reference snapshot: the reference's camera pass into targets
    /// of its own, both images read back here, FLIP on a thread of its own.
    pub(super) fn want_flip(&mut self, reference_serial: u64, update: &mut Update) {
        let Some(key) = self.sides[0].key else {
            return;
        };
        let wanted = (key, reference_serial);
        if self.flip.made == Some(wanted)
            || self.flip.job.as_ref().is_some_and(|j| j.wanted == wanted)
        {
            return;
        }
        match self.start_flip(&key.request, wanted) {
            Ok(job) => self.flip.job = Some(job),
            Err(e) => update.errors.push(format!("FLIP: {e}")),
        }
    }

    pub(super) fn start_flip(
        &mut self,
        request: &FrameRequest,
        wanted: (RenderKey, u64),
    ) -> Result<FlipJob, RenderError> {
        let reference = FrameRequest {
            method: truth::SOFT,
            ..*request
        };
        self.session.submit(
            &self.ctx,
            &mut [FrameJob {
                targets: &mut self.flip.targets,
                request: reference,
                view: None,
                render: true,
                probes: Vec::new(),
            }],
        )?;
        let truth = self.session.read(&self.ctx, &mut self.flip.targets, None)?;
        let shown = self.read(0, None)?;
        let key = self.session.reference_key(&reference);
        let (tx, rx) = mpsc::channel();
        std::thread::Builder::new()
            .name("dbuffer-flip".into())
            .spawn(move || {
                let rgb = |f: &Frame| -> Vec<[u8; 3]> {
                    f.color.iter().map(|c| [c[0], c[1], c[2]]).collect()
                };
                let map = flip::ldr_flip(
                    &rgb(&truth),
                    &rgb(&shown),
                    shown.width,
                    shown.height,
                    flip::DEFAULT_PPD,
                )
                .map(|map| FlipMap {
                    map,
                    thread: std::thread::current().id(),
                })
                .map_err(|e| e.to_string());
                let _ = tx.send(map);
            })
            .map_err(|e| RenderError::Request(format!("no thread for FLIP: {e}")))?;
        Ok(FlipJob { wanted, key, rx })
    }

    /// Hand the GPU the FLIP map computed, if it has arrived (`wait`: once it has).
    pub(super) fn take_flip(&mut self, wait: bool, update: &mut Update) {
        let Some(job) = self.flip.job.as_ref() else {
            return;
        };
        let arrived = if wait {
            job.rx.recv().map_err(|_| TryRecvError::Disconnected)
        } else {
            job.rx.try_recv()
        };
        let result = match arrived {
            Ok(result) => result,
            Err(TryRecvError::Empty) => {
                update.repaint.after(Duration::from_millis(15));
                return;
            }
            Err(TryRecvError::Disconnected) => Err("its thread ended without a map".into()),
        };
        let Some(job) = self.flip.job.take() else {
            return;
        };
        let uploaded = result.and_then(|m| {
            self.session
                .set_flip(&self.ctx, job.key, &m.map)
                .map_err(|e| e.to_string())
                .map(|()| m.thread)
        });
        match uploaded {
            Ok(thread) => {
                self.flip.made = Some(job.wanted);
                self.flip.serial += 1;
                self.flip.thread = Some(thread);
                update.repaint.now = true;
            }
            Err(e) => update.errors.push(format!("FLIP: {e}")),
        }
    }
}

//! The hidden `--resize-cycle` test: programmatic resizes (1×1 among them, half of them under a frame in flight)
//! and a simulated minimize, one at a time.

use super::*;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Step {
    Size(u32, u32),
    Minimize,
}

/// The hidden `--resize-cycle` test: programmatic resizes, one at a time, each held until a frame has been
/// presented at the new size (or 60 frames went by). Every other resize is requested between the acquire and the
/// present of a frame, so that the window changes size under a frame in flight.
pub(super) struct ResizeCycle {
    pub(super) steps: Vec<Step>,
    pub(super) next: usize,
    pub(super) current: Option<(Step, u64)>,
    /// A resize to request right after the next acquire.
    pub(super) mid_frame: Option<(u32, u32)>,
}

impl ResizeCycle {
    pub(super) fn new(k: u32, initial: (u32, u32)) -> Self {
        const PATTERN: [(u32, u32); 10] =
            [(1, 1), (320, 240), (1, 1), (57, 31), (1, 200), (200, 1), (640, 480), (1, 1), (97, 61), (333, 77)];
        // Every step changes the size (so that each one is seen), and the last one restores the initial size.
        let mut steps = Vec::new();
        let mut prev = initial;
        for &size in PATTERN.iter().cycle() {
            if steps.len() + 1 >= k as usize {
                break;
            }
            if size != prev {
                steps.push(Step::Size(size.0, size.1));
                prev = size;
            }
        }
        if k > 0 && prev != initial {
            steps.push(Step::Size(initial.0, initial.1));
        }
        if k >= 4 {
            steps.insert(steps.len() / 2, Step::Minimize);
        }
        ResizeCycle { steps, next: 0, current: None, mid_frame: None }
    }

    pub(super) fn finished(&self) -> bool {
        self.next >= self.steps.len() && self.current.is_none()
    }
}

impl Viewer {
    /// Testing (`--resize-cycle`): issue the next programmatic resize once the current one has been presented.
    pub(super) fn resize_tick(&mut self) {
        let presented = self.counters.presented;
        let extent = self.swapchain.as_ref().map(|s| (s.extent.width, s.extent.height));
        let minimizing = self.simulated_minimize_until.is_some();
        let Some(rc) = self.resize.as_mut() else {
            return;
        };
        let done = match rc.current {
            None => true,
            Some((Step::Size(w, h), at)) => (extent == Some((w, h)) && presented > at) || presented >= at + 60,
            Some((Step::Minimize, at)) => !minimizing && presented > at,
        };
        if !done {
            return;
        }
        rc.current = None;
        let Some(&step) = rc.steps.get(rc.next) else {
            return;
        };
        rc.next += 1;
        rc.current = Some((step, presented));
        match step {
            Step::Size(w, h) if rc.next % 2 == 0 => rc.mid_frame = Some((w, h)),
            Step::Size(w, h) => self.request_size(w, h),
            Step::Minimize => {
                self.counters.simulated_minimizes += 1;
                self.simulated_minimize_until = Some(Instant::now() + Duration::from_millis(200));
            }
        }
    }

    pub(super) fn request_size(&mut self, w: u32, h: u32) {
        self.counters.resize_requests += 1;
        if let Some(size) = self.window.request_inner_size(PhysicalSize::new(w, h)) {
            // Applied at once (no Resized event on some platforms).
            if size != self.last_size {
                self.counters.resizes_seen += 1;
                self.last_size = size;
            }
            self.dirty = true;
        }
    }
}

//! The UI's own cost per frame (its logic and panels, not the render thread's) for the status bar and
//! the editor's measurements, and `--log-times`: each change's times printed once it converged, with
//! the frames it took and the latency of a dab.

use crate::live::LiveDriver;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// Frames less than this apart ran back to back (a frame was asked for while one was drawn).
const BACK_TO_BACK_MS: f32 = 250.0;

/// UI frame costs kept for the status bar and measurements.
const FRAME_COSTS_KEPT: usize = 256;

#[derive(Default)]
pub struct FrameTiming {
    /// Smoothed cost of a frame's work, ms.
    smoothed_ms: f32,
    /// The last frames' costs, ms.
    costs: VecDeque<f32>,
    /// The time from one frame's start to the next's, ms: where frames run back to back (continuous
    /// input) this is the whole frame, egui's painting and presenting included.
    intervals: VecDeque<f32>,
    last_start: Option<Instant>,
    /// When this frame's work started.
    started: Option<Instant>,
    /// A dab not yet seen on screen: when its frame began, and the driver's restart it made.
    pending_dab: Option<(Instant, u64)>,
    /// The driver's restart and convergence time last logged, and the UI frames since.
    logged: Option<(u64, Duration)>,
    frames_since_change: usize,
}

fn push_bounded(v: &mut VecDeque<f32>, x: f32) {
    if v.len() == FRAME_COSTS_KEPT {
        v.pop_front();
    }
    v.push_back(x);
}

impl FrameTiming {
    /// A frame's work starts.
    pub fn start(&mut self) {
        let now = Instant::now();
        if let Some(last) = self.last_start {
            push_bounded(&mut self.intervals, (now - last).as_secs_f32() * 1e3);
        }
        self.last_start = Some(now);
        self.started = Some(now);
    }

    /// The frame's work ends: its cost goes to the smoothed figure and the recent costs.
    pub fn end(&mut self) {
        let Some(t) = self.started.take() else {
            return;
        };
        let ms = t.elapsed().as_secs_f32() * 1e3;
        self.smoothed_ms = if self.smoothed_ms == 0.0 {
            ms
        } else {
            0.9 * self.smoothed_ms + 0.1 * ms
        };
        push_bounded(&mut self.costs, ms);
    }

    pub fn smoothed_ms(&self) -> f32 {
        self.smoothed_ms
    }

    /// Frames whose cost was measured (at most the number kept).
    pub fn frames_measured(&self) -> usize {
        self.costs.len()
    }

    /// A dab painted: its latency counts from this frame's start until the driver shows restart
    /// `restarts` (one at a time).
    pub fn dab_painted(&mut self, restarts: u64) {
        if self.pending_dab.is_none() {
            self.pending_dab = Some((self.started.unwrap_or_else(Instant::now), restarts));
        }
    }

    /// Prints the times of a change that has converged (once per change).
    pub fn log_times(&mut self, d: &LiveDriver) {
        if let Some((t, r)) = self.pending_dab
            && d.restarts() >= r
            && d.first_image_in().is_some()
        {
            self.pending_dab = None;
            eprintln!(
                "dab: shown {:.1} ms after the frame that took it",
                t.elapsed().as_secs_f64() * 1e3
            );
        }
        let done = d.clock.progress.is_some_and(|p| p.converged) && !d.tables_pending();
        let (restarts, first, sharp) = (d.restarts(), d.first_image_in(), d.clock.full_image_in);
        let converged = d.clock.converged_in.filter(|_| done);
        self.frames_since_change += 1;
        let Some(converged) = converged else {
            return;
        };
        if self
            .logged
            .is_some_and(|(r, c)| r == restarts && c == converged)
        {
            return;
        }
        self.logged = Some((restarts, converged));
        let n = self.frames_since_change;
        let p95 = |v: &VecDeque<f32>, keep: &dyn Fn(f32) -> bool| {
            let mut v: Vec<f32> = v
                .iter()
                .rev()
                .take(n)
                .copied()
                .filter(|x| keep(*x))
                .collect();
            v.sort_by(f32::total_cmp);
            let q = v
                .get(((v.len().max(1) - 1) as f32 * 0.95).round() as usize)
                .copied();
            (q.unwrap_or(0.0), v.len())
        };
        let (cost, _) = p95(&self.costs, &|_| true);
        let (whole, back_to_back) = p95(&self.intervals, &|x| x < BACK_TO_BACK_MS);
        let s = |t: Option<Duration>| t.map_or(-1.0, |t| t.as_secs_f64());
        eprintln!(
            "times: first {:.3} s, sharp {:.3} s, converged {:.3} s; UI frames {n}, own work p95 \
             {cost:.1} ms; {back_to_back} frames back to back, whole frame p95 {whole:.1} ms",
            s(first),
            s(sharp),
            converged.as_secs_f64(),
        );
        self.frames_since_change = 0;
    }
}

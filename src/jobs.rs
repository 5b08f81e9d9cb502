//! Background jobs (loading, fitting, table builds, autosave writes): a worker thread that sends its
//! result back and calls a wake function; polled once a frame by its owner, never waited on. It knows
//! no UI toolkit (the editor's wake function asks egui for a repaint), so the session's autosave and
//! the live driver use it as the editor does.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::Instant;

/// What a finished job calls to have its owner poll it (the editor: egui's `request_repaint`).
pub type Wake = Arc<dyn Fn() + Send + Sync>;

pub struct Job<T> {
    pub label: String,
    pub started: Instant,
    rx: Receiver<T>,
    cancel: Arc<AtomicBool>,
    finished: bool,
}

impl<T: Send + 'static> Job<T> {
    /// Runs `work` on a new thread; `wake` is called when it is done (egui's `request_repaint`).
    pub fn spawn(
        label: impl Into<String>,
        wake: impl Fn() + Send + 'static,
        work: impl FnOnce(&AtomicBool) -> T + Send + 'static,
    ) -> Self {
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = cancel.clone();
        std::thread::spawn(move || {
            let out = work(&flag);
            let _ = tx.send(out);
            wake();
        });
        Self {
            label: label.into(),
            started: Instant::now(),
            rx,
            cancel,
            finished: false,
        }
    }

    /// The result once the worker is done (once); a worker that died without one (a panic) is an
    /// error, so no caller waits for it forever.
    pub fn poll(&mut self) -> Option<Result<T, String>> {
        if self.finished {
            return None;
        }
        match self.rx.try_recv() {
            Ok(v) => {
                self.finished = true;
                Some(Ok(v))
            }
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => {
                self.finished = true;
                Some(Err(format!(
                    "{}: the worker stopped without a result",
                    self.label
                )))
            }
        }
    }

    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Asks the worker to stop (it checks the flag where it can).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_job_delivers_its_result_once() {
        let mut job = Job::spawn("add", || {}, |_| 2 + 2);
        let t = Instant::now();
        let v = loop {
            if let Some(v) = job.poll() {
                break v.unwrap();
            }
            assert!(t.elapsed().as_secs() < 10);
            std::thread::yield_now();
        };
        assert_eq!(v, 4);
        assert!(job.poll().is_none() && job.is_finished());
    }

    #[test]
    fn a_worker_that_panics_is_an_error_not_a_hang() {
        let mut job: Job<u32> = Job::spawn("doomed", || {}, |_| panic!("on purpose"));
        let t = Instant::now();
        let r = loop {
            if let Some(r) = job.poll() {
                break r;
            }
            assert!(t.elapsed().as_secs() < 10);
            std::thread::yield_now();
        };
        assert!(r.unwrap_err().contains("doomed"));
    }
}

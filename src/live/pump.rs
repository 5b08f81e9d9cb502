//! The render thread: it owns the pace of refinement. While work remains it submits the driver's next
//! unit as soon as the last one finished (it waits on the GPU, never on a UI frame), and it wakes the
//! UI only when there is something new to draw. The UI thread locks the driver to tell it what
//! changed ([`LiveDriver::sync`], dabs) and kicks the thread; it never waits for a unit.
//!
//! Why a thread and not one unit per UI frame: on a software GPU a UI frame costs ~100 ms, so units
//! paced by frames ran one per ~130 ms whatever their own cost (a 5 s frame took over a minute).

use super::driver::LiveDriver;
use super::settings::StepOutcome;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How the thread and its owner meet.
struct Shared {
    driver: Mutex<LiveDriver>,
    control: Mutex<Control>,
    kick: Condvar,
    wake: Box<dyn Fn() + Send + Sync>,
    /// The least time between two wakes of the UI for images that only refine the one shown.
    wake_interval: Duration,
}

#[derive(Default)]
struct Control {
    kicked: bool,
    stop: bool,
}

/// A [`LiveDriver`] refined on its own thread.
pub struct LiveHandle {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

/// The longest a wait on the GPU lasts before the thread looks at its controls again.
const GPU_WAIT: Duration = Duration::from_millis(100);
/// The tick while work remains but nothing is on the GPU (tables or a picker built on a worker).
const IDLE_TICK: Duration = Duration::from_millis(4);

impl LiveHandle {
    /// Starts the render thread for `driver`; `wake` asks the UI for a frame (egui's
    /// `request_repaint`; a no-op for benchmarks and tests, which read the driver).
    pub fn start(driver: LiveDriver, wake: impl Fn() + Send + Sync + 'static) -> Self {
        let wake_interval = driver.wake_interval();
        let shared = Arc::new(Shared {
            driver: Mutex::new(driver),
            control: Mutex::new(Control {
                kicked: true,
                stop: false,
            }),
            kick: Condvar::new(),
            wake: Box::new(wake),
            wake_interval,
        });
        let thread = {
            let shared = shared.clone();
            std::thread::Builder::new()
                .name("strandlight render".into())
                .spawn(move || run(&shared))
                .ok()
        };
        Self { shared, thread }
    }

    /// The driver, for the caller's changes and reads. Hold it briefly: the render thread takes it
    /// between units.
    pub fn lock(&self) -> MutexGuard<'_, LiveDriver> {
        // A panic in a step is caught on the render thread (`LiveDriver::step_panicked`): the
        // lock is poisoned only by a panic elsewhere, which leaves the driver as that step did.
        self.shared
            .driver
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// Tells the render thread that something may have changed (it looks at once).
    pub fn kick(&self) {
        self.shared.signal(|c| c.kicked = true);
    }

    /// Whether the render thread is running (it stops only when dropped, or if it panicked).
    pub fn running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Waits until the driver has nothing left to do (converged, tables in, picker built) or
    /// `timeout` passes; true when it is done. For benchmarks and tests: the UI never waits.
    pub fn wait_idle(&self, timeout: Duration) -> bool {
        let end = Instant::now() + timeout;
        loop {
            if !self.lock().working() {
                return true;
            }
            if Instant::now() >= end || !self.running() {
                return false;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Waits until `done` holds for the driver or `timeout` passes (checked every millisecond).
    pub fn wait_for(&self, timeout: Duration, mut done: impl FnMut(&LiveDriver) -> bool) -> bool {
        let end = Instant::now() + timeout;
        loop {
            if done(&self.lock()) {
                return true;
            }
            if Instant::now() >= end || !self.running() {
                return false;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

impl Drop for LiveHandle {
    fn drop(&mut self) {
        self.shared.signal(|c| c.stop = true);
        // Bounded: the thread waits on the GPU at most GPU_WAIT at a time.
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Shared {
    /// Changes the thread's controls and wakes it to read them.
    fn signal(&self, change: impl FnOnce(&mut Control)) {
        let mut c = self.control.lock().unwrap_or_else(PoisonError::into_inner);
        change(&mut c);
        self.kick.notify_one();
    }
}

/// The render thread's loop.
fn run(shared: &Shared) {
    let mut working = true;
    let mut owed = false;
    let mut last_wake: Option<Instant> = None;
    loop {
        {
            let mut c = shared
                .control
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            while !c.stop && !c.kicked && !working {
                c = shared.kick.wait(c).unwrap_or_else(PoisonError::into_inner);
            }
            if c.stop {
                return;
            }
            c.kicked = false;
        }
        let (outcome, device) = {
            let mut d = shared.driver.lock().unwrap_or_else(PoisonError::into_inner);
            // A panic in a step (a bug, or no thread to be had for a job) is reported, not lost
            // with the thread: the driver stops stepping until something changes.
            let step = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| d.pump_step()));
            let outcome = step.unwrap_or_else(|panic| {
                let why = panic
                    .downcast_ref::<String>()
                    .map(String::as_str)
                    .or_else(|| panic.downcast_ref::<&str>().copied())
                    .unwrap_or("unknown");
                d.step_panicked(why);
                StepOutcome {
                    news: true,
                    urgent: true,
                    ..StepOutcome::idle()
                }
            });
            (outcome, d.ctx.device.clone())
        };
        // The UI is woken without the driver's lock held (its frame takes that lock), also when
        // the work ends without a new image (a table build that died, a picker built).
        owed |= outcome.news || (working && !outcome.working);
        let due = last_wake.is_none_or(|t| t.elapsed() >= shared.wake_interval);
        if owed && (outcome.urgent || due || !outcome.working) {
            owed = false;
            last_wake = Some(Instant::now());
            (shared.wake)();
        }
        working = outcome.working;
        if outcome.gpu_busy {
            // A timeout only means the unit runs longer; the next step notices it.
            let _ = device.poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(GPU_WAIT),
            });
        } else if working {
            let c = shared
                .control
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            if !c.kicked && !c.stop {
                let _ = shared.kick.wait_timeout(c, IDLE_TICK);
            }
        }
    }
}

//! The GPU device's health: wgpu's device-lost callback and uncaptured errors, caught in flags the
//! frame loop reads (wgpu's default handler panics: a resource made on a device that is being lost,
//! say, must not take the session down), and the restart after a loss. eframe owns the device and
//! cannot replace it (egui draws with it too): a new editor on a new device takes the session over.

use crate::gpu::GpuContext;
use crate::jobs::Wake;
use std::ffi::OsString;
use std::path::Path;
use std::sync::{Arc, Mutex};

type Flag = Arc<Mutex<Option<String>>>;

/// What the device reported since the last frame.
pub enum DeviceEvent {
    /// Lost (the reason and message).
    Lost(String),
    /// The first GPU validation error (shown once, not once a frame).
    Error(String),
}

#[derive(Default)]
pub struct DeviceWatch {
    lost: Flag,
    error: Flag,
    error_shown: bool,
    /// After a loss: the arguments of the editor that takes over (`edit --recover FILE`).
    relaunch: Option<Vec<OsString>>,
    /// This editor is closing for its replacement: the recovery file stays as it is.
    relaunching: bool,
}

/// How a restart after a loss went.
pub enum Restart {
    /// A new editor was started; this one closes.
    Started,
    /// Not started: this editor was itself such a restart and lost its device at once (no loop),
    /// or it was not asked to.
    NotTried,
    Failed(std::io::Error),
}

impl DeviceWatch {
    /// Watches `gpu`'s device; `wake` asks for a frame to report it.
    pub fn watch(gpu: &GpuContext, wake: Wake) -> Self {
        let w = Self::default();
        let (flag, wake_lost) = (w.lost.clone(), wake.clone());
        gpu.device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut f) = flag.lock() {
                *f = Some(format!("{reason:?}: {message}"));
            }
            wake_lost();
        });
        let first = w.error.clone();
        gpu.device
            .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                if let Ok(mut f) = first.lock()
                    && f.is_none()
                {
                    *f = Some(e.to_string());
                }
                wake();
            }));
        w
    }

    /// Once a frame: a loss, or else the first error not shown yet.
    pub fn poll(&mut self) -> Option<DeviceEvent> {
        let lost = self.lost.lock().ok().and_then(|mut f| f.take());
        let error = self.error.lock().ok().and_then(|mut f| f.take());
        if let Some(why) = lost {
            return Some(DeviceEvent::Lost(why));
        }
        let e = error.filter(|_| !self.error_shown)?;
        self.error_shown = true;
        Some(DeviceEvent::Error(e))
    }

    /// The arguments of the editor that takes over after a loss.
    pub fn relaunch(&self) -> Option<&[OsString]> {
        self.relaunch.as_deref()
    }

    /// Closing for a replacement: the recovery file is the replacement's now.
    pub fn relaunching(&self) -> bool {
        self.relaunching
    }

    /// After a loss with the session kept in `recovery`: starts `edit --recover` on it when `start`
    /// (a restart that loses its device again within a minute passes false: no loop).
    pub fn restart(&mut self, recovery: &Path, start: bool) -> Restart {
        let args: Vec<OsString> = vec!["edit".into(), "--recover".into(), recovery.into()];
        self.relaunch = Some(args.clone());
        if !start {
            return Restart::NotTried;
        }
        let spawned = std::env::current_exe()
            .and_then(|exe| std::process::Command::new(exe).args(&args).spawn());
        match spawned {
            Ok(_) => {
                self.relaunching = true;
                Restart::Started
            }
            Err(e) => Restart::Failed(e),
        }
    }
}

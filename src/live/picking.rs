//! The brush's view of the live scene: the frame's view depth read back (without waiting) once the
//! renderer has drawn the current view's visibility, the points projected for that view on a worker
//! ([`Picker`]), and a dab's absorption written to the renderer for only the points it changed.

use super::driver::{LiveDriver, LiveError};
use super::jobs::Job;
use crate::gpu::context::PendingRead;
use crate::paint::brush::effective;
use crate::paint::pick::{Picker, ViewDepth};
use crate::render::camera::CameraUniform;
use crate::session::Session;
use crate::session::assemble::mean_absorption;
use std::sync::Arc;

#[derive(Default)]
pub struct Picking {
    /// The view depth on its way back, for this camera.
    reading: Option<(PendingRead, CameraUniform)>,
    /// The picker being built, and the one built (for its view's camera).
    building: Option<Job<Picker>>,
    picker: Option<Arc<Picker>>,
}

impl Picking {
    /// The view depth is on its way back.
    pub fn reading(&self) -> bool {
        self.reading.is_some()
    }
}

impl LiveDriver {
    /// The brush wants a picker and the current view has none yet.
    pub(super) fn picking_pending(&self) -> bool {
        self.picker().is_none()
    }

    /// Once a frame while the brush is active: when the renderer has the current view's depth and
    /// the picker is for another view, reads the depth back and builds a picker from it.
    pub fn update_picking(&mut self) {
        let camera = self.renderer.view_camera();
        let current = |c: &CameraUniform| *c == camera;
        let p = &mut self.picking;
        if let Some(job) = &mut p.building
            && let Some(result) = job.poll()
        {
            p.building = None;
            if let Ok(picker) = result {
                p.picker = Some(Arc::new(picker));
            }
        }
        if let Some((read, c)) = &p.reading
            && let Some(result) = read.poll(&self.ctx.device)
        {
            let c = *c;
            p.reading = None;
            if let (Ok(bytes), true) = (result, current(&c)) {
                let view = ViewDepth {
                    width: c.size[0],
                    height: c.size[1],
                    depth: bytemuck::pod_collect_to_vec(&bytes[0]),
                    camera: c,
                };
                let hair = self.hair.clone();
                let (lo, hi) = self.bounds;
                let mirror_x = 0.5 * (lo.x + hi.x);
                p.building = Some(Job::spawn(
                    "brush picking",
                    || {},
                    move |_| Picker::new(&hair, view, mirror_x),
                ));
            }
        }
        let have = p.picker.as_ref().is_some_and(|k| current(&k.view.camera));
        let coming = p.building.is_some() || p.reading.as_ref().is_some_and(|(_, c)| current(c));
        if !have && !coming && self.renderer.view_depth_ready() {
            p.reading = Some(self.renderer.start_read_view_depth(&self.ctx));
        }
    }

    /// The picker of the view on screen (None while it is being made).
    pub fn picker(&self) -> Option<Arc<Picker>> {
        let camera = self.renderer.view_camera();
        self.picking
            .picker
            .clone()
            .filter(|k| k.view.camera == camera)
    }

    /// A dab changed the session's paint layer at the points `changed` (sorted): their absorption
    /// goes to the renderer at once (only theirs); the volume and grid follow (a deferred rebuild).
    pub fn paint_points(&mut self, session: &Session, changed: &[u32]) -> Result<(), LiveError> {
        let Some(layer) = &session.paint_layer else {
            return Ok(());
        };
        if !layer
            .get()
            .fits(self.hair.point_count(), self.hair.strand_count())
        {
            return Ok(());
        }
        let points = &layer.get().points;
        for &i in changed {
            let i = i as usize;
            self.sigma_a[i] = effective(self.paint.base_sigma_a[i], points[i]);
        }
        self.renderer
            .set_absorption_points_deferred(&self.ctx, &self.sigma_a, changed)?;
        self.note_paint(session);
        // The volume and grid wait for the stroke's end (a rebuild between dabs would take the
        // converged image the next dab repaints).
        self.paint.painting = true;
        if self.renderer.repaint_points(changed) {
            // Converged: the dab's segments alone are shaded again, at full resolution.
            self.restarted();
        } else if self.renderer.preview_under_way() {
            self.paint.paint_restart = true;
        } else {
            self.renderer.restart();
            self.restarted();
        }
        Ok(())
    }

    /// A stroke ended (the volume and grid may follow whatever it left).
    pub fn end_painting(&mut self) {
        self.paint.painting = false;
    }

    /// The stroke ended. Nothing more to send: the volume and shadow grid follow the dabs by
    /// themselves (a deferred rebuild once the image shows), and every table reads each point's own
    /// absorption, so the points' mean (kept for the look's uniform) changes no table.
    pub fn paint_finished(&mut self, _session: &Session) -> Result<(), LiveError> {
        self.paint.painting = false;
        self.paint.mean_sigma_a = mean_absorption(&self.sigma_a);
        Ok(())
    }
}

//! The viewport's tools, each owning its state: navigation (always at hand: the middle button, the
//! wheel, Alt+left) and the brush. The viewport panel hands them its input; what they change in the
//! document or the camera goes to the app as commands.

pub mod brush;
pub mod navigate;

use super::command::AppCommand;
use super::context::PanelContext;
use brush::BrushTool;

/// The active tool.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tool {
    #[default]
    Navigate,
    Brush,
}

#[derive(Default)]
pub struct Tools {
    active: Tool,
    brush: BrushTool,
}

impl Tools {
    pub fn brush(&self) -> &BrushTool {
        &self.brush
    }

    pub fn brush_mut(&mut self) -> &mut BrushTool {
        &mut self.brush
    }

    pub fn active(&self) -> Tool {
        self.active
    }

    /// The tool row's choice.
    pub fn select(&mut self, tool: Tool) {
        self.active = tool;
    }

    /// Tool keys (while the pointer is over the viewport and no text field has focus): B brush,
    /// V / Esc navigate; the brush's own keys while it is active.
    pub fn keys(
        &mut self,
        ctx: &PanelContext,
        egui_ctx: &egui::Context,
        pointer: Option<egui::Pos2>,
    ) {
        let keys = brush::Keys::read(egui_ctx);
        if keys.b {
            self.active = Tool::Brush;
        }
        if keys.esc && self.brush.cancel_adjustment() {
            // Esc cancels an adjustment, and does no more.
        } else if keys.v || keys.esc {
            self.brush.drop_adjustment();
            ctx.send(AppCommand::EndStroke);
            self.active = Tool::Navigate;
        }
        if self.active == Tool::Brush {
            self.brush.keys(ctx, &keys, pointer);
        }
    }
}

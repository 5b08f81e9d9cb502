//! The native file dialogs behind the menu and the shortcuts: each turns what the user picked into
//! the command that acts on it.

use super::command::{AppCommand, DEFAULT_LIGHTS, Dialog};
use std::path::PathBuf;

impl Dialog {
    /// Shows the dialog (blocking, as native dialogs do); the command for what was picked.
    pub fn run(self) -> Option<AppCommand> {
        use rfd::FileDialog;
        let with_ext = |mut p: PathBuf, ext: &str| {
            if p.extension().is_none() {
                p.set_extension(ext);
            }
            p
        };
        Some(match self {
            Dialog::OpenSession => AppCommand::OpenSession(
                FileDialog::new()
                    .add_filter("strandlight session", &["slsession", "json"])
                    .pick_file()?,
            ),
            Dialog::SaveAs => AppCommand::SaveSession(with_ext(
                FileDialog::new()
                    .add_filter("strandlight session", &["slsession"])
                    .set_file_name("look.slsession")
                    .save_file()?,
                "slsession",
            )),
            Dialog::OpenHair => AppCommand::OpenHair(
                FileDialog::new()
                    .add_filter(
                        "hair",
                        &[
                            "hair", "tfx", "gltf", "glb", "usd", "usda", "usdc", "usdz", "abc",
                        ],
                    )
                    .pick_file()?,
            ),
            Dialog::OpenOccluder => AppCommand::OpenOccluder(
                FileDialog::new()
                    .add_filter("mesh", &["obj", "gltf", "glb"])
                    .pick_file()?,
            ),
            Dialog::OpenEnvironment => AppCommand::LoadEnvironment {
                path: FileDialog::new()
                    .add_filter("environment", &["hdr", "exr", "json"])
                    .pick_file()?,
                lights: DEFAULT_LIGHTS,
            },
            Dialog::ExportStill => AppCommand::ExportStill {
                exr: with_ext(
                    FileDialog::new()
                        .add_filter("OpenEXR", &["exr"])
                        .set_file_name("still.exr")
                        .save_file()?,
                    "exr",
                ),
                tile: None,
            },
            Dialog::ExportHair => AppCommand::ExportHair(with_ext(
                FileDialog::new()
                    .add_filter("USD curves", &["usda"])
                    .add_filter("cyHair", &["hair"])
                    .set_file_name("hair.usda")
                    .save_file()?,
                "usda",
            )),
        })
    }
}

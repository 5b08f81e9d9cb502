//! The painted hair for other tools: USD (`.usda`, BasisCurves with widths and per-vertex
//! displayColor) or cyHair (`.hair`, with its colour array), the colour of each point being the
//! albedo its absorption gives (the dye inversion run forward).

use super::Session;
use super::assemble::{AssembleError, load_hair_source, session_absorption};
use crate::hair::Hair;
use crate::hair::cyhair::write_cyhair;
use crate::hair::usd::write::{GroomLook, write_usda};
use crate::paint::dye::{DEFAULT_BETA_N, colour_from_sigma_a};
use crate::session::Look;
use std::path::Path;

/// Writes `hair` with one colour per point from `sigma_a` to `out` (by its extension: .usda or
/// .hair), atomically. USD carries the look too (`hair::usd::write`).
pub fn write_painted_hair(
    hair: &Hair,
    sigma_a: &[[f32; 3]],
    look: &Look,
    out: &Path,
) -> Result<(), String> {
    let colours: Vec<[f32; 3]> = sigma_a
        .iter()
        .map(|s| colour_from_sigma_a(s.map(f64::from), DEFAULT_BETA_N).map(|c| c as f32))
        .collect();
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let bytes = match ext.as_str() {
        "usda" => {
            let groom = groom_look(sigma_a, &colours, look)?;
            write_usda(hair, Some(&groom), "strandlight painted hair").into_bytes()
        }
        "hair" => {
            let mut h = hair.clone();
            h.colour = Some(colours);
            write_cyhair(&h, "strandlight painted hair")
        }
        _ => {
            return Err(format!(
                "{}: hair is exported as .usda (USD) or .hair (cyHair)",
                out.display()
            ));
        }
    };
    crate::files::write_atomic(out, &bytes).map_err(|e| format!("{}: {e}", out.display()))
}

/// The session's hair with its look and paint, to `out` (`strandlight export-hair`).
pub fn export_session_hair(session: &Session, out: &Path) -> Result<(), String> {
    let loaded = load_hair_source(&session.hair).map_err(|e| e.to_string())?;
    let mut hair = loaded.hair;
    let (sigma_a, _) =
        session_absorption(session, &hair).map_err(|e: AssembleError| e.to_string())?;
    hair.transform(|p| p, session.look.thickness_scale);
    write_painted_hair(&hair, &sigma_a, &session.look, out)
}

/// The look in the groom's USD: Unreal's roughness is √β_R (its hair shader takes roughness² as
/// the R lobe's longitudinal width), the scalars strandlight uses, and the whole look as JSON.
fn groom_look<'a>(
    sigma_a: &'a [[f32; 3]],
    colours: &'a [[f32; 3]],
    look: &Look,
) -> Result<GroomLook<'a>, String> {
    let p = &look.params;
    Ok(GroomLook {
        sigma_a,
        colours,
        roughness: p.beta_r.max(0.0).sqrt().min(1.0) as f32,
        params: vec![
            ("eta", p.eta),
            ("alpha_r_radians", p.alpha_r),
            ("beta_r_radians", p.beta_r),
            ("eccentricity", p.eccentricity),
            ("d_f", look.d_f as f64),
            ("d_b", look.d_b as f64),
        ],
        // The widths carry the thickness scale already: the look that travels has none, or a
        // reopened groom would be scaled twice.
        json: serde_json::to_string(&Look {
            thickness_scale: 1.0,
            ..*look
        })
        .map_err(|e| format!("the look as JSON: {e}"))?,
    })
}

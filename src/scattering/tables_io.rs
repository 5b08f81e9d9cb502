//! Writing and reading the `luts/` tables: one float32 EXR per table (one channel per k, so they can
//! be looked at) and `manifest.json` describing axes and sampling (see [`super::tables`]).

use super::tables::{Axis, TABLES_VERSION, Table2D};
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestEntry {
    pub file: String,
    pub name: String,
    pub channels: Vec<String>,
    pub x_axis: Axis,
    pub y_axis: Axis,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub generator: String,
    pub version: u32,
    pub sampling: String,
    pub tables: Vec<ManifestEntry>,
}

fn file_name(t: &Table2D) -> String {
    format!("{}.exr", t.name)
}

/// Writes every table and the manifest into `dir`.
pub fn write_tables(tables: &[Table2D], dir: &Path) -> anyhow_free::Result<()> {
    use exr::prelude::*;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut entries = Vec::new();
    for t in tables {
        let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = t
            .channels
            .iter()
            .zip(&t.data)
            .map(|(name, d)| AnyChannel::new(name.as_str(), FlatSamples::F32(d.clone())))
            .collect();
        let layer = Layer::new(
            (t.x_axis.samples, t.y_axis.samples),
            LayerAttributes::named(t.name.as_str()),
            Encoding::UNCOMPRESSED,
            AnyChannels::sort(list),
        );
        let path = dir.join(file_name(t));
        Image::from_layer(layer)
            .write()
            .to_file(&path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        entries.push(ManifestEntry {
            file: file_name(t),
            name: t.name.clone(),
            channels: t.channels.clone(),
            x_axis: t.x_axis.clone(),
            y_axis: t.y_axis.clone(),
        });
    }
    let manifest = Manifest {
        generator: format!("strandlight {} precompute", env!("CARGO_PKG_VERSION")),
        version: TABLES_VERSION,
        sampling: "texel i of N holds the value at sample i: log10 axes v_i = min (max/min)^(i/(N-1)), \
                   linear axes v_i = min + (max-min) i/(N-1); sample texel centres at u = (i + 0.5)/N"
            .into(),
        tables: entries,
    };
    let path = dir.join("manifest.json");
    let text = serde_json::to_string_pretty(&manifest).map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}

/// Reads one table's channels back (in the manifest's channel order).
pub fn read_table(dir: &Path, entry: &ManifestEntry) -> anyhow_free::Result<Table2D> {
    use exr::prelude::*;
    let path = dir.join(&entry.file);
    let image =
        read_all_flat_layers_from_file(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let layer = image
        .layer_data
        .first()
        .ok_or_else(|| format!("{}: no layer", path.display()))?;
    let mut data = Vec::new();
    for name in &entry.channels {
        let ch = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == *name)
            .ok_or_else(|| format!("{}: channel {name} missing", path.display()))?;
        let v: Vec<f32> = ch.sample_data.values_as_f32().collect();
        if v.len() != entry.x_axis.samples * entry.y_axis.samples {
            return Err(format!(
                "{}: channel {name} has {} samples",
                path.display(),
                v.len()
            ));
        }
        data.push(v);
    }
    Ok(Table2D {
        name: entry.name.clone(),
        x_axis: entry.x_axis.clone(),
        y_axis: entry.y_axis.clone(),
        channels: entry.channels.clone(),
        data,
    })
}

pub fn read_manifest(dir: &Path) -> anyhow_free::Result<Manifest> {
    let path = dir.join("manifest.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Errors here are messages naming the file (library code stays free of anyhow).
pub mod anyhow_free {
    pub type Result<T> = std::result::Result<T, String>;
}

//! Hair parameters as command-line flags and as JSON fields (the same struct serves both).

use anyhow::{Context, bail};
use clap::Args;
use serde::{Deserialize, Serialize};
use strandlight::scattering::params::sigma_a_from_melanin;
use strandlight::scattering::{HairParams, Lobe, LongitudinalModel, ModelVariant, Preset};

/// Which form of the exact model to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum VariantArg {
    /// Marschner 2003: exact Fresnel with Bravais indices, caustic fix.
    #[default]
    Marschner,
    /// Xu 2011: Schlick Fresnel reused for the internal reflection, caustic fix.
    Xu,
    /// Exact Fresnel, bare root sum (no caustic fix; conserves energy).
    Unsmoothed,
}

impl VariantArg {
    pub fn variant(self) -> ModelVariant {
        match self {
            VariantArg::Marschner => ModelVariant::MARSCHNER,
            VariantArg::Xu => ModelVariant::XU,
            VariantArg::Unsmoothed => ModelVariant::UNSMOOTHED,
        }
    }
}

/// Hair parameters. Unset values come from the preset (default: brown), and TT/TRT shifts and
/// widths follow Marschner's couplings unless given. Angles in degrees.
#[derive(Args, Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamArgs {
    /// Named look (melanin concentrations).
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Index of refraction.
    #[arg(long, allow_negative_numbers = true)]
    pub eta: Option<f64>,
    /// Absorption per unit fiber radius: one value (grey) or R,G,B.
    #[arg(long, value_delimiter = ',', num_args = 1..=3, allow_negative_numbers = true)]
    pub sigma_a: Option<Vec<f64>>,
    /// Eumelanin concentration (sigma_a from melanin, d'Eon et al. 2011); overrides the preset's.
    #[arg(long, allow_negative_numbers = true)]
    pub eumelanin: Option<f64>,
    /// Pheomelanin concentration; overrides the preset's.
    #[arg(long, allow_negative_numbers = true)]
    pub pheomelanin: Option<f64>,
    /// R lobe shift alpha_R, degrees.
    #[arg(long, allow_negative_numbers = true)]
    pub alpha_r: Option<f64>,
    /// TT lobe shift, degrees (default -alpha_R/2).
    #[arg(long, allow_negative_numbers = true)]
    pub alpha_tt: Option<f64>,
    /// TRT lobe shift, degrees (default -3 alpha_R/2).
    #[arg(long, allow_negative_numbers = true)]
    pub alpha_trt: Option<f64>,
    /// R lobe width beta_R (standard deviation), degrees.
    #[arg(long, allow_negative_numbers = true)]
    pub beta_r: Option<f64>,
    /// TT lobe width, degrees (default beta_R/2).
    #[arg(long, allow_negative_numbers = true)]
    pub beta_tt: Option<f64>,
    /// TRT lobe width, degrees (default 2 beta_R).
    #[arg(long, allow_negative_numbers = true)]
    pub beta_trt: Option<f64>,
    /// Eccentricity a of the cross-section (1 = circular).
    #[arg(long, allow_negative_numbers = true)]
    pub eccentricity: Option<f64>,
    /// TRT caustic width w_c, degrees (the exact model's Marschner and Xu variants; the renderer
    /// integrates the exact caustic).
    #[arg(long, allow_negative_numbers = true)]
    pub caustic_width: Option<f64>,
    /// Caustic fade range Delta eta' (as the caustic width).
    #[arg(long, allow_negative_numbers = true)]
    pub caustic_fade: Option<f64>,
    /// Caustic intensity limit.
    #[arg(long, allow_negative_numbers = true)]
    pub caustic_limit: Option<f64>,
    /// Glint scale factor.
    #[arg(long, allow_negative_numbers = true)]
    pub glint_scale: Option<f64>,
    /// Model variant.
    #[arg(long, value_enum)]
    pub variant: Option<VariantArg>,
    /// Longitudinal function: normalized (d'Eon et al. 2011, energy-conserving, the default) or
    /// published (Marschner 2003 / Xu 2011 Eq. 7: about twice too bright, for comparison with the papers).
    #[arg(long, value_enum)]
    pub longitudinal: Option<LongitudinalModel>,
}

impl ParamArgs {
    /// Fields set here replace those of `base`.
    pub fn overlay(&self, base: &ParamArgs) -> ParamArgs {
        macro_rules! pick {
            ($($f:ident),*) => { ParamArgs { $($f: self.$f.clone().or_else(|| base.$f.clone()),)* } };
        }
        pick!(
            preset,
            eta,
            sigma_a,
            eumelanin,
            pheomelanin,
            alpha_r,
            alpha_tt,
            alpha_trt,
            beta_r,
            beta_tt,
            beta_trt,
            eccentricity,
            caustic_width,
            caustic_fade,
            caustic_limit,
            glint_scale,
            variant,
            longitudinal
        )
    }

    /// The resolved, validated parameters.
    pub fn resolve(&self) -> anyhow::Result<HairParams> {
        let preset = self.preset.unwrap_or(Preset::Brown);
        let mut p = preset.params();
        if self.eumelanin.is_some() || self.pheomelanin.is_some() {
            let (eu, ph) = preset.melanin();
            p.sigma_a =
                sigma_a_from_melanin(self.eumelanin.unwrap_or(eu), self.pheomelanin.unwrap_or(ph));
        }
        if let Some(s) = &self.sigma_a {
            p.sigma_a = match s.as_slice() {
                [g] => [*g; 3],
                [r, g, b] => [*r, *g, *b],
                _ => bail!("sigma_a takes 1 or 3 values, got {}", s.len()),
            };
        }
        let rad = |x: Option<f64>| x.map(f64::to_radians);
        if let Some(x) = self.eta {
            p.eta = x;
        }
        if let Some(x) = rad(self.alpha_r) {
            p.alpha_r = x;
        }
        p.alpha_tt = rad(self.alpha_tt).or(p.alpha_tt);
        p.alpha_trt = rad(self.alpha_trt).or(p.alpha_trt);
        if let Some(x) = rad(self.beta_r) {
            p.beta_r = x;
        }
        p.beta_tt = rad(self.beta_tt).or(p.beta_tt);
        p.beta_trt = rad(self.beta_trt).or(p.beta_trt);
        if let Some(x) = self.eccentricity {
            p.eccentricity = x;
        }
        if let Some(x) = rad(self.caustic_width) {
            p.caustic_width = x;
        }
        if let Some(x) = self.caustic_fade {
            p.caustic_fade = x;
        }
        if let Some(x) = self.caustic_limit {
            p.caustic_limit = x;
        }
        if let Some(x) = self.glint_scale {
            p.glint_scale = x;
        }
        p.validate()
            .map_err(anyhow::Error::msg)
            .context("invalid hair parameters")?;
        Ok(p)
    }
}

/// Parameters as printed in JSON: every value resolved, angles in degrees.
#[derive(Serialize)]
pub struct ParamsReport {
    pub eta: f64,
    pub sigma_a: [f64; 3],
    pub alpha_deg: [f64; 3],
    pub beta_deg: [f64; 3],
    pub eccentricity: f64,
    pub caustic_width_deg: f64,
    pub caustic_fade: f64,
    pub caustic_limit: f64,
    pub glint_scale: f64,
}

impl ParamsReport {
    pub fn new(p: &HairParams) -> Self {
        Self {
            eta: p.eta,
            sigma_a: p.sigma_a,
            alpha_deg: Lobe::ALL.map(|l| p.alpha(l).to_degrees()),
            beta_deg: Lobe::ALL.map(|l| p.beta(l).to_degrees()),
            eccentricity: p.eccentricity,
            caustic_width_deg: p.caustic_width.to_degrees(),
            caustic_fade: p.caustic_fade,
            caustic_limit: p.caustic_limit,
            glint_scale: p.glint_scale,
        }
    }
}

/// Rejects non-finite angles and inclinations outside [-90, 90] degrees, naming the field.
pub fn check_angles(all: &[(&str, f64)], inclinations: &[(&str, f64)]) -> anyhow::Result<()> {
    for (name, v) in all {
        if !v.is_finite() {
            bail!("{name} must be finite");
        }
    }
    for (name, v) in inclinations {
        if v.abs() > 90.0 {
            bail!("{name} must lie in [-90, 90] degrees, got {v}");
        }
    }
    Ok(())
}

/// Reads a JSON array of queries from standard input; errors say which command's queries they were.
pub fn read_stdin_queries<T: serde::de::DeserializeOwned>(command: &str) -> anyhow::Result<Vec<T>> {
    use std::io::Read;
    let mut text = String::new();
    std::io::stdin()
        .read_to_string(&mut text)
        .context("reading queries from standard input")?;
    serde_json::from_str(&text)
        .with_context(|| format!("standard input is not a JSON array of {command} queries"))
}

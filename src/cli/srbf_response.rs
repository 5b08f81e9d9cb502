//! `strandlight srbf-response`: the fast per-SRBF response (Xu 2011 Sec. 4.2) for given parameters, light
//! and view, optionally with the brute-force integral of the exact model and the relative error.

use super::bsdf::LobeReport;
use super::params_args::{ParamArgs, ParamsReport, VariantArg, check_angles, read_stdin_queries};
use anyhow::{Context, bail};
use clap::Args;
use serde::{Deserialize, Serialize};
use strandlight::scattering::azimuthal_table::AzimuthalTable;
use strandlight::scattering::fast_params::{DEFAULT_QUADRATURE_SEGMENTS, FastHairParams};
use strandlight::scattering::fast_response::{SrbfInFrame, srbf_response};
use strandlight::scattering::lut::Luts;
use strandlight::scattering::srbf_reference::{SrbfLight64, srbf_response_reference};
use strandlight::scattering::{CausticModel, FiberAngles, Lobe, LobeValues, ModelVariant, Rgb};

#[derive(Args, Debug)]
pub struct SrbfResponseArgs {
    /// SRBF centre inclination theta_j, degrees (fiber frame).
    #[arg(long, allow_negative_numbers = true, required_unless_present = "stdin")]
    pub theta_j: Option<f64>,
    /// SRBF centre azimuth phi_j, degrees.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub phi_j: f64,
    /// SRBF bandwidth lambda_j (G = exp(2 (w . w_j - 1) / lambda_j^2)), radians.
    #[arg(long, required_unless_present = "stdin")]
    pub lambda: Option<f64>,
    /// View inclination theta_o, degrees.
    #[arg(long, allow_negative_numbers = true, required_unless_present = "stdin")]
    pub theta_o: Option<f64>,
    /// View azimuth phi_o, degrees.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub phi_o: f64,
    /// Segments m of the linear quadrature (Xu Sec. 4.2.2).
    #[arg(long, default_value_t = DEFAULT_QUADRATURE_SEGMENTS)]
    pub segments: u32,
    /// Also integrate the exact model (Xu's Schlick Fresnel, bare root sum) against the SRBF over the
    /// sphere by adaptive quadrature (relative accuracy ~1e-5) and report the relative error.
    #[arg(long)]
    pub reference: bool,
    /// Read a JSON array of queries from standard input, e.g.
    /// [{"theta_j": 20, "phi_j": 150, "lambda": 0.3, "theta_o": -10, "phi_o": 0, "params": {"preset": "blond"}}].
    #[arg(long)]
    pub stdin: bool,
    #[command(flatten)]
    pub params: ParamArgs,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Query {
    pub theta_j: f64,
    #[serde(default)]
    pub phi_j: f64,
    pub lambda: f64,
    pub theta_o: f64,
    #[serde(default)]
    pub phi_o: f64,
    #[serde(default)]
    pub params: ParamArgs,
}

/// Per lobe and channel, with the total (the `bsdf` report's shape).
fn lobes(v: [Rgb; 3]) -> LobeReport {
    let lobes = LobeValues {
        r: v[0],
        tt: v[1],
        trt: v[2],
    };
    LobeReport {
        total: lobes.total(),
        lobes,
    }
}

#[derive(Serialize)]
pub struct Answer {
    pub theta_j: f64,
    pub phi_j: f64,
    pub lambda: f64,
    pub theta_o: f64,
    pub phi_o: f64,
    pub segments: u32,
    pub params: ParamsReport,
    /// integral of G S cos(theta_i) d omega_i, per lobe and channel (fast form).
    pub fast: LobeReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<LobeReport>,
    /// |fast - reference| / reference of the total, per channel.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relative_error: Option<Rgb>,
}

/// Azimuthal tables by (eta, eccentricity), built once each for a batch of queries.
#[derive(Default)]
struct Tables(std::sync::Mutex<Vec<std::sync::Arc<AzimuthalTable>>>);

impl Tables {
    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<std::sync::Arc<AzimuthalTable>>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn get(&self, fp: &FastHairParams) -> std::sync::Arc<AzimuthalTable> {
        if let Some(t) = self.lock().iter().find(|t| t.matches(fp)) {
            return t.clone();
        }
        // Built outside the lock (the build runs on rayon's threads); a duplicate build is harmless.
        let t = std::sync::Arc::new(AzimuthalTable::for_params(fp));
        let mut tables = self.lock();
        // 22-75 MB each (f32 cells and the GPU's copy): a sweep over many fibers keeps the last few.
        if tables.len() >= 4 {
            tables.remove(0);
        }
        tables.push(t.clone());
        t
    }
}

fn evaluate(
    luts: &Luts,
    tables: &Tables,
    q: &Query,
    defaults: &ParamArgs,
    segments: u32,
    reference: bool,
) -> anyhow::Result<Answer> {
    check_angles(
        &[
            ("theta_j", q.theta_j),
            ("phi_j", q.phi_j),
            ("lambda", q.lambda),
            ("theta_o", q.theta_o),
            ("phi_o", q.phi_o),
        ],
        &[("theta_j", q.theta_j), ("theta_o", q.theta_o)],
    )?;
    if !(0.001..=10.0).contains(&q.lambda) {
        bail!("lambda must lie in [0.001, 10] radians, got {}", q.lambda);
    }
    if !(2..=1000).contains(&segments) {
        bail!("segments must lie in [2, 1000], got {segments}");
    }
    let args = q.params.overlay(defaults);
    if args.variant.is_some_and(|v| v != VariantArg::Xu) {
        bail!(
            "srbf-response evaluates Xu's fast form (Schlick Fresnel); its reference is the exact model with that Fresnel and no caustic smoothing, so --variant cannot be changed"
        );
    }
    let params = args.resolve()?;
    let longitudinal = args.longitudinal.unwrap_or_default();
    let fp = FastHairParams::new(&params, segments).with_longitudinal(longitudinal);
    let light = SrbfInFrame {
        theta: q.theta_j.to_radians() as f32,
        phi: q.phi_j.to_radians() as f32,
        lambda: q.lambda as f32,
    };
    let table = tables.get(&fp);
    let fast = srbf_response(
        luts,
        &table,
        &fp,
        light,
        q.theta_o.to_radians() as f32,
        q.phi_o.to_radians() as f32,
    )
    .map(|l| l.map(|v| v as f64));
    let fast = lobes(fast);
    let (reference, relative_error) = if reference {
        let variant = ModelVariant {
            caustic: CausticModel::None,
            ..ModelVariant::XU
        }
        .with_longitudinal(longitudinal);
        let l64 = SrbfLight64 {
            theta: q.theta_j.to_radians(),
            phi: q.phi_j.to_radians(),
            lambda: q.lambda,
        };
        let wo = FiberAngles::new(q.theta_o.to_radians(), q.phi_o.to_radians());
        let r = Lobe::ALL.map(|lobe| {
            std::array::from_fn(|c| srbf_response_reference(&params, variant, lobe, l64, wo, c))
        });
        let r = lobes(r);
        let err = std::array::from_fn(|c| {
            (fast.total[c] - r.total[c]).abs() / r.total[c].max(f64::MIN_POSITIVE)
        });
        (Some(r), Some(err))
    } else {
        (None, None)
    };
    Ok(Answer {
        theta_j: q.theta_j,
        phi_j: q.phi_j,
        lambda: q.lambda,
        theta_o: q.theta_o,
        phi_o: q.phi_o,
        segments,
        params: ParamsReport::new(&params),
        fast,
        reference,
        relative_error,
    })
}

pub fn run(args: SrbfResponseArgs) -> anyhow::Result<()> {
    let luts = Luts::default_tables();
    let tables = Tables::default();
    if args.stdin {
        let queries: Vec<Query> = read_stdin_queries("srbf-response")?;
        use rayon::prelude::*;
        let answers = queries
            .par_iter()
            .enumerate()
            .map(|(k, q)| {
                evaluate(
                    &luts,
                    &tables,
                    q,
                    &args.params,
                    args.segments,
                    args.reference,
                )
                .with_context(|| format!("query {k}"))
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        println!("{}", serde_json::to_string_pretty(&answers)?);
    } else {
        let q = Query {
            theta_j: args.theta_j.context("--theta-j is required")?,
            phi_j: args.phi_j,
            lambda: args.lambda.context("--lambda is required")?,
            theta_o: args.theta_o.context("--theta-o is required")?,
            phi_o: args.phi_o,
            params: ParamArgs::default(),
        };
        let a = evaluate(
            &luts,
            &tables,
            &q,
            &args.params,
            args.segments,
            args.reference,
        )?;
        println!("{}", serde_json::to_string_pretty(&a)?);
    }
    Ok(())
}

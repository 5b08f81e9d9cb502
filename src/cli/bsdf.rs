//! `strandlight bsdf`: evaluate the exact Marschner model for given directions.

use super::params_args::{ParamArgs, ParamsReport, check_angles, read_stdin_queries};
use anyhow::Context;
use clap::Args;
use serde::{Deserialize, Serialize};
use strandlight::scattering::{FiberAngles, HalfAngles, LobeValues, Rgb, scattering_s};

#[derive(Args, Debug)]
pub struct BsdfArgs {
    /// Light direction inclination theta_i, degrees (fiber frame).
    #[arg(long, allow_negative_numbers = true, required_unless_present = "stdin")]
    pub theta_i: Option<f64>,
    /// Light direction azimuth phi_i, degrees.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub phi_i: f64,
    /// View direction inclination theta_o, degrees.
    #[arg(long, allow_negative_numbers = true, required_unless_present = "stdin")]
    pub theta_o: Option<f64>,
    /// View direction azimuth phi_o, degrees.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub phi_o: f64,
    /// Read a JSON array of queries from standard input, e.g.
    /// [{"theta_i": 10, "phi_i": 0, "theta_o": -5, "phi_o": 160, "params": {"preset": "blond"}}].
    /// Flags given on the command line are defaults for every query's parameters.
    #[arg(long)]
    pub stdin: bool,
    #[command(flatten)]
    pub params: ParamArgs,
}

/// One query of a batch.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Query {
    pub theta_i: f64,
    #[serde(default)]
    pub phi_i: f64,
    pub theta_o: f64,
    #[serde(default)]
    pub phi_o: f64,
    #[serde(default)]
    pub params: ParamArgs,
}

/// The lobes (R, TT, TRT) and their sum.
#[derive(Serialize)]
pub struct LobeReport {
    #[serde(flatten)]
    pub lobes: LobeValues,
    pub total: Rgb,
}

#[derive(Serialize)]
pub struct Answer {
    pub theta_i: f64,
    pub phi_i: f64,
    pub theta_o: f64,
    pub phi_o: f64,
    pub theta_h: f64,
    pub theta_d: f64,
    pub phi: f64,
    pub variant: super::params_args::VariantArg,
    pub longitudinal: strandlight::scattering::LongitudinalModel,
    pub params: ParamsReport,
    #[serde(rename = "S")]
    pub s: LobeReport,
}

pub fn evaluate(q: &Query, defaults: &ParamArgs) -> anyhow::Result<Answer> {
    check_angles(
        &[
            ("theta_i", q.theta_i),
            ("phi_i", q.phi_i),
            ("theta_o", q.theta_o),
            ("phi_o", q.phi_o),
        ],
        &[("theta_i", q.theta_i), ("theta_o", q.theta_o)],
    )?;
    let args = q.params.overlay(defaults);
    let params = args.resolve()?;
    let variant = args.variant.unwrap_or_default();
    let wi = FiberAngles::new(q.theta_i.to_radians(), q.phi_i.to_radians());
    let wo = FiberAngles::new(q.theta_o.to_radians(), q.phi_o.to_radians());
    let ha = HalfAngles::new(wi, wo);
    let longitudinal = args.longitudinal.unwrap_or_default();
    let v = scattering_s(
        &params,
        variant.variant().with_longitudinal(longitudinal),
        wi,
        wo,
    );
    Ok(Answer {
        theta_i: q.theta_i,
        phi_i: q.phi_i,
        theta_o: q.theta_o,
        phi_o: q.phi_o,
        theta_h: ha.theta_h.to_degrees(),
        theta_d: ha.theta_d.to_degrees(),
        phi: ha.phi.to_degrees(),
        variant,
        longitudinal,
        params: ParamsReport::new(&params),
        s: LobeReport {
            total: v.total(),
            lobes: v,
        },
    })
}

pub fn run(args: BsdfArgs) -> anyhow::Result<()> {
    if args.stdin {
        let queries: Vec<Query> = read_stdin_queries("bsdf")?;
        let answers = queries
            .iter()
            .enumerate()
            .map(|(k, q)| evaluate(q, &args.params).with_context(|| format!("query {k}")))
            .collect::<anyhow::Result<Vec<_>>>()?;
        println!("{}", serde_json::to_string_pretty(&answers)?);
    } else {
        let q = Query {
            theta_i: args.theta_i.context("--theta-i is required")?,
            phi_i: args.phi_i,
            theta_o: args.theta_o.context("--theta-o is required")?,
            phi_o: args.phi_o,
            params: ParamArgs::default(),
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&evaluate(&q, &args.params)?)?
        );
    }
    Ok(())
}

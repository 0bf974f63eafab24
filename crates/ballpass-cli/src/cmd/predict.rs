//! `ballpass predict`: ball-pass frequency, period and band for a bearing.

use std::io::Write;

use anyhow::Result;
use ballpass::bearing::{self, Prediction};
use clap::Args;
use serde::Serialize;

use crate::args::{parse_velocities, BearingArgs};

/// Arguments of `ballpass predict`.
#[derive(Debug, Args)]
pub struct PredictArgs {
    #[command(flatten)]
    bearing: BearingArgs,
    /// Tracking velocity in mm/s, or a range START:STOP:STEP (inclusive).
    #[arg(
        long,
        short = 'v',
        allow_hyphen_values = true,
        required_unless_present = "list_bearings",
        value_name = "MM/S"
    )]
    velocity: Option<String>,
    /// Number of harmonics k·f_c to list.
    #[arg(long, default_value_t = 5, value_name = "K")]
    harmonics: usize,
    /// Print JSON for a program instead of text for a person.
    #[arg(long)]
    json: bool,
    /// List the bearing catalog and exit.
    #[arg(long)]
    list_bearings: bool,
}

#[derive(Serialize)]
struct Output<'a> {
    schema: &'static str,
    version: &'static str,
    bearing: &'a str,
    geometry: ballpass::bearing::Geometry,
    predictions: &'a [Prediction],
}

/// Runs `ballpass predict`.
pub fn run(a: &PredictArgs) -> Result<()> {
    let mut out = crate::output::stdout();
    if a.list_bearings {
        for e in bearing::CATALOG {
            let g = e.geometry;
            writeln!(
                out,
                "{:<10} {:<14} d = {} mm, d_ext = {} mm, N_B = {}{}  [{}]",
                e.key,
                e.name,
                g.ball_diameter_mm,
                g.free_space_mm,
                g.balls_in_race,
                if e.estimated { " (estimated)" } else { "" },
                e.provenance
            )?;
        }
        return Ok(());
    }
    let (name, geometry) = a.bearing.geometry()?;
    let velocities = parse_velocities(a.velocity.as_deref().unwrap_or_default())?;
    let predictions = velocities
        .iter()
        .map(|&v| geometry.predict(v, a.harmonics))
        .collect::<ballpass::Result<Vec<_>>>()?;
    if a.json {
        let o = Output {
            schema: "ballpass.predict/1",
            version: ballpass::VERSION,
            bearing: &name,
            geometry,
            predictions: &predictions,
        };
        serde_json::to_writer_pretty(&mut out, &o)?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(
        out,
        "{name}: d = {} mm, d_ext = {} mm, N_B = {}  →  d_avg = {:.5} mm, d_var = {:.4} mm",
        geometry.ball_diameter_mm,
        geometry.free_space_mm,
        geometry.balls_in_race,
        geometry.d_avg_mm(),
        geometry.d_var_mm()
    )?;
    if let [p] = predictions.as_slice() {
        writeln!(out, "at v = {} mm/s:", p.velocity_mm_s)?;
        writeln!(out, "  ball-pass frequency f_c = {:.6} Hz", p.f_c_hz)?;
        writeln!(out, "  ball-pass period  tau_c = {:.5} s", p.tau_c_s)?;
        writeln!(
            out,
            "  band (even spacing ± d_var): {:.6} – {:.6} Hz",
            p.f_band_low_hz, p.f_band_high_hz
        )?;
        writeln!(
            out,
            "  one gap from 0 to d_ext:    {:.6} – {:.6} Hz",
            p.f_single_spacing_low_hz, p.f_single_spacing_high_hz
        )?;
        let h: Vec<String> = p.harmonics_hz.iter().map(|f| format!("{f:.4}")).collect();
        writeln!(out, "  harmonics k·f_c: {} Hz", h.join(", "))?;
    } else {
        writeln!(
            out,
            "{:>10} {:>12} {:>10} {:>12} {:>12}",
            "v mm/s", "f_c Hz", "tau_c s", "band lo Hz", "band hi Hz"
        )?;
        for p in &predictions {
            writeln!(
                out,
                "{:>10.3} {:>12.6} {:>10.5} {:>12.6} {:>12.6}",
                p.velocity_mm_s, p.f_c_hz, p.tau_c_s, p.f_band_low_hz, p.f_band_high_hz
            )?;
        }
    }
    Ok(())
}

//! The stage a compensation table is designed with (identified from the
//! records, else the loop gains given) and the linear prediction of the
//! periodic velocity error through it.

use super::StageSource;
use crate::analysis::sync::coefficient;
use crate::analysis::Analysis;
use crate::error::{Error, Result};
use crate::model::stage::PdLoop;

/// The stage the table is designed and predicted with: the one identified
/// from the records, else the loop gains given; its source and in words.
pub(super) fn stage_of(
    a: &Analysis,
    gains: Option<PdLoop>,
    bad: &dyn Fn(String) -> Error,
) -> Result<(PdLoop, StageSource, String)> {
    Ok(match (&a.stage, gains) {
        (Some(id), _) if id.identified => {
            let (Some(m), Some(kd), Some(kp)) = (id.mass_kg, id.kkd_n_s_per_m, id.kkp_n_per_m)
            else {
                return Err(bad("identified stage without its parameters".into()));
            };
            (
                PdLoop::from_products(m.value, kp.value, kd.value)?,
                StageSource::Identified,
                format!("identified from the records: {}", id.text),
            )
        }
        (id, Some(g)) => (
            g,
            StageSource::GivenGains,
            format!(
                "loop gains given ({}), the stage not identified from the data{}",
                describe(&g),
                id.as_ref()
                    .map(|i| format!(": {}", i.text))
                    .unwrap_or_default()
            ),
        ),
        (id, None) => {
            return Err(Error::setting(
                "stage",
                format!(
                    "the stage could not be identified from the records ({}); give the loop \
                     gains (mass, K*KP, K*KD)",
                    id.as_ref()
                        .map_or("no friction and position".into(), |i| i.text.clone())
                ),
            ))
        }
    })
}

/// The linear prediction of the periodic velocity error with `force`
/// applied (module docs).
pub(super) struct Linear {
    pub(super) f_c_um_s: f64,
    pub(super) var_before: f64,
    pub(super) var_after: f64,
    pub(super) waveform_um_s: Vec<f64>,
}

pub(super) fn linear(v_mean: &[f64], force: &[f64], stage: &PdLoop, w_c: f64) -> Linear {
    let b = force.len();
    let mut after = vec![0.0; b];
    let (mut var_before, mut var_after) = (0.0, 0.0);
    let mut f1 = (0.0, 0.0);
    for k in 1..b / 2 {
        let vk = coefficient(v_mean, k);
        let uk = coefficient(force, k);
        let g = stage.g_vf(k as f64 * w_c) * 1e6;
        let rk = (
            vk.0 + g.re * uk.0 - g.im * uk.1,
            vk.1 + g.re * uk.1 + g.im * uk.0,
        );
        if k == 1 {
            f1 = rk;
        }
        var_before += 2.0 * (vk.0 * vk.0 + vk.1 * vk.1);
        var_after += 2.0 * (rk.0 * rk.0 + rk.1 * rk.1);
        for (j, a) in after.iter_mut().enumerate() {
            let th = std::f64::consts::TAU * (k * j) as f64 / b as f64;
            *a += 2.0 * (rk.0 * th.cos() - rk.1 * th.sin());
        }
    }
    Linear {
        f_c_um_s: 2.0 * f1.0.hypot(f1.1),
        var_before,
        var_after,
        waveform_um_s: after,
    }
}

fn describe(g: &PdLoop) -> String {
    format!(
        "m = {:.4} kg, K·K_P = {:.4} N/m, K·K_D = {:.4} N·s/m",
        g.mass_kg, g.stiffness_n_per_m, g.damping_n_s_per_m
    )
}

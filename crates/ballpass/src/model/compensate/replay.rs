//! The records' friction replayed through the identified stage, with and
//! without the table: the prediction that still holds near stall.
//!
//! ```text
//! friction   F(x): the record's friction against its encoder position (the
//!            friction of a bearing follows the balls, that is position)
//! stage      m y'' = −k y − c y' − F(x)·sat(x'/v_ε) + u(φ),  x = x_s + V t + y
//! key        φ = (travel since the last passage position) / P,  P = 2·d_avg
//! start      y = −mean F / k, y' = 0 at the record's first position
//! ```
//!
//! integrated exactly per step (zero-order hold, [`crate::sim::stage`]) at
//! ten steps per sample, until the record's last position. `sat` keeps the
//! friction from pushing a stopped stage backwards (`v_ε` as the
//! simulator's). The replayed velocity error is low-passed as the analysis
//! does, and its f_c component is the fundamental of its synchronous
//! average keyed on the times the replay crosses the passage positions;
//! its std is that of the low-passed replay.

use super::travel::{at_index, RecordKeys};
use crate::analysis::sync::{synchronous_average, SyncInput, SyncKey, SyncSettings};
use crate::analysis::{AnalyzeSettings, Signal};
use crate::model::stage::PdLoop;

/// Rounds of the table's design ([`design`]).
pub(crate) const ROUNDS: usize = 4;

/// The table designed by replay and the replay with it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Design {
    /// Force per bin, N, zero mean.
    pub table: Vec<f64>,
    /// The replay with it.
    pub after: Replayed,
    /// Each record's friction level ([`fit_levels`]).
    pub levels: Vec<LevelFit>,
    /// Amplitude of the difference between the fundamentals of the
    /// records' velocity error and of the replay without a table, µm/s:
    /// how far the replay is from the stage it stands for, at the f_c
    /// component.
    pub f_c_model_error_um_s: f64,
    /// Fixed-point rounds kept (of [`ROUNDS`]) and correction steps kept
    /// (of [`FUNDAMENTAL_STEPS`]) by the guard ([`design`]).
    pub kept: Kept,
    /// How the design went, for the validation's look inside.
    pub trace: Trace,
}

/// The steps of the replay's design kept by its guard: a step is kept
/// only when the replay says it helps (`compensation.json`,
/// `design_kept`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Kept {
    /// The fixed-point round whose table the table comes from, of 4 (0:
    /// the friction against travel).
    pub rounds: usize,
    /// The round refused, when one was: the first whose table the replay
    /// says makes the velocity error's std larger than no table does
    /// (the rounds stop there).
    pub refused_round: Option<usize>,
    /// Corrections of the table's fundamental kept, of 3.
    pub corrections: usize,
}

/// One table of the design and the replay with it (for the trace).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Step {
    /// Fundamental of the table (coefficient, N).
    pub table_c1: (f64, f64),
    /// The replay's f_c component with it, µm/s.
    pub f_c_um_s: f64,
    /// The replay's std with it, µm/s.
    pub std_um_s: f64,
}

impl Step {
    fn of(table: &[f64], r: &Replayed) -> Self {
        Self {
            table_c1: crate::analysis::sync::coefficient(table, 1),
            f_c_um_s: r.f_c_um_s,
            std_um_s: r.std_um_s,
        }
    }
}

/// The steps of [`design`], for the validation.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Trace {
    /// The table after the fixed-point rounds kept, before the
    /// fundamental's correction.
    pub fixed_point: Vec<f64>,
    /// The replay with it.
    pub fixed_point_after: Replayed,
    /// The replay without a table.
    pub bare: Replayed,
    /// Fundamental of the records' velocity error (coefficient, µm/s).
    pub measured_v1: Option<(f64, f64)>,
    /// The friction against travel and each fixed-point round tried
    /// (the first refused one last, when the guard stopped the rounds).
    pub rounds: Vec<Step>,
    /// Each correction of the fundamental tried.
    pub corrections: Vec<Step>,
    /// The fundamental of the fixed-point table alone, corrected as the
    /// table is (guarded only; without a ball-pass frequency, `None`).
    pub fundamental_only: Option<Corrected>,
}

/// What [`design`] takes from the analysis of the records.
#[derive(Debug, Clone)]
pub(crate) struct DesignAt {
    /// Ball pitch `2·d_avg`, mm.
    pub pitch_mm: f64,
    /// Commanded velocity, mm/s.
    pub velocity_mm_s: f64,
    /// The analysis' settings (the replay's low-pass).
    pub settings: AnalyzeSettings,
    /// Fundamental of the records' velocity error (coefficient, µm/s).
    pub measured_v1: Option<(f64, f64)>,
    /// Ball-pass angular frequency of the synchronous average, rad/s
    /// (without it, no correction of the fundamental).
    pub w_c_rad_s: Option<f64>,
    /// Whether to make, for the validation, the fundamental of the
    /// fixed-point table alone, corrected ([`Trace::fundamental_only`];
    /// guarded designs only; the product does not).
    pub fundamental_only: bool,
}

impl DesignAt {
    /// From the analysis `a` of the records.
    pub(crate) fn of(a: &crate::analysis::Analysis) -> Self {
        Self {
            pitch_mm: 2.0 * a.prediction.d_avg_mm,
            velocity_mm_s: a.prediction.velocity_mm_s,
            settings: a.settings.clone(),
            measured_v1: a
                .sync
                .as_ref()
                .and_then(|s| s.waveform(Signal::VelocityError))
                .map(|w| crate::analysis::sync::coefficient(&w.mean, 1)),
            w_c_rad_s: a
                .sync
                .as_ref()
                .map(|s| std::f64::consts::TAU / s.period_s.mean),
            fundamental_only: false,
        }
    }
}

/// The table of `bins` bins the compensated stage meets: starting from the
/// friction against travel ([`super::travel`]), each round replays the
/// records with the table and takes the friction met, averaged over time
/// against the travel phase (a fixed point: the table equals the periodic
/// friction as the stage moves with it applied); up to [`ROUNDS`] rounds.
/// Then up to [`FUNDAMENTAL_STEPS`] steps of [`correct_fundamental`] on the
/// replay with the table, and the replay's own error at f_c without a
/// table.
///
/// With `guarded` (the product), a step is kept only when the replay says
/// it helps. A round is refused when the replay with its table gives a
/// velocity-error std not below the replay's without any table (near stall
/// the rounds can run away, the table feeding the stalls it is meant to
/// remove); the rounds then stop, and the table kept is the one, of the
/// friction against travel and the rounds before, with which the replay's
/// std is lowest. A correction of the fundamental is kept only when the
/// replay's f_c component falls (what the correction is for), and the
/// corrections stop at the first that does not. Without `guarded` (the
/// validation's comparison), every round and correction is taken, as
/// before session 12.
pub(crate) fn design(
    keys: &[RecordKeys],
    stage: &PdLoop,
    at: &DesignAt,
    bins: usize,
    fit_level: bool,
    guarded: bool,
) -> Result<Design, String> {
    let pitch = at.pitch_mm;
    let (sum, count) = super::travel::travel_bins(keys, |k| &k.friction_n, pitch, bins);
    let mut table = super::travel::travel_table(&sum, &count)
        .ok_or("no period between two passages to average the friction over")?;
    let v = at.velocity_mm_s;
    let settings = &at.settings;
    let mut keys = keys.to_vec();
    let levels = if fit_level {
        fit_levels(&mut keys, stage, pitch, v, settings)?
    } else {
        keys.iter()
            .map(|k| {
                let m = k.friction_n.iter().sum::<f64>() / k.friction_n.len().max(1) as f64;
                LevelFit {
                    restored_n: m,
                    fitted_n: m,
                }
            })
            .collect()
    };
    let keys = &keys[..];
    let play = |t: &[f64]| replay(keys, stage, Some(t), pitch, v, settings);
    let bare = replay(keys, stage, None, pitch, v, settings)?;
    let mut after = play(&table)?;
    let mut rounds = vec![Step::of(&table, &after)];
    let mut tables = vec![(table.clone(), after.clone())];
    let mut kept = Kept {
        rounds: 0,
        refused_round: None,
        corrections: 0,
    };
    for r in 1..=ROUNDS {
        let next = after
            .friction_met_n
            .clone()
            .ok_or("the replay did not reach the passages")?;
        let next_after = play(&next)?;
        rounds.push(Step::of(&next, &next_after));
        if guarded {
            let stds: Vec<f64> = rounds.iter().map(|x| x.std_um_s).collect();
            if let Some(best) = round_refused(&stds, bare.std_um_s) {
                (table, after) = tables.swap_remove(best);
                kept.rounds = best;
                kept.refused_round = Some(r);
                break;
            }
        }
        (table, after) = (next, next_after);
        if guarded {
            tables.push((table.clone(), after.clone()));
        }
        kept.rounds = r;
    }
    let (fixed_point, fixed_point_after) = (table.clone(), after.clone());
    let measured = at.measured_v1;
    let (re, im) = crate::analysis::sync::coefficient(&bare.waveform_um_s, 1);
    let f_c_model_error_um_s = measured.map_or(f64::NAN, |m| 2.0 * (m.0 - re).hypot(m.1 - im));
    let mut corrections = Vec::new();
    let mut fundamental_only = None;
    if let Some(w_c) = at.w_c_rad_s {
        let c = correct(table, after, &play, stage, w_c, guarded)?;
        (table, after, kept.corrections, corrections) = (c.table, c.after, c.kept, c.steps);
        if guarded && at.fundamental_only {
            let only = fundamental_of(&fixed_point);
            let only_after = play(&only)?;
            fundamental_only = Some(correct(only, only_after, &play, stage, w_c, true)?);
        }
    }
    Ok(Design {
        table,
        after,
        levels,
        f_c_model_error_um_s,
        kept,
        trace: Trace {
            fixed_point,
            fixed_point_after,
            bare,
            measured_v1: measured,
            rounds,
            corrections,
            fundamental_only,
        },
    })
}

/// A table after the corrections of its fundamental ([`correct`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Corrected {
    /// The table.
    pub table: Vec<f64>,
    /// The replay with it.
    pub after: Replayed,
    /// Corrections kept.
    pub kept: usize,
    /// Each correction tried.
    pub steps: Vec<Step>,
}

/// Up to [`FUNDAMENTAL_STEPS`] corrections of the fundamental of `table`
/// ([`correct_fundamental`]) on the replay `play`; with `guarded`, a
/// correction is kept only when the replay's f_c component falls, and the
/// corrections stop at the first that does not.
fn correct(
    mut table: Vec<f64>,
    mut after: Replayed,
    play: &dyn Fn(&[f64]) -> Result<Replayed, String>,
    stage: &PdLoop,
    w_c: f64,
    guarded: bool,
) -> Result<Corrected, String> {
    let (mut kept, mut steps) = (0, Vec::new());
    for k in 1..=FUNDAMENTAL_STEPS {
        let mut next = table.clone();
        correct_fundamental(&mut next, &after.waveform_um_s, stage, w_c);
        let next_after = play(&next)?;
        steps.push(Step::of(&next, &next_after));
        // A NaN (a replay that cannot say) refuses the correction too.
        let lower =
            next_after.f_c_um_s.partial_cmp(&after.f_c_um_s) == Some(std::cmp::Ordering::Less);
        if guarded && !lower {
            break;
        }
        (table, after) = (next, next_after);
        kept = k;
    }
    Ok(Corrected {
        table,
        after,
        kept,
        steps,
    })
}

/// The fundamental of `table` alone (zero mean, no harmonics).
pub(crate) fn fundamental_of(table: &[f64]) -> Vec<f64> {
    let (re, im) = crate::analysis::sync::coefficient(table, 1);
    let b = table.len() as f64;
    (0..table.len())
        .map(|j| {
            let th = std::f64::consts::TAU * j as f64 / b;
            2.0 * (re * th.cos() - im * th.sin())
        })
        .collect()
}

impl Design {
    /// The rounds and corrections kept by the guard, in words, with the
    /// replay's figures for the first step refused.
    pub(crate) fn guard_text(&self) -> String {
        let t = &self.trace;
        let mut out = match self.kept.refused_round {
            None => format!("{ROUNDS} rounds"),
            Some(r) => {
                let from = if self.kept.rounds == 0 {
                    "the friction against travel".to_string()
                } else {
                    format!("round {}", self.kept.rounds)
                };
                format!(
                    "the rounds stopped at round {r} of {ROUNDS}, whose table the replay says makes \
                     the velocity error worse than no table (std {:.1} µm/s, {:.1} without a \
                     table): the table is {from}'s (std {:.1} µm/s, the lowest before)",
                    t.rounds[r].std_um_s, t.bare.std_um_s, t.fixed_point_after.std_um_s
                )
            }
        };
        out += &format!(
            ", then {} of {FUNDAMENTAL_STEPS} corrections of the table's fundamental",
            self.kept.corrections
        );
        if self.kept.corrections < t.corrections.len() {
            let before = if self.kept.corrections == 0 {
                t.fixed_point_after.f_c_um_s
            } else {
                t.corrections[self.kept.corrections - 1].f_c_um_s
            };
            out += &format!(
                " (the next would have taken the replay's f_c component from {:.1} to {:.1} \
                 µm/s; a correction is kept only when it lowers it)",
                before, t.corrections[self.kept.corrections].f_c_um_s
            );
        }
        out
    }
}

/// The table given, from the replay with and without it (session 13):
/// the design's table when its replay leaves a smaller velocity-error std
/// than the replay without a table; else none (`Err`, with the reason):
/// the replay says the table does harm, and a table is refused rather
/// than given to do it. Near stall, the replay's std said so on the
/// benches where even the friction against travel made the stage stick
/// more (session 12), and there the table did harm in closed loop.
/// (The fundamental of the fixed-point table alone, tried as a second
/// choice on the design seeds, left the std where it was in closed loop
/// on 50 benches between 15 and 89 % of v, median 1.00 of the one
/// without a table; docs/methods.md §14.)
pub(crate) fn select(d: &Design) -> Result<(), String> {
    let bare = d.trace.bare.std_um_s;
    // A NaN (a replay that cannot say) refuses the table too.
    if d.after.std_um_s < bare {
        return Ok(());
    }
    Err(format!(
        "the replay through the stage says the table makes the velocity error worse: \
         its std is {:.0} µm/s with the table, {:.0} without",
        d.after.std_um_s, bare
    ))
}

/// The guard on the fixed-point rounds: `stds` the replay's velocity-error
/// std with the friction against travel and each round so far (µm/s), the
/// last one just tried, `bare_std` the replay's without a table. `None`
/// when the last round is kept: the replay says its table makes the
/// velocity error smaller than no table. Else the round to keep instead:
/// of those before, the one with the lowest std (a NaN std, a replay that
/// cannot say, refuses the round too).
pub(crate) fn round_refused(stds: &[f64], bare_std: f64) -> Option<usize> {
    let (&last, before) = stds.split_last()?;
    if last < bare_std || before.is_empty() {
        return None;
    }
    (0..before.len()).min_by(|&i, &j| before[i].total_cmp(&before[j]))
}

/// Steps of the fundamental's correction ([`correct_fundamental`]).
pub(crate) const FUNDAMENTAL_STEPS: usize = 3;

/// Moves the table's fundamental by `−R_1 / G_vf(jω_c)`, `R_1` the
/// fundamental of the replayed velocity error `waveform_um_s` (µm/s):
/// the change of the table's fundamental that cancels it if the stage
/// responds to the table's fundamental as the linear loop does.
pub(crate) fn correct_fundamental(
    table: &mut [f64],
    waveform_um_s: &[f64],
    stage: &PdLoop,
    w_c: f64,
) {
    let (re, im) = crate::analysis::sync::coefficient(waveform_um_s, 1);
    let d = -rustfft::num_complex::Complex64::new(re, im) / (stage.g_vf(w_c) * 1e6);
    let b = table.len() as f64;
    for (j, u) in table.iter_mut().enumerate() {
        let th = std::f64::consts::TAU * j as f64 / b;
        *u += 2.0 * (d.re * th.cos() - d.im * th.sin());
    }
}

/// Candidate friction levels above the lowest one, in stds of the
/// record's friction ([`fit_levels`]).
const LEVEL_STEPS: [f64; 5] = [0.0, 0.5, 1.0, 2.0, 4.0];

/// Quantile of the friction put at zero by the lowest candidate level.
const LEVEL_QUANTILE: f64 = 0.005;

/// The friction level of one record as the replay takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LevelFit {
    /// Mean of the friction as restored from the record, N.
    pub restored_n: f64,
    /// Mean of the friction replayed, N.
    pub fitted_n: f64,
}

/// Sets each record's friction level (its mean) to the one whose replay
/// without a table gives the record's own velocity-error std.
///
/// The level is the one thing about the friction the load cell does not
/// give (its discharge is undone from an assumed start, and a record cut
/// mid-run, or one whose decay was mis-fitted, reads a level far from the
/// true one), and near stall it matters: a friction that reads negative is
/// held at zero, and where the stage stops the level decides how long.
/// Above the level at which the friction stays positive, the replay hardly
/// depends on it. So each record is replayed alone at levels `L_0 + k·σ`,
/// `L_0` the level that puts the record's 0.5 % quantile at zero, `σ` the
/// friction's std and `k` in [`LEVEL_STEPS`], and the level whose replayed
/// std is nearest the record's is kept.
pub(crate) fn fit_levels(
    keys: &mut [RecordKeys],
    stage: &PdLoop,
    pitch_mm: f64,
    velocity_mm_s: f64,
    settings: &AnalyzeSettings,
) -> Result<Vec<LevelFit>, String> {
    let mut out = Vec::with_capacity(keys.len());
    for k in keys.iter_mut() {
        let n = k.friction_n.len();
        if n < 2 {
            return Err("a record with fewer than 2 friction samples".into());
        }
        let restored = k.friction_n.iter().sum::<f64>() / n as f64;
        let shape: Vec<f64> = k.friction_n.iter().map(|f| f - restored).collect();
        let mut sorted = shape.clone();
        sorted.sort_by(f64::total_cmp);
        let low = sorted[((LEVEL_QUANTILE * (n - 1) as f64).round() as usize).min(n - 1)];
        let sigma = (shape.iter().map(|f| f * f).sum::<f64>() / n as f64).sqrt();
        let mut best: Option<(f64, f64)> = None;
        for step in LEVEL_STEPS {
            let level = -low + step * sigma;
            let mut one = k.clone();
            one.friction_n = shape.iter().map(|f| f + level).collect();
            let r = replay(
                std::slice::from_ref(&one),
                stage,
                None,
                pitch_mm,
                velocity_mm_s,
                settings,
            )?;
            let miss = (r.std_um_s - k.velocity_error_std_um_s).abs();
            if best.is_none_or(|(m, _)| miss < m) {
                best = Some((miss, level));
            }
        }
        let level = best.map_or(restored, |b| b.1);
        k.friction_n = shape.iter().map(|f| f + level).collect();
        out.push(LevelFit {
            restored_n: restored,
            fitted_n: level,
        });
    }
    Ok(out)
}

/// Internal steps per sample.
const OVERSAMPLE: usize = 10;

/// The replay's velocity error.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Replayed {
    /// f_c component (fundamental of the synchronous average), µm/s.
    pub f_c_um_s: f64,
    /// Std of the low-passed velocity error, µm/s (pooled over records).
    pub std_um_s: f64,
    /// Mean periodic velocity error per bin of the period (time phase
    /// after the passage, as the synchronous average), µm/s, zero mean.
    pub waveform_um_s: Vec<f64>,
    /// The friction met, mean per bin of the travel phase over time (each
    /// internal step weighs the same: where the stage dwells, it counts
    /// more), minus its mean, when a table of that many bins was given.
    pub friction_met_n: Option<Vec<f64>>,
}

/// Replays `keys` at `velocity_mm_s` through `stage`, with `table` (keyed
/// on travel, pitch `pitch_mm`) when given.
pub(crate) fn replay(
    keys: &[RecordKeys],
    stage: &PdLoop,
    table: Option<&[f64]>,
    pitch_mm: f64,
    velocity_mm_s: f64,
    settings: &AnalyzeSettings,
) -> Result<Replayed, String> {
    let st = crate::sim::StageSettings {
        mass_kg: stage.mass_kg,
        kkp_n_per_m: stage.stiffness_n_per_m,
        kkd_n_s_per_m: stage.damping_n_s_per_m,
    };
    let mut outs: Vec<(f64, Vec<f64>, Vec<f64>)> = Vec::new();
    let nb = table.map_or(0, <[f64]>::len);
    let (mut met_sum, mut met_count) = (vec![0.0; nb], vec![0usize; nb]);
    for k in keys {
        let fs = k.fs_hz;
        let dt = 1.0 / (fs * OVERSAMPLE as f64);
        let mut pd = crate::sim::stage::PdStage::new(&st, dt).map_err(|e| e.to_string())?;
        let dir = k.direction();
        // Travel along the motion, made non-decreasing (a backward step of
        // the encoder keeps the friction met first).
        let mut run = f64::NEG_INFINITY;
        let travel: Vec<f64> = k
            .position_mm
            .iter()
            .map(|&x| {
                run = run.max(dir * (x - k.position_mm[0]));
                run
            })
            .collect();
        let end = *travel.last().unwrap_or(&0.0);
        let passages: Vec<f64> = k
            .passage_mm
            .iter()
            .map(|&x| dir * (x - k.position_mm[0]))
            .collect();
        let mean_f = k.friction_n.iter().sum::<f64>() / k.friction_n.len() as f64;
        pd.set_state(-mean_f / stage.stiffness_n_per_m, 0.0);
        let v = velocity_mm_s.abs() * 1e-3;
        let m = stage.mass_kg;
        let (mut ve, mut key_times) = (Vec::new(), Vec::new());
        let (mut i_f, mut next_passage) = (0usize, 0usize);
        let mut step = 0usize;
        loop {
            let t = step as f64 * dt;
            // Travel, mm.
            let s = (v * t + pd.deviation_m() + mean_f / stage.stiffness_n_per_m) * 1e3;
            if s >= end || !s.is_finite() {
                break;
            }
            while i_f + 1 < travel.len() && travel[i_f + 1] <= s {
                i_f += 1;
            }
            let frac = if i_f + 1 < travel.len() && travel[i_f + 1] > travel[i_f] {
                ((s - travel[i_f]) / (travel[i_f + 1] - travel[i_f])).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mag = at_index(&k.friction_n, i_f as f64 + frac).max(0.0);
            let xdot = v + pd.velocity_error_m_s();
            let v_eps = 1e-6f64.max(2.0 * mag * dt / m);
            let f = mag * (xdot / v_eps).clamp(-1.0, 1.0);
            while next_passage < passages.len() && passages[next_passage] <= s {
                key_times.push(t);
                next_passage += 1;
            }
            let u = match (table, next_passage) {
                (Some(tb), j) if j > 0 => {
                    let phi = (s - passages[j - 1]) / pitch_mm;
                    // Bin j is the table's value at phase j/B: the
                    // nearest bin.
                    let b = (phi.rem_euclid(1.0) * nb as f64).round() as usize % nb;
                    met_sum[b] += f;
                    met_count[b] += 1;
                    crate::analysis::sync::at_phase(tb, phi)
                }
                _ => 0.0,
            };
            if step % OVERSAMPLE == 0 {
                // mm/s, as the analysis' velocity error.
                ve.push(pd.velocity_error_m_s() * 1e3);
            }
            pd.step(f - u, 0.0);
            step += 1;
        }
        outs.push((fs, ve, key_times));
    }
    // Low-pass and statistics as the analysis.
    let mut filtered = Vec::new();
    let mut var = (0.0, 0usize);
    for (fs, ve, _) in &outs {
        let y = match crate::analysis::preprocess::lowpass_filter(settings, *fs)
            .map_err(|e| e.to_string())?
        {
            Some(lp) if ve.len() > 64 => lp.apply(ve).map_err(|e| e.to_string())?,
            _ => ve.clone(),
        };
        let n = y.len().max(1) as f64;
        let mean = y.iter().sum::<f64>() / n;
        var.0 += y.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
        var.1 += y.len();
        filtered.push(y);
    }
    let inputs: Vec<SyncInput<'_>> = outs
        .iter()
        .zip(&filtered)
        .enumerate()
        .map(|(i, ((fs, _, keys), y))| SyncInput {
            source: format!("replay {i}"),
            fs_hz: *fs,
            friction_n: None,
            velocity_error_mm_s: Some(y),
            key_times_s: keys.clone(),
        })
        .collect();
    // The replay is in mm/s; the average gives µm/s.
    let avg = synchronous_average(
        &inputs,
        SyncKey::OpticalPassage,
        None,
        &SyncSettings::default(),
    )
    .map_err(|e| e.to_string())?;
    let w = avg
        .waveform(Signal::VelocityError)
        .ok_or("no velocity error in the replay")?;
    let wm = w.mean.iter().sum::<f64>() / w.mean.len().max(1) as f64;
    Ok(Replayed {
        waveform_um_s: w.mean.iter().map(|v| v - wm).collect(),
        f_c_um_s: w.fundamental_amplitude,
        std_um_s: 1e3 * (var.0 / var.1.max(1) as f64).sqrt(),
        friction_met_n: (nb > 0)
            .then(|| super::travel::travel_table(&met_sum, &met_count))
            .flatten(),
    })
}

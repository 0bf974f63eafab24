//! The measurements that take compensated benches apart (`--diagnose`,
//! `--stall`, `--trace`, `--near-stall`, `--runaway`; see the bench's
//! module docs in `main.rs`).

use super::{bench, n_and_seed, n_seed_first};

/// The `--diagnose` measurement: each bench's stage, periods, and the
/// table built on the simulated stage's gains beside the product's.
pub(crate) fn diagnose() {
    let (n, seed) = n_and_seed(7_600_000);
    println!(
        "v_mm_s,condition,std_over_v,stage,f_n_used,zeta_used,f_n_true,zeta_true,periods,fc_before,fc_after,fc_pred,std_before,std_after,std_pred,fc_after_true_gains,fc_pred_true_gains,std_after_true_gains,std_pred_true_gains,fc_after_dc,fc_pred_dc,level,level_dc"
    );
    for i in 0..n {
        let s = bench(seed, i);
        match ballpass::validate::compensation::diagnose(&s) {
            Ok(d) => {
                let p = &d.product;
                println!(
                    "{:.3},{},{:.3},{:?},{:.3},{:.3},{:.3},{:.3},{},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{:.2},{:.2}",
                    p.velocity_mm_s,
                    p.condition.name(),
                    p.std_before_um_s * 1e-3 / p.velocity_mm_s,
                    p.stage_source,
                    d.used_f_n_zeta.0,
                    d.used_f_n_zeta.1,
                    d.true_f_n_zeta.0,
                    d.true_f_n_zeta.1,
                    d.periods,
                    p.f_c_before_um_s,
                    p.f_c_after_um_s,
                    p.f_c_predicted_um_s,
                    p.std_before_um_s,
                    p.std_after_um_s,
                    p.std_predicted_um_s,
                    d.true_gains_f_c_um_s.0,
                    d.true_gains_f_c_um_s.1,
                    d.true_gains_std_um_s.0,
                    d.true_gains_std_um_s.1,
                    d.dc_sensor_f_c_um_s.0,
                    d.dc_sensor_f_c_um_s.1,
                    d.friction_level_n.0,
                    d.friction_level_n.1,
                );
            }
            Err(e) => println!("# bench {i} ({} mm/s): {e}", s.velocity_mm_s),
        }
    }
}

/// The `--stall` measurement (module docs).
pub(crate) fn stall() {
    use ballpass::validate::compensation_stall::{diagnose_stall, Run};
    let (n, seed) = n_and_seed(9_500_000);
    println!(
        "i,v_mm_s,std_over_v,fc0,std0,stuck0,pstuck0,share0,fc_prod,std_prod,stuck_prod,pstuck_prod,fc_pred,std_pred,fc_sync,std_sync,fund_best_fc,fund_best_fc_std,shape_best_fc,shape_best_fc_std,shape_best_ok_std,shape_stuck,u1_learnt_n,miss_prod,miss_sync,miss_inverse,learn_fc_steps"
    );
    let fmt = |r: &[Run]| {
        r.iter()
            .map(|x| format!("{:.1}/{:.0}", x.f_c_um_s, x.std_um_s))
            .collect::<Vec<_>>()
            .join(" ")
    };
    for i in 0..n {
        let s = bench(seed, i);
        if s.condition != ballpass::sim::Condition::Sticking || s.velocity_mm_s > 6.0 {
            continue;
        }
        match diagnose_stall(&s, 0.3) {
            Ok(Some(d)) => {
                let best = |r: &[Run]| {
                    r.iter()
                        .min_by(|a, b| a.f_c_um_s.total_cmp(&b.f_c_um_s))
                        .cloned()
                };
                let f = best(&d.learnt_fundamental);
                let sh = best(&d.learnt_shape);
                let ok_std = d
                    .learnt_shape
                    .iter()
                    .chain(&d.learnt_fundamental)
                    .filter(|x| x.f_c_um_s <= 0.2 * d.none.f_c_um_s)
                    .map(|x| x.std_um_s)
                    .fold(f64::NAN, f64::min);
                let (f, sh) = (f.unwrap_or(d.none.clone()), sh.unwrap_or(d.none.clone()));
                println!(
                    "{i},{:.3},{:.3},{:.1},{:.0},{:.3},{:.2},{:.2},{:.1},{:.0},{:.3},{:.2},{:.1},{:.0},{:.1},{:.0},{:.1},{:.0},{:.1},{:.0},{:.0},{:.3},{:.2},{:.3},{:.3},{:.3},{} | {}",
                    d.velocity_mm_s,
                    d.std_over_v,
                    d.none.f_c_um_s,
                    d.none.std_um_s,
                    d.none.stuck_fraction,
                    d.none.periods_stuck,
                    d.none.periodic_share,
                    d.product.f_c_um_s,
                    d.product.std_um_s,
                    d.product.stuck_fraction,
                    d.product.periods_stuck,
                    d.predicted_um_s.0,
                    d.predicted_um_s.1,
                    d.sync_table.f_c_um_s,
                    d.sync_table.std_um_s,
                    f.f_c_um_s,
                    f.std_um_s,
                    sh.f_c_um_s,
                    sh.std_um_s,
                    ok_std,
                    sh.stuck_fraction,
                    d.learnt_fundamental_n,
                    d.fundamental_miss.0,
                    d.fundamental_miss.1,
                    d.fundamental_miss.2,
                    fmt(&d.learnt_fundamental),
                    fmt(&d.learnt_shape),
                );
            }
            Ok(None) => {}
            Err(e) => println!("# bench {i} ({} mm/s): {e}", s.velocity_mm_s),
        }
    }
}

/// The `--trace` measurement (session 11,
/// [`ballpass::validate::compensation_fc`]): each bench's fundamentals of
/// the velocity error recorded, replayed and simulated with the tables
/// before and after the fundamental's correction. With `--sticking`, only
/// the sticking benches below 6 mm/s.
pub(crate) fn trace() {
    let (n, seed) = n_and_seed(11_000_000);
    let sticking = std::env::args().any(|a| a == "--sticking");
    println!(
        "i,v_mm_s,std_over_v,stage,fn_used,zeta_used,fn_true,zeta_true,g_ratio_re,g_ratio_im,std0,meas_re,meas_im,bare_re,bare_im,rfix_re,rfix_im,rfin_re,rfin_im,tfix_re,tfix_im,tfin_re,tfin_im,std_fix,std_fin,std_rep,ufix_re,ufix_im,ufin_re,ufin_im,periods,band"
    );
    for i in 0..n {
        let s = bench(seed, i);
        if sticking && (s.condition != ballpass::sim::Condition::Sticking || s.velocity_mm_s > 6.0)
        {
            continue;
        }
        match ballpass::validate::compensation_fc::trace(&s) {
            Ok(t) => {
                let c = |x: (f64, f64)| format!("{:.3},{:.3}", x.0, x.1);
                println!(
                    "{i},{:.3},{:.3},{:?},{:.3},{:.3},{:.3},{:.3},{:.4},{:.4},{:.1},{},{},{},{},{},{},{:.1},{:.1},{:.1},{},{},{},{:.3}",
                    t.velocity_mm_s,
                    t.std_over_v,
                    t.stage_source,
                    t.stage_f_n_zeta.0 .0,
                    t.stage_f_n_zeta.0 .1,
                    t.stage_f_n_zeta.1 .0,
                    t.stage_f_n_zeta.1 .1,
                    t.g_ratio.0,
                    t.g_ratio.1,
                    t.std_before_um_s,
                    c(t.measured),
                    c(t.replay_bare),
                    c(t.replay_fixed),
                    c(t.replay_final),
                    c(t.truth_fixed),
                    c(t.truth_final),
                    t.std_after_um_s.0,
                    t.std_after_um_s.1,
                    t.std_after_um_s.2,
                    c(t.table_fixed),
                    c(t.table_final),
                    t.periods,
                    t.measured_band_um_s,
                );
            }
            Err(e) => println!("# bench {i} ({} mm/s): {e}", s.velocity_mm_s),
        }
    }
}

/// The `--near-stall` measurement (module docs).
pub(crate) fn near_stall() {
    use ballpass::validate::compensation_near_stall::{near_stall_check, Alternative};
    let (n, seed, first) = n_seed_first(18_000_000);
    println!(
        "i,v_mm_s,std_over_v,rounds_kept,refused_round,corrections_kept,fc_before,std_before,stuck_none,replay_bare_fc,replay_bare_std,travel_replay_std,\
prod_fc,prod_std,prod_stuck,prod_replay_fc,prod_replay_std,prod_u1,\
fo_fc,fo_std,fo_stuck,fo_replay_fc,fo_replay_std,fo_u1,\
tg_fc,tg_std,tg_stuck,tg_replay_fc,tg_replay_std,tg_u1,\
e0_amp,et_amp,et_over_e0,et_minus_e0_deg,g_ratio_abs,g_ratio_deg"
    );
    let alt = |a: &Alternative| {
        format!(
            "{:.3},{:.1},{:.3},{:.3},{:.1},{:.2}",
            a.run.f_c_um_s,
            a.run.std_um_s,
            a.run.stuck_fraction,
            a.replay_f_c_um_s,
            a.replay_std_um_s,
            a.u1_n
        )
    };
    for i in first..n {
        let s = bench(seed, i);
        if s.condition != ballpass::sim::Condition::Sticking || s.velocity_mm_s >= 8.0 {
            continue;
        }
        match near_stall_check(&s) {
            Ok(c) => {
                let Some(a) = &c.apart else {
                    println!(
                        "# bench {i} ({:.3} mm/s): std {:.3} of v",
                        s.velocity_mm_s, c.std_over_v
                    );
                    continue;
                };
                let p = &c.product;
                let amp = |x: (f64, f64)| 2.0 * x.0.hypot(x.1);
                let arg = |x: (f64, f64)| x.1.atan2(x.0).to_degrees();
                let mut dphi = arg(a.e_t) - arg(a.e_0);
                dphi = (dphi + 540.0).rem_euclid(360.0) - 180.0;
                println!(
                    "{i},{:.3},{:.3},{},{},{},{:.2},{:.1},{:.3},{:.2},{:.1},{:.1},{},{},{},{:.2},{:.2},{:.3},{:.3},{:.2},{:.1}",
                    p.velocity_mm_s,
                    c.std_over_v,
                    c.kept.map_or(-1, |k| k.rounds as i64),
                    c.kept
                        .and_then(|k| k.refused_round)
                        .map_or(String::new(), |r| r.to_string()),
                    c.kept.map_or(-1, |k| k.corrections as i64),
                    p.f_c_before_um_s,
                    p.std_before_um_s,
                    a.none.stuck_fraction,
                    a.replay_bare.0,
                    a.replay_bare.1,
                    a.travel_replay_std_um_s,
                    alt(&a.product),
                    a.fundamental_only
                        .as_ref()
                        .map_or(",,,,,".to_string(), &alt),
                    alt(&a.true_gains),
                    amp(a.e_0),
                    amp(a.e_t),
                    amp(a.e_t) / amp(a.e_0),
                    dphi,
                    a.g_ratio.0.hypot(a.g_ratio.1),
                    arg(a.g_ratio),
                );
            }
            Err(e) => println!("# bench {i} ({} mm/s): {e}", s.velocity_mm_s),
        }
    }
}

/// The `--runaway` look-up (session 13): bench `I` of `SEED` cut to each
/// duration given, with the product's table and the unguarded one
/// (`-- --runaway SEED I D1 D2 ...`), to find a short bench whose
/// unguarded table runs away for the test.
pub(crate) fn runaway() {
    use ballpass::validate::compensation_guard::guard_check;
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .filter_map(|a| a.parse().ok())
        .collect();
    let (seed, i) = (args[0] as u64, args[1] as u64);
    println!("duration_s,v_mm_s,std_before,std_after,refused,std_unguarded,fc_before,fc_after,fc_unguarded,seconds");
    for &d in &args[2..] {
        let mut s = bench(seed, i);
        s.duration_s = d;
        let t = std::time::Instant::now();
        match guard_check(&s) {
            Ok(g) => {
                let p = &g.product;
                println!(
                    "{d},{:.3},{:.1},{:.1},{},{},{:.1},{:.2},{},{:.1}",
                    s.velocity_mm_s,
                    p.std_before_um_s,
                    p.std_after_um_s,
                    u8::from(p.refused),
                    g.unguarded
                        .as_ref()
                        .map_or(String::new(), |u| format!("{:.1}", u.std_um_s)),
                    p.f_c_before_um_s,
                    p.f_c_after_um_s,
                    g.unguarded
                        .as_ref()
                        .map_or(String::new(), |u| format!("{:.2}", u.f_c_um_s)),
                    t.elapsed().as_secs_f64()
                );
            }
            Err(e) => println!("# {d} s: {e}"),
        }
    }
}

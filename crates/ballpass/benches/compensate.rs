//! Closed-loop check of `ballpass compensate` on randomized simulated
//! benches (issue 17): `cargo bench -p ballpass --bench compensate -- [N] [SEED]`.
//!
//! Each bench (velocity log-uniform in 1–20 mm/s, good and sticking
//! alternately, ≥ 40 periods) is simulated, the table built, the same
//! bench simulated with the table as feedforward and analysed again.
//! Prints one row per bench and the rates against the goals:
//! f_c component reduced ≥ 80 %, std reduced, prediction within 20 %.

use ballpass::validate::compensation::{bench, check};

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let n: u64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(20);
    let seed: u64 = args
        .get(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(7_000_000);
    println!(
        "v_mm_s,condition,stage,fc_before_um_s,fc_after_um_s,fc_pred_um_s,reduction,std_before_um_s,std_after_um_s,std_pred_um_s,fc_pred_err,std_pred_err"
    );
    let mut rows = Vec::new();
    for i in 0..n {
        let s = bench(seed, i);
        match check(&s) {
            Ok(c) => {
                println!(
                    "{:.3},{},{:?},{:.2},{:.2},{:.2},{:.3},{:.2},{:.2},{:.2},{:.3},{:.3}",
                    c.velocity_mm_s,
                    c.condition.name(),
                    c.stage_source,
                    c.f_c_before_um_s,
                    c.f_c_after_um_s,
                    c.f_c_predicted_um_s,
                    c.f_c_reduction(),
                    c.std_before_um_s,
                    c.std_after_um_s,
                    c.std_predicted_um_s,
                    c.f_c_prediction_error(),
                    c.std_prediction_error()
                );
                rows.push(c);
            }
            Err(e) => println!("# bench {i} ({} mm/s): {e}", s.velocity_mm_s),
        }
    }
    let count = |f: &dyn Fn(&ballpass::validate::compensation::CompensationCheck) -> bool| {
        rows.iter().filter(|c| f(c)).count()
    };
    let m = rows.len();
    println!("# benches run: {m} of {n}");
    println!(
        "# f_c reduced >= 80 %: {}/{m}",
        count(&|c| c.f_c_reduction() >= 0.8)
    );
    println!(
        "# std reduced: {}/{m}",
        count(&|c| c.std_after_um_s < c.std_before_um_s)
    );
    println!(
        "# std predicted within 20 %: {}/{m}",
        count(&|c| c.std_prediction_error() <= 0.2)
    );
    println!(
        "# f_c after predicted within 20 %: {}/{m}",
        count(&|c| c.f_c_prediction_error() <= 0.2)
    );
    println!(
        "# stage identified: {}/{m}",
        count(&|c| c.stage_source == ballpass::model::compensate::StageSource::Identified)
    );
}
